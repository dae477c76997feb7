/* Guards for PETSc API differences between 3.18 (Debian 12) and newer releases. */
#pragma once
#include <petscversion.h>
#include <petscdmplex.h>

#if PETSC_VERSION_LT(3, 19, 0)
#  define PETSC_SUCCESS 0
#endif

/* DMPlexComputeBdResidualSingle/BdJacobianSingle moved the time argument in 3.20. */
#if PETSC_VERSION_LT(3, 20, 0)
#  define CompatComputeBdResidualSingle(dm, wf, key, locX, locF) DMPlexComputeBdResidualSingle(dm, 0.0, wf, key, locX, NULL, locF)
#  define CompatComputeBdJacobianSingle(dm, wf, label, n, vals, locX, J) \
    DMPlexComputeBdJacobianSingle(dm, 0.0, wf, label, n, vals, 0, locX, NULL, 0.0, J, J)
#else
#  define CompatComputeBdResidualSingle(dm, wf, key, locX, locF) DMPlexComputeBdResidualSingle(dm, wf, key, locX, NULL, 0.0, locF)
#  define CompatComputeBdJacobianSingle(dm, wf, label, n, vals, locX, J) \
    DMPlexComputeBdJacobianSingle(dm, wf, label, n, vals, 0, locX, NULL, 0.0, 0.0, J, J)
#endif

/* DMPlexSNESComputeResidualFEM/JacobianFEM keep their arguments; DMPlexSetSNESLocalFEM is not used. */

/* DMPlexCreateBoxMesh gained the localization arguments in 3.22. */
#if PETSC_VERSION_LT(3, 22, 0)
#  define CompatCreateBoxMesh(comm, dim, simplex, faces, lower, upper, periodicity, interpolate, dm) \
    DMPlexCreateBoxMesh(comm, dim, simplex, faces, lower, upper, periodicity, interpolate, dm)
#else
#  define CompatCreateBoxMesh(comm, dim, simplex, faces, lower, upper, periodicity, interpolate, dm) \
    DMPlexCreateBoxMesh(comm, dim, simplex, faces, lower, upper, periodicity, interpolate, 0, PETSC_FALSE, dm)
#endif

/* PETSC_NAN appeared after 3.18 */
#if !defined(PETSC_NAN)
#  include <math.h>
#  define PETSC_NAN ((PetscReal)NAN)
#endif

/* A helper that reads options inside a PetscOptionsBegin() block takes the block's PetscOptionsObject; its type became
   a pointer typedef in 3.23. */
#if PETSC_VERSION_LT(3, 23, 0)
typedef PetscOptionItems *CompatOptionItems;
#else
typedef PetscOptionItems CompatOptionItems;
#endif
