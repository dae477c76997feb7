/* Options of the contact treatment and the penalty parameter eps. */
#include "app.h"
#include "physics.h"

const char *const ContactMethods[]     = {"penalty", "vi", "none", "ContactMethod", "CONTACT_", NULL};
const char *const PenaltyQuadratures[] = {"gauss", "nodal", "PenaltyQuadrature", "PENALTY_QUADRATURE_", NULL};
const char *const PenaltyModuli[]      = {"young", "pwave", "PenaltyModulus", "PENALTY_MODULUS_", NULL};

PetscErrorCode ContactGetOptions(MPI_Comm comm, ContactOptions *opts)
{
  PetscBool eps_set, sweep_set;

  PetscFunctionBeginUser;
  PetscOptionsBegin(comm, NULL, "Contact on Gamma_C", "Signorini");
  opts->method = CONTACT_PENALTY;
  PetscCall(PetscOptionsEnum("-contact_method", "Contact treatment: penalty, vi (SNESVI reference), none (no contact)", NULL, ContactMethods,
                             (PetscEnum)opts->method, (PetscEnum *)&opts->method, NULL));
  opts->quadrature = PENALTY_QUADRATURE_GAUSS;
  PetscCall(PetscOptionsEnum("-penalty_quadrature", "Quadrature of the penalty term: gauss (L2 product) or nodal (lumped, vertex rule)", NULL,
                             PenaltyQuadratures, (PetscEnum)opts->quadrature, (PetscEnum *)&opts->quadrature, NULL));
  opts->eps0 = 1.0;
  PetscCall(PetscOptionsReal("-penalty_eps0", "eps = eps0 h^power / M (M: -penalty_eps_modulus, E by default): the factor eps0", NULL, opts->eps0,
                             &opts->eps0, NULL));
  opts->eps_power = 1.0;
  PetscCall(
      PetscOptionsReal("-penalty_eps_power", "eps = eps0 h^power / M: the power of h, in [0, 4]", NULL, opts->eps_power, &opts->eps_power, NULL));
  opts->eps_local = PETSC_TRUE;
  PetscCall(PetscOptionsBool("-penalty_eps_local",
                             "eps from the local h: the diameter of the cell at each contact face (gauss) or the largest at each node (nodal)", NULL,
                             opts->eps_local, &opts->eps_local, NULL));
  opts->modulus = PENALTY_MODULUS_YOUNG;
  PetscCall(PetscOptionsEnum("-penalty_eps_modulus",
                             "Stiffness M of eps = eps0 h^power / M: young (E) or pwave (lambda + 2 mu, for nearly incompressible bodies)", NULL,
                             PenaltyModuli, (PetscEnum)opts->modulus, (PetscEnum *)&opts->modulus, NULL));
  opts->eps_fixed = 0.0;
  PetscCall(PetscOptionsReal("-penalty_eps", "Set eps directly (overrides eps0 and power)", NULL, opts->eps_fixed, &opts->eps_fixed, &eps_set));
  opts->monitor = PETSC_FALSE;
  PetscCall(
      PetscOptionsBool("-contact_monitor", "Print residual and active-set changes at each Newton step", NULL, opts->monitor, &opts->monitor, NULL));
  opts->continuation = PETSC_TRUE;
  PetscCall(PetscOptionsBool("-penalty_continuation", "Reach an eps below h/M through the sequence h/M, h/M f, h/M f^2, ... (warm starts)", NULL,
                             opts->continuation, &opts->continuation, NULL));
  opts->continuation_factor = 1e-2;
  PetscCall(PetscOptionsReal("-penalty_continuation_factor", "Ratio f of two consecutive eps of the continuation, in (0, 1)", NULL,
                             opts->continuation_factor, &opts->continuation_factor, NULL));
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
  PetscCall(PetscOptionsBool("-contact_pc_recovery",
                             "After a breakdown of the preconditioner (DIVERGED_INDEFINITE_PC, DIVERGED_PC_FAILED, ...), go on from the last "
                             "Newton iterate with a fresh build, then GMRES, then a direct solve (counted in /run pc_breakdowns)",
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
  PetscCall(OptionsCountListValues("-penalty_eps0_sweep", &opts->n_sweep));
  PetscCall(PetscCalloc1(opts->n_sweep + 1, &opts->eps0_sweep)); /* zeros: -help shows the first as the default */
  PetscCall(PetscOptionsRealArray("-penalty_eps0_sweep", "eps0 values solved in turn on the final mesh, each from the last solution", NULL,
                                  opts->eps0_sweep, &opts->n_sweep, &sweep_set));
  if (!sweep_set) opts->n_sweep = 0;
  opts->load_rtol = 1e-12;
  PetscCall(PetscOptionsReal("-contact_load_rtol",
                             "Newton also stops, converged, when |F| <= this times ||F(0)|| (the load): the residual is at round-off", NULL,
                             opts->load_rtol, &opts->load_rtol, NULL));
  PetscOptionsEnd();
  {
    const char *names[]  = {"-penalty_eps0",      "-penalty_eps_power",   "-penalty_eps",     "-penalty_continuation_factor",
                            "-contact_load_rtol", "-contact_coarse_rtol", "-contact_ew_guard"};
    PetscReal   values[] = {opts->eps0,      opts->eps_power,   opts->eps_fixed, opts->continuation_factor,
                            opts->load_rtol, opts->coarse_rtol, opts->ew_guard};

    for (size_t i = 0; i < sizeof(values) / sizeof(values[0]); ++i) PetscCall(OptionsCheckFinite(comm, names[i], values[i]));
    PetscCall(OptionsCheckFiniteArray(comm, "-penalty_eps0_sweep", opts->n_sweep, opts->eps0_sweep));
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
  PetscCheck(!sweep_set || opts->n_sweep > 0, comm, PETSC_ERR_USER_INPUT, "-penalty_eps0_sweep needs a comma-separated list of values");
  for (PetscInt k = 0; k < opts->n_sweep; ++k)
    PetscCheck(opts->eps0_sweep[k] > 0.0, comm, PETSC_ERR_USER_INPUT, "-penalty_eps0_sweep: every value must be positive, got %g",
               (double)opts->eps0_sweep[k]);
  PetscCheck(!(sweep_set && eps_set), comm, PETSC_ERR_USER_INPUT, "-penalty_eps0_sweep cannot be given together with -penalty_eps");
  PetscCheck(!sweep_set || opts->method == CONTACT_PENALTY, comm, PETSC_ERR_USER_INPUT, "-penalty_eps0_sweep needs -contact_method penalty");
  if (opts->n_sweep) opts->eps0 = opts->eps0_sweep[0]; /* the sweep starts with its first value, in place of -penalty_eps0 */
  PetscCheck(opts->pc_update_truncate >= 0.0, comm, PETSC_ERR_USER_INPUT, "-contact_pc_update_truncate must be >= 0 (0: never), got %g",
             (double)opts->pc_update_truncate);
  PetscCheck(opts->pc_reuse_changes >= 0, comm, PETSC_ERR_USER_INPUT, "-contact_pc_reuse_changes must be >= 0, got %" PetscInt_FMT,
             opts->pc_reuse_changes);
  PetscCheck(opts->continuation_factor > 0.0 && opts->continuation_factor < 1.0, comm, PETSC_ERR_USER_INPUT,
             "-penalty_continuation_factor must lie in (0, 1), got %g", (double)opts->continuation_factor);
  PetscCheck(opts->eps0 > 0.0, comm, PETSC_ERR_USER_INPUT, "-penalty_eps0 must be positive, got %g", (double)opts->eps0);
  PetscCheck(opts->eps_power >= 0.0 && opts->eps_power <= 4.0, comm, PETSC_ERR_USER_INPUT, "-penalty_eps_power must lie in [0, 4], got %g",
             (double)opts->eps_power);
  PetscCheck(!eps_set || opts->eps_fixed > 0.0, comm, PETSC_ERR_USER_INPUT, "-penalty_eps must be positive, got %g", (double)opts->eps_fixed);
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode ContactOptionsDestroy(ContactOptions *opts)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree(opts->eps0_sweep));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* M of eps = eps0 h^power / M: E, or the P-wave modulus lambda + 2 mu, which grows without bound as nu -> 1/2. */
PetscReal ContactPenaltyModulus(const AppCtx *user)
{
  return user->opt.contact.modulus == PENALTY_MODULUS_PWAVE ? user->opt.material.lambda + 2.0 * user->opt.material.mu
                                                            : user->opt.material.young_modulus;
}

/* eps = eps0 h^power / M (Corollary 3.3 takes eps = h), or the fixed -penalty_eps. */
PetscErrorCode ContactComputeEps(AppCtx *user)
{
  PetscFunctionBeginUser;
  if (user->opt.contact.eps_fixed > 0.0)
    user->prob.eps = user->opt.contact.eps_fixed;
  else
    user->prob.eps = user->opt.contact.eps0 * PetscPowReal(user->prob.h, user->opt.contact.eps_power) / ContactPenaltyModulus(user);
  /* the penalty term multiplies by 1/eps: an eps that underflows (eps0 = 1e-320) or overflows would make it inf or 0 */
  PetscCheck(user->opt.contact.method != CONTACT_PENALTY || (user->prob.eps >= 1e-290 && user->prob.eps <= 1e290), PETSC_COMM_WORLD,
             PETSC_ERR_USER_INPUT,
             "eps = %g (-penalty_eps0 %g, -penalty_eps %g, h = %g, modulus %g) is outside [1e-290, 1e290]: the penalty 1/eps would overflow "
             "or vanish in double precision; give another -penalty_eps0 or -penalty_eps",
             (double)user->prob.eps, (double)user->opt.contact.eps0, (double)user->opt.contact.eps_fixed, (double)user->prob.h,
             (double)ContactPenaltyModulus(user));
  PetscFunctionReturn(PETSC_SUCCESS);
}
