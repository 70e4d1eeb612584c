#!/usr/bin/python3
"""External schemes through the documented adapter interface (docs/peers.md).

    tests/harness/external/test_external_scheme.py RICOCHET

1. A toy external scheme (adapters/examples/rigid_body.py, the example of docs/peers.md: the
   stand-in for a user's solver) in a study of its own beside ricochet's semi-explicit scheme:
   `ricochet reproduce` runs both, measures both against the same reference, checks a gate on the
   toy's rows (a ratio gate among them, whose selector has its own `kind`) and draws a
   work-precision figure with a series per scheme, captioned with the cost it plots (CPU time),
   and a runs table; every summary's `final` has the probe's displacement.
2. Bad adapters (missing result.json, a truncated table, non-finite values, unknown columns, a
   crash, a signal, a timeout, a program that does not exist, a run that stops early): each is a
   failed run with one line on stderr naming what is wrong, exit 1, and no summary.json or
   history.csv; in a sweep, a failed run beside good ones, and the sweep goes on.
3. The case keys of [external] refused with one line naming the key.
4. A study whose [requires] names what the machine lacks is skipped, never passed.
5. An edited adapter reruns the runs of its external scheme, and only those.
"""
import csv
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import textwrap
import unittest

RICOCHET = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else "build/ricochet")

CASE = """name = "disk"
scheme = "semi_explicit"
plane = "stress"
mesh = "disk"
[meshes.disk]
generator = "disk"
radius = 0.05
center = [0.0, 0.05]
n = 3
[[bodies]]
name = "disk"
thickness = 0.01
velocity = [0.0, -2.0]
[bodies.material]
young = 1.0e7
poisson = 0.3
density = 1000.0
[[obstacles]]
name = "ground"
type = "line"
point = [0.0, 0.0]
normal = [0.0, 1.0]
[time]
end = 2.0e-2
dt = 2.0e-5
[output]
interval = 2.0e-4
[[output.probes]]
name = "P"
point = [0.0, 0.0]
"""

SWEEP = """name = "peers"
base = "disk.toml"
[reference]
set = { "time.dt" = 5.0e-6 }
[[group]]
name = "ours"
cross = { "time.dt" = [2.0e-5, 1.0e-5] }
[[group]]
name = "toy"
set = { scheme = "toy", "external.command" = ["{python}", "{adapters}/examples/rigid_body.py"] }
cross = { "time.dt" = [2.0e-5, 1.0e-5] }
"""

GATES = """[[gate]]
name = "every run finished"
kind = "count"
where = { status = "failed" }
max = 0
[[gate]]
name = "the toy bounces back at its impact speed"
kind = "near"
where = { scheme = "toy" }
column = "rebound_velocity_y"
reference = 2.0
rel_tolerance = 1e-9
[[gate]]
name = "the toy costs more than the semi-explicit scheme"
kind = "ratio"
column = "cpu_seconds"
numerator = { scheme = "toy", "time.dt" = 1e-5 }
denominator = { group = "ours", "time.dt" = 1e-5, kind = "run" }
floor = 1.0
"""

STUDY = """title = "A toy external scheme"
summary = "A stand-in external solver beside the semi-explicit scheme."
[[sweep]]
name = "peers"
file = "sweep.toml"
gates = "gates.toml"
[report]
[[report.section]]
kind = "work_precision"
sweep = "peers"
error = "error_probe_P"
cost = "cpu_seconds"
[[report.section]]
kind = "runs_table"
sweep = "peers"
columns = ["rebound_velocity_y", "cpu_seconds"]
"""


def run(args, cwd=None, timeout=300):
    return subprocess.run([RICOCHET] + args, capture_output=True, text=True, timeout=timeout, cwd=cwd)


def toml_value(v):
    return json.dumps(v)


class ToyStudy(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        root = pathlib.Path(cls.tmp.name)
        study = root / "studies" / "toy"
        study.mkdir(parents=True)
        for name, text in [("disk.toml", CASE), ("sweep.toml", SWEEP), ("gates.toml", GATES), ("study.toml", STUDY)]:
            (study / name).write_text(text)
        cls.out = root / "out"
        cls.r = run(["reproduce", "toy", "--studies", str(root / "studies"), "--tier", "fast", "--out", str(cls.out),
                     "--quiet"], cwd=root, timeout=600)

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def rows(self):
        with open(self.out / "toy" / "peers" / "summary.csv", newline="") as f:
            return list(csv.DictReader(f))

    def test_gates_pass_on_the_toys_rows(self):
        self.assertEqual(self.r.returncode, 0, self.r.stdout + self.r.stderr)
        sj = json.loads((self.out / "toy" / "study.json").read_text())
        results = {g["name"]: g["passed"] for g in sj["sweeps"][0]["gate_results"]}
        self.assertEqual(results, {"every run finished": True, "the toy bounces back at its impact speed": True,
                                   "the toy costs more than the semi-explicit scheme": True})
        # The page is drawn without an error: a ratio gate's selector with its own `kind` among them.
        self.assertNotIn("Traceback", self.r.stdout + self.r.stderr)

    def test_toy_rows_are_measured_against_the_same_reference(self):
        toy = [r for r in self.rows() if r["scheme"] == "toy"]
        ours = [r for r in self.rows() if r["summary.scheme"] == "semi_explicit" and r["kind"] == "run"]
        self.assertEqual((len(toy), len(ours)), (2, 2))
        for r in toy + ours:
            self.assertEqual(r["status"], "ok")
            self.assertEqual(r["reference_run"], ours[0]["reference_run"])
            self.assertNotEqual(r["error_probe_P"], "", r["run_id"])
        # The rigid toy never deforms: its probe error against an elastic disk is far larger.
        self.assertGreater(min(float(r["error_probe_P"]) for r in toy),
                           10 * max(float(r["error_probe_P"]) for r in ours))
        # A column the toy cannot fill is empty, not zero; ricochet's energy error is there.
        for r in toy:
            self.assertEqual(r["contact_force_max"], "")
            self.assertEqual(float(r["energy_error_max"]), 0.0)
            self.assertGreater(float(r["cpu_seconds"]), 0.0)

    def test_summaries_end_with_the_probes_displacement(self):
        for r in self.rows():
            if r["kind"] == "run":
                self.assertNotEqual(r["final.P_uy"], "", r["run_id"])
        toy = [r for r in self.rows() if r["scheme"] == "toy"]
        # The rigid toy bounces at once: P's last displacement is its rigid travel, up then.
        self.assertGreater(float(toy[0]["final.P_uy"]), 0.0)

    def test_work_precision_page_names_the_cost_it_plots(self):
        md = (self.out / "toy" / "report" / "report.md").read_text()
        self.assertIn("against (`cpu_seconds`;", md)
        self.assertIn("cpu_seconds (s): median", md)
        self.assertNotIn("wall time, time loop", md)

    def test_work_precision_figure_has_a_series_per_scheme(self):
        manifest = json.loads((self.out / "toy" / "report" / "manifest.json").read_text())
        figures = [s for s in manifest["sections"] if s["kind"] == "figure"]
        self.assertEqual(len(figures), 1, manifest)
        self.assertEqual(figures[0]["series"], {"semi-explicit": 2, "toy": 2})
        for f in figures[0]["files"]:
            self.assertGreater((self.out / "toy" / "report" / f).stat().st_size, 1000)


# Adapters that go wrong, as small Python programs: name -> (source, expected part of the reason).
GOOD_RESULT = ('{"format": "ricochet-external-result", "version": 1, "status": "ok", "steps": 1000, '
               '"dt": 2e-05}')


def history(rows, cols="time,kinetic_energy,total_energy"):
    return cols + "\n" + "\n".join(rows) + "\n"


FULL_ROWS = ["%r,1.0,1.0" % (k * 2e-4) for k in range(101)]

BAD = {
    "no_result": ("pass", "result.json: missing"),
    "truncated": (f"write('result.json', {GOOD_RESULT!r}); write('history.csv', {history(['0,1,1', '0.0002,1'])!r})",
                  "history.csv:3"),
    "non_finite": (f"write('result.json', {GOOD_RESULT!r}); write('history.csv', {history(['0,1,1', '0.0002,nan,1'])!r})",
                   "kinetic_energy: expected a finite number"),
    "unknown_column": (f"write('result.json', {GOOD_RESULT!r}); write('history.csv', {history(['0,1'], 'time,speed')!r})",
                       "unknown column \"speed\""),
    "energy_error_given": (f"write('result.json', {GOOD_RESULT!r}); write('history.csv', {history(['0,1'], 'time,energy_error')!r})",
                           "energy_error is computed by ricochet"),
    "stops_early": (f"write('result.json', {GOOD_RESULT!r}); write('history.csv', {history(FULL_ROWS[:50])!r})",
                    "not time.end"),
    "bad_json": ("write('result.json', '{\"format\": ')", "result.json"),
    "bad_status": ("write('result.json', '{\"format\": \"ricochet-external-result\", \"version\": 1, \"status\": \"fine\", "
                   "\"steps\": 1, \"dt\": 1e-5}')", "status: expected"),
    "crash": ("import sys; print('reading job.inp', file=sys.stderr); "
              "print('ccx: *ERROR in e_c3d: nonpositive jacobian', file=sys.stderr); sys.exit(1)",
              "adapter exit 1: ccx: *ERROR in e_c3d: nonpositive jacobian"),
    "signal": ("import os, signal; os.kill(os.getpid(), signal.SIGSEGV)", "killed by signal 11"),
    "traceback": ("raise RuntimeError('mesh has no cells')", "adapter exit 1: RuntimeError: mesh has no cells"),
    "timeout": ("import time; print('step 1'); time.sleep(60)", "timed out after 1 s"),
}
PRELUDE = "def write(name, text):\n    open(name, 'w').write(text)\n"


class BadAdapters(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        cls.root = pathlib.Path(cls.tmp.name)
        (cls.root / "disk.toml").write_text(CASE)
        for name, (body, _) in BAD.items():
            (cls.root / f"bad_{name}.py").write_text(PRELUDE + body + "\n")

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def run_bad(self, name, extra=()):
        out = self.root / f"out_{name}"
        args = ["run", str(self.root / "disk.toml"), "--quiet", "--out", str(out), "--set", f"scheme={name}",
                "--set", f'external.command=["{{python}}", "{{case_dir}}/bad_{name}.py"]',
                "--set", "external.timeout=1"] + list(extra)
        return run(args), out

    def test_each_is_a_failed_run_with_one_line(self):
        for name, (_, expected) in BAD.items():
            with self.subTest(adapter=name):
                r, out = self.run_bad(name)
                self.assertEqual(r.returncode, 1, r.stderr)
                lines = r.stderr.strip().splitlines()
                self.assertEqual(len(lines), 1, r.stderr)
                self.assertIn(f"external scheme '{name}'", lines[0])
                self.assertIn(expected, lines[0])
                self.assertFalse((out / "summary.json").exists())
                self.assertFalse((out / "history.csv").exists())
                self.assertTrue((out / "external" / "case.json").exists())

    def test_a_program_that_does_not_exist(self):
        out = self.root / "out_missing"
        r = run(["run", str(self.root / "disk.toml"), "--quiet", "--out", str(out), "--set", "scheme=mine",
                 "--set", 'external.command=["no-such-solver-xyz"]'])
        self.assertEqual(r.returncode, 1, r.stderr)
        self.assertIn("cannot run 'no-such-solver-xyz'", r.stderr)
        self.assertFalse((out / "summary.json").exists())

    def test_a_sweep_records_the_failure_and_goes_on(self):
        sweep = self.root / "sweep.toml"
        sweep.write_text(textwrap.dedent("""\
            name = "mixed"
            base = "disk.toml"
            [[group]]
            name = "toy"
            set = { scheme = "toy", "external.command" = ["{python}", "{adapters}/examples/rigid_body.py"] }
            [[group]]
            name = "crash"
            set = { scheme = "crash", "external.command" = ["{python}", "{case_dir}/bad_crash.py"] }
            """))
        out = self.root / "sweep_out"
        r = run(["sweep", str(sweep), "--out", str(out), "--quiet"])
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)  # failed runs are results (docs/sweeps.md)
        with open(out / "summary.csv", newline="") as f:
            rows = list(csv.DictReader(f))
        self.assertEqual(sorted(r["status"] for r in rows), ["failed", "ok"])
        failed = [r for r in rows if r["status"] == "failed"][0]
        self.assertIn("nonpositive jacobian", failed["reason"])


class AdapterIdentity(unittest.TestCase):
    def test_an_edited_adapter_reruns_its_runs_and_only_them(self):
        with tempfile.TemporaryDirectory() as d:
            root = pathlib.Path(d)
            (root / "disk.toml").write_text(CASE)
            toy = root / "toy.py"
            toy.write_text((pathlib.Path(__file__).resolve().parents[3] / "adapters" / "examples" / "rigid_body.py").read_text())
            (root / "sweep.toml").write_text(textwrap.dedent("""\
                name = "identity"
                base = "disk.toml"
                [[group]]
                name = "ours"
                [[group]]
                name = "toy"
                set = { scheme = "toy", "external.command" = ["{python}", "{case_dir}/toy.py"] }
                """))

            def sweep():
                r = run(["sweep", str(root / "sweep.toml"), "--out", str(root / "out")])
                self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
                return r.stdout + r.stderr

            self.assertIn("2 runs, 0 done before, 2 to run", sweep())
            self.assertIn("2 runs, 2 done before, 0 to run", sweep())
            toy.write_text(toy.read_text() + "\n# edited\n")
            self.assertIn("2 runs, 1 done before, 1 to run", sweep())


class MissingRequirement(unittest.TestCase):
    def test_a_study_that_needs_a_missing_code_is_skipped(self):
        with tempfile.TemporaryDirectory() as d:
            root = pathlib.Path(d)
            study = root / "studies" / "needs"
            study.mkdir(parents=True)
            (study / "disk.toml").write_text(CASE)
            (study / "sweep.toml").write_text('base = "disk.toml"\n[[group]]\nname = "one"\n')
            (study / "study.toml").write_text(
                'title = "Needs a code"\nsummary = "Runs only where the code is."\n'
                '[requires]\nprograms = ["no-such-solver-xyz"]\npython_modules = ["no_such_module_xyz"]\n'
                '[[sweep]]\nname = "one"\nfile = "sweep.toml"\n')
            out = root / "out"
            r = run(["reproduce", "needs", "--studies", str(root / "studies"), "--tier", "fast", "--out", str(out)])
            self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
            self.assertIn("study needs: skipped (missing program no-such-solver-xyz, Python module no_such_module_xyz",
                          r.stdout)
            self.assertIn("0 passed, 0 gates failed, 0 failed, 1 skipped", r.stdout)
            sj = json.loads((out / "needs" / "study.json").read_text())
            self.assertEqual(sj["status"], "skipped")
            self.assertEqual(sj["sweeps"], [])
            self.assertFalse((out / "needs" / "one").exists())
            index = (out / "index.html").read_text()
            self.assertIn("skipped", index)
            self.assertIn("no-such-solver-xyz", index)


class CaseKeys(unittest.TestCase):
    def check(self, sets, expected):
        with tempfile.TemporaryDirectory() as d:
            case = pathlib.Path(d) / "disk.toml"
            case.write_text(CASE)
            args = ["run", str(case), "--quiet", "--out", str(pathlib.Path(d) / "out")]
            for s in sets:
                args += ["--set", s]
            r = run(args)
            self.assertEqual(r.returncode, 2, r.stderr)
            self.assertEqual(len(r.stderr.strip().splitlines()), 1, r.stderr)
            self.assertIn(expected, r.stderr)
            self.assertFalse((pathlib.Path(d) / "out").exists())

    def test_refusals(self):
        cmd = 'external.command=["{python}", "x.py"]'
        self.check(["scheme=implicitt"], "scheme: \"implicitt\" is not one of ricochet's schemes (did you mean \"implicit\"?)")
        self.check(["external.adapter=calculix"], "external: applies to external schemes")
        self.check(["scheme=mine", "external.adapter=calculx"], "no shipped adapter \"calculx\"")
        self.check(["scheme=mine", "external.adapter=calculix", cmd], "external.command: give either")
        self.check(["scheme=mine", "external.timeout=10"], "external.adapter: missing")
        self.check(["scheme=my solver", cmd], "an external scheme's name has letters")
        self.check(["scheme=mine", 'external.command=["{pyton}"]'], "unknown placeholder \"{pyton}\"")
        self.check(["scheme=mine", cmd, "external.timeout=0"], "external.timeout")
        self.check(["scheme=mine", cmd, "external.option={}"], "external.option: unknown key")
        self.check(["scheme=mine", cmd, "external.options.k=inf"], "non-finite")


if __name__ == "__main__":
    unittest.main(argv=sys.argv[:1])
