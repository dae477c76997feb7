"""Every boundary-condition family at once (a clamp with a translation, a slip with its value, a traction, a pressure,
a body force, two contact face sets under a curved obstacle) on a Gmsh mesh, against GetFEM on the very same mesh
(tests/getfem_reference.py): the nodal displacements agree to solver tolerance, serially and on 2 ranks."""
import os

import numpy as np
import pytest

import getfem_reference as ref
from harness import load, run


@pytest.fixture(scope="module")
def problem(tmp_path_factory):
    path = str(tmp_path_factory.mktemp("getfem") / "every_family.msh")
    ref.write_mesh(path)
    x, u, force = ref.solve(path)
    return path, x, u, force


@pytest.mark.parametrize("ranks", [1, 2])
def test_every_family_against_getfem(outdir, problem, ranks):
    path, x_ref, u_ref, force_ref = problem
    _, h5 = run(["-dm_plex_filename", path] + ref.solver_options(), "every_family", np_=ranks, output=os.path.join(outdir, "ef.h5"))
    attrs, fields = load(h5)
    assert attrs["converged"] == 1 and attrs["active_vertices"] > 3 and attrs["active_vertices"] < attrs["contact_nodes"]
    order_ref = np.lexsort(np.round(x_ref, 9).T)
    order = np.lexsort(np.round(fields["x"], 9).T)
    assert np.allclose(x_ref[order_ref], fields["x"][order], atol=1e-12)
    diff = np.max(np.abs(u_ref[order_ref] - fields["displacement"][order]))
    scale = np.max(np.abs(u_ref))
    assert diff < 1e-10 * scale, f"max difference {diff:.3e} against GetFEM (displacement scale {scale:.3e})"
    assert abs(attrs["contact_force"] / force_ref - 1) < 1e-9
