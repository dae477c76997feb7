#!/usr/bin/env python3
"""Distance to the hardware limit (make bench): bin/signorini -perf_bandwidth on the bench's finest 2D mesh with GAMG,
one rank, the elastic and the penalty solve. Each run measures, after its solve and in the same process, a
STREAM-like triad, a MatMult with the final Jacobian and one V-cycle of its GAMG (src/solver/bandwidth.c gives the byte
accounting), and reports each achieved bandwidth and its fraction of the triad's. Writes bench/bandwidth.md and .csv."""
import argparse
import csv
import os
import sys

import h5py

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from signorini.mpirun import run_mpi  # noqa: E402
from signorini.paths import BIN, ROOT  # noqa: E402

KEYS = ["bandwidth_triad_gbs", "bandwidth_matmult_gbs", "bandwidth_vcycle_gbs", "time_matmult", "time_vcycle"]


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--faces", type=int, default=704, help="cells per side (default 704, the bench's 2D mesh: 994k unknowns)")
    ap.add_argument("--out", default=os.path.join(ROOT, "bench"))
    args = ap.parse_args()
    runs = os.path.join(args.out, "runs", "bandwidth")
    os.makedirs(runs, exist_ok=True)
    rows = []
    for method in ("none", "penalty"):
        h5 = os.path.join(runs, f"{method}.h5")
        cmd = ["mpiexec", "-n", "1", BIN, "-options_file", "options/square.yaml", "-options_file", "options/solvers/gamg.yaml", "-contact_monitor", "0",
               "-dm_plex_box_faces", f"{args.faces},{args.faces}", "-contact_method", method, "-perf_bandwidth", "-output", h5]
        r = run_mpi(cmd, timeout=1200)
        if r.returncode != 0:
            sys.exit(f"{' '.join(cmd)} failed:\n{r.output[-3000:]}")
        with h5py.File(h5, "r") as f:
            a = f["run"].attrs
            row = {"run": "elastic" if method == "none" else "penalty", "dofs": int(a["n_dofs"]), **{k: float(a[k]) for k in KEYS}}
        rows.append(row)
        print(row, flush=True)
    with open(os.path.join(args.out, "bandwidth.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    lines = [f"# Memory bandwidth ({args.faces} x {args.faces}, {rows[0]['dofs']} unknowns, GAMG, one rank)", "",
             "`/usr/bin/python3 scripts/bench_bandwidth.py` (make bench): `-perf_bandwidth`, best of 10 repeats each, after the solve, in the same process.",
             "The V-cycle counts the level matrices' and interpolations' bytes only (not the vectors, not the coarsest solve): a lower bound of its traffic.",
             "", "| run | triad GB/s | MatMult GB/s | MatMult / triad | MatMult ms | V-cycle GB/s | V-cycle / triad | V-cycle ms |", "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        t = r["bandwidth_triad_gbs"]
        lines.append(f"| {r['run']} | {t:.2f} | {r['bandwidth_matmult_gbs']:.2f} | {r['bandwidth_matmult_gbs'] / t:.2f} | {1e3 * r['time_matmult']:.2f} | "
                     f"{r['bandwidth_vcycle_gbs']:.2f} | {r['bandwidth_vcycle_gbs'] / t:.2f} | {1e3 * r['time_vcycle']:.2f} |")
    with open(os.path.join(args.out, "bandwidth.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
