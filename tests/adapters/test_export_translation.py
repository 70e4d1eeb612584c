#!/usr/bin/python3
"""ricochet's own export of a case, through each shipped adapter's translation (docs/peers.md).

    tests/adapters/test_export_translation.py RICOCHET

Exports the oblique plate on M1 (mu = 0.1, dt = 1e-6 s) with `ricochet run` and an adapter
command that does nothing (`true`: the run fails for want of a result, and OUT/external/case.json
stays), checks case.json against the case, then hands it to the CalculiX and GetFEM adapters'
translations, without running either code: node and element counts, material constants,
initial velocities, contact stiffness, time step. The adapters' own tests check the same on
hand-written fixtures; this one checks that the harness and the adapters agree on the format.
"""
import json
import math
import os
import pathlib
import re
import subprocess
import sys
import tempfile
import unittest

ROOT = pathlib.Path(__file__).resolve().parents[2]
RICOCHET = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else ROOT / "build" / "ricochet")
sys.path.insert(0, str(ROOT / "adapters"))
import calculix  # noqa: E402
import getfem as getfem_adapter  # noqa: E402  (adapters/getfem.py, not the GetFEM module)

NODES, CELLS, CANDIDATES = 13 * 33, 12 * 32, 2 * (12 + 32)  # M1: 12 x 32 Q4 cells


def export(tmp):
    out = pathlib.Path(tmp) / "out"
    r = subprocess.run([RICOCHET, "run", str(ROOT / "cases" / "oblique_plate.toml"), "--quiet", "--out", str(out),
                        "--set", "scheme=mine", "--set", 'external.command=["true"]',
                        "--set", "obstacles[0].friction=0.1", "--set", "time.dt=1e-6"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 1 and "result.json: missing" in r.stderr, r.stderr
    return json.loads((out / "external" / "case.json").read_text())


class Export(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        with tempfile.TemporaryDirectory() as tmp:
            cls.case = export(tmp)

    def test_case_json(self):
        c = self.case
        self.assertEqual((c["format"], c["version"], c["scheme"], c["dimension"], c["plane"]),
                         ("ricochet-external-case", 1, "mine", 2, "stress"))
        self.assertEqual(len(c["nodes"]), NODES)
        body = c["bodies"][0]
        self.assertEqual(len(body["cells"]["quad4"]), CELLS)
        self.assertEqual(body["material"], {"model": "saint_venant_kirchhoff", "density": 1000.0,
                                            "young": 1.0e7, "poisson": 0.25})
        self.assertEqual(body["thickness"], 0.01)
        self.assertTrue(all(v == [3.0, -5.0] for v in c["velocity"]))
        # Lumped masses sum to the plate's mass rho e A (A from the cells' shoelace areas).
        xy = c["nodes"]
        area = sum(0.5 * abs(sum(xy[q[k]][0] * xy[q[(k + 1) % 4]][1] - xy[q[(k + 1) % 4]][0] * xy[q[k]][1]
                                 for k in range(4))) for q in body["cells"]["quad4"])
        self.assertAlmostEqual(sum(c["mass"]), 1000.0 * 0.01 * area, delta=1e-12)
        cands = c["contact"]["candidates"]
        self.assertEqual(len(cands), CANDIDATES)
        self.assertTrue(all(k["friction"] == 0.1 and k["obstacle"] == 0 and k["stiffness"] > 0 for k in cands))
        # The candidates' areas are the boundary's: perimeter x thickness.
        perimeter = sum(math.dist(xy[a], xy[b]) for a, b in boundary_edges(body["cells"]["quad4"]))
        self.assertAlmostEqual(sum(k["area"] for k in cands), perimeter * 0.01, delta=1e-12)
        self.assertEqual(c["time"], {"dt": 1e-6, "end": 3e-3, "steps": 3000, "dt_auto": False,
                                     "critical_dt": c["time"]["critical_dt"]})
        self.assertEqual(c["obstacles"], [{"name": "ground", "type": "line", "point": [0.0, 0.0], "normal": [0.0, 1.0]}])
        self.assertEqual([p["name"] for p in c["output"]["probes"]], ["P", "top_left", "top_right", "centroid"])

    def test_calculix_translation(self):
        tr = calculix.translate(self.case, calculix.parse_options({}))
        deck = tr.deck
        # The plate: two copies of each node, one brick per cell.
        self.assertEqual(tr.bricks.copies.shape, (NODES, 2))
        self.assertEqual(len(tr.bricks.element_ids[0]), CELLS)
        self.assertIn("*ELEMENT, TYPE=C3D8, ELSET=BODY1", deck)
        elastic = deck.split("*ELASTIC")[1].splitlines()[1]
        self.assertEqual([float(x) for x in elastic.split(",")[:2]], [1.0e7, 0.25])
        density = deck.split("*DENSITY")[1].splitlines()[1]
        self.assertEqual(float(density.split(",")[0]), 1000.0)
        vel = [l for l in deck.split("*INITIAL CONDITIONS, TYPE=VELOCITY")[1].split("*")[0].splitlines() if l.strip()]
        self.assertEqual(len(vel), 2 * NODES * 3)
        by_component = {}
        for line in vel:
            _, comp, value = line.split(",")
            by_component.setdefault(int(comp), set()).add(float(value))
        self.assertEqual(by_component, {1: {3.0}, 2: {-5.0}, 3: {0.0}})
        # The penalty slopes come from ricochet's springs: within their k/a range.
        ratios = [k["stiffness"] / k["area"] for k in self.case["contact"]["candidates"]]
        slopes = tr.slopes[0] if isinstance(tr.slopes[0], (list, tuple)) else [tr.slopes[0]]
        for K in slopes:
            self.assertTrue(min(ratios) * (1 - 1e-12) <= K <= max(ratios) * (1 + 1e-12), (K, min(ratios), max(ratios)))
        self.assertIn("*FRICTION", deck)
        mu = deck.split("*FRICTION")[1].splitlines()[1]
        self.assertEqual(float(mu.split(",")[0]), 0.1)
        dyn = deck.split("*DYNAMIC, EXPLICIT")[1].splitlines()[1]
        self.assertEqual([float(x) for x in dyn.split(",") if x.strip()], [1e-6, 3e-3, 1e-6])

    def test_getfem_translation(self):
        d = getfem_adapter.describe(self.case)
        self.assertEqual(d.nodes.shape, (NODES, 2))
        self.assertTrue((d.velocity == [3.0, -5.0]).all())
        self.assertEqual((d.dt, d.end, d.steps), (1e-6, 3e-3, 3000))
        self.assertEqual((d.bodies[0].thickness, d.bodies[0].material.density), (0.01, 1000.0))
        self.assertEqual(len(d.obstacles), 1)
        self.assertEqual(d.obstacles[0].friction, 0.1)
        self.assertEqual(len(d.obstacles[0].nodes), CANDIDATES)
        prob = getfem_adapter.build(d)
        self.assertEqual((prob.mesh.nbpts(), prob.mesh.nbcvs(), prob.mf.nbdof()), (NODES, CELLS, 2 * NODES))
        # Node i is GetFEM's point i, and its dofs are where the node is.
        pts = prob.mesh.pts()
        self.assertLess(abs(pts.T - d.nodes).max(), 1e-15)


def boundary_edges(quads):
    count = {}
    for q in quads:
        for k in range(4):
            e = tuple(sorted((q[k], q[(k + 1) % 4])))
            count[e] = count.get(e, 0) + 1
    return [e for e, n in count.items() if n == 1]


if __name__ == "__main__":
    unittest.main(argv=sys.argv[:1])
