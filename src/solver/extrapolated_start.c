/* The start of a solve extrapolated from earlier solutions: the eps sweep's (eps_sweep.c), the load path's
   (load_path.c) and the penetration tolerance's (penetration_tol.c). */
#include "contact.h"
#include "solver_impl.h"

/* u <- u + factor dir if the penalty is active there at the same points as at u (the last solution) and the residual
   at the current eps is lower, or, whatever the points, if that residual is below relaxed times the last one (the
   tangent's guess, below; 0 for the secant's). A secant guess active elsewhere is not taken: a Gauss point it lifts off that the new eps keeps
   in contact (near the edge of the contact zone) makes the line search cut every Newton step at that kink, and Newton
   stalls. Such a guess that still lowers
   the residual gives, with step_guess, the first linear solve's initial guess instead (step_guess.c): Newton starts
   from u, with its active points, and CG from the step factor dir; dir is then scaled. */
PetscErrorCode SolverExtrapolatedStart(SNES snes, DM dm, Solver s, Vec u, Vec dir, PetscReal factor, PetscReal relaxed, PetscBool step_guess)
{
  const SolverCtx sc = s->prob.sctx;
  Vec             guess;
  PetscReal       f_last, f_guess;
  PetscBool       same;

  PetscFunctionBeginUser;
  PetscCall(VecDuplicate(u, &guess));
  PetscCall(VecWAXPY(guess, factor, dir, u));
  PetscCall(ContactSameActivity(s->contact, dm, u, guess, &same));
  PetscCall(SolverResidualNorm(snes, sc, u, &f_last)); /* every start needs both: the tangent's and the secant's rules */
  PetscCall(SolverResidualNorm(snes, sc, guess, &f_guess));
  if ((same && f_guess < f_last) || f_guess < relaxed * f_last)
    PetscCall(VecCopy(guess, u));
  else if (step_guess && f_guess < f_last) {
    PetscCall(VecScale(dir, factor));
    PetscCall(SolverSetStepGuess(sc, dir));
  }
  PetscCall(VecDestroy(&guess));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The start of a solve on the secant of the last two solutions: u <- u + factor (u - prev) where
   SolverExtrapolatedStart() takes it (use; relaxed as there), and prev <- the old u. Shared by a load path's steps
   (along the factor), force control's positions (along the position) and the penetration tolerance's values of eps. */
PetscErrorCode SolverSecantStart(SNES snes, DM dm, Solver s, Vec u, Vec prev, Vec dir, PetscBool use, PetscReal factor, PetscReal relaxed)
{
  PetscFunctionBeginUser;
  if (use) {
    PetscCall(VecWAXPY(dir, -1.0, prev, u));
    PetscCall(VecCopy(u, prev));
    PetscCall(SolverExtrapolatedStart(snes, dm, s, u, dir, factor, relaxed, PETSC_TRUE));
  } else
    PetscCall(VecCopy(u, prev));
  PetscFunctionReturn(PETSC_SUCCESS);
}
