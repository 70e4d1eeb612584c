#!/usr/bin/python3
"""The implicit scheme's cost against the mesh, beside the semi-explicit scheme's
(docs/performance.md, "The implicit scheme at scale").

    bench/implicit_scaling.py [--ricochet build/ricochet] [--steps 30] [--dt 1e-5]
                              [--meshes2 M1,M2,M2x2,M2x4] [--meshes3 M1x2,M1x4,M2x2]
                              [--factor-precision double|single] [--out DIR]

Runs, one after the other on one thread, the oblique plate (cases/oblique_plate.toml) on each 2D
mesh and the oblique block (cases/three_d/oblique_block.toml) on each 3D mesh, for `--steps`
steps of the implicit scheme at `--dt` and the semi-explicit scheme over the same simulated
time at its automatic step (0.9 of the critical one), fields off, and prints one Markdown
table: cells, DOFs, per-step CPU time of each scheme, the implicit scheme's phases
(summary.json implicit.phase_seconds, wall time per step), Newton iterations and
factorizations per step, the ratio of the two runs' CPU times over the same simulated time,
and each run's peak resident memory. `--factor-precision` is the implicit runs'
implicit.factor_precision (docs/implicit.md, "Single-precision solves"). Each run is a process of its own, so its peak memory is its own. Timings move
with the machine's load: compare the rows of one table, measured together.
"""
import argparse
import json
import pathlib
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent


def run(ricochet, case, mesh, scheme, steps, dt, out, precision="double"):
    """summary.json of one run (raises on a failed run)."""
    args = [str(ricochet), "run", str(case), "--set", f"mesh={mesh}", "--set", f"scheme={scheme}",
            "--set", "output.fields=[]", "--threads", "1", "--quiet", "--out", str(out)]
    if scheme == "implicit":
        args += ["--set", f'implicit.factor_precision="{precision}"']
    args += ["--set", f"time.dt={dt!r}" if scheme == "implicit" else "time.dt=auto", "--set", f"time.end={steps * dt!r}"]
    done = subprocess.run(args, capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(args)}: {done.stderr.strip()}")
    return json.loads((out / "summary.json").read_text())


def row(dim, mesh, imp, semi):
    """One table row; what a summary lacks (an older build's) is shown as –."""
    steps_i = max(imp["steps"], 1)
    steps_s = max(semi["steps"], 1)
    im = imp["implicit"]
    ph = im.get("phase_seconds", {})
    ms = lambda x: f"{1e3 * x / steps_i:.2f}" if x is not None else "–"  # ms per implicit step
    mib = lambda s: f"{s['peak_memory_bytes'] / 2**20:.0f}" if "peak_memory_bytes" in s else "–"
    cells = [f"{dim}D {mesh}", str(imp["elements"]), str(dim * imp["nodes"]), ms(imp["cpu_seconds"])]
    cells += [ms(ph.get(k)) for k in ("assembly", "factorization", "solve", "contact", "residual")]
    cells += [f"{im['newton_iterations_per_step']:.1f}", f"{im['factorizations'] / steps_i:.2f}", mib(imp),
              f"{1e3 * semi['cpu_seconds'] / steps_s:.3f}", str(steps_s),
              f"{imp['cpu_seconds'] / max(semi['cpu_seconds'], 1e-9):.1f}", mib(semi)]
    return "| " + " | ".join(cells) + " |"


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--ricochet", default=str(ROOT / "build" / "ricochet"))
    p.add_argument("--steps", type=int, default=30)
    p.add_argument("--dt", type=float, default=1e-5)
    p.add_argument("--meshes2", default="M1,M2,M2x2,M2x4")
    p.add_argument("--meshes3", default="M1x2,M1x4,M2x2")
    p.add_argument("--factor-precision", choices=["double", "single"], default="double")
    p.add_argument("--out", default=None, help="keep the runs' folders here (default: a temporary folder)")
    a = p.parse_args()
    out = pathlib.Path(a.out) if a.out else pathlib.Path(tempfile.mkdtemp(prefix="implicit_scaling_"))
    cases = [(2, ROOT / "cases" / "oblique_plate.toml", [m for m in a.meshes2.split(",") if m]),
             (3, ROOT / "cases" / "three_d" / "oblique_block.toml", [m for m in a.meshes3.split(",") if m])]
    print(f"implicit: {a.steps} steps at dt = {a.dt:g} s; semi-explicit: the same time at its automatic step; "
          "one thread; ms per step (CPU), memory MiB")
    print()
    print("| mesh | cells | DOFs | implicit ms/step | assembly | factorization | solves | contact | residual | "
          "Newton/step | factorizations/step | implicit MiB | semi-explicit ms/step | semi-explicit steps | "
          "implicit / semi-explicit CPU | semi-explicit MiB |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for dim, case, meshes in cases:
        for mesh in meshes:
            try:
                imp = run(a.ricochet, case, mesh, "implicit", a.steps, a.dt, out / f"{dim}d_{mesh}_implicit",
                          a.factor_precision)
                semi = run(a.ricochet, case, mesh, "semi_explicit", a.steps, a.dt, out / f"{dim}d_{mesh}_semi")
            except RuntimeError as e:
                print(f"implicit_scaling: {e}", file=sys.stderr)
                return 1
            print(row(dim, mesh, imp, semi), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
