/* Active set of Gamma_C and the per-Newton-step contact monitor (-contact_monitor). */
#include "signorini.h"

/* A vertex of Gamma_C is active when it penetrates (penalty) or sits on its bound (vi).
   With update, the active flags are stored and the vertices that entered and left are counted. */
PetscErrorCode ContactCountActive(AppCtx *user, Vec X, PetscBool update, PetscInt *active, PetscInt *entered, PetscInt *left)
{
  const PetscReal    tol = user->contact.method == CONTACT_VI ? 1e-10 * user->h : 0.0;
  const PetscScalar *x;
  PetscInt           dim, local[3] = {0, 0, 0}, global[3];
  DM                 dm;

  PetscFunctionBeginUser;
  PetscCall(VecGetDM(X, &dm));
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(VecGetArrayRead(X, &x));
  for (PetscInt i = 0; i < user->cset.n; ++i) {
    PetscBool on;

    if (!user->cset.is_vertex[i]) continue;
    on = (PetscBool)(user->contact.method != CONTACT_NONE && ContactNodePenetration(user, dim, i, x) > -tol);
    local[0] += on;
    local[1] += on && !user->cset.active[i];
    local[2] += !on && user->cset.active[i];
    if (update) user->cset.active[i] = on;
  }
  PetscCall(VecRestoreArrayRead(X, &x));
  PetscCall(MPIU_Allreduce(local, global, 3, MPIU_INT, MPI_SUM, PetscObjectComm((PetscObject)dm)));
  *active = global[0];
  if (entered) *entered = global[1];
  if (left) *left = global[2];
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode ContactMonitor(SNES snes, PetscInt it, PetscReal fnorm, void *ctx)
{
  AppCtx  *user = (AppCtx *)ctx;
  Vec      X;
  PetscInt active, entered, left;

  PetscFunctionBeginUser;
  user->stats.residual_norm = fnorm;
  if (!user->contact.monitor) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(SNESGetSolution(snes, &X));
  PetscCall(ContactCountActive(user, X, PETSC_TRUE, &active, &entered, &left));
  PetscCall(PetscPrintf(PetscObjectComm((PetscObject)snes),
                        "  %3" PetscInt_FMT " contact: |F| %12.6e  active vertices %6" PetscInt_FMT "  entered %5" PetscInt_FMT
                        "  left %5" PetscInt_FMT "\n",
                        it, (double)fnorm, active, entered, left));
  PetscFunctionReturn(PETSC_SUCCESS);
}
