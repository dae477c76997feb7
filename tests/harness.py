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
TESTS = []


def test(fn):
    TESTS.append(fn)
    return fn


def run(args, name, np_=1, expect_rc=0):
    """Runs the solver; returns (combined output, path of the HDF5 file)."""
    out = os.path.join(OUT, name + ".h5")
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
