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
/* What the error norms and the -reference comparison read of the run, read only: its options and data, and the problem
   on its mesh (the caller's pieces of it). */
typedef struct {
  const VerifyOptions *opt;     /* the accurate rule, the -reference file */
  const Scene         *scene;   /* Gamma_C's face sets, the obstacle, the exact solution (if any), the scene's name */
  const Material      *mat;     /* sigma(e) of the energy norm, sigma_n(u_exact) */
  PetscInt             degree;  /* of the displacement (-reference compares vertex values: degree 1) */
  Contact              contact; /* how the pressure follows from u_h, the penalty's eps, the contact set */
  PetscReal            h;       /* the largest cell diameter of the run's mesh: the pressure's weight without eps */
  Vec                  loc_bc;  /* the Dirichlet values, a local vector of the run's mesh */
  Mat                  K;       /* the bulk operator of the run's mesh, read only */
} VerifyRun;
PetscErrorCode ErrorNormsReset(ErrorNorms *e);
/* loc_p = p n at the contact set's nodes, from their nodal pressures */
PetscErrorCode ErrorNormsPressureVector(DM dm, Contact contact, Vec loc_p);
/* the norms of u_h against the target on the mesh of dm (a refinement of the run's: run_cell_h), K its bulk operator */
PetscErrorCode ErrorNormsEvaluate(DM dm, const PetscReal run_cell_h[], const VerifyRun *run, Mat K, Vec loc_uh, Vec loc_ph, const ErrorTarget *target,
                                  ErrorNorms *e);
/* the run's norms into *e: the penetration, and the errors against the scene's exact solution if it has one */
PetscErrorCode ErrorNormsCompute(DM dm, const VerifyRun *run, Vec u, ErrorNorms *e);
/* the run's norms against the -reference solution into *e (NaN without -reference) */
PetscErrorCode ReferenceCompute(DM dm, const VerifyRun *run, Vec u, ErrorNorms *e);
/* before the solve: the -reference file fits the run (reads run's opt, scene, mat and degree only) */
PetscErrorCode ReferenceCheckFile(DM dm, const VerifyRun *run);
PetscErrorCode VerifyView(MPI_Comm comm, const ErrorNorms *errors, const ErrorNorms *ref_errors); /* their lines of the summary */
PetscErrorCode VerifyWrite(const VerifyOptions *opt, const ErrorNorms *errors, const ErrorNorms *ref_errors, PetscViewer v); /* their part of /run */
