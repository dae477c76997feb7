/* The mesh Gmsh writes at each remeshing (mesh_remesh.c), read as PETSc's Gmsh reader reads it with interpolation, in
   about two fifths of its time. PETSc 3.18 reads the cells and vertices, then builds the faces and edges by
   DMPlexInterpolate(), which was four fifths of the reading and a tenth of a 3D adaptive run (docs/estimate.md, "The
   remeshing's own costs"). Here PETSc reads the cells and vertices alone (DMPlexCreateGmshFromFile() without interpolation: the same
   vertex numbering and cell cones), the faces and edges are built directly as the simplex box's are
   (MeshCreateInterpolatedSimplices(): DMPlexInterpolate()'s points, cones and orientations), and the labels are set as
   PETSc's reader sets them: its "Cell Sets" copied, and each boundary element of the file gives the face its vertices
   join the first physical tag of its entity ("Face Sets"; PETSc's default, without -dm_plex_gmsh_multiple_tags).
   The boundary elements come from the file itself (Gmsh's MSH 4.1 ASCII, as GmshRemesh() writes it), with PETSc's
   vertex numbering: the nodes in the file's order, those used by some element. On the make hertz sphere's graded mesh
   (121,151 tetrahedra): 0.51 s against 1.23 s (0.2 s of it the boundary elements' parsing), and no entry of the
   topology, the coordinates or the labels differs (MeshCompareTopology()). Rank 0 reads; the other ranks have the
   empty mesh, as with PETSc's reader. */
#include <stdio.h>
#include <string.h>
#include "mesh.h"

#define GMSH_LINE 4096

/* Skips the file to the line "$name"; PETSC_FALSE at the end of the file. */
static PetscBool SeekSection(FILE *fp, const char name[])
{
  char line[GMSH_LINE];

  while (fgets(line, sizeof(line), fp))
    if (line[0] == '$' && !strncmp(line + 1, name, strlen(name)) && (line[1 + strlen(name)] == '\n' || line[1 + strlen(name)] == '\r'))
      return PETSC_TRUE;
  return PETSC_FALSE;
}

/* The first physical tag of each entity of dimension fdim (-1: none), indexed by its tag (*ntags of them). */
static PetscErrorCode ReadEntityTags(FILE *fp, const char file[], PetscInt fdim, PetscInt *ntags, PetscInt **tag)
{
  long   count[4];
  double x;

  PetscFunctionBeginUser;
  *ntags = 0;
  *tag   = NULL;
  PetscCheck(SeekSection(fp, "Entities"), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "%s: no $Entities section (MSH 4.1)", file);
  PetscCheck(fscanf(fp, "%ld %ld %ld %ld", &count[0], &count[1], &count[2], &count[3]) == 4, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "%s: $Entities",
             file);
  for (PetscInt d = 0; d < 4; ++d) {
    for (long e = 0; e < count[d]; ++e) {
      long etag, nphys, p, nb, b;

      PetscCheck(fscanf(fp, "%ld", &etag) == 1, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "%s: $Entities", file);
      for (PetscInt k = 0; k < (d == 0 ? 3 : 6); ++k)
        PetscCheck(fscanf(fp, "%lf", &x) == 1, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "%s: $Entities", file);
      PetscCheck(fscanf(fp, "%ld", &nphys) == 1, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "%s: $Entities", file);
      if (d == fdim) { /* grown to the largest entity tag */
        if (etag >= *ntags) {
          PetscInt *grown;

          PetscCall(PetscMalloc1(etag + 1, &grown));
          for (PetscInt i = 0; i <= etag; ++i) grown[i] = i < *ntags ? (*tag)[i] : -1;
          PetscCall(PetscFree(*tag));
          *tag   = grown;
          *ntags = etag + 1;
        }
      }
      for (long k = 0; k < nphys; ++k) {
        PetscCheck(fscanf(fp, "%ld", &p) == 1, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "%s: $Entities", file);
        if (d == fdim && k == 0) (*tag)[etag] = (PetscInt)p;
      }
      if (d > 0) {
        PetscCheck(fscanf(fp, "%ld", &nb) == 1, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "%s: $Entities", file);
        for (long k = 0; k < nb; ++k) PetscCheck(fscanf(fp, "%ld", &b) == 1, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "%s: $Entities", file);
      }
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Each node tag's index in the file's order (*index[tag - *tag0], -1 where no node has the tag), and the node count. */
static PetscErrorCode ReadNodeOrder(FILE *fp, const char file[], PetscInt *nnodes, PetscInt *tag0, PetscInt *ntag, PetscInt **index)
{
  long   nblocks, n, tmin, tmax, edim, etag, param, nin, t;
  double x;
  long   k = 0;

  PetscFunctionBeginUser;
  PetscCheck(SeekSection(fp, "Nodes"), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "%s: no $Nodes section", file);
  PetscCheck(fscanf(fp, "%ld %ld %ld %ld", &nblocks, &n, &tmin, &tmax) == 4, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "%s: $Nodes", file);
  *nnodes = (PetscInt)n;
  *tag0   = (PetscInt)tmin;
  *ntag   = (PetscInt)(tmax - tmin + 1);
  PetscCall(PetscMalloc1(*ntag + 1, index));
  for (PetscInt i = 0; i < *ntag; ++i) (*index)[i] = -1;
  for (long b = 0; b < nblocks; ++b) {
    PetscCheck(fscanf(fp, "%ld %ld %ld %ld", &edim, &etag, &param, &nin) == 4, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "%s: $Nodes", file);
    PetscCheck(!param, PETSC_COMM_SELF, PETSC_ERR_SUP, "%s: parametric nodes", file);
    for (long i = 0; i < nin; ++i) {
      PetscCheck(fscanf(fp, "%ld", &t) == 1 && t >= tmin && t <= tmax, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "%s: $Nodes", file);
      (*index)[t - tmin] = (PetscInt)k++;
    }
    for (long i = 0; i < 3 * nin; ++i) PetscCheck(fscanf(fp, "%lf", &x) == 1, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "%s: $Nodes", file);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The nodes of a Gmsh element type (points, lines, triangles, tetrahedra: the first order). */
static PetscInt TypeNodes(long type)
{
  switch (type) {
    case 15:
      return 1;
    case 1:
      return 2;
    case 2:
      return 3;
    case 4:
      return 4;
    default:
      return -1;
  }
}

/* The elements: those of dimension fdim (their node indices, nv each, and their entity's tag) kept, and every node an
   element uses marked (used[]). */
static PetscErrorCode ReadElements(FILE *fp, const char file[], PetscInt fdim, PetscInt tag0, PetscInt ntag, const PetscInt index[], PetscBool used[],
                                   PetscInt *nfaces, PetscInt **fnodes, PetscInt **fentity)
{
  long     nblocks, n, tmin, tmax, edim, etag, type, nin, t, node;
  PetscInt cap = 0;

  PetscFunctionBeginUser;
  *nfaces  = 0;
  *fnodes  = NULL;
  *fentity = NULL;
  PetscCheck(SeekSection(fp, "Elements"), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "%s: no $Elements section", file);
  PetscCheck(fscanf(fp, "%ld %ld %ld %ld", &nblocks, &n, &tmin, &tmax) == 4, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "%s: $Elements", file);
  for (long b = 0; b < nblocks; ++b) {
    PetscInt nn;

    PetscCheck(fscanf(fp, "%ld %ld %ld %ld", &edim, &etag, &type, &nin) == 4, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "%s: $Elements", file);
    nn = TypeNodes(type);
    PetscCheck(nn > 0, PETSC_COMM_SELF, PETSC_ERR_SUP, "%s: element type %ld (first-order simplices only)", file, type);
    if (edim == fdim && *nfaces + nin > cap) {
      PetscInt *grown_n, *grown_e;

      cap = *nfaces + (PetscInt)nin;
      PetscCall(PetscMalloc1(cap * nn, &grown_n));
      PetscCall(PetscMalloc1(cap, &grown_e));
      PetscCall(PetscArraycpy(grown_n, *fnodes, *nfaces * nn));
      PetscCall(PetscArraycpy(grown_e, *fentity, *nfaces));
      PetscCall(PetscFree(*fnodes));
      PetscCall(PetscFree(*fentity));
      *fnodes  = grown_n;
      *fentity = grown_e;
    }
    for (long i = 0; i < nin; ++i) {
      PetscCheck(fscanf(fp, "%ld", &t) == 1, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "%s: $Elements", file);
      for (PetscInt k = 0; k < nn; ++k) {
        PetscInt at;

        PetscCheck(fscanf(fp, "%ld", &node) == 1 && node >= tag0 && node < tag0 + ntag && index[node - tag0] >= 0, PETSC_COMM_SELF,
                   PETSC_ERR_FILE_READ, "%s: $Elements names node %ld, which $Nodes does not have", file, node);
        at       = index[node - tag0];
        used[at] = PETSC_TRUE;
        if (edim == fdim) (*fnodes)[*nfaces * nn + k] = at;
      }
      if (edim == fdim) (*fentity)[(*nfaces)++] = (PetscInt)etag;
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Rank 0's faces of the file: each face of dimension dim - 1 as its dim vertices in PETSc's numbering (0-based among
   the used nodes) and its face set (-1: none). */
static PetscErrorCode ReadFileFaces(const char file[], PetscInt dim, PetscInt *nfaces, PetscInt **fverts, PetscInt **fset)
{
  FILE      *fp;
  PetscInt   nentity, *etag, nnodes, tag0, ntag, *index, *vertex, *fentity, nv = 0;
  PetscBool *used;

  PetscFunctionBeginUser;
  fp = fopen(file, "r");
  PetscCheck(fp, PETSC_COMM_SELF, PETSC_ERR_FILE_OPEN, "Cannot open the remeshed mesh %s", file);
  PetscCall(ReadEntityTags(fp, file, dim - 1, &nentity, &etag));
  PetscCall(ReadNodeOrder(fp, file, &nnodes, &tag0, &ntag, &index));
  PetscCall(PetscCalloc2(nnodes + 1, &used, nnodes + 1, &vertex));
  PetscCall(ReadElements(fp, file, dim - 1, tag0, ntag, index, used, nfaces, fverts, &fentity));
  (void)fclose(fp);
  for (PetscInt i = 0; i < nnodes; ++i) vertex[i] = used[i] ? nv++ : -1; /* PETSc's vertexMap */
  PetscCall(PetscMalloc1(*nfaces + 1, fset));
  for (PetscInt f = 0; f < *nfaces; ++f) {
    for (PetscInt k = 0; k < dim; ++k) (*fverts)[f * dim + k] = vertex[(*fverts)[f * dim + k]];
    (*fset)[f] = fentity[f] >= 0 && fentity[f] < nentity ? etag[fentity[f]] : -1;
  }
  PetscCall(PetscFree2(used, vertex));
  PetscCall(PetscFree(index));
  PetscCall(PetscFree(etag));
  PetscCall(PetscFree(fentity));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode MeshReadGmshRemeshed(MPI_Comm comm, const char file[], DM *dm)
{
  DM                 cv;
  PetscInt           dim, cStart, cEnd, vStart, vEnd, *cells, nfaces = 0, *fverts = NULL, *fset = NULL;
  Vec                coords;
  const PetscScalar *xc;
  PetscMPIInt        rank;
  DMLabel            face_sets;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCall(DMPlexCreateGmshFromFile(comm, file, PETSC_FALSE, &cv));
  PetscCall(DMGetDimension(cv, &dim));
  PetscCall(DMPlexGetHeightStratum(cv, 0, &cStart, &cEnd));
  PetscCall(DMPlexGetDepthStratum(cv, 0, &vStart, &vEnd));
  PetscCall(PetscMalloc1((cEnd - cStart) * (dim + 1) + 1, &cells));
  for (PetscInt c = cStart; c < cEnd; ++c) {
    const PetscInt *cone;
    PetscInt        n;

    PetscCall(DMPlexGetConeSize(cv, c, &n));
    PetscCheck(n == dim + 1, comm, PETSC_ERR_SUP, "%s: a cell of %" PetscInt_FMT " vertices (simplices only)", file, n);
    PetscCall(DMPlexGetCone(cv, c, &cone));
    for (PetscInt k = 0; k <= dim; ++k) cells[(c - cStart) * (dim + 1) + k] = cone[k] - vStart;
  }
  PetscCall(MeshCreateInterpolatedSimplices(comm, dim, cEnd - cStart, vEnd - vStart, cells, NULL, dm));
  PetscCall(PetscFree(cells));
  PetscCall(DMGetCoordinatesLocal(cv, &coords));
  PetscCall(VecGetArrayRead(coords, &xc));
  PetscCall(DMPlexBuildCoordinatesFromCellList(*dm, dim, (const PetscReal *)xc));
  PetscCall(VecRestoreArrayRead(coords, &xc));
  PetscCall(DMCopyLabels(cv, *dm, PETSC_COPY_VALUES, PETSC_FALSE, DM_COPY_LABELS_FAIL)); /* "Cell Sets": the cells keep their numbers */
  PetscCall(DMDestroy(&cv));
  PetscCall(DMCreateLabel(*dm, "Face Sets"));
  PetscCall(DMGetLabel(*dm, "Face Sets", &face_sets));
  if (rank == 0) PetscCall(ReadFileFaces(file, dim, &nfaces, &fverts, &fset));
  {
    PetscInt vbase;

    PetscCall(DMPlexGetDepthStratum(*dm, 0, &vbase, NULL));
    for (PetscInt f = 0; f < nfaces; ++f) {
      PetscInt        verts[3], njoin;
      const PetscInt *join = NULL;

      if (fset[f] < 0) continue;
      for (PetscInt k = 0; k < dim; ++k) verts[k] = vbase + fverts[f * dim + k];
      PetscCall(DMPlexGetFullJoin(*dm, dim, verts, &njoin, &join));
      PetscCheck(njoin == 1, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED,
                 "%s: no face of the mesh joins the vertices of boundary element %" PetscInt_FMT, file, f);
      PetscCall(DMLabelSetValue(face_sets, join[0], fset[f]));
      PetscCall(DMPlexRestoreJoin(*dm, dim, verts, &njoin, &join));
    }
  }
  PetscCall(PetscFree(fverts));
  PetscCall(PetscFree(fset));
  PetscFunctionReturn(PETSC_SUCCESS);
}
