"""Unit invariance (make test): the penalty problem with a zero initial gap and eps = eps0 h / E, and the Signorini
problem itself, are positively homogeneous, so u(E, load) = (load / E) u(1, 1) exactly (the elastic problem too). Steel in SI units with a light
load used to be reported converged with u = 0 (the critical-point line search stopped at the initial point on an
absolute test), and SNESVI found the wrong active set (its bound tolerance is absolute). Every scaling must converge
to the same scaled solution, in 2D and 3D, with the penalty (gauss and nodal quadrature) and with SNESVI.
"""
import numpy as np
import pytest

from harness import load, run, sorted_by_position

# (E, load): load is -square_beta, the body force factor; E from 1e-6 to 1e16, loads from 1e-9 to 1e12
SCALINGS = [(2e11, 1e-2), (1e16, 1.0), (1.0, 1e-9), (1e-6, 1e12), (1e-6, 1e-9), (1e16, 1e12), (1e4, 1e-5)]
METHODS = {"gauss": ["-contact_method", "penalty"], "nodal": ["-contact_method", "penalty", "-penalty_quadrature", "nodal"],
           "vi": ["-contact_method", "vi"], "none": ["-contact_method", "none"]}
MESHES = {"2d": ["-dm_plex_box_faces", "16,16"], "3d": ["-dm_plex_dim", 3, "-dm_plex_box_faces", "4,4,4"]}

@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("dim", MESHES)
def test_unit_invariance(dim, method):
    mesh, margs = MESHES[dim], METHODS[method]
    base = ["-options_file", "options/square.yaml", "-contact_monitor", "false"] + mesh + margs
    a1, f1 = load(run(base + ["-young_modulus", 1, "-square_beta", 1], f"units_{dim}_{method}_ref")[1])
    assert a1["converged"] == 1 and (a1["active_vertices"] > 0) == (method != "none")
    u1 = sorted_by_position(f1, "displacement")
    for E, beta in SCALINGS:
        a, f = load(run(base + ["-young_modulus", E, "-square_beta", beta], f"units_{dim}_{method}_E{E:g}_b{beta:g}")[1])
        assert a["converged"] == 1, (E, beta, a["snes_reason"])
        assert a["newton_its"] >= 1, (E, beta, "no Newton step")
        u = sorted_by_position(f, "displacement") * (E / beta)
        rel = np.abs(u - u1).max() / np.abs(u1).max()
        assert rel <= 1e-8, f"E = {E:g}, load = {beta:g}: |u E/load - u(1,1)| / |u(1,1)| = {rel:.2e}"
        assert a["active_vertices"] == a1["active_vertices"], (E, beta, a["active_vertices"], a1["active_vertices"])
        if method != "none":  # without contact the force is round-off
            assert abs(a["contact_force"] / beta - a1["contact_force"]) <= 1e-8 * abs(a1["contact_force"]), (E, beta)


def test_zero_load_gives_zero_displacement_at_once():
    """No load and no initial penetration: F(0) = 0, so u = 0 is the solution, converged with no Newton step."""
    for margs in METHODS.values():
        a, f = load(run(["-dm_plex_box_faces", "8,8", "-square_beta", 0] + margs, "units_zero_load")[1])
        assert a["converged"] == 1 and a["newton_its"] == 0 and a["load_norm"] == 0.0, (margs, a["snes_reason"])
        assert np.abs(f["displacement"]).max() == 0.0
