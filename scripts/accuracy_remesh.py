#!/usr/bin/env python3
"""-accuracy TOL by remeshing the body's Gmsh model (-adapt_model, issue 34) on make hertz's curved bodies: the elastic
cylinder (quarter disk, 2D) from a uniform h = 0.1, the elastic sphere (quarter sphere, 3D) from a uniform h = 0.2, and
(--cases sphere-indenter) the rigid sphere indenting the unit block (its quarter, 3D) from a uniform h = 0.2, eps = h/10. For each TOL: the cycles, unknowns and time, and at the stop the errors of the largest pressure and of the
zone's size (the half-width in 2D, the quarter zone's area in 3D) against the closed form at the run's force, and of
the force against the finest run's, each with the run's bar; and the moments' a and the fitted p0 of make hertz
(signorini.hertz.measure). Then make hertz's hand-graded meshes of the case, one solve each at the same eps, for the
fewest unknowns within TOL, timed side by side with the adaptive run (--pairs alternated pairs, medians). Writes
output/accuracy_remesh/accuracy_remesh.md and .csv.

    /usr/bin/python3 scripts/accuracy_remesh.py [--cases cylinder,sphere] [--tols 0.03,0.01] [--tols-3d 0.1] [--pairs 3] [--radius 1]
    /usr/bin/python3 scripts/accuracy_remesh.py --cases sphere-indenter --hand-bars 0.04,0.02,0.01  (the graded meshes with their own bars)
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from signorini import geometry, hertz  # noqa: E402
from signorini.mpirun import paired_medians, timing_text  # noqa: E402
from signorini.mpirun import timed_or_exit as solve  # noqa: E402
from signorini.paths import ROOT  # noqa: E402
from signorini.report import csv_text, own_bars_table, write_text  # noqa: E402
from signorini.runs import accuracy_bars, own_bars  # noqa: E402
from signorini.runs import read_cycles as cycles  # noqa: E402
from signorini.runs import read_run  # noqa: E402

# the largest pressure asked for: the nodal maximum in 2D, the recovered peak on tetrahedra, whose nodal pressures
# scatter by a few percent (src/physics/pressure_peak.c)
QUANTITIES = {2: ("contact_force", "pressure_max", "contact_size"), 3: ("contact_force", "pressure_peak", "contact_size")}
COARSE = {"cylinder": (geometry.quarter_disk, 0.1), "sphere": (geometry.quarter_sphere, 0.2), "sphere-indenter": (geometry.quarter_block, 0.2)}
SOLVER = {"cylinder": [], "sphere": hertz.GAMG_3D, "sphere-indenter": hertz.GAMG_3D}


# -bars' names of -accuracy's quantities in 3D: its largest pressure is the nodal maximum
BARS_QUANTITIES = ("contact_force_z", "pressure_max", "contact_size")


def hand_bars(args, case, adaptive, tols):
    """--hand-bars: make hertz's graded meshes of the case with their own bars (-bars on the mesh and two uniform
    refinements of it, whose finest has 64 times its unknowns); for each TOL, the fewest unknowns whose bars are all
    within TOL, timed side by side with the adaptive run. Markdown lines."""
    runs = []
    for h_near in (float(v) for v in args.hand_bars.split(",")):
        mesh = os.path.join(args.outdir, f"{case}_graded_{h_near:g}.msh")
        hertz.write_mesh(case, h_near, mesh)
        out = os.path.join(args.outdir, f"{case}_graded_bars_{h_near:g}.h5")
        cmd = hertz.command(case, mesh, "eps=h/10", out, radius=args.radius)[3:] + SOLVER[case] + ["-bars", "-contact_grid_sequence", "2"]
        solve(cmd)
        a = read_run(out)
        runs.append((f"h_near {h_near:g}", cmd, int(a["n_dofs"]), own_bars(a, BARS_QUANTITIES)))
        print(f"{case} hand-graded h_near {h_near:g} with -bars: {runs[-1][2]} unknowns", flush=True)
    intro = (f"{case}: make hertz's graded meshes with their own bars (`-bars -contact_grid_sequence 2`: the mesh and two uniform "
             "refinements, the answer and the unknowns the finest's; NaN: no bar, the three levels outside the asymptotic range):")
    return own_bars_table(runs, ["force's bar", "largest pressure's bar", "size's bar"], intro, tols,
                          {tol: (cmd, int(a["n_dofs"]), t_once) for tol, (cmd, a, _, _, t_once) in adaptive.items()}, args.pairs)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cases", default="cylinder,sphere")
    ap.add_argument("--tols", default="0.03,0.01", help="the tolerances in 2D")
    ap.add_argument("--tols-3d", default="0.1", help="the tolerances in 3D (3%% took 143,995 unknowns and 55 s on the sphere, one run: docs/estimate.md)")
    ap.add_argument("--pairs", type=int, default=3, help="alternated timing pairs of the adaptive and the hand-graded run (0: the first run's time alone)")
    ap.add_argument("--outdir", default=os.path.join(ROOT, "output", "accuracy_remesh"))
    ap.add_argument("--radius", type=float, default=hertz.RADIUS,
                    help="the sphere indenter's rigid radius, its depth 0.01 / radius (the same a; the closed form neglects terms of order a / R)")
    ap.add_argument("--hand-h-near", default=None, help="the hand-graded meshes' h_near, comma-separated (default: make hertz's, the case's)")
    ap.add_argument("--hand-h-far", type=float, default=None,
                    help="the hand-graded meshes' far-field size (default: make hertz's, 0.2 on the sphere, whose force stands 3%% off)")
    ap.add_argument("--hand-bars", default=None,
                    help="sphere-indenter: make hertz's graded meshes at these h_near (comma-separated) solved with their own bars "
                         "(-bars -contact_grid_sequence 2), as a user without a closed form would show the error")
    ap.add_argument("--peak-2d", action="store_true", help="ask for the recovered peak (pressure_peak) in 2D too, instead of the nodal maximum")
    args = ap.parse_args()
    if args.hand_bars and args.cases != "sphere-indenter":
        ap.error("--hand-bars takes --cases sphere-indenter alone: the curved bodies' uniform refinements keep their first mesh's "
                 "facets, whose error -bars cannot see")
    os.makedirs(args.outdir, exist_ok=True)
    rows, md = [], []
    for case in args.cases.split(","):
        tols = sorted((float(t) for t in (args.tols if hertz.CASES[case]["dim"] == 2 else args.tols_3d).split(",")), reverse=True)
        shape, h = COARSE[case]
        quantities = QUANTITIES[3 if args.peak_2d else hertz.CASES[case]["dim"]]
        mesh, model = os.path.join(args.outdir, f"{case}_h{h:g}.msh"), os.path.join(args.outdir, f"{case}.geo")
        shape(mesh, radius=hertz.RADIUS, h_far=h, h_near=h, width=0.5, model=model)
        adaptive = {}
        for tol in tols:
            out = os.path.join(args.outdir, f"{case}_accuracy_{tol:g}.h5")
            cmd = hertz.command(case, mesh, "eps=h/10", out, radius=args.radius)[3:] + SOLVER[case] + ["-adapt_model", model, "-accuracy", str(tol),
                                                                                     "-accuracy_quantity", ",".join(quantities)]
            t_once = solve(cmd)
            adaptive[tol] = (cmd, read_run(out), cycles(out), hertz.measure(case, out, radius=args.radius), t_once)
            print(f"{case} -accuracy {tol:g}: {adaptive[tol][1]['n_dofs']} unknowns", flush=True)
        axis = "xyz"[hertz.CASES[case]["dim"] - 1]
        force_ref = abs(float(adaptive[tols[-1]][1][f"contact_force_{axis}"]))
        hand = []
        h_nears = [float(v) for v in args.hand_h_near.split(",")] if args.hand_h_near else hertz.CASES[case]["h_near"]
        far = {"h_far": args.hand_h_far} if args.hand_h_far else {}
        for h_near in h_nears:
            label = f"{h_near:g}" + (f"_far{args.hand_h_far:g}" if far else "")
            hmesh = os.path.join(args.outdir, f"{case}_graded_{label}.msh")
            hertz.write_mesh(case, h_near, hmesh, **far)
            out = os.path.join(args.outdir, f"{case}_graded_{label}.h5")
            hcmd = hertz.command(case, hmesh, "eps=h/10", out, radius=args.radius)[3:] + SOLVER[case]
            solve(hcmd)
            hand.append((h_near, hcmd, read_run(out), hertz.measure(case, out, radius=args.radius)))
            print(f"{case} hand-graded h_near {h_near:g}: {hand[-1][2]['n_dofs']} unknowns", flush=True)
        hand.sort(key=lambda t: int(t[2]["n_dofs"]))
        for tol in tols:
            cmd, a, c, m, t_once = adaptive[tol]
            err = hertz.quantity_errors(case, a, force_ref, args.radius, quantities)
            bars = accuracy_bars(a, quantities)
            within = [t for t in hand if all(abs(hertz.quantity_errors(case, t[2], force_ref, args.radius, quantities)[q]) <= tol for q in quantities)]
            best = within[0] if within else None
            t_ad, t_hd = paired_medians(cmd, best[1] if best else None, args.pairs, once=t_once)
            ratio = t_ad / t_hd if best else float("nan")
            covered = all(abs(err[q]) <= bars[q] for q in quantities)
            rows.append([case, tol, len(c["n_dofs"]) - 1, int(a["n_dofs"]), int(a["accuracy_reached"]), t_ad, quantities[1]]
                        + [err[q] for q in quantities] + [bars[q] for q in quantities] + [m["a_error"], m["p0_error"], int(covered)]
                        + [best[0] if best else float("nan"), int(best[2]["n_dofs"]) if best else 0,
                           t_hd, ratio])
            md.append(f"| {case} | {tol:g} | {len(c['n_dofs']) - 1} | {int(a['n_dofs'])} | {'yes' if a['accuracy_reached'] else 'no'} | "
                      + " | ".join(("reference" if q == "contact_force" and tol == tols[-1] else f"{err[q]:+.3%}") + f" ({bars[q]:.2%})"
                                   for q in quantities)
                      + f" | {m['a_error']:+.3%}, {m['p0_error']:+.3%} | {'yes' if covered else 'NO'} | {t_ad:.2f} | "
                      + (f"{best[0]:g}: {int(best[2]['n_dofs'])} | {t_hd:.2f} | {ratio:.2f} |" if best else "none | | |"))
        for h_near, _, b, m in hand:
            e = hertz.quantity_errors(case, b, force_ref, args.radius, quantities)
            md.append(f"| {case} hand-graded h_near {h_near:g} | | | {int(b['n_dofs'])} | | " + " | ".join(f"{e[q]:+.3%}" for q in quantities)
                      + f" | {m['a_error']:+.3%}, {m['p0_error']:+.3%} | | | | | |")
    if args.hand_bars:
        md += hand_bars(args, case, adaptive, tols)
    header = ["case", "tol", "cycles", "n_dofs", "reached", "time", "pressure", "err_force", "err_pressure", "err_contact_size", "bar_force",
              "bar_pressure", "bar_contact_size", "a_error", "p0_error", "covered", "hand_h_near", "hand_n_dofs", "hand_time", "time_ratio"]
    write_text(os.path.join(args.outdir, "accuracy_remesh.csv"), csv_text(header, rows))
    text = ["# -accuracy by remeshing the Gmsh model on make hertz's curved bodies (eps = h/10)", "",
            f"`/usr/bin/python3 scripts/accuracy_remesh.py --cases {args.cases} --tols {args.tols} --tols-3d {args.tols_3d} --pairs {args.pairs} --radius {args.radius:g}"
            + (f" --hand-h-near {args.hand_h_near}" if args.hand_h_near else "") + (" --peak-2d" if args.peak_2d else "") + (f" --hand-h-far {args.hand_h_far:g}" if args.hand_h_far else "") + (f" --hand-bars {args.hand_bars}" if args.hand_bars else "") + f"`. The cylinder starts "
            "from a uniform h = 0.1, the sphere from 0.2. Errors: the largest pressure (the nodal maximum in 2D, the recovered peak "
            "pressure_peak in 3D) and the size (2D half-width, 3D quarter area) against "
            "the closed form at the run's force, the force against the finest run's; in brackets the run's bar (relative); make hertz's "
            f"moments' a and fitted p0. Times: {timing_text(args.pairs)}.", "",
            "| case | TOL | cycles | unknowns | reached | force | largest pressure | size | a, p0 (make hertz) | covered | time (s) | "
            "fewest hand-graded within TOL (h_near: unknowns) | its time (s) | adaptive / hand-graded |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"] + md
    write_text(os.path.join(args.outdir, "accuracy_remesh.md"), "\n".join(text) + "\n")
    print("\n".join(text))


if __name__ == "__main__":
    main()
