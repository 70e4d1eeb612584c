"""The report's stability-envelope and long-run parts (docs/report.md, Stability envelope and
Long runs), built by make_report.py from two sweeps:

* the stability envelope, a finished sweep of cases/envelope/sweep_full.toml (docs/stability.md):
  one row per stability search (`kind` = `stability`: `stable_dt`, `unstable_dt`,
  `estimate_dt`, `stable_over_estimate`, `outcome`, `unstable_reason`) and the remedy runs
  (`kind` = `run`). Two sections: the envelope figure (largest stable step / estimate against
  each parameter, per scheme) with a table of counts per group, and the table of the points
  where the default automatic step is not stable, with the remedy runs;
* the long runs, a finished sweep of cases/long_runs/sweep.toml with the DIR/drift.csv that
  cases/long_runs/drift.py writes. Two sections: the energy residual R / E_ref against the step
  (the residual of cases/long_runs/drift.py, imported, not copied), one panel per scene, and the
  drift.csv table.

Each section is "not available", with the command that produces its data, when its source is
missing; rows that failed or have empty cells are tabled as such, never a crash.

It also holds the reading of `ricochet stability` results (stability.json) and their table,
shared by the paper report's stability map (make_report.py) and the 3D Table 1
(report_three_d.py).
"""

import csv
import json
import math
import os

import numpy as np

import report_figures as F
from report_io import (Sweep, fmt_dt, fmt_g, fnum, read_case, read_stability,
                       resolve_case_file, same, scheme_name, show_path)

ENV_CMD = ("build/ricochet sweep cases/envelope/sweep_full.toml --out results/envelope "
           "--jobs 2 --check cases/envelope/gates_full.toml")
LONG_SWEEP_CMD = "build/ricochet sweep cases/long_runs/sweep.toml --out results/long_runs --jobs 2"
LONG_DRIFT_CMD = "/usr/bin/python3 cases/long_runs/drift.py results/long_runs"
LONG_CMD = f"{LONG_SWEEP_CMD}`, then `{LONG_DRIFT_CMD}"
SAFETY = 0.9          # time.safety's default: the automatic step is 0.9 x the estimate
SCHEMES = ("semi_explicit", "explicit_penalty", "implicit")

MATERIALS = {"saint_venant_kirchhoff": "St Venant–Kirchhoff", "neo_hookean": "neo-Hookean",
             "mooney_rivlin": "Mooney–Rivlin", "blatz_ko": "Blatz–Ko"}
SCENES = {   # long-run scenes: panel titles (another scene: its case's description)
    "block_resting": "block resting on the ground (gravity, μ = 0.3)",
    "block_sliding": "block sliding to rest (1 m/s, μ = 0.3)",
    "ball_bouncing": "elastic ball bouncing on the ground",
    "oblique_plate": "the paper's plate, 100 × its end time, gravity",
    "incline_relaxed": "block at rest on a 20° incline, quasi-static start",
    "incline_unrelaxed": "block on a 20° incline, started unstressed",
    "incline_unrelaxed_rot90": "the same, turned by a further 90°",
}
# drift.csv columns shown in their own table columns; any other one is scene-specific
DRIFT_FIXED = {"run_id", "group", "scheme", "status", "steps", "dt", "samples",
               "energy_error_max", "energy_error_end", "residual_max",
               "energy_drift_per_1e5_steps", "energy_drift_abs_per_1e5_steps", "penetration_max",
               "status_changes", "status_changes_per_step", "status_change_steps",
               "contact_steps"}


# ---------------------------------------------------------------------------------------------
# Stability searches (`ricochet stability`, docs/stability.md): the stability map of the paper's
# report and the stability table of the 3D Table 1 (report_three_d.py)

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


# ---------------------------------------------------------------------------------------------
# The stability envelope

def _get(d, *keys):
    for k in keys:
        if not isinstance(d, (dict, list)):
            return None
        try:
            d = d[k]
        except (KeyError, IndexError, TypeError):
            return None
    return d


def _num(x):
    if isinstance(x, bool):
        return None
    if isinstance(x, (int, float)):
        return float(x)
    return fnum(x)


class EnvPoint:
    """One search (or remedy run) of the envelope sweep with its parameters, read from the
    run's case file with its overrides applied (summary.csv `case_file`, `overrides`), so that
    a key the group does not set has the case's own value."""

    _cases = {}

    def __init__(self, run):
        self.run = run
        row = run.row
        self.id = run.id
        self.group = run.group
        self.kind = run.kind
        self.status = run.status or "missing"
        self.scheme = run.scheme
        try:
            self.overrides = json.loads(row.get("overrides") or "[]")
            if not isinstance(self.overrides, list):
                self.overrides = []
        except ValueError:
            self.overrides = []
        self.override_keys = [o.split("=", 1)[0].strip() for o in self.overrides
                              if isinstance(o, str)]
        case = self._case(row.get("case_file"), tuple(str(o) for o in self.overrides))
        mesh = row.get("mesh") or case.get("mesh") or ""
        body = _get(case, "bodies", 0) or {}
        mat = body.get("material") or {}
        v = body.get("velocity")
        try:
            self.speed = float(math.hypot(float(v[0]), float(v[1])))
        except (TypeError, ValueError, IndexError):
            self.speed = None
        self.friction = _num(_get(case, "obstacles", 0, "friction"))
        self.model = mat.get("model") or ""
        self.plane = case.get("plane") or ""
        self.nu = _num(mat.get("poisson"))
        if self.model == "mooney_rivlin":
            c10, c01, k = (_num(mat.get(x)) for x in ("c10", "c01", "bulk_modulus"))
            if c10 is not None and c01 is not None and k:
                mu = 2 * (c10 + c01)
                self.nu = (3 * k - 2 * mu) / (2 * (3 * k + mu))
        meshd = _get(case, "meshes", mesh) or {}
        self.distort = _num(meshd.get("distort")) or 0.0
        self.tri = meshd.get("cells") == "tri"
        self.element = body.get("element") or row.get("element") or ""
        self.hourglass = _get(body, "hourglass", "form") or ""
        self.level = _get(case, "contact", "level") or "position"
        self.safety = _num(_get(case, "time", "safety")) or SAFETY
        # the search's columns
        self.stable = fnum(row.get("stable_dt"))
        self.unstable = fnum(row.get("unstable_dt"))
        self.estimate = fnum(row.get("estimate_dt"))
        self.ratio = fnum(row.get("stable_over_estimate"))
        if self.ratio is None and self.stable and self.estimate:
            self.ratio = self.stable / self.estimate
        self.outcome = row.get("outcome") or ""
        self.reason = row.get("unstable_reason") or ""

    @classmethod
    def _case(cls, case_file, overrides):
        key = (case_file, overrides)
        if key not in cls._cases:
            path = resolve_case_file(case_file)
            try:
                # without the case file, the overrides alone (applied to an empty case)
                cls._cases[key] = read_case(path or os.devnull, overrides)
            except (OSError, ValueError):
                cls._cases[key] = read_case(os.devnull, overrides)
        return cls._cases[key]

    # -- what the search says about the default automatic step
    @property
    def searched(self):
        return self.kind == "stability" and self.status == "ok" and bool(self.outcome)

    @property
    def unsafe(self):
        """The automatic step (safety x the estimate) is not stable: no stable step at all, or
        the largest stable step is below safety x the estimate."""
        if not self.searched:
            return False
        if self.outcome == "no_stable_down_to_floor":
            return True
        return self.ratio is not None and self.ratio < self.safety

    @property
    def safe(self):
        return self.searched and not self.unsafe and self.ratio is not None

    # -- labels
    def material_label(self, nu=True):
        name = MATERIALS.get(self.model, self.model or "?")
        if self.model == "mooney_rivlin" and nu:
            parts = [name]
            if self.nu is not None:
                parts.append(f"ν = {self.nu:.2f}")
            if self.plane:
                parts.append(f"plane {self.plane}")
            return ", ".join(parts)
        return name

    def element_label(self):
        if self.tri:
            return "T3"
        if self.element == "q4_hourglass":
            return f"Q4 1-point, {self.hourglass or 'viscous'} hourglass"
        return {"q4": "Q4 (2×2)", "t3": "T3"}.get(self.element, self.element or "?")

    @property
    def short_id(self):
        return _short(self.id)

    def speed_label(self):
        return f"{self.speed:.3g} m/s" if self.speed is not None else "?"

    def params(self):
        """The parameters this point sets (its group's keys), as text."""
        keys = " ".join(self.override_keys)
        out = []
        if self.speed is not None:
            out.append(f"v = {self.speed_label()}")
        if "friction" in keys or self.family in ("speed", "contact"):
            out.append(f"μ = {fmt_g(self.friction)}")
        out.append(self.material_label())
        if "distort" in keys or "element" in keys or "cells" in keys:
            out.append(f"{self.element_label()}, distortion {fmt_g(self.distort)}")
        if "contact.level" in keys:
            out.append(f"contact level {self.level}")
        if "dt_update_interval" in keys:
            out.append("Δt recomputed every step")
        return ", ".join(out)

    @property
    def family(self):
        keys = " ".join(self.override_keys)
        if "contact.level" in keys:
            return "contact"
        if ".distort" in keys or "meshes." in keys and ".cells" in keys:
            return "element"
        return "speed"

    def same_point(self, other):
        """The same scheme and physical parameters (the remedy run against its search)."""
        return (self.scheme == other.scheme and self.model == other.model
                and self.plane == other.plane and _close(self.speed, other.speed)
                and _close(self.friction, other.friction) and _close(self.nu, other.nu)
                and _close(self.distort, other.distort) and self.tri == other.tri
                and self.element == other.element and self.level == other.level)


def _short(run_id):
    """`<group>/<index>`: a sweep's run id without its slug (the other columns say it)."""
    head, _, _ = run_id.partition("-")
    return head if "/" in head else run_id


def _close(a, b):
    if a is None or b is None:
        return a is None and b is None
    return abs(a - b) <= 1e-6 * max(abs(a), abs(b), 1e-12)


def _marker_kind(p):
    if p.outcome == "no_stable_down_to_floor":
        return "floor"
    if p.ratio is None:
        return None
    if p.outcome == "no_unstable_up_to_cap":
        return "cap"
    if p.outcome == "bracketed":
        return "bracketed"
    return "lower"      # run_limit: the largest stable step found, the bracket not converged


def _family_rows(points):
    """The figure's rows: (title, x label, [x tick labels], [series: (label, [(x index,
    point)])])."""
    rows = []

    def build(title, xlabel, pts, xkey, xfmt, skey):
        if not pts:
            return
        xs = sorted({xkey(p) for p in pts if xkey(p) is not None})
        if not xs:
            return
        names = []
        for p in pts:
            if skey(p) not in names:
                names.append(skey(p))
        series = [(n, [(xs.index(xkey(p)), p) for p in pts if skey(p) == n
                       and xkey(p) is not None]) for n in names]
        rows.append((title, xlabel, [xfmt(x) for x in xs], series))

    speed = [p for p in points if p.family == "speed"]
    spd = lambda p: None if p.speed is None else round(p.speed, 3)  # noqa: E731
    svk = [p for p in speed if p.model in ("saint_venant_kirchhoff", "")]
    if len({p.friction for p in svk}) > 1:
        build("impact speed × friction, St Venant–Kirchhoff", "impact speed (m/s)", svk, spd,
              lambda x: f"{x:.3g}", lambda p: f"μ = {fmt_g(p.friction)}")
    mu0 = min((p.friction for p in speed if p.friction is not None), default=None)
    mats = [p for p in speed if p.friction == mu0]
    build("impact speed × material" + (f", μ = {fmt_g(mu0)}" if mu0 is not None else ""),
          "impact speed (m/s)", mats, spd, lambda x: f"{x:.3g}", lambda p: p.material_label())
    elem = [p for p in points if p.family == "element"]
    build("mesh distortion × element, paper's speed", "mesh distortion (fraction of the "
          "element size)", elem, lambda p: p.distort, lambda x: f"{x:g}",
          lambda p: p.element_label())
    cont = [p for p in points if p.family == "contact"]
    build("contact level × friction × speed", "friction coefficient μ", cont,
          lambda p: p.friction, lambda x: fmt_g(x),
          lambda p: f"{p.level} level, v = {p.speed_label()}")
    return rows


def read_envelope(folder):
    """(Sweep, [EnvPoint]) of an envelope sweep folder, or (None, reason)."""
    try:
        sw = Sweep(folder)
    except (OSError, ValueError) as e:
        return None, str(e)
    return sw, [EnvPoint(r) for r in sw.runs]


def _ratio_text(p):
    if p.outcome == "no_stable_down_to_floor":
        return "no stable Δt"
    return fmt_g(p.ratio, 3) if p.ratio is not None else "–"


def _unavailable(sections, what, err, cmd, option, folder):
    """Marks the sections "not available", saying what is missing and the command that makes it."""
    for s in sections:
        s.available = False
        s.missing = (what + (f" ({err})" if err else "") + f". Run `{cmd}` and pass "
                     f"`{option} results/{folder}` (or place it next to the paper sweep as "
                     f"`{folder}/`).")
    return sections


def envelope_sections(ctx, Section):
    """The envelope figure and the table of unsafe points, or two "not available" sections."""
    fig = Section("envelope", "Stability envelope: largest stable Δt / estimate against the "
                  "parameters (beyond the paper)", "figure")
    tab = Section("envelope_unsafe", "Stability envelope: where the default automatic Δt is "
                  "not stable, and the remedy runs (beyond the paper)", "table")
    env = ctx.get("env")
    if env is None:
        return _unavailable([fig, tab], "no stability-envelope sweep", ctx.get("env_err"), ENV_CMD,
                            "--envelope", "envelope")
    sw, points = env
    searches = [p for p in points if p.kind == "stability"]
    done = [p for p in searches if p.searched]
    if not done:
        for s in (fig, tab):
            s.available = False
            s.missing = (f"the sweep {sw.dir} has no finished stability search (rows with "
                         "`kind` = `stability`, `status` ok and an `outcome`). "
                         f"Run `{ENV_CMD}`.")
        return [fig, tab]
    failed = [p for p in searches if not p.searched]
    safety = sorted({p.safety for p in done})
    sf = safety[0] if len(safety) == 1 else SAFETY
    schemes = [s for s in SCHEMES if any(p.scheme == s for p in done)]
    schemes += sorted({p.scheme for p in done} - set(schemes))

    # ---- counts per scheme (caption) and per group and scheme (table under the figure)
    def counts(ps):
        return (len(ps), sum(p.safe for p in ps), sum(p.unsafe for p in ps),
                sum(p.outcome == "no_stable_down_to_floor" for p in ps),
                sum(p.outcome == "no_unstable_up_to_cap" for p in ps))

    per_scheme = []
    for sc in schemes:
        n, ok, bad, floor, cap = counts([p for p in done if p.scheme == sc])
        ps = [p for p in done if p.scheme == sc and p.ratio is not None
              and p.outcome == "bracketed"]
        lo = min(ps, key=lambda p: p.ratio) if ps else None
        per_scheme.append(
            f"{scheme_name(sc)}: {n} searches, {ok} safe, {bad} not"
            + (f" ({floor} without any stable Δt)" if floor else "")
            + (f", {cap} stable up to the cap" if cap else "")
            + (f"; smallest bracketed ratio {lo.ratio:.3g} ({lo.params()})" if lo else ""))
    rows = []
    groups = []
    for p in done:
        if p.group not in groups:
            groups.append(p.group)
    for g in groups:
        for sc in schemes:
            ps = [p for p in done if p.group == g and p.scheme == sc]
            if not ps:
                continue
            n, ok, bad, floor, cap = counts(ps)
            rs = [p.ratio for p in ps if p.ratio is not None]
            rows.append([f"`{g}`", scheme_name(sc), str(n), str(ok), str(bad), str(floor),
                         str(cap), fmt_g(min(rs)) if rs else "–",
                         fmt_g(max(rs)) if rs else "–"])
    fig.extra.append(("envelope_counts", "Searches per group and scheme: how many leave the "
                      f"default automatic step ({sf:g} × the estimate) stable",
                      ["group", "scheme", "searches", f"safe (ratio ≥ {sf:g})", "not safe",
                       "of which no stable Δt", "stable up to the cap",
                       "smallest stable / estimate", "largest stable / estimate"], rows))

    # ---- the figure
    frows = _family_rows(done)
    n_all, n_safe, n_bad = len(done), sum(p.safe for p in done), sum(p.unsafe for p in done)
    if frows:
        fig.files = F.fig_envelope(ctx["out"], "stability_envelope", frows, schemes, sf)
    fig.sources = [sw.dir]
    fig.runs = [p.id for p in done]
    drawn = {id(p) for _, _, _, ser in frows for _, pts in ser for _, p in pts}
    not_drawn = [p for p in done if id(p) not in drawn]
    fig.caption = (
        "Each point is one `ricochet stability` search of the sweep, every row with `kind` = "
        "`stability` and `status` = `ok` (docs/stability.md: bisection over whole runs; "
        "cases/envelope/sweep_full.toml searches the oblique plate on M1 with energy bound 1, so "
        "that only a blow-up, an inverted element or energy growth counts as unstable): the "
        "largest stable fixed Δt over the estimate min L_e/c_p (`stable_over_estimate` of "
        "summary.csv), on a log scale. One column per scheme, one row per parameter family; "
        "colours tell the series "
        "of a row apart (legend on the right), points of one x are spread sideways. Filled "
        "circle: bracketed; open triangle: stable up to the search cap (the implicit scheme; "
        "drawn at the cap, a lower bound); "
        + ("open circle: the search stopped at its run limit (a lower bound); "
           if any(_marker_kind(p) == "lower" for p in done) else "")
        + "down-triangle in the grey band at the bottom: no stable Δt down to the floor "
        "(estimate / 1000: every step tried diverges; the table of unsafe points says why). "
        "The dashed "
        f"line is the automatic step, `time.safety` = {sf:g} × the estimate: a point below it "
        "(the shaded region) means that the default `time.dt = \"auto\"` is not stable there. "
        f"{n_all} searches: {n_safe} leave the automatic step stable, {n_bad} do not. "
        + "; ".join(per_scheme) + ". "
        + (f"Searches that failed or have no outcome (not counted): "
           f"{', '.join(f'`{p.id}`' for p in failed)}. " if failed else "")
        + (f"Not drawn (no row of the figure): {', '.join(f'`{p.id}`' for p in not_drawn)}. "
           if not_drawn else "")
        + f"Source: `{sw.dir}` (sweep `{sw.name}`, summary.csv), one run folder per search "
        "under `runs/`; the table below gives the counts per group.")
    if not frows:
        fig.available = False
        fig.missing = (f"no search of {sw.dir} has a parameter this figure draws (speed, "
                       f"friction, material, element, distortion, contact level). Run `{ENV_CMD}`.")

    # ---- the unsafe points
    tab.sources = [sw.dir]
    tab.header = ["run", "scheme", "parameters", "stable / estimate",
                  f"margin (ratio / {sf:g})", "outcome",
                  "why the smallest unstable Δt failed"]
    bad = [p for p in done if p.unsafe]
    for p in bad:
        outcome = (f"none stable down to the floor, {fmt_dt(p.unstable)} s"
                   if p.outcome == "no_stable_down_to_floor" and p.unstable else p.outcome)
        tab.rows.append([
            f"`{p.short_id}`", scheme_name(p.scheme), p.params(), _ratio_text(p),
            fmt_g(p.ratio / p.safety, 3) if p.ratio is not None else "–", outcome,
            (p.reason.replace("diverged: ", "") or "–")[:160]])
        tab.runs.append(p.id)
    # remedy runs: rows of kind run, each beside the search at the same point
    remedies = [p for p in points if p.kind == "run"]
    rrows = []
    for p in remedies:
        r = p.run
        match = next((q for q in done if q.same_point(p)), None)
        dmin, dmax = r.num("dt_min"), r.num("dt_max")
        steps = r.num("steps")
        upd = r.get("dt_update_interval") or r.get("time.dt_update_interval") or "?"
        status = "ok" if p.status == "ok" else (
            f"**{p.status}**" + (f" at t = {fmt_dt(r.num('diverged.time'))} s"
                                 if r.num("diverged.time") is not None else "")
            + (f": {r.reason[:160]}" if r.reason else ""))
        rrows.append([
            f"`{p.short_id}`", scheme_name(p.scheme),
            p.params().replace(", Δt recomputed every step", ""), status,
            (f"{fmt_dt(dmin)} – {fmt_dt(dmax)}" if dmin and dmax else fmt_dt(r.dt))
            + (" (every step)" if upd == "1" else f" (every {upd} steps)"),
            f"{steps:.0f}" if steps is not None else "–",
            f"{100 * r.num('energy_error_max'):.3g} %" if r.num("energy_error_max") is not None
            else "–",
            (f"{_ratio_text(match)} (`{match.short_id}`)" if match else
             "no search at this point")])
    if remedies:
        ok = sum(p.status == "ok" for p in remedies)
        tab.extra.append(("envelope_remedy", "Remedy runs: the automatic step recomputed from "
                          "the current configuration (`time.dt_update_interval`), at points "
                          f"where the step fixed at t = 0 is not stable: {ok} of "
                          f"{len(remedies)} ok",
                          ["run", "scheme", "parameters", "status", "Δt min – max (s), "
                           "recomputed", "steps", "energy_error_max",
                           "the search at the same point: stable / estimate"], rrows))
        tab.runs += [p.id for p in remedies]
    floors = sum(p.outcome == "no_stable_down_to_floor" for p in bad)
    limited = [p for p in bad if p.outcome == "run_limit"]
    tab.caption = (
        f"Every search of the envelope sweep whose largest stable Δt is below the automatic "
        f"step, `time.safety` × the estimate ({sf:g} ×; stable / estimate < {sf:g}), or that "
        f"found no stable Δt at all (`no_stable_down_to_floor`): {len(bad)} of {n_all} searches"
        + (f", {floors} of them without any stable Δt" if floors else "") + ". "
        f"Margin = (stable / estimate) / {sf:g}: below 1 the default automatic step "
        "diverges; the largest safe `time.safety` there is the ratio itself. "
        "The last column is the reason the smallest unstable trial stopped (summary.csv "
        "`unstable_reason`). "
        + (f"{len(limited)} of these searches stopped at their run limit, so their ratio is a "
           "lower bound. " if limited else "")
        + ("The table under it gives the remedy runs (`kind` = `run`): status, the range of "
           "the recomputed step, and the search at the same parameters. " if remedies else
           "The sweep has no remedy runs (groups `remedy_*`). ")
        + f"Source: `{sw.dir}` (summary.csv). Runs: the run column gives `<group>/<index>`, the "
        "run id without its slug (the folder `runs/<group>/<index>-<slug>`).")
    return [fig, tab]


# ---------------------------------------------------------------------------------------------
# Long runs

def read_drift(folder):
    """DIR/drift.csv as a list of dicts (cases/long_runs/drift.py), or None."""
    path = os.path.join(folder, "drift.csv")
    try:
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
    except (OSError, UnicodeDecodeError, csv.Error):
        return None
    return [r for r in rows if r.get("run_id")]


def _residual_fn():
    try:
        from long_runs import residual
    except ImportError as e:   # cases/long_runs/drift.py missing
        return None, str(e)
    return residual, None


def _drift_units():
    """{column: (unit, meaning)} of drift.csv, from cases/long_runs/drift.py's COLUMNS."""
    try:
        from long_runs import COLUMNS
    except ImportError:
        return {}
    return {c[0]: (c[1], c[2]) for c in COLUMNS if len(c) >= 3}


def _scene_title(sweep, group):
    if group in SCENES:
        return SCENES[group]
    run = next((r for r in sweep.runs if r.group == group), None)
    if run is not None:
        try:
            over = json.loads(run.get("overrides") or "[]")
            desc = EnvPoint._case(run.get("case_file"), tuple(str(o) for o in over)).get(
                "description")
        except (ValueError, TypeError, AttributeError):
            desc = None
        if isinstance(desc, str) and desc:
            return desc if len(desc) <= 70 else desc[:68].rsplit(" ", 1)[0] + " …"
    return group


def long_run_sections(ctx, Section):
    fig = Section("long_runs", "Long runs: energy residual over 1e5 steps per scene and scheme "
                  "(beyond the paper)", "figure")
    tab = Section("long_runs_table", "Long runs: energy drift, penetration and chatter per run "
                  "(beyond the paper)", "table")
    lr = ctx.get("long")
    if lr is None:
        return _unavailable([fig, tab], "no long-run sweep", ctx.get("long_err"), LONG_CMD,
                            "--long-runs", "long_runs")
    drift = read_drift(lr.dir)
    by_id = {d["run_id"]: d for d in drift or []}

    # ---- the figure: R / E_ref against the step, one panel per scene
    residual, imp_err = _residual_fn()
    scenes = []
    for r in lr.runs:
        if r.kind == "run" and r.group not in scenes:
            scenes.append(r.group)
    panels, used, skipped = [], [], []
    for g in scenes:
        lines = []
        for r in lr.find(group=g):
            h = r.history() if r.ok else None
            dt = r.dt or fnum(by_id.get(r.id, {}).get("dt"))
            if h is None or residual is None or not dt:
                skipped.append(f"`{r.id}` ({r.status or 'no status'}"
                               + ("" if r.ok else "") + (", no history.csv" if r.ok and h is None
                                                         else "") + ")")
                continue
            try:
                res = residual(h, r.scheme)
            except (KeyError, ValueError, IndexError) as e:
                skipped.append(f"`{r.id}` (history.csv lacks {e})")
                continue
            n = np.rint(h["time"] / dt)
            d = by_id.get(r.id, {})
            dr, rmax = fnum(d.get("energy_drift_per_1e5_steps")), fnum(d.get("residual_max"))
            label = (f"{scheme_name(r.scheme)}: drift "
                     + (("+" if dr > 0 else "") + fmt_g(dr, 2) if dr is not None else "–")
                     + " per 1e5 steps, |R| max "
                     + (fmt_g(rmax, 2) if rmax is not None else
                        fmt_g(float(np.nanmax(np.abs(res))), 2)))
            lines.append((label, r.scheme, n, res))
            used.append(r.id)
        if lines:
            panels.append((f"{g}: {_scene_title(lr, g)}", lines))
    fig.sources = [lr.dir]
    fig.runs = used
    if residual is None:
        fig.available = False
        fig.missing = f"cases/long_runs/drift.py cannot be imported ({imp_err})."
    elif not panels:
        fig.available = False
        fig.missing = (f"no ok run with a history.csv in {lr.dir}. Run `{LONG_SWEEP_CMD}`.")
    else:
        fig.files = F.fig_long_runs(ctx["out"], "long_runs_residual", panels)  # PNG only: dense
        fig.caption = (
            "The energy residual R / E_ref of cases/long_runs/drift.py (its `residual`, imported) "
            "against the time step n = t / Δt: for the bi-potential schemes R = E_t + D − E₀ − "
            "W_ext − W_cn, for the explicit penalty scheme R = E_t + E_pen + D − E₀ − W_ext, "
            "with E_t the bodies' energy (`total_energy`), D the friction dissipation, W_ext "
            "the external work (gravity), W_cn the work of the normal contact reactions "
            "(`contact_work_normal`), E_pen the springs' energy (`contact_energy`), all from "
            "history.csv, over E_ref = max(E₀, max |W_ext|). What is left is the time "
            "integrator's own energy error; the paper's energy error also counts the energy "
            "that position-level contact takes out of a node it stops. One panel per scene, "
            "one line per scheme; symmetric log scale (linear near 0, the grey band). The "
            "legend gives drift.csv's drift (least-squares slope of R / E_ref per 1e5 steps) "
            "and largest |R| / E_ref. "
            + (f"Not drawn: {', '.join(skipped)}. " if skipped else "")
            + f"Source: `{lr.dir}`. Runs: " + ", ".join(f"`{i}`" for i in used) + ".")

    # ---- the table: drift.csv
    tab.sources = [os.path.join(lr.dir, "drift.csv")]
    if drift is None:
        tab.available = False
        drift_cmd = LONG_DRIFT_CMD.replace("results/long_runs", lr.dir)
        tab.missing = (f"no drift.csv in {lr.dir}: run `{drift_cmd}` (the sweep itself: "
                       f"`{LONG_SWEEP_CMD}`).")
        return [fig, tab]
    tab.header = ["run", "scheme", "status", "steps", "Δt (s)",
                  "drift of R / E_ref per 1e5 steps", "max |R| / E_ref", "energy error max",
                  "penetration max (m)", "status changes / step", "contact steps",
                  "scene-specific"]

    def g(d, k, digits=3):
        v = fnum(d.get(k))
        return fmt_g(v, digits) if v is not None else "–"

    def count(d, k):
        v = fnum(d.get(k))
        return f"{v:.0f}" if v is not None else "–"

    units = _drift_units()
    specific = []      # scene-specific columns with a value somewhere, in drift.csv's order
    for d in drift:
        for k, v in d.items():
            if k and k not in DRIFT_FIXED and k not in specific and (v or "").strip():
                specific.append(k)
    for d in drift:
        extra = []
        for k in specific:
            v = fnum(d.get(k))
            if v is None:
                continue
            unit = units.get(k, ("", ""))[0]
            val = f"{v:.0f}" if v == int(v) and abs(v) < 1e9 and unit in ("-", "") else \
                fmt_g(v, 3)
            extra.append(f"{k} {val}" + (f" {unit}" if unit not in ("-", "") else ""))
        dr = fnum(d.get("energy_drift_per_1e5_steps"))
        status = d.get("status") or "missing"
        tab.rows.append([
            f"`{_short(d['run_id'])}`", scheme_name(d.get("scheme") or "–"),
            status if status == "ok" else f"**{status}**", count(d, "steps"),
            fmt_dt(fnum(d.get("dt"))) if fnum(d.get("dt")) else "–",
            (("+" if dr > 0 else "") + fmt_g(dr, 2)) if dr is not None else "–",
            g(d, "residual_max", 2), g(d, "energy_error_max", 2), g(d, "penetration_max", 2),
            g(d, "status_changes_per_step"), count(d, "contact_steps"),
            "; ".join(extra) or "–"])
        tab.runs.append(d["run_id"])
    shortened = any(_short(d["run_id"]) != d["run_id"] for d in drift)
    worst = max((d for d in drift if fnum(d.get("energy_drift_abs_per_1e5_steps")) is not None),
                key=lambda d: fnum(d["energy_drift_abs_per_1e5_steps"]), default=None)
    chat = max((d for d in drift if fnum(d.get("status_changes_per_step")) is not None),
               key=lambda d: fnum(d["status_changes_per_step"]), default=None)
    pen = max((d for d in drift if fnum(d.get("penetration_max")) is not None),
              key=lambda d: fnum(d["penetration_max"]), default=None)
    bad_rows = [f"`{d['run_id']}` {d.get('status') or 'missing'}" for d in drift
                if (d.get("status") or "") != "ok"]
    notes = []
    if worst:
        notes.append(f"largest |drift| {fmt_g(fnum(worst['energy_drift_abs_per_1e5_steps']))} "
                     f"per 1e5 steps (`{worst['run_id']}`)")
    if pen:
        notes.append(f"largest penetration {g(pen, 'penetration_max')} m (`{pen['run_id']}`)")
    if chat:
        notes.append(f"most chatter {g(chat, 'status_changes_per_step')} status changes per "
                     f"step (`{chat['run_id']}`)")
    tab.caption = (
        "One row per run of drift.csv (cases/long_runs/drift.py; columns in docs/stability.md, Long "
        "runs): the drift is the least-squares slope of R / E_ref (the figure above) against "
        "the step, × 1e5; max |R| / E_ref its largest size; `energy_error_max` the paper's "
        "energy error (summary.json), which also counts the energy that position-level contact "
        "takes out of the nodes it stops; `penetration_max` in m; status changes per step: "
        "contact status changes summed over every step / steps (the chatter of the active "
        "set); contact steps: steps with an active contact. "
        + ("Scene-specific (empty where they do not apply): " + "; ".join(
            f"`{k}`" + (f" [{units[k][0]}]" if k in units and units[k][0] not in ("-", "")
                        else "") + (f": {units[k][1]}" if k in units else "")
            for k in specific) + ". " if specific else "")
        + (("; ".join(notes) + ". ")[:1].upper() + ("; ".join(notes) + ". ")[1:] if notes
           else "")
        + f"Source: `{os.path.join(lr.dir, 'drift.csv')}`. Runs: the run column"
        + (" gives `<scene>/<index>`, the run id without its slug (the folder "
           "`runs/<scene>/<index>-<slug>`)." if shortened else ".")
        + (f" Rows without a value: the run is not ok ({', '.join(bad_rows)})."
           if bad_rows else ""))
    return [fig, tab]


def sections(ctx, Section):
    """The four sections in report order: envelope figure, unsafe table, long-run figure,
    long-run table."""
    return envelope_sections(ctx, Section) + long_run_sections(ctx, Section)
