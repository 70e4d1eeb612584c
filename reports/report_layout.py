"""The `[report]` layout of a study.toml (docs/studies.md, The layout): reads and checks it.

A layout error is one line naming the study.toml and the key, e.g.
  cases/x/study.toml: report.section[2].colour: unknown key for kind "metric"; allowed: ...
raised as LayoutError; make_report.py prints it and exits 2. The checks are all made before
anything is drawn, so a bad layout never leaves half a page."""

import os
import tomllib

COMMON = ("kind", "title", "text", "sweep")

# kind -> {key: type}; the types below. `sweep` is required for every kind but `plugin`.
KINDS = {
    "runs_table": {"columns": "strs", "where": "table"},
    "metric": {"x": "str", "y": "str", "by": "str", "where": "table", "logx": "bool",
               "logy": "bool"},
    "work_precision": {"error": "strs", "cost": "str", "by": "str", "where": "table"},
    "histories": {"y": "strs", "where": "table", "runs": "strs"},
    "fields": {"run": "str", "field": "str", "times": "numbers"},
    "stability": {"where": "table"},
    "plugin": {"name": "str", "args": "table"},
}
REQUIRED = {"metric": ("x", "y"), "work_precision": ("error",), "histories": ("y",),
            "plugin": ("name",)}
TOP = ("plugin", "section")


class LayoutError(ValueError):
    pass


def _type_ok(kind, v):
    if kind == "str":
        return isinstance(v, str) and v != ""
    if kind == "strs":
        return (isinstance(v, str) and v != "") or (
            isinstance(v, list) and v and all(isinstance(x, str) and x for x in v))
    if kind == "bool":
        return isinstance(v, bool)
    if kind == "table":
        return isinstance(v, dict)
    if kind == "numbers":
        return isinstance(v, list) and all(isinstance(x, (int, float)) and not
                                           isinstance(x, bool) for x in v)
    return False


TYPE_TEXT = {"str": "a string", "strs": "a string or an array of strings", "bool": "true or false",
             "table": "a table", "numbers": "an array of numbers"}


def as_list(v):
    return [] if v is None else [v] if isinstance(v, str) else list(v)


def read_study_toml(path):
    """The parsed study.toml; LayoutError (one line) when it cannot be read."""
    try:
        with open(path, "rb") as f:
            return tomllib.load(f)
    except OSError as e:
        raise LayoutError(f"{path}: cannot read ({e.strerror})") from e
    except tomllib.TOMLDecodeError as e:
        raise LayoutError(f"{path}: not valid TOML ({e})") from e


def sweep_names(study):
    """The sweep names a study.toml declares (each once, in order)."""
    out = []
    for s in study.get("sweep", []) or []:
        if isinstance(s, dict) and isinstance(s.get("name"), str) and s["name"] not in out:
            out.append(s["name"])
    return out


def check_layout(path, study, plugin_functions=None):
    """The layout of study.toml `path` (parsed: `study`) as {"plugin": file or None,
    "sections": [dict]}, or None when it has no [report]. plugin_functions: the names the
    plug-in module defines (None: not loaded yet; the names are then not checked)."""
    rep = study.get("report")
    if rep is None:
        return None
    where = f"{path}: report"
    if not isinstance(rep, dict):
        raise LayoutError(f"{where}: must be a table ([report])")
    for k in rep:
        if k not in TOP:
            raise LayoutError(f"{where}.{k}: unknown key; allowed: {', '.join(TOP)}")
    plugin = rep.get("plugin")
    if plugin is not None:
        if not isinstance(plugin, str) or not plugin.endswith(".py"):
            raise LayoutError(f"{where}.plugin: must be a .py file name, got {plugin!r}")
        if not os.path.isfile(os.path.join(os.path.dirname(path), plugin)):
            raise LayoutError(f"{where}.plugin: {plugin}: no such file in the study folder")
    secs = rep.get("section", [])
    if not isinstance(secs, list) or not all(isinstance(s, dict) for s in secs):
        raise LayoutError(f"{where}.section: must be an array of tables ([[report.section]])")
    names = sweep_names(study)
    for i, s in enumerate(secs):
        at = f"{where}.section[{i}]"
        kind = s.get("kind")
        if kind not in KINDS:
            raise LayoutError(f"{at}.kind: got {kind!r}; allowed: {', '.join(KINDS)}")
        allowed = KINDS[kind]
        for k, v in s.items():
            if k in ("title", "text", "sweep"):
                if not isinstance(v, str) or not v:
                    raise LayoutError(f"{at}.{k}: must be a non-empty string")
            elif k == "kind":
                continue
            elif k not in allowed:
                raise LayoutError(f"{at}.{k}: unknown key for kind \"{kind}\"; allowed: "
                                  + ", ".join(COMMON + tuple(allowed)))
            elif not _type_ok(allowed[k], v):
                raise LayoutError(f"{at}.{k}: must be {TYPE_TEXT[allowed[k]]}, got {v!r}")
        for k in REQUIRED.get(kind, ()):
            if k not in s:
                raise LayoutError(f"{at}.{k}: required for kind \"{kind}\"")
        if kind != "plugin" and "sweep" not in s:
            raise LayoutError(f"{at}.sweep: required (the sweep the section reads)")
        if "sweep" in s and s["sweep"] not in names:
            raise LayoutError(f"{at}.sweep: \"{s['sweep']}\" is not a sweep of this study "
                              f"(its sweeps: {', '.join(names) or 'none'})")
        if kind == "plugin":
            if plugin is None:
                raise LayoutError(f"{at}.name: a plugin section needs report.plugin (the "
                                  "study's plug-in module)")
            if plugin_functions is not None and s["name"] not in plugin_functions:
                raise LayoutError(f"{at}.name: \"{s['name']}\" is not a function of {plugin}")
    return {"plugin": plugin, "sections": secs}
