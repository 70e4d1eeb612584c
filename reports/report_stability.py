"""Reading `ricochet stability` results (stability.json, docs/stability.md) and their table: the
`stability` kind of a layout (report_kinds.py) and the plug-ins that draw a stability map."""

import math

from report_io import fmt_g, read_stability, same, scheme_name, show_path

# ---------------------------------------------------------------------------------------------
# Stability searches (`ricochet stability`, docs/stability.md)

STABILITY_HEADER = ["mesh, scheme", "estimate Δt_crit", "largest stable", "smallest unstable",
                    "stable / estimate", "outcome", "why the smallest unstable Δt failed",
                    "energy bound", "trials", "file"]


def hi_reason(d):
    """Why the smallest unstable Δt of a stability.json failed: its trial's reason."""
    hi = d.get("smallest_unstable_dt")
    if hi is None:
        return "–"
    for t in d.get("trials", []):
        if same(t.get("dt"), hi) and not t.get("stable"):
            why = t.get("reason") or t.get("status") or ""
            return why.replace("diverged: ", "")[:120] or "–"
    return d.get("unstable_by") or "–"


def read_stability_entries(files):
    """([entry], [error text]): per stability.json file its mesh, scheme, estimate, largest
    stable Δt (lo), smallest unstable Δt (hi), outcome, search cap, bracket width, path and the
    file's content (d)."""
    entries, bad = [], []
    for p in files:
        try:
            d = read_stability(p)
        except (OSError, ValueError) as e:
            bad.append(f"{p}: {e}")
            continue
        entries.append({"mesh": d.get("mesh", "?"), "scheme": d.get("scheme", "?"),
                        "estimate": d.get("estimate") or d.get("critical_dt"),
                        "lo": d.get("largest_stable_dt"), "hi": d.get("smallest_unstable_dt"),
                        "outcome": d.get("outcome", "?"), "cap": (d.get("search") or {}).get("cap"),
                        "width": d.get("bracket_width"), "path": p, "d": d})
    return entries, bad


def best_entries(entries):
    """One entry per (mesh, scheme), in the order of their first search: the narrowest
    bracket."""
    best = {}
    for e in entries:
        k = (e["mesh"], e["scheme"])
        w = e["width"] if e["width"] is not None else math.inf
        if k not in best or w < (best[k]["width"] if best[k]["width"] is not None else math.inf):
            best[k] = e
    return list(best.values())


def stability_rows(entries):
    """The rows of STABILITY_HEADER, one per search, by mesh and scheme."""
    rows = []
    for e in sorted(entries, key=lambda e: (e["mesh"], e["scheme"])):
        d, est = e["d"], e["estimate"]
        rows.append([f"{e['mesh']} {scheme_name(e['scheme'])}", f"{fmt_g(est, 4)} s",
                     f"{fmt_g(e['lo'], 4)} s" if e["lo"] else "–",
                     f"{fmt_g(e['hi'], 4)} s" if e["hi"] else "–",
                     f"{e['lo'] / est:.4g}" if e["lo"] and est else "–",
                     e["outcome"], hi_reason(d),
                     f"{d.get('criterion', {}).get('energy_error_max_bound', '–')}",
                     str(d.get("runs", "–")), f"`{show_path(e['path'])}`"])
    return rows


def stability_summary(best):
    """One sentence part per (mesh, scheme): the largest stable Δt and its ratio to the
    estimate."""
    return "; ".join(
        f"{e['mesh']} {scheme_name(e['scheme'])}: "
        + (f"{fmt_g(e['lo'], 3)} s = {e['lo'] / e['estimate']:.3g} × the estimate"
           if e["lo"] and e["estimate"] else f"{fmt_g(e['lo'], 3)} s" if e["lo"] else "no stable Δt")
        + (" (no unstable Δt up to the cap)" if e["outcome"] == "no_unstable_up_to_cap" else "")
        for e in sorted(best, key=lambda e: (e["mesh"], e["scheme"])))
