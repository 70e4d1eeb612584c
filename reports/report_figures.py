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


# ---------------------------------------------------------------------------------------------
# Verification cases (report_verification.py): the analytic reference beside every run

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


def fig_ver_contact_force(outdir, stem, runs, force, duration, p_ref, ref_label, p_label,
                          conserved=False):
    """Top row: normal_force (kN) against time (µs), one panel per run (shared scale), with the
    analytic plateau `force` for `duration`. Bottom: momentum_x of every run with p_ref(t) (or,
    with conserved, each run's initial value)."""
    import textwrap
    n = len(runs)
    fig = plt.figure(figsize=(max(10.5, 2.6 * n + 3.0), 6.8))
    gs = fig.add_gridspec(2, n, height_ratios=[1.15, 1.0], hspace=0.5, wspace=0.08)
    styles = _styles(runs)
    top = []
    alternating = False
    fmax = 0.0
    for j, ((label, r), st) in enumerate(zip(runs, styles)):
        ax = fig.add_subplot(gs[0, j], sharey=top[0] if top else None)
        top.append(ax)
        h = r.history()
        t, f = h["time"] * 1e6, h["normal_force"] / 1e3
        fmax = max(fmax, float(np.nanmax(f)))
        if force and duration:
            tend = max(float(t[-1]), duration * 1e6)
            ax.plot([0, duration * 1e6, duration * 1e6, tend], [force / 1e3] * 2 + [0, 0],
                    color="k", ls="--", lw=1.3, zorder=3)
        if _alternates(h["normal_force"]):
            alternating = True
            ax.plot(t, f, color=st["color"], lw=0.5, alpha=0.3)
            tm, fm = _running_mean(t, f, 2)
            ax.plot(tm, fm, color=st["color"], lw=1.5)
        else:
            ax.plot(t, f, color=st["color"], lw=1.5)
        ax.set_title("\n".join(textwrap.wrap(label, 26)), fontsize=9)
        ax.set_xlabel("time t (µs)")
        if j == 0:
            ax.set_ylabel("contact force normal_force (kN)")
        else:
            plt.setp(ax.get_yticklabels(), visible=False)
    if force:
        topv = min(fmax, 2.5 * force / 1e3) * 1.08
        top[0].set_ylim(-0.04 * topv, topv)
    handles = ([Line2D([0], [0], color="k", ls="--", lw=1.3, label=ref_label)]
               if force and duration else [])
    handles.append(Line2D([0], [0], color="0.3", lw=1.5, label="run: every sample"))
    if alternating:
        handles += [Line2D([0], [0], color="0.3", lw=0.5, alpha=0.4,
                           label="every step (force alternating)"),
                    Line2D([0], [0], color="0.3", lw=1.5, label="…its mean over 2 steps")]
    top[-1].legend(handles=handles, loc="upper left", bbox_to_anchor=(1.03, 1.0),
                   frameon=False)
    ax = fig.add_subplot(gs[1, :])
    for (label, r), st in zip(runs, styles):
        h = r.history()
        ax.plot(h["time"] * 1e6, h["momentum_x"], lw=1.4, label=label, **st)
        if conserved:
            ax.axhline(h["momentum_x"][0], color=st["color"], lw=0.8, ls=":")
    if p_ref is not None:
        tt = np.linspace(0.0, max(float(r.history()["time"][-1]) for _, r in runs), 600)
        pr = p_ref(tt)
        if pr is not None:
            ax.plot(tt * 1e6, pr, color="k", ls="--", lw=1.3, label=p_label)
    ax.set_xlabel("time t (µs)")
    ax.set_ylabel("momentum_x (kg·m/s)")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    return save(fig, outdir, stem)


def fig_ver_sliding(outdir, stem, series, v0, a, t_stop):
    """series = [(label, run, t, v)]: velocity against time beside max(v0 - a t, 0), and the
    difference from it (mm/s)."""
    fig, axes = plt.subplots(1, 2, figsize=(11.0, 4.2))
    styles = _styles([(lab, r) for lab, r, _, _ in series])

    def v_ref(t):
        return np.maximum(v0 - a * t, 0.0)
    tend = max(float(t[-1]) for _, _, t, _ in series)
    tt = np.linspace(0.0, tend, 1000)
    axes[0].plot(tt, v_ref(tt), color="k", ls="--", lw=1.6, zorder=20,
                 label="analytic max(v₀ − μg t, 0)")
    n = len(series)
    for i, ((label, r, t, v), st) in enumerate(zip(series, styles)):
        # the first runs on top: the penalty run's larger wiggles must not hide the others
        axes[0].plot(t, v, lw=1.2, label=label, zorder=2 + n - i, **st)
        axes[1].plot(t, 1e3 * (v - v_ref(t)), lw=0.9, label=label, zorder=2 + n - i, **st)
    for ax in axes:
        ax.axvline(t_stop, color="0.3", ls=":", lw=1.2)
        ax.set_xlabel("time t (s)")
        ax.set_xlim(0, tend)
    axes[0].text(t_stop, 0.12 * v0, f" stop v₀/(μg)\n = {t_stop:.4g} s", fontsize=8,
                 va="bottom", color="0.25")
    axes[0].set_ylabel("velocity momentum_x / m (m/s)")
    axes[0].set_title("centre-of-mass velocity")
    axes[0].legend(loc="upper right", fontsize=8)
    axes[1].axhline(0.0, color="k", lw=0.8)
    axes[1].set_ylabel("momentum_x / m − analytic (mm/s)")
    axes[1].set_title("difference from the analytic velocity")
    axes[1].legend(loc="lower left", fontsize=8)
    return save(fig, outdir, stem)


def fig_ver_impulse(outdir, stem, runs, mu):
    """The impulse path Δp_x against Δp_y (with |Δp_x| = μ Δp_y) and angular_momentum(t)."""
    fig, axes = plt.subplots(1, 2, figsize=(11.0, 4.2))
    styles = _styles(runs)
    ymax = 0.0
    for (label, r), st in zip(runs, styles):
        h = r.history()
        dx, dy = h["momentum_x"] - h["momentum_x"][0], h["momentum_y"] - h["momentum_y"][0]
        ymax = max(ymax, float(np.max(dy)))
        axes[0].plot(dy, dx, lw=1.3, label=label, **st)
        axes[1].plot(ms(h["time"]), h["angular_momentum"], lw=1.3, label=label, **st)
    if mu and ymax > 0:
        yy = np.array([0.0, ymax])
        axes[0].plot(yy, mu * yy, color="k", ls="--", lw=1.2, label=f"|Δp_x| = μ Δp_y, μ = {mu:g}")
        axes[0].plot(yy, -mu * yy, color="k", ls="--", lw=1.2)
    axes[0].set_xlabel("normal impulse Δp_y (kg·m/s)")
    axes[0].set_ylabel("tangential impulse Δp_x (kg·m/s)")
    axes[0].set_title("impulse path")
    axes[1].set_xlabel("time t (ms)")
    axes[1].set_ylabel("angular_momentum (kg·m²/s)")
    axes[1].set_title("spin")
    for ax in axes:
        ax.legend(loc="best", fontsize=8)
    return save(fig, outdir, stem)
