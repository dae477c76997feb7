"""Mesh partitioning tests (make test): -partitioner metis|ptscotch|simple gives the serial answer on 2 and 3 ranks, for
every kind of mesh (simplex box, tensor box, Gmsh and HDF5 files), the simplex box built distributed (box, the default for
it) gives it too, and the recorded edge cut and load imbalance are right.

Every assertion checks numbers computed by the solver against a bound or an independent count that can fail.
"""
import os
import re
import shutil

import numpy as np
import pytest

from harness import OUT, load, run, solve, sorted_by_position, write_gmsh_square

SQUARE = ["-options_file", "options/square.yaml", "-contact_monitor", "false"]  # 32x32, default solver (MUMPS)
MMS3D = ["-options_file", "options/mms.yaml", "-dm_plex_dim", 3, "-dm_plex_box_faces", "6,6,6"]


def displacement_difference(a, b):
    """max |u_a - u_b| / max |u_b| over the vertices, matched by position."""
    ua, ub = sorted_by_position(a, "displacement"), sorted_by_position(b, "displacement")
    assert ua.shape == ub.shape, (ua.shape, ub.shape)
    return np.abs(ua - ub).max() / np.abs(ub).max()


def metis_edge_cut(log):
    """The edge cut METIS reports for its own partition of the serial cell graph (-info :dm), an independent count."""
    m = re.findall(r"METIS: (\d+) cells, (\d+) parts, edge cut (\d+)", log)
    assert len(m) == 1, f"no METIS line in the log:\n{log[-2000:]}"
    return int(m[0][2])


def check_same_as_serial(args, name, nranks=(2, 3)):
    ref_attrs, ref = load(run(args, f"{name}_serial")[1])
    assert ref_attrs["converged"] == 1
    assert ref_attrs["partition_edge_cut"] == 0 and ref_attrs["partition_imbalance"] == 1.0, "one rank: no cut, no imbalance"
    for n in nranks:
        log, h5 = run(args + ["-partitioner", "metis", "-info", ":dm"], f"{name}_metis_{n}", np_=n)
        a, f = load(h5)
        assert a["converged"] == 1 and a["nprocs"] == n and a["partitioner"] == "metis", (a["converged"], a["nprocs"], a["partitioner"])
        assert a["n_cells"] == ref_attrs["n_cells"]
        assert a["partition_edge_cut"] == metis_edge_cut(log) > 0, (a["partition_edge_cut"], metis_edge_cut(log))
        diff = displacement_difference(f, ref)
        assert diff <= 1e-8, (n, diff)


def test_metis_2d_square_matches_serial():
    """The 2D square on 2 and 3 ranks partitioned by METIS: the serial displacement to 1e-8 (MUMPS, Newton to 1e-14)."""
    check_same_as_serial(SQUARE, "part_square")


def test_metis_3d_mms_matches_serial():
    """The 3D manufactured solution on 2 and 3 ranks partitioned by METIS: the serial displacement to 1e-8."""
    check_same_as_serial(MMS3D, "part_mms3d")


def test_metis_tensor_box_matches_serial():
    """Quadrilaterals come from DMSetFromOptions, not the project's generator: METIS must partition them too."""
    check_same_as_serial(SQUARE + ["-dm_plex_simplex", 0], "part_quads", nranks=(2,))


def test_metis_gmsh_file_matches_serial():
    """A mesh read from a Gmsh file goes through the same distribution: METIS on 2 ranks, the serial answer."""
    msh = os.path.join(OUT, "part_square16.msh")
    write_gmsh_square(msh, 16, quads=True)
    check_same_as_serial(SQUARE + ["-dm_plex_filename", msh], "part_msh", nranks=(2,))


def test_metis_hdf5_mesh_matches_serial():
    """PETSc reads an HDF5 mesh in parallel, in pieces: METIS (on the mesh gathered to rank 0) on 2 and 3 ranks gives the
    serial answer. Without PETSc's own distribution first, this gave a wrong solution (ptscotch, simple) or an error (metis)."""
    mesh = os.path.join(OUT, "part_square32_mesh.h5")
    run(SQUARE + ["-dm_view", f"hdf5:{mesh}"], "part_write_mesh")
    check_same_as_serial(SQUARE + ["-dm_plex_filename", mesh], "part_h5mesh")
    _, ref = load(os.path.join(OUT, "part_h5mesh_serial.h5"))
    for p in ("ptscotch", "simple"):
        a, f = load(run(SQUARE + ["-dm_plex_filename", mesh, "-partitioner", p], f"part_h5mesh_{p}", np_=2)[1])
        assert a["partitioner"] == p and displacement_difference(f, ref) <= 1e-8, (p, displacement_difference(f, ref))


def test_partition_quality_is_recorded():
    """METIS on the 32x32 square (2048 triangles): imbalance in [1, 1.1], edge cut above 0 and below twice a straight cut
    (32 faces per straight line across the square). The simple partitioner splits the row-by-row cell numbering in
    halves, so on 2 ranks it cuts exactly the 32 faces of the line y = 1/2 with 1024 cells each, for triangles and quads."""
    for n, straight in ((2, 32), (3, 64)):
        a, _ = load(run(SQUARE + ["-partitioner", "metis"], f"quality_metis_{n}", np_=n)[1])
        assert 1.0 <= a["partition_imbalance"] <= 1.1, a["partition_imbalance"]
        assert 0 < a["partition_edge_cut"] < 2 * straight, a["partition_edge_cut"]
    for extra in ([], ["-dm_plex_simplex", 0]):
        a, _ = load(run(SQUARE + extra + ["-partitioner", "simple"], f"quality_simple{len(extra)}", np_=2)[1])
        assert a["partitioner"] == "simple" and a["partition_edge_cut"] == 32 and a["partition_imbalance"] == 1.0, (
            a["partition_edge_cut"], a["partition_imbalance"])
    a, _ = load(run(SQUARE + ["-partitioner", "ptscotch"], "quality_ptscotch", np_=2)[1])
    assert a["partitioner"] == "ptscotch" and 0 < a["partition_edge_cut"] < 64 and 1.0 <= a["partition_imbalance"] <= 1.1


def check_box_same_as_serial(args, name, nranks, cut2):
    """The default partitioner of the project's simplex box: each rank builds a contiguous half of the cell numbering
    (x fastest), so on 2 ranks the cut is the straight one, cut2 faces, with half the cells each; on every count of
    ranks, the serial displacement to 1e-8 and the boundary's face sets intact (the same contact force)."""
    ref_attrs, ref = load(run(args, f"{name}_serial")[1])
    assert ref_attrs["converged"] == 1 and ref_attrs["partition_edge_cut"] == 0
    for n in nranks:
        a, f = load(run(args, f"{name}_box_{n}", np_=n)[1])
        assert a["converged"] == 1 and a["nprocs"] == n and a["partitioner"] == "box", (a["converged"], a["nprocs"], a["partitioner"])
        assert a["n_cells"] == ref_attrs["n_cells"] and a["n_dofs"] == ref_attrs["n_dofs"]
        assert displacement_difference(f, ref) <= 1e-8, (n, displacement_difference(f, ref))
        assert abs(a["contact_force"] - ref_attrs["contact_force"]) <= 1e-8 * abs(ref_attrs["contact_force"])
        assert a["active_vertices"] == ref_attrs["active_vertices"]
        if n == 2:
            assert a["partition_edge_cut"] == cut2 and a["partition_imbalance"] == 1.0, (a["partition_edge_cut"], a["partition_imbalance"])
        else:
            assert 0 < a["partition_edge_cut"] <= 2 * (n - 1) * cut2 and 1.0 <= a["partition_imbalance"] <= 1.01, (
                a["partition_edge_cut"], a["partition_imbalance"])


def test_box_built_distributed_matches_serial():
    """The 2D square (32 x 32, MUMPS) and the 3D manufactured solution (6^3 Kuhn tetrahedra) built distributed on 2 and 3
    ranks: the serial answer; the 2-rank cut is the 32 edges of y = 1/2, and the 2 x 36 triangles of z = 1/2."""
    check_box_same_as_serial(SQUARE, "box_square", (2, 3), 32)
    check_box_same_as_serial(MMS3D, "box_mms3d", (2, 3), 72)


def test_box_partitioner_refuses_other_meshes():
    """-partitioner box with a tensor box or a mesh file: non-zero exit, a message naming the problem, no output file."""
    msh = os.path.join(OUT, "box_refused.msh")
    write_gmsh_square(msh, 4, quads=False)
    for extra, what in ((["-dm_plex_simplex", 0], "a tensor box (-dm_plex_simplex 0)"),
                        (["-dm_plex_filename", msh], "a mesh file (-dm_plex_filename)")):
        d = os.path.join(OUT, "box_refused")
        shutil.rmtree(d, ignore_errors=True)
        os.makedirs(d)
        out = os.path.join(d, "box_refused.h5")
        rc, text = solve(SQUARE + extra + ["-partitioner", "box"], np_=2, output=out, timeout=120)
        assert rc == 2, f"-partitioner box accepted for {what}, or not refused as input (exit {rc})"
        message = "-partitioner box splits the project's simplex box as it builds it; " + what + " needs ptscotch, metis or simple"
        assert message in text, f"'{message}' not in:\n{text[-2000:]}"
        # neither the output pair nor a temporary (.signorini-XXXXXX, src/io/output_file.c) in the output's directory
        assert os.listdir(d) == [], f"output left behind: {os.listdir(d)}"


@pytest.mark.parametrize("n", (1, 2), ids=("np1", "np2"))
def test_bad_partitioner_is_refused(n):
    """-partitioner bogus: non-zero exit, a message naming the choices, and no output file."""
    d = os.path.join(OUT, f"bad_partitioner_{n}")
    shutil.rmtree(d, ignore_errors=True)
    os.makedirs(d)
    out = os.path.join(d, "out.h5")
    rc, text = solve(SQUARE + ["-partitioner", "bogus"], np_=n, output=out, timeout=120)
    assert rc == 2, f"bad -partitioner accepted, or not refused as input (exit {rc})"
    message = "Unknown option bogus for -partitioner. Available options: ptscotch metis simple box"
    assert message in text, f"'{message}' not in:\n{text[-2000:]}"
    # neither the output pair nor a temporary (.signorini-XXXXXX, src/io/output_file.c) in the output's directory
    assert os.listdir(d) == [], f"output left behind: {os.listdir(d)}"
