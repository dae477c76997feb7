/* A predicted Newton step as the initial guess of the next solve's first linear solve, instead of zero.
   The eps sweep (eps_sweep.c) extrapolates the solution for a new eps from the last two; where that guess changes the
   penalty's active points it is not taken as Newton's first iterate, whose Jacobian would miss them and whose steps
   the line search then cut at those kinks. Newton starts from the last solution instead, and its first linear solve,
   the step to the new eps with the last solution's active points, starts from the step the guess predicts.
   The linear solve is then asked to reduce the smaller of its first residual and its right-hand side's
   (KSPConvergedDefaultSetUMIRNorm()): relative to the right-hand side alone, as PETSc measures a nonzero guess by default,
   a close guess meets the forcing term almost at once, and Newton, left with the guess as its step, needs more steps.
   The test stays so set for later solves, where it changes nothing unless the options ask for a nonzero initial guess,
   which it then measures the same way. */
#include "linear.h"

/* At the SNES's set-up: what the options asked of its KSP (given: the solver's options given, SolverGiven). */
PetscErrorCode SolverStepGuessSetUp(SolverStepGuess *sg, KSP ksp, const SolverGiven *given)
{
  const char *prefix;

  PetscFunctionBeginUser;
  PetscCall(VecDestroy(&sg->du));
  PetscCall(KSPGetInitialGuessNonzero(ksp, &sg->nonzero));
  PetscCall(KSPGetOptionsPrefix(ksp, &prefix));
  {
    PetscInt k;

    PetscCall(SolverGivenIndex(prefix, &k));
    sg->user_rnorm0 = given->use_initial_rnorm[k]; /* -ksp_converged_use_initial_residual_norm */
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The next solve's first linear solve starts from the Newton step that the change du of the solution (the user's
   units) predicts. du is referenced until that linear solve, or the end of that solve (SolverStepGuessDrop()). */
PetscErrorCode SolverStepGuessSet(SolverStepGuess *sg, Vec du)
{
  PetscFunctionBeginUser;
  PetscCall(PetscObjectReference((PetscObject)du));
  PetscCall(VecDestroy(&sg->du));
  sg->du = du;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Before each linear solve (the linear layer's pre-solve, presolve.c): the guess, if one is pending, else the options' initial guess.
   snes_scale: U, the SNES iterating on u/U. */
PetscErrorCode SolverStepGuessPreSolve(SolverStepGuess *sg, KSP ksp, Vec x, PetscReal snes_scale)
{
  PetscBool preonly;

  PetscFunctionBeginUser;
  PetscCall(KSPSetInitialGuessNonzero(ksp, sg->nonzero));
  if (!sg->du) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscObjectTypeCompare((PetscObject)ksp, KSPPREONLY, &preonly)); /* a factorization alone takes no guess */
  if (!preonly) {
    PetscCall(VecCopy(sg->du, x)); /* Newton's step y of the SNES, x~_next = x~ - y with x~ = u / U: y = -du / U */
    PetscCall(VecScale(x, -1.0 / snes_scale));
    PetscCall(KSPSetInitialGuessNonzero(ksp, PETSC_TRUE));
    if (!sg->user_rnorm0) PetscCall(KSPConvergedDefaultSetUMIRNorm(ksp));
  }
  PetscCall(VecDestroy(&sg->du));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode SolverStepGuessDrop(SolverStepGuess *sg)
{
  PetscFunctionBeginUser;
  PetscCall(VecDestroy(&sg->du));
  PetscFunctionReturn(PETSC_SUCCESS);
}
