/* The linear layer's KSP pre-solve: before each linear solve of a Newton step, the finest multigrid smoother's -mg_fine_
   options (fine_smoother.c), the initial guess (step_guess.c), then the linear tolerance of the inexact Newton
   (ew_forcing.c). It is PETSc's hook for what changes from one linear solve to the next (KSPSetPreSolve()), called
   after the SNES has set the new Jacobian as the operator and before the KSP sets up its preconditioner. What it reads
   of the Newton core, the stopping reference and the SNES's scale, comes through the core's LinearCore. */
#include "linear.h"

static PetscErrorCode LinearPreSolveApply(KSP ksp, Vec b, Vec x, void *ctx)
{
  LinearPreSolve *ps = (LinearPreSolve *)ctx;
  PetscReal       ref, scale;

  PetscFunctionBeginUser;
  PetscCall((*ps->core.scales)(ps->core.core, &ref, &scale));
  PetscCall(FineSmootherSetUp(ksp, ps->given));
  PetscCall(SolverStepGuessPreSolve(ps->step_guess, ksp, x, scale));
  PetscCall(SolverForcingPreSolve(ps->forcing, ksp, ref, scale));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Attaches the pre-solve to ksp, with the states it acts on (kept by the core) and what it reads of the core. */
PetscErrorCode LinearPreSolveAttach(LinearPreSolve *ps, KSP ksp, const SolverGiven *given, SolverStepGuess *sg, SolverForcing *fc,
                                    const LinearCore *core)
{
  PetscFunctionBeginUser;
  ps->given      = given;
  ps->step_guess = sg;
  ps->forcing    = fc;
  ps->core       = *core;
  PetscCall(KSPSetPreSolve(ksp, LinearPreSolveApply, ps));
  PetscFunctionReturn(PETSC_SUCCESS);
}
