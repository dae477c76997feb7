"""The GetFEM side-by-side of make bench: the default scene (`square`, 2D) on one structured mesh written here, solved by
bin/signorini and by GetFEM (Debian's python3-getfem) with the same eps and the same (nodal) penalty quadrature.

The mesh is the one bin/signorini builds for -dm_plex_box_faces N,N (the same vertices and the same diagonal in every
square), written as Gmsh 2.2 with the box's face numbers (bottom 1, right 2, top 3, left 4), so that both codes read the
very same file. GetFEM's problem is stated in its own weak-form language from the formulas of the scene (src/scenes/square.c):
plane-strain linear elasticity, the body force (0, beta (x - x0)), the top clamped, and the penalty
(1/eps) [-u_y]_+ (-v_y) on the bottom integrated by the trapezoidal rule on each edge (Newton-Cotes, the nodal rule);
GetFEM's own Newton solves it with MUMPS. Each code is timed as a whole process (/usr/bin/time -v)."""
import os
import sys
import time

import numpy as np

from .paths import BIN
from .runs import vertex_order

E, NU, BETA, X0 = 1.0, 0.3, 2.0, 0.6  # options/square.yaml
BOTTOM, RIGHT, TOP, LEFT = 1, 2, 3, 4


def write_box_mesh(path, n):
    """The unit square cut into n x n squares, each split along its (0,0)-(1,1) diagonal, as Gmsh 2.2 with the box's
    face numbers as physical groups of lines (2D body: physical group 10)."""
    t = np.linspace(0.0, 1.0, n + 1)
    X, Y = np.meshgrid(t, t)  # vertex (i, j) is number j (n + 1) + i
    v = lambda i, j: j * (n + 1) + i + 1  # Gmsh numbers from 1
    i, j = np.meshgrid(np.arange(n), np.arange(n))
    i, j = i.ravel(), j.ravel()
    c0, c1, c2, c3 = v(i, j), v(i + 1, j), v(i, j + 1), v(i + 1, j + 1)
    tris = np.concatenate([np.stack([c0, c1, c3], 1), np.stack([c0, c3, c2], 1)])
    k = np.arange(n)
    lines = [(BOTTOM, v(k, 0), v(k + 1, 0)), (RIGHT, v(n, k), v(n, k + 1)), (TOP, v(k + 1, n), v(k, n)), (LEFT, v(0, k + 1), v(0, k))]
    with open(path + ".part", "w") as f:
        f.write("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n5\n1 1 \"bottom\"\n1 2 \"right\"\n1 3 \"top\"\n1 4 \"left\"\n2 10 \"body\"\n$EndPhysicalNames\n")
        f.write(f"$Nodes\n{(n + 1) ** 2}\n")
        np.savetxt(f, np.column_stack([np.arange(1, (n + 1) ** 2 + 1), X.ravel(), Y.ravel(), np.zeros(X.size)]), fmt="%d %.17g %.17g %g")
        f.write(f"$EndNodes\n$Elements\n{4 * n + len(tris)}\n")
        num = 1
        for tag, a, b in lines:
            np.savetxt(f, np.column_stack([np.arange(num, num + n), np.full(n, 1), np.full(n, 2), np.full(n, tag), np.full(n, tag), a, b]), fmt="%d")
            num += n
        np.savetxt(f, np.column_stack([np.arange(num, num + len(tris)), np.full(len(tris), 2), np.full(len(tris), 2), np.full(len(tris), 10),
                                       np.full(len(tris), 10), tris]), fmt="%d")
        f.write("$EndElements\n")
    os.replace(path + ".part", path)


def getfem_solve(mesh_path, eps, rtol=1e-10):
    """GetFEM's solution: (vertex coordinates [n, 2], displacement [n, 2], Newton steps, seconds spent in md.solve)."""
    import getfem as gf

    gf.util("trace level", 0)
    gf.util("warning level", 0)
    lam, mu = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
    mesh = gf.Mesh("import", "gmsh", mesh_path)
    mfu = gf.MeshFem(mesh, 2)
    mfu.set_classical_fem(1)
    mim = gf.MeshIm(mesh, gf.Integ("IM_TRIANGLE(2)"))  # exact for the body force (linear) times P1
    mim_nodal = gf.MeshIm(mesh, gf.Integ("IM_NC(2,1)"))  # on the edges: the trapezoidal rule, the nodal penalty
    md = gf.Model("real")
    md.add_fem_variable("u", mfu)
    md.add_initialized_data("lambda", [lam])
    md.add_initialized_data("mu", [mu])
    md.add_isotropic_linearized_elasticity_brick(mim, "u", "lambda", "mu")
    md.add_source_term(mim, f"[0, {BETA!r}*(X(1)-{X0!r})].Test_u")
    md.add_Dirichlet_condition_with_simplification("u", TOP)
    md.add_nonlinear_term(mim_nodal, f"(1/{eps!r})*pos_part(-u(2))*(-Test_u(2))", BOTTOM)
    # GetFEM's Newton measures the residual in the 1-norm: stop at rtol times its value at u = 0, as -snes_rtol does
    # (a tolerance relative to the 2-norm of the load sat below GetFEM's round-off floor at 128 x 128: 50 steps)
    md.assembly("build_rhs")
    load = np.abs(md.rhs()).sum()
    t0 = time.perf_counter()
    its, _ = md.solve("max_res", rtol * load, "max_iter", 50, "lsolver", "mumps")
    t1 = time.perf_counter()
    x = mfu.basic_dof_nodes().T[0::2]
    return x, md.variable("u").reshape(-1, 2), int(its), t1 - t0


def sorted_by_position(x, u):
    return u[vertex_order(x)]


def signorini_cmd(mesh_path, eps, output, solver_file=None, box_faces=None):
    """bin/signorini on the mesh file, or (box_faces) on the box it builds itself, the very mesh write_box_mesh() writes."""
    mesh = ["-dm_plex_box_faces", f"{box_faces},{box_faces}"] if box_faces else ["-dm_plex_filename", mesh_path]
    cmd = ["mpiexec", "-n", "1", BIN, "-options_file", "options/square.yaml", "-contact_monitor", "0"] + mesh + [
        "-penalty_quadrature", "nodal", "-penalty_eps", repr(eps), "-output", output]
    if solver_file:
        cmd += ["-options_file", solver_file]
    return cmd


def getfem_cmd(mesh_path, eps, result):
    """GetFEM in a process of its own (this module's command line), so that it is timed as a whole process too."""
    return [sys.executable, "-m", "signorini.getfem_side", mesh_path, repr(eps), result]


def main(argv):
    """python -m signorini.getfem_side MESH EPS RESULT.npz: GetFEM's solve, saved for the comparison."""
    mesh_path, eps, result = argv[0], float(argv[1]), argv[2]
    x, u, its, t = getfem_solve(mesh_path, eps)
    np.savez(result + ".part.npz", x=x, u=u, newton_its=its, solve_time=t)
    os.replace(result + ".part.npz", result)


if __name__ == "__main__":
    main(sys.argv[1:])
