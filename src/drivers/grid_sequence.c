/* Nested iteration. -contact_grid_sequence N: the problem is solved on the mesh of the options, then on N uniform
   refinements of it, each level from the interpolation of the solution of the level below (exact for nested P1/Q1).
   -contact_coarse_levels K (by default where the P1 simplex box allows it, 2D or 3D): the mesh of the options is the last of K box
   doublings from a coarser box, each solved to the looser -contact_coarse_rtol; the final mesh is the direct build's.
   From a zero guess, semismooth Newton needs more steps as h falls (the active set moves about a cell per step);
   from the coarse solution it needs only a few on each level. A failed level of -contact_grid_sequence ends the
   sequence: the output is that level's, flagged as not converged. A failed coarser box of -contact_coarse_levels is
   reported and the next level starts from zero: the mesh of the options is always solved. */
#include "contact.h"
#include "estimate.h"
#include "mesh.h"
#include "physics.h"
#include "drivers_impl.h"

/* The solution u on dm as a local vector, with the Dirichlet values of loc_bc (the problem's, inserted by ProblemSetUp()). */
static PetscErrorCode LocalSolution(DM dm, Vec loc_bc, Vec u, Vec *loc)
{
  PetscFunctionBeginUser;
  PetscCall(DMCreateLocalVector(dm, loc));
  PetscCall(VecCopy(loc_bc, *loc));
  PetscCall(DMGlobalToLocal(dm, u, INSERT_VALUES, *loc));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The new mesh in place of the old, and u its global vector from the local fine_loc (which is destroyed). */
static PetscErrorCode TakeMesh(DM *dm, DM fine, Vec *fine_loc, Vec *u)
{
  PetscFunctionBeginUser;
  PetscCall(DMDestroy(dm));
  *dm = fine;
  PetscCall(DMCreateGlobalVector(fine, u));
  PetscCall(PetscObjectSetName((PetscObject)*u, "displacement"));
  PetscCall(DMLocalToGlobal(fine, *fine_loc, INSERT_VALUES, *u)); /* the fixed components are not in u: their values are the problem's */
  PetscCall(VecDestroy(fine_loc));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Replaces the problem on *dm by the problem on its uniform refinement, or with marked (the adaptive cycles, adapt.c) on
   its refinement where marked says, with *u interpolated as the initial guess (exact for nested P1/Q1). */
PetscErrorCode GridSequenceRefine(DM *dm, AppCtx *user, SNES *snes, Vec *u, DMLabel marked)
{
  Problem  *prob = SolverProblem(user->solver);
  DM        fine;
  PetscInt *parent, *vertex_source = NULL;
  Vec       loc, fine_loc;

  PetscFunctionBeginUser;
  PetscCall(LocalSolution(*dm, prob->loc_bc, *u, &loc));
  PetscCall(VecDestroy(u));
  PetscCall(ProblemDestroy(user->solver, snes));
  if (marked) {
    parent = NULL;
    PetscCall(MeshRefineMarked(*dm, marked, &fine, &vertex_source));
  } else if (user->box.is_box && user->opt->degree == 1) { /* the box of twice as many cells, built directly */
    parent = NULL;
    PetscCall(MeshCreateBoxLevel(*dm, &user->box, prob->level, &fine, &vertex_source));
  } else
    PetscCall(MeshRefineRegular(*dm, 1, &fine, &parent, &vertex_source));
  prob->level++;
  PetscCall(GridSequenceBarsSizes(fine, user->opt, user->contact, &user->box, prob->level)); /* -bars on tetrahedra: the final mesh's eps here */
  if (marked) PetscCall(MeshSetContactCellSizes(fine, user->scene.bcs.ncontact, user->scene.bcs.contact_ids)); /* one eps on Gamma_C */
  PetscCall(ProblemSetUp(fine, user->solver, &user->scene, snes));
  PetscCall(MultigridAddLevel(user->mg, *snes, *dm, fine, vertex_source, user->opt->degree)); /* with -pc_type mg */
  if (user->opt->degree == 1)
    PetscCall(MeshInterpolateVertexSources(*dm, fine, vertex_source, loc, &fine_loc)); /* exact and fast */
  else
    PetscCall(MeshInterpolateFromParents(*dm, fine, parent, 1, &loc, &fine_loc));
  if (user->bars.pressure_recorded) { /* -bars: the 2h level's pressure, for the pressure's band on the final mesh */
    PetscReal *fine_levels[2];

    PetscCall(MeshInterpolateVertexArrays(*dm, fine, vertex_source, 2, user->bars.pressure_levels, fine_levels));
    for (PetscInt k = 0; k < 2; ++k) {
      PetscCall(PetscFree(user->bars.pressure_levels[k]));
      user->bars.pressure_levels[k] = fine_levels[k];
    }
  }
  PetscCall(PetscFree(parent));
  PetscCall(PetscFree(vertex_source));
  PetscCall(VecDestroy(&loc));
  PetscCall(TakeMesh(dm, fine, &fine_loc, u));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The next mesh of the adaptive cycles from the Gmsh model (-adapt_model; the 3D box of the options without it;
   MeshRemesh()): each cell asks for its mean
   edge length, halved where marked and scaled by unmarked elsewhere (1 for the cycles, 0.5 for -bars's levels), and
   Gmsh meshes the model with these sizes. The meshes do not nest: the last solution is carried to the new mesh by
   locating each new vertex in the old mesh (MeshTransferApply()), the next solve's start. */
PetscErrorCode GridSequenceRemesh(DM *dm, AppCtx *user, SNES *snes, Vec *u, DMLabel marked, PetscReal unmarked)
{
  Problem     *prob = SolverProblem(user->solver);
  DM           fine;
  PetscReal   *size;
  PetscInt     cStart, cEnd;
  Vec          loc;
  MeshTransfer tr = NULL, tr_p = NULL;

  PetscFunctionBeginUser;
  PetscCall(DMPlexGetHeightStratum(*dm, 0, &cStart, &cEnd));
  PetscCall(PetscMalloc1(cEnd - cStart + 1, &size));
  for (PetscInt c = cStart; c < cEnd; ++c) {
    PetscInt value = -1;

    PetscCall(MeshCellMeanEdge(*dm, c, &size[c - cStart]));
    if (marked) PetscCall(DMLabelGetValue(marked, c, &value));
    size[c - cStart] *= value == DM_ADAPT_REFINE ? 0.5 : unmarked;
  }
  PetscCall(LocalSolution(*dm, prob->loc_bc, *u, &loc));
  PetscCall(MeshTransferCreateFromField(*dm, loc, &tr));
  if (user->bars.pressure_recorded) PetscCall(BarsPressureTransferCreate(*dm, &user->bars, loc, &tr_p)); /* -bars's 2h pressure */
  PetscCall(VecDestroy(u));
  PetscCall(ProblemDestroy(user->solver, snes));
  PetscCall(MeshRemesh(*dm, user->opt->adapt.model, &user->box, size, &fine));
  PetscCall(VecDestroy(&loc));
  PetscCall(PetscFree(size));
  prob->level++;
  PetscCall(MeshSetContactCellSizes(fine, user->scene.bcs.ncontact, user->scene.bcs.contact_ids)); /* one eps on Gamma_C */
  PetscCall(ProblemSetUp(fine, user->solver, &user->scene, snes));
  PetscCall(DMCreateLocalVector(fine, &loc));
  PetscCall(MeshTransferApply(tr, fine, loc));
  PetscCall(MeshTransferDestroy(&tr));
  if (tr_p) PetscCall(BarsPressureTransferApply(fine, &user->bars, loc, &tr_p));
  PetscCall(TakeMesh(dm, fine, &loc, u));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* -bars with the body's Gmsh model (-adapt_model): the levels of -contact_grid_sequence are the model meshed again at
   half the cells' sizes (GridSequenceRemesh()), not the mesh refined on its chords, so that the finest level's body is
   the curved body. The levels do not nest: the pressure's band carries the 2h level's nodal pressures to the final
   mesh's nodes by the remeshing's transfer (BarsPressureTransferCreate()), and eps, one value on Gamma_C on each level
   (MeshSetContactCellSizes()), is the same on all three: that of the first mesh's smallest contact cell halved at
   each level (GridSequenceBarsEps()), so that the levels differ by their meshes alone (a remeshed level's own
   smallest cell does not halve with its sizes). */
static PetscErrorCode GridSequenceRemeshHalf(DM *dm, AppCtx *user, SNES *snes, Vec *u)
{
  PetscFunctionBeginUser;
  PetscCall(GridSequenceRemesh(dm, user, snes, u, NULL, 0.5));
  user->bars.remeshed = PETSC_TRUE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Newton's relative tolerance on level `level` when it is a box below the one of the options (the coarse_levels of
   -contact_coarse_levels): -contact_coarse_rtol where looser than -snes_rtol. Its solution is only the next level's
   initial guess, whose own error is of the order of h. */
static PetscErrorCode GridSequenceSetTolerance(SNES snes, const RunOptions *opt, PetscInt coarse_levels, PetscInt level)
{
  const PetscInt nlevels = coarse_levels + opt->solver.grid_sequence;
  PetscReal      atol, rtol, stol;
  PetscInt       maxit, maxf;

  PetscFunctionBeginUser;
  if (level >= coarse_levels) PetscFunctionReturn(PETSC_SUCCESS);
  if (opt->bars && level >= nlevels - (BARS_LEVELS - 1)) PetscFunctionReturn(PETSC_SUCCESS); /* they serve the bars */
  PetscCall(SNESGetTolerances(snes, &atol, &rtol, &stol, &maxit, &maxf));
  if (opt->solver.coarse_rtol > rtol) PetscCall(SNESSetTolerances(snes, atol, opt->solver.coarse_rtol, stol, maxit, maxf));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The nested iteration asked for, in 2D (request[0]) and in 3D (request[1]), and the coarsest box's least cells per side
   in 2D and in 3D and its most in 3D (faces). coarse_mg: whether the coarser boxes are solved by their geometric multigrid
   (-contact_coarse_mg). default_mg: whether the 3D box, where it nests, is solved by the boxes' geometric multigrid
   without any linear solver in the options (MultigridSetDefault(); docs/decisions.md, "The 3D box's default solver"). */
PetscErrorCode GridSequenceCoarseRequest(MPI_Comm comm, Contact ct, const RunOptions *opt, PetscInt request[2], PetscInt faces[3],
                                         PetscInt *min_levels, PetscBool *coarse_mg, PetscBool *default_mg)
{
  const PetscInt               k       = opt->solver.coarse_levels;
  const char                  *pc_type = opt->solver.given.pc_type;
  const PetscBool              given   = opt->solver.given.pc_type_given;
  PetscBool                    is_mg, is_factor, mg_3d;
  const ContactSolverDefaults *defaults;

  PetscFunctionBeginUser;
  PetscCheck(k <= 0 || opt->degree == 1, comm, PETSC_ERR_USER_INPUT,
             "-contact_coarse_levels %" PetscInt_FMT " needs P1 displacements, got -displacement_petscspace_degree %" PetscInt_FMT, k, opt->degree);
  PetscCall(PetscStrcmp(pc_type, PCMG, &is_mg));
  PetscCall(PetscStrInList(pc_type, PCLU "," PCCHOLESKY, ',', &is_factor));
  /* -contact_coarse_mg: with an iterative preconditioner that is not already the boxes' multigrid (without -pc_type, the
     default is MUMPS's factorization, which a coarser box's small matrix does not make expensive); not with SNESVI, whose
     reduced system (vinewtonrsls) no PCMG can follow and whose vinewtonssls Jacobian CG cannot take */
  PetscCall(ContactGetSolverDefaults(ct, &defaults));
  *coarse_mg = (PetscBool)(opt->solver.coarse_mg && given && !is_mg && !is_factor && defaults->multigrid);
  /* without a preconditioner in the options, the penalty method and the elastic solve on P1 */
  *default_mg = (PetscBool)(!given && opt->degree == 1 && defaults->multigrid);
  mg_3d       = (PetscBool)(is_mg || *coarse_mg || *default_mg);
  request[0] = request[1] = k;
  /* the coarsest box's least cells per side in 2D and in 3D, and its most in 3D (0: any) */
  faces[0]    = (is_mg || *coarse_mg) ? GRID_SEQUENCE_MIN_FACES_MG : GRID_SEQUENCE_MIN_FACES;
  faces[1]    = mg_3d ? GRID_SEQUENCE_MIN_FACES_MG_3D : GRID_SEQUENCE_MIN_FACES_3D;
  faces[2]    = mg_3d ? GRID_SEQUENCE_MAX_COARSEST_MG_3D : 0;
  *min_levels = opt->bars ? BARS_LEVELS - 1 : 0; /* -bars: at least two boxes below the final one, whatever their size */
  /* by default: the penalty method, and the elastic solve with the geometric multigrid (its levels: -pc_type mg, and in
     3D the default's), on P1 */
  {
    const PetscBool penalty = (PetscBool)(opt->degree == 1 && defaults->nested_iteration),
                    elastic = (PetscBool)(opt->degree == 1 && defaults->linear);

    if (k < 0 && !(penalty || (elastic && is_mg))) request[0] = 0;
    if (k < 0 && !(penalty || (elastic && (is_mg || *default_mg)))) request[1] = 0;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* -bars on a tetrahedral mesh that the grid sequence refines: the children of a tetrahedron are not similar to it (the
   four inner ones are longer than half, by the diagonal of the octahedron they split), so that the cells do not halve
   (the Hertz sphere indenter's largest: 0.297, 0.243, 0.121) and eps, which follows each cell's diameter, would differ
   between the levels (0.0074, 0.0121, 0.0121): the bars' three levels would not solve one penalty problem. Each cell of
   the two levels below the final one gets instead the size of its descendants on the final mesh (MeshDescendantSizes(),
   the mean of their diameters^power: the mean of their eps), measured on the mesh refined for that purpose and
   destroyed; the final mesh keeps its own diameters, so that the answer is the run's without -bars. Triangles,
   quadrilaterals and hexahedra halve exactly and need none of it; nor do the boxes (built, not refined). dm is level
   `level` of the sequence of the options opt from the mesh box, ct the contact whose eps follows the cells. */
PetscErrorCode GridSequenceBarsSizes(DM dm, const RunOptions *opt, Contact ct, const MeshBox *box, PetscInt level)
{
  const PetscInt        nlevels = box->coarse_levels + opt->solver.grid_sequence;
  const ContactOptions *copt;
  PetscInt              dim;
  PetscBool             simplex;
  PetscReal            *sizes, hmax;

  PetscFunctionBeginUser;
  if (!opt->bars || ContactGetEpsScaling(ct) != CONTACT_EPS_MESH || (box->is_box && opt->degree == 1)) PetscFunctionReturn(PETSC_SUCCESS);
  if (level >= nlevels || level < nlevels - (BARS_LEVELS - 1)) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(ContactGetOptions(ct, &copt));
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMPlexIsSimplex(dm, &simplex));
  if (dim != 3 || !simplex) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(MeshDescendantSizes(dm, nlevels - level, copt->eps_power, &sizes, &hmax));
  PetscCall(MeshSetCellSizes(dm, hmax, sizes));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* -bars: the two levels below the final one solve at the final mesh's eps, so that the three differ by their
   discretization alone: eps = eps0 h^power / M with h halved at each level up to the final one (the local factors are the
   same on nested meshes). The levels below them only give the next its initial guess, at their own eps. snes solves
   level `level` of nlevels with the contact ct; bars holds the remeshed levels' one eps. */
static PetscErrorCode GridSequenceBarsEps(SNES snes, const RunOptions *opt, Contact ct, PetscInt level, PetscInt nlevels, ErrorBars *bars)
{
  const ContactOptions *copt;
  PetscReal             eps;
  DM                    dm;

  PetscFunctionBeginUser;
  if (!opt->bars || ContactGetEpsScaling(ct) != CONTACT_EPS_MESH || level < nlevels - (BARS_LEVELS - 1)) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(ContactGetOptions(ct, &copt));
  PetscCall(SNESGetDM(snes, &dm));
  if (opt->adapt.model[0]) { /* the remeshed levels' one eps, from the first bars level's own (GridSequenceRemeshHalf()) */
    if (level == nlevels - (BARS_LEVELS - 1)) {
      PetscCall(ContactGetEps(ct, &eps));
      bars->eps_levels = eps * PetscPowReal(2.0, -(PetscReal)(BARS_LEVELS - 1) * copt->eps_power);
    }
    PetscCall(ContactSetEps(ct, dm, bars->eps_levels));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  if (level >= nlevels) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(ContactGetEps(ct, &eps));
  PetscCall(ContactSetEps(ct, dm, eps * PetscPowReal(2.0, -(PetscReal)(nlevels - level) * copt->eps_power)));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* -bars: the quantities of the two levels below the final one (the final mesh's are those of the run, computed after the
   solve), and on the finer of them (2h) those of a second solve at eps / BARS_EPS_RATIO from its solution (the penalty's
   part of the bars, src/estimate/bars.c); that solve leaves the level's solution, eps and record of the outcome as they
   were, and counts in the run's totals. The 2h level, not the coarsest: the penalty widens the contact zone by a fringe
   that the coarsest level (4h) does not resolve (on the manufactured solution at 128 x 128 it saw a fifth of the
   widening that the final mesh has, the 2h level all of it; docs/estimate.md). */
static PetscErrorCode GridSequenceBarsLevel(SNES snes, AppCtx *user, Vec u, PetscInt nlevels)
{
  Problem       *prob  = SolverProblem(user->solver);
  RunStats      *stats = SolverStats(user->solver);
  ErrorBars     *b     = &user->bars;
  const PetscInt first = nlevels - (BARS_LEVELS - 1);
  DM             dm;

  PetscFunctionBeginUser;
  if (!user->opt->bars || prob->level < first || prob->level >= nlevels || !stats->converged) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(SNESGetDM(snes, &dm));
  PetscCall(PostprocessContact(dm, user->contact, prob, &user->scene.bcs, &user->opt->material, u, &user->quantities));
  b->level[b->nlevels]     = user->quantities.q;
  b->level_h[b->nlevels++] = prob->h;
  /* a driver's question: the penalty's part of the bars is a second solve at eps / R, which a type without eps has not */
  if (prob->level == first + BARS_EPS_LEVEL && !ContactHasPenalty(user->contact)) {
    const ContactSet *cs;

    PetscCall(ContactGetSet(user->contact, &cs));
    PetscCall(BarsRecordPressure(dm, user->contact, cs->pressure, NULL, b)); /* the pressure's band: no penalty part */
  } else if (prob->level == first + BARS_EPS_LEVEL) {
    const RunStats    saved = *stats;
    const ContactSet *cs;
    PetscReal        *p_eps;
    Vec               u0;

    PetscCall(ContactGetSet(user->contact, &cs));
    PetscCall(PetscMalloc1(cs->n, &p_eps));
    PetscCall(PetscArraycpy(p_eps, cs->pressure, cs->n));

    PetscCall(ContactGetEps(user->contact, &b->eps));
    b->eps_second = b->eps / BARS_EPS_RATIO;
    PetscCall(VecDuplicate(u, &u0));
    PetscCall(VecCopy(u, u0));
    PetscCall(ContactSetEps(user->contact, dm, b->eps_second));
    PetscCall(SolverSolve(snes, user->solver, u, SOLVER_START_NEARBY_EPS));
    if (stats->converged) {
      PetscCall(PostprocessContact(dm, user->contact, prob, &user->scene.bcs, &user->opt->material, u, &user->quantities));
      b->eps_level = user->quantities.q;
      b->eps_done  = PETSC_TRUE;
    }
    PetscCall(BarsRecordPressure(dm, user->contact, p_eps, b->eps_done ? cs->pressure : NULL, b));
    PetscCall(PetscFree(p_eps));
    PetscCall(ContactSetEps(user->contact, dm, b->eps));
    PetscCall(VecCopy(u0, u));
    PetscCall(VecDestroy(&u0));
    {
      RunStats now = *stats;

      *stats                  = saved;
      stats->newton_its_total = now.newton_its_total;
      stats->ksp_its_total    = now.ksp_its_total;
      stats->time_solve       = now.time_solve;
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Whether level `level` of nlevels starts from the coarser one's solution as SolverStartFromCoarser() decides: where
   -bars (bars) has solved both at the same eps. The other levels start as nested iteration does. */
static PetscBool GridSequenceStartsAsCoarser(PetscBool bars, PetscInt level, PetscInt nlevels)
{
  return (PetscBool)(bars && level > nlevels - (BARS_LEVELS - 1));
}

/* The run's first solve, on the coarsest level of nested iteration, and a solve on each finer level from the coarser
   one's solution (-contact_grid_sequence, and the coarser boxes of -contact_coarse_levels). */
static PetscErrorCode GridSequenceSolve(Driver d, AppCtx *user, DM *dm, SNES *snes, Vec *u)
{
  Problem       *prob    = SolverProblem(user->solver);
  RunStats      *stats   = SolverStats(user->solver);
  const PetscInt nlevels = user->box.coarse_levels + user->opt->solver.grid_sequence;

  PetscFunctionBeginUser;
  user->bars.nlevels    = 0;
  user->bars.eps_done   = PETSC_FALSE;
  user->bars.remeshed   = PETSC_FALSE;
  user->bars.eps_levels = 0.0;
  PetscCall(GridSequenceSetTolerance(*snes, user->opt, user->box.coarse_levels, prob->level));
  PetscCall(GridSequenceBarsEps(*snes, user->opt, user->contact, prob->level, nlevels, &user->bars));
  PetscCall(SolverSolve(*snes, user->solver, *u, SOLVER_START_ZERO));
  PetscCall(GridSequenceBarsLevel(*snes, user, *u, nlevels));
  for (PetscInt l = 1; l <= nlevels; ++l) {
    const PetscBool failed = (PetscBool)!stats->converged;
    PetscLogDouble  t0, t1;
    SolverStart     start;

    if (failed && prob->level >= user->box.coarse_levels) break; /* a failed level of -contact_grid_sequence ends it */
    if (failed)
      PetscCall(PetscPrintf(PetscObjectComm((PetscObject)*dm), "  nested iteration: level %" PetscInt_FMT " failed (%s), the next starts from zero\n",
                            prob->level, SNESConvergedReasons[stats->reason]));
    PetscCall(PetscTime(&t0));
    if (user->opt->bars && user->opt->adapt.model[0] && prob->level >= user->box.coarse_levels)
      PetscCall(GridSequenceRemeshHalf(dm, user, snes, u));
    else
      PetscCall(GridSequenceRefine(dm, user, snes, u, NULL));
    PetscCall(PetscTime(&t1));
    prob->setup_time = t1 - t0; /* refinement, set-up and interpolation */
    stats->time_setup += t1 - t0;
    PetscCall(GridSequenceSetTolerance(*snes, user->opt, user->box.coarse_levels, prob->level));
    PetscCall(GridSequenceBarsEps(*snes, user->opt, user->contact, prob->level, nlevels, &user->bars));
    start = SOLVER_START_COARSER_MESH;
    if (GridSequenceStartsAsCoarser(user->opt->bars, prob->level, nlevels)) PetscCall(SolverStartFromCoarser(user->contact, &start));
    PetscCall(SolverSolve(*snes, user->solver, *u, failed ? SOLVER_START_ZERO : start));
    PetscCall(GridSequenceBarsLevel(*snes, user, *u, nlevels));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The grid sequence's driver: its solves are rows of the solver's table of solves, and the levels' quantities the
   -bars of the run (AppCtx's bars) read. */
PetscErrorCode DriverCreate_GridSequence(Driver d)
{
  PetscFunctionBeginUser;
  d->ops.solve = GridSequenceSolve;
  PetscFunctionReturn(PETSC_SUCCESS);
}
