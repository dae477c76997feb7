#!/usr/bin/python3
"""Hertz along a load path against the closed form: the cylinder and sphere indenters of scripts/signorini/hertz.py
(on its PATH_MESHES: make hertz's finest for the cylinder, a graded mesh for the sphere) driven by the obstacle's
translation in 10 equal steps (-load_steps 10, eps = h/100), each step's contact half-width a and peak pressure p0
measured as make hertz measures a run (from the step's nodal reactions) and compared with the closed form at the
step's force, and the 3D force-depth curve's exponent.

Usage: hertz_path.py [--outdir DIR] [--cases C,...] [--check TOL] [--no-force]

DIR (default output/hertz_path) receives the meshes, the runs, and
  hertz_path.csv   one row per step: case, step, factor, depth, load, a, a_h, a_error, p0, p0_h, p0_error, newton_its, converged
  hertz_path.md    the table, the largest errors of each case and the sphere's force-depth exponent
  hertz_path.png   a and p0 against the load, with the closed form, and the sphere's force against the depth
--check TOL: exit 1 unless every step converged with a and p0 within TOL (relative) of the closed form, and the sphere's
force-depth exponent, over the steps with a <= SMALL_CONTACT, is within 0.03 of 3/2; and, driven by force
(-obstacle_force, unless --no-force), every step reaches its force to 1e-8 and its depth is the displacement-driven
run's at that force to 1e-6.
"""
import argparse
import csv
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from signorini import hertz  # noqa: E402
from signorini.figures import plt, save_png  # noqa: E402
from signorini.mpirun import error_line, run_mpi  # noqa: E402
from signorini.paths import ROOT, display_path  # noqa: E402


def run_case(case, outdir):
    mesh = os.path.join(outdir, hertz.path_mesh_name(case))
    if not os.path.isfile(mesh):
        hertz.write_path_mesh(case, mesh)
    out = mesh[:-4] + "_path.h5"
    cmd = (hertz.command(case, display_path(mesh), hertz.PATH_METHOD, display_path(out)) + ["-load_steps", str(hertz.PATH_STEPS)]
           + hertz.PATH_MESHES[case].get("solver", []))
    res = run_mpi(cmd, log=out[:-3] + ".log", timeout=3600, header=" ".join(cmd) + "\n")
    if res.returncode != 0 or not os.path.isfile(out):
        sys.exit(f"failed: {' '.join(cmd)}: {error_line(res.output)}")
    return hertz.path_rows(case, out)


def force_control(case, outdir, rows):
    """The indenter driven by force (-obstacle_force) in the path's steps to the displacement-driven path's last force,
    then driven by displacement to the positions force control found: each step's force against its target (1e-8
    relative is what force control promises) and the displacement-driven force at the found depth against the target,
    with the depth difference it means (the force's relative difference over the local force-depth exponent). Returns
    one row per step."""
    from signorini.history import history
    mesh = os.path.join(outdir, hertz.path_mesh_name(case))
    solver = hertz.PATH_MESHES[case].get("solver", [])
    target = rows[-1]["load"] / hertz.CASES[case]["parts"]  # the modelled part's force at the last step
    out = mesh[:-4] + "_force.h5"
    cmd = (hertz.command(case, display_path(mesh), hertz.PATH_METHOD, display_path(out)) + ["-load_steps", str(hertz.PATH_STEPS), "-obstacle_force",
           repr(target)] + solver)
    res = run_mpi(cmd, log=out[:-3] + ".log", timeout=3600, header=" ".join(cmd) + "\n")
    if res.returncode != 0 or not os.path.isfile(out):
        sys.exit(f"failed: {' '.join(cmd)}: {error_line(res.output)}")
    fc = history(out)
    args = hertz.CASES[case]["args"]
    full = float(np.linalg.norm([float(x) for x in args[args.index("-obstacle_translate") + 1].split(",")]))  # the travel at factor 1
    out_d = mesh[:-4] + "_at_force_positions.h5"
    cmd = (hertz.command(case, display_path(mesh), hertz.PATH_METHOD, display_path(out_d)) + ["-load_path", ",".join(repr(float(d) / full) for d in fc["depth"])]
           + solver)
    res = run_mpi(cmd, log=out_d[:-3] + ".log", timeout=3600, header=" ".join(cmd) + "\n")
    if res.returncode != 0 or not os.path.isfile(out_d):
        sys.exit(f"failed: {' '.join(cmd)}: {error_line(res.output)}")
    disp = history(out_d)
    d = np.asarray(fc["depth"], dtype=float)
    F = np.asarray(disp["force_along"], dtype=float)
    exponent = np.gradient(np.log(F), np.log(d))  # the local force-depth exponent along the path
    out_rows = []
    for k in range(len(d)):
        goal = float(fc["factor"][k]) * target
        force_error = abs(float(fc["force_along"][k]) - goal) / goal
        disp_error = abs(F[k] - goal) / goal
        out_rows.append({"case": case, "step": k + 1, "target": goal, "depth": float(d[k]), "force_error": force_error,
                         "displacement_force_error": disp_error, "depth_error": disp_error / exponent[k],
                         "newton_its": int(fc["newton_its"][k]), "converged": int(fc["converged"][k]) * int(disp["converged"][k])})
    return out_rows


def figure(rows, path):
    cases = sorted({r["case"] for r in rows})
    fig, axes = plt.subplots(1, 3, figsize=(14, 4))
    for case in cases:
        sel = [r for r in rows if r["case"] == case]
        load = np.array([r["load"] for r in sel])
        for ax, key, label in ((axes[0], "a", "contact half-width a"), (axes[1], "p0", "peak pressure p0")):
            ax.loglog(load, [r[key + "_h"] for r in sel], "o", label=f"{case} (run)")
            ax.loglog(load, [r[key] for r in sel], "-", label=f"{case} (closed form)")
            ax.set_xlabel("load (force of the whole body)")
            ax.set_ylabel(label)
    for ax in axes[:2]:
        ax.legend(fontsize=7)
        ax.grid(True, which="both", alpha=0.3)
    sphere = [r for r in rows if hertz.CASES[r["case"]]["dim"] == 3]
    if sphere:
        d = np.array([r["depth"] for r in sphere])
        F = np.array([r["load"] for r in sphere])
        es = hertz.e_star()
        axes[2].loglog(d, F, "o", label="run")
        axes[2].loglog(d, 4.0 / 3.0 * es * np.sqrt(hertz.RADIUS) * d**1.5, "-", label="half-space: (4/3) E* R^1/2 d^3/2")
        axes[2].set_xlabel("indentation depth (the sphere's translation)")
        axes[2].set_ylabel("force")
        axes[2].set_title(f"fitted exponent {hertz.force_depth_exponent(sphere, hertz.SMALL_CONTACT):.3f} (a <= {hertz.SMALL_CONTACT:g}), "
                          f"{hertz.force_depth_exponent(sphere):.3f} (all steps)", fontsize=9)
        axes[2].legend(fontsize=7)
        axes[2].grid(True, which="both", alpha=0.3)
    save_png(fig, path, 120)


def report(rows, outdir, forced=()):
    lines = ["# Hertz along a load path", "", f"Made by `scripts/hertz_path.py` (make hertz-path): {hertz.PATH_STEPS} equal steps of the "
             f"obstacle's translation, {hertz.PATH_METHOD}, the meshes of `signorini.hertz.PATH_MESHES`.", "",
             "| case | step | factor | depth | load | a error | p0 error | Newton |", "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['case']} | {r['step']} | {r['factor']:.2f} | {r['depth']:.3g} | {r['load']:.4g} | {r['a_error']:+.4f} | "
                     f"{r['p0_error']:+.4f} | {r['newton_its']} |")
    lines.append("")
    for case in sorted({r["case"] for r in rows}):
        sel = [r for r in rows if r["case"] == case]
        lines.append(f"- {case}: largest |a error| {max(abs(r['a_error']) for r in sel):.4f}, largest |p0 error| "
                     f"{max(abs(r['p0_error']) for r in sel):.4f}")
        if hertz.CASES[case]["dim"] == 3:
            ratio, intercept, slope = hertz.half_space_ratio(sel)
            lines.append(f"- {case}: force-depth exponent {hertz.force_depth_exponent(sel, hertz.SMALL_CONTACT):.4f} over the steps with "
                         f"a <= {hertz.SMALL_CONTACT:g} (half-space: 1.5), {hertz.force_depth_exponent(sel):.4f} over all steps")
            lines.append(f"- {case}: load over the half-space's at the same depth from {ratio[0]:.4f} to {ratio[-1]:.4f}; the line through "
                         f"them against a: {intercept:.4f} + {slope:.3f} a (the block, of depth 1, stiffer as a grows; a half-space at a -> 0)")
    if forced:
        lines += ["", "## Force control", "", f"The sphere indenter driven by `-obstacle_force` ({hertz.PATH_STEPS} steps to the displacement-driven "
                  "path's last force), then driven by displacement to the positions it found.", "",
                  "| step | target force | depth found | force error | displacement-driven force error | depth error | Newton |",
                  "|---|---|---|---|---|---|---|"]
        for r in forced:
            lines.append(f"| {r['step']} | {r['target']:.6g} | {r['depth']:.6g} | {r['force_error']:.2e} | {r['displacement_force_error']:.2e} | "
                         f"{r['depth_error']:.2e} | {r['newton_its']} |")
        lines += ["", f"- largest force error {max(r['force_error'] for r in forced):.2e} (force control stops at 1e-8); largest depth error "
                  f"against the displacement-driven run {max(r['depth_error'] for r in forced):.2e}; "
                  f"{sum(r['newton_its'] for r in forced)} Newton steps in all"]
    with open(os.path.join(outdir, "hertz_path.md"), "w") as fh:
        fh.write("\n".join(lines) + "\n")


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--outdir", default=os.path.join(ROOT, "output", "hertz_path"))
    p.add_argument("--cases", default=",".join(hertz.PATH_CASES))
    p.add_argument("--check", type=float, default=None)
    p.add_argument("--no-force", action="store_true", help="without the sphere driven by force")
    args = p.parse_args()
    os.makedirs(args.outdir, exist_ok=True)
    rows = []
    for case in args.cases.split(","):
        rows += run_case(case, args.outdir)
        for r in rows[-hertz.PATH_STEPS:]:
            print(f"{case} step {r['step']}: load {r['load']:.4g}, a {r['a_error']:+.4f}, p0 {r['p0_error']:+.4f}")
    with open(os.path.join(args.outdir, "hertz_path.csv"), "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    forced = []
    for case in args.cases.split(","):
        if hertz.CASES[case]["dim"] == 3 and not args.no_force:
            new = force_control(case, args.outdir, [r for r in rows if r["case"] == case])
            forced += new
            for r in new:
                print(f"{case} force control step {r['step']}: force {r['force_error']:.1e}, depth against displacement {r['depth_error']:.1e}")
    report(rows, args.outdir, forced)
    figure(rows, os.path.join(args.outdir, "hertz_path.png"))
    print(f"wrote {display_path(os.path.join(args.outdir, 'hertz_path.md'))}")
    if args.check is None:
        return 0
    bad = [f"{r['case']} step {r['step']}: not converged" for r in rows if not r["converged"]]
    bad += [f"{r['case']} step {r['step']}: a {r['a_error']:+.4f}, p0 {r['p0_error']:+.4f}" for r in rows
            if max(abs(r["a_error"]), abs(r["p0_error"])) > args.check]
    sphere = [r for r in rows if hertz.CASES[r["case"]]["dim"] == 3]
    exponent = hertz.force_depth_exponent(sphere, hertz.SMALL_CONTACT) if sphere else 1.5
    if not abs(exponent - 1.5) <= 0.03:
        bad.append(f"force-depth exponent {exponent:.4f} over the steps with a <= {hertz.SMALL_CONTACT:g}")
    bad += [f"force control step {r['step']}: not converged" for r in forced if not r["converged"]]
    bad += [f"force control step {r['step']}: force {r['force_error']:.2e} from its target" for r in forced if not r["force_error"] <= 1e-8]
    bad += [f"force control step {r['step']}: depth {r['depth_error']:.2e} from the displacement-driven run's" for r in forced
            if not r["depth_error"] <= 1e-6]
    for b in bad:
        print("CHECK FAILED:", b, file=sys.stderr)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
