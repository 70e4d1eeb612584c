#!/usr/bin/python3
"""The repository stands on its own: no tracked text file may point at notes that live outside
it. Fails, naming file:line, on any of PATTERNS below (spelled out in PATTERNS only, so that
this file does not match itself):

- the word "literature" followed by a section sign, or the file name literature + ".md" (the
  old external literature notes; their content is now in docs/background.md);
- a "shared/" path that leaves the repository: shared/ + "paper" or "literature" + ".md",
  ".." + "/shared", or the machine's shared-notes folder;
- any absolute path under the machine's work folder (a path on one machine only).

In-repository paths that merely contain "shared/" (e.g. ci/gates/shared/ as a temporary
directory in tests/harness/gates/test_gates.cpp) are not flagged: only the patterns below are.

The files are those `git ls-files` lists from the repository root; without git, the tree is
walked, skipping .git/, build*/, results/ and bench-results/. Binary files are skipped.
Run: /usr/bin/python3 tests/repo/test_self_contained.py (registered with CTest as
self_contained_py)."""

import os
import re
import subprocess
import sys
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))

# Written with character classes so that this file does not match itself.
PATTERNS = [
    ("external literature notes", re.compile(r"literature[ ]\u00a7|literature[.]md")),
    ("external shared notes", re.compile(r"(?:^|[^\w.-])shared/(?:paper|literature)[.]md")),
    ("path to a shared folder outside the repository",
     re.compile(r"[.][.]/shared\b|/wor[k]/shared\b")),
    ("absolute path on one machine", re.compile(r"/wor[k]/")),
]

SKIP_DIRS = {".git", "results", "bench-results", "__pycache__"}


def tracked_files(root):
    """Paths relative to root: git's list when available, else a walk of the tree."""
    try:
        out = subprocess.run(["git", "-C", root, "ls-files", "-z"], capture_output=True,
                             check=True).stdout
        files = [f for f in out.decode("utf-8", "surrogateescape").split("\0") if f]
        if files:
            return files
    except (OSError, subprocess.CalledProcessError):
        pass
    files = []
    for dirpath, dirnames, filenames in os.walk(root):
        dirnames[:] = sorted(d for d in dirnames
                             if d not in SKIP_DIRS and not d.startswith("build"))
        for name in sorted(filenames):
            files.append(os.path.relpath(os.path.join(dirpath, name), root))
    return files


def read_text(path):
    """The file's text, or None for a binary or unreadable file."""
    try:
        with open(path, "rb") as f:
            data = f.read()
    except OSError:
        return None
    if b"\0" in data:
        return None
    return data.decode("utf-8", "replace")


def offences(root, files):
    """(file, line number, what, line) for every match of PATTERNS."""
    found = []
    for rel in files:
        text = read_text(os.path.join(root, rel))
        if text is None:
            continue
        for number, line in enumerate(text.splitlines(), 1):
            for what, pattern in PATTERNS:
                if pattern.search(line):
                    found.append((rel, number, what, line.strip()))
    return found


class SelfContained(unittest.TestCase):
    def test_no_reference_leaves_the_repository(self):
        files = tracked_files(ROOT)
        self.assertGreater(len(files), 10, "no files found under " + ROOT)
        found = offences(ROOT, files)
        report = "\n".join("%s:%d: %s: %s" % f for f in found)
        self.assertEqual(found, [], "references to files outside the repository "
                         "(point them at docs/background.md instead):\n" + report)

    def test_patterns_catch_what_they_should(self):
        def hits(line):
            return [what for what, p in PATTERNS if p.search(line)]
        w = "/wo" + "rk/"
        bad = ["see literature " + "\u00a72.3", "(full text: shared/" + "paper.md)",
               "literature" + ".md 1.2", ".." + "/shared/notes.txt", w + "shared/x",
               w + "main/build", "derived in shared/" + "literature" + ".md"]
        for line in bad:
            self.assertTrue(hits(line), line)
        good = ['dir.write("ci/gates/shared/common.toml",', 'include = ["shared/energy.toml"]',
                "docs/background.md, Critical time step", "the literature's estimate",
                "the work/energy balance", "shared/rows.toml"]
        for line in good:
            self.assertEqual(hits(line), [], line)


if __name__ == "__main__":
    unittest.main(verbosity=2)
