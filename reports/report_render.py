"""Writes a page (report_page.py) as index.html, report.md and manifest.json.

page: {"out": folder, "title": str, "intro": inline markdown or "", "meta": [(label, text)],
       "sections": [Section], "manifest": {extra keys}}.
Sections with the same `part` in a row stand under one heading (a layout section's title),
with its `part_intro` (the layout's `text`) below it."""

import html
import json
import os
import re

from report_page import md_inline_to_html, md_table, html_table, part_id

CSS = """
body{font-family:system-ui,-apple-system,'Segoe UI',Helvetica,Arial,sans-serif;max-width:1150px;
margin:1.5em auto;padding:0 1em;color:#222;line-height:1.45}
h1{font-size:1.6em;margin-bottom:.2em} h2{margin-top:1.8em;border-bottom:1px solid #ccc}
h3{font-size:1.05em} h3.sec{font-size:1.2em;margin-top:1.6em}
.part-intro,.intro{font-size:.95em}
table{border-collapse:collapse;margin:.6em 0;font-size:.88em}
th,td{border:1px solid #bbb;padding:.25em .5em;vertical-align:top}
th{background:#f0f0f0} td.diverged{background:#fdecea} td.nw{white-space:nowrap}
td.nw code,th code{word-break:normal;overflow-wrap:anywhere}
figure{margin:1em 0} figure img{max-width:100%;border:1px solid #ddd}
figcaption,.caption{font-size:.9em;color:#333;margin-top:.4em}
code{font-size:.85em;background:#f4f4f4;padding:0 .2em;word-break:break-all}
.na{border:2px dashed #c33;background:#fff6f6;padding:.6em 1em}
.note{border-left:4px solid #bbb;background:#f7f7f7;padding:.4em 1em;color:#444}
.meta td{border:none;padding:.1em .8em .1em 0}
"""


def _heading(s):
    return f"{s.number}: {s.title}" if s.number else s.title


def _markdown(page):
    md = [f"# {page['title']}", ""]
    if page.get("intro"):
        md += [page["intro"], ""]
    for k, v in page["meta"]:
        md.append(f"- **{k}:** {v}")
    md.append("")
    part = None
    for s in page["sections"]:
        if s.part != part:
            part = s.part
            if part:
                md += [f"## {part}", ""] + ([s.part_intro, ""] if s.part_intro else [])
        if s.kind == "note":
            md += [f"> {s.caption}", ""]
            continue
        md += [f"{'###' if s.part else '##'} {_heading(s)}", ""]
        if s.error:
            md += [f"**Error while building this section:** `{s.error}`", ""]
            continue
        if not s.available:
            md += [f"**Not available:** {s.missing}", ""]
            continue
        if s.kind == "table":
            md += [md_table(s.header, s.rows) if s.rows else "(no rows)", "",
                   f"*{s.label}.* {s.caption}"]
        else:
            md += [f"![{s.title}]({f})" for f in s.files if f.endswith(".png")] + [""]
            others = [f for f in s.files if not f.endswith(".png")]
            md.append(f"*{s.label}.* {s.caption}" +
                      (" Also: " + ", ".join(f"[{f}]({f})" for f in others) + "." if others
                       else ""))
        md.append("")
        for _tid, title, hdr, rows in s.extra:
            md += [f"**{title}**", "", md_table(hdr, rows) if rows else "(no rows)", ""]
    return "\n".join(md) + "\n"


def _html_section(s, h):
    if s.kind == "note":
        h.append(f'<p class="note" id="{html.escape(s.id)}">{md_inline_to_html(s.caption)}</p>')
        return
    hx = '<h3 class="sec"' if s.part else "<h2"
    h.append(f'<section id="sec-{s.id}">{hx} id="{s.id}">{html.escape(_heading(s))}'
             f"</{hx[1:3]}>")
    if s.error:
        h.append(f'<div class="na not-available"><b>Error while building this section:</b> '
                 f"<code>{html.escape(s.error)}</code></div></section>")
        return
    if not s.available:
        h.append(f'<div class="na not-available"><b>Not available:</b> '
                 f"{md_inline_to_html(s.missing)}</div></section>")
        return
    if s.kind == "table":
        h.append(html_table("tab-" + s.id, s.header, s.rows))
        h.append(f'<p class="caption"><b>{html.escape(s.label)}.</b> '
                 f"{md_inline_to_html(s.caption)}</p>")
    else:
        h.append("<figure>")
        for f in s.files:
            if f.endswith(".png"):
                h.append(f'<a href="{html.escape(f)}"><img src="{html.escape(f)}" '
                         f'alt="{html.escape(s.title)}"></a>')
        others = [f for f in s.files if not f.endswith(".png")]
        also = (" Also: " + ", ".join(f'<a href="{html.escape(f)}">{html.escape(f)}</a>'
                                      for f in others) + ".") if others else ""
        h.append(f"<figcaption><b>{html.escape(s.label)}.</b> "
                 f"{md_inline_to_html(s.caption)}{also}</figcaption></figure>")
    for tid, title, hdr, rows in s.extra:
        h.append(f"<h3>{md_inline_to_html(title)}</h3>")
        h.append(html_table("tab-" + tid, hdr, rows))
    h.append("</section>")


def _html(page):
    sections = page["sections"]
    h = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
         f"<title>ricochet: {html.escape(page['title'])}</title>",
         f"<style>{CSS}</style></head><body>"]
    if page.get("up"):
        h.append(f'<p><a href="{html.escape(page["up"])}">← all studies</a></p>')
    h.append(f"<h1>{html.escape(page['title'])}</h1>")
    if page.get("intro"):
        h.append(f'<p class="intro">{md_inline_to_html(page["intro"])}</p>')
    h.append('<table class="meta">')
    for k, v in page["meta"]:
        h.append(f"<tr><td><b>{html.escape(k)}</b></td><td>{md_inline_to_html(v)}</td></tr>")
    h.append("</table>")
    h.append("<h2>Contents</h2><ol>")
    part = None
    for s in sections:
        if s.part != part:
            if part:
                h.append("</ul></li>")
            part = s.part
            if part:
                h.append(f'<li><a href="#part-{part_id(part)}">{html.escape(part)}</a><ul>')
        if s.kind == "note":
            continue
        flag = "" if s.available and not s.error else " — <b>not available</b>"
        h.append(f'<li><a href="#{s.id}">{html.escape(_heading(s))}</a>{flag}</li>')
    if part:
        h.append("</ul></li>")
    h.append("</ol>")
    part = None
    for s in sections:
        if s.part != part:
            part = s.part
            if part:
                h.append(f'<h2 id="part-{part_id(part)}">{html.escape(part)}</h2>')
                if s.part_intro:
                    h.append(f'<p class="part-intro">{md_inline_to_html(s.part_intro)}</p>')
        _html_section(s, h)
    h.append("</body></html>")
    return "\n".join(h) + "\n"


def _manifest(page):
    man = dict(page.get("manifest") or {})
    man.update({"title": page["title"], "sections": []})
    for s in page["sections"]:
        man["sections"].append({
            "id": s.id, "number": s.number, "title": s.title, "kind": s.kind,
            "reproduces": s.paper, "part": s.part, "case": s.case,
            "available": s.available and not s.error, "error": s.error,
            "missing": s.missing or None, "files": s.files, "runs": s.runs,
            "sources": s.sources, "series": s.series, "text": s.caption if s.kind == "note" else None,
            "tables": ([{"id": s.id, "rows": s.row_labels()}] if s.kind == "table" and
                       s.available and not s.error else []) +
                      [{"id": tid, "rows": [re.sub(r"[*`]", "", r[0]) for r in rows]}
                       for tid, _, _, rows in s.extra]})
    return man


def render(page):
    out = page["out"]
    with open(os.path.join(out, "report.md"), "w") as f:
        f.write(_markdown(page))
    with open(os.path.join(out, "index.html"), "w") as f:
        f.write(_html(page))
    with open(os.path.join(out, "manifest.json"), "w") as f:
        json.dump(_manifest(page), f, indent=1)
        f.write("\n")
