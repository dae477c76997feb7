/* Error norms of the verification (verification.md section 1), integrated with the accurate rule of src/discretization/cell_quadrature.c:
   ||u - u_h|| in L2, H1 (semi and full) and energy; on Gamma_C the contact-pressure residual R = sigma_n(u) + p_h in L2,
   weighted by eps^1/2, and in the H^-1/2 dual norm; and the penetration [u_h,n - g]_+ in L2 and max.
   p_h is the penalty law (1/eps)[u_h,n - g]_+ for the penalty method and the nodal multiplier, interpolated, otherwise. */
#include "mesh.h"
#include "obstacle.h"
#include "discretization.h"
#include "physics.h"
#include "verify.h"
#include "app.h"

PetscErrorCode ErrorNormsReset(ErrorNorms *e)
{
  PetscFunctionBeginUser;
  e->l2 = e->h1_semi = e->h1 = e->energy = PETSC_NAN;
  e->pressure_l2 = e->pressure_weighted = e->pressure_dual = PETSC_NAN;
  e->penetration_l2 = e->penetration_max = PETSC_NAN;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* loc_p = p n at the nodes of Gamma_C, from the nodal pressures of the contact set (zero elsewhere). */
PetscErrorCode ErrorNormsPressureVector(DM dm, Contact contact, Vec loc_p)
{
  Vec               P;
  PetscScalar      *p;
  PetscInt          dim;
  const ContactSet *cs;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMGetGlobalVector(dm, &P));
  PetscCall(VecZeroEntries(P));
  PetscCall(VecGetArray(P, &p));
  PetscCall(ContactGetSet(contact, &cs));
  for (PetscInt i = 0; i < cs->n; ++i) /* fixed components stay 0 */
    for (PetscInt c = 0; c < dim; ++c)
      if (cs->dof[i * dim + c] >= 0) p[cs->dof[i * dim + c]] = cs->pressure[i] * cs->normal[i * dim + c];
  PetscCall(VecRestoreArray(P, &p));
  PetscCall(VecZeroEntries(loc_p));
  PetscCall(DMGlobalToLocal(dm, P, INSERT_VALUES, loc_p));
  PetscCall(DMRestoreGlobalVector(dm, &P));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Integrals over Omega: |e|^2, |grad e|^2 and sigma(e) : grad e with e = u_target - u_h. */
static PetscErrorCode IntegrateBulk(DM dm, const Material *mat, CellQuadrature *cq, Vec loc_uh, const ErrorTarget *t, PetscReal sums[3])
{
  const PetscInt dim = cq->dim;
  PetscInt       cStart, cEnd;

  PetscFunctionBeginUser;
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  for (PetscInt c = cStart; c < cEnd; ++c) {
    PetscScalar *uh = NULL, *ur = NULL;
    PetscReal    g0[9]; /* u_h's gradient at the first point: at every point where D is the same there (P1, affine cell) */

    PetscCall(CellQuadratureSetCell(cq, c));
    PetscCall(DMPlexVecGetClosure(dm, NULL, loc_uh, c, NULL, &uh));
    if (!t->scene) PetscCall(DMPlexVecGetClosure(dm, NULL, t->loc_u, c, NULL, &ur));
    for (PetscInt q = 0; q < cq->Nq; ++q) {
      PetscReal u[3], g[9], ut[3], gt[9], sigma[9], s0 = 0.0, s1 = 0.0, s2 = 0.0;

      if (q == 0 || !cq->D_uniform) {
        PetscCall(CellQuadratureInterpolate(cq, uh, q, u, g));
        if (q == 0) PetscCall(PetscArraycpy(g0, g, dim * dim));
      } else {
        PetscCall(CellQuadratureInterpolate(cq, uh, q, u, NULL));
        PetscCall(PetscArraycpy(g, g0, dim * dim));
      }
      if (t->scene) {
        PetscScalar us[3], gs[9];

        PetscCall((*t->scene->exact)(dim, 0.0, &cq->x[q * dim], dim, us, (void *)t->scene->constants));
        PetscCall((*t->scene->exact_gradient)(dim, 0.0, &cq->x[q * dim], dim * dim, gs, (void *)t->scene->constants));
        for (PetscInt k = 0; k < dim; ++k) ut[k] = PetscRealPart(us[k]);
        for (PetscInt k = 0; k < dim * dim; ++k) gt[k] = PetscRealPart(gs[k]);
      } else
        PetscCall(CellQuadratureInterpolate(cq, ur, q, ut, gt));
      for (PetscInt k = 0; k < dim; ++k) s0 += PetscSqr(ut[k] - u[k]);
      for (PetscInt k = 0; k < dim * dim; ++k) {
        g[k] = gt[k] - g[k];
        s1 += PetscSqr(g[k]);
      }
      ElasticStress(dim, mat, g, sigma);
      for (PetscInt k = 0; k < dim * dim; ++k) s2 += sigma[k] * g[k];
      sums[0] += cq->w[q] * s0;
      sums[1] += cq->w[q] * s1;
      sums[2] += cq->w[q] * s2;
    }
    PetscCall(DMPlexVecRestoreClosure(dm, NULL, loc_uh, c, NULL, &uh));
    if (!t->scene) PetscCall(DMPlexVecRestoreClosure(dm, NULL, t->loc_u, c, NULL, &ur));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Integrals over Gamma_C: R^2 and [d]_+^2, the max of [d]_+, and the load b_i = int R phi_i . n of the dual problem.
   Without a target (t == NULL) only the penetration is integrated. */
static PetscErrorCode IntegrateContact(DM dm, const PetscReal run_cell_h[], const VerifyRun *run, CellQuadrature *cq, Vec loc_uh, Vec loc_ph,
                                       const ErrorTarget *t, Vec loc_b, PetscReal sums[2], PetscReal *dmax)
{
  const PetscInt dim = cq->dim;
  PetscInt      *faces, nf;
  PetscScalar   *elem;
  PetscReal      eps = 0.0; /* of the face, for the penalty law p = [u_n - g]_+ / eps */
  PetscInt       cStart;

  PetscFunctionBeginUser;
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, NULL));
  PetscCall(PetscMalloc1(PetscMax(cq->Nb, 1), &elem));
  for (PetscInt s = 0; s < run->scene->bcs.ncontact; ++s) {
    PetscCall(MeshGetBoundaryFaces(dm, run->scene->bcs.contact_ids[s], &nf, &faces)); /* of this mesh, maybe a refinement of the run's */
    for (PetscInt i = 0; i < nf; ++i) {
      PetscScalar *uh = NULL, *ph = NULL, *pr = NULL;

      PetscCall(CellQuadratureSetFace(cq, faces[i]));
      if (!loc_ph && t) { /* the penalty's eps at this face: that of the run's cell holding it (local eps on a graded mesh) */
        PetscReal diam;

        if (run_cell_h)
          diam = run_cell_h[cq->cell - cStart];
        else
          PetscCall(MeshCellDiameter(dm, cq->cell, &diam));
        PetscCall(ContactFaceEps(run->contact, diam, &eps));
      }
      PetscCall(DMPlexVecGetClosure(dm, NULL, loc_uh, cq->cell, NULL, &uh));
      if (loc_ph) PetscCall(DMPlexVecGetClosure(dm, NULL, loc_ph, cq->cell, NULL, &ph));
      if (t && !t->scene) PetscCall(DMPlexVecGetClosure(dm, NULL, t->loc_pressure, cq->cell, NULL, &pr));
      for (PetscInt b = 0; b < cq->Nb; ++b) elem[b] = 0.0;
      for (PetscInt q = 0; q < cq->Nq; ++q) {
        const PetscReal *x = &cq->x[q * dim];
        PetscReal        u[3], v[3], n[3], d, p_h = 0.0, p_target = 0.0, R;

        PetscCall(CellQuadratureInterpolate(cq, uh, q, u, NULL));
        ObstacleGapNormalAt(&run->scene->obstacle, dim, x, n, &d);
        d = -d;
        for (PetscInt k = 0; k < dim; ++k) d += u[k] * n[k];
        sums[1] += cq->w[q] * PetscSqr(PetscMax(d, 0.0));
        *dmax = PetscMax(*dmax, d);
        if (!t) continue;
        if (ph) { /* the interpolated nodal pressure, stored as p n */
          PetscCall(CellQuadratureInterpolate(cq, ph, q, v, NULL));
          for (PetscInt k = 0; k < dim; ++k) p_h += v[k] * n[k];
        } else
          p_h = d > 0.0 ? d / eps : 0.0;
        if (t->scene) {
          PetscReal sn;

          PetscCall(WeakDataExactNormalStress(run->scene, run->mat, dim, x, &sn));
          p_target = -sn;
        } else {
          PetscCall(CellQuadratureInterpolate(cq, pr, q, v, NULL));
          for (PetscInt k = 0; k < dim; ++k) p_target += v[k] * n[k];
        }
        R = p_h - p_target; /* sigma_n(u) + p_h */
        sums[0] += cq->w[q] * R * R;
        for (PetscInt b = 0; b < cq->Nb; ++b) {
          PetscReal vn = 0.0;

          for (PetscInt k = 0; k < cq->Nc; ++k) vn += cq->B[(q * cq->Nb + b) * cq->Nc + k] * n[k];
          elem[b] += cq->w[q] * R * vn;
        }
      }
      if (t) PetscCall(DMPlexVecSetClosure(dm, NULL, loc_b, cq->cell, elem, ADD_VALUES));
      PetscCall(DMPlexVecRestoreClosure(dm, NULL, loc_uh, cq->cell, NULL, &uh));
      if (ph) PetscCall(DMPlexVecRestoreClosure(dm, NULL, loc_ph, cq->cell, NULL, &ph));
      if (pr) PetscCall(DMPlexVecRestoreClosure(dm, NULL, t->loc_pressure, cq->cell, NULL, &pr));
    }
    PetscCall(PetscFree(faces));
  }
  PetscCall(PetscFree(elem));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* ||R||_{-1/2,Gamma_C} as the energy norm of w with a(w, v) = <R, v_n> for all v (Remark 3.10): sqrt(b . K^-1 b).
   The solve uses the options prefix dual_ (default: a direct MUMPS solve, like the main solve). */
static PetscErrorCode DualNorm(DM dm, Mat K, Vec loc_b, PetscReal *norm)
{
  KSP         ksp;
  PC          pc;
  Vec         b, w;
  PetscScalar bw;

  PetscFunctionBeginUser;
  PetscCall(DMGetGlobalVector(dm, &b));
  PetscCall(DMGetGlobalVector(dm, &w));
  PetscCall(VecZeroEntries(b));
  PetscCall(DMLocalToGlobal(dm, loc_b, ADD_VALUES, b));
  PetscCall(KSPCreate(PetscObjectComm((PetscObject)dm), &ksp));
  PetscCall(KSPSetOptionsPrefix(ksp, "dual_"));
  PetscCall(KSPSetOperators(ksp, K, K));
  PetscCall(KSPSetType(ksp, KSPPREONLY));
  PetscCall(KSPGetPC(ksp, &pc));
  {
    PetscBool sbaij; /* K's upper triangle only: MUMPS factors it by Cholesky */

    PetscCall(PetscObjectTypeCompareAny((PetscObject)K, &sbaij, MATSEQSBAIJ, MATMPISBAIJ, ""));
    PetscCall(PCSetType(pc, sbaij ? PCCHOLESKY : PCLU));
  }
  PetscCall(PCFactorSetMatSolverType(pc, MATSOLVERMUMPS));
  PetscCall(KSPSetFromOptions(ksp));
  PetscCall(KSPSolve(ksp, b, w));
  {
    KSPConvergedReason reason;

    PetscCall(KSPGetConvergedReason(ksp, &reason));
    PetscCheck(reason > 0, PetscObjectComm((PetscObject)dm), PETSC_ERR_NOT_CONVERGED, "The dual-norm solve (prefix dual_) failed: %s",
               KSPConvergedReasons[reason]);
  }
  PetscCall(VecDot(b, w, &bw));
  *norm = PetscSqrtReal(PetscMax(PetscRealPart(bw), 0.0));
  PetscCall(KSPDestroy(&ksp));
  PetscCall(DMRestoreGlobalVector(dm, &b));
  PetscCall(DMRestoreGlobalVector(dm, &w));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* All norms of u_h (loc_uh, with its pressure loc_ph or the penalty law if NULL) against the target, on the mesh of dm;
   K is the elastic operator of dm for the dual norm. Without a target (NULL) only the penetration norms. run_cell_h:
   for each cell of dm, the diameter of the run's cell that holds it, whose local eps the penalty law takes (NULL: dm
   is the run's mesh). */
PetscErrorCode ErrorNormsEvaluate(DM dm, const PetscReal run_cell_h[], const VerifyRun *run, Mat K, Vec loc_uh, Vec loc_ph, const ErrorTarget *target,
                                  ErrorNorms *e)
{
  MPI_Comm       comm = PetscObjectComm((PetscObject)dm);
  CellQuadrature cq;
  PetscReal      bulk[3] = {0.0, 0.0, 0.0}, contact[2] = {0.0, 0.0}, dmax = PETSC_MIN_REAL, gbulk[3], gcontact[2], gmax;
  Vec            loc_b = NULL;

  PetscFunctionBeginUser;
  PetscCall(ErrorNormsReset(e));
  PetscCall(CellQuadratureCreate(dm, run->scene, run->opt, &cq));
  if (target) {
    PetscCall(DMGetLocalVector(dm, &loc_b));
    PetscCall(VecZeroEntries(loc_b));
    PetscCall(IntegrateBulk(dm, run->mat, &cq, loc_uh, target, bulk));
  }
  PetscCall(IntegrateContact(dm, run_cell_h, run, &cq, loc_uh, loc_ph, target, loc_b, contact, &dmax));
  PetscCall(CellQuadratureDestroy(&cq));
  PetscCall(MPIU_Allreduce(bulk, gbulk, 3, MPIU_REAL, MPIU_SUM, comm));
  PetscCall(MPIU_Allreduce(contact, gcontact, 2, MPIU_REAL, MPIU_SUM, comm));
  PetscCall(MPIU_Allreduce(&dmax, &gmax, 1, MPIU_REAL, MPIU_MAX, comm));
  e->penetration_l2  = PetscSqrtReal(gcontact[1]);
  e->penetration_max = PetscMax(gmax, 0.0);
  if (target) {
    PetscReal           weight = run->h;
    ContactPressureForm form;

    PetscCall(ContactGetPressureForm(run->contact, &form));
    if (form.law) PetscCall(ContactGetEps(run->contact, &weight)); /* eps^1/2 ||R|| for the penalty, h^1/2 ||R|| otherwise */

    e->l2                = PetscSqrtReal(gbulk[0]);
    e->h1_semi           = PetscSqrtReal(gbulk[1]);
    e->h1                = PetscSqrtReal(gbulk[0] + gbulk[1]);
    e->energy            = PetscSqrtReal(gbulk[2]);
    e->pressure_l2       = PetscSqrtReal(gcontact[0]);
    e->pressure_weighted = PetscSqrtReal(weight) * e->pressure_l2;
    PetscCall(DualNorm(dm, K, loc_b, &e->pressure_dual));
    PetscCall(DMRestoreLocalVector(dm, &loc_b));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The norms of the run into *e: penetration always, the errors when the scene has an exact solution. */
PetscErrorCode ErrorNormsCompute(DM dm, const VerifyRun *run, Vec u, ErrorNorms *e)
{
  Vec                 loc_uh, loc_ph = NULL;
  ErrorTarget         exact = {run->scene, NULL, NULL};
  ContactPressureForm form;

  PetscFunctionBeginUser;
  PetscCall(MeshIndexCellTypes(dm)); /* the closures below look each point's cell type up: sorted, not hashed */
  PetscCall(ErrorNormsReset(e));
  PetscCall(DMGetLocalVector(dm, &loc_uh));
  PetscCall(VecCopy(run->loc_bc, loc_uh)); /* the Dirichlet values, inserted once by ProblemSetUp() */
  PetscCall(DMGlobalToLocal(dm, u, INSERT_VALUES, loc_uh));
  PetscCall(ContactGetPressureForm(run->contact, &form));
  if (!form.law) { /* the nodal pressure, where no law gives it at every point */
    PetscCall(DMGetLocalVector(dm, &loc_ph));
    PetscCall(ErrorNormsPressureVector(dm, run->contact, loc_ph));
  }
  if (run->scene->exact && run->scene->exact_gradient) {
    Mat K;

    PetscCall(ContactBulkOperator(run->contact, run->K, &K)); /* K, or a copy without the penalty Jacobian: K is read only */
    PetscCall(ErrorNormsEvaluate(dm, NULL, run, K, loc_uh, loc_ph, &exact, e));
    PetscCall(MatDestroy(&K));
  } else
    PetscCall(ErrorNormsEvaluate(dm, NULL, run, NULL, loc_uh, loc_ph, NULL, e));
  if (loc_ph) PetscCall(DMRestoreLocalVector(dm, &loc_ph));
  PetscCall(DMRestoreLocalVector(dm, &loc_uh));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* prefix_l2, prefix_h1, ... for the norms that were computed (NaN: not computed, not written). */
static PetscErrorCode ErrorNormsWrite(const char prefix[], const ErrorNorms *e, PetscViewer v)
{
  const char *names[]  = {"l2", "h1_semi", "h1", "energy", "pressure_l2", "pressure_weighted", "pressure_dual"};
  PetscReal   values[] = {e->l2, e->h1_semi, e->h1, e->energy, e->pressure_l2, e->pressure_weighted, e->pressure_dual};

  PetscFunctionBeginUser;
  for (size_t i = 0; i < sizeof(values) / sizeof(values[0]); ++i)
    if (!PetscIsNanReal(values[i])) PetscCall(RunAttrReal(v, values[i], "%s_%s", prefix, names[i]));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The summary's lines of the error norms, against the exact solution and against the -reference, where they exist. */
PetscErrorCode VerifyView(MPI_Comm comm, const ErrorNorms *errors, const ErrorNorms *ref_errors)
{
  PetscFunctionBeginUser;
  if (!PetscIsNanReal(errors->h1))
    PetscCall(PetscPrintf(comm, "  error against the exact solution: H1 %.4e, L2 %.4e, pressure L2 %.4e, pressure H^-1/2 %.4e\n", (double)errors->h1,
                          (double)errors->l2, (double)errors->pressure_l2, (double)errors->pressure_dual));
  if (!PetscIsNanReal(ref_errors->h1))
    PetscCall(PetscPrintf(comm, "  error against the reference: H1 %.4e, L2 %.4e, pressure L2 %.4e, pressure H^-1/2 %.4e\n", (double)ref_errors->h1,
                          (double)ref_errors->l2, (double)ref_errors->pressure_l2, (double)ref_errors->pressure_dual));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The verification's part of /run: the penetration's norms, the errors against the scene's exact solution (error_*)
   and against -reference (reference_error_*, with the reference's file), and the finer quadrature they took. */
PetscErrorCode VerifyWrite(const VerifyOptions *opt, const ErrorNorms *errors, const ErrorNorms *ref_errors, PetscViewer v)
{
  PetscFunctionBeginUser;
  PetscCall(RunAttrReal(v, errors->penetration_l2, "penetration_l2"));
  PetscCall(RunAttrReal(v, errors->penetration_max, "penetration_max"));
  PetscCall(ErrorNormsWrite("error", errors, v));
  PetscCall(ErrorNormsWrite("reference_error", ref_errors, v));
  if (opt->reference[0]) PetscCall(RunAttrString(v, opt->reference, "reference"));
  PetscCall(RunAttrInt(v, opt->quad_points, "verify_quadrature_points"));
  PetscCall(RunAttrInt(v, opt->quad_refine, "verify_quadrature_refine"));
  PetscFunctionReturn(PETSC_SUCCESS);
}
