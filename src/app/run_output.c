/* The run's results in the output file, through PETSc's HDF5 viewer: an attribute of the group /run, and a column of a
   table (/solves, /steps, /cycles: one dataset per column, one row per solve, step or cycle). Each module writes its
   own results with them (ContactWrite(), EstimateWrite(), ...), and src/main.c composes the file's /run from those
   writers (docs/output.md lists what they write). A name may be formatted, as "contact_force_%c". */
#include <petscviewerhdf5.h>
#include <stdarg.h>
#include "app.h"

/* The attribute of /run whose name the format and its arguments make, of the given type. */
static PetscErrorCode RunAttrWrite(PetscViewer v, PetscDataType type, const void *value, const char format[], va_list ap)
{
  char name[256];

  PetscFunctionBeginUser;
  PetscCheck(vsnprintf(name, sizeof(name), format, ap) < (int)sizeof(name), PETSC_COMM_SELF, PETSC_ERR_PLIB, "The attribute name %s is too long",
             format);
  PetscCall(PetscViewerHDF5WriteAttribute(v, "/run", name, type, value));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* va_end() runs before an error returns */
#define RUN_ATTR(v, type, value, format)             \
  do {                                               \
    va_list        ap;                               \
    PetscErrorCode ierr;                             \
    va_start(ap, format);                            \
    ierr = RunAttrWrite(v, type, value, format, ap); \
    va_end(ap);                                      \
    PetscCall(ierr);                                 \
  } while (0)

PetscErrorCode RunAttrReal(PetscViewer v, PetscReal value, const char format[], ...)
{
  PetscFunctionBeginUser;
  RUN_ATTR(v, PETSC_REAL, &value, format);
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode RunAttrInt(PetscViewer v, PetscInt value, const char format[], ...)
{
  PetscFunctionBeginUser;
  RUN_ATTR(v, PETSC_INT, &value, format);
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode RunAttrString(PetscViewer v, const char value[], const char format[], ...)
{
  PetscFunctionBeginUser;
  RUN_ATTR(v, PETSC_STRING, value, format);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The column name of the viewer's current group: n values on rank 0 (the table's rows), as a dataset of length n. */
PetscErrorCode RunColumn(MPI_Comm comm, PetscViewer v, const char name[], PetscInt n, const PetscReal values[])
{
  Vec          col;
  PetscScalar *a;
  PetscMPIInt  rank;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCall(VecCreateMPI(comm, rank == 0 ? n : 0, n, &col));
  PetscCall(PetscObjectSetName((PetscObject)col, name));
  PetscCall(VecGetArray(col, &a));
  for (PetscInt i = 0; rank == 0 && i < n; ++i) a[i] = values[i];
  PetscCall(VecRestoreArray(col, &a));
  PetscCall(VecView(col, v));
  PetscCall(VecDestroy(&col));
  PetscFunctionReturn(PETSC_SUCCESS);
}
