"""The output (make test): the HDF5 file read back by the Python reader, the XDMF beside it, the plot, YAML option
files, and a Gmsh mesh equal to the built-in box."""
import math
import os
import subprocess
import sys
import xml.etree.ElementTree as ET

import h5py
import numpy as np
import pytest

from harness import ENV, OUT, ROOT, load, read_runs, run, write_gmsh_square


def test_hdf5_read_back_by_python_reader():
    _, h5 = run(["-dm_plex_box_faces", "8,8"], "reader")
    with h5py.File(h5, "r") as f:
        raw = dict(f["run"].attrs)
        nv = f["geometry/vertices"].shape[0]
        assert f["vertex_fields/displacement"].shape == (nv, 2)
    row = read_runs.read_run(h5)
    for key, value in raw.items():
        value = value.decode() if isinstance(value, bytes) else value
        assert row[key] == value, key
    required = ("scene dim method degree nprocs n_cells n_vertices n_dofs h eps young_modulus poisson_ratio snes_reason converged newton_its "
                "ksp_its time_setup time_solve time_total active_vertices max_penetration contact_force energy").split()
    missing = [k for k in required if k not in row]
    assert not missing, f"missing /run attributes: {missing}"
    assert row["n_vertices"] == nv == 81 and row["n_cells"] == 128 and row["n_dofs"] == 2 * (81 - 9)
    assert abs(row["h"] - math.sqrt(2) / 8) < 1e-14 and abs(row["eps"] - row["h"]) < 1e-14
    csv_out = os.path.join(OUT, "runs.csv")
    _, h5b = run(["-dm_plex_box_faces", "8,8", "-contact_method", "vi"], "reader_vi")
    assert read_runs.main([h5, h5b, "--format", "csv", "-o", csv_out]) == 0
    lines = open(csv_out).read().strip().splitlines()
    assert len(lines) == 3 and "contact_force" in lines[0]


def test_xdmf_points_at_existing_datasets():
    _, h5 = run(["-dm_plex_box_faces", "8,8"], "xdmf")
    xdmf = h5[:-3] + ".xdmf"
    root = ET.parse(xdmf).getroot()
    with h5py.File(h5, "r") as f:
        items = root.iter("DataItem")
        n = 0
        for item in items:
            fname, path = item.text.strip().split(":")
            assert fname == os.path.basename(h5)
            dims = tuple(int(d) for d in item.get("Dimensions").split())
            assert f[path].shape == dims, f"{path}: {f[path].shape} vs {dims}"
            n += 1
        assert n == 10  # topology, geometry, the vertex fields (displacement, pressure, gap, boundary, reaction, area), the cell fields
        # (error_indicator, error_density)


def test_plot_script_writes_png(outdir):
    _, h5 = run(["-dm_plex_box_faces", "8,8"], "plot")
    png = os.path.join(outdir, "plot_contact.png")
    subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "plot_contact.py"), h5, "-o", png], check=True, env=ENV,
                   stdout=subprocess.DEVNULL)
    with open(png, "rb") as fp:
        assert fp.read(8) == b"\x89PNG\r\n\x1a\n"


def test_yaml_options_file():
    log, h5 = run(["-options_file", "options/square.yaml", "-dm_plex_box_faces", "8,8", "-options_file", "options/solvers/hypre.yaml"], "yaml")
    attrs, _ = load(h5)
    assert attrs["converged"] == 1 and attrs["scene"] == "square" and attrs["n_cells"] == 128 and attrs["ksp_its"] > attrs["newton_its"]


def test_gmsh_mesh_matches_builtin_box(outdir):
    msh = os.path.join(outdir, "square8.msh")
    write_gmsh_square(msh, 8)
    a_box, _ = load(run(["-dm_plex_box_faces", "8,8"], "box8")[1])
    a_msh, _ = load(run(["-dm_plex_filename", msh], "msh8")[1])
    assert a_msh["converged"] == 1 and a_msh["n_cells"] == a_box["n_cells"]
    for key in ("contact_force", "energy", "max_penetration"):
        assert abs(a_msh[key] - a_box[key]) <= 1e-10 * abs(a_box[key]), f"{key}: {a_msh[key]} vs {a_box[key]}"


@pytest.mark.parametrize("np_,extra,name", (
    (1, ["-dm_plex_box_faces", "9,7"], "tri"),
    (1, ["-dm_plex_dim", 3, "-dm_plex_box_faces", "3,4,2"], "tet"),
    (1, ["-dm_plex_simplex", 0, "-dm_plex_box_faces", "6,5"], "quad"),
    (1, ["-dm_plex_dim", 3, "-dm_plex_simplex", 0, "-dm_plex_box_faces", "3,2,3"], "hex"),
    (2, ["-dm_plex_box_faces", "9,7"], "tri_np2"),
    (3, ["-dm_plex_dim", 3, "-dm_plex_box_faces", "4,3,5"], "tet_np3"),
    (2, ["-dm_plex_dim", 3, "-dm_plex_simplex", 0, "-dm_plex_box_faces", "3,2,3"], "hex_np2"),
    (2, ["-dm_plex_filename", "options/meshes/square8.msh"], "gmsh_np2")))
def test_mesh_datasets_are_dmviews(np_, extra, name):
    """The project writes /geometry/vertices and /viz/topology/cells itself (src/io/output_mesh.c); -output_dmview has
    PETSc's DMView() write them. Both files must hold the same datasets, with the same shapes, types, attributes and
    values to the last bit (and on one rank every other dataset too, the times aside)."""
    files = []
    for how, flag in (("own", []), ("dmview", ["-output_dmview"])):
        _, h5 = run(["-options_file", "options/square.yaml", "-contact_monitor", "0"] + extra + flag, f"mesh_view_{name}_{how}", np_=np_)
        files.append(h5)
    with h5py.File(files[0], "r") as a, h5py.File(files[1], "r") as b:
        names_a, names_b = [], []
        a.visit(names_a.append)
        b.visit(names_b.append)
        assert sorted(names_a) == sorted(names_b)
        for key in ("geometry/vertices", "viz/topology/cells"):
            assert a[key].shape == b[key].shape and a[key].dtype == b[key].dtype, key
            assert np.array_equal(a[key][...], b[key][...]), key
            assert dict(a[key].attrs) == dict(b[key].attrs), key
        assert a["viz/topology/cells"].shape[0] == a["run"].attrs["n_cells"]
        if np_ == 1:
            for key in names_a:
                if isinstance(a[key], h5py.Dataset) and not key.startswith("solves/time"):
                    assert np.array_equal(a[key][...], b[key][...]), key


def test_the_peak_memory_is_the_run_s_own_not_its_starter_s():
    """/run peak_memory_mb is the run's own high-water mark (VmHWM): a run started by a process holding 400 MB (this
    test's Python, as a script that keeps its results does) reports its own 50-odd MB. getrusage()'s ru_maxrss, kept
    across execve(), reported the starter's resident set, and the suite's memory-budget test saw 179 to 211 MB for a
    run whose cycles held 114 (tests/test_accuracy.py)."""
    ballast = np.ones(400 * 2**20 // 8)  # 400 MB, touched
    _, h5 = run(["-dm_plex_box_faces", "8,8"], "peak_memory_own")
    a, _ = load(h5)
    assert ballast.sum() > 0 and 10 < a["peak_memory_mb"] < 200 and a["peak_memory_total_mb"] == a["peak_memory_mb"], a["peak_memory_mb"]
    _, h5 = run(["-dm_plex_box_faces", "8,8"], "peak_memory_own_np2", np_=2)
    b, _ = load(h5)
    assert 10 < b["peak_memory_mb"] < 200 and b["peak_memory_mb"] <= b["peak_memory_total_mb"] <= 2 * b["peak_memory_mb"], b
