#!/usr/bin/env python3
"""Adaptive refinement (-adapt_cycles) on make hertz's 2D cylinder indenter, against its closed form and make hertz's
hand-graded meshes (issue 34, its 2D part): the block [0,1] x [-1,0] meshed uniformly at --h (0.05), then refined where
the error estimate is largest, cycle after cycle, at eps = h/10 from the local cell size. Each row is one run to that
many cycles (the contact width a from the moments of the nodal forces, p0 from the fit of the profile, as make hertz
measures them). The block is polygonal, so that its refinement is exact (a curved mesh file is refused,
docs/scenes_and_meshes.md). Writes output/adapt_hertz/adapt_hertz.md and .csv.

    /usr/bin/python3 scripts/adapt_hertz.py [--h 0.05] [--cycles 0,2,4,6,8,10]
"""
import argparse
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from signorini import hertz  # noqa: E402
from signorini.mpirun import BENCH_ENV, MPI_ENV  # noqa: E402
from signorini.paths import ROOT  # noqa: E402
from signorini.report import csv_text, write_text  # noqa: E402

CASE = "cylinder-indenter"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--h", type=float, default=0.05, help="the uniform mesh size of the first mesh")
    ap.add_argument("--cycles", default="0,2,4,6,8,10", help="the runs' numbers of cycles")
    ap.add_argument("--method", default="eps=h/10", choices=sorted(hertz.METHODS))
    ap.add_argument("--outdir", default=os.path.join(ROOT, "output", "adapt_hertz"))
    args = ap.parse_args()
    os.makedirs(args.outdir, exist_ok=True)
    mesh = os.path.join(args.outdir, f"block_h{args.h}.msh")
    hertz.write_mesh(CASE, args.h, mesh, h_far=args.h, near=0.06)
    rows = []
    for cycles in [int(c) for c in args.cycles.split(",")]:
        out = os.path.join(args.outdir, f"adapt_{cycles}.h5")
        cmd = hertz.command(CASE, mesh, args.method, out)[3:] + (["-adapt_cycles", str(cycles)] if cycles else [])
        p = subprocess.run(cmd, cwd=ROOT, env={**os.environ, **MPI_ENV, **BENCH_ENV}, capture_output=True, text=True)
        if p.returncode:
            sys.exit(f"{' '.join(cmd)} failed:\n{p.stdout[-2000:]}")
        m = hertz.measure(CASE, out)
        rows.append([cycles, m["n_dofs"], m["a_error"], m["p0_error"], m["load"], m["time_total"]])
        print(f"{cycles} cycles: {m['n_dofs']} unknowns, a {m['a_error']:+.2%}, p0 {m['p0_error']:+.2%}", flush=True)
    header = ["cycles", "n_dofs", "a_error", "p0_error", "load", "time_total"]
    write_text(os.path.join(args.outdir, "adapt_hertz.csv"), csv_text(header, rows))
    md = [f"# Adaptive refinement on the 2D cylinder indenter ({args.method}, from a uniform mesh of h = {args.h})", "",
          f"`/usr/bin/python3 scripts/adapt_hertz.py --h {args.h} --cycles {args.cycles}`; a and p0 against the closed form "
          "(make hertz's measures; the unit block's own gap to the half-space is about 0.2%).", "",
          "| cycles | unknowns | a | p0 | load | time (s) |", "|---|---|---|---|---|---|"]
    md += [f"| {c} | {n} | {a:+.2%} | {p:+.2%} | {load:.6g} | {t:.2f} |" for c, n, a, p, load, t in rows]
    write_text(os.path.join(args.outdir, "adapt_hertz.md"), "\n".join(md) + "\n")


if __name__ == "__main__":
    main()
