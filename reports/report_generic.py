"""The report's parts for any sweep (docs/report.md, "Any sweep"): the runs table with the gate
results, work-precision diagrams per error metric, and each run's history as small multiples.
make_report.py builds them for every sweep, the paper's included.

    runs_section(ctx, sweep, Section)      the runs table (+ the gates table)
    wp_sections(ctx, sweep, Section)       one work-precision figure and table per error_* column
    histories_section(ctx, sweep, Section) one small-multiples figure per run (capped)
"""

import math
import os
import re
import xml.etree.ElementTree as ET

import numpy as np

import report_figures as F
from report_io import fmt_dt, fmt_g, scheme_name

# Units of the error columns of summary.csv (docs/sweeps.md): exact names first, then prefixes.
METRIC_UNITS = {
    "error_energy": "–",
    "error_penetration": "m",
    "error_rebound_velocity": "m/s",
    "error_angular_momentum": "kg·m²/s",
    "error_impulse_normal": "N·s",
    "error_impulse_tangential": "N·s",
    "error_contact_duration": "s",
    "error_von_mises_interior": "Pa",
}
METRIC_PREFIX_UNITS = {"error_probe_": "m"}
METRIC_TEXT = {
    "error_energy": "largest difference of the total energy from the reference run's, "
                    "relative to the reference's initial energy",
    "error_penetration": "difference of the penetration from the reference run's",
    "error_rebound_velocity": "difference of the rebound velocity from the reference run's",
    "error_angular_momentum": "difference of the angular momentum from the reference run's",
    "error_impulse_normal": "difference of the normal contact impulse from the reference run's",
    "error_impulse_tangential": "difference of the tangential contact impulse from the "
                                "reference run's",
    "error_contact_duration": "difference of the contact duration from the reference run's",
    "error_von_mises_interior": "difference of the interior von Mises stress from the "
                                "reference run's",
}
MAX_RUN_PLOTS = 30   # default cap on the per-run history figures (--max-run-plots)


def metric_unit(col):
    """The unit of an error column, or None when the report does not know it."""
    if col in METRIC_UNITS:
        return METRIC_UNITS[col]
    for prefix, unit in METRIC_PREFIX_UNITS.items():
        if col.startswith(prefix):
            return unit
    return None


def metric_text(col):
    if col in METRIC_TEXT:
        return METRIC_TEXT[col]
    if col.startswith("error_probe_"):
        p = col[len("error_probe_"):]
        return f"largest distance of probe {p} from its position in the reference run"
    return "difference from the reference run (docs/sweeps.md)"


def metric_label(col):
    u = metric_unit(col)
    return f"{col} [{u}]" if u else col


def finite(x):
    return x is not None and math.isfinite(x)


def metric_columns(sweep):
    """Every column of summary.csv named error_*, in table order, that holds a positive number
    in at least one run (not a reference run). A metric that is 0 in every run (e.g. the
    tangential impulse without friction, exactly 0 in the run and its reference) has nothing
    to draw on a log scale."""
    out = []
    for c in sweep.columns:
        if c.startswith("error_") and any(r.kind == "run" and (r.num(c) or 0) > 0
                                          for r in sweep.runs):
            out.append(c)
    return out


def has_reference(sweep):
    return any(r.kind == "reference" for r in sweep.runs) or \
        any(r.get("reference_run") for r in sweep.runs)


# ---------------------------------------------------------------------------------------------
# Gates (DIR/gates-junit.xml, written by `ricochet sweep --check`; docs/gates.md)

RUN_RE = re.compile(r"\brun ([^\s:;,()]+)")


def read_gates(folder, run_ids):
    """The sweep's gate results, or None without gates-junit.xml:
    {"passed", "failed", "cases": [{name, failed, text, runs}], "by_run": {id: [gate names]}}.
    A gate is mapped to the runs its JUnit text names (`run <id>`): for a failed gate the runs
    that missed it, for a passed one its tightest run."""
    path = os.path.join(folder, "gates-junit.xml")
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError):
        return None
    ids = set(run_ids)
    cases, by_run = [], {}
    for c in root.iter("testcase"):
        bad = c.find("failure")
        if bad is None:
            bad = c.find("error")
        if bad is not None:
            text = bad.get("message") or (bad.text or "")
        else:
            so = c.find("system-out")
            text = so.text if so is not None and so.text else ""
        runs = []
        for m in RUN_RE.finditer(text):
            rid = m.group(1)
            if rid in ids and rid not in runs:
                runs.append(rid)
        name = c.get("name", "?")
        cases.append({"name": name, "failed": bad is not None, "text": text.strip(),
                      "runs": runs})
        if bad is not None:
            for rid in runs:
                by_run.setdefault(rid, []).append(name)
    nfail = sum(c["failed"] for c in cases)
    return {"passed": len(cases) - nfail, "failed": nfail, "cases": cases, "by_run": by_run,
            "path": path}


def gates_line(g):
    if g is None:
        return "no `gates-junit.xml` (the sweep ran without `--check`)"
    failing = [c["name"] for c in g["cases"] if c["failed"]]
    return (f"gates (`gates-junit.xml`): {g['passed']} passed, {g['failed']} failed"
            + (": " + "; ".join(f"**{n}**" for n in failing) if failing else ""))


# ---------------------------------------------------------------------------------------------
# Cells

def wall_cell(r):
    """Median time-loop wall time, with the min–max over the repeats when there are several."""
    w = r.num("wall_seconds")
    if w is None:
        return "–"
    reps = r.num("repeats")
    lo, hi = r.num("wall_seconds_min"), r.num("wall_seconds_max")
    if reps and reps > 1 and lo is not None and hi is not None:
        return f"{fmt_g(w)} ({fmt_g(lo)}–{fmt_g(hi)})"
    return fmt_g(w)


def dt_cell(r):
    if r.dt is None:
        return "–"
    return fmt_dt(r.dt) + (" (auto)" if r.get("dt_mode") == "auto" else "")


def status_cell(r):
    if r.ok:
        return "ok"
    return f"**{r.status or 'failed'}**"


def repeats_text(runs):
    reps = sorted({int(r.num("repeats")) for r in runs if r.num("repeats")})
    if not reps:
        return "single runs"
    if reps == [1]:
        return "single runs, no repeats"
    if len(reps) == 1:
        return f"median of {reps[0]} repeats"
    return f"median of {reps[0]}–{reps[-1]} repeats"


# ---------------------------------------------------------------------------------------------
# Sections

def runs_section(ctx, sweep, Section, sid="runs"):
    s = Section(sid, f"Runs of the sweep {sweep.name}", "table")
    g = read_gates(sweep.dir, [r.id for r in sweep.runs])
    refs = any(r.kind == "reference" for r in sweep.runs)
    s.header = ["run"] + (["kind"] if refs else []) + [
        "status", "scheme", "mesh", "Δt (s)", "wall time, time loop (s): median (min–max)",
        "energy_error_max (%)", "penetration_max (m)"] + (["gates that failed"] if g else [])
    for r in sweep.runs:
        e = r.num("energy_error_max")
        row = [f"`{r.id}`"] + ([r.kind] if refs else []) + [
            status_cell(r), scheme_name(r.scheme) or "–", r.mesh or "–", dt_cell(r),
            wall_cell(r), f"{fmt_g(100 * e)} %" if e is not None else "–",
            fmt_g(r.num("penetration_max"))]
        if g:
            names = g["by_run"].get(r.id)
            row.append("**failed**: " + "; ".join(names) if names else "–")
        s.rows.append(row)
        s.runs.append(r.id)
    s.sources = [sweep.dir]
    s.caption = (
        f"`summary.csv` of `{sweep.dir}`, one row per run, in the sweep's order. Wall time: "
        "`wall_seconds`, the time loop only (set-up and output excluded); with `--repeat K` "
        "the median over the K repeats, with the fastest and slowest in brackets "
        "(`wall_seconds_min`, `wall_seconds_max`). `energy_error_max`: the largest "
        "`energy_error` of history.csv, |E_kin + E_strain + E_hg + E_contact + D − E₀ − W_ext| "
        "/ max(E₀, |W_ext|) (docs/outputs.md). " + gates_line(g) + "."
        + (" Column *gates that failed*: the failed gates whose JUnit message names the run "
           "(`run <id>`); a gate that names no run (a count, `require_rows`) is only in the "
           "line above and the gates table." if g else ""))
    if g:
        rows = []
        for c in g["cases"]:
            text = c["text"]
            text = text if len(text) <= 240 else text[:237] + "…"
            rows.append([c["name"], "**failed**" if c["failed"] else "passed",
                         ", ".join(f"`{x}`" for x in c["runs"]) or "–", text or "–"])
        s.extra.append((sid + "_gates", f"Gates (`{os.path.basename(g['path'])}`): "
                        f"{g['passed']} passed, {g['failed']} failed",
                        ["gate", "result", "runs named", "JUnit text"], rows))
    return s


def safe_name(text, limit=70):
    return re.sub(r"[^A-Za-z0-9._=-]+", "_", text)[:limit].strip("_") or "run"


def histories_section(ctx, sweep, Section, sid="histories"):
    s = Section(sid, f"Run histories of the sweep {sweep.name}", "figure")
    cap = ctx.get("max_run_plots", MAX_RUN_PLOTS)
    withh = [r for r in sweep.runs if r.history() is not None]
    without = [r for r in sweep.runs if r.history() is None]
    if not withh:
        s.available = False
        s.missing = (f"no run of {sweep.dir} has a readable history.csv (failed runs write "
                     "none).")
        return s
    if cap == 0:
        s.available = False
        s.missing = (f"not drawn (`--max-run-plots 0`); {len(withh)} runs have a history. "
                     "`reports/plot_run.py RUN_DIR` draws one run.")
        return s
    drawn = withh[:cap]
    left = withh[cap:]
    for k, r in enumerate(drawn):
        stem = f"history_{k:03d}_{safe_name(r.id)}"
        title = (f"{r.id}   ({', '.join(x for x in (scheme_name(r.scheme), r.mesh) if x)}"
                 + (f", Δt = {dt_cell(r)} s" if r.dt is not None else "")
                 + (f", {r.status}" if not r.ok else "") + ")")
        F.fig_run_history(os.path.join(ctx["out"], stem + ".png"), r.history(), title,
                          e0=r.num("initial_energy"))
        s.files.append(stem + ".png")
        s.runs.append(r.id)
    s.sources = [sweep.dir]
    s.caption = (
        "Each run's history.csv (docs/outputs.md), one row of four panels per run. "
        "Energies: kinetic, strain, and where they are not zero the hourglass energy, the "
        "energy held in penalty springs (`contact_energy`), the friction dissipation D and the "
        "external work W; the total E = E_kin + E_strain + E_hg + E_contact (black) and the "
        "balance E + D − W − E₀ (dashed, J), the numerator of `energy_error`. Contact forces: "
        "`normal_force` and `tangential_force`, sums over the active contacts. Largest "
        "penetration: `penetration_max`. Probes: u_x (solid) and u_y (dashed) of each probe "
        f"(at most {F.MAX_PROBES}). Runs drawn: " + ", ".join(f"`{i}`" for i in s.runs) + "."
        + (f" **Only the first {cap} of {len(withh)} runs are drawn** (`--max-run-plots`); "
           "not drawn: " + ", ".join(f"`{r.id}`" for r in left)
           + ". `reports/plot_run.py RUN_DIR` draws any one of them." if left else "")
        + (" Without a history.csv (not drawn): " + ", ".join(f"`{r.id}`" for r in without)
           + "." if without else ""))
    return s


def _overrides(sweep):
    """run id -> {case key: value text} from sweep.json's run list."""
    out = {}
    for e in sweep.meta.get("runs", []) or []:
        if not isinstance(e, dict):
            continue
        d = {}
        for item in e.get("overrides", []) or []:
            if isinstance(item, str) and "=" in item:
                k, v = item.split("=", 1)
                d[k.strip()] = v.strip()
        out[e.get("id")] = d
    return out


def _series_names(runs, sweep):
    """run id -> series label: the scheme, plus the case keys (other than time.dt, mesh and
    scheme) whose values differ between runs of that scheme."""
    ov = _overrides(sweep)
    skip = {"time.dt", "mesh", "scheme"}
    by_scheme = {}
    for r in runs:
        by_scheme.setdefault(r.scheme, []).append(r)
    names = {}
    for scheme, rs in by_scheme.items():
        keys = sorted({k for r in rs for k in ov.get(r.id, {})} - skip)
        varying = [k for k in keys if len({ov.get(r.id, {}).get(k) for r in rs}) > 1]
        for r in rs:
            extra = ", ".join(f"{k} = {ov.get(r.id, {}).get(k, '(case)')}" for k in varying)
            names[r.id] = scheme_name(scheme) + (f", {extra}" if extra else "")
    return names


FALLBACK_COLORS = ["#ff7f0e", "#8c564b", "#e377c2", "#17becf", "#bcbd22", "#7f7f7f"]


def wp_sections(ctx, sweep, Section, prefix="wp", title_of=""):
    """One figure section per error metric of the sweep (error_* columns); [] when there is
    none. Section ids `<prefix>_<metric>`, figures `work_precision_<metric>.png` (prefix
    `wp`) or `<prefix>_work_precision_<metric>.png`."""
    out = []
    for m in metric_columns(sweep):
        stem = ("" if prefix == "wp" else safe_name(prefix) + "_") + "work_precision_" + \
            safe_name(m)
        out.append(wp_section(ctx, sweep, Section, m, f"{prefix}_{m}", stem, title_of))
    return out


def wp_section(ctx, sweep, Section, metric, sid, stem, title_of=""):
    unit = metric_unit(metric)
    s = Section(sid, f"Work-precision: {metric} against time-loop wall time{title_of}",
                "figure")
    runs = [r for r in sweep.runs if r.kind == "run"]
    floor_col = "floor_" + metric
    has_floor = floor_col in sweep.columns
    drawn, skipped = [], []
    for r in runs:
        e, w = r.num(metric), r.num("wall_seconds")
        if not r.ok:
            skipped.append((r, r.status or "failed"))
        elif e is None:
            skipped.append((r, "no error value"))
        elif not math.isfinite(e):
            skipped.append((r, f"error {e}"))
        elif e <= 0:
            skipped.append((r, "error 0 (the reference's own Δt)"))
        elif w is None or w <= 0:
            skipped.append((r, "no wall time"))
        else:
            drawn.append(r)
    if not drawn:
        s.available = False
        s.missing = (f"no ok run of {sweep.dir} with a positive `{metric}` and a wall time.")
        return s
    series = _series_names(drawn, sweep)
    names = list(dict.fromkeys(series[r.id] for r in drawn))
    style = {}
    scheme_count, fb = {}, 0
    for name in names:
        r0 = next(r for r in drawn if series[r.id] == name)
        k = scheme_count.get(r0.scheme, 0)
        scheme_count[r0.scheme] = k + 1
        c = F.SCHEME_COLORS.get(r0.scheme)
        if c is None:
            c = FALLBACK_COLORS[fb % len(FALLBACK_COLORS)]
            fb += 1
        style[name] = (c, F.WP_MARKERS[k % len(F.WP_MARKERS)])
    meshes = list(dict.fromkeys(r.mesh for r in drawn))
    points = {}
    for r in drawn:
        fl = r.num(floor_col) if has_floor else None
        c, mk = style[series[r.id]]
        points.setdefault(r.mesh, []).append(dict(
            series=series[r.id], color=c, marker=mk, x=r.num("wall_seconds"),
            xlo=r.num("wall_seconds_min"), xhi=r.num("wall_seconds_max"), y=r.num(metric),
            floor=fl if finite(fl) and fl > 0 else None, dt=r.dt, run=r))
    panels = [(f"mesh {m}" if m else "mesh (not recorded)", points[m]) for m in meshes]
    reps = repeats_text(drawn)
    xlabel = f"time-loop wall time [s] ({reps})"
    files, left_out, guides = F.fig_work_precision(
        ctx["out"], stem, panels, metric_label(metric), xlabel,
        f"{metric}: {metric_text(metric)}", f"reference uncertainty ({floor_col})")
    s.files = files
    s.runs = [r.id for r in drawn]
    s.sources = [sweep.dir]
    # table of the points
    rows = []
    fronts = {}
    for m in meshes:
        for name in names:
            pts = [(p["x"], p["y"], p["run"].id) for p in points[m] if p["series"] == name]
            fronts.update({q[2]: True for q in F.pareto_front(pts)})
    below_n = 0
    order = {n: i for i, n in enumerate(names)}
    for r in sorted(drawn, key=lambda r: (meshes.index(r.mesh), order[series[r.id]],
                                          -(r.dt or 0))):
        e = r.num(metric)
        fl = r.num(floor_col) if has_floor else None
        below = finite(fl) and fl > 0 and e < fl
        below_n += below
        note = []
        if below:
            note.append("below the reference uncertainty")
        note.append("Pareto front" if r.id in fronts else "dominated")
        rows.append([f"`{r.id}`", series[r.id], r.mesh or "–", dt_cell(r), wall_cell(r),
                     fmt_g(r.num("repeats")),
                     (f"< {fmt_g(fl)}" if below else fmt_g(e, 4))]
                    + ([fmt_g(fl) if finite(fl) else "–"] if has_floor else [])
                    + ["; ".join(note), f"`{r.get('reference_run')}`" if r.get("reference_run")
                       else "–"])
    for r, why in skipped:
        rows.append([f"`{r.id}`", scheme_name(r.scheme), r.mesh or "–", dt_cell(r),
                     wall_cell(r), fmt_g(r.num("repeats")), f"not drawn: {why}"]
                    + (["–"] if has_floor else []) + ["–", f"`{r.get('reference_run')}`"
                                                      if r.get("reference_run") else "–"])
    u = f" [{unit}]" if unit else ""
    s.extra.append((sid + "_data", f"The points of the `{metric}` diagram",
                    ["run", "series", "mesh", "Δt (s)", "wall time, time loop (s): median "
                     "(min–max)", "repeats", metric + u]
                    + ([floor_col + u] if has_floor else [])
                    + ["Pareto", "reference run"], rows))
    # observed order in Δt per series and mesh
    orders = []
    for m in meshes:
        for name in names:
            p = [(q["dt"], q["y"]) for q in points[m] if q["series"] == name and q["dt"]
                 and not (q["floor"] and q["y"] < q["floor"])]
            if len(p) >= 3 and len({a for a, _ in p}) >= 3:
                k = np.polyfit(np.log([a for a, _ in p]), np.log([b for _, b in p]), 1)[0]
                orders.append(f"{name}" + (f" on {m}" if len(meshes) > 1 else "") + f" {k:.2f}")
    refs = sorted({r.get("reference_run") for r in drawn} - {""})
    s.caption = (
        f"`{metric}`{u} ({metric_text(metric)}) against the time-loop wall time "
        f"(`wall_seconds`; {reps}"
        + ("; bars: fastest to slowest repeat, `wall_seconds_min`–`wall_seconds_max`"
           if any((r.num("repeats") or 1) > 1 for r in drawn) else "")
        + "), log–log, " + ("one panel per mesh" if len(meshes) > 1 else
                            f"mesh {meshes[0] or '(not recorded)'}")
        + ". One colour per scheme; each point is one run, labelled with its Δt (s)"
        + (f"; {left_out} label(s) that would overlap are left out (the table has every point)"
           if left_out else "")
        + ". Dotted: the runs in Δt order. Solid step line: the scheme's Pareto front, the "
        "points that no other point of the scheme beats on both cost and error. "
        + ("Grey guides: slopes −1 and −2, i.e. first and second order in Δt where the cost is "
           "proportional to 1/Δt." if guides else
           "No slope guides: the wall times span too narrow a range beside the errors for "
           "them to be told apart.")
        + (f" Shaded: the uncertainty of the reference itself (`{floor_col}`); the "
           f"{below_n} hollow point(s) below it are not measured errors, only bounds."
           if has_floor else "")
        + " Observed order of the error in Δt (least squares over the points above any floor): "
        + (", ".join(orders) if orders else "– (fewer than 3 Δt per series)") + ". "
        "Each run is compared with the reference run that shares its crossed values "
        "(docs/sweeps.md), so these are discretisation errors against that reference. "
        "References: " + (", ".join(f"`{x}`" for x in refs) if refs else "–") + "."
        + (" Not drawn: " + ", ".join(f"`{r.id}` ({why})" for r, why in skipped) + "."
           if skipped else "")
        + " Runs: " + ", ".join(f"`{i}`" for i in s.runs) + ".")
    return s
