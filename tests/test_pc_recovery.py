"""Recovery from a breakdown of the preconditioner (make test; src/linear/pc_recovery.c): a Krylov solve that stops on
its preconditioner (DIVERGED_INDEFINITE_PC) no longer ends the run; Newton goes on from its last iterate after a fresh
build, then safer smoother bounds, then a direct solve, each counted in /run pc_breakdowns and named in pc_recovery,
and the answer is the direct solver's. With -contact_pc_recovery 0 the breakdown stays a failed solve
(tests/test_robustness.py::test_iterative_solver_failure_at_small_eps_is_loud)."""
import numpy as np
import pytest

from harness import load, run, sorted_by_position

SQUARE = ["-options_file", "options/square.yaml", "-contact_monitor", "false", "-dm_plex_box_faces", "32,32"]
GAMG = ["-options_file", "options/solvers/gamg.yaml"]


@pytest.fixture(scope="module")
def direct(out_root):
    """The same problems solved by the default direct solver (MUMPS), on 1 rank."""
    answers = {}
    for name, eps0 in (("small_eps", "1e-8"), ("eps_h", "1")):
        _, h5 = run(SQUARE + ["-penalty_eps0", eps0], f"pc_recovery_direct_{name}")
        answers[name] = load(h5)
    return answers


def check_same_answer(h5, reference):
    attrs, fields = load(h5)
    ref_attrs, ref_fields = reference
    assert attrs["converged"] == 1
    u, u_ref = sorted_by_position(fields, "displacement"), sorted_by_position(ref_fields, "displacement")
    assert np.abs(u - u_ref).max() <= 1e-7 * np.abs(u_ref).max(), np.abs(u - u_ref).max()
    assert abs(attrs["contact_force"] - ref_attrs["contact_force"]) <= 1e-8 * ref_attrs["contact_force"]
    return attrs


@pytest.mark.parametrize("np_", (1, 2))
def test_breakdown_of_sa_bounds_recovered_by_safer_bounds(direct, np_):
    """GAMG with PETSc 3.18's default smoother bounds (from the smoothed aggregation) breaks down at eps = 1e-8 h on a
    fresh build too; GAMG rebuilt with each level's own estimate solves it."""
    args = SQUARE + GAMG + ["-pc_gamg_use_sa_esteig", "1", "-contact_pc_update_truncate", "0", "-penalty_eps0", "1e-8"]
    out, h5 = run(args, f"pc_recovery_sa_{np_}", np_=np_)
    attrs = check_same_answer(h5, direct["small_eps"])
    assert attrs["pc_breakdowns"] >= 1 and "DIVERGED_INDEFINITE_PC" in attrs["pc_recovery"], attrs.get("pc_recovery")
    assert "preconditioner breakdown (DIVERGED_INDEFINITE_PC)" in out and "preconditioner breakdowns:" in out


def test_breakdown_of_given_bounds_recovered_by_a_direct_solve(direct):
    """Chebyshev intervals given too small (-mg_levels_ksp_chebyshev_esteig, read at every build): every multigrid
    build breaks down, and the third step, a direct solve, gives the direct solver's answer."""
    args = SQUARE + GAMG + ["-mg_levels_ksp_chebyshev_esteig", "0,0.05,0,0.3", "-penalty_eps0", "1"]
    out, h5 = run(args, "pc_recovery_direct_fallback", np_=2)
    attrs = check_same_answer(h5, direct["eps_h"])
    assert attrs["pc_breakdowns"] == 3 and "direct solve (MUMPS)" in attrs["pc_recovery"], attrs.get("pc_recovery")


def test_no_breakdown_no_recovery(direct):
    """A run that never breaks down records pc_breakdowns = 0 and no pc_recovery."""
    _, h5 = run(SQUARE + GAMG + ["-penalty_eps0", "1"], "pc_recovery_none")
    attrs = check_same_answer(h5, direct["eps_h"])
    assert attrs["pc_breakdowns"] == 0 and "pc_recovery" not in attrs
