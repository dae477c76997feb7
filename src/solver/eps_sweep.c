/* -penalty_eps0_sweep a,b,c,...: the penalty problems for eps = eps0 h^power / M with eps0 = a, b, c, ... solved in
   turn on the final mesh, each from the solution for the previous value (the first is the run's main solve). The
   bulk matrix, the load and the solver objects are shared; the output holds the last solution, and /solves one row
   per value. A failed value ends the sweep.
   From the third value on, the start is extrapolated linearly in eps from the last two solutions: while the active
   set stays, u(eps) = (K + P/eps)^-1 f is u(0) + eps u'(0) + O(eps^2) once the penalty dominates, so the
   penetration, whose 1/eps multiple is most of the residual after a step of eps, is predicted instead of carried
   over (256 x 256, eps down by 10 per value: first residuals of 2e-5 to 2e-8 instead of 0.16). */
#include "physics.h"
#include "solver.h"

/* u <- u + factor (u - prev) if the penalty is active there at the same points as at u (the last solution) and the
   residual at the current eps is lower. A guess active elsewhere is not taken: a Gauss point it lifts off that the
   new eps keeps in contact (near the edge of the contact zone) made the line search cut every Newton step at that
   kink, and Newton stalled (16 x 16 and 32 x 32, GAMG, 1e-5 h to 1e-7 h: 40 and 50 steps). Halving the step when the
   full one changes the active points was tried: 116 CG iterations instead of 119 at 256 x 256, not kept. */
static PetscErrorCode ExtrapolatedStart(SNES snes, DM dm, AppCtx *user, Vec u, Vec prev, PetscReal factor)
{
  Vec       guess;
  PetscReal f_last, f_guess;
  PetscBool same;

  PetscFunctionBeginUser;
  PetscCall(VecDuplicate(u, &guess));
  PetscCall(VecWAXPY(guess, -1.0, prev, u));
  PetscCall(VecAYPX(guess, factor, u));
  PetscCall(PenaltySameActivity(dm, user, u, guess, &same));
  if (same) {
    PetscCall(SolverResidualNorm(snes, user, u, &f_last));
    PetscCall(SolverResidualNorm(snes, user, guess, &f_guess));
    if (f_guess < f_last) PetscCall(VecCopy(guess, u));
  }
  PetscCall(VecDestroy(&guess));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode EpsSweepSolve(DM dm, AppCtx *user, SNES snes, Vec u)
{
  Vec       prev = NULL, last = NULL; /* the solutions for the values before the last, and for the last */
  PetscReal eps_prev = 0.0;

  PetscFunctionBeginUser;
  for (PetscInt k = 1; k < user->opt.contact.n_sweep && user->rec.stats.converged; ++k) {
    const PetscReal eps_last = user->prob.eps;

    user->opt.contact.eps0 = user->opt.contact.eps0_sweep[k];
    PetscCall(ContactComputeEps(user));
    PetscCall(ElasticityUpdateConstants(dm, user));
    if (!last) PetscCall(VecDuplicate(u, &last));
    PetscCall(VecCopy(u, last));
    if (k > 1 && eps_last != eps_prev) PetscCall(ExtrapolatedStart(snes, dm, user, u, prev, (user->prob.eps - eps_last) / (eps_last - eps_prev)));
    if (!prev) PetscCall(VecDuplicate(u, &prev));
    PetscCall(VecSwap(prev, last));
    eps_prev = eps_last;
    PetscCall(SolverSolve(snes, user, u, SOLVER_START_NEARBY_EPS));
  }
  PetscCall(VecDestroy(&prev));
  PetscCall(VecDestroy(&last));
  PetscFunctionReturn(PETSC_SUCCESS);
}
