/* The Gmsh model of -adapt_model checked against the mesh before the first solve (MeshRemeshCheckModel()): the
   cycles mesh the model again at each cycle (mesh_remesh.c), so that from the first remesh on the run solves the
   model's body, not the mesh's. A model of another body, or a mesh file in its place, is refused here, naming what
   differs; CheckFaceSets() in mesh_remesh.c checks each remeshed mesh's face sets again. */
#include <petscsf.h>
#include "mesh_gmsh.h"

#define MESH_MODEL_BOX_TOL 0.05 /* the mesh's bounding box within this fraction of the model's extent */
#define MESH_MODEL_ON_TOL 0.1   /* a boundary vertex within this fraction of its face's longest edge of the model */
#define MESH_MODEL_PER 5        /* x, y, z, the face set (-1: none) and the tolerance of a boundary face's vertex */

/* The vertices of dm's boundary faces, each face's vertices with the face's "Face Sets" value and the tolerance
   MESH_MODEL_ON_TOL times its longest edge, gathered on rank 0 (*n of them there, 0 elsewhere; free *data). A vertex
   Gmsh made of the model lies on it; a vertex put on a chord of a curved boundary by a refinement (-dm_refine) lies
   h^2 / 8R inside it, within the tolerance where h < 0.8 R. */
static PetscErrorCode BoundaryVertices(DM dm, PetscInt *n, double **data)
{
  MPI_Comm           comm = PetscObjectComm((PetscObject)dm);
  DMLabel            sets;
  PetscSF            sf;
  const PetscInt    *leaves, *degree = NULL;
  PetscInt           nroots, nleaves, pStart, pEnd, fStart, fEnd, dim, count = 0;
  PetscBool         *shared;
  PetscSection       csec;
  Vec                coords;
  const PetscScalar *x;
  double            *mine;
  PetscMPIInt        rank, nranks, nloc, *counts = NULL, *displs = NULL;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCallMPI(MPI_Comm_size(comm, &nranks));
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMGetLabel(dm, "Face Sets", &sets));
  /* a face with one cell is on the body's boundary unless another rank holds it too (a leaf of the point SF, or a
     root that has leaves): DMPlexMarkBoundaryFaces() of PETSc 3.18 marks the roots' side of the ranks' interface */
  PetscCall(DMPlexGetChart(dm, &pStart, &pEnd));
  PetscCall(DMPlexGetHeightStratum(dm, 1, &fStart, &fEnd));
  PetscCall(PetscCalloc1(pEnd - pStart + 1, &shared));
  PetscCall(DMGetPointSF(dm, &sf));
  PetscCall(PetscSFGetGraph(sf, &nroots, &nleaves, &leaves, NULL));
  if (nroots >= 0) {
    PetscCall(PetscSFComputeDegreeBegin(sf, &degree));
    PetscCall(PetscSFComputeDegreeEnd(sf, &degree));
    for (PetscInt i = 0; i < nleaves; ++i) shared[(leaves ? leaves[i] : i) - pStart] = PETSC_TRUE;
    for (PetscInt p = pStart; p < pEnd && p - pStart < nroots; ++p)
      if (degree[p - pStart] > 0) shared[p - pStart] = PETSC_TRUE;
  }
  PetscCall(DMGetCoordinateSection(dm, &csec));
  PetscCall(DMGetCoordinatesLocal(dm, &coords));
  PetscCall(VecGetArrayRead(coords, &x));
  PetscCall(PetscCalloc1((fEnd - fStart) * dim * MESH_MODEL_PER + 1, &mine));
  for (PetscInt f = fStart; f < fEnd; ++f) {
    PetscInt verts[8], nv, value = -1, support;
    double   p[3][3] = {{0.0}}, longest = 0.0;

    PetscCall(DMPlexGetSupportSize(dm, f, &support));
    if (support != 1 || shared[f - pStart]) continue;
    PetscCall(MeshCellVertices(dm, f, verts, &nv));
    if (sets) PetscCall(DMLabelGetValue(sets, f, &value));
    for (PetscInt k = 0; k < nv && k < 3; ++k) {
      PetscInt off;

      PetscCall(PetscSectionGetOffset(csec, verts[k], &off));
      for (PetscInt d = 0; d < dim; ++d) p[k][d] = PetscRealPart(x[off + d]);
    }
    for (PetscInt a = 0; a < nv && a < 3; ++a)
      for (PetscInt b = a + 1; b < nv && b < 3; ++b)
        longest = PetscMax(longest, PetscSqrtReal(PetscSqr(p[a][0] - p[b][0]) + PetscSqr(p[a][1] - p[b][1]) + PetscSqr(p[a][2] - p[b][2])));
    for (PetscInt k = 0; k < nv && k < 3; ++k) {
      double *row = &mine[count++ * MESH_MODEL_PER];

      for (PetscInt d = 0; d < 3; ++d) row[d] = p[k][d];
      row[3] = (double)value;
      row[4] = MESH_MODEL_ON_TOL * longest;
    }
  }
  PetscCall(VecRestoreArrayRead(coords, &x));
  PetscCall(PetscFree(shared));
  PetscCall(PetscMPIIntCast(count * MESH_MODEL_PER, &nloc));
  if (rank == 0) PetscCall(PetscMalloc2(nranks, &counts, nranks, &displs));
  PetscCallMPI(MPI_Gather(&nloc, 1, MPI_INT, counts, 1, MPI_INT, 0, comm));
  *n    = 0;
  *data = NULL;
  if (rank == 0) {
    PetscInt total = 0;

    for (PetscMPIInt r = 0; r < nranks; ++r) {
      displs[r] = (PetscMPIInt)total;
      total += counts[r];
    }
    *n = total / MESH_MODEL_PER;
    PetscCall(PetscMalloc1(total + 1, data));
  }
  PetscCallMPI(MPI_Gatherv(mine, nloc, MPI_DOUBLE, rank == 0 ? *data : NULL, counts, displs, MPI_DOUBLE, 0, comm));
  PetscCall(PetscFree(mine));
  if (rank == 0) PetscCall(PetscFree2(counts, displs));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* dist[which[j]] <- the smaller of it and the distance of the point j of pts (m points, x, y, z each) to the model's
   entity (edim, tag), by Gmsh's closest point on it. */
static PetscErrorCode CloserTo(int edim, int tag, PetscInt m, double pts[], const PetscInt which[], double dist[])
{
  double *closest = NULL, *param = NULL;
  size_t  nc = 0, np = 0;

  PetscFunctionBeginUser;
  GmshCall(gmsh_api.gmshModelGetClosestPoint(edim, tag, pts, (size_t)(3 * m), &closest, &nc, &param, &np, &ierr_gmsh),
           "find the model's closest points");
  for (PetscInt j = 0; j < m && 3 * (size_t)j + 2 < nc; ++j) {
    const double r = PetscSqrtReal(PetscSqr(closest[3 * j] - pts[3 * j]) + PetscSqr(closest[3 * j + 1] - pts[3 * j + 1]) +
                                   PetscSqr(closest[3 * j + 2] - pts[3 * j + 2]));

    dist[which[j]] = PetscMin(dist[which[j]], r);
  }
  if (closest) gmsh_api.gmshFree(closest);
  if (param) gmsh_api.gmshFree(param);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Rank 0, with the model open: whether each boundary vertex (BoundaryVertices()) lies on the model, on the entities
   of the physical group its face carries (on any boundary entity of the model for a face without one), within its
   tolerance. Gmsh gives the closest point of each entity (OpenCASCADE projects onto a planar face's whole plane, so
   that in 3D a vertex is checked against the planes of its group's faces, not their trimmed parts; the bounding box
   bounds the rest). why[] names the vertex farthest off relative to its tolerance ("" if none is off). */
static PetscErrorCode GmshCheckBoundaryOnModel(PetscInt dim, PetscInt n, const double data[], char why[], size_t len)
{
  int      *all  = NULL;
  size_t    nall = 0;
  double   *dist, *pts, worst = 1.0;
  PetscInt *which, nsets = 0, iworst = -1;

  PetscFunctionBeginUser;
  if (!n) PetscFunctionReturn(PETSC_SUCCESS);
  GmshCall(gmsh_api.gmshModelGetEntities(&all, &nall, (int)dim - 1, &ierr_gmsh), "list the model's boundary entities");
  PetscCall(PetscMalloc3(n, &dist, 3 * n, &pts, n, &which));
  for (PetscInt i = 0; i < n; ++i) {
    dist[i] = PETSC_MAX_REAL;
    nsets   = PetscMax(nsets, (PetscInt)data[i * MESH_MODEL_PER + 3] + 1);
  }
  for (PetscInt v = -1; v < nsets; ++v) { /* the vertices of face set v, against its group's entities (v = -1: all) */
    int     *tags  = NULL;
    size_t   ntags = 0;
    PetscInt m     = 0;

    for (PetscInt i = 0; i < n; ++i)
      if ((PetscInt)data[i * MESH_MODEL_PER + 3] == v) {
        for (PetscInt d = 0; d < 3; ++d) pts[3 * m + d] = data[i * MESH_MODEL_PER + d];
        which[m++] = i;
      }
    if (!m) continue;
    if (v >= 0)
      GmshCall(gmsh_api.gmshModelGetEntitiesForPhysicalGroup((int)dim - 1, (int)v, &tags, &ntags, &ierr_gmsh), "list a physical group's entities");
    for (size_t e = 0; e < (v >= 0 ? ntags : nall / 2); ++e)
      PetscCall(CloserTo((int)dim - 1, v >= 0 ? tags[e] : all[2 * e + 1], m, pts, which, dist));
    if (tags) gmsh_api.gmshFree(tags);
  }
  /* a vertex where the group's entity ends (the end of an arc, a face's edge in 3D): Gmsh's closest point of the
     entity may miss that end (the half disk's 180-degree arc from its end gave its other end), so such a vertex is
     taken against the model's points, by their bounding boxes' centres, and in 3D its curves too */
  for (int d = 0; d < (int)dim - 1; ++d) {
    int     *low  = NULL;
    size_t   nlow = 0;
    PetscInt m    = 0;

    for (PetscInt i = 0; i < n; ++i)
      if (dist[i] > data[i * MESH_MODEL_PER + 4]) {
        for (PetscInt k = 0; k < 3; ++k) pts[3 * m + k] = data[i * MESH_MODEL_PER + k];
        which[m++] = i;
      }
    if (!m) break;
    GmshCall(gmsh_api.gmshModelGetEntities(&low, &nlow, d, &ierr_gmsh), "list the model's points and curves");
    for (size_t e = 0; e < nlow / 2; ++e) {
      double bb[6];

      if (d == 0) {
        GmshCall(gmsh_api.gmshModelGetBoundingBox(0, low[2 * e + 1], &bb[0], &bb[1], &bb[2], &bb[3], &bb[4], &bb[5], &ierr_gmsh),
                 "locate a model point");
        for (PetscInt j = 0; j < m; ++j) {
          const double r = PetscSqrtReal(PetscSqr(0.5 * (bb[0] + bb[3]) - pts[3 * j]) + PetscSqr(0.5 * (bb[1] + bb[4]) - pts[3 * j + 1]) +
                                         PetscSqr(0.5 * (bb[2] + bb[5]) - pts[3 * j + 2]));

          dist[which[j]] = PetscMin(dist[which[j]], r);
        }
        continue;
      }
      PetscCall(CloserTo(d, low[2 * e + 1], m, pts, which, dist));
    }
    if (low) gmsh_api.gmshFree(low);
  }
  for (PetscInt i = 0; i < n; ++i) {
    const double tol = data[i * MESH_MODEL_PER + 4], off = dist[i] / PetscMax(tol, 1e-300);

    if (dist[i] > tol && off > worst) {
      worst  = off;
      iworst = i;
    }
  }
  if (iworst >= 0) {
    const double *row = &data[iworst * MESH_MODEL_PER];
    char          at[128];

    if (dim == 2)
      PetscCall(PetscSNPrintf(at, sizeof(at), "(%g, %g)", row[0], row[1]));
    else
      PetscCall(PetscSNPrintf(at, sizeof(at), "(%g, %g, %g)", row[0], row[1], row[2]));
    if (row[3] >= 0)
      PetscCall(PetscSNPrintf(why, len,
                              "the mesh's boundary vertex %s, of face set %d, lies %g from the model's physical group %d (more than a tenth of its "
                              "face's longest edge, %g)",
                              at, (int)row[3], dist[iworst], (int)row[3], 10.0 * row[4]));
    else
      PetscCall(PetscSNPrintf(why, len,
                              "the mesh's boundary vertex %s lies %g from the model's boundary (more than a tenth of its face's longest edge, %g)",
                              at, dist[iworst], 10.0 * row[4]));
  }
  PetscCall(PetscFree3(dist, pts, which));
  if (all) gmsh_api.gmshFree(all);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Rank 0's part of MeshRemeshCheckModel(): the model opened, its dimension, its bounding box, which of the face sets
   in need (need[v] for v < n) are no physical group of its faces, and whether the nb boundary vertices lie on it;
   why[] says what is wrong ("" if nothing). */
static PetscErrorCode GmshCheckModel(const char model[], PetscInt dim, const PetscReal lo[], const PetscReal hi[], PetscInt n, const PetscBool need[],
                                     PetscInt nb, const double boundary[], char why[], size_t len)
{
  int   *dimtags = NULL, mdim;
  size_t ntags   = 0;
  double bb[6];

  PetscFunctionBeginUser;
  why[0] = '\0';
  PetscCall(MeshGmshLoad());
  GmshCall(gmsh_api.gmshInitialize(0, NULL, 0, &ierr_gmsh), "start");
  GmshCall(gmsh_api.gmshOptionSetNumber("General.Terminal", 0, &ierr_gmsh), "set General.Terminal");
  GmshCall(gmsh_api.gmshOpen(model, &ierr_gmsh), "read the model");
  GmshCall(mdim = gmsh_api.gmshModelGetDimension(&ierr_gmsh), "get the model's dimension");
  if (mdim != (int)dim) {
    PetscCall(PetscSNPrintf(why, len, "the model is %dD and the mesh %" PetscInt_FMT "D", mdim, dim));
    GmshCall(gmsh_api.gmshFinalize(&ierr_gmsh), "finish");
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  GmshCall(gmsh_api.gmshModelGetBoundingBox(-1, -1, &bb[0], &bb[1], &bb[2], &bb[3], &bb[4], &bb[5], &ierr_gmsh), "bound the model");
  for (PetscInt d = 0; d < dim && !why[0]; ++d) {
    const PetscReal extent = PetscMax(hi[d] - lo[d], bb[3 + d] - bb[d]), tol = MESH_MODEL_BOX_TOL * extent + 1e-6;

    if (PetscAbsReal(bb[d] - lo[d]) > tol || PetscAbsReal(bb[3 + d] - hi[d]) > tol)
      PetscCall(
          PetscSNPrintf(why, len, "the model spans [%g, %g] along %c, the mesh [%g, %g]", bb[d], bb[3 + d], "xyz"[d], (double)lo[d], (double)hi[d]));
  }
  GmshCall(gmsh_api.gmshModelGetPhysicalGroups(&dimtags, &ntags, (int)dim - 1, &ierr_gmsh), "list the model's physical groups");
  for (PetscInt v = 0; v < n && !why[0]; ++v) {
    PetscBool found = PETSC_FALSE;

    if (!need[v]) continue;
    for (size_t i = 0; i < ntags / 2 && !found; ++i) found = (PetscBool)(dimtags[2 * i + 1] == (int)v);
    if (!found)
      PetscCall(PetscSNPrintf(why, len, "the model has no physical group of %s numbered %" PetscInt_FMT ", the mesh's face set %" PetscInt_FMT,
                              dim == 2 ? "curves" : "surfaces", v, v));
  }
  if (dimtags) gmsh_api.gmshFree(dimtags);
  if (!why[0]) PetscCall(GmshCheckBoundaryOnModel(dim, nb, boundary, why, len));
  GmshCall(gmsh_api.gmshFinalize(&ierr_gmsh), "finish");
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Refuses, before any solve, a model the cycles could not remesh as the mesh's body: a mesh file given in its place
   (a .msh opens in Gmsh as a discrete model, which remeshing cannot refine), a model Gmsh cannot read, one of another
   dimension, one whose bounding box is not the mesh's (another body), and one without a physical group for each face
   set of the mesh (CheckFaceSets() checks the remeshed mesh again), and one on which the mesh's boundary does not lie
   (GmshCheckBoundaryOnModel()). The box's tolerance is MESH_MODEL_BOX_TOL of its extent: a curved boundary's mesh lies
   inside its model by about h^2 / 8R. */
PetscErrorCode MeshRemeshCheckModel(DM dm, const char model[])
{
  MPI_Comm    comm = PetscObjectComm((PetscObject)dm);
  PetscMPIInt rank;
  PetscInt    dim, n;
  PetscBool  *need, msh;
  PetscInt    nb       = 0;
  double     *boundary = NULL;
  PetscReal   lo[3] = {PETSC_MAX_REAL, PETSC_MAX_REAL, PETSC_MAX_REAL}, hi[3] = {PETSC_MIN_REAL, PETSC_MIN_REAL, PETSC_MIN_REAL};
  char        why[1024] = "";
  int         failed    = 0;

  PetscFunctionBeginUser;
  if (!model[0]) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscStrendswith(model, ".msh", &msh));
  PetscCheck(!msh, comm, PETSC_ERR_USER_INPUT,
             "-adapt_model %s is a mesh file, not a model: Gmsh cannot remesh a mesh finer; give the body's model (.geo; scripts/make_mesh.py "
             "--model FILE.geo writes the model of its meshes)",
             model);
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCall(DMGetDimension(dm, &dim));
  {
    Vec                coords;
    const PetscScalar *x;
    PetscInt           nloc, cdim;

    PetscCall(DMGetCoordinateDim(dm, &cdim));
    PetscCall(DMGetCoordinatesLocal(dm, &coords));
    PetscCall(VecGetLocalSize(coords, &nloc));
    PetscCall(VecGetArrayRead(coords, &x));
    for (PetscInt i = 0; i < nloc / cdim; ++i)
      for (PetscInt d = 0; d < cdim; ++d) {
        lo[d] = PetscMin(lo[d], PetscRealPart(x[i * cdim + d]));
        hi[d] = PetscMax(hi[d], PetscRealPart(x[i * cdim + d]));
      }
    PetscCall(VecRestoreArrayRead(coords, &x));
    PetscCall(MPIU_Allreduce(MPI_IN_PLACE, lo, 3, MPIU_REAL, MPIU_MIN, comm));
    PetscCall(MPIU_Allreduce(MPI_IN_PLACE, hi, 3, MPIU_REAL, MPIU_MAX, comm));
  }
  PetscCall(MeshFaceSetValues(dm, &n, &need));
  PetscCall(BoundaryVertices(dm, &nb, &boundary));
  if (rank == 0) {
    PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
    failed = GmshCheckModel(model, dim, lo, hi, n, need, nb, boundary, why, sizeof(why));
    PetscCall(PetscPopErrorHandler());
    if (failed) {
      const char *text     = NULL;
      char       *specific = NULL;
      int         ierr_gmsh;

      if (gmsh_api.gmshFinalize) gmsh_api.gmshFinalize(&ierr_gmsh);
      PetscCall(PetscErrorMessage(failed, &text, &specific));
      PetscCall(PetscStrncpy(why, specific && specific[0] ? specific : text, sizeof(why)));
    }
  }
  PetscCall(PetscFree(need));
  PetscCall(PetscFree(boundary));
  PetscCallMPI(MPI_Bcast(why, sizeof(why), MPI_CHAR, 0, comm));
  PetscCheck(!why[0], comm, PETSC_ERR_USER_INPUT, "-adapt_model %s: %s: is it the model of the mesh?", model, why);
  PetscFunctionReturn(PETSC_SUCCESS);
}
