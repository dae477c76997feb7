/* The Contact type "vi", the reference for the exact constraint: u . n <= g as bounds of SNESVI on one unknown of each
   Gamma_C node, which needs the obstacle's normal along a coordinate axis at that node (a flat foundation normal to an
   axis, for example). The contact pressure is the reaction of the bound (ContactPostProcess()). */
#include "contact_impl.h"

typedef struct {
  Vec xl, xu; /* SNESVI's bounds */
} Contact_VI;

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

/* The bounds from the set's gaps and normals: n = +e_k: u_k <= g;  n = -e_k: u_k >= -g. Every other unknown is free; a
   fixed axis component needs no bound. At set-up, and again at each load state of a path (the obstacle's translation
   changes the gaps), before the SNES scales them (SolverSNESSolve()). Refused where a normal is not an axis. */
static PetscErrorCode FillBounds(Contact ct)
{
  Contact_VI       *vi   = (Contact_VI *)ct->data;
  MPI_Comm          comm = ct->comm;
  const ContactSet *cs   = &ct->set;
  const PetscInt    dim  = ct->dim;
  PetscInt          bad = -1, nbad = 0, total;
  PetscScalar      *xl, *xu;

  PetscFunctionBeginUser;
  PetscCall(VecSet(vi->xl, PETSC_NINFINITY));
  PetscCall(VecSet(vi->xu, PETSC_INFINITY));
  PetscCall(VecGetArray(vi->xl, &xl));
  PetscCall(VecGetArray(vi->xu, &xu));
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
  PetscCall(VecRestoreArray(vi->xl, &xl));
  PetscCall(VecRestoreArray(vi->xu, &xu));
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
            "%" PetscInt_FMT " contact nodes of the scene have another normal, for example (%g, %g, %g): use -contact_method penalty",
            total, (double)n[0], (double)n[1], (double)n[2]);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode ContactSetUp_VI(Contact ct, DM dm)
{
  Contact_VI *vi = (Contact_VI *)ct->data;

  PetscFunctionBeginUser;
  PetscCall(DMCreateGlobalVector(dm, &vi->xl));
  PetscCall(DMCreateGlobalVector(dm, &vi->xu));
  PetscCall(FillBounds(ct));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A new load state (ContactSetLoad()): the bounds of the new gaps, in the vectors SNESVISetVariableBounds() holds. */
static PetscErrorCode ContactLoad_VI(Contact ct, DM dm)
{
  PetscFunctionBeginUser;
  PetscCall(FillBounds(ct));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode ContactReset_VI(Contact ct)
{
  Contact_VI *vi = (Contact_VI *)ct->data;

  PetscFunctionBeginUser;
  PetscCall(VecDestroy(&vi->xl));
  PetscCall(VecDestroy(&vi->xu));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* SNESVI's reduced-space method with the bounds; the options may choose vinewtonssls instead. */
static PetscErrorCode ContactSetUpSNES_VI(Contact ct, DM dm, SNES snes)
{
  Contact_VI *vi = (Contact_VI *)ct->data;

  PetscFunctionBeginUser;
  PetscCall(SNESSetType(snes, SNESVINEWTONRSLS));
  PetscCall(SNESVISetVariableBounds(snes, vi->xl, vi->xu));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The bounds times s: the SNES iterates on u/U (src/solver/solver.c), and its bounds with it. */
static PetscErrorCode ContactScaleBounds_VI(Contact ct, PetscReal s)
{
  Contact_VI *vi = (Contact_VI *)ct->data;

  PetscFunctionBeginUser;
  if (vi->xl) PetscCall(VecScale(vi->xl, s));
  if (vi->xu) PetscCall(VecScale(vi->xu, s));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode ContactCreate_VI(Contact ct)
{
  Contact_VI *vi;

  PetscFunctionBeginUser;
  PetscCall(PetscNew(&vi));
  ct->data             = vi;
  ct->has_bounds       = PETSC_TRUE;
  ct->ops.setup        = ContactSetUp_VI;
  ct->ops.reset        = ContactReset_VI;
  ct->ops.setup_snes   = ContactSetUpSNES_VI;
  ct->ops.scale_bounds = ContactScaleBounds_VI;
  ct->ops.load         = ContactLoad_VI;
  PetscFunctionReturn(PETSC_SUCCESS);
}
