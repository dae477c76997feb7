/* Nested iteration. -contact_grid_sequence N: the problem is solved on the mesh of the options, then on N uniform
   refinements of it, each level from the interpolation of the solution of the level below (exact for nested P1/Q1).
   -contact_coarse_levels K (by default where the 2D P1 box allows it): the mesh of the options is the last of K box
   doublings from a coarser box, each solved to the looser -contact_coarse_rtol; the final mesh is the direct build's.
   From a zero guess, semismooth Newton needs more steps as h falls (the active set moves about a cell per step);
   from the coarse solution it needs only a few on each level. A failed level of -contact_grid_sequence ends the
   sequence: the output is that level's, flagged as not converged. A failed coarser box of -contact_coarse_levels is
   reported and the next level starts from zero: the mesh of the options is always solved. */
#include "contact.h"
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
  if (user->box.is_box && user->opt->degree == 1) { /* the box of twice as many cells, built directly */
    parent = NULL;
    PetscCall(MeshCreateBoxLevel(*dm, &user->box, user->prob.level, &fine, &vertex_source));
  } else
    PetscCall(MeshRefineRegular(*dm, 1, &fine, &parent, &vertex_source));
  user->prob.level++;
  PetscCall(ProblemSetUp(fine, user, snes));
  PetscCall(MultigridAddLevel(*snes, *dm, fine, vertex_source, user)); /* with -pc_type mg */
  if (user->opt->degree == 1)
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

/* Newton's relative tolerance on a box below the one of the options (-contact_coarse_levels): -contact_coarse_rtol where
   looser than -snes_rtol. Its solution is only the next level's initial guess, whose own error is of the order of h. */
static PetscErrorCode GridSequenceSetTolerance(SNES snes, const AppCtx *user)
{
  PetscReal atol, rtol, stol;
  PetscInt  maxit, maxf;

  PetscFunctionBeginUser;
  if (user->prob.level >= user->box.coarse_levels) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(SNESGetTolerances(snes, &atol, &rtol, &stol, &maxit, &maxf));
  if (user->opt->solver.coarse_rtol > rtol) PetscCall(SNESSetTolerances(snes, atol, user->opt->solver.coarse_rtol, stol, maxit, maxf));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode GridSequenceCoarseRequest(MPI_Comm comm, Contact ct, const RunOptions *opt, PetscInt *request, PetscInt *min_faces,
                                         PetscBool *coarse_mg)
{
  const PetscInt  k       = opt->solver.coarse_levels;
  const char     *pc_type = opt->solver.given.pc_type;
  const PetscBool given   = opt->solver.given.pc_type_given;
  PetscBool       is_mg, is_factor;

  PetscFunctionBeginUser;
  PetscCheck(k <= 0 || opt->degree == 1, comm, PETSC_ERR_USER_INPUT,
             "-contact_coarse_levels %" PetscInt_FMT " needs P1 displacements, got -displacement_petscspace_degree %" PetscInt_FMT, k, opt->degree);
  PetscCall(PetscStrcmp(pc_type, PCMG, &is_mg));
  PetscCall(PetscStrInList(pc_type, PCLU "," PCCHOLESKY, ',', &is_factor));
  /* -contact_coarse_mg: with an iterative preconditioner that is not already the boxes' multigrid (without -pc_type, the
     default is MUMPS's factorization, which a coarser box's small matrix does not make expensive); not with SNESVI, whose
     reduced system (vinewtonrsls) no PCMG can follow and whose vinewtonssls Jacobian CG cannot take */
  *coarse_mg = (PetscBool)(opt->solver.coarse_mg && given && !is_mg && !is_factor && !ContactHasBounds(ct));
  *request   = k;
  *min_faces = (is_mg || *coarse_mg) ? GRID_SEQUENCE_MIN_FACES_MG : GRID_SEQUENCE_MIN_FACES;
  /* by default: the penalty method, and the elastic solve with the geometric multigrid (its levels) */
  if (k < 0 && (!(ContactHasPenalty(ct) || (ContactIsNone(ct) && is_mg)) || opt->degree != 1)) *request = 0;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode GridSequenceSolve(DM *dm, AppCtx *user, SNES *snes, Vec *u)
{
  const PetscInt nlevels = user->box.coarse_levels + user->opt->solver.grid_sequence;

  PetscFunctionBeginUser;
  PetscCall(GridSequenceSetTolerance(*snes, user));
  PetscCall(SolverSolve(*snes, user, *u, SOLVER_START_ZERO));
  for (PetscInt l = 1; l <= nlevels; ++l) {
    const PetscBool failed = (PetscBool)!user->rec.stats.converged;
    PetscLogDouble  t0, t1;

    if (failed && user->prob.level >= user->box.coarse_levels) break; /* a failed level of -contact_grid_sequence ends it */
    if (failed)
      PetscCall(PetscPrintf(PetscObjectComm((PetscObject)*dm), "  nested iteration: level %" PetscInt_FMT " failed (%s), the next starts from zero\n",
                            user->prob.level, SNESConvergedReasons[user->rec.stats.reason]));
    PetscCall(PetscTime(&t0));
    PetscCall(GridSequenceRefine(dm, user, snes, u));
    PetscCall(PetscTime(&t1));
    user->prob.setup_time = t1 - t0; /* refinement, set-up and interpolation */
    user->rec.stats.time_setup += t1 - t0;
    PetscCall(GridSequenceSetTolerance(*snes, user));
    PetscCall(SolverSolve(*snes, user, *u, failed ? SOLVER_START_ZERO : SOLVER_START_COARSER_MESH));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}
