/* The finest level's Chebyshev smoother while a GAMG hierarchy follows the penalty Jacobian (pc_reuse.c): its interval
   is bounded at each update instead of estimated again.
   With point Jacobi the smoother needs the top of the spectrum of D_J^-1 J, where J = K + P, P the penalty term
   (nonzero in the contact rows and columns only, with a diagonal D_P >= 0) and D_J = D_K + D_P. For every x,
     x^T J x = x^T K x + x^T P x <= lambda_K x^T D_K x + beta x^T D_P x <= max(lambda_K, beta) x^T D_J x,
   lambda_K the top eigenvalue of D_K^-1 K and beta that of D_P^-1/2 P D_P^-1/2, which Gershgorin bounds by the largest
   row sum of |p_ij| / sqrt(p_ii p_jj). So lambda_max(D_J^-1 J) <= max(lambda_K, beta): Chebyshev's estimate of lambda_K,
   made at the build on K, serves every later Newton step while beta stays below it, and beta replaces it when it does
   not. An estimate costs ten products with the finest matrix at each update; the bound, a pass
   over the contact rows. The coarse levels still estimate again: their estimates cost little. */
#include "contact.h"
#include "linear_impl.h"

/* The finest level's smoother if it is Chebyshev with point Jacobi (the case the bound covers), else NULL. */
static PetscErrorCode FinestChebyshevJacobi(PC pc, PetscInt nlevels, KSP *smoother)
{
  KSP          ksp;
  PC           jacobi;
  PetscBool    is_cheb, is_jacobi, use_abs = PETSC_FALSE;
  PCJacobiType type = PC_JACOBI_DIAGONAL;

  PetscFunctionBeginUser;
  *smoother = NULL;
  PetscCall(PCMGGetSmoother(pc, nlevels - 1, &ksp));
  PetscCall(PetscObjectTypeCompare((PetscObject)ksp, KSPCHEBYSHEV, &is_cheb));
  PetscCall(KSPGetPC(ksp, &jacobi));
  PetscCall(PetscObjectTypeCompare((PetscObject)jacobi, PCJACOBI, &is_jacobi));
  if (is_jacobi) {
    PetscCall(PCJacobiGetType(jacobi, &type));
    PetscCall(PCJacobiGetUseAbs(jacobi, &use_abs));
  }
  if (is_cheb && is_jacobi && type == PC_JACOBI_DIAGONAL && !use_abs) *smoother = ksp;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The extreme eigenvalues of the last solve of a Krylov method that computed them, as Chebyshev reads its estimate. */
static PetscErrorCode ExtremeEigenvalues(KSP ksp, PetscReal *emin, PetscReal *emax, PetscBool *found)
{
  PetscInt   max_it, neig;
  PetscReal *re, *im;

  PetscFunctionBeginUser;
  PetscCall(KSPGetTolerances(ksp, NULL, NULL, NULL, &max_it));
  PetscCall(PetscMalloc2(max_it + 1, &re, max_it + 1, &im));
  PetscCall(KSPComputeEigenvalues(ksp, max_it + 1, re, im, &neig));
  *found = (PetscBool)(neig > 0);
  *emin  = PETSC_MAX_REAL;
  *emax  = PETSC_MIN_REAL;
  for (PetscInt k = 0; k < neig; ++k) {
    *emin = PetscMin(*emin, re[k]);
    *emax = PetscMax(*emax, re[k]);
  }
  PetscCall(PetscFree2(re, im));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A fresh estimate of the extreme eigenvalues of D_A^-1 A made as Chebyshev's estimator makes one: CG with point
   Jacobi from a random right-hand side, for the given number of steps. */
static PetscErrorCode FreshEstimate(Mat A, PetscInt steps, PetscReal *emin, PetscReal *emax)
{
  MPI_Comm    comm = PetscObjectComm((PetscObject)A);
  KSP         ksp;
  PC          pc;
  Vec         b, x;
  PetscRandom rand;
  PetscBool   found;

  PetscFunctionBeginUser;
  PetscCall(KSPCreate(comm, &ksp));
  PetscCall(KSPSetType(ksp, KSPCG));
  PetscCall(KSPSetOperators(ksp, A, A));
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(PCSetType(pc, PCJACOBI));
  PetscCall(KSPSetTolerances(ksp, 1e-12, PETSC_DEFAULT, PETSC_DEFAULT, steps));
  PetscCall(KSPSetComputeEigenvalues(ksp, PETSC_TRUE));
  PetscCall(MatCreateVecs(A, &x, &b));
  PetscCall(PetscRandomCreate(comm, &rand));
  PetscCall(VecSetRandom(b, rand));
  PetscCall(KSPSolve(ksp, b, x));
  PetscCall(ExtremeEigenvalues(ksp, emin, emax, &found));
  PetscCheck(found, comm, PETSC_ERR_PLIB, "no eigenvalue estimate of the finest operator");
  PetscCall(PetscRandomDestroy(&rand));
  PetscCall(VecDestroy(&x));
  PetscCall(VecDestroy(&b));
  PetscCall(KSPDestroy(&ksp));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* beta above: Gershgorin's bound of the top eigenvalue of D_P^-1/2 P D_P^-1/2, P = J - K in the contact rows (jvals
   holds J's values there, K's pattern); PETSC_MAX_REAL if P's diagonal cannot bound it (a negative diagonal entry, or
   an entry in a row or column with a zero diagonal). */
static PetscErrorCode PenaltyBound(PcReuse *r, const PetscScalar jvals[], PetscReal *beta)
{
  const ContactBulkRows *br = ContactBulkRowsOf(r->contact);
  PetscInt               rstart;
  PetscScalar           *d;
  const PetscScalar     *dcol;
  PetscReal              local = 0.0;

  PetscFunctionBeginUser;
  if (!r->pdiag) {
    PetscCall(MatCreateVecs(r->K, &r->pdiag, NULL));
    PetscCall(VecDuplicate(br->x, &r->pcols));
  }
  PetscCall(MatGetOwnershipRange(r->K, &rstart, NULL));
  PetscCall(VecSet(r->pdiag, 0.0));
  PetscCall(VecGetArray(r->pdiag, &d));
  for (PetscInt row = 0; row < br->n; ++row) d[br->rows[row] - rstart] = jvals[br->diag[row]] - br->vals[br->diag[row]];
  PetscCall(VecRestoreArray(r->pdiag, &d));
  PetscCall(VecScatterBegin(br->scatter, r->pdiag, r->pcols, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecScatterEnd(br->scatter, r->pdiag, r->pcols, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecGetArrayRead(r->pcols, &dcol));
  for (PetscInt row = 0; row < br->n && local < PETSC_MAX_REAL; ++row) {
    const PetscReal pii = PetscRealPart(jvals[br->diag[row]] - br->vals[br->diag[row]]);
    PetscReal       sum = 0.0;

    for (PetscInt k = br->ptr[row]; k < br->ptr[row + 1]; ++k) {
      const PetscReal pij = PetscAbsScalar(jvals[k] - br->vals[k]), pjj = PetscRealPart(dcol[br->lcols[k]]);

      if (pij == 0.0) continue;
      if (pii <= 0.0 || pjj <= 0.0) {
        sum = PETSC_MAX_REAL;
        break;
      }
      sum += pij / PetscSqrtReal(pii * pjj);
    }
    if (pii < 0.0) sum = PETSC_MAX_REAL;
    local = PetscMax(local, sum);
  }
  PetscCall(VecRestoreArrayRead(r->pcols, &dcol));
  PetscCall(MPIU_Allreduce(&local, beta, 1, MPIU_REAL, MPIU_MAX, PetscObjectComm((PetscObject)r->K)));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The build's estimate (made on K), and Chebyshev's transform of estimates into its interval: a, b, c, d of
   -ksp_chebyshev_esteig on the smoother's prefix, PETSc's default 0, 0.1, 0, 1.1 if unset. */
static PetscErrorCode ReadBuildEstimate(KSP smoother, const SolverGiven *given, PcReuse *r)
{
  KSP         est;
  const char *prefix;
  PetscReal   t[4];
  PetscInt    nt = 4;
  PetscBool   found;

  PetscFunctionBeginUser;
  r->bound_read = PETSC_TRUE;
  PetscCall(KSPChebyshevEstEigGetKSP(smoother, &est));
  if (!est || !r->built_on_K) PetscFunctionReturn(PETSC_SUCCESS); /* given eigenvalues, or a build on K + P: no bound */
  PetscCall(ExtremeEigenvalues(est, &r->est_min, &r->est_max, &found));
  PetscCall(KSPGetTolerances(est, NULL, NULL, NULL, &r->est_steps));
  if (!found || r->est_max <= 0.0) PetscFunctionReturn(PETSC_SUCCESS);
  r->tform[0] = 0.0;
  r->tform[1] = 0.1;
  r->tform[2] = 0.0;
  r->tform[3] = 1.1;
  PetscCall(KSPGetOptionsPrefix(smoother, &prefix));
  PetscCall(SolverGivenEsteig(given, prefix, &nt, t)); /* -ksp_chebyshev_esteig under the smoother's prefix */
  if (nt == 2) {                                       /* PETSc's short form: b and d */
    r->tform[1] = t[0];
    r->tform[3] = t[1];
  } else if (nt == 4)
    PetscCall(PetscArraycpy(r->tform, t, 4));
  r->bound_set = PETSC_TRUE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode SmootherBoundFinest(PcReuse *r, PC pc, PetscInt nlevels, const PetscScalar jvals[], PetscBool check)
{
  KSP       smoother;
  PetscReal beta, top, emin, emax;

  PetscFunctionBeginUser;
  PetscCall(FinestChebyshevJacobi(pc, nlevels, &smoother));
  if (!smoother) PetscFunctionReturn(PETSC_SUCCESS);
  if (!r->bound_read) PetscCall(ReadBuildEstimate(smoother, &r->opt->given, r));
  if (!r->bound_set) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PenaltyBound(r, jvals, &beta));
  if (beta < PETSC_MAX_REAL)
    top = PetscMax(r->est_max, beta);
  else { /* no bound: estimate, as Chebyshev would */
    Mat A;

    PetscCall(KSPGetOperators(smoother, &A, NULL));
    PetscCall(FreshEstimate(A, r->est_steps, &emin, &top));
  }
  emin = r->tform[0] * r->est_min + r->tform[1] * top;
  emax = r->tform[2] * r->est_min + r->tform[3] * top;
  PetscCall(KSPChebyshevSetEigenvalues(smoother, emax, emin));
  if (check) {
    Mat       A;
    PetscReal fresh_min, fresh_max;

    PetscCall(KSPGetOperators(smoother, &A, NULL));
    PetscCall(FreshEstimate(A, r->est_steps, &fresh_min, &fresh_max));
    PetscCall(PetscPrintf(PetscObjectComm((PetscObject)pc),
                          "pc update check: finest level: Chebyshev interval [%.6e, %.6e] from the build's estimate %.6e and the penalty bound %.6e; "
                          "a fresh estimate gives %.6e, interval top / fresh estimate = %.4f\n",
                          (double)emin, (double)emax, (double)r->est_max, (double)beta, (double)fresh_max, (double)(emax / fresh_max)));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}
