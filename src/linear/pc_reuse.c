/* When to rebuild the preconditioner (or the factorization) of the penalty Newton steps.
   J = K + (1/eps) P_A changes only in the Gamma_C rows of the nodes whose contact state changed, so J_new - J_old has
   a rank of about the number of those nodes: a Krylov method preconditioned by the previous build converges in about
   that many more iterations (exactly, for a direct solver). The build is reused while few nodes changed, eps is the
   same and the linear solves stay cheap; it is rebuilt otherwise.
   With GAMG (-contact_pc_update, the default) the hierarchy is built once and then follows the Jacobian: its change D
   since the last step lives in the contact rows, and each coarse operator A_c = R^T A_f R (R the prolongator)
   changes by R^T D R, a
   Galerkin product of a matrix with a few hundred nonzero rows. The hierarchy then equals a rebuild's (GAMG reuses its
   prolongators on a rebuild) at the cost of a few sparse products instead of the products of the whole matrix.
   Where the coarse levels are dense those products, and the coarse smoothers' new eigenvalue estimates, cost several
   linear iterations (docs/decisions.md, "The finest level alone"). There, while a Newton step changed the state of few contact
   nodes since the coarse operators last followed the Jacobian (at most -contact_pc_update_changes, at the same eps, the
   last linear solve converged in at most twice the iterations of the first after that, plus 5), only the finest level
   is updated: its smoother's Jacobi diagonal and Chebyshev bound (smoother_bound.c), while its operator is the Jacobian
   itself. The coarse operators are then the Galerkin products of an earlier Jacobian, which differs from this one by a
   term of the rank of those nodes: the preconditioner stays symmetric positive definite, and CG pays a few iterations
   for the change (a load path's steps settle the rim of the contact zone a few nodes per Newton step). "There" is where
   the last carried update cost more than PC_FINEST_ONLY_CYCLES CG iterations, in flops (deterministic, unlike times);
   where an update costs less, the finest-only steps cost more CG iterations than they save. */
#include "contact.h"
#include "linear_impl.h"

#define PC_FINEST_ONLY_CYCLES 2.0 /* the coarse operators may stay where a carried update costs more CG iterations than this */

/* Number of contact nodes (over all ranks) whose state differs from the state at the last build. */
static PetscErrorCode CountChangesSince(PcReuse *r, PetscInt dim, const PetscScalar x[], PetscBool **state, PetscBool record, PetscInt *changes)
{
  PetscInt          local = 0;
  const ContactSet *cs;

  PetscFunctionBeginUser;
  PetscCall(ContactGetSet(r->contact, &cs));
  if (!*state) PetscCall(PetscCalloc1(cs->n + 1, state)); /* no node penetrated before the first record */
  for (PetscInt i = 0; i < cs->n; ++i) {
    const PetscBool on = (PetscBool)(ContactNodePenetration(cs, dim, i, x) > 0.0);

    local += on != (*state)[i];
    if (record) (*state)[i] = on;
  }
  PetscCall(MPIU_Allreduce(&local, changes, 1, MPIU_INT, MPI_SUM, PetscObjectComm((PetscObject)r->K)));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* ... since the last build (record: the current states become the build's). */
/* The last linear solve needed more than twice the iterations of the first one after the preconditioner last changed
   (a build, or the coarse operators' last update), plus 5: the preconditioner no longer fits the Jacobian. */
static inline PetscBool LinearSolveGrew(PetscInt its, PetscInt its_first)
{
  return (PetscBool)(its_first >= 0 && its > 2 * its_first + 5);
}

static PetscErrorCode CountChanges(PcReuse *r, PetscInt dim, const PetscScalar x[], PetscBool record, PetscInt *changes)
{
  PetscFunctionBeginUser;
  PetscCall(CountChangesSince(r, dim, x, &r->built_active, record, changes));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Whether this Newton step updates the finest level only (the header's comment), and if not, the current states become
   those the coarse operators follow. Collective. */
static PetscErrorCode DecideFinestOnly(KSP ksp, DM dm, PcReuse *r, Vec X)
{
  PetscInt           changes = 0, its, dim;
  PetscReal          eps;
  KSPConvergedReason reason;
  const PetscScalar *x;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(ContactGetEps(r->contact, &eps));
  PetscCall(VecGetArrayRead(X, &x));
  r->finest_only = PETSC_FALSE;
  /* only where the coarse operators have followed the Jacobian since the build, at this eps (a new eps changes the
     penalty at every contact node, not at a few), and the last linear solve converged */
  if (r->dcoarse && r->opt->pc_update_changes > 0 && eps == r->carried_eps && r->cycle_cost > 0.0 &&
      r->carry_cost > PC_FINEST_ONLY_CYCLES * r->cycle_cost) {
    PetscCall(KSPGetIterationNumber(ksp, &its));
    PetscCall(KSPGetConvergedReason(ksp, &reason));
    if (r->its_after_carry < 0) r->its_after_carry = its;
    PetscCall(CountChangesSince(r, dim, x, &r->carried_active, PETSC_FALSE, &changes));
    r->finest_only = (PetscBool)(changes <= r->opt->pc_update_changes && reason >= 0 && !LinearSolveGrew(its, r->its_after_carry));
  }
  if (!r->finest_only) {
    PetscCall(CountChangesSince(r, dim, x, &r->carried_active, PETSC_TRUE, &changes));
    r->its_after_carry = -1; /* set by the next call */
    r->carried_eps     = eps;
  }
  PetscCall(VecRestoreArrayRead(X, &x));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The levels of a GAMG hierarchy whose coarse operators can follow the Jacobian (0 if there is none yet, or if the
   Jacobian is not K itself with its kept contact rows). */
static PetscErrorCode HierarchyLevels(SNES snes, PcReuse *r, PC *pc, PetscInt *nlevels)
{
  KSP       ksp;
  PetscBool is_gamg;

  PetscFunctionBeginUser;
  *nlevels = 0;
  PetscCall(SNESGetKSP(snes, &ksp));
  PetscCall(KSPGetPC(ksp, pc));
  PetscCall(PetscObjectTypeCompare((PetscObject)*pc, PCGAMG, &is_gamg));
  if (!is_gamg || !r->opt->pc_update || r->no_update || !ContactBulkRowsOf(r->contact) || !ContactBulkRowsOf(r->contact)->ptr)
    PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PCMGGetLevels(*pc, nlevels));
  for (PetscInt l = 0; l < *nlevels; ++l) {
    KSP smoother;
    Mat A, B;

    PetscCall(PCMGGetSmoother(*pc, l, &smoother));
    PetscCall(KSPGetOperators(smoother, &A, &B));
    if (A != B) *nlevels = 0; /* a level with its own preconditioning matrix: rebuild instead */
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The Jacobian's values in the contact rows into vals (collective only through the caller). */
static PetscErrorCode ContactRowValues(PcReuse *r, PetscScalar vals[])
{
  const ContactBulkRows *br = ContactBulkRowsOf(r->contact);

  PetscFunctionBeginUser;
  for (PetscInt row = 0; row < br->n; ++row) {
    const PetscScalar *v;
    PetscInt           ncols;

    PetscCall(MatGetRow(r->K, br->rows[row], &ncols, NULL, &v));
    PetscCheck(ncols == br->ptr[row + 1] - br->ptr[row], PETSC_COMM_SELF, PETSC_ERR_PLIB, "the Jacobian's row %" PetscInt_FMT " left K's pattern",
               br->rows[row]);
    PetscCall(PetscArraycpy(&vals[br->ptr[row]], v, ncols));
    PetscCall(MatRestoreRow(r->K, br->rows[row], &ncols, NULL, &v));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The coarse products of the updates. */
static PetscErrorCode DestroyProducts(PcReuse *r)
{
  PetscFunctionBeginUser;
  for (PetscInt l = 0; l < r->nlevels - 1 && r->dcoarse; ++l) PetscCall(MatDestroy(&r->dcoarse[l]));
  PetscCall(PetscFree(r->dcoarse));
  PetscCall(MatDestroy(&r->rlocal));
  PetscCall(MatDestroy(&r->dlocal));
  PetscCall(MatDestroy(&r->clocal));
  PetscCall(PetscFree2(r->mirror_k, r->mirror_at));
  PetscCall(PetscFree3(r->eff_vals, r->eff_dvals, r->zrows));
  PetscCall(PetscFree3(r->rrow_ptr, r->rrow_cols, r->rrow_vals));
  PetscCall(MatDestroy(&r->rfine));
  PetscCall(VecDestroy(&r->zmark));
  PetscCall(VecDestroy(&r->zcols));
  r->nmirror    = 0;
  r->nz         = 0;
  r->nlevels    = 0;
  r->carry_cost = 0.0; /* the costs are the hierarchy's: counted again on the next one */
  r->cycle_cost = 0.0;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The marks of the contact rows (1, or 2 in Z) at their columns, from any rank. */
static PetscErrorCode ScatterMarks(PcReuse *r, const ContactBulkRows *br)
{
  PetscFunctionBeginUser;
  PetscCall(VecScatterBegin(br->scatter, r->zmark, r->zcols, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecScatterEnd(br->scatter, r->zmark, r->zcols, INSERT_VALUES, SCATTER_FORWARD));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The mirrors: the entries (s, c) of J whose column c is a contact row of this rank and whose row s is no contact row
   of any rank, J(s, c) = K(c, s) by symmetry. */
static PetscErrorCode MirrorsSetUp(PcReuse *r)
{
  const ContactBulkRows *br = ContactBulkRowsOf(r->contact);
  PetscInt               n  = 0;
  const PetscScalar     *mark;

  PetscFunctionBeginUser;
  PetscCall(MatCreateVecs(r->K, &r->zmark, NULL));
  PetscCall(VecDuplicate(br->x, &r->zcols));
  for (PetscInt row = 0; row < br->n; ++row) PetscCall(VecSetValue(r->zmark, br->rows[row], 1.0, INSERT_VALUES));
  PetscCall(VecAssemblyBegin(r->zmark));
  PetscCall(VecAssemblyEnd(r->zmark));
  PetscCall(ScatterMarks(r, br));
  PetscCall(VecGetArrayRead(r->zcols, &mark));
  for (PetscInt k = 0; k < br->ptr[br->n]; ++k) n += PetscRealPart(mark[br->lcols[k]]) == 0.0;
  PetscCall(PetscMalloc2(n, &r->mirror_k, n, &r->mirror_at));
  r->nmirror = 0;
  for (PetscInt row = 0; row < br->n; ++row) {
    const PetscInt kd = br->diag[row];

    for (PetscInt k = br->ptr[row]; k < br->ptr[row + 1]; ++k)
      if (PetscRealPart(mark[br->lcols[k]]) == 0.0) {
        r->mirror_k[r->nmirror]  = k;
        r->mirror_at[r->nmirror] = br->lcols[kd];
        r->nmirror++;
      }
  }
  PetscCall(VecRestoreArrayRead(r->zcols, &mark));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* J' at dlocal's entries, from J's values in the contact rows (jvals): J itself without the truncation; with it, zero
   in the rows and columns of Z, the contact dofs whose penalty diagonal exceeds -contact_pc_update_truncate times K's
   diagonal. Such a row is nearly diagonal, so the finest level's smoother (Jacobi, SOR) solves it alone, while in the coarse
   operators its 1/eps would pin every coarse function touching it (GAMG's aggregates mix the contact dofs with the
   bulk); a rebuild at that eps would leave the same dofs out of its aggregates. Also sets zrows. */
static PetscErrorCode EffectiveValues(PcReuse *r, const PetscScalar jvals[], PetscScalar eff[])
{
  const ContactBulkRows *br    = ContactBulkRowsOf(r->contact);
  const PetscInt         nnz   = br->ptr[br->n];
  const PetscReal        ratio = r->opt->pc_update_truncate;
  const PetscScalar     *mark;

  PetscFunctionBeginUser;
  if (ratio <= 0.0) {
    PetscCall(PetscArraycpy(eff, jvals, nnz));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  r->nz = 0;
  for (PetscInt row = 0; row < br->n; ++row) {
    const PetscInt  kd   = br->diag[row];
    const PetscBool in_z = (PetscBool)(PetscRealPart(jvals[kd] - br->vals[kd]) > ratio * PetscRealPart(br->vals[kd]));
    if (in_z) r->zrows[r->nz++] = br->rows[row];
    PetscCall(VecSetValue(r->zmark, br->rows[row], in_z ? 2.0 : 1.0, INSERT_VALUES));
  }
  PetscCall(VecAssemblyBegin(r->zmark));
  PetscCall(VecAssemblyEnd(r->zmark));
  PetscCall(ScatterMarks(r, br));
  PetscCall(VecGetArrayRead(r->zcols, &mark));
  for (PetscInt row = 0; row < br->n; ++row) {
    const PetscInt kd = br->diag[row];

    for (PetscInt k = br->ptr[row]; k < br->ptr[row + 1]; ++k)
      eff[k] = PetscRealPart(mark[br->lcols[kd]]) == 2.0 || PetscRealPart(mark[br->lcols[k]]) == 2.0 ? 0.0 : jvals[k];
  }
  for (PetscInt t = 0; t < r->nmirror; ++t) eff[nnz + t] = PetscRealPart(mark[r->mirror_at[t]]) == 2.0 ? 0.0 : br->vals[r->mirror_k[t]];
  PetscCall(VecRestoreArrayRead(r->zcols, &mark));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The finest prolongator's rows at the owned contact rows, as GAMG made them. */
static PetscErrorCode ProlongatorRowsSave(PC pc, PcReuse *r)
{
  const ContactBulkRows *br = ContactBulkRowsOf(r->contact);

  PetscFunctionBeginUser;
  PetscCall(PCMGGetInterpolation(pc, r->nlevels - 1, &r->rfine));
  PetscCall(PetscObjectReference((PetscObject)r->rfine));
  PetscCall(ContactCopyRows(r->rfine, br->n, br->rows, &r->rrow_ptr, &r->rrow_cols, &r->rrow_vals));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The finest prolongator's contact rows: zero in Z (all = PETSC_FALSE), GAMG's values elsewhere (all rows with all). */
static PetscErrorCode ProlongatorRowsSet(PcReuse *r, PetscBool all)
{
  const ContactBulkRows *br = ContactBulkRowsOf(r->contact);
  PetscScalar           *zero;
  PetscInt               iz = 0, nmax = 0;

  PetscFunctionBeginUser;
  if (!r->rfine) PetscFunctionReturn(PETSC_SUCCESS);
  for (PetscInt row = 0; row < br->n; ++row) nmax = PetscMax(nmax, r->rrow_ptr[row + 1] - r->rrow_ptr[row]);
  PetscCall(PetscCalloc1(nmax, &zero));
  for (PetscInt row = 0; row < br->n; ++row) {
    const PetscInt  n    = r->rrow_ptr[row + 1] - r->rrow_ptr[row];
    const PetscBool in_z = (PetscBool)(!all && iz < r->nz && r->zrows[iz] == br->rows[row]); /* zrows follow the rows' order */

    iz += in_z;
    PetscCall(
        MatSetValues(r->rfine, 1, &br->rows[row], n, &r->rrow_cols[r->rrow_ptr[row]], in_z ? zero : &r->rrow_vals[r->rrow_ptr[row]], INSERT_VALUES));
  }
  PetscCall(PetscFree(zero));
  PetscCall(MatAssemblyBegin(r->rfine, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(r->rfine, MAT_FINAL_ASSEMBLY));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The product on the finest level without matrices of its size: D is nonzero in the contact rows only, at the columns
   S of those rows, so R^T D R = R_S^T D_S R_S with R_S the rows S of the prolongator (fetched from any rank) and D_S
   the change restricted to S x S. Each rank computes its own part, and a COO matrix sums the parts. */
static PetscErrorCode FinestProductSetUp(PC pc, PcReuse *r)
{
  const ContactBulkRows *br  = ContactBulkRowsOf(r->contact);
  const PetscInt         nnz = br->ptr[br->n];
  PetscInt               nS  = nnz, N1, n1, *S, *coo_i, *coo_j, nrows;
  const PetscInt        *ia, *ja;
  PetscBool              done;
  PetscCount             ncoo;
  IS                     is_rows, is_cols;
  Mat                    R, *sub;

  PetscFunctionBeginUser;
  PetscCall(PCMGGetInterpolation(pc, r->nlevels - 1, &R));
  PetscCall(MatGetSize(R, NULL, &N1));
  PetscCall(MatGetLocalSize(R, NULL, &n1));
  PetscCall(PetscMalloc1(nnz, &S));
  PetscCall(PetscArraycpy(S, br->cols, nnz));
  PetscCall(PetscSortRemoveDupsInt(&nS, S)); /* the order of bulk_lcols */
  PetscCall(ISCreateGeneral(PETSC_COMM_SELF, nS, S, PETSC_OWN_POINTER, &is_rows));
  PetscCall(ISCreateStride(PETSC_COMM_SELF, N1, 0, 1, &is_cols));
  PetscCall(MatCreateSubMatrices(R, 1, &is_rows, &is_cols, MAT_INITIAL_MATRIX, &sub));
  r->rlocal = sub[0];
  PetscCall(PetscFree(sub));
  /* with the truncation, the columns S that are no contact row (on any rank) get the mirrors of their entries */
  if (r->opt->pc_update_truncate > 0.0) {
    PetscCall(MirrorsSetUp(r));
    PetscCall(ProlongatorRowsSave(pc, r));
  }
  /* D_S in COO form: the contact rows' places in S, their columns' places (bulk_lcols); then the mirrors */
  PetscCall(PetscMalloc2(nnz + r->nmirror, &coo_i, nnz + r->nmirror, &coo_j));
  for (PetscInt row = 0; row < br->n; ++row) {
    const PetscInt at = br->lcols[br->diag[row]]; /* the row's own place in S */

    for (PetscInt k = br->ptr[row]; k < br->ptr[row + 1]; ++k) {
      coo_i[k] = at;
      coo_j[k] = br->lcols[k];
    }
  }
  for (PetscInt t = 0; t < r->nmirror; ++t) {
    coo_i[nnz + t] = br->lcols[r->mirror_k[t]];
    coo_j[nnz + t] = r->mirror_at[t];
  }
  PetscCall(MatCreate(PETSC_COMM_SELF, &r->dlocal));
  PetscCall(MatSetSizes(r->dlocal, nS, nS, nS, nS));
  PetscCall(MatSetType(r->dlocal, MATSEQAIJ));
  PetscCall(MatSetPreallocationCOO(r->dlocal, nnz + r->nmirror, coo_i, coo_j));
  PetscCall(PetscFree2(coo_i, coo_j));
  /* the coarse operators hold the build's Jacobian, nothing left out */
  PetscCall(PetscMalloc3(nnz + r->nmirror, &r->eff_vals, nnz + r->nmirror, &r->eff_dvals, br->n, &r->zrows));
  PetscCall(PetscArraycpy(r->eff_vals, r->built_vals, nnz));
  for (PetscInt t = 0; t < r->nmirror; ++t) r->eff_vals[nnz + t] = br->vals[r->mirror_k[t]];
  PetscCall(PetscArrayzero(r->eff_dvals, nnz + r->nmirror));
  PetscCall(MatSetValuesCOO(r->dlocal, r->eff_dvals, INSERT_VALUES));
  PetscCall(MatPtAP(r->dlocal, r->rlocal, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &r->clocal));
  /* the sum over the ranks, on the first coarse level's layout */
  PetscCall(MatGetRowIJ(r->clocal, 0, PETSC_FALSE, PETSC_FALSE, &nrows, &ia, &ja, &done));
  PetscCheck(done, PETSC_COMM_SELF, PETSC_ERR_PLIB, "no CSR access to the coarse product");
  ncoo = ia[nrows];
  PetscCall(PetscMalloc2(ncoo, &coo_i, ncoo, &coo_j));
  for (PetscInt row = 0; row < nrows; ++row)
    for (PetscInt k = ia[row]; k < ia[row + 1]; ++k) {
      coo_i[k] = row;
      coo_j[k] = ja[k];
    }
  PetscCall(MatRestoreRowIJ(r->clocal, 0, PETSC_FALSE, PETSC_FALSE, &nrows, &ia, &ja, &done));
  PetscCall(MatCreate(PetscObjectComm((PetscObject)pc), &r->dcoarse[r->nlevels - 2]));
  PetscCall(MatSetSizes(r->dcoarse[r->nlevels - 2], n1, n1, N1, N1));
  PetscCall(MatSetType(r->dcoarse[r->nlevels - 2], MATAIJ));
  PetscCall(MatSetPreallocationCOO(r->dcoarse[r->nlevels - 2], ncoo, coo_i, coo_j));
  PetscCall(PetscFree2(coo_i, coo_j));
  PetscCall(ISDestroy(&is_rows));
  PetscCall(ISDestroy(&is_cols));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* -contact_pc_update_check: each updated coarse operator against the Galerkin product of the level above, computed
   in full (R^T A_f R, as a rebuild would; with the truncation, R's rows Z are zero). */
static PetscErrorCode CheckHierarchy(PC pc, PetscInt nlevels, PcReuse *r)
{
  PetscFunctionBeginUser;
  for (PetscInt l = nlevels - 1; l > 0; --l) {
    Mat       R, Af, Ac, C;
    KSP       smoother;
    PetscReal norm, diff;

    PetscCall(PCMGGetInterpolation(pc, l, &R));
    PetscCall(PCMGGetSmoother(pc, l, &smoother));
    PetscCall(KSPGetOperators(smoother, &Af, NULL));
    PetscCall(PCMGGetSmoother(pc, l - 1, &smoother));
    PetscCall(KSPGetOperators(smoother, &Ac, NULL));
    PetscCall(MatPtAP(Af, R, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &C));
    PetscCall(MatNorm(C, NORM_FROBENIUS, &norm));
    PetscCall(MatAXPY(C, -1.0, Ac, DIFFERENT_NONZERO_PATTERN));
    PetscCall(MatNorm(C, NORM_FROBENIUS, &diff));
    PetscCall(MatDestroy(&C));
    PetscCall(PetscPrintf(PetscObjectComm((PetscObject)pc),
                          "pc update check: update %" PetscInt_FMT ", level %" PetscInt_FMT " of %" PetscInt_FMT
                          ": ||A_c - R^T A_f R||_F / ||R^T A_f R||_F = %.3e\n",
                          r->updates, l - 1, nlevels, (double)(diff / norm)));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The hierarchy's nonzeros, counted once per build (the updates keep the operators' patterns): those of the coarse
   levels, whose smoothers estimate their eigenvalues again at each carried update (Chebyshev's 10 CG steps, a product
   with the level's operator each), and the flops of a CG iteration (a product with the finest operator, and a V-cycle:
   on each level 2 Chebyshev steps down and 2 up and a residual, 5 products with its operator), 2 flops a nonzero.
   Collective. */
static PetscErrorCode HierarchyNonzeros(PC pc, PetscInt nlevels, PcReuse *r)
{
  PetscReal coarse = 0.0, all = 0.0, fine = 0.0;

  PetscFunctionBeginUser;
  for (PetscInt l = 0; l < nlevels; ++l) {
    KSP     smoother;
    Mat     A;
    MatInfo info;

    PetscCall(PCMGGetSmoother(pc, l, &smoother));
    PetscCall(KSPGetOperators(smoother, &A, NULL));
    PetscCall(MatGetInfo(A, MAT_GLOBAL_SUM, &info));
    all += info.nz_used;
    if (l < nlevels - 1)
      coarse += info.nz_used;
    else
      fine = info.nz_used;
  }
  r->coarse_nnz = coarse;
  r->cycle_cost = 2.0 * (fine + 5.0 * all);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The flops of a carried update: its products (the flops counted on this rank, summed over the ranks) and the coarse
   smoothers' new eigenvalue estimates (HierarchyNonzeros()). Collective. */
static PetscErrorCode CarryCost(PC pc, PetscLogDouble products, PcReuse *r)
{
  PetscFunctionBeginUser;
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &products, 1, MPI_DOUBLE, MPI_SUM, PetscObjectComm((PetscObject)pc)));
  r->carry_cost = (PetscReal)products + 2.0 * 10.0 * r->coarse_nnz;
  PetscCall(PetscInfo(pc, "carried update: %g flops (%g in its products), a CG iteration %g: %.2f iterations\n", (double)r->carry_cost,
                      (double)products, (double)r->cycle_cost, (double)(r->carry_cost / r->cycle_cost)));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The change of the Jacobian since the last build or update, carried down the hierarchy: each coarse operator gets
   R^T D R, D the change on the level above (the first product makes the patterns, the later ones reuse them). */
static PetscErrorCode UpdateHierarchy(PC pc, PetscInt nlevels, PcReuse *r)
{
  const ContactBulkRows *br   = ContactBulkRowsOf(r->contact);
  PetscInt               nnz  = br->ptr[br->n];
  PetscReal              dmax = 0.0;
  PetscLogDouble         flops0, flops1;

  PetscFunctionBeginUser;
  if (!r->dcoarse) {
    r->nlevels = nlevels;
    PetscCall(PetscCalloc1(nlevels, &r->dcoarse));
    PetscCall(FinestProductSetUp(pc, r));
    PetscCall(HierarchyNonzeros(pc, nlevels, r));
  }
  PetscCheck(r->nlevels == nlevels, PetscObjectComm((PetscObject)pc), PETSC_ERR_PLIB, "the multigrid hierarchy changed its levels");
  PetscCall(ContactRowValues(r, r->dvals));
  PetscCall(PetscArraycpy(r->built_vals, r->dvals, nnz)); /* J now, for the finest smoother's bound */
  if (r->finest_only) { /* the coarse operators, R's rows Z and eff_vals stay as they are, consistent with each other */
    KSP smoother;
    Mat A;

    PetscCall(PCMGGetSmoother(pc, nlevels - 1, &smoother));
    PetscCall(KSPGetOperators(smoother, &A, NULL));
    PetscCall(KSPSetOperators(smoother, A, A)); /* its Jacobi diagonal again */
    if (!r->opt->pc_update_esteig) PetscCall(SmootherBoundFinest(r, pc, nlevels, r->built_vals, r->opt->pc_update_check));
    r->finest_updates++;
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  PetscCall(EffectiveValues(r, r->dvals, r->eff_dvals));
  PetscCall(ProlongatorRowsSet(r, PETSC_FALSE));
  for (PetscInt k = 0; k < nnz + r->nmirror; ++k) {
    const PetscScalar now = r->eff_dvals[k];

    r->eff_dvals[k] = now - r->eff_vals[k];
    r->eff_vals[k]  = now;
    dmax            = PetscMax(dmax, PetscAbsScalar(r->eff_dvals[k]));
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &dmax, 1, MPIU_REAL, MPIU_MAX, PetscObjectComm((PetscObject)pc)));
  if (dmax == 0.0) PetscFunctionReturn(PETSC_SUCCESS); /* the same Jacobian in the contact rows: nothing to carry */
  PetscCall(PetscGetFlops(&flops0));
  /* the first coarse level: this rank's R_S^T D_S R_S, summed over the ranks */
  PetscCall(MatSetValuesCOO(r->dlocal, r->eff_dvals, INSERT_VALUES));
  PetscCall(MatPtAP(r->dlocal, r->rlocal, MAT_REUSE_MATRIX, PETSC_DEFAULT, &r->clocal));
  {
    const PetscScalar *v;

    PetscCall(MatSeqAIJGetArrayRead(r->clocal, &v));
    PetscCall(MatSetValuesCOO(r->dcoarse[nlevels - 2], v, INSERT_VALUES));
    PetscCall(MatSeqAIJRestoreArrayRead(r->clocal, &v));
  }
  for (PetscInt l = nlevels - 1; l > 0; --l) {
    Mat R, A;
    KSP smoother;

    if (l < nlevels - 1) {
      PetscCall(PCMGGetInterpolation(pc, l, &R));
      PetscCall(MatPtAP(r->dcoarse[l], R, r->dcoarse[l - 1] ? MAT_REUSE_MATRIX : MAT_INITIAL_MATRIX, PETSC_DEFAULT, &r->dcoarse[l - 1]));
    }
    PetscCall(PCMGGetSmoother(pc, l - 1, &smoother));
    PetscCall(KSPGetOperators(smoother, &A, NULL));
    PetscCall(MatAXPY(A, 1.0, r->dcoarse[l - 1], SUBSET_NONZERO_PATTERN));
  }
  PetscCall(PetscGetFlops(&flops1));
  PetscCall(CarryCost(pc, flops1 - flops0, r));
  if (r->opt->pc_update_check) PetscCall(CheckHierarchy(pc, nlevels, r));
  /* every level's operator is new: its Chebyshev smoother estimates its eigenvalues again, its Jacobi or LU sets up
     again (KSPSetOperators() marks the new matrix, as a rebuild would) */
  for (PetscInt l = 0; l < nlevels; ++l) {
    KSP smoother;
    Mat A;

    PetscCall(PCMGGetSmoother(pc, l, &smoother));
    PetscCall(KSPGetOperators(smoother, &A, NULL));
    PetscCall(KSPSetOperators(smoother, A, A));
  }
  /* except the finest level's Chebyshev interval, which a bound keeps (smoother_bound.c) */
  if (!r->opt->pc_update_esteig) PetscCall(SmootherBoundFinest(r, pc, nlevels, r->built_vals, r->opt->pc_update_check));
  r->updates++;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A PCMG of one level (the coarsest box's own solve) is its coarse solve, whose operator is the Jacobian itself: PETSc
   factors it again at every Newton step whose Jacobian changed, whatever the SNES's lag says of the outer PC. In 3D its
   coarse KSP is told to keep the factorization where the outer PC is kept, as a factorization is (the count of changed
   nodes decides); in 2D the coarsest box factors in about a millisecond, and keeping it costs more than it saves: 2D
   factors again (docs/decisions.md, "The coarsest box's factorization"). *coarse: that coarse KSP in 3D, else NULL. */
static PetscErrorCode OneLevelMG(KSP ksp, PetscInt dim, KSP *coarse)
{
  PC        pc;
  PetscBool is_mg;
  PetscInt  nlevels = 0;

  PetscFunctionBeginUser;
  *coarse = NULL;
  if (dim != 3) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(PetscObjectTypeCompare((PetscObject)pc, PCMG, &is_mg));
  if (is_mg) PetscCall(PCMGGetLevels(pc, &nlevels));
  if (nlevels == 1) PetscCall(PCMGGetCoarseSolve(pc, coarse));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Called by the Jacobian evaluation at X, before SNES sets up the preconditioner: sets the SNES preconditioner lag to
   rebuild (-2) or reuse (-1), and records the state of the build. */
PetscErrorCode PcReuseDecide(PcReuse *r, SNES snes, DM dm, Vec X)
{
  KSP                ksp, one_level;
  PetscInt           dim, changes = 0, its = 0;
  KSPConvergedReason reason = KSP_CONVERGED_ITERATING;
  PetscBool          rebuild;
  const PetscScalar *x;
  PetscReal          eps;

  PetscFunctionBeginUser;
  if (!r->enabled) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(SNESGetKSP(snes, &ksp));
  PetscCall(OneLevelMG(ksp, dim, &one_level));
  r->update = PETSC_FALSE;
  if (r->built) {
    PC       pc;
    PetscInt nlevels;

    PetscCall(HierarchyLevels(snes, r, &pc, &nlevels));
    if (nlevels > 1 && r->recorded) { /* the hierarchy follows the Jacobian (PcReuseAfterJacobian()): no rebuild */
      r->update = PETSC_TRUE;
      PetscCall(DecideFinestOnly(ksp, dm, r, X));
      PetscCall(SNESSetLagPreconditioner(snes, -1));
      PetscFunctionReturn(PETSC_SUCCESS);
    }
  }
  PetscCall(VecGetArrayRead(X, &x));
  PetscCall(ContactGetEps(r->contact, &eps));
  rebuild = (PetscBool)(!r->built || r->eps != eps);
  if (!rebuild) {
    PC        pc;
    PetscBool geometric;

    PetscCall(CountChanges(r, dim, x, PETSC_FALSE, &changes));
    PetscCall(KSPGetIterationNumber(ksp, &its));
    PetscCall(KSPGetConvergedReason(ksp, &reason));
    /* The boxes' geometric multigrid (PCMG) is not rebuilt for the count of changed nodes: its finest level is the
       Jacobian itself, whose Jacobi diagonal and Chebyshev estimate PETSc sets up again when its values change, and
       only its Galerkin coarse operators stay those of the build, a change of the rank of those nodes (docs/decisions.md,
       "The boxes' multigrid kept"). A factorization is exact on
       the Jacobian of its build: each changed node costs CG about dim iterations. */
    PetscCall(KSPGetPC(ksp, &pc));
    PetscCall(PetscObjectTypeCompare((PetscObject)pc, PCMG, &geometric));
    geometric = (PetscBool)(geometric && !one_level); /* with one level its coarse solve factors the Jacobian itself (OneLevelMG()) */
    /* rebuild after a failed solve, or when the last solve needed twice the iterations of the first after the build */
    rebuild = (PetscBool)((!geometric && changes > r->opt->pc_reuse_changes) || reason < 0 || LinearSolveGrew(its, r->its_after_build));
  }
  if (one_level) PetscCall(KSPSetReusePreconditioner(one_level, (PetscBool)!rebuild));
  if (rebuild) {
    PetscCall(CountChanges(r, dim, x, PETSC_TRUE, &changes));
    r->built           = PETSC_TRUE;
    r->eps             = eps;
    r->its_after_build = -1; /* set by the next call */
    r->builds++;
    r->record = PETSC_TRUE;
    PetscCall(SNESSetLagPreconditioner(snes, -2)); /* rebuild now, then reuse until told otherwise */
  } else {
    if (r->its_after_build < 0) r->its_after_build = its;
    PetscCall(SNESSetLagPreconditioner(snes, -1));
  }
  PetscCall(VecRestoreArrayRead(X, &x));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Called by the Jacobian evaluation once the Jacobian is assembled: records its contact rows for a build, or carries
   their change down the hierarchy. */
PetscErrorCode PcReuseAfterJacobian(PcReuse *r, SNES snes)
{
  const ContactBulkRows *br = ContactBulkRowsOf(r->contact);
  PC                     pc;
  PetscInt               nlevels;

  PetscFunctionBeginUser;
  if (!r->enabled || !r->opt->pc_update || r->no_update || !br->jacobian_in_K) PetscFunctionReturn(PETSC_SUCCESS);
  if (r->update) {
    PetscCall(HierarchyLevels(snes, r, &pc, &nlevels));
    PetscCall(UpdateHierarchy(pc, nlevels, r));
  } else if (r->record) {
    KSP       ksp;
    PetscBool is_gamg;

    r->record = PETSC_FALSE;
    PetscCall(SNESGetKSP(snes, &ksp));
    PetscCall(KSPGetPC(ksp, &pc));
    PetscCall(PetscObjectTypeCompare((PetscObject)pc, PCGAMG, &is_gamg));
    if (!is_gamg) PetscFunctionReturn(PETSC_SUCCESS);
    if (!r->recorded) PetscCall(PetscMalloc2(br->ptr[br->n], &r->built_vals, br->ptr[br->n], &r->dvals));
    r->recorded = PETSC_TRUE;
    PetscCall(ContactRowValues(r, r->built_vals));
    {
      const PetscInt nnz  = br->ptr[br->n];
      PetscBool      on_K = PETSC_TRUE;

      PetscCheck(!r->bound_set, PetscObjectComm((PetscObject)pc), PETSC_ERR_PLIB, "a rebuild after the finest smoother's interval was bounded");
      for (PetscInt k = 0; k < nnz && on_K; ++k) on_K = (PetscBool)(r->built_vals[k] == br->vals[k]);
      PetscCall(MPIU_Allreduce(&on_K, &r->built_on_K, 1, MPIU_BOOL, MPI_LAND, PetscObjectComm((PetscObject)pc)));
    }
    PetscCall(ProlongatorRowsSet(r, PETSC_TRUE)); /* GAMG may reuse its prolongators: give them back whole */
    PetscCall(DestroyProducts(r));                /* a rebuild may make new prolongators: new patterns */
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* What the reuse reads, for the life of the problem: the bulk operator K, in which the Jacobian is made
   (ContactComputeJacobian()), the contact term and the solver's options. None is referenced. */
/* The SNES's Jacobian evaluation with the reuse around it: the decision at the iterate's displacement (the core's
   LinearCore), the core's own evaluation, then the record or the update. The order is the one of a Jacobian callback
   that calls them itself; SNESComputeJacobian() applies the lag the decision set (SNESSetLagPreconditioner()) once this
   returns. */
static PetscErrorCode PcReuseJacobian(SNES snes, Vec X, Mat J, Mat P, void *ctx)
{
  PcReuse *r = (PcReuse *)ctx;
  DM       dm;
  Vec      u;

  PetscFunctionBeginUser;
  if (r->enabled) { /* off (SNESVI, a direct solve, -contact_pc_reuse 0): the core's evaluation alone */
    PetscCall(SNESGetDM(snes, &dm));
    PetscCall((*r->core.displacement)(r->core.core, X, &u));
    PetscCall(PcReuseDecide(r, snes, dm, u));
  }
  PetscCall((*r->jacobian)(snes, X, J, P, r->jacobian_ctx));
  if (r->enabled) PetscCall(PcReuseAfterJacobian(r, snes));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Attaches the reuse to the SNES: its Jacobian evaluation, the core's callback, is wrapped by PcReuseJacobian(), with
   the same matrices; the reuse acts where it is enabled (set before the first Jacobian). A PC type wrapping the inner PC would see neither the
   iterate nor the SNES's lag, which the decision needs, and an SNES update hook (SNESSetUpdate()) has no context; docs/decisions.md, "The
   acceleration's hooks". */
PetscErrorCode PcReuseAttach(PcReuse *r, SNES snes, const LinearCore *core)
{
  Mat A, P;

  PetscFunctionBeginUser;
  r->core = *core;
  PetscCall(SNESGetJacobian(snes, &A, &P, &r->jacobian, &r->jacobian_ctx));
  PetscCheck(r->jacobian, PetscObjectComm((PetscObject)snes), PETSC_ERR_ARG_WRONGSTATE, "The SNES has no Jacobian callback to attach the reuse to");
  PetscCall(SNESSetJacobian(snes, A, P, PcReuseJacobian, r));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PcReuseSetUp(PcReuse *r, Mat K, Contact contact, const SolverOptions *opt)
{
  PetscFunctionBeginUser;
  r->K       = K;
  r->contact = contact;
  r->opt     = opt;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Frees the state of the updates (with the problem: the next mesh has its own rows and hierarchy). */
PetscErrorCode PcReuseDestroy(PcReuse *r)
{
  PetscFunctionBeginUser;
  PetscCall(DestroyProducts(r));
  PetscCall(PetscFree2(r->built_vals, r->dvals));
  PetscCall(VecDestroy(&r->pdiag));
  PetscCall(VecDestroy(&r->pcols));
  PetscCall(PetscFree(r->built_active));
  PetscCall(PetscFree(r->carried_active));
  PetscCall(PetscMemzero(r, sizeof(*r)));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Forgets the build, so that the next Newton step builds the preconditioner afresh, and gives up the coarse-level
   updates for the rest of the run (pc_recovery.c): every later preconditioner is a build, with its own smoother
   estimates. What it reads (PcReuseSetUp()), its attachment (PcReuseAttach()), enabled and the three counts stay. */
PetscErrorCode PcReuseReset(PcReuse *r)
{
  const PetscBool            enabled = r->enabled;
  const PetscInt             builds = r->builds, updates = r->updates, finest_updates = r->finest_updates;
  Mat                        K                            = r->K;
  Contact                    contact                      = r->contact;
  const SolverOptions *const opt                          = r->opt;
  const LinearCore           core                         = r->core;
  PetscErrorCode (*jacobian)(SNES, Vec, Mat, Mat, void *) = r->jacobian;
  void *jacobian_ctx                                      = r->jacobian_ctx;

  PetscFunctionBeginUser;
  PetscCall(PcReuseDestroy(r));
  PetscCall(PcReuseSetUp(r, K, contact, opt));
  r->core           = core; /* still attached */
  r->jacobian       = jacobian;
  r->jacobian_ctx   = jacobian_ctx;
  r->enabled        = enabled;
  r->builds         = builds;
  r->updates        = updates;
  r->finest_updates = finest_updates;
  r->no_update      = PETSC_TRUE;
  PetscFunctionReturn(PETSC_SUCCESS);
}
