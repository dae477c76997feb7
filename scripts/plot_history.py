#!/usr/bin/python3
"""Plot a load path's history: the force-depth curve and the contact quantities against the load factor.

Reads the /steps table of a solver output written with -load_steps or -load_path (one row per step) and writes
  OUT.png: the obstacle's force against the indentation depth (its translation along the direction it moves in; the
           force against the load factor where the obstacle does not move), and the contact size, the largest
           pressure and the energy against the load factor (a failed step drawn as a cross);
  OUT.csv: every column of /steps, and depth and force_along where the obstacle moves, one row per step.

Usage:
    plot_history.py FILE.h5 [-o OUT.png] [--csv OUT.csv]

The defaults are FILE with .h5 replaced by _history.png and _history.csv. Exit code 2 if the file cannot be read or
has no /steps.
"""
import argparse
import csv
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from signorini.figures import plt, save_png  # noqa: E402
from signorini.history import history  # noqa: E402


def default_outputs(h5path):
    base = h5path[:-3] if h5path.endswith(".h5") else h5path
    return base + "_history.png", base + "_history.csv"


def write_csv(steps, path):
    names = list(steps)
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(names)
        for k in range(len(steps["factor"])):
            w.writerow([f"{steps[n][k]:.17g}" for n in names])


def plot_history(steps, path, title):
    ok = steps["converged"] > 0.5
    fig, axes = plt.subplots(2, 2, figsize=(10, 7))
    if "depth" in steps:
        x, y, xl, yl = steps["depth"], steps["force_along"], "indentation depth", "force of the obstacle along its motion"
    else:
        x, y, xl, yl = steps["factor"], steps["contact_force"], "load factor", "contact force"
    panels = ((x, y, xl, yl), (steps["factor"], steps["contact_size"], "load factor", "contact size"),
              (steps["factor"], steps["pressure_max"], "load factor", "largest contact pressure"),
              (steps["factor"], steps["energy"], "load factor", "energy"))
    for ax, (px, py, lx, ly) in zip(axes.ravel(), panels):
        ax.plot(px[ok], py[ok], "o-", ms=4)
        if (~ok).any():
            ax.plot(px[~ok], py[~ok], "rx", ms=8, label="failed step")
            ax.legend(fontsize=8)
        ax.set_xlabel(lx)
        ax.set_ylabel(ly)
        ax.grid(True, alpha=0.3)
    fig.suptitle(title, fontsize=10)
    save_png(fig, path, 120)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("h5file", metavar="FILE.h5", help="solver HDF5 output of a load path")
    ap.add_argument("-o", "--output", metavar="OUT.png", default=None, help="output PNG (default: FILE_history.png)")
    ap.add_argument("--csv", metavar="OUT.csv", default=None, help="output CSV (default: FILE_history.csv)")
    args = ap.parse_args(argv)
    png, table = default_outputs(args.h5file)
    png, table = args.output or png, args.csv or table
    try:
        steps = history(args.h5file)
    except (OSError, ValueError, KeyError) as exc:
        print(f"plot_history.py: error: {exc}", file=sys.stderr)
        return 2
    n, failed = len(steps["factor"]), int(np.sum(steps["converged"] < 0.5))
    plot_history(steps, png, f"{os.path.basename(args.h5file)}: {n} steps" + (f", {failed} failed" if failed else ""))
    write_csv(steps, table)
    print(png)
    print(table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
