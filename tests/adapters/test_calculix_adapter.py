#!/usr/bin/python3
"""Tests of the CalculiX adapter's translation and output reading (adapters/calculix.py),
without running ccx.

From a hand-written case.json (docs/peers.md, "case.json: what the adapter is given"): a
2 x 2-cell square plate of 9 nodes above the line y = 0, its 8 boundary nodes the contact
candidates (and a 4 x 4 one), checks
  * the deck: node count (2 copies of each 2D node + the ground's copies), element counts,
    the material constants, the initial velocities per copy, the *DYNAMIC card of both
    procedures, the plane-strain z constraints, the slave faces, the ground's geometry,
    copies and supports, and that every brick has a positive volume;
  * the contact slopes: per slave face the mean of k_i/a_i over its nodes, one *CONTACT PAIR
    (slave surface, interaction, own master) per distinct value (6 on the 2 x 2 plate; 2 when
    one node differs, with the right faces in each, the stick slope per pair), 8 groups of
    neighbouring values when there are more (the 4 x 4 plate: 16), the grouping rule itself
    (4 significant digits; a dominant value kept alone), a number given as an option (one
    pair), the notes (groups, deviation, springs against k_i) and the springs' critical step;
  * rejections, each one line (exit 2 and no result.json through main()): bad options,
    blatz_ko, a circle obstacle, body pairs, non-zero prescribed values, nodal loads;
  * the .dat reader on a small synthetic job.dat (and a number with a 3-digit exponent);
  * the post-processing: St Venant-Kirchhoff and Mooney-Rivlin stresses against hand
    values, a sampled rigid translation (no strain, momentum, probes), the force sign.

    /usr/bin/python3 tests/adapters/test_calculix_adapter.py
"""

import copy
import json
import math
import os
import subprocess
import sys
import tempfile
import unittest

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ADAPTERS = os.path.join(HERE, "..", "..", "adapters")
sys.path.insert(0, ADAPTERS)
import calculix as cx  # noqa: E402

E, NU, RHO, THICK = 2.0e7, 0.3, 1200.0, 0.005
V0 = (1.5, -4.0)
H = 0.01          # cell size


def fixture(n=2, ratio=None):
    """The n x n plate (default 2 x 2), node k = (n + 1) j + i at (i H, j H + 1e-4), above the
    ground y = 0; its boundary nodes are the candidates, k_i = ratio(k) a_i (default, n = 2:
    1e9 .. 8e9 in the order of the boundary nodes, median 4.5e9)."""
    m = n + 1
    nodes = [[i * H, j * H + 1e-4] for j in range(m) for i in range(m)]
    cells = [[m * j + i, m * j + i + 1, m * j + i + m + 1, m * j + i + m] for j in range(n) for i in range(n)]
    boundary = [k for k in range(m * m) if k % m in (0, n) or k // m in (0, n)]
    area = {k: H * THICK for k in boundary}      # two half edges of length H each
    if ratio is None:
        ratio = dict(zip(boundary, [1e9, 2e9, 3e9, 4e9, 5e9, 6e9, 7e9, 8e9])).get
    adjacent = [sum(k in c for c in cells) for k in range(m * m)]
    mass = [RHO * THICK * H * H * w / 4 for w in adjacent]
    return {
        "format": "ricochet-external-case", "version": 1, "case": "tiny_plate",
        "case_file": "/nowhere/tiny_plate.toml", "scheme": "calculix", "dimension": 2, "plane": "stress",
        "nodes": nodes, "velocity": [list(V0)] * (m * m), "mass": mass,
        "bodies": [{"name": "plate", "element": "q4", "thickness": THICK, "nodes": [0, m * m],
                    "cells": {"quad4": cells},
                    "material": {"model": "saint_venant_kirchhoff", "density": RHO, "young": E,
                                 "poisson": NU}}],
        "gravity": [0.0, 0.0], "prescribed": [], "loads": [],
        "obstacles": [{"name": "ground", "type": "line", "point": [0.0, 0.0], "normal": [0.0, 1.0]}],
        "contact": {"candidates": [{"node": k, "obstacle": 0, "friction": 0.0,
                                    "stiffness": ratio(k) * area[k], "area": area[k]} for k in boundary],
                    "penalty_scale_factor": 0.1, "body_pairs": []},
        "time": {"dt": 2e-6, "end": 1e-3, "steps": 500, "dt_auto": False, "critical_dt": 5e-6},
        "output": {"interval": 2e-5, "stress_measure": "pk2",
                   "probes": [{"name": "P", "body": "plate", "node": 1}]},
        "threads": 1, "options": {},
    }


def deck_cards(deck):
    """[(keyword line, [data lines])] of a deck, comments dropped."""
    cards = []
    for line in deck.splitlines():
        if line.startswith("**") or not line.strip():
            continue
        if line.startswith("*"):
            cards.append((line, []))
        else:
            cards[-1][1].append(line)
    return cards


def card(deck, head):
    """The data lines of the only card whose keyword line starts with head."""
    found = [data for key, data in deck_cards(deck) if key.upper().startswith(head.upper())]
    if len(found) != 1:
        raise AssertionError("%d cards '%s' in the deck" % (len(found), head))
    return found[0]


def material(deck, name):
    """{keyword line: data lines} of the cards of *MATERIAL, NAME=name."""
    out, inside = {}, False
    for key, data in deck_cards(deck):
        if key.upper().startswith("*MATERIAL"):
            inside = key.upper() == "*MATERIAL, NAME=" + name
        elif key.upper().startswith(("*DENSITY", "*ELASTIC", "*HYPERELASTIC")) and inside:
            out[key.upper()] = data
        else:
            inside = False
    return out


def numbers(line):
    return [float(v) for v in line.split(",") if v.strip()]


def nodes_of(deck):
    out = {}
    for key, data in deck_cards(deck):
        if key.upper().startswith("*NODE,") or key.upper() == "*NODE":
            for line in data:
                v = numbers(line)
                out[int(v[0])] = np.array(v[1:4])
    return out


def translate(case):
    return cx.translate(case, cx.parse_options(case.get("options")))


def contact_groups(deck):
    """[(slave faces {(element, "S#")}, slope K, sigma_inf, friction line or None, master)] per
    *CONTACT PAIR of the deck, in the deck's order, through the pair's named cards."""
    cards = deck_cards(deck)
    surfaces, behaviours, frictions, inter = {}, {}, {}, None
    for key, data in cards:
        head = key.upper().replace(" ", "")
        if head.startswith("*SURFACE,NAME="):
            surfaces[head.split("=")[1]] = {(int(line.split(",")[0]), line.split(",")[1].strip())
                                            for line in data}
        elif head.startswith("*SURFACEINTERACTION,NAME="):
            inter = head.split("=")[1]
        elif head.startswith("*SURFACEBEHAVIOR"):
            behaviours[inter] = numbers(data[0])
        elif head.startswith("*FRICTION"):
            frictions[inter] = numbers(data[0])
    out = []
    for key, data in cards:
        head = key.upper().replace(" ", "")
        if head.startswith("*CONTACTPAIR"):
            inter = head.split("INTERACTION=")[1].split(",")[0]
            slave, master = [v.strip() for v in data[0].split(",")]
            out.append((surfaces[slave], behaviours[inter][0], behaviours[inter][1], frictions.get(inter),
                        surfaces[master]))
    return out


def face_slopes(case):
    """{(element, "S#"): the mean of k_i/a_i over the face's two nodes} of a 2D plate fixture's
    boundary faces (element ids from 1, edge k of a quad is face S3 + k)."""
    ratio = {c["node"]: c["stiffness"] / c["area"] for c in case["contact"]["candidates"]}
    cells = case["bodies"][0]["cells"]["quad4"]
    edges = {}
    for e, cell in enumerate(cells):
        for k in range(4):
            key = tuple(sorted((cell[k], cell[(k + 1) % 4])))
            edges.setdefault(key, []).append((e + 1, "S%d" % (3 + k)))
    return {faces[0]: 0.5 * (ratio[a] + ratio[b]) for (a, b), faces in edges.items() if len(faces) == 1}


def run_adapter(case_path, folder):
    """The adapter as the harness runs it, with a ccx that does not exist."""
    return subprocess.run([sys.executable, os.path.join(ADAPTERS, "calculix.py"), case_path, folder],
                          cwd=folder, capture_output=True, text=True,
                          env=dict(os.environ, RICOCHET_CCX="/nonexistent/ccx"))


class Translation(unittest.TestCase):
    def setUp(self):
        self.case = fixture()
        self.tr = translate(self.case)
        self.deck = self.tr.deck

    def test_nodes_two_copies_and_ground(self):
        nodes = nodes_of(self.deck)
        ground = self.tr.grounds[0]
        self.assertEqual(len(nodes), 2 * 9 + ground.copies * len(ground.coords))
        for k, (x, y) in enumerate(self.case["nodes"]):
            np.testing.assert_allclose(nodes[k + 1], [x, y, -THICK / 2], rtol=1e-12, atol=1e-15)
            np.testing.assert_allclose(nodes[k + 10], [x, y, THICK / 2], rtol=1e-12, atol=1e-15)

    def test_elements(self):
        cards = deck_cards(self.deck)
        body = [d for k, d in cards if k.upper().startswith("*ELEMENT, TYPE=C3D8, ELSET=BODY1")]
        ground = [d for k, d in cards if k.upper().startswith("*ELEMENT, TYPE=C3D8, ELSET=GROUND1")]
        self.assertEqual(len(body), 1)
        self.assertEqual(len(body[0]), 4)
        self.assertEqual(len(ground[0]), len(self.tr.grounds[0].elements))
        # The first cell (0, 1, 4, 3) is the brick of its front copies then its back copies.
        self.assertEqual([int(v) for v in numbers(body[0][0])], [1, 1, 2, 5, 4, 10, 11, 14, 13])

    def test_positive_volumes(self):
        nodes = nodes_of(self.deck)
        _, dN = cx.hex_shape(np.zeros((1, 3)))
        for key, data in deck_cards(self.deck):
            if key.upper().startswith("*ELEMENT"):
                for line in data:
                    ids = [int(v) for v in numbers(line)[1:]]
                    x = np.array([nodes[i] for i in ids])
                    self.assertGreater(np.linalg.det(x.T @ dN[0]), 0.0, line)

    def test_material(self):
        cards = material(self.deck, "MAT1")
        self.assertEqual(sorted(cards), ["*DENSITY", "*ELASTIC"])
        self.assertEqual(numbers(cards["*ELASTIC"][0]), [E, NU])
        self.assertEqual(numbers(cards["*DENSITY"][0]), [RHO])
        self.assertIn("*SOLID SECTION, ELSET=BODY1, MATERIAL=MAT1", self.deck)
        self.assertIn("*STEP, NLGEOM", self.deck)

    def test_hyperelastic_constants(self):
        case = fixture()
        case["bodies"][0]["material"] = {"model": "mooney_rivlin", "density": RHO, "c10": 1e5, "c01": 2e4,
                                         "bulk_modulus": 5e6}
        cards = material(translate(case).deck, "MAT1")
        self.assertEqual(numbers(cards["*HYPERELASTIC, MOONEY-RIVLIN"][0]), [1e5, 2e4, 2 / 5e6])
        case["bodies"][0]["material"] = {"model": "neo_hookean", "density": RHO, "young": E, "poisson": NU}
        tr = translate(case)
        lam, mu = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
        c10, d1 = numbers(material(tr.deck, "MAT1")["*HYPERELASTIC, NEO HOOKE"][0])
        self.assertAlmostEqual(c10 / (mu / 2), 1.0, places=11)
        self.assertAlmostEqual(d1 / (2 / (lam + 2 * mu / 3)), 1.0, places=11)
        self.assertTrue(any("small-strain limit only" in n for n in tr.notes))

    def test_initial_velocities(self):
        lines = card(self.deck, "*INITIAL CONDITIONS, TYPE=VELOCITY")
        got = {}
        for line in lines:
            node, comp, value = numbers(line)
            got[(int(node), int(comp))] = value
        self.assertEqual(len(got), 18 * 3)
        for k in range(9):
            for copy_id in (k + 1, k + 10):
                self.assertEqual([got[(copy_id, c)] for c in (1, 2, 3)], [V0[0], V0[1], 0.0])

    def test_penalty_per_face_six_groups(self):
        # Faces along the ring of ratios 1 .. 8e9 (nodes 0 1 2 5 8 7 6 3): K_face = 1.5, 2.5,
        # 4, 6.5, 7.5, 6.5, 5, 2.5e9: six distinct values, six pairs.
        groups = contact_groups(self.deck)
        self.assertEqual([round(K / 1e9, 9) for _, K, _, _, _ in groups], [1.5, 2.5, 4.0, 5.0, 6.5, 7.5])
        expected = face_slopes(self.case)
        for faces, K, _, _, _ in groups:
            for f in faces:
                self.assertAlmostEqual(expected[f] / K, 1.0, places=12, msg=str(f))
        self.assertEqual(sorted(len(f) for f, _, _, _, _ in groups), [1, 1, 1, 1, 2, 2])
        self.assertEqual(self.tr.slopes, [[K for _, K, _, _, _ in groups]])
        self.assertTrue(any("6 interactions" in s and "min 1.5e+09" in s and "max 7.5e+09" in s
                            for s in self.tr.translated))
        self.assertTrue(any("6 contact interactions" in n and "by at most 0 %" in n for n in self.tr.notes))

    def test_penalty_two_ratios_two_groups(self):
        # Node 1 (bottom middle) at 3e9, the others at 1e9: its two faces (the bottoms of
        # elements 1 and 2) have K_face = 2e9, the other six 1e9.
        case = fixture(ratio=lambda k: 3e9 if k == 1 else 1e9)
        case["contact"]["candidates"] = [dict(c, friction=0.2) for c in case["contact"]["candidates"]]
        tr = translate(case)
        groups = contact_groups(tr.deck)
        self.assertEqual(len(groups), 2)
        self.assertEqual(len([k for k, _ in deck_cards(tr.deck) if k.upper().startswith("*SURFACE INTERACTION")]),
                         2)
        (soft, K1, s1, mu1, m1), (stiff, K2, s2, mu2, m2) = groups
        self.assertAlmostEqual(K1 / 1e9, 1.0, places=12)
        self.assertAlmostEqual(K2 / 2e9, 1.0, places=12)
        self.assertEqual(stiff, {(1, "S3"), (2, "S3")})
        self.assertEqual(soft, {(2, "S4"), (4, "S4"), (3, "S5"), (4, "S5"), (1, "S6"), (3, "S6")})
        self.assertAlmostEqual(s2 / s1, 2.0, places=12)            # the same smoothing length eps
        self.assertEqual((mu1, mu2), ([0.2, K1], [0.2, K2]))        # stick slope = the group's K
        # Each pair on its own copy of the ground's top face: same place, other elements.
        self.assertEqual(len(m1), len(tr.grounds[0].elements))
        self.assertEqual(len(m2), len(m1))
        self.assertFalse({e for e, _ in m1} & {e for e, _ in m2})
        # The springs: node 1's 2 faces x 2e9 x (H e / 2) = 2e9 H e against ricochet's 3e9 H e
        # (-33 %); the corners 0 and 2, (2e9 + 1e9) H e / 2 against 1e9 H e (+50 %).
        note = [n for n in tr.notes if "contact interactions" in n]
        self.assertEqual(len(note), 1)
        self.assertIn("2 contact interactions", note[0])
        self.assertRegex(note[0], r"differ from ricochet's k_i by at most 50 % \(node [02]\)")
        case["options"] = {"stick_slope": 5e8}
        self.assertEqual([g[3] for g in contact_groups(translate(case).deck)], [[0.2, 5e8], [0.2, 5e8]])

    def test_penalty_more_than_eight_values(self):
        # A 4 x 4 plate, 16 faces, every node its own ratio: 16 distinct K_face, 8 groups.
        case = fixture(4, ratio=lambda k: 1e9 * (1 + 0.1 * k ** 1.3))
        tr = translate(case)
        groups = contact_groups(tr.deck)
        expected = face_slopes(case)
        self.assertEqual(len(set("%.4g" % K for K in expected.values())), 16)
        self.assertEqual(len(groups), 8)
        seen = [f for faces, _, _, _, _ in groups for f in faces]
        self.assertEqual(sorted(seen), sorted(expected))            # every face once
        deviation, top = 0.0, 0.0
        for faces, K, _, _, _ in groups:
            values = [expected[f] for f in faces]
            self.assertAlmostEqual(K / np.mean(values), 1.0, places=12)
            self.assertGreater(min(values), top)                     # groups of neighbouring values
            top = max(values)
            deviation = max(deviation, max(abs(v / K - 1) for v in values))
        note = [n for n in tr.notes if "contact interactions" in n][0]
        self.assertIn("8 contact interactions", note)
        self.assertIn("by at most %.2g %%" % (100 * deviation), note)

    def test_group_slopes(self):
        # Equal to 4 significant digits: one group, the slope their mean.
        labels, slopes = cx.group_slopes([2e9, 1e9, 1.00001e9, 2e9])
        self.assertEqual(labels.tolist(), [1, 0, 0, 1])
        np.testing.assert_allclose(slopes, [1.000005e9, 2e9], rtol=1e-14)
        # A dominant value and 8 others (9 distinct): the dominant one alone, the closest two
        # merged (1.33, 1.34: 0.37 % from their mean). Quantiles would mix 1.0 with 1.1 .. 1.3.
        K = [1.0] * 60 + [v for v in (1.10, 1.26, 1.275, 1.30, 1.31, 1.32, 1.33, 1.34) for _ in (0, 1)]
        labels, slopes = cx.group_slopes(np.array(K) * 1e8)
        self.assertEqual(len(slopes), 8)
        self.assertEqual(np.bincount(labels).tolist(), [60, 2, 2, 2, 2, 2, 2, 4])
        deviation = np.abs(np.array(K) * 1e8 / slopes[labels] - 1).max()
        self.assertLess(deviation, 0.004)
        self.assertTrue(np.all(np.diff(slopes) > 0))

    def test_penalty_number(self):
        case = fixture()
        case["options"] = {"penalty": 3e10}
        tr = translate(case)
        groups = contact_groups(tr.deck)
        self.assertEqual(len(groups), 1)
        self.assertEqual(groups[0][1], 3e10)
        self.assertEqual(len(groups[0][0]), 8)
        self.assertEqual(tr.slopes, [[3e10]])
        self.assertEqual(len(tr.grounds[0].coords) * 1 + 18, len(nodes_of(tr.deck)))
        self.assertFalse(any("contact interactions" in n for n in tr.notes))

    def test_friction(self):
        self.assertNotIn("*FRICTION", self.deck)
        case = fixture()
        for c in case["contact"]["candidates"]:
            c["friction"] = 0.1
        case["options"] = {"stick_slope": 1e9}
        self.assertEqual([g[3] for g in contact_groups(translate(case).deck)], [[0.1, 1e9]] * 6)

    def test_explicit_step(self):
        self.assertEqual(numbers(card(self.deck, "*DYNAMIC, EXPLICIT")[0]), [2e-6, 1e-3, 2e-6])
        self.assertIn("FREQUENCY=10", self.deck)     # 2e-5 / 2e-6

    def test_implicit_step(self):
        case = fixture()
        case["options"] = {"procedure": "implicit", "alpha": -0.2}
        deck = translate(case).deck
        head = [k for k, _ in deck_cards(deck) if k.upper().startswith("*DYNAMIC")]
        self.assertEqual(len(head), 1)
        self.assertIn("DIRECT", head[0])
        self.assertNotIn("EXPLICIT", head[0])
        self.assertAlmostEqual(float(head[0].split("ALPHA=")[1]), -0.2, places=12)
        self.assertEqual(numbers(card(deck, "*DYNAMIC")[0]), [2e-6, 1e-3])

    def test_plane_strain_fixes_z(self):
        self.assertNotIn("NBODIES, 3, 3", card(self.deck, "*BOUNDARY"))
        case = fixture()
        case["plane"] = "strain"
        self.assertIn("NBODIES, 3, 3", card(translate(case).deck, "*BOUNDARY"))
        nset = [d for k, d in deck_cards(translate(case).deck) if k.upper() == "*NSET, NSET=NBODY1"][0]
        self.assertEqual(sorted(int(v) for line in nset for v in numbers(line)), list(range(1, 19)))

    def test_slave_faces_are_the_boundary(self):
        faces = [f for group, _, _, _, _ in contact_groups(self.deck) for f in group]
        # 8 boundary edges, each in one slave surface: bottom (S3) of cells 1, 2; right (S4) of
        # 2, 4; top (S5) of 3, 4; left (S6) of 1, 3.
        self.assertEqual(sorted(faces), sorted([(1, "S3"), (2, "S3"), (2, "S4"), (4, "S4"),
                                                (3, "S5"), (4, "S5"), (1, "S6"), (3, "S6")]))

    def test_ground(self):
        g = self.tr.grounds[0]
        top = g.coords[np.isclose(g.coords[:, 1], 0.0)]
        self.assertEqual(len(top), len(g.coords) // 2)          # half the nodes on the plane y = 0
        self.assertLess(g.coords[:, 1].min(), 0.0)
        self.assertLess(g.coords[:, 2].min(), -THICK / 2)       # wider than the slab in z
        self.assertGreater(g.coords[:, 2].max(), THICK / 2)
        # along x: the plate (0 .. 0.02) and its travel 1.5 m/s x 1 ms, with margins
        self.assertLess(g.coords[:, 0].min(), 0.0)
        self.assertGreater(g.coords[:, 0].max(), 0.02 + V0[0] * 1e-3)
        self.assertEqual(card(self.deck, "*BOUNDARY")[0], "NGROUND1, 1, 3")
        self.assertEqual([line.split(",")[1].strip() for line in card(self.deck, "*SURFACE, NAME=MASTER1_1")],
                         ["S2"] * len(g.elements))

    def test_ground_copies(self):
        # One copy of the layer per pair (6 here): same coordinates, own nodes and elements;
        # NGROUND1 (supports, reaction) and GROUND1 (section) are their union.
        g = self.tr.grounds[0]
        self.assertEqual(g.copies, 6)
        nodes = nodes_of(self.deck)
        self.assertEqual(len(nodes), 18 + 6 * len(g.coords))
        copies = [sorted(int(numbers(line)[0]) for line in card(self.deck, "*NODE, NSET=NGROUND1_%d" % c))
                  for c in range(1, 7)]
        for ids in copies:
            np.testing.assert_allclose([nodes[i] for i in ids], g.coords, rtol=0, atol=1e-13)
        self.assertEqual(len({i for ids in copies for i in ids}), 6 * len(g.coords))
        self.assertEqual(card(self.deck, "*NSET, NSET=NGROUND1"), ["NGROUND1_%d" % c for c in range(1, 7)])
        self.assertEqual(card(self.deck, "*ELSET, ELSET=GROUND1"), ["GROUND1_%d" % c for c in range(1, 7)])
        self.assertIn("*SOLID SECTION, ELSET=GROUND1, MATERIAL=MATGROUND", self.deck)
        masters = [m for _, _, _, _, m in contact_groups(self.deck)]
        self.assertEqual(len({e for m in masters for e, _ in m}), 6 * len(g.elements))

    def test_fixed_supports(self):
        case = fixture()
        case["prescribed"] = [{"node": 6, "component": 0, "kind": "velocity", "value": 0.0, "ramp": 0.0}]
        self.assertIn("7, 1, 1", card(translate(case).deck, "*BOUNDARY"))
        self.assertIn("16, 1, 1", card(translate(case).deck, "*BOUNDARY"))

    def test_gravity(self):
        case = fixture()
        case["gravity"] = [0.0, -9.81]
        line = card(translate(case).deck, "*DLOAD")[0].split(",")
        self.assertEqual(line[:2], ["BODY1", " GRAV"])
        self.assertEqual([float(v) for v in line[2:]], [9.81, 0.0, -1.0, 0.0])
        self.assertIn("external_work", cx.history_columns(case, translate(case)))

    def test_numbers_fit_twenty_characters(self):
        case = fixture()
        case["nodes"] = [[x - 1.0 / 3.0, y] for x, y in case["nodes"]]
        for line in translate(case).deck.splitlines():
            if not line.startswith("*"):
                for v in line.split(","):
                    self.assertLessEqual(len(v.strip()), 20, line)


    def test_output_requests(self):
        cards = deck_cards(self.deck)
        heads = [k for k, _ in cards]
        self.assertIn("*NODE PRINT, NSET=NBODIES, FREQUENCY=10", heads)
        self.assertEqual(card(self.deck, "*NODE PRINT, NSET=NBODIES"), ["U, V"])
        self.assertEqual(card(self.deck, "*NODE PRINT, NSET=NGROUND1, TOTALS=ONLY"), ["RF"])
        self.assertEqual(card(self.deck, "*CONTACT PRINT, TOTALS=YES"), ["CELS, CSTR"])
        self.assertEqual(heads[-1], "*END STEP")

    def test_without_obstacles(self):
        case = fixture()
        case["obstacles"], case["contact"]["candidates"] = [], []
        tr = translate(case)
        self.assertNotIn("*CONTACT", tr.deck)
        self.assertNotIn("NGROUND", tr.deck)
        self.assertEqual(len(nodes_of(tr.deck)), 18)
        cols = cx.history_columns(case, tr)
        self.assertNotIn("normal_force", cols)
        self.assertNotIn("contact_energy", cols)

    def test_penalty_step_note(self):
        # 2 sqrt(m / k) with k the translated spring, sum over the node's faces of K_face x
        # (H e / 2): smallest at the corner node 8 (m = rho e H^2/4), faces 6.5e9 and 7.5e9.
        expected = 2 * math.sqrt((RHO * THICK * H * H / 4) / (7e9 * H * THICK))
        note = [n for n in self.tr.translated if "critical step" in n]
        self.assertEqual(len(note), 1)
        self.assertIn("%.3g s" % expected, note[0])


class Translation3D(unittest.TestCase):
    """A 2 x 2 x 2 hex8 cube above the plane z = 0 (normal +z)."""

    def setUp(self):
        idx = lambda i, j, k: (k * 3 + j) * 3 + i
        nodes = [[i * H, j * H, k * H + 1e-4] for k in range(3) for j in range(3) for i in range(3)]
        cells = []
        for k in range(2):
            for j in range(2):
                for i in range(2):
                    bottom = [idx(i, j, k), idx(i + 1, j, k), idx(i + 1, j + 1, k), idx(i, j + 1, k)]
                    cells.append(bottom + [v + 9 for v in bottom])
        floor = [idx(i, j, 0) for j in range(3) for i in range(3)]
        self.case = fixture()
        self.case.update({
            "dimension": 3, "plane": None, "nodes": nodes, "velocity": [[1.0, 0.5, -3.0]] * 27,
            "mass": [RHO * H ** 3] * 27, "gravity": [0.0, 0.0, -9.81],
            "bodies": [{"name": "cube", "element": "hex8", "thickness": None, "nodes": [0, 27],
                        "cells": {"hex8": cells},
                        "material": {"model": "neo_hookean", "density": RHO, "young": E, "poisson": NU}}],
            "obstacles": [{"name": "floor", "type": "plane", "point": [0.0, 0.0, 0.0],
                           "normal": [0.0, 0.0, 1.0]}],
            "output": {"interval": 2e-5, "stress_measure": "cauchy",
                       "probes": [{"name": "C", "body": "cube", "node": 4}]},
        })
        self.case["contact"]["candidates"] = [{"node": k, "obstacle": 0, "friction": 0.2,
                                               "stiffness": 1e9 * H * H, "area": H * H} for k in floor]
        self.tr = translate(self.case)

    def test_nodes_elements_faces(self):
        nodes = nodes_of(self.tr.deck)
        self.assertEqual(len(nodes), 27 + len(self.tr.grounds[0].coords))
        np.testing.assert_allclose(nodes[27], [2 * H, 2 * H, 2 * H + 1e-4])
        body = card(self.tr.deck, "*ELEMENT, TYPE=C3D8, ELSET=BODY1")
        self.assertEqual(len(body), 8)
        # Only the four bottom faces (S1) have all their nodes among the candidates.
        self.assertEqual(sorted(card(self.tr.deck, "*SURFACE, NAME=SLAVE1_1")),
                         ["1, S1", "2, S1", "3, S1", "4, S1"])
        self.assertEqual(self.tr.slopes, [[1e9]])
        # The centre node's spring is its 4 faces' quarters, 1e9 x H^2: 2 sqrt(rho H^3 / (1e9 H^2)).
        note = [n for n in self.tr.translated if "critical step" in n][0]
        self.assertIn("%.3g s" % (2 * math.sqrt(RHO * H ** 3 / (1e9 * H * H))), note)
        g = self.tr.grounds[0]
        self.assertTrue(np.isclose(g.coords[:, 2], 0.0).sum() == len(g.coords) // 2)
        self.assertLess(g.coords[:, 0].min(), 0.0)
        self.assertGreater(g.coords[:, 0].max(), 2 * H + 1.0 * 1e-3)
        self.assertGreater(g.coords[:, 1].max(), 2 * H + 0.5 * 1e-3)
        _, dN = cx.hex_shape(np.zeros((1, 3)))
        for key, data in deck_cards(self.tr.deck):
            if key.upper().startswith("*ELEMENT"):
                for line in data:
                    x = np.array([nodes[int(v)] for v in numbers(line)[1:]])
                    self.assertGreater(np.linalg.det(x.T @ dN[0]), 0.0, line)

    def test_velocities_friction_gravity(self):
        got = {tuple(int(v) for v in numbers(line)[:2]): numbers(line)[2]
               for line in card(self.tr.deck, "*INITIAL CONDITIONS, TYPE=VELOCITY")}
        self.assertEqual(len(got), 27 * 3)
        self.assertEqual([got[(27, c)] for c in (1, 2, 3)], [1.0, 0.5, -3.0])
        self.assertEqual(numbers(card(self.tr.deck, "*FRICTION")[0]), [0.2, 1e9])
        self.assertEqual(numbers(card(self.tr.deck, "*DLOAD")[0].split(",", 2)[2]), [9.81, 0.0, 0.0, -1.0])
        cols = cx.history_columns(self.case, self.tr)
        for c in ("momentum_z", "angular_momentum_x", "C_uz", "C_vz", "external_work"):
            self.assertIn(c, cols)
        self.assertNotIn("angular_momentum", cols)

    def test_tilted_plane(self):
        case = copy.deepcopy(self.case)
        n = np.array([0.0, 0.6, 0.8])
        case["obstacles"][0]["normal"] = n.tolist()
        tr = translate(case)
        g = tr.grounds[0]
        heights = (g.coords - 0.0) @ n
        self.assertEqual(int(np.isclose(heights, 0.0, atol=1e-15).sum()), len(g.coords) // 2)
        self.assertAlmostEqual(heights.min(), -g.depth, places=15)


class Rejections(unittest.TestCase):
    def expect(self, case, *words):
        with self.assertRaises(cx.TranslationError) as ctx:
            translate(case)
        message = str(ctx.exception)
        self.assertNotIn("\n", message)
        for w in words:
            self.assertIn(w, message)

    def test_bad_options(self):
        for options, words in [({"procedure": "central"}, ("options.procedure", "explicit", "implicit")),
                               ({"procedure": "implicit", "alpha": 0.5}, ("options.alpha", "[-1/3, 0]")),
                               ({"alpha": -0.1}, ("options.alpha", "implicit")),
                               ({"penalty": -1.0}, ("options.penalty", "> 0")),
                               ({"penalty": "soft"}, ("options.penalty", "ricochet")),
                               ({"stick_slope": 0}, ("options.stick_slope", "> 0")),
                               ({"ground_thickness": "thick"}, ("options.ground_thickness",)),
                               ({"procedur": "explicit"}, ("options.procedur", "unknown", "procedure"))]:
            case = fixture()
            case["options"] = options
            with self.subTest(options=options), self.assertRaises(cx.TranslationError) as ctx:
                cx.parse_options(case["options"])
            for w in words:
                self.assertIn(w, str(ctx.exception))
        self.assertEqual(cx.parse_options({"procedure": "implicit", "alpha": -1.0 / 3.0}).alpha, -1.0 / 3.0)

    def test_blatz_ko(self):
        case = fixture()
        case["bodies"][0]["material"] = {"model": "blatz_ko", "density": RHO, "shear_modulus": 1e6}
        self.expect(case, "blatz_ko has no CalculiX equivalent")

    def test_circle(self):
        case = fixture()
        case["obstacles"][0] = {"name": "post", "type": "circle"}
        self.expect(case, "obstacle 'post'", "circle", "flat")

    def test_body_pairs(self):
        case = fixture()
        case["contact"]["body_pairs"] = [{"slave": "plate", "master": "block", "friction": 0.2}]
        self.expect(case, "body_pairs", "'plate' on 'block'")
        case = fixture()
        case["contact"]["candidates"][0]["obstacle"] = -1
        self.expect(case, "body_pairs")

    def test_prescribed_and_loads(self):
        case = fixture()
        case["prescribed"] = [{"node": 4, "component": 1, "kind": "velocity", "value": 2.0, "ramp": 0.0}]
        self.expect(case, "prescribed", "node 4 component 1")
        case = fixture()
        case["loads"] = [{"node": 4, "component": 1, "force": 2.0, "start": 0.0, "ramp": 0.0}]
        self.expect(case, "loads")

    def test_simplex_cells(self):
        case = fixture()
        case["bodies"][0]["element"] = "t3"
        self.expect(case, "element 't3'")

    def test_keep_dat(self):
        self.assertTrue(cx.parse_options({"keep_dat": True}).keep_dat)
        with self.assertRaises(cx.TranslationError) as ctx:
            cx.parse_options({"keep_dat": "yes"})
        self.assertIn("options.keep_dat", str(ctx.exception))

    def test_no_boundary_area(self):
        case = fixture()
        for c in case["contact"]["candidates"]:
            c["area"] = 0.0
        self.expect(case, "obstacle 'ground'", "no contact candidate with a boundary area", "options.penalty")
        case["options"] = {"penalty": 1e9}
        tr = translate(case)
        self.assertEqual(tr.slopes, [[1e9]])
        self.assertNotIn("nan", tr.deck.lower())

    def test_mixed_friction(self):
        case = fixture()
        case["contact"]["candidates"][0]["friction"] = 0.3
        self.expect(case, "obstacle 'ground'", "different friction")

    def test_main_exit_2_one_line_no_result(self):
        case = fixture()
        case["bodies"][0]["material"] = {"model": "blatz_ko", "density": RHO, "shear_modulus": 1e6}
        with tempfile.TemporaryDirectory() as folder:
            path = os.path.join(folder, "case.json")
            with open(path, "w") as f:
                json.dump(case, f)
            proc = run_adapter(path, folder)
            self.assertEqual(proc.returncode, 2)
            self.assertEqual(len(proc.stderr.strip().splitlines()), 1)
            self.assertIn("blatz_ko", proc.stderr)
            self.assertFalse(os.path.exists(os.path.join(folder, "result.json")))

    def test_main_exit_1_without_ccx(self):
        with tempfile.TemporaryDirectory() as folder:
            path = os.path.join(folder, "case.json")
            with open(path, "w") as f:
                json.dump(fixture(), f)
            proc = run_adapter(path, folder)
            self.assertEqual(proc.returncode, 1)
            self.assertEqual(len(proc.stderr.strip().splitlines()), 1)
            self.assertIn("/nonexistent/ccx", proc.stderr)
            self.assertFalse(os.path.exists(os.path.join(folder, "result.json")))


DAT = """
 displacements (vx,vy,vz) for set NBODIES and time  0.2000000E-04

         1  1.000000E-05 -2.000000E-05  3.000000E-07
        10  1.100000E-05 -2.200000E-05 -3.000000E-07

 velocities (vx,vy,vz) for set NBODIES and time  0.2000000E-04

         1  1.500000E+00 -3.900000E+00  1.000000-100
        10  1.500000E+00 -4.100000E+00  0.000000E+00

 total force (fx,fy,fz) for set NGROUND1 and time  0.2000000E-04

        1.000000E-01  2.500000E+01  0.000000E+00

 total contact spring energy for time  0.2000000E-04

        1.250000E-03

 contact stress (slave node,press,tang1,tang2) for all contact elements and time 0.2000000E-04

         1  3.000000E+05  0.000000E+00  0.000000E+00
        10  0.000000E+00  0.000000E+00  0.000000E+00

 contact print energy (slave node,energy) forall contact elements and time 0.2000000E-04

         1  9.000000E-04

 displacements (vx,vy,vz) for set NBODIES and time  0.4000000E-04

         1  2.000000E-05 -4.000000E-05  0.000000E+00
"""


class Reading(unittest.TestCase):
    def test_parse_dat(self):
        s = cx.parse_dat(DAT)
        self.assertEqual(sorted(s), [2e-5, 4e-5])
        a = s[2e-5]
        self.assertEqual(sorted(a), ["CELS_total", "CSTR", "RF_total", "U", "V"])
        self.assertEqual(a["U"][0].tolist(), [1, 10])
        self.assertEqual(a["U"][1].tolist(), [[1e-5, -2e-5, 3e-7], [1.1e-5, -2.2e-5, -3e-7]])
        self.assertEqual(a["V"][1][0].tolist(), [1.5, -3.9, 1e-100])
        self.assertEqual(a["RF_total"], {"NGROUND1": [0.1, 25.0, 0.0]})
        self.assertEqual(a["CELS_total"], 1.25e-3)
        self.assertEqual(a["CSTR"][0].tolist(), [1, 10])
        self.assertEqual(a["CSTR"][1][:, 0].tolist(), [3e5, 0.0])
        self.assertEqual(set(s[4e-5]), {"U"})
        u = cx._field(a, "U", 12)
        self.assertEqual(u[9].tolist(), [1.1e-5, -2.2e-5, -3e-7])
        self.assertTrue(np.isnan(u[1]).all())

    def test_read_samples_streams_in_order(self):
        times = [t for t, _ in cx.read_samples(iter(DAT.splitlines(keepends=True)))]
        self.assertEqual(times, [2e-5, 4e-5])

    def test_first_error_is_one_line(self):
        out = ("x\n *ERROR in e_c3d: nonpositive jacobian\n        determinant in element          41\n"
               "\n *ERROR again\n")
        self.assertEqual(cx.first_error(out),
                         "*ERROR in e_c3d: nonpositive jacobian determinant in element 41")
        self.assertIsNone(cx.first_error("all good\n"))

    def test_ccx_facts(self):
        out = "CalculiX Version 2.20, Copyright(C) 1998-2022\n SELECTED time increment:1.000000e-06\n"
        self.assertEqual(cx.ccx_facts(out), {"version": "2.20", "increment": 1e-6})


class Writing(unittest.TestCase):
    def test_history_csv(self):
        rows = [{"time": 0.0, "kinetic_energy": 0.5, "normal_force": 0.0},
                {"time": 1e-5, "kinetic_energy": 0.25, "normal_force": 3.0}]
        with tempfile.TemporaryDirectory() as folder:
            path = os.path.join(folder, "history.csv")
            cx.write_history(path, ["time", "kinetic_energy", "normal_force"], rows)
            with open(path) as f:
                lines = f.read().splitlines()
        self.assertEqual(lines, ["time,kinetic_energy,normal_force", "0,0.5,0", "1e-05,0.25,3"])

    def test_contact_summary(self):
        rows = [{"time": t, "normal_force": f, "tangential_force": -0.1 * f}
                for t, f in [(0.0, 0.0), (1e-5, 0.0), (2e-5, 10.0), (3e-5, 20.0), (4e-5, 0.0)]]
        s = cx.contact_summary(rows)
        # trapezoids: 5e-5 + 1.5e-4 + 1e-4
        self.assertAlmostEqual(s["contact_impulse_normal"], 3e-4, places=15)
        self.assertAlmostEqual(s["contact_impulse_tangential"], -3e-5, places=15)
        self.assertEqual((s["contact_start_time"], s["contact_end_time"]), (2e-5, 3e-5))
        self.assertAlmostEqual(s["contact_duration"], 1e-5, places=15)


class PostProcessing(unittest.TestCase):
    def test_svk_uniaxial(self):
        lam, mu = cx.lame(E, NU)
        F = np.diag([1.1, 1.0, 1.0])
        S, W = cx.pk2_and_energy(F, {"model": "saint_venant_kirchhoff", "young": E, "poisson": NU})
        e = 0.5 * (1.1 ** 2 - 1)
        np.testing.assert_allclose(S, np.diag([lam * e + 2 * mu * e, lam * e, lam * e]), rtol=1e-13)
        self.assertAlmostEqual(W / (0.5 * lam * e * e + mu * e * e), 1.0, places=12)
        self.assertAlmostEqual(cx.von_mises(S), 2 * mu * e, delta=1e-6 * mu * e)

    def test_mooney_rivlin_small_strain_and_energy(self):
        m = {"model": "mooney_rivlin", "c10": 1e5, "c01": 2e4, "bulk_modulus": 5e6}
        mu, kappa = 2 * (1e5 + 2e4), 5e6
        S0, W0 = cx.pk2_and_energy(np.eye(3), m)
        self.assertLess(np.abs(S0).max(), 1e-6)
        self.assertLess(abs(W0), 1e-9)
        eps = 1e-6 * np.array([[1.0, 0.3, 0.0], [0.3, -0.5, 0.2], [0.0, 0.2, 0.4]])
        S, _ = cx.pk2_and_energy(np.eye(3) + eps, m)
        linear = (kappa - 2 * mu / 3) * np.trace(eps) * np.eye(3) + 2 * mu * eps
        np.testing.assert_allclose(S, linear, rtol=0, atol=1e-4 * np.abs(linear).max())
        # S = 2 dW/dC: a finite difference of W along a symmetric direction.
        F = np.array([[1.1, 0.2, 0.0], [0.05, 0.9, 0.1], [0.0, -0.1, 1.05]])
        C = F.T @ F
        D = np.array([[0.3, 0.1, 0.0], [0.1, -0.2, 0.05], [0.0, 0.05, 0.1]])
        h = 1e-6
        w = lambda c: cx.pk2_and_energy(np.linalg.cholesky(c).T, m)[1]
        dW = (w(C + h * D) - w(C - h * D)) / (2 * h)
        S, _ = cx.pk2_and_energy(F, m)
        self.assertAlmostEqual(0.5 * np.sum(S * D) / dW, 1.0, places=6)

    def test_rigid_translation_sample(self):
        case = fixture()
        tr = translate(case)
        n = len(tr.bricks.coords)
        shift = np.array([2e-4, -3e-4, 0.0])
        U = np.tile(shift, (n, 1))
        V = np.tile([V0[0], V0[1], 0.0], (n, 1))
        ids = np.arange(1, n + 1)
        sample = {"U": (ids, U), "V": (ids, V), "RF_total": {"NGROUND1": [0.5, 30.0, 0.0]},
                  "CELS_total": 2e-3,
                  "CSTR": (np.array([1, 10, 2]), np.array([[1e5, 0, 0], [2e5, 0, 0], [0.0, 0, 0]]))}
        rows, bad = cx.build_history(case, tr, [(2.0000001e-5, sample)], 2e-6)
        self.assertIsNone(bad)
        self.assertEqual([r["time"] for r in rows], [0.0, 2e-5])     # k dt, printed time rounded
        r = rows[1]
        M = sum(case["mass"])
        self.assertLess(r["strain_energy"], 1e-20)
        self.assertLess(r["von_mises_max"], 1e-6)
        self.assertAlmostEqual(r["kinetic_energy"], 0.5 * M * (V0[0] ** 2 + V0[1] ** 2), places=12)
        self.assertAlmostEqual(r["momentum_y"], M * V0[1], places=12)
        self.assertAlmostEqual(r["P_uy"], shift[1], places=15)
        self.assertEqual(r["P_vx"], V0[0])
        self.assertEqual(r["normal_force"], 30.0)            # reaction along +y: pushes the plate up
        self.assertEqual(r["tangential_force"], 0.5)         # along t = (n_y, -n_x) = (1, 0)
        self.assertEqual(r["contact_nodes"], 1)              # node 0's two copies count once
        self.assertEqual(r["contact_energy"], 2e-3)
        self.assertAlmostEqual(r["penetration_max"], 3e-4 - 1e-4, places=15)
        # A non-finite sample ends the history there, with a reason.
        broken = dict(sample, U=(ids, np.where(np.arange(n)[:, None] == 3, np.nan, U)))
        rows2, bad2 = cx.build_history(case, tr, [(2e-5, sample), (4e-5, broken)], 2e-6)
        self.assertEqual(len(rows2), 2)
        self.assertIn("non-finite", bad2)
        cols = cx.history_columns(case, tr)
        self.assertEqual(cols[0], "time")
        self.assertNotIn("friction_dissipation", cols)
        self.assertTrue(set(cols) <= set(r))


if __name__ == "__main__":
    unittest.main()
