/* -contact_penetration_tol d: the penalty run ends when the largest penetration (over the contact nodes and the
   points of the rule: the output's max_penetration) is at most d, a length, as engineers state it (ANSYS's FTOLN, NX's
   TMAX, MOOSE's al_penetration_tolerance) instead of an eps. The penetration is the one the contact treatment controls:
   at the contact nodes and at the rule's points (ContactMaxPenetration(); /run penetration_tol_measured). Between
   them a curved obstacle cuts the straight faces by up to about h^2 / 8R whatever eps is (the output's
   max_penetration, measured with the finer quadrature of the error norms, includes it): that part is the mesh's,
   which only refinement reduces.
   The penalty law p = (1/eps)[u . n - g]_+ makes the penetration at a point eps times the pressure there, and the
   pressure tends to the exact contact's as eps -> 0 (the discrete penalty solution tends to SNESVI's linearly in eps,
   docs/verification.md). So after a solve at eps whose largest penetration d_max exceeds d,
       eps <- eps * PENETRATION_TOL_AIM * d / d_max
   predicts a largest penetration of PENETRATION_TOL_AIM d; the aim below 1 is the margin for the pressure's growth as
   eps falls (a wider zone of smaller penetration). eps falls by at most -penalty_continuation_factor (1e-2) a solve,
   as in the continuation of a solve from zero (SolverSolve()): a warm start 1e5 times stiffer, the 3D sphere
   indenter's from eps = h to 1e-5 h in one solve, did not converge in 50 Newton steps. Each solve starts from the last solution, from the third on
   from the secant of the last two in eps (the eps sweep's start: u(eps) is nearly linear in eps once the penalty dominates); a warm solve that fails
   (the 3D sphere indenter's from eps = 1e-2 h to 2.7e-4 h stalled at a kink of the penalty, the critical-point line search's steps shrinking to
   nothing, as force control's did) is solved again from zero, as a direct run. The run's eps is the last one. A run that has not reached d in
   PENETRATION_TOL_MAX_SOLVES solves, or whose solve failed, is reported failed (converged = 0). Each solve is a row of /solves, with its eps and its
   largest penetration at the nodes. */
#include "contact.h"
#include "drivers_impl.h"
#include "app.h"

#define PENETRATION_TOL_AIM 0.9
#define PENETRATION_TOL_MAX_SOLVES 12
#define PENETRATION_TOL_MAX_UPDATES 60
#define PENETRATION_TOL_STALL 8

/* The augmented Lagrangian (-contact_method al): Uzawa's updates of the multipliers at the contact nodes, each followed
   by a solve from the last solution at the same eps, until the update would change eps lambda by at most d anywhere:
   then the penetration is at most d and no node whose multiplier pushes stands off the obstacle by more than d (on a
   path that unloads, the last step's multipliers push too hard at first, the body stands off and the penetration alone,
   zero, would end the loop with the wrong answer). Where the active set stays, a solve is one linear solve with the
   last Jacobian; the change falls by a constant factor per update (about 0.6 at the edge of the contact zone,
   docs/solvers.md). */
static PetscErrorCode UzawaSolve(DM dm, AppCtx *user, SNES snes, Vec u, PetscReal tol, PetscReal *d_max, PetscInt *solves, PetscBool *reached)
{
  MPI_Comm  comm = PetscObjectComm((PetscObject)dm);
  PetscReal change, best;
  PetscInt  since_best = 0;

  PetscFunctionBeginUser;
  PetscCall(ContactAugment(user->contact, dm, u, PETSC_FALSE, &change));
  best = change;
  while (change > tol && SolverStats(user->solver)->converged && *solves < PENETRATION_TOL_MAX_UPDATES) {
    PetscCall(ContactAugment(user->contact, dm, u, PETSC_TRUE, &change));
    PetscCall(SolverSolve(snes, user->solver, u, SOLVER_START_NEARBY_EPS));
    ++*solves;
    PetscCall(ContactMaxPenetration(user->contact, dm, u, d_max));
    PetscCall(ContactAugment(user->contact, dm, u, PETSC_FALSE, &change));
    PetscCall(PetscInfo(snes, "augmented Lagrangian: update %" PetscInt_FMT ", largest penetration %g, next change %g\n", *solves - 1, (double)*d_max,
                        (double)change));
    if (change < best) {
      best       = change;
      since_best = 0;
    } else if (++since_best == PENETRATION_TOL_STALL) { /* Uzawa's change need not fall at every update, but it must fall */
      PetscCall(PetscPrintf(comm, "  augmented Lagrangian: the multipliers' change has not fallen below %g in %d updates\n", (double)best,
                            PENETRATION_TOL_STALL));
      break;
    }
  }
  *reached = (PetscBool)(change <= tol);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* eps continuation (-contact_method penalty): eps <- eps 0.9 d / d_max after each solve, by at most the continuation
   factor, each solve from the secant in eps of the last two solutions (or the last one), and from zero where the warm
   solve fails. */
static PetscErrorCode ContinuationSolve(DM dm, AppCtx *user, SNES snes, Vec u, PetscReal tol, PetscReal *d_max, PetscInt *solves, PetscBool *reached)
{
  const ContactOptions *copt;
  MPI_Comm              comm = PetscObjectComm((PetscObject)dm);
  Vec                   prev = NULL, dir = NULL;
  PetscReal             eps, eps_prev    = 0.0;

  PetscFunctionBeginUser;
  PetscCall(ContactGetOptions(user->contact, &copt));
  PetscCall(ContactGetEps(user->contact, &eps));
  while (*d_max > tol && SolverStats(user->solver)->converged && *solves < PENETRATION_TOL_MAX_SOLVES) {
    const PetscReal eps_new = eps * PetscMax(PENETRATION_TOL_AIM * tol / *d_max, copt->continuation_factor);
    const PetscBool secant  = (PetscBool)(prev != NULL);

    PetscCall(PetscPrintf(comm, "  penetration tolerance: eps = %g gives the largest penetration %g > %g: eps = %g next\n", (double)eps,
                          (double)*d_max, (double)tol, (double)eps_new));
    if (!prev) {
      PetscCall(VecDuplicate(u, &prev));
      PetscCall(VecDuplicate(u, &dir));
    }
    PetscCall(ContactSetEps(user->contact, dm, eps_new));
    PetscCall(SolverSecantStart(snes, dm, user->solver, u, prev, dir, secant, secant ? (eps_new - eps) / (eps - eps_prev) : 0.0, 0.0));
    eps_prev = eps;
    eps      = eps_new;
    PetscCall(SolverSolveWarm(snes, user->solver, u, "penetration tolerance")); /* from zero where it stalls at a kink of the penalty */
    ++*solves;
    PetscCall(ContactMaxPenetration(user->contact, dm, u, d_max));
  }
  *reached = (PetscBool)(*d_max <= tol);
  PetscCall(VecDestroy(&prev));
  PetscCall(VecDestroy(&dir));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The continuation from the solution u to -contact_penetration_tol (nothing without it, or after a failed solve). */
PetscErrorCode PenetrationTolReach(DM dm, AppCtx *user, SNES snes, Vec u)
{
  RunStats             *stats = SolverStats(user->solver);
  const ContactOptions *copt;
  MPI_Comm              comm = PetscObjectComm((PetscObject)dm);
  PetscReal             d_max, eps;
  PetscInt              solves  = 1;
  PetscBool             reached = PETSC_FALSE, augment;

  PetscFunctionBeginUser;
  PetscCall(ContactGetOptions(user->contact, &copt));
  if (!(copt->penetration_tol > 0.0) || !stats->converged) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(ContactMaxPenetration(user->contact, dm, u, &d_max));
  /* a driver's choice between two ways to the tolerance: Uzawa's updates of the type's multipliers, or a smaller eps */
  augment = ContactCanAugment(user->contact);
  if (augment)
    PetscCall(UzawaSolve(dm, user, snes, u, copt->penetration_tol, &d_max, &solves, &reached));
  else
    PetscCall(ContinuationSolve(dm, user, snes, u, copt->penetration_tol, &d_max, &solves, &reached));
  PetscCall(ContactGetEps(user->contact, &eps));
  stats->penetration_tol_solves += solves; /* over the steps of a load path */
  stats->penetration_tol_measured = d_max;
  if (stats->converged && !reached) {
    PetscCall(PetscPrintf(
        comm, "  penetration tolerance: -contact_penetration_tol %g not reached after %" PetscInt_FMT " solves (the largest penetration %g%s)\n",
        (double)copt->penetration_tol, solves, (double)d_max, augment ? "; the multipliers still move by more than the tolerance" : ""));
    stats->converged = PETSC_FALSE;
  } else if (stats->converged)
    PetscCall(PetscPrintf(comm, "  penetration tolerance: the largest penetration %g <= %g at eps = %g, in %" PetscInt_FMT " solve(s)\n",
                          (double)d_max, (double)copt->penetration_tol, (double)eps, solves));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* -contact_penetration_tol's part of /run: the solves that reached it (over a load path's steps) and the largest
   penetration it ended with, at the nodes and the rule's points; the tolerance itself is the contact's (ContactWrite()). */
static PetscErrorCode PenetrationTolWrite(Driver d, MPI_Comm comm, const DriverReport *r, PetscViewer v)
{
  const ContactOptions *copt;

  PetscFunctionBeginUser;
  PetscCall(ContactGetOptions(r->contact, &copt));
  if (!(copt->penetration_tol > 0.0)) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(RunAttrInt(v, r->stats->penetration_tol_solves, "penetration_tol_solves"));
  PetscCall(RunAttrReal(v, r->stats->penetration_tol_measured, "penetration_tol_measured"));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PenetrationTolSolve(Driver d, AppCtx *user, DM *dm, SNES *snes, Vec *u)
{
  PetscFunctionBeginUser;
  PetscCall(PenetrationTolReach(*dm, user, *snes, *u));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The penetration tolerance's driver: on the final mesh, from the last solution (a load path's steps each reach the
   tolerance again, from the last step's eps or multipliers). */
PetscErrorCode DriverCreate_PenetrationTol(Driver d)
{
  PetscFunctionBeginUser;
  d->ops.solve = PenetrationTolSolve;
  d->ops.write = PenetrationTolWrite;
  PetscFunctionReturn(PETSC_SUCCESS);
}
