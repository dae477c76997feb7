/* Contact quantities after the solve: nodal pressure, penetration, total force, energy. */
#include "physics.h"

/* The contact quantities of the run (ContactPostProcess(), include/contact.h: the force, pressure and active set from the
   force the rule exerts), the supports' reactions, and the energy 1/2 a(u,u) - L(u) + the contact term's energy, with
   K the bulk operator (exact for homogeneous Dirichlet data on the free unknowns). */
PetscErrorCode PostprocessContact(DM dm, AppCtx *user, Vec u)
{
  RunStats     *st = &user->rec.stats;
  ContactResult res;
  Vec           R;
  PetscScalar   uKu, r0u;

  PetscFunctionBeginUser;
  PetscCall(VecDuplicate(u, &R));
  PetscCall(ContactBulkMult(user->contact, user->prob.K, u, R)); /* K u, not the penalty Jacobian times u */
  PetscCall(VecDot(u, R, &uKu));
  PetscCall(VecDot(u, user->prob.r0, &r0u));
  PetscCall(VecAXPY(R, 1.0, user->prob.r0)); /* the bulk residual K u + r0, whose contact rows are the reactions */
  PetscCall(ContactPostProcess(user->contact, dm, R, u, user->prob.displacement_scale, &res));
  PetscCall(VecDestroy(&R));
  for (PetscInt c = 0; c < 3; ++c) st->contact_force_vector[c] = res.force_vector[c];
  PetscCall(BoundaryComputeReactions(dm, user, u, st->reaction));
  st->max_penetration = res.max_penetration;
  st->contact_force   = res.force;
  st->active_vertices = res.active_vertices;
  st->energy          = 0.5 * PetscRealPart(uKu) + PetscRealPart(r0u) + res.energy;
  {
    const ContactSet *cs;
    PetscReal         pmax = 0.0;

    PetscCall(ContactGetSet(user->contact, &cs));
    for (PetscInt i = 0; i < cs->n; ++i) pmax = PetscMax(pmax, cs->pressure[i]);
    PetscCall(MPIU_Allreduce(&pmax, &st->pressure_max, 1, MPIU_REAL, MPIU_MAX, PetscObjectComm((PetscObject)dm)));
  }
  PetscCall(PostprocessContactSize(dm, user, u, &st->contact_size, &st->contact_size_band));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The quantities users read, as PostprocessContact() left them in the record. */
void PostprocessGetQuantities(const AppCtx *user, Quantities *q)
{
  const RunStats *st = &user->rec.stats;

  for (PetscInt c = 0; c < 3; ++c) q->force[c] = st->contact_force_vector[c];
  q->pressure_max      = st->pressure_max;
  q->contact_size      = st->contact_size;
  q->contact_size_band = st->contact_size_band;
  q->penetration_max   = st->max_penetration;
  q->energy            = st->energy;
  for (PetscInt i = 0; i < BOUNDARY_MAX; ++i)
    for (PetscInt c = 0; c < 3; ++c) q->reaction[i][c] = st->reaction[i][c];
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
