#!/usr/bin/python3
"""reports/bench_compare.py on synthetic Google Benchmark JSON pairs: identical files are the
same; 20 % slower with tight repetitions is slower; a noisy overlap is the same within noise;
--fail-on-slower sets the exit status. Run: /usr/bin/python3 tests/reports/test_bench_compare.py
(registered with CTest as bench_compare_py)."""

import json
import os
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPT = os.path.join(HERE, "..", "..", "reports", "bench_compare.py")
sys.path.insert(0, os.path.join(HERE, "..", "..", "reports"))

import bench_compare  # noqa: E402


def entries(name, times, unit="us", metric_key="cpu_time", manual=False):
    """Per-repetition entries plus the aggregates Google Benchmark 1.7.1 writes."""
    run_name = name + ("/iterations:1/manual_time" if manual else "")
    out = []
    for i, t in enumerate(times):
        e = {"name": run_name, "run_name": run_name, "run_type": "iteration",
             "repetitions": len(times), "repetition_index": i, "threads": 1, "iterations": 100,
             "real_time": t * (1.0 if manual else 1.3), "cpu_time": t, "time_unit": unit}
        if manual:  # manual time: real_time is the measured one, cpu_time unrelated
            e["cpu_time"] = t * 0.5
        out.append(e)
    med = sorted(times)[len(times) // 2]
    out.append({"name": run_name + "_median", "run_name": run_name, "run_type": "aggregate",
                "aggregate_name": "median", "real_time": med, "cpu_time": med,
                "time_unit": unit})
    return out


def document(benchmarks, commit="abc", **context):
    ctx = {"date": "2026-11-21T00:00:00+00:00", "num_cpus": 2,
           "machine": {"cpu_model": "AMD EPYC", "nproc": 2}, "git_commit": commit,
           "date_utc": "2026-11-21T00:00:00Z", "compiler": "g++ (Debian 12.2.0-14) 12.2.0"}
    ctx.update(context)
    return {"context": ctx, "benchmarks": benchmarks}


TIGHT = [100.0, 100.4, 99.7, 100.2, 99.9]          # ~0.3 % spread
NOISY = [100.0, 80.0, 125.0, 95.0, 110.0]          # ~15 % spread


class CompareTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()

    def tearDown(self):
        self.tmp.cleanup()

    def write(self, name, doc):
        path = os.path.join(self.tmp.name, name)
        with open(path, "w") as f:
            json.dump(doc, f)
        return path

    def run_script(self, *args):
        p = subprocess.run([sys.executable, SCRIPT, *args], capture_output=True, text=True)
        return p.returncode, p.stdout, p.stderr

    def verdict_line(self, out, name):
        lines = [l for l in out.splitlines() if l.startswith(name + " ")]
        self.assertEqual(len(lines), 1, out)
        return lines[0]

    def test_identical_files_are_the_same(self):
        doc = document(entries("k/a", TIGHT) + entries("k/b", NOISY) +
                       entries("scheme_run/x", [1.2, 1.25, 1.21], unit="s", manual=True))
        old = self.write("old.json", doc)
        new = self.write("new.json", doc)
        code, out, err = self.run_script(old, new, "--fail-on-slower", "0")
        self.assertEqual(code, 0, out + err)
        self.assertIn("3 compared: 0 faster, 0 slower, 3 same within noise", out)
        self.assertIn("1.000", self.verdict_line(out, "k/a"))

    def test_twenty_percent_slower_with_tight_repetitions_is_slower(self):
        old = self.write("old.json", document(entries("k/a", TIGHT) + entries("k/b", TIGHT)))
        new = self.write("new.json", document(
            entries("k/a", [1.2 * t for t in TIGHT]) + entries("k/b", [t / 1.2 for t in TIGHT])))
        code, out, err = self.run_script(old, new)
        self.assertEqual(code, 0, out + err)  # no --fail-on-slower: report only
        line = self.verdict_line(out, "k/a")
        self.assertTrue(line.endswith("slower"), line)
        self.assertIn("1.200", line)
        self.assertIn("100 us", line)
        self.assertIn("120 us", line)
        self.assertTrue(self.verdict_line(out, "k/b").endswith("faster"), out)

    def test_noisy_overlap_is_the_same_within_noise(self):
        # The medians differ by 10 %, but the repetitions spread by ~15 %: not beyond noise.
        old = self.write("old.json", document(entries("k/a", NOISY)))
        new = self.write("new.json", document(entries("k/a", [1.1 * t for t in NOISY])))
        code, out, err = self.run_script(old, new, "--fail-on-slower", "5")
        self.assertEqual(code, 0, out + err)
        self.assertTrue(self.verdict_line(out, "k/a").endswith("same within noise"), out)

    def test_small_tight_change_below_min_change_is_the_same(self):
        old = self.write("old.json", document(entries("k/a", TIGHT)))
        # 1.5 %: above the noise of these repetitions (3 x 0.44 % = 1.3 %), below min_change.
        new = self.write("new.json", document(entries("k/a", [1.015 * t for t in TIGHT])))
        code, out, _ = self.run_script(old, new)
        self.assertTrue(self.verdict_line(out, "k/a").endswith("same within noise"), out)
        code, out, _ = self.run_script(old, new, "--min-change", "0.5")
        self.assertTrue(self.verdict_line(out, "k/a").endswith("slower"), out)

    def test_fail_on_slower_exit_status(self):
        old = self.write("old.json", document(entries("k/a", TIGHT) + entries("k/b", TIGHT)))
        new = self.write("new.json", document(
            entries("k/a", [1.2 * t for t in TIGHT]) + entries("k/b", TIGHT)))
        code, out, err = self.run_script(old, new, "--fail-on-slower", "10")
        self.assertEqual(code, 1, out + err)
        self.assertIn("k/a is 20.0 % slower (limit 10 %)", err)
        code, out, err = self.run_script(old, new, "--fail-on-slower", "25")
        self.assertEqual(code, 0, out + err)
        # Faster never fails.
        code, out, err = self.run_script(new, old, "--fail-on-slower", "0")
        self.assertEqual(code, 0, out + err)

    def test_manual_time_benchmarks_use_real_time(self):
        # Whole runs report manual (real) time; their cpu_time is not the measured quantity.
        old = self.write("old.json", document(
            entries("scheme_run/x", [1.0, 1.01, 0.99, 1.0, 1.0], unit="s", manual=True)))
        newb = entries("scheme_run/x", [1.3, 1.31, 1.29, 1.3, 1.3], unit="s", manual=True)
        for e in newb:
            e["cpu_time"] = 0.5  # unchanged cpu_time must not hide the change
        new = self.write("new.json", document(newb))
        code, out, err = self.run_script(old, new)
        line = self.verdict_line(out, "scheme_run/x/iterations:1/manual_time")
        self.assertTrue(line.endswith("slower"), line)
        self.assertIn("1.300", line)

    def test_units_are_converted(self):
        old = self.write("old.json", document(entries("k/a", TIGHT, unit="us")))
        new = self.write("new.json", document(entries("k/a", [t * 1e3 for t in TIGHT], unit="ns")))
        code, out, _ = self.run_script(old, new)
        self.assertIn("1.000", self.verdict_line(out, "k/a"))
        self.assertTrue(self.verdict_line(out, "k/a").endswith("same within noise"))

    def test_few_repetitions_are_flagged(self):
        old = self.write("old.json", document(entries("k/a", [100.0])))
        new = self.write("new.json", document(entries("k/a", [150.0])))
        code, out, _ = self.run_script(old, new)
        self.assertIn("slower (few reps)", self.verdict_line(out, "k/a"))

    def test_benchmarks_in_one_file_only_are_listed(self):
        old = self.write("old.json", document(entries("k/a", TIGHT) + entries("k/gone", TIGHT)))
        new = self.write("new.json", document(entries("k/a", TIGHT) + entries("k/new", TIGHT)))
        code, out, _ = self.run_script(old, new)
        self.assertEqual(code, 0)
        self.assertIn("only in old (1): k/gone", out)
        self.assertIn("only in new (1): k/new", out)

    def test_bad_input(self):
        good = self.write("good.json", document(entries("k/a", TIGHT)))
        other = self.write("other.json", document(entries("k/z", TIGHT)))
        bad = os.path.join(self.tmp.name, "bad.json")
        with open(bad, "w") as f:
            f.write("{not json")
        self.assertEqual(self.run_script(good, bad)[0], 2)
        self.assertEqual(self.run_script(good, os.path.join(self.tmp.name, "missing.json"))[0], 2)
        self.assertEqual(self.run_script(good, other)[0], 2)  # nothing in common
        self.assertEqual(self.run_script(good)[0], 2)          # argparse: missing argument

    def test_judge_rule(self):
        import numpy as np
        tight = np.array(TIGHT)
        r = bench_compare.judge(tight, 1.2 * tight)
        self.assertEqual(r["verdict"], "slower")
        self.assertAlmostEqual(r["ratio"], 1.2)
        self.assertLess(r["noise"], 0.02)          # tight: the 2 % floor decides
        self.assertEqual(r["threshold"], 0.02)
        noisy = np.array(NOISY)
        r = bench_compare.judge(noisy, 1.1 * noisy)
        self.assertEqual(r["verdict"], "same within noise")
        self.assertGreater(r["noise"], 0.1)
        # One wild repetition does not make a tight benchmark noisy (median and MAD are robust).
        wild = np.array([100.0, 100.4, 99.7, 100.2, 400.0])
        r = bench_compare.judge(tight, wild)
        self.assertEqual(r["verdict"], "same within noise")
        self.assertLess(r["noise"], 0.03)


if __name__ == "__main__":
    unittest.main(verbosity=1)
