"""The simplex box's interpolated topology, built directly by the project (src/mesh/mesh_interpolate.c), is PETSc's:
the same points, cones, orientations, supports, cell types, depths and coordinates as DMPlexInterpolate() gives, and the
same numbers in the output, to the last bit.

Every assertion checks what the code computes against PETSc's own construction of the same mesh, in the same run or in
a run with -box_petsc_interpolate.
"""
import re

import numpy as np
import pytest

from harness import load, run, sorted_by_position

SQUARE = ["-options_file", "options/square.yaml", "-contact_monitor", "false"]


@pytest.mark.parametrize("dim,faces", ((2, "7,5"), (2, "32,32"), (3, "3,4,5"), (3, "8,8,8")))
def test_direct_interpolation_is_petscs(dim, faces):
    """-box_interpolation_check builds the box both ways and counts the entries that differ; -dm_plex_check_all runs
    PETSc's own consistency checks (symmetry, skeleton, faces, geometry) on the directly built mesh."""
    log, h5 = run(SQUARE + ["-dm_plex_dim", dim, "-dm_plex_box_faces", faces, "-box_interpolation_check", "-dm_plex_check_all"],
                  f"mesh_build_check_{dim}d_{faces.replace(',', 'x')}")
    m = re.findall(r"box interpolation check: (\d+) differences from DMPlexInterpolate\(\) in (\d+) compared entries", log)
    assert len(m) == 1, log[-2000:]
    differences, compared = int(m[0][0]), int(m[0][1])
    n = [int(f) for f in faces.split(",")]
    cells = (2 if dim == 2 else 6) * int(np.prod(n))
    assert compared > 4 * cells, (compared, cells)  # every point's cone, support, type and depth, and the coordinates
    assert differences == 0, (differences, compared)
    assert load(h5)[0]["converged"] == 1


@pytest.mark.parametrize("extra,name", ((["-dm_plex_box_faces", "24,24", "-dm_refine", 1], "2d_refined"),
                                        (["-dm_plex_dim", 3, "-dm_plex_box_faces", "5,5,5", "-penalty_quadrature", "gauss"], "3d_gauss")))
def test_direct_interpolation_gives_the_same_bits(extra, name):
    """A whole run on the directly built box and on PETSc's interpolation: every field and every /run number equal to the
    last bit (the serial build is the same mesh, so nothing may change, not even round-off)."""
    a_attrs, a = load(run(SQUARE + extra, f"mesh_build_direct_{name}")[1])
    b_attrs, b = load(run(SQUARE + extra + ["-box_petsc_interpolate"], f"mesh_build_petsc_{name}")[1])
    assert a_attrs["converged"] == b_attrs["converged"] == 1
    for key in a:
        assert np.array_equal(a[key], b[key]), key
    assert sorted(a_attrs) == sorted(b_attrs)
    for key in a_attrs:
        if not key.startswith(("time_", "peak_memory")):  # the only entries that may differ: what the runs cost
            assert np.array_equal(a_attrs[key], b_attrs[key]), (key, a_attrs[key], b_attrs[key])


@pytest.mark.parametrize("np_", (2, 3))
@pytest.mark.parametrize("extra,name", ((["-dm_plex_box_faces", "33,17", "-dm_refine", 1], "2d_refined"),
                                        (["-dm_plex_dim", 3, "-dm_plex_box_faces", "4,3,5", "-dm_refine", 1], "3d_refined"),
                                        (["-dm_plex_dim", 3, "-dm_plex_box_faces", "4,3,5", "-displacement_petscspace_degree", 2], "3d_p2")))
def test_distributed_direct_build_gives_petscs_answer(np_, extra, name):
    """The box built distributed, its faces, edges and shared points made by the project (src/mesh/mesh_interpolate.c),
    against PETSc's parallel interpolation of the same cells: PETSc's checks pass on the direct mesh (-dm_plex_check_all:
    symmetry, skeleton, faces, geometry, the point SF), a refinement of it after the distribution (which needs the shared
    edges and faces to agree between ranks) and P2 (dofs on the shared edges) give the same displacement to 1e-10 and the
    same active set, contact force and Newton steps."""
    a_attrs, a = load(run(SQUARE + extra + ["-dm_plex_check_all"], f"mesh_build_np{np_}_direct_{name}", np_=np_)[1])
    b_attrs, b = load(run(SQUARE + extra + ["-box_petsc_interpolate"], f"mesh_build_np{np_}_petsc_{name}", np_=np_)[1])
    assert a_attrs["converged"] == b_attrs["converged"] == 1 and a_attrs["nprocs"] == np_
    ua, ub = sorted_by_position(a, "displacement"), sorted_by_position(b, "displacement")
    assert ua.shape == ub.shape
    assert np.abs(ua - ub).max() <= 1e-10 * np.abs(ub).max(), np.abs(ua - ub).max()
    for key in ("active_vertices", "newton_its", "n_cells", "n_dofs"):
        assert a_attrs[key] == b_attrs[key], (key, a_attrs[key], b_attrs[key])
    assert abs(a_attrs["contact_force"] - b_attrs["contact_force"]) <= 1e-10 * abs(b_attrs["contact_force"])


@pytest.mark.parametrize("np_,extra,name", (
    (1, ["-dm_plex_box_faces", "9,7"], "tri"),
    (1, ["-dm_plex_dim", 3, "-dm_plex_box_faces", "3,4,2"], "tet"),
    (1, ["-dm_plex_simplex", 0, "-dm_plex_box_faces", "6,5"], "quad"),
    (1, ["-dm_plex_dim", 3, "-dm_plex_simplex", 0, "-dm_plex_box_faces", "3,2,3"], "hex"),
    (1, ["-dm_plex_filename", "options/meshes/square8.msh"], "gmsh"),
    (2, ["-dm_plex_dim", 3, "-dm_plex_box_faces", "4,3,5", "-dm_refine", 1], "tet_np2"),
    (2, ["-dm_plex_dim", 3, "-dm_plex_box_faces", "4,3,5", "-box_petsc_interpolate", "-partitioner", "ptscotch"], "tet_np2_petsc")))
def test_closure_walk_is_petscs(np_, extra, name):
    """-mesh_closure_check walks every point's closure and star by depth (src/mesh/mesh_closure.c: the cell type of each
    depth instead of a label lookup per point) and compares it with DMPlexGetTransitiveClosure(), point, orientation
    and order, and each closure's vertices as MeshClosureVertices() lists them (the P1 residual's). The walk by depth must serve on every rank of these meshes (one cell type per depth), so the comparison
    is between the two codes, not of PETSc with itself."""
    log, h5 = run(SQUARE + extra + ["-mesh_closure_check"], f"mesh_closure_{name}", np_=np_)
    m = re.findall(r"closure check: (\d+) differences from DMPlexGetTransitiveClosure\(\) in (\d+) closures and stars; walk by depth on (\d+) rank",
                   log)
    assert len(m) == 1, log[-2000:]
    differences, compared, by_depth = (int(v) for v in m[0])
    assert by_depth == np_
    assert compared > 0 and compared % 2 == 0
    assert differences == 0, (differences, compared)
    assert load(h5)[0]["converged"] == 1
