/* Nested iteration (-contact_grid_sequence N): the problem is solved on the mesh of the options, then on N uniform
   refinements of it, each level from the interpolation of the solution of the level below (exact for nested P1/Q1).
   From a zero guess, semismooth Newton needs more steps as h falls (the active set moves about a cell per step);
   from the coarse solution it needs only a few on each level. A failed level ends the sequence: the output is that
   level's, flagged as not converged. */
#include "mesh.h"
#include "solver.h"

/* Replaces the problem on *dm by the problem on its uniform refinement, with *u interpolated as the initial guess. */
static PetscErrorCode GridSequenceRefine(DM *dm, AppCtx *user, SNES *snes, Vec *u)
{
  DM        fine;
  PetscInt *parent, *vertex_source = NULL;
  Vec       loc, fine_loc;

  PetscFunctionBeginUser;
  PetscCall(DMCreateLocalVector(*dm, &loc));
  PetscCall(VecCopy(user->prob.loc_bc, loc)); /* the Dirichlet values, inserted by ProblemSetUp() */
  PetscCall(DMGlobalToLocal(*dm, *u, INSERT_VALUES, loc));
  PetscCall(VecDestroy(u));
  PetscCall(ProblemDestroy(user, snes));
  if (user->opt.box.is_box && user->opt.degree == 1) { /* the box of twice as many cells, built directly */
    parent = NULL;
    PetscCall(MeshCreateBoxLevel(*dm, &user->opt.box, user->prob.level, &fine, &vertex_source));
  } else
    PetscCall(MeshRefineRegular(*dm, 1, &fine, &parent, &vertex_source));
  user->prob.level++;
  PetscCall(ProblemSetUp(fine, user, snes));
  if (user->opt.degree == 1)
    PetscCall(MeshInterpolateVertexSources(*dm, fine, vertex_source, loc, &fine_loc)); /* exact and fast */
  else
    PetscCall(MeshInterpolateFromParents(*dm, fine, parent, 1, &loc, &fine_loc));
  PetscCall(PetscFree(parent));
  PetscCall(PetscFree(vertex_source));
  PetscCall(VecDestroy(&loc));
  PetscCall(DMDestroy(dm));
  *dm = fine;
  PetscCall(DMCreateGlobalVector(fine, u));
  PetscCall(PetscObjectSetName((PetscObject)*u, "displacement"));
  PetscCall(DMLocalToGlobal(fine, fine_loc, INSERT_VALUES, *u));
  PetscCall(VecDestroy(&fine_loc));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode GridSequenceSolve(DM *dm, AppCtx *user, SNES *snes, Vec *u)
{
  PetscFunctionBeginUser;
  PetscCall(SolverSolve(*snes, user, *u, PETSC_FALSE));
  for (PetscInt l = 1; l <= user->opt.contact.grid_sequence && user->rec.stats.converged; ++l) {
    PetscLogDouble t0, t1;

    PetscCall(PetscTime(&t0));
    PetscCall(GridSequenceRefine(dm, user, snes, u));
    PetscCall(PetscTime(&t1));
    user->prob.setup_time = t1 - t0; /* refinement, set-up and interpolation */
    user->rec.stats.time_setup += t1 - t0;
    PetscCall(SolverSolve(*snes, user, *u, PETSC_TRUE));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}
