/* The last solution carried to a remeshed mesh (mesh_remesh.c): the next solve's start, as nested iteration's
   interpolation is for a refined mesh. The meshes do not nest, so each new vertex is located in the old mesh and the
   old P1 field evaluated there, u(x) = sum_k lambda_k(x) u_k with the barycentric coordinates lambda of the old cell
   holding x. A new vertex on a curved boundary may lie just outside the old mesh (the old boundary is the chords of the
   new one's curve, a sagitta h^2 / 8R away): it takes the linear extension of the nearest old cell's field (the cell
   whose smallest barycentric coordinate is the largest).
   The old cells, their vertices and values, are on rank 0 (gathered for Gmsh anyway); each rank sends its new vertices'
   positions there and gets the values back; rank 0 finds the old cells with a MeshLocator (mesh_locate.c). */
#include "mesh.h"

struct _n_MeshTransfer {
  MPI_Comm    comm;
  PetscInt    dim, nv; /* rank 0: the old cells, nv vertices each */
  PetscReal  *x;       /*   [cells][nv][dim] their vertices */
  PetscReal  *u;       /*   [cells][nv][dim] the field at them */
  MeshLocator locator; /*   finds the old cell of a new vertex (mesh_locate.c) */
};

/* The field at x (rank 0): the old field of the cell that holds x best, or outside the old mesh of the cell x is nearest
   to leaving, whose linear field extends to x (MeshLocatorFind()). */
static void Evaluate(const MeshTransfer tr, const PetscReal x[], PetscReal u[])
{
  const PetscInt dim = tr->dim;
  PetscInt       best;
  PetscReal      lambda[4];

  MeshLocatorFind(tr->locator, x, &best, lambda);
  for (PetscInt d = 0; d < dim; ++d) u[d] = 0.0;
  if (best < 0) return; /* no old cell: the start is zero there */
  for (PetscInt v = 0; v <= dim; ++v)
    for (PetscInt d = 0; d < dim; ++d) u[d] += lambda[v] * tr->u[(best * tr->nv + v) * dim + d];
}

PetscErrorCode MeshTransferCreate(MPI_Comm comm, PetscInt dim, PetscInt ncells, PetscReal x[], PetscReal u[], MeshTransfer *tr)
{
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  PetscCall(PetscNew(tr));
  (*tr)->comm = comm;
  (*tr)->dim  = dim;
  (*tr)->nv   = dim + 1;
  (*tr)->x    = x;
  (*tr)->u    = u;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  if (rank == 0) PetscCall(MeshLocatorCreate(dim, ncells, x, &(*tr)->locator));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Each rank's n reals of mine gathered on rank 0 in the ranks' order: *all, *total of them, and the counts and
   displacements that scatter values in that order back (rank 0; free with PetscFree() and PetscFree2()). */
static PetscErrorCode GatherOnRoot(MPI_Comm comm, PetscInt n, const PetscReal mine[], PetscReal **all, PetscInt *total, PetscMPIInt **counts,
                                   PetscMPIInt **displs)
{
  PetscMPIInt rank, nranks, count;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCallMPI(MPI_Comm_size(comm, &nranks));
  PetscCall(PetscMPIIntCast(n, &count));
  *all    = NULL;
  *total  = 0;
  *counts = *displs = NULL;
  if (rank == 0) PetscCall(PetscMalloc2(nranks, counts, nranks, displs));
  PetscCallMPI(MPI_Gather(&count, 1, MPI_INT, *counts, 1, MPI_INT, 0, comm));
  if (rank == 0) {
    for (PetscMPIInt r = 0; r < nranks; ++r) {
      (*displs)[r] = (PetscMPIInt)*total;
      *total += (*counts)[r];
    }
    PetscCall(PetscMalloc1(*total + 1, all));
  }
  PetscCallMPI(MPI_Gatherv(mine, count, MPIU_REAL, *all, *counts, *displs, MPIU_REAL, 0, comm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The transfer of loc, a local P1 field of dm (each vertex's first dim components): dm's cells, their vertices and
   the field at them gathered on rank 0, each rank's cells in its local order. Made before dm is remeshed. */
PetscErrorCode MeshTransferCreateFromField(DM dm, Vec loc, MeshTransfer *tr)
{
  MPI_Comm           comm = PetscObjectComm((PetscObject)dm);
  PetscInt           dim, cStart, cEnd, nv, per, total = 0;
  PetscSection       csec, lsec;
  Vec                coords;
  const PetscScalar *xc, *lu;
  PetscReal         *mine, *all = NULL, *x = NULL, *u = NULL;
  PetscMPIInt        rank, *counts = NULL, *displs = NULL;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  nv  = dim + 1;
  per = 2 * nv * dim; /* a cell: its vertices' coordinates, then the field at them */
  PetscCall(DMGetCoordinateSection(dm, &csec));
  PetscCall(DMGetCoordinatesLocal(dm, &coords));
  PetscCall(DMGetLocalSection(dm, &lsec));
  PetscCall(VecGetArrayRead(coords, &xc));
  PetscCall(VecGetArrayRead(loc, &lu));
  PetscCall(PetscCalloc1((cEnd - cStart) * per + 1, &mine));
  for (PetscInt c = cStart; c < cEnd; ++c) {
    PetscReal *d = &mine[(c - cStart) * per];
    PetscInt   verts[8], n;

    PetscCall(MeshCellVertices(dm, c, verts, &n));
    PetscCheck(n == nv, comm, PETSC_ERR_SUP, "the transfer to a remeshed mesh takes simplices (triangles, tetrahedra) only");
    for (PetscInt k = 0; k < nv; ++k) {
      PetscInt off, ndof;

      PetscCall(PetscSectionGetOffset(csec, verts[k], &off));
      for (PetscInt j = 0; j < dim; ++j) d[k * dim + j] = PetscRealPart(xc[off + j]);
      PetscCall(PetscSectionGetDof(lsec, verts[k], &ndof));
      PetscCall(PetscSectionGetOffset(lsec, verts[k], &off));
      for (PetscInt j = 0; j < dim && j < ndof; ++j) d[nv * dim + k * dim + j] = PetscRealPart(lu[off + j]);
    }
  }
  PetscCall(VecRestoreArrayRead(coords, &xc));
  PetscCall(VecRestoreArrayRead(loc, &lu));
  PetscCall(GatherOnRoot(comm, (cEnd - cStart) * per, mine, &all, &total, &counts, &displs));
  PetscCall(PetscFree(mine));
  if (rank == 0) {
    PetscCall(PetscMalloc1(total / 2 + 1, &x));
    PetscCall(PetscMalloc1(total / 2 + 1, &u));
    for (PetscInt c = 0; c < total / per; ++c) {
      PetscCall(PetscArraycpy(&x[c * nv * dim], &all[c * per], nv * dim));
      PetscCall(PetscArraycpy(&u[c * nv * dim], &all[c * per + nv * dim], nv * dim));
    }
    PetscCall(PetscFree(all));
    PetscCall(PetscFree2(counts, displs));
  }
  PetscCall(MeshTransferCreate(comm, dim, total / per, x, u, tr)); /* which owns x and u (rank 0) */
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode MeshTransferDestroy(MeshTransfer *tr)
{
  PetscFunctionBeginUser;
  if (!*tr) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscFree((*tr)->x));
  PetscCall(PetscFree((*tr)->u));
  PetscCall(MeshLocatorDestroy(&(*tr)->locator));
  PetscCall(PetscFree(*tr));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* fine_loc (a local vector of fine) <- the old field at each local vertex of fine, each component the section holds. */
PetscErrorCode MeshTransferApply(MeshTransfer tr, DM fine, Vec fine_loc)
{
  const PetscInt     dim = tr->dim;
  PetscMPIInt        rank, count, *counts = NULL, *displs = NULL;
  PetscInt           vStart, vEnd, n, total               = 0;
  PetscSection       sec, csec;
  Vec                coords;
  const PetscScalar *xc;
  PetscScalar       *a;
  PetscReal         *mine, *vals, *all = NULL, *allv = NULL;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(tr->comm, &rank));
  PetscCall(DMPlexGetDepthStratum(fine, 0, &vStart, &vEnd));
  n = vEnd - vStart;
  PetscCall(DMGetCoordinateSection(fine, &csec));
  PetscCall(DMGetCoordinatesLocal(fine, &coords));
  PetscCall(VecGetArrayRead(coords, &xc));
  PetscCall(PetscMalloc2(n * dim + 1, &mine, n * dim + 1, &vals));
  for (PetscInt v = vStart; v < vEnd; ++v) {
    PetscInt off;

    PetscCall(PetscSectionGetOffset(csec, v, &off));
    for (PetscInt d = 0; d < dim; ++d) mine[(v - vStart) * dim + d] = PetscRealPart(xc[off + d]);
  }
  PetscCall(VecRestoreArrayRead(coords, &xc));
  PetscCall(PetscMPIIntCast(n * dim, &count));
  PetscCall(GatherOnRoot(tr->comm, n * dim, mine, &all, &total, &counts, &displs)); /* the new vertices' positions */
  if (rank == 0) {
    PetscCall(PetscMalloc1(total + 1, &allv));
    for (PetscInt p = 0; p < total / dim; ++p) Evaluate(tr, &all[p * dim], &allv[p * dim]);
  }
  PetscCallMPI(MPI_Scatterv(allv, counts, displs, MPIU_REAL, vals, count, MPIU_REAL, 0, tr->comm));
  if (rank == 0) {
    PetscCall(PetscFree(all));
    PetscCall(PetscFree(allv));
    PetscCall(PetscFree2(counts, displs));
  }
  PetscCall(DMGetLocalSection(fine, &sec));
  PetscCall(VecGetArray(fine_loc, &a));
  for (PetscInt v = vStart; v < vEnd; ++v) {
    PetscInt ndof, off;

    PetscCall(PetscSectionGetDof(sec, v, &ndof));
    PetscCall(PetscSectionGetOffset(sec, v, &off));
    for (PetscInt k = 0; k < ndof && k < dim; ++k) a[off + k] = vals[(v - vStart) * dim + k];
  }
  PetscCall(VecRestoreArray(fine_loc, &a));
  PetscCall(PetscFree2(mine, vals));
  PetscFunctionReturn(PETSC_SUCCESS);
}
