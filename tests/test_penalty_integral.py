"""The penalty term of the Gauss rule against face integrals computed by hand in Python (issue 29, item 5).

tests/test_assembly.py compares the closed-form Gauss assembly with PETSc's boundary integration, but both call the same
pointwise kernels (src/contact/penalty_kernels.h), so a wrong kernel passes it. Here the observable is the solver's nodal
reaction of the foundation, the field contact_reaction = -R_i . n with R = K u + r0 the bulk residual: at a converged
solve R = -(penalty term), so on a flat obstacle with every component of the Gamma_C nodes free

    contact_reaction_i = (1/eps) int_{Gamma_C} [u_h . n - g]_+ phi_i ds,   contact_force = its sum,
    (contact_force_x, _y, _z) = -(1/eps) int [u_h . n - g]_+ n ds,

which Python integrates from the output's mesh and displacement alone (scripts/signorini/exact.py: d = (x + u_h - p0) . n
is affine on each face; the positive part is integrated exactly by clipping the face at the zero crossing).
Set-up: scene general, the top clamped and pushed down, Gamma_C the bottom, a tilted plane (-obstacle_normal), eps from the
uniform mesh (eps_min = eps_max). The nodes of Gamma_C never share a face set with the clamp, so all their components
are free.
"""
import os

import h5py
import numpy as np
import pytest

from harness import load, run
from signorini.exact import boundary_faces, plane_penetration, positive_part_loads, read_p1_mesh

CASES = {
    # every Gamma_C node penetrating: no face is cut, the Gauss rule (exact for the quadratic d phi_i) is the integral
    "2d_all_active": (["-dm_plex_box_faces", "8,8", "-bc_clamp", 3, "-bc_clamp_3_translate", "0,-0.05"], (0.1, -1.0)),
    "3d_all_active": (["-dm_plex_dim", 3, "-dm_plex_box_faces", "3,3,3", "-bc_clamp", 2, "-bc_clamp_2_translate", "0,0,-0.05"],
                      (0.05, 0.03, -1.0)),
    # the plane falls away with x: contact on x < 0.3 only, one face cut by the zero of d
    "2d_cut": (["-dm_plex_box_faces", "8,8", "-bc_clamp", 3, "-bc_clamp_3_translate", "0,-0.02"], (-0.05, -1.0)),
}


def solve(outdir, case):
    args, normal = CASES[case]
    _, h5 = run(["-scene", "general", "-contact_faces", 1, "-obstacle_normal", ",".join(map(str, normal)), "-snes_rtol", "1e-14"] + args, case,
                output=os.path.join(outdir, "p.h5"))
    a, _ = load(h5)
    assert a["converged"] == 1 and a["residual_norm"] <= 1e-12 * a["load_norm"], (a["converged"], a["residual_norm"], a["load_norm"])
    assert a["penalty_quadrature"] == "gauss" and a["eps"] > 0  # uniform: the 3D box's cell sizes differ by rounding only
    assert abs(a["eps_min"] / a["eps"] - 1) <= 1e-12 and abs(a["eps_max"] / a["eps"] - 1) <= 1e-12
    x, cells, u = read_p1_mesh(h5)
    with h5py.File(h5, "r") as f:
        on = f["vertex_fields/contact_boundary"][:] > 0.5
        reaction = f["vertex_fields/contact_reaction"][:]
    faces = boundary_faces(cells, on)
    d, n = plane_penetration(x, u, np.zeros(len(normal)), normal)
    return a, x, on, reaction, faces, d, n


@pytest.mark.parametrize("case", ("2d_all_active", "3d_all_active"))
def test_penalty_reaction_equals_the_exact_face_integral(outdir, case):
    """Every Gamma_C node active: the nodal reactions equal (1/eps) int [d]_+ phi_i to 1e-10 of the largest (measured
    1.3e-15 in 2D, 4.4e-16 in 3D: the solve is direct and the residual at round-off), and the total force and its vector
    likewise. A kernel off by a factor, a wrong normal or a wrong gap fails this; the two assemblies of test_assembly.py
    would still agree."""
    a, x, on, reaction, faces, d, n = solve(outdir, case)
    assert a["active_vertices"] == a["contact_nodes"] == on.sum() and np.all(d[on] > 0)
    b = positive_part_loads(x, faces, d) / a["eps"]
    assert np.abs(reaction[on] - b[on]).max() <= 1e-10 * b.max(), np.abs(reaction[on] - b[on]).max()
    assert abs(a["contact_force"] / b.sum() - 1) <= 1e-10, (a["contact_force"], b.sum())
    force = np.array([a["contact_force_" + k] for k in "xyz"[:len(n)]])
    assert np.abs(force + b.sum() * n).max() <= 1e-10 * b.sum(), (force, -b.sum() * n)


def test_penalty_reaction_on_a_cut_face_2d(outdir):
    """Contact on part of Gamma_C, the zero of d inside one face. Off that face's two nodes the reactions equal the exact
    integral to 1e-10 (measured 3.9e-15). On it the solver's rule is PETSc's 2-point Gauss-Legendre on the whole face,
    which a kink does not integrate exactly: its reactions equal the textbook 2-point rule applied to (1/eps)[d]_+ phi_i,
    written here, to 1e-10 (measured 4e-15), and the exact integral within 10% of the cut face's exact load at its
    active node (measured 5.3%): the rule's error, not the law's."""
    a, x, on, reaction, faces, d, n = solve(outdir, "2d_cut")
    assert 0 < a["active_vertices"] < a["contact_nodes"]
    exact = positive_part_loads(x, faces, d) / a["eps"]
    gauss = positive_part_loads(x, faces, d, rule="gauss2") / a["eps"]
    cut = [f for f in faces if d[f].max() > 0 > d[f].min()]
    assert len(cut) == 1
    on_cut = np.zeros(len(d), bool)
    on_cut[cut[0]] = True
    scale = exact.max()
    assert np.abs(reaction[on & ~on_cut] - exact[on & ~on_cut]).max() <= 1e-10 * scale
    assert np.abs(reaction[on] - gauss[on]).max() <= 1e-10 * scale
    active = cut[0][np.argmax(d[cut[0]])]
    assert abs(reaction[active] - exact[active]) <= 0.1 * exact[active], (reaction[active], exact[active])
    assert abs(a["contact_force"] / gauss.sum() - 1) <= 1e-10
