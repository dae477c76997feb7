#!/usr/bin/env python3
"""Where the time of the 3D default run goes (issue 35): bin/signorini on the N^3 box (N = 40 by default) with its default
solver, the penalty run and the elastic solve, one rank each, with PETSc's -log_view (inclusive times of its events) and
-perf_bandwidth (a STREAM-like triad, a MatMult with the final Jacobian and one V-cycle, src/solver/bandwidth.c): the
set-up (mesh, sections, K), the residual and Jacobian evaluations, the preconditioner's set-ups, the linear solves and
their V-cycles, and the rest (estimate, output); the V-cycle's bandwidth against the triad's. Writes bench/profile3d.md
and bench/profile3d.csv, the logs under bench/runs/profile3d/."""
import argparse
import os
import re
import sys

import h5py

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from signorini.mpirun import run_mpi  # noqa: E402
from signorini.paths import BIN, ROOT  # noqa: E402
from signorini.report import dict_csv_text, write_text  # noqa: E402

EVENTS = ["SNESSolve", "SNESFunctionEval", "SNESJacobianEval", "PCSetUp", "KSPSolve", "PCApply", "MatMult", "MatPtAPNumeric", "MatPtAPSymbolic",
          "KSPSetUp", "MatLUFactorNum", "AssemblyP1Prealloc"]


def events(path):
    """{event: (count, max time s)} of a -log_view ASCII file."""
    out = {}
    with open(path) as fh:
        for line in fh:
            m = re.match(r"^(\w+)\s+(\d+)\s+[\d.]+\s+([\d.e+-]+)\s", line)
            if m:
                out[m.group(1)] = (int(m.group(2)), float(m.group(3)))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--faces", type=int, default=40, help="cells per side (default 40: 201,720 unknowns)")
    ap.add_argument("--out", default=os.path.join(ROOT, "bench"))
    args = ap.parse_args()
    n = args.faces
    runs = os.path.join(args.out, "runs", "profile3d")
    os.makedirs(runs, exist_ok=True)
    rows = []
    for method in ("none", "penalty"):
        h5, log = os.path.join(runs, f"{method}.h5"), os.path.join(runs, f"{method}.log_view.txt")
        cmd = ["mpiexec", "-n", "1", BIN, "-options_file", "options/square.yaml", "-contact_monitor", "0", "-dm_plex_dim", "3",
               "-dm_plex_box_faces", f"{n},{n},{n}", "-contact_method", method, "-perf_bandwidth", "-log_view", f"ascii:{log}", "-output", h5]
        r = run_mpi(cmd, timeout=1200)
        if r.returncode != 0:
            sys.exit(f"{' '.join(cmd)} failed:\n{r.output[-3000:]}")
        with h5py.File(h5, "r") as f:
            a = dict(f["run"].attrs)
        ev = events(log)
        t = lambda k: ev.get(k, (0, 0.0))[1]  # noqa: E731
        c = lambda k: ev.get(k, (0, 0.0))[0]  # noqa: E731
        row = {"run": "elastic" if method == "none" else "penalty", "dofs": int(a["n_dofs"]), "default_mg": int(a.get("default_mg", 0)),
               "coarse_levels": int(a.get("coarse_levels", 0)), "newton_total": int(a["newton_its_total"]), "cg_total": int(a["ksp_its_total"]),
               "time_total": float(a["time_total"]), "time_setup": float(a["time_setup"]), "time_solve": float(a["time_solve"]),
               "snes_solve": t("SNESSolve"), "residual_jacobian": t("SNESFunctionEval") + t("SNESJacobianEval"), "residuals": c("SNESFunctionEval"),
               "pc_setup": t("PCSetUp"), "pc_setups": c("PCSetUp"), "galerkin": t("MatPtAPNumeric") + t("MatPtAPSymbolic"), "lu": t("MatLUFactorNum"),
               "ksp_solve": t("KSPSolve"), "vcycles": t("PCApply"), "vcycle_count": c("PCApply"), "matmult": t("MatMult"),
               "triad_gbs": float(a["bandwidth_triad_gbs"]), "vcycle_gbs": float(a["bandwidth_vcycle_gbs"]), "vcycle_ms": 1e3 * float(a["time_vcycle"]),
               "matmult_gbs": float(a["bandwidth_matmult_gbs"])}
        row["rest"] = row["time_total"] - row["time_setup"] - row["time_solve"]
        rows.append(row)
        print(row, flush=True)
    write_text(os.path.join(args.out, "profile3d.csv"), dict_csv_text(list(rows[0]), rows))
    e, p = rows
    lines = [f"# Where the time of the 3D default run goes ({n}^3 box, {e['dofs']} unknowns, one rank)", "",
             f"`/usr/bin/python3 scripts/profile3d.py` (make bench): `bin/signorini -options_file options/square.yaml -dm_plex_dim 3 -dm_plex_box_faces {n},{n},{n} "
             "[-contact_method none] -log_view -perf_bandwidth`, one run each (the time of one run, not a median: the ratios are `make bench`'s `default3d` section).",
             "PETSc's events are inclusive: the linear solves include their V-cycles, the solve includes the rest; the solve and set-up are the run's own clocks (`/run`).",
             "", "| | elastic | penalty | penalty - elastic |", "|---|---|---|---|"]
    items = [("whole run (time_total), s", "time_total"), ("set-up: mesh, boxes, sections, K (time_setup), s", "time_setup"),
             ("solve, all boxes (time_solve), s", "time_solve"), ("  residual and Jacobian evaluations (SNESFunctionEval + SNESJacobianEval), s", "residual_jacobian"),
             ("  preconditioner set-ups (PCSetUp), s", "pc_setup"), ("    of which Galerkin products (MatPtAP), s", "galerkin"),
             ("    of which coarsest factorizations (MatLUFactorNum), s", "lu"), ("  linear solves (KSPSolve), s", "ksp_solve"),
             ("    of which V-cycles (PCApply), s", "vcycles"), ("after the solve: estimate, output (time_total - set-up - solve), s", "rest")]
    for label, k in items:
        lines.append(f"| {label} | {e[k]:.3f} | {p[k]:.3f} | {p[k] - e[k]:+.3f} |")
    for label, k in (("Newton steps, all boxes", "newton_total"), ("CG iterations, all boxes", "cg_total"), ("V-cycles", "vcycle_count"),
                     ("PC set-ups (PETSc's count, every level's smoother included)", "pc_setups"), ("coarser boxes", "coarse_levels")):
        lines.append(f"| {label} | {e[k]} | {p[k]} | {p[k] - e[k]:+d} |")
    for label, k in (("triad GB/s", "triad_gbs"), ("MatMult GB/s (final Jacobian)", "matmult_gbs"), ("one V-cycle GB/s (a lower bound of its bytes)", "vcycle_gbs"),
                     ("one V-cycle, ms", "vcycle_ms")):
        lines.append(f"| {label} | {e[k]:.2f} | {p[k]:.2f} | |")
    lines += ["", f"The V-cycle runs at {p['vcycle_gbs'] / p['triad_gbs']:.2f} of the triad's bandwidth (penalty; elastic {e['vcycle_gbs'] / e['triad_gbs']:.2f}), "
              f"MatMult at {p['matmult_gbs'] / p['triad_gbs']:.2f}."]
    write_text(os.path.join(args.out, "profile3d.md"), "\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
