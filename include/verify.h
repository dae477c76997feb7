/* Verification: accurate quadrature, weak data of manufactured solutions, error norms, reference runs (src/verify/). */
#pragma once
#include "signorini.h"

/* cell_quadrature.c: basis functions at the points of an accurate rule, cell by cell or on faces */
typedef struct {
  PetscInt         dim, Nb, Nc; /* space dimension, basis functions, components */
  PetscInt         Nq;          /* points of the current cell or face */
  const PetscReal *x;           /* [Nq][dim] physical points */
  const PetscReal *w;           /* [Nq] weights times the Jacobian determinant */
  const PetscReal *B;           /* [Nq][Nb][Nc] basis values */
  const PetscReal *D;           /* [Nq][Nb][Nc][dim] physical basis gradients (cells only) */
  PetscInt         cell;        /* the cell whose basis is tabulated (the support cell of a face) */
  /* private */
  DM              dm;
  PetscFE         fe;
  const Scene    *scene;
  PetscQuadrature cell_rule[2], face_rule[2]; /* plain and refined */
  PetscTabulation cell_tab[2], face_tab;
  PetscReal      *xbuf, *wbuf, *dbuf, *J, *invJ, *detJ, *refbuf;
} CellQuadrature;
PetscErrorCode CellQuadratureCreate(DM dm, const Scene *scene, const VerifyOptions *opts, CellQuadrature *cq);
PetscErrorCode CellQuadratureSetCell(CellQuadrature *cq, PetscInt cell);
PetscErrorCode CellQuadratureSetFace(CellQuadrature *cq, PetscInt face);
PetscErrorCode CellQuadratureDestroy(CellQuadrature *cq);
PetscErrorCode CellQuadratureInterpolate(const CellQuadrature *cq, const PetscScalar closure[], PetscInt q, PetscReal u[], PetscReal grad[]);

/* verify_options.c, weak_data.c, error_norms.c, reference.c */
PetscErrorCode VerifyGetOptions(MPI_Comm comm, VerifyOptions *opts);
PetscErrorCode WeakDataAddToResidual(DM dm, AppCtx *user, Vec r0);
PetscErrorCode WeakDataExactNormalStress(const AppCtx *user, PetscInt dim, const PetscReal x[], PetscReal *sn);
/* What the discrete solution is compared with: the scene's exact solution, or an FE function on the same mesh. */
typedef struct {
  const Scene *scene;        /* exact solution and gradient, if not NULL; otherwise */
  Vec          loc_u;        /*   a displacement (local vector, boundary values inserted) */
  Vec          loc_pressure; /*   and its contact pressure p, stored as p n at the nodes of Gamma_C */
} ErrorTarget;
PetscErrorCode ErrorNormsReset(ErrorNorms *e);
PetscErrorCode ErrorNormsPressureVector(DM dm, AppCtx *user, Vec loc_p);
PetscErrorCode ErrorNormsEvaluate(DM dm, AppCtx *user, Mat K, Vec loc_uh, Vec loc_ph, const ErrorTarget *target, ErrorNorms *e);
PetscErrorCode ErrorNormsCompute(DM dm, AppCtx *user, Vec u);
PetscErrorCode ReferenceCompute(DM dm, AppCtx *user, Vec u);
PetscErrorCode ReferenceCheckFile(DM dm, const AppCtx *user);
