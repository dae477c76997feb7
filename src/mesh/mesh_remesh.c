/* Remeshing a Gmsh model with a size field (-adapt_model, src/solver/adapt.c): the adaptive cycles' refinement where
   the mesh's own cannot serve. PETSc 3.18 as Debian builds it refines triangles locally (skeleton-based refinement,
   mesh_refine.c) but not tetrahedra, and any refinement of a mesh file splits its curved boundary's edges on their
   chords, so that the body it solves stays the first mesh's polygon. Gmsh meshes the model itself, its curved
   boundary exact, with a size given at every point: here the size each cell of the current mesh asks for, as a
   list-based view of constant values on the cells, used as the background mesh (Gmsh's "PostView" field). The model's
   physical groups, which the run's boundary conditions name, are those of the new mesh.
   Gmsh runs on rank 0 on the gathered cells; the mesh it writes is read by all ranks and distributed as a mesh file
   is (METIS), so that every partition of the run meshes the same model with the same sizes. */
#include <gmshc.h>
#include <unistd.h>
#include "mesh.h"

/* A Gmsh call's error as a PETSc error, with Gmsh's last message. */
#define GmshCall(call, what) \
  do { \
    int ierr_gmsh = 0; \
    call; \
    if (ierr_gmsh) { \
      char *msg = NULL; \
      int   e2  = 0; \
      gmshLoggerGetLastError(&msg, &e2); \
      SETERRQ(PETSC_COMM_SELF, PETSC_ERR_LIB, "Gmsh failed to %s: %s", what, msg && msg[0] ? msg : "(no message)"); \
    } \
  } while (0)

/* Rank 0's part: the model opened, the cells' sizes as its background mesh, the mesh generated and written. data:
   ncells cells of nv vertices, each as Gmsh's list data (x of the vertices, then y, then z, then the size at each). */
static PetscErrorCode GmshRemesh(const char model[], PetscInt dim, PetscInt ncells, PetscInt nv, double data[], const char out[])
{
  int view, field;

  PetscFunctionBeginUser;
  GmshCall(gmshInitialize(0, NULL, 0, &ierr_gmsh), "start");
  GmshCall(gmshOptionSetNumber("General.Terminal", 0, &ierr_gmsh), "set General.Terminal");
  GmshCall(gmshOptionSetNumber("General.NumThreads", 1, &ierr_gmsh), "set General.NumThreads");
  GmshCall(gmshOpen(model, &ierr_gmsh), "open the model (-adapt_model)");
  /* the size is the background mesh's alone: not the model's points', not extended from the boundary, not the
     curvature's */
  GmshCall(gmshOptionSetNumber("Mesh.MeshSizeExtendFromBoundary", 0, &ierr_gmsh), "set Mesh.MeshSizeExtendFromBoundary");
  GmshCall(gmshOptionSetNumber("Mesh.MeshSizeFromPoints", 0, &ierr_gmsh), "set Mesh.MeshSizeFromPoints");
  GmshCall(gmshOptionSetNumber("Mesh.MeshSizeFromCurvature", 0, &ierr_gmsh), "set Mesh.MeshSizeFromCurvature");
  GmshCall(gmshOptionSetNumber("Mesh.MshFileVersion", 4.1, &ierr_gmsh), "set Mesh.MshFileVersion");
  GmshCall(view = gmshViewAdd("size", -1, &ierr_gmsh), "add the size view");
  GmshCall(gmshViewAddListData(view, dim == 2 ? "ST" : "SS", (int)ncells, data, (size_t)(ncells * nv * 4), &ierr_gmsh), "fill the size view");
  GmshCall(field = gmshModelMeshFieldAdd("PostView", -1, &ierr_gmsh), "add the size field");
  GmshCall(gmshModelMeshFieldSetNumber(field, "ViewTag", view, &ierr_gmsh), "set the size field's view");
  GmshCall(gmshModelMeshFieldSetAsBackgroundMesh(field, &ierr_gmsh), "set the background mesh");
  GmshCall(gmshModelMeshGenerate((int)dim, &ierr_gmsh), "mesh the model");
  GmshCall(gmshWrite(out, &ierr_gmsh), "write the mesh");
  GmshCall(gmshFinalize(&ierr_gmsh), "finish");
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode MeshRemesh(DM dm, const char model[], const PetscReal size[], DM *remeshed)
{
  MPI_Comm     comm = PetscObjectComm((PetscObject)dm);
  PetscMPIInt  rank, nranks;
  PetscInt     dim, cStart, cEnd, nv, per;
  double      *mine, *all = NULL;
  PetscMPIInt  count, *counts = NULL, *displs = NULL;
  PetscInt     total = 0;
  char         out[PETSC_MAX_PATH_LEN] = "", why[512] = "";
  int          failed = 0;
  PetscSection csec;
  Vec          coords;
  const PetscScalar *xc;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCallMPI(MPI_Comm_size(comm, &nranks));
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  nv  = dim + 1;
  per = 4 * nv; /* x, y, z of each vertex, then its value */
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
      d[3 * nv + k] = size[c - cStart];
    }
  }
  PetscCall(VecRestoreArrayRead(coords, &xc));
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
    char tmp[PETSC_MAX_PATH_LEN];

    PetscCall(PetscGetTmp(PETSC_COMM_SELF, tmp, sizeof(tmp)));
    PetscCall(PetscSNPrintf(out, sizeof(out), "%s/signorini-remesh-%d.msh", tmp, (int)getpid()));
    PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
    failed = GmshRemesh(model, dim, total / per, nv, all, out);
    PetscCall(PetscPopErrorHandler());
    if (failed) {
      const char *text     = NULL;
      char       *specific = NULL;
      int         ierr_gmsh;

      gmshFinalize(&ierr_gmsh); /* whatever state Gmsh was left in */
      PetscCall(PetscErrorMessage(failed, &text, &specific));
      PetscCall(PetscStrncpy(why, specific && specific[0] ? specific : text, sizeof(why)));
    }
    PetscCall(PetscFree(all));
    PetscCall(PetscFree2(counts, displs));
  }
  PetscCallMPI(MPI_Bcast(&failed, 1, MPI_INT, 0, comm));
  PetscCallMPI(MPI_Bcast(why, sizeof(why), MPI_CHAR, 0, comm));
  PetscCheck(!failed, comm, PETSC_ERR_LIB, "-adapt_model %s: %s", model, why);
  PetscCallMPI(MPI_Bcast(out, sizeof(out), MPI_CHAR, 0, comm));
  PetscCall(MeshReadRemeshed(comm, out, remeshed));
  PetscCallMPI(MPI_Barrier(comm));
  if (rank == 0) (void)unlink(out);
  {
    MatType mtype;

    PetscCall(DMGetMatType(dm, &mtype));
    PetscCall(DMSetMatType(*remeshed, mtype));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}
