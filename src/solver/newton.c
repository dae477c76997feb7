/* The callbacks of the SNES (residual, Jacobian, convergence test) and of its linear solves (the pre-solve), on the
   solver's context (solver_impl.h): the bulk operator K and r0, the Contact, the solver's options. The bulk operator is
   linear: K and r0 = F_bulk(0) are assembled once, the residual is K u + r0 + (contact term) and the Jacobian
   K + (contact Jacobian). */
#include <math.h>
#include "solver_impl.h"

PetscErrorCode SolverCtxCreate(Mat K, Vec r0, Contact contact, const SolverOptions *opt, RunStats *stats, SolverCtx *sc)
{
  PetscFunctionBeginUser;
  PetscCall(PetscNew(sc));
  (*sc)->K          = K;
  (*sc)->r0         = r0;
  (*sc)->contact    = contact;
  (*sc)->opt        = opt;
  (*sc)->stats      = stats;
  (*sc)->snes_scale = 1.0;
  PetscCall(PcReuseSetUp(&(*sc)->pc_reuse, K, contact, opt));
  PetscCall(VecDuplicate(r0, &(*sc)->work)); /* DMCreateGlobalVector() would scan every mesh point again */
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode SolverCtxDestroy(SolverCtx *sc)
{
  PetscFunctionBeginUser;
  if (!*sc) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PcReuseDestroy(&(*sc)->pc_reuse));
  PetscCall(SolverStepGuessDrop(&(*sc)->step_guess));
  PetscCall(VecDestroy(&(*sc)->work));
  PetscCall(PetscFree(*sc));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The next solve's first linear solve starts from the Newton step that the change du of the solution (the user's
   units) predicts (src/linear/step_guess.c). */
PetscErrorCode SolverSetStepGuess(SolverCtx sc, Vec du)
{
  PetscFunctionBeginUser;
  PetscCall(SolverStepGuessSet(&sc->step_guess, du));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* R = K X + r0: the residual of the elastic problem without the contact terms. */
PetscErrorCode SolverBulkResidual(SolverCtx sc, Vec X, Vec R)
{
  PetscFunctionBeginUser;
  PetscCall(ContactBulkMult(sc->contact, sc->K, X, R)); /* K X, also while K holds the penalty Jacobian (which it leaves alone) */
  PetscCall(VecAXPY(R, 1.0, sc->r0));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The SNES works on x~ = u/U with the residual F~(x~) = F(U x~)/U, U = sc->snes_scale a power of 2 (exact in floating
   point): F~ has the Jacobian of F, so Newton's iterates are U times smaller and the same, while the absolute tolerances
   inside PETSc (SNESVI's bound tolerance, the line searches' maximal step) see a displacement of size one in any units.
   The displacement of the iterate, U x~, goes to sc->work; with SNESVI's rotated frames (ContactSolverFrame()) the SNES's
   unknowns are x~ = Q^T u/U and the displacement U Q x~. */
PetscErrorCode SolverIterateDisplacement(SolverCtx sc, Vec X, Vec *u)
{
  PetscFunctionBeginUser;
  PetscCall(ContactSolverDisplacement(sc->contact, X, sc->work, u)); /* X itself, or Q X in sc->work */
  if (sc->snes_scale == 1.0) PetscFunctionReturn(PETSC_SUCCESS);
  if (*u == X) PetscCall(VecCopy(X, sc->work));
  PetscCall(VecScale(sc->work, sc->snes_scale));
  *u = sc->work;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The residual K u + r0 + (penalty term) at the displacement u, in the user's units. */
PetscErrorCode SolverResidual(SolverCtx sc, DM dm, Vec u, Vec F)
{
  PetscFunctionBeginUser;
  PetscCall(SolverBulkResidual(sc, u, F));
  PetscCall(ContactAddResidual(sc->contact, dm, u, F));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* ||F(u)||_2 at the displacement u, in the user's units (outside SolverSolve()). */
PetscErrorCode SolverResidualNorm(SNES snes, SolverCtx sc, Vec u, PetscReal *norm)
{
  DM  dm;
  Vec F;

  PetscFunctionBeginUser;
  PetscCall(SNESGetDM(snes, &dm));
  PetscCall(VecDuplicate(u, &F));
  PetscCall(SolverResidual(sc, dm, u, F));
  PetscCall(VecNorm(F, NORM_2, norm));
  PetscCall(VecDestroy(&F));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode SolverFormFunction(SNES snes, Vec X, Vec F, void *ctx)
{
  SolverCtx sc = (SolverCtx)ctx;
  DM        dm;
  Vec       u;

  PetscFunctionBeginUser;
  PetscCall(SNESGetDM(snes, &dm));
  PetscCall(SolverIterateDisplacement(sc, X, &u));
  PetscCall(SolverResidual(sc, dm, u, F));
  PetscCall(ContactSolverFrame(sc->contact, F, PETSC_TRUE)); /* F_w = Q^T F(Q w) */
  if (sc->snes_scale != 1.0) PetscCall(VecScale(F, 1.0 / sc->snes_scale));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode SolverFormJacobian(SNES snes, Vec X, Mat J, Mat P, void *ctx)
{
  SolverCtx sc = (SolverCtx)ctx;
  DM        dm;
  Vec       u;

  PetscFunctionBeginUser;
  PetscCall(SNESGetDM(snes, &dm));
  PetscCall(SolverIterateDisplacement(sc, X, &u));
  /* J = K for the types without a contact Jacobian, which ContactComputeJacobian() leaves; the preconditioner's reuse
     wraps this callback where it is on (PcReuseAttach(), src/linear/pc_reuse.c) */
  PetscCall(ContactComputeJacobian(sc->contact, dm, u, sc->K, P)); /* P is K itself, or a copy (SBAIJ: no row access) */
  if (J != P) {
    PetscCall(MatAssemblyBegin(J, MAT_FINAL_ASSEMBLY));
    PetscCall(MatAssemblyEnd(J, MAT_FINAL_ASSEMBLY));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Newton stops, converged, when PETSc's tests say so (|F| fell by -snes_rtol, ...) or when |F| <= -contact_load_rtol
   ||F(0)||: at round-off for the load, which a warm start (eps sweep, grid sequence) may reach before any reduction
   by -snes_rtol. A warm start stops when |F| <= -snes_rtol ||F(0)||, whatever its first residual: its final residual
   is as tight as a start from zero would give. One whose first residual exceeds the load (an interpolated guess, whose
   error is of the order of h) is not stopped by a reduction of that residual alone; one far below it (an extrapolated
   start of the eps sweep) is not held to a reduction that round-off cannot reach.
   Every norm here is relative, so the test is the same in any units. The reference of -snes_rtol is
   SolverStopReference() (solver_impl.h), which the core passes to the forcing terms (src/linear/ew_forcing.c). */

/* The size of the round-off in the residual at u: F = K u + r0 + (1/eps)[u_n - g]_+ n w sums terms much larger than F
   itself near the solution, and double precision knows each to about PETSC_MACHINE_EPSILON of its size. The terms:
   |diag(J)| |u| (the bulk's rows, and the penalty's (1/eps) u_n, since J holds the penalty Jacobian in its contact
   rows), r0, and the penalty's (1/eps) g w at the penetrating nodes (its gap term, large where the obstacle is
   far from the origin or the indentation deep). This is an estimate of the floor, not a bound: it is used only where
   Newton has stopped making progress (SolverConverged()). */
static PetscErrorCode SolverRoundoffFloor(SNES snes, SolverCtx sc, PetscReal *floor)
{
  Vec       X, u, D;
  Mat       J;
  PetscReal bulk, r0, gap = 0.0;

  PetscFunctionBeginUser;
  PetscCall(SNESGetSolution(snes, &X));
  PetscCall(SolverIterateDisplacement(sc, X, &u));
  PetscCall(SNESGetJacobian(snes, &J, NULL, NULL, NULL));
  PetscCall(VecDuplicate(u, &D));
  PetscCall(MatGetDiagonal(J, D));
  PetscCall(VecPointwiseMult(D, D, u));
  PetscCall(VecNorm(D, NORM_2, &bulk));
  PetscCall(VecDestroy(&D));
  /* J is the Jacobian of F/U in u/U, that is of F in u: diag(J) u is in the user's units, as u (U x~) is */
  PetscCall(VecNorm(sc->r0, NORM_2, &r0));
  PetscCall(ContactRoundoffTerm(sc->contact, u, &gap));
  *floor = PETSC_MACHINE_EPSILON * PetscSqrtReal(bulk * bulk + r0 * r0 + gap);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The energy norm of the last Newton step, (du^T J du)^(1/2) with du = U lambda Y the displacement's change (Y the
   Newton direction, lambda the line search's length): J is the Jacobian of F in u (SolverRoundoffFloor()), the
   elasticity's stiffness plus the penalty's, so that this is at least the step's a(du, du)^(1/2), the estimate's norm. */
static PetscErrorCode SolverStepEnergy(SNES snes, SolverCtx sc, PetscReal *energy)
{
  SNESLineSearch ls;
  Vec            Y, du, Jdu;
  Mat            J;
  PetscReal      lambda, dot;

  PetscFunctionBeginUser;
  PetscCall(SNESGetSolutionUpdate(snes, &Y));
  PetscCall(SNESGetLineSearch(snes, &ls));
  PetscCall(SNESLineSearchGetLambda(ls, &lambda));
  PetscCall(SolverIterateDisplacement(sc, Y, &du));
  PetscCall(SNESGetJacobian(snes, &J, NULL, NULL, NULL));
  PetscCall(VecDuplicate(du, &Jdu));
  PetscCall(MatMult(J, du, Jdu));
  PetscCall(VecDot(du, Jdu, &dot));
  PetscCall(VecDestroy(&Jdu));
  *energy = PetscAbsReal(lambda) * PetscSqrtReal(PetscMax(dot, 0.0));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode SolverConverged(SNES snes, PetscInt it, PetscReal xnorm, PetscReal snorm, PetscReal fnorm, SNESConvergedReason *reason, void *ctx)
{
  SolverCtx       sc = (SolverCtx)ctx;
  const PetscReal f  = fnorm * sc->snes_scale; /* |F| in the user's units */

  PetscFunctionBeginUser;
  PetscCall(SNESConvergedDefault(snes, it, xnorm, snorm, fnorm, reason, NULL));
  if (it == 0) sc->fnorm0 = f;
  if (sc->warm && (*reason == SNES_CONVERGED_FNORM_RELATIVE || *reason == SNES_CONVERGED_ITERATING)) {
    PetscReal atol, rtol, stol, ref;
    PetscInt  maxit, maxf;

    PetscCall(SNESGetTolerances(snes, &atol, &rtol, &stol, &maxit, &maxf));
    ref     = SolverStopReference(sc);
    *reason = f <= rtol * ref ? SNES_CONVERGED_FNORM_RELATIVE : SNES_CONVERGED_ITERATING;
  }
  if (*reason <= 0 && !PetscIsInfOrNanReal(f) && f <= sc->opt->load_rtol * sc->load_norm) *reason = SNES_CONVERGED_FNORM_ABS;
  /* A tolerance below what double precision can reach: Newton stalls at the round-off of the terms the residual sums
     (with eps far below h/E, (1/eps) times the displacement times the machine epsilon). Where a step did not halve |F|
     and |F| is within 100 times the estimated round-off (SolverRoundoffFloor()), it stops, converged at round-off,
     instead of running to the iteration limit; /run says so (stopped_at_roundoff). A step that still makes progress is
     never stopped here. */
  if (it == 0) sc->roundoff_stop = PETSC_FALSE;
  if (it == 0) sc->energy_stop = PETSC_FALSE;
  if (*reason <= 0 && it > 0 && !PetscIsInfOrNanReal(f) && f > 0.5 * sc->fnorm_last) {
    PetscReal floor = 0.0;

    PetscCall(SolverRoundoffFloor(snes, sc, &floor));
    if (f <= 100.0 * floor) {
      *reason           = SNES_CONVERGED_FNORM_ABS;
      sc->roundoff_stop = PETSC_TRUE;
    }
  }
  /* A warm solve that has a way out (SolverSolveWarm()) stops, failed, where SOLVER_STALL_STEPS Newton steps have not
     halved |F|: converging semismooth Newton does that in one or two steps, while a start whose active set is far off
     can stall, the critical-point line search taking steps of 1e-3 at every iteration (solver.c). */
  if (sc->stall_stop && !PetscIsInfOrNanReal(f)) {
    const PetscInt w = SOLVER_STALL_STEPS + 1;

    if (*reason == SNES_CONVERGED_ITERATING && it >= SOLVER_STALL_STEPS && f > 0.5 * sc->fnorm_window[(it - SOLVER_STALL_STEPS) % w])
      *reason = SNES_DIVERGED_LINE_SEARCH;
    sc->fnorm_window[it % w] = f;
  }
  /* The accuracy's stop (-accuracy_newton_fraction, adapt.c): Newton stops once its step is below a fraction of the
     discretization's error in the energy norm. Semismooth Newton converges superlinearly near the solution, so that
     the error left after a step is far below the step, and the step's energy norm bounds it. */
  if (*reason == SNES_CONVERGED_ITERATING && it > 0 && sc->step_energy_stop > 0.0) {
    PetscReal e = 0.0;

    PetscCall(SolverStepEnergy(snes, sc, &e));
    if (e <= sc->step_energy_stop) {
      *reason         = SNES_CONVERGED_SNORM_RELATIVE;
      sc->energy_stop = PETSC_TRUE;
    }
  }
  sc->fnorm_last = f;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* What the linear layer reads of the core (LinearCore, include/linear.h): the displacement of an iterate, and the
   current solve's stopping reference and scale. */
static PetscErrorCode SolverCoreDisplacement(void *core, Vec X, Vec *u)
{
  PetscFunctionBeginUser;
  PetscCall(SolverIterateDisplacement((SolverCtx)core, X, u));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode SolverCoreScales(void *core, PetscReal *stop_reference, PetscReal *snes_scale)
{
  const SolverCtx sc = (SolverCtx)core;

  PetscFunctionBeginUser;
  *stop_reference = SolverStopReference(sc);
  *snes_scale     = sc->snes_scale;
  PetscFunctionReturn(PETSC_SUCCESS);
}

void SolverCtxLinearCore(SolverCtx sc, LinearCore *core)
{
  core->displacement = SolverCoreDisplacement;
  core->scales       = SolverCoreScales;
  core->core         = sc;
}
