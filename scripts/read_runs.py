#!/usr/bin/python3
"""Collect the /run metadata of solver HDF5 output files into a table.

All attributes of /run are read generically (bytes decoded, numpy scalars ->
int/float). Directories expand to their sorted *.h5 files; an unreadable file or
one without /run is an error (exit code 2), never skipped.

Usage: read_runs.py FILE_OR_DIR [...] [--format markdown|csv] [--columns a,b,c] [-o OUT]
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from signorini.report import csv_text, md_row, md_rule  # noqa: E402
from signorini.runs import all_columns, expand_paths, read_run, read_runs, to_python  # noqa: E402,F401

DEFAULT_COLUMNS = [
    "file", "scene", "dim", "method", "penalty_quadrature", "degree", "nprocs",
    "n_dofs", "h", "eps", "converged", "snes_reason", "newton_its", "ksp_its",
    "active_vertices", "max_penetration", "contact_force", "energy",
    "time_solve", "time_total",
]
FORMATS = ("markdown", "csv")


def format_markdown(runs, columns):
    """Render runs as a markdown table; floats with %.6g, missing -> empty."""
    def cell(v):
        if v is None:
            return ""
        if isinstance(v, float):
            return "%.6g" % v
        return str(v).replace("|", "\\|")
    lines = [md_row(columns), md_rule(len(columns))]
    for run in runs:
        lines.append(md_row(cell(run.get(c)) for c in columns))
    return "\n".join(lines) + "\n"


def format_csv(runs, columns):
    """Render runs as CSV with full float precision (repr); missing -> empty."""
    return csv_text(columns, ([run.get(c) for c in columns] for run in runs))


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
