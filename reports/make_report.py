#!/usr/bin/python3
"""The report (docs/report.md): a study's page from its layout, the index of a reproduction,
or the default page of any sweep.

    /usr/bin/python3 reports/make_report.py --study STUDY_OUT [--out DIR]
    /usr/bin/python3 reports/make_report.py --index OUT
    /usr/bin/python3 reports/make_report.py DIR [--out DIR]

--study STUDY_OUT  a study's output folder (`ricochet reproduce`, docs/studies.md): its
                   study.json and one folder per sweep. Writes STUDY_OUT/report/index.html,
                   report.md, manifest.json and the figures, laid out by the study's
                   study.toml `[report]` (its plug-in for what the data kinds cannot say).
--index OUT        OUT/index.html: one row per OUT/<study>/study.json.
DIR                a study's output folder (as --study), a folder of them (each study's page,
                   then the index), or a plain sweep folder: its default page, DIR/report/
                   (the runs table and one figure per swept key).
--out DIR          the report folder (not with --index).
--max-run-plots N  plug-ins that draw run histories draw at most N (default 30).

Exit status: 0 written (sections without data say so), 2 bad input (no such folder, not a
sweep, a layout error: one line on stderr naming the study.toml and the key), 1 the report
folder cannot be created."""

import argparse
import datetime
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import report_default as RD  # noqa: E402
from report_index import write_index  # noqa: E402
from report_io import Sweep, git_commit, REPO  # noqa: E402
from report_layout import LayoutError  # noqa: E402
from report_page import number  # noqa: E402
from report_render import render  # noqa: E402
from report_study import study_page  # noqa: E402


class OneLineParser(argparse.ArgumentParser):
    """Bad options: one line on stderr, exit 2 (no usage block)."""

    def error(self, message):
        self.exit(2, f"{self.prog}: {message} (--help for the options)\n")


def now():
    return datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")


def is_study(d):
    return os.path.isfile(os.path.join(d, "study.json"))


def study_dirs(d):
    return [os.path.join(d, n) for n in sorted(os.listdir(d)) if is_study(os.path.join(d, n))]


def sweep_page(folder, out, stamp):
    """The default page of a plain sweep folder."""
    sweep = Sweep(folder)
    out = os.path.abspath(out or os.path.join(folder, "report"))
    os.makedirs(out, exist_ok=True)
    ctx = RD.sweep_page_context(out, sweep)
    sections = RD.default_sections(ctx, sweep, sweep.name)
    number(sections, out)
    commit, dirty = git_commit(REPO)
    meta = [("Sweep", f"`{sweep.dir}` (sweep `{sweep.name}`, file "
                      f"`{sweep.meta.get('sweep_file', '?')}`, {len(sweep.runs)} runs; finished "
                      f"{sweep.meta.get('finished_at', '?')})"),
            ("Program", f"ricochet {sweep.version()}, `{sweep.meta.get('program', '?')}`"),
            ("Source tree", (f"commit `{commit}`" + (" with uncommitted changes" if dirty else ""))
             if commit else "not a git work tree"),
            ("Report written", stamp)]
    render({"out": out, "title": f"Sweep {sweep.name}", "intro": sweep.meta.get("description", ""),
            "meta": meta, "sections": sections,
            "manifest": {"sweep": sweep.dir, "generated_at": stamp}})
    return os.path.join(out, "index.html"), sections


def _done(path, sections):
    na = [s.id for s in sections if s.kind != "note" and (not s.available or s.error)]
    print(f"make_report: {path}: {len(sections)} sections"
          + (f", not available: {', '.join(na)}" if na else ""))


def main(argv=None):
    ap = OneLineParser(prog="make_report.py", description=__doc__.split("\n\n")[0])
    ap.add_argument("dir", nargs="?", help="a study's output folder, a folder of them, or a "
                                           "sweep folder")
    ap.add_argument("--study", metavar="STUDY_OUT", help="a study's output folder")
    ap.add_argument("--index", metavar="OUT", help="write OUT/index.html over its studies")
    ap.add_argument("--out", help="report folder (default: DIR/report)")
    ap.add_argument("--max-run-plots", type=int, default=30, metavar="N",
                    help="plug-ins draw the histories of at most N runs (default 30)")
    args = ap.parse_args(argv)
    named = [(t, x) for t, x in (("DIR", args.dir), ("--study", args.study),
                                 ("--index", args.index)) if x]
    if len(named) != 1:
        ap.error((" and ".join(f"{t} {x}" for t, x in named) + ": " if named else "")
                 + "give one of DIR, --study STUDY_OUT, --index OUT")
    given = [x for _, x in named]
    if args.index and args.out:
        ap.error("--out does not go with --index (the index is OUT/index.html)")
    if args.max_run_plots < 0:
        ap.error(f"--max-run-plots {args.max_run_plots}: must be 0 or more")
    folder = given[0]
    if not os.path.isdir(folder):
        print(f"make_report: {folder}: no such folder", file=sys.stderr)
        return 2
    stamp = now()
    try:
        if args.index:
            path, rows = write_index(folder, stamp)
            print(f"make_report: {path}: {len(rows)} studies")
        elif args.study or is_study(folder):
            if not is_study(folder):
                print(f"make_report: {folder}: no study.json (not a study's output folder)",
                      file=sys.stderr)
                return 2
            _done(*study_page(folder, args.out, args.max_run_plots, stamp))
        elif study_dirs(folder):
            if args.out:
                ap.error("--out does not go with a folder of studies (each page is "
                         "STUDY/report/, the index OUT/index.html)")
            for d in study_dirs(folder):
                _done(*study_page(d, None, args.max_run_plots, stamp))
            path, rows = write_index(folder, stamp)
            print(f"make_report: {path}: {len(rows)} studies")
        else:
            _done(*sweep_page(folder, args.out, stamp))
    except LayoutError as e:
        print(f"make_report: {e}", file=sys.stderr)
        return 2
    except (FileNotFoundError, ValueError) as e:
        print(f"make_report: {e}", file=sys.stderr)
        return 2
    except PermissionError as e:
        print(f"make_report: cannot write the report: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
