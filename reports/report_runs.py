"""Run labels and gate totals shared by the plug-ins' tables (docs/studies.md, Writing a
plug-in): which case keys tell runs of one scheme apart, the schemes' usual order, and a sweep's
gates-junit.xml in one line."""

import json
import os
import xml.etree.ElementTree as ET

from report_io import scheme_name

SCHEMES = ("semi_explicit", "implicit", "explicit_penalty")


def parse_overrides(run):
    out = {}
    raw = run.get("overrides")
    try:
        items = json.loads(raw) if raw else run.summary().get("overrides", [])
    except ValueError:
        items = []
    for it in items or []:
        if "=" in it:
            k, v = it.split("=", 1)
            out[k.strip()] = v.strip().strip('"')
    return out


def effective(run, key, ov):
    """The value a run used for a case key: its own summary column when it has one (so the
    default shows too), else its override, else 'default'."""
    for c in (key.replace(".", "_"), key.split(".")[-1], "summary." + key):
        v = run.get(c)
        if v not in ("", None):
            return v
    return ov.get(key, "default")


def column_labels(runs):
    """{run id: header label}: scheme name, plus, for several runs of one scheme, the keys
    whose values differ between them (else the group)."""
    labels = {}
    by_scheme = {}
    for r in runs:
        by_scheme.setdefault(r.scheme, []).append(r)
    for scheme, rs in by_scheme.items():
        name = scheme_name(scheme)
        if len(rs) == 1:
            labels[rs[0].id] = name
            continue
        ovs = {r.id: parse_overrides(r) for r in rs}
        keys = []
        for r in rs:
            keys += [k for k in ovs[r.id] if k != "scheme" and k not in keys]
        diff = [k for k in keys if len({effective(r, k, ovs[r.id]) for r in rs}) > 1]
        for r in rs:
            if diff:
                labels[r.id] = name + ", " + ", ".join(
                    f"{k} = {effective(r, k, ovs[r.id])}" for k in diff)
            else:
                labels[r.id] = f"{name}, group `{r.group}`"
    return labels


def order_runs(runs):
    def key(r):
        s = SCHEMES.index(r.scheme) if r.scheme in SCHEMES else len(SCHEMES)
        return (s, r.scheme, runs.index(r))
    return sorted(runs, key=key)


def gates_result(folder):
    """(text, failed gate names) from the sweep's gates-junit.xml (written by --check), or
    (None, []) without it."""
    try:
        root = ET.parse(os.path.join(folder, "gates-junit.xml")).getroot()
    except (OSError, ET.ParseError):
        return None, []
    cases = list(root.iter("testcase"))
    failed = [c.get("name", "?") for c in cases
              if c.find("failure") is not None or c.find("error") is not None]
    n = int(root.get("tests", str(len(cases))))
    bad = int(root.get("failures", "0")) + int(root.get("errors", "0"))
    return f"{n - bad} passed, {bad} failed", failed
