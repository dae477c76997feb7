/* The Gauss rule of the penalty term on P1 simplices in closed form: PETSc's face quadrature and the same pointwise
   kernels (src/contact/penalty_kernels.h), each face's points and weights computed once, instead of PETSc's boundary
   integration (DMPlexComputeBdJacobianSingle()) with its generic element loops at every call. The numbers are PETSc
   3.18's to round-off (-assembly_check):
   the kernel sees the point x of the face's own map, the displacement and the test functions are the support cell's
   basis at its reference face's points, as PETSc evaluates them. On a face whose orientation in its cell is not the
   identity (3D refinement makes such faces) those are other points of the same face; PETSc's choice is kept.
   One of PETSc 3.18's mirrors (docs/decisions.md, "PETSc 3.18's mirrors"). */
#include "penalty.h"
#include "penalty_kernels.h"
#include "mesh.h"

/* ref_face[i * dim + k]: the k-th vertex of face i of PETSc's reference simplex (in the face's closure order), as an
   index among the cell's vertices (in the cell's closure order, which every cell of the mesh shares with it). */
static PetscErrorCode ReferenceFaceVertices(PetscInt dim, PetscInt ref_face[])
{
  DM              ref;
  const PetscInt *cone;
  PetscInt       *cl = NULL, ncl, vStart, vEnd, cellv[4], nv = 0;

  PetscFunctionBeginUser;
  PetscCall(DMPlexCreateReferenceCell(PETSC_COMM_SELF, dim == 2 ? DM_POLYTOPE_TRIANGLE : DM_POLYTOPE_TETRAHEDRON, &ref));
  PetscCall(DMPlexGetDepthStratum(ref, 0, &vStart, &vEnd));
  PetscCall(DMPlexGetTransitiveClosure(ref, 0, PETSC_TRUE, &ncl, &cl));
  for (PetscInt k = 0; k < ncl; ++k)
    if (cl[2 * k] >= vStart && cl[2 * k] < vEnd) cellv[nv++] = cl[2 * k];
  PetscCall(DMPlexRestoreTransitiveClosure(ref, 0, PETSC_TRUE, &ncl, &cl));
  PetscCall(DMPlexGetCone(ref, 0, &cone));
  for (PetscInt i = 0; i < dim + 1; ++i) {
    PetscInt m = 0;

    PetscCall(DMPlexGetTransitiveClosure(ref, cone[i], PETSC_TRUE, &ncl, &cl));
    for (PetscInt k = 0; k < ncl; ++k)
      for (PetscInt j = 0; j < nv; ++j)
        if (cl[2 * k] == cellv[j]) ref_face[i * dim + m++] = j;
    PetscCall(DMPlexRestoreTransitiveClosure(ref, cone[i], PETSC_TRUE, &ncl, &cl));
  }
  PetscCall(DMDestroy(&ref));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The faces of every contact face set (a face in two sets counts twice, as in PETSc's integration per set), mapped
   once per mesh; nothing unless the penalty term has the Gauss rule and K the P1 assembly (the closed form's cases). */
PetscErrorCode PenaltyFacesSetUp(Contact ct, DM dm, PenaltyFaces *pf)
{
  const PetscBool  local_eps = ct->eps_local;
  PetscSection     lsec, gsec;
  PetscObject      fe;
  PetscQuadrature  quad;
  const PetscReal *qp, *qw;
  PetscInt         dim, qdim, qnc, vStart, vEnd, nfaces = 0, e = 0;
  PetscInt       **faces, *nf, ref_face[4 * 3];

  PetscFunctionBeginUser;
  PetscCall(PenaltyFacesDestroy(pf));
  if (ct->opt.quadrature != PENALTY_QUADRATURE_GAUSS || ct->assembly != ASSEMBLY_P1) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMGetLocalSection(dm, &lsec));
  PetscCall(DMGetGlobalSection(dm, &gsec));
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  PetscCall(DMGetField(dm, 0, NULL, &fe));
  PetscCall(PetscFEGetFaceQuadrature((PetscFE)fe, &quad));
  PetscCall(PetscQuadratureGetData(quad, &qdim, &qnc, &pf->nq, &qp, &qw));
  PetscCheck(qdim == dim - 1 && qnc == 1, PetscObjectComm((PetscObject)dm), PETSC_ERR_PLIB, "unexpected face quadrature");
  pf->nv = dim;
  PetscCall(ReferenceFaceVertices(dim, ref_face));
  PetscCall(PetscMalloc2(ct->nids, &faces, ct->nids, &nf));
  for (PetscInt s = 0; s < ct->nids; ++s) {
    PetscCall(MeshGetBoundaryFaces(dm, ct->ids[s], &nf[s], &faces[s]));
    nfaces += nf[s];
  }
  pf->n = nfaces;
  PetscCall(PetscMalloc5(nfaces * dim, &pf->loff, nfaces * dim * dim, &pf->gidx, nfaces * pf->nq * dim, &pf->x, nfaces * pf->nq, &pf->w, pf->nq * dim,
                         &pf->lambda));
  if (local_eps) PetscCall(PetscMalloc1(nfaces, &pf->inv_factor));
  for (PetscInt q = 0; q < pf->nq; ++q) { /* PETSc's reference simplex has its vertices at -1 and the unit vectors */
    PetscReal sum = 0.0;

    for (PetscInt j = 0; j < qdim; ++j) {
      pf->lambda[q * dim + j + 1] = 0.5 * (qp[q * qdim + j] + 1.0);
      sum += pf->lambda[q * dim + j + 1];
    }
    pf->lambda[q * dim] = 1.0 - sum;
  }
  for (PetscInt s = 0; s < ct->nids; ++s)
    for (PetscInt i = 0; i < nf[s]; ++i, ++e) {
      const PetscInt  f = faces[s][i];
      const PetscInt *support, *cone;
      PetscInt       *cl = NULL, ncl, nv = 0, cellv[4], li;
      PetscReal       v0[3], J[9], detJ;

      /* PETSc's own affine map of the face, vertices in closure order: x = v0 + J (xi + 1) */
      PetscCall(DMPlexComputeCellGeometryAffineFEM(dm, f, v0, J, NULL, &detJ));
      for (PetscInt q = 0; q < pf->nq; ++q) {
        PetscReal *x = &pf->x[(e * pf->nq + q) * dim];

        for (PetscInt d = 0; d < dim; ++d) x[d] = v0[d];
        for (PetscInt d = 0; d < dim; ++d)
          for (PetscInt j = 0; j < qdim; ++j) x[d] += J[d * dim + j] * (qp[q * qdim + j] + 1.0);
        pf->w[e * pf->nq + q] = detJ * qw[q];
      }
      /* the displacement where PETSc evaluates it: the support cell's basis at the points of its reference face li */
      PetscCall(DMPlexGetSupport(dm, f, &support));
      PetscCall(DMPlexGetCone(dm, support[0], &cone));
      for (li = 0; li < dim + 1 && cone[li] != f; ++li) {
      }
      PetscCheck(li < dim + 1, PETSC_COMM_SELF, PETSC_ERR_PLIB, "face %" PetscInt_FMT " is not in the cone of its cell", f);
      PetscCall(DMPlexGetTransitiveClosure(dm, support[0], PETSC_TRUE, &ncl, &cl));
      for (PetscInt k = 0; k < ncl; ++k)
        if (cl[2 * k] >= vStart && cl[2 * k] < vEnd) cellv[nv++] = cl[2 * k];
      PetscCall(DMPlexRestoreTransitiveClosure(dm, support[0], PETSC_TRUE, &ncl, &cl));
      PetscCheck(nv == dim + 1, PETSC_COMM_SELF, PETSC_ERR_PLIB, "cell %" PetscInt_FMT " is not a simplex", support[0]);
      for (PetscInt k = 0; k < dim; ++k) {
        const PetscInt p = cellv[ref_face[li * dim + k]];

        PetscCall(PetscSectionGetOffset(lsec, p, &pf->loff[e * dim + k]));
        PetscCall(MeshPointGlobalIndices(lsec, gsec, p, dim, &pf->gidx[(e * dim + k) * dim]));
      }
      if (local_eps) {
        PetscReal diam;

        PetscCall(MeshCellSize(dm, support[0], &diam));
        pf->inv_factor[e] = 1.0 / ContactEpsFactor(ct, diam);
      }
    }
  for (PetscInt s = 0; s < ct->nids; ++s) PetscCall(PetscFree(faces[s]));
  PetscCall(PetscFree2(faces, nf));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PenaltyFacesDestroy(PenaltyFaces *pf)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree5(pf->loff, pf->gidx, pf->x, pf->w, pf->lambda));
  PetscCall(PetscFree(pf->inv_factor));
  PetscCall(PetscMemzero(pf, sizeof(*pf)));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The displacement at point q of face e, from the local vector x. */
static inline void FaceDisplacement(const PenaltyFaces *pf, PetscInt dim, PetscInt e, PetscInt q, const PetscScalar x[], PetscScalar u[])
{
  for (PetscInt c = 0; c < dim; ++c) u[c] = 0.0;
  for (PetscInt k = 0; k < pf->nv; ++k)
    for (PetscInt c = 0; c < dim; ++c) u[c] += pf->lambda[q * pf->nv + k] * x[pf->loff[e * pf->nv + k] + c];
}

/* What the kernels need besides u, x and the face's 1/eps factor: the dimension and the constants of the discretization. */
static PetscErrorCode FaceKernelData(DM dm, PetscInt *dim, PetscInt *ncst, const PetscScalar **cst)
{
  PetscDS ds;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, dim));
  PetscCall(DMGetDS(dm, &ds));
  PetscCall(PetscDSGetConstants(ds, ncst, cst));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Without energy: locF += the penalty term (f0_bd_penalty) at the local solution locX. With energy: *energy = this
   rank's integral of the energy density (f0_bd_penalty_energy), and locF is not touched. */
static PetscErrorCode PenaltyFacesIntegrate(const PenaltyFaces *pf, DM dm, Vec locX, Vec locF, PetscReal *energy)
{
  const PetscInt     zero[1]  = {0};
  const PetscReal    nzero[3] = {0.0, 0.0, 0.0};
  const PetscScalar *x, *cst;
  PetscScalar       *f = NULL;
  PetscInt           dim, ncst;
  PetscReal          esum = 0.0;

  PetscFunctionBeginUser;
  PetscCall(FaceKernelData(dm, &dim, &ncst, &cst));
  PetscCall(VecGetArrayRead(locX, &x));
  if (!energy) PetscCall(VecGetArray(locF, &f));
  for (PetscInt e = 0; e < pf->n; ++e) {
    const PetscScalar a[1]  = {pf->inv_factor ? pf->inv_factor[e] : 1.0};
    const PetscInt    nfaux = pf->inv_factor ? 1 : 0;
    PetscScalar       ev[9] = {0.0};

    for (PetscInt q = 0; q < pf->nq; ++q) {
      const PetscReal  w  = pf->w[e * pf->nq + q];
      const PetscReal *xq = &pf->x[(e * pf->nq + q) * dim];
      PetscScalar      u[3], f0[3];

      FaceDisplacement(pf, dim, e, q, x, u);
      if (energy) {
        f0_bd_penalty_energy(dim, 1, nfaux, zero, zero, u, NULL, NULL, zero, zero, a, NULL, NULL, 0.0, xq, nzero, ncst, cst, f0);
        esum += w * PetscRealPart(f0[0]);
        continue;
      }
      f0_bd_penalty(dim, 1, nfaux, zero, zero, u, NULL, NULL, zero, zero, a, NULL, NULL, 0.0, xq, nzero, ncst, cst, f0);
      for (PetscInt k = 0; k < pf->nv; ++k)
        for (PetscInt c = 0; c < dim; ++c) ev[k * dim + c] += pf->lambda[q * pf->nv + k] * w * f0[c];
    }
    if (!energy)
      for (PetscInt k = 0; k < pf->nv; ++k)
        for (PetscInt c = 0; c < dim; ++c) f[pf->loff[e * pf->nv + k] + c] += ev[k * dim + c];
  }
  if (!energy) PetscCall(VecRestoreArray(locF, &f));
  PetscCall(VecRestoreArrayRead(locX, &x));
  if (energy) *energy = esum;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PenaltyFacesResidual(const PenaltyFaces *pf, DM dm, Vec locX, Vec locF)
{
  PetscFunctionBeginUser;
  PetscCall(PenaltyFacesIntegrate(pf, dm, locX, locF, NULL));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PenaltyFacesEnergy(const PenaltyFaces *pf, DM dm, Vec locX, PetscReal *energy)
{
  PetscFunctionBeginUser;
  PetscCall(PenaltyFacesIntegrate(pf, dm, locX, NULL, energy));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The largest u_n - g at the Gauss points of this rank's contact faces (-PETSC_MAX_REAL if it has none). */
PetscErrorCode PenaltyFacesMaxPenetration(const PenaltyFaces *pf, DM dm, Vec locX, PetscReal *dmax)
{
  const PetscScalar *x, *cst;
  PetscInt           dim, ncst;

  PetscFunctionBeginUser;
  PetscCall(FaceKernelData(dm, &dim, &ncst, &cst));
  *dmax = -PETSC_MAX_REAL;
  PetscCall(VecGetArrayRead(locX, &x));
  for (PetscInt e = 0; e < pf->n; ++e)
    for (PetscInt q = 0; q < pf->nq; ++q) {
      PetscScalar u[3];
      PetscReal   nu[3];

      FaceDisplacement(pf, dim, e, q, x, u);
      *dmax = PetscMax(*dmax, ObstaclePenetration(dim, &cst[CONST_OBSTACLE], &pf->x[(e * pf->nq + q) * dim], u, nu));
    }
  PetscCall(VecRestoreArrayRead(locX, &x));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The Jacobian's kernel g0 at point q of face e for the local solution x, and whether it is nonzero there (the point
   penetrates: the penalty is active). */
static inline PetscBool FacePointKernel(const PenaltyFaces *pf, PetscInt dim, PetscInt e, PetscInt q, const PetscScalar x[], PetscInt ncst,
                                        const PetscScalar cst[], PetscScalar g0[])
{
  const PetscInt    zero[1] = {0}, nfaux = pf->inv_factor ? 1 : 0;
  const PetscReal   nzero[3] = {0.0, 0.0, 0.0};
  const PetscScalar a[1]     = {pf->inv_factor ? pf->inv_factor[e] : 1.0};
  PetscScalar       u[3];
  PetscBool         active = PETSC_FALSE;

  for (PetscInt c = 0; c < dim * dim; ++c) g0[c] = 0.0;
  FaceDisplacement(pf, dim, e, q, x, u);
  g0_bd_penalty(dim, 1, nfaux, zero, zero, u, NULL, NULL, zero, zero, a, NULL, NULL, 0.0, 0.0, &pf->x[(e * pf->nq + q) * dim], nzero, ncst, cst, g0);
  for (PetscInt c = 0; c < dim * dim; ++c) active = (PetscBool)(active || g0[c] != 0.0);
  return active;
}

/* J += the penalty Jacobian at locX (ADD_VALUES into the global rows, any rank's; the caller assembles J). A face
   without a penetrating point adds nothing and is skipped. */
PetscErrorCode PenaltyFacesJacobian(const PenaltyFaces *pf, DM dm, Vec locX, Mat J)
{
  const PetscScalar *x, *cst;
  PetscInt           dim, ncst;

  PetscFunctionBeginUser;
  PetscCall(FaceKernelData(dm, &dim, &ncst, &cst));
  PetscCall(VecGetArrayRead(locX, &x));
  for (PetscInt e = 0; e < pf->n; ++e) {
    const PetscInt nd     = pf->nv * dim;
    PetscScalar    em[81] = {0.0};
    PetscBool      any    = PETSC_FALSE;

    for (PetscInt q = 0; q < pf->nq; ++q) {
      const PetscReal w = pf->w[e * pf->nq + q];
      PetscScalar     g0[9];

      if (!FacePointKernel(pf, dim, e, q, x, ncst, cst, g0)) continue;
      any = PETSC_TRUE;
      for (PetscInt k = 0; k < pf->nv; ++k)
        for (PetscInt l = 0; l < pf->nv; ++l) {
          const PetscReal bb = w * pf->lambda[q * pf->nv + k] * pf->lambda[q * pf->nv + l];

          for (PetscInt c = 0; c < dim; ++c)
            for (PetscInt d = 0; d < dim; ++d) em[(k * dim + c) * nd + l * dim + d] += bb * g0[c * dim + d];
        }
    }
    if (any) PetscCall(MatSetValues(J, nd, &pf->gidx[e * nd], nd, &pf->gidx[e * nd], em, ADD_VALUES));
  }
  PetscCall(VecRestoreArrayRead(locX, &x));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Whether the Gauss points penetrating at locA are those penetrating at locB (this rank's faces): where the Jacobian's
   kernel is nonzero at one and not at the other, Newton's model at one misses a kink that the other crosses. */
PetscErrorCode PenaltyFacesSameActivity(const PenaltyFaces *pf, DM dm, Vec locA, Vec locB, PetscBool *same)
{
  const PetscScalar *xa, *xb, *cst;
  PetscInt           dim, ncst;

  PetscFunctionBeginUser;
  PetscCall(FaceKernelData(dm, &dim, &ncst, &cst));
  PetscCall(VecGetArrayRead(locA, &xa));
  PetscCall(VecGetArrayRead(locB, &xb));
  *same = PETSC_TRUE;
  for (PetscInt e = 0; e < pf->n && *same; ++e)
    for (PetscInt q = 0; q < pf->nq && *same; ++q) {
      PetscScalar g0[9];

      *same = (PetscBool)(FacePointKernel(pf, dim, e, q, xa, ncst, cst, g0) == FacePointKernel(pf, dim, e, q, xb, ncst, cst, g0));
    }
  PetscCall(VecRestoreArrayRead(locA, &xa));
  PetscCall(VecRestoreArrayRead(locB, &xb));
  PetscFunctionReturn(PETSC_SUCCESS);
}
