"""Reading the solver's HDF5 outputs: the /run attributes (as plain Python or as stored), the
vertex fields in an order that does not depend on the ranks, the per-solve history (/solves) and
the values on the contact boundary."""
import os

import h5py
import numpy as np


def to_python(value):
    """Convert an HDF5 attribute value to plain Python (bytes -> str, numpy -> int/float/list)."""
    if isinstance(value, (bytes, np.bytes_)):
        return bytes(value).decode("utf-8", errors="replace")
    if isinstance(value, np.ndarray):
        if value.ndim == 0:
            return to_python(value[()])
        return [to_python(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


def decoded_attrs(group):
    """The attributes of an open HDF5 group with bytes decoded; numbers stay numpy scalars."""
    return {k: (v.decode() if isinstance(v, bytes) else v) for k, v in group.attrs.items()}


def read_run(path):
    """Return all attributes of /run in the HDF5 file `path` as a dict.

    The key "file" is set to `path`. Raises ValueError naming the file if it
    cannot be opened or has no /run group.
    """
    try:
        with h5py.File(path, "r") as f:
            if "run" not in f:
                raise ValueError(f"{path}: no /run group")
            run = {"file": str(path)}
            for key, value in f["run"].attrs.items():
                run[key] = to_python(value)
            return run
    except ValueError:
        raise
    except Exception as exc:  # h5py raises OSError and others
        raise ValueError(f"{path}: cannot read HDF5 file ({exc})") from exc


def expand_paths(paths):
    """Expand directories into their sorted *.h5 files; ValueError on a missing path or empty dir."""
    out = []
    for p in paths:
        p = str(p)
        if os.path.isdir(p):
            files = sorted(os.path.join(p, n) for n in os.listdir(p)
                           if n.endswith(".h5") and os.path.isfile(os.path.join(p, n)))
            if not files:
                raise ValueError(f"{p}: directory contains no *.h5 files")
            out.extend(files)
        elif os.path.exists(p):
            out.append(p)
        else:
            raise ValueError(f"{p}: no such file or directory")
    return out


def read_runs(paths):
    """Read /run of every file in `paths` (directories expanded); list of dicts."""
    return [read_run(p) for p in expand_paths(paths)]


def all_columns(runs):
    """Union of the keys of all runs, in order of first appearance."""
    cols = {}
    for run in runs:
        for key in run:
            cols.setdefault(key, None)
    return list(cols)


def vertex_fields(path):
    """{name: array} of /vertex_fields, the vertices sorted by position (rank-independent order)."""
    with h5py.File(path, "r") as f:
        x = f["geometry/vertices"][:]
        order = np.lexsort(np.round(x, 12).T)  # a vertex order that does not depend on the ranks
        return {k: f["vertex_fields"][k][:][order] for k in f["vertex_fields"]}


def read_solves(f):
    """{name: 1-D array} of the /solves group of an open file (one entry per solve), {} if none."""
    if "solves" not in f:
        return {}
    return {k: np.asarray(f["solves"][k][:]).ravel() for k in f["solves"]}


def read_contact(h5path):
    """Return (x1, pressure, gap, run_attrs) for the Gamma_C vertices, sorted by x1.

    Raises ValueError if the file cannot be read, lacks a needed dataset, or
    has no contact-boundary vertices.
    """
    try:
        with h5py.File(h5path, "r") as f:
            x = f["geometry/vertices"][()]
            vf = f["vertex_fields"]
            mask = np.isclose(vf["contact_boundary"][()], 1.0)
            p = vf["contact_pressure"][()]
            g = vf["normal_gap"][()]
            run = decoded_attrs(f["run"]) if "run" in f else {}
    except Exception as exc:
        raise ValueError(f"{h5path}: cannot read contact data ({exc})") from exc
    if not mask.any():
        raise ValueError(f"{h5path}: no contact_boundary vertices (Gamma_C is empty)")
    x1 = x[mask, 0] if x.ndim == 2 else x[mask]
    order = np.argsort(x1, kind="stable")
    return x1[order], p[mask][order], g[mask][order], run
