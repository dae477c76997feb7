/* -adapt_cycles N: adaptive refinement driven by the error estimate (issue 34). After the first solve, each cycle
   estimates the error of the solution (src/estimate/), marks the fewest cells whose indicators hold the fraction
   -adapt_fraction of the estimate's square (Doerfler, src/estimate/marking.c), and makes the next mesh:
   - 2D, a polygonal body: PETSc's skeleton-based refinement of the marked cells and as many more as keep the mesh
     conforming (MeshRefineMarked()); the last solution is interpolated (the meshes are nested: exact for P1), as
     nested iteration does (GridSequenceRefine()); the face sets and Gmsh names follow the refinement;
   - a curved body or 3D: Gmsh meshes the body's model (-adapt_model), or the 3D box of the options, again with the
     marked cells' sizes halved (GridSequenceRemesh(), MeshRemesh()), and the last solution is carried to it by
     locating the new vertices in the old cells (MeshTransferApply()).
   Then it solves again, from the carried solution, without the eps continuation where it would be one stage
   (SolverStartFromCoarser()). eps is one value on Gamma_C from its smallest cell (MeshSetContactCellSizes()), so that the
   penalty's error shrinks with the contact zone's cells. /cycles records each mesh: unknowns, cells, the estimate, the
   true energy-norm error where the scene knows the exact solution, the quantities and their bars, the marked cells,
   the solve and the times.
   With -accuracy on the zone's size, the cells along the zone's edge are marked too while its one-cell band, the floor
   of the size's bar, is above the tolerance (EstimateMarkContactEdge(); -adapt_mark_edge): Doerfler's marking on the
   energy-norm indicators refines the band only where the energy's error is, and the size's bar cannot fall below it.
   What it saves and costs in 2D and 3D is measured in docs/estimate.md, "Marking the zone's edge".
   -adapt_max_dofs N is a budget, as MFEM's ThresholdRefiner::SetMaxElements(): no mesh with N unknowns or more is
   refined, so the cycles stop at the first that reaches it (its growth over N is one cycle's); where -accuracy is not
   reached there, the summary says so, and /run adapt_stop records why the cycles stopped. It decides where the cycles
   stop, never what they compute. */
#include <petscviewerhdf5.h>
#include <sys/resource.h>
#include "app.h"
#include "contact.h"
#include "estimate.h"
#include "io.h"
#include "mesh.h"
#include "physics.h"
#include "scenes.h"
#include "drivers_impl.h"
#include "verify.h"

/* The adaptive cycles' results: one record per mesh (/cycles), the quantities -accuracy asks for on the mesh's
   dimension (AdaptTargets()), the fraction of the estimate's square the marked cells hold (Doerfler's theta) and why
   the cycles stopped. */
typedef struct {
  CycleRecord *cycles;
  PetscInt     ncycles;
  PetscBool    target[ACCURACY_NUM];
  PetscReal    fraction;
  AdaptStop    stop;
} Adapt;

#define ADAPT_ACCURACY_CYCLES 40 /* -accuracy's most cycles unless -adapt_cycles says */

const char *const AdaptStops[] = {"accuracy",  "cycles",     "max_dofs",     "solve_failed", "nothing_marked", "interrupted",
                                  "fixed_eps", "max_memory", "out_of_reach", "AdaptStop",    "ADAPT_STOP_",    NULL};

/* The default memory budget of the cycles, MB over all ranks: ADAPT_MEMORY_SHARE of what each rank's node had available
   at the start (/proc/meminfo's MemAvailable, shared by the ranks on the node) plus what the rank held then, so that
   the cycles stop before the kernel kills the run (docs/options.md). */
#define ADAPT_MEMORY_SHARE 0.8

static PetscErrorCode AdaptDefaultMemory(MPI_Comm comm, PetscReal *mb)
{
  MPI_Comm       node;
  PetscMPIInt    on_node;
  PetscLogDouble rss = 0.0;
  PetscReal      mine, available = 0.0;
  FILE          *fp;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_split_type(comm, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &node));
  PetscCallMPI(MPI_Comm_size(node, &on_node));
  PetscCallMPI(MPI_Comm_free(&node));
  if ((fp = fopen("/proc/meminfo", "r"))) {
    char line[256];

    while (fgets(line, sizeof(line), fp)) {
      double kb;

      if (sscanf(line, "MemAvailable: %lf kB", &kb) == 1) available = (PetscReal)kb / 1024.0;
    }
    (void)fclose(fp);
  }
  PetscCall(PetscMemoryGetCurrentUsage(&rss));
  mine = available > 0.0 ? ADAPT_MEMORY_SHARE * (available / on_node + (PetscReal)rss / 1048576.0) : 0.0; /* 0: not known, no budget */
  PetscCall(MPIU_Allreduce(&mine, mb, 1, MPIU_REAL, MPIU_SUM, comm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode AdaptGetOptions(MPI_Comm comm, AdaptOptions *ad)
{
  PetscEnum quantities[ACCURACY_NUM];
  PetscInt  nq = ACCURACY_NUM;
  PetscBool cycles_given, quantities_given, fraction_given;

  PetscFunctionBeginUser;
  for (PetscInt k = 0; k < ACCURACY_NUM; ++k) quantities[k] = (PetscEnum)k; /* what -help shows */
  ad->cycles          = 0;
  ad->fraction        = 0.0; /* AdaptFraction()'s default */
  ad->accuracy        = 0.0;
  ad->newton_fraction = 0.0;
  ad->mark_edge       = PETSC_TRUE;
  ad->max_dofs        = 0;
  PetscCall(OptionsCheckEnum(comm, "-accuracy_quantity", AccuracyQuantities, PETSC_TRUE)); /* a misspelled quantity named, with the nearest */
  PetscOptionsBegin(comm, NULL, "Adaptive refinement", "Signorini");
  PetscCall(PetscOptionsInt(
      "-adapt_cycles",
      "Refine where the error estimate is largest and solve again, this many times (2D triangles, P1); with -accuracy, at most this many", NULL,
      ad->cycles, &ad->cycles, &cycles_given));
  PetscCall(PetscOptionsReal("-adapt_fraction",
                             "The fraction of the estimate's square that the cells refined at each cycle hold (Doerfler's theta; default 0.5, "
                             "and 0.3 in 3D where -accuracy asks for contact quantities only)",
                             NULL, ad->fraction, &ad->fraction, &fraction_given));
  PetscCall(PetscOptionsReal("-accuracy", "Refine adaptively until the error bars of the quantities are below this fraction of their values", NULL,
                             ad->accuracy, &ad->accuracy, NULL));
  PetscCall(PetscOptionsEnumArray(
      "-accuracy_quantity",
      "The quantities -accuracy asks for (energy: the energy-norm estimate against the solution's energy norm; pressure_peak: the "
      "largest pressure recovered from the nodes around it; default: energy, contact_force, contact_size and the largest pressure, "
      "pressure_max in 2D and pressure_peak in 3D)",
      NULL, AccuracyQuantities, quantities, &nq, &quantities_given));
  PetscCall(PetscOptionsReal("-accuracy_newton_fraction",
                             "Each cycle's Newton stops once its step's energy norm is below this fraction of the error estimate expected on the "
                             "cycle's mesh (0: at -snes_rtol)",
                             NULL, ad->newton_fraction, &ad->newton_fraction, NULL));
  PetscCall(PetscOptionsBool("-adapt_mark_edge",
                             "With -accuracy on the contact size, refine the cells along the contact zone's edge too while its one-cell band, "
                             "the floor of the size's bar, is above the tolerance",
                             NULL, ad->mark_edge, &ad->mark_edge, NULL));
  ad->monitor = (PetscBool)(ad->accuracy > 0.0 || ad->cycles > 0); /* a long run prints a line per cycle by default */
  PetscCall(PetscOptionsBool("-adapt_monitor",
                             "Print a line for each adaptive cycle as it ends: its unknowns, estimate, solve, time and, with -accuracy, the bars "
                             "asked for",
                             NULL, ad->monitor, &ad->monitor, NULL));
  PetscCall(PetscOptionsInt("-adapt_max_dofs",
                            "Refine no mesh with this many unknowns or more: the cycles stop there, as a budget (0: no limit; the last mesh "
                            "may exceed it by one cycle's growth)",
                            NULL, ad->max_dofs, &ad->max_dofs, NULL));
  ad->max_memory = 0.0;
  PetscCall(PetscOptionsReal("-adapt_max_memory",
                             "Refine no mesh whose cycle is predicted to take more memory than this, MB over all ranks (default: 80% of the memory "
                             "available at the start; 0: no limit)",
                             NULL, ad->max_memory, &ad->max_memory, &ad->max_memory_given));
  ad->model[0] = '\0';
  PetscCall(PetscOptionsString(
      "-adapt_model",
      "A Gmsh model (.geo) of the body, meshed again by Gmsh at each cycle with the sizes the marking asks for (3D, curved boundaries)", "MeshRemesh",
      ad->model, ad->model, sizeof(ad->model), NULL));
  PetscOptionsEnd();
  if (ad->model[0]) {
    PetscBool exists;

    PetscCall(PetscTestFile(ad->model, 'r', &exists));
    char where[PETSC_MAX_PATH_LEN + 96];

    PetscCall(OptionsPathWhere(ad->model, where, sizeof(where)));
    PetscCheck(exists, comm, PETSC_ERR_USER_INPUT, "-adapt_model: the Gmsh model '%s' does not exist or cannot be read%s", ad->model, where);
  }
  PetscCheck(ad->cycles >= 0, comm, PETSC_ERR_USER_INPUT, "-adapt_cycles must be >= 0, got %" PetscInt_FMT, ad->cycles);
  PetscCheck(ad->max_dofs >= 0, comm, PETSC_ERR_USER_INPUT, "-adapt_max_dofs must be >= 0 (0: no limit), got %" PetscInt_FMT, ad->max_dofs);
  PetscCall(OptionsCheckFinite(comm, "-adapt_max_memory", ad->max_memory));
  PetscCheck(ad->max_memory >= 0.0, comm, PETSC_ERR_USER_INPUT, "-adapt_max_memory must be >= 0 MB (0: no limit), got %g", (double)ad->max_memory);
  if (!ad->max_memory_given && (ad->cycles > 0 || ad->accuracy > 0.0)) PetscCall(AdaptDefaultMemory(comm, &ad->max_memory));
  ad->run_to_budget = (PetscBool)(cycles_given || ad->max_dofs > 0);
  PetscCheck(!fraction_given || (ad->fraction > 0.0 && ad->fraction <= 1.0), comm, PETSC_ERR_USER_INPUT, "-adapt_fraction must lie in (0, 1], got %g",
             (double)ad->fraction);
  PetscCheck(ad->accuracy >= 0.0 && ad->accuracy < 1.0, comm, PETSC_ERR_USER_INPUT, "-accuracy is a relative error in (0, 1), got %g",
             (double)ad->accuracy);
  PetscCheck(ad->newton_fraction >= 0.0 && ad->newton_fraction < 1.0, comm, PETSC_ERR_USER_INPUT,
             "-accuracy_newton_fraction is a fraction of the error estimate in [0, 1), got %g", (double)ad->newton_fraction);
  PetscCheck(!quantities_given || ad->accuracy > 0.0, comm, PETSC_ERR_USER_INPUT, "-accuracy_quantity needs -accuracy TOL");
  PetscCheck(!quantities_given || nq > 0, comm, PETSC_ERR_USER_INPUT,
             "-accuracy_quantity needs at least one of energy, contact_force, pressure_max, contact_size, pressure_peak");
  for (PetscInt k = 0; k < ACCURACY_NUM; ++k) ad->target[k] = PETSC_FALSE; /* the default's, AdaptTargets() */
  for (PetscInt k = 0; k < nq && quantities_given; ++k) ad->target[quantities[k]] = PETSC_TRUE;
  if (ad->accuracy > 0.0) {
    PetscCheck(!cycles_given || ad->cycles > 0, comm, PETSC_ERR_USER_INPUT, "-accuracy refines adaptively: -adapt_cycles 0 leaves it no cycle");
    if (!cycles_given) ad->cycles = ADAPT_ACCURACY_CYCLES;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* What the adaptive cycles (and -bars's remeshed levels) cannot do yet with the options opt, the contact ct, the mesh
   box and the scene, refused before the solve. */
PetscErrorCode AdaptCheck(DM dm, const RunOptions *opt, Contact ct, const MeshBox *box, const Scene *scene)
{
  MPI_Comm              comm = PetscObjectComm((PetscObject)dm);
  const ContactOptions *copt;
  PetscInt              dim;
  PetscBool             simplex, is_mg;

  PetscFunctionBeginUser;
  PetscCheck(!opt->adapt.model[0] || opt->adapt.cycles > 0 || (opt->bars && opt->solver.grid_sequence > 0), comm, PETSC_ERR_USER_INPUT,
             "-adapt_model %s is the model that -adapt_cycles and -accuracy mesh again at each cycle, and -bars with -contact_grid_sequence at "
             "each level; without them nothing reads it (-dm_refine refines the mesh itself): give -accuracy TOL, -adapt_cycles N or -bars "
             "-contact_grid_sequence 2, or leave -adapt_model out",
             opt->adapt.model);
  PetscCall(PetscStrcmp(opt->solver.given.pc_type, PCMG, &is_mg));
  if (!opt->adapt.cycles && opt->adapt.model[0]) { /* -bars's levels, remeshed */
    PetscCall(DMPlexIsSimplex(dm, &simplex));
    PetscCheck(simplex, comm, PETSC_ERR_USER_INPUT, "-bars with -adapt_model remeshes triangles and tetrahedra only");
    PetscCheck(!is_mg, comm, PETSC_ERR_USER_INPUT,
               "-bars with -adapt_model: the remeshed levels do not nest, which -pc_type mg needs: use GAMG or MUMPS");
    PetscCheck(opt->degree == 1, comm, PETSC_ERR_USER_INPUT, "-bars with -adapt_model needs P1 displacements (the remeshed levels carry P1 fields)");
    PetscCall(MeshRemeshCheckModel(dm, opt->adapt.model));
  }
  if (!opt->adapt.cycles) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMPlexIsSimplex(dm, &simplex));
  PetscCall(ContactGetOptions(ct, &copt));
  PetscCheck(simplex, comm, PETSC_ERR_USER_INPUT, "-adapt_cycles refines triangles and tetrahedra only, not %s",
             dim == 3 ? "hexahedra" : "quadrilaterals");
  PetscCheck(dim == 2 || opt->adapt.model[0] || !box->from_file, comm, PETSC_ERR_USER_INPUT,
             "-adapt_cycles on a 3D mesh file needs the Gmsh model of the body (-adapt_model FILE.geo), which Gmsh meshes again at each cycle: "
             "PETSc 3.18 as Debian builds it has no conforming local refinement of tetrahedra (scripts/make_mesh.py --model FILE.geo writes the "
             "model of its meshes)");
  PetscCheck(opt->degree == 1, comm, PETSC_ERR_USER_INPUT, "-adapt_cycles needs P1 displacements, got -displacement_petscspace_degree %" PetscInt_FMT,
             opt->degree);
  PetscCheck(opt->estimate, comm, PETSC_ERR_USER_INPUT,
             "-adapt_cycles refines where the error estimate is largest: it cannot run with -estimate false");
  PetscCheck(!opt->bars, comm, PETSC_ERR_USER_INPUT, "-adapt_cycles with -bars is not supported yet: the bars need three uniformly nested meshes");
  /* The drivers after the cycles (DRIVER_FLOW, src/drivers/drivers.c) solve on the cycles' last mesh: the eps sweep, the
     penetration tolerance and the load path from the cycles' state. -accuracy bounds the error of that one state, which
     they would change after its bars were computed, so that the bars written would be those of another state. */
  PetscCheck(!(opt->adapt.accuracy > 0.0 && copt->n_sweep > 1), comm, PETSC_ERR_USER_INPUT,
             "-accuracy bounds the error of one solve's state, and -penalty_eps0_sweep solves again at other eps after it: give one of them "
             "(-adapt_cycles N adapts the mesh, and the sweep then runs on its last mesh)");
  PetscCheck(!(opt->adapt.accuracy > 0.0 && copt->penetration_tol > 0.0), comm, PETSC_ERR_USER_INPUT,
             "-accuracy bounds the error of one solve's state, and -contact_penetration_tol lowers eps after it: give one of them "
             "(-adapt_cycles N adapts the mesh, and the penetration tolerance is then reached on its last mesh)");
  PetscCheck(!(opt->adapt.accuracy > 0.0 && opt->load_path.n), comm, PETSC_ERR_USER_INPUT,
             "-accuracy bounds the error of one load state, and a load path (-load_steps, -load_path) solves others after it: give one of them "
             "(-adapt_cycles N adapts the mesh to the path's first load state, and the path then runs on its last mesh)");
  /* the cycles adapt the mesh to the solution at the obstacle's given translation, and force control would move it on
     the last mesh only: the bars printed would belong to another state than the one written */
  PetscCheck(!SceneForceControlled(scene), comm, PETSC_ERR_USER_INPUT,
             "-adapt_cycles and -accuracy with -obstacle_force are not supported yet: the cycles adapt to one position of the obstacle, and "
             "force control would move it on the last mesh only, so that the bars would be those of another state than the one written; give "
             "the obstacle's translation instead (a force-controlled run on a fixed mesh reports the translation it found)");
  PetscCheck(!opt->verify.reference[0], comm, PETSC_ERR_USER_INPUT,
             "-adapt_cycles with -reference is not supported: the reference is on another mesh");
  PetscCheck(!is_mg, comm, PETSC_ERR_USER_INPUT,
             "-adapt_cycles with -pc_type mg is not supported yet: use GAMG (options/solvers/gamg.yaml) or MUMPS");
  PetscCall(MeshRemeshCheckModel(dm, opt->adapt.model)); /* a model the cycles could not remesh, before the first solve */
  PetscCheck(opt->adapt.model[0] || !box->from_file || box->curved_ridges < MESH_CURVED_RIDGES_MIN, comm, PETSC_ERR_USER_INPUT,
             "-adapt_cycles: the mesh file's boundary turns by less than 20 degrees at %" PetscInt_FMT
             " of its vertices (one at %g, %g), a curved boundary's chords: the refinement would split them on the chords, and the "
             "answer would be the file's polygon's, not the curved body's (the Hertz cylinder meshed at h = 0.05: its contact width 27%% short "
             "after 10 cycles): give the body's Gmsh model (-adapt_model FILE.geo; scripts/make_mesh.py --model FILE.geo writes it), "
             "which Gmsh meshes again at each cycle, its boundary exact",
             box->curved_ridges, (double)box->curved_x[0], (double)box->curved_x[1]);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The cycle's row of /cycles: the mesh and its solve (the last record), the estimate of its solution and, where the
   scene knows it, the true error. */
static PetscErrorCode AdaptRecord(DM dm, AppCtx *user, Adapt *a, Vec u, PetscInt k)
{
  Problem           *prob = SolverProblem(user->solver);
  CycleRecord       *c    = &a->cycles[k];
  const SolveRecord *records, *r;
  PetscInt           cStart, cEnd, local, nrecords;

  PetscFunctionBeginUser;
  PetscCall(SolverGetSolves(user->solver, &records, &nrecords));
  r = &records[nrecords - 1];
  PetscCall(EstimateReset(&user->estimate));
  if (user->opt->estimate) { /* always: -adapt_cycles refuses -estimate false (AdaptCheck()) */
    const EstimateRun run = {.scene   = &user->scene,
                             .mat     = &user->opt->material,
                             .verify  = &user->opt->verify,
                             .contact = user->contact,
                             .degree  = user->opt->degree,
                             .loc_bc  = prob->loc_bc};

    PetscCall(EstimateCompute(dm, &run, u, &user->estimate));
  }
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  local = cEnd - cStart;
  PetscCall(MPIU_Allreduce(&local, &c->n_cells, 1, MPIU_INT, MPIU_SUM, PetscObjectComm((PetscObject)dm)));
  c->n_dofs           = r->n_dofs;
  c->newton_its       = r->newton_its;
  c->ksp_its          = r->ksp_its;
  c->time_solve       = r->time_solve;
  c->converged        = r->converged;
  c->estimate         = user->estimate.total;
  c->estimate_penalty = user->estimate.part[ESTIMATE_PENALTY];
  c->norm             = user->estimate.norm;
  PetscCall(PostprocessContact(dm, user->contact, prob, &user->scene.bcs, &user->opt->material, u, &user->quantities));
  c->q      = user->quantities.q;
  c->marked = 0;
  for (PetscInt q = 0; q < ACCURACY_NUM; ++q) c->value_eps[q] = PETSC_NAN;
  c->eps       = PETSC_NAN;
  c->eps_scale = PETSC_NAN;
  if (ContactGetEpsScaling(user->contact) != CONTACT_EPS_NONE) { /* NaN in /cycles for the types without eps */
    PetscCall(ContactGetEps(user->contact, &c->eps));
    PetscCall(ContactGetPenaltyScale(user->contact, &c->eps_scale));
  }
  c->error_energy = PETSC_NAN;
  if (user->scene.exact) {
    const VerifyRun run = {.opt     = &user->opt->verify,
                           .scene   = &user->scene,
                           .mat     = &user->opt->material,
                           .degree  = user->opt->degree,
                           .contact = user->contact,
                           .h       = prob->h,
                           .loc_bc  = prob->loc_bc,
                           .K       = prob->K};

    PetscCall(ErrorNormsCompute(dm, &run, u, &user->errors));
    c->error_energy = user->errors.energy;
  }
  a->ncycles = k + 1;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The quantities' penalty parts (src/estimate/cycle_bars.c): with -accuracy on the force, the largest pressure or the
   zone's size and the penalty method, the quantities at eps / CYCLE_EPS_RATIO on the cycle's mesh, predicted along the
   tangent of the solution path from the cycle's solution (one linear solve with its preconditioner, EpsSweepTangent(),
   whose iterations count in the run's totals); the cycle records them. The cycle's solution, eps and contact state stay
   as they were. No values if the tangent's solve fails. */
static PetscErrorCode AdaptQuantitiesAtSmallerEps(DM dm, AppCtx *user, const Adapt *a, SNES snes, Vec u, CycleRecord *c)
{
  Problem            *prob   = SolverProblem(user->solver);
  RunStats           *stats  = SolverStats(user->solver);
  const AdaptOptions *ad     = &user->opt->adapt;
  const PetscBool    *target = a->target;
  PetscReal           eps, eps_new;
  PetscBool           ok = PETSC_FALSE;
  PetscInt            dim;
  Vec                 dir, u_new;
  Quantities          q;

  PetscFunctionBeginUser;
  if (!(ad->accuracy > 0.0) || !(target[ACCURACY_FORCE] || target[ACCURACY_PRESSURE] || target[ACCURACY_SIZE] || target[ACCURACY_PEAK]) ||
      !ContactHasPenalty(user->contact) || !c->converged) /* a driver's question: a second solve at eps / R has an eps to vary */
    PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(ContactGetEps(user->contact, &eps));
  eps_new = eps / CYCLE_EPS_RATIO;
  PetscCall(ContactSetEps(user->contact, dm, eps_new));
  PetscCall(VecDuplicate(u, &dir));
  PetscCall(EpsSweepTangent(snes, dm, user->contact, u, dir, &stats->ksp_its_total, &ok));
  if (ok) { /* u(eps_new) = u + (eps_new - eps) du/deps, du/deps = dir eps_new / eps^2 */
    PetscCall(VecDuplicate(u, &u_new));
    PetscCall(VecWAXPY(u_new, (eps_new - eps) * eps_new / (eps * eps), dir, u));
    PetscCall(PostprocessContact(dm, user->contact, prob, &user->scene.bcs, &user->opt->material, u_new, &user->quantities));
    q                               = user->quantities.q;
    c->value_eps[ACCURACY_FORCE]    = PostprocessForceMagnitude(&q, dim);
    c->value_eps[ACCURACY_PRESSURE] = q.pressure_max;
    c->value_eps[ACCURACY_SIZE]     = q.contact_size;
    c->value_eps[ACCURACY_PEAK]     = q.pressure_peak;
    PetscCall(VecDestroy(&u_new));
  }
  PetscCall(VecDestroy(&dir));
  PetscCall(ContactSetEps(user->contact, dm, eps));
  /* the contact state of the cycle's solution again */
  PetscCall(PostprocessContact(dm, user->contact, prob, &user->scene.bcs, &user->opt->material, u, &user->quantities));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Whether the last cycle reached -accuracy: a converged solve that sees its contact, and each quantity asked for with
   a bar below the tolerance times its value.
   Seeing its contact: the force the penalty law would put on the nodes the rule misses (ContactUnseenNodes()), which
   no bar holds, is at most ADAPT_UNSEEN_SHARE of the tolerance times the force. A mesh that misses the whole zone has
   no force, and never passes; a resolved zone whose edge leaves a few nodes between the rule's points does (their
   force is a small share of the force: docs/decisions.md, "The nodes the rule does not see"). */
#define ADAPT_UNSEEN_SHARE 0.1

static PetscBool UnseenHolds(const AdaptOptions *ad, const CycleRecord *c)
{
  return (PetscBool)(c->unseen && !(c->unseen_force <= ADAPT_UNSEEN_SHARE * ad->accuracy * c->value[ACCURACY_FORCE]));
}

/* Whether quantity k's bar is within the tolerance on cycle c (a NaN bar, before the cycles compared exist, is not). */
static PetscBool Within(const AdaptOptions *ad, const CycleRecord *c, PetscInt k)
{
  return (PetscBool)(c->bar[k] <= ad->accuracy * PetscAbsReal(c->value[k]));
}

static PetscBool Accurate(const AdaptOptions *ad, const PetscBool target[], const CycleRecord *c)
{
  if (!(ad->accuracy > 0.0) || !c->converged || UnseenHolds(ad, c)) return PETSC_FALSE;
  for (PetscInt k = 0; k < ACCURACY_NUM; ++k)
    if (target[k] && !Within(ad, c, k)) return PETSC_FALSE;
  return PETSC_TRUE;
}

/* Whether the energy's bar alone keeps a converged cycle from -accuracy: asked for and above the tolerance, while every
   other quantity asked for has a bar within it (at least one such quantity). The summary then says so. */
static PetscBool OnlyEnergyHolds(const AdaptOptions *ad, const PetscBool target[], const CycleRecord *c)
{
  PetscBool others = PETSC_FALSE;

  if (!(ad->accuracy > 0.0) || !c->converged || UnseenHolds(ad, c) || !target[ACCURACY_ENERGY] || Within(ad, c, ACCURACY_ENERGY)) return PETSC_FALSE;
  for (PetscInt k = ACCURACY_FORCE; k < ACCURACY_NUM; ++k) {
    if (!target[k]) continue;
    if (!Within(ad, c, k)) return PETSC_FALSE;
    others = PETSC_TRUE;
  }
  return others;
}

/* The quantities asked for other than the energy, comma-separated, as -accuracy_quantity takes them. */
static PetscErrorCode ContactTargetNames(const PetscBool target[], char names[], size_t len)
{
  PetscFunctionBeginUser;
  names[0] = '\0';
  for (PetscInt k = ACCURACY_FORCE; k < ACCURACY_NUM; ++k)
    if (target[k]) {
      PetscCall(PetscStrlcat(names, names[0] ? "," : "", len));
      PetscCall(PetscStrlcat(names, AccuracyQuantities[k], len));
    }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The first cycle that the energy's bar alone keeps from -accuracy says so as it ends, once: on a body much larger than
   its contact zone the cycles may go on for long for the energy alone, and the user may rather stop and ask for the
   contact quantities. It changes nothing of the run. */
static PetscErrorCode AdaptWarnEnergyAlone(MPI_Comm comm, const AdaptOptions *ad, const PetscBool target[], const CycleRecord *c, PetscInt k,
                                           PetscBool *warned)
{
  char        names[256];
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  if (*warned || !OnlyEnergyHolds(ad, target, c)) PetscFunctionReturn(PETSC_SUCCESS);
  *warned = PETSC_TRUE;
  PetscCall(ContactTargetNames(target, names, sizeof(names)));
  PetscCall(PetscPrintf(comm,
                        "  -accuracy %g: at cycle %" PetscInt_FMT " (%" PetscInt_FMT " dofs) only the energy's bar (%.2g%%) is above the tolerance, "
                        "and the cycles go on for it; -accuracy_quantity %s asks for the contact quantities alone, -adapt_max_dofs bounds "
                        "the cycles\n",
                        (double)ad->accuracy, k, c->n_dofs, (double)(100.0 * c->bar[ACCURACY_ENERGY] / PetscAbsReal(c->value[ACCURACY_ENERGY])),
                        names));
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  if (rank == 0) fflush(PETSC_STDOUT);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* -adapt_monitor: cycle k's line as it ends (the /cycles row's numbers), so that a long -accuracy run shows its progress;
   flushed, since the summary's table comes only after the last cycle. */
static PetscErrorCode AdaptMonitor(MPI_Comm comm, const AdaptOptions *ad, const PetscBool target[], const CycleRecord *c, PetscInt k)
{
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  if (!ad->monitor) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscPrintf(comm, "  adapt cycle %" PetscInt_FMT ": %" PetscInt_FMT " dofs, estimate %.4e, Newton %" PetscInt_FMT ", %.3g s%s", k,
                        c->n_dofs, (double)c->estimate, c->newton_its, (double)c->time_cycle, c->converged ? "" : " (solve failed)"));
  if (ad->accuracy > 0.0) {
    PetscCall(PetscPrintf(comm, "; bars"));
    for (PetscInt q = 0; q < ACCURACY_NUM; ++q) {
      if (!target[q]) continue;
      if (PetscIsNanReal(c->bar[q]))
        PetscCall(PetscPrintf(comm, " %s --", AccuracyQuantities[q]));
      else if (c->value[q] == 0.0) /* a zero solution: no relative bar */
        PetscCall(PetscPrintf(comm, " %s 0 +- %g", AccuracyQuantities[q], (double)c->bar[q]));
      else
        PetscCall(PetscPrintf(comm, " %s %.2g%%", AccuracyQuantities[q], (double)(100.0 * c->bar[q] / PetscAbsReal(c->value[q]))));
    }
    PetscCall(PetscPrintf(comm, "%s", c->accurate ? ": reached" : ""));
  }
  PetscCall(PetscPrintf(comm, "\n"));
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  if (rank == 0) fflush(PETSC_STDOUT);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The quantities -accuracy asks for on a mesh of dimension dim: those of -accuracy_quantity, or by default the force,
   the zone's size and the largest pressure, with the energy in 2D. The largest pressure is the nodal maximum on
   triangles and the recovered peak on tetrahedra, where the nodal pressures scatter by a few percent about the profile
   and the nodal maximum takes the scatter's upper tail, so that its bar, floored by the step from its node to its
   neighbours, does not fall with the cycles. The energy's bar, the estimate against the energy norm, falls like
   N^(-1/dim): in 3D like N^(-1/3), so that a tolerance the contact quantities reach in seconds takes it millions of
   unknowns (docs/estimate.md, "The default quantities in 3D", measures it on README's 3D box). */
static void AdaptTargets(const AdaptOptions *ad, PetscInt dim, PetscBool target[])
{
  PetscBool given = PETSC_FALSE;

  for (PetscInt k = 0; k < ACCURACY_NUM; ++k) given = (PetscBool)(given || ad->target[k]);
  for (PetscInt k = 0; k < ACCURACY_NUM; ++k) target[k] = ad->target[k];
  if (given) return;
  target[ACCURACY_FORCE] = target[ACCURACY_SIZE]       = PETSC_TRUE;
  target[dim == 3 ? ACCURACY_PEAK : ACCURACY_PRESSURE] = PETSC_TRUE;
  target[ACCURACY_ENERGY]                              = (PetscBool)(dim == 2);
}

/* Doerfler's theta: -adapt_fraction where given; by default 0.5, and 0.3 in 3D where -accuracy asks for contact
   quantities only (not the energy). In 3D each remeshed vertex takes the smallest size of its cells
   (mesh_remesh.c), so a marked cell refines its twenty-odd neighbours too, and theta = 0.5 grows the unknowns about
   3 times a cycle: the stop, the first cycle whose bars are within the tolerance, overshoots the unknowns the bars
   need by up to that factor; 0.3 grows them about twice. The energy's estimate is spread over the body, where a
   smaller theta stalls the meshes, and in 2D (no spreading) 0.3 is slower (docs/estimate.md, "Doerfler's fraction
   in 3D"). */
static PetscReal AdaptFraction(const AdaptOptions *ad, const PetscBool target[], PetscInt dim)
{
  if (ad->fraction > 0.0) return ad->fraction;
  if (dim == 3 && ad->accuracy > 0.0 && !target[ACCURACY_ENERGY]) return 0.3;
  return 0.5;
}

/* Whether -accuracy cannot be reached at the fixed eps of -penalty_eps (or -penalty_eps_power 0): a quantity asked for
   whose bar's penalty part alone is above the tolerance on this cycle and the one before, both cycles with a bar
   (CycleBarsPenaltyPart()). The mesh's part falls with the cycles, the penalty's tends to the penalty problem's own
   error, which a fixed eps keeps (docs/estimate.md, "A fixed eps"). Returns the first such quantity (-1: none). */
static PetscInt FixedEpsHolds(const AdaptOptions *ad, Contact ct, const CycleRecord cycles[], const PetscBool target[], PetscInt k)
{
  if (!(ad->accuracy > 0.0) || k < 1 || ContactGetEpsScaling(ct) != CONTACT_EPS_FIXED) return -1;
  for (PetscInt q = 0; q < ACCURACY_NUM; ++q) {
    PetscBool above = target[q];

    for (PetscInt m = k - 1; m <= k && above; ++m) {
      const CycleRecord *c = &cycles[m];

      above = (PetscBool)(!PetscIsNanReal(c->bar[q]) && CycleBarsPenaltyPart(c, q) > ad->accuracy * PetscAbsReal(c->value[q]));
    }
    if (above) return q;
  }
  return -1;
}

/* The run's resident memory now, at a cycle's end (its mesh, its operators and its factorization held), MB summed over
   the ranks. Not the peak so far, which a transient of the start can hold above the first cycles' memory, so that
   their growth would not show. */
static PetscErrorCode AdaptCycleMemory(MPI_Comm comm, PetscReal *mb)
{
  PetscLogDouble rss = 0.0;
  PetscReal      mine;

  PetscFunctionBeginUser;
  PetscCall(PetscMemoryGetCurrentUsage(&rss));
  mine = (PetscReal)rss / 1048576.0;
  PetscCall(MPIU_Allreduce(&mine, mb, 1, MPIU_REAL, MPIU_SUM, comm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The memory the next cycle is predicted to take, MB over all ranks, from the memory at the last two cycles' ends: the part that
   grows with the mesh, m_k - m_(k-1), scaled as N^p from the last cycle's N_(k-1) -> N_k to the next N_(k+1) = g N_k
   (g the last growth of the unknowns), p = 1.2 in 2D and 4/3 in 3D, a sparse direct factorization's fill (n log n and
   n^(4/3) on 2D and 3D meshes), which bounds an iterative solver's. The difference leaves out what does not grow with
   the mesh: the libraries and the set-up, much of it loaded after the options phase. */
static PetscReal AdaptMemoryAt(const CycleRecord c[], PetscInt k, PetscInt dim, PetscReal n)
{
  const PetscReal p  = dim == 3 ? 4.0 / 3.0 : 1.2;
  const PetscReal nk = PetscPowReal((PetscReal)c[k].n_dofs, p), nk1 = PetscPowReal((PetscReal)c[k - 1].n_dofs, p), at = PetscPowReal(n, p);
  const PetscReal grown = PetscMax(c[k].memory_mb - c[k - 1].memory_mb, 0.0);

  return c[k].memory_mb + (nk > nk1 ? grown * (at - nk) / (nk - nk1) : 0.0);
}

static void AdaptPredictMemory(const CycleRecord c[], PetscInt k, PetscInt dim, PetscReal *mb, PetscReal *growth)
{
  *growth = PetscMax((PetscReal)c[k].n_dofs / (PetscReal)c[k - 1].n_dofs, 1.0);
  *mb     = AdaptMemoryAt(c, k, dim, *growth * (PetscReal)c[k].n_dofs);
}

/* Whether -accuracy is out of reach within -adapt_max_memory: a quantity asked for whose bar falls so slowly with the
   cycles that, at the rate it fell, it reaches the tolerance only on a mesh predicted (AdaptMemoryAt()) to take more
   than ADAPT_REACH_MARGIN times the memory budget, so that the cycles would end at the budget anyway, not reached.
   The rate: with b_j the relative bar of the first cycle j with a bar and e_k the smallest relative bar up to cycle k
   (the envelope, so that a bar's scatter from cycle to cycle, the recovered peak's on tetrahedra, does not read as a
   stall), e_k = b_j (N_k / N_j)^(-r), and the tolerance T needs N = N_k (e_k / T)^(1/r) unknowns; r <= 0 needs an
   infinite mesh. The rate is taken once at least three cycles have bars and the unknowns grew 2^dim times over them,
   and the margin covers its extrapolation. A run given -adapt_cycles or -adapt_max_dofs runs on to them (the user's
   budget). Returns the quantity that needs the largest mesh (-1: none), that mesh's unknowns, its memory and its rate. */
#define ADAPT_REACH_MARGIN 4.0
static PetscInt AdaptOutOfReach(const AdaptOptions *ad, const CycleRecord c[], const PetscBool target[], PetscInt k, PetscInt dim, PetscReal *n_need,
                                PetscReal *mb_need, PetscReal *rate)
{
  PetscInt worst = -1;

  *n_need = *mb_need = *rate = 0.0;
  if (!(ad->accuracy > 0.0) || ad->run_to_budget || !(ad->max_memory > 0.0) || k < 1) return -1;
  for (PetscInt q = 0; q < ACCURACY_NUM; ++q) {
    PetscInt  first = -1, nbars = 0;
    PetscReal envelope = PETSC_MAX_REAL, r, n;

    if (!target[q] || c[k].value[q] == 0.0 || !(c[k].bar[q] > ad->accuracy * PetscAbsReal(c[k].value[q]))) continue;
    for (PetscInt m = 0; m <= k; ++m) {
      if (PetscIsNanReal(c[m].bar[q]) || c[m].value[q] == 0.0) continue;
      if (first < 0) first = m;
      envelope = PetscMin(envelope, c[m].bar[q] / PetscAbsReal(c[m].value[q]));
      ++nbars;
    }
    if (nbars < 3 || (PetscReal)c[k].n_dofs < PetscPowReal(2.0, dim) * (PetscReal)c[first].n_dofs || envelope <= ad->accuracy) continue;
    r = PetscLogReal(c[first].bar[q] / PetscAbsReal(c[first].value[q]) / envelope) /
        PetscLogReal((PetscReal)c[k].n_dofs / (PetscReal)c[first].n_dofs);
    n = r > 0.0 ? (PetscReal)c[k].n_dofs * PetscPowReal(envelope / ad->accuracy, 1.0 / r) : PETSC_INFINITY;
    if (worst < 0 || n > *n_need) {
      worst   = q;
      *n_need = n;
      *rate   = r;
    }
  }
  if (worst < 0) return -1;
  *mb_need = PetscIsInfReal(*n_need) ? PETSC_INFINITY : AdaptMemoryAt(c, k, dim, *n_need);
  return *mb_need > ADAPT_REACH_MARGIN * ad->max_memory ? worst : -1;
}

/* Cycle k finished and another follows: the output written now, with /run adapt_stop = interrupted, so that a run
   ended by a signal (Ctrl-C, a scheduler's SIGTERM at its time limit) keeps a finished cycle, its /cycles and its
   bars, and says so as it dies (OutputFileStageSignalNote()); the run's final write replaces it. A cycle is written
   where the cycles since the last write took ADAPT_CHECKPOINT_RATIO times that write's time (the first always), so
   that the writes cost at most about 1/ADAPT_CHECKPOINT_RATIO of the run (docs/running.md); the small first cycles'
   writes cost as much as their solves, while a long run's cycles, each far dearer than a write, are each written. */
#define ADAPT_CHECKPOINT_RATIO 20.0
/* What a signal during the checkpoint of cycle c (the k-th) into the file output says as the run dies. */
static PetscErrorCode AdaptCheckpointNote(MPI_Comm comm, const char output[], const CycleRecord *c, PetscInt k)
{
  char note[1024];

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(note, sizeof(note),
                          "signorini: interrupted during adaptive cycle %" PetscInt_FMT ": %s holds cycle %" PetscInt_FMT " (%" PetscInt_FMT
                          " dofs), with /run adapt_stop = interrupted\n",
                          k + 1, output, k, c->n_dofs));
  PetscCall(OutputFileStageSignalNote(comm, note));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The adaptive cycles from the run's solution (-adapt_cycles, -accuracy): estimate, mark, refine or remesh, solve,
   until the quantities asked for are accurate or a budget is spent; each finished cycle is written as a checkpoint
   (d->checkpoint) where the cycles since the last write took long enough, so that an interrupted run keeps it. */
static PetscErrorCode AdaptSolve(Driver d, AppCtx *user, DM *dm, SNES *snes, Vec *u)
{
  RunStats           *stats = SolverStats(user->solver);
  Adapt              *a     = (Adapt *)d->data;
  const OutputWriter  write = d->checkpoint;
  const AdaptOptions *ad    = &user->opt->adapt;
  PetscInt            dim;
  PetscBool           remesh;
  PetscLogDouble      t_last, time_mesh = 0.0, ck_cost = 0.0, ck_since = 0.0; /* the last checkpoint's write, and the cycles' time since */
  PetscBool           warned_energy = PETSC_FALSE;                            /* AdaptWarnEnergyAlone(), once */

  PetscFunctionBeginUser;
  if (!ad->cycles) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(DMGetDimension(*dm, &dim));
  remesh = (PetscBool)(ad->model[0] || dim == 3); /* Gmsh meshes the model, or the 3D box of the options, again (MeshRemesh()) */
  AdaptTargets(ad, dim, a->target);
  a->fraction = AdaptFraction(ad, a->target, dim);
  PetscCall(PetscCalloc1(ad->cycles + 1, &a->cycles));
  PetscCall(PetscTime(&t_last));
  for (PetscInt k = 0;; ++k) {
    CycleRecord   *c      = &a->cycles[k];
    DMLabel        marked = NULL;
    PetscLogDouble t0, t1;
    SolverStart    start;
    PetscBool      at_max, done, at_memory;
    PetscInt       fixed_eps, unreachable = -1;
    PetscReal      next_mb = 0.0, growth = 1.0, n_need = 0.0, mb_need = 0.0, rate = 0.0;

    PetscCall(AdaptRecord(*dm, user, a, *u, k));
    PetscCall(AdaptQuantitiesAtSmallerEps(*dm, user, a, *snes, *u, c));
    c->time_mesh = time_mesh;
    PetscCall(CycleBarsCompute(a->cycles, dim, k));
    /* the cells around the contact the mesh misses */
    PetscCall(EstimateMarkUnseenContact(*dm, user->contact, *u, &marked, &c->unseen, &c->unseen_force));
    c->accurate    = Accurate(ad, a->target, c);
    c->marked_edge = 0;
    at_max         = (PetscBool)(ad->max_dofs > 0 && c->n_dofs >= ad->max_dofs);
    fixed_eps      = c->accurate ? -1 : FixedEpsHolds(ad, user->contact, a->cycles, a->target, k);
    PetscCall(AdaptCycleMemory(PetscObjectComm((PetscObject)*dm), &c->memory_mb));
    at_memory = PETSC_FALSE;
    if (!c->accurate && !at_max && fixed_eps < 0 && k < ad->cycles && ad->max_memory > 0.0 && k > 0) { /* from the first measured growth */
      AdaptPredictMemory(a->cycles, k, dim, &next_mb, &growth);
      at_memory = (PetscBool)(next_mb > ad->max_memory);
      if (!at_memory) unreachable = AdaptOutOfReach(ad, a->cycles, a->target, k, dim, &n_need, &mb_need, &rate);
    }
    if (!c->accurate && k < ad->cycles && stats->converged && !at_max && fixed_eps < 0 && !at_memory && unreachable < 0) {
      PetscCall(EstimateMark(*dm, &user->estimate, a->fraction, &marked, &c->marked));
      if (ad->mark_edge && ad->accuracy > 0.0 && a->target[ACCURACY_SIZE] &&
          c->q.contact_size_band > ad->accuracy * PetscAbsReal(c->q.contact_size)) {
        PetscInt *faces, nfaces;

        PetscCall(PostprocessContactEdgeFaces(*dm, user->contact, &user->scene.bcs, &user->opt->material, *u, &nfaces, &faces));
        PetscCall(EstimateMarkContactEdge(*dm, nfaces, faces, &marked, &c->marked_edge));
        PetscCall(PetscFree(faces));
      }
    }
    PetscCall(PetscTime(&t0)); /* the cycle: its mesh, its solve (the first solve for cycle 0), estimate and marking */
    c->time_cycle = (t0 - t_last) + (k == 0 ? c->time_solve : 0.0);
    t_last        = t0;
    /* the slowest rank's time, so that every rank takes the checkpoint's decision below alike: a rank's own clock
       would have one rank enter the collective write and the other go on to the next cycle, and the run hang */
    PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &c->time_cycle, 1, MPIU_REAL, MPIU_MAX, PetscObjectComm((PetscObject)*dm)));
    done = (PetscBool)(c->accurate || !stats->converged || at_max || fixed_eps >= 0 || at_memory || unreachable >= 0 || k == ad->cycles ||
                       (!c->marked && !c->marked_edge && !c->unseen)); /* done, or a zero estimate: nothing to refine */
    ck_since += c->time_cycle;
    if (!done && (ck_cost == 0.0 || ck_since >= ADAPT_CHECKPOINT_RATIO * ck_cost)) { /* what a signal during the next cycles leaves */
      PetscLogDouble w0, w1;

      PetscCall(PetscTime(&w0));
      if (write) {
        PetscCall(AdaptCheckpointNote(PetscObjectComm((PetscObject)*dm), user->opt->output, c, k));
        a->stop = ADAPT_STOP_INTERRUPTED;
        PetscCall(write(*dm, user, *u));
      }
      PetscCall(PetscTime(&w1));
      ck_cost = PetscMax(w1 - w0, 1e-6);
      PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &ck_cost, 1, MPI_DOUBLE, MPI_MAX, PetscObjectComm((PetscObject)*dm))); /* alike on every rank */
      ck_since = 0.0;
    }
    PetscCall(AdaptMonitor(PetscObjectComm((PetscObject)*dm), ad, a->target, c, k)); /* once it is written */
    PetscCall(AdaptWarnEnergyAlone(PetscObjectComm((PetscObject)*dm), ad, a->target, c, k, &warned_energy));
    if (done) {
      a->stop = c->accurate         ? ADAPT_STOP_ACCURACY
                : !stats->converged ? ADAPT_STOP_SOLVE_FAILED
                : at_max            ? ADAPT_STOP_MAX_DOFS
                : fixed_eps >= 0    ? ADAPT_STOP_FIXED_EPS
                : at_memory         ? ADAPT_STOP_MAX_MEMORY
                : unreachable >= 0  ? ADAPT_STOP_OUT_OF_REACH
                : k == ad->cycles   ? ADAPT_STOP_CYCLES
                                    : ADAPT_STOP_NOTHING_MARKED;
      if (at_memory)
        PetscCall(PetscPrintf(PetscObjectComm((PetscObject)*dm),
                              "  the next cycle would take about %.0f MB (the last cycle's growth of memory scaled by its growth of the unknowns, "
                              "%.2g, to the power of a direct factorization's fill), more than -adapt_max_memory %.0f MB%s: the cycles stop at cycle "
                              "%" PetscInt_FMT "\n",
                              (double)next_mb, (double)growth, (double)ad->max_memory,
                              ad->max_memory_given ? "" : " (80% of the memory available at the start)", k));
      if (unreachable >= 0) {
        char need[128];

        if (PetscIsInfReal(n_need))
          PetscCall(PetscSNPrintf(need, sizeof(need), "it does not fall, and no mesh reaches the tolerance"));
        else
          PetscCall(
              PetscSNPrintf(need, sizeof(need), "it reaches the tolerance at about %.2g unknowns, about %.2g MB", (double)n_need, (double)mb_need));
        PetscCall(PetscPrintf(PetscObjectComm((PetscObject)*dm),
                              "  -accuracy %g out of reach: the bar of %s fell as N^(-%.2g) over the cycles with bars (%.2g%% at cycle %" PetscInt_FMT
                              "); at that rate %s, more than %d times -adapt_max_memory %.0f MB%s: the cycles stop at cycle %" PetscInt_FMT
                              " (-adapt_cycles N or -adapt_max_dofs N runs on to that budget)\n",
                              (double)ad->accuracy, AccuracyQuantities[unreachable], (double)rate,
                              (double)(100.0 * c->bar[unreachable] / PetscAbsReal(c->value[unreachable])), k, need, (int)ADAPT_REACH_MARGIN,
                              (double)ad->max_memory, ad->max_memory_given ? "" : " (80% of the memory available at the start)", k));
      }
      if (fixed_eps >= 0) {
        const PetscReal part = CycleBarsPenaltyPart(c, fixed_eps);

        PetscCall(
            PetscPrintf(PetscObjectComm((PetscObject)*dm),
                        "  -accuracy %g: the penalty's part of the %s bar, %.2g%% of it, is above the tolerance on this cycle and the one "
                        "before; at the fixed eps of -penalty_eps it does not fall as the mesh is refined, so the cycles stop at cycle %" PetscInt_FMT
                        ": give a smaller -penalty_eps, or -penalty_eps0 (eps = eps0 h / E follows the mesh), or -contact_method vi\n",
                        (double)ad->accuracy, AccuracyQuantities[fixed_eps], (double)(100.0 * part / PetscAbsReal(c->value[fixed_eps])), k));
      }
      PetscCall(DMLabelDestroy(&marked));
      break;
    }
    if (remesh)
      PetscCall(GridSequenceRemesh(dm, user, snes, u, marked, 1.0));
    else
      PetscCall(GridSequenceRefine(dm, user, snes, u, marked));
    PetscCall(PetscTime(&t1));
    time_mesh = t1 - t0; /* the next cycle's mesh and its problem's set-up */
    PetscCall(DMLabelDestroy(&marked));
    /* the next mesh's estimate as an adapted mesh's falls, like N^(-1/dim) */
    if (ad->newton_fraction > 0.0) {
      PetscInt n_next;

      PetscCall(VecGetSize(*u, &n_next));
      PetscCall(SolverSetStepEnergyStop(SolverProblem(user->solver),
                                        ad->newton_fraction * c->estimate * PetscPowReal((PetscReal)c->n_dofs / n_next, 1.0 / dim)));
    }
    PetscCall(SolverStartFromCoarser(user->contact, &start));
    PetscCall(SolverSolve(*snes, user->solver, *u, start));
  }
  PetscCall(EstimateReset(&user->estimate)); /* the run's own, after the last solve, as without cycles */
  PetscCall(ErrorNormsReset(&user->errors));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The cycles in the summary, one line each (with the true error where the scene knows the exact
   solution), and -accuracy's outcome: the last cycle's quantities with their bars. */
static PetscErrorCode AdaptView(Driver d, MPI_Comm comm, const DriverReport *r)
{
  const Adapt        *rec   = (const Adapt *)d->data;
  const AdaptOptions *ad    = &r->opt->adapt;
  const PetscBool     exact = (PetscBool)(r->scene->exact != NULL);

  PetscFunctionBeginUser;
  if (!rec->ncycles) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscPrintf(comm, "  adaptive cycles (-adapt_fraction %g): cycle  dofs        cells       estimate    %s  marked  Newton  Krylov\n",
                        (double)rec->fraction, exact ? "error      " : ""));
  for (PetscInt k = 0; k < rec->ncycles; ++k) {
    const CycleRecord *c       = &rec->cycles[k];
    char               err[32] = "";

    if (exact) PetscCall(PetscSNPrintf(err, sizeof(err), "%.4e  ", (double)c->error_energy));
    PetscCall(PetscPrintf(comm,
                          "                                           %5" PetscInt_FMT "  %-10" PetscInt_FMT "  %-10" PetscInt_FMT
                          "  %.4e  %s%6" PetscInt_FMT "  %6" PetscInt_FMT "  %6" PetscInt_FMT "\n",
                          k, c->n_dofs, c->n_cells, (double)c->estimate, err, c->marked, c->newton_its, c->ksp_its));
  }
  if (rec->stop == ADAPT_STOP_MAX_DOFS && !(ad->accuracy > 0.0))
    PetscCall(PetscPrintf(comm, "  the cycles stopped at -adapt_max_dofs %" PetscInt_FMT ": the last mesh has %" PetscInt_FMT " dofs\n", ad->max_dofs,
                          rec->cycles[rec->ncycles - 1].n_dofs));
  if (ad->accuracy > 0.0 && rec->cycles[rec->ncycles - 1].norm == 0.0 && rec->cycles[rec->ncycles - 1].estimate == 0.0) {
    /* u = 0 exactly (no load, no contact): every quantity and its error are zero, and no bar is relative to anything */
    PetscCall(PetscPrintf(comm,
                          "  WARNING: -accuracy %g: the solution is zero (no load acts and the obstacle does not press on the body: u = 0 exactly, "
                          "with no error to refine); check the loads and the obstacle's position\n",
                          (double)ad->accuracy));
  } else if (ad->accuracy > 0.0) {
    const CycleRecord *c = &rec->cycles[rec->ncycles - 1];

    if (c->accurate)
      PetscCall(PetscPrintf(comm, "  accuracy %g reached at cycle %" PetscInt_FMT " (%" PetscInt_FMT " dofs):\n", (double)ad->accuracy,
                            rec->ncycles - 1, c->n_dofs));
    else
      PetscCall(PetscPrintf(
          comm, "  WARNING: accuracy %g not reached after %" PetscInt_FMT " cycles (%" PetscInt_FMT " dofs)%s%s%s; the last cycle's bars:\n",
          (double)ad->accuracy, rec->ncycles - 1, c->n_dofs, UnseenHolds(ad, c) ? ": the mesh does not see the contact at some nodes" : "",
          !c->converged ? ": the last solve failed" : "",
          rec->stop == ADAPT_STOP_MAX_DOFS       ? ": the mesh reached -adapt_max_dofs"
          : rec->stop == ADAPT_STOP_MAX_MEMORY   ? ": the next cycle would exceed -adapt_max_memory"
          : rec->stop == ADAPT_STOP_FIXED_EPS    ? ": the fixed eps's penalty part of a bar is above the tolerance (-penalty_eps)"
          : rec->stop == ADAPT_STOP_OUT_OF_REACH ? ": a bar falls too slowly to reach it within -adapt_max_memory"
                                                 : ""));
    for (PetscInt k = 0; k < ACCURACY_NUM; ++k) {
      if (!rec->target[k]) continue;
      if (PetscIsNanReal(c->bar[k]))
        PetscCall(PetscPrintf(comm, "    %-14s %.6g, no bar yet (no earlier cycle twice as coarse: N^(-1/dim) twice the last one's)\n",
                              AccuracyQuantities[k], (double)c->value[k]));
      else
        PetscCall(PetscPrintf(comm, "    %-14s %.6g +- %.2g (%.2g%%)%s\n", AccuracyQuantities[k], (double)c->value[k], (double)c->bar[k],
                              (double)(100.0 * c->bar[k] / PetscAbsReal(c->value[k])),
                              k == ACCURACY_ENERGY ? " (the energy norm and the error estimate)" : ""));
    }
    if (OnlyEnergyHolds(ad, rec->target, c)) {
      char names[256];

      PetscCall(ContactTargetNames(rec->target, names, sizeof(names)));
      PetscCall(PetscPrintf(comm,
                            "  only the energy's bar is above the tolerance: the energy norm's error lies over the whole body, and on a body much "
                            "larger than its contact zone it falls slowly; -accuracy_quantity %s asks for the contact quantities alone\n",
                            names));
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The cycles' part of /run (the fraction they marked, why they stopped, -adapt_max_dofs; with -accuracy, the tolerance,
   whether it was reached and the last cycle's values and bars of the quantities asked for), and the table /cycles:
   one row per mesh of the adaptive refinement. */
static PetscErrorCode AdaptWrite(Driver d, MPI_Comm comm, const DriverReport *r, PetscViewer v)
{
  const Adapt        *rec = (const Adapt *)d->data;
  const AdaptOptions *ad  = &r->opt->adapt;
  const PetscInt      dim = r->dim;
  const PetscInt      n   = rec->ncycles;
  const CycleRecord  *c   = rec->cycles;
  PetscReal          *col;

  PetscFunctionBeginUser;
  if (!n) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(RunAttrReal(v, rec->fraction, "adapt_fraction"));
  PetscCall(RunAttrString(v, AdaptStops[rec->stop], "adapt_stop"));
  if (ad->max_dofs) PetscCall(RunAttrInt(v, ad->max_dofs, "adapt_max_dofs"));
  if (ad->accuracy > 0.0) {
    PetscCall(RunAttrReal(v, ad->accuracy, "accuracy"));
    PetscCall(RunAttrInt(v, c[n - 1].accurate, "accuracy_reached"));
    for (PetscInt k = 0; k < ACCURACY_NUM; ++k) {
      if (!rec->target[k]) continue;
      PetscCall(RunAttrReal(v, c[n - 1].value[k], "accuracy_%s_value", AccuracyQuantities[k]));
      PetscCall(RunAttrReal(v, c[n - 1].bar[k], "accuracy_%s_bar", AccuracyQuantities[k]));
    }
  }
  PetscCall(PetscMalloc1(n, &col));
  PetscCall(PetscViewerHDF5PushGroup(v, "/cycles"));
#define CYCLE_COLUMN(label, expr) RUN_TABLE_COLUMN(comm, v, label, n, col, expr)
  CYCLE_COLUMN("n_dofs", (PetscReal)c[i].n_dofs);
  CYCLE_COLUMN("n_cells", (PetscReal)c[i].n_cells);
  CYCLE_COLUMN("estimate", c[i].estimate);
  CYCLE_COLUMN("estimate_penalty", c[i].estimate_penalty);
  CYCLE_COLUMN("norm", c[i].norm);
  for (PetscInt d = 0; d < dim; ++d) {
    char label[32];

    PetscCall(PetscSNPrintf(label, sizeof(label), "contact_force_%c", "xyz"[d]));
    CYCLE_COLUMN(label, c[i].q.force[d]);
  }
  CYCLE_COLUMN("pressure_max", c[i].q.pressure_max);
  CYCLE_COLUMN("contact_size", c[i].q.contact_size);
  CYCLE_COLUMN("contact_size_band", c[i].q.contact_size_band);
  CYCLE_COLUMN("pressure_max_step", c[i].q.pressure_max_step);
  CYCLE_COLUMN("pressure_peak", c[i].q.pressure_peak);
  CYCLE_COLUMN("pressure_peak_resolution", c[i].q.pressure_peak_resolution);
  for (PetscInt k = 0; k < ACCURACY_NUM; ++k) {
    char label[64];

    PetscCall(PetscSNPrintf(label, sizeof(label), "%s_value", AccuracyQuantities[k]));
    CYCLE_COLUMN(label, c[i].value[k]);
    PetscCall(PetscSNPrintf(label, sizeof(label), "%s_bar", AccuracyQuantities[k]));
    CYCLE_COLUMN(label, c[i].bar[k]);
    if (k == ACCURACY_ENERGY) continue;
    PetscCall(PetscSNPrintf(label, sizeof(label), "%s_value_eps", AccuracyQuantities[k]));
    CYCLE_COLUMN(label, c[i].value_eps[k]);
  }
  CYCLE_COLUMN("eps", c[i].eps);
  CYCLE_COLUMN("unseen_contact", (PetscReal)c[i].unseen);
  CYCLE_COLUMN("unseen_force", c[i].unseen_force);
  CYCLE_COLUMN("accurate", c[i].accurate ? 1.0 : 0.0);
  CYCLE_COLUMN("error_energy", c[i].error_energy);
  CYCLE_COLUMN("marked", (PetscReal)c[i].marked);
  CYCLE_COLUMN("marked_edge", (PetscReal)c[i].marked_edge);
  CYCLE_COLUMN("newton_its", (PetscReal)c[i].newton_its);
  CYCLE_COLUMN("ksp_its", (PetscReal)c[i].ksp_its);
  CYCLE_COLUMN("time_solve", c[i].time_solve);
  CYCLE_COLUMN("time_mesh", c[i].time_mesh);
  CYCLE_COLUMN("time_cycle", c[i].time_cycle);
  CYCLE_COLUMN("memory_mb", c[i].memory_mb);
  CYCLE_COLUMN("converged", c[i].converged ? 1.0 : 0.0);
#undef CYCLE_COLUMN
  PetscCall(PetscViewerHDF5PopGroup(v));
  PetscCall(PetscFree(col));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode AdaptDestroy(Driver d)
{
  Adapt *a = (Adapt *)d->data;

  PetscFunctionBeginUser;
  PetscCall(PetscFree(a->cycles));
  PetscCall(PetscFree(d->data));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The adaptive cycles' driver. */
PetscErrorCode DriverCreate_Adapt(Driver d)
{
  Adapt *a;

  PetscFunctionBeginUser;
  PetscCall(PetscNew(&a));
  d->data        = a;
  d->ops.solve   = AdaptSolve;
  d->ops.view    = AdaptView;
  d->ops.write   = AdaptWrite;
  d->ops.destroy = AdaptDestroy;
  PetscFunctionReturn(PETSC_SUCCESS);
}
