/* The size view's cover of the model's boundary (MeshRemesh()): the view Gmsh meshes the model with is made of the
   current mesh's cells, whose boundary is the chords of a curved boundary, and the model's curve bulges out of each
   chord by about h^2 / 8R. Gmsh's PostView field finds no cell of the view at a point outside them and gives it no
   size of the view's: the model's arc then takes sizes far above the mesh's, so that a remesh would coarsen the
   boundary the cycles refined (docs/estimate.md, "Remeshing the Gmsh model", measures it). Each boundary face of the view gets a cap outside the
   body: the triangle (2D) or tetrahedron (3D) over the face whose apex lies CAP_HEIGHT times the face's longest edge out along its outward normal,
   which covers a bulge of up to a quarter of the chord (an arc of about 110 degrees per chord). Its sizes are the face's, at most the face's longest
   edge (the apex the smallest of them): a convex boundary, which lies in the caps, is meshed no coarser than the mesh it comes from (a cell's size is
   its mean edge, longer than its boundary face where the cell is stretched along the normal). In 3D the wedge between the caps of two boundary faces
   that share an edge, over which a curved surface bulges too, is filled by the tetrahedron of the edge and the two apexes. */
#include <stdlib.h>
#include "mesh.h"

#define CAP_HEIGHT 0.5

/* One side (face) of a view cell: the cell and the local vertex it omits; sorted by the coordinates of its vertices
   so that the two sides of an interior face meet in the order. */
typedef struct {
  PetscInt cell, omit;
  double   key[9]; /* its vertices' coordinates, the vertices in lexicographic order */
} Side;

static PetscInt side_len; /* the doubles of a key compared: dim * (nv - 1) */

static int CompareKeys(const double *a, const double *b, PetscInt n)
{
  for (PetscInt i = 0; i < n; ++i)
    if (a[i] != b[i]) return a[i] < b[i] ? -1 : 1;
  return 0;
}

static int CompareSides(const void *a, const void *b)
{
  return CompareKeys(((const Side *)a)->key, ((const Side *)b)->key, side_len);
}

static int ComparePoints(const void *a, const void *b)
{
  return CompareKeys((const double *)a, (const double *)b, 3);
}

/* The point k of cell c of the view data (per = 4 nv doubles a cell: x of its nv vertices, then y, z, the size). */
static void ViewPoint(const double data[], PetscInt nv, PetscInt c, PetscInt k, double p[3])
{
  for (PetscInt d = 0; d < 3; ++d) p[d] = data[c * 4 * nv + d * nv + k];
}

static void ViewSetPoint(double cell[], PetscInt nv, PetscInt k, const double p[3], double value)
{
  for (PetscInt d = 0; d < 3; ++d) cell[d * nv + k] = p[d];
  cell[3 * nv + k] = value;
}

/* An edge of a boundary face (3D): its two points in order, and the apex of the face's cap. */
typedef struct {
  double key[6], apex[3], value;
} Edge;

static int CompareEdges(const void *a, const void *b)
{
  return CompareKeys(((const Edge *)a)->key, ((const Edge *)b)->key, 6);
}

/* The caps of the boundary faces of the view's ncells cells (nv vertices each, dim 2 or 3), and in 3D the wedges
   between them, as *ncaps more view cells in *caps (free with PetscFree). */
PetscErrorCode MeshRemeshViewCaps(PetscInt ncells, PetscInt nv, PetscInt dim, const double data[], PetscInt *ncaps, double **caps)
{
  const PetscInt per = 4 * nv, nf = nv - 1;
  Side          *sides;
  Edge          *edges  = NULL;
  PetscInt       nsides = ncells * nv, nbound = 0, nedges = 0, nout = 0;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc1(nsides + 1, &sides));
  side_len = 3 * nf;
  for (PetscInt c = 0; c < ncells; ++c)
    for (PetscInt omit = 0; omit < nv; ++omit) {
      Side    *s = &sides[c * nv + omit];
      PetscInt m = 0;

      s->cell = c;
      s->omit = omit;
      for (PetscInt k = 0; k < nv; ++k)
        if (k != omit) ViewPoint(data, nv, c, k, &s->key[3 * m++]);
      qsort(s->key, (size_t)nf, 3 * sizeof(double), ComparePoints);
    }
  qsort(sides, (size_t)nsides, sizeof(Side), CompareSides);
  for (PetscInt i = 0; i < nsides;) { /* a side met once is a boundary face; move them to the front */
    PetscInt j = i + 1;

    while (j < nsides && !CompareSides(&sides[i], &sides[j])) ++j;
    if (j == i + 1) sides[nbound++] = sides[i];
    i = j;
  }
  /* the caps, then (3D) up to 3 wedges a face: each boundary edge has two faces, so 3/2 wedges a face */
  PetscCall(PetscMalloc1((dim == 3 ? 3 : 1) * nbound * per + 1, caps));
  if (dim == 3) PetscCall(PetscMalloc1(3 * nbound + 1, &edges));
  for (PetscInt b = 0; b < nbound; ++b) {
    const Side *s       = &sides[b];
    double      p[3][3] = {{0.0}}, o[3], n[3] = {0.0, 0.0, 0.0}, centre[3] = {0.0, 0.0, 0.0}, value[3], smallest = PETSC_MAX_REAL, longest = 0.0;
    double      len = 0.0, side = 0.0, apex[3];
    double     *cap = &(*caps)[nout * per];
    PetscInt    m   = 0;

    for (PetscInt k = 0; k < nv; ++k) {
      if (k == s->omit) {
        ViewPoint(data, nv, s->cell, k, o);
        continue;
      }
      ViewPoint(data, nv, s->cell, k, p[m]);
      value[m] = data[s->cell * per + 3 * nv + k];
      smallest = PetscMin(smallest, value[m]);
      ++m;
    }
    for (PetscInt a = 0; a < nf; ++a) {
      for (PetscInt d = 0; d < 3; ++d) centre[d] += p[a][d] / nf;
      for (PetscInt c = a + 1; c < nf; ++c)
        longest = PetscMax(longest, PetscSqrtReal(PetscSqr(p[a][0] - p[c][0]) + PetscSqr(p[a][1] - p[c][1]) + PetscSqr(p[a][2] - p[c][2])));
    }
    if (dim == 2) {
      n[0] = p[1][1] - p[0][1];
      n[1] = p[0][0] - p[1][0];
    } else {
      const double u[3] = {p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]}, v[3] = {p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};

      n[0] = u[1] * v[2] - u[2] * v[1];
      n[1] = u[2] * v[0] - u[0] * v[2];
      n[2] = u[0] * v[1] - u[1] * v[0];
    }
    for (PetscInt d = 0; d < 3; ++d) {
      len += n[d] * n[d];
      side += n[d] * (centre[d] - o[d]); /* outward: away from the cell's omitted vertex */
    }
    len = PetscSqrtReal(len);
    if (!(len > 0.0)) continue; /* a degenerate face: no cap */
    for (PetscInt d = 0; d < 3; ++d) apex[d] = centre[d] + (side < 0.0 ? -1.0 : 1.0) * CAP_HEIGHT * longest * n[d] / len;
    smallest = PetscMin(smallest, longest); /* the boundary no coarser than the face */
    for (PetscInt a = 0; a < nf; ++a) ViewSetPoint(cap, nv, a, p[a], PetscMin(value[a], longest));
    ViewSetPoint(cap, nv, nf, apex, smallest);
    ++nout;
    for (PetscInt a = 0; a < nf && dim == 3; ++a) { /* its edges, for the wedges */
      Edge         *e  = &edges[nedges++];
      const double *q0 = p[a], *q1 = p[(a + 1) % nf];
      const int     first = ComparePoints(q0, q1) < 0;

      for (PetscInt d = 0; d < 3; ++d) {
        e->key[d]     = first ? q0[d] : q1[d];
        e->key[3 + d] = first ? q1[d] : q0[d];
        e->apex[d]    = apex[d];
      }
      e->value = PetscMin(PetscMin(value[a], value[(a + 1) % nf]), longest);
    }
  }
  if (dim == 3) {
    qsort(edges, (size_t)nedges, sizeof(Edge), CompareEdges);
    for (PetscInt i = 0; i + 1 < nedges; ++i) {
      const Edge *e = &edges[i], *f = &edges[i + 1];
      double     *w = &(*caps)[nout * per];
      double      u[3], v[3], t[3], vol, scale = 0.0;

      if (CompareEdges(e, f)) continue;
      for (PetscInt d = 0; d < 3; ++d) {
        u[d] = e->key[3 + d] - e->key[d];
        v[d] = e->apex[d] - e->key[d];
        t[d] = f->apex[d] - e->key[d];
        scale += u[d] * u[d];
      }
      vol = u[0] * (v[1] * t[2] - v[2] * t[1]) - u[1] * (v[0] * t[2] - v[2] * t[0]) + u[2] * (v[0] * t[1] - v[1] * t[0]);
      if (PetscAbsReal(vol) <= 1e-6 * scale * PetscSqrtReal(scale)) continue; /* coplanar faces: no wedge between their caps */
      ViewSetPoint(w, nv, 0, &e->key[0], PetscMin(e->value, f->value));
      ViewSetPoint(w, nv, 1, &e->key[3], PetscMin(e->value, f->value));
      ViewSetPoint(w, nv, 2, e->apex, PetscMin(e->value, f->value));
      ViewSetPoint(w, nv, 3, f->apex, PetscMin(e->value, f->value));
      ++nout;
      ++i;
    }
  }
  *ncaps = nout;
  PetscCall(PetscFree(sides));
  PetscCall(PetscFree(edges));
  PetscFunctionReturn(PETSC_SUCCESS);
}
