#!/usr/bin/env python3
"""How close Hertz's closed form holds for the 2D cylinder indenter: the model the solver solves lets the rigid cylinder
act along its own normal, which leans by r / R from the vertical at the distance r from the axis, on the body's surface
points as they move sideways (u_x, which the Poisson effect drives: (1 - 2 nu) / (1 - nu) in the half-space's surface
displacement); Hertz's theory takes the vertical and the undeformed surface. Their a and p0 then differ at the order
(1 - 2 nu) / (1 - nu) a / R, which no mesh removes. This study measures it: the indenter of make accuracy-ladder (the
10 x 10 block, eps = h/10) at -accuracy 0.01 with R = 1 (make hertz's, a / R = 0.017), R = 10 (the depth 10 times
smaller, the same a) and R = 1 with nu = 0, each against its closed form: the fitted a and p0 and the moments' a
(signorini.hertz.measure), the width and the largest pressure, and the fitted a's offset over
(1 - 2 nu) / (1 - nu) a / R. Writes output/hertz_curvature/hertz_curvature.md and .csv.

    /usr/bin/python3 scripts/hertz_curvature.py [--tol 0.01]
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from signorini import estimates as st  # noqa: E402
from signorini import geometry, hertz  # noqa: E402
from signorini.mpirun import timed_or_exit as solve  # noqa: E402
from signorini.paths import ROOT  # noqa: E402
from signorini.report import csv_text, write_text  # noqa: E402
from signorini.runs import read_run  # noqa: E402

CASE = "cylinder-indenter"
QUANTITIES = "contact_force,pressure_max,contact_size"
VARIANTS = ((1.0, 0.3), (10.0, 0.3), (1.0, 0.0))  # (R, nu)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--tol", type=float, default=0.01, help="-accuracy of each run")
    ap.add_argument("--outdir", default=os.path.join(ROOT, "output", "hertz_curvature"))
    args = ap.parse_args()
    os.makedirs(args.outdir, exist_ok=True)
    coarse = os.path.join(args.outdir, "block10_h0.5.msh")
    geometry.block(coarse, radius=st.BLOCK, h_far=0.5, h_near=0.5, width=3.0, near=0.6)
    rows = []
    for radius, nu in VARIANTS:
        out = os.path.join(args.outdir, f"indenter_R{radius:g}_nu{nu:g}.h5")
        solve(hertz.command(CASE, coarse, "eps=h/10", out, radius=radius, poisson=nu)[3:]
              + ["-accuracy", str(args.tol), "-accuracy_quantity", QUANTITIES, "-options_file", "options/solvers/gamg.yaml"])
        m, r = hertz.measure(CASE, out, radius=radius, poisson=nu), read_run(out)
        scale = (1 - 2 * nu) / (1 - nu) * m["a"] / radius
        rows.append([radius, nu, int(m["n_dofs"]), m["a"] / radius, m["a_fit"] / m["a"] - 1, m["p0_h"] / m["p0"] - 1, m["a_error"],
                     float(r["contact_size"]) / m["a"] - 1, float(r["pressure_max"]) / m["p0"] - 1, scale, (m["a_fit"] / m["a"] - 1) / scale])
        print(f"R {radius:g}, nu {nu:g}: {rows[-1][2]} unknowns, fitted a {rows[-1][4]:+.3%}", flush=True)
    header = ["radius", "poisson", "n_dofs", "a_over_R", "a_fit_error", "p0_fit_error", "a_moments_error", "width_error", "pressure_max_error",
              "curvature_scale", "a_fit_error_over_scale"]
    write_text(os.path.join(args.outdir, "hertz_curvature.csv"), csv_text(header, rows))
    text = [f"# Hertz's closed form against the 2D cylinder indenter's model (block {st.BLOCK:g} x {st.BLOCK:g}, -accuracy {args.tol:g}, eps = h/10)", "",
            f"`/usr/bin/python3 scripts/hertz_curvature.py --tol {args.tol:g}`. Each run against its own closed form at its force; "
            "s = (1 - 2 nu) / (1 - nu) a / R.", "",
            "| R | nu | unknowns | a / R | fitted a | fitted p0 | moments' a | width | largest pressure | s | fitted a / s |",
            "|---|---|---|---|---|---|---|---|---|---|---|"]
    text += [f"| {r[0]:g} | {r[1]:g} | {r[2]} | {r[3]:.4f} | " + " | ".join(f"{v:+.3%}" for v in r[4:9]) + f" | {r[9]:.4f} | {r[10]:.3f} |"
             for r in rows]
    write_text(os.path.join(args.outdir, "hertz_curvature.md"), "\n".join(text) + "\n")
    print("\n".join(text))


if __name__ == "__main__":
    main()
