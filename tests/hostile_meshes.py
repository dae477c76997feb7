"""Gmsh meshes a new user may bring that the solver cannot handle (tests/test_hostile.py): made with Gmsh's Python API
(a mixed mesh, a second-order mesh, a physical group inside the body) or by editing a Gmsh 2.2 file (a cell twice)."""
import gmsh

from harness import write_gmsh_square

NAMES = {1: "bottom", 2: "right", 3: "top", 4: "left"}


def _square(path, order=1, recombine_right=False, interior_line=False):
    """The unit square, sides named bottom (1), right (2), top (3), left (4); optionally its right half in quadrilaterals
    (the left half stays triangles), a second-order mesh, or a line inside the body named 'inner' (7)."""
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        g = gmsh.model.geo
        pts = [g.addPoint(x, y, 0, 0.25) for x, y in ((0, 0), (0.5, 0), (1, 0), (1, 1), (0.5, 1), (0, 1))]
        a, b, c, d, e, f = pts
        ab, bc, cd, de, ef, fa, be = (g.addLine(a, b), g.addLine(b, c), g.addLine(c, d), g.addLine(d, e), g.addLine(e, f),
                                      g.addLine(f, a), g.addLine(b, e))
        s1 = g.addPlaneSurface([g.addCurveLoop([ab, be, ef, fa])])
        s2 = g.addPlaneSurface([g.addCurveLoop([bc, cd, de, -be])])
        if interior_line:
            p, q = g.addPoint(0.1, 0.5, 0, 0.25), g.addPoint(0.4, 0.5, 0, 0.25)
            inner = g.addLine(p, q)
        g.synchronize()
        if interior_line:
            gmsh.model.mesh.embed(1, [inner], 2, s1)
            gmsh.model.addPhysicalGroup(1, [inner], 7)
            gmsh.model.setPhysicalName(1, 7, "inner")
        if recombine_right:
            gmsh.model.mesh.setRecombine(2, s2)
        for tag, lines in ((1, [ab, bc]), (2, [cd]), (3, [de, ef]), (4, [fa])):
            gmsh.model.addPhysicalGroup(1, lines, tag)
            gmsh.model.setPhysicalName(1, tag, NAMES[tag])
        gmsh.model.addPhysicalGroup(2, [s1, s2], 10)
        gmsh.model.mesh.generate(2)
        if order > 1:
            gmsh.model.mesh.setOrder(order)
        gmsh.write(path)
    finally:
        gmsh.finalize()


def write_named_square(path):
    """The unit square in triangles, its sides named bottom (1), right (2), top (3), left (4)."""
    _square(path)


def write_mixed(path):
    _square(path, recombine_right=True)


def write_second_order(path):
    _square(path, order=2)


def write_interior_group(path):
    _square(path, interior_line=True)


def write_duplicate_cell(path):
    """The 4 x 4 square of harness.write_gmsh_square() with its last triangle listed a second time."""
    write_gmsh_square(path, 4)
    lines = open(path).read().split("\n")
    i = lines.index("$Elements")
    n = int(lines[i + 1])
    last = lines[i + 1 + n].split()
    lines.insert(i + 2 + n, " ".join([str(n + 1)] + last[1:]))
    lines[i + 1] = str(n + 1)
    with open(path, "w") as fh:
        fh.write("\n".join(lines))
