/* Names of Gmsh physical groups: PETSc 3.18 labels the faces of a .msh file by number only ("Face Sets"), so the
   project reads the file's $PhysicalNames and adds, for each group of faces, a label of that name carrying the same
   value. The boundary options then accept the name wherever they accept the number (scenes/boundary_options.c). */
#include <stdio.h>
#include "mesh.h"

/* Reads the $PhysicalNames section (text in every .msh version, binary ones too), stopping at the first section after it. */
static int ReadPhysicalNames(const char filename[], MeshPhysicalName names[], int *n)
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
    if (count < MESH_MAX_NAMES) {
      MeshPhysicalName g;
      char            *open, *close;

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

/* On a serial mesh (rank 0's names; the other ranks' are not read): a label per named group of faces, with the group's
   number. */
PetscErrorCode MeshLabelPhysicalNames(DM dm, int n, const MeshPhysicalName names_in[])
{
  MPI_Comm         comm = PetscObjectComm((PetscObject)dm);
  MeshPhysicalName names[MESH_MAX_NAMES];
  PetscInt         dim;
  DMLabel          face_sets;
  PetscMPIInt      rank;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCallMPI(MPI_Bcast(&n, 1, MPI_INT, 0, comm));
  PetscCheck(n <= MESH_MAX_NAMES, comm, PETSC_ERR_PLIB, "more than %d physical names", MESH_MAX_NAMES);
  if (rank == 0 && n) PetscCall(PetscArraycpy(names, names_in, n)); /* rank 0's, sent below */
  PetscCallMPI(MPI_Bcast(names, (PetscMPIInt)(n * sizeof(MeshPhysicalName)), MPI_BYTE, 0, comm));
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

/* On the serial mesh just read from a .msh file: its $PhysicalNames' labels (MeshLabelPhysicalNames()). */
PetscErrorCode MeshLabelGmshNames(DM dm, const char filename[])
{
  MeshPhysicalName names[MESH_MAX_NAMES];
  int              n = 0;
  PetscMPIInt      rank;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(PetscObjectComm((PetscObject)dm), &rank));
  if (rank == 0) (void)ReadPhysicalNames(filename, names, &n);
  PetscCall(MeshLabelPhysicalNames(dm, n, names));
  PetscFunctionReturn(PETSC_SUCCESS);
}
