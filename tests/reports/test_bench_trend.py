#!/usr/bin/python3
"""reports/bench_trend.py on a synthetic history of three commits: the benchmark with a planted
slowdown at the third commit is the only regression, named with that commit; a benchmark that
moves within its noise and one that got faster are not regressions; a fourth file from another
machine is not compared with the others; bad input fails with one line naming the file and
leaves the previous page. Run: /usr/bin/python3 tests/reports/test_bench_trend.py (registered with
CTest as bench_trend_py)."""

import html.parser
import json
import os
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPT = os.path.join(HERE, "..", "..", "reports", "bench_trend.py")

COMMITS = ["1111111aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
           "2222222bbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbbb",
           "3333333ccccccccccccccccccccccccccccccccc"]
TIGHT = [100.0, 100.4, 99.7, 100.2, 99.9]          # ~0.3 % spread
NOISY = [100.0, 80.0, 125.0, 95.0, 110.0]          # ~15 % spread


def entries(name, times, unit="us", manual=False, rate=False):
    """Per-repetition entries plus the median aggregate, as Google Benchmark 1.7.1 writes."""
    run_name = name + ("/iterations:1/manual_time" if manual else "")
    out = []
    for i, t in enumerate(times):
        e = {"name": run_name, "run_name": run_name, "run_type": "iteration",
             "repetitions": len(times), "repetition_index": i, "threads": 1, "iterations": 100,
             "real_time": t if manual else 1.3 * t, "cpu_time": 0.5 * t if manual else t,
             "time_unit": unit}
        if rate:
            e["element_steps_per_second"] = 1e9 / t
        out.append(e)
    med = sorted(times)[len(times) // 2]
    out.append({"name": run_name + "_median", "run_name": run_name, "run_type": "aggregate",
                "aggregate_name": "median", "real_time": med, "cpu_time": med,
                "time_unit": unit})
    return out


def document(commit, commit_date, benchmarks, cpu_model="AMD EPYC 7B13"):
    """A result file with the context keys ci/bench writes."""
    ctx = {"date": commit_date.replace("Z", "+00:00"), "host_name": "bench", "num_cpus": 2,
           "machine": {"cpu_model": cpu_model, "cpu_flags": ["avx2", "fma"], "nproc": 2,
                       "memory_bytes": 8 << 30, "kernel": "6.1.0", "load_avg_after": [1, 1, 1]},
           "compiler": "g++ (Debian 12.2.0-14) 12.2.0",
           "build": {"dir": "build", "type": "Release", "native": "ON",
                     "compiler_path": "/usr/bin/x86_64-linux-gnu-g++-12"},
           "git_commit": commit, "git_commit_date_utc": commit_date,
           "date_utc": "2026-11-26T06:00:00Z",  # one run date: the commit date must order them
           "ci_bench": {"quick": True, "repetitions": 5, "filter": "", "arguments": ""}}
    return {"context": ctx, "benchmarks": benchmarks}


def suite(planted, steady, improved):
    """The three benchmarks of every synthetic commit, each scaled by the factor given."""
    return (entries("k/planted", [planted * t for t in TIGHT]) +
            entries("k/steady", [steady * t for t in NOISY]) +
            entries("scheme_run/improved", [improved * t / 100 for t in TIGHT], unit="s",
                    manual=True, rate=True))


class TableParser(html.parser.HTMLParser):
    """The text of every cell of the tables of a page, by table id: {id: [[cell, ...], ...]}."""

    def __init__(self):
        super().__init__()
        self.tables, self.images = {}, []
        self.table = self.row = self.cell = None

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if tag == "table" and attrs.get("id"):
            self.table = self.tables.setdefault(attrs["id"], [])
        elif tag == "tr" and self.table is not None:
            self.row = []
        elif tag == "td" and self.row is not None:
            self.cell = []
        elif tag == "img":
            self.images.append(attrs["src"])

    def handle_endtag(self, tag):
        if tag == "table":
            self.table = None
        elif tag == "tr" and self.row is not None:
            if self.row:
                self.table.append(self.row)
            self.row = None
        elif tag == "td" and self.cell is not None:
            self.row.append("".join(self.cell).strip())
            self.cell = None

    def handle_data(self, data):
        if self.cell is not None:
            self.cell.append(data)


class TrendTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.history = os.path.join(self.tmp.name, "history")
        os.mkdir(self.history)
        # File names in the opposite order to the commits: the dates must order them.
        self.write("c-first.json", document(COMMITS[0], "2026-11-20T10:00:00Z",
                                            suite(1.0, 1.0, 1.0)))
        self.write("b-second.json", document(COMMITS[1], "2026-11-21T10:00:00Z",
                                             suite(1.0, 1.0, 0.7)))        # improvement
        self.write("a-third.json", document(COMMITS[2], "2026-11-22T10:00:00Z",
                                            suite(1.3, 1.06, 0.7)))        # planted slowdown

    def tearDown(self):
        self.tmp.cleanup()

    def write(self, name, doc, folder=None):
        path = os.path.join(folder or self.history, name)
        with open(path, "w") as f:
            json.dump(doc, f)
        return path

    def run_script(self, *args):
        p = subprocess.run([sys.executable, SCRIPT, *args], capture_output=True, text=True)
        return p.returncode, p.stdout, p.stderr

    def page(self, folder=None):
        parser = TableParser()
        with open(os.path.join(folder or self.history, "index.html")) as f:
            parser.feed(f.read())
        return parser

    def test_the_planted_regression_is_flagged_with_its_commit(self):
        code, out, err = self.run_script(self.history)
        self.assertEqual(code, 0, out + err)
        page = self.page()
        rows = page.tables.get("regressions", [])
        self.assertEqual(len(rows), 1, rows)
        benchmark, before, after, ratio = rows[0][:4]
        self.assertEqual(benchmark, "k/planted")
        self.assertEqual(before, COMMITS[1][:7])
        self.assertEqual(after, COMMITS[2][:7])
        self.assertAlmostEqual(float(ratio), 1.3, places=3)
        self.assertIn("1 regressions beyond noise", out)
        self.assertIn("k/planted: x1.300 at 3333333", out)

    def test_noise_and_improvements_are_not_regressions(self):
        self.assertEqual(self.run_script(self.history)[0], 0)
        page = self.page()
        flagged = [r[0] for r in page.tables.get("regressions", [])]
        self.assertNotIn("k/steady", flagged)
        self.assertNotIn("scheme_run/improved/iterations:1/manual_time", flagged)
        improvements = page.tables.get("improvements", [])
        self.assertEqual([(r[0], r[2]) for r in improvements],
                         [("scheme_run/improved/iterations:1/manual_time", COMMITS[1][:7])])

    def test_page_lists_commits_in_date_order_and_has_a_plot_per_benchmark(self):
        self.assertEqual(self.run_script(self.history)[0], 0)
        page = self.page()
        commits = [row[1] for row in page.tables["commits"]]
        self.assertEqual(commits, [c[:7] for c in COMMITS])
        self.assertTrue(all("AMD EPYC 7B13" in row[4] for row in page.tables["commits"]))
        self.assertTrue(all("g++" in row[5] for row in page.tables["commits"]))
        self.assertEqual(len(page.images), 3)
        for src in page.images:
            self.assertTrue(os.path.getsize(os.path.join(self.history, src)) > 1000, src)

    def test_another_machine_is_not_compared(self):
        # Twice as slow on another CPU, a day later: its own series, not a regression.
        doc = document("4444444ddddddddddddddddddddddddddddddddd", "2026-11-23T10:00:00Z",
                       suite(2.6, 2.0, 1.4), cpu_model="Intel Xeon E5-2690")
        self.write("d-other-machine.json", doc)
        code, out, err = self.run_script(self.history)
        self.assertEqual(code, 0, out + err)
        page = self.page()
        regressions = page.tables.get("regressions", [])
        self.assertEqual([(r[0], r[1]) for r in regressions],
                         [("k/planted", "AMD EPYC 7B13, 2 cpus")])
        self.assertEqual(regressions[0][3], COMMITS[2][:7])

    def test_out_folder(self):
        out_dir = os.path.join(self.tmp.name, "page")
        code, out, err = self.run_script(self.history, "--out", out_dir)
        self.assertEqual(code, 0, out + err)
        self.assertEqual(len(self.page(out_dir).tables["regressions"]), 1)
        self.assertFalse(os.path.exists(os.path.join(self.history, "index.html")))

    def assert_fails_cleanly(self, folder, named):
        code, out, err = self.run_script(folder)
        self.assertEqual(code, 2, out + err)
        self.assertEqual(len(err.strip().splitlines()), 1, err)
        self.assertIn(named, err)

    def test_bad_input_fails_cleanly_and_keeps_the_previous_page(self):
        self.assertEqual(self.run_script(self.history)[0], 0)
        with open(os.path.join(self.history, "index.html")) as f:
            previous = f.read()
        bad = os.path.join(self.history, "e-bad.json")
        with open(bad, "w") as f:
            f.write("{not json")
        self.assert_fails_cleanly(self.history, bad)
        with open(os.path.join(self.history, "index.html")) as f:
            self.assertEqual(f.read(), previous)
        self.assertEqual([n for n in os.listdir(self.history) if n.startswith(".")], [])

    def test_a_file_that_is_not_a_ci_bench_result_is_named(self):
        doc = document(COMMITS[0], "2026-11-20T10:00:00Z", suite(1.0, 1.0, 1.0))
        del doc["context"]["git_commit"]
        self.assert_fails_cleanly(self.history, self.write("no-commit.json", doc))

    def test_empty_or_missing_folder(self):
        empty = os.path.join(self.tmp.name, "empty")
        os.mkdir(empty)
        self.assert_fails_cleanly(empty, empty)
        self.assertFalse(os.path.exists(os.path.join(empty, "index.html")))
        self.assert_fails_cleanly(os.path.join(self.tmp.name, "missing"), "missing")


if __name__ == "__main__":
    unittest.main(verbosity=1)
