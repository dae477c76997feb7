"""Memory errors (make test): a few runs covering every module under AddressSanitizer and UndefinedBehaviorSanitizer
(`make asan`, bin/signorini-asan), with PETSc's own allocation tracking (-malloc_debug -malloc_dump) for leaks of
PETSc-allocated memory. Open MPI's and HDF5's own allocations at exit are not ours, so ASan's leak checker is off
(ASAN_OPTIONS=detect_leaks=0) and -malloc_dump stands in for it.
"""
import os
import re
import subprocess

import pytest

from harness import ENV, OUT, ROOT
from hostile_meshes import write_named_square

ASAN_BIN = os.path.join(ROOT, "bin", "signorini-asan")
CASES = {
    "square_penalty": (1, ["-dm_plex_box_faces", "8,8"], 0),
    "vi_condition_np2": (2, ["-dm_plex_box_faces", "8,8", "-contact_method", "vi", "-contact_condition_estimate"], 0),
    "nodal_3d_grid_sequence": (1, ["-dm_plex_dim", 3, "-dm_plex_box_faces", "2,2,2", "-penalty_quadrature", "nodal", "-contact_grid_sequence", 1], 0),
    "mms_sweep_metis_np2": (2, ["-scene", "mms", "-dm_plex_box_faces", "8,8", "-penalty_eps0_sweep", "1,0.01", "-partitioner", "metis"], 0),
    "quads_p2_fe_assembly": (1, ["-dm_plex_simplex", 0, "-dm_plex_box_faces", "4,4", "-displacement_petscspace_degree", 2], 0),
    "reference_vi": (1, ["-dm_plex_box_faces", "8,8", "-contact_method", "vi", "-reference", os.path.relpath(os.path.join(OUT, "asan", "square_penalty.h5"), ROOT)], 0),
    # GAMG with its coarse-level updates, the eps sweep with its step guess, Eisenstat-Walker's forcing terms
    "gamg_update_sweep_np2": (2, ["-dm_plex_box_faces", "16,16", "-options_file", "options/solvers/gamg.yaml", "-penalty_eps0_sweep", "1,0.1,0.01"], 0),
    "geometric_multigrid": (1, ["-dm_plex_box_faces", "16,16", "-contact_coarse_levels", 2, "-options_file", "options/solvers/mg.yaml"], 0),
    # the general scene on a Gmsh mesh with named faces: every boundary family, a body force, a curved obstacle
    "gmsh_names_cylinder": (1, ["-scene", "general", "-dm_plex_filename", os.path.relpath(os.path.join(OUT, "asan", "named_square.msh"), ROOT), "-contact_faces", "bottom",
                                "-bc_clamp", "top", "-bc_clamp_top_translate", "0,-0.01", "-bc_slip", "left", "-bc_slip_left_components", 0,
                                "-bc_traction", "right", "-bc_traction_right", "0.01,0", "-body_force", "0,-0.01", "-obstacle", "cylinder",
                                "-obstacle_center", "0.5,-2", "-obstacle_radius", 2], 0),
    "sphere_3d_pressure_np2": (2, ["-scene", "general", "-dm_plex_dim", 3, "-dm_plex_box_faces", "2,2,2", "-contact_faces", 1, "-bc_clamp", 2,
                                   "-bc_clamp_2_translate", "0,0,-0.01", "-bc_pressure", 3, "-bc_pressure_3", 0.001, "-obstacle", "sphere",
                                   "-obstacle_center", "0.5,0.5,-2", "-obstacle_radius", 2], 0),
    # the recovered peak's fit on tetrahedra (30 nodes in contact: its 20 nearest, gathered from both ranks)
    "sphere_3d_peak_fit_np2": (2, ["-scene", "general", "-dm_plex_dim", 3, "-dm_plex_box_faces", "12,12,3", "-contact_faces", 1, "-bc_clamp", 2,
                                   "-bc_clamp_2_translate", "0,0,-0.01", "-obstacle", "sphere", "-obstacle_center", "0.5,0.5,-2", "-obstacle_radius", 2], 0),
    # a preconditioner breakdown at every multigrid build, recovered by a direct solve (src/linear/pc_recovery.c)
    "pc_recovery": (1, ["-dm_plex_box_faces", "16,16", "-options_file", "options/solvers/gamg.yaml", "-mg_levels_ksp_chebyshev_esteig", "0,0.05,0,0.3"], 0),
    # a Gmsh file read on rank 0 (the other rank checks a mesh without cells), a local eps on PETSc's boundary integration,
    # the closed form checked against it, the SBAIJ copy of K for the penalty Jacobian with its Cholesky factorization
    "graded_gmsh_fe_check_np2": (2, ["-options_file", "options/cylinder.yaml", "-dm_plex_filename", "options/meshes/disk_graded.msh",
                                     "-assembly", "fe", "-assembly_check", "-contact_condition_estimate",
                                     "-output", os.path.relpath(os.path.join(OUT, "asan", "graded_gmsh_fe_check_np2.h5"), ROOT)], 0),  # after the file's own output: its folder may not exist
    "sbaij_nodal_continuation": (1, ["-dm_plex_box_faces", "8,8", "-dm_mat_type", "sbaij", "-penalty_quadrature", "nodal", "-penalty_eps0", 1e-4], 0),
    "bars_mms_np2": (2, ["-scene", "mms", "-dm_plex_box_faces", "16,16", "-bars"], 0),
    "bars_3d_grid_sequence_nodal": (1, ["-dm_plex_dim", 3, "-dm_plex_box_faces", "2,2,2", "-penalty_quadrature", "nodal", "-contact_grid_sequence", 2,
                                        "-bars"], 0),
    # the 3D box remeshed by Gmsh on rank 0 (its sizes gathered, the old cells' tree carrying the solution to the new mesh)
    "remesh_3d_slip_np2": (2, ["-dm_plex_dim", 3, "-dm_plex_box_faces", "2,2,2", "-adapt_cycles", 2, "-bc_slip", 4, "-bc_slip_4_components", 0], 0),
    "failed_solve": (1, ["-dm_plex_box_faces", "8,8", "-snes_max_it", 1], 3),
    "bad_input": (1, ["-dm_plex_box_faces", "8,8", "-young_modulus", "nan"], None),
}


@pytest.mark.slow
def test_sanitizers_report_nothing():
    p = subprocess.run(["make", "--no-print-directory", "-j2", "asan"], cwd=ROOT, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    assert p.returncode == 0, p.stdout[-3000:]
    env = dict(ENV, ASAN_OPTIONS="detect_leaks=0", UBSAN_OPTIONS="print_stacktrace=1")
    os.makedirs(os.path.join(OUT, "asan"), exist_ok=True)
    write_named_square(os.path.join(OUT, "asan", "named_square.msh"))
    for name, (np_, args, rc) in CASES.items():
        cmd = ["mpiexec", "-n", str(np_), ASAN_BIN, "-malloc_debug", "-malloc_dump", "-output", os.path.join(OUT, "asan", name + ".h5")]
        p = subprocess.run(cmd + [str(a) for a in args], cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=300)
        if rc is None:
            assert p.returncode != 0, f"{name}: bad input accepted"
        else:
            assert p.returncode == rc, f"{name}: exit status {p.returncode}, expected {rc}\n{p.stdout[-3000:]}"
        assert "AddressSanitizer" not in p.stdout and "runtime error:" not in p.stdout, f"{name}:\n{p.stdout[-5000:]}"
        leaks = re.findall(r"^\[\s*\d+\]\s*\d+ bytes .*$", p.stdout, re.M)
        assert not leaks, f"{name}: PETSc memory not freed:\n" + "\n".join(leaks[:20])
