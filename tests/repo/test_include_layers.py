#!/usr/bin/python3
"""The solver's folders form layers: no include cycle between them, and no solver file includes
anything of the harness (docs/architecture.md, "Folders and layers").

    tests/repo/test_include_layers.py [SOURCE_ROOT]

Reads every `#include "solver/..."` and `#include "harness/..."` of the C++ files below
SOURCE_ROOT/solver (default: the checkout this file is in), makes the graph of solver folders
(solver/contact -> solver/model when a file of contact includes one of model), and fails on:
  - a cycle in that graph (each strongly connected set of folders is named, with one include
    per edge of it: file, line and the included file), and
  - a solver file that includes a harness file.
The tests below run the check on the checkout, and on a copy of a small tree in which a cycle
and a harness include were planted, to show that the check fails on them.
"""
import pathlib
import re
import sys
import tempfile
import unittest

INCLUDE = re.compile(r'^\s*#\s*include\s+"((solver|harness)/[^"]+)"')
SOURCE_SUFFIXES = {".hpp", ".cpp", ".h", ".cc", ".inl"}


def folder_of(path):
    """The solver folder of a path relative to the source root: solver/contact/x.hpp -> solver/contact."""
    parts = pathlib.PurePosixPath(path).parts
    return "/".join(parts[:2]) if len(parts) > 2 else parts[0]


def read_includes(root):
    """[(file, line number, included path)] of every solver source file below root/solver."""
    out = []
    for f in sorted((root / "solver").rglob("*")):
        if f.suffix not in SOURCE_SUFFIXES or not f.is_file():
            continue
        rel = f.relative_to(root).as_posix()
        for n, line in enumerate(f.read_text(errors="replace").splitlines(), 1):
            m = INCLUDE.match(line)
            if m:
                out.append((rel, n, m.group(1)))
    return out


def strongly_connected(graph):
    """Tarjan's strongly connected components of {node: set(nodes)}, each as a sorted list."""
    index, low, on_stack, stack, comps = {}, {}, set(), [], []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            comps.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return comps


def problems(root):
    """The layer violations below root, one line each (empty: none)."""
    root = pathlib.Path(root)
    includes = read_includes(root)
    out = []
    graph, witness = {}, {}
    for f, n, inc in includes:
        if inc.startswith("harness/"):
            out.append(f"{f}:{n}: the solver includes the harness: \"{inc}\"")
            continue
        a, b = folder_of(f), folder_of(inc)
        if a == b:
            continue
        graph.setdefault(a, set()).add(b)
        graph.setdefault(b, set())
        witness.setdefault((a, b), f"{f}:{n} includes \"{inc}\"")
    for comp in strongly_connected(graph):
        if len(comp) < 2:
            continue
        edges = [f"{witness[(a, b)]}" for a in comp for b in sorted(graph[a]) if b in comp]
        out.append("include cycle between " + ", ".join(comp) + ": " + "; ".join(edges))
    return out


class Layers(unittest.TestCase):
    # The repository root: the first folder above this file with solver/ and tests/ (tests/ itself
    # has a solver/ folder, the solver's tests).
    ROOT = next(p for p in pathlib.Path(__file__).resolve().parents
                if (p / "solver").is_dir() and (p / "tests").is_dir())

    def test_checkout_has_no_cycle_and_no_harness_include(self):
        self.assertEqual(problems(self.ROOT), [])
        self.assertGreater(len(read_includes(self.ROOT)), 50, "the check read the solver's includes")

    def plant(self, files):
        tmp = tempfile.TemporaryDirectory()
        self.addCleanup(tmp.cleanup)
        root = pathlib.Path(tmp.name)
        for name, text in files.items():
            (root / name).parent.mkdir(parents=True, exist_ok=True)
            (root / name).write_text(text)
        return root

    def test_fails_on_a_planted_cycle(self):
        root = self.plant({
            "solver/core/state.hpp": '#pragma once\n#include "solver/core/types.hpp"\n',
            "solver/core/types.hpp": "#pragma once\n",
            "solver/model/model.hpp": '#pragma once\n#include "solver/core/types.hpp"\n',
            "solver/contact/set.hpp": '#pragma once\n#include "solver/model/model.hpp"\n',
            "solver/schemes/step.cpp": '#include "solver/contact/set.hpp"\n',
            # the planted cycle: model -> schemes -> contact -> model
            "solver/model/extra.cpp": '#include "solver/model/model.hpp"\n  #  include "solver/schemes/step.hpp"\n',
            "solver/schemes/step.hpp": "#pragma once\n",
        })
        found = problems(root)
        self.assertEqual(len(found), 1, found)
        self.assertIn("include cycle between solver/contact, solver/model, solver/schemes", found[0])
        self.assertIn("solver/model/extra.cpp:2", found[0])

    def test_fails_on_a_harness_include(self):
        root = self.plant({
            "solver/core/types.hpp": "#pragma once\n",
            "solver/schemes/run.cpp": '#include "solver/core/types.hpp"\n#include "harness/input/case.hpp"\n',
        })
        self.assertEqual(problems(root), ['solver/schemes/run.cpp:2: the solver includes the harness: "harness/input/case.hpp"'])

    def test_a_tree_without_cycles_passes(self):
        root = self.plant({
            "solver/core/types.hpp": "#pragma once\n",
            "solver/model/model.hpp": '#pragma once\n#include "solver/core/types.hpp"\n',
            "solver/schemes/step.cpp": '#include "solver/model/model.hpp"\n#include "solver/core/types.hpp"\n',
        })
        self.assertEqual(problems(root), [])


if __name__ == "__main__":
    if len(sys.argv) > 1 and not sys.argv[1].startswith("-"):
        found = problems(sys.argv[1])
        print("\n".join(found) if found else "no include cycle between solver folders, no harness include")
        sys.exit(1 if found else 0)
    unittest.main()
