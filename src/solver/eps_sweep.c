/* -penalty_eps0_sweep a,b,c,...: the penalty problems for eps = eps0 h^power / M with eps0 = a, b, c, ... solved in
   turn on the final mesh, each from the solution for the previous value (the first is the run's main solve). The
   bulk matrix, the load and the solver objects are shared; the output holds the last solution, and /solves one row
   per value. A failed value ends the sweep.
   From the third value on, the start is extrapolated linearly in eps from the last two solutions: while the active
   set stays, u(eps) = (K + P/eps)^-1 f is u(0) + eps u'(0) + O(eps^2) once the penalty dominates, so the
   penetration, whose 1/eps multiple is most of the residual after a step of eps, is predicted instead of carried
   over. The second value starts
   on the tangent of the solution path at the first (TangentDirection()). */
#include "contact.h"
#include "solver_impl.h"

/* The first new value has no earlier solution to extrapolate from: its start follows the tangent of the solution path
   at the last eps instead. F(u; eps) = K u + r0 + P(u; eps) with the penalty term P proportional to 1/eps, so
   du/deps = J^-1 P(u; eps) / eps, J the Jacobian, which K and the SNES's preconditioner still hold from the last Newton
   step. dir = J^-1 P(u; eps_new), solved loosely (CG to 1e-2, the preconditioner shared); the step to eps_new is
   (eps_new - eps) du/deps = dir (eps_new - eps) eps_new / eps^2. Its CG iterations count in ksp_its_total. *ok is false
   if CG did not converge. A few Gauss points at the edge of the contact zone may flip on the tangent, so its guess is
   taken where its residual is 100 times lower than the last solution's, whatever its active points; the secant's rule
   (the same active points) would refuse it. */
static PetscErrorCode TangentDirection(SNES snes, DM dm, AppCtx *user, Vec u, Vec dir, PetscBool *ok)
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
  PetscCall(ContactAddResidual(user->contact, dm, u, rhs)); /* P(u; eps_new) */
  PetscCall(KSPCreate(PetscObjectComm((PetscObject)snes), &tangent));
  PetscCall(KSPSetType(tangent, KSPCG));
  PetscCall(KSPSetOperators(tangent, A, P));
  PetscCall(KSPSetPC(tangent, pc)); /* shared: set up for A already, and left alone by KSPDestroy() */
  PetscCall(KSPSetTolerances(tangent, 1e-2, 0.0, PETSC_DEFAULT, 200));
  PetscCall(KSPSolve(tangent, rhs, dir));
  PetscCall(KSPGetConvergedReason(tangent, &reason));
  PetscCall(KSPGetIterationNumber(tangent, &its));
  user->rec.stats.ksp_its_total += its;
  *ok = (PetscBool)(reason > 0);
  PetscCall(KSPDestroy(&tangent));
  PetscCall(VecDestroy(&rhs));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode EpsSweepSolve(DM dm, AppCtx *user, SNES snes, Vec u)
{
  Vec                   prev = NULL, last = NULL, dir = NULL; /* the solutions for the values before the last, and for the last */
  PetscReal             eps_prev = 0.0, eps;
  const ContactOptions *copt;

  PetscFunctionBeginUser;
  PetscCall(ContactGetOptions(user->contact, &copt));
  for (PetscInt k = 1; k < copt->n_sweep && user->rec.stats.converged; ++k) {
    PetscReal eps_last;

    PetscCall(ContactGetEps(user->contact, &eps_last));
    PetscCall(ContactEpsFromFactor(user->contact, copt->eps0_sweep[k], &eps));
    PetscCall(ContactSetEps(user->contact, dm, eps));
    if (!last) PetscCall(VecDuplicate(u, &last));
    if (!dir) PetscCall(VecDuplicate(u, &dir));
    PetscCall(VecCopy(u, last));
    if (k > 1 && eps_last != eps_prev) { /* the secant of the last two solutions */
      PetscCall(VecWAXPY(dir, -1.0, prev, u));
      PetscCall(SolverExtrapolatedStart(snes, dm, user, u, dir, (eps - eps_last) / (eps_last - eps_prev), 0.0, PETSC_TRUE));
    } else if (k == 1 && ContactHasPenalty(user->contact) && eps != eps_last) { /* the tangent */
      PetscBool ok = PETSC_FALSE;

      PetscCall(TangentDirection(snes, dm, user, u, dir, &ok));
      if (ok) PetscCall(SolverExtrapolatedStart(snes, dm, user, u, dir, (eps - eps_last) * eps / (eps_last * eps_last), 1e-2, PETSC_FALSE));
    }
    if (!prev) PetscCall(VecDuplicate(u, &prev));
    PetscCall(VecSwap(prev, last));
    eps_prev = eps_last;
    PetscCall(SolverSolve(snes, user, u, SOLVER_START_NEARBY_EPS));
  }
  PetscCall(VecDestroy(&prev));
  PetscCall(VecDestroy(&last));
  PetscCall(VecDestroy(&dir));
  PetscFunctionReturn(PETSC_SUCCESS);
}
