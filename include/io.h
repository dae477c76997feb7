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
/* the writer of /run's part and the tables that each module owns, called by OutputWriteHDF5() once /run exists */
typedef PetscErrorCode (*OutputResultsWriter)(DM dm, const AppCtx *user, Vec u, PetscViewer v);
PetscErrorCode OutputWriteHDF5(DM dm, const AppCtx *user, Vec u, OutputResultsWriter write_results);
#define OUTPUT_STATE_FIELDS 5 /* displacement, contact_pressure, normal_gap, contact_boundary, contact_reaction */
PetscErrorCode OutputStateFields(DM dm, const AppCtx *user, Vec u, Vec fields[OUTPUT_STATE_FIELDS]);
/* output_mesh.c */
PetscErrorCode OutputViewMesh(DM dm, PetscViewer viewer);
