"""Drawing a run's field snapshots (fields/*.vtu, docs/outputs.md) with matplotlib: the
deformed 2D meshes with the case's rigid obstacles, or the deformed surface of a 3D mesh above
its ground plane, coloured by a cell field on one scale for all panels. Used by the `fields`
kind (report_kinds.py) and by the plug-ins that draw their own snapshots."""

import json
import math
import os

import numpy as np

import report_figures as F
from report_io import field_files, fmt_dt, fmt_g, read_case, read_vtu, resolve_case_file, scheme_name

MAX_PANELS = 6


def _label(cb, field):
    """The colour bar's label: von Mises in Pa with its power of ten, else the field's name."""
    if field == "von_mises":
        return F._sci(cb) + ", cell"
    return F._sci(cb, unit="", what=field) + ", cell"


def find_fields(folder):
    """The folder holding the VTU files of a run: FOLDER/fields, else FOLDER itself."""
    if not folder:
        return None
    for d in (os.path.join(folder, "fields"), folder):
        if os.path.isdir(d) and field_files(d):
            return d
    return None



def obstacle_artists(ax, obstacles, scale=1e3):
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


def fig_shapes_2d(outdir, stem, frames, obstacles, probes, title, field="von_mises"):
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
    has_vm = all(field in v["cell_data"] for _, v in frames)
    norm = None
    if has_vm:
        vmax = max(float(np.max(v["cell_data"][field])) for _, v in frames) or 1.0
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
            pc = PolyCollection(polys, array=v["cell_data"][field], cmap=F.CMAP,
                                norm=norm, edgecolors="face", linewidths=0.3, zorder=1)
            ax.add_collection(pc)
        else:
            body = v["cell_data"].get("body", np.zeros(len(polys)))
            ax.add_collection(PolyCollection(
                polys, facecolors=[("#c6dbef", "#fdd0a2")[int(b) % 2] for b in body],
                edgecolors="face", linewidths=0.3, zorder=1))
        ax.add_collection(PolyCollection(polys, facecolors="none", edgecolors=(0, 0, 0, 0.45),
                                         linewidths=0.25, zorder=1.5))
        handles = obstacle_artists(ax, obstacles)
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
        cb.set_label(_label(cb, field))
    fig.suptitle(title, fontsize=10, y=1 - 0.12 / fh)
    return F.save(fig, outdir, stem, svg=False)


# The faces of a VTK hexahedron and tetrahedron, corners counter-clockwise seen from outside
# (solver/model/mesh3.hpp, kHexFaces and kTetFaces).
HEX_FACES = ((0, 4, 7, 3), (1, 2, 6, 5), (0, 1, 5, 4), (3, 7, 6, 2), (0, 3, 2, 1), (4, 5, 6, 7))
TET_FACES = ((0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2))


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



def fig_shapes_3d(outdir, stem, frames, title, ground_y=0.0, field="von_mises"):
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
    vmax = max((float(np.max(v["cell_data"][field])) for _, v in frames
                if field in v["cell_data"]), default=1.0) or 1.0
    norm = Normalize(0.0, vmax)
    cmap = plt.get_cmap(F.CMAP)
    fig = plt.figure(figsize=(4.2 * ncol + 1.2, 4.0 * nrow + 0.6))
    for k, (t, v) in enumerate(frames):
        ax = fig.add_subplot(nrow, ncol, k + 1, projection="3d")
        ax.computed_zorder = False  # the plane below the body, whatever mplot3d's depth sort says
        p = v["points3"] * 1e3
        faces = boundary_faces(v["cells"])
        vm = v["cell_data"].get(field)
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
    cb.set_label(_label(cb, field))
    fig.suptitle(title, fontsize=10)
    return F.save(fig, outdir, stem, svg=False)


def run_frames(folder, times=None, max_panels=MAX_PANELS):
    """(fields folder, [(time, vtu)]) of a run folder: the snapshots nearest `times` (s), else
    at most max_panels spread over the run; (None, []) without field files."""
    fdir = find_fields(folder)
    if fdir is None:
        return None, []
    files = field_files(fdir)
    if times:
        files = list(dict.fromkeys(min(files, key=lambda f: abs(f[0] - t)) for t in times))
    elif len(files) > max_panels:
        keep = np.unique(np.round(np.linspace(0, len(files) - 1, max_panels)).astype(int))
        files = [files[i] for i in keep]
    return fdir, [(t, read_vtu(p)) for t, p in files]


def run_summary(folder):
    try:
        with open(os.path.join(folder, "summary.json")) as f:
            return json.load(f)
    except (OSError, ValueError):
        return {}


def draw_run_fields(out, stem, folder, field="von_mises", times=None):
    """Draws the run's snapshots (2D: with the case's obstacles and probes; 3D: above the plane
    y = 0) coloured by the cell field. {"files", "caption"}."""
    fdir, frames = run_frames(folder, times)
    summ = run_summary(folder)
    scheme = scheme_name(summ.get("scheme", "")) or "?"
    dt = summ.get("dt")
    title = (f"{summ.get('case', os.path.basename(folder))}, {scheme}"
             + (f", Δt = {fmt_dt(dt)} s" if isinstance(dt, (int, float)) else ""))
    three = all("points3" in v for _, v in frames)
    obstacles = []
    if three:
        files = fig_shapes_3d(out, stem, frames, title, field=field)
    else:
        case_path = resolve_case_file(summ.get("case_file"))
        if case_path:
            case = read_case(case_path, summ.get("overrides") or [])
            obstacles = [o for o in case.get("obstacles", []) if isinstance(o, dict)]
        probes = [(p.get("name", "?"), int(p["node"])) for p in summ.get("probes", [])
                  if isinstance(p.get("node"), int)]
        files = fig_shapes_2d(out, stem, frames, obstacles, probes, title, field=field)
    peaks = [(t, float(np.max(v["cell_data"][field]))) for t, v in frames
             if field in v["cell_data"]]
    caption = (("The deformed surface (3D, boundary faces)" if three else
                "The deformed meshes (true scale, cell outlines)")
               + (f", coloured by the cell field `{field}` on one scale" if peaks else
                  f" (the files hold no cell field `{field}`)")
               + ", at t = " + ", ".join(f"{t * 1e3:.3g}" for t, _ in frames) + " ms (fields/*.vtu"
               + (f" of `{fdir}`" if fdir else "") + ")"
               + (", with the rigid obstacles of the run's case file" if obstacles else "")
               + "." + (" Largest cell value per instant: "
                        + ", ".join(f"{t * 1e3:.3g} ms: {fmt_g(m)}" for t, m in peaks) + "."
                        if peaks else "") + f" Run: {title}.")
    return {"files": files, "caption": caption}
