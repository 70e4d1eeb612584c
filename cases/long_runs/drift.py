#!/usr/bin/python3
"""The long runs' figures (docs/stability.md, Long runs): energy drift per 1e5 steps, the
largest penetration and the chatter of the active set, one row per run of a finished sweep of
cases/long_runs/sweep.toml (or sweep_fast.toml).

    /usr/bin/python3 cases/long_runs/drift.py results/long_runs      # writes results/long_runs/drift.csv

drift.csv is a table that `ricochet check` gates (cases/long_runs/gates_full.toml). Its columns, with
units, are listed in COLUMNS below and in docs/stability.md (Long runs).

The energy residual. The paper's energy error |E_t + D - E_0 - W_ext| / E_ref counts the energy
that the position-level contact of the bi-potential schemes takes out of a node it stops as an
error (docs/outputs.md). Over 1e5 steps of bouncing that is most of the energy, and it is not
drift. The residual here closes the balance with what the contact does:
  bi-potential schemes (semi_explicit, implicit):  R = E_t + D - E_0 - W_ext - W_cn
  explicit_penalty:                                 R = E_t + E_pen + D - E_0 - W_ext
with W_cn = contact_work_normal (the normal reactions' work, <= 0, exactly the change they cause
in the kinetic energy), E_pen = contact_energy (the springs' stored energy), D the friction
dissipation, all from history.csv, over E_ref = max(E_0, max |W_ext|). What is left is the time
integrator's own energy error. Its drift is the least-squares slope of R / E_ref against the
step number over the second half of the run, times 1e5: the first half holds the start-up
transients (a load applied suddenly, the first impacts), which are a step in R, not a drift.
"""
import argparse
import csv
import json
import math
import os
import sys

import numpy as np

BI_POTENTIAL = ("semi_explicit", "implicit")

# (column, unit, meaning)
COLUMNS = [
    ("run_id", "-", "the sweep's run id"),
    ("group", "-", "the scene: block_resting, block_sliding, ball_bouncing, oblique_plate, "
                   "incline_relaxed, incline_unrelaxed, incline_unrelaxed_rot90"),
    ("scheme", "-", "semi_explicit, explicit_penalty or implicit"),
    ("status", "-", "the run's status (ok, diverged, failed)"),
    ("steps", "-", "time steps taken"),
    ("dt", "s", "the time step"),
    ("samples", "-", "history rows used"),
    ("energy_error_max", "-", "the paper's energy error, largest over the samples (summary.json)"),
    ("energy_error_end", "-", "the paper's energy error at the last sample"),
    ("residual_max", "-", "largest |R| / E_ref over the samples"),
    ("energy_drift_per_1e5_steps", "-", "least-squares slope of R / E_ref against the step over "
                                        "the second half of the run, x 1e5"),
    ("energy_drift_abs_per_1e5_steps", "-", "its absolute value (what the gates bound)"),
    ("penetration_max", "m", "largest penetration over the samples (summary.json)"),
    ("status_changes", "-", "contact status changes summed over every step (summary.json)"),
    ("status_changes_per_step", "-", "status_changes / steps: the chatter of the active set"),
    ("status_change_steps", "-", "steps with at least one status change"),
    ("contact_steps", "-", "steps with at least one active contact"),
    ("creep_last_half", "m", "the blocks (block_*, incline_*): how far the centre probe moved "
                              "over the last half of the run, |u(end) - u(mid)| (creep while it "
                              "should rest); empty otherwise"),
    ("displacement_end", "m", "the blocks: |u(end) - u(0)| of the centre probe; empty otherwise"),
    ("slide_distance", "m", "block_sliding: the centre probe's final x displacement "
                            "(rigid Coulomb block: 0.1699 m); empty otherwise"),
    ("bounces", "-", "ball_bouncing: flights (samples without contact between two contacts) "
                     "whose apex is more than 1 mm above the resting height (the median height of the samples "
                     "in contact); empty otherwise"),
    ("restitution_first", "-", "ball_bouncing: sqrt(h2 / h1) of the first two apex heights above "
                               "the resting height; empty otherwise"),
]


def fail(msg):
    sys.stderr.write(f"long_runs.py: {msg}\n")
    sys.exit(2)


def read_history(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if len(rows) < 3:
        fail(f"{path}: fewer than two samples")
    head = rows[0]
    data = np.array([[float(x) if x else math.nan for x in r] for r in rows[1:]])
    return {name: data[:, k] for k, name in enumerate(head)}


def slope(x, y):
    x = np.asarray(x, float)
    y = np.asarray(y, float)
    if len(x) < 2 or np.ptp(x) == 0:
        return 0.0
    xc = x - x.mean()
    return float(np.dot(xc, y - y.mean()) / np.dot(xc, xc))


def residual(h, scheme):
    e0 = h["total_energy"][0] + h["contact_energy"][0]
    w = h["external_work"]
    e_ref = max(abs(e0), float(np.max(np.abs(w))))
    r = h["total_energy"] + h["friction_dissipation"] - e0 - w
    if scheme in BI_POTENTIAL:
        r = r - h["contact_work_normal"]
    else:
        r = r + h["contact_energy"]
    return r / e_ref


def flight_apexes(y, in_contact):
    """The highest sample of each flight: each run of consecutive samples without an active
    contact, between two contacts (the vibration of the ball during a contact makes local
    maxima that are not apexes)."""
    out = []
    k = 0
    n = len(y)
    while k < n:
        if in_contact[k]:
            k += 1
            continue
        j = k
        while j < n and not in_contact[j]:
            j += 1
        if k > 0 and j < n:  # a whole flight, from a take-off to a landing
            out.append(float(np.max(y[k:j])))
        k = j
    return out


def analyse(run_dir, row):
    sj = os.path.join(run_dir, "summary.json")
    hc = os.path.join(run_dir, "history.csv")
    out = {c[0]: "" for c in COLUMNS}
    out.update(run_id=row["run_id"], group=row["group"], scheme=row.get("scheme", ""),
               status=row["status"])
    if row["status"] == "failed" or not os.path.exists(sj):
        return out
    with open(sj) as f:
        s = json.load(f)
    h = read_history(hc)
    steps = int(s["steps"])
    dt = float(s["dt"])
    # The step of each sample: t / dt (the runs take a fixed step).
    n = np.rint(h["time"] / dt)
    r = residual(h, out["scheme"])
    half = len(n) // 2
    d = slope(n[half:], r[half:]) * 1e5
    ci = s.get("contact_iterations") or {}
    out.update(steps=steps, dt=dt, samples=len(n),
               energy_error_max=s["energy_error_max"],
               energy_error_end=float(h["energy_error"][-1]),
               residual_max=float(np.max(np.abs(r))),
               energy_drift_per_1e5_steps=d, energy_drift_abs_per_1e5_steps=abs(d),
               penetration_max=s["penetration_max"],
               status_changes=ci.get("status_changes", ""),
               status_changes_per_step=(ci["status_changes"] / steps
                                        if steps and "status_changes" in ci else ""),
               status_change_steps=ci.get("status_change_steps", ""),
               contact_steps=ci.get("steps_with_contact", ""))
    g = row["group"]
    if g.startswith(("block_", "incline_")) and "centre_ux" in h:
        ux, uy = h["centre_ux"], h["centre_uy"]
        half = len(ux) // 2
        out["creep_last_half"] = float(math.hypot(ux[-1] - ux[half], uy[-1] - uy[half]))
        out["displacement_end"] = float(math.hypot(ux[-1] - ux[0], uy[-1] - uy[0]))
        if g == "block_sliding":
            out["slide_distance"] = float(ux[-1])
    if g == "ball_bouncing" and "centre_uy" in h:
        y = h["centre_uy"]
        touching = h["contact_nodes"] > 0
        if not touching.any():
            return out
        rest = float(np.median(y[touching]))  # the centre's height while the ball touches
        apex = flight_apexes(y, touching)
        heights = [a - rest for a in apex if a - rest > 1e-3]
        out["bounces"] = len(heights)
        if len(heights) >= 2 and heights[0] > 0:
            out["restitution_first"] = math.sqrt(heights[1] / heights[0])
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dir", help="a finished sweep of cases/long_runs/sweep.toml")
    ap.add_argument("--out", help="the table to write (default DIR/drift.csv)")
    a = ap.parse_args(argv)
    summary = os.path.join(a.dir, "summary.csv")
    if not os.path.exists(summary):
        fail(f"{summary}: not found (run the sweep first)")
    with open(summary, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        fail(f"{summary}: no runs")
    table = [analyse(os.path.join(a.dir, "runs", r["run_id"]), r) for r in rows]
    out = a.out or os.path.join(a.dir, "drift.csv")
    tmp = out + ".tmp"
    with open(tmp, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow([c[0] for c in COLUMNS])
        for t in table:
            w.writerow([("%.9g" % v) if isinstance(v, float) else v for v in (t[c[0]] for c in COLUMNS)])
    os.replace(tmp, out)
    for t in table:
        print(f"{t['run_id']:40s} {t['status']:8s} steps {t['steps']!s:>7} "
              f"drift/1e5 {t['energy_drift_per_1e5_steps'] if t['energy_drift_per_1e5_steps'] == '' else '%+.2e' % t['energy_drift_per_1e5_steps']:>10} "
              f"|R|max {'' if t['residual_max'] == '' else '%.2e' % t['residual_max']:>9} "
              f"pen {'' if t['penetration_max'] == '' else '%.2e' % t['penetration_max']:>9} "
              f"chg/step {'' if t['status_changes_per_step'] == '' else '%.3g' % t['status_changes_per_step']}")
    print(f"-> {out}")


if __name__ == "__main__":
    main()
