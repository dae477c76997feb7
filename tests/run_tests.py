#!/usr/bin/python3
"""Test suite of bin/signorini (make test). Ends with a line 'N passed, N failed'; exits 1 on any failure.

Every assertion checks a number computed by the solver (read back from its HDF5 output or its log)
against a tolerance that can fail.
"""
import glob
import math
import os
import re
import shutil
import subprocess
import sys
import time
import traceback
import xml.etree.ElementTree as ET

import h5py
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from harness import BIN, ENV, OUT, ROOT, TESTS, load, read_runs, run, sorted_by_position, test, write_gmsh_square  # noqa: E402

# ---------------------------------------------------------------- discretization
PATCH_MESHES = {
    "tri": [],
    "quad": ["-dm_plex_simplex", 0],
    "tet": ["-dm_plex_dim", 3, "-dm_plex_box_faces", "3,3,3"],
    "hex": ["-dm_plex_dim", 3, "-dm_plex_simplex", 0, "-dm_plex_box_faces", "3,3,3"],
    "p2": ["-displacement_petscspace_degree", 2, "-dm_plex_box_faces", "4,4"],
}
for _mesh, _args in PATCH_MESHES.items():
    for _method in ("none", "penalty"):
        def _patch(mesh=_mesh, args=_args, method=_method):
            _, h5 = run(["-scene", "patch", "-contact_method", method] + args, f"patch_{mesh}_{method}")
            attrs, f = load(h5)
            assert attrs["converged"] == 1
            err, scale = np.abs(f["error"]).max(), np.abs(f["exact_displacement"]).max()
            assert err <= 1e-11 * scale, f"patch test error {err:.3e} for a field of size {scale:.3e}"
            assert attrs["active_vertices"] == 0 and attrs["max_penetration"] <= 0.0
        _patch.__name__ = f"patch_test_{_mesh}_{_method}"
        test(_patch)


def jacobian_ratios(log):
    return [float(m) for m in re.findall(r"\|\|J - Jfd\|\|_F/\|\|J\|\|_F = ([0-9.eE+-]+)", log)]


for _dim, _faces in ((2, "4,4"), (3, "2,2,2")):
    for _quad in ("gauss", "nodal"):
        def _jac(dim=_dim, faces=_faces, quad=_quad):
            log, _ = run(["-dm_plex_dim", dim, "-dm_plex_box_faces", faces, "-penalty_quadrature", quad, "-snes_test_jacobian"], f"jacobian_{dim}d_{quad}")
            ratios = jacobian_ratios(log)
            assert len(ratios) >= 2, "no Jacobian test output"
            assert max(ratios) < 1e-6, f"||J - Jfd||/||J|| = {max(ratios):.3e}"
        _jac.__name__ = f"penalty_jacobian_fd_{_dim}d_{_quad}"
        test(_jac)


# ---------------------------------------------------------------- the square scene
def check_square(h5, max_newton=8):
    attrs, f = load(h5)
    assert attrs["converged"] == 1, attrs["snes_reason"]
    assert 1 <= attrs["newton_its"] <= max_newton, f"{attrs['newton_its']} Newton steps"
    on = f["contact_boundary"] > 0.5
    x1, p = f["x"][on, 0], f["contact_pressure"][on]
    assert p[x1 < 0.4].min() > 0.0, "the body must press the foundation where x_1 < x0"
    assert np.all(p[x1 > 0.7] == 0.0), "the body must lift off where x_1 > x0"
    return attrs, f


@test
def square_2d_converges():
    _, h5 = run(["-dm_plex_box_faces", "32,32"], "square_2d")
    attrs, _ = check_square(h5)
    assert attrs["contact_force"] > 0.0 and attrs["active_vertices"] > 0


@test
def square_3d_converges():
    _, h5 = run(["-dm_plex_dim", 3, "-dm_plex_box_faces", "6,6,6"], "square_3d")
    attrs, _ = check_square(h5)
    assert attrs["dim"] == 3 and attrs["contact_force"] > 0.0


@test
def square_quads_and_p2_converge():
    for name, args in (("quad", ["-dm_plex_simplex", 0, "-dm_plex_box_faces", "16,16"]), ("p2", ["-displacement_petscspace_degree", 2, "-dm_plex_box_faces", "8,8"])):
        _, h5 = run(args, f"square_{name}")
        check_square(h5)


@test
def contact_monitor_reports_active_set():
    log, h5 = run(["-dm_plex_box_faces", "16,16", "-contact_monitor"], "monitor")
    lines = re.findall(r"^\s*(\d+) contact: \|F\| (\S+)\s+active vertices\s+(\d+)\s+entered\s+(\d+)\s+left\s+(\d+)", log, re.M)
    attrs, _ = load(h5)
    assert len(lines) == attrs["newton_its"] + 1
    assert int(lines[-1][2]) == attrs["active_vertices"]
    active = 0
    for _, _, a, e, l in lines:  # the counts are consistent from step to step
        active += int(e) - int(l)
        assert active == int(a)


@test
def nodal_penalty_tends_to_vi_linearly_in_eps():
    args = ["-dm_plex_box_faces", "16,16"]
    _, h5 = run(args + ["-contact_method", "vi"], "vi_ref")
    _, fvi = load(h5)
    uvi = sorted_by_position(fvi, "displacement")
    eps_list, diffs = [1e-3, 1e-4, 1e-5, 1e-6], []
    for eps in eps_list:
        _, h5 = run(args + ["-penalty_quadrature", "nodal", "-penalty_eps", eps], f"nodal_eps{eps:g}")
        attrs, f = load(h5)
        assert attrs["converged"] == 1
        diffs.append(np.abs(sorted_by_position(f, "displacement") - uvi).max())
    assert all(d2 < d1 for d1, d2 in zip(diffs, diffs[1:])), f"not monotone: {diffs}"
    slope = np.polyfit(np.log(eps_list), np.log(diffs), 1)[0]
    assert 0.9 <= slope <= 1.1, f"|u_eps - u_vi| ~ eps^{slope:.3f}, expected eps^1 ({diffs})"


@test
def vi_constraint_and_complementarity():
    _, h5 = run(["-dm_plex_box_faces", "24,24", "-contact_method", "vi"], "vi_compl")
    attrs, f = load(h5)
    assert attrs["converged"] == 1 and attrs["max_penetration"] <= 1e-12
    on = f["contact_boundary"] > 0.5
    gap, p = f["normal_gap"][on], f["contact_pressure"][on]
    pmax = p.max()
    assert pmax > 0.0
    assert gap.min() >= -1e-12, f"u_n > g by {-gap.min():.3e}"
    assert p.min() >= -1e-8 * pmax, f"tensile contact pressure {p.min():.3e}"
    assert np.abs(p * gap).max() <= 1e-10 * pmax, f"complementarity violated: {np.abs(p * gap).max():.3e}"
    assert attrs["active_vertices"] == np.sum(gap <= 1e-10 * attrs["displacement_scale"])


@test
def penalty_approaches_vi_in_force_and_energy():
    args = ["-dm_plex_box_faces", "16,16"]
    vi, _ = load(run(args + ["-contact_method", "vi"], "vi_force")[1])
    pen, _ = load(run(args + ["-penalty_quadrature", "nodal", "-penalty_eps", 1e-7], "nodal_force")[1])
    assert abs(pen["contact_force"] - vi["contact_force"]) <= 1e-5 * vi["contact_force"]
    assert abs(pen["energy"] - vi["energy"]) <= 1e-5 * abs(vi["energy"])
    none, _ = load(run(args + ["-contact_method", "none"], "none_energy")[1])
    assert none["energy"] < pen["energy"] < vi["energy"] + 1e-12, "the constraint must raise the energy"


# ---------------------------------------------------------------- parallel = serial
for _name, _args in (("penalty_gauss_2d", ["-dm_plex_box_faces", "24,24"]),
                     ("penalty_nodal_2d", ["-dm_plex_box_faces", "24,24", "-penalty_quadrature", "nodal"]),
                     ("vi_2d", ["-dm_plex_box_faces", "24,24", "-contact_method", "vi"]),
                     ("penalty_3d", ["-dm_plex_dim", 3, "-dm_plex_box_faces", "5,5,5"])):
    def _par(name=_name, args=_args):
        a1, f1 = load(run(args, f"serial_{name}")[1])
        a2, f2 = load(run(args, f"parallel_{name}", np_=2)[1])
        assert a2["nprocs"] == 2 and a1["converged"] == a2["converged"] == 1
        assert a1["n_dofs"] == a2["n_dofs"] and a1["n_vertices"] == a2["n_vertices"] and a1["n_cells"] == a2["n_cells"]
        for key in ("displacement", "contact_pressure", "normal_gap", "contact_boundary"):
            v1, v2 = sorted_by_position(f1, key), sorted_by_position(f2, key)
            scale = max(np.abs(v1).max(), 1e-300)
            assert np.abs(v1 - v2).max() <= 1e-9 * scale, f"{key} differs by {np.abs(v1 - v2).max():.3e}"
        for key in ("contact_force", "energy", "max_penetration"):
            assert abs(a1[key] - a2[key]) <= 1e-9 * max(abs(a1[key]), 1e-12), f"{key}: {a1[key]} vs {a2[key]}"
        assert a1["active_vertices"] == a2["active_vertices"]
    _par.__name__ = f"mpiexec_n2_equals_serial_{_name}"
    test(_par)


# ---------------------------------------------------------------- output
@test
def hdf5_read_back_by_python_reader():
    _, h5 = run(["-dm_plex_box_faces", "8,8"], "reader")
    with h5py.File(h5, "r") as f:
        raw = dict(f["run"].attrs)
        nv = f["geometry/vertices"].shape[0]
        assert f["vertex_fields/displacement"].shape == (nv, 2)
    row = read_runs.read_run(h5)
    for key, value in raw.items():
        value = value.decode() if isinstance(value, bytes) else value
        assert row[key] == value, key
    required = ("scene dim method degree nprocs n_cells n_vertices n_dofs h eps young_modulus poisson_ratio snes_reason converged newton_its "
                "ksp_its time_setup time_solve time_total active_vertices max_penetration contact_force energy").split()
    missing = [k for k in required if k not in row]
    assert not missing, f"missing /run attributes: {missing}"
    assert row["n_vertices"] == nv == 81 and row["n_cells"] == 128 and row["n_dofs"] == 2 * (81 - 9)
    assert abs(row["h"] - math.sqrt(2) / 8) < 1e-14 and abs(row["eps"] - row["h"]) < 1e-14
    csv_out = os.path.join(OUT, "runs.csv")
    _, h5b = run(["-dm_plex_box_faces", "8,8", "-contact_method", "vi"], "reader_vi")
    assert read_runs.main([h5, h5b, "--format", "csv", "-o", csv_out]) == 0
    lines = open(csv_out).read().strip().splitlines()
    assert len(lines) == 3 and "contact_force" in lines[0]


@test
def xdmf_points_at_existing_datasets():
    _, h5 = run(["-dm_plex_box_faces", "8,8"], "xdmf")
    xdmf = h5[:-3] + ".xdmf"
    root = ET.parse(xdmf).getroot()
    with h5py.File(h5, "r") as f:
        items = root.iter("DataItem")
        n = 0
        for item in items:
            fname, path = item.text.strip().split(":")
            assert fname == os.path.basename(h5)
            dims = tuple(int(d) for d in item.get("Dimensions").split())
            assert f[path].shape == dims, f"{path}: {f[path].shape} vs {dims}"
            n += 1
        assert n == 6


@test
def plot_script_writes_png():
    _, h5 = run(["-dm_plex_box_faces", "8,8"], "plot")
    png = os.path.join(OUT, "plot_contact.png")
    subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "plot_contact.py"), h5, "-o", png], check=True, env=ENV,
                   stdout=subprocess.DEVNULL)
    with open(png, "rb") as fp:
        assert fp.read(8) == b"\x89PNG\r\n\x1a\n"


@test
def yaml_options_file():
    log, h5 = run(["-options_file", "options/square.yaml", "-dm_plex_box_faces", "8,8", "-options_file", "options/solvers/hypre.yaml"], "yaml")
    attrs, _ = load(h5)
    assert attrs["converged"] == 1 and attrs["scene"] == "square" and attrs["n_cells"] == 128 and attrs["ksp_its"] > attrs["newton_its"]


@test
def gmsh_mesh_matches_builtin_box():
    msh = os.path.join(OUT, "square8.msh")
    write_gmsh_square(msh, 8)
    a_box, _ = load(run(["-dm_plex_box_faces", "8,8"], "box8")[1])
    a_msh, _ = load(run(["-dm_plex_filename", msh], "msh8")[1])
    assert a_msh["converged"] == 1 and a_msh["n_cells"] == a_box["n_cells"]
    for key in ("contact_force", "energy", "max_penetration"):
        assert abs(a_msh[key] - a_box[key]) <= 1e-10 * abs(a_box[key]), f"{key}: {a_msh[key]} vs {a_box[key]}"


# ---------------------------------------------------------------- failures are loud
@test
def failed_solve_is_flagged():
    log, h5 = run(["-dm_plex_box_faces", "16,16", "-snes_max_it", 1], "failed", expect_rc=3)
    attrs, _ = load(h5)
    assert attrs["converged"] == 0 and attrs["snes_reason"] == "DIVERGED_MAX_IT" and attrs["newton_its"] == 1
    assert attrs["residual_norm"] > 1e-8
    assert "the nonlinear solve failed: DIVERGED_MAX_IT after 1 Newton steps, residual" in log


BAD_INPUTS = {
    "unknown_scene": (["-scene", "nosuch"], "Unknown scene 'nosuch'"),
    "eps_zero": (["-penalty_eps", 0], "-penalty_eps must be positive"),
    "eps_negative": (["-penalty_eps", -1e-3], "-penalty_eps must be positive"),
    "eps0_zero": (["-penalty_eps0", 0], "-penalty_eps0 must be positive"),
    "eps_power": (["-penalty_eps_power", 5], "-penalty_eps_power must lie in [0, 4]"),
    "poisson_half": (["-poisson_ratio", 0.5], "-poisson_ratio must lie in (-1, 0.5)"),
    "poisson_high": (["-poisson_ratio", 0.7], "-poisson_ratio must lie in (-1, 0.5)"),
    "young_zero": (["-young_modulus", 0], "-young_modulus must be positive"),
    "missing_mesh": (["-dm_plex_filename", "tests/out/missing.msh"], "Mesh file 'tests/out/missing.msh' (-dm_plex_filename) does not exist"),
    "no_contact_boundary": (["-dm_plex_filename", "tests/out/no_contact.msh"], "The mesh has no contact boundary"),
    "option_typo": (["-penalty_esp", 1], "never used (misspelled? see -help): -penalty_esp"),
    "unknown_method": (["-contact_method", "bogus"], "Unknown option bogus for -contact_method"),
    "vi_with_newtonls": (["-contact_method", "vi", "-snes_type", "newtonls"], "does not fit -contact_method vi"),
    "vi_with_gamg": (["-contact_method", "vi", "-pc_type", "gamg"], "-pc_type gamg cannot follow"),
    "missing_options_file": (["-options_file", "tests/out/missing.yaml"], "Unable to open YAML option file"),
    "bad_output_dir": (["-output", "/nonexistent_dir/x.h5"], "Output directory '/nonexistent_dir' (-output /nonexistent_dir/x.h5) does not exist"),
}
for _name, (_args, _message) in BAD_INPUTS.items():
    def _bad(name=_name, args=_args, message=_message):
        write_gmsh_square(os.path.join(OUT, "no_contact.msh"), 4, with_contact=False)
        out = os.path.join(OUT, f"bad_{name}.h5")
        cmd = ["mpiexec", "-n", "1", BIN, "-output", out] + [str(a) for a in args]
        p = subprocess.run(cmd, cwd=ROOT, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=120)
        assert p.returncode != 0, "bad input accepted"
        assert message in p.stdout, f"message '{message}' not in:\n{p.stdout[-2000:]}"
        assert not glob.glob(out + "*") and not glob.glob(out[:-3] + ".xdmf*"), "output left behind"
    _bad.__name__ = f"bad_input_{_name}"
    test(_bad)


import performance  # noqa: E402,F401  (registers the performance tests)
import assembly  # noqa: E402,F401  (registers the assembly tests)
import robustness  # noqa: E402,F401  (registers the robustness tests)
import partition  # noqa: E402,F401  (registers the partitioning tests)
import verification  # noqa: E402,F401  (registers the verification tests)
import hostile  # noqa: E402,F401  (registers the hostile-input catalogue)
import units  # noqa: E402,F401  (registers the unit-invariance tests)
import safety  # noqa: E402,F401  (registers the signal and concurrency tests of the output)
import sanitize  # noqa: E402,F401  (registers the sanitizer runs)
import test_regression  # noqa: E402,F401  (registers the test of scripts/regression.py)


def main():
    shutil.rmtree(OUT, ignore_errors=True)
    os.makedirs(OUT)
    selected = [t for t in TESTS if len(sys.argv) < 2 or any(s in t.__name__ for s in sys.argv[1:])]
    passed = failed = 0
    start = time.time()
    for t in selected:
        t0 = time.time()
        try:
            t()
            passed += 1
            print(f"PASS {t.__name__} ({time.time() - t0:.1f} s)", flush=True)
        except Exception as e:  # noqa: BLE001 - report every failure and go on
            failed += 1
            print(f"FAIL {t.__name__} ({time.time() - t0:.1f} s): {e}", flush=True)
            traceback.print_exc(limit=1)
    print(f"total time {time.time() - start:.1f} s")
    print(f"{passed} passed, {failed} failed")
    return 1 if failed or not passed else 0


if __name__ == "__main__":
    sys.exit(main())
