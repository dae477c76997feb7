/* Contact quantities after the solve: nodal pressure, penetration, total force, energy. */
#include "physics.h"
#include "discretization.h"
#include "app.h"

/* The potential energy of the Dirichlet lift u_D (loc_bc: the Dirichlet values, zero on the free unknowns),
     J(u_D) = 1/2 a(u_D, u_D) - L(u_D) = u_D . r0_loc - 1/2 u_D . A u_D,
   since r0_loc = A u_D - b holds every row (the fixed ones too) of the residual at u_D (SolverAssembleLoad(): the bulk
   and the surface loads of BoundaryAddLoads()); a scene's load in weak form is not in r0_loc, and WeakDataAddToResidual()
   gives its L(u_D), weak_lift. Computed once per load state, by SolverAssembleLoad(). Both vectors hold this rank's cells only, so that the local dot
   products add up over the ranks to the sums over the cells. A u_D by the mesh's assembly (AssemblyLiftStiffness()). Zero when the Dirichlet
   data are. The problem's loc_bc, loc_r0 and assembly, in the material. */
PetscErrorCode PostprocessLiftEnergy(DM dm, const Material *mat, const Problem *prob, PetscReal weak_lift, PetscReal *energy)
{
  Vec         locA;
  PetscReal   ud_max, local[2], global[2];
  PetscScalar dot;

  PetscFunctionBeginUser;
  *energy = 0.0;
  PetscCall(VecNorm(prob->loc_bc, NORM_INFINITY, &ud_max));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &ud_max, 1, MPIU_REAL, MPIU_MAX, PetscObjectComm((PetscObject)dm)));
  if (ud_max == 0.0) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(DMGetLocalVector(dm, &locA));
  PetscCall(AssemblyLiftStiffness(dm, prob->assembly, mat, prob->loc_bc, locA)); /* A u_D */
  PetscCall(VecDot(prob->loc_bc, prob->loc_r0, &dot));
  local[0] = PetscRealPart(dot);
  PetscCall(VecDot(prob->loc_bc, locA, &dot));
  local[1] = PetscRealPart(dot);
  PetscCall(DMRestoreLocalVector(dm, &locA));
  PetscCall(MPIU_Allreduce(local, global, 2, MPIU_REAL, MPIU_SUM, PetscObjectComm((PetscObject)dm)));
  *energy = global[0] - 0.5 * global[1] - weak_lift;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The contact quantities of the run (ContactPostProcess(), include/contact.h: the force, pressure and active set from the
   force the rule exerts), the supports' reactions, and the potential energy of u_h = w + u_D (w on the free unknowns),
     J(u_h) = 1/2 a(u_h, u_h) - L(u_h) + the contact term's energy,
   with 1/2 a(u_h, u_h) - L(u_h) = 1/2 w.K w + w.r0 + J(u_D): K the bulk operator on the free unknowns and r0 = A u_D - b
   there, so that w.r0 = a(u_D, w) - L(w). Of the solution u of the problem prob (K, r0, the scales) with the contact,
   the boundary conditions bcs in the material; into sq. */
PetscErrorCode PostprocessContact(DM dm, Contact contact, const Problem *prob, const BoundarySet *bcs, const Material *mat, Vec u,
                                  SolutionQuantities *sq)
{
  ContactResult res;
  Vec           R;
  PetscScalar   uKu, r0u;

  PetscFunctionBeginUser;
  PetscCall(VecDuplicate(u, &R));
  PetscCall(ContactBulkMult(contact, prob->K, u, R)); /* K u, not the penalty Jacobian times u */
  PetscCall(VecDot(u, R, &uKu));
  PetscCall(VecDot(u, prob->r0, &r0u));
  PetscCall(VecAXPY(R, 1.0, prob->r0)); /* the bulk residual K u + r0, whose contact rows are the reactions */
  PetscCall(ContactPostProcess(contact, dm, R, u, prob->displacement_scale, &res));
  PetscCall(VecDestroy(&R));
  for (PetscInt c = 0; c < 3; ++c) sq->q.force[c] = res.force_vector[c];
  PetscCall(BoundaryComputeReactions(dm, bcs, mat, prob, u, sq->q.reaction));
  sq->q.penetration_max = res.max_penetration;
  sq->contact_force     = res.force;
  sq->active_vertices   = res.active_vertices;
  sq->q.energy          = 0.5 * PetscRealPart(uKu) + PetscRealPart(r0u) + prob->lift_energy + res.energy;
  {
    const ContactSet *cs;
    PetscReal         pmax = 0.0;

    PetscCall(ContactGetSet(contact, &cs));
    for (PetscInt i = 0; i < cs->n; ++i) pmax = PetscMax(pmax, cs->pressure[i]);
    PetscCall(MPIU_Allreduce(&pmax, &sq->q.pressure_max, 1, MPIU_REAL, MPIU_MAX, PetscObjectComm((PetscObject)dm)));
  }
  PetscCall(PostprocessContactSize(dm, contact, bcs, mat, u, &sq->q.contact_size, &sq->q.contact_size_band));
  PetscCall(PostprocessPressureStep(dm, contact, bcs, sq->q.pressure_max, &sq->q.pressure_max_step));
  PetscCall(PostprocessPressurePeak(dm, contact, sq->q.pressure_max, sq->q.pressure_max_step, &sq->q.pressure_peak, &sq->q.pressure_peak_resolution));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The contact force's magnitude, |F| over its dim components: the value of the force that -bars and -accuracy bar. */
PetscReal PostprocessForceMagnitude(const Quantities *q, PetscInt dim)
{
  PetscReal f = 0.0;

  for (PetscInt d = 0; d < dim; ++d) f += PetscSqr(q->force[d]);
  return PetscSqrtReal(f);
}

/* The largest penetration of the run: that of the nodes and the rule's points (PostprocessContact()) and that of the
   finer quadrature of the error norms (ErrorNormsCompute(), errors), which a curved obstacle may reach between them;
   into sq. */
PetscErrorCode PostprocessPenetration(const ErrorNorms *errors, SolutionQuantities *sq)
{
  PetscFunctionBeginUser;
  if (!PetscIsNanReal(errors->penetration_max) && errors->penetration_max > sq->q.penetration_max) {
    sq->q.penetration_max   = errors->penetration_max;
    sq->penetration_between = PETSC_TRUE;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The solution's line of the summary: where the rule acts, the largest penetration (and where the finer quadrature
   found it), the contact force and the energy. */
PetscErrorCode PostprocessView(MPI_Comm comm, const SolutionQuantities *sq)
{
  PetscFunctionBeginUser;
  PetscCall(PetscPrintf(comm, "  contact: %" PetscInt_FMT " active vertices, max penetration %g%s, contact force %g, energy %.10g\n",
                        sq->active_vertices, (double)sq->q.penetration_max,
                        sq->penetration_between
                            ? " (between the nodes and the rule's points, where a curved obstacle cuts the straight faces by about "
                              "h^2/8R and a cone's apex reaches between them, which eps does not reduce)"
                            : "",
                        (double)sq->contact_force, (double)sq->q.energy));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The solution's quantities in /run (PostprocessContact()): where the rule acts, the largest penetration, the contact
   force and its vector, the energy, the largest pressure with its step and its recovered peak, the contact zone's size
   with its band, and the force of each clamp's and slip's support on the body (reaction_clamp_3_x, ...). */
PetscErrorCode PostprocessWrite(const SolutionQuantities *s, const BoundarySet *bcs, PetscInt dim, PetscViewer v)
{
  PetscFunctionBeginUser;
  PetscCall(RunAttrInt(v, s->active_vertices, "active_vertices"));
  PetscCall(RunAttrReal(v, s->q.penetration_max, "max_penetration"));
  PetscCall(RunAttrReal(v, s->contact_force, "contact_force"));
  PetscCall(RunAttrReal(v, s->q.energy, "energy"));
  PetscCall(RunAttrReal(v, s->q.pressure_max, "pressure_max"));                         /* the largest nodal contact pressure */
  PetscCall(RunAttrReal(v, s->q.contact_size, "contact_size"));                         /* the contact zone's width (2D) or area (3D) */
  PetscCall(RunAttrReal(v, s->q.contact_size_band, "contact_size_band"));               /* the one-cell strip along its edge */
  PetscCall(RunAttrReal(v, s->q.pressure_max_step, "pressure_max_step"));               /* the largest pressure's change to its neighbours */
  PetscCall(RunAttrReal(v, s->q.pressure_peak, "pressure_peak"));                       /* the largest pressure recovered by a local fit */
  PetscCall(RunAttrReal(v, s->q.pressure_peak_resolution, "pressure_peak_resolution")); /*   and its resolution */
  for (PetscInt c = 0; c < dim; ++c) PetscCall(RunAttrReal(v, s->q.force[c], "contact_force_%c", "xyz"[c]));
  for (PetscInt i = 0; i < bcs->n; ++i) {
    const BoundaryCondition *bc = &bcs->bc[i];

    if (bc->kind != BC_CLAMP && bc->kind != BC_SLIP) continue;
    for (PetscInt c = 0; c < dim; ++c)
      PetscCall(RunAttrReal(v, s->q.reaction[i][c], "reaction_%s_%s_%c", BoundaryKinds[bc->kind], bc->token, "xyz"[c]));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}
