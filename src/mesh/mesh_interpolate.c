/* The interpolated topology of a simplex mesh (cells, faces, edges, vertices) built directly from its cell list, with
   the points, cones and orientations that DMPlexInterpolate() gives: new faces numbered in the order the cells first
   meet them, each face's cone the first cell's raw face, edges after faces. PETSc 3.18 finds faces through a generic hash
   table and a cell-type label lookup per point; here a face is found among the few faces whose smallest vertex is the
   same (a bucket per vertex), with no hash table and no label lookup.
   One of PETSc 3.18's mirrors (docs/decisions.md, "PETSc 3.18's mirrors"). */
#include <stdlib.h>
#include <petscsf.h>
#include "mesh.h"

/* The raw faces of a triangle (segments) and of a tetrahedron (triangles), as DMPlexGetRawFaces_Internal() lists them. */
static const PetscInt tri_faces[3][2] = {{0, 1}, {1, 2}, {2, 0}};
static const PetscInt tet_faces[4][3] = {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {2, 1, 3}};

static void SortKey(PetscInt n, PetscInt k[])
{
  for (PetscInt i = 1; i < n; ++i)
    for (PetscInt j = i; j > 0 && k[j - 1] > k[j]; --j) {
      const PetscInt t = k[j];
      k[j]             = k[j - 1];
      k[j - 1]         = t;
    }
}

/* DMPolytopeGetVertexOrientation() inlined (PETSc's search over the arrangements, in the same order): the orientation
   o of the cone target of type ct relative to source, target[c] = source[arrangement(o)[c]]; -1 - nO if none. */
static inline PetscInt VertexOrientation(DMPolytopeType ct, const PetscInt source[], const PetscInt target[])
{
  const PetscInt cS = DMPolytopeTypeGetNumVertices(ct), nO = DMPolytopeTypeGetNumArrangments(ct) / 2;

  if (!nO) return 0;
  for (PetscInt o = -nO; o < nO; ++o) {
    const PetscInt *arr = DMPolytopeTypeGetVertexArrangment(ct, o);
    PetscInt        c;

    for (c = 0; c < cS; ++c)
      if (source[arr[c]] != target[c]) break;
    if (c == cS) return o;
  }
  return -1 - nO;
}

/* One interpolation step: the nsrc sources (cells, or the faces of a tetrahedral mesh), each with the vertex list
   src[s * (fs + 1) .. ] of a simplex of fs + 1 vertices, get their fs + 1 faces of fs vertices (the vertices are points
   vbase .. vbase + nv - 1). Out: the number of new faces, their vertex cones (first met), and per source its faces
   (numbered from first) and their orientations. */
static PetscErrorCode InterpolateStep(PetscInt nsrc, PetscInt fs, const PetscInt src[], PetscInt vbase, PetscInt nv, PetscInt first,
                                      const MeshInterface *itf, PetscBool edges, PetscInt *nnew, PetscInt **new_cones, PetscInt face[],
                                      PetscInt ornt[])
{
  const PetscInt       nf = fs + 1;
  const DMPolytopeType ft = fs == 2 ? DM_POLYTOPE_SEGMENT : DM_POLYTOPE_TRIANGLE;
  PetscInt            *start, *fill, *bkey, *bid, *cones, *met, n = 0;

  PetscFunctionBeginUser;
  PetscCall(PetscCalloc2(nv + 1, &start, nv, &fill));
  PetscCall(PetscMalloc3(nsrc * nf * (fs - 1), &bkey, nsrc * nf, &bid, nsrc * nf * fs, &cones));
  for (PetscInt s = 0; s < nsrc; ++s) /* count the faces met per smallest vertex */
    for (PetscInt lf = 0; lf < nf; ++lf) {
      PetscInt v = PETSC_MAX_INT;

      for (PetscInt i = 0; i < fs; ++i) v = PetscMin(v, src[s * nf + (fs == 2 ? tri_faces[lf][i] : tet_faces[lf][i])]);
      PetscCheck(v >= vbase && v < vbase + nv, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
                 "Vertex %" PetscInt_FMT " of simplex %" PetscInt_FMT " is not in [%" PetscInt_FMT ", %" PetscInt_FMT ")", v, s, vbase, vbase + nv);
      ++start[v - vbase + 1];
    }
  for (PetscInt v = 0; v < nv; ++v) start[v + 1] += start[v];
  for (PetscInt s = 0; s < nsrc; ++s)
    for (PetscInt lf = 0; lf < nf; ++lf) {
      PetscInt raw[3], key[3], b, id = -1;

      for (PetscInt i = 0; i < fs; ++i) raw[i] = key[i] = src[s * nf + (fs == 2 ? tri_faces[lf][i] : tet_faces[lf][i])];
      SortKey(fs, key);
      b = key[0] - vbase;
      for (PetscInt e = start[b]; e < start[b] + fill[b]; ++e)
        if (bkey[e * (fs - 1)] == key[1] && (fs == 2 || bkey[e * (fs - 1) + 1] == key[2])) {
          id = bid[e];
          break;
        }
      if (id < 0) {
        const PetscInt e = start[b] + fill[b]++;

        for (PetscInt i = 1; i < fs; ++i) bkey[e * (fs - 1) + i - 1] = key[i];
        id = bid[e] = n++;
        for (PetscInt i = 0; i < fs; ++i) cones[id * fs + i] = raw[i];
      }
      face[s * nf + lf] = first + id;
    }
  /* On a distributed mesh, a face that may be shared with another rank gets the same cone on every rank: its vertices
     ordered by global number. Those are the faces met by one local cell, with all their vertices shared, that are not on
     the domain's boundary (where the first cell's raw face, PETSc's choice, is kept: it fixes where PETSc evaluates a
     boundary integral); and, in 3D, every edge of shared vertices. */
  if (itf) {
    PetscCall(PetscCalloc1(n, &met));
    for (PetscInt i = 0; i < nsrc * nf; ++i) ++met[face[i] - first];
    for (PetscInt id = 0; id < n; ++id) {
      PetscInt *c          = &cones[id * fs], g[3];
      PetscBool all_shared = PETSC_TRUE;

      for (PetscInt i = 0; i < fs; ++i) {
        all_shared = (PetscBool)(all_shared && itf->shared[c[i] - vbase]);
        g[i]       = itf->gid[c[i] - vbase];
      }
      if (!all_shared || (!edges && (met[id] != 1 || itf->on_boundary(fs, g, itf->ctx)))) continue;
      for (PetscInt i = 1; i < fs; ++i) /* sort the cone by global vertex number */
        for (PetscInt j = i; j > 0 && itf->gid[c[j - 1] - vbase] > itf->gid[c[j] - vbase]; --j) {
          const PetscInt t = c[j];
          c[j]             = c[j - 1];
          c[j - 1]         = t;
        }
    }
    PetscCall(PetscFree(met));
  }
  for (PetscInt s = 0; s < nsrc; ++s)
    for (PetscInt lf = 0; lf < nf; ++lf) {
      PetscInt raw[3];

      for (PetscInt i = 0; i < fs; ++i) raw[i] = src[s * nf + (fs == 2 ? tri_faces[lf][i] : tet_faces[lf][i])];
      ornt[s * nf + lf] = VertexOrientation(ft, &cones[(face[s * nf + lf] - first) * fs], raw);
      PetscCheck(ornt[s * nf + lf] >= -DMPolytopeTypeGetNumArrangments(ft) / 2, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                 "No orientation of face %" PetscInt_FMT " in simplex %" PetscInt_FMT, face[s * nf + lf], s);
    }
  PetscCall(PetscFree2(start, fill));
  PetscCall(PetscMalloc1(n * fs, new_cones));
  PetscCall(PetscArraycpy(*new_cones, cones, n * fs));
  PetscCall(PetscFree3(bkey, bid, cones));
  *nnew = n;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The interpolated DMPlex (topology and cell types, no coordinates) of ncells simplices of dimension dim (2 or 3) on
   vertices 0 .. nverts - 1, cells[c * (dim + 1) + i] the vertices of cell c: cells are points 0 .. ncells - 1, vertices
   follow, then faces, then (3D) edges, as DMPlexCreateFromCellListPetsc() with interpolation numbers them. */
PetscErrorCode MeshCreateInterpolatedSimplices(MPI_Comm comm, PetscInt dim, PetscInt ncells, PetscInt nverts, const PetscInt cells[],
                                               const MeshInterface *itf, DM *dm)
{
  const PetscInt nc = dim + 1, vbase = ncells;
  PetscInt      *src, *cell_face, *cell_ornt, *faces_v = NULL, *face_edge = NULL, *face_ornt = NULL, *edges_v = NULL;
  PetscInt       nfaces = 0, nedges = 0, fbase, ebase, npoints, *cones, *ornts;
  DMLabel        celltype;

  PetscFunctionBeginUser;
  PetscCheck(dim == 2 || dim == 3, comm, PETSC_ERR_SUP, "Simplex meshes of dimension 2 or 3, not %" PetscInt_FMT, dim);
  PetscCall(PetscMalloc3(ncells * nc, &src, ncells * nc, &cell_face, ncells * nc, &cell_ornt));
  for (PetscInt i = 0; i < ncells * nc; ++i) src[i] = cells[i] + vbase;
  fbase = ncells + nverts;
  PetscCall(InterpolateStep(ncells, dim, src, vbase, nverts, fbase, itf, PETSC_FALSE, &nfaces, &faces_v, cell_face, cell_ornt));
  ebase = fbase + nfaces;
  if (dim == 3) {
    PetscCall(PetscMalloc2(nfaces * 3, &face_edge, nfaces * 3, &face_ornt));
    PetscCall(InterpolateStep(nfaces, 2, faces_v, vbase, nverts, ebase, itf, PETSC_TRUE, &nedges, &edges_v, face_edge, face_ornt));
  }
  npoints = ebase + nedges;

  PetscCall(DMCreate(comm, dm));
  PetscCall(DMSetType(*dm, DMPLEX));
  PetscCall(DMSetDimension(*dm, dim));
  PetscCall(DMPlexSetChart(*dm, 0, npoints));
  for (PetscInt c = 0; c < ncells; ++c) PetscCall(DMPlexSetConeSize(*dm, c, nc));
  for (PetscInt f = fbase; f < ebase; ++f) PetscCall(DMPlexSetConeSize(*dm, f, dim == 3 ? 3 : 2));
  for (PetscInt e = ebase; e < npoints; ++e) PetscCall(DMPlexSetConeSize(*dm, e, 2));
  PetscCall(DMSetUp(*dm));
  /* the cones are stored in point order: cells, (vertices: none), faces, edges */
  PetscCall(DMPlexGetCones(*dm, &cones));
  PetscCall(DMPlexGetConeOrientations(*dm, &ornts));
  PetscCall(PetscArraycpy(cones, cell_face, ncells * nc));
  PetscCall(PetscArraycpy(ornts, cell_ornt, ncells * nc));
  cones += ncells * nc;
  ornts += ncells * nc;
  if (dim == 2) {
    PetscCall(PetscArraycpy(cones, faces_v, nfaces * 2));
    PetscCall(PetscArrayzero(ornts, nfaces * 2));
  } else {
    PetscCall(PetscArraycpy(cones, face_edge, nfaces * 3));
    PetscCall(PetscArraycpy(ornts, face_ornt, nfaces * 3));
    PetscCall(PetscArraycpy(cones + nfaces * 3, edges_v, nedges * 2));
    PetscCall(PetscArrayzero(ornts + nfaces * 3, nedges * 2));
  }
  PetscCall(PetscFree3(src, cell_face, cell_ornt));
  PetscCall(PetscFree(faces_v));
  PetscCall(PetscFree2(face_edge, face_ornt));
  PetscCall(PetscFree(edges_v));
  /* the cell types before the stratification, as DMPlexInterpolate() sets them; each type is a range of points */
  PetscCall(DMCreateLabel(*dm, "celltype"));
  PetscCall(DMPlexGetCellTypeLabel(*dm, &celltype));
  PetscCall(DMLabelSetStratumBounds(celltype, dim == 2 ? DM_POLYTOPE_TRIANGLE : DM_POLYTOPE_TETRAHEDRON, 0, ncells));
  PetscCall(DMLabelSetStratumBounds(celltype, DM_POLYTOPE_POINT, vbase, fbase));
  PetscCall(DMLabelSetStratumBounds(celltype, dim == 2 ? DM_POLYTOPE_SEGMENT : DM_POLYTOPE_TRIANGLE, fbase, ebase));
  if (dim == 3) PetscCall(DMLabelSetStratumBounds(celltype, DM_POLYTOPE_SEGMENT, ebase, npoints));
  PetscCall(DMPlexSymmetrize(*dm));
  PetscCall(DMPlexStratify(*dm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* How two meshes' topologies differ (for checks): the number of differing chart ends, cone and support sizes, cone and
   support entries, cone orientations, cell types, depths and vertex coordinates, out of the number compared. */
PetscErrorCode MeshCompareTopology(DM a, DM b, PetscInt *differences, PetscInt *compared)
{
  PetscInt pStart, pEnd, pStartB, pEndB, n = 0, m = 0;
  Vec      xa, xb;

  PetscFunctionBeginUser;
  PetscCall(DMPlexGetChart(a, &pStart, &pEnd));
  PetscCall(DMPlexGetChart(b, &pStartB, &pEndB));
  n += (pStart != pStartB) + (pEnd != pEndB);
  m += 2;
  for (PetscInt p = pStart; p < PetscMin(pEnd, pEndB); ++p) {
    const PetscInt *ca, *cb, *oa, *ob, *sa, *sb;
    PetscInt        nca, ncb, nsa, nsb, da, db;
    DMPolytopeType  ta, tb;

    PetscCall(DMPlexGetConeSize(a, p, &nca));
    PetscCall(DMPlexGetConeSize(b, p, &ncb));
    PetscCall(DMPlexGetCone(a, p, &ca));
    PetscCall(DMPlexGetCone(b, p, &cb));
    PetscCall(DMPlexGetConeOrientation(a, p, &oa));
    PetscCall(DMPlexGetConeOrientation(b, p, &ob));
    PetscCall(DMPlexGetSupportSize(a, p, &nsa));
    PetscCall(DMPlexGetSupportSize(b, p, &nsb));
    PetscCall(DMPlexGetSupport(a, p, &sa));
    PetscCall(DMPlexGetSupport(b, p, &sb));
    PetscCall(DMPlexGetCellType(a, p, &ta));
    PetscCall(DMPlexGetCellType(b, p, &tb));
    PetscCall(DMPlexGetPointDepth(a, p, &da));
    PetscCall(DMPlexGetPointDepth(b, p, &db));
    n += (nca != ncb) + (nsa != nsb) + (ta != tb) + (da != db);
    m += 4;
    for (PetscInt i = 0; i < PetscMin(nca, ncb); ++i) n += (ca[i] != cb[i]) + (oa[i] != ob[i]);
    for (PetscInt i = 0; i < PetscMin(nsa, nsb); ++i) n += sa[i] != sb[i];
    m += 2 * PetscMin(nca, ncb) + PetscMin(nsa, nsb);
  }
  PetscCall(DMGetCoordinatesLocal(a, &xa));
  PetscCall(DMGetCoordinatesLocal(b, &xb));
  {
    const PetscScalar *va, *vb;
    PetscInt           na, nb;

    PetscCall(VecGetLocalSize(xa, &na));
    PetscCall(VecGetLocalSize(xb, &nb));
    n += na != nb;
    m += 1;
    PetscCall(VecGetArrayRead(xa, &va));
    PetscCall(VecGetArrayRead(xb, &vb));
    for (PetscInt i = 0; i < PetscMin(na, nb); ++i) n += va[i] != vb[i];
    m += PetscMin(na, nb);
    PetscCall(VecRestoreArrayRead(xa, &va));
    PetscCall(VecRestoreArrayRead(xb, &vb));
  }
  *differences = n;
  *compared    = m;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A point shared with other ranks, by the sorted global numbers of its vertices. */
typedef struct {
  PetscInt key[3], point;
} SharedCandidate;

static int CompareCandidates(const void *a, const void *b)
{
  const SharedCandidate *x = (const SharedCandidate *)a, *y = (const SharedCandidate *)b;

  for (PetscInt i = 0; i < 3; ++i)
    if (x->key[i] != y->key[i]) return x->key[i] < y->key[i] ? -1 : 1;
  return 0;
}

/* The faces and edges of the distributed mesh dm (vertices vStart .. vEnd - 1, gid their global numbers, shared: on
   other ranks too) that another rank also has, found by their vertices' global numbers: each rank sends its candidates
   (points of shared vertices only) to all; the lowest rank holding a point owns it. Out: the point SF, the leaves of the
   uninterpolated mesh's point SF vsf (its vertices, numbered as in dm) plus those points. */
static PetscErrorCode InterfacePointSF(DM dm, PetscSF vsf, const PetscInt gid[], const PetscBool shared[], PetscSF *sf)
{
  MPI_Comm           comm;
  PetscMPIInt        rank, size, *counts, *displs;
  PetscInt           vStart, vEnd, pStart, pEnd, ncand = 0, nall, nvleaves, nleaves = 0, *owner_rank, *owner_point, *ilocal;
  const PetscInt    *vlocal;
  const PetscSFNode *vremote;
  PetscSFNode       *iremote;
  SharedCandidate   *cand, *all;

  PetscFunctionBeginUser;
  PetscCall(PetscObjectGetComm((PetscObject)dm, &comm));
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  PetscCall(DMPlexGetChart(dm, &pStart, &pEnd));
  PetscCall(PetscMalloc1(pEnd - vEnd, &cand));
  for (PetscInt p = vEnd; p < pEnd; ++p) { /* faces and edges */
    const PetscInt *cone;
    PetscInt        ncone, nv = 0;
    SharedCandidate c          = {{-1, -1, -1}, p};
    PetscBool       all_shared = PETSC_TRUE;

    PetscCall(DMPlexGetConeSize(dm, p, &ncone));
    PetscCall(DMPlexGetCone(dm, p, &cone));
    for (PetscInt i = 0; i < ncone && all_shared; ++i) { /* the vertices: the cone, or the cones of a face's edges */
      const PetscInt *sub  = &cone[i];
      PetscInt        nsub = 1;

      if (cone[i] < vStart || cone[i] >= vEnd) {
        PetscCall(DMPlexGetCone(dm, cone[i], &sub));
        nsub = 2;
      }
      for (PetscInt j = 0; j < nsub; ++j) {
        const PetscInt q    = sub[j];
        PetscBool      seen = PETSC_FALSE;

        all_shared = (PetscBool)(all_shared && shared[q - vStart]);
        for (PetscInt k = 0; k < nv; ++k) seen = (PetscBool)(seen || c.key[k] == gid[q - vStart]);
        if (!seen && nv < 3) c.key[nv++] = gid[q - vStart];
      }
    }
    if (!all_shared) continue;
    SortKey(nv, c.key);
    cand[ncand++] = c;
  }
  PetscCall(PetscMalloc2(size, &counts, size, &displs));
  {
    PetscMPIInt n = (PetscMPIInt)(ncand * 4);

    PetscCallMPI(MPI_Allgather(&n, 1, MPI_INT, counts, 1, MPI_INT, comm));
  }
  displs[0] = 0;
  for (PetscMPIInt r = 1; r < size; ++r) displs[r] = displs[r - 1] + counts[r - 1];
  nall = (displs[size - 1] + counts[size - 1]) / 4;
  PetscCall(PetscMalloc1(nall, &all));
  PetscCallMPI(MPI_Allgatherv(cand, (PetscMPIInt)(ncand * 4), MPIU_INT, all, counts, displs, MPIU_INT, comm));
  qsort(cand, (size_t)ncand, sizeof(SharedCandidate), CompareCandidates);
  PetscCall(PetscMalloc2(ncand, &owner_rank, ncand, &owner_point));
  for (PetscInt k = 0; k < ncand; ++k) {
    owner_rank[k]  = rank;
    owner_point[k] = cand[k].point;
  }
  for (PetscMPIInt r = 0; r < rank; ++r) /* only a lower rank can own one of this rank's points */
    for (PetscInt j = displs[r] / 4; j < (displs[r] + counts[r]) / 4; ++j) {
      const SharedCandidate *hit = (const SharedCandidate *)bsearch(&all[j], cand, (size_t)ncand, sizeof(SharedCandidate), CompareCandidates);

      if (hit && owner_rank[hit - cand] > r) {
        owner_rank[hit - cand]  = r;
        owner_point[hit - cand] = all[j].point;
      }
    }
  PetscCall(PetscSFGetGraph(vsf, NULL, &nvleaves, &vlocal, &vremote));
  for (PetscInt k = 0; k < ncand; ++k) nleaves += owner_rank[k] != rank;
  PetscCall(PetscMalloc1(nvleaves + nleaves, &ilocal));
  PetscCall(PetscMalloc1(nvleaves + nleaves, &iremote));
  for (PetscInt l = 0; l < nvleaves; ++l) {
    ilocal[l]  = vlocal ? vlocal[l] : l;
    iremote[l] = vremote[l];
  }
  nleaves = nvleaves;
  for (PetscInt k = 0; k < ncand; ++k)
    if (owner_rank[k] != rank) {
      ilocal[nleaves]        = cand[k].point;
      iremote[nleaves].rank  = owner_rank[k];
      iremote[nleaves].index = owner_point[k];
      ++nleaves;
    }
  {
    PetscSFNode swap;

    PetscCall(PetscSortIntWithDataArray(nleaves, ilocal, iremote, sizeof(PetscSFNode), &swap));
  }
  PetscCall(PetscSFCreate(comm, sf));
  PetscCall(PetscSFSetGraph(*sf, pEnd - pStart, nleaves, ilocal, PETSC_OWN_POINTER, iremote, PETSC_OWN_POINTER));
  PetscCall(PetscFree2(owner_rank, owner_point));
  PetscCall(PetscFree2(counts, displs));
  PetscCall(PetscFree(all));
  PetscCall(PetscFree(cand));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The distributed interpolated mesh of the simplices cells[] (global vertex numbers; this rank's block of the cells) on
   nverts_total vertices, of which this rank holds the block of nverts_owned coordinates coords[]: PETSc numbers the local
   vertices and links them (DMPlexBuildFromCellListParallel()), the faces and edges are built here, with the same cone
   on every rank for a shared one, and the point SF gets the shared faces and edges. on_boundary says whether a face
   lies on the domain's boundary. */
PetscErrorCode MeshCreateInterpolatedSimplicesParallel(MPI_Comm comm, PetscInt dim, PetscInt ncells, PetscInt nverts_owned, PetscInt nverts_total,
                                                       const PetscInt cells[], const PetscReal coords[], MeshOnBoundary on_boundary, void *ctx,
                                                       DM *dm)
{
  DM              udm;
  PetscSF         sfvert, sfpoint, sf;
  PetscInt       *gid = NULL, *lcells, vStart, vEnd, nleaves, *cones;
  const PetscInt *ilocal, *degree;
  PetscBool      *shared;
  MeshInterface   itf;

  PetscFunctionBeginUser;
  PetscCall(DMPlexCreateFromCellListParallelPetsc(comm, dim, ncells, nverts_owned, nverts_total, dim + 1, PETSC_FALSE, cells, dim, coords, &sfvert,
                                                  NULL, &udm));
  PetscCall(DMPlexGetDepthStratum(udm, 0, &vStart, &vEnd));
  PetscCheck(vStart == ncells, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Expected the vertices after the %" PetscInt_FMT " cells, not from %" PetscInt_FMT,
             ncells, vStart);
  { /* the local vertices' global numbers: the owner's first vertex plus the index in its block (sfvert: roots the owned
       blocks, leaves the local vertices in order; PETSc 3.18 crashes when asked for them) */
    PetscMPIInt        size;
    PetscInt          *first, nl, v0;
    const PetscInt    *il;
    const PetscSFNode *ir;

    PetscCallMPI(MPI_Comm_size(comm, &size));
    PetscCall(PetscMalloc1(size, &first));
    PetscCallMPI(MPI_Scan(&nverts_owned, &v0, 1, MPIU_INT, MPI_SUM, comm));
    v0 -= nverts_owned;
    PetscCallMPI(MPI_Allgather(&v0, 1, MPIU_INT, first, 1, MPIU_INT, comm));
    PetscCall(PetscSFGetGraph(sfvert, NULL, &nl, &il, &ir));
    PetscCheck(nl == vEnd - vStart, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Expected a leaf per local vertex");
    PetscCall(PetscMalloc1(nl, &gid));
    for (PetscInt l = 0; l < nl; ++l) gid[il ? il[l] : l] = first[ir[l].rank] + ir[l].index;
    PetscCall(PetscFree(first));
  }
  PetscCall(PetscMalloc2(ncells * (dim + 1), &lcells, vEnd - vStart, &shared));
  PetscCall(DMPlexGetCones(udm, &cones));
  for (PetscInt i = 0; i < ncells * (dim + 1); ++i) lcells[i] = cones[i] - vStart;
  PetscCall(DMGetPointSF(udm, &sfpoint));
  PetscCall(PetscSFGetGraph(sfpoint, NULL, &nleaves, &ilocal, NULL));
  PetscCall(PetscArrayzero(shared, vEnd - vStart));
  for (PetscInt l = 0; l < nleaves; ++l) shared[(ilocal ? ilocal[l] : l) - vStart] = PETSC_TRUE;
  PetscCall(PetscSFComputeDegreeBegin(sfpoint, &degree));
  PetscCall(PetscSFComputeDegreeEnd(sfpoint, &degree));
  for (PetscInt v = vStart; v < vEnd; ++v)
    if (degree[v]) shared[v - vStart] = PETSC_TRUE;
  itf.gid         = gid;
  itf.shared      = shared;
  itf.on_boundary = on_boundary;
  itf.ctx         = ctx;
  PetscCall(MeshCreateInterpolatedSimplices(comm, dim, ncells, vEnd - vStart, lcells, &itf, dm));
  PetscCall(InterfacePointSF(*dm, sfpoint, gid, shared, &sf));
  PetscCall(DMSetPointSF(*dm, sf));
  PetscCall(PetscSFDestroy(&sf));
  PetscCall(DMPlexBuildCoordinatesFromCellListParallel(*dm, dim, sfvert, coords));
  PetscCall(PetscSFDestroy(&sfvert));
  PetscCall(PetscFree2(lcells, shared));
  PetscCall(PetscFree(gid));
  PetscCall(DMDestroy(&udm));
  PetscFunctionReturn(PETSC_SUCCESS);
}
