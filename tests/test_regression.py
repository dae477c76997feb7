"""scripts/regression.py (make test): the record-and-compare tool that shows a change of structure keeps every number.
Two runs recorded twice compare equal; a changed displacement, iteration count, table row or attribute is found."""
import os
import shutil
import subprocess
import sys

import h5py

from harness import ENV, ROOT

SCRIPT = os.path.join(ROOT, "scripts", "regression.py")


def regression(*args):
    return subprocess.run([sys.executable, SCRIPT] + list(args), cwd=ROOT, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                          timeout=300)


def test_regression_script_finds_a_changed_number(outdir):
    base = outdir
    runs = os.path.join(base, "runs.yaml")
    with open(runs, "w") as fh:
        fh.write('runs:\n  - {name: small, args: "-dm_plex_box_faces 8,8"}\n  - {name: small_np2, ranks: 2, args: "-dm_plex_box_faces 8,8 -contact_method vi"}\n')
    for d in ("a", "b"):
        p = regression("--runs", runs, "run", os.path.join(base, d))
        assert p.returncode == 0, p.stdout
    p = regression("--runs", runs, "compare", os.path.join(base, "a"), os.path.join(base, "b"))
    assert p.returncode == 0 and "2 same, 0 different" in p.stdout, p.stdout
    for change in ("field", "iterations", "table", "attribute"):
        c = os.path.join(base, "c")
        shutil.rmtree(c, ignore_errors=True)
        shutil.copytree(os.path.join(base, "b"), c)
        with h5py.File(os.path.join(c, "small.h5"), "a") as f:
            if change == "field":
                f["vertex_fields/displacement"][0, 1] *= 1.0 + 1e-10
            elif change == "iterations":
                f["run"].attrs["newton_its"] = f["run"].attrs["newton_its"] + 1
            elif change == "table":  # a row of /solves (the compare reads /solves, /steps and /cycles too)
                f["solves/newton_its"][0] += 1
            else:
                f["run"].attrs["extra"] = 1.0
        p = regression("--runs", runs, "compare", os.path.join(base, "a"), c)
        assert p.returncode == 1 and "1 same, 1 different" in p.stdout, (change, p.stdout)
    p = regression("--runs", runs, "compare", os.path.join(base, "a"), c, "--allow-added")
    assert p.returncode == 0, p.stdout
