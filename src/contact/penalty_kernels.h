/* The pointwise kernels of the penalty term on Gamma_C (the Gauss rule): pure functions of the displacement, the
   quadrature point and constants[] (include/physics.h's index map), shared by PETSc's boundary integration
   (src/contact/penalty.c) and the closed-form one on P1 simplices (src/contact/penalty_faces.c). */
#pragma once
#include "obstacle.h"

/* 1/eps at the face: 1/eps of the run (constants) over the face's eps factor, held inverted by the auxiliary field of the
   local eps (a cellwise constant) when there is one. */
static inline PetscReal Kappa(PetscInt NfAux, const PetscScalar a[], const PetscScalar constants[])
{
  return PetscRealPart(constants[CONST_PENALTY]) * (NfAux > 0 ? PetscRealPart(a[0]) : 1.0);
}

static inline void f0_bd_penalty(PetscInt dim, PetscInt Nf, PetscInt NfAux, const PetscInt uOff[], const PetscInt uOff_x[], const PetscScalar u[],
                                 const PetscScalar u_t[], const PetscScalar u_x[], const PetscInt aOff[], const PetscInt aOff_x[],
                                 const PetscScalar a[], const PetscScalar a_t[], const PetscScalar a_x[], PetscReal t, const PetscReal x[],
                                 const PetscReal n[], PetscInt numConstants, const PetscScalar constants[], PetscScalar f0[])
{
  PetscReal       nu[3];
  const PetscReal d = ObstaclePenetration(dim, &constants[CONST_OBSTACLE], x, u, nu);
  const PetscReal p = d > 0.0 ? Kappa(NfAux, a, constants) * d : 0.0;

  for (PetscInt c = 0; c < dim; ++c) f0[c] = p * nu[c];
}

/* The normal nu depends on the undeformed position only, so the Jacobian is exact: (1/eps) H(u . nu - g) nu nu^T. */
static inline void g0_bd_penalty(PetscInt dim, PetscInt Nf, PetscInt NfAux, const PetscInt uOff[], const PetscInt uOff_x[], const PetscScalar u[],
                                 const PetscScalar u_t[], const PetscScalar u_x[], const PetscInt aOff[], const PetscInt aOff_x[],
                                 const PetscScalar a[], const PetscScalar a_t[], const PetscScalar a_x[], PetscReal t, PetscReal u_tShift,
                                 const PetscReal x[], const PetscReal n[], PetscInt numConstants, const PetscScalar constants[], PetscScalar g0[])
{
  PetscReal nu[3];

  if (ObstaclePenetration(dim, &constants[CONST_OBSTACLE], x, u, nu) <= 0.0) return;
  for (PetscInt c = 0; c < dim; ++c)
    for (PetscInt e = 0; e < dim; ++e) g0[c * dim + e] = Kappa(NfAux, a, constants) * nu[c] * nu[e];
}

/* (1/2eps) [u_n - g]_+^2, the penalty energy density, in the first component: summed over the
   entries of the local boundary residual it gives the integral (the basis is a partition of unity). */
static inline void f0_bd_penalty_energy(PetscInt dim, PetscInt Nf, PetscInt NfAux, const PetscInt uOff[], const PetscInt uOff_x[],
                                        const PetscScalar u[], const PetscScalar u_t[], const PetscScalar u_x[], const PetscInt aOff[],
                                        const PetscInt aOff_x[], const PetscScalar a[], const PetscScalar a_t[], const PetscScalar a_x[], PetscReal t,
                                        const PetscReal x[], const PetscReal n[], PetscInt numConstants, const PetscScalar constants[],
                                        PetscScalar f0[])
{
  PetscReal       nu[3];
  const PetscReal d = ObstaclePenetration(dim, &constants[CONST_OBSTACLE], x, u, nu);

  for (PetscInt c = 1; c < dim; ++c) f0[c] = 0.0;
  f0[0] = d > 0.0 ? 0.5 * Kappa(NfAux, a, constants) * d * d : 0.0;
}
