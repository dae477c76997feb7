/* Recovery from a breakdown of the preconditioner. A Krylov solve of a Newton step can stop on the preconditioner
   rather than on the problem: CG meets a direction with p^T B p <= 0 (DIVERGED_INDEFINITE_PC) when a multigrid's
   Chebyshev smoothers were bounded below the top of the spectrum (an eigenvalue estimate made on an earlier Jacobian,
   or on one whose penalty rows have grown since), and the setup itself can fail (DIVERGED_PC_FAILED: a failed
   estimate, a zero pivot). The Jacobian is symmetric positive definite whatever eps (K is, and the penalty term adds
   a positive semidefinite part), so such a stop says nothing about the problem. Newton then goes on from its last
   iterate (a failed linear solve leaves it untouched) after, in turn:
     1. a fresh build of the preconditioner on the current Jacobian, and builds only from then on (no more updates of a
        GAMG hierarchy's coarse operators, whose finest smoother is bounded rather than estimated again): new smoother
        estimates at every build;
     2. for a multigrid, safer smoother bounds and aggregates: GAMG built anew with its Chebyshev smoothers bounded by
        an estimate on each level's own operator (-pc_gamg_use_sa_esteig 0, not the smoothed aggregation's estimate,
        which PETSc 3.18 uses by default and which the penalty rows of a small eps exceed), and its aggregates made on
        the whole graph of the matrix (-pc_gamg_threshold 0); a geometric multigrid's Chebyshev intervals stretched to
        SAFER_EMAX times the top estimate (PETSc's default is 1.1). The penalty couples the normal components of the
        contact nodes by 1/eps; where it dwarfs their elastic couplings, options/solvers/gamg.yaml's threshold 0.01
        drops the links into the body, and aggregates of contact nodes alone, nearly coplanar, carry the rigid-body
        modes badly, so that CG breaks down whatever the smoothers' bounds (the Hertz sphere remeshed by -adapt_model,
        whose carried solutions bring the penalty rows into the first Jacobian: docs/estimate.md);
     3. a direct solve: LU (Cholesky for SBAIJ) by MUMPS, exact for any eps.
   Each step is taken once per run, counted in /run pc_breakdowns and described in pc_recovery; -contact_pc_recovery 0
   leaves the breakdown a failed solve. A breakdown is never turned into a converged result without the Newton
   convergence test it would have had to pass anyway. */
#include "linear_impl.h"

#define SAFER_EMAX 1.5

/* Chebyshev's interval on every level of a multigrid preconditioner: [0.1, SAFER_EMAX] times the estimate of the top
   eigenvalue instead of PETSc's [0.1, 1.1]: an estimate a little low no longer puts the top of the spectrum outside
   the interval, where the Chebyshev polynomial grows. */
static PetscErrorCode SaferChebyshev(PC pc)
{
  PetscInt nlevels;

  PetscFunctionBeginUser;
  PetscCall(PCMGGetLevels(pc, &nlevels));
  for (PetscInt l = 1; l < nlevels; ++l) {
    KSP       smoother;
    PetscBool is_cheb;

    PetscCall(PCMGGetSmoother(pc, l, &smoother));
    PetscCall(PetscObjectTypeCompare((PetscObject)smoother, KSPCHEBYSHEV, &is_cheb));
    if (is_cheb) PetscCall(KSPChebyshevEstEigSet(smoother, 0.0, 0.1, 0.0, SAFER_EMAX));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Whether the last SNESSolve ended on a breakdown of the linear solver (not on its iteration limit: a tolerance the
   user set, or a solve that is merely slow, stays a failure). */
static PetscErrorCode IsBreakdown(SNES snes, KSPConvergedReason *kreason, PetscBool *breakdown)
{
  SNESConvergedReason sreason;
  KSP                 ksp;

  PetscFunctionBeginUser;
  *breakdown = PETSC_FALSE;
  PetscCall(SNESGetConvergedReason(snes, &sreason));
  PetscCall(SNESGetKSP(snes, &ksp));
  PetscCall(KSPGetConvergedReason(ksp, kreason));
  if (sreason != SNES_DIVERGED_LINEAR_SOLVE) PetscFunctionReturn(PETSC_SUCCESS);
  switch (*kreason) {
    case KSP_DIVERGED_INDEFINITE_PC:
    case KSP_DIVERGED_PC_FAILED:
    case KSP_DIVERGED_BREAKDOWN:
    case KSP_DIVERGED_BREAKDOWN_BICG:
    case KSP_DIVERGED_INDEFINITE_MAT:
    case KSP_DIVERGED_NANORINF:
      *breakdown = PETSC_TRUE;
      break;
    default:
      break;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Appends one action to the run's record (/run pc_recovery, "; "-separated). */
static PetscErrorCode Record(RunStats *s, const char action[], KSPConvergedReason kreason)
{
  char item[160];

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(item, sizeof(item), "%s%s after %s", s->pc_recovery[0] ? "; " : "", action, KSPConvergedReasons[kreason]));
  PetscCall(PetscStrlcat(s->pc_recovery, item, sizeof(s->pc_recovery)));
  s->pc_breakdowns++;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* 3. A direct solve: LU (Cholesky for SBAIJ) by MUMPS, on the current Jacobian. */
static PetscErrorCode UseDirectSolve(SNES snes, PC pc)
{
  Mat       J;
  PetscBool is_sbaij;

  PetscFunctionBeginUser;
  PetscCall(SNESGetJacobian(snes, &J, NULL, NULL, NULL));
  PetscCall(PetscObjectTypeCompareAny((PetscObject)J, &is_sbaij, MATSEQSBAIJ, MATMPISBAIJ, ""));
  PetscCall(PCSetType(pc, is_sbaij ? PCCHOLESKY : PCLU));
  PetscCall(PCFactorSetMatSolverType(pc, MATSOLVERMUMPS));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* After a failed SNESSolve: if it ended on a breakdown and a recovery step is left, takes the next one and sets
 *retry (solve again from the last iterate); else leaves the failure as it is. reuse: the preconditioner's reuse, whose
   build is forgotten; stats: where the steps are recorded (/run pc_breakdowns and pc_recovery). */
PetscErrorCode PcRecoveryTry(PcRecovery *rec, SNES snes, const SolverOptions *opt, PcReuse *reuse, RunStats *stats, PetscBool *retry)
{
  MPI_Comm           comm = PetscObjectComm((PetscObject)snes);
  KSPConvergedReason kreason;
  PetscBool          breakdown, is_gamg, is_mg;
  KSP                ksp;
  PC                 pc;

  PetscFunctionBeginUser;
  *retry = PETSC_FALSE;
  if (!opt->pc_recovery || rec->stage >= 3) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(IsBreakdown(snes, &kreason, &breakdown));
  if (!breakdown) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(SNESGetKSP(snes, &ksp));
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(PetscObjectTypeCompare((PetscObject)pc, PCGAMG, &is_gamg));
  PetscCall(PetscObjectTypeCompare((PetscObject)pc, PCMG, &is_mg));
  PetscCall(PcReuseReset(reuse));               /* the next Newton step builds afresh, and builds only from then on */
  PetscCall(SNESSetLagPreconditioner(snes, 1)); /* (PcReuseDecide() sets the lag again where it takes over) */
  if (rec->stage == 0) {                        /* 1. a fresh build */
    rec->stage = 1;
    PetscCall(Record(stats, "preconditioner rebuilt", kreason));
    PetscCall(PetscPrintf(comm, "  preconditioner breakdown (%s): rebuilt on the current Jacobian, Newton goes on from its last iterate\n",
                          KSPConvergedReasons[kreason]));
  } else if (rec->stage == 1 && (is_gamg || is_mg)) { /* 2. safer smoother bounds */
    rec->stage = 2;
    if (is_gamg) { /* a new hierarchy whose smoothers estimate on their own operators, not from the aggregation's */
      PetscReal unfiltered = 0.0;

      PetscCall(PCSetType(pc, PCNONE)); /* the old hierarchy destroyed with its smoothers, whose SA estimates would stay */
      PetscCall(PCSetType(pc, PCGAMG));
      PetscCall(PCSetFromOptions(pc)); /* the options given for GAMG, as at the first set-up */
      PetscCall(PCGAMGSetUseSAEstEig(pc, PETSC_FALSE));
      PetscCall(PCGAMGSetThreshold(pc, &unfiltered, 1)); /* every level's graph whole: aggregates reach into the body */
    } else
      PetscCall(SaferChebyshev(pc)); /* the levels of the nested meshes stay */
    PetscCall(Record(stats, is_gamg ? "GAMG rebuilt with each level's own eigenvalue estimate and unfiltered graph" : "Chebyshev intervals widened",
                     kreason));
    PetscCall(PetscPrintf(comm, "  preconditioner breakdown (%s) again: %s, from the last iterate\n", KSPConvergedReasons[kreason],
                          is_gamg
                              ? "GAMG rebuilt, each level's smoother bounded by its own eigenvalue estimate, its aggregates on the unfiltered graph"
                              : "the smoothers' Chebyshev intervals widened"));
  } else { /* 3. a direct solve */
    rec->stage = 3;
    PetscCall(UseDirectSolve(snes, pc));
    PetscCall(Record(stats, "direct solve (MUMPS)", kreason));
    PetscCall(
        PetscPrintf(comm, "  preconditioner breakdown (%s) again: a direct solve (MUMPS) from the last iterate\n", KSPConvergedReasons[kreason]));
  }
  *retry = PETSC_TRUE;
  PetscFunctionReturn(PETSC_SUCCESS);
}
