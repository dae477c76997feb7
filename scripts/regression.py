#!/usr/bin/python3
"""Record and compare the numbers of a fixed set of runs (options/regression/runs.yaml), so that a change of structure
can show that it keeps every number.

  regression.py run DIR [--bin PATH] [--runs FILE]   runs them, writing DIR/<name>.h5
  regression.py compare A B [--rtol R] [--atol T] [--allow-added]
                                                     /run attributes, vertex fields and the tables /solves, /steps, /cycles of A/<name>.h5 and B/<name>.h5:
                                                     reals to R relative (default 1e-12)
                                                     or T absolute (default 1e-14: a force, a
                                                     reaction or a field zero up to round-off), integers and strings equal, the
                                                     final residual (round-off) to 1e-12 of the load; timings, memory and
                                                     file names are not compared. Exit 1 on a difference.
"""
import argparse
import os
import shlex
import subprocess
import sys

import numpy as np
import yaml

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from signorini.mpirun import run_mpi  # noqa: E402
from signorini.paths import ROOT  # noqa: E402
from signorini.runs import read_run, vertex_fields  # noqa: E402

NOT_COMPARED = ("time_", "peak_memory", "reference")
NOT_COMPARED_COLUMNS = ("time", "memory_mb")  # the tables' timings and memory
TABLES = ("solves", "steps", "cycles")


def tables(path):
    """The columns of the tables /solves, /steps and /cycles, as {"group/column": array}."""
    import h5py
    out = {}
    with h5py.File(path, "r") as f:
        for group in TABLES:
            if group in f:
                for name, dataset in f[group].items():
                    out[f"{group}/{name}"] = np.asarray(dataset[()], dtype=float).ravel()
    return out
TIMEOUT = 600  # seconds per run


def load_runs(path):
    with open(path) as fh:
        runs = yaml.safe_load(fh)["runs"]
    for r in runs:
        if set(r) - {"name", "ranks", "args"} or "name" not in r or "args" not in r:
            raise ValueError(f"{path}: a run needs name and args (and may have ranks): {r}")
    return runs


def run_all(directory, binary, runs):
    os.makedirs(directory, exist_ok=True)
    failed = 0
    for r in runs:
        out = os.path.join(os.path.abspath(directory), r["name"] + ".h5")
        cmd = ["mpiexec", "-n", str(r.get("ranks", 1)), binary] + shlex.split(r["args"]) + ["-output", out]
        p = run_mpi(cmd, timeout=TIMEOUT)
        if p.timed_out:
            raise subprocess.TimeoutExpired(cmd, TIMEOUT)
        with open(out[:-3] + ".log", "w") as fh:
            fh.write(p.output)
        print(f"{r['name']}: exit {p.returncode}")
        failed += p.returncode != 0
    return 1 if failed else 0


def compare_one(a, b, rtol, allow_added=False, atol=1e-14):
    diffs = []
    ra, rb = read_run(a), read_run(b)
    for key in sorted(set(ra) | set(rb)):
        if key == "file" or key.startswith(NOT_COMPARED) or (allow_added and key not in ra):
            continue
        va, vb = ra.get(key), rb.get(key)
        if key == "residual_norm" and "load_norm" in rb:  # a converged residual is round-off: compared to the load
            same = abs(va - vb) <= 1e-12 * rb["load_norm"]
        elif isinstance(va, float) and isinstance(vb, float):
            same = va == vb or (np.isnan(va) and np.isnan(vb)) or abs(va - vb) <= max(rtol * max(abs(va), abs(vb)), atol)
        else:
            same = va == vb
        if not same:
            diffs.append(f"/run {key}: {va} != {vb}")
    ta, tb = tables(a), tables(b)
    for key in sorted(set(ta) | set(tb)):
        if key.split("/")[-1].startswith(NOT_COMPARED_COLUMNS) or (allow_added and key not in ta):
            continue
        if key not in ta or key not in tb or ta[key].shape != tb[key].shape:
            diffs.append(f"table {key}: missing or of another length")
            continue
        x, y = ta[key], tb[key]
        same = (x == y) | (np.isnan(x) & np.isnan(y)) | (np.abs(x - y) <= np.maximum(rtol * np.maximum(np.abs(x), np.abs(y)), atol))
        if not np.all(same):
            diffs.append(f"table {key}: rows {np.flatnonzero(~same).tolist()} differ")
    fa, fb = vertex_fields(a), vertex_fields(b)
    for key in sorted(set(fa) | set(fb)):
        if allow_added and key not in fa:
            continue
        if key not in fa or key not in fb or fa[key].shape != fb[key].shape:
            diffs.append(f"field {key}: missing or of another shape")
            continue
        scale = max(np.abs(fa[key]).max(), np.abs(fb[key]).max(), 1e-300)
        diff = np.abs(fa[key] - fb[key]).max()
        d = diff / scale
        if d > rtol and diff > atol:  # a field zero up to round-off (a reaction of 1e-17) differs only by round-off
            diffs.append(f"field {key}: relative difference {d:.3e}")
    return diffs


def compare_all(dir_a, dir_b, runs, rtol, allow_added=False, atol=1e-14):
    bad = 0
    for r in runs:
        a, b = os.path.join(dir_a, r["name"] + ".h5"), os.path.join(dir_b, r["name"] + ".h5")
        if not (os.path.exists(a) and os.path.exists(b)):
            print(f"{r['name']}: MISSING ({a if not os.path.exists(a) else b})")
            bad += 1
            continue
        diffs = compare_one(a, b, rtol, allow_added, atol)
        print(f"{r['name']}: {'same' if not diffs else 'DIFFERENT'}")
        for d in diffs:
            print(f"    {d}")
        bad += bool(diffs)
    print(f"{len(runs) - bad} same, {bad} different")
    return 1 if bad else 0


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", default=os.path.join(ROOT, "options", "regression", "runs.yaml"))
    sub = parser.add_subparsers(dest="command", required=True)
    p_run = sub.add_parser("run")
    p_run.add_argument("directory")
    p_run.add_argument("--bin", default=os.path.join(ROOT, "bin", "signorini"))
    p_cmp = sub.add_parser("compare")
    p_cmp.add_argument("a")
    p_cmp.add_argument("b")
    p_cmp.add_argument("--rtol", type=float, default=1e-12)
    p_cmp.add_argument("--atol", type=float, default=1e-14, help="absolute tolerance of the /run reals (round-off zeros)")
    p_cmp.add_argument("--allow-added", action="store_true", help="attributes of /run and vertex fields that only B has are not differences")
    args = parser.parse_args(argv)
    runs = load_runs(args.runs)
    if args.command == "run":
        return run_all(args.directory, os.path.abspath(args.bin), runs)
    return compare_all(args.a, args.b, runs, args.rtol, args.allow_added, args.atol)


if __name__ == "__main__":
    sys.exit(main())
