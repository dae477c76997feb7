static const char help[] =
    "Frictionless Signorini contact in linear elasticity by the penalty method (Chouly & Hild 2013),\n"
    "with SNESVI as the reference for the exact constraint. 2D plane strain and 3D, DMPlex + PetscFE.\n\n";

#include <sys/resource.h>
#include "app.h"
#include "contact.h"
#include "discretization.h"
#include "drivers.h"
#include "estimate.h"
#include "linear.h"
#include "scenes.h"
#include "mesh.h"
#include "physics.h"
#include "solver.h"
#include "verify.h"
#include "io.h"

/* The summary: the run's first line, then each module's own lines (its ...View()), in the order of the run. */
static PetscErrorCode PrintSummary(DM dm, const AppCtx *user, Vec u)
{
  MPI_Comm        comm = PetscObjectComm((PetscObject)dm);
  const RunStats *s    = SolverStats(user->solver);
  PetscInt        dim, ndofs;
  PetscMPIInt     size;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(VecGetSize(u, &ndofs));
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCall(PetscPrintf(comm, "scene %s, %" PetscInt_FMT "D, ", user->scene.name, dim));
  PetscCall(ContactView(user->contact, PETSC_VIEWER_STDOUT_(comm))); /* method penalty (gauss quadrature, eps = ...) */
  PetscCall(PetscPrintf(comm, ", P%" PetscInt_FMT ", %" PetscInt_FMT " dofs, largest cell h = %g, %d rank(s)\n", user->opt->degree, ndofs,
                        (double)SolverProblem(user->solver)->h, size));
  PetscCall(SolverView(user->solver, comm)); /* the solves */
  PetscCall(PostprocessView(comm, &user->quantities));
  PetscCall(VerifyView(comm, &user->errors, &user->ref_errors));
  {
    const DriverReport r = {
        .opt = user->opt, .scene = &user->scene, .contact = user->contact, .stats = s, .quantities = &user->quantities, .dim = dim};

    PetscCall(DriversView(user->drivers, comm, &r)); /* the adaptive cycles, the load path */
  }
  PetscCall(EstimateView(comm, &user->estimate, &user->errors));
  PetscCall(BarsView(comm, &user->bars));
  PetscCall(ContactChecksWarnings(comm, &user->checks, PETSC_TRUE, NULL));
  if (user->diagnostics_failed[0])
    PetscCall(
        PetscPrintf(comm, "  WARNING: written without a diagnostic that failed after the solve (exit status 4): %s\n", user->diagnostics_failed));
  PetscCall(PetscPrintf(comm, "  time: setup %.3f s, solve %.3f s, total %.3f s; peak memory %.1f MB per rank (max), %.1f MB in all\n", s->time_setup,
                        s->time_solve, s->time_total, (double)s->peak_memory_mb, (double)s->peak_memory_total_mb));
  PetscCall(BandwidthView(comm, &user->bandwidth));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Peak resident set size of each rank, its maximum and sum over the ranks, in MB: the process's own high-water mark,
   VmHWM of /proc/self/status, where Linux has it. getrusage()'s ru_maxrss is kept across execve(), so that a run
   started by a large process (a Python script holding its results) would report the resident set the starter had
   when it forked as its own peak (docs/output.md); ru_maxrss is the fallback. */
/* The run's results in the output: each module writes its own part of /run and its tables (docs/output.md), in the
   order of the run: the scene, the method, the solve and its drivers, the distribution. */
static PetscErrorCode WriteResults(DM dm, Vec u, PetscViewer v, void *ctx)
{
  const AppCtx   *user  = (const AppCtx *)ctx;
  MPI_Comm        comm  = PetscObjectComm((PetscObject)dm);
  const RunStats *stats = SolverStats(user->solver);
  PetscInt        dim;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(RunAttrReal(v, stats->time_total, "time_total"));
  PetscCall(RunAttrReal(v, stats->peak_memory_mb, "peak_memory_mb"));
  PetscCall(RunAttrReal(v, stats->peak_memory_total_mb, "peak_memory_total_mb"));
  if (user->diagnostics_failed[0]) PetscCall(RunAttrString(v, user->diagnostics_failed, "diagnostics_failed"));
  PetscCall(MeshBoxWrite(&user->box, v));
  PetscCall(SceneWrite(&user->scene, &user->opt->material, dim, v));
  PetscCall(ContactWrite(user->contact, v));
  PetscCall(PostprocessWrite(&user->quantities, &user->scene.bcs, dim, v));
  PetscCall(ContactChecksWrite(comm, &user->checks, v));
  PetscCall(VerifyWrite(&user->opt->verify, &user->errors, &user->ref_errors, v));
  PetscCall(EstimateWrite(&user->estimate, v));
  PetscCall(BarsWrite(&user->bars, v));
  PetscCall(SolverWrite(user->solver, comm, v)); /* with /solves */
  {
    const DriverReport r = {
        .opt = user->opt, .scene = &user->scene, .contact = user->contact, .stats = stats, .quantities = &user->quantities, .dim = dim};

    PetscCall(DriversWrite(user->drivers, comm, &r, v)); /* the cycles, the penetration tolerance, the steps */
  }
  PetscCall(BandwidthWrite(&user->bandwidth, v));
  PetscCall(MeshPartitionWrite(&user->partition, v));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The output file: the mesh and the fields (src/io/), and the results (WriteResults()). */
static PetscErrorCode WriteOutput(DM dm, const AppCtx *user, Vec u)
{
  OutputContent out = {.path          = user->opt->output,
                       .dmview        = user->opt->output_dmview,
                       .contact       = user->contact,
                       .loc_bc        = SolverProblem(user->solver)->loc_bc,
                       .scene         = &user->scene,
                       .degree        = user->opt->degree,
                       .bars          = &user->bars,
                       .estimate      = &user->estimate,
                       .write_results = WriteResults,
                       .ctx           = (void *)user};

  PetscFunctionBeginUser;
  PetscCall(DriversGetStepFields(user->drivers, &out.nsteps, &out.step_fields)); /* a load path's time series */
  PetscCall(OutputWriteHDF5(dm, u, &out));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode RecordPeakMemory(MPI_Comm comm, RunStats *s)
{
  struct rusage ru;
  PetscReal     mb = -1.0;
  FILE         *fp = fopen("/proc/self/status", "r");

  PetscFunctionBeginUser;
  if (fp) {
    char line[256];

    while (fgets(line, sizeof(line), fp))
      if (!strncmp(line, "VmHWM:", 6)) mb = atof(line + 6) / 1024.0; /* kB */
    (void)fclose(fp);
  }
  if (mb < 0.0) {
    PetscCheck(getrusage(RUSAGE_SELF, &ru) == 0, PETSC_COMM_SELF, PETSC_ERR_SYS, "getrusage() failed");
    mb = (PetscReal)ru.ru_maxrss / 1024.0; /* kB on Linux */
  }
  PetscCall(MPIU_Allreduce(&mb, &s->peak_memory_mb, 1, MPIU_REAL, MPIU_MAX, comm));
  PetscCall(MPIU_Allreduce(&mb, &s->peak_memory_total_mb, 1, MPIU_REAL, MPIU_SUM, comm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The diagnostics after the solve (AppDiagnosticRun()), each with what it reads of the run and the record it fills. */
typedef struct {
  DM             dm;
  Vec            u;
  VerifyRun      verify;         /* the error norms' and the -reference comparison's view of the run */
  EstimateRun    estimate;       /* the estimate's */
  PetscBool      estimate_asked; /* -estimate */
  ErrorNorms    *errors, *ref_errors;
  ErrorEstimate *est;
} Diagnostic;

static PetscErrorCode DiagnosticErrorNorms(void *ctx)
{
  const Diagnostic *d = (const Diagnostic *)ctx;

  PetscFunctionBeginUser;
  PetscCall(ErrorNormsCompute(d->dm, &d->verify, d->u, d->errors));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode DiagnosticReference(void *ctx)
{
  const Diagnostic *d = (const Diagnostic *)ctx;

  PetscFunctionBeginUser;
  PetscCall(ReferenceCompute(d->dm, &d->verify, d->u, d->ref_errors));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The estimate where -estimate asks for it; without it the record is reset (no estimate, and no reason for none). */
static PetscErrorCode DiagnosticEstimate(void *ctx)
{
  const Diagnostic *d = (const Diagnostic *)ctx;

  PetscFunctionBeginUser;
  if (d->estimate_asked)
    PetscCall(EstimateCompute(d->dm, &d->estimate, d->u, d->est));
  else
    PetscCall(EstimateReset(d->est));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The options phase: every module reads its options once, into opt, which is read only after it; the Contact reads its
   own (-contact_method, -penalty_*). */
static PetscErrorCode RunGetOptions(MPI_Comm comm, RunOptions *opt, Contact *contact)
{
  PetscFunctionBeginUser;
  PetscCall(SceneGetOptions(comm, opt->scene_name, sizeof(opt->scene_name)));
  PetscCall(ElasticityGetOptions(comm, &opt->material, &opt->degree, &opt->section_check));
  PetscCall(ContactCreate(comm, contact));
  PetscCall(ContactSetFromOptions(*contact)); /* -contact_method, -penalty_* */
  PetscCall(SolverGetOptions(comm, &opt->solver));
  PetscCall(VerifyGetOptions(comm, &opt->verify));
  PetscCall(EstimateGetOptions(comm, opt));
  PetscCall(AssemblyGetOptions(comm, &opt->assembly, &opt->assembly_check));
  PetscCall(OutputGetOptions(comm, opt));
  PetscCall(LoadPathGetOptions(comm, &opt->load_path));
  PetscCall(AdaptGetOptions(comm, &opt->adapt));
  PetscCall(BandwidthGetOptions(comm, &opt->perf_bandwidth));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The set-up, before any solve: the mesh, the solver object, the scene, the problem on the mesh and its SNES, and every
   check of the input that needs them (a -reference file, -estimate, -bars, -adapt_cycles, misspelled options), with the
   set-up's warnings; u, the solution vector, zero. */
static PetscErrorCode RunSetUp(MPI_Comm comm, AppCtx *user, DM *dm, SNES *snes, Vec *u)
{
  const RunOptions *opt = user->opt;
  Problem          *prob;
  RunStats         *stats;

  PetscFunctionBeginUser;
  {
    PetscInt  coarse_requests[2], coarse_faces[3], coarse_min_levels;
    PetscBool coarse_mg, default_mg;

    PetscCall(GridSequenceCoarseRequest(comm, user->contact, opt, coarse_requests, coarse_faces, &coarse_min_levels, &coarse_mg, &default_mg));
    PetscCall(MultigridCreate(coarse_mg, &user->mg));
    PetscCall(MeshCreate(comm, opt->solver.grid_sequence, coarse_requests, coarse_faces, coarse_min_levels, &user->box, dm));
    PetscCall(SolverCreate(opt, user->contact, user->mg, &user->box, &user->solver)); /* the solves' object, for the whole run */
    prob              = SolverProblem(user->solver);
    stats             = SolverStats(user->solver);
    stats->coarse_mg  = coarse_mg;
    stats->default_mg = (PetscBool)(default_mg && user->box.dim == 3 && user->box.coarse_levels > 0);
    PetscCall(MultigridSetDefault(user->mg, stats->default_mg));
  }
  PetscCall(MeshPartitionGetStats(*dm, &user->partition));                    /* the partitioner; the final mesh's cut is taken after the solve */
  PetscCall(SceneCreate(opt->scene_name, *dm, &opt->material, &user->scene)); /* its options, once for every level */
  PetscCall(LoadPathSetUp(comm, opt, user->contact, &user->scene));           /* a load path: the scene at its first factor */
  /* -bars on tetrahedra: the final mesh's eps on the levels below it */
  PetscCall(GridSequenceBarsSizes(*dm, opt, user->contact, &user->box, prob->level));
  if (opt->adapt.cycles || (opt->bars && opt->adapt.model[0])) /* one eps on Gamma_C: the remeshed meshes do not nest */
    PetscCall(MeshSetContactCellSizes(*dm, user->scene.bcs.ncontact, user->scene.bcs.contact_ids));
  PetscCall(ProblemSetUp(*dm, user->solver, &user->scene, snes));
  { /* before the solve, not after it */
    const VerifyRun verify = {.opt = &opt->verify, .scene = &user->scene, .mat = &opt->material, .degree = opt->degree};

    PetscCall(ReferenceCheckFile(*dm, &verify));
  }
  PetscCall(EstimateCheckSupported(*dm, opt->estimate, opt->estimate_given, opt->degree)); /* -estimate on a discretization it does not cover */
  PetscCall(BarsCheck(comm, opt->bars, user->box.coarse_levels + opt->solver.grid_sequence, user->contact)); /* -bars without three nested meshes */
  PetscCall(AdaptCheck(*dm, opt, user->contact, &user->box, &user->scene)); /* -adapt_cycles where it cannot refine */
  PetscCall(EstimateReset(&user->estimate));
  PetscCall(BarsReset(&user->bars));
  { /* initial overlap, an obstacle facing away, a curved boundary refined on its chords, a locking body: warnings */
    const ContactChecksGeometryInputs in = {.contact          = user->contact,
                                            .scene            = &user->scene,
                                            .material         = &opt->material,
                                            .degree           = opt->degree,
                                            .box              = &user->box,
                                            .grid_refinements = opt->adapt.model[0] ? 0 : opt->solver.grid_sequence}; /* a model remeshes */

    PetscCall(ContactChecksGeometry(*dm, &in, &user->checks));
  }
  PetscCall(VecDuplicate(prob->r0, u)); /* a global vector of dm (DMCreateGlobalVector() would scan every mesh point again) */
  PetscCall(PetscObjectSetName((PetscObject)*u, "displacement"));
  PetscCall(DMSNESCheckFromOptions(*snes, *u));     /* -dmsnes_check: PETSc's checks against the exact solution */
  PetscCall(OptionsCheckAllUsed(comm, PETSC_TRUE)); /* a misspelled option before the solve, not after it */
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* After the drivers' solves: the quantities of the solution, its bars and warnings, and the diagnostics (the error norms,
   the -reference comparison, the estimate), each of which is reported and left out where it fails, never the solve lost. */
static PetscErrorCode RunDiagnostics(DM dm, SNES snes, Vec u, AppCtx *user)
{
  const RunOptions *opt   = user->opt;
  const Problem    *prob  = SolverProblem(user->solver);
  const RunStats   *stats = SolverStats(user->solver);

  PetscFunctionBeginUser;
  PetscCall(SolverConditionEstimate(snes, user->solver, u));
  PetscCall(PostprocessContact(dm, user->contact, prob, &user->scene.bcs, &opt->material, u, &user->quantities));
  if (opt->bars) { /* -bars: from the levels' quantities and this mesh's */
    PetscCall(BarsCompute(dm, &user->scene.bcs, user->contact, &user->quantities.q, stats->converged, &user->bars));
  }
  /* cells across the contact zone, contact the mesh does not see: warnings */
  PetscCall(ContactChecksResolution(dm, user->contact, &user->scene.bcs, user->quantities.q.force, u, &user->checks));
  { /* diagnostics: a failure there is reported and the output written without them, never the solve lost */
    char       failed[512];
    Diagnostic d = {
        .dm             = dm,
        .u              = u,
        .verify         = {.opt     = &opt->verify,
                           .scene   = &user->scene,
                           .mat     = &opt->material,
                           .degree  = opt->degree,
                           .contact = user->contact,
                           .h       = prob->h,
                           .loc_bc  = prob->loc_bc,
                           .K       = prob->K},
        .estimate       = {.scene   = &user->scene,
                           .mat     = &opt->material,
                           .verify  = &opt->verify,
                           .contact = user->contact,
                           .degree  = opt->degree,
                           .loc_bc  = prob->loc_bc},
        .estimate_asked = opt->estimate,
        .errors         = &user->errors,
        .ref_errors     = &user->ref_errors,
        .est            = &user->estimate,
    };

    PetscCall(AppDiagnosticRun("error norms", DiagnosticErrorNorms, &d, failed, sizeof(failed)));
    if (failed[0]) {
      PetscCall(ErrorNormsReset(&user->errors));
      PetscCall(PetscStrlcat(user->diagnostics_failed, failed, sizeof(user->diagnostics_failed)));
    }
    PetscCall(AppDiagnosticRun("-reference comparison", DiagnosticReference, &d, failed, sizeof(failed)));
    if (failed[0]) {
      PetscCall(ErrorNormsReset(&user->ref_errors));
      if (user->diagnostics_failed[0]) PetscCall(PetscStrlcat(user->diagnostics_failed, "; ", sizeof(user->diagnostics_failed)));
      PetscCall(PetscStrlcat(user->diagnostics_failed, failed, sizeof(user->diagnostics_failed)));
    }
    PetscCall(AppDiagnosticRun("error estimate", DiagnosticEstimate, &d, failed, sizeof(failed)));
    if (failed[0]) {
      PetscCall(EstimateReset(&user->estimate));
      if (user->diagnostics_failed[0]) PetscCall(PetscStrlcat(user->diagnostics_failed, "; ", sizeof(user->diagnostics_failed)));
      PetscCall(PetscStrlcat(user->diagnostics_failed, failed, sizeof(user->diagnostics_failed)));
    }
  }
  PetscCall(PostprocessPenetration(&user->errors, &user->quantities)); /* with the error norms' finer quadrature */
  PetscCall(MeshPartitionGetStats(dm, &user->partition));              /* of the final mesh */
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The summary, the output file, and a failed solve's reason on its last line. */
static PetscErrorCode RunReport(DM dm, const AppCtx *user, Vec u)
{
  MPI_Comm        comm  = PetscObjectComm((PetscObject)dm);
  const RunStats *stats = SolverStats(user->solver);
  const Problem  *prob  = SolverProblem(user->solver);

  PetscFunctionBeginUser;
  PetscCall(PrintSummary(dm, user, u));
  PetscCall(WriteOutput(dm, user, u));
  PetscCall(PetscPrintf(comm, "  output: %s\n", user->opt->output));
  if (!stats->converged && stats->force_control_failed)
    PetscCall(PetscPrintf(comm, "ERROR: force control did not reach -obstacle_force %g (above: why); written with converged = 0\n",
                          (double)user->scene.obstacle.force));
  else if (!stats->converged && stats->reason > 0)
    PetscCall(PetscPrintf(comm,
                          "ERROR: the nonlinear solve failed: it stopped with %s after %" PetscInt_FMT
                          " Newton steps at residual %g, which fell neither by -snes_rtol from %g nor to round-off for the load %g; written with "
                          "converged = 0\n",
                          SNESConvergedReasons[stats->reason], stats->newton_its, (double)stats->residual_norm, (double)stats->residual_start,
                          (double)prob->load_norm));
  else if (!stats->converged)
    PetscCall(PetscPrintf(comm,
                          "ERROR: the nonlinear solve failed: %s after %" PetscInt_FMT " Newton steps, residual %g; written with converged = 0\n",
                          SNESConvergedReasons[stats->reason], stats->newton_its, (double)stats->residual_norm));

  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The run, from the options to the output; *converged says whether the nonlinear solve converged. An error returns here
   and then to main(), which ends the run as the error asks (AppErrorExit()). */
static PetscErrorCode Run(PetscBool *converged, PetscBool *diagnostics_ok)
{
  AppCtx         user;
  RunOptions     opt;
  RunStats      *stats; /* the solver's */
  DM             dm;
  SNES           snes;
  Vec            u;
  MPI_Comm       comm;
  PetscLogDouble t0, t1;

  PetscFunctionBeginUser;
  comm = PETSC_COMM_WORLD;
  PetscCall(PetscTime(&t0));
  PetscCall(PetscMemzero(&user, sizeof(user)));
  PetscCall(PetscMemzero(&opt, sizeof(opt)));
  PetscCall(OutputFileInstallCleanup());
  PetscCall(OptionsCheckValuesGiven(comm)); /* -young_modulus without its value is not the default */
  PetscCall(SceneRegisterAll());
  PetscCall(DriverRegisterAll());
  PetscCall(RunGetOptions(comm, &opt, &user.contact));
  user.opt = &opt;
  PetscCall(DriversCreate(WriteOutput, &user.drivers)); /* the run's flow after the set-up: include/drivers.h */

  PetscCall(RunSetUp(comm, &user, &dm, &snes, &u));
  stats = SolverStats(user.solver);
  PetscCall(PetscTime(&t1));
  stats->time_setup = t1 - t0;

  PetscCall(DriversSolve(user.drivers, &user, &dm, &snes, &u)); /* the first solve, the cycles, the sweep, ..., the load path */
  PetscCall(RunDiagnostics(dm, snes, u, &user));
  PetscCall(PetscTime(&t1));
  stats->time_total = t1 - t0;
  PetscCall(RecordPeakMemory(comm, stats));
  /* -perf_bandwidth: after the peak memory, which its vectors would raise */
  PetscCall(BandwidthMeasure(snes, opt.perf_bandwidth, &user.bandwidth));
  PetscCall(OptionsCheckAllUsed(comm, PETSC_FALSE)); /* the options read during the solve too */
  PetscCall(RunReport(dm, &user, u));
  *converged      = stats->converged;
  *diagnostics_ok = (PetscBool)!user.diagnostics_failed[0];
  PetscCall(VecDestroy(&u));
  PetscCall(ProblemDestroy(user.solver, &snes));
  PetscCall(SolverDestroy(&user.solver));
  PetscCall(MultigridDestroy(&user.mg));
  PetscCall(DMDestroy(&dm));
  PetscCall(ContactDestroy(&user.contact));
  PetscCall(ContactFinalizePackage());
  PetscCall(DriversDestroy(&user.drivers));
  PetscCall(EstimateReset(&user.estimate));
  PetscCall(BarsReset(&user.bars));
  PetscCall(SceneFinalize());
  PetscCall(DriverFinalize());
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  PetscErrorCode ierr;
  PetscBool      converged = PETSC_FALSE, diagnostics_ok = PETSC_TRUE;

  if (OptionsFilesCheckYAML(argc, argv)) return 2; /* a refusal of the input; PETSc's own message would not name the file */
  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(AppErrorPushHandler());
  ierr = Run(&converged, &diagnostics_ok);
  if (ierr) return AppErrorExit(ierr);
  PetscCall(PetscPopErrorHandler());
  PetscCall(PetscFinalize());
  return !converged ? 3 : diagnostics_ok ? 0 : 4; /* 4: converged, written without a diagnostic that failed */
}
