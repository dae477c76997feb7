/* The Contact type "none": no contact term, the linear elastic problem (Newton converges in one step). Gamma_C keeps
   its contact set, so that the outputs (gap, reaction) are written as for the other types. */
#include "contact_impl.h"

/* No contact force acts anywhere: every node's pressure is zero. */
static PetscErrorCode ContactActs_None(Contact ct, DM dm, Vec u, PetscBool acts[], PetscReal *dmax)
{
  PetscFunctionBeginUser;
  for (PetscInt i = 0; i < ct->set.n; ++i) acts[i] = PETSC_FALSE;
  *dmax = -PETSC_MAX_REAL;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode ContactCreate_None(Contact ct)
{
  PetscFunctionBeginUser;
  ct->ops.acts           = ContactActs_None;
  ct->defaults.linear    = PETSC_TRUE; /* J = K: one Newton step, a linear solve */
  ct->defaults.multigrid = PETSC_TRUE;
  PetscFunctionReturn(PETSC_SUCCESS);
}
