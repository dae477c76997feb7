/* Scene "square": Omega = (0,1)^d clamped on top (x_d = 1), Gamma_C the bottom (x_d = 0) on a flat
   foundation, other faces traction-free, body force f = (0, ..., 0, beta (x_1 - x0)): the body is
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

  for (PetscInt c = 0; c < dim - 1; ++c) f0[c] = 0.0;
  f0[dim - 1] = -beta * (x[0] - x0);
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
  scene->contact_id               = 1; /* bottom, x_d = 0, in 2D and 3D */
  scene->num_dirichlet            = 1;
  scene->dirichlet_ids[0]         = dim == 2 ? 3 : 2; /* top, x_d = 1 */
  scene->f0_body                  = f0_body_square;
  scene->obstacle_normal[0]       = PetscSinReal(tilt * PETSC_PI / 180.0); /* foundation below: u_n = -u_d when not tilted */
  scene->obstacle_normal[dim - 1] = -PetscCosReal(tilt * PETSC_PI / 180.0);
  scene->obstacle_offset          = 0.0; /* plane x_d = 0 */
  scene->num_constants            = SQUARE_NUM_CONSTANTS;
  scene->constants[SQUARE_BETA]   = beta;
  scene->constants[SQUARE_X0]     = x0;
  PetscFunctionReturn(PETSC_SUCCESS);
}
