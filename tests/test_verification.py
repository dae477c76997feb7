"""Verification tests (make test): the error norms, the mms scene, -reference and the small convergence studies.

Every assertion checks numbers computed by the solver against a tolerance that can fail.
"""
import glob
import os
import subprocess

import numpy as np
import pytest

from harness import ENV, OUT, ROOT, load, run
from signorini.exact import gauss_legendre01, mms_from_run, p1_error_norms, read_p1_mesh

STUDY = os.path.join(ROOT, "scripts", "study.py")
NORMS = ["error_l2", "error_h1_semi", "error_h1", "error_energy", "error_pressure_l2", "error_pressure_weighted", "error_pressure_dual"]


def run_study(name):
    """Runs options/studies/<name>.yaml with --check; returns the combined output (asserts success)."""
    outdir = os.path.join(OUT, "studies", name)
    cmd = ["/usr/bin/python3", STUDY, os.path.join(ROOT, "options", "studies", name + ".yaml"), "--check", "--quiet", "--outdir", outdir]
    p = subprocess.run(cmd, cwd=ROOT, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=900)
    assert p.returncode == 0, f"study {name} failed its checks:\n{p.stdout[-4000:]}"
    for ext in (".csv", ".md"):
        assert os.path.isfile(os.path.join(outdir, name + ext)), f"{name}{ext} not written"
    return p.stdout


def test_error_norms_vanish_for_the_patch_test():
    """The patch test field is in the FE space: every norm must be round-off, on every cell type."""
    for mesh, args in {"tri": [], "quad": ["-dm_plex_simplex", 0], "tet": ["-dm_plex_dim", 3, "-dm_plex_box_faces", "3,3,3"]}.items():
        _, h5 = run(["-scene", "patch"] + args, f"norms_patch_{mesh}")
        attrs, _ = load(h5)
        for k in NORMS:
            assert 0.0 <= attrs[k] <= 1e-12, f"{mesh}: {k} = {attrs[k]:.3e}"
        assert attrs["penetration_l2"] == 0.0 and attrs["penetration_max"] == 0.0


def test_mms_norms_are_consistent():
    """h1^2 = l2^2 + h1_semi^2, the energy norm is at most sqrt(2 mu + d lambda) times the semi-norm,
    the weighted pressure norm is eps^1/2 times the L2 one, and the dual norm is at most the energy error (Galerkin)."""
    _, h5 = run(["-options_file", "options/mms.yaml", "-dm_plex_box_faces", "16,16"], "mms_norms")
    a, f = load(h5)
    assert a["converged"] == 1
    assert abs(a["error_h1"] ** 2 - a["error_l2"] ** 2 - a["error_h1_semi"] ** 2) <= 1e-12 * a["error_h1"] ** 2
    nu, E = a["poisson_ratio"], a["young_modulus"]
    mu, lam = E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))
    assert 0.0 < a["error_energy"] <= np.sqrt(2 * mu + 2 * lam) * a["error_h1_semi"] * 1.001
    assert abs(a["error_pressure_weighted"] - np.sqrt(a["eps"]) * a["error_pressure_l2"]) <= 1e-12
    assert 0.0 < a["error_pressure_dual"] <= a["error_energy"] * 1.01, (a["error_pressure_dual"], a["error_energy"])
    # the nodal error field of the HDF5 file agrees with the exact solution of the scene
    assert np.abs(f["error"] - (f["displacement"] - f["exact_displacement"])).max() <= 1e-14
    # the scene is a Signorini solution: u_n = -phi <= 0 on Gamma_C, so the exact field never penetrates
    on_c = f["contact_boundary"] > 0.5
    assert np.all(f["exact_displacement"][on_c, 1] >= -1e-15)


def test_mms_quadrature_does_not_pollute_the_error():
    """Refining the composite rule on the cells cut by x = a from 2 to 4 levels changes the norms by less than 1%."""
    vals = {}
    for r in (2, 4):
        _, h5 = run(["-options_file", "options/mms.yaml", "-mms_nu", 0.25, "-dm_plex_box_faces", "32,32", "-verify_quadrature_refine", r],
                    f"mms_quad_{r}")
        vals[r], _ = load(h5)
    for k in ("error_h1", "error_pressure_l2", "error_pressure_dual"):
        rel = abs(vals[2][k] - vals[4][k]) / vals[4][k]
        assert rel < 1e-2, f"{k}: {vals[2][k]:.6e} (refine 2) vs {vals[4][k]:.6e} (refine 4)"


def test_mms_3d_error_decreases():
    """3D tetrahedra, eps = h, 4^3, 8^3 and 12^3 cells: the level rates of the H1 error must be at least 0.85. README's
    study 2 (rates3d.yaml) reports 0.93 and 0.92 for these levels (measured here: the same); the bar is that minus
    0.07, and above the predicted 3/4 of Corollary 3.3, so a loss of the observed rate (not only of the bound) fails."""
    errs, hs = [], []
    for n in (4, 8, 12):
        _, h5 = run(["-options_file", "options/mms.yaml", "-dm_plex_dim", 3, "-dm_plex_box_faces", f"{n},{n},{n}"], f"mms_3d_{n}")
        a, _ = load(h5)
        assert a["converged"] == 1
        errs.append(a["error_h1"])
        hs.append(a["h"])
    rates = [np.log(errs[k] / errs[k + 1]) / np.log(hs[k] / hs[k + 1]) for k in range(2)]
    assert min(rates) >= 0.85, (rates, errs)


def test_penalty_eps_modulus_and_power():
    """eps as /run records it against the formulas of docs/options.md ("Options the project adds"), from /run's own h, E and nu:
    -penalty_eps_modulus pwave gives eps0 h / (lambda + 2 mu), -penalty_eps_power p gives eps0 h^p / E (p = 0.5, 2, 0),
    to 1e-12 relative (the same formula in double precision)."""
    base = ["-options_file", "options/square.yaml", "-contact_monitor", "false", "-dm_plex_box_faces", "8,8", "-young_modulus", 3.0,
            "-poisson_ratio", 0.45, "-penalty_eps0", 0.7]
    cases = {"pwave": (["-penalty_eps_modulus", "pwave"], 1.0, "pwave"), "power_half": (["-penalty_eps_power", 0.5], 0.5, "young"),
             "power_2": (["-penalty_eps_power", 2], 2.0, "young"), "power_0": (["-penalty_eps_power", 0], 0.0, "young"),
             "pwave_power_2": (["-penalty_eps_modulus", "pwave", "-penalty_eps_power", 2], 2.0, "pwave")}
    for name, (extra, power, modulus) in cases.items():
        _, h5 = run(base + extra, f"eps_rule_{name}")
        a, _ = load(h5)
        assert a["converged"] == 1 and a["penalty_eps_modulus"] == modulus
        E, nu = a["young_modulus"], a["poisson_ratio"]
        lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
        M = lam + 2 * mu if modulus == "pwave" else E
        expected = 0.7 * a["h"] ** power / M
        assert abs(a["eps"] / expected - 1) <= 1e-12, (name, a["eps"], expected)
        assert abs(a["eps_min"] / expected - 1) <= 1e-12 and abs(a["eps_max"] / expected - 1) <= 1e-12, (name, a["eps_min"], a["eps_max"])
    assert abs(a["h"] - np.sqrt(2) / 8) <= 1e-15  # the diameter of the 8x8 box's cells


def test_mms_norms_parallel_match_serial():
    """The norms computed on 2 ranks equal the serial ones to solver tolerance."""
    args = ["-options_file", "options/mms.yaml", "-dm_plex_box_faces", "16,16"]
    a1, _ = load(run(args, "mms_serial")[1])
    a2, _ = load(run(args, "mms_parallel", np_=2)[1])
    for k in NORMS + ["penetration_l2", "penetration_max"]:
        assert abs(a1[k] - a2[k]) <= 1e-9 * max(abs(a1[k]), 1e-14), f"{k}: {a1[k]:.12e} vs {a2[k]:.12e}"


def _gamma_c_load_norm(h5):
    """||b||_2, b_i = int_{Gamma_C} sigma_n(u_exact) phi_i ds over the vertices i of y = 0 (P1 hats of the uniform box),
    integrated in Python from the closed form (Gauss on each edge, the kink x = a a breakpoint)."""
    a, f = load(h5)
    m = mms_from_run(a)
    xs = np.sort(f["x"][np.abs(f["x"][:, 1]) < 1e-14, 0])
    t, w = gauss_legendre01(40)
    b = np.zeros(len(xs))
    for k in range(len(xs) - 1):
        x0, x1 = xs[k], xs[k + 1]
        br = sorted([x0, x1] + ([m.a] if x0 < m.a < x1 else []))
        for y0, y1 in zip(br[:-1], br[1:]):
            X, W = y0 + (y1 - y0) * t, (y1 - y0) * w
            s = m.normal_stress(X, a["young_modulus"], a["poisson_ratio"])
            b[k] += W @ (s * (x1 - X) / (x1 - x0))
            b[k + 1] += W @ (s * (X - x0) / (x1 - x0))
    return np.linalg.norm(b)


def test_dmsnes_check_runs_against_the_exact_solution():
    """PETSc's -dmsnes_check on the interpolant u_I of the exact solution, 8x8 and 16x16:
    - "L_2 Error" (||u - u_I||_0 with PETSc's quadrature) falls by 3.5 to 4.3 from 8x8 to 16x16: O(h^2), since u is
      C^1 with bounded second derivatives (s^(1/2) at the kink), so nothing limits the interpolation rate (measured 3.73,
      3.86 from 16 to 32, the pre-asymptotic approach to 4); and it is within 6% of the same norm computed in Python
      exactly (exact.p1_error_norms of u_I: PETSc's rule for P1 underestimates it by a steady 4.0 to 4.3%);
    - "Function appears to be linear": u_I never penetrates (u_I,n = -I_h phi <= 0), so the penalty term vanishes at u_I
      and at 0 and F(u_I) = J u_I + F(0);
    - "L_2 Residual" = ||F(u_I)||_2 is then, up to the bulk consistency error, the Gamma_C load int sigma_n(u) phi_i that
      no penalty pressure balances: within 5% of its norm computed in Python at 16x16 (measured 2.2%; 13% at 8x8, where
      the bulk term is larger), falling like h^(1/2) (about a/h nodes of size h each: ratio 1.3 to 1.6, measured 1.45)."""
    err, res = {}, {}
    for n in (8, 16):
        out, h5 = run(["-options_file", "options/mms.yaml", "-dm_plex_box_faces", f"{n},{n}", "-dmsnes_check"], f"mms_dmsnes_check_{n}")
        err[n] = float(out.split("L_2 Error:")[1].split()[0])
        res[n] = float(out.split("L_2 Residual:")[1].split()[0])
        assert "Function appears to be linear" in out, out[:2000]
        a, _ = load(h5)
        x, cells, _ = read_p1_mesh(h5)
        m = mms_from_run(a)
        ref = p1_error_norms(x, cells, m.u(x), m)["l2"]
        assert abs(err[n] / ref - 1) <= 0.06, (n, err[n], ref)
        if n == 16:
            load16 = _gamma_c_load_norm(h5)
            assert abs(res[n] / load16 - 1) <= 0.05, (res[n], load16)
    assert 3.5 <= err[8] / err[16] <= 4.3, err
    assert 1.3 <= res[8] / res[16] <= 1.6, res


def test_reference_on_nested_meshes_is_exact_for_the_patch_test():
    """A P1-exact field compared with its own solution on a twice refined mesh: zero difference, serial and parallel,
    triangles and tetrahedra (the coarse solution is interpolated to the fine mesh)."""
    for dim, faces in ((2, "4,4"), (3, "2,2,2")):
        _, ref = run(["-scene", "patch", "-dm_plex_dim", dim, "-dm_plex_box_faces", faces, "-dm_refine", 2], f"ref_patch_{dim}d_fine")
        for np_ in (1, 2):
            _, h5 = run(["-scene", "patch", "-dm_plex_dim", dim, "-dm_plex_box_faces", faces, "-reference", ref], f"ref_patch_{dim}d_{np_}", np_=np_)
            a, _ = load(h5)
            for k in NORMS:
                assert a["reference_" + k] <= 1e-12, f"{dim}D np {np_}: reference_{k} = {a['reference_' + k]:.3e}"


def test_reference_errors_of_square_converge():
    """square scene against a VI run refined 3 times: the H1 difference falls with h (rate > 0.7) and vanishes
    for the reference itself."""
    base = ["-options_file", "options/square.yaml", "-contact_monitor", "false", "-dm_plex_box_faces", "4,4"]
    _, ref = run(base + ["-contact_method", "vi", "-dm_refine", 3], "ref_square_fine")
    e = []
    for r in (0, 1, 2):
        _, h5 = run(base + ["-contact_method", "vi", "-dm_refine", r, "-reference", ref], f"ref_square_{r}", np_=2)
        a, _ = load(h5)
        e.append(a["reference_error_h1"])
    assert e[0] / e[1] > 2 ** 0.7 and e[1] / e[2] > 2 ** 0.7, e
    _, h5 = run(base + ["-contact_method", "vi", "-dm_refine", 3, "-reference", ref], "ref_square_self")
    a, _ = load(h5)
    assert a["reference_error_h1"] == 0.0 and a["reference_error_pressure_l2"] == 0.0


def test_reference_mismatch_is_refused():
    _, ref = run(["-scene", "patch", "-dm_plex_box_faces", "4,4", "-dm_refine", 1], "ref_mismatch_fine")
    cases = {
        "scene": (["-scene", "square", "-dm_plex_box_faces", "4,4"], "is a run of scene patch, this is scene square"),
        "cells": (["-scene", "patch", "-dm_plex_box_faces", "3,3"], "which is not this mesh (18 cells) uniformly refined"),
        "degree": (["-scene", "patch", "-dm_plex_box_faces", "4,4", "-displacement_petscspace_degree", 2], "-reference needs degree 1"),
        "missing": (["-scene", "patch", "-reference", "tests/out/none.h5"], "Reference file 'tests/out/none.h5' (-reference) does not exist"),
    }
    for name, (args, message) in cases.items():
        if "-reference" not in args:
            args = args + ["-reference", ref]
        out, h5 = run(args, f"ref_bad_{name}", expect_rc=None)
        assert message in out, f"{name}: '{message}' not in\n{out[-1500:]}"
        assert "  SNES " not in out, f"{name}: refused only after the solve"
        assert not glob.glob(h5 + "*"), f"{name}: output left behind"
    # a mismatch found only on the refined mesh, after the solve: the solve is not lost (issue 29): written without the
    # comparison, /run says which diagnostic failed and why, exit status 4
    out, h5 = run(["-scene", "patch", "-dm_plex_box_faces", "4,4", "-dm_plex_box_upper", "1,2", "-reference", ref], "ref_bad_vertices", expect_rc=4)
    a, _ = load(h5)
    assert a["converged"] == 1 and "-reference comparison: " in a["diagnostics_failed"] and "a vertex of this mesh refined is not one" in a["diagnostics_failed"]
    assert "reference_error_h1" not in a and "WARNING: written without a diagnostic that failed" in out


def test_mms_bad_parameters_are_refused():
    for args, message in ((["-mms_nu", 0], "-mms_nu must lie in (0, 1]"), (["-mms_nu", 1.5], "-mms_nu must lie in (0, 1]"),
                          (["-mms_a", 1], "-mms_a must lie in (0, 1)"), (["-mms_amplitude_B", -1], "must be positive")):
        out, h5 = run(["-scene", "mms"] + args, "mms_bad", expect_rc=None)
        assert message in out, f"'{message}' not in\n{out[-1500:]}"
        assert not os.path.exists(h5)


@pytest.mark.slow
def test_study_rates_2d_reach_the_predictions():
    """Small version of study 1 (make rates): eps = h, nu = 0.25 and 0.5, 8x8 to 64x64; study.py --check asserts
    that the fitted H1 and pressure rates reach the predicted exponents within 0.1."""
    out = run_study("quick_rates2d")
    assert out.count("PASS") == 2, out


@pytest.mark.slow
def test_study_eps_refinement_is_monotone_until_the_floor():
    """Small version of study 4: on a 32x32 mesh the error against the exact solution falls with eps until the
    discretization floor, and the distance to the SNESVI solution falls like eps (rate >= 0.9)."""
    out = run_study("quick_epsrefine2d")
    assert out.count("PASS") == 3, out


def write_graded_unit_square(path):
    """The unit square with Gmsh's face sets 1 (y = 0), 2 (x = 1), 3 (y = 1), 4 (x = 0), as the built-in box numbers
    them, and cells of size 0.015 + 0.1 y: finer toward Gamma_C, so that eps is local."""
    import gmsh
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add("graded_square")
    p = [gmsh.model.geo.addPoint(x, y, 0) for x, y in ((0, 0), (1, 0), (1, 1), (0, 1))]
    lines = [gmsh.model.geo.addLine(p[i], p[(i + 1) % 4]) for i in range(4)]
    surface = gmsh.model.geo.addPlaneSurface([gmsh.model.geo.addCurveLoop(lines)])
    gmsh.model.geo.synchronize()
    for tag, line in zip((1, 2, 3, 4), lines):
        gmsh.model.addPhysicalGroup(1, [line], tag)
    gmsh.model.addPhysicalGroup(2, [surface], 10)
    field = gmsh.model.mesh.field.add("MathEval")
    gmsh.model.mesh.field.setString(field, "F", "0.015 + 0.1*y")
    gmsh.model.mesh.field.setAsBackgroundMesh(field)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    gmsh.model.mesh.generate(2)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.write(path)
    gmsh.finalize()


def test_penalty_pressure_error_takes_the_local_eps(outdir):
    """The error norms evaluate the penalty's pressure by its law, p = [u_n - g]_+ / eps, with the eps of each contact
    face, as the solve does: on a mesh graded toward Gamma_C the local eps (0.015 to 0.020, against 0.128 for the largest
    cell) gives smaller errors than one eps for the whole mesh, the pressure's too. The law with the largest cell's eps
    reported a pressure error 31 times too large (1.19e-1 against 3.79e-3) and 5 times that of the uniform eps."""
    mesh = os.path.join(outdir, "graded_square.msh")
    write_graded_unit_square(mesh)
    res = {}
    for local in (1, 0):
        _, h5 = run(["-options_file", "options/mms.yaml", "-dm_plex_filename", mesh, "-penalty_eps_local", local], f"local_eps_norms_{local}")
        res[local] = load(h5)[0]
    loc, uni = res[1], res[0]
    assert loc["converged"] == 1 and uni["converged"] == 1
    assert loc["eps_max"] < 0.25 * loc["eps"], (loc["eps_max"], loc["eps"])  # eps is local: the contact cells are small
    for key in ("error_h1", "error_pressure_l2", "error_pressure_dual"):
        assert loc[key] < uni[key], (key, loc[key], uni[key])
    assert loc["error_pressure_l2"] < 0.5 * uni["error_pressure_l2"], (loc["error_pressure_l2"], uni["error_pressure_l2"])


def test_dual_norm_solver_options():
    """The dual-norm solve takes its own options (-dual_ksp_type, -dual_pc_type, read after the solve: they were refused
    as never used before it, found by make estimates): CG with GAMG gives MUMPS's dual norm to the solve's tolerance."""
    base = ["-scene", "mms", "-dm_plex_box_faces", "16,16"]
    _, direct = run(base, "dual_direct")
    _, cg = run(base + ["-dual_ksp_type", "cg", "-dual_pc_type", "gamg", "-dual_ksp_rtol", "1e-12"], "dual_cg")
    a, b = load(direct)[0], load(cg)[0]
    assert abs(a["error_pressure_dual"] - b["error_pressure_dual"]) <= 1e-8 * a["error_pressure_dual"]
