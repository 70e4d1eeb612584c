"""Table 1 in 3D, the plug-in of cases/three_d_table1/study.toml (docs/studies.md, Writing a
plug-in; docs/three-dimensions.md, The 3D Table 1): the paper's Table 1 (Cros, Feng & Magnain
2010) on the oblique block, wall time and energy error per mesh × Δt × scheme with the penalty
runs at their automatic step, and the largest stable steps of the 3D meshes (the study's
`stability` sweep) beside them."""

import math
import os

import report_figures as F
import report_stability as RS
from report_io import REPO, find_stability_files, fmt_dt, fmt_g, same, show_path
from report_page import Section as PageSection

T1_CMD = ("build/ricochet sweep cases/three_d_table1/sweep_full.toml --out results/three_d_table1 "
          "--repeat 3")
STAB_CMD = "the study's `stability` sweep (cases/three_d_table1/stability.toml)"
DOC = os.path.join(REPO, "docs", "three-dimensions.md")
T1_ANCHOR = "#the-3d-table-1"


def doc_link(out, anchor="", text="docs/three-dimensions.md"):
    return f"[{text}]({os.path.relpath(DOC, out)}{anchor})"


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
                + (f" ({'; '.join(bad)})" if bad else "") + f": {STAB_CMD} did not run in this tier. ")
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
                     "run by `ricochet reproduce three_d_table1`).")
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


# ---------------------------------------------------------------------------------------------
# The plug-in's entry. args.stability: the name of the stability sweep (default "stability").

def table1(ctx, section):
    stab = ctx.sweep(section.get("args", {}).get("stability", "stability"))
    legacy = {"out": ctx.out, "td_t1": ctx.sweep(section["sweep"]),
              "td_stab": find_stability_files([stab.dir]) if stab else []}
    return [sec_table1(legacy, PageSection, "td_table1",
                       "Table 1 in 3D: wall time and energy error per mesh × Δt × scheme")]
