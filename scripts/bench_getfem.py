#!/usr/bin/env python3
"""GetFEM side by side (make bench): the default scene on one N x N mesh written by this project, the nodal penalty at
eps = h (the cell diameter), solved by bin/signorini (its default solver, GAMG, and on the box it builds itself GAMG and the
geometric multigrid) and by GetFEM with MUMPS, each as a whole process, alternating, PAIRS times; the medians, their ratio, and the largest difference between the two
displacement fields. Writes bench/getfem.md and bench/getfem.csv."""
import argparse
import csv
import math
import os
import statistics
import sys

import h5py
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from signorini import getfem_side as gs  # noqa: E402
from signorini.mpirun import run_timed  # noqa: E402
from signorini.paths import ROOT  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--faces", type=int, default=256, help="cells per side (default 256: 132k unknowns)")
    ap.add_argument("--pairs", type=int, default=3, help="runs of each code, alternating (default 3)")
    ap.add_argument("--out", default=os.path.join(ROOT, "bench"), help="directory of getfem.md, getfem.csv and the runs")
    args = ap.parse_args()
    runs = os.path.join(args.out, "runs", "getfem")
    os.makedirs(runs, exist_ok=True)
    mesh = os.path.join(runs, f"box{args.faces}.msh")
    gs.write_box_mesh(mesh, args.faces)
    eps = math.sqrt(2.0) / args.faces  # h, the cell diameter, as -penalty_eps0 1 gives on this mesh
    # the last signorini row builds the same mesh itself (its box, the mesh the file holds) instead of reading the file:
    # what a user of the box gets, nested iteration included
    codes = {"signorini (MUMPS)": ("file", None), "signorini (GAMG)": ("file", "options/solvers/gamg.yaml"),
             "signorini (GAMG, its own box)": ("box", "options/solvers/gamg.yaml"),
             "signorini (geometric MG, its own box)": ("box", "options/solvers/mg.yaml"), "GetFEM (MUMPS)": ("getfem", None)}
    h5_of = {"signorini (MUMPS)": "mumps.h5", "signorini (GAMG)": "gamg.h5", "signorini (GAMG, its own box)": "gamg_box.h5",
             "signorini (geometric MG, its own box)": "mg_box.h5"}
    times = {k: [] for k in codes}
    mems = {k: [] for k in codes}
    for p in range(args.pairs):
        for name, (kind, solver) in codes.items():
            if kind == "getfem":
                result = os.path.join(runs, "getfem.npz")
                wall, mem, _ = run_timed(gs.getfem_cmd(mesh, eps, result), env={"PYTHONPATH": os.path.dirname(os.path.abspath(__file__))})
            else:
                h5 = os.path.join(runs, h5_of[name])
                if kind == "box":
                    wall, mem, _ = run_timed(gs.signorini_cmd(None, eps, h5, solver, box_faces=args.faces))
                else:
                    wall, mem, _ = run_timed(gs.signorini_cmd(mesh, eps, h5, solver))
            times[name].append(wall)
            mems[name].append(mem)
            print(f"pair {p + 1}/{args.pairs}: {name} {wall:.2f} s, {mem:.0f} MiB", flush=True)
    ref = np.load(os.path.join(runs, "getfem.npz"))
    u_ref = gs.sorted_by_position(ref["x"], ref["u"])
    rows = []
    for name, (kind, solver) in codes.items():
        row = {"code": name, "dofs": 2 * (args.faces + 1) ** 2, "eps": eps, "wall_median_s": statistics.median(times[name]),
               "walls_s": " ".join(f"{t:.2f}" for t in times[name]), "peak_memory_mib": statistics.median(mems[name])}
        if kind == "getfem":
            row.update(newton=int(ref["newton_its"]), max_rel_diff=0.0)
        else:
            with h5py.File(os.path.join(runs, h5_of[name]), "r") as f:
                assert int(f["run"].attrs["converged"]) == 1, f"{name} did not converge"
                u = gs.sorted_by_position(f["geometry/vertices"][:], f["vertex_fields/displacement"][:])
                row.update(newton=int(f["run"].attrs["newton_its"]), max_rel_diff=float(np.abs(u - u_ref).max() / np.abs(u_ref).max()))
        row["getfem_over_this"] = statistics.median(times["GetFEM (MUMPS)"]) / row["wall_median_s"]
        rows.append(row)
    with open(os.path.join(args.out, "getfem.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    lines = [f"# GetFEM side by side ({args.faces} x {args.faces}, {rows[0]['dofs']} unknowns)", "",
             "`/usr/bin/python3 scripts/bench_getfem.py` (make bench): the default scene `square` on one mesh written by this project "
             f"(`{os.path.relpath(mesh, ROOT)}`), nodal penalty, eps = h = {eps:.6g}, snes_rtol 1e-10 (GetFEM: max_res 1e-10 times the 1-norm of its residual at u = 0, the norm of its Newton).",
             f"Whole-process wall time (`/usr/bin/time -v`), median of {args.pairs} runs of each code, alternating; max diff = max |u - u_GetFEM| / max |u_GetFEM| over the vertices.",
             "", "| code | wall s (median) | runs s | peak MiB | Newton | max diff | GetFEM / this |", "|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['code']} | {r['wall_median_s']:.2f} | {r['walls_s']} | {r['peak_memory_mib']:.0f} | {r['newton']} | {r['max_rel_diff']:.1e} | {r['getfem_over_this']:.1f} |")
    with open(os.path.join(args.out, "getfem.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
