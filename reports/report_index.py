"""The index of a reproduction (docs/studies.md, Outputs): OUT/index.html, one row per study
folder OUT/<study>/ holding a study.json: its title linking to its page, its summary, the
tier, its gates passed and failed, its status (coloured) and its runs reused and run."""

import html
import os

from report_layout import LayoutError, read_study_toml
from report_render import CSS
from report_study import read_study_json, study_folder

STATUS_CLASS = {"passed": "ok", "gates failed": "bad", "failed": "bad", "skipped": "bad"}


def studies(out):
    """[(folder name, study.json)] of OUT's subfolders with a study.json, in the studies'
    `order` (study.toml), then by name."""
    found = []
    for name in sorted(os.listdir(out)):
        d = os.path.join(out, name)
        if os.path.isfile(os.path.join(d, "study.json")):
            sj = read_study_json(d)
            order = 1e9
            folder = study_folder(d, sj)
            if folder:
                try:
                    order = float(read_study_toml(os.path.join(folder, "study.toml"))
                                  .get("order", 1e9))
                except (LayoutError, TypeError, ValueError):
                    pass
            found.append((order, name, sj))
    return [(n, sj) for _, n, sj in sorted(found, key=lambda x: (x[0], x[1]))]


def gate_counts(sj):
    """(passed, failed) over the gates of every sweep and post step in study.json."""
    ok = bad = 0
    for e in (sj.get("sweeps", []) or []) + (sj.get("post", []) or []):
        for g in (e.get("gate_results", []) if isinstance(e, dict) else []) or []:
            if isinstance(g, dict):
                ok += bool(g.get("passed"))
                bad += not g.get("passed")
    return ok, bad


def run_counts(sj):
    n = {"runs": 0, "reused": 0, "run_now": 0, "failed": 0}
    for e in sj.get("sweeps", []) or []:
        for k in n:
            v = e.get(k) if isinstance(e, dict) else None
            n[k] += v if isinstance(v, int) else 0
    return n


def write_index(out, now=""):
    rows = studies(out)
    h = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
         "<title>ricochet: studies</title>",
         f"<style>{CSS} td.ok{{background:#e6f4e6}} td.bad{{background:#fdecea}}</style>"
         "</head><body>", "<h1>ricochet: studies</h1>",
         f"<p>{len(rows)} studies in <code>{html.escape(os.path.abspath(out))}</code>"
         + (f"; written {html.escape(now)}" if now else "") + ".</p>",
         '<table id="studies"><thead><tr><th>study</th><th>what it shows</th><th>tier</th>'
         "<th>gates passed</th><th>gates failed</th><th>status</th><th>runs: reused / run "
         "/ failed</th></tr></thead><tbody>"]
    for name, sj in rows:
        title = sj.get("title") or name
        link = f"{name}/report/index.html"
        has = os.path.isfile(os.path.join(out, link))
        cell = (f'<a href="{html.escape(link)}">{html.escape(title)}</a>' if has
                else html.escape(title) + " <i>(no page)</i>")
        ok, bad = gate_counts(sj)
        status = sj.get("status", "unknown")
        n = run_counts(sj)
        note = (f"<br><small>{html.escape(str(sj.get('reason')))}</small>"
                if status == "skipped" and sj.get("reason") else "")
        h.append(f'<tr id="study-{html.escape(name)}"><td>{cell}<br><code>{html.escape(name)}'
                 f"</code></td><td>{html.escape(sj.get('summary', ''))}</td>"
                 f"<td>{html.escape(str(sj.get('tier', '?')))}</td><td>{ok}</td>"
                 f'<td class="{"bad" if bad else "nw"}">{bad}</td>'
                 f'<td class="{STATUS_CLASS.get(status, "")}">{html.escape(status)}{note}</td>'
                 f"<td>{n['reused']} / {n['run_now']} / {n['failed']}</td></tr>")
    h.append("</tbody></table></body></html>")
    path = os.path.join(out, "index.html")
    with open(path, "w") as f:
        f.write("\n".join(h) + "\n")
    return path, rows
