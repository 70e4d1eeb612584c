"""Which runs a layout section reads and what a run's swept values are (docs/studies.md, The
layout: `where`, the swept keys). A key is a summary.csv column, else a case key the sweep set
on the run (`overrides` of sweep.json, docs/sweeps.md), e.g. "obstacles[0].friction"."""

from report_io import fnum


def overrides(sweep):
    """run id -> {case key: value text}, from sweep.json's run list (its `--set` arguments)."""
    out = {}
    for e in sweep.meta.get("runs", []) or []:
        if not isinstance(e, dict):
            continue
        d = {}
        for item in e.get("overrides", []) or []:
            if isinstance(item, str) and "=" in item:
                k, v = item.split("=", 1)
                d[k.strip()] = v.strip().strip('"')
        out[e.get("id")] = d
    return out


def swept_keys(sweep):
    """The keys the sweep crossed (sweep.json runs[].swept, a list of keys or a table), in
    their first order; without sweep.json, the override keys that differ between runs."""
    keys = []
    for e in sweep.meta.get("runs", []) or []:
        sw = e.get("swept") if isinstance(e, dict) else None
        for k in (sw.keys() if isinstance(sw, dict) else sw or []):
            if isinstance(k, str) and k not in keys:
                keys.append(k)
    if keys:
        return keys
    ov = overrides(sweep)
    allk = []
    for d in ov.values():
        allk += [k for k in d if k not in allk]
    return [k for k in allk if len({d.get(k) for d in ov.values()}) > 1]


def value(run, key, ov=None):
    """The run's value of `key` as text ("" when it has none): its summary.csv column, else
    the case key the sweep set on it."""
    v = run.row.get(key)
    if v not in (None, ""):
        return v
    if ov is None:
        ov = overrides(run.sweep)
    return ov.get(run.id, {}).get(key, "")


def _same(text, want):
    if isinstance(want, bool):
        return text.lower() == str(want).lower()
    if isinstance(want, (int, float)):
        x = fnum(text)
        return x is not None and abs(x - want) <= 1e-9 * max(abs(x), abs(want), 1e-300)
    return text == str(want)


def matches(run, where, ov=None):
    """Whether the run matches every key of `where` ({key: value or [values]}, as a gate's
    selector, docs/gates.md). `kind` defaults to "run": a section does not mix the searches of
    stability groups and the reference runs with the runs unless asked to."""
    where = dict(where or {})
    kinds = where.pop("kind", "run")
    kinds = kinds if isinstance(kinds, list) else [kinds]
    if run.kind not in kinds:
        return False
    for k, want in where.items():
        wants = want if isinstance(want, list) else [want]
        if not any(_same(value(run, k, ov), w) for w in wants):
            return False
    return True


def select(sweep, where=None):
    ov = overrides(sweep)
    return [r for r in sweep.runs if matches(r, where, ov)]


def as_number(text):
    """A value as a float, or None (a mesh name, a scheme)."""
    return fnum(text)
