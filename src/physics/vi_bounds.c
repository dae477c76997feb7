/* SNESVI reference: the exact constraint u_n <= g as bounds on the normal unknown of each Gamma_C node. */
#include "physics.h"

/* Bounds act on one unknown each, so the foundation normal must be +-e_axis. */
static PetscErrorCode VIAxisOfNormal(const AppCtx *user, PetscInt dim, PetscInt *axis, PetscReal *sign)
{
  const PetscReal *n     = user->scene.obstacle_normal;
  PetscInt         count = 0;

  PetscFunctionBeginUser;
  *axis = -1;
  for (PetscInt d = 0; d < dim; ++d) {
    if (PetscAbsReal(n[d]) > 1e-12) {
      ++count;
      *axis = d;
    }
  }
  PetscCheck(
      count == 1 && PetscAbsReal(PetscAbsReal(n[*axis]) - 1.0) < 1e-12, PETSC_COMM_SELF, PETSC_ERR_USER_INPUT,
      "-contact_method vi needs Gamma_C normal to a coordinate axis (bounds act on one unknown each); scene %s has obstacle normal (%g, %g, %g)",
      user->scene.name, (double)n[0], (double)n[1], (double)n[2]);
  *sign = n[*axis] > 0.0 ? 1.0 : -1.0;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* n = +e_k: u_k <= g;  n = -e_k: u_k >= -g. Every other unknown is free. */
PetscErrorCode VICreateBounds(DM dm, AppCtx *user)
{
  PetscInt     dim, axis;
  PetscReal    sign;
  PetscScalar *xl, *xu;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(VIAxisOfNormal(user, dim, &axis, &sign));
  PetscCall(DMCreateGlobalVector(dm, &user->prob.xl));
  PetscCall(DMCreateGlobalVector(dm, &user->prob.xu));
  PetscCall(VecSet(user->prob.xl, PETSC_NINFINITY));
  PetscCall(VecSet(user->prob.xu, PETSC_INFINITY));
  PetscCall(VecGetArray(user->prob.xl, &xl));
  PetscCall(VecGetArray(user->prob.xu, &xu));
  for (PetscInt i = 0; i < user->prob.cset.n; ++i) {
    const PetscInt k = user->prob.cset.global_off[i] + axis;
    if (sign > 0.0)
      xu[k] = user->prob.cset.gap[i];
    else
      xl[k] = -user->prob.cset.gap[i];
  }
  PetscCall(VecRestoreArray(user->prob.xl, &xl));
  PetscCall(VecRestoreArray(user->prob.xu, &xu));
  PetscFunctionReturn(PETSC_SUCCESS);
}
