/* Verification: error norms against an exact solution and against a reference run, read only (src/verify/). */
#pragma once
#include "signorini.h"

/* verify_options.c, error_norms.c, reference.c */
PetscErrorCode VerifyGetOptions(MPI_Comm comm, VerifyOptions *opts);
/* What the discrete solution is compared with: the scene's exact solution, or an FE function on the same mesh. */
typedef struct {
  const Scene *scene;        /* exact solution and gradient, if not NULL; otherwise */
  Vec          loc_u;        /*   a displacement (local vector, boundary values inserted) */
  Vec          loc_pressure; /*   and its contact pressure p, stored as p n at the nodes of Gamma_C */
} ErrorTarget;
PetscErrorCode ErrorNormsReset(ErrorNorms *e);
PetscErrorCode ErrorNormsPressureVector(DM dm, AppCtx *user, Vec loc_p);
PetscErrorCode ErrorNormsEvaluate(DM dm, const PetscReal run_cell_h[], AppCtx *user, Mat K, Vec loc_uh, Vec loc_ph, const ErrorTarget *target,
                                  ErrorNorms *e);
PetscErrorCode ErrorNormsCompute(DM dm, AppCtx *user, Vec u);
PetscErrorCode ReferenceCompute(DM dm, AppCtx *user, Vec u);
PetscErrorCode ReferenceCheckFile(DM dm, const AppCtx *user);
