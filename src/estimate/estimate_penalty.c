/* The penalty part of the estimate: the error the penalty law adds to that of the exact contact on the same mesh.

   With the active set fixed, the penalty solution u_h(eps) and the exact contact's u_h(0) differ by the elastic field
   e that takes the penetration d = [u_h . n - g]_+ = eps p_h on Gamma_C and carries no load elsewhere: the residual of
   u_h(eps) vanishes off Gamma_C, and on the contact zone u_h(0) . n = g. Its energy is the work of the traction that
   imposes d, which for an elastic half-space is (Boussinesq, Johnson's "Contact mechanics" 2.9 and 3.4)
     ||e||_a^2 = (E* / 2) int |xi| |d^(xi)|^2 dxi / (2 pi)^(dim-1)  <=  (E* / 2) ||d||_{0,Gamma_C} ||grad_t d||_{0,Gamma_C},
   E* = E / (1 - nu^2), the bound by Cauchy-Schwarz in Fourier space (sharp when d is a single wave length). So
     eta_penalty^2 = (E* / 2) ||d|| ||grad_t d||,
   which falls like eps at a fixed mesh (d = eps p_h) and like h with eps = h, as the penalty's error does. It needs no
   solve; the half-space's operator is that of a body large against the contact zone, and a stiffer body (a contact zone
   across the whole of a thin body) has a larger one. Each contact face gets the share
   (||d||_F^2 / ||d||^2 + ||grad_t d||_F^2 / ||grad_t d||^2) / 2 of the total.
   d is the rule's: [u_h . n - g]_+ at each point for the Gauss rule, the interpolant of the nodal [u_n - g]_+ for the
   nodal rule (whose constraint is nodal); grad_t d is that of the interpolant of the nodal values of u_h . n - g, where
   d > 0. SNESVI and no contact have no penalty part. */
#include "contact.h"
#include "estimate_impl.h"
#include "obstacle.h"

/* |grad_t v|^2 of the linear interpolant on the face of the nodal values v[]: with the edges e_k = x_k - x_0 and
   v_k - v_0 = grad_t v . e_k, grad_t v = sum_k a_k e_k solves the Gram system G a = dv, and |grad_t v|^2 = a . dv. */
static PetscReal TangentialGradientSquared(PetscInt dim, const EstimateCell *cell, const EstimateFace *face, const PetscReal v[])
{
  PetscReal e[2][3], dv[2], G[4], a[2];
  PetscInt  m = face->nv - 1;

  for (PetscInt k = 0; k < m; ++k) {
    for (PetscInt d = 0; d < dim; ++d) e[k][d] = cell->x[face->local[k + 1] * dim + d] - cell->x[face->local[0] * dim + d];
    dv[k] = v[k + 1] - v[0];
  }
  for (PetscInt i = 0; i < m; ++i)
    for (PetscInt j = 0; j < m; ++j) {
      G[i * m + j] = 0.0;
      for (PetscInt d = 0; d < dim; ++d) G[i * m + j] += e[i][d] * e[j][d];
    }
  if (m == 1) return dv[0] * dv[0] / G[0];
  {
    const PetscReal det = G[0] * G[3] - G[1] * G[2];

    a[0] = (G[3] * dv[0] - G[1] * dv[1]) / det;
    a[1] = (G[0] * dv[1] - G[2] * dv[0]) / det;
  }
  return a[0] * dv[0] + a[1] * dv[1];
}

PetscErrorCode EstimatePenaltyTerm(EstimateWork *w)
{
  const PetscInt     dim   = w->dim;
  const Material    *mat   = w->mat;
  const BoundarySet *bcs   = &w->scene->bcs;
  const PetscBool    nodal = w->pressure.nodal; /* the nodal rule */
  PetscReal         *share, sums[2] = {0.0, 0.0}, gsums[2], estar, eta2;

  PetscFunctionBeginUser;
  if (!w->pressure.law) PetscFunctionReturn(PETSC_SUCCESS);   /* no eps: no penalty part */
  PetscCall(PetscCalloc1(2 * (w->cEnd - w->cStart), &share)); /* per cell: ||d||^2 and ||grad_t d||^2 on its contact faces */
  for (PetscInt s = 0; s < bcs->ncontact; ++s) {
    PetscInt *faces, nf;

    PetscCall(MeshGetBoundaryFaces(w->dm, bcs->contact_ids[s], &nf, &faces));
    for (PetscInt i = 0; i < nf; ++i) {
      const PetscInt *support;
      PetscInt        ns;
      EstimateCell    cell;
      EstimateFace    face;
      PetscReal       v[3], vp[3], gg, gg_plus, dd = 0.0, gd = 0.0;

      PetscCall(DMPlexGetSupportSize(w->dm, faces[i], &ns));
      PetscCall(DMPlexGetSupport(w->dm, faces[i], &support));
      if (ns != 1) continue; /* not a boundary face */
      PetscCall(EstimateCellLoad(w, support[0], &cell));
      PetscCall(EstimateFaceOfCell(w, &cell, faces[i], &face));
      for (PetscInt k = 0; k < face.nv; ++k) { /* u . n - g at the face's nodes */
        const PetscInt a = face.local[k];
        PetscReal      n[3], g;

        ObstacleGapNormalAt(&w->scene->obstacle, dim, &cell.x[a * dim], n, &g);
        v[k] = -g;
        for (PetscInt d = 0; d < dim; ++d) v[k] += cell.u[a * dim + d] * n[d];
        vp[k] = PetscMax(v[k], 0.0);
      }
      gg      = TangentialGradientSquared(dim, &cell, &face, v);
      gg_plus = TangentialGradientSquared(dim, &cell, &face, vp);
      for (PetscInt q = 0; q < w->face_rule.n; ++q) {
        const PetscReal *b = &w->face_rule.bary[q * w->face_rule.nb];
        PetscReal        x[3], u[3], wq, d = 0.0;

        EstimateFacePoint(w, &cell, &face, q, x, u, &wq);
        if (nodal) {
          for (PetscInt k = 0; k < face.nv; ++k) d += b[k] * vp[k];
          gd += wq * gg_plus;
        } else {
          PetscReal n[3], g;

          ObstacleGapNormalAt(&w->scene->obstacle, dim, x, n, &g);
          d = -g;
          for (PetscInt k = 0; k < dim; ++k) d += u[k] * n[k];
          d = PetscMax(d, 0.0);
          if (d > 0.0) gd += wq * gg;
        }
        dd += wq * d * d;
      }
      share[2 * (support[0] - w->cStart)] += dd;
      share[2 * (support[0] - w->cStart) + 1] += gd;
      sums[0] += dd;
      sums[1] += gd;
    }
    PetscCall(PetscFree(faces));
  }
  PetscCall(MPIU_Allreduce(sums, gsums, 2, MPIU_REAL, MPIU_SUM, PetscObjectComm((PetscObject)w->dm)));
  estar = mat->young_modulus / (1.0 - PetscSqr(mat->poisson_ratio));
  eta2  = 0.5 * estar * PetscSqrtReal(gsums[0] * gsums[1]);
  if (eta2 > 0.0)
    for (PetscInt c = 0; c < w->cEnd - w->cStart; ++c)
      w->eta2[c * ESTIMATE_NUM_PARTS + ESTIMATE_PENALTY] = eta2 * 0.5 * (share[2 * c] / gsums[0] + share[2 * c + 1] / gsums[1]);
  PetscCall(PetscFree(share));
  PetscFunctionReturn(PETSC_SUCCESS);
}
