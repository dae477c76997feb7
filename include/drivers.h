/* The drivers (src/drivers/): the outer strategies of a run around the Newton core's solves (include/solver.h). Each is
 * an object of a type registered by name (drivers.c), with one interface: it solves on from the run's last solution,
 * keeps its own results, and shows them in the summary (view) and the output (write). The run composes them in one
 * place, DriversCreate()'s flow: the first solve with its nested iteration (grid_sequence), the adaptive cycles on its
 * mesh (adapt), then on the final mesh the eps sweep (eps_sweep), the continuation to a penetration tolerance
 * (penetration_tol) and the load path (load_path). Each driver does nothing unless its options ask for it. */
#pragma once
#include "signorini.h"
#include "solver.h"

/* What a driver's summary and output read of the run besides its own results. */
typedef struct {
  const RunOptions         *opt;
  const Scene              *scene;
  Contact                   contact;
  const RunStats           *stats;
  const SolutionQuantities *quantities;
  PetscInt                  dim;
} DriverReport;

/* drivers.c: the registry and the run's flow */
/* Drivers (include/signorini.h): the run's drivers, in the order of its flow */
PetscErrorCode DriverRegisterAll(void);
PetscErrorCode DriverFinalize(void);
PetscErrorCode DriversCreate(OutputWriter checkpoint, Drivers *list);
PetscErrorCode DriversSolve(Drivers list, AppCtx *user, DM *dm, SNES *snes, Vec *u);
PetscErrorCode DriversView(Drivers list, MPI_Comm comm, const DriverReport *r);
PetscErrorCode DriversWrite(Drivers list, MPI_Comm comm, const DriverReport *r, PetscViewer v);
PetscErrorCode DriversGetStepFields(Drivers list, PetscInt *nsteps, Vec const **fields);
PetscErrorCode DriversDestroy(Drivers *list);

/* grid_sequence.c: the coarser boxes of nested iteration (-contact_grid_sequence) and their eps for -bars.
   The coarsest box of nested iteration by default (-contact_coarse_levels -1) has at least this many cells per side:
   where each box builds its own preconditioner (a factorization, or an algebraic multigrid with -contact_coarse_mg 0),
   each coarser box costs that build; with the geometric multigrid (-pc_type mg, or the coarser boxes' solver of
   -contact_coarse_mg) a coarser box costs little and is one more level of the hierarchy (a smaller coarse factorization). */
#define GRID_SEQUENCE_MIN_FACES 64
#define GRID_SEQUENCE_MIN_FACES_MG 16
/* In 3D the boxes of about as many unknowns as 2D's: 16^3 against 64^2, and 4^3, whose factorization is the
   multigrid's coarse solve, against 16^2 (docs/decisions.md, "The coarsest box"). */
#define GRID_SEQUENCE_MIN_FACES_3D 16
#define GRID_SEQUENCE_MIN_FACES_MG_3D 4
/* ... and the multigrid's coarsest box in 3D has at most 20 cells per side (27,783 unknowns) where it nests by default:
   it is factored by MUMPS at each build of the hierarchy and solved alone by GAMG (src/linear/multigrid.c; docs/decisions.md,
   "The coarsest box"). */
#define GRID_SEQUENCE_MAX_COARSEST_MG_3D 20
PetscErrorCode GridSequenceCoarseRequest(MPI_Comm comm, Contact ct, const RunOptions *opt, PetscInt request[2], PetscInt faces[3],
                                         PetscInt *min_levels, PetscBool *coarse_mg, PetscBool *default_mg);
PetscErrorCode GridSequenceBarsSizes(DM dm, const RunOptions *opt, Contact ct, const MeshBox *box, PetscInt level);

/* adapt.c: -adapt_cycles and -accuracy, the adaptive refinement driven by the error estimate */
PetscErrorCode AdaptGetOptions(MPI_Comm comm, AdaptOptions *ad);
PetscErrorCode AdaptCheck(DM dm, const RunOptions *opt, Contact ct, const MeshBox *box, const Scene *scene);

/* load_path.c: -load_steps, -load_path, and force control (-obstacle_force) */
PetscErrorCode LoadPathGetOptions(MPI_Comm comm, LoadPathOptions *lp);
PetscErrorCode LoadPathSetUp(MPI_Comm comm, const RunOptions *opt, Contact ct, Scene *scene);
