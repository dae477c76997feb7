/* The last solution carried to a remeshed mesh (mesh_remesh.c): the next solve's start, as nested iteration's
   interpolation is for a refined mesh. The meshes do not nest, so each new vertex is located in the old mesh and the
   old P1 field evaluated there, u(x) = sum_k lambda_k(x) u_k with the barycentric coordinates lambda of the old cell
   holding x. A new vertex on a curved boundary may lie just outside the old mesh (the old boundary is the chords of the
   new one's curve, a sagitta h^2 / 8R away): it takes the linear extension of the nearest old cell's field (the cell
   whose smallest barycentric coordinate is the largest).
   The old cells, their vertices and values, are on rank 0 (gathered for Gmsh anyway); each rank sends its new vertices'
   positions there and gets the values back. Rank 0 finds the cell holding a point in a tree of the cells' bounding boxes
   (a bounding volume hierarchy: each node the box of its cells, halved at the median centroid along its longest side,
   down to a few cells a leaf), whose depth follows the mesh's grading; outside the mesh, among the cells whose boxes
   come nearest. A uniform grid of buckets, about one cell a bucket, took a fifth of the sphere's -accuracy 0.1 run
   (1.1 s of its last remesh): the contact zone's cells, a hundred times smaller than the mean, crowded its buckets by
   thousands, and the contact zone is on the curved boundary, whose new vertices lie outside the old mesh and so
   searched 125 of them. */
#include "mesh.h"

struct _n_MeshTransfer {
  MPI_Comm   comm;
  PetscInt   dim, nv, ncells; /* rank 0: the old cells, nv vertices each */
  PetscReal *x;               /*   [ncells][nv][dim] their vertices */
  PetscReal *u;               /*   [ncells][nv][dim] the field at them */
  PetscReal *box;             /*   [ncells][2][dim] each cell's bounding box (lower, upper corner) */
  PetscInt   nnodes;          /*   the tree's nodes: */
  PetscReal *node_box;        /*     [nnodes][2][dim] their boxes, */
  PetscInt  *node_kid;        /*     [nnodes][2] their children (a leaf: -1 and its first cell's place in order), */
  PetscInt  *node_end;        /*     [nnodes] a leaf's end in order, */
  PetscInt  *order;           /*     [ncells] the cells, each leaf's contiguous */
};

#define TRANSFER_LEAF 8 /* the most cells a leaf of the tree holds */

/* The tree's node over the cells order[begin, end): its box, and below it the halves at the median centroid along the
   box's longest side (rank 0). Returns the node's index. */
static PetscErrorCode TreeBuild(MeshTransfer tr, PetscInt begin, PetscInt end, PetscReal key[], PetscInt *node)
{
  const PetscInt dim = tr->dim;
  PetscInt       me = tr->nnodes++, axis = 0;
  PetscReal     *b = &tr->node_box[me * 2 * dim];

  PetscFunctionBeginUser;
  for (PetscInt d = 0; d < dim; ++d) {
    b[d]       = PETSC_MAX_REAL;
    b[dim + d] = PETSC_MIN_REAL;
  }
  for (PetscInt i = begin; i < end; ++i)
    for (PetscInt d = 0; d < dim; ++d) {
      b[d]       = PetscMin(b[d], tr->box[tr->order[i] * 2 * dim + d]);
      b[dim + d] = PetscMax(b[dim + d], tr->box[tr->order[i] * 2 * dim + dim + d]);
    }
  *node = me;
  if (end - begin <= TRANSFER_LEAF) {
    tr->node_kid[2 * me]     = -1;
    tr->node_kid[2 * me + 1] = begin;
    tr->node_end[me]         = end;
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  for (PetscInt d = 1; d < dim; ++d)
    if (b[dim + d] - b[d] > b[dim + axis] - b[axis]) axis = d;
  for (PetscInt i = begin; i < end; ++i) { /* the centroid along axis: the middle of the cell's box */
    const PetscReal *cb = &tr->box[tr->order[i] * 2 * dim];

    key[i] = 0.5 * (cb[axis] + cb[dim + axis]);
  }
  PetscCall(PetscSortRealWithArrayInt(end - begin, &key[begin], &tr->order[begin]));
  PetscCall(TreeBuild(tr, begin, begin + (end - begin) / 2, key, &tr->node_kid[2 * me]));
  PetscCall(TreeBuild(tr, begin + (end - begin) / 2, end, key, &tr->node_kid[2 * me + 1]));
  tr->node_end[me] = end;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The cells' boxes and the tree over them (rank 0). */
static PetscErrorCode TreeCreate(MeshTransfer tr)
{
  const PetscInt dim = tr->dim, nv = tr->nv;
  PetscReal     *key;
  PetscInt       root;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc2(tr->ncells * 2 * dim + 1, &tr->box, tr->ncells + 1, &tr->order));
  for (PetscInt c = 0; c < tr->ncells; ++c) {
    PetscReal *cb = &tr->box[c * 2 * dim];

    for (PetscInt d = 0; d < dim; ++d) {
      cb[d]       = PETSC_MAX_REAL;
      cb[dim + d] = PETSC_MIN_REAL;
      for (PetscInt k = 0; k < nv; ++k) {
        cb[d]       = PetscMin(cb[d], tr->x[(c * nv + k) * dim + d]);
        cb[dim + d] = PetscMax(cb[dim + d], tr->x[(c * nv + k) * dim + d]);
      }
    }
    tr->order[c] = c;
  }
  { /* a binary tree whose leaves hold at most TRANSFER_LEAF cells has fewer than 2 ncells / (TRANSFER_LEAF / 2) nodes */
    const PetscInt most = 4 * tr->ncells / TRANSFER_LEAF + 2;

    PetscCall(PetscMalloc3(most * 2 * dim, &tr->node_box, most * 2, &tr->node_kid, most, &tr->node_end));
  }
  PetscCall(PetscMalloc1(tr->ncells + 1, &key));
  tr->nnodes = 0;
  if (tr->ncells) PetscCall(TreeBuild(tr, 0, tr->ncells, key, &root));
  PetscCall(PetscFree(key));
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

/* Among the cells whose boxes, grown by delta on each side, hold x, the one that holds x best (the largest smallest
   barycentric coordinate), through the tree (rank 0): *best -1 where there is none. */
static void TreeLocate(const MeshTransfer tr, const PetscReal x[], PetscReal delta, PetscInt *best, PetscReal *best_min)
{
  const PetscInt dim = tr->dim;
  PetscInt       stack[128], top = 0;
  PetscReal      lambda[4];

  *best     = -1;
  *best_min = PETSC_MIN_REAL;
  if (!tr->nnodes) return;
  stack[top++] = 0;
  while (top) {
    const PetscInt   n  = stack[--top];
    const PetscReal *b  = &tr->node_box[n * 2 * dim];
    PetscBool        in = PETSC_TRUE;

    for (PetscInt d = 0; d < dim && in; ++d) in = (PetscBool)(x[d] >= b[d] - delta && x[d] <= b[dim + d] + delta);
    if (!in) continue;
    if (tr->node_kid[2 * n] >= 0) { /* the depth is about log2(ncells / TRANSFER_LEAF): 128 is far beyond any mesh */
      stack[top++] = tr->node_kid[2 * n];
      stack[top++] = tr->node_kid[2 * n + 1];
      continue;
    }
    for (PetscInt i = tr->node_kid[2 * n + 1]; i < tr->node_end[n]; ++i) {
      const PetscInt c = tr->order[i];
      PetscReal      m = PETSC_MAX_REAL;

      Barycentric(tr, c, x, lambda);
      for (PetscInt v = 0; v <= dim; ++v) m = PetscMin(m, lambda[v]);
      if (m > *best_min || (m == *best_min && c < *best)) { /* ties to the lowest cell: the same on any traversal */
        *best_min = m;
        *best     = c;
      }
    }
  }
}

/* The field at x (rank 0): the old field of the cell that holds x best. Outside the old mesh (a new vertex of a curved
   boundary, beyond the old one's chords by their sagitta), the search grows the boxes by a distance that doubles from
   a millionth of the mesh's extent until some come within it, then once more, and takes the best of them (the one
   x is nearest to leaving, relative to its size): its linear field extends to x. */
static void Evaluate(const MeshTransfer tr, const PetscReal x[], PetscReal u[])
{
  const PetscInt dim  = tr->dim;
  PetscInt       best = -1;
  PetscReal      best_min, lambda[4], extent = 0.0, delta;

  TreeLocate(tr, x, 0.0, &best, &best_min);
  if (best_min < -1e-10 && tr->nnodes) {
    for (PetscInt d = 0; d < dim; ++d) extent = PetscMax(extent, tr->node_box[dim + d] - tr->node_box[d]);
    for (delta = 1e-6 * extent; delta < 4.0 * extent; delta *= 2.0) {
      TreeLocate(tr, x, delta, &best, &best_min);
      if (best >= 0) break;
    }
    TreeLocate(tr, x, 2.0 * delta, &best, &best_min);
  }
  for (PetscInt d = 0; d < dim; ++d) u[d] = 0.0;
  if (best < 0) return; /* no old cell: the start is zero there */
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
  (*tr)->ncells = ncells;
  (*tr)->x      = x;
  (*tr)->u      = u;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  if (rank == 0) PetscCall(TreeCreate(*tr));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode MeshTransferDestroy(MeshTransfer *tr)
{
  PetscFunctionBeginUser;
  if (!*tr) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscFree((*tr)->x));
  PetscCall(PetscFree((*tr)->u));
  PetscCall(PetscFree2((*tr)->box, (*tr)->order));
  PetscCall(PetscFree3((*tr)->node_box, (*tr)->node_kid, (*tr)->node_end));
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
