#!/usr/bin/python3
"""The study of the a posteriori error estimate (make estimates; docs/estimate.md).

Usage: estimates.py [--outdir DIR] [--parts estimate,bars] [--check]

1. Effectivity (estimate / exact energy-norm error) on the manufactured solution, 2D and 3D, Poisson ratio 0.3 and 0.49,
   eps = h and h/100, SNESVI, and the solution's regularities 0.3 and 1 (-mms_nu), each on a series of meshes
   (signorini.estimates.SERIES).
2. The penalty part of the estimate against the energy-norm distance of the penalty solution to SNESVI's on the same
   mesh, eps = h to h/1000, both rules, 2D and 3D.
3. Hertz: how far from the contact zone's edge the largest error densities lie (the four cases of make hertz, on their
   coarsest graded mesh, eps = h/10), and a figure of the 2D cylinder's error density.

4. The error bars (-bars) against the known values: the manufactured solution's force, largest pressure and contact size
   in 2D and 3D, and the Hertz indenters' contact size and peak pressure at the run's force, in a block 10 times make
   hertz's (the closed form is a half-space's), and make hertz's curved bodies with their Gmsh models (-adapt_model, the
   levels remeshed); the pressure's band against the manufactured solution's pressure at the nodes (--parts bars: this
   part alone, --parts estimate: the others).

DIR (default output/estimates) receives the runs, estimates.csv, penalty.csv, hertz.csv, bars.csv, estimates.md, bars.md,
effectivity.png, hertz_density.png and band.png. --check: exit 1 unless, in every series, the effectivity varies by at
most 1.5x over the four finest meshes and the estimate's rate is the error's within 0.1; the effectivity over all series varies by at most 3x;
every penalty ratio lies in [1/3, 3]; on every Hertz case the densest cell lies within 2 cell diameters of the zone's
edge; at least 9 in 10 error bars cover the true error, and none is over 10 times the larger of an error above its
reference's accuracy (1e-4 relative; Hertz's closed forms on make hertz's own bodies 0.25%) and the sum of its two
causes (where they cancel in the error), but the zone's size where its bar is the one-cell band along the edge (its
resolution); the
pressure's band covers at least 9 in 10 of the nodes where the pressure's error is above 1e-3 of its peak.
"""
import argparse
import csv
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from signorini import estimates as st  # noqa: E402
from signorini import hertz  # noqa: E402
from signorini.figures import plt, save_png  # noqa: E402
from signorini.mpirun import error_line, run_mpi  # noqa: E402
from signorini.paths import ROOT, display_path  # noqa: E402

HERTZ_METHOD = "eps=h/10"


def run(cmd, out):
    res = run_mpi(cmd, log=out[:-3] + ".log", timeout=1800, header=" ".join(cmd) + "\n")
    if res.returncode != 0 or not os.path.isfile(out):
        sys.exit(f"failed: {' '.join(cmd)}: {error_line(res.output)}")
    return st.read(out)


def effectivity_series(outdir):
    rows = []
    for label, dim, args, sizes in st.SERIES:
        for n in sizes:
            out = os.path.join(outdir, f"{label.replace(' ', '_').replace('=', '').replace('/', '_')}_{n}.h5")
            a = run(st.mms_command(dim, n, args, display_path(out)), out)
            rows.append({"series": label, "dim": dim, "n": n, "h": a["h"], "n_dofs": a["n_dofs"], "estimate_total": a["estimate_total"],
                         **{"estimate_" + p: a["estimate_" + p] for p in st.PARTS}, "error_energy": a["error_energy"],
                         "effectivity": a["estimate_total"] / a["error_energy"], "time_total": a["time_total"],
                         "time_estimate": a["time_estimate"]})
            print(f"{label} n={n}: effectivity {rows[-1]['effectivity']:.3f}")
    return rows


def penalty_ladder(outdir):
    rows = []
    for dim, n in st.PENALTY_MESHES.items():
        vi = os.path.join(outdir, f"penalty{dim}d_vi.h5")
        run(st.mms_command(dim, n, ["-contact_method", "vi"], display_path(vi)), vi)
        for rule in ("nodal", "gauss"):
            for eps0 in st.EPS0_LADDER:
                out = os.path.join(outdir, f"penalty{dim}d_{rule}_{eps0:g}.h5")
                a = run(st.mms_command(dim, n, ["-penalty_quadrature", rule, "-penalty_eps0", str(eps0)], display_path(out),
                                       reference=display_path(vi)), out)
                rows.append({"dim": dim, "n": n, "rule": rule, "eps0": eps0, "estimate_penalty": a["estimate_penalty"],
                             "distance_to_vi": a["reference_error_energy"], "ratio": a["estimate_penalty"] / a["reference_error_energy"]})
                print(f"penalty {dim}D {rule} eps=h*{eps0:g}: ratio {rows[-1]['ratio']:.3f}")
    return rows


def hertz_cases(outdir):
    rows, files = [], {}
    for case, spec in hertz.CASES.items():
        h_near = spec["h_near"][0]
        mesh = os.path.join(outdir, hertz.mesh_name(case, h_near))
        if not os.path.isfile(mesh):
            hertz.write_mesh(case, h_near, mesh)
        out = os.path.join(outdir, hertz.output_name(case, h_near, HERTZ_METHOD))
        run(hertz.command(case, display_path(mesh), HERTZ_METHOD, display_path(out)), out)
        m, dist = st.hertz_peak(case, out)
        files[case] = (out, m)
        rows.append({"case": case, "h_near": h_near, "a": m["a"], "a_h": m["a_h"], "densest_cells_from_edge": float(dist[0]),
                     "median_of_10_densest": float(np.median(dist))})
        print(f"hertz {case}: densest cell {dist[0]:.2f} cells from the zone's edge")
    return rows, files


def coverage(outdir):
    """The bars against the known values: one row per (run, quantity)."""
    from signorini.exact import mms_from_run, mms_quantities
    rows, bands = [], []
    for dim, n, extra in st.COVERAGE_MMS:
        out = os.path.join(outdir, f"bars_mms{dim}d_{n}.h5")
        a = run(st.mms_command(dim, n, ["-bars"] + extra, display_path(out)), out)
        ref_out = os.path.join(outdir, f"bars_mms{dim}d_{n}_eps1000.h5")
        ref = run(st.mms_command(dim, n, extra + st.eps_over_1000(extra), display_path(ref_out)), ref_out)
        exact = mms_quantities(mms_from_run(a), a["young_modulus"], a["poisson_ratio"])
        for q in st.MMS_QUANTITIES:
            name = f"contact_force_{'xyz'[dim - 1]}" if q == "contact_force" else q
            rows.append(coverage_row(f"mms{dim}d {a['n_cells']} cells", name, *st.qoi(a, name), exact[name], float(ref[name])))
        if (dim, n) == (2, 32):  # the figure of the pressure with its band (docs/estimate_band.png)
            from plot_contact import plot_contact
            plot_contact(out, os.path.join(outdir, "band.png"))
        nodes, covered, median = st.pressure_band_coverage(out)
        bands.append({"case": f"mms{dim}d {a['n_cells']} cells", "nodes": nodes, "covered": covered, "median_band_over_error": median})
        print(f"pressure band mms{dim}d {a['n_cells']} cells: covers {covered} of {nodes} nodes, median band / error {median:.2f}")
    for case, method in st.COVERAGE_HERTZ:
        spec = hertz.CASES[case]
        h_near = spec["h_near"][0]
        mesh = os.path.join(outdir, f"block{st.BLOCK:g}_" + hertz.mesh_name(case, h_near))
        if not os.path.isfile(mesh):
            st.write_block_mesh(case, h_near, mesh)
        out = os.path.join(outdir, f"bars_block{st.BLOCK:g}_" + hertz.output_name(case, h_near, method))
        cmd = hertz.command(case, display_path(mesh), method, display_path(out)) + ["-bars", "-contact_grid_sequence", "2"]
        if spec["dim"] == 3:
            cmd += st.SOLVER_3D[:2]  # GAMG; no dual norm without an exact solution
        a = run(cmd, out)
        ref_out = out.replace(".h5", "_eps1000.h5")
        at = cmd.index("-output")  # the same run (its final mesh too) without -bars, at eps/1000, to another file
        ref_cmd = [c for c in cmd[:at] + cmd[at + 2:] if c != "-bars"]
        ref_cmd += st.eps_over_1000(ref_cmd) + ["-output", display_path(ref_out)]
        ref = run(ref_cmd, ref_out)
        at_ref = st.hertz_truth(case, ref)  # the closed form at the reference's own force
        for q, (name, exact) in st.hertz_truth(case, a).items():
            rows.append(coverage_row(f"hertz {case} {a['n_cells']} cells", name, *st.qoi(a, name), exact, float(ref[name]), at_ref[q][1],
                                     floor=name == "contact_size" and st.size_bar_is_its_floor(a)))
    for case, method, h_near in st.COVERAGE_REMESHED:
        spec = hertz.CASES[case]
        tag = f"{case}_remeshed_{h_near:g}_{method.replace('=', '').replace('/', '_')}"
        mesh, model, out = (os.path.join(outdir, tag + ext) for ext in (".msh", ".geo", ".h5"))
        spec["shape"](mesh, radius=hertz.RADIUS, h_far=spec["h_far"], h_near=h_near, width=spec["width"], near=spec["near"], model=model)
        cmd = hertz.command(case, display_path(mesh), method, display_path(out)) + ["-bars", "-contact_grid_sequence", "2", "-adapt_model",
                                                                                     display_path(model)]
        if spec["dim"] == 3:
            cmd += hertz.GAMG_3D
        a = run(cmd, out)
        for q, (name, exact) in st.hertz_truth(case, a).items():  # no eps -> 0 run of the same levels: the causes unmeasured
            value = st.qoi(a, name)[0]
            rows.append(coverage_row(f"hertz {case} remeshed h_near={h_near:g} {method}", name, *st.qoi(a, name), exact,
                                     value if method == "vi" else float("nan"), floor=name == "contact_size" and st.size_bar_is_its_floor(a),
                                     reference=hertz.CLOSED_FORM_ACCURACY))
    return rows, bands


def coverage_row(case, name, value, bar, exact, limit, limit_exact=None, floor=False, reference=1e-4):
    """A quantity's bar against its true error, and against the sum of its two causes' own errors: the penalty's,
    |value - limit|, limit the same run at eps/1000 (its eps -> 0 limit on the same mesh; NaN where not run), and the
    mesh's |limit - limit_exact| (limit_exact: the exact value for the limit's run, the closed form at its own force for
    Hertz; exact by default). Where the two have opposite signs they cancel in part in the error, and the bar, which adds
    them, is wide against it. floor: the bar's mesh part is the zone's one-cell band (size_bar_is_its_floor()).
    reference: the exact value's own accuracy, relative (a closed form's is hertz.CLOSED_FORM_ACCURACY): below it the
    error, and so the bar's ratio to it, is not known."""
    err = abs(value - exact)
    limit_exact = exact if limit_exact is None else limit_exact
    causes = abs(value - limit) + abs(limit - limit_exact)
    row = {"case": case, "quantity": name, "value": value, "exact": exact, "error": err, "bar": bar,
           "covered": int(bool(bar >= err)) if np.isfinite(bar) else "no bar", "bar_over_error": bar / err if err > 0 else float("nan"),
           "eps_error": abs(value - limit), "mesh_error": abs(limit - limit_exact), "bar_over_causes": bar / causes if causes > 0 else float("nan"),
           "floor": int(bool(floor)), "reference": reference}
    print(f"bars {case} {name}: {value:.6g} +- {bar:.2g} against {exact:.6g} (error {err:.2g}): "
          f"{'covered' if row['covered'] == 1 else 'NOT covered' if row['covered'] == 0 else 'no bar'}")
    return row


def write_csv(rows, path):
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


def figures(rows, hertz_files, outdir):
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for ax, dim in zip(axes, (2, 3)):
        for label, d, _, _ in st.SERIES:
            if d != dim:
                continue
            sel = [r for r in rows if r["series"] == label]
            ax.semilogx([r["n_dofs"] for r in sel], [r["effectivity"] for r in sel], "o-", label=label.split(" ", 1)[1])
        ax.set_xlabel("dofs")
        ax.set_ylabel("estimate / exact energy-norm error")
        ax.set_title(f"mms {dim}D")
        ax.set_ylim(0, None)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    save_png(fig, os.path.join(outdir, "effectivity.png"), 120)

    path, m = hertz_files["cylinder"]
    import h5py
    with h5py.File(path, "r") as f:
        X, cells, dens = f["geometry/vertices"][:], f["viz/topology/cells"][:], f["cell_fields/error_density"][:]
    a = m["a_h"]
    cen = X[cells].mean(axis=1)
    keep = (cen[:, 0] < 4 * a) & (cen[:, 1] < 2 * a)
    fig, ax = plt.subplots(figsize=(8, 4))
    tp = ax.tripcolor(X[:, 0], X[:, 1], cells[keep], facecolors=np.log10(dens[keep]), cmap="viridis", edgecolors="none")
    ax.axvline(a, color="w", ls="--", lw=1)
    ax.set_xlim(0, 4 * a)
    ax.set_ylim(0, 2 * a)
    ax.set_aspect("equal")
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_title(f"Hertz cylinder: log10 error_density (dashed: the contact zone's edge x = a = {a:.4f})", fontsize=10)
    fig.colorbar(tp, ax=ax, shrink=0.8)
    save_png(fig, os.path.join(outdir, "hertz_density.png"), 120)


def report(rows, pen, hz, outdir):
    lines = ["# The a posteriori estimate: effectivity, penalty part, Hertz", "",
             f"Made by `make estimates` (scripts/estimates.py). Effectivity = estimate_total / error_energy; spread and rates over "
             f"the {st.ASYMPTOTIC} finest meshes of each series.", "",
             "| series | effectivity (finest) | min | max | spread | rate of the estimate | rate of the error |", "|---|---|---|---|---|---|---|"]
    summaries = {}
    for label, _, _, _ in st.SERIES:
        sel = [r for r in rows if r["series"] == label]
        s = st.series_summary(sel)
        summaries[label] = s
        lines.append(f"| {label} | {sel[-1]['effectivity']:.3f} | {s['eff_min']:.3f} | {s['eff_max']:.3f} | {s['eff_spread']:.3f} | "
                     f"{s['rate_estimate']:.3f} | {s['rate_error']:.3f} |")
    allfine = [r["effectivity"] for label in summaries for r in [x for x in rows if x["series"] == label][-st.ASYMPTOTIC:]]
    lines += ["", f"Over all series (their {st.ASYMPTOTIC} finest meshes): effectivity from {min(allfine):.3f} to {max(allfine):.3f}, "
              f"a spread of {max(allfine) / min(allfine):.3f}.", "",
              "## The penalty part against the distance to SNESVI (same mesh)", "",
              "| dim | mesh | rule | eps | estimate_penalty | ‖u_eps − u_vi‖_a | ratio |", "|---|---|---|---|---|---|---|"]
    for r in pen:
        lines.append(f"| {r['dim']} | {r['n']}^{r['dim']} | {r['rule']} | h × {r['eps0']:g} | {r['estimate_penalty']:.3e} | "
                     f"{r['distance_to_vi']:.3e} | {r['ratio']:.3f} |")
    lines += ["", f"## Hertz: where the error density is largest ({HERTZ_METHOD}, the coarsest mesh of make hertz)", "",
              "| case | a (closed form) | a (run) | densest cell from the edge (cell diameters) | median of the 10 densest |", "|---|---|---|---|---|"]
    for r in hz:
        lines.append(f"| {r['case']} | {r['a']:.4f} | {r['a_h']:.4f} | {r['densest_cells_from_edge']:.2f} | {r['median_of_10_densest']:.2f} |")
    with open(os.path.join(outdir, "estimates.md"), "w") as fh:
        fh.write("\n".join(lines) + "\n")
    return summaries, allfine


def bars_report(cov, bands, outdir):
    with_bar = [r for r in cov if r["covered"] != "no bar"]
    covered = sum(r["covered"] for r in with_bar)
    lines = ["# The error bars against the known values", "",
             f"Made by `scripts/estimates.py` (make estimates). {covered} of {len(with_bar)} bars cover the true error; "
             f"{len(cov) - len(with_bar)} quantities got no bar (outside the asymptotic range): {covered} of the {len(cov)} cases are "
             "covered by a bar. The Hertz indenters' block is "
             f"{st.BLOCK:g} times make hertz's (scripts/signorini/estimates.py).", "",
             "The error's two causes, each against its own reference: eps, |Q - Q(eps/1000)| on the same mesh, and the mesh, "
             "|Q(eps/1000) - exact|; bar / causes = bar / (the sum of the two).", "",
             "floor: the size's mesh part is the one-cell band along the zone's edge, its resolution (no 10x check). "
             f"Hertz's closed forms are references to about {hertz.CLOSED_FORM_ACCURACY:.2%} for make hertz's own bodies (the remeshed "
             "rows; make hertz-curvature): a smaller error is not known, nor its bar's ratio to it (no 10x check).", "",
             "| run | quantity | value | bar | exact | error | covered | bar / error | eps error | mesh error | bar / causes | floor |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in cov:
        lines.append(f"| {r['case']} | {r['quantity']} | {r['value']:.6g} | {r['bar']:.2g} | {r['exact']:.6g} | {r['error']:.2g} | {r['covered']} | "
                     f"{r['bar_over_error']:.2f} | {r['eps_error']:.2g} | {r['mesh_error']:.2g} | {r['bar_over_causes']:.2f} | {r['floor']} |")
    lines += ["", "The pressure's band (contact_pressure_bar) against the exact pressure at the nodes of Gamma_C whose error is above "
              "1e-3 of the peak:", "", "| run | nodes | covered | median band / error |", "|---|---|---|---|"]
    lines += [f"| {b['case']} | {b['nodes']} | {b['covered']} | {b['median_band_over_error']:.2f} |" for b in bands]
    with open(os.path.join(outdir, "bars.md"), "w") as fh:
        fh.write("\n".join(lines) + "\n")


def check_bars(cov):
    bad = []
    with_bar = [r for r in cov if r["covered"] != "no bar"]
    if with_bar and sum(r["covered"] for r in with_bar) < 0.9 * len(with_bar):
        bad.append(f"bars: {sum(r['covered'] for r in with_bar)} of {len(with_bar)} cover the true error (at least 9 in 10 asked)")
    bad += [f"bars: {r['case']} {r['quantity']}: bar {r['bar']:.2g} over 10 times the error {r['error']:.2g}" for r in with_bar
            if r["error"] > r["reference"] * abs(r["exact"]) and r["bar"] > 10 * max(r["error"], causes_of(r)) and not r["floor"]]
    return bad


def causes_of(r):
    """The sum of the error's two causes, each against its own reference (0 where not measured): where they have
    opposite signs and cancel in the error, a bar that adds them is judged against their sum."""
    c = r["eps_error"] + r["mesh_error"]
    return c if np.isfinite(c) else 0.0


def check(summaries, allfine, pen, hz):
    bad = []
    for label, s in summaries.items():
        if s["eff_spread"] > 1.5:
            bad.append(f"{label}: effectivity spread {s['eff_spread']:.3f} > 1.5")
        if abs(s["rate_estimate"] - s["rate_error"]) > 0.1:
            bad.append(f"{label}: rate {s['rate_estimate']:.3f} against the error's {s['rate_error']:.3f}")
    if max(allfine) / min(allfine) > 3:
        bad.append(f"effectivity over all series varies {max(allfine) / min(allfine):.3f}x > 3")
    bad += [f"penalty {r['dim']}D {r['rule']} eps0={r['eps0']}: ratio {r['ratio']:.3f}" for r in pen if not 1 / 3 <= r["ratio"] <= 3]
    bad += [f"hertz {r['case']}: densest cell {r['densest_cells_from_edge']:.2f} cells from the edge" for r in hz
            if r["densest_cells_from_edge"] > 2]
    return bad


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--outdir", default=os.path.join(ROOT, "output", "estimates"))
    p.add_argument("--check", action="store_true")
    p.add_argument("--parts", default="estimate,bars", help="estimate (parts 1 to 3), bars (part 4), or both (default)")
    args = p.parse_args()
    parts = args.parts.split(",")
    os.makedirs(args.outdir, exist_ok=True)
    bad = []
    if "bars" in parts:
        cov, bands = coverage(args.outdir)
        write_csv(cov, os.path.join(args.outdir, "bars.csv"))
        bars_report(cov, bands, args.outdir)
        bad += check_bars(cov)
        bad += [f"pressure band: {b['case']} covers {b['covered']} of {b['nodes']} nodes" for b in bands if b["covered"] < 0.9 * b["nodes"]]
    if "estimate" in parts:
        bad += estimate_parts(args.outdir)
    if args.check:
        for b in bad:
            print("CHECK FAILED:", b, file=sys.stderr)
        return 1 if bad else 0
    return 0


def estimate_parts(outdir):
    """Parts 1 to 3; the failed checks."""
    rows = effectivity_series(outdir)
    pen = penalty_ladder(outdir)
    hz, hertz_files = hertz_cases(outdir)
    write_csv(rows, os.path.join(outdir, "estimates.csv"))
    write_csv(pen, os.path.join(outdir, "penalty.csv"))
    write_csv(hz, os.path.join(outdir, "hertz.csv"))
    figures(rows, hertz_files, outdir)
    summaries, allfine = report(rows, pen, hz, outdir)
    print(f"wrote {display_path(os.path.join(outdir, 'estimates.md'))}")
    return check(summaries, allfine, pen, hz)


if __name__ == "__main__":
    sys.exit(main())
