"""Closed forms and accurate quadrature for checking the solver independently of its C code.

    MMS                 the manufactured Signorini solution of verification.md section 2 (scene mms): u and grad u
    mms_from_run        its parameters as the /run attributes of an output file record them (scene_0..3 = nu, a, A, B)
    read_p1_mesh        vertices, simplex cells and the P1 displacement of an HDF5 output
    p1_error_norms      ||u - u_h||_L2 and |u - u_h|_H1 of a P1 field on a simplex mesh against a closed form,
                        integrated slice by slice along x_1 so that a kink at x_1 = a is resolved (see below)
    plane_strain_lame   lambda, mu of (E, nu), 2D plane strain and 3D alike

The quadrature (p1_error_norms): the exact solutions handled here depend on x_1 through non-smooth profiles
(s_+^p, s = x_1 - a) and polynomially on the other coordinates. On a simplex the error integrand is then a polynomial
of degree <= 2 in the other coordinates on every slice x_1 = const, integrated exactly on the slice (Gauss on a segment in
2D, a degree-2 triangle rule on the slice polygon in 3D), and the slices are integrated along x_1 by Gauss-Legendre on the
intervals between the cell's vertex abscissae and a. On an interval that ends at a the substitution
x_1 - a = L t^2 turns the half-integer powers of nu = 1/2 into polynomials in t, so the rule is exact there too (other nu:
the singularity is weakened to t^(2 nu + 1) and the rule converges fast). Nothing here uses the solver's own quadrature.
"""
import h5py
import numpy as np

_GL = {}


def gauss_legendre01(n):
    """Gauss-Legendre points and weights on [0, 1]."""
    if n not in _GL:
        x, w = np.polynomial.legendre.leggauss(n)
        _GL[n] = (0.5 * (x + 1.0), 0.5 * w)
    return _GL[n]


def plane_strain_lame(E, nu):
    """(lambda, mu) of Young's modulus and Poisson's ratio (2D is plane strain, so the 3D formulas hold)."""
    return E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))


class MMS:
    """u = (-x_d phi'(x_1), 0, ..., phi(x_1) + x_d psi(x_1)), phi = A s_+^(2+nu), psi = -B (-s)_+^(1+nu), s = x_1 - a
    (verification.md section 2; 3D: the same in (x, z))."""

    def __init__(self, nu, a, A=1.0, B=1.0, dim=2):
        self.nu, self.a, self.A, self.B, self.dim = float(nu), float(a), float(A), float(B), int(dim)
        self.p, self.q = 2.0 + self.nu, 1.0 + self.nu

    @staticmethod
    def _pow_plus(s, e):
        return np.where(s > 0.0, np.abs(s) ** e, 0.0)

    def profiles(self, x1):
        """phi, phi', phi'', psi, psi' at x1 (arrays)."""
        s = np.asarray(x1, dtype=float) - self.a
        A, B, p, q = self.A, self.B, self.p, self.q
        return (A * self._pow_plus(s, p), A * p * self._pow_plus(s, p - 1), A * p * (p - 1) * self._pow_plus(s, p - 2),
                -B * self._pow_plus(-s, q), B * q * self._pow_plus(-s, q - 1))

    def u(self, x):
        """u at the points x (n x dim)."""
        x = np.atleast_2d(x)
        d = self.dim - 1
        f0, f1, _, f3, _ = self.profiles(x[:, 0])
        out = np.zeros_like(x, dtype=float)
        out[:, 0] = -x[:, d] * f1
        out[:, d] = f0 + x[:, d] * f3
        return out

    def grad(self, x):
        """G[k, i, j] = du_i/dx_j at the points x (n x dim)."""
        x = np.atleast_2d(x)
        d = self.dim - 1
        _, f1, f2, f3, f4 = self.profiles(x[:, 0])
        G = np.zeros((len(x), self.dim, self.dim))
        G[:, 0, 0] = -x[:, d] * f2
        G[:, 0, d] = -f1
        G[:, d, 0] = f1 + x[:, d] * f4
        G[:, d, d] = f3
        return G

    def strain_energy(self, E, poisson, n=64):
        """1/2 a(u, u) over the unit box (times the unit depth in 3D, where u does not depend on y and u_y = 0, so that
        the strain is the 2D plane strain one): the kink x = a splits the x-integration, each part x - a = +-L t^2 from
        it (the profiles' powers 1 + nu of the distance are then smooth in t), Gauss-Legendre in x and y."""
        lam, mu = plane_strain_lame(E, poisson)
        t, w = gauss_legendre01(n)
        xs = np.concatenate([self.a - self.a * t * t, self.a + (1.0 - self.a) * t * t])
        wx = np.concatenate([2.0 * self.a * t * w, 2.0 * (1.0 - self.a) * t * w])
        X, Y = np.meshgrid(xs, t, indexing="ij")
        W = np.outer(wx, w).ravel()
        G = MMS(self.nu, self.a, self.A, self.B, 2).grad(np.column_stack([X.ravel(), Y.ravel()]))
        e = 0.5 * (G + G.transpose(0, 2, 1))
        tr = e[:, 0, 0] + e[:, 1, 1]
        return float(W @ (0.5 * lam * tr * tr + mu * np.einsum("kij,kij->k", e, e)))

    def normal_stress(self, x1, E, poisson):
        """sigma_n on Gamma_C = {x_d = 0}: (lambda + 2 mu) psi(x_1)."""
        lam, mu = plane_strain_lame(E, poisson)
        return (lam + 2 * mu) * self.profiles(x1)[3]


def mms_quantities(mms, E, poisson):
    """The quantities of the error bars (/run qoi_*) of the exact solution: the obstacle's force on the body (the pressure
    (lambda + 2 mu) B (a - x)^q integrated over [0, a], times the unit depth in 3D, along +x_d), the largest pressure
    (at x = 0), the contact zone's size (a: a width in 2D, a x 1 area in 3D), the penetration (none) and the energy.
    The energy: the scene's load is L(v) = a(u, v) - int_Gamma_C sigma_n(u) v_n (src/physics/weak_data.c), so that
    J(u) = 1/2 a(u, u) - L(u) = -1/2 a(u, u) + int_Gamma_C sigma_n u_n = -1/2 a(u, u), sigma_n u_n = 0 on Gamma_C."""
    lam, mu = plane_strain_lame(E, poisson)
    m = lam + 2 * mu
    axis = "xyz"[mms.dim - 1]
    q = {f"contact_force_{c}": 0.0 for c in "xyz"[: mms.dim]}
    q[f"contact_force_{axis}"] = m * mms.B * mms.a ** (mms.q + 1) / (mms.q + 1)
    q.update({"pressure_max": m * mms.B * mms.a ** mms.q, "contact_size": mms.a, "penetration_max": 0.0,
              "energy": -mms.strain_energy(E, poisson)})
    return q


def mms_from_run(attrs):
    """The MMS of a run of scene mms, from its /run attributes (scene_0..3 = nu, a, A, B; dim)."""
    assert attrs["scene"] == "mms", attrs["scene"]
    return MMS(attrs["scene_0"], attrs["scene_1"], attrs["scene_2"], attrs["scene_3"], int(attrs["dim"]))


def read_p1_mesh(path, field="displacement"):
    """(vertices n x d, cells m x (d+1) of vertex indices, the vertex field n x d) of an HDF5 output of a P1 simplex run."""
    with h5py.File(path, "r") as f:
        x = f["geometry/vertices"][:]
        cells = f["viz/topology/cells"][:].astype(int)
        u = f["vertex_fields"][field][:]
    d = x.shape[1]
    cells = cells.reshape(-1, d + 1)
    return x, cells, u.reshape(len(x), d)


def _slice_nodes(xs, a, n_smooth, n_kink):
    """Points and weights along x_1 for a cell spanning the sorted breakpoints xs (a among them if it cuts the cell)."""
    pts, wts = [], []
    for x0, x1 in zip(xs[:-1], xs[1:]):
        L = x1 - x0
        if L <= 1e-14 * max(1.0, abs(x1)):
            continue
        if x0 == a or x1 == a:  # x - a = +-L t^2 from the kink
            t, w = gauss_legendre01(n_kink)
            if x0 == a:
                pts.append(x0 + L * t * t)
            else:
                pts.append(x1 - L * t * t)
            wts.append(2.0 * L * t * w)
        else:
            t, w = gauss_legendre01(n_smooth)
            pts.append(x0 + L * t)
            wts.append(L * w)
    return np.concatenate(pts), np.concatenate(wts)


def _slice_2d(V, xq):
    """For a triangle V (3 x 2) and abscissae xq inside it: the lower and upper y of the vertical slices."""
    lo = np.full(len(xq), np.inf)
    hi = np.full(len(xq), -np.inf)
    for i, j in ((0, 1), (1, 2), (2, 0)):
        (xa, ya), (xb, yb) = V[i], V[j]
        if xa == xb:
            continue
        t = (xq - xa) / (xb - xa)
        ok = (t >= -1e-14) & (t <= 1 + 1e-14)
        y = ya + t * (yb - ya)
        lo = np.where(ok, np.minimum(lo, y), lo)
        hi = np.where(ok, np.maximum(hi, y), hi)
    return lo, hi


_TRI2 = (np.array([[1 / 6, 1 / 6], [2 / 3, 1 / 6], [1 / 6, 2 / 3]]), np.array([1 / 6, 1 / 6, 1 / 6]))  # degree 2, reference triangle


def _slice_3d(V, x1):
    """For a tetrahedron V (4 x 3) and an abscissa x1 inside it: points and weights in (x2, x3) of a rule exact for
    quadratics on the slice polygon."""
    P = []
    for i in range(4):
        for j in range(i + 1, 4):
            xa, xb = V[i, 0], V[j, 0]
            if (xa - x1) * (xb - x1) < 0.0:
                t = (x1 - xa) / (xb - xa)
                P.append(V[i, 1:] + t * (V[j, 1:] - V[i, 1:]))
    P = np.array(P)
    c = P.mean(axis=0)
    P = P[np.argsort(np.arctan2(P[:, 1] - c[1], P[:, 0] - c[0]))]
    pts, wts = [], []
    rp, rw = _TRI2
    for k in range(1, len(P) - 1):  # fan from P[0]; the slice is convex
        a, b, d = P[0], P[k], P[k + 1]
        J = np.column_stack((b - a, d - a))
        pts.append(a + rp @ J.T)
        wts.append(rw * abs(np.linalg.det(J)))
    return np.concatenate(pts), np.concatenate(wts)


def cell_points(V, a, n_smooth=10, n_kink=12):
    """Points and weights of the rule of the module's docstring on the simplex V ((d+1) x d)."""
    d = V.shape[1]
    xs = np.unique(V[:, 0])
    if xs[0] < a < xs[-1]:
        xs = np.unique(np.append(xs, a))
    xq, wq = _slice_nodes(xs, a, n_smooth, n_kink)
    if d == 2:
        lo, hi = _slice_2d(V, xq)
        t, w = gauss_legendre01(3)
        y = lo[:, None] + (hi - lo)[:, None] * t[None, :]
        pts = np.column_stack((np.repeat(xq, len(t)), y.ravel()))
        wts = (wq[:, None] * (hi - lo)[:, None] * w[None, :]).ravel()
        return pts, wts
    pts, wts = [], []
    for x1, w1 in zip(xq, wq):
        p, w = _slice_3d(V, x1)
        pts.append(np.column_stack((np.full(len(p), x1), p)))
        wts.append(w1 * w)
    return np.concatenate(pts), np.concatenate(wts)


def p1_error_norms(x, cells, uh, exact, n_smooth=10, n_kink=12):
    """{"l2": ||u - u_h||_0, "h1_semi": |u - u_h|_1} of the P1 field uh (vertex values) on the simplex mesh (x, cells)
    against exact (with .u, .grad and .a, the abscissa of its kink), integrated by the rule of cell_points()."""
    d = x.shape[1]
    s0 = s1 = 0.0
    for c in cells:
        V = x[c]
        J = (V[1:] - V[0]).T  # x = V0 + J xi
        Gh = (uh[c[1:]] - uh[c[0]]).T @ np.linalg.inv(J)  # du_h/dx, constant on the cell
        pts, wts = cell_points(V, exact.a, n_smooth, n_kink)
        e = exact.u(pts) - (uh[c[0]] + (pts - V[0]) @ Gh.T)
        ge = exact.grad(pts) - Gh[None, :, :]
        s0 += wts @ np.sum(e * e, axis=1)
        s1 += wts @ np.sum(ge * ge, axis=(1, 2))
        assert d == V.shape[1]
    return {"l2": float(np.sqrt(s0)), "h1_semi": float(np.sqrt(s1))}


def boundary_faces(cells, mask):
    """The boundary faces (d vertex indices each) of the simplex mesh `cells` with every vertex in the boolean mask:
    the faces that belong to one cell only."""
    count = {}
    k = cells.shape[1]
    for c in cells:
        for drop in range(k):
            f = tuple(sorted(int(v) for j, v in enumerate(c) if j != drop))
            count[f] = count.get(f, 0) + 1
    return np.array(sorted(f for f, n in count.items() if n == 1 and all(mask[list(f)])), dtype=int)


def _simplex_measure(P):
    """Length of a segment or area of a triangle with vertices P (2 x d or 3 x d)."""
    E = P[1:] - P[0]
    return float(np.sqrt(abs(np.linalg.det(E @ E.T)))) / (1.0 if len(P) == 2 else 2.0)


def positive_part_integral(P, d):
    """int_F [d]_+ ds, exactly, for d affine on the segment or triangle F with vertices P (2 x dim or 3 x dim) and vertex
    values d: F is clipped to d >= 0 at the zero crossings and d, affine, integrates to measure times its mean at the
    vertices on each piece."""
    P, d = np.asarray(P, float), np.asarray(d, float)
    if np.all(d <= 0.0):
        return 0.0
    if np.all(d >= 0.0):
        return _simplex_measure(P) * d.mean()
    pos = [i for i in range(len(d)) if d[i] > 0.0]
    neg = [i for i in range(len(d)) if d[i] <= 0.0]
    cut = lambda i, j: P[i] + d[i] / (d[i] - d[j]) * (P[j] - P[i])  # noqa: E731, the zero of d on edge ij
    if len(P) == 2:
        i, j = pos[0], neg[0]
        return _simplex_measure(np.array([P[i], cut(i, j)])) * d[i] / 2.0
    if len(pos) == 1:  # a triangle: the corner at pos[0]
        i, (j, k) = pos[0], neg
        return _simplex_measure(np.array([P[i], cut(i, j), cut(i, k)])) * d[i] / 3.0
    (i, j), k = pos, neg[0]  # the quadrilateral P_i, P_j, cut(j, k), cut(i, k), as two triangles
    a, b = cut(i, k), cut(j, k)
    return _simplex_measure(np.array([P[i], P[j], b])) * (d[i] + d[j]) / 3.0 + _simplex_measure(np.array([P[i], b, a])) * d[i] / 3.0


def plane_penetration(x, u, point, normal):
    """d = u . n - g = (x + u - point) . n at the points x with displacements u, for the plane through `point` with the
    normal `normal` (from the body into the obstacle, normalized here)."""
    n = np.asarray(normal, float) / np.linalg.norm(normal)
    return (np.asarray(x) + np.asarray(u) - np.asarray(point, float)) @ n, n


def gauss_segment_integral(P, f, npoints=2):
    """int over the segment P (2 x dim) of f(points) by npoints-point Gauss-Legendre."""
    t, w = gauss_legendre01(npoints)
    X = P[0][None, :] + t[:, None] * (P[1] - P[0])[None, :]
    return _simplex_measure(P) * float(w @ f(X, t))


def positive_part_loads(x, faces, d, rule="exact"):
    """b_i = int_{faces} [d]_+ phi_i ds for every vertex i (phi_i the P1 hat, d affine on each face with the vertex values
    d): rule "exact" clips each face to d >= 0 at the zero crossings and integrates the quadratic d phi_i exactly on
    the pieces (Gauss-Legendre 2 points on segments, the degree-2 triangle rule on a fan of triangles); rule "gauss2"
    (segments only) evaluates [d]_+ phi_i at the 2 Gauss-Legendre points of the whole face, the textbook rule."""
    b = np.zeros(len(x))
    for f in faces:
        P, dv = x[f], d[f]
        k = len(f)
        if rule == "gauss2":
            assert k == 2, "gauss2 is for segments"
            t, w = gauss_legendre01(2)
            dq = np.maximum((1 - t) * dv[0] + t * dv[1], 0.0)
            L = _simplex_measure(P)
            b[f[0]] += L * w @ (dq * (1 - t))
            b[f[1]] += L * w @ (dq * t)
            continue
        if np.all(dv <= 0.0):
            continue
        # the clipped polygon in barycentric coordinates of the face
        lam = np.eye(k)
        poly = []
        for i in range(k):
            j = (i + 1) % k
            if dv[i] >= 0.0:
                poly.append(lam[i])
            if (dv[i] > 0.0 > dv[j]) or (dv[i] < 0.0 < dv[j]):
                s = dv[i] / (dv[i] - dv[j])
                poly.append(lam[i] + s * (lam[j] - lam[i]))
            if k == 2:
                break
        if k == 2 and dv[1] >= 0.0:
            poly.append(lam[1])
        poly = np.array(poly)
        meas = _simplex_measure(P)
        if k == 2:
            pieces = [(poly[0], poly[-1])]
            t, w = gauss_legendre01(2)
            for l0, l1 in pieces:
                Lq = l0[None, :] + t[:, None] * (l1 - l0)[None, :]  # barycentric points
                wq = w * meas * abs(l1 - l0)[0]
                b[f] += (wq * (Lq @ dv)) @ Lq
        else:
            rp, rw = _TRI2
            for m in range(1, len(poly) - 1):
                l0, l1, l2 = poly[0], poly[m], poly[m + 1]
                Lq = l0[None, :] + rp[:, :1] * (l1 - l0)[None, :] + rp[:, 1:] * (l2 - l0)[None, :]
                area = abs(np.linalg.det(np.array([l1 - l0, l2 - l0])[:, :2]))  # fraction of the face's (2 x its area)
                wq = 2.0 * rw * area * meas
                b[f] += (wq * (Lq @ dv)) @ Lq
    return b
