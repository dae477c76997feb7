/* The position of a mesh point, and a boundary face's outward geometry: apart from mesh.c, whose set-up calls the
   checks of mesh_check.c that use them. */
#include "mesh.h"

/* Position of a node: the vertex itself, or the centroid of the edge/face that carries it (Lagrange P2/Q2). */
PetscErrorCode MeshPointPosition(DM dm, PetscInt p, PetscReal x[])
{
  PetscInt depth, cdim;

  PetscFunctionBeginUser;
  PetscCall(DMGetCoordinateDim(dm, &cdim));
  PetscCall(DMPlexGetPointDepth(dm, p, &depth));
  if (depth == 0) {
    DM                 cdm;
    PetscSection       cs;
    Vec                coords;
    PetscInt           off;
    const PetscScalar *a;

    PetscCall(DMGetCoordinateDM(dm, &cdm));
    PetscCall(DMGetLocalSection(cdm, &cs));
    PetscCall(DMGetCoordinatesLocal(dm, &coords));
    PetscCall(PetscSectionGetOffset(cs, p, &off));
    PetscCall(VecGetArrayRead(coords, &a));
    for (PetscInt d = 0; d < cdim; ++d) x[d] = PetscRealPart(a[off + d]);
    PetscCall(VecRestoreArrayRead(coords, &a));
  } else
    PetscCall(DMPlexComputeCellGeometryFVM(dm, p, NULL, x, NULL));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The outward unit normal, centroid and area of boundary face f (its one cell on the inside). */
PetscErrorCode MeshFaceOutwardGeometry(DM dm, PetscInt f, PetscInt dim, PetscReal n[], PetscReal xc[], PetscReal *area)
{
  const PetscInt *support;
  PetscReal       cc[3], vol, dot = 0.0, norm = 0.0;

  PetscFunctionBeginUser;
  PetscCall(DMPlexComputeCellGeometryFVM(dm, f, area, xc, n));
  PetscCall(DMPlexGetSupport(dm, f, &support));
  PetscCall(DMPlexComputeCellGeometryFVM(dm, support[0], &vol, cc, NULL));
  for (PetscInt d = 0; d < dim; ++d) {
    dot += n[d] * (xc[d] - cc[d]);
    norm += n[d] * n[d];
  }
  norm = PetscSqrtReal(norm);
  for (PetscInt d = 0; d < dim; ++d) n[d] = (dot < 0.0 ? -n[d] : n[d]) / (norm > 0.0 ? norm : 1.0);
  PetscFunctionReturn(PETSC_SUCCESS);
}
