"""Every contact output from the same rule as the contact force (issue 29): for every method, penalty rule, obstacle
and dimension, the nodal pressure times the area each node stands for sums to the contact force to round-off, the
active vertices and the largest penetration are nonzero whenever the force is, and the plot script draws that
pressure.

Before, the Gauss rule's pressure was the nodal penalty law: under a curved obstacle touching the faces between their
vertices, sum(pressure x area) / force was 0.98, 0.51 and 0 at eps0 = 1, 0.1, 0.01 (2D cylinder, 16 x 16), and the
summary said "0 active vertices, max penetration 0" while the force was 0.0113.
"""
import os

import numpy as np
import pytest

from harness import ROOT, load, run

BOX = {2: ["-dm_plex_box_faces", "16,16"], 3: ["-dm_plex_dim", 3, "-dm_plex_box_faces", "4,4,4"]}
PRESS = {2: ["-bc_clamp", 3, "-bc_clamp_3_translate", "0,-0.02"], 3: ["-bc_clamp", 2, "-bc_clamp_2_translate", "0,0,-0.02"]}
OBSTACLES = {
    "plane": {2: ["-obstacle", "plane"], 3: ["-obstacle", "plane"]},
    "tilted": {2: ["-obstacle_normal", "0.2,-1"], 3: ["-obstacle_normal", "0.1,0.2,-1"]},
    "curved": {2: ["-obstacle", "cylinder", "-obstacle_center", "0.5,-1", "-obstacle_radius", 1],
               3: ["-obstacle", "sphere", "-obstacle_center", "0.5,0.5,-1", "-obstacle_radius", 1]},
}
METHODS = {"gauss": ["-penalty_quadrature", "gauss"], "nodal": ["-penalty_quadrature", "nodal"], "vi": ["-contact_method", "vi"]}


def cases():
    for dim in (2, 3):
        for obstacle in OBSTACLES:
            for method in METHODS:  # SNESVI too on the tilted and curved obstacles (its frames per node, vi_frames.c)
                for eps0 in ((1.0, 0.01) if method != "vi" else (1.0,)):
                    yield dim, obstacle, method, eps0


@pytest.mark.parametrize("dim,obstacle,method,eps0", list(cases()), ids=lambda v: str(v))
def test_pressure_times_area_is_the_contact_force(dim, obstacle, method, eps0):
    args = ["-scene", "general", "-contact_faces", 1] + BOX[dim] + PRESS[dim] + OBSTACLES[obstacle][dim] + METHODS[method]
    args += ["-penalty_eps0", eps0] if method != "vi" else []
    _, h5 = run(args, f"outputs_{dim}d_{obstacle}_{method}_{eps0}")
    a, f = load(h5)
    assert a["converged"] == 1
    force = a["contact_force"]
    total = float(np.sum(f["contact_pressure"] * f["contact_area"]))
    assert force > 1e-4, f"the case does not press: force {force}"
    assert abs(total - force) <= 1e-12 * abs(force), f"sum(pressure x area) = {total!r}, contact force {force!r}"
    assert a["active_vertices"] > 0
    if method != "vi":  # the exact constraint does not penetrate
        assert a["max_penetration"] > 0.0
    # the pressure is positive where the rule acts: at most round-off of the largest pressure below zero
    assert f["contact_pressure"].min() >= -1e-10 * f["contact_pressure"].max()


def test_plot_script_draws_the_pressure_of_the_force(outdir):
    """scripts/plot_contact.py reads contact_pressure, the field above; on the cylinder at eps0 = 0.01 (where the old
    field was zero everywhere) its data are nonzero."""
    import subprocess
    args = ["-scene", "general", "-contact_faces", 1] + BOX[2] + PRESS[2] + OBSTACLES["curved"][2] + ["-penalty_eps0", 0.01]
    _, h5 = run(args, "outputs_plot")
    png = os.path.join(outdir, "plot.png")
    p = subprocess.run(["/usr/bin/python3", os.path.join(ROOT, "scripts", "plot_contact.py"), h5, "-o", png], cwd=ROOT,
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    assert p.returncode == 0 and os.path.getsize(png) > 0, p.stdout
    _, f = load(h5)
    assert f["contact_pressure"].max() > 0.0


# ---------------------------------------------------------------- warnings: they report, they never change the answer
CYL = ["-scene", "general", "-contact_faces", 1, "-bc_clamp", 3, "-bc_clamp_3_translate", "0,-0.004", "-obstacle", "cylinder",
       "-obstacle_center", "0.5,-1", "-obstacle_radius", 1, "-penalty_eps0", 0.01]


@pytest.mark.parametrize("n,warned", ((16, True), (96, False)))
def test_under_resolved_contact_zone_is_warned(n, warned):
    """The cylinder of scripts/zone_resolution.py: at 16 x 16 its contact zone spans 2 fully pressed faces and the force
    is 11.5% off the 256 x 256 one (bench/zone_resolution.md); at 96 x 96, 8 faces and 0.5%: warned and not warned."""
    out, h5 = run(CYL + ["-dm_plex_box_faces", f"{n},{n}"], f"warn_zone_{n}")
    a, _ = load(h5)
    assert a["converged"] == 1
    assert (a["contact_zone_cells"] < 4) == warned and a["warnings"] == (1 if warned else 0), (a["contact_zone_cells"], a["warnings"])
    assert ("WARNING: the contact zone spans" in out) == warned


def test_under_resolved_contact_zone_is_warned_in_3d():
    """The sphere of scripts/zone_resolution.py --dim 3: at 12^3 the contact zone is 2.8 cells across (the diameter of a
    round zone of its fully pressed faces, sqrt(2 n / pi)) and the force 11% off the 40^3 one (bench/zone_resolution_3d.md):
    warned below 6 cells."""
    args = ["-scene", "general", "-dm_plex_dim", 3, "-dm_plex_box_faces", "12,12,12", "-contact_faces", 1, "-bc_clamp", 2,
            "-bc_clamp_2_translate", "0,0,-0.02", "-obstacle", "sphere", "-obstacle_center", "0.5,0.5,-1", "-obstacle_radius", 1,
            "-penalty_eps0", 0.01]
    out, h5 = run(args, "warn_zone_3d", np_=2)
    a, _ = load(h5)
    assert a["converged"] == 1 and a["contact_zone_faces"] > 0
    assert abs(a["contact_zone_cells"] - (2 * a["contact_zone_faces"] / np.pi) ** 0.5) < 1e-12  # a round zone: the round count
    assert a["contact_zone_cells"] < 6 and a["warnings"] == 1 and "fewer than 6" in out


def test_a_line_contact_is_as_wide_as_its_strip():
    """A rigid cylinder pressed 0.04 across a 3D block (its axis along y, the block 4 long in 32 cells): the contact is a
    strip, 98 fully pressed faces, which a round zone's count takes for 7.9 cells across and did not warn of; it is 2.1
    cells wide (its faces' second moments; more than 3 times as long), 2D-like in its cross-section, and warned below
    the 2D threshold of 4. Its
    force with SNESVI is 2.5% below the 16 x 64 x 8 block's and 1.4% below the 24 x 96 x 12 one's (measured)."""
    args = ["-scene", "general", "-dm_plex_dim", 3, "-dm_plex_box_faces", "8,32,4", "-dm_plex_box_upper", "1,4,1", "-contact_faces", 2,
            "-bc_clamp", 1, "-obstacle", "cylinder", "-obstacle_axis", "0,1,0", "-obstacle_center", "0.5,2,1.5", "-obstacle_radius", 0.5,
            "-obstacle_translate", "0,0,-0.04", "-contact_method", "vi", "-contact_monitor", 0]
    out, h5 = run(args, "warn_strip")
    a, _ = load(h5)
    assert a["contact_zone_faces"] == 98 and (2 * 98 / np.pi) ** 0.5 > 6
    assert 1.5 < a["contact_zone_cells"] < 3 and "fewer than 4" in out, (a["contact_zone_cells"], out[-1500:])


@pytest.mark.parametrize("method", [["-contact_method", "vi"], ["-penalty_quadrature", "nodal"]], ids=["vi", "nodal"])
def test_a_single_pressed_node_is_warned(method):
    """A cylinder pressed 1e-4 into a 16 x 8 block presses on one node: no face of Gamma_C is pressed at all its nodes
    (contact_zone_faces 0), so that before no zone was counted and nothing said, while the force was 69% above the
    512 x 256 block's with SNESVI (4.56e-5 against 2.70e-5, measured). Warned now, as a zone of no cell."""
    args = ["-scene", "general", "-dm_plex_box_faces", "16,8", "-contact_faces", 3, "-bc_clamp", 1, "-obstacle", "cylinder", "-obstacle_center",
            "0.5,1.5", "-obstacle_radius", 0.5, "-obstacle_translate", "0,-0.0001", "-contact_monitor", 0] + method
    out, h5 = run(args, f"warn_node_{method[-1]}")
    a, _ = load(h5)
    assert a["contact_force"] > 0 and a["contact_zone_faces"] == 0 and a["active_vertices"] == 1
    assert "the contact zone spans 0.0 cell(s)" in out and a["warnings"] >= 1, out[-1500:]


def test_indentation_by_overlap_is_not_warned_however_fine_the_mesh(tmp_path):
    """A rigid cylinder prescribed 0.001 into the block of make hertz (2D), on a mesh graded down to 5e-5 at the axis:
    Gamma_C starts many cells deep there, but over a part whose half-length is sqrt(2 R d) (the half model), so the
    depth is sqrt(d / 2R) = 0.022 of that width, far below the warning's 0.1: no warning, the ratio within 10% of
    sqrt(d / 2R) (the overlapped length is measured by faces, to a cell at its end). Warned before by the depth in cells
    alone."""
    import sys
    sys.path.insert(0, os.path.join(ROOT, "scripts"))
    from signorini import hertz
    mesh = str(tmp_path / "graded_block.msh")
    hertz.write_mesh("cylinder-indenter", 5e-5, mesh, grade=0.05, near=0.06)
    out, h5 = run(["-dm_plex_filename", mesh] + hertz.CASES["cylinder-indenter"]["args"] + ["-penalty_eps0", 0.1], "overlap_indentation")
    a, _ = load(h5)
    depth = 0.001
    assert a["initial_overlap_cells"] > 5, a["initial_overlap_cells"]
    assert abs(a["initial_overlap_ratio"] / (depth / 2) ** 0.5 - 1) < 0.1, a["initial_overlap_ratio"]
    assert "cells deep inside the obstacle" not in out and a["warnings"] == 0, out


def test_obstacle_facing_away_and_deep_overlap_are_warned():
    """A plane whose normal points into the body (the foundation given upside down), and an obstacle placed half the body
    deep: each warned in the summary and counted in /run; the default square is not."""
    base = ["-scene", "general", "-dm_plex_box_faces", "16,16", "-contact_faces", 1, "-bc_clamp", 3]
    out, h5 = run(base + ["-obstacle_normal", "0,1", "-obstacle_point", "0,-0.01"], "warn_away")
    a, _ = load(h5)
    assert a["obstacle_away_fraction"] == 1.0 and a["warnings"] >= 1 and "the obstacle's normal points into the body" in out
    out, h5 = run(base + ["-obstacle_point", "0,0.5"], "warn_overlap")
    a, _ = load(h5)
    assert abs(a["initial_overlap_cells"] - 0.5 / (2 ** 0.5 / 16)) < 1e-9 and a["initial_overlap_fraction"] == 1.0
    assert abs(a["initial_overlap_ratio"] - 0.5) < 1e-12  # 0.5 deep over the whole contact side, of length 1
    assert a["warnings"] >= 1 and "cells deep inside the obstacle" in out
    out, h5 = run(["-dm_plex_box_faces", "16,16"], "warn_none")
    a, _ = load(h5)
    assert a["warnings"] == 0 and "WARNING" not in out and a["obstacle_away_fraction"] == 0.0


def test_plot_zooms_on_a_narrow_contact_zone(outdir):
    """scripts/plot_contact.py zooms on the contact zone when it spans less than a third of Gamma_C (issue 31's plots):
    the window holds every vertex with a positive pressure and the free vertices next to it, and no zoom is made where
    nothing or everything is in contact."""
    import subprocess
    import sys
    sys.path.insert(0, os.path.join(ROOT, "scripts"))
    from plot_contact import contact_window
    from signorini.runs import read_contact
    _, h5 = run(CYL + ["-dm_plex_box_faces", "64,64"], "outputs_zoom")
    t, p, _, _ = read_contact(h5, "x")
    window = contact_window(t, p)
    assert window is not None
    lo, hi = window
    assert lo <= t[p > 0].min() and t[p > 0].max() <= hi and hi - lo <= (t.max() - t.min()) / 3, (window, t[p > 0].min(), t[p > 0].max())
    inside = (t >= lo) & (t <= hi)
    assert (p[inside] == 0).sum() >= 2 and inside.sum() < len(t) / 2, (inside.sum(), len(t))  # the gap opening on each side
    assert contact_window(t, np.zeros_like(p)) is None and contact_window(t, np.ones_like(p)) is None
    for zoom in ("auto", "off"):
        png = os.path.join(outdir, f"zoom_{zoom}.png")
        q = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "plot_contact.py"), h5, "-o", png, "--zoom", zoom], cwd=ROOT,
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        assert q.returncode == 0 and open(png, "rb").read(8) == b"\x89PNG\r\n\x1a\n", q.stdout


def test_plot_draws_the_pressure_band(outdir, monkeypatch):
    """With -bars the plot shades the pressure's band: a filled region from p - bar to p + bar at the file's own vertices
    (contact_pressure_bar); without -bars there is none."""
    import sys
    sys.path.insert(0, os.path.join(ROOT, "scripts"))
    import plot_contact
    from matplotlib.collections import PolyCollection
    from signorini.runs import read_contact_fields
    figures = []
    monkeypatch.setattr(plot_contact, "save_png", lambda fig, path, dpi: figures.append(fig))
    _, h5 = run(["-scene", "mms", "-dm_plex_box_faces", "32,32", "-bars", "-estimate", "false"], "outputs_band")
    t, fields, _ = read_contact_fields(h5, "x", optional=("contact_pressure_bar",))
    p, bar = fields["contact_pressure"], fields["contact_pressure_bar"]
    assert bar.max() > 0 and np.all(bar >= 0)
    plot_contact.plot_contact(h5, os.path.join(outdir, "band.png"))
    bands = [c for c in figures[-1].axes[0].collections if isinstance(c, PolyCollection)]
    assert len(bands) == 1
    ys = bands[0].get_paths()[0].vertices[:, 1]
    assert np.isclose(ys.max(), np.max(p + bar), rtol=1e-12) and np.isclose(ys.min(), np.min(p - bar), rtol=1e-12), (ys.min(), ys.max())
    _, h5 = run(["-scene", "mms", "-dm_plex_box_faces", "32,32", "-estimate", "false"], "outputs_noband")
    assert "contact_pressure_bar" not in read_contact_fields(h5, "x", optional=("contact_pressure_bar",))[1]
    plot_contact.plot_contact(h5, os.path.join(outdir, "noband.png"))
    assert not [c for c in figures[-1].axes[0].collections if isinstance(c, PolyCollection)]


@pytest.mark.parametrize("nu,extra,warned,eps_named", [
    (0.44, [], False, False), (0.45, [], True, True), (0.49, ["-penalty_eps_modulus", "pwave"], True, False),
    (0.49, ["-contact_method", "vi"], True, False), (0.49, ["-displacement_petscspace_degree", 2], False, False)])
def test_a_nearly_incompressible_linear_body_is_warned(nu, extra, warned, eps_named):
    """P1 from nu = 0.45 on, where make incompressible measured the Hertz cylinder's largest pressure 1% off the closed
    form (SNESVI), 2% to 5% at 0.49, not falling with the mesh: warned, naming quadratic elements, and where the penalty
    takes eps from E, -penalty_eps_modulus pwave with the ratio (lambda + 2 mu) / E = (1 - nu) / ((1 + nu)(1 - 2 nu));
    not below 0.45, nor for P2. The warning changes nothing: the answer is that of the same run at nu whatever is said."""
    out, h5 = run(["-options_file", "options/square.yaml", "-poisson_ratio", nu] + extra, f"locking_{nu}_{len(extra)}")
    line = [ln for ln in out.splitlines() if "linear elements lock" in ln]
    assert bool(line) == warned, out[-2000:]
    if warned:
        assert f"nu = {nu:g}" in line[0] and "-displacement_petscspace_degree 2" in line[0]
        ratio = (1 - nu) / ((1 + nu) * (1 - 2 * nu))
        assert ("-penalty_eps_modulus pwave" in line[0]) == eps_named
        if eps_named:
            assert f"{ratio:.3g} times softer" in line[0], (line[0], ratio)
    attrs, _ = load(h5)
    assert attrs["warnings"] >= int(warned)
