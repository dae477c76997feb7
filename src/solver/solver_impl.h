/* The solver's own state, private to src/solver/: the context of the SNES's callbacks (residual, Jacobian, convergence
   test, monitor, the linear solves' pre-solve), which holds what they use and nothing of the rest of the run: the bulk
   operator K and r0, the Contact, the solver's options and the record its callbacks write; and the state of the linear
   acceleration they keep between Newton steps (preconditioner reuse and recovery, forcing terms, step guess), whose
   types and functions are the linear layer's (include/linear.h): the core calls it, never the reverse. One per
   problem: created by SolverCtxCreate() with the problem's operator, destroyed with the problem. */
#pragma once
#include "contact.h"
#include "linear.h"
#include "solver.h"

/* A warm solve with a way out (SolverSolveWarm()) stops, failed, once this many Newton steps have not halved |F|
   (SolverConverged()): it has stalled, and is solved again from zero. */
#define SOLVER_STALL_STEPS 6

/* The solver object (include/solver.h): the problem on the current mesh, which it owns, what its solves read (the
   Contact, the options, the nested meshes' multigrid and the box, which it does not), and their outcome, which it
   owns: the run's statistics and the table of solves (one record per solve, with its length and capacity). */
struct _n_Solver {
  Problem           prob;
  Contact           contact;
  const RunOptions *opt;
  Multigrid         mg;  /* the nested meshes' multigrid (-pc_type mg) */
  const MeshBox    *box; /* the box of the mesh options, whose levels the multigrid's are */
  RunStats          stats;
  SolveRecord      *records;
  PetscInt          nrecords, maxrecords;
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
  /* the linear acceleration's state (include/linear.h) */
  PcReuse         pc_reuse;
  PcRecovery      pc_recovery;
  SolverForcing   forcing;
  SolverStepGuess step_guess;
  LinearPreSolve  presolve;
};

/* The residual that -snes_rtol reduces (SolverConverged() in newton.c, and the forcing terms of src/linear/ew_forcing.c): the
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
void           SolverCtxLinearCore(SolverCtx sc, LinearCore *core);
PetscErrorCode SolverIterateDisplacement(SolverCtx sc, Vec X, Vec *u);
PetscErrorCode SolverResidual(SolverCtx sc, DM dm, Vec u, Vec F);

/* contact_monitor.c */
PetscErrorCode ContactMonitor(SNES snes, PetscInt it, PetscReal fnorm, void *ctx);

/* newton.c: the next solve's first linear solve starts from the Newton step du predicts (SolverStepGuessSet()) */
PetscErrorCode SolverSetStepGuess(SolverCtx sc, Vec du);
