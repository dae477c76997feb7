"""The cone (-obstacle cone: -obstacle_point the apex, -obstacle_axis from the apex into the cone, -obstacle_half_angle;
a wedge in 2D; issue 63's first shape): the written gap of every contact node against a brute-force distance to the
cone's surface, the penalty tending to SNESVI as eps falls, 2 ranks equal to 1, the overlap warning of an indentation
and of a misplaced cone, and the refusals."""
import os

import numpy as np
import pytest

from harness import load, refused, run, sorted_by_position

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


def test_two_ranks_equal_one_under_a_cone(outdir):
    """A 3D cone pressed into the block with the penalty and with SNESVI (its rotated frames: the cone's normal turns
    around the axis node by node): 2 ranks give 1 rank's answer."""
    args = BOX3 + cone([0.5, 0.5, 1.0], [0.0, 0.0, 1.0], 65.0) + ["-obstacle_translate", "0,0,-0.1", "-dm_plex_box_faces", "8,8,8",
                                                               "-contact_monitor", "0"]
    for method in ("penalty", "vi"):
        got = []
        for ranks in (1, 2):
            _, h5 = run(args + ["-contact_method", method], f"cone_np{ranks}_{method}", np_=ranks, output=os.path.join(outdir, f"{method}_{ranks}.h5"))
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
