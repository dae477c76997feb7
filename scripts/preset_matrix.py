#!/usr/bin/python3
"""Robustness of the shipped solver presets on graded 3D Gmsh meshes: the Hertz sphere (an elastic quarter sphere
pressed on a plane) and the sphere indenter (a rigid sphere into a block), at eps = eps0 h / E for eps0 = 1, 1e-2, 1e-4,
with every preset of options/solvers/ (and the default, MUMPS), on 1 to 4 ranks, partitioned by METIS and by PTScotch.
One row per run: whether it converged, how (SNES reason), the Newton steps, linear iterations, preconditioner builds
and the preconditioner rebuilds after a breakdown (/run pc_breakdowns), and the wall time.

  preset_matrix.py [--out bench/preset_matrix.md] [--cases sphere,sphere-indenter] [--eps0 1,1e-2,1e-4]
                   [--presets default,gamg,hypre] [--ranks 1,2,3,4] [--partitioners metis,ptscotch] [--h-near 0.02]
                   [--outdir output/preset_matrix]

Exit status 1 if a run did not converge (tests/test_reproducible.py runs a subset).
"""
import argparse
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from signorini import hertz  # noqa: E402
from signorini.mpirun import error_line, run_mpi  # noqa: E402
from signorini.paths import ROOT  # noqa: E402
from signorini.runs import read_run  # noqa: E402

PRESETS = {
    "default": [],
    "gamg": ["-options_file", os.path.join(ROOT, "options", "solvers", "gamg.yaml")],
    "hypre": ["-options_file", os.path.join(ROOT, "options", "solvers", "hypre.yaml")],
    "mumps": ["-options_file", os.path.join(ROOT, "options", "solvers", "mumps.yaml")],
}
COLUMNS = ["case", "preset", "eps0", "ranks", "partitioner", "converged", "reason", "newton", "ksp", "pc_builds", "pc_breakdowns",
           "contact_force", "wall"]


def run_one(case, mesh, preset, eps0, ranks, partitioner, outdir):
    out = os.path.join(outdir, f"{case}_{preset}_{eps0:g}_{ranks}_{partitioner}.h5")
    cmd = hertz.command(case, mesh, "eps=h", out, ranks=ranks)
    cmd += ["-penalty_eps0", f"{eps0:g}"] + (["-partitioner", partitioner] if ranks > 1 else []) + PRESETS[preset]
    t0 = time.time()
    r = run_mpi(cmd, timeout=900)
    row = {"case": case, "preset": preset, "eps0": eps0, "ranks": ranks, "partitioner": partitioner, "wall": time.time() - t0}
    if r.returncode not in (0, 3) or not os.path.exists(out):
        row.update(converged=0, reason=f"exit {r.returncode}: {error_line(r.output)}")
        return row, cmd
    a = read_run(out)
    row.update(converged=int(a["converged"]), reason=a["snes_reason_code"], newton=a["newton_its_total"],
               ksp=a["ksp_its_total"], pc_builds=a.get("pc_builds"), pc_breakdowns=a.get("pc_breakdowns", 0),
               contact_force=f"{a['contact_force']:.12g}")
    return row, cmd


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default=os.path.join(ROOT, "bench", "preset_matrix.md"))
    ap.add_argument("--cases", default="sphere,sphere-indenter")
    ap.add_argument("--eps0", default="1,1e-2,1e-4")
    ap.add_argument("--presets", default=",".join(PRESETS))
    ap.add_argument("--ranks", default="1,2,3,4")
    ap.add_argument("--partitioners", default="metis,ptscotch")
    ap.add_argument("--h-near", type=float, default=0.02)
    ap.add_argument("--outdir", default=os.path.join(ROOT, "output", "preset_matrix"), help="where the meshes and runs go")
    args = ap.parse_args()
    outdir = args.outdir
    os.makedirs(outdir, exist_ok=True)
    rows, failed = [], []
    for case in args.cases.split(","):
        mesh = os.path.join(outdir, hertz.mesh_name(case, args.h_near))
        if not os.path.exists(mesh):
            hertz.write_mesh(case, args.h_near, mesh)
        for preset in args.presets.split(","):
            for eps0 in (float(e) for e in args.eps0.split(",")):
                for ranks in (int(n) for n in args.ranks.split(",")):
                    for part in args.partitioners.split(",") if ranks > 1 else ["-"]:
                        row, cmd = run_one(case, mesh, preset, eps0, ranks, part, outdir)
                        rows.append(row)
                        print(" ".join(f"{k}={row.get(k, '')}" for k in COLUMNS), flush=True)
                        if not row["converged"]:
                            failed.append(" ".join(cmd))
    with open(args.out, "w") as fh:
        fh.write("# The solver presets on graded 3D Gmsh meshes\n\n")
        fh.write("Made by `" + " ".join(["scripts/preset_matrix.py"] + sys.argv[1:]) + "`, on " + time.strftime("%Y-%m-%d") + ".\n\n")
        fh.write("| " + " | ".join(COLUMNS) + " |\n|" + "---|" * len(COLUMNS) + "\n")
        for row in rows:
            fh.write("| " + " | ".join(f"{row[k]:.1f}" if k == "wall" else str(row.get(k, "")) for k in COLUMNS) + " |\n")
        fh.write(f"\n{len(rows) - len(failed)} of {len(rows)} runs converged.\n")
        for cmd in failed:
            fh.write(f"\nNot converged: `{cmd}`\n")
    print(f"{len(rows) - len(failed)} of {len(rows)} converged; table in {args.out}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
