/* The solver's record in the summary (SolverView()) and in the output (SolverWrite(): its part of /run and the table
   /solves). */
#include <petscviewerhdf5.h>
#include "app.h"
#include "discretization.h"
#include "solver_impl.h"

/* The solve's lines of the summary: the default linear solver where it is the boxes' multigrid, the last solve's
   outcome (PETSc's reason, the iterations, the preconditioner's builds and updates, the residual), the breakdowns it
   recovered from, the eps continuation, the condition estimate, and the table of solves where there are several. */
PetscErrorCode SolverView(Solver solver, MPI_Comm comm)
{
  const RunStats *s = &solver->stats;

  PetscFunctionBeginUser;
  if (s->default_mg)
    PetscCall(PetscPrintf(comm,
                          "  linear solver: CG with the geometric multigrid of the %" PetscInt_FMT
                          " nested boxes (the default on a 3D box that nests; "
                          "-pc_type lu for MUMPS)\n",
                          solver->box->coarse_levels + solver->opt->solver.grid_sequence + 1));
  PetscCall(PetscPrintf(comm,
                        "  SNES %s: %" PetscInt_FMT " Newton steps, %" PetscInt_FMT " linear iterations, %" PetscInt_FMT " preconditioner builds",
                        SNESConvergedReasons[s->reason], s->newton_its, s->ksp_its, s->pc_builds));
  if (s->pc_updates) PetscCall(PetscPrintf(comm, " and %" PetscInt_FMT " coarse-level updates", s->pc_updates));
  if (s->pc_finest_updates) PetscCall(PetscPrintf(comm, " (and %" PetscInt_FMT " of the finest level only)", s->pc_finest_updates));
  PetscCall(PetscPrintf(comm, ", |F| = %g%s\n", (double)s->residual_norm,
                        s->roundoff_stop ? " (stopped at round-off: -snes_rtol asks for less than double precision can reach)" : ""));
  if (s->pc_breakdowns) PetscCall(PetscPrintf(comm, "  preconditioner breakdowns: %" PetscInt_FMT " (%s)\n", s->pc_breakdowns, s->pc_recovery));
  if (s->continuation_stages)
    PetscCall(PetscPrintf(comm, "  eps continuation: %" PetscInt_FMT " solve(s) from eps = h/M before the target eps (counted in the Newton steps)\n",
                          s->continuation_stages));
  if (!PetscIsNanReal(s->condition_1norm))
    PetscCall(PetscPrintf(comm, "  condition number estimate (1-norm) of the Jacobian: %.3e\n", (double)s->condition_1norm));
  if (solver->nrecords > 1) {
    PetscCall(PetscPrintf(comm, "  solves: level   dofs        h           eps         Newton  Krylov  PC builds  setup s   solve s\n"));
    for (PetscInt i = 0; i < solver->nrecords; ++i) {
      const SolveRecord *r = &solver->records[i];

      PetscCall(PetscPrintf(comm,
                            "          %5" PetscInt_FMT "  %9" PetscInt_FMT "  %.4e  %.4e  %6" PetscInt_FMT "  %6" PetscInt_FMT "  %9" PetscInt_FMT
                            "  %8.3f  %8.3f%s\n",
                            r->level, r->n_dofs, (double)r->h, (double)r->eps, r->newton_its, r->ksp_its, r->pc_builds, (double)r->time_setup,
                            (double)r->time_solve, r->converged ? "" : "  FAILED"));
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* /solves/<column>: one row per solve of the run (grid sequence levels, eps sweep values), as datasets of length n. */
static PetscErrorCode WriteSolves(MPI_Comm comm, const SolveRecord records[], PetscInt n, PetscViewer v)
{
  const char    *columns[] = {"level",     "n_dofs",    "h",          "eps",        "newton_its",     "ksp_its",
                              "pc_builds", "converged", "time_setup", "time_solve", "max_penetration"};
  const PetscInt ncol      = (PetscInt)(sizeof(columns) / sizeof(columns[0]));
  PetscReal     *col;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc1(n + 1, &col));
  PetscCall(PetscViewerHDF5PushGroup(v, "/solves"));
  for (PetscInt j = 0; j < ncol; ++j) {
    for (PetscInt i = 0; i < n; ++i) {
      const SolveRecord *r      = &records[i];
      const PetscReal    vals[] = {
             (PetscReal)r->level,     (PetscReal)r->n_dofs,     r->h,          r->eps,        (PetscReal)r->newton_its, (PetscReal)r->ksp_its,
             (PetscReal)r->pc_builds, r->converged ? 1.0 : 0.0, r->time_setup, r->time_solve, r->max_penetration};
      col[i] = vals[j];
    }
    PetscCall(RunColumn(comm, v, columns[j], n, col));
  }
  PetscCall(PetscViewerHDF5PopGroup(v));
  PetscCall(PetscFree(col));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The solve's part of /run: the last solve's outcome (PETSc's reason and its code, converged, the residual and how it
   stopped), its iterations and the run's totals, the nested boxes, the linear solver's statistics (the builds and
   updates of the preconditioner, its breakdowns, Eisenstat-Walker, the condition estimate), the problem's assembly,
   size h, load and scale, and the set-up and solve times; and the table /solves. */
PetscErrorCode SolverWrite(Solver solver, MPI_Comm comm, PetscViewer v)
{
  const RunStats      *s             = &solver->stats;
  const Problem       *prob          = &solver->prob;
  const SolverOptions *sopt          = &solver->opt->solver;
  const PetscInt       coarse_levels = solver->box->coarse_levels;
  const PetscInt       nsolves       = solver->nrecords;

  PetscFunctionBeginUser;
  PetscCall(RunAttrString(v, AssemblyTypes[prob->assembly], "assembly"));
  PetscCall(RunAttrString(v, SNESConvergedReasons[s->reason], "snes_reason"));
  PetscCall(RunAttrReal(v, prob->h, "h"));
  PetscCall(RunAttrInt(v, s->converged ? 1 : 0, "converged"));
  PetscCall(RunAttrInt(v, (PetscInt)s->reason, "snes_reason_code"));
  PetscCall(RunAttrInt(v, s->newton_its, "newton_its"));
  PetscCall(RunAttrInt(v, s->ksp_its, "ksp_its"));
  PetscCall(RunAttrInt(v, s->newton_its_total, "newton_its_total"));
  PetscCall(RunAttrInt(v, s->ksp_its_total, "ksp_its_total"));
  PetscCall(RunAttrInt(v, sopt->grid_sequence, "grid_sequence"));
  PetscCall(RunAttrInt(v, coarse_levels, "coarse_levels"));
  PetscCall(RunAttrInt(v, s->coarse_mg && coarse_levels > 0 ? 1 : 0, "coarse_mg")); /* -contact_coarse_mg applied */
  PetscCall(RunAttrInt(v, s->default_mg ? 1 : 0, "default_mg"));                    /* the 3D box's default: the boxes' geometric multigrid */
  PetscCall(RunAttrInt(v, nsolves, "n_solves"));
  PetscCall(RunAttrReal(v, s->residual_norm, "residual_norm"));
  PetscCall(RunAttrInt(v, s->residual_reduced ? 1 : 0, "residual_reduced"));
  PetscCall(RunAttrInt(v, s->roundoff_stop ? 1 : 0, "stopped_at_roundoff")); /* Newton stalled at the round-off of its terms */
  PetscCall(RunAttrInt(v, s->pc_breakdowns, "pc_breakdowns"));               /* preconditioner breakdowns recovered from (pc_recovery.c) */
  if (s->pc_recovery[0]) PetscCall(RunAttrString(v, s->pc_recovery, "pc_recovery"));
  PetscCall(RunAttrReal(v, prob->load_norm, "load_norm"));
  PetscCall(RunAttrReal(v, prob->displacement_scale, "displacement_scale"));
  PetscCall(RunAttrReal(v, s->time_setup, "time_setup"));
  PetscCall(RunAttrReal(v, s->time_solve, "time_solve"));
  PetscCall(RunAttrInt(v, s->continuation_stages, "continuation_stages"));
  PetscCall(RunAttrInt(v, s->active_set_cycles, "active_set_cycles"));
  PetscCall(RunAttrInt(v, s->pc_builds, "pc_builds"));
  PetscCall(RunAttrInt(v, s->pc_updates, "pc_updates"));               /* -contact_pc_update: coarse-operator updates of a GAMG hierarchy */
  PetscCall(RunAttrInt(v, s->pc_finest_updates, "pc_finest_updates")); /* -contact_pc_update_changes: updates of its finest level only */
  PetscCall(RunAttrInt(v, s->ksp_ew, "ksp_ew"));                       /* 1: the linear tolerances of Eisenstat-Walker */
  if (sopt->condition_estimate) PetscCall(RunAttrReal(v, s->condition_1norm, "condition_1norm")); /* NaN: the estimate failed */
  PetscCall(WriteSolves(comm, solver->records, solver->nrecords, v));
  PetscFunctionReturn(PETSC_SUCCESS);
}
