/* -penalty_eps0_sweep a,b,c,...: the penalty problems for eps = eps0 h^power / M with eps0 = a, b, c, ... solved in
   turn on the final mesh, each from the solution for the previous value (the first is the run's main solve). The
   bulk matrix, the load and the solver objects are shared; the output holds the last solution, and /solves one row
   per value. A failed value ends the sweep.
   From the third value on, the start is extrapolated in eps from the last solutions: while the active set stays,
   u(eps) = (K + P/eps)^-1 f is smooth in eps, u(0) + eps u'(0) + eps^2 u''(0)/2 + O(eps^3) once the penalty dominates,
   so the penetration, whose 1/eps multiple is most of the residual after a step of eps, is predicted instead of
   carried over. The polynomial goes through the last SWEEP_POINTS solutions (fewer at the start): the secant of two
   leaves the eps^2 term, eps_last eps_prev u''(0)/2 about, which the parabola of three removes; at 256 x 256 with
   GAMG (eps = h to 1e-7 h) the last four values then take 2, 1, 1 and 0 Newton steps and 11, 6, 5 and 0 CG iterations
   instead of 2, 2, 1, 1 and 11, 11, 6, 5 (one OpenBLAS thread; with its threads 2, 1, 1, 1 and 11, 5, 5, 4); the fourth
   point of a cubic saved one more CG iteration there (not kept).
   The second value starts on the tangent of the solution path at the first (EpsSweepTangent()). */
#include "contact.h"
#include "drivers_impl.h"

#define SWEEP_POINTS 3 /* the solutions the start's polynomial in eps goes through */

/* The first new value has no earlier solution to extrapolate from: its start follows the tangent of the solution path
   at the last eps instead. F(u; eps) = K u + r0 + P(u; eps) with the penalty term P proportional to 1/eps, so
   du/deps = J^-1 P(u; eps) / eps, J the Jacobian, which K and the SNES's preconditioner still hold from the last Newton
   step. dir = J^-1 P(u; eps_new), P the contact ct's at its new eps, solved loosely (CG to 1e-2, the preconditioner shared); the step to eps_new is
   (eps_new - eps) du/deps = dir (eps_new - eps) eps_new / eps^2. Its CG iterations are added to *ksp_its_total (the run's). *ok is false
   if CG did not converge. A few Gauss points at the edge of the contact zone may flip on the tangent, so its guess is
   taken where its residual is 100 times lower than the last solution's, whatever its active points; the secant's rule
   (the same active points) would refuse it. */
PetscErrorCode EpsSweepTangent(SNES snes, DM dm, Contact ct, Vec u, Vec dir, PetscInt *ksp_its_total, PetscBool *ok)
{
  KSP                ksp, tangent;
  PC                 pc;
  Mat                A, P;
  Vec                rhs;
  PetscInt           its;
  KSPConvergedReason reason;

  PetscFunctionBeginUser;
  PetscCall(SNESGetKSP(snes, &ksp));
  PetscCall(KSPGetOperators(ksp, &A, &P));
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(VecDuplicate(u, &rhs));
  PetscCall(VecZeroEntries(rhs));
  PetscCall(ContactAddResidual(ct, dm, u, rhs)); /* P(u; eps_new) */
  PetscCall(KSPCreate(PetscObjectComm((PetscObject)snes), &tangent));
  PetscCall(KSPSetType(tangent, KSPCG));
  PetscCall(KSPSetOperators(tangent, A, P));
  PetscCall(KSPSetPC(tangent, pc)); /* shared: set up for A already, and left alone by KSPDestroy() */
  PetscCall(KSPSetTolerances(tangent, 1e-2, 0.0, PETSC_DEFAULT, 200));
  PetscCall(KSPSolve(tangent, rhs, dir));
  PetscCall(KSPGetConvergedReason(tangent, &reason));
  PetscCall(KSPGetIterationNumber(tangent, &its));
  *ksp_its_total += its;
  *ok = (PetscBool)(reason > 0);
  PetscCall(KSPDestroy(&tangent));
  PetscCall(VecDestroy(&rhs));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The start for eps from the solutions hist[0..n-1] (the newest first) for the distinct values e[0..n-1]: dir <- p(eps)
   - hist[0], p the polynomial in eps through them (Lagrange's form). */
static PetscErrorCode ExtrapolationStep(PetscInt n, Vec hist[], const PetscReal e[], PetscReal eps, Vec dir)
{
  PetscFunctionBeginUser;
  PetscCall(VecCopy(hist[0], dir));
  PetscCall(VecScale(dir, -1.0));
  for (PetscInt j = 0; j < n; ++j) {
    PetscReal w = 1.0;

    for (PetscInt i = 0; i < n; ++i)
      if (i != j) w *= (eps - e[i]) / (e[j] - e[i]);
    PetscCall(VecAXPY(dir, w, hist[j]));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode EpsSweepSolve(Driver d, AppCtx *user, DM *dmp, SNES *snesp, Vec *up)
{
  RunStats             *stats              = SolverStats(user->solver);
  DM                    dm                 = *dmp;
  SNES                  snes               = *snesp;
  Vec                   u                  = *up;
  Vec                   hist[SWEEP_POINTS] = {NULL}, dir = NULL; /* the solutions for the last values, the newest first */
  PetscReal             e[SWEEP_POINTS] = {0.0}, eps;
  PetscInt              nh              = 0;
  const ContactOptions *copt;

  PetscFunctionBeginUser;
  PetscCall(ContactGetOptions(user->contact, &copt));
  for (PetscInt k = 1; k < copt->n_sweep && stats->converged; ++k) {
    PetscReal eps_last;
    PetscInt  n = 1;

    PetscCall(ContactGetEps(user->contact, &eps_last));
    PetscCall(ContactEpsFromFactor(user->contact, copt->eps0_sweep[k], &eps));
    PetscCall(ContactSetEps(user->contact, dm, eps));
    if (!dir) PetscCall(VecDuplicate(u, &dir));
    { /* u, the solution for eps_last, becomes the newest of the history */
      Vec oldest = hist[SWEEP_POINTS - 1];

      for (PetscInt j = SWEEP_POINTS - 1; j > 0; --j) hist[j] = hist[j - 1], e[j] = e[j - 1];
      hist[0] = oldest;
      if (!hist[0]) PetscCall(VecDuplicate(u, &hist[0]));
      PetscCall(VecCopy(u, hist[0]));
      e[0] = eps_last;
      nh   = PetscMin(nh + 1, SWEEP_POINTS);
    }
    for (PetscBool distinct = PETSC_TRUE; n < nh && distinct; n += distinct) /* the newest values, as far as they are distinct */
      for (PetscInt i = 0; i < n; ++i) distinct = (PetscBool)(distinct && e[n] != e[i]);
    if (n > 1 && eps != eps_last) { /* the polynomial through the last n solutions */
      PetscCall(ExtrapolationStep(n, hist, e, eps, dir));
      PetscCall(SolverExtrapolatedStart(snes, dm, user->solver, u, dir, 1.0, 0.0, PETSC_TRUE));
    } else if (k == 1 && eps != eps_last) { /* the tangent (a sweep is the penalty's: ContactSetFromOptions()) */
      PetscBool ok = PETSC_FALSE;

      PetscCall(EpsSweepTangent(snes, dm, user->contact, u, dir, &stats->ksp_its_total, &ok));
      if (ok) PetscCall(SolverExtrapolatedStart(snes, dm, user->solver, u, dir, (eps - eps_last) * eps / (eps_last * eps_last), 1e-2, PETSC_FALSE));
    }
    PetscCall(SolverSolve(snes, user->solver, u, SOLVER_START_NEARBY_EPS));
  }
  for (PetscInt j = 0; j < SWEEP_POINTS; ++j) PetscCall(VecDestroy(&hist[j]));
  PetscCall(VecDestroy(&dir));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The eps sweep's driver: its solves are rows of the solver's table of solves (/solves), its only results. */
PetscErrorCode DriverCreate_EpsSweep(Driver d)
{
  PetscFunctionBeginUser;
  d->ops.solve = EpsSweepSolve;
  PetscFunctionReturn(PETSC_SUCCESS);
}
