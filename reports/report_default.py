"""The default page of a sweep (docs/report.md, The default page): for a plain sweep folder, or
a study without a `[report]` layout. The runs table from the sweep's swept keys, then one
`metric` figure per swept key: energy_error_max against it, one line per value of the other
swept key when there is exactly one other. Nothing else: no study's own sections."""

import os

import report_kinds as RK
from report_select import as_number, swept_keys, value

DEFAULT_Y = "energy_error_max"


class SweepContext:
    """The part of a study's context (report_study.StudyContext) the data kinds use, for a
    sweep on its own: gates from the sweep's own gates-junit.xml."""

    def __init__(self, out, sweep):
        self.out, self._sweep, self.max_run_plots = out, sweep, 30

    def sweep(self, _name):
        return self._sweep

    def sweep_entry(self, _name):
        return {}

    def gates_file(self, _name):
        return None


def default_sections(ctx, sweep, name):
    """[Section]: the runs table and the metric figures of one sweep."""
    keys = swept_keys(sweep)
    sid = "".join(c if c.isalnum() else "_" for c in name)
    out = RK.runs_table(ctx, {"sweep": name}, sweep, f"{sid}_runs")
    for k, key in enumerate(keys):
        others = [o for o in keys if o != key]
        xs = [as_number(value(r, key)) for r in sweep.runs]
        xs = [x for x in xs if x is not None]
        # a key swept over decades (a time step) reads best on a log axis
        logx = bool(xs) and min(xs) > 0 and max(xs) / min(xs) >= 50
        sec = {"sweep": name, "x": key, "y": DEFAULT_Y, "logy": True, "logx": logx}
        if len(others) == 1:
            sec["by"] = others[0]
        out += RK.metric(ctx, sec, sweep, f"{sid}_metric_{k}")
    return out


def sweep_page_context(out, sweep):
    return SweepContext(os.path.abspath(out), sweep)
