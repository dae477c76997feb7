/* The interpolated topology of a simplex mesh (cells, faces, edges, vertices) built directly from its cell list, with
   the points, cones and orientations that DMPlexInterpolate() gives: new faces numbered in the order the cells first
   meet them, each face's cone the first cell's raw face, edges after faces. PETSc 3.18 finds faces through a generic hash
   table and a cell-type label lookup per point; here a face is found among the few faces whose smallest vertex is the
   same (a bucket per vertex), which makes this several times cheaper. */
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

/* One interpolation step: the nsrc sources (cells, or the faces of a tetrahedral mesh), each with the vertex list
   src[s * (fs + 1) .. ] of a simplex of fs + 1 vertices, get their fs + 1 faces of fs vertices (the vertices are points
   vbase .. vbase + nv - 1). Out: the number of new faces, their vertex cones (first met), and per source its faces
   (numbered from first) and their orientations. */
static PetscErrorCode InterpolateStep(PetscInt nsrc, PetscInt fs, const PetscInt src[], PetscInt vbase, PetscInt nv, PetscInt first, PetscInt *nnew,
                                      PetscInt **new_cones, PetscInt face[], PetscInt ornt[])
{
  const PetscInt       nf = fs + 1;
  const DMPolytopeType ft = fs == 2 ? DM_POLYTOPE_SEGMENT : DM_POLYTOPE_TRIANGLE;
  PetscInt            *start, *fill, *bkey, *bid, *cones, n = 0;

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
      PetscCall(DMPolytopeGetVertexOrientation(ft, &cones[id * fs], raw, &ornt[s * nf + lf]));
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
PetscErrorCode MeshCreateInterpolatedSimplices(MPI_Comm comm, PetscInt dim, PetscInt ncells, PetscInt nverts, const PetscInt cells[], DM *dm)
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
  PetscCall(InterpolateStep(ncells, dim, src, vbase, nverts, fbase, &nfaces, &faces_v, cell_face, cell_ornt));
  ebase = fbase + nfaces;
  if (dim == 3) {
    PetscCall(PetscMalloc2(nfaces * 3, &face_edge, nfaces * 3, &face_ornt));
    PetscCall(InterpolateStep(nfaces, 2, faces_v, vbase, nverts, ebase, &nedges, &edges_v, face_edge, face_ornt));
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
