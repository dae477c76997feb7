/* Solver: assembly of the bulk operator, the SNES (residual, Jacobian, scaling, convergence), the problem on one mesh, grid sequencing, eps sweep,
 * the Newton monitor (src/solver/). Its linear acceleration (preconditioner reuse and recovery, forcing terms, step
 * guess, the nested meshes' multigrid, the solver's options) is the layer below, include/linear.h. */
#pragma once
#include "signorini.h"
#include "linear.h"

/* solver.c */
/* The solver object (Solver, include/signorini.h): what the solves of the run read, the problem on the current mesh, the
   Contact, the options, the nested meshes' multigrid and the box, and where their outcome goes, the run's statistics and
   the table of solves. Created once, after the options, the Contact, the multigrid and the mesh; it owns none of them. */
PetscErrorCode SolverCreate(const RunOptions *opt, Contact contact, Multigrid mg, const MeshBox *box, Problem *prob, RunRecord *rec, Solver *s);
PetscErrorCode SolverDestroy(Solver *s);
/* the bound of Eisenstat-Walker's linear tolerances, the penalty method's default with an iterative preconditioner */
#define SOLVER_EW_RTOL_MAX 0.01
PetscErrorCode SolverAssembleBulk(DM dm, const RunOptions *opt, Problem *prob);
PetscErrorCode SolverAssembleLoad(DM dm, const RunOptions *opt, const Scene *scene, Problem *prob);
PetscErrorCode SolverCreateSNES(DM dm, Contact contact, const SolverOptions *opt, Problem *prob, Multigrid mg, const MeshBox *box, SNES *snes);
PetscErrorCode SolverComputeScales(DM dm, Contact contact, Problem *prob);
/* Where a solve starts: from zero, from the solution for a nearby eps (the sweep), or from a coarser mesh's (nested
   iteration); the last two are warm starts, and the first and last reach a small eps by continuation. */
typedef enum { SOLVER_START_ZERO, SOLVER_START_NEARBY_EPS, SOLVER_START_COARSER_MESH } SolverStart;
PetscErrorCode SolverSolve(SNES snes, Solver s, Vec u, SolverStart start);
PetscErrorCode SolverStartFromCoarser(Contact contact, SolverStart *start);
/* A solve from the guess u (a load path's step, force control's position, the penetration tolerance's eps) that, where
   it stalls or fails, is solved again from zero as a direct run: never less reliable than the direct run */
PetscErrorCode SolverSolveWarm(SNES snes, Solver s, Vec u, const char what[]);
/* The next solves of the problem stop once a Newton step's energy norm is below energy (0: at -snes_rtol only) */
PetscErrorCode SolverSetStepEnergyStop(Problem *prob, PetscReal energy);
/* |F| (user's units) that -snes_rtol is relative to in the current solve: its first, or for a warm start the load
   ||F(0)||, so that a warm start ends as tight as a start from zero */
PetscErrorCode SolverResidualNorm(SNES snes, SolverCtx sc, Vec u, PetscReal *norm);
PetscErrorCode SolverConditionEstimate(SNES snes, Solver s, Vec u);
/* the solve's part of /run, and the table /solves */
PetscErrorCode SolverWrite(const RunStats *s, const Problem *prob, const SolverOptions *sopt, PetscInt coarse_levels, PetscInt nsolves,
                           PetscViewer v);
PetscErrorCode SolverWriteSolves(MPI_Comm comm, const SolveRecord records[], PetscInt n, PetscViewer v);

/* problem.c, grid_sequence.c, eps_sweep.c */
PetscErrorCode ProblemSetUp(DM dm, Solver s, const Scene *scene, SNES *snes);
PetscErrorCode ProblemDestroy(Solver s, SNES *snes);
/* The coarsest box of nested iteration by default (-contact_coarse_levels -1) has at least this many cells per side:
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
PetscErrorCode GridSequenceSolve(DM *dm, AppCtx *user, SNES *snes, Vec *u);
PetscErrorCode GridSequenceRefine(DM *dm, AppCtx *user, SNES *snes, Vec *u, DMLabel marked);
PetscErrorCode GridSequenceRemesh(DM *dm, AppCtx *user, SNES *snes, Vec *u, DMLabel marked, PetscReal unmarked);
PetscErrorCode GridSequenceBarsSizes(DM dm, const RunOptions *opt, Contact ct, const MeshBox *box, PetscInt level);
PetscErrorCode EpsSweepSolve(DM dm, AppCtx *user, SNES snes, Vec u);
PetscErrorCode EpsSweepTangent(SNES snes, DM dm, Contact ct, Vec u, Vec dir, PetscInt *ksp_its_total, PetscBool *ok);
/* adapt.c: -adapt_cycles, the adaptive refinement driven by the error estimate */
PetscErrorCode AdaptGetOptions(MPI_Comm comm, AdaptOptions *ad);
PetscErrorCode AdaptCheck(DM dm, const RunOptions *opt, Contact ct, const MeshBox *box, const Scene *scene);
PetscErrorCode AdaptSolve(DM *dm, AppCtx *user, SNES *snes, Vec *u, OutputWriter write);
PetscErrorCode AdaptView(MPI_Comm comm, const AdaptOptions *ad, const RunRecord *rec, PetscBool exact);
PetscErrorCode AdaptWrite(MPI_Comm comm, const AdaptOptions *ad, const RunRecord *rec, PetscInt dim, PetscViewer v); /* /run's and /cycles */
PetscErrorCode PenetrationTolSolve(DM dm, AppCtx *user, SNES snes, Vec u); /* penetration_tol.c: -contact_penetration_tol */
PetscErrorCode PenetrationTolWrite(Contact ct, const RunStats *s, PetscViewer v);

/* load_path.c: -load_steps, -load_path */
PetscErrorCode LoadPathGetOptions(MPI_Comm comm, LoadPathOptions *lp);
PetscErrorCode LoadPathSetUp(MPI_Comm comm, const RunOptions *opt, Contact ct, Scene *scene);
PetscErrorCode LoadPathSolve(DM dm, AppCtx *user, SNES snes, Vec u);
PetscErrorCode LoadPathView(MPI_Comm comm, const LoadPathOptions *lp, const Scene *scene, const RunRecord *rec);
PetscErrorCode LoadPathWrite(MPI_Comm comm, const Scene *scene, const RunStats *s, const StepRecord st[], PetscInt n, PetscInt dim,
                             PetscViewer v); /* /steps */

/* bandwidth.c */
PetscErrorCode BandwidthGetOptions(MPI_Comm comm, PetscBool *measure);
PetscErrorCode BandwidthMeasure(SNES snes, PetscBool measure, Bandwidth *b);
PetscErrorCode BandwidthWrite(const Bandwidth *b, PetscViewer v);
