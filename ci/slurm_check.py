#!/usr/bin/python3
"""The checks of ci/slurm-test on a sweep folder written by Slurm array tasks (docs/sweeps.md,
"Sharded sweeps" and "Running on a cluster"). Standard library only.

    slurm_check.py compare REF.csv MERGED.csv
        The two summary.csv tables hold the same runs (by run_id, in the same order), the same
        columns, and in every row the same text in every cell but the timing columns
        (TIMING below). Exit 1 on any difference, listing at most 20.
    slurm_check.py running DIR K N
        If shard K of N has finished at least one run and is now running another (its run
        folder's run.lock held, no summary.json) that started at least MIN_AGE seconds ago,
        prints that run's id; else nothing. The age (from its overrides.json, written as the run
        starts) keeps the runs of a few tenths of a second out: one of them could end between
        this answer and the kill that follows it.
    slurm_check.py pid DIR K N
        The pid in DIR/shards/K-of-N/shard.json (the shard process).
    slurm_check.py settled DIR K N
        Exit 1 while shard K of N's process is alive or one of its runs holds its run.lock;
        then prints the runs it started and did not finish (overrides.json, but neither
        summary.json nor failure.json): the run a stopped shard interrupted, or none if it was
        stopped between two runs.
    slurm_check.py interrupted DIR RUN_ID
        Exit 0 if the run folder is free (nobody holds its run.lock) and holds no summary.json:
        the run was stopped before it finished and nothing writes its folder any more.
    slurm_check.py snapshot DIR OUT.json
        Every finished run of DIR (a summary.json beside its overrides.json): its summary.json's
        modification time (ns) and SHA-256, into OUT.json.
    slurm_check.py unchanged DIR SNAPSHOT.json
        Every run of the snapshot still has the same summary.json (time and content): none of
        them ran again. Prints their number.
    slurm_check.py executed DIR N
        The runs executed by each shard's last invocation (shard.json counts.executed), as
        "K:executed" words, and their sum last.
    slurm_check.py seconds DIR K N
        Shard K of N's last invocation's wall time from its shard.json (finished_unix -
        started_unix), or "-" if it did not finish.
    slurm_check.py missing DIR
        The missing runs of the last merge (sweep.json merge.missing), one "SHARD RUN_ID" line each.
"""

import csv
import fcntl
import hashlib
import json
import os
import sys
import time

MIN_AGE = 0.5  # s

# Columns that measure the machine and the moment, not the results (docs/sweeps.md, summary.csv;
# docs/outputs.md): compared by name, or by the last part of a flattened name
# (relaxation.wall_seconds).
TIMING = {"wall_seconds", "cpu_seconds", "element_steps_per_second", "wall_seconds_min", "wall_seconds_max",
          "written_at", "peak_memory_bytes"}


def is_timing(column):
    return (column in TIMING or column.rsplit(".", 1)[-1] in TIMING
            or column.startswith("implicit.phase_seconds."))


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if not rows:
        sys.exit(f"slurm_check: {path}: empty")
    return rows[0], rows[1:]


def compare(ref_path, merged_path):
    ref_head, ref_rows = read_csv(ref_path)
    head, rows = read_csv(merged_path)
    problems = []
    if head != ref_head:
        problems.append(f"columns differ: only in {ref_path}: {sorted(set(ref_head) - set(head))}; "
                        f"only in {merged_path}: {sorted(set(head) - set(ref_head))}")
    ref_ids = [r[0] for r in ref_rows]
    ids = [r[0] for r in rows]
    if ids != ref_ids:
        problems.append(f"runs differ: only in {ref_path}: {sorted(set(ref_ids) - set(ids))}; "
                        f"only in {merged_path}: {sorted(set(ids) - set(ref_ids))}; "
                        f"same set, other order: {set(ids) == set(ref_ids)}")
    if len(set(ids)) != len(ids):
        problems.append(f"{merged_path}: a run appears more than once")
    cells = 0
    if not problems:
        timing = [c for c in head if is_timing(c)]
        for a, b in zip(ref_rows, rows):
            if len(a) != len(ref_head) or len(b) != len(head):
                problems.append(f"{a[0]}: rows of {len(a)} and {len(b)} fields for {len(head)} columns")
                continue
            for column, x, y in zip(head, a, b):
                if is_timing(column):
                    continue
                cells += 1
                if x != y:
                    problems.append(f"{a[0]}: {column}: {x!r} (single host) != {y!r} (Slurm)")
    for p in problems[:20]:
        print(f"compare: {p}")
    if len(problems) > 20:
        print(f"compare: ... and {len(problems) - 20} more")
    if problems:
        return 1
    print(f"compare: {len(ids)} runs, {cells} cells equal, statuses included "
          f"(left out, timings: {', '.join(timing)})")
    return 0


def held(lock_path):
    """Whether another process holds the flock on lock_path (the sweep's run.lock)."""
    try:
        fd = os.open(lock_path, os.O_RDWR)
    except FileNotFoundError:
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        return False
    except BlockingIOError:
        return True
    finally:
        os.close(fd)  # releases the lock if we took it


def manifest(out, k, n):
    path = os.path.join(out, "shards", f"{k}-of-{n}", "shard.json")
    try:
        with open(path) as f:
            return json.load(f)
    except (FileNotFoundError, json.JSONDecodeError):  # not started, or being replaced
        return None


def running(out, k, n):
    m = manifest(out, k, n)
    if not m or m.get("finished_at") is not None:
        return 0
    ids = m.get("runs", [])
    done = [i for i in ids if os.path.exists(os.path.join(out, "runs", i, "summary.json"))]
    busy = [i for i in ids if i not in done and held(os.path.join(out, "runs", i, "run.lock"))]
    for i in busy if done else []:
        try:
            age = time.time() - os.stat(os.path.join(out, "runs", i, "overrides.json")).st_mtime
        except FileNotFoundError:
            continue
        if age >= MIN_AGE:
            print(i)
            break
    return 0


def settled(out, k, n):
    m = manifest(out, k, n)
    if not m:
        return 1
    try:
        os.kill(int(m["pid"]), 0)
        return 1  # the shard process is still alive
    except ProcessLookupError:
        pass
    except PermissionError:
        return 1
    unfinished = []
    for i in m.get("runs", []):
        folder = os.path.join(out, "runs", i)
        if held(os.path.join(folder, "run.lock")):
            return 1
        started = os.path.exists(os.path.join(folder, "overrides.json"))
        ended = any(os.path.exists(os.path.join(folder, f)) for f in ("summary.json", "failure.json"))
        if started and not ended:
            unfinished.append(i)
    for i in unfinished:
        print(i)
    return 0


def finished_runs(out):
    found = {}
    for root, _dirs, files in os.walk(os.path.join(out, "runs")):
        if "overrides.json" in files and "summary.json" in files:
            with open(os.path.join(root, "overrides.json")) as f:
                run_id = json.load(f)["run_id"]
            path = os.path.join(root, "summary.json")
            with open(path, "rb") as f:
                digest = hashlib.sha256(f.read()).hexdigest()
            found[run_id] = [os.stat(path).st_mtime_ns, digest]
    return found


def main(argv):
    if len(argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    cmd, args = argv[1], argv[2:]
    if cmd == "compare" and len(args) == 2:
        return compare(*args)
    if cmd == "running" and len(args) == 3:
        return running(args[0], int(args[1]), int(args[2]))
    if cmd == "pid" and len(args) == 3:
        m = manifest(args[0], int(args[1]), int(args[2]))
        if not m:
            return 1
        print(m["pid"])
        return 0
    if cmd == "settled" and len(args) == 3:
        return settled(args[0], int(args[1]), int(args[2]))
    if cmd == "interrupted" and len(args) == 2:
        folder = os.path.join(args[0], "runs", args[1])
        return 1 if held(os.path.join(folder, "run.lock")) or os.path.exists(os.path.join(folder, "summary.json")) else 0
    if cmd == "snapshot" and len(args) == 2:
        with open(args[1], "w") as f:
            json.dump(finished_runs(args[0]), f, indent=1)
        return 0
    if cmd == "unchanged" and len(args) == 2:
        with open(args[1]) as f:
            before = json.load(f)
        now = finished_runs(args[0])
        changed = [i for i, v in before.items() if now.get(i) != v]
        for i in changed:
            print(f"unchanged: {i}: its summary.json was written again (it ran twice)")
        print(f"unchanged: {len(before) - len(changed)} of {len(before)} runs finished before the resubmission")
        return 1 if changed else 0
    if cmd == "executed" and len(args) == 2:
        n = int(args[1])
        words, total = [], 0
        for k in range(1, n + 1):
            m = manifest(args[0], k, n)
            c = (m or {}).get("counts") or {}
            if "executed" not in c:
                print(f"executed: shard {k} of {n} did not finish (no counts in its shard.json)", file=sys.stderr)
                return 1
            words.append(f"{k}:{c['executed']}")
            total += c["executed"]
        print(" ".join(words + [str(total)]))
        return 0
    if cmd == "seconds" and len(args) == 3:
        m = manifest(args[0], int(args[1]), int(args[2])) or {}
        start, end = m.get("started_unix"), m.get("finished_unix")
        print(f"{end - start:.1f}" if isinstance(start, (int, float)) and isinstance(end, (int, float)) else "-")
        return 0
    if cmd == "missing" and len(args) == 1:
        with open(os.path.join(args[0], "sweep.json")) as f:
            for m in json.load(f)["merge"]["missing"]:
                print(m["shard"], m["id"])
        return 0
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv))
