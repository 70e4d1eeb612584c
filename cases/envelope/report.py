"""The stability envelope's page (cases/envelope/study.toml, docs/stability.md): the plug-in
for what its layout's data kinds cannot say (docs/studies.md, Writing a plug-in).

The sweep: one row per stability search (`kind` = `stability`: `stable_dt`, `unstable_dt`,
`estimate_dt`, `stable_over_estimate`, `outcome`, `unstable_reason`) and the remedy runs
(`kind` = `run`). `envelope` gives two sections: the envelope figure (largest stable step /
estimate against each parameter, per scheme) with a table of counts per group, and the table
of the points where the default automatic step is not stable, with the remedy runs. Rows that
failed or have empty cells are tabled as such, never a crash."""

import json
import math
import os

from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.ticker import FuncFormatter, LogLocator, NullLocator
from report_figures import SERIES_COLORS, color, plt, save
from report_io import Sweep, fmt_dt, fmt_g, fnum, read_case, resolve_case_file, scheme_name
from report_page import Section, unavailable

ENV_CMD = ("build/ricochet sweep cases/envelope/sweep_full.toml --out results/envelope "
           "--jobs 2 --check cases/envelope/gates_full.toml")
SAFETY = 0.9          # time.safety's default: the automatic step is 0.9 x the estimate
SCHEMES = ("semi_explicit", "explicit_penalty", "implicit")

MATERIALS = {"saint_venant_kirchhoff": "St Venant–Kirchhoff", "neo_hookean": "neo-Hookean",
             "mooney_rivlin": "Mooney–Rivlin", "blatz_ko": "Blatz–Ko"}
def _get(d, *keys):
    for k in keys:
        if not isinstance(d, (dict, list)):
            return None
        try:
            d = d[k]
        except (KeyError, IndexError, TypeError):
            return None
    return d


def _num(x):
    if isinstance(x, bool):
        return None
    if isinstance(x, (int, float)):
        return float(x)
    return fnum(x)


class EnvPoint:
    """One search (or remedy run) of the envelope sweep with its parameters, read from the
    run's case file with its overrides applied (summary.csv `case_file`, `overrides`), so that
    a key the group does not set has the case's own value."""

    _cases = {}

    def __init__(self, run):
        self.run = run
        row = run.row
        self.id = run.id
        self.group = run.group
        self.kind = run.kind
        self.status = run.status or "missing"
        self.scheme = run.scheme
        try:
            self.overrides = json.loads(row.get("overrides") or "[]")
            if not isinstance(self.overrides, list):
                self.overrides = []
        except ValueError:
            self.overrides = []
        self.override_keys = [o.split("=", 1)[0].strip() for o in self.overrides
                              if isinstance(o, str)]
        case = self._case(row.get("case_file"), tuple(str(o) for o in self.overrides))
        mesh = row.get("mesh") or case.get("mesh") or ""
        body = _get(case, "bodies", 0) or {}
        mat = body.get("material") or {}
        v = body.get("velocity")
        try:
            self.speed = float(math.hypot(float(v[0]), float(v[1])))
        except (TypeError, ValueError, IndexError):
            self.speed = None
        self.friction = _num(_get(case, "obstacles", 0, "friction"))
        self.model = mat.get("model") or ""
        self.plane = case.get("plane") or ""
        self.nu = _num(mat.get("poisson"))
        if self.model == "mooney_rivlin":
            c10, c01, k = (_num(mat.get(x)) for x in ("c10", "c01", "bulk_modulus"))
            if c10 is not None and c01 is not None and k:
                mu = 2 * (c10 + c01)
                self.nu = (3 * k - 2 * mu) / (2 * (3 * k + mu))
        meshd = _get(case, "meshes", mesh) or {}
        self.distort = _num(meshd.get("distort")) or 0.0
        self.tri = meshd.get("cells") == "tri"
        self.element = body.get("element") or row.get("element") or ""
        self.hourglass = _get(body, "hourglass", "form") or ""
        self.level = _get(case, "contact", "level") or "position"
        self.safety = _num(_get(case, "time", "safety")) or SAFETY
        # the search's columns
        self.stable = fnum(row.get("stable_dt"))
        self.unstable = fnum(row.get("unstable_dt"))
        self.estimate = fnum(row.get("estimate_dt"))
        self.ratio = fnum(row.get("stable_over_estimate"))
        if self.ratio is None and self.stable and self.estimate:
            self.ratio = self.stable / self.estimate
        self.outcome = row.get("outcome") or ""
        self.reason = row.get("unstable_reason") or ""

    @classmethod
    def _case(cls, case_file, overrides):
        key = (case_file, overrides)
        if key not in cls._cases:
            path = resolve_case_file(case_file)
            try:
                # without the case file, the overrides alone (applied to an empty case)
                cls._cases[key] = read_case(path or os.devnull, overrides)
            except (OSError, ValueError):
                cls._cases[key] = read_case(os.devnull, overrides)
        return cls._cases[key]

    # -- what the search says about the default automatic step
    @property
    def searched(self):
        return self.kind == "stability" and self.status == "ok" and bool(self.outcome)

    @property
    def unsafe(self):
        """The automatic step (safety x the estimate) is not stable: no stable step at all, or
        the largest stable step is below safety x the estimate."""
        if not self.searched:
            return False
        if self.outcome == "no_stable_down_to_floor":
            return True
        return self.ratio is not None and self.ratio < self.safety

    @property
    def safe(self):
        return self.searched and not self.unsafe and self.ratio is not None

    # -- labels
    def material_label(self, nu=True):
        name = MATERIALS.get(self.model, self.model or "?")
        if self.model == "mooney_rivlin" and nu:
            parts = [name]
            if self.nu is not None:
                parts.append(f"ν = {self.nu:.2f}")
            if self.plane:
                parts.append(f"plane {self.plane}")
            return ", ".join(parts)
        return name

    def element_label(self):
        if self.tri:
            return "T3"
        if self.element == "q4_hourglass":
            return f"Q4 1-point, {self.hourglass or 'viscous'} hourglass"
        return {"q4": "Q4 (2×2)", "t3": "T3"}.get(self.element, self.element or "?")

    @property
    def short_id(self):
        return _short(self.id)

    def speed_label(self):
        return f"{self.speed:.3g} m/s" if self.speed is not None else "?"

    def params(self):
        """The parameters this point sets (its group's keys), as text."""
        keys = " ".join(self.override_keys)
        out = []
        if self.speed is not None:
            out.append(f"v = {self.speed_label()}")
        if "friction" in keys or self.family in ("speed", "contact"):
            out.append(f"μ = {fmt_g(self.friction)}")
        out.append(self.material_label())
        if "distort" in keys or "element" in keys or "cells" in keys:
            out.append(f"{self.element_label()}, distortion {fmt_g(self.distort)}")
        if "contact.level" in keys:
            out.append(f"contact level {self.level}")
        if "dt_update_interval" in keys:
            out.append("Δt recomputed every step")
        return ", ".join(out)

    @property
    def family(self):
        keys = " ".join(self.override_keys)
        if "contact.level" in keys:
            return "contact"
        if ".distort" in keys or "meshes." in keys and ".cells" in keys:
            return "element"
        return "speed"

    def same_point(self, other):
        """The same scheme and physical parameters (the remedy run against its search)."""
        return (self.scheme == other.scheme and self.model == other.model
                and self.plane == other.plane and _close(self.speed, other.speed)
                and _close(self.friction, other.friction) and _close(self.nu, other.nu)
                and _close(self.distort, other.distort) and self.tri == other.tri
                and self.element == other.element and self.level == other.level)


def _short(run_id):
    """`<group>/<index>`: a sweep's run id without its slug (the other columns say it)."""
    head, _, _ = run_id.partition("-")
    return head if "/" in head else run_id


def _close(a, b):
    if a is None or b is None:
        return a is None and b is None
    return abs(a - b) <= 1e-6 * max(abs(a), abs(b), 1e-12)


def _marker_kind(p):
    if p.outcome == "no_stable_down_to_floor":
        return "floor"
    if p.ratio is None:
        return None
    if p.outcome == "no_unstable_up_to_cap":
        return "cap"
    if p.outcome == "bracketed":
        return "bracketed"
    return "lower"      # run_limit: the largest stable step found, the bracket not converged


def _family_rows(points):
    """The figure's rows: (title, x label, [x tick labels], [series: (label, [(x index,
    point)])])."""
    rows = []

    def build(title, xlabel, pts, xkey, xfmt, skey):
        if not pts:
            return
        xs = sorted({xkey(p) for p in pts if xkey(p) is not None})
        if not xs:
            return
        names = []
        for p in pts:
            if skey(p) not in names:
                names.append(skey(p))
        series = [(n, [(xs.index(xkey(p)), p) for p in pts if skey(p) == n
                       and xkey(p) is not None]) for n in names]
        rows.append((title, xlabel, [xfmt(x) for x in xs], series))

    speed = [p for p in points if p.family == "speed"]
    spd = lambda p: None if p.speed is None else round(p.speed, 3)  # noqa: E731
    svk = [p for p in speed if p.model in ("saint_venant_kirchhoff", "")]
    if len({p.friction for p in svk}) > 1:
        build("impact speed × friction, St Venant–Kirchhoff", "impact speed (m/s)", svk, spd,
              lambda x: f"{x:.3g}", lambda p: f"μ = {fmt_g(p.friction)}")
    mu0 = min((p.friction for p in speed if p.friction is not None), default=None)
    mats = [p for p in speed if p.friction == mu0]
    build("impact speed × material" + (f", μ = {fmt_g(mu0)}" if mu0 is not None else ""),
          "impact speed (m/s)", mats, spd, lambda x: f"{x:.3g}", lambda p: p.material_label())
    elem = [p for p in points if p.family == "element"]
    build("mesh distortion × element, paper's speed", "mesh distortion (fraction of the "
          "element size)", elem, lambda p: p.distort, lambda x: f"{x:g}",
          lambda p: p.element_label())
    cont = [p for p in points if p.family == "contact"]
    build("contact level × friction × speed", "friction coefficient μ", cont,
          lambda p: p.friction, lambda x: fmt_g(x),
          lambda p: f"{p.level} level, v = {p.speed_label()}")
    return rows


def read_envelope(folder):
    """(Sweep, [EnvPoint]) of an envelope sweep folder, or (None, reason)."""
    try:
        sw = Sweep(folder)
    except (OSError, ValueError) as e:
        return None, str(e)
    return sw, [EnvPoint(r) for r in sw.runs]


def _ratio_text(p):
    if p.outcome == "no_stable_down_to_floor":
        return "no stable Δt"
    return fmt_g(p.ratio, 3) if p.ratio is not None else "–"


def envelope_sections(ctx, Section):
    """The envelope figure and the table of unsafe points, or two "not available" sections."""
    fig = Section("envelope", "Stability envelope: largest stable Δt / estimate against the "
                  "parameters (beyond the paper)", "figure")
    tab = Section("envelope_unsafe", "Stability envelope: where the default automatic Δt is "
                  "not stable, and the remedy runs (beyond the paper)", "table")
    env = ctx.get("env")
    if env is None:
        return unavailable([fig, tab], "no stability-envelope sweep", ctx.get("env_err"), ENV_CMD)
    sw, points = env
    searches = [p for p in points if p.kind == "stability"]
    done = [p for p in searches if p.searched]
    if not done:
        for s in (fig, tab):
            s.available = False
            s.missing = (f"the sweep {sw.dir} has no finished stability search (rows with "
                         "`kind` = `stability`, `status` ok and an `outcome`). "
                         f"Run `{ENV_CMD}`.")
        return [fig, tab]
    failed = [p for p in searches if not p.searched]
    safety = sorted({p.safety for p in done})
    sf = safety[0] if len(safety) == 1 else SAFETY
    schemes = [s for s in SCHEMES if any(p.scheme == s for p in done)]
    schemes += sorted({p.scheme for p in done} - set(schemes))

    # ---- counts per scheme (caption) and per group and scheme (table under the figure)
    def counts(ps):
        return (len(ps), sum(p.safe for p in ps), sum(p.unsafe for p in ps),
                sum(p.outcome == "no_stable_down_to_floor" for p in ps),
                sum(p.outcome == "no_unstable_up_to_cap" for p in ps))

    per_scheme = []
    for sc in schemes:
        n, ok, bad, floor, cap = counts([p for p in done if p.scheme == sc])
        ps = [p for p in done if p.scheme == sc and p.ratio is not None
              and p.outcome == "bracketed"]
        lo = min(ps, key=lambda p: p.ratio) if ps else None
        per_scheme.append(
            f"{scheme_name(sc)}: {n} searches, {ok} safe, {bad} not"
            + (f" ({floor} without any stable Δt)" if floor else "")
            + (f", {cap} stable up to the cap" if cap else "")
            + (f"; smallest bracketed ratio {lo.ratio:.3g} ({lo.params()})" if lo else ""))
    rows = []
    groups = []
    for p in done:
        if p.group not in groups:
            groups.append(p.group)
    for g in groups:
        for sc in schemes:
            ps = [p for p in done if p.group == g and p.scheme == sc]
            if not ps:
                continue
            n, ok, bad, floor, cap = counts(ps)
            rs = [p.ratio for p in ps if p.ratio is not None]
            rows.append([f"`{g}`", scheme_name(sc), str(n), str(ok), str(bad), str(floor),
                         str(cap), fmt_g(min(rs)) if rs else "–",
                         fmt_g(max(rs)) if rs else "–"])
    fig.extra.append(("envelope_counts", "Searches per group and scheme: how many leave the "
                      f"default automatic step ({sf:g} × the estimate) stable",
                      ["group", "scheme", "searches", f"safe (ratio ≥ {sf:g})", "not safe",
                       "of which no stable Δt", "stable up to the cap",
                       "smallest stable / estimate", "largest stable / estimate"], rows))

    # ---- the figure
    frows = _family_rows(done)
    n_all, n_safe, n_bad = len(done), sum(p.safe for p in done), sum(p.unsafe for p in done)
    if frows:
        fig.files = fig_envelope(ctx["out"], "stability_envelope", frows, schemes, sf)
    fig.sources = [sw.dir]
    fig.runs = [p.id for p in done]
    drawn = {id(p) for _, _, _, ser in frows for _, pts in ser for _, p in pts}
    not_drawn = [p for p in done if id(p) not in drawn]
    fig.caption = (
        "Each point is one `ricochet stability` search of the sweep, every row with `kind` = "
        "`stability` and `status` = `ok` (docs/stability.md: bisection over whole runs; "
        "cases/envelope/sweep_full.toml searches the oblique plate on M1 with energy bound 1, so "
        "that only a blow-up, an inverted element or energy growth counts as unstable): the "
        "largest stable fixed Δt over the estimate min L_e/c_p (`stable_over_estimate` of "
        "summary.csv), on a log scale. One column per scheme, one row per parameter family; "
        "colours tell the series "
        "of a row apart (legend on the right), points of one x are spread sideways. Filled "
        "circle: bracketed; open triangle: stable up to the search cap (the implicit scheme; "
        "drawn at the cap, a lower bound); "
        + ("open circle: the search stopped at its run limit (a lower bound); "
           if any(_marker_kind(p) == "lower" for p in done) else "")
        + "down-triangle in the grey band at the bottom: no stable Δt down to the floor "
        "(estimate / 1000: every step tried diverges; the table of unsafe points says why). "
        "The dashed "
        f"line is the automatic step, `time.safety` = {sf:g} × the estimate: a point below it "
        "(the shaded region) means that the default `time.dt = \"auto\"` is not stable there. "
        f"{n_all} searches: {n_safe} leave the automatic step stable, {n_bad} do not. "
        + "; ".join(per_scheme) + ". "
        + (f"Searches that failed or have no outcome (not counted): "
           f"{', '.join(f'`{p.id}`' for p in failed)}. " if failed else "")
        + (f"Not drawn (no row of the figure): {', '.join(f'`{p.id}`' for p in not_drawn)}. "
           if not_drawn else "")
        + f"Source: `{sw.dir}` (sweep `{sw.name}`, summary.csv), one run folder per search "
        "under `runs/`; the table below gives the counts per group.")
    if not frows:
        fig.available = False
        fig.missing = (f"no search of {sw.dir} has a parameter this figure draws (speed, "
                       f"friction, material, element, distortion, contact level). Run `{ENV_CMD}`.")

    # ---- the unsafe points
    tab.sources = [sw.dir]
    tab.header = ["run", "scheme", "parameters", "stable / estimate",
                  f"margin (ratio / {sf:g})", "outcome",
                  "why the smallest unstable Δt failed"]
    bad = [p for p in done if p.unsafe]
    for p in bad:
        outcome = (f"none stable down to the floor, {fmt_dt(p.unstable)} s"
                   if p.outcome == "no_stable_down_to_floor" and p.unstable else p.outcome)
        tab.rows.append([
            f"`{p.short_id}`", scheme_name(p.scheme), p.params(), _ratio_text(p),
            fmt_g(p.ratio / p.safety, 3) if p.ratio is not None else "–", outcome,
            (p.reason.replace("diverged: ", "") or "–")[:160]])
        tab.runs.append(p.id)
    # remedy runs: rows of kind run, each beside the search at the same point
    remedies = [p for p in points if p.kind == "run"]
    rrows = []
    for p in remedies:
        r = p.run
        match = next((q for q in done if q.same_point(p)), None)
        dmin, dmax = r.num("dt_min"), r.num("dt_max")
        steps = r.num("steps")
        upd = r.get("dt_update_interval") or r.get("time.dt_update_interval") or "?"
        status = "ok" if p.status == "ok" else (
            f"**{p.status}**" + (f" at t = {fmt_dt(r.num('diverged.time'))} s"
                                 if r.num("diverged.time") is not None else "")
            + (f": {r.reason[:160]}" if r.reason else ""))
        rrows.append([
            f"`{p.short_id}`", scheme_name(p.scheme),
            p.params().replace(", Δt recomputed every step", ""), status,
            (f"{fmt_dt(dmin)} – {fmt_dt(dmax)}" if dmin and dmax else fmt_dt(r.dt))
            + (" (every step)" if upd == "1" else f" (every {upd} steps)"),
            f"{steps:.0f}" if steps is not None else "–",
            f"{100 * r.num('energy_error_max'):.3g} %" if r.num("energy_error_max") is not None
            else "–",
            (f"{_ratio_text(match)} (`{match.short_id}`)" if match else
             "no search at this point")])
    if remedies:
        ok = sum(p.status == "ok" for p in remedies)
        tab.extra.append(("envelope_remedy", "Remedy runs: the automatic step recomputed from "
                          "the current configuration (`time.dt_update_interval`), at points "
                          f"where the step fixed at t = 0 is not stable: {ok} of "
                          f"{len(remedies)} ok",
                          ["run", "scheme", "parameters", "status", "Δt min – max (s), "
                           "recomputed", "steps", "energy_error_max",
                           "the search at the same point: stable / estimate"], rrows))
        tab.runs += [p.id for p in remedies]
    floors = sum(p.outcome == "no_stable_down_to_floor" for p in bad)
    limited = [p for p in bad if p.outcome == "run_limit"]
    tab.caption = (
        f"Every search of the envelope sweep whose largest stable Δt is below the automatic "
        f"step, `time.safety` × the estimate ({sf:g} ×; stable / estimate < {sf:g}), or that "
        f"found no stable Δt at all (`no_stable_down_to_floor`): {len(bad)} of {n_all} searches"
        + (f", {floors} of them without any stable Δt" if floors else "") + ". "
        f"Margin = (stable / estimate) / {sf:g}: below 1 the default automatic step "
        "diverges; the largest safe `time.safety` there is the ratio itself. "
        "The last column is the reason the smallest unstable trial stopped (summary.csv "
        "`unstable_reason`). "
        + (f"{len(limited)} of these searches stopped at their run limit, so their ratio is a "
           "lower bound. " if limited else "")
        + ("The table under it gives the remedy runs (`kind` = `run`): status, the range of "
           "the recomputed step, and the search at the same parameters. " if remedies else
           "The sweep has no remedy runs (groups `remedy_*`). ")
        + f"Source: `{sw.dir}` (summary.csv). Runs: the run column gives `<group>/<index>`, the "
        "run id without its slug (the folder `runs/<group>/<index>-<slug>`).")
    return [fig, tab]



def fig_envelope(outdir, stem, rows, schemes, safety):
    """The stability envelope: rows = [(title, x label, [x tick labels], [(series label,
    [(x index, point)])])], each point with .scheme, .ratio (largest stable Δt / estimate) and
    .outcome; one column per scheme (log y axis shared down the column), one row per parameter
    family. Bracketed: filled circle; up to the cap: open up-triangle at the value; run limit:
    open circle; no stable Δt: down-triangle in a band at the bottom. The automatic step
    (safety × the estimate) is a dashed line, the region below it shaded."""
    nr, nc = len(rows), len(schemes)
    fig, axes = plt.subplots(nr, nc, figsize=(3.4 * nc + 2.5, 2.55 * nr + 0.8), squeeze=False,
                             sharey="col")
    # y range per column: every ratio drawn, the safety line and 1
    for j, sc in enumerate(schemes):
        vals = [p.ratio for _, _, _, ser in rows for _, pts in ser for _, p in pts
                if p.scheme == sc and p.ratio is not None
                and p.outcome != "no_stable_down_to_floor"]
        lo = min(vals + [safety, 1.0])
        hi = max(vals + [safety, 1.0])
        axes[0][j].set_yscale("log")
        # room at the bottom for the band of "no stable Δt"
        axes[0][j].set_ylim(lo / 2.6, hi * 1.6)
        # labelled ticks at 1, 2, 5 x 10^k over a narrow range, at the decades over a wide one
        subs = (1.0, 2.0, 5.0) if hi / lo < 300 else (1.0,)
        axes[0][j].yaxis.set_major_locator(LogLocator(base=10, subs=subs))
        axes[0][j].yaxis.set_minor_locator(NullLocator())
    for i, (title, xlabel, ticks, series) in enumerate(rows):
        nser = max(1, len(series))
        width = min(0.7, 0.16 * nser)
        for j, sc in enumerate(schemes):
            ax = axes[i][j]
            ax.axhline(safety, color="k", ls="--", lw=1.1, zorder=2)
            ax.axhline(1.0, color="0.55", ls=":", lw=0.9, zorder=2)
            ax.axhspan(1e-12, safety, color="#d62728", alpha=0.06, lw=0, zorder=0)
            ax.axhspan(1e-12, ax.get_ylim()[0] * 1.28, color="0.85", lw=0, zorder=1)
            ax.set_xticks(range(len(ticks)))
            ax.set_xticklabels(ticks)
            ax.set_xlim(-0.6, len(ticks) - 0.4)
            any_pt = False
            for k, (label, pts) in enumerate(series):
                c = SERIES_COLORS[k % len(SERIES_COLORS)]
                off = (k - (nser - 1) / 2) * (width / max(1, nser - 1)) if nser > 1 else 0.0
                mine = sorted([(x, p) for x, p in pts if p.scheme == sc], key=lambda t: t[0])
                line = [(x + off, p.ratio) for x, p in mine
                        if p.ratio is not None and p.outcome != "no_stable_down_to_floor"]
                if len(line) > 1:
                    ax.plot(*zip(*line), color=c, lw=0.9, alpha=0.55, zorder=3)
                for x, p in mine:
                    any_pt = True
                    xo = x + off
                    if p.outcome == "no_stable_down_to_floor":
                        ax.plot(xo, ax.get_ylim()[0] * 1.13, marker="v", ms=6, color=c,
                                ls="none", zorder=4, clip_on=False)
                    elif p.ratio is None:
                        continue
                    elif p.outcome == "no_unstable_up_to_cap":
                        ax.plot(xo, p.ratio, marker="^", ms=7, mfc="white", mec=c, mew=1.5,
                                ls="none", zorder=4)
                    elif p.outcome == "bracketed":
                        ax.plot(xo, p.ratio, marker="o", ms=5.5, color=c, ls="none", zorder=4)
                    else:
                        ax.plot(xo, p.ratio, marker="o", ms=6, mfc="white", mec=c, mew=1.3,
                                ls="none", zorder=4)
            if not any_pt:
                ax.text(0.5, 0.5, "no search of this scheme" + (
                    "\n(the penalty scheme has no contact level)"
                    if sc == "explicit_penalty" and "contact level" in title else ""),
                    ha="center", va="center", transform=ax.transAxes, color="0.4", fontsize=8.5,
                    bbox=dict(facecolor="white", edgecolor="none", alpha=0.9))
            ax.set_title(title, fontsize=9)
            if i == 0:   # the column's scheme, above its first panel
                ax.text(0.5, 1.16, scheme_name(sc), transform=ax.transAxes, ha="center",
                        va="bottom", fontsize=11.5, fontweight="bold", color=color(sc))
            ax.set_xlabel(xlabel, fontsize=8.5)
            ax.grid(True, which="major", axis="y", alpha=0.3)
            ax.grid(False, axis="x")
            if j == 0:
                ax.set_ylabel("largest stable Δt / estimate")
        handles = [Line2D([0], [0], color=SERIES_COLORS[k % len(SERIES_COLORS)], marker="o",
                          ms=5.5, lw=0.9, label=lab) for k, (lab, _) in enumerate(series)]
        axes[i][-1].legend(handles=handles, loc="center left", bbox_to_anchor=(1.03, 0.5),
                           frameon=False, fontsize=8)
    for ax in axes.flat:
        ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    outcomes = {p.outcome for _, _, _, ser in rows for _, pts in ser for _, p in pts}
    handles = [Line2D([0], [0], marker="o", color="0.3", ls="none", ms=5.5, label="bracketed")]
    if "no_unstable_up_to_cap" in outcomes:
        handles.append(Line2D([0], [0], marker="^", mfc="white", mec="0.3", mew=1.5, ls="none",
                              ms=7, label="stable up to the search cap (drawn at the cap)"))
    if outcomes - {"bracketed", "no_unstable_up_to_cap", "no_stable_down_to_floor"}:
        handles.append(Line2D([0], [0], marker="o", mfc="white", mec="0.3", mew=1.3, ls="none",
                              ms=6, label="search stopped at its run limit (lower bound)"))
    handles += [
        Line2D([0], [0], marker="v", color="0.3", ls="none", ms=6,
               label="no stable Δt down to the floor (grey band)"),
        Line2D([0], [0], color="k", ls="--", lw=1.1,
               label=f"automatic step: time.safety = {safety:g} × estimate"),
        Line2D([0], [0], color="0.55", ls=":", lw=0.9, label="the estimate min L_e/c_p"),
        Patch(facecolor="#d62728", alpha=0.12, label="automatic step not stable"),
    ]
    fig.tight_layout(h_pad=1.2, w_pad=0.8)
    fig.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, 0.0), ncol=4,
               frameon=False, fontsize=8.5)
    return save(fig, outdir, stem)


# ---------------------------------------------------------------------------------------------
# The plug-in's entry

def envelope(ctx, section):
    """The envelope figure and the table of unsafe points of the layout's sweep."""
    sw = ctx.sweep(section["sweep"])
    return envelope_sections({"out": ctx.out, "env": (sw, [EnvPoint(r) for r in sw.runs])},
                             Section)
