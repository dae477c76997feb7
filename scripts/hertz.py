#!/usr/bin/python3
"""Hertz contact against the closed form: every case of scripts/signorini/hertz.py on its sequence of graded Gmsh meshes,
with the penalty method at eps = h, h/10, h/100 (eps0 = 1, 0.1, 0.01; eps from the local mesh size) and with SNESVI
(the exact constraint; on the indenters' curved obstacles in its rotated frames, src/contact/vi_frames.c).

Usage: hertz.py [--outdir DIR] [--cases C,...] [--methods M,...] [--levels N] [--np N] [--check TOL]

DIR (default output/hertz) receives the meshes, the runs (.h5, .xdmf, .log), and
  hertz.csv   one row per run: case, h_near, method, n_dofs, load, a, a_h, a_error, p0, p0_h, p0_error, balance,
              contact_nodes, eps_min, converged, time_total, wall_time
  hertz.md    the table, and the finest mesh's errors of every method
  hertz_<case>.png   the nodal pressure of the finest mesh against the closed form, and |error| of a and p0 against h_near
--check TOL: exit 1 unless, on the finest mesh of every case, a and p0 are within TOL (relative) of the closed form for
SNESVI and for the penalty method at eps = h/100, every run converged, and the contact force balances
the supports' reactions to 1e-8.
"""
import argparse
import csv
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from signorini import hertz  # noqa: E402
from signorini.figures import plt, save_png  # noqa: E402
from signorini.mpirun import error_line, run_mpi  # noqa: E402
from signorini.paths import ROOT, display_path  # noqa: E402

COLUMNS = ["case", "h_near", "method", "n_dofs", "load", "a", "a_h", "a_error", "a_fit", "p0", "p0_h", "p0_error", "p0_max",
           "p0_max_error", "balance", "contact_nodes",
           "eps_min", "converged", "time_total", "wall_time"]
CHECKED_METHODS = ("vi", "eps=h/100")


def run_all(args, outdir):
    rows = []
    for case in args.cases:
        spec = hertz.CASES[case]
        for h_near in spec["h_near"][: args.levels]:
            mesh = os.path.join(outdir, hertz.mesh_name(case, h_near))
            if not os.path.isfile(mesh):
                hertz.write_mesh(case, h_near, mesh)
            for method in args.methods:
                out = os.path.join(outdir, hertz.output_name(case, h_near, method))
                cmd = hertz.command(case, display_path(mesh), method, display_path(out), ranks=args.np)
                res = run_mpi(cmd, log=out[:-3] + ".log", timeout=args.timeout, header=" ".join(cmd) + "\n")
                row = {"case": case, "h_near": h_near, "method": method, "wall_time": res.wall}
                if res.returncode != 0 or not os.path.isfile(out):
                    print(f"{case} h_near={h_near:g} {method}: FAILED ({error_line(res.output)})", file=sys.stderr)
                    row["converged"] = 0
                else:
                    row.update(hertz.measure(case, out))
                    print(f"{case} h_near={h_near:g} {method}: a {row['a_error']:+.2%}, p0 {row['p0_error']:+.2%}, "
                          f"balance {row['balance']:.1e}, {row['time_total']:.1f} s")
                rows.append(row)
    return rows


def write_csv(rows, path):
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=COLUMNS, extrasaction="ignore")
        w.writeheader()
        for row in rows:
            w.writerow({k: row.get(k, "") for k in COLUMNS})


def pct(v):
    return "" if v is None or v == "" else f"{100 * v:+.2f}%"


def write_md(rows, path):
    lines = ["# Hertz contact against the closed form", "",
             "Produced by `scripts/hertz.py` (`make hertz`); how a and p0 are measured: `scripts/signorini/hertz.py`.", ""]
    for case, spec in hertz.CASES.items():
        case_rows = [r for r in rows if r["case"] == case]
        if not case_rows:
            continue
        lines += [f"## {case}: {spec['what']}", "",
                  "| h_near | method | dofs | load | a (moments) | p0 (fit) | p0 (largest node) | balance | time (s) |",
                  "|---|---|---|---|---|---|---|---|---|"]
        for r in case_rows:
            if "a_error" not in r:
                lines.append(f"| {r['h_near']:g} | {r['method']} | | | failed | | | | |")
                continue
            lines.append(f"| {r['h_near']:g} | {r['method']} | {r['n_dofs']} | {r['load']:.4g} | {pct(r['a_error'])} | "
                         f"{pct(r['p0_error'])} | {pct(r['p0_max_error'])} | {r['balance']:.1e} | {r['time_total']:.2f} |")
        lines.append("")
    lines += ["Errors relative to the closed form at the measured load; balance: |obstacle force + supports' reactions| / "
              "obstacle force along the pressing axis.", ""]
    with open(path, "w") as fh:
        fh.write("\n".join(lines) + "\n")


def plot(rows, case, path):
    case_rows = [r for r in rows if r["case"] == case and "a_error" in r]
    if not case_rows:
        return
    dim = hertz.CASES[case]["dim"]
    finest = min(r["h_near"] for r in case_rows)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    for r in case_rows:
        if r["h_near"] != finest:
            continue
        rad = r["radius_sq"] ** 0.5
        order = rad.argsort()
        ax1.plot(rad[order] / r["a"], r["pressure"][order] / r["p0"], ".", label=r["method"])
    s = [i / 200 for i in range(201)]
    ax1.plot(s, hertz.pressure_profile(s, 1.0, 1.0), "k-", label="Hertz")
    ax1.set_xlim(0, 1.5)
    ax1.set_xlabel("r / a (closed form at the measured load)")
    ax1.set_ylabel("p / p0")
    ax1.set_title(f"{case} ({dim}D), h_near = {finest:g}")
    ax1.legend()
    for method in sorted({r["method"] for r in case_rows}):
        mr = sorted((r for r in case_rows if r["method"] == method), key=lambda r: r["h_near"])
        h = [r["h_near"] for r in mr]
        ax2.loglog(h, [abs(r["a_error"]) + 1e-16 for r in mr], "o-", label=f"a, {method}")
        ax2.loglog(h, [abs(r["p0_error"]) + 1e-16 for r in mr], "s--", label=f"p0, {method}")
    ax2.axhline(0.01, color="grey", lw=0.8)
    ax2.set_xlabel("h_near (mesh size at the contact)")
    ax2.set_ylabel("relative error")
    ax2.legend(fontsize=7)
    save_png(fig, path, 110)


def check(rows, tol):
    problems = []
    for case in {r["case"] for r in rows}:
        case_rows = [r for r in rows if r["case"] == case]
        finest = min(r["h_near"] for r in case_rows)
        for r in case_rows:
            where = f"{case} h_near={r['h_near']:g} {r['method']}"
            if not r.get("converged"):
                problems.append(f"{where}: did not converge")
                continue
            if r["balance"] > 1e-8:
                problems.append(f"{where}: the contact force does not balance the reactions ({r['balance']:.1e})")
            if r["h_near"] == finest and r["method"] in CHECKED_METHODS:
                for key in ("a_error", "p0_error"):
                    if abs(r[key]) > tol:
                        problems.append(f"{where}: {key[:-6]} off the closed form by {r[key]:+.2%} (> {tol:.0%})")
    return problems


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--outdir", default=os.path.join(ROOT, "output", "hertz"))
    parser.add_argument("--cases", default=",".join(hertz.CASES))
    parser.add_argument("--methods", default=",".join(hertz.METHODS))
    parser.add_argument("--levels", type=int, default=3, help="meshes of each case's sequence to run (coarsest first)")
    parser.add_argument("--np", type=int, default=2)
    parser.add_argument("--timeout", type=float, default=600)
    parser.add_argument("--check", type=float, metavar="TOL")
    args = parser.parse_args(argv)
    args.cases = [c for c in args.cases.split(",") if c]
    args.methods = [m for m in args.methods.split(",") if m]
    for c in args.cases:
        if c not in hertz.CASES:
            parser.error(f"unknown case {c} (known: {', '.join(hertz.CASES)})")
    for m in args.methods:
        if m not in hertz.METHODS:
            parser.error(f"unknown method {m} (known: {', '.join(hertz.METHODS)})")
    os.makedirs(args.outdir, exist_ok=True)
    rows = run_all(args, args.outdir)
    write_csv(rows, os.path.join(args.outdir, "hertz.csv"))
    write_md(rows, os.path.join(args.outdir, "hertz.md"))
    for case in args.cases:
        plot(rows, case, os.path.join(args.outdir, f"hertz_{case}.png"))
    print(f"written {display_path(os.path.join(args.outdir, 'hertz.md'))}")
    if args.check is not None:
        problems = check(rows, args.check)
        for p in problems:
            print("CHECK FAILED:", p, file=sys.stderr)
        return 1 if problems else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
