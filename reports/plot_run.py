#!/usr/bin/python3
"""One run's history.csv as one PNG of small multiples: energies with the energy balance,
contact forces, the largest penetration and the probes' displacements (docs/report.md,
"plot_run.py"). The same figure as each run's in the sweep report.

    /usr/bin/python3 reports/plot_run.py RUN_DIR [--out PNG]

RUN_DIR    a run's output folder (`ricochet run ... --out RUN_DIR`, or a sweep's
           DIR/runs/<group>/<run>/): its history.csv, and summary.json for the title if present.
--out PNG  the figure to write (default RUN_DIR/history.png).
Exit status: 0 written; 2 bad input (no history.csv, a malformed one, a bad option): one line on
stderr; 1 the PNG could not be written.
"""

import argparse
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

from report_io import fmt_dt, read_history, scheme_name  # noqa: E402


class OneLineParser(argparse.ArgumentParser):
    def error(self, message):
        self.exit(2, f"{self.prog}: {message} (--help for the options)\n")


def title_of(run_dir, summary):
    """'<folder>   (case, scheme, mesh, Δt = …, status)' from summary.json when present."""
    name = os.path.normpath(os.path.abspath(run_dir))
    parts = os.path.basename(name)
    if os.path.basename(os.path.dirname(name)) not in ("", "runs"):
        parts = os.path.basename(os.path.dirname(name)) + "/" + parts
    if not summary:
        return parts
    info = [str(summary.get("case") or ""), scheme_name(str(summary.get("scheme") or "")),
            str(summary.get("mesh") or "")]
    dt = summary.get("dt")
    if isinstance(dt, (int, float)):
        info.append(f"Δt = {fmt_dt(float(dt))} s" + (" (auto)" if summary.get("dt_mode") ==
                                                     "auto" else ""))
    status = summary.get("status")
    if status and status != "ok":
        info.append(str(status))
    info = [x for x in info if x]
    return parts + (f"   ({', '.join(info)})" if info else "")


def main(argv=None):
    ap = OneLineParser(prog="plot_run.py", description=__doc__.split("\n\n")[0])
    ap.add_argument("run_dir", metavar="RUN_DIR", help="a run's output folder (history.csv)")
    ap.add_argument("--out", metavar="PNG", help="output PNG (default RUN_DIR/history.png)")
    args = ap.parse_args(argv)
    path = os.path.join(args.run_dir, "history.csv")
    if not os.path.isfile(path):
        what = "no such folder" if not os.path.isdir(args.run_dir) else "no history.csv"
        print(f"plot_run: {args.run_dir}: {what} (give a run's output folder, which holds "
              "history.csv)", file=sys.stderr)
        return 2
    try:
        h = read_history(path, strict=True)
    except ValueError as e:
        print(f"plot_run: {e}", file=sys.stderr)
        return 2
    if "time" not in h:
        print(f"plot_run: {path}: no `time` column (not a ricochet history.csv)",
              file=sys.stderr)
        return 2
    try:
        with open(os.path.join(args.run_dir, "summary.json")) as f:
            summary = json.load(f)
        if not isinstance(summary, dict):
            summary = {}
    except (OSError, ValueError):
        summary = {}
    out = args.out or os.path.join(args.run_dir, "history.png")
    if not out.lower().endswith(".png"):
        print(f"plot_run: --out {out}: the figure is a PNG; give a name ending in .png",
              file=sys.stderr)
        return 2
    import report_figures as F  # matplotlib only once the input is known to be good
    try:
        e0 = summary.get("initial_energy")
        F.fig_run_history(out, h, title_of(args.run_dir, summary),
                          e0=float(e0) if isinstance(e0, (int, float)) else None)
    except OSError as e:
        print(f"plot_run: cannot write {out}: {e.strerror or e}", file=sys.stderr)
        return 1
    print(f"plot_run: {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
