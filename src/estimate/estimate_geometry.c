/* The geometry the estimate walks: a P1 simplex (its barycentric gradients, grad u_h and sigma(u_h)), its faces
   (outward normal, measure, diameter) and the points of the face rule on them. */
#include "estimate_impl.h"
#include "physics.h"
#include "discretization.h"

/* The cell c: vertices, coordinates, displacement, the gradients of the barycentric coordinates, grad u_h and sigma(u_h). */
PetscErrorCode EstimateCellLoad(EstimateWork *w, PetscInt c, EstimateCell *cell)
{
  const PetscInt dim = w->dim;

  PetscFunctionBeginUser;
  PetscCall(MeshClosureVertices(&w->mc, c, 4, &cell->nv, cell->vert));
  PetscCheck(cell->nv == dim + 1, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Cell %" PetscInt_FMT " is not a simplex", c);
  for (PetscInt k = 0; k < cell->nv; ++k) {
    PetscInt coff;

    PetscCall(PetscSectionGetOffset(w->csec, cell->vert[k], &coff));
    PetscCall(PetscSectionGetOffset(w->lsec, cell->vert[k], &cell->off[k]));
    for (PetscInt d = 0; d < dim; ++d) {
      cell->x[k * dim + d] = PetscRealPart(w->xc[coff + d]);
      cell->u[k * dim + d] = PetscRealPart(w->lu[cell->off[k] + d]);
    }
  }
  {
    PetscReal g[4][3];

    PetscCall(ElementP1Gradients(dim, cell->x, g, &cell->volume));
    for (PetscInt k = 0; k < cell->nv; ++k)
      for (PetscInt d = 0; d < dim; ++d) cell->dl[k * dim + d] = g[k][d];
  }
  cell->diameter = 0.0;
  for (PetscInt a = 0; a < cell->nv; ++a)
    for (PetscInt b = a + 1; b < cell->nv; ++b) {
      PetscReal d2 = 0.0;

      for (PetscInt d = 0; d < dim; ++d) d2 += PetscSqr(cell->x[a * dim + d] - cell->x[b * dim + d]);
      cell->diameter = PetscMax(cell->diameter, PetscSqrtReal(d2));
    }
  for (PetscInt i = 0; i < dim; ++i)
    for (PetscInt j = 0; j < dim; ++j) {
      cell->grad[i * dim + j] = 0.0;
      for (PetscInt k = 0; k < cell->nv; ++k) cell->grad[i * dim + j] += cell->u[k * dim + i] * cell->dl[k * dim + j];
    }
  ElasticStress(dim, w->mat, cell->grad, cell->sigma);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The face f of the cell: its vertices among the cell's, and its outward normal -grad lambda_opp / |grad lambda_opp|
   (lambda_opp the barycentric coordinate of the vertex opposite f, which vanishes on f and grows into the cell). */
PetscErrorCode EstimateFaceOfCell(EstimateWork *w, const EstimateCell *cell, PetscInt f, EstimateFace *face)
{
  const PetscInt dim = w->dim;
  PetscInt       fv[3], nfv, opp = -1;
  PetscReal      len = 0.0;

  PetscFunctionBeginUser;
  PetscCall(MeshClosureVertices(&w->mc, f, 3, &nfv, fv));
  PetscCheck(nfv == dim, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Face %" PetscInt_FMT " has %" PetscInt_FMT " vertices", f, nfv);
  face->nv = nfv;
  for (PetscInt k = 0; k < cell->nv; ++k) {
    PetscInt j;

    for (j = 0; j < nfv; ++j)
      if (fv[j] == cell->vert[k]) break;
    if (j < nfv)
      face->local[j] = k;
    else
      opp = k;
  }
  PetscCheck(opp >= 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Face %" PetscInt_FMT " is not a face of its cell", f);
  for (PetscInt d = 0; d < dim; ++d) len += PetscSqr(cell->dl[opp * dim + d]);
  len = PetscSqrtReal(len);
  for (PetscInt d = 0; d < dim; ++d) face->normal[d] = -cell->dl[opp * dim + d] / len;
  face->measure  = dim * cell->volume * len; /* |T| = |F| dist(x_opp, F) / dim and |grad lambda_opp| = 1 / dist */
  face->diameter = 0.0;
  for (PetscInt a = 0; a < nfv; ++a)
    for (PetscInt b = a + 1; b < nfv; ++b) {
      PetscReal d2 = 0.0;

      for (PetscInt d = 0; d < dim; ++d) d2 += PetscSqr(cell->x[face->local[a] * dim + d] - cell->x[face->local[b] * dim + d]);
      face->diameter = PetscMax(face->diameter, PetscSqrtReal(d2));
    }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Point q of the face rule on the face: its position, u_h there, and its weight times the face's measure. */
void EstimateFacePoint(const EstimateWork *w, const EstimateCell *cell, const EstimateFace *face, PetscInt q, PetscReal x[], PetscReal u[],
                       PetscReal *weight)
{
  const PetscInt   dim = w->dim;
  const PetscReal *b   = &w->face_rule.bary[q * w->face_rule.nb];

  for (PetscInt d = 0; d < dim; ++d) {
    x[d] = 0.0;
    u[d] = 0.0;
    for (PetscInt k = 0; k < face->nv; ++k) {
      x[d] += b[k] * cell->x[face->local[k] * dim + d];
      u[d] += b[k] * cell->u[face->local[k] * dim + d];
    }
  }
  *weight = w->face_rule.w[q] * face->measure;
}
