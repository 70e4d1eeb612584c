"""The report's 3D part (docs/three-dimensions.md, Cases in 3D), from three sources:

  * the sweep of cases/three_d/sweep.toml: the bar on a rigid wall in 3D against the 1D solution
    (a figure of the normal force of every run, a table of plateau, duration and rebound), the
    oblique block beside the 2D plane-stress plate (a table of the 3D/2D ratios), and the frame
    invariance of the turned runs (a table of relative differences);
  * the sweep of cases/three_d/refinement.toml: the same comparison on refined meshes;
  * a run of cases/three_d/oblique_block.toml with its fields: the deformed block at each field
    time, drawn from its boundary faces with matplotlib;
  * the sweep of cases/three_d_table1/sweep_full.toml (or table1_fast.toml), the paper's Table 1 in 3D: wall
    time and energy error per mesh x dt x scheme, with the penalty runs at their automatic step,
    and `ricochet stability` results of the 3D meshes beside them.
  * the sweep of cases/ball_block/sweep_full.toml and a run of cases/ball_block/ball_block.toml
    with its fields: the Mooney-Rivlin ball striking a free Mooney-Rivlin block
    (report_ball_block.py).

A source that is missing gives "not available" sections with the command that produces it.
"""

import json
import math
import os

import numpy as np

import report_figures as F
import report_generic as RG
import report_kim_kwak as RK
import report_stability as RS
from report_io import (REPO, field_files, fmt_dt, fmt_g, read_vtu, resolve_case_file, same,
                       scheme_name, show_path)

SWEEP_CMD = ("build/ricochet sweep cases/three_d/sweep.toml --out results/three_d "
             "--check cases/three_d/gates.toml")
REF_CMD = ("build/ricochet sweep cases/three_d/refinement.toml --out results/three_d_refinement "
           "--threads 1")
FIELDS_CMD = ("build/ricochet run cases/three_d/oblique_block.toml --set obstacles[0].friction=0.1 "
              "--out results/oblique_block")
T1_CMD = ("build/ricochet sweep cases/three_d_table1/sweep_full.toml --out results/three_d_table1 "
          "--repeat 3")
STAB_CMD = ("build/ricochet stability cases/three_d/oblique_block.toml --set mesh=M1x2 "
            "--set scheme=semi_explicit --set obstacles[0].friction=0 "
            "--out results/three_d_stability/semi_explicit_M1x2")
STAB_MORE = ("(and likewise for the mesh M1x4 and the scheme `implicit`, with `--energy-bound 1`)")
DOC = os.path.join(REPO, "docs", "three-dimensions.md")
T1_ANCHOR = "#the-3d-table-1"
PART_TITLE = ("Three dimensions: the bar on a wall, the oblique block against plane stress, "
              "frame invariance, Table 1 in 3D, a Mooney–Rivlin ball on a free block")
MAX_PANELS = 6

# The bar (cases/three_d/bar_wall3.toml): rho c v0 A and 2L/c.
BAR_FORCE = 8000.0 * math.sqrt(2.0e11 / 8000.0) * 1.0 * 0.02 * 0.02  # 16000 N
BAR_DURATION = 2.0 * 0.2 / math.sqrt(2.0e11 / 8000.0)                # 8e-5 s

# The faces of a VTK hexahedron and tetrahedron, corners counter-clockwise seen from outside
# (solver/model/mesh3.hpp, kHexFaces and kTetFaces).
HEX_FACES = ((0, 4, 7, 3), (1, 2, 6, 5), (0, 1, 5, 4), (3, 7, 6, 2), (0, 3, 2, 1), (4, 5, 6, 7))
TET_FACES = ((0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2))


def doc_link(out, anchor="", text="docs/three-dimensions.md"):
    return f"[{text}]({os.path.relpath(DOC, out)}{anchor})"


def boundary_faces(cells):
    """[(corner indices, cell index)] of the faces used by one cell only: the surface of a mesh
    of hexahedra (8 corners) and tetrahedra (4)."""
    seen = {}
    for c, cell in enumerate(cells):
        faces = HEX_FACES if len(cell) == 8 else TET_FACES if len(cell) == 4 else ()
        for f in faces:
            nodes = tuple(int(cell[i]) for i in f)
            key = tuple(sorted(nodes))
            seen[key] = None if key in seen else (nodes, c)
    return [v for v in seen.values() if v is not None]


# ---------------------------------------------------------------------------------------------
# Figures

def fig_shapes(outdir, stem, frames, title, ground_y=0.0):
    """One 3D panel per (time, vtu): the deformed surface (boundary faces, coloured by their
    cell's von Mises stress on one scale for all panels) above the plane y = ground_y; one view
    for all panels. Axes in mm; the plot's vertical axis is the case's y (up)."""
    from matplotlib.colors import Normalize
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection
    plt = F.plt
    n = len(frames)
    ncol = min(3, n)
    nrow = math.ceil(n / ncol)
    pts_all = np.vstack([v["points3"] for _, v in frames]) * 1e3
    lo, hi = pts_all.min(axis=0), pts_all.max(axis=0)
    span = float(np.max(hi - lo))
    mid = 0.5 * (lo + hi)
    vmax = max((float(np.max(v["cell_data"]["von_mises"])) for _, v in frames
                if "von_mises" in v["cell_data"]), default=1.0) or 1.0
    norm = Normalize(0.0, vmax)
    cmap = plt.get_cmap(F.CMAP)
    fig = plt.figure(figsize=(4.2 * ncol + 1.2, 4.0 * nrow + 0.6))
    for k, (t, v) in enumerate(frames):
        ax = fig.add_subplot(nrow, ncol, k + 1, projection="3d")
        ax.computed_zorder = False  # the plane below the body, whatever mplot3d's depth sort says
        p = v["points3"] * 1e3
        faces = boundary_faces(v["cells"])
        vm = v["cell_data"].get("von_mises")
        # plot axes (X, Y, Z) = the case's (x, z, y): y up in the picture
        polys = [p[list(f)][:, [0, 2, 1]] for f, _ in faces]
        colors = [cmap(norm(vm[c])) if vm is not None else (0.75, 0.82, 0.93, 1.0) for _, c in faces]
        body = Poly3DCollection(polys, facecolors=colors, edgecolors=(0, 0, 0, 0.35), linewidths=0.2)
        body.set_zorder(2)
        ax.add_collection3d(body)
        gx = np.array([mid[0] - 0.6 * span, mid[0] + 0.6 * span])
        gz = np.array([mid[2] - 0.6 * span, mid[2] + 0.6 * span])
        GX, GZ = np.meshgrid(gx, gz)
        ax.plot_surface(GX, GZ, np.full_like(GX, ground_y * 1e3), color="0.6", alpha=0.25,
                        shade=False, zorder=1)
        ax.set_xlim(mid[0] - 0.55 * span, mid[0] + 0.55 * span)
        ax.set_ylim(mid[2] - 0.55 * span, mid[2] + 0.55 * span)
        ax.set_zlim(min(lo[1], ground_y * 1e3) - 0.05 * span, lo[1] + 1.05 * span)
        ax.set_box_aspect((1, 1, 1))
        ax.view_init(elev=18, azim=-62)
        ax.set_xlabel("x (mm)")
        ax.set_ylabel("z (mm)")
        ax.set_zlabel("y (mm)")
        ax.set_title(f"t = {round(t * 1e3, 2):g} ms")
    sm = plt.cm.ScalarMappable(norm=norm, cmap=cmap)
    cax = fig.add_axes([0.93, 0.15, 0.012, 0.7])
    cb = fig.colorbar(sm, cax=cax)
    cb.set_label(F._sci(cb) + ", cell")
    fig.suptitle(title, fontsize=10)
    return F.save(fig, outdir, stem, svg=False)


def fig_bar(outdir, stem, runs):
    """runs = [(label, run)]: the summed normal contact force against time, one line each, with
    the 1D solution's plateau rho c v0 A over 0 < t < 2L/c."""
    plt = F.plt
    fig, ax = plt.subplots(figsize=(9.5, 4.4))
    styles = F._styles(runs)
    tend = 0.0
    for (label, r), st in zip(runs, styles):
        h = r.history()
        t = h["time"] * 1e6
        tend = max(tend, float(t[-1]))
        ax.plot(t, h["normal_force"] / 1e3, lw=1.2, label=label, **st)
    ax.plot([0, BAR_DURATION * 1e6, BAR_DURATION * 1e6], [BAR_FORCE / 1e3, BAR_FORCE / 1e3, 0],
            color="k", ls=":", lw=1.3, label="1D solution: ρcv₀A for 2L/c")
    ax.set_xlabel("time t (µs)")
    ax.set_ylabel("normal contact force (kN)")
    ax.set_xlim(0, tend)
    ax.set_title("bar on a rigid wall in 3D (normal_force)")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=3, frameon=False)
    fig.tight_layout()
    return F.save(fig, outdir, stem)


# ---------------------------------------------------------------------------------------------
# Sections

def sections(ctx, Section):
    import report_ball_block as RB   # here: it imports this module for its helpers
    intro = (
        "The three schemes on 3D models (" + doc_link(ctx["out"]) + "): a bar striking a "
        "rigid wall against the 1D solution, the paper's plate extruded through its 1 cm "
        "thickness and hitting a rigid plane at (3, −5, 0) m/s beside the 2D plane-stress plate, "
        "and the same block with the whole scene turned about an oblique axis; the paper's "
        "Table 1 (mesh × Δt × scheme) on the block; and contact between two bodies in 3D: a "
        "Mooney–Rivlin ball striking a free Mooney–Rivlin block obliquely, with friction ("
        + RB.doc_link(ctx["out"]) + ").")
    builders = (("td_shapes", "The oblique block in 3D: deformed shapes", sec_shapes),
                ("td_bar", "The bar on a rigid wall in 3D", sec_bar),
                ("td_oblique", "The oblique block against the 2D plane-stress plate", sec_oblique),
                ("td_frame", "Frame invariance: the turned scene", sec_frame),
                ("td_table1", "Table 1 in 3D: wall time and energy error per mesh × Δt × scheme",
                 sec_table1)) + RB.builders()
    return RG.part_sections(ctx, Section, builders, PART_TITLE, intro)


def _no_sweep(ctx, s, key="td", cmd=SWEEP_CMD, name="three_d"):
    err = ctx.get(key + "_err")
    s.available = False
    s.missing = ((f"the sweep could not be read ({err}). " if err else f"no {name} sweep. ")
                 + f"Run `{cmd}` (results/{name}, found next to the main sweep).")
    return s


def _fields_frames(folder):
    """(the fields folder, [(time, vtu)] of at most MAX_PANELS field times) of a run folder."""
    fdir = RK.find_fields(folder)
    if fdir is None:
        return None, []
    files = field_files(fdir)
    if len(files) > MAX_PANELS:
        keep = np.unique(np.round(np.linspace(0, len(files) - 1, MAX_PANELS)).astype(int))
        files = [files[i] for i in keep]
    return fdir, [(t, read_vtu(p)) for t, p in files]


def sec_shapes(ctx, Section, sid, title):
    s = Section(sid, title, "figure")
    folder = ctx.get("td_fields")
    fdir, frames = _fields_frames(folder)
    if not frames:
        s.available = False
        s.missing = ((f"no fields/*.vtu in `{folder}`. " if folder else
                      "no run of the oblique block with fields. ")
                     + f"Run `{FIELDS_CMD}` (results/oblique_block, found next to the main sweep).")
        return s
    if any("points3" not in v for _, v in frames):
        s.available = False
        s.missing = f"the fields in `{fdir}` are not 3D."
        return s
    run_dir = os.path.dirname(fdir) if os.path.basename(fdir) == "fields" else fdir
    try:
        with open(os.path.join(run_dir, "summary.json")) as f:
            summ = json.load(f)
    except (OSError, ValueError):
        summ = {}
    scheme = scheme_name(summ.get("scheme", "")) or "?"
    mu = summ.get("friction_coeff")
    run_title = (f"{summ.get('case', 'oblique_block')}, {scheme}, mesh {summ.get('mesh', '?')}"
                 + (f", μ = {mu:g}" if isinstance(mu, (int, float)) else ""))
    s.files = fig_shapes(ctx["out"], "three_d_shapes", frames, run_title)
    s.runs = [run_dir]
    s.sources = [fdir]
    vm = [(t, float(np.max(v["cell_data"]["von_mises"]))) for t, v in frames
          if "von_mises" in v["cell_data"]]
    case_path = resolve_case_file(summ.get("case_file"))
    s.caption = (
        "The deformed block (true scale) drawn from its boundary faces, each coloured by its "
        "cell's von Mises stress (the run's `stress_measure`, "
        f"{summ.get('stress_measure', '?')}) on one scale, at each field time ("
        + ", ".join(f"{t * 1e3:.3g}" for t, _ in frames) + " ms; fields/*.vtu), above the rigid "
        "plane y = 0 (grey). The picture's vertical axis is the case's y. "
        + (("Largest cell von Mises stress per instant: "
            + ", ".join(f"{t * 1e3:.3g} ms: {fmt_g(m)} Pa" for t, m in vm) + ". ") if vm else "")
        + f"Run: `{run_dir}` ({run_title}"
        + (f"; case file `{os.path.relpath(case_path, REPO)}`" if case_path else "") + ").")
    return s


def _bar_runs(sw):
    return [r for r in sw.runs if r.kind == "run" and r.ok and r.get("case") == "bar_wall3"]


def _bar_label(r):
    el = r.get("bodies[0].element") or "hex8"
    if r.get("meshes.bar.cells") == "tet":
        el = "tet4"
    f = r.get("penalty.scale_factor")
    return scheme_name(r.scheme) + ", " + el + (f", f_si = {f}" if f else
                                                 ", f_si = 0.1" if r.scheme == "explicit_penalty" else "")


def sec_bar(ctx, Section, sid, title):
    s = Section(sid, title, "figure")
    sw = ctx.get("td")
    if sw is None:
        return _no_sweep(ctx, s)
    runs = _bar_runs(sw)
    if not runs:
        s.available = False
        s.missing = f"no finished bar_wall3 run in `{sw.dir}`."
        return s
    labelled = [(_bar_label(r), r) for r in runs]
    s.files = fig_bar(ctx["out"], "three_d_bar", labelled)
    s.runs = [r.id for r in runs]
    s.sources = [sw.dir]
    rows = []
    for label, r in labelled:
        f = r.num("contact_force_mean")
        d = r.num("contact_iterations.contact_time")
        v = r.num("rebound_velocity_x")
        rows.append([f"`{r.id}`", label,
                     f"{fmt_g(f, 5)} ({100 * (f / BAR_FORCE - 1):+.2f} %)" if f else "–",
                     f"{fmt_g(d, 5)} ({100 * (d / BAR_DURATION - 1):+.2f} %)" if d else "–",
                     f"{fmt_g(v, 5)} ({100 * (v - 1):+.2f} %)" if v else "–",
                     fmt_g(r.num("penetration_max"))])
    s.extra = [("td_bar_table", "Against the 1D solution (ρcv₀A = 16000 N, 2L/c = 8e-5 s, v₀ = 1 m/s)",
                ["run", "scheme, element", "mean normal force in contact (N)",
                 "contact time (s)", "rebound v_x (m/s)", "penetration (m)"], rows)]
    s.caption = (
        "The summed normal contact force (history `normal_force`) of every bar run of the 3D "
        "sweep against time, with the 1D solution: while the bar (0.2 × 0.02 × 0.02 m, "
        "E = 2e11 Pa, ν = 0, ρ = 8000 kg/m³, 200 × 2 × 2 cells) touches the wall the force is "
        "ρcv₀A = 16000 N, for 2L/c = 80 µs, then it leaves at +v₀. The penalty springs at "
        "LS-DYNA's default f_si = 0.1 delay each wave front by ρcA/k = 6 µs, so their contact "
        "lasts longer, as in 2D; at f_si = 1 the delay is 0.6 µs. The implicit scheme runs at "
        "a fixed Δt = 1e-7 s. The table gives the gated "
        "quantities (`cases/three_d/gates.toml`: 2 %). Runs: "
        + ", ".join(f"`{r.id}`" for r in runs) + f" of `{sw.dir}`.")
    return s


SCHEMES = ("semi_explicit", "implicit", "explicit_penalty")


def oblique_group(scheme):
    """The 3D sweep's group of the oblique block run by `scheme` (cases/three_d/sweep.toml)."""
    return "oblique_implicit" if scheme == "implicit" else "oblique"


def _pick(sw, group, scheme, mu):
    for r in sw.runs:
        if (r.kind == "run" and r.ok and r.group == group and r.scheme == scheme
                and r.friction is not None and abs(r.friction - mu) < 1e-12):
            return r
    return None


COMPARED = (("rebound_velocity_x", "rebound v_x (m/s)"), ("rebound_velocity_y", "rebound v_y (m/s)"),
            ("contact_iterations.contact_time", "contact time (s)"),
            ("friction_dissipation", "friction dissipation (J)"),
            ("von_mises_max", "von Mises peak (Pa)"),
            ("von_mises_interior_max", "von Mises peak off the contact boundary (Pa)"),
            ("energy_error_max", "energy error"))


def sec_oblique(ctx, Section, sid, title):
    s = Section(sid, title, "table")
    sw = ctx.get("td")
    if sw is None:
        return _no_sweep(ctx, s)
    s.header = ["scheme, μ", "quantity", "3D (M1x4)", "2D plane stress (M1)", "3D / 2D"]
    runs = []
    for scheme in SCHEMES:
        for mu in (0.0, 0.1):
            a, b = _pick(sw, oblique_group(scheme), scheme, mu), _pick(sw, "oblique2d", scheme, mu)
            if a is None or b is None:
                continue
            runs += [a.id, b.id]
            for col, name in COMPARED:
                x, y = a.num(col), b.num(col)
                if x is None or y is None or (col == "friction_dissipation" and mu == 0.0):
                    continue
                ratio = f"{x / y:.4f}" if y else "–"
                s.rows.append([f"{scheme_name(scheme)}, {mu:g}", name, fmt_g(x, 6), fmt_g(y, 6), ratio])
    if not s.rows:
        s.available = False
        s.missing = f"no finished oblique and oblique2d runs in `{sw.dir}`."
        return s
    s.runs = runs
    s.sources = [sw.dir]
    ref = ctx.get("td_ref")
    if ref is not None:
        rows = []
        for r in sorted((r for r in ref.runs if r.kind == "run" and r.ok),
                        key=lambda r: (r.group, r.friction or 0.0, r.num("elements") or 0)):
            rows.append([f"`{r.id}`", r.mesh, f"{int(r.num('elements') or 0)}", f"{r.friction:g}"]
                        + [fmt_g(r.num(c), 6) for c, _ in COMPARED])
        s.extra = [("td_refinement", "Under refinement (semi-explicit, Δt = 2e-6 s on every mesh; "
                    f"`{ref.dir}`)", ["run", "mesh", "cells", "μ"] + [n for _, n in COMPARED], rows)]
        s.sources.append(ref.dir)
    s.caption = (
        "The oblique block (cases/three_d/oblique_block.toml: the paper's plate extruded "
        "through e = 0.01 m in 4 layers, 1536 hexahedra) and the 2D plane-stress plate "
        "(cases/oblique_plate.toml, M1) hitting the ground at (3, −5) m/s, Δt = 1e-5 s, each "
        "scheme against its own 2D run. The "
        "rebound and the contact time agree to about 1 %; the 3D block dissipates 1–2 % more by "
        "friction and its semi-explicit von Mises peak is 2–3 % higher, next to a free face where "
        "the 3D stress departs from its thickness average, which is what plane stress computes. "
        "The penalty scheme's 3D peak is 55 % higher: it sits in the cell at the penetrated "
        "contact edge next to the face z = 0; off the contact boundary (in 3D the middle layers "
        "only, since the faces z = 0 and z = e are contact boundary too) the peaks agree within "
        "2 % (" + doc_link(ctx["out"]) + ", 3D and plane stress). "
        + ("The second table follows the comparison to finer meshes. " if ref is not None else
           f"The refinement table is not available: run `{REF_CMD}`. ")
        + f"Sweep `{sw.dir}`.")
    return s


def sec_frame(ctx, Section, sid, title):
    s = Section(sid, title, "table")
    sw = ctx.get("td")
    if sw is None:
        return _no_sweep(ctx, s)
    s.header = ["scheme", "quantity", "unturned", "turned", "relative difference"]
    runs = []
    for scheme in SCHEMES:
        turned = next((r for r in sw.runs if r.kind == "run" and r.ok and r.group == "frame"
                       and r.scheme == scheme), None)
        plain = _pick(sw, oblique_group(scheme), scheme, turned.friction if turned and turned.friction is not None
                      else 0.1) if turned else None
        if turned is None or plain is None:
            continue
        runs += [plain.id, turned.id]
        for col, name in (("final.kinetic_energy", "kinetic energy (J)"),
                          ("final.strain_energy", "strain energy (J)"),
                          ("friction_dissipation", "friction dissipation (J)"),
                          ("contact_work", "contact work (J)"),
                          ("contact_iterations.contact_time", "contact time (s)")):
            x, y = plain.num(col), turned.num(col)
            if x is None or y is None:
                continue
            rel = abs(y - x) / abs(x) if x else abs(y - x)
            s.rows.append([scheme_name(scheme), name, repr(x), repr(y), f"{rel:.1e}"])
    if not s.rows:
        s.available = False
        s.missing = f"no finished frame runs in `{sw.dir}`."
        return s
    s.runs = runs
    s.sources = [sw.dir]
    s.caption = (
        "The oblique block (μ = 0.1) and the same case with `[scene_rotation]` 50° about "
        "(1, 2, −1.5): every position, velocity and the plane turned. The energies, the "
        "dissipation and the contact time do not depend on the frame; the gates "
        "(`cases/three_d/gates.toml`) hold them to 1e-9. The differences are round-off: the turned "
        "run's contact tangents are other vectors of the same tangent planes; the implicit "
        "scheme's, about 1e-11, are its Newton tolerance, met in each frame on its own. "
        f"Sweep `{sw.dir}`.")
    return s


# ---------------------------------------------------------------------------------------------
# Table 1 in 3D (cases/three_d_table1/sweep_full.toml)

T1_SCHEMES = (("semi_explicit", "Semi-explicit"), ("implicit", "Implicit"))
MESH_MARKERS = ("o", "s", "^", "D")
MESH_STYLES = ("-", "--", ":", "-.")


def _t1_meshes(runs):
    """The meshes of the runs, coarsest first (by cell count, then name)."""
    cells = {}
    for r in runs:
        cells.setdefault(r.mesh, r.num("elements") or math.inf)
    return sorted(cells, key=lambda m: (cells[m], m))


def _t1_columns(runs):
    """[(mesh, Δt)] of the Table 1 runs: by mesh, then the largest step first (the paper's
    order)."""
    cols = []
    for m in _t1_meshes(runs):
        dts = []
        for r in runs:
            if r.mesh == m and r.dt is not None and not any(same(r.dt, d, 1e-6) for d in dts):
                dts.append(r.dt)
        cols += [(m, d) for d in sorted(dts, reverse=True)]
    return cols


def _t1_find(runs, mesh, dt, scheme):
    return next((r for r in runs if r.mesh == mesh and r.scheme == scheme
                 and same(r.dt, dt, 1e-6)), None)


def _t1_wall(r):
    """The wall time of a run, with the spread of its repeats when there were several."""
    w = r.num("wall_seconds")
    if w is None:
        return "–"
    lo, hi = r.num("wall_seconds_min"), r.num("wall_seconds_max")
    spread = (f" ({fmt_g(lo)}–{fmt_g(hi)})" if (r.num("repeats") or 1) > 1 and lo is not None
              and hi is not None else "")
    return f"{fmt_g(w)} s{spread}"


def _pct(x):
    return "–" if x is None else f"{fmt_g(100 * x, 2)} %"


def _t1_cell(r):
    if r is None:
        return "not run"
    if r.status == "diverged":
        return f"**diverged** at t = {fmt_g(r.num('diverged.time'))} s"
    if r.status != "ok":
        return f"**failed**: {r.reason or r.status or '?'}"[:140]
    return f"{_t1_wall(r)}; energy error {_pct(r.num('energy_error_max'))}"


def _t1_timing_text(sw, runs):
    """How the timings were taken: repeats, threads, jobs; a warning when runs shared the
    machine."""
    reps = sorted({int(r.num("repeats")) for r in runs if r.num("repeats")})
    rep_txt = (f"medians over {', '.join(map(str, reps))} repeats (in brackets the fastest and "
               "slowest)" if reps and reps != [1] else "single runs, no medians (`--repeat 1`)")
    threads = sorted({int(r.num("threads")) for r in runs if r.num("threads") is not None})
    thr_txt = (f"{', '.join(map(str, threads))} thread{'s' if threads != [1] else ''} per run "
               "(`threads`)" if threads else "the case's threads")
    jobs = sw.meta.get("jobs")
    warn = (f" **The sweep ran {jobs} runs at a time (`--jobs {jobs}`), so these timings are "
            "disturbed; use `--jobs 1` for this table.**" if isinstance(jobs, int) and jobs > 1
            else "")
    return rep_txt, thr_txt, warn


def _t1_command(sw):
    """The command that wrote the sweep, from its sweep.json."""
    m = sw.meta
    f = m.get("sweep_file")
    cmd = "ricochet sweep " + (show_path(f) if f else "cases/three_d_table1/sweep_full.toml") + \
        f" --out {show_path(sw.dir)}"
    if isinstance(m.get("jobs"), int) and m["jobs"] != 1:
        cmd += f" --jobs {m['jobs']}"
    if m.get("threads") is not None:
        cmd += f" --threads {m['threads']}"
    if isinstance(m.get("repeat"), int) and m["repeat"] != 1:
        cmd += f" --repeat {m['repeat']}"
    return cmd


def fig_table1(outdir, stem, runs, penalty):
    """Two panels against Δt (log-log): the time-loop wall time and the energy error, one line
    per (mesh, scheme) of the Table 1 runs; a diverged run is an X at the top of each panel, a
    penalty run (automatic Δt) a lone marker."""
    plt = F.plt
    from matplotlib.lines import Line2D
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter
    from matplotlib.transforms import blended_transform_factory
    meshes = _t1_meshes(list(runs) + list(penalty))
    fig, axes = plt.subplots(1, 2, figsize=(11.5, 4.6))
    handles = []
    for ax, col, ylabel in ((axes[0], "wall_seconds", "wall time, time loop (s)"),
                            (axes[1], "energy_error_max", "energy error (energy_error_max)")):
        top = blended_transform_factory(ax.transData, ax.transAxes)
        for i, mesh in enumerate(meshes):
            mk, ls = MESH_MARKERS[i % len(MESH_MARKERS)], MESH_STYLES[i % len(MESH_STYLES)]
            for scheme, label in T1_SCHEMES:
                rs = sorted((r for r in runs if r.mesh == mesh and r.scheme == scheme
                             and r.dt is not None), key=lambda r: r.dt)
                if not rs:
                    continue
                ok = [(r.dt, r.num(col)) for r in rs if r.ok and r.num(col)]
                c = F.color(scheme)
                if ok:
                    ax.plot([p[0] for p in ok], [p[1] for p in ok], color=c, ls=ls, marker=mk,
                            ms=6, lw=1.4)
                # the X of each mesh a little apart, so that the meshes' Xs do not hide each other
                shift = 1.12 ** (i - (len(meshes) - 1) / 2)
                for r in rs:
                    if r.status == "diverged":
                        ax.plot(r.dt * shift, 0.95, transform=top, marker="X", ms=10, color=c,
                                mec="k", ls="none", clip_on=False)
                if ax is axes[0]:
                    handles.append(Line2D([0], [0], color=c, ls=ls, marker=mk, ms=6,
                                          label=f"{mesh}, {label.lower()}"))
            for r in penalty:
                if r.mesh == mesh and r.dt is not None and r.ok and r.num(col):
                    ax.plot(r.dt, r.num(col), marker=mk, ms=8, color=F.color("explicit_penalty"),
                            mec="k", ls="none")
                    if ax is axes[0]:
                        handles.append(Line2D([0], [0], marker=mk, ms=8, mec="k", ls="none",
                                              color=F.color("explicit_penalty"),
                                              label=f"{mesh}, explicit penalty (Δt auto)"))
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("time step Δt (s)")
        ax.set_ylabel(ylabel)
        ax.grid(True, which="both", alpha=0.25)
    lo, hi = axes[0].get_xlim()
    for ax in axes:
        ax.set_xlim(lo / 1.6, hi * 1.6)
        yl, yh = ax.get_ylim()
        ax.set_ylim(yl, yh * 3)   # room for the X of the diverged runs at the top
        if yh * 3 / yl < 300:     # under about two decades: ticks at 1, 2 and 5 too
            ax.yaxis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
            ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: fmt_g(v, 2)))
            ax.yaxis.set_minor_formatter(NullFormatter())
    if any(r.status == "diverged" for r in runs):
        handles.append(Line2D([0], [0], marker="X", ms=10, color="0.5", mec="k", ls="none",
                              label="diverged (at the top of the panel)"))
    axes[0].set_title("wall time")
    axes[1].set_title("energy error")
    fig.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, 0.0),
               ncol=min(3, len(handles)), frameon=False)
    fig.tight_layout()
    return F.save(fig, outdir, stem)


def _t1_stability(ctx, s):
    """The stability table of the 3D meshes (ricochet stability) as an extra table of s; the
    caption's sentence about it."""
    files = ctx.get("td_stab") or []
    entries, bad = RS.read_stability_entries(files)
    if not entries:
        return ("Stability results of the 3D meshes are not available"
                + (f" ({'; '.join(bad)})" if bad else "") + f": run `{STAB_CMD}` {STAB_MORE} "
                "and pass `--three-d-stability results/three_d_stability` (or place it next to "
                "the main sweep as `three_d_stability/`). ")
    best = RS.best_entries(entries)
    s.extra.append(("td_table1_stability", "Largest stable and smallest unstable Δt of the 3D "
                    "meshes, by `ricochet stability` (docs/stability.md)", RS.STABILITY_HEADER,
                    RS.stability_rows(entries)))
    s.sources += [e["path"] for e in entries]
    return ("The last table gives the largest stable and smallest unstable Δt per mesh and "
            "scheme found by `ricochet stability` (bisection over whole runs; "
            + RS.stability_summary(best) + "), to be read beside the steps of the table. ")


def sec_table1(ctx, Section, sid, title):
    s = Section(sid, title, "figure")
    sw = ctx.get("td_t1")
    if sw is None:
        err = ctx.get("td_t1_err")
        s.available = False
        s.missing = ((f"the sweep could not be read ({err}). " if err else
                      "no three_d_table1 sweep. ")
                     + f"Run `{T1_CMD}` (or cases/three_d_table1/sweep_fast.toml; results/three_d_table1, "
                     "found next to the main sweep, or `--three-d-table1`).")
        return s
    runs = [r for r in sw.find(group="table1") if r.scheme in dict(T1_SCHEMES)]
    penalty = sw.find(group="penalty")
    if not runs:
        s.available = False
        s.missing = (f"no run of the group `table1` in `{sw.dir}` (not a sweep of "
                     f"cases/three_d_table1/sweep_full.toml?). Run `{T1_CMD}`.")
        return s
    cols = _t1_columns(runs)
    hdr = [f"{m}, Δt = {fmt_dt(d)} s" for m, d in cols]
    rows, used = [], []
    for scheme, label in T1_SCHEMES:
        row = [f"**{label}**"]
        for mesh, dt in cols:
            r = _t1_find(runs, mesh, dt, scheme)
            if r is not None:
                used.append(r.id)
            row.append(_t1_cell(r))
        rows.append(row)
    ratio = ["implicit / semi-explicit"]
    for mesh, dt in cols:
        a, b = _t1_find(runs, mesh, dt, "implicit"), _t1_find(runs, mesh, dt, "semi_explicit")
        wa, wb = (a.num("wall_seconds") if a and a.ok else None,
                  b.num("wall_seconds") if b and b.ok else None)
        ratio.append(f"×{wa / wb:.1f}" if wa and wb else "–")
    prow = []
    for r in sorted(penalty, key=lambda r: (_t1_meshes(penalty).index(r.mesh), r.id)):
        used.append(r.id)
        if r.ok:
            prow.append([r.mesh, f"{fmt_g(r.dt, 4)} s", _t1_wall(r),
                         _pct(r.num("energy_error_max")), f"`{r.id}`"])
        else:
            prow.append([r.mesh, f"{fmt_g(r.dt, 4)} s" if r.dt else "–", _t1_cell(r), "–",
                         f"`{r.id}`"])
    s.extra = [("td_table1_table", "Wall time (time loop) and energy error per mesh × Δt × "
                "scheme, μ = 0", ["scheme"] + hdr, rows),
               ("td_table1_ratio", "How much longer the implicit scheme takes than the "
                "semi-explicit one (same machine; – where one of the two did not finish)",
                ["wall-time ratio"] + hdr, [ratio])]
    if prow:
        s.extra.append(("td_table1_penalty", "The explicit penalty scheme at its automatic Δt",
                        ["mesh", "Δt (auto)", "wall time (time loop)", "energy error", "run"],
                        prow))
    s.runs = used
    s.sources = [sw.dir]
    s.files = fig_table1(ctx["out"], "three_d_table1", runs, [r for r in penalty if r.ok])
    stab_txt = _t1_stability(ctx, s)
    rep_txt, thr_txt, warn = _t1_timing_text(sw, runs + penalty)
    ndiv = sum(r.status == "diverged" for r in runs)
    s.caption = (
        "The pattern of the paper's Table 1 (mesh × Δt × scheme; Cros, Feng & Magnain 2010) on "
        "the oblique block (cases/three_d/oblique_block.toml with μ = 0, output every 1e-5 s, "
        "no fields): the 2D mesh M1 extruded through the thickness in 2 or 4 layers of "
        "hexahedra. Left: the time-loop wall time (`wall_seconds` of summary.csv, set-up and "
        f"output excluded; {rep_txt}, {thr_txt}) against Δt; right: the largest relative "
        "error of the energy balance (`energy_error_max`). One line per mesh and scheme; "
        + (f"{ndiv} run{'s' if ndiv != 1 else ''} diverged (X at the top of the panels; the "
           "table gives the time of divergence, the `diverged.time` column). " if ndiv else
           "no run diverged. ")
        + "The penalty scheme runs at its automatic step (`time.dt = \"auto\"`). The tables "
        "below give the cells, the ratio of the two schemes' wall times per cell and the "
        "penalty runs. " + stab_txt
        + "Timings depend on the machine and its load: compare the schemes on one machine (the "
        "ratio), not the seconds across machines. Obtained with `" + _t1_command(sw) + "`"
        + (f" (sweep `{sw.name}`)" if sw.name else "") + "; "
        + doc_link(ctx["out"], T1_ANCHOR, "docs/three-dimensions.md, The 3D Table 1")
        + " discusses them. Runs: " + ", ".join(f"`{i}`" for i in used) + "." + warn)
    return s
