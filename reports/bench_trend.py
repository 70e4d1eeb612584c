#!/usr/bin/python3
"""The trend page of a benchmark history: one plot per benchmark over commits and the
regressions beyond noise between consecutive commits, each named with the commit that caused it.

    /usr/bin/python3 reports/bench_trend.py HISTORY_DIR [--out DIR] [--metric M] [--min-change PCT]

HISTORY_DIR holds ci/bench result files (`ci/bench --history DIR` puts one per commit there);
every *.json directly in it is read, and each must be one. The files are put in order by
context.git_commit_date_utc (the commit's committer date, recorded by ci/bench), falling back
to context.date_utc (when the run started) for files without it, with date_utc breaking ties.
Two files of the same commit on the same machine: the later run is used, the other is listed.

Machines are never compared with each other: the machine of a file is its context
machine.cpu_model and machine.nproc, each machine has its own series in the plots, and a
regression is judged only between consecutive commits measured on the same machine.

The judgement is reports/bench_compare.py's (imported, not copied): per benchmark, the median
of the repetitions and their robust spread on each side; "beyond noise" when the ratio of the
medians exceeds 1 + max(3 sqrt(s_old^2 + s_new^2), min change 2 %). Slower beyond noise is a
regression, named by the later commit of the pair; faster beyond noise is listed as an
improvement. The time judged and plotted is bench_compare's: real time for manual-time and
real-time benchmarks, CPU time otherwise, in the unit of the JSON's time_unit.

Writes DIR/index.html (default DIR: HISTORY_DIR) and the plots DIR/plots/*.png (plots/ is the
page's: other PNGs there are removed). The page and plots are built in a temporary folder and
moved into place, index.html last, so a failure leaves the previous page. Exit status: 0
written (regressions or not), 1 the page could not be written, 2 bad input (one line on stderr
naming the file: not a folder, no result file, a file that is not a ci/bench result).
"""

import argparse
import datetime
import html
import math
import os
import re
import shutil
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import bench_compare as BC  # noqa: E402

RATE_COUNTER = "element_steps_per_second"
METRIC_LABEL = {"real_time": "real time", "cpu_time": "CPU time"}
UNIT_LABEL = {"us": "µs"}


class Run:
    """One result file: its provenance and its samples (ns) per benchmark."""

    def __init__(self, path, doc, metric):
        ctx = doc.get("context")
        if not isinstance(ctx, dict):
            raise BC.InputError(f"{path}: no \"context\" object (not a ci/bench result file)")
        self.path = path
        self.file = os.path.basename(path)
        self.commit = str(ctx.get("git_commit") or "")
        if not self.commit:
            raise BC.InputError(f"{path}: no context.git_commit (not a ci/bench result file)")
        self.short = short_commit(self.commit)
        run_date = ctx.get("date_utc") or ctx.get("date")
        if not run_date:
            raise BC.InputError(f"{path}: no context.date_utc (not a ci/bench result file)")
        self.run_date = parse_date(run_date, path, "date_utc")
        commit_date = ctx.get("git_commit_date_utc")
        self.commit_date = parse_date(commit_date, path, "git_commit_date_utc") \
            if commit_date else None
        machine = ctx.get("machine") if isinstance(ctx.get("machine"), dict) else {}
        nproc = machine.get("nproc", ctx.get("num_cpus"))
        self.machine = (str(machine.get("cpu_model", ctx.get("host_name", "unknown machine"))),
                        nproc if isinstance(nproc, int) or nproc is None else str(nproc))
        self.compiler = str(ctx.get("compiler", "unknown compiler"))
        self.build = describe_build(ctx.get("build"))
        self.options = describe_options(ctx.get("ci_bench"))
        try:
            self.samples, self.notes = BC.samples_of(doc, metric)
            self.units, self.counters = units_and_counters(doc)
        except (ValueError, TypeError, AttributeError) as e:
            raise BC.InputError(f"{path}: malformed benchmark entry: {e}")
        if not self.samples:
            raise BC.InputError(f"{path}: no benchmark result in the file")

    def order_key(self):
        return (self.commit_date or self.run_date, self.run_date)


def short_commit(commit):
    """The first 7 hex digits, keeping the -dirty mark of a run on modified sources."""
    base = commit.split("-")[0]
    return base[:7] + ("-dirty" if commit.endswith("-dirty") else "")


def parse_date(value, path, key):
    """An aware UTC datetime from an ISO 8601 string; InputError naming path and key if not."""
    try:
        d = datetime.datetime.fromisoformat(str(value).replace("Z", "+00:00"))
    except ValueError:
        raise BC.InputError(f"{path}: context.{key} is not an ISO 8601 date: {value!r}")
    return (d if d.tzinfo else d.replace(tzinfo=datetime.timezone.utc)).astimezone(
        datetime.timezone.utc)


def describe_build(build):
    if not isinstance(build, dict):
        return ""
    native = {"ON": ", native", "OFF": ", portable"}.get(str(build.get("native", "")), "")
    return f"{build.get('type', '')}{native}"


def describe_options(opts):
    if not isinstance(opts, dict):
        return ""
    parts = [f"{opts.get('repetitions', '?')} reps"]
    if opts.get("quick"):
        parts.append("quick")
    if opts.get("filter") and not opts.get("quick"):
        parts.append(f"filter {opts['filter']}")
    return ", ".join(parts)


def units_and_counters(doc):
    """{name: time_unit} and {name: set of counter keys} from the per-repetition entries."""
    units, counters = {}, {}
    for b in doc["benchmarks"]:
        name = b.get("run_name") or b.get("name")
        if name is None:
            continue
        units.setdefault(name, str(b.get("time_unit", "ns")))
        if RATE_COUNTER in b:
            counters.setdefault(name, set()).add(RATE_COUNTER)
    return units, counters


def machine_label(machine):
    model, nproc = machine
    return model if nproc is None else f"{model}, {nproc} cpus"


def read_history(history_dir, metric):
    """Every run of history_dir in commit order, and the runs superseded by a later run of the
    same commit on the same machine. InputError for anything that is not a usable history."""
    if not os.path.isdir(history_dir):
        raise BC.InputError(f"{history_dir}: not a folder")
    names = sorted(n for n in os.listdir(history_dir)
                   if n.endswith(".json") and not n.startswith("."))
    if not names:
        raise BC.InputError(f"{history_dir}: no result file (*.json) in the folder")
    runs = []
    for n in names:
        path = os.path.join(history_dir, n)
        runs.append(Run(path, BC.read_document(path), metric))
    runs.sort(key=Run.order_key)
    latest = {}
    for r in runs:
        latest[(r.commit, r.machine)] = r
    kept = [r for r in runs if latest[(r.commit, r.machine)] is r]
    superseded = [r for r in runs if latest[(r.commit, r.machine)] is not r]
    return kept, superseded


def judge_history(runs, min_change):
    """Each change beyond noise between consecutive runs of one machine that both measured a
    benchmark: dicts with benchmark, machine, before, after (Runs), the judge() result, and
    skipped (commits in between that did not measure it on that machine)."""
    changes = []
    commits = commit_axis(runs)
    for machine in machines_of(runs):
        series = [r for r in runs if r.machine == machine]
        for name in benchmark_names(series):
            measured = [r for r in series if name in r.samples]
            for before, after in zip(measured, measured[1:]):
                verdict = BC.judge(before.samples[name], after.samples[name], min_change)
                if verdict["verdict"] == "same within noise":
                    continue
                skipped = commits.index(after.commit) - commits.index(before.commit) - 1
                changes.append({"benchmark": name, "machine": machine, "before": before,
                                "after": after, "judge": verdict, "skipped": skipped})
    return changes


def machines_of(runs):
    seen = []
    for r in runs:
        if r.machine not in seen:
            seen.append(r.machine)
    return seen


def benchmark_names(runs):
    """Every benchmark of runs, in the order of the files (the suite's order)."""
    names = {}
    for r in runs:
        for n in r.samples:
            names.setdefault(n, None)
    return list(names)


def display_unit(runs, name):
    """The benchmark's time_unit in its latest run (the JSON's own unit; ns if unknown)."""
    for r in reversed(runs):
        if name in r.units and r.units[name] in BC.TO_NS:
            return r.units[name]
    return "ns"


def plot_file_name(index, name):
    return f"{index:03d}-{re.sub(r'[^A-Za-z0-9_.-]+', '_', name)[:80]}.png"


def plot_benchmark(path, name, runs, changes, metric):
    """One PNG: per machine the median of each commit, bars from the fastest to the slowest
    repetition, regressions ringed in red with their ratio, improvements in green."""
    commits = commit_axis(runs)
    unit = display_unit(runs, name)
    scale = BC.TO_NS[unit]
    fig, ax = plt.subplots(figsize=(10, 3.4), dpi=100)
    for k, machine in enumerate(machines_of(runs)):
        points = [r for r in runs if r.machine == machine and name in r.samples]
        if not points:
            continue
        x = [commits.index(r.commit) for r in points]
        med = np.array([np.median(r.samples[name]) for r in points]) / scale
        lo = np.array([np.min(r.samples[name]) for r in points]) / scale
        hi = np.array([np.max(r.samples[name]) for r in points]) / scale
        ax.errorbar(x, med, yerr=[med - lo, hi - med], fmt="o-", ms=4, lw=1.2, capsize=3,
                    color=f"C{k % 10}", label=machine_label(machine))
    for c in changes:
        if c["benchmark"] != name:
            continue
        x = commits.index(c["after"].commit)
        y = c["judge"]["new"] / scale
        slower = c["judge"]["verdict"] == "slower"
        color = "#c62828" if slower else "#2e7d32"
        ax.plot([x], [y], "o", ms=13, mfc="none", mec=color, mew=2)
        ax.annotate(f"×{c['judge']['ratio']:.3g}", (x, y), textcoords="offset points",
                    xytext=(9, 7 if slower else -14), color=color, fontsize=9, weight="bold")
    label_commit_axis(ax, commits, runs)
    metric_name = METRIC_LABEL[BC.metric_for(name, metric)]
    ax.set_ylabel(f"{metric_name} ({UNIT_LABEL.get(unit, unit)})")
    ax.grid(True, axis="y", alpha=0.3)
    ax.margins(x=0.05, y=0.2)
    if len(machines_of(runs)) > 1:
        ax.legend(fontsize=8, loc="best")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def commit_axis(runs):
    """The distinct commits in history order (a commit run on two machines appears once)."""
    commits = []
    for r in runs:
        if r.commit not in commits:
            commits.append(r.commit)
    return commits


def label_commit_axis(ax, commits, runs):
    """Short commits as tick labels, thinned to at most about 30 so that they stay legible."""
    shorts = {r.commit: r.short for r in runs}
    step = max(1, math.ceil(len(commits) / 30))
    ticks = list(range(0, len(commits), step))
    ax.set_xticks(ticks)
    ax.set_xticklabels([shorts[commits[i]] for i in ticks], rotation=45, ha="right",
                       fontsize=8, family="monospace")
    ax.set_xlim(-0.5, len(commits) - 0.5)
    ax.set_xlabel("commit (oldest left)")


CSS = """
body{font-family:system-ui,-apple-system,'Segoe UI',Helvetica,Arial,sans-serif;max-width:1150px;
margin:1.5em auto;padding:0 1em;color:#222;line-height:1.45}
h1{font-size:1.6em;margin-bottom:.2em} h2{margin-top:1.8em;border-bottom:1px solid #ccc}
h3{font-size:1.05em;margin-bottom:.2em}
table{border-collapse:collapse;margin:.6em 0;font-size:.88em}
th,td{border:1px solid #bbb;padding:.25em .5em;vertical-align:top}
th{background:#f0f0f0} td.num{text-align:right;white-space:nowrap} td code{white-space:nowrap}
tr.regression td.ratio{background:#fdecea;font-weight:bold}
tr.improvement td.ratio{background:#e8f5e9}
figure{margin:1em 0} figure img{max-width:100%;border:1px solid #ddd}
figcaption,.caption{font-size:.9em;color:#333;margin-top:.4em}
code{font-family:ui-monospace,'DejaVu Sans Mono',Menlo,Consolas,monospace;font-size:.9em;
background:#f4f4f4;padding:0 .2em}
.none{border:2px solid #2e7d32;background:#f3faf3;padding:.5em 1em}
.warn{border:2px dashed #c33;background:#fff6f6;padding:.5em 1em}
.meta td{border:none;padding:.1em .8em .1em 0}
"""


def esc(value):
    return html.escape(str(value))


def table(tid, header, rows, row_class=None):
    """An HTML table; cells are already escaped HTML; row_class(i) gives a row's class."""
    out = [f'<table id="{tid}"><thead><tr>']
    out += [f"<th>{h}</th>" for h in header]
    out.append("</tr></thead><tbody>")
    for i, row in enumerate(rows):
        cls = f' class="{row_class(i)}"' if row_class else ""
        out.append(f"<tr{cls}>" + "".join(row) + "</tr>")
    out.append("</tbody></table>")
    return "\n".join(out)


def td(value, cls=None):
    return f'<td class="{cls}">{value}</td>' if cls else f"<td>{value}</td>"


def commit_cell(run):
    return f'<code title="{esc(run.commit)}">{esc(run.short)}</code>'


def change_rows(changes, anchors, multi_machine):
    rows = []
    for c in changes:
        j = c["judge"]
        note = []
        if c["skipped"]:
            note.append(f"{c['skipped']} commit(s) in between not measured here: the change is "
                        f"in one of them or in {esc(c['after'].short)}")
        if j["few"]:
            note.append(f"fewer than 3 repetitions: only the {100 * j['threshold']:g} % "
                        "floor applies")
        if c["before"].compiler != c["after"].compiler:
            note.append("compiler changed")
        if c["before"].options != c["after"].options or c["before"].build != c["after"].build:
            note.append("ci/bench options or build changed")
        row = [td(f'<a href="#{anchors[c["benchmark"]]}">{esc(c["benchmark"])}</a>')]
        if multi_machine:
            row.append(td(esc(machine_label(c["machine"]))))
        row += [td(commit_cell(c["before"])), td(commit_cell(c["after"])),
                td(f"{j['ratio']:.3f}", "num ratio"),
                td(f"{BC.human(j['old'])} → {BC.human(j['new'])}", "num"),
                td(f"{100 * j['threshold']:.1f} %", "num"), td("; ".join(note))]
        rows.append(row)
    return rows


def change_table(tid, changes, anchors, multi_machine, kind):
    header = ["benchmark"] + (["machine"] if multi_machine else []) + [
        "commit before", "commit after (the cause)" if kind == "regression" else "commit after",
        "after/before", "medians", "noise threshold", "note"]
    return table(tid, header, change_rows(changes, anchors, multi_machine),
                 lambda i: kind)


def commits_table(runs):
    rows = []
    for i, r in enumerate(runs, 1):
        commit_date = r.commit_date.strftime("%Y-%m-%d %H:%M") if r.commit_date else "—"
        rows.append([td(i, "num"), td(commit_cell(r)), td(esc(commit_date)),
                     td(esc(r.run_date.strftime("%Y-%m-%d %H:%M"))),
                     td(esc(machine_label(r.machine))), td(esc(r.compiler)), td(esc(r.build)),
                     td(esc(r.options)), td(f"<code>{esc(r.file)}</code>")])
    header = ["#", "commit", "commit date (UTC)", "run date (UTC)", "machine (cpu_model)",
              "compiler", "build", "ci/bench options", "file"]
    return table("commits", header, rows)


def render_page(history_dir, runs, superseded, changes, plots, metric, min_change):
    """The page's HTML: regressions first, then improvements, commits and the plots."""
    regressions = [c for c in changes if c["judge"]["verdict"] == "slower"]
    improvements = [c for c in changes if c["judge"]["verdict"] == "faster"]
    anchors = {name: f"plot-{i:03d}" for i, (name, _) in enumerate(plots)}
    machines = machines_of(runs)
    multi = len(machines) > 1
    now = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    h = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
         "<title>ricochet: benchmark trend</title>", f"<style>{CSS}</style></head><body>",
         "<h1>Benchmark trend</h1>", '<table class="meta">']
    files = f"{len(runs) + len(superseded)} result files" + (
        f" ({len(superseded)} superseded)" if superseded else "")
    meta = [("history", f"<code>{esc(history_dir)}</code>: {files}, "
                        f"{len(commit_axis(runs))} commits, {len(plots)} benchmarks"),
            ("machines", "; ".join(esc(machine_label(m)) for m in machines)),
            ("generated", esc(now))]
    h += [f"<tr><td><b>{k}</b></td><td>{v}</td></tr>" for k, v in meta]
    h.append("</table>")
    if multi:
        h.append('<p class="warn">The history holds results from more than one machine '
                 "(cpu_model and cpu count). Each machine is its own series; changes are "
                 "judged only between commits measured on the same machine.</p>")
    h.append(f'<h2 id="regressions">Regressions beyond noise ({len(regressions)})</h2>')
    h.append(f"<p>{rule_text(min_change)}</p>")
    if regressions:
        h.append(change_table("regressions", regressions, anchors, multi, "regression"))
    else:
        h.append('<p class="none" id="no-regressions">No benchmark got slower beyond the noise '
                 "between consecutive commits.</p>")
    h.append(f'<h2 id="improvements">Improvements beyond noise ({len(improvements)})</h2>')
    if improvements:
        h.append(change_table("improvements", improvements, anchors, multi, "improvement"))
    else:
        h.append("<p>None.</p>")
    h.append('<h2 id="commits-list">Commits</h2>')
    h.append("<p>In the order of the plots: by commit date (context.git_commit_date_utc), or "
             "by run date (context.date_utc) for files without it.</p>")
    h.append(commits_table(runs))
    if superseded:
        h.append("<p>Superseded by a later run of the same commit on the same machine, not "
                 "plotted: " + ", ".join(f"<code>{esc(r.file)}</code>" for r in superseded) +
                 ".</p>")
    h.append('<h2 id="plots">Benchmarks</h2>')
    h.append("<p>Each point is the median of a commit's repetitions; its bar spans the fastest "
             "to the slowest repetition. A red ring marks a regression beyond noise (its ratio "
             "beside it), a green ring an improvement. The time axes start at the data, not "
             "at zero: read the size of a change from the tables above.</p>")
    for name, file_name in plots:
        h.append(f'<figure id="{anchors[name]}"><h3>{esc(name)}</h3>'
                 f'<a href="plots/{esc(file_name)}"><img src="plots/{esc(file_name)}" '
                 f'alt="{esc(name)} over commits"></a>')
        caption = plot_caption(name, runs, metric)
        if caption:
            h.append(f"<figcaption>{caption}</figcaption>")
        h.append("</figure>")
    h.append("</body></html>")
    return "\n".join(h) + "\n"


def rule_text(min_change):
    return ("Consecutive commits measured on the same machine are compared as "
            "<code>reports/bench_compare.py</code> compares two files: the medians of the "
            "repetitions, and the change is beyond noise when the ratio exceeds 1 + max(3 "
            "&radic;(s<sub>before</sub>&sup2; + s<sub>after</sub>&sup2;), "
            f"{100 * min_change:g} %), s the robust relative spread (1.4826 MAD / median) of "
            "each side. The later commit of a slower pair is named as the cause.")


def plot_caption(name, runs, metric):
    """What the plot shows beyond the obvious: the time judged and the rate counter."""
    parts = []
    if BC.metric_for(name, metric) == "real_time" and metric == "auto":
        parts.append("Real (wall) time: a manual-time or real-time benchmark.")
    if any(RATE_COUNTER in r.counters.get(name, ()) for r in runs):
        parts.append(f"This benchmark also records <code>{RATE_COUNTER}</code>; the plot shows "
                     "time per iteration anyway (the rate is work over this time, so it falls "
                     "when the time rises).")
    return " ".join(parts)


def write_page(out_dir, runs, superseded, changes, history_dir, metric, min_change):
    """Builds plots and page in a temporary folder inside out_dir, then moves the plots into
    out_dir/plots (removing plots of benchmarks no longer present) and index.html last."""
    os.makedirs(out_dir, exist_ok=True)
    tmp = tempfile.mkdtemp(prefix=".bench_trend-", dir=out_dir)
    try:
        os.mkdir(os.path.join(tmp, "plots"))
        plots = []
        for i, name in enumerate(benchmark_names(runs)):
            file_name = plot_file_name(i, name)
            plot_benchmark(os.path.join(tmp, "plots", file_name), name, runs, changes, metric)
            plots.append((name, file_name))
        with open(os.path.join(tmp, "index.html"), "w") as f:
            f.write(render_page(history_dir, runs, superseded, changes, plots, metric,
                                min_change))
        plots_dir = os.path.join(out_dir, "plots")
        os.makedirs(plots_dir, exist_ok=True)
        fresh = {file_name for _, file_name in plots}
        for file_name in fresh:
            os.replace(os.path.join(tmp, "plots", file_name), os.path.join(plots_dir, file_name))
        for stale in set(os.listdir(plots_dir)) - fresh:
            if stale.endswith(".png"):
                os.remove(os.path.join(plots_dir, stale))
        os.replace(os.path.join(tmp, "index.html"), os.path.join(out_dir, "index.html"))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return plots


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("history", help="folder of ci/bench result files (ci/bench --history DIR)")
    ap.add_argument("--out", default=None, metavar="DIR",
                    help="where index.html and plots/ go (default: the history folder)")
    ap.add_argument("--metric", choices=["auto", "real_time", "cpu_time"], default="auto",
                    help="time judged and plotted (default auto, as bench_compare.py)")
    ap.add_argument("--min-change", type=float, default=2.0, metavar="PCT",
                    help="smallest change reported as beyond the noise, %% (default 2)")
    args = ap.parse_args(argv)
    if args.min_change < 0:
        ap.error("--min-change must be >= 0")
    try:
        runs, superseded = read_history(args.history, args.metric)
    except BC.InputError as e:
        print(f"bench_trend: {e}", file=sys.stderr)
        return 2
    changes = judge_history(runs, args.min_change / 100.0)
    out = args.out or args.history
    try:
        plots = write_page(out, runs, superseded, changes, args.history, args.metric,
                           args.min_change / 100.0)
    except OSError as e:
        print(f"bench_trend: cannot write the page in {out}: {e}", file=sys.stderr)
        return 1
    regressions = [c for c in changes if c["judge"]["verdict"] == "slower"]
    print(f"bench_trend: {os.path.join(out, 'index.html')}: {len(runs)} files, "
          f"{len(plots)} benchmarks, {len(regressions)} regressions beyond noise")
    for c in regressions:
        print(f"  {c['benchmark']}: x{c['judge']['ratio']:.3f} at {c['after'].short} "
              f"(after {c['before'].short}, {machine_label(c['machine'])})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
