"""SNESVI on obstacles whose normal is not a coordinate axis (src/contact/vi_frames.c: the free components of such a
contact node are solved in a frame of their own, (normal, tangents), so that u . n <= g bounds one unknown).

Independent references:
- rotation: frictionless linear elasticity is invariant under a rotation of the whole problem. A problem whose
  obstacle normals are axes (solved without frames, as before) and the same problem rotated by an angle that puts
  every normal off the axes (solved in frames) give displacements that are the rotation of each other, node by node;
- the penalty: the nodal penalty constrains the same nodal u . n - g, and converges to SNESVI linearly in eps; at a tiny
  eps it equals SNESVI on the sphere and cylinder indenters;
- two ranks give what one rank gives."""
import math
import os

import numpy as np
import pytest

from harness import load, run, sorted_by_position, write_gmsh_cube, write_gmsh_square
from signorini import hertz

THETA = math.radians(30.0)


def rotation_2d(t):
    return [[math.cos(t), -math.sin(t)], [math.sin(t), math.cos(t)]]


def rotation_3d():
    """A rotation about the axis (1, 2, 3)/|.| by 40 degrees (Rodrigues): every axis goes off every axis."""
    k = np.array([1.0, 2.0, 3.0]) / math.sqrt(14.0)
    t = math.radians(40.0)
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return (np.eye(3) + math.sin(t) * kx + (1 - math.cos(t)) * kx @ kx).tolist()


def vec(v):
    return ",".join(repr(float(x)) for x in v)


def matched(x_ref, x_rot, rot):
    """For each reference vertex, the index of the rotated mesh's vertex at rot x (to 1e-9)."""
    target = x_ref @ np.asarray(rot).T
    idx = np.array([np.argmin(np.sum((x_rot - t) ** 2, axis=1)) for t in target])
    assert np.max(np.linalg.norm(x_rot[idx] - target, axis=1)) < 1e-9
    return idx


def rotated_pair(outdir, name, dim, rot, n, args_of):
    """Runs the problem (args_of(R) with the mesh written rotated by R) unrotated and rotated; returns the reference and
    rotated outputs' (attrs, fields) and the vertex matching."""
    res = []
    for tag, r in (("ref", None), ("rot", rot)):
        mesh = os.path.join(outdir, f"{name}_{tag}.msh")
        (write_gmsh_square(mesh, n, rotation=r) if dim == 2 else write_gmsh_cube(mesh, n, rotation=r))
        R = np.eye(dim) if r is None else np.asarray(r)
        text, out = run(["-dm_plex_filename", mesh, "-scene", "general", "-contact_method", "vi", "-poisson_ratio", "0.3"] + args_of(R),
                        f"{name}_{tag}", output=os.path.join(outdir, f"{name}_{tag}.h5"))
        res.append((text, load(out)))
    (_, (a0, f0)), (_, (a1, f1)) = res
    return a0, f0, a1, f1, matched(f0["x"][:, :dim], f1["x"][:, :dim], rot)


def test_rotated_cantilever_2d(outdir):
    """A cantilever clamped on its left side bends under its weight onto a plane 0.01 below it (partial contact). Rotated
    by 30 degrees (the plane's normal (sin 30, -cos 30)), the displacement is R u_ref to 1e-9 of its size, the contact
    force R F_ref, the active vertices the same; the reference's normal is an axis (no frames), the rotated one's is not."""
    def args(R):
        return ["-bc_clamp", "4", "-contact_faces", "1", "-body_force", vec(R @ [0.0, -0.05]), "-obstacle", "plane",
                "-obstacle_point", vec(R @ [0.0, -0.01]), "-obstacle_normal", vec(R @ [0.0, -1.0])]

    a0, f0, a1, f1, idx = rotated_pair(outdir, "vi_rot2d", 2, rotation_2d(THETA), 12, args)
    R = np.asarray(rotation_2d(THETA))
    u0, u1 = f0["displacement"][:, :2], f1["displacement"][:, :2]
    assert 2 < int(a0["active_vertices"]) < 12, "partial contact expected"
    assert int(a1["active_vertices"]) == int(a0["active_vertices"])
    assert np.max(np.abs(u1[idx] - u0 @ R.T)) <= 1e-9 * np.max(np.abs(u0))
    F0 = np.array([a0["contact_force_x"], a0["contact_force_y"]])
    F1 = np.array([a1["contact_force_x"], a1["contact_force_y"]])
    assert np.linalg.norm(F1 - R @ F0) <= 1e-8 * np.linalg.norm(F0)
    assert np.max(np.abs(f1["contact_pressure"][idx] - f0["contact_pressure"])) <= 1e-8 * np.max(f0["contact_pressure"])


def rotation_about_x(t):
    return [[1.0, 0.0, 0.0], [0.0, math.cos(t), -math.sin(t)], [0.0, math.sin(t), math.cos(t)]]


@pytest.mark.parametrize("about", ["axis123", "x"])
def test_rotated_block_3d(outdir, about):
    """A cube clamped on its top face, pressed down by 0.003 with a sideways shift onto a plane 0.002 under its bottom
    face (frictionless: it slides) and pushed sideways by a body force, which lifts part of the face (partial contact);
    rotated about (1, 2, 3) by 40 degrees every normal component mixes, rotated about x by 30 degrees the normal is
    (0, sin, -cos), whose first free component is not on it (the frame's normal unknown must still carry the bound):
    the displacement is R u_ref to 1e-9 of its size, the active vertices the same, the contact force R F_ref."""
    rot = rotation_3d() if about == "axis123" else rotation_about_x(THETA)

    def args(R):
        return ["-bc_clamp", "2", "-bc_clamp_2_translate", vec(R @ [0.003, -0.002, -0.003]), "-contact_faces", "1",
                "-body_force", vec(R @ [0.01, 0.0, 0.0]), "-obstacle", "plane", "-obstacle_point", vec(R @ [0.0, 0.0, -0.002]),
                "-obstacle_normal", vec(R @ [0.0, 0.0, -1.0])]

    a0, f0, a1, f1, idx = rotated_pair(outdir, "vi_rot3d", 3, rot, 4, args)
    R = np.asarray(rot)
    u0, u1 = f0["displacement"][:, :3], f1["displacement"][:, :3]
    assert 3 < int(a0["active_vertices"]) < 20, "partial contact expected"
    assert int(a1["active_vertices"]) == int(a0["active_vertices"])
    assert np.max(np.abs(u1[idx] - u0 @ R.T)) <= 1e-9 * np.max(np.abs(u0))
    F0 = np.array([a0[f"contact_force_{c}"] for c in "xyz"])
    F1 = np.array([a1[f"contact_force_{c}"] for c in "xyz"])
    assert np.linalg.norm(F1 - R @ F0) <= 1e-8 * np.linalg.norm(F0)


def cube_mesh(outdir):
    mesh = os.path.join(outdir, "cube.msh")
    write_gmsh_cube(mesh, 6)
    return mesh


def hertz_mesh(outdir, case, h_near):
    mesh = os.path.join(outdir, f"{case}.msh")
    hertz.write_mesh(case, h_near, mesh)
    return mesh


PRESS = ["-scene", "general", "-contact_faces", "1", "-bc_clamp", "2", "-bc_clamp_2_translate", "0,0,-0.01"]
# name: (options of the problem, without the contact method, given the test's directory)
OBSTACLES = {
    "tilted-plane-2d": lambda d: ["-scene", "square", "-square_tilt", "10", "-dm_plex_box_faces", "16,16"],
    "cylinder-2d": lambda d: hertz.command("cylinder-indenter", hertz_mesh(d, "cylinder-indenter", 0.01), "vi", "unused")[4:-4],
    "tilted-plane-3d": lambda d: ["-dm_plex_filename", cube_mesh(d)] + PRESS + ["-obstacle", "plane", "-obstacle_point", "0,0,0",
                                                                                "-obstacle_normal", "0.17,0.1,-0.98"],
    "sphere-3d": lambda d: hertz.command("sphere-indenter", hertz_mesh(d, "sphere-indenter", 0.05), "vi", "unused")[4:-4],
    "cylinder-3d": lambda d: ["-dm_plex_filename", cube_mesh(d)] + PRESS + ["-obstacle", "cylinder", "-obstacle_center", "0.5,0.5,-1",
                                                                            "-obstacle_radius", "1", "-obstacle_axis", "1,0,0"],
}


@pytest.mark.parametrize("name", OBSTACLES)
def test_nodal_penalty_converges_to_vi(outdir, name):
    """The nodal penalty's distance to SNESVI (max |u_eps - u_vi| / max |u_vi|) falls linearly with eps: slope 1 +- 0.1
    from eps = h to h/1000 (-penalty_eps0 1 to 1e-3), and at eps = 1e-9 h the two equal to 1e-8: they constrain the same
    nodal u . n - g, SNESVI exactly (in the rotated frames wherever the normal is not an axis), the penalty in u itself."""
    problem = OBSTACLES[name](outdir)
    assert "-contact_method" not in problem
    _, ref = run(problem + ["-contact_method", "vi"], "vi", output=os.path.join(outdir, "vi.h5"))
    u_vi = sorted_by_position(load(ref)[1], "displacement")
    scale = np.max(np.abs(u_vi))
    dist = {}
    for eps0 in (1.0, 1e-3, 1e-9):
        _, out = run(problem + ["-contact_method", "penalty", "-penalty_quadrature", "nodal", "-penalty_eps0", eps0], "pen",
                     output=os.path.join(outdir, f"pen_{eps0:g}.h5"))
        attrs, fields = load(out)
        assert attrs["converged"] == 1
        dist[eps0] = np.max(np.abs(sorted_by_position(fields, "displacement") - u_vi)) / scale
    slope = math.log10(dist[1.0] / dist[1e-3]) / 3.0
    print(f"{name}: distance to SNESVI {dist[1.0]:.3e} (eps = h), {dist[1e-3]:.3e} (h/1000), {dist[1e-9]:.3e} (1e-9 h); slope {slope:.3f}")
    assert abs(slope - 1.0) <= 0.1, (slope, dist)
    assert dist[1e-9] <= 1e-8, dist
    assert int(load(ref)[0]["active_vertices"]) >= 3


def test_vi_zone_count_ignores_round_off(outdir):
    """SNESVI's pressure is the nodal reaction, round-off (1e-16) at the free nodes: the contact-zone count of the
    resolution check (contact_zone_faces, faces whose every node carries force) counts a node above 1e-10 of the
    largest pressure only. The 8 x 8 square: 3 faces on 1 and 2 ranks (before, 4 or 6 on 2 ranks from one run to the
    next, as the round-off's signs fell)."""
    counts = []
    for ranks in (1, 2):
        _, out = run(["-dm_plex_box_faces", "8,8", "-contact_method", "vi"], f"zone{ranks}", np_=ranks, output=os.path.join(outdir, f"zone{ranks}.h5"))
        attrs, fields = load(out)
        counts.append(int(attrs["contact_zone_faces"]))
        on = fields["contact_boundary"] > 0.5
        assert np.max(np.abs(fields["contact_pressure"][on][fields["normal_gap"][on] > 1e-12])) < 1e-12  # free nodes: round-off
    assert counts == [3, 3], counts
