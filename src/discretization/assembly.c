/* The bulk terms by the assembly this mesh takes (AssemblyResolve()): fe, PetscFE's generic loops over the cells and
   their closures, or p1, the closed form of the P1 simplex (assembly_p1.c). Both give K, F_bulk and K u_D to round-off
   (-assembly_check compares them); the rest of the code asks for the term and not for the assembly. */
#include "discretization.h"

/* K, the Jacobian of the bulk residual, assembled at locX (u = 0 with the Dirichlet values: K does not depend on it);
   with check, the closed form is compared with PETSc's integration (AssemblyP1Check()). The pointwise kernels read
   constants[] alone, so PetscFE's assembly takes no context. */
PetscErrorCode AssemblyCreateOperator(DM dm, AssemblyType assembly, const AssemblyP1Inputs *p1, PetscBool check, Vec locX, Mat *K)
{
  PetscFunctionBeginUser;
  if (assembly == ASSEMBLY_P1)
    PetscCall(AssemblyP1CreateMatrix(dm, p1, K));
  else
    PetscCall(DMCreateMatrix(dm, K));
  if (assembly == ASSEMBLY_FE) PetscCall(DMPlexSNESComputeJacobianFEM(dm, locX, *K, *K, NULL));
  if (check) PetscCall(AssemblyP1Check(dm, p1, locX));
  PetscCall(MatAssemblyBegin(*K, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*K, MAT_FINAL_ASSEMBLY));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* locF += F_bulk(locX), the bulk residual (body force and the lifting of the Dirichlet values in locX), local. */
PetscErrorCode AssemblyResidual(DM dm, AssemblyType assembly, const Material *mat, Vec locX, Vec locF)
{
  PetscFunctionBeginUser;
  if (assembly == ASSEMBLY_P1)
    PetscCall(AssemblyP1Residual(dm, mat, locX, locF)); /* the same residual without PetscFE's generic cell loop */
  else
    PetscCall(DMPlexSNESComputeResidualFEM(dm, locX, locF, NULL));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* locA = K u_D, the stiffness applied to the Dirichlet values loc_bc alone, local (the lift's energy 1/2 a(u_D, u_D)):
   on P1 only the cells at a fixed component contribute; PetscFE's residual gives it as F(u_D) - F(0), which cancels
   the body force. */
PetscErrorCode AssemblyLiftStiffness(DM dm, AssemblyType assembly, const Material *mat, Vec loc_bc, Vec locA)
{
  Vec locZ, locR;

  PetscFunctionBeginUser;
  PetscCall(VecZeroEntries(locA));
  if (assembly == ASSEMBLY_P1) {
    PetscCall(ElementP1AddFixedCellsStiffness(dm, mat, loc_bc, locA));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  PetscCall(DMGetLocalVector(dm, &locZ));
  PetscCall(DMGetLocalVector(dm, &locR));
  PetscCall(VecZeroEntries(locZ));
  PetscCall(VecZeroEntries(locR));
  PetscCall(DMPlexSNESComputeResidualFEM(dm, loc_bc, locA, NULL));
  PetscCall(DMPlexSNESComputeResidualFEM(dm, locZ, locR, NULL));
  PetscCall(VecAXPY(locA, -1.0, locR));
  PetscCall(DMRestoreLocalVector(dm, &locZ));
  PetscCall(DMRestoreLocalVector(dm, &locR));
  PetscFunctionReturn(PETSC_SUCCESS);
}
