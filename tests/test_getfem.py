"""Every boundary-condition family at once (a clamp with a translation, a slip with its value, a traction, a pressure,
a body force, two contact face sets under a curved obstacle) on a Gmsh mesh, against GetFEM on the very same mesh
(tests/getfem_reference.py): the nodal displacements agree to solver tolerance, serially and on 2 ranks; and the same
problem on a tilted plane foundation (-obstacle_point, -obstacle_normal), serially."""
import os

import numpy as np
import pytest

import getfem_reference as ref
from harness import load, run


def displacement_difference(x_ref, u_ref, fields):
    """(max |u_ref - u| over the vertices matched by position, max |u_ref|): the reference's vertices are the file's."""
    order_ref = np.lexsort(np.round(x_ref, 9).T)
    order = np.lexsort(np.round(fields["x"], 9).T)
    assert np.allclose(x_ref[order_ref], fields["x"][order], atol=1e-12)
    return np.max(np.abs(u_ref[order_ref] - fields["displacement"][order])), np.max(np.abs(u_ref))


@pytest.fixture(scope="module")
def problem(tmp_path_factory):
    path = str(tmp_path_factory.mktemp("getfem") / "every_family.msh")
    ref.write_mesh(path)
    x, u, force = ref.solve(path)
    return path, x, u, force


@pytest.fixture(scope="module")
def problem_plane(problem):
    path = problem[0]
    x, u, force = ref.solve(path, obstacle="plane")
    return path, x, u, force


@pytest.mark.parametrize("ranks", [1, 2])
def test_every_family_against_getfem(outdir, problem, ranks):
    path, x_ref, u_ref, force_ref = problem
    _, h5 = run(["-dm_plex_filename", path] + ref.solver_options(), "every_family", np_=ranks, output=os.path.join(outdir, "ef.h5"))
    attrs, fields = load(h5)
    assert attrs["converged"] == 1 and attrs["active_vertices"] > 3 and attrs["active_vertices"] < attrs["contact_nodes"]
    diff, scale = displacement_difference(x_ref, u_ref, fields)
    assert diff < 1e-10 * scale, f"max difference {diff:.3e} against GetFEM (displacement scale {scale:.3e})"
    assert abs(attrs["contact_force"] / force_ref - 1) < 1e-9


def test_tilted_plane_against_getfem(outdir, problem_plane):
    """The tilted plane (normal (0.1, -1) normalized, through (1, -0.05)): the gap and normal of each contact node
    from GetFEM's side's formula g = (p - x) . n, the rest as above. Contact on part of Gamma_C only (the plane falls
    away on one side); the displacements agree to 1e-10 of their size and the contact force to 1e-9, as for the disk
    (both solve the same discrete problem to 1e-13 and 1e-14 relative residuals)."""
    path, x_ref, u_ref, force_ref = problem_plane
    _, h5 = run(["-dm_plex_filename", path] + ref.solver_options("plane"), "tilted", output=os.path.join(outdir, "tp.h5"))
    attrs, fields = load(h5)
    assert attrs["converged"] == 1 and attrs["obstacle"] == "plane"
    assert 3 < attrs["active_vertices"] < attrs["contact_nodes"], (attrs["active_vertices"], attrs["contact_nodes"])
    diff, scale = displacement_difference(x_ref, u_ref, fields)
    assert diff < 1e-10 * scale, f"max difference {diff:.3e} against GetFEM (displacement scale {scale:.3e})"
    assert abs(attrs["contact_force"] / force_ref - 1) < 1e-9
    # the gap written by the solver is the plane's: normal_gap = g - u_n at every contact node
    on = fields["contact_boundary"] > 0.5
    n, g = ref.obstacle_normal_gap(fields["x"][on], "plane")
    un = np.sum(fields["displacement"][on] * n, axis=1)
    assert np.max(np.abs(fields["normal_gap"][on] - (g - un))) < 1e-12


@pytest.fixture(scope="module")
def exact(problem):
    path = problem[0]
    return {obstacle: ref.solve_exact(path, obstacle=obstacle) for obstacle in ("cylinder", "plane")}


@pytest.mark.parametrize("obstacle,ranks", [("cylinder", 1), ("cylinder", 2), ("plane", 1)])
def test_snesvi_against_getfem_exact_contact(outdir, problem, exact, obstacle, ranks):
    """SNESVI (-contact_method vi) on the disk and on the tilted plane, whose normals are no axis at any contact node
    (the rotated frames of src/contact/vi_frames.c), against the exact nodal contact on GetFEM's operators
    (getfem_reference.solve_exact: an active set iteration on the saddle-point system, in numpy): the displacements
    agree to 1e-8 of their size, the contact force (sum of the multipliers there, of the nodal reactions here) to 1e-8."""
    path = problem[0]
    x_ref, u_ref, force_ref = exact[obstacle]
    _, h5 = run(["-dm_plex_filename", path] + ref.solver_options(obstacle, "vi"), "vi", np_=ranks, output=os.path.join(outdir, "vi.h5"))
    attrs, fields = load(h5)
    assert attrs["converged"] == 1 and attrs["method"] == "vi"
    assert 3 < attrs["active_vertices"] < attrs["contact_nodes"], (attrs["active_vertices"], attrs["contact_nodes"])
    diff, scale = displacement_difference(x_ref, u_ref, fields)
    assert diff < 1e-8 * scale, f"max difference {diff:.3e} against GetFEM's exact contact (displacement scale {scale:.3e})"
    assert abs(attrs["contact_force"] / force_ref - 1) < 1e-8, (attrs["contact_force"], force_ref)


def test_snesvi_against_getfem_contact_brick(outdir, problem):
    """SNESVI in its rotated frames on the tilted plane against GetFEM alone (getfem_reference.solve_brick: GetFEM's
    elasticity, load and Dirichlet bricks, its nodal contact brick with the rigid obstacle given as a signed distance,
    its Newton), on the problem without the left slip: the displacements to 1e-8 of their size (measured 3.3e-13) and
    the contact force to 1e-8. (Under the disk the brick differs by 1.1e-5, by an amount that grows with the obstacle's
    curvature: 2.1e-6 at R = 50, 1.5e-5 at R = 1.5 (python3 tests/getfem_reference.py prints them), where the exact
    normals of solve_exact() agree to 6e-15; GetFEM's brick approximates the curved obstacle's normal or gap.)"""
    path = problem[0]
    x_ref, u_ref, force_ref = ref.solve_brick(path, obstacle="plane")
    _, h5 = run(["-dm_plex_filename", path] + ref.solver_options("plane", "vi", slip=False), "brick", output=os.path.join(outdir, "brick.h5"))
    attrs, fields = load(h5)
    assert attrs["converged"] == 1 and 3 < attrs["active_vertices"] < attrs["contact_nodes"]
    diff, scale = displacement_difference(x_ref, u_ref, fields)
    assert diff < 1e-8 * scale, f"max difference {diff:.3e} against GetFEM's contact brick (displacement scale {scale:.3e})"
    assert abs(attrs["contact_force"] / force_ref - 1) < 1e-8, (attrs["contact_force"], force_ref)
