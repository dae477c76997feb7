"""Failures are loud (make test): a failed solve is flagged, and each bad input is rejected with its message and no
output left behind."""
import glob
import os
import subprocess

import pytest

from harness import BIN, ENV, OUT, ROOT, load, run


def test_failed_solve_is_flagged():
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
    "coarse_levels_range": (["-contact_coarse_levels", -2], "-contact_coarse_levels must lie in [-1, 8]"),
    "ew_guard": (["-contact_ew_guard", 2], "-contact_ew_guard must lie in [0, 1]"),
    "coarse_rtol": (["-contact_coarse_rtol", 0], "-contact_coarse_rtol must lie in (0, 1)"),
    "coarse_levels_not_divisible": (["-dm_plex_box_faces", "12,20", "-contact_coarse_levels", 3], "-dm_plex_box_faces 12 is not divisible by 2^3"),
    "coarse_levels_quads": (["-dm_plex_simplex", 0, "-contact_coarse_levels", 1], "-contact_coarse_levels 1 needs the 2D simplex box"),
    "coarse_levels_p2": (["-displacement_petscspace_degree", 2, "-contact_coarse_levels", 1], "-contact_coarse_levels 1 needs P1 displacements"),
    "mg_without_nested_meshes": (["-pc_type", "mg", "-contact_coarse_levels", 0], "-pc_type mg takes its levels from nested meshes, and this mesh has none"),
    "mg_p2": (["-pc_type", "mg", "-displacement_petscspace_degree", 2], "-pc_type mg takes its levels from nested meshes, and this mesh has none"),
    "vi_with_mg": (["-contact_method", "vi", "-pc_type", "mg"], "-pc_type mg cannot follow"),
    "mg_levels": (["-dm_plex_box_faces", "64,64", "-pc_type", "mg", "-pc_mg_levels", 3], "-pc_mg_levels: the levels of -pc_type mg are the nested meshes"),
    "bad_output_dir": (["-output", "/nonexistent_dir/x.h5"], "Output directory '/nonexistent_dir' (-output /nonexistent_dir/x.h5) does not exist"),
}


@pytest.mark.parametrize("name", BAD_INPUTS)
def test_bad_input(name, no_contact_mesh):
    """no_contact_mesh: tests/out/no_contact.msh, written once for the session."""
    args, message = BAD_INPUTS[name]
    out = os.path.join(OUT, f"bad_{name}.h5")
    cmd = ["mpiexec", "-n", "1", BIN, "-output", out] + [str(a) for a in args]
    p = subprocess.run(cmd, cwd=ROOT, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=120)
    assert p.returncode != 0, "bad input accepted"
    assert message in p.stdout, f"message '{message}' not in:\n{p.stdout[-2000:]}"
    assert not glob.glob(out + "*") and not glob.glob(out[:-3] + ".xdmf*"), "output left behind"
