/* One matrix for the bulk operator and the penalty Jacobian: J = K + P differs from K only in the rows of the contact
   dofs (P couples contact dofs only), so K's values in those rows are kept (a few hundred rows against the whole
   matrix) and J is made in K itself: those rows put back, P added. The residual computes K u with K's own rows there
   (BulkRowsMult()), exactly: no subtraction of the penalty term, which at small eps would cancel K's digits. */
#include "penalty.h"

/* A's values in the rows rows[0 .. n-1] (global numbers, owned), in CSR arrays allocated together (PetscFree3(*ptr,
   *cols, *vals)): row i's columns and values at ptr[i] .. ptr[i + 1] - 1. The contact rows of K here, and those of the
   finest GAMG prolongator (src/linear/pc_reuse.c). */
PetscErrorCode ContactCopyRows(Mat A, PetscInt n, const PetscInt rows[], PetscInt **ptr, PetscInt **cols, PetscScalar **vals)
{
  PetscInt nnz = 0;

  PetscFunctionBeginUser;
  for (PetscInt r = 0; r < n; ++r) {
    PetscInt ncols;

    PetscCall(MatGetRow(A, rows[r], &ncols, NULL, NULL));
    nnz += ncols;
    PetscCall(MatRestoreRow(A, rows[r], &ncols, NULL, NULL));
  }
  PetscCall(PetscMalloc3(n + 1, ptr, nnz, cols, nnz, vals));
  (*ptr)[0] = 0;
  for (PetscInt r = 0; r < n; ++r) {
    const PetscInt    *c;
    const PetscScalar *v;
    PetscInt           ncols;

    PetscCall(MatGetRow(A, rows[r], &ncols, &c, &v));
    PetscCall(PetscArraycpy(&(*cols)[(*ptr)[r]], c, ncols));
    PetscCall(PetscArraycpy(&(*vals)[(*ptr)[r]], v, ncols));
    (*ptr)[r + 1] = (*ptr)[r] + ncols;
    PetscCall(MatRestoreRow(A, rows[r], &ncols, &c, &v));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* K's rows at the free components of the contact nodes, their diagonal entries, and a scatter of the displacement at
   their columns (any rank's). */
PetscErrorCode BulkRowsSave(ContactBulkRows *br, const ContactSet *cs, PetscInt dim, Mat K)
{
  PetscInt rstart, n = 0, nnz;

  PetscFunctionBeginUser;
  PetscCall(BulkRowsFree(br));
  PetscCall(MatGetOwnershipRange(K, &rstart, NULL));
  for (PetscInt i = 0; i < cs->n * dim; ++i) n += cs->dof[i] >= 0;
  PetscCall(PetscMalloc1(n, &br->rows));
  n = 0;
  for (PetscInt i = 0; i < cs->n * dim; ++i)
    if (cs->dof[i] >= 0) br->rows[n++] = rstart + cs->dof[i];
  PetscCall(ContactCopyRows(K, n, br->rows, &br->ptr, &br->cols, &br->vals));
  nnz = br->ptr[n];
  PetscCall(PetscMalloc1(n, &br->diag));
  for (PetscInt r = 0; r < n; ++r) { /* the diagonal entry of each row */
    for (br->diag[r] = br->ptr[r]; br->diag[r] < br->ptr[r + 1] && br->cols[br->diag[r]] != br->rows[r]; ++br->diag[r]) {
    }
    PetscCheck(br->diag[r] < br->ptr[r + 1], PETSC_COMM_SELF, PETSC_ERR_PLIB, "K's pattern has no diagonal in contact row %" PetscInt_FMT,
               br->rows[r]);
  }
  {
    PetscInt *cols, ncols = nnz;
    IS        is;
    Vec       g;

    PetscCall(PetscMalloc1(nnz, &cols));
    PetscCall(PetscArraycpy(cols, br->cols, nnz));
    PetscCall(PetscSortRemoveDupsInt(&ncols, cols));
    PetscCall(PetscMalloc1(nnz, &br->lcols));
    for (PetscInt k = 0; k < nnz; ++k) PetscCall(PetscFindInt(br->cols[k], ncols, cols, &br->lcols[k]));
    PetscCall(ISCreateGeneral(PETSC_COMM_SELF, ncols, cols, PETSC_OWN_POINTER, &is));
    PetscCall(VecCreateSeq(PETSC_COMM_SELF, ncols, &br->x));
    PetscCall(MatCreateVecs(K, &g, NULL));
    PetscCall(VecScatterCreate(g, is, br->x, NULL, &br->scatter));
    PetscCall(VecDestroy(&g));
    PetscCall(ISDestroy(&is));
  }
  br->n             = n;
  br->jacobian_in_K = PETSC_FALSE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode BulkRowsFree(ContactBulkRows *br)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree(br->rows));
  PetscCall(PetscFree3(br->ptr, br->cols, br->vals));
  PetscCall(PetscFree(br->lcols));
  PetscCall(PetscFree(br->diag));
  PetscCall(VecScatterDestroy(&br->scatter));
  PetscCall(VecDestroy(&br->x));
  br->n             = 0;
  br->jacobian_in_K = PETSC_FALSE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* K's own values back in the rows of the contact dofs (collective: every rank holds the same jacobian_in_K). */
PetscErrorCode BulkRowsRestore(ContactBulkRows *br, Mat K, MatAssemblyType type)
{
  PetscFunctionBeginUser;
  for (PetscInt r = 0; r < br->n; ++r)
    PetscCall(MatSetValues(K, 1, &br->rows[r], br->ptr[r + 1] - br->ptr[r], &br->cols[br->ptr[r]], &br->vals[br->ptr[r]], INSERT_VALUES));
  PetscCall(MatAssemblyBegin(K, type));
  PetscCall(MatAssemblyEnd(K, type));
  br->jacobian_in_K = PETSC_FALSE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* R = K X with K the bulk operator, whether K holds the penalty Jacobian or not: the rows of the contact dofs are
   recomputed from K's own values, so that K is not touched (a residual evaluated between a Jacobian and its use, as by
   -snes_test_jacobian or a line search, must leave the Jacobian alone). */
PetscErrorCode BulkRowsMult(const ContactBulkRows *br, Mat K, Vec X, Vec R)
{
  PetscFunctionBeginUser;
  PetscCall(MatMult(K, X, R));
  if (br->jacobian_in_K) {
    const PetscScalar *x;
    PetscScalar       *r;
    PetscInt           rstart;

    PetscCall(VecScatterBegin(br->scatter, X, br->x, INSERT_VALUES, SCATTER_FORWARD));
    PetscCall(VecScatterEnd(br->scatter, X, br->x, INSERT_VALUES, SCATTER_FORWARD));
    PetscCall(VecGetOwnershipRange(R, &rstart, NULL));
    PetscCall(VecGetArrayRead(br->x, &x));
    PetscCall(VecGetArray(R, &r));
    for (PetscInt i = 0; i < br->n; ++i) {
      PetscScalar sum = 0.0;

      for (PetscInt k = br->ptr[i]; k < br->ptr[i + 1]; ++k) sum += br->vals[k] * x[br->lcols[k]];
      r[br->rows[i] - rstart] = sum;
    }
    PetscCall(VecRestoreArray(R, &r));
    PetscCall(VecRestoreArrayRead(br->x, &x));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}
