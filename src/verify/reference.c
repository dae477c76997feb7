/* -reference FILE.h5: the error norms of the run against the output of a reference run on the same mesh or on a uniform
   refinement of it (the same coarse mesh with a larger -dm_refine). The run's solution is interpolated to the refined
   mesh (nested P1 spaces: exactly), the reference is matched to it vertex by vertex by position and cell by cell, and
   the norms of error_norms.c are evaluated there with the reference displacement and contact pressure as the target. */
#include <petscdmplextransform.h>
#include <petscviewerhdf5.h>
#include "mesh.h"
#include "obstacle.h"
#include "physics.h"
#include "verify.h"
#include "io.h"
#include "scenes.h"

typedef struct {
  PetscInt   dim, nv, ncells, ncorners;
  PetscReal *x, *u, *p;     /* vertex coordinates, displacement, contact pressure */
  PetscInt  *cells;         /* [ncells][ncorners] vertex indices, each row sorted */
  PetscInt  *cell_first;    /* the smallest vertex of each cell, sorted, */
  PetscInt  *cell_perm;     /*   and the cells in that order */
  PetscReal  lo[3], s, tol; /* bucket grid of the vertices: origin, bucket size, matching tolerance */
  PetscInt   nb[3];
  PetscInt  *key, *perm; /* bucket of each vertex, sorted, and the vertices in that order */
} Reference;

static PetscErrorCode ReadArray(PetscViewer v, const char file[], const char group[], const char name[], PetscInt *n, PetscReal **a)
{
  char               path[PETSC_MAX_PATH_LEN];
  PetscBool          has;
  Vec                x;
  const PetscScalar *xa;

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(path, sizeof(path), "%s/%s", group, name));
  PetscCall(PetscViewerHDF5HasDataset(v, path, &has));
  PetscCheck(has, PETSC_COMM_SELF, PETSC_ERR_USER_INPUT, "Reference file %s has no dataset %s: not an output of this solver", file, path);
  PetscCall(VecCreate(PETSC_COMM_SELF, &x));
  PetscCall(PetscObjectSetName((PetscObject)x, name));
  PetscCall(PetscViewerHDF5PushGroup(v, group));
  PetscCall(VecLoad(x, v));
  PetscCall(PetscViewerHDF5PopGroup(v));
  PetscCall(VecGetLocalSize(x, n));
  PetscCall(PetscMalloc1(PetscMax(*n, 1), a));
  PetscCall(VecGetArrayRead(x, &xa));
  for (PetscInt i = 0; i < *n; ++i) (*a)[i] = PetscRealPart(xa[i]);
  PetscCall(VecRestoreArrayRead(x, &xa));
  PetscCall(VecDestroy(&x));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode ReadIntAttribute(PetscViewer v, const char file[], const char name[], PetscInt *value)
{
  PetscBool has;

  PetscFunctionBeginUser;
  PetscCall(PetscViewerHDF5HasAttribute(v, "/run", name, &has));
  PetscCheck(has, PETSC_COMM_SELF, PETSC_ERR_USER_INPUT, "Reference file %s has no /run attribute %s: not an output of this solver", file, name);
  PetscCall(PetscViewerHDF5ReadAttribute(v, "/run", name, PETSC_INT, NULL, value));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* (key, index) pairs sorted by key, then index: libc qsort (PETSc 3.18's integer sorts slow down on many equal keys) */
typedef struct {
  PetscInt key, index;
} KeyIndex;

static int CompareKeyIndex(const void *a, const void *b)
{
  const KeyIndex *x = (const KeyIndex *)a, *y = (const KeyIndex *)b;

  if (x->key != y->key) return x->key < y->key ? -1 : 1;
  return x->index < y->index ? -1 : (x->index > y->index);
}

static PetscErrorCode SortKeysWithIndices(PetscInt n, PetscInt key[], PetscInt index[])
{
  KeyIndex *ki;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc1(PetscMax(n, 1), &ki));
  for (PetscInt i = 0; i < n; ++i) {
    ki[i].key   = key[i];
    ki[i].index = index[i];
  }
  qsort(ki, (size_t)n, sizeof(KeyIndex), CompareKeyIndex);
  for (PetscInt i = 0; i < n; ++i) {
    key[i]   = ki[i].key;
    index[i] = ki[i].index;
  }
  PetscCall(PetscFree(ki));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static inline PetscInt BucketKey(const Reference *ref, const PetscInt i[])
{
  return (i[0] * ref->nb[1] + i[1]) * ref->nb[2] + i[2];
}

/* Sorts the vertices into buckets and the cells by their smallest vertex, for the searches below. */
static PetscErrorCode ReferenceIndex(Reference *ref)
{
  const PetscInt dim   = ref->dim;
  PetscReal      hi[3] = {0, 0, 0}, diam = 0.0;

  PetscFunctionBeginUser;
  for (PetscInt d = 0; d < 3; ++d) ref->lo[d] = 0.0;
  for (PetscInt d = 0; d < dim; ++d) {
    ref->lo[d] = PETSC_MAX_REAL;
    hi[d]      = PETSC_MIN_REAL;
    for (PetscInt i = 0; i < ref->nv; ++i) {
      ref->lo[d] = PetscMin(ref->lo[d], ref->x[i * dim + d]);
      hi[d]      = PetscMax(hi[d], ref->x[i * dim + d]);
    }
    diam += PetscSqr(hi[d] - ref->lo[d]);
  }
  diam     = PetscSqrtReal(diam);
  ref->tol = 1e-8 * diam;
  ref->s   = diam / PetscPowReal((PetscReal)ref->nv, 1.0 / dim) + 10.0 * ref->tol; /* about one vertex per bucket */
  for (PetscInt d = 0; d < 3; ++d) ref->nb[d] = d < dim ? (PetscInt)((hi[d] - ref->lo[d]) / ref->s) + 1 : 1;
  PetscCall(PetscMalloc2(ref->nv, &ref->key, ref->nv, &ref->perm));
  for (PetscInt i = 0; i < ref->nv; ++i) {
    PetscInt b[3] = {0, 0, 0};

    for (PetscInt d = 0; d < dim; ++d) b[d] = (PetscInt)((ref->x[i * dim + d] - ref->lo[d]) / ref->s);
    ref->key[i]  = BucketKey(ref, b);
    ref->perm[i] = i;
  }
  PetscCall(SortKeysWithIndices(ref->nv, ref->key, ref->perm));
  PetscCall(PetscMalloc2(ref->ncells, &ref->cell_first, ref->ncells, &ref->cell_perm));
  for (PetscInt c = 0; c < ref->ncells; ++c) {
    PetscCall(PetscSortInt(ref->ncorners, &ref->cells[c * ref->ncorners]));
    ref->cell_first[c] = ref->cells[c * ref->ncorners];
    ref->cell_perm[c]  = c;
  }
  PetscCall(SortKeysWithIndices(ref->ncells, ref->cell_first, ref->cell_perm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* First position in the sorted a[0..n) with a[pos] >= value. */
static PetscInt LowerBound(PetscInt n, const PetscInt a[], PetscInt value)
{
  PetscInt lo = 0, hi = n;

  while (lo < hi) {
    const PetscInt mid = (lo + hi) / 2;

    if (a[mid] < value)
      lo = mid + 1;
    else
      hi = mid;
  }
  return lo;
}

/* The reference vertex at position x (within the tolerance), or -1. */
static PetscInt ReferenceFindVertex(const Reference *ref, const PetscReal x[])
{
  const PetscInt dim   = ref->dim;
  PetscInt       lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0}, b[3];

  for (PetscInt d = 0; d < dim; ++d) {
    lo[d] = PetscMax((PetscInt)PetscFloorReal((x[d] - ref->tol - ref->lo[d]) / ref->s), 0);
    hi[d] = PetscMin((PetscInt)PetscFloorReal((x[d] + ref->tol - ref->lo[d]) / ref->s), ref->nb[d] - 1);
  }
  for (b[0] = lo[0]; b[0] <= hi[0]; ++b[0])
    for (b[1] = lo[1]; b[1] <= hi[1]; ++b[1])
      for (b[2] = lo[2]; b[2] <= hi[2]; ++b[2]) {
        const PetscInt key = BucketKey(ref, b);

        for (PetscInt k = LowerBound(ref->nv, ref->key, key); k < ref->nv && ref->key[k] == key; ++k) {
          const PetscInt i  = ref->perm[k];
          PetscReal      d2 = 0.0;

          for (PetscInt d = 0; d < dim; ++d) d2 += PetscSqr(ref->x[i * dim + d] - x[d]);
          if (d2 <= ref->tol * ref->tol) return i;
        }
      }
  return -1;
}

/* Is the sorted tuple v[ncorners] a cell of the reference? */
static PetscBool ReferenceHasCell(const Reference *ref, const PetscInt v[])
{
  for (PetscInt k = LowerBound(ref->ncells, ref->cell_first, v[0]); k < ref->ncells && ref->cell_first[k] == v[0]; ++k) {
    const PetscInt *c    = &ref->cells[ref->cell_perm[k] * ref->ncorners];
    PetscBool       same = PETSC_TRUE;

    for (PetscInt j = 1; j < ref->ncorners; ++j) same = (PetscBool)(same && c[j] == v[j]);
    if (same) return PETSC_TRUE;
  }
  return PETSC_FALSE;
}

/* Every rank reads the whole reference: mesh, displacement and contact pressure at the vertices. */
/* The checks of the reference's /run against this run: same scene and dimension, converged, degree 1. */
/* The reference solved this run's problem: its /run attribute "problem" (scenes/fingerprint.c) equals this run's; the
   message names the first item that differs. */
static PetscErrorCode ReferenceCheckProblem(MPI_Comm comm, const VerifyRun *run, PetscInt dim, PetscViewer v)
{
  const char *file = run->opt->reference;
  char        mine[SCENE_FINGERPRINT_LEN], *theirs = NULL;
  PetscBool   has, same;

  PetscFunctionBeginUser;
  PetscCall(PetscViewerHDF5HasAttribute(v, "/run", "problem", &has));
  PetscCheck(has, comm, PETSC_ERR_USER_INPUT,
             "Reference file %s has no /run attribute problem (written by an older version of the solver): the problem it solved cannot be "
             "compared with this run's; run the reference again",
             file);
  PetscCall(SceneFingerprint(run->scene, run->mat, dim, mine, sizeof(mine)));
  PetscCall(PetscViewerHDF5ReadAttribute(v, "/run", "problem", PETSC_STRING, NULL, &theirs));
  PetscCall(PetscStrcmp(mine, theirs, &same));
  if (!same) {
    char        a[512] = "", b[512] = "";
    const char *p = mine, *q = theirs;

    while (*p || *q) { /* the first differing item, "; "-separated */
      const size_t lp = strcspn(p, ";"), lq = strcspn(q, ";");

      if (lp != lq || strncmp(p, q, lp)) {
        PetscCall(PetscStrncpy(a, p, PetscMin(lp + 1, sizeof(a))));
        PetscCall(PetscStrncpy(b, q, PetscMin(lq + 1, sizeof(b))));
        break;
      }
      p += lp + (p[lp] ? 2 : 0);
      q += lq + (q[lq] ? 2 : 0);
    }
    PetscCall(PetscFree(theirs));
    SETERRQ(comm, PETSC_ERR_USER_INPUT, "Reference %s solved another problem: it has '%s' where this run has '%s'", file, b[0] ? b : "(nothing)",
            a[0] ? a : "(nothing)");
  }
  PetscCall(PetscFree(theirs));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode ReferenceCheckHeader(MPI_Comm comm, const VerifyRun *run, PetscInt dim, PetscViewer v, PetscInt *ref_dim, PetscInt *ncells)
{
  const char *file       = run->opt->reference;
  const char *datasets[] = {"/geometry/vertices", "/vertex_fields/displacement", "/vertex_fields/contact_pressure", "/viz/topology/cells"};
  PetscInt    converged, degree;
  char       *scene = NULL;
  PetscBool   same, has;

  PetscFunctionBeginUser;
  PetscCall(PetscViewerHDF5HasGroup(v, "/run", &has));
  PetscCheck(has, PETSC_COMM_SELF, PETSC_ERR_USER_INPUT, "Reference file %s has no /run group: not an output of this solver", file);
  PetscCall(ReadIntAttribute(v, file, "dim", ref_dim));
  PetscCall(ReadIntAttribute(v, file, "degree", &degree));
  PetscCall(ReadIntAttribute(v, file, "converged", &converged));
  PetscCall(ReadIntAttribute(v, file, "n_cells", ncells));
  PetscCall(PetscViewerHDF5HasAttribute(v, "/run", "scene", &has));
  PetscCheck(has, PETSC_COMM_SELF, PETSC_ERR_USER_INPUT, "Reference file %s has no /run attribute scene: not an output of this solver", file);
  PetscCall(PetscViewerHDF5ReadAttribute(v, "/run", "scene", PETSC_STRING, NULL, &scene));
  PetscCall(PetscStrcmp(scene, run->scene->name, &same));
  PetscCheck(same, comm, PETSC_ERR_USER_INPUT, "Reference %s is a run of scene %s, this is scene %s", file, scene, run->scene->name);
  PetscCall(PetscFree(scene));
  PetscCall(ReferenceCheckProblem(comm, run, dim, v));
  PetscCheck(*ref_dim == dim, comm, PETSC_ERR_USER_INPUT, "Reference %s is %" PetscInt_FMT "D, this run is %" PetscInt_FMT "D", file, *ref_dim, dim);
  PetscCheck(converged == 1, comm, PETSC_ERR_USER_INPUT, "Reference %s did not converge (/run converged = 0)", file);
  PetscCheck(degree == 1 && run->degree == 1, comm, PETSC_ERR_USER_INPUT,
             "-reference needs degree 1 in the run and the reference (they are compared through vertex values); got %" PetscInt_FMT
             " and %" PetscInt_FMT,
             run->degree, degree);
  for (size_t i = 0; i < sizeof(datasets) / sizeof(datasets[0]); ++i) {
    PetscCall(PetscViewerHDF5HasDataset(v, datasets[i], &has));
    PetscCheck(has, PETSC_COMM_SELF, PETSC_ERR_USER_INPUT, "Reference file %s has no dataset %s: not an output of this solver", file, datasets[i]);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Before the solve: the -reference file (if any) opens as HDF5 and fits this run (ReferenceCheckHeader()). */
PetscErrorCode ReferenceCheckFile(DM dm, const VerifyRun *run)
{
  const char    *file = run->opt->reference;
  PetscViewer    v;
  PetscInt       dim, ref_dim, ncells;
  PetscErrorCode ierr;
  int            cwd;
  char           base[PETSC_MAX_PATH_LEN];

  PetscFunctionBeginUser;
  if (!file[0]) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(OutputFileEnterDirectory(file, &cwd, base, sizeof(base)));
  PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  ierr = PetscViewerHDF5Open(PETSC_COMM_SELF, base, FILE_MODE_READ, &v);
  PetscCall(PetscPopErrorHandler());
  if (ierr) PetscCall(OutputFileLeaveDirectory(cwd));
  PetscCheck(!ierr, PETSC_COMM_SELF, PETSC_ERR_FILE_OPEN, "Reference file '%s' (-reference) cannot be opened as an HDF5 file", file);
  PetscCall(ReferenceCheckHeader(PetscObjectComm((PetscObject)dm), run, dim, v, &ref_dim, &ncells));
  PetscCall(PetscViewerDestroy(&v));
  PetscCall(OutputFileLeaveDirectory(cwd));
  { /* the reference's mesh is this one refined uniformly (the final mesh of nested iteration too: this one refined) */
    PetscInt cStart, cEnd, mine, levels = 0;

    PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
    PetscCall(MeshCountOwned(dm, cStart, cEnd, &mine));
    while ((PetscInt64)mine << (dim * levels) < (PetscInt64)ncells && levels < 12) ++levels;
    PetscCheck((PetscInt64)mine << (dim * levels) == (PetscInt64)ncells, PetscObjectComm((PetscObject)dm), PETSC_ERR_USER_INPUT,
               "Reference %s has %" PetscInt_FMT " cells, which is not this mesh (%" PetscInt_FMT " cells) uniformly refined", file, ncells, mine);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode ReferenceRead(MPI_Comm comm, const VerifyRun *run, PetscInt dim, Reference *ref)
{
  const char *file = run->opt->reference;
  PetscViewer v;
  PetscInt    n;
  PetscReal  *cells;
  int         cwd;
  char        base[PETSC_MAX_PATH_LEN];

  PetscFunctionBeginUser;
  PetscCall(PetscMemzero(ref, sizeof(*ref)));
  PetscCall(OutputFileEnterDirectory(file, &cwd, base, sizeof(base))); /* read by its short name */
  PetscCall(PetscViewerHDF5Open(PETSC_COMM_SELF, base, FILE_MODE_READ, &v));
  PetscCall(ReferenceCheckHeader(comm, run, dim, v, &ref->dim, &ref->ncells));
  PetscCall(ReadArray(v, file, "/geometry", "vertices", &n, &ref->x));
  ref->nv = n / dim;
  PetscCall(ReadArray(v, file, "/vertex_fields", "displacement", &n, &ref->u));
  PetscCheck(n == ref->nv * dim, comm, PETSC_ERR_USER_INPUT,
             "Reference %s: displacement has %" PetscInt_FMT " entries for %" PetscInt_FMT " vertices", file, n, ref->nv);
  PetscCall(ReadArray(v, file, "/vertex_fields", "contact_pressure", &n, &ref->p));
  PetscCheck(n == ref->nv, comm, PETSC_ERR_USER_INPUT, "Reference %s: contact_pressure has %" PetscInt_FMT " entries for %" PetscInt_FMT " vertices",
             file, n, ref->nv);
  PetscCall(ReadArray(v, file, "/viz/topology", "cells", &n, &cells));
  PetscCheck(ref->ncells > 0 && n % ref->ncells == 0, comm, PETSC_ERR_USER_INPUT,
             "Reference %s: /viz/topology/cells does not hold %" PetscInt_FMT " cells", file, ref->ncells);
  ref->ncorners = n / ref->ncells;
  PetscCall(PetscMalloc1(n, &ref->cells));
  for (PetscInt i = 0; i < n; ++i) ref->cells[i] = (PetscInt)cells[i];
  PetscCall(PetscFree(cells));
  PetscCall(PetscViewerDestroy(&v));
  PetscCall(OutputFileLeaveDirectory(cwd));
  PetscCall(ReferenceIndex(ref));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode ReferenceDestroy(Reference *ref)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree(ref->x));
  PetscCall(PetscFree(ref->u));
  PetscCall(PetscFree(ref->p));
  PetscCall(PetscFree(ref->cells));
  PetscCall(PetscFree2(ref->cell_first, ref->cell_perm));
  PetscCall(PetscFree2(ref->key, ref->perm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Refines dm `levels` times (regular refinement) into fine, with the run's discretization and boundary conditions, and
   interpolates the local vectors loc[] (boundary values included) to fine_loc[]. */
static PetscErrorCode RefineAndInterpolate(DM dm, PetscInt levels, PetscInt nvec, Vec loc[], DM *fine, Vec fine_loc[], PetscReal **run_cell_h)
{
  PetscInt *parent, cStart, cEnd;

  PetscFunctionBeginUser;
  PetscCall(MeshRefineRegular(dm, levels, fine, &parent, NULL));
  PetscCall(DMCopyDisc(dm, *fine)); /* the run's field, weak form and boundary conditions */
  PetscCall(MeshInterpolateFromParents(dm, *fine, parent, nvec, loc, fine_loc));
  PetscCall(DMPlexGetHeightStratum(*fine, 0, &cStart, &cEnd));
  PetscCall(PetscMalloc1(cEnd - cStart + 1, run_cell_h)); /* each fine cell: the diameter of the run's cell holding it */
  {
    PetscInt   rStart, rEnd;
    PetscReal *diam;

    PetscCall(DMPlexGetHeightStratum(dm, 0, &rStart, &rEnd));
    PetscCall(PetscMalloc1(rEnd - rStart + 1, &diam));
    for (PetscInt c = rStart; c < rEnd; ++c) PetscCall(MeshCellDiameter(dm, c, &diam[c - rStart]));
    for (PetscInt c = cStart; c < cEnd; ++c) (*run_cell_h)[c - cStart] = diam[parent[c - cStart] - rStart];
    PetscCall(PetscFree(diam));
  }
  PetscCall(PetscFree(parent));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Fills the reference displacement and pressure (as p n) into local vectors of fine, vertex by vertex, after checking
   that every vertex and cell of fine is one of the reference. */
static PetscErrorCode MatchReference(DM fine, const VerifyRun *run, const Reference *ref, Vec loc_u, Vec loc_p)
{
  MPI_Comm           comm = PetscObjectComm((PetscObject)fine);
  const PetscInt     dim  = ref->dim;
  DM                 cdm;
  PetscSection       lsec, csec;
  Vec                coords;
  const PetscScalar *xc;
  PetscScalar       *u, *p;
  PetscInt           vStart, vEnd, cStart, cEnd, *vmap, bad_vertex = -1, bad_cell = -1, nbad[2], lbad[2];

  PetscFunctionBeginUser;
  PetscCall(DMGetLocalSection(fine, &lsec));
  PetscCall(DMGetCoordinateDM(fine, &cdm));
  PetscCall(DMGetLocalSection(cdm, &csec));
  PetscCall(DMGetCoordinatesLocal(fine, &coords));
  PetscCall(DMPlexGetDepthStratum(fine, 0, &vStart, &vEnd));
  PetscCall(DMPlexGetHeightStratum(fine, 0, &cStart, &cEnd));
  PetscCall(PetscMalloc1(vEnd - vStart, &vmap));
  PetscCall(VecZeroEntries(loc_u));
  PetscCall(VecZeroEntries(loc_p));
  PetscCall(VecGetArrayRead(coords, &xc));
  PetscCall(VecGetArray(loc_u, &u));
  PetscCall(VecGetArray(loc_p, &p));
  for (PetscInt v = vStart; v < vEnd; ++v) {
    PetscInt  coff, off, i;
    PetscReal x[3], n[3], gap;

    PetscCall(PetscSectionGetOffset(csec, v, &coff));
    for (PetscInt d = 0; d < dim; ++d) x[d] = PetscRealPart(xc[coff + d]);
    ObstacleGapNormalAt(&run->scene->obstacle, dim, x, n, &gap);
    i                = ReferenceFindVertex(ref, x);
    vmap[v - vStart] = i;
    if (i < 0) {
      if (bad_vertex < 0) bad_vertex = v;
      continue;
    }
    PetscCall(PetscSectionGetOffset(lsec, v, &off));
    for (PetscInt d = 0; d < dim; ++d) {
      u[off + d] = ref->u[i * dim + d];
      p[off + d] = ref->p[i] * n[d];
    }
  }
  PetscCall(VecRestoreArray(loc_p, &p));
  PetscCall(VecRestoreArray(loc_u, &u));
  PetscCall(VecRestoreArrayRead(coords, &xc));
  for (PetscInt c = cStart; c < cEnd && bad_vertex < 0; ++c) {
    PetscInt nv, verts[8];

    PetscCall(MeshCellVertices(fine, c, verts, &nv));
    for (PetscInt i = 0; i < nv; ++i) verts[i] = vmap[verts[i] - vStart];
    PetscCall(PetscSortInt(nv, verts));
    if (nv != ref->ncorners || !ReferenceHasCell(ref, verts)) {
      bad_cell = c;
      break;
    }
  }
  PetscCall(PetscFree(vmap));
  lbad[0] = bad_vertex >= 0;
  lbad[1] = bad_cell >= 0;
  PetscCall(MPIU_Allreduce(lbad, nbad, 2, MPIU_INT, MPI_SUM, comm));
  PetscCheck(!nbad[0], comm, PETSC_ERR_USER_INPUT,
             "Reference %s does not match: a vertex of this mesh refined is not one of its vertices. Run the reference on the same coarse mesh "
             "with a larger -dm_refine",
             run->opt->reference);
  PetscCheck(!nbad[1], comm, PETSC_ERR_USER_INPUT,
             "Reference %s does not match: its vertices are those of this mesh refined, but not its cells. Run the reference on the same coarse "
             "mesh with a larger -dm_refine",
             run->opt->reference);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The norms of the run against the -reference solution into *e (NaN without -reference). */
PetscErrorCode ReferenceCompute(DM dm, const VerifyRun *run, Vec u, ErrorNorms *e)
{
  MPI_Comm            comm = PetscObjectComm((PetscObject)dm);
  Reference           ref;
  PetscInt            dim, cStart, cEnd, ncells, levels = 0, nvec;
  ContactPressureForm form;
  DM                  fine;
  Vec                 loc[2], fine_loc[2], loc_uref, loc_pref;
  Mat                 K;
  ErrorTarget         target;
  PetscReal          *run_cell_h;

  PetscFunctionBeginUser;
  PetscCall(ErrorNormsReset(e));
  if (!run->opt->reference[0]) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(ReferenceRead(comm, run, dim, &ref));
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  PetscCall(MeshCountOwned(dm, cStart, cEnd, &ncells));
  while ((PetscInt64)ncells << (dim * levels) < (PetscInt64)ref.ncells && levels < 8) ++levels;
  PetscCheck((PetscInt64)ncells << (dim * levels) == (PetscInt64)ref.ncells, comm, PETSC_ERR_USER_INPUT,
             "Reference %s has %" PetscInt_FMT " cells, which is not this mesh (%" PetscInt_FMT " cells) uniformly refined", run->opt->reference,
             ref.ncells, ncells);

  /* the run's displacement and, without the penalty law, its nodal pressure, on the refined mesh */
  PetscCall(ContactGetPressureForm(run->contact, &form));
  nvec = form.law ? 1 : 2;
  PetscCall(DMCreateLocalVector(dm, &loc[0]));
  PetscCall(VecCopy(run->loc_bc, loc[0])); /* the Dirichlet values, inserted by ProblemSetUp() */
  PetscCall(DMGlobalToLocal(dm, u, INSERT_VALUES, loc[0]));
  if (nvec == 2) {
    PetscCall(DMCreateLocalVector(dm, &loc[1]));
    PetscCall(ErrorNormsPressureVector(dm, run->contact, loc[1]));
  }
  PetscCall(RefineAndInterpolate(dm, levels, nvec, loc, &fine, fine_loc, &run_cell_h));
  for (PetscInt k = 0; k < nvec; ++k) PetscCall(VecDestroy(&loc[k]));

  PetscCall(DMCreateLocalVector(fine, &loc_uref));
  PetscCall(DMCreateLocalVector(fine, &loc_pref));
  PetscCall(MatchReference(fine, run, &ref, loc_uref, loc_pref));
  PetscCall(ReferenceDestroy(&ref));

  if (levels == 0)
    PetscCall(ContactBulkOperator(run->contact, run->K, &K)); /* the run's bulk operator, K read only */
  else {
    Vec locX;

    PetscCall(DMCreateMatrix(fine, &K));
    PetscCall(DMGetLocalVector(fine, &locX));
    PetscCall(VecZeroEntries(locX));
    PetscCall(DMPlexSNESComputeJacobianFEM(fine, locX, K, K, NULL)); /* the weak form's kernels read the constants of the DS, no context */
    PetscCall(DMRestoreLocalVector(fine, &locX));
    PetscCall(MatAssemblyBegin(K, MAT_FINAL_ASSEMBLY));
    PetscCall(MatAssemblyEnd(K, MAT_FINAL_ASSEMBLY));
  }
  target.scene        = NULL;
  target.loc_u        = loc_uref;
  target.loc_pressure = loc_pref;
  PetscCall(ErrorNormsEvaluate(fine, run_cell_h, run, K, fine_loc[0], nvec == 2 ? fine_loc[1] : NULL, &target, e));
  PetscCall(PetscFree(run_cell_h));
  PetscCall(PetscInfo(dm, "Reference %s: %" PetscInt_FMT " refinement(s)\n", run->opt->reference, levels));

  PetscCall(MatDestroy(&K));
  for (PetscInt k = 0; k < nvec; ++k) PetscCall(VecDestroy(&fine_loc[k]));
  PetscCall(VecDestroy(&loc_uref));
  PetscCall(VecDestroy(&loc_pref));
  PetscCall(DMDestroy(&fine));
  PetscFunctionReturn(PETSC_SUCCESS);
}
