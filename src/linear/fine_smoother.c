/* -mg_fine_ksp_* and -mg_fine_pc_*: the options of the finest level's smoother of a multigrid preconditioner (PCMG,
   the geometric multigrid, or PCGAMG), as -mg_coarse_ are those of the coarsest. PETSc 3.18 names a level's smoother
   by its number (-mg_levels_N_), which depends on the mesh and on GAMG's coarsening; here the finest smoother gets the
   prefix mg_fine_ once the hierarchy exists, and its options are read again under it (those not given keep the values
   -mg_levels_ gave). Without -mg_fine_ksp_type and -mg_fine_pc_type nothing is changed. */
#include "linear.h"

/* The PC's prefix followed by mg_fine_. */
static PetscErrorCode FinePrefix(PC pc, char fine[], size_t len)
{
  const char *prefix;

  PetscFunctionBeginUser;
  PetscCall(PCGetOptionsPrefix(pc, &prefix));
  PetscCall(PetscSNPrintf(fine, len, "%smg_fine_", prefix ? prefix : ""));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Whether -mg_fine_ksp_type or -mg_fine_pc_type is given for the PC of ksp (read in the options phase, SolverGiven). */
PetscErrorCode FineSmootherGiven(KSP ksp, const SolverGiven *g, PetscBool *given)
{
  PC          pc;
  const char *prefix;
  PetscInt    k;

  PetscFunctionBeginUser;
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(PCGetOptionsPrefix(pc, &prefix));
  PetscCall(SolverGivenIndex(prefix, &k));
  *given = (PetscBool)(g->fine_ksp_type[k] || g->fine_pc_type[k]);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Before a linear solve: with a multigrid PC and -mg_fine_ options, sets the PC up (it would be next) and gives the
   finest smoother its options, unless it has them already (a rebuild may have made a new smoother). */
PetscErrorCode FineSmootherSetUp(KSP ksp, const SolverGiven *g)
{
  PC          pc;
  KSP         smoother;
  PetscBool   is_mg, given;
  PetscInt    nlevels;
  char        fine[256];
  const char *prefix;

  PetscFunctionBeginUser;
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(PetscObjectTypeCompareAny((PetscObject)pc, &is_mg, PCMG, PCGAMG, ""));
  if (!is_mg) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(FineSmootherGiven(ksp, g, &given));
  if (!given) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(KSPSetUp(ksp)); /* the hierarchy, and its levels' smoothers */
  PetscCall(PCMGGetLevels(pc, &nlevels));
  if (nlevels < 2) PetscFunctionReturn(PETSC_SUCCESS); /* one level: the coarse solver */
  PetscCall(PCMGGetSmoother(pc, nlevels - 1, &smoother));
  PetscCall(FinePrefix(pc, fine, sizeof(fine)));
  PetscCall(KSPGetOptionsPrefix(smoother, &prefix));
  if (prefix && !strcmp(prefix, fine)) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(KSPSetOptionsPrefix(smoother, fine));
  PetscCall(KSPSetFromOptions(smoother));
  PetscFunctionReturn(PETSC_SUCCESS);
}
