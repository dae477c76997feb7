/* Physics: linear elasticity, the contact set, the penalty term, the SNESVI bounds, the contact quantities after the solve (src/physics/). */
#pragma once
#include "signorini.h"

/* elasticity.c */
PetscErrorCode ElasticityGetOptions(MPI_Comm comm, Material *mat, PetscInt *degree);
PetscErrorCode ElasticitySetUpDiscretization(DM dm, AppCtx *user);
PetscErrorCode ElasticityUpdateConstants(DM dm, AppCtx *user);
PetscErrorCode ElasticityRigidBodyModesP1(DM dm, MatNullSpace *nullspace);

/* contact_options.c, contact_set.c */
PetscErrorCode ContactGetOptions(MPI_Comm comm, ContactOptions *opts);
PetscErrorCode ContactOptionsDestroy(ContactOptions *opts);
PetscErrorCode ContactComputeEps(AppCtx *user);
PetscReal      ContactPenaltyModulus(const AppCtx *user);
PetscErrorCode ContactSetCreate(DM dm, AppCtx *user, ContactSet *cs);
PetscErrorCode ContactSetDestroy(ContactSet *cs);
PetscErrorCode ContactCountActive(AppCtx *user, Vec X, PetscBool update, PetscInt *active, PetscInt *entered, PetscInt *left);

/* Penetration u_n - g of contact node i, from the owned part x[] of a global vector. */
static inline PetscReal ContactNodePenetration(const AppCtx *user, PetscInt dim, PetscInt i, const PetscScalar x[])
{
  PetscReal un = 0.0;

  for (PetscInt c = 0; c < dim; ++c) un += PetscRealPart(x[user->prob.cset.global_off[i] + c]) * user->scene.obstacle_normal[c];
  return un - user->prob.cset.gap[i];
}

/* penalty.c */
PetscErrorCode PenaltySetUp(DM dm, AppCtx *user);
PetscErrorCode PenaltyAddResidual(DM dm, AppCtx *user, Vec X, Vec F);
PetscErrorCode PenaltyAddJacobian(DM dm, AppCtx *user, Vec X, Mat J);
PetscErrorCode PenaltyEnergy(DM dm, AppCtx *user, Vec X, PetscReal *energy);

/* vi_bounds.c */
PetscErrorCode VICreateBounds(DM dm, AppCtx *user);

/* postprocess.c */
PetscErrorCode PostprocessContact(DM dm, AppCtx *user, Vec u);

/* elasticity.c: sigma(grad u) = lambda tr(eps) I + 2 mu eps, grad[i*dim+j] = du_i/dx_j */
void ElasticStress(PetscInt dim, const Material *mat, const PetscReal grad[], PetscReal sigma[]);
