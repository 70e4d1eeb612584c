#!/usr/bin/python3
"""A complete external-scheme adapter in 90 lines: the example of docs/peers.md ("Writing an
adapter"), and the stand-in for a user's solver in the tests.

    rigid_body.py CASE_JSON WORK_DIR

The "solver" is deliberately trivial: every body moves as one rigid body without rotation (its
centre-of-mass velocity), and bounces off flat obstacles with a coefficient of restitution
(option `restitution`, default 1: elastic) when its lowest node reaches them. No strain, no
friction. It reads ricochet's case.json, steps with the case's dt to time.end, and writes
result.json and history.csv in ricochet's schema; ricochet then checks them, computes the
energy error and writes the run's summary.json and history.csv.

Options (case key external.options):
    restitution   number in [0, 1], default 1
"""
import json
import math
import sys


def fail(why, status=2):
    """One line on stderr, no result.json: ricochet reports the run as failed with this line."""
    print(f"rigid_body: {why}", file=sys.stderr)
    sys.exit(status)


def main(case_path, work):
    case = json.load(open(case_path))
    opts = case["options"]
    unknown = set(opts) - {"restitution"}
    if unknown:
        fail(f"options: unknown key {sorted(unknown)[0]!r}; allowed: restitution")
    e = opts.get("restitution", 1.0)
    if not isinstance(e, (int, float)) or not 0.0 <= e <= 1.0:
        fail(f"options.restitution: expected a number in [0, 1], got {e!r}")
    flat = {"line", "plane"}
    for ob in case["obstacles"]:
        if ob["type"] not in flat:
            fail(f"obstacle {ob['name']!r}: type {ob['type']!r} is not translated; allowed: line, plane")
    if case["contact"]["body_pairs"]:
        fail("contact between bodies is not translated")
    d = case["dimension"]
    x0, v0, m = case["nodes"], case["velocity"], case["mass"]
    mass = sum(m)
    vel = [sum(m[i] * v0[i][k] for i in range(len(m))) / mass for k in range(d)]
    shift = [0.0] * d  # rigid translation so far
    dt, end = case["time"]["dt"], case["time"]["end"]
    interval = case["output"]["interval"] or dt
    probes = case["output"]["probes"]
    axes = "xyz"[:d]
    cols = ["time", "kinetic_energy", "strain_energy", "total_energy"] + [f"momentum_{a}" for a in axes]
    for p in probes:
        cols += [f"{p['name']}_u{a}" for a in axes] + [f"{p['name']}_v{a}" for a in axes]
    rows = []

    def sample(t):
        ke = 0.5 * mass * sum(c * c for c in vel)
        row = [t, ke, 0.0, ke] + [mass * c for c in vel]
        for _ in probes:
            row += shift + vel
        rows.append(row)

    def gap(ob):
        """Smallest signed distance of any node to the obstacle's plane."""
        n, q = ob["normal"], ob["point"]
        return min(sum(n[k] * (x[k] + shift[k] - q[k]) for k in range(d)) for x in x0)

    steps, t, next_sample = 0, 0.0, 0.0
    total = math.ceil(end / dt - 1e-9)
    sample(0.0)
    next_sample += interval
    while steps < total:
        h = min(dt, end - t)
        for k in range(d):
            shift[k] += h * vel[k]
        for ob in case["obstacles"]:
            n = ob["normal"]
            vn = sum(n[k] * vel[k] for k in range(d))
            if gap(ob) < 0.0 and vn < 0.0:  # reflect the normal velocity
                for k in range(d):
                    vel[k] -= (1.0 + e) * vn * n[k]
        steps += 1
        t = end if steps == total else steps * dt
        if t >= next_sample - 1e-12 * dt or steps == total:
            sample(t)
            next_sample += interval
    with open(f"{work}/history.csv", "w") as f:
        f.write(",".join(cols) + "\n")
        for r in rows:
            f.write(",".join(repr(float(v)) for v in r) + "\n")
    result = {"format": "ricochet-external-result", "version": 1, "status": "ok", "steps": steps, "dt": dt,
              "time_reached": t, "code": "rigid_body example", "code_version": "1",
              "translation": {"translated": ["bodies as one rigid body each, without rotation",
                                             "flat obstacles, restitution %g" % e],
                              "not_translated": ["deformation (no strain energy)", "friction"]}}
    with open(f"{work}/result.json", "w") as f:
        json.dump(result, f, indent=2)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        fail("usage: rigid_body.py CASE_JSON WORK_DIR")
    main(sys.argv[1], sys.argv[2])
