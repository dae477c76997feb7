#!/usr/bin/python3
"""P1 near incompressibility on make hertz's elastic cylinder: the contact half-width a and the peak pressure p0 of
each run against Hertz's closed form at the run's own force, for Poisson ratios up to 0.499, with SNESVI (the exact
constraint: the discretization's error alone) and the penalty method with eps from E and from lambda + 2 mu
(-penalty_eps_modulus). It measures from which nu P1's answer is off by more than 1%, the threshold of the solver's
warning (src/physics/contact_checks.c, ContactChecksMaterial()).

    /usr/bin/python3 scripts/incompressible.py [--h-near 0.004] [--out docs/incompressible.md]
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from signorini import hertz  # noqa: E402
from signorini.mpirun import run_mpi  # noqa: E402
from signorini.paths import ROOT  # noqa: E402

NUS = (0.3, 0.4, 0.45, 0.48, 0.49, 0.495, 0.499)
METHODS = {"vi": ["-contact_method", "vi"], "penalty, eps from E": ["-contact_method", "penalty", "-penalty_eps0", "0.1"],
           "penalty, eps from lambda + 2 mu": ["-contact_method", "penalty", "-penalty_eps0", "0.1", "-penalty_eps_modulus", "pwave"],
           "P2 penalty, eps from lambda + 2 mu": ["-contact_method", "penalty", "-penalty_eps0", "0.1", "-penalty_eps_modulus", "pwave",
                                                  "-displacement_petscspace_degree", "2"]}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--h-near", type=float, default=0.004, help="the cylinder's mesh size near the contact (make hertz's coarsest)")
    parser.add_argument("--nus", default=",".join(f"{nu:g}" for nu in NUS), help="the Poisson ratios")
    parser.add_argument("--methods", default=";".join(METHODS), help="';'-separated, of: " + "; ".join(METHODS))
    parser.add_argument("--outdir", default=os.path.join(ROOT, "output", "incompressible"))
    parser.add_argument("--out", default=None, help="the Markdown table (default OUTDIR/incompressible.md)")
    args = parser.parse_args(argv)
    os.makedirs(args.outdir, exist_ok=True)
    mesh = os.path.join(args.outdir, f"cylinder_{args.h_near:g}.msh")
    hertz.write_mesh("cylinder", args.h_near, mesh)
    rows = []
    for nu in [float(v) for v in args.nus.split(",")]:
        for label in [m.strip() for m in args.methods.split(";") if m.strip() in METHODS] or METHODS:
            opts = METHODS[label]
            out = os.path.join(args.outdir, f"nu{nu:g}_{label.split(',')[0]}_{len(rows)}.h5")
            cmd = hertz.command("cylinder", mesh, "vi", out, ranks=1, poisson=nu)
            i = cmd.index("-contact_method")
            cmd = cmd[:i] + cmd[i + 2:] + opts
            r = run_mpi(cmd, timeout=600)
            if r.returncode not in (0, 4):
                print(f"nu {nu}: {label}: exit {r.returncode}", file=sys.stderr)
                return 1
            m = hertz.measure("cylinder", out, poisson=nu)
            rows.append((nu, label, m["a_error"], m["p0_error"], m["p0_max_error"]))
            print(f"nu {nu:<6g} {label:<32s} a {100 * m['a_error']:+.2f}%  p0 {100 * m['p0_error']:+.2f}%  p_max {100 * m['p0_max_error']:+.2f}%",
                  flush=True)
    path = args.out or os.path.join(args.outdir, "incompressible.md")
    with open(path, "w") as fh:
        fh.write(f"| nu | method | a - a_Hertz | p0 - p0_Hertz | largest nodal pressure - p0_Hertz |\n|---|---|---|---|---|\n")
        for nu, label, ea, ep, em in rows:
            fh.write(f"| {nu:g} | {label} | {100 * ea:+.2f}% | {100 * ep:+.2f}% | {100 * em:+.2f}% |\n")
    print(f"written {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
