#!/usr/bin/python3
"""The measurement behind the contact-zone resolution warning (CONTACT_CHECK_ZONE_CELLS_2D and _3D, src/physics/contact_checks.c):
a unit square pressed by its top (-bc_clamp 3 translated by -delta) onto a rigid cylinder of radius R under its bottom,
solved on N x N simplex boxes, both penalty rules at eps = eps0 h / E; the contact force of each run against the same
rule's on the finest box, with the cells the solver counts across the contact zone (/run contact_zone_cells).

  zone_resolution.py [--out bench/zone_resolution.md] [--sizes 8,12,16,24,32,48,64,256] [--radius 1] [--delta 0.004]
                     [--dim 3 --np 2]   (3D: a unit cube pressed onto a rigid sphere)
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from signorini.mpirun import run_mpi  # noqa: E402
from signorini.paths import BIN, ROOT  # noqa: E402
from signorini.runs import read_run  # noqa: E402


def solve(n, rule, eps0, radius, delta, outdir, dim=2, ranks=1):
    out = os.path.join(outdir, f"zone{dim}d_{rule}_{n}.h5")
    if dim == 2:  # the square's top is face set 3; a cylinder (a disk) under its bottom
        geometry = ["-dm_plex_box_faces", f"{n},{n}", "-bc_clamp", "3", "-bc_clamp_3_translate", f"0,{-delta}", "-obstacle", "cylinder",
                    "-obstacle_center", f"0.5,{-radius}"]
    else:  # the cube's top is face set 2; a sphere under its bottom
        geometry = ["-dm_plex_dim", "3", "-dm_plex_box_faces", f"{n},{n},{n}", "-bc_clamp", "2", "-bc_clamp_2_translate", f"0,0,{-delta}",
                    "-obstacle", "sphere", "-obstacle_center", f"0.5,0.5,{-radius}"]
    cmd = ["mpiexec", "-n", str(ranks), BIN, "-scene", "general", "-contact_faces", "1"] + geometry + [
           "-obstacle_radius", str(radius), "-penalty_quadrature", rule, "-penalty_eps0", str(eps0), "-output", out]
    r = run_mpi(cmd, timeout=600)
    if r.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed ({r.returncode}):\n{r.text[-2000:]}")
    return read_run(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default=os.path.join(ROOT, "bench", "zone_resolution.md"))
    ap.add_argument("--sizes", default="8,12,16,24,32,48,64,96,256")
    ap.add_argument("--radius", type=float, default=1.0)
    ap.add_argument("--delta", type=float, default=0.004)
    ap.add_argument("--eps0", type=float, default=0.01)
    ap.add_argument("--dim", type=int, default=2, choices=(2, 3), help="3: a unit cube pressed onto a rigid sphere")
    ap.add_argument("--np", type=int, default=1, help="ranks of each run")
    args = ap.parse_args()
    sizes = [int(s) for s in args.sizes.split(",")]
    outdir = os.path.join(ROOT, "output", "zone_resolution")
    os.makedirs(outdir, exist_ok=True)
    lines = [f"# Force error against the cells across the contact zone\n",
             f"`{' '.join(['scripts/zone_resolution.py'] + sys.argv[1:])}`: unit {'square on a rigid cylinder' if args.dim == 2 else 'cube on a rigid sphere'} "
             f"(R = {args.radius:g}), top pushed by {args.delta:g}, eps = {args.eps0:g} h/E; the error is the contact force against the same rule's "
             f"on {sizes[-1]}^{args.dim} (cells across the zone in 3D: the diameter of a round zone of its fully pressed faces, sqrt(2 n / pi)).\n",
             "| rule | N | cells across the zone | zone faces | contact force | error of the force |", "|---|---|---|---|---|---|"]
    for rule in ("gauss", "nodal"):
        runs = {n: solve(n, rule, args.eps0, args.radius, args.delta, outdir, args.dim, args.np) for n in sizes}
        ref = runs[sizes[-1]]["contact_force"]
        for n in sizes[:-1]:
            r = runs[n]
            err = abs(r["contact_force"] / ref - 1)
            lines.append(f"| {rule} | {n} | {r['contact_zone_cells']:.1f} | {r['contact_zone_faces']} | {r['contact_force']:.6g} | {100 * err:.2f}% |")
            print(lines[-1], flush=True)
    with open(args.out, "w") as fh:
        fh.write("\n".join(lines) + "\n")
    print(f"written {args.out}")


if __name__ == "__main__":
    main()
