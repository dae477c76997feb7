/* Uniform refinement with the parent of every fine cell, and the interpolation of FE functions from the coarse mesh
   to the fine one: used by the grid sequencing (grid_sequence.c) and by -reference (reference.c). */
#include <stdlib.h>
#include <petscdmplextransform.h>
#include "mesh.h"

/* Reference coordinates xi[n][dim] of the physical points x[n][dim] in cell c, by Newton on the cell map (one step for
   affine cells). Replaces DMPlexCoordinatesToReference(), which re-sorts a label on every call in PETSc 3.18. */
PetscErrorCode MeshCellReferenceCoordinates(DM dm, PetscInt c, PetscInt n, const PetscReal x[], PetscReal xi[])
{
  PetscInt        dim;
  PetscQuadrature q;
  PetscReal      *pt, *wt;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(PetscQuadratureCreate(PETSC_COMM_SELF, &q));
  PetscCall(PetscMalloc1(dim, &pt)); /* owned by q, which reads the point at each geometry call */
  PetscCall(PetscMalloc1(1, &wt));
  wt[0] = 1.0;
  PetscCall(PetscQuadratureSetData(q, dim, 1, 1, pt, wt));
  for (PetscInt i = 0; i < n; ++i) {
    PetscReal v[3], J[9], invJ[9], detJ, res = PETSC_MAX_REAL, scale = 1.0;
    PetscInt  it;

    for (PetscInt d = 0; d < dim; ++d) xi[i * dim + d] = 0.0;
    /* The steps are in reference coordinates, but x - v loses the digits of the coordinates' size: a point known to
       round-off in physical units is known to |x| / (cell size) times round-off in the cell's. The tolerances scale with
       that ratio (|x| ||J^-1||), so that a mesh far from the origin (a CAD part in millimetres) is located as one near it. */
    for (it = 0; it < 20 && res > 1e-13 * scale; ++it) {
      for (PetscInt d = 0; d < dim; ++d) pt[d] = xi[i * dim + d];
      PetscCall(DMPlexComputeCellGeometryFEM(dm, c, q, v, J, invJ, &detJ));
      if (it == 0) {
        PetscReal xmax = 0.0, jnorm = 0.0;

        for (PetscInt d = 0; d < dim; ++d) {
          PetscReal row = 0.0;

          xmax = PetscMax(xmax, PetscAbsReal(x[i * dim + d]));
          for (PetscInt e = 0; e < dim; ++e) row += PetscAbsReal(invJ[d * dim + e]);
          jnorm = PetscMax(jnorm, row);
        }
        scale = PetscMax(1.0, 1e3 * PETSC_MACHINE_EPSILON / 1e-13 * xmax * jnorm);
      }
      res = 0.0;
      for (PetscInt d = 0; d < dim; ++d) {
        PetscReal step = 0.0;

        for (PetscInt e = 0; e < dim; ++e) step += invJ[d * dim + e] * (x[i * dim + e] - v[e]);
        xi[i * dim + d] += step;
        res = PetscMax(res, PetscAbsReal(step));
      }
    }
    PetscCheck(res <= 1e-10 * scale, PETSC_COMM_SELF, PETSC_ERR_CONV_FAILED,
               "No reference coordinates for a point of cell %" PetscInt_FMT " (Newton residual %g, in the cell's reference coordinates)", c,
               (double)res);
  }
  PetscCall(PetscQuadratureDestroy(&q));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The vertices of cell c (at most 8), in closure order. */
PetscErrorCode MeshCellVertices(DM dm, PetscInt c, PetscInt verts[], PetscInt *nv)
{
  PetscInt *closure = NULL, ncl, vStart, vEnd;

  PetscFunctionBeginUser;
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  *nv = 0;
  PetscCall(DMPlexGetTransitiveClosure(dm, c, PETSC_TRUE, &ncl, &closure));
  for (PetscInt j = 0; j < ncl; ++j)
    if (closure[2 * j] >= vStart && closure[2 * j] < vEnd && *nv < 8) verts[(*nv)++] = closure[2 * j];
  PetscCall(DMPlexRestoreTransitiveClosure(dm, c, PETSC_TRUE, &ncl, &closure));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Refines dm `levels` times (regular refinement, labels kept) into fine, without a discretization; parent[c - cStart]
   is the cell of dm that holds fine cell c (an array the caller frees with PetscFree()). With one level and
   vertex_source not NULL, vertex_source[v - vStart] is the point of dm (vertex, edge, face or cell) whose centre fine
   vertex v is. */
PetscErrorCode MeshRefineRegular(DM dm, PetscInt levels, DM *fine, PetscInt **parent, PetscInt **vertex_source)
{
  MPI_Comm  comm = PetscObjectComm((PetscObject)dm);
  DM        cur  = dm;
  PetscInt *par, cStart, cEnd;
  MatType   mtype;

  PetscFunctionBeginUser;
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  PetscCall(PetscMalloc1(cEnd - cStart, &par));
  for (PetscInt c = cStart; c < cEnd; ++c) par[c - cStart] = c;
  for (PetscInt l = 0; l < levels; ++l) {
    DMPlexTransform tr;
    DM              next;
    PetscInt        nStart, nEnd, *np;

    PetscCall(DMPlexTransformCreate(comm, &tr));
    PetscCall(DMPlexTransformSetType(tr, DMPLEXREFINEREGULAR));
    PetscCall(DMPlexTransformSetDM(tr, cur));
    PetscCall(DMPlexTransformSetUp(tr));
    PetscCall(DMPlexTransformApply(tr, cur, &next));
    PetscCall(DMPlexGetHeightStratum(next, 0, &nStart, &nEnd));
    PetscCall(PetscMalloc1(nEnd - nStart, &np));
    for (PetscInt c = nStart; c < nEnd; ++c) {
      DMPolytopeType ct, ctn;
      PetscInt       src, r;

      PetscCall(DMPlexTransformGetSourcePoint(tr, c, &ct, &ctn, &src, &r));
      np[c - nStart] = par[src - cStart];
    }
    if (vertex_source && levels == 1) {
      PetscInt vStart, vEnd;

      PetscCall(DMPlexGetDepthStratum(next, 0, &vStart, &vEnd));
      PetscCall(PetscMalloc1(vEnd - vStart, vertex_source));
      for (PetscInt v = vStart; v < vEnd; ++v) {
        DMPolytopeType ct, ctn;
        PetscInt       r;

        PetscCall(DMPlexTransformGetSourcePoint(tr, v, &ct, &ctn, &(*vertex_source)[v - vStart], &r));
      }
    }
    PetscCall(PetscFree(par));
    par    = np;
    cStart = nStart;
    PetscCall(DMPlexTransformDestroy(&tr));
    if (cur != dm) PetscCall(DMDestroy(&cur));
    cur = next;
  }
  if (cur == dm)
    PetscCall(DMClone(dm, fine));
  else
    *fine = cur;
  PetscCall(DMGetMatType(dm, &mtype));
  PetscCall(DMSetMatType(*fine, mtype));
  PetscCall(PetscObjectSetName((PetscObject)*fine, "mesh"));
  *parent = par;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A point of the coarse mesh and its position, sorted by position (VertexSourcesByPosition()). */
typedef struct {
  PetscReal x[2];
  PetscInt  point;
} PositionKey;

static int ComparePositions(const void *a, const void *b)
{
  const PositionKey *p = (const PositionKey *)a, *q = (const PositionKey *)b;

  for (PetscInt d = 0; d < 2; ++d)
    if (p->x[d] != q->x[d]) return p->x[d] < q->x[d] ? -1 : 1;
  return 0;
}

/* vertex_source for a 2D fine mesh nested in dm whose new vertices are midpoints of dm's edges: each fine vertex is
   matched by its position (exactly: both are computed as the mean of the same two coordinates) to a vertex of dm or
   to the midpoint of an edge of dm, among the points of this rank (its ghosts included). */
static PetscErrorCode VertexSourcesByPosition(DM dm, DM fine, PetscInt **vertex_source)
{
  PetscInt     vStart, vEnd, eStart, eEnd, fvStart, fvEnd, n = 0;
  PositionKey *keys;

  PetscFunctionBeginUser;
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  PetscCall(DMPlexGetDepthStratum(dm, 1, &eStart, &eEnd));
  PetscCall(PetscMalloc1(vEnd - vStart + eEnd - eStart, &keys));
  for (PetscInt v = vStart; v < vEnd; ++v, ++n) {
    PetscReal x[3];

    PetscCall(MeshPointPosition(dm, v, x));
    keys[n].x[0]  = x[0];
    keys[n].x[1]  = x[1];
    keys[n].point = v;
  }
  for (PetscInt e = eStart; e < eEnd; ++e, ++n) {
    const PetscInt *cone;
    PetscReal       a[3], b[3];

    PetscCall(DMPlexGetCone(dm, e, &cone));
    PetscCall(MeshPointPosition(dm, cone[0], a));
    PetscCall(MeshPointPosition(dm, cone[1], b));
    keys[n].x[0]  = 0.5 * (a[0] + b[0]);
    keys[n].x[1]  = 0.5 * (a[1] + b[1]);
    keys[n].point = e;
  }
  qsort(keys, (size_t)n, sizeof(*keys), ComparePositions);
  PetscCall(DMPlexGetDepthStratum(fine, 0, &fvStart, &fvEnd));
  PetscCall(PetscMalloc1(fvEnd - fvStart, vertex_source));
  for (PetscInt v = fvStart; v < fvEnd; ++v) {
    PositionKey key, *hit;
    PetscReal   x[3];

    PetscCall(MeshPointPosition(fine, v, x));
    key.x[0] = x[0];
    key.x[1] = x[1];
    hit      = (PositionKey *)bsearch(&key, keys, (size_t)n, sizeof(*keys), ComparePositions);
    PetscCheck(hit, PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "the refined mesh's vertex at (%g, %g) is neither a vertex nor an edge midpoint of the mesh it refines", (double)x[0], (double)x[1]);
    (*vertex_source)[v - fvStart] = hit->point;
  }
  PetscCall(PetscFree(keys));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Refines the triangles of dm that `marked` holds with the value DM_ADAPT_REFINE, and those more that keep the mesh
   conforming: PETSc's skeleton-based refinement (refine_sbr; Plaza and Carey, Appl. Numer. Math. 32, 2000) splits the
   marked cells' edges at their midpoints, and every cell with a split edge into two to four triangles, so that the new
   mesh is nested in dm and P1 functions of dm are P1 functions of it. Labels (face sets, Gmsh names) are kept.
   As MeshRefineRegular()'s, vertex_source[v - vStart] is the point of dm (a vertex, or the edge it halves) whose centre
   the new vertex v is; it is found by position, since PETSc 3.18's DMPlexTransformGetSourcePoint() fails on this
   transform's new points ("Replica number ... could be not found" for its vertices, "Source point ... is not a
   triangle" for some cells on 2 ranks). */
PetscErrorCode MeshRefineMarked(DM dm, DMLabel marked, DM *fine, PetscInt **vertex_source)
{
  DMPlexTransform tr;
  MatType         mtype;

  PetscFunctionBeginUser;
  PetscCall(DMPlexTransformCreate(PetscObjectComm((PetscObject)dm), &tr));
  PetscCall(DMPlexTransformSetType(tr, DMPLEXREFINESBR));
  PetscCall(DMPlexTransformSetDM(tr, dm));
  PetscCall(DMPlexTransformSetActive(tr, marked));
  PetscCall(DMPlexTransformSetUp(tr));
  PetscCall(MeshRefineSBRLookups(tr));
  PetscCall(DMPlexTransformApply(tr, dm, fine));
  PetscCall(DMPlexTransformDestroy(&tr));
  PetscCall(VertexSourcesByPosition(dm, *fine, vertex_source));
  PetscCall(DMGetMatType(dm, &mtype));
  PetscCall(DMSetMatType(*fine, mtype));
  PetscCall(PetscObjectSetName((PetscObject)*fine, "mesh"));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The size each cell of dm would have for eps = eps0 h^power / M if eps were that of its descendants on the mesh refined
   `levels` times: 2^levels (the mean of their diameters^power)^(1/power), and hmax = 2^levels times their largest
   diameter (over all ranks). sizes has one entry per local cell and one more (MeshSetCellSizes()). The refined mesh is
   built for the measurement and destroyed. */
PetscErrorCode MeshDescendantSizes(DM dm, PetscInt levels, PetscReal power, PetscReal **sizes, PetscReal *hmax)
{
  DM         fine;
  PetscInt  *parent, *count, cStart, cEnd, fStart, fEnd;
  PetscReal  scale = PetscPowReal(2.0, (PetscReal)levels), local = 0.0;
  PetscReal *s;

  PetscFunctionBeginUser;
  PetscCall(MeshRefineRegular(dm, levels, &fine, &parent, NULL));
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  PetscCall(DMPlexGetHeightStratum(fine, 0, &fStart, &fEnd));
  PetscCall(PetscCalloc1(cEnd - cStart + 1, &s));
  PetscCall(PetscCalloc1(cEnd - cStart + 1, &count));
  for (PetscInt c = fStart; c < fEnd; ++c) {
    PetscReal d;

    PetscCall(MeshCellDiameter(fine, c, &d));
    local = PetscMax(local, d);
    s[parent[c - fStart] - cStart] += PetscPowReal(d, power);
    count[parent[c - fStart] - cStart]++;
  }
  for (PetscInt c = cStart; c < cEnd; ++c)
    s[c - cStart] = count[c - cStart] ? scale * PetscPowReal(s[c - cStart] / count[c - cStart], 1.0 / power) : 0.0;
  PetscCall(MPIU_Allreduce(&local, hmax, 1, MPIU_REAL, MPIU_MAX, PetscObjectComm((PetscObject)dm)));
  *hmax *= scale;
  *sizes = s;
  PetscCall(PetscFree(count));
  PetscCall(PetscFree(parent));
  PetscCall(DMDestroy(&fine));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The coarse vertices whose mean is the fine vertex with source point src (MeshRefineRegular(), MeshCreateBoxLevel()): the
   vertex itself, an edge's cone, or the vertices of a quad's or hex's closure (at most 8). vb, eb: dm's vertex and edge
   strata. */
PetscErrorCode MeshSourceVertices(DM dm, const PetscInt vb[2], const PetscInt eb[2], PetscInt src, PetscInt verts[], PetscInt *nv)
{
  PetscInt *closure = NULL, ncl;

  PetscFunctionBeginUser;
  *nv = 0;
  if (src >= vb[0] && src < vb[1]) {
    verts[(*nv)++] = src;
  } else if (src >= eb[0] && src < eb[1]) {
    const PetscInt *cone;

    PetscCall(DMPlexGetCone(dm, src, &cone));
    verts[(*nv)++] = cone[0];
    verts[(*nv)++] = cone[1];
  } else {
    PetscCall(DMPlexGetTransitiveClosure(dm, src, PETSC_TRUE, &ncl, &closure));
    for (PetscInt j = 0; j < ncl; ++j)
      if (closure[2 * j] >= vb[0] && closure[2 * j] < vb[1] && *nv < 8) verts[(*nv)++] = closure[2 * j];
    PetscCall(DMPlexRestoreTransitiveClosure(dm, src, PETSC_TRUE, &ncl, &closure));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The interpolation of a local vector of dm with its unknowns at the vertices (P1, Q1) to fine, refined once by
   MeshRefineRegular(): every fine vertex is the centre of its source point (a vertex, an edge midpoint, the centre of
   a quad or a hex) and gets the mean of the values at the source point's vertices, which is exact for nested P1/Q1.
   A vertex-by-vertex loop, with none of the cell-by-cell geometry of MeshInterpolateFromParents(). */
PetscErrorCode MeshInterpolateVertexSources(DM dm, DM fine, const PetscInt vertex_source[], Vec loc, Vec *fine_loc)
{
  PetscSection       csec, fsec;
  PetscInt           vStart, vEnd, cvb[2], ceb[2], nc;
  const PetscScalar *cv;
  PetscScalar       *fv;

  PetscFunctionBeginUser;
  PetscCall(DMGetLocalSection(dm, &csec));
  PetscCall(DMGetLocalSection(fine, &fsec));
  PetscCall(DMPlexGetDepthStratum(fine, 0, &vStart, &vEnd));
  PetscCall(DMPlexGetDepthStratum(dm, 0, &cvb[0], &cvb[1]));
  PetscCall(DMPlexGetDepthStratum(dm, 1, &ceb[0], &ceb[1]));
  PetscCall(DMCreateLocalVector(fine, fine_loc));
  PetscCall(VecZeroEntries(*fine_loc));
  PetscCall(VecGetArrayRead(loc, &cv));
  PetscCall(VecGetArray(*fine_loc, &fv));
  for (PetscInt v = vStart; v < vEnd; ++v) {
    PetscInt verts[8], nv, foff;

    PetscCall(PetscSectionGetDof(fsec, v, &nc));
    if (!nc) continue;
    PetscCall(PetscSectionGetOffset(fsec, v, &foff));
    PetscCall(MeshSourceVertices(dm, cvb, ceb, vertex_source[v - vStart], verts, &nv));
    for (PetscInt i = 0; i < nv; ++i) {
      PetscInt coff;

      PetscCall(PetscSectionGetOffset(csec, verts[i], &coff));
      for (PetscInt c = 0; c < nc; ++c) fv[foff + c] += cv[coff + c] / nv;
    }
  }
  PetscCall(VecRestoreArray(*fine_loc, &fv));
  PetscCall(VecRestoreArrayRead(loc, &cv));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The same interpolation for nc arrays of values at dm's vertices (index v - vStart, ghosts included): fine_values[k] over
   fine's vertices, for the caller to free. */
PetscErrorCode MeshInterpolateVertexArrays(DM dm, DM fine, const PetscInt vertex_source[], PetscInt nc, PetscReal *const coarse[],
                                           PetscReal *fine_values[])
{
  PetscInt vStart, vEnd, cvb[2], ceb[2];

  PetscFunctionBeginUser;
  PetscCall(DMPlexGetDepthStratum(fine, 0, &vStart, &vEnd));
  PetscCall(DMPlexGetDepthStratum(dm, 0, &cvb[0], &cvb[1]));
  PetscCall(DMPlexGetDepthStratum(dm, 1, &ceb[0], &ceb[1]));
  for (PetscInt k = 0; k < nc; ++k) PetscCall(PetscCalloc1(vEnd - vStart, &fine_values[k]));
  for (PetscInt v = vStart; v < vEnd; ++v) {
    PetscInt verts[8], nv;

    PetscCall(MeshSourceVertices(dm, cvb, ceb, vertex_source[v - vStart], verts, &nv));
    for (PetscInt i = 0; i < nv; ++i)
      for (PetscInt k = 0; k < nc; ++k) fine_values[k][v - vStart] += coarse[k][verts[i] - cvb[0]] / nv;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Interpolates the local vectors loc[] of dm (boundary values included) into new local vectors fine_loc[] of fine, which
   has the same discretization: every vertex of a fine cell gets the value of the FE function in its parent cell
   (exact for the nested P1/Q1 spaces). */
PetscErrorCode MeshInterpolateFromParents(DM dm, DM fine, const PetscInt parent[], PetscInt nvec, Vec loc[], Vec fine_loc[])
{
  PetscInt           dim, Nb, Nc, fcStart, fcEnd;
  PetscFE            fe;
  DM                 cdm;
  PetscSection       fsec, csec;
  Vec                coords;
  const PetscScalar *xc;
  PetscScalar       *fv[2];

  PetscFunctionBeginUser;
  PetscCheck(nvec <= 2, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "At most 2 vectors at a time");
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMGetField(dm, 0, NULL, (PetscObject *)&fe));
  PetscCall(PetscFEGetDimension(fe, &Nb));
  PetscCall(PetscFEGetNumComponents(fe, &Nc));
  PetscCall(DMGetLocalSection(fine, &fsec));
  PetscCall(DMGetCoordinateDM(fine, &cdm));
  PetscCall(DMGetLocalSection(cdm, &csec));
  PetscCall(DMGetCoordinatesLocal(fine, &coords));
  PetscCall(DMPlexGetHeightStratum(fine, 0, &fcStart, &fcEnd));
  for (PetscInt k = 0; k < nvec; ++k) {
    PetscCall(DMCreateLocalVector(fine, &fine_loc[k]));
    PetscCall(VecZeroEntries(fine_loc[k]));
    PetscCall(VecGetArray(fine_loc[k], &fv[k]));
  }
  PetscCall(VecGetArrayRead(coords, &xc));
  for (PetscInt c = fcStart; c < fcEnd; ++c) {
    PetscInt        nv, verts[8], off;
    PetscReal       x[8 * 3], xi[8 * 3];
    PetscTabulation T;

    PetscCall(MeshCellVertices(fine, c, verts, &nv));
    for (PetscInt i = 0; i < nv; ++i) {
      PetscCall(PetscSectionGetOffset(csec, verts[i], &off));
      for (PetscInt d = 0; d < dim; ++d) x[i * dim + d] = PetscRealPart(xc[off + d]);
    }
    PetscCall(MeshCellReferenceCoordinates(dm, parent[c - fcStart], nv, x, xi));
    PetscCall(PetscFECreateTabulation(fe, 1, nv, xi, 0, &T));
    for (PetscInt k = 0; k < nvec; ++k) {
      PetscScalar *cv = NULL;

      PetscCall(DMPlexVecGetClosure(dm, NULL, loc[k], parent[c - fcStart], NULL, &cv));
      for (PetscInt i = 0; i < nv; ++i) {
        PetscCall(PetscSectionGetOffset(fsec, verts[i], &off));
        for (PetscInt comp = 0; comp < Nc; ++comp) {
          PetscScalar val = 0.0;

          for (PetscInt b = 0; b < Nb; ++b) val += cv[b] * T->T[0][(i * Nb + b) * Nc + comp];
          fv[k][off + comp] = val;
        }
      }
      PetscCall(DMPlexVecRestoreClosure(dm, NULL, loc[k], parent[c - fcStart], NULL, &cv));
    }
    PetscCall(PetscTabulationDestroy(&T));
  }
  PetscCall(VecRestoreArrayRead(coords, &xc));
  for (PetscInt k = 0; k < nvec; ++k) PetscCall(VecRestoreArray(fine_loc[k], &fv[k]));
  PetscFunctionReturn(PETSC_SUCCESS);
}
