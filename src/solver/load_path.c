/* A load path (-load_steps N, -load_path t1,t2,...): the problem solved at a sequence of load factors on the final
   mesh, each step from the last step's solution. Every prescribed datum scales with the factor (SceneSetLoadFactor():
   the loads, the clamps' and slips' translations, the obstacle's translation; not the initial gap). Frictionless linear
   elasticity has no history, so each step's answer is the direct solve's at its factor: the path only gives each
   solve a nearby start and the run a table of its steps (/steps). K and the solver objects are kept; a step changes
   the Dirichlet values, the load r0 = K_fD u_D - f, the kernels' constants and the contact set's gaps. */
#include "app.h"
#include "contact.h"
#include "io.h"
#include "physics.h"
#include "scenes.h"
#include "solver_impl.h"

PetscErrorCode LoadPathGetOptions(MPI_Comm comm, LoadPathOptions *lp)
{
  PetscInt  steps = 0, n = LOAD_PATH_MAX;
  PetscBool steps_set, path_set;

  PetscFunctionBeginUser;
  PetscCall(PetscMemzero(lp, sizeof(*lp)));
  PetscOptionsBegin(comm, NULL, "Load path", "Signorini");
  PetscCall(PetscOptionsInt("-load_steps", "Solve at the load factors 1/N, 2/N, ..., 1 in turn, each from the last solution", NULL, steps, &steps,
                            &steps_set));
  PetscCall(PetscOptionsRealArray("-load_path", "Solve at these load factors in turn (loading and unloading), each from the last solution", NULL,
                                  lp->factor, &n, &path_set));
  PetscOptionsEnd();
  PetscCheck(!(steps_set && path_set), comm, PETSC_ERR_USER_INPUT, "-load_steps and -load_path both give the load path: give one of them");
  if (steps_set) {
    PetscCheck(steps >= 1 && steps <= LOAD_PATH_MAX, comm, PETSC_ERR_USER_INPUT, "-load_steps must lie in [1, %d], got %" PetscInt_FMT, LOAD_PATH_MAX,
               steps);
    lp->n = steps;
    for (PetscInt k = 0; k < steps; ++k) lp->factor[k] = (PetscReal)(k + 1) / (PetscReal)steps;
  } else if (path_set) {
    PetscCheck(n >= 1, comm, PETSC_ERR_USER_INPUT, "-load_path needs at least one load factor");
    PetscCall(OptionsCountListValues("-load_path", &steps));
    PetscCheck(steps <= LOAD_PATH_MAX, comm, PETSC_ERR_USER_INPUT, "-load_path has %" PetscInt_FMT " load factors, more than %d", steps,
               LOAD_PATH_MAX);
    PetscCall(OptionsCheckFiniteArray(comm, "-load_path", n, lp->factor));
    lp->n = n;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* What a load path cannot do yet, refused before the set-up; then the scene at the path's first factor. */
PetscErrorCode LoadPathSetUp(MPI_Comm comm, AppCtx *user)
{
  const RunOptions     *opt = user->opt;
  const ContactOptions *copt;

  PetscFunctionBeginUser;
  if (!opt->load_path.n) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(ContactGetOptions(user->contact, &copt));
  PetscCall(SceneCheckLoadPath(comm, &user->scene));
  PetscCheck(!ContactHasBounds(user->contact), comm, PETSC_ERR_USER_INPUT,
             "-load_steps and -load_path work with -contact_method penalty or none: SNESVI's bounds do not follow the load yet");
  PetscCheck(!opt->bars, comm, PETSC_ERR_USER_INPUT, "-bars measures one load state: give it without -load_steps or -load_path");
  PetscCheck(copt->n_sweep <= 1, comm, PETSC_ERR_USER_INPUT, "-penalty_eps0_sweep and a load path both solve a sequence: give one of them");
  PetscCheck(!opt->verify.reference[0], comm, PETSC_ERR_USER_INPUT, "-reference compares one load state: give it without -load_steps or -load_path");
  PetscCall(SceneSetLoadFactor(&user->scene, opt->load_path.factor[0]));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The problem on the current mesh at the load factor t: K stays, the data follow. */
static PetscErrorCode ProblemSetLoadFactor(DM dm, AppCtx *user, PetscReal t)
{
  PetscReal eps;

  PetscFunctionBeginUser;
  PetscCall(SceneSetLoadFactor(&user->scene, t));
  PetscCall(VecZeroEntries(user->prob.loc_bc));
  PetscCall(BoundaryInsertDirichlet(dm, user, user->prob.loc_bc));
  PetscCall(ElasticityUpdateConstants(dm, user)); /* the obstacle, the body force, the scene's loads; 1/eps is reset below */
  PetscCall(ContactGetEps(user->contact, &eps));
  PetscCall(ContactSetEps(user->contact, dm, eps));
  PetscCall(ContactSetLoad(user->contact, dm, &user->scene.obstacle));
  PetscCall(SolverAssembleLoad(dm, user));
  PetscCall(SolverComputeScales(dm, user));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The step just solved at factor t: its quantities (PostprocessContact()), its solve's record and its state at the
   vertices (OutputStateFields(): the output's time series). */
static PetscErrorCode LoadPathRecordStep(DM dm, AppCtx *user, Vec u, PetscReal t)
{
  StepRecord        *s;
  const SolveRecord *r = &user->rec.records[user->rec.nrecords - 1];

  PetscFunctionBeginUser;
  if (!user->rec.steps) {
    PetscCall(PetscCalloc1(user->opt->load_path.n, &user->rec.steps));
    PetscCall(PetscCalloc1(user->opt->load_path.n * OUTPUT_STATE_FIELDS, &user->rec.step_fields));
  }
  s = &user->rec.steps[user->rec.nsteps];
  PetscCall(PostprocessContact(dm, user, u));
  PetscCall(OutputStateFields(dm, user, u, &user->rec.step_fields[user->rec.nsteps * OUTPUT_STATE_FIELDS]));
  user->rec.nsteps++;
  PostprocessGetQuantities(user, &s->q);
  s->factor        = t;
  s->contact_force = user->rec.stats.contact_force;
  for (PetscInt c = 0; c < 3; ++c) s->obstacle_translate[c] = user->scene.obstacle.translate[c];
  s->newton_its = r->newton_its;
  s->ksp_its    = r->ksp_its;
  s->time       = r->time_solve;
  s->converged  = r->converged;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The steps after the first (the run's main solve, at the first factor), each from the last solution extrapolated
   along the path: the secant of the last two solutions, u_k = u_{k-1} + (t_k - t_{k-1}) / (t_{k-1} - t_{k-2})
   (u_{k-1} - u_{k-2}), and for the second step the secant from u = 0 at t = 0 (a linear problem's u is proportional to
   t; the contact's active set makes it piecewise so). The guess is taken where it keeps the penalty's active points and
   lowers the residual at the new load, and else gives the first linear solve's initial guess (SolverExtrapolatedStart(),
   as the eps sweep's). A failed step ends the path: the output is its state, with converged = 0, and /steps holds the
   steps up to it. */
PetscErrorCode LoadPathSolve(DM dm, AppCtx *user, SNES snes, Vec u)
{
  const LoadPathOptions *lp   = &user->opt->load_path;
  Vec                    prev = NULL, dir = NULL;

  PetscFunctionBeginUser;
  if (!lp->n) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(LoadPathRecordStep(dm, user, u, lp->factor[0]));
  if (lp->n > 1) {
    PetscCall(VecDuplicate(u, &prev));
    PetscCall(VecDuplicate(u, &dir));
    PetscCall(VecZeroEntries(prev)); /* u = 0 at t = 0 */
  }
  for (PetscInt k = 1; k < lp->n && user->rec.stats.converged; ++k) {
    const PetscReal t_last = lp->factor[k - 1], t_prev = k > 1 ? lp->factor[k - 2] : 0.0;

    PetscCall(ProblemSetLoadFactor(dm, user, lp->factor[k]));
    if (t_last != t_prev && ContactHasPenalty(user->contact)) {
      PetscCall(VecWAXPY(dir, -1.0, prev, u));
      PetscCall(VecCopy(u, prev));
      PetscCall(SolverExtrapolatedStart(snes, dm, user, u, dir, (lp->factor[k] - t_last) / (t_last - t_prev), 0.0, PETSC_TRUE));
    } else
      PetscCall(VecCopy(u, prev));
    PetscCall(SolverSolve(snes, user, u, SOLVER_START_NEARBY_EPS));
    PetscCall(LoadPathRecordStep(dm, user, u, lp->factor[k]));
  }
  PetscCall(VecDestroy(&prev));
  PetscCall(VecDestroy(&dir));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The steps in the summary: one line each. */
PetscErrorCode LoadPathView(MPI_Comm comm, const AppCtx *user)
{
  PetscFunctionBeginUser;
  if (!user->rec.nsteps) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(
      PetscPrintf(comm, "  load path: step  factor      contact force  largest pressure  contact size  penetration  energy        Newton  Krylov\n"));
  for (PetscInt k = 0; k < user->rec.nsteps; ++k) {
    const StepRecord *s = &user->rec.steps[k];

    PetscCall(PetscPrintf(
        comm, "             %4" PetscInt_FMT "  %-10.4g  %-13.6g  %-16.6g  %-12.6g  %-11.4g  %-12.6g  %6" PetscInt_FMT "  %6" PetscInt_FMT "%s\n",
        k + 1, (double)s->factor, (double)s->contact_force, (double)s->q.pressure_max, (double)s->q.contact_size, (double)s->q.penetration_max,
        (double)s->q.energy, s->newton_its, s->ksp_its, s->converged ? "" : "  FAILED"));
  }
  if (user->rec.nsteps < user->opt->load_path.n || !user->rec.steps[user->rec.nsteps - 1].converged)
    PetscCall(PetscPrintf(comm, "  load path: stopped at step %" PetscInt_FMT " of %" PetscInt_FMT " (factor %g), whose solve failed\n",
                          user->rec.nsteps, user->opt->load_path.n, (double)user->rec.steps[user->rec.nsteps - 1].factor));
  PetscFunctionReturn(PETSC_SUCCESS);
}
