/* Scene "mms": the manufactured Signorini solution of verification.md section 2, with chosen regularity.
   Omega = (0,1)^d, Gamma_C = {x_d = 0} on the foundation x_d = 0 (n = -e_d), Gamma_D = {x_d = 1} with u = u_exact,
   the other faces loaded by sigma(u_exact) n. With s = x_1 - a, p = 2 + nu, q = 1 + nu,
     phi = A s_+^p (separation side), psi = -B (-s)_+^q (contact side),
     u_1 = -x_d phi'(x_1),  u_d = phi(x_1) + x_d psi(x_1),  the other components 0,
   so that on Gamma_C u_n = -phi <= 0, sigma_n = (lambda + 2 mu) psi <= 0, sigma_t = 0 and sigma_n u_n = 0,
   and u is in H^{3/2 + nu - delta} for every delta > 0. The data enter through the weak form (src/physics/weak_data.c). */
#include "app.h"
#include "scenes.h"

enum { MMS_NU, MMS_A, MMS_AMP_A, MMS_AMP_B, MMS_NUM_CONSTANTS };

static inline PetscReal PowPlus(PetscReal s, PetscReal e)
{
  return s > 0.0 ? PetscPowReal(s, e) : 0.0;
}

/* phi, phi', phi'', psi, psi' at x_1 */
static void Profiles(const PetscScalar c[], PetscReal x1, PetscReal f[5])
{
  const PetscReal nu = PetscRealPart(c[MMS_NU]), s = x1 - PetscRealPart(c[MMS_A]);
  const PetscReal A = PetscRealPart(c[MMS_AMP_A]), B = PetscRealPart(c[MMS_AMP_B]), p = 2.0 + nu, q = 1.0 + nu;

  f[0] = A * PowPlus(s, p);
  f[1] = A * p * PowPlus(s, p - 1.0);
  f[2] = A * p * (p - 1.0) * PowPlus(s, p - 2.0);
  f[3] = -B * PowPlus(-s, q);
  f[4] = B * q * PowPlus(-s, q - 1.0);
}

static PetscErrorCode MMSExact(PetscInt dim, PetscReal t, const PetscReal x[], PetscInt Nc, PetscScalar u[], void *ctx)
{
  const PetscInt d = dim - 1;
  PetscReal      f[5];

  Profiles((const PetscScalar *)ctx, x[0], f);
  for (PetscInt k = 0; k < dim; ++k) u[k] = 0.0;
  u[0] = -x[d] * f[1];
  u[d] = f[0] + x[d] * f[3];
  return PETSC_SUCCESS;
}

/* G[i*dim+j] = du_i/dx_j */
static PetscErrorCode MMSExactGradient(PetscInt dim, PetscReal t, const PetscReal x[], PetscInt Nc, PetscScalar G[], void *ctx)
{
  const PetscInt d = dim - 1;
  PetscReal      f[5];

  Profiles((const PetscScalar *)ctx, x[0], f);
  for (PetscInt k = 0; k < dim * dim; ++k) G[k] = 0.0;
  G[0 * dim + 0] = -x[d] * f[2];
  G[0 * dim + d] = -f[1];
  G[d * dim + 0] = f[1] + x[d] * f[4];
  G[d * dim + d] = f[3];
  return PETSC_SUCCESS;
}

PetscErrorCode SceneCreate_MMS(DM dm, const Material *mat, Scene *scene)
{
  MPI_Comm  comm = PetscObjectComm((PetscObject)dm);
  PetscInt  dim;
  PetscReal nu, a, amp_a, amp_b;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscOptionsBegin(comm, NULL, "Scene mms (manufactured solution)", "Signorini");
  nu = 0.5;
  PetscCall(PetscOptionsReal("-mms_nu", "Regularity: u in H^(3/2+nu), nu in (0, 1]", NULL, nu, &nu, NULL));
  a = 1.0 / PetscSqrtReal(5.0);
  PetscCall(PetscOptionsReal("-mms_a", "Position x_1 = a of the contact/separation transition, in (0, 1)", NULL, a, &a, NULL));
  amp_a = 1.0;
  PetscCall(PetscOptionsReal("-mms_amplitude_A", "Amplitude A of the separation profile phi", NULL, amp_a, &amp_a, NULL));
  amp_b = 1.0;
  PetscCall(PetscOptionsReal("-mms_amplitude_B", "Amplitude B of the contact profile psi", NULL, amp_b, &amp_b, NULL));
  PetscOptionsEnd();
  PetscCall(OptionsCheckFinite(comm, "-mms_nu", nu));
  PetscCall(OptionsCheckFinite(comm, "-mms_a", a));
  PetscCall(OptionsCheckFinite(comm, "-mms_amplitude_A", amp_a));
  PetscCall(OptionsCheckFinite(comm, "-mms_amplitude_B", amp_b));
  PetscCheck(nu > 0.0 && nu <= 1.0, comm, PETSC_ERR_USER_INPUT, "-mms_nu must lie in (0, 1], got %g", (double)nu);
  PetscCheck(a > 0.0 && a < 1.0, comm, PETSC_ERR_USER_INPUT, "-mms_a must lie in (0, 1), got %g", (double)a);
  PetscCheck(amp_a > 0.0 && amp_b > 0.0, comm, PETSC_ERR_USER_INPUT, "-mms_amplitude_A and -mms_amplitude_B must be positive, got %g and %g",
             (double)amp_a, (double)amp_b);
  PetscCall(SceneSetFoundation(scene, dim));
  PetscCall(SceneAddContactFaces(scene, 1));                                /* bottom, x_d = 0 */
  PetscCall(SceneAddBoundary(scene, BC_CLAMP, dim == 2 ? 3 : 2, MMSExact)); /* top, x_d = 1 */
  scene->exact                = MMSExact;
  scene->exact_gradient       = MMSExactGradient;
  scene->weak_data            = PETSC_TRUE;
  scene->has_kink             = PETSC_TRUE;
  scene->kink_normal[0]       = 1.0;
  scene->kink_offset          = a;
  scene->num_constants        = MMS_NUM_CONSTANTS;
  scene->constants[MMS_NU]    = nu;
  scene->constants[MMS_A]     = a;
  scene->constants[MMS_AMP_A] = amp_a;
  scene->constants[MMS_AMP_B] = amp_b;
  PetscFunctionReturn(PETSC_SUCCESS);
}
