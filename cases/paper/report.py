"""The paper's study page, the plug-in of cases/paper/study.toml (docs/studies.md, Writing a
plug-in): Table 1 and Figs. 1–7 of Cros, Feng & Magnain (2010), "A semi-explicit method to
simulate frictional impact problems", C. R. Mécanique 338, 176–180, with our numbers beside the
paper's (reference/cros2010.toml), and what goes beyond the paper: the stability map and the
penetration per scheme. Each entry reads the layout section's sweep (`table1`, the sweep of
table1.toml with its groups table1, penalty and friction; `stability`, the stability searches
of stability.toml; `accuracy` for the scheme limits)."""

import os

import numpy as np

import report_figures as F
import report_generic as RG
import report_stability as RS
from report_io import (find_stability_files, fmt_dt, fmt_g, read_reference, read_vtu, same,
                       scheme_name, show_path)
from report_page import Section, runs_text

FIG1_TIMES = [5e-4, 1e-3, 2e-3, 3e-3]
FIG2_TIME = 6e-4
PAPER_CMD = "build/ricochet reproduce paper"
STAB_CMD = "build/ricochet reproduce paper --tier full"
STAB_MORE = "(its `stability` sweep)"


# ---------------------------------------------------------------------------------------------
# Helpers on runs

def ok_runs(sweep, group, **kw):
    return [r for r in sweep.find(group=group, **kw) if r.ok and r.history() is not None]


def finest(runs):
    runs = [r for r in runs if r.dt is not None]
    return min(runs, key=lambda r: r.dt) if runs else None


def _on_time_diff(ra, rb, col):
    """ra[col] − rb[col], rb interpolated at ra's samples within rb's time range."""
    ha, hb = ra.history(), rb.history()
    t = ha["time"]
    m = t <= hb["time"][-1] * (1 + 1e-9)
    return ha[col][m] - np.interp(t[m], hb["time"], hb[col])


def interp_diff(ra, rb, col):
    ha, hb = ra.history(), rb.history()
    t = ha["time"]
    m = t <= hb["time"][-1]
    return np.abs(ha[col][m] - np.interp(t[m], hb["time"], hb[col]))


def paper_table1(ref):
    t = ref.get("table1", {})
    cols = list(zip(t.get("mesh", []), t.get("dt", [])))
    return cols, {"semi_explicit": t.get("semi_explicit", []), "implicit": t.get("implicit", [])}


def fmt_s(x):
    if x is None:
        return "–"
    if x >= 100:
        return f"{x:.0f} s"
    if x >= 1:
        return f"{x:.3g} s"
    return f"{x:.3g} s"


def fmt_paper(v):
    if isinstance(v, str):
        return v
    return f"{v:.10g} s"


# ---------------------------------------------------------------------------------------------
# Sections (ctx: main = the table1 sweep, ref = the paper's numbers, out, stab_files)

def sec_table1(ctx):
    s = Section("table1", "Wall time (time loop) per mesh × Δt × scheme, μ = 0, beside the "
                "paper's CPU time", "table")
    s.paper = "Table 1"
    sw, ref = ctx["main"], ctx["ref"]
    cols, paper = paper_table1(ref)
    if not cols:
        cols = [(m, d) for m in ("M1", "M2") for d in (1e-4, 1e-5, 1e-6)]
    s.header = ["scheme (ours: wall time, time loop)"] + \
        [f"{m}, Δt = {fmt_dt(d)} s" for m, d in cols]
    used = []
    timing = "wall_seconds"
    for scheme, label in (("semi_explicit", "Semi-explicit"), ("implicit", "Implicit")):
        row = [f"**{label}**"]
        for k, (mesh, dt) in enumerate(cols):
            pv = paper.get(scheme, [None] * len(cols))
            pv = pv[k] if k < len(pv) else None
            pdiv = isinstance(pv, str)
            rs = sw.find(group="table1", mesh=mesh, scheme=scheme, dt=dt)
            if not rs:
                cell = "not run"
                if pv is not None:
                    cell += f" (paper {fmt_paper(pv)})"
                row.append(cell)
                continue
            r = rs[0]
            used.append(r.id)
            if r.status == "diverged":
                agree = "✓ agrees" if pdiv else "✗ paper stable"
                cell = f"**diverged** at t = {fmt_g(r.num('diverged.time'))} s " \
                       f"(paper {fmt_paper(pv)}; {agree})"
            elif r.status != "ok":
                cell = f"**failed** (paper {fmt_paper(pv)})"
            else:
                w = r.num(timing)
                if pdiv:
                    cell = f"{fmt_s(w)} (paper: divergence ✗)"
                elif pv is not None and w:
                    cell = f"{fmt_s(w)} (paper {fmt_paper(pv)}; speed-up ×{pv / w:.0f})"
                else:
                    cell = fmt_s(w)
            row.append(cell)
        s.rows.append(row)
    s.runs = used
    s.sources = [sw.dir]
    reps = {r.get("repeats") for r in sw.runs if r.get("repeats")}
    rep_txt = (f"medians over {', '.join(sorted(reps))} repeats" if reps and reps != {"1"}
               else "single runs (`--repeat 1`)")
    jobs = sw.meta.get("jobs")
    warn = (f" **The sweep ran {jobs} runs at a time (`--jobs {jobs}`), so these timings are "
            "disturbed; use `--jobs 1` for Table 1.**" if isinstance(jobs, int) and jobs > 1
            else "")
    s.caption = (
        "Each cell: our time-loop wall time (`wall_seconds` of summary.json, set-up and output "
        f"excluded; {rep_txt}), then the paper's CPU time (reference/cros2010.toml, "
        "[table1]) and the speed-up = paper / ours. Diverged cells give the time of "
        "divergence and whether the paper also reports a divergence. The paper's machine and "
        "ours differ by 15 years of hardware, so the speed-up mixes hardware and code; the "
        "ratio table below compares the schemes on one machine. Runs (group `table1` of "
        f"{sw.dir}): " + runs_text(used) + "." + warn)
    # ratio implicit / semi-explicit, ours and paper
    hdr = ["implicit / semi-explicit (ours: wall time, time loop; paper: CPU time)"] + \
        [f"{m}, Δt = {fmt_dt(d)} s" for m, d in cols]
    ours, pap = ["ours"], ["paper"]
    for k, (mesh, dt) in enumerate(cols):
        a = sw.find(group="table1", mesh=mesh, scheme="implicit", dt=dt, status="ok")
        b = sw.find(group="table1", mesh=mesh, scheme="semi_explicit", dt=dt, status="ok")
        ours.append(f"×{a[0].num(timing) / b[0].num(timing):.1f}" if a and b and
                    b[0].num(timing) else "–")
        pi = paper["implicit"][k] if k < len(paper["implicit"]) else None
        ps = paper["semi_explicit"][k] if k < len(paper["semi_explicit"]) else None
        pap.append(f"×{pi / ps:.1f}" if isinstance(pi, (int, float)) and
                   isinstance(ps, (int, float)) else "–")
    s.extra.append(("table1_ratio", "How much longer the implicit scheme takes than the "
                    "semi-explicit one (same machine; – where one of the two diverged)", hdr,
                    [ours, pap]))
    return s


def sec_fig1(ctx):
    s = Section("fig1", "Deformed shapes with von Mises stress, μ = 0.1", "figure")
    s.paper = "Fig. 1"
    sw = ctx["main"]
    cands = [r for r in sw.find(scheme="semi_explicit", status="ok")
             if r.friction is not None and abs(r.friction - 0.1) < 1e-12]
    cands.sort(key=lambda r: (r.group != "friction", {"M1": 0, "M2": 1}.get(r.mesh, 2), r.dt))
    chosen = None
    for r in cands:
        frames = [r.field_at(t) for t in FIG1_TIMES]
        if all(frames):
            chosen = (r, frames)
            break
    if not chosen:
        s.available = False
        s.missing = ("no ok semi-explicit run with μ = 0.1 and fields at 0.5, 1, 2 and 3 ms in "
                     f"{sw.dir}. Run `{PAPER_CMD}` (group `friction`).")
        return s
    r, frames = chosen
    vtus = [(t, F_read(p)) for t, p in frames]
    s.files = F.fig_deformed_shapes(ctx["out"], "fig1_deformed_shapes", vtus, vtus[0][1],
                                    f"{r.mesh}, semi-explicit, Δt = {fmt_dt(r.dt)} s, μ = 0.1")
    s.runs = [r.id]
    s.sources = [r.folder]
    maxes = ", ".join(f"{t * 1e3:g} ms: {float(np.max(v['cell_data']['von_mises'])):.3g} Pa"
                      for t, v in vtus)
    s.caption = (
        f"Oblique impact of the elastic plate on mesh {r.mesh} ({r.row.get('elements')} "
        "elements; the paper's M1 has 379): the undeformed mesh, then the deformed shapes "
        "(true scale) with the cell-maximum von Mises stress at 0.5, 1, 2 and 3 ms, "
        "one colour scale, μ = 0.1. Largest cell value per instant: " + maxes + ". "
        f"Run: `{r.id}` (fields/*.vtu).")
    return s


def F_read(path):
    return read_vtu(path)


def sec_fig2(ctx):
    s = Section("fig2", "Von Mises stress at t = 0.6 ms, μ = 0, semi-explicit and implicit", "figure")
    s.paper = "Fig. 2"
    sw, ref = ctx["main"], ctx["ref"]
    pairs = []
    for mesh in ("M2", "M1"):
        se = sorted([r for r in sw.find(group="table1", mesh=mesh, scheme="semi_explicit",
                                        status="ok") if r.field_at(FIG2_TIME)],
                    key=lambda r: r.dt)
        for r in se:
            im = [q for q in sw.find(group="table1", mesh=mesh, scheme="implicit", status="ok")
                  if same(q.dt, r.dt) and q.field_at(FIG2_TIME)]
            if im:
                pairs.append((r, im[0]))
    if not pairs:
        s.available = False
        s.missing = ("no semi-explicit and implicit pair of ok runs (group `table1`, same "
                     "mesh and Δt) with fields at 0.6 ms in " + sw.dir + f". Run `{PAPER_CMD}`.")
        return s
    a, b = pairs[0]
    va, vb = F_read(a.field_at(FIG2_TIME)[1]), F_read(b.field_at(FIG2_TIME)[1])
    s.files = F.fig_von_mises_pair(ctx["out"], "fig2_von_mises_0.6ms", [
        (f"semi-explicit, {a.mesh}, Δt = {fmt_dt(a.dt)} s, t = {va['time'] * 1e3:g} ms", va),
        (f"implicit, {b.mesh}, Δt = {fmt_dt(b.dt)} s, t = {vb['time'] * 1e3:g} ms", vb)])
    s.runs = [a.id, b.id]
    s.sources = [a.folder, b.folder]
    ma, mb = float(np.max(va["cell_data"]["von_mises"])), float(np.max(vb["cell_data"]["von_mises"]))
    diff = ""
    if len(va["cells"]) == len(vb["cells"]):
        d = np.abs(va["cell_data"]["von_mises"] - vb["cell_data"]["von_mises"])
        diff = (f" Cell by cell the two fields differ by at most {np.max(d):.3g} Pa "
                f"({100 * np.max(d) / max(ma, mb):.1f} % of the maximum; mean "
                f"{np.mean(d):.3g} Pa).")
    s.caption = (
        f"Cell-maximum von Mises stress at t = 0.6 ms, μ = 0, mesh {a.mesh}, Δt = "
        f"{fmt_dt(a.dt)} s, semi-explicit (left) and implicit (right) on one colour scale; the "
        f"star marks the largest cell value: {ma:.4g} Pa and {mb:.4g} Pa.{diff} As in the paper, "
        "the maximum lies inside the plate, not on the contact surface. "
        f"Runs: `{a.id}`, `{b.id}`.")
    # maxima over the run against the paper's
    vm = ref.get("von_mises_max", {})
    rows = []
    for r, key in ((a, "semi_explicit"), (b, "implicit")):
        ours = r.num("von_mises_max")
        pv = vm.get(key)
        rows.append([scheme_name(key), f"{fmt_g(ours, 4)} Pa",
                     f"{fmt_g(r.num('von_mises_max_time'), 3)} s",
                     f"{pv:.4g} Pa" if pv else "–",
                     f"{100 * (ours / pv - 1):+.1f} %" if pv and ours else "–", f"`{r.id}`"])
    measure = {"cauchy": "Cauchy", "pk2": "second Piola–Kirchhoff",
               "kirchhoff": "Kirchhoff"}.get(a.get("stress_measure") or "", "Cauchy")
    s.extra.append(("vm_max", "Largest von Mises stress over every step of the run (μ = 0), "
                    f"of the {measure} stress (`stress_measure`): ours and the paper's (§3; the "
                    "paper states neither the mesh nor the stress measure). The second "
                    "Piola–Kirchhoff measure is the one that matches the paper's values; the "
                    "Cauchy peak is 10 % lower (docs/oblique-plate.md compares the measures). "
                    "The colour maps above show the same measure.",
                    ["scheme", "ours", "at t", "paper", "ours vs paper", "run"], rows))
    return s


def sec_fig3(ctx):
    s = Section("fig3", "Energies on M2, semi-explicit and explicit penalty", "figure")
    s.paper = "Fig. 3"
    sw, ref = ctx["main"], ctx["ref"]
    se = finest(ok_runs(sw, "table1", mesh="M2", scheme="semi_explicit")) or \
        finest(ok_runs(sw, "table1", scheme="semi_explicit"))
    pen = [r for r in sw.runs if r.group == "penalty" and r.ok and r.history() is not None]
    pen = pen[0] if pen else None
    panels = []
    if se:
        panels.append((f"semi-explicit (bi-potential), {se.mesh}, Δt = {fmt_dt(se.dt)} s", se))
    if pen:
        panels.append((f"explicit penalty (LS-DYNA-like), {pen.mesh}, Δt = {fmt_dt(pen.dt)} s "
                       f"({pen.get('dt_mode') or 'fixed'})", pen))
    if not panels:
        s.available = False
        s.missing = f"no ok run in groups `table1` (semi-explicit) or `penalty` of {sw.dir}. " \
                    f"Run `{PAPER_CMD}`."
        return s
    s.files = F.fig_energies(ctx["out"], "fig3_energies_M2", panels)
    s.runs = [r.id for _, r in panels]
    s.sources = [r.folder for _, r in panels]
    parts = []
    for _, r in panels:
        h = r.history()
        total, _ = F.energy_balance(h, r.num("initial_energy"))
        part = (f"{scheme_name(r.scheme)}: E_t(0) = {total[0]:.4g} J, E_t(end) = "
                f"{total[-1]:.4g} J, largest energy error "
                f"{100 * float(np.nanmax(h['energy_error'])):.2g} %")
        if F._nonzero(h, "contact_energy"):
            ce = h["total_energy"]
            dip = float(np.max(ce[0] - ce)) / ce[0]
            part += (f" (E_c + E_e alone dips by up to {100 * dip:.1f} % of E_t(0) while "
                     f"the springs hold up to {float(np.max(h['contact_energy'])):.3g} J)")
        parts.append(part)
    note = ""
    if pen:
        lsd = ref.get("ls_dyna", {}).get("mean_dt")
        note = (f" Our penalty run's automatic Δt is {fmt_dt(pen.dt)} s"
                + (f" (LS-DYNA in the paper: mean {fmt_dt(lsd)} s)." if lsd else "."))
    else:
        note = f" The penalty run is missing (group `penalty`; run `{PAPER_CMD}`)."
    s.caption = ("Kinetic E_c, elastic E_e and total energy E_t against time, μ = 0. In the "
                 "penalty run the total counts the energy held in the penalty springs, "
                 "E_t = E_c + E_e + E_pen (`contact_energy`; green), as the energy balance "
                 "does; the grey dashed line is E_c + E_e without it. Energy error, as "
                 "everywhere in this report: the `energy_error` column of history.csv, "
                 "|E_c + E_e + E_hg + E_pen + D − E₀ − W_ext| / max(E₀, |W_ext|) "
                 "(docs/outputs.md). " + "; ".join(parts) + "." + note + " Runs: " +
                 runs_text(s.runs) + ".")
    return s


def sec_fig4(ctx):
    s = Section("fig4", "Energy error over time", "figure")
    s.paper = "Fig. 4"
    sw, ref = ctx["main"], ctx["ref"]
    runs = ok_runs(sw, "table1")
    if not runs:
        s.available = False
        s.missing = f"no ok run in group `table1` of {sw.dir}. Run `{PAPER_CMD}`."
        return s
    bound = ref.get("energy", {}).get("error_bound", 0.02)
    by_mesh = {}
    for r in sorted(runs, key=lambda r: (r.mesh, r.scheme != "semi_explicit", -r.dt)):
        by_mesh.setdefault(r.mesh, []).append(r)
    pairs = {}
    for m, rs in by_mesh.items():
        for a in rs:
            if a.scheme != "semi_explicit":
                continue
            b = [q for q in rs if q.scheme == "implicit" and same(q.dt, a.dt)]
            if b:
                pairs.setdefault(m, []).append((a, b[0]))
    s.files = F.fig_energy_error(ctx["out"], "fig4_energy_error", by_mesh, bound, pairs)
    # runs of one scheme and mesh on top of each other: how far apart they are
    apart = []
    for m, rs in by_mesh.items():
        for scheme in ("semi_explicit", "implicit"):
            same_s = sorted([r for r in rs if r.scheme == scheme], key=lambda r: -r.dt)
            for a, b in zip(same_s, same_s[1:]):
                d = 100 * np.abs(_on_time_diff(a, b, "energy_error"))
                if d.size:
                    apart.append(f"{scheme_name(scheme)} on {m}, Δt = {fmt_dt(a.dt)} and "
                                 f"{fmt_dt(b.dt)} s: at most {np.max(d):.2g}, at the end "
                                 f"{d[-1]:.2g}")
    s.runs = [r.id for rs in by_mesh.values() for r in rs]
    s.sources = [sw.dir]
    worst = max(runs, key=lambda r: r.num("energy_error_max") or 0)
    above = [r for r in runs if (r.num("energy_error_max") or 0) > bound]
    s.caption = (
        "Energy error (`energy_error` of history.csv: |E_c + E_e + E_hg + E_pen + D − E₀ − "
        "W_ext| / max(E₀, |W_ext|); here D = 0 since μ = 0, and E_hg = E_pen = W_ext = 0, so "
        "it is the paper's |E_t(t) − E_t(0)| / E_t(0)) for every ok run of group "
        f"`table1`; dashed line: the paper's {bound * 100:g} % (\"l'erreur est le plus souvent "
        "inférieure à 2 %\"). Bottom row: the semi-explicit run's error minus the implicit "
        "run's at the same Δt and mesh, in percentage points. Runs of one scheme at successive "
        "Δt (some lie on top of each other above) differ by (percentage points) "
        + ("; ".join(apart) if apart else "–") + ". "
        f"Largest: {100 * worst.num('energy_error_max'):.2f} % "
        f"({worst.label()}); {len(above)} of {len(runs)} runs exceed {bound * 100:g} %. "
        "Diverged runs are left out (see the failed-runs table). Runs: " + runs_text(s.runs) + ".")
    return s


def _probe_runs(sw, group):
    out = []
    for mesh, ls, lw in (("M2", "-", 1.8), ("M1", "--", 1.2)):
        for scheme in ("semi_explicit", "implicit"):
            r = finest(ok_runs(sw, group, mesh=mesh, scheme=scheme))
            if r is not None and "P_ux" in r.history():
                out.append((r, dict(color=F.color(scheme), ls=ls, lw=lw)))
    return out


def sec_probe(ctx, sid, group, mu, paper_fig):
    s = Section(sid, f"Displacement of point P, μ = {mu:g}", "figure")
    s.paper = paper_fig
    sw = ctx["main"]
    runs = _probe_runs(sw, group)
    if not runs:
        s.available = False
        s.missing = (f"no ok run with probe P in group `{group}` of {sw.dir}. "
                     f"Run `{PAPER_CMD}`.")
        return s
    stem = "fig5_P_displacement_mu0" if sid == "fig5" else "fig6_P_displacement_mu0.1"
    refs = {}   # per mesh the implicit run, when the semi-explicit run has its Δt
    for r, _ in runs:
        if r.scheme == "implicit" and r.mesh not in refs and any(
                q.scheme == "semi_explicit" and q.mesh == r.mesh and same(q.dt, r.dt)
                for q, _ in runs):
            refs[r.mesh] = r
    s.files = F.fig_probe(ctx["out"], stem, runs, f"μ = {mu:g}", refs=refs)
    s.runs = [r.id for r, _ in runs]
    s.sources = [sw.dir]
    parts = []
    for mesh in ("M2", "M1"):
        pair = {r.scheme: r for r, _ in runs if r.mesh == mesh}
        if "semi_explicit" in pair and "implicit" in pair:
            a, b = pair["semi_explicit"], pair["implicit"]
            dx = np.max(interp_diff(a, b, "P_ux"))
            dy = np.max(interp_diff(a, b, "P_uy"))
            parts.append(f"On {mesh} the two schemes differ by at most {dx * 1e6:.3g} µm in U_x "
                         f"and {dy * 1e6:.3g} µm in U_y")
    r0 = runs[0][0]
    h = r0.history()
    parts.append(f"At 3 ms, {r0.label()} gives U_x = {h['P_ux'][-1] * 1e3:.3g} mm, "
                 f"U_y = {h['P_uy'][-1] * 1e3:.3g} mm")
    s.caption = (f"Horizontal U_x and vertical U_y displacement of point P (the lowest point of "
                 f"the arc, the paper does not locate P), implicit and semi-explicit, μ = {mu:g}; "
                 "solid: M2, dashed: M1, each at its smallest Δt in the sweep. The curves lie on "
                 "top of each other; the bottom row shows the semi-explicit run minus the "
                 "implicit run of the same mesh and Δt, in µm. "
                 + ". ".join(parts) + ". Runs (group `" + group + "`): " + runs_text(s.runs)
                 + ".")
    return s


def sec_fig7(ctx):
    s = Section("fig7", "Total energy dissipation with friction, μ = 0.1", "figure")
    s.paper = "Fig. 7"
    sw = ctx["main"]
    runs = sorted(ok_runs(sw, "friction"), key=lambda r: (r.mesh, -r.dt, r.scheme))
    if not runs:
        s.available = False
        s.missing = f"no ok run in group `friction` of {sw.dir}. Run `{PAPER_CMD}`."
        return s
    s.files = F.fig_friction_energy(ctx["out"], "fig7_friction_dissipation", runs)
    s.runs = [r.id for r in runs]
    s.sources = [sw.dir]
    rows = []
    for r in runs:
        h = r.history()
        e0 = h["total_energy"][0]
        de = h["total_energy"][-1] - e0
        rows.append([r.label(), f"{de:.4g} J", f"{100 * de / e0:.2f} %",
                     f"{h['friction_dissipation'][-1]:.4g} J",
                     f"{100 * (r.num('energy_error_max') or 0):.2f} %", f"`{r.id}`"])
    s.extra.append(("fig7_table", "Energy lost by t = 3 ms, μ = 0.1",
                    ["run", "E_t(3 ms) − E_t(0)", "of E_t(0)", "friction dissipation D(3 ms)",
                     "max energy error", "run id"], rows))
    failed = [r for r in sw.find(group="friction") if not r.ok]
    s.caption = ("Left: change of the total energy E_t = E_c + E_e against time with friction "
                 "μ = 0.1, per mesh and Δt (solid: semi-explicit, dashed: implicit); right: "
                 "the frictional slip work D(t). The table below gives the values at 3 ms. "
                 + (f"Not drawn, not ok: {runs_text(r.id for r in failed)}. " if failed else "")
                 + "Runs (group `friction`): " + runs_text(s.runs) + ".")
    return s


def sec_stability(ctx):
    s = Section("stability", "Stability map: largest stable Δt per mesh and scheme (beyond the paper)", "figure")
    files = ctx.get("stab_files") or []
    entries, bad = RS.read_stability_entries(files)
    if not entries:
        s.available = False
        s.missing = ("no stability.json found" + (f" ({'; '.join(bad)})" if bad else "") +
                     ". Run `" + STAB_CMD + "` " + STAB_MORE + " and pass `--stability results/stability` "
                     "(or place the folder next to the paper sweep as `stability/`).")
        return s
    best = RS.best_entries(entries)
    sw = ctx["main"]
    paper = ctx.get("paper", True)
    marks = [(r.mesh, r.scheme, r.dt, r.status)
             for r in (sw.find(group="table1") if paper else sw.find())
             if r.status in ("ok", "diverged") and r.dt is not None]
    marks = [m for m in marks if any(m[0] == e["mesh"] for e in best)]
    if paper:
        cols, _ = paper_table1(ctx["ref"])
        dts = sorted({d for _, d in cols}) or [1e-6, 1e-5, 1e-4]
        s.files = F.fig_stability(ctx["out"], "stability_map", best, marks, dts)
        marks_text = ("Small squares / black X: the Table 1 runs of the paper sweep that "
                      "finished ok / diverged, at the paper's Δt (dotted lines). ")
    else:
        dts = sorted({m[2] for m in marks})
        dts = dts if len(dts) <= 6 else []
        s.files = F.fig_stability(ctx["out"], "stability_map", best, marks, dts,
                                  dt_label="sweep Δt", mark_label="sweep run")
        marks_text = (f"Small squares / black X: the runs of the sweep `{sw.name}` on these "
                      "meshes and schemes that finished ok / diverged"
                      + (", at their Δt (dotted lines). " if dts else ". "))
    s.sources = [e["path"] for e in entries]
    s.runs = [os.path.dirname(e["path"]) for e in best]
    s.extra.append(("stability_table", "Largest stable Δt found by `ricochet stability` "
                    "(docs/stability.md)", RS.STABILITY_HEADER, RS.stability_rows(entries)))
    summ = RS.stability_summary(best)
    s.caption = (
        "Largest stable Δt (filled circle) and smallest unstable Δt (cross) per mesh and "
        "scheme, found by bisection over whole runs, against the estimate Δt_crit = min "
        "L_e/c_p (black bar; for the penalty scheme combined with the spring limit). An arrow: "
        "no unstable Δt up to the search cap. " + marks_text + "The "
        "table below says why the smallest unstable Δt failed: for the explicit schemes a "
        "blow-up (inverted element or energy growth), for the implicit scheme a Newton or "
        "contact iteration that no longer converges. " + summ +
        ". Sources: " + runs_text(show_path(e["path"]) for e in best) + ".")
    return s


def sec_penetration(ctx):
    s = Section("penetration", "Penetration over time per scheme (beyond the paper)", "figure")
    sw = ctx["main"]
    runs = []
    for scheme in ("semi_explicit", "implicit"):
        r = finest(ok_runs(sw, "table1", mesh="M2", scheme=scheme)) or \
            finest(ok_runs(sw, "table1", scheme=scheme))
        if r is not None:
            runs.append((r, dict(color=F.color(scheme), lw=1.5)))
    for r in ok_runs(sw, "penalty"):
        runs.append((r, dict(color=F.color(r.scheme), lw=1.5)))
    if not runs:
        s.available = False
        s.missing = f"no ok run in groups `table1` or `penalty` of {sw.dir}. Run `{PAPER_CMD}`."
        return s
    s.files = F.fig_penetration(ctx["out"], "penetration", runs)
    s.runs = [r.id for r, _ in runs]
    s.sources = [sw.dir]
    parts = [f"{scheme_name(r.scheme)} {fmt_g(float(np.max(r.history()['penetration_max'])))} m"
             for r, _ in runs]
    s.caption = ("Largest depth of any contact node behind the ground at each sample "
                 "(`penetration_max` of history.csv), μ = 0, log scale, one run per scheme. "
                 "Largest over the run: " + ", ".join(parts) + ". The bi-potential schemes "
                 "enforce the gap at the end of each step (round-off level); penalty contact "
                 "lets nodes in by f/k (the paper: impenetrability \"parfaitement satisfaite\", "
                 "\"ce qui n'est pas le cas avec LS-DYNA\"). Runs: " + runs_text(s.runs) + ".")
    rows = []
    for r in sw.runs:
        if not r.ok:
            continue
        rows.append([f"`{r.id}`", scheme_name(r.scheme), r.mesh, fmt_dt(r.dt),
                     f"{fmt_g(r.friction)}", f"{fmt_g(r.num('penetration_max'))} m"])
    s.extra.append(("penetration_table", "Largest penetration over each ok run of the paper "
                    "sweep (`penetration_max` of summary.json)",
                    ["run", "scheme", "mesh", "Δt (s)", "μ", "penetration_max"], rows))
    return s


# ---------------------------------------------------------------------------------------------
# The plug-in's entries

def _legacy(ctx, section, **kw):
    d = {"out": ctx.out, "ref": read_reference(), "paper": True,
         "main": ctx.sweep(section["sweep"])}
    d.update(kw)
    return d


def table1(ctx, section):
    return [sec_table1(_legacy(ctx, section))]


def fig1(ctx, section):
    return [sec_fig1(_legacy(ctx, section))]


def fig2(ctx, section):
    return [sec_fig2(_legacy(ctx, section))]


def fig3(ctx, section):
    return [sec_fig3(_legacy(ctx, section))]


def fig4(ctx, section):
    return [sec_fig4(_legacy(ctx, section))]


def fig5(ctx, section):
    return [sec_probe(_legacy(ctx, section), "fig5", "table1", 0.0, "Fig. 5")]


def fig6(ctx, section):
    return [sec_probe(_legacy(ctx, section), "fig6", "friction", 0.1, "Fig. 6")]


def fig7(ctx, section):
    return [sec_fig7(_legacy(ctx, section))]


def penetration(ctx, section):
    return [sec_penetration(_legacy(ctx, section))]


def stability_map(ctx, section):
    """The largest stable Δt of the `stability` sweep's searches beside the Table 1 runs of the
    sweep named by args.runs (default "table1")."""
    stab = ctx.sweep(section["sweep"])
    runs = ctx.sweep(section.get("args", {}).get("runs", "table1"))
    return [sec_stability(_legacy(ctx, section, main=runs or stab,
                                  stab_files=find_stability_files([stab.dir])))]


def scheme_limits(ctx, section):
    """How far apart the schemes are at their smallest Δt, per mesh (report_generic.py)."""
    return [RG.scheme_limits_section({"out": ctx.out}, ctx.sweep(section["sweep"]), Section,
                                     sid="scheme_limits")]
