#!/usr/bin/python3
"""Collect the /run metadata of solver HDF5 output files into a table.

All attributes of /run are read generically (bytes decoded, numpy scalars ->
int/float). Directories expand to their sorted *.h5 files; an unreadable file or
one without /run is an error (exit code 2), never skipped.

Usage: read_runs.py FILE_OR_DIR [...] [--format markdown|csv] [--columns a,b,c] [-o OUT]
"""
import argparse
import csv
import io
import os
import sys

import h5py
import numpy as np

DEFAULT_COLUMNS = [
    "file", "scene", "dim", "method", "penalty_quadrature", "degree", "nprocs",
    "n_dofs", "h", "eps", "converged", "snes_reason", "newton_its", "ksp_its",
    "active_vertices", "max_penetration", "contact_force", "energy",
    "time_solve", "time_total",
]
FORMATS = ("markdown", "csv")


def to_python(value):
    """Convert an HDF5 attribute value to plain Python (bytes -> str, numpy -> int/float/list)."""
    if isinstance(value, (bytes, np.bytes_)):
        return bytes(value).decode("utf-8", errors="replace")
    if isinstance(value, np.ndarray):
        if value.ndim == 0:
            return to_python(value[()])
        return [to_python(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


def read_run(path):
    """Return all attributes of /run in the HDF5 file `path` as a dict.

    The key "file" is set to `path`. Raises ValueError naming the file if it
    cannot be opened or has no /run group.
    """
    try:
        with h5py.File(path, "r") as f:
            if "run" not in f:
                raise ValueError(f"{path}: no /run group")
            run = {"file": str(path)}
            for key, value in f["run"].attrs.items():
                run[key] = to_python(value)
            return run
    except ValueError:
        raise
    except Exception as exc:  # h5py raises OSError and others
        raise ValueError(f"{path}: cannot read HDF5 file ({exc})") from exc


def expand_paths(paths):
    """Expand directories into their sorted *.h5 files; ValueError on a missing path or empty dir."""
    out = []
    for p in paths:
        p = str(p)
        if os.path.isdir(p):
            files = sorted(os.path.join(p, n) for n in os.listdir(p)
                           if n.endswith(".h5") and os.path.isfile(os.path.join(p, n)))
            if not files:
                raise ValueError(f"{p}: directory contains no *.h5 files")
            out.extend(files)
        elif os.path.exists(p):
            out.append(p)
        else:
            raise ValueError(f"{p}: no such file or directory")
    return out


def read_runs(paths):
    """Read /run of every file in `paths` (directories expanded); list of dicts."""
    return [read_run(p) for p in expand_paths(paths)]


def all_columns(runs):
    """Union of the keys of all runs, in order of first appearance."""
    cols = {}
    for run in runs:
        for key in run:
            cols.setdefault(key, None)
    return list(cols)


def format_markdown(runs, columns):
    """Render runs as a markdown table; floats with %.6g, missing -> empty."""
    def cell(v):
        if v is None:
            return ""
        if isinstance(v, float):
            return "%.6g" % v
        return str(v).replace("|", "\\|")
    lines = ["| " + " | ".join(columns) + " |",
             "|" + "|".join("---" for _ in columns) + "|"]
    for run in runs:
        lines.append("| " + " | ".join(cell(run.get(c)) for c in columns) + " |")
    return "\n".join(lines) + "\n"


def format_csv(runs, columns):
    """Render runs as CSV with full float precision (repr); missing -> empty."""
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(columns)
    for run in runs:
        writer.writerow([repr(v) if isinstance(v, float) else ("" if v is None else v)
                         for v in (run.get(c) for c in columns)])
    return buf.getvalue()


def main(argv=None):
    """Command-line entry point; returns the process exit code."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("paths", nargs="+", metavar="FILE_OR_DIR",
                    help="HDF5 output files or directories of *.h5 files")
    ap.add_argument("--format", default="markdown", help="markdown (default) or csv")
    ap.add_argument("--columns", default=None,
                    help="comma-separated column list, or 'all' (default: a standard set)")
    ap.add_argument("-o", "--output", default=None, help="write the table to OUT instead of stdout")
    args = ap.parse_args(argv)

    if args.format not in FORMATS:
        print(f"read_runs.py: error: unknown --format {args.format!r} "
              f"(choose from {', '.join(FORMATS)})", file=sys.stderr)
        return 2
    try:
        runs = read_runs(args.paths)
    except ValueError as exc:
        print(f"read_runs.py: error: {exc}", file=sys.stderr)
        return 2

    if args.columns is None:
        columns = DEFAULT_COLUMNS
    elif args.columns.strip() == "all":
        columns = all_columns(runs)
    else:
        columns = [c.strip() for c in args.columns.split(",") if c.strip()]
    fmt = format_markdown if args.format == "markdown" else format_csv
    text = fmt(runs, columns)
    if args.output:
        with open(args.output, "w", newline="") as fh:
            fh.write(text)
    else:
        sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
