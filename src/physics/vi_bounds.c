/* SNESVI reference: the exact constraint u . n <= g as bounds on one unknown of each Gamma_C node, which needs the
   obstacle's normal along a coordinate axis at that node (a flat foundation normal to an axis, for example). */
#include "physics.h"

/* The axis k and the sign s of n = s e_k, or k = -1 when n is not along an axis. */
static void AxisOfNormal(PetscInt dim, const PetscReal n[], PetscInt *axis, PetscReal *sign)
{
  PetscInt count = 0;

  *axis = -1;
  *sign = 0.0;
  for (PetscInt d = 0; d < dim; ++d)
    if (PetscAbsReal(n[d]) > 1e-12) {
      ++count;
      *axis = d;
    }
  if (count != 1 || PetscAbsReal(PetscAbsReal(n[*axis]) - 1.0) > 1e-12) {
    *axis = -1;
    return;
  }
  *sign = n[*axis] > 0.0 ? 1.0 : -1.0;
}

/* n = +e_k: u_k <= g;  n = -e_k: u_k >= -g. Every other unknown is free; a fixed axis component needs no bound. */
PetscErrorCode VICreateBounds(DM dm, AppCtx *user)
{
  MPI_Comm          comm = PetscObjectComm((PetscObject)dm);
  const ContactSet *cs   = &user->prob.cset;
  PetscInt          dim, bad = -1, nbad = 0, total;
  PetscScalar      *xl, *xu;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMCreateGlobalVector(dm, &user->prob.xl));
  PetscCall(DMCreateGlobalVector(dm, &user->prob.xu));
  PetscCall(VecSet(user->prob.xl, PETSC_NINFINITY));
  PetscCall(VecSet(user->prob.xu, PETSC_INFINITY));
  PetscCall(VecGetArray(user->prob.xl, &xl));
  PetscCall(VecGetArray(user->prob.xu, &xu));
  for (PetscInt i = 0; i < cs->n; ++i) {
    PetscInt  axis, k;
    PetscReal sign;

    AxisOfNormal(dim, &cs->normal[i * dim], &axis, &sign);
    if (axis < 0) {
      if (bad < 0) bad = i;
      ++nbad;
      continue;
    }
    k = cs->dof[i * dim + axis];
    if (k < 0) continue; /* the normal component is prescribed */
    if (sign > 0.0)
      xu[k] = cs->gap[i];
    else
      xl[k] = -cs->gap[i];
  }
  PetscCall(VecRestoreArray(user->prob.xl, &xl));
  PetscCall(VecRestoreArray(user->prob.xu, &xu));
  PetscCall(MPIU_Allreduce(&nbad, &total, 1, MPIU_INT, MPI_SUM, comm));
  if (total) {
    PetscReal   n[3] = {0, 0, 0};
    PetscMPIInt rank, size, first, mine;

    PetscCallMPI(MPI_Comm_rank(comm, &rank));
    PetscCallMPI(MPI_Comm_size(comm, &size));
    mine = bad >= 0 ? rank : size;
    PetscCallMPI(MPI_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, comm)); /* the example comes from the first rank that has one */
    if (bad >= 0)
      for (PetscInt d = 0; d < dim; ++d) n[d] = cs->normal[bad * dim + d];
    PetscCallMPI(MPI_Bcast(n, 3, MPIU_REAL, first, comm));
    SETERRQ(comm, PETSC_ERR_USER_INPUT,
            "-contact_method vi needs the obstacle's normal along a coordinate axis at every contact node (its bounds act on one unknown each); "
            "%" PetscInt_FMT " contact nodes of scene %s have another normal, for example (%g, %g, %g): use -contact_method penalty",
            total, user->scene.name, (double)n[0], (double)n[1], (double)n[2]);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}
