/* Contact quantities after the solve: nodal pressure, penetration, total force, energy. */
#include "physics.h"

/* The contact outputs, every one from the force the rule exerts, for every method, rule and obstacle:
   - the reaction of the obstacle at node i is -R_i . n with R = K u + r0 the bulk residual: the nodal contact force
     (the penalty term's at a converged penalty solve, the multiplier of SNESVI's bound);
   - the pressure is that reaction over the lumped boundary mass (the area the node stands for), where the contact acts
     (penalty: where the rule's force is positive, exactly zero elsewhere; SNESVI: everywhere), so that the sum of
     pressure times contact_area is the contact force up to the reactions of the nodes where nothing acts, round-off
     with a direct solver, the linear solver's tolerance with an iterative one. With the Gauss rule it is the face integral of
     (1/eps)[u_n - g]_+ against the node's basis function over that of the basis function: a curved obstacle touching
     the faces between their vertices has a pressure where it pushes, not the nodal penalty law's zero;
   - the active vertices are those where the rule acts (the penalty term's nodal force is positive: a Gauss point of
     one of its faces penetrates, or the node itself with the nodal rule; on the bound with SNESVI);
   - the penetration is the largest of the nodes' and the rule's points' (PostprocessPenetration() adds those of the
     finer quadrature of the error norms). */
PetscErrorCode PostprocessContact(DM dm, AppCtx *user, Vec u)
{
  MPI_Comm           comm = PetscObjectComm((PetscObject)dm);
  ContactSet        *cs   = &user->prob.cset;
  Vec                R;
  const PetscScalar *x, *r;
  PetscInt           dim;
  PetscReal          local[5] = {0.0, 0.0, 0.0, 0.0, 0.0}, global[5], uKu, r0u, penalty_energy, dgauss = -PETSC_MAX_REAL;
  PetscBool         *acts;
  PetscInt           nacts = 0;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(PetscMalloc1(cs->n + 1, &acts));
  for (PetscInt i = 0; i < cs->n; ++i) acts[i] = (PetscBool)(user->opt.contact.method == CONTACT_VI);
  if (user->opt.contact.method == CONTACT_PENALTY) PetscCall(PenaltyRuleActs(dm, user, u, acts, &dgauss));
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
    cs->pressure[i] = acts[i] && cs->weight[i] > 0.0 ? reaction / cs->weight[i] : 0.0;
    nacts += acts[i] && cs->is_vertex[i];
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
  if (user->opt.contact.method == CONTACT_PENALTY)
    PetscCall(MPIU_Allreduce(&nacts, &user->rec.stats.active_vertices, 1, MPIU_INT, MPI_SUM, comm));
  else
    PetscCall(ContactCountActive(user, u, PETSC_FALSE, &user->rec.stats.active_vertices, NULL, NULL));
  user->rec.stats.max_penetration = PetscMax(user->rec.stats.max_penetration, dgauss);
  PetscCall(PetscFree(acts));
  PetscCall(PenaltyEnergy(dm, user, u, &penalty_energy));
  if (user->opt.assembly_check) PetscCall(PenaltyCheckClosedForm(dm, user, u));
  /* 1/2 a(u,u) - L(u) on the free unknowns (exact for homogeneous Dirichlet data) + penalty energy */
  user->rec.stats.energy = 0.5 * uKu + r0u + penalty_energy;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The largest penetration of the run: that of the nodes and the rule's points (PostprocessContact()) and that of the
   finer quadrature of the error norms (ErrorNormsCompute()), which a curved obstacle may reach between them. */
PetscErrorCode PostprocessPenetration(AppCtx *user)
{
  PetscFunctionBeginUser;
  if (!PetscIsNanReal(user->rec.errors.penetration_max))
    user->rec.stats.max_penetration = PetscMax(user->rec.stats.max_penetration, user->rec.errors.penetration_max);
  PetscFunctionReturn(PETSC_SUCCESS);
}
