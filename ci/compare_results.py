#!/usr/bin/python3
"""Compares the results of two sweep output folders run by two builds: every number of every
run's summary.json and history.csv, timings aside (ci/compare_results builds and runs them).

    /usr/bin/python3 ci/compare_results.py BASE_DIR HEAD_DIR [--rel 1e-12] [--allow-new-keys]

BASE_DIR and HEAD_DIR are sweep folders (summary.csv, runs/<id>/). Runs are matched by run id.
A value differs when |a - b| > rel * max(|a|, |b|, scale), scale being 1e-6 x the largest
|value| of that history column or summary key in the base run (so that round-off around 0, such
as a penetration of 1e-22 m against 2e-22 m, is not a difference while any real change is).
Prints one line per difference (at most 20 per run, then a count) and a last line
"compare: N runs, M values, K differences"; exit 0 if none, 1 if any, 2 on bad input.
"""

import csv
import json
import math
import os
import sys

# Keys that measure the machine, not the results (the threads a run used follow the load:
# results are bitwise the same for any count).
IGNORED = {"wall_seconds", "cpu_seconds", "element_steps_per_second", "written_at", "ricochet_version",
           "build", "case_file", "overrides", "wall_seconds_min", "wall_seconds_max", "threads", "threads_min",
           "peak_memory_bytes", "phase_seconds"}


def flatten(prefix, value, out):
    if isinstance(value, dict):
        for k, v in value.items():
            if k in IGNORED:
                continue
            flatten(f"{prefix}.{k}" if prefix else k, v, out)
    elif isinstance(value, list):
        for i, v in enumerate(value):
            flatten(f"{prefix}[{i}]", v, out)
    else:
        out[prefix] = value


def read_history(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if not rows:
        return [], []
    return rows[0], [[float(x) for x in r] for r in rows[1:]]


def close(a, b, rel, scale):
    if isinstance(a, (int, float)) and isinstance(b, (int, float)) and \
            not isinstance(a, bool) and not isinstance(b, bool):
        if math.isnan(a) and math.isnan(b):
            return True
        if a == b:
            return True
        return abs(a - b) <= rel * max(abs(a), abs(b), scale)
    return a == b


def compare_run(base, head, rel, allow_new, out):
    n = 0
    diffs = []
    sb, sh = os.path.join(base, "summary.json"), os.path.join(head, "summary.json")
    if os.path.isfile(sb) or os.path.isfile(sh):
        if not (os.path.isfile(sb) and os.path.isfile(sh)):
            return 0, [f"summary.json only in {'base' if os.path.isfile(sb) else 'head'}"]
        fb, fh = {}, {}
        with open(sb) as f:
            flatten("", json.load(f), fb)
        with open(sh) as f:
            flatten("", json.load(f), fh)
        for k in sorted(set(fb) | set(fh)):
            if k not in fb:
                if not allow_new:
                    diffs.append(f"summary {k}: only in head ({fh[k]!r})")
                continue
            if k not in fh:
                diffs.append(f"summary {k}: only in base ({fb[k]!r})")
                continue
            n += 1
            a, b = fb[k], fh[k]
            scale = 1e-6 * abs(a) if isinstance(a, (int, float)) and not isinstance(a, bool) else 0.0
            if not close(a, b, rel, scale):
                diffs.append(f"summary {k}: base {a!r}, head {b!r}")
    hb, hh = os.path.join(base, "history.csv"), os.path.join(head, "history.csv")
    if os.path.isfile(hb) and os.path.isfile(hh):
        cb, rb = read_history(hb)
        ch, rh = read_history(hh)
        if len(rb) != len(rh):
            diffs.append(f"history: {len(rb)} rows in base, {len(rh)} in head")
        for j, name in enumerate(cb):
            if name not in ch:
                diffs.append(f"history column {name}: only in base")
                continue
            k = ch.index(name)
            scale = 1e-6 * max((abs(r[j]) for r in rb), default=0.0)
            worst = None
            for i in range(min(len(rb), len(rh))):
                n += 1
                a, b = rb[i][j], rh[i][k]
                if not close(a, b, rel, scale):
                    d = abs(a - b) / max(abs(a), abs(b), scale)
                    if worst is None or d > worst[0]:
                        worst = (d, i, a, b)
            if worst:
                d, i, a, b = worst
                diffs.append(f"history {name}: row {i}: base {a!r}, head {b!r} (relative {d:.3g})")
        if not allow_new:
            for name in ch:
                if name not in cb:
                    diffs.append(f"history column {name}: only in head")
    elif os.path.isfile(hb) != os.path.isfile(hh):
        diffs.append(f"history.csv only in {'base' if os.path.isfile(hb) else 'head'}")
    return n, diffs


def run_ids(folder):
    with open(os.path.join(folder, "summary.csv"), newline="") as f:
        return [r["run_id"] for r in csv.DictReader(f)]


def main(argv):
    args = [a for a in argv if not a.startswith("--")]
    rel = 1e-12
    for a in argv:
        if a.startswith("--rel="):
            rel = float(a.split("=", 1)[1])
    allow_new = "--allow-new-keys" in argv
    if len(args) != 2 or not all(os.path.isfile(os.path.join(d, "summary.csv")) for d in args):
        print("compare_results: give two sweep folders (each with summary.csv)", file=sys.stderr)
        return 2
    base, head = args
    ids_b, ids_h = run_ids(base), run_ids(head)
    total_values = total_diffs = 0
    for rid in sorted(set(ids_b) | set(ids_h)):
        if rid not in ids_b or rid not in ids_h:
            print(f"{rid}: only in {'base' if rid in ids_b else 'head'}")
            total_diffs += 1
            continue
        n, diffs = compare_run(os.path.join(base, "runs", rid), os.path.join(head, "runs", rid), rel,
                               allow_new, sys.stdout)
        total_values += n
        total_diffs += len(diffs)
        for d in diffs[:20]:
            print(f"{rid}: {d}")
        if len(diffs) > 20:
            print(f"{rid}: ... {len(diffs) - 20} more")
    print(f"compare: {len(set(ids_b) | set(ids_h))} runs, {total_values} values, {total_diffs} differences "
          f"(relative tolerance {rel:g})")
    return 1 if total_diffs else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
