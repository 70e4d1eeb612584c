"""The long runs' page (cases/long_runs/study.toml, docs/stability.md, Long runs): the plug-in
for what its layout's data kinds cannot say (docs/studies.md, Writing a plug-in).

The sweep of the long runs with the drift.csv that drift.py (beside this file) writes into it.
`long_runs` gives two sections: the energy residual R / E_ref against the step (drift.py's
residual, imported, not copied), one panel per scene, and the drift.csv table. Rows that
failed or have empty cells are tabled as such, never a crash."""

import csv
import json
import os

import numpy as np

from matplotlib.ticker import FixedLocator, FuncFormatter, NullLocator
from report_figures import color, plt, save
from report_io import fmt_dt, fmt_g, fnum, read_case, resolve_case_file, scheme_name
from report_page import Section, unavailable

try:   # drift.py beside this file (the study folder is on sys.path while a plug-in imports)
    import drift as DRIFT
except ImportError:   # pragma: no cover - a study folder without drift.py
    DRIFT = None


def _short(run_id):
    return run_id.rsplit("/", 1)[-1]


LONG_SWEEP_CMD = "build/ricochet sweep cases/long_runs/sweep.toml --out results/long_runs --jobs 2"
LONG_DRIFT_CMD = "/usr/bin/python3 cases/long_runs/drift.py results/long_runs"
LONG_CMD = f"{LONG_SWEEP_CMD}`, then `{LONG_DRIFT_CMD}"
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
        return DRIFT.residual, None
    except AttributeError as e:   # drift.py missing or without residual()
        return None, str(e)


def _drift_units():
    """{column: (unit, meaning)} of drift.csv, from cases/long_runs/drift.py's COLUMNS."""
    try:
        COLUMNS = DRIFT.COLUMNS
    except AttributeError:
        return {}
    return {c[0]: (c[1], c[2]) for c in COLUMNS if len(c) >= 3}


def _scene_title(sweep, group):
    if group in SCENES:
        return SCENES[group]
    run = next((r for r in sweep.runs if r.group == group), None)
    if run is not None:
        try:
            over = json.loads(run.get("overrides") or "[]")
            path = resolve_case_file(run.get("case_file"))
            desc = read_case(path, [str(o) for o in over]).get("description") if path else None
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
        return unavailable([fig, tab], "no long-run sweep", ctx.get("long_err"), LONG_CMD)
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
        fig.files = fig_long_runs(ctx["out"], "long_runs_residual", panels)  # PNG only: dense
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



def fig_long_runs(outdir, stem, panels):
    """Long runs: panels = [(title, [(label, scheme, step numbers, R / E_ref)])]; one panel per
    scene, a line per scheme, symmetric log y axis (linear within the smallest residual's
    decade, shaded)."""
    n = len(panels)
    nc = 2 if n > 1 else 1
    nr = (n + nc - 1) // nc
    fig, axes = plt.subplots(nr, nc, figsize=(6.2 * nc, 3.9 * nr), squeeze=False)
    for ax, (title, lines) in zip(axes.flat, panels):
        peaks = [float(np.nanmax(np.abs(r))) for _, _, _, r in lines
                 if np.isfinite(r).any() and np.nanmax(np.abs(r)) > 0]
        lin = max(min(peaks) / 10, 1e-12) if peaks else 1e-12
        for label, scheme, steps, r in lines:
            ax.plot(steps, r, color=color(scheme), lw=0.8, label=label)
        ax.set_yscale("symlog", linthresh=lin, linscale=1.0)
        ax.axhspan(-lin, lin, color="0.9", lw=0, zorder=0)
        ax.axhline(0.0, color="k", lw=0.6)
        # ticks: 0 and ±10^k beyond the linear band, every other decade when there are many
        y0, y1 = ax.get_ylim()
        k0 = int(np.ceil(np.log10(3 * lin)))      # no tick crowding the 0 tick
        k1 = int(np.ceil(np.log10(max(abs(y0), abs(y1), lin * 10))))
        step = 1 if k1 - k0 <= 4 else 2
        ks = list(range(k1, k0 - 1, -step))
        ticks = [0.0] + [s * 10.0 ** k for k in ks for s in (1, -1)
                         if (y0 <= s * 10.0 ** k <= y1)]
        ax.yaxis.set_major_locator(FixedLocator(sorted(ticks)))
        ax.yaxis.set_minor_locator(NullLocator())
        ax.yaxis.set_major_formatter(FuncFormatter(
            lambda v, _: "0" if v == 0 else
            ("−" if v < 0 else "") + f"10$^{{{int(round(np.log10(abs(v))))}}}$"))
        ax.set_title(title, fontsize=9.5)
        ax.set_xlabel("time step n = t / Δt")
        ax.set_ylabel(f"energy residual R / E_ref (–)\nsymlog, linear within ±{fmt_g(lin, 1)}",
                      fontsize=8.5)
        ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:,.0f}".replace(",", " ")))
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=1, frameon=False,
                  fontsize=8)
    for ax in list(axes.flat)[n:]:
        ax.set_visible(False)
    fig.tight_layout(h_pad=2.0)
    return save(fig, outdir, stem, svg=False)   # 1e4 samples a line: no SVG


# ---------------------------------------------------------------------------------------------
# The plug-in's entry

def long_runs(ctx, section):
    """The residual figure and the drift table of the layout's sweep."""
    return long_run_sections({"out": ctx.out, "long": ctx.sweep(section["sweep"])}, Section)
