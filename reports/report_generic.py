"""The report's parts for any sweep (docs/report.md, "Any sweep"): the runs table with the gate
results, work-precision diagrams per error metric, and each run's history as small multiples.
make_report.py builds them for every sweep, the paper's included.

    runs_section(ctx, sweep, Section)      the runs table (+ the gates table)
    wp_sections(ctx, sweep, Section)       one work-precision figure and table per error_* column
    histories_section(ctx, sweep, Section) one small-multiples figure per run (capped)
    scheme_limits_section(ctx, sweep, Section)
                                           per mesh, how far apart the schemes are at their
                                           smallest Δt (P trajectory, energy loss, rebound
                                           velocity, normal impulse), and the shared
                                           reference against its check run
"""

import math
import os
import re
import xml.etree.ElementTree as ET

import numpy as np

import report_figures as F
from report_io import fmt_dt, fmt_g, scheme_name
from report_select import overrides

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


def part_sections(ctx, Section, builders, part, intro):
    """The sections of one part of the report: fn(ctx, Section, sid, title) for each
    (sid, title, fn) of builders, each under the part's title and intro; a builder that raises
    gives a section that shows the error (one broken section must not stop the others)."""
    import traceback
    out = []
    for sid, title, fn in builders:
        try:
            s = fn(ctx, Section, sid, title)
        except Exception as e:  # noqa: BLE001
            traceback.print_exc()
            s = Section(sid, title, "figure")
            s.error = f"{type(e).__name__}: {e}"
        s.part = part
        s.part_intro = intro
        out.append(s)
    return out


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


def floor_column(sweep, metric):
    """The reference-uncertainty column of an error column: `floor_<X>` for `error_<X>` as the
    sweep writes it (docs/sweeps.md), else `floor_<metric>`."""
    name = "floor_" + metric[len("error_"):] if metric.startswith("error_") else None
    return name if name and name in sweep.columns else "floor_" + metric


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

def wall_cell(r, cost="wall_seconds"):
    """Median time-loop wall time (or the cost column `cost`), with the min–max over the repeats
    when there are several."""
    w = r.num(cost)
    if w is None:
        return "–"
    reps = r.num("repeats")
    lo, hi = r.num(cost + "_min"), r.num(cost + "_max")
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


_overrides = overrides   # run id -> {case key: value text} (report_select.py)


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


def _reference_text(runs):
    """How the runs were compared (summary.csv `reference_kind`, docs/sweeps.md)."""
    kinds = {r.get("reference_kind") for r in runs} - {""}
    shared = ("Runs compared with the sweep's shared reference (`[reference]`, on its own "
              "mesh, scheme and Δt) carry the mesh and time discretisation errors together, "
              "and for another scheme also the difference between the schemes.")
    group = ("Runs compared with their group's own reference runs are compared with the "
             "reference run that shares their crossed values, so these are time "
             "discretisation errors of the scheme against itself at a small Δt.")
    if kinds == {"shared"}:
        return shared
    if kinds == {"group"}:
        return group
    if kinds >= {"shared", "group"}:
        return shared + " " + group
    return ("Each run is compared with the reference run that shares its crossed values "
            "(docs/sweeps.md), so these are discretisation errors against that reference.")


def wp_section(ctx, sweep, Section, metric, sid, stem, title_of="", cost="wall_seconds",
               by=None, runs=None):
    """One work-precision diagram: `metric` against the cost column (its `_min`/`_max` as
    bars when there), one panel per mesh, one series per scheme (and the case keys that vary
    within it), or per value of the column `by` when given; runs: the runs to draw (default:
    every run of kind `run`)."""
    unit = metric_unit(metric)
    what = "time-loop wall time" if cost == "wall_seconds" else f"`{cost}`"
    s = Section(sid, f"Work-precision: {metric} against {what}{title_of}", "figure")
    runs = [r for r in (sweep.runs if runs is None else runs) if r.kind == "run"]
    floor_col = floor_column(sweep, metric)
    has_floor = floor_col in sweep.columns
    drawn, skipped = [], []
    for r in runs:
        e, w = r.num(metric), r.num(cost)
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
    series = (_series_names(drawn, sweep) if by is None else
              {r.id: f"{by} = {r.get(by) or _overrides(sweep).get(r.id, {}).get(by, '–')}"
               for r in drawn})
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
            series=series[r.id], color=c, marker=mk, x=r.num(cost),
            xlo=r.num(cost + "_min"), xhi=r.num(cost + "_max"), y=r.num(metric),
            floor=fl if finite(fl) and fl > 0 else None, dt=r.dt, run=r))
    panels = [(f"mesh {m}" if m else "mesh (not recorded)", points[m]) for m in meshes]
    reps = repeats_text(drawn)
    xlabel = (f"time-loop wall time [s] ({reps})" if cost == "wall_seconds" else
              f"{cost} ({reps})")
    files, left_out, guides = F.fig_work_precision(
        ctx["out"], stem, panels, metric_label(metric), xlabel,
        f"{metric}: {metric_text(metric)}", f"reference uncertainty ({floor_col})")
    s.files = files
    s.runs = [r.id for r in drawn]
    s.sources = [sweep.dir]
    s.series = {name: sum(1 for r in drawn if series[r.id] == name) for name in names}
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
        rows.append([f"`{r.id}`", series[r.id], r.mesh or "–", dt_cell(r), wall_cell(r, cost),
                     fmt_g(r.num("repeats")),
                     (f"< {fmt_g(fl)}" if below else fmt_g(e, 4))]
                    + ([fmt_g(fl) if finite(fl) else "–"] if has_floor else [])
                    + ["; ".join(note), f"`{r.get('reference_run')}`" if r.get("reference_run")
                       else "–"])
    for r, why in skipped:
        rows.append([f"`{r.id}`", scheme_name(r.scheme), r.mesh or "–", dt_cell(r),
                     wall_cell(r, cost), fmt_g(r.num("repeats")), f"not drawn: {why}"]
                    + (["–"] if has_floor else []) + ["–", f"`{r.get('reference_run')}`"
                                                      if r.get("reference_run") else "–"])
    u = f" [{unit}]" if unit else ""
    s.extra.append((sid + "_data", f"The points of the `{metric}` diagram",
                    ["run", "series", "mesh", "Δt (s)",
                     ("wall time, time loop (s)" if cost == "wall_seconds" else f"{cost} (s)")
                     + ": median (min–max)", "repeats", metric + u]
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
        f"`{metric}`{u} ({metric_text(metric)}) against "
        + ("the time-loop wall time " if cost == "wall_seconds" else "")
        + f"(`{cost}`; {reps}"
        + (f"; bars: fastest to slowest repeat, `{cost}_min`–`{cost}_max`"
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
        + _reference_text(drawn) + " References: " + (", ".join(f"`{x}`" for x in refs) if refs else "–") + "."
        + (" Not drawn: " + ", ".join(f"`{r.id}` ({why})" for r, why in skipped) + "."
           if skipped else "")
        + " Runs: " + ", ".join(f"`{i}`" for i in s.runs) + ".")
    return s


# ---------------------------------------------------------------------------------------------
# Scheme limits: how far apart the schemes are at their smallest Δt, per mesh

SCHEME_ORDER = ("semi_explicit", "implicit", "explicit_penalty")
SHARED_REFERENCE_GROUP = "reference"   # the folder / group of the shared reference's runs


def _scheme_rank(scheme):
    return (SCHEME_ORDER.index(scheme), "") if scheme in SCHEME_ORDER else (len(SCHEME_ORDER),
                                                                            scheme)


def probe_difference(ra, rb, probe="P"):
    """max over time of |u_P,a(t) − u_P,b(t)| (Euclidean, history columns <P>_ux, <P>_uy): at
    the samples of the run with fewer samples (ra's on a tie), the other run interpolated
    linearly in time; samples outside the other run's time span are skipped. None when a
    history or the probe is missing or no sample is compared."""
    ha, hb = ra.history(), rb.history()
    cx, cy = f"{probe}_ux", f"{probe}_uy"
    if ha is None or hb is None or any(c not in h for h in (ha, hb) for c in (cx, cy, "time")):
        return None
    if len(hb["time"]) < len(ha["time"]):
        ha, hb = hb, ha
    t, tb = ha["time"], hb["time"]
    tol = 1e-9 * max(abs(tb[0]), abs(tb[-1]))
    m = (t >= tb[0] - tol) & (t <= tb[-1] + tol)
    if not m.any():
        return None
    dx = ha[cx][m] - np.interp(t[m], tb, hb[cx])
    dy = ha[cy][m] - np.interp(t[m], tb, hb[cy])
    d = np.hypot(dx, dy)
    d = d[np.isfinite(d)]
    return float(d.max()) if d.size else None


def _summary_num(r, *keys):
    """A number of the run's summary.json (nested keys), else None."""
    v = r.summary()
    for k in keys:
        if not isinstance(v, dict) or k not in v:
            return None
        v = v[k]
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return None
    return float(v) if math.isfinite(v) else None


def energy_loss(r):
    """1 − E_end/E_0: E_end = the last history row's total_energy + contact_energy (the energy
    held in penalty springs counts), E_0 = summary.json initial_energy. None when missing."""
    h = r.history()
    e0 = _summary_num(r, "initial_energy")
    if e0 is None:
        e0 = r.num("initial_energy")
    if h is None or "total_energy" not in h or not e0:
        return None
    e = float(h["total_energy"][-1])
    if "contact_energy" in h and math.isfinite(h["contact_energy"][-1]):
        e += float(h["contact_energy"][-1])
    return 1.0 - e / e0 if math.isfinite(e) else None


def rebound_velocity(r):
    """(v_x, v_y): summary.json rebound_velocity_x/_y, else final.momentum_x/_y ÷ total_mass."""
    vx, vy = _summary_num(r, "rebound_velocity_x"), _summary_num(r, "rebound_velocity_y")
    if vx is not None and vy is not None:
        return vx, vy
    px, py = _summary_num(r, "final", "momentum_x"), _summary_num(r, "final", "momentum_y")
    m = _summary_num(r, "total_mass")
    if px is not None and py is not None and m:
        return px / m, py / m
    return None


def normal_impulse(r):
    v = _summary_num(r, "contact_impulse_normal")
    return v if v is not None else r.num("contact_impulse_normal")


def compare_runs(ra, rb, probe="P"):
    """The scheme-limits measures of run rb against the base run ra (None where missing)."""
    la, lb = energy_loss(ra), energy_loss(rb)
    va, vb = rebound_velocity(ra), rebound_velocity(rb)
    ia, ib = normal_impulse(ra), normal_impulse(rb)
    return {
        "probe": probe_difference(ra, rb, probe),
        "loss_a": la, "loss_b": lb,
        "loss_diff": lb - la if la is not None and lb is not None else None,
        "velocity": (math.hypot(vb[0] - va[0], vb[1] - va[1])
                     if va is not None and vb is not None else None),
        "impulse": ib - ia if ia is not None and ib is not None else None,
    }


def _pct(x):
    return "–" if x is None else f"{fmt_g(100 * x)} %"


def _pp(x):
    return "–" if x is None else ("+" if x > 0 else "") + fmt_g(100 * x)


def _run_cell(r):
    auto = ", automatic" if r.get("dt_mode") == "auto" else ""
    fsi = r.num("penalty_scale_factor")
    return (f"`{r.id}` ({scheme_name(r.scheme)}"
            + (f", f_si = {fmt_g(fsi)}" if fsi is not None else "")
            + f", Δt = {fmt_dt(r.dt)} s{auto})")


def scheme_limit_pairs(sweep):
    """[(mesh label, elements, base run, compared run)], meshes by elements: per (case, mesh),
    each scheme's ok run with the smallest Δt (the groups' own reference runs included, the
    shared reference's runs not), every other scheme against the base scheme (semi-explicit
    where it ran)."""
    cands = [r for r in sweep.runs if r.ok and r.group != SHARED_REFERENCE_GROUP
             and r.dt is not None and r.scheme and r.mesh]
    cases = {r.get("case") for r in cands}
    by_mesh = {}
    for r in cands:
        by_mesh.setdefault((r.get("case"), r.mesh), []).append(r)
    out = []
    for (case, mesh), rs in by_mesh.items():
        finest_of = {}
        for r in rs:   # smallest Δt per scheme; the first in the sweep's order on a tie
            if r.scheme not in finest_of or r.dt < finest_of[r.scheme].dt * (1 - 1e-9):
                finest_of[r.scheme] = r
        if len(finest_of) < 2:
            continue
        schemes = sorted(finest_of, key=_scheme_rank)
        base = finest_of[schemes[0]]
        els = [r.num("elements") for r in rs if r.num("elements") is not None]
        label = mesh + (f" ({case})" if len(cases) > 1 and case else "")
        for sc in schemes[1:]:
            out.append((label, els[0] if els else None, base, finest_of[sc]))
    out.sort(key=lambda p: (p[1] if p[1] is not None else math.inf, p[0],
                            _scheme_rank(p[3].scheme)))
    return out


def shared_reference_pair(sweep):
    """(reference run, check run) of the sweep's [reference], or None."""
    refs = [r for r in sweep.runs if r.group == SHARED_REFERENCE_GROUP]
    for ref in refs:
        if ref.id.endswith("-check"):
            continue
        chk = next((r for r in refs if r.id == ref.id + "-check"), None)
        if chk is not None:
            return ref, chk
    return None


def _trend(values, unit):
    """'a u (M1) → b u (M2), shrinking with every refinement (×r overall)' over the meshes in
    order; '–' without values."""
    vals = [(m, v) for m, v in values if v is not None]
    if not vals:
        return "–"
    text = " → ".join(f"{fmt_g(v)} {unit} ({m})" for m, v in vals)
    vs = [v for _, v in vals]
    if len(vs) >= 2:
        if all(b < a for a, b in zip(vs, vs[1:])):
            text += (", shrinking with every refinement" if len(vs) > 2 else
                     ", shrinking with refinement") + (
                f" (×{vs[-1] / vs[0]:.2g} from {vals[0][0]} to {vals[-1][0]})" if vs[0] else "")
        elif all(b > a for a, b in zip(vs, vs[1:])):
            text += ", growing with refinement"
        else:
            text += ", not monotonic in the mesh"
    return text


def scheme_limits_section(ctx, sweep, Section, sid="scheme_limits", title_of=""):
    s = Section(sid, f"Scheme limits: how far apart the schemes are at their smallest Δt, per "
                f"mesh{title_of}", "table")
    probe = ((sweep.meta.get("reference") or {}).get("error_probe")
             if isinstance(sweep.meta.get("reference"), dict) else None) or "P"
    pairs = scheme_limit_pairs(sweep)
    refpair = shared_reference_pair(sweep)
    if not pairs:
        s.available = False
        s.missing = (f"no mesh of {sweep.dir} has ok runs of two schemes.")
        return s
    s.header = ["mesh: compared vs base scheme", "elements", "base run", "compared run",
                f"{probe} trajectory difference, max over time (m)",
                "energy loss 1 − E_end/E₀, base (%)", "energy loss, compared (%)",
                "energy loss, compared − base (% points)",
                "rebound velocity difference |v_compared − v_base| (m/s)",
                "normal contact impulse, compared − base (N·s)"]
    results = []
    for label, els, a, b in pairs:
        c = compare_runs(a, b, probe)
        results.append((label, a, b, c))
        s.rows.append([f"{label}: {scheme_name(b.scheme)} vs {scheme_name(a.scheme)}",
                       fmt_g(els) if els is not None else "–", _run_cell(a), _run_cell(b),
                       fmt_g(c["probe"]), _pct(c["loss_a"]), _pct(c["loss_b"]),
                       _pp(c["loss_diff"]), fmt_g(c["velocity"]), fmt_g(c["impulse"])])
        s.runs += [x for x in (a.id, b.id) if x not in s.runs]
    refc = None
    if refpair:
        ref, chk = refpair
        meshes = " / ".join(dict.fromkeys(m for m in (ref.mesh, chk.mesh) if m)) or "–"
        if ref.ok and chk.ok:
            refc = compare_runs(ref, chk, probe)
        else:
            refc = dict.fromkeys(("probe", "loss_a", "loss_b", "loss_diff", "velocity",
                                  "impulse"))
        els = ref.num("elements")
        s.rows.append([f"reference uncertainty (check − reference, {meshes})",
                       fmt_g(els) if els is not None else "–", _run_cell(ref), _run_cell(chk),
                       fmt_g(refc["probe"]), _pct(refc["loss_a"]), _pct(refc["loss_b"]),
                       _pp(refc["loss_diff"]), fmt_g(refc["velocity"]),
                       fmt_g(refc["impulse"])])
        s.runs += [ref.id, chk.id]
    s.sources = [sweep.dir]
    # the trend, per compared scheme pair, over the meshes in order of elements
    kinds = list(dict.fromkeys((b.scheme, a.scheme) for _, a, b, _ in results))
    trends = []
    for sb, sa in kinds:
        rows = [(lab, c) for lab, a, b, c in results if (b.scheme, a.scheme) == (sb, sa)]
        trends.append(
            f"{scheme_name(sb)} vs {scheme_name(sa)}: {probe} difference "
            + _trend([(lab, c["probe"]) for lab, c in rows], "m") + "; rebound velocity "
            "difference " + _trend([(lab, c["velocity"]) for lab, c in rows], "m/s") + "; "
            "energy loss difference "
            + (", ".join(f"{_pp(c['loss_diff'])} ({lab})" for lab, c in rows
                         if c["loss_diff"] is not None) or "–") + " % points")
    unequal = [f"{lab} ({scheme_name(b.scheme)} at {fmt_dt(b.dt)} s, {scheme_name(a.scheme)} at "
               f"{fmt_dt(a.dt)} s)" for lab, a, b, _ in results if not _same_dt(a.dt, b.dt)]
    pens = [r for r in (x for _, a, b, _ in results for x in (a, b))
            if r.num("penalty_scale_factor") is not None]
    if refpair:
        pens += [r for r in refpair if r.num("penalty_scale_factor") is not None]
    pens = list({r.id: r for r in pens}.values())
    pen_text = (" Penalty runs (f_si = `penalty_scale_factor`): their difference to a "
                "bi-potential run includes the penetration that the springs allow, "
                "`penetration_max` " + ", ".join(
                    f"{fmt_g(r.num('penetration_max'))} m ({r.mesh}, f_si = "
                    f"{fmt_g(r.num('penalty_scale_factor'))})" for r in pens) + "."
                if pens else "")
    ref_text = ""
    if refpair:
        ref, chk = refpair
        ref_text = (f" Last row: the sweep's shared reference `{ref.id}` against its check run "
                    f"`{chk.id}`, measured the same way (check − reference): the reference's own "
                    "uncertainty (the `floor_*` columns measure the same pair)"
                    + (f", {probe} difference {fmt_g(refc['probe'])} m and rebound velocity "
                       f"difference {fmt_g(refc['velocity'])} m/s"
                       if refc and refc["probe"] is not None
                       else " (not measured: a run missing or not ok)")
                    + (f"; as the check run is {scheme_name(chk.scheme)} and the reference "
                       f"{scheme_name(ref.scheme)}, it is also that pair's difference on "
                       f"{ref.mesh} ({fmt_g(ref.num('elements'))} elements)"
                       if chk.scheme != ref.scheme else "") + ".")
    s.caption = (
        "Per mesh (ordered by elements; `elements` of summary.csv), each scheme's ok run with "
        "the smallest Δt on that mesh (the groups' own reference runs included, the shared "
        "reference's runs not), compared with the base scheme's (semi-explicit where it ran). "
        f"**{probe} trajectory difference**: max over time of the Euclidean distance between "
        f"the two runs' probe {probe} (history.csv `{probe}_ux`, `{probe}_uy`), at the samples of "
        "the run with fewer samples, the other run interpolated linearly in time, samples "
        "outside its time span skipped. **Energy loss**: 1 − E_end/E₀, E_end = the last history "
        "row's `total_energy` + `contact_energy` (the energy held in penalty springs counts), "
        "E₀ = summary.json `initial_energy`. **Rebound velocity difference**: |v_compared − "
        "v_base| of summary.json `rebound_velocity_x`, `rebound_velocity_y` (else "
        "`final.momentum_x`, `_y` ÷ `total_mass`). **Normal contact impulse**: the difference "
        "of summary.json `contact_impulse_normal`. – : a value missing (no history, no probe, "
        "no summary key). Trend over the meshes: " + "; ".join(trends) + "."
        + (" The two runs' Δt differ on " + "; ".join(unequal) + ": there the difference also "
           "holds the time-discretisation error of the larger Δt, not only the schemes' limits."
           if unequal else "")
        + ref_text + pen_text + " Runs: " + ", ".join(f"`{i}`" for i in s.runs) + ".")
    return s


def _same_dt(a, b):
    return a is not None and b is not None and abs(a - b) <= 1e-9 * max(abs(a), abs(b))
