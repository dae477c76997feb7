/* The penalty term on Gamma_C: (1/eps) int [u_n - g]_+ v_n and its generalized Jacobian (1/eps) H(u_n - g) n n^T.
   gauss: PetscFE boundary kernels with the face Gauss rule (the paper's L2 product);
   nodal: the same term with the vertex rule, node by node with the lumped boundary mass. */
#include "physics.h"

/* u_n - g with g = offset - x . n: the penetration into the foundation (positive = penetrating). */
static inline PetscReal Penetration(PetscInt dim, const PetscScalar u[], const PetscReal x[], const PetscScalar constants[])
{
  PetscReal d = -PetscRealPart(constants[CONST_OBSTACLE_OFFSET]);

  for (PetscInt c = 0; c < dim; ++c) d += (PetscRealPart(u[c]) + x[c]) * PetscRealPart(constants[CONST_NORMAL_X + c]);
  return d;
}

static void f0_bd_penalty(PetscInt dim, PetscInt Nf, PetscInt NfAux, const PetscInt uOff[], const PetscInt uOff_x[], const PetscScalar u[],
                          const PetscScalar u_t[], const PetscScalar u_x[], const PetscInt aOff[], const PetscInt aOff_x[], const PetscScalar a[],
                          const PetscScalar a_t[], const PetscScalar a_x[], PetscReal t, const PetscReal x[], const PetscReal n[],
                          PetscInt numConstants, const PetscScalar constants[], PetscScalar f0[])
{
  const PetscReal d = Penetration(dim, u, x, constants);
  const PetscReal p = d > 0.0 ? PetscRealPart(constants[CONST_PENALTY]) * d : 0.0;

  for (PetscInt c = 0; c < dim; ++c) f0[c] = p * constants[CONST_NORMAL_X + c];
}

static void g0_bd_penalty(PetscInt dim, PetscInt Nf, PetscInt NfAux, const PetscInt uOff[], const PetscInt uOff_x[], const PetscScalar u[],
                          const PetscScalar u_t[], const PetscScalar u_x[], const PetscInt aOff[], const PetscInt aOff_x[], const PetscScalar a[],
                          const PetscScalar a_t[], const PetscScalar a_x[], PetscReal t, PetscReal u_tShift, const PetscReal x[], const PetscReal n[],
                          PetscInt numConstants, const PetscScalar constants[], PetscScalar g0[])
{
  if (Penetration(dim, u, x, constants) <= 0.0) return;
  for (PetscInt c = 0; c < dim; ++c)
    for (PetscInt e = 0; e < dim; ++e) g0[c * dim + e] = constants[CONST_PENALTY] * constants[CONST_NORMAL_X + c] * constants[CONST_NORMAL_X + e];
}

/* (1/2eps) [u_n - g]_+^2, the penalty energy density, in the first component: summed over the
   entries of the local boundary residual it gives the integral (the basis is a partition of unity). */
static void f0_bd_penalty_energy(PetscInt dim, PetscInt Nf, PetscInt NfAux, const PetscInt uOff[], const PetscInt uOff_x[], const PetscScalar u[],
                                 const PetscScalar u_t[], const PetscScalar u_x[], const PetscInt aOff[], const PetscInt aOff_x[],
                                 const PetscScalar a[], const PetscScalar a_t[], const PetscScalar a_x[], PetscReal t, const PetscReal x[],
                                 const PetscReal n[], PetscInt numConstants, const PetscScalar constants[], PetscScalar f0[])
{
  const PetscReal d = Penetration(dim, u, x, constants);

  for (PetscInt c = 1; c < dim; ++c) f0[c] = 0.0;
  f0[0] = d > 0.0 ? 0.5 * constants[CONST_PENALTY] * d * d : 0.0;
}

enum { PENALTY_PART_TERM, PENALTY_PART_ENERGY }; /* parts of the penalty weak form */

PetscErrorCode PenaltySetUp(DM dm, AppCtx *user)
{
  PetscFunctionBeginUser;
  PetscCall(PetscWeakFormCreate(PetscObjectComm((PetscObject)dm), &user->prob.wf_penalty));
  PetscCall(DMCreateLocalVector(dm, &user->prob.loc_bc));
  PetscCall(VecZeroEntries(user->prob.loc_bc));
  PetscCall(DMPlexInsertBoundaryValues(dm, PETSC_TRUE, user->prob.loc_bc, 0.0, NULL, NULL, NULL));
  PetscCall(PetscWeakFormSetNumFields(user->prob.wf_penalty, 1));
  PetscCall(PetscWeakFormSetIndexBdResidual(user->prob.wf_penalty, user->prob.face_sets, user->scene.contact_id, 0, PENALTY_PART_TERM, 0,
                                            f0_bd_penalty, 0, NULL));
  PetscCall(PetscWeakFormSetIndexBdResidual(user->prob.wf_penalty, user->prob.face_sets, user->scene.contact_id, 0, PENALTY_PART_ENERGY, 0,
                                            f0_bd_penalty_energy, 0, NULL));
  PetscCall(PetscWeakFormSetIndexBdJacobian(user->prob.wf_penalty, user->prob.face_sets, user->scene.contact_id, 0, 0, PENALTY_PART_TERM, 0,
                                            g0_bd_penalty, 0, NULL, 0, NULL, 0, NULL));
  if (user->opt.contact.quadrature == PENALTY_QUADRATURE_NODAL) {
    PetscInt bad = 0, nbad;

    for (PetscInt i = 0; i < user->prob.cset.n; ++i) bad += user->prob.cset.weight[i] <= 0.0;
    PetscCall(MPIU_Allreduce(&bad, &nbad, 1, MPIU_INT, MPI_SUM, PetscObjectComm((PetscObject)dm)));
    PetscCheck(!nbad, PetscObjectComm((PetscObject)dm), PETSC_ERR_USER_INPUT,
               "-penalty_quadrature nodal needs a positive lumped boundary mass at every node of Gamma_C; %" PetscInt_FMT
               " nodes have none (use degree 1 or gauss)",
               nbad);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Local solution with the Dirichlet values inserted, for the boundary integrals. The values come from user->prob.loc_bc,
   filled once in PenaltySetUp(): inserting them is a projection over Gamma_D that cost more than the whole boundary
   integral (0.1 s per call at 512x512). */
static PetscErrorCode GetLocalSolution(DM dm, AppCtx *user, Vec X, Vec *locX)
{
  PetscFunctionBeginUser;
  PetscCall(DMGetLocalVector(dm, locX));
  PetscCall(VecCopy(user->prob.loc_bc, *locX));
  PetscCall(DMGlobalToLocal(dm, X, INSERT_VALUES, *locX));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* locF = the local boundary residual of one part of the penalty weak form (Gauss rule). */
static PetscErrorCode ComputePenaltyPartLocal(DM dm, AppCtx *user, PetscInt part, Vec X, Vec locF)
{
  PetscFormKey key;
  Vec          locX;

  PetscFunctionBeginUser;
  key.label = user->prob.face_sets;
  key.value = user->scene.contact_id;
  key.field = 0;
  key.part  = part;
  PetscCall(GetLocalSolution(dm, user, X, &locX));
  PetscCall(VecZeroEntries(locF));
  PetscCall(CompatComputeBdResidualSingle(dm, user->prob.wf_penalty, key, locX, locF));
  PetscCall(DMRestoreLocalVector(dm, &locX));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PenaltyAddResidual(DM dm, AppCtx *user, Vec X, Vec F)
{
  const PetscReal kappa = 1.0 / user->prob.eps;
  PetscInt        dim;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  if (user->opt.contact.quadrature == PENALTY_QUADRATURE_GAUSS) {
    Vec locF;

    PetscCall(DMGetLocalVector(dm, &locF));
    PetscCall(ComputePenaltyPartLocal(dm, user, PENALTY_PART_TERM, X, locF));
    PetscCall(DMLocalToGlobal(dm, locF, ADD_VALUES, F));
    PetscCall(DMRestoreLocalVector(dm, &locF));
  } else {
    const PetscScalar *x;
    PetscScalar       *f;

    PetscCall(VecGetArrayRead(X, &x));
    PetscCall(VecGetArray(F, &f));
    for (PetscInt i = 0; i < user->prob.cset.n; ++i) {
      const PetscReal d = ContactNodePenetration(user, dim, i, x);
      if (d <= 0.0) continue;
      for (PetscInt c = 0; c < dim; ++c)
        f[user->prob.cset.global_off[i] + c] += kappa * user->prob.cset.weight[i] * d * user->scene.obstacle_normal[c];
    }
    PetscCall(VecRestoreArray(F, &f));
    PetscCall(VecRestoreArrayRead(X, &x));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Adds the penalty Jacobian to J (ADD_VALUES); the caller assembles J. */
PetscErrorCode PenaltyAddJacobian(DM dm, AppCtx *user, Vec X, Mat J)
{
  const PetscReal kappa = 1.0 / user->prob.eps;
  PetscInt        dim;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  if (user->opt.contact.quadrature == PENALTY_QUADRATURE_GAUSS) {
    Vec locX;

    PetscCall(GetLocalSolution(dm, user, X, &locX));
    PetscCall(CompatComputeBdJacobianSingle(dm, user->prob.wf_penalty, user->prob.face_sets, 1, &user->scene.contact_id, locX, J));
    PetscCall(DMRestoreLocalVector(dm, &locX));
  } else {
    const PetscScalar *x;
    PetscInt           rstart, rows[3];
    PetscScalar        block[9];

    PetscCall(MatGetOwnershipRange(J, &rstart, NULL));
    PetscCall(VecGetArrayRead(X, &x));
    for (PetscInt i = 0; i < user->prob.cset.n; ++i) {
      if (ContactNodePenetration(user, dim, i, x) <= 0.0) continue;
      for (PetscInt c = 0; c < dim; ++c) {
        rows[c] = rstart + user->prob.cset.global_off[i] + c;
        for (PetscInt e = 0; e < dim; ++e)
          block[c * dim + e] = kappa * user->prob.cset.weight[i] * user->scene.obstacle_normal[c] * user->scene.obstacle_normal[e];
      }
      PetscCall(MatSetValues(J, dim, rows, dim, rows, block, ADD_VALUES));
    }
    PetscCall(VecRestoreArrayRead(X, &x));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* (1/2eps) int [u_n - g]_+^2 with the quadrature of the penalty term. */
PetscErrorCode PenaltyEnergy(DM dm, AppCtx *user, Vec X, PetscReal *energy)
{
  PetscInt dim;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  *energy = 0.0;
  if (user->opt.contact.method != CONTACT_PENALTY) PetscFunctionReturn(PETSC_SUCCESS);
  if (user->opt.contact.quadrature == PENALTY_QUADRATURE_GAUSS) {
    Vec         locE;
    PetscScalar e;

    /* each face is integrated on one rank only, so the local sums add up to the integral */
    PetscCall(DMGetLocalVector(dm, &locE));
    PetscCall(ComputePenaltyPartLocal(dm, user, PENALTY_PART_ENERGY, X, locE));
    PetscCall(VecSum(locE, &e));
    PetscCall(DMRestoreLocalVector(dm, &locE));
    PetscCall(MPIU_Allreduce(&e, energy, 1, MPIU_SCALAR, MPIU_SUM, PetscObjectComm((PetscObject)dm)));
  } else {
    const PetscScalar *x;
    PetscReal          e = 0.0;

    PetscCall(VecGetArrayRead(X, &x));
    for (PetscInt i = 0; i < user->prob.cset.n; ++i) {
      const PetscReal d = ContactNodePenetration(user, dim, i, x);
      if (d > 0.0) e += 0.5 / user->prob.eps * user->prob.cset.weight[i] * d * d;
    }
    PetscCall(VecRestoreArrayRead(X, &x));
    PetscCall(MPIU_Allreduce(&e, energy, 1, MPIU_REAL, MPIU_SUM, PetscObjectComm((PetscObject)dm)));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}
