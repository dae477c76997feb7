"""The study of the a posteriori estimate (make estimates, docs/estimate.md): its effectivity on the manufactured
solutions, its penalty part against the distance to SNESVI, and where its indicator is largest on Hertz."""
import math

import h5py
import numpy as np

from . import geometry, hertz
from .runs import decoded_attrs

# Refinement series on the manufactured solution: (label, dim, solver arguments, mesh sizes)
SIZES_2D = [16, 32, 64, 128, 256]
# nested, as the 2D series (non-nested sizes made the observed rates jump with the kink's place in the cells); 3D from 6
# cells across (4^3 was pre-asymptotic at nu = 0.49), to 48^3 with GAMG (MUMPS's factors of 48^3 take 10 GB)
SIZES_3D = [6, 12, 24, 48]
SOLVER_3D = ["-options_file", "options/solvers/gamg.yaml", "-dual_ksp_type", "cg", "-dual_pc_type", "gamg", "-dual_ksp_rtol", "1e-12"]
SERIES = []
for _dim, _sizes in ((2, SIZES_2D), (3, SIZES_3D)):
    for _nu in (0.3, 0.49):
        for _eps0 in (1, 0.01):
            SERIES.append((f"mms{_dim}d nu={_nu} eps=h" + ("" if _eps0 == 1 else "/100"), _dim,
                           ["-poisson_ratio", str(_nu), "-penalty_eps0", str(_eps0)] + (SOLVER_3D if _dim == 3 else []), _sizes))
    # SNESVI's reduced systems change size, which GAMG cannot follow: MUMPS, to 32^3 in 3D (3.9 GB)
    SERIES.append((f"mms{_dim}d nu=0.3 SNESVI", _dim, ["-contact_method", "vi"], _sizes if _dim == 2 else [4, 8, 16, 32]))
    # the solution's regularity (u in H^(3/2 + r)) on either side of the shipped r = 1/2: at r = 0.3 the pointwise body
    # force is not square-integrable, which the estimate's divergence-form load is for
    for _reg in (0.3, 1.0):
        SERIES.append((f"mms{_dim}d nu=0.3 regularity={_reg:g} eps=h", _dim, ["-mms_nu", str(_reg)] + (SOLVER_3D if _dim == 3 else []), _sizes))

EPS0_LADDER = [1, 0.1, 0.01, 0.001]  # the penalty part against SNESVI, eps = h to h/1000
PENALTY_MESHES = {2: 64, 3: 8}

PARTS = ["bulk", "jump", "neumann", "contact_normal", "contact_tangential", "penalty"]  # estimate_PART of /run
ASYMPTOTIC = 4  # the finest meshes of a series over which the effectivity's spread and the rates are measured


def box(dim, n):
    return ["-dm_plex_dim", str(dim), "-dm_plex_box_faces", ",".join([str(n)] * dim)]


def mms_command(dim, n, args, output, reference=None):
    return (["bin/signorini", "-scene", "mms"] + box(dim, n) + list(args) + (["-reference", reference] if reference else [])
            + ["-output", output])


def read(path):
    with h5py.File(path, "r") as f:
        return decoded_attrs(f["run"])


def series_summary(rows):
    """Effectivity spread and rates over the ASYMPTOTIC finest meshes of one series (rows sorted by h, coarse first)."""
    fine = rows[-ASYMPTOTIC:]
    h = np.array([r["h"] for r in fine])
    est = np.array([r["estimate_total"] for r in fine])
    err = np.array([r["error_energy"] for r in fine])
    eff = est / err
    return {"eff_min": float(eff.min()), "eff_max": float(eff.max()), "eff_spread": float(eff.max() / eff.min()),
            "rate_estimate": float(np.polyfit(np.log(h), np.log(est), 1)[0]),
            "rate_error": float(np.polyfit(np.log(h), np.log(err), 1)[0])}


def cell_geometry(path):
    """(centroids, diameters, error_indicator, error_density) of the cells of an output."""
    with h5py.File(path, "r") as f:
        X, cells = f["geometry/vertices"][:], f["viz/topology/cells"][:]
        eta, dens = f["cell_fields/error_indicator"][:], f["cell_fields/error_density"][:]
    P = X[cells]
    cen = P.mean(axis=1)
    nv = P.shape[1]
    diam = np.max([np.linalg.norm(P[:, i] - P[:, j], axis=1) for i in range(nv) for j in range(i)], axis=0)
    return cen, diam, eta, dens


def hertz_peak(case, path, top=10):
    """Where the error density is largest on a Hertz run: the distance of each of the `top` densest cells' centroids
    from the contact zone's edge (the points |x| = a, x_d = 0 in 2D, the circle r = a, x_d = 0 in 3D: every Hertz case
    touches at the origin), in units of the cell's diameter; a is the run's (hertz.measure's a_h). Returns (measure,
    distances)."""
    dim = hertz.CASES[case]["dim"]
    m = hertz.measure(case, path)
    cen, diam, _, dens = cell_geometry(path)
    r = np.abs(cen[:, 0]) if dim == 2 else np.hypot(cen[:, 0], cen[:, 1])
    order = np.argsort(dens)[::-1][:top]
    dist = np.hypot(r[order] - m["a_h"], cen[order, dim - 1])
    return m, dist / diam[order]


# The coverage of the error bars (-bars): runs whose quantities have a known value. The manufactured solution in 2D
# (the box's coarser levels) and 3D (-contact_grid_sequence 2 from the box of the options), and the two Hertz indenters,
# whose flat block is refined without changing its geometry (the curved bodies of the other two Hertz cases are
# faceted on the coarse mesh, which a uniform refinement keeps: their bars cannot see that error). The closed form is a
# half-space's, and the bars measure the discretization of the body's own problem: on make hertz's unit block the
# 2D indenter's a and p0 settle 0.2% from the closed form as h and eps fall (docs/hertz.md), more than the bars of these
# meshes, so the indenters are pressed here into a block 10 times larger (BLOCK, the far field's cells 10 times larger
# too), where that gap fell to 0.02% (eps = h/100, h_near = 0.001: a -0.012%, p0 -0.016%).
COVERAGE_MMS = [(2, 32, []), (2, 64, []), (2, 128, []), (3, 4, ["-contact_grid_sequence", "2"] + SOLVER_3D),
                (3, 8, ["-contact_grid_sequence", "2"] + SOLVER_3D)]
COVERAGE_HERTZ = [("cylinder-indenter", "eps=h/10"), ("sphere-indenter", "eps=h/10")]
# -bars with the body's Gmsh model (-adapt_model): make hertz's curved bodies from their file mesh at h_near, the levels
# the model remeshed at halved sizes; the 3D sphere's with GAMG
COVERAGE_REMESHED = [("cylinder", "vi", 0.006), ("cylinder", "eps=h/10", 0.006), ("cylinder", "vi", 0.003), ("cylinder", "eps=h/10", 0.003),
                     ("cylinder", "vi", 0.024), ("cylinder", "eps=h/10", 0.024), ("sphere", "eps=h/10", 0.04)]
MMS_QUANTITIES = ["contact_force", "pressure_max", "contact_size", "energy"]


def eps_over_1000(args):
    """The options that take the run of args to eps/1000 on the same mesh (the last -penalty_eps0 wins): the limit
    eps -> 0 of its quantities, against which the bars' penalty part is measured."""
    eps0 = float(args[len(args) - 1 - args[::-1].index("-penalty_eps0") + 1]) if "-penalty_eps0" in args else 1.0
    return ["-penalty_eps0", f"{eps0 * 1e-3:g}"]
BLOCK = 10.0  # the indenters' block, [0, BLOCK] x [-BLOCK, 0] (2D) or [0, BLOCK]^2 x [-BLOCK, 0] (3D)


def write_block_mesh(case, h_near, path, size=BLOCK):
    """The Hertz indenter's block of the given size, graded as make hertz's from h_near at the contact to size x h_far."""
    spec = hertz.CASES[case]
    spec["shape"](path, radius=size, h_far=spec["h_far"] * size, h_near=h_near, width=spec["width"], near=spec["near"])


# The 2D indenter's block graded by hand (make accuracy-ladder, make work-precision): (h_near, grade G) of the size
# h_near + G r around the contact point, up to 0.5
INDENTER_GRADES = [(0.002, 0.1), (0.001, 0.1), (0.001, 0.05), (0.0005, 0.05), (0.0005, 0.02), (0.00025, 0.02)]


def write_graded_block(path, h_near, grade, h_far=0.5):
    """The 2D block of size BLOCK graded from h_near at the contact point by G r up to h_far."""
    near = min(0.98 * (h_far - h_near) / grade, 0.9 * BLOCK)
    geometry.block(path, radius=BLOCK, h_far=h_far, h_near=h_near, grade=grade, near=near, width=min(2.0, 0.95 * BLOCK - near))


def pressure_band_coverage(path):
    """The pressure's band (contact_pressure_bar) against the manufactured solution's pressure at the nodes of Gamma_C:
    (nodes whose error is above 1e-3 of the peak, how many of them the band covers, the median of band / error there)."""
    from .exact import mms_from_run
    with h5py.File(path, "r") as f:
        x = f["geometry/vertices"][:]
        on = f["vertex_fields/contact_boundary"][:].ravel() > 0.5
        p = f["vertex_fields/contact_pressure"][:].ravel()[on]
        band = f["vertex_fields/contact_pressure_bar"][:].ravel()[on]
        attrs = decoded_attrs(f["run"])
    exact = -mms_from_run(attrs).normal_stress(x[on, 0], attrs["young_modulus"], attrs["poisson_ratio"])
    err = np.abs(p - exact)
    large = err > 1e-3 * exact.max()
    return int(large.sum()), int(np.sum(err[large] <= band[large])), float(np.median(band[large] / err[large]))


def qoi(attrs, name):
    """(value, bar) of qoi_NAME (bar NaN where there is none)."""
    return float(attrs[f"qoi_{name}"]), float(attrs.get(f"qoi_{name}_bar", float("nan")))


def size_bar_is_its_floor(attrs):
    """Whether the zone's size's mesh part is the final mesh's one-cell band along the edge: its resolution, which the
    bar takes where the levels' differences are smaller (src/estimate/bars.c), not a measured convergence."""
    return float(attrs.get("qoi_contact_size_bar_mesh", float("nan"))) == float(attrs["contact_size_band"])


def hertz_truth(case, attrs):
    """The closed form at the run's force: {quantity: (qoi name, its exact value)} for the contact size (a half-width of
    the half model in 2D, a quarter disk pi a^2 / 4 in 3D) and the largest pressure p0."""
    spec = hertz.CASES[case]
    dim = spec["dim"]
    axis = "xyz"[dim - 1]
    force = spec["parts"] * abs(float(attrs.get(f"qoi_contact_force_{axis}", attrs[f"contact_force_{axis}"])))
    a, p0 = hertz.closed_form(dim, force)
    return {"contact_size": ("contact_size", a if dim == 2 else math.pi * a * a / 4), "pressure_max": ("pressure_max", p0)}
