"""Property-based fuzzing of the problem's option families (make test): random but type-aware values of the face sets
(names, numbers, and names no face carries), vectors of every length, slip components in and out of range, obstacles
with and without their data, eps, the material, E from 1e-6 to 1e16 and loads from 1e-9 to 1e12 times their values and misspelled
options, on small Gmsh meshes of the unit square and cube
whose sides are named (so the resultant of the loads is known in closed form).

Every run must end in one of three ways:
- refused (exit 2): one paragraph "signorini: error: ..." naming an option of the command line or the mesh file, no
  PETSc error block, and no output file;
- converged (exit 0): every written field finite, and the forces balanced: the obstacle's force, the supports'
  reactions and the applied loads (body force times volume, each traction times its side's area, each pressure times
  its side's area along the inward normal) sum to zero within 1e-10 of the largest of them (or of E max|u|, if larger);
- not converged (exit 3): reported as such, the output flagged converged = 0.
Any other exit (a crash, an abort, an MPI error) fails.

The draws are seeded, so a failure reproduces; SIGNORINI_FUZZ_EXAMPLES sets the number of runs of the
default test (300), and the long-marked test runs 2000 more (make test-long, or pytest -m long tests/test_fuzz.py).
"""
import math
import os
import re
import subprocess

import h5py
import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis", reason="python3-hypothesis is a test dependency (scripts/install-deps.sh)")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from harness import BIN, ENV, OUT, ROOT, SINGLETON_ENV  # noqa: E402

FUZZ = os.path.join(OUT, "fuzz")
EXAMPLES = int(os.environ.get("SIGNORINI_FUZZ_EXAMPLES", "300"))
SERIAL = dict(ENV, **SINGLETON_ENV)  # one process without mpiexec (harness.SINGLETON_ENV)

# The sides of the meshes: name -> (physical number, outward unit normal, area). The square [0,1]^2 and the cube [0,1]^3.
SIDES = {
    2: {"bottom": (1, (0, -1)), "right": (2, (1, 0)), "top": (3, (0, 1)), "left": (4, (-1, 0))},
    3: {"bottom": (1, (0, 0, -1)), "top": (2, (0, 0, 1)), "front": (3, (0, -1, 0)), "back": (4, (0, 1, 0)),
        "left": (5, (-1, 0, 0)), "right": (6, (1, 0, 0))},
}


def write_meshes(directory):
    """square.msh (h = 0.25) and cube.msh (h = 0.5), first order, sides as in SIDES, the body physical group 10."""
    import gmsh

    paths = {2: os.path.join(directory, "square.msh"), 3: os.path.join(directory, "cube.msh")}
    for dim, path in paths.items():
        gmsh.initialize()
        try:
            gmsh.option.setNumber("General.Terminal", 0)
            gmsh.option.setNumber("Mesh.MshFileVersion", 2.2)
            occ = gmsh.model.occ
            body = occ.addRectangle(0, 0, 0, 1, 1) if dim == 2 else occ.addBox(0, 0, 0, 1, 1, 1)
            occ.synchronize()
            for name, (tag, normal) in SIDES[dim].items():
                ents = []
                for d, e in gmsh.model.getBoundary([(dim, body)], oriented=False):
                    c = gmsh.model.occ.getCenterOfMass(d, e)
                    axis = int(np.argmax(np.abs(normal)))
                    if abs(c[axis] - (1.0 if normal[axis] > 0 else 0.0)) < 1e-9:
                        ents.append(e)
                assert len(ents) == 1, (name, ents)
                gmsh.model.addPhysicalGroup(dim - 1, ents, tag)
                gmsh.model.setPhysicalName(dim - 1, tag, name)
            gmsh.model.addPhysicalGroup(dim, [body], 10)
            gmsh.option.setNumber("Mesh.MeshSizeMax", 0.25 if dim == 2 else 0.5)
            gmsh.model.mesh.generate(dim)
            gmsh.write(path)
        finally:
            gmsh.finalize()
    return paths


@pytest.fixture(scope="module")
def meshes(out_root):
    os.makedirs(FUZZ, exist_ok=True)
    return write_meshes(FUZZ)


# ---- strategies ------------------------------------------------------------------------------------------------------
# A problem is drawn valid at every site (a site: one option's value), then up to two sites are drawn wrong: a run with
# no fault should solve, one with a fault must be refused or solve anyway (a fault a site tolerates, such as a plane
# that misses the body).

def tidy(x):
    """Loads and lengths of a physical size: 0 or at least 1e-6 in magnitude (a load of 1e-160 is below every tolerance
    of the solve, which then stops at u = 0 with the load unbalanced)."""
    return 0.0 if abs(x) < 1e-6 else x


def good_real(lo, hi):
    return st.floats(lo, hi, allow_nan=False, allow_infinity=False).map(lambda x: f"{tidy(x):.6g}")


BAD_REALS = st.sampled_from(["0", "-1", "inf", "-inf", "nan", "1e400", "abc", "1,", "1e-320"])


def good_vector(dim, lo, hi):
    return st.lists(st.floats(lo, hi, allow_nan=False), min_size=dim, max_size=dim).map(lambda v: ",".join(f"{tidy(x):.6g}" for x in v))


def bad_vector(dim):
    wrong_length = st.sampled_from([n for n in range(1, 5) if n != dim]).flatmap(lambda n: good_vector(n, -1, 1))
    with_bad_entry = st.tuples(good_vector(dim - 1, -1, 1), BAD_REALS).map(lambda t: t[0] + "," + t[1])
    return st.one_of(wrong_length, with_bad_entry, st.just(""), st.just(",".join(["0"] * dim)))


def bad_face(dim):
    names = list(SIDES[dim])
    return st.one_of(st.sampled_from(["7", "0", "-1", "99", "inner", "Bottom", "10", "bottom,bottom", "top,"]),
                     st.sampled_from(names))  # a side already taken by another family


class Sites:
    """Draws each site's value, good or, while the problem's fault budget lasts and with probability 1/6, bad."""

    def __init__(self, draw, faults):
        self.draw, self.faults, self.used = draw, faults, 0

    def __call__(self, good, bad):
        if self.faults > 0 and self.draw(st.integers(0, 5)) == 0:
            self.faults -= 1
            self.used += 1
            return self.draw(bad), True
        return self.draw(good), False


def plain(text, length):
    """The floats of a comma-separated text if there are length of them, all finite; else None."""
    try:
        v = np.array([float(x) for x in text.split(",")])
    except ValueError:
        return None
    return v if len(v) == length and np.all(np.isfinite(v)) else None


@st.composite
def problems(draw):
    """(dim, options, the resultant of the applied loads or None where a load is not a plain finite value, whether a
    fault was drawn)."""
    dim = draw(st.sampled_from([2, 2, 3]))
    site = Sites(draw, draw(st.sampled_from([0, 0, 1, 1, 2])))
    opts = {"-scene": "general", "-dm_plex_dim": str(dim)}
    load = np.zeros(dim)
    known = True
    sides = draw(st.permutations([n for n in SIDES[dim] if n != "bottom"]))
    token = lambda name: draw(st.sampled_from([name, str(SIDES[dim][name][0])]))  # noqa: E731
    down = np.eye(dim)[dim - 1] * -1

    contact = ["bottom"] + ([sides.pop()] if draw(st.integers(0, 5)) == 0 else [])
    value, _ = site(st.just(",".join(token(n) for n in contact)), bad_face(dim))
    opts["-contact_faces"] = value
    n_clamp = draw(st.integers(0, 1)) if draw(st.integers(0, 3)) else 2
    n_slip = draw(st.integers(0, 2)) if n_clamp else 2 if dim == 2 else 3
    for family, count in (("clamp", n_clamp), ("slip", n_slip), ("traction", draw(st.integers(0, 1))),
                          ("pressure", draw(st.integers(0, 1)))):
        chosen = [sides.pop() for _ in range(min(count, len(sides)))]
        if not chosen:
            continue
        tokens = [token(n) for n in chosen]
        value, bad = site(st.just(",".join(tokens)), bad_face(dim))
        opts[f"-bc_{family}"] = value
        if bad:
            known = False
        for name, t in zip(chosen, tokens):
            normal = np.array(SIDES[dim][name][1], float)
            if family == "clamp" and draw(st.booleans()):
                opts[f"-bc_clamp_{t}_translate"], _ = site(st.just(",".join(f"{x:.6g}" for x in -0.01 * normal)), bad_vector(dim))
            elif family == "slip":
                axis = int(np.argmax(np.abs(normal)))  # the slip plane's normal component, fixed: a roller
                good = st.just(str(axis)) if dim == 2 else st.sampled_from([str(axis), f"{axis},{(axis + 1) % 3}"])
                bad = st.sampled_from(["-1", str(dim), ",".join(map(str, range(dim))), "", "0,0", "x"])
                opts[f"-bc_slip_{t}_components"], _ = site(good, bad)
                if draw(st.booleans()):
                    opts[f"-bc_slip_{t}_translate"], _ = site(good_vector(dim, -0.01, 0.01), bad_vector(dim))
            elif family == "traction":
                value, _ = site(good_vector(dim, -0.05, 0.05), bad_vector(dim))
                opts[f"-bc_traction_{t}"] = value
                v = plain(value, dim)
                if v is None:
                    known = False
                else:
                    load += v  # every side has area 1
            elif family == "pressure":
                value, _ = site(good_real(-0.05, 0.05), BAD_REALS)
                opts[f"-bc_pressure_{t}"] = value
                v = plain(value, 1)
                if v is None:
                    known = False
                else:
                    load += -v[0] * normal
    if draw(st.booleans()):
        value, _ = site(good_vector(dim, -0.05, 0.05), bad_vector(dim))
        opts["-body_force"] = value
        v = plain(value, dim)
        if v is None:
            known = False
        else:
            load += v  # the volume is 1
    if n_clamp == 0 and not any(k.startswith("-bc_clamp") for k in opts):
        if "-body_force" not in opts:  # slips alone: the body force pushes the body onto the obstacle
            opts["-body_force"] = ",".join(f"{x:.6g}" for x in 0.02 * down)
            load += 0.02 * down
    method, _ = site(st.sampled_from(["penalty", "penalty", "penalty", "vi", "none"]), st.sampled_from(["lagrange", "", "PENALTY"]))
    opts["-contact_method"] = method
    obstacle, _ = site(st.sampled_from(["plane", "plane", "sphere", "cylinder"] if method != "vi" else ["plane"]),
                       st.sampled_from(["torus", "", "sphere" if method == "vi" else "plane,sphere"]))
    opts["-obstacle"] = obstacle
    if obstacle == "plane" and draw(st.booleans()):
        opts["-obstacle_point"], _ = site(good_vector(dim, -0.02, 0.02), bad_vector(dim))
        tilted = good_vector(dim - 1, -0.3, 0.3).map(lambda s: s + ",-1")
        opts["-obstacle_normal"], _ = site(st.just(",".join(f"{x:g}" for x in down)) if method == "vi" else tilted, bad_vector(dim))
    if obstacle in ("sphere", "cylinder"):
        center = "0.5,-2" if dim == 2 else "0.5,0.5,-2"  # a ball or a cylinder of radius 2 under the bottom, touching it
        opts["-obstacle_center"], _ = site(st.just(center), bad_vector(dim))
        opts["-obstacle_radius"], _ = site(good_real(1.98, 2.0), BAD_REALS)
        if obstacle == "cylinder" and dim == 3:
            opts["-obstacle_axis"], _ = site(st.sampled_from(["1,0,0", "0,1,0", "1,1,0"]), bad_vector(3))
    if draw(st.booleans()):
        opts["-obstacle_translate"], _ = site(good_vector(dim, -0.01, 0.01), bad_vector(dim))
    if method == "penalty":
        opts["-penalty_quadrature"], _ = site(st.sampled_from(["gauss", "nodal"]), st.sampled_from(["simpson", "", "Gauss"]))
        opts["-penalty_eps0"], _ = site(st.sampled_from(["1", "0.1", "0.01"]), BAD_REALS)
    if draw(st.integers(0, 3)) == 0:
        opts["-young_modulus"], _ = site(good_real(0.5, 100), BAD_REALS)
    if draw(st.integers(0, 3)) == 0:
        opts["-poisson_ratio"], _ = site(good_real(-0.5, 0.45), st.sampled_from(["0.5", "0.6", "-1", "-1.5", "nan", "x"]))
    if site.faults > 0 and draw(st.integers(0, 5)) == 0:
        opts[draw(st.sampled_from(["-bc_clam", "-contact_face", "-snes_rtoll", "-obstacle_radious", "-penalty_eps_0"]))] = "1"
        site.used += 1
    if draw(st.integers(0, 2)) == 0:  # other units: E times 10^a, every load times 10^b (the displacement 10^(b-a))
        scale_e, scale_load = 10.0 ** draw(st.integers(-6, 16)), 10.0 ** draw(st.integers(-9, 12))
        for key in list(opts):
            factor = scale_e if key == "-young_modulus" else scale_load if key == "-body_force" or key.startswith(("-bc_traction_", "-bc_pressure_")) else None
            if factor is not None:
                try:
                    opts[key] = ",".join(f"{float(x) * factor:.6g}" for x in opts[key].split(","))
                except ValueError:
                    pass  # a bad value stays as drawn
        if "-young_modulus" not in opts:
            opts["-young_modulus"] = f"{scale_e:g}"
        load = load * scale_load
    return dim, opts, (load if known else None), site.used > 0


# ---- the properties -------------------------------------------------------------------------------------------------

def check_run(meshes, dim, opts, load, name, faulty=True):
    out = os.path.join(FUZZ, name + ".h5")
    for path in (out, out[:-3] + ".xdmf"):
        if os.path.exists(path):
            os.remove(path)
    args = ["-dm_plex_filename", meshes[dim], "-output", out, "-snes_rtol", "1e-10", "-snes_max_it", "40"]
    for key, value in opts.items():
        args += [key, value]
    p = subprocess.run([BIN] + args, cwd=ROOT, env=SERIAL, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                       timeout=120)
    text = p.stdout
    command = " ".join(args)
    assert p.returncode in (0, 2, 3), f"exit {p.returncode}: {command}\n{text[-3000:]}"
    if p.returncode == 2:
        assert "signorini: error:" in text, f"refusal without its paragraph: {command}\n{text[-3000:]}"
        assert "PETSC ERROR" not in text, f"PETSc's block after a refusal: {command}\n{text[-3000:]}"
        message = text[text.index("signorini: error:"):]
        assert re.search(r"(^|[\s(`'\"])-[a-z][a-z0-9_]+", message[len("signorini: error:"):]) or meshes[dim] in message, \
            f"a refusal naming no option nor file: {command}\n{message}"
        assert not os.path.exists(out), f"a refused run wrote {out}: {command}"
        return "refused"
    with h5py.File(out, "r") as f:
        attrs = dict(f["run"].attrs)
        u_max = float(np.abs(f["vertex_fields/displacement"][:]).max())
        for key in f["vertex_fields"]:
            values = f["vertex_fields"][key][:]
            assert np.all(np.isfinite(values)), f"non-finite {key}: {command}"
    if p.returncode == 3:
        assert attrs["converged"] == 0, f"exit 3 but written as converged: {command}"
        assert faulty, f"a draw without a fault did not converge: {command}\n{text[-3000:]}"
        return "diverged"
    assert attrs["converged"] == 1, command
    force = np.array([attrs.get(f"contact_force_{c}", 0.0) for c in "xyz"[:dim]])
    reactions, largest = np.zeros(dim), 0.0
    for key, value in attrs.items():
        m = re.match(r"reaction_.*_([xyz])$", key)
        if m and "xyz".index(m.group(1)) < dim:
            reactions["xyz".index(m.group(1))] += value
            largest = max(largest, abs(value))
    if load is not None:
        # the largest force, at least the stiffness's force scale E |u| (a rigid motion moves the body without force)
        scale = max(np.abs(load).max(), np.abs(force).max(), largest, attrs["young_modulus"] * u_max, 1e-300)
        residual = np.abs(force + reactions + load).max()
        assert residual <= 1e-10 * scale, f"forces off balance by {residual:.3e} of {scale:.3e}: {command}\n" \
            f"force {force} reactions {reactions} load {load}"
    return "converged"


OUTCOMES = {}


def fuzz(meshes, examples, seed_name, seed):
    @hypothesis.seed(seed)
    @settings(max_examples=examples, deadline=None, database=None, print_blob=True, suppress_health_check=list(HealthCheck))
    @given(problems())
    def property_(problem):
        dim, opts, load, faulty = problem
        outcome = check_run(meshes, dim, opts, load, seed_name, faulty)
        OUTCOMES.setdefault(seed_name, {}).setdefault(outcome, 0)
        OUTCOMES[seed_name][outcome] += 1

    property_()
    return OUTCOMES.get(seed_name, {})


def test_fuzz_option_families(meshes):
    counts = fuzz(meshes, EXAMPLES, "default", 29)
    print("fuzz outcomes:", counts)
    # The draws must reach both sides: runs that solve and runs that are refused (else the strategies have drifted).
    assert counts.get("converged", 0) >= EXAMPLES // 10 and counts.get("refused", 0) >= EXAMPLES // 10, counts


@pytest.mark.long
@pytest.mark.slow
def test_fuzz_option_families_long(meshes):
    counts = fuzz(meshes, 2000, "long", 2029)
    print("fuzz outcomes:", counts)
    assert counts.get("converged", 0) >= 100, counts
