"""-contact_penetration_tol d (src/solver/penetration_tol.c): the penalty run ends when its largest penetration, over
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


@pytest.mark.parametrize("name", ["square", "square-nodal", "cylinder-indenter", "sphere-indenter"])
def test_penetration_ladder(outdir, name):
    """d = 1e-1, 1e-3, 1e-5 times the plain run's largest penetration (eps = h/E; the graded meshes' h near the contact
    is not their largest) on the square, 1e-1 to 1e-3 on the indenters (the 3D sphere's default solver fails from zero
    at eps = 1e-6 h, the extreme such a tolerance would need): every run ends converged with its penetration at the nodes and the rule's points
    (penetration_tol_measured, recomputed here from the nodes' normal_gap) at most d, but not below d/2 (eps no smaller
    than d needs), after more than one solve; on the flat obstacles the output's max_penetration too (a curved one cuts
    the faces between the points by the mesh's h^2/8R, which eps does not reach); the smallest tolerance's displacement
    is the direct run's at its final eps to 1e-7."""
    import numpy as np

    args = problems(outdir)[name]
    _, plain = run(args, "plain", output=os.path.join(outdir, "plain.h5"))
    a0 = load(plain)[0]
    pen0 = float(a0["max_penetration"])
    assert pen0 > 0
    for k in ((1, 3, 5) if name.startswith("square") else (1, 2, 3)):
        d = 10.0 ** -k * pen0
        _, out = run(args + ["-contact_penetration_tol", d], f"tol{k}", output=os.path.join(outdir, f"tol{k}.h5"))
        attrs, fields = load(out)
        measured = float(attrs["penetration_tol_measured"])
        assert attrs["converged"] == 1 and 0.5 * d < measured <= d, (k, measured, d)
        assert int(attrs["penetration_tol_solves"]) >= 2 and float(attrs["penetration_tol"]) == d
        on = fields["contact_boundary"] > 0.5
        assert np.max(-fields["normal_gap"][on]) <= measured * (1 + 1e-9)  # the nodes' penetration, g - u_n = -(u_n - g)
        if name.startswith("square"):
            assert float(attrs["max_penetration"]) <= d
    # eps0 = 1 in every problem here: the final eps is eps0 = eps_final / eps_plain times h/E, with its local factors
    _, direct = run(args + ["-penalty_eps0", float(attrs["eps"]) / float(a0["eps"])], "direct", output=os.path.join(outdir, "direct.h5"))
    u, ud = fields["displacement"], load(direct)[1]["displacement"]
    assert np.max(np.abs(u - ud)) <= 1e-7 * np.max(np.abs(ud))


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
    (["-contact_penetration_tol", "1e-6", "-contact_method", "vi"], "-contact_penetration_tol needs -contact_method penalty"),
    (["-contact_penetration_tol", "1e-6", "-penalty_eps0_sweep", "1,0.1"], "-contact_penetration_tol and -penalty_eps0_sweep"),
    (["-contact_penetration_tol", "1e-6", "-load_steps", "2"], "-contact_penetration_tol and -load_steps and -load_path both solve a sequence"),
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

    r = subprocess.run(["/usr/bin/python3", "scripts/penetration_tol.py", "--small", "--cases", "square512", "--outdir", outdir], cwd=ROOT,
                       env=ENV, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    rows = list(csv.DictReader(open(os.path.join(outdir, "penetration_tol.csv"))))
    assert [x["d_over_h"] for x in rows] == ["1e-2", "1e-4", "1e-6"]
    for k, x in zip((2, 4, 6), rows):
        a = read_run(os.path.join(outdir, f"square512_d{k}.h5"))
        assert int(x["converged"]) == int(a["converged"]) == 1
        assert float(x["penetration"]) == float(a["penetration_tol_measured"]) <= float(x["d"])
        assert int(x["solves"]) == int(a["penetration_tol_solves"]) >= 2
