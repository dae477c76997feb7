#!/usr/bin/env python3
"""The performance targets of docs/solvers.md, "Performance" measured in one invocation (make bench): each row is a target,
the figure measured here, whether it is met, and the command behind it. Whole-process wall times and peak resident
sets come from /usr/bin/time -v; ratios are of medians of runs alternated side by side in this invocation. The GetFEM
row reads bench/getfem.csv (scripts/bench_getfem.py), the FEniCSx row bench/fenicsx.csv (scripts/bench_fenicsx.py). Writes bench/targets.md and bench/targets.csv."""
import argparse
import csv
import json
import os
import statistics
import sys
import time

import h5py

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from signorini.mpirun import BENCH_ENV, run_timed  # noqa: E402
from signorini.paths import BIN, ROOT  # noqa: E402

BASE = ["-options_file", "options/square.yaml", "-options_file", "options/solvers/gamg.yaml", "-contact_monitor", "0"]
BASE_MG = ["-options_file", "options/square.yaml", "-options_file", "options/solvers/mg.yaml", "-contact_monitor", "0"]
BASE_SSOR = BASE + ["-options_file", "options/solvers/ssor_fine.yaml"]  # GAMG with one SSOR sweep on the finest level (2D)


def solver(args, name, out, ranks=1, may_fail=False, base=BASE):
    """One whole-process run: (wall s, peak MiB of the largest rank (/usr/bin/time on mpiexec), /run attributes).
    A failed solve (exit 3, converged = 0 in its file) stops the bench unless may_fail: then its attributes say so."""
    h5 = os.path.join(out, name + ".h5")
    wall, mem, log = run_timed(["mpiexec", "-n", str(ranks), BIN] + base + [str(a) for a in args] + ["-output", h5], env=BENCH_ENV, ok_codes=(0, 3) if may_fail else (0,))
    with h5py.File(h5, "r") as f:
        attrs = dict(f["run"].attrs)
    if int(attrs["converged"]) != 1 and not may_fail:
        raise RuntimeError(f"{name} did not converge:\n{log[-2000:]}")
    print(f"{name}: {wall:.2f} s, {mem:.0f} MiB, {int(attrs['n_dofs'])} dofs, {int(attrs['newton_its'])} Newton, {int(attrs['ksp_its'])} Krylov", flush=True)
    return wall, mem, attrs


def side_by_side(runs, pairs, out):
    """runs: {name: (args, ranks[, base options])}; each run `pairs` times, alternating;
    {name: (median wall, median MiB, attrs of the last, walls, attrs of each run)}."""
    walls, mems, attrs, every = {k: [] for k in runs}, {k: [] for k in runs}, {}, {k: [] for k in runs}
    for _ in range(pairs):
        for name, spec in runs.items():
            w, m, a = solver(spec[0], name, out, spec[1], base=spec[2] if len(spec) > 2 else BASE)
            walls[name].append(w)
            mems[name].append(m)
            attrs[name] = a
            every[name].append(a)
    return {k: (statistics.median(walls[k]), statistics.median(mems[k]), attrs[k], walls[k], every[k]) for k in runs}


def median_attr(result, key):
    """The median of a /run attribute over the runs of one side_by_side entry."""
    return statistics.median(float(a[key]) for a in result[4])


def pair_range(a, b):
    """The spread of the ratios a_i / b_i of runs made side by side: 'pairs 1.31 to 1.45'."""
    r = [x / y for x, y in zip(a[3], b[3])]
    return f"pairs {min(r):.2f} to {max(r):.2f}"


def row(target, measured, met, command):
    return {"target": target, "measured": measured, "met": "(figure)" if met is None else "met" if met else "not met", "command": command}


def measure_default(out, s, pairs):
    """The default run against the elastic solve, 512 x 512: the default nests (-contact_coarse_levels -1: 16 to 256
    cells per side first, solved by the boxes' geometric multigrid, -contact_coarse_mg), so it is the nested run too;
    GAMG on every box (-contact_coarse_mg 0, the default before: 64 to 256 cells per side) and the direct solve
    (-contact_coarse_levels 0) are measured alongside. Set-up, memory and the inexact Newton."""
    n = 512 // s
    box = ["-dm_plex_box_faces", f"{n},{n}"]
    r = side_by_side({"elastic": (box + ["-contact_method", "none"], 1), "penalty": (box, 1),
                      "penalty_gamg_boxes": (box + ["-contact_coarse_mg", 0], 1), "penalty_direct": (box + ["-contact_coarse_levels", 0], 1)}, pairs, out)
    e, p, g, o = r["elastic"], r["penalty"], r["penalty_direct"], r["penalty_gamg_boxes"]
    cmd = f"bin/signorini {' '.join(BASE)} -dm_plex_box_faces {n},{n} [-contact_method none]"
    dofs = int(e[2]["n_dofs"])
    setup = median_attr(e, "time_setup")
    rows = [row(f"default penalty run / elastic solve <= 1.3 ({n} x {n}, 1 rank, whole process)", f"{p[0] / e[0]:.3f} ({p[0]:.3f} s / {e[0]:.3f} s; {pair_range(p, e)})",
                p[0] / e[0] <= 1.3, cmd),
            row("with nested iteration <= 1.1", f"{p[0] / e[0]:.3f} (the default run, {int(p[2]['coarse_levels'])} coarser boxes first, by the geometric MG; "
                f"GAMG on every box, -contact_coarse_mg 0: {o[0] / e[0]:.3f}, {o[0]:.3f} s, {pair_range(o, e)}, {int(o[2]['coarse_levels'])} coarser boxes; "
                f"without them, -contact_coarse_levels 0: {g[0] / e[0]:.3f}, {g[0]:.3f} s, {pair_range(g, e)})", p[0] / e[0] <= 1.1, cmd),
            row("set-up <= 1.5 s per million unknowns (2D)", f"{setup / dofs * 1e6:.2f} s (set-up {setup:.3f} s, the median of the elastic runs; {dofs} unknowns)",
                setup / dofs * 1e6 <= 1.5, cmd + " (time_setup in /run)")]
    for name, v in (("elastic", e), ("penalty", p)):
        kb = v[1] * 2**20 / dofs / 1e3  # MiB from /usr/bin/time, KB of 1000 bytes
        rows.append(row(f"peak memory <= 1.2 KB per unknown in 2D, {name}", f"{kb:.2f} KB ({v[1]:.0f} MiB whole process)", kb <= 1.2, cmd))
    # the hierarchy's reuse: one GAMG build on the final box, updated at the Newton steps whose contact rows change
    rows.append(row("Newton: inexact linear solves (Eisenstat-Walker), final residual as tight; the GAMG hierarchy reused while only the contact rows change",
                    f"ksp_ew = {int(p[2]['ksp_ew'])}, {int(p[2]['ksp_its'])} CG iterations "
                    f"in {int(p[2]['newton_its'])} Newton steps on the final box, |F| = {p[2]['residual_norm']:.1e}, GAMG built {int(p[2]['pc_builds'])} time(s) and "
                    f"updated {int(p[2]['pc_updates'])} time(s) (without nesting: {int(g[2]['ksp_its'])} in {int(g[2]['newton_its'])}, |F| = {g[2]['residual_norm']:.1e}, "
                    f"built {int(g[2]['pc_builds'])} time(s) and updated {int(g[2]['pc_updates'])} time(s))",
                    int(p[2]["ksp_ew"]) == 1 and p[2]["residual_norm"] <= max(g[2]["residual_norm"], 1e-8 * p[2]["load_norm"])
                    and int(p[2]["pc_builds"]) == 1 and int(g[2]["pc_builds"]) == 1, cmd))
    return rows


def measure_iterations(out, s, pairs):
    """GAMG iterations of the elastic solve to rtol 1e-8, 2D from 10k to 2M unknowns, 3D to 1M: in PETSc's default test
    for CG, the preconditioned residual (as PETSc's ex17 counts the issue's 14), one linear solve (-snes_type ksponly;
    -snes_rtol 1e-4 accepts its true residual, about 1e-5 of the load); and in the true residual, the project's default
    for the elastic solve (a figure)."""
    its, true_its = [], []
    for dim, faces, ranks in [(2, 72, 1), (2, 256, 1), (2, 1024, 2), (3, 16, 1), (3, 32, 2), (3, 68, 2)]:
        f = max(faces // s, 4)
        mesh = ["-dm_plex_dim", dim, "-dm_plex_box_faces", ",".join([str(f)] * dim), "-contact_method", "none", "-ksp_rtol", "1e-8"]
        _, _, a = solver(mesh + ["-snes_type", "ksponly", "-ksp_norm_type", "preconditioned", "-snes_rtol", "1e-4"], f"gamg_pits_{dim}d_{f}", out, ranks)
        if int(a["newton_its"]) != 1:
            raise RuntimeError(f"gamg_pits_{dim}d_{f}: {int(a['newton_its'])} linear solves, not one")
        its.append((f"{dim}D {int(a['n_dofs'])}", int(a["ksp_its"])))
        _, _, a = solver(mesh, f"gamg_its_{dim}d_{f}", out, ranks)
        true_its.append((f"{dim}D {int(a['n_dofs'])}", int(a["ksp_its"])))
    # GAMG with SSOR on the finest level, 2D (a figure)
    ssor_its = []
    for faces, ranks in [(72, 1), (256, 1), (1024, 2)]:
        f = max(faces // s, 4)
        _, _, a = solver(["-dm_plex_box_faces", f"{f},{f}", "-contact_method", "none", "-ksp_rtol", "1e-8"], f"ssor_its_2d_{f}", out, ranks, base=BASE_SSOR)
        ssor_its.append((f"2D {int(a['n_dofs'])}", int(a["ksp_its"])))
    # the geometric multigrid on the same sizes: the 2D boxes nest by default, 3D over the grid sequence (2^3 to 9^3 cells refined)
    mg_its = []
    for dim, faces, ranks in [(2, 72, 1), (2, 256, 1), (2, 1024, 2), (3, 16, 1), (3, 32, 2), (3, 72, 2)]:
        f = max(faces // s, 32 if dim == 2 else 4)  # a 2D box nests (-contact_coarse_levels) from 32 cells per side
        mesh = ["-dm_plex_box_faces", f"{f},{f}"] if dim == 2 else ["-dm_plex_dim", 3, "-dm_plex_box_faces", ",".join([str(max(f // 8, 1))] * 3),
                                                                    "-contact_grid_sequence", 3]
        if dim == 2 and ranks > 1:  # 2 ranks: the grid sequence from 32^2, five times (the row's command since before the boxes nested on several ranks)
            mesh = ["-dm_plex_box_faces", f"{max(f // 32, 1)},{max(f // 32, 1)}", "-contact_grid_sequence", 5]
        _, _, a = solver(mesh + ["-contact_method", "none", "-ksp_rtol", "1e-8"], f"mg_its_{dim}d_{f}", out, ranks, base=BASE_MG)
        mg_its.append((f"{dim}D {int(a['n_dofs'])}", f"{int(a['ksp_its'])} in {int(a['newton_its'])} Newton steps"))
    return [row("elastic GAMG <= 20 CG iterations to rtol 1e-8, 10k to 2M unknowns in 2D, to 1M in 3D (PETSc's default test for CG: the "
                "preconditioned residual, as ex17)", "; ".join(f"{k}: {v}" for k, v in its), max(v for _, v in its) <= 20,
                "bin/signorini ... -contact_method none -ksp_rtol 1e-8 -snes_type ksponly -ksp_norm_type preconditioned -snes_rtol 1e-4 "
                "-dm_plex_dim D -dm_plex_box_faces N,..."),
            row("elastic GAMG: CG iterations to rtol 1e-8 in the true residual (a figure: the project's default norm for the elastic solve)",
                "; ".join(f"{k}: {v}" for k, v in true_its), None, "bin/signorini ... -contact_method none -ksp_rtol 1e-8 -dm_plex_dim D -dm_plex_box_faces N,..."),
            row("GAMG + ssor_fine.yaml (2D): CG iterations of the elastic solve to rtol 1e-8 (a figure)", "; ".join(f"{k}: {v}" for k, v in ssor_its), None,
                "bin/signorini ... gamg.yaml ssor_fine.yaml -contact_method none -ksp_rtol 1e-8 -dm_plex_box_faces N,N"),
            row("geometric MG (mg.yaml): CG iterations of the elastic solve to rtol 1e-8, from the coarser meshes' solution (a figure: the target is GAMG's)",
                "; ".join(f"{k}: {v}" for k, v in mg_its),
                None, "bin/signorini ... mg.yaml -contact_method none -ksp_rtol 1e-8 (2D: the box, 2 ranks 32^2 refined 5 times; 3D: N/8 cells refined 3 times)")]


SWEEP = "1,0.1,0.01,1e-3,1e-4,1e-5,1e-6,1e-7"  # the 8 values of eps0 of the sweep
SPREAD = ["1e4", "1e2", "1", "1e-2", "1e-4", "1e-6", "1e-8"]  # the eps0 of the Krylov spread


def sweep_against_one(box, tag, pairs, out, base=BASE):
    """The sweep and one penalty solve side by side (runs <tag>one and <tag>sweep): (ratio of medians, sweep, one)."""
    r = side_by_side({f"{tag}one": (box, 1, base), f"{tag}sweep": (box + ["-penalty_eps0_sweep", SWEEP], 1, base)}, pairs, out)
    return r[f"{tag}sweep"][0] / r[f"{tag}one"][0], r[f"{tag}sweep"], r[f"{tag}one"]


def iterations_per_step(box, tag, out, base=BASE, may_fail=False):
    """Krylov iterations per Newton step for each eps0 of SPREAD (runs <tag>eps_<eps0>): [(eps0, value, None)], or
    [(eps0, None, reason)] for a failed solve (with may_fail)."""
    per = []
    for eps0 in SPREAD:
        _, _, a = solver(box + ["-penalty_eps0", eps0], f"{tag}eps_{eps0}", out, base=base, may_fail=may_fail)
        if int(a["converged"]) == 1:
            per.append((eps0, int(a["ksp_its"]) / max(int(a["newton_its"]), 1), None))
        else:
            per.append((eps0, None, a["snes_reason"].decode() if isinstance(a["snes_reason"], bytes) else a["snes_reason"]))
    return per


def spread_of(per):
    values = [v for _, v, _ in per if v is not None]
    return max(values) / min(values)


def measure_eps(out, s, pairs):
    """The 8-value sweep against one penalty solve, and the Krylov iterations per Newton step over eps."""
    n2 = 256 // s
    box2 = ["-dm_plex_box_faces", f"{n2},{n2}"]
    ratio, sweep, one = sweep_against_one(box2, "", pairs, out)
    rows = [row(f"8-value eps sweep (h to 1e-7 h) <= 2 penalty solves ({n2} x {n2})",
                f"{ratio:.2f} ({sweep[0]:.2f} s / {one[0]:.2f} s, medians of {pairs} pairs; {pair_range(sweep, one)}; "
                f"{int(sweep[2]['ksp_its_total'])} CG iterations in {int(sweep[2]['newton_its_total'])} Newton steps)", ratio <= 2.0,
                f"... -dm_plex_box_faces {n2},{n2} [-penalty_eps0_sweep 1,0.1,...,1e-7]")]
    per = iterations_per_step(box2, "", out, may_fail=True)
    failed = [e for e, v, _ in per if v is None]
    spread = spread_of(per)
    rows.append(row(f"GAMG Krylov iterations per Newton step within 2x over eps = 1e4 h to 1e-8 h ({n2} x {n2})",
                    ", ".join(f"{e} h: {v:.1f}" if v is not None else f"{e} h: failed ({why})" for e, v, why in per)
                    + f" (spread {spread:.1f} over the converged)", spread <= 2.0 and not failed,
                    f"... -dm_plex_box_faces {n2},{n2} -penalty_eps0 E"))
    # GAMG with SSOR on the finest level (options/solvers/ssor_fine.yaml, the 2D configuration)
    ssor_ratio, sweep, one = sweep_against_one(box2, "ssor_", pairs, out, base=BASE_SSOR)
    per = iterations_per_step(box2, "ssor_", out, base=BASE_SSOR)
    ssor_spread = spread_of(per)
    rows.append(row(f"GAMG + ssor_fine.yaml (2D): 8-value eps sweep <= 2 penalty solves, Krylov iterations per Newton step within 2x ({n2} x {n2})",
                    f"sweep {ssor_ratio:.2f} ({sweep[0]:.2f} s / {one[0]:.2f} s, medians of {pairs} pairs; {pair_range(sweep, one)}; "
                    f"{int(sweep[2]['ksp_its_total'])} CG iterations in {int(sweep[2]['newton_its_total'])} Newton steps); per step "
                    + ", ".join(f"{e} h: {v:.1f}" for e, v, _ in per) + f" (spread {ssor_spread:.2f})", ssor_ratio <= 2.0 and ssor_spread <= 2.0,
                    f"... gamg.yaml ssor_fine.yaml -dm_plex_box_faces {n2},{n2} [-penalty_eps0_sweep 1,...,1e-7 | -penalty_eps0 E]"))
    # the same with the geometric multigrid (a figure: the targets are GAMG's)
    box2 = ["-dm_plex_box_faces", f"{max(n2, 32)},{max(n2, 32)}"]
    mg_ratio, sweep, one = sweep_against_one(box2, "mg_", 3, out, base=BASE_MG)
    per = iterations_per_step(box2, "mg_", out, base=BASE_MG)
    rows.append(row("geometric MG (mg.yaml): the eps sweep over one solve, and Krylov iterations per Newton step over eps = 1e4 h to 1e-8 h (figures)",
                    f"sweep {mg_ratio:.2f} ({sweep[0]:.2f} s / {one[0]:.2f} s, medians of 3 pairs); per step "
                    + ", ".join(f"{e} h: {v:.1f}" for e, v, _ in per) + f" (spread {spread_of(per):.2f})", None,
                    f"... mg.yaml -dm_plex_box_faces {n2},{n2} [-penalty_eps0_sweep 1,...,1e-7 | -penalty_eps0 E]"))
    return rows


def measure_parallel(out, s, pairs):
    """3D 1M unknowns on 2 ranks, the speed-up of 2 ranks at 1M unknowns in 2D and 3D, and the peak memory per unknown
    in 3D on one rank (the elastic solve and the penalty run of the same box)."""
    n3, n4 = 68 // s, 704 // s
    box3 = ["-dm_plex_dim", 3, "-dm_plex_box_faces", f"{n3},{n3},{n3}"]
    r3 = side_by_side({"3d_np2": (box3, 2), "3d_np1": (box3, 1), "3d_elastic_np1": (box3 + ["-contact_method", "none"], 1)}, 1, out)
    d3 = int(r3["3d_np2"][2]["n_dofs"])
    mem3 = [(name, r3[run][1], r3[run][1] * 2**20 / int(r3[run][2]["n_dofs"]) / 1e3) for name, run in (("elastic", "3d_elastic_np1"), ("penalty", "3d_np1"))]
    box4 = ["-dm_plex_box_faces", f"{n4},{n4}"]
    # both nest by default (-contact_coarse_levels -1: 704 = 2^5 x 22, and 22 rows split in two slabs of rows)
    r2 = side_by_side({"2d_np1": (box4, 1), "2d_np2": (box4, 2)}, 1, out)
    s2, s3 = r2["2d_np1"][0] / r2["2d_np2"][0], r3["3d_np1"][0] / r3["3d_np2"][0]
    # the geometric multigrid (mg.yaml) over the grid sequence, the same command on 1 and 2 ranks: 3D 9^3 refined 3 times
    # (72^3, 1.15M unknowns, PETSc's refinements), 2D 22^2 refined 5 times (704^2: the project's boxes, in slabs of rows on 2 ranks)
    m3, m2 = max(72 // s // 8, 2), max(704 // s // 32, 4)
    g3 = ["-dm_plex_dim", 3, "-dm_plex_box_faces", f"{m3},{m3},{m3}", "-contact_grid_sequence", 3]
    g2 = ["-dm_plex_box_faces", f"{m2},{m2}", "-contact_grid_sequence", 5]
    rm = side_by_side({"3d_mg_np2": (g3, 2, BASE_MG), "3d_mg_np1": (g3, 1, BASE_MG), "2d_mg_np1": (g2, 1, BASE_MG), "2d_mg_np2": (g2, 2, BASE_MG)}, 1, out)
    dm3 = int(rm["3d_mg_np2"][2]["n_dofs"])
    sm2, sm3 = rm["2d_mg_np1"][0] / rm["2d_mg_np2"][0], rm["3d_mg_np1"][0] / rm["3d_mg_np2"][0]
    t3 = min(r3["3d_np2"][0], rm["3d_mg_np2"][0])
    # the memory system: the STREAM-like triad of -perf_bandwidth (three 64 MB vectors per rank, whatever the mesh) on 1
    # and 2 ranks, alternated 3 times; a solve bound by the memory bandwidth speeds up by about its ratio
    tb = ["-dm_plex_box_faces", "32,32", "-contact_method", "none", "-perf_bandwidth"]
    rt = side_by_side({"triad_np1": (tb, 1), "triad_np2": (tb, 2)}, 3, out)
    tri1, tri2 = median_attr(rt["triad_np1"], "bandwidth_triad_gbs"), median_attr(rt["triad_np2"], "bandwidth_triad_gbs")
    tri_each = [a2["bandwidth_triad_gbs"] / a1["bandwidth_triad_gbs"] for a1, a2 in zip(rt["triad_np1"][4], rt["triad_np2"][4])]
    return [row(f"peak memory <= 3 KB per unknown in 3D, {name} (1 rank, the box of {n3}^3)", f"{kb:.2f} KB ({mib:.0f} MiB whole process, {d3} unknowns)", kb <= 3.0,
                f"bin/signorini ... -dm_plex_dim 3 -dm_plex_box_faces {n3},{n3},{n3} [-contact_method none]") for name, mib, kb in mem3] + [
            row("3D penalty, eps = h, 1M unknowns on 2 ranks <= 30 s", f"GAMG {r3['3d_np2'][0]:.1f} s ({d3} unknowns, the box of {n3}^3); geometric MG "
                f"{rm['3d_mg_np2'][0]:.1f} s ({dm3} unknowns, {m3}^3 refined 3 times, mg.yaml)", t3 <= 30.0,
                f"mpiexec -n 2 bin/signorini ... -dm_plex_dim 3 -dm_plex_box_faces {n3},{n3},{n3}; ... mg.yaml -dm_plex_box_faces {m3},{m3},{m3} -contact_grid_sequence 3"),
            row("mpiexec -n 2 speed-up >= 1.8 at 1M unknowns, 2D and 3D (default penalty run)",
                f"GAMG: 2D {s2:.2f} ({r2['2d_np1'][0]:.1f} s / {r2['2d_np2'][0]:.1f} s, both nested, {int(r2['2d_np2'][2]['coarse_levels'])} coarser boxes), "
                f"3D {s3:.2f} ({r3['3d_np1'][0]:.1f} s / {r3['3d_np2'][0]:.1f} s); geometric MG: "
                f"2D {sm2:.2f} ({rm['2d_mg_np1'][0]:.1f} s / {rm['2d_mg_np2'][0]:.1f} s), 3D {sm3:.2f} ({rm['3d_mg_np1'][0]:.1f} s / {rm['3d_mg_np2'][0]:.1f} s)",
                max(min(s2, s3), min(sm2, sm3)) >= 1.8,
                f"bin/signorini ... -dm_plex_box_faces {n4},{n4} on 1 and 2 ranks, 3D as above; mg.yaml: {m2},{m2} -contact_grid_sequence 5, 3D as above"),
            row("the memory bandwidth on 2 ranks over 1 rank (a figure: the speed-up a solve bound by the bandwidth can reach)",
                f"STREAM-like triad {tri2 / tri1:.2f} ({tri2:.1f} GB/s / {tri1:.1f} GB/s, medians of 3 runs each; pairs {min(tri_each):.2f} to {max(tri_each):.2f})", None,
                "mpiexec -n 1|2 bin/signorini ... -dm_plex_box_faces 32,32 -contact_method none -perf_bandwidth")]


def measure_mg(out, s, pairs):
    """The same targets with the geometric multigrid (options/solvers/mg.yaml in place of gamg.yaml): the elastic solve
    and the penalty run both nest (the box halved while 16 cells per side remain, one PCMG level per box), side by side
    with GAMG's elastic solve, the issue's baseline."""
    n = 512 // s
    box = ["-dm_plex_box_faces", f"{n},{n}"]
    r = side_by_side({"elastic_gamg": (box + ["-contact_method", "none"], 1), "elastic_mg": (box + ["-contact_method", "none"], 1, BASE_MG),
                      "penalty_mg": (box, 1, BASE_MG)}, pairs, out)
    eg, e, p = r["elastic_gamg"], r["elastic_mg"], r["penalty_mg"]
    cmd = f"bin/signorini {' '.join(BASE_MG)} -dm_plex_box_faces {n},{n} [-contact_method none]"
    dofs = int(e[2]["n_dofs"])
    ratio = p[0] / e[0]
    rows = [row(f"geometric MG: default penalty run / elastic solve <= 1.3, nested <= 1.1 ({n} x {n}, both with mg.yaml)",
                f"{ratio:.3f} ({p[0]:.3f} s / {e[0]:.3f} s; {pair_range(p, e)}; {int(p[2]['coarse_levels'])} coarser boxes first); "
                f"against GAMG's elastic solve: {p[0] / eg[0]:.3f} ({eg[0]:.3f} s, {pair_range(p, eg)})", ratio <= 1.1, cmd)]
    for name, v in (("elastic", e), ("penalty", p)):
        kb = v[1] * 2**20 / dofs / 1e3
        rows.append(row(f"geometric MG: peak memory <= 1.2 KB per unknown in 2D, {name}", f"{kb:.2f} KB ({v[1]:.0f} MiB whole process)", kb <= 1.2, cmd))
    rows.append(row("geometric MG: CG iterations (a figure, not a target: the iteration target is GAMG's)",
                    f"elastic: {int(e[2]['ksp_its'])} to rtol 1e-10 (true residual); penalty: {int(p[2]['ksp_its'])} in {int(p[2]['newton_its'])} Newton steps on the final box, "
                    f"|F| = {p[2]['residual_norm']:.1e}", None, cmd))
    return rows


BASE_DEFAULT = ["-options_file", "options/square.yaml", "-contact_monitor", "0"]  # the default run: MUMPS (2D), the boxes' geometric multigrid (3D box)


def measure_estimate(out, s, pairs):
    """The error estimate and the error bars (issue 31) against the default run without them, 512 x 512 with the default
    solver (MUMPS), side by side: the estimate at most 5% of the run (also its own time_estimate over time_total), the
    bars at most 25% more."""
    n = 512 // s
    box = ["-dm_plex_box_faces", f"{n},{n}"]
    r = side_by_side({"no_estimate": (box + ["-estimate", "false"], 1, BASE_DEFAULT), "estimate": (box, 1, BASE_DEFAULT),
                      "bars": (box + ["-bars"], 1, BASE_DEFAULT)}, pairs, out)
    o, e, b = r["no_estimate"], r["estimate"], r["bars"]
    own = statistics.median(float(a["time_estimate"]) / float(a["time_total"]) for a in e[4])
    cmd = f"bin/signorini {' '.join(BASE_DEFAULT)} -dm_plex_box_faces {n},{n} [-estimate false | -bars]"
    return [row(f"error estimate <= 5% of the default run ({n} x {n}, MUMPS, 1 rank, whole process)",
                f"{e[0] / o[0]:.3f} ({e[0]:.3f} s / {o[0]:.3f} s without it; {pair_range(e, o)}); its own time_estimate {100 * own:.1f}% of time_total",
                own <= 0.05, cmd),
            row("error bars (-bars) <= 25% more than the run without them", f"{b[0] / e[0]:.3f} ({b[0]:.3f} s / {e[0]:.3f} s; {pair_range(b, e)})",
                b[0] / e[0] <= 1.25, cmd)]


def measure_load_path(out, s, pairs):
    """A 10-step load path (issue 32) against one solve at the final load, side by side: the default square at 512 x 512
    with GAMG, the 3D sphere indenter of make hertz (h_near 0.02, eps = h/100, the default solver) and the same on make
    hertz-path's graded mesh (GAMG): at most 3 single solves each."""
    from signorini import hertz
    n = 512 // s
    box = ["-dm_plex_box_faces", f"{n},{n}"]
    r = side_by_side({"path_square": (box + ["-load_steps", "10"], 1), "single_square": (box, 1)}, pairs, out)
    mesh = os.path.join(out, "sphere_indenter_h0.02.msh")
    if not os.path.isfile(mesh):
        hertz.write_mesh("sphere-indenter", 0.02, mesh)
    sphere = hertz.command("sphere-indenter", mesh, "eps=h/100", "unused.h5")[4:-2]  # the options, without mpiexec, the binary and -output
    r3 = side_by_side({"path_sphere": (["-load_steps", "10"], 1, sphere), "single_sphere": ([], 1, sphere)}, pairs, out)
    graded = os.path.join(out, hertz.path_mesh_name("sphere-indenter"))
    if s > 1:  # --small: the coarse mesh again
        graded = mesh
    elif not os.path.isfile(graded):
        hertz.write_path_mesh("sphere-indenter", graded)
    path_opts = hertz.command("sphere-indenter", graded, "eps=h/100", "unused.h5")[4:-2] + hertz.PATH_MESHES["sphere-indenter"]["solver"]
    rg = side_by_side({"path_graded": (["-load_steps", "10"], 1, path_opts), "single_graded": ([], 1, path_opts)}, pairs, out)
    rows = []
    for (p, o), what, cmd in (((r["path_square"], r["single_square"]), f"the default square, {n} x {n}, GAMG",
                               f"bin/signorini {' '.join(BASE)} -dm_plex_box_faces {n},{n} [-load_steps 10]"),
                              ((r3["path_sphere"], r3["single_sphere"]), "the 3D sphere indenter (h_near 0.02, eps = h/100)",
                               "bin/signorini (make hertz's sphere-indenter options, eps=h/100) [-load_steps 10]"),
                              ((rg["path_graded"], rg["single_graded"]), "the 3D sphere indenter on make hertz-path's graded mesh (GAMG, eps = h/100)",
                               "bin/signorini (make hertz-path's sphere-indenter options and mesh, GAMG) [-load_steps 10]")):
        rows.append(row(f"a 10-step load path <= 3 single solves at the final load: {what}", f"{p[0] / o[0]:.2f} ({p[0]:.2f} s / {o[0]:.2f} s; {pair_range(p, o)})",
                        p[0] / o[0] <= 3.0, cmd))
    return rows


def measure_default3d(out, s, pairs):
    """Issue 35: the 3D default run (no solver options: on the box that nests, CG with the boxes' geometric multigrid)
    against the elastic solve with the same defaults, on the 40^3 box (201,720 unknowns) and the 68^3 box (971,244; --small:
    5^3 and 8^3), 1 and 2 ranks, side by side: at most 1.1. GAMG (options/solvers/gamg.yaml) on the 40^3 box as a figure."""
    rows = []
    for n in (max(40 // s, 2), max(68 // s, 2)):
        box = ["-dm_plex_dim", "3", "-dm_plex_box_faces", f"{n},{n},{n}"]
        for ranks in (1, 2):
            runs = {"default3d": (box, ranks, BASE_DEFAULT), "elastic3d": (box + ["-contact_method", "none"], ranks, BASE_DEFAULT)}
            if n == max(40 // s, 2) and ranks == 1:
                runs.update({"gamg3d": (box, ranks), "gamg_elastic3d": (box + ["-contact_method", "none"], ranks)})
            r = side_by_side(runs, pairs, out)
            p, e = r["default3d"], r["elastic3d"]
            gamg = ""
            if "gamg3d" in r:
                g, ge = r["gamg3d"], r["gamg_elastic3d"]
                gamg = f"; GAMG (gamg.yaml): {g[0]:.2f} s, over its elastic solve {g[0] / ge[0]:.3f}"
            rows.append(row(f"3D default penalty run / elastic solve <= 1.1 ({n}^3, {int(e[2]['n_dofs'])} unknowns, {ranks} rank(s), whole process)",
                            f"{p[0] / e[0]:.3f} ({p[0]:.2f} s / {e[0]:.2f} s; {pair_range(p, e)}; default_mg = {int(p[2].get('default_mg', 0))}, "
                            f"{int(p[2].get('coarse_levels', 0))} coarser boxes, {int(p[2].get('newton_its', 0))} Newton steps on the final box{gamg})",
                            p[0] / e[0] <= 1.1,
                            f"{'mpiexec -n 2 ' if ranks == 2 else ''}bin/signorini {' '.join(BASE_DEFAULT)} {' '.join(box)} [-contact_method none]"))
    return rows


def measure_vi(out, s, pairs):
    """SNESVI (issue 33) on the 3D sphere indenter of make hertz, whose normals are no axis (its rotated frames), against
    the penalty at eps = h/10 on the same mesh (make hertz's finest, h_near 0.007; --small: 0.02), side by side, each
    with its default solver: at most 3 times the penalty's time."""
    from signorini import hertz
    h_near = 0.007 if s == 1 else 0.02
    mesh = os.path.join(out, hertz.mesh_name("sphere-indenter", h_near))
    if not os.path.isfile(mesh):
        hertz.write_mesh("sphere-indenter", h_near, mesh)
    opts = lambda m: hertz.command("sphere-indenter", mesh, m, "unused.h5")[4:-2]  # noqa: E731  (without mpiexec, the binary and -output)
    r = side_by_side({"vi_sphere": ([], 1, opts("vi")), "penalty_h10_sphere": ([], 1, opts("eps=h/10"))}, pairs, out)
    v, p = r["vi_sphere"], r["penalty_h10_sphere"]
    return [row(f"SNESVI on the 3D sphere indenter (h_near {h_near}, {int(v[2]['n_dofs'])} unknowns, rotated frames) <= 3 times the penalty at eps = h/10",
                f"{v[0] / p[0]:.2f} ({v[0]:.2f} s / {p[0]:.2f} s; {pair_range(v, p)}; {int(v[2]['newton_its'])} and {int(p[2]['newton_its'])} Newton steps)",
                v[0] / p[0] <= 3.0, "bin/signorini (make hertz's sphere-indenter options) [-contact_method vi | -penalty_eps0 0.1]")]


def measure_getfem(out, s, pairs):
    """The ratio of bench/getfem.csv (scripts/bench_getfem.py)."""
    gcsv = os.path.join(os.path.dirname(os.path.dirname(out)), "getfem.csv")
    with open(gcsv) as fh:
        g = {x["code"]: x for x in csv.DictReader(fh)}
    best = max(float(g[c]["getfem_over_this"]) for c in g if c.startswith("signorini"))
    return [row(f"at least 20 times faster than GetFEM on the same problem and mesh ({g['GetFEM (MUMPS)']['dofs']} unknowns)",
                ", ".join(f"{c}: {float(g[c]['getfem_over_this']):.1f}" for c in g if c.startswith("signorini")), best >= 20.0,
                "scripts/bench_getfem.py (bench/getfem.md)")]


def measure_fenicsx(out, s, pairs):
    """Issue 35: the ratio and the contact forces of bench/fenicsx.csv (scripts/bench_fenicsx.py): FEniCSx's best of plain
    Newton and Eisenstat-Walker over the 3D default run on the 40^3 box, at least 5, with the same contact force to 1e-3.
    Judged only on the 40^3 box (another box's table is shown as a figure); no table yet: a row saying so."""
    target = "3D default run (no solver options: the boxes' geometric multigrid) at 40^3 at least 5 times faster than FEniCSx on the same problem (contact force to 1e-3)"
    cmd = "scripts/bench_fenicsx.py (bench/fenicsx.md)"
    fcsv = os.path.join(os.path.dirname(os.path.dirname(out)), "fenicsx.csv")
    if not os.path.exists(fcsv):
        return [row(target, "not measured: no bench/fenicsx.csv (run scripts/bench_fenicsx.py first)", False, cmd)]
    with open(fcsv) as fh:
        g = {x["code"]: x for x in csv.DictReader(fh)}
    ours = next(x for c, x in g.items() if c.startswith("signorini"))
    fenicsx = {c: x for c, x in g.items() if c.startswith("FEniCSx")}
    ratio = float(ours["fenicsx_best_over_this"])
    converged = [x for x in fenicsx.values() if int(x["converged"])]  # the best is over these (bench_fenicsx.py)
    diff = max([float(x["force_rel_diff"]) for x in converged], default=float("nan"))
    n = int(ours["faces"])
    agrees = bool(converged) and diff <= 1e-3
    others = [(c, x) for c, x in g.items() if c.startswith("signorini") and x is not ours]
    measured = (f"{ratio:.2f} (signorini {float(ours['wall_median_s']):.2f} s; "
                + "".join(f"{c} {float(x['wall_median_s']):.2f} s, ratio {float(x['fenicsx_best_over_this']):.2f}; " for c, x in others)
                + ", ".join(f"{c} {float(x['wall_median_s']):.2f} s{'' if int(x['converged']) else ' (did not converge)'}" for c, x in fenicsx.items())
                + f"; {n}^3, {ours['unknowns']} unknowns); contact force {'agrees' if agrees else 'does not agree'}: largest relative difference {diff:.1e}"
                + ("" if n == 40 else f" (measured at {n}^3, not 40^3)"))
    return [row(target, measured, (ratio >= 5.0 and agrees) if n == 40 else None, cmd)]


SECTIONS = {"default": measure_default, "mg": measure_mg, "iterations": measure_iterations, "eps": measure_eps, "parallel": measure_parallel, "getfem": measure_getfem,
            "estimate": measure_estimate, "load_path": measure_load_path, "vi": measure_vi,
            "default3d": measure_default3d, "fenicsx": measure_fenicsx}


def rows_of_table(path):
    """The sections' rows of an earlier table (targets.csv), for a clone without the runs of its last invocation."""
    kept = {}
    if os.path.exists(path):
        with open(path, newline="") as fh:
            for r in csv.DictReader(fh):
                sec = kept.setdefault(r["section"], {"date": r["date"], "rows": []})
                sec["rows"].append({k: r[k] for k in ("target", "measured", "met", "command")})
    return kept


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--pairs", type=int, default=3, help="runs of each command in the side-by-side ratios (default 3)")
    ap.add_argument("--out", default=os.path.join(ROOT, "bench"))
    ap.add_argument("--small", action="store_true", help="small meshes (a test of the script, not of the targets)")
    ap.add_argument("--sections", default=",".join(SECTIONS),
                    help="the sections to measure (default all); the rows of the others are kept from the last invocation (bench/runs/targets/rows.json, "
                         "or the table's targets.csv where that is missing)")
    args = ap.parse_args()
    out = os.path.join(args.out, "runs", "targets")
    os.makedirs(out, exist_ok=True)
    saved = os.path.join(out, "rows.json")
    kept = json.load(open(saved)) if os.path.exists(saved) else rows_of_table(os.path.join(args.out, "targets.csv"))
    for name in args.sections.split(","):
        if name not in SECTIONS:
            sys.exit(f"unknown section '{name}' (known: {', '.join(SECTIONS)})")
        kept[name] = {"date": time.strftime("%Y-%m-%d %H:%M"), "rows": SECTIONS[name](out, 8 if args.small else 1, args.pairs)}
        with open(saved + ".part", "w") as fh:
            json.dump(kept, fh, indent=1)
        os.replace(saved + ".part", saved)
    rows = [dict(r, section=k, date=kept[k]["date"]) for k in SECTIONS if k in kept for r in kept[k]["rows"]]
    with open(os.path.join(args.out, "targets.csv"), "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    lines = ["# Performance targets", "", "`/usr/bin/python3 scripts/bench_targets.py` (make bench): one rank unless said, GAMG (`options/solvers/gamg.yaml`), "
             f"whole-process wall time and peak memory (`/usr/bin/time -v`); the default-run ratios are medians of {args.pairs} runs of each command, alternated.",
             "", "| target | measured | | command | measured on |", "|---|---|---|---|---|"]
    lines += [f"| {x['target']} | {x['measured']} | {x['met']} | `{x['command']}` | {x['date']} |" for x in rows]
    with open(os.path.join(args.out, "targets.md"), "w") as fh:
        fh.write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
