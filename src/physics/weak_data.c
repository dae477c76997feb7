/* Data of a manufactured solution through the weak form (verification.md section 2): for v = 0 on Gamma_D,
     L(v) = int_Omega sigma(u_exact) : eps(v) dx - int_Gamma_C sigma_n(u_exact) v_n ds,
   so no singular source term is ever evaluated pointwise. Integrated with the accurate rule of src/discretization/cell_quadrature.c. */
#include "mesh.h"
#include "obstacle.h"
#include "physics.h"
#include "discretization.h"

/* sigma(u_exact) at x, the load G of the weak form: the scene's exact gradient in the material */
PetscErrorCode WeakDataExactStress(const Scene *scene, const Material *mat, PetscInt dim, const PetscReal x[], PetscReal sigma[])
{
  PetscScalar g[9];
  PetscReal   grad[9];

  PetscFunctionBeginUser;
  PetscCall((*scene->exact_gradient)(dim, 0.0, x, dim * dim, g, (void *)scene->constants));
  for (PetscInt k = 0; k < dim * dim; ++k) grad[k] = PetscRealPart(g[k]);
  ElasticStress(dim, mat, grad, sigma);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* sigma_n(u_exact) = (sigma n) . n at x, with n the normal of the scene's obstacle at x */
PetscErrorCode WeakDataExactNormalStress(const Scene *scene, const Material *mat, PetscInt dim, const PetscReal x[], PetscReal *sn)
{
  PetscReal sigma[9], n[3], gap;

  PetscFunctionBeginUser;
  ObstacleGapNormalAt(&scene->obstacle, dim, x, n, &gap);
  PetscCall(WeakDataExactStress(scene, mat, dim, x, sigma));
  *sn = 0.0;
  for (PetscInt i = 0; i < dim; ++i)
    for (PetscInt j = 0; j < dim; ++j) *sn += n[i] * sigma[i * dim + j] * n[j];
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* r0 -= L for the scene's exact solution in the material, integrated with the accurate rule of quad: r0 holds the bulk
   residual at u = 0 (the Dirichlet lifting) on entry. *lift = L(u_D) of the Dirichlet lift (loc_bc: its values),
   for the energy (PostprocessLiftEnergy()), 0 without weak data; loc_r0 does not take L: the supports' reactions stay the
   stress a(u_h, phi) on Gamma_D that holds the body, which L on the fixed rows (a(u_exact, phi) there) would cancel. */
PetscErrorCode WeakDataAddToResidual(DM dm, const Scene *scene, const Material *mat, const VerifyOptions *quad, Vec loc_bc, Vec r0, PetscReal *lift)
{
  CellQuadrature cq;
  Vec            locL;
  PetscInt       dim, cStart, cEnd, nf, *faces;
  PetscScalar   *elem;

  PetscFunctionBeginUser;
  *lift = 0.0;
  if (!scene->weak_data) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCheck(scene->exact && scene->exact_gradient, PetscObjectComm((PetscObject)dm), PETSC_ERR_PLIB,
             "Scene %s asks for weak data but has no exact solution and gradient", scene->name);
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(CellQuadratureCreate(dm, scene, quad, &cq));
  PetscCall(PetscMalloc1(PetscMax(cq.Nb, 1), &elem));
  PetscCall(DMGetLocalVector(dm, &locL));
  PetscCall(VecZeroEntries(locL));
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  for (PetscInt c = cStart; c < cEnd; ++c) {
    PetscCall(CellQuadratureSetCell(&cq, c));
    for (PetscInt b = 0; b < cq.Nb; ++b) elem[b] = 0.0;
    for (PetscInt q = 0; q < cq.Nq; ++q) {
      PetscReal sigma[9];

      PetscCall(WeakDataExactStress(scene, mat, dim, &cq.x[q * dim], sigma));
      for (PetscInt b = 0; b < cq.Nb; ++b) {
        PetscReal s = 0.0;

        for (PetscInt k = 0; k < cq.Nc; ++k)
          for (PetscInt e = 0; e < dim; ++e)
            s += sigma[k * dim + e] * cq.D[((CellQuadratureGradientPoint(&cq, q) * cq.Nb + b) * cq.Nc + k) * dim + e];
        elem[b] += cq.w[q] * s;
      }
    }
    PetscCall(DMPlexVecSetClosure(dm, NULL, locL, c, elem, ADD_ALL_VALUES));
  }
  for (PetscInt s = 0; s < scene->bcs.ncontact; ++s) {
    PetscCall(MeshGetBoundaryFaces(dm, scene->bcs.contact_ids[s], &nf, &faces));
    for (PetscInt i = 0; i < nf; ++i) {
      PetscCall(CellQuadratureSetFace(&cq, faces[i]));
      for (PetscInt b = 0; b < cq.Nb; ++b) elem[b] = 0.0;
      for (PetscInt q = 0; q < cq.Nq; ++q) {
        PetscReal sn, n[3], gap;

        PetscCall(WeakDataExactNormalStress(scene, mat, dim, &cq.x[q * dim], &sn));
        ObstacleGapNormalAt(&scene->obstacle, dim, &cq.x[q * dim], n, &gap);
        for (PetscInt b = 0; b < cq.Nb; ++b) {
          PetscReal vn = 0.0;

          for (PetscInt k = 0; k < cq.Nc; ++k) vn += cq.B[(q * cq.Nb + b) * cq.Nc + k] * n[k];
          elem[b] -= cq.w[q] * sn * vn;
        }
      }
      PetscCall(DMPlexVecSetClosure(dm, NULL, locL, cq.cell, elem, ADD_ALL_VALUES));
    }
    PetscCall(PetscFree(faces));
  }
  {
    PetscScalar dot;

    PetscCall(VecDot(locL, loc_bc, &dot)); /* this rank's cells only: the sum over the ranks is L(u_D) */
    PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &dot, 1, MPIU_SCALAR, MPIU_SUM, PetscObjectComm((PetscObject)dm)));
    *lift = PetscRealPart(dot);
  }
  /* r0 -= L */
  PetscCall(VecScale(locL, -1.0));
  PetscCall(DMLocalToGlobal(dm, locL, ADD_VALUES, r0));
  PetscCall(DMRestoreLocalVector(dm, &locL));
  PetscCall(PetscFree(elem));
  PetscCall(CellQuadratureDestroy(&cq));
  PetscFunctionReturn(PETSC_SUCCESS);
}
