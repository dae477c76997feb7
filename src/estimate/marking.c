/* Doerfler's marking (SIAM J. Numer. Anal. 33, 1996): the fewest cells whose squared indicators hold the fraction theta
   of the estimate's square, the cells with the largest indicators first. In parallel the cells are not sorted: the
   set is {T : eta_T >= t} with t the largest threshold whose set holds that fraction, found by bisection on t with one
   reduction per step, so that every partition marks the same cells (to the indicators' round-off). The cells are added
   to *marked, created if NULL; *nmarked counts them over all ranks. */
#include "contact.h"
#include "estimate.h"

#define MARK_BISECTIONS 60 /* halvings of [0, max eta_T]: t to 1e-18 of the largest indicator */

/* Sum of eta_T^2 over the cells with eta_T >= t, over all ranks. */
static PetscErrorCode SumAbove(MPI_Comm comm, const ErrorEstimate *est, PetscReal t, PetscReal *sum)
{
  PetscReal local = 0.0;

  PetscFunctionBeginUser;
  for (PetscInt c = 0; c < est->ncells; ++c)
    if (est->cell[c] >= t) local += est->cell[c] * est->cell[c];
  PetscCall(MPIU_Allreduce(&local, sum, 1, MPIU_REAL, MPIU_SUM, comm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode EstimateMark(DM dm, const ErrorEstimate *est, PetscReal theta, DMLabel *marked, PetscInt *nmarked)
{
  MPI_Comm  comm = PetscObjectComm((PetscObject)dm);
  PetscReal total, emax = 0.0, lo = 0.0, hi, sum;
  PetscInt  cStart, cEnd, local   = 0;

  PetscFunctionBeginUser;
  PetscCheck(est->computed && est->cell, comm, PETSC_ERR_ARG_WRONGSTATE, "marking needs the cells' indicators of the error estimate");
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  PetscCheck(cEnd - cStart == est->ncells, comm, PETSC_ERR_ARG_WRONGSTATE, "the estimate's cells are not the mesh's");
  for (PetscInt c = 0; c < est->ncells; ++c) emax = PetscMax(emax, est->cell[c]);
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &emax, 1, MPIU_REAL, MPIU_MAX, comm));
  PetscCall(SumAbove(comm, est, 0.0, &total));
  hi = emax; /* SumAbove(lo) >= theta total always; SumAbove(hi) holds at least the largest cell */
  PetscCall(SumAbove(comm, est, hi, &sum));
  if (sum < theta * total)
    for (PetscInt k = 0; k < MARK_BISECTIONS; ++k) {
      const PetscReal mid = 0.5 * (lo + hi);

      PetscCall(SumAbove(comm, est, mid, &sum));
      if (sum >= theta * total)
        lo = mid;
      else
        hi = mid;
    }
  else
    lo = hi;
  if (!*marked) PetscCall(DMLabelCreate(PETSC_COMM_SELF, "adapt", marked));
  for (PetscInt c = 0; c < est->ncells; ++c)
    if (est->cell[c] >= lo && est->cell[c] > 0.0) {
      PetscCall(DMLabelSetValue(*marked, cStart + c, DM_ADAPT_REFINE));
      ++local;
    }
  PetscCall(MPIU_Allreduce(&local, nmarked, 1, MPIU_INT, MPIU_SUM, comm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The cells around each contact node the mesh does not see (ContactUnseenNodes(): it penetrates the obstacle while the
   rule exerts no force on it, as on a mesh whose Gauss points all miss the contact zone, where the solution and the
   estimate are zero) are marked too (added to *marked, created if NULL and there is one), so that the cycles refine
   until the rule sees the contact; *nunseen counts the nodes over all ranks, *force is the force the penalty law
   would put on them. */
PetscErrorCode EstimateMarkUnseenContact(DM dm, Contact contact, Vec u, DMLabel *marked, PetscInt *nunseen, PetscReal *force)
{
  const ContactSet *cs;
  PetscBool        *unseen;
  PetscInt          cStart, cEnd;

  PetscFunctionBeginUser;
  PetscCall(ContactGetSet(contact, &cs));
  PetscCall(PetscMalloc1(cs->n + 1, &unseen));
  PetscCall(ContactUnseenNodes(contact, u, unseen, nunseen, force));
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  for (PetscInt i = 0; i < cs->n; ++i) {
    PetscInt *star = NULL, nstar;

    if (!unseen[i]) continue;
    if (!*marked) PetscCall(DMLabelCreate(PETSC_COMM_SELF, "adapt", marked));
    PetscCall(DMPlexGetTransitiveClosure(dm, cs->point[i], PETSC_FALSE, &nstar, &star));
    for (PetscInt k = 0; k < nstar; ++k)
      if (star[2 * k] >= cStart && star[2 * k] < cEnd) PetscCall(DMLabelSetValue(*marked, star[2 * k], DM_ADAPT_REFINE));
    PetscCall(DMPlexRestoreTransitiveClosure(dm, cs->point[i], PETSC_FALSE, &nstar, &star));
  }
  PetscCall(PetscFree(unseen));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The cells along the contact zone's edge: the cells of the faces of Gamma_C that the edge crosses, the one-cell band
   that floors the zone's size's bar (src/estimate/cycle_bars.c, src/physics/contact_zone.c), the faces faces[0..n) that
   PostprocessContactEdgeFaces() finds. Doerfler's marking on the
   energy-norm indicators refines them only where the energy's error is, while the size's bar cannot fall below the
   band: marking them too halves the band at each cycle (-adapt_mark_edge). Added to *marked, created if NULL and there
   is one; *nmarked counts the cells over all ranks. */
PetscErrorCode EstimateMarkContactEdge(DM dm, PetscInt n, const PetscInt faces[], DMLabel *marked, PetscInt *nmarked)
{
  PetscInt local = 0;

  PetscFunctionBeginUser;
  for (PetscInt i = 0; i < n; ++i) {
    const PetscInt *support;

    if (!*marked) PetscCall(DMLabelCreate(PETSC_COMM_SELF, "adapt", marked));
    PetscCall(DMPlexGetSupport(dm, faces[i], &support)); /* one cell: a boundary face */
    PetscCall(DMLabelSetValue(*marked, support[0], DM_ADAPT_REFINE));
    ++local;
  }
  PetscCall(MPIU_Allreduce(&local, nmarked, 1, MPIU_INT, MPIU_SUM, PetscObjectComm((PetscObject)dm)));
  PetscFunctionReturn(PETSC_SUCCESS);
}
