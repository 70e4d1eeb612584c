"""The Kim–Kwak-type study's plug-in (cases/kim_kwak/study.toml; docs/studies.md, Writing a
plug-in): the rubber ball, rubber block, V groove and bump of
cases/kim_kwak/rubber_groove.toml (docs/kim-kwak-type.md). No closed-form answer exists, so the
part shows the motion and what the gates of cases/kim_kwak/gates.toml check, from two sources:

  * the sweep of cases/kim_kwak/sweep.toml (five runs: semi-explicit at two steps, implicit,
    explicit penalty with and without the soft constraint): a figure of every run's energy
    error and ball velocity over time, and a table of every run with the gate result;
  * a run of the case with its fields (fields/*.vtu): the deformed shapes of both bodies at each
    field time, with the rigid groove and bump read from the case file the run used.

A source that is missing gives "not available" sections with the command that produces it.
"""

import json
import os

import numpy as np

import report_fields as RF
import report_figures as F
from report_page import Section as PageSection
from report_runs import column_labels, gates_result, order_runs
from report_io import (REPO, field_files, fmt_dt, fmt_g, read_case, read_vtu,
                       resolve_case_file, scheme_name)

KK_CMD = ("build/ricochet sweep cases/kim_kwak/sweep.toml --out results/kim_kwak "
          "--check cases/kim_kwak/gates.toml")
FIELDS_CMD = "build/ricochet run cases/kim_kwak/rubber_groove.toml --out results/rubber_groove"
CASE = "rubber_groove"
CASE_FILE = os.path.join("cases", "kim_kwak", "rubber_groove.toml")
GATES_FILE = os.path.join("cases", "kim_kwak", "gates.toml")
DOC = os.path.join(REPO, "docs", "kim-kwak-type.md")
PART_TITLE = "Kim–Kwak-type problem: rubber ball, rubber block, V groove and bump"
MAX_PANELS = 12
ENERGY_BOUND = 0.02  # the paper's bound, drawn on the energy-error panel


# ---------------------------------------------------------------------------------------------
# Sources

def kk_runs(sweep):
    runs = [r for r in sweep.runs if r.kind == "run"]
    if any(r.get("case") for r in runs):
        runs = [r for r in runs if r.get("case") == CASE]
    return order_runs(runs)


def doc_link(out):
    """docs/kim-kwak-type.md, linked relative to the report folder."""
    return f"[docs/kim-kwak-type.md]({os.path.relpath(DOC, out)})"


def last(h, name):
    return float(h[name][-1]) if h is not None and name in h and len(h[name]) else None


# ---------------------------------------------------------------------------------------------
# Figures

def fig_histories(outdir, stem, runs):
    """runs = [(label, run)]: energy_error (%) and ball_centre_vx against time, one line each."""
    plt = F.plt
    fig, axes = plt.subplots(1, 2, figsize=(11.5, 4.3))
    styles = F._styles(runs)
    tend = 0.0
    for (label, r), st in zip(runs, styles):
        h = r.history()
        t = F.ms(h["time"])
        tend = max(tend, float(t[-1]))
        axes[0].plot(t, 100 * h["energy_error"], lw=1.3, label=label, **st)
        if "ball_centre_vx" in h:
            axes[1].plot(t, h["ball_centre_vx"], lw=1.3, label=label, **st)
    axes[0].axhline(100 * ENERGY_BOUND, color="k", ls=":", lw=1.1,
                    label=f"{100 * ENERGY_BOUND:g} % (the paper's bound)")
    axes[0].set_ylabel("energy error |E_t + D − E_t(0)| / E_t(0) (%)")
    axes[0].set_title("energy balance (energy_error)")
    axes[1].axhline(0.0, color="k", lw=0.8)
    axes[1].set_ylabel("ball centre velocity v_x (m/s)")
    axes[1].set_title("ball centre, horizontal velocity (ball_centre_vx)")
    for ax in axes:
        ax.set_xlabel("time t (ms)")
        ax.set_xlim(0, tend)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, 0.0), ncol=3,
               frameon=False)
    fig.tight_layout()
    return F.save(fig, outdir, stem)


def interfaces(h):
    """The contact interfaces of a history (docs/outputs.md): the names N with the columns
    N_normal_force and N_contact_nodes, in column order."""
    names = list(h.dtype.names) if hasattr(h, "dtype") else list(h.keys())
    return [c[:-len("_normal_force")] for c in names
            if c.endswith("_normal_force") and c != "normal_force"
            and c[:-len("_normal_force")] + "_contact_nodes" in names]


def fig_interfaces(outdir, stem, runs, names):
    """One panel per contact interface: its normal force (N) against time, one line per run."""
    plt = F.plt
    n = len(names)
    fig, axes = plt.subplots(1, n, figsize=(4.0 * n + 0.6, 4.0), squeeze=False)
    axes = axes.ravel()
    styles = F._styles(runs)
    tend = 0.0
    for (label, r), st in zip(runs, styles):
        h = r.history()
        t = F.ms(h["time"])
        tend = max(tend, float(t[-1]))
        for ax, name in zip(axes, names):
            col = name + "_normal_force"
            if col in h:
                ax.plot(t, h[col], lw=1.1, label=label, **st)
    for ax, name in zip(axes, names):
        ax.set_title(f"{name} ({name}_normal_force)")
        ax.set_xlabel("time t (ms)")
        ax.set_xlim(0, tend)
    axes[0].set_ylabel("normal force Σ r_n (N)")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, 0.0), ncol=3,
               frameon=False)
    fig.tight_layout()
    return F.save(fig, outdir, stem)


# ---------------------------------------------------------------------------------------------
# Sections

def _no_sweep(ctx, s):
    err = ctx.get("kk_err")
    s.available = False
    s.missing = (("the Kim–Kwak-type sweep could not be read (" + err + "). " if err else
                  "no Kim–Kwak-type sweep. ") +
                 f"Run `{KK_CMD}`.")
    return s


def sec_shapes(ctx, Section, sid, title):
    s = Section(sid, title, "figure")
    given = ctx.get("kk_fields")
    fdir = RF.find_fields(given)
    if fdir is None:
        s.available = False
        s.missing = ((f"no fields/*.vtu in `{given}`. " if given else
                      "no run of the Kim–Kwak-type case with fields. ") +
                     f"Run `{FIELDS_CMD}`.")
        return s
    run_dir = os.path.dirname(fdir) if os.path.basename(fdir) == "fields" else fdir
    summ = {}
    try:
        with open(os.path.join(run_dir, "summary.json")) as f:
            summ = json.load(f)
    except (OSError, ValueError):
        summ = {}
    files = field_files(fdir)
    skipped = 0
    if len(files) > MAX_PANELS:
        keep = np.unique(np.round(np.linspace(0, len(files) - 1, MAX_PANELS)).astype(int))
        skipped = len(files) - len(keep)
        files = [files[i] for i in keep]
    frames = [(t, read_vtu(p)) for t, p in files]
    # the obstacles: from the case file the run names, with its overrides
    case_note = ""
    case_path = resolve_case_file(summ.get("case_file"))
    if case_path is None:
        case_path = resolve_case_file(CASE_FILE)
        case_note = (f" The run's case file (`{summ.get('case_file')}`) was not found; the "
                     if summ.get("case_file") else " The run has no summary.json; the ")
        case_note += f"obstacles are drawn from `{CASE_FILE}`."
    obstacles = []
    if case_path:
        case = read_case(case_path, summ.get("overrides") or [])
        obstacles = [o for o in case.get("obstacles", []) if isinstance(o, dict)]
    probes = [(p.get("name", "?"), int(p["node"])) for p in summ.get("probes", [])
              if isinstance(p.get("node"), int)]
    scheme = scheme_name(summ.get("scheme", "")) or "?"
    dt = summ.get("dt")
    title_run = (f"{summ.get('case', CASE)}, {scheme}"
                 + (f", Δt = {fmt_dt(dt)} s" if isinstance(dt, (int, float)) else ""))
    s.files = RF.fig_shapes_2d(ctx["out"], "kim_kwak_shapes", frames, obstacles, probes, title_run)
    rid = _show(run_dir)
    s.runs = [rid]
    s.sources = [fdir] + ([case_path] if case_path else [])
    vm = [(t, float(np.max(v["cell_data"]["von_mises"]))) for t, v in frames
          if "von_mises" in v["cell_data"]]
    ov = summ.get("overrides") or []
    s.caption = (
        "The deformed meshes of both bodies (true scale, cell outlines), "
        + ("coloured by the cell von Mises stress on one scale, " if vm else "")
        + "at each field time of the run (" + ", ".join(f"{t * 1e3:.3g}" for t, _ in frames)
        + " ms; fields/*.vtu), with the rigid obstacles ("
        + (", ".join(f"{o.get('name', '?')}: {o.get('type', 'line')}" for o in obstacles)
           or "none found")
        + f") as the case file `{_show(case_path) if case_path else '?'}` gives them"
        + (" with the run's overrides " + ", ".join(f"`{o}`" for o in ov) if ov else "")
        + "." + case_note
        + (" Markers: the probe nodes " + ", ".join(f"`{n}`" for n, _ in probes) + "."
           if probes else "")
        + (" Largest cell von Mises stress per instant: "
           + ", ".join(f"{t * 1e3:.3g} ms: {fmt_g(m)} Pa" for t, m in vm) + "." if vm else "")
        + (f" {skipped} further field times are not drawn." if skipped else "")
        + f" Run: `{rid}` ({title_run}).")
    return s


def _show(p):
    p = os.path.abspath(p)
    return os.path.relpath(p, REPO) if p.startswith(REPO + os.sep) else p


def _ok_runs(kk, column=None):
    """(the case's runs, [(label, run)] of those ok with a history (holding `column`))."""
    runs = kk_runs(kk)
    labels = column_labels(runs)
    ok = [(labels[r.id], r) for r in runs if r.ok and r.history() is not None
          and (column is None or column in r.history())]
    return runs, ok


def sec_histories(ctx, Section, sid, title):
    s = Section(sid, title, "figure")
    kk = ctx.get("kk")
    if kk is None:
        return _no_sweep(ctx, s)
    runs, ok = _ok_runs(kk, "energy_error")
    if not ok:
        s.available = False
        s.missing = (f"no ok run of case `{CASE}` with a history in {kk.dir}. Run `{KK_CMD}`.")
        return s
    s.files = fig_histories(ctx["out"], "kim_kwak_histories", ok)
    s.runs = [r.id for _, r in ok]
    s.sources = [kk.dir]
    parts, v0 = [], None
    for lab, r in ok:
        h = r.history()
        v0 = v0 if v0 is not None or "ball_centre_vx" not in h else float(h["ball_centre_vx"][0])
        vx = last(h, "ball_centre_vx")
        parts.append(f"{lab}: {100 * float(np.max(h['energy_error'])):.2f} %"
                     + (f", v_x = {vx:.2f} m/s" if vx is not None else ""))
    left = [r.id for r in runs if r.id not in {x.id for _, x in ok}]
    s.caption = (
        "Left: the relative error of the energy balance |E_t(t) + D(t) − E_t(0)| / E_t(0) "
        "(`energy_error` of history.csv, D the friction dissipation), dotted: the paper's 2 %. "
        "Right: the horizontal velocity of the ball's centre (probe `ball_centre`, "
        "`ball_centre_vx`, the velocity of one node, so it carries the ball's vibration)"
        + (f": thrown at {v0:.3g} m/s" if v0 is not None else "")
        + ", it is stopped by the block and rebounds to the left. Colour = scheme; a second "
        "run of one scheme is dashed. Largest energy error and final v_x: "
        + "; ".join(parts) + "."
        + (f" Not drawn (not ok or no history): {', '.join(f'`{i}`' for i in left)}."
           if left else "")
        + f" Runs (sweep `{kk.dir}`): " + "; ".join(f"{lab}: `{r.id}`" for lab, r in ok) + ".")
    return s


def sec_interfaces(ctx, Section, sid, title):
    s = Section(sid, title, "figure")
    kk = ctx.get("kk")
    if kk is None:
        return _no_sweep(ctx, s)
    _, ok = _ok_runs(kk)
    names = []
    for _, r in ok:
        names += [n for n in interfaces(r.history()) if n not in names]
    if not names:
        s.available = False
        s.missing = (f"no run of case `{CASE}` in {kk.dir} has per-interface history columns "
                     f"(`<name>_normal_force`, docs/outputs.md). Run `{KK_CMD}`.")
        return s
    s.files = fig_interfaces(ctx["out"], "kim_kwak_interfaces", ok, names)
    s.runs = [r.id for _, r in ok]
    s.sources = [kk.dir]
    parts = []
    for lab, r in ok:
        h = r.history()
        peaks = []
        for n in names:
            if n + "_normal_force" not in h:
                continue
            f, c = h[n + "_normal_force"], h[n + "_contact_nodes"]
            on = np.nonzero(c > 0)[0]
            first = f"{1e3 * float(h['time'][on[0]]):.2f} ms" if len(on) else "never"
            peaks.append(f"{n} {fmt_g(float(np.max(f)))} N (from {first})")
        parts.append(f"{lab}: " + ", ".join(peaks))
    s.caption = (
        "The normal contact force of each interface against time: each rigid obstacle and "
        "each contact pair has its own history columns (`<name>_normal_force`, "
        "`_tangential_force`, `_contact_nodes`, `_contact_work`, `_friction_dissipation`; "
        "docs/outputs.md), which add up to the summed columns. The groove carries the block "
        "(and, once it lands, the ball), the ball–block pair acts from the strike on, the bump "
        "when the block reaches it. Colour = scheme; a second run of one scheme is dashed. "
        "Peak force and first contact per run: " + "; ".join(parts) + "."
        + f" Runs (sweep `{kk.dir}`): " + "; ".join(f"{lab}: `{r.id}`" for lab, r in ok) + ".")
    return s


def sec_runs(ctx, Section, sid, title):
    s = Section(sid, title, "table")
    kk = ctx.get("kk")
    if kk is None:
        return _no_sweep(ctx, s)
    runs = kk_runs(kk)
    if not runs:
        s.available = False
        s.missing = f"no run of case `{CASE}` in {kk.dir}. Run `{KK_CMD}`."
        return s
    labels = column_labels(runs)
    s.header = ["run", "scheme", "Δt (s)", "energy_error_max", "penetration_max (m)",
                "friction_dissipation (J)", "final ball_centre_vx (m/s)",
                "final block_corner (u_x, u_y) (m)", "wall (s)", "status"]
    for r in runs:
        h = r.history() if r.ok else None
        vx, ux, uy = (last(h, c) for c in ("ball_centre_vx", "block_corner_ux",
                                             "block_corner_uy"))
        e = r.num("energy_error_max")
        s.rows.append([
            f"`{r.id}`", labels[r.id],
            f"{fmt_dt(r.dt)} ({r.get('dt_mode') or 'fixed'})" if r.dt is not None else "–",
            f"{100 * e:.2f} %" if e is not None else "–",
            fmt_g(r.num("penetration_max")), fmt_g(r.num("friction_dissipation")),
            f"{vx:.3g}" if vx is not None else "–",
            f"({ux:.3g}, {uy:.3g})" if ux is not None and uy is not None else "–",
            fmt_g(r.num("wall_seconds")),
            r.status if r.ok else f"**{r.status or 'missing'}**" + (f": {r.reason}" if r.reason
                                                                   else "")])
    s.runs = [r.id for r in runs]
    s.sources = [kk.dir]
    gates, failed = gates_result(kk.dir)
    gate_line = (f"**Gates** (`{GATES_FILE}`, `gates-junit.xml` of the sweep): {gates}"
                 + (" — failed: " + "; ".join(failed) if failed else "") + "."
                 if gates else
                 f"**Gates:** no `gates-junit.xml`: the sweep ran without `--check {GATES_FILE}`.")
    s.caption = (
        f"One row per run of the sweep `{kk.dir}` (summary.csv; the final values are the "
        "last sample of history.csv): Δt and how it was set, the largest energy error, the "
        "largest penetration (between the bodies or into an obstacle), the friction "
        "dissipation, the ball centre's final horizontal velocity and the final displacement "
        "of the block's struck corner (probe `block_corner`), the time-loop wall time. "
        + gate_line)
    return s


# ---------------------------------------------------------------------------------------------
# The plug-in's entries: each reads the layout section's sweep

def _one(fn, sid, title, ctx, section):
    sw = ctx.sweep(section["sweep"])
    legacy = {"out": ctx.out, "kk": sw,
              "kk_fields": next((r.folder for r in sw.runs if RF.find_fields(r.folder)), None)}
    return [fn(legacy, PageSection, sid, title)]


def shapes(ctx, section):
    """The deformed ball and block of the sweep's first run with fields, with the obstacles."""
    return _one(sec_shapes, "kk_shapes", "Deformed shapes of the ball and the block", ctx, section)


def histories(ctx, section):
    return _one(sec_histories, "kk_histories", "Energy error and ball velocity per run", ctx,
                section)


def contact_forces(ctx, section):
    return _one(sec_interfaces, "kk_interfaces", "Contact forces per interface", ctx, section)


def runs(ctx, section):
    return _one(sec_runs, "kk_runs", "The Kim–Kwak-type runs", ctx, section)
