/* When to rebuild the preconditioner (or the factorization) of the penalty Newton steps.
   J = K + (1/eps) P_A changes only in the Gamma_C rows of the nodes whose contact state changed, so J_new - J_old has
   a rank of about the number of those nodes: a Krylov method preconditioned by the previous build converges in about
   that many more iterations (exactly, for a direct solver). The build is reused while few nodes changed, eps is the
   same and the linear solves stay cheap; it is rebuilt otherwise. */
#include "physics.h"
#include "solver.h"

/* Number of contact nodes (over all ranks) whose state differs from the state at the last build. */
static PetscErrorCode CountChanges(AppCtx *user, PetscInt dim, const PetscScalar x[], PetscBool record, PetscInt *changes)
{
  PetscInt local = 0;

  PetscFunctionBeginUser;
  for (PetscInt i = 0; i < user->prob.cset.n; ++i) {
    const PetscBool on = (PetscBool)(ContactNodePenetration(&user->prob.cset, dim, i, x) > 0.0);

    local += on != user->prob.cset.built_active[i];
    if (record) user->prob.cset.built_active[i] = on;
  }
  PetscCall(MPIU_Allreduce(&local, changes, 1, MPIU_INT, MPI_SUM, PetscObjectComm((PetscObject)user->prob.K)));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Called by the Jacobian evaluation at X, before SNES sets up the preconditioner: sets the SNES preconditioner lag to
   rebuild (-2) or reuse (-1), and records the state of the build. */
PetscErrorCode PcReuseDecide(SNES snes, DM dm, AppCtx *user, Vec X)
{
  PcReuse           *r = &user->prob.pc_reuse;
  KSP                ksp;
  PetscInt           dim, changes = 0, its = 0;
  KSPConvergedReason reason = KSP_CONVERGED_ITERATING;
  PetscBool          rebuild;
  const PetscScalar *x;

  PetscFunctionBeginUser;
  if (!r->enabled) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(SNESGetKSP(snes, &ksp));
  PetscCall(VecGetArrayRead(X, &x));
  rebuild = (PetscBool)(!r->built || r->eps != user->prob.eps);
  if (!rebuild) {
    PetscCall(CountChanges(user, dim, x, PETSC_FALSE, &changes));
    PetscCall(KSPGetIterationNumber(ksp, &its));
    PetscCall(KSPGetConvergedReason(ksp, &reason));
    /* rebuild after a failed solve, or when the last solve needed twice the iterations of the first after the build */
    rebuild =
        (PetscBool)(changes > user->opt.contact.pc_reuse_changes || reason < 0 || (r->its_after_build >= 0 && its > 2 * r->its_after_build + 5));
  }
  if (rebuild) {
    PetscCall(CountChanges(user, dim, x, PETSC_TRUE, &changes));
    r->built           = PETSC_TRUE;
    r->eps             = user->prob.eps;
    r->its_after_build = -1; /* set by the next call */
    r->builds++;
    PetscCall(SNESSetLagPreconditioner(snes, -2)); /* rebuild now, then reuse until told otherwise */
  } else {
    if (r->its_after_build < 0) r->its_after_build = its;
    PetscCall(SNESSetLagPreconditioner(snes, -1));
  }
  PetscCall(VecRestoreArrayRead(X, &x));
  PetscFunctionReturn(PETSC_SUCCESS);
}
