"""The FEniCSx side of the 3D bench (issue 35, scripts/bench_fenicsx.py) solves the project's problem: the 3D default run
on the 8^3 box against scripts/signorini/fenicsx_side.py (Debian's python3-dolfinx) on the same box. The meshes are the
same Kuhn tetrahedra, eps and the unknowns are the same, and the contact forces agree to 1e-3 (measured 3.3e-5: the face
rules of degree 3 differ in their points, docs/solvers.md), and to 2e-4, which a rule of another degree misses; and the
comparison can fail: FEniCSx with eps 1% larger is off by more than 1e-3 (measured 1.8e-3)."""
import json
import os
import subprocess
import sys

import pytest

from harness import ENV, ROOT, load, run

sys.path.insert(0, os.path.join(ROOT, "scripts"))
from signorini import fenicsx_side  # noqa: E402

N = 8
FORCE_RTOL = 1e-3  # issue 35: the same contact force to 1e-3
RULE_RTOL = 2e-4  # at 8^3 the face rule's degree shows at this level (below)
DEFAULT_3D = ["-options_file", "options/square.yaml", "-contact_monitor", "0", "-dm_plex_dim", "3",
              "-dm_plex_box_faces", f"{N},{N},{N}"]


def fenicsx(outdir, name, extra=()):
    """fenicsx_side.py on the N^3 box in a process of its own (as the bench runs it): its JSON result."""
    result = os.path.join(outdir, name + ".json")
    p = subprocess.run(fenicsx_side.fenicsx_cmd(N, result, extra=extra), cwd=ROOT, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                       timeout=300)
    assert p.returncode == 0, p.stdout[-3000:]
    with open(result) as fh:
        return json.load(fh)


@pytest.fixture(scope="module")
def project(tmp_path_factory):
    """The project's 3D default run on the N^3 box: (its /run attributes, its output file)."""
    out = str(tmp_path_factory.mktemp("fenicsx") / "signorini.h5")
    _, h5 = run(DEFAULT_3D, "fenicsx_project", output=out)
    return load(h5)[0], h5


def test_fenicsx_contact_force_agrees_with_the_3d_default_run(outdir, project):
    attrs, h5 = project
    assert attrs["converged"] == 1 and attrs["penalty_quadrature"] == "gauss" and attrs["dim"] == 3
    # in a process of its own: dolfinx initializes MPI, after which this process could not start mpiexec for the other tests
    cells = subprocess.run(fenicsx_side.same_cells_cmd(h5, N), cwd=ROOT, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=300)
    assert cells.returncode == 0, f"dolfinx's create_unit_cube tetrahedra are not the project's Kuhn box: {cells.stdout[-2000:]}"
    fx = fenicsx(outdir, "newton")
    assert fx["converged"] == 1 and fx["snes_reason_name"] == "CONVERGED_FNORM_RELATIVE", fx
    assert fx["free_dofs"] == attrs["n_dofs"], (fx["free_dofs"], attrs["n_dofs"])
    assert abs(fx["eps_min"] / attrs["eps"] - 1) < 1e-12 and abs(fx["eps_max"] / attrs["eps"] - 1) < 1e-12, (fx["eps_min"], fx["eps_max"], attrs["eps"])
    diff = abs(fx["contact_force"] - attrs["contact_force"]) / attrs["contact_force"]
    assert diff <= FORCE_RTOL, f"contact force {fx['contact_force']!r} (FEniCSx) against {attrs['contact_force']!r}: {diff:.2e} relative"
    # tighter, at this box: the rules of degree 3 differ by 3.3e-5 here, a face rule of degree 2 or 8 by 3.6e-4 and 3.8e-4
    assert diff <= RULE_RTOL, f"contact force {diff:.2e} off: is the penalty term's face rule of degree {fx['penalty_quadrature_degree']} PETSc's (3)?"
    assert attrs["contact_force"] > 0.1  # the obstacle pushes up, both codes' sign


def test_fenicsx_force_comparison_sees_a_one_percent_eps(outdir, project):
    """The comparison is not loose: FEniCSx with eps0 = 1.01 (eps 1% larger) is off by more than the tolerance."""
    attrs, _ = project
    fx = fenicsx(outdir, "eps101", extra=["--eps0", "1.01"])
    assert fx["converged"] == 1
    diff = abs(fx["contact_force"] - attrs["contact_force"]) / attrs["contact_force"]
    assert diff > FORCE_RTOL, f"a 1% larger eps moved the contact force by only {diff:.2e}"
