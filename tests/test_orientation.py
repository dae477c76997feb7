"""Cells listed clockwise (or, in 3D, with the opposite handedness) give the answer of the same mesh listed the usual
way, on every path that integrates: PETSc's boundary and cell integration (-assembly fe, every P2 run, every
quadrilateral and hexahedron) weighs a point by det J, which such a cell makes negative, so that before the cells were
reflected at set-up (src/mesh/mesh_orient.c) a body pulled to the right moved to the left. The reference is a closed
form: the uniaxial patch test of tests/test_boundary.py, which P1, Q1 and P2 reproduce to round-off on any mesh."""
import itertools
import os

import numpy as np
import pytest

from harness import load, run, refused
from test_boundary import patch_args, uniaxial

S, LIFT = 0.05, 0.01


def write_msh(path, nodes, faces, cells, reverse=False):
    """A Gmsh 2.2 file: nodes [(x, y, z)], faces [(type, tag, vertices)], cells [(type, vertices)] (0-based), each
    cell's vertex order reversed where asked (the same cell, the other orientation)."""
    flip = {2: [0, 2, 1], 3: [0, 3, 2, 1], 4: [0, 1, 3, 2], 5: [0, 3, 2, 1, 4, 7, 6, 5]}
    elems = [(t, tag, v) for t, tag, v in faces] + [(t, 10, [v[i] for i in flip[t]] if reverse else v) for t, v in cells]
    with open(path, "w") as fp:
        fp.write("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n%d\n" % len(nodes))
        fp.writelines(f"{k + 1} {x!r} {y!r} {z!r}\n" for k, (x, y, z) in enumerate(nodes))
        fp.write("$EndNodes\n$Elements\n%d\n" % len(elems))
        fp.writelines(f"{k + 1} {t} 2 {tag} {tag} " + " ".join(str(i + 1) for i in v) + "\n" for k, (t, tag, v) in enumerate(elems))
        fp.write("$EndElements\n")


def square(n, quads):
    """The unit square in n x n cells, counterclockwise, its sides numbered as PETSc's box (bottom 1, right 2, top 3, left 4)."""
    vid = lambda i, j: j * (n + 1) + i  # noqa: E731
    nodes = [(i / n, j / n, 0.0) for j in range(n + 1) for i in range(n + 1)]
    faces = [(1, 1, [vid(i, 0), vid(i + 1, 0)]) for i in range(n)] + [(1, 2, [vid(n, j), vid(n, j + 1)]) for j in range(n)]
    faces += [(1, 3, [vid(i, n), vid(i + 1, n)]) for i in range(n)] + [(1, 4, [vid(0, j), vid(0, j + 1)]) for j in range(n)]
    cells = []
    for j, i in itertools.product(range(n), range(n)):
        a, b, c, d = vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1)
        cells += [(3, [a, b, c, d])] if quads else [(2, [a, b, c]), (2, [a, c, d])]
    return nodes, faces, cells


def cube(n, hexes):
    """The unit cube in n^3 hexahedra or 6 n^3 Kuhn tetrahedra, each positively oriented as Gmsh lists them, its faces
    numbered as PETSc's box (bottom z = 0 1, top 2, front y = 0 3, back 4, right x = 1 5, left 6)."""
    vid = lambda i, j, k: (k * (n + 1) + j) * (n + 1) + i  # noqa: E731
    nodes = [(i / n, j / n, k / n) for k in range(n + 1) for j in range(n + 1) for i in range(n + 1)]
    quad_of = {1: lambda a, b: (a, b, 0), 2: lambda a, b: (a, b, n), 3: lambda a, b: (a, 0, b), 4: lambda a, b: (a, n, b),
               5: lambda a, b: (n, a, b), 6: lambda a, b: (0, a, b)}
    faces = []
    for tag, at in quad_of.items():
        for a, b in itertools.product(range(n), range(n)):
            q = [vid(*at(a, b)), vid(*at(a + 1, b)), vid(*at(a + 1, b + 1)), vid(*at(a, b + 1))]
            faces += [(3, tag, q)] if hexes else [(2, tag, [q[0], q[1], q[2]]), (2, tag, [q[0], q[2], q[3]])]
    cells = []
    for k, j, i in itertools.product(range(n), range(n), range(n)):
        corner = lambda bits: vid(i + (bits & 1), j + ((bits >> 1) & 1), k + ((bits >> 2) & 1))  # noqa: E731
        if hexes:
            cells.append((5, [corner(b) for b in (0, 1, 3, 2, 4, 5, 7, 6)]))
            continue
        for p in itertools.permutations(range(3)):
            b1 = 1 << p[0]
            tet = [corner(0), corner(b1), corner(b1 | (1 << p[1])), corner(7)]
            x = np.array([nodes[v] for v in tet])
            if np.linalg.det(x[1:] - x[0]) < 0:
                tet[2], tet[3] = tet[3], tet[2]
            cells.append((4, tet))
    return nodes, faces, cells


MESHES = {"triangles": (2, lambda: square(4, False)), "quadrilaterals": (2, lambda: square(4, True)),
          "tetrahedra": (3, lambda: cube(3, False)), "hexahedra": (3, lambda: cube(3, True))}
PATHS = {"default": [], "fe": ["-assembly", "fe"], "p2": ["-displacement_petscspace_degree", "2"]}
# quadrilaterals and hexahedra are assembled by PETSc (-assembly fe) by default already
CASES = [(k, p) for k in MESHES for p in PATHS if not (p == "fe" and k in ("quadrilaterals", "hexahedra"))]


@pytest.mark.parametrize("reverse", [False, True], ids=["as_gmsh", "reversed"])
@pytest.mark.parametrize("kind,path", CASES)
def test_reversed_cells_reproduce_the_patch_test(outdir, kind, path, reverse):
    """The uniaxial stress patch test (a traction s pulling the right face to the right) on the mesh as Gmsh lists it
    and with every cell's vertices in the reversed order: the exact linear field to round-off both ways, on the
    project's assembly, PETSc's (-assembly fe) and P2; the reversed file's cells are reported reflected."""
    dim, make = MESHES[kind]
    mesh = os.path.join(outdir, f"{kind}_{'rev' if reverse else 'ccw'}.msh")
    write_msh(mesh, *make(), reverse=reverse)
    args = patch_args(dim, "traction", S, LIFT)  # on the box; the file's mesh replaces it
    i = args.index("-dm_plex_box_faces")
    del args[i:i + 2]
    if "-dm_plex_dim" in args:
        j = args.index("-dm_plex_dim")
        del args[j:j + 2]
    out, h5 = run(args + ["-dm_plex_filename", mesh] + PATHS[path], "orient", output=os.path.join(outdir, f"{kind}_{path}_{reverse}.h5"))
    attrs, fields = load(h5)
    exact = uniaxial(dim, S, LIFT)(fields["x"])
    err = np.max(np.abs(fields["displacement"] - exact))
    assert err < 1e-10 * np.max(np.abs(exact)), f"{kind} {path} reversed={reverse}: patch test error {err:.3e}"
    assert np.max(fields["displacement"][:, 0]) > 0.0  # pulled to the right, it moves to the right
    assert ("listed with the reversed orientation" in out) == reverse, out[-2000:]


@pytest.mark.parametrize("np_", [1, 2])
def test_reversed_triangles_in_contact_give_the_counterclockwise_answer(outdir, np_):
    """The default scene's contact problem on a clockwise Gmsh square with PETSc's assembly: the same force and energy
    as the counterclockwise file with the project's P1 assembly (which used |det J| and was right before), on 1 and 2
    ranks. Before the reflection the clockwise run diverged (DIVERGED_LINEAR_SOLVE, energy +2.47 against -0.0254)."""
    got = {}
    for reverse, assembly in ((False, "p1"), (True, "fe")):
        mesh = os.path.join(outdir, f"contact_{reverse}.msh")
        write_msh(mesh, *square(8, False), reverse=reverse)
        _, h5 = run(["-scene", "square", "-dm_plex_filename", mesh, "-assembly", assembly, "-snes_rtol", "1e-12"], "orient_contact", np_=np_,
                    output=os.path.join(outdir, f"contact_{reverse}_{np_}.h5"))
        got[reverse], _ = load(h5)
    for key in ("contact_force", "energy"):
        a, b = got[False][key], got[True][key]
        assert abs(a - b) <= 1e-10 * abs(a), (key, a, b)


def test_a_cell_of_zero_area_is_refused(outdir):
    """A triangle whose three vertices lie on one line gives a singular stiffness: refused before any solve, naming
    where it is."""
    nodes, faces, cells = square(4, False)
    nodes.append((0.375, 0.0, 0.0))  # the midpoint of the bottom's second edge, on the line of the edge's two ends
    cells.append((2, [1, len(nodes) - 1, 2]))
    mesh = os.path.join(outdir, "flat.msh")
    write_msh(mesh, nodes, faces, cells)
    refused(["-scene", "square", "-dm_plex_filename", mesh], "flat", "cell(s) of zero volume, the first at (0.375, 0, 0)")
