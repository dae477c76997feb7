/* K on several ranks as MPIAIJ, built in its own CSR arrays and handed to PETSc (MatCreateMPIAIJWithSplitArrays()),
   the parallel counterpart of assembly_p1_csr.c. Each rank owns the rows of its owned vertices; the cells it holds
   also touch vertices another rank owns (ghosts), and a row's owner does not see the other ranks' cells. So each rank
   sends, for each ghost vertex, its block row (the neighbours along its local edges, then the values of its local
   cells) to the owner, which adds them to its own: one exchange for the pattern, one for the values. It needs
   neither a MATPREALLOCATOR dry run nor MatSetValues(), with their stash and hash tables. Applies where every vertex
   is free or fully constrained (a block per vertex).
   One of PETSc 3.18's mirrors (docs/decisions.md, "PETSc 3.18's mirrors"). */
#include <petscdmplex.h>
#include <petscsf.h>
#include "discretization.h"
#include "physics.h"

/* Block rows of global block columns: rows [ptr[r], ptr[r + 1]) of col, sorted and unique after BlockRowsFinish(). */
typedef struct {
  PetscInt  n, *ptr, *col;
  PetscInt *fill;
} BlockRows;

static PetscErrorCode BlockRowsCount(BlockRows *br, PetscInt n)
{
  PetscFunctionBeginUser;
  br->n = n;
  PetscCall(PetscCalloc1(n + 1, &br->ptr));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode BlockRowsAllocate(BlockRows *br)
{
  PetscFunctionBeginUser;
  for (PetscInt r = 0; r < br->n; ++r) br->ptr[r + 1] += br->ptr[r];
  PetscCall(PetscMalloc1(br->ptr[br->n], &br->col));
  PetscCall(PetscCalloc1(br->n, &br->fill));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* sorts each row and removes repeated columns (the owner's edges and a ghost row's may share some) */
static PetscErrorCode BlockRowsFinish(BlockRows *br)
{
  PetscInt k = 0;

  PetscFunctionBeginUser;
  for (PetscInt r = 0; r < br->n; ++r) {
    PetscInt n = br->ptr[r + 1] - br->ptr[r], start = br->ptr[r];

    PetscCall(PetscSortRemoveDupsInt(&n, &br->col[start]));
    br->ptr[r] = k;
    for (PetscInt q = 0; q < n; ++q) br->col[k++] = br->col[start + q];
  }
  br->ptr[br->n] = k;
  PetscCall(PetscFree(br->fill));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode BlockRowsDestroy(BlockRows *br)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree(br->ptr));
  PetscCall(PetscFree(br->col));
  PetscCall(PetscFree(br->fill));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The place of block column b in block row r (present by construction). */
static inline PetscInt BlockRowsFind(const BlockRows *br, PetscInt r, PetscInt b)
{
  PetscInt lo = br->ptr[r], hi = br->ptr[r + 1] - 1;

  while (lo < hi) {
    const PetscInt mid = (lo + hi) / 2;

    if (br->col[mid] < b)
      lo = mid + 1;
    else
      hi = mid;
  }
  return lo - br->ptr[r];
}

/* Owned rows in the split arrays: block row r has nlow[r] off-diagonal blocks before its diagonal ones (the global
   block columns are sorted, the owned ones a contiguous range), ndiag[r] diagonal and the rest after them. */
typedef struct {
  PetscInt     bs, b0, nb; /* block size, first owned block, owned blocks */
  BlockRows    rows;
  PetscInt    *nlow, *ndiag, *dstart, *ostart; /* per block row: its first entries in the diagonal and off-diagonal arrays */
  PetscInt    *i, *j, *oi, *oj;
  PetscScalar *a, *oa;
} SplitRows;

static PetscErrorCode SplitRowsSetUp(SplitRows *s, PetscInt nlocal)
{
  const PetscInt bs   = s->bs;
  PetscInt       dsum = 0, osum = 0;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc4(s->nb, &s->nlow, s->nb, &s->ndiag, s->nb, &s->dstart, s->nb, &s->ostart));
  for (PetscInt r = 0; r < s->nb; ++r) {
    const PetscInt *c = &s->rows.col[s->rows.ptr[r]], n = s->rows.ptr[r + 1] - s->rows.ptr[r];
    PetscInt        lo = 0, d = 0;

    while (lo < n && c[lo] < s->b0) ++lo;
    while (lo + d < n && c[lo + d] < s->b0 + s->nb) ++d;
    s->nlow[r]   = lo;
    s->ndiag[r]  = d;
    s->dstart[r] = dsum;
    s->ostart[r] = osum;
    dsum += bs * bs * d;
    osum += bs * bs * (n - d);
  }
  PetscCall(PetscMalloc1(nlocal + 1, &s->i));
  PetscCall(PetscMalloc1(nlocal + 1, &s->oi));
  PetscCall(PetscMalloc1(dsum, &s->j));
  PetscCall(PetscMalloc1(osum, &s->oj));
  PetscCall(PetscCalloc1(dsum, &s->a));
  PetscCall(PetscCalloc1(osum, &s->oa));
  for (PetscInt r = 0; r < s->nb; ++r) {
    const PetscInt *c = &s->rows.col[s->rows.ptr[r]], n = s->rows.ptr[r + 1] - s->rows.ptr[r], nd = s->ndiag[r], no = n - nd;

    for (PetscInt ci = 0; ci < bs; ++ci) {
      PetscInt *jd = &s->j[s->dstart[r] + ci * bs * nd], *jo = &s->oj[s->ostart[r] + ci * bs * no];

      s->i[r * bs + ci]  = s->dstart[r] + ci * bs * nd;
      s->oi[r * bs + ci] = s->ostart[r] + ci * bs * no;
      for (PetscInt k = 0; k < n; ++k) {
        const PetscBool diag = (PetscBool)(k >= s->nlow[r] && k < s->nlow[r] + nd);

        for (PetscInt d = 0; d < bs; ++d) {
          if (diag)
            jd[(k - s->nlow[r]) * bs + d] = (c[k] - s->b0) * bs + d;
          else
            jo[(k < s->nlow[r] ? k : k - nd) * bs + d] = c[k] * bs + d;
        }
      }
    }
  }
  s->i[nlocal]  = dsum;
  s->oi[nlocal] = osum;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Adds the bs x bs block v (row stride ld) at block row r (owned, local), global block column b. */
static inline void SplitRowsAdd(SplitRows *s, PetscInt r, PetscInt b, const PetscScalar *v, PetscInt ld)
{
  const PetscInt bs = s->bs, n = s->rows.ptr[r + 1] - s->rows.ptr[r], nd = s->ndiag[r], k = BlockRowsFind(&s->rows, r, b);

  if (k >= s->nlow[r] && k < s->nlow[r] + nd) {
    PetscScalar *a = &s->a[s->dstart[r] + (k - s->nlow[r]) * bs];

    for (PetscInt ci = 0; ci < bs; ++ci)
      for (PetscInt d = 0; d < bs; ++d) a[ci * bs * nd + d] += v[ci * ld + d];
  } else {
    PetscScalar *a = &s->oa[s->ostart[r] + (k < s->nlow[r] ? k : k - nd) * bs];

    for (PetscInt ci = 0; ci < bs; ++ci)
      for (PetscInt d = 0; d < bs; ++d) a[ci * bs * (n - nd) + d] += v[ci * ld + d];
  }
}

/* Several ranks: the block (va, vb) added in place into an owned block row, or kept for the owner of a ghost row (gval,
   block row by block row as sent). A vertex whose components are all fixed has no row and no column. */
typedef struct {
  SplitRows       *s;
  const BlockRows *grows;
  const PetscInt  *blk, *ghost;
  PetscScalar     *gval;
} MPIAdd;

static void MPIAddBlock(void *ctx, PetscInt va, PetscInt vb, const PetscScalar *v, PetscInt ld)
{
  const MPIAdd  *m  = (const MPIAdd *)ctx;
  const PetscInt bs = m->s->bs;

  if (m->blk[va] < 0 || m->blk[vb] < 0) return;
  if (m->ghost[va] < 0)
    SplitRowsAdd(m->s, m->blk[va] - m->s->b0, m->blk[vb], v, ld);
  else {
    PetscScalar *g = &m->gval[bs * bs * (m->grows->ptr[m->ghost[va]] + BlockRowsFind(m->grows, m->ghost[va], m->blk[vb]))];

    for (PetscInt ci = 0; ci < bs; ++ci)
      for (PetscInt d = 0; d < bs; ++d) g[ci * bs + d] += v[ci * ld + d];
  }
}

/* The entry (r, c) of local vertices r and c: counted (fill false) or filled into r's block row. */
static inline void LocalPatternAdd(const PetscInt blk[], const PetscInt ghost[], PetscInt b0, BlockRows *own, BlockRows *ghosts, PetscBool fill,
                                   PetscInt r, PetscInt c)
{
  BlockRows     *br  = ghost[r] >= 0 ? ghosts : own;
  const PetscInt row = ghost[r] >= 0 ? ghost[r] : blk[r] - b0;

  if (!br) return;
  if (fill)
    br->col[br->ptr[row] + br->fill[row]++] = blk[c];
  else
    ++br->ptr[row + 1];
}

/* Counts (fill false) or fills the entries of the local block rows along this rank's edges, each free vertex with
   itself and its free neighbours: an owned vertex's row into own (block row blk - b0), a ghost's into ghosts (its ghost
   number); either may be NULL. blk[], ghost[]: per local vertex, its global block (-1: fixed) and ghost number (-1: owned). */
static PetscErrorCode LocalPattern(DM dm, const PetscInt blk[], const PetscInt ghost[], PetscInt b0, BlockRows *own, BlockRows *ghosts,
                                   PetscBool fill)
{
  PetscInt vStart, vEnd, eStart, eEnd;

  PetscFunctionBeginUser;
  PetscCall(DMPlexGetDepthStratum(dm, 1, &eStart, &eEnd));
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  for (PetscInt v = 0; v < vEnd - vStart; ++v)
    if (blk[v] >= 0) LocalPatternAdd(blk, ghost, b0, own, ghosts, fill, v, v);
  for (PetscInt e = eStart; e < eEnd; ++e) {
    const PetscInt *cone;
    PetscInt        va, vb;

    PetscCall(DMPlexGetCone(dm, e, &cone));
    va = cone[0] - vStart;
    vb = cone[1] - vStart;
    if (blk[va] < 0 || blk[vb] < 0) continue;
    LocalPatternAdd(blk, ghost, b0, own, ghosts, fill, va, vb);
    LocalPatternAdd(blk, ghost, b0, own, ghosts, fill, vb, va);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* at[q]: where rank q's part starts in a buffer of counts[] per rank, in rank order; total: its length. */
static PetscErrorCode RankOffsets(PetscMPIInt size, const PetscMPIInt counts[], PetscInt at[], PetscInt *total)
{
  PetscFunctionBeginUser;
  *total = 0;
  for (PetscMPIInt q = 0; q < size; ++q) {
    at[q] = *total;
    *total += counts[q];
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Sends the ghost rows to their owners in groups by rank (MPI_Alltoallv): sendcounts[] per rank, the data in rank order. */
static PetscErrorCode Exchange(MPI_Comm comm, MPI_Datatype type, const PetscMPIInt sendcounts[], const void *sendbuf, PetscMPIInt **recvcounts,
                               PetscMPIInt **rdispls, void **recvbuf, size_t unit)
{
  PetscMPIInt size, *sdispls, nrecv = 0;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCall(PetscMalloc1(size, &sdispls));
  PetscCall(PetscMalloc1(size, recvcounts));
  PetscCall(PetscMalloc1(size + 1, rdispls));
  PetscCallMPI(MPI_Alltoall(sendcounts, 1, MPI_INT, *recvcounts, 1, MPI_INT, comm));
  sdispls[0]    = 0;
  (*rdispls)[0] = 0;
  for (PetscMPIInt q = 1; q < size; ++q) sdispls[q] = sdispls[q - 1] + sendcounts[q - 1];
  for (PetscMPIInt q = 0; q < size; ++q) (*rdispls)[q + 1] = (*rdispls)[q] + (*recvcounts)[q];
  nrecv = (*rdispls)[size];
  PetscCall(PetscMalloc(unit * (size_t)(nrecv ? nrecv : 1), recvbuf));
  PetscCallMPI(MPI_Alltoallv(sendbuf, sendcounts, sdispls, type, *recvbuf, *recvcounts, *rdispls, type, comm));
  PetscCall(PetscFree(sdispls));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode AssemblyP1CreateMPIAIJ(DM dm, const AssemblyP1Inputs *in, PetscInt nlocal, PetscInt bs, const PetscInt vidx[], const PetscInt cverts[],
                                      Mat *K, PetscBool *done)
{
  MPI_Comm     comm = PetscObjectComm((PetscObject)dm);
  PetscMPIInt  size, *icounts, *scounts, *ircounts, *irdispls, *srcounts, *srdispls;
  PetscInt     dim, cStart, cEnd, vStart, vEnd, rstart, ng = 0, *blk, *ghost, *owner, *ibuf, *irecv, *at, total;
  PetscScalar *sbuf, *srecv, *gval;
  PetscBool    applies;
  SplitRows    s;
  BlockRows    grows;

  PetscFunctionBeginUser;
  *done = PETSC_FALSE;
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(AssemblyP1CSRApplies(dm, bs, in->mat_type_given, &applies));
  if (size == 1 || !applies) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscMemzero(&s, sizeof(s)));
  PetscCall(PetscMemzero(&grows, sizeof(grows)));
  PetscCallMPI(MPI_Scan(&nlocal, &rstart, 1, MPIU_INT, MPI_SUM, comm));
  rstart -= nlocal;
  s.bs = bs;
  s.b0 = rstart / bs;
  s.nb = nlocal / bs;
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));

  /* each free vertex's global block, and for a ghost its number among the ghosts and its owner's rank (the point SF) */
  PetscCall(PetscMalloc3(vEnd - vStart, &blk, vEnd - vStart, &ghost, vEnd - vStart, &owner));
  for (PetscInt v = vStart; v < vEnd; ++v) {
    const PetscInt *g = &vidx[(v - vStart) * dim];

    for (PetscInt e = 0; e < dim; ++e)
      PetscCheck(g[e] == (g[0] < 0 ? -1 : g[0] + e) && (g[0] < 0 || g[0] % bs == 0), PETSC_COMM_SELF, PETSC_ERR_PLIB,
                 "Vertex %" PetscInt_FMT " is not one block", v);
    blk[v - vStart]   = g[0] < 0 ? -1 : g[0] / bs;
    ghost[v - vStart] = -1;
    owner[v - vStart] = -1;
  }
  {
    PetscSF            sf;
    PetscInt           nleaves;
    const PetscInt    *ilocal;
    const PetscSFNode *iremote;

    PetscCall(DMGetPointSF(dm, &sf));
    PetscCall(PetscSFGetGraph(sf, NULL, &nleaves, &ilocal, &iremote));
    for (PetscInt l = 0; l < nleaves; ++l) {
      const PetscInt p = ilocal ? ilocal[l] : l;

      if (p >= vStart && p < vEnd) owner[p - vStart] = iremote[l].rank;
    }
  }
  for (PetscInt v = 0; v < vEnd - vStart; ++v) {
    if (blk[v] < 0 || (blk[v] >= s.b0 && blk[v] < s.b0 + s.nb)) continue;
    PetscCheck(owner[v] >= 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Vertex %" PetscInt_FMT " has another rank's unknowns but no owner in the point SF",
               v + vStart);
    ghost[v] = ng++;
  }

  /* the local block rows along the edges: owned rows into s.rows (with room for what the other ranks send), ghosts into grows */
  PetscCall(BlockRowsCount(&s.rows, s.nb));
  PetscCall(BlockRowsCount(&grows, ng));
  PetscCall(LocalPattern(dm, blk, ghost, s.b0, &s.rows, &grows, PETSC_FALSE));
  PetscCall(BlockRowsAllocate(&grows));
  PetscCall(LocalPattern(dm, blk, ghost, s.b0, NULL, &grows, PETSC_TRUE));
  PetscCall(BlockRowsFinish(&grows));
  /* the ghost rows' patterns to their owners, [block row, n, n block columns] each, and later their values */
  PetscCall(PetscCalloc2(size, &icounts, size, &scounts));
  for (PetscInt v = 0; v < vEnd - vStart; ++v)
    if (ghost[v] >= 0) {
      icounts[owner[v]] += 2 + grows.ptr[ghost[v] + 1] - grows.ptr[ghost[v]];
      scounts[owner[v]] += bs * bs * (grows.ptr[ghost[v] + 1] - grows.ptr[ghost[v]]);
    }
  PetscCall(PetscMalloc1(size, &at));
  PetscCall(RankOffsets(size, icounts, at, &total));
  PetscCall(PetscMalloc1(total ? total : 1, &ibuf));
  for (PetscInt v = 0; v < vEnd - vStart; ++v)
    if (ghost[v] >= 0) {
      const PetscInt g = ghost[v], n = grows.ptr[g + 1] - grows.ptr[g];

      ibuf[at[owner[v]]++] = blk[v];
      ibuf[at[owner[v]]++] = n;
      for (PetscInt k = 0; k < n; ++k) ibuf[at[owner[v]]++] = grows.col[grows.ptr[g] + k];
    }
  PetscCall(Exchange(comm, MPIU_INT, icounts, ibuf, &ircounts, &irdispls, (void **)&irecv, sizeof(PetscInt)));

  /* the owned rows: the local edges and the rows received */
  for (PetscInt q = 0; q < irdispls[size];) {
    const PetscInt r = irecv[q] - s.b0, n = irecv[q + 1];

    PetscCheck(r >= 0 && r < s.nb, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Received block row %" PetscInt_FMT " outside this rank's", irecv[q]);
    s.rows.ptr[r + 1] += n;
    q += 2 + n;
  }
  PetscCall(BlockRowsAllocate(&s.rows));
  PetscCall(LocalPattern(dm, blk, ghost, s.b0, &s.rows, NULL, PETSC_TRUE));
  for (PetscInt q = 0; q < irdispls[size];) {
    const PetscInt r = irecv[q] - s.b0, n = irecv[q + 1];

    for (PetscInt k = 0; k < n; ++k) s.rows.col[s.rows.ptr[r] + s.rows.fill[r]++] = irecv[q + 2 + k];
    q += 2 + n;
  }
  PetscCall(BlockRowsFinish(&s.rows));
  PetscCall(SplitRowsSetUp(&s, nlocal));

  /* the cells' element matrices: owned rows in place, ghost rows into gval (block row by block row, as sent) */
  PetscCall(PetscCalloc1(bs * bs * grows.ptr[ng] + 1, &gval));
  {
    MPIAdd add = {&s, &grows, blk, ghost, gval};

    PetscCall(AssemblyP1CellLoop(dm, in->material, cverts, MPIAddBlock, &add));
  }

  /* the ghost rows' values to their owners, in the order of their patterns */
  PetscCall(RankOffsets(size, scounts, at, &total));
  PetscCall(PetscMalloc1(total ? total : 1, &sbuf));
  for (PetscInt v = 0; v < vEnd - vStart; ++v)
    if (ghost[v] >= 0) {
      const PetscInt g = ghost[v], m = bs * bs * (grows.ptr[g + 1] - grows.ptr[g]);

      PetscCall(PetscArraycpy(&sbuf[at[owner[v]]], &gval[bs * bs * grows.ptr[g]], m));
      at[owner[v]] += m;
    }
  PetscCall(Exchange(comm, MPIU_SCALAR, scounts, sbuf, &srcounts, &srdispls, (void **)&srecv, sizeof(PetscScalar)));
  for (PetscInt q = 0, sq = 0; q < irdispls[size];) {
    const PetscInt r = irecv[q] - s.b0, n = irecv[q + 1];

    for (PetscInt k = 0; k < n; ++k, sq += bs * bs) SplitRowsAdd(&s, r, irecv[q + 2 + k], &srecv[sq], bs);
    q += 2 + n;
  }

  PetscCall(MatCreateMPIAIJWithSplitArrays(comm, nlocal, nlocal, PETSC_DETERMINE, PETSC_DETERMINE, s.i, s.j, s.a, s.oi, s.oj, s.oa, K));
  PetscCall(AssemblyP1CSRCompose(*K, s.i, s.j, s.a, s.oi, s.oj, s.oa));
  PetscCall(MatSetBlockSize(*K, bs));
  PetscCall(MatSetFromOptions(*K));
  *done = PETSC_TRUE;

  PetscCall(PetscFree(at));
  PetscCall(PetscFree3(blk, ghost, owner));
  PetscCall(PetscFree2(icounts, scounts));
  PetscCall(PetscFree(ibuf));
  PetscCall(PetscFree(irecv));
  PetscCall(PetscFree(ircounts));
  PetscCall(PetscFree(irdispls));
  PetscCall(PetscFree(sbuf));
  PetscCall(PetscFree(srecv));
  PetscCall(PetscFree(srcounts));
  PetscCall(PetscFree(srdispls));
  PetscCall(PetscFree(gval));
  PetscCall(BlockRowsDestroy(&grows));
  PetscCall(BlockRowsDestroy(&s.rows));
  PetscCall(PetscFree4(s.nlow, s.ndiag, s.dstart, s.ostart));
  PetscFunctionReturn(PETSC_SUCCESS);
}
