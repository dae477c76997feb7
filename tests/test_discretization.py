"""The discretization and the contact solvers (make test): the patch test, the penalty Jacobian against finite
differences, the square scene, the penalty tending to SNESVI, SNESVI's complementarity, and mpiexec -n 2 = serial.

Every assertion checks a number computed by the solver (read back from its HDF5 output or its log)
against a tolerance that can fail.
"""
import re

import numpy as np
import pytest

from harness import load, run, sorted_by_position

PATCH_MESHES = {
    "tri": [],
    "quad": ["-dm_plex_simplex", 0],
    "tet": ["-dm_plex_dim", 3, "-dm_plex_box_faces", "3,3,3"],
    "hex": ["-dm_plex_dim", 3, "-dm_plex_simplex", 0, "-dm_plex_box_faces", "3,3,3"],
    "p2": ["-displacement_petscspace_degree", 2, "-dm_plex_box_faces", "4,4"],
}


@pytest.mark.parametrize("method", ("none", "penalty"))
@pytest.mark.parametrize("mesh", PATCH_MESHES)
def test_patch_test(mesh, method):
    args = PATCH_MESHES[mesh]
    _, h5 = run(["-scene", "patch", "-contact_method", method] + args, f"patch_{mesh}_{method}")
    attrs, f = load(h5)
    assert attrs["converged"] == 1
    err, scale = np.abs(f["error"]).max(), np.abs(f["exact_displacement"]).max()
    assert err <= 1e-11 * scale, f"patch test error {err:.3e} for a field of size {scale:.3e}"
    assert attrs["active_vertices"] == 0 and attrs["max_penetration"] <= 0.0
    # the energy of the whole field (its Dirichlet values carry the load): 1/2 sigma : eps over the unit box, with the
    # strain of the exact linear field fitted at the vertices (plane strain in 2D)
    x, ue = f["x"], f["exact_displacement"]
    G = np.linalg.lstsq(np.column_stack([x, np.ones(len(x))]), ue, rcond=None)[0][:-1].T
    e = 0.5 * (G + G.T)
    E, nu = attrs["young_modulus"], attrs["poisson_ratio"]
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    energy = 0.5 * (lam * np.trace(e) ** 2 + 2 * mu * np.sum(e * e))
    assert abs(attrs["energy"] - energy) <= 1e-10 * energy, (attrs["energy"], energy)


ACTIVE_PATCH = {
    2: ["-dm_plex_box_faces", "4,4", "-bc_slip", "2,4,3", "-bc_slip_2_components", 0, "-bc_slip_4_components", 0,
        "-bc_slip_3_components", 1],
    3: ["-dm_plex_dim", 3, "-dm_plex_box_faces", "2,2,2", "-bc_slip", "3,4,5,6,2", "-bc_slip_3_components", 1,
        "-bc_slip_4_components", 1, "-bc_slip_5_components", 0, "-bc_slip_6_components", 0, "-bc_slip_2_components", 2],
}


@pytest.mark.parametrize("quad", ("gauss", "nodal"))
@pytest.mark.parametrize("dim", (2, 3), ids=("2d", "3d"))
def test_patch_test_with_active_penalty(dim, quad):
    """The patch test with the penalty term active on the whole of Gamma_C. The unit box rests on the foundation
    x_d = 0 (scene general, Gamma_C the bottom face set 1), its sides are symmetry planes (slips fixing the normal
    component) and its top is pushed down by delta (a slip fixing u_d = -delta), eps set directly (-penalty_eps, so it is
    uniform). By hand (uniaxial strain, M = lambda + 2 mu, 2D plane strain as 3D): u_i = 0 for i < d and
    u_d = c0 + c1 x_d with sigma_dd = M c1 uniform, the penalty pressure p = -c0/eps balancing it (M c1 = c0/eps) and
    c0 + c1 = -delta, so c0 = -delta eps M / (1 + eps M), p = delta M / (1 + eps M) and the penetration is eps p.
    The field is affine and the penalty pressure uniform, so P1 with either rule (Gauss, exact for the constant pressure;
    nodal, lumped) reproduces it: the field to 1e-12 delta (a direct solve, round-off), the penetration, pressure and
    contact force (p times the unit area) to 1e-10 relative, and every Gamma_C vertex active."""
    delta, eps = 0.01, 0.05
    last = "3" if dim == 2 else "2"
    translate = ",".join(["0"] * (dim - 1) + [str(-delta)])
    args = ["-scene", "general", "-contact_faces", 1, "-penalty_eps", eps, "-penalty_quadrature", quad,
            f"-bc_slip_{last}_translate", translate] + ACTIVE_PATCH[dim]
    _, h5 = run(args, f"patch_active_{dim}d_{quad}")
    a, f = load(h5)
    assert a["converged"] == 1
    assert a["eps"] == eps and a["eps_min"] == eps and a["eps_max"] == eps
    E, nu = a["young_modulus"], a["poisson_ratio"]
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    M = lam + 2 * mu
    c0 = -delta * eps * M / (1 + eps * M)
    c1 = -delta - c0
    p = delta * M / (1 + eps * M)
    exact = np.zeros_like(f["displacement"])
    exact[:, dim - 1] = c0 + c1 * f["x"][:, dim - 1]
    err = np.abs(f["displacement"] - exact).max()
    assert err <= 1e-12 * delta, f"field error {err:.3e}"
    on = f["contact_boundary"] > 0.5
    assert on.sum() == a["contact_nodes"] and a["active_vertices"] == a["contact_nodes"] == (5 if dim == 2 else 9)
    assert abs(a["max_penetration"] / (eps * p) - 1) <= 1e-10, (a["max_penetration"], eps * p)
    assert np.abs(f["contact_pressure"][on] / p - 1).max() <= 1e-10, (f["contact_pressure"][on], p)
    assert abs(a["contact_force"] / p - 1) <= 1e-10, (a["contact_force"], p)


def jacobian_ratios(log):
    return [float(m) for m in re.findall(r"\|\|J - Jfd\|\|_F/\|\|J\|\|_F = ([0-9.eE+-]+)", log)]


@pytest.mark.parametrize("quad", ("gauss", "nodal"))
@pytest.mark.parametrize("dim,faces", ((2, "4,4"), (3, "2,2,2")), ids=("2d", "3d"))
def test_penalty_jacobian_fd(dim, faces, quad):
    log, _ = run(["-dm_plex_dim", dim, "-dm_plex_box_faces", faces, "-penalty_quadrature", quad, "-snes_test_jacobian"], f"jacobian_{dim}d_{quad}")
    ratios = jacobian_ratios(log)
    assert len(ratios) >= 2, "no Jacobian test output"
    assert max(ratios) < 1e-6, f"||J - Jfd||/||J|| = {max(ratios):.3e}"


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


def test_square_2d_converges():
    _, h5 = run(["-dm_plex_box_faces", "32,32"], "square_2d")
    attrs, _ = check_square(h5)
    assert attrs["contact_force"] > 0.0 and attrs["active_vertices"] > 0


def test_square_3d_converges():
    _, h5 = run(["-dm_plex_dim", 3, "-dm_plex_box_faces", "6,6,6"], "square_3d")
    attrs, _ = check_square(h5)
    assert attrs["dim"] == 3 and attrs["contact_force"] > 0.0


@pytest.mark.parametrize("name,args", (("quad", ["-dm_plex_simplex", 0, "-dm_plex_box_faces", "16,16"]),
                                       ("p2", ["-displacement_petscspace_degree", 2, "-dm_plex_box_faces", "8,8"])), ids=("quad", "p2"))
def test_square_quads_and_p2_converge(name, args):
    _, h5 = run(args, f"square_{name}")
    check_square(h5)


def test_contact_monitor_reports_active_set():
    log, h5 = run(["-dm_plex_box_faces", "16,16", "-contact_monitor"], "monitor")
    lines = re.findall(r"^\s*(\d+) contact: \|F\| (\S+)\s+active vertices\s+(\d+)\s+entered\s+(\d+)\s+left\s+(\d+)", log, re.M)
    attrs, _ = load(h5)
    assert len(lines) == attrs["newton_its"] + 1
    # the monitor counts the penetrating vertices (Newton's active set); the summary, with the Gauss rule, also the
    # vertices of a face whose Gauss points penetrate between them (issue 29): at least as many, and with the nodal
    # rule the same
    assert int(lines[-1][2]) <= attrs["active_vertices"] <= int(lines[-1][2]) + 2
    log_nodal, h5_nodal = run(["-dm_plex_box_faces", "16,16", "-contact_monitor", "-penalty_quadrature", "nodal"], "monitor_nodal")
    nodal = re.findall(r"active vertices\s+(\d+)", log_nodal)
    assert int(nodal[-1]) == load(h5_nodal)[0]["active_vertices"]
    active = 0
    for _, _, a, e, l in lines:  # the counts are consistent from step to step
        active += int(e) - int(l)
        assert active == int(a)


def test_nodal_penalty_tends_to_vi_linearly_in_eps():
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


def test_vi_constraint_and_complementarity():
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


def test_penalty_approaches_vi_in_force_and_energy():
    args = ["-dm_plex_box_faces", "16,16"]
    vi, _ = load(run(args + ["-contact_method", "vi"], "vi_force")[1])
    pen, _ = load(run(args + ["-penalty_quadrature", "nodal", "-penalty_eps", 1e-7], "nodal_force")[1])
    assert abs(pen["contact_force"] - vi["contact_force"]) <= 1e-5 * vi["contact_force"]
    assert abs(pen["energy"] - vi["energy"]) <= 1e-5 * abs(vi["energy"])
    none, _ = load(run(args + ["-contact_method", "none"], "none_energy")[1])
    assert none["energy"] < pen["energy"] < vi["energy"] + 1e-12, "the constraint must raise the energy"


# ---------------------------------------------------------------- parallel = serial
PARALLEL_CASES = {"penalty_gauss_2d": ["-dm_plex_box_faces", "24,24"],
                  "penalty_nodal_2d": ["-dm_plex_box_faces", "24,24", "-penalty_quadrature", "nodal"],
                  "vi_2d": ["-dm_plex_box_faces", "24,24", "-contact_method", "vi"],
                  "penalty_3d": ["-dm_plex_dim", 3, "-dm_plex_box_faces", "5,5,5"]}


@pytest.mark.parametrize("name", PARALLEL_CASES)
def test_mpiexec_n2_equals_serial(name):
    args = PARALLEL_CASES[name]
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
