"""A sweep's gates for the runs table (docs/gates.md): which summary.csv columns are gated, by
which gates, and each gate's verdict. The definitions come from the gates file (with its
`include`s); the verdicts from study.json (what `ricochet reproduce` checked) or else the
sweep's gates-junit.xml (`ricochet sweep --check`)."""

import os
import tomllib

import report_generic as RG
from report_select import matches


def read_gate_defs(path, seen=None):
    """[gate table] of a gates file, its includes first (docs/gates.md, `include`); [] when the
    file cannot be read (the verdicts are still shown, the columns are not marked)."""
    seen = set() if seen is None else seen
    path = os.path.abspath(path)
    if path in seen:
        return []
    seen.add(path)
    try:
        with open(path, "rb") as f:
            d = tomllib.load(f)
    except (OSError, tomllib.TOMLDecodeError):
        return []
    out = []
    inc = d.get("include", [])
    for p in [inc] if isinstance(inc, str) else inc:
        out += read_gate_defs(os.path.join(os.path.dirname(path), p), seen)
    out += [g for g in d.get("gate", []) if isinstance(g, dict)]
    return out


def verdicts(sweep_dir, run_ids, entry):
    """{gate name: {"passed": bool, "detail": text, "runs": [run ids named]}} from the
    study.json entry of the sweep (its `gate_results`), else gates-junit.xml; {} without either."""
    out = {}
    for g in (entry or {}).get("gate_results", []) or []:
        if isinstance(g, dict) and "name" in g:
            out[g["name"]] = {"passed": bool(g.get("passed")), "detail": str(g.get("detail", "")),
                              "runs": [r for r in run_ids if r in str(g.get("detail", ""))]}
    if out:
        return out
    j = RG.read_gates(sweep_dir, run_ids)
    for c in (j or {}).get("cases", []):
        out[c["name"]] = {"passed": not c["failed"], "detail": c["text"], "runs": c["runs"]}
    return out


def _selected(run, g):
    """Whether gate g looks at the run: its `where`, or for a ratio its numerator or
    denominator row (docs/gates.md)."""
    def selector(*parts):
        # A selector without its own `kind` looks at the run whatever its kind.
        sel = {}
        for part in parts:
            sel.update(part)
        sel.setdefault("kind", run.kind)
        return sel
    if g.get("kind") == "ratio":
        return any(matches(run, selector(g.get("where", {}), g.get(k, {})))
                   for k in ("numerator", "denominator"))
    return matches(run, selector(g.get("where", {})))


class GatedColumns:
    """The gated columns of a sweep (in the gates file's order) and per run and column the
    verdict of the gates on it: "✓" (all passed), "✗ NAME" (one failed on this run), "" (no
    gate on that column looks at the run)."""

    def __init__(self, sweep, gates_file, entry):
        defs = read_gate_defs(gates_file) if gates_file else []
        self.verdicts = verdicts(sweep.dir, [r.id for r in sweep.runs], entry)
        self.defs = [g for g in defs if isinstance(g.get("column"), str)
                     and g.get("kind") != "pattern"]
        self.columns = list(dict.fromkeys(g["column"] for g in self.defs))

    def mark(self, run, column):
        marks = []
        for g in self.defs:
            if g["column"] != column or not _selected(run, g):
                continue
            v = self.verdicts.get(g.get("name"))
            if v is None:
                continue
            bad = not v["passed"] and (run.id in v["runs"] or not v["runs"])
            marks.append((bad, g.get("name")))
        if not marks:
            return ""
        bad = [n for b, n in marks if b]
        return "✗ " + "; ".join(bad) if bad else "✓"

    def summary(self):
        n = len(self.verdicts)
        bad = [k for k, v in self.verdicts.items() if not v["passed"]]
        return n - len(bad), bad
