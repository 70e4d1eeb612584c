#!/usr/bin/python3
"""The report of a sweep: for any sweep its runs (with the gate results), work-precision
diagrams per error metric, each run's history and the runs that failed; for the paper's sweep
(cases/paper/table1.toml) also Table 1 and Figs. 1-7 of Cros, Feng & Magnain (2010), ours beside
the paper's numbers, with the accuracy sweep, the stability map, the stability envelope and the
long runs (report_stability.py), penetration over time, the verification cases, the
Kim–Kwak-type problem and the 3D cases (report_three_d.py).

    /usr/bin/python3 reports/make_report.py DIR [--accuracy ACC_DIR] [--stability PATH ...]
                                                [--verification VER_DIR] [--kim-kwak KK_DIR]
                                                [--kim-kwak-fields FIELDS_DIR]
                                                [--envelope ENV_DIR] [--long-runs LONG_DIR]
                                                [--three-d TD_DIR] [--three-d-refinement TDR_DIR]
                                                [--three-d-fields FIELDS_DIR]
                                                [--three-d-table1 TDT1_DIR]
                                                [--three-d-stability TDS_DIR]
                                                [--ball-block BB_DIR]
                                                [--ball-block-fields FIELDS_DIR]
                                                [--out OUT] [--max-run-plots N] [--no-discover]

DIR        a finished sweep (summary.csv, sweep.json, runs/). It is the paper's sweep when it is
           named paper_table1 or has the groups table1, penalty and friction.
--accuracy a finished sweep of cases/accuracy/accuracy.toml (the paper report's work-precision diagrams).
--stability stability.json files, or folders searched for them (stability map).
--verification a finished sweep of cases/verification/sweep.toml (the verification cases, each
           against its analytic reference: report_verification.py). Without it, DIR itself
           when its runs are verification cases.
--kim-kwak a finished sweep of cases/kim_kwak/sweep.toml (the Kim–Kwak-type problem's runs
           and its gates: report_kim_kwak.py). Without it, DIR itself when its runs are that case.
--kim-kwak-fields a run of cases/kim_kwak/rubber_groove.toml with its fields/*.vtu (the
           deformed shapes of the Kim–Kwak-type problem).
--envelope a finished sweep of cases/envelope/sweep_full.toml (the stability envelope: largest
           stable step / estimate per parameter and scheme, the points where the automatic step
           is not stable, the remedy runs: report_stability.py). Without it, DIR itself when it
           is such a sweep (stability searches with `stable_over_estimate`).
--three-d, --three-d-refinement, --three-d-fields  the 3D sweep cases/three_d/sweep.toml, its
           refinement sweep cases/three_d/refinement.toml and a run of
           cases/three_d/oblique_block.toml with fields (the 3D part: report_three_d.py). Without
           --three-d, DIR itself when its runs are the 3D cases.
--three-d-table1, --three-d-stability  the sweep of cases/three_d_table1/sweep_full.toml (or
           table1_fast.toml: Table 1 in 3D) and a folder of `ricochet stability` results of the
           3D meshes (subfolders with stability.json). Without --three-d-table1, DIR itself when
           it is that sweep.
--ball-block, --ball-block-fields  the sweep of cases/ball_block/sweep_full.toml (or
           ball_block_fast.toml) and a run of cases/ball_block/ball_block.toml with fields (the
           Mooney–Rivlin ball on a free block, in the 3D part: report_ball_block.py). Without
           --ball-block, DIR itself when its runs are that case.
--long-runs a finished sweep of cases/long_runs/sweep.toml with the drift.csv of
           cases/long_runs/drift.py (energy residual per scene and scheme, the drift table). Without
           it, DIR itself when it holds a drift.csv.
--out      report folder (default DIR/report).
--max-run-plots N  draw the histories of at most N runs (default 30).
For the paper's sweep, without --accuracy / --stability / --verification / --kim-kwak /
--kim-kwak-fields / --envelope / --long-runs, the script looks for DIR/../accuracy,
DIR/accuracy, DIR/../stability, DIR/stability, DIR/../verification, DIR/verification,
DIR/../kim_kwak, DIR/kim_kwak, DIR/../rubber_groove, DIR/rubber_groove, DIR/../envelope,
DIR/envelope, DIR/../long_runs, DIR/long_runs, DIR/../three_d, DIR/three_d,
DIR/../three_d_refinement, DIR/three_d_refinement, DIR/../oblique_block, DIR/oblique_block,
DIR/../three_d_table1, DIR/three_d_table1, DIR/../three_d_stability, DIR/three_d_stability,
DIR/../ball_block, DIR/ball_block, DIR/../ball_block_fields and DIR/ball_block_fields
(unless --no-discover); a source that is missing
gives a "not available" section saying how to produce it, never a crash. For any other sweep
only DIR/stability is looked for, and for a 3D sweep (cases/three_d/sweep.toml, table1.toml or
ball_block_sweep.toml) the other 3D sources as above; parts without data are left out.

Writes OUT/index.html (self-contained apart from its relative figure links), OUT/report.md,
OUT/manifest.json (figures, tables and their row labels) and the figures (PNG; SVG for the
line plots). Exit status: 0 written (even with sections not available), 2 bad input
(DIR is not a sweep folder, a bad option: one line on stderr). docs/report.md describes every
figure and its sources.
"""

import argparse
import datetime
import html
import json
import os
import re
import sys
import traceback

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import numpy as np  # noqa: E402

import report_figures as F  # noqa: E402
import report_generic as RG  # noqa: E402
import report_kim_kwak as RK  # noqa: E402
import report_stability as RS  # noqa: E402
import report_ball_block as RB  # noqa: E402
import report_three_d as R3  # noqa: E402
import report_verification as RV  # noqa: E402
from report_io import (REPO, REFERENCE_TOML, Sweep, field_files, find_stability_files,  # noqa: E402
                       fmt_dt, fmt_g, git_commit, read_reference, same, scheme_name,
                       show_path)

FIG1_TIMES = [5e-4, 1e-3, 2e-3, 3e-3]
FIG2_TIME = 6e-4
PAPER_CMD = "build/ricochet sweep cases/paper/table1.toml --out results/paper"
ACC_CMD = "build/ricochet sweep cases/accuracy/accuracy.toml --out results/accuracy"
STAB_CMD = ("build/ricochet stability cases/oblique_plate.toml --set mesh=M1 "
            "--set scheme=semi_explicit --out results/stability/semi_explicit_M1")
STAB_MORE = ("(and likewise for mesh M2 and the schemes `implicit`, with `--energy-bound 1`, and "
             "`explicit_penalty`)")


# ---------------------------------------------------------------------------------------------
# Report model: sections rendered to both Markdown and HTML

class Section:
    def __init__(self, sid, title, kind):
        self.id = sid
        self.title = title
        self.kind = kind          # "figure" or "table"
        self.number = None        # "Figure 3", "Table 1"
        self.paper = None         # which figure/table of the paper it reproduces
        self.caption = ""         # inline markdown
        self.files = []           # figure files, relative to the report folder
        self.header = []          # table header (inline markdown)
        self.rows = []            # table rows: lists of inline-markdown cells
        self.runs = []            # run ids it came from
        self.sources = []         # sweep folders / files it came from
        self.available = True
        self.missing = ""         # why not available and how to produce it
        self.error = None         # the exception text if building failed
        self.label = ""           # "Figure 3"
        self.extra = []           # further tables inside a figure section: (title, header, rows)
        self.part = None          # a group of sections under one heading (the verification cases)
        self.part_intro = ""      # inline markdown under the part's heading
        self.case = None          # verification case name

    def row_labels(self):
        return [re.sub(r"[*`]", "", r[0]) for r in self.rows]


def md_inline_to_html(text):
    s = html.escape(text, quote=False)
    s = re.sub(r"`([^`]+)`", r"<code>\1</code>", s)
    s = re.sub(r"\*\*([^*]+)\*\*", r"<b>\1</b>", s)
    s = re.sub(r"(?<![\w*])\*([^*\s][^*]*)\*(?![\w*])", r"<i>\1</i>", s)
    s = re.sub(r"\[([^\]]+)\]\(([^)]+)\)", r'<a href="\2">\1</a>', s)
    return s.replace("\n", "<br>")


def md_cell(text):
    return str(text).replace("|", "\\|").replace("\n", " ")


def md_table(header, rows):
    out = ["| " + " | ".join(md_cell(h) for h in header) + " |",
           "|" + "|".join("---" for _ in header) + "|"]
    for r in rows:
        out.append("| " + " | ".join(md_cell(c) for c in r) + " |")
    return "\n".join(out)


def html_table(tid, header, rows):
    out = [f'<table id="{html.escape(tid)}">', "<thead><tr>"]
    out += [f"<th>{md_inline_to_html(h)}</th>" for h in header]
    out.append("</tr></thead><tbody>")
    for r in rows:
        cells = []
        for c in r:
            bad = re.match(r"\**(diverged|failed|missing)\b", str(c))
            cls = ' class="diverged"' if bad else ""
            if not bad and (len(str(c)) <= 12 or re.fullmatch(r"`[^`\s]{1,30}`", str(c))) \
                    and " " not in str(c).strip():
                cls = ' class="nw"'   # a short number, word or run id: never broken
            cells.append(f"<td{cls}>{md_inline_to_html(str(c))}</td>")
        out.append("<tr>" + "".join(cells) + "</tr>")
    out.append("</tbody></table>")
    return "\n".join(out)


def runs_text(ids, limit=None):
    ids = list(ids)
    if not ids:
        return "none"
    return ", ".join(f"`{i}`" for i in ids)


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
# Sections

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
    from report_io import read_vtu
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


def sec_work_precision(ctx):
    """The paper report's work-precision diagrams: one per error metric of the accuracy sweep
    (report_generic.wp_sections), or one "not available" section."""
    acc = ctx.get("acc")
    s = Section("work_precision", "Work-precision diagram (beyond the paper)", "figure")
    if acc is None:
        s.available = False
        s.missing = ("no accuracy sweep. Run `" + ACC_CMD + "` and pass `--accuracy "
                     "results/accuracy` (or place it next to the paper sweep as `accuracy/`).")
        return s
    out = RG.wp_sections(ctx, acc, Section, prefix="wp",
                         title_of=" (accuracy sweep; beyond the paper)")
    if not out:
        s.available = False
        s.missing = (f"the accuracy sweep {acc.dir} has no run with an error column "
                     f"(`error_*`). Run `{ACC_CMD}`.")
        return s
    return out


def sec_scheme_limits(ctx):
    """The paper report's scheme-limits table of the accuracy sweep (its work-precision part):
    nothing without an accuracy sweep (the work-precision section says it is missing)."""
    acc = ctx.get("acc")
    if acc is None:
        return []
    s = RG.scheme_limits_section(ctx, acc, Section, sid="scheme_limits",
                                 title_of=" (accuracy sweep; beyond the paper)")
    if not s.available:
        s.missing += f" Run `{ACC_CMD}`."
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


def _sweeps(ctx):
    """The main sweep and the other sweeps read, each once."""
    out, seen = [], set()
    for sw in [ctx["main"]] + [ctx[k] for k in ("acc", "ver", "kk") if ctx.get(k)]:
        if sw.dir not in seen:
            seen.add(sw.dir)
            out.append(sw)
    return out


def sec_failed(ctx):
    paper = ctx.get("paper", True)
    s = Section("failed", "Runs that failed or diverged" + (" (beyond the paper)" if paper
                                                             else ""), "table")
    s.header = ["run", "sweep", "status", "Δt (s)", "Δt / estimate", "at t (s)", "reason"]
    for sw in _sweeps(ctx):
        for r in sw.runs:
            if r.ok:
                continue
            crit = r.num("critical_dt")
            s.rows.append([f"`{r.id}`", sw.name, f"**{r.status or 'missing'}**",
                           fmt_dt(r.dt), f"{r.dt / crit:.2f}" if r.dt and crit else "–",
                           fmt_g(r.num("diverged.time")), r.reason or "–"])
            s.runs.append(r.id)
        s.sources.append(sw.dir)
    s.caption = ("Every run of the sweeps above whose status is not `ok` (summary.csv "
                 "`status`, `reason`; `diverged` = stopped by the divergence detector, "
                 "`failed` = no usable summary.json). Δt / estimate uses the run's "
                 "`critical_dt` (min L_e/c_p). " +
                 ("None." if not s.rows else f"{len(s.rows)} run(s)."))
    if not paper and not s.rows:
        return []   # any other sweep: a table of nothing is left out
    return s


def sec_runs(ctx):
    return RG.runs_section(ctx, ctx["main"], Section)


def sec_histories(ctx):
    return RG.histories_section(ctx, ctx["main"], Section)


def sec_sweep_wp(ctx):
    """Any sweep's own work-precision diagrams (one per error_* column), then those of an
    accuracy sweep given with --accuracy."""
    out = RG.wp_sections(ctx, ctx["main"], Section, prefix="wp")
    if ctx.get("acc") is not None and ctx["acc"].dir != ctx["main"].dir:
        out += RG.wp_sections(ctx, ctx["acc"], Section, prefix="acc_wp",
                              title_of=f" (sweep {ctx['acc'].name})")
    return out


def sec_sweep_scheme_limits(ctx):
    """Any sweep's scheme-limits table, then that of an accuracy sweep given with --accuracy."""
    out = [RG.scheme_limits_section(ctx, ctx["main"], Section, sid="scheme_limits")]
    if ctx.get("acc") is not None and ctx["acc"].dir != ctx["main"].dir:
        out.append(RG.scheme_limits_section(ctx, ctx["acc"], Section, sid="acc_scheme_limits",
                                            title_of=f" (sweep {ctx['acc'].name})"))
    return out


# The paper's sweep: the paper's Table 1 and Figs. 1-7 first, then what goes beyond the paper.
PAPER_SECTIONS = [
    ("table1", sec_table1),
    ("fig1", sec_fig1),
    ("fig2", sec_fig2),
    ("fig3", sec_fig3),
    ("fig4", sec_fig4),
    ("fig5", lambda c: sec_probe(c, "fig5", "table1", 0.0, "Fig. 5")),
    ("fig6", lambda c: sec_probe(c, "fig6", "friction", 0.1, "Fig. 6")),
    ("fig7", sec_fig7),
    ("work_precision", sec_work_precision),
    ("scheme_limits", sec_scheme_limits),
    ("stability", sec_stability),
    ("envelope", lambda c: RS.envelope_sections(c, Section)),   # figure, unsafe-points table
    ("long_runs", lambda c: RS.long_run_sections(c, Section)),  # residual figure, drift table
    ("penetration", sec_penetration),
    ("verification", lambda c: RV.sections(c, Section)),   # one section per verification case
    ("kim_kwak", lambda c: RK.sections(c, Section)),       # shapes, histories, runs table
    ("three_d", lambda c: R3.sections(c, Section)),        # 3D shapes, bar, oblique block, frame
    ("failed", sec_failed),
    ("runs", sec_runs),
    ("histories", sec_histories),
]

# Any other sweep: what every sweep has; the parts whose data are missing are left out.
SWEEP_SECTIONS = [
    ("runs", sec_runs),
    ("failed", sec_failed),
    ("work_precision", sec_sweep_wp),
    ("scheme_limits", sec_sweep_scheme_limits),
    ("stability", sec_stability),
    ("envelope", lambda c: RS.envelope_sections(c, Section) if c.get("env") else []),
    ("long_runs", lambda c: RS.long_run_sections(c, Section) if c.get("long") else []),
    ("verification", lambda c: RV.sections(c, Section) if c.get("ver") else []),
    ("kim_kwak", lambda c: RK.sections(c, Section) if c.get("kk") or c.get("kk_fields")
     else []),
    ("three_d", lambda c: R3.sections(c, Section) if c.get("td") or c.get("td_fields")
     or c.get("td_t1") or c.get("td_stab") or c.get("bb") or c.get("bb_fields") else []),
    ("histories", sec_histories),
]

PAPER_GROUPS = {"table1", "penalty", "friction"}


def is_paper_sweep(sweep):
    """The paper's sweep (cases/paper/table1.toml): its name, or its three groups."""
    return sweep.name == "paper_table1" or PAPER_GROUPS <= {r.group for r in sweep.runs}


# ---------------------------------------------------------------------------------------------
# Rendering

CSS = """
body{font-family:system-ui,-apple-system,'Segoe UI',Helvetica,Arial,sans-serif;max-width:1150px;
margin:1.5em auto;padding:0 1em;color:#222;line-height:1.45}
h1{font-size:1.6em;margin-bottom:.2em} h2{margin-top:1.8em;border-bottom:1px solid #ccc}
h3{font-size:1.05em} h3.sec{font-size:1.2em;margin-top:1.6em}
.part-intro{font-size:.92em}
table{border-collapse:collapse;margin:.6em 0;font-size:.88em}
th,td{border:1px solid #bbb;padding:.25em .5em;vertical-align:top}
th{background:#f0f0f0} td.diverged{background:#fdecea} td.nw{white-space:nowrap}
td.nw code{word-break:normal}
figure{margin:1em 0} figure img{max-width:100%;border:1px solid #ddd}
figcaption,.caption{font-size:.9em;color:#333;margin-top:.4em}
code{font-size:.85em;background:#f4f4f4;padding:0 .2em;word-break:break-all}
.na{border:2px dashed #c33;background:#fff6f6;padding:.6em 1em}
.meta td{border:none;padding:.1em .8em .1em 0}
"""


def render(ctx, sections):
    out = ctx["out"]
    meta = ctx["meta"]
    # ---- markdown
    md = [f"# {ctx['title']}", ""]
    for k, v in meta:
        md.append(f"- **{k}:** {v}")
    md.append("")
    part = None
    for s in sections:
        if s.part != part:
            part = s.part
            if part:
                md += [f"## {part}", "", s.part_intro, ""]
        md.append(f"{'###' if s.part else '##'} {s.number}: {s.title}")
        md.append("")
        if s.error:
            md.append(f"**Error while building this section:** `{s.error}`")
            md.append("")
            continue
        if not s.available:
            md.append(f"**Not available:** {s.missing}")
            md.append("")
            continue
        if s.kind == "table":
            md.append(md_table(s.header, s.rows) if s.rows else "(no rows)")
            md.append("")
            md.append(f"*{s.label}.* {s.caption}")
        else:
            png = [f for f in s.files if f.endswith(".png")]
            for f in png:
                md.append(f"![{s.title}]({f})")
            md.append("")
            others = [f for f in s.files if not f.endswith(".png")]
            md.append(f"*{s.label}.* {s.caption}" +
                      (" Also: " + ", ".join(f"[{f}]({f})" for f in others) + "." if others
                       else ""))
        md.append("")
        for tid, title, hdr, rows in s.extra:
            md.append(f"**{title}**")
            md.append("")
            md.append(md_table(hdr, rows) if rows else "(no rows)")
            md.append("")
    with open(os.path.join(out, "report.md"), "w") as f:
        f.write("\n".join(md) + "\n")

    # ---- html
    h = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
         f"<title>ricochet: {html.escape(ctx['title'])}</title>",
         f"<style>{CSS}</style></head><body>",
         f"<h1>{html.escape(ctx['title'])}</h1>",
         '<table class="meta">']
    for k, v in meta:
        h.append(f"<tr><td><b>{html.escape(k)}</b></td><td>{md_inline_to_html(v)}</td></tr>")
    h.append("</table>")
    h.append("<h2>Contents</h2><ol>")
    part = None
    for s in sections:
        if s.part != part:
            if part:
                h.append("</ul></li>")
            part = s.part
            if part:
                h.append(f'<li><a href="#part-{part_id(part)}">{html.escape(part)}</a><ul>')
        flag = "" if s.available and not s.error else " — <b>not available</b>"
        h.append(f'<li><a href="#{s.id}">{html.escape(s.number)}: {html.escape(s.title)}</a>'
                 f"{flag}</li>")
    if part:
        h.append("</ul></li>")
    h.append("</ol>")
    part = None
    for s in sections:
        if s.part != part:
            part = s.part
            if part:
                h.append(f'<h2 id="part-{part_id(part)}">{html.escape(part)}</h2>')
                h.append(f'<p class="part-intro">{md_inline_to_html(s.part_intro)}</p>')
        hx = '<h3 class="sec"' if s.part else "<h2"
        h.append(f'<section id="sec-{s.id}">{hx} id="{s.id}">{html.escape(s.number)}: '
                 f"{html.escape(s.title)}</{hx[1:3]}>")
        if s.error:
            h.append(f'<div class="na not-available"><b>Error while building this section:</b> '
                     f"<code>{html.escape(s.error)}</code></div></section>")
            continue
        if not s.available:
            h.append(f'<div class="na not-available"><b>Not available:</b> '
                     f"{md_inline_to_html(s.missing)}</div></section>")
            continue
        if s.kind == "table":
            h.append(html_table("tab-" + s.id, s.header, s.rows))
            h.append(f'<p class="caption"><b>{html.escape(s.label)}.</b> '
                     f"{md_inline_to_html(s.caption)}</p>")
        else:
            h.append("<figure>")
            for f in s.files:
                if f.endswith(".png"):
                    h.append(f'<a href="{html.escape(f)}"><img src="{html.escape(f)}" '
                             f'alt="{html.escape(s.title)}"></a>')
            others = [f for f in s.files if not f.endswith(".png")]
            also = (" Also: " + ", ".join(f'<a href="{html.escape(f)}">{html.escape(f)}</a>'
                                          for f in others) + ".") if others else ""
            h.append(f"<figcaption><b>{html.escape(s.label)}.</b> "
                     f"{md_inline_to_html(s.caption)}{also}</figcaption></figure>")
        for tid, title, hdr, rows in s.extra:
            h.append(f"<h3>{md_inline_to_html(title)}</h3>")
            h.append(html_table("tab-" + tid, hdr, rows))
        h.append("</section>")
    h.append("</body></html>")
    with open(os.path.join(out, "index.html"), "w") as f:
        f.write("\n".join(h) + "\n")

    # ---- manifest (for tests and tools)
    man = {"generated_at": ctx["now"], "sweep": ctx["main"].dir,
           "paper_sweep": ctx["paper"], "title": ctx["title"],
           "accuracy": ctx["acc"].dir if ctx.get("acc") else None,
           "verification": ctx["ver"].dir if ctx.get("ver") else None,
           "kim_kwak": ctx["kk"].dir if ctx.get("kk") else None,
           "kim_kwak_fields": ctx.get("kk_fields"),
           "envelope": ctx["env"][0].dir if ctx.get("env") else None,
           "long_runs": ctx["long"].dir if ctx.get("long") else None,
           "three_d": ctx["td"].dir if ctx.get("td") else None,
           "three_d_refinement": ctx["td_ref"].dir if ctx.get("td_ref") else None,
           "three_d_fields": ctx.get("td_fields"),
           "three_d_table1": ctx["td_t1"].dir if ctx.get("td_t1") else None,
           "three_d_stability": ctx.get("td_stab") or [],
           "ball_block": ctx["bb"].dir if ctx.get("bb") else None,
           "ball_block_fields": ctx.get("bb_fields"),
           "stability": ctx.get("stab_files") or [], "sections": []}
    for s in sections:
        man["sections"].append({
            "id": s.id, "number": s.number, "title": s.title, "kind": s.kind,
            "paper": s.paper, "part": s.part, "case": s.case, "available": s.available and not s.error, "error": s.error,
            "missing": s.missing or None, "files": s.files, "runs": s.runs,
            "sources": s.sources,
            "tables": ([{"id": s.id, "rows": s.row_labels()}] if s.kind == "table" and
                       s.available and not s.error else []) +
                      [{"id": tid, "rows": [re.sub(r"[*`]", "", r[0]) for r in rows]}
                       for tid, _, _, rows in s.extra]})
    with open(os.path.join(out, "manifest.json"), "w") as f:
        json.dump(man, f, indent=1)
        f.write("\n")


def part_id(title):
    return re.sub(r"[^a-z0-9]+", "-", title.lower()).strip("-")


def discover(main_dir, args):
    """The accuracy, stability, verification and Kim–Kwak-type folders: as given, else found
    beside or inside the paper sweep's folder (unless --no-discover)."""
    parent = os.path.dirname(os.path.abspath(main_dir))
    places = lambda name: (os.path.join(parent, name), os.path.join(main_dir, name))

    def sweep_folder(given, name):
        if given is not None or args.no_discover:
            return given
        return next((c for c in places(name) if os.path.exists(os.path.join(c, "summary.csv"))), None)

    stab = list(args.stability or [])
    if not stab and not args.no_discover:
        stab = [c for c in places("stability") if os.path.isdir(c)]
    fields = args.kim_kwak_fields
    if fields is None and not args.no_discover:
        fields = next((c for c in places("rubber_groove") if RK.find_fields(c)), None)
    three_d = discover_three_d(main_dir, args)
    return (sweep_folder(args.accuracy, "accuracy"), stab,
            sweep_folder(args.verification, "verification"), sweep_folder(args.kim_kwak, "kim_kwak"),
            os.path.abspath(fields) if fields else None,
            sweep_folder(args.envelope, "envelope"), sweep_folder(args.long_runs, "long_runs"), three_d,
            discover_ball_block(main_dir, args))


def discover_three_d(main_dir, args, found=()):
    """The 3D sources (sweep, refinement sweep, fields run, Table 1 sweep, stability folders):
    as given, else found beside or inside main_dir (unless --no-discover). found: the
    (sweep, Table 1 sweep) already known, e.g. the main sweep itself."""
    parent = os.path.dirname(os.path.abspath(main_dir))
    places = lambda name: (os.path.join(parent, name), os.path.join(main_dir, name))  # noqa: E731
    td, t1 = found or (args.three_d, args.three_d_table1)

    def sweep_folder(given, name):
        if given is not None or args.no_discover:
            return given
        return next((c for c in places(name) if os.path.exists(os.path.join(c, "summary.csv"))), None)

    td_fields = args.three_d_fields
    if td_fields is None and not args.no_discover:
        td_fields = next((c for c in places("oblique_block") if RK.find_fields(c)), None)
    stab = args.three_d_stability
    if stab is None and not args.no_discover:
        stab = next((c for c in places("three_d_stability") if os.path.isdir(c)), None)
    return (sweep_folder(td, "three_d"), sweep_folder(args.three_d_refinement, "three_d_refinement"),
            os.path.abspath(td_fields) if td_fields else None, sweep_folder(t1, "three_d_table1"),
            os.path.abspath(stab) if stab else None)


def discover_ball_block(main_dir, args, found=None):
    """The sources of the ball on the block (its sweep, its run with fields): as given, else
    found beside or inside main_dir (unless --no-discover). found: the sweep already known,
    e.g. the main sweep itself."""
    parent = os.path.dirname(os.path.abspath(main_dir))
    places = lambda name: (os.path.join(parent, name), os.path.join(main_dir, name))  # noqa: E731
    bb = found if found is not None else getattr(args, "ball_block", None)
    fields = getattr(args, "ball_block_fields", None)
    if not args.no_discover:
        if bb is None:
            bb = next((c for c in places("ball_block")
                       if os.path.exists(os.path.join(c, "summary.csv"))), None)
        if fields is None:
            fields = next((c for c in places("ball_block_fields") if RK.find_fields(c)), None)
    return bb, os.path.abspath(fields) if fields else None


def is_three_d_table1(sweep, cases):
    """The sweep of cases/three_d_table1/sweep_full.toml (or table1_fast.toml): its name, or the groups
    table1 and penalty on the oblique block."""
    return (sweep.name.startswith("three_d_table1")
            or ({"table1", "penalty"} <= {r.group for r in sweep.runs} and cases == {"oblique_block"}))


def td_t1_meta(t1, err, stab_dir, stab_files):
    if t1 is None:
        line = "not available" + (f" ({err})" if err else "") + f": run `{R3.T1_CMD}`"
    else:
        line = (f"`{t1.dir}` (sweep `{t1.name}`, {len(t1.runs)} runs; jobs "
                f"{t1.meta.get('jobs', '?')}, repeat {t1.meta.get('repeat', '?')})")
    if stab_files:
        line += "; stability " + ", ".join(f"`{show_path(p)}`" for p in stab_files)
    else:
        line += ("; stability not available" + (f" (no stability.json in `{show_path(stab_dir)}`)"
                                                if stab_dir else "")
                 + f": run `{R3.STAB_CMD}` {R3.STAB_MORE}")
    return line


def td_meta(td, err, ref, ref_err):
    if td is None:
        return ("not available" + (f" ({err})" if err else "") + f": run `{R3.SWEEP_CMD}`")
    gates = RK.gates_result(td.dir)[0]
    return (f"`{td.dir}` ({len(td.runs)} runs; " + (f"gates {gates}" if gates else "no gates-junit.xml")
            + "); refinement " + (f"`{ref.dir}` ({len(ref.runs)} runs)" if ref is not None else
                                  "not available" + (f" ({ref_err})" if ref_err else "")
                                  + f": run `{R3.REF_CMD}`"))


def bb_meta(bb, err, fields):
    if bb is None:
        line = "not available" + (f" ({err})" if err else "") + f": run `{RB.BB_CMD}`"
    else:
        gates = RK.gates_result(bb.dir)[0]
        line = (f"`{bb.dir}` (sweep `{bb.name}`, {len(bb.runs)} runs; "
                + (f"gates {gates}" if gates else "no gates-junit.xml") + ")")
    fdir = RK.find_fields(fields)
    if fdir is not None:
        line += f"; fields run `{show_path(fields)}` ({len(field_files(fdir))} field files)"
    else:
        line += ("; fields run not available" + (f" (no fields/*.vtu in `{fields}`)" if fields
                                                 else "") + f": run `{RB.FIELDS_CMD}`")
    return line


def kk_meta(kk, err):
    if kk is None:
        return ("not available" + (f" ({err})" if err else "") + f": run `{RK.KK_CMD}`")
    gates = RK.gates_result(kk.dir)[0]
    return (f"`{kk.dir}` ({len(kk.runs)} runs; "
            + (f"gates {gates}" if gates else "no gates-junit.xml") + ")")


def kk_fields_meta(folder):
    fdir = RK.find_fields(folder)
    if fdir is None:
        return ("not available" + (f" (no fields/*.vtu in `{folder}`)" if folder else "")
                + f": run `{RK.FIELDS_CMD}`")
    return f"`{show_path(folder)}` ({len(field_files(fdir))} field files)"


def env_meta(env, err):
    if env is None:
        return ("not available" + (f" ({err})" if err else "") + f": run `{RS.ENV_CMD}`")
    sw, points = env
    n = sum(p.kind == "stability" for p in points)
    return (f"`{sw.dir}` ({n} stability searches, {len(points) - n} runs; finished "
            f"{sw.meta.get('finished_at', '?')})")


def long_meta(sw, err):
    if sw is None:
        return ("not available" + (f" ({err})" if err else "") + f": run `{RS.LONG_CMD}`")
    drift = os.path.isfile(os.path.join(sw.dir, "drift.csv"))
    return (f"`{sw.dir}` ({len(sw.runs)} runs; "
            + ("with drift.csv" if drift else f"no drift.csv: run `{RS.LONG_DRIFT_CMD}`") + ")")


class OneLineParser(argparse.ArgumentParser):
    """Bad options: one line on stderr, exit 2 (no usage block)."""

    def error(self, message):
        self.exit(2, f"{self.prog}: {message} (--help for the options)\n")


def read_sweep(folder, what):
    """(Sweep, None) or (None, error text)."""
    try:
        return Sweep(folder), None
    except (OSError, ValueError) as e:
        return None, str(e)


def generic_sources(main_sweep, args):
    """For a sweep that is not the paper's: the sources given, else the sweep itself for the
    verification / Kim–Kwak-type parts when its runs are those cases, and DIR/stability."""
    cases = {r.get("case") for r in main_sweep.runs if r.kind == "run"}
    ver_cases = {n for c in RV.CASES for n in (c.case,) + tuple(c.aliases)}
    ver = args.verification
    if ver is None and cases & ver_cases:
        ver = main_sweep.dir
    kk = args.kim_kwak
    if kk is None and RK.CASE in cases:
        kk = main_sweep.dir
    stab = list(args.stability or [])
    if not stab and not args.no_discover and os.path.isdir(os.path.join(main_sweep.dir,
                                                                         "stability")):
        stab = [os.path.join(main_sweep.dir, "stability")]
    fields = os.path.abspath(args.kim_kwak_fields) if args.kim_kwak_fields else None
    env = args.envelope
    if env is None and "stable_over_estimate" in main_sweep.columns and any(
            r.kind == "stability" for r in main_sweep.runs):
        env = main_sweep.dir
    long_dir = args.long_runs
    if long_dir is None and os.path.isfile(os.path.join(main_sweep.dir, "drift.csv")):
        long_dir = main_sweep.dir
    td = args.three_d
    if td is None and "bar_wall3" in cases and "oblique_block" in cases:
        td = main_sweep.dir
    t1 = args.three_d_table1
    if t1 is None and is_three_d_table1(main_sweep, cases):
        t1 = main_sweep.dir
    bb = getattr(args, "ball_block", None)
    if bb is None and RB.CASE in cases:
        bb = main_sweep.dir
    if main_sweep.dir in (td, t1, bb):
        # a 3D sweep: the other 3D sources beside it, as for the paper's sweep
        three_d = discover_three_d(main_sweep.dir, args, (td, t1))
        ball_block = discover_ball_block(main_sweep.dir, args, bb)
    else:
        three_d = (td, args.three_d_refinement,
                   os.path.abspath(args.three_d_fields) if args.three_d_fields else None, t1,
                   os.path.abspath(args.three_d_stability) if args.three_d_stability else None)
        bb_fields = getattr(args, "ball_block_fields", None)
        ball_block = (bb, os.path.abspath(bb_fields) if bb_fields else None)
    return args.accuracy, stab, ver, kk, fields, env, long_dir, three_d, ball_block


def main(argv=None):
    ap = OneLineParser(prog="make_report.py", description=__doc__.split("\n\n")[0])
    ap.add_argument("dir", help="a finished sweep folder (summary.csv, sweep.json, runs/)")
    ap.add_argument("--accuracy", help="accuracy sweep folder (cases/accuracy/accuracy.toml)")
    ap.add_argument("--stability", nargs="*", default=None,
                    help="stability.json files or folders holding them")
    ap.add_argument("--verification", metavar="VER_DIR",
                    help="verification sweep folder (cases/verification/sweep.toml)")
    ap.add_argument("--kim-kwak", metavar="KK_DIR",
                    help="Kim–Kwak-type sweep folder (cases/kim_kwak/sweep.toml)")
    ap.add_argument("--kim-kwak-fields", metavar="FIELDS_DIR",
                    help="run folder of cases/kim_kwak/rubber_groove.toml with fields/*.vtu")
    ap.add_argument("--envelope", metavar="ENV_DIR",
                    help="stability-envelope sweep folder (cases/envelope/sweep_full.toml)")
    ap.add_argument("--long-runs", metavar="LONG_DIR",
                    help="long-run sweep folder (cases/long_runs/sweep.toml) with its drift.csv "
                         "(cases/long_runs/drift.py)")
    ap.add_argument("--three-d", metavar="TD_DIR",
                    help="3D sweep folder (cases/three_d/sweep.toml)")
    ap.add_argument("--three-d-refinement", metavar="TDR_DIR",
                    help="3D refinement sweep folder (cases/three_d/refinement.toml)")
    ap.add_argument("--three-d-fields", metavar="FIELDS_DIR",
                    help="run folder of cases/three_d/oblique_block.toml with fields/*.vtu")
    ap.add_argument("--three-d-table1", metavar="TDT1_DIR",
                    help="3D Table 1 sweep folder (cases/three_d_table1/sweep_full.toml or table1_fast.toml)")
    ap.add_argument("--three-d-stability", metavar="TDS_DIR",
                    help="folder of ricochet stability results of the 3D meshes (subfolders "
                         "with stability.json)")
    ap.add_argument("--ball-block", metavar="BB_DIR",
                    help="sweep folder of the ball on the block "
                         "(cases/ball_block/sweep_full.toml)")
    ap.add_argument("--ball-block-fields", metavar="FIELDS_DIR",
                    help="run folder of cases/ball_block/ball_block.toml with fields/*.vtu")
    ap.add_argument("--out", help="report folder (default DIR/report)")
    ap.add_argument("--max-run-plots", type=int, default=RG.MAX_RUN_PLOTS, metavar="N",
                    help=f"draw the histories of at most N runs (default {RG.MAX_RUN_PLOTS})")
    ap.add_argument("--no-discover", action="store_true",
                    help="do not look for accuracy/, stability/, verification/, kim_kwak/, "
                         "rubber_groove/, envelope/, long_runs/, three_d/, three_d_refinement/, "
                         "oblique_block/, three_d_table1/, three_d_stability/, ball_block/ and "
                         "ball_block_fields/ next to DIR")
    args = ap.parse_args(argv)
    if args.max_run_plots < 0:
        ap.error(f"--max-run-plots {args.max_run_plots}: must be 0 or more")
    if not os.path.isdir(args.dir):
        print(f"make_report: {args.dir}: no such folder (give a sweep's output folder)",
              file=sys.stderr)
        return 2
    main_sweep, err = read_sweep(args.dir, "sweep")
    if main_sweep is None:
        print(f"make_report: {err}", file=sys.stderr)
        return 2
    paper = is_paper_sweep(main_sweep)
    out = os.path.abspath(args.out or os.path.join(args.dir, "report"))
    try:
        os.makedirs(out, exist_ok=True)
    except OSError as e:
        print(f"make_report: cannot create the report folder {out}: {e.strerror}",
              file=sys.stderr)
        return 1
    if paper:
        acc_dir, stab_paths, ver_dir, kk_dir, kk_fields, env_dir, long_dir, three_d, ball_block = \
            discover(args.dir, args)
    else:
        acc_dir, stab_paths, ver_dir, kk_dir, kk_fields, env_dir, long_dir, three_d, ball_block = \
            generic_sources(main_sweep, args)
    td_dir, td_ref_dir, td_fields, td_t1_dir, td_stab_dir = three_d
    bb_dir, bb_fields = ball_block
    same_dir = lambda d: d is not None and os.path.abspath(d) == main_sweep.dir  # noqa: E731
    acc, acc_err = read_sweep(acc_dir, "accuracy") if acc_dir else (None, None)
    ver, ver_err = ((main_sweep, None) if same_dir(ver_dir) else
                    read_sweep(ver_dir, "verification") if ver_dir else (None, None))
    kk, kk_err = ((main_sweep, None) if same_dir(kk_dir) else
                  read_sweep(kk_dir, "kim_kwak") if kk_dir else (None, None))
    long_sw, long_err = ((main_sweep, None) if same_dir(long_dir) else
                         read_sweep(long_dir, "long_runs") if long_dir else (None, None))
    td, td_err = ((main_sweep, None) if same_dir(td_dir) else
                  read_sweep(td_dir, "three_d") if td_dir else (None, None))
    td_ref, td_ref_err = read_sweep(td_ref_dir, "three_d_refinement") if td_ref_dir else (None, None)
    td_t1, td_t1_err = ((main_sweep, None) if same_dir(td_t1_dir) else
                        read_sweep(td_t1_dir, "three_d_table1") if td_t1_dir else (None, None))
    td_stab = find_stability_files([td_stab_dir]) if td_stab_dir else []
    bb, bb_err = ((main_sweep, None) if same_dir(bb_dir) else
                  read_sweep(bb_dir, "ball_block") if bb_dir else (None, None))
    env, env_err = None, None     # env: (Sweep, [EnvPoint]) of the envelope sweep
    if env_dir:
        sw_env, got = RS.read_envelope(env_dir)
        if sw_env is None:
            env_err = got
        else:
            env = (sw_env, got)
    stab_files = find_stability_files(stab_paths)
    ref = read_reference()
    now = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    title = ("Cros, Feng & Magnain (2010): our reproduction" if paper else
             f"Sweep {main_sweep.name}: report")
    ctx = {"main": main_sweep, "acc": acc, "stab_files": stab_files, "ref": ref, "out": out,
           "now": now, "ver": ver, "ver_err": ver_err, "kk": kk, "kk_err": kk_err,
           "kk_fields": kk_fields, "paper": paper, "title": title,
           "max_run_plots": args.max_run_plots, "env": env, "env_err": env_err,
           "long": long_sw, "long_err": long_err, "td": td, "td_err": td_err, "td_ref": td_ref,
           "td_ref_err": td_ref_err, "td_fields": td_fields, "td_t1": td_t1,
           "td_t1_err": td_t1_err, "td_stab": td_stab, "bb": bb, "bb_err": bb_err,
           "bb_fields": bb_fields}

    commit, dirty = git_commit(REPO)
    program = main_sweep.meta.get("program", "unknown")
    builds = sorted({f"{r.get('build.compiler')} ({r.get('build.build_type')})"
                     for r in main_sweep.runs if r.get("build.compiler")})
    counts = main_sweep.meta.get("counts") or {}
    if not isinstance(counts, dict):
        counts = {}
    sweep_line = (f"`{main_sweep.dir}` (sweep `{main_sweep.name}`, file "
                  f"`{main_sweep.meta.get('sweep_file', '?')}`, {len(main_sweep.runs)} runs"
                  + (": " + ", ".join(f"{k} {v}" for k, v in counts.items() if k != "executed")
                     if counts else "")
                  + f"; finished {main_sweep.meta.get('finished_at', '?')}; "
                  f"jobs {main_sweep.meta.get('jobs', '?')}, repeat "
                  f"{main_sweep.meta.get('repeat', '?')})")
    desc = main_sweep.meta.get("description")
    common_tail = [
        ("Program", f"ricochet {main_sweep.version()}, `{program}`"
                    + (f", built with {'; '.join(builds)}" if builds else "")),
        ("Source tree", (f"commit `{commit}`" + (" with uncommitted changes" if dirty else "")
                         + f" (`{REPO}`, at report time)") if commit else "not a git work tree"),
    ]
    if paper:
        meta = [
            ("Paper sweep", sweep_line),
            ("Accuracy sweep", f"`{acc.dir}` ({len(acc.runs)} runs)" if acc else
             ("not available" + (f" ({acc_err})" if acc_err else "") + f": run `{ACC_CMD}`")),
            ("Verification sweep", f"`{ver.dir}` ({len(ver.runs)} runs; references "
                                   "`reference/verification.toml`)" if ver else
             ("not available" + (f" ({ver_err})" if ver_err else "") + f": run `{RV.VER_CMD}`")),
            ("Kim–Kwak-type sweep", kk_meta(kk, kk_err)),
            ("Kim–Kwak-type fields run", kk_fields_meta(kk_fields)),
            ("Stability results", (", ".join(f"`{show_path(p)}`" for p in stab_files)
                                   if stab_files else
                                   f"not available: run `{STAB_CMD}` {STAB_MORE}")),
            ("Stability-envelope sweep", env_meta(env, env_err)),
            ("Long-run sweep", long_meta(long_sw, long_err)),
            ("3D sweeps", td_meta(td, td_err, td_ref, td_ref_err)),
            ("3D fields run", f"`{show_path(td_fields)}`" if td_fields else
             f"not available: run `{R3.FIELDS_CMD}`"),
            ("3D Table 1", td_t1_meta(td_t1, td_t1_err, td_stab_dir, td_stab)),
            ("3D ball on a block", bb_meta(bb, bb_err, bb_fields)),
        ] + common_tail + [
            ("Paper's numbers", f"`{os.path.relpath(REFERENCE_TOML, REPO)}` (Cros, Feng & "
                                "Magnain, C. R. Mécanique 338 (2010) 176–180)"),
            ("Report written", now),
        ]
    else:
        meta = [("Sweep", sweep_line)]
        if desc:
            meta.append(("Description", desc))
        for label, sw, err in (("Accuracy sweep", acc, acc_err),
                               ("Verification sweep", ver, ver_err),
                               ("Kim–Kwak-type sweep", kk, kk_err)):
            if sw is not None and sw is not main_sweep:
                meta.append((label, f"`{sw.dir}` ({len(sw.runs)} runs)"))
            elif err:
                meta.append((label, f"could not be read ({err})"))
        if kk_fields:
            meta.append(("Kim–Kwak-type fields run", kk_fields_meta(kk_fields)))
        if stab_files:
            meta.append(("Stability results", ", ".join(f"`{show_path(p)}`" for p in stab_files)))
        if env is not None and env[0].dir != main_sweep.dir:
            meta.append(("Stability-envelope sweep", env_meta(env, env_err)))
        elif env_err:
            meta.append(("Stability-envelope sweep", f"could not be read ({env_err})"))
        if long_sw is not None and long_sw is not main_sweep:
            meta.append(("Long-run sweep", long_meta(long_sw, long_err)))
        elif long_err:
            meta.append(("Long-run sweep", f"could not be read ({long_err})"))
        if (td is not None and td is not main_sweep) or td_err or td_ref is not None:
            meta.append(("3D sweeps", td_meta(td, td_err, td_ref, td_ref_err)))
        if td_fields:
            meta.append(("3D fields run", f"`{show_path(td_fields)}`"))
        if (td_t1 is not None and td_t1 is not main_sweep) or td_t1_err or td_stab:
            meta.append(("3D Table 1", td_t1_meta(td_t1, td_t1_err, td_stab_dir, td_stab)))
        if (bb is not None and bb is not main_sweep) or bb_err or bb_fields:
            meta.append(("3D ball on a block", bb_meta(bb, bb_err, bb_fields)))
        meta += common_tail + [("Report written", now)]
    ctx["meta"] = meta

    sections = []
    nfig = ntab = 0
    built = []
    for sid, fn in (PAPER_SECTIONS if paper else SWEEP_SECTIONS):
        try:
            s = fn(ctx)
        except Exception as e:  # noqa: BLE001 - a broken section must not stop the report
            s = Section(sid, sid, "figure")
            s.error = f"{type(e).__name__}: {e}"
            traceback.print_exc()
        built += s if isinstance(s, list) else [s]
    if not paper:
        # any other sweep: a part without data is left out, not shown as "not available"
        built = [s for s in built if s.available or s.error]
    for s in built:
        if s.kind == "figure":
            nfig += 1
            s.number = f"Figure {nfig}"
        else:
            ntab += 1
            s.number = f"Table {ntab}"
        if s.paper:
            s.number += f" (paper's {s.paper})"
        s.label = s.number.split(" (")[0]
        for f in s.files:
            if not os.path.getsize(os.path.join(out, f)):
                s.error = f"empty figure file {f}"
        sections.append(s)
    render(ctx, sections)
    na = [s.id for s in sections if not s.available or s.error]
    print(f"make_report: {out}/index.html, {out}/report.md: {len(sections)} sections"
          + (f", not available: {', '.join(na)}" if na else ", all available"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
