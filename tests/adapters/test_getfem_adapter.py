#!/usr/bin/env python3
"""Tests of the GetFEM adapter (adapters/getfem.py): the translation of a case.json into the
GetFEM model, checked without the time loop, and a few short time loops on a tiny plate.

Run: /usr/bin/python3 tests/adapters/test_getfem_adapter.py   (exit 0 when every test passes)

The fixture is a hand-written case.json (docs/peers.md, "case.json: what the adapter is given"):
a 0.02 m x 0.02 m plate of 2 x 2 quadrilaterals, its 9 nodes numbered in a scrambled order so that
GetFEM's dof numbering (by convex) cannot coincide with the case's node order by accident.
"""

import importlib.util
import json
import math
import os
import subprocess
import sys
import tempfile
import unittest

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ADAPTER = os.path.normpath(os.path.join(HERE, "..", "..", "adapters", "getfem.py"))


def load_adapter():
    # The adapter's file is named getfem.py like GetFEM's package: load it under another name
    # (and leave no compiled copy in adapters/).
    sys.dont_write_bytecode = True
    spec = importlib.util.spec_from_file_location("ricochet_getfem_adapter", ADAPTER)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


ga = load_adapter()

E, NU, RHO, THICK = 1.0e7, 0.25, 1000.0, 0.01
LAMBDA3 = E * NU / ((1 + NU) * (1 - 2 * NU))  # 4e6
MU = E / (2 * (1 + NU))  # 4e6
# Grid node (i, j), i along x, j along y, has the case index PERM[j * 3 + i].
PERM = [4, 7, 0, 8, 2, 5, 1, 6, 3]


def plate_case(y0=0.001, velocity=None, friction=0.0, options=None, plane="stress"):
    """The 2 x 2 plate: nodes at x = 0, 0.01, 0.02 and y = y0, y0 + 0.01, y0 + 0.02."""
    nodes = [None] * 9
    grid = lambda i, j: PERM[j * 3 + i]
    for j in range(3):
        for i in range(3):
            nodes[grid(i, j)] = [0.01 * i, y0 + 0.01 * j]
    quads = [[grid(i, j), grid(i + 1, j), grid(i + 1, j + 1), grid(i, j + 1)] for j in range(2) for i in range(2)]
    # Lumped (row-sum) masses: a quarter cell at a corner, half at an edge, one at the centre.
    cell = RHO * THICK * 0.01 * 0.01
    mass = [0.0] * 9
    for q in quads:
        for n in q:
            mass[n] += cell / 4
    if velocity is None:
        velocity = [[0.1 * k, -1.0 - 0.2 * k] for k in range(9)]
    boundary = [grid(i, j) for j in range(3) for i in range(3) if (i, j) != (1, 1)]
    # Stiffness / area ratios (k + 1)^2 1e9, k = 0 ... 7: the median is 20.5e9 (the mean 25.5e9).
    candidates = [{"node": n, "obstacle": 0, "friction": friction, "stiffness": 1e3 * (k + 1) ** 2, "area": 1e-6}
                  for k, n in enumerate(boundary)]
    return {
        "format": "ricochet-external-case", "version": 1, "case": "tiny_plate", "case_file": "/tmp/tiny_plate.toml",
        "scheme": "getfem", "dimension": 2, "plane": plane,
        "nodes": nodes, "velocity": velocity, "mass": mass,
        "bodies": [{"name": "plate", "element": "q4", "thickness": THICK, "nodes": [0, 9],
                    "cells": {"quad4": quads},
                    "material": {"model": "saint_venant_kirchhoff", "density": RHO, "young": E, "poisson": NU}}],
        "gravity": [0.0, 0.0], "prescribed": [], "loads": [],
        "obstacles": [{"name": "ground", "type": "line", "point": [0.0, 0.0], "normal": [0.0, 1.0]}],
        "contact": {"candidates": candidates, "penalty_scale_factor": 0.1, "body_pairs": []},
        "time": {"dt": 1e-5, "end": 1e-4, "steps": 10, "dt_auto": False, "critical_dt": 2e-6},
        "output": {"interval": 2e-5, "stress_measure": "pk2",
                   "probes": [{"name": "corner", "body": "plate", "node": grid(2, 2)}]},
        "threads": 1, "options": options if options is not None else {},
    }


def grid_node(i, j):
    return PERM[j * 3 + i]


def assert_one_line_rejection(test, case, *words):
    """describe(case) raises Unsupported with one line naming every word."""
    with test.assertRaises(ga.Unsupported) as ctx:
        ga.describe(case)
    msg = str(ctx.exception)
    test.assertNotIn("\n", msg)
    for w in words:
        test.assertIn(w, msg)
    return msg


class Translation(unittest.TestCase):
    """case.json -> the plain description -> the GetFEM model."""

    @classmethod
    def setUpClass(cls):
        cls.case = plate_case()
        cls.d = ga.describe(cls.case)
        cls.p = ga.build(cls.d)

    def test_mesh_counts_and_coordinates_in_case_order(self):
        mesh = self.p.mesh
        self.assertEqual(mesh.nbpts(), 9)
        self.assertEqual(mesh.nbcvs(), 4)
        np.testing.assert_array_equal(mesh.pts().T, np.asarray(self.case["nodes"]))
        # Each convex is a case cell, its corners in GetFEM's tensor order (VTK 0, 1, 3, 2).
        pid, idx = mesh.pid_from_cvid(np.arange(4))
        for k, q in enumerate(self.case["bodies"][0]["cells"]["quad4"]):
            self.assertEqual(list(pid[idx[k]:idx[k + 1]]), [q[0], q[1], q[3], q[2]])
        self.assertEqual(self.p.mf.nbdof(), 18)

    def test_dofs_map_to_their_nodes(self):
        xyz = self.p.mf.basic_dof_nodes()
        nodes = np.asarray(self.case["nodes"])
        for c in range(2):
            np.testing.assert_array_equal(xyz[:, self.p.node_dofs[:, c]].T, nodes)
        self.assertEqual(len(set(self.p.node_dofs.ravel())), 18)
        # The scrambled numbering really differs from GetFEM's.
        self.assertFalse(np.array_equal(self.p.node_dofs[:, 0], 2 * np.arange(9)))

    def test_material_constants(self):
        c = self.d.bodies[0].material.constants
        self.assertAlmostEqual(c["lambda_3d"], LAMBDA3, delta=1e-6)
        self.assertAlmostEqual(c["mu"], MU, delta=1e-6)
        self.assertAlmostEqual(c["lambda"], 2 * LAMBDA3 * MU / (LAMBDA3 + 2 * MU), delta=1e-6)  # plane stress
        self.assertAlmostEqual(c["e33_per_trace"], -LAMBDA3 / (LAMBDA3 + 2 * MU), places=15)
        strain = ga.describe(plate_case(plane="strain")).bodies[0].material.constants
        self.assertAlmostEqual(strain["lambda"], LAMBDA3, delta=1e-6)
        self.assertEqual(self.d.bodies[0].thickness, THICK)
        self.assertEqual(self.d.bodies[0].material.density, RHO)

    def _uniaxial(self, eps):
        """Set u = (eps X, 0): E11 = eps + eps^2/2, every other E component 0."""
        u = np.zeros(18)
        u[self.p.node_dofs[:, 0]] = eps * np.asarray(self.case["nodes"])[:, 0]
        self.p.md.set_variable("u", u)
        return eps + eps * eps / 2

    def test_plane_stress_energy_and_pk2_von_mises(self):
        e11 = self._uniaxial(0.05)
        lam = 2 * LAMBDA3 * MU / (LAMBDA3 + 2 * MU)
        w = (lam / 2 + MU) * e11 ** 2
        obs = ga.Observer(self.d, self.p, ga.Stepper(self.d, self.p))
        self._uniaxial(0.05)  # the Stepper reset u
        self.assertAlmostEqual(obs.strain_energy() / (w * 0.02 * 0.02 * THICK), 1.0, places=12)
        s11, s22 = (lam + 2 * MU) * e11, lam * e11  # S33 = 0 in plane stress
        self.assertAlmostEqual(obs.von_mises() / math.sqrt(s11 ** 2 - s11 * s22 + s22 ** 2), 1.0, places=12)

    def test_plane_strain_von_mises_includes_the_out_of_plane_stress(self):
        # Plane strain, u = (eps X, 0): S11 = (lambda + 2 mu) E11, S22 = S33 = lambda E11, so the
        # von Mises equivalent of S is 2 mu E11 (without S33 it would be sqrt(S11^2 - S11 S22 + S22^2)).
        d = ga.describe(plate_case(plane="strain"))
        p = ga.build(d)
        obs = ga.Observer(d, p, ga.Stepper(d, p))
        u = np.zeros(18)
        u[p.node_dofs[:, 0]] = 0.05 * np.asarray(self.case["nodes"])[:, 0]
        p.md.set_variable("u", u)
        e11 = 0.05 + 0.05 ** 2 / 2
        self.assertAlmostEqual(obs.von_mises() / (2 * MU * e11), 1.0, places=12)
        self.assertAlmostEqual(obs.strain_energy() / ((LAMBDA3 / 2 + MU) * e11 ** 2 * 0.02 * 0.02 * THICK), 1.0,
                               places=12)

    def test_angular_momentum_about_the_centre_of_mass(self):
        # Spinning at omega about the plate's centre c while translating: L = omega m (a^2 + b^2) / 12
        # (a linear velocity field is exact in the bilinear elements, so is the integral).
        nodes = np.asarray(self.case["nodes"])
        c, omega = nodes.mean(0), 7.0
        vel = [[3.0 - omega * (y - c[1]), -5.0 + omega * (x - c[0])] for x, y in nodes]
        d = ga.describe(plate_case(velocity=vel))
        p = ga.build(d)
        obs = ga.Observer(d, p, ga.Stepper(d, p))
        _, l = obs.momenta()
        m = RHO * THICK * 0.02 * 0.02
        self.assertAlmostEqual(l[0] / (omega * m * (0.02 ** 2 + 0.02 ** 2) / 12), 1.0, places=12)

    def test_first_piola_is_the_derivative_of_the_energy(self):
        # The internal force (assembled from P) against a central difference of the energy (W).
        obs = ga.Observer(self.d, self.p, ga.Stepper(self.d, self.p))
        rng = np.random.default_rng(1)
        u0, w = 0.02 * rng.standard_normal(18) * 0.01, rng.standard_normal(18) * 1e-3
        law = self.p.laws[0]
        md, mim = self.p.md, self.p.mim
        md.set_variable("u", u0)
        f = ga.import_getfem().asm_generic(mim, 1, f"{THICK}*({law['P']}:Grad_Test_u)", ga.BODY_REGION0, md)
        h = 1e-4
        md.set_variable("u", u0 + h * w)
        wp = obs.strain_energy()
        md.set_variable("u", u0 - h * w)
        wm = obs.strain_energy()
        self.assertAlmostEqual(((wp - wm) / (2 * h)) / float(np.asarray(f).ravel() @ w), 1.0, places=6)

    def test_initial_velocity_field_and_mass(self):
        st = ga.Stepper(self.d, self.p)
        vel = np.asarray(self.case["velocity"])
        for node in range(9):
            for c in range(2):
                self.assertEqual(st.v[self.p.node_dofs[node, c]], vel[node, c])
        # Consistent mass on a uniform grid: its row sums are the lumped masses, so the momentum
        # is sum of m_i v_i with the case's masses.
        obs = ga.Observer(self.d, self.p, st)
        p, _ = obs.momenta()
        expected = np.asarray(self.case["mass"]) @ vel
        np.testing.assert_allclose(p, expected, rtol=1e-13)
        self.assertAlmostEqual(obs.total_mass(), RHO * THICK * 0.02 * 0.02, places=15)
        ke = 0.5 * st.v @ self.p.mass.mult(st.v).ravel()
        lumped = 0.5 * np.asarray(self.case["mass"]) @ (vel ** 2).sum(1)
        self.assertLess(ke, lumped)  # a consistent mass gives less kinetic energy to a non-uniform field
        self.assertGreater(ke, 0.8 * lumped)

    def test_penalty_default_explicit_and_ricochet(self):
        self.assertEqual(self.d.penalty, 2e11)
        self.assertEqual(self.d.penalty_source, "default")
        self.assertEqual(ga.describe(plate_case(options={"penalty": 3.5e10})).penalty, 3.5e10)
        # ricochet: the median of stiffness / area over the candidates, (16e9 + 25e9) / 2.
        self.assertAlmostEqual(ga.describe(plate_case(options={"penalty": "ricochet"})).penalty, 20.5e9, delta=1e-3)

    def test_contact_faces_are_the_ground_candidates_faces(self):
        # All 8 boundary edges have both ends among the candidates.
        self.assertEqual([c["faces"] for c in self.p.contacts], [8])
        d = ga.describe(plate_case())
        ob = d.obstacles[0]
        self.assertEqual(sorted(ob.nodes), sorted(n for n in range(9) if n != grid_node(1, 1)))
        np.testing.assert_array_equal(ob.normal, [0.0, 1.0])

    def test_time_step_and_newmark_parameters(self):
        self.assertEqual((self.d.dt, self.d.end, self.d.steps), (1e-5, 1e-4, 10))
        self.assertEqual((self.d.beta, self.d.gamma), (0.25, 0.5))
        d = ga.describe(plate_case(options={"beta": 0.3025, "gamma": 0.6}))
        self.assertEqual((d.beta, d.gamma), (0.3025, 0.6))
        # The inertia part of the Newton matrix is M / (beta dt^2): two steps' matrices differ by
        # M (1/dt1^2 - 1/dt2^2) / beta, the stiffness cancelling.
        st = ga.Stepper(self.d, self.p)
        self.p.md.set_variable("u", np.zeros(18))
        k = []
        for dt in (1e-5, 2e-5):
            st.set_mass_matrix(dt)
            self.p.md.assembly("build_matrix")
            k.append(self.p.md.tangent_matrix().full())
        m = self.p.mass.full()
        np.testing.assert_allclose(k[0] - k[1], m * (1 / 1e-10 - 1 / 4e-10) / 0.25, rtol=1e-9, atol=1e-9 * m.max() / 1e-10)

    def test_samples_follow_ricochet(self):
        self.assertEqual(sorted(ga.sample_steps(self.d)), [0, 2, 4, 6, 8, 10])
        d = ga.describe(plate_case())
        d.interval = 0.0
        self.assertEqual(sorted(ga.sample_steps(d)), list(range(11)))

    def test_triangles(self):
        # The same plate cut into 8 triangles: GT_PK(2,1) convexes, the same boundary edges, and
        # a uniform stretch's energy exactly W x area x thickness.
        case = plate_case()
        tris = [t for q in case["bodies"][0]["cells"]["quad4"] for t in ([q[0], q[1], q[2]], [q[0], q[2], q[3]])]
        case["bodies"][0].update(element="t3", cells={"tri3": tris})
        d = ga.describe(case)
        p = ga.build(d)
        self.assertEqual((p.mesh.nbpts(), p.mesh.nbcvs(), p.mf.nbdof()), (9, 8, 18))
        self.assertEqual([c["faces"] for c in p.contacts], [8])
        obs = ga.Observer(d, p, ga.Stepper(d, p))
        # The triangles' face quadrature: the contact faces' length is the perimeter.
        self.assertAlmostEqual(obs.integral("1", p.contacts[0]["region"]), 0.08, places=14)
        u = np.zeros(18)
        u[p.node_dofs[:, 0]] = 0.05 * np.asarray(case["nodes"])[:, 0]
        p.md.set_variable("u", u)
        lam = 2 * LAMBDA3 * MU / (LAMBDA3 + 2 * MU)
        e11 = 0.05 + 0.05 ** 2 / 2
        self.assertAlmostEqual(obs.strain_energy() / ((lam / 2 + MU) * e11 ** 2 * 0.02 * 0.02 * THICK), 1.0, places=12)
        # A linear triangle's consistent mass rows sum to a third of its mass at each corner.
        nodes = np.asarray(case["nodes"])
        lumped = np.zeros(9)
        for t in tris:
            a, b, c = nodes[t]
            lumped[t] += RHO * THICK * 0.5 * abs(np.cross(b - a, c - a)) / 3
        p_total, _ = obs.momenta()
        np.testing.assert_allclose(p_total, lumped @ np.asarray(case["velocity"]), rtol=1e-13)

    def test_3d_hexahedron(self):
        # One unit hexahedron (VTK order) with a spin: 8 nodes, 1 cell, mass rho.
        pts = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]]
        case = plate_case()
        case.update(dimension=3, plane=None, nodes=pts, velocity=[[-p[1], p[0], 0.0] for p in pts],
                    mass=[125.0] * 8, gravity=[0.0, 0.0, 0.0], obstacles=[], contact={"candidates": [], "body_pairs": []})
        case["bodies"][0].update(element="hex8", thickness=None, cells={"hex8": [list(range(8))]})
        case["output"]["probes"] = []
        d = ga.describe(case)
        p = ga.build(d)
        self.assertEqual((p.mesh.nbpts(), p.mesh.nbcvs(), p.mf.nbdof()), (8, 1, 24))
        pid, _ = p.mesh.pid_from_cvid([0])
        self.assertEqual(list(pid), [0, 1, 3, 2, 4, 5, 7, 6])
        obs = ga.Observer(d, p, ga.Stepper(d, p))
        _, l = obs.momenta()
        # L_z of a unit cube (mass 1000) spinning at 1 rad/s about its edge x = y = 0, taken
        # about its centre of mass: I_zz = m (1 + 1) / 12.
        np.testing.assert_allclose(l, [0.0, 0.0, 1000.0 / 6.0], atol=1e-9)


# ---- the laws, independently: ricochet's 3D strain energies (solver/materials/material3d.hpp)
# in numpy, the stresses by central differences, the plane reductions by solving S33 = 0.

LAWS = {  # model -> (case.json material constants, W3D(F))
    "saint_venant_kirchhoff": ({"young": E, "poisson": NU},
                               lambda F: (lambda G: LAMBDA3 / 2 * np.trace(G) ** 2 + MU * np.sum(G * G))(
                                   (F.T @ F - np.eye(3)) / 2)),
    "neo_hookean": ({"young": E, "poisson": NU},
                    lambda F: MU / 2 * (np.sum(F * F) - 3) - MU * np.log(np.linalg.det(F))
                    + LAMBDA3 / 2 * np.log(np.linalg.det(F)) ** 2),
    "blatz_ko": ({"shear_modulus": MU},
                 lambda F: MU / 2 * (np.trace(np.linalg.inv(F.T @ F)) + 2 * np.linalg.det(F) - 5)),
    "mooney_rivlin": ({"c10": 1.5e6, "c01": 0.5e6, "bulk_modulus": 2e7},
                      lambda F: (lambda J, C: 1.5e6 * (J ** (-2 / 3) * np.trace(C) - 3)
                                 + 0.5e6 * (J ** (-4 / 3) * (np.trace(C) ** 2 - np.trace(C @ C)) / 2 - 3)
                                 + 1e7 * (J - 1) ** 2)(np.linalg.det(F), F.T @ F)),
}


def first_piola(w, F, h=1e-6):
    P = np.zeros((3, 3))
    for i in range(3):
        for j in range(3):
            dF = np.zeros((3, 3))
            dF[i, j] = h
            P[i, j] = (w(F + dF) - w(F - dF)) / (2 * h)
    return P


def plane_stress_stretch(w, F2):
    """F33 with S33 = 0 (dW/dF33 = 0), by the secant method on the central difference."""
    def s33(f33):
        F = np.eye(3)
        F[:2, :2], F[2, 2] = F2, f33
        return first_piola(w, F)[2, 2]
    a, b = 1.0, 0.99
    for _ in range(50):
        fa, fb = s33(a), s33(b)
        if fb == fa:
            break
        a, b = b, b - fb * (b - a) / (fb - fa)
        if abs(b - a) < 1e-13:
            break
    return b


def von_mises(A):
    A = (A + A.T) / 2
    dev = A - np.trace(A) / 3 * np.eye(3)
    return math.sqrt(1.5 * np.sum(dev * dev))


def reference_state(model, F3, measure):
    """(W, von Mises of `measure`) of ricochet's law at the 3D deformation gradient F3."""
    w = LAWS[model][1]
    P = first_piola(w, F3)
    J = np.linalg.det(F3)
    stress = {"pk2": np.linalg.solve(F3, P), "kirchhoff": P @ F3.T, "cauchy": P @ F3.T / J}[measure]
    return w(F3), von_mises(stress)


class Laws(unittest.TestCase):
    """Each translated law against ricochet's definitions, at a homogeneous deformation."""

    F2 = np.array([[1.06, 0.08], [-0.03, 0.95]])

    def check(self, case, F, area_or_volume, thickness, model, measure, F3):
        d = ga.describe(case)
        p = ga.build(d)
        obs = ga.Observer(d, p, ga.Stepper(d, p))
        nodes = np.asarray(case["nodes"])
        u = np.zeros(p.mf.nbdof())
        disp = nodes @ (F - np.eye(len(F))).T
        for c in range(len(F)):
            u[p.node_dofs[:, c]] = disp[:, c]
        p.md.set_variable("u", u)
        w_ref, vm_ref = reference_state(model, F3, measure)
        self.assertAlmostEqual(obs.strain_energy() / (w_ref * area_or_volume * thickness), 1.0, places=7)
        self.assertAlmostEqual(obs.von_mises() / vm_ref, 1.0, places=6)

    def test_internal_force_is_the_energy_derivative_for_every_law(self):
        # The weak form (P) against a central difference of the strain energy (W) at a random
        # displacement of the plate, for each translated 2D law.
        rng = np.random.default_rng(3)
        u0, du = 2e-4 * rng.standard_normal(18), 1e-3 * rng.standard_normal(18)
        for model, (constants, _) in LAWS.items():
            for plane in ("strain", "stress"):
                if plane == "stress" and model in ("neo_hookean", "mooney_rivlin"):
                    continue
                with self.subTest(model=model, plane=plane):
                    case = plate_case(plane=plane)
                    case["bodies"][0]["material"] = dict(constants, model=model, density=RHO)
                    d = ga.describe(case)
                    p = ga.build(d)
                    obs = ga.Observer(d, p, ga.Stepper(d, p))
                    p.md.set_variable("u", u0)
                    f = ga.import_getfem().asm_generic(p.mim, 1, f"{THICK}*({p.laws[0]['P']}:Grad_Test_u)",
                                                       ga.BODY_REGION0, p.md)
                    h = 1e-4
                    p.md.set_variable("u", u0 + h * du)
                    wp = obs.strain_energy()
                    p.md.set_variable("u", u0 - h * du)
                    wm = obs.strain_energy()
                    self.assertAlmostEqual(((wp - wm) / (2 * h)) / float(np.asarray(f).ravel() @ du), 1.0, places=6)

    def test_plane_strain_plane_stress_and_3d(self):
        for model, (constants, w) in LAWS.items():
            for plane in ("strain", "stress", "3d"):
                if plane == "stress" and model in ("neo_hookean", "mooney_rivlin"):
                    continue  # not translated (Rejections)
                for measure in ("pk2", "cauchy", "kirchhoff"):
                    with self.subTest(model=model, plane=plane, measure=measure):
                        material = dict(constants, model=model, density=RHO)
                        if plane == "3d":
                            pts = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]]
                            case = plate_case()
                            case.update(dimension=3, plane=None, nodes=pts, velocity=[[0.0] * 3] * 8, mass=[125.0] * 8,
                                        gravity=[0.0] * 3, obstacles=[], contact={"candidates": [], "body_pairs": []})
                            case["bodies"][0].update(element="hex8", thickness=None, cells={"hex8": [list(range(8))]},
                                                     material=material)
                            case["output"].update(stress_measure=measure, probes=[])
                            F3 = np.array([[1.06, 0.08, 0.02], [-0.03, 0.95, 0.04], [0.01, -0.05, 1.03]])
                            self.check(case, F3, 1.0, 1.0, model, measure, F3)
                        else:
                            case = plate_case(plane=plane)
                            case["bodies"][0]["material"] = material
                            case["output"]["stress_measure"] = measure
                            F3 = np.eye(3)
                            F3[:2, :2] = self.F2
                            if plane == "stress":
                                F3[2, 2] = plane_stress_stretch(w, self.F2)
                            self.check(case, self.F2, 0.02 * 0.02, THICK, model, measure, F3)


class Rejections(unittest.TestCase):
    """What the adapter does not translate: one line naming it."""

    def test_bad_options(self):
        assert_one_line_rejection(self, plate_case(options={"beta": 0.0}), "options.beta", "(0, 0.5]")
        assert_one_line_rejection(self, plate_case(options={"gamma": 0.3}), "options.gamma")
        assert_one_line_rejection(self, plate_case(options={"penalty": "stiff"}), "options.penalty", "ricochet")
        assert_one_line_rejection(self, plate_case(options={"penalty": -1.0}), "options.penalty")
        assert_one_line_rejection(self, plate_case(options={"newton_max_iter": 2.5}), "options.newton_max_iter")
        assert_one_line_rejection(self, plate_case(options={"sheme": "x"}), "options.sheme", "unknown", "penalty")

    def test_unsupported_materials(self):
        case = plate_case()
        case["bodies"][0]["material"]["model"] = "ogden"
        assert_one_line_rejection(self, case, "ogden", "saint_venant_kirchhoff")
        case = plate_case()
        case["bodies"][0]["material"] = {"model": "neo_hookean", "density": RHO, "young": E, "poisson": NU}
        assert_one_line_rejection(self, case, "neo_hookean", "plane stress")
        case["plane"] = "strain"
        self.assertEqual(ga.describe(case).bodies[0].material.model, "neo_hookean")

    def test_circle_obstacle(self):
        case = plate_case()
        case["obstacles"].append({"name": "post", "type": "circle"})
        assert_one_line_rejection(self, case, "post", "circle")

    def test_body_pairs(self):
        case = plate_case()
        case["contact"]["body_pairs"] = [{"slave": "plate", "master": "block", "friction": 0.0}]
        assert_one_line_rejection(self, case, "body_pairs", "plate")

    def test_several_friction_coefficients_on_one_obstacle(self):
        case = plate_case(friction=0.1)
        case["contact"]["candidates"][0]["friction"] = 0.2
        assert_one_line_rejection(self, case, "ground", "friction")

    def test_command_line_exit_2_one_line_no_result(self):
        case = plate_case()
        case["obstacles"][0]["type"] = "polyline"
        with tempfile.TemporaryDirectory() as out:
            path = os.path.join(out, "case.json")
            with open(path, "w") as f:
                json.dump(case, f)
            r = subprocess.run([sys.executable, ADAPTER, path, out], cwd=out, capture_output=True, text=True)
            self.assertEqual(r.returncode, 2, r.stderr)
            self.assertEqual(len(r.stderr.strip().splitlines()), 1)
            self.assertIn("polyline", r.stderr)
            self.assertFalse(os.path.exists(os.path.join(out, "result.json")))


def run_steps(case, steps):
    d = ga.describe(case)
    p = ga.build(d)
    st = ga.Stepper(d, p)
    obs = ga.Observer(d, p, st)
    obs.sample()
    for _ in range(steps):
        why = st.step(d.dt)
        assert why is None, why
        obs.after_step(d.dt, True)
        obs.sample()
    cols = {c: np.array([r[k] for r in obs.rows]) for k, c in enumerate(obs.columns)}
    return d, st, obs, cols


class TimeLoop(unittest.TestCase):
    """A few steps of the tiny plate."""

    def test_free_flight_conserves_momentum_and_energy(self):
        # 5 cm above the ground, spinning and stretching: no contact in 10 steps.
        vel = [[3.0 - 50 * (y - 0.06), -5.0 + 50 * x] for x, y in plate_case(y0=0.05)["nodes"]]
        vel[grid_node(2, 2)][0] += 2.0  # and one node moving off: the plate deforms
        d, st, obs, h = run_steps(plate_case(y0=0.05, velocity=vel), 10)
        self.assertEqual(h["normal_force"].max(), 0.0)
        for c in ("momentum_x", "momentum_y"):
            np.testing.assert_allclose(h[c], h[c][0], rtol=1e-12, atol=1e-16)
        self.assertGreater(h["strain_energy"][-1], 1e-4 * h["total_energy"][0])  # it did deform
        drift = np.abs(h["total_energy"] - h["total_energy"][0]).max() / h["total_energy"][0]
        self.assertLess(drift, 1e-5)
        # Newmark's trapezoidal rule conserves the angular momentum of a body up to the
        # (small) error of its position update.
        self.assertLess(np.abs(h["angular_momentum"] - h["angular_momentum"][0]).max(),
                        1e-4 * abs(h["angular_momentum"][0]))
        # The probe columns are the probe node's displacement.
        corner = grid_node(2, 2)
        self.assertEqual(h["corner_ux"][-1], st.u[st.p.node_dofs[corner, 0]])

    def test_impact_pushes_back_and_keeps_energy(self):
        # Touching the ground at t = 0, falling at 1 m/s, with r = 2e9 N/m^3 and dt = 2e-6.
        case = plate_case(y0=0.0, velocity=[[0.0, -1.0]] * 9, options={"penalty": 2e9})
        case["time"].update(dt=2e-6, end=2e-4, steps=100)
        d, st, obs, h = run_steps(case, 100)
        self.assertGreater(h["normal_force"].max(), 0.0)
        self.assertGreater(h["penetration_max"].max(), 0.0)
        self.assertGreater(h["momentum_y"][-1], h["momentum_y"][0])  # the ground pushes up
        # A symmetric frictionless impact: no horizontal momentum, up to round-off.
        self.assertLess(np.abs(h["momentum_x"]).max(), 1e-12 * np.abs(h["momentum_y"]).max())
        # The contact impulse is the momentum the plate gained.
        self.assertAlmostEqual(obs.impulse_n / (h["momentum_y"][-1] - h["momentum_y"][0]), 1.0, places=9)
        balance = h["total_energy"] + h["contact_energy"]
        self.assertLess(np.abs(balance - balance[0]).max() / balance[0], 2e-5)

    def test_friction_opposes_sliding_and_dissipates(self):
        # Pressed onto the ground (falling at 1 m/s) while sliding along +x at 2 m/s, mu = 0.3.
        case = plate_case(y0=0.0, velocity=[[2.0, -1.0]] * 9, friction=0.3, options={"penalty": 2e9})
        case["time"].update(dt=2e-6, end=1e-4, steps=50)
        d, st, obs, h = run_steps(case, 50)
        contact = h["normal_force"] > 0
        self.assertTrue(contact.any())
        # t = (n_y, -n_x) = (1, 0): the friction on the body points along -x.
        self.assertLess(h["tangential_force"][contact].max(), 0.0)
        self.assertTrue(np.all(np.abs(h["tangential_force"]) <= 0.3 * h["normal_force"] * (1 + 1e-9) + 1e-12))
        self.assertLess(h["momentum_x"][-1], h["momentum_x"][0])
        self.assertGreater(h["friction_dissipation"][-1], 0.0)
        # Energy balance with the slip work counted.
        balance = h["total_energy"] + h["contact_energy"] + h["friction_dissipation"]
        self.assertLess(np.abs(balance - balance[0]).max() / balance[0], 2e-3)  # the slip work is 6 %

    def test_friction_state_is_stored_point_by_point(self):
        # The traction stored after a step (im_data on the contact faces) is, point by point, the
        # traction the weak form computes at that state: with no further slip (u_n = u) the
        # return map gives it back unchanged. A scrambled store would not.
        case = plate_case(y0=0.0, velocity=[[0.5, -1.0]] * 9, friction=0.3, options={"penalty": 2e9})
        d, st, obs, h = run_steps(case, 20)
        c = st.p.contacts[0]
        stored = np.asarray(st.p.md.variable("ft0_0")).ravel()
        self.assertGreater(np.abs(stored).max(), 0.0)
        st.p.md.set_variable("u_n", st.u)
        again = np.asarray(st.p.md.interpolation(c["expr"]["ft"], c["mimd"], c["region"])).ravel()
        np.testing.assert_allclose(again, stored, rtol=1e-12, atol=1e-12 * np.abs(stored).max())

    def test_prescribed_motion_gravity_and_loads(self):
        # The left edge held, the top-right node pulled along x at 0.1 m/s, gravity, and a load
        # ramped on the bottom-right node: the held dofs stay at 0, the driven one at 0.1 t, and
        # the energy balance closes with external_work (gravity, load and support reactions).
        case = plate_case(y0=0.05, velocity=[[0.0, 0.0]] * 9)
        case.update(obstacles=[], contact={"candidates": [], "body_pairs": []}, gravity=[0.0, -9.81])
        held = [grid_node(0, j) for j in range(3)]
        driven = grid_node(2, 2)
        case["prescribed"] = [{"node": n, "component": c, "kind": "displacement", "value": 0.0, "ramp": 0.0}
                              for n in held for c in (0, 1)]
        case["prescribed"].append({"node": driven, "component": 0, "kind": "velocity", "value": 0.1, "ramp": 0.0})
        case["velocity"][driven] = [0.1, 0.0]
        case["loads"] = [{"node": grid_node(2, 0), "component": 1, "force": -5.0, "start": 0.0, "ramp": 5e-5}]
        case["time"].update(dt=2e-6, end=2e-4, steps=100)
        d, st, obs, h = run_steps(case, 100)
        nd = st.p.node_dofs
        self.assertEqual(np.abs(st.u[nd[held]]).max(), 0.0)
        self.assertAlmostEqual(st.u[nd[driven, 0]], 0.1 * 2e-4, places=15)
        self.assertLess(st.u[nd[grid_node(2, 0), 1]], 0.0)  # the load pulls the corner down
        self.assertGreater(h["external_work"][-1], 0.0)
        balance = h["total_energy"] - h["external_work"]
        self.assertLess(np.abs(balance - balance[0]).max(), 1e-4 * h["external_work"][-1])

    def test_command_line_writes_the_contract(self):
        case = plate_case(y0=0.0, velocity=[[3.0, -5.0]] * 9, options={"penalty": 2e9})
        with tempfile.TemporaryDirectory() as out:
            path = os.path.join(out, "case.json")
            with open(path, "w") as f:
                json.dump(case, f)
            r = subprocess.run([sys.executable, ADAPTER, path, out], cwd=out, capture_output=True, text=True)
            self.assertEqual(r.returncode, 0, r.stderr)
            with open(os.path.join(out, "result.json")) as f:
                res = json.load(f)
            with open(os.path.join(out, "history.csv")) as f:
                lines = f.read().splitlines()
        self.assertEqual((res["format"], res["version"], res["status"], res["steps"], res["dt"]),
                         ("ricochet-external-result", 1, "ok", 10, 1e-5))
        self.assertEqual(res["code"], "GetFEM")
        allowed = {"von_mises_max", "von_mises_max_time", "von_mises_interior_max", "von_mises_interior_max_time",
                   "penetration_max", "contact_impulse_normal", "contact_impulse_tangential", "contact_start_time",
                   "contact_end_time", "contact_duration", "friction_dissipation", "contact_work"}
        self.assertLessEqual(set(res["summary"]), allowed)
        self.assertGreater(res["summary"]["von_mises_max"], 0.0)
        header = lines[0].split(",")
        self.assertEqual(header[0], "time")
        self.assertEqual(len(set(header)), len(header))
        self.assertNotIn("energy_error", header)
        rows = np.array([[float(x) for x in l.split(",")] for l in lines[1:]])
        self.assertEqual(rows.shape, (6, len(header)))
        np.testing.assert_allclose(rows[:, 0], [0, 2e-5, 4e-5, 6e-5, 8e-5, 1e-4], atol=1e-15)
        self.assertTrue(np.all(np.isfinite(rows)))
        self.assertEqual(max(rows[:, header.index("von_mises_max")]) <= res["summary"]["von_mises_max"], True)


if __name__ == "__main__":
    unittest.main(verbosity=1)
