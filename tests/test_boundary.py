"""Boundary conditions by face set (-contact_faces, -bc_clamp, -bc_slip, -bc_traction, -bc_pressure, -body_force) in the
scene general: patch tests reproduced to round-off (slip and a traction or a pressure balancing a uniaxial stress, a
clamp's translation), the supports' reactions, the built-in scenes as defaults of the options, Gmsh names for numbers,
local eps on graded meshes, and every bad input refused by name before any solve, with no output written."""
import os
import sys

import numpy as np
import pytest

from harness import ROOT, load, run, sorted_by_position

sys.path.insert(0, os.path.join(ROOT, "scripts"))
from signorini import geometry  # noqa: E402

E, NU = 2.0, 0.3
FAR = {2: ["-obstacle_point", "0,-1"], 3: ["-obstacle_point", "0,0,-1"]}  # the foundation out of reach


def uniaxial(dim, s, lift):
    """The exact displacement of the uniaxial stress sigma_xx = s with u_x = 0 at x = 0, the transverse components 0 on
    their symmetry faces, and u_d = lift on the top face x_d = 1 (plane strain in 2D)."""
    if dim == 2:
        exx, eyy = (1 - NU**2) * s / E, -NU * (1 + NU) * s / E
        return lambda x: np.column_stack([exx * x[:, 0], eyy * (x[:, 1] - 1) + lift])
    exx, ett = s / E, -NU * s / E
    return lambda x: np.column_stack([exx * x[:, 0], ett * x[:, 1], ett * (x[:, 2] - 1) + lift])


def patch_args(dim, load_kind, s, lift):
    """Left face x = 0 slips along x (component 0 fixed), the top face slips with u_d = lift, the right face x = 1
    carries the traction (s, 0[, 0]) or the pressure -s; in 3D the front y = 0 slips along y. Gamma_C is the bottom."""
    base = ["-scene", "general", "-young_modulus", E, "-poisson_ratio", NU, "-contact_faces", "1", "-snes_rtol", "1e-12"] + FAR[dim]
    if dim == 2:
        right, slips = "2", ["-bc_slip", "4,3", "-bc_slip_4_components", "0", "-bc_slip_3_components", "1", "-bc_slip_3_translate", f"0,{lift}"]
        box = ["-dm_plex_box_faces", "4,4"]
    else:
        right = "5"
        slips = ["-bc_slip", "6,3,2", "-bc_slip_6_components", "0", "-bc_slip_3_components", "1", "-bc_slip_2_components", "2",
                 "-bc_slip_2_translate", f"0,0,{lift}"]
        box = ["-dm_plex_dim", "3", "-dm_plex_box_faces", "3,3,3"]
    if load_kind == "traction":
        loads = ["-bc_traction", right, f"-bc_traction_{right}", ",".join([str(s)] + ["0"] * (dim - 1))]
    else:
        loads = ["-bc_pressure", right, f"-bc_pressure_{right}", str(-s)]
    return base + box + slips + loads


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("load_kind", ["traction", "pressure"])
def test_patch_slip_and_surface_load(outdir, dim, load_kind):
    """A traction (or a pressure) on the right face balancing sigma_xx = s, slips on the symmetry faces and a slip with a
    translation on top: the linear exact field, reproduced to round-off, and the left support pulls with -s on area 1."""
    s, lift = 0.05, 0.01
    _, h5 = run(patch_args(dim, load_kind, s, lift), "patch", output=os.path.join(outdir, "patch.h5"))
    attrs, fields = load(h5)
    exact = uniaxial(dim, s, lift)(fields["x"])
    err = np.max(np.abs(fields["displacement"] - exact))
    assert err < 1e-12 * np.max(np.abs(exact)) + 1e-15, f"patch test error {err:.3e}"
    assert attrs["active_vertices"] == 0
    left = "4" if dim == 2 else "6"
    assert abs(attrs[f"reaction_slip_{left}_x"] + s) < 1e-10, attrs[f"reaction_slip_{left}_x"]
    # the potential energy 1/2 a(u, u) - L(u) = 1/2 s exx - s exx (the load s on the right face, of area 1, moves by exx);
    # the top's lift carries no load and no stress (it follows the free contraction)
    exx = (1 - NU**2) * s / E if dim == 2 else s / E
    assert abs(attrs["energy"] + 0.5 * s * exx) < 1e-12 * s * exx, (attrs["energy"], -0.5 * s * exx)


@pytest.mark.parametrize("np_", [1, 2])
def test_energy_with_a_lift_and_a_body_force(outdir, np_):
    """The potential energy J(u_h) = 1/2 a(u_h, u_h) - L(u_h) with Dirichlet data that are not zero, by hand: nu = 0, a
    body force b along y, slips u_y = 0 at y = 0 and u_y = d at y = 1, u_x = 0 at x = 0. The solution is 1D,
    u_y = d y + b/(2E) y (1 - y), with J(u) = E d^2/2 - b d/2 - b^2/(24 E); P1 is exact at the nodes (1D Galerkin), and
    J(u_h) - J(u) = 1/2 a(u - u_h, u - u_h) = b^2 h^2 / (24 E) on n rows of height h = 1/n. The free unknowns alone
    (1/2 w.K w + w.r0) miss J(u_D), which grows like 1/h: they gave -0.00087, -0.00134, -0.00218 on 4, 8, 16 rows
    against -0.000595, -0.000605, -0.000608."""
    d, b = 0.01, 0.1
    for n in (4, 8, 16):
        args = ["-scene", "general", "-dm_plex_box_faces", f"{n},{n}", "-young_modulus", E, "-poisson_ratio", 0, "-contact_faces", "2",
                "-obstacle_point", "2,0", "-obstacle_normal", "1,0", "-bc_slip", "1,3,4", "-bc_slip_1_components", "1",
                "-bc_slip_3_components", "1", "-bc_slip_3_translate", f"0,{d}", "-bc_slip_4_components", "0", "-body_force", f"0,{b}",
                "-snes_rtol", "1e-12"]
        _, h5 = run(args, "energy", np_=np_, output=os.path.join(outdir, f"energy_{n}.h5"))
        attrs, _ = load(h5)
        expected = E * d * d / 2 - b * d / 2 - b * b / (24 * E) + b * b / (24 * E * n * n)
        assert attrs["active_vertices"] == 0
        assert abs(attrs["energy"] - expected) < 1e-10 * abs(expected), (n, attrs["energy"], expected)


@pytest.mark.parametrize("dim", [2, 3])
def test_clamp_translate(outdir, dim):
    """-bc_clamp_ID_translate with no load: the body moves rigidly by the translation, to round-off."""
    top = "3" if dim == 2 else "2"
    t = [0.01, -0.02, 0.03][:dim]
    args = ["-scene", "general", "-contact_faces", "1", "-bc_clamp", top, f"-bc_clamp_{top}_translate", ",".join(map(str, t))] + FAR[dim]
    args += ["-dm_plex_box_faces", "4,4"] if dim == 2 else ["-dm_plex_dim", "3", "-dm_plex_box_faces", "2,2,2"]
    _, h5 = run(args, "translate", output=os.path.join(outdir, "t.h5"))
    _, fields = load(h5)
    assert np.max(np.abs(fields["displacement"] - np.array(t))) < 1e-13


def test_square_scene_is_defaults_of_the_options(outdir):
    """The built-in square scene with its body force off and a -body_force equals the scene general given the square's
    face sets as options: same iterations, same displacement."""
    common = ["-dm_plex_box_faces", "16,16", "-body_force", "0.5,-1"]
    _, a = run(["-scene", "square", "-square_beta", "0"] + common, "square", output=os.path.join(outdir, "square.h5"))
    _, b = run(["-scene", "general", "-contact_faces", "1", "-bc_clamp", "3"] + common, "general", output=os.path.join(outdir, "general.h5"))
    (ra, fa), (rb, fb) = load(a), load(b)
    assert ra["newton_its"] == rb["newton_its"] and ra["active_vertices"] == rb["active_vertices"] > 0
    assert np.max(np.abs(fa["displacement"] - fb["displacement"])) < 1e-14


@pytest.fixture(scope="module")
def quarter_disk(tmp_path_factory):
    path = str(tmp_path_factory.mktemp("meshes") / "quarter_disk.msh")
    geometry.quarter_disk(path, h_near=0.01, h_far=0.1, width=0.3, near=0.05)
    return path


HERTZ_2D = ["-scene", "general", "-contact_faces", "contact", "-bc_slip", "top,symmetry_x", "-bc_slip_top_components", "1",
            "-bc_slip_top_translate", "0,-0.002", "-bc_slip_symmetry_x_components", "0"]


def test_gmsh_names_equal_numbers(outdir, quarter_disk):
    """Physical group names stand for their "Face Sets" values: the same run by names and by numbers."""
    by_number = ["-scene", "general", "-contact_faces", "1", "-bc_slip", "3,4", "-bc_slip_3_components", "1", "-bc_slip_3_translate", "0,-0.002",
                 "-bc_slip_4_components", "0"]
    _, a = run(["-dm_plex_filename", quarter_disk] + HERTZ_2D, "names", output=os.path.join(outdir, "names.h5"))
    _, b = run(["-dm_plex_filename", quarter_disk] + by_number, "numbers", output=os.path.join(outdir, "numbers.h5"))
    ra, fa = load(a)
    rb, fb = load(b)
    assert ra["active_vertices"] > 2 and ra["active_vertices"] == rb["active_vertices"]
    assert np.array_equal(fa["displacement"], fb["displacement"])


def test_local_eps(outdir, quarter_disk):
    """On a graded mesh eps follows the local cell size (/run eps_min < eps_max, the largest at the run's h); with
    -penalty_eps_local 0 it is one value, and the answers differ; on a uniform box the range is one value."""
    _, a = run(["-dm_plex_filename", quarter_disk] + HERTZ_2D, "local", output=os.path.join(outdir, "local.h5"))
    _, b = run(["-dm_plex_filename", quarter_disk, "-penalty_eps_local", "0"] + HERTZ_2D, "global", output=os.path.join(outdir, "global.h5"))
    ra, rb = load(a)[0], load(b)[0]
    assert ra["eps_min"] < 0.5 * ra["eps_max"] and ra["eps_max"] <= ra["eps"] * (1 + 1e-12)
    assert rb["eps_min"] == rb["eps_max"] == rb["eps"]
    assert abs(ra["contact_force"] / rb["contact_force"] - 1) > 1e-3
    _, c = run(["-dm_plex_box_faces", "8,8", "-penalty_quadrature", "nodal"], "uniform", output=os.path.join(outdir, "uniform.h5"))
    rc = load(c)[0]
    assert abs(rc["eps_min"] / rc["eps"] - 1) < 1e-12 and abs(rc["eps_max"] / rc["eps"] - 1) < 1e-12
    # the tetrahedra of a 3D box differ in diameter by rounding only: one eps (the graded mesh's log names its range)
    log_a, _ = run(["-dm_plex_filename", quarter_disk] + HERTZ_2D, "local_log", output=os.path.join(outdir, "local_log.h5"))
    log_d, d = run(["-dm_plex_dim", 3, "-dm_plex_box_faces", "5,5,5", "-penalty_quadrature", "gauss"], "uniform3d",
                   output=os.path.join(outdir, "uniform3d.h5"))
    rd = load(d)[0]
    assert ", local " in log_a and ", local " not in log_d, log_d[:400]
    assert rd["eps_min"] != rd["eps_max"] and abs(rd["eps_max"] / rd["eps_min"] - 1) < 1e-12  # rounding, but not equal


BAD = [  # (options after a valid general set-up on the unit square, a fragment of the message)
    (["-bc_clamp", "7"], "no face of the mesh carries \"Face Sets\" value 7"),
    (["-bc_clamp", "1"], "Face set 1 is listed twice"),
    (["-bc_clamp", "top"], "'top' is neither a \"Face Sets\" value nor the name of a physical group"),
    (["-bc_clamp", "3", "-bc_clamp_3_translate", "1,2,3"], "-bc_clamp_3_translate needs 2 comma-separated values"),
    (["-bc_clamp", "3", "-bc_clamp_3_tanslate", "1,2"], "-bc_clamp_3_tanslate"),
    (["-bc_clamp", "3", "-bc_slip", "4"], "-bc_slip 4 needs -bc_slip_4_components"),
    (["-bc_clamp", "3", "-bc_slip", "4", "-bc_slip_4_components", "2"], "component 2 is outside 0..1"),
    (["-bc_clamp", "3", "-bc_slip", "4", "-bc_slip_4_components", "0,1"], "fixes fewer than 2 components"),
    (["-bc_clamp", "3", "-bc_traction", "2"], "-bc_traction 2 needs -bc_traction_2"),
    (["-bc_clamp", "3", "-bc_pressure", "2"], "-bc_pressure 2 needs -bc_pressure_2"),
    (["-bc_clamp", "3", "-bc_pressure", "2", "-bc_pressure_2", "nan"], "-bc_pressure_2 must be a finite number"),
    (["-bc_clamp", "3", "-body_force", "1"], "-body_force needs 2 comma-separated values"),
    (["-bc_slip", "3", "-bc_slip_3_components", "1"], "leave 1 rigid motion(s) free (mostly: translation along x)"),
    (["-bc_traction", "3", "-bc_traction_3", "0,-1"], "leave 3 rigid motion(s) free"),
    (["-bc_clamp", "3", "-obstacle", "sphere", "-obstacle_center", "0.5,2"], "-obstacle sphere needs a positive -obstacle_radius"),
    (["-bc_clamp", "3", "-obstacle", "sphere", "-obstacle_radius", "1"], "-obstacle sphere needs -obstacle_center"),
    (["-bc_clamp", "3", "-obstacle_normal", "0,0"], "-obstacle_normal must not be the zero vector"),
    (["-bc_clamp", "3", "-obstacle", "plane", "-obstacle_radius", "1"], "-obstacle_radius"),
]


@pytest.mark.parametrize("extra,message", BAD, ids=[" ".join(b[0]) for b in BAD])
def test_bad_boundary_input(outdir, extra, message):
    out = os.path.join(outdir, "bad.h5")
    contact = [] if any(e in ("-contact_faces",) for e in extra) else ["-contact_faces", "1"]
    text, _ = run(["-scene", "general", "-dm_plex_box_faces", "4,4"] + contact + extra, "bad", expect_rc=None, output=out)
    assert message in " ".join(text.split()), text[-2000:]
    assert "signorini: error: " in text and "PETSC ERROR" not in text and not os.path.exists(out) and not os.path.exists(out[:-3] + ".xdmf")


def test_no_contact_faces_refused(outdir):
    out = os.path.join(outdir, "bad.h5")
    text, _ = run(["-scene", "general", "-bc_clamp", "3"], "bad", expect_rc=None, output=out)
    assert "Scene general has no contact boundary: give its face sets with -contact_faces" in text and not os.path.exists(out)


def test_cylinder_options_file(outdir, quarter_disk):
    """options/cylinder.yaml, the README's example of a problem stated in an options file, on a coarse quarter disk:
    converged, in contact, and the obstacle's force balancing the top's reaction."""
    out = os.path.join(outdir, "c.h5")  # after the options file, which names its own output
    _, h5 = run(["-options_file", "options/cylinder.yaml", "-dm_plex_filename", quarter_disk, "-output", out], "cylinder", output=out)
    attrs = load(h5)[0]
    assert attrs["converged"] == 1 and attrs["active_vertices"] > 2 and attrs["obstacle"] == "plane"
    assert abs(attrs["contact_force_y"] + attrs["reaction_slip_top_y"]) < 1e-10 * attrs["contact_force_y"]


@pytest.mark.parametrize("np_", [1, 2])
@pytest.mark.parametrize("case", ["slips_2d", "slips_3d", "clamp_quads", "clamp_hexes", "mms", "disk_names"])
def test_p1_section_is_petscs(outdir, quarter_disk, case, np_):
    """src/discretization/section.c builds the P1/Q1 section itself (the Dirichlet components constrained face set by face set,
    several on one vertex at the corners); -section_check also has DMCreateLocalSection() build it and compares the two
    with PetscSectionCompare() (dofs, offsets, constraint counts and indices, the field's too); the global section and the
    section SF built over the vertices (src/discretization/section_global.c) are compared with PETSc's, the SF graph entry by entry."""
    args = {"slips_2d": patch_args(2, "traction", 0.05, 0.01), "slips_3d": patch_args(3, "pressure", 0.05, 0.01),
            "clamp_quads": ["-dm_plex_simplex", 0, "-dm_plex_box_faces", "5,4"],
            "clamp_hexes": ["-dm_plex_dim", 3, "-dm_plex_simplex", 0, "-dm_plex_box_faces", "2,3,2"],
            "mms": ["-scene", "mms", "-dm_plex_box_faces", "6,5"],
            "disk_names": HERTZ_2D + ["-dm_plex_filename", quarter_disk]}[case]
    log, h5 = run(args + ["-section_check"], f"section_{case}_np{np_}", np_=np_, output=os.path.join(outdir, f"section_{case}_np{np_}.h5"))
    assert log.count("section check: the P1 section is equal to DMCreateLocalSection()'s") == 1, log[-2000:]
    assert log.count("section check: the global section is equal to PetscSectionCreateGlobalSection()'s, "
                     "the section SF equal to PetscSFSetGraphSection()'s") == 1, log[-2000:]
    assert load(h5)[0]["converged"] == 1


@pytest.mark.parametrize("order", ["6,3,2", "3,6,2", "2,3,6"])
def test_each_slip_reacts_only_along_what_it_fixes(outdir, order):
    """The 3D patch test with its three slips listed in any order: the planes x = 0 (u_x fixed), y = 0 (u_y) and the
    top (u_z) share the nodes of their edges, and each set's reaction has only its fixed component, the uniaxial
    stress's -s along x on x = 0 and zero on the others, whatever the order. Before, the first listed set took every
    fixed component of a shared node: listed 3,6,2, the plane y = 0 pushed along x with a part of x = 0's reaction."""
    s = 0.05
    args = patch_args(3, "traction", s, 0.01)
    args[args.index("6,3,2")] = order
    _, h5 = run(args, "slip_order", output=os.path.join(outdir, f"slip_{order}.h5"))
    attrs, _ = load(h5)
    for ident, comp in (("6", "x"), ("3", "y"), ("2", "z")):
        for other in "xyz":
            if other != comp:
                assert attrs[f"reaction_slip_{ident}_{other}"] == 0.0, (ident, other, attrs[f"reaction_slip_{ident}_{other}"])
    assert abs(attrs["reaction_slip_6_x"] + s) < 1e-10, attrs["reaction_slip_6_x"]
    assert abs(attrs["reaction_slip_3_y"]) < 1e-10 and abs(attrs["reaction_slip_2_z"]) < 1e-10
