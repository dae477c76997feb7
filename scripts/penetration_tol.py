#!/usr/bin/python3
"""-contact_penetration_tol d on a ladder of tolerances (issue 33), by its two ways: eps continuation (-contact_method
penalty, the Gauss rule and the nodal one) and the augmented Lagrangian (-contact_method al, nodal), on the default
square at 512 x 512 with GAMG and the 3D sphere indenter of make hertz (h_near 0.01, its default solver), d = 1e-2 h_c,
1e-4 h_c, 1e-6 h_c with h_c the cell size at the contact (the square's h; the sphere's smallest contact cell, from the
plain run's smallest local eps). Each row: whether it converged, the penetration it ended with (at the nodes and the
rule's points), the smallest local eps, the solves, Newton steps, linear iterations and the whole-process time against
the plain run's (eps = h, the Gauss rule).

Usage: penetration_tol.py [--outdir DIR] [--cases square512,sphere] [--methods continuation,continuation_nodal,al] [--small]
Writes DIR/penetration_tol.{md,csv} (default output/penetration_tol)."""
import argparse
import csv
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from signorini import hertz  # noqa: E402
from signorini.mpirun import run_mpi  # noqa: E402
from signorini.paths import BIN, ROOT  # noqa: E402
from signorini.runs import read_run  # noqa: E402

COLUMNS = ["case", "method", "d_over_h", "d", "converged", "penetration", "eps", "solves", "newton", "krylov", "time", "time_plain"]


METHODS = {"continuation": [], "continuation_nodal": ["-penalty_quadrature", "nodal"], "al": ["-contact_method", "al", "-penalty_quadrature", "nodal"]}


def cases(outdir, small):
    n = 64 if small else 512
    h_near = 0.02 if small else 0.01
    mesh = os.path.join(outdir, hertz.mesh_name("sphere-indenter", h_near))
    if not os.path.isfile(mesh):
        hertz.write_mesh("sphere-indenter", h_near, mesh)
    return {"square512": ["-options_file", "options/square.yaml", "-options_file", "options/solvers/gamg.yaml", "-dm_plex_box_faces", f"{n},{n}"],
            "sphere": hertz.command("sphere-indenter", mesh, "eps=h", "unused.h5")[4:-2]}


def solve(args, out):
    res = run_mpi([BIN] + args + ["-output", out], log=out[:-3] + ".log")
    attrs = read_run(out) if os.path.isfile(out) else {}
    return res, attrs


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--outdir", default=os.path.join(ROOT, "output", "penetration_tol"))
    ap.add_argument("--cases", default="square512,sphere")
    ap.add_argument("--methods", default=",".join(METHODS))
    ap.add_argument("--small", action="store_true", help="small meshes (a test of the script)")
    args = ap.parse_args()
    os.makedirs(args.outdir, exist_ok=True)
    rows = []
    for name in args.cases.split(","):
        base = cases(args.outdir, args.small)[name]
        plain_res, plain = solve(base, os.path.join(args.outdir, f"{name}_plain.h5"))
        h_c = float(plain["eps_min"]) * float(plain["young_modulus"]) if "young_modulus" in plain else float(plain["eps_min"])
        for method, k in [(m, k) for k in (2, 4, 6) for m in args.methods.split(",")]:
            d = 10.0 ** -k * h_c
            out = os.path.join(args.outdir, f"{name}_{method}_d{k}.h5")
            res, a = solve(base + ["-contact_penetration_tol", repr(d)] + METHODS[method], out)
            row = {"case": name, "method": method, "d_over_h": f"1e-{k}", "d": d, "converged": int(a.get("converged", 0)),
                   "penetration": a.get("penetration_tol_measured", ""), "eps": a.get("eps_min", ""), "solves": a.get("penetration_tol_solves", ""),
                   "newton": a.get("newton_its_total", ""), "krylov": a.get("ksp_its_total", ""), "time": res.wall, "time_plain": plain_res.wall}
            print(row, flush=True)
            rows.append(row)
    with open(os.path.join(args.outdir, "penetration_tol.csv"), "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=COLUMNS)
        w.writeheader()
        w.writerows(rows)
    lines = ["| case | method | d / h_c | converged | penetration / d | smallest eps / h_c | solves | Newton | Krylov | time (s) | over eps = h |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        pen = f"{float(r['penetration']) / r['d']:.2f}" if r["penetration"] != "" else "-"
        eps = f"{float(r['eps']) / (r['d'] / float(r['d_over_h'])):.2e}" if r["eps"] != "" else "-"
        lines.append(f"| {r['case']} | {r['method']} | {r['d_over_h']} | {r['converged']} | {pen} | {eps} | {r['solves']} | {r['newton']} | {r['krylov']} | "
                     f"{r['time']:.2f} | {r['time'] / r['time_plain']:.2f} |")
    with open(os.path.join(args.outdir, "penetration_tol.md"), "w") as fh:
        fh.write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
