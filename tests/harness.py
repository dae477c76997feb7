"""Shared helpers of the test suite: running the solver and reading its output back."""
import os
import subprocess
import sys

import h5py
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
import read_runs  # noqa: E402

BIN = os.path.join(ROOT, "bin", "signorini")
OUT = os.path.join(ROOT, "tests", "out")
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OMPI_MCA_rmaps_base_oversubscribe="1")


def run(args, name, np_=1, expect_rc=0, output=None):
    """Runs the solver; returns (combined output, path of the HDF5 file: tests/out/NAME.h5, or output)."""
    out = output or os.path.join(OUT, name + ".h5")
    cmd = ["mpiexec", "-n", str(np_), BIN, "-output", out] + [str(a) for a in args]
    p = subprocess.run(cmd, cwd=ROOT, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=600)
    if expect_rc is not None:
        assert p.returncode == expect_rc, f"exit code {p.returncode}, expected {expect_rc}: {' '.join(cmd)}\n{p.stdout[-3000:]}"
    return p.stdout, out


def load(path):
    with h5py.File(path, "r") as f:
        attrs = {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f["run"].attrs.items()}
        fields = {k: f["vertex_fields"][k][:] for k in f["vertex_fields"]}
        fields["x"] = f["geometry/vertices"][:]
    return attrs, fields


def sorted_by_position(fields, key):
    """Field values in a rank-independent vertex order (lexicographic in the coordinates)."""
    order = np.lexsort(np.round(fields["x"], 12).T)
    return fields[key][order]


def write_gmsh_square(path, n, with_contact=True, with_clamp=True, quads=False):
    """A Gmsh 2.2 file of the unit square in n x n cells, triangles split like the built-in simplex box (or quadrilaterals),
    physical lines 1-4 numbered as PETSc's box (bottom 1 = Gamma_C, top 3 = the clamped face of the built-in scenes)."""
    nodes = [(i / n, j / n) for j in range(n + 1) for i in range(n + 1)]
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


def write_gmsh_cube(path, n):
    """A Gmsh 2.2 file of the unit cube in n^3 cubes of 6 Kuhn tetrahedra, physical surfaces numbered as PETSc's box
    (bottom z = 0 1, top 2)."""
    vid = lambda i, j, k: (k * (n + 1) + j) * (n + 1) + i + 1  # noqa: E731
    nodes = [(i / n, j / n, k / n) for k in range(n + 1) for j in range(n + 1) for i in range(n + 1)]
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
