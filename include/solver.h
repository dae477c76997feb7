/* Solver: the nonlinear core (src/solver/): assembly of the bulk operator, the SNES (residual, Jacobian, scaling,
 * convergence), the problem on one mesh, the Newton monitor. The drivers around its solves are the layer above
 * (include/drivers.h). Its linear acceleration (preconditioner reuse and recovery, forcing terms, step
 * guess, the nested meshes' multigrid, the solver's options) is the layer below, include/linear.h. */
#pragma once
#include "signorini.h"
#include "linear.h"

/* solver.c */
/* The solver object (Solver, include/signorini.h): the problem on the current mesh, which it owns, what the solves of
   the run read (the Contact, the options, the nested meshes' multigrid and the box), and their outcome, which it owns:
   the run's statistics and the table of solves. Created once, after the options, the Contact, the multigrid and the
   mesh. */
PetscErrorCode SolverCreate(const RunOptions *opt, Contact contact, Multigrid mg, const MeshBox *box, Solver *s);
PetscErrorCode SolverDestroy(Solver *s);
Problem       *SolverProblem(Solver s);
RunStats      *SolverStats(Solver s);
PetscErrorCode SolverGetSolves(Solver s, const SolveRecord **records, PetscInt *n);
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
/* extrapolated_start.c: a solve's start extrapolated from earlier solutions, along dir (the tangent) or the secant
   u - prev, where the guess keeps the active set and lowers the residual */
PetscErrorCode SolverExtrapolatedStart(SNES snes, DM dm, Solver s, Vec u, Vec dir, PetscReal factor, PetscReal relaxed, PetscBool step_guess);
PetscErrorCode SolverSecantStart(SNES snes, DM dm, Solver s, Vec u, Vec prev, Vec dir, PetscBool use, PetscReal factor, PetscReal relaxed);
PetscErrorCode SolverConditionEstimate(SNES snes, Solver s, Vec u);
/* solver_output.c: the solver's record in the summary, and its part of /run with the table /solves */
PetscErrorCode SolverView(Solver s, MPI_Comm comm);
PetscErrorCode SolverWrite(Solver s, MPI_Comm comm, PetscViewer v);

/* problem.c: the problem on one mesh (its section, K, r0, the SNES), which the Solver owns */
PetscErrorCode ProblemSetUp(DM dm, Solver s, const Scene *scene, SNES *snes);
PetscErrorCode ProblemDestroy(Solver s, SNES *snes);

/* bandwidth.c */
PetscErrorCode BandwidthGetOptions(MPI_Comm comm, PetscBool *measure);
PetscErrorCode BandwidthMeasure(SNES snes, PetscBool measure, Bandwidth *b);
PetscErrorCode BandwidthView(MPI_Comm comm, const Bandwidth *b);
PetscErrorCode BandwidthWrite(const Bandwidth *b, PetscViewer v);
