"""The 3D study's plug-in (cases/three_d/study.toml; docs/studies.md, Writing a plug-in;
docs/three-dimensions.md, Cases in 3D), from its three sweeps:

  * `cases` (sweep.toml): the bar on a rigid wall in 3D against the 1D solution (a figure of
    the normal force of every run, a table of plateau, duration and rebound), the oblique block
    beside the 2D plane-stress plate (a table of the 3D/2D ratios), and the frame invariance of
    the turned runs (a table of relative differences);
  * `refinement` (refinement.toml): the same comparison on refined meshes;
  * `fields` (fields.toml): the oblique block with friction and its fields, drawn by the
    layout's `fields` kind (reports/report_fields.py).

A sweep not run in the tier gives the page's "not run in this tier" note.
"""

import math
import os

import report_figures as F
from report_page import Section as PageSection
from report_io import REPO, fmt_g, scheme_name

SWEEP_CMD = ("build/ricochet sweep cases/three_d/sweep.toml --out results/three_d "
             "--check cases/three_d/gates.toml")
REF_CMD = ("build/ricochet sweep cases/three_d/refinement.toml --out results/three_d_refinement "
           "--threads 1")
FIELDS_CMD = ("build/ricochet run cases/three_d/oblique_block.toml --set obstacles[0].friction=0.1 "
              "--out results/oblique_block")
DOC = os.path.join(REPO, "docs", "three-dimensions.md")
MAX_PANELS = 6

# The bar (cases/three_d/bar_wall3.toml): rho c v0 A and 2L/c.
BAR_FORCE = 8000.0 * math.sqrt(2.0e11 / 8000.0) * 1.0 * 0.02 * 0.02  # 16000 N
BAR_DURATION = 2.0 * 0.2 / math.sqrt(2.0e11 / 8000.0)                # 8e-5 s

def doc_link(out, anchor="", text="docs/three-dimensions.md"):
    return f"[{text}]({os.path.relpath(DOC, out)}{anchor})"


def fig_bar(outdir, stem, runs):
    """runs = [(label, run)]: the summed normal contact force against time, one line each, with
    the 1D solution's plateau rho c v0 A over 0 < t < 2L/c."""
    plt = F.plt
    fig, ax = plt.subplots(figsize=(9.5, 4.4))
    styles = F._styles(runs)
    tend = 0.0
    for (label, r), st in zip(runs, styles):
        h = r.history()
        t = h["time"] * 1e6
        tend = max(tend, float(t[-1]))
        ax.plot(t, h["normal_force"] / 1e3, lw=1.2, label=label, **st)
    ax.plot([0, BAR_DURATION * 1e6, BAR_DURATION * 1e6], [BAR_FORCE / 1e3, BAR_FORCE / 1e3, 0],
            color="k", ls=":", lw=1.3, label="1D solution: ρcv₀A for 2L/c")
    ax.set_xlabel("time t (µs)")
    ax.set_ylabel("normal contact force (kN)")
    ax.set_xlim(0, tend)
    ax.set_title("bar on a rigid wall in 3D (normal_force)")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=3, frameon=False)
    fig.tight_layout()
    return F.save(fig, outdir, stem)


# ---------------------------------------------------------------------------------------------
# Sections

def _no_sweep(ctx, s, key="td", cmd=SWEEP_CMD, name="three_d"):
    err = ctx.get(key + "_err")
    s.available = False
    s.missing = ((f"the sweep could not be read ({err}). " if err else f"no {name} sweep. ")
                 + f"Run `{cmd}` (results/{name}, found next to the main sweep).")
    return s


def _bar_runs(sw):
    return [r for r in sw.runs if r.kind == "run" and r.ok and r.get("case") == "bar_wall3"]


def _bar_label(r):
    el = r.get("bodies[0].element") or "hex8"
    if r.get("meshes.bar.cells") == "tet":
        el = "tet4"
    f = r.get("penalty.scale_factor")
    return scheme_name(r.scheme) + ", " + el + (f", f_si = {f}" if f else
                                                 ", f_si = 0.1" if r.scheme == "explicit_penalty" else "")


def sec_bar(ctx, Section, sid, title):
    s = Section(sid, title, "figure")
    sw = ctx.get("td")
    if sw is None:
        return _no_sweep(ctx, s)
    runs = _bar_runs(sw)
    if not runs:
        s.available = False
        s.missing = f"no finished bar_wall3 run in `{sw.dir}`."
        return s
    labelled = [(_bar_label(r), r) for r in runs]
    s.files = fig_bar(ctx["out"], "three_d_bar", labelled)
    s.runs = [r.id for r in runs]
    s.sources = [sw.dir]
    rows = []
    for label, r in labelled:
        f = r.num("contact_force_mean")
        d = r.num("contact_iterations.contact_time")
        v = r.num("rebound_velocity_x")
        rows.append([f"`{r.id}`", label,
                     f"{fmt_g(f, 5)} ({100 * (f / BAR_FORCE - 1):+.2f} %)" if f else "–",
                     f"{fmt_g(d, 5)} ({100 * (d / BAR_DURATION - 1):+.2f} %)" if d else "–",
                     f"{fmt_g(v, 5)} ({100 * (v - 1):+.2f} %)" if v else "–",
                     fmt_g(r.num("penetration_max"))])
    s.extra = [("td_bar_table", "Against the 1D solution (ρcv₀A = 16000 N, 2L/c = 8e-5 s, v₀ = 1 m/s)",
                ["run", "scheme, element", "mean normal force in contact (N)",
                 "contact time (s)", "rebound v_x (m/s)", "penetration (m)"], rows)]
    s.caption = (
        "The summed normal contact force (history `normal_force`) of every bar run of the 3D "
        "sweep against time, with the 1D solution: while the bar (0.2 × 0.02 × 0.02 m, "
        "E = 2e11 Pa, ν = 0, ρ = 8000 kg/m³, 200 × 2 × 2 cells) touches the wall the force is "
        "ρcv₀A = 16000 N, for 2L/c = 80 µs, then it leaves at +v₀. The penalty springs at "
        "LS-DYNA's default f_si = 0.1 delay each wave front by ρcA/k = 6 µs, so their contact "
        "lasts longer, as in 2D; at f_si = 1 the delay is 0.6 µs. The implicit scheme runs at "
        "a fixed Δt = 1e-7 s. The table gives the gated "
        "quantities (`cases/three_d/gates.toml`: 2 %). Runs: "
        + ", ".join(f"`{r.id}`" for r in runs) + f" of `{sw.dir}`.")
    return s


SCHEMES = ("semi_explicit", "implicit", "explicit_penalty")


def oblique_group(scheme):
    """The 3D sweep's group of the oblique block run by `scheme` (cases/three_d/sweep.toml)."""
    return "oblique_implicit" if scheme == "implicit" else "oblique"


def _pick(sw, group, scheme, mu):
    for r in sw.runs:
        if (r.kind == "run" and r.ok and r.group == group and r.scheme == scheme
                and r.friction is not None and abs(r.friction - mu) < 1e-12):
            return r
    return None


COMPARED = (("rebound_velocity_x", "rebound v_x (m/s)"), ("rebound_velocity_y", "rebound v_y (m/s)"),
            ("contact_iterations.contact_time", "contact time (s)"),
            ("friction_dissipation", "friction dissipation (J)"),
            ("von_mises_max", "von Mises peak (Pa)"),
            ("von_mises_interior_max", "von Mises peak off the contact boundary (Pa)"),
            ("energy_error_max", "energy error"))


def sec_oblique(ctx, Section, sid, title):
    s = Section(sid, title, "table")
    sw = ctx.get("td")
    if sw is None:
        return _no_sweep(ctx, s)
    s.header = ["scheme, μ", "quantity", "3D (M1x4)", "2D plane stress (M1)", "3D / 2D"]
    runs = []
    for scheme in SCHEMES:
        for mu in (0.0, 0.1):
            a, b = _pick(sw, oblique_group(scheme), scheme, mu), _pick(sw, "oblique2d", scheme, mu)
            if a is None or b is None:
                continue
            runs += [a.id, b.id]
            for col, name in COMPARED:
                x, y = a.num(col), b.num(col)
                if x is None or y is None or (col == "friction_dissipation" and mu == 0.0):
                    continue
                ratio = f"{x / y:.4f}" if y else "–"
                s.rows.append([f"{scheme_name(scheme)}, {mu:g}", name, fmt_g(x, 6), fmt_g(y, 6), ratio])
    if not s.rows:
        s.available = False
        s.missing = f"no finished oblique and oblique2d runs in `{sw.dir}`."
        return s
    s.runs = runs
    s.sources = [sw.dir]
    ref = ctx.get("td_ref")
    if ref is not None:
        rows = []
        for r in sorted((r for r in ref.runs if r.kind == "run" and r.ok),
                        key=lambda r: (r.group, r.friction or 0.0, r.num("elements") or 0)):
            rows.append([f"`{r.id}`", r.mesh, f"{int(r.num('elements') or 0)}", f"{r.friction:g}"]
                        + [fmt_g(r.num(c), 6) for c, _ in COMPARED])
        s.extra = [("td_refinement", "Under refinement (semi-explicit, Δt = 2e-6 s on every mesh; "
                    f"`{ref.dir}`)", ["run", "mesh", "cells", "μ"] + [n for _, n in COMPARED], rows)]
        s.sources.append(ref.dir)
    s.caption = (
        "The oblique block (cases/three_d/oblique_block.toml: the paper's plate extruded "
        "through e = 0.01 m in 4 layers, 1536 hexahedra) and the 2D plane-stress plate "
        "(cases/oblique_plate.toml, M1) hitting the ground at (3, −5) m/s, Δt = 1e-5 s, each "
        "scheme against its own 2D run. The "
        "rebound and the contact time agree to about 1 %; the 3D block dissipates 1–2 % more by "
        "friction and its semi-explicit von Mises peak is 2–3 % higher, next to a free face where "
        "the 3D stress departs from its thickness average, which is what plane stress computes. "
        "The penalty scheme's 3D peak is 55 % higher: it sits in the cell at the penetrated "
        "contact edge next to the face z = 0; off the contact boundary (in 3D the middle layers "
        "only, since the faces z = 0 and z = e are contact boundary too) the peaks agree within "
        "2 % (" + doc_link(ctx["out"]) + ", 3D and plane stress). "
        + ("The second table follows the comparison to finer meshes. " if ref is not None else
           f"The refinement table is not available: run `{REF_CMD}`. ")
        + f"Sweep `{sw.dir}`.")
    return s


def sec_frame(ctx, Section, sid, title):
    s = Section(sid, title, "table")
    sw = ctx.get("td")
    if sw is None:
        return _no_sweep(ctx, s)
    s.header = ["scheme", "quantity", "unturned", "turned", "relative difference"]
    runs = []
    for scheme in SCHEMES:
        turned = next((r for r in sw.runs if r.kind == "run" and r.ok and r.group == "frame"
                       and r.scheme == scheme), None)
        plain = _pick(sw, oblique_group(scheme), scheme, turned.friction if turned and turned.friction is not None
                      else 0.1) if turned else None
        if turned is None or plain is None:
            continue
        runs += [plain.id, turned.id]
        for col, name in (("final.kinetic_energy", "kinetic energy (J)"),
                          ("final.strain_energy", "strain energy (J)"),
                          ("friction_dissipation", "friction dissipation (J)"),
                          ("contact_work", "contact work (J)"),
                          ("contact_iterations.contact_time", "contact time (s)")):
            x, y = plain.num(col), turned.num(col)
            if x is None or y is None:
                continue
            rel = abs(y - x) / abs(x) if x else abs(y - x)
            s.rows.append([scheme_name(scheme), name, repr(x), repr(y), f"{rel:.1e}"])
    if not s.rows:
        s.available = False
        s.missing = f"no finished frame runs in `{sw.dir}`."
        return s
    s.runs = runs
    s.sources = [sw.dir]
    s.caption = (
        "The oblique block (μ = 0.1) and the same case with `[scene_rotation]` 50° about "
        "(1, 2, −1.5): every position, velocity and the plane turned. The energies, the "
        "dissipation and the contact time do not depend on the frame; the gates "
        "(`cases/three_d/gates.toml`) hold them to 1e-9. The differences are round-off: the turned "
        "run's contact tangents are other vectors of the same tangent planes; the implicit "
        "scheme's, about 1e-11, are its Newton tolerance, met in each frame on its own. "
        f"Sweep `{sw.dir}`.")
    return s


# ---------------------------------------------------------------------------------------------
# The plug-in's entries. args.refinement: the name of the refinement sweep.

def _legacy(ctx, section):
    args = section.get("args", {})
    return {"out": ctx.out, "td": ctx.sweep(section["sweep"]),
            "td_ref": ctx.sweep(args.get("refinement", "refinement"))}


def bar(ctx, section):
    return [sec_bar(_legacy(ctx, section), PageSection, "td_bar", "The bar on a rigid wall in 3D")]


def oblique(ctx, section):
    return [sec_oblique(_legacy(ctx, section), PageSection, "td_oblique",
                        "The oblique block against the 2D plane-stress plate")]


def frame(ctx, section):
    return [sec_frame(_legacy(ctx, section), PageSection, "td_frame",
                      "Frame invariance: the turned scene")]
