/* The linear acceleration (src/linear/): what the Newton core (src/solver/) adds to the linear solves of its Newton
 * steps: the preconditioner's reuse and the updates of a GAMG hierarchy (pc_reuse.c, smoother_bound.c), the recovery
 * from preconditioner breakdowns (pc_recovery.c), the finest multigrid smoother's options (fine_smoother.c), the forcing
 * terms of the inexact Newton (ew_forcing.c), the step guess (step_guess.c), the geometric multigrid of the nested
 * meshes (multigrid.c) and the solver's options (solver_options.c). A layer below the core: each component takes its
 * own state and what it reads (the Contact, the options, the record, the SNES's scale); the core keeps the states in
 * its context (src/solver/solver_impl.h). The components that act at each Newton step or linear solve attach
 * themselves to PETSc's hooks (the SNES's Jacobian evaluation, the KSP's pre-solve) and read the core through a
 * LinearCore; the core's own callbacks call none of them. */
#pragma once
#include "signorini.h"

/* What the linear layer reads of the Newton core while it solves, through two of the core's functions, so that it does
   not see the core's context: the displacement of an iterate X of the SNES in the user's units (the SNES's scaling and
   SNESVI's rotated frames), and the current solve's stopping reference (the residual -snes_rtol is relative to) and the
   SNES's scale. */
typedef struct {
  PetscErrorCode (*displacement)(void *core, Vec X, Vec *u);
  PetscErrorCode (*scales)(void *core, PetscReal *stop_reference, PetscReal *snes_scale);
  void *core;
} LinearCore;

/* State of the preconditioner reuse (pc_reuse.c). */
typedef struct {
  /* how it is attached (PcReuseAttach()): around the SNES's Jacobian evaluation, the core's, with what it reads of the core */
  LinearCore core;
  PetscErrorCode (*jacobian)(SNES, Vec, Mat, Mat, void *);
  void *jacobian_ctx;
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
  PetscInt stage; /* recovery steps taken: 0 none, 1 rebuilt, 2 safer smoother bounds (a multigrid), 3 direct */
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

/* solver_options.c: the solver's options, read once before any set-up */
PetscErrorCode SolverGetOptions(MPI_Comm comm, SolverOptions *opts);
PetscErrorCode SolverGivenIndex(const char prefix[], PetscInt *k);

/* pc_reuse.c: attached around the SNES's Jacobian evaluation, it decides before each Jacobian's assembly whether the
   preconditioner is built again, and after it records the build's contact rows or updates the GAMG hierarchy */
PetscErrorCode PcReuseSetUp(PcReuse *r, Mat K, Contact contact, const SolverOptions *opt);
PetscErrorCode PcReuseAttach(PcReuse *r, SNES snes, const LinearCore *core);
PetscErrorCode PcReuseDestroy(PcReuse *r);

/* pc_recovery.c: after a failed SNESSolve */
PetscErrorCode PcRecoveryTry(PcRecovery *rec, SNES snes, const SolverOptions *opt, PcReuse *reuse, RunStats *stats, PetscBool *retry);

/* The linear layer's KSP pre-solve (presolve.c): before each linear solve, the finest smoother's -mg_fine_ options,
   the step guess and the forcing term, in that order. */
typedef struct {
  const SolverGiven *given;
  SolverStepGuess   *step_guess;
  SolverForcing     *forcing;
  LinearCore         core;
} LinearPreSolve;
PetscErrorCode LinearPreSolveAttach(LinearPreSolve *ps, KSP ksp, const SolverGiven *given, SolverStepGuess *sg, SolverForcing *fc,
                                    const LinearCore *core);

/* ew_forcing.c, step_guess.c, fine_smoother.c: at the SNES's set-up, and before each linear solve (LinearPreSolve) */
PetscErrorCode SolverForcingSetUp(SolverForcing *fc, SNES snes, PetscReal guard, PetscBool *petsc_presolve);
PetscErrorCode SolverForcingPreSolve(SolverForcing *fc, KSP ksp, PetscReal ref, PetscReal snes_scale);
PetscErrorCode SolverStepGuessSetUp(SolverStepGuess *sg, KSP ksp, const SolverGiven *given);
PetscErrorCode SolverStepGuessSet(SolverStepGuess *sg, Vec du);
PetscErrorCode SolverStepGuessPreSolve(SolverStepGuess *sg, KSP ksp, Vec x, PetscReal snes_scale);
PetscErrorCode SolverStepGuessDrop(SolverStepGuess *sg);
/* -mg_fine_ksp_*, -mg_fine_pc_* */
PetscErrorCode FineSmootherGiven(KSP ksp, const SolverGiven *g, PetscBool *given);
PetscErrorCode FineSmootherSetUp(KSP ksp, const SolverGiven *g);

/* multigrid.c: the levels of -pc_type mg over the nested meshes (level: the problem's grid level; box: the mesh of the options) */
PetscErrorCode MultigridCreate(PetscBool coarse_mg, Multigrid *mg);
PetscErrorCode MultigridDestroy(Multigrid *mg);
PetscErrorCode MultigridSetDefault(Multigrid mg, PetscBool is_default);
PetscBool      MultigridIsDefault(Multigrid mg);
PetscErrorCode MultigridAddLevel(Multigrid mg, SNES snes, DM coarse, DM fine, const PetscInt vertex_source[], PetscInt degree);
PetscErrorCode MultigridSetUpPC(Multigrid mg, SNES snes, PetscInt level, const MeshBox *box, const SolverOptions *opt);
PetscErrorCode MultigridSetCoarseBoxSolver(Multigrid mg, KSP ksp, PetscInt level, const MeshBox *box);
