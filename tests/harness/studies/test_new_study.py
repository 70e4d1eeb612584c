#!/usr/bin/python3
"""A user's own study, from nothing, through the same command as the shipped ones.

    tests/harness/studies/test_new_study.py RICOCHET

Writes a study folder in a temporary folder (docs/studies.md): a small 2D case (an elastic disk
striking a plane obliquely), a 2 x 2 sweep of the friction coefficient x scheme, one gate, and a
layout asking for the runs table and for the tangential rebound velocity against friction, one
line per scheme. Runs it with `ricochet reproduce --studies DIR`, then checks the gate verdict
in study.json, that the runs table has a friction column, that the figure exists with two lines
(manifest.json), that no other study's section appears, and that a second run reuses every run.
"""
import csv
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import unittest

RICOCHET = sys.argv[1] if len(sys.argv) > 1 else "build/ricochet"

CASE = """name = "disk"
scheme = "semi_explicit"
plane = "stress"
mesh = "disk"
[meshes.disk]
generator = "disk"
radius = 0.05
center = [0.0, 0.05]
n = 4
[[bodies]]
name = "disk"
thickness = 0.01
velocity = [3.0, -2.0]
[bodies.material]
young = 1.0e8
poisson = 0.3
density = 1000.0
[[obstacles]]
name = "ground"
type = "line"
point = [0.0, 0.0]
normal = [0.0, 1.0]
friction = 0.0
[time]
end = 2.0e-3
dt = "auto"
[output]
interval = 1.0e-4
"""

SWEEP = """name = "friction_scheme"
base = "disk.toml"
[[group]]
name = "grid"
cross = { "obstacles[0].friction" = [0.0, 0.4], scheme = ["semi_explicit", "explicit_penalty"] }
"""

GATES = """[[gate]]
name = "energy error below 5 %"
kind = "max"
column = "energy_error_max"
limit = 0.05
"""

STUDY = """title = "Friction against rebound"
summary = "The disk's tangential rebound velocity against the friction coefficient, two schemes."

[[sweep]]
name = "grid"
file = "sweep.toml"
gates = "gates.toml"

[report]
[[report.section]]
kind = "runs_table"
sweep = "grid"
columns = ["rebound_velocity_x", "friction_dissipation"]

[[report.section]]
kind = "metric"
sweep = "grid"
x = "obstacles[0].friction"
y = "rebound_velocity_x"
by = "scheme"
"""


class NewStudy(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        root = pathlib.Path(cls.tmp.name)
        cls.studies = root / "studies"
        study = cls.studies / "mystudy"
        study.mkdir(parents=True)
        for name, text in [("disk.toml", CASE), ("sweep.toml", SWEEP), ("gates.toml", GATES),
                           ("study.toml", STUDY)]:
            (study / name).write_text(text)
        cls.out = root / "out"
        cls.first = cls.reproduce()
        cls.second = cls.reproduce()

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    @classmethod
    def reproduce(cls):
        # From the folder above the studies, as ci/test runs from the checkout above cases/.
        r = subprocess.run([os.path.abspath(RICOCHET), "reproduce", "mystudy", "--studies", str(cls.studies),
                            "--tier", "fast", "--out", str(cls.out), "--quiet"],
                           capture_output=True, text=True, timeout=600, cwd=cls.studies.parent)
        study_json = json.loads((cls.out / "mystudy" / "study.json").read_text())
        return r, study_json

    def test_gate_verdict(self):
        r, sj = self.first
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        self.assertEqual(sj["status"], "passed")
        results = sj["sweeps"][0]["gate_results"]
        self.assertEqual([g["name"] for g in results], ["energy error below 5 %"])
        self.assertTrue(results[0]["passed"])
        self.assertEqual(sj["sweeps"][0]["runs"], 4)

    def manifest(self):
        return json.loads((self.out / "mystudy" / "report" / "manifest.json").read_text())

    def test_runs_table_has_the_friction_column(self):
        md = (self.out / "mystudy" / "report" / "report.md").read_text()
        headers = [line for line in md.splitlines() if line.startswith("|") and "run" in line]
        self.assertTrue(any("obstacles[0].friction" in h and "scheme" in h and "rebound_velocity_x" in h
                            for h in headers), "\n".join(headers))

    def test_figure_with_a_line_per_scheme(self):
        figures = [s for s in self.manifest()["sections"] if s["kind"] == "figure"]
        self.assertEqual(len(figures), 1)
        fig = figures[0]
        self.assertTrue(fig["available"], fig)
        self.assertEqual(fig["series"], {"semi_explicit": 2, "explicit_penalty": 2})
        for f in fig["files"]:
            path = self.out / "mystudy" / "report" / f
            self.assertGreater(path.stat().st_size, 1000, path)

    def test_only_this_studys_sections(self):
        sections = self.manifest()["sections"]
        self.assertTrue(sections)
        for s in sections:
            self.assertIsNone(s["reproduces"], s["title"])
            for src in s["sources"]:
                self.assertTrue(str(src).endswith("grid"), (s["title"], src))
        index = (self.out / "index.html").read_text()
        self.assertIn("Friction against rebound", index)
        self.assertNotIn("Cros, Feng", index)

    def test_case_paths_as_ricochet_sweep_names_them(self):
        # summary.csv's case_file is the path `ricochet sweep studies/mystudy/sweep.toml` run from the
        # same folder records, so a study's sweep and the same sweep run by hand (or through Slurm)
        # compare cell for cell.
        with open(self.out / "mystudy" / "grid" / "summary.csv", newline="") as f:
            rows = list(csv.DictReader(f))
        self.assertEqual(len(rows), 4)
        self.assertEqual({row["case_file"] for row in rows}, {"studies/mystudy/disk.toml"})

    def test_second_run_reuses_every_run(self):
        r, sj = self.second
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        sweep = sj["sweeps"][0]
        self.assertEqual((sweep["reused"], sweep["run_now"]), (4, 0))


if __name__ == "__main__":
    unittest.main(argv=sys.argv[:1])
