"""Gmsh geometries (scripts/make_mesh.py, scripts/signorini/geometry.py): a 2D half-disk and a 3D quarter sphere
touching the plane x_d = 0 at the origin, graded toward that point, with numbered and named physical groups that the
solver reads as "Face Sets"; the built-in square scene (Gamma_C = 1, clamped top) solves on them, penalty and SNESVI,
and 2 ranks give the serial answer on curved contact faces."""
import os
import subprocess
import sys

import numpy as np
import pytest

from harness import ENV, ROOT, load, read_gmsh_simplices, run, sorted_by_position

MAKE_MESH = os.path.join(ROOT, "scripts", "make_mesh.py")
SHAPES = {"half-disk": (2, {"contact": 1, "top": 3}), "quarter-sphere": (3, {"contact": 1, "top": 2, "symmetry_y": 3, "symmetry_x": 6})}
SIZES = {"half-disk": ["--h-far", "0.05", "--h-near", "0.01"], "quarter-sphere": ["--h-far", "0.15", "--h-near", "0.04"]}
RADIUS = 0.5


def make_mesh(shape, path, extra=()):
    return subprocess.run([sys.executable, MAKE_MESH, shape, "-o", path, "--radius", str(RADIUS)] + SIZES[shape] + list(extra), cwd=ROOT, env=ENV,
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=300)


def cell_sizes(path, dim):
    """(distance of each cell's centroid to the origin, largest edge of the cell), read back with Gmsh's API."""
    x, simplices = read_gmsh_simplices(path, dim)
    nv = dim + 1
    cells = x[simplices]
    r = np.linalg.norm(cells.mean(axis=1), axis=1)
    edges = np.max([np.linalg.norm(cells[:, i] - cells[:, j], axis=1) for i in range(nv) for j in range(i + 1, nv)], axis=0)
    return r, edges


@pytest.fixture(scope="module")
def meshes(tmp_path_factory):
    d = tmp_path_factory.mktemp("geometry")
    paths = {}
    for shape in SHAPES:
        paths[shape] = str(d / f"{shape}.msh")
        p = make_mesh(shape, paths[shape])
        assert p.returncode == 0, p.stdout
    return paths


@pytest.mark.parametrize("shape", SHAPES)
def test_mesh_groups_and_grading(meshes, shape):
    """The physical groups carry the documented numbers and names, and the cells at the contact point are several times
    smaller than those far from it."""
    dim, groups = SHAPES[shape]
    text = open(meshes[shape]).read()
    names = text[text.index("$PhysicalNames"):text.index("$EndPhysicalNames")]
    for name, tag in groups.items():
        assert f'{dim - 1} {tag} "{name}"' in names, (name, tag, names)
    r, h = cell_sizes(meshes[shape], dim)
    near, far = h[r < (0.05 if dim == 2 else 0.15) * RADIUS].mean(), h[r > 0.6 * RADIUS].mean()
    assert near < far / 2, f"cells near the contact point {near:.3g}, far {far:.3g}"


@pytest.mark.parametrize("method", ["penalty", "vi"])
@pytest.mark.parametrize("shape", SHAPES)
def test_square_scene_solves_on_the_mesh(meshes, shape, method):
    """The body, clamped on its top and pushed down, touches the plane around the origin: converged, a contact force,
    and the largest pressure at a vertex near the origin."""
    a, f = load(run(["-dm_plex_filename", meshes[shape], "-contact_method", method], f"geometry_{shape}_{method}")[1])
    assert a["converged"] == 1 and a["active_vertices"] > 0 and a["contact_force"] > 0, (a["snes_reason"], a["active_vertices"])
    on = f["contact_boundary"] > 0.5
    x, p = f["x"][on], f["contact_pressure"][on]
    assert np.linalg.norm(x[np.argmax(p)]) < 0.25 * RADIUS, x[np.argmax(p)]
    assert np.abs(p[x[:, -1] > 0.2 * RADIUS]).max() <= 1e-8 * p.max(), "contact far above the plane"


def test_two_ranks_equal_serial_on_curved_contact_faces(meshes):
    args = ["-dm_plex_filename", meshes["half-disk"], "-penalty_quadrature", "gauss"]
    a1, f1 = load(run(args, "geometry_serial")[1])
    a2, f2 = load(run(args, "geometry_np2", np_=2)[1])
    assert a1["converged"] == a2["converged"] == 1 and a2["nprocs"] == 2
    u1, u2 = sorted_by_position(f1, "displacement"), sorted_by_position(f2, "displacement")
    assert np.abs(u1 - u2).max() <= 1e-9 * np.abs(u1).max()
    assert a1["active_vertices"] == a2["active_vertices"]


def test_bad_sizes_are_refused(tmp_path):
    path = str(tmp_path / "bad.msh")
    p = make_mesh("half-disk", path, ["--h-near", "0.5"])
    assert p.returncode == 2 and "h_near (0.5) must not exceed h_far (0.05)" in p.stdout, p.stdout
    assert not os.path.exists(path)


def test_graded_size_follows_h_near_plus_grade_r(tmp_path):
    """--grade G: inside --near the cells' size follows h_near + G r (the path meshes of docs/hertz.md), measured on
    rings of a 2D mesh: each ring's mean largest edge within 35% of the field at its centroids, and growing with r as
    the field does (a constant size would fail both); a grade that would exceed h_far at --near is refused."""
    path = str(tmp_path / "graded.msh")
    p = subprocess.run([sys.executable, MAKE_MESH, "half-disk", "-o", path, "--radius", str(RADIUS), "--h-far", "0.05", "--h-near", "0.001",
                        "--grade", "0.1", "--near", "0.3"], cwd=ROOT, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                       timeout=300)
    assert p.returncode == 0, p.stdout
    r, h = cell_sizes(path, 2)
    means = []
    for lo, hi in ((0.02, 0.04), (0.08, 0.12), (0.18, 0.25)):
        sel = (r > lo * RADIUS) & (r < hi * RADIUS)
        field = 0.001 + 0.1 * r[sel]
        ratio = h[sel].mean() / field.mean()
        assert 1 / 1.35 <= ratio <= 1.35, f"ring {lo}-{hi}: cells {h[sel].mean():.4g}, field {field.mean():.4g}"
        means.append(h[sel].mean())
    assert means[2] > 3 * means[0], means
    bad = str(tmp_path / "bad.msh")
    p = subprocess.run([sys.executable, MAKE_MESH, "half-disk", "-o", bad, "--h-far", "0.05", "--h-near", "0.01", "--grade", "1", "--near", "0.3"],
                       cwd=ROOT, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=300)
    assert p.returncode == 2 and "h_near + grade near (0.31), must not exceed h_far (0.05)" in p.stdout, p.stdout
    assert not os.path.exists(bad)


def test_pressure_along_the_arc_and_the_radius(meshes, tmp_path):
    """scripts/plot_contact.py --along arc (2D) follows the contact curve: the abscissa of each vertex is its arc length
    R phi from the lowest point, to the chords' error; --along r (3D) is the distance from the touching point in the plane."""
    sys.path.insert(0, os.path.join(ROOT, "scripts"))
    from signorini.runs import read_contact
    _, h5 = run(["-dm_plex_filename", meshes["half-disk"]], "geometry_arc")
    s, p, _, _ = read_contact(h5, "arc")
    _, f = load(h5)
    on = f["contact_boundary"] > 0.5
    x = f["x"][on]
    phi = np.sort(np.arctan2(x[:, 0], RADIUS - x[:, 1]))
    assert np.abs(s - RADIUS * phi).max() <= 2e-3 * RADIUS, np.abs(s - RADIUS * phi).max()
    assert p.max() > 0
    _, h5 = run(["-dm_plex_filename", meshes["quarter-sphere"]], "geometry_r")
    r, _, _, _ = read_contact(h5, "r")
    _, f = load(h5)
    x = f["x"][f["contact_boundary"] > 0.5]
    assert np.abs(r - np.sort(np.hypot(x[:, 0], x[:, 1]))).max() <= 1e-12
    for along, h5file in (("arc", os.path.join(os.path.dirname(h5), "geometry_arc.h5")), ("r", h5)):
        png = str(tmp_path / f"{along}.png")
        q = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "plot_contact.py"), h5file, "-o", png, "--along", along], cwd=ROOT, env=ENV,
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        assert q.returncode == 0 and open(png, "rb").read(8) == b"\x89PNG\r\n\x1a\n", q.stdout
    q = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "plot_contact.py"), h5, "-o", str(tmp_path / "no.png"), "--along", "arc"],
                       cwd=ROOT, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    assert q.returncode == 2 and "the arc length is for 2D contact curves" in q.stdout, q.stdout
