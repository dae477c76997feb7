/* Simplex box meshes: a structured grid split into triangles (2D) or Kuhn tetrahedra (3D),
   with the boundary faces labelled as PETSc labels its own box meshes. */
#include "mesh.h"

/* Signed measure of the simplex with vertex coordinates x[0..dim], times dim!. */
static PetscReal SimplexOrientation(PetscInt dim, const PetscReal x[])
{
  PetscReal a[3][3];

  for (PetscInt i = 0; i < dim; ++i)
    for (PetscInt d = 0; d < dim; ++d) a[i][d] = x[(i + 1) * dim + d] - x[d];
  if (dim == 2) return a[0][0] * a[1][1] - a[0][1] * a[1][0];
  return a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
         a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
}

/* The grid indices of vertex v of the (n[0]+1) x (n[1]+1) x (n[2]+1) grid of vertices, numbered x fastest. */
static void BoxVertexIndex(const PetscInt n[], PetscInt v, PetscInt idx[])
{
  idx[0] = v % (n[0] + 1);
  idx[1] = (v / (n[0] + 1)) % (n[1] + 1);
  idx[2] = v / ((n[0] + 1) * (n[1] + 1));
}

/* The coordinates of vertex v of the grid. */
static void BoxVertexCoordinates(PetscInt dim, const PetscInt n[], const PetscReal lower[], const PetscReal upper[], PetscInt v, PetscReal x[])
{
  PetscInt idx[3];

  BoxVertexIndex(n, v, idx);
  for (PetscInt d = 0; d < dim; ++d) x[d] = lower[d] + (upper[d] - lower[d]) * idx[d] / (PetscReal)n[d];
}

/* The vertices of cell c of the box: the grid's boxes x fastest, each split into 2 triangles or 6 Kuhn tetrahedra,
   oriented as PETSc's reference cell (counterclockwise triangle, negatively oriented tetrahedron). */
static void BoxCell(PetscInt dim, const PetscInt n[], const PetscReal lower[], const PetscReal upper[], PetscInt c, PetscInt cell[])
{
  const PetscInt  perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  const PetscInt  per_box = dim == 2 ? 2 : 6, nc = dim + 1, nvx = n[0] + 1, nvy = n[1] + 1;
  const PetscInt  box = c / per_box, t = c % per_box, i = box % n[0], j = (box / n[0]) % n[1], k = dim == 3 ? box / (n[0] * n[1]) : 0;
  const PetscReal sign = dim == 2 ? 1.0 : -1.0;
  PetscInt        corner[8];
  PetscReal       x[4 * 3];

  for (PetscInt b = 0; b < (dim == 2 ? 4 : 8); ++b) corner[b] = ((k + ((b >> 2) & 1)) * nvy + j + ((b >> 1) & 1)) * nvx + i + (b & 1);
  if (dim == 2) {
    const PetscInt tri[2][3] = {{corner[0], corner[1], corner[3]}, {corner[0], corner[3], corner[2]}};
    for (PetscInt l = 0; l < 3; ++l) cell[l] = tri[t][l];
  } else { /* Kuhn (Freudenthal) split: the 6 monotone paths from corner 0 to corner 7 */
    const PetscInt b1 = 1 << perms[t][0], b2 = b1 | (1 << perms[t][1]);
    cell[0] = corner[0];
    cell[1] = corner[b1];
    cell[2] = corner[b2];
    cell[3] = corner[7];
  }
  for (PetscInt l = 0; l < nc; ++l) BoxVertexCoordinates(dim, n, lower, upper, cell[l], &x[l * dim]);
  if (sign * SimplexOrientation(dim, x) < 0.0) {
    const PetscInt tmp = cell[1];
    cell[1]            = cell[2];
    cell[2]            = tmp;
  }
}

typedef struct {
  PetscInt dim, n[3];
} BoxGrid;

/* Whether the face of vertices gid[0 .. nv-1] (global numbers) lies on a side of the box: all its vertices have grid
   index 0, or all have n[d], in some direction d. */
static PetscBool BoxFaceOnBoundary(PetscInt nv, const PetscInt gid[], void *ctx)
{
  const BoxGrid *g = (const BoxGrid *)ctx;

  for (PetscInt d = 0; d < g->dim; ++d)
    for (PetscInt side = 0; side < 2; ++side) {
      PetscBool all = PETSC_TRUE;

      for (PetscInt i = 0; i < nv && all; ++i) {
        PetscInt idx[3];

        BoxVertexIndex(g->n, gid[i], idx);
        all = (PetscBool)(idx[d] == (side ? g->n[d] : 0));
      }
      if (all) return PETSC_TRUE;
    }
  return PETSC_FALSE;
}

/* The simplex box: serial (on rank 0, for a partitioner to distribute), or, with distribute, built in parallel: each
   rank makes a contiguous block of the cell numbering (slabs along the last axis; with slab_rows > 0 whole rows, rank r
   those of rows [floor(R r / size), floor(R (r + 1) / size)) of a box of R = slab_rows rows, scaled to this box's: the
   slabs of the boxes of nested iteration refine one another, whether or not R divides by the ranks; 0: as many cells
   on each rank, to one) and the vertices it needs, and its faces
   and edges are built directly (src/mesh/mesh_interpolate.c; with petsc_interpolate by PETSc's interpolation); nothing is
   built on one rank and moved. check (one rank): print how the direct build differs from DMPlexInterpolate()'s. */
PetscErrorCode MeshCreateSimplexBox(MPI_Comm comm, PetscInt dim, const PetscInt faces[], const PetscReal lower[], const PetscReal upper[],
                                    PetscBool distribute, PetscInt slab_rows, PetscBool petsc_interpolate, PetscBool check, DM *dm)
{
  const PetscInt n[3] = {faces[0], faces[1], dim == 3 ? faces[2] : 1};
  const PetscInt nc   = dim + 1;
  PetscInt       ncells_total, nverts_total, c0 = 0, c1 = 0, v0 = 0, v1 = 0, *cells = NULL;
  PetscReal     *coords = NULL;
  PetscMPIInt    rank, size;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCallMPI(MPI_Comm_size(comm, &size));
  ncells_total = (dim == 2 ? 2 : 6) * n[0] * n[1] * n[2];
  nverts_total = (n[0] + 1) * (n[1] + 1) * (dim == 3 ? n[2] + 1 : 1);
  if (size == 1) distribute = PETSC_FALSE;
  if (!distribute) size = 1;          /* everything on rank 0 */
  if (rank < size && slab_rows > 0) { /* whole rows: rank r's rows of the box of slab_rows rows, scaled to this box's */
    const PetscInt rows = n[dim - 1], scale = rows / slab_rows, row_cells = ncells_total / rows;

    c0 = row_cells * scale * (PetscInt)(((PetscInt64)slab_rows * rank) / size);
    c1 = row_cells * scale * (PetscInt)(((PetscInt64)slab_rows * (rank + 1)) / size);
  } else if (rank < size) {
    c0 = (PetscInt)(((PetscInt64)ncells_total * rank) / size);
    c1 = (PetscInt)(((PetscInt64)ncells_total * (rank + 1)) / size);
  }
  if (rank < size) {
    v0 = (PetscInt)(((PetscInt64)nverts_total * rank) / size);
    v1 = (PetscInt)(((PetscInt64)nverts_total * (rank + 1)) / size);
  }
  PetscCall(PetscMalloc2((v1 - v0) * dim, &coords, (c1 - c0) * nc, &cells));
  for (PetscInt v = v0; v < v1; ++v) BoxVertexCoordinates(dim, n, lower, upper, v, &coords[(v - v0) * dim]);
  for (PetscInt c = c0; c < c1; ++c) BoxCell(dim, n, lower, upper, c, &cells[(c - c0) * nc]);
  if (distribute && petsc_interpolate)
    PetscCall(DMPlexCreateFromCellListParallelPetsc(comm, dim, c1 - c0, v1 - v0, nverts_total, nc, PETSC_TRUE, cells, dim, coords, NULL, NULL, dm));
  else if (distribute) {
    BoxGrid grid = {dim, {n[0], n[1], n[2]}};

    PetscCall(MeshCreateInterpolatedSimplicesParallel(comm, dim, c1 - c0, v1 - v0, nverts_total, cells, coords, BoxFaceOnBoundary, &grid, dm));
  } else if (petsc_interpolate)
    PetscCall(DMPlexCreateFromCellListPetsc(comm, dim, c1 - c0, v1 - v0, nc, PETSC_TRUE, cells, dim, coords, dm));
  else {
    PetscCall(MeshCreateInterpolatedSimplices(comm, dim, c1 - c0, v1 - v0, cells, NULL, dm));
    PetscCall(DMPlexBuildCoordinatesFromCellList(*dm, dim, coords));
  }
  if (check && !distribute) {
    DM       ref;
    PetscInt mismatches, compared;

    PetscCall(DMPlexCreateFromCellListPetsc(comm, dim, c1 - c0, v1 - v0, nc, PETSC_TRUE, cells, dim, coords, &ref));
    PetscCall(MeshCompareTopology(ref, *dm, &mismatches, &compared));
    PetscCall(PetscPrintf(comm,
                          "box interpolation check: %" PetscInt_FMT " differences from DMPlexInterpolate() in %" PetscInt_FMT " compared entries\n",
                          mismatches, compared));
    PetscCall(DMDestroy(&ref));
  }
  PetscCall(PetscFree2(coords, cells));
  PetscCall(MeshLabelBoxFaces(*dm, lower, upper));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* PETSc's box numbering of the sides (2D: bottom 1, right 2, top 3, left 4; 3D: bottom z=0 1, top 2, front y=0 3,
   back 4, right x=1 5, left x=0 6): the "Face Sets" value of the side x_d = lower (s = 0) or upper (s = 1). */
PetscInt MeshBoxFaceId(PetscInt dim, PetscInt d, PetscInt s)
{
  const PetscInt ids2[2][2] = {{4, 2}, {1, 3}};
  const PetscInt ids3[3][2] = {{6, 5}, {3, 4}, {1, 2}};

  return dim == 2 ? ids2[d][s] : ids3[d][s];
}

/* "Face Sets" with PETSc's box numbering (MeshBoxFaceId()), and "marker" = 1 on the boundary. A face is on the
   boundary when its centroid lies on a side of the box: on a distributed mesh, a face at a rank's border also has one
   cell on that rank. */
PetscErrorCode MeshLabelBoxFaces(DM dm, const PetscReal lower[], const PetscReal upper[])
{
  PetscInt dim, fStart, fEnd;
  DMLabel  face_sets, marker;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMCreateLabel(dm, "Face Sets"));
  PetscCall(DMCreateLabel(dm, "marker"));
  PetscCall(DMGetLabel(dm, "Face Sets", &face_sets));
  PetscCall(DMGetLabel(dm, "marker", &marker));
  PetscCall(DMPlexGetHeightStratum(dm, 1, &fStart, &fEnd));
  for (PetscInt f = fStart; f < fEnd; ++f) {
    PetscInt  support;
    PetscReal centroid[3];

    PetscBool on_side = PETSC_FALSE;

    PetscCall(DMPlexGetSupportSize(dm, f, &support));
    if (support != 1) continue; /* interior; a face with one cell may still be interior, at a rank's border */
    PetscCall(DMPlexComputeCellGeometryFVM(dm, f, NULL, centroid, NULL));
    for (PetscInt d = 0; d < dim; ++d) {
      const PetscReal tol = 1e-10 * (upper[d] - lower[d]);
      for (PetscInt s = 0; s < 2; ++s) {
        const PetscReal side = s ? upper[d] : lower[d];
        if (PetscAbsReal(centroid[d] - side) < tol) {
          PetscCall(DMLabelSetValue(face_sets, f, MeshBoxFaceId(dim, d, s)));
          on_side = PETSC_TRUE;
        }
      }
    }
    if (on_side) PetscCall(DMLabelSetValue(marker, f, 1));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* With box (the simplex box of the options, not refined by -dm_refine; on several ranks built in slabs of rows, each
   slab boundary a row of the coarsest box, so that a rank's fine slab is the refinement of its coarse slab and every
   local fine vertex has its source among the local coarse points), the next level of a grid sequence
   as the box of twice as many cells per side, built directly (cheaper than PETSc's general regular refinement,
   DMPlexTransformApply()), numbered as a direct run of that many cells numbers it. In 2D that box is the regular
   refinement of the coarse one (each triangle split in four at its edges' midpoints); in 3D it also refines the coarse
   Kuhn box (each coarse tetrahedron is a union of 8 fine Kuhn tetrahedra: MeshCreate()), though not as PETSc's
   regular refinement, which splits a tetrahedron's inner octahedron along another diagonal. Every fine vertex is a
   coarse vertex or the midpoint of a coarse edge (a side or a diagonal; in 3D the monotone diagonals of the Kuhn split):
   vertex_source[v - vStart] is that coarse point, as MeshRefineRegular() gives it, so MeshInterpolateVertexSources()
   is exact for P1. */
PetscErrorCode MeshCreateBoxLevel(DM coarse, const MeshBox *box, PetscInt level, DM *fine, PetscInt **vertex_source)
{
  MPI_Comm           comm  = PetscObjectComm((PetscObject)coarse);
  const PetscInt     dim   = box->dim;
  PetscInt           cf[3] = {1, 1, 1}, ff[3] = {1, 1, 1}, cvStart, cvEnd, fvStart, fvEnd, *lattice, nlat = 1;
  PetscSection       csec, fsec;
  Vec                ccoords, fcoords;
  const PetscScalar *cx, *fx;
  MatType            mtype;

  PetscFunctionBeginUser;
  for (PetscInt d = 0; d < dim; ++d) {
    cf[d] = box->faces[d] << level;
    ff[d] = 2 * cf[d];
    nlat *= cf[d] + 1;
  }
  PetscCall(MeshCreateSimplexBox(comm, dim, ff, box->lower, box->upper, PETSC_TRUE, box->slab_rows, PETSC_FALSE, PETSC_FALSE, fine)); /* in slabs */
  PetscCall(DMGetMatType(coarse, &mtype));
  PetscCall(DMSetMatType(*fine, mtype));
  PetscCall(PetscObjectSetName((PetscObject)*fine, "mesh"));
  /* the coarse vertices by lattice position */
  PetscCall(PetscMalloc1(nlat, &lattice));
  for (PetscInt i = 0; i < nlat; ++i) lattice[i] = -1;
  PetscCall(DMPlexGetDepthStratum(coarse, 0, &cvStart, &cvEnd));
  PetscCall(DMGetCoordinateSection(coarse, &csec));
  PetscCall(DMGetCoordinatesLocal(coarse, &ccoords));
  PetscCall(VecGetArrayRead(ccoords, &cx));
  for (PetscInt v = cvStart; v < cvEnd; ++v) {
    PetscInt off, idx = 0;

    PetscCall(PetscSectionGetOffset(csec, v, &off));
    for (PetscInt d = dim - 1; d >= 0; --d) {
      const PetscInt i = (PetscInt)PetscFloorReal((PetscRealPart(cx[off + d]) - box->lower[d]) / (box->upper[d] - box->lower[d]) * cf[d] + 0.5);

      idx = idx * (cf[d] + 1) + i;
    }
    PetscCheck(idx >= 0 && idx < nlat && lattice[idx] < 0, comm, PETSC_ERR_PLIB, "Coarse vertex %" PetscInt_FMT " is not a lattice point of the box",
               v);
    lattice[idx] = v;
  }
  PetscCall(VecRestoreArrayRead(ccoords, &cx));
  /* each fine vertex: its coarse vertex, or the coarse edge whose midpoint it is */
  PetscCall(DMPlexGetDepthStratum(*fine, 0, &fvStart, &fvEnd));
  PetscCall(DMGetCoordinateSection(*fine, &fsec));
  PetscCall(DMGetCoordinatesLocal(*fine, &fcoords));
  PetscCall(PetscMalloc1(fvEnd - fvStart, vertex_source));
  PetscCall(VecGetArrayRead(fcoords, &fx));
  for (PetscInt v = fvStart; v < fvEnd; ++v) {
    PetscInt off, lat[3] = {0, 0, 0}, odd[3], nodd = 0, source = -1;

    PetscCall(PetscSectionGetOffset(fsec, v, &off));
    for (PetscInt d = 0; d < dim; ++d) {
      lat[d] = (PetscInt)PetscFloorReal((PetscRealPart(fx[off + d]) - box->lower[d]) / (box->upper[d] - box->lower[d]) * ff[d] + 0.5);
      if (lat[d] % 2) odd[nodd++] = d;
    }
    /* the antipodal corners of the coarse sub-cell spanned by the odd directions, the first odd direction at its floor */
    for (PetscInt mask = 0; mask < (1 << PetscMax(nodd - 1, 0)) && source < 0; ++mask) {
      PetscInt a = 0, b = 0, ends[2];

      for (PetscInt d = dim - 1; d >= 0; --d) {
        PetscInt ia = lat[d] / 2, ib = lat[d] / 2; /* even: the same coarse index */

        for (PetscInt k = 0; k < nodd; ++k)
          if (odd[k] == d) {
            const PetscBool up = k > 0 && ((mask >> (k - 1)) & 1);

            ia = up ? (lat[d] + 1) / 2 : (lat[d] - 1) / 2;
            ib = up ? (lat[d] - 1) / 2 : (lat[d] + 1) / 2;
          }
        a = a * (cf[d] + 1) + ia;
        b = b * (cf[d] + 1) + ib;
      }
      ends[0] = lattice[a];
      ends[1] = lattice[b];
      if (!nodd)
        source = ends[0];
      else {
        const PetscInt *join;
        PetscInt        njoin;

        PetscCall(DMPlexGetJoin(coarse, 2, ends, &njoin, &join));
        if (njoin == 1) source = join[0];
        PetscCall(DMPlexRestoreJoin(coarse, 2, ends, &njoin, &join));
      }
    }
    PetscCheck(source >= 0, comm, PETSC_ERR_PLIB, "Fine vertex %" PetscInt_FMT " is neither a coarse vertex nor an edge's midpoint", v);
    (*vertex_source)[v - fvStart] = source;
  }
  PetscCall(VecRestoreArrayRead(fcoords, &fx));
  PetscCall(PetscFree(lattice));
  PetscFunctionReturn(PETSC_SUCCESS);
}
