/* Options of the nonlinear solve around the contact: the monitor, the preconditioner's reuse, updates and recovery,
   nested iteration, the inexact Newton's guard and the round-off stop. Read once, before any set-up. */
#include "app.h"
#include "linear.h"

static const char *const solver_ksp_prefixes[SOLVER_KSP_PREFIXES] = {"", "contact_coarse_"};

/* PETSc's options that change the project's defaults when given (SolverGiven), under each prefix the solver's objects
   can have. Only their presence (and a few values) is read here; PETSc reads them itself when it sets its objects up. */
static PetscErrorCode SolverReadGiven(SolverGiven *g)
{
  PetscFunctionBeginUser;
  PetscCall(PetscOptionsHasName(NULL, NULL, "-mat_type", &g->mat_type));
  PetscCall(PetscOptionsHasName(NULL, NULL, "-snes_ksp_ew", &g->snes_ksp_ew));
  PetscCall(PetscOptionsHasName(NULL, NULL, "-snes_ksp_ew_rtolmax", &g->snes_ksp_ew_rtolmax));
  PetscCall(PetscOptionsGetString(NULL, NULL, "-pc_type", g->pc_type, sizeof(g->pc_type), &g->pc_type_given));
  for (PetscInt k = 0; k < SOLVER_KSP_PREFIXES; ++k) {
    const char *pre = k ? solver_ksp_prefixes[k] : NULL;

    PetscCall(PetscOptionsHasName(NULL, pre, "-ksp_norm_type", &g->ksp_norm_type[k]));
    PetscCall(PetscOptionsHasName(NULL, pre, "-ksp_converged_use_initial_residual_norm", &g->use_initial_rnorm[k]));
    PetscCall(PetscOptionsHasName(NULL, pre, "-pc_mg_levels", &g->pc_mg_levels[k]));
    PetscCall(PetscOptionsHasName(NULL, pre, "-pc_mg_galerkin", &g->pc_mg_galerkin[k]));
    PetscCall(PetscOptionsHasName(NULL, pre, "-mg_fine_ksp_type", &g->fine_ksp_type[k]));
    PetscCall(PetscOptionsHasName(NULL, pre, "-mg_fine_pc_type", &g->fine_pc_type[k]));
    for (PetscInt l = 0; l <= MULTIGRID_MAX_LEVELS; ++l) {
      const PetscInt e = k * (MULTIGRID_MAX_LEVELS + 1) + l;
      char           name[96];
      PetscBool      set;

      if (l == MULTIGRID_MAX_LEVELS)
        PetscCall(PetscSNPrintf(g->esteig_prefix[e], sizeof(g->esteig_prefix[e]), "%smg_fine_", solver_ksp_prefixes[k]));
      else
        PetscCall(PetscSNPrintf(g->esteig_prefix[e], sizeof(g->esteig_prefix[e]), "%smg_levels_%d_", solver_ksp_prefixes[k], (int)l));
      PetscCall(PetscSNPrintf(name, sizeof(name), "-%sksp_chebyshev_esteig", g->esteig_prefix[e]));
      g->esteig_n[e] = 4;
      PetscCall(PetscOptionsGetRealArray(NULL, NULL, name, g->esteig[e], &g->esteig_n[e], &set));
      if (!set) g->esteig_n[e] = 0;
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The index in SolverGiven of an object's options prefix (NULL or "": the solve's; "contact_coarse_": the coarser boxes'). */
PetscErrorCode SolverGivenIndex(const char prefix[], PetscInt *k)
{
  PetscBool same;

  PetscFunctionBeginUser;
  for (*k = 0; *k < SOLVER_KSP_PREFIXES; ++*k) {
    PetscCall(PetscStrcmp(prefix ? prefix : "", solver_ksp_prefixes[*k], &same));
    if (same) PetscFunctionReturn(PETSC_SUCCESS);
  }
  SETERRQ(PETSC_COMM_SELF, PETSC_ERR_PLIB, "options prefix %s is none of the solver's", prefix);
}

/* The -ksp_chebyshev_esteig given for a multigrid smoother with options prefix prefix (the solve's or the coarser boxes'
   mg_levels_N_ or mg_fine_): *n values in t (0: not given). */
PetscErrorCode SolverGivenEsteig(const SolverGiven *g, const char prefix[], PetscInt *n, PetscReal t[])
{
  PetscFunctionBeginUser;
  *n = 0;
  for (PetscInt e = 0; e < SOLVER_KSP_PREFIXES * (MULTIGRID_MAX_LEVELS + 1); ++e) {
    PetscBool same;

    PetscCall(PetscStrcmp(prefix ? prefix : "", g->esteig_prefix[e], &same));
    if (!same) continue;
    *n = g->esteig_n[e];
    PetscCall(PetscArraycpy(t, g->esteig[e], *n));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  SETERRQ(PETSC_COMM_SELF, PETSC_ERR_PLIB, "smoother options prefix %s is none of the solver's", prefix);
}

PetscErrorCode SolverGetOptions(MPI_Comm comm, SolverOptions *opts)
{
  PetscFunctionBeginUser;
  PetscCall(SolverReadGiven(&opts->given));
  PetscOptionsBegin(comm, NULL, "Nonlinear solve", "Signorini");
  opts->monitor = PETSC_FALSE;
  PetscCall(
      PetscOptionsBool("-contact_monitor", "Print residual and active-set changes at each Newton step", NULL, opts->monitor, &opts->monitor, NULL));
  opts->condition_estimate = PETSC_FALSE;
  PetscCall(PetscOptionsBool("-contact_condition_estimate", "Estimate the 1-norm condition number of the final Jacobian (a few extra solves)", NULL,
                             opts->condition_estimate, &opts->condition_estimate, NULL));
  opts->cycle_damping = PETSC_TRUE;
  PetscCall(PetscOptionsBool("-contact_cycle_damping",
                             "Damp the next Newton step by 1/2 when the active set cycles (the cycle is reported either way)", NULL,
                             opts->cycle_damping, &opts->cycle_damping, NULL));
  opts->pc_reuse = PETSC_TRUE;
  PetscCall(PetscOptionsBool("-contact_pc_reuse",
                             "Penalty: reuse the preconditioner (or factorization) of an earlier Newton step while few contact nodes changed "
                             "state (needs a Krylov method, not -ksp_type preonly)",
                             NULL, opts->pc_reuse, &opts->pc_reuse, NULL));
  opts->pc_recovery = PETSC_TRUE;
  PetscCall(PetscOptionsBool(
      "-contact_pc_recovery",
      "After a breakdown of the preconditioner (DIVERGED_INDEFINITE_PC, DIVERGED_PC_FAILED, ...), go on from the last "
      "Newton iterate with a fresh build, then safer smoother bounds for a multigrid, then a direct solve (counted in /run pc_breakdowns)",
      NULL, opts->pc_recovery, &opts->pc_recovery, NULL));
  opts->pc_reuse_changes = 20;
  PetscCall(PetscOptionsInt("-contact_pc_reuse_changes", "Rebuild when more contact nodes than this changed state since the last build", NULL,
                            opts->pc_reuse_changes, &opts->pc_reuse_changes, NULL));
  opts->pc_update = PETSC_TRUE;
  PetscCall(PetscOptionsBool("-contact_pc_update",
                             "Penalty with GAMG: build the hierarchy once and update its coarse operators by the Galerkin products of the "
                             "Jacobian's change in the contact rows, instead of rebuilds",
                             NULL, opts->pc_update, &opts->pc_update, NULL));
  opts->pc_update_check = PETSC_FALSE;
  PetscCall(PetscOptionsBool("-contact_pc_update_check",
                             "After each update, print each coarse operator's distance to the Galerkin product of the level above computed in full",
                             NULL, opts->pc_update_check, &opts->pc_update_check, NULL));
  opts->pc_update_esteig = PETSC_FALSE;
  PetscCall(PetscOptionsBool("-contact_pc_update_esteig",
                             "With the updates: the finest level's Chebyshev smoother estimates its eigenvalues again at each update, "
                             "instead of keeping the build's interval when the penalty term provably does not raise them",
                             NULL, opts->pc_update_esteig, &opts->pc_update_esteig, NULL));
  opts->pc_update_truncate = 10.0;
  PetscCall(PetscOptionsReal("-contact_pc_update_truncate",
                             "With the updates: the coarse operators leave out the contact dofs whose penalty diagonal exceeds this times "
                             "K's diagonal (Jacobi smooths them alone), so that a small eps does not stiffen the coarse spaces; 0: never",
                             NULL, opts->pc_update_truncate, &opts->pc_update_truncate, NULL));
  opts->pc_update_changes = 50;
  PetscCall(PetscOptionsInt("-contact_pc_update_changes",
                            "With the updates: a Newton step at which at most this many contact nodes changed state since the coarse operators "
                            "last followed the Jacobian (and whose last linear solve stayed cheap) updates the finest level only; 0: every step "
                            "updates every level",
                            NULL, opts->pc_update_changes, &opts->pc_update_changes, NULL));
  opts->grid_sequence = 0;
  PetscCall(PetscOptionsInt("-contact_grid_sequence",
                            "Nested iteration: solve on the mesh, then on N uniform refinements of it, each from the interpolated last solution",
                            NULL, opts->grid_sequence, &opts->grid_sequence, NULL));
  opts->coarse_levels = -1;
  PetscCall(PetscOptionsInt("-contact_coarse_levels",
                            "Nested iteration to the mesh of the options: solve first on this many coarser boxes, each with half the cells per "
                            "side of the next, each from the last; -1: as many as keep 64 cells per side (16 with -pc_type mg or "
                            "-contact_coarse_mg), where the mesh is the 2D P1 simplex box and the method penalty (or the elastic solve with "
                            "-pc_type mg), else 0",
                            NULL, opts->coarse_levels, &opts->coarse_levels, NULL));
  opts->coarse_rtol = 1e-4;
  PetscCall(PetscOptionsReal("-contact_coarse_rtol",
                             "Newton's relative tolerance on the coarser boxes of -contact_coarse_levels (their solutions are only initial guesses; "
                             "the final mesh keeps -snes_rtol)",
                             NULL, opts->coarse_rtol, &opts->coarse_rtol, NULL));
  opts->coarse_mg = PETSC_TRUE;
  PetscCall(PetscOptionsBool("-contact_coarse_mg",
                             "With an iterative -pc_type other than mg (gamg, hypre, ...): the coarser boxes of -contact_coarse_levels are solved by "
                             "CG with the geometric multigrid of the boxes below them (options prefix -contact_coarse_), the final mesh by the "
                             "options' solver; 0: every box by the options' solver",
                             NULL, opts->coarse_mg, &opts->coarse_mg, NULL));
  opts->ew_guard = 0.5;
  PetscCall(PetscOptionsReal("-contact_ew_guard",
                             "Inexact Newton (Eisenstat-Walker, version 2): no linear solve tighter than this times Newton's stopping residual / |F| "
                             "(the guard against oversolving; 0: PETSc's terms)",
                             NULL, opts->ew_guard, &opts->ew_guard, NULL));
  opts->load_rtol = 1e-12;
  PetscCall(PetscOptionsReal("-contact_load_rtol",
                             "Newton also stops, converged, when |F| <= this times ||F(0)|| (the load): the residual is at round-off", NULL,
                             opts->load_rtol, &opts->load_rtol, NULL));
  PetscOptionsEnd();
  {
    const char *names[]  = {"-contact_load_rtol", "-contact_coarse_rtol", "-contact_ew_guard"};
    PetscReal   values[] = {opts->load_rtol, opts->coarse_rtol, opts->ew_guard};

    for (size_t i = 0; i < sizeof(values) / sizeof(values[0]); ++i) PetscCall(OptionsCheckFinite(comm, names[i], values[i]));
  }
  PetscCheck(opts->load_rtol >= 0.0 && opts->load_rtol < 1.0, comm, PETSC_ERR_USER_INPUT, "-contact_load_rtol must lie in [0, 1), got %g",
             (double)opts->load_rtol);
  PetscCheck(opts->grid_sequence >= 0 && opts->grid_sequence <= 8, comm, PETSC_ERR_USER_INPUT,
             "-contact_grid_sequence must lie in [0, 8], got %" PetscInt_FMT, opts->grid_sequence);
  PetscCheck(opts->coarse_levels >= -1 && opts->coarse_levels <= 8, comm, PETSC_ERR_USER_INPUT,
             "-contact_coarse_levels must lie in [-1, 8] (-1: automatic), got %" PetscInt_FMT, opts->coarse_levels);
  PetscCheck(opts->coarse_rtol > 0.0 && opts->coarse_rtol < 1.0, comm, PETSC_ERR_USER_INPUT, "-contact_coarse_rtol must lie in (0, 1), got %g",
             (double)opts->coarse_rtol);
  PetscCheck(opts->ew_guard >= 0.0 && opts->ew_guard <= 1.0, comm, PETSC_ERR_USER_INPUT, "-contact_ew_guard must lie in [0, 1], got %g",
             (double)opts->ew_guard);
  PetscCheck(opts->pc_update_truncate >= 0.0, comm, PETSC_ERR_USER_INPUT, "-contact_pc_update_truncate must be >= 0 (0: never), got %g",
             (double)opts->pc_update_truncate);
  PetscCheck(opts->pc_update_changes >= 0, comm, PETSC_ERR_USER_INPUT,
             "-contact_pc_update_changes must be >= 0 (0: every step updates every level), got %" PetscInt_FMT, opts->pc_update_changes);
  PetscCheck(opts->pc_reuse_changes >= 0, comm, PETSC_ERR_USER_INPUT, "-contact_pc_reuse_changes must be >= 0, got %" PetscInt_FMT,
             opts->pc_reuse_changes);
  PetscFunctionReturn(PETSC_SUCCESS);
}
