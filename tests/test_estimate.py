"""The a posteriori error estimate (make test; issue 31): the estimator recomputed independently from the output file, its
effectivity on the manufactured solutions (stable over meshes and Poisson ratios), its penalty part against the distance
to SNESVI, the same numbers on two ranks, the cell fields in the HDF5 and XDMF files (read back by ParaView's own reader),
and the refusal of a discretization it does not cover.

Every number asserted is computed by the solver; the tolerances can fail (docs/estimate.md has the measured values)."""
import os
import subprocess

import h5py
import numpy as np
import pytest

from harness import OUT, load, run, solve

PARTS = ["bulk", "jump", "neumann", "contact_normal", "contact_tangential", "penalty"]
GL3 = (np.array([-np.sqrt(0.6), 0.0, np.sqrt(0.6)]) + 1) / 2, np.array([5, 8, 5]) / 18  # 3-point Gauss-Legendre on [0, 1]


def estimate_of(h5):
    a, _ = load(h5)
    return a["estimate_total"], {p: a["estimate_" + p] for p in PARTS}, a


def python_estimate(h5, beta=2.0, x0=0.6):
    """The estimator of src/estimate/ recomputed from the output of the square scene (2D P1, Gauss rule, flat foundation
    y = 0, clamped top, free sides, body force f = (0, beta (x - x0))): the squared parts."""
    a, _ = load(h5)
    with h5py.File(h5) as f:
        X, cells, U = f["geometry/vertices"][:], f["viz/topology/cells"][:], f["vertex_fields/displacement"][:]
        eta_file = f["cell_fields/error_indicator"][:]
    E, nu, eps = a["young_modulus"], a["poisson_ratio"], a["eps"]
    mu, lam = E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))
    M, S = lam + 2 * mu, 2 * mu

    def wsq(R, n):  # |R.n|^2 / (lambda + 2 mu) + |R_t|^2 / (2 mu)
        rn = R @ n
        return rn ** 2 / M + (R @ R - rn ** 2) / S

    parts = dict.fromkeys(PARTS, 0.0)
    faces = {}
    sigmas = []
    A = B = 0.0
    for c, tri in enumerate(cells):
        x = X[tri]
        J = np.array([x[1] - x[0], x[2] - x[0]]).T
        G = np.linalg.inv(J)  # rows: grad lambda_1, grad lambda_2
        dl = np.vstack([-G.sum(axis=0), G])
        gu = U[tri].T @ dl
        eps_u = 0.5 * (gu + gu.T)
        sig = lam * np.trace(eps_u) * np.eye(2) + 2 * mu * eps_u
        sigmas.append(sig)
        area = abs(np.linalg.det(J)) / 2
        hT = max(np.linalg.norm(x[i] - x[j]) for i in range(3) for j in range(i))
        # body force: f_y = beta (x - x0), f^2 quadratic, integrated exactly by the edge-midpoint rule
        mids = [(x[0] + x[1]) / 2, (x[1] + x[2]) / 2, (x[2] + x[0]) / 2]
        ff = area * np.mean([(beta * (m[0] - x0)) ** 2 for m in mids])
        parts["bulk"] += hT ** 2 * ff / M
        for k in range(3):  # the face opposite vertex k
            i, j = [v for v in range(3) if v != k]
            n = -dl[k] / np.linalg.norm(dl[k])
            faces.setdefault(tuple(sorted((tri[i], tri[j]))), []).append((c, n, hT))
    for (vi, vj), adj in faces.items():
        L = np.linalg.norm(X[vi] - X[vj])
        if len(adj) == 2:
            Jv = sigmas[adj[0][0]] @ adj[0][1] + sigmas[adj[1][0]] @ adj[1][1]
            parts["jump"] += L * L * wsq(Jv, adj[0][1])
            continue
        c, n, hT = adj[0]
        sn = sigmas[c] @ n
        ym = (X[vi, 1] + X[vj, 1]) / 2
        if ym > 1 - 1e-12:
            continue  # clamped
        if ym > 1e-12:
            parts["neumann"] += L * L * wsq(-sn, n)  # free sides
            continue
        no = np.array([0.0, -1.0])  # Gamma_C on y = 0: u . n - g = -u_y
        rn = rt = dd = gd = 0.0
        v = -U[[vi, vj], 1]
        grad2 = (v[1] - v[0]) ** 2 / L ** 2
        for s, w in zip(*GL3):
            d = (1 - s) * v[0] + s * v[1]
            p = max(d, 0.0) / eps
            R = sn + p * no
            rn += w * L * (R @ no) ** 2
            rt += w * L * (R @ R - (R @ no) ** 2)
            dd += w * L * max(d, 0.0) ** 2
            gd += w * L * grad2 * (d > 0)
        parts["contact_normal"] += L * rn / M
        parts["contact_tangential"] += L * rt / S
        A += dd
        B += gd
    parts["penalty"] = 0.5 * E / (1 - nu ** 2) * np.sqrt(A * B)
    return parts, eta_file


def test_estimator_recomputed_from_the_output():
    """Every part of the estimate, and the sum of the cells' squared indicators, equal an independent computation from
    the output file (numpy, the same formulas: docs/estimate.md) to round-off."""
    _, h5 = run(["-options_file", "options/square.yaml", "-contact_monitor", "false", "-dm_plex_box_faces", "12,12"], "estimate_square")
    total, parts, _ = estimate_of(h5)
    ref, eta = python_estimate(h5)
    for p in PARTS:
        assert ref[p] > 0, p
        assert abs(parts[p] ** 2 - ref[p]) <= 1e-10 * ref[p], (p, parts[p] ** 2, ref[p])
    assert abs(total ** 2 - sum(ref.values())) <= 1e-10 * total ** 2
    assert abs(np.sum(eta ** 2) - total ** 2) <= 1e-10 * total ** 2


def series(args, sizes, name):
    rows = []
    for n in sizes:
        _, h5 = run(["-scene", "mms", "-dm_plex_box_faces", n] + args, f"{name}_{n.split(',')[0]}")
        total, _, a = estimate_of(h5)
        rows.append((a["h"], total, a["error_energy"]))
    return np.array(rows)


def test_effectivity_is_stable_on_the_manufactured_solution():
    """2D mms on four meshes: effectivity = estimate / exact energy-norm error in a band about the measured 2.46 to 2.51
    (1.5 to 3.5: above 1, a reliable estimate, and a change of the estimator by half fails it), varying by at most 1.5x,
    and the estimate converging at the exact error's observed rate within 0.1."""
    r = series([], ["16,16", "32,32", "64,64", "128,128"], "estimate_mms")
    eff = r[:, 1] / r[:, 2]
    assert np.all((eff > 1.5) & (eff < 3.5)), eff
    assert eff.max() / eff.min() <= 1.5, eff
    rate_est = np.polyfit(np.log(r[:, 0]), np.log(r[:, 1]), 1)[0]
    rate_err = np.polyfit(np.log(r[:, 0]), np.log(r[:, 2]), 1)[0]
    assert abs(rate_est - rate_err) <= 0.1, (rate_est, rate_err)


@pytest.mark.parametrize("dim,sizes", [(2, ["16,16", "32,32", "64,64", "128,128"]), (3, ["8,8,8", "12,12,12", "16,16,16"])])
def test_effectivity_is_stable_on_a_rough_manufactured_solution(dim, sizes):
    """The manufactured solution of regularity nu = 0.3 (u in H^(1.8 - delta)), not shipped: its pointwise body force
    |x_1 - a|^(nu - 1) is not square-integrable, so the estimate takes its load in divergence form, the oscillation of
    G = sigma(u_exact) about its cells' means (docs/estimate.md). The effectivity varies by at most 1.5x over the meshes
    and stays above 1 (measured 2.1 to 2.3 in 2D, 2.82 to 2.87 in 3D; with h_T ||f||_T it swung 11.1, 5.1, 8.9 in 3D)."""
    r = series(["-dm_plex_dim", dim, "-mms_nu", 0.3], sizes, f"estimate_rough{dim}d")
    eff = r[:, 1] / r[:, 2]
    assert np.all(eff > 1.2), eff
    assert eff.max() / eff.min() <= 1.5, eff


def test_effectivity_does_not_depend_on_the_poisson_ratio():
    """Nearly incompressible (nu = 0.49, lambda = 49 mu): the effectivity stays within 1.5x of nu = 0.3's, because the
    normal tractions are weighted by lambda + 2 mu (with 2 mu alone it grew 3.6-fold: docs/estimate.md)."""
    eff = []
    for nu in (0.3, 0.49):
        _, h5 = run(["-scene", "mms", "-dm_plex_box_faces", "32,32", "-poisson_ratio", nu], f"estimate_nu{nu}")
        total, _, a = estimate_of(h5)
        eff.append(total / a["error_energy"])
    assert max(eff) / min(eff) <= 1.5, eff


def test_effectivity_in_3d():
    """The 3D mms on 4^3 and 8^3: the effectivity in a band about the measured 2.91 and 3.04 (2 to 4.5)."""
    r = series(["-dm_plex_dim", "3"], ["4,4,4", "8,8,8"], "estimate_mms3d")
    eff = r[:, 1] / r[:, 2]
    assert np.all((eff > 2) & (eff < 4.5)), eff


@pytest.mark.parametrize("rule", ["nodal", "gauss"])
def test_penalty_part_follows_the_distance_to_snesvi(rule):
    """At a fixed mesh, the penalty part of the estimate against the energy-norm distance of the penalty solution to
    SNESVI's (the -reference norms) from eps = h to h/1000: between 1 and 1.7 at every eps (measured: 1.29 to 1.38)."""
    _, vi = run(["-scene", "mms", "-dm_plex_box_faces", "32,32", "-contact_method", "vi"], f"estimate_vi_{rule}")
    for eps0 in (1, 0.01, 0.001):
        _, h5 = run(["-scene", "mms", "-dm_plex_box_faces", "32,32", "-penalty_quadrature", rule, "-penalty_eps0", eps0, "-reference", vi],
                    f"estimate_pen_{rule}_{eps0}")
        _, parts, a = estimate_of(h5)
        ratio = parts["penalty"] / a["reference_error_energy"]
        assert 1.0 <= ratio <= 1.7, (eps0, ratio)


def test_same_estimate_on_two_ranks():
    args = ["-options_file", "options/square.yaml", "-contact_monitor", "false", "-dm_plex_box_faces", "24,24"]
    _, h1 = run(args, "estimate_np1")
    _, h2 = run(args, "estimate_np2", np_=2)
    t1, p1, _ = estimate_of(h1)
    t2, p2, _ = estimate_of(h2)
    assert abs(t1 - t2) <= 1e-10 * t1
    for p in PARTS:
        assert abs(p1[p] - p2[p]) <= 1e-10 * t1, p
    with h5py.File(h1) as f1, h5py.File(h2) as f2:  # the same cells: sorted indicators equal
        e1, e2 = np.sort(f1["cell_fields/error_indicator"][:]), np.sort(f2["cell_fields/error_indicator"][:])
    assert e1.shape == e2.shape and np.max(np.abs(e1 - e2)) <= 1e-10 * e1.max()


def test_cell_fields_open_in_paraview(tmp_path):
    """ParaView's XDMF reader (pvbatch) finds error_indicator and error_density as cell data of every cell, and with
    -bars the pressure's band contact_pressure_bar as point data of every vertex, with the HDF5 file's values."""
    _, h5 = run(["-options_file", "options/square.yaml", "-contact_monitor", "false", "-bars"], "estimate_paraview")
    xdmf = h5[:-3] + ".xdmf"
    script = tmp_path / "read.py"
    script.write_text(
        "from paraview.simple import XDMFReader\n"
        "from paraview import servermanager as sm\n"
        f"r = XDMFReader(FileNames=[{xdmf!r}])\n"
        "r.UpdatePipeline()\n"
        "d = sm.Fetch(r)\n"
        "cd = d.GetCellData()\n"
        "for name in ('error_indicator', 'error_density'):\n"
        "    a = cd.GetArray(name)\n"
        "    print(name, d.GetNumberOfCells(), a.GetNumberOfTuples(), *a.GetRange())\n"
        "a = d.GetPointData().GetArray('contact_pressure_bar')\n"
        "print('contact_pressure_bar', d.GetNumberOfPoints(), a.GetNumberOfTuples(), *a.GetRange())\n")
    p = subprocess.run(["pvbatch", "--force-offscreen-rendering", str(script)], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                       timeout=300)
    assert p.returncode == 0, p.stdout[-3000:]
    with h5py.File(h5) as f:
        for name in ("error_indicator", "error_density", "contact_pressure_bar"):
            v = f[("vertex_fields/" if name == "contact_pressure_bar" else "cell_fields/") + name][:]
            line = [ln.split() for ln in p.stdout.splitlines() if ln.startswith(name + " ")]
            assert line, p.stdout[-2000:]
            ncells, ntuples, lo, hi = int(line[0][1]), int(line[0][2]), float(line[0][3]), float(line[0][4])
            assert ncells == ntuples == v.size
            assert abs(lo - v.min()) <= 1e-12 * v.max() and abs(hi - v.max()) <= 1e-12 * v.max()


def test_unsupported_discretization():
    """P2 and quadrilaterals: without -estimate the run goes on and says why there is no estimate (in the summary and
    /run estimate_unavailable, no cell field); with -estimate it is refused before the solve (exit 2, nothing written)."""
    for name, args, why in (("p2", ["-displacement_petscspace_degree", 2], "P1, not P2"), ("q1", ["-dm_plex_simplex", 0], "quadrilaterals")):
        text, h5 = run(["-scene", "mms", "-dm_plex_box_faces", "8,8"] + args, f"estimate_{name}")
        assert "error estimate: none" in text and why in text, text
        a, _ = load(h5)
        assert why in a["estimate_unavailable"] and "estimate_total" not in a
        with h5py.File(h5) as f:
            assert "cell_fields" not in f
        out = os.path.join(OUT, f"estimate_{name}_refused.h5")
        rc, text = solve(["-scene", "mms", "-dm_plex_box_faces", "8,8", "-estimate"] + args, output=out)
        assert rc == 2 and "-estimate" in text and why in text, text
        assert not os.path.exists(out)


def test_estimate_false():
    _, h5 = run(["-options_file", "options/square.yaml", "-contact_monitor", "false", "-estimate", "false"], "estimate_off")
    a, _ = load(h5)
    assert not any(k.startswith("estimate") for k in a)
