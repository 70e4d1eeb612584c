"""The report's figures (matplotlib, Agg). Each function draws one figure from runs it is given,
saves PNG (and SVG for line plots) into the report folder and returns the file names.

Units on every axis; a legend on every figure; the caller writes the caption naming the runs.
"""

import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.collections import PolyCollection  # noqa: E402
from matplotlib.colors import Normalize  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402
from matplotlib.ticker import FuncFormatter, ScalarFormatter  # noqa: E402
from matplotlib.transforms import Bbox  # noqa: E402
import numpy as np  # noqa: E402

from report_io import fmt_dt, fmt_g, scheme_name  # noqa: E402

plt.rcParams.update({
    "font.size": 10,
    "axes.titlesize": 10.5,
    "axes.labelsize": 10,
    "legend.fontsize": 8.5,
    "xtick.labelsize": 9,
    "ytick.labelsize": 9,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "figure.dpi": 100,
    "savefig.dpi": 150,
    "svg.fonttype": "none",
})

SCHEME_COLORS = {
    "semi_explicit": "#1f77b4",
    "implicit": "#d62728",
    "explicit_penalty": "#2ca02c",
    "explicit": "#9467bd",
}
DT_STYLES = ["-", "--", ":", "-."]
MESH_MARKERS = {"M1": "o", "M2": "s"}
CMAP = "jet"  # the paper's figures use a rainbow scale


def color(scheme):
    return SCHEME_COLORS.get(scheme, "#555555")


def save(fig, outdir, stem, svg=True):
    files = []
    fig.savefig(os.path.join(outdir, stem + ".png"), bbox_inches="tight")
    files.append(stem + ".png")
    if svg:
        fig.savefig(os.path.join(outdir, stem + ".svg"), bbox_inches="tight")
        files.append(stem + ".svg")
    plt.close(fig)
    return files


def ms(t):
    return np.asarray(t) * 1e3


# ---------------------------------------------------------------------------------------------
# Field plots (Figs. 1 and 2)

def _polys(vtu, reference=False):
    pts = vtu["points"] - vtu["displacement"] if reference else vtu["points"]
    pts = pts * 1e3  # mm
    return [pts[c] for c in vtu["cells"]], pts


def _draw_field(ax, vtu, norm, cmap, edges=True):
    polys, pts = _polys(vtu)
    vm = vtu["cell_data"].get("von_mises")
    pc = PolyCollection(polys, array=vm, cmap=cmap, norm=norm,
                        edgecolors=(0, 0, 0, 0.35) if edges else "face",
                        linewidths=0.25 if edges else 0.0)
    ax.add_collection(pc)
    return pc, pts


def _sci(cb, unit="Pa", what="von Mises stress"):
    """Colour-bar ticks as plain numbers with the power of ten in the label, not as an offset
    text above the bar (which collides with the titles beside it)."""
    vmax = max(abs(float(cb.vmin)), abs(float(cb.vmax)))
    e = int(np.floor(np.log10(vmax))) if vmax > 0 and np.isfinite(vmax) else 0
    cb.ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v / 10 ** e:g}"))
    cb.ax.yaxis.get_offset_text().set_visible(False)
    power = f"10$^{{{e}}}$ {unit}" if e else unit
    return f"{what} ({power})"


def plain_axis(ax, which="y"):
    """No offset text ('1e-12+6.4e-1') on an axis: the ticks show the values themselves; a
    power of ten, if any, goes with the ticks as '×10^n'."""
    axis = ax.yaxis if which == "y" else ax.xaxis
    fmt = ScalarFormatter(useOffset=False, useMathText=True)
    fmt.set_powerlimits((-3, 4))
    axis.set_major_formatter(fmt)


def _ground(ax, x0, x1):
    ax.axhline(0.0, color="k", lw=1.2, zorder=3)
    ax.fill_between([x0, x1], [0, 0], [-4, -4], color="0.85", hatch="///", edgecolor="0.5",
                    lw=0, zorder=0)


def fig_deformed_shapes(outdir, stem, frames, ref_vtu, title_run):
    """Fig. 1: the reference mesh, then deformed shapes coloured by cell von Mises at each
    (time, vtu) of frames, one colour scale."""
    vmax = max(float(np.max(v["cell_data"]["von_mises"])) for _, v in frames)
    norm = Normalize(0.0, vmax)
    n = len(frames) + 1
    fig, axes = plt.subplots(1, n, figsize=(2.35 * n + 1.0, 4.2), sharey=True)
    width = 56.0  # mm shown per panel
    # reference configuration
    polys, pts = _polys(ref_vtu, reference=True)
    axes[0].add_collection(PolyCollection(polys, facecolors="0.93", edgecolors="0.3",
                                          linewidths=0.3))
    cx = 0.5 * (pts[:, 0].min() + pts[:, 0].max())
    axes[0].set_xlim(cx - width / 2, cx + width / 2)
    _ground(axes[0], cx - width / 2, cx + width / 2)
    axes[0].set_title("t = 0 (mesh)")
    axes[0].annotate("", xy=(cx - 16, 88), xytext=(cx - 22, 98),
                     arrowprops=dict(arrowstyle="->", color="k", lw=1.2))
    axes[0].text(cx - 14, 92, "v₀ = (3, −5) m/s", fontsize=7.5)
    pc = None
    for ax, (t, v) in zip(axes[1:], frames):
        pc, pts = _draw_field(ax, v, norm, CMAP)
        cx = 0.5 * (pts[:, 0].min() + pts[:, 0].max())
        ax.set_xlim(cx - width / 2, cx + width / 2)
        _ground(ax, cx - width / 2, cx + width / 2)
        k = int(np.argmax(v["cell_data"]["von_mises"]))
        ax.set_title(f"t = {t * 1e3:g} ms\nmax {v['cell_data']['von_mises'][k]:.3g} Pa")
    for ax in axes:
        ax.set_aspect("equal")
        ax.set_ylim(-4, 100)
        ax.set_xlabel("x (mm)")
        ax.grid(False)
    axes[0].set_ylabel("y (mm)")
    handles = [Line2D([0], [0], color="k", lw=1.2, label="rigid ground y = 0"),
               Line2D([0], [0], color="0.3", lw=0.6, marker="s", mfc="0.93", ls="none", ms=8,
                      label="undeformed mesh (t = 0)")]
    fig.legend(handles=handles, loc="lower center", ncol=2, bbox_to_anchor=(0.45, -0.04),
               frameon=False)
    cb = fig.colorbar(pc, ax=list(axes), fraction=0.025, pad=0.01)
    cb.set_label(_sci(cb) + ", cell maximum")
    fig.suptitle(title_run, y=1.02, fontsize=10)
    return save(fig, outdir, stem, svg=False)


def fig_von_mises_pair(outdir, stem, panels):
    """Fig. 2: panels = [(title, vtu)] side by side on one colour scale, maximum marked."""
    vmax = max(float(np.max(v["cell_data"]["von_mises"])) for _, v in panels)
    norm = Normalize(0.0, vmax)
    fig, axes = plt.subplots(1, len(panels), figsize=(3.6 * len(panels) + 1.2, 5.0),
                             sharey=True)
    axes = np.atleast_1d(axes)
    pc = None
    for ax, (title, v) in zip(axes, panels):
        pc, pts = _draw_field(ax, v, norm, CMAP, edges=len(v["cells"]) < 1000)
        x0, x1 = pts[:, 0].min() - 4, pts[:, 0].max() + 4
        ax.set_xlim(x0, x1)
        _ground(ax, x0, x1)
        vm = v["cell_data"]["von_mises"]
        k = int(np.argmax(vm))
        c = np.mean(pts[v["cells"][k]], axis=0)
        ax.plot(c[0], c[1], marker="*", ms=13, mfc="white", mec="k", ls="none",
                label=f"max {vm[k]:.4g} Pa at y = {c[1]:.1f} mm")
        ax.set_title(title)
        ax.set_aspect("equal")
        ax.set_ylim(-4, 92)
        ax.set_xlabel("x (mm)")
        ax.grid(False)
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.12), frameon=False)
    axes[0].set_ylabel("y (mm)")
    cb = fig.colorbar(pc, ax=list(axes), fraction=0.04, pad=0.02)
    cb.set_label(_sci(cb) + ", cell maximum")
    return save(fig, outdir, stem, svg=False)


# ---------------------------------------------------------------------------------------------
# History plots

def _nonzero(h, name):
    a = h.get(name)
    return a is not None and bool(np.nanmax(np.abs(a)) > 0)


def _fig_legend_below(fig, axes, ncol=4, y=-0.02):
    """One legend under the panels: the union of their labelled lines, in order."""
    seen, handles = set(), []
    for ax in np.atleast_1d(axes):
        for hd, lab in zip(*ax.get_legend_handles_labels()):
            if lab not in seen and not lab.startswith("_"):
                seen.add(lab)
                handles.append(hd)
    fig.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, y),
               ncol=min(ncol, max(1, len(handles))), frameon=False)


def fig_energies(outdir, stem, panels):
    """Fig. 3: panels = [(title, run)]; E_c, E_e and the total against time. Where the run has
    penalty springs, the total counts their energy (the balance of `energy_error`), and the
    springs' energy and E_c + E_e without it are drawn too."""
    fig, axes = plt.subplots(1, len(panels), figsize=(5.0 * len(panels), 3.9), sharey=True)
    axes = np.atleast_1d(axes)
    for ax, (title, run) in zip(axes, panels):
        h = run.history()
        t = ms(h["time"])
        ax.plot(t, h["kinetic_energy"], color="#1f77b4", label="kinetic $E_c$")
        ax.plot(t, h["strain_energy"], color="#ff7f0e", label="elastic (strain) $E_e$")
        total, _ = energy_balance(h)
        if _nonzero(h, "contact_energy"):
            ax.plot(t, h["contact_energy"], color="#2ca02c", label="penalty-spring energy $E_{pen}$")
            ax.plot(t, h["total_energy"], color="0.45", ls="--", lw=1.2,
                    label="$E_c + E_e$ (springs not counted)")
        ax.plot(t, total, color="k", lw=1.8,
                label="total $E_t = E_c + E_e + E_{pen}$ ($E_{pen}$ = 0 without springs)")
        ax.set_title(title)
        ax.set_xlabel("time t (ms)")
        ax.set_xlim(0, t[-1])
    axes[0].set_ylabel("energy (J)")
    axes[0].set_ylim(bottom=0)
    _fig_legend_below(fig, axes, ncol=3, y=0.0)
    return save(fig, outdir, stem)


def _on_time(run, ref, col):
    """(t, run[col] − ref[col] interpolated at the run's samples), over the common time."""
    h, g = run.history(), ref.history()
    t = h["time"]
    m = t <= g["time"][-1] * (1 + 1e-9)
    return t[m], h[col][m] - np.interp(t[m], g["time"], g[col])


def fig_energy_error(outdir, stem, runs_by_mesh, bound, pairs=None):
    """Fig. 4: energy_error(t) in % for each run, one panel per mesh, bound line. Under each
    panel, for pairs[mesh] = [(semi-explicit run, implicit run)] at the same Δt, the
    difference of their energy errors in percentage points."""
    meshes = list(runs_by_mesh)
    pairs = pairs or {}
    fig, axes = plt.subplots(2, len(meshes), figsize=(5.2 * len(meshes), 6.6), sharey="row",
                             squeeze=False, gridspec_kw=dict(height_ratios=[1.0, 0.7]),
                             sharex="col")
    ymax = bound * 100 * 1.3
    for k, mesh in enumerate(meshes):
        ax, dax = axes[0][k], axes[1][k]
        dts = sorted({r.dt for r in runs_by_mesh[mesh]}, reverse=True)
        for r in runs_by_mesh[mesh]:
            h = r.history()
            y = 100 * h["energy_error"]
            ymax = max(ymax, float(np.nanmax(y)) * 1.1)
            ax.plot(ms(h["time"]), y, color=color(r.scheme),
                    ls=DT_STYLES[dts.index(r.dt) % len(DT_STYLES)],
                    label=f"{scheme_name(r.scheme)}, Δt = {fmt_dt(r.dt)} s")
        ax.axhline(bound * 100, color="0.2", ls="--", lw=1.2,
                   label=f"{bound * 100:g} % (paper: error mostly below)")
        ax.set_title(f"mesh {mesh}, μ = 0")
        ax.set_xlim(0, None)
        dax.axhline(0.0, color="k", lw=0.7)
        for a, b in pairs.get(mesh, []):
            t, d = _on_time(a, b, "energy_error")
            dax.plot(ms(t), 100 * d, color="k", lw=1.3,
                     ls=DT_STYLES[dts.index(a.dt) % len(DT_STYLES)],
                     label=f"{scheme_name(a.scheme)} − {scheme_name(b.scheme)}, "
                           f"Δt = {fmt_dt(a.dt)} s")
        if not pairs.get(mesh):
            dax.text(0.5, 0.5, "no Δt at which both schemes are ok", ha="center",
                     va="center", transform=dax.transAxes, color="0.4")
        dax.set_xlabel("time t (ms)")
        dax.set_title("semi-explicit − implicit at the same Δt", fontsize=9)
        plain_axis(dax)
    axes[0][0].set_ylabel("energy error (%)")
    axes[0][0].set_ylim(0, ymax)
    axes[1][0].set_ylabel("difference (percentage points)")
    # one legend per mesh, under its column: the runs above, then the differences
    for k in range(len(meshes)):
        h0, l0 = axes[0][k].get_legend_handles_labels()
        h1, l1 = axes[1][k].get_legend_handles_labels()
        axes[1][k].legend(h0 + h1, l0 + l1, loc="upper center", bbox_to_anchor=(0.5, -0.3),
                          ncol=2, frameon=False, fontsize=8)
    fig.subplots_adjust(hspace=0.28)
    return save(fig, outdir, stem)


def fig_probe(outdir, stem, runs, title, probe="P", refs=None):
    """Figs. 5, 6: probe Ux, Uy (mm) against time; runs = [(run, style dict)]. Below, per mesh,
    each other run minus refs[mesh] (the implicit run at the smallest Δt on the mesh), in mm:
    the curves above lie on top of each other."""
    refs = refs or {}
    fig, axes = plt.subplots(2, 2, figsize=(10.0, 6.4), sharex="col",
                             gridspec_kw=dict(height_ratios=[1.0, 0.75]))
    for j, comp in enumerate(("ux", "uy")):
        ax, dax = axes[0][j], axes[1][j]
        for r, style in runs:
            h = r.history()
            ax.plot(ms(h["time"]), 1e3 * h[f"{probe}_{comp}"], label=r.label(), **style)
            ref = refs.get(r.mesh)
            if ref is not None and r is not ref:
                t, d = _on_time(r, ref, f"{probe}_{comp}")
                dax.plot(ms(t), 1e6 * d, label=f"{r.label()} − {scheme_name(ref.scheme)}",
                         **style)
        dax.axhline(0.0, color="k", lw=0.7)
        ax.set_ylabel(f"$U_{comp[1]}$ of point {probe} (mm)")
        ax.set_title(f"{'horizontal' if comp == 'ux' else 'vertical'} displacement "
                     f"$U_{comp[1]}$, {title}")
        dax.set_xlabel("time t (ms)")
        dax.set_ylabel(f"difference in $U_{comp[1]}$ (µm)")
        dax.set_title("semi-explicit − implicit, same mesh and Δt", fontsize=9)
        plain_axis(dax)
    _fig_legend_below(fig, axes[0], ncol=2, y=0.02)
    fig.subplots_adjust(hspace=0.3, wspace=0.3, bottom=0.14)
    return save(fig, outdir, stem)


def fig_friction_energy(outdir, stem, runs):
    """Fig. 7: E_t(t) − E_t(0) and the friction dissipation D(t) for each run."""
    fig, axes = plt.subplots(1, 2, figsize=(10.5, 4.0))
    combos = []
    for r in runs:
        key = (r.mesh, r.dt)
        if key not in combos:
            combos.append(key)
    palette = ["#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#e377c2"]
    for r in runs:
        h = r.history()
        c = palette[combos.index((r.mesh, r.dt)) % len(palette)]
        ls = "-" if r.scheme == "semi_explicit" else "--"
        lab = r.label()
        axes[0].plot(ms(h["time"]), h["total_energy"] - h["total_energy"][0], color=c, ls=ls,
                     label=lab)
        axes[1].plot(ms(h["time"]), h["friction_dissipation"], color=c, ls=ls, label=lab)
    axes[0].set_ylabel("change of total energy $E_t(t) − E_t(0)$ (J)")
    axes[0].set_title("total energy dissipation, μ = 0.1")
    axes[1].set_ylabel("friction dissipation D(t) (J)")
    axes[1].set_title("frictional slip work, μ = 0.1")
    for ax in axes:
        ax.set_xlabel("time t (ms)")
    _fig_legend_below(fig, axes[:1], ncol=4, y=0.0)
    return save(fig, outdir, stem)


def fig_penetration(outdir, stem, runs, floor=1e-24):
    """Penetration depth (max over contact nodes) against time, log scale; zeros at floor."""
    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    for r, style in runs:
        h = r.history()
        y = np.maximum(h["penetration_max"], floor)
        ax.semilogy(ms(h["time"]), y, label=r.label(), **style)
    ax.axhline(floor, color="0.5", lw=0.8)
    ax.text(0.98, floor * 3, f"zero is drawn at {floor:g} m", color="0.4", fontsize=8,
            ha="right", transform=ax.get_yaxis_transform())
    ax.set_xlabel("time t (ms)")
    ax.set_ylabel("largest penetration behind the ground (m)")
    ax.set_ylim(floor / 10, None)
    ax.legend(loc="center right")
    return save(fig, outdir, stem)


def fig_stability(outdir, stem, entries, marks, mark_dts, dt_label="Δt of the runs",
                  mark_label="sweep run"):
    """entries = [{mesh, scheme, estimate, lo, hi, outcome, cap}]; marks =
    [(mesh, scheme, dt, status)] from the sweep (the paper's: its Table 1 runs)."""
    meshes = sorted({e["mesh"] for e in entries} | {m[0] for m in marks})
    schemes = [s for s in ("semi_explicit", "implicit", "explicit_penalty")
               if any(e["scheme"] == s for e in entries)]
    schemes += sorted({e["scheme"] for e in entries} - set(schemes))
    fig, ax = plt.subplots(figsize=(8.5, 4.8))
    w = 0.8 / max(1, len(schemes))
    for dt in mark_dts:
        ax.axhline(dt, color="0.6", ls=":", lw=1.0, zorder=0)
        ax.text(len(meshes) - 0.45, dt, f" {dt_label} = {fmt_dt(dt)} s", va="center",
                fontsize=7.5, color="0.35")
    for e in entries:
        i = meshes.index(e["mesh"])
        j = schemes.index(e["scheme"])
        x = i - 0.4 + w * (j + 0.5)
        c = color(e["scheme"])
        ax.plot([x - w * 0.4, x + w * 0.4], [e["estimate"], e["estimate"]], color="k", lw=2.2)
        capped = e["outcome"] == "no_unstable_up_to_cap"
        if e["lo"] is not None:
            ax.plot(x - w * 0.06, e["lo"], marker=r"$\uparrow$" if capped else "o",
                    ms=14 if capped else 8, color=c, ls="none")
            ax.text(x, 0.03, f"{e['lo'] / e['estimate']:.3g}×" + (" (cap)" if capped else ""),
                    transform=ax.get_xaxis_transform(), ha="center", fontsize=8, color=c)
        if e["hi"] is not None:
            ax.plot(x + w * 0.16, e["hi"], marker="x", ms=8, mew=2, color=c, ls="none")
    for mesh, scheme, dt, status in marks:
        if scheme not in schemes:
            continue
        i = meshes.index(mesh)
        j = schemes.index(scheme)
        x = i - 0.4 + w * (j + 0.5) - w * 0.34
        ax.plot(x, dt, marker="s" if status == "ok" else "X", ms=5,
                mfc="none" if status == "ok" else "k", mec="k", ls="none")
    ax.set_xticks(range(len(meshes)))
    ax.set_xticklabels(meshes)
    ax.set_xlim(-0.5, len(meshes) - 0.5 + 0.55)
    ax.set_yscale("log")
    lows = [e["estimate"] for e in entries if e["estimate"]] + list(mark_dts) + \
        [m[2] for m in marks if m[1] in schemes]
    if lows:
        ax.set_ylim(min(lows) / 5, None)
    ax.set_xlabel("mesh (numbers at the bottom: largest stable Δt / estimate)")
    ax.set_ylabel("time step Δt (s)")
    handles = [Line2D([0], [0], color=color(s), lw=6, label=scheme_name(s)) for s in schemes]
    handles += [
        Line2D([0], [0], color="k", lw=2.2, label="estimate Δt_crit = min L_e/c_p"),
        Line2D([0], [0], marker="o", color="0.3", ls="none", ms=7, label="largest stable Δt"),
        Line2D([0], [0], marker="x", color="0.3", ls="none", ms=7, mew=2,
               label="smallest unstable Δt"),
        Line2D([0], [0], marker=r"$\uparrow$", color="0.3", ls="none", ms=11,
               label="stable up to the search cap (no instability found)"),
        Line2D([0], [0], marker="s", mfc="none", mec="k", ls="none", ms=5,
               label=f"{mark_label}: ok"),
        Line2D([0], [0], marker="X", mfc="k", mec="k", ls="none", ms=5,
               label=f"{mark_label}: diverged"),
    ]
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    ax.grid(True, which="both", axis="y", alpha=0.25)
    ax.grid(False, axis="x")
    return save(fig, outdir, stem)


# ---------------------------------------------------------------------------------------------
# Line styles of several runs of one scheme

def _styles(runs):
    """One (colour, line style) per run: the scheme's colour; a second run of the same scheme
    gets a dashed line, a third a dotted one."""
    seen, out = {}, []
    for _, r in runs:
        k = seen.get(r.scheme, 0)
        seen[r.scheme] = k + 1
        out.append(dict(color=color(r.scheme), ls=DT_STYLES[k % len(DT_STYLES)]))
    return out


def _alternates(f):
    """True when a force history jumps from step to step by more than a third of its size
    (the implicit scheme's wall contact)."""
    pos = f[f > 0]
    if len(f) < 8 or pos.size < 4:
        return False
    return float(np.median(np.abs(np.diff(f)))) > float(np.median(pos)) / 3


def _running_mean(t, f, n):
    if len(f) < n:
        return t, f
    k = np.ones(n) / n
    return np.convolve(t, k, mode="valid"), np.convolve(f, k, mode="valid")


# ---------------------------------------------------------------------------------------------
# Any run: its history.csv as small multiples (report_generic.py, plot_run.py)

PROBE_COLORS = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#8c564b", "#17becf"]
MAX_PROBES = 6


def time_unit(tmax):
    """(factor, unit) for a time axis that ends at tmax seconds."""
    if tmax < 1e-3:
        return 1e6, "µs"
    if tmax < 1.0:
        return 1e3, "ms"
    return 1.0, "s"


def length_unit(vmax):
    """(factor, unit) for lengths up to vmax metres; below 0.1 µm None (use scaled_ylabel)."""
    if vmax >= 0.1:
        return 1.0, "m"
    if vmax >= 1e-4:
        return 1e3, "mm"
    if vmax >= 1e-7:
        return 1e6, "µm"
    return None


def scaled_ylabel(ax, what, unit, vmax):
    """The y axis labelled 'what (unit)', or 'what (10^e unit)' with the ticks divided by 10^e
    when vmax is outside [1e-3, 1e4): the power of ten in the label, never as an offset text
    over the axis (where it collides with the title)."""
    if not (vmax > 0 and np.isfinite(vmax)) or 1e-3 <= vmax < 1e4:
        plain_axis(ax)
        ax.set_ylabel(f"{what} ({unit})")
        return
    e = int(np.floor(np.log10(vmax)))
    ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v / 10 ** e:g}"))
    ax.set_ylabel(f"{what} (10$^{{{e}}}$ {unit})")


def _length_axis(ax, what, vmax):
    """(factor to multiply metres by, ) after labelling the axis for lengths up to vmax."""
    lu = length_unit(vmax)
    if lu is None:
        scaled_ylabel(ax, what, "m", vmax)
        return 1.0
    plain_axis(ax)
    ax.set_ylabel(f"{what} ({lu[1]})")
    return lu[0]


def history_probes(h):
    """Probe names with both <probe>_ux and <probe>_uy columns, in column order."""
    return [c[:-3] for c in h if c.endswith("_ux") and c[:-3] + "_uy" in h]


def energy_balance(h, e0=None):
    """(total, balance): total = E_kin + E_strain + E_hg + E_contact, balance = total + D −
    W_ext − E0 [J], the numerator of `energy_error` (docs/outputs.md). E0 is the run's
    `initial_energy` (summary.json) when given, else the total of the first sample (which can
    differ: the first sample's velocities already include the first contact reactions)."""
    zero = np.zeros_like(h["time"])
    total = h.get("total_energy", zero) + h.get("contact_energy", zero)
    if e0 is None or not np.isfinite(e0):
        e0 = total[0]
    bal = total + h.get("friction_dissipation", zero) - h.get("external_work", zero) - e0
    return total, bal


def _legend_under(ax, ncol=2):
    hd, lab = ax.get_legend_handles_labels()
    if hd:
        ax.legend(hd, lab, loc="upper center", bbox_to_anchor=(0.5, -0.17), ncol=ncol,
                  frameon=False, fontsize=7.5, handlelength=1.8, columnspacing=1.0,
                  labelspacing=0.3)


def fig_run_history(path, h, title, dpi=110, e0=None):
    """One run's history.csv (h: column -> array) in four panels: energies with the balance
    (E0 = e0, the run's initial_energy, else the first sample's total), contact forces,
    penetration, probe displacements. Writes the PNG at path."""
    # a run that stopped at once has one or two samples: draw points, not invisible lines
    with plt.rc_context({"lines.marker": "o"} if len(h["time"]) < 3 else {}):
        return _fig_run_history(path, h, title, dpi, e0)


def _fig_run_history(path, h, title, dpi, e0):
    t = h["time"]
    tf, tu = time_unit(float(np.nanmax(t)) if len(t) else 0.0)
    tt = t * tf
    fig, axes = plt.subplots(1, 4, figsize=(14.0, 4.3))
    zero = np.zeros_like(t)
    # energies
    ax = axes[0]
    ax.plot(tt, h.get("kinetic_energy", zero), color="#1f77b4", label="kinetic")
    ax.plot(tt, h.get("strain_energy", zero), color="#ff7f0e", label="strain")
    for col, c, lab in (("hourglass_energy", "#8c564b", "hourglass"),
                        ("contact_energy", "#2ca02c", "contact (penalty springs)"),
                        ("friction_dissipation", "#d62728", "friction dissipation D"),
                        ("external_work", "#9467bd", "external work W")):
        if _nonzero(h, col):
            ax.plot(tt, h[col], color=c, lw=1.1, label=lab)
    total, bal = energy_balance(h, e0)
    ax.plot(tt, total, color="k", lw=1.6, label="total E" + (" (springs counted)"
                                                             if _nonzero(h, "contact_energy")
                                                             else ""))
    err = h.get("energy_error")
    ax.plot(tt, bal, color="0.45", ls="--", lw=1.2, label="balance E + D − W − E₀")
    scaled_ylabel(ax, "energy", "J", max(float(np.nanmax(np.abs(ln.get_ydata()))) for ln in
                                         ax.get_lines()))
    ax.set_title(f"energies; |balance| ≤ {fmt_g(float(np.nanmax(np.abs(bal))), 2)} J"
                 + (f" ({100 * float(np.nanmax(err)):.2g} %)" if err is not None
                    and np.any(np.isfinite(err)) else ""))
    _legend_under(ax, ncol=1)
    # contact forces
    ax = axes[1]
    if _nonzero(h, "normal_force") or _nonzero(h, "tangential_force"):
        ax.plot(tt, h.get("normal_force", zero), color="#1f77b4", label="normal_force")
        ax.plot(tt, h.get("tangential_force", zero), color="#d62728", lw=1.1,
                label="tangential_force")
        _legend_under(ax)
    else:
        ax.text(0.5, 0.5, "no contact force" if "normal_force" in h else "no force columns",
                transform=ax.transAxes, ha="center", va="center", color="0.4")
    fmax = max([float(np.nanmax(np.abs(h[c]))) for c in ("normal_force", "tangential_force")
                if c in h] or [0.0])
    scaled_ylabel(ax, "force", "N", fmax)
    ax.set_title("contact forces (sums)")
    # penetration
    ax = axes[2]
    pen = h.get("penetration_max")
    if pen is not None and np.nanmax(np.abs(pen)) > 0:
        f = _length_axis(ax, "penetration_max", float(np.nanmax(np.abs(pen))))
        ax.plot(tt, pen * f, color="#2ca02c")
        ax.text(0.02, 0.95, f"max {fmt_g(float(np.nanmax(pen)))} m", transform=ax.transAxes,
                va="top", fontsize=8, color="0.25")
    else:
        ax.text(0.5, 0.5, "0 throughout" if pen is not None else "no penetration column",
                transform=ax.transAxes, ha="center", va="center", color="0.4")
        ax.set_ylabel("penetration_max (m)")
        plain_axis(ax)
    ax.set_title("largest penetration")
    # probes
    ax = axes[3]
    probes = history_probes(h)
    shown = probes[:MAX_PROBES]
    if shown:
        vmax = max(float(np.nanmax(np.abs(h[p + s]))) for p in shown for s in ("_ux", "_uy"))
        f = _length_axis(ax, "displacement", vmax)
        for p, c in zip(shown, PROBE_COLORS):
            ax.plot(tt, h[p + "_ux"] * f, color=c, label=f"{p} u_x")
            ax.plot(tt, h[p + "_uy"] * f, color=c, ls="--", label=f"{p} u_y")
        _legend_under(ax, ncol=2)
    else:
        ax.text(0.5, 0.5, "no probes", transform=ax.transAxes, ha="center", va="center",
                color="0.4")
        plain_axis(ax)
    ax.set_title("probes" + (f" (first {MAX_PROBES} of {len(probes)})"
                             if len(probes) > MAX_PROBES else ""))
    for ax in axes:
        ax.set_xlabel(f"time t ({tu})")
        if len(tt):
            ax.set_xlim(tt[0], tt[-1] if tt[-1] > tt[0] else tt[0] + 1)
    fig.suptitle(title, x=0.01, y=0.985, ha="left", fontsize=10)
    # a fixed layout (no bbox_inches="tight": one drawing pass instead of two)
    fig.subplots_adjust(wspace=0.36, left=0.055, right=0.985, top=0.86, bottom=0.40)
    try:
        fig.savefig(path, dpi=dpi)
    finally:
        plt.close(fig)
    return path


# ---------------------------------------------------------------------------------------------
# Work-precision (report_generic.py): error against time-loop wall time, per metric

WP_MARKERS = ["o", "s", "^", "D", "v", "P", "X", "*"]


def pareto_front(points):
    """The non-dominated points of one series: no other point is both cheaper (smaller x) and
    more accurate (smaller y). points = [(x, y, ...)]; returned sorted by x."""
    front, best = [], np.inf
    for p in sorted(points, key=lambda p: (p[0], p[1])):
        if p[1] < best:
            front.append(p)
            best = p[1]
    return front


def _place_labels(fig, ax, items, avoid):
    """Annotate items = [(x, y, text, colour)] next to their points, each at the first of a few
    offsets where its box stays inside the axes and overlaps neither an earlier label nor a
    marker (avoid = [(x, y)]). Returns the number of labels left out."""
    fig.canvas.draw()
    rend = fig.canvas.get_renderer()
    axbox = ax.get_window_extent(rend)
    boxes = []
    for x, y in avoid:
        px, py = ax.transData.transform((x, y))
        boxes.append(Bbox.from_extents(px - 4, py - 4, px + 4, py + 4))
    cands = [(5, 4, "left", "bottom"), (5, -4, "left", "top"), (-5, 4, "right", "bottom"),
             (-5, -4, "right", "top"), (0, 7, "center", "bottom"), (0, -7, "center", "top"),
             (9, 0, "left", "center"), (-9, 0, "right", "center"), (12, 10, "left", "bottom"),
             (-12, -10, "right", "top")]
    left_out = 0
    for x, y, text, c in items:
        for dx, dy, ha, va in cands:
            a = ax.annotate(text, (x, y), xytext=(dx, dy), textcoords="offset points", ha=ha,
                            va=va, fontsize=7, color=c)
            bb = a.get_window_extent(rend)
            inside = (bb.x0 >= axbox.x0 and bb.x1 <= axbox.x1 and bb.y0 >= axbox.y0
                      and bb.y1 <= axbox.y1)
            if inside and not any(bb.overlaps(b) for b in boxes):
                boxes.append(bb)
                break
            a.remove()
        else:
            left_out += 1
    return left_out


def _slope_guides(ax, xlim, ylim, pts):
    """Lines of slope −1 and −2 (log–log) over up to 30 % of the x range, where they pass
    fewest points (the upper right corner, costly and inaccurate, when it is free). Returns
    points along them (data coordinates) for the label placement to avoid."""
    lx0, lx1 = np.log10(xlim)
    ly0, ly1 = np.log10(ylim)
    wx, wy = lx1 - lx0, ly1 - ly0
    L = min(0.3 * wx, 0.42 * wy)          # in decades; the slope −2 line falls by 2 L
    if L < 0.05 * wy:
        # the x range is too narrow beside the y range: the two guides would look flat and
        # lie on top of each other
        return None
    lp = np.array([((np.log10(x) - lx0) / wx, (np.log10(y) - ly0) / wy) for x, y in pts])

    def near(ua, va):
        """Points within 0.05 (axes fraction) of either guide starting at (ua, va)."""
        n = 0
        for order in (1, 2):
            a = np.array([ua, va])
            b = np.array([ua + L / wx, va - order * L / wy])
            ab = b - a
            tpar = np.clip(((lp - a) @ ab) / (ab @ ab), 0, 1) if len(lp) else np.zeros(0)
            d = np.hypot(*(lp - (a + np.outer(tpar, ab))).T) if len(lp) else np.zeros(0)
            n += int(np.sum(d < 0.05))
        return n
    cands = []
    for va in (0.95, 0.75, 0.05 + 2 * L / wy + 0.02):
        for ua in (0.94 - L / wx, 0.5 - 0.5 * L / wx, 0.05):
            if va - 2 * L / wy >= 0.03:
                cands.append((ua, va))
    ua, va = min(cands, key=lambda c: (near(*c), cands.index(c)))
    xa, ya = lx0 + ua * wx, ly0 + va * wy
    xb = xa + L
    avoid = []
    for order, ls in ((1, "-"), (2, "-.")):
        yb = ya - order * L
        ax.plot(10 ** np.array([xa, xb]), 10 ** np.array([ya, yb]), color="0.3", lw=1.0,
                ls=ls, zorder=1)
        ax.text(10 ** xb, 10 ** yb, f" {order}", fontsize=8, color="0.3", va="center")
        avoid.append((10 ** (xb + 0.02 * wx), 10 ** yb))
        for f in np.linspace(0.0, 1.0, 16):
            avoid.append((10 ** (xa + f * (xb - xa)), 10 ** (ya + f * (yb - ya))))
    return avoid


def _log_span(lo, hi, pad):
    a, b = np.log10(lo), np.log10(hi)
    if b - a < 0.3:
        m = 0.5 * (a + b)
        a, b = m - 0.15, m + 0.15
    w = b - a
    return 10 ** (a - pad[0] * w), 10 ** (b + pad[1] * w)


def fig_work_precision(outdir, stem, panels, ylabel, xlabel, title, floor_label):
    """panels = [(panel title, [point])], one panel per mesh; point = dict(series, color,
    marker, x (wall time), xlo, xhi (or None), y (error > 0), floor (or None), dt). Draws per
    series the points (hollow below their floor), a dotted line in Δt order, the Pareto front as
    a step line, the floor as a band, and slope guides −1 and −2. Returns (files, number of Δt
    labels left out, whether the slope guides were drawn)."""
    n = len(panels)
    fig, axes = plt.subplots(1, n, figsize=(max(6.6, 5.6 * n), 4.6), sharey=True,
                             squeeze=False)
    axes = axes[0]
    allx = [p["x"] for _, pts in panels for p in pts]
    ally = [p["y"] for _, pts in panels for p in pts]
    ally += [p["floor"] for _, pts in panels for p in pts if p.get("floor")]
    xlim = _log_span(min(allx), max(allx), (0.12, 0.12))
    ylim = _log_span(min(ally), max(ally), (0.12, 0.35))
    series_seen = {}
    guides = {}
    any_guides = False
    any_floor = any_below = any_err = False
    left_out = 0
    for ax, (ptitle, pts) in zip(axes, panels):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlim(*xlim)
        ax.set_ylim(*ylim)
        by_series = {}
        for p in pts:
            by_series.setdefault(p["series"], []).append(p)
        floors = {}
        for name, sp in by_series.items():
            c, mk = sp[0]["color"], sp[0]["marker"]
            series_seen.setdefault(name, (c, mk))
            sp = sorted(sp, key=lambda p: -p["dt"] if p["dt"] else 0)
            ax.plot([p["x"] for p in sp], [p["y"] for p in sp], color=c, ls=":", lw=0.9,
                    zorder=2)
            front = pareto_front([(p["x"], p["y"]) for p in sp])
            if len(front) > 1:
                ax.step([q[0] for q in front], [q[1] for q in front], where="post", color=c,
                        lw=1.7, alpha=0.85, zorder=3)
            for p in sp:
                below = p.get("floor") is not None and p["y"] < p["floor"]
                any_below |= below
                if p.get("xlo") is not None and p.get("xhi") is not None and \
                        p["xhi"] > p["xlo"]:
                    any_err = True
                    ax.errorbar([p["x"]], [p["y"]], xerr=[[p["x"] - p["xlo"]], [p["xhi"] - p["x"]]],
                                fmt="none", ecolor=c, elinewidth=0.9, capsize=2.5, zorder=4)
                ax.plot([p["x"]], [p["y"]], marker=mk, ms=6.5, color=c, ls="none",
                        mfc="white" if below else c, mec=c, mew=1.4, zorder=5)
                if p.get("floor"):
                    floors.setdefault(name, p["floor"])
        same_floor = len(set(floors.values())) == 1
        for fl in sorted(set(floors.values())):
            any_floor = True
            # one band per distinct floor; with several, each line in its series' colour
            names_fl = [n for n, f in floors.items() if f == fl]
            c = "0.35" if same_floor else series_seen[names_fl[0]][0]
            ax.axhspan(ylim[0], fl, color="0.5" if same_floor else c, alpha=0.12, lw=0,
                       zorder=0)
            ax.axhline(fl, color=c, ls="--", lw=1.0, zorder=1)
        ax.set_title(ptitle)
        ax.set_xlabel(xlabel)
        ax.grid(True, which="major", alpha=0.3)
        ax.grid(True, which="minor", alpha=0.07)
        # slope guides in the emptier of two corners: upper right (costly and inaccurate,
        # dominated) or lower left (cheap and accurate)
        guides[id(ax)] = _slope_guides(ax, xlim, ylim, [(p["x"], p["y"]) for p in pts])
        any_guides |= guides[id(ax)] is not None
    axes[0].set_ylabel(ylabel)
    handles = [Line2D([0], [0], color=c, marker=mk, ls=":", lw=0.9, ms=6, label=name)
               for name, (c, mk) in series_seen.items()]
    handles.append(Line2D([0], [0], color="0.2", lw=1.7, label="Pareto front of a scheme (step)"))
    if any_guides:
        handles += [Line2D([0], [0], color="0.3", lw=1.0,
                           label="slope −1: 1st order if cost ∝ 1/Δt"),
                    Line2D([0], [0], color="0.3", lw=1.0, ls="-.",
                           label="slope −2: 2nd order if cost ∝ 1/Δt")]
    if any_err:
        handles.append(Line2D([0], [0], color="0.3", marker="|", ms=8, ls="-", lw=0.9,
                              label="wall time min–max over the repeats"))
    if any_floor:
        handles.append(Patch(facecolor="0.5", alpha=0.25, edgecolor="0.35", ls="--",
                             label=floor_label))
    if any_below:
        handles.append(Line2D([0], [0], marker="o", mfc="white", mec="0.2", ls="none", ms=6,
                              label="below the reference uncertainty (not a precise value)"))
    fig.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, 0.0), ncol=3,
               frameon=False, title="point labels: Δt (s)", title_fontsize=8.5)
    fig.suptitle(title, fontsize=10.5)
    fig.tight_layout()
    # the Δt labels last, once the layout is fixed
    for ax, (_, pts) in zip(axes, panels):
        items = [(p["x"], p["y"], fmt_dt(p["dt"]), p["color"]) for p in pts if p["dt"]]
        left_out += _place_labels(fig, ax, items, [(p["x"], p["y"]) for p in pts]
                                  + (guides[id(ax)] or []))
    return save(fig, outdir, stem), left_out, any_guides


# ---------------------------------------------------------------------------------------------
# Series colours beyond the schemes' own

SERIES_COLORS = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2",
                 "#17becf", "#7f7f7f", "#bcbd22"]
