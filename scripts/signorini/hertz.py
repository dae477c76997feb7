"""Hertz contact against the closed form (../shared/notes/verification.md, section 4): the four set-ups on the Gmsh
geometries of geometry.py, the command line of each run, and the measurement of the contact half-width a, the peak
pressure p0 and the total force from a run's HDF5 file.

Closed forms, with E* = E / (1 - nu^2) (one elastic body against a rigid one):
  2D (plane strain, per unit length, load P):  a = 2 sqrt(P R / (pi E*)),  p0 = 2 P / (pi a)
  3D (load F):                                 a = (3 F R / (4 E*))^(1/3),  p0 = 3 F / (2 pi a^2),  approach a^2 / R
and p(r) = p0 sqrt(1 - r^2 / a^2). Each run is displacement driven; P or F is the force the run measures (the obstacle's
total force on the modelled part times the number of symmetric parts), and a, p0 are compared at that force.

How a is measured: from the nodal contact forces f_i (the vertex field contact_reaction, -R . n with R = K u + r0),
by the ratio of the second moment to the total, which for the Hertz pressure is a^2 / 4 in 2D and 2 a^2 / 5 in 3D:
  a_h = 2 sqrt(sum f_i r_i^2 / sum f_i)  (2D),   a_h = sqrt(5/2 sum f_i r_i^2 / sum f_i)  (3D),
with r_i the distance of node i from the axis of symmetry. How p0 is measured: the nodal tractions f_i / m_i (m_i the
node's lumped boundary mass, contact_area) are fitted, inside r < 0.8 a_h, by the Hertz profile p0 sqrt(1 - r^2 / a^2)
(a linear least-squares fit of p^2 against r^2). Their largest value is reported too (p0_max): on tetrahedra the nodal
tractions scatter by a few percent from node to node, and the largest is that scatter's top, not the peak. The penalty
law at a node, (1/eps)[u . n - g]_+, is not used: with the Gauss rule at small eps it oscillates from node to node (+32%
at eps = h/100 on the coarse sphere), while the reaction, an integral, does not.
"""
import math

import h5py
import numpy as np

from . import geometry
from .paths import BIN
from .runs import field_at

YOUNG, POISSON, RADIUS = 1.0, 0.3, 1.0


def e_star(young=YOUNG, poisson=POISSON):
    return young / (1.0 - poisson * poisson)


def closed_form(dim, load, radius=RADIUS, young=YOUNG, poisson=POISSON):
    """(a, p0) of the Hertz solution at the load P (2D, per unit length) or F (3D)."""
    es = e_star(young, poisson)
    if dim == 2:
        a = 2.0 * math.sqrt(load * radius / (math.pi * es))
        return a, 2.0 * load / (math.pi * a)
    a = (3.0 * load * radius / (4.0 * es)) ** (1.0 / 3.0)
    return a, 3.0 * load / (2.0 * math.pi * a * a)


def pressure_profile(r, a, p0):
    return p0 * np.sqrt(np.clip(1.0 - (np.asarray(r) / a) ** 2, 0.0, None))


# Each case: the mesh (a geometry.py shape), the copies of the modelled part in the whole body (symmetry), whether
# SNESVI applies (a flat foundation: the normal is an axis at every node), the imposed displacement, and the options.
CASES = {
    "cylinder": {
        "dim": 2, "shape": geometry.quarter_disk, "parts": 2, "near": 0.06, "h_far": 0.05, "width": 0.3,
        "h_near": [0.004, 0.002, 0.001],
        "args": ["-scene", "general", "-contact_faces", "contact", "-bc_slip", "top,symmetry_x",
                 "-bc_slip_top_components", "1", "-bc_slip_top_translate", "0,-0.002", "-bc_slip_symmetry_x_components", "0"],
        "what": "elastic cylinder (quarter disk, radius 1) pressed on a rigid plane by a displacement 0.002 of its axis plane",
    },
    "sphere": {
        "dim": 3, "shape": geometry.quarter_sphere, "parts": 4, "near": 0.15, "h_far": 0.2, "width": 0.4,
        "h_near": [0.02, 0.01, 0.005],
        "args": ["-scene", "general", "-contact_faces", "contact", "-bc_slip", "top,symmetry_x,symmetry_y",
                 "-bc_slip_top_components", "2", "-bc_slip_top_translate", "0,0,-0.01", "-bc_slip_symmetry_x_components", "0",
                 "-bc_slip_symmetry_y_components", "1"],
        "what": "elastic sphere (quarter sphere, radius 1) pressed on a rigid plane by a displacement 0.01 of its equator plane",
    },
    "cylinder-indenter": {
        "dim": 2, "shape": geometry.block, "parts": 2, "near": 0.06, "h_far": 0.05, "width": 0.3,
        "h_near": [0.004, 0.002, 0.001],
        "args": ["-scene", "general", "-contact_faces", "contact", "-bc_clamp", "bottom", "-bc_slip", "symmetry_x",
                 "-bc_slip_symmetry_x_components", "0", "-obstacle", "cylinder", "-obstacle_center", "0,1", "-obstacle_radius", "1",
                 "-obstacle_translate", "0,-0.001"],
        "what": "rigid cylinder (radius 1) indenting an elastic block [0,1] x [-1,0] (clamped bottom) by 0.001",
    },
    "sphere-indenter": {
        "dim": 3, "shape": geometry.quarter_block, "parts": 4, "near": 0.2, "h_far": 0.15, "width": 0.5,
        "h_near": [0.02, 0.01, 0.007],
        "args": ["-scene", "general", "-contact_faces", "contact", "-bc_clamp", "bottom", "-bc_slip", "symmetry_x,symmetry_y",
                 "-bc_slip_symmetry_x_components", "0", "-bc_slip_symmetry_y_components", "1", "-obstacle", "sphere",
                 "-obstacle_center", "0,0,1", "-obstacle_radius", "1", "-obstacle_translate", "0,0,-0.01"],
        "what": "rigid sphere (radius 1) indenting an elastic block [0,1]^2 x [-1,0] (clamped bottom) by 0.01",
    },
}

# How far Hertz's closed form is from the model the solver solves on make hertz's own bodies (radius 1, the unit
# block), relative: the fitted a's and p0's offsets of make hertz-curvature at R = 1 (+0.25% and -0.23%; docs/hertz.md).
# Errors below it are not known against the closed form (in a block 10 times larger the offset is about 0.02%).
CLOSED_FORM_ACCURACY = 2.5e-3

# The remeshed 3D cases' solver: GAMG with its aggregates on the unfiltered graph; the carried solutions' penalty rows
# broke gamg.yaml's threshold 0.01 down on the sphere (docs/estimate.md, "Remeshing the Gmsh model")
GAMG_3D = ["-options_file", "options/solvers/gamg.yaml", "-pc_gamg_threshold", "0"]

METHODS = {  # label: solver options
    "eps=h": ["-contact_method", "penalty", "-penalty_eps0", "1"],
    "eps=h/10": ["-contact_method", "penalty", "-penalty_eps0", "0.1"],
    "eps=h/100": ["-contact_method", "penalty", "-penalty_eps0", "0.01"],
    "vi": ["-contact_method", "vi"],
}


def write_mesh(case, h_near, path, **size):
    """The case's mesh at h_near; size: its other size parameters (near, width, h_far, grade) where not the case's."""
    c = CASES[case]
    kw = {"h_far": c["h_far"], "width": c["width"], "near": c["near"], **size}
    c["shape"](path, radius=RADIUS, h_near=h_near, **kw)


def case_args(case, radius=RADIUS):
    """The case's options; an indenter's with its rigid body's radius set to radius and its depth d to d RADIUS / radius,
    which keeps the contact zone's a ~ (R d)^(1/2) (in 2D about: the block's compliance holds a logarithm), so that
    only the obstacle's curvature, a / R, changes: Hertz's closed form neglects the terms of order a / R (the obstacle's
    normal leaning by r / R, along which the contact acts; docs/hertz.md, "How close the closed form holds")."""
    args = list(CASES[case]["args"])
    if radius == RADIUS:
        return args
    if "-obstacle_radius" not in args:
        raise ValueError(f"{case}: a rigid obstacle's radius only (the elastic bodies are meshed at radius {RADIUS:g})")
    dim = CASES[case]["dim"]
    args[args.index("-obstacle_radius") + 1] = repr(float(radius))
    args[args.index("-obstacle_center") + 1] = ",".join(["0"] * (dim - 1) + [repr(float(radius))])
    i = args.index("-obstacle_translate") + 1
    args[i] = ",".join(repr(float(v) * RADIUS / radius) if float(v) else "0" for v in args[i].split(","))
    return args


def command(case, mesh, method, output, ranks=1, mpiexec="mpiexec", radius=RADIUS, poisson=POISSON):
    """The mpiexec command line of one run; radius: an indenter's (case_args())."""
    return ([mpiexec, "-n", str(ranks), BIN, "-dm_plex_filename", mesh, "-young_modulus", str(YOUNG), "-poisson_ratio",
             str(poisson)] + case_args(case, radius) + METHODS[method] + ["-output", output])


def measure(case, path, step=None, radius=RADIUS, poisson=POISSON):
    """What a run gives against the closed form: a dict with the load, a, p0 (measured and closed form), their relative
    errors, the force balance (|obstacle force + supports' reactions| / obstacle force, along the pressing axis), and the
    contact nodes. step: of a load path's output, the step's (0-based: its row of /steps and its slab of the time
    series) instead of the last. radius, poisson: the run's (command()). Raises ValueError if the run has no contact.
    The moments take the nodes within twice the run's zone (its contact_size): beyond it the reactions are the linear
    solve's residual, about 1e-13 on the 2D indenter at 1.7M unknowns, whose r^2 up to 10^2 against a^2 = 3e-4 moved
    a_h by -0.5% and +2% there."""
    c = CASES[case]
    dim = c["dim"]
    axis = "xyz"[dim - 1]
    at = -1 if step is None else step
    with h5py.File(path, "r") as f:
        run = {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f["run"].attrs.items()}
        if step is not None:  # the step's quantities, from its row of /steps
            run.update({k: float(np.ravel(f["steps"][k][:])[step]) for k in f["steps"]})
        x = f["geometry/vertices"][:]
        force = field_at(f["vertex_fields/contact_reaction"], at).ravel()
        pressure = field_at(f["vertex_fields/contact_pressure"], at).ravel()
        boundary = field_at(f["vertex_fields/contact_boundary"], at).ravel() > 0
        area = f["vertex_fields/contact_area"][:].ravel()
    r2 = (x[:, 0] ** 2) if dim == 2 else (x[:, 0] ** 2 + x[:, 1] ** 2)
    size = float(run.get("contact_size", 0.0))  # the half-width in 2D, the quarter zone's area in 3D
    if size > 0:
        zone = size if dim == 2 else math.sqrt(4.0 * size / math.pi)
        boundary &= r2 <= (2.0 * zone) ** 2
    m0 = float(np.sum(force[boundary]))
    if not m0 > 0:
        raise ValueError(f"{path}: no contact force")
    m2 = float(np.sum(force[boundary] * r2[boundary]))
    a_h = 2.0 * math.sqrt(m2 / m0) if dim == 2 else math.sqrt(2.5 * m2 / m0)
    obstacle = float(run[f"contact_force_{axis}"])
    supports = sum(float(v) for k, v in run.items() if k.startswith("reaction_") and k.endswith(f"_{axis}"))
    load = c["parts"] * abs(obstacle)
    a, p0 = closed_form(dim, load, radius, poisson=poisson)
    traction = np.where(area[boundary] > 0, force[boundary] / np.where(area[boundary] > 0, area[boundary], 1.0), 0.0)
    p0_h, a_fit = fit_profile(r2[boundary], traction, a_h)
    return {"load": load, "a": a, "a_h": a_h, "a_error": a_h / a - 1.0, "p0": p0, "p0_h": p0_h, "p0_error": p0_h / p0 - 1.0,
            "a_fit": a_fit, "p0_max": float(np.max(traction)), "p0_max_error": float(np.max(traction)) / p0 - 1.0,
            "balance": abs(obstacle + supports) / abs(obstacle), "contact_nodes": int(np.sum(force[boundary] > 0)),
            "converged": int(run.get("converged", 0)), "time_total": float(run.get("time_total", float("nan"))),
            "n_dofs": int(run.get("n_dofs", 0)), "eps_min": float(run.get("eps_min", 0.0)),
            "radius_sq": r2[boundary], "pressure": traction}


def quantity_exact(case, force, radius=RADIUS):
    """The closed form of -accuracy's contact quantities at the force the run's modelled part takes: the largest
    pressure p0 and the contact zone's size, its half-width a in 2D (the modelled half of the zone) and the area of the
    zone's quarter, pi a^2 / 4, in 3D."""
    c = CASES[case]
    a, p0 = closed_form(c["dim"], c["parts"] * abs(force), radius)
    return {"pressure_max": p0, "contact_size": a if c["dim"] == 2 else math.pi * a * a / 4}


def quantity_errors(case, attrs, force_ref, radius=RADIUS, quantities=("contact_force", "pressure_max", "contact_size")):
    """Relative errors of a run's -accuracy quantities (its /run attributes), in the order of quantities: the largest
    pressure (pressure_max, nodal, or pressure_peak, recovered) and the size against the closed form at the run's force
    (quantity_exact()), and the force against force_ref."""
    axis = "xyz"[CASES[case]["dim"] - 1]
    force = abs(float(attrs[f"contact_force_{axis}"]))
    exact = quantity_exact(case, force, radius)
    errors = {"contact_force": force / force_ref - 1, "contact_size": float(attrs["contact_size"]) / exact["contact_size"] - 1}
    for q in ("pressure_max", "pressure_peak"):  # the nodal maximum and the recovered peak (src/physics/pressure_peak.c)
        if q in quantities:
            errors[q] = float(attrs[q]) / exact["pressure_max"] - 1
    return {q: errors[q] for q in quantities}


def fit_profile(radius_sq, traction, a_h, inner=0.8):
    """(p0, a) of the Hertz profile fitted to the nodal tractions inside r < inner a_h: p^2 = p0^2 - (p0 / a)^2 r^2 is
    linear in r^2, so the fit is a linear least-squares one; it averages the node-to-node scatter of the tractions."""
    sel = radius_sq < (inner * a_h) ** 2
    if np.count_nonzero(sel) < 3:
        return float("nan"), float("nan")
    design = np.column_stack([np.ones(np.count_nonzero(sel)), -radius_sq[sel]])
    (p0_sq, slope), *_ = np.linalg.lstsq(design, traction[sel] ** 2, rcond=None)
    if not (p0_sq > 0 and slope > 0):
        return float("nan"), float("nan")
    return math.sqrt(p0_sq), math.sqrt(p0_sq / slope)


def mesh_name(case, h_near):
    return f"{case}_h{h_near:g}.msh"


def output_name(case, h_near, method):
    label = method.replace("=", "").replace("/", "_")
    return f"{case}_h{h_near:g}_{label}.h5"


# Hertz along a load path (scripts/hertz_path.py, make hertz-path): the two indenters, driven by the obstacle's
# translation in PATH_STEPS equal steps, each step measured as a run at its force, eps = h/100. The contact zone grows
# from a third of its final radius (a ~ sqrt(R d)), so a mesh fine enough at the last step is too coarse at the first:
# the cylinder's is make hertz's finest (h_near 0.001, 30 cells across a at the first step), the sphere's is graded,
# h = 0.0015 + 0.05 r up to r = 0.15 (about 10 cells across a at the first step, 15 at the last; make hertz's finest,
# h_near 0.007, had 4.5 at the first step and missed 1% there by 2.0%), solved with GAMG (28,744 unknowns).
PATH_MESHES = {"cylinder-indenter": {"h_near": 0.001},
               "sphere-indenter": {"h_near": 0.0015, "grade": 0.05, "near": 0.15, "width": 1.0,
                                   "solver": ["-options_file", "options/solvers/gamg.yaml"]}}
PATH_CASES = list(PATH_MESHES)
PATH_METHOD = "eps=h/100"
PATH_STEPS = 10
# The half-space's force-depth law F = (4/3) E* R^(1/2) d^(3/2) holds while a is small against the body: the block of
# depth 1 (clamped at its bottom) is stiffer by a term linear in a (F / F_half-space = 1.008 + 1.11 a on the path's
# sphere mesh), which raises the local exponent by about (1/2) 1.11 a: 0.03 at a = 0.055. The exponent is fitted over
# the steps with a <= SMALL_CONTACT (in units of the block's depth).
SMALL_CONTACT = 0.07


def path_mesh_name(case):
    m = PATH_MESHES[case]
    return f"{case}_h{m['h_near']:g}" + (f"_grade{m['grade']:g}_near{m['near']:g}_width{m['width']:g}" if "grade" in m else "") + ".msh"


def write_path_mesh(case, path):
    """The load path's mesh of the case (PATH_MESHES)."""
    m = {k: v for k, v in PATH_MESHES[case].items() if k != "solver"}
    write_mesh(case, m.pop("h_near"), path, **m)


def path_rows(case, path):
    """One row per step of a load path's output of the Hertz case: the step, its factor, the indentation depth (the
    obstacle's translation along its motion), the load and measure()'s a, p0 and their errors at the step's force."""
    from .history import history
    steps = history(path)
    rows = []
    for k in range(len(steps["factor"])):
        m = measure(case, path, step=k)
        rows.append({"case": case, "step": k + 1, "factor": float(steps["factor"][k]), "depth": float(steps["depth"][k]),
                     "load": m["load"], "a": m["a"], "a_h": m["a_h"], "a_error": m["a_error"], "p0": m["p0"], "p0_h": m["p0_h"],
                     "p0_error": m["p0_error"], "newton_its": int(steps["newton_its"][k]), "converged": int(steps["converged"][k])})
    return rows


def force_depth_exponent(rows, a_max=None):
    """The exponent of the load against the depth, fitted over the steps (log-log least squares) whose measured a is at
    most a_max (all steps without it): 3/2 for a sphere on a half-space, F = (4/3) E* R^(1/2) d^(3/2). NaN with fewer
    than 2 such steps."""
    sel = [r for r in rows if a_max is None or r["a_h"] <= a_max]
    if len(sel) < 2:
        return float("nan")
    d = np.array([r["depth"] for r in sel])
    F = np.array([r["load"] for r in sel])
    return float(np.polyfit(np.log(d), np.log(F), 1)[0])


def half_space_ratio(rows):
    """Each step's load over the half-space's at its depth, (4/3) E* R^(1/2) d^(3/2), and the straight line through
    them against the closed form's a: (intercept, slope). The intercept is the ratio at a -> 0, where the block is a
    half-space: 1 up to the discretization."""
    d = np.array([r["depth"] for r in rows])
    ratio = np.array([r["load"] for r in rows]) / (4.0 / 3.0 * e_star() * math.sqrt(RADIUS) * d**1.5)
    slope, intercept = np.polyfit(np.array([r["a"] for r in rows]), ratio, 1)
    return ratio, float(intercept), float(slope)
