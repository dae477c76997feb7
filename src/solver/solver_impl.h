/* The solver's own state, private to src/solver/: the context of the SNES's callbacks (residual, Jacobian, convergence
   test, monitor, the linear solves' pre-solve), which holds what they use and nothing of the rest of the run: the bulk
   operator K and r0, the Contact, the solver's options and the record its callbacks write; and the acceleration state
   they keep between Newton steps (preconditioner reuse and recovery, forcing terms, step guess). One per problem:
   created by SolverCtxCreate() with the problem's operator, destroyed with the problem. */
#pragma once
#include "contact.h"
#include "solver.h"

/* A warm solve with a way out (SolverSolveWarm()) stops, failed, once this many Newton steps have not halved |F|
   (SolverConverged()): it has stalled, and is solved again from zero. */
#define SOLVER_STALL_STEPS 6

/* State of the preconditioner reuse (pc_reuse.c). */
typedef struct {
  /* what it reads (PcReuseSetUp()) */
  Mat                  K;       /* the bulk operator, in which the Jacobian is made */
  Contact              contact; /* the contact term, its rows of K (ContactBulkRowsOf()) */
  const SolverOptions *opt;
  /* the reuse */
  PetscBool enabled;         /* penalty method with a Krylov method around the preconditioner */
  PetscBool built;           /* a build exists */
  PetscReal eps;             /* eps of the build */
  PetscInt  its_after_build; /* Krylov iterations of the first solve after the build (-1: not yet known) */
  PetscInt  builds;          /* builds so far */
  /* -contact_pc_update: after the first build of a GAMG hierarchy, each new Jacobian changes the coarse operators by
     the Galerkin products of its change, which lives in the contact rows only (the bulk matrix is constant) */
  PetscBool    update;     /* the hierarchy exists and follows the Jacobian */
  PetscBool    no_update;  /* updates given up after a preconditioner breakdown (pc_recovery.c): builds only */
  PetscBool    record;     /* the Jacobian being assembled is the one of a build: record its contact rows */
  PetscBool    recorded;   /* they are (on every rank alike) */
  PetscInt     updates;    /* updates so far */
  PetscScalar *built_vals; /* the Jacobian's values in the contact rows (K's pattern, bulk_ptr) at the last build or update */
  PetscScalar *dvals;      /* their change since then, the values of dlocal */
  Mat          rlocal;     /* the finest prolongator's rows at the columns S of the contact rows (from any rank) */
  Mat          dlocal;     /* the change of the Jacobian since then, on S x S (nonzero in the contact rows only) */
  Mat          clocal;     /* this rank's part of its product on the first coarse level */
  PetscInt     nlevels;
  Mat         *dcoarse; /* [nlevels - 1]: the change on the coarser levels, coarsest first */
  /* -contact_pc_update_truncate: the finest prolongator R has zero rows at the penalty-dominated contact dofs Z, so the
     coarse operators are R^T J' R, J' the Jacobian with the rows and columns Z set to zero (R the build's), and dlocal also holds the
     columns Z of the rows that are not contact rows: the mirrors of the contact rows' entries there */
  PetscInt     nmirror;              /* those entries */
  PetscInt    *mirror_k;             /* [nmirror]: the contact-row entry (bulk_ptr numbering) each one mirrors, */
  PetscInt    *mirror_at;            /*   and that row's place among the columns (bulk_x) */
  PetscScalar *eff_vals;             /* [nnz + nmirror]: J' at dlocal's entries, as the coarse operators hold it */
  PetscScalar *eff_dvals;            /* [nnz + nmirror]: its change, the values of dlocal */
  PetscInt     nz;                   /* owned rows in Z */
  PetscInt    *zrows;                /* [nbulk_rows]: their global numbers */
  Mat          rfine;                /* the finest prolongator, whose rows Z are set to zero, */
  PetscInt    *rrow_ptr, *rrow_cols; /*   its rows at the owned contact rows (CSR, global columns), */
  PetscScalar *rrow_vals;            /*   with their values as GAMG made them */
  Vec          zmark, zcols;         /* 0 outside the contact rows, 1 in them, 2 in Z; and those marks at the contact rows' columns */
  /* the finest level's Chebyshev interval, bounded instead of estimated again at each update (SmootherBoundFinest(), smoother_bound.c) */
  PetscBool  built_on_K;       /* the build's Jacobian was K itself in the contact rows (no penalty term yet) */
  PetscBool  bound_set;        /* the build's estimate has been read, and the bound applies */
  PetscBool  bound_read;       /* ... has been looked for */
  PetscReal  est_min, est_max; /* the build's Chebyshev estimate of the extreme eigenvalues of diag(K)^-1 K */
  PetscInt   est_steps;        /* the steps of its estimator */
  PetscBool *built_active;     /* the contact nodes' penetration when the preconditioner was last built */
  /* -contact_pc_update_changes: the coarse operators stay while few contact nodes changed since they followed the Jacobian */
  PetscBool *carried_active;  /* the contact nodes' penetration when the coarse operators last followed the Jacobian */
  PetscInt   its_after_carry; /* Krylov iterations of the first solve after that (-1: not yet known) */
  PetscReal  carried_eps;     /* eps then */
  PetscReal  carry_cost;      /* the flops of the last carried update: its products, and its coarse smoothers' eigenvalue estimates */
  PetscReal  cycle_cost;      /* the flops of a CG iteration with the hierarchy's V-cycle (0: not yet counted) */
  PetscReal  coarse_nnz;      /* the nonzeros of its coarse operators */
  PetscBool  finest_only;     /* this Newton step updates the finest level only */
  PetscInt   finest_updates;  /* such updates so far */
  PetscReal  tform[4];        /* Chebyshev's transform of estimates into its interval (-ksp_chebyshev_esteig) */
  Vec        pdiag, pcols;    /* the penalty term's diagonal, and its values at the contact rows' columns */
} PcReuse;

/* State of the recovery from preconditioner breakdowns (pc_recovery.c). */
typedef struct {
  PetscInt stage; /* recovery steps taken: 0 none, 1 rebuilt, 2 GMRES, 3 direct */
} PcRecovery;

/* The forcing terms of the inexact Newton (ew_forcing.c): Eisenstat-Walker's, with the guard against oversolving. */
typedef struct {
  SNES      snes;                 /* the problem's SNES (not referenced) */
  PetscReal guard;                /* -contact_ew_guard: no linear solve below guard * Newton's target / |F| (0: none) */
  PetscReal norm_last, rtol_last; /* |F| and the linear tolerance of the last step */
} SolverForcing;

/* A predicted Newton step for the first linear solve of the next solve (step_guess.c). */
typedef struct {
  Vec       du;          /* the predicted change of the solution, in the user's units; NULL if none */
  PetscBool nonzero;     /* the options' -ksp_initial_guess_nonzero, kept by every other linear solve */
  PetscBool user_rnorm0; /* -ksp_converged_use_initial_residual_norm given: the options' test stays */
} SolverStepGuess;

/* The interpolations between the nested meshes solved so far (multigrid.c): the levels of a geometric multigrid
   (-pc_type mg) on the mesh of the current problem, which has n + 1 of them. */
struct _n_Multigrid {
  PetscInt  n;
  Mat       interp[MULTIGRID_MAX_LEVELS]; /* [l]: from the global vector of mesh l to that of mesh l + 1 */
  PetscBool coarse_mg;                    /* the coarser boxes are solved with the geometric multigrid of the boxes below */
  PetscBool is_default;                   /* it is the default linear solver (no -pc_type; the 3D box that nests) */
};

struct _n_SolverCtx {
  /* the problem the callbacks solve: F(u) = K u + r0 + (contact term) */
  Mat                  K;       /* the bulk operator (the Jacobian is made in it: ContactComputeJacobian()) */
  Vec                  r0;      /* F(0) without the contact term */
  Contact              contact; /* the contact term */
  const SolverOptions *opt;
  RunStats            *stats;              /* where the callbacks record: residual, active-set cycles, breakdowns */
  PetscReal            load_norm;          /* ||F(0)||, the problem's load */
  PetscReal            displacement_scale; /* U: the SNES iterates on u/U */
  /* the Newton iteration */
  PetscReal  snes_scale;                           /* U inside SolverSolve(), 1 outside it (so -dmsnes_check and the estimates see u itself) */
  Vec        work;                                 /* U x~: the displacement of the SNES iterate x~ */
  PetscReal  fnorm0;                               /* |F| at the start of the last SNESSolve, in the user's units */
  PetscReal  fnorm_last;                           /* |F| at the last Newton step, in the user's units */
  PetscBool  roundoff_stop;                        /* the last SNESSolve stopped at the round-off of its terms (SolverConverged()) */
  PetscBool  warm;                                 /* the last SolverSolve() started from a given guess, not from zero */
  PetscBool  stall_stop;                           /* the current solve is SolverSolveWarm()'s: it stops where it stalls */
  PetscReal  step_energy_stop;                     /* Newton stops once a step's energy norm is below this (0: never; adapt.c), */
  PetscBool  energy_stop;                          /*   and the last SNESSolve did (SolverConverged()) */
  PetscReal  fnorm_window[SOLVER_STALL_STEPS + 1]; /* |F| of its last Newton steps (a ring), for that test */
  PetscInt64 active_history[CONTACT_HISTORY];      /* active-set hashes of the Newton steps of the current solve, */
  PetscReal  fnorm_history[CONTACT_HISTORY];       /*   and their residual norms */
  /* acceleration */
  PcReuse         pc_reuse;
  PcRecovery      pc_recovery;
  SolverForcing   forcing;
  SolverStepGuess step_guess;
};

/* The residual that -snes_rtol reduces (SolverConverged() in newton.c, and the forcing terms of ew_forcing.c): the
   load ||F(0)|| for a warm start (eps sweep, nested iteration), else the first residual of the solve; user's units. */
static inline PetscReal SolverStopReference(SolverCtx sc)
{
  return sc->warm ? sc->load_norm : sc->fnorm0;
}

/* newton.c: the callbacks */
PetscErrorCode SolverCtxCreate(Mat K, Vec r0, Contact contact, const SolverOptions *opt, RunStats *stats, SolverCtx *sc);
PetscErrorCode SolverCtxDestroy(SolverCtx *sc);
PetscErrorCode SolverFormFunction(SNES snes, Vec X, Vec F, void *ctx);
PetscErrorCode SolverFormJacobian(SNES snes, Vec X, Mat J, Mat P, void *ctx);
PetscErrorCode SolverConverged(SNES snes, PetscInt it, PetscReal xnorm, PetscReal snorm, PetscReal fnorm, SNESConvergedReason *reason, void *ctx);
PetscErrorCode SolverPreSolve(KSP ksp, Vec b, Vec x, void *ctx);
PetscErrorCode SolverIterateDisplacement(SolverCtx sc, Vec X, Vec *u);
PetscErrorCode SolverResidual(SolverCtx sc, DM dm, Vec u, Vec F);

/* contact_monitor.c */
PetscErrorCode ContactMonitor(SNES snes, PetscInt it, PetscReal fnorm, void *ctx);

/* ew_forcing.c */
PetscErrorCode SolverForcingSetUp(SolverForcing *fc, SNES snes, PetscReal guard, PetscBool *petsc_presolve);
PetscErrorCode SolverForcingPreSolve(SolverForcing *fc, KSP ksp, PetscReal ref, PetscReal snes_scale);

/* step_guess.c */
PetscErrorCode SolverStepGuessSetUp(SolverStepGuess *sg, KSP ksp, const SolverGiven *given);
PetscErrorCode SolverStepGuessSet(SolverStepGuess *sg, Vec du);
PetscErrorCode SolverStepGuessPreSolve(SolverStepGuess *sg, KSP ksp, Vec x, PetscReal snes_scale);
PetscErrorCode SolverStepGuessDrop(SolverStepGuess *sg);
/* newton.c: the next solve's first linear solve starts from the Newton step du predicts (SolverStepGuessSet()) */
PetscErrorCode SolverSetStepGuess(SolverCtx sc, Vec du);

/* extrapolated_start.c */
PetscErrorCode SolverExtrapolatedStart(SNES snes, DM dm, AppCtx *user, Vec u, Vec dir, PetscReal factor, PetscReal relaxed, PetscBool step_guess);
PetscErrorCode SolverSecantStart(SNES snes, DM dm, AppCtx *user, Vec u, Vec prev, Vec dir, PetscBool use, PetscReal factor, PetscReal relaxed);

/* pc_reuse.c */
PetscErrorCode PcReuseSetUp(PcReuse *r, Mat K, Contact contact, const SolverOptions *opt);
PetscErrorCode PcReuseDecide(PcReuse *r, SNES snes, DM dm, Vec X);
PetscErrorCode PcReuseAfterJacobian(PcReuse *r, SNES snes);
PetscErrorCode PcReuseDestroy(PcReuse *r);
PetscErrorCode PcReuseReset(PcReuse *r);

/* pc_recovery.c */
PetscErrorCode PcRecoveryTry(PcRecovery *rec, SNES snes, const SolverOptions *opt, PcReuse *reuse, RunStats *stats, PetscBool *retry);

/* smoother_bound.c */
PetscErrorCode SmootherBoundFinest(PcReuse *r, PC pc, PetscInt nlevels, const PetscScalar jvals[], PetscBool check);
