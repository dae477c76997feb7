"""An independent solution of the nodal penalty contact problem with every boundary-condition family, by GetFEM
(Debian's python3-getfem) on the very mesh the solver reads: GetFEM assembles the plane-strain stiffness, the body
force, the traction, the pressure and the lumped contact masses; the obstacle's gap and normal, the Dirichlet
elimination and the semismooth Newton iteration are written here in numpy, from the formulas, not from the solver.
solve_exact(): the exact nodal contact (u . n <= g at every contact node, the reference of -contact_method vi) on the
same GetFEM operators, by a primal-dual active set iteration on the saddle-point system with the nodal multipliers."""
import gmsh
import numpy as np

# the problem (tests/test_getfem.py passes the same to bin/signorini)
E, NU = 1.0, 0.3
BODY_FORCE = (0.05, -0.2)
PRESSURE = 0.02                      # on "right" (x = 2)
TRACTION = (0.01, -0.05)             # on "traction" (top, x in [1, 2])
CLAMP = (0.001, -0.01)               # "clamp" (top, x in [0, 1]) moved by this translation
SLIP_LEFT = 0.0                      # "left" (x = 0): u_x = this, u_y free
CENTER, RADIUS = (1.0, -5.0), 5.0    # the rigid disk below: the body stays outside it
PLANE_POINT, PLANE_NORMAL = (1.0, -0.05), (0.1, -1.0)  # obstacle="plane": a tilted foundation (the normal normalized below)
EPS = 1e-2                           # -penalty_eps
GROUPS = {"contact_a": 1, "contact_b": 2, "right": 3, "traction": 4, "clamp": 5, "left": 6}


def write_mesh(path, size=0.1):
    """The rectangle [0, 2] x [0, 1], its bottom in two contact face sets and its top in a clamped and a loaded half
    (Gmsh 2.2, which GetFEM imports)."""
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("every_family")
        pts = [gmsh.model.geo.addPoint(x, y, 0, size) for x, y in [(0, 0), (1, 0), (2, 0), (2, 1), (1, 1), (0, 1)]]
        lines = [gmsh.model.geo.addLine(pts[i], pts[(i + 1) % 6]) for i in range(6)]
        surface = gmsh.model.geo.addPlaneSurface([gmsh.model.geo.addCurveLoop(lines)])
        gmsh.model.geo.synchronize()
        for (name, tag), line in zip(GROUPS.items(), [lines[0], lines[1], lines[2], lines[3], lines[4], lines[5]]):
            gmsh.model.addPhysicalGroup(1, [line], tag)
            gmsh.model.setPhysicalName(1, tag, name)
        gmsh.model.addPhysicalGroup(2, [surface], 10)
        gmsh.model.setPhysicalName(2, 10, "body")
        gmsh.model.mesh.generate(2)
        gmsh.option.setNumber("Mesh.MshFileVersion", 2.2)
        gmsh.write(path)
    finally:
        gmsh.finalize()


def obstacle_options(obstacle="cylinder"):
    """The obstacle as bin/signorini options: the disk below (cylinder) or the tilted plane."""
    if obstacle == "plane":
        return ["-obstacle", "plane", "-obstacle_point", f"{PLANE_POINT[0]},{PLANE_POINT[1]}",
                "-obstacle_normal", f"{PLANE_NORMAL[0]},{PLANE_NORMAL[1]}"]
    return ["-obstacle", "cylinder", "-obstacle_center", f"{CENTER[0]},{CENTER[1]}", "-obstacle_radius", RADIUS]


def obstacle_normal_gap(x, obstacle="cylinder"):
    """The obstacle's unit normal (from the body into it) and the gap at the points x, from the formulas: for the disk,
    n = -(x - c)/|x - c| and g = |x - c| - R; for the plane through p with unit normal n, g = (p - x) . n."""
    if obstacle == "plane":
        n = np.array(PLANE_NORMAL) / np.linalg.norm(PLANE_NORMAL)
        return np.tile(n, (len(x), 1)), (np.array(PLANE_POINT) - x) @ n
    r = x - np.array(CENTER)
    dist = np.linalg.norm(r, axis=1)
    return -r / dist[:, None], dist - RADIUS


def solver_options(obstacle="cylinder", method="penalty", slip=True):
    """The same problem as bin/signorini options (scene general; the nodal penalty quadrature with a fixed eps, or
    method "vi": SNESVI); slip=False leaves the left side free (solve_brick()'s problem)."""
    contact = (["-penalty_quadrature", "nodal", "-penalty_eps", EPS] if method == "penalty" else ["-contact_method", "vi"])
    left = ["-bc_slip", "left", "-bc_slip_left_components", "0", "-bc_slip_left_translate", f"{SLIP_LEFT},0"] if slip else []
    return ["-scene", "general", "-young_modulus", E, "-poisson_ratio", NU, "-contact_faces", "contact_a,contact_b",
            "-bc_clamp", "clamp", "-bc_clamp_clamp_translate", f"{CLAMP[0]},{CLAMP[1]}"] + left + ["-bc_traction", "traction",
            "-bc_traction_traction", f"{TRACTION[0]},{TRACTION[1]}", "-bc_pressure", "right", "-bc_pressure_right", PRESSURE,
            "-body_force", f"{BODY_FORCE[0]},{BODY_FORCE[1]}"] + obstacle_options(obstacle) + contact + ["-snes_rtol", "1e-14"]


def operators(path, obstacle, slip=True):
    """GetFEM's K, F, the dofs' coordinates, the Dirichlet dofs and values (the left slip's too, if slip), the contact
    nodes with their normals, gaps and lumped masses, on the mesh at path."""
    import getfem as gf

    lam, mu = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
    mesh = gf.Mesh("import", "gmsh", path)
    mfu = gf.MeshFem(mesh, 2)
    mfu.set_classical_fem(1)
    mim = gf.MeshIm(mesh, 4)
    md = gf.Model("real")
    md.add_fem_variable("u", mfu)
    K = gf.asm_generic(mim, 2, f"{lam!r}*Div_u*Div_Test_u + {mu!r}*(Grad_u+Grad_u'):Grad_Test_u", -1, md).full()
    F = gf.asm_generic(mim, 1, f"[{BODY_FORCE[0]!r},{BODY_FORCE[1]!r}].Test_u", -1, md)
    F = F + gf.asm_generic(mim, 1, f"[{TRACTION[0]!r},{TRACTION[1]!r}].Test_u", GROUPS["traction"], md)
    F = F - gf.asm_generic(mim, 1, f"{PRESSURE!r}*Normal.Test_u", GROUPS["right"], md)
    W = sum(gf.asm_generic(mim, 1, "[1,1].Test_u", GROUPS[r], md) for r in ("contact_a", "contact_b"))
    x = mfu.basic_dof_nodes().T  # [ndof, 2], the dofs node by node (x, y)
    ndof = x.shape[0]
    fixed, value = np.zeros(ndof, bool), np.zeros(ndof)
    clamp = mfu.basic_dof_on_region(GROUPS["clamp"])
    fixed[clamp] = True
    value[clamp] = np.where(clamp % 2 == 0, CLAMP[0], CLAMP[1])
    left = [d for d in mfu.basic_dof_on_region(GROUPS["left"]) if d % 2 == 0 and not fixed[d]] if slip else []
    fixed[left] = True
    value[left] = SLIP_LEFT
    nodes = np.unique(np.concatenate([mfu.basic_dof_on_region(GROUPS[r]) for r in ("contact_a", "contact_b")]) // 2)
    normal, gap = obstacle_normal_gap(x[2 * nodes], obstacle)
    weight = W[2 * nodes]
    return K, F, x, fixed, value, nodes, normal, gap, weight


def solve(path, tol=1e-13, max_it=50, obstacle="cylinder"):
    """(vertex coordinates [n, 2], displacement [n, 2], contact force) of the nodal penalty problem on the mesh at path."""
    K, F, x, fixed, value, nodes, normal, gap, weight = operators(path, obstacle)
    free = ~fixed
    u = value.copy()
    for _ in range(max_it):
        un = u[2 * nodes] * normal[:, 0] + u[2 * nodes + 1] * normal[:, 1]
        d = un - gap
        active = d > 0
        R = K @ u - F
        J = K.copy()
        for k in np.nonzero(active)[0]:
            i = 2 * nodes[k]
            R[i:i + 2] += weight[k] / EPS * d[k] * normal[k]
            J[i:i + 2, i:i + 2] += weight[k] / EPS * np.outer(normal[k], normal[k])
        if np.linalg.norm(R[free]) < tol * max(np.linalg.norm(F), 1.0):
            break
        u[free] -= np.linalg.solve(J[np.ix_(free, free)], R[free])
    else:
        raise RuntimeError("the GetFEM reference Newton did not converge")
    force = float(np.sum(weight / EPS * np.maximum(d, 0.0)))
    return x[0::2], u.reshape(-1, 2), force


def solve_exact(path, max_it=50, obstacle="cylinder", slip=True):
    """(vertex coordinates, displacement, contact force) of the exact nodal contact: K u = F - N^T lam, N u <= g,
    lam >= 0, lam . (g - N u) = 0, with N's row k the normal n_k at node k's two dofs. The primal-dual active set
    iteration: A = {k : lam_k + c (N u - g)_k > 0}; on A the constraint holds as an equality, off A lam_k = 0; it stops
    when A repeats. The Dirichlet values are eliminated; a node's fixed component moves its part of n . u to the right
    side. The force is sum(lam), the multipliers being the nodal normal reactions."""
    K, F, x, fixed, value, nodes, normal, gap, weight = operators(path, obstacle, slip)
    free = np.nonzero(~fixed)[0]
    m = len(nodes)
    N = np.zeros((m, K.shape[0]))
    for k, node in enumerate(nodes):
        N[k, 2 * node:2 * node + 2] = normal[k]
    g = gap - N[:, fixed] @ value[fixed]  # N_free u_free <= g - N_fixed u_fixed
    Nf, Kff, Ff = N[:, free], K[np.ix_(free, free)], F[free] - K[np.ix_(free, fixed)] @ value[fixed]
    c = float(np.max(np.diag(Kff)))  # any positive c; K's scale makes lam and c (N u - g) comparable
    lam, uf = np.zeros(m), np.linalg.solve(Kff, Ff)
    active = None
    for _ in range(max_it):
        new = lam + c * (Nf @ uf - g) > 0
        if active is not None and np.array_equal(new, active):
            break
        active = new
        a = np.nonzero(active)[0]
        n_a = len(a)
        S = np.zeros((len(free) + n_a, len(free) + n_a))
        S[:len(free), :len(free)] = Kff
        S[:len(free), len(free):] = Nf[a].T
        S[len(free):, :len(free)] = Nf[a]
        sol = np.linalg.solve(S, np.concatenate([Ff, g[a]]))
        uf, lam = sol[:len(free)], np.zeros(m)
        lam[a] = sol[len(free):]
    else:
        raise RuntimeError("the exact-contact active set iteration did not settle")
    assert np.all(lam >= -1e-12 * max(1.0, np.max(np.abs(lam)))) and np.all(Nf @ uf - g <= 1e-12), "not a solution"
    u = value.copy()
    u[free] = uf
    return x[0::2], u.reshape(-1, 2), float(np.sum(lam))


def solve_brick(path, obstacle="cylinder", tol=1e-13):
    """(vertex coordinates, displacement, contact force) of the exact nodal contact by GetFEM alone, on the problem
    without the left slip (solver_options(slip=False)): its linearized elasticity and source-term bricks, the clamp by
    its nodal Dirichlet brick (with simplification), its nodal contact brick with a rigid obstacle given as the signed
    distance expression (Model.add_nodal_contact_with_rigid_obstacle_brick, the Alart-Curnier augmented Lagrangian,
    r = E) and its Newton (Model.solve). Nothing here is the solver's or the numpy iteration's; the force is the sum
    of the brick's nodal multipliers. (The slip is left out: GetFEM imposes a normal Dirichlet condition by
    multipliers, the L2 projection on the side, which differs from the nodal one where it meets the clamp, by 2.7e-4
    at the corner's neighbour.)"""
    import getfem as gf

    lam, mu = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
    mesh = gf.Mesh("import", "gmsh", path)
    contact = 100
    mesh.set_region(contact, mesh.region(GROUPS["contact_a"]))
    mesh.region_merge(contact, GROUPS["contact_b"])
    mfu = gf.MeshFem(mesh, 2)
    mfu.set_classical_fem(1)
    mim = gf.MeshIm(mesh, 4)
    md = gf.Model("real")
    md.add_fem_variable("u", mfu)
    md.add_initialized_data("lambda", [lam])
    md.add_initialized_data("mu", [mu])
    md.add_isotropic_linearized_elasticity_brick(mim, "u", "lambda", "mu")
    md.add_source_term_brick(mim, "u", f"[{BODY_FORCE[0]!r},{BODY_FORCE[1]!r}]")
    md.add_source_term_brick(mim, "u", f"[{TRACTION[0]!r},{TRACTION[1]!r}]", GROUPS["traction"])
    md.add_source_term_brick(mim, "u", f"-{PRESSURE!r}*Normal", GROUPS["right"])
    md.add_initialized_data("clamp", list(CLAMP))
    md.add_Dirichlet_condition_with_simplification("u", GROUPS["clamp"], "clamp")
    if obstacle == "plane":
        n = np.array(PLANE_NORMAL) / np.linalg.norm(PLANE_NORMAL)
        distance = f"({PLANE_POINT[0]!r}-x)*{n[0]!r}+({PLANE_POINT[1]!r}-y)*{n[1]!r}"
    else:
        distance = f"sqrt(sqr(x-{CENTER[0]!r})+sqr(y-{CENTER[1]!r}))-{RADIUS!r}"
    nodes = mfu.basic_dof_on_region(contact).size // 2
    md.add_variable("lambda_n", nodes)
    md.add_initialized_data("r", [E])
    md.add_nodal_contact_with_rigid_obstacle_brick(mim, "u", "lambda_n", "r", contact, distance, 1)
    its = md.solve("max_res", tol, "max_iter", 100)
    if its is not None and np.ndim(its) and its[0] >= 100:
        raise RuntimeError("GetFEM's Newton did not converge")
    x = mfu.basic_dof_nodes().T
    return x[0::2], md.variable("u").reshape(-1, 2), float(abs(np.sum(md.variable("lambda_n"))))


def brick_against_exact(radii=(1.5, 5.0, 50.0), path=None):
    """{R: max |u_brick - u_exact| / max |u_exact|} under disks of radius R (centre R below the point (1, 0)), on the
    problem without the slip: GetFEM's contact brick against the exact normals of solve_exact()'s iteration on the
    same GetFEM operators. The figures of test_getfem.py's note on the disk: python3 tests/getfem_reference.py."""
    global CENTER, RADIUS
    import os
    import tempfile

    kept = CENTER, RADIUS
    path = path or os.path.join(tempfile.mkdtemp(), "every_family.msh")
    write_mesh(path)
    out = {}
    try:
        for r in radii:
            CENTER, RADIUS = (1.0, -r), r
            x, u, _ = solve_brick(path)
            xe, ue, _ = solve_exact(path, slip=False)
            assert np.allclose(x, xe)
            out[r] = float(np.max(np.abs(u - ue)) / np.max(np.abs(ue)))
    finally:
        CENTER, RADIUS = kept
    return out


if __name__ == "__main__":
    for r, d in brick_against_exact().items():
        print(f"disk of radius {r:g}: GetFEM's contact brick differs from the exact nodal contact by {d:.2e}")
