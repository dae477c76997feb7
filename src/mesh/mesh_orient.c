/* Every cell positively oriented, whatever order its file lists its vertices in.

   A Gmsh file may list a triangle's or a quadrilateral's vertices clockwise (a plane surface whose curve loop turns
   clockwise, or an exporter's convention), and a tetrahedron's or a hexahedron's with the opposite handedness. The
   mesh is legal, but the map x(xi) from PETSc's reference cell is then orientation-reversing: det J < 0 at every point.
   PetscFE's integration weights are w_q det J, so that on such a cell every integral, the stiffness included, has the
   wrong sign: a body pulled to the right moves to the left (-assembly fe and every P2 run, before this), and a
   clockwise quadrilateral mesh diverges. The project's own P1 assembly uses |det J| and was right.

   So each cell with det J < 0 is reflected in place at set-up: DMPlexOrientPoint() with a reflection (a negative
   orientation of the cell's polytope) permutes the cell's cone and composes its cones' orientations, so that its
   closure lists the same vertices in the reversed sense and det J > 0. Faces, edges, vertices, the labels and the
   coordinates are untouched (the cell has no support to update), and on a mesh that needs no reflection nothing
   changes. det J is taken at the cell's center, which for a simplex is its one value; a quadrilateral or hexahedron
   whose det J changes sign inside (a non-convex or tangled cell) is refused, as is a cell of zero volume. */
#include "mesh.h" /* MeshOrientCells() only: nothing of mesh.c is called here (mesh.c calls this file) */

/* The points at which a tensor cell's det J is taken: its corners, where a bilinear or trilinear map is most
   distorted, then its center (NULL for simplices, whose det J is one value). */
static PetscErrorCode CornerQuadrature(PetscInt dim, PetscBool simplex, PetscQuadrature *q)
{
  const PetscInt ncorners = dim == 2 ? 4 : 8;
  PetscReal     *p, *w;

  PetscFunctionBeginUser;
  *q = NULL;
  if (simplex) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscMalloc1((ncorners + 1) * dim, &p)); /* apart: PetscQuadratureDestroy() frees each */
  PetscCall(PetscMalloc1(ncorners + 1, &w));
  for (PetscInt k = 0; k < ncorners; ++k)
    for (PetscInt d = 0; d < dim; ++d) p[k * dim + d] = (k >> d) & 1 ? 1.0 : -1.0;
  for (PetscInt d = 0; d < dim; ++d) p[ncorners * dim + d] = 0.0; /* the center, last */
  for (PetscInt k = 0; k <= ncorners; ++k) w[k] = 1.0;
  PetscCall(PetscQuadratureCreate(PETSC_COMM_SELF, q));
  PetscCall(PetscQuadratureSetData(*q, dim, 1, ncorners + 1, p, w)); /* q owns p and w */
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* det J of cell c at its center, and its smallest and largest at the points of q (a tensor cell's corners; a
   simplex's one value where q is NULL). */
static PetscErrorCode CellDeterminants(DM dm, PetscInt c, PetscQuadrature q, PetscReal *det_center, PetscReal *det_min, PetscReal *det_max)
{
  PetscReal v[8 * 3 + 3], J[9 * 9], invJ[9 * 9], dets[9];
  PetscInt  npoints;

  PetscFunctionBeginUser;
  if (!q) {
    PetscCall(DMPlexComputeCellGeometryAffineFEM(dm, c, v, J, invJ, &dets[0]));
    *det_center = *det_min = *det_max = dets[0];
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  PetscCall(PetscQuadratureGetData(q, NULL, NULL, &npoints, NULL, NULL));
  PetscCall(DMPlexComputeCellGeometryFEM(dm, c, q, v, J, invJ, dets));
  *det_center = dets[npoints - 1];
  *det_min = *det_max = dets[0];
  for (PetscInt k = 1; k < npoints - 1; ++k) {
    *det_min = PetscMin(*det_min, dets[k]);
    *det_max = PetscMax(*det_max, dets[k]);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The diameter of cell c: its largest vertex-to-vertex distance. */
static PetscErrorCode CellDiameter(DM dm, PetscInt c, PetscReal *diam)
{
  DM           cdm;
  Vec          coords;
  PetscScalar *xc = NULL;
  PetscInt     n, cdim;

  PetscFunctionBeginUser;
  PetscCall(DMGetCoordinateDim(dm, &cdim));
  PetscCall(DMGetCoordinateDM(dm, &cdm));
  PetscCall(DMGetCoordinatesLocal(dm, &coords));
  PetscCall(DMPlexVecGetClosure(cdm, NULL, coords, c, &n, &xc)); /* the vertices' coordinates */
  *diam = 0.0;
  for (PetscInt i = 0; i < n / cdim; ++i)
    for (PetscInt j = i + 1; j < n / cdim; ++j) {
      PetscReal d2 = 0.0;

      for (PetscInt d = 0; d < cdim; ++d) d2 += PetscSqr(PetscRealPart(xc[i * cdim + d] - xc[j * cdim + d]));
      *diam = PetscMax(*diam, PetscSqrtReal(d2));
    }
  PetscCall(DMPlexVecRestoreClosure(cdm, NULL, coords, c, &n, &xc));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The centroid of the first of the local cells marked (cell >= 0) on the lowest rank that has one, on every rank. */
static PetscErrorCode FirstMarkedCentroid(DM dm, PetscInt cell, PetscReal x[3])
{
  MPI_Comm    comm = PetscObjectComm((PetscObject)dm);
  PetscMPIInt rank, size, first;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCallMPI(MPI_Comm_size(comm, &size));
  x[0] = x[1] = x[2] = 0.0;
  if (cell >= 0) { /* the mean of its vertices: a degenerate cell has no area to weigh a centroid by */
    DM           cdm;
    Vec          coords;
    PetscScalar *xc = NULL;
    PetscInt     n, cdim;

    PetscCall(DMGetCoordinateDim(dm, &cdim));
    PetscCall(DMGetCoordinateDM(dm, &cdm));
    PetscCall(DMGetCoordinatesLocal(dm, &coords));
    PetscCall(DMPlexVecGetClosure(cdm, NULL, coords, cell, &n, &xc)); /* the vertices' coordinates */
    for (PetscInt k = 0; k < n / cdim; ++k)
      for (PetscInt d = 0; d < cdim; ++d) x[d] += PetscRealPart(xc[k * cdim + d]) / (PetscReal)(n / cdim);
    PetscCall(DMPlexVecRestoreClosure(cdm, NULL, coords, cell, &n, &xc));
  }
  first = cell >= 0 ? rank : size;
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &first, 1, MPI_INT, MPI_MIN, comm));
  if (first < size) PetscCallMPI(MPI_Bcast(x, 3, MPIU_REAL, first, comm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Reflects every local cell with det J < 0 (see above); *nreflected is the number reflected over all ranks (a cell
   two ranks hold counted on each). A cell whose det J is zero to round-off (|det J| below 1e-12 times its diameter to
   the dimension: collinear or coplanar vertices) or changes sign inside it is refused, the first one's centroid named;
   what names the mesh. */
PetscErrorCode MeshOrientCells(DM dm, const char what[], PetscInt *nreflected)
{
  MPI_Comm        comm = PetscObjectComm((PetscObject)dm);
  PetscInt        cStart, cEnd, dim, counts[3] = {0, 0, 0}, bad = -1, tangled = -1;
  PetscBool       simplex;
  PetscQuadrature q;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMGetCoordinatesLocalSetUp(dm)); /* collective: a mesh just distributed (a parallel HDF5 read) has none yet */
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  PetscCall(DMPlexIsSimplex(dm, &simplex));
  PetscCall(CornerQuadrature(dim, simplex, &q));
  for (PetscInt c = cStart; c < cEnd; ++c) {
    PetscReal det, det_min, det_max, diam = 0.0;

    PetscCall(CellDeterminants(dm, c, q, &det, &det_min, &det_max));
    PetscCall(CellDiameter(dm, c, &diam));
    if (!(PetscAbsReal(det) > 1e-12 * PetscPowRealInt(diam, dim))) { /* zero to round-off, or not finite */
      if (bad < 0) bad = c;
      ++counts[1];
      continue;
    }
    if (det_min * det_max <= 0.0) { /* det J changes sign inside the cell: no reflection orients it */
      if (tangled < 0) tangled = c;
      ++counts[2];
      continue;
    }
    if (det < 0.0) {
      PetscReal det_after, dmin, dmax;

      PetscCall(DMPlexOrientPoint(dm, c, -1)); /* a reflection of every polytope: its closure in the reversed sense */
      PetscCall(CellDeterminants(dm, c, q, &det_after, &dmin, &dmax));
      PetscCheck(det_after > 0.0 && dmin > 0.0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Cell %" PetscInt_FMT " still has det J = %g after its reflection",
                 c, (double)det_after);
      ++counts[0];
    }
  }
  PetscCall(PetscQuadratureDestroy(&q));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, counts, 3, MPIU_INT, MPI_SUM, comm));
  if (counts[1]) {
    PetscReal x[3];

    PetscCall(FirstMarkedCentroid(dm, bad, x));
    SETERRQ(comm, PETSC_ERR_USER_INPUT,
            "The mesh %s has %" PetscInt_FMT
            " cell(s) of zero volume, the first at (%.6g, %.6g, %.6g): their vertices are collinear or coplanar, so that "
            "their stiffness is singular; remove or mend them in the mesh generator",
            what, counts[1], (double)x[0], (double)x[1], (double)x[2]);
  }
  if (counts[2]) {
    PetscReal x[3];

    PetscCall(FirstMarkedCentroid(dm, tangled, x));
    SETERRQ(comm, PETSC_ERR_USER_INPUT,
            "The mesh %s has %" PetscInt_FMT
            " tangled cell(s), the first at (%.6g, %.6g, %.6g): the Jacobian changes sign inside them (a non-convex or "
            "self-intersecting quadrilateral or hexahedron), which no order of their vertices mends; mesh them again",
            what, counts[2], (double)x[0], (double)x[1], (double)x[2]);
  }
  *nreflected = counts[0];
  PetscFunctionReturn(PETSC_SUCCESS);
}
