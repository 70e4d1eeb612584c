#!/usr/bin/python3
"""Smoke test of reports/make_report.py on tiny sweeps (registered with CTest as report_smoke).

Builds, in a temporary folder and with the given ricochet binary:
  * a tiny paper sweep: the groups of cases/paper/table1.toml (table1, penalty, friction) on the
    oblique plate with coarse meshes (M1 4 x 8, M2 6 x 14 cells), all the paper's Δt;
  * a tiny accuracy sweep (two schemes, a reference run each, one diverged run);
  * two stability searches (semi-explicit bracketed, implicit up to the cap);
  * a tiny verification sweep: the groups of cases/verification/sweep.toml (bar_wall with the
    three schemes and a second penalty run at another scale factor; sliding_block with the three
    schemes) on coarse meshes;
  * the Kim–Kwak-type sweep cases/kim_kwak/sweep.toml with its gates (five runs, ~2.5 s, in the
    background while the other sweeps run), placed next to the paper sweep so that the report
    discovers it, and one run of cases/kim_kwak/rubber_groove.toml with its fields;
  * a tiny sweep of the Mooney–Rivlin ball on a free block (BB_SWEEP: the groups of
    cases/ball_block/sweep_fast.toml for 1 ms, ~8 s, in the background) checked with
    cases/ball_block/gates_fast.toml, next to the paper sweep (discovered), and a 1 ms run of
    cases/ball_block/ball_block.toml with fields (given with --ball-block-fields);
  * a synthetic stability-envelope sweep (a summary.csv of searches and remedy runs, ENV_ROWS)
    next to the paper sweep (discovered), and a tiny long-run sweep (two scenes, 0.03 s each, a
    failed row added) with its drift.csv written by cases/long_runs/drift.py (given with
    --long-runs).
Then runs the report twice: without the accuracy, stability, verification, Kim–Kwak-type,
envelope and long-run sources (those sections must say "not available" and how to produce
them, everything else must be there), and with them (every section available, except the
verification cases not in the tiny sweep, which must say so). The envelope's table of unsafe
points must list exactly the searches below 0.9 x the estimate or without a stable step; the
long-run table one row per drift.csv row. The envelope and long-run sections are also built
with partial sources (none, no drift.csv, only a failed search). Checks that every figure file exists and is non-empty, that every
table has its expected rows and columns (computed here from the sweeps' summary.csv), and that
every figure's caption names its runs. The Kim–Kwak-type sections are also built with only one
of their two sources.

The report of any sweep (class SweepReport) is run on
  (a) the verification sweep itself, cases/verification/sweep.toml with its gates;
  (b) a two-run sweep written here from docs/sweeps.md alone (the oblique plate on M1 for 1 ms,
      two schemes, a reference, --repeat 2), with gates checked by `ricochet check` so that one
      run fails one gate, and a copy of it with a `floor_` column;
and, like the paper reports, each must give an index.html whose every <img> exists and loads
as a non-empty PNG; the paper's sections must be absent, the runs table, the gate mapping, the
work-precision points, the scheme-limits table (one row per mesh × scheme pair, its P difference
recomputed here from the two history.csv files) and the run histories present. reports/plot_run.py must draw one run and
fail with one line (exit 2) on a folder without history.csv.

The VTU reader of the reports (class VtuReader) must read one snapshot written in each field
encoding (ascii, binary and base64, with and without zlib) to the same arrays, bit for bit.

    /usr/bin/python3 tests/test_report.py [RICOCHET_BINARY]     (or env RICOCHET_BINARY)
"""

import csv
import html.parser
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import unittest
import xml.etree.ElementTree as ET

import matplotlib

matplotlib.use("Agg")
import matplotlib.image  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.normpath(os.path.join(HERE, ".."))
SCRIPT = os.path.join(REPO, "reports", "make_report.py")
PLOT_RUN = os.path.join(REPO, "reports", "plot_run.py")
VER_SWEEP_FILE = os.path.join(REPO, "cases", "verification", "sweep.toml")
VER_GATES = os.path.join(REPO, "ci", "gates", "verification.toml")
PAPER_IDS = {"table1", "fig1", "fig2", "fig3", "fig4", "fig5", "fig6", "fig7", "penetration"}
BASE = os.path.join(REPO, "cases", "oblique_plate.toml")
VER_BASE = os.path.join(REPO, "cases", "verification", "bar_wall.toml")
PY = sys.executable or "/usr/bin/python3"
sys.path.insert(0, os.path.join(REPO, "reports"))
import report_kim_kwak as RK  # noqa: E402
import report_three_d as R3  # noqa: E402
import report_verification as RV  # noqa: E402  (the case specs: which sections to expect)
from report_io import fmt_g  # noqa: E402  (the cells' number format)

BINARY = None

COARSE = ('"meshes.M1.nx" = 4, "meshes.M1.ny" = 8, "meshes.M2.nx" = 6, "meshes.M2.ny" = 14')

PAPER_SWEEP = f"""
name = "tiny_paper"
description = "report smoke test: the paper sweep's groups on coarse meshes"
base = "{BASE}"
set = {{ "output.interval" = 5e-5, {COARSE} }}

[[group]]
name = "table1"
set = {{ "obstacles[0].friction" = 0.0 }}
cross = {{ mesh = ["M1", "M2"], "time.dt" = [1e-4, 1e-5, 1e-6], scheme = ["semi_explicit", "implicit"] }}

[[group]]
name = "penalty"
set = {{ "obstacles[0].friction" = 0.0, scheme = "explicit_penalty", mesh = "M2", "time.dt" = "auto" }}

[[group]]
name = "friction"
set = {{ "obstacles[0].friction" = 0.1 }}
cross = {{ mesh = ["M1", "M2"], "time.dt" = [1e-5, 1e-6], scheme = ["semi_explicit", "implicit"] }}
"""

ACC_SWEEP = f"""
name = "tiny_accuracy"
base = "{BASE}"
set = {{ mesh = "M1", "obstacles[0].friction" = 0.0, "output.interval" = 5e-5, "output.fields" = [], {COARSE} }}

[[group]]
name = "semi_explicit"
set = {{ scheme = "semi_explicit" }}
cross = {{ "time.dt" = [2e-5, 1e-5, 5e-6, 1e-4] }}
reference = {{ "time.dt" = 1e-6 }}

[[group]]
name = "implicit"
set = {{ scheme = "implicit" }}
cross = {{ "time.dt" = [1e-4, 2e-5, 1e-5] }}
reference = {{ "time.dt" = 1e-6 }}
"""

# cases/verification/sweep.toml's groups, coarse: bar 50 x 2 cells, block 5 x 2 cells, 0.4 s
BLOCK = ('name = "sliding_block", gravity = [0.0, -9.81], mesh = "block", meshes = { block = { '
         'generator = "rectangle", width = 0.1, height = 0.05, nx = 5, ny = 2 } }, bodies = [{ '
         'name = "block", element = "q4", thickness = 0.05, velocity = [1.0, 0.0], material = { '
         'model = "saint_venant_kirchhoff", young = 1.0e9, poisson = 0.3, density = 1000.0 } }], '
         'obstacles = [{ name = "ground", type = "line", point = [0.0, 0.0], normal = [0.0, 1.0], '
         'friction = 0.3 }], "time.end" = 0.4, "output.interval" = 2.0e-3, "output.probes" = '
         '[{ name = "centre", point = [0.05, 0.025] }]')

VER_SWEEP = f"""
name = "tiny_verification"
description = "report smoke test: the verification sweep's groups on coarse meshes"
base = "{VER_BASE}"
set = {{ "meshes.bar.nx" = 50 }}

[[group]]
name = "bar"
cross = {{ scheme = ["semi_explicit", "explicit_penalty"] }}

[[group]]
name = "bar_implicit"
set = {{ scheme = "implicit", "time.dt" = 4e-7 }}

[[group]]
name = "bar_penalty_stiff"
set = {{ scheme = "explicit_penalty", "penalty.scale_factor" = 1.0 }}

[[group]]
name = "block"
set = {{ {BLOCK} }}
cross = {{ scheme = ["semi_explicit", "explicit_penalty"] }}

[[group]]
name = "block_implicit"
set = {{ {BLOCK}, scheme = "implicit", "time.dt" = 1e-4 }}
"""
VER_CASES = ("bar_wall", "sliding_block")  # in the tiny sweep; the other specs must be "not available"
KK_SWEEP = os.path.join(REPO, "cases", "kim_kwak", "sweep.toml")
KK_CASE = os.path.join(REPO, "cases", "kim_kwak", "rubber_groove.toml")
KK_GATES = os.path.join(REPO, "ci", "gates", "kim_kwak.toml")
KK_IDS = ("kk_shapes", "kk_histories", "kk_interfaces", "kk_runs")
BB_IDS = ("bb_shapes", "bb_histories", "bb_runs")   # report_ball_block.py, in the 3D part
TD_IDS = ("td_shapes", "td_bar", "td_oblique", "td_frame", "td_table1") + BB_IDS
TD_SWEEP = os.path.join(REPO, "cases", "three_d", "sweep.toml")
TD_T1_SWEEP = os.path.join(REPO, "cases", "three_d", "table1_fast.toml")
TD_GATES = os.path.join(REPO, "ci", "gates", "three_d.toml")
TD_CASE = os.path.join(REPO, "cases", "three_d", "oblique_block.toml")
BB_CASE = os.path.join(REPO, "cases", "three_d", "ball_block.toml")
BB_GATES = os.path.join(REPO, "ci", "gates", "ball_block_fast.toml")
# The groups of cases/ball_block/sweep_fast.toml for 1 ms (the ball touches the block at
# 0.24 ms): semi-explicit with and without frame updates, implicit, penalty with the soft
# constraint.
BB_SWEEP = f"""
name = "tiny_ball_block"
base = "{BB_CASE}"
set = {{ "output.fields" = [], "time.end" = 1e-3 }}

[[group]]
name = "semi"
cross = {{ "contact.frame_updates" = [10, 0] }}

[[group]]
name = "implicit"
set = {{ scheme = "implicit", "time.dt" = 1e-4, "contact.frame_updates" = 10 }}

[[group]]
name = "penalty"
set = {{ scheme = "explicit_penalty", "penalty.soft" = true }}
"""
ENV_IDS = ("envelope", "envelope_unsafe")           # report_stability.py: the envelope sweep
LONG_IDS = ("long_runs", "long_runs_table")         # and the long-run sweep with drift.csv
LONG_RUNS_PY = os.path.join(REPO, "reports", "long_runs.py")

# A tiny long-run sweep (cases/long_runs/sweep.toml's scenes, 0.03 s each, ~500 steps); the test
# adds a failed row to its summary.csv and writes drift.csv with cases/long_runs/drift.py.
LONG_SWEEP = f"""
name = "tiny_long_runs"

[[group]]
name = "block_resting"
base = "{os.path.join(REPO, "cases", "long_runs", "block_resting.toml")}"
set = {{ "time.end" = 0.03, "output.interval" = 6e-4 }}
cross = {{ scheme = ["semi_explicit", "explicit_penalty"] }}

[[group]]
name = "block_sliding"
base = "{os.path.join(REPO, "cases", "long_runs", "block_sliding.toml")}"
set = {{ "time.end" = 0.03, "output.interval" = 6e-4 }}
cross = {{ scheme = ["semi_explicit", "implicit"] }}
"""
LONG_FAILED = "ball_bouncing/000-scheme=semi_explicit"   # a failed row, no run folder

# A synthetic stability-envelope sweep (the summary.csv of cases/envelope/sweep_full.toml, few
# rows): (run id, kind, status, scheme, overrides, outcome, stable/estimate, unsafe). The automatic
# step is 0.9 x the estimate: unsafe = stable/estimate < 0.9 or no stable step at all.
V = {1: "[0.514496, -0.857493]", 5: "[2.57248, -4.28746]", 20: "[10.2899, -17.1499]",
     50: "[25.7248, -42.8746]"}
ENV_ROWS = [
    ("speed_friction/000-scheme=semi_explicit_v1_mu0", "stability", "ok", "semi_explicit",
     {"bodies[0].velocity": V[1], "obstacles[0].friction": "0.0"}, "bracketed", 1.262, False),
    ("speed_friction/001-scheme=semi_explicit_v50_mu0.5", "stability", "ok", "semi_explicit",
     {"bodies[0].velocity": V[50], "obstacles[0].friction": "0.5"}, "no_stable_down_to_floor",
     None, True),
    ("speed_friction/002-scheme=explicit_penalty_v50_mu0", "stability", "ok", "explicit_penalty",
     {"bodies[0].velocity": V[50], "obstacles[0].friction": "0.0"}, "bracketed", 0.6, True),
    ("speed_friction/003-scheme=implicit_v1_mu0", "stability", "ok", "implicit",
     {"bodies[0].velocity": V[1], "obstacles[0].friction": "0.0"}, "no_unstable_up_to_cap", 156.2,
     False),
    ("speed_friction/004-scheme=implicit_v50_mu0.5", "stability", "ok", "implicit",
     {"bodies[0].velocity": V[50], "obstacles[0].friction": "0.5"}, "bracketed", 0.95, False),
    ("speed_friction/005-scheme=semi_explicit_v20_mu0.1", "stability", "ok", "semi_explicit",
     {"bodies[0].velocity": V[20], "obstacles[0].friction": "0.1"}, "run_limit", 0.85, True),
    ("speed_friction/006-scheme=explicit_penalty_v5_mu0.1", "stability", "failed",
     "explicit_penalty", {"bodies[0].velocity": V[5], "obstacles[0].friction": "0.1"}, "", None,
     False),
    ("neo_hookean/000-scheme=semi_explicit_v50", "stability", "ok", "semi_explicit",
     {"bodies[0].material.model": '"neo_hookean"', "bodies[0].velocity": V[50]}, "bracketed",
     0.699, True),
    ("element_t3/000-scheme=semi_explicit_distort0.2", "stability", "ok", "semi_explicit",
     {"meshes.M1.cells": '"tri"', "meshes.M1.distort": "0.2"}, "bracketed", 1.66, False),
    ("contact_level/000-scheme=implicit_velocity_mu0.1_v5", "stability", "ok", "implicit",
     {"contact.level": '"velocity"', "obstacles[0].friction": "0.1",
      "bodies[0].velocity": V[5]}, "bracketed", 0.89, True),
    ("remedy_neo_hookean/000-scheme=semi_explicit", "run", "ok", "semi_explicit",
     {"bodies[0].material.model": '"neo_hookean"', "bodies[0].velocity": V[50],
      "time.dt_update_interval": "1"}, "", None, False),
    ("remedy_neo_hookean/001-scheme=explicit_penalty", "run", "diverged", "explicit_penalty",
     {"bodies[0].material.model": '"neo_hookean"', "bodies[0].velocity": V[50],
      "time.dt_update_interval": "1"}, "", None, False),
]


def write_envelope(folder):
    """ENV_ROWS as a sweep's summary.csv (docs/sweeps.md, search columns) in FOLDER."""
    keys = ["bodies[0].velocity", "obstacles[0].friction", "bodies[0].material.model",
            "meshes.M1.cells", "meshes.M1.distort", "contact.level", "time.dt_update_interval"]
    cols = ["run_id", "group", "kind", "status", "reason", "time.dt", "scheme"] + keys + [
        "case", "case_file", "overrides", "summary.scheme", "mesh", "critical_dt", "dt", "dt_min",
        "dt_max", "steps", "energy_error_max", "diverged.time", "stable_dt", "unstable_dt",
        "estimate_dt", "stable_over_estimate", "outcome", "converged", "trials",
        "unstable_reason"]
    est = 1.921108115727834e-05
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, "summary.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=cols, lineterminator="\n")
        w.writeheader()
        for rid, kind, status, scheme, over, outcome, ratio, _ in ENV_ROWS:
            r = {"run_id": rid, "group": rid.split("/")[0], "kind": kind, "status": status,
                 "time.dt": "auto", "scheme": scheme, "summary.scheme": scheme, "mesh": "M1",
                 "case": "oblique_plate", "case_file": "cases/oblique_plate.toml",
                 "overrides": json.dumps(['time.dt="auto"', f'scheme="{scheme}"'] +
                                         [f"{k}={v}" for k, v in over.items()])}
            r.update({k: v.strip('"') for k, v in over.items()})
            if kind == "stability" and status == "ok":
                r.update(estimate_dt=repr(est), outcome=outcome, trials="9",
                         converged="true" if outcome == "bracketed" else "false")
                if ratio is not None:
                    r.update(stable_dt=repr(ratio * est), stable_over_estimate=repr(ratio))
                if outcome == "no_stable_down_to_floor":
                    r.update(unstable_dt=repr(est / 1000),
                             unstable_reason="diverged: inverted element (det F = -0.0001)")
                elif outcome != "no_unstable_up_to_cap":
                    r.update(unstable_dt=repr(ratio * est * 1.01),
                             unstable_reason="diverged: energy growth: test")
            elif kind == "stability":
                r["reason"] = "exit 2: a test failure"
            else:
                r.update(dt=repr(1e-5), dt_min=repr(9e-6), dt_max=repr(1.7e-5), steps="252",
                         energy_error_max="0.1", critical_dt=repr(est))
                if status != "ok":
                    r.update({"reason": "inverted element (det F = -0.1)",
                              "diverged.time": "0.0002"})
            w.writerow(r)


# (b): a sweep written from docs/sweeps.md alone: two schemes on the oblique plate, each measured
# against its own reference run at a smaller Δt (work-precision section).
TWO_RUNS = f"""
name = "two_runs"
description = "report test: two schemes, oblique plate, M1, 1 ms, against a reference"
base = "{BASE}"
set = {{ mesh = "M1", "time.end" = 1e-3, "output.fields" = [], "output.interval" = 2e-5 }}

[[group]]
name = "schemes"
set = {{ "time.dt" = 4e-6 }}
cross = {{ scheme = ["semi_explicit", "explicit_penalty"] }}
reference = {{ "time.dt" = 1e-6 }}
"""


# A guard against a hang, not a speed target (those are benchmarks): generous, because the
# sanitizer build (ci/sanitize) and a loaded 2-core machine run these commands several times
# slower than a quiet Release build.
CALL_TIMEOUT = 900


def run(cmd, ok=(0,), **kw):
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=CALL_TIMEOUT, **kw)
    if p.returncode not in ok:
        raise AssertionError(f"{' '.join(cmd)}: exit {p.returncode}\n{p.stdout}\n{p.stderr}")
    return p


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


class Tables(html.parser.HTMLParser):
    """Tables by id: a list of body rows, each a list of cell texts; and sections' raw text."""

    def __init__(self):
        super().__init__()
        self.tables = {}
        self.headers = {}
        self.cur = None
        self.row = None
        self.cell = None
        self.in_body = False

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "table" and a.get("id"):
            self.cur = a["id"]
            self.tables[self.cur] = []
        elif tag == "tbody" and self.cur:
            self.in_body = True
        elif tag == "tr" and self.cur and self.in_body:
            self.row = []
        elif tag == "td" and self.row is not None:
            self.cell = ""
        elif tag == "th" and self.cur and not self.in_body:
            self.headers.setdefault(self.cur, [])
            self.cell = ""

    def handle_endtag(self, tag):
        if tag == "td" and self.cell is not None:
            self.row.append(self.cell.strip())
            self.cell = None
        elif tag == "th" and self.cell is not None:
            self.headers[self.cur].append(self.cell.strip())
            self.cell = None
        elif tag == "tr" and self.row is not None:
            self.tables[self.cur].append(self.row)
            self.row = None
        elif tag == "tbody":
            self.in_body = False
        elif tag == "table":
            self.cur = None

    def handle_data(self, data):
        if self.cell is not None:
            self.cell += data


class Images(html.parser.HTMLParser):
    """The src of every <img>, and the ids of the <section>s."""

    def __init__(self):
        super().__init__()
        self.srcs, self.sections = [], []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "img":
            self.srcs.append(a.get("src"))
        elif tag == "section" and (a.get("id") or "").startswith("sec-"):
            self.sections.append(a["id"][4:])


def check_images(tc, out):
    """Every <img src> of OUT/index.html exists and loads as a non-empty, non-blank PNG.
    Returns (page text, parser)."""
    with open(os.path.join(out, "index.html")) as f:
        page = f.read()
    p = Images()
    p.feed(page)
    tc.assertTrue(p.srcs, out)
    for src in p.srcs:
        tc.assertTrue(src and src.endswith(".png"), src)
        path = os.path.join(out, src)
        tc.assertTrue(os.path.isfile(path), path)
        a = matplotlib.image.imread(path)
        tc.assertGreaterEqual(a.ndim, 2, path)
        tc.assertGreater(min(a.shape[:2]), 50, path)
        tc.assertGreater(float(a.std()), 0.0, f"{path} is blank")
    return page, p


def section_html(text, sid):
    start = text.index(f'<section id="sec-{sid}">')
    return text[start:text.index("</section>", start)]


def history_columns(path, cols):
    """Columns of a history.csv as lists of floats (read here, not with the report's reader)."""
    rows = read_csv(path)
    return {c: [float(r[c]) for r in rows] for c in cols}


def p_difference(dir_a, dir_b):
    """The scheme-limits P trajectory difference recomputed from two history.csv files: max
    over the samples of the run with fewer samples (a's on a tie) of |u_P − u_P,other|, the
    other run interpolated linearly in time, samples outside its time span skipped."""
    import numpy as np
    cols = ("time", "P_ux", "P_uy")
    a = history_columns(os.path.join(dir_a, "history.csv"), cols)
    b = history_columns(os.path.join(dir_b, "history.csv"), cols)
    if len(b["time"]) < len(a["time"]):
        a, b = b, a
    tb = np.array(b["time"])
    tol = 1e-9 * max(abs(tb[0]), abs(tb[-1]))
    best = None
    for t, ux, uy in zip(a["time"], a["P_ux"], a["P_uy"]):
        if t < tb[0] - tol or t > tb[-1] + tol:
            continue
        d = float(np.hypot(ux - np.interp(t, tb, b["P_ux"]), uy - np.interp(t, tb, b["P_uy"])))
        best = d if best is None else max(best, d)
    return best


def check_scheme_limits(tc, rows, folder, expected_labels):
    """The scheme-limits table of the sweep in FOLDER: one row per mesh × compared scheme
    (labels as expected), built from each scheme's ok run with the smallest Δt on the mesh,
    whose P difference is the one recomputed from the two history.csv files."""
    import math
    runs = [r for r in read_csv(os.path.join(folder, "summary.csv"))
            if r["status"] == "ok" and r["group"] != "reference"]
    tc.assertEqual([r[0] for r in rows], expected_labels)
    for row in rows:
        mesh = row[0].split(":")[0]
        picked = []
        for cell in row[2:4]:
            rid = re.match(r"(\S+) \(", cell).group(1)
            r = next(x for x in runs if x["run_id"] == rid)
            tc.assertEqual(r["summary.mesh"], mesh, row)
            same = [x for x in runs if x["summary.mesh"] == mesh
                    and x["summary.scheme"] == r["summary.scheme"]]
            tc.assertEqual(float(r["dt"]), min(float(x["dt"]) for x in same), row)
            picked.append(os.path.join(folder, "runs", rid))
        want = p_difference(*picked)
        tc.assertIsNotNone(want)
        got = float(row[4])
        unit = 10 ** math.floor(math.log10(want))   # the cell has 3 significant digits
        tc.assertLessEqual(abs(got - want), 0.0051 * unit, (row, want))


BG = {}   # the verification sweep of SweepReport, started first so that it runs beside the others


def setUpModule():
    BG["tmp"] = tempfile.mkdtemp(prefix="ricochet_report_any_")
    BG["ver"] = os.path.join(BG["tmp"], "verification")
    BG["ver_cmd"] = [BINARY, "sweep", VER_SWEEP_FILE, "--out", BG["ver"], "--check", VER_GATES,
                     "--quiet"]
    BG["ver_proc"] = subprocess.Popen(BG["ver_cmd"], stdout=subprocess.PIPE,
                                      stderr=subprocess.PIPE, text=True)


def tearDownModule():
    proc = BG.get("ver_proc")
    if proc is not None and proc.poll() is None:
        proc.kill()
        proc.communicate()
    if BG.get("tmp") and not os.environ.get("KEEP_REPORT_TMP"):
        shutil.rmtree(BG["tmp"], ignore_errors=True)


class ReportSmoke(unittest.TestCase):
    tmp = None

    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="ricochet_report_")
        t = cls.tmp
        with open(os.path.join(t, "paper.toml"), "w") as f:
            f.write(PAPER_SWEEP)
        with open(os.path.join(t, "accuracy.toml"), "w") as f:
            f.write(ACC_SWEEP)
        with open(os.path.join(t, "verification.toml"), "w") as f:
            f.write(VER_SWEEP)
        cls.paper = os.path.join(t, "sweeps", "paper")
        cls.acc = os.path.join(t, "other", "acc")
        cls.stab = os.path.join(t, "other", "stab")
        cls.ver = os.path.join(t, "other", "ver")
        cls.kk = os.path.join(t, "sweeps", "kim_kwak")  # next to the paper sweep: discovered
        cls.kk_fields = os.path.join(t, "other", "rubber_groove")
        cls.env = os.path.join(t, "sweeps", "envelope")   # next to the paper sweep: discovered
        cls.long = os.path.join(t, "other", "long")       # given with --long-runs
        write_envelope(cls.env)
        # the Kim–Kwak-type sweep in the background; a failed gate (exit 4) must still report
        kk_cmd = [BINARY, "sweep", KK_SWEEP, "--out", cls.kk, "--check", KK_GATES, "--quiet"]
        kk = subprocess.Popen(kk_cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        run([BINARY, "run", KK_CASE, "--out", cls.kk_fields, "--quiet"])
        # the 3D sweep next to the paper sweep (discovered), the oblique block with its fields
        # given with --three-d-fields
        cls.td = os.path.join(t, "sweeps", "three_d")
        cls.td_fields = os.path.join(t, "other", "oblique_block")
        # the fast 3D Table 1 (one diverged run) in the background and one stability search of
        # a 3D mesh, both next to the paper sweep (discovered)
        cls.td_t1 = os.path.join(t, "sweeps", "three_d_table1")
        cls.td_stab = os.path.join(t, "sweeps", "three_d_stability")
        t1_cmd = [BINARY, "sweep", TD_T1_SWEEP, "--out", cls.td_t1, "--quiet"]
        t1 = subprocess.Popen(t1_cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        # the ball on the block: a tiny sweep next to the paper sweep (discovered) in the
        # background, a run with fields given with --ball-block-fields
        cls.bb = os.path.join(t, "sweeps", "ball_block")
        cls.bb_fields = os.path.join(t, "other", "ball_block_fields")
        with open(os.path.join(t, "ball_block.toml"), "w") as f:
            f.write(BB_SWEEP)
        bb_cmd = [BINARY, "sweep", os.path.join(t, "ball_block.toml"), "--out", cls.bb,
                  "--check", BB_GATES, "--quiet"]
        bb = subprocess.Popen(bb_cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        run([BINARY, "run", BB_CASE, "--out", cls.bb_fields, "--quiet", "--set", "time.end=1e-3",
             "--set", "output.fields=[5e-4, 1e-3]"])
        run([BINARY, "stability", TD_CASE, "--set", "mesh=M1x2", "--set", "scheme=semi_explicit",
             "--set", "obstacles[0].friction=0", "--max-runs", "4", "--quiet",
             "--out", os.path.join(cls.td_stab, "semi_explicit_M1x2")], ok=(0, 4, 5))
        run([BINARY, "sweep", TD_SWEEP, "--out", cls.td, "--check", TD_GATES, "--quiet",
             "--jobs", "2"], ok=(0, 4))
        run([BINARY, "run", TD_CASE, "--out", cls.td_fields, "--quiet", "--set",
             "obstacles[0].friction=0.1", "--set", "output.fields=[0.0, 1e-3, 3e-3]"])
        run([BINARY, "sweep", os.path.join(t, "paper.toml"), "--out", cls.paper, "--jobs", "2",
             "--quiet"])
        run([BINARY, "sweep", os.path.join(t, "accuracy.toml"), "--out", cls.acc, "--jobs", "2",
             "--quiet"])
        run([BINARY, "sweep", os.path.join(t, "verification.toml"), "--out", cls.ver, "--jobs",
             "2", "--quiet"])
        with open(os.path.join(t, "long.toml"), "w") as f:
            f.write(LONG_SWEEP)
        run([BINARY, "sweep", os.path.join(t, "long.toml"), "--out", cls.long, "--jobs", "2",
             "--quiet"])
        with open(os.path.join(cls.long, "summary.csv"), newline="") as f:
            cols = next(csv.reader(f))
        with open(os.path.join(cls.long, "summary.csv"), "a", newline="") as f:
            csv.DictWriter(f, fieldnames=cols, lineterminator="\n").writerow(
                {"run_id": LONG_FAILED, "group": "ball_bouncing", "kind": "run",
                 "status": "failed", "reason": "exit 2: a test failure",
                 "scheme": "semi_explicit"})
        run([PY, LONG_RUNS_PY, cls.long])
        coarse = ["--set", "meshes.M1.nx=4", "--set", "meshes.M1.ny=8"]
        run([BINARY, "stability", BASE, *coarse, "--end", "1e-3", "--max-runs", "8",
             "--out", os.path.join(cls.stab, "semi_explicit_M1"), "--quiet"], ok=(0, 4, 5))
        run([BINARY, "stability", BASE, *coarse, "--set", "scheme=implicit", "--energy-bound", "1",
             "--end", "1e-3", "--max-runs", "8", "--out", os.path.join(cls.stab, "implicit_M1"),
             "--quiet"], ok=(0, 4, 5))
        out, err = kk.communicate(timeout=CALL_TIMEOUT)
        if kk.returncode not in (0, 4):
            raise AssertionError(f"{' '.join(kk_cmd)}: exit {kk.returncode}\n{out}\n{err}")
        out, err = t1.communicate(timeout=CALL_TIMEOUT)
        if t1.returncode != 0:
            raise AssertionError(f"{' '.join(t1_cmd)}: exit {t1.returncode}\n{out}\n{err}")
        out, err = bb.communicate(timeout=CALL_TIMEOUT)
        if bb.returncode not in (0, 4):
            raise AssertionError(f"{' '.join(bb_cmd)}: exit {bb.returncode}\n{out}\n{err}")
        # 1: no accuracy / stability / verification / Kim–Kwak-type sources, default output
        # folder DIR/report
        run([PY, SCRIPT, cls.paper, "--no-discover", "--max-run-plots", "3"])
        cls.out_bare = os.path.join(cls.paper, "report")
        # 2: every source (the Kim–Kwak-type sweep discovered next to DIR)
        cls.out_full = os.path.join(t, "full_report")
        run([BINARY, "report", cls.paper, "--accuracy", cls.acc, "--stability", cls.stab,
             "--verification", cls.ver, "--kim-kwak-fields", cls.kk_fields,
             "--long-runs", cls.long, "--three-d-fields", cls.td_fields,
             "--ball-block-fields", cls.bb_fields, "--out", cls.out_full])

    @classmethod
    def tearDownClass(cls):
        if cls.tmp and not os.environ.get("KEEP_REPORT_TMP"):
            shutil.rmtree(cls.tmp, ignore_errors=True)

    def manifest(self, out):
        with open(os.path.join(out, "manifest.json")) as f:
            return json.load(f)

    def check_files(self, out):
        man = self.manifest(out)
        with open(os.path.join(out, "index.html")) as f:
            page = f.read()
        for s in man["sections"]:
            self.assertIsNone(s["error"], s["id"])
            if s["kind"] == "figure" and s["available"]:
                self.assertTrue(any(f.endswith(".png") for f in s["files"]), s["id"])
            for name in s["files"]:
                path = os.path.join(out, name)
                self.assertTrue(os.path.isfile(path), path)
                self.assertGreater(os.path.getsize(path), 1000, path)
                with open(path, "rb") as f:
                    head = f.read(2000)
                if name.endswith(".png"):
                    self.assertEqual(head[:8], b"\x89PNG\r\n\x1a\n", path)
                    self.assertIn(f'src="{name}"', page)
                elif name.endswith(".svg"):
                    self.assertIn(b"<svg", head, path)
        self.assertGreater(os.path.getsize(os.path.join(out, "report.md")), 1000)
        check_images(self, out)
        self.assertTrue(man["paper_sweep"])
        return man, page

    def test_bare_report_says_what_is_missing(self):
        man, page = self.check_files(self.out_bare)
        by_id = {s["id"]: s for s in man["sections"]}
        missing = ("work_precision", "stability", "verification") + KK_IDS + ENV_IDS + LONG_IDS + TD_IDS
        for sid in missing:
            self.assertFalse(by_id[sid]["available"], sid)
            sec = section_html(page, sid)
            self.assertIn("not-available", sec)
            self.assertIn("build/ricochet", sec)  # how to produce it
        self.assertIn("cases/accuracy/accuracy.toml", section_html(page, "work_precision"))
        self.assertIn("ricochet stability", section_html(page, "stability").replace(
            "build/ricochet stability", "ricochet stability"))
        self.assertIn("cases/verification/sweep.toml", section_html(page, "verification"))
        self.assertIn("cases/kim_kwak/rubber_groove.toml", section_html(page, "kk_shapes"))
        for sid in ("kk_histories", "kk_interfaces", "kk_runs"):
            self.assertIn("cases/kim_kwak/sweep.toml", section_html(page, sid))
        for sid in ENV_IDS:
            self.assertIn("cases/envelope/sweep_full.toml", section_html(page, sid))
            self.assertIn("--envelope", section_html(page, sid))
        self.assertIn("cases/three_d/oblique_block.toml", section_html(page, "td_shapes"))
        for sid in ("td_bar", "td_oblique", "td_frame"):
            self.assertIn("cases/three_d/sweep.toml", section_html(page, sid))
        self.assertIn("build/ricochet sweep cases/three_d_table1/sweep_full.toml", section_html(page, "td_table1"))
        self.assertIn("build/ricochet run cases/ball_block/ball_block.toml",
                      section_html(page, "bb_shapes"))
        for sid in ("bb_histories", "bb_runs"):
            self.assertIn("build/ricochet sweep cases/ball_block/sweep_full.toml",
                          section_html(page, sid))
            self.assertIn("--ball-block", section_html(page, sid))
        self.assertIsNone(man["ball_block"])
        self.assertIsNone(man["ball_block_fields"])
        self.assertIsNone(man["three_d_table1"])
        self.assertEqual(man["three_d_stability"], [])
        for sid in LONG_IDS:
            self.assertIn("cases/long_runs/sweep.toml", section_html(page, sid))
            self.assertIn("cases/long_runs/drift.py", section_html(page, sid))
        self.assertIsNone(man["envelope"])
        self.assertIsNone(man["long_runs"])
        self.assertFalse([s for s in by_id if s.startswith("ver_")])
        for sid, s in by_id.items():
            if sid not in missing:
                self.assertTrue(s["available"], f"{sid}: {s['missing']}")
        self.assertIsNone(man["kim_kwak"])
        self.assertIsNone(man["kim_kwak_fields"])
        # the paper sweep's run histories, capped by --max-run-plots 3
        with_history = [r["run_id"] for r in read_csv(os.path.join(self.paper, "summary.csv"))
                        if os.path.isfile(os.path.join(self.paper, "runs", r["run_id"],
                                                       "history.csv"))]
        self.assertEqual(by_id["histories"]["runs"], with_history[:3])
        self.assertEqual(len(by_id["histories"]["files"]), 3)
        self.assertIn(f"Only the first 3 of {len(with_history)} runs are drawn",
                      section_html(page, "histories"))
        with open(os.path.join(self.out_bare, "report.md")) as f:
            md = f.read()
        self.assertEqual(md.count("**Not available:**"), len(missing))

    def test_full_report_has_every_section(self):
        man, page = self.check_files(self.out_full)
        ver_ids = {"ver_" + c.case for c in RV.CASES}
        ver_ok = {"ver_" + c for c in VER_CASES}
        acc = read_csv(os.path.join(self.acc, "summary.csv"))
        metrics = [c for c in acc[0] if c.startswith("error_")
                   and any(r[c] and float(r[c]) > 0 for r in acc if r["kind"] == "run")]
        self.assertIn("error_probe_P", metrics)
        wp_ids = {"wp_" + m for m in metrics}
        expected = {"table1", "fig1", "fig2", "fig3", "fig4", "fig5", "fig6", "fig7",
                    "stability", "penetration", "failed", "runs", "histories",
                    "scheme_limits"} | wp_ids \
            | ver_ids | set(KK_IDS) | set(ENV_IDS) | set(LONG_IDS) | set(TD_IDS)
        by_id = {s["id"]: s for s in man["sections"]}
        self.assertEqual(set(by_id), expected)
        for sid, s in by_id.items():
            if sid in ver_ids - ver_ok:
                # a case of the spec that the sweep does not run: says so, with the command
                self.assertFalse(s["available"], sid)
                self.assertIn("cases/verification/sweep.toml", s["missing"])
                self.assertIn("not-available", section_html(page, sid))
            else:
                self.assertTrue(s["available"], f"{sid}: {s['missing']}")
                self.assertNotIn("not-available", section_html(page, sid))
            self.assertEqual(s["part"] == RV.PART_TITLE, sid in ver_ids, sid)
            self.assertEqual(s["part"] == RK.PART_TITLE, sid in KK_IDS, sid)
        # figures: expected files, caption names the runs
        for sid, stem in (("fig1", "fig1_deformed_shapes"), ("fig2", "fig2_von_mises_0.6ms"),
                          ("fig3", "fig3_energies_M2"), ("fig4", "fig4_energy_error"),
                          ("fig5", "fig5_P_displacement_mu0"),
                          ("fig6", "fig6_P_displacement_mu0.1"),
                          ("fig7", "fig7_friction_dissipation"),
                          *((f"wp_{m}", f"work_precision_{m}") for m in metrics),
                          ("stability", "stability_map"),
                          ("penetration", "penetration"),
                          *((f"ver_{c}", f"verification_{c}") for c in VER_CASES),
                          ("kk_shapes", "kim_kwak_shapes"),
                          ("kk_histories", "kim_kwak_histories"),
                          ("kk_interfaces", "kim_kwak_interfaces"),
                          ("long_runs", "long_runs_residual"),
                          ("td_shapes", "three_d_shapes"), ("td_bar", "three_d_bar"),
                          ("td_table1", "three_d_table1"),
                          ("bb_shapes", "ball_block_shapes"),
                          ("bb_histories", "ball_block_histories")):
            self.assertIn(stem + ".png", by_id[sid]["files"], sid)
            self.assertTrue(by_id[sid]["runs"], sid)
            sec = section_html(page, sid)
            cap = sec[sec.index("<figcaption>"):sec.index("</figcaption>")]
            for rid in by_id[sid]["runs"]:
                self.assertIn(rid, cap, f"{sid} caption does not name {rid}")
        # Kim–Kwak-type: the discovered sweep, the given fields run; five runs drawn; one panel
        # title per field time
        self.assertEqual(man["kim_kwak"], os.path.abspath(self.kk))
        self.assertEqual(man["kim_kwak_fields"], os.path.abspath(self.kk_fields))
        kk_ids = [r["run_id"] for r in read_csv(os.path.join(self.kk, "summary.csv"))]
        self.assertEqual(sorted(by_id["kk_histories"]["runs"]), sorted(kk_ids))
        self.assertEqual(sorted(by_id["kk_interfaces"]["runs"]), sorted(kk_ids))
        cap = section_html(page, "kk_interfaces")
        for name in ("groove", "bump", "ball_block"):
            self.assertIn(f"{name} ", cap)
        self.assertEqual(len(kk_ids), 5)
        self.assertEqual(by_id["kk_shapes"]["runs"], [os.path.abspath(self.kk_fields)])
        cap = section_html(page, "kk_shapes")
        self.assertIn("groove: polyline, bump: circle", cap)
        self.assertRegex(cap, r"\((\d[\d.]*, ){5}\d[\d.]* ms; fields/\*\.vtu\)")  # 6 times
        intro = page[page.index('<h2 id="part-'):]
        self.assertIn("docs/kim-kwak-type.md", intro)
        # Fig. 3 holds both the semi-explicit and the penalty run
        self.assertIn("penalty/000", by_id["fig3"]["runs"])
        # Fig. 2 is M2 at the smallest Δt, both schemes
        self.assertEqual(sorted(by_id["fig2"]["runs"]),
                         ["table1/010-mesh=M2_time.dt=1e-6_scheme=semi_explicit",
                          "table1/011-mesh=M2_time.dt=1e-6_scheme=implicit"])

    def test_three_d_part(self):
        """The 3D part: the discovered 3D sweep, the given fields run; the bar table against the
        1D solution and the 3D/2D ratios recomputed from summary.csv; frame invariance rows."""
        man, page = self.check_files(self.out_full)
        self.assertEqual(man["three_d"], os.path.abspath(self.td))
        self.assertEqual(man["three_d_fields"], os.path.abspath(self.td_fields))
        by_id = {s["id"]: s for s in man["sections"]}
        for sid in TD_IDS:
            self.assertEqual(by_id[sid]["part"], R3.PART_TITLE, sid)
        with open(os.path.join(self.out_full, "index.html")) as f:
            parser = Tables()
            parser.feed(f.read())
        tables = parser.tables
        rows = {r["run_id"]: r for r in read_csv(os.path.join(self.td, "summary.csv"))}
        bar = tables["tab-td_bar_table"]
        bar_ids = sorted(i for i, r in rows.items() if r["case"] == "bar_wall3" and r["status"] == "ok")
        self.assertEqual(len(bar_ids), 6)   # the three schemes, stiff springs, hourglass, tet4
        self.assertEqual(sorted(r[0] for r in bar), bar_ids)
        for r in bar:
            f = float(rows[r[0]]["contact_force_mean"])
            self.assertIn(f"({100 * (f / 16000.0 - 1):+.2f} %)", r[2], r[0])
        self.assertEqual(sorted(by_id["td_bar"]["runs"]), bar_ids)
        # 3D / 2D: every quantity of every scheme and mu, the ratio of the two runs' cells
        ob = tables["tab-td_oblique"]
        self.assertGreaterEqual(len(ob), 20)
        col = {"rebound v_y (m/s)": "rebound_velocity_y", "contact time (s)":
               "contact_iterations.contact_time", "von Mises peak (Pa)": "von_mises_max"}
        checked = 0
        for r in ob:
            if r[1] not in col:
                continue
            label, mu = r[0].split(", ")
            scheme = {"semi-explicit": "semi_explicit", "implicit": "implicit",
                      "explicit penalty": "explicit_penalty"}[label]
            pick = lambda g: next(v for v in rows.values() if v["group"] == g and v["status"] == "ok"  # noqa: E731
                                  and float(v["obstacles[0].friction"]) == float(mu)
                                  and v["summary.scheme"] == scheme)
            a = float(pick(R3.oblique_group(scheme))[col[r[1]]])
            b = float(pick("oblique2d")[col[r[1]]])
            self.assertEqual(r[4], f"{a / b:.4f}", r)
            checked += 1
        self.assertEqual(checked, 18)  # 3 quantities x 3 schemes x 2 mu
        frame = tables["tab-td_frame"]
        self.assertEqual(len(frame), 15)  # 5 quantities x 3 schemes
        for r in frame:
            self.assertLess(float(r[4]), 1e-9, r)
        cap = section_html(page, "td_shapes")
        self.assertIn("(0, 1, 3 ms; fields/*.vtu)", cap)
        self.assertEqual(by_id["td_shapes"]["runs"], [os.path.abspath(self.td_fields)])

    def test_three_d_table1(self):
        """Table 1 in 3D from the fast sweep and the stability search found next to the paper
        sweep: one cell per (mesh, Δt) and scheme with the run's wall time and energy error or
        its time of divergence, the implicit / semi-explicit ratio, the penalty run, the
        stability bracket, the figure."""
        man, page = self.check_files(self.out_full)
        self.assertEqual(man["three_d_table1"], os.path.abspath(self.td_t1))
        stab_file = os.path.join(os.path.abspath(self.td_stab), "semi_explicit_M1x2",
                                 "stability.json")
        self.assertEqual(man["three_d_stability"], [stab_file])
        by_id = {s["id"]: s for s in man["sections"]}
        sec = by_id["td_table1"]
        self.assertTrue(sec["available"], sec["missing"])
        self.assertEqual(sec["files"], ["three_d_table1.png", "three_d_table1.svg"])
        a = matplotlib.image.imread(os.path.join(self.out_full, "three_d_table1.png"))
        self.assertGreater(float(a.std()), 0.0)
        parser = Tables()
        parser.feed(page)
        rows = read_csv(os.path.join(self.td_t1, "summary.csv"))
        t1 = [r for r in rows if r["group"] == "table1"]
        self.assertEqual(len(t1), 4)   # M1x2 x 1e-4, 1e-5 x two schemes
        self.assertEqual(sorted(sec["runs"]), sorted(r["run_id"] for r in rows))
        hdr = parser.headers["tab-td_table1_table"]
        self.assertEqual(hdr, ["scheme", "M1x2, Δt = 1e-4 s", "M1x2, Δt = 1e-5 s"])
        table = parser.tables["tab-td_table1_table"]
        self.assertEqual([r[0] for r in table], ["Semi-explicit", "Implicit"])
        wall = {}
        diverged = 0
        for r in t1:
            row = table[0] if r["summary.scheme"] == "semi_explicit" else table[1]
            cell = row[hdr.index(f"M1x2, Δt = {r['time.dt']} s")]
            if r["status"] == "diverged":
                diverged += 1
                t = float(r["diverged.time"])
                self.assertEqual(cell, f"diverged at t = {fmt_g(t)} s")
            else:
                self.assertEqual(r["status"], "ok")
                w, e = float(r["wall_seconds"]), float(r["energy_error_max"])
                wall[(r["summary.scheme"], r["time.dt"])] = w
                self.assertEqual(cell, f"{fmt_g(w)} s; energy error {fmt_g(100 * e, 2)} %")
        self.assertGreaterEqual(diverged, 1)   # the semi-explicit scheme at 1e-4 s
        self.assertIn('<td class="diverged"><b>diverged</b> at t =', section_html(page, "td_table1"))
        ratio = parser.tables["tab-td_table1_ratio"]
        self.assertEqual(len(ratio), 1)
        for k, dt in enumerate(("1e-4", "1e-5")):
            a, b = wall.get(("implicit", dt)), wall.get(("semi_explicit", dt))
            self.assertEqual(ratio[0][k + 1], f"×{a / b:.1f}" if a and b else "–")
        pen = [r for r in rows if r["group"] == "penalty"]
        ptab = parser.tables["tab-td_table1_penalty"]
        self.assertEqual([r[-1] for r in ptab], [r["run_id"] for r in pen])
        self.assertEqual(ptab[0][1], f"{fmt_g(float(pen[0]['dt']), 4)} s")
        with open(stab_file) as f:
            st = json.load(f)
        stab = parser.tables["tab-td_table1_stability"]
        self.assertEqual([r[0] for r in stab], ["M1x2 semi-explicit"])
        self.assertEqual(stab[0][2], f"{fmt_g(st['largest_stable_dt'], 4)} s")
        cap = section_html(page, "td_table1")
        cap = cap[cap.index("<figcaption>"):cap.index("</figcaption>")]
        self.assertIn("single runs", cap)    # no --repeat
        self.assertIn("three-dimensions.md#the-3d-table-1", cap)
        self.assertIn("ricochet sweep cases/three_d_table1/sweep_fast.toml", cap)

    def test_ball_block(self):
        """The ball on the block: the discovered tiny sweep, the given fields run; one history
        run per scheme (the case's settings), the runs table's frame updates and momentum
        deviation recomputed from summary.csv and history.csv, the gate line."""
        man, page = self.check_files(self.out_full)
        self.assertEqual(man["ball_block"], os.path.abspath(self.bb))
        self.assertEqual(man["ball_block_fields"], os.path.abspath(self.bb_fields))
        by_id = {s["id"]: s for s in man["sections"]}
        self.assertEqual(by_id["bb_histories"]["runs"], ["semi/000-contact.frame_updates=10",
                                                         "implicit/000", "penalty/000"])
        self.assertEqual(by_id["bb_shapes"]["runs"], [os.path.abspath(self.bb_fields)])
        # two field times (0.5 and 1 ms, each at the nearest step), both bodies drawn
        cap = section_html(page, "bb_shapes")
        self.assertRegex(cap, r"\(0\.\d+, 1\.?\d* ms; fields/\*\.vtu\)")
        self.assertRegex(cap, r"ball [\d.e+-]+ Pa, block [\d.e+-]+ Pa")
        parser = Tables()
        parser.feed(page)
        table = parser.tables["tab-bb_runs"]
        rows = read_csv(os.path.join(self.bb, "summary.csv"))
        self.assertEqual([r[0] for r in table], [r["run_id"] for r in rows])
        frames = {"semi/000-contact.frame_updates=10": "10",
                  "semi/001-contact.frame_updates=0": "0 (frozen frame)", "implicit/000": "10",
                  "penalty/000": "– (penalty)"}
        for r in table:
            self.assertEqual(r[2], frames[r[0]], r)
            h = history_columns(os.path.join(self.bb, "runs", r[0], "history.csv"),
                                [f"momentum_{c}" for c in "xyz"])
            dev = max(abs(v - col[0]) for col in h.values() for v in col)
            self.assertEqual(r[7], fmt_g(dev, 2), r)
            self.assertLess(dev, 1e-14, r)
        sec = section_html(page, "bb_runs")
        self.assertIn("cases/ball_block/gates_fast.toml", sec)
        self.assertRegex(sec, r"\d+ passed, 0 failed")
        self.assertIn("three-dimensions.md#the-ball-on-the-block", sec)

    def test_tables_have_expected_rows(self):
        with open(os.path.join(self.out_full, "index.html")) as f:
            parser = Tables()
            parser.feed(f.read())
        tables = parser.tables
        main = read_csv(os.path.join(self.paper, "summary.csv"))
        acc = read_csv(os.path.join(self.acc, "summary.csv"))

        def first(tid):
            return [r[0] for r in tables[tid]]

        self.assertEqual(first("tab-table1"), ["Semi-explicit", "Implicit"])
        t1 = tables["tab-table1"]
        self.assertEqual([len(r) for r in t1], [7, 7])  # label + M1/M2 x 3 dt
        # the paper's values beside ours; diverged cells marked
        self.assertIn("paper 5.68 s", t1[0][2])
        self.assertIn("paper 26977.02 s", t1[1][6])
        self.assertIn("diverged", t1[0][1])  # M1, 1e-4 diverges on the coarse mesh too
        self.assertIn("speed-up", t1[1][1])
        self.assertEqual(first("tab-table1_ratio"), ["ours", "paper"])
        self.assertEqual(first("tab-vm_max"), ["semi-explicit", "implicit"])
        friction_ok = {r["run_id"] for r in main if r["group"] == "friction" and r["status"] == "ok"}
        self.assertEqual({r[-1] for r in tables["tab-fig7_table"]}, friction_ok)
        # work-precision points: every run of the accuracy sweep, the drawn ones (ok, a
        # positive error) first; the others say why they are not drawn
        acc_runs = [r for r in acc if r["kind"] == "run"]
        drawn = {r["run_id"] for r in acc_runs if r["status"] == "ok" and r["error_probe_P"]
                 and float(r["error_probe_P"]) > 0}
        wp = tables["tab-wp_error_probe_P_data"]
        self.assertEqual(sorted(r[0] for r in wp), sorted(r["run_id"] for r in acc_runs))
        self.assertEqual({r[0] for r in wp if "not drawn" not in r[6]}, drawn)
        self.assertTrue(drawn and len(drawn) < len(acc_runs))  # the diverged run is not drawn
        # scheme limits of the accuracy sweep: one mesh (M1), implicit against semi-explicit
        check_scheme_limits(self, tables["tab-scheme_limits"], self.acc,
                            ["M1: implicit vs semi-explicit"])
        self.assertEqual(len(tables["tab-stability_table"]), 2)
        self.assertEqual(first("tab-penetration_table"),
                         [r["run_id"] for r in main if r["status"] == "ok"])
        ver = read_csv(os.path.join(self.ver, "summary.csv"))
        kk = read_csv(os.path.join(self.kk, "summary.csv"))
        not_ok = [r["run_id"] for r in main + acc + ver + kk if r["status"] != "ok"]
        self.assertTrue(not_ok)  # the tiny sweeps have diverged runs
        self.assertEqual(first("tab-failed"), not_ok)
        self.assertEqual(first("tab-runs"), [r["run_id"] for r in main])
        # verification: per case, the reference column, then every run in scheme order, and the
        # spec's quantities as rows, each with its reference and a relative error per run
        specs = {c.case: c for c in RV.CASES}
        order = {sc: k for k, sc in enumerate(RV.SCHEMES)}
        for case in VER_CASES:
            tid = f"tab-ver_{case}_table"
            hdr, rows = parser.headers[tid], tables[tid]
            runs = sorted([r for r in ver if r["case"] == case],
                          key=lambda r: (order[r["summary.scheme"]], ver.index(r)))
            self.assertEqual(hdr[:2], ["quantity", f"analytic reference ([{specs[case].ref}])"])
            self.assertEqual(len(hdr), 2 + len(runs))
            for sc in RV.SCHEMES:  # the three schemes
                self.assertTrue(any(h.startswith(RV.scheme_name(sc)) for h in hdr[2:]),
                                (case, sc))
            self.assertEqual(rows[0], ["run", "–"] + [r["run_id"] for r in runs])
            labels = [re.sub(r"[*`]", "", q.label) for q in specs[case].quantities]
            self.assertEqual([r[0] for r in rows],
                             ["run", "Δt"] + labels + ["energy_error_max", "penetration_max"])
            for row in rows[2:2 + len(labels)]:
                self.assertNotIn("missing", row[1], (case, row[0]))  # reference found
                for cell in row[2:]:
                    self.assertRegex(cell, r"\d.*\(.*%.*\)", (case, row[0]))
        # two penalty runs of the bar: one column each, told apart by the scale factor
        bar_hdr = parser.headers["tab-ver_bar_wall_table"]
        self.assertIn("explicit penalty, penalty.scale_factor = 0.1", bar_hdr)
        self.assertIn("explicit penalty, penalty.scale_factor = 1", bar_hdr)
        # Kim–Kwak-type runs: one row per run in scheme order, a label telling the runs of one
        # scheme apart, the final probe values, the gate result under the table
        order_kk = sorted(kk, key=lambda r: (order[r["summary.scheme"]], kk.index(r)))
        rows = tables["tab-kk_runs"]
        self.assertEqual(first("tab-kk_runs"), [r["run_id"] for r in order_kk])
        self.assertEqual(parser.headers["tab-kk_runs"][0], "run")
        self.assertEqual(len(parser.headers["tab-kk_runs"]), 10)
        for row, r in zip(rows, order_kk):
            self.assertEqual(len(row), 10)
            self.assertTrue(row[9].startswith(r["status"]), row)
            if r["status"] == "ok":
                self.assertRegex(row[6], r"^-?\d")                     # final ball_centre_vx
                self.assertRegex(row[7], r"^\(-?[\d.e-]+, -?[\d.e-]+\)$")  # block_corner
        self.assertIn("semi-explicit, time.safety = 0.9", [r[1] for r in rows])
        self.assertIn("explicit penalty, penalty.soft = false", [r[1] for r in rows])
        with open(os.path.join(self.out_full, "index.html")) as f:
            kk_sec = section_html(f.read(), "kk_runs")
        self.assertRegex(kk_sec, r"<b>Gates</b>.*: \d+ passed, \d+ failed")
        # the manifest agrees with the page
        man = self.manifest(self.out_full)
        for s in man["sections"]:
            for t in s["tables"]:
                self.assertEqual(len(t["rows"]), len(tables["tab-" + t["id"]]), t["id"])

    def test_kim_kwak_one_source_only(self):
        """Either source alone: its own sections built, the other's not available with the
        command that produces it."""
        import make_report
        from report_io import Sweep
        out = os.path.join(self.tmp, "kk_partial")
        os.makedirs(out, exist_ok=True)
        only_sweep = RK.sections({"out": out, "kk": Sweep(self.kk), "kk_fields": None},
                                 make_report.Section)
        only_fields = RK.sections({"out": out, "kk": None,
                                   "kk_fields": os.path.join(self.kk_fields, "fields")},
                                  make_report.Section)
        self.assertEqual([s.id for s in only_sweep], list(KK_IDS))
        self.assertEqual([s.available for s in only_sweep], [False, True, True, True])
        self.assertIn(RK.FIELDS_CMD, only_sweep[0].missing)
        self.assertEqual([s.available for s in only_fields], [True, False, False, False])
        for s in only_fields[1:]:
            self.assertIn(RK.KK_CMD, s.missing)
        for s in only_sweep + only_fields:
            self.assertIsNone(s.error, s.id)
            for name in s.files:
                self.assertGreater(os.path.getsize(os.path.join(out, name)), 1000, name)
        # a folder without VTU files is not a fields run
        none = RK.sections({"out": out, "kk": None, "kk_fields": self.kk}, make_report.Section)
        self.assertFalse(none[0].available)
        self.assertIn("no fields/*.vtu", none[0].missing)

    def test_envelope_and_long_runs(self):
        """The envelope (discovered next to the paper sweep) and the long runs (--long-runs):
        the unsafe-points table lists exactly the searches below 0.9 x the estimate or without a
        stable step, the remedy runs beside their search, the counts; the long-run table one row
        per drift.csv row, the failed one marked; the figures written."""
        man = self.manifest(self.out_full)
        self.assertEqual(man["envelope"], os.path.abspath(self.env))
        self.assertEqual(man["long_runs"], os.path.abspath(self.long))
        by_id = {s["id"]: s for s in man["sections"]}
        self.assertEqual(by_id["envelope"]["files"],
                         ["stability_envelope.png", "stability_envelope.svg"])
        with open(os.path.join(self.out_full, "index.html")) as f:
            page = f.read()
        p = Tables()
        p.feed(page)
        short = lambda rid: rid.split("-")[0]  # noqa: E731  <group>/<index>
        unsafe = [r for r in ENV_ROWS if r[7]]
        rows = p.tables["tab-envelope_unsafe"]
        self.assertEqual([r[0] for r in rows], [short(r[0]) for r in unsafe])
        for row, r in zip(rows, unsafe):
            self.assertEqual(row[1], r[3].replace("_", " ").replace("semi explicit",
                                                                     "semi-explicit"))
            if r[6] is None:    # no stable step at all
                self.assertEqual((row[3], row[4]), ("no stable Δt", "–"))
            else:
                self.assertAlmostEqual(float(row[3]), r[6], places=2)
                self.assertAlmostEqual(float(row[4]), r[6] / 0.9, places=2)   # the margin
        self.assertIn("v = 50 m/s, μ = 0.5, St Venant–Kirchhoff", rows[0][2])
        self.assertIn("neo-Hookean", rows[3][2])
        self.assertIn("contact level velocity", rows[4][2])
        self.assertIn("run_limit", rows[2][5])
        self.assertIn("inverted element", rows[0][6])
        # the remedy runs: status, the search at the same point (or none)
        remedy = p.tables["tab-envelope_remedy"]
        self.assertEqual([r[0] for r in remedy], ["remedy_neo_hookean/000",
                                                  "remedy_neo_hookean/001"])
        self.assertEqual(remedy[0][3], "ok")
        self.assertTrue(remedy[1][3].startswith("diverged at t = 2e-4 s: inverted element"))
        self.assertEqual(remedy[0][-1], "0.699 (neo_hookean/000)")
        self.assertEqual(remedy[1][-1], "no search at this point")
        # counts: the failed search left out, the others per group and scheme
        searches = [r for r in ENV_ROWS if r[1] == "stability" and r[2] == "ok"]
        safe = [r for r in searches if not r[7]]
        cap = section_html(page, "envelope")
        self.assertIn(f"{len(searches)} searches: {len(safe)} leave the automatic step stable, "
                      f"{len(unsafe)} do not", cap)
        self.assertIn("speed_friction/006-scheme=explicit_penalty_v5_mu0.1", cap)  # failed, named
        counts = {(r[0], r[1]): r for r in p.tables["tab-envelope_counts"]}
        self.assertEqual(counts[("speed_friction", "semi-explicit")][2:5], ["3", "1", "2"])
        self.assertEqual(counts[("speed_friction", "implicit")][2:7], ["2", "2", "0", "0", "1"])
        # the long runs: every row of drift.csv, the failed one without values
        drift = read_csv(os.path.join(self.long, "drift.csv"))
        self.assertEqual(len(drift), 5)
        lrows = p.tables["tab-long_runs_table"]
        self.assertEqual([r[0] for r in lrows], [short(d["run_id"]) for d in drift])
        hdr = p.headers["tab-long_runs_table"]
        col = {h: k for k, h in enumerate(hdr)}
        for row, d in zip(lrows, drift):
            if d["status"] == "ok":
                self.assertEqual(float(row[col["drift of R / E_ref per 1e5 steps"]]),
                                 float(f"{float(d['energy_drift_per_1e5_steps']):.2g}"))
                self.assertEqual(row[col["steps"]], d["steps"])
            else:
                self.assertEqual(row[col["status"]], "failed")
                self.assertEqual(row[col["steps"]], "–")
        sliding = [r for r in lrows if r[0].startswith("block_sliding")]
        self.assertTrue(all("slide_distance" in r[-1] for r in sliding), sliding)
        ok_ids = [d["run_id"] for d in drift if d["status"] == "ok"]
        self.assertEqual(by_id["long_runs"]["runs"], ok_ids)
        self.assertIn(f"Not drawn: {LONG_FAILED} (failed)", section_html(page, "long_runs")
                      .replace("<code>", "").replace("</code>", ""))

    def test_envelope_and_long_runs_partial(self):
        """Missing or partial sources: the sections say what is missing and how to produce it;
        a long-run sweep without drift.csv still draws its residuals; an envelope whose only
        search failed has nothing to draw. And a report of either sweep alone shows them."""
        import make_report
        import report_stability as RS
        from report_io import Sweep
        out = os.path.join(self.tmp, "stab_partial")
        os.makedirs(out, exist_ok=True)
        none = RS.sections({"out": out, "env": None, "long": None}, make_report.Section)
        self.assertEqual([s.id for s in none], list(ENV_IDS + LONG_IDS))
        for s in none:
            self.assertFalse(s.available, s.id)
            self.assertIn("build/ricochet sweep", s.missing)
        nodrift = os.path.join(self.tmp, "long_nodrift")
        os.makedirs(nodrift, exist_ok=True)
        shutil.copy(os.path.join(self.long, "summary.csv"), nodrift)
        os.symlink(os.path.join(self.long, "runs"), os.path.join(nodrift, "runs"))
        fig, tab = RS.long_run_sections({"out": out, "long": Sweep(nodrift)}, make_report.Section)
        self.assertTrue(fig.available, fig.missing)
        self.assertGreater(os.path.getsize(os.path.join(out, fig.files[0])), 1000)
        self.assertFalse(tab.available)
        self.assertIn(f"cases/long_runs/drift.py {nodrift}", tab.missing)
        failed_only = os.path.join(self.tmp, "env_failed")
        os.makedirs(failed_only, exist_ok=True)
        with open(os.path.join(self.env, "summary.csv"), newline="") as f:
            rows = list(csv.DictReader(f))
        with open(os.path.join(failed_only, "summary.csv"), "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0]), lineterminator="\n")
            w.writeheader()
            w.writerows(r for r in rows if r["status"] == "failed")
        env = RS.read_envelope(failed_only)
        secs = RS.envelope_sections({"out": out, "env": env}, make_report.Section)
        for s in secs:
            self.assertFalse(s.available, s.id)
            self.assertIn("no finished stability search", s.missing)
        # a report of either sweep by itself gives its part: the envelope sweep is found as
        # its own source (the figure is drawn by the full report already), the long-run sweep's
        # report is written
        import argparse
        args = argparse.Namespace(accuracy=None, stability=None, verification=None,
                                  kim_kwak=None, kim_kwak_fields=None, envelope=None,
                                  long_runs=None, three_d=None, three_d_refinement=None,
                                  three_d_fields=None, three_d_table1=None,
                                  three_d_stability=None, no_discover=False)
        src = make_report.generic_sources(Sweep(self.env), args)
        self.assertEqual(src[5:7], (os.path.abspath(self.env), None))
        src = make_report.generic_sources(Sweep(self.long), args)
        self.assertEqual(src[5:7], (None, os.path.abspath(self.long)))
        self.assertEqual(src[7], (None,) * 5)  # no 3D sources for the long runs
        # the 3D sweep is its own source; the 3D Table 1 and the stability folder beside it
        src = make_report.generic_sources(Sweep(self.td), args)
        t1, stab = os.path.abspath(self.td_t1), os.path.abspath(self.td_stab)
        self.assertEqual(src[7], (os.path.abspath(self.td), None, None, t1, stab))
        src = make_report.generic_sources(Sweep(self.td_t1), args)  # and so is the Table 1 sweep
        self.assertEqual(src[7], (os.path.abspath(self.td), None, None, t1, stab))
        args.no_discover = True
        src = make_report.generic_sources(Sweep(self.td_t1), args)
        self.assertEqual(src[7], (None, None, None, t1, None))
        rep = os.path.join(self.tmp, "alone_long")
        run([PY, SCRIPT, self.long, "--out", rep, "--max-run-plots", "1"])
        got = {s["id"]: s for s in self.manifest(rep)["sections"]}
        for sid in LONG_IDS:
            self.assertTrue(got[sid]["available"], sid)
        self.assertNotIn("envelope", got)
        check_images(self, rep)

    def test_markdown_table1(self):
        with open(os.path.join(self.out_full, "report.md")) as f:
            md = f.read()
        self.assertIn("| scheme (ours: wall time, time loop) | M1, Δt = 1e-4 s | M1, Δt = 1e-5 s "
                      "| M1, Δt = 1e-6 s | M2, Δt = 1e-4 s | M2, Δt = 1e-5 s | M2, Δt = 1e-6 s "
                      "|", md)
        self.assertIn("| **Semi-explicit** |", md)
        self.assertIn("| **Implicit** |", md)
        self.assertIn("## Verification cases: analytic reference against the three schemes", md)
        self.assertIn("| quantity | analytic reference ([bar_wall]) | semi-explicit | implicit | "
                      "explicit penalty, penalty.scale_factor = 0.1 | explicit penalty, "
                      "penalty.scale_factor = 1 |", md)
        self.assertIn("![Bar on a rigid wall", md)
        # only the verification cases that the tiny sweep does not run are not available
        missing = len(RV.CASES) - len(VER_CASES)
        self.assertEqual(md.count("**Not available:**"), missing)

class SweepReport(unittest.TestCase):
    """make_report.py on sweeps that are not the paper's, and plot_run.py."""

    @classmethod
    def setUpClass(cls):
        t = BG["tmp"]
        # (b) the two-run sweep, each run twice (median and spread of the wall time)
        with open(os.path.join(t, "two_runs.toml"), "w") as f:
            f.write(TWO_RUNS)
        cls.two = os.path.join(t, "two_runs")
        run([BINARY, "sweep", os.path.join(t, "two_runs.toml"), "--out", cls.two, "--repeat",
             "2", "--quiet"])
        rows = read_csv(os.path.join(cls.two, "summary.csv"))
        runs = [r for r in rows if r["kind"] == "run"]
        assert len(runs) == 2 and all(r["status"] == "ok" for r in runs), rows
        # gates by `ricochet check`: a limit between the two runs' energy_error_max, so that
        # exactly one run fails it, and a count gate that passes
        e = sorted(float(r["energy_error_max"]) for r in runs)
        assert e[0] < e[1], e
        cls.limit = (e[0] + e[1]) / 2
        cls.gate_fail = "energy error below the middle"
        with open(os.path.join(t, "gates.toml"), "w") as f:
            f.write(f'name = "two_runs"\n\n[[gate]]\nname = "{cls.gate_fail}"\nkind = "max"\n'
                    f'column = "energy_error_max"\nlimit = {cls.limit!r}\n'
                    'where = { kind = "run" }\n\n[[gate]]\nname = "two ok runs"\n'
                    'kind = "count"\nmin = 2\nwhere = { kind = "run", status = "ok" }\n')
        run([BINARY, "check", os.path.join(cls.two, "summary.csv"), os.path.join(t, "gates.toml")],
            ok=(4,))
        # a copy with the reference's uncertainty: floor = 2 x the smaller probe error
        cls.floor = os.path.join(t, "two_runs_floor")
        os.makedirs(cls.floor)
        shutil.copy(os.path.join(cls.two, "sweep.json"), cls.floor)
        os.symlink(os.path.join(cls.two, "runs"), os.path.join(cls.floor, "runs"))
        errs = [float(r["error_probe_P"]) for r in runs]
        cls.floor_value = 2 * min(errs)
        cols = list(rows[0]) + ["floor_error_probe_P"]
        with open(os.path.join(cls.floor, "summary.csv"), "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=cols, lineterminator="\n")
            w.writeheader()
            for r in rows:
                w.writerow(dict(r, floor_error_probe_P=repr(cls.floor_value)
                                if r["kind"] == "run" else ""))
        cls.out_two = os.path.join(t, "report_two")
        # (a), (b) and the full paper report go through `ricochet report`, as a user runs it
        run([BINARY, "report", cls.two, "--out", cls.out_two])
        cls.out_two1 = os.path.join(t, "report_two_capped")
        run([PY, SCRIPT, cls.two, "--out", cls.out_two1, "--max-run-plots", "1"])
        cls.out_floor = os.path.join(cls.floor, "report")   # the default output folder
        run([PY, SCRIPT, cls.floor])
        # (a) the verification sweep, started by setUpModule
        out, err = BG["ver_proc"].communicate(timeout=CALL_TIMEOUT)
        if BG["ver_proc"].returncode not in (0, 4):
            raise AssertionError(f"{' '.join(BG['ver_cmd'])}: exit "
                                 f"{BG['ver_proc'].returncode}\n{out}\n{err}")
        cls.ver = BG["ver"]
        cls.out_ver = os.path.join(t, "report_ver")
        run([BINARY, "report", cls.ver, "--out", cls.out_ver])

    def manifest(self, out):
        with open(os.path.join(out, "manifest.json")) as f:
            return json.load(f)

    def tables(self, out):
        with open(os.path.join(out, "index.html")) as f:
            p = Tables()
            p.feed(f.read())
        return p

    def test_images_and_sections(self):
        """Every image loads; the paper's sections and "not available" are absent; the runs
        table and the histories are there."""
        for out, folder in ((self.out_ver, self.ver), (self.out_two, self.two),
                            (self.out_two1, self.two), (self.out_floor, self.floor)):
            page, p = check_images(self, out)
            man = self.manifest(out)
            self.assertFalse(man["paper_sweep"], out)
            ids = {s["id"] for s in man["sections"]}
            self.assertEqual(set(p.sections), ids, out)
            self.assertFalse(ids & PAPER_IDS, out)
            self.assertIn("runs", ids)
            self.assertIn("histories", ids)
            self.assertNotIn("not-available", page, out)
            self.assertNotIn("Cros", page, out)
            for s in man["sections"]:
                self.assertTrue(s["available"], (out, s["id"]))
                self.assertIsNone(s["error"], (out, s["id"]))
            rows = read_csv(os.path.join(folder, "summary.csv"))
            self.assertEqual([r[0] for r in self.tables(out).tables["tab-runs"]],
                             [r["run_id"] for r in rows])

    def test_histories(self):
        rows = read_csv(os.path.join(self.two, "summary.csv"))
        with_history = [r["run_id"] for r in rows if os.path.isfile(
            os.path.join(self.two, "runs", r["run_id"], "history.csv"))]
        self.assertEqual(len(with_history), 4)  # two runs, two references
        by_id = {s["id"]: s for s in self.manifest(self.out_two)["sections"]}
        self.assertEqual(by_id["histories"]["runs"], with_history)
        self.assertEqual(len(by_id["histories"]["files"]), len(with_history))
        capped = {s["id"]: s for s in self.manifest(self.out_two1)["sections"]}["histories"]
        self.assertEqual(capped["runs"], with_history[:1])
        with open(os.path.join(self.out_two1, "index.html")) as f:
            self.assertIn(f"Only the first 1 of {len(with_history)} runs are drawn",
                          section_html(f.read(), "histories"))

    def test_gates_mapped_to_runs(self):
        rows = [r for r in read_csv(os.path.join(self.two, "summary.csv"))]
        p = self.tables(self.out_two)
        hdr = p.headers["tab-runs"]
        self.assertEqual(hdr[-1], "gates that failed")
        for row in p.tables["tab-runs"]:
            r = next(x for x in rows if x["run_id"] == row[0])
            fails = r["kind"] == "run" and float(r["energy_error_max"]) > self.limit
            self.assertEqual(self.gate_fail in row[-1], fails, row)
        gates = {r[0]: r[1] for r in p.tables["tab-runs_gates"]}
        self.assertEqual(gates, {self.gate_fail: "failed", "two ok runs": "passed"})
        # the verification sweep: one row per JUnit test case, failed ones marked
        root = ET.parse(os.path.join(self.ver, "gates-junit.xml")).getroot()
        cases = {c.get("name"): c.find("failure") is not None for c in root.iter("testcase")}
        pv = self.tables(self.out_ver)
        got = {r[0]: r[1] == "failed" for r in pv.tables["tab-runs_gates"]}
        self.assertEqual(got, cases)

    def test_verification_part_from_the_sweep_itself(self):
        """The verification sweep's own report has its analytic comparisons: one section per
        case that it runs, nothing for the others."""
        cases = {r["case"] for r in read_csv(os.path.join(self.ver, "summary.csv"))}
        spec = {c.case for c in RV.CASES}
        ids = {s["id"] for s in self.manifest(self.out_ver)["sections"]}
        self.assertEqual({i for i in ids if i.startswith("ver_")},
                         {"ver_" + c for c in cases & spec})
        self.assertFalse({i for i in ids if i.startswith("wp_")})  # no reference runs

    def test_work_precision(self):
        rows = read_csv(os.path.join(self.two, "summary.csv"))
        runs = [r for r in rows if r["kind"] == "run"]
        metrics = [c for c in rows[0] if c.startswith("error_")
                   and any(r[c] and float(r[c]) > 0 for r in runs)]
        self.assertIn("error_probe_P", metrics)
        man = {s["id"]: s for s in self.manifest(self.out_two)["sections"]}
        p = self.tables(self.out_two)
        reps = {r["repeats"] for r in runs}
        self.assertEqual(reps, {"2"})
        for m in metrics:
            s = man["wp_" + m]
            drawn = sorted(r["run_id"] for r in runs if float(r[m]) > 0)
            self.assertEqual(sorted(s["runs"]), drawn)
            self.assertEqual(sorted(r[0] for r in p.tables[f"tab-wp_{m}_data"]), drawn)
            svg = os.path.join(self.out_two, f"work_precision_{m}.svg")
            with open(svg) as f:
                text = f.read()
            self.assertIn("time-loop wall time [s] (median of 2 repeats)", text)
            self.assertIn("mesh M1", text)
            self.assertIn("Pareto front", text)
            for r in runs:  # every point's Δt is labelled (no collisions in two points)
                self.assertIn(r["time.dt"].replace("e-0", "e-"), text)

    def test_scheme_limits(self):
        """The two-run sweep has two schemes on M1: one row, explicit penalty against
        semi-explicit, at each scheme's smallest Δt (its reference run), with the P difference
        of the two history.csv files."""
        p = self.tables(self.out_two)
        check_scheme_limits(self, p.tables["tab-scheme_limits"], self.two,
                            ["M1: explicit penalty vs semi-explicit"])
        self.assertEqual(len(p.headers["tab-scheme_limits"]), 10)
        man = {s["id"]: s for s in self.manifest(self.out_two)["sections"]}
        self.assertEqual(man["scheme_limits"]["tables"][0]["rows"],
                         ["M1: explicit penalty vs semi-explicit"])

    def test_floor(self):
        """Points under the reference's uncertainty are flagged, the others are not."""
        rows = [r for r in read_csv(os.path.join(self.floor, "summary.csv"))
                if r["kind"] == "run"]
        p = self.tables(self.out_floor)
        hdr = p.headers["tab-wp_error_probe_P_data"]
        self.assertIn("floor_error_probe_P [m]", hdr)
        note = hdr.index("Pareto")
        below = 0
        for row in p.tables["tab-wp_error_probe_P_data"]:
            r = next(x for x in rows if x["run_id"] == row[0])
            is_below = float(r["error_probe_P"]) < self.floor_value
            below += is_below
            self.assertEqual("below the reference uncertainty" in row[note], is_below, row)
        self.assertGreaterEqual(below, 1)
        with open(os.path.join(self.out_floor, "work_precision_error_probe_P.svg")) as f:
            self.assertIn("reference uncertainty", f.read())

    def test_plot_run(self):
        rid = read_csv(os.path.join(self.two, "summary.csv"))[-1]["run_id"]
        rdir = os.path.join(self.two, "runs", rid)
        p = run([PY, PLOT_RUN, rdir])
        png = os.path.join(rdir, "history.png")
        a = matplotlib.image.imread(png)
        self.assertGreater(min(a.shape[:2]), 100)
        self.assertGreater(float(a.std()), 0.0)
        self.assertIn(png, p.stdout)
        other = os.path.join(BG["tmp"], "elsewhere.png")
        run([PY, PLOT_RUN, rdir, "--out", other])
        self.assertGreater(float(matplotlib.image.imread(other).std()), 0.0)
        # a folder without history.csv: exit 2, one line, nothing written
        for bad in (self.two, os.path.join(BG["tmp"], "no_such_folder")):
            p = run([PY, PLOT_RUN, bad], ok=(2,))
            self.assertEqual(len(p.stderr.strip().splitlines()), 1, p.stderr)
            self.assertIn("history.csv", p.stderr)
            self.assertNotIn("Traceback", p.stderr)
        self.assertFalse(os.path.exists(os.path.join(self.two, "history.png")))

    def test_bad_sweep_folder(self):
        """Not a sweep folder, or a summary.csv that is not a sweep's: exit 2, one line."""
        bad = os.path.join(BG["tmp"], "bad_sweep")
        os.makedirs(bad, exist_ok=True)
        p = run([PY, SCRIPT, bad], ok=(2,))
        self.assertEqual(len(p.stderr.strip().splitlines()), 1, p.stderr)
        with open(os.path.join(bad, "summary.csv"), "w") as f:
            f.write("a,b\n1,2\n")
        p = run([PY, SCRIPT, bad], ok=(2,))
        self.assertEqual(len(p.stderr.strip().splitlines()), 1, p.stderr)
        self.assertIn("run_id", p.stderr)
        p = run([PY, SCRIPT, self.two, "--max-run-plots", "x"], ok=(2,))
        self.assertEqual(len(p.stderr.strip().splitlines()), 1, p.stderr)


class VtuReader(unittest.TestCase):
    """reports/report_io.read_vtu reads every field encoding of docs/outputs.md: the same run
    (the sliding block, 0.1 ms, one snapshot) written in ascii, binary and base64, with and
    without zlib, gives the same arrays, bit for bit."""

    def test_every_encoding_reads_the_same(self):
        sys.path.insert(0, os.path.join(REPO, "reports"))
        from report_io import read_vtu
        case = os.path.join(REPO, "cases", "verification", "sliding_block.toml")
        tmp = tempfile.mkdtemp(prefix="ricochet_vtu_")
        try:
            read = {}
            for fmt, comp in (("ascii", "none"), ("binary", "none"), ("binary", "zlib"),
                              ("base64", "none"), ("base64", "zlib")):
                out = os.path.join(tmp, f"{fmt}_{comp}")
                run([BINARY, "run", case, "--out", out, "--quiet", "--set", "time.end=1e-4",
                     "--set", "output.fields=[1e-4]", "--set", f"output.field_format={fmt}",
                     "--set", f"output.field_compression={comp}"])
                files = [f for f in os.listdir(os.path.join(out, "fields")) if f.endswith(".vtu")]
                self.assertEqual(len(files), 1)
                read[(fmt, comp)] = read_vtu(os.path.join(out, "fields", files[0]))
            ref = read[("ascii", "none")]
            self.assertEqual(ref["cell_data"]["cauchy_stress"].shape, (len(ref["cells"]), 6))
            self.assertEqual(ref["point_data"]["contact_force"].shape, (len(ref["points"]), 3))
            self.assertGreater(ref["point_data"]["contact_status"].max(), 1)
            for key, v in read.items():
                self.assertEqual(v["time"], ref["time"], key)
                self.assertTrue(all((a == b).all() for a, b in zip(v["cells"], ref["cells"])), key)
                self.assertTrue((v["points"] == ref["points"]).all(), key)
                for section in ("point_data", "cell_data"):
                    self.assertEqual(sorted(v[section]), sorted(ref[section]), key)
                    for name, a in v[section].items():
                        self.assertTrue((a.view("u8") == ref[section][name].view("u8")).all(),
                                        f"{key} {name}")
        finally:
            shutil.rmtree(tmp, ignore_errors=True)

def main():
    global BINARY
    args = sys.argv[1:]
    BINARY = (args.pop(0) if args and not args[0].startswith("-") else None) or \
        os.environ.get("RICOCHET_BINARY") or os.path.join(REPO, "build", "ricochet")
    if not os.access(BINARY, os.X_OK):
        print(f"test_report: ricochet binary '{BINARY}' not found or not executable",
              file=sys.stderr)
        return 1
    prog = unittest.main(argv=[sys.argv[0]] + args, exit=False, verbosity=2)
    return 0 if prog.result.wasSuccessful() else 1


if __name__ == "__main__":
    sys.exit(main())
