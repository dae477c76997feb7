/* Options of the verification: the accurate quadrature rule of the error norms and weak data, and -reference. */
#include "signorini.h"

PetscErrorCode VerifyGetOptions(MPI_Comm comm, VerifyOptions *opts)
{
  PetscBool set;

  PetscFunctionBeginUser;
  PetscOptionsBegin(comm, NULL, "Verification: error norms and reference solutions", "Signorini");
  opts->quad_points = 4;
  PetscCall(PetscOptionsRangeInt("-verify_quadrature_points", "Gauss points per direction of the rule of the error norms and weak data", NULL,
                                 opts->quad_points, &opts->quad_points, NULL, 1, 20));
  opts->quad_refine = 2;
  PetscCall(PetscOptionsRangeInt("-verify_quadrature_refine", "Refinements of the reference cell for the composite rule on cells cut by a kink", NULL,
                                 opts->quad_refine, &opts->quad_refine, NULL, 0, 6));
  opts->reference[0] = '\0';
  PetscCall(PetscOptionsString("-reference", "HDF5 output of a reference run on the same or a uniformly refined mesh: norms against it", NULL,
                               opts->reference, opts->reference, sizeof(opts->reference), &set));
  PetscOptionsEnd();
  if (set) {
    PetscBool exists;

    PetscCheck(opts->reference[0], comm, PETSC_ERR_USER_INPUT, "-reference needs a file name");
    PetscCall(PetscTestFile(opts->reference, 'r', &exists));
    PetscCheck(exists, comm, PETSC_ERR_USER_INPUT, "Reference file '%s' (-reference) does not exist or cannot be read", opts->reference);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}
