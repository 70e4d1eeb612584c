#!/usr/bin/python3
"""Smoke test of the report (reports/make_report.py, docs/report.md and docs/studies.md, The
layout), registered with CTest as report_smoke.

Builds, in a temporary folder:
  * a tiny real sweep with the given ricochet binary (the oblique plate on a 4 x 8 mesh for
    0.5 ms, two schemes x two steps, two field snapshots; about 2 s), checked by a gates file
    with one gate that passes and one that fails;
  * a synthetic sweep of two swept keys (scheme x time.dt) and a synthetic stability search
    (summary.csv row of kind "stability" and its stability.json);
  * a study folder (study.toml with a layout using every kind, a plug-in report.py) and its
    output folder with a hand-written study.json, as `ricochet reproduce` writes them.
Then checks:
  * the default page of the 2-key sweep: the table has both key columns, one figure per key,
    and nothing of any study;
  * each data kind (runs_table with the gated columns' verdicts, metric, work_precision,
    histories, fields, stability) and the plug-in's section on the study page; a sweep not run
    in the tier gives a note, not an error;
  * layout errors: one line naming the study.toml and the key, exit 2, for an unknown kind, an
    unknown key, a sweep the study does not have, a plug-in function that does not exist;
  * the index of a folder of studies (a row per study, its link, gates counts, status), also
    through `ricochet report OUT`;
  * every shipped study.toml's layout is valid and its plug-in has the functions it names;
  * reports/plot_run.py on one run, and on a folder without history.csv (exit 2);
  * the VTU reader on every field encoding.

    /usr/bin/python3 tests/reports/test_report.py [RICOCHET_BINARY]     (or env RICOCHET_BINARY)
"""

import csv
import glob
import html.parser
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

import matplotlib

matplotlib.use("Agg")
import matplotlib.image  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.normpath(os.path.join(HERE, "..", ".."))
SCRIPT = os.path.join(REPO, "reports", "make_report.py")
PLOT_RUN = os.path.join(REPO, "reports", "plot_run.py")
PY = "/usr/bin/python3"
CALL_TIMEOUT = 120
BINARY = None
TMP = None

TINY_SWEEP = """
name = "tiny"
description = "report smoke test: the oblique plate, coarse, 0.5 ms"
base = "{base}"
set = {{ mesh = "M1", "meshes.M1.nx" = 4, "meshes.M1.ny" = 8, "obstacles[0].friction" = 0.1, "time.end" = 5e-4, "output.interval" = 2.5e-5, "output.fields" = [2.5e-4, 5e-4] }}

[[group]]
name = "runs"
cross = {{ scheme = ["semi_explicit", "implicit"], "time.dt" = [1e-5, 5e-6] }}
"""

GATES = """
name = "tiny"

[[gate]]
name = "energy error below 50 %"
kind = "max"
column = "energy_error_max"
limit = 0.5

[[gate]]
name = "penetration below 1e-30 (fails)"
kind = "max"
column = "penetration_max"
limit = 1e-30
where = { scheme = "explicit_penalty" }
allow_empty = true

[[gate]]
name = "wall time below an hour"
kind = "max"
column = "wall_seconds"
limit = 3600
"""

PLUGIN = '''
"""A test plug-in: one table of its sweep's run ids and one note."""
from report_page import Section, note


def ids(ctx, section):
    s = Section("plugin_ids", "Run ids", "table")
    sw = ctx.sweep(section["sweep"])
    s.header = ["run"]
    s.rows = [[f"`{r.id}`"] for r in sw.runs]
    s.caption = "args: " + repr(section.get("args", {}))
    return [s, note("plugin_note", "tier " + ctx.tier)]
'''

LAYOUT = """
title = "Test study"
summary = "A study of the report smoke test."
order = 5

[[sweep]]
name = "tiny"
file = "tiny.toml"
gates = "gates.toml"

[[sweep]]
name = "two"
file = "two.toml"

[[sweep]]
name = "later"
file = "later.toml"
tier = ["full"]

[report]
plugin = "report.py"

[[report.section]]
kind = "runs_table"
sweep = "tiny"
columns = ["energy_error_max"]
title = "Runs"
text = "Every run with its gates."

[[report.section]]
kind = "metric"
sweep = "two"
x = "time.dt"
y = "energy_error_max"
by = "scheme"
logx = true
logy = true
title = "Metric"

[[report.section]]
kind = "work_precision"
sweep = "two"
error = "energy_error_max"
cost = "wall_seconds"
by = "scheme"

[[report.section]]
kind = "histories"
sweep = "tiny"
y = ["kinetic_energy", "energy_error"]
where = { scheme = "semi_explicit" }
title = "Histories"

[[report.section]]
kind = "fields"
sweep = "tiny"
field = "von_mises"
title = "Fields"

[[report.section]]
kind = "stability"
sweep = "two"
title = "Stability"

[[report.section]]
kind = "plugin"
name = "ids"
sweep = "tiny"
args = { answer = 42 }
title = "Plug-in"

[[report.section]]
kind = "runs_table"
sweep = "later"
title = "Later"
"""


def run(cmd, ok=(0,), **kw):
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=CALL_TIMEOUT, **kw)
    if p.returncode not in ok:
        raise AssertionError(f"{' '.join(cmd)}: exit {p.returncode}\n{p.stdout}\n{p.stderr}")
    return p


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def write(path, text):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        f.write(text)
    return path


def two_key_sweep(d):
    """A synthetic sweep (docs/sweeps.md, Outputs): scheme x time.dt, a history per run, and one
    stability search with its stability.json."""
    rows, runs = [], []
    for scheme in ("semi_explicit", "implicit"):
        for dt in (1e-4, 1e-5, 1e-6):
            rid = f"{scheme}/{len(rows):02d}-time.dt={dt:g}"
            e = (0.02 if scheme == "semi_explicit" else 0.01) * dt / 1e-4
            rows.append({"run_id": rid, "group": scheme, "kind": "run", "status": "ok",
                         "reason": "", "scheme": scheme, "time.dt": dt, "dt": dt, "mesh": "M1",
                         "energy_error_max": e, "wall_seconds": 1e-6 / dt,
                         "penetration_max": 1e-9})
            runs.append({"id": rid, "group": scheme, "kind": "run", "swept": ["scheme", "time.dt"],
                         "overrides": [f"scheme={scheme}", f"time.dt={dt}"]})
            t = [k * 1e-4 for k in range(20)]
            write(os.path.join(d, "runs", rid, "history.csv"),
                  "time,kinetic_energy,energy_error\n" +
                  "".join(f"{x},{math.exp(-x * 1e3)},{e * k / 20}\n" for k, x in enumerate(t)))
    rid = "search/06-mesh=M1"
    rows.append({"run_id": rid, "group": "search", "kind": "stability", "status": "ok",
                 "reason": "", "scheme": "semi_explicit", "time.dt": "", "dt": "", "mesh": "M1",
                 "energy_error_max": "", "wall_seconds": "", "penetration_max": ""})
    runs.append({"id": rid, "group": "search", "kind": "stability", "swept": [], "overrides": []})
    write(os.path.join(d, "runs", rid, "stability.json"), json.dumps({
        "mesh": "M1", "scheme": "semi_explicit", "estimate": 2e-6, "largest_stable_dt": 1.9e-6,
        "smallest_unstable_dt": 2.1e-6, "outcome": "bracketed", "bracket_width": 0.1,
        "search": {"cap": 1e-3}, "criterion": {"energy_error_max_bound": 0.1}, "runs": 7,
        "trials": [{"dt": 2.1e-6, "stable": False, "reason": "diverged: energy growth"}]}))
    with open(os.path.join(d, "summary.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    write(os.path.join(d, "sweep.json"), json.dumps({"sweep": "two", "runs": runs}))


class Page(html.parser.HTMLParser):
    """The parts of an index.html the tests read: images, table headers, ids, classes."""

    def __init__(self, path):
        super().__init__()
        self.imgs, self.th, self.ids, self.tds = [], [], set(), []
        self._th = None
        with open(path) as f:
            self.text = f.read()
        self.feed(self.text)

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "img":
            self.imgs.append(a.get("src"))
        if "id" in a:
            self.ids.add(a["id"])
        if tag == "th":
            self._th = ""
        if tag == "td":
            self.tds.append(a.get("class", ""))

    def handle_data(self, data):
        if self._th is not None:
            self._th += data

    def handle_endtag(self, tag):
        if tag == "th" and self._th is not None:
            self.th.append(self._th)
            self._th = None


def manifest(out):
    with open(os.path.join(out, "manifest.json")) as f:
        return json.load(f)


def images_load(test, out):
    page = Page(os.path.join(out, "index.html"))
    for src in page.imgs:
        a = matplotlib.image.imread(os.path.join(out, src))
        test.assertGreater(float(a.std()), 0.0, src)
    return page


def setUpModule():
    global TMP
    TMP = tempfile.mkdtemp(prefix="ricochet_report_")
    study = os.path.join(TMP, "cases", "teststudy")
    write(os.path.join(study, "tiny.toml"),
          TINY_SWEEP.format(base=os.path.join(REPO, "cases", "oblique_plate.toml")))
    write(os.path.join(study, "gates.toml"), GATES)
    write(os.path.join(study, "study.toml"), LAYOUT)
    write(os.path.join(study, "report.py"), PLUGIN)
    out = os.path.join(TMP, "out", "teststudy")
    run([BINARY, "sweep", os.path.join(study, "tiny.toml"), "--out", os.path.join(out, "tiny"),
         "--quiet", "--check", os.path.join(study, "gates.toml")], ok=(0, 4))
    two_key_sweep(os.path.join(out, "two"))
    first = read_csv(os.path.join(out, "tiny", "summary.csv"))[0]["run_id"]
    write(os.path.join(out, "study.json"), json.dumps({
        "study": "teststudy", "title": "Test study", "summary": "A study of the smoke test.",
        "folder": study, "tier": "fast", "status": "gates failed",
        "sweeps": [{"name": "tiny", "dir": "tiny", "gates": os.path.join(study, "gates.toml"),
                    "runs": 4, "reused": 0, "run_now": 4, "failed": 0, "seconds": 2.0,
                    "gate_results": [{"name": "energy error below 50 %", "passed": True, "detail": ""},
                              {"name": "wall time below an hour", "passed": False,
                               "detail": f"run {first}: too slow"}]},
                   {"name": "two", "dir": "two", "runs": 7, "reused": 7, "run_now": 0,
                    "failed": 0, "seconds": 0.1, "gate_results": []}]}))
    # a second study with no layout: the default page
    other = os.path.join(TMP, "cases", "plain")
    write(os.path.join(other, "study.toml"),
          'title = "Plain"\nsummary = "No layout."\norder = 1\n[[sweep]]\nname = "two"\n'
          'file = "two.toml"\n')
    two_key_sweep(os.path.join(TMP, "out", "plain", "two"))
    write(os.path.join(TMP, "out", "plain", "study.json"), json.dumps({
        "study": "plain", "title": "Plain", "summary": "No layout.", "folder": other,
        "tier": "fast", "status": "passed",
        "sweeps": [{"name": "two", "runs": 7, "reused": 0, "run_now": 7, "failed": 0,
                    "gate_results": [{"name": "g", "passed": True}]}]}))


def tearDownModule():
    shutil.rmtree(TMP, ignore_errors=True)


class DefaultPage(unittest.TestCase):
    """A plain sweep: the runs table from its swept keys and one figure per key, nothing else."""

    def test_two_key_sweep(self):
        sw = os.path.join(TMP, "default_two")
        two_key_sweep(sw)
        p = run([PY, SCRIPT, sw])
        out = os.path.join(sw, "report")
        self.assertIn("index.html", p.stdout)
        page = images_load(self, out)
        self.assertIn("scheme", page.th)
        self.assertIn("time.dt", page.th)
        man = manifest(out)
        figs = [s for s in man["sections"] if s["kind"] == "figure"]
        tabs = [s for s in man["sections"] if s["kind"] == "table"]
        self.assertEqual(len(figs), 2, figs)
        self.assertEqual(len(tabs), 1)
        self.assertEqual(len(page.imgs), 2)
        self.assertTrue(all(s["available"] for s in man["sections"]), man["sections"])
        # only this sweep's sections: the runs table and the two metric figures
        self.assertEqual([s["id"] for s in man["sections"]],
                         ["two_runs", "two_metric_0", "two_metric_1"])
        self.assertEqual(len(tabs[0]["tables"][0]["rows"]), 6)   # the search is not a run

    def test_bad_input(self):
        bad = os.path.join(TMP, "bad_sweep")
        os.makedirs(bad, exist_ok=True)
        for args in ([bad], [os.path.join(TMP, "no_such")], ["--index", bad, bad]):
            p = run([PY, SCRIPT] + args, ok=(2,))
            self.assertEqual(len(p.stderr.strip().splitlines()), 1, p.stderr)
            self.assertNotIn("Traceback", p.stderr)


class StudyPage(unittest.TestCase):
    """Every kind of a layout, and a plug-in, on the test study's page."""

    @classmethod
    def setUpClass(cls):
        cls.study_out = os.path.join(TMP, "out", "teststudy")
        cls.p = run([PY, SCRIPT, "--study", cls.study_out])
        cls.out = os.path.join(cls.study_out, "report")
        cls.man = manifest(cls.out)
        cls.by_part = {}
        for s in cls.man["sections"]:
            cls.by_part.setdefault(s["part"], []).append(s)

    def test_every_section_available(self):
        bad = [s for s in self.man["sections"] if s["kind"] != "note" and not s["available"]]
        self.assertEqual(bad, [])
        images_load(self, self.out)
        self.assertEqual(self.man["tier"], "fast")

    def test_runs_table_gated_columns(self):
        s = self.by_part["Runs"][0]
        runs = read_csv(os.path.join(self.study_out, "tiny", "summary.csv"))
        self.assertEqual(s["tables"][0]["rows"], [r["run_id"] for r in runs])
        page = Page(os.path.join(self.out, "index.html"))
        for head in ("scheme", "time.dt", "energy_error_max", "wall_seconds (gated)"):
            self.assertIn(head, page.th)
        # a gate with no verdict in study.json (and no run it selects) marks no column
        self.assertNotIn("penetration_max (gated)", page.th)
        with open(os.path.join(self.out, "report.md")) as f:
            md = f.read()
        self.assertIn("✓", md)
        self.assertIn("✗ wall time below an hour", md)   # the failed gate names this run
        self.assertEqual(md.count("✗ wall time below an hour"), 1)

    def test_figures(self):
        for part in ("Metric", "Histories", "Fields"):
            s = self.by_part[part][0]
            self.assertEqual(s["kind"], "figure")
            self.assertTrue(s["files"], part)
        wp = [s for s in self.by_part["Metric"] if s["title"].startswith("Work-precision")]
        self.assertEqual(len(wp), 1)
        self.assertEqual(len(self.by_part["Histories"][0]["runs"]), 2)   # where: semi-explicit

    def test_stability_and_plugin(self):
        st = self.by_part["Stability"][0]
        self.assertEqual(st["tables"][0]["rows"], ["M1 semi-explicit"])
        plug = self.by_part["Plug-in"]
        self.assertEqual([s["id"] for s in plug], ["plugin_ids", "plugin_note"])
        self.assertEqual(plug[1]["text"], "tier fast")
        self.assertEqual(len(plug[0]["tables"][0]["rows"]), 4)

    def test_not_run_in_this_tier(self):
        later = self.by_part["Later"]
        self.assertEqual([s["kind"] for s in later], ["note"])
        self.assertIn("not run in this tier", later[0]["text"])
        self.assertIn("full tier", later[0]["text"])


class LayoutErrors(unittest.TestCase):
    """A bad layout: one line naming the study.toml and the key, exit 2, no traceback."""

    def check(self, extra, key):
        study = os.path.join(TMP, "cases", "bad")
        shutil.rmtree(study, ignore_errors=True)
        write(os.path.join(study, "report.py"), PLUGIN)
        toml = write(os.path.join(study, "study.toml"),
                     'title = "Bad"\nsummary = "x"\n[[sweep]]\nname = "two"\nfile = "t.toml"\n'
                     + extra)
        out = os.path.join(TMP, "out_bad", "bad")
        two_key_sweep(os.path.join(out, "two"))
        write(os.path.join(out, "study.json"), json.dumps({"study": "bad", "folder": study}))
        p = run([PY, SCRIPT, "--study", out], ok=(2,))
        lines = p.stderr.strip().splitlines()
        self.assertEqual(len(lines), 1, p.stderr)
        self.assertIn(toml, lines[0])
        self.assertIn(key, lines[0])

    def test_errors(self):
        sec = '[report]\nplugin = "report.py"\n[[report.section]]\n'
        self.check(sec + 'kind = "pie"\nsweep = "two"\n', "report.section[0].kind")
        self.check(sec + 'kind = "metric"\nsweep = "two"\nx = "a"\ny = "b"\ncolour = "red"\n',
                   "report.section[0].colour")
        self.check(sec + 'kind = "runs_table"\nsweep = "nope"\n', "report.section[0].sweep")
        self.check(sec + 'kind = "metric"\nsweep = "two"\nx = "a"\n', "report.section[0].y")
        self.check(sec + 'kind = "plugin"\nname = "absent"\n', "report.section[0].name")
        self.check(sec + 'kind = "runs_table"\nsweep = "two"\nlogx = 1\n',
                   "report.section[0].logx")
        self.check('[report]\nplugins = "x.py"\n', "report.plugins")


class Index(unittest.TestCase):
    def test_folder_of_studies(self):
        out = os.path.join(TMP, "out")
        p = run([BINARY, "report", out])
        self.assertIn("2 studies", p.stdout)
        page = Page(os.path.join(out, "index.html"))
        self.assertIn("study-teststudy", page.ids)
        self.assertIn("study-plain", page.ids)
        self.assertLess(page.text.index("study-plain"), page.text.index("study-teststudy"))
        self.assertIn('href="teststudy/report/index.html"', page.text)
        self.assertIn('<td class="bad">gates failed</td>', page.text)
        self.assertIn('<td class="ok">passed</td>', page.text)
        for d in ("teststudy", "plain"):
            self.assertTrue(os.path.isfile(os.path.join(out, d, "report", "index.html")))
        # the study without a layout: the default page of its sweep
        man = manifest(os.path.join(out, "plain", "report"))
        self.assertEqual(sum(s["kind"] == "figure" for s in man["sections"]), 2)
        # --index alone writes only the index
        run([PY, SCRIPT, "--index", out])


class ShippedLayouts(unittest.TestCase):
    """Every cases/*/study.toml layout is valid, with the plug-in functions it names."""

    def test_layouts(self):
        sys.path.insert(0, os.path.join(REPO, "reports"))
        from report_layout import check_layout, read_study_toml
        from report_study import load_plugin
        paths = sorted(glob.glob(os.path.join(REPO, "cases", "*", "study.toml")))
        self.assertGreater(len(paths), 5)
        for path in paths:
            toml = read_study_toml(path)
            layout = check_layout(path, toml)
            if layout and layout["plugin"]:
                mod = load_plugin(os.path.dirname(path), layout["plugin"])
                check_layout(path, toml, {n for n in dir(mod) if callable(getattr(mod, n))})


class PlotRun(unittest.TestCase):
    def test_plot_run(self):
        rid = read_csv(os.path.join(TMP, "out", "teststudy", "tiny", "summary.csv"))[0]["run_id"]
        rdir = os.path.join(TMP, "out", "teststudy", "tiny", "runs", rid)
        p = run([PY, PLOT_RUN, rdir])
        png = os.path.join(rdir, "history.png")
        self.assertIn(png, p.stdout)
        self.assertGreater(float(matplotlib.image.imread(png).std()), 0.0)
        p = run([PY, PLOT_RUN, os.path.join(TMP, "no_such_folder")], ok=(2,))
        self.assertEqual(len(p.stderr.strip().splitlines()), 1, p.stderr)
        self.assertIn("history.csv", p.stderr)


class VtuReader(unittest.TestCase):
    """reports/report_io.read_vtu reads every field encoding of docs/outputs.md: the same run
    (the sliding block, 0.1 ms, one snapshot) written in ascii, binary and base64, with and
    without zlib, gives the same arrays, bit for bit."""

    def test_every_encoding_reads_the_same(self):
        sys.path.insert(0, os.path.join(REPO, "reports"))
        from report_io import read_vtu
        case = os.path.join(REPO, "cases", "verification", "sliding_block.toml")
        read = {}
        for fmt, comp in (("ascii", "none"), ("binary", "none"), ("binary", "zlib"),
                          ("base64", "none"), ("base64", "zlib")):
            out = os.path.join(TMP, "vtu", f"{fmt}_{comp}")
            run([BINARY, "run", case, "--out", out, "--quiet", "--set", "time.end=1e-4",
                 "--set", "output.fields=[1e-4]", "--set", f"output.field_format={fmt}",
                 "--set", f"output.field_compression={comp}"])
            files = [f for f in os.listdir(os.path.join(out, "fields")) if f.endswith(".vtu")]
            self.assertEqual(len(files), 1)
            read[(fmt, comp)] = read_vtu(os.path.join(out, "fields", files[0]))
        ref = read[("ascii", "none")]
        self.assertEqual(ref["cell_data"]["cauchy_stress"].shape, (len(ref["cells"]), 6))
        for key, v in read.items():
            self.assertEqual(v["time"], ref["time"], key)
            self.assertTrue((v["points"] == ref["points"]).all(), key)
            for section in ("point_data", "cell_data"):
                self.assertEqual(sorted(v[section]), sorted(ref[section]), key)
                for name, a in v[section].items():
                    self.assertTrue((a.view("u8") == ref[section][name].view("u8")).all(),
                                    f"{key} {name}")


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
