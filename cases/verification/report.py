"""The verification study's plug-in (cases/verification/study.toml; docs/studies.md, Writing a
plug-in): the analytic cases of this folder (docs/verification.md) run by one sweep, each measured against its reference in reference/verification.toml, for every
run of every scheme.

Adding a case is adding one CaseSpec to CASES below:
  * `case`: the case's name, as in the `case` column of the sweep's summary.csv;
  * `ref`: its table in reference/verification.toml;
  * `quantities`: one Quantity per analytic row: a label (inline Markdown, saying how the
    value is measured), a unit, the reference value's key in that table (or a function of the
    table, for a derived value), and a function (run, reference table) -> measured value or None
    that reads the run's summary.csv row / summary.json / history.csv;
  * `figure`: a function (outdir, stem, runs, reference table) -> (files, caption text) drawing
    the reference beside the runs' histories (the fig_ver_* functions below);
  * `pending`: non-empty while the case is not yet in cases/verification/sweep.toml; says what
    is still missing. A case that is not in the sweep gives a "not available" section with the
    command that produces it, never a crash.
Every table then also gets the run id, Δt, energy_error_max and penetration_max of each run.
"""

import math
import os
import tomllib
import traceback
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from typing import Callable, Optional, Union

import numpy as np

from matplotlib.lines import Line2D
from report_figures import _alternates, _running_mean, _styles, ms, plain_axis, plt, save
from report_io import REPO, fmt_dt, scheme_name
from report_page import Section as PageSection
from report_runs import SCHEMES, column_labels, order_runs

REFERENCE_VER = os.path.join(REPO, "reference", "verification.toml")
VER_CMD = ("build/ricochet sweep cases/verification/sweep.toml --out results/verification "
           "--check cases/verification/gates_fast.toml")
PART_TITLE = "Verification cases: analytic reference against the three schemes"


# ---------------------------------------------------------------------------------------------
# The declarative spec

@dataclass
class Quantity:
    label: str                                  # inline Markdown: what and how it is measured
    unit: str                                   # "N", "s", "" ...
    ref: Union[str, Callable, None]             # key in the case's reference table, or fn(table)
    extract: Optional[Callable]                 # fn(run, table) -> float or None
    scale: Union[str, Callable, None] = None    # for a zero reference: the error is relative to it
    scale_label: str = ""                       # "E0", "m v0"
    digits: int = 5                             # significant digits of the measured value


@dataclass
class CaseSpec:
    case: str
    title: str
    ref: str
    quantities: list
    figure: Optional[Callable] = None           # fn(outdir, stem, runs, table) -> (files, caption)
    pending: str = ""                           # not yet in the sweep: what is missing
    notes: str = ""                             # appended to the table caption
    aliases: tuple = ()                         # other case names accepted in the sweep
    groups: tuple = ()                          # only runs of these sweep groups (empty: all)


def ref_value(q_ref, table):
    """(value, key text) of a quantity's reference; value None when the key is missing."""
    if q_ref is None:
        return None, ""
    if callable(q_ref):
        try:
            return q_ref(table), ""
        except KeyError as e:
            return None, f"needs {e.args[0] if e.args else e}"
        except (TypeError, ValueError, ZeroDivisionError) as e:
            return None, f"needs {e}"
    v = table.get(q_ref)
    return (float(v) if isinstance(v, (int, float)) else None), q_ref


# ---------------------------------------------------------------------------------------------
# Extractors: from a run's summary.csv row (flattened summary.json) and history.csv

def col(name):
    """A summary.csv column (summary.json key, nested keys joined by '.')."""
    def get(run, table):
        v = run.num(name)
        if v is None:
            s = run.summary()
            for part in name.split("."):
                s = s.get(part) if isinstance(s, dict) else None
            v = float(s) if isinstance(s, (int, float)) and not isinstance(s, bool) else None
        return v
    return get


def hist(run, name):
    h = run.history()
    if h is None or name not in h or "time" not in h:
        return None, None
    return h["time"], h[name]


def contact_duration_steps(run, table):
    n, dt = col("contact_iterations.steps_with_contact")(run, table), run.dt
    return n * dt if n is not None and dt else None


def plateau_mean(lo=0.025, hi=0.975, duration_key="contact_duration"):
    """Mean of normal_force over [lo, hi] x the analytic contact duration: away from the
    rise and the release of the force."""
    def get(run, table):
        t, f = hist(run, "normal_force")
        d = table.get(duration_key)
        if t is None or not d:
            return None
        m = (t >= lo * d) & (t <= hi * d)
        return float(np.mean(f[m])) if np.any(m) else None
    return get


def impulse(run, table):
    t, f = hist(run, "normal_force")
    return float(np.trapezoid(f, t) if hasattr(np, "trapezoid") else np.trapz(f, t)) \
        if t is not None and len(t) > 1 else None


def velocity_x(run, table):
    """momentum_x / m (the centre-of-mass velocity), m from the reference table."""
    t, p = hist(run, "momentum_x")
    m = table.get("mass")
    return (t, p / m) if t is not None and m else (None, None)


def deceleration(t0, t1):
    def get(run, table):
        t, v = velocity_x(run, table)
        if t is None:
            return None
        m = (t >= t0) & (t <= t1)
        return float(-np.polyfit(t[m], v[m], 1)[0]) if np.count_nonzero(m) >= 3 else None
    return get


def stop_time(threshold):
    def get(run, table):
        t, v = velocity_x(run, table)
        if t is None:
            return None
        below = np.nonzero(np.abs(v) < threshold)[0]
        return float(t[below[0]]) if below.size else None
    return get


def final_ux(probe):
    """u_x of a probe node at the end; without that probe, ∫ momentum_x/m dt."""
    def get(run, table):
        t, u = hist(run, f"{probe}_ux")
        if t is not None:
            return float(u[-1])
        t, v = velocity_x(run, table)
        if t is None:
            return None
        return float(np.sum(0.5 * (v[1:] + v[:-1]) * np.diff(t)))
    return get


def change(name):
    """Last minus first sample of a history column."""
    def get(run, table):
        t, y = hist(run, name)
        return float(y[-1] - y[0]) if t is not None else None
    return get


def impulse_ratio(run, table):
    """|Δp_x| / Δp_y over the run (history momentum_x, momentum_y)."""
    dx, dy = change("momentum_x")(run, table), change("momentum_y")(run, table)
    return abs(dx) / dy if dx is not None and dy else None


def spin_arm(run, table):
    """ΔL / Δp_x over the run: the arm of the friction impulse about the centre (history
    angular_momentum, momentum_x)."""
    dl, dx = change("angular_momentum")(run, table), change("momentum_x")(run, table)
    return dl / dx if dl is not None and dx else None


def first_key(*keys):
    def get(table):
        for k in keys:
            if isinstance(table.get(k), (int, float)):
                return float(table[k])
        raise KeyError(" or ".join(f"`{k}`" for k in keys))
    return get


# ---------------------------------------------------------------------------------------------
# Figures and their caption numbers

def _runs_by_label(runs, labels):
    return [(labels[r.id], r) for r in runs if r.ok and r.history() is not None]


def fig_bar(outdir, stem, runs, table, labels):
    """Contact force per run beside the analytic plateau; momentum_x against -m v0 + F t."""
    ok = _runs_by_label(runs, labels)
    if not ok:
        return [], ""
    force, dur = table.get("contact_force"), table.get("contact_duration")
    m, v0 = table.get("mass"), table.get("v0")

    def p_ref(t):
        if not (force and dur and m and v0):
            return None
        return np.where(t < dur, -m * v0 + force * t, m * v0)
    files = fig_ver_contact_force(outdir, stem, ok, force, dur, p_ref,
                                    "analytic: F = ρcv₀A for 2L/c, then 0",
                                    "analytic: −mv₀ + Ft, then +mv₀")
    return files, (f"Top: the contact force on the wall (`normal_force` of history.csv), one "
                   f"panel per run, against the analytic plateau F = ρcv₀A = {force:g} N for "
                   f"2L/c = {dur * 1e6:g} µs (dashed). Bottom: the bar's momentum_x against the "
                   f"analytic −mv₀ + Ft, which reaches +mv₀ = {m * v0:g} kg·m/s at 2L/c. "
                   "Where the force alternates from one step to the next (the implicit "
                   "scheme's wall contact), the panel also draws its mean over two steps.")


def fig_block(outdir, stem, runs, table, labels):
    ok = _runs_by_label(runs, labels)
    if not ok:
        return [], ""
    v0, a, ts, m = (table.get(k) for k in ("v0", "deceleration", "stop_time", "mass"))
    files = fig_ver_sliding(outdir, stem, [(lab, r, r.history()["time"],
                                               r.history()["momentum_x"] / m) for lab, r in ok],
                              v0, a, ts)
    dev = []
    for lab, r in ok:
        t = r.history()["time"]
        d = np.abs(r.history()["momentum_x"] / m - np.maximum(v0 - a * t, 0.0))
        dev.append(f"{lab} {1e3 * float(np.max(d)):.2g} mm/s")
    return files, (f"Left: the block's centre-of-mass velocity momentum_x/m (m = {m:g} kg) "
                   f"against the analytic v₀ − μgt = {v0:g} − {a:g} t m/s until the stop at "
                   f"v₀/(μg) = {ts:.4g} s (dotted), then 0 (stick). Right: the difference "
                   "from the analytic line, in mm/s: the vibration of the suddenly loaded "
                   "block on the ground, sampled every `output.interval`. Largest: "
                   + ", ".join(dev) + ".")


def fig_disk(outdir, stem, runs, table, labels):
    ok = [(lab, r) for lab, r in _runs_by_label(runs, labels)
          if all(c in r.history() for c in ("momentum_x", "momentum_y", "angular_momentum"))]
    if not ok:
        return [], ""
    mu = table.get("mu")
    files = fig_ver_impulse(outdir, stem, ok, mu)
    left = [r.id for r in runs if r.ok and r.history() is not None
            and r.id not in {x.id for _, x in ok}]
    return files, ("Left: the impulse path, Δp_x against Δp_y from the start of the run "
                   "(history momentum_x, momentum_y)" +
                   (f", beside the analytic |Δp_x| = μ Δp_y, μ = {mu:g} (dashed)" if mu else "") +
                   ". Right: the spin, `angular_momentum` against time." +
                   (" Not drawn (history without momentum_x, momentum_y or angular_momentum): "
                    + ", ".join(f"`{i}`" for i in left) + "." if left else ""))


def fig_head_on(outdir, stem, runs, table, labels):
    ok = _runs_by_label(runs, labels)
    if not ok:
        return [], ""
    force, dur = table.get("contact_force"), table.get("contact_duration")

    def p_ref(t):
        return None  # total momentum: drawn against each run's own initial value
    files = fig_ver_contact_force(outdir, stem, ok, force, dur, p_ref,
                                    "analytic interface force for 2L/c, then 0", None,
                                    conserved=True)
    drift = []
    for lab, r in ok:
        p = r.history()["momentum_x"]
        drift.append(f"{lab} {float(np.max(np.abs(p - p[0]))):.2g}")
    return files, ("Top: the interface force (`normal_force` of history.csv), one panel per "
                   "run" + (f", against the analytic {force:g} N for {dur * 1e6:g} µs"
                            if force and dur else "") +
                   ". Bottom: the change of the total momentum_x from its initial value, "
                   "which must stay 0 (the axis spans at least ±10⁻⁶ of the initial momentum). "
                   "Largest |p_x(t) − p_x(0)| in kg·m/s: " + ", ".join(drift) + ".")


# ---------------------------------------------------------------------------------------------
# The cases

CASES = [
    CaseSpec(
        case="bar_wall", title="Bar on a rigid wall (benchmarks B1, B1a of docs/background.md)",
        ref="bar_wall",
        quantities=[
            Quantity("plateau contact force: mean of `normal_force` over 2.5–97.5 % of 2L/c",
                     "N", "contact_force", plateau_mean()),
            Quantity("contact duration 2L/c: `steps_with_contact` × Δt", "s",
                     "contact_duration", contact_duration_steps),
            Quantity("impulse 2mv₀: ∫ `normal_force` dt (trapezoids over the samples)", "N·s",
                     "impulse", impulse),
            Quantity("rebound momentum +mv₀: final `momentum_x`", "kg·m/s",
                     "final_momentum_x", col("final.momentum_x")),
            Quantity("strain energy after the rebound: final `strain_energy`", "J",
                     "final_strain_energy", col("final.strain_energy"),
                     scale="initial_energy", scale_label="E₀"),
            Quantity("plateau stress ρcv₀: `von_mises_max` over the run (the front overshoots "
                     "it on the lumped-mass mesh)", "Pa", "contact_stress", col("von_mises_max")),
        ],
        figure=fig_bar,
        notes=("The penalty spring delays the rise and the release of the force by "
               "τ = ρcA/k each (6 µs at f_si 0.1, 0.6 µs at f_si 1), which lengthens the "
               "contact and lowers the mean over the analytic window (docs/verification.md).")),
    CaseSpec(
        case="sliding_block", title="Block sliding with Coulomb friction", ref="sliding_block",
        quantities=[
            Quantity("deceleration μg: −slope of `momentum_x`/m, least squares over 0.02–0.30 s",
                     "m/s²", "deceleration", deceleration(0.02, 0.30)),
            Quantity("stop time v₀/(μg): first sample with |`momentum_x`/m| < 1e-3 m/s "
                     "(samples every `output.interval`)", "s", "stop_time", stop_time(1e-3)),
            Quantity("stop distance v₀²/(2μg): u_x of probe `centre` at the end", "m",
                     "stop_distance", final_ux("centre"), digits=7),
            Quantity("friction dissipation ½mv₀²: `friction_dissipation`", "J",
                     "friction_dissipation", col("friction_dissipation")),
            Quantity("stick: final `momentum_x`", "kg·m/s", "final_momentum_x",
                     col("final.momentum_x"), scale=lambda t: t["mass"] * t["v0"],
                     scale_label="mv₀"),
        ],
        figure=fig_block,
        notes=("With penalty, the stuck block oscillates on its tangential springs with no "
               "damping, so its final momentum is one phase of that oscillation.")),
    CaseSpec(
        case="disk_oblique", title="Elastic disk striking a rigid plane obliquely, with friction",
        ref="disk_oblique",
        quantities=[
            Quantity("impulse ratio |Δp_x|/Δp_y = μ while it slides: first to last sample of "
                     "`momentum_x`, `momentum_y`", "", first_key("impulse_ratio", "mu"),
                     impulse_ratio),
            Quantity("spin arm R = ΔL/P_t: Δ`angular_momentum` / Δ`momentum_x`, first to last "
                     "sample", "m", "spin_arm", spin_arm),
        ],
        figure=fig_disk,
        groups=("disk", "disk_implicit"),
        notes=("The level plane with μ = 0.3 (groups `disk`, `disk_implicit`). The frictionless "
               "and cone-edge groups of the sweep are gated on exact momentum conservation "
               "(cases/verification/gates_fast.toml) and not repeated here."),
        pending=("the case `disk_oblique` (cases/verification/, history column "
                 "`angular_momentum`, reference/verification.toml [disk_oblique]) is being "
                 "added; its reference keys are read as `impulse_ratio` (else `mu`) and "
                 "`angular_momentum_gain` (else `final_angular_momentum`)")),
    CaseSpec(
        case="head_on", title="Two bars, head-on impact (benchmark B2 of docs/background.md)",
        ref="head_on",
        aliases=("two_bars", "bar_bar"),
        quantities=[
            Quantity("interface force: mean of `normal_force` over 2.5–97.5 % of 2L/c", "N",
                     "contact_force", plateau_mean()),
            Quantity("contact duration 2L/c: `steps_with_contact` × Δt", "s",
                     "contact_duration", contact_duration_steps),
            Quantity("total momentum conserved: change of `momentum_x`, first to last sample",
                     "kg·m/s", lambda t: 0.0, change("momentum_x"),
                     scale=lambda t: t["mass"] * t["v0"], scale_label="mv₀"),
        ],
        figure=fig_head_on,
        pending=("the two-bar case (B2; read as case `head_on`, reference/verification.toml "
                 "[head_on] with `contact_force`, `contact_duration`, `mass`, `v0`) is being "
                 "added. The exchange of the bars' velocities is not tabled yet: it needs the "
                 "case's probes per bar")),
]


# ---------------------------------------------------------------------------------------------
# Formatting

def fmt_num(x, digits=5):
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "–"
    if x == 0:
        return "0"
    ax = abs(x)
    if 1e-3 <= ax < 1e6:
        s = f"{x:.{digits}g}"
    else:
        m, e = f"{x:.{digits - 1}e}".split("e")
        if "." in m:
            m = m.rstrip("0").rstrip(".")
        s = f"{m}e{int(e)}"
    return s


def fmt_rel(e):
    pct = 100 * e
    if pct == 0:
        return "0 %"
    if abs(pct) >= 0.01:
        s = f"{pct:+.2f} %"
    else:
        m, x = f"{pct:+.1e}".split("e")
        s = f"{m}e{int(x)} %"
    return "−" + s[1:] if s.startswith("-") else s


def with_unit(v, unit, digits=5):
    s = fmt_num(v, digits)
    return s + (f" {unit}" if unit and s != "–" else "")


# ---------------------------------------------------------------------------------------------
# Runs, columns

def read_reference_ver(path=REFERENCE_VER):
    try:
        with open(path, "rb") as f:
            return tomllib.load(f), None
    except (OSError, tomllib.TOMLDecodeError) as e:
        return {}, str(e)


def case_runs(sweep, spec):
    names = (spec.case,) + tuple(spec.aliases)
    return [r for r in sweep.runs if r.kind == "run" and r.get("case") in names
            and (not spec.groups or r.group in spec.groups)]


# ---------------------------------------------------------------------------------------------
# Figures: the analytic reference beside every run

def fig_ver_contact_force(outdir, stem, runs, force, duration, p_ref, ref_label, p_label,
                          conserved=False):
    """Top row: normal_force (kN) against time (µs), one panel per run (shared scale), with the
    analytic plateau `force` for `duration`. Bottom: momentum_x of every run with p_ref(t) (or,
    with conserved, each run's initial value)."""
    import textwrap
    n = len(runs)
    fig = plt.figure(figsize=(max(10.5, 2.6 * n + 3.0), 6.8))
    gs = fig.add_gridspec(2, n, height_ratios=[1.15, 1.0], hspace=0.5, wspace=0.08)
    styles = _styles(runs)
    top = []
    alternating = False
    fmax = 0.0
    for j, ((label, r), st) in enumerate(zip(runs, styles)):
        ax = fig.add_subplot(gs[0, j], sharey=top[0] if top else None)
        top.append(ax)
        h = r.history()
        t, f = h["time"] * 1e6, h["normal_force"] / 1e3
        fmax = max(fmax, float(np.nanmax(f)))
        if force and duration:
            tend = max(float(t[-1]), duration * 1e6)
            ax.plot([0, duration * 1e6, duration * 1e6, tend], [force / 1e3] * 2 + [0, 0],
                    color="k", ls="--", lw=1.3, zorder=3)
        if _alternates(h["normal_force"]):
            alternating = True
            ax.plot(t, f, color=st["color"], lw=0.5, alpha=0.3)
            tm, fm = _running_mean(t, f, 2)
            ax.plot(tm, fm, color=st["color"], lw=1.5)
        else:
            ax.plot(t, f, color=st["color"], lw=1.5)
        ax.set_title("\n".join(textwrap.wrap(label, 26)), fontsize=9)
        ax.set_xlabel("time t (µs)")
        if j == 0:
            ax.set_ylabel("contact force normal_force (kN)")
        else:
            plt.setp(ax.get_yticklabels(), visible=False)
    if force:
        topv = min(fmax, 2.5 * force / 1e3) * 1.08
        top[0].set_ylim(-0.04 * topv, topv)
    handles = ([Line2D([0], [0], color="k", ls="--", lw=1.3, label=ref_label)]
               if force and duration else [])
    handles.append(Line2D([0], [0], color="0.3", lw=1.5, label="run: every sample"))
    if alternating:
        handles += [Line2D([0], [0], color="0.3", lw=0.5, alpha=0.4,
                           label="every step (force alternating)"),
                    Line2D([0], [0], color="0.3", lw=1.5, label="…its mean over 2 steps")]
    top[-1].legend(handles=handles, loc="upper left", bbox_to_anchor=(1.03, 1.0),
                   frameon=False)
    ax = fig.add_subplot(gs[1, :])
    dmax, pmax = 0.0, 0.0
    for (label, r), st in zip(runs, styles):
        h = r.history()
        p = h["momentum_x"]
        if conserved:
            # the change from the initial value: the value itself would need an offset label
            d = p - p[0]
            dmax, pmax = max(dmax, float(np.nanmax(np.abs(d)))), max(pmax, abs(float(p[0])))
            ax.plot(h["time"] * 1e6, d, lw=1.4, label=label, **st)
        else:
            ax.plot(h["time"] * 1e6, p, lw=1.4, label=label, **st)
    if conserved:
        half = max(1.25 * dmax, 1e-6 * pmax, 1e-30)
        ax.set_ylim(-half, half)
        ax.axhline(0.0, color="k", lw=0.8, ls=":")
    plain_axis(ax)
    if p_ref is not None:
        tt = np.linspace(0.0, max(float(r.history()["time"][-1]) for _, r in runs), 600)
        pr = p_ref(tt)
        if pr is not None:
            ax.plot(tt * 1e6, pr, color="k", ls="--", lw=1.3, label=p_label)
    ax.set_xlabel("time t (µs)")
    ax.set_ylabel("change of total momentum_x,\n$p_x(t) − p_x(0)$ (kg·m/s)" if conserved
                  else "momentum_x (kg·m/s)")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    return save(fig, outdir, stem)


def fig_ver_sliding(outdir, stem, series, v0, a, t_stop):
    """series = [(label, run, t, v)]: velocity against time beside max(v0 - a t, 0), and the
    difference from it (mm/s)."""
    fig, axes = plt.subplots(1, 2, figsize=(11.0, 4.2))
    styles = _styles([(lab, r) for lab, r, _, _ in series])

    def v_ref(t):
        return np.maximum(v0 - a * t, 0.0)
    tend = max(float(t[-1]) for _, _, t, _ in series)
    tt = np.linspace(0.0, tend, 1000)
    axes[0].plot(tt, v_ref(tt), color="k", ls="--", lw=1.6, zorder=20,
                 label="analytic max(v₀ − μg t, 0)")
    n = len(series)
    for i, ((label, r, t, v), st) in enumerate(zip(series, styles)):
        # the first runs on top: the penalty run's larger wiggles must not hide the others
        axes[0].plot(t, v, lw=1.2, label=label, zorder=2 + n - i, **st)
        axes[1].plot(t, 1e3 * (v - v_ref(t)), lw=0.9, label=label, zorder=2 + n - i, **st)
    for ax in axes:
        ax.axvline(t_stop, color="0.3", ls=":", lw=1.2)
        ax.set_xlabel("time t (s)")
        ax.set_xlim(0, tend)
    axes[0].text(t_stop, 0.12 * v0, f" stop v₀/(μg)\n = {t_stop:.4g} s", fontsize=8,
                 va="bottom", color="0.25")
    axes[0].set_ylabel("velocity momentum_x / m (m/s)")
    axes[0].set_title("centre-of-mass velocity")
    axes[0].legend(loc="upper right", fontsize=8)
    axes[1].axhline(0.0, color="k", lw=0.8)
    axes[1].set_ylabel("momentum_x / m − analytic (mm/s)")
    axes[1].set_title("difference from the analytic velocity")
    axes[1].legend(loc="lower left", fontsize=8)
    return save(fig, outdir, stem)


def fig_ver_impulse(outdir, stem, runs, mu):
    """The impulse path Δp_x against Δp_y (with |Δp_x| = μ Δp_y) and angular_momentum(t)."""
    fig, axes = plt.subplots(1, 2, figsize=(11.0, 4.2))
    styles = _styles(runs)
    ymax = 0.0
    for (label, r), st in zip(runs, styles):
        h = r.history()
        dx, dy = h["momentum_x"] - h["momentum_x"][0], h["momentum_y"] - h["momentum_y"][0]
        ymax = max(ymax, float(np.max(dy)))
        axes[0].plot(dy, dx, lw=1.3, label=label, **st)
        axes[1].plot(ms(h["time"]), h["angular_momentum"], lw=1.3, label=label, **st)
    if mu and ymax > 0:
        yy = np.array([0.0, ymax])
        axes[0].plot(yy, mu * yy, color="k", ls="--", lw=1.2, label=f"|Δp_x| = μ Δp_y, μ = {mu:g}")
        axes[0].plot(yy, -mu * yy, color="k", ls="--", lw=1.2)
    axes[0].set_xlabel("normal impulse Δp_y (kg·m/s)")
    axes[0].set_ylabel("tangential impulse Δp_x (kg·m/s)")
    axes[0].set_title("impulse path")
    axes[1].set_xlabel("time t (ms)")
    axes[1].set_ylabel("angular_momentum (kg·m²/s)")
    axes[1].set_title("spin")
    for ax in axes:
        ax.legend(loc="best", fontsize=8)
    return save(fig, outdir, stem)


# ---------------------------------------------------------------------------------------------
# Sections

def junit_text(folder):
    """'gates: N passed, M failed' from the sweep's gates-junit.xml (written by --check)."""
    p = os.path.join(folder, "gates-junit.xml")
    try:
        root = ET.parse(p).getroot()
    except (OSError, ET.ParseError):
        return "no gates-junit.xml (the sweep ran without `--check`)"
    n = int(root.get("tests", "0"))
    bad = int(root.get("failures", "0")) + int(root.get("errors", "0"))
    return f"gates (`gates-junit.xml`): {n - bad} passed, {bad} failed"


def sections(ctx, Section):
    """The verification part: one Section per case of CASES (plus one per unknown case in the
    sweep), or a single 'not available' Section without a verification sweep."""
    ver, err = ctx.get("ver"), ctx.get("ver_err")
    if ver is None:
        s = Section("verification", PART_TITLE, "figure")
        s.available = False
        s.missing = (("the verification sweep could not be read (" + err + "). " if err else
                      "no verification sweep. ") +
                     f"Run `{VER_CMD}`.")
        return [s]
    refs, ref_err = read_reference_ver()
    intro = (f"The analytic cases of docs/verification.md, run by one sweep: `{ver.dir}` "
             f"({len(ver.runs)} runs, {junit_text(ver.dir)}). References: "
             "`reference/verification.toml`" + (f" (**unreadable**: {ref_err})" if ref_err else "")
             + ". Each table gives, per analytic quantity, the reference, then each run of each "
             "scheme: measured value (relative error). Where the reference is 0 the error is "
             "given relative to the scale named in the cell. Every run of the case is a column; "
             "several runs of one scheme are told apart by the case keys that differ.")
    out = []
    known = set()
    for spec in CASES:
        known.update((spec.case,) + tuple(spec.aliases))
        try:
            s = case_section(ctx, Section, ver, spec, refs.get(spec.ref, {}))
        except Exception as e:  # noqa: BLE001 - one broken case must not stop the others
            traceback.print_exc()
            s = Section("ver_" + spec.case, spec.title, "figure")
            s.error = f"{type(e).__name__}: {e}"
        out.append(s)
    for name in sorted({r.get("case") for r in ver.runs if r.kind == "run"} - known - {""}):
        s = Section("ver_" + name, f"Case `{name}`", "figure")
        s.available = False
        s.missing = (f"the sweep {ver.dir} has runs of case `{name}`, but "
                     "cases/verification/report.py has no CaseSpec for it: add one to CASES. Runs: "
                     + ", ".join(f"`{r.id}`" for r in ver.runs if r.get("case") == name) + ".")
        out.append(s)
    for s in out:
        s.part = PART_TITLE
        s.part_intro = intro
    return out


def case_section(ctx, Section, ver, spec, table):
    s = Section("ver_" + spec.case, spec.title, "figure")
    s.case = spec.case
    runs = order_runs(case_runs(ver, spec))
    if not runs:
        s.available = False
        if spec.pending:
            s.missing = (f"case `{spec.case}` is not yet in the verification sweep {ver.dir}: "
                         f"{spec.pending}. Once cases/verification/sweep.toml runs it, run "
                         f"`{VER_CMD}`.")
        else:
            s.missing = (f"no run of case `{spec.case}` in the verification sweep {ver.dir}. "
                         f"Run `{VER_CMD}`.")
        return s
    labels = column_labels(runs)
    s.runs = [r.id for r in runs]
    s.sources = [ver.dir, REFERENCE_VER]
    missing_schemes = [sc for sc in SCHEMES if not any(r.scheme == sc for r in runs)]
    # columns: every run, in scheme order; a scheme without a run gets a column saying so
    cols = []
    for sc in SCHEMES:
        cols += [r for r in runs if r.scheme == sc] or [None]
    cols += [r for r in runs if r.scheme not in SCHEMES]
    gap = "no run in the sweep"
    header = ["quantity", f"analytic reference ([{spec.ref}])"]
    k = 0
    for c in cols:
        header.append(labels[c.id] if c else scheme_name(missing_schemes[k]))
        k += c is None

    def cells(fn):
        return [fn(c) if c else gap for c in cols]
    rows = [["run", "–"] + cells(lambda r: f"`{r.id}`"),
            ["Δt", "–"] + cells(lambda r: f"{fmt_dt(r.dt)} s ({r.get('dt_mode') or 'fixed'})")]
    if not table:
        note_ref = f" reference/verification.toml has no table [{spec.ref}]."
    else:
        note_ref = ""
    for q in spec.quantities:
        ref, key = ref_value(q.ref, table)
        scale, _ = ref_value(q.scale, table) if q.scale is not None else (None, "")
        if ref is None:
            ref_cell = f"**missing** ({key or 'no reference'})" if key else "**missing**"
            if isinstance(q.ref, str):
                ref_cell = f"**missing**: no `{q.ref}` in [{spec.ref}]"
        else:
            ref_cell = with_unit(ref, q.unit, 6)
        def measured(r, q=q, ref=ref, scale=scale):
            if not r.ok:
                return f"**{r.status or 'failed'}**"
            v = q.extract(r, table) if q.extract else None
            if v is None:
                return "–" if q.extract else "not yet implemented"
            cell = with_unit(v, q.unit, q.digits)
            if ref is not None and ref != 0:
                cell += f" ({fmt_rel((v - ref) / abs(ref))})"
            elif ref == 0 and scale:
                cell += f" ({fmt_rel((v - ref) / abs(scale))} of {q.scale_label})"
            return cell
        rows.append([q.label, ref_cell] + cells(measured))
    rows.append(["`energy_error_max`", "–"] +
                cells(lambda r: f"{100 * r.num('energy_error_max'):.3g} %"
                      if r.num("energy_error_max") is not None else "–"))
    rows.append(["`penetration_max`", "–"] +
                cells(lambda r: with_unit(r.num("penetration_max"), "m", 3)))
    tid = "ver_" + spec.case + "_table"
    s.extra.append((tid, f"{spec.title}: analytic reference and every run", header, rows))
    # figure
    files, fig_text = ([], "")
    if spec.figure:
        files, fig_text = spec.figure(ctx["out"], "verification_" + spec.case, runs, table,
                                      labels)
    s.files = files
    not_ok = [r.id for r in runs if not r.ok or r.history() is None]
    runs_txt = "; ".join(f"{labels[r.id]}: `{r.id}`" for r in runs)
    s.caption = ((fig_text + " " if fig_text else "") +
                 "The table below: measured value (relative error to the analytic reference "
                 f"of reference/verification.toml [{spec.ref}]) per run; rows `run` and Δt say "
                 "which run each column is." + note_ref +
                 (" " + spec.notes if spec.notes else "") +
                 (f" No run of {', '.join(scheme_name(sc) for sc in missing_schemes)} in the "
                  "sweep." if missing_schemes else "") +
                 (f" Not drawn (not ok or no history): {', '.join(f'`{i}`' for i in not_ok)}."
                  if not_ok else "") +
                 f" Runs (sweep `{ver.dir}`): {runs_txt}.")
    if not files:
        # no drawable run: the table still shows every run
        s.kind = "table"
        s.header, s.rows = header, rows
        s.extra = []
    return s


# ---------------------------------------------------------------------------------------------
# The plug-in's entry

def cases(ctx, section):
    """One section per verification case of the layout's sweep."""
    return sections({"out": ctx.out, "ver": ctx.sweep(section["sweep"])}, PageSection)
