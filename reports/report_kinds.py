"""The data kinds of a layout (docs/studies.md, The layout): each turns one [[report.section]]
and its sweep into Sections (report_page.py). `plugin` sections are the study's own
(report_study.py). Every builder takes (ctx, sec, sweep): ctx the study's context
(report_study.StudyContext: `out`, `gates(name)`, `max_run_plots`), sec the layout table,
sweep the Sweep (report_io.py) it names."""

import report_generic as RG
import report_fields as RF
import report_kind_figures as KF
import report_stability as RS
from report_gates import GatedColumns
from report_io import find_stability_files, fmt_g, scheme_name
from report_layout import as_list
from report_page import Section, runs_text
from report_select import as_number, overrides, select, swept_keys, value


def _where_text(where):
    if not where:
        return ""
    return " (" + ", ".join(f"`{k}` = {v}" for k, v in where.items()) + ")"


def _cell(text, column):
    """A summary.csv cell: numbers in 4 significant digits, scheme names spelled out."""
    if column == "scheme":
        return scheme_name(text) or "–"
    x = as_number(text)
    if x is not None and text.strip().lower() not in ("nan", "inf", "-inf"):
        return fmt_g(x, 4)
    return text or "–"


def runs_table(ctx, sec, sweep, sid):
    s = Section(sid, f"Runs of `{sweep.name}`", "table")
    runs = select(sweep, sec.get("where"))
    ov = overrides(sweep)
    keys = swept_keys(sweep)
    cols = [c for c in as_list(sec.get("columns")) if c not in keys]
    gates = GatedColumns(sweep, ctx.gates_file(sec["sweep"]), ctx.sweep_entry(sec["sweep"]))
    # a gated column is shown when some gate on it has a verdict for a run of the table
    gated = [c for c in gates.columns if c not in cols and c not in keys
             and any(gates.mark(r, c) for r in runs)]
    s.header = ["run", "status"] + [f"`{k}`" for k in keys] + [f"`{c}`" for c in cols] + \
        [f"`{c}` (gated)" for c in gated]
    for r in runs:
        row = [f"`{r.id}`", RG.status_cell(r)]
        row += [_cell(value(r, k, ov), k) for k in keys]
        for c in cols:
            m = gates.mark(r, c)
            row.append(_cell(value(r, c, ov), c) + (f" {m}" if m else ""))
        for c in gated:
            m = gates.mark(r, c)
            row.append(_cell(value(r, c, ov), c) + (f" {m}" if m else ""))
        s.rows.append(row)
        s.runs.append(r.id)
    s.sources = [sweep.dir]
    npass, bad = gates.summary()
    gl = ("" if not gates.verdicts else
          f" Gates: {npass} passed, {len(bad)} failed" +
          (": " + "; ".join(f"**{b}**" for b in bad) if bad else "") + ".")
    s.caption = (f"`summary.csv` of `{sweep.dir}`, one row per run{_where_text(sec.get('where'))}"
                 f", in the sweep's order: the swept keys, then the columns chosen, then every "
                 "column a gate checks, with ✓ where the gates on it passed for that run and ✗ "
                 "with the gate's name where one failed (docs/gates.md)." + gl)
    if gates.verdicts:
        s.extra.append((sid + "_gates", "Gates", ["gate", "result", "detail"],
                        [[n, "passed" if v["passed"] else "**failed**",
                          (v["detail"][:237] + "…" if len(v["detail"]) > 240 else v["detail"])
                          or "–"] for n, v in gates.verdicts.items()]))
    return [s]


def metric(ctx, sec, sweep, sid):
    x, y, by = sec["x"], sec["y"], sec.get("by")
    s = Section(sid, f"`{y}` against `{x}`"
                + (f", by `{by}`" if by else ""), "figure")
    runs = [r for r in select(sweep, sec.get("where")) if r.ok]
    ov = overrides(sweep)
    series = {}
    for r in runs:
        yv = as_number(value(r, y, ov))
        xv = value(r, x, ov)
        if yv is None or xv == "":
            continue
        series.setdefault(value(r, by, ov) if by else "", []).append((xv, yv, r.id))
    if not series:
        s.available = False
        s.missing = f"no ok run of `{sweep.dir}` has both `{x}` and `{y}`."
        return [s]
    s.files = KF.fig_metric(ctx.out, sid, series, x, y, by, sec.get("logx", False),
                            sec.get("logy", False))
    s.runs = [i for pts in series.values() for _, _, i in pts]
    s.series = {str(k): len(pts) for k, pts in series.items()}
    s.sources = [sweep.dir]
    s.caption = (f"`{y}` of summary.csv against `{x}`" + (f", one line per value of `{by}`"
                 if by else "") + f"{_where_text(sec.get('where'))}; ok runs only. Runs: "
                 + runs_text(s.runs) + ".")
    return [s]


def work_precision(ctx, sec, sweep, sid):
    out = []
    runs = select(sweep, sec.get("where"))
    for k, m in enumerate(as_list(sec["error"])):
        s = RG.wp_section({"out": ctx.out}, sweep, Section, m, f"{sid}_{k}", f"{sid}_{k}",
                          cost=sec.get("cost", "wall_seconds"), by=sec.get("by"), runs=runs)
        out.append(s)
    return out


def histories(ctx, sec, sweep, sid):
    ys = as_list(sec["y"])
    s = Section(sid, "History: " + ", ".join(f"`{y}`" for y in ys),
                "figure")
    if sec.get("runs"):
        want = as_list(sec["runs"])
        runs = [r for r in sweep.runs if r.id in want or r.group in want]
    else:
        runs = select(sweep, sec.get("where"))
    runs = [r for r in runs if r.history() is not None][:KF.MAX_LINES]
    if not runs:
        s.available = False
        s.missing = f"no chosen run of `{sweep.dir}` has a history.csv."
        return [s]
    s.files = KF.fig_histories(ctx.out, sid, runs, ys)
    s.runs = [r.id for r in runs]
    s.sources = [sweep.dir]
    s.caption = ("The columns " + ", ".join(f"`{y}`" for y in ys) + " of each run's "
                 f"history.csv (docs/outputs.md) against time, one panel per column, at most "
                 f"{KF.MAX_LINES} runs. Runs: " + runs_text(s.runs) + ".")
    return [s]


def fields(ctx, sec, sweep, sid):
    s = Section(sid, "Deformed shapes", "figure")
    want = sec.get("run")
    runs = [r for r in sweep.runs if r.kind == "run" and (want is None or r.id == want
                                                           or r.group == want)]
    runs = [r for r in runs if RF.find_fields(r.folder)]
    if not runs:
        s.available = False
        s.missing = (f"no run of `{sweep.dir}`" + (f" named `{want}`" if want else "")
                     + " has field files (fields/*.vtu; the case's `output.fields`).")
        return [s]
    r = runs[0]
    got = RF.draw_run_fields(ctx.out, sid, r.folder, sec.get("field", "von_mises"),
                             sec.get("times"))
    s.files, s.caption = got["files"], got["caption"]
    s.runs = [r.id]
    s.sources = [r.folder]
    return [s]


def stability(ctx, sec, sweep, sid):
    s = Section(sid, "Largest stable time step per search", "table")
    where = dict(sec.get("where") or {})
    where.setdefault("kind", "stability")
    runs = select(sweep, where)
    files = [p for r in runs for p in find_stability_files([r.folder])]
    entries, bad = RS.read_stability_entries(files)
    if not entries:
        s.available = False
        s.missing = f"no stability search of `{sweep.dir}` has a stability.json" + \
            (f" ({'; '.join(bad)})" if bad else "") + "."
        return [s]
    s.header = RS.STABILITY_HEADER
    s.rows = RS.stability_rows(entries)
    s.runs = [r.id for r in runs]
    s.sources = [sweep.dir]
    s.caption = ("Per stability search of the sweep (docs/stability.md): the estimate "
                 "Δt_crit = min L_e/c_p, the largest stable and smallest unstable Δt the "
                 "bisection found, their ratio to the estimate and why the unstable step "
                 "failed. " + RS.stability_summary(RS.best_entries(entries)) + ".")
    return [s]


BUILDERS = {"runs_table": runs_table, "metric": metric, "work_precision": work_precision,
            "histories": histories, "fields": fields, "stability": stability}
