/* Contact quantities after the solve: nodal pressure, penetration, total force, energy. */
#include "physics.h"

/* The reaction of the foundation at node i is -R_i . n with R = K u + r0 the bulk residual;
   the pressure is the penalty law (penalty) or the reaction over the lumped boundary mass (vi). */
PetscErrorCode PostprocessContact(DM dm, AppCtx *user, Vec u)
{
  MPI_Comm           comm = PetscObjectComm((PetscObject)dm);
  ContactSet        *cs   = &user->prob.cset;
  Vec                R;
  const PetscScalar *x, *r;
  PetscInt           dim;
  PetscReal          local[5] = {0.0, 0.0, 0.0, 0.0, 0.0}, global[5], uKu, r0u, penalty_energy;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(VecDuplicate(u, &R));
  PetscCall(PenaltyBulkMult(user, u, R)); /* K u, not the penalty Jacobian times u */
  PetscCall(VecDot(u, R, &uKu));
  PetscCall(VecDot(u, user->prob.r0, &r0u));
  PetscCall(VecAXPY(R, 1.0, user->prob.r0));
  PetscCall(VecGetArrayRead(u, &x));
  PetscCall(VecGetArrayRead(R, &r));
  for (PetscInt i = 0; i < cs->n; ++i) {
    const PetscReal d        = ContactNodePenetration(cs, dim, i, x);
    PetscReal       reaction = 0.0; /* along the free components: a fixed one takes its reaction from its boundary condition */

    for (PetscInt c = 0; c < dim; ++c)
      if (cs->dof[i * dim + c] >= 0) {
        reaction -= PetscRealPart(r[cs->dof[i * dim + c]]) * cs->normal[i * dim + c];
        local[2 + c] += PetscRealPart(r[cs->dof[i * dim + c]]); /* the obstacle's force on the body: R = K u + r0 */
      }
    cs->reaction[i] = reaction;
    switch (user->opt.contact.method) {
      case CONTACT_PENALTY:
        cs->pressure[i] = d > 0.0 ? d / ContactNodeEps(cs, user->prob.eps, i) : 0.0;
        break;
      case CONTACT_VI:
        cs->pressure[i] = cs->weight[i] > 0.0 ? reaction / cs->weight[i] : 0.0;
        break;
      case CONTACT_NONE:
        cs->pressure[i] = 0.0;
        break;
    }
    local[0] = PetscMax(local[0], d);
    local[1] += reaction;
  }
  PetscCall(VecRestoreArrayRead(R, &r));
  PetscCall(VecRestoreArrayRead(u, &x));
  PetscCall(VecDestroy(&R));
  PetscCall(MPIU_Allreduce(&local[0], &global[0], 1, MPIU_REAL, MPIU_MAX, comm));
  PetscCall(MPIU_Allreduce(&local[1], &global[1], 4, MPIU_REAL, MPIU_SUM, comm));
  for (PetscInt c = 0; c < 3; ++c) user->rec.stats.contact_force_vector[c] = global[2 + c];
  PetscCall(BoundaryComputeReactions(dm, user, u, user->rec.stats.reaction));
  user->rec.stats.max_penetration = global[0];
  user->rec.stats.contact_force   = global[1];
  PetscCall(ContactCountActive(user, u, PETSC_FALSE, &user->rec.stats.active_vertices, NULL, NULL));
  PetscCall(PenaltyEnergy(dm, user, u, &penalty_energy));
  if (user->opt.assembly_check) PetscCall(PenaltyCheckClosedForm(dm, user, u));
  /* 1/2 a(u,u) - L(u) on the free unknowns (exact for homogeneous Dirichlet data) + penalty energy */
  user->rec.stats.energy = 0.5 * uKu + r0u + penalty_energy;
  PetscFunctionReturn(PETSC_SUCCESS);
}
