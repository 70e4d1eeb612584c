"""The figures of the `metric` and `histories` kinds (report_kinds.py): plain line plots of
summary.csv and history.csv columns, one colour per series."""

import report_figures as F
from report_io import fnum, scheme_name

MAX_LINES = 12   # histories: at most this many runs overlaid (a legend beyond is unreadable)
COLORS = ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2",
          "#17becf", "#bcbd22", "#7f7f7f", "#393b79", "#637939"]
MARKERS = ["o", "s", "^", "D", "v", "P", "X", "*"]


def _series_color(name, k):
    return F.SCHEME_COLORS.get(name) or COLORS[k % len(COLORS)]


def fig_metric(outdir, stem, series, x, y, by, logx, logy):
    """series = {by value: [(x text, y, run id)]}: y against x, one line per series, points in
    x order. Numeric x on a linear or log axis; any other x (mesh names) as categories in
    their first order."""
    plt = F.plt
    numeric = all(fnum(p[0]) is not None for pts in series.values() for p in pts)
    cats = list(dict.fromkeys(p[0] for pts in series.values() for p in pts))
    fig, ax = plt.subplots(figsize=(8.5, 4.6))
    for k, (name, pts) in enumerate(series.items()):
        if numeric:
            pts = sorted(pts, key=lambda p: fnum(p[0]))
            xs = [fnum(p[0]) for p in pts]
        else:
            pts = sorted(pts, key=lambda p: cats.index(p[0]))
            xs = [cats.index(p[0]) for p in pts]
        label = (scheme_name(name) if by == "scheme" else f"{by} = {name}") if by else y
        ax.plot(xs, [p[1] for p in pts], marker=MARKERS[k % len(MARKERS)], ms=5, lw=1.3,
                color=_series_color(name, k), label=label)
    if not numeric:
        ax.set_xticks(range(len(cats)))
        ax.set_xticklabels(cats)
    if logx and numeric:
        ax.set_xscale("log")
    if logy:
        ax.set_yscale("log")
    ax.set_xlabel(x)
    ax.set_ylabel(y)
    ax.grid(True, alpha=0.3, which="both")
    if by or len(series) > 1:
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=4, frameon=False)
    fig.tight_layout()
    return F.save(fig, outdir, stem)


def fig_histories(outdir, stem, runs, ys):
    """One panel per history column in ys, one line per run against time (ms)."""
    plt = F.plt
    n = len(ys)
    fig, axes = plt.subplots(n, 1, figsize=(9, 2.6 * n + 0.8), sharex=True, squeeze=False)
    for k, r in enumerate(runs):
        h = r.history()
        t = h["time"] * 1e3
        for ax, y in zip(axes[:, 0], ys):
            if y in h:
                ax.plot(t, h[y], lw=1.1, color=COLORS[k % len(COLORS)],
                        label=r.id if ax is axes[0, 0] else None)
    for ax, y in zip(axes[:, 0], ys):
        ax.set_ylabel(y)
        ax.grid(True, alpha=0.3)
        F.plain_axis(ax)
    axes[-1, 0].set_xlabel("time t (ms)")
    fig.legend(loc="lower center", ncol=min(3, len(runs)), frameon=False, fontsize=8)
    fig.tight_layout(rect=(0, 0.04 + 0.025 * ((len(runs) + 2) // 3), 1, 1))
    return F.save(fig, outdir, stem)
