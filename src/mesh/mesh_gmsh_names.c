/* Names of Gmsh physical groups: PETSc 3.18 labels the faces of a .msh file by number only ("Face Sets"), so the
   project reads the file's $PhysicalNames and adds, for each group of faces, a label of that name carrying the same
   value. The boundary options then accept the name wherever they accept the number (scenes/boundary_options.c). */
#include <stdio.h>
#include "mesh.h"

#define GMSH_MAX_NAMES 64

typedef struct {
  int  dim, tag;
  char name[64];
} GmshName;

/* Reads the $PhysicalNames section (text in every .msh version, binary ones too), stopping at the first section after it. */
static int ReadPhysicalNames(const char filename[], GmshName names[], int *n)
{
  FILE *f = fopen(filename, "r");
  char  line[512];
  int   count = 0, in_section = 0;

  *n = 0;
  if (!f) return 1;
  while (fgets(line, sizeof(line), f)) {
    if (!in_section) {
      if (!strncmp(line, "$PhysicalNames", 14))
        in_section = 1;
      else if (!strncmp(line, "$Nodes", 6) || !strncmp(line, "$Entities", 9))
        break; /* no names: the large sections start */
      continue;
    }
    if (!strncmp(line, "$EndPhysicalNames", 17)) break;
    if (in_section == 1) { /* the count */
      in_section = 2;
      continue;
    }
    if (count < GMSH_MAX_NAMES) {
      GmshName g;
      char    *open, *close;

      if (sscanf(line, "%d %d", &g.dim, &g.tag) != 2) continue;
      open  = strchr(line, '"');
      close = open ? strchr(open + 1, '"') : NULL;
      if (!open || !close || close - open - 1 <= 0 || close - open - 1 >= (long)sizeof(g.name)) continue;
      memcpy(g.name, open + 1, (size_t)(close - open - 1));
      g.name[close - open - 1] = '\0';
      names[count++]           = g;
    }
  }
  fclose(f);
  *n = count;
  return 0;
}

/* On the serial mesh just read from a .msh file: a label per named group of faces, with the group's number. */
PetscErrorCode MeshLabelGmshNames(DM dm, const char filename[])
{
  MPI_Comm    comm = PetscObjectComm((PetscObject)dm);
  GmshName    names[GMSH_MAX_NAMES];
  int         n = 0;
  PetscMPIInt rank;
  PetscInt    dim;
  DMLabel     face_sets;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  if (rank == 0) (void)ReadPhysicalNames(filename, names, &n);
  PetscCallMPI(MPI_Bcast(&n, 1, MPI_INT, 0, comm));
  PetscCallMPI(MPI_Bcast(names, (PetscMPIInt)(n * sizeof(GmshName)), MPI_BYTE, 0, comm));
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMGetLabel(dm, "Face Sets", &face_sets));
  for (int i = 0; i < n; ++i) {
    PetscBool exists;
    DMLabel   label;
    IS        is = NULL;

    if (names[i].dim != dim - 1 || !face_sets) continue;
    PetscCall(DMHasLabel(dm, names[i].name, &exists));
    if (exists) continue; /* a name PETSc already uses ("Face Sets", "depth", ...) stays PETSc's */
    PetscCall(DMCreateLabel(dm, names[i].name));
    PetscCall(DMGetLabel(dm, names[i].name, &label));
    PetscCall(DMLabelGetStratumIS(face_sets, names[i].tag, &is));
    if (is) {
      PetscCall(DMLabelSetStratumIS(label, names[i].tag, is));
      PetscCall(ISDestroy(&is));
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}
