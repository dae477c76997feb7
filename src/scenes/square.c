/* Scene "square": Omega = (0,1)^d clamped on top (x_d = 1), Gamma_C the bottom (x_d = 0) on a flat
   foundation, other faces traction-free, body force f = (0, ..., 0, beta (x_1 - x0)) (plus -body_force): the body is
   pressed down where x_1 < x0 and lifted where x_1 > x0, so the contact zone ends inside Gamma_C. */
#include "app.h"
#include "scenes.h"

enum { SQUARE_BETA, SQUARE_X0, SQUARE_NUM_CONSTANTS };

/* residual term -f */
static void f0_body_square(PetscInt dim, PetscInt Nf, PetscInt NfAux, const PetscInt uOff[], const PetscInt uOff_x[], const PetscScalar u[],
                           const PetscScalar u_t[], const PetscScalar u_x[], const PetscInt aOff[], const PetscInt aOff_x[], const PetscScalar a[],
                           const PetscScalar a_t[], const PetscScalar a_x[], PetscReal t, const PetscReal x[], PetscInt numConstants,
                           const PetscScalar constants[], PetscScalar f0[])
{
  const PetscScalar beta = constants[CONST_SCENE + SQUARE_BETA], x0 = constants[CONST_SCENE + SQUARE_X0];

  for (PetscInt c = 0; c < dim; ++c) f0[c] = -constants[CONST_BODY_FORCE + c]; /* -body_force, 0 by default */
  f0[dim - 1] -= beta * (x[0] - x0);
}

PetscErrorCode SceneCreate_Square(DM dm, const Material *mat, Scene *scene)
{
  PetscInt  dim;
  PetscReal beta, x0, tilt;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscOptionsBegin(PetscObjectComm((PetscObject)dm), NULL, "Scene square", "Signorini");
  beta = 2.0;
  PetscCall(PetscOptionsReal("-square_beta", "Body force f_d = beta (x_1 - x0)", NULL, beta, &beta, NULL));
  x0 = 0.6;
  PetscCall(PetscOptionsReal("-square_x0", "Where the body force changes sign", NULL, x0, &x0, NULL));
  tilt = 0.0;
  PetscCall(
      PetscOptionsReal("-square_tilt", "Angle (degrees) of the foundation plane about the origin, in the (x_1, x_d) plane", NULL, tilt, &tilt, NULL));
  PetscOptionsEnd();
  PetscCall(OptionsCheckFinite(PetscObjectComm((PetscObject)dm), "-square_beta", beta));
  PetscCall(OptionsCheckFinite(PetscObjectComm((PetscObject)dm), "-square_x0", x0));
  PetscCall(OptionsCheckFinite(PetscObjectComm((PetscObject)dm), "-square_tilt", tilt));
  PetscCheck(PetscAbsReal(tilt) < 45.0, PetscObjectComm((PetscObject)dm), PETSC_ERR_USER_INPUT, "-square_tilt must lie in (-45, 45) degrees, got %g",
             (double)tilt);
  {
    const PetscReal origin[3] = {0.0, 0.0, 0.0};
    PetscReal       n[3]      = {0.0, 0.0, 0.0};

    n[0]       = PetscSinReal(tilt * PETSC_PI / 180.0); /* foundation below: u_n = -u_d when not tilted */
    n[dim - 1] = -PetscCosReal(tilt * PETSC_PI / 180.0);
    PetscCall(SceneSetObstaclePlane(scene, origin, n)); /* plane through the origin: x_d = 0 when not tilted */
  }
  PetscCall(SceneAddContactFaces(scene, 1));                            /* bottom, x_d = 0, in 2D and 3D */
  PetscCall(SceneAddBoundary(scene, BC_CLAMP, dim == 2 ? 3 : 2, NULL)); /* top, x_d = 1 */
  scene->f0_body                    = f0_body_square;
  scene->num_constants              = SQUARE_NUM_CONSTANTS;
  scene->constants[SQUARE_BETA]     = beta;
  scene->load_constant[SQUARE_BETA] = PETSC_TRUE; /* the body force's size: scaled by a load path */
  scene->constants[SQUARE_X0]       = x0;
  PetscFunctionReturn(PETSC_SUCCESS);
}
