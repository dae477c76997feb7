"""Assembly tests (make test): the P1 path of the bulk matrix K and of the penalty term's Gauss rule (-assembly p1)
against PETSc's FE assembly and boundary integration (-assembly fe).

-assembly_check assembles K both ways and prints the relative Frobenius distance with the type, size, block size and
number of nonzeros (used and allocated) of both; with the Gauss rule it also prints the penalty residual, Jacobian and
energy at the solution both ways. Every assertion checks those numbers or the solver's output.
"""
import glob
import os
import re

import numpy as np
import pytest

from harness import OUT, ROOT, load, run, solve, sorted_by_position

CHECK = re.compile(r"assembly check: \|\|K_p1 - K_fe\|\|_F/\|\|K_fe\|\|_F = (\S+); size (\d+)x(\d+) \(p1\) (\d+)x(\d+) \(fe\); "
                   r"type (\S+) \(p1\) (\S+) \(fe\); block size (\d+) \(p1\) (\d+) \(fe\); nonzeros (\d+) \(p1\) (\d+) \(fe\); "
                   r"allocated (\d+) \(p1\) (\d+) \(fe\)")
PENALTY_CHECK = re.compile(r"penalty check: \|F_p1 - F_fe\|/\|F_fe\| = (\S+) \(\|F_fe\| = (\S+)\); \|\|J_p1 - J_fe\|\|_F/\|\|J_fe\|\|_F = (\S+) "
                           r"\((\S+)\); energy (\S+) \(p1\) (\S+) \(fe\)")
MESH = {2: ["-dm_plex_dim", 2, "-dm_plex_box_faces", "12,12"], 3: ["-dm_plex_dim", 3, "-dm_plex_box_faces", "4,4,4"]}


def check_matrices(out, dim, mat_type=None, bs=None):
    """Parses the -assembly_check line and asserts that the two matrices are the same (block size bs, by default dim)."""
    m = CHECK.search(out)
    assert m, f"no assembly check line in:\n{out[-2000:]}"
    rel = float(m.group(1))
    size_p1, size_fe = m.group(2, 3), m.group(4, 5)
    type_p1, type_fe = m.group(6, 7)
    bs_p1, bs_fe = int(m.group(8)), int(m.group(9))
    nz_p1, nz_fe, alloc_p1, alloc_fe = (int(m.group(i)) for i in (10, 11, 12, 13))
    assert rel < 1e-12, f"||K_p1 - K_fe||_F/||K_fe||_F = {rel:.3e}"
    assert size_p1 == size_fe, (size_p1, size_fe)
    assert type_p1 == type_fe, (type_p1, type_fe)
    assert mat_type is None or type_p1.endswith(mat_type) and type_p1 in ("seq" + mat_type, "mpi" + mat_type), (type_p1, mat_type)
    assert bs_p1 == bs_fe == (bs or dim), (bs_p1, bs_fe, bs or dim)
    assert nz_p1 == nz_fe > 0, (nz_p1, nz_fe)  # same nonzero pattern size: no entry missing or extra
    assert alloc_p1 == nz_p1, f"preallocation not exact: {alloc_p1} allocated for {nz_p1} nonzeros"
    return rel


def check_penalty(out):
    """Parses the penalty check line: the Gauss rule's residual, Jacobian and energy at the solution, in closed form
    and by PETSc's boundary integration, are the same to round-off, and not trivially (contact is active)."""
    m = PENALTY_CHECK.search(out)
    assert m, f"no penalty check line in:\n{out[-2000:]}"
    rel_f, norm_f, rel_j, norm_j, e_p1, e_fe = (float(g) for g in m.groups())
    assert norm_f > 0 and norm_j > 0 and e_fe > 0, (norm_f, norm_j, e_fe)
    assert rel_f < 1e-12 and rel_j < 1e-12, (rel_f, rel_j)
    assert abs(e_p1 - e_fe) <= 1e-12 * e_fe, (e_p1, e_fe)


@pytest.mark.parametrize("np_", (1, 2), ids=("np1", "np2"))
@pytest.mark.parametrize("scene", ("square", "mms"))
@pytest.mark.parametrize("dim", (2, 3), ids=("2d", "3d"))
def test_assembly_p1_equals_fe(dim, scene, np_):
    """K_p1 = K_fe to round-off, with the same type, size, block size and pattern; mms has inhomogeneous
    Dirichlet data, so its constrained dofs must be absent from both."""
    out, h5 = run(["-options_file", f"options/{scene}.yaml", "-contact_monitor", 0, "-assembly_check"] + MESH[dim],
                  f"assembly_check_{scene}_{dim}d_np{np_}", np_=np_)
    check_matrices(out, dim)
    check_penalty(out)
    a, _ = load(h5)
    assert a["assembly"] == "p1" and a["converged"] == 1, (a["assembly"], a["converged"])
    assert a["nprocs"] == np_


@pytest.mark.parametrize("name,args", (
    ("refined_3d", ["-options_file", "options/square.yaml", "-dm_plex_dim", 3, "-dm_plex_box_faces", "3,3,3", "-dm_refine", 1]),
    ("grid_sequence_2d", ["-options_file", "options/square.yaml", "-dm_plex_box_faces", "8,8", "-contact_grid_sequence", 2]),
    ("sphere_refined_3d", ["-options_file", "options/square.yaml", "-dm_plex_dim", 3, "-dm_plex_box_faces", "3,3,3", "-dm_refine", 1,
                           "-obstacle", "sphere", "-obstacle_center", "0.5,0.5,-1", "-obstacle_radius", 1.05]),
    ("graded_local_eps", "quarter_disk")), ids=("refined_3d", "grid_sequence_2d", "sphere_refined_3d", "graded_local_eps"))
def test_penalty_gauss_closed_form_equals_petsc(name, args, tmp_path):
    """The closed-form Gauss rule on faces that refinement made (3D -dm_refine, where faces have other orientations in
    their cells, and 2D grid sequencing), under a curved obstacle, and on a graded Gmsh mesh with a local eps per face:
    PETSc's boundary integration to round-off."""
    if args == "quarter_disk":
        import sys
        sys.path.insert(0, os.path.join(ROOT, "scripts"))
        from signorini import geometry
        mesh = str(tmp_path / "quarter_disk.msh")
        geometry.quarter_disk(mesh, h_near=0.01, h_far=0.1, width=0.3, near=0.05)
        args = ["-dm_plex_filename", mesh, "-scene", "general", "-contact_faces", "contact", "-bc_slip", "top,symmetry_x",
                "-bc_slip_top_components", "1", "-bc_slip_top_translate", "0,-0.002", "-bc_slip_symmetry_x_components", "0"]
    out, h5 = run(args + ["-contact_monitor", 0, "-assembly_check"], f"penalty_closed_form_{name}")
    check_penalty(out)
    a, _ = load(h5)
    assert a["converged"] == 1 and a["assembly"] == "p1"
    if name == "graded_local_eps":
        assert a["eps_min"] < 0.5 * a["eps_max"], (a["eps_min"], a["eps_max"])


@pytest.mark.parametrize("mat_type", ("aij", "sbaij"))
@pytest.mark.parametrize("dim", (2, 3), ids=("2d", "3d"))
def test_partly_constrained_vertices_are_preallocated_exactly(dim, mat_type, tmp_path):
    """A slip face fixes one component of its vertices, so K has a row per dof (block size 1): on one rank aij is built
    in its own CSR arrays with the pattern of the mesh's edges (AssemblyP1CreateSeqAIJScalar()), and sbaij's upper
    triangle is preallocated from the same edges (AssemblyP1PreallocateScalar()); both exact, and K is the FE one. The
    Hertz cylinder's quarter disk (2D) and the sphere indenter's quarter block (3D)."""
    import sys
    sys.path.insert(0, os.path.join(ROOT, "scripts"))
    from signorini import hertz
    case = "cylinder" if dim == 2 else "sphere-indenter"
    mesh = str(tmp_path / f"{case}.msh")
    hertz.write_mesh(case, 0.05 if dim == 2 else 0.1, mesh)
    args = hertz.command(case, mesh, "eps=h/10", "unused.h5")[4:-2] + ["-contact_monitor", 0, "-assembly_check", "-dm_mat_type", mat_type]
    if mat_type == "sbaij":
        args += ["-ksp_type", "cg", "-pc_type", "jacobi", "-ksp_rtol", 1e-12]
    out, h5 = run(args, f"assembly_scalar_{dim}d_{mat_type}")
    check_matrices(out, dim, mat_type, bs=1)
    assert load(h5)[0]["converged"] == 1


@pytest.mark.parametrize("mat_type,scene,dim,np_", (("baij", "mms", 3, 2), ("sbaij", "square", 2, 1)), ids=("baij", "sbaij"))
def test_assembly_p1_honours_the_matrix_type(mat_type, scene, dim, np_):
    """-dm_mat_type baij (mms, 3D, 2 ranks) and sbaij (square, 2D, 1 rank; the dual-norm LU of mms refuses sbaij): the
    P1 matrix has the type and equals the FE one."""
    out, h5 = run(["-options_file", f"options/{scene}.yaml", "-contact_monitor", 0, "-assembly", "p1", "-assembly_check", "-dm_mat_type", mat_type, "-ksp_type", "cg",
                   "-pc_type", "jacobi", "-ksp_rtol", 1e-12] + MESH[dim], f"assembly_type_{mat_type}", np_=np_)
    check_matrices(out, dim, mat_type)
    assert load(h5)[0]["converged"] == 1


@pytest.mark.parametrize("scene,np_", (("square", 1), ("square", 2), ("mms", 1)), ids=("square", "square_np2", "mms"))
def test_sbaij_with_the_default_solver_gives_the_aij_answer(scene, np_):
    """-dm_mat_type sbaij with the default direct solver: MUMPS factors K's upper triangle by Cholesky (its LU refuses a
    symmetric block matrix), in the solve and in the dual norm of the error norms; the answer is aij's to 1e-10."""
    res = {}
    for m in ("aij", "sbaij"):
        _, h5 = run(["-options_file", f"options/{scene}.yaml", "-contact_monitor", 0, "-dm_plex_box_faces", "16,16", "-dm_mat_type", m],
                    f"sbaij_default_{scene}_{np_}_{m}", np_=np_)
        res[m] = load(h5)
    (a, fa), (b, fb) = res["aij"], res["sbaij"]
    assert a["converged"] == 1 and b["converged"] == 1
    u, v = fa["displacement"], fb["displacement"]
    assert np.abs(u - v).max() <= 1e-10 * np.abs(u).max(), np.abs(u - v).max()
    for key in ("contact_force", "energy") + (("error_h1", "error_pressure_dual") if scene == "mms" else ()):
        assert abs(a[key] - b[key]) <= 1e-10 * abs(a[key]), (key, a[key], b[key])


@pytest.mark.parametrize("name,args,np_", (("square_2d", ["-options_file", "options/square.yaml", "-dm_plex_box_faces", "32,32"], 1),
                                          ("mms_3d", ["-options_file", "options/mms.yaml"] + MESH[3], 2),
                                          ("square_3d_body_force", ["-options_file", "options/square.yaml", "-body_force", "0.1,0.2,-0.3"] + MESH[3], 2)),
                         ids=("square_2d", "mms_3d", "square_3d_body_force"))
def test_assembly_p1_solution_equals_fe(name, args, np_):
    """The solution with -assembly p1 is the -assembly fe one to solver tolerance (direct solves): 2D square on 1 rank,
    3D mms on 2 ranks (inhomogeneous Dirichlet data), 3D square with its body force and a constant one on 2 ranks; same
    Newton steps and active set. The P1 path also assembles r0 itself (AssemblyP1Residual), with PetscFE's rule, and the
    penalty term's Gauss rule in closed form (src/contact/penalty_faces.c)."""
    sol, attrs = {}, {}
    for asm in ("fe", "p1"):
        _, h5 = run(args + ["-contact_monitor", 0, "-assembly", asm], f"assembly_solution_{name}_{asm}", np_=np_)
        attrs[asm], f = load(h5)
        assert attrs[asm]["assembly"] == asm and attrs[asm]["converged"] == 1, (asm, attrs[asm]["assembly"])
        sol[asm] = sorted_by_position(f, "displacement")
    rel = np.abs(sol["p1"] - sol["fe"]).max() / np.abs(sol["fe"]).max()
    assert rel <= 1e-10, f"{name}: max |u_p1 - u_fe| / max |u_fe| = {rel:.3e}"
    for key in ("newton_its", "active_vertices"):
        assert attrs["p1"][key] == attrs["fe"][key], (name, key, attrs["p1"][key], attrs["fe"][key])
    assert abs(attrs["p1"]["energy"] - attrs["fe"]["energy"]) <= 1e-10 * abs(attrs["fe"]["energy"])


REFUSED_CASES = {"quad": (["-dm_plex_simplex", 0], "the cells are not all triangles (2D) or tetrahedra (3D)"),
                 "p2": (["-displacement_petscspace_degree", 2], "the displacement is not of degree 1")}


@pytest.mark.parametrize("name", REFUSED_CASES)
def test_assembly_p1_refused_where_it_does_not_apply(name):
    """-assembly p1 on quads or P2 stops with the reason, a non-zero exit and no output; -assembly auto falls back to fe there."""
    args, reason = REFUSED_CASES[name]
    square = ["-options_file", "options/square.yaml", "-contact_monitor", 0, "-dm_plex_box_faces", "8,8"]
    out = os.path.join(OUT, f"assembly_refused_{name}.h5")
    rc, text = solve(square + args + ["-assembly", "p1"], output=out, timeout=120)
    assert rc == 2, f"{name}: -assembly p1 accepted, or not refused as input (exit {rc})"
    assert "-assembly p1 needs P1 displacements on triangles or tetrahedra, but " + reason in text, text[-2000:]
    assert not glob.glob(out + "*"), f"{name}: output left behind"
    _, h5 = run(square + args, f"assembly_auto_{name}")
    a, _ = load(h5)
    assert a["assembly"] == "fe" and a["converged"] == 1, (name, a["assembly"])
