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
#include "drivers_impl.h"
#include <petscviewerhdf5.h>

/* The load path driver's results: one record per step solved (the failed one included), and each step's state at
   the vertices, OUTPUT_STATE_FIELDS per step (the output's time series). */
typedef struct {
  StepRecord *steps;
  Vec        *step_fields;
  PetscInt    nsteps;
} LoadPath;

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

/* What a load path or force control cannot do yet with the options opt and the contact ct, refused before the set-up;
   then the scene at the path's first factor. */
PetscErrorCode LoadPathSetUp(MPI_Comm comm, const RunOptions *opt, Contact ct, Scene *scene)
{
  const ContactOptions *copt;
  const char           *what = opt->load_path.n ? "-load_steps and -load_path" : "-obstacle_force";

  PetscFunctionBeginUser;
  if (!opt->load_path.n && !SceneForceControlled(scene)) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(ContactGetOptions(ct, &copt));
  PetscCall(SceneCheckLoadPath(comm, scene, what));
  /* a capability, not an operation: the refusal names the method to give, and force control's position secant follows
     the penalty's force, smooth in the obstacle's position where SNESVI's reaction is not */
  PetscCheck(ContactHasPenalty(ct) || !(scene->obstacle.force > 0.0), comm, PETSC_ERR_USER_INPUT,
             "-obstacle_force works with -contact_method penalty (its positions' warm solves and force secant are the penalty's)");
  PetscCheck(!opt->bars, comm, PETSC_ERR_USER_INPUT, "-bars measures one load state: give it without %s", what);
  PetscCheck(copt->n_sweep <= 1, comm, PETSC_ERR_USER_INPUT, "-penalty_eps0_sweep and %s both solve a sequence: give one of them", what);
  PetscCheck(!(copt->penetration_tol > 0.0 && scene->obstacle.force > 0.0), comm, PETSC_ERR_USER_INPUT,
             "-contact_penetration_tol and -obstacle_force both move a solve's data (eps, the obstacle's position): give one of them");
  PetscCheck(!opt->verify.reference[0], comm, PETSC_ERR_USER_INPUT, "-reference compares one load state: give it without %s", what);
  PetscCall(SceneSetLoadFactor(scene, opt->load_path.n ? opt->load_path.factor[0] : 1.0)); /* keeps the data at the factor 1 */
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The problem on the current mesh at the scene's current data: K stays, the Dirichlet values, the kernels' constants,
   the contact set's gaps, the load r0 and the scales follow. */
static PetscErrorCode ProblemUpdateData(DM dm, AppCtx *user)
{
  Problem  *prob = SolverProblem(user->solver);
  PetscReal eps;

  PetscFunctionBeginUser;
  PetscCall(VecZeroEntries(prob->loc_bc));
  PetscCall(BoundaryInsertDirichlet(dm, &user->scene, prob->face_sets, user->opt->degree, prob->loc_bc));
  PetscCall(
      ElasticityUpdateConstants(dm, &user->opt->material, &user->scene)); /* the obstacle, the body force, the scene's loads; 1/eps is reset below */
  PetscCall(ContactGetEps(user->contact, &eps));
  PetscCall(ContactSetEps(user->contact, dm, eps));
  PetscCall(ContactSetLoad(user->contact, dm, &user->scene.obstacle));
  PetscCall(SolverAssembleLoad(dm, user->opt, &user->scene, prob));
  PetscCall(SolverComputeScales(dm, user->contact, prob));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A force and a position of the obstacle along the unit direction of the scene's full translation (the force positive
   as the obstacle presses): of the solution PostprocessContact() last measured into sq (ForceAlong()) at the scene's
   translation, or of a recorded step. */
static void Along(const Scene *scene, const PetscReal force[3], const PetscReal translate[3], PetscReal *f, PetscReal *s)
{
  const PetscReal *dir = scene->full_load.translate;
  PetscReal        len = 0.0;

  *f = *s = 0.0;
  for (PetscInt c = 0; c < 3; ++c) len += PetscSqr(dir[c]);
  len = PetscSqrtReal(len);
  for (PetscInt c = 0; c < 3; ++c) {
    *f += force[c] * dir[c] / len;
    *s += translate[c] * dir[c] / len;
  }
}

static void ForceAlong(const Scene *scene, const SolutionQuantities *sq, PetscReal *f, PetscReal *s)
{
  Along(scene, sq->q.force, scene->obstacle.translate, f, s);
}

/* The force's local power of the obstacle's position, from the last two of the nsteps steps recorded (1.5 for a
   sphere's indentation), in [1, 3]; 1 before there are two. */
static PetscReal ForcePower(const Scene *scene, const StepRecord steps[], PetscInt nsteps)
{
  PetscReal power = 1.0;

  if (nsteps >= 2) {
    PetscReal         f1, s1, f2, s2;
    const StepRecord *st = &steps[nsteps - 2];

    Along(scene, st[0].q.force, st[0].obstacle_translate, &f1, &s1);
    Along(scene, st[1].q.force, st[1].obstacle_translate, &f2, &s2);
    if (f1 > 0.0 && f2 > f1 && s1 > 0.0 && s2 > s1) power = PetscMin(PetscMax(PetscLogReal(f2 / f1) / PetscLogReal(s2 / s1), 1.0), 3.0);
  }
  return power;
}

/* The body's depth along the obstacle's direction of motion (the scene's full translation): the extent of its
   vertices' projections on it, over all ranks. Force control moves the obstacle at most that far from its unloaded
   position: beyond, it would pass through the body (the gap and the normal are taken at the undeformed position), and
   a target that needs more is out of the small-deformation model's reach. */
static PetscErrorCode BodyDepth(DM dm, const Scene *scene, PetscReal *depth)
{
  const PetscReal   *dir = scene->full_load.translate;
  Vec                coords;
  const PetscScalar *x;
  PetscInt           n, cdim;
  PetscReal          len = 0.0, range[2] = {PETSC_MAX_REAL, PETSC_MAX_REAL}; /* -min and max of the projections */

  PetscFunctionBeginUser;
  PetscCall(DMGetCoordinateDim(dm, &cdim));
  for (PetscInt c = 0; c < cdim; ++c) len += PetscSqr(dir[c]);
  len = PetscSqrtReal(len);
  PetscCall(DMGetCoordinatesLocal(dm, &coords));
  PetscCall(VecGetLocalSize(coords, &n));
  PetscCall(VecGetArrayRead(coords, &x));
  range[1] = -PETSC_MAX_REAL;
  for (PetscInt i = 0; i < n / cdim; ++i) {
    PetscReal p = 0.0;

    for (PetscInt c = 0; c < cdim; ++c) p += PetscRealPart(x[i * cdim + c]) * dir[c] / len;
    range[0] = PetscMin(range[0], p);
    range[1] = PetscMax(range[1], p);
  }
  PetscCall(VecRestoreArrayRead(coords, &x));
  range[0] = -range[0];
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, range, 2, MPIU_REAL, MPIU_MAX, PetscObjectComm((PetscObject)dm)));
  *depth = range[0] + range[1];
  PetscFunctionReturn(PETSC_SUCCESS);
}

#define FORCE_CONTROL_RTOL 1e-8 /* |F - target| / target at which the position is found */
#define FORCE_CONTROL_MAX_ITS 60
#define FORCE_CONTROL_SOLVE_TOL 1e-2 /* each position's Newton residual, relative to FORCE_CONTROL_RTOL times the target */

/* Force control (-obstacle_force F): the obstacle's position s along its direction such that its force equals the
   target, from the solution at the position it has (the translation's length times the load factor on the first
   call, the last step's position after). The force is a nondecreasing function of s (the energy is convex in the
   obstacle's position; frictionless, linear), piecewise smooth as nodes enter the contact, and near a power of s
   (F ~ s^(3/2) for a sphere's indentation, s for a flat punch). Until the target is bracketed, the secant of log f
   against log s through the last two positions; the first move, the power law through the origin (where the obstacle
   does not press yet) with the power of the last two steps (1 before there are two). Once the target is bracketed
   by [s_lo, s_hi], Illinois' regula falsi (it halves the stale end's residual). A step doubles the last move where
   the force stays below the target and the secant has nothing to go on.
   Each position is a warm penalty solve from the solution's secant along s (through u = 0 at s = 0 for the first
   move), and where that fails (Newton's line search stalls at a kink of the penalty, seen at eps = h/100 in 3D)
   a solve from zero as a direct run's (both in /solves). On the 3D sphere indenter of make hertz-path (10 steps, the
   graded mesh) the secant start and the powers took the path from 994 to 292 Newton steps and the failed warm solves
   from 10 to 2 (docs/hertz.md).
   The force is a sum of the solve's nodal reactions, exact to about the Newton residual: each position's solve stops
   at FORCE_CONTROL_SOLVE_TOL times FORCE_CONTROL_RTOL times the target (or at -snes_rtol times the load, if tighter),
   so that the force is known well below the tolerance it must reach. At -snes_rtol times the load alone the first
   step's force there (4e-5, the load 0.0045) was exact to about 1e-6 relative, and the search stalled at 1.0e-8.
   Once the active set settles a solve is linear, so the tighter stop costs about one Newton step. *ok is false when
   the solve fails or the target is not reached in FORCE_CONTROL_MAX_ITS positions; *its counts the positions solved. */
static PetscErrorCode ForceControlSolve(DM dm, AppCtx *user, const LoadPath *path, SNES snes, Vec u, PetscReal target, PetscBool *ok, PetscInt *its)
{
  Problem  *prob  = SolverProblem(user->solver);
  RunStats *stats = SolverStats(user->solver);
  PetscReal f, s, f_prev = 0.0, s_prev = 0.0, s_lo = 0.0, f_lo = 0.0, s_hi = 0.0, f_hi = 0.0, atol, rtol, stol, power, depth = PETSC_MAX_REAL;
  PetscBool have_lo = PETSC_FALSE, have_hi = PETSC_FALSE;
  PetscInt  side = 0, maxit, maxf; /* side: the bracket's end kept last time (Illinois) */
  Vec       u_prev, dir;

  PetscFunctionBeginUser;
  *ok   = PETSC_FALSE;
  *its  = 0;
  power = ForcePower(&user->scene, path->steps, path->nsteps);
  PetscCall(VecDuplicate(u, &u_prev)); /* the solution at s_prev: u = 0 at s = 0, before the obstacle presses */
  PetscCall(VecDuplicate(u, &dir));
  PetscCall(VecZeroEntries(u_prev));
  PetscCall(SNESGetTolerances(snes, &atol, &rtol, &stol, &maxit, &maxf));
  if (prob->load_norm > 0.0)
    PetscCall(
        SNESSetTolerances(snes, atol, PetscMin(rtol, FORCE_CONTROL_SOLVE_TOL * FORCE_CONTROL_RTOL * target / prob->load_norm), stol, maxit, maxf));
  PetscCall(BodyDepth(dm, &user->scene, &depth));
  PetscCall(PostprocessContact(dm, user->contact, prob, &user->scene.bcs, &user->opt->material, u, &user->quantities));
  ForceAlong(&user->scene, &user->quantities, &f, &s);
  for (PetscInt it = 0; it < FORCE_CONTROL_MAX_ITS && stats->converged; ++it) {
    PetscReal s_next;

    if (PetscAbsReal(f - target) <= FORCE_CONTROL_RTOL * target) {
      *ok = PETSC_TRUE;
      break;
    }
    if (it && s > s_prev && f < f_prev && f < target) { /* the force falls as the obstacle moves on: it passes through the body */
      PetscCall(PetscPrintf(PetscObjectComm((PetscObject)dm),
                            "  force control: the force %g is out of reach: moved on from %g to %g along its direction, the obstacle presses with "
                            "%g instead of %g, so that it passes through the body, beyond the small-deformation model (a smaller -obstacle_force?)\n",
                            (double)target, (double)s_prev, (double)s, (double)f, (double)f_prev));
      break;
    }
    if (it && f == f_prev && s != s_prev) { /* the solve did not move: the force is as exact as the Newton tolerance */
      PetscCall(PetscPrintf(PetscObjectComm((PetscObject)dm),
                            "  force control: stalled %g from the force %g (relative); the force is the residual of the solve, exact to about "
                            "its Newton tolerance (%g times the force, or -snes_rtol times the load where tighter)\n",
                            (double)(PetscAbsReal(f - target) / target), (double)target, (double)(FORCE_CONTROL_SOLVE_TOL * FORCE_CONTROL_RTOL)));
      break;
    }
    if (f < target && (!have_lo || s > s_lo)) {
      if (side == -1) f_hi = target + 0.5 * (f_hi - target);
      s_lo = s, f_lo = f, side = -1, have_lo = PETSC_TRUE;
    } else if (f > target && (!have_hi || s < s_hi)) {
      if (side == 1) f_lo = target + 0.5 * (f_lo - target);
      s_hi = s, f_hi = f, side = 1, have_hi = PETSC_TRUE;
    }
    if (!have_lo || !have_hi) { /* no bracket yet: the secant, or a doubled move outward */
      const PetscReal move = it ? s - s_prev : (s != 0.0 ? s : 1.0);

      if (it && f > 0.0 && f_prev > 0.0 && s > 0.0 && s_prev > 0.0 && f != f_prev && (f - f_prev) / (s - s_prev) > 0.0)
        s_next = s * PetscPowReal(target / f, PetscLogReal(s / s_prev) / PetscLogReal(f / f_prev)); /* the secant of log f against log s */
      else if (it && f != f_prev && (f - f_prev) / (s - s_prev) > 0.0)
        s_next = s + (target - f) * (s - s_prev) / (f - f_prev);
      else if (!it && f > 0.0 && s > 0.0)
        s_next = s * PetscPowReal(target / f, 1.0 / power); /* the power law through (0, 0): no force before the contact */
      else
        s_next = s + (f < target ? 1.0 : -1.0) * PetscAbsReal(move);
      if (f < target && s_next > s + 4.0 * PetscAbsReal(move) && it) s_next = s + 4.0 * PetscAbsReal(move);
    } else
      s_next = s_lo + (target - f_lo) * (s_hi - s_lo) / (f_hi - f_lo); /* regula falsi in the bracket */
    if (s_next > depth) {                                              /* no deeper than the body (BodyDepth()) */
      if (s >= depth * (1.0 - 1e-12) && f < target) {
        PetscCall(PetscPrintf(PetscObjectComm((PetscObject)dm),
                              "  force control: the force %g is out of reach: with the obstacle moved by the body's whole depth along its "
                              "direction (%g) it presses with %g; the small-deformation model cannot press further (a smaller -obstacle_force?)\n",
                              (double)target, (double)depth, (double)f));
        break;
      }
      s_next = depth;
    }
    PetscCall(SceneSetObstaclePosition(&user->scene, s_next));
    PetscCall(ProblemUpdateData(dm, user));
    PetscCall(
        SolverSecantStart(snes, dm, user->solver, u, u_prev, dir, (PetscBool)(s != s_prev), s != s_prev ? (s_next - s) / (s - s_prev) : 0.0, 1.0));
    s_prev = s, f_prev = f;
    PetscCall(SolverSolveWarm(snes, user->solver, u, "force control")); /* from zero where Newton stalls at a kink of the penalty */
    PetscCall(PostprocessContact(dm, user->contact, prob, &user->scene.bcs, &user->opt->material, u, &user->quantities));
    ForceAlong(&user->scene, &user->quantities, &f, &s);
    ++*its;
  }
  PetscCall(SNESSetTolerances(snes, atol, rtol, stol, maxit, maxf));
  PetscCall(VecDestroy(&u_prev));
  PetscCall(VecDestroy(&dir));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Force control to a zero target (a path that unloads to the factor 0): the obstacle withdrawn until it exerts no
   force at all. The state is then unique, the body under its other loads as if the obstacle were not there, while the
   position is any at which the obstacle does not press; the one found is the onset of the contact as the force's power
   law F = C (s - s0)^p puts it (the power p of the last two steps), a little behind it (FORCE_CONTROL_RELEASE of the
   last move), so that the nodes the obstacle just touches there are free. The first move assumes the onset at the
   obstacle's unloaded position s = 0, as the first move to a positive force does; after it, the onset through the last
   two positions with a force, (s_a - s0) / (s_b - s0) = (f_a / f_b)^(1/p). The target is reached where the force is
   zero to the last bit and no node or point of the rule lies inside the obstacle (a node the rule's points miss may
   still overlap it: that is no release); behind the onset the state is u = 0 where the other loads are zero too. */
#define FORCE_CONTROL_RELEASE 1e-6

static PetscErrorCode ForceControlRelease(DM dm, AppCtx *user, const LoadPath *path, SNES snes, Vec u, PetscBool *ok, PetscInt *its)
{
  Problem        *prob  = SolverProblem(user->solver);
  RunStats       *stats = SolverStats(user->solver);
  const PetscReal power = ForcePower(&user->scene, path->steps, path->nsteps);
  PetscReal       f, s, f_prev = 0.0, s_prev = 0.0;
  PetscBool       have_prev = PETSC_FALSE;

  PetscFunctionBeginUser;
  *ok  = PETSC_FALSE;
  *its = 0;
  PetscCall(PostprocessContact(dm, user->contact, prob, &user->scene.bcs, &user->opt->material, u, &user->quantities));
  ForceAlong(&user->scene, &user->quantities, &f, &s);
  for (PetscInt it = 0; it < FORCE_CONTROL_MAX_ITS && stats->converged; ++it) {
    PetscReal s_next, move, d;

    PetscCall(ContactMaxPenetration(user->contact, dm, u, &d));
    if (!(f > 0.0) && d <= 0.0) { /* no force, and no point inside the obstacle */
      *ok = PETSC_TRUE;
      break;
    }
    if (!have_prev)
      s_next = s > 0.0 ? 0.0 : s - PetscMax(PetscAbsReal(s), 1.0); /* the onset where the first move to a force puts it */
    else {
      const PetscReal r = PetscPowReal(f_prev / f, 1.0 / power);

      s_next = r != 1.0 ? (s_prev - r * s) / (1.0 - r) : PETSC_MAX_REAL;
      if (!(s_next < PetscMin(s, s_prev))) s_next = PetscMin(s, s_prev) - PetscAbsReal(s - s_prev); /* the law gives no onset behind both */
    }
    move = PetscAbsReal(s_next - s);
    s_next -= FORCE_CONTROL_RELEASE * move;
    s_prev = s, f_prev = f, have_prev = PETSC_TRUE;
    PetscCall(SceneSetObstaclePosition(&user->scene, s_next));
    PetscCall(ProblemUpdateData(dm, user));
    PetscCall(SolverSolveWarm(snes, user->solver, u, "force control"));
    PetscCall(PostprocessContact(dm, user->contact, prob, &user->scene.bcs, &user->opt->material, u, &user->quantities));
    ForceAlong(&user->scene, &user->quantities, &f, &s);
    ++*its;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The step just solved at factor t, of a path of n steps, into the path's record: its quantities (PostprocessContact()
   with the contact ct, the solver's problem, the scene's boundary conditions and the material mat, into sq), its
   solves' records from first_record on (summed: force control solves several positions) and its
   state at the vertices (OutputStateFields(): the output's time series). */
static PetscErrorCode LoadPathRecordStep(DM dm, Contact ct, Solver solver, const Scene *scene, const Material *mat, PetscInt n, Vec u, PetscReal t,
                                         PetscInt first_record, PetscBool ok, SolutionQuantities *sq, LoadPath *path)
{
  const Problem     *prob  = SolverProblem(solver);
  RunStats          *stats = SolverStats(solver);
  const SolveRecord *records;
  PetscInt           nrecords;
  StepRecord        *s;

  PetscFunctionBeginUser;
  if (!path->steps) {
    PetscCall(PetscCalloc1(n, &path->steps));
    PetscCall(PetscCalloc1(n * OUTPUT_STATE_FIELDS, &path->step_fields));
  }
  s = &path->steps[path->nsteps];
  PetscCall(PostprocessContact(dm, ct, prob, &scene->bcs, mat, u, sq));
  PetscCall(OutputStateFields(dm, ct, prob->loc_bc, u, &path->step_fields[path->nsteps * OUTPUT_STATE_FIELDS]));
  path->nsteps++;
  s->q             = sq->q;
  s->factor        = t;
  s->contact_force = sq->contact_force;
  for (PetscInt c = 0; c < 3; ++c) s->obstacle_translate[c] = scene->obstacle.translate[c];
  s->newton_its = s->ksp_its = 0;
  s->time                    = 0.0;
  PetscCall(SolverGetSolves(solver, &records, &nrecords));
  for (PetscInt i = first_record; i < nrecords; ++i) {
    s->newton_its += records[i].newton_its;
    s->ksp_its += records[i].ksp_its;
    s->time += records[i].time_solve;
  }
  s->converged = (PetscBool)(records[nrecords - 1].converged && ok && stats->converged);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Force control at the current load (-obstacle_force): the obstacle moved until it presses with the scene's force
   (the factor times -obstacle_force); a target not reached fails the solve, as a failed Newton solve does. */
static PetscErrorCode LoadPathForce(DM dm, AppCtx *user, const LoadPath *path, SNES snes, Vec u, PetscBool *ok)
{
  RunStats *stats = SolverStats(user->solver);
  PetscInt  its;

  PetscFunctionBeginUser;
  *ok = PETSC_TRUE;
  if (!SceneForceControlled(&user->scene) || !stats->converged) PetscFunctionReturn(PETSC_SUCCESS);
  if (user->scene.obstacle.force > 0.0)
    PetscCall(ForceControlSolve(dm, user, path, snes, u, user->scene.obstacle.force, ok, &its));
  else
    PetscCall(ForceControlRelease(dm, user, path, snes, u, ok, &its)); /* the factor 0 */
  stats->force_control_its += its;
  if (!*ok && stats->converged) {
    PetscCall(PetscPrintf(PetscObjectComm((PetscObject)dm),
                          "  force control: the force %g was not reached in %" PetscInt_FMT " position(s) of the obstacle\n",
                          (double)user->scene.obstacle.force, its));
    stats->converged            = PETSC_FALSE;
    stats->force_control_failed = PETSC_TRUE;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The steps after the first (the run's main solve, at the first factor), each from the last solution extrapolated
   along the path: the secant of the last two solutions, u_k = u_{k-1} + (t_k - t_{k-1}) / (t_{k-1} - t_{k-2})
   (u_{k-1} - u_{k-2}), and for the second step the secant from u = 0 at t = 0 (a linear problem's u is proportional to
   t; the contact's active set makes it piecewise so). The guess is taken wherever it lowers the residual at the new
   load, even where it moves the penalty's active points (the contact zone grows along a path: the 3D sphere
   indenter's warm steps took 6 Newton steps from the last solution and 4 from the secant, docs/solvers.md, "Load
   paths"), and else gives the first linear solve's initial guess (SolverExtrapolatedStart(), as the eps sweep's).
   Under force control each step starts at the last step's position and solution instead, and moves the obstacle to
   the step's force. A failed step ends the path: the output is its state, with converged = 0, and /steps holds the
   steps up to it. Without a path, force control at the run's one load. */
static PetscErrorCode LoadPathSolve(Driver d, AppCtx *user, DM *dmp, SNES *snesp, Vec *up)
{
  RunStats              *stats = SolverStats(user->solver);
  LoadPath              *path  = (LoadPath *)d->data;
  DM                     dm    = *dmp;
  SNES                   snes  = *snesp;
  Vec                    u     = *up;
  const LoadPathOptions *lp    = &user->opt->load_path;
  const PetscBool        force = SceneForceControlled(&user->scene);
  Vec                    prev = NULL, dir = NULL;
  PetscInt               first = 0; /* the first step counts every solve before it: the levels of the grid sequence, the cycles */
  PetscBool              ok;

  PetscFunctionBeginUser;
  PetscCall(LoadPathForce(dm, user, path, snes, u, &ok)); /* the first step's force, or the run's one force without a path */
  if (!lp->n) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(LoadPathRecordStep(dm, user->contact, user->solver, &user->scene, &user->opt->material, lp->n, u, lp->factor[0], first, ok,
                               &user->quantities, path));
  if (lp->n > 1) {
    PetscCall(VecDuplicate(u, &prev));
    PetscCall(VecDuplicate(u, &dir));
    PetscCall(VecZeroEntries(prev)); /* u = 0 at t = 0 */
  }
  for (PetscInt k = 1; k < lp->n && stats->converged; ++k) {
    const PetscReal t_last = lp->factor[k - 1], t_prev = k > 1 ? lp->factor[k - 2] : 0.0;
    PetscReal       f, s;

    PetscCall(SolverGetSolves(user->solver, NULL, &first));
    ForceAlong(&user->scene, &user->quantities, &f, &s);
    PetscCall(SceneSetLoadFactor(&user->scene, lp->factor[k]));
    if (force) PetscCall(SceneSetObstaclePosition(&user->scene, s)); /* the last step's position */
    PetscCall(ProblemUpdateData(dm, user));
    {
      /* the secant through the last two solutions, measured for the penalty (docs/solvers.md, "Load paths"); SNESVI and
         none start from the last step's solution, which their solve needs no better guess than */
      const PetscBool secant = (PetscBool)(!force && t_last != t_prev && ContactHasPenalty(user->contact));

      PetscCall(SolverSecantStart(snes, dm, user->solver, u, prev, dir, secant, secant ? (lp->factor[k] - t_last) / (t_last - t_prev) : 0.0, 1.0));
    }
    PetscCall(SolverSolveWarm(snes, user->solver, u, "load path")); /* from zero where the guess's active set is too far off */
    PetscCall(PenetrationTolReach(dm, user, snes, u)); /* -contact_penetration_tol at every step, from the last step's eps (or multipliers) */
    PetscCall(LoadPathForce(dm, user, path, snes, u, &ok));
    PetscCall(LoadPathRecordStep(dm, user->contact, user->solver, &user->scene, &user->opt->material, lp->n, u, lp->factor[k], first, ok,
                                 &user->quantities, path));
  }
  PetscCall(VecDestroy(&prev));
  PetscCall(VecDestroy(&dir));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The steps of the path (-load_steps, -load_path) in the summary, one line each, and where force control left the scene's
   obstacle. */
static PetscErrorCode LoadPathView(Driver d, MPI_Comm comm, const DriverReport *r)
{
  const LoadPath        *path  = (const LoadPath *)d->data;
  const LoadPathOptions *lp    = &r->opt->load_path;
  const Scene           *scene = r->scene;

  PetscFunctionBeginUser;
  if (SceneForceControlled(scene)) {
    PetscReal f, s;

    ForceAlong(scene, r->quantities, &f, &s);
    PetscCall(PetscPrintf(comm,
                          "  force control: the obstacle %g along its direction presses with %.10g (target %g; %" PetscInt_FMT " positions solved)\n",
                          (double)s, (double)f, (double)scene->obstacle.force, r->stats->force_control_its));
  }
  if (!path->nsteps) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(
      PetscPrintf(comm, "  load path: step  factor      contact force  largest pressure  contact size  penetration  energy        Newton  Krylov\n"));
  for (PetscInt k = 0; k < path->nsteps; ++k) {
    const StepRecord *s = &path->steps[k];

    PetscCall(PetscPrintf(
        comm, "             %4" PetscInt_FMT "  %-10.4g  %-13.6g  %-16.6g  %-12.6g  %-11.4g  %-12.6g  %6" PetscInt_FMT "  %6" PetscInt_FMT "%s\n",
        k + 1, (double)s->factor, (double)s->contact_force, (double)s->q.pressure_max, (double)s->q.contact_size, (double)s->q.penetration_max,
        (double)s->q.energy, s->newton_its, s->ksp_its, s->converged ? "" : "  FAILED"));
  }
  if (path->nsteps < lp->n || !path->steps[path->nsteps - 1].converged)
    PetscCall(PetscPrintf(comm, "  load path: stopped at step %" PetscInt_FMT " of %" PetscInt_FMT " (factor %g), whose solve failed\n", path->nsteps,
                          lp->n, (double)path->steps[path->nsteps - 1].factor));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The load path's part of the output: force control's positions solved over the steps, and the table /steps, one row
   per step solved, the failed one included (the factor, the obstacle's translation and force, the supports' reactions,
   the contact size, the largest pressure and penetration, the energy, the solve's Newton steps, linear iterations,
   time and whether it converged). */
static PetscErrorCode LoadPathWrite(Driver d, MPI_Comm comm, const DriverReport *r, PetscViewer v)
{
  const LoadPath   *path  = (const LoadPath *)d->data;
  const Scene      *scene = r->scene;
  const StepRecord *st    = path->steps;
  const PetscInt    n = path->nsteps, dim = r->dim;
  PetscReal        *col;
  char              name[128];

  PetscFunctionBeginUser;
  if (SceneForceControlled(scene)) PetscCall(RunAttrInt(v, r->stats->force_control_its, "force_control_its"));
  if (!n) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscMalloc1(n, &col));
  PetscCall(PetscViewerHDF5PushGroup(v, "/steps"));
#define STEP_COLUMN(label, expr) RUN_TABLE_COLUMN(comm, v, label, n, col, expr)
  STEP_COLUMN("factor", st[i].factor);
  STEP_COLUMN("contact_force", st[i].contact_force);
  for (PetscInt c = 0; c < dim; ++c) {
    PetscCall(PetscSNPrintf(name, sizeof(name), "obstacle_translate_%c", "xyz"[c]));
    STEP_COLUMN(name, st[i].obstacle_translate[c]);
    PetscCall(PetscSNPrintf(name, sizeof(name), "contact_force_%c", "xyz"[c]));
    STEP_COLUMN(name, st[i].q.force[c]);
  }
  for (PetscInt b = 0; b < scene->bcs.n; ++b) {
    const BoundaryCondition *bc = &scene->bcs.bc[b];

    if (bc->kind != BC_CLAMP && bc->kind != BC_SLIP) continue;
    for (PetscInt c = 0; c < dim; ++c) {
      PetscCall(PetscSNPrintf(name, sizeof(name), "reaction_%s_%s_%c", BoundaryKinds[bc->kind], bc->token, "xyz"[c]));
      STEP_COLUMN(name, st[i].q.reaction[b][c]);
    }
  }
  STEP_COLUMN("contact_size", st[i].q.contact_size);
  STEP_COLUMN("pressure_max", st[i].q.pressure_max);
  STEP_COLUMN("penetration_max", st[i].q.penetration_max);
  STEP_COLUMN("energy", st[i].q.energy);
  STEP_COLUMN("newton_its", (PetscReal)st[i].newton_its);
  STEP_COLUMN("ksp_its", (PetscReal)st[i].ksp_its);
  STEP_COLUMN("time", st[i].time);
  STEP_COLUMN("converged", st[i].converged ? 1.0 : 0.0);
#undef STEP_COLUMN
  PetscCall(PetscViewerHDF5PopGroup(v));
  PetscCall(PetscFree(col));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode LoadPathFields(Driver d, PetscInt *nsteps, Vec const **fields)
{
  const LoadPath *path = (const LoadPath *)d->data;

  PetscFunctionBeginUser;
  *nsteps = path->nsteps;
  *fields = path->step_fields;
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode LoadPathDestroy(Driver d)
{
  LoadPath *path = (LoadPath *)d->data;

  PetscFunctionBeginUser;
  for (PetscInt k = 0; k < path->nsteps * OUTPUT_STATE_FIELDS; ++k) PetscCall(VecDestroy(&path->step_fields[k]));
  PetscCall(PetscFree(path->step_fields));
  PetscCall(PetscFree(path->steps));
  PetscCall(PetscFree(d->data));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The load path driver: the steps after the run's first, each from the last, and force control at each. */
PetscErrorCode DriverCreate_LoadPath(Driver d)
{
  LoadPath *path;

  PetscFunctionBeginUser;
  PetscCall(PetscNew(&path));
  d->data        = path;
  d->ops.solve   = LoadPathSolve;
  d->ops.view    = LoadPathView;
  d->ops.write   = LoadPathWrite;
  d->ops.fields  = LoadPathFields;
  d->ops.destroy = LoadPathDestroy;
  PetscFunctionReturn(PETSC_SUCCESS);
}
