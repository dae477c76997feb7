/* The nonlinear solve. The bulk operator is linear: K and r0 = F_bulk(0) are assembled once,
   the residual is K u + r0 + (contact terms) and the Jacobian K + (contact Jacobian). */
#include <math.h>
#include <petscviewerhdf5.h>
#include "app.h"
#include "contact.h"
#include "discretization.h"
#include "physics.h"
#include "solver_impl.h"

PetscErrorCode SolverCreate(const RunOptions *opt, Contact contact, Multigrid mg, const MeshBox *box, Solver *s)
{
  PetscFunctionBeginUser;
  PetscCall(PetscNew(s));
  (*s)->contact = contact;
  (*s)->opt     = opt;
  (*s)->mg      = mg;
  (*s)->box     = box;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode SolverDestroy(Solver *s)
{
  PetscFunctionBeginUser;
  if (!*s) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscFree((*s)->records));
  PetscCall(PetscFree(*s));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The problem on the current mesh, which ProblemSetUp() fills and each change of mesh replaces. */
Problem *SolverProblem(Solver s)
{
  return &s->prob;
}

/* The run's statistics: the last solve's outcome and the counts over all solves, which the solves write and the
   postprocessing, the checks and the drivers add to. */
RunStats *SolverStats(Solver s)
{
  return &s->stats;
}

/* The table of solves, one record per solve (a level of the grid sequence, an eps of the sweep, a cycle, a step). */
PetscErrorCode SolverGetSolves(Solver s, const SolveRecord **records, PetscInt *n)
{
  PetscFunctionBeginUser;
  if (records) *records = s->records;
  *n = s->nrecords;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode SolverAssembleBulk(DM dm, const RunOptions *opt, Problem *prob)
{
  const AssemblyP1Inputs p1 = {&opt->material, opt->solver.given.mat_type};
  Vec                    locX;
  MatNullSpace           rigid;

  PetscFunctionBeginUser;
  PetscCall(DMGetLocalVector(dm, &locX));
  PetscCall(VecCopy(prob->loc_bc, locX)); /* u = 0 with the Dirichlet values, inserted once by ProblemSetUp() */
  PetscCall(AssemblyCreateOperator(dm, prob->assembly, &p1, opt->assembly_check, locX, &prob->K));
  PetscCall(DMRestoreLocalVector(dm, &locX));
  if (opt->degree == 1)
    PetscCall(ElasticityRigidBodyModesP1(dm, prob->r0, &rigid)); /* unknowns at the vertices only */
  else
    PetscCall(DMPlexCreateRigidBody(dm, 0, &rigid));
  PetscCall(MatSetNearNullSpace(prob->K, rigid));
  PetscCall(MatNullSpaceDestroy(&rigid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* r0 = F_bulk(u_D) - f, the residual at u = 0 with the Dirichlet values of loc_bc (the lifting K u_D and the body
   force), the surface loads and a scene's load in weak form, and its local copy loc_r0 with the fixed rows; and the
   energy of the Dirichlet lift, which these data fix. Assembled by ProblemSetUp() and again at each step of a load path
   (the data changed, K did not). */
PetscErrorCode SolverAssembleLoad(DM dm, const RunOptions *opt, const Scene *scene, Problem *prob)
{
  Vec       locX, locF;
  PetscReal weak_lift;

  PetscFunctionBeginUser;
  PetscCall(DMGetLocalVector(dm, &locX));
  PetscCall(DMGetLocalVector(dm, &locF));
  PetscCall(VecCopy(prob->loc_bc, locX));
  PetscCall(VecZeroEntries(locF));
  PetscCall(AssemblyResidual(dm, prob->assembly, &opt->material, locX, locF));
  PetscCall(VecZeroEntries(prob->r0));
  PetscCall(DMLocalToGlobal(dm, locF, ADD_VALUES, prob->r0));
  if (!prob->loc_r0) PetscCall(VecDuplicate(locF, &prob->loc_r0)); /* with the fixed rows, which the global vector drops */
  PetscCall(VecCopy(locF, prob->loc_r0));
  PetscCall(DMRestoreLocalVector(dm, &locX));
  PetscCall(DMRestoreLocalVector(dm, &locF));
  PetscCall(BoundaryAddLoads(dm, &scene->bcs, prob->face_sets, prob->loc_r0, prob->r0));
  PetscCall(WeakDataAddToResidual(dm, scene, &opt->material, &opt->verify, prob->loc_bc, prob->r0, &weak_lift));
  PetscCall(PostprocessLiftEnergy(dm, &opt->material, prob, weak_lift, &prob->lift_energy)); /* a datum of the load state, not of u */
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The scales of the problem on this mesh: the load ||F(0)||_2, and the displacement scale U, the largest entry of
   the best displacement along F(0) (one steepest-descent step of the energy from u = 0: alpha F(0) with
   alpha = |F(0)|^2 / F(0).K F(0)), rounded to a power of 2. Only U's order of magnitude matters. */
PetscErrorCode SolverComputeScales(DM dm, Contact contact, Problem *prob)
{
  MPI_Comm    comm = PetscObjectComm((PetscObject)dm);
  Vec         zero, F, KF;
  PetscScalar fkf;
  PetscReal   finf, U = 1.0;

  PetscFunctionBeginUser;
  PetscCall(VecDuplicate(prob->r0, &zero));
  PetscCall(VecDuplicate(prob->r0, &F));
  PetscCall(VecDuplicate(prob->r0, &KF));
  PetscCall(VecZeroEntries(zero));
  PetscCall(SolverResidual(prob->sctx, dm, zero, F));
  PetscCall(VecNorm(F, NORM_2, &prob->load_norm));
  PetscCheck(!PetscIsInfOrNanReal(prob->load_norm), comm, PETSC_ERR_USER_INPUT,
             "The load of the problem is not finite (||F(0)|| = %g): check the loads, the material and the mesh coordinates",
             (double)prob->load_norm);
  if (prob->load_norm > 0.0) {
    PetscCall(VecNorm(F, NORM_INFINITY, &finf));
    PetscCall(ContactBulkMult(contact, prob->K, F, KF));
    PetscCall(VecDot(F, KF, &fkf));
    if (PetscRealPart(fkf) > 0.0) U = PetscSqr(prob->load_norm) / PetscRealPart(fkf) * finf;
    if (!(U > 0.0) || PetscIsInfOrNanReal(U)) U = 1.0;
  }
  prob->displacement_scale       = (PetscReal)ldexp(1.0, (int)lround(PetscLog2Real(U)));
  prob->sctx->load_norm          = prob->load_norm; /* the solver's copies of the problem's scales */
  prob->sctx->displacement_scale = prob->displacement_scale;
  PetscCall(VecDestroy(&zero));
  PetscCall(VecDestroy(&F));
  PetscCall(VecDestroy(&KF));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The default linear solver: on the 3D box that nests (MultigridIsDefault()), CG with the boxes' geometric multigrid, whose
   levels are given: MUMPS's fill grows as n^(4/3) there (docs/decisions.md, "The 3D box's default solver"). Elsewhere
   a direct solve (MUMPS), robust for the small problems of a first run; for the penalty
   method inside CG, so that a factorization can serve as the preconditioner of later Newton steps (src/linear/pc_reuse.c).
   The Newton steps are as accurate as with a fresh factorization, also when it is reused. */
static PetscErrorCode SolverSetDefaultLinearSolver(KSP ksp, Contact contact, const SolverOptions *opt, const Problem *prob, Multigrid mg)
{
  PC                           pc;
  PetscBool                    sbaij;
  const ContactSolverDefaults *defaults;

  PetscFunctionBeginUser;
  if (MultigridIsDefault(mg)) { /* the 3D box that nests: CG with the boxes' geometric multigrid, as options/solvers/mg.yaml */
    PetscCall(KSPSetType(ksp, KSPCG));
    PetscCall(KSPSetTolerances(ksp, 1e-10, PETSC_DEFAULT, PETSC_DEFAULT, PETSC_DEFAULT));
    PetscCall(KSPGetPC(ksp, &pc));
    PetscCall(PCSetType(pc, PCMG));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  PetscCall(ContactGetSolverDefaults(contact, &defaults));
  PetscCall(KSPSetType(ksp, defaults->reuse_factorization && opt->pc_reuse ? KSPCG : KSPPREONLY));
  PetscCall(KSPSetTolerances(ksp, 1e-10, PETSC_DEFAULT, PETSC_DEFAULT, PETSC_DEFAULT));
  PetscCall(KSPGetPC(ksp, &pc));
  /* K is symmetric positive definite: a symmetric block matrix (-dm_mat_type sbaij) holds its upper triangle only,
     which MUMPS factors by Cholesky and not by LU */
  PetscCall(PetscObjectTypeCompareAny((PetscObject)prob->K, &sbaij, MATSEQSBAIJ, MATMPISBAIJ, ""));
  PetscCall(PCSetType(pc, sbaij ? PCCHOLESKY : PCLU));
  PetscCall(PCFactorSetMatSolverType(pc, MATSOLVERMUMPS));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Defaults for an iterative linear solver (a multigrid PC such as GAMG or hypre, not a factorization), where the options
   say nothing:
   - the linear elastic solve (-contact_method none): CG measures the true residual (-ksp_norm_type unpreconditioned),
     so that -ksp_rtol means what -snes_rtol means, and the solve takes one Newton step (the preconditioned norm's 1e-10
     can leave the true residual above -snes_rtol, and a second step);
   - the penalty method: an inexact Newton, Eisenstat-Walker's forcing terms (-snes_ksp_ew) bounded by
     -snes_ksp_ew_rtolmax 0.01. Newton's final residual is as tight as before (-snes_rtol decides), the linear solves
     are as loose as Newton allows. PETSc's bound, 0.9, lets the semismooth Newton cycle between active sets on
     steps too inexact to settle them; 0.01 does not (tests/test_performance.py). -snes_ksp_ew 0 restores the fixed
     -ksp_rtol. */
static PetscErrorCode SolverSetIterativeDefaults(SNES snes, Contact contact, const SolverOptions *opt)
{
  const SolverGiven           *given = &opt->given;
  KSP                          ksp;
  PC                           pc;
  PetscBool                    is_cg, is_factor;
  const ContactSolverDefaults *defaults;

  PetscFunctionBeginUser;
  PetscCall(SNESGetKSP(snes, &ksp));
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(PetscObjectTypeCompare((PetscObject)ksp, KSPCG, &is_cg));
  PetscCall(PetscObjectTypeCompareAny((PetscObject)pc, &is_factor, PCLU, PCCHOLESKY, ""));
  if (is_factor) PetscFunctionReturn(PETSC_SUCCESS); /* a factorization: CG converges in one or a few iterations anyway */
  PetscCall(ContactGetSolverDefaults(contact, &defaults));
  {
    const char *prefix;
    PetscInt    k;

    PetscCall(KSPGetOptionsPrefix(ksp, &prefix));
    PetscCall(SolverGivenIndex(prefix, &k));
    if (is_cg && !given->ksp_norm_type[k] && defaults->linear) PetscCall(KSPSetNormType(ksp, KSP_NORM_UNPRECONDITIONED));
  }
  if (!given->snes_ksp_ew && defaults->inexact_newton) {
    PetscCall(SNESKSPSetUseEW(snes, PETSC_TRUE));
    if (!given->snes_ksp_ew_rtolmax)
      PetscCall(
          SNESKSPSetParametersEW(snes, PETSC_DEFAULT, PETSC_DEFAULT, SOLVER_EW_RTOL_MAX, PETSC_DEFAULT, PETSC_DEFAULT, PETSC_DEFAULT, PETSC_DEFAULT));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode SolverCreateSNES(DM dm, Contact contact, const SolverOptions *opt, Problem *prob, Multigrid mg, const MeshBox *box, SNES *snes)
{
  MPI_Comm   comm = PetscObjectComm((PetscObject)dm);
  Mat        J;
  KSP        ksp;
  PC         pc;
  PetscBool  is_multigrid;
  PCType     pc_type;
  LinearCore core; /* what the linear layer's hooks read of the core */

  PetscFunctionBeginUser;
  PetscCall(SNESCreate(comm, snes));
  PetscCall(SNESSetDM(*snes, dm));
  PetscCall(ContactCreateJacobian(contact, dm, prob->K, &J)); /* K itself, or a copy the penalty Jacobian can be made in */
  PetscCall(SNESSetFunction(*snes, NULL, SolverFormFunction, prob->sctx));
  PetscCall(SNESSetJacobian(*snes, J, J, SolverFormJacobian, prob->sctx));
  PetscCall(MatDestroy(&J));
  /* the preconditioner's reuse around the Jacobian's evaluation, before SNESSetFromOptions(): -snes_fd, -snes_mf and
     the like replace both, as they replaced the core's callback; the reuse acts once it is enabled, below */
  SolverCtxLinearCore(prob->sctx, &core);
  PetscCall(PcReuseAttach(&prob->sctx->pc_reuse, *snes, &core));
  PetscCall(ContactSetUpSNES(contact, dm, *snes)); /* SNESVI with its bounds, or semismooth Newton */
  {
    SNESLineSearch ls;

    /* no absolute test in the line search: the critical-point search would stop at the initial point, and report
       CONVERGED_FNORM_ABS, wherever |F . dx| < 1e-15, that is for any problem whose loads are small in absolute terms */
    PetscCall(SNESGetLineSearch(*snes, &ls));
    PetscCall(SNESLineSearchSetTolerances(ls, PETSC_DEFAULT, PETSC_DEFAULT, PETSC_DEFAULT, 0.0, PETSC_DEFAULT, PETSC_DEFAULT));
  }
  PetscCall(SNESSetConvergenceTest(*snes, SolverConverged, prob->sctx, NULL));
  PetscCall(SNESGetKSP(*snes, &ksp));
  PetscCall(SolverSetDefaultLinearSolver(ksp, contact, opt, prob, mg));
  PetscCall(MultigridSetCoarseBoxSolver(mg, ksp, prob->level, box)); /* -contact_coarse_mg on a coarser box */
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(SNESMonitorSet(*snes, ContactMonitor, prob->sctx, NULL));
  PetscCall(SNESSetFromOptions(*snes));
  PetscCall(PCGetType(pc, &pc_type));
  PetscCall(PetscObjectTypeCompareAny((PetscObject)pc, &is_multigrid, PCGAMG, PCMG, ""));
  {
    PetscBool is_rsls;

    PetscCall(PetscObjectTypeCompare((PetscObject)*snes, SNESVINEWTONRSLS, &is_rsls));
    PetscCheck(!(is_multigrid && is_rsls), comm, PETSC_ERR_USER_INPUT,
               "-pc_type %s cannot follow the reduced system of -snes_type vinewtonrsls (its size changes between steps): use hypre or mumps with "
               "-contact_method vi",
               pc_type);
  }
  {
    PetscBool                    is_preonly;
    const ContactSolverDefaults *defaults;

    PetscCall(PetscObjectTypeCompare((PetscObject)ksp, KSPPREONLY, &is_preonly));
    PetscCall(ContactGetSolverDefaults(contact, &defaults));
    prob->sctx->pc_reuse.enabled = (PetscBool)(defaults->reuse_factorization && opt->pc_reuse && !is_preonly);
  }
  PetscCall(SolverSetIterativeDefaults(*snes, contact, opt));
  {
    PetscBool petsc_presolve, fine;

    /* Eisenstat-Walker's terms with the oversolving guard */
    PetscCall(SolverForcingSetUp(&prob->sctx->forcing, *snes, opt->ew_guard, &petsc_presolve));
    PetscCall(SolverStepGuessSetUp(&prob->sctx->step_guess, ksp, &opt->given));
    if (!petsc_presolve)
      PetscCall(LinearPreSolveAttach(&prob->sctx->presolve, ksp, &opt->given, &prob->sctx->step_guess, &prob->sctx->forcing, &core));
    PetscCall(FineSmootherGiven(ksp, &opt->given, &fine));
    PetscCheck(!fine || is_multigrid, comm, PETSC_ERR_USER_INPUT,
               "-mg_fine_ksp_type and -mg_fine_pc_type need a multigrid preconditioner (-pc_type gamg or mg), not %s", pc_type);
    PetscCheck(
        !(petsc_presolve && fine), comm, PETSC_ERR_USER_INPUT,
        "-mg_fine_ksp_type and -mg_fine_pc_type need -snes_ksp_ew_version 2 (or no Eisenstat-Walker): another version keeps PETSc's own pre-solve");
  }
  PetscCall(ContactCheckSNES(contact, *snes, prob->K)); /* the SNES type and the matrix the method can use */
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Records the outcome of the last SNESSolve, with the iteration counts of all solves so far. A solve counts as
   converged only if PETSc says so and the residual fell by -snes_rtol or reached round-off for the load (or the
   user's -snes_atol): a stop on a small step or in the line search with a large residual is a failure. */
static PetscErrorCode RecordSolve(SNES snes, Solver s, PetscInt *newton, PetscInt *ksp)
{
  PetscInt  its, lits, maxit, maxf;
  PetscReal fnorm, atol, rtol, stol, ref;

  PetscFunctionBeginUser;
  PetscCall(SNESGetConvergedReason(snes, &s->stats.reason));
  PetscCall(SNESGetIterationNumber(snes, &its));
  PetscCall(SNESGetLinearSolveIterations(snes, &lits));
  PetscCall(SNESGetFunctionNorm(snes, &fnorm));
  PetscCall(SNESGetTolerances(snes, &atol, &rtol, &stol, &maxit, &maxf));
  *newton += its;
  *ksp += lits;
  s->stats.newton_its     = *newton;
  s->stats.ksp_its        = *ksp;
  s->stats.residual_norm  = fnorm * s->prob.displacement_scale; /* the SNES saw F/U */
  s->stats.residual_start = s->prob.sctx->fnorm0;
  ref                     = SolverStopReference(s->prob.sctx);
  s->stats.residual_reduced =
      (PetscBool)(s->stats.residual_norm <= rtol * ref || s->stats.residual_norm <= s->opt->solver.load_rtol * s->prob.load_norm || fnorm <= atol ||
                  s->prob.sctx->roundoff_stop || s->prob.sctx->energy_stop);
  s->stats.roundoff_stop = s->prob.sctx->roundoff_stop;
  s->stats.converged     = (PetscBool)(s->stats.reason > 0 && s->stats.residual_reduced);
  PetscCall(SNESKSPGetUseEW(snes, &s->stats.ksp_ew));
  s->stats.pc_builds         = s->prob.sctx->pc_reuse.enabled ? s->prob.sctx->pc_reuse.builds : *newton; /* without reuse: one per Newton step */
  s->stats.pc_updates        = s->prob.sctx->pc_reuse.updates;
  s->stats.pc_finest_updates = s->prob.sctx->pc_reuse.finest_updates;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Appends the outcome of the last SolverSolve() to the table of solves (/solves in the output). */
static PetscErrorCode SolverAddRecord(SNES snes, Solver s, Vec u, PetscReal time_solve)
{
  SolveRecord *r;
  DM           dm;

  PetscFunctionBeginUser;
  if (s->nrecords == s->maxrecords) { /* grow */
    SolveRecord *grown;

    s->maxrecords = PetscMax(16, 2 * (s->maxrecords));
    PetscCall(PetscMalloc1(s->maxrecords, &grown));
    if (s->nrecords) PetscCall(PetscArraycpy(grown, s->records, s->nrecords));
    PetscCall(PetscFree(s->records));
    s->records = grown;
  }
  r = &s->records[(s->nrecords)++];
  PetscCall(SNESGetDM(snes, &dm));
  PetscCall(ContactMaxNodePenetration(s->contact, u, &r->max_penetration));
  PetscCall(VecGetSize(u, &r->n_dofs));
  r->level = s->prob.level;
  r->h     = s->prob.h;
  PetscCall(ContactGetEps(s->contact, &r->eps)); /* 0 for the types without eps */
  r->newton_its      = s->stats.newton_its;
  r->ksp_its         = s->stats.ksp_its;
  r->pc_builds       = s->stats.pc_builds;
  r->converged       = s->stats.converged;
  r->time_setup      = s->prob.setup_time;
  r->time_solve      = time_solve;
  s->prob.setup_time = 0.0; /* counted once, with the first solve on the mesh */
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* SNESSolve on x~ = u/U, or Q^T u/U in SNESVI's frames (and the bounds of SNESVI divided by U): see
   SolverIterateDisplacement(). */
static PetscErrorCode SolverSNESSolve(SNES snes, Solver s, Vec u)
{
  const PetscReal U = s->prob.displacement_scale;

  PetscFunctionBeginUser;
  s->prob.sctx->snes_scale = U;
  PetscCall(VecScale(u, 1.0 / U));
  PetscCall(ContactSolverFrame(s->contact, u, PETSC_TRUE)); /* the SNES's unknowns: Q^T u/U */
  PetscCall(ContactScaleBounds(s->contact, 1.0 / U));
  PetscCall(SNESSolve(snes, NULL, u));
  PetscCall(SolverStepGuessDrop(&s->prob.sctx->step_guess)); /* unused if no linear solve came */
  PetscCall(ContactSolverFrame(s->contact, u, PETSC_FALSE));
  PetscCall(VecScale(u, U));
  PetscCall(ContactScaleBounds(s->contact, U));
  s->prob.sctx->snes_scale = 1.0;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* SolverSNESSolve() and RecordSolve(), then again from the last iterate after each recovery from a breakdown of the
   preconditioner (src/linear/pc_recovery.c) while one is left; the Newton steps and linear iterations of every attempt count. */
static PetscErrorCode SolveRecovering(SNES snes, Solver s, Vec u, PetscInt *newton, PetscInt *ksp)
{
  const SolverCtx sc    = s->prob.sctx;
  PetscBool       retry = PETSC_TRUE;

  PetscFunctionBeginUser;
  PetscCall(SolverSNESSolve(snes, s, u));
  PetscCall(RecordSolve(snes, s, newton, ksp));
  while (!s->stats.converged && retry) {
    PetscCall(PcRecoveryTry(&sc->pc_recovery, snes, sc->opt, &sc->pc_reuse, sc->stats, &retry));
    if (!retry) break;
    PetscCall(SolverSNESSolve(snes, s, u));
    PetscCall(RecordSolve(snes, s, newton, ksp));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* How a solve starts from a coarser mesh's converged solution at its own eps, interpolated to this mesh: like the
   sweep's start from a nearby eps (no continuation) when the continuation would make one stage only, eps >= f h / M
   (f the continuation factor): that stage solves at h / M, 1/(eps0) times softer, and returns, for nothing, since the
   coarser solution already holds this problem's contact set to within the refinement. Otherwise as nested iteration
   does (SolverSolve()): below f h / M the new contact nodes, between an active and a free coarse one, start far off
   on the 1/eps scale. */
PetscErrorCode SolverStartFromCoarser(Contact contact, SolverStart *start)
{
  const ContactOptions *copt;
  PetscReal             eps, eps_start;

  PetscFunctionBeginUser;
  *start = SOLVER_START_COARSER_MESH;
  PetscCall(ContactGetOptions(contact, &copt));
  PetscCall(ContactGetEps(contact, &eps));
  PetscCall(ContactGetPenaltyScale(contact, &eps_start));
  if (eps > 0.0 && eps >= copt->continuation_factor * eps_start) *start = SOLVER_START_NEARBY_EPS; /* eps 0: a type without one */
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Solves from a zero initial guess (or from u, start) and records the outcome; a failed solve is recorded, not raised.
   An eps below h/M is reached by continuation: the penalty problems for eps = h/M, h/M f, h/M f^2, ... are solved in turn,
   each from the solution of the previous one, so that Newton starts near the active set and the 1/eps scale of the
   residual never meets a far-off initial guess, where semismooth Newton's steps are driven by the penetration's 1/eps
   multiple and may not converge. A warm start from the solution for a nearby eps (the sweep) needs no continuation;
   one from a coarser mesh's (nested iteration) runs it from that guess: below h/100 its new contact nodes, between an
   active and a free coarse one, start far off on the 1/eps scale. */
/* Whether the load state is zero: no load, body force or prescribed displacement (r0 = F_bulk(0) plus the loads, zero
   to the last bit) and no point of Gamma_C inside the obstacle at u = 0 (no initial overlap). Then u = 0 is the
   solution, and the only one (the energy is strictly convex on the admissible set): its residual is exactly zero, no
   point presses, and every multiplier is zero. A step of a load path at the factor 0 is such a state: from the last
   step's solution Newton would take steps down to round-off, whose penetrations raise the contact warnings. */
static PetscErrorCode SolverZeroData(DM dm, Solver s, PetscBool *zero)
{
  PetscReal r0;

  PetscFunctionBeginUser;
  *zero = PETSC_FALSE;
  PetscCall(VecNorm(s->prob.r0, NORM_INFINITY, &r0));
  if (r0 != 0.0) PetscFunctionReturn(PETSC_SUCCESS);
  {
    Vec       zero_u;
    PetscReal d;

    PetscCall(VecDuplicate(s->prob.r0, &zero_u));
    PetscCall(VecZeroEntries(zero_u));
    PetscCall(ContactMaxPenetration(s->contact, dm, zero_u, &d));
    PetscCall(VecDestroy(&zero_u));
    *zero = (PetscBool)(d <= 0.0);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode SolverSolve(SNES snes, Solver s, Vec u, SolverStart start)
{
  const PetscBool       warm = (PetscBool)(start != SOLVER_START_ZERO);
  PetscReal             eps_target, eps_start;
  PetscLogDouble        t0, t1;
  PetscInt              newton = 0, ksp = 0;
  DM                    dm;
  const ContactOptions *copt;

  PetscFunctionBeginUser;
  PetscCall(ContactGetOptions(s->contact, &copt));
  PetscCall(SNESGetDM(snes, &dm));
  PetscCall(ContactGetEps(s->contact, &eps_target));
  PetscCall(ContactGetPenaltyScale(s->contact, &eps_start));
  if (!warm) PetscCall(VecZeroEntries(u));
  {
    PetscBool zero;

    PetscCall(SolverZeroData(dm, s, &zero));
    if (zero) { /* u = 0 exactly: the SNES finds |F| = 0 at its start and stops there, converged in no step */
      PetscCall(VecZeroEntries(u));
      PetscCall(ContactForgetMultipliers(s->contact));
    }
  }
  /* -pc_type mg: the levels of the meshes solved so far */
  PetscCall(MultigridSetUpPC(s->mg, snes, s->prob.level, s->box, &s->opt->solver));
  s->prob.sctx->warm = warm;
  PetscCall(PetscTime(&t0));
  s->prob.sctx->pc_reuse.builds         = 0; /* counted per solve */
  s->prob.sctx->pc_reuse.updates        = 0;
  s->prob.sctx->pc_reuse.finest_updates = 0;
  s->stats.continuation_stages          = 0;
  if (start != SOLVER_START_NEARBY_EPS && copt->continuation && eps_target < eps_start) { /* both 0 for a type without eps */
    for (PetscReal eps = eps_start; eps > eps_target * 1.000001; eps *= copt->continuation_factor) {
      PetscCall(ContactSetEps(s->contact, dm, eps));
      PetscCall(SolveRecovering(snes, s, u, &newton, &ksp));
      s->stats.continuation_stages++;
      if (!s->stats.converged) break; /* reported as the failure of the whole solve */
    }
    PetscCall(ContactSetEps(s->contact, dm, eps_target));
  }
  if (s->stats.continuation_stages == 0 || s->stats.converged) {
    PetscCall(SolveRecovering(snes, s, u, &newton, &ksp));
  }
  PetscCall(PetscTime(&t1));
  s->stats.time_solve += t1 - t0;
  s->stats.newton_its_total += newton;
  s->stats.ksp_its_total += ksp;
  PetscCall(SolverAddRecord(snes, s, u, t1 - t0));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode SolverSetStepEnergyStop(Problem *prob, PetscReal energy)
{
  PetscFunctionBeginUser;
  prob->sctx->step_energy_stop = energy;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A warm solve with a way out. Semismooth Newton from a guess whose active set is far off can stall: on a path that
   unloads the 3D sphere indenter from 1 to 0.5 (make hertz-path's mesh, or h_near 0.02), the secant's guess u/2 lifts
   all but a few contact nodes off the sphere, whose profile does not scale; each Newton step then pushes hundreds of
   nodes deep into the obstacle, the critical-point line search's one secant step along the energy's derivative, whose
   slope jumps by 1/eps there, takes lambda = 6e-4, and the active set never grows: 50 Newton steps and a failed step,
   where the direct run converges in 13. So the warm solve stops once SOLVER_STALL_STEPS Newton steps have not halved
   |F| (SolverConverged()), or on any failure, and the problem is solved again from zero as a direct run would be; both
   solves are in /solves and the Newton steps of both count. */
PetscErrorCode SolverSolveWarm(SNES snes, Solver s, Vec u, const char what[])
{
  SNESConvergedReason reason;
  PetscInt            its;

  PetscFunctionBeginUser;
  s->prob.sctx->stall_stop = PETSC_TRUE;
  PetscCall(SolverSolve(snes, s, u, SOLVER_START_NEARBY_EPS));
  s->prob.sctx->stall_stop = PETSC_FALSE;
  if (s->stats.converged) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(SNESGetConvergedReason(snes, &reason));
  PetscCall(SNESGetIterationNumber(snes, &its));
  PetscCall(PetscPrintf(PetscObjectComm((PetscObject)snes), "  %s: the warm solve %s (%s, %" PetscInt_FMT " Newton steps); solved again from zero\n",
                        what, reason == SNES_DIVERGED_LINE_SEARCH ? "stalled" : "failed", SNESConvergedReasons[reason], its));
  PetscCall(SolverSolve(snes, s, u, SOLVER_START_ZERO));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Hager's estimate of ||J^-1||_1 (Higham, ACM TOMS 14, 1988), with solves by the SNES's own linear solver, times ||J||_1:
   the 1-norm condition number of the Jacobian at the solution (for vi: of K). J is symmetric, so J^-T x is a solve with J.
   SNESVI's linear solver holds the reduced system of the last active set, so vi gets a linear solver of its own for K,
   set up as the SNES's (the same defaults and options). */
PetscErrorCode SolverConditionEstimate(SNES snes, Solver s, Vec u)
{
  KSP                ksp, ksp_vi = NULL;
  Mat                J;
  Vec                x, y, z;
  PetscReal          normJ, est = 0.0;
  PetscInt           n, last    = -1;
  KSPConvergedReason reason;
  PetscBool          is_vi;

  PetscFunctionBeginUser;
  s->stats.condition_1norm = PETSC_NAN;
  if (!s->opt->solver.condition_estimate) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(SNESGetKSP(snes, &ksp));
  PetscCall(SNESGetJacobian(snes, &J, NULL, NULL, NULL));
  PetscCall(PetscObjectTypeCompareAny((PetscObject)snes, &is_vi, SNESVINEWTONRSLS, SNESVINEWTONSSLS, ""));
  if (is_vi) { /* its KSP holds the reduced system of the last active set */
    J = s->prob.K;
    PetscCall(KSPCreate(PetscObjectComm((PetscObject)snes), &ksp_vi));
    PetscCall(SolverSetDefaultLinearSolver(ksp_vi, s->contact, &s->opt->solver, &s->prob, s->mg));
    PetscCall(KSPSetFromOptions(ksp_vi));
    ksp = ksp_vi;
  } else
    PetscCall(SNESComputeJacobian(snes, u, J, J));
  PetscCall(KSPSetReusePreconditioner(ksp, PETSC_FALSE)); /* a preconditioner built for this very J */
  PetscCall(KSPSetOperators(ksp, J, J));
  PetscCall(MatNorm(J, NORM_1, &normJ));
  PetscCall(VecDuplicate(u, &x));
  PetscCall(VecDuplicate(u, &y));
  PetscCall(VecDuplicate(u, &z));
  PetscCall(VecGetSize(u, &n));
  PetscCall(VecSet(x, 1.0 / n));
  for (PetscInt it = 0; it < 5; ++it) {
    PetscScalar *a, ztx;
    PetscReal    zmax;
    PetscInt     jmax;
    PetscInt     nloc;

    PetscCall(KSPSolve(ksp, x, y)); /* y = J^-1 x */
    PetscCall(KSPGetConvergedReason(ksp, &reason));
    if (reason <= 0) { /* no estimate without solves: reported as not computed */
      PetscCall(PetscPrintf(PetscObjectComm((PetscObject)snes), "  condition number estimate: the linear solve failed (%s), no estimate\n",
                            KSPConvergedReasons[reason]));
      est = PETSC_NAN;
      break;
    }
    PetscCall(VecNorm(y, NORM_1, &est));
    PetscCall(VecCopy(y, z));
    PetscCall(VecGetLocalSize(z, &nloc));
    PetscCall(VecGetArray(z, &a));
    for (PetscInt i = 0; i < nloc; ++i) a[i] = PetscRealPart(a[i]) >= 0.0 ? 1.0 : -1.0;
    PetscCall(VecRestoreArray(z, &a));
    PetscCall(KSPSolve(ksp, z, y)); /* y = J^-T sign(J^-1 x) */
    PetscCall(VecDot(y, x, &ztx));
    PetscCall(VecAbs(y));
    PetscCall(VecMax(y, &jmax, &zmax));
    if (zmax <= PetscRealPart(ztx) || jmax == last) break;
    last = jmax;
    PetscCall(VecSet(x, 0.0));
    PetscCall(VecSetValue(x, jmax, 1.0, INSERT_VALUES));
    PetscCall(VecAssemblyBegin(x));
    PetscCall(VecAssemblyEnd(x));
  }
  s->stats.condition_1norm = normJ * est;
  PetscCall(VecDestroy(&x));
  PetscCall(VecDestroy(&y));
  PetscCall(KSPDestroy(&ksp_vi));
  PetscCall(VecDestroy(&z));
  PetscFunctionReturn(PETSC_SUCCESS);
}
