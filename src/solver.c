/* The nonlinear solve. The bulk operator is linear: K and r0 = F_bulk(0) are assembled once,
   the residual is K u + r0 + (contact terms) and the Jacobian K + (contact Jacobian). */
#include "signorini.h"

PetscErrorCode SolverAssembleBulk(DM dm, AppCtx *user)
{
  Vec          locX, locF;
  MatNullSpace rigid;

  PetscFunctionBeginUser;
  PetscCall(DMCreateMatrix(dm, &user->K));
  PetscCall(DMCreateGlobalVector(dm, &user->r0));
  PetscCall(DMGetLocalVector(dm, &locX));
  PetscCall(DMGetLocalVector(dm, &locF));
  PetscCall(VecZeroEntries(locX));
  PetscCall(VecZeroEntries(locF));
  PetscCall(DMPlexInsertBoundaryValues(dm, PETSC_TRUE, locX, 0.0, NULL, NULL, NULL));
  PetscCall(DMPlexSNESComputeJacobianFEM(dm, locX, user->K, user->K, user));
  PetscCall(MatAssemblyBegin(user->K, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(user->K, MAT_FINAL_ASSEMBLY));
  PetscCall(DMPlexSNESComputeResidualFEM(dm, locX, locF, user));
  PetscCall(VecZeroEntries(user->r0));
  PetscCall(DMLocalToGlobal(dm, locF, ADD_VALUES, user->r0));
  PetscCall(DMRestoreLocalVector(dm, &locX));
  PetscCall(DMRestoreLocalVector(dm, &locF));
  PetscCall(DMPlexCreateRigidBody(dm, 0, &rigid));
  PetscCall(MatSetNearNullSpace(user->K, rigid));
  PetscCall(MatNullSpaceDestroy(&rigid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* R = K X + r0: the residual of the elastic problem without the contact terms. */
PetscErrorCode SolverBulkResidual(AppCtx *user, Vec X, Vec R)
{
  PetscFunctionBeginUser;
  PetscCall(MatMult(user->K, X, R));
  PetscCall(VecAXPY(R, 1.0, user->r0));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode FormFunction(SNES snes, Vec X, Vec F, void *ctx)
{
  AppCtx *user = (AppCtx *)ctx;
  DM      dm;

  PetscFunctionBeginUser;
  PetscCall(SNESGetDM(snes, &dm));
  PetscCall(SolverBulkResidual(user, X, F));
  if (user->contact.method == CONTACT_PENALTY) PetscCall(PenaltyAddResidual(dm, user, X, F));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode FormJacobian(SNES snes, Vec X, Mat J, Mat P, void *ctx)
{
  AppCtx *user = (AppCtx *)ctx;
  DM      dm;

  PetscFunctionBeginUser;
  PetscCall(SNESGetDM(snes, &dm));
  if (user->contact.method == CONTACT_PENALTY) {
    PetscCall(MatCopy(user->K, P, SAME_NONZERO_PATTERN));
    PetscCall(PenaltyAddJacobian(dm, user, X, P));
    PetscCall(MatAssemblyBegin(P, MAT_FINAL_ASSEMBLY));
    PetscCall(MatAssemblyEnd(P, MAT_FINAL_ASSEMBLY));
  }
  if (J != P) {
    PetscCall(MatAssemblyBegin(J, MAT_FINAL_ASSEMBLY));
    PetscCall(MatAssemblyEnd(J, MAT_FINAL_ASSEMBLY));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode SolverCreateSNES(DM dm, AppCtx *user, SNES *snes)
{
  MPI_Comm  comm = PetscObjectComm((PetscObject)dm);
  Mat       J;
  KSP       ksp;
  PC        pc;
  PetscBool is_vi;
  SNESType  type;

  PetscFunctionBeginUser;
  PetscCall(SNESCreate(comm, snes));
  PetscCall(SNESSetDM(*snes, dm));
  if (user->contact.method == CONTACT_PENALTY) {
    MatNullSpace rigid;

    PetscCall(MatDuplicate(user->K, MAT_COPY_VALUES, &J));
    PetscCall(MatGetNearNullSpace(user->K, &rigid));
    PetscCall(MatSetNearNullSpace(J, rigid));
  } else {
    J = user->K; /* the Jacobian is K itself */
    PetscCall(PetscObjectReference((PetscObject)J));
  }
  PetscCall(SNESSetFunction(*snes, NULL, FormFunction, user));
  PetscCall(SNESSetJacobian(*snes, J, J, FormJacobian, user));
  PetscCall(MatDestroy(&J));
  if (user->contact.method == CONTACT_VI) {
    PetscCall(SNESSetType(*snes, SNESVINEWTONRSLS));
    PetscCall(VICreateBounds(dm, user));
    PetscCall(SNESVISetVariableBounds(*snes, user->xl, user->xu));
  } else {
    SNESLineSearch ls;

    PetscCall(SNESSetType(*snes, SNESNEWTONLS));
    /* the penalty problem is the minimization of a convex energy: the critical-point line search keeps the semismooth Newton
       converging for small eps, where backtracking on |F| stalls (32x32 mms, eps = 1e-5: bt fails, cp converges) */
    PetscCall(SNESGetLineSearch(*snes, &ls));
    PetscCall(SNESLineSearchSetType(ls, SNESLINESEARCHCP));
    /* no convergence on a small step: with eps = 1e-7 (128x128 mms) it stopped Newton at |F| = 3e-4, far from the solution */
    PetscCall(SNESSetTolerances(*snes, PETSC_DEFAULT, PETSC_DEFAULT, 0.0, PETSC_DEFAULT, PETSC_DEFAULT));
  }
  /* default linear solver: a direct solve (MUMPS), robust for the small problems of a first run */
  PetscCall(SNESGetKSP(*snes, &ksp));
  PetscCall(KSPSetType(ksp, KSPPREONLY));
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(PCSetType(pc, PCLU));
  PetscCall(PCFactorSetMatSolverType(pc, MATSOLVERMUMPS));
  PetscCall(SNESMonitorSet(*snes, ContactMonitor, user, NULL));
  PetscCall(SNESSetFromOptions(*snes));
  PetscCall(PetscObjectTypeCompareAny((PetscObject)*snes, &is_vi, SNESVINEWTONRSLS, SNESVINEWTONSSLS, ""));
  PetscCall(SNESGetType(*snes, &type));
  {
    PetscBool is_gamg, is_rsls;

    PetscCall(PetscObjectTypeCompare((PetscObject)pc, PCGAMG, &is_gamg));
    PetscCall(PetscObjectTypeCompare((PetscObject)*snes, SNESVINEWTONRSLS, &is_rsls));
    PetscCheck(!(is_gamg && is_rsls), comm, PETSC_ERR_USER_INPUT,
               "-pc_type gamg cannot follow the reduced system of -snes_type vinewtonrsls (its size changes between steps): use hypre or mumps with "
               "-contact_method vi");
  }
  PetscCheck(is_vi == (user->contact.method == CONTACT_VI), comm, PETSC_ERR_USER_INPUT,
             "-snes_type %s does not fit -contact_method %s: use vinewtonrsls or vinewtonssls with vi, and a non-VI type otherwise", type,
             ContactMethods[user->contact.method]);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Solves from a zero initial guess and records the outcome; a failed solve is recorded, not raised. */
PetscErrorCode SolverSolve(SNES snes, AppCtx *user, Vec u)
{
  PetscLogDouble t0, t1;

  PetscFunctionBeginUser;
  PetscCall(VecZeroEntries(u));
  PetscCall(PetscTime(&t0));
  PetscCall(SNESSolve(snes, NULL, u));
  PetscCall(PetscTime(&t1));
  user->stats.time_solve = t1 - t0;
  PetscCall(SNESGetConvergedReason(snes, &user->stats.reason));
  PetscCall(SNESGetIterationNumber(snes, &user->stats.newton_its));
  PetscCall(SNESGetLinearSolveIterations(snes, &user->stats.ksp_its));
  user->stats.converged = (PetscBool)(user->stats.reason > 0);
  PetscFunctionReturn(PETSC_SUCCESS);
}
