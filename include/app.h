/* Helpers of the command line and the options: checks shared by every module's *GetOptions, and the YAML options files checked before PETSc starts
 * (src/app/). */
#pragma once
#include "signorini.h"

/* options_files.c (before PetscInitialize(): plain C, returns 1 after printing the problem) */
int OptionsFilesCheckYAML(int argc, char **argv);

/* options_check.c */
PetscErrorCode OptionsCheckEnum(MPI_Comm comm, const char name[], const char *const list[], PetscBool array);
PetscErrorCode OptionsCheckFinite(MPI_Comm comm, const char name[], PetscReal value);
PetscErrorCode OptionsPathWhere(const char path[], char where[], size_t len);
PetscErrorCode OptionsCheckFiniteArray(MPI_Comm comm, const char name[], PetscInt n, const PetscReal values[]);
PetscErrorCode OptionsCountListValues(const char name[], PetscInt *n);
PetscErrorCode OptionsCheckPrefixesUsed(MPI_Comm comm, const char prefixes[]);
PetscErrorCode OptionsCheckAllUsed(MPI_Comm comm, PetscBool before_solve);
PetscErrorCode OptionsCheckValuesGiven(MPI_Comm comm);
PetscErrorCode OptionsReadVector(CompatOptionItems PetscOptionsObject, MPI_Comm comm, const char name[], const char help[], PetscInt dim,
                                 PetscReal v[], PetscBool *set);

/* errors.c: a refusal of the user's input as one paragraph, PETSc's error block for internal errors */
PetscErrorCode AppErrorPushHandler(void);
int            AppErrorExit(PetscErrorCode ierr);
PetscErrorCode AppDiagnosticRun(const char name[], PetscErrorCode (*fn)(void *ctx), void *ctx, char failed[], size_t len);

/* run_output.c: the run's results in the output file, each module's written by the module: an attribute of /run, its
   name formatted as printf() formats, and a column of a table (/solves, /steps, /cycles) in the viewer's group */
PetscErrorCode RunAttrReal(PetscViewer v, PetscReal value, const char format[], ...) PETSC_ATTRIBUTE_FORMAT(3, 4);
PetscErrorCode RunAttrInt(PetscViewer v, PetscInt value, const char format[], ...) PETSC_ATTRIBUTE_FORMAT(3, 4);
PetscErrorCode RunAttrString(PetscViewer v, const char value[], const char format[], ...) PETSC_ATTRIBUTE_FORMAT(3, 4);
PetscErrorCode RunColumn(MPI_Comm comm, PetscViewer v, const char name[], PetscInt n, const PetscReal values[]);
/* A column of a table of n rows, `i` its row: col[i] = expr for each i (col, n reals of work), written by RunColumn(). */
#define RUN_TABLE_COLUMN(comm, v, label, n, col, expr)    \
  do {                                                    \
    for (PetscInt i = 0; i < (n); ++i) (col)[i] = (expr); \
    PetscCall(RunColumn(comm, v, label, n, col));         \
  } while (0)
