"""Gmsh geometries for contact problems (Gmsh's Python API, Debian's python3-gmsh): bodies that touch a rigid plane at
one point, meshed finer toward that point, with physical groups (numbered and named) that the solver reads as
"Face Sets" values through -dm_plex_filename.

Every shape rests on the plane {x_d = 0} and touches it at the origin (or, for the blocks, is indented there); the mesh
size is h_near at the origin, grows as h_near + grade r up to the distance near from it (grade 0: constant), and then
linearly to h_far over the distance width. A grade makes the cells across a contact zone of radius a about as many at
every a inside near: what a load path, whose zone grows from small, needs at every step.
"""
import contextlib
import os

import gmsh

# "Face Sets" values, as PETSc numbers the faces of its boxes (2D: bottom 1, top 3; 3D: bottom 1, top 2, front y = 0 3,
# left x = 0 6), so that the built-in scenes (Gamma_C = 1, clamped top) run on these meshes as they are
HALF_DISK_GROUPS = {"contact": 1, "top": 3}
QUARTER_DISK_GROUPS = {"contact": 1, "top": 3, "symmetry_x": 4}
QUARTER_SPHERE_GROUPS = {"contact": 1, "top": 2, "symmetry_y": 3, "symmetry_x": 6}
# the blocks indented from above: their top {x_d = 0} is Gamma_C
BLOCK_GROUPS = {"contact": 1, "bottom": 2, "symmetry_x": 4, "side": 5}
QUARTER_BLOCK_GROUPS = {"contact": 1, "bottom": 2, "symmetry_y": 3, "symmetry_x": 6, "side": 5}
BODY_GROUP = 10


def _size_field(h_near, h_far, width, dim, near=0.0, grade=0.0):
    """A mesh size field equal to h_near + grade r up to the distance near from the origin (r), then growing linearly
    to h_far over the distance width, used everywhere."""
    r = "Sqrt(x^2 + y^2)" if dim == 2 else "Sqrt(x^2 + y^2 + z^2)"
    h_edge = h_near + grade * near
    field = gmsh.model.mesh.field.add("MathEval")
    gmsh.model.mesh.field.setString(
        field, "F", f"Min({h_far!r}, {h_near!r} + {grade!r} * Min({r}, {near!r}) + ({h_far!r} - {h_edge!r}) * Max({r} - {near!r}, 0) / {width!r})")
    gmsh.model.mesh.field.setAsBackgroundMesh(field)
    for option in ("Mesh.MeshSizeExtendFromBoundary", "Mesh.MeshSizeFromPoints", "Mesh.MeshSizeFromCurvature"):
        gmsh.option.setNumber(option, 0)


def _entities_in_box(dim, lo, hi, eps):
    return [tag for _, tag in gmsh.model.getEntitiesInBoundingBox(lo[0] - eps, lo[1] - eps, lo[2] - eps, hi[0] + eps, hi[1] + eps, hi[2] + eps, dim)]


def _physical(dim, tags, tag, name):
    if not tags:
        raise ValueError(f"no entity of dimension {dim} for the physical group {name}")
    gmsh.model.addPhysicalGroup(dim, tags, tag)
    gmsh.model.setPhysicalName(dim, tag, name)


@contextlib.contextmanager
def _model(name):
    """A Gmsh session with one model, quiet; finalized whatever happens."""
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add(name)
        yield
    finally:
        gmsh.finalize()


def _groups():
    """Each physical group's dimension, tag and name, and the bounding boxes of its entities (sorted)."""
    out = {}
    for d, tag in gmsh.model.getPhysicalGroups():
        boxes = sorted(tuple(round(v, 9) for v in gmsh.model.getBoundingBox(d, e)) for e in gmsh.model.getEntitiesForPhysicalGroup(d, tag))
        out[(d, tag)] = (gmsh.model.getPhysicalName(d, tag), boxes)
    return out


def _write_model(model):
    """The geometry as a Gmsh model the solver remeshes (-adapt_model): the OpenCASCADE shape in model's .brep, and
    model, a .geo that merges it and names the physical groups, without any mesh size (the solver gives its own). A
    .brep read back numbers its entities anew, so the groups' entities are found again in it by their bounding boxes;
    the .geo is then read back and checked: the same groups of the same entities."""
    brep = os.path.splitext(model)[0] + ".brep"
    kind = {0: "Point", 1: "Curve", 2: "Surface", 3: "Volume"}
    groups = _groups()
    gmsh.write(brep)
    gmsh.clear()
    gmsh.merge(brep)
    lines = ["// The geometry of a mesh written by scripts/make_mesh.py, for the solver's remeshing (-adapt_model)",
             'SetFactory("OpenCASCADE");', f'Merge "{os.path.basename(brep)}";']
    for (d, tag), (name, boxes) in sorted(groups.items()):
        found = {tuple(round(v, 9) for v in gmsh.model.getBoundingBox(d, e)): e for _, e in gmsh.model.getEntities(d)}
        if any(b not in found for b in boxes):
            raise ValueError(f"the model {brep} read back lacks entities of the physical group {name}")
        entities = ", ".join(str(found[b]) for b in boxes)
        lines.append(f'Physical {kind[d]}("{name}", {tag}) = {{{entities}}};')
    with open(model, "w") as f:
        f.write("\n".join(lines) + "\n")
    gmsh.clear()
    gmsh.open(model)
    if _groups() != groups:
        raise ValueError(f"the model {model} read back does not give the same physical groups")


def _write(path, dim, h_near, h_far, width, near=0.0, grade=0.0, model=None):
    """The body's physical group, the size field, the mesh, and the file; with model, the geometry too."""
    _physical(dim, [tag for _, tag in gmsh.model.getEntities(dim)], BODY_GROUP, "body")
    _size_field(h_near, h_far, width, dim, near, grade)
    gmsh.model.mesh.generate(dim)
    gmsh.write(path)
    if model:
        _write_model(model)


def _check(radius, h_far, h_near, width, near=0.0, grade=0.0):
    for name, value in (("radius", radius), ("h_far", h_far), ("h_near", h_near), ("width", width)):
        if not value > 0:
            raise ValueError(f"{name} must be positive, got {value}")
    if not 0 <= near < radius:
        raise ValueError(f"near must lie in [0, radius), got {near}")
    if not grade >= 0:
        raise ValueError(f"grade must be >= 0, got {grade}")
    if h_near > h_far:
        raise ValueError(f"h_near ({h_near}) must not exceed h_far ({h_far})")
    if h_near + grade * near > h_far:
        raise ValueError(f"the size at near, h_near + grade near ({h_near + grade * near:g}), must not exceed h_far ({h_far})")


def half_disk(path, radius=1.0, h_far=0.1, h_near=0.02, width=None, near=0.0, grade=0.0, model=None):
    """The lower half of the disk of the given radius centred at (0, radius): the arc (Gamma_C, "contact") touches the
    plane y = 0 at the origin, the flat top y = radius is "top". Triangles; writes a Gmsh .msh file at path."""
    width = radius / 2 if width is None else width
    _check(radius, h_far, h_near, width, near, grade)
    with _model("half_disk"):
        disk = gmsh.model.occ.addDisk(0, radius, 0, radius, radius)
        upper = gmsh.model.occ.addRectangle(-2 * radius, radius, 0, 4 * radius, 2 * radius)
        gmsh.model.occ.cut([(2, disk)], [(2, upper)])
        gmsh.model.occ.synchronize()
        eps = 1e-3 * radius  # OCC bounding boxes carry a tolerance
        top = _entities_in_box(1, (-radius, radius, 0), (radius, radius, 0), eps)
        curves = [tag for _, tag in gmsh.model.getEntities(1)]
        _physical(1, [c for c in curves if c not in top], HALF_DISK_GROUPS["contact"], "contact")
        _physical(1, top, HALF_DISK_GROUPS["top"], "top")
        _write(path, 2, h_near, h_far, width, near, grade, model)


def quarter_sphere(path, radius=1.0, h_far=0.2, h_near=0.05, width=None, near=0.0, grade=0.0, model=None):
    """The quarter of the lower half of the ball of the given radius centred at (0, 0, radius) with x >= 0 and y >= 0:
    the curved surface ("contact") touches the plane z = 0 at the origin, the flat top z = radius is "top", and the
    planes x = 0 and y = 0 are "symmetry_x" and "symmetry_y". Tetrahedra; writes a Gmsh .msh file at path."""
    width = radius / 2 if width is None else width
    _check(radius, h_far, h_near, width, near, grade)
    with _model("quarter_sphere"):
        ball = gmsh.model.occ.addSphere(0, 0, radius, radius)
        box = gmsh.model.occ.addBox(0, 0, 0, 2 * radius, 2 * radius, radius)
        gmsh.model.occ.intersect([(3, ball)], [(3, box)])
        gmsh.model.occ.synchronize()
        eps = 1e-3 * radius  # OCC bounding boxes carry a tolerance
        top = _entities_in_box(2, (0, 0, radius), (radius, radius, radius), eps)
        sym_x = _entities_in_box(2, (0, 0, 0), (0, radius, radius), eps)
        sym_y = _entities_in_box(2, (0, 0, 0), (radius, 0, radius), eps)
        surfaces = [tag for _, tag in gmsh.model.getEntities(2)]
        _physical(2, [s for s in surfaces if s not in top + sym_x + sym_y], QUARTER_SPHERE_GROUPS["contact"], "contact")
        _physical(2, top, QUARTER_SPHERE_GROUPS["top"], "top")
        _physical(2, sym_y, QUARTER_SPHERE_GROUPS["symmetry_y"], "symmetry_y")
        _physical(2, sym_x, QUARTER_SPHERE_GROUPS["symmetry_x"], "symmetry_x")
        _write(path, 3, h_near, h_far, width, near, grade, model)


def quarter_disk(path, radius=1.0, h_far=0.1, h_near=0.02, width=None, near=0.0, grade=0.0, model=None):
    """The half of the half-disk with x >= 0: the arc ("contact") touches the plane y = 0 at the origin, the flat top
    y = radius is "top", the plane x = 0 is "symmetry_x". Triangles; writes a Gmsh .msh file at path."""
    width = radius / 2 if width is None else width
    _check(radius, h_far, h_near, width, near, grade)
    with _model("quarter_disk"):
        disk = gmsh.model.occ.addDisk(0, radius, 0, radius, radius)
        box = gmsh.model.occ.addRectangle(0, 0, 0, 2 * radius, radius)
        gmsh.model.occ.intersect([(2, disk)], [(2, box)])
        gmsh.model.occ.synchronize()
        eps = 1e-3 * radius
        top = _entities_in_box(1, (0, radius, 0), (radius, radius, 0), eps)
        sym_x = _entities_in_box(1, (0, 0, 0), (0, radius, 0), eps)
        curves = [tag for _, tag in gmsh.model.getEntities(1)]
        _physical(1, [c for c in curves if c not in top + sym_x], QUARTER_DISK_GROUPS["contact"], "contact")
        _physical(1, top, QUARTER_DISK_GROUPS["top"], "top")
        _physical(1, sym_x, QUARTER_DISK_GROUPS["symmetry_x"], "symmetry_x")
        _write(path, 2, h_near, h_far, width, near, grade, model)


def block(path, radius=1.0, h_far=0.1, h_near=0.02, width=None, near=0.0, grade=0.0, model=None):
    """The rectangle [0, radius] x [-radius, 0], to be indented at the origin from above: its top y = 0 is "contact",
    its bottom "bottom", x = 0 "symmetry_x", x = radius "side". Triangles; writes a Gmsh .msh file at path."""
    width = radius / 2 if width is None else width
    _check(radius, h_far, h_near, width, near, grade)
    with _model("block"):
        gmsh.model.occ.addRectangle(0, -radius, 0, radius, radius)
        gmsh.model.occ.synchronize()
        eps = 1e-3 * radius
        groups = {"contact": _entities_in_box(1, (0, 0, 0), (radius, 0, 0), eps),
                  "bottom": _entities_in_box(1, (0, -radius, 0), (radius, -radius, 0), eps),
                  "symmetry_x": _entities_in_box(1, (0, -radius, 0), (0, 0, 0), eps),
                  "side": _entities_in_box(1, (radius, -radius, 0), (radius, 0, 0), eps)}
        for name, tags in groups.items():
            _physical(1, tags, BLOCK_GROUPS[name], name)
        _write(path, 2, h_near, h_far, width, near, grade, model)


def quarter_block(path, radius=1.0, h_far=0.2, h_near=0.05, width=None, near=0.0, grade=0.0, model=None):
    """The box [0, radius]^2 x [-radius, 0], to be indented at the origin from above: its top z = 0 is "contact", its
    bottom "bottom", x = 0 "symmetry_x", y = 0 "symmetry_y", the faces x = radius and y = radius "side". Tetrahedra."""
    width = radius / 2 if width is None else width
    _check(radius, h_far, h_near, width, near, grade)
    with _model("quarter_block"):
        gmsh.model.occ.addBox(0, 0, -radius, radius, radius, radius)
        gmsh.model.occ.synchronize()
        eps = 1e-3 * radius
        r = radius
        groups = {"contact": _entities_in_box(2, (0, 0, 0), (r, r, 0), eps),
                  "bottom": _entities_in_box(2, (0, 0, -r), (r, r, -r), eps),
                  "symmetry_x": _entities_in_box(2, (0, 0, -r), (0, r, 0), eps),
                  "symmetry_y": _entities_in_box(2, (0, 0, -r), (r, 0, 0), eps),
                  "side": _entities_in_box(2, (r, 0, -r), (r, r, 0), eps) + _entities_in_box(2, (0, r, -r), (r, r, 0), eps)}
        for name, tags in groups.items():
            _physical(2, tags, QUARTER_BLOCK_GROUPS[name], name)
        _write(path, 3, h_near, h_far, width, near, grade, model)


SHAPES = {"half-disk": half_disk, "quarter-disk": quarter_disk, "quarter-sphere": quarter_sphere, "block": block, "quarter-block": quarter_block}
