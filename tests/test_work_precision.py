"""scripts/work_precision.py's table (make work-precision): each family's fewest unknowns within an error, and the
unknowns a power law through the uniform family's last three meshes would need."""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scripts"))
import work_precision as wp  # noqa: E402


def family(n, err):
    """Rows (unknowns, time, force, pressure, size) with the time 1e-3 n."""
    n = np.asarray(n, dtype=float)
    return np.column_stack([n, 1e-3 * n, n * 0, n * 0, n * 0]), np.asarray(err, dtype=float)


def test_fewest_takes_the_fewest_unknowns_within_the_error_not_the_first_row():
    rows, err = family([400, 100, 200, 800], [0.005, 0.02, 0.009, 0.001])
    assert wp.fewest(rows, err, 0.01) == (200, 0.2)
    assert wp.fewest(rows, err, 0.001) == (800, 0.8)
    assert wp.fewest(rows, err, 1e-4) is None


def test_the_power_law_recovers_its_own_exponent_and_refuses_the_unresolved():
    n = np.array([1e3, 4e3, 1.6e4, 6.4e4])
    rows, err = family(n, 0.5 * n ** -0.5)
    assert abs(wp.power_law_dofs(rows, err, 0.5 * 1e6 ** -0.5) / 1e6 - 1) < 1e-9
    rows, err = family(n, [0.9, 0.8, 0.6, 0.5])  # a mesh that does not resolve the zone is not on the law
    assert np.isnan(wp.power_law_dofs(rows, err, 0.01))
    rows, err = family(n, [0.1, 0.05, 0.06, 0.08])  # an error that grows
    assert np.isnan(wp.power_law_dofs(rows, err, 0.01))


def test_the_table_row_says_none_and_gives_no_ratio_where_a_family_misses_the_error():
    fam = {"adaptive": family([100, 300, 900], [0.05, 0.02, 0.004])[0], "hand-graded": family([500, 2000], [0.03, 0.012])[0],
           "uniform": family([1000, 4000, 16000], [0.2, 0.1, 0.05])[0]}
    err = {"adaptive": np.array([0.05, 0.02, 0.004]), "hand-graded": np.array([0.03, 0.012]), "uniform": np.array([0.2, 0.1, 0.05])}
    row, line = wp.table_row("cylinder", 0.01, fam, err)
    assert row[2] == 900 and row[4] == 0 and abs(row[6] / (16000 * 25) - 1) < 1e-9  # the uniform law: the error halves as N quadruples
    assert "none up to 2000 (least error 1.20%)" in line and "about 4.4e+02" in line, line
    row, line = wp.table_row("cylinder", 0.03, fam, err)
    assert row[2] == 300 and row[4] == 500 and "1.67, 0.60" in line, line
