/* Geometric multigrid (-pc_type mg) over the nested meshes of nested iteration: the box's coarser boxes
   (-contact_coarse_levels) and the uniform refinements of -contact_grid_sequence. Each refinement adds the interpolation
   from the global vector of the coarser mesh to that of the finer one (P1/Q1: a fine vertex gets the mean of the values
   at the vertices of its source point, exact for nested spaces); the problem on the finest mesh so far then has a PCMG
   of one level per mesh, with Galerkin coarse operators (P^T A P: the penalty rows included, whatever the coarser
   meshes' own eps), and the coarsest mesh's operator is solved by the PCMG's coarse solver (LU by default).
   -contact_coarse_mg: with another iterative preconditioner, the coarser boxes of nested iteration are solved by this
   geometric multigrid under the options prefix contact_coarse_, and the final mesh by the options' preconditioner. */
#include "mesh.h"
#include "linear_impl.h"

/* a 3D coarsest mesh of more unknowns is solved alone by GAMG, not by a factorization at each Newton step */
#define MULTIGRID_COARSE_LU_ROWS_3D 10000

/* coarse_mg: GridSequenceCoarseRequest()'s answer, whether the coarser boxes are solved by their geometric multigrid. */
PetscErrorCode MultigridCreate(PetscBool coarse_mg, Multigrid *mg)
{
  PetscFunctionBeginUser;
  PetscCall(PetscNew(mg));
  (*mg)->coarse_mg = coarse_mg;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* is_default: the run's linear solver is this geometric multigrid, no -pc_type given (GridSequenceCoarseRequest()'s
   default_mg, on a 3D box that nests). */
PetscErrorCode MultigridSetDefault(Multigrid mg, PetscBool is_default)
{
  PetscFunctionBeginUser;
  mg->is_default = is_default;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscBool MultigridIsDefault(Multigrid mg)
{
  return mg->is_default;
}

/* Forgets the levels (the meshes no longer nest with the current one). */
static PetscErrorCode MultigridClear(Multigrid mg)
{
  PetscFunctionBeginUser;
  for (PetscInt l = 0; l < mg->n; ++l) PetscCall(MatDestroy(&mg->interp[l]));
  mg->n = 0;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode MultigridDestroy(Multigrid *mg)
{
  PetscFunctionBeginUser;
  if (!*mg) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(MultigridClear(*mg));
  PetscCall(PetscFree(*mg));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Whether the problem's mesh (at grid level level) is a coarser box of nested iteration (box) solved under -contact_coarse_mg. */
static inline PetscBool MultigridOnCoarseBox(Multigrid mg, PetscInt level, const MeshBox *box)
{
  return (PetscBool)(mg->coarse_mg && level < box->coarse_levels);
}

/* With -pc_type mg (the PC of snes, the fine mesh's problem) and P1/Q1, adds the interpolation from coarse to fine,
   refined once (vertex_source[]: MeshCreateBoxLevel(), MeshRefineRegular()). Both meshes' problems must be set up (their
   sections); fine's rows are its owned free components, coarse's columns its free components, a fixed coarse component
   contributing nothing. degree: the displacement's (the interpolation is P1/Q1's). */
PetscErrorCode MultigridAddLevel(Multigrid mg, SNES snes, DM coarse, DM fine, const PetscInt vertex_source[], PetscInt degree)
{
  MPI_Comm     comm = PetscObjectComm((PetscObject)fine);
  PetscSection cl, cg, fl, fg;
  PetscInt     dim, vStart, vEnd, cvb[2], ceb[2], m, n, rstart, cstart, cend, *dnz, *onz;
  Mat          P;
  KSP          ksp;
  PC           pc;
  PetscBool    is_mg;

  PetscFunctionBeginUser;
  PetscCall(SNESGetKSP(snes, &ksp));
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(PetscObjectTypeCompare((PetscObject)pc, PCMG, &is_mg));
  if (!is_mg || degree != 1) { /* the coarser meshes' interpolations, if any (-contact_coarse_mg), serve no longer */
    PetscCall(MultigridClear(mg));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  PetscCheck(mg->n < MULTIGRID_MAX_LEVELS, comm, PETSC_ERR_USER_INPUT, "-pc_type mg: at most %d nested meshes", MULTIGRID_MAX_LEVELS + 1);
  PetscCall(DMGetDimension(fine, &dim));
  PetscCall(DMGetLocalSection(coarse, &cl));
  PetscCall(DMGetGlobalSection(coarse, &cg));
  PetscCall(DMGetLocalSection(fine, &fl));
  PetscCall(DMGetGlobalSection(fine, &fg));
  PetscCall(DMPlexGetDepthStratum(fine, 0, &vStart, &vEnd));
  PetscCall(DMPlexGetDepthStratum(coarse, 0, &cvb[0], &cvb[1]));
  PetscCall(DMPlexGetDepthStratum(coarse, 1, &ceb[0], &ceb[1]));
  PetscCall(PetscSectionGetConstrainedStorageSize(fg, &m));
  PetscCall(PetscSectionGetConstrainedStorageSize(cg, &n));
  PetscCallMPI(MPI_Scan(&m, &rstart, 1, MPIU_INT, MPI_SUM, comm));
  rstart -= m;
  PetscCallMPI(MPI_Scan(&n, &cend, 1, MPIU_INT, MPI_SUM, comm));
  cstart = cend - n;
  PetscCall(PetscCalloc2(m, &dnz, m, &onz));
  for (PetscInt pass = 0; pass < 2; ++pass) {
    if (pass == 1) {
      PetscCall(MatCreateAIJ(comm, m, n, PETSC_DETERMINE, PETSC_DETERMINE, 0, dnz, 0, onz, &P));
      PetscCall(MatSetOption(P, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_TRUE));
    }
    for (PetscInt v = vStart; v < vEnd; ++v) {
      PetscInt fidx[3], verts[8], nv, goff, dof;

      PetscCall(PetscSectionGetDof(fg, v, &dof));
      PetscCall(PetscSectionGetOffset(fg, v, &goff));
      if (dof <= 0 || goff < 0) continue; /* no unknowns, or another rank's */
      PetscCall(MeshPointGlobalIndices(fl, fg, v, dim, fidx));
      PetscCall(MeshSourceVertices(coarse, cvb, ceb, vertex_source[v - vStart], verts, &nv));
      for (PetscInt i = 0; i < nv; ++i) {
        PetscInt cidx[3];

        PetscCall(MeshPointGlobalIndices(cl, cg, verts[i], dim, cidx));
        for (PetscInt c = 0; c < dim; ++c) {
          if (fidx[c] < 0 || cidx[c] < 0) continue;
          if (pass == 0) {
            if (cidx[c] >= cstart && cidx[c] < cend)
              dnz[fidx[c] - rstart]++;
            else
              onz[fidx[c] - rstart]++;
          } else
            PetscCall(MatSetValue(P, fidx[c], cidx[c], 1.0 / nv, INSERT_VALUES));
        }
      }
    }
  }
  PetscCall(PetscFree2(dnz, onz));
  PetscCall(MatAssemblyBegin(P, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(P, MAT_FINAL_ASSEMBLY));
  mg->interp[mg->n++] = P;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The solve of the coarsest mesh. Alone (its own Newton steps, before any finer mesh) PCMG's one level would be a
   smoother: it is the coarse solver, under the prefix mg_coarse_ as on more levels. In 2D PETSc's default, LU (on
   several ranks redundant LU). In 3D, where PETSc has MUMPS, MUMPS's factorization: PETSc's own LU orders a box's
   unknowns with far more fill than MUMPS's own orderings. And a 3D coarsest mesh of more than
   MULTIGRID_COARSE_LU_ROWS_3D unknowns is solved alone by GAMG, not factored at each of its Newton steps; below finer
   meshes it is factored once per build of their hierarchy (docs/decisions.md, "The coarsest mesh's solve"). Options under the prefix
   (-mg_coarse_pc_type, ...) decide over all of these. */
static PetscErrorCode MultigridSetCoarseSolve(SNES snes, PC pc, PetscInt nfine, const char prefix[])
{
  KSP         coarse;
  PC          cpc;
  PetscMPIInt size;
  PetscInt    dim, rows;
  PetscBool   mumps;
  DM          dm;
  Mat         A;

  PetscFunctionBeginUser;
  PetscCall(PCMGGetCoarseSolve(pc, &coarse));
  PetscCall(KSPGetPC(coarse, &cpc));
  PetscCallMPI(MPI_Comm_size(PetscObjectComm((PetscObject)pc), &size));
  PetscCall(SNESGetDM(snes, &dm));
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(PetscHasExternalPackage("mumps", &mumps));
  PetscCall(SNESGetJacobian(snes, &A, NULL, NULL, NULL));
  PetscCall(MatGetSize(A, &rows, NULL));
  if (!nfine) {
    PetscCall(KSPSetOptionsPrefix(coarse, prefix));
    PetscCall(KSPAppendOptionsPrefix(coarse, "mg_coarse_"));
  }
  if (dim == 3 && mumps) {
    PetscCall(KSPSetType(coarse, KSPPREONLY));
    if (!nfine && rows > MULTIGRID_COARSE_LU_ROWS_3D)
      PetscCall(PCSetType(cpc, PCGAMG));
    else {
      PetscCall(PCSetType(cpc, PCLU));
      PetscCall(PCFactorSetMatSolverType(cpc, MATSOLVERMUMPS));
    }
  } else if (!nfine) {
    PetscCall(KSPSetType(coarse, KSPPREONLY));
    PetscCall(PCSetType(cpc, size > 1 ? PCREDUNDANT : PCLU));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* With -pc_type mg, gives the SNES's PCMG one level per mesh solved so far (the current one the finest), the
   interpolations between them, and Galerkin coarse operators unless -pc_mg_galerkin says otherwise. The problem of the
   options must have coarser meshes: a PCMG of one level would be its coarse solver alone. level: the problem's grid
   level; box: the mesh of the options (its coarser boxes); opt: the solver's options. */
PetscErrorCode MultigridSetUpPC(Multigrid mg, SNES snes, PetscInt level, const MeshBox *box, const SolverOptions *opt)
{
  KSP         ksp;
  PC          pc;
  PetscBool   is_mg;
  PetscInt    nlevels, k;
  const char *prefix;

  PetscFunctionBeginUser;
  PetscCall(SNESGetKSP(snes, &ksp));
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(PetscObjectTypeCompare((PetscObject)pc, PCMG, &is_mg));
  if (!is_mg) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCheck(mg->n > 0 || level < box->coarse_levels + opt->grid_sequence, PetscObjectComm((PetscObject)snes), PETSC_ERR_USER_INPUT,
             "-pc_type mg takes its levels from nested meshes, and this mesh has none: use the simplex box (-dm_plex_box_faces, "
             "-contact_coarse_levels) or -contact_grid_sequence N, or another -pc_type");
  PetscCall(PCGetOptionsPrefix(pc, &prefix));
  PetscCall(SolverGivenIndex(prefix, &k));
  PetscCheck(!opt->given.pc_mg_levels[k], PetscObjectComm((PetscObject)snes), PETSC_ERR_USER_INPUT,
             "-pc_mg_levels: the levels of -pc_type mg are the nested meshes (-contact_coarse_levels, -contact_grid_sequence)");
  PetscCall(PCMGGetLevels(pc, &nlevels));
  if (nlevels == mg->n + 1) { /* set up by an earlier solve on this mesh? */
    if (mg->n) {
      Mat P;

      PetscCall(PCMGGetInterpolation(pc, mg->n, &P));
      if (P == mg->interp[mg->n - 1]) PetscFunctionReturn(PETSC_SUCCESS);
    } else {
      KSP         coarse;
      const char *kprefix;
      PetscBool   done;

      PetscCall(PCMGGetCoarseSolve(pc, &coarse));
      PetscCall(KSPGetOptionsPrefix(coarse, &kprefix));
      PetscCall(PetscStrendswith(kprefix, "mg_coarse_", &done));
      if (done) PetscFunctionReturn(PETSC_SUCCESS);
    }
  }
  PetscCall(PCMGSetLevels(pc, mg->n + 1, NULL));
  for (PetscInt l = 1; l <= mg->n; ++l) PetscCall(PCMGSetInterpolation(pc, l, mg->interp[l - 1]));
  PetscCall(MultigridSetCoarseSolve(snes, pc, mg->n, prefix));
  if (MultigridOnCoarseBox(mg, level, box) || mg->is_default) /* the smoothers of mg.yaml; options may change them */
    for (PetscInt l = 1; l <= mg->n; ++l) {
      KSP smoother;
      PC  spc;

      PetscCall(PCMGGetSmoother(pc, l, &smoother));
      PetscCall(KSPGetPC(smoother, &spc));
      PetscCall(PCSetType(spc, PCJACOBI));
    }
  if (!opt->given.pc_mg_galerkin[k]) PetscCall(PCMGSetGalerkin(pc, PC_MG_GALERKIN_BOTH));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* -contact_coarse_mg, on a coarser box of nested iteration: the linear solver is CG with the geometric multigrid of the
   boxes solved so far (MultigridSetUpPC() gives it its levels before each solve; Chebyshev smoothers with point Jacobi,
   LU on the coarsest box), read from the options under the prefix contact_coarse_ (-contact_coarse_ksp_rtol,
   -contact_coarse_mg_levels_ksp_max_it, ...): the options without it are the final mesh's. level: the problem's grid
   level; box: the mesh of the options. */
PetscErrorCode MultigridSetCoarseBoxSolver(Multigrid mg, KSP ksp, PetscInt level, const MeshBox *box)
{
  PC pc;

  PetscFunctionBeginUser;
  if (!MultigridOnCoarseBox(mg, level, box)) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(KSPSetOptionsPrefix(ksp, "contact_coarse_"));
  PetscCall(KSPSetType(ksp, KSPCG));
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(PCSetType(pc, PCMG));
  PetscFunctionReturn(PETSC_SUCCESS);
}
