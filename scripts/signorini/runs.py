"""Reading the solver's HDF5 outputs: the /run attributes (as plain Python or as stored), the
vertex fields (in the file's order with the coordinates, or in an order that does not depend on the
ranks), the per-solve history (/solves) and the values on the contact boundary."""
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


def vertex_order(x):
    """The permutation putting the vertices of coordinates x (one row a vertex) in an order that does not depend on the
    ranks: lexicographic in the coordinates rounded to 12 digits, the last coordinate first."""
    return np.lexsort(np.round(x, 12).T)


def field_at(ds, step=-1):
    """The values of a /vertex_fields dataset: of one step (the last by default) where it is a load path's time series
    (attribute timestepping: the step the first dimension), else the dataset itself."""
    return ds[step] if int(ds.attrs.get("timestepping", 0)) else ds[()]


def read_steps(path):
    """({column: 1-D array} of /steps, {name: array of the steps' values} of the time series of /vertex_fields) of a load
    path's output; ({}, {}) for a run without one."""
    with h5py.File(path, "r") as f:
        steps = {k: np.asarray(f["steps"][k][:]).ravel() for k in f["steps"]} if "steps" in f else {}
        series = {k: f["vertex_fields"][k][()] for k in f["vertex_fields"] if int(f["vertex_fields"][k].attrs.get("timestepping", 0))}
    return steps, series


def read_cycles(path):
    """The adaptive cycles' table /cycles (-adapt_cycles, -accuracy): one array per column."""
    with h5py.File(path, "r") as f:
        return {k: np.asarray(f["cycles"][k][:]).ravel() for k in f["cycles"]}


def accuracy_bars(attrs, quantities):
    """-accuracy's bars relative to their values, from a run's /run attributes."""
    return {q: float(attrs[f"accuracy_{q}_bar"]) / abs(float(attrs[f"accuracy_{q}_value"])) for q in quantities}


def own_bars(attrs, names):
    """-bars' bars relative to their values, from a run's /run attributes: {name: bar / |value|} for the qoi names
    (contact_force_y, pressure_max, contact_size, ...), NaN where the three levels gave no bar (qoi_NAME_note says why)."""
    return {n: float(attrs.get(f"qoi_{n}_bar", "nan")) / abs(float(attrs[f"qoi_{n}"])) for n in names}


def read_output(path):
    """(attrs, fields) of the output `path`: the /run attributes with bytes decoded (numbers stay numpy scalars), and
    {name: array} of /vertex_fields in the file's vertex order (a load path's: its last step), plus "x":
    /geometry/vertices (vertex_order(fields["x"]) sorts them)."""
    with h5py.File(path, "r") as f:
        attrs = decoded_attrs(f["run"])
        fields = {k: field_at(f["vertex_fields"][k]) for k in f["vertex_fields"]}
        fields["x"] = f["geometry/vertices"][:]
    return attrs, fields


def vertex_fields(path):
    """{name: array} of /vertex_fields (a load path's: its last step), the vertices sorted by position (vertex_order:
    rank-independent)."""
    with h5py.File(path, "r") as f:
        order = vertex_order(f["geometry/vertices"][:])
        return {k: field_at(f["vertex_fields"][k])[order] for k in f["vertex_fields"]}


def read_solves(f):
    """{name: 1-D array} of the /solves group of an open file (one entry per solve), {} if none."""
    if "solves" not in f:
        return {}
    return {k: np.asarray(f["solves"][k][:]).ravel() for k in f["solves"]}


ABSCISSAE = ("x", "y", "z", "arc", "r")


def _arc_length(x, mask, cells):
    """Signed arc length of the Gamma_C vertices along the contact curve (2D): the boundary edges with both ends on
    Gamma_C, walked from the lowest vertex (smallest last coordinate), negative toward smaller x_1."""
    count = {}
    for c in cells:
        for i in range(len(c)):
            e = tuple(sorted((int(c[i]), int(c[(i + 1) % len(c)]))))
            count[e] = count.get(e, 0) + 1
    nbrs = {}
    for (a, b), n in count.items():
        if n == 1 and mask[a] and mask[b]:
            nbrs.setdefault(a, []).append(b)
            nbrs.setdefault(b, []).append(a)
    idx = np.flatnonzero(mask)
    start = idx[np.argmin(x[idx, -1])]
    s = {start: 0.0}
    for first in nbrs.get(start, []):
        sign = 1.0 if x[first, 0] >= x[start, 0] else -1.0
        prev, cur, length = start, first, 0.0
        while cur is not None and cur not in s:
            length += np.linalg.norm(x[cur] - x[prev])
            s[cur] = sign * length
            nxt = [v for v in nbrs.get(cur, []) if v != prev]
            prev, cur = cur, (nxt[0] if nxt else None)
    missing = [v for v in idx if v not in s]
    if missing:
        raise ValueError(f"{len(missing)} Gamma_C vertices are not on the curve through the lowest one: the arc length needs one connected contact curve")
    return np.array([s[v] for v in idx])


def read_contact(h5path, along="x"):
    """Return (abscissa, pressure, gap, run_attrs) for the Gamma_C vertices, sorted by the abscissa (read_contact_fields)."""
    t, fields, run = read_contact_fields(h5path, along)
    return t, fields["contact_pressure"], fields["normal_gap"], run


def read_contact_fields(h5path, along="x", optional=()):
    """Return (abscissa, {name: values}, run_attrs) for the Gamma_C vertices, sorted by the abscissa: the pressure and the
    gap, and each vertex field of `optional` that the file has (contact_pressure_bar: the pressure's band of -bars).

    along: "x", "y", "z" (a coordinate), "arc" (2D: the signed arc length along the contact curve from its lowest vertex)
    or "r" (the distance from the lowest vertex in the coordinates other than the last, for bodies touching a plane
    x_d = const). Raises ValueError if the file cannot be read, lacks a needed dataset, has no contact-boundary vertices,
    or the abscissa does not apply.
    """
    if along not in ABSCISSAE:
        raise ValueError(f"unknown abscissa '{along}': one of {', '.join(ABSCISSAE)}")
    try:
        with h5py.File(h5path, "r") as f:
            x = f["geometry/vertices"][()]
            vf = f["vertex_fields"]
            mask = np.isclose(field_at(vf["contact_boundary"]), 1.0)
            fields = {name: field_at(vf[name]) for name in ("contact_pressure", "normal_gap") + tuple(optional) if name in vf}
            if "contact_pressure" not in fields or "normal_gap" not in fields:
                raise KeyError("contact_pressure or normal_gap")
            run = decoded_attrs(f["run"]) if "run" in f else {}
            cells = f["viz/topology/cells"][()] if along == "arc" else None
    except Exception as exc:
        raise ValueError(f"{h5path}: cannot read contact data ({exc})") from exc
    if not mask.any():
        raise ValueError(f"{h5path}: no contact_boundary vertices (Gamma_C is empty)")
    x = x.reshape(len(mask), -1)
    dim = x.shape[1]
    if along in ("x", "y", "z"):
        axis = "xyz".index(along)
        if axis >= dim:
            raise ValueError(f"{h5path}: a {dim}D mesh has no coordinate {along}")
        t = x[mask, axis]
    elif along == "arc":
        if dim != 2:
            raise ValueError(f"{h5path}: the arc length is for 2D contact curves; use r or a coordinate in {dim}D")
        t = _arc_length(x, mask, cells.astype(int))
    else:
        idx = np.flatnonzero(mask)
        low = x[idx[np.argmin(x[idx, -1])], :-1]
        t = np.linalg.norm(x[mask, :-1] - low, axis=1)
    order = np.argsort(t, kind="stable")
    return t[order], {name: np.ravel(v)[mask][order] for name, v in fields.items()}, run
