#!/usr/bin/env python3
"""The accuracy asked for (-accuracy TOL, issue 34) on the 2D Hertz cylinder indenter, against the closed form and
against hand-graded meshes: the rigid cylinder pressed into a block 10 times make hertz's ([0, 10] x [-10, 0], where
the block's own gap to the half-space of the closed form is 0.02%, docs/estimate.md), eps = h/10.

For each TOL the run starts from the block meshed uniformly at h = 0.5 (the contact zone, a = 0.017, is 30 times
smaller than a cell) and refines until the bars of the force, the largest pressure and the contact width are below
TOL. Each is compared with the closed form at the run's force (the width and the largest pressure) and with the force
of the finest run (the force has no closed form in 2D). Then the hand-graded meshes (make hertz's grading on the same
block, h_near = 0.004, 0.002, 0.001, 0.0005) are solved once each, and for each TOL the cheapest one whose true errors
are below TOL is timed side by side with the adaptive run (--pairs alternated pairs, medians). Writes
output/accuracy_ladder/accuracy_ladder.md and .csv.

    /usr/bin/python3 scripts/accuracy_ladder.py [--tols 0.03,0.01] [--pairs 3]
"""
import argparse
import os
import statistics
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from signorini import estimates as st  # noqa: E402
from signorini import geometry, hertz  # noqa: E402
from signorini.mpirun import BENCH_ENV, MPI_ENV  # noqa: E402
from signorini.paths import ROOT  # noqa: E402
from signorini.report import csv_text, write_text  # noqa: E402
from signorini.runs import read_run  # noqa: E402

CASE = "cylinder-indenter"
QUANTITIES = "contact_force,pressure_max,contact_size"
HAND = [0.004, 0.002, 0.001, 0.0005]


def solve(cmd):
    t0 = time.perf_counter()
    p = subprocess.run(cmd, cwd=ROOT, env={**os.environ, **MPI_ENV, **BENCH_ENV}, capture_output=True, text=True)
    if p.returncode:
        sys.exit(f"{' '.join(cmd)} failed:\n{p.stdout[-2000:]}")
    return time.perf_counter() - t0


def errors(attrs, force_ref):
    """Relative errors of the width and largest pressure against the closed form at the run's force, and of the force
    against force_ref."""
    force = abs(float(attrs["contact_force_y"]))
    a, p0 = hertz.closed_form(2, 2 * force)
    return {"contact_size": float(attrs["contact_size"]) / a - 1, "pressure_max": float(attrs["pressure_max"]) / p0 - 1,
            "contact_force": force / force_ref - 1}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--tols", default="0.03,0.01")
    ap.add_argument("--pairs", type=int, default=3, help="alternated timing pairs of the adaptive and the hand-graded run")
    ap.add_argument("--outdir", default=os.path.join(ROOT, "output", "accuracy_ladder"))
    args = ap.parse_args()
    os.makedirs(args.outdir, exist_ok=True)
    tols = sorted((float(t) for t in args.tols.split(",")), reverse=True)
    coarse = os.path.join(args.outdir, "block10_h0.5.msh")
    geometry.block(coarse, radius=st.BLOCK, h_far=0.5, h_near=0.5, width=3.0, near=0.6)
    adaptive = {}
    for tol in tols:
        out = os.path.join(args.outdir, f"accuracy_{tol:g}.h5")
        cmd = hertz.command(CASE, coarse, "eps=h/10", out)[3:] + ["-accuracy", str(tol), "-accuracy_quantity", QUANTITIES]
        solve(cmd)
        adaptive[tol] = (cmd, read_run(out))
        print(f"-accuracy {tol:g}: {adaptive[tol][1]['n_dofs']} unknowns, reached {adaptive[tol][1]['accuracy_reached']}", flush=True)
    force_ref = abs(float(adaptive[tols[-1]][1]["contact_force_y"]))
    hand = []
    for h_near in HAND:
        mesh = os.path.join(args.outdir, f"block10_graded_{h_near:g}.msh")
        st.write_block_mesh(CASE, h_near, mesh)
        out = os.path.join(args.outdir, f"graded_{h_near:g}.h5")
        cmd = hertz.command(CASE, mesh, "eps=h/10", out)[3:]
        solve(cmd)
        hand.append((h_near, cmd, read_run(out)))
        print(f"hand-graded h_near {h_near:g}: {hand[-1][2]['n_dofs']} unknowns", flush=True)
    rows, md = [], []
    for tol in tols:
        cmd, a = adaptive[tol]
        err = errors(a, force_ref)
        bars = {q: float(a[f"accuracy_{q}_bar"]) / abs(float(a[f"accuracy_{q}_value"])) for q in QUANTITIES.split(",")}
        best = next(((h, c, b) for h, c, b in hand if all(abs(e) <= tol for e in errors(b, force_ref).values())), None)
        t_ad, t_hd = [], []
        for _ in range(args.pairs):
            t_ad.append(solve(cmd))
            if best:
                t_hd.append(solve(best[1]))
        ratio = statistics.median(t_ad) / statistics.median(t_hd) if best else float("nan")
        row = [tol, int(a["n_dofs"]), int(a["accuracy_reached"]), statistics.median(t_ad)]
        row += [err[q] for q in QUANTITIES.split(",")] + [bars[q] for q in QUANTITIES.split(",")]
        row += [best[0] if best else float("nan"), int(best[2]["n_dofs"]) if best else 0, statistics.median(t_hd) if best else float("nan"), ratio]
        rows.append(row)
        covered = all(abs(err[q]) <= bars[q] for q in bars)
        md.append(f"| {tol:g} | {row[1]} | {'yes' if row[2] else 'no'} | " + " | ".join(f"{err[q]:+.3%} ({bars[q]:.2%})" for q in bars)
                  + f" | {'yes' if covered else 'NO'} | {row[3]:.2f} | " + (f"{best[0]:g}: {row[-3]} | {row[-2]:.2f} | {ratio:.2f} |" if best else "none | | |"))
    header = ["tol", "n_dofs", "reached", "time", "err_force", "err_pressure_max", "err_contact_size", "bar_force", "bar_pressure_max",
              "bar_contact_size", "hand_h_near", "hand_n_dofs", "hand_time", "time_ratio"]
    write_text(os.path.join(args.outdir, "accuracy_ladder.csv"), csv_text(header, rows))
    hand_md = [f"| {h:g} | {b['n_dofs']} | " + " | ".join(f"{e:+.3%}" for e in errors(b, force_ref).values()) + " |" for h, _, b in hand]
    text = [f"# -accuracy on the 2D Hertz cylinder indenter (block {st.BLOCK:g} x {st.BLOCK:g}, eps = h/10, from h = 0.5 uniform)", "",
            f"`/usr/bin/python3 scripts/accuracy_ladder.py --tols {args.tols} --pairs {args.pairs}`. Errors: the width and the largest "
            "pressure against the closed form at the run's force, the force against the finest run's; in brackets the run's bar "
            f"(relative). Times: medians of {args.pairs} alternated pairs, whole processes.", "",
            "| TOL | unknowns | reached | force | largest pressure | width | covered | time (s) | cheapest hand-graded within TOL: h_near: unknowns | its time (s) | adaptive / hand-graded |",
            "|---|---|---|---|---|---|---|---|---|---|---|"] + md + ["", "Hand-graded meshes (make hertz's grading on the same block), one solve each:", "",
                                                                     "| h_near | unknowns | force | largest pressure | width |", "|---|---|---|---|---|"] + hand_md
    write_text(os.path.join(args.outdir, "accuracy_ladder.md"), "\n".join(text) + "\n")
    print("\n".join(text))


if __name__ == "__main__":
    main()
