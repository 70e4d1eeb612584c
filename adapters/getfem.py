#!/usr/bin/env python3
"""ricochet's GetFEM adapter: a case.json in, result.json and history.csv out (docs/peers.md).

Usage: python3 adapters/getfem.py OUT/external/case.json OUT/external

The case is rebuilt with GetFEM 5.4 through its Python interface (Debian's python3-getfem), and
the time loop runs here, in Python: per Newton iteration one GetFEM assembly of the model and one
linear solve. References: GetFEM 5.4 user documentation (the model object and its bricks, the
generic weak form language GWFL, mesh_im_data); Newmark (1959), "A method of computation for
structural dynamics"; Laursen & Chawla (1997), "Design of energy conserving algorithms for
frictionless dynamic contact problems", for why the trapezoidal rule gains energy at contact.

Mesh and elements. GetFEM's mesh points are the case's `nodes`, added in case order, so that point
i is node i (checked: GetFEM merges coincident points, which is an error here). Quadrilaterals
(`quad4`, VTK corner order) become GT_QK(2,1) convexes with the bilinear FEM_QK(2,1) element and
2x2 Gauss points (IM_GAUSS_PARALLELEPIPED(2,2)); triangles (`tri3`) GT_PK(2,1) / FEM_PK(2,1) with
the 3-point IM_TRIANGLE(2); in 3D hexahedra (`hex8`) GT_QK(3,1) / FEM_QK(3,1) with 2x2x2 points,
tetrahedra (`tet4`) GT_PK(3,1) / FEM_PK(3,1) with IM_TETRAHEDRON(2). Every element is fully
integrated: ricochet's one-point `q4_hourglass` / `hex8_hourglass` run as the fully integrated
element (said in `not_translated`). The dofs of the vector field u are mapped to the case's
nodes through each convex's points and local dofs, checked against GetFEM's dof coordinates.

Material. Finite strain, total Lagrangian: F = I + Grad u, and each body adds its internal
virtual work e * integral of P(F) : Grad(du) (e its thickness, 1 in 3D), written in GWFL with the
first Piola-Kirchhoff stress P of ricochet's laws (solver/materials/material.hpp,
material3d.hpp); GetFEM differentiates it for the tangent matrix. The strain energy density W
is written out too (strain_energy; tests check P = dW/dF).
  saint_venant_kirchhoff  W = lambda/2 tr(E)^2 + mu E:E, P = F (lambda tr(E) I + 2 mu E),
                          E = (F^T F - I)/2. Plane strain: lambda the 3D constant. Plane stress:
                          S33 = 0 gives E33 = -lambda tr E / (lambda + 2 mu) exactly, which
                          leaves the same in-plane law with lambda* = 2 lambda mu / (lambda + 2 mu).
  neo_hookean             W = mu/2 (I1 - 3) - mu ln J + lambda/2 (ln J)^2, P = mu F + (lambda ln J - mu) F^-T;
                          3D and plane strain (C33 = 1). Plane stress needs a Newton solve for
                          C33 at every point, which one GWFL expression cannot hold: not translated.
  mooney_rivlin           W = c10 (J^-2/3 I1 - 3) + c01 (J^-4/3 I2 - 3) + kappa/2 (J - 1)^2; 3D and
                          plane strain (I1 = |F|^2 + 1, I2 = det(F)^2 + |F|^2, J = det F); plane
                          stress (a local Newton solve in ricochet) is not translated.
  blatz_ko                W = mu/2 (tr C^-1 + 2 J - 5); 3D, plane strain, and plane stress with
                          ricochet's closed-form C33 = j^(-2/3), j = det F:
                          W = mu/2 (|F|^2/j^2 + 3 j^(2/3) - 5).

Mass. Consistent: M = sum over the bodies of rho e integral of N_i N_j (ricochet's is lumped).
Kinetic energy 1/2 v^T M v; momentum the sum of M v, the integral of rho e v.

Contact. Penalty on each flat obstacle (2D `line`, 3D `plane`: a point p, the unit normal n
towards the bodies), integrated (face quadrature) over the boundary faces whose nodes are all
contact candidates of that obstacle. Gap g = (X + u - p).n, pressure p_n = r max(-g, 0) [Pa] with
r the penalty [N/m^3 = Pa/m] (option `penalty`): the force on the body is e * integral of p_n n,
the stored energy e * integral of r g^2 / 2 over g < 0. Coulomb friction (mu from the
candidates, one value per obstacle): an elastic tangential traction of the same r per unit slip
with a return map, as in ricochet's explicit penalty scheme: at each boundary integration point
f_t = Proj_{|f| <= mu p_n}(f_t,n - r du_T), du_T the tangential part of the step's displacement
increment and f_t,n the traction at the end of the previous step (a GetFEM mesh_im_data on the
contact faces). Its stored energy is |f_t|^2 / (2 r), its slip work per step
|f_t| |f_trial - f_t| / r (friction_dissipation). The contact terms are in the Newton problem.

Time scheme. Newmark (options `beta`, `gamma`; default 1/4, 1/2, the trapezoidal rule) on the
displacement: with u~ = u_n + dt v_n + dt^2 (1/2 - beta) a_n each step solves
M (u - u~) / (beta dt^2) + f_int(u) - f_contact(u) - f_ext(t_n+1) = 0 for u = u_n+1, then
a_n+1 = (u - u~) / (beta dt^2), v_n+1 = v_n + dt ((1 - gamma) a_n + gamma a_n+1). The step is
case.json's time.dt (the last one ends on time.end); M a_0 = f_ext(0) - f_int(u_0) + f_contact(u_0).
Newton takes full steps (no line search) from u_n + dt v_n + dt^2 a_n / 2 and stops when its
largest correction is at most `newton_tol` (default 1e-9) times the mesh's bounding-box
diagonal; a step not converged after `newton_max_iter` (20) iterations, or a non-finite value,
ends the run as `diverged`. Linear systems (`linear_solver`): "iterative" (default) conjugate
gradients with an incomplete LDL^T preconditioner, GMRES with ILU when friction makes the
tangent unsymmetric, checked (residual <= 1e-12 of the right-hand side) and otherwise redone by
MUMPS; "mumps": GetFEM's MUMPS interface always. (GetFEM 5.4.2's SuperLU entry point of the
Python interface crashes on Debian 12; it is not used.)

Gravity is the body force rho g; nodal loads and prescribed degrees of freedom follow case.json
(a prescribed dof leaves the Newton system; the work of its reaction counts in external_work, by
the trapezoidal rule). Contact between bodies (`contact.body_pairs`) and curved obstacles are not
translated: exit status 2 and one line on stderr.

Outputs. history.csv at ricochet's sample steps (round(k output.interval / dt), and the last):
kinetic_energy, strain_energy (integral of e W), total_energy, external_work, contact_energy,
friction_dissipation (with friction), momentum and angular momentum (about the moving centre of
mass, with the consistent mass), von_mises_max (at the integration points, of
output.stress_measure; in 2D with the law's out-of-plane S33 and F33), penetration_max (the
deepest contact-candidate node), normal_force and tangential_force (the penalty tractions
integrated: normal positive pushing the body away; tangential along t = (n_y, -n_x) in 2D, its
magnitude in 3D), and each probe's displacement and velocity. result.json's summary:
von_mises_max and von_mises_interior_max (cells without a candidate node) over every step
(option `stress_every_step`, default true; false: over the samples), with their times;
penetration_max over every step; contact impulses, the sum over the steps of
dt ((1 - gamma) F_n + gamma F_n+1), which is exactly the momentum the contact gives; contact
start and end times (first and last step ending with a non-zero normal force);
friction_dissipation. solver_cpu_seconds is the time loop's CPU time.

Exit status: 0 with result.json written (status ok, or diverged for a run that stopped early);
2 when the case holds something the adapter does not translate or an option is wrong; 1 on
any other failure. A non-zero exit prints one line on stderr and writes no result.json.
"""

from __future__ import annotations

import json
import math
import os
import sys
import time
from dataclasses import dataclass, field

import numpy as np

CODE = "GetFEM"
DEFAULT_PENALTY = 2.0e11  # [N/m^3]: the oblique plate's measured choice (docs/peers.md)

# VTK corner order -> GetFEM's local point order (tensor-product order for QK).
GETFEM_CELLS = {
    # kind: (dimension, corners, permutation, geometric transformation, FEM, integration)
    "quad4": (2, 4, [0, 1, 3, 2], "GT_QK(2,1)", "FEM_QK(2,1)", "IM_GAUSS_PARALLELEPIPED(2,2)"),
    "tri3": (2, 3, [0, 1, 2], "GT_PK(2,1)", "FEM_PK(2,1)", "IM_TRIANGLE(2)"),
    "hex8": (3, 8, [0, 1, 3, 2, 4, 5, 7, 6], "GT_QK(3,1)", "FEM_QK(3,1)", "IM_GAUSS_PARALLELEPIPED(3,2)"),
    "tet4": (3, 4, [0, 1, 2, 3], "GT_PK(3,1)", "FEM_PK(3,1)", "IM_TETRAHEDRON(2)"),
}
ELEMENTS = {2: ("q4", "q4_hourglass", "t3"), 3: ("hex8", "hex8_hourglass", "tet4")}
MATERIALS = ("saint_venant_kirchhoff", "neo_hookean", "mooney_rivlin", "blatz_ko")
STRESS_MEASURES = ("cauchy", "pk2", "kirchhoff")


class Unsupported(Exception):
    """Something in the case that the adapter does not translate (exit status 2)."""


class Failure(Exception):
    """Anything else that stops the adapter before it has a result (exit status 1)."""


# ----------------------------------------------------------------------------------- options

OPTION_HELP = {
    "beta": "a number in (0, 0.5]",
    "gamma": "a number in [0.5, 1]",
    "penalty": 'a number > 0 [N/m^3] or "ricochet"',
    "newton_tol": "a number in (0, 1e-3]",
    "newton_max_iter": "an integer in [1, 1000]",
    "stress_every_step": "true or false",
    "linear_solver": '"iterative" or "mumps"',
}


def _number(options, key, default, ok):
    value = options.get(key, default)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or not ok(value):
        raise Unsupported(f"options.{key} = {json.dumps(value)}: expected {OPTION_HELP[key]}")
    return float(value)


def read_options(options):
    """The adapter's options (case.json `options`), checked; returns a plain dict."""
    if options is None:
        options = {}
    if not isinstance(options, dict):
        raise Unsupported("options: expected a table of the adapter's settings")
    unknown = sorted(set(options) - set(OPTION_HELP))
    if unknown:
        raise Unsupported(f"options.{unknown[0]}: unknown option (allowed: {', '.join(OPTION_HELP)})")
    out = {
        "beta": _number(options, "beta", 0.25, lambda x: 0.0 < x <= 0.5),
        "gamma": _number(options, "gamma", 0.5, lambda x: 0.5 <= x <= 1.0),
        "newton_tol": _number(options, "newton_tol", 1e-9, lambda x: 0.0 < x <= 1e-3),
    }
    n = options.get("newton_max_iter", 20)
    if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= 1000:
        raise Unsupported(f"options.newton_max_iter = {json.dumps(n)}: expected {OPTION_HELP['newton_max_iter']}")
    out["newton_max_iter"] = n
    every = options.get("stress_every_step", True)
    if not isinstance(every, bool):
        raise Unsupported(f"options.stress_every_step = {json.dumps(every)}: expected {OPTION_HELP['stress_every_step']}")
    out["stress_every_step"] = every
    solver = options.get("linear_solver", "iterative")
    if solver not in ("iterative", "mumps"):
        raise Unsupported(f"options.linear_solver = {json.dumps(solver)}: expected {OPTION_HELP['linear_solver']}")
    out["linear_solver"] = solver
    penalty = options.get("penalty", DEFAULT_PENALTY)
    if penalty != "ricochet":
        penalty = _number(options, "penalty", DEFAULT_PENALTY, lambda x: x > 0.0)
    out["penalty"] = penalty
    return out


# ----------------------------------------------------------------------- the plain description


@dataclass
class Material:
    model: str
    density: float
    plane: str | None  # "stress", "strain", or None in 3D
    constants: dict  # the law's constants [Pa], named as in material.hpp


@dataclass
class Body:
    name: str
    element: str
    thickness: float  # [m]; 1 in 3D
    material: Material
    cells: dict  # kind -> (k, corners) int array of global node indices, GetFEM local order


@dataclass
class Obstacle:
    name: str
    index: int  # in case.json obstacles
    point: np.ndarray
    normal: np.ndarray  # unit, towards the bodies
    friction: float
    nodes: np.ndarray  # contact-candidate nodes


@dataclass
class Description:
    """What the adapter makes of a case.json, before any GetFEM object exists."""

    dim: int
    plane: str | None
    nodes: np.ndarray  # (N, dim) reference positions [m]
    velocity: np.ndarray  # (N, dim) initial velocities [m/s]
    bodies: list
    gravity: np.ndarray
    prescribed: list  # (node, component, kind, value, ramp)
    loads: list  # (node, component, force, start, ramp)
    obstacles: list
    penalty: float  # r [N/m^3]
    penalty_source: str
    beta: float
    gamma: float
    dt: float
    end: float
    steps: int
    interval: float
    stress_measure: str
    probes: list  # (name, node)
    newton_tol: float
    newton_max_iter: int
    stress_every_step: bool
    linear_solver: str
    penalty_step_ratio: float | None = None
    translated: list = field(default_factory=list)
    not_translated: list = field(default_factory=list)
    notes: list = field(default_factory=list)


def _get(d, key, where):
    if not isinstance(d, dict) or key not in d:
        raise Failure(f"case.json: {where}{key} is missing")
    return d[key]


def lame(young, poisson):
    """3D Lame constants (lambda, mu) of (E, nu) [Pa]."""
    return young * poisson / ((1 + poisson) * (1 - 2 * poisson)), young / (2 * (1 + poisson))


def read_material(m, plane, where):
    model = _get(m, "model", where)
    if model not in MATERIALS:
        raise Unsupported(f"{where}model = {json.dumps(model)}: no such material law in this adapter "
                          f"(it translates {', '.join(MATERIALS)})")
    density = float(_get(m, "density", where))
    if model in ("neo_hookean", "mooney_rivlin") and plane == "stress":
        raise Unsupported(f"{where}model = \"{model}\" in plane stress: its out-of-plane stretch needs a local Newton "
                          "solve at every point, which GetFEM's weak form language cannot express "
                          "(plane strain, 3D and the other laws translate)")
    if model in ("saint_venant_kirchhoff", "neo_hookean"):
        lam3, mu = lame(float(_get(m, "young", where)), float(_get(m, "poisson", where)))
        c = {"lambda_3d": lam3, "mu": mu, "lambda": lam3}
        if model == "saint_venant_kirchhoff" and plane == "stress":
            c["lambda"] = 2 * lam3 * mu / (lam3 + 2 * mu)
            c["e33_per_trace"] = -lam3 / (lam3 + 2 * mu)
    elif model == "mooney_rivlin":
        c = {k: float(_get(m, k, where)) for k in ("c10", "c01", "bulk_modulus")}
    else:
        c = {"mu": float(_get(m, "shear_modulus", where))}
    return Material(model, density, plane, c)


def read_bodies(case, dim, plane, n_nodes):
    bodies = []
    for b, body in enumerate(_get(case, "bodies", "")):
        where = f"bodies[{b}]."
        element = _get(body, "element", where)
        if element not in ELEMENTS[dim]:
            raise Unsupported(f"{where}element = {json.dumps(element)}: not a {dim}D element of this adapter "
                              f"(allowed: {', '.join(ELEMENTS[dim])})")
        thickness = 1.0
        if dim == 2:
            thickness = float(_get(body, "thickness", where))
            if not thickness > 0:
                raise Failure(f"case.json: {where}thickness = {thickness}: expected > 0")
        cells = {}
        for kind, conn in _get(body, "cells", where).items():
            if kind not in GETFEM_CELLS or GETFEM_CELLS[kind][0] != dim:
                raise Unsupported(f"{where}cells.{kind}: no such {dim}D cell type in this adapter")
            spec = GETFEM_CELLS[kind]
            a = np.asarray(conn, dtype=np.int64).reshape(-1, spec[1])
            if a.size and (a.min() < 0 or a.max() >= n_nodes):
                raise Failure(f"case.json: {where}cells.{kind}: a node index outside 0..{n_nodes - 1}")
            if len(a):
                cells[kind] = a[:, spec[2]]
        if not cells:
            raise Failure(f"case.json: {where}cells: the body has no cells")
        material = read_material(_get(body, "material", where), plane, where + "material.")
        bodies.append(Body(str(_get(body, "name", where)), element, thickness, material, cells))
    if not bodies:
        raise Failure("case.json: bodies is empty")
    return bodies


def read_obstacles(case, dim):
    """The flat obstacles with their candidate nodes and friction coefficients."""
    contact = case.get("contact") or {}
    pairs = contact.get("body_pairs") or []
    if pairs:
        p = pairs[0]
        raise Unsupported(f"contact.body_pairs ({p.get('slave')} on {p.get('master')}): contact between bodies is not "
                          "translated (GetFEM's large-sliding contact would be a different formulation)")
    obstacles = []
    for k, ob in enumerate(case.get("obstacles") or []):
        kind = ob.get("type")
        flat = "line" if dim == 2 else "plane"
        if kind != flat:
            raise Unsupported(f"obstacles[{k}] ({ob.get('name')}): type \"{kind}\" is not translated "
                              f"(the adapter takes flat obstacles, a {dim}D \"{flat}\", only)")
        normal = np.asarray(_get(ob, "normal", f"obstacles[{k}]."), dtype=float)
        point = np.asarray(_get(ob, "point", f"obstacles[{k}]."), dtype=float)
        if normal.shape != (dim,) or point.shape != (dim,) or not np.linalg.norm(normal) > 0:
            raise Failure(f"case.json: obstacles[{k}]: point and normal must be {dim} numbers, normal not zero")
        obstacles.append(Obstacle(str(ob.get("name", f"obstacle{k}")), k, point, normal / np.linalg.norm(normal),
                                  0.0, np.zeros(0, dtype=np.int64)))
    candidates = contact.get("candidates") or []
    per = {k: [] for k in range(len(obstacles))}
    for c in candidates:
        k = int(c["obstacle"])
        if k < 0:
            raise Unsupported("contact.candidates: a body-pair candidate (obstacle -1): contact between bodies is "
                              "not translated")
        if k not in per:
            raise Failure(f"case.json: contact.candidates: obstacle {k} does not exist")
        per[k].append(c)
    for k, ob in enumerate(obstacles):
        mus = sorted({float(c["friction"]) for c in per[k]})
        if len(mus) > 1:
            raise Unsupported(f"obstacles[{k}] ({ob.name}): its candidates have several friction coefficients "
                              f"({mus[0]} ... {mus[-1]}); the adapter takes one per obstacle")
        ob.friction = mus[0] if mus else 0.0
        ob.nodes = np.array(sorted({int(c["node"]) for c in per[k]}), dtype=np.int64)
    return obstacles, candidates


def ricochet_penalty(candidates):
    """The median over the candidates of ricochet's penalty stiffness per unit boundary area,
    k / area [N/m^3]."""
    ratios = [float(c["stiffness"]) / float(c["area"]) for c in candidates if float(c.get("area", 0)) > 0]
    if not ratios:
        raise Unsupported('options.penalty = "ricochet": the case has no contact candidate with an area to derive it from')
    return float(np.median(ratios))


def penalty_step_ratio(case, candidates, penalty, dt):
    """The largest sqrt(r area / m) dt over the candidates: the penalty spring's angular frequency
    at a node (case.json's lumped mass m) times the step. Above about 1 the step does not resolve
    the contact's oscillation."""
    mass = case.get("mass") or []
    ratios = [math.sqrt(penalty * float(c["area"]) / mass[int(c["node"])]) * dt for c in candidates
              if float(c.get("area", 0)) > 0 and int(c["node"]) < len(mass) and mass[int(c["node"])] > 0]
    return max(ratios) if ratios else None


def read_prescribed(case, dim, n_nodes):
    out = []
    for i, p in enumerate(case.get("prescribed") or []):
        kind = p.get("kind")
        if kind not in ("velocity", "displacement"):
            raise Unsupported(f"prescribed[{i}].kind = {json.dumps(kind)}: expected \"velocity\" or \"displacement\"")
        node, comp = int(p["node"]), int(p["component"])
        if not (0 <= node < n_nodes and 0 <= comp < dim):
            raise Failure(f"case.json: prescribed[{i}]: node {node} / component {comp} out of range")
        out.append((node, comp, kind, float(p["value"]), float(p.get("ramp", 0.0))))
    seen = set()
    for node, comp, *_ in out:
        if (node, comp) in seen:
            raise Failure(f"case.json: prescribed: node {node} component {comp} is prescribed twice")
        seen.add((node, comp))
    return out


def read_loads(case, dim, n_nodes):
    """Nodal loads as (node, component, force, start, ramp); `force` given either per component
    (with `component`) or as a vector."""
    out = []
    for i, l in enumerate(case.get("loads") or []):
        node = int(l["node"])
        if not 0 <= node < n_nodes:
            raise Failure(f"case.json: loads[{i}]: node {node} out of range")
        start, ramp = float(l.get("start", 0.0)), float(l.get("ramp", 0.0))
        if "component" in l:
            out.append((node, int(l["component"]), float(l["force"]), start, ramp))
        else:
            for comp, f in enumerate(np.asarray(l["force"], dtype=float).reshape(dim)):
                if f != 0.0:
                    out.append((node, comp, float(f), start, ramp))
    return out


def describe(case):
    """case.json (a dict) -> Description; raises Unsupported or Failure."""
    if case.get("format") != "ricochet-external-case" or case.get("version") != 1:
        raise Failure(f"case.json: format/version {case.get('format')!r}/{case.get('version')!r}: expected "
                      "\"ricochet-external-case\"/1")
    opts = read_options(case.get("options"))
    dim = int(_get(case, "dimension", ""))
    if dim not in (2, 3):
        raise Unsupported(f"dimension = {dim}: expected 2 or 3")
    plane = case.get("plane") if dim == 2 else None
    if dim == 2 and plane not in ("stress", "strain"):
        raise Failure(f"case.json: plane = {json.dumps(plane)}: expected \"stress\" or \"strain\"")
    nodes = np.asarray(_get(case, "nodes", ""), dtype=float).reshape(-1, dim)
    velocity = np.asarray(_get(case, "velocity", ""), dtype=float).reshape(-1, dim)
    if velocity.shape != nodes.shape:
        raise Failure("case.json: velocity must have one entry per node")
    bodies = read_bodies(case, dim, plane, len(nodes))
    obstacles, candidates = read_obstacles(case, dim)
    penalty, source = opts["penalty"], "options.penalty"
    if penalty == "ricochet":
        penalty, source = ricochet_penalty(candidates), "ricochet (median candidate stiffness / area)"
    elif "penalty" not in (case.get("options") or {}):
        source = "default"
    t = _get(case, "time", "")
    dt, end = float(_get(t, "dt", "time.")), float(_get(t, "end", "time."))
    if not (dt > 0 and end > 0):
        raise Failure(f"case.json: time.dt = {dt}, time.end = {end}: both must be > 0")
    steps = int(t.get("steps") or math.ceil(end / dt - 1e-9))
    out = _get(case, "output", "")
    measure = out.get("stress_measure", "cauchy")
    if measure not in STRESS_MEASURES:
        raise Unsupported(f"output.stress_measure = {json.dumps(measure)}: expected one of {', '.join(STRESS_MEASURES)}")
    probes = [(str(p["name"]), int(p["node"])) for p in out.get("probes") or []]
    for name, node in probes:
        if not 0 <= node < len(nodes):
            raise Failure(f"case.json: output.probes {name}: node {node} out of range")
    d = Description(
        dim=dim, plane=plane, nodes=nodes, velocity=velocity, bodies=bodies,
        gravity=np.asarray(case.get("gravity") or [0.0] * dim, dtype=float).reshape(dim),
        prescribed=read_prescribed(case, dim, len(nodes)), loads=read_loads(case, dim, len(nodes)),
        obstacles=obstacles, penalty=float(penalty), penalty_source=source,
        beta=opts["beta"], gamma=opts["gamma"], dt=dt, end=end, steps=max(steps, 1),
        interval=float(out.get("interval") or 0.0), stress_measure=measure, probes=probes,
        newton_tol=opts["newton_tol"], newton_max_iter=opts["newton_max_iter"],
        stress_every_step=opts["stress_every_step"], linear_solver=opts["linear_solver"])
    d.penalty_step_ratio = penalty_step_ratio(case, candidates, d.penalty, dt) if obstacles else None
    translation_notes(d)
    return d


def translation_notes(d):
    """Fill d.translated / not_translated / notes (copied to result.json `translation`)."""
    cells = sorted({k for b in d.bodies for k in b.cells})
    d.translated.append(f"mesh: {len(d.nodes)} nodes, cells {', '.join(cells)} as GetFEM "
                        + ", ".join(f"{GETFEM_CELLS[k][3]}/{GETFEM_CELLS[k][4]}/{GETFEM_CELLS[k][5]}" for k in cells))
    for b in d.bodies:
        m = b.material
        mode = f", plane {d.plane}" if d.dim == 2 else ""
        d.translated.append(f"body {b.name}: {m.model}{mode}, rho = {m.density:g} kg/m^3, "
                            + ", ".join(f"{k} = {v:.6g}" for k, v in m.constants.items())
                            + (f", thickness {b.thickness:g} m" if d.dim == 2 else ""))
        if b.element.endswith("_hourglass"):
            d.not_translated.append(f"body {b.name}: element {b.element} (one point, hourglass control) run as the "
                                    "fully integrated element (GetFEM has no hourglass control)")
    d.translated.append(f"time: Newmark beta = {d.beta:g}, gamma = {d.gamma:g}, dt = {d.dt:g} s, "
                        f"{d.steps} steps to {d.end:g} s; Newton with full steps")
    d.translated.append("mass: consistent (ricochet's is lumped)")
    for ob in d.obstacles:
        law = f"Coulomb mu = {ob.friction:g} (elastic tangential spring, return map)" if ob.friction > 0 else "frictionless"
        d.translated.append(f"obstacle {ob.name}: penalty r = {d.penalty:.6g} N/m^3 ({d.penalty_source}) on the "
                            f"boundary faces of its {len(ob.nodes)} candidate nodes, {law}")
    if np.any(d.gravity != 0):
        d.translated.append("gravity: body force rho g")
    if d.prescribed:
        d.translated.append(f"prescribed: {len(d.prescribed)} degrees of freedom, removed from the Newton system")
    if d.loads:
        d.translated.append(f"loads: {len(d.loads)} nodal force components")
    d.notes.append("von_mises_max at the integration points (quadrilaterals 2x2, triangles 3, hexahedra 2x2x2, "
                   "tetrahedra 4), "
                   + ("every step" if d.stress_every_step else "at the history samples")
                   + (", out-of-plane stress included" if d.dim == 2 else ""))
    if d.penalty_step_ratio is not None:
        d.notes.append(f"penalty frequency x dt = {d.penalty_step_ratio:.3g} (max over the candidates of "
                       "sqrt(r area / m) dt)" + (": above 1 the step does not resolve the contact's oscillation; the "
                                                 "trapezoidal rule (gamma = 1/2) then gains energy when contacts "
                                                 "open and close, gamma > 1/2 damps it"
                                                 if d.penalty_step_ratio > 1 else ""))
    d.notes.append("contact forces are the penalty tractions integrated over the contact faces; "
                   "penetration_max is the deepest candidate node")
    d.notes.append("contact impulses: sum of dt ((1 - gamma) F_n + gamma F_n+1), the momentum the contact gives")


# ------------------------------------------------------------------------------ GWFL laws


def num(x):
    """A float as GWFL text."""
    return f"({float(x)!r})"


def material_gwfl(mat, dim):
    """GWFL expressions of one law, in terms of the macro F = Id(meshdim) + Grad_u:
    W (energy density per reference volume), P (first Piola-Kirchhoff), and in 2D S33 (the
    out-of-plane 2nd Piola-Kirchhoff stress) and F33sq (F33^2)."""
    c = mat.constants
    plane_stress = dim == 2 and mat.plane == "stress"
    j = "Det(F)"
    cof = f"({j}*Inv(F)')"
    out = {"S33": "0", "F33sq": "1"}
    if mat.model == "saint_venant_kirchhoff":
        lam, mu = c["lambda"], c["mu"]
        e = "((F'*F-Id(meshdim))/2)"
        out["W"] = f"({num(lam / 2)}*sqr(Trace({e}))+{num(mu)}*Norm_sqr({e}))"
        out["P"] = f"(F*({num(lam)}*Trace({e})*Id(meshdim)+{num(2 * mu)}*{e}))"
        if dim == 2 and plane_stress:
            out["F33sq"] = f"(1+{num(2 * c['e33_per_trace'])}*Trace({e}))"
        elif dim == 2:
            out["S33"] = f"({num(c['lambda_3d'])}*Trace({e}))"
    elif mat.model == "neo_hookean":
        lam, mu = c["lambda"], c["mu"]
        i1 = "Norm_sqr(F)" if dim == 3 else "(Norm_sqr(F)+1)"
        out["W"] = f"({num(mu / 2)}*({i1}-3)-{num(mu)}*log({j})+{num(lam / 2)}*sqr(log({j})))"
        out["P"] = f"({num(mu)}*F+({num(lam)}*log({j})-{num(mu)})*Inv(F)')"
        if dim == 2:
            out["S33"] = f"({num(lam)}*log({j}))"
    elif mat.model == "blatz_ko":
        mu = c["mu"]
        if dim == 3:
            g = "Inv(F)'"
            out["W"] = f"({num(mu / 2)}*(Norm_sqr({g})+2*{j}-5))"
            out["P"] = f"({num(mu)}*({j}*{g}-{g}*({g})'*{g}))"
        else:
            n = "Norm_sqr(F)"
            wn = f"({num(mu / 2)}/sqr({j}))"
            if plane_stress:
                out["W"] = f"({num(mu / 2)}*({n}/sqr({j})+3*pow({j},2/3)-5))"
                wj = f"({num(mu)}*(pow({j},-1/3)-{n}/pow({j},3)))"
                out["F33sq"] = f"pow({j},-2/3)"
            else:
                out["W"] = f"({num(mu / 2)}*({n}/sqr({j})+2*{j}-4))"
                wj = f"({num(mu)}*(1-{n}/pow({j},3)))"
                out["S33"] = f"({num(mu)}*({j}-1))"
            out["P"] = f"(2*{wn}*F+{wj}*{cof})"
    else:  # mooney_rivlin
        c10, c01, k = c["c10"], c["c01"], c["bulk_modulus"]
        if dim == 3:
            i1, i2 = "Norm_sqr(F)", f"(sqr({j})*Norm_sqr(Inv(F)))"
            out["W"] = (f"({num(c10)}*(pow({j},-2/3)*{i1}-3)+{num(c01)}*(pow({j},-4/3)*{i2}-3)"
                        f"+{num(k / 2)}*sqr({j}-1))")
            w1, w2 = f"({num(c10)}*pow({j},-2/3))", f"({num(c01)}*pow({j},-4/3))"
            wj = (f"({num(-2 / 3 * c10)}*pow({j},-5/3)*{i1}+{num(-4 / 3 * c01)}*pow({j},-7/3)*{i2}"
                  f"+{num(k)}*({j}-1))")
            out["P"] = f"(2*{w1}*F+2*{w2}*({i1}*F-F*F'*F)+{wj}*{cof})"
        else:  # plane strain: I1 = n + 1, I2 = j^2 + n, J = j
            n = "Norm_sqr(F)"
            out["W"] = (f"({num(c10)}*(pow({j},-2/3)*({n}+1)-3)+{num(c01)}*(pow({j},-4/3)*(sqr({j})+{n})-3)"
                        f"+{num(k / 2)}*sqr({j}-1))")
            wn = f"({num(c10)}*pow({j},-2/3)+{num(c01)}*pow({j},-4/3))"
            wj = (f"({num(-2 / 3 * c10)}*pow({j},-5/3)*({n}+1)+{num(c01)}*({num(2 / 3)}*pow({j},-1/3)"
                  f"-{num(4 / 3)}*pow({j},-7/3)*{n})+{num(k)}*({j}-1))")
            out["P"] = f"(2*{wn}*F+{wj}*{cof})"
            # S33 = dW/dt at t = ln F33 = 0 (material.cpp, MooneyRivlin::terms)
            m1, m2 = f"({num(c10)}*{n}*pow({j},-2/3))", f"({num(c10)}*pow({j},-2/3))"
            m3, m4 = f"({num(c01)}*pow({j},2/3))", f"({num(c01)}*{n}*pow({j},-4/3))"
            out["S33"] = (f"(-2/3*{m1}+4/3*{m2}-4/3*{m3}+2/3*{m4}+{num(k)}*({j}-1)*{j})")
    return out


def von_mises_gwfl(law, dim, measure):
    """The von Mises equivalent of `measure` at a point, out-of-plane component included in 2D."""
    P = law["P"]
    if measure == "pk2":
        a, a33 = f"Sym(Inv(F)*{P})", law["S33"]
    else:
        a, a33 = f"Sym({P}*F')", f"({law['F33sq']}*{law['S33']})"
        if measure == "cauchy":
            jj = f"(Det(F)*sqrt({law['F33sq']}))" if dim == 2 else "Det(F)"
            a, a33 = f"({a}/{jj})", f"({a33}/{jj})"
    if dim == 3:
        return f"sqrt(pos_part(1.5*(Norm_sqr({a})-sqr(Trace({a}))/3)))"
    return f"sqrt(pos_part(1.5*(Norm_sqr({a})+sqr({a33})-sqr(Trace({a})+{a33})/3)))"


# ----------------------------------------------------------------------------- the GetFEM side


def import_getfem():
    """GetFEM's Python package. This file is itself named getfem.py, so its folder is taken off
    the module search path (and a module "getfem" that is this adapter forgotten) first."""
    here = os.path.dirname(os.path.abspath(__file__))
    loaded = sys.modules.get("getfem")
    if loaded is not None and not hasattr(loaded, "Mesh"):
        del sys.modules["getfem"]
    saved = sys.path[:]
    sys.path[:] = [p for p in sys.path if os.path.abspath(p or os.curdir) != here]
    try:
        import importlib
        gf = importlib.import_module("getfem")
    except ImportError as exc:
        raise Failure(f"cannot import getfem ({exc}): install Debian's python3-getfem") from exc
    finally:
        sys.path[:] = saved
    gf.util_trace_level(0)
    gf.util_warning_level(0)
    return gf


def getfem_version():
    """GetFEM's version, from the Debian package or the Python distribution metadata."""
    try:
        from importlib import metadata
        return metadata.version("getfem")
    except Exception:
        pass
    try:
        for line in open("/var/lib/dpkg/status", encoding="utf-8", errors="replace").read().split("\n\n"):
            if line.startswith("Package: python3-getfem\n"):
                for l in line.splitlines():
                    if l.startswith("Version:"):
                        v = l.split()[1]
                        return v.split("+")[0]
    except OSError:
        pass
    return "unknown"


BODY_REGION0 = 1  # region of body b: 1 + b
INTERIOR_REGION0 = 200  # body b's cells with no contact-candidate node: 200 + b
EDGE_REGION0 = 400  # body b's cells with a contact-candidate node: 400 + b
CONTACT_REGION0 = 1000  # region of (obstacle k, body b): 1000 + 100 k + b


@dataclass
class Problem:
    """The GetFEM objects of a translated case, and the maps between them and the case."""

    gf: object
    mesh: object
    mf: object
    mim: object
    md: object
    node_dofs: np.ndarray  # (N, dim): the dof of each node's components
    mass: object  # consistent mass matrix (Spmat)
    laws: list  # per body, material_gwfl()
    contacts: list  # per (obstacle, body) with faces: dict(region, obstacle, body, friction data names)
    mass_brick: int = -1
    rhs_brick: int = -1


def build_mesh(gf, d):
    mesh = gf.Mesh("empty", d.dim)
    ids = np.asarray(mesh.add_point(d.nodes.T.copy())).ravel()
    if len(ids) != len(d.nodes) or np.any(ids != np.arange(len(d.nodes))):
        bad = int(np.nonzero(ids != np.arange(len(d.nodes)))[0][0])
        raise Failure(f"node {bad} coincides with node {int(ids[bad])} (GetFEM merges points closer than about 1e-8 m)")
    body_cvs = []
    for b, body in enumerate(d.bodies):
        cvs = []
        for kind, conn in body.cells.items():
            spec = GETFEM_CELLS[kind]
            pts = np.transpose(d.nodes[conn], (2, 1, 0)).copy()  # (dim, corners, cells)
            cv = np.asarray(mesh.add_convex(gf.GeoTrans(spec[3]), pts)).ravel()
            pid, idx = mesh.pid_from_cvid(cv)
            got = np.asarray(pid).reshape(len(cv), spec[1])
            if not np.array_equal(got, conn):
                raise Failure(f"body {body.name}: GetFEM's convexes do not use the case's nodes (coincident nodes?)")
            cvs.append((kind, cv))
        body_cvs.append(cvs)
        mesh.set_region(BODY_REGION0 + b, np.concatenate([cv for _, cv in cvs]).reshape(1, -1))
        # ricochet's interior cells (docs/outputs.md, von_mises_interior_max): no node on a
        # contact boundary, i.e. no contact-candidate node.
        candidates = np.zeros(len(d.nodes), dtype=bool)
        for ob in d.obstacles:
            candidates[ob.nodes] = True
        edge = np.concatenate([cv[candidates[body.cells[kind]].any(axis=1)] for kind, cv in cvs])
        inner = np.concatenate([cv[~candidates[body.cells[kind]].any(axis=1)] for kind, cv in cvs])
        for region, cv in ((INTERIOR_REGION0 + b, inner), (EDGE_REGION0 + b, edge)):
            if len(cv):
                mesh.set_region(region, cv.reshape(1, -1))
    return mesh, body_cvs


def map_dofs(mf, mesh, d):
    """(N, dim) array of the dof of each node's components, through each convex's points and
    local dofs, checked against the dofs' coordinates."""
    node_dofs = -np.ones((len(d.nodes), d.dim), dtype=np.int64)
    cvs = np.arange(mesh.nbcvs())
    pid, pidx = mesh.pid_from_cvid(cvs)
    dofs, didx = mf.basic_dof_from_cvid(cvs)
    for k in range(len(cvs)):
        p = pid[pidx[k]:pidx[k + 1]]
        q = np.asarray(dofs[didx[k]:didx[k + 1]]).reshape(len(p), d.dim)
        node_dofs[p] = q
    if np.any(node_dofs < 0):
        raise Failure(f"node {int(np.nonzero(node_dofs < 0)[0][0])} belongs to no cell")
    xyz = mf.basic_dof_nodes()
    for c in range(d.dim):
        if not np.allclose(xyz[:, node_dofs[:, c]].T, d.nodes, rtol=0, atol=1e-12 * (1 + np.abs(d.nodes).max())):
            raise Failure("GetFEM's dof coordinates do not match the case's nodes")
    return node_dofs


def contact_faces(mesh, d, body_cvs):
    """Per (obstacle k, body b): the outer faces of body b whose points are all candidates of k."""
    faces = mesh.outer_faces()
    body_of = {}
    for b, cvs in enumerate(body_cvs):
        for _, cv in cvs:
            for c in cv:
                body_of[int(c)] = b
    out = {}
    for k, ob in enumerate(d.obstacles):
        cand = set(int(n) for n in ob.nodes)
        for f in range(faces.shape[1]):
            pts = np.asarray(mesh.pid_in_faces(faces[:, f:f + 1])).ravel()
            if all(int(p) in cand for p in pts):
                out.setdefault((k, body_of[int(faces[0, f])]), []).append(f)
    return {key: faces[:, idx] for key, idx in out.items()}


def contact_expressions(ob_k, body, r, mu):
    """GWFL of the contact at obstacle k: pn (normal pressure), ft (tangential traction vector),
    ftrial, all per unit area (thickness not included)."""
    n = f"nrm{ob_k}"
    gap = f"((X+u).{n}-dist{ob_k})"
    pn = f"({num(r)}*neg_part({gap}))"
    du = "(u-u_n)"
    if mu > 0:
        trial = f"(ft{ob_k}_{body}-{num(r)}*({du}-({du}.{n})*{n}))"
        ft = f"Ball_projection({trial},{num(mu)}*{pn})"
    else:
        trial = ft = None
    return {"gap": gap, "pn": pn, "ft": ft, "trial": trial, "n": n}


def add_material_terms(md, mim, d):
    """Each body's internal virtual work, e P(F) : Grad(du); returns the laws (material_gwfl)."""
    laws = []
    for b, body in enumerate(d.bodies):
        law = material_gwfl(body.material, d.dim)
        laws.append(law)
        md.add_nonlinear_term(mim, f"{num(body.thickness)}*({law['P']}:Grad_Test_u)", BODY_REGION0 + b)
    return laws


def assemble_mass(gf, md, mim, d):
    """The consistent mass matrix, sum over the bodies of rho e N_i N_j (a GetFEM Spmat)."""
    mass = None
    for b, body in enumerate(d.bodies):
        mb = gf.asm_generic(mim, 2, f"{num(body.material.density * body.thickness)}*(Test_u.Test2_u)",
                            BODY_REGION0 + b, md)
        mass = mb if mass is None else gf.Spmat("add", mass, mb)
    return mass


def add_contact_terms(gf, md, mim, mesh, d, body_cvs):
    """The penalty terms, one per (obstacle, body) with contact faces; returns their records
    (region, obstacle, body, number of faces, GWFL expressions, friction im_data)."""
    for k, ob in enumerate(d.obstacles):
        md.add_initialized_data(f"nrm{k}", ob.normal)
        md.add_initialized_data(f"dist{k}", [float(ob.point @ ob.normal)])
    contacts = []
    for (k, b), faces in sorted(contact_faces(mesh, d, body_cvs).items()):
        ob, e = d.obstacles[k], d.bodies[b].thickness
        region = CONTACT_REGION0 + 100 * k + b
        mesh.set_region(region, faces)
        c = {"region": region, "obstacle": k, "body": b, "faces": faces.shape[1], "mimd": None,
             "expr": contact_expressions(k, b, d.penalty, ob.friction)}
        if ob.friction > 0:  # the tangential traction of the previous step, per integration point
            c["mimd"] = gf.MeshImData(mim, region, [d.dim])
            md.add_im_data(f"ft{k}_{b}", c["mimd"])
        x = c["expr"]
        force = f"{x['pn']}*{x['n']}" + (f"+{x['ft']}" if x["ft"] else "")
        md.add_nonlinear_term(mim, f"-{num(e)}*(({force}).Test_u)", region)
        contacts.append(c)
    return contacts


def build(d):
    """Description -> Problem: the GetFEM mesh, fields, integration and model."""
    gf = import_getfem()
    mesh, body_cvs = build_mesh(gf, d)
    mf = gf.MeshFem(mesh, d.dim)
    mim = gf.MeshIm(mesh)
    for cvs in body_cvs:
        for kind, cv in cvs:
            mf.set_fem(gf.Fem(GETFEM_CELLS[kind][4]), cv)
            mim.set_integ(gf.Integ(GETFEM_CELLS[kind][5]), cv)
    node_dofs = map_dofs(mf, mesh, d)
    md = gf.Model("real")
    md.add_fem_variable("u", mf)
    md.add_fem_data("u_n", mf)  # the displacement at t_n (friction's slip increment)
    md.add_macro("F", "(Id(meshdim)+Grad_u)")
    laws = add_material_terms(md, mim, d)
    mass = assemble_mass(gf, md, mim, d)
    contacts = add_contact_terms(gf, md, mim, mesh, d, body_cvs)
    prob = Problem(gf, mesh, mf, mim, md, node_dofs, mass, laws, contacts)
    # Inertia: M u / (beta dt^2) on the left, M u~ / (beta dt^2) + f_ext on the right (Stepper).
    prob.mass_brick = md.add_explicit_matrix("u", "u", gf.Spmat("copy", mass))
    prob.rhs_brick = md.add_explicit_rhs("u", np.zeros(mf.nbdof()))
    return prob


# ------------------------------------------------------------------------------- the run


def ramp(t, start, length):
    if t < start:
        return 0.0
    return 1.0 if length <= 0 else min(1.0, (t - start) / length)


class Stepper:
    """Newmark on the GetFEM model: state (u, v, a) as dof vectors, one step per call."""

    def __init__(self, d, prob):
        self.d, self.p = d, prob
        md = prob.md
        self.n = prob.mf.nbdof()
        nd = prob.node_dofs
        self.fixed = np.array([nd[node, comp] for node, comp, *_ in d.prescribed], dtype=np.int64)
        self.free = np.setdiff1d(np.arange(self.n), self.fixed)
        g_field = np.zeros(self.n)
        for c in range(d.dim):
            g_field[nd[:, c]] = d.gravity[c]
        self.f_gravity = prob.mass.mult(g_field).ravel()
        self.length = float(np.linalg.norm(d.nodes.max(0) - d.nodes.min(0))) or 1.0
        self.u = np.zeros(self.n)
        self.v = np.zeros(self.n)
        for c in range(d.dim):
            self.v[nd[:, c]] = d.velocity[:, c]
        self.u[self.fixed] = self.prescribed_u(0.0)
        self.u0 = self.u.copy()
        self.t, self.step_no, self.dt_matrix = 0.0, 0, None
        self.iterations = []
        self.direct_solves = 0  # iterative solves that fell back to MUMPS
        self.symmetric = not any(ob.friction > 0 for ob in d.obstacles)
        self.reaction = np.zeros(len(self.fixed))
        self.external_work = 0.0
        md.set_variable("u", self.u)
        md.set_variable("u_n", self.u)
        self.a = self.initial_acceleration()

    # -- loads and prescribed motion
    def f_ext(self, t):
        f = self.f_gravity.copy()
        for node, comp, force, start, length in self.d.loads:
            f[self.p.node_dofs[node, comp]] += force * ramp(t, start, length)
        return f

    def prescribed_u(self, t):
        out = np.zeros(len(self.d.prescribed))
        for i, (node, comp, kind, value, length) in enumerate(self.d.prescribed):
            out[i] = value * t if kind == "velocity" else value * ramp(t, 0.0, length)
        return out

    # -- linear algebra
    def solve(self, K, rhs):
        """K x = rhs with the prescribed dofs held (x = 0 there). Option linear_solver
        "iterative": conjugate gradients with an incomplete LDL^T preconditioner (GMRES with
        ILU when friction makes K unsymmetric), accepted when the residual is below 1e-12 of
        rhs, else MUMPS; "mumps": MUMPS (direct) always."""
        gf = self.p.gf
        if len(self.fixed):
            K = gf.Spmat("copy", K)
            K.clear(self.fixed, np.arange(self.n))
            K.clear(np.arange(self.n), self.fixed)
            diag = np.zeros(self.n)
            diag[self.fixed] = 1.0
            K = gf.Spmat("add", K, gf.Spmat("diag", diag))
            rhs = rhs.copy()
            rhs[self.fixed] = 0.0
        K.to_csc()
        if self.d.linear_solver == "iterative":
            if self.symmetric:
                x = gf.linsolve_cg(K, rhs, gf.Precond("ildlt", K), "res", 1e-14, "maxiter", 1000)
            else:
                x = gf.linsolve_gmres(K, rhs, 50, gf.Precond("ilu", K), "res", 1e-14, "maxiter", 1000)
            x = np.asarray(x).ravel()
            if np.all(np.isfinite(x)) and np.linalg.norm(K.mult(x).ravel() - rhs) <= 1e-12 * np.linalg.norm(rhs):
                return x
            self.direct_solves += 1
        return np.asarray(gf.linsolve_mumps(K, rhs)).ravel()

    def set_mass_matrix(self, dt):
        """The inertia brick's matrix M / (beta dt^2), rebuilt when the step changes."""
        if self.dt_matrix != dt:
            m = self.p.gf.Spmat("copy", self.p.mass)
            m.scale(1.0 / (self.d.beta * dt * dt))
            self.p.md.set_private_matrix(self.p.mass_brick, m)
            self.dt_matrix = dt

    def initial_acceleration(self):
        """M a0 = f_ext(0) - f_int(u0) + f_contact(u0): the static residual at u0, the inertia
        brick's matrix and right-hand side set so that they cancel."""
        md = self.p.md
        self.set_mass_matrix(self.d.dt)
        m_u0 = self.p.mass.mult(self.u).ravel() / (self.d.beta * self.d.dt ** 2)
        md.set_private_rhs(self.p.rhs_brick, m_u0 + self.f_ext(0.0))
        md.assembly("build_rhs")
        rhs = np.asarray(md.rhs()).ravel()
        self.reaction = -rhs[self.fixed]
        return self.solve(self.p.mass, rhs)

    def newton(self, u_start):
        """Full Newton steps from u_start; returns (u, iterations, None) or (None, iterations, why)."""
        md = self.p.md
        u = u_start.copy()
        tol = self.d.newton_tol * self.length
        for it in range(1, self.d.newton_max_iter + 1):
            md.set_variable("u", u)
            md.assembly("build_all")
            rhs = np.asarray(md.rhs()).ravel()
            if not np.all(np.isfinite(rhs)):
                return None, it, "a non-finite residual (an element turned inside out?)"
            self.reaction_next = -rhs[self.fixed]
            delta = self.solve(md.tangent_matrix(), rhs)
            if not np.all(np.isfinite(delta)):
                return None, it, "a non-finite Newton correction"
            u += delta
            if np.max(np.abs(delta)) <= tol:
                md.set_variable("u", u)
                return u, it, None
        return None, self.d.newton_max_iter, (f"Newton did not converge in {self.d.newton_max_iter} iterations "
                                               f"(last correction {np.max(np.abs(delta)):.3g} m)")

    def step(self, dt, t1=None):
        """One Newmark step of length dt, to t1 (default t + dt); returns None, or why it failed."""
        d, md = self.d, self.p.md
        t1 = self.t + dt if t1 is None else t1
        self.set_mass_matrix(dt)
        u_tilde = self.u + dt * self.v + dt * dt * (0.5 - d.beta) * self.a
        f1 = self.f_ext(t1)
        md.set_private_rhs(self.p.rhs_brick, self.p.mass.mult(u_tilde).ravel() / (d.beta * dt * dt) + f1)
        md.set_variable("u_n", self.u)
        guess = self.u + dt * self.v + 0.5 * dt * dt * self.a
        guess[self.fixed] = self.prescribed_u(t1)
        u1, its, why = self.newton(guess)
        self.iterations.append(its)
        if u1 is None:
            md.set_variable("u", self.u)
            return why
        a1 = (u1 - u_tilde) / (d.beta * dt * dt)
        v1 = self.v + dt * ((1 - d.gamma) * self.a + d.gamma * a1)
        du = u1 - self.u
        f0 = self.f_ext(self.t)
        self.external_work += 0.5 * float((f0 + f1) @ du)
        self.external_work += 0.5 * float((self.reaction + self.reaction_next) @ du[self.fixed])
        self.reaction = self.reaction_next
        self.u, self.v, self.a = u1, v1, a1
        self.t, self.step_no = t1, self.step_no + 1
        return None


def history_columns(d):
    """The history.csv columns the adapter fills (ricochet's names, docs/outputs.md)."""
    comps = "xyz"[: d.dim]
    cols = ["time", "kinetic_energy", "strain_energy", "total_energy", "external_work"]
    if any(ob.friction > 0 for ob in d.obstacles):
        cols.append("friction_dissipation")
    if d.obstacles:
        cols.append("contact_energy")
    cols += [f"momentum_{c}" for c in comps]
    cols += ["angular_momentum"] if d.dim == 2 else [f"angular_momentum_{c}" for c in comps]
    cols.append("von_mises_max")
    if d.obstacles:
        cols += ["penetration_max", "normal_force", "tangential_force"]
    for name, _ in d.probes:
        cols += [f"{name}_u{c}" for c in comps] + [f"{name}_v{c}" for c in comps]
    return cols


class Observer:
    """The history columns and the summary quantities, from the Stepper's state."""

    def __init__(self, d, prob, stepper):
        self.d, self.p, self.s = d, prob, stepper
        gf, mim = prob.gf, prob.mim
        self.gf = gf
        self.columns = history_columns(d)
        self.rows = []
        self.vm_expr = [von_mises_gwfl(law, d.dim, d.stress_measure) for law in prob.laws]
        # (expression, im_data, region, interior?) per non-empty part of each body
        self.vm_parts = []
        for b in range(len(d.bodies)):
            for region, interior in ((INTERIOR_REGION0 + b, True), (EDGE_REGION0 + b, False)):
                if region in prob.mesh.regions():
                    self.vm_parts.append((self.vm_expr[b], gf.MeshImData(mim, region), region, interior))
        self.vm_max, self.vm_time = 0.0, 0.0
        self.vm_interior_max, self.vm_interior_time = 0.0, 0.0
        self.pen_max = 0.0
        self.dissipation = 0.0
        self.impulse_n = self.impulse_t = 0.0
        self.contact_start = self.contact_end = None
        self.forces = self.contact_forces()

    # -- pieces
    def integral(self, expr, region):
        return float(self.gf.asm_generic(self.p.mim, 0, expr, region, self.p.md))

    def strain_energy(self):
        return sum(self.integral(f"{num(b.thickness)}*{law['W']}", BODY_REGION0 + i)
                   for i, (b, law) in enumerate(zip(self.d.bodies, self.p.laws)))

    def von_mises(self):
        """The largest von Mises equivalent at the integration points now [Pa]. It and the
        largest over the interior cells are recorded as peaks, with the current time."""
        peak = interior = 0.0
        for expr, mimd, region, inner in self.vm_parts:
            vm = float(np.max(self.p.md.interpolation(expr, mimd, region)))
            peak = max(peak, vm)
            if inner:
                interior = max(interior, vm)
        if peak > self.vm_max:
            self.vm_max, self.vm_time = peak, self.s.t
        if interior > self.vm_interior_max:
            self.vm_interior_max, self.vm_interior_time = interior, self.s.t
        return peak

    def contact_forces(self):
        """(normal, tangential) total contact force at the current state [N]."""
        fn = ft = 0.0
        for c in self.p.contacts:
            e, x = self.d.bodies[c["body"]].thickness, c["expr"]
            fn += self.integral(f"{num(e)}*{x['pn']}", c["region"])
            if x["ft"]:
                if self.d.dim == 2:
                    t = f"[{x['n']}(2);-{x['n']}(1)]"
                    ft += self.integral(f"{num(e)}*({x['ft']}.{t})", c["region"])
                else:
                    ft += self.integral(f"{num(e)}*Norm({x['ft']})", c["region"])
        return fn, ft

    def contact_energy(self):
        """The penalty's stored energy, e * integral of (r g^2 / 2 + |f_t|^2 / (2 r)) [J]."""
        total = 0.0
        for c in self.p.contacts:
            e, x = self.d.bodies[c["body"]].thickness, c["expr"]
            expr = f"{num(0.5 * self.d.penalty)}*sqr(neg_part({x['gap']}))"
            if x["ft"]:
                expr += f"+Norm_sqr({x['ft']})/{num(2 * self.d.penalty)}"
            total += self.integral(f"{num(e)}*({expr})", c["region"])
        return total

    def penetration(self):
        """The largest depth of a contact-candidate node behind its obstacle, >= 0 [m]."""
        u = self.s.u[self.p.node_dofs]
        depth = 0.0
        for ob in self.d.obstacles:
            if len(ob.nodes):
                g = (self.d.nodes[ob.nodes] + u[ob.nodes]) @ ob.normal - ob.point @ ob.normal
                depth = max(depth, float(np.max(-g)))
        return max(depth, 0.0)

    def momenta(self):
        """(linear momentum, angular momentum about the moving centre of mass) with the
        consistent mass: p = integral of rho v = sum of M v, L = integral of rho x x v - x_c x p;
        x and v are interpolated alike, so integral of rho x x v = sum over nodes of x_i x (M v)_i."""
        d, nd = self.d, self.p.node_dofs
        mv = self.p.mass.mult(self.s.v).ravel()[nd]  # (N, dim): rows of M v per node
        x = d.nodes + self.s.u[nd]
        mx = self.p.mass.mult(self.x_ref() + self.s.u).ravel()[nd]
        p = mv.sum(0)
        mass = self.total_mass()
        xc = mx.sum(0) / mass
        if d.dim == 2:
            lz = float(np.sum(x[:, 0] * mv[:, 1] - x[:, 1] * mv[:, 0]) - (xc[0] * p[1] - xc[1] * p[0]))
            return list(p), [lz]
        l = np.cross(x, mv).sum(0) - np.cross(xc, p)
        return list(p), list(l)

    def x_ref(self):
        """The reference positions as a dof vector."""
        if not hasattr(self, "_x_ref"):
            self._x_ref = np.zeros(self.s.n)
            for c in range(self.d.dim):
                self._x_ref[self.p.node_dofs[:, c]] = self.d.nodes[:, c]
        return self._x_ref

    def total_mass(self):
        """The bodies' mass, the sum of M over one component's dofs [kg]."""
        if not hasattr(self, "_mass"):
            ones = np.zeros(self.s.n)
            ones[self.p.node_dofs[:, 0]] = 1.0
            self._mass = float(self.p.mass.mult(ones).ravel()[self.p.node_dofs[:, 0]].sum())
        return self._mass

    # -- per step and per sample
    def after_step(self, dt, sample):
        """Contact bookkeeping after a converged step (before the friction state moves on)."""
        s, d = self.s, self.d
        fn0, ft0 = self.forces
        self.forces = fn1, ft1 = self.contact_forces()
        self.impulse_n += dt * ((1 - d.gamma) * fn0 + d.gamma * fn1)
        self.impulse_t += dt * ((1 - d.gamma) * ft0 + d.gamma * ft1)
        if fn1 > 0:
            if self.contact_start is None:
                self.contact_start = s.t - dt
            self.contact_end = s.t
        self.pen_max = max(self.pen_max, self.penetration())
        for c in self.p.contacts:
            x = c["expr"]
            if x["ft"]:
                e = d.bodies[c["body"]].thickness
                self.dissipation += self.integral(
                    f"{num(e)}*Norm({x['ft']})*Norm({x['trial']}-{x['ft']})/{num(d.penalty)}", c["region"])
        self.contact_energy_now = self.contact_energy() if (sample and d.obstacles) else None
        for c in self.p.contacts:
            x = c["expr"]
            if x["ft"]:
                k, b = c["obstacle"], c["body"]
                self.p.md.set_variable(f"ft{k}_{b}", np.asarray(
                    self.p.md.interpolation(x["ft"], c["mimd"], c["region"])).ravel())
        if d.stress_every_step or sample:
            return self.von_mises()
        return None

    def sample(self, vm=None):
        s, d = self.s, self.d
        if vm is None:
            vm = self.von_mises()
        ke = 0.5 * float(s.v @ self.p.mass.mult(s.v).ravel())
        se = self.strain_energy()
        row = {"time": s.t, "kinetic_energy": ke, "strain_energy": se, "total_energy": ke + se,
               "external_work": s.external_work,
               "friction_dissipation": self.dissipation, "von_mises_max": vm}
        if d.obstacles:
            ce = getattr(self, "contact_energy_now", None)
            row["contact_energy"] = self.contact_energy() if ce is None else ce
            row["penetration_max"] = self.penetration()
            row["normal_force"], row["tangential_force"] = self.forces
        p, l = self.momenta()
        comps = "xyz"[: d.dim]
        for c, val in zip(comps, p):
            row[f"momentum_{c}"] = val
        if d.dim == 2:
            row["angular_momentum"] = l[0]
        else:
            for c, val in zip(comps, l):
                row[f"angular_momentum_{c}"] = val
        nd = self.p.node_dofs
        for name, node in d.probes:
            for k, c in enumerate(comps):
                row[f"{name}_u{c}"] = s.u[nd[node, k]]
                row[f"{name}_v{c}"] = s.v[nd[node, k]]
        self.rows.append([float(row[c]) for c in self.columns])

    def summary(self):
        out = {"von_mises_max": self.vm_max, "von_mises_max_time": self.vm_time}
        if any(inner for *_, inner in self.vm_parts):
            out["von_mises_interior_max"] = self.vm_interior_max
            out["von_mises_interior_max_time"] = self.vm_interior_time
        if self.d.obstacles:
            out["penetration_max"] = self.pen_max
            out["contact_impulse_normal"] = self.impulse_n
            out["contact_impulse_tangential"] = self.impulse_t
            if self.contact_start is not None:
                out["contact_start_time"] = self.contact_start
                out["contact_end_time"] = self.contact_end
                out["contact_duration"] = self.contact_end - self.contact_start
        if any(ob.friction > 0 for ob in self.d.obstacles):
            out["friction_dissipation"] = self.dissipation
        return out


def sample_steps(d):
    """The steps at which ricochet samples the history: round(k interval / dt) for k = 0, 1, ...,
    and the last step; every step when the interval is at most one step."""
    if not d.interval > d.dt:
        return set(range(d.steps + 1))
    out, k = {0, d.steps}, 1
    while True:
        n = int(round(k * d.interval / d.dt))
        if n >= d.steps:
            return out
        out.add(n)
        k += 1


def write_history(path, columns, rows):
    with open(path, "w", encoding="utf-8") as f:
        f.write(",".join(columns) + "\n")
        for r in rows:
            f.write(",".join(f"{x:.17g}" for x in r) + "\n")


def write_result(path, d, status, reason, stepper, observer, wall0, cpu):
    result = {
        "format": "ricochet-external-result", "version": 1, "status": status,
        "steps": stepper.step_no, "dt": d.dt, "time_reached": stepper.t,
        "code": CODE, "code_version": getfem_version(),
        "solver_cpu_seconds": cpu,  # the time loop's CPU time, as ricochet's own cpu_seconds
        "summary": {k: float(v) for k, v in observer.summary().items() if math.isfinite(v)},
        "translation": {"translated": d.translated, "not_translated": d.not_translated,
                        "notes": d.notes + [f"Newton iterations per step: mean "
                                            f"{np.mean(stepper.iterations) if stepper.iterations else 0:.2f}, "
                                            f"max {max(stepper.iterations, default=0)}; iterative linear solves "
                                            f"that fell back to MUMPS: {stepper.direct_solves}; time loop CPU "
                                            f"{cpu:.1f} s, adapter wall {time.time() - wall0:.1f} s"]},
    }
    if reason:
        result["reason"] = reason
    with open(path, "w", encoding="utf-8") as f:
        json.dump(result, f, indent=1)
        f.write("\n")


def progress(message):
    print(message, flush=True)


def run(d, out_dir, log=progress):
    """Build, integrate to time.end, write result.json and history.csv; returns the status."""
    wall0 = time.time()
    prob = build(d)
    log(f"getfem: {len(d.nodes)} nodes, {prob.mesh.nbcvs()} cells, {prob.mf.nbdof()} dofs, "
        f"{sum(c['faces'] for c in prob.contacts)} contact faces, {d.steps} steps of {d.dt:g} s")
    stepper = Stepper(d, prob)
    obs = Observer(d, prob, stepper)
    samples = sample_steps(d)
    obs.sample()
    status, reason = "ok", None
    report_every = max(1, d.steps // 20)
    cpu0 = time.process_time()
    for n in range(1, d.steps + 1):
        t1 = n * d.dt if n < d.steps else d.end
        dt = t1 - stepper.t
        if abs(dt - d.dt) <= 1e-9 * d.dt:
            dt = d.dt
        sample = n in samples
        try:
            why = stepper.step(dt, t1)
            if not why:
                vm = obs.after_step(dt, sample)
                if sample:
                    obs.sample(vm)
        except RuntimeError as exc:  # GetFEM's own errors: the run stops here
            why = "GetFEM: " + " ".join(str(exc).split())[:300]
        if why:
            status, reason = "diverged", f"step {n} (t = {t1:.6g} s): {why}"
            log(f"getfem: {reason}")
            break
        if n % report_every == 0 or n == d.steps:
            log(f"getfem: step {n}/{d.steps} t = {stepper.t:.6g} s, Newton {stepper.iterations[-1]}, "
                f"{time.time() - wall0:.1f} s")
    cpu = time.process_time() - cpu0
    if status != "ok" and (not obs.rows or obs.rows[-1][0] != stepper.t):
        try:
            obs.sample()  # the last converged state
        except RuntimeError:
            pass
    write_history(os.path.join(out_dir, "history.csv"), obs.columns, obs.rows)
    write_result(os.path.join(out_dir, "result.json"), d, status, reason, stepper, obs, wall0, cpu)
    return status


def main(argv):
    if len(argv) != 3:
        print("usage: getfem.py CASE_JSON OUT_DIR", file=sys.stderr)
        return 1
    try:
        with open(argv[1], encoding="utf-8") as f:
            case = json.load(f)
        d = describe(case)
        status = run(d, argv[2])
        progress(f"getfem: {status}")
        return 0
    except Unsupported as exc:
        print(f"getfem adapter: {exc}", file=sys.stderr)
        return 2
    except Failure as exc:
        print(f"getfem adapter: {exc}", file=sys.stderr)
        return 1
    except OSError as exc:
        print(f"getfem adapter: {' '.join(str(exc).split())}", file=sys.stderr)
        return 1
    except (ValueError, KeyError, TypeError) as exc:  # a malformed case.json
        print(f"getfem adapter: case.json: {type(exc).__name__}: {' '.join(str(exc).split())}", file=sys.stderr)
        return 1
    except RuntimeError as exc:  # GetFEM's errors before any result exists
        print(f"getfem adapter: GetFEM: {' '.join(str(exc).split())}", file=sys.stderr)
        return 1
    except Exception as exc:  # anything else, still on one line
        print(f"getfem adapter: {type(exc).__name__}: {' '.join(str(exc).split())}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
