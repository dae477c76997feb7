#!/usr/bin/python3
"""make bench: what a penalty contact solve costs, against what users would pick instead, in one invocation.

For every problem of the bench file (options/bench/bench.yaml), every linear solver file options/solvers/<name>.yaml
and every rank count, on the same mesh:
  elastic     the linear elastic problem without contact (-contact_method none): assembly + one linear solve;
  penalty     the penalty problem, eps = h, from a zero guess;
  penalty_gs  the same with grid sequencing (-contact_grid_sequence N from the mesh coarsened N times);
(all on the coarse mesh of the bench file refined N times, the elastic, penalty and vi runs by -dm_refine N)
  vi          SNESVI (the exact Signorini constraint) from a zero guess;
  sweep       8 values of eps, each from the last solution, after a grid-sequenced first solve.
The time of a run is the solver's own set-up + solve time (/run time_setup + time_solve: mesh, assembly and solves;
not MPI start-up, post-processing or output). The tables go to bench/<name>.md and bench/<name>.csv, the runs
(HDF5 and console output) to bench/runs/<name>/.

A run longer than the bench file's `timeout` (seconds, default 3600) is stopped and listed as failed.
Usage: scripts/bench.py [options/bench/bench.yaml] [--outdir DIR] [--resume]
"""
import argparse
import os
import shlex
import sys
import time

import h5py
import yaml

SCRIPTS = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, SCRIPTS)
from signorini.formatting import fmt_sig as fmt  # noqa: E402
from signorini.mpirun import BENCH_ENV, MPI_ENV, run_mpi, tail  # noqa: E402,F401
from signorini.paths import BIN, ROOT  # noqa: E402
from signorini.report import dict_csv_text, write_atomic  # noqa: E402
from signorini.runs import decoded_attrs, read_solves  # noqa: E402
from signorini.studyfile import StudyError, option_value  # noqa: E402

KINDS = ("elastic", "penalty", "penalty_gs", "vi", "sweep")
COLUMNS = ["problem", "solver", "ranks", "kind", "n_dofs", "converged", "snes_reason", "newton_its", "newton_its_total",
           "ksp_its", "ksp_its_total", "pc_builds", "time_setup", "time_solve", "time", "wall", "peak_memory_mb",
           "memory_total_mb", "bytes_per_dof", "contact_force", "grid_newton", "sweep_ksp_per_newton", "note"]
# SNESVI's reduced system (vinewtonrsls) changes size between Newton steps, which GAMG cannot follow on PETSc 3.18;
# the solver refuses the combination with a message, and the bench lists it as skipped with that reason.
SKIP = {("vi", "gamg"): "SNESVI (vinewtonrsls) + GAMG is refused by the solver on PETSc 3.18"}


def load_bench(path):
    with open(path) as fh:
        bench = yaml.safe_load(fh)
    if not isinstance(bench, dict) or "problems" not in bench:
        raise StudyError(f"{path}: needs a 'problems' list")
    for key in ("name", "solvers", "ranks", "sweep_eps0", "problems"):
        if key not in bench:
            raise StudyError(f"{path}: missing key '{key}'")
    for solver in bench["solvers"]:
        if not os.path.exists(os.path.join(ROOT, "options", "solvers", f"{solver}.yaml")):
            raise StudyError(f"{path}: no options/solvers/{solver}.yaml")
    if len(bench["sweep_eps0"]) < 2:
        raise StudyError(f"{path}: sweep_eps0 needs at least 2 values")
    for p in bench["problems"]:
        for key in ("name", "options", "faces", "grid_sequence"):
            if key not in p:
                raise StudyError(f"{path}: problem {p.get('name', '?')} lacks '{key}'")
        if any(f % (1 << p["grid_sequence"]) for f in p["faces"]):
            raise StudyError(f"{path}: problem {p['name']}: faces {p['faces']} not divisible by 2^{p['grid_sequence']}")
    return bench


def faces_option(faces):
    return ",".join(str(f) for f in faces)


def case_args(problem, kind, bench):
    """Solver options of one run of `kind` on `problem` (beyond the problem's own options). Every run has the same
    mesh: the coarse box refined grid_sequence times, by -dm_refine or, for penalty_gs and sweep, by the sequence
    (in 3D a refined box is not the box generated with as many cells: its tetrahedra differ)."""
    n = problem["grid_sequence"]
    coarse = ["-dm_plex_box_faces", faces_option([f >> n for f in problem["faces"]])]
    refined = coarse + ["-dm_refine", str(n)]
    if kind == "elastic":
        return refined + ["-contact_method", "none"]
    if kind == "penalty":
        return refined
    if kind == "vi":
        return refined + ["-contact_method", "vi"]
    gs = coarse + ["-contact_grid_sequence", str(n)]
    if kind == "penalty_gs":
        return gs
    return gs + ["-penalty_eps0_sweep", ",".join(str(e) for e in bench["sweep_eps0"])]


def command(problem, solver, ranks, kind, bench, h5):
    cmd = ["mpiexec", "-n", str(ranks), BIN]
    for key, value in problem["options"].items():
        cmd += [f"-{key}", option_value(value, f"problem {problem['name']}")]
    cmd += ["-options_file", f"options/solvers/{solver}.yaml"] + case_args(problem, kind, bench)
    return cmd + ["-output", h5]


def run_case(problem, solver, ranks, kind, bench, outdir, resume=False):
    """Runs one case, or with resume reads the output an earlier invocation left (its log holds its exit status)."""
    row = {"problem": problem["name"], "solver": solver, "ranks": ranks, "kind": kind, "note": ""}
    if (kind, solver) in SKIP:
        row["note"] = "skipped: " + SKIP[(kind, solver)]
        return row
    name = f"{problem['name']}_{solver}_np{ranks}_{kind}"
    h5 = os.path.join(outdir, name + ".h5")
    log = h5[:-3] + ".log"
    cmd = command(problem, solver, ranks, kind, bench, os.path.relpath(h5, ROOT))
    limit = bench.get("timeout", 3600)
    if resume and os.path.exists(h5) and os.path.exists(log):
        with open(log) as fh:
            first = fh.readline().rstrip("\n")
        if first.startswith("exit ") and first.split(" ", 2)[2] == shlex.join(cmd):
            returncode = int(first.split(" ", 2)[1])
            return read_case(row, name, h5, cmd, returncode, "", problem, kind)
    if os.path.exists(h5):
        os.remove(h5)
    proc = run_mpi(cmd, timeout=limit, env=BENCH_ENV)
    returncode, output = (None if proc.timed_out else proc.returncode), proc.output
    row["wall"] = proc.wall
    with open(log, "w") as fh:
        fh.write(f"exit {returncode} {shlex.join(cmd)}\n" + output)
    if returncode is None:
        row["note"] = f"FAILED: stopped after the bench's time limit of {limit} s"
        return row
    return read_case(row, name, h5, cmd, returncode, output, problem, kind)


def read_case(row, name, h5, cmd, returncode, output, problem, kind):
    """Fills row from the output file of one run."""
    if not os.path.exists(h5):
        raise StudyError(f"{name}: exit status {returncode}, no output; command:\n  {shlex.join(cmd)}\n{tail(output, 15)}")
    with h5py.File(h5, "r") as f:
        a = decoded_attrs(f["run"])
        solves = read_solves(f)
    for key in ("n_dofs", "converged", "snes_reason", "newton_its", "newton_its_total", "ksp_its", "ksp_its_total",
                "pc_builds", "time_setup", "time_solve", "peak_memory_mb", "contact_force"):
        row[key] = a[key]
    row["time"] = a["time_setup"] + a["time_solve"]
    row["memory_total_mb"] = a["peak_memory_total_mb"]
    row["bytes_per_dof"] = a["peak_memory_total_mb"] * 1048576.0 / a["n_dofs"]
    if kind in ("penalty_gs", "sweep") and solves:
        levels = solves["level"].astype(int)
        row["grid_newton"] = "/".join(str(int(solves["newton_its"][i])) for i in range(len(levels))
                                      if kind == "penalty_gs" or i <= problem["grid_sequence"])
    if kind == "sweep" and solves:
        first = problem["grid_sequence"]  # the last grid level solves the first eps of the sweep
        per = [solves["ksp_its"][i] / max(solves["newton_its"][i], 1) for i in range(first, len(solves["eps"]))]
        row["sweep_ksp_per_newton"] = "/".join(f"{p:.0f}" for p in per)
        row["sweep_solved"] = len(per)
    if returncode != 0 or a["converged"] != 1:
        row["note"] = f"FAILED: exit {returncode}, {a['snes_reason']}"
    return row


def find(rows, problem, solver, ranks, kind):
    for r in rows:
        if (r["problem"], r["solver"], r["ranks"], r["kind"]) == (problem, solver, ranks, kind) and r.get("converged") == 1:
            return r
    return None


def ratio(a, b, key="time"):
    return a[key] / b[key] if a and b and b.get(key) else float("nan")


def summarize(rows, bench):
    """One line per (problem, solver, ranks): the ratios of the issue's targets."""
    out = []
    for p in bench["problems"]:
        for solver in p.get("solvers", bench["solvers"]):
            for ranks in bench["ranks"]:
                g = {k: find(rows, p["name"], solver, ranks, k) for k in KINDS}
                one = {k: find(rows, p["name"], solver, bench["ranks"][0], k) for k in KINDS}
                s = {"problem": p["name"], "solver": solver, "ranks": ranks}
                s["penalty/elastic"] = ratio(g["penalty"], g["elastic"])
                s["penalty_gs/elastic"] = ratio(g["penalty_gs"], g["elastic"])
                s["sweep/penalty_gs"] = ratio(g["sweep"], g["penalty_gs"])
                s["vi/penalty_gs"] = ratio(g["vi"], g["penalty_gs"])
                s["newton_cold"] = g["penalty"]["newton_its"] if g["penalty"] else None
                s["newton_gs_finest"] = g["penalty_gs"]["newton_its"] if g["penalty_gs"] else None
                s["bytes_per_dof_penalty_gs"] = g["penalty_gs"]["bytes_per_dof"] if g["penalty_gs"] else float("nan")
                s["speedup_penalty_gs"] = ratio(one["penalty_gs"], g["penalty_gs"]) if ranks != bench["ranks"][0] else float("nan")
                s["speedup_elastic"] = ratio(one["elastic"], g["elastic"]) if ranks != bench["ranks"][0] else float("nan")
                s["sweep_ksp_per_newton"] = g["sweep"]["sweep_ksp_per_newton"] if g["sweep"] else ""
                out.append(s)
    return out


def markdown(rows, summary, bench, machine):
    lines = [f"# Benchmark `{bench['name']}`", "", machine, "",
             "Time = the solver's set-up + solve time in seconds (mesh, assembly, solves).",
             "Memory = peak resident set summed over ranks; B/dof = that over the number of unknowns.", "",
             "## Ratios", "",
             "| problem | solver | ranks | penalty / elastic | penalty (grid seq.) / elastic | "
             f"{len(bench['sweep_eps0'])}-eps sweep / penalty (grid seq.) "
             "| SNESVI / penalty (grid seq.) | Newton, zero guess | Newton finest, grid seq. | B/dof | speed-up vs 1 rank "
             "| Krylov per Newton step, eps0 = " + ", ".join(str(e) for e in bench["sweep_eps0"]) + " |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for s in summary:
        lines.append(f"| {s['problem']} | {s['solver']} | {s['ranks']} | {fmt(s['penalty/elastic'])} | "
                     f"{fmt(s['penalty_gs/elastic'])} | {fmt(s['sweep/penalty_gs'])} | {fmt(s['vi/penalty_gs'])} | "
                     f"{fmt(s['newton_cold'])} | {fmt(s['newton_gs_finest'])} | {fmt(s['bytes_per_dof_penalty_gs'], 4)} | "
                     f"{fmt(s['speedup_penalty_gs'])} | {fmt(s['sweep_ksp_per_newton'])} |")
    lines += ["", "## Runs", "",
              "| problem | solver | ranks | run | dofs | time s | setup s | solve s | Newton (levels) | Krylov | PC builds "
              "| memory MB | B/dof | contact force | note |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        newton = fmt(r.get("newton_its")) + (f" ({r['grid_newton']})" if r.get("grid_newton") else "")
        lines.append(f"| {r['problem']} | {r['solver']} | {r['ranks']} | {r['kind']} | {fmt(r.get('n_dofs'))} | "
                     f"{fmt(r.get('time'))} | {fmt(r.get('time_setup'))} | {fmt(r.get('time_solve'))} | {newton} | "
                     f"{fmt(r.get('ksp_its'))} | {fmt(r.get('pc_builds'))} | {fmt(r.get('memory_total_mb'), 4)} | "
                     f"{fmt(r.get('bytes_per_dof'), 4)} | {fmt(r.get('contact_force'), 6)} | {r.get('note', '')} |")
    return "\n".join(lines) + "\n"


def machine_line():
    cpu = "unknown CPU"
    try:
        with open("/proc/cpuinfo") as fh:
            cpu = next(line.split(":", 1)[1].strip() for line in fh if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    mem = ""
    try:
        with open("/proc/meminfo") as fh:
            mem = f", {int(fh.readline().split()[1]) / 1048576:.0f} GB RAM"
    except (OSError, ValueError, IndexError):
        pass
    return f"Machine: {cpu}, {os.cpu_count()} cores{mem}; measured {time.strftime('%Y-%m-%d')}."


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("bench", nargs="?", default="options/bench/bench.yaml")
    ap.add_argument("--outdir", default="bench", help="directory of the tables (default bench/)")
    ap.add_argument("--resume", action="store_true", help="reuse the outputs of an earlier invocation with the same commands")
    args = ap.parse_args(argv)
    try:
        bench = load_bench(os.path.join(ROOT, args.bench) if not os.path.isabs(args.bench) else args.bench)
        outdir = os.path.join(ROOT, args.outdir)
        rundir = os.path.join(outdir, "runs", bench["name"])
        os.makedirs(rundir, exist_ok=True)
        rows = []
        for p in bench["problems"]:
            for solver in p.get("solvers", bench["solvers"]):
                for ranks in bench["ranks"]:
                    for kind in KINDS:
                        r = run_case(p, solver, ranks, kind, bench, rundir, args.resume)
                        rows.append(r)
                        print(f"{p['name']:10s} {solver:6s} np={ranks} {kind:10s} time {fmt(r.get('time'))} s, "
                              f"Newton {fmt(r.get('newton_its'))}, Krylov {fmt(r.get('ksp_its'))} {r.get('note', '')}",
                              flush=True)
    except StudyError as exc:
        print(f"bench: {exc}", file=sys.stderr)
        return 1
    summary = summarize(rows, bench)
    md = markdown(rows, summary, bench, machine_line())
    base = os.path.join(outdir, bench["name"])
    write_atomic(base + ".md", md)
    write_atomic(base + ".csv", dict_csv_text(COLUMNS, rows))
    print(md)
    print(f"written {os.path.relpath(base, ROOT)}.md and .csv")
    return 0


if __name__ == "__main__":
    sys.exit(main())
