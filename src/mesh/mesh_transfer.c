/* The last solution carried to a remeshed mesh (mesh_remesh.c): the next solve's start, as nested iteration's
   interpolation is for a refined mesh. The meshes do not nest, so each new vertex is located in the old mesh and the
   old P1 field evaluated there, u(x) = sum_k lambda_k(x) u_k with the barycentric coordinates lambda of the old cell
   holding x. A new vertex on a curved boundary may lie just outside the old mesh (the old boundary is the chords of the
   new one's curve, a sagitta h^2 / 8R away): it takes the linear extension of the nearest old cell's field (the cell
   whose smallest barycentric coordinate is the largest).
   The old cells, their vertices and values, are on rank 0 (gathered for Gmsh anyway); each rank sends its new vertices'
   positions there and gets the values back. Rank 0 finds the cells through a grid of buckets over their bounding box,
   about one cell a bucket, each bucket listing the cells whose bounding box meets it. */
#include "mesh.h"

struct _n_MeshTransfer {
  MPI_Comm   comm;
  PetscInt   dim, nv, ncells; /* rank 0: the old cells, nv vertices each */
  PetscReal *x;               /*   [ncells][nv][dim] their vertices */
  PetscReal *u;               /*   [ncells][nv][dim] the field at them */
  PetscReal  lo[3], hi[3];    /*   the buckets' box, */
  PetscInt   nb[3];           /*   their number per direction, */
  PetscInt  *start, *list;    /*   and the cells of each (CSR) */
};

static PetscInt BucketIndex(const MeshTransfer tr, const PetscReal x[], PetscInt d)
{
  const PetscReal t = (x[d] - tr->lo[d]) / (tr->hi[d] - tr->lo[d]) * tr->nb[d];
  const PetscInt  i = (PetscInt)PetscFloorReal(t);

  return PetscMax(0, PetscMin(tr->nb[d] - 1, i));
}

/* The buckets of the cells' bounding boxes (rank 0). */
static PetscErrorCode BucketsBuild(MeshTransfer tr)
{
  const PetscInt dim = tr->dim, nv = tr->nv;
  PetscInt       nbt = 1, *count;
  PetscReal      span[3];

  PetscFunctionBeginUser;
  for (PetscInt d = 0; d < dim; ++d) {
    tr->lo[d] = PETSC_MAX_REAL;
    tr->hi[d] = PETSC_MIN_REAL;
  }
  for (PetscInt i = 0; i < tr->ncells * nv; ++i)
    for (PetscInt d = 0; d < dim; ++d) {
      tr->lo[d] = PetscMin(tr->lo[d], tr->x[i * dim + d]);
      tr->hi[d] = PetscMax(tr->hi[d], tr->x[i * dim + d]);
    }
  for (PetscInt d = 0; d < dim; ++d) {
    span[d] = tr->hi[d] - tr->lo[d];
    tr->lo[d] -= 1e-9 * span[d];
    tr->hi[d] += 1e-9 * span[d];
  }
  { /* about one cell a bucket, the buckets about square */
    PetscReal vol = 1.0;

    for (PetscInt d = 0; d < dim; ++d) vol *= span[d];
    for (PetscInt d = 0; d < dim; ++d) {
      tr->nb[d] = (PetscInt)PetscCeilReal(span[d] * PetscPowReal(tr->ncells / vol, 1.0 / dim));
      tr->nb[d] = PetscMax(1, PetscMin(tr->nb[d], 4096));
      nbt *= tr->nb[d];
    }
  }
  PetscCall(PetscCalloc1(nbt + 1, &tr->start));
  PetscCall(PetscCalloc1(nbt, &count));
  for (PetscInt pass = 0; pass < 2; ++pass) {
    for (PetscInt c = 0; c < tr->ncells; ++c) {
      PetscInt  b0[3] = {0, 0, 0}, b1[3] = {0, 0, 0};
      PetscReal cl[3], ch[3];

      for (PetscInt d = 0; d < dim; ++d) {
        cl[d] = PETSC_MAX_REAL;
        ch[d] = PETSC_MIN_REAL;
        for (PetscInt k = 0; k < nv; ++k) {
          cl[d] = PetscMin(cl[d], tr->x[(c * nv + k) * dim + d]);
          ch[d] = PetscMax(ch[d], tr->x[(c * nv + k) * dim + d]);
        }
      }
      for (PetscInt d = 0; d < dim; ++d) {
        b0[d] = BucketIndex(tr, cl, d);
        b1[d] = BucketIndex(tr, ch, d);
      }
      for (PetscInt i = b0[0]; i <= b1[0]; ++i)
        for (PetscInt j = b0[1]; j <= b1[1]; ++j)
          for (PetscInt k = b0[2]; k <= b1[2]; ++k) {
            const PetscInt b = (k * tr->nb[1] + j) * tr->nb[0] + i;

            if (pass == 0)
              tr->start[b + 1]++;
            else
              tr->list[tr->start[b] + count[b]++] = c;
          }
    }
    if (pass == 0) {
      for (PetscInt b = 0; b < nbt; ++b) tr->start[b + 1] += tr->start[b];
      PetscCall(PetscMalloc1(tr->start[nbt] + 1, &tr->list));
    }
  }
  PetscCall(PetscFree(count));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The barycentric coordinates of x in cell c (rank 0). */
static void Barycentric(const MeshTransfer tr, PetscInt c, const PetscReal x[], PetscReal lambda[])
{
  const PetscInt   dim = tr->dim;
  const PetscReal *v   = &tr->x[c * tr->nv * dim];
  PetscReal        J[9], r[3], det;

  for (PetscInt i = 0; i < dim; ++i) {
    r[i] = x[i] - v[i];
    for (PetscInt j = 0; j < dim; ++j) J[i * dim + j] = v[(j + 1) * dim + i] - v[i];
  }
  if (dim == 2) {
    det       = J[0] * J[3] - J[1] * J[2];
    lambda[1] = (J[3] * r[0] - J[1] * r[1]) / det;
    lambda[2] = (-J[2] * r[0] + J[0] * r[1]) / det;
  } else {
    det       = J[0] * (J[4] * J[8] - J[5] * J[7]) - J[1] * (J[3] * J[8] - J[5] * J[6]) + J[2] * (J[3] * J[7] - J[4] * J[6]);
    lambda[1] = ((J[4] * J[8] - J[5] * J[7]) * r[0] - (J[1] * J[8] - J[2] * J[7]) * r[1] + (J[1] * J[5] - J[2] * J[4]) * r[2]) / det;
    lambda[2] = (-(J[3] * J[8] - J[5] * J[6]) * r[0] + (J[0] * J[8] - J[2] * J[6]) * r[1] - (J[0] * J[5] - J[2] * J[3]) * r[2]) / det;
    lambda[3] = ((J[3] * J[7] - J[4] * J[6]) * r[0] - (J[0] * J[7] - J[1] * J[6]) * r[1] + (J[0] * J[4] - J[1] * J[3]) * r[2]) / det;
  }
  lambda[0] = 1.0;
  for (PetscInt k = 1; k <= dim; ++k) lambda[0] -= lambda[k];
}

/* The field at x (rank 0): the cell of x's bucket, or of the buckets around it, that holds x best. */
static void Evaluate(const MeshTransfer tr, const PetscReal x[], PetscReal u[])
{
  const PetscInt dim  = tr->dim;
  PetscInt       b[3] = {0, 0, 0}, best = -1;
  PetscReal      best_min = PETSC_MIN_REAL, lambda[4];

  for (PetscInt d = 0; d < dim; ++d) b[d] = BucketIndex(tr, x, d);
  for (PetscInt ring = 0; ring <= 2 && best_min < -1e-10; ++ring)
    for (PetscInt i = PetscMax(0, b[0] - ring); i <= PetscMin(tr->nb[0] - 1, b[0] + ring); ++i)
      for (PetscInt j = PetscMax(0, b[1] - ring); j <= PetscMin(tr->nb[1] - 1, b[1] + ring); ++j)
        for (PetscInt k = PetscMax(0, b[2] - ring); k <= PetscMin(PetscMax(tr->nb[2], 1) - 1, b[2] + ring); ++k) {
          const PetscInt bb = (k * tr->nb[1] + j) * tr->nb[0] + i;

          for (PetscInt q = tr->start[bb]; q < tr->start[bb + 1]; ++q) {
            PetscReal m = PETSC_MAX_REAL;

            Barycentric(tr, tr->list[q], x, lambda);
            for (PetscInt v = 0; v <= dim; ++v) m = PetscMin(m, lambda[v]);
            if (m > best_min) {
              best_min = m;
              best     = tr->list[q];
            }
          }
        }
  for (PetscInt d = 0; d < dim; ++d) u[d] = 0.0;
  if (best < 0) return; /* no old cell near: the start is zero there */
  Barycentric(tr, best, x, lambda);
  for (PetscInt v = 0; v <= dim; ++v)
    for (PetscInt d = 0; d < dim; ++d) u[d] += lambda[v] * tr->u[(best * tr->nv + v) * dim + d];
}

PetscErrorCode MeshTransferCreate(MPI_Comm comm, PetscInt dim, PetscInt ncells, PetscReal x[], PetscReal u[], MeshTransfer *tr)
{
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  PetscCall(PetscNew(tr));
  (*tr)->comm   = comm;
  (*tr)->dim    = dim;
  (*tr)->nv     = dim + 1;
  (*tr)->nb[2]  = 1;
  (*tr)->ncells = ncells;
  (*tr)->x      = x;
  (*tr)->u      = u;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  if (rank == 0) PetscCall(BucketsBuild(*tr));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode MeshTransferDestroy(MeshTransfer *tr)
{
  PetscFunctionBeginUser;
  if (!*tr) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscFree((*tr)->x));
  PetscCall(PetscFree((*tr)->u));
  PetscCall(PetscFree((*tr)->start));
  PetscCall(PetscFree((*tr)->list));
  PetscCall(PetscFree(*tr));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* fine_loc (a local vector of fine) <- the old field at each local vertex of fine, each component the section holds. */
PetscErrorCode MeshTransferApply(MeshTransfer tr, DM fine, Vec fine_loc)
{
  const PetscInt     dim = tr->dim;
  PetscMPIInt        rank, nranks, count, *counts = NULL, *displs = NULL;
  PetscInt           vStart, vEnd, n, total = 0;
  PetscSection       sec, csec;
  Vec                coords;
  const PetscScalar *xc;
  PetscScalar       *a;
  PetscReal         *mine, *vals, *all = NULL, *allv = NULL;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(tr->comm, &rank));
  PetscCallMPI(MPI_Comm_size(tr->comm, &nranks));
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
  if (rank == 0) PetscCall(PetscMalloc2(nranks, &counts, nranks, &displs));
  PetscCallMPI(MPI_Gather(&count, 1, MPI_INT, counts, 1, MPI_INT, 0, tr->comm));
  if (rank == 0) {
    for (PetscMPIInt r = 0; r < nranks; ++r) {
      displs[r] = (PetscMPIInt)total;
      total += counts[r];
    }
    PetscCall(PetscMalloc2(total + 1, &all, total + 1, &allv));
  }
  PetscCallMPI(MPI_Gatherv(mine, count, MPIU_REAL, all, counts, displs, MPIU_REAL, 0, tr->comm));
  if (rank == 0)
    for (PetscInt p = 0; p < total / dim; ++p) Evaluate(tr, &all[p * dim], &allv[p * dim]);
  PetscCallMPI(MPI_Scatterv(allv, counts, displs, MPIU_REAL, vals, count, MPIU_REAL, 0, tr->comm));
  if (rank == 0) {
    PetscCall(PetscFree2(all, allv));
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
