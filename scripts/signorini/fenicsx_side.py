"""The FEniCSx side of the 3D benchmark (issue 35, scripts/bench_fenicsx.py): the 3D default run of this project, the
scene `square` on the unit cube (options/square.yaml with -dm_plex_dim 3), solved by Debian's python3-dolfinx (0.5)
with the same penalty formulation, so that the two codes can be timed on the same problem and their contact forces
compared.

What bin/signorini solves there (src/scenes/square.c, src/contact/penalty*.c, src/contact/contact*.c):
  - the unit cube in N^3 cubes of 6 Kuhn tetrahedra (src/mesh/mesh_box_simplex.c: the 6 monotone paths from corner
    (0,0,0) to (1,1,1) of each cube); dolfinx's create_unit_cube(..., CellType.tetrahedron) makes the very same 6
    tetrahedra of each cube (cells {v0,v1,v3,v7}, {v0,v1,v7,v5}, {v0,v5,v7,v4}, {v0,v3,v2,v7}, {v0,v6,v4,v7},
    {v0,v2,v6,v7}, every one along the diagonal v0-v7: the same monotone paths), only numbered differently; same_cells()
    checks it against the cells of an output file;
  - P1 displacement, linear elasticity E = 1, nu = 0.3, body force f = (0, 0, beta (x - x0)), beta = 2, x0 = 0.6;
  - the top z = 1 clamped (u = 0), the other sides traction-free, Gamma_C the bottom z = 0 above the rigid plane
    z = 0 (the obstacle's normal nu = (0, 0, -1), from the body into the obstacle; gap g = (p - x) . nu = z = 0 there);
  - the penalty term (1/eps) int_{Gamma_C} [u . nu - g]_+ v . nu ds by the face Gauss rule of PETSc's P1 element
    (-penalty_quadrature gauss: PetscFEGetFaceQuadrature() of PetscFECreateLagrange(3, 3, simplex, 1, PETSC_DETERMINE),
    a 4-point collapsed Gauss-Jacobi rule exact to degree 3), here UFL's ds with quadrature_degree 3 (basix's 6-point
    rule of the same degree: the two rules differ only on the faces the contact zone's edge crosses, where the
    integrand has a kink; the forces agree to about 1e-5, see bench/fenicsx.md);
  - eps = eps0 h^power / E (eps0 = 1, power = 1, E = 1), with h the diameter of the cell at each contact face
    (-penalty_eps_local, the default: its longest edge, sqrt(3)/N on the Kuhn box, which is also the largest cell of
    the mesh, the global h): here a cellwise constant 1/eps from each cell's longest edge (cell_diameters());
  - Newton on the generalized Jacobian K + (1/eps) int H(u . nu - g) nu nu^T (H(0) = 0, as the project's kernel).
The contact force the project reports (/run contact_force) is the sum over the contact nodes of the obstacle's nodal
reaction, -R . nu with R = K u + r0; at a converged solve that is the penalty term summed over the nodes, the integral of
the penalty pressure (1/eps)[u . nu - g]_+ over Gamma_C by the same rule (the basis is a partition of unity): positive,
here the z component of the obstacle's force on the body. This program reports that integral.

Linear and nonlinear solvers, by PETSc options (prefix fenicsx_): CG + GAMG with the rigid-body near-null space, as
options/solvers/gamg.yaml (ksp_rtol 1e-10, pc_gamg_threshold 0.01, Chebyshev/Jacobi smoothers, pc_gamg_use_sa_esteig
false); SNES newtonls (full steps: snes_linesearch_type basic; semismooth Newton) to snes_rtol 1e-8 (PETSc's default, the
project's), snes_stol 0 (as the project: no convergence on a small step); --ew adds -snes_ksp_ew (PETSc's
Eisenstat-Walker forcing terms, its default parameters). The Jacobian is assembled whole at every Newton step, as a
FEniCSx user would write it.

    python3 -m signorini.fenicsx_side --faces N --result RESULT.json [--ew] [--petsc KEY=VALUE ...]
    python3 scripts/signorini/fenicsx_side.py ...          (the same, as a script path: fenicsx_cmd())

RESULT.json: the contact force, the Newton and CG iterations, the unknowns, eps, the SNES reason, the wall times
(total from the start of this program, imports and form compilation included); RESULT.npz beside it (--fields): the
vertex coordinates and displacements."""
import argparse
import json
import os
import sys
import time

T_START = time.perf_counter()  # this program's own wall time counts from here (before dolfinx is imported)

import numpy as np  # noqa: E402

E, NU, BETA, X0 = 1.0, 0.3, 2.0, 0.6  # options/square.yaml
EPS0, EPS_POWER = 1.0, 1.0  # -penalty_eps0, -penalty_eps_power of options/square.yaml
BOTTOM, TOP = 1, 2  # PETSc's box face numbers: Gamma_C z = 0, the clamped top z = 1
PENALTY_QUADRATURE_DEGREE = 3  # the degree of PETSc's face rule for P1 (src/contact/penalty_faces.c reads it)
PREFIX = "fenicsx_"
# PETSc 3.18's face rule of that element (PetscFEGetFaceQuadrature(): PetscDTStroudConicalQuadrature(2, 1, 2, ...), 4
# points, degree 3), moved from its reference triangle (-1,-1), (1,-1), (-1,1) to basix's (0,0), (1,0), (0,1): the points
# (xi + 1)/2, the weights over 4. Not symmetric: which points of a face it samples depends on the order of the face's
# vertices, which differs between the codes; --quadrature-rule petsc uses it in dolfinx's order (a diagnostic).
PETSC_FACE_RULE = (((0.1785587282636164, 0.15505102572168217), (0.07503111022260811, 0.6449489742783178),
                    (0.6663902460147014, 0.15505102572168217), (0.2800199154990741, 0.6449489742783178)),
                   (0.15902069087198858, 0.09097930912801142, 0.15902069087198858, 0.09097930912801142))

# options/solvers/gamg.yaml, and the Newton of the project's defaults (snes_rtol 1e-8, no small-step test)
SOLVER_OPTIONS = {
    "snes_type": "newtonls", "snes_linesearch_type": "basic", "snes_rtol": 1e-8, "snes_atol": 1e-50, "snes_stol": 0.0, "snes_max_it": 50,
    "ksp_type": "cg", "ksp_rtol": 1e-10, "pc_type": "gamg", "pc_gamg_threshold": 0.01, "mg_levels_ksp_type": "chebyshev",
    "mg_levels_pc_type": "jacobi", "pc_gamg_use_sa_esteig": "false",
}


def rigid_body_modes(V):
    """The 6 rigid-body motions of the P1 vector space V (3 translations, 3 rotations), orthonormalized, as a PETSc
    near-null space (the project's CreateRigidBodyModes())."""
    from petsc4py import PETSc
    import dolfinx.la

    imap, bs = V.dofmap.index_map, V.dofmap.index_map_bs
    x = V.tabulate_dof_coordinates()[: imap.size_local + imap.num_ghosts]
    vecs = [dolfinx.la.create_petsc_vector(imap, bs) for _ in range(6)]
    for k, vec in enumerate(vecs):
        with vec.localForm() as loc:
            b = loc.array.reshape(-1, 3)
            b[:] = 0.0
            if k < 3:
                b[:, k] = 1.0
            else:  # rotations about z, x, y: (-y, x, 0), (0, -z, y), (z, 0, -x)
                i, j = {3: (0, 1), 4: (1, 2), 5: (2, 0)}[k]
                b[:, i] = -x[:, j]
                b[:, j] = x[:, i]
    dolfinx.la.orthonormalize(vecs)
    return PETSc.NullSpace().create(vectors=vecs)


def cell_diameters(msh):
    """The diameter of every cell of this rank (owned and ghost), its longest edge: the largest distance between two of
    its vertices (the project's MeshCellDiameter()). P1 geometry: the geometry nodes of a cell are its vertices."""
    xg = msh.geometry.x
    cells = msh.geometry.dofmap.array.reshape(-1, 4)
    d = np.zeros(len(cells))
    for a in range(4):
        for b in range(a + 1, 4):
            d = np.maximum(d, np.linalg.norm(xg[cells[:, a]] - xg[cells[:, b]], axis=1))
    return d


def solve(n, ew=False, eps0=EPS0, eps_power=EPS_POWER, quadrature_degree=PENALTY_QUADRATURE_DEGREE, quadrature_rule="default", petsc_options=None,
          monitor=False, fields=False):
    """FEniCSx's solve of the 3D square scene on the N^3 Kuhn box: a dict of the results (see the module's doc)."""
    from mpi4py import MPI
    from petsc4py import PETSc
    import ufl
    import dolfinx
    import dolfinx.fem.petsc as fem_petsc
    from dolfinx import fem, mesh as dmesh

    t_import = time.perf_counter()
    comm = MPI.COMM_WORLD
    msh = dmesh.create_unit_cube(comm, n, n, n, dmesh.CellType.tetrahedron)
    tdim, fdim = msh.topology.dim, msh.topology.dim - 1
    V = fem.VectorFunctionSpace(msh, ("Lagrange", 1))

    # faces: Gamma_C (z = 0) tagged BOTTOM, the clamped top (z = 1)
    bottom = dmesh.locate_entities_boundary(msh, fdim, lambda x: np.isclose(x[2], 0.0))
    top = dmesh.locate_entities_boundary(msh, fdim, lambda x: np.isclose(x[2], 1.0))
    tags = dmesh.meshtags(msh, fdim, np.sort(bottom).astype(np.int32), np.full(len(bottom), BOTTOM, dtype=np.int32))
    bc = fem.dirichletbc(np.zeros(3, dtype=PETSc.ScalarType), fem.locate_dofs_topological(V, fdim, top), V)

    # 1/eps on each cell: eps = eps0 diam^power / E (the local eps of the Gauss rule, the diameter of the face's cell;
    # on this mesh every cell's diameter is the largest, the global h, so eps is one number)
    diam = cell_diameters(msh)
    Q = fem.FunctionSpace(msh, ("DG", 0))
    inv_eps = fem.Function(Q)
    eps_cells = eps0 * diam ** eps_power / E
    inv_eps.x.array[:] = 1.0 / eps_cells
    h_max = comm.allreduce(float(diam[: msh.topology.index_map(tdim).size_local].max()), op=MPI.MAX)

    lam, mu = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
    u, v, du = fem.Function(V), ufl.TestFunction(V), ufl.TrialFunction(V)
    x = ufl.SpatialCoordinate(msh)

    def sigma(w):
        e = ufl.sym(ufl.grad(w))
        return 2.0 * mu * e + lam * ufl.tr(e) * ufl.Identity(3)

    f = ufl.as_vector((0.0, 0.0, BETA * (x[0] - X0)))
    nu = ufl.as_vector((0.0, 0.0, -1.0))  # the plane z = 0 below the body: its normal from the body into it
    point = ufl.as_vector((0.0, 0.0, 0.0))
    pen = ufl.dot(u, nu) - ufl.dot(point - x, nu)  # u . nu - g
    if quadrature_rule == "petsc":  # PETSc's own face points and weights, in dolfinx's order of each face's vertices
        pts, wts = PETSC_FACE_RULE
        md = {"quadrature_rule": "custom", "quadrature_points": pts, "quadrature_weights": wts, "quadrature_degree": 3}
    elif quadrature_rule == "vertex":  # the vertex rule: the project's -penalty_quadrature nodal (lumped boundary mass)
        md = {"quadrature_rule": "custom", "quadrature_points": ((0.0, 0.0), (1.0, 0.0), (0.0, 1.0)), "quadrature_weights": (1 / 6, 1 / 6, 1 / 6),
              "quadrature_degree": 1}  # FFCx 0.5's own "vertex" scheme takes the cell's vertices on a face
    else:
        md = {"quadrature_degree": quadrature_degree}
    ds_c = ufl.Measure("ds", domain=msh, subdomain_data=tags, subdomain_id=BOTTOM, metadata=md)
    F = ufl.inner(sigma(u), ufl.grad(v)) * ufl.dx - ufl.dot(f, v) * ufl.dx + inv_eps * ufl.max_value(pen, 0.0) * ufl.dot(v, nu) * ds_c
    J = ufl.inner(sigma(du), ufl.grad(v)) * ufl.dx + inv_eps * ufl.conditional(ufl.gt(pen, 0.0), 1.0, 0.0) * ufl.dot(du, nu) * ufl.dot(v, nu) * ds_c
    force_form = inv_eps * ufl.max_value(pen, 0.0) * ds_c  # the penalty pressure's integral over Gamma_C
    F_form, J_form, force_c = fem.form(F), fem.form(J), fem.form(force_form)
    t_forms = time.perf_counter()

    A = fem_petsc.create_matrix(J_form)
    A.setNearNullSpace(rigid_body_modes(V))
    b = fem_petsc.create_vector(F_form)
    X = fem_petsc.create_vector(F_form)

    def residual(snes, xv, bv):
        xv.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        xv.copy(u.vector)
        u.vector.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        with bv.localForm() as bl:
            bl.set(0.0)
        fem_petsc.assemble_vector(bv, F_form)
        fem_petsc.apply_lifting(bv, [J_form], bcs=[[bc]], x0=[xv], scale=-1.0)
        bv.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        fem_petsc.set_bc(bv, [bc], xv, -1.0)

    def jacobian(snes, xv, Am, Pm):
        Am.zeroEntries()
        fem_petsc.assemble_matrix(Am, J_form, bcs=[bc])
        Am.assemble()

    snes = PETSc.SNES().create(comm)
    snes.setFunction(residual, b)
    snes.setJacobian(jacobian, A, A)
    opts = PETSc.Options()
    given = dict(SOLVER_OPTIONS)
    if ew:
        given["snes_ksp_ew"] = "true"
    given.update(petsc_options or {})
    if monitor:
        given.update(snes_monitor="", ksp_converged_reason="", snes_converged_reason="")
    for k, val in given.items():
        opts[PREFIX + k] = val
    snes.setOptionsPrefix(PREFIX)
    snes.setFromOptions()
    X.set(0.0)
    t_setup = time.perf_counter()
    snes.solve(None, X)
    t_solve = time.perf_counter()
    X.copy(u.vector)
    u.vector.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
    force = comm.allreduce(fem.assemble_scalar(force_c), op=MPI.SUM)
    reason = snes.getConvergedReason()
    ndofs = V.dofmap.index_map.size_global * V.dofmap.index_map_bs
    nfixed = comm.allreduce(int(bc.dof_indices()[1]), op=MPI.SUM)  # the clamped unknowns this rank owns (blocked: 3 a node)
    res = {
        "code": "FEniCSx", "dolfinx": dolfinx.__version__, "faces": n, "ew": bool(ew), "ranks": comm.size,
        "dofs": int(ndofs), "free_dofs": int(ndofs - nfixed), "cells": int(msh.topology.index_map(tdim).size_global),
        "h": h_max, "eps_min": comm.allreduce(float(eps_cells.min()), op=MPI.MIN), "eps_max": comm.allreduce(float(eps_cells.max()), op=MPI.MAX),
        "penalty_quadrature_degree": int(quadrature_degree), "penalty_quadrature_rule": quadrature_rule,
        "contact_force": float(force), "converged": int(reason > 0), "snes_reason": int(reason), "snes_reason_name": snes_reason_name(reason),
        "newton_its": int(snes.getIterationNumber()), "ksp_its": int(snes.getLinearSolveIterations()),
        "residual_norm": float(snes.getFunctionNorm()),
        "options": {k: str(val) for k, val in given.items()},
        "time_import": t_import - T_START, "time_forms": t_forms - t_import, "time_setup": t_setup - t_import, "time_solve": t_solve - t_setup,
    }
    if fields:
        nown = V.dofmap.index_map.size_local
        res["_x"] = V.tabulate_dof_coordinates()[:nown].copy()
        res["_u"] = u.x.array.reshape(-1, 3)[:nown].copy()
    for k in list(given):
        del opts[PREFIX + k]
    snes.destroy()
    res["time_total"] = time.perf_counter() - T_START
    return res


def snes_reason_name(reason):
    from petsc4py import PETSc

    names = {getattr(PETSc.SNES.ConvergedReason, k): k for k in dir(PETSc.SNES.ConvergedReason) if not k.startswith("_")}
    return names.get(reason, str(reason))


def same_cells(h5path, n):
    """Whether the cells of bin/signorini's output h5path (viz/topology/cells, geometry/vertices) are, as sets of vertex
    positions, dolfinx's create_unit_cube tetrahedra of the N^3 box (one rank: the whole mesh)."""
    import h5py
    from mpi4py import MPI
    from dolfinx import mesh as dmesh

    with h5py.File(h5path, "r") as f:
        xv, cells = f["geometry/vertices"][:], f["viz/topology/cells"][:]
    ours = {tuple(sorted(tuple(np.rint(p * n).astype(int)) for p in xv[c])) for c in cells}
    msh = dmesh.create_unit_cube(MPI.COMM_SELF, n, n, n, dmesh.CellType.tetrahedron)
    geo = msh.geometry.x
    theirs = {tuple(sorted(tuple(np.rint(geo[i] * n).astype(int)) for i in c)) for c in msh.geometry.dofmap.array.reshape(-1, 4)}
    return ours == theirs and len(ours) == len(cells) == 6 * n ** 3


def same_cells_cmd(h5path, n):
    """same_cells() in a process of its own: dolfinx initializes MPI, and a process that did cannot start mpiexec."""
    return [sys.executable, os.path.abspath(__file__), "--faces", str(n), "--same-cells", h5path]


def fenicsx_cmd(n, result, ew=False, extra=()):
    """This program in a process of its own (as a script path: no PYTHONPATH needed), so that it is timed as a whole
    process too."""
    return [sys.executable, os.path.abspath(__file__), "--faces", str(n), "--result", result] + (["--ew"] if ew else []) + list(extra)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--faces", type=int, required=True, help="cells per side of the Kuhn box")
    ap.add_argument("--result", help="the result, JSON (and its fields, with --fields, as RESULT.npz beside it)")
    ap.add_argument("--same-cells", metavar="H5", help="only check that bin/signorini's output H5 has dolfinx's tetrahedra (same_cells()): exit 0 if so, 1 if not")
    ap.add_argument("--ew", action="store_true", help="Eisenstat-Walker forcing terms (-snes_ksp_ew)")
    ap.add_argument("--eps0", type=float, default=EPS0, help="eps = eps0 h^power / E (default 1)")
    ap.add_argument("--eps-power", type=float, default=EPS_POWER, help="the power of h (default 1)")
    ap.add_argument("--quadrature-degree", type=int, default=PENALTY_QUADRATURE_DEGREE, help="degree of the penalty term's face rule (default 3)")
    ap.add_argument("--quadrature-rule", choices=("default", "petsc", "vertex"), default="default",
                    help="the penalty term's face rule: basix's of --quadrature-degree (default), PETSc's 4 points (a diagnostic), or the vertex rule (the project's -penalty_quadrature nodal)")
    ap.add_argument("--petsc", action="append", default=[], metavar="KEY=VALUE", help="a PETSc option of the solve, without the dash (repeatable)")
    ap.add_argument("--fields", action="store_true", help="also write the vertex coordinates and displacements (RESULT.npz)")
    ap.add_argument("--monitor", action="store_true", help="print PETSc's Newton and CG convergence")
    args = ap.parse_args(argv)
    if args.same_cells:
        same = same_cells(args.same_cells, args.faces)
        print(f"{args.same_cells}: {'the same' if same else 'not the same'} tetrahedra as dolfinx's create_unit_cube({args.faces})")
        return 0 if same else 1
    if not args.result:
        ap.error("--result is required")
    extra = dict(kv.split("=", 1) if "=" in kv else (kv, "") for kv in args.petsc)
    res = solve(args.faces, ew=args.ew, eps0=args.eps0, eps_power=args.eps_power, quadrature_degree=args.quadrature_degree, quadrature_rule=args.quadrature_rule, petsc_options=extra,
                monitor=args.monitor, fields=args.fields)
    from mpi4py import MPI

    if MPI.COMM_WORLD.rank == 0:
        if args.fields:
            np.savez(args.result + ".part.npz", x=res["_x"], u=res["_u"])
            os.replace(args.result + ".part.npz", os.path.splitext(args.result)[0] + ".npz")
        out = {k: v for k, v in res.items() if not k.startswith("_")}
        with open(args.result + ".part", "w") as fh:
            json.dump(out, fh, indent=1)
        os.replace(args.result + ".part", args.result)
        print(f"FEniCSx {args.faces}^3 ({out['dofs']} dofs{', EW' if args.ew else ''}): {out['snes_reason_name']}, {out['newton_its']} Newton, "
              f"{out['ksp_its']} CG, contact force {out['contact_force']:.10g}, solve {out['time_solve']:.2f} s, total {out['time_total']:.2f} s", flush=True)
    return 0 if res["converged"] else 3


if __name__ == "__main__":
    sys.exit(main())
