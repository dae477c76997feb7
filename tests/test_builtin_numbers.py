"""The built-in scenes give the numbers they gave before their boundary conditions, loads and foundation became defaults
of the options (tests/data/builtin_numbers.json, recorded with the binary of commit 36f5706 by scripts/regression.py):
iterations and active sets equal, energies, forces, penetrations and displacements to 1e-11 (1e-14 absolute for what is
zero up to round-off)."""
import json
import os

import numpy as np
import pytest

from harness import ROOT, load, run

RECORD = json.load(open(os.path.join(ROOT, "tests", "data", "builtin_numbers.json")))["runs"]


@pytest.mark.parametrize("rec", RECORD, ids=[r["name"] for r in RECORD])
def test_builtin_scene_numbers(outdir, rec):
    _, h5 = run(rec["args"].split(), rec["name"], np_=rec["ranks"], output=os.path.join(outdir, "r.h5"))
    attrs, fields = load(h5)
    assert attrs["newton_its"] == rec["newton_its"] and attrs["active_vertices"] == rec["active_vertices"]
    for key in ("contact_force", "energy", "max_penetration"):
        # relative 1e-11, and 1e-14 absolute for what is zero up to round-off (the patch test's contact force, 1e-17)
        assert abs(attrs[key] - rec[key]) <= 1e-11 * abs(rec[key]) + 1e-14, (key, attrs[key], rec[key])
    u = fields["displacement"]
    order = np.lexsort(np.round(fields["x"], 12).T)
    assert abs(np.linalg.norm(u) / rec["displacement_norm"] - 1) < 1e-11
    weighted = float(np.sum(u[order][:, 0] * (1 + np.arange(len(order)) / len(order))))
    assert abs(weighted - rec["displacement_sum_x"]) <= 1e-11 * np.linalg.norm(u) * len(order)
