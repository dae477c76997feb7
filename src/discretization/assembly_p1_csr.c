/* K on one rank as SeqAIJ, built in its own CSR arrays and handed to PETSc (MatCreateSeqAIJWithArrays()): the pattern
   from the mesh's edges (two vertices of a simplex mesh share a cell exactly when an edge joins them), the element
   matrices added in place, cell by cell in the order MatSetValues() would add them, so the values are the same to the
   bit. MatSetValues() searches the row for each entry it adds, and
   MatSeqAIJSetPreallocationCSR() inserts a given pattern row by row through it. The arrays belong to a container
   composed with K and are freed with it. A block per vertex where every vertex is free or fully constrained; scalar
   rows where some vertex is partly fixed (a slip condition), whose MatSetValues() path was two thirds of the set-up of
   each remeshed cycle of the Hertz sphere (its symmetry planes).
   One of PETSc 3.18's mirrors (docs/decisions.md, "PETSc 3.18's mirrors"). */
#include <petscdmplex.h>
#include "discretization.h"
#include "physics.h"

typedef struct {
  PetscInt    *i, *j, *oi, *oj; /* the off-diagonal part of an MPIAIJ K (assembly_p1_mpiaij.c), NULL on one rank */
  PetscScalar *a, *oa;
} AssemblyCSR;

static PetscErrorCode AssemblyCSRDestroy(void *ctx)
{
  AssemblyCSR *csr = (AssemblyCSR *)ctx;

  PetscFunctionBeginUser;
  PetscCall(PetscFree(csr->i));
  PetscCall(PetscFree(csr->j));
  PetscCall(PetscFree(csr->a));
  PetscCall(PetscFree(csr->oi));
  PetscCall(PetscFree(csr->oj));
  PetscCall(PetscFree(csr->oa));
  PetscCall(PetscFree(csr));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Whether K can be built in its own CSR arrays (here and in assembly_p1_mpiaij.c): AIJ (the DM's type, no -mat_type for
   MatSetFromOptions() to convert it to), a block of bs = dim dofs per vertex, and the edges (an interpolated mesh). */
PetscErrorCode AssemblyP1CSRApplies(DM dm, PetscInt bs, PetscBool mat_type_given, PetscBool *applies)
{
  PetscInt  dim, depth;
  MatType   mtype;
  PetscBool aij, seqaij, mpiaij;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMPlexGetDepth(dm, &depth));
  PetscCall(DMGetMatType(dm, &mtype));
  PetscCall(PetscStrcmp(mtype, MATAIJ, &aij));
  PetscCall(PetscStrcmp(mtype, MATSEQAIJ, &seqaij));
  PetscCall(PetscStrcmp(mtype, MATMPIAIJ, &mpiaij));
  *applies = (PetscBool)((aij || seqaij || mpiaij) && !mat_type_given && bs == dim && depth == dim);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The coordinates x[dim + 1][dim] of the vertices verts[] of a cell. */
PetscErrorCode AssemblyP1CellCoordinates(PetscSection csection, const PetscScalar xa[], PetscInt dim, const PetscInt verts[], PetscReal x[])
{
  PetscFunctionBeginUser;
  for (PetscInt a = 0; a <= dim; ++a) {
    PetscInt off;

    PetscCall(PetscSectionGetOffset(csection, verts[a], &off));
    for (PetscInt e = 0; e < dim; ++e) x[a * dim + e] = PetscRealPart(xa[off + e]);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The cell loop of the P1 assembly, for one rank and many: the element stiffness of every cell of dm (cverts: each
   cell's dim + 1 vertices, in the cell's closure order), handed block by block to add(ctx, va, vb, Kab, ld) for each pair
   of its vertices, row vertex va first, in the cell's order (local vertex numbers from the first vertex; Kab the
   dim x dim block of the element matrix, row stride ld). The order is MatSetValues()'s, so sums come out the same to the
   bit whoever adds them. */
PetscErrorCode AssemblyP1CellLoop(DM dm, const Material *mat, const PetscInt cverts[], AssemblyP1AddBlock add, void *ctx)
{
  PetscInt           dim, cStart, cEnd, vStart;
  PetscSection       csection;
  Vec                coords;
  const PetscScalar *xa;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, NULL));
  PetscCall(DMGetCoordinateSection(dm, &csection));
  PetscCall(DMGetCoordinatesLocal(dm, &coords));
  PetscCall(VecGetArrayRead(coords, &xa));
  for (PetscInt c = cStart; c < cEnd; ++c) {
    const PetscInt *cv = &cverts[(c - cStart) * (dim + 1)], n = (dim + 1) * dim;
    PetscReal       x[12];
    PetscScalar     Ke[144];

    PetscCall(AssemblyP1CellCoordinates(csection, xa, dim, cv, x));
    PetscCall(ElementP1Stiffness(dim, mat->lambda, mat->mu, x, Ke));
    for (PetscInt a = 0; a <= dim; ++a)
      for (PetscInt b = 0; b <= dim; ++b) add(ctx, cv[a] - vStart, cv[b] - vStart, &Ke[(a * dim) * n + b * dim], n);
  }
  PetscCall(VecRestoreArrayRead(coords, &xa));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Gives K's own CSR arrays to a container composed with K, which frees them with K. */
PetscErrorCode AssemblyP1CSRCompose(Mat K, PetscInt *i, PetscInt *j, PetscScalar *a, PetscInt *oi, PetscInt *oj, PetscScalar *oa)
{
  AssemblyCSR   *csr;
  PetscContainer container;

  PetscFunctionBeginUser;
  PetscCall(PetscNew(&csr));
  csr->i  = i;
  csr->j  = j;
  csr->a  = a;
  csr->oi = oi;
  csr->oj = oj;
  csr->oa = oa;
  PetscCall(PetscContainerCreate(PETSC_COMM_SELF, &container));
  PetscCall(PetscContainerSetPointer(container, csr));
  PetscCall(PetscContainerSetUserDestroy(container, AssemblyCSRDestroy));
  PetscCall(PetscObjectCompose((PetscObject)K, "AssemblyP1CSR", (PetscObject)container));
  PetscCall(PetscContainerDestroy(&container));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The vertices next to each kept vertex v (keep[v], local numbers from the first vertex): itself, then its kept
   neighbours along the edges in the edges' order (two vertices of a simplex mesh share a cell exactly when an edge
   joins them), nbr[vptr[v] .. vptr[v + 1]). Counted in a first pass, filled in a second; free both with PetscFree(). */
static PetscErrorCode VertexNeighbours(DM dm, const PetscBool keep[], PetscInt **vptr, PetscInt **nbr)
{
  PetscInt vStart, vEnd, eStart, eEnd, nv, *fill;

  PetscFunctionBeginUser;
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  PetscCall(DMPlexGetDepthStratum(dm, 1, &eStart, &eEnd));
  nv = vEnd - vStart;
  PetscCall(PetscCalloc1(nv + 1, vptr));
  PetscCall(PetscCalloc1(nv + 1, &fill));
  for (PetscInt pass = 0; pass < 2; ++pass) {
    if (pass) {
      for (PetscInt v = 0; v < nv; ++v) (*vptr)[v + 1] += (*vptr)[v];
      PetscCall(PetscMalloc1((*vptr)[nv] + 1, nbr));
    }
    for (PetscInt v = 0; v < nv; ++v) {
      if (!keep[v]) continue;
      if (pass)
        (*nbr)[(*vptr)[v] + fill[v]++] = v;
      else
        ++(*vptr)[v + 1];
    }
    for (PetscInt e = eStart; e < eEnd; ++e) {
      const PetscInt *cone;
      PetscInt        a, b;

      PetscCall(DMPlexGetCone(dm, e, &cone));
      a = cone[0] - vStart;
      b = cone[1] - vStart;
      if (!keep[a] || !keep[b]) continue;
      if (pass) {
        (*nbr)[(*vptr)[a] + fill[a]++] = b;
        (*nbr)[(*vptr)[b] + fill[b]++] = a;
      } else {
        ++(*vptr)[a + 1];
        ++(*vptr)[b + 1];
      }
    }
  }
  PetscCall(PetscFree(fill));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The block pattern of K on one rank with a block of bs = dim dofs per vertex: block row r (a free vertex) holds the
   blocks bcol[bptr[r] .. bptr[r + 1]), sorted: itself and its free neighbours along the edges (two vertices of a
   simplex mesh share a cell exactly when an edge joins them: VertexNeighbours()). */
PetscErrorCode AssemblyP1BlockPattern(DM dm, PetscInt bs, PetscInt nb, const PetscInt vidx[], PetscInt **bptr, PetscInt **bcol)
{
  PetscInt   dim, vStart, vEnd, *vptr, *nbr;
  PetscBool *keep;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  PetscCall(PetscMalloc1(vEnd - vStart + 1, &keep));
  for (PetscInt v = vStart; v < vEnd; ++v) {
    const PetscInt *g = &vidx[(v - vStart) * dim];

    keep[v - vStart] = (PetscBool)(g[0] >= 0); /* fully constrained: no row */
    if (g[0] < 0) continue;
    for (PetscInt e = 0; e < dim; ++e)
      PetscCheck(g[e] == g[0] + e && g[0] % bs == 0 && g[0] / bs < nb, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Vertex %" PetscInt_FMT " is not one block",
                 v);
  }
  PetscCall(VertexNeighbours(dm, keep, &vptr, &nbr));
  PetscCall(PetscCalloc1(nb + 1, bptr)); /* block row r = a free vertex's first dof / bs: its vertex's neighbours' blocks */
  for (PetscInt v = 0; v < vEnd - vStart; ++v)
    if (keep[v]) (*bptr)[vidx[v * dim] / bs + 1] = vptr[v + 1] - vptr[v];
  for (PetscInt r = 0; r < nb; ++r) (*bptr)[r + 1] += (*bptr)[r];
  PetscCall(PetscMalloc1((*bptr)[nb], bcol));
  for (PetscInt v = 0; v < vEnd - vStart; ++v) {
    const PetscInt r = keep[v] ? vidx[v * dim] / bs : -1;

    for (PetscInt k = 0; r >= 0 && k < vptr[v + 1] - vptr[v]; ++k) (*bcol)[(*bptr)[r] + k] = vidx[nbr[vptr[v] + k] * dim] / bs;
  }
  for (PetscInt r = 0; r < nb; ++r) PetscCall(PetscSortInt((*bptr)[r + 1] - (*bptr)[r], &(*bcol)[(*bptr)[r]]));
  PetscCall(PetscFree(vptr));
  PetscCall(PetscFree(nbr));
  PetscCall(PetscFree(keep));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* One rank: the block (va, vb) added in place into the CSR arrays (block row r of n blocks starts at bs^2 bptr[r], its
   row ci at ci bs n, block k of it at k bs). A vertex whose components are all fixed has no row and no column. */
typedef struct {
  PetscInt        bs;
  const PetscInt *vidx, *bptr, *bcol;
  PetscScalar    *ca;
} SeqAdd;

static void SeqAddBlock(void *ctx, PetscInt va, PetscInt vb, const PetscScalar *v, PetscInt ld)
{
  const SeqAdd  *s  = (const SeqAdd *)ctx;
  const PetscInt bs = s->bs, ga = s->vidx[va * bs], gb = s->vidx[vb * bs];
  PetscInt       r, nr, k                              = 0;

  if (ga < 0 || gb < 0) return;
  r  = ga / bs;
  nr = s->bptr[r + 1] - s->bptr[r];
  while (s->bcol[s->bptr[r] + k] != gb / bs) ++k; /* present: an edge or the vertex itself */
  for (PetscInt ci = 0; ci < bs; ++ci)
    for (PetscInt d = 0; d < bs; ++d) s->ca[bs * bs * s->bptr[r] + ci * bs * nr + k * bs + d] += v[ci * ld + d];
}

/* One rank, a vertex with some components fixed and others free (a slip condition: -bc_slip, a symmetry plane): K's
   rows are scalar. The free components of a vertex have consecutive global numbers, first[v] on; every row of vertex
   v holds the same columns: the free components of v and of its neighbours along the edges, nbr[vptr[v] ..
   vptr[v + 1]) in the order of their first[] (sorted columns), neighbour k's at colofs[vptr[v] + k] of the row. */
typedef struct {
  PetscInt        dim;
  const PetscInt *vidx, *first, *vptr, *nbr, *colofs, *ci;
  PetscScalar    *ca;
} SeqAddScalar;

static void SeqAddScalarBlock(void *ctx, PetscInt va, PetscInt vb, const PetscScalar *v, PetscInt ld)
{
  const SeqAddScalar *s   = (const SeqAddScalar *)ctx;
  const PetscInt      dim = s->dim;
  PetscInt            k   = s->vptr[va];

  if (s->first[va] < 0 || s->first[vb] < 0) return;
  while (s->nbr[k] != vb) ++k; /* present: an edge or the vertex itself */
  for (PetscInt ci = 0; ci < dim; ++ci) {
    const PetscInt g = s->vidx[va * dim + ci];

    if (g < 0) continue;
    for (PetscInt d = 0; d < dim; ++d) {
      const PetscInt j = s->vidx[vb * dim + d];

      if (j >= 0) s->ca[s->ci[g] + s->colofs[k] + (j - s->first[vb])] += v[ci * ld + d];
    }
  }
}

/* K on one rank as SeqAIJ with scalar rows (bs = 1: some vertex partly fixed), in its own CSR arrays as for a block per
   vertex (AssemblyP1CreateSeqAIJ()): the pattern from the edges, the element matrices added in place in MatSetValues()'s
   order, so the values are the same to the bit. *done is false, and nothing is built, where a vertex's free components
   are not numbered consecutively. */
static PetscErrorCode AssemblyP1CreateSeqAIJScalar(DM dm, const Material *mat, PetscInt nlocal, const PetscInt vidx[], const PetscInt cverts[],
                                                   Mat *K, PetscBool *done)
{
  PetscInt     dim, vStart, vEnd, nv, *first, *nfree, *vptr, *nbr, *key, *colofs, *ci_, *cj;
  PetscScalar *ca;
  PetscBool    consecutive = PETSC_TRUE;

  PetscFunctionBeginUser;
  *done = PETSC_FALSE;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  nv = vEnd - vStart;
  PetscCall(PetscMalloc2(nv, &first, nv, &nfree));
  for (PetscInt v = 0; v < nv && consecutive; ++v) {
    first[v] = -1;
    nfree[v] = 0;
    for (PetscInt e = 0; e < dim; ++e) {
      const PetscInt g = vidx[v * dim + e];

      if (g < 0) continue;
      if (first[v] < 0) first[v] = g;
      consecutive = (PetscBool)(g == first[v] + nfree[v] && g < nlocal);
      ++nfree[v];
      if (!consecutive) break;
    }
  }
  if (!consecutive) {
    PetscCall(PetscFree2(first, nfree));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  { /* the vertices next to each free vertex, itself included */
    PetscBool *keep;

    PetscCall(PetscMalloc1(nv + 1, &keep));
    for (PetscInt v = 0; v < nv; ++v) keep[v] = (PetscBool)(first[v] >= 0);
    PetscCall(VertexNeighbours(dm, keep, &vptr, &nbr));
    PetscCall(PetscFree(keep));
    PetscCall(PetscMalloc2(vptr[nv] + 1, &key, vptr[nv] + 1, &colofs));
  }
  /* each vertex's neighbours in the order of their columns, and where each one's columns start in the row */
  PetscCall(PetscMalloc1(nlocal + 1, &ci_));
  ci_[0] = 0;
  {
    PetscInt *len; /* the length of each row */

    PetscCall(PetscCalloc1(nlocal + 1, &len));
    for (PetscInt v = 0; v < nv; ++v) {
      PetscInt n = 0;

      if (first[v] < 0) continue;
      for (PetscInt k = vptr[v]; k < vptr[v + 1]; ++k) key[k] = first[nbr[k]];
      PetscCall(PetscSortIntWithArray(vptr[v + 1] - vptr[v], &key[vptr[v]], &nbr[vptr[v]]));
      for (PetscInt k = vptr[v]; k < vptr[v + 1]; ++k) {
        colofs[k] = n;
        n += nfree[nbr[k]];
      }
      for (PetscInt c = 0; c < nfree[v]; ++c) len[first[v] + c] = n;
    }
    for (PetscInt g = 0; g < nlocal; ++g) ci_[g + 1] = ci_[g] + len[g];
    PetscCall(PetscFree(len));
  }
  PetscCall(PetscMalloc1(ci_[nlocal] + 1, &cj));
  PetscCall(PetscCalloc1(ci_[nlocal] + 1, &ca));
  for (PetscInt v = 0; v < nv; ++v)
    for (PetscInt c = 0; c < nfree[v]; ++c)
      for (PetscInt k = vptr[v]; k < vptr[v + 1]; ++k)
        for (PetscInt d = 0; d < nfree[nbr[k]]; ++d) cj[ci_[first[v] + c] + colofs[k] + d] = first[nbr[k]] + d;
  {
    SeqAddScalar add = {dim, vidx, first, vptr, nbr, colofs, ci_, ca};

    PetscCall(AssemblyP1CellLoop(dm, mat, cverts, SeqAddScalarBlock, &add));
  }
  PetscCall(PetscFree2(key, colofs));
  PetscCall(PetscFree(nbr));
  PetscCall(PetscFree(vptr));
  PetscCall(PetscFree2(first, nfree));
  PetscCall(MatCreateSeqAIJWithArrays(PetscObjectComm((PetscObject)dm), nlocal, nlocal, ci_, cj, ca, K));
  PetscCall(AssemblyP1CSRCompose(*K, ci_, cj, ca, NULL, NULL, NULL));
  PetscCall(MatSetFromOptions(*K));
  *done = PETSC_TRUE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode AssemblyP1CreateSeqAIJ(DM dm, const AssemblyP1Inputs *in, PetscInt nlocal, PetscInt bs, const PetscInt vidx[], const PetscInt cverts[],
                                      Mat *K, PetscBool *done)
{
  MPI_Comm     comm = PetscObjectComm((PetscObject)dm);
  PetscMPIInt  size;
  PetscInt     dim, nb, *bptr, *bcol;
  PetscBool    applies;
  PetscInt    *ci_, *cj;
  PetscScalar *ca;

  PetscFunctionBeginUser;
  *done = PETSC_FALSE;
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCall(DMGetDimension(dm, &dim));
  if (size > 1) PetscFunctionReturn(PETSC_SUCCESS);
  if (bs == 1 && dim > 1) { /* some vertex partly fixed */
    PetscCall(AssemblyP1CSRApplies(dm, dim, in->mat_type_given, &applies));
    if (applies) PetscCall(AssemblyP1CreateSeqAIJScalar(dm, in->material, nlocal, vidx, cverts, K, done));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  PetscCall(AssemblyP1CSRApplies(dm, bs, in->mat_type_given, &applies));
  if (!applies) PetscFunctionReturn(PETSC_SUCCESS);
  nb = nlocal / bs;
  PetscCall(AssemblyP1BlockPattern(dm, bs, nb, vidx, &bptr, &bcol));
  PetscCall(PetscMalloc1(nlocal + 1, &ci_));
  PetscCall(PetscMalloc1(bs * bs * bptr[nb], &cj));
  PetscCall(PetscCalloc1(bs * bs * bptr[nb], &ca));
  for (PetscInt r = 0; r < nb; ++r) { /* row r bs + c: the blocks of block row r, each as bs consecutive columns */
    const PetscInt n = bptr[r + 1] - bptr[r];

    for (PetscInt c = 0; c < bs; ++c) {
      const PetscInt start = bs * bs * bptr[r] + c * bs * n;

      ci_[r * bs + c] = start;
      for (PetscInt k = 0; k < n; ++k)
        for (PetscInt d = 0; d < bs; ++d) cj[start + k * bs + d] = bcol[bptr[r] + k] * bs + d;
    }
  }
  ci_[nlocal] = bs * bs * bptr[nb];

  {
    SeqAdd add = {bs, vidx, bptr, bcol, ca};

    PetscCall(AssemblyP1CellLoop(dm, in->material, cverts, SeqAddBlock, &add));
  }
  PetscCall(PetscFree(bptr));
  PetscCall(PetscFree(bcol));

  PetscCall(MatCreateSeqAIJWithArrays(comm, nlocal, nlocal, ci_, cj, ca, K));
  PetscCall(AssemblyP1CSRCompose(*K, ci_, cj, ca, NULL, NULL, NULL));
  PetscCall(MatSetBlockSize(*K, bs));
  PetscCall(MatSetFromOptions(*K));
  *done = PETSC_TRUE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The entries allocated in K's own CSR arrays, if K was built on them (PETSc reports 0 allocated for such a matrix);
 *nz is left alone otherwise. */
PetscErrorCode AssemblyP1CSRAllocated(Mat K, PetscLogDouble *nz)
{
  PetscContainer container;
  AssemblyCSR   *csr;
  PetscInt       m;

  PetscFunctionBeginUser;
  PetscCall(PetscObjectQuery((PetscObject)K, "AssemblyP1CSR", (PetscObject *)&container));
  if (!container) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscContainerGetPointer(container, (void **)&csr));
  PetscCall(MatGetLocalSize(K, &m, NULL));
  {
    PetscLogDouble local = (PetscLogDouble)csr->i[m] + (csr->oi ? (PetscLogDouble)csr->oi[m] : 0.0);

    PetscCallMPI(MPIU_Allreduce(&local, nz, 1, MPI_DOUBLE, MPI_SUM, PetscObjectComm((PetscObject)K)));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}
