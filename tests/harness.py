"""Shared helpers of the test suite: running the solver and reading its output back, a thin layer over the scripts'
library (scripts/signorini: mpirun for running, runs for reading), and the Gmsh meshes the tests write."""
import atexit
import os
import shutil
import sys
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
import read_runs  # noqa: E402,F401  (tests/test_output.py tests the script through harness.read_runs)
from signorini.mpirun import MPI_ENV, run_mpi, tail  # noqa: E402
from signorini.runs import read_output, vertex_order  # noqa: E402

BIN = os.path.join(ROOT, "bin", "signorini")
# tests/out, the root of every test's output; under pytest-xdist (make test runs the suite on as many workers as cores)
# each worker writes under tests/out/gwN, so that two tests running at once never share a file's name
OUT_ROOT = os.path.join(ROOT, "tests", "out")
OUT = os.path.join(OUT_ROOT, os.environ["PYTEST_XDIST_WORKER"]) if os.environ.get("PYTEST_XDIST_WORKER") else OUT_ROOT
ENV = dict(os.environ, **MPI_ENV)  # for the programs the tests start themselves (make, the scripts, test_fuzz.py's direct runs)
TIMEOUT = 600  # seconds a run of the solver may take


# One rank runs as a singleton, without mpiexec, and Open MPI is told not to look for a launcher or a network: 0.08 s
# a run instead of 0.4 s, and a non-zero exit without mpiexec's 2 s wait before it reports it (Open MPI 4.1).
# Isolated singletons all take the same session directory, TMPDIR/ompi.HOST.UID/jf.0/1, and each removes it at its
# end (it is empty): one ending beside another took it from under the other's MPI-IO, which keeps its shared file
# pointer's file there, so that the other's write failed (exit 67, twice in a make test on two workers) or Open MPI fell
# back to a lock file beside the output. Each process of the suite (each pytest-xdist worker) gives its singletons a
# directory of their own; the singletons of one process run one at a time.
SESSION_BASE = tempfile.mkdtemp(prefix="signorini-ompi-")
atexit.register(shutil.rmtree, SESSION_BASE, ignore_errors=True)
SINGLETON_ENV = {"OMPI_MCA_ess_singleton_isolated": "1", "OMPI_MCA_plm": "isolated", "OMPI_MCA_btl": "self", "OMPI_MCA_pml": "ob1",
                 "OMPI_MCA_orte_tmpdir_base": SESSION_BASE}


def command(args, np_=1, output=None):
    """The command line of the solver on np_ ranks (under mpiexec from 2 ranks on): the arguments, then -output OUTPUT
    when given (the last of an option given twice wins)."""
    launcher = [] if np_ == 1 else ["mpiexec", "-n", str(np_)]
    return launcher + [BIN] + [str(a) for a in args] + ([] if output is None else ["-output", str(output)])


def solve(args, np_=1, output=None, timeout=TIMEOUT):
    """Runs the solver with any arguments (command()) in ROOT with the MPI environment; returns (exit status, output:
    stdout and stderr merged). A run past the time limit is stopped, mpiexec and its ranks (signorini.mpirun.run_mpi),
    and fails the test."""
    cmd = command(args, np_, output)
    r = run_mpi(cmd, timeout=timeout, env=SINGLETON_ENV if np_ == 1 else None)
    assert not r.timed_out, f"stopped after {timeout} s: {' '.join(cmd)}\n{tail(r.output)}"
    return r.returncode, r.output


def run(args, name, np_=1, expect_rc=0, output=None):
    """Runs the solver; returns (combined output, path of the HDF5 file: tests/out/NAME.h5, or output). Asserts the exit
    status expect_rc (None: any)."""
    out = output or os.path.join(OUT, name + ".h5")
    args = ["-output", out] + list(args)
    rc, text = solve(args, np_=np_)
    if expect_rc is not None:
        shown = "\n".join(ln for ln in text.splitlines() if "PETSC ERROR: Configure options" not in ln)  # PETSc's 3,000 characters of them
        assert rc == expect_rc, f"exit code {rc}, expected {expect_rc}: {' '.join(command(args, np_))}\n{shown[-3000:]}"
    return text, out


def refused(args, name, message, np_=1):
    """Runs the solver on input it must refuse: exit status 2 (README: the input was refused), the message in its
    output, and no output file written."""
    out, h5 = run(args, name, np_=np_, expect_rc=2)
    assert message in out, f"'{message}' not in the output of {args}:\n{out[-1500:]}"
    assert not os.path.exists(h5)


def load(path):
    """(attrs, fields) of an output: /run with bytes decoded, the vertex fields in the file's order and "x", the vertex
    coordinates (signorini.runs.read_output)."""
    return read_output(path)


def sorted_by_position(fields, key):
    """Field values in a rank-independent vertex order (signorini.runs.vertex_order, as runs.vertex_fields())."""
    return fields[key][vertex_order(fields["x"])]


def read_gmsh_simplices(path, dim):
    """(vertices, cells) of a Gmsh mesh file of simplices, read with Gmsh's Python API."""
    import gmsh
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(path)
        tags, xs, _ = gmsh.model.mesh.getNodes()
        index = {t: i for i, t in enumerate(tags)}
        _, _, nodes = gmsh.model.mesh.getElements(dim)
        return xs.reshape(-1, 3), np.array([index[n] for n in nodes[0]]).reshape(-1, dim + 1)
    finally:
        gmsh.finalize()


def rotated(nodes, rotation):
    """The points times the matrix rotation (rows of the matrix; None: the points as they are)."""
    if rotation is None:
        return nodes
    return [tuple(sum(rotation[a][b] * p[b] for b in range(len(p))) for a in range(len(p))) for p in nodes]


def write_gmsh_square(path, n, with_contact=True, with_clamp=True, quads=False, rotation=None):
    """A Gmsh 2.2 file of the unit square in n x n cells, triangles split like the built-in simplex box (or quadrilaterals),
    physical lines 1-4 numbered as PETSc's box (bottom 1 = Gamma_C, right 2, top 3 = the clamped face of the built-in
    scenes, left 4); rotation: a 2 x 2 matrix applied to the coordinates."""
    nodes = rotated([(i / n, j / n) for j in range(n + 1) for i in range(n + 1)], rotation)
    vid = lambda i, j: j * (n + 1) + i + 1  # noqa: E731
    sides = {1: [(vid(i, 0), vid(i + 1, 0)) for i in range(n)], 2: [(vid(n, j), vid(n, j + 1)) for j in range(n)],
             3: [(vid(i, n), vid(i + 1, n)) for i in range(n)], 4: [(vid(0, j), vid(0, j + 1)) for j in range(n)]}
    elems = []
    for tag, segs in sides.items():
        if (tag == 1 and not with_contact) or (tag == 3 and not with_clamp):
            continue
        elems += [f"1 2 {tag} {tag} {a} {b}" for a, b in segs]
    for j in range(n):
        for i in range(n):
            if quads:
                elems.append(f"3 2 10 10 {vid(i, j)} {vid(i + 1, j)} {vid(i + 1, j + 1)} {vid(i, j + 1)}")
            else:
                elems += [f"2 2 10 10 {vid(i, j)} {vid(i + 1, j)} {vid(i + 1, j + 1)}", f"2 2 10 10 {vid(i, j)} {vid(i + 1, j + 1)} {vid(i, j + 1)}"]
    with open(path, "w") as fp:
        fp.write("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n%d\n" % len(nodes))
        fp.writelines(f"{k + 1} {x!r} {y!r} 0\n" for k, (x, y) in enumerate(nodes))
        fp.write("$EndNodes\n$Elements\n%d\n" % len(elems))
        fp.writelines(f"{k + 1} {e}\n" for k, e in enumerate(elems))
        fp.write("$EndElements\n")


def write_gmsh_cube(path, n, rotation=None):
    """A Gmsh 2.2 file of the unit cube in n^3 cubes of 6 Kuhn tetrahedra, physical surfaces numbered as PETSc's box
    (bottom z = 0 1, top 2); rotation: a 3 x 3 matrix applied to the coordinates."""
    vid = lambda i, j, k: (k * (n + 1) + j) * (n + 1) + i + 1  # noqa: E731
    nodes = rotated([(i / n, j / n, k / n) for k in range(n + 1) for j in range(n + 1) for i in range(n + 1)], rotation)
    elems = []
    for k_face, tag in ((0, 1), (n, 2)):
        for j in range(n):
            for i in range(n):
                a, b, c, d = vid(i, j, k_face), vid(i + 1, j, k_face), vid(i + 1, j + 1, k_face), vid(i, j + 1, k_face)
                elems += [f"2 2 {tag} {tag} {a} {b} {c}", f"2 2 {tag} {tag} {a} {c} {d}"]
    perms = [(0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)]
    for k in range(n):
        for j in range(n):
            for i in range(n):
                corner = lambda b: vid(i + (b & 1), j + ((b >> 1) & 1), k + ((b >> 2) & 1))  # noqa: E731
                for p in perms:
                    b1 = 1 << p[0]
                    b2 = b1 | (1 << p[1])
                    elems.append(f"4 2 10 10 {corner(0)} {corner(b1)} {corner(b2)} {corner(7)}")
    with open(path, "w") as fp:
        fp.write("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n%d\n" % len(nodes))
        fp.writelines(f"{m + 1} {x!r} {y!r} {z!r}\n" for m, (x, y, z) in enumerate(nodes))
        fp.write("$EndNodes\n$Elements\n%d\n" % len(elems))
        fp.writelines(f"{m + 1} {e}\n" for m, e in enumerate(elems))
        fp.write("$EndElements\n")
