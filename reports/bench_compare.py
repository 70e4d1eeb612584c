#!/usr/bin/python3
"""Compare two Google Benchmark JSON files (ci/bench output): per benchmark, the old and new
medians over the repetitions, the ratio new/old and whether the change is beyond the noise.

    /usr/bin/python3 reports/bench_compare.py OLD.json NEW.json [--fail-on-slower PCT]

The rule (numpy only; scipy is not needed):

  * samples: the per-repetition entries (run_type "iteration") of each benchmark, in the time
    the benchmark is judged by: real_time for manual-time benchmarks (the whole-run timings,
    ".../manual_time") and for ".../real_time" ones, cpu_time otherwise (--metric overrides).
  * per side: median m and the relative robust spread s = 1.4826 MAD / m (MAD the median
    absolute deviation; 1.4826 MAD estimates the standard deviation of normal noise, and one
    outlier repetition cannot inflate it).
  * noise = 3 sqrt(s_old^2 + s_new^2); the change is beyond the noise when
    |ln(new median / old median)| > ln(1 + max(noise, min_change)), min_change = 2 %
    (--min-change); then "slower" (ratio > 1) or "faster", else "same within noise".
  * fewer than 3 repetitions on a side leave the spread unknown: only min_change applies and
    the verdict is marked "(few reps)".

Exit status: 0; 1 with --fail-on-slower PCT when a benchmark is "slower" by more than PCT %;
2 for bad input (unreadable file, no benchmark in common).
"""

import argparse
import json
import math
import re
import sys

import numpy as np

TO_NS = {"ns": 1.0, "us": 1e3, "ms": 1e6, "s": 1e9}
MAD_TO_SIGMA = 1.4826


class InputError(Exception):
    pass


def metric_for(name, metric):
    if metric != "auto":
        return metric
    return "real_time" if ("/manual_time" in name or "/real_time" in name) else "cpu_time"


def load(path, metric="auto"):
    """Returns (context, {benchmark name: numpy array of samples in ns}, {name: note})."""
    doc = read_document(path)
    samples, notes = samples_of(doc, metric)
    return doc.get("context", {}), samples, notes


def read_document(path):
    """The parsed Google Benchmark JSON of path; InputError naming path if it is not one."""
    try:
        with open(path) as f:
            doc = json.load(f)
    except (OSError, ValueError) as e:
        raise InputError(f"{path}: cannot read a benchmark JSON file: {e}")
    if not isinstance(doc, dict) or not isinstance(doc.get("benchmarks"), list):
        raise InputError(f"{path}: no \"benchmarks\" list (not Google Benchmark JSON output)")
    return doc


def samples_of(doc, metric="auto"):
    """({benchmark name: numpy array of samples in ns}, {name: note}) of a read document."""
    samples, medians, notes = {}, {}, {}
    for b in doc["benchmarks"]:
        name = b.get("run_name") or b.get("name")
        if name is None:
            continue
        if b.get("error_occurred"):
            notes[name] = "error: " + str(b.get("error_message", ""))
            continue
        kind = b.get("run_type", "iteration")
        m = metric_for(name, metric)
        if m not in b:
            continue
        value = float(b[m]) * TO_NS.get(b.get("time_unit", "ns"), 1.0)
        if kind == "iteration":
            samples.setdefault(name, []).append(value)
        elif kind == "aggregate" and b.get("aggregate_name") == "median":
            medians[name] = value
    # Files written with --benchmark_report_aggregates_only hold only aggregates: use the
    # median as a single sample.
    for name, value in medians.items():
        if name not in samples:
            samples[name] = [value]
            notes.setdefault(name, "aggregates only")
    return {k: np.asarray(v) for k, v in samples.items()}, notes


def spread(x):
    """Median and relative robust spread 1.4826 MAD / median (nan with fewer than 3 samples)."""
    med = float(np.median(x))
    if len(x) < 3 or med <= 0.0:
        return med, math.nan
    return med, MAD_TO_SIGMA * float(np.median(np.abs(x - med))) / med


def judge(old, new, min_change=0.02):
    """The verdict of one benchmark: dict with old/new medians, ratio, noise, verdict."""
    mo, so = spread(old)
    mn, sn = spread(new)
    few = math.isnan(so) or math.isnan(sn)
    noise = 0.0 if few else 3.0 * math.hypot(so, sn)
    threshold = max(noise, min_change)
    ratio = mn / mo if mo > 0 else math.inf
    if math.isfinite(ratio) and ratio > 0 and abs(math.log(ratio)) > math.log1p(threshold):
        verdict = "slower" if ratio > 1.0 else "faster"
    elif not math.isfinite(ratio) or ratio <= 0:
        verdict = "slower" if ratio > 1.0 else "faster"
    else:
        verdict = "same within noise"
    return {"old": mo, "new": mn, "ratio": ratio, "noise": noise, "threshold": threshold,
            "verdict": verdict, "few": few, "n_old": len(old), "n_new": len(new)}


def human(ns):
    for unit, scale in (("s", 1e9), ("ms", 1e6), ("us", 1e3)):
        if ns >= scale:
            return f"{ns / scale:.4g} {unit}"
    return f"{ns:.4g} ns"


def describe(ctx):
    machine = ctx.get("machine", {})
    commit = str(ctx.get("git_commit", "?"))
    short = commit.split("-")[0][:12] + ("-dirty" if commit.endswith("-dirty") else "")
    parts = [short, ctx.get("date_utc", ctx.get("date", "?")),
             machine.get("cpu_model", ctx.get("host_name", "?"))]
    if "nproc" in machine:
        parts.append(f"{machine['nproc']} cpus")
    if ctx.get("compiler"):
        parts.append(ctx["compiler"])
    return ", ".join(str(p) for p in parts)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("old", help="baseline JSON (ci/bench output)")
    ap.add_argument("new", help="JSON to compare with it")
    ap.add_argument("--metric", choices=["auto", "real_time", "cpu_time"], default="auto",
                    help="time compared (default auto: real_time for manual/real-time "
                         "benchmarks, cpu_time otherwise)")
    ap.add_argument("--min-change", type=float, default=2.0, metavar="PCT",
                    help="smallest change reported as beyond the noise, %% (default 2)")
    ap.add_argument("--fail-on-slower", type=float, default=None, metavar="PCT",
                    help="exit 1 when a benchmark is slower beyond the noise by more than PCT %%")
    ap.add_argument("--filter", default=None, metavar="REGEX",
                    help="compare only benchmarks whose name matches REGEX")
    args = ap.parse_args(argv)
    if args.min_change < 0 or (args.fail_on_slower is not None and args.fail_on_slower < 0):
        ap.error("percentages must be >= 0")

    try:
        ctx_old, old, notes_old = load(args.old, args.metric)
        ctx_new, new, notes_new = load(args.new, args.metric)
        pattern = re.compile(args.filter) if args.filter else None
    except (InputError, re.error) as e:
        print(f"bench_compare: {e}", file=sys.stderr)
        return 2
    names = [n for n in old if n in new and (pattern is None or pattern.search(n))]
    if not names:
        print(f"bench_compare: no benchmark in common between {args.old} and {args.new}",
              file=sys.stderr)
        return 2

    print(f"old: {args.old} ({describe(ctx_old)})")
    print(f"new: {args.new} ({describe(ctx_new)})")
    mo, mn = ctx_old.get("machine", {}), ctx_new.get("machine", {})
    if mo.get("cpu_model") != mn.get("cpu_model") or mo.get("nproc") != mn.get("nproc"):
        print("note: the two files come from different machines (or lack machine data); "
              "ratios compare machines as well as code")
    width = max(len("benchmark"), max(len(n) for n in names))
    print(f"{'benchmark':<{width}}  {'old median':>11}  {'new median':>11}  {'new/old':>8}  "
          f"{'noise':>6}  verdict")
    counts = {"faster": 0, "slower": 0, "same within noise": 0}
    worst = None
    for name in names:
        r = judge(old[name], new[name], args.min_change / 100.0)
        counts[r["verdict"]] += 1
        noise = "  n/a " if r["few"] else f"{100 * r['noise']:5.1f}%"
        note = " (few reps)" if r["few"] else ""
        extra = "; ".join(x for x in (notes_old.get(name), notes_new.get(name)) if x)
        if extra:
            note += f" [{extra}]"
        print(f"{name:<{width}}  {human(r['old']):>11}  {human(r['new']):>11}  "
              f"{r['ratio']:8.3f}  {noise}  {r['verdict']}{note}")
        if r["verdict"] == "slower" and (worst is None or r["ratio"] > worst[1]):
            worst = (name, r["ratio"])
    only_old = sorted(set(old) - set(new))
    only_new = sorted(set(new) - set(old))
    if only_old:
        print(f"only in old ({len(only_old)}): " + ", ".join(only_old))
    if only_new:
        print(f"only in new ({len(only_new)}): " + ", ".join(only_new))
    for name in sorted(set(notes_old) | set(notes_new)):
        if name not in old or name not in new:
            print(f"{name}: " + "; ".join(
                x for x in (notes_old.get(name), notes_new.get(name)) if x))
    print(f"{len(names)} compared: {counts['faster']} faster, {counts['slower']} slower, "
          f"{counts['same within noise']} same within noise")
    if args.fail_on_slower is not None and worst is not None and \
            worst[1] > 1.0 + args.fail_on_slower / 100.0:
        print(f"bench_compare: {worst[0]} is {100 * (worst[1] - 1):.1f} % slower "
              f"(limit {args.fail_on_slower:g} %)", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
