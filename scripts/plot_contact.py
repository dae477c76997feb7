#!/usr/bin/python3
"""Plot contact pressure and normal gap along the contact boundary Gamma_C.

Reads a solver HDF5 output file, selects the vertices with
/vertex_fields/contact_boundary == 1 and plots, against the first coordinate
x_1 (or the abscissa of --along), the contact pressure (top) and the normal gap
g - u_n (bottom). Where many vertices share an abscissa (3D faces), the values
are scattered and the mean per distinct abscissa is overlaid as a line.

--along x|y|z: a coordinate; arc (2D): the signed arc length along a curved
contact curve from its lowest vertex; r: the distance from the lowest vertex in
the coordinates other than the last (a body touching a plane x_d = const).

With -bars the file holds the pressure's error band (the vertex field contact_pressure_bar: the mesh's part from the
2h level and the penalty's from the second eps, docs/estimate.md), drawn as a shaded band p +- bar around the pressure.

--zoom auto|on|off: the abscissa range shown. auto (the default) zooms on the contact zone (the vertices with a
positive pressure, and the free vertices next to them) when it spans less than a third of Gamma_C: a Hertz contact
of width 0.03 on a unit arc is then the whole plot, not its first 4%; the title says so. off shows Gamma_C whole.

Usage:
    plot_contact.py FILE.h5 [-o OUT.png] [--along x|y|z|arc|r] [--zoom auto|on|off]

The default output is FILE with .h5 replaced by _contact.png. Exit code 2 if
the file cannot be read or has no contact-boundary vertices.
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from signorini.figures import plt, save_png  # noqa: E402
from signorini.runs import ABSCISSAE, read_contact_fields  # noqa: E402,F401


def default_output(h5path):
    """FILE.h5 -> FILE_contact.png (suffix appended if not ending in .h5)."""
    base = h5path[:-3] if h5path.endswith(".h5") else h5path
    return base + "_contact.png"


def mean_per_x(x1, values, decimals=10):
    """Mean of `values` per distinct x1 (rounded to `decimals`); sorted."""
    keys, inverse = np.unique(np.round(x1, decimals), return_inverse=True)
    sums = np.bincount(inverse, weights=values, minlength=len(keys))
    counts = np.bincount(inverse, minlength=len(keys))
    return keys, sums / counts


def make_title(run):
    """Title string from the /run attributes (missing ones shown as '?')."""
    def fmt(key):
        v = run.get(key, "?")
        return "%.4g" % v if isinstance(v, (float, np.floating)) else str(v)
    return (f"{fmt('scene')} | {fmt('method')} | dim={fmt('dim')} | h={fmt('h')}"
            f" | eps={fmt('eps')} | converged={fmt('converged')}")


def contact_window(t, p, neighbours=2, fraction=1.0 / 3.0):
    """The abscissa window (lo, hi) of the contact zone: the vertices with p > 0 and, on each side, the next
    `neighbours` distinct abscissae (the zone's edge and the gap opening beyond it). None when nothing is in contact, or
    when the zone spans more than `fraction` of the whole range (zooming would hide little)."""
    keys = np.unique(np.round(t, 12))
    if not (p > 0.0).any() or len(keys) < 2:
        return None
    lo, hi = t[p > 0.0].min(), t[p > 0.0].max()
    i, j = np.searchsorted(keys, np.round(lo, 12)), np.searchsorted(keys, np.round(hi, 12))
    lo, hi = keys[max(i - neighbours, 0)], keys[min(j + neighbours, len(keys) - 1)]
    if hi - lo > fraction * (keys[-1] - keys[0]):
        return None
    return lo, hi


XLABELS = {"x": "$x_1$", "y": "$x_2$", "z": "$x_3$", "arc": "arc length from the lowest contact vertex", "r": "distance from the lowest contact vertex"}


def plot_contact(h5path, pngpath, along="x", zoom="auto"):
    """Plot pressure and gap along Gamma_C of `h5path` into `pngpath`; return it."""
    x1, fields, run = read_contact_fields(h5path, along, optional=("contact_pressure_bar",))
    p, g, bar = fields["contact_pressure"], fields["normal_gap"], fields.get("contact_pressure_bar")
    window = contact_window(x1, p, fraction=1.0 if zoom == "on" else 1.0 / 3.0) if zoom != "off" else None
    if window:  # the values inside the window only, so that the axes fit them
        inside = (x1 >= window[0]) & (x1 <= window[1])
        x1, p, g = x1[inside], p[inside], g[inside]
        bar = bar[inside] if bar is not None else None
    keys = np.unique(np.round(x1, 10))
    many = len(keys) < len(x1)  # several vertices per x_1 (3D faces)
    fig, (ax_p, ax_g) = plt.subplots(2, 1, sharex=True, figsize=(8, 6.5))
    for ax, vals, label, color in ((ax_p, p, "contact pressure", "tab:red"),
                                   (ax_g, g, "normal gap $g - u_n$", "tab:blue")):
        if many:
            ax.scatter(x1, vals, s=12, alpha=0.5, color=color, label="vertices")
            xm, vm = mean_per_x(x1, vals)
            ax.plot(xm, vm, "-o", ms=3, color="k", lw=1.2, label="mean per abscissa")
        else:
            xm, vm = x1, vals
            ax.plot(x1, vals, "-o", ms=4, color=color, label=label if bar is not None and ax is ax_p else None)
        if bar is not None and ax is ax_p:  # the band around the curve drawn (the mean per abscissa in 3D)
            bm = mean_per_x(x1, bar)[1] if many else bar
            ax.fill_between(xm, vm - bm, vm + bm, color=color, alpha=0.25, lw=0, label="error band (-bars: mesh + eps)")
        if many or (bar is not None and ax is ax_p):
            ax.legend(loc="best", fontsize=8)
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
    ax_g.axhline(0.0, color="gray", lw=1, ls="--")
    ax_g.set_xlabel(XLABELS[along])
    title = make_title(run)
    if window:
        title += f"\nzoomed on the contact zone: {window[0]:.4g} to {window[1]:.4g} (--zoom off: the whole of Gamma_C)"
    fig.suptitle(title, fontsize=10)
    save_png(fig, pngpath, 120)
    return pngpath


def main(argv=None):
    """Command-line entry point; returns the process exit code."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("h5file", metavar="FILE.h5", help="solver HDF5 output file")
    ap.add_argument("-o", "--output", metavar="OUT.png", default=None,
                    help="output PNG (default: FILE_contact.png)")
    ap.add_argument("--along", choices=ABSCISSAE, default="x", help="abscissa: a coordinate, the arc length (2D) or r (default x)")
    ap.add_argument("--zoom", choices=("auto", "on", "off"), default="auto",
                    help="auto: the contact zone when it spans less than a third of Gamma_C (default); on: always; off: never")
    args = ap.parse_args(argv)
    out = args.output or default_output(args.h5file)
    try:
        plot_contact(args.h5file, out, args.along, args.zoom)
    except ValueError as exc:
        print(f"plot_contact.py: error: {exc}", file=sys.stderr)
        return 2
    print(out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
