#!/usr/bin/python3
"""The M1 plate through CalculiX and GetFEM, judged against ricochet's own runs (docs/peers.md,
"The peers study").

    tests/cases/test_peers_m1.py RICOCHET OUT

Runs the peers study's fast tier (`ricochet reproduce peers --tier fast --out OUT`: the runs
that `ci/test` made there before CTest are reused, so this costs seconds after it, about a
minute alone) and checks that every gate of cases/peers/m1_gates.toml was evaluated and passed:
the external runs complete, start with ricochet's energy, CalculiX with ricochet's penalty
springs rebounds within 0.5 % of ricochet's penalty scheme, GetFEM within 0.5 % of the
semi-explicit scheme, energy errors below 2 %, and the semi-explicit scheme at least as
accurate at lower cost. Where CalculiX or GetFEM is missing the study is skipped, and so is
this test (exit 77, CTest's "skipped"), never passed.
"""
import json
import pathlib
import re
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]


def main():
    ricochet, out = sys.argv[1], pathlib.Path(sys.argv[2])
    # From the checkout's root, as ci/test runs it: a run's identity holds its case file's path
    # as the studies folder gives it (relative to the working folder), so the same folder reuses.
    r = subprocess.run([ricochet, "reproduce", "peers", "--tier", "fast", "--out", str(out.resolve()), "--quiet",
                        "--no-report"], capture_output=True, text=True, timeout=1800, cwd=ROOT)
    if "study peers: skipped" in r.stdout:
        print(r.stdout.strip())
        return 77
    sj = json.loads((out / "peers" / "study.json").read_text())
    assert r.returncode == 0 and sj["status"] == "passed", (r.returncode, sj.get("status"), sj.get("reason"), r.stdout, r.stderr)
    expected = re.findall(r'^name = "(.*)"$', (ROOT / "cases" / "peers" / "m1_gates.toml").read_text(), re.M)
    expected = [n for n in expected if n != "peers_m1"]
    results = {g["name"]: g["passed"] for s in sj["sweeps"] for g in s["gate_results"]}
    assert set(expected) <= set(results), sorted(set(expected) - set(results))
    assert len(expected) >= 10, expected
    failed = [n for n in expected if not results[n]]
    assert not failed, failed
    print(f"peers m1: {len(expected)} gates passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
