/* Scene "patch": the patch test. Omega = (0,1)^d with the exact linear field of a uniaxial stress along x_1
   (sigma = a E e_1 e_1, so Gamma_C = {x_d = 0} is traction-free), plus a rigid lift c along x_d and a rigid rotation w
   in the (x_1, x_d) plane, prescribed on every face but Gamma_C, f = 0. With c > w and a >= 0 the body leaves the
   foundation, so P1/Q1 elements must reproduce the field to round-off with or without the contact terms. */
#include "app.h"
#include "scenes.h"

enum { PATCH_STRAIN, PATCH_LATERAL, PATCH_LIFT, PATCH_ROTATION, PATCH_NUM_CONSTANTS };

static PetscErrorCode PatchExact(PetscInt dim, PetscReal t, const PetscReal x[], PetscInt Nc, PetscScalar u[], void *ctx)
{
  const PetscScalar *c = (const PetscScalar *)ctx;
  const PetscScalar  a = c[PATCH_STRAIN], b = c[PATCH_LATERAL], lift = c[PATCH_LIFT], w = c[PATCH_ROTATION];

  u[0] = a * x[0] - w * x[dim - 1];
  for (PetscInt d = 1; d < dim; ++d) u[d] = b * x[d];
  u[dim - 1] += lift + w * x[0];
  return PETSC_SUCCESS;
}

/* G[i*dim+j] = du_i/dx_j */
static PetscErrorCode PatchExactGradient(PetscInt dim, PetscReal t, const PetscReal x[], PetscInt Nc, PetscScalar G[], void *ctx)
{
  const PetscScalar *c = (const PetscScalar *)ctx;

  for (PetscInt k = 0; k < dim * dim; ++k) G[k] = 0.0;
  G[0] = c[PATCH_STRAIN];
  for (PetscInt d = 1; d < dim; ++d) G[d * dim + d] = c[PATCH_LATERAL];
  G[0 * dim + dim - 1] -= c[PATCH_ROTATION];
  G[(dim - 1) * dim + 0] += c[PATCH_ROTATION];
  return PETSC_SUCCESS;
}

PetscErrorCode SceneCreate_Patch(DM dm, const Material *mat, Scene *scene)
{
  PetscInt  dim;
  PetscReal strain, lift, rotation;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscOptionsBegin(PetscObjectComm((PetscObject)dm), NULL, "Scene patch", "Signorini");
  strain = 1e-2;
  PetscCall(PetscOptionsReal("-patch_strain", "Axial strain a of the uniaxial stress state", NULL, strain, &strain, NULL));
  lift = 2e-2;
  PetscCall(PetscOptionsReal("-patch_lift", "Rigid translation along x_d (positive: away from the foundation)", NULL, lift, &lift, NULL));
  rotation = 1e-2;
  PetscCall(PetscOptionsReal("-patch_rotation", "Rigid rotation angle in the (x_1, x_d) plane", NULL, rotation, &rotation, NULL));
  PetscOptionsEnd();
  PetscCall(OptionsCheckFinite(PetscObjectComm((PetscObject)dm), "-patch_strain", strain));
  PetscCall(OptionsCheckFinite(PetscObjectComm((PetscObject)dm), "-patch_lift", lift));
  PetscCall(OptionsCheckFinite(PetscObjectComm((PetscObject)dm), "-patch_rotation", rotation));
  PetscCall(SceneSetFoundation(scene, dim));
  PetscCall(SceneAddContactFaces(scene, 1));
  for (PetscInt i = 0; i < 2 * dim - 1; ++i) PetscCall(SceneAddBoundary(scene, BC_CLAMP, i + 2, PatchExact)); /* every box face but the bottom */
  scene->exact                   = PatchExact;
  scene->exact_gradient          = PatchExactGradient;
  scene->num_constants           = PATCH_NUM_CONSTANTS;
  scene->constants[PATCH_STRAIN] = strain;
  /* lateral strain of a uniaxial stress: -nu in 3D, -nu/(1-nu) in plane strain */
  scene->constants[PATCH_LATERAL]  = dim == 3 ? -mat->poisson_ratio * strain : -mat->poisson_ratio / (1.0 - mat->poisson_ratio) * strain;
  scene->constants[PATCH_LIFT]     = lift;
  scene->constants[PATCH_ROTATION] = rotation;
  PetscFunctionReturn(PETSC_SUCCESS);
}
