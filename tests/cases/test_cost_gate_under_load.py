#!/usr/bin/python3
"""The paper study's cost gate holds on a shared machine.

    tests/cases/test_cost_gate_under_load.py RICOCHET

Runs the cells of the paper study's Table 1 sweep that its cost gate compares (the `ratio` gates
of cases/paper/gates.toml, on `cpu_seconds`) as a sweep, with one busy process per core beside
it, and checks that gate on the result: the runs get one thread each (a sweep's default) and the
gate compares their CPU times, which do not count the time the busy processes held the core.
With wall times and two spinning threads per run this gate failed at a ratio of 0.71 against a
floor of 5 (docs/performance.md, Threads on a shared machine).
"""
import csv
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import tomllib

ROOT = pathlib.Path(__file__).resolve().parents[2]
STUDY = ROOT / "cases" / "paper"


def toml_value(v):
    """A TOML literal of `v` (strings, numbers, booleans, lists and tables of them)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    return "{ " + ", ".join(f"{json.dumps(k)} = {toml_value(x)}" for k, x in v.items()) + " }"


def main():
    ricochet = sys.argv[1]
    gates = [g for g in tomllib.loads((STUDY / "gates.toml").read_text())["gate"]
             if g["kind"] == "ratio" and g["column"] == "cpu_seconds"]
    assert gates, "the paper study has no cost gate on cpu_seconds"
    sweep = tomllib.loads((STUDY / "table1.toml").read_text())
    failed = 0
    for gate in gates:
        where = gate["where"]
        group = next(g for g in sweep["group"] if g["name"] == where["group"])
        # The gate's cells: the group with its crossed keys pinned to the gate's `where`, and to
        # the numerator's and denominator's values of the keys that tell the two apart.
        sides = (gate["numerator"], gate["denominator"])
        cross = {}
        for k, v in group.get("cross", {}).items():
            if k in where:
                cross[k] = [where[k]]
            elif any(k in s for s in sides):
                cross[k] = [x for x in v if any(s.get(k) == x for s in sides)]
            else:
                cross[k] = v
        with tempfile.TemporaryDirectory() as tmp:
            tmp = pathlib.Path(tmp)
            lines = [f'name = "cost_under_load"', f'base = {toml_value(str(STUDY / sweep["base"]))}']
            if "set" in sweep:
                lines.append(f"set = {toml_value(sweep['set'])}")
            lines += ["[[group]]", f'name = {toml_value(group["name"])}']
            if "set" in group:
                lines.append(f"set = {toml_value(group['set'])}")
            lines.append(f"cross = {toml_value(cross)}")
            (tmp / "sweep.toml").write_text("\n".join(lines) + "\n")
            (tmp / "gates.toml").write_text(
                "[[gate]]\n" + "".join(f"{k} = {toml_value(v)}\n" for k, v in gate.items()))
            busy = [subprocess.Popen([sys.executable, "-c", "while True: pass"])
                    for _ in range(os.cpu_count() or 2)]
            try:
                r = subprocess.run([ricochet, "sweep", str(tmp / "sweep.toml"), "--out", str(tmp / "out"),
                                    "--quiet", "--check", str(tmp / "gates.toml")],
                                   capture_output=True, text=True, timeout=600)
            finally:
                for p in busy:
                    p.kill()
                    p.wait()
            rows = list(csv.DictReader(open(tmp / "out" / "summary.csv")))
            print(f"{gate['name']}: exit {r.returncode}")
            print(r.stdout.strip())
            for row in rows:
                print(f"  {row['run_id']}: cpu {row['cpu_seconds']} s, wall {row['wall_seconds']} s, threads {row['threads']}")
            ok = r.returncode == 0 and len(rows) >= 2 and all(row["threads"] == "1" for row in rows)
            if not ok:
                print(r.stderr.strip())
                failed += 1
    print(f"{len(gates) - failed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
