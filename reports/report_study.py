"""A study's page (docs/studies.md, Outputs; docs/report.md): STUDY_OUT/report/index.html from
the study's `[report]` layout, drawn from the sweeps that `ricochet reproduce` wrote into
STUDY_OUT/<sweep>/ and what it recorded in STUDY_OUT/study.json. A study without a layout gets
the default page (report_default.py). Plug-ins (docs/studies.md, Writing a plug-in) receive a
StudyContext."""

import importlib.util
import json
import os
import sys
import traceback

import report_default as RD
import report_kinds as RK
from report_io import REPO, Sweep, git_commit
from report_layout import LayoutError, check_layout, read_study_toml, sweep_names
from report_page import Section, note, number
from report_render import render


def read_study_json(study_out):
    """study.json as a dict ({} when missing or unreadable: the page then says so)."""
    try:
        with open(os.path.join(study_out, "study.json")) as f:
            d = json.load(f)
        return d if isinstance(d, dict) else {}
    except (OSError, ValueError):
        return {}


def study_folder(study_out, sj):
    """The study's source folder: study.json `folder`, else the folder of that name under the
    source tree's cases/ (a study run before `folder` was recorded)."""
    f = sj.get("folder")
    if isinstance(f, str) and os.path.isfile(os.path.join(f, "study.toml")):
        return f
    name = sj.get("study") or os.path.basename(os.path.abspath(study_out))
    f = os.path.join(REPO, "cases", name)
    return f if os.path.isfile(os.path.join(f, "study.toml")) else None


def load_plugin(folder, file):
    """The plug-in module, imported under a name of its own (two studies' report.py never
    clash); its folder is on sys.path while it imports, for modules beside it."""
    path = os.path.join(folder, file)
    name = "plugin_" + "".join(c if c.isalnum() else "_" for c in os.path.abspath(path))
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    sys.path.insert(0, folder)
    try:
        spec.loader.exec_module(mod)
    finally:
        sys.path.remove(folder)
    return mod


class StudyContext:
    """What a section builder may ask about the study (the plug-in API, docs/studies.md):
    out (the report folder, figures go there), out_dir (STUDY_OUT), folder (the study's
    source folder), tier, study (study.json), sweep(name) (a Sweep, or None when the sweep did
    not run in this tier), sweep_dir(name), sweep_entry(name) (its study.json entry),
    gates_file(name), not_run(name) (the note to show instead), max_run_plots."""

    def __init__(self, study_out, out, sj, folder, toml, max_run_plots=30):
        self.out_dir, self.out, self.study, self.folder = study_out, out, sj, folder
        self.toml = toml or {}
        self.tier = sj.get("tier") or "?"
        self.max_run_plots = max_run_plots
        self._sweeps = {}

    def sweep_entry(self, name):
        for e in self.study.get("sweeps", []) or []:
            if isinstance(e, dict) and e.get("name") == name:
                return e
        return {}

    def sweep_dir(self, name):
        d = self.sweep_entry(name).get("dir") or name
        return d if os.path.isabs(d) else os.path.join(self.out_dir, d)

    def sweep(self, name):
        if name not in self._sweeps:
            d = self.sweep_dir(name)
            try:
                self._sweeps[name] = Sweep(d) if os.path.isfile(os.path.join(d, "summary.csv")) else None
            except (OSError, ValueError):
                self._sweeps[name] = None
        return self._sweeps[name]

    def gates_file(self, name):
        g = self.sweep_entry(name).get("gates")
        if isinstance(g, str) and g:
            return g
        for s in self.toml.get("sweep", []) or []:
            if (isinstance(s, dict) and s.get("name") == name and s.get("gates")
                    and self.tier in s.get("tier", ["fast", "full"])):
                return os.path.join(self.folder or "", s["gates"])
        return None

    def not_run(self, name, sid):
        tiers = sorted({t for s in self.toml.get("sweep", []) or [] if isinstance(s, dict)
                        and s.get("name") == name for t in s.get("tier", ["fast", "full"])})
        return note(sid, f"Sweep `{name}` not run in this tier ({self.tier})"
                    + (f"; it runs in the {' and '.join(tiers)} tier" + ("s" if len(tiers) > 1
                                                                         else "")
                       if tiers and self.tier not in tiers else "")
                    + f": no `{os.path.join(self.sweep_dir(name), 'summary.csv')}`.")


def _as_list(x):
    return x if isinstance(x, list) else [x]


def build_sections(ctx, layout, plugin):
    """The page's sections, in layout order. A layout section's `title` heads what it builds
    and `text` stands under the heading; a section without a title continues the heading
    before it (its `text`, if any, as a paragraph of its own)."""
    out = []
    part, intro = None, ""
    for i, sec in enumerate(layout["sections"]):
        sid = f"s{i + 1}"
        got = []
        if sec.get("title"):
            part, intro = sec["title"], sec.get("text", "")
        elif sec.get("text"):
            n = note(sid + "_text", sec["text"])
            n.part, n.part_intro = part, intro
            out.append(n)
        try:
            name = sec.get("sweep")
            if name and ctx.sweep(name) is None:
                got = [ctx.not_run(name, sid)]
            elif sec["kind"] == "plugin":
                got = _as_list(getattr(plugin, sec["name"])(ctx, sec) or [])
            else:
                got = RK.BUILDERS[sec["kind"]](ctx, sec, ctx.sweep(name), sid)
        except Exception as e:  # noqa: BLE001 - one broken section must not stop the page
            traceback.print_exc()
            bad = Section(sid, sec.get("title") or sec["kind"], "figure")
            bad.error = f"{type(e).__name__}: {e}"
            got = [bad]
        for s in got:
            s.part = part if part is not None else s.part
            s.part_intro = intro if part is not None else s.part_intro
        out += got
    seen = set()
    for s in out:   # ids unique on the page (two plug-in calls may use the same)
        base, k = s.id, 1
        while s.id in seen:
            k += 1
            s.id = f"{base}_{k}"
        seen.add(s.id)
    return out


def _meta(ctx, sj, folder):
    meta = [("Study", f"`{folder}`" if folder else "source folder not found"),
            ("Tier", ctx.tier), ("Status", sj.get("status", "unknown (no study.json)"))]
    for e in sj.get("sweeps", []) or []:
        if not isinstance(e, dict):
            continue
        meta.append((f"Sweep {e.get('name', '?')}",
                     f"`{ctx.sweep_dir(e.get('name', '?'))}`: {e.get('runs', '?')} runs "
                     f"({e.get('reused', '?')} reused, {e.get('run_now', '?')} run, "
                     f"{e.get('failed', '?')} failed; {e.get('seconds', '?')} s)"
                     + (f"; gates `{e['gates']}`" if isinstance(e.get("gates"), str) else "")))
    for p in sj.get("post", []) or []:
        if isinstance(p, dict):
            meta.append((f"Post {p.get('name', '?')}", f"exit {p.get('exit', '?')}"))
    commit, dirty = git_commit(REPO)
    meta.append(("Source tree", (f"commit `{commit}`" + (" with uncommitted changes" if dirty
                                                         else "")) if commit else "not a git work tree"))
    return meta


def study_page(study_out, out=None, max_run_plots=30, now=""):
    """Writes the page; returns (index.html path, sections). LayoutError on a bad layout."""
    study_out = os.path.abspath(study_out)
    sj = read_study_json(study_out)
    folder = study_folder(study_out, sj)
    toml_path = os.path.join(folder, "study.toml") if folder else None
    toml = read_study_toml(toml_path) if toml_path else {}
    layout = check_layout(toml_path, toml) if toml_path else None
    plugin = None
    if layout and layout["plugin"]:
        plugin = load_plugin(folder, layout["plugin"])
        check_layout(toml_path, toml, {n for n in dir(plugin) if callable(getattr(plugin, n))})
    out = os.path.abspath(out or os.path.join(study_out, "report"))
    os.makedirs(out, exist_ok=True)
    ctx = StudyContext(study_out, out, sj, folder, toml, max_run_plots)
    if layout is None:
        names = sweep_names(toml) or [e.get("name") for e in sj.get("sweeps", []) or []
                                      if isinstance(e, dict)]
        sections = []
        for name in names:
            sw = ctx.sweep(name)
            part = f"Sweep {name}"
            got = RD.default_sections(ctx, sw, name) if sw else [ctx.not_run(name, name)]
            for s in got:
                s.part = part
            sections += got
    else:
        sections = build_sections(ctx, layout, plugin)
    number(sections, out)
    name = sj.get("study") or os.path.basename(study_out)
    title = sj.get("title") or toml.get("title") or f"Study {name}"
    render({"out": out, "title": title, "intro": sj.get("summary") or toml.get("summary", ""),
            "meta": _meta(ctx, sj, folder) + [("Report written", now)], "sections": sections,
            "up": "../../index.html" if out == os.path.join(study_out, "report") else None,
            "manifest": {"study": name, "study_out": study_out, "tier": ctx.tier,
                         "layout": layout is not None, "generated_at": now}})
    return os.path.join(out, "index.html"), sections


__all__ = ["LayoutError", "study_page", "StudyContext"]
