"""Load paths (-load_steps, -load_path; issue 32): each step's answer is the direct solve's at its factor, with the
data scaled in the options instead (frictionless elasticity has no history), whether the factor is reached by loading,
by unloading or directly; 2 ranks give 1 rank's steps; a failed step ends the path, flagged; bad input is refused before
any solve, with no output written."""
import os

import h5py
import numpy as np
import pytest

from harness import load, refused, run, solve
from signorini import hertz

SQUARE = ["-options_file", "options/square.yaml", "-contact_monitor", "false", "-snes_rtol", "1e-12"]
# a cylinder pressed into the top of a clamped block: the contact zone grows with the indentation (a curved gap)
INDENT = ["-scene", "general", "-dm_plex_box_faces", "32,16", "-contact_faces", "3", "-bc_clamp", "1", "-obstacle", "cylinder",
          "-obstacle_center", "0.5,1.5", "-obstacle_radius", "0.5", "-snes_rtol", "1e-12"]
QUANTITIES = ("contact_force", "contact_force_x", "contact_force_y", "energy", "pressure_max", "contact_size")


def steps(path):
    with h5py.File(path, "r") as f:
        return {k: f["steps"][k][:] for k in f["steps"]}


def vec(values):
    return ",".join(f"{v:.17g}" for v in values)


def assert_step_is_direct(st, k, attrs, rtol=1e-8):
    for q in QUANTITIES + tuple(k_ for k_ in st if k_.startswith("reaction_")):
        tol = rtol * abs(attrs[q]) + 1e-12 * abs(attrs["contact_force"])  # a component zero by symmetry is round-off
        assert abs(st[q][k] - attrs[q]) <= tol, (k, q, st[q][k], attrs[q])


def test_steps_are_the_direct_solves_square(outdir):
    """The square (its body force scales: square_beta) along 0.5, 1.5, 1: each row of /steps is the direct run with
    -square_beta 2t; the last step's fields are the direct run's at 1."""
    _, h5 = run(SQUARE + ["-load_path", "0.5,1.5,1"], "path", output=os.path.join(outdir, "path.h5"))
    st = steps(h5)
    assert list(st["factor"]) == [0.5, 1.5, 1.0] and st["converged"].all()
    for k, t in enumerate((0.5, 1.5, 1.0)):
        _, d = run(SQUARE + ["-square_beta", 2 * t], f"direct_{k}", output=os.path.join(outdir, f"direct_{k}.h5"))
        attrs, fields = load(d)
        assert_step_is_direct(st, k, attrs)
    last, path_fields = load(h5)
    assert np.max(np.abs(path_fields["displacement"] - fields["displacement"])) <= 1e-8 * np.max(np.abs(fields["displacement"]))


@pytest.mark.parametrize("np_", [1, 2])
def test_steps_are_the_direct_solves_indentation(outdir, np_):
    """A cylinder driven by displacement into a block whose clamp also moves and whose side carries a traction, in 3
    steps: the obstacle's translation, the clamp's and the traction scale, the gap does not; each row is the direct run
    with the scaled options, on 1 and 2 ranks."""
    move, clamp, load_ = np.array([0.0, -0.02]), np.array([0.002, 0.0]), np.array([0.0, -0.01])
    data = lambda t: ["-obstacle_translate", vec(t * move), "-bc_clamp_1_translate", vec(t * clamp), "-bc_traction", "2",  # noqa: E731
                      "-bc_traction_2", vec(t * load_)]
    _, h5 = run(INDENT + data(1.0) + ["-load_steps", "3"], "steps", np_=np_, output=os.path.join(outdir, "steps.h5"))
    st = steps(h5)
    assert np.allclose(st["factor"], [1 / 3, 2 / 3, 1]) and st["converged"].all()
    assert np.all(np.diff(st["contact_size"]) > 0), st["contact_size"]  # the zone grows: the curved gap is not scaled
    assert np.allclose(st["obstacle_translate_y"], st["factor"] * move[1], rtol=1e-14)
    for k, t in enumerate(st["factor"]):
        _, d = run(INDENT + data(t), f"direct_{k}", np_=np_, output=os.path.join(outdir, f"direct_{k}.h5"))
        assert_step_is_direct(st, k, load(d)[0])


def test_the_same_factor_by_any_path(outdir):
    """Factor 1 reached directly, by loading (0.25, 0.5, 1) and by unloading (2, 1): the same displacement to the solver's
    tolerance."""
    fields = {}
    for name, path in (("direct", "1"), ("loading", "0.25,0.5,1"), ("unloading", "2,1")):
        _, h5 = run(INDENT + ["-obstacle_translate", "0,-0.02", "-load_path", path], name, output=os.path.join(outdir, f"{name}.h5"))
        fields[name] = load(h5)[1]["displacement"]
    scale = np.max(np.abs(fields["direct"]))
    for name in ("loading", "unloading"):
        assert np.max(np.abs(fields[name] - fields["direct"])) <= 1e-8 * scale, name


@pytest.mark.parametrize("np_", [1, 2])
def test_unloading_the_sphere_indenter(outdir, np_):
    """The 3D sphere indenter (make hertz's mesh at h_near 0.02, eps = h/100) unloaded from 1 to 0.5 and 0.25, then
    loaded to 0.6: every step is the direct run at its factor (force and energy to 1e-8), on 1 and 2 ranks. The secant's
    guess u/2 lifts all but a few nodes off the sphere, whose profile does not scale, and Newton from it stalled (50
    steps, the critical-point line search at lambda = 6e-4 each, a failed step) until a stalled warm solve was solved
    again from zero (SolverSolveWarm())."""
    import sys
    sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "scripts"))
    from signorini import hertz
    mesh = os.path.join(outdir, "sphere.msh")
    hertz.write_mesh("sphere-indenter", 0.02, mesh)
    base = hertz.command("sphere-indenter", mesh, "eps=h/100", "unused.h5")[4:-2] + ["-snes_rtol", "1e-12"]  # the options only
    path = [1.0, 0.5, 0.25, 0.6]
    _, h5 = run(base + ["-load_path", vec(path)], "unload", np_=np_, output=os.path.join(outdir, "unload.h5"))
    st = steps(h5)
    assert list(st["factor"]) == path and st["converged"].all(), st
    move = np.array(base[base.index("-obstacle_translate") + 1].split(","), dtype=float)
    for k, t in enumerate(path[1:], start=1):
        direct = base + ["-obstacle_translate", vec(t * move)]
        _, d = run(direct, f"unload_direct_{k}", np_=np_, output=os.path.join(outdir, f"unload_direct_{k}.h5"))
        attrs = load(d)[0]
        for q in ("contact_force", "energy"):
            assert abs(st[q][k] - attrs[q]) <= 1e-8 * abs(attrs[q]), (k, q, st[q][k], attrs[q])


@pytest.mark.parametrize("np_", [1, 2])
def test_snesvi_path_follows_the_gap(outdir, np_):
    """SNESVI along a path: the bounds u . n <= g are renewed at each step from the moved obstacle's gaps (a flat
    foundation under a block pressed by its moving clamp, and a plane obstacle moved up into a block held at its
    bottom). Loading to 0.3, overshooting to 1.5 and unloading to 1 ends at the direct SNESVI run's displacement and
    force to 1e-10, each step is the direct run at its factor, on 1 and 2 ranks. With the bounds of the set-up kept,
    the obstacle's moves would be ignored."""
    base = ["-scene", "general", "-dm_plex_box_faces", "16,8", "-contact_faces", "1", "-bc_clamp", "3", "-contact_method", "vi",
            "-snes_rtol", "1e-12", "-obstacle", "plane", "-obstacle_point", "0,-0.01", "-obstacle_normal", "0,-1"]
    move, clamp = np.array([0.0, 0.02]), np.array([0.0, -0.005])
    data = lambda t: ["-obstacle_translate", vec(t * move), "-bc_clamp_3_translate", vec(t * clamp)]  # noqa: E731
    _, h5 = run(base + data(1.0) + ["-load_path", "0.3,1.5,1"], "vi_path", np_=np_, output=os.path.join(outdir, "vi_path.h5"))
    st = steps(h5)
    assert list(st["factor"]) == [0.3, 1.5, 1.0] and st["converged"].all()
    # in contact at the overshoot and at the end; at 0.3 the block does not reach the foundation (the force is round-off,
    # 1e-18, whose last bits MUMPS's parallel factorization changes from run to run): the forces are compared relative
    # to the path's largest
    scale = st["contact_force"].max()
    assert st["contact_force"][1] > 0 and st["contact_force"][2] > 0, st["contact_force"]
    for k, t in enumerate(st["factor"]):
        _, d = run(base + data(t), f"vi_direct_{k}", np_=np_, output=os.path.join(outdir, f"vi_direct_{k}.h5"))
        attrs, fields = load(d)
        assert abs(st["contact_force"][k] - attrs["contact_force"]) <= 1e-10 * scale, (k, st["contact_force"][k], attrs["contact_force"])
    last = load(h5)[1]["displacement"]
    assert np.max(np.abs(last - fields["displacement"])) <= 1e-10 * np.max(np.abs(fields["displacement"]))


@pytest.mark.parametrize("np_", [1, 2])
def test_snesvi_path_on_a_curved_obstacle(outdir, np_):
    """SNESVI along a path on a cylinder pressed into a block's top face: at each step the obstacle's move changes the
    contact nodes' normals, so their rotated frames (src/contact/vi_frames.c), the bounds and Q^T K Q are renewed. Each
    step of 0.3, 1.5, 1 is the direct SNESVI run at its factor (force to 1e-10, the last displacement to 1e-10), on 1
    and 2 ranks."""
    base = ["-scene", "general", "-dm_plex_box_faces", "32,8", "-contact_faces", "3", "-bc_clamp", "1", "-contact_method", "vi",
            "-snes_rtol", "1e-12", "-obstacle", "cylinder", "-obstacle_center", "0.4,2.001", "-obstacle_radius", "1"]
    data = lambda t: ["-obstacle_translate", vec(t * np.array([0.0, -0.03]))]  # noqa: E731
    _, h5 = run(base + data(1.0) + ["-load_path", "0.3,1.5,1"], "vi_path", np_=np_, output=os.path.join(outdir, "vi_path.h5"))
    st = steps(h5)
    assert list(st["factor"]) == [0.3, 1.5, 1.0] and st["converged"].all()
    assert st["contact_force"][0] > 0 and st["contact_force"][1] > 1.5 * st["contact_force"][2]
    for k, t in enumerate(st["factor"]):
        _, d = run(base + data(t), f"vi_direct_{k}", np_=np_, output=os.path.join(outdir, f"vi_direct_{k}.h5"))
        attrs, fields = load(d)
        assert attrs["active_vertices"] >= 3
        assert abs(st["contact_force"][k] - attrs["contact_force"]) <= 1e-10 * attrs["contact_force"], (k, st["contact_force"][k], attrs["contact_force"])
    last = load(h5)[1]["displacement"]
    assert np.max(np.abs(last - fields["displacement"])) <= 1e-10 * np.max(np.abs(fields["displacement"]))


def test_a_failed_step_ends_the_path(outdir):
    """A step whose solve fails (3 Newton steps allowed for a jump to 30 times the load) ends the path: /steps holds the
    steps up to it, the failed one with converged = 0, /run converged = 0, the summary names it, the exit status is 3."""
    out = os.path.join(outdir, "failed.h5")
    rc, text = solve(INDENT + ["-obstacle_translate", "0,-0.02", "-load_path", "0.3,30,1", "-snes_max_it", "3"], output=out)
    assert rc == 3, text[-2000:]
    st = steps(out)
    assert list(st["converged"]) == [1.0, 0.0] and list(st["factor"]) == [0.3, 30.0]
    assert load(out)[0]["converged"] == 0
    assert "stopped at step 2 of 3" in text


@pytest.mark.parametrize("extra, message", [
    (["-load_steps", "2", "-load_path", "1"], "-load_steps and -load_path both give the load path"),
    (["-load_steps", "0"], "-load_steps must lie in [1, 1000]"),
    (["-load_path", "0.5,nan"], "-load_path"),
    (["-load_steps", "2", "-scene", "mms"], "the scene mms takes its load from its manufactured solution"),
    (["-load_steps", "2", "-scene", "patch"], "prescribes its own displacement"),
    (["-load_steps", "2", "-bars"], "-bars measures one load state"),
])
def test_bad_load_path_refused(outdir, extra, message):
    out = os.path.join(outdir, "bad.h5")
    rc, text = solve(["-dm_plex_box_faces", "8,8"] + extra, output=out)
    assert rc != 0 and message in text, text[-2000:]
    assert not os.path.exists(out)


def test_time_series_opens_in_paraview(outdir, tmp_path):
    """The steps' state (displacement, contact_pressure, normal_gap, contact_boundary, contact_reaction) is a time series under
    /vertex_fields, the step the first dimension (PETSc's timestepping); ParaView's own XDMF reader (pvbatch) finds one
    time per step (1, 2, 3) and at each the step's arrays, equal to the HDF5 file's; the last step's are the direct
    run's at its factor (signorini.runs.read_output)."""
    import subprocess
    import sys
    sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "scripts"))
    from signorini.runs import read_steps
    _, h5 = run(INDENT + ["-obstacle_translate", "0,-0.02", "-load_path", "0.3,1.2,1"], "series", output=os.path.join(outdir, "series.h5"))
    st, series = read_steps(h5)
    assert sorted(series) == ["contact_boundary", "contact_pressure", "contact_reaction", "displacement", "normal_gap"]
    assert series["displacement"].shape[:2] == (3, series["contact_pressure"].shape[1])
    npz = tmp_path / "pv.npz"
    script = tmp_path / "read.py"
    script.write_text(
        "import numpy as np\n"
        "from paraview.simple import XDMFReader\n"
        "from paraview import servermanager as sm\n"
        "from vtk.util.numpy_support import vtk_to_numpy\n"
        f"r = XDMFReader(FileNames=[{h5[:-3] + '.xdmf'!r}])\n"
        "r.UpdatePipelineInformation()\n"
        "out = {'times': np.array(r.TimestepValues)}\n"
        "for k, t in enumerate(r.TimestepValues):\n"
        "    r.UpdatePipeline(t)\n"
        "    pd = sm.Fetch(r).GetPointData()\n"
        "    for name in ('displacement', 'contact_pressure', 'normal_gap', 'contact_boundary', 'contact_reaction'):\n"
        "        out[f'{name}_{k}'] = vtk_to_numpy(pd.GetArray(name))\n"
        f"np.savez({str(npz)!r}, **out)\n")
    p = subprocess.run(["pvbatch", "--force-offscreen-rendering", str(script)], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                       timeout=300)
    assert p.returncode == 0, p.stdout[-3000:]
    pv = np.load(npz)
    assert list(pv["times"]) == [1.0, 2.0, 3.0]
    for k in range(3):
        for name, values in series.items():
            got = pv[f"{name}_{k}"]
            want = values[k]
            if name == "displacement":  # ParaView pads 2D vectors with a zero third component
                assert np.all(got[:, 2] == 0.0)
                got = got[:, :2]
            assert got.shape == want.shape and np.array_equal(got, want), (k, name)
    _, d = run(INDENT + ["-obstacle_translate", "0,-0.02"], "series_direct", output=os.path.join(outdir, "direct.h5"))
    last, direct = load(h5)[1], load(d)[1]
    assert np.max(np.abs(last["displacement"] - direct["displacement"])) <= 1e-8 * np.max(np.abs(direct["displacement"]))


def test_plot_history(outdir):
    """scripts/plot_history.py: the CSV holds every column of /steps, and the depth (the obstacle's translation along
    its motion) and the force along it, positive as it presses; the PNG is written; a file without /steps is refused
    (exit 2) by name."""
    import csv
    import subprocess
    import sys
    from harness import ROOT
    _, h5 = run(INDENT + ["-obstacle_translate", "0,-0.02", "-load_steps", "4"], "history", output=os.path.join(outdir, "history.h5"))
    png, table = os.path.join(outdir, "h.png"), os.path.join(outdir, "h.csv")
    script = os.path.join(ROOT, "scripts", "plot_history.py")
    p = subprocess.run([sys.executable, script, h5, "-o", png, "--csv", table], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    assert p.returncode == 0, p.stdout
    assert os.path.getsize(png) > 10000
    rows = list(csv.DictReader(open(table)))
    st = steps(h5)
    assert len(rows) == 4
    for k, row in enumerate(rows):
        for name, values in st.items():
            assert float(row[name]) == values[k], (k, name)
        assert abs(float(row["depth"]) - 0.005 * (k + 1)) <= 1e-15
        assert abs(float(row["force_along"]) + st["contact_force_y"][k]) <= 1e-15 and float(row["force_along"]) > 0
    _, plain = run(INDENT + ["-obstacle_translate", "0,-0.02"], "no_history", output=os.path.join(outdir, "plain.h5"))
    p = subprocess.run([sys.executable, script, plain, "-o", png], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    assert p.returncode == 2 and "no /steps" in p.stdout, p.stdout


def test_hertz_measures_each_step(outdir):
    """signorini.hertz.measure(case, path, step=k) reads step k of a load path (its row of /steps, its slab of the time
    series): on the cylinder indenter along 0.5, 1, the first step's a, p0 and load are the direct run's at half the
    indentation, to the solver's tolerance."""
    import sys
    sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "scripts"))
    from signorini import hertz
    mesh = os.path.join(outdir, "block.msh")
    hertz.write_mesh("cylinder-indenter", 0.004, mesh)
    path, direct = os.path.join(outdir, "path.h5"), os.path.join(outdir, "direct.h5")
    base = hertz.command("cylinder-indenter", mesh, "eps=h/10", path)[3:-2]  # without mpiexec -n 1 and -output
    assert base[0].endswith("bin/signorini")
    run(base[1:] + ["-load_path", "0.5,1", "-snes_rtol", "1e-12"], "hertz_path", output=path)
    run(base[1:] + ["-obstacle_translate", "0,-0.0005", "-snes_rtol", "1e-12"], "hertz_direct", output=direct)
    m_step, m_direct, m_last = hertz.measure("cylinder-indenter", path, step=0), hertz.measure("cylinder-indenter", direct), \
        hertz.measure("cylinder-indenter", path)
    for key in ("load", "a_h", "p0_h"):
        assert abs(m_step[key] - m_direct[key]) <= 1e-8 * abs(m_direct[key]), (key, m_step[key], m_direct[key])
    assert m_last["load"] > 1.9 * m_step["load"]


@pytest.mark.parametrize("np_", [1, 2])
def test_force_control(outdir, np_):
    """-obstacle_force F drives the cylinder along -obstacle_translate's direction until it presses with F: along 3
    steps (targets F/3, 2F/3, F) the obstacle's force along its motion equals each target to 1e-8; the displacement-
    driven run at each position found gives that force to 1e-6 (the depth is the displacement-driven run's at that
    force); 2 ranks as 1."""
    F = 0.01
    _, h5 = run(INDENT + ["-obstacle_translate", "0,-0.01", "-obstacle_force", F, "-load_steps", "3"], "force", np_=np_,
                output=os.path.join(outdir, "force.h5"))
    st = steps(h5)
    assert st["converged"].all()
    targets = st["factor"] * F
    assert np.all(np.abs(-st["contact_force_y"] - targets) <= 1e-8 * targets), (st["contact_force_y"], targets)
    attrs = load(h5)[0]
    assert attrs["force_control_its"] >= 3 and attrs["obstacle_translate_y"] == st["obstacle_translate_y"][-1]
    for k in range(3):
        _, d = run(INDENT + ["-obstacle_translate", vec([0.0, st["obstacle_translate_y"][k]])], f"depth_{k}", np_=np_,
                   output=os.path.join(outdir, f"depth_{k}.h5"))
        force = -load(d)[0]["contact_force_y"]
        assert abs(force - targets[k]) <= 1e-6 * targets[k], (k, force, targets[k])


@pytest.mark.parametrize("extra, message", [
    (["-obstacle_force", "0.01"], "-obstacle_force needs -obstacle_translate to give the direction"),
    (["-obstacle_force", "-1", "-obstacle_translate", "0,-0.01"], "-obstacle_force must be positive"),
    (["-obstacle_force", "0.01", "-obstacle_translate", "0,-0.01", "-contact_method", "vi"], "-obstacle_force works with -contact_method penalty"),
    (["-obstacle_force", "0.01", "-obstacle_translate", "0,-0.01", "-contact_method", "none"], "-obstacle_force works with -contact_method penalty"),
])
def test_bad_force_control_refused(outdir, extra, message):
    out = os.path.join(outdir, "bad.h5")
    rc, text = solve(INDENT + extra, output=out)
    assert rc != 0 and message in text, text[-2000:]
    assert not os.path.exists(out)


UNLOAD = ["-load_path", "0.5,1,0.3,0"]


@pytest.mark.parametrize("np_", [1, 2])
@pytest.mark.parametrize("drive", ["displacement", "force", "al"])
def test_a_path_that_unloads_to_zero_ends_at_rest(outdir, np_, drive):
    """A path back to the factor 0: every datum is zero there, so the solution is u = 0 and the obstacle exerts no force;
    recognised (0 Newton steps, u = 0 exactly, no warning), by displacement, by force (the obstacle withdrawn until it
    no longer presses; /run keeps obstacle_force, the last step's target 0) and with the augmented Lagrangian (its
    multipliers back to 0). Before, force control wrote the factor-0 step with the last step's state (force 3e-3,
    converged), displacement took 5 Newton steps to reach |u| = 1e-60 and warned of penetrating nodes, and the augmented
    Lagrangian ended with a force of 2.4e-6."""
    extra = {"displacement": [], "force": ["-obstacle_force", "0.01"], "al": ["-contact_method", "al", "-contact_penetration_tol", "1e-5"]}[drive]
    out, h5 = run(INDENT + ["-obstacle_translate", "0,-0.01"] + extra + UNLOAD, "unload", np_=np_, output=os.path.join(outdir, "unload.h5"))
    st = steps(h5)
    attrs, fields = load(h5)
    assert st["converged"].all() and list(st["factor"]) == [0.5, 1, 0.3, 0]
    assert st["contact_force"][2] > 0 and st["contact_force"][3] == 0.0 and st["energy"][3] == 0.0
    assert np.all(fields["displacement"] == 0.0)
    assert attrs["contact_force"] == 0.0 and attrs["converged"] == 1
    assert "WARNING" not in out, out[-2000:]
    if drive == "force":
        assert attrs["obstacle_force"] == 0.0
        assert attrs["obstacle_translate_y"] >= 0.0  # at or behind the unloaded position, where the cylinder just touches
    else:
        assert st["newton_its"][3] == 0


def test_force_control_releases_an_overlapping_obstacle(outdir):
    """The cylinder placed 0.005 into the block: at the factor 0 force control withdraws it until no point of the block
    lies inside it, behind the overlap (the obstacle at least 0.005 back, translate_y >= 0.005) but not far behind it
    (within a tenth of the overlap); the body is then at rest, u = 0."""
    args = [a if a != "0.5,1.5" else "0.5,1.495" for a in INDENT]
    out, h5 = run(args + ["-obstacle_translate", "0,-0.01", "-obstacle_force", "0.01"] + UNLOAD, "release", output=os.path.join(outdir, "release.h5"))
    st = steps(h5)
    attrs, fields = load(h5)
    assert st["converged"].all()
    assert st["contact_force"][3] == 0.0 and st["penetration_max"][3] <= 0.0
    assert 0.005 <= attrs["obstacle_translate_y"] <= 0.0055, attrs["obstacle_translate_y"]
    assert np.all(fields["displacement"] == 0.0)


@pytest.mark.parametrize("np_", [1, 2])
def test_force_control_in_3d_along_an_unloading_path(outdir, np_):
    """A sphere pressed into a 3D box by force, loading to F and unloading to F/2: the force along the motion equals
    each target to 1e-8, and the displacement-driven run at each position found gives that force to 1e-6; 2 ranks as 1."""
    F = 0.002
    box = ["-scene", "general", "-dm_plex_dim", "3", "-dm_plex_box_faces", "8,8,8", "-contact_faces", "2", "-bc_clamp", "1", "-obstacle", "sphere",
           "-obstacle_center", "0.5,0.5,1.5", "-obstacle_radius", "0.5", "-snes_rtol", "1e-12", "-contact_monitor", "0"]
    _, h5 = run(box + ["-obstacle_translate", "0,0,-0.01", "-obstacle_force", F, "-load_path", "0.5,1,0.5"], "force3d", np_=np_,
                output=os.path.join(outdir, "force3d.h5"))
    st = steps(h5)
    assert st["converged"].all()
    targets = st["factor"] * F
    assert np.all(np.abs(-st["contact_force_z"] - targets) <= 1e-8 * targets), (st["contact_force_z"], targets)
    for k in (1, 2):
        _, d = run(box + ["-obstacle_translate", vec([0.0, 0.0, st["obstacle_translate_z"][k]])], f"depth3d_{k}", np_=np_,
                   output=os.path.join(outdir, f"depth3d_{k}.h5"))
        force = -load(d)[0]["contact_force_z"]
        assert abs(force - targets[k]) <= 1e-6 * targets[k], (k, force, targets[k])


def test_a_body_resting_on_the_foundation_unloaded_is_at_rest(outdir):
    """The default square rests on its foundation (gap 0 along Gamma_C) and is pressed by its top's displacement; at
    the factor 0 it is at rest: no contact size, no penetration, no warning. Before, Newton left round-off
    penetrations of 4e-63 at 10 nodes, which the contact-resolution warning called 2.2e+03% of the force, and /steps
    gave the step a contact size of 0.1257."""
    out, h5 = run(SQUARE + ["-load_path", "1,0"], "rest", output=os.path.join(outdir, "rest.h5"))
    st = steps(h5)
    assert st["converged"].all() and st["contact_force"][0] > 0
    assert st["contact_force"][1] == 0.0 and st["contact_size"][1] == 0.0 and st["penetration_max"][1] <= 0.0
    assert "WARNING" not in out, out[-2000:]


@pytest.mark.parametrize("obstacle", [["-obstacle", "cylinder", "-obstacle_center", "0.5,1.5", "-obstacle_radius", "0.5"],
                                      ["-obstacle", "plane", "-obstacle_point", "0,1", "-obstacle_normal", "0,1"]], ids=["cylinder", "plane"])
def test_a_force_out_of_reach_is_said_so(outdir, obstacle):
    """-obstacle_force 1000 on the unit block (E = 1): the secant would throw the obstacle through the body (before, the
    indenter went 16,410 units through a block 10 deep and stopped 'stalled' with a force of 1e-57). The obstacle moves
    at most the body's depth along its direction, the run says the target is out of reach (the cylinder's force falls
    once it passes through; the plane at the whole depth presses with less), and fails: exit 3, converged = 0."""
    args = ["-scene", "general", "-dm_plex_box_faces", "16,8", "-contact_faces", "3", "-bc_clamp", "1", "-contact_monitor", "0"] + obstacle
    out, h5 = run(args + ["-obstacle_translate", "0,-0.01", "-obstacle_force", "1000"], "out_of_reach", expect_rc=3, output=os.path.join(outdir, "reach.h5"))
    assert "the force 1000 is out of reach" in out.replace("1000.", "1000") and "ERROR: force control did not reach -obstacle_force" in out, out[-2000:]
    attrs, _ = load(h5)
    assert attrs["converged"] == 0 and -1.0 - 1e-12 <= attrs["obstacle_translate_y"] < 0


def test_hertz_along_a_force_controlled_path(outdir):
    """make hertz's cylinder indenter (h_near 0.002, eps = h/100) driven by force along 0.5, 1, 0.5 of the force the
    depth 0.001 gives: at each step the half-width and the peak pressure are within 1% of Hertz's closed form at the
    step's force (measured +0.37% and -0.49% at 0.5, +0.25% and -0.36% at 1), and the unloading step is the loading
    step at the same force (frictionless elasticity has no history)."""
    mesh = os.path.join(outdir, "ci.msh")
    hertz.write_mesh("cylinder-indenter", 0.002, mesh)
    _, direct = run(hertz.command("cylinder-indenter", mesh, "eps=h/100", "unused")[4:-2], "hertz_depth", output=os.path.join(outdir, "d.h5"))
    force = abs(load(direct)[0]["contact_force_y"])
    _, h5 = run(hertz.command("cylinder-indenter", mesh, "eps=h/100", "unused")[4:-2] + ["-obstacle_force", repr(force), "-load_path", "0.5,1,0.5"],
                "hertz_force", output=os.path.join(outdir, "f.h5"))
    rows = hertz.path_rows("cylinder-indenter", h5)
    assert [r["converged"] for r in rows] == [1, 1, 1]
    for r in rows:
        assert abs(r["a_error"]) < 0.01 and abs(r["p0_error"]) < 0.01, r
    assert abs(rows[2]["load"] - rows[0]["load"]) <= 1e-8 * rows[0]["load"] and abs(rows[2]["a_h"] - rows[0]["a_h"]) <= 1e-6 * rows[0]["a_h"]


@pytest.mark.parametrize("np_", [1, 2])
def test_a_load_path_runs_on_the_adapted_mesh(outdir, np_):
    """The drivers compose (DRIVER_FLOW, src/drivers/drivers.c): with -adapt_cycles the cycles adapt the mesh at the
    path's first load state, and the path's later steps run on their last mesh. The cylinder's indentation grows its
    contact zone; frictionless contact has no history, so the last state does not depend on the steps between: two
    paths through 0.5 to 1, with and without a step at 0.75, give the same cycles and the same last state, on 1 and 2
    ranks."""
    data = INDENT + ["-obstacle_translate", "0,-0.02", "-adapt_cycles", "2"]
    h5s = []
    for name, path in (("two", "0.5,1"), ("three", "0.5,0.75,1")):
        _, h5 = run(data + ["-load_path", path], f"adapted_path_{name}_np{np_}", np_=np_, output=os.path.join(outdir, f"{name}.h5"))
        h5s.append(h5)
    with h5py.File(h5s[0], "r") as f, h5py.File(h5s[1], "r") as g:
        dofs = f["cycles"]["n_dofs"][:]
        assert len(dofs) == 3 and dofs[-1] > dofs[0]  # the cycles refined the mesh
        assert np.array_equal(dofs, g["cycles"]["n_dofs"][:])  # at the same first load state
    st2, st3 = steps(h5s[0]), steps(h5s[1])
    assert list(st3["factor"]) == [0.5, 0.75, 1.0] and st2["converged"].all() and st3["converged"].all()
    assert st3["contact_size"][0] < st3["contact_size"][-1]  # the zone grows along the path
    a2, f2 = load(h5s[0])
    a3, f3 = load(h5s[1])
    assert a2["n_dofs"] == dofs[-1]  # the path's last state is on the cycles' last mesh
    for q in QUANTITIES:
        assert abs(a2[q] - a3[q]) <= 1e-8 * abs(a2[q]) + 1e-12 * abs(a2["contact_force"]), (q, a2[q], a3[q])
    assert np.max(np.abs(f2["displacement"] - f3["displacement"])) <= 1e-8 * np.max(np.abs(f2["displacement"]))


def test_accuracy_with_a_load_path_is_refused():
    """-accuracy bounds the error of one load state; a path solves others after it, so the bars written would be
    another state's: refused before any solve, naming both."""
    refused(INDENT + ["-accuracy", "0.1", "-load_steps", "2"], "accuracy_load_path", "-accuracy bounds the error of one load state")
