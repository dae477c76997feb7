/* Accurate quadrature for the verification: the basis functions of the displacement FE and the physical points and
   weights of a Gauss rule, cell by cell (values and gradients) or on a boundary face (values, from its support cell).
   The cells and faces cut by a scene's kink get a composite rule: the same rule on every subcell of the reference
   cell refined -verify_quadrature_refine times, so the non-smooth exact solution does not spoil the integrals. */
#include "mesh.h"
#include "discretization.h"

/* Whether two arrays of reals differ in any bit-for-bit comparison of their values. */
static PetscBool RealsDiffer(const PetscReal a[], const PetscReal b[], PetscInt n)
{
  for (PetscInt i = 0; i < n; ++i)
    if (a[i] != b[i]) return PETSC_TRUE;
  return PETSC_FALSE;
}

/* Gauss rule with npoints per direction (Stroud conical on simplices), repeated on the subcells of the reference cell refined `refine` times. */
static PetscErrorCode RuleCreate(DMPolytopeType ct, PetscInt npoints, PetscInt refine, PetscQuadrature *q)
{
  const PetscInt   dim     = DMPolytopeTypeGetDim(ct);
  const PetscBool  simplex = (PetscBool)(DMPolytopeTypeGetNumVertices(ct) == dim + 1);
  PetscQuadrature  base;
  DM               rdm;
  PetscInt         Nq, cStart, cEnd, n = 0;
  const PetscReal *bp, *bw;
  PetscReal       *pts, *wts, *v, *J, *invJ, *detJ;

  PetscFunctionBeginUser;
  if (simplex)
    PetscCall(PetscDTStroudConicalQuadrature(dim, 1, npoints, -1.0, 1.0, &base));
  else
    PetscCall(PetscDTGaussTensorQuadrature(dim, 1, npoints, -1.0, 1.0, &base));
  if (refine == 0) {
    *q = base;
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  PetscCall(DMPlexCreateReferenceCell(PETSC_COMM_SELF, ct, &rdm));
  for (PetscInt r = 0; r < refine; ++r) {
    DM fine;

    PetscCall(DMRefine(rdm, PETSC_COMM_SELF, &fine));
    PetscCall(DMDestroy(&rdm));
    rdm = fine;
  }
  PetscCall(DMPlexGetHeightStratum(rdm, 0, &cStart, &cEnd));
  PetscCall(PetscQuadratureGetData(base, NULL, NULL, &Nq, &bp, &bw));
  PetscCall(PetscMalloc1((cEnd - cStart) * Nq * dim, &pts)); /* owned by the quadrature from PetscQuadratureSetData() on */
  PetscCall(PetscMalloc1((cEnd - cStart) * Nq, &wts));
  PetscCall(PetscMalloc4(Nq * dim, &v, Nq * dim * dim, &J, Nq * dim * dim, &invJ, Nq, &detJ));
  for (PetscInt c = cStart; c < cEnd; ++c) {
    PetscCall(DMPlexComputeCellGeometryFEM(rdm, c, base, v, J, invJ, detJ));
    for (PetscInt k = 0; k < Nq; ++k, ++n) {
      for (PetscInt d = 0; d < dim; ++d) pts[n * dim + d] = v[k * dim + d];
      wts[n] = bw[k] * detJ[k];
    }
  }
  PetscCall(PetscFree4(v, J, invJ, detJ));
  PetscCall(PetscQuadratureCreate(PETSC_COMM_SELF, q));
  PetscCall(PetscQuadratureSetData(*q, dim, 1, n, pts, wts));
  PetscCall(PetscQuadratureDestroy(&base));
  PetscCall(DMDestroy(&rdm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Is point p (cell or face) cut by the scene's kink plane? */
static PetscErrorCode IsCutByKink(const CellQuadrature *cq, PetscInt p, PetscBool *cut)
{
  DM           cdm;
  PetscSection cs;
  Vec          coords;
  PetscScalar *x = NULL;
  PetscInt     n;
  PetscReal    lo = PETSC_MAX_REAL, hi = PETSC_MIN_REAL;

  PetscFunctionBeginUser;
  *cut = PETSC_FALSE;
  if (!cq->scene->has_kink) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(DMGetCoordinateDM(cq->dm, &cdm));
  PetscCall(DMGetLocalSection(cdm, &cs));
  PetscCall(DMGetCoordinatesLocal(cq->dm, &coords));
  PetscCall(DMPlexVecGetClosure(cdm, cs, coords, p, &n, &x));
  for (PetscInt i = 0; i < n / cq->dim; ++i) {
    PetscReal s = -cq->scene->kink_offset;

    for (PetscInt d = 0; d < cq->dim; ++d) s += PetscRealPart(x[i * cq->dim + d]) * cq->scene->kink_normal[d];
    lo = PetscMin(lo, s);
    hi = PetscMax(hi, s);
  }
  PetscCall(DMPlexVecRestoreClosure(cdm, cs, coords, p, &n, &x));
  *cut = (PetscBool)(lo < 0.0 && hi > 0.0);
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode CellQuadratureCreate(DM dm, const Scene *scene, const VerifyOptions *opts, CellQuadrature *cq)
{
  DMPolytopeType ct = DM_POLYTOPE_UNKNOWN, fct = DM_POLYTOPE_UNKNOWN;
  PetscInt       cStart, cEnd, fStart, fEnd, maxq = 0;

  PetscFunctionBeginUser;
  PetscCall(PetscMemzero(cq, sizeof(*cq)));
  cq->dm    = dm;
  cq->scene = scene;
  PetscCall(DMGetDimension(dm, &cq->dim));
  PetscCall(DMGetField(dm, 0, NULL, (PetscObject *)&cq->fe));
  PetscCall(PetscFEGetDimension(cq->fe, &cq->Nb));
  PetscCall(PetscFEGetNumComponents(cq->fe, &cq->Nc));
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  PetscCall(DMPlexGetHeightStratum(dm, 1, &fStart, &fEnd));
  if (cEnd > cStart) PetscCall(DMPlexGetCellType(dm, cStart, &ct));
  if (fEnd > fStart) PetscCall(DMPlexGetCellType(dm, fStart, &fct));
  if (ct == DM_POLYTOPE_UNKNOWN) PetscFunctionReturn(PETSC_SUCCESS); /* no cells on this rank */
  for (PetscInt r = 0; r < 2; ++r) {
    PetscInt Nq;

    PetscCall(RuleCreate(ct, opts->quad_points, r ? opts->quad_refine : 0, &cq->cell_rule[r]));
    PetscCall(RuleCreate(fct, opts->quad_points, r ? opts->quad_refine : 0, &cq->face_rule[r]));
    PetscCall(PetscQuadratureGetData(cq->cell_rule[r], NULL, NULL, &Nq, NULL, NULL));
    maxq = PetscMax(maxq, Nq);
    {
      const PetscReal *pts;

      PetscCall(PetscQuadratureGetData(cq->cell_rule[r], NULL, NULL, NULL, &pts, NULL));
      PetscCall(PetscFECreateTabulation(cq->fe, 1, Nq, pts, 1, &cq->cell_tab[r]));
    }
    {
      const PetscInt   n  = cq->Nb * cq->Nc * cq->dim;
      const PetscReal *T1 = cq->cell_tab[r]->T[1];

      cq->grad_const[r] = PETSC_TRUE;
      for (PetscInt q = 1; q < Nq && cq->grad_const[r]; ++q) cq->grad_const[r] = (PetscBool)!RealsDiffer(&T1[q * n], T1, n);
    }
    PetscCall(PetscQuadratureGetData(cq->face_rule[r], NULL, NULL, &Nq, NULL, NULL));
    maxq = PetscMax(maxq, Nq);
  }
  PetscCall(PetscMalloc3(maxq * cq->dim, &cq->xbuf, maxq, &cq->wbuf, maxq * cq->Nb * cq->Nc * cq->dim, &cq->dbuf));
  PetscCall(PetscMalloc4(maxq * cq->dim * cq->dim, &cq->J, maxq * cq->dim * cq->dim, &cq->invJ, maxq, &cq->detJ, maxq * cq->dim, &cq->refbuf));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode CellQuadratureDestroy(CellQuadrature *cq)
{
  PetscFunctionBeginUser;
  for (PetscInt r = 0; r < 2; ++r) {
    PetscCall(PetscQuadratureDestroy(&cq->cell_rule[r]));
    PetscCall(PetscQuadratureDestroy(&cq->face_rule[r]));
    PetscCall(PetscTabulationDestroy(&cq->cell_tab[r]));
  }
  PetscCall(PetscTabulationDestroy(&cq->face_tab));
  PetscCall(PetscFree3(cq->xbuf, cq->wbuf, cq->dbuf));
  PetscCall(PetscFree4(cq->J, cq->invJ, cq->detJ, cq->refbuf));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Points, weights, basis values and physical gradients on cell c. */
PetscErrorCode CellQuadratureSetCell(CellQuadrature *cq, PetscInt c)
{
  const PetscInt   dim = cq->dim, Nb = cq->Nb, Nc = cq->Nc;
  PetscBool        cut;
  const PetscReal *qw, *T1;
  PetscInt         r;

  PetscFunctionBeginUser;
  PetscCall(IsCutByKink(cq, c, &cut));
  r = cut ? 1 : 0;
  PetscCall(PetscQuadratureGetData(cq->cell_rule[r], NULL, NULL, &cq->Nq, NULL, &qw));
  PetscCall(DMPlexComputeCellGeometryFEM(cq->dm, c, cq->cell_rule[r], cq->xbuf, cq->J, cq->invJ, cq->detJ));
  T1 = cq->cell_tab[r]->T[1];
  /* P1 on an affine cell: the same reference gradients and the same inverse Jacobian at every point, so the physical
     gradients are those of the first point (D_uniform: D holds that point's alone, and D's users read it for all) */
  cq->D_uniform = cq->grad_const[r];
  for (PetscInt q = 1; q < cq->Nq && cq->D_uniform; ++q) cq->D_uniform = (PetscBool)!RealsDiffer(&cq->invJ[q * dim * dim], cq->invJ, dim * dim);
  for (PetscInt q = 0; q < cq->Nq; ++q) {
    const PetscReal *invJ = &cq->invJ[q * dim * dim];

    PetscCheck(cq->detJ[q] > 0.0, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG, "Cell %" PetscInt_FMT " is inverted or degenerate (det J = %g)", c,
               (double)cq->detJ[q]);
    cq->wbuf[q] = qw[q] * cq->detJ[q];
    if (q > 0 && cq->D_uniform) continue;
    for (PetscInt b = 0; b < Nb; ++b)
      for (PetscInt k = 0; k < Nc; ++k) {
        const PetscReal *ref  = &T1[((q * Nb + b) * Nc + k) * dim];
        PetscReal       *phys = &cq->dbuf[((q * Nb + b) * Nc + k) * dim];

        PetscBool zero = PETSC_TRUE; /* a vector basis function has one non-zero component */

        for (PetscInt d = 0; d < dim; ++d) zero = (PetscBool)(zero && ref[d] == 0.0);
        for (PetscInt e = 0; e < dim; ++e) {
          phys[e] = 0.0;
          if (!zero)
            for (PetscInt d = 0; d < dim; ++d) phys[e] += ref[d] * invJ[d * dim + e];
        }
      }
  }
  cq->x    = cq->xbuf;
  cq->w    = cq->wbuf;
  cq->B    = cq->cell_tab[r]->T[0];
  cq->D    = cq->dbuf;
  cq->cell = c;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Physical points x[Nq][dim] and surface Jacobians detJ[Nq] of face f at the reference points of a rule: the affine map of
   its vertices (segment, triangle) or the bilinear one (quadrilateral, vertices in closure order). */
static PetscErrorCode FaceGeometry(const CellQuadrature *cq, PetscInt f, PetscInt Nq, const PetscReal ref[], PetscReal x[], PetscReal detJ[])
{
  const PetscInt dim = cq->dim;
  DM             cdm;
  PetscSection   cs;
  Vec            coords;
  PetscScalar   *v = NULL;
  PetscInt       n, nv;

  PetscFunctionBeginUser;
  PetscCall(DMGetCoordinateDM(cq->dm, &cdm));
  PetscCall(DMGetLocalSection(cdm, &cs));
  PetscCall(DMGetCoordinatesLocal(cq->dm, &coords));
  PetscCall(DMPlexVecGetClosure(cdm, cs, coords, f, &n, &v));
  nv = n / dim;
  PetscCheck(nv == dim || (dim == 3 && nv == 4), PETSC_COMM_SELF, PETSC_ERR_SUP, "Face %" PetscInt_FMT " with %" PetscInt_FMT " vertices", f, nv);
  for (PetscInt q = 0; q < Nq; ++q) {
    const PetscReal *xi = &ref[q * (dim - 1)];
    PetscReal        N[4], dN[2][4], t[2][3] = {{0, 0, 0}, {0, 0, 0}};

    if (nv == 2) { /* segment */
      N[0] = 0.5 * (1 - xi[0]), N[1] = 0.5 * (1 + xi[0]);
      dN[0][0] = -0.5, dN[0][1] = 0.5;
    } else if (nv == 3) { /* triangle, reference (-1,-1), (1,-1), (-1,1) */
      N[0] = -0.5 * (xi[0] + xi[1]), N[1] = 0.5 * (1 + xi[0]), N[2] = 0.5 * (1 + xi[1]);
      dN[0][0] = -0.5, dN[0][1] = 0.5, dN[0][2] = 0.0;
      dN[1][0] = -0.5, dN[1][1] = 0.0, dN[1][2] = 0.5;
    } else { /* quadrilateral, corners (-1,-1), (1,-1), (1,1), (-1,1) */
      const PetscReal s[4] = {-1, 1, 1, -1}, r[4] = {-1, -1, 1, 1};

      for (PetscInt i = 0; i < 4; ++i) {
        N[i]     = 0.25 * (1 + s[i] * xi[0]) * (1 + r[i] * xi[1]);
        dN[0][i] = 0.25 * s[i] * (1 + r[i] * xi[1]);
        dN[1][i] = 0.25 * r[i] * (1 + s[i] * xi[0]);
      }
    }
    for (PetscInt d = 0; d < dim; ++d) {
      x[q * dim + d] = 0.0;
      for (PetscInt i = 0; i < nv; ++i) {
        x[q * dim + d] += N[i] * PetscRealPart(v[i * dim + d]);
        for (PetscInt k = 0; k < dim - 1; ++k) t[k][d] += dN[k][i] * PetscRealPart(v[i * dim + d]);
      }
    }
    if (dim == 2)
      detJ[q] = PetscSqrtReal(t[0][0] * t[0][0] + t[0][1] * t[0][1]);
    else
      detJ[q] = PetscSqrtReal(PetscSqr(t[0][1] * t[1][2] - t[0][2] * t[1][1]) + PetscSqr(t[0][2] * t[1][0] - t[0][0] * t[1][2]) +
                              PetscSqr(t[0][0] * t[1][1] - t[0][1] * t[1][0]));
  }
  PetscCall(DMPlexVecRestoreClosure(cdm, cs, coords, f, &n, &v));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Points and weights on face f, with the basis values of its (first) support cell there. */
PetscErrorCode CellQuadratureSetFace(CellQuadrature *cq, PetscInt f)
{
  const PetscInt  *support;
  const PetscReal *qp, *qw;
  PetscBool        cut;
  PetscInt         r;

  PetscFunctionBeginUser;
  PetscCall(IsCutByKink(cq, f, &cut));
  r = cut ? 1 : 0;
  PetscCall(PetscQuadratureGetData(cq->face_rule[r], NULL, NULL, &cq->Nq, &qp, &qw));
  PetscCall(FaceGeometry(cq, f, cq->Nq, qp, cq->xbuf, cq->detJ));
  for (PetscInt q = 0; q < cq->Nq; ++q) cq->wbuf[q] = qw[q] * cq->detJ[q];
  PetscCall(DMPlexGetSupport(cq->dm, f, &support));
  cq->cell = support[0];
  PetscCall(MeshCellReferenceCoordinates(cq->dm, cq->cell, cq->Nq, cq->xbuf, cq->refbuf));
  PetscCall(PetscTabulationDestroy(&cq->face_tab));
  PetscCall(PetscFECreateTabulation(cq->fe, 1, cq->Nq, cq->refbuf, 0, &cq->face_tab));
  cq->x = cq->xbuf;
  cq->w = cq->wbuf;
  cq->B = cq->face_tab->T[0];
  cq->D = NULL;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The FE function with the given closure values at point q: u[Nc] and, on cells, grad[Nc*dim] (grad may be NULL). */
PetscErrorCode CellQuadratureInterpolate(const CellQuadrature *cq, const PetscScalar closure[], PetscInt q, PetscReal u[], PetscReal grad[])
{
  const PetscInt dim = cq->dim, Nb = cq->Nb, Nc = cq->Nc, qd = CellQuadratureGradientPoint(cq, q);

  PetscFunctionBeginUser;
  for (PetscInt k = 0; k < Nc; ++k) u[k] = 0.0;
  if (grad)
    for (PetscInt k = 0; k < Nc * dim; ++k) grad[k] = 0.0;
  for (PetscInt b = 0; b < Nb; ++b) {
    const PetscReal c = PetscRealPart(closure[b]);

    if (c == 0.0) continue;
    for (PetscInt k = 0; k < Nc; ++k) {
      u[k] += c * cq->B[(q * Nb + b) * Nc + k];
      if (grad)
        for (PetscInt e = 0; e < dim; ++e) grad[k * dim + e] += c * cq->D[((qd * Nb + b) * Nc + k) * dim + e];
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}
