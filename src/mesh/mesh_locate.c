/* The cell of a simplex mesh that holds a point (mesh_transfer.c: the old solution at the new vertices of a remeshed
   mesh). The cells are given by their vertices alone, as gathered on rank 0. A tree of the cells' bounding boxes (a
   bounding volume hierarchy: each node the box of its cells, halved at the median centroid along its longest side,
   down to a few cells a leaf) follows the mesh's grading, where a uniform grid of buckets crowded the contact zone's
   cells, a hundred times smaller than the mean, by thousands a bucket. Outside the mesh (a point of a curved boundary,
   beyond the old mesh's chords by their sagitta), the cell the point is nearest to leaving, among those whose boxes
   come nearest. */
#include "mesh.h"

struct _n_MeshLocator {
  PetscInt         dim, nv, ncells; /* the cells, nv = dim + 1 vertices each, */
  const PetscReal *x;               /*   [ncells][nv][dim] their vertices (the caller's) */
  PetscReal       *box;             /*   [ncells][2][dim] each cell's bounding box (lower, upper corner) */
  PetscInt         nnodes;          /* the tree's nodes: */
  PetscReal       *node_box;        /*   [nnodes][2][dim] their boxes, */
  PetscInt        *node_kid;        /*   [nnodes][2] their children (a leaf: -1 and its first cell's place in order), */
  PetscInt        *node_end;        /*   [nnodes] a leaf's end in order, */
  PetscInt        *order;           /*   [ncells] the cells, each leaf's contiguous */
};

#define LOCATOR_LEAF 8 /* the most cells a leaf of the tree holds */

/* The tree's node over the cells order[begin, end): its box, and below it the halves at the median centroid along the
   box's longest side. Returns the node's index. */
static PetscErrorCode TreeBuild(MeshLocator tr, PetscInt begin, PetscInt end, PetscReal key[], PetscInt *node)
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
  if (end - begin <= LOCATOR_LEAF) {
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

/* The cells' boxes and the tree over them; x stays the caller's. */
PetscErrorCode MeshLocatorCreate(PetscInt dim, PetscInt ncells, const PetscReal x[], MeshLocator *locator)
{
  const PetscInt nv = dim + 1;
  MeshLocator    tr;
  PetscReal     *key;
  PetscInt       root;

  PetscFunctionBeginUser;
  PetscCall(PetscNew(&tr));
  tr->dim    = dim;
  tr->nv     = nv;
  tr->ncells = ncells;
  tr->x      = x;
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
  { /* a binary tree whose leaves hold at most LOCATOR_LEAF cells has fewer than 2 ncells / (LOCATOR_LEAF / 2) nodes */
    const PetscInt most = 4 * tr->ncells / LOCATOR_LEAF + 2;

    PetscCall(PetscMalloc3(most * 2 * dim, &tr->node_box, most * 2, &tr->node_kid, most, &tr->node_end));
  }
  PetscCall(PetscMalloc1(tr->ncells + 1, &key));
  tr->nnodes = 0;
  if (tr->ncells) PetscCall(TreeBuild(tr, 0, tr->ncells, key, &root));
  PetscCall(PetscFree(key));
  *locator = tr;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode MeshLocatorDestroy(MeshLocator *locator)
{
  PetscFunctionBeginUser;
  if (!*locator) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscFree2((*locator)->box, (*locator)->order));
  PetscCall(PetscFree3((*locator)->node_box, (*locator)->node_kid, (*locator)->node_end));
  PetscCall(PetscFree(*locator));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The barycentric coordinates of x in cell c. */
static void Barycentric(const MeshLocator tr, PetscInt c, const PetscReal x[], PetscReal lambda[])
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
   barycentric coordinate), through the tree: *best -1 where there is none. */
static void TreeLocate(const MeshLocator tr, const PetscReal x[], PetscReal delta, PetscInt *best, PetscReal *best_min)
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
    if (tr->node_kid[2 * n] >= 0) { /* the depth is about log2(ncells / LOCATOR_LEAF): 128 is far beyond any mesh */
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

/* The cell that holds p best (the largest smallest barycentric coordinate) and p's barycentric coordinates in it: the
   tree's search; outside the mesh, the boxes grown by a distance that doubles from a millionth of the mesh's extent
   until some come within it, then once more, and the best of them (whose linear functions extend to p). *cell is -1
   only for a mesh without cells. */
void MeshLocatorFind(MeshLocator tr, const PetscReal p[], PetscInt *cell, PetscReal lambda[])
{
  const PetscInt dim = tr->dim;
  PetscReal      best_min, extent = 0.0, delta;

  TreeLocate(tr, p, 0.0, cell, &best_min);
  if (best_min < -1e-10 && tr->nnodes) {
    for (PetscInt d = 0; d < dim; ++d) extent = PetscMax(extent, tr->node_box[dim + d] - tr->node_box[d]);
    for (delta = 1e-6 * extent; delta < 4.0 * extent; delta *= 2.0) {
      TreeLocate(tr, p, delta, cell, &best_min);
      if (*cell >= 0) break;
    }
    TreeLocate(tr, p, 2.0 * delta, cell, &best_min);
  }
  if (*cell >= 0) Barycentric(tr, *cell, p, lambda);
}
