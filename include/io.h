/* Input and output files: the safe replacement of output files, the HDF5/XDMF writer (src/io/). */
#pragma once
#include "signorini.h"

/* output_file.c */
PetscErrorCode OutputFileInstallCleanup(void);
PetscErrorCode OutputFileStageSignalNote(MPI_Comm comm, const char note[]);
PetscErrorCode OutputFileSplitPath(const char path[], char dir[], size_t dlen, char base[], size_t blen);
PetscErrorCode OutputFileXdmfName(const char h5[], char xdmf[], size_t len);
PetscErrorCode OutputFileCheckTarget(MPI_Comm comm, const char path[], PetscBool create_dir);
PetscErrorCode OutputFileCreateTemps(MPI_Comm comm, const char dir[], PetscInt n, char temps[][PETSC_MAX_PATH_LEN]);
PetscErrorCode OutputFileDiscardTemps(MPI_Comm comm);
PetscErrorCode OutputFileEnterDirectory(const char path[], int *cwd, char base[], size_t len);
PetscErrorCode OutputFileLeaveDirectory(int cwd);
PetscErrorCode OutputFileCommit(MPI_Comm comm, const char dir[], PetscInt n, char temps[][PETSC_MAX_PATH_LEN], const char *targets[]);

/* output_hdf5.c */
PetscErrorCode OutputGetOptions(MPI_Comm comm, RunOptions *opt);
#define OUTPUT_STATE_FIELDS 5 /* displacement, contact_pressure, normal_gap, contact_boundary, contact_reaction */
/* What the output file holds besides the mesh, as the run gives it (src/main.c): where it goes, the sources of the
   fields, and the writer of the results, which each module writes into /run and its tables once /run exists. */
typedef struct {
  const char          *path;        /* -output */
  PetscBool            dmview;      /* -output_dmview: the mesh by DMView() */
  Contact              contact;     /* the contact set: the nodal pressure, gap, reaction and area */
  Vec                  loc_bc;      /* the Dirichlet values, inserted into the displacement */
  const Scene         *scene;       /* its exact solution, where it has one: exact_displacement and error */
  PetscInt             degree;      /* of the displacement */
  PetscInt             nsteps;      /* a load path's steps, whose state fields are a time series, */
  Vec const           *step_fields; /*   OUTPUT_STATE_FIELDS per step (OutputStateFields()) */
  const ErrorBars     *bars;        /* the pressure's band (-bars) */
  const ErrorEstimate *estimate;    /* the cells' indicators */
  PetscErrorCode (*write_results)(DM dm, Vec u, PetscViewer v, void *ctx);
  void *ctx;
} OutputContent;
PetscErrorCode OutputWriteHDF5(DM dm, Vec u, const OutputContent *out);
PetscErrorCode OutputStateFields(DM dm, Contact contact, Vec loc_bc, Vec u, Vec fields[OUTPUT_STATE_FIELDS]);
/* output_mesh.c */
PetscErrorCode OutputViewMesh(DM dm, PetscViewer viewer);
