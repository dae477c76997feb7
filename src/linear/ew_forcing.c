/* Eisenstat-Walker's forcing terms (PETSc's version 2, with PETSc's parameters and -snes_ksp_ew_* options), plus the
   safeguard against oversolving of Eisenstat and Walker (1996) and Kelley (1995, 6.3): the linear solve of a Newton
   step need not reduce its residual below guard * target / |F|, where target is the |F| at which Newton stops
   (-snes_rtol times |F| at the start, or times the load for a warm start). Near the solution version 2's terms fall
   superlinearly, so the last linear solve can go orders of magnitude below what Newton needs. The guard only loosens a
   term, never beyond -snes_ksp_ew_rtolmax.
   This pre-solve (part of the linear layer's, presolve.c) replaces PETSc's (KSPPreSolve_SNESEW(), installed with the
   SNES's KSP); without the guard its terms are PETSc's exactly. Other versions (-snes_ksp_ew_version) keep PETSc's.
   One of PETSc 3.18's mirrors (docs/decisions.md, "PETSc 3.18's mirrors"). */
#include "linear.h"

#define EW_ENDGAME 10.0 /* a step expected to land within this factor of Newton's target ... */
#define EW_FINISH 0.3   /* ... is solved to this fraction of it */

/* Before a linear solve (the linear layer's pre-solve, presolve.c): its tolerance, if the forcing is on. ref: the residual that -snes_rtol
   reduces, in the user's units (the core's SolverStopReference()); snes_scale: U, the SNES seeing F/U. */
PetscErrorCode SolverForcingPreSolve(SolverForcing *fc, KSP ksp, PetscReal ref, PetscReal snes_scale)
{
  SNES      snes = fc->snes;
  PetscInt  it;
  PetscReal norm, rtol, rtol_0, rtol_max, gamma, alpha, threshold, srtol, atol, stol, target;
  PetscInt  maxit, maxf;
  PetscBool ew;

  PetscFunctionBeginUser;
  if (!snes) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(SNESKSPGetUseEW(snes, &ew));
  if (!ew) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(SNESKSPGetParametersEW(snes, NULL, &rtol_0, &rtol_max, &gamma, &alpha, NULL, &threshold));
  PetscCall(SNESGetIterationNumber(snes, &it));
  PetscCall(SNESGetFunctionNorm(snes, &norm));
  if (!it)
    rtol = rtol_0;
  else {
    const PetscReal stol_ew = gamma * PetscPowReal(fc->rtol_last, alpha);

    rtol = gamma * PetscPowReal(norm / fc->norm_last, alpha);
    if (stol_ew > threshold) rtol = PetscMax(rtol, stol_ew);
  }
  if (fc->guard > 0.0 && norm > 0.0) {
    PetscCall(SNESGetTolerances(snes, &atol, &srtol, &stol, &maxit, &maxf));
    target = srtol * (ref / snes_scale); /* SolverConverged()'s reference, in the user's units; the SNES sees F/U */
    rtol   = PetscMax(rtol, fc->guard * target / norm);
    /* the endgame: where this step is to land within EW_ENDGAME times the target, it is solved to EW_FINISH times it, so
       that it ends Newton instead of leaving one more step of a V-cycle's start, an assembly and a line search (CG's
       tolerance is on the preconditioned residual, which here underestimates |F| by about 2: the 68^3 box's third step
       landed at 1.05 times the target, and its fourth cost 4 CG iterations where the third needed 1 more) */
    if (rtol * norm <= EW_ENDGAME * target) rtol = PetscMin(rtol, EW_FINISH * target / norm);
  }
  rtol = PetscMin(rtol, rtol_max);
  PetscCall(KSPSetTolerances(ksp, rtol, PETSC_DEFAULT, PETSC_DEFAULT, PETSC_DEFAULT));
  fc->rtol_last = rtol;
  fc->norm_last = norm;
  PetscCall(PetscInfo(snes, "iter %" PetscInt_FMT ", Eisenstat-Walker (version 2, oversolving guard %g) KSP rtol=%g\n", it, (double)fc->guard,
                      (double)rtol));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Records the forcing's parameters if Eisenstat-Walker's version 2 is on (SolverForcingPreSolve() then computes the
   terms); guard: -contact_ew_guard; *petsc_presolve: another version is on, whose pre-solve is PETSc's own and must stay. */
PetscErrorCode SolverForcingSetUp(SolverForcing *fc, SNES snes, PetscReal guard, PetscBool *petsc_presolve)
{
  PetscBool ew;
  PetscInt  version;

  PetscFunctionBeginUser;
  PetscCall(PetscMemzero(fc, sizeof(*fc)));
  *petsc_presolve = PETSC_FALSE;
  PetscCall(SNESKSPGetUseEW(snes, &ew));
  if (!ew) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(SNESKSPGetParametersEW(snes, &version, NULL, NULL, NULL, NULL, NULL, NULL));
  *petsc_presolve = (PetscBool)(version != 2);
  if (version != 2) PetscFunctionReturn(PETSC_SUCCESS);
  fc->snes  = snes;
  fc->guard = guard;
  PetscFunctionReturn(PETSC_SUCCESS);
}
