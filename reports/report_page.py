"""The page model of every report (docs/report.md, Output): a page is a title, a header of
(label, text) pairs and a list of Sections, each a numbered table or figure (or a short note),
written as index.html, report.md and manifest.json. Text is inline Markdown (`code`, **bold**,
*italic*, [links](url)); the same text gives both the HTML and the Markdown. Nothing here knows
what a study shows: the layout (report_layout.py) and the plug-ins fill the sections."""

import html
import os
import re


class Section:
    """One table, figure or note of a page. Builders (report_kinds.py, a study's plug-in) set
    what they have; the page numbers the tables and figures in order."""

    def __init__(self, sid, title, kind):
        self.id = sid
        self.title = title
        self.kind = kind          # "figure", "table" or "note" (a paragraph, not numbered)
        self.number = None        # "Figure 3", "Table 1"
        self.paper = None         # which figure/table of a publication it reproduces
        self.caption = ""         # inline markdown
        self.files = []           # figure files, relative to the report folder
        self.header = []          # table header (inline markdown)
        self.rows = []            # table rows: lists of inline-markdown cells
        self.runs = []            # run ids it came from
        self.sources = []         # sweep folders / files it came from
        self.available = True
        self.missing = ""         # why not available and how to produce it
        self.error = None         # the exception text if building failed
        self.label = ""           # "Figure 3"
        self.extra = []           # further tables inside a section: (id, title, header, rows)
        self.part = None          # the heading it stands under (a layout section's title)
        self.part_intro = ""      # inline markdown under the part's heading
        self.case = None          # a plug-in's own tag (e.g. the case a section is about)
        self.series = None        # a figure's lines: {label: points}, for manifest.json

    def row_labels(self):
        return [re.sub(r"[*`]", "", r[0]) for r in self.rows]


def note(sid, text):
    """A short paragraph instead of a table or figure: e.g. a sweep not run in this tier."""
    s = Section(sid, "", "note")
    s.caption = text
    return s


def md_inline_to_html(text):
    s = html.escape(text, quote=False)
    s = re.sub(r"`([^`]+)`", r"<code>\1</code>", s)
    s = re.sub(r"\*\*([^*]+)\*\*", r"<b>\1</b>", s)
    s = re.sub(r"(?<![\w*])\*([^*\s][^*]*)\*(?![\w*])", r"<i>\1</i>", s)
    s = re.sub(r"\[([^\]]+)\]\(([^)]+)\)", r'<a href="\2">\1</a>', s)
    return s.replace("\n", "<br>")


def md_cell(text):
    return str(text).replace("|", "\\|").replace("\n", " ")


def md_table(header, rows):
    out = ["| " + " | ".join(md_cell(h) for h in header) + " |",
           "|" + "|".join("---" for _ in header) + "|"]
    for r in rows:
        out.append("| " + " | ".join(md_cell(c) for c in r) + " |")
    return "\n".join(out)


def html_table(tid, header, rows):
    out = [f'<table id="{html.escape(tid)}">', "<thead><tr>"]
    out += [f"<th>{md_inline_to_html(h)}</th>" for h in header]
    out.append("</tr></thead><tbody>")
    for r in rows:
        cells = []
        for c in r:
            bad = re.match(r"\**(diverged|failed|missing)\b|✗", str(c))
            cls = ' class="diverged"' if bad else ""
            if not bad and (len(str(c)) <= 12 or re.fullmatch(r"`[^`\s]{1,30}`", str(c))) \
                    and " " not in str(c).strip():
                cls = ' class="nw"'   # a short number, word or run id: never broken
            cells.append(f"<td{cls}>{md_inline_to_html(str(c))}</td>")
        out.append("<tr>" + "".join(cells) + "</tr>")
    out.append("</tbody></table>")
    return "\n".join(out)


def unavailable(sections, what, err, cmd):
    """Marks the sections "not available": what is missing (and the error reading it), and the
    command that makes it."""
    for s in sections:
        s.available = False
        s.missing = what + (f" ({err})" if err else "") + f". Run `{cmd}`."
    return sections


def runs_text(ids):
    ids = list(ids)
    return ", ".join(f"`{i}`" for i in ids) if ids else "none"


def part_id(title):
    return re.sub(r"[^a-z0-9]+", "-", title.lower()).strip("-")


def number(sections, out):
    """Numbers the tables and figures in order ("Table 2", "Figure 5 (paper's Fig. 3)") and
    flags an empty figure file as an error."""
    nfig = ntab = 0
    for s in sections:
        if s.kind == "note":
            continue
        if s.kind == "figure":
            nfig += 1
            s.number = f"Figure {nfig}"
        else:
            ntab += 1
            s.number = f"Table {ntab}"
        if s.paper:
            s.number += f" (paper's {s.paper})"
        s.label = s.number.split(" (")[0]
        for f in s.files:
            p = os.path.join(out, f)
            if not os.path.exists(p) or not os.path.getsize(p):
                s.error = f"empty or missing figure file {f}"
