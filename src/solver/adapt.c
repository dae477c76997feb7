/* -adapt_cycles N: adaptive refinement driven by the error estimate (issue 34, its first part: 2D). After the first
   solve, each cycle estimates the error of the solution (src/estimate/), marks the fewest cells whose indicators hold
   the fraction -adapt_fraction of the estimate's square (Doerfler, src/estimate/marking.c), refines them and as many
   more as keep the mesh conforming (PETSc's skeleton-based refinement, MeshRefineMarked()), and solves again from the
   last solution interpolated (the meshes are nested: exact for P1), as nested iteration does (GridSequenceRefine()).
   The face sets and Gmsh names follow the refinement, and eps follows each contact face's size (eps = eps0 h^power /
   M with the local h), so that the penalty's error shrinks with the cells where they shrink. /cycles records each
   mesh: unknowns, cells, the estimate, the true energy-norm error where the scene knows the exact solution, the marked
   cells and the solve. */
#include "contact.h"
#include "estimate.h"
#include "mesh.h"
#include "solver.h"
#include "verify.h"

PetscErrorCode AdaptGetOptions(MPI_Comm comm, AdaptOptions *ad)
{
  PetscFunctionBeginUser;
  ad->cycles   = 0;
  ad->fraction = 0.5;
  PetscOptionsBegin(comm, NULL, "Adaptive refinement", "Signorini");
  PetscCall(PetscOptionsInt("-adapt_cycles", "Refine where the error estimate is largest and solve again, this many times (2D triangles, P1)", NULL,
                            ad->cycles, &ad->cycles, NULL));
  PetscCall(PetscOptionsReal("-adapt_fraction", "The fraction of the estimate's square that the cells refined at each cycle hold (Doerfler's theta)",
                             NULL, ad->fraction, &ad->fraction, NULL));
  PetscOptionsEnd();
  PetscCheck(ad->cycles >= 0, comm, PETSC_ERR_USER_INPUT, "-adapt_cycles must be >= 0, got %" PetscInt_FMT, ad->cycles);
  PetscCheck(ad->fraction > 0.0 && ad->fraction <= 1.0, comm, PETSC_ERR_USER_INPUT, "-adapt_fraction must lie in (0, 1], got %g",
             (double)ad->fraction);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* What the adaptive cycles cannot do yet, refused before the solve. */
PetscErrorCode AdaptCheck(DM dm, const AppCtx *user)
{
  MPI_Comm              comm = PetscObjectComm((PetscObject)dm);
  const RunOptions     *opt  = user->opt;
  const ContactOptions *copt;
  PetscInt              dim;
  PetscBool             simplex, is_mg;

  PetscFunctionBeginUser;
  if (!opt->adapt.cycles) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMPlexIsSimplex(dm, &simplex));
  PetscCall(ContactGetOptions(user->contact, &copt));
  PetscCall(PetscStrcmp(opt->solver.given.pc_type, PCMG, &is_mg));
  PetscCheck(dim == 2 && simplex, comm, PETSC_ERR_USER_INPUT,
             "-adapt_cycles refines triangles only (2D): PETSc 3.18 as Debian builds it has no conforming local refinement of %s",
             dim == 3 ? "tetrahedra" : "quadrilaterals");
  PetscCheck(opt->degree == 1, comm, PETSC_ERR_USER_INPUT, "-adapt_cycles needs P1 displacements, got -displacement_petscspace_degree %" PetscInt_FMT,
             opt->degree);
  PetscCheck(opt->estimate, comm, PETSC_ERR_USER_INPUT,
             "-adapt_cycles refines where the error estimate is largest: it cannot run with -estimate false");
  PetscCheck(!opt->bars, comm, PETSC_ERR_USER_INPUT, "-adapt_cycles with -bars is not supported yet: the bars need three uniformly nested meshes");
  PetscCheck(copt->n_sweep <= 1, comm, PETSC_ERR_USER_INPUT, "-adapt_cycles with -penalty_eps0_sweep is not supported yet");
  PetscCheck(copt->penetration_tol <= 0.0, comm, PETSC_ERR_USER_INPUT, "-adapt_cycles with -contact_penetration_tol is not supported yet");
  PetscCheck(!opt->load_path.n, comm, PETSC_ERR_USER_INPUT, "-adapt_cycles with a load path (-load_steps, -load_path) is not supported yet");
  PetscCheck(!opt->verify.reference[0], comm, PETSC_ERR_USER_INPUT,
             "-adapt_cycles with -reference is not supported: the reference is on another mesh");
  PetscCheck(!is_mg, comm, PETSC_ERR_USER_INPUT,
             "-adapt_cycles with -pc_type mg is not supported yet: use GAMG (options/solvers/gamg.yaml) or MUMPS");
  PetscCheck(!user->box.from_file || user->box.curved_ridges < MESH_CURVED_RIDGES_MIN, comm, PETSC_ERR_USER_INPUT,
             "-adapt_cycles: the mesh file's boundary turns by less than 20 degrees at %" PetscInt_FMT
             " of its vertices (one at %g, %g), a curved boundary's chords: the refinement would split them on the chords, and the "
             "answer would be the file's polygon's, not the curved body's (the Hertz cylinder meshed at h = 0.05: its contact width 27%% short "
             "after 10 cycles); refinement that follows the Gmsh model is not there yet (issue 34): mesh finer with Gmsh, or refine a "
             "polygonal body",
             user->box.curved_ridges, (double)user->box.curved_x[0], (double)user->box.curved_x[1]);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The cycle's row of /cycles: the mesh and its solve (the last record), the estimate of its solution and, where the
   scene knows it, the true error. */
static PetscErrorCode AdaptRecord(DM dm, AppCtx *user, Vec u, PetscInt k)
{
  CycleRecord       *c = &user->rec.cycles[k];
  const SolveRecord *r = &user->rec.records[user->rec.nrecords - 1];
  PetscInt           cStart, cEnd, local;

  PetscFunctionBeginUser;
  PetscCall(EstimateReset(&user->rec.estimate));
  PetscCall(EstimateCompute(dm, user, u));
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  local = cEnd - cStart;
  PetscCall(MPIU_Allreduce(&local, &c->n_cells, 1, MPIU_INT, MPIU_SUM, PetscObjectComm((PetscObject)dm)));
  c->n_dofs       = r->n_dofs;
  c->newton_its   = r->newton_its;
  c->ksp_its      = r->ksp_its;
  c->time_solve   = r->time_solve;
  c->converged    = r->converged;
  c->estimate     = user->rec.estimate.total;
  c->marked       = 0;
  c->error_energy = PETSC_NAN;
  if (user->scene.exact) {
    PetscCall(ErrorNormsCompute(dm, user, u));
    c->error_energy = user->rec.errors.energy;
  }
  user->rec.ncycles = k + 1;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode AdaptSolve(DM *dm, AppCtx *user, SNES *snes, Vec *u)
{
  const AdaptOptions *ad = &user->opt->adapt;

  PetscFunctionBeginUser;
  if (!ad->cycles) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscCalloc1(ad->cycles + 1, &user->rec.cycles));
  for (PetscInt k = 0;; ++k) {
    DMLabel marked;

    PetscCall(AdaptRecord(*dm, user, *u, k));
    if (k == ad->cycles || !user->rec.stats.converged) break;
    PetscCall(EstimateMark(*dm, &user->rec.estimate, ad->fraction, &marked, &user->rec.cycles[k].marked));
    PetscCall(GridSequenceRefine(dm, user, snes, u, marked));
    PetscCall(DMLabelDestroy(&marked));
    PetscCall(SolverSolve(*snes, user, *u, SOLVER_START_COARSER_MESH));
  }
  PetscCall(EstimateReset(&user->rec.estimate)); /* the run's own, after the last solve, as without cycles */
  PetscCall(ErrorNormsReset(&user->rec.errors));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The cycles in the summary, one line each. */
PetscErrorCode AdaptView(MPI_Comm comm, const AppCtx *user)
{
  PetscFunctionBeginUser;
  if (!user->rec.ncycles) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscPrintf(comm, "  adaptive cycles (-adapt_fraction %g): cycle  dofs        cells       estimate    %s  marked  Newton  Krylov\n",
                        (double)user->opt->adapt.fraction, user->scene.exact ? "error      " : ""));
  for (PetscInt k = 0; k < user->rec.ncycles; ++k) {
    const CycleRecord *c       = &user->rec.cycles[k];
    char               err[32] = "";

    if (user->scene.exact) PetscCall(PetscSNPrintf(err, sizeof(err), "%.4e  ", (double)c->error_energy));
    PetscCall(PetscPrintf(comm,
                          "                                           %5" PetscInt_FMT "  %-10" PetscInt_FMT "  %-10" PetscInt_FMT
                          "  %.4e  %s%6" PetscInt_FMT "  %6" PetscInt_FMT "  %6" PetscInt_FMT "\n",
                          k, c->n_dofs, c->n_cells, (double)c->estimate, err, c->marked, c->newton_its, c->ksp_its));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}
