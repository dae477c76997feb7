"""The study of the a posteriori estimate (make estimates, docs/estimate.md): its effectivity on the manufactured
solutions, its penalty part against the distance to SNESVI, and where its indicator is largest on Hertz."""
import h5py
import numpy as np

from . import hertz
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
    SERIES.append((f"mms{_dim}d nu=0.3 SNESVI", _dim, ["-contact_method", "vi"] + (SOLVER_3D if _dim == 3 else []), _sizes))

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
