/* The position of a mesh point, apart from mesh.c, whose set-up calls the checks of mesh_check.c that use it. */
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
