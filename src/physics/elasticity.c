/* Isotropic linear elasticity (plane strain in 2D): material options, pointwise kernels, discretization. */
#include "app.h"
#include "obstacle.h"
#include "physics.h"
#include "discretization.h"

/* sigma(u) = 2 mu eps(u) + lambda tr(eps(u)) I */
static void f1_u(PetscInt dim, PetscInt Nf, PetscInt NfAux, const PetscInt uOff[], const PetscInt uOff_x[], const PetscScalar u[],
                 const PetscScalar u_t[], const PetscScalar u_x[], const PetscInt aOff[], const PetscInt aOff_x[], const PetscScalar a[],
                 const PetscScalar a_t[], const PetscScalar a_x[], PetscReal t, const PetscReal x[], PetscInt numConstants,
                 const PetscScalar constants[], PetscScalar f1[])
{
  const PetscReal lambda = PetscRealPart(constants[CONST_LAMBDA]), mu = PetscRealPart(constants[CONST_MU]);
  PetscScalar     trace = 0.0;

  for (PetscInt c = 0; c < dim; ++c) trace += u_x[c * dim + c];
  for (PetscInt c = 0; c < dim; ++c) {
    for (PetscInt d = 0; d < dim; ++d) f1[c * dim + d] = mu * (u_x[c * dim + d] + u_x[d * dim + c]);
    f1[c * dim + c] += lambda * trace;
  }
}

/* d sigma_{cd} / d (du_e/dx_f) */
static void g3_uu(PetscInt dim, PetscInt Nf, PetscInt NfAux, const PetscInt uOff[], const PetscInt uOff_x[], const PetscScalar u[],
                  const PetscScalar u_t[], const PetscScalar u_x[], const PetscInt aOff[], const PetscInt aOff_x[], const PetscScalar a[],
                  const PetscScalar a_t[], const PetscScalar a_x[], PetscReal t, PetscReal u_tShift, const PetscReal x[], PetscInt numConstants,
                  const PetscScalar constants[], PetscScalar g3[])
{
  const PetscReal lambda = PetscRealPart(constants[CONST_LAMBDA]), mu = PetscRealPart(constants[CONST_MU]);

  for (PetscInt c = 0; c < dim; ++c)
    for (PetscInt d = 0; d < dim; ++d) {
      g3[((c * dim + c) * dim + d) * dim + d] += mu;
      g3[((c * dim + d) * dim + d) * dim + c] += mu;
      g3[((c * dim + d) * dim + c) * dim + d] += lambda;
    }
}

/* residual term -f of the constant body force f = constants[CONST_BODY_FORCE..] (-body_force) */
static void f0_body_constant(PetscInt dim, PetscInt Nf, PetscInt NfAux, const PetscInt uOff[], const PetscInt uOff_x[], const PetscScalar u[],
                             const PetscScalar u_t[], const PetscScalar u_x[], const PetscInt aOff[], const PetscInt aOff_x[], const PetscScalar a[],
                             const PetscScalar a_t[], const PetscScalar a_x[], PetscReal t, const PetscReal x[], PetscInt numConstants,
                             const PetscScalar constants[], PetscScalar f0[])
{
  for (PetscInt c = 0; c < dim; ++c) f0[c] = -constants[CONST_BODY_FORCE + c];
}

static PetscErrorCode CreateRigidBodyModes(DM dm, PetscInt origField, PetscInt field, MatNullSpace *nullspace)
{
  PetscFunctionBeginUser;
  PetscCall(DMPlexCreateRigidBody(dm, origField, nullspace));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The rigid-body modes (the near-null space of GAMG) of a field whose unknowns all sit at the vertices (P1, Q1),
   directly from the vertex coordinates, without DMPlexCreateRigidBody's projection through PetscFE. Constrained (Dirichlet) unknowns drop out in the
   local-to-global map, as there. like: a global vector of dm. */
PetscErrorCode ElasticityRigidBodyModesP1(DM dm, Vec like, MatNullSpace *nullspace)
{
  const PetscInt nmodes[4] = {0, 1, 3, 6};
  PetscInt       dim, vStart, vEnd, n, rstart;
  PetscSection   sec, gsec, csec;
  Vec            coords, mode[6];
  DM             cdm;
  PetscScalar   *a[6];

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  n = nmodes[dim];
  PetscCall(DMGetLocalSection(dm, &sec));
  PetscCall(DMGetGlobalSection(dm, &gsec));
  PetscCall(DMGetCoordinateDM(dm, &cdm));
  PetscCall(DMGetLocalSection(cdm, &csec));
  PetscCall(DMGetCoordinatesLocal(dm, &coords));
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  PetscCall(VecDuplicate(like, &mode[0])); /* not DMCreateGlobalVector(), which scans every mesh point for a block size */
  PetscCall(VecGetOwnershipRange(mode[0], &rstart, NULL));
  for (PetscInt m = 0; m < n; ++m) { /* written straight into the global vectors: the free components of the owned vertices */
    if (m) PetscCall(VecDuplicate(mode[0], &mode[m]));
    PetscCall(VecZeroEntries(mode[m]));
    PetscCall(VecGetArray(mode[m], &a[m]));
  }
  {
    const PetscScalar *x;

    PetscCall(VecGetArrayRead(coords, &x));
    for (PetscInt v = vStart; v < vEnd; ++v) {
      PetscInt  coff, ndof, gdof, idx[3];
      PetscReal p[3] = {0.0, 0.0, 0.0};

      PetscCall(PetscSectionGetDof(sec, v, &ndof));
      PetscCall(PetscSectionGetDof(gsec, v, &gdof));
      if (ndof < dim || gdof < 0) continue; /* no displacement here, or another rank's vertex */
      PetscCall(MeshPointGlobalIndices(sec, gsec, v, dim, idx));
      PetscCall(PetscSectionGetOffset(csec, v, &coff));
      for (PetscInt d = 0; d < dim; ++d) p[d] = PetscRealPart(x[coff + d]);
      for (PetscInt m = 0; m < n; ++m) {
        PetscReal r[3] = {0.0, 0.0, 0.0};

        if (m < dim)
          r[m] = 1.0; /* translations */
        else if (dim == 2) {
          r[0] = -p[1];
          r[1] = p[0];
        } /* rotation about z */
        else if (m == 3) {
          r[0] = -p[1];
          r[1] = p[0];
        } else if (m == 4) {
          r[1] = -p[2];
          r[2] = p[1];
        } else {
          r[0] = p[2];
          r[2] = -p[0];
        }
        for (PetscInt d = 0; d < dim; ++d)
          if (idx[d] >= 0) a[m][idx[d] - rstart] = r[d];
      }
    }
    PetscCall(VecRestoreArrayRead(coords, &x));
  }
  for (PetscInt m = 0; m < n; ++m) PetscCall(VecRestoreArray(mode[m], &a[m]));
  for (PetscInt m = 0; m < n; ++m) { /* modified Gram-Schmidt: MatNullSpaceCreate wants an orthonormal basis */
    PetscScalar dots[6];

    if (m > 0) {
      PetscCall(VecMDot(mode[m], m, mode, dots));
      for (PetscInt k = 0; k < m; ++k) dots[k] = -dots[k];
      PetscCall(VecMAXPY(mode[m], m, dots, mode));
    }
    PetscCall(VecNormalize(mode[m], NULL));
  }
  PetscCall(MatNullSpaceCreate(PetscObjectComm((PetscObject)dm), PETSC_FALSE, n, mode, nullspace));
  for (PetscInt m = 0; m < n; ++m) PetscCall(VecDestroy(&mode[m]));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The material and the degree of the displacement (-displacement_petscspace_degree, PETSc's name for it, default 1). */
PetscErrorCode ElasticityGetOptions(MPI_Comm comm, Material *mat, PetscInt *degree, PetscBool *section_check)
{
  PetscFunctionBeginUser;
  PetscOptionsBegin(comm, NULL, "Linear elastic material and its discretization", "Signorini");
  *degree = 1;
  PetscCall(PetscOptionsRangeInt("-displacement_petscspace_degree", "Degree of the Lagrange displacement space (P1/Q1 by default)", NULL, *degree,
                                 degree, NULL, 1, 8));
  *section_check = PETSC_FALSE;
  PetscCall(PetscOptionsBool("-section_check", "Build the P1 section both ways (the project's and DMCreateLocalSection()) and compare them",
                             "SectionSetUpP1", *section_check, section_check, NULL));
  mat->young_modulus = 1.0;
  PetscCall(PetscOptionsReal("-young_modulus", "Young's modulus E", NULL, mat->young_modulus, &mat->young_modulus, NULL));
  mat->poisson_ratio = 0.3;
  PetscCall(PetscOptionsReal("-poisson_ratio", "Poisson ratio nu, in (-1, 0.5)", NULL, mat->poisson_ratio, &mat->poisson_ratio, NULL));
  PetscOptionsEnd();
  PetscCall(OptionsCheckFinite(comm, "-young_modulus", mat->young_modulus));
  PetscCall(OptionsCheckFinite(comm, "-poisson_ratio", mat->poisson_ratio));
  PetscCheck(mat->young_modulus > 0.0, comm, PETSC_ERR_USER_INPUT, "-young_modulus must be positive, got %g", (double)mat->young_modulus);
  PetscCheck(mat->poisson_ratio > -1.0 && mat->poisson_ratio < 0.5, comm, PETSC_ERR_USER_INPUT, "-poisson_ratio must lie in (-1, 0.5), got %g",
             (double)mat->poisson_ratio);
  mat->lambda = mat->young_modulus * mat->poisson_ratio / ((1.0 + mat->poisson_ratio) * (1.0 - 2.0 * mat->poisson_ratio));
  mat->mu     = mat->young_modulus / (2.0 * (1.0 + mat->poisson_ratio));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Writes the material, the scene's obstacle, body force and own parameters into the constants[] of the kernels; the
   penalty's 1/eps is the contact's to set (ContactSetEps()), after this. */
PetscErrorCode ElasticityUpdateConstants(DM dm, const Material *mat, const Scene *scene)
{
  PetscDS     ds;
  PetscScalar c[CONST_SCENE_MAX];

  PetscFunctionBeginUser;
  c[CONST_LAMBDA]  = mat->lambda;
  c[CONST_MU]      = mat->mu;
  c[CONST_PENALTY] = 0.0; /* 1/eps, set by the contact (ContactSetEps()) */
  ObstaclePack(&scene->obstacle, &c[CONST_OBSTACLE]);
  for (PetscInt k = 0; k < 3; ++k) {
    c[CONST_BODY_FORCE + k] = scene->bcs.body_force[k];
    c[CONST_LOAD + k]       = 0.0; /* set while a surface load is assembled (BoundaryAddLoads) */
  }
  for (PetscInt i = 0; i < scene->num_constants; ++i) c[CONST_SCENE + i] = scene->constants[i];
  PetscCall(DMGetDS(dm, &ds));
  PetscCall(PetscDSSetConstants(ds, CONST_SCENE + scene->num_constants, c));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The displacement field of this degree (PetscFE, prefix displacement_) and the bulk weak form with the scene's body
   force and exact solution; the caller adds Gamma_D (BoundaryAddDirichlet(), before anything builds the section) and
   then the constants (ElasticityUpdateConstants()). */
PetscErrorCode ElasticitySetUpDiscretization(DM dm, const Scene *scene, PetscInt degree)
{
  MPI_Comm  comm = PetscObjectComm((PetscObject)dm);
  PetscFE   fe;
  PetscDS   ds;
  PetscInt  dim;
  PetscBool simplex;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMPlexIsSimplex(dm, &simplex));
  PetscCall(PetscFECreateLagrange(comm, dim, dim, simplex, degree, PETSC_DETERMINE, &fe)); /* the degree of ElasticityGetOptions() */
  PetscCall(PetscObjectSetName((PetscObject)fe, "displacement"));
  PetscCall(DMSetField(dm, 0, NULL, (PetscObject)fe));
  PetscCall(PetscFEDestroy(&fe));
  PetscCall(DMCreateDS(dm));
  PetscCall(DMGetDS(dm, &ds));
  {
    PetscBool has_body_force = PETSC_FALSE;

    for (PetscInt k = 0; k < dim; ++k) has_body_force = (PetscBool)(has_body_force || scene->bcs.body_force[k] != 0.0);
    PetscCall(PetscDSSetResidual(ds, 0, scene->f0_body ? scene->f0_body : (has_body_force ? f0_body_constant : NULL), f1_u));
  }
  PetscCall(PetscDSSetJacobian(ds, 0, 0, NULL, NULL, NULL, g3_uu));
  if (scene->exact) PetscCall(PetscDSSetExactSolution(ds, 0, scene->exact, (void *)scene->constants));
  PetscCall(DMSetNearNullSpaceConstructor(dm, 0, CreateRigidBodyModes));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* sigma = lambda tr(G) I + mu (G + G^T) for the displacement gradient G[i*dim+j] = du_i/dx_j. */
void ElasticStress(PetscInt dim, const Material *mat, const PetscReal grad[], PetscReal sigma[])
{
  PetscReal trace = 0.0;

  for (PetscInt i = 0; i < dim; ++i) trace += grad[i * dim + i];
  for (PetscInt i = 0; i < dim; ++i)
    for (PetscInt j = 0; j < dim; ++j) sigma[i * dim + j] = mat->mu * (grad[i * dim + j] + grad[j * dim + i]) + (i == j ? mat->lambda * trace : 0.0);
}
