"""The report's Kim–Kwak-type part: the rubber ball, rubber block, V groove and bump of
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
import math
import os
import xml.etree.ElementTree as ET

import numpy as np

import report_figures as F
import report_generic as RG
import report_verification as RV
from report_io import (REPO, field_files, fmt_dt, fmt_g, read_case, read_vtu,
                       resolve_case_file, scheme_name)

KK_CMD = ("build/ricochet sweep cases/kim_kwak/sweep.toml --out results/kim_kwak "
          "--check cases/kim_kwak/gates.toml")
FIELDS_CMD = "build/ricochet run cases/kim_kwak/rubber_groove.toml --out results/rubber_groove"
CASE = "rubber_groove"
CASE_FILE = os.path.join("cases", "kim_kwak", "rubber_groove.toml")
GATES_FILE = os.path.join("ci", "gates", "kim_kwak.toml")
DOC = os.path.join(REPO, "docs", "kim-kwak-type.md")
PART_TITLE = "Kim–Kwak-type problem: rubber ball, rubber block, V groove and bump"
MAX_PANELS = 12
ENERGY_BOUND = 0.02  # the paper's bound, drawn on the energy-error panel


# ---------------------------------------------------------------------------------------------
# Sources

def find_fields(folder):
    """The folder holding the VTU files of a run: FOLDER/fields, else FOLDER itself."""
    if not folder:
        return None
    for d in (os.path.join(folder, "fields"), folder):
        if os.path.isdir(d) and field_files(d):
            return d
    return None


def gates_result(folder):
    """(text, failed gate names) from the sweep's gates-junit.xml (written by --check), or
    (None, []) without it."""
    try:
        root = ET.parse(os.path.join(folder, "gates-junit.xml")).getroot()
    except (OSError, ET.ParseError):
        return None, []
    cases = list(root.iter("testcase"))
    failed = [c.get("name", "?") for c in cases
              if c.find("failure") is not None or c.find("error") is not None]
    n = int(root.get("tests", str(len(cases))))
    bad = int(root.get("failures", "0")) + int(root.get("errors", "0"))
    return f"{n - bad} passed, {bad} failed", failed


def kk_runs(sweep):
    runs = [r for r in sweep.runs if r.kind == "run"]
    if any(r.get("case") for r in runs):
        runs = [r for r in runs if r.get("case") == CASE]
    return RV.order_runs(runs)


def doc_link(out):
    """docs/kim-kwak-type.md, linked relative to the report folder."""
    return f"[docs/kim-kwak-type.md]({os.path.relpath(DOC, out)})"


def last(h, name):
    return float(h[name][-1]) if h is not None and name in h and len(h[name]) else None


# ---------------------------------------------------------------------------------------------
# Figures

def _obstacle_artists(ax, obstacles, scale=1e3):
    """Draws the case's rigid obstacles (line, circle, polyline) in mm: the boundary and a grey
    fill on the rigid side. Returns legend handles."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Circle, Polygon
    handles = []
    far = 50.0 * scale  # beyond any view
    for ob in obstacles:
        kind = ob.get("type", "line")
        name = ob.get("name", kind)
        if kind == "circle" and "center" in ob and "radius" in ob:
            c = np.asarray(ob["center"], float) * scale
            r = float(ob["radius"]) * scale
            inside = bool(ob.get("inside", False))
            ax.add_patch(Circle(c, r, facecolor="none" if inside else "0.8",
                                edgecolor="k", lw=1.2, zorder=2))
            handles.append(Line2D([0], [0], color="k", lw=1.2, marker="o", mfc="0.8", ms=8,
                                  ls="none", label=f"{name} (rigid circle, r = "
                                                   f"{r:g} mm)"))
        elif kind == "polyline" and len(ob.get("points", [])) >= 2:
            p = np.asarray(ob["points"], float) * scale
            d0 = (p[1] - p[0]) / np.linalg.norm(p[1] - p[0])
            d1 = (p[-1] - p[-2]) / np.linalg.norm(p[-1] - p[-2])
            sign = 1.0 if ob.get("side", "left") == "left" else -1.0

            # the chain and its end rays, closed far on the rigid side (right of travel for
            # side = left), along the mean of the segments' normals towards it
            seg = np.diff(p, axis=0)
            nrm = sign * np.column_stack([seg[:, 1], -seg[:, 0]])
            m = np.sum(nrm / np.linalg.norm(nrm, axis=1)[:, None], axis=0)
            m = m / np.linalg.norm(m) if np.linalg.norm(m) > 0 else nrm[0] / np.linalg.norm(nrm[0])
            a, b = p[0] - far * d0, p[-1] + far * d1
            poly = np.vstack([a, p, b, b + 4 * far * m, a + 4 * far * m])
            ax.add_patch(Polygon(poly, closed=True, facecolor="0.88", edgecolor="none",
                                 zorder=0))
            ax.plot(p[:, 0], p[:, 1], color="k", lw=1.4, zorder=2)
            handles.append(Line2D([0], [0], color="k", lw=1.4,
                                  label=f"{name} (rigid polyline)"))
        elif kind == "line" and "point" in ob and "normal" in ob:
            q = np.asarray(ob["point"], float) * scale
            n = np.asarray(ob["normal"], float)
            n = n / np.linalg.norm(n)
            t = np.array([n[1], -n[0]])
            a, b = q - far * t, q + far * t
            ax.add_patch(Polygon(np.vstack([a, b, b - far * n, a - far * n]), closed=True,
                                 facecolor="0.88", edgecolor="none", zorder=0))
            ax.plot([a[0], b[0]], [a[1], b[1]], color="k", lw=1.4, zorder=2)
            handles.append(Line2D([0], [0], color="k", lw=1.4, label=f"{name} (rigid line)"))
    return handles


def fig_shapes(outdir, stem, frames, obstacles, probes, title):
    """One panel per (time, vtu) of frames: both bodies' deformed meshes (cell outlines,
    coloured by the cell von Mises stress when the files hold it), the rigid obstacles and the
    probe nodes; one view and one colour scale for all panels."""
    from matplotlib.collections import PolyCollection
    from matplotlib.colors import Normalize
    from matplotlib.lines import Line2D
    plt = F.plt
    n = len(frames)
    ncol = min(3, n)
    nrow = math.ceil(n / ncol)
    pts = np.vstack([v["points"] for _, v in frames]) * 1e3
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    for ob in obstacles:  # keep a circle obstacle near the bodies in view
        if ob.get("type") == "circle" and "center" in ob and "radius" in ob:
            c, r = np.asarray(ob["center"], float) * 1e3, float(ob["radius"]) * 1e3
            if np.all(c + r > lo - 40) and np.all(c - r < hi + 40):
                lo, hi = np.minimum(lo, c - r), np.maximum(hi, c + r)
    pad = 0.06 * float(np.max(hi - lo)) + 5.0
    lo, hi = lo - pad, hi + pad
    has_vm = all("von_mises" in v["cell_data"] for _, v in frames)
    norm = None
    if has_vm:
        vmax = max(float(np.max(v["cell_data"]["von_mises"])) for _, v in frames) or 1.0
        norm = Normalize(0.0, vmax)
    w = 4.0  # inches per panel
    h = w * (hi[1] - lo[1]) / (hi[0] - lo[0])
    fw, fh = w * ncol + 0.6 * (ncol - 1) + 1.9, h * nrow + 0.75 * (nrow - 1) + 1.55
    fig, axes = plt.subplots(nrow, ncol, figsize=(fw, fh), squeeze=False, sharex=True,
                             sharey=True)
    fig.subplots_adjust(left=0.8 / fw, right=1 - 1.1 / fw, bottom=1.0 / fh, top=1 - 0.55 / fh,
                        wspace=0.6 / w, hspace=0.75 / h)
    pc = None
    handles = []
    for k, ax in enumerate(axes.ravel()):
        if k >= n:
            ax.set_visible(False)
            continue
        t, v = frames[k]
        p = v["points"] * 1e3
        polys = [p[c] for c in v["cells"]]
        # faces (edged in their own colour, so no seams show), then the cell outlines
        if has_vm:
            pc = PolyCollection(polys, array=v["cell_data"]["von_mises"], cmap=F.CMAP,
                                norm=norm, edgecolors="face", linewidths=0.3, zorder=1)
            ax.add_collection(pc)
        else:
            body = v["cell_data"].get("body", np.zeros(len(polys)))
            ax.add_collection(PolyCollection(
                polys, facecolors=[("#c6dbef", "#fdd0a2")[int(b) % 2] for b in body],
                edgecolors="face", linewidths=0.3, zorder=1))
        ax.add_collection(PolyCollection(polys, facecolors="none", edgecolors=(0, 0, 0, 0.45),
                                         linewidths=0.25, zorder=1.5))
        handles = _obstacle_artists(ax, obstacles)
        for (name, node), mk in zip(probes, ("o", "s", "^", "D")):
            if 0 <= node < len(p):
                ax.plot(p[node, 0], p[node, 1], marker=mk, ms=5, mfc="white", mec="k",
                        ls="none", zorder=4)
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
        ax.set_aspect("equal")
        ax.grid(False)
        ax.set_title(f"t = {round(t * 1e3, 1):g} ms")
        if k % ncol == 0:
            ax.set_ylabel("y (mm)")
        if k // ncol == nrow - 1 or k + ncol >= n:
            ax.set_xlabel("x (mm)")
            ax.xaxis.set_tick_params(labelbottom=True)
    handles += [Line2D([0], [0], marker=mk, ms=5, mfc="white", mec="k", ls="none",
                       label=f"probe {name}") for (name, _), mk in zip(probes, ("o", "s", "^", "D"))]
    fig.legend(handles=handles, loc="lower center", ncol=min(4, max(1, len(handles))),
               bbox_to_anchor=(0.5, 0.0), frameon=False)
    if pc is not None:
        cax = fig.add_axes([1 - 0.95 / fw, 1.0 / fh, 0.15 / fw, 1 - 1.55 / fh])
        cax.grid(False)
        cb = fig.colorbar(pc, cax=cax)
        cb.set_label(F._sci(cb) + ", cell")
    fig.suptitle(title, fontsize=10, y=1 - 0.12 / fh)
    return F.save(fig, outdir, stem, svg=False)


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

def sections(ctx, Section):
    """The Kim–Kwak-type part: deformed shapes (fields run), histories and runs table
    (sweep). Each section is 'not available' on its own when its source is missing."""
    intro = (
        "A Kim–Kwak-type problem (" + doc_link(ctx["out"]) + ", `" + CASE_FILE + "`): a "
        "Blatz–Ko foam-rubber ball thrown at a Mooney–Rivlin block resting on the floor of a "
        "rigid V groove; it strikes the block and the floor, dents itself on the block's "
        "corner and rebounds, and the block trips over a rigid bump. Large deformation, "
        "contact between the bodies and with the obstacles, Coulomb friction μ = 0.3 "
        "everywhere, gravity. No closed-form answer exists, so nothing here is compared with a "
        "reference. The gates (`" + GATES_FILE + "`) check what every impact scheme must "
        "deliver: every run reaches the end; the energy error stays below 2 % and shrinks "
        "with the step; the bi-potential schemes' penetration between the bodies stays below "
        "5 % of a rim segment (0.2 mm) and shrinks like the step squared; the penalty scheme's "
        "soft constraint at least halves its penetration; friction only dissipates. The "
        "gate result is under the runs table.")
    builders = (("kk_shapes", "Deformed shapes of the ball and the block", sec_shapes),
                ("kk_histories", "Energy error and ball velocity per run", sec_histories),
                ("kk_interfaces", "Contact forces per interface", sec_interfaces),
                ("kk_runs", "The Kim–Kwak-type runs", sec_runs))
    return RG.part_sections(ctx, Section, builders, PART_TITLE, intro)


def _no_sweep(ctx, s):
    err = ctx.get("kk_err")
    s.available = False
    s.missing = (("the Kim–Kwak-type sweep could not be read (" + err + "). " if err else
                  "no Kim–Kwak-type sweep. ") +
                 f"Run `{KK_CMD}` and pass `--kim-kwak results/kim_kwak` (or place it next to "
                 "the paper sweep as `kim_kwak/`).")
    return s


def sec_shapes(ctx, Section, sid, title):
    s = Section(sid, title, "figure")
    given = ctx.get("kk_fields")
    fdir = find_fields(given)
    if fdir is None:
        s.available = False
        s.missing = ((f"no fields/*.vtu in `{given}`. " if given else
                      "no run of the Kim–Kwak-type case with fields. ") +
                     f"Run `{FIELDS_CMD}` and pass `--kim-kwak-fields results/rubber_groove` "
                     "(or place it next to the paper sweep as `rubber_groove/`).")
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
    s.files = fig_shapes(ctx["out"], "kim_kwak_shapes", frames, obstacles, probes, title_run)
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
    labels = RV.column_labels(runs)
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
    labels = RV.column_labels(runs)
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
