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
import numpy as np  # noqa: E402

from report_io import fmt_dt, scheme_name  # noqa: E402

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


def _sci(cb):
    cb.formatter.set_powerlimits((0, 0))
    cb.formatter.set_useMathText(True)
    cb.update_ticks()


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
    _sci(cb)
    cb.set_label("von Mises stress (Pa), cell maximum")
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
    _sci(cb)
    cb.set_label("von Mises stress (Pa), cell maximum")
    return save(fig, outdir, stem, svg=False)


# ---------------------------------------------------------------------------------------------
# History plots

def fig_energies(outdir, stem, panels):
    """Fig. 3: panels = [(title, run)]; E_c, E_e, E_t (and E_pen) against time."""
    fig, axes = plt.subplots(1, len(panels), figsize=(5.0 * len(panels), 4.0), sharey=True)
    axes = np.atleast_1d(axes)
    for ax, (title, run) in zip(axes, panels):
        h = run.history()
        t = ms(h["time"])
        ax.plot(t, h["kinetic_energy"], color="#1f77b4", label="kinetic $E_c$")
        ax.plot(t, h["strain_energy"], color="#ff7f0e", label="elastic (strain) $E_e$")
        ax.plot(t, h["total_energy"], color="k", lw=1.8, label="total $E_t = E_c + E_e$")
        pen = h.get("contact_energy")
        if pen is not None and np.nanmax(np.abs(pen)) > 0:
            ax.plot(t, h["total_energy"] + pen, color="k", ls=":", lw=1.4,
                    label="$E_t$ + penalty-spring energy")
        ax.set_title(title)
        ax.set_xlabel("time t (ms)")
        ax.set_xlim(0, t[-1])
        ax.legend(loc="center right")
    axes[0].set_ylabel("energy (J)")
    axes[0].set_ylim(bottom=0)
    return save(fig, outdir, stem)


def fig_energy_error(outdir, stem, runs_by_mesh, bound):
    """Fig. 4: energy_error(t) in % for each run, one panel per mesh, bound line."""
    meshes = list(runs_by_mesh)
    fig, axes = plt.subplots(1, len(meshes), figsize=(5.2 * len(meshes), 4.0), sharey=True,
                             squeeze=False)
    axes = axes[0]
    ymax = bound * 100 * 1.3
    for ax, mesh in zip(axes, meshes):
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
        ax.set_xlabel("time t (ms)")
        ax.set_xlim(0, None)
        ax.legend(loc="upper left")
    axes[0].set_ylabel("relative total-energy error (%)")
    axes[0].set_ylim(0, ymax)
    return save(fig, outdir, stem)


def fig_probe(outdir, stem, runs, title, probe="P"):
    """Figs. 5, 6: probe Ux, Uy (mm) against time; runs = [(run, style dict)]."""
    fig, axes = plt.subplots(1, 2, figsize=(10.0, 3.9))
    for comp, ax in zip(("ux", "uy"), axes):
        for r, style in runs:
            h = r.history()
            ax.plot(ms(h["time"]), 1e3 * h[f"{probe}_{comp}"], label=r.label(), **style)
        ax.set_xlabel("time t (ms)")
        ax.set_ylabel(f"$U_{comp[1]}$ of point {probe} (mm)")
        ax.set_title(f"{'horizontal' if comp == 'ux' else 'vertical'} displacement "
                     f"$U_{comp[1]}$, {title}")
        ax.legend(loc="upper left" if comp == "ux" else "lower left")
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
        ax.legend(loc="lower left" if ax is axes[0] else "upper left")
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


def fig_work_precision(outdir, stem, series):
    """series = {scheme: [(cpu_s, err_P, err_E, dt)]}: error against CPU time, log-log."""
    fig, axes = plt.subplots(1, 2, figsize=(10.5, 4.2))
    for scheme, pts in series.items():
        pts = sorted(pts, key=lambda p: -p[3])
        for ax, idx, in ((axes[0], 1), (axes[1], 2)):
            xy = [(p[0], p[idx], p[3]) for p in pts if p[idx] is not None and p[idx] > 0]
            if not xy:
                continue
            x, y, dts = zip(*xy)
            ax.loglog(x, y, marker="o", color=color(scheme), label=scheme_name(scheme))
            for xx, yy, dt in xy:
                ax.annotate(fmt_dt(dt), (xx, yy), textcoords="offset points", xytext=(4, 3),
                            fontsize=7, color=color(scheme))
    axes[0].set_ylabel(r"max$_t$ $|u_P - u_{P,\mathrm{ref}}|$ (m)")
    axes[0].set_title("displacement error of point P")
    axes[1].set_ylabel(r"max$_t$ $|E_t - E_{t,\mathrm{ref}}|\ /\ E_{0,\mathrm{ref}}$ (–)")
    axes[1].set_title("total-energy error")
    for ax in axes:
        ax.set_xlabel("CPU time of the time loop (s)")
        ax.grid(True, which="both", alpha=0.25)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, title="scheme (point labels: Δt in s)", loc="upper center",
               bbox_to_anchor=(0.5, 0.0), ncol=len(labels), frameon=False)
    return save(fig, outdir, stem)


def fig_stability(outdir, stem, entries, table1_marks, table1_dts):
    """entries = [{mesh, scheme, estimate, lo, hi, outcome, cap}]; table1_marks =
    [(mesh, scheme, dt, status)] from the paper sweep."""
    meshes = sorted({e["mesh"] for e in entries} | {m[0] for m in table1_marks})
    schemes = [s for s in ("semi_explicit", "implicit", "explicit_penalty")
               if any(e["scheme"] == s for e in entries)]
    schemes += sorted({e["scheme"] for e in entries} - set(schemes))
    fig, ax = plt.subplots(figsize=(8.5, 4.8))
    w = 0.8 / max(1, len(schemes))
    for dt in table1_dts:
        ax.axhline(dt, color="0.6", ls=":", lw=1.0, zorder=0)
        ax.text(len(meshes) - 0.45, dt, f" Table 1 Δt = {fmt_dt(dt)} s", va="center",
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
    for mesh, scheme, dt, status in table1_marks:
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
    lows = [e["estimate"] for e in entries if e["estimate"]] + list(table1_dts)
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
               label="paper sweep run: ok"),
        Line2D([0], [0], marker="X", mfc="k", mec="k", ls="none", ms=5,
               label="paper sweep run: diverged"),
    ]
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    ax.grid(True, which="both", axis="y", alpha=0.25)
    ax.grid(False, axis="x")
    return save(fig, outdir, stem)
