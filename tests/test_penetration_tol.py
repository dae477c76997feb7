"""-contact_penetration_tol d (src/drivers/penetration_tol.c): the penalty run ends when its largest penetration, over
the contact nodes and the rule's points (/run max_penetration), is at most d, eps being lowered from the measured
penetration. Checked on a ladder of tolerances and obstacles: the penetration written is at most d; the answer is the
direct run's at the eps the run ended with (the continuation only finds eps); a tolerance out of reach fails the run
(converged = 0, exit 3); bad values and combinations are refused."""
import os

import pytest

from harness import load, run, solve
from signorini import hertz


def problems(outdir):
    mesh = os.path.join(outdir, "cyl.msh")
    hertz.write_mesh("cylinder-indenter", 0.01, mesh)
    sphere = os.path.join(outdir, "sph.msh")
    hertz.write_mesh("sphere-indenter", 0.02, sphere)
    return {"square": ["-dm_plex_box_faces", "32,32"],
            "square-nodal": ["-dm_plex_box_faces", "32,32", "-penalty_quadrature", "nodal"],
            "cylinder-indenter": hertz.command("cylinder-indenter", mesh, "eps=h", "unused")[4:-2],
            "sphere-indenter": hertz.command("sphere-indenter", sphere, "eps=h", "unused")[4:-2]}


def closed_form_penetration(args, x, u):
    """u . n - g at the points x with displacements u under the rigid cylinder (2D) or sphere of the run's options: its
    centre c moved by -obstacle_translate, its radius R; g = |x - c| - R, n = (c - x) / |x - c| (from the body into it)."""
    import numpy as np

    opt = lambda name: np.array([float(v) for v in args[args.index(name) + 1].split(",")])  # noqa: E731
    c = opt("-obstacle_center") + opt("-obstacle_translate")
    R = float(args[args.index("-obstacle_radius") + 1])
    r = c[None, :] - x
    dist = np.linalg.norm(r, axis=1)
    return np.sum(u * r / dist[:, None], axis=1) - (dist - R)


@pytest.mark.parametrize("name", ["square", "square-nodal", "cylinder-indenter", "sphere-indenter", "square-al", "cylinder-indenter-al"])
def test_penetration_ladder(outdir, name):
    """d = 1e-1, 1e-3, 1e-5 times the plain run's largest penetration (eps = h/E; the graded meshes' h near the contact
    is not their largest) on the square, 1e-1 to 1e-3 on the indenters (the 3D sphere's default solver fails from zero
    at eps = 1e-6 h, the extreme such a tolerance would need): every run ends converged with its penetration at the nodes and the rule's points
    (penetration_tol_measured, recomputed here from the nodes' normal_gap) at most d, but not below d/2 (eps no smaller
    than d needs), after more than one solve; on the flat obstacles the output's max_penetration too (a curved one cuts
    the faces between the points by the mesh's h^2/8R, which eps does not reach); the smallest tolerance's displacement
    is the direct run's at its final eps to 1e-7."""
    import numpy as np

    al = name.endswith("-al")
    args = problems(outdir)[name[:-3] if al else name]
    if al:  # the augmented Lagrangian: the plain run is the nodal penalty at the same eps, which it starts from
        args = args + ["-penalty_quadrature", "nodal"]
    _, plain = run(args, "plain", output=os.path.join(outdir, "plain.h5"))
    a0 = load(plain)[0]
    pen0 = float(a0["max_penetration"])
    assert pen0 > 0
    for k in ((1, 3, 5) if name.startswith("square") else (1, 2, 3)):
        d = 10.0 ** -k * pen0
        _, out = run(args + ["-contact_penetration_tol", d] + (["-contact_method", "al"] if al else []), f"tol{k}", output=os.path.join(outdir, f"tol{k}.h5"))
        attrs, fields = load(out)
        measured = float(attrs["penetration_tol_measured"])
        assert attrs["converged"] == 1 and (0.5 * d < measured or al) and measured <= d, (k, measured, d)
        assert int(attrs["penetration_tol_solves"]) >= 2 and float(attrs["penetration_tol"]) == d
        on = fields["contact_boundary"] > 0.5
        assert np.max(-fields["normal_gap"][on]) <= measured * (1 + 1e-9)  # the nodes' penetration, g - u_n = -(u_n - g)
        if "indenter" in name:  # and recomputed from the displacement and the rigid body's closed form, not the code's gap
            pen = closed_form_penetration(args, fields["x"][on], fields["displacement"][on])
            assert pen.max() <= d * (1 + 1e-9), (k, pen.max(), d)
            if al:  # the nodal rule's points are the nodes: the code's measure is this one
                assert abs(pen.max() - measured) <= 1e-9 * measured, (pen.max(), measured)
        if name.startswith("square"):
            assert float(attrs["max_penetration"]) <= d
    if al:  # eps stays; the multipliers move the answer to the exact contact's: checked against SNESVI below
        assert float(attrs["eps"]) == float(a0["eps"])
        return
    # eps0 = 1 in every problem here: the final eps is eps0 = eps_final / eps_plain times h/E, with its local factors
    _, direct = run(args + ["-penalty_eps0", float(attrs["eps"]) / float(a0["eps"])], "direct", output=os.path.join(outdir, "direct.h5"))
    u, ud = fields["displacement"], load(direct)[1]["displacement"]
    assert np.max(np.abs(u - ud)) <= 1e-7 * np.max(np.abs(ud))


@pytest.mark.parametrize("name", ["square", "cylinder-indenter"])
def test_augmented_lagrangian_tends_to_snesvi(outdir, name):
    """The augmented Lagrangian's fixed point is the exact nodal contact: its distance to SNESVI (max |u_al - u_vi| /
    max |u_vi|) falls with the tolerance d = 1e-4 and 1e-6 times max |u_vi|: at most 2 d / max |u_vi| (measured 0.77 and
    0.77 on the square, 0.55 and 0.67 on the cylinder indenter) and 30 times lower at the smaller d, with eps kept at h/E."""
    import numpy as np

    args = [a for a in problems(outdir)[name] if a not in ("penalty",)]
    args = [a for i, a in enumerate(args) if not (a == "-contact_method" or (i and args[i - 1] == "-contact_method"))]
    _, ref = run(args + ["-contact_method", "vi"], "vi", output=os.path.join(outdir, "vi.h5"))
    u_vi = load(ref)[1]["displacement"]
    scale = np.max(np.abs(u_vi))
    dist = {}
    for k in (4, 6):
        d = 10.0 ** -k * scale
        _, out = run(args + ["-contact_method", "al", "-contact_penetration_tol", d], "al", output=os.path.join(outdir, f"al{k}.h5"))
        attrs, fields = load(out)
        assert attrs["converged"] == 1 and attrs["method"] == "al" and attrs["penalty_quadrature"] == "nodal"
        dist[k] = np.max(np.abs(fields["displacement"] - u_vi)) / scale
        print(f"al: d = 1e-{k} max|u_vi|: distance to SNESVI {dist[k]:.3e} = {dist[k] * 10.0 ** k:.2f} d / max|u_vi|")
        assert dist[k] <= 2 * 10.0 ** -k, (k, dist)  # measured 0.55 to 0.77 d / max|u_vi|
    assert dist[6] < dist[4] / 30, dist


@pytest.mark.parametrize("method", ["penalty", "al"])
def test_penetration_tol_along_a_path(outdir, method):
    """-contact_penetration_tol at every step of a load path that loads and unloads (0.5, 1, 0.7), each step from the
    last one's eps (or multipliers): every step converged with its penetration at most d, and the last step's force the
    direct run's at 0.7 to 1e-4 (both within d of the exact contact; with al, the multipliers of the heavier step 1 push
    too hard at 0.7 and must be relaxed, not stopped at a zero penetration: the force was 2% high before)."""
    from signorini.runs import read_steps

    d = 1e-6
    base = ["-dm_plex_box_faces", "32,32", "-contact_method", method, "-contact_penetration_tol", d]
    _, path = run(base + ["-load_path", "0.5,1,0.7"], "path", output=os.path.join(outdir, "path.h5"))
    st = read_steps(path)[0]
    assert list(st["converged"]) == [1, 1, 1] and max(st["penetration_max"]) <= d, st["penetration_max"]
    assert load(path)[0]["converged"] == 1
    _, direct = run(base + ["-load_path", "0.7"], "direct", output=os.path.join(outdir, "direct.h5"))
    f = read_steps(direct)[0]["contact_force"][-1]
    assert abs(st["contact_force"][-1] / f - 1) < 1e-4, (st["contact_force"][-1], f)


def test_unreachable_tolerance_fails(outdir):
    """A tolerance below what double precision can resolve (1e-30) is not reached: the run is written with
    converged = 0 and exits with 3, never as a converged result."""
    out = os.path.join(outdir, "tiny.h5")
    rc, text = solve(["-dm_plex_box_faces", "16,16", "-contact_penetration_tol", "1e-30"], output=out)
    assert rc == 3, text[-2000:]
    assert load(out)[0]["converged"] == 0
    assert "penetration" in text


@pytest.mark.parametrize("extra,message", [
    (["-contact_penetration_tol", "0"], "-contact_penetration_tol must be positive, got 0"),
    (["-contact_penetration_tol", "-1e-3"], "-contact_penetration_tol must be positive"),
    (["-contact_penetration_tol", "nan"], "-contact_penetration_tol must be a finite number"),
    (["-contact_penetration_tol", "1e-6", "-contact_method", "vi"], "-contact_penetration_tol needs -contact_method penalty or al"),
    (["-contact_method", "al"], "-contact_method al needs -contact_penetration_tol"),
    (["-contact_method", "al", "-contact_penetration_tol", "1e-6", "-penalty_quadrature", "gauss"], "-contact_method al has its multipliers at the contact nodes"),
    (["-contact_penetration_tol", "1e-6", "-penalty_eps0_sweep", "1,0.1"], "-contact_penetration_tol and -penalty_eps0_sweep"),
    (["-contact_penetration_tol", "1e-6", "-obstacle_force", "0.01", "-obstacle_translate", "0,0.01"], "-contact_penetration_tol and -obstacle_force"),
])
def test_bad_penetration_tol_refused(outdir, extra, message):
    out = os.path.join(outdir, "bad.h5")
    rc, text = solve(["-dm_plex_box_faces", "8,8"] + extra, output=out)
    assert rc != 0 and message in text, text[-2000:]
    assert not os.path.exists(out)


def test_ladder_script(outdir):
    """scripts/penetration_tol.py --small: its table's rows are the runs' own figures (the penetration over d read back
    from each output, at most 1 where converged)."""
    import csv
    import subprocess

    from harness import ENV, ROOT
    from signorini.runs import read_run

    r = subprocess.run(["/usr/bin/python3", "scripts/penetration_tol.py", "--small", "--cases", "square512", "--methods", "continuation,al", "--outdir", outdir], cwd=ROOT,
                       env=ENV, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    rows = list(csv.DictReader(open(os.path.join(outdir, "penetration_tol.csv"))))
    assert [(x["d_over_h"], x["method"]) for x in rows] == [(f"1e-{k}", m) for k in (2, 4, 6) for m in ("continuation", "al")]
    for x in rows:
        a = read_run(os.path.join(outdir, f"square512_{x['method']}_d{x['d_over_h'][-1]}.h5"))
        assert a["method"] == ("al" if x["method"] == "al" else "penalty")
        assert int(x["converged"]) == int(a["converged"]) == 1
        assert float(x["penetration"]) == float(a["penetration_tol_measured"]) <= float(x["d"])
        assert int(x["solves"]) == int(a["penetration_tol_solves"]) >= 2


@pytest.mark.parametrize("method", ["penalty", "al"])
def test_penetration_tol_two_ranks(outdir, method):
    """2 ranks give the serial answer: the same solves (the loop's decisions are reduced over the ranks), the same
    penetration and the displacement to 1e-9, on the cylinder indenter's graded mesh (local eps)."""
    import numpy as np

    from harness import sorted_by_position

    args = problems(outdir)["cylinder-indenter"]
    args = [a for i, a in enumerate(args) if not (a == "-contact_method" or (i and args[i - 1] == "-contact_method"))]
    extra = ["-contact_method", method, "-contact_penetration_tol", 1e-7] + (["-penalty_quadrature", "nodal"] if method == "al" else [])
    res = []
    for ranks in (1, 2):
        _, out = run(args + extra, f"np{ranks}", np_=ranks, output=os.path.join(outdir, f"np{ranks}.h5"))
        res.append(load(out))
    (a1, f1), (a2, f2) = res
    assert a1["converged"] == a2["converged"] == 1 and a1["penetration_tol_solves"] == a2["penetration_tol_solves"] >= 2
    assert abs(a1["penetration_tol_measured"] - a2["penetration_tol_measured"]) <= 1e-9 * a1["penetration_tol_measured"] + 1e-15
    u1, u2 = sorted_by_position(f1, "displacement"), sorted_by_position(f2, "displacement")
    assert np.max(np.abs(u1 - u2)) <= 1e-9 * np.max(np.abs(u1))
