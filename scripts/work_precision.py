#!/usr/bin/env python3
"""Error against unknowns and against time (issue 34's study and figure): adaptive refinement, uniform meshes and
hand-graded meshes on the 2D Hertz cylinder indenter (make accuracy-ladder's block, 10 times make hertz's), make
hertz's elastic cylinder (remeshed from its Gmsh model), the 2D manufactured solution and make hertz's elastic sphere
(3D, remeshed from its Gmsh model, GAMG as make accuracy-remesh gives it), eps = h/10 throughout.

The error of a run is the largest relative error of the three contact quantities -accuracy targets: the force, the
largest pressure and the contact zone's size. Hertz: the largest pressure and the size against the closed form at the
run's own force, the force against the last adaptive cycle's; the manufactured solution: its closed form.
- adaptive: one run of -adapt_cycles N; each cycle is a point, its time the cycles' times up to it (/cycles time_cycle:
  every mesh, solve, estimate and marking before it; the process's start and the first mesh's reading are not in it);
- uniform: meshes of one size h (the block and the disk by Gmsh, the manufactured solution's box by PETSc);
- hand-graded: the size h_near + G r around the contact point (the indenter, as make accuracy-ladder grades it) or
  make hertz's grading (the cylinder); the time of a single run is its /run time_total.
For each error E (3%, 1%, 0.3%; in 3D 10% and 3%) the table gives each family's fewest unknowns, and their time, with an error at most E:
for the adaptive family the first cycle within E (what an oracle that knew the error would stop at; -accuracy's own stop,
whose bars are wider than the errors, is make accuracy-ladder's and make accuracy-remesh's); for the uniform family past
its finest mesh, the unknowns a power law through its last three points would need.
Writes output/work_precision/work_precision.{md,csv} and docs/accuracy_work_precision.png.

    /usr/bin/python3 scripts/work_precision.py [--cases cylinder-indenter,cylinder,mms,sphere] [--outdir DIR] [--figure PATH]
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from signorini import estimates as st  # noqa: E402
from signorini import geometry, hertz  # noqa: E402
from signorini.figures import plt, save_png  # noqa: E402
from signorini.mpirun import timed_or_exit as solve  # noqa: E402
from signorini.paths import ROOT  # noqa: E402
from signorini.report import csv_text, write_text  # noqa: E402
from signorini.runs import read_cycles, read_run  # noqa: E402

QUANTITIES = ("contact_force", "pressure_max", "contact_size")
MMS_EXACT = {"contact_force": 0.0720182, "pressure_max": 0.402594, "contact_size": 0.447214}  # docs/estimate.md
ERRORS = {2: (0.03, 0.01, 0.003), 3: (0.1, 0.03)}  # 3D: 1% would reach the last cycle, the force's reference
BIN = os.path.join(ROOT, "bin", "signorini")
CYLINDER_HAND = [0.004, 0.002, 0.001, 0.0005]


def dim_of(case):
    return 2 if case == "mms" else hertz.CASES[case]["dim"]


def errors(case, force, pressure_max, size, force_ref):
    """The largest relative error of the three quantities (arrays of runs or cycles)."""
    force = np.abs(np.asarray(force, dtype=float))
    if case == "mms":
        exact = {q: np.full(force.shape, v) for q, v in MMS_EXACT.items()}
    else:
        closed = [hertz.quantity_exact(case, f) for f in force]
        exact = {"contact_force": np.full(force.shape, force_ref), "pressure_max": np.array([c["pressure_max"] for c in closed]),
                 "contact_size": np.array([c["contact_size"] for c in closed])}
    values = {"contact_force": force, "pressure_max": np.asarray(pressure_max, dtype=float), "contact_size": np.asarray(size, dtype=float)}
    with np.errstate(divide="ignore", invalid="ignore"):  # a first mesh that misses the contact: no force, error 100% or NaN
        return np.max([np.abs(values[q] / exact[q] - 1) for q in QUANTITIES], axis=0)


def single(cmd, out, dim=2):
    """Solve once; (unknowns, time, force, largest pressure, size)."""
    solve(cmd + ["-output", out])
    a = read_run(out)
    force = abs(float(a[f"contact_force_{'xyz'[dim - 1]}"]))
    return int(a["n_dofs"]), float(a["time_total"]), force, float(a["pressure_max"]), float(a["contact_size"])


def hertz_cmd(case, mesh):
    return hertz.command(case, mesh, "eps=h/10", "unused")[3:-2]


def runs_of(case, outdir, cycles):
    """The three families of one case: {family: (unknowns, time, force, pressure, size) arrays}, and the adaptive run's
    command."""
    fam = {"uniform": [], "hand-graded": []}
    if case == "mms":
        mms = [BIN, "-options_file", "options/mms.yaml", "-penalty_eps0", "0.1"]
        adaptive = mms + ["-dm_plex_box_faces", "8,8", "-adapt_cycles", str(cycles)]
        for n in (8, 16, 32, 64, 128, 256):
            fam["uniform"].append(single(mms + ["-dm_plex_box_faces", f"{n},{n}"], os.path.join(outdir, f"mms_uniform_{n}.h5")))
    elif case == "cylinder-indenter":
        coarse = os.path.join(outdir, "block10_h0.5.msh")
        for h in (0.5, 0.25, 0.125, 0.0625, 0.03125):
            mesh = os.path.join(outdir, f"block10_h{h:g}.msh")
            geometry.block(mesh, radius=st.BLOCK, h_far=h, h_near=h, width=3.0, near=0.6)
            fam["uniform"].append(single(hertz_cmd(case, mesh), os.path.join(outdir, f"indenter_uniform_{h:g}.h5")))
        for h_near, grade in st.INDENTER_GRADES:
            mesh = os.path.join(outdir, f"block10_h{h_near:g}_grade{grade:g}.msh")
            st.write_graded_block(mesh, h_near, grade)
            fam["hand-graded"].append(single(hertz_cmd(case, mesh), os.path.join(outdir, f"indenter_graded_{h_near:g}_{grade:g}.h5")))
        adaptive = hertz_cmd(case, coarse) + ["-adapt_cycles", str(cycles), "-options_file", "options/solvers/gamg.yaml"]
    elif case == "sphere":  # uniform meshes of the quarter sphere, make hertz's grading, the model remeshed
        model = os.path.join(outdir, "sphere.geo")
        for h in (0.2, 0.1, 0.05, 0.035):
            mesh = os.path.join(outdir, f"sphere_h{h:g}.msh")
            geometry.quarter_sphere(mesh, radius=hertz.RADIUS, h_far=h, h_near=h, width=0.5, model=model if h == 0.2 else None)
            fam["uniform"].append(single(hertz_cmd(case, mesh) + hertz.GAMG_3D, os.path.join(outdir, f"sphere_uniform_{h:g}.h5"), 3))
        for h_near in hertz.CASES[case]["h_near"]:
            mesh = os.path.join(outdir, f"sphere_graded_{h_near:g}.msh")
            hertz.write_mesh(case, h_near, mesh)
            fam["hand-graded"].append(single(hertz_cmd(case, mesh) + hertz.GAMG_3D, os.path.join(outdir, f"sphere_graded_{h_near:g}.h5"), 3))
        adaptive = hertz_cmd(case, os.path.join(outdir, "sphere_h0.2.msh")) + hertz.GAMG_3D + ["-adapt_model", model, "-adapt_cycles", str(cycles)]
    else:  # the elastic cylinder: uniform meshes of the quarter disk, make hertz's grading, the model remeshed
        model = os.path.join(outdir, "disk.geo")
        for h in (0.1, 0.05, 0.025, 0.0125, 0.00625):
            mesh = os.path.join(outdir, f"disk_h{h:g}.msh")
            geometry.quarter_disk(mesh, radius=hertz.RADIUS, h_far=h, h_near=h, width=0.5, model=model if h == 0.1 else None)
            fam["uniform"].append(single(hertz_cmd(case, mesh), os.path.join(outdir, f"cylinder_uniform_{h:g}.h5")))
        for h_near in CYLINDER_HAND:
            mesh = os.path.join(outdir, f"cylinder_graded_{h_near:g}.msh")
            hertz.write_mesh(case, h_near, mesh)
            fam["hand-graded"].append(single(hertz_cmd(case, mesh), os.path.join(outdir, f"cylinder_graded_{h_near:g}.h5")))
        adaptive = hertz_cmd(case, os.path.join(outdir, "disk_h0.1.msh")) + ["-adapt_model", model, "-adapt_cycles", str(cycles)]
    out = os.path.join(outdir, f"{case}_adaptive.h5")
    solve(adaptive + ["-output", out])
    c = read_cycles(out)
    fam["adaptive"] = list(zip(c["n_dofs"].astype(int), np.cumsum(c["time_cycle"]), np.abs(c["contact_force_value"]), c["pressure_max_value"],
                               c["contact_size_value"]))
    return {k: np.array(v, dtype=float).reshape(-1, 5) for k, v in fam.items()}, " ".join(adaptive)


def fewest(rows, err, e):
    """The fewest unknowns, and their time, among rows with an error at most e; None if none."""
    ok = np.where(err <= e)[0]
    if not len(ok):
        return None
    i = ok[np.argmin(rows[ok, 0])]
    return int(rows[i, 0]), float(rows[i, 1])


def power_law_dofs(rows, err, e):
    """The unknowns a power law err = C N^(-s) through the family's last three points needs for e; NaN unless the three
    are below 30% (a mesh that barely sees the contact zone is not on the law) and the error falls through them."""
    if len(err) < 3 or not np.all(err[-3:] < 0.3):
        return float("nan")
    s, c = np.polyfit(np.log(rows[-3:, 0]), np.log(err[-3:]), 1)
    return float(np.exp((np.log(e) - c) / s)) if s < 0 else float("nan")


def cell(best):
    return f"{best[0]} ({best[1]:.2f} s)" if best else "none"


def none_up_to(rows, err):
    return f"none up to {int(rows[:, 0].max())} (least error {np.nanmin(err):.2%})" if len(rows) else ""


def table_row(case, e, fam, err):
    """The families' fewest unknowns within the error e: the csv row and the markdown line."""
    best = {k: fewest(fam[k], err[k], e) if len(fam[k]) else None for k in fam}
    ad, hd, un = best["adaptive"], best["hand-graded"], best["uniform"]
    un_dofs = un[0] if un else power_law_dofs(fam["uniform"], err["uniform"], e)
    row = [case, e, ad[0] if ad else 0, ad[1] if ad else float("nan"), hd[0] if hd else 0, hd[1] if hd else float("nan"), un_dofs,
           un[1] if un else float("nan")]
    un_cell = cell(un) if un else none_up_to(fam["uniform"], err["uniform"]) + (f"; a power law: about {un_dofs:.2g}" if np.isfinite(un_dofs) else "")
    ratio_u = "" if not ad else f"{un[0] / ad[0]:.2g}" if un else f"about {un_dofs / ad[0]:.2g}" if np.isfinite(un_dofs) else ""
    ratio_h = f"{hd[0] / ad[0]:.2f}, {ad[1] / hd[1]:.2f}" if ad and hd else ""
    hd_cell = cell(hd) if hd else none_up_to(fam["hand-graded"], err["hand-graded"])
    return row, f"| {case} | {e:.1%} | {cell(ad)} | {hd_cell} | {un_cell} | {ratio_u} | {ratio_h} |"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cases", default="cylinder-indenter,cylinder,mms,sphere")
    ap.add_argument("--cycles", default="cylinder-indenter:16,cylinder:15,mms:12,sphere:7", help="the adaptive runs' cycles, per case")
    ap.add_argument("--outdir", default=os.path.join(ROOT, "output", "work_precision"))
    ap.add_argument("--figure", default=os.path.join(ROOT, "docs", "accuracy_work_precision.png"))
    args = ap.parse_args()
    os.makedirs(args.outdir, exist_ok=True)
    ncycles = dict((k, int(v)) for k, v in (p.split(":") for p in args.cycles.split(",")))
    cases = args.cases.split(",")
    fig, axes = plt.subplots(len(cases), 2, figsize=(10, 3.6 * len(cases)), squeeze=False)
    rows, md = [], []
    for i, case in enumerate(cases):
        fam, adaptive_cmd = runs_of(case, args.outdir, ncycles[case])
        force_ref = fam["adaptive"][-1, 2]
        err = {k: errors(case, v[:, 2], v[:, 3], v[:, 4], force_ref) for k, v in fam.items()}
        for k, style, color in (("uniform", "s-", "C0"), ("hand-graded", "^-", "C1"), ("adaptive", "o-", "C2")):
            if not len(fam[k]):
                continue
            for ax, col in ((axes[i, 0], 0), (axes[i, 1], 1)):
                ax.loglog(fam[k][:, col], err[k], style, color=color, label=k)
        for ax, xlabel in ((axes[i, 0], "unknowns"), (axes[i, 1], "time (s)")):
            for e in ERRORS[dim_of(case)]:
                ax.axhline(e, color="0.8", lw=0.8, zorder=0)
            ax.set_xlabel(xlabel)
            ax.set_ylabel("largest relative error")
            ax.set_title(case)
            ax.legend(fontsize=8)
        for e in ERRORS[dim_of(case)]:
            row, line = table_row(case, e, fam, err)
            rows.append(row)
            md.append(line)
        write_text(os.path.join(args.outdir, f"{case}_families.csv"),
                   csv_text(["family", "n_dofs", "time", "force", "pressure_max", "contact_size", "largest_error"],
                            [[k, int(r[0])] + list(r[1:]) + [float(x)] for k in fam for r, x in zip(fam[k], err[k])]))
        print(f"{case}: adaptive {adaptive_cmd}", flush=True)
    save_png(fig, args.figure, 110)
    write_text(os.path.join(args.outdir, "work_precision.csv"),
               csv_text(["case", "error", "adaptive_n_dofs", "adaptive_time", "hand_n_dofs", "hand_time", "uniform_n_dofs", "uniform_time"], rows))
    text = ["# Error against unknowns and time: adaptive, uniform and hand-graded meshes (eps = h/10)", "",
            f"`/usr/bin/python3 scripts/work_precision.py --cases {args.cases} --cycles {args.cycles}`; each family's fewest unknowns "
            "(and its time, in the process) with the largest relative error of the force, the largest pressure and the size at most "
            "the error of the row; the adaptive family's time is its cycles' up to the one within the error.", "",
            "| case | error | adaptive | hand-graded | uniform | uniform / adaptive unknowns | hand-graded / adaptive unknowns, adaptive / hand-graded time |",
            "|---|---|---|---|---|---|---|"] + md
    write_text(os.path.join(args.outdir, "work_precision.md"), "\n".join(text) + "\n")
    print("\n".join(text))


if __name__ == "__main__":
    main()
