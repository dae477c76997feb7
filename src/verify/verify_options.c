/* Options of the verification: the accurate quadrature rule of the error norms and weak data, and -reference. */
#include <string.h>
#include "app.h"
#include "verify.h"

/* An HDF5 file starts with its 8-byte signature (the project's files have no user block). */
static PetscErrorCode VerifyCheckHDF5Signature(MPI_Comm comm, const char file[])
{
  const unsigned char signature[8] = {0x89, 'H', 'D', 'F', '\r', '\n', 0x1a, '\n'};
  unsigned char       head[8]      = {0};
  FILE               *fp;
  size_t              n = 0;

  PetscFunctionBeginUser;
  fp = fopen(file, "rb");
  if (fp) {
    n = fread(head, 1, sizeof(head), fp);
    (void)fclose(fp);
  }
  PetscCheck(n == sizeof(head) && !memcmp(head, signature, sizeof(head)), comm, PETSC_ERR_USER_INPUT,
             "Reference file '%s' (-reference) is not an HDF5 file", file);
  PetscFunctionReturn(PETSC_SUCCESS);
}

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
    char where[PETSC_MAX_PATH_LEN + 96];

    PetscCall(OptionsPathWhere(opts->reference, where, sizeof(where)));
    PetscCheck(exists, comm, PETSC_ERR_USER_INPUT, "Reference file '%s' (-reference) does not exist or cannot be read%s", opts->reference, where);
    PetscCall(VerifyCheckHDF5Signature(comm, opts->reference));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}
