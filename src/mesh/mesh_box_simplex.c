/* Simplex box meshes: a structured grid split into triangles (2D) or Kuhn tetrahedra (3D),
   with the boundary faces labelled as PETSc labels its own box meshes. */
#include "mesh.h"

/* Signed measure of the simplex (v0, ..., vdim), times dim!. */
static PetscReal SimplexOrientation(PetscInt dim, const PetscReal coords[], const PetscInt v[])
{
  PetscReal a[3][3];

  for (PetscInt i = 0; i < dim; ++i)
    for (PetscInt d = 0; d < dim; ++d) a[i][d] = coords[v[i + 1] * dim + d] - coords[v[0] * dim + d];
  if (dim == 2) return a[0][0] * a[1][1] - a[0][1] * a[1][0];
  return a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
         a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
}

PetscErrorCode MeshCreateSimplexBox(MPI_Comm comm, PetscInt dim, const PetscInt faces[], const PetscReal lower[], const PetscReal upper[], DM *dm)
{
  /* PETSc's reference triangle is counterclockwise, its reference tetrahedron has negative orientation */
  const PetscReal sign = dim == 2 ? 1.0 : -1.0;
  const PetscInt  nx = faces[0], ny = faces[1], nz = dim == 3 ? faces[2] : 1;
  const PetscInt  perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  PetscInt       *cells = NULL, ncells = 0, nverts = 0, nc = dim + 1;
  PetscReal      *coords = NULL;
  PetscMPIInt     rank;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  if (rank == 0) {
    const PetscInt nvx = nx + 1, nvy = ny + 1, nvz = dim == 3 ? nz + 1 : 1;

    nverts = nvx * nvy * nvz;
    ncells = (dim == 2 ? 2 : 6) * nx * ny * nz;
    PetscCall(PetscMalloc2(nverts * dim, &coords, ncells * nc, &cells));
    for (PetscInt k = 0; k < nvz; ++k)
      for (PetscInt j = 0; j < nvy; ++j)
        for (PetscInt i = 0; i < nvx; ++i) {
          const PetscInt v      = (k * nvy + j) * nvx + i;
          const PetscInt idx[3] = {i, j, k}, n[3] = {nx, ny, nz};
          for (PetscInt d = 0; d < dim; ++d) coords[v * dim + d] = lower[d] + (upper[d] - lower[d]) * idx[d] / (PetscReal)n[d];
        }
    ncells = 0;
    for (PetscInt k = 0; k < nz; ++k)
      for (PetscInt j = 0; j < ny; ++j)
        for (PetscInt i = 0; i < nx; ++i) {
          PetscInt corner[8];

          for (PetscInt b = 0; b < (dim == 2 ? 4 : 8); ++b) corner[b] = ((k + ((b >> 2) & 1)) * nvy + j + ((b >> 1) & 1)) * nvx + i + (b & 1);
          if (dim == 2) {
            const PetscInt tri[2][3] = {{corner[0], corner[1], corner[3]}, {corner[0], corner[3], corner[2]}};
            for (PetscInt t = 0; t < 2; ++t, ++ncells)
              for (PetscInt l = 0; l < 3; ++l) cells[ncells * nc + l] = tri[t][l];
          } else {
            /* Kuhn (Freudenthal) split: the 6 monotone paths from corner 0 to corner 7 */
            for (PetscInt p = 0; p < 6; ++p, ++ncells) {
              const PetscInt b1 = 1 << perms[p][0], b2 = b1 | (1 << perms[p][1]);
              const PetscInt tet[4] = {corner[0], corner[b1], corner[b2], corner[7]};
              for (PetscInt l = 0; l < 4; ++l) cells[ncells * nc + l] = tet[l];
            }
          }
        }
    for (PetscInt c = 0; c < ncells; ++c) {
      if (sign * SimplexOrientation(dim, coords, &cells[c * nc]) < 0.0) {
        const PetscInt tmp = cells[c * nc + 1];
        cells[c * nc + 1]  = cells[c * nc + 2];
        cells[c * nc + 2]  = tmp;
      }
    }
  }
  PetscCall(DMPlexCreateFromCellListPetsc(comm, dim, ncells, nverts, nc, PETSC_TRUE, cells, dim, coords, dm));
  PetscCall(PetscFree2(coords, cells));
  PetscCall(MeshLabelBoxFaces(*dm, lower, upper));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* "Face Sets" with PETSc's box numbering (2D: bottom 1, right 2, top 3, left 4;
   3D: bottom z=0 1, top 2, front y=0 3, back 4, right x=1 5, left x=0 6), and "marker" = 1 on the boundary. */
PetscErrorCode MeshLabelBoxFaces(DM dm, const PetscReal lower[], const PetscReal upper[])
{
  const PetscInt ids2[2][2] = {{4, 2}, {1, 3}};
  const PetscInt ids3[3][2] = {{6, 5}, {3, 4}, {1, 2}};
  PetscInt       dim, fStart, fEnd;
  DMLabel        face_sets, marker;

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

    PetscCall(DMPlexGetSupportSize(dm, f, &support));
    if (support != 1) continue;
    PetscCall(DMPlexComputeCellGeometryFVM(dm, f, NULL, centroid, NULL));
    PetscCall(DMLabelSetValue(marker, f, 1));
    for (PetscInt d = 0; d < dim; ++d) {
      const PetscReal tol = 1e-10 * (upper[d] - lower[d]);
      for (PetscInt s = 0; s < 2; ++s) {
        const PetscReal side = s ? upper[d] : lower[d];
        if (PetscAbsReal(centroid[d] - side) < tol) PetscCall(DMLabelSetValue(face_sets, f, dim == 2 ? ids2[d][s] : ids3[d][s]));
      }
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}
