"""The indenters of issue 63. The cone (-obstacle cone: -obstacle_point the apex, -obstacle_axis from the apex into the
cone, -obstacle_half_angle; a wedge in 2D): the written gap of every contact node against a brute-force distance to
the cone's surface, the penalty tending to SNESVI as eps falls, 2 ranks equal to 1, the overlap warning of an
indentation and of a misplaced cone, and the refusals. The flat punch (-obstacle punch: -obstacle_point the center of
its flat end, -obstacle_axis, -obstacle_radius, -obstacle_edge_radius): the gap against a brute-force distance to its
profile, the 2D pressure p(x) = P / (pi sqrt(a^2 - x^2)) of a rigid flat punch, and the refusals. A wedge unloaded
along a load path gives the direct runs."""
import os
import subprocess
import sys

import h5py
import numpy as np
import pytest

from harness import ENV, ROOT, load, refused, run, sorted_by_position

BOX2 = ["-scene", "general", "-dm_plex_box_faces", "16,16", "-contact_faces", "3", "-bc_clamp", "1"]
BOX3 = ["-scene", "general", "-dm_plex_dim", "3", "-dm_plex_box_faces", "6,6,6", "-contact_faces", "2", "-bc_clamp", "1"]


def cone(point, axis, half_angle):
    return ["-obstacle", "cone", "-obstacle_point", ",".join(f"{v:.17g}" for v in point), "-obstacle_axis",
            ",".join(f"{v:.17g}" for v in axis), "-obstacle_half_angle", f"{half_angle:.17g}"]


def brute_force_distance(x, point, axis, half_angle):
    """The distance from each row of x to the cone's surface, by sampling the generator in the plane of the axis and
    the point (t from 0, the apex, to 3 in steps of 1e-5) and refining the best sample by a parabola through it and
    its neighbours; positive outside the cone."""
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    alpha = np.radians(half_angle)
    t = np.linspace(0.0, 3.0, 300001)
    out = []
    for p in np.atleast_2d(x):
        r = p - np.asarray(point, float)
        z = r @ a
        rho = np.linalg.norm(r - z * a)
        d2 = (rho - t * np.sin(alpha)) ** 2 + (z - t * np.cos(alpha)) ** 2
        k = int(np.argmin(d2))
        if 0 < k < len(t) - 1:  # the parabola's vertex through the three samples around the least
            y0, y1, y2 = d2[k - 1], d2[k], d2[k + 1]
            den = y0 - 2 * y1 + y2
            s = 0.5 * (y0 - y2) / den if den > 0 else 0.0
            dt = t[1] - t[0]
            tk = t[k] + s * dt
            best = (rho - tk * np.sin(alpha)) ** 2 + (z - tk * np.cos(alpha)) ** 2
        else:
            best = d2[k]
        inside = z > 0 and rho < z * np.tan(alpha)
        out.append(-np.sqrt(best) if inside else np.sqrt(best))
    return np.array(out)


GAPS = {  # id: (box, apex, axis, half-angle): the apex above the top face, so that no node touches
    "wedge-2d": (BOX2, [0.5, 1.3], [0.3, 1.0], 60.0),
    "cone-3d": (BOX3, [0.45, 0.55, 1.25], [0.2, 0.1, 1.0], 55.0),
}


@pytest.mark.parametrize("case", sorted(GAPS))
def test_gap_of_the_cone(outdir, case):
    """With the cone out of reach and no load, u = 0 and the written normal gap of every contact node is its distance
    to the cone's surface: near the apex the distance to the apex, elsewhere to the flank (both kinds of node are
    asserted present)."""
    box, point, axis, alpha = GAPS[case]
    _, h5 = run(box + cone(point, axis, alpha), "cone_gap", output=os.path.join(outdir, "gap.h5"))
    _, f = load(h5)
    on = f["contact_boundary"] > 0
    x = f["x"][on]
    g = brute_force_distance(x, point, axis, alpha)
    assert np.max(np.abs(f["displacement"])) == 0.0
    assert np.max(np.abs(f["normal_gap"][on] - g)) < 1e-9, np.max(np.abs(f["normal_gap"][on] - g))
    a = np.asarray(axis) / np.linalg.norm(axis)
    r = x - np.asarray(point)
    z = r @ a
    rho = np.linalg.norm(r - np.outer(z, a), axis=1)
    apex = rho * np.sin(np.radians(alpha)) + z * np.cos(np.radians(alpha)) <= 0
    assert apex.any() and (~apex).any()


WEDGE = BOX2 + cone([0.5, 1.0], [0.0, 1.0], 70.3) + ["-obstacle_translate", "0,-0.02", "-dm_plex_box_faces", "32,32", "-contact_monitor", "0"]


@pytest.mark.parametrize("quadrature", ["nodal"])
def test_penalty_tends_to_snesvi_under_a_wedge(outdir, quadrature):
    """A wedge pressed 0.02 into the block: the nodal penalty's distance to SNESVI on the same mesh (both constrain the
    nodes) falls with eps, by a factor of at least 50 from eps0 = 1e-2 to 1e-4 (linear in eps: 100), and is below 1e-4
    of the displacement there. The Gauss rule also presses where the apex reaches between the nodes, so it tends to
    another discrete solution (6% from SNESVI's on this mesh)."""
    _, vi = run(WEDGE + ["-contact_method", "vi"], f"wedge_vi_{quadrature}", output=os.path.join(outdir, "vi.h5"))
    u_vi = sorted_by_position(load(vi)[1], "displacement")
    dist = []
    for eps0 in (1e-2, 1e-4):
        _, h5 = run(WEDGE + ["-penalty_quadrature", quadrature, "-penalty_eps0", eps0], f"wedge_{quadrature}",
                    output=os.path.join(outdir, f"pen_{eps0:g}.h5"))
        attrs, f = load(h5)
        assert attrs["converged"] == 1 and attrs["contact_force"] > 0
        dist.append(np.max(np.abs(sorted_by_position(f, "displacement") - u_vi)) / np.max(np.abs(u_vi)))
    assert dist[1] < dist[0] / 50 and dist[1] < 1e-4, dist


@pytest.mark.parametrize("shape", ["cone", "punch"])
def test_two_ranks_equal_one_under_a_cone(outdir, shape):
    """A 3D cone, and a flat punch with a rounded edge, pressed into the block with the penalty and with SNESVI (its
    rotated frames: the cone's normal turns around the axis node by node, the fillet's too): 2 ranks give 1 rank's
    answer."""
    obstacle = cone([0.5, 0.5, 1.0], [0.0, 0.0, 1.0], 65.0) if shape == "cone" else punch([0.5, 0.5, 1.0], [0.0, 0.0, 1.0], 0.2, 0.1)
    args = BOX3 + obstacle + ["-obstacle_translate", "0,0,-0.1" if shape == "cone" else "0,0,-0.02", "-dm_plex_box_faces", "8,8,8",
                              "-contact_monitor", "0"]
    for method in ("penalty", "vi"):
        got = []
        for ranks in (1, 2):
            _, h5 = run(args + ["-contact_method", method], f"{shape}_np{ranks}_{method}", np_=ranks, output=os.path.join(outdir, f"{method}_{ranks}.h5"))
            got.append(load(h5))
        (r1, f1), (r2, f2) = got
        u1, u2 = sorted_by_position(f1, "displacement"), sorted_by_position(f2, "displacement")
        assert r1["active_vertices"] == r2["active_vertices"] > 1
        assert np.max(np.abs(u1 - u2)) <= 1e-9 * np.max(np.abs(u1)), method
        assert abs(r1["contact_force"] / r2["contact_force"] - 1) < 1e-9, method


def test_an_indenting_cone_is_not_warned_of_a_misplaced_one_is():
    """The overlap warning (a misplaced obstacle?) takes the cone's own shape into account: a cone pressed d into a
    body overlaps it on a width 2 d tan(alpha), a ratio far above the 0.1 of round indenters. Pressed 0.05 (several
    cells) into a quarter model it is not warned of; its apex put half the body deep is."""
    quarter = ["-scene", "general", "-dm_plex_dim", "3", "-dm_plex_box_faces", "12,12,12", "-contact_faces", "2", "-bc_clamp", "1",
               "-bc_slip", "3,5", "-bc_slip_3_components", "1", "-bc_slip_5_components", "0", "-contact_monitor", "0"]
    text, _ = run(quarter + cone([0.0, 0.0, 1.0], [0.0, 0.0, 1.0], 70.3) + ["-obstacle_translate", "0,0,-0.05"], "cone_indent")
    assert "cells deep inside the obstacle" not in text
    text, _ = run(BOX2 + cone([0.5, 0.5], [0.0, 1.0], 70.3), "cone_misplaced")
    assert "cells deep inside the obstacle" in text and "a misplaced obstacle?" in text


BAD = {
    "no_angle": (cone([0.5, 1.0], [0.0, 1.0], 70.3)[:-2], "-obstacle cone needs -obstacle_half_angle"),
    "angle_90": (cone([0.5, 1.0], [0.0, 1.0], 90.0), "-obstacle_half_angle must lie in (0, 90) degrees"),
    "angle_0": (cone([0.5, 1.0], [0.0, 1.0], 0.0), "-obstacle_half_angle must lie in (0, 90) degrees"),
    "zero_axis": (cone([0.5, 1.0], [0.0, 0.0], 70.3), "-obstacle_axis must not be the zero vector"),
    "no_apex": (["-obstacle", "cone", "-obstacle_axis", "0,1", "-obstacle_half_angle", "70"], "-obstacle cone needs -obstacle_point"),
    "no_axis": (["-obstacle", "cone", "-obstacle_point", "0.5,1", "-obstacle_half_angle", "70"], "-obstacle cone needs -obstacle_axis"),
    "radius": (cone([0.5, 1.0], [0.0, 1.0], 70.3) + ["-obstacle_radius", "1"], "-obstacle_radius"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_cone_refusals(case):
    extra, message = BAD[case]
    refused(BOX2 + extra, f"cone_bad_{case}", message)


def punch(point, axis, radius, edge=None):
    args = ["-obstacle", "punch", "-obstacle_point", ",".join(f"{v:.17g}" for v in point), "-obstacle_axis",
            ",".join(f"{v:.17g}" for v in axis), "-obstacle_radius", f"{radius:.17g}"]
    return args + (["-obstacle_edge_radius", f"{edge:.17g}"] if edge is not None else [])


def punch_profile_distance(x, point, axis, radius, edge):
    """The distance from each row of x (outside the punch) to the punch's profile in the plane of the axis and the
    point: the flat end, the fillet's quarter circle and the side, each sampled every 1e-6 or finer."""
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    flat = np.stack([np.linspace(0.0, radius, 200001), np.zeros(200001)], axis=1)
    th = np.linspace(-np.pi / 2, 0.0, 200001)
    arc = np.stack([radius + edge * np.cos(th), edge + edge * np.sin(th)], axis=1)
    side = np.stack([np.full(200001, radius + edge), np.linspace(edge, edge + 0.5, 200001)], axis=1)
    profile = np.concatenate([flat, arc, side])
    out = []
    for p in np.atleast_2d(x):
        r = p - np.asarray(point, float)
        z = r @ a
        rho = np.linalg.norm(r - z * a)
        out.append(np.sqrt(np.min((profile[:, 0] - rho) ** 2 + (profile[:, 1] - z) ** 2)))
    return np.array(out)


PUNCH_GAPS = {  # id: (box, center, axis, radius, edge radius): the flat end above the top face, no node touching
    "filleted-2d": (BOX2, [0.5, 1.05], [0.1, 1.0], 0.2, 0.1),
    "sharp-3d": (BOX3, [0.5, 0.45, 1.05], [0.0, 0.1, 1.0], 0.25, 0.0),
}


@pytest.mark.parametrize("case", sorted(PUNCH_GAPS))
def test_gap_of_the_punch(outdir, case):
    """With the punch out of reach and no load, the written normal gap of every contact node is its distance to the
    punch's profile (nodes below the flat end and beside it, under the fillet or the edge, both asserted present)."""
    box, point, axis, radius, edge = PUNCH_GAPS[case]
    _, h5 = run(box + punch(point, axis, radius, edge), "punch_gap", output=os.path.join(outdir, "gap.h5"))
    _, f = load(h5)
    on = f["contact_boundary"] > 0
    x = f["x"][on]
    g = punch_profile_distance(x, point, axis, radius, edge)
    assert np.max(np.abs(f["displacement"])) == 0.0
    assert np.max(np.abs(f["normal_gap"][on] - g)) < 1e-6, np.max(np.abs(f["normal_gap"][on] - g))
    a = np.asarray(axis) / np.linalg.norm(axis)
    r = x - np.asarray(point)
    rho = np.linalg.norm(r - np.outer(r @ a, a), axis=1)
    assert (rho <= radius).any() and (rho > radius).any()


def test_flat_punch_pressure_in_2d(outdir):
    """A rigid flat punch of half-width a = 0.05 pressed 0.001 into a block 20 a wide and deep (plane strain, the half
    model with its symmetry slip, a mesh graded to h = a/20 at the punch): the exact constraint (SNESVI) gives the
    pressure P / (pi sqrt(a^2 - x^2)) of the closed form under the punch. p(x) sqrt(a^2 - x^2) spreads by at most 2%
    over |x| < 0.8 a (measured: 1.6%), and its mean is P / pi to 2% (P the whole punch's force, twice the half's)."""
    mesh = os.path.join(outdir, "block.msh")
    p = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "make_mesh.py"), "block", "-o", mesh, "--radius", "1", "--h-near", "0.0025",
                        "--near", "0.08", "--h-far", "0.1", "--width", "0.5"], cwd=ROOT, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                       text=True)
    assert p.returncode == 0, p.stdout
    a = 0.05
    args = ["-scene", "general", "-dm_plex_filename", mesh, "-young_modulus", "1", "-poisson_ratio", "0.3", "-contact_faces", "contact", "-bc_clamp",
            "bottom", "-bc_slip", "symmetry_x", "-bc_slip_symmetry_x_components", "0", "-contact_method", "vi", "-contact_monitor", "0"]
    _, h5 = run(args + punch([0.0, 0.0], [0.0, 1.0], a) + ["-obstacle_translate", "0,-0.001"], "flat_punch", output=os.path.join(outdir, "punch.h5"))
    attrs, f = load(h5)
    on = f["contact_boundary"] > 0
    x, pressure = f["x"][on][:, 0], f["contact_pressure"][on]
    inner = np.abs(x) < 0.8 * a
    q = pressure[inner] * np.sqrt(a * a - x[inner] ** 2)
    assert inner.sum() >= 10 and attrs["converged"] == 1
    assert (q.max() - q.min()) / q.mean() < 0.02, (q.min(), q.max())
    assert abs(q.mean() / (2 * attrs["contact_force"] / np.pi) - 1) < 0.02, (q.mean(), 2 * attrs["contact_force"] / np.pi)


PUNCH_BAD = {
    "no_radius": (punch([0.5, 1.0], [0.0, 1.0], 0.2)[:-2], "-obstacle punch needs a positive -obstacle_radius"),
    "negative_edge": (punch([0.5, 1.0], [0.0, 1.0], 0.2, -0.1), "-obstacle_edge_radius must be >= 0"),
    "half_angle": (punch([0.5, 1.0], [0.0, 1.0], 0.2) + ["-obstacle_half_angle", "70"], "-obstacle_half_angle"),
}


@pytest.mark.parametrize("case", sorted(PUNCH_BAD))
def test_punch_refusals(case):
    extra, message = PUNCH_BAD[case]
    refused(BOX2 + extra, f"punch_bad_{case}", message)


def test_unloading_a_wedge_along_a_path_gives_the_direct_runs(outdir):
    """-load_path 1,0.5,0 on the wedge (its translation scales with the factor): each step's force, energy and largest
    pressure are the direct run's at that translation, to 1e-8 (frictionless contact has no history); at 0 the wedge
    only touches, and the force is zero."""
    base = BOX2 + cone([0.5, 1.0], [0.0, 1.0], 70.3) + ["-dm_plex_box_faces", "32,32", "-contact_monitor", "0", "-snes_rtol", "1e-12"]
    _, h5 = run(base + ["-obstacle_translate", "0,-0.02", "-load_path", "1,0.5,0"], "wedge_path", output=os.path.join(outdir, "path.h5"))
    with h5py.File(h5, "r") as f:
        st = {k: f["steps"][k][:] for k in f["steps"]}
    assert list(st["factor"]) == [1.0, 0.5, 0.0] and st["converged"].all()
    for k, t in enumerate((1.0, 0.5)):
        _, d = run(base + ["-obstacle_translate", f"0,{-0.02 * t:.17g}"], f"wedge_direct_{k}", output=os.path.join(outdir, f"direct_{k}.h5"))
        attrs, _ = load(d)
        for q in ("contact_force", "energy", "pressure_max"):
            assert abs(st[q][k] - attrs[q]) <= 1e-8 * abs(attrs[q]), (k, q, st[q][k], attrs[q])
    assert abs(st["contact_force"][2]) <= 1e-12 * abs(st["contact_force"][0])


def test_force_control_and_the_penetration_tolerance_under_a_wedge(outdir):
    """Force control moves the wedge down until it presses with -obstacle_force, to 1e-8 along its direction; the
    augmented Lagrangian reaches -contact_penetration_tol at the nodes and the rule's points."""
    wedge = BOX2 + cone([0.5, 1.0], [0.0, 1.0], 70.3) + ["-dm_plex_box_faces", "32,32", "-contact_monitor", "0"]
    _, h5 = run(wedge + ["-obstacle_translate", "0,-0.01", "-obstacle_force", "0.003"], "wedge_force", output=os.path.join(outdir, "force.h5"))
    attrs, _ = load(h5)
    assert attrs["converged"] == 1 and attrs["force_control_its"] >= 2
    assert abs(-attrs["contact_force_y"] - 0.003) <= 1e-8 * 0.003, attrs["contact_force_y"]
    assert attrs["obstacle_translate_y"] < -0.01  # it moved past its first position
    _, h5 = run(wedge + ["-obstacle_translate", "0,-0.02", "-contact_method", "al", "-contact_penetration_tol", "1e-4"], "wedge_al",
                output=os.path.join(outdir, "al.h5"))
    attrs, _ = load(h5)
    assert attrs["converged"] == 1 and attrs["penetration_tol_solves"] >= 2
    assert attrs["penetration_tol_measured"] <= 1e-4
