#!/usr/bin/python3
"""cases/long_runs/drift.py on synthetic long-run sweeps: the energy residual closes the balance
with the contact's work (bi-potential) or the springs' energy (penalty); a planted linear drift
comes out as its slope per 1e5 steps; the ball's apexes are counted per flight, not per
vibration; the blocks' creep; a failed run gives an empty row; a missing summary.csv is a
one-line error with exit 2. Run: /usr/bin/python3 tests/cases/test_long_runs.py (registered with CTest
as long_runs_py)."""

import csv
import json
import math
import os
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPT = os.path.join(HERE, "..", "..", "cases", "long_runs", "drift.py")
sys.path.insert(0, os.path.join(HERE, "..", "..", "cases", "long_runs"))

import drift as long_runs  # noqa: E402

HEAD = ["time", "kinetic_energy", "strain_energy", "total_energy", "external_work",
        "friction_dissipation", "energy_error", "contact_work_normal", "contact_energy",
        "contact_nodes", "centre_ux", "centre_uy"]


def write_run(root, run_id, rows, summary):
    d = os.path.join(root, "runs", run_id)
    os.makedirs(d)
    with open(os.path.join(d, "history.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(HEAD)
        for r in rows:
            w.writerow([r.get(k, 0.0) for k in HEAD])
    with open(os.path.join(d, "summary.json"), "w") as f:
        json.dump(summary, f)


def write_sweep(root, runs):
    with open(os.path.join(root, "summary.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["run_id", "group", "kind", "status", "scheme"])
        for run_id, group, status, scheme in runs:
            w.writerow([run_id, group, "run", status, scheme])


def summary(steps, dt, **kw):
    s = {"steps": steps, "dt": dt, "energy_error_max": 0.5, "penetration_max": 1e-18,
         "contact_iterations": {"status_changes": 2 * steps, "status_change_steps": steps // 2,
                                "steps_with_contact": steps}}
    s.update(kw)
    return s


class LongRuns(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.root = self.tmp.name

    def tearDown(self):
        self.tmp.cleanup()

    def read(self):
        with open(os.path.join(self.root, "drift.csv"), newline="") as f:
            return {r["run_id"]: r for r in csv.DictReader(f)}

    def test_residual_excludes_contact_losses_and_measures_the_drift(self):
        dt, steps = 1e-3, 1000
        e0 = 2.0
        # Bi-potential block: the contact takes 1.5 J out (contact_work_normal), which the
        # paper's energy error counts, and the integrator loses 2e-6 J per step: a residual
        # slope of 2e-6 / E0 = 1e-6 per step, -0.1 per 1e5 steps, and |R| = 2e-3 J / E0 at the end.
        rows = []
        for n in range(0, steps + 1, 10):
            wcn = -1.5 * min(1.0, n / 100)
            drift = -2e-6 * n
            rows.append({"time": n * dt, "total_energy": e0 + wcn + drift, "contact_work_normal": wcn,
                         "centre_ux": 0.0, "centre_uy": 0.0, "contact_nodes": 3})
        write_run(self.root, "block_resting/000", rows, summary(steps, dt))
        # Penalty: 0.5 J held in the springs, no drift.
        rows = [{"time": n * dt, "total_energy": e0 - 0.5 * min(1.0, n / 100),
                 "contact_energy": 0.5 * min(1.0, n / 100)} for n in range(0, steps + 1, 10)]
        write_run(self.root, "block_resting/001", rows, summary(steps, dt))
        write_sweep(self.root, [("block_resting/000", "block_resting", "ok", "semi_explicit"),
                                ("block_resting/001", "block_resting", "ok", "explicit_penalty"),
                                ("block_resting/002", "block_resting", "failed", "implicit")])
        long_runs.main([self.root])
        t = self.read()
        self.assertAlmostEqual(float(t["block_resting/000"]["energy_drift_per_1e5_steps"]), -0.1, places=9)
        self.assertAlmostEqual(float(t["block_resting/000"]["residual_max"]), 1e-3, places=12)
        self.assertAlmostEqual(float(t["block_resting/001"]["energy_drift_per_1e5_steps"]), 0.0, places=12)
        self.assertLess(float(t["block_resting/001"]["residual_max"]), 1e-15)  # round-off of the sums
        self.assertEqual(float(t["block_resting/000"]["status_changes_per_step"]), 2.0)
        self.assertEqual(t["block_resting/002"]["status"], "failed")
        self.assertEqual(t["block_resting/002"]["energy_drift_per_1e5_steps"], "")

    def test_ball_apexes_are_counted_per_flight(self):
        dt = 1e-3
        rows, t = [], 0.0
        g, rest = 9.81, -0.05
        heights = [0.05, 0.04, 0.032]  # e = sqrt(0.8)
        n = 0
        # Each flight is a parabola from the ground up to h and back; during each contact the
        # centre vibrates (two local maxima that are not apexes).
        for h in heights:
            v = math.sqrt(2 * g * h)
            tf = 2 * v / g
            for k in range(int(tf / dt)):
                tau = k * dt
                rows.append({"time": n * dt, "centre_uy": rest + v * tau - 0.5 * g * tau * tau,
                             "contact_nodes": 0 if k > 0 else 2, "total_energy": 1.0})
                n += 1
            for y in (rest, rest + 1e-4, rest, rest + 1e-4, rest):
                rows.append({"time": n * dt, "centre_uy": y, "contact_nodes": 2, "total_energy": 1.0})
                n += 1
        write_run(self.root, "ball_bouncing/000", rows, summary(n, dt))
        write_sweep(self.root, [("ball_bouncing/000", "ball_bouncing", "ok", "semi_explicit")])
        long_runs.main([self.root])
        r = self.read()["ball_bouncing/000"]
        # The first flight starts at t = 0 in contact; the last ends in contact: 3 flights.
        self.assertEqual(int(r["bounces"]), 3)
        self.assertAlmostEqual(float(r["restitution_first"]), math.sqrt(0.8), places=2)

    def test_creep_of_a_block(self):
        dt, steps = 1e-3, 100
        rows = [{"time": n * dt, "centre_ux": 1e-6 * n, "centre_uy": 0.0, "total_energy": 1.0}
                for n in range(steps + 1)]
        write_run(self.root, "incline_unrelaxed/000", rows, summary(steps, dt))
        write_sweep(self.root, [("incline_unrelaxed/000", "incline_unrelaxed", "ok", "implicit")])
        long_runs.main([self.root])
        r = self.read()["incline_unrelaxed/000"]
        self.assertAlmostEqual(float(r["displacement_end"]), 1e-4, places=12)
        self.assertAlmostEqual(float(r["creep_last_half"]), 5e-5, places=12)
        self.assertEqual(r["slide_distance"], "")

    def test_missing_sweep_is_one_line_error(self):
        p = subprocess.run([sys.executable, SCRIPT, os.path.join(self.root, "nothing")],
                           capture_output=True, text=True)
        self.assertEqual(p.returncode, 2)
        self.assertEqual(len(p.stderr.strip().splitlines()), 1)
        self.assertIn("summary.csv", p.stderr)
        self.assertFalse(os.path.exists(os.path.join(self.root, "nothing", "drift.csv")))


if __name__ == "__main__":
    unittest.main()
