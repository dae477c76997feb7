/* The linear acceleration's own parts, private to src/linear/: the multigrid's levels, the finest smoother's bound
   (smoother_bound.c, called by pc_reuse.c), the reset of the reuse (pc_recovery.c's) and the options given for the
   smoothers' eigenvalue estimates. */
#pragma once
#include "linear.h"

/* The interpolations between the nested meshes solved so far (multigrid.c): the levels of a geometric multigrid
   (-pc_type mg) on the mesh of the current problem, which has n + 1 of them. */
struct _n_Multigrid {
  PetscInt  n;
  Mat       interp[MULTIGRID_MAX_LEVELS]; /* [l]: from the global vector of mesh l to that of mesh l + 1 */
  PetscBool coarse_mg;                    /* the coarser boxes are solved with the geometric multigrid of the boxes below */
  PetscBool is_default;                   /* it is the default linear solver (no -pc_type; the 3D box that nests) */
};

/* pc_reuse.c: forgets the build (pc_recovery.c) */
PetscErrorCode PcReuseReset(PcReuse *r);
PetscErrorCode PcReuseDecide(PcReuse *r, SNES snes, DM dm, Vec X);
PetscErrorCode PcReuseAfterJacobian(PcReuse *r, SNES snes);

/* smoother_bound.c: the finest level's Chebyshev interval at each update of a GAMG hierarchy (pc_reuse.c) */
PetscErrorCode SmootherBoundFinest(PcReuse *r, PC pc, PetscInt nlevels, const PetscScalar jvals[], PetscBool check);

/* solver_options.c */
PetscErrorCode SolverGivenEsteig(const SolverGiven *g, const char prefix[], PetscInt *n, PetscReal t[]);
