/* Remeshing a Gmsh model with a size field (-adapt_model, src/drivers/adapt.c): the adaptive cycles' refinement where
   the mesh's own cannot serve. PETSc 3.18 as Debian builds it refines triangles locally (skeleton-based refinement,
   mesh_refine.c) but not tetrahedra, and any refinement of a mesh file splits its curved boundary's edges on their
   chords, so that the body it solves stays the first mesh's polygon. Gmsh meshes the model itself, its curved
   boundary exact, with a size given at every point: here the size each cell of the current mesh asks for, as a
   list-based view on the cells, used as the background mesh (Gmsh's "PostView" field). The model's physical groups,
   which the run's boundary conditions name, are those of the new mesh.
   The view's values, and Gmsh's options:
   - 2D: each cell's own size, constant on it: the marked cells' halves, exactly where marked;
   - 3D: the smallest size of the vertex's cells at each vertex, which spreads a mark to the cells around it (with the
     cells' own sizes, one or two marked cells around a contact the mesh does not see refine nothing);
   - 2D without Gmsh's Laplace smoothing (Mesh.Smoothing 0) and with its Delaunay algorithm (Mesh.Algorithm 5), the
     faster for the same bars; 3D keeps Gmsh's defaults.
   What each was measured against: docs/decisions.md, "The remeshing's size view".
   Gmsh runs on rank 0 on the gathered cells, sorted by their centroids so that the view is the same on any number of
   ranks (Gmsh's search of a point's cell depends on their order where the values jump); the mesh it makes is taken
   from its API on rank 0, built as PETSc's reader builds the file Gmsh would write (mesh_gmsh_build.c), and
   distributed as a mesh file is (METIS).
   Without a model, the box of the options (-dm_plex_box_*) is the model: a 3D box adapts so. */
#include <petscsf.h>
#include <stdlib.h>
#include <unistd.h>
#include "mesh_gmsh.h"

/* The 3D box of the options as a Gmsh model (a 2D box is refined by PETSc, AdaptSolve()): an OpenCASCADE box, its
   sides' physical groups numbered as PETSc numbers them (MeshBoxFaceId(), found by their bounding boxes), the body 10. */
static PetscErrorCode GmshBoxModel(const MeshBox *box)
{
  const PetscInt dim = box->dim;
  const double  *lo = box->lower, *hi = box->upper;
  int           *dimtags = NULL, body;
  size_t         n       = 0;

  PetscFunctionBeginUser;
  GmshCall(gmsh_api.gmshModelAdd("box", &ierr_gmsh), "add the box model");
  PetscCheck(dim == 3, PETSC_COMM_SELF, PETSC_ERR_PLIB, "the box's Gmsh model is 3D");
  GmshCall(body = gmsh_api.gmshModelOccAddBox(lo[0], lo[1], lo[2], hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], -1, &ierr_gmsh), "add the box");
  GmshCall(gmsh_api.gmshModelOccSynchronize(&ierr_gmsh), "synchronize the box");
  GmshCall(gmsh_api.gmshModelGetEntities(&dimtags, &n, (int)dim - 1, &ierr_gmsh), "list the box's sides");
  for (size_t i = 0; i < n / 2; ++i) {
    double   bb[6];
    int      side = dimtags[2 * i + 1];
    PetscInt id   = -1;

    GmshCall(gmsh_api.gmshModelGetBoundingBox((int)dim - 1, side, &bb[0], &bb[1], &bb[2], &bb[3], &bb[4], &bb[5], &ierr_gmsh), "bound a side");
    for (PetscInt d = 0; d < dim; ++d) {
      const double tol = 1e-6 * (hi[d] - lo[d]) + 1e-6; /* OpenCASCADE pads its bounding boxes by about 1e-7 */

      if (bb[3 + d] - bb[d] > 2 * tol) continue; /* the side is flat across d */
      id = MeshBoxFaceId(dim, d, PetscAbsReal(bb[d] - lo[d]) < PetscAbsReal(bb[d] - hi[d]) ? 0 : 1);
    }
    PetscCheck(id > 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "a side of the Gmsh box is on no side of the box");
    GmshCall(gmsh_api.gmshModelAddPhysicalGroup((int)dim - 1, &side, 1, (int)id, &ierr_gmsh), "name a side");
  }
  gmsh_api.gmshFree(dimtags);
  GmshCall(gmsh_api.gmshModelAddPhysicalGroup((int)dim, &body, 1, 10, &ierr_gmsh), "name the body");
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Rank 0's part: the model opened (or the box built), the cells' sizes as its background mesh, the mesh generated, and
   taken from Gmsh's API (made) or, with out, written to that file. data: ncells cells of nv vertices, each as Gmsh's
   list data (x of the vertices, then y, then z, then the size at each). */
static PetscErrorCode GmshRemesh(const char model[], const MeshBox *box, PetscInt dim, PetscInt ncells, PetscInt nv, double data[], const char out[],
                                 MeshSimplices *made)
{
  int view, field;

  PetscFunctionBeginUser;
  PetscCall(MeshGmshLoad());
  GmshCall(gmsh_api.gmshInitialize(0, NULL, 0, &ierr_gmsh), "start");
  GmshCall(gmsh_api.gmshOptionSetNumber("General.Terminal", 0, &ierr_gmsh), "set General.Terminal");
  GmshCall(gmsh_api.gmshOptionSetNumber("General.NumThreads", 1, &ierr_gmsh), "set General.NumThreads");
  if (model[0])
    GmshCall(gmsh_api.gmshOpen(model, &ierr_gmsh), "open the model (-adapt_model)");
  else
    PetscCall(GmshBoxModel(box));
  /* the size is the background mesh's alone: not the model's points', not extended from the boundary, not the
     curvature's */
  GmshCall(gmsh_api.gmshOptionSetNumber("Mesh.MeshSizeExtendFromBoundary", 0, &ierr_gmsh), "set Mesh.MeshSizeExtendFromBoundary");
  GmshCall(gmsh_api.gmshOptionSetNumber("Mesh.MeshSizeFromPoints", 0, &ierr_gmsh), "set Mesh.MeshSizeFromPoints");
  GmshCall(gmsh_api.gmshOptionSetNumber("Mesh.MeshSizeFromCurvature", 0, &ierr_gmsh), "set Mesh.MeshSizeFromCurvature");
  GmshCall(gmsh_api.gmshOptionSetNumber("Mesh.MshFileVersion", 4.1, &ierr_gmsh), "set Mesh.MshFileVersion");
  /* 2D: Gmsh's Delaunay algorithm, no Laplace smoothing (see the head of the file) */
  if (dim == 2) {
    GmshCall(gmsh_api.gmshOptionSetNumber("Mesh.Algorithm", 5, &ierr_gmsh), "set Mesh.Algorithm");
    GmshCall(gmsh_api.gmshOptionSetNumber("Mesh.Smoothing", 0, &ierr_gmsh), "set Mesh.Smoothing");
  }
  GmshCall(view = gmsh_api.gmshViewAdd("size", -1, &ierr_gmsh), "add the size view");
  GmshCall(gmsh_api.gmshViewAddListData(view, dim == 2 ? "ST" : "SS", (int)ncells, data, (size_t)(ncells * nv * 4), &ierr_gmsh),
           "fill the size view");
  GmshCall(field = gmsh_api.gmshModelMeshFieldAdd("PostView", -1, &ierr_gmsh), "add the size field");
  GmshCall(gmsh_api.gmshModelMeshFieldSetNumber(field, "ViewTag", view, &ierr_gmsh), "set the size field's view");
  GmshCall(gmsh_api.gmshModelMeshFieldSetAsBackgroundMesh(field, &ierr_gmsh), "set the background mesh");
  GmshCall(gmsh_api.gmshModelMeshGenerate((int)dim, &ierr_gmsh), "mesh the model");
  if (out)
    GmshCall(gmsh_api.gmshWrite(out, &ierr_gmsh), "write the mesh");
  else
    PetscCall(MeshSimplicesFromGmsh(dim, made));
  GmshCall(gmsh_api.gmshFinalize(&ierr_gmsh), "finish");
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The size at each local vertex (indexed by point from the chart's start): the smallest its cells ask for, over all
   ranks (the point SF's MIN at the owner, then sent back). */
static PetscErrorCode VertexSizes(DM dm, const PetscReal size[], PetscReal **vsize)
{
  PetscInt   pStart, pEnd, cStart, cEnd, nroots;
  PetscSF    sf;
  PetscReal *v;

  PetscFunctionBeginUser;
  PetscCall(DMPlexGetChart(dm, &pStart, &pEnd));
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  PetscCall(PetscMalloc1(pEnd - pStart, &v));
  for (PetscInt p = pStart; p < pEnd; ++p) v[p - pStart] = PETSC_MAX_REAL;
  for (PetscInt c = cStart; c < cEnd; ++c) {
    PetscInt verts[8], n;

    PetscCall(MeshCellVertices(dm, c, verts, &n));
    for (PetscInt k = 0; k < n; ++k) v[verts[k] - pStart] = PetscMin(v[verts[k] - pStart], size[c - cStart]);
  }
  PetscCall(DMGetPointSF(dm, &sf));
  PetscCall(PetscSFGetGraph(sf, &nroots, NULL, NULL, NULL));
  if (nroots >= 0) {
    PetscCall(PetscSFReduceBegin(sf, MPIU_REAL, v, v, MPI_MIN));
    PetscCall(PetscSFReduceEnd(sf, MPIU_REAL, v, v, MPI_MIN));
    PetscCall(PetscSFBcastBegin(sf, MPIU_REAL, v, v, MPI_REPLACE));
    PetscCall(PetscSFBcastEnd(sf, MPIU_REAL, v, v, MPI_REPLACE));
  }
  *vsize = v;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The cells' list data in the order of their centroids (lexicographic in x, y, z): the same on any partition. C's
   qsort() passes no context to its comparison: the data it compares are these file-scope variables, set by
   SortCells() on rank 0 just before the sort. */
static PetscInt      sort_per, sort_nv;
static const double *sort_data;
static int           CompareCentroids(const void *a, const void *b)
{
  const double *da = &sort_data[*(const PetscInt *)a * sort_per], *db = &sort_data[*(const PetscInt *)b * sort_per];

  for (PetscInt j = 0; j < 3; ++j) {
    double ca = 0.0, cb = 0.0;

    for (PetscInt k = 0; k < sort_nv; ++k) {
      ca += da[j * sort_nv + k];
      cb += db[j * sort_nv + k];
    }
    if (ca != cb) return ca < cb ? -1 : 1;
  }
  return 0;
}

static PetscErrorCode SortCells(PetscInt ncells, PetscInt nv, double data[])
{
  PetscInt      *order;
  double        *copy;
  const PetscInt per = 4 * nv;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc2(ncells, &order, ncells * per, &copy));
  for (PetscInt i = 0; i < ncells; ++i) order[i] = i;
  PetscCall(PetscArraycpy(copy, data, ncells * per));
  sort_per  = per;
  sort_nv   = nv;
  sort_data = copy;
  qsort(order, (size_t)ncells, sizeof(PetscInt), CompareCentroids);
  for (PetscInt i = 0; i < ncells; ++i) PetscCall(PetscArraycpy(&data[i * per], &copy[order[i] * per], per));
  PetscCall(PetscFree2(order, copy));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The "Face Sets" values the faces of dm carry, over all ranks: present[v] for v < *n (free with PetscFree). */
PetscErrorCode MeshFaceSetValues(DM dm, PetscInt *n, PetscBool **present)
{
  DMLabel         label;
  IS              is = NULL;
  PetscInt        nv = 0, vmax = -1;
  const PetscInt *v = NULL;
  PetscInt       *flag;

  PetscFunctionBeginUser;
  PetscCall(DMGetLabel(dm, "Face Sets", &label));
  if (label) {
    PetscCall(DMLabelGetNonEmptyStratumValuesIS(label, &is));
    PetscCall(ISGetLocalSize(is, &nv));
    PetscCall(ISGetIndices(is, &v));
  }
  for (PetscInt i = 0; i < nv; ++i) vmax = PetscMax(vmax, v[i]);
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &vmax, 1, MPIU_INT, MPI_MAX, PetscObjectComm((PetscObject)dm)));
  *n = vmax + 1;
  PetscCall(PetscCalloc1(*n + 1, &flag));
  for (PetscInt i = 0; i < nv; ++i)
    if (v[i] >= 0) flag[v[i]] = 1;
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, flag, *n, MPIU_INT, MPI_MAX, PetscObjectComm((PetscObject)dm)));
  PetscCall(PetscMalloc1(*n + 1, present));
  for (PetscInt i = 0; i < *n; ++i) (*present)[i] = (PetscBool)(flag[i] != 0);
  PetscCall(PetscFree(flag));
  if (is) {
    PetscCall(ISRestoreIndices(is, &v));
    PetscCall(ISDestroy(&is));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Every face set of the old mesh on the new one: a model that is not the mesh's would lose the boundary conditions. */
static PetscErrorCode CheckFaceSets(DM dm, DM remeshed, const char model[])
{
  PetscInt   n_old, n_new;
  PetscBool *old_sets, *new_sets;

  PetscFunctionBeginUser;
  PetscCall(MeshFaceSetValues(dm, &n_old, &old_sets));
  PetscCall(MeshFaceSetValues(remeshed, &n_new, &new_sets));
  for (PetscInt i = 0; i < n_old; ++i)
    PetscCheck(!old_sets[i] || (i < n_new && new_sets[i]), PetscObjectComm((PetscObject)dm), PETSC_ERR_USER_INPUT,
               "-adapt_model %s: the mesh Gmsh made of the model has no face in the face set %" PetscInt_FMT
               " (\"Face Sets\" value, a physical group's number) that the mesh had: is it the model of the mesh?",
               model[0] ? model : "(the box of the options)", i);
  PetscCall(PetscFree(old_sets));
  PetscCall(PetscFree(new_sets));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode MeshRemesh(DM dm, const char model[], const MeshBox *box, const PetscReal size[], DM *remeshed)
{
  MPI_Comm           comm = PetscObjectComm((PetscObject)dm);
  PetscMPIInt        rank, nranks, count, *counts = NULL, *displs = NULL;
  PetscInt           dim, cStart, cEnd, pStart, nv, per, total = 0;
  PetscReal         *vsize = NULL;
  double            *mine, *all = NULL;
  char               out[PETSC_MAX_PATH_LEN] = "", why[512] = "", what[PETSC_MAX_PATH_LEN + 64];
  MeshSimplices      made;
  int                failed = 0;
  PetscSection       csec;
  Vec                coords;
  const PetscScalar *xc;

  PetscFunctionBeginUser;
  PetscCall(PetscMemzero(&made, sizeof(made)));
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCallMPI(MPI_Comm_size(comm, &nranks));
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  PetscCall(DMPlexGetChart(dm, &pStart, NULL));
  nv  = dim + 1;
  per = 4 * nv; /* x, y, z of each vertex, then its value */
  if (dim == 3) PetscCall(VertexSizes(dm, size, &vsize));
  PetscCall(DMGetCoordinateSection(dm, &csec));
  PetscCall(DMGetCoordinatesLocal(dm, &coords));
  PetscCall(VecGetArrayRead(coords, &xc));
  PetscCall(PetscCalloc1((cEnd - cStart) * per + 1, &mine));
  for (PetscInt c = cStart; c < cEnd; ++c) {
    double  *d = &mine[(c - cStart) * per];
    PetscInt verts[8], n;

    PetscCall(MeshCellVertices(dm, c, verts, &n));
    PetscCheck(n == nv, comm, PETSC_ERR_SUP, "-adapt_model remeshes simplices (triangles, tetrahedra) only");
    for (PetscInt k = 0; k < nv; ++k) {
      PetscInt off;

      PetscCall(PetscSectionGetOffset(csec, verts[k], &off));
      for (PetscInt j = 0; j < dim; ++j) d[j * nv + k] = PetscRealPart(xc[off + j]);
      d[3 * nv + k] = vsize ? vsize[verts[k] - pStart] : size[c - cStart];
    }
  }
  PetscCall(VecRestoreArrayRead(coords, &xc));
  PetscCall(PetscFree(vsize));
  PetscCall(PetscMPIIntCast((cEnd - cStart) * per, &count));
  if (rank == 0) PetscCall(PetscMalloc2(nranks, &counts, nranks, &displs));
  PetscCallMPI(MPI_Gather(&count, 1, MPI_INT, counts, 1, MPI_INT, 0, comm));
  if (rank == 0) {
    for (PetscMPIInt r = 0; r < nranks; ++r) {
      displs[r] = (PetscMPIInt)total;
      total += counts[r];
    }
    PetscCall(PetscMalloc1(total + 1, &all));
  }
  PetscCallMPI(MPI_Gatherv(mine, count, MPI_DOUBLE, all, counts, displs, MPI_DOUBLE, 0, comm));
  PetscCall(PetscFree(mine));
  if (rank == 0) {
    char     tmp[PETSC_MAX_PATH_LEN];
    PetscInt ncaps;
    double  *caps, *view;

    PetscCall(MeshRemeshViewCaps(total / per, nv, dim, all, &ncaps, &caps)); /* the view over the model's bulge too */
    PetscCall(PetscMalloc1(total + ncaps * per + 1, &view));
    PetscCall(PetscArraycpy(view, all, total));
    PetscCall(PetscArraycpy(view + total, caps, ncaps * per));
    PetscCall(PetscFree(caps));
    PetscCall(SortCells(total / per + ncaps, nv, view));
    if (box->petsc_read) { /* for comparison: Gmsh writes the mesh, PETSc's reader reads it */
      PetscCall(PetscGetTmp(PETSC_COMM_SELF, tmp, sizeof(tmp)));
      PetscCall(PetscSNPrintf(out, sizeof(out), "%s/signorini-remesh-%d.msh", tmp, (int)getpid()));
    }
    PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
    failed = GmshRemesh(model, box, dim, total / per + ncaps, nv, view, out[0] ? out : NULL, &made);
    PetscCall(PetscPopErrorHandler());
    if (failed) {
      const char *text     = NULL;
      char       *specific = NULL;
      int         ierr_gmsh;

      if (gmsh_api.gmshFinalize) gmsh_api.gmshFinalize(&ierr_gmsh); /* whatever state Gmsh was left in */
      PetscCall(PetscErrorMessage(failed, &text, &specific));
      PetscCall(PetscStrncpy(why, specific && specific[0] ? specific : text, sizeof(why)));
      if (out[0]) (void)unlink(out);
      PetscCall(MeshSimplicesReset(&made));
    }
    PetscCall(PetscFree(all));
    PetscCall(PetscFree(view));
    PetscCall(PetscFree2(counts, displs));
  }
  PetscCallMPI(MPI_Bcast(&failed, 1, MPI_INT, 0, comm));
  PetscCallMPI(MPI_Bcast(why, sizeof(why), MPI_CHAR, 0, comm));
  PetscCheck(!failed, comm, PETSC_ERR_LIB, "-adapt_model %s: %s", model[0] ? model : "(the box of the options)", why);
  PetscCall(PetscSNPrintf(what, sizeof(what), "the mesh Gmsh made of -adapt_model %s", model[0] ? model : "(the box of the options)"));
  if (box->petsc_read) {
    PetscCallMPI(MPI_Bcast(out, sizeof(out), MPI_CHAR, 0, comm));
    PetscCall(MeshReadRemeshedFile(comm, out, remeshed));
    PetscCallMPI(MPI_Barrier(comm));
    if (rank == 0) (void)unlink(out); /* read: removed before the checks, which may refuse the mesh */
  } else {
    PetscCall(MeshSimplicesBuild(comm, &made, remeshed));
    PetscCall(MeshSimplicesReset(&made));
  }
  PetscCall(MeshDistributeRemeshed(what, remeshed));
  PetscCall(CheckFaceSets(dm, *remeshed, model));
  {
    MatType mtype;

    PetscCall(DMGetMatType(dm, &mtype));
    PetscCall(DMSetMatType(*remeshed, mtype));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}
