/* The Contact type "vi", the reference for the exact constraint: u . n <= g as bounds of SNESVI on one unknown of each
   Gamma_C node: the component along n where n is a coordinate axis, the normal unknown of the node's rotated frame
   everywhere else (vi_frames.c: tilted planes, spheres, cylinders). The contact pressure is the reaction of the bound
   (ContactPostProcess()). */
#include "contact_impl.h"

typedef struct {
  Vec      xl, xu; /* SNESVI's bounds, on the SNES's unknowns (the frames' where there are frames) */
  ViFrames frames;
  Mat      K;  /* the bulk operator (referenced), and */
  Mat      Kw; /* Q^T K Q, the SNES's Jacobian where there are frames */
} Contact_VI;

/* The bounds from the set's gaps and normals (ViNodeConstraint(): coef x <= rhs on the node's one constrained
   unknown): x <= rhs / coef for coef > 0 (n = +e_k: u_k <= g; a frame's w_n), x >= rhs / coef for coef < 0 (n = -e_k:
   u_k >= -g). Every other unknown is free; a node whose normal meets no free component needs no bound. At set-up, and
   again at each load state of a path (the obstacle's translation changes the gaps and a curved obstacle's normals),
   before the SNES scales them (SolverSNESSolve()). A normal that needs a frame on a mesh set up without frames (the
   obstacle's normals were all axes then) is refused. */
static PetscErrorCode FillBounds(Contact ct)
{
  Contact_VI       *vi   = (Contact_VI *)ct->data;
  MPI_Comm          comm = ct->comm;
  const ContactSet *cs   = &ct->set;
  const PetscInt    dim  = ct->dim;
  PetscInt          bad = -1, nbad = 0, total;
  PetscScalar      *xl, *xu;

  PetscFunctionBeginUser;
  PetscCall(ViFramesUpdate(cs, dim, &vi->frames));
  PetscCall(VecSet(vi->xl, PETSC_NINFINITY));
  PetscCall(VecSet(vi->xu, PETSC_INFINITY));
  PetscCall(VecGetArray(vi->xl, &xl));
  PetscCall(VecGetArray(vi->xu, &xu));
  for (PetscInt i = 0; i < cs->n; ++i) {
    PetscInt  comp, k;
    PetscReal coef, rhs;
    PetscBool rotate;

    ViNodeConstraint(cs, dim, i, &comp, &coef, &rhs, &rotate);
    if (comp < 0) continue; /* the normal component is prescribed */
    if (rotate && !vi->frames.nrotated) {
      if (bad < 0) bad = i;
      ++nbad;
      continue;
    }
    k = cs->dof[i * dim + comp];
    if (coef > 0.0)
      xu[k] = rhs / coef;
    else
      xl[k] = rhs / coef;
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
            "-contact_method vi: the obstacle's normals were coordinate axes at every contact node when the mesh was set up, and now "
            "%" PetscInt_FMT
            " contact nodes have another normal, for example (%g, %g, %g): start the load path where the normals are as they will be",
            total, (double)n[0], (double)n[1], (double)n[2]);
  }
  if (vi->Kw && vi->frames.operator_state != vi->frames.state) PetscCall(ViFramesOperator(cs, dim, &vi->frames, vi->K, &vi->Kw));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode ContactSetUp_VI(Contact ct, DM dm)
{
  Contact_VI *vi = (Contact_VI *)ct->data;

  PetscFunctionBeginUser;
  PetscCall(DMCreateGlobalVector(dm, &vi->xl));
  PetscCall(DMCreateGlobalVector(dm, &vi->xu));
  PetscCall(ViFramesSetUp(ct->comm, &ct->set, ct->dim, vi->xl, &vi->frames));
  ct->has_frames = (PetscBool)(vi->frames.nrotated > 0);
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
  PetscCall(ViFramesDestroy(&vi->frames));
  ct->has_frames = PETSC_FALSE;
  PetscCall(MatDestroy(&vi->K));
  PetscCall(MatDestroy(&vi->Kw));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* SNESVI's reduced-space method with the bounds; the options may choose vinewtonssls instead. With frames, the
   Jacobian is Q^T K Q (made once per mesh and frames; the SNES's Jacobian callback leaves it as it is). */
static PetscErrorCode ContactSetUpSNES_VI(Contact ct, DM dm, SNES snes)
{
  Contact_VI *vi = (Contact_VI *)ct->data;

  PetscFunctionBeginUser;
  if (vi->frames.nrotated) {
    Mat K;

    PetscCall(SNESGetJacobian(snes, &K, NULL, NULL, NULL));
    if (vi->K != K) {
      PetscCall(PetscObjectReference((PetscObject)K));
      PetscCall(MatDestroy(&vi->K));
      PetscCall(MatDestroy(&vi->Kw));
      vi->K = K;
    }
    if (!vi->Kw || vi->frames.operator_state != vi->frames.state) PetscCall(ViFramesOperator(&ct->set, ct->dim, &vi->frames, vi->K, &vi->Kw));
    PetscCall(SNESSetJacobian(snes, vi->Kw, vi->Kw, NULL, NULL)); /* the callback stays */
  }
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

/* v <- Q^T v (to the SNES's unknowns) or v <- Q v (back to u). */
static PetscErrorCode ContactFrame_VI(Contact ct, Vec v, PetscBool to_solver)
{
  Contact_VI *vi = (Contact_VI *)ct->data;

  PetscFunctionBeginUser;
  PetscCall(ViFramesApply(&ct->set, ct->dim, &vi->frames, v, to_solver));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode ContactCreate_VI(Contact ct)
{
  Contact_VI *vi;

  PetscFunctionBeginUser;
  PetscCall(PetscNew(&vi));
  ct->data       = vi;
  ct->has_bounds = PETSC_TRUE;
  /* the defaults all PETSC_FALSE: SNESVI's reduced system changes size between steps, which no multigrid follows */
  ct->ops.setup        = ContactSetUp_VI;
  ct->ops.reset        = ContactReset_VI;
  ct->ops.setup_snes   = ContactSetUpSNES_VI;
  ct->ops.scale_bounds = ContactScaleBounds_VI;
  ct->ops.load         = ContactLoad_VI;
  ct->ops.frame        = ContactFrame_VI;
  PetscFunctionReturn(PETSC_SUCCESS);
}
