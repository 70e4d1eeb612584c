#!/usr/bin/python3
"""The report's generic code and the command line know no study (docs/studies.md: "Nothing
about a study is written anywhere else"). Fails, naming file:line, where a shipped study's
name appears as an identifier in reports/*.py, harness/cli/* or the CI scripts ci/test and
ci/reproduce: the folder names of cases/*/study.toml (and `table1`, the paper's sweep), as a
word when they hold an underscore (kim_kwak, three_d, also spelt with a hyphen), and for
one-word names (paper, accuracy, ...) where they name something: in quotes, in a path, as an
option, or joined to another word by an underscore. English prose ("the paper's Table 1")
is not flagged.

Run: /usr/bin/python3 tests/repo/test_no_study_names.py (registered with CTest as
no_study_names_py)."""

import glob
import os
import re
import sys
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
# ci/test and ci/reproduce are listed in CI_FILES: they are checked once they call
# `ricochet reproduce` (CHECK_CI below); until then they still name the studies' sweeps.
CHECK_CI = True
CI_FILES = ["ci/test", "ci/reproduce"]


def study_names():
    names = sorted(os.path.basename(os.path.dirname(p))
                   for p in glob.glob(os.path.join(ROOT, "cases", "*", "study.toml")))
    return names + ["table1"]


def patterns(names):
    out = []
    for n in names:
        if "_" in n or any(c.isdigit() for c in n):
            for spelling in {n, n.replace("_", "-")}:
                out.append((n, re.compile(r"(?i)(?<![A-Za-z0-9])" + re.escape(spelling)
                                          + r"(?![A-Za-z0-9])")))
        else:
            w = re.escape(n)
            out.append((n, re.compile(
                r"(?i)[\"'/]" + w + r"[\"'/.]|--" + w + r"(?![A-Za-z0-9])|(?<![A-Za-z0-9])" + w
                + r"_|_" + w + r"(?![A-Za-z0-9])")))
    return out


def files():
    fs = sorted(glob.glob(os.path.join(ROOT, "reports", "*.py")))
    fs += sorted(p for p in glob.glob(os.path.join(ROOT, "harness", "cli", "*")) if os.path.isfile(p))
    if CHECK_CI:
        fs += [os.path.join(ROOT, p) for p in CI_FILES if os.path.isfile(os.path.join(ROOT, p))]
    return fs


def findings():
    pats = patterns(study_names())
    out = []
    for path in files():
        with open(path, encoding="utf-8", errors="replace") as f:
            for k, line in enumerate(f, 1):
                for name, p in pats:
                    m = p.search(line)
                    if m:
                        out.append(f"{os.path.relpath(path, ROOT)}:{k}: study name "
                                   f"'{name}' ({m.group(0)!r}): {line.strip()[:120]}")
    return out


class NoStudyNames(unittest.TestCase):
    def test_studies_found(self):
        self.assertIn("table1", study_names())
        self.assertGreater(len(study_names()), 5)

    def test_patterns(self):
        pats = patterns(["paper", "kim_kwak", "table1"])
        hit = lambda s: any(p.search(s) for _, p in pats)  # noqa: E731
        for bad in ('x = "paper"', "cases/paper/x.toml", "--kim-kwak", "import report_kim_kwak",
                    "is_paper_sweep", "sec_table1", "--paper"):
            self.assertTrue(hit(bad), bad)
        for fine in ("the paper's Table 1", "a paper", "kimkwak", "Table 1"):
            self.assertFalse(hit(fine), fine)

    def test_generic_code_names_no_study(self):
        bad = findings()
        self.assertEqual(bad, [], "\n" + "\n".join(bad))


if __name__ == "__main__":
    unittest.main(argv=[sys.argv[0]] + sys.argv[1:], verbosity=1)
