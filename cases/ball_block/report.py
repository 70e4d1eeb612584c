"""The plug-in of cases/ball_block/study.toml (docs/studies.md, Writing a plug-in): the
Mooney–Rivlin ball striking a free Mooney–Rivlin block (ball_block.toml; docs/three-dimensions.md,
The ball on the block), from two sweeps:

  * the sweep of cases/ball_block/sweep_full.toml (or ball_block_fast.toml): the histories of
    one run per scheme (energy error, normal contact force, deviation of the total momentum from
    its value at t = 0) and a table of every run with the gate result;
  * a run of cases/ball_block/ball_block.toml with its fields: the deformed ball and block at each
    field time, drawn from their boundary faces with matplotlib.

A source that is missing gives "not available" sections with the command that produces it.
"""

import json
import math
import os
import re

import numpy as np

import report_fields as RF
import report_figures as F
from report_page import Section as PageSection
from report_runs import SCHEMES, gates_result
from report_io import REPO, fmt_dt, fmt_g, resolve_case_file, scheme_name, show_path

CASE = "ball_block"
CASE_FILE = os.path.join("cases", "ball_block", "ball_block.toml")
SWEEP_FILE = os.path.join("cases", "ball_block", "sweep_full.toml")
GATES_FILE = os.path.join("cases", "ball_block", "gates_full.toml")
BB_CMD = ("build/ricochet sweep cases/ball_block/sweep_full.toml --out results/ball_block "
          "--check cases/ball_block/gates_full.toml")
FIELDS_CMD = "build/ricochet run cases/ball_block/ball_block.toml --out results/ball_block_fields"
ANCHOR = "#the-ball-on-the-block"
TITLE = "Mooney–Rivlin ball on a free block (3D)"
ENERGY_BOUND = 0.02          # cases/ball_block/gates_common.toml, "energy error below 2 %"
MOMENTUM_TOLERANCE = 1e-14   # the same file: each component of the final momentum, kg m/s
EPS = np.finfo(float).eps

# The colour of each body's faces, by the VTU's cell_data `body`: the index of [[bodies]] in the
# case (0 the ball, 1 the block).
BODY_COLOURS = ("#e8743b", "#4e79a7", "#59a14f", "#b07aa1")


def doc_link(out, text="docs/three-dimensions.md, The ball on the block"):
    return f"[{text}]({os.path.relpath(os.path.join(REPO, 'docs', 'three-dimensions.md'), out)}{ANCHOR})"


# ---------------------------------------------------------------------------------------------
# Runs

def bb_runs(sweep):
    """The ball-on-block runs of a sweep (all of them when the sweep has no `case` column)."""
    runs = [r for r in sweep.runs if r.kind == "run"]
    if any(r.get("case") for r in runs):
        runs = [r for r in runs if r.get("case") == CASE]
    return runs


def frame_updates(r):
    """The contact frame updates of a run: the swept or set key, else the summary's
    `contact_frame_updates` (null there for the paper's frozen frame, 0); None for the penalty
    scheme, which has no contact frame to update."""
    if r.scheme == "explicit_penalty":
        return None
    for key in ("contact.frame_updates", "contact_frame_updates"):
        v = r.num(key)
        if v is not None:
            return int(v)
    return 0


def soft(r):
    """Whether a penalty run has LS-DYNA's soft constraint (penalty.soft)."""
    v = str(r.get("penalty.soft")).strip().lower()
    if v in ("true", "false"):
        return v == "true"
    return (r.num("penalty_soft_scale") or 0.0) > 0.0


def scheme_label(r, coarsest):
    """The scheme with what tells the sweep's runs of one scheme apart."""
    label = scheme_name(r.scheme) or r.scheme or "?"
    if r.scheme == "explicit_penalty":
        label += ", soft constraint" if soft(r) else ", bulk-modulus springs"
    n = r.num("elements")
    if n is not None and coarsest is not None and n > coarsest:
        label += f", fine mesh ({int(n)} cells)"
    return label


def _coarsest(runs):
    cells = [r.num("elements") for r in runs if r.num("elements") is not None]
    return min(cells) if cells else None


def pick_scheme_runs(runs):
    """One ok run per scheme with a history, on the case's mesh: the semi-explicit scheme with
    ten frame updates at 0.9 x the critical step, the implicit scheme with frame updates,
    the penalty scheme with the soft constraint (the case's settings); else the first of the
    scheme."""
    coarsest = _coarsest(runs)
    prefer = {
        "semi_explicit": lambda r: (frame_updates(r) == 10 and r.num("dt_safety") is not None
                                    and abs(r.num("dt_safety") - 0.9) < 1e-9),
        "implicit": lambda r: (frame_updates(r) or 0) > 0,
        "explicit_penalty": soft,
    }
    picked = []
    for scheme in SCHEMES:
        cands = [r for r in runs if r.scheme == scheme and r.ok and r.history() is not None]
        if not cands:
            continue
        cands.sort(key=lambda r: (not prefer[scheme](r),
                                  coarsest is not None and (r.num("elements") or 0) > coarsest,
                                  runs.index(r)))
        picked.append(cands[0])
    return picked


def momentum(h):
    """The total momentum history (rows, 3), or None without the columns."""
    cols = [f"momentum_{c}" for c in "xyz"]
    if h is None or any(c not in h for c in cols):
        return None
    return np.column_stack([h[c] for c in cols])


def momentum_deviation(h):
    """max over the history and the components of |p_i(t) − p_i(row 0)| (kg m/s), or None."""
    p = momentum(h)
    if p is None or not len(p):
        return None
    return float(np.max(np.abs(p - p[0])))


# ---------------------------------------------------------------------------------------------
# Figures

def _shade(polys):
    """A Lambert factor per face (0.5 to 1) from its normal, so that the faces of a body read as
    a surface: light from the viewer's upper left."""
    light = np.array([-0.45, -0.55, 0.70])
    light /= np.linalg.norm(light)
    out = []
    for q in polys:
        n = np.cross(q[2] - q[0], q[-1] - q[1] if len(q) == 4 else q[1] - q[0])
        ln = np.linalg.norm(n)
        out.append(0.5 + 0.5 * abs(float(np.dot(n / ln, light))) if ln > 0 else 0.75)
    return out


def fig_bodies(outdir, stem, frames, names, title):
    """One 3D panel per (time, vtu): the boundary faces of every body (cell_data `body`), each
    body in its own colour, shaded by the faces' orientation, all faces depth-sorted together;
    one view and one box (equal axes, in mm) for all panels. The plot's vertical axis is the
    case's y."""
    from matplotlib.colors import to_rgb
    from matplotlib.patches import Patch
    from matplotlib.ticker import MaxNLocator
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection
    plt = F.plt
    n = len(frames)
    ncol = 2 if n == 4 else min(3, n)
    nrow = math.ceil(n / ncol)
    pts_all = np.vstack([v["points3"] for _, v in frames]) * 1e3
    lo, hi = pts_all.min(axis=0), pts_all.max(axis=0)
    span = float(np.max(hi - lo))
    mid = 0.5 * (lo + hi)
    fig = plt.figure(figsize=(5.4 * ncol, 4.8 * nrow + 0.8))
    seen = set()
    for k, (t, v) in enumerate(frames):
        ax = fig.add_subplot(nrow, ncol, k + 1, projection="3d")
        p = v["points3"] * 1e3
        faces = RF.boundary_faces(v["cells"])   # the faces of one cell only: each body's surface
        body = v["cell_data"].get("body")
        bodies = [int(body[c]) if body is not None else 0 for _, c in faces]
        seen.update(bodies)
        polys = [p[list(f)][:, [0, 2, 1]] for f, _ in faces]   # (x, z, y): y up
        shade = _shade([p[list(f)] for f, _ in faces])
        colours = [tuple(s * np.array(to_rgb(BODY_COLOURS[b % len(BODY_COLOURS)]))) + (1.0,)
                   for b, s in zip(bodies, shade)]
        ax.add_collection3d(Poly3DCollection(polys, facecolors=colours,
                                             edgecolors=(0, 0, 0, 0.3), linewidths=0.2))
        ax.set_xlim(mid[0] - 0.5 * span, mid[0] + 0.5 * span)
        ax.set_ylim(mid[2] - 0.5 * span, mid[2] + 0.5 * span)
        ax.set_zlim(mid[1] - 0.5 * span, mid[1] + 0.5 * span)
        ax.set_box_aspect((1, 1, 1), zoom=0.9)
        ax.view_init(elev=16, azim=-58)
        for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
            axis.set_major_locator(MaxNLocator(5))
        ax.set_xlabel("x (mm)")
        ax.set_ylabel("z (mm)")
        ax.set_zlabel("y (mm)")
        ax.set_title(f"t = {round(t * 1e3, 2):g} ms")
    handles = [Patch(facecolor=BODY_COLOURS[b % len(BODY_COLOURS)], edgecolor="k", lw=0.4,
                     label=names[b] if b < len(names) else f"body {b}") for b in sorted(seen)]
    fig.legend(handles=handles, loc="lower center", ncol=len(handles), frameon=False,
               bbox_to_anchor=(0.5, 0.0))
    fig.suptitle(title, fontsize=10)
    fh = fig.get_figheight()
    fig.subplots_adjust(left=0.02, right=0.95, bottom=0.5 / fh + 0.02, top=1 - 0.65 / fh,
                        wspace=0.12, hspace=0.08)
    return F.save(fig, outdir, stem, svg=False)


def fig_histories(outdir, stem, runs):
    """runs = [(label, run)]: three panels against time: the energy error (%), the summed normal
    contact force (N) and the deviation of the total momentum from its value at t = 0,
    |p(t) − p(0)| (kg m/s, log scale), one line per run."""
    plt = F.plt
    fig, axes = plt.subplots(1, 3, figsize=(15.0, 4.5))
    styles = F._styles(runs)
    tend, p0max = 0.0, 0.0
    for (label, r), st in zip(runs, styles):
        h = r.history()
        t = F.ms(h["time"])
        tend = max(tend, float(t[-1]))
        axes[0].plot(t, 100 * h["energy_error"], lw=1.3, label=label, **st)
        if "normal_force" in h:
            axes[1].plot(t, h["normal_force"], lw=1.2, label=label, **st)
        p = momentum(h)
        if p is not None:
            d = np.linalg.norm(p - p[0], axis=1)
            p0max = max(p0max, float(np.linalg.norm(p[0])))
            axes[2].plot(t, np.where(d > 0, d, np.nan), lw=1.1, marker=".", ms=3, label=label,
                         **st)
    axes[0].axhline(100 * ENERGY_BOUND, color="k", ls=":", lw=1.1,
                    label=f"{100 * ENERGY_BOUND:g} % (the gate, the paper's bound)")
    axes[0].set_ylabel("energy error |E_t + D − E_t(0)| / E_t(0) (%)")
    axes[0].set_title("energy balance (energy_error)")
    axes[1].set_ylabel("normal contact force Σ r_n (N)")
    axes[1].set_title("ball–block contact (normal_force)")
    axes[2].set_yscale("log")
    axes[2].axhline(MOMENTUM_TOLERANCE, color="k", ls="--", lw=1.0,
                    label=f"{MOMENTUM_TOLERANCE:g} kg m/s (the gates' tolerance, per component)")
    if p0max > 0:
        axes[2].axhline(EPS * p0max, color="0.4", ls=":", lw=1.1,
                        label=f"ε |p(0)| = {fmt_g(EPS * p0max, 2)} kg m/s (round-off)")
    lo, hi = axes[2].get_ylim()
    axes[2].set_ylim(min(lo, EPS * p0max / 10 if p0max else lo), max(hi, 10 * MOMENTUM_TOLERANCE))
    axes[2].set_ylabel("|p(t) − p(0)| (kg m/s)")
    axes[2].set_title("total momentum p (momentum_x, _y, _z)")
    for ax in axes:
        ax.set_xlabel("time t (ms)")
        ax.set_xlim(0, tend)
    handles, labels = axes[0].get_legend_handles_labels()
    h2, l2 = axes[2].get_legend_handles_labels()
    extra = [(a, b) for a, b in zip(h2, l2) if b not in labels]
    fig.legend(handles + [a for a, _ in extra], labels + [b for _, b in extra],
               loc="upper center", bbox_to_anchor=(0.5, 0.0), ncol=3, frameon=False)
    fig.tight_layout()
    return F.save(fig, outdir, stem)


# ---------------------------------------------------------------------------------------------
# Sections

def _no_sweep(ctx, s):
    err = ctx.get("bb_err")
    s.available = False
    s.missing = ((f"the sweep could not be read ({err}). " if err else
                  "no sweep of the ball on the block. ")
                 + f"Run `{BB_CMD}`.")
    return s


def _run_dir(fdir):
    return os.path.dirname(fdir) if os.path.basename(fdir) == "fields" else fdir


def sec_shapes(ctx, Section, sid, title):
    s = Section(sid, title, "figure")
    folder = ctx.get("bb_fields")
    fdir, frames = RF.run_frames(folder)
    if not frames:
        s.available = False
        s.missing = ((f"no fields/*.vtu in `{folder}`. " if folder else
                      "no run of the ball on the block with fields. ")
                     + f"Run `{FIELDS_CMD}`.")
        return s
    if any("points3" not in v for _, v in frames):
        s.available = False
        s.missing = f"the fields in `{fdir}` are not 3D."
        return s
    run_dir = _run_dir(fdir)
    try:
        with open(os.path.join(run_dir, "summary.json")) as f:
            summ = json.load(f)
    except (OSError, ValueError):
        summ = {}
    # the bodies' names, in the order of the case's [[bodies]] (the VTU's `body`)
    names = [b.strip() for b in str(summ.get("mesh") or "ball+block").split("+")]
    scheme = scheme_name(summ.get("scheme", "")) or "?"
    dt = summ.get("dt")
    run_title = (f"{summ.get('case', CASE)}, {scheme}"
                 + (f", Δt = {fmt_dt(dt)} s" if isinstance(dt, (int, float)) else ""))
    s.files = fig_bodies(ctx["out"], "ball_block_shapes", frames, names, run_title)
    rid = show_path(run_dir)
    s.runs = [rid]
    s.sources = [fdir]
    vm = []
    for t, v in frames:
        a, b = v["cell_data"].get("von_mises"), v["cell_data"].get("body")
        if a is None or b is None:
            continue
        per = [f"{names[k] if k < len(names) else k} {fmt_g(float(np.max(a[b == k])))} Pa"
               for k in sorted({int(x) for x in b})]
        vm.append(f"{t * 1e3:.3g} ms: " + ", ".join(per))
    ct = (summ.get("contact_iterations") or {}).get("contact_time")
    t0, t1 = summ.get("contact_start_time"), summ.get("contact_end_time")
    case_path = resolve_case_file(summ.get("case_file"))
    s.caption = (
        "The deformed ball (orange) and block (blue), true scale, drawn from their boundary "
        "faces (the faces used by one cell of the VTU's hexahedra), each face shaded by its "
        "orientation, at each field time ("
        + ", ".join(f"{t * 1e3:.3g}" for t, _ in frames) + " ms; fields/*.vtu). One box and "
        "one view for all panels; the picture's vertical axis is the case's y. Nothing else "
        "acts: no gravity, no ground. The ball, thrown at (4, −8, 3) m/s, dents the block's "
        "top face, slides and sticks on it under Coulomb friction (μ = 0.5), and leaves it "
        "spinning; the block, at rest before, moves off and turns"
        + (f"; contact from {fmt_g(t0 * 1e3, 3)} ms to {fmt_g(t1 * 1e3, 3)} ms"
           if isinstance(t0, (int, float)) and isinstance(t1, (int, float)) else "")
        + (f" ({fmt_g(ct * 1e3, 3)} ms in contact)" if isinstance(ct, (int, float)) else "")
        + ". " + ("Largest cell von Mises stress per instant and body: " + "; ".join(vm) + ". "
                  if vm else "")
        + f"Run: `{rid}` ({run_title}"
        + (f"; case file `{os.path.relpath(case_path, REPO)}`" if case_path else "")
        + ("; overrides " + ", ".join(f"`{o}`" for o in summ.get("overrides") or [])
           if summ.get("overrides") else "") + ").")
    return s


def sec_histories(ctx, Section, sid, title):
    s = Section(sid, title, "figure")
    sw = ctx.get("bb")
    if sw is None:
        return _no_sweep(ctx, s)
    runs = bb_runs(sw)
    picked = pick_scheme_runs(runs)
    if not picked:
        s.available = False
        s.missing = f"no ok run of case `{CASE}` with a history in `{sw.dir}`. Run `{BB_CMD}`."
        return s
    coarsest = _coarsest(runs)
    labelled = []
    for r in picked:
        fu = frame_updates(r)
        label = scheme_label(r, coarsest)
        if fu is not None:
            label += f", {fu} frame update{'s' if fu != 1 else ''}"
        labelled.append((label, r))
    s.files = fig_histories(ctx["out"], "ball_block_histories", labelled)
    s.runs = [r.id for r in picked]
    s.sources = [sw.dir]
    parts = []
    for label, r in labelled:
        h = r.history()
        d = momentum_deviation(h)
        f = float(np.max(h["normal_force"])) if "normal_force" in h else None
        parts.append(f"{label}: {fmt_g(100 * float(np.max(h['energy_error'])), 3)} %"
                     + (f", peak force {fmt_g(f)} N" if f is not None else "")
                     + (f", max |p_i − p_i(0)| {fmt_g(d, 2)} kg m/s" if d is not None else ""))
    missing = [sch for sch in SCHEMES if sch not in {r.scheme for r in picked}]
    s.caption = (
        "One run per scheme, on the case's mesh and with its settings (the semi-explicit "
        "scheme with ten contact-frame updates at 0.9 × the critical step, the implicit scheme "
        "at Δt = 1e-4 s with the frames taken where the last Newton iterate left the nodes, "
        "the penalty scheme with the soft constraint). Left: the relative error of the energy "
        "balance (`energy_error` of history.csv, D the friction dissipation), dotted: the "
        "gate's 2 %. Middle: the summed normal contact force between the ball and the block "
        "(`normal_force`). Right: the Euclidean norm of the total momentum's deviation from "
        "history row 0 (`momentum_x`, `_y`, `_z`), log scale; zero (exactly conserved samples, "
        "and row 0 itself) is not drawn. No obstacle and no gravity act, so the contact forces "
        "between the bodies cancel and the momentum stays the ball's initial one: the "
        "deviation stays at round-off, a few ε |p(0)| (dotted), far below the gates' 1e-14 kg m/s "
        "per component (dashed). Largest energy error, peak force and momentum deviation: "
        + "; ".join(parts) + "."
        + (" No ok run of " + ", ".join(scheme_name(x) for x in missing) + "."
           if missing else "")
        + f" Runs (sweep `{sw.dir}`): " + "; ".join(f"{lab}: `{r.id}`" for lab, r in labelled)
        + ".")
    return s


def _status(r):
    return (r.status if r.ok else f"**{r.status or 'missing'}**"
            + (f": {r.reason}" if r.reason else ""))


def _gates_file(sw):
    """The gate file the sweep was checked with: gates_fast.toml for the fast sweep file
    (sweep_fast.toml), else gates_full.toml, in this folder."""
    f = os.path.basename(str(sw.meta.get("sweep_file") or SWEEP_FILE))
    return GATES_FILE.replace("_full", "_fast") if "fast" in f else GATES_FILE


def _sweep_command(sw):
    """The command that wrote the sweep, from its sweep.json, with the gate file when it ran
    with --check (gates-junit.xml)."""
    m = sw.meta
    f = m.get("sweep_file")
    cmd = ("build/ricochet sweep " + (show_path(f) if f else SWEEP_FILE)
           + f" --out {show_path(sw.dir)}")
    if isinstance(m.get("jobs"), int) and m["jobs"] != 1:
        cmd += f" --jobs {m['jobs']}"
    if gates_result(sw.dir)[0]:
        cmd += " --check " + _gates_file(sw)
    return cmd


def sec_runs(ctx, Section, sid, title):
    s = Section(sid, title, "table")
    sw = ctx.get("bb")
    if sw is None:
        return _no_sweep(ctx, s)
    runs = bb_runs(sw)
    if not runs:
        s.available = False
        s.missing = f"no run of case `{CASE}` in `{sw.dir}`. Run `{BB_CMD}`."
        return s
    coarsest = _coarsest(runs)
    s.header = ["run", "scheme", "frame updates", "Δt (s)", "energy_error_max",
                "penetration_max (m)", "friction_dissipation (J)",
                "max |p_i − p_i(0)| (kg m/s)", "contact time (s)", "wall (s)", "status"]
    for r in runs:
        fu = frame_updates(r)
        e = r.num("energy_error_max")
        mode = r.get("dt_mode")
        safety = r.num("dt_safety")
        dt_txt = ("–" if r.dt is None else fmt_dt(r.dt)
                  + (f" ({fmt_g(safety)} Δt_c)" if mode == "auto" and safety else
                     " (fixed)" if mode == "fixed" else ""))
        s.rows.append([
            f"`{r.id}`", scheme_label(r, coarsest),
            "– (penalty)" if fu is None else str(fu) + (" (frozen frame)" if fu == 0 else ""),
            dt_txt,
            f"{fmt_g(100 * e, 3)} %" if e is not None else "–",
            fmt_g(r.num("penetration_max")), fmt_g(r.num("friction_dissipation")),
            fmt_g(momentum_deviation(r.history()), 2) if r.ok else "–",
            fmt_g(r.num("contact_iterations.contact_time"), 4),
            fmt_g(r.num("wall_seconds")), _status(r)])
    s.runs = [r.id for r in runs]
    s.sources = [sw.dir]
    cmd = _sweep_command(sw)
    gates, failed = gates_result(sw.dir)
    gates_file = _gates_file(sw)
    gate_line = (f"**Gates** (`{gates_file}` with `cases/ball_block/gates_common.toml`, "
                 f"`gates-junit.xml` of the sweep): {gates}"
                 + (" — failed: " + "; ".join(failed) if failed else "") + "."
                 if gates else
                 f"**Gates:** no `gates-junit.xml`: the sweep ran without `--check {gates_file}`.")
    s.caption = (
        "A Mooney–Rivlin ball (R = 30 mm, 864 hexahedra) thrown at (4, −8, 3) m/s, a third of "
        "the block's shear wave speed, at the top face of a free Mooney–Rivlin block (10 × 4 × 8 "
        "hexahedra of 1 cm) 2 mm below it, off every axis of the mesh, Coulomb friction "
        "μ = 0.5, no gravity, no obstacle (`" + CASE_FILE + "`): two deformable bodies in "
        "large deformation meeting node to face, the 3D counterpart of the Kim–Kwak-type case. "
        "No closed-form answer exists; the gates check what must hold: every scheme reaches "
        "the end; the total momentum stays the ball's initial one to round-off (1e-14 kg m/s "
        "per component); the energy error stays below 2 % and falls with the mesh; no node of "
        "the ball inside the block beyond round-off with the semi-explicit scheme's frame "
        "updates, at the Newton tolerance with the implicit scheme's, the frozen frame's "
        "residual bounded; the penalty soft constraint at least halves the penetration; "
        "friction only dissipates. One row per run of the sweep (summary.csv): the contact "
        "frame updates (`contact.frame_updates`; 0 is the paper's frame frozen at the "
        "predicted positions), Δt (automatic: in brackets its fraction of the critical step Δt_c, "
        "`time.safety`; else fixed), the largest energy error, the largest "
        "penetration of a ball node into the block, the friction dissipation, the largest "
        "deviation of a momentum component from history row 0 over the run, the time in "
        "contact (`contact_iterations.contact_time`), the time-loop wall time. "
        + gate_line + " Obtained with `" + cmd + "`"
        + (f" (ci/reproduce: `{BB_CMD}`)" if re.sub(r" --jobs \d+", "", cmd) != BB_CMD
           else "")
        + "; "
        + doc_link(ctx["out"]) + " discusses the case.")
    return s


# ---------------------------------------------------------------------------------------------
# The plug-in's entries: each reads the layout section's sweep

def _legacy(ctx, section):
    sw = ctx.sweep(section["sweep"])
    return {"out": ctx.out, "bb": sw,
            "bb_fields": next((r.folder for r in sw.runs if RF.find_fields(r.folder)), None)}


def shapes(ctx, section):
    return [sec_shapes(_legacy(ctx, section), PageSection, "bb_shapes", "Deformed shapes")]


def histories(ctx, section):
    return [sec_histories(_legacy(ctx, section), PageSection, "bb_histories",
                          "Energy, contact force and momentum per scheme")]


def runs(ctx, section):
    return [sec_runs(_legacy(ctx, section), PageSection, "bb_runs", "The runs")]
