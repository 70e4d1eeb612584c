#!/usr/bin/python3
"""ricochet's CalculiX adapter: runs a case with CalculiX `ccx` (2.20) and reads it back.

    /usr/bin/python3 adapters/calculix.py OUT/external/case.json OUT/external

The contract (case.json in; result.json and history.csv out; exit 0, 1 or 2) is
docs/peers.md. This file translates the case into a CalculiX deck `job.inp`, runs
`ccx -i job` in the output folder, and turns its `job.dat` into ricochet's history. Standard
output gets progress lines; a failure is one line on standard error.

The formulation as translated
-----------------------------
Bodies. A 2D body becomes ONE LAYER of 8-node bricks through its thickness e: each node
(x, y) has two copies, (x, y, -e/2) and (x, y, +e/2), and each Q4 cell the brick between
them (C3D8: full 2 x 2 x 2 Gauss integration, like ricochet's Q4; `q4_hourglass` becomes the
reduced-integration C3D8R with CalculiX's own hourglass control). Plane stress leaves both
faces free (sigma_zz = 0 in the weak sense of one linear layer); plane strain fixes the
z-displacement of every node of both faces. CalculiX's plane-stress elements (CPS4) are not
used: in explicit dynamics they do not move in CalculiX 2.20. A 3D body's hex8 cells are
C3D8 (C3D8R for `hex8_hourglass`) as they are. Simplex meshes (tri3, tet4) are not
translated. Everything is geometrically nonlinear (*STEP, NLGEOM).

Materials (CalculiX 2.20 User's Manual, *ELASTIC and *HYPERELASTIC):
  * saint_venant_kirchhoff -> *ELASTIC (E, nu) with NLGEOM: CalculiX's geometrically
    nonlinear linear elasticity is S = lambda tr(E) I + 2 mu E of the Green-Lagrange strain,
    St Venant-Kirchhoff exactly as ricochet's (solver/materials/material3d.hpp).
  * mooney_rivlin -> *HYPERELASTIC, MOONEY-RIVLIN with C10, C01 and D1 = 2/kappa:
    U = C10 (J^-2/3 I1 - 3) + C01 (J^-4/3 I2 - 3) + (J - 1)^2 / D1, the same function as
    ricochet's W = c10 (J^-2/3 I1 - 3) + c01 (J^-4/3 I2 - 3) + kappa/2 (J - 1)^2.
  * neo_hookean -> *HYPERELASTIC, NEO HOOKE with C10 = mu/2 and D1 = 2/kappa, kappa =
    lambda + 2 mu/3: U = C10 (J^-2/3 I1 - 3) + (J - 1)^2 / D1, the isochoric/volumetric split.
    ricochet's neo-Hookean is W = mu/2 (I1 - 3) - mu ln J + lambda/2 (ln J)^2 (Bonet & Wood):
    the same small-strain limit (shear modulus mu, bulk modulus kappa), a different law at
    finite strain. The translation says so in its notes.
  * blatz_ko has no CalculiX equivalent: not translated (exit 2).

Mass. CalculiX's explicit dynamics uses a lumped mass (the row sums of the C3D8 consistent
mass, which for a one-layer brick are half of ricochet's Q4 lumped nodal mass on each copy:
the initial kinetic energies agree to all printed digits); its implicit dynamics the
consistent mass. The adapter's kinetic energy is the integrator's measure: 1/2 sum m v^2
over the copies with half of ricochet's `mass` on each (explicit), and the consistent-mass
1/2 integral rho |v|^2 dV at the Gauss points (implicit). (CalculiX's own energy printout
takes the consistent-mass kinetic energy in explicit runs too, which is why its energy
balance drifts by up to 0.7 % on the M1 plate while this one stays at 2e-4.) Momenta and the
angular momentum use ricochet's lumped masses and the copies' mean velocity, as ricochet's.

Obstacles. A flat obstacle (2D `line`, 3D `plane`) becomes a layer of C3D8 bricks below its
plane, every node fixed, so its top face IS the plane and does not move (its material,
a soft heavy elastic one, then does not matter; it is chosen so that it never limits the
explicit stable increment). Along the plane it covers the bodies' extent, plus where their
initial velocities carry them by `time.end`, plus a quarter of the extent on each side; in
2D it spans twice the thickest body in z, so that the slab's faces stay over it when they
thicken under Poisson. Contact is CalculiX's node-to-surface penalty (*CONTACT PAIR,
TYPE=NODE TO SURFACE): slave, the bodies' boundary faces whose nodes are all ricochet's
contact candidates of that obstacle; master, the ground's top face. The law is
*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR: a slave node of area a penetrating by d feels
a K d (1/2 + arctan(d/eps)/pi) along the normal, eps = pi sigma_inf / K (CalculiX 2.20
source, springforc_n2f.f), no force at a clearance; sigma_inf is set so that
eps = 1e-6 sqrt(a_median), a linear law for any penetration that matters (the same eps in
every interaction). A slave node's area a is its share of the pair's slave faces (a quarter
of each adjacent brick face: ricochet's a_i shared by the two copies).

ricochet's penalty has one spring k_i [N/m] per candidate over its boundary share a_i [m^2];
CalculiX takes one pressure slope K [N/m^3] per *SURFACE INTERACTION. `penalty = "ricochet"`
gives each slave face the slope of its own nodes, K_face = the mean of k_i/a_i over them (a
2D slab's brick face: its two 2D nodes; a 3D quad face: its four), so a node's spring,
sum over its faces of K_face x its share of the face, is ricochet's k_i where the ratio
varies smoothly (on the oblique plate the nodes that touch, the arc bottom, have a ratio
25-35 % above the sides'). The faces are grouped by slope: one group per distinct K_face (to
4 significant digits) when there are at most 8, else 8 groups of neighbouring values, chosen
so that the largest spread max/min of K_face within a group is as small as 8 groups allow
(a plain quantile split mixes the few distinct values that matter with a dominant repeated
one: 15 % off on the plate, against 0.4-0.5 % this way). Each group's slope is the mean
K_face of its faces; each group is one slave surface, one *SURFACE INTERACTION and one
*CONTACT PAIR. The notes give the number of groups, the largest relative deviation of a
face's K_face from its group's slope, and the largest relative difference of a node's
translated spring from ricochet's k_i (on the plate at the corners of the arc and the top,
where the ratio jumps: up to 5 %). A number `penalty = K` keeps one group of slope K.
Each pair has its own master: a copy of the ground layer (own nodes and elements, the same
place, all fixed; the reaction is summed over all copies). Pairs sharing one master surface
do not work in ccx 2.20, explicit or implicit: it catalogues the master triangles'
neighbours over all pairs at once by their edges' nodes (trianeighbor.f), so a pair's
triangles get neighbours in another pair's copy of the triangulation, the search for a slave
node's master face stops at a false border, and that node gets no spring (on the M1 plate,
8 pairs of equal slope on one master lost a third of the contact energy, and the implicit
run diverged; on 8 copies they reproduce the single pair to ccx's printed digits).

HARD contact is not used: CalculiX turns it into LINEAR in explicit dynamics anyway. With
friction mu > 0, *FRICTION in each interaction with mu and a stick slope (default: that
interaction's K, as ricochet's tangential spring has the normal one's stiffness). The
translation notes give the springs' own critical step, min over the slave nodes of
2 sqrt(m_i / k_i) with k_i the translated spring; a time.dt above it makes the explicit run
unstable, and one below it is not enough either: on the M2 plate at dt = 1e-6 s,
K = 1e11 N/m^3 (springs' step 3.1e-6 s) gains 57 % energy by 2 ms, K = 3e10 N/m^3
(5.7e-6 s) keeps it to 2e-4.

Time. `procedure = "explicit"`: *DYNAMIC, EXPLICIT (central differences) with the initial
and the maximum increment time.dt: CalculiX then takes exactly time.end / time.dt
increments, unless its own stable-increment estimate is smaller (then it takes that one; the
result's `dt` is the increment it reports, and a note says so). `procedure = "implicit"`:
*DYNAMIC, DIRECT (no adaptation) with ALPHA = `alpha` (Hilber-Hughes-Taylor alpha method,
CalculiX 2.20 User's Manual, *DYNAMIC), the increment time.dt, Newton iterations with the
penalty contact inside. Initial velocities: *INITIAL CONDITIONS, TYPE=VELOCITY per node
(both copies of a 2D node get its (vx, vy), vz = 0). Gravity: *DLOAD, GRAV. Prescribed
degrees of freedom of value 0 (fixed supports) become *BOUNDARY on both copies; others, and
nodal loads, are not translated (exit 2).

Outputs. Every n = round(output.interval / dt) increments (every increment for interval 0)
CalculiX prints to job.dat (*NODE PRINT, FREQUENCY=n): the bodies' nodal displacements and
velocities, the grounds' total reaction force (their nodes are fixed, so the sum is minus the
contact springs' force on the ground, i.e. the force on the bodies), the contact spring
energy (*CONTACT PRINT, CELS) and the contact pressures (CSTR). The t = 0 row is the initial
state. job.dat is read as it streams (one sample in memory) and removed after a run that
reached time.end (option keep_dat). From these the adapter computes, at each sample:
  * kinetic_energy (above), strain_energy = sum over Gauss points of W(F) w det J0 with F from
    the nodal displacements and CalculiX's law (C3D8: 2x2x2 points; C3D8R: the centre, so
    the hourglass modes' energy is missing; it equals CalculiX's own internal energy to its
    7 printed digits), total_energy = their sum (the bodies only; the grounds do not
    deform), contact_energy = CalculiX's contact spring energy (CELS), external_work =
    sum m g . u with gravity;
  * von_mises_max: the von Mises equivalent of the 3D `output.stress_measure` stress
    recomputed from F at the Gauss points (S the law's 2nd Piola-Kirchhoff stress,
    tau = F S F^T, sigma = tau / J): CalculiX's own stress output is Cauchy only. The summary's
    value is the largest over the samples, ricochet's own over every step;
  * normal_force = sum over obstacles of the grounds' reaction . n (the force on the bodies,
    > 0 pushing them away), tangential_force along t = (n_y, -n_x) in 2D (the magnitude of
    the tangential part in 3D); contact_nodes = (2D) nodes of which a copy has a positive
    contact pressure; penetration_max = the deepest candidate copy behind its plane;
  * momentum, angular momentum, and each probe's displacement and velocity (2D: the mean of
    the node's two copies, x and y components).
The contact impulses and the contact start/end times of the summary come from the sampled
forces (trapezoidal rule; the first and last sample with a positive normal force), so they
are as fine as output.interval. Not reported: friction_dissipation and contact_work
(CalculiX gives neither per sample: the energy balance counts the friction loss as error),
hourglass_energy.

Options (case.json `options`, from `[external.options]`):
  procedure         "explicit" (default) or "implicit"
  alpha             HHT alpha of the implicit procedure, in [-1/3, 0]; default -0.05
  penalty           "ricochet" (default: each face its nodes' k_i/a_i, grouped: above) or a
                    number K > 0 [N/m^3] (one interaction)
  stick_slope       the friction's stick slope [N/m^3], > 0, in every interaction; default:
                    each interaction's penalty slope K
  ground_thickness  the ground layer's depth below the plane [m], > 0; default: its element
                    length along the plane (an eighth of the bodies' extent)
  keep_dat          true: keep job.dat (every body node at every sample: large) after a run
                    that reached time.end; default false (it is removed once read)
Environment: RICOCHET_THREADS (default 1) sets OMP_NUM_THREADS and CalculiX's
CCX_NPROC_* variables; RICOCHET_CCX names the ccx program (default `ccx` on PATH).
"""

import json
import math
import os
import re
import resource
import subprocess
import sys
import warnings
from dataclasses import dataclass, field

import numpy as np

JOB = "job"
OPTION_KEYS = ("procedure", "alpha", "penalty", "stick_slope", "ground_thickness", "keep_dat")
# Cell types and the CalculiX element of each ricochet element.
ELEMENT_TYPES = {"q4": "C3D8", "hex8": "C3D8", "q4_hourglass": "C3D8R", "hex8_hourglass": "C3D8R"}
# C3D8 faces (CalculiX 2.20 User's Manual, *SURFACE), corner numbers from 0; each face's
# outward normal follows the right-hand rule on its nodes.
C3D8_FACES = ((0, 1, 2, 3), (4, 7, 6, 5), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7))
GROUND_EXTENT_DIVISIONS = 8      # ground element length = the bodies' extent / 8
GROUND_MARGIN = 0.25             # ground beyond the travelled extent, per side, x the extent
SMOOTHING = 1e-6                 # eps of the LINEAR law = SMOOTHING x sqrt(median slave area)
MAX_GROUPS = 8                   # *SURFACE INTERACTIONs (slopes) per obstacle, penalty = "ricochet"


class TranslationError(Exception):
    """Something in the case that matters and has no CalculiX translation (exit 2)."""


class RunError(Exception):
    """ccx could not be run or failed before any result (exit 1)."""


# ----------------------------------------------------------------------------------------
# Options

@dataclass
class Options:
    procedure: str = "explicit"
    alpha: float = -0.05
    penalty: object = "ricochet"      # "ricochet" or a number [N/m^3]
    stick_slope: float | None = None
    ground_thickness: float | None = None
    keep_dat: bool = False


def _number(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def parse_options(raw):
    """The validated options; TranslationError naming the key and what is allowed."""
    if raw is None:
        raw = {}
    if not isinstance(raw, dict):
        raise TranslationError("options: must be a table (got %s)" % type(raw).__name__)
    for key in raw:
        if key not in OPTION_KEYS:
            raise TranslationError("options.%s: unknown option (allowed: %s)" % (key, ", ".join(OPTION_KEYS)))
    o = Options()
    if "procedure" in raw:
        if raw["procedure"] not in ("explicit", "implicit"):
            raise TranslationError('options.procedure: must be "explicit" or "implicit" (got %s)'
                                   % json.dumps(raw["procedure"]))
        o.procedure = raw["procedure"]
    if "alpha" in raw:
        a = raw["alpha"]
        if o.procedure != "implicit":
            raise TranslationError('options.alpha: applies to procedure = "implicit" only')
        if not _number(a) or not (-1.0 / 3.0 - 1e-12 <= a <= 0.0):
            raise TranslationError("options.alpha: must be a number in [-1/3, 0] (got %s)" % json.dumps(a))
        o.alpha = float(a)
    if "penalty" in raw:
        p = raw["penalty"]
        if p != "ricochet" and not (_number(p) and p > 0):
            raise TranslationError('options.penalty: must be "ricochet" or a number > 0 [N/m^3] (got %s)'
                                   % json.dumps(p))
        o.penalty = p if p == "ricochet" else float(p)
    for key in ("stick_slope", "ground_thickness"):
        if key in raw:
            v = raw[key]
            if not (_number(v) and v > 0):
                raise TranslationError("options.%s: must be a number > 0 (got %s)" % (key, json.dumps(v)))
            setattr(o, key, float(v))
    if "keep_dat" in raw:
        if not isinstance(raw["keep_dat"], bool):
            raise TranslationError("options.keep_dat: must be true or false (got %s)"
                                   % json.dumps(raw["keep_dat"]))
        o.keep_dat = raw["keep_dat"]
    return o


# ----------------------------------------------------------------------------------------
# Case checks

def check_translatable(case):
    """TranslationError for anything that matters and cannot be translated."""
    dim = case["dimension"]
    if dim not in (2, 3):
        raise TranslationError("dimension: must be 2 or 3 (got %s)" % dim)
    for b in case["bodies"]:
        model = b["material"]["model"]
        if model == "blatz_ko":
            raise TranslationError("body '%s': blatz_ko has no CalculiX equivalent" % b["name"])
        if model not in ("saint_venant_kirchhoff", "neo_hookean", "mooney_rivlin"):
            raise TranslationError("body '%s': unknown material model '%s'" % (b["name"], model))
        if b["element"] not in ELEMENT_TYPES:
            raise TranslationError("body '%s': element '%s' is not translated (the adapter takes "
                                   "quadrilateral and hexahedral meshes only)" % (b["name"], b["element"]))
        wanted = "quad4" if dim == 2 else "hex8"
        other = sorted(k for k, v in b["cells"].items() if k != wanted and v)
        if other:
            raise TranslationError("body '%s': %s cells are not translated (the adapter takes %s only)"
                                   % (b["name"], other[0], wanted))
    pairs = case["contact"].get("body_pairs", [])
    if pairs or any(c["obstacle"] < 0 for c in case["contact"]["candidates"]):
        first = pairs[0] if pairs else None
        what = "'%s' on '%s'" % (first["slave"], first["master"]) if first else "between bodies"
        raise TranslationError("contact.body_pairs: contact between bodies (%s) is not translated "
                               "(the adapter takes rigid flat obstacles only)" % what)
    flat = "line" if dim == 2 else "plane"
    for ob in case["obstacles"]:
        if ob["type"] != flat:
            raise TranslationError("obstacle '%s': a %s is not translated (the adapter takes flat "
                                   "obstacles only: %s)" % (ob["name"], ob["type"], flat))
    for p in case.get("prescribed", []):
        if p["value"] != 0:
            raise TranslationError("prescribed: node %d component %d %s %s is not translated (the "
                                   "adapter takes fixed supports, value 0, only)"
                                   % (p["node"], p["component"], p["kind"], p["value"]))
    if case.get("loads"):
        raise TranslationError("loads: nodal loads (%d) are not translated" % len(case["loads"]))
    for ob_index, ob in enumerate(case["obstacles"]):
        mus = {c["friction"] for c in case["contact"]["candidates"] if c["obstacle"] == ob_index}
        if len(mus) > 1:
            raise TranslationError("obstacle '%s': candidates with different friction coefficients "
                                   "%s (CalculiX takes one per interaction)" % (ob["name"], sorted(mus)))


# ----------------------------------------------------------------------------------------
# The brick model

@dataclass
class Brick:
    """The bodies as CalculiX sees them, ids from 1."""
    coords: np.ndarray            # (n, 3) reference positions of the body nodes, id = index + 1
    copies: np.ndarray            # (N, c) ids of each ricochet node's copies (c = 2 in 2D, 1 in 3D)
    elements: list                # per body: (e, 8) node ids
    element_ids: list             # per body: (e,) element ids
    body_nodes: list              # per body: sorted node ids
    boundary_faces: list          # per body: list of (element id, face number 1..6, ricochet nodes)


def _body_cells(case, b):
    kind, corners = ("quad4", 4) if case["dimension"] == 2 else ("hex8", 8)
    return np.asarray(b["cells"][kind], dtype=int).reshape(-1, corners)


def build_bricks(case):
    """The bodies' C3D8 nodes and elements (2D: one layer through the thickness)."""
    X = np.asarray(case["nodes"], dtype=float)
    n = len(X)
    dim = case["dimension"]
    if dim == 2:
        coords = np.zeros((2 * n, 3))
        coords[:n, :2] = X
        coords[n:, :2] = X
        for b in case["bodies"]:
            first, count = b["nodes"]
            half = 0.5 * b["thickness"]
            coords[first:first + count, 2] = -half
            coords[n + first:n + first + count, 2] = half
        copies = np.stack([np.arange(n) + 1, np.arange(n) + n + 1], axis=1)
    else:
        coords = X.copy()
        copies = (np.arange(n) + 1).reshape(-1, 1)
    elements, element_ids, body_nodes, faces = [], [], [], []
    next_id = 1
    for b in case["bodies"]:
        cells = _body_cells(case, b)
        if dim == 2:
            conn = np.concatenate([copies[cells, 0], copies[cells, 1]], axis=1)
        else:
            conn = copies[cells, 0]
        ids = np.arange(next_id, next_id + len(cells))
        next_id += len(cells)
        elements.append(conn)
        element_ids.append(ids)
        first, count = b["nodes"]
        body_nodes.append(np.sort(copies[first:first + count].ravel()))
        faces.append(_boundary_faces(cells, ids, dim))
    return Brick(coords, copies, elements, element_ids, body_nodes, faces)


def _boundary_faces(cells, ids, dim):
    """(element id, CalculiX face number, the face's ricochet nodes) of each boundary face."""
    if dim == 2:
        # Edge k of a quad (corners k, k+1) is face S3 + k of its brick.
        local = [((k, (k + 1) % 4), 3 + k) for k in range(4)]
    else:
        local = [(f, s + 1) for s, f in enumerate(C3D8_FACES)]
    count = {}
    for cell in cells:
        for corners, _ in local:
            key = tuple(sorted(cell[list(corners)]))
            count[key] = count.get(key, 0) + 1
    out = []
    for cell, eid in zip(cells, ids):
        for corners, face in local:
            nodes = cell[list(corners)]
            if count[tuple(sorted(nodes))] == 1:
                out.append((int(eid), face, tuple(int(v) for v in nodes)))
    return out


@dataclass
class Ground:
    """The fixed brick layer of one flat obstacle."""
    name: str
    normal: np.ndarray            # unit, 3 components
    point: np.ndarray             # 3 components
    coords: np.ndarray            # (m, 3)
    elements: np.ndarray          # (g, 8) local node indices, top face = S2
    elem_size: float
    depth: float
    copies: int = 1               # identical layers in the deck, one per contact pair (master)


def _tangents(normal, dim):
    if dim == 2:
        t = np.array([normal[1], -normal[0], 0.0])
        return t, np.array([0.0, 0.0, 1.0])
    helper = np.array([1.0, 0.0, 0.0]) if abs(normal[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    t1 = np.cross(normal, helper)
    t1 /= np.linalg.norm(t1)
    return t1, np.cross(normal, t1)


def _extent(s, v, end):
    """The interval along one tangent the ground covers: the nodes' span, their travel, margins."""
    lo, hi = float(s.min()), float(s.max())
    span = max(hi - lo, 1e-12)
    lo += min(0.0, float(v.min()) * end) - GROUND_MARGIN * span
    hi += max(0.0, float(v.max()) * end) + GROUND_MARGIN * span
    return lo, hi, span


def build_ground(case, ob, options):
    dim = case["dimension"]
    X = np.asarray(case["nodes"], dtype=float)
    V = np.asarray(case["velocity"], dtype=float)
    normal = np.zeros(3)
    normal[:dim] = ob["normal"]
    normal /= np.linalg.norm(normal)
    point = np.zeros(3)
    point[:dim] = ob["point"]
    a1, a2 = _tangents(normal, dim)
    X3 = np.zeros((len(X), 3))
    X3[:, :dim] = X
    V3 = np.zeros((len(V), 3))
    V3[:, :dim] = V
    end = case["time"]["end"]
    lo1, hi1, span1 = _extent((X3 - point) @ a1, V3 @ a1, end)
    if dim == 2:
        half = max(b["thickness"] for b in case["bodies"])  # twice the thickest slab, centred
        lo2, hi2, span2 = -half, half, 2 * half
    else:
        lo2, hi2, span2 = _extent((X3 - point) @ a2, V3 @ a2, end)
    h = max(span1, span2 if dim == 3 else 0.0) / GROUND_EXTENT_DIVISIONS
    n1 = max(1, math.ceil((hi1 - lo1) / h))
    n2 = 1 if dim == 2 else max(1, math.ceil((hi2 - lo2) / h))
    depth = options.ground_thickness or h
    s1 = np.linspace(lo1, hi1, n1 + 1)
    s2 = np.linspace(lo2, hi2, n2 + 1)
    s3 = np.array([-depth, 0.0])
    grid = np.array([[[point + u * a1 + w * a2 + d * normal for d in s3] for w in s2] for u in s1])
    coords = grid.reshape(-1, 3)
    index = lambda i, j, k: (i * (n2 + 1) + j) * 2 + k
    right_handed = np.dot(np.cross(a1, a2), normal) > 0
    elems = []
    for i in range(n1):
        for j in range(n2):
            quad = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)]
            if not right_handed:
                quad = [quad[0], quad[3], quad[2], quad[1]]
            elems.append([index(p, q, 0) for p, q in quad] + [index(p, q, 1) for p, q in quad])
    return Ground(ob["name"], normal, point, coords, np.array(elems), h, depth)


# ----------------------------------------------------------------------------------------
# Materials

def lame(young, poisson):
    mu = young / (2 * (1 + poisson))
    lam = young * poisson / ((1 + poisson) * (1 - 2 * poisson))
    return lam, mu


def material_card(m):
    """(CalculiX material lines, small-strain Young's modulus, translation note)."""
    model = m["model"]
    if model == "saint_venant_kirchhoff":
        E, nu = m["young"], m["poisson"]
        return (["*ELASTIC", "%s, %s" % (f20(E), f20(nu))], E,
                "saint_venant_kirchhoff -> *ELASTIC E = %g Pa, nu = %g with NLGEOM (St Venant-Kirchhoff)"
                % (E, nu))
    if model == "neo_hookean":
        lam, mu = lame(m["young"], m["poisson"])
        kappa = lam + 2 * mu / 3
        c10, d1 = mu / 2, 2 / kappa
        return (["*HYPERELASTIC, NEO HOOKE", "%s, %s" % (f20(c10), f20(d1))], m["young"],
                "neo_hookean -> *HYPERELASTIC, NEO HOOKE C10 = mu/2 = %g Pa, D1 = 2/kappa = %g 1/Pa"
                % (c10, d1))
    c10, c01, kappa = m["c10"], m["c01"], m["bulk_modulus"]
    mu = 2 * (c10 + c01)
    young = 9 * kappa * mu / (3 * kappa + mu)
    return (["*HYPERELASTIC, MOONEY-RIVLIN", "%s, %s, %s" % (f20(c10), f20(c01), f20(2 / kappa))], young,
            "mooney_rivlin -> *HYPERELASTIC, MOONEY-RIVLIN C10 = %g, C01 = %g Pa, D1 = 2/kappa = %g 1/Pa"
            % (c10, c01, 2 / kappa))


# ----------------------------------------------------------------------------------------
# Translation: case -> deck text + what the post-processing needs

@dataclass
class Translation:
    deck: str
    bricks: Brick
    grounds: list                 # Ground per obstacle
    slopes: list                  # per obstacle: its interactions' slopes K [N/m^3] ([]: no contact)
    frequency: int                # output every this many increments
    options: Options
    translated: list = field(default_factory=list)
    not_translated: list = field(default_factory=list)
    notes: list = field(default_factory=list)


def has_contact(tr):
    """Whether any obstacle has a contact pair."""
    return any(len(s) for s in tr.slopes)


def f20(x):
    """A number for the deck: ccx reads at most 20 characters per number."""
    return "%.12e" % float(x)


def _lines(ids, per_line=8):
    ids = [str(int(i)) for i in ids]
    return [", ".join(ids[k:k + per_line]) for k in range(0, len(ids), per_line)]


def face_ratios(cands, faces, name):
    """K_face [N/m^3] of each slave face: the mean of ricochet's k_i/a_i over its nodes (those
    with a boundary area and a spring; TranslationError when a face has none)."""
    ratio = {c["node"]: c["stiffness"] / c["area"] for c in cands if c["area"] > 0 and c["stiffness"] > 0}
    out = []
    for face in faces:
        r = [ratio[v] for v in face.nodes if v in ratio]
        if not r:
            raise TranslationError("obstacle '%s': a slave face (element %d, S%d) has no contact candidate "
                                   "with a boundary area and a stiffness, so no penalty slope (set "
                                   "options.penalty to a number)" % (name, face.element, face.face))
        out.append(float(np.mean(r)))
    return np.array(out)


def _split_log_range(x, groups):
    """Labels (0.., ascending) splitting the values x into `groups` runs of the sorted distinct
    values, the largest spread max/min of a run as small as it gets: the smallest width w of
    log x for which a greedy sweep needs at most `groups` runs (bisection), then the widest
    gaps inside runs split until there are `groups` runs (x has more distinct values)."""
    u = np.unique(np.log(x))

    def starts(w):
        out, i = [], 0
        while i < len(u) and len(out) <= groups:
            out.append(i)
            i = int(np.searchsorted(u, u[i] + w, side="right"))
        return out

    lo, hi = 0.0, float(u[-1] - u[0])
    while hi - lo > 1e-12 * max(1.0, hi):
        mid = 0.5 * (lo + hi)
        if len(starts(mid)) <= groups:
            hi = mid
        else:
            lo = mid
    first = set(starts(hi))
    gaps = np.diff(u)
    for i in np.argsort(-gaps, kind="stable"):
        if len(first) >= groups:
            break
        first.add(int(i) + 1)
    run = np.cumsum([1 if i in first else 0 for i in range(len(u))]) - 1
    return run[np.searchsorted(u, np.log(x))]


def group_slopes(K, groups=MAX_GROUPS):
    """(labels (f,), slopes (g,)) grouping the faces' slopes K_face for CalculiX's one slope per
    interaction: one group per distinct value to 4 significant digits when there are at most
    `groups` of them, else `groups` groups of neighbouring values (_split_log_range); each
    group's slope is the mean K_face of its faces. Groups are numbered by ascending slope."""
    K = np.asarray(K, dtype=float)
    keys = np.array([float("%.4g" % k) for k in K])
    distinct = np.unique(keys)
    if len(distinct) <= groups:
        labels = np.searchsorted(distinct, keys)
    else:
        labels = _split_log_range(K, groups)
    slopes = np.array([K[labels == g].mean() for g in range(int(labels.max()) + 1)])
    return labels, slopes


def penalty_groups(case, o, faces, options):
    """(labels, slopes, description, deviation) of obstacle o's slave faces: which interaction
    each face is in, each interaction's pressure slope K [N/m^3], a line for the translation,
    and the largest relative deviation of a face's K_face from its interaction's slope (None
    for a numeric options.penalty: one interaction)."""
    name = case["obstacles"][o]["name"]
    if options.penalty != "ricochet":
        K = float(options.penalty)
        return (np.zeros(len(faces), dtype=int), np.array([K]),
                "obstacle '%s': penalty slope K = %g N/m^3 (options.penalty), one interaction" % (name, K), None)
    cands = [c for c in case["contact"]["candidates"] if c["obstacle"] == o]
    Kf = face_ratios(cands, faces, name)
    labels, slopes = group_slopes(Kf)
    deviation = float(np.abs(Kf / slopes[labels] - 1).max())
    counts = np.bincount(labels, minlength=len(slopes))
    return labels, slopes, (
        "obstacle '%s': penalty slope per slave face K_face = the mean of ricochet's k_i/a_i over its nodes "
        "(%d faces, %d distinct to 4 digits, min %g, max %g N/m^3), grouped into %d interactions (CalculiX "
        "takes one slope per interaction), slopes %s N/m^3 (each the mean K_face of its faces) over %s faces"
        % (name, len(Kf), len({"%.4g" % k for k in Kf}), Kf.min(), Kf.max(), len(slopes),
           ", ".join("%.4g" % K for K in slopes), ", ".join(str(int(c)) for c in counts))), deviation


def face_area(X, face):
    """A slave face's reference area [m^2] (2D: edge length x thickness)."""
    p = X[list(face.nodes)]
    if len(face.nodes) == 2:
        return float(np.linalg.norm(p[1] - p[0])) * face.thickness
    return 0.5 * float(np.linalg.norm(np.cross(p[2] - p[0], p[3] - p[1])))


def node_springs(case, faces, face_slopes):
    """{ricochet node: the translated spring [N/m]}: over its slave faces, the face's slope x
    the face's area shared equally by its corners (as CalculiX shares it among the copies)."""
    X = np.asarray(case["nodes"], dtype=float)
    springs = {}
    for face, K in zip(faces, face_slopes):
        share = face_area(X, face) / len(face.nodes)
        for v in face.nodes:
            springs[v] = springs.get(v, 0.0) + K * share
    return springs


def spring_difference(cands, springs):
    """(largest |translated spring / ricochet's k_i - 1| over the slave nodes, that node)."""
    k = {c["node"]: c["stiffness"] for c in cands}
    diffs = [(abs(s / k[v] - 1), v) for v, s in springs.items() if k.get(v, 0) > 0]
    return max(diffs) if diffs else (None, None)


def penalty_step_note(case, springs, name):
    """The translated contact springs' own critical step, min over the slave nodes of 2 sqrt(m/k)."""
    mass = case["mass"]
    steps = [2 * math.sqrt(mass[v] / s) for v, s in springs.items() if s > 0 and mass[v] > 0]
    if not steps:
        return "obstacle '%s': no slave node with mass and a spring" % name
    dt = case["time"]["dt"]
    return ("obstacle '%s': the contact springs' critical step min 2 sqrt(m/k) = %.3g s%s"
            % (name, min(steps), "" if min(steps) > dt else ", below time.dt %g s: unstable" % dt))


def output_frequency(case):
    dt, interval = case["time"]["dt"], case["output"]["interval"]
    return max(1, int(round(interval / dt))) if interval > 0 else 1


def _node_lines(ids, coords):
    return ["%d, %s, %s, %s" % (i, f20(x), f20(y), f20(z)) for i, (x, y, z) in zip(ids, coords)]


def _element_lines(ids, conn):
    return ["%d, %s" % (eid, ", ".join(str(int(v)) for v in nodes)) for eid, nodes in zip(ids, conn)]


def body_cards(case, tr):
    """*NODE, *ELEMENT and the sets of the bodies."""
    bricks = tr.bricks
    L = ["*NODE, NSET=NBODIES"] + _node_lines(range(1, len(bricks.coords) + 1), bricks.coords)
    for k, b in enumerate(case["bodies"]):
        etype, count = ELEMENT_TYPES[b["element"]], len(bricks.element_ids[k])
        L.append("*ELEMENT, TYPE=%s, ELSET=BODY%d" % (etype, k + 1))
        L += _element_lines(bricks.element_ids[k], bricks.elements[k])
        L += ["*NSET, NSET=NBODY%d" % (k + 1)] + _lines(bricks.body_nodes[k])
        if case["dimension"] == 2:
            faces = ": z fixed on both faces" if case["plane"] == "strain" else ": faces free"
            tr.translated.append("body '%s': %d Q4 cells -> %d %s bricks, one layer through the thickness %g m "
                                 "(z = +-%g m), plane %s%s" % (b["name"], count, count, etype, b["thickness"],
                                                               b["thickness"] / 2, case["plane"], faces))
        else:
            tr.translated.append("body '%s': %d hex8 cells -> %s" % (b["name"], count, etype))
        if etype == "C3D8R":
            tr.not_translated.append("hourglass_energy of body '%s': C3D8R's hourglass control is "
                                     "CalculiX's own and its energy is not reported (strain energy and "
                                     "stress at the centre point)" % b["name"])
    L += ["*ELSET, ELSET=BODIES"] + ["BODY%d" % (k + 1) for k in range(len(case["bodies"]))]
    return L


def ground_cards(case, tr, plans):
    """*NODE, *ELEMENT and the master surfaces of each obstacle's ground layer: one copy of the
    layer (its own nodes and elements, all at the same place) per contact pair, MASTERo_g the
    top face of copy g; NGROUNDo and GROUNDo are the union of the copies."""
    L = []
    next_node = len(tr.bricks.coords) + 1
    next_elem = sum(len(e) for e in tr.bricks.element_ids) + 1
    for o, ob in enumerate(case["obstacles"]):
        g = build_ground(case, ob, tr.options)
        g.copies = len(plans[o].slopes) if plans[o] else 1
        for c in range(g.copies):
            name = "%d_%d" % (o + 1, c + 1)
            ids = np.arange(next_node, next_node + len(g.coords))
            eids = np.arange(next_elem, next_elem + len(g.elements))
            next_node, next_elem = next_node + len(ids), next_elem + len(eids)
            L += ["*NODE, NSET=NGROUND" + name] + _node_lines(ids, g.coords)
            L += ["*ELEMENT, TYPE=C3D8, ELSET=GROUND" + name] + _element_lines(eids, ids[g.elements])
            L += ["*SURFACE, NAME=MASTER" + name] + ["%d, S2" % eid for eid in eids]
        L += ["*NSET, NSET=NGROUND%d" % (o + 1)] + ["NGROUND%d_%d" % (o + 1, c + 1) for c in range(g.copies)]
        L += ["*ELSET, ELSET=GROUND%d" % (o + 1)] + ["GROUND%d_%d" % (o + 1, c + 1) for c in range(g.copies)]
        tr.grounds.append(g)
    return L


def material_cards(case, tr):
    """*MATERIAL and *SOLID SECTION of the bodies and the grounds."""
    L = []
    for k, b in enumerate(case["bodies"]):
        card, _, note = material_card(b["material"])
        L += ["*MATERIAL, NAME=MAT%d" % (k + 1), "*DENSITY", f20(b["material"]["density"])] + card
        L.append("*SOLID SECTION, ELSET=BODY%d, MATERIAL=MAT%d" % (k + 1, k + 1))
        tr.translated.append("body '%s': %s" % (b["name"], note))
        if b["material"]["model"] == "neo_hookean":
            tr.notes.append("body '%s': CalculiX's NEO HOOKE, C10 (J^-2/3 I1 - 3) + (J - 1)^2/D1, and "
                            "ricochet's neo-Hookean, mu/2 (I1 - 3) - mu ln J + lambda/2 (ln J)^2, share the "
                            "small-strain limit only" % b["name"])
    if case["obstacles"]:
        # Every ground node is fixed: the material only enters CalculiX's stable-increment
        # estimate, so it is soft and heavy (wave speed 1/100 of the bodies').
        young = max(material_card(b["material"])[1] for b in case["bodies"])
        rho = max(float(b["material"]["density"]) for b in case["bodies"])
        L += ["*MATERIAL, NAME=MATGROUND", "*DENSITY", f20(1e4 * rho), "*ELASTIC", "%s, 0.25" % f20(young)]
        L += ["*SOLID SECTION, ELSET=GROUND%d, MATERIAL=MATGROUND" % (o + 1)
              for o in range(len(case["obstacles"]))]
    return L


@dataclass
class SlaveFace:
    element: int                  # element id
    face: int                     # CalculiX face number 1..6
    nodes: tuple                  # its ricochet nodes (2 in 2D, 4 in 3D)
    thickness: float | None       # the 2D body's thickness (None in 3D)


def slave_faces(case, bricks, cand_nodes):
    """The bodies' boundary faces whose nodes are all candidates (SlaveFace), and those nodes."""
    faces, nodes = [], set()
    for body, body_faces in zip(case["bodies"], bricks.boundary_faces):
        thickness = body["thickness"] if case["dimension"] == 2 else None
        for eid, face, corners in body_faces:
            if all(v in cand_nodes for v in corners):
                faces.append(SlaveFace(eid, face, corners, thickness))
                nodes.update(corners)
    return faces, nodes


@dataclass
class ContactPlan:
    """Obstacle o's node-to-surface contact: its slave faces and their slope groups."""
    cands: list                   # its contact candidates
    faces: list                   # SlaveFace
    on_faces: set                 # the candidates on a slave face
    labels: np.ndarray            # (f,) each face's group
    slopes: np.ndarray            # (g,) each group's slope K [N/m^3]
    description: str
    deviation: float | None       # largest |K_face / K_group - 1| (None: numeric penalty)


def contact_plan(case, tr, o):
    """Obstacle o's ContactPlan, its slopes appended to tr.slopes; None (and [] appended)
    when no boundary face has all its nodes among the candidates."""
    cands = [c for c in case["contact"]["candidates"] if c["obstacle"] == o]
    faces, on_faces = slave_faces(case, tr.bricks, {c["node"] for c in cands})
    if not faces:
        tr.slopes.append([])
        return None
    labels, slopes, description, deviation = penalty_groups(case, o, faces, tr.options)
    tr.slopes.append([float(K) for K in slopes])
    return ContactPlan(cands, faces, on_faces, labels, slopes, description, deviation)


def contact_cards(case, tr, o, plan):
    """The node-to-surface contact pairs of obstacle o, one per slope group g: SLAVEo_g (the
    group's faces) on MASTERo_g (the top face of the ground's copy g) with the interaction
    CONTACTo_g. Not one master for all: ccx 2.20 catalogues the neighbours of the master
    triangles over all contact pairs at once by their edges' nodes (trianeighbor.f), so pairs
    sharing a master surface get neighbours in each other's triangulation, and the search for
    a slave node's master face then stops at a false border: that node gets no spring."""
    ob = case["obstacles"][o]
    if plan is None:
        tr.not_translated.append("obstacle '%s': no boundary face has all its nodes among the contact "
                                 "candidates: no contact with it" % ob["name"])
        return []
    cands, faces, labels, slopes = plan.cands, plan.faces, plan.labels, plan.slopes
    cand_nodes = {c["node"] for c in cands}
    X = np.asarray(case["nodes"], dtype=float)
    areas = ([c["area"] for c in cands if c["area"] > 0]
             or [face_area(X, f) for f in faces])     # candidates without area: ~ a face each
    eps = SMOOTHING * math.sqrt(float(np.median(areas)))
    mu = cands[0]["friction"]
    L = []
    for g, K in enumerate(slopes):
        name = "%d_%d" % (o + 1, g + 1)
        L += ["*SURFACE, NAME=SLAVE" + name]
        L += ["%d, S%d" % (f.element, f.face) for f, label in zip(faces, labels) if label == g]
        L += ["*SURFACE INTERACTION, NAME=CONTACT" + name,
              "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR", "%s, %s" % (f20(K), f20(K * eps / math.pi))]
        if mu > 0:
            L += ["*FRICTION", "%s, %s" % (f20(mu), f20(tr.options.stick_slope or K))]
        L += ["*CONTACT PAIR, INTERACTION=CONTACT%s, TYPE=NODE TO SURFACE" % name,
              "SLAVE%s, MASTER%s" % (name, name)]
    g = tr.grounds[o]
    pairs = ("one *CONTACT PAIR" if len(slopes) == 1 else
             "%d *CONTACT PAIRs, one per slope group, each on its own copy of the ground layer (ccx "
             "finds no master face for some slave nodes when pairs share a master surface)" % len(slopes))
    tr.translated += [
        "obstacle '%s' (%s) -> a fixed layer of %d C3D8 bricks below it (%g m long elements, %g m deep); "
        "node-to-surface penalty contact, slave: %d boundary faces (%d candidate nodes), master: its top "
        "face; %s" % (ob["name"], ob["type"], len(g.elements), g.elem_size, g.depth, len(faces),
                      len(plan.on_faces), pairs),
        plan.description,
        "obstacle '%s': *SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR with each interaction's slope K, "
        "sigma_inf = K eps/pi (smoothing length eps = %g m in each: %s Pa)"
        % (ob["name"], eps, ", ".join("%.4g" % (K * eps / math.pi) for K in slopes))]
    if mu > 0:
        stick = ("%g N/m^3 (options.stick_slope)" % tr.options.stick_slope if tr.options.stick_slope
                 else "each interaction's slope K")
        tr.translated.append("obstacle '%s': *FRICTION mu = %g, stick slope %s" % (ob["name"], mu, stick))
    springs = node_springs(case, faces, slopes[labels])
    tr.translated.append(penalty_step_note(case, springs, ob["name"]))
    if plan.deviation is not None:
        diff, node = spring_difference(cands, springs)
        tr.notes.append("obstacle '%s': %d contact interactions (slope groups); a slave face's K_face deviates "
                        "from its interaction's slope by at most %.2g %%%s"
                        % (ob["name"], len(slopes), 100 * plan.deviation, "" if diff is None else
                           "; the slave nodes' springs (slope x area share, over their faces) differ from "
                           "ricochet's k_i by at most %.2g %% (node %d)" % (100 * diff, node)))
    if cand_nodes - plan.on_faces:
        tr.not_translated.append("obstacle '%s': %d candidate nodes are on no boundary face of candidates "
                                 "and are not slaves" % (ob["name"], len(cand_nodes - plan.on_faces)))
    return L


def support_cards(case, tr):
    """*BOUNDARY: the grounds, plane strain's z, the fixed supports (on both copies in 2D)."""
    L = ["*BOUNDARY"] + ["NGROUND%d, 1, 3" % (o + 1) for o in range(len(case["obstacles"]))]
    if case["dimension"] == 2 and case["plane"] == "strain":
        L.append("NBODIES, 3, 3")
    fixed = sorted({(p["node"], p["component"]) for p in case.get("prescribed", [])})
    for node, comp in fixed:
        L += ["%d, %d, %d" % (cid, comp + 1, comp + 1) for cid in tr.bricks.copies[node]]
    if fixed:
        tr.translated.append("prescribed: %d degrees of freedom of value 0 -> *BOUNDARY (fixed)" % len(fixed))
    return L


def initial_velocity_cards(case, tr):
    dim = case["dimension"]
    L = ["*INITIAL CONDITIONS, TYPE=VELOCITY"]
    for v, ids in zip(np.asarray(case["velocity"], dtype=float), tr.bricks.copies):
        v3 = list(v) + [0.0] * (3 - dim)
        L += ["%d, %d, %s" % (cid, comp + 1, f20(v3[comp])) for cid in ids for comp in range(3)]
    tr.translated.append("initial velocity: *INITIAL CONDITIONS, TYPE=VELOCITY per node%s"
                         % (" (both copies, v_z = 0)" if dim == 2 else ""))
    return L


def step_cards(case, tr):
    """*STEP and *DYNAMIC of the procedure, and gravity."""
    dt, end = case["time"]["dt"], case["time"]["end"]
    steps = int(case["time"].get("steps") or math.ceil(end / dt - 1e-9))
    L = ["*STEP, NLGEOM, INC=%d" % (steps + 100)]
    if tr.options.procedure == "explicit":
        L += ["*DYNAMIC, EXPLICIT", "%s, %s, , %s" % (f20(dt), f20(end), f20(dt))]
        tr.translated.append("time: *DYNAMIC, EXPLICIT (central differences, lumped mass), increment %g s "
                             "(initial and maximum), %d increments to %g s" % (dt, steps, end))
    else:
        L += ["*DYNAMIC, DIRECT, ALPHA=%s" % f20(tr.options.alpha), "%s, %s" % (f20(dt), f20(end))]
        tr.translated.append("time: *DYNAMIC, DIRECT, ALPHA=%g (HHT-alpha, consistent mass, Newton), fixed "
                             "increment %g s, %d increments to %g s" % (tr.options.alpha, dt, steps, end))
    g = np.asarray(case.get("gravity") or [0.0] * case["dimension"], dtype=float)
    if np.any(g != 0):
        size = float(np.linalg.norm(g))
        direction = [f20(c / size) for c in list(g) + [0.0] * (3 - case["dimension"])]
        L.append("*DLOAD")
        L += ["BODY%d, GRAV, %s, %s" % (k + 1, f20(size), ", ".join(direction))
              for k in range(len(case["bodies"]))]
        tr.translated.append("gravity: *DLOAD, GRAV %g m/s^2" % size)
    return L


def output_cards(case, tr):
    """The .dat requests (the FREQUENCY of the first applies to all) and *END STEP."""
    L = ["*NODE PRINT, NSET=NBODIES, FREQUENCY=%d" % tr.frequency, "U, V"]
    for o in range(len(case["obstacles"])):
        L += ["*NODE PRINT, NSET=NGROUND%d, TOTALS=ONLY" % (o + 1), "RF"]
    if has_contact(tr):
        L += ["*CONTACT PRINT, TOTALS=YES", "CELS, CSTR"]     # TOTALS=ONLY would drop CSTR
    interval, dt = case["output"]["interval"], case["time"]["dt"]
    tr.translated.append("output every %d increments (output.interval %g s)" % (tr.frequency, interval))
    if interval > 0 and abs(tr.frequency * dt - interval) > 1e-9 * interval:
        tr.notes.append("output.interval %g s is not a multiple of time.dt: samples every %d increments (%g s)"
                        % (interval, tr.frequency, tr.frequency * dt))
    return L + ["*END STEP"]


def general_notes(case, tr):
    tr.not_translated.append("friction_dissipation and contact_work: CalculiX reports neither per sample "
                             "(ricochet's energy balance counts the friction loss as error)")
    tr.notes.append("von_mises_max: the %s stress recomputed from the sampled displacements at the Gauss "
                    "points, the largest over the samples (ricochet's own: over every step)"
                    % case["output"]["stress_measure"])
    mass = ("lumped mass (row sums, equal to ricochet's lumped mass)" if tr.options.procedure == "explicit"
            else "consistent mass (kinetic energy at the Gauss points)")
    tr.notes.append("mass: CalculiX's %s; momenta from ricochet's lumped masses and the copies' mean velocity"
                    % mass)
    if case["obstacles"]:
        tr.notes.append("contact impulses and start/end times: from the sampled ground reactions "
                        "(trapezoidal rule), as fine as the output interval")


def translate(case, options):
    """The CalculiX deck of the case and what reading its output back needs. Pure: no files."""
    check_translatable(case)
    tr = Translation("", build_bricks(case), [], [], output_frequency(case), options)
    L = ["** ricochet case '%s', translated by adapters/calculix.py" % case["case"]]
    L += body_cards(case, tr)
    plans = [contact_plan(case, tr, o) for o in range(len(case["obstacles"]))]
    L += ground_cards(case, tr, plans)
    L += material_cards(case, tr)
    for o, plan in enumerate(plans):
        L += contact_cards(case, tr, o, plan)
    L += support_cards(case, tr)
    L += initial_velocity_cards(case, tr)
    L += step_cards(case, tr)
    L += output_cards(case, tr)
    general_notes(case, tr)
    tr.deck = "\n".join(L) + "\n"
    return tr


# ----------------------------------------------------------------------------------------
# Reading job.dat

# A block's header, e.g. " displacements (vx,vy,vz) for set NBODIES and time  0.1000000E-04",
# " contact stress (...) for all contact elements and time ...", " total ... for time ...".
_HEADER = re.compile(r"^\s*(?P<what>\S.*?)\s+for\s*"
                     r"(?:set\s+(?P<set>\S+)\s+and\s+|all\s+contact\s+elements\s+and\s+)?"
                     r"time\s+(?P<time>\S+)\s*$")
_KINDS = (("displacements", "U"), ("velocities", "V"), ("total force", "RF_total"),
          ("contact spring energy", "CELS_total"), ("contact stress", "CSTR"))


def _float(token):
    """A Fortran number: 1.234567E-05, and also 1.234567-100 (no E with three exponent digits)."""
    try:
        return float(token)
    except ValueError:
        m = re.fullmatch(r"([-+]?\d*\.?\d*)([-+]\d+)", token)
        if m:
            return float(m.group(1) + "e" + m.group(2))
        return math.nan


def _numbers(tokens):
    try:
        return [float(v) for v in tokens]
    except ValueError:
        return [_float(v) for v in tokens]


def _table(lines):
    """The numbers of a block's data lines as an array (k, m): numpy's fast reader, or, when
    a number is not in its format (1.234567-100), one line at a time."""
    if not lines:
        return np.zeros((0, 0))
    width = len(lines[0].split())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        flat = np.fromstring(" ".join(lines), sep=" ")
    if flat.size == width * len(lines):
        return flat.reshape(len(lines), width)
    return np.array([_numbers(line.split()) for line in lines], dtype=float).reshape(len(lines), -1)


def _finish(kind, lines):
    """A block's value: (node ids, values (k, m)) for a nodal block, else its first line's numbers."""
    table = _table(lines)
    if kind in ("U", "V", "CSTR"):
        if table.size == 0:
            return np.zeros(0, dtype=int), np.zeros((0, 3))
        return table[:, 0].astype(int), table[:, 1:]
    return table[0].tolist() if len(table) else []


def read_samples(lines):
    """Yield (time, sample) from the lines of a CalculiX .dat file, in the file's order.

    A sample holds the blocks printed at one time: "U", "V", "CSTR" as (node ids, values
    (k, m)); "RF_total" as {node set: [fx, fy, fz]}; "CELS_total" as a number. Blocks of
    other kinds are skipped. One sample at a time is in memory (the file can be large)."""
    time, sample, kind, key, rows = None, {}, None, None, []

    def close():
        if kind == "RF_total":
            sample.setdefault("RF_total", {})[key] = _finish(kind, rows)
        elif kind == "CELS_total":
            values = _finish(kind, rows)
            sample[kind] = values[0] if values else 0.0
        elif kind is not None:
            sample[kind] = _finish(kind, rows)

    for line in lines:
        m = _HEADER.match(line) if "time" in line else None
        if m:
            close()
            what = m.group("what").lower()
            kind = next((k for name, k in _KINDS if name in what), None)
            key, rows = (m.group("set") or "").upper(), []
            if kind is None:
                continue
            t = _float(m.group("time"))
            if t != time:
                if time is not None:
                    yield time, sample
                time, sample = t, {}
            continue
        if kind is not None and not line.isspace() and line:
            rows.append(line)
    close()
    if time is not None:
        yield time, sample


def parse_dat(text):
    """{time: sample} of a .dat text (read_samples)."""
    return dict(read_samples(text.splitlines()))


# ----------------------------------------------------------------------------------------
# Kinematics and stress at the Gauss points

GAUSS2 = np.array([-1.0, 1.0]) / math.sqrt(3.0)
HEX_SIGNS = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                      [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], dtype=float)


def hex_points(reduced):
    """(points (p, 3), weights (p,)) of the C3D8 (2x2x2) or C3D8R (centre) rule."""
    if reduced:
        return np.zeros((1, 3)), np.array([8.0])
    pts = np.array([[a, b, c] for c in GAUSS2 for b in GAUSS2 for a in GAUSS2])
    return pts, np.ones(8)


def hex_shape(points):
    """N (p, 8) and dN/dxi (p, 8, 3) of the trilinear brick at the points."""
    s = HEX_SIGNS[None, :, :] * points[:, None, :]      # (p, 8, 3)
    f = 1.0 + s
    N = f.prod(axis=2) / 8.0
    dN = np.empty(points.shape[:1] + (8, 3))
    for d in range(3):
        others = [k for k in range(3) if k != d]
        dN[:, :, d] = HEX_SIGNS[None, :, d] * f[:, :, others[0]] * f[:, :, others[1]] / 8.0
    return N, dN


@dataclass
class Kinematics:
    """Per body: reference gradients of the shape functions at its Gauss points."""
    conn: np.ndarray             # (e, 8) node indices (id - 1)
    N: np.ndarray                # (p, 8)
    grad: np.ndarray             # (e, p, 8, 3) dN/dX
    dvol: np.ndarray             # (e, p) weight x det J0
    material: dict


def kinematics(tr, case):
    out = []
    for k, b in enumerate(case["bodies"]):
        conn = tr.bricks.elements[k] - 1
        pts, w = hex_points(ELEMENT_TYPES[b["element"]] == "C3D8R")
        N, dN = hex_shape(pts)
        Xe = tr.bricks.coords[conn]                       # (e, 8, 3)
        J = np.einsum("eai,pad->epid", Xe, dN)            # dX_i/dxi_d
        detJ = np.linalg.det(J)
        grad = np.einsum("pad,epdi->epai", dN, np.linalg.inv(J))
        out.append(Kinematics(conn, N, grad, detJ * w[None, :], b["material"]))
    return out


def pk2_and_energy(F, material):
    """S (..., 3, 3) and W (...) of CalculiX's law for the material at F (..., 3, 3)."""
    C = np.swapaxes(F, -1, -2) @ F
    I = np.eye(3)
    model = material["model"]
    if model == "saint_venant_kirchhoff":
        lam, mu = lame(material["young"], material["poisson"])
        E = 0.5 * (C - I)
        tr = np.trace(E, axis1=-2, axis2=-1)
        S = lam * tr[..., None, None] * I + 2 * mu * E
        W = 0.5 * lam * tr ** 2 + mu * (E * E).sum(axis=(-2, -1))
        return S, W
    if model == "neo_hookean":
        lam, mu = lame(material["young"], material["poisson"])
        c10, c01, kappa = mu / 2, 0.0, lam + 2 * mu / 3
    else:
        c10, c01, kappa = material["c10"], material["c01"], material["bulk_modulus"]
    J = np.sqrt(np.linalg.det(C))
    Cinv = np.linalg.inv(C)
    I1 = np.trace(C, axis1=-2, axis2=-1)
    I2 = 0.5 * (I1 ** 2 - (C * C).sum(axis=(-2, -1)))       # C is symmetric
    j23, j43 = J ** (-2.0 / 3.0), J ** (-4.0 / 3.0)
    W = c10 * (j23 * I1 - 3) + c01 * (j43 * I2 - 3) + 0.5 * kappa * (J - 1) ** 2
    S = (2 * c10 * j23[..., None, None] * (I - (I1 / 3)[..., None, None] * Cinv)
         + 2 * c01 * j43[..., None, None]
         * (I1[..., None, None] * I - C - (2 * I2 / 3)[..., None, None] * Cinv)
         + (kappa * (J - 1) * J)[..., None, None] * Cinv)
    return S, W


def von_mises(s):
    d = s - np.trace(s, axis1=-2, axis2=-1)[..., None, None] * np.eye(3) / 3
    return np.sqrt(1.5 * (d * d).sum(axis=(-2, -1)))


def stress_and_energy(kin, U, measure):
    """(largest von Mises of `measure` over all Gauss points, strain energy, kinetic-energy helper)."""
    vm_max, energy = 0.0, 0.0
    for k in kin:
        Ue = U[k.conn]                                     # (e, 8, 3)
        F = np.eye(3) + np.swapaxes(Ue, 1, 2)[:, None] @ k.grad     # (e, p, 3, 3)
        S, W = pk2_and_energy(F, k.material)
        if measure == "pk2":
            s = S
        else:
            s = F @ S @ np.swapaxes(F, -1, -2)
            if measure == "cauchy":
                s = s / np.linalg.det(F)[..., None, None]
        vm_max = max(vm_max, float(von_mises(s).max()))
        energy += float((W * k.dvol).sum())
    return vm_max, energy


def consistent_kinetic(kin, V, case):
    total = 0.0
    for k, b in zip(kin, case["bodies"]):
        v = np.einsum("pa,eai->epi", k.N, V[k.conn])
        total += 0.5 * b["material"]["density"] * float((np.einsum("epi,epi->ep", v, v) * k.dvol).sum())
    return total


# ----------------------------------------------------------------------------------------
# From samples to the history

def _field(sample, kind, n_nodes):
    """(n_nodes, 3) nodal values of a sample's block (NaN where absent)."""
    arr = np.full((n_nodes, 3), math.nan)
    ids, vals = sample[kind]
    keep = (ids >= 1) & (ids <= n_nodes)
    arr[ids[keep] - 1] = vals[keep, :3]
    return arr


def history_columns(case, tr):
    dim = case["dimension"]
    axes = "xyz"[:dim]
    cols = ["time", "kinetic_energy", "strain_energy"]
    if np.any(np.asarray(case.get("gravity", [0.0] * dim), dtype=float) != 0):
        cols.append("external_work")
    cols.append("total_energy")
    if case["obstacles"] and has_contact(tr):
        cols.append("contact_energy")
    cols += ["momentum_" + a for a in axes]
    cols += ["angular_momentum"] if dim == 2 else ["angular_momentum_" + a for a in "xyz"]
    cols.append("von_mises_max")
    if case["obstacles"]:
        cols += ["penetration_max", "normal_force", "tangential_force"]
        if has_contact(tr):
            cols.append("contact_nodes")
    for p in case["output"]["probes"]:
        cols += ["%s_u%s" % (p["name"], a) for a in axes] + ["%s_v%s" % (p["name"], a) for a in axes]
    return cols


def kinetic_energy(case, tr, kin, V):
    """The integrator's kinetic energy: lumped (explicit), consistent (implicit)."""
    if tr.options.procedure != "explicit":
        return consistent_kinetic(kin, V, case)
    copies = tr.bricks.copies - 1
    mass = np.asarray(case["mass"], dtype=float)
    speed2 = (V[copies] ** 2).sum(axis=(1, 2))             # (N,) summed over the copies
    return 0.5 * float((mass / copies.shape[1] * speed2).sum())


def momentum_columns(case, um, vm):
    """Momentum and the angular momentum about the moving centre of mass (ricochet's masses)."""
    dim = case["dimension"]
    mass = np.asarray(case["mass"], dtype=float)
    p = (mass[:, None] * vm).sum(axis=0)
    x = np.zeros((len(mass), 3))
    x[:, :dim] = np.asarray(case["nodes"], dtype=float)
    x += um
    xc, vc = (mass[:, None] * x).sum(axis=0) / mass.sum(), p / mass.sum()
    L = (mass[:, None] * np.cross(x - xc, vm - vc)).sum(axis=0)
    row = {"momentum_" + "xyz"[a]: float(p[a]) for a in range(dim)}
    if dim == 2:
        row["angular_momentum"] = float(L[2])
    else:
        row.update({"angular_momentum_" + a: float(L[k]) for k, a in enumerate("xyz")})
    return row


def contact_columns(case, tr, U, sample):
    """penetration_max, the grounds' reactions, contact_nodes and contact_energy."""
    copies = tr.bricks.copies - 1
    X = tr.bricks.coords
    depth, fn, ft = 0.0, 0.0, 0.0
    for o, g in enumerate(tr.grounds):
        cand = [c["node"] for c in case["contact"]["candidates"] if c["obstacle"] == o]
        if cand:
            ids = copies[cand].ravel()
            depth = max(depth, float(-((X[ids] + U[ids] - g.point) @ g.normal).min()))
        R = sample.get("RF_total", {}).get("NGROUND%d" % (o + 1), [0.0, 0.0, 0.0])
        R = np.asarray(R[:3], dtype=float)
        fn += float(R @ g.normal)
        if case["dimension"] == 2:
            ft += float(R @ np.array([g.normal[1], -g.normal[0], 0.0]))
        else:
            ft += float(np.linalg.norm(R - (R @ g.normal) * g.normal))
    pressed = set()
    if len(sample.get("CSTR", ((),))[0]):
        ids, vals = sample["CSTR"]
        ids = ids[(ids >= 1) & (ids <= len(X)) & (vals[:, 0] > 0)]
        node_of = np.empty(len(X), dtype=int)
        node_of[copies] = np.arange(len(copies))[:, None]
        pressed = set(node_of[ids - 1].tolist())
    return {"penetration_max": max(depth, 0.0), "normal_force": fn, "tangential_force": ft,
            "contact_nodes": len(pressed), "contact_energy": float(sample.get("CELS_total", 0.0))}


def sample_row(case, tr, kin, t, U, V, sample):
    """One history row (dict) at time t from the copies' displacements U and velocities V (n, 3)."""
    dim = case["dimension"]
    copies = tr.bricks.copies - 1
    um, vm = U[copies].mean(axis=1), V[copies].mean(axis=1)      # (N, 3): mean over the copies
    row = {"time": t, "kinetic_energy": kinetic_energy(case, tr, kin, V)}
    row["von_mises_max"], row["strain_energy"] = stress_and_energy(kin, U, case["output"]["stress_measure"])
    row["total_energy"] = row["kinetic_energy"] + row["strain_energy"]
    g = np.zeros(3)
    g[:dim] = case.get("gravity") or [0.0] * dim
    row["external_work"] = float((np.asarray(case["mass"], dtype=float)[:, None] * um * g).sum())
    row.update(momentum_columns(case, um, vm))
    if case["obstacles"]:
        row.update(contact_columns(case, tr, U, sample))
    for pr in case["output"]["probes"]:
        for a in range(dim):
            row["%s_u%s" % (pr["name"], "xyz"[a])] = float(um[pr["node"], a])
            row["%s_v%s" % (pr["name"], "xyz"[a])] = float(vm[pr["node"], a])
    return row


def build_history(case, tr, samples, dt_used):
    """Rows at t = 0 and at every sample of `samples` ((time, sample) pairs, in time order);
    stops at the first sample with a non-finite number.

    Returns (rows, diverged reason or None)."""
    kin = kinematics(tr, case)
    n = len(tr.bricks.coords)
    V0 = np.zeros((n, 3))
    vel = np.asarray(case["velocity"], dtype=float)
    for c in range(tr.bricks.copies.shape[1]):
        V0[tr.bricks.copies[:, c] - 1, :case["dimension"]] = vel
    rows = [sample_row(case, tr, kin, 0.0, np.zeros((n, 3)), V0, {})]
    for t, s in samples:
        if "U" not in s or "V" not in s:
            continue
        U, V = _field(s, "U", n), _field(s, "V", n)
        time = float("%.12g" % (round(t / dt_used) * dt_used))   # k dt, without the round-off tail
        if time <= rows[-1]["time"]:
            continue
        if not (np.isfinite(U).all() and np.isfinite(V).all()):
            return rows, "non-finite displacements or velocities in CalculiX's output at t = %g s" % t
        row = sample_row(case, tr, kin, time, U, V, s)
        if not all(math.isfinite(v) for v in row.values()):
            return rows, "non-finite results at t = %g s" % t
        rows.append(row)
    return rows, None


def contact_summary(rows):
    """Summary keys of the contact from the sampled forces."""
    if not rows or "normal_force" not in rows[0]:
        return {}
    t = np.array([r["time"] for r in rows])
    fn = np.array([r["normal_force"] for r in rows])
    ft = np.array([r["tangential_force"] for r in rows])
    trapezoid = lambda f: float((0.5 * (f[1:] + f[:-1]) * np.diff(t)).sum())
    out = {"contact_impulse_normal": trapezoid(fn), "contact_impulse_tangential": trapezoid(ft)}
    on = np.nonzero(fn > 0)[0]
    if len(on):
        out["contact_start_time"] = float(t[on[0]])
        out["contact_end_time"] = float(t[on[-1]])
        out["contact_duration"] = float(t[on[-1]] - t[on[0]])
    return out


# ----------------------------------------------------------------------------------------
# Running ccx

def threads():
    raw = os.environ.get("RICOCHET_THREADS", "1")
    try:
        n = int(raw)
    except ValueError:
        n = 1
    return max(1, n)


def ccx_environment(n):
    env = dict(os.environ)
    for key in ("OMP_NUM_THREADS", "CCX_NPROC_STIFFNESS", "CCX_NPROC_EQUATION_SOLVER",
                "CCX_NPROC_RESULTS", "CCX_NPROC_CFD", "NUMBER_OF_CPUS"):
        env[key] = str(n)
    return env


def first_error(text):
    """The first *ERROR message of ccx's output, its continuation lines joined, as one line."""
    lines = text.splitlines()
    for i, line in enumerate(lines):
        if "*ERROR" in line:
            parts = [line.strip()]
            for nxt in lines[i + 1:i + 4]:
                if not nxt.strip() or "*ERROR" in nxt:
                    break
                parts.append(nxt.strip())
            return " ".join(" ".join(parts).split())
    return None


def run_ccx(folder, n_threads, end):
    """(exit status, ccx's standard output, its CPU seconds); a progress line every tenth of end."""
    program = os.environ.get("RICOCHET_CCX", "ccx")
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    try:
        proc = subprocess.Popen([program, "-i", JOB], cwd=folder, env=ccx_environment(n_threads),
                                stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                stderr=subprocess.STDOUT, text=True)
    except OSError as e:
        raise RunError("cannot run '%s': %s" % (program, e.strerror or e))
    chunks, reported = [], 0
    for line in proc.stdout:
        chunks.append(line)
        m = re.search(r"actual total time=\s*(\S+)", line)
        if m and end > 0:
            tenth = int(10 * _float(m.group(1)) / end + 1e-9)
            if tenth > reported:
                reported = tenth
                print("calculix: t = %s s (%d %%)" % (m.group(1), 10 * tenth), flush=True)
    status = proc.wait()
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return status, "".join(chunks), cpu


def ccx_facts(stdout):
    """{version, selected increment} from ccx's standard output."""
    facts = {}
    m = re.search(r"CalculiX Version (\S+?),", stdout)
    if m:
        facts["version"] = m.group(1)
    m = re.search(r"SELECTED time increment:\s*(\S+)", stdout)
    if m:
        facts["increment"] = _float(m.group(1))
    return facts


def mass_scaled_elements(folder):
    path = os.path.join(folder, JOB + "_WarnElementMassScaled.nam")
    if not os.path.exists(path):
        return []
    with open(path) as f:
        return [int(tok) for line in f for tok in line.replace(",", " ").split() if tok.isdigit()]


# ----------------------------------------------------------------------------------------
# Writing the results

def _num(v):
    return repr(float(v)) if not float(v).is_integer() or abs(v) >= 1e16 else repr(int(v))


def write_history(path, columns, rows):
    with open(path, "w") as f:
        f.write(",".join(columns) + "\n")
        for r in rows:
            f.write(",".join(_num(r.get(c, 0.0)) for c in columns) + "\n")


def write_result(path, result):
    with open(path + ".tmp", "w") as f:
        json.dump(result, f, indent=1)
        f.write("\n")
    os.replace(path + ".tmp", path)


def load_case(case_path):
    with open(case_path) as f:
        case = json.load(f)
    if case.get("format") != "ricochet-external-case" or case.get("version") != 1:
        raise TranslationError("%s: not a ricochet-external-case version 1" % case_path)
    return case


def increment_used(case, options, facts):
    """The increment ccx took: its SELECTED increment (explicit), else time.dt."""
    dt = case["time"]["dt"]
    used = facts.get("increment", dt) if options.procedure == "explicit" else dt
    return used if used > 0 and math.isfinite(used) else dt


def read_history(case, tr, folder, dt_used):
    """(rows, reason to call the run diverged or None), or None without a job.dat."""
    path = os.path.join(folder, JOB + ".dat")
    if not os.path.exists(path):
        return None
    with open(path) as f:
        return build_history(case, tr, read_samples(f), dt_used)


def run_summary(case, rows):
    """result.json's `summary` from the history rows."""
    peak = max(rows, key=lambda r: r["von_mises_max"])
    summary = {"von_mises_max": peak["von_mises_max"], "von_mises_max_time": peak["time"]}
    if case["obstacles"]:
        summary["penetration_max"] = max(r["penetration_max"] for r in rows)
        summary.update(contact_summary(rows))
    return summary


def add_run_notes(tr, folder, dt_used, dt):
    if abs(dt_used - dt) > 1e-9 * dt:
        tr.notes.append("CalculiX took the increment %g s, below time.dt %g s (its stable-increment estimate)"
                        % (dt_used, dt))
    n_body = sum(len(e) for e in tr.bricks.element_ids)
    scaled = [e for e in mass_scaled_elements(folder) if e <= n_body]
    if scaled:
        tr.notes.append("CalculiX scaled the mass of %d body elements (%s_WarnElementMassScaled.nam)"
                        % (len(scaled), JOB))


def run(case_path, folder):
    case = load_case(case_path)
    options = parse_options(case.get("options"))
    tr = translate(case, options)
    for name in ("result.json", "history.csv"):
        if os.path.exists(os.path.join(folder, name)):
            os.remove(os.path.join(folder, name))
    with open(os.path.join(folder, JOB + ".inp"), "w") as f:
        f.write(tr.deck)
    n_threads = threads()
    print("calculix: %s.inp written (%d body nodes, %d bricks), running ccx with %d thread(s)"
          % (JOB, len(tr.bricks.coords), sum(len(e) for e in tr.bricks.element_ids), n_threads), flush=True)
    status, stdout, cpu = run_ccx(folder, n_threads, case["time"]["end"])
    with open(os.path.join(folder, "ccx_stdout.txt"), "w") as f:
        f.write(stdout)
    error, facts = first_error(stdout), ccx_facts(stdout)
    dt, end = case["time"]["dt"], case["time"]["end"]
    dt_used = increment_used(case, options, facts)
    read = read_history(case, tr, folder, dt_used)
    failed = status != 0 or error is not None
    if read is None or (failed and len(read[0]) < 2):
        raise RunError("ccx failed (exit %d): %s" % (status, error or "no *ERROR message and no %s.dat "
                                                     "(see ccx_stdout.txt)" % JOB))
    rows, reason = read
    reached = rows[-1]["time"]
    print("calculix: ccx done (%.1f s CPU), %d samples read" % (cpu, len(rows) - 1), flush=True)
    if reason is None and failed:
        reason = "ccx stopped after t = %g s: %s" % (reached, error or "exit status %d" % status)
    if reason is None and reached < end - 0.5 * dt_used:
        reason = "ccx's output stops at t = %g s, before time.end %g s" % (reached, end)
    add_run_notes(tr, folder, dt_used, dt)
    write_history(os.path.join(folder, "history.csv"), history_columns(case, tr), rows)
    result = {
        "format": "ricochet-external-result", "version": 1,
        "status": "diverged" if reason else "ok",
        "steps": int(round(reached / dt_used)), "dt": dt_used, "time_reached": reached,
        "code": "CalculiX", "code_version": facts.get("version", "unknown"),
        "solver_cpu_seconds": cpu,
        "summary": run_summary(case, rows),
        "translation": {"translated": tr.translated, "not_translated": tr.not_translated, "notes": tr.notes},
    }
    if reason:
        result["reason"] = reason
    elif not options.keep_dat:
        os.remove(os.path.join(folder, JOB + ".dat"))     # large (every node at every sample); read
    write_result(os.path.join(folder, "result.json"), result)
    print("calculix: %s, %d samples to t = %g s, von_mises_max %.4g Pa"
          % (result["status"], len(rows), reached, result["summary"]["von_mises_max"]), flush=True)


def main(argv):
    if len(argv) != 3:
        print("usage: calculix.py CASE_JSON OUT_FOLDER", file=sys.stderr)
        return 2
    try:
        run(argv[1], argv[2])
    except TranslationError as e:
        print("calculix: %s" % e, file=sys.stderr)
        return 2
    except RunError as e:
        print("calculix: %s" % e, file=sys.stderr)
        return 1
    except (OSError, KeyError, ValueError, TypeError) as e:
        print("calculix: %s: %s" % (type(e).__name__, e), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
