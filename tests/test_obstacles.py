"""Rigid obstacles (-obstacle plane | sphere | cylinder, -obstacle_translate): the gap of each contact node against the
closed form, a translated plane equal to a moved plane, the penalty Jacobian with curved obstacles against finite
differences (2D and 3D, Gauss and nodal), small Hertz cases against the closed form (make hertz runs the 1% ones), and
2 ranks equal to serial on curved contact faces."""
import os
import re
import sys

import numpy as np
import pytest

from harness import ROOT, load, run, sorted_by_position

sys.path.insert(0, os.path.join(ROOT, "scripts"))
from signorini import hertz  # noqa: E402

BOX2 = ["-scene", "general", "-dm_plex_box_faces", "6,6", "-contact_faces", "3", "-bc_clamp", "1"]
BOX3 = ["-scene", "general", "-dm_plex_dim", "3", "-dm_plex_box_faces", "3,3,3", "-contact_faces", "2", "-bc_clamp", "1"]
INDENTERS = {  # id: (box, obstacle options): an obstacle above the top face x_d = 1, pressed into it
    "sphere-2d": (BOX2, ["-obstacle", "sphere", "-obstacle_center", "0.5,1.6", "-obstacle_radius", "0.7", "-obstacle_translate", "0,-0.05"]),
    "sphere-3d": (BOX3, ["-obstacle", "sphere", "-obstacle_center", "0.5,0.5,1.6", "-obstacle_radius", "0.7", "-obstacle_translate", "0,0,-0.05"]),
    "cylinder-3d": (BOX3, ["-obstacle", "cylinder", "-obstacle_center", "0.5,0.5,1.6", "-obstacle_axis", "1,1,0", "-obstacle_radius", "0.7",
                           "-obstacle_translate", "0,0,-0.05"]),
}


def exact_gap(kind, x, center, radius, axis=None):
    r = x - np.array(center)
    if kind == "cylinder":
        a = np.array(axis) / np.linalg.norm(axis)
        r = r - np.outer(r @ a, a)
    return np.linalg.norm(r, axis=1) - radius


@pytest.mark.parametrize("case", sorted(INDENTERS))
def test_gap_of_curved_obstacles(outdir, case):
    """With the obstacle out of reach and no load, u = 0 and the written normal gap of every contact node is the
    distance to the sphere or cylinder."""
    box, obstacle = INDENTERS[case]
    obstacle = [o if not o.startswith(("0,-0.05", "0,0,-0.05")) else o.replace("-0.05", "0.5") for o in obstacle]
    _, h5 = run(box + obstacle, "gap", output=os.path.join(outdir, "gap.h5"))
    _, f = load(h5)
    on = f["contact_boundary"] > 0
    dim = f["x"].shape[1]
    center = [0.5, 1.6 + 0.5] if dim == 2 else [0.5, 0.5, 1.6 + 0.5]
    kind = "cylinder" if case.startswith("cylinder") else "sphere"
    g = exact_gap(kind, f["x"][on], center, 0.7, axis=[1, 1, 0] if kind == "cylinder" else None)
    assert np.max(np.abs(f["displacement"])) == 0.0
    assert np.max(np.abs(f["normal_gap"][on] - g)) < 1e-14


def test_translated_plane_equals_moved_plane(outdir):
    """-obstacle_translate moves the obstacle rigidly: the same run as the plane through the moved point."""
    common = ["-dm_plex_box_faces", "12,12"]
    _, a = run(common + ["-obstacle_translate", "0,0.01"], "translated", output=os.path.join(outdir, "a.h5"))
    _, b = run(common + ["-obstacle_point", "0,0.01"], "moved", output=os.path.join(outdir, "b.h5"))
    (ra, fa), (rb, fb) = load(a), load(b)
    assert ra["active_vertices"] == rb["active_vertices"] > 0
    assert np.array_equal(fa["displacement"], fb["displacement"])


@pytest.mark.parametrize("quadrature", ["gauss", "nodal"])
@pytest.mark.parametrize("case", sorted(INDENTERS))
def test_penalty_jacobian_curved_obstacles(outdir, case, quadrature):
    """PETSc's finite-difference check of the Jacobian at every Newton step, with eps small enough that the penalty
    term dominates it: ||J - J_fd|| / ||J|| at finite-difference accuracy."""
    box, obstacle = INDENTERS[case]
    text, h5 = run(box + obstacle + ["-penalty_quadrature", quadrature, "-penalty_eps", "1e-3", "-snes_test_jacobian", "-contact_monitor", "0"],
                   "jacobian", output=os.path.join(outdir, "j.h5"))
    ratios = [float(v) for v in re.findall(r"\|\|J - Jfd\|\|_F/\|\|J\|\|_F = ([0-9.eE+-]+)", text)]
    assert ratios and max(ratios) < 1e-6, ratios
    assert load(h5)[0]["contact_force"] > 0  # the penalty term is in the Jacobian


# small Hertz cases: (case, h_near, method, tolerance on a and p0); make hertz runs the finer meshes to 1%.
# docs/verification.md ("Hertz contact against the closed form") says these run within 1% in 2D and 2% in 3D: the 2D cases are held
# to 1% (measured: cylinder vi a -0.14%, p0 -0.13%; eps=h/100 -0.12%, -0.18%; cylinder-indenter eps=h/100 +0.73%, -0.87%;
# vi, in its rotated frames, +0.67%, -0.82%).
HERTZ = [("cylinder", 0.004, "vi", 0.01), ("cylinder", 0.004, "eps=h/100", 0.01), ("sphere", 0.02, "vi", 0.02),
         ("cylinder-indenter", 0.004, "eps=h/100", 0.01), ("sphere-indenter", 0.02, "eps=h/10", 0.02), ("cylinder-indenter", 0.004, "vi", 0.01)]


@pytest.mark.parametrize("case,h_near,method,tol", HERTZ, ids=[f"{c}-{m}" for c, _, m, _ in HERTZ])
def test_hertz_small(outdir, case, h_near, method, tol):
    mesh = os.path.join(outdir, "hertz.msh")
    hertz.write_mesh(case, h_near, mesh)
    out = os.path.join(outdir, "hertz.h5")
    cmd = hertz.command(case, mesh, method, out)
    run(cmd[4:-2], "hertz", output=out)  # without mpiexec -n 1 bin/signorini ... -output, which run() adds
    m = hertz.measure(case, out)
    assert abs(m["a_error"]) < tol and abs(m["p0_error"]) < tol, m
    assert m["balance"] < 1e-10 and m["converged"] == 1


@pytest.mark.parametrize("case,method", [("cylinder-indenter", "eps=h/10"), ("sphere", "vi"), ("cylinder-indenter", "vi"), ("sphere-indenter", "vi")])
def test_two_ranks_curved_contact(outdir, case, method):
    """2 ranks give the serial answer on curved contact faces (a graded Gmsh mesh, local eps), and on curved obstacles
    with SNESVI in its rotated frames (the indenters)."""
    mesh = os.path.join(outdir, "mesh.msh")
    hertz.write_mesh(case, 0.004 if hertz.CASES[case]["dim"] == 2 else 0.02, mesh)
    fields = []
    for ranks in (1, 2):
        out = os.path.join(outdir, f"np{ranks}.h5")
        run(hertz.command(case, mesh, method, out)[4:-2], "np", np_=ranks, output=out)
        fields.append(load(out))
    (r1, f1), (r2, f2) = fields
    u1, u2 = sorted_by_position(f1, "displacement"), sorted_by_position(f2, "displacement")
    assert np.max(np.abs(u1 - u2)) < 1e-9 * np.max(np.abs(u1))
    assert r1["active_vertices"] == r2["active_vertices"] > 3
    assert abs(r1["contact_force"] / r2["contact_force"] - 1) < 1e-9


@pytest.mark.parametrize("case,h_near,tol", [("cylinder", 0.004, 0.005), ("sphere", 0.01, 0.01)])
def test_snesvi_reproduces_hertz_on_curved_bodies(tmp_path, case, h_near, tol):
    """SNESVI, the exact constraint, on make hertz's elastic cylinder and sphere against Hertz's closed form at the
    run's force: the half-width (or radius) a and the peak pressure p0 within 0.5% in 2D and 1% in 3D (measured -0.14%
    and -0.14% on the cylinder at h = 0.004, -0.55% and +0.25% on the sphere at h = 0.01; docs/hertz.md). Before, no
    test read SNESVI's pressure on a curved body against the closed form."""
    from signorini.mpirun import run_mpi
    mesh, out = str(tmp_path / f"{case}.msh"), str(tmp_path / f"{case}_vi.h5")
    hertz.write_mesh(case, h_near, mesh)
    r = run_mpi(hertz.command(case, mesh, "vi", out, ranks=1), timeout=600)
    assert r.returncode == 0, r.output[-2000:]
    m = hertz.measure(case, out)
    assert abs(m["a_error"]) < tol and abs(m["p0_error"]) < tol, (m["a_error"], m["p0_error"])
