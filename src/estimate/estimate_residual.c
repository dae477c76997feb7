/* The residual parts of the estimate (estimate.c says where they come from), for P1 simplices, each squared term divided
   by 2 mu:
     bulk      eta_T^2 = h_T^2 ||f||_T^2                       (div sigma(u_h) = 0 in a P1 cell)
     jump      eta_F^2 = h_F ||[sigma(u_h) n]||_F^2            interior faces, half to each of the two cells
     neumann   eta_F^2 = h_F ||t - sigma(u_h) n||_F^2          loaded and free faces; on a slip face the free components
     contact   eta_F^2 = h_F ||sigma(u_h) n + p_h n_o||_F^2    on Gamma_C, split along the obstacle's normal n_o (normal)
                                                               and across it (tangential: frictionless, the traction has none)
   with h_T, h_F the diameters, f the body force, t the traction of the face, p_h the contact pressure of the method:
   the penalty law (1/eps)[u_h . n_o - g]_+ at each point for the Gauss rule (the traction the discrete problem applies),
   and the nodal force over the lumped area, interpolated, for the nodal rule and SNESVI.

   A scene with weak data (mms) is loaded in divergence form, L(v) = (G, eps(v)) - (n_o . G n_o, v . n_o)_Gamma_C with
   G = sigma(u_exact), and its pointwise f = -div G need not be square-integrable (|x_1 - a|^(nu - 1) for the
   manufactured solution). Its residual is split with the cells' means Pi_0 G: in a P1 cell Pi_0 G - sigma(u_h) is
   constant, so (Pi_0 G - sigma(u_h), eps(v))_T moves to T's faces, and what remains in the cell is (G - Pi_0 G, eps(v))_T,
   bounded by the data oscillation ||G - Pi_0 G||_{C^-1,T} ||v||_a with the constant 1 (Verfurth 2013, section 1.4.5).
   So for such a scene
     bulk      eta_T^2 = ||G - Pi_0 G||^2_{C^-1,T} = int_T (G - Pi_0 G) : C^-1 (G - Pi_0 G),
   and sigma(u_h) - Pi_0 G replaces sigma(u_h) in the jumps and on the free faces (whose datum G n is inside (G, eps(v))),
   while Gamma_C keeps its pointwise datum: R = (sigma(u_h) - Pi_0 G) n + (n_o . G n_o) n_o + p_h n_o.
   The means and the oscillation use the load's own rule (src/discretization/cell_quadrature.c: composite on the cells
   the kink cuts), where G is Holder continuous.
   The jumps need the stress of both cells of a face, which may sit on two ranks: each cell adds sigma n_out to its
   faces, and the point SF sums them, so that an interior face holds sigma_1 n_1 + sigma_2 n_2 = [sigma n]. */
#include <petscsf.h>
#include "contact.h"
#include "discretization.h"
#include "estimate_impl.h"
#include "obstacle.h"
#include "physics.h"

/* The body force at x: -f0_body (which includes -body_force), or the constant body force. */
static PetscErrorCode BodyForce(const EstimateWork *w, const PetscReal x[], PetscReal f[])
{
  const Scene   *scene = w->scene;
  const PetscInt dim   = w->dim;

  PetscFunctionBeginUser;
  for (PetscInt d = 0; d < dim; ++d) f[d] = 0.0;
  if (scene->f0_body) {
    const PetscScalar zero[9] = {0.0};
    PetscScalar       f0[3];

    scene->f0_body(dim, 1, 0, NULL, NULL, zero, NULL, zero, NULL, NULL, NULL, NULL, NULL, 0.0, x, w->nconstants, w->constants, f0);
    for (PetscInt d = 0; d < dim; ++d) f[d] -= PetscRealPart(f0[d]);
  } else
    for (PetscInt d = 0; d < dim; ++d) f[d] += PetscRealPart(w->constants[CONST_BODY_FORCE + d]);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* tau : C^-1 tau, the complementary energy density of a symmetric tensor: C^-1 tau = (tau - lambda / (2 mu + d lambda)
   tr(tau) I) / (2 mu), in plane strain (d = 2) as in 3D. */
static PetscReal ComplianceSquare(const EstimateWork *w, const PetscReal tau[])
{
  const PetscReal lambda = w->mat->lambda, mu = w->mat->mu;
  PetscReal       tr = 0.0, tt = 0.0;

  for (PetscInt d = 0; d < w->dim; ++d) tr += tau[d * w->dim + d];
  for (PetscInt k = 0; k < w->dim * w->dim; ++k) tt += tau[k] * tau[k];
  return (tt - lambda / (2.0 * mu + w->dim * lambda) * tr * tr) / (2.0 * mu);
}

/* Pi_0 G on cell c and the oscillation ||G - Pi_0 G||^2_{C^-1,T}, by the load's rule (G at its points kept between
   the two passes, in a work array of the DM) */
static PetscErrorCode LoadOscillation(EstimateWork *w, CellQuadrature *cq, PetscInt c, PetscReal mean[], PetscReal *osc)
{
  const PetscInt n   = w->dim * w->dim;
  PetscReal      vol = 0.0, D[9], *G;

  PetscFunctionBeginUser;
  PetscCall(CellQuadratureSetCell(cq, c));
  PetscCall(DMGetWorkArray(w->dm, cq->Nq * n, MPIU_REAL, &G));
  for (PetscInt k = 0; k < n; ++k) mean[k] = 0.0;
  for (PetscInt q = 0; q < cq->Nq; ++q) {
    PetscCall(WeakDataExactStress(w->scene, w->mat, w->dim, &cq->x[q * w->dim], &G[q * n]));
    for (PetscInt k = 0; k < n; ++k) mean[k] += cq->w[q] * G[q * n + k];
    vol += cq->w[q];
  }
  for (PetscInt k = 0; k < n; ++k) mean[k] /= vol;
  *osc = 0.0;
  for (PetscInt q = 0; q < cq->Nq; ++q) {
    for (PetscInt k = 0; k < n; ++k) D[k] = G[q * n + k] - mean[k];
    *osc += cq->w[q] * ComplianceSquare(w, D);
  }
  PetscCall(DMRestoreWorkArray(w->dm, cq->Nq * n, MPIU_REAL, &G));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* sigma(u_h) of a cell, less Pi_0 G for a scene with weak data: the stress whose tractions the faces' terms measure */
static void CellStress(const EstimateWork *w, const EstimateCell *cell, PetscInt c, PetscReal s[])
{
  for (PetscInt k = 0; k < w->dim * w->dim; ++k)
    s[k] = cell->sigma[k] - (w->scene->weak_data ? w->load_mean[(c - w->cStart) * w->dim * w->dim + k] : 0.0);
}

/* |R . n|^2 / (lambda + 2 mu) + |R - (R . n) n|^2 / (2 mu): a traction R in energy units, by the stiffness of the body
   against it (a normal traction stretches, a tangential one shears). */
static PetscReal WeightedSquare(const EstimateWork *w, const PetscReal R[], const PetscReal n[])
{
  PetscReal rn = 0.0, rt = 0.0;

  for (PetscInt d = 0; d < w->dim; ++d) rn += R[d] * n[d];
  for (PetscInt d = 0; d < w->dim; ++d) rt += PetscSqr(R[d] - rn * n[d]);
  return rn * rn / w->m_normal + rt / w->m_shear;
}

/* Bulk terms, and each cell's sigma n_out (less Pi_0 G n_out with weak data) added to its faces' sums (with a count
   of the cells). */
static PetscErrorCode CellTerms(EstimateWork *w, PetscInt pStart)
{
  const PetscInt dim      = w->dim;
  PetscBool      has_load = (PetscBool)(w->scene->f0_body != NULL);
  CellQuadrature cq;

  PetscFunctionBeginUser;
  for (PetscInt d = 0; d < dim && !has_load; ++d) has_load = (PetscBool)(PetscRealPart(w->constants[CONST_BODY_FORCE + d]) != 0.0);
  if (w->scene->weak_data) PetscCall(CellQuadratureCreate(w->dm, w->scene, w->verify, &cq));
  for (PetscInt c = w->cStart; c < w->cEnd; ++c) {
    EstimateCell    cell;
    const PetscInt *cone;
    PetscInt        ncone;
    PetscReal       sigma[9];

    PetscCall(EstimateCellLoad(w, c, &cell));
    if (w->scene->weak_data) {
      PetscReal osc = 0.0;

      PetscCall(LoadOscillation(w, &cq, c, &w->load_mean[(c - w->cStart) * dim * dim], &osc));
      w->eta2[(c - w->cStart) * ESTIMATE_NUM_PARTS + ESTIMATE_BULK] += osc;
    }
    CellStress(w, &cell, c, sigma);
    w->volume[c - w->cStart] = cell.volume;
    for (PetscInt i = 0; i < dim * dim; ++i) w->norm2 += cell.volume * cell.sigma[i] * cell.grad[i]; /* sigma : eps(u_h), sigma symmetric */
    if (has_load) {
      PetscReal ff = 0.0;

      for (PetscInt q = 0; q < w->cell_rule.n; ++q) {
        const PetscReal *b = &w->cell_rule.bary[q * w->cell_rule.nb];
        PetscReal        x[3], f[3];

        for (PetscInt d = 0; d < dim; ++d) {
          x[d] = 0.0;
          for (PetscInt k = 0; k < cell.nv; ++k) x[d] += b[k] * cell.x[k * dim + d];
        }
        PetscCall(BodyForce(w, x, f));
        for (PetscInt d = 0; d < dim; ++d) ff += w->cell_rule.w[q] * cell.volume * f[d] * f[d];
      }
      w->eta2[(c - w->cStart) * ESTIMATE_NUM_PARTS + ESTIMATE_BULK] += PetscSqr(cell.diameter) * ff / w->m_normal;
    }
    PetscCall(DMPlexGetConeSize(w->dm, c, &ncone));
    PetscCall(DMPlexGetCone(w->dm, c, &cone));
    for (PetscInt k = 0; k < ncone; ++k) {
      EstimateFace face;
      PetscReal   *s = &w->face_sum[(cone[k] - pStart) * (dim + 1)];

      PetscReal *geom = &w->face_geom[(cone[k] - w->fStart) * (dim + 2)];

      PetscCall(EstimateFaceOfCell(w, &cell, cone[k], &face));
      for (PetscInt i = 0; i < dim; ++i)
        for (PetscInt j = 0; j < dim; ++j) s[i] += sigma[i * dim + j] * face.normal[j];
      s[dim] += 1.0;
      geom[0] = face.measure; /* the normal's sign does not matter to the jump's weighted square */
      geom[1] = face.diameter;
      for (PetscInt d = 0; d < dim; ++d) geom[2 + d] = face.normal[d];
    }
  }
  if (w->scene->weak_data) PetscCall(CellQuadratureDestroy(&cq));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The contact traction's misfit on a face of Gamma_C of cell c: into eta2[normal] and eta2[tangential]. */
static PetscErrorCode ContactFace(EstimateWork *w, PetscInt c, const EstimateCell *cell, const EstimateFace *face, PetscReal eta2[])
{
  const PetscInt dim = w->dim;
  PetscReal      sigma[9], sn[3], eps = 0.0, rn = 0.0, rt = 0.0;

  PetscFunctionBeginUser;
  CellStress(w, cell, c, sigma);
  for (PetscInt i = 0; i < dim; ++i) {
    sn[i] = 0.0;
    for (PetscInt j = 0; j < dim; ++j) sn[i] += sigma[i * dim + j] * face->normal[j];
  }
  if (w->pressure.law && !w->pressure.nodal) PetscCall(ContactFaceEps(w->contact, cell->diameter, &eps));
  for (PetscInt q = 0; q < w->face_rule.n; ++q) {
    PetscReal x[3], u[3], wq, n[3], g, p = 0.0, R[3], Rn = 0.0, Rt = 0.0;

    EstimateFacePoint(w, cell, face, q, x, u, &wq);
    ObstacleGapNormalAt(&w->scene->obstacle, dim, x, n, &g);
    if (w->lp) { /* the nodal pressure, stored as p n at the nodes */
      const PetscReal *b = &w->face_rule.bary[q * w->face_rule.nb];

      for (PetscInt k = 0; k < face->nv; ++k)
        for (PetscInt d = 0; d < dim; ++d) p += b[k] * PetscRealPart(w->lp[cell->off[face->local[k]] + d]) * n[d];
    } else if (w->pressure.law) { /* the penalty law at the point */
      PetscReal d = -g;

      for (PetscInt k = 0; k < dim; ++k) d += u[k] * n[k];
      p = d > 0.0 ? d / eps : 0.0;
    }
    for (PetscInt i = 0; i < dim; ++i) R[i] = sn[i] + p * n[i];
    if (w->scene->weak_data) { /* the load's normal stress on Gamma_C, n_o . G n_o (sn holds (sigma(u_h) - Pi_0 G) n) */
      PetscReal G[9], gnn = 0.0;

      PetscCall(WeakDataExactStress(w->scene, w->mat, dim, x, G));
      for (PetscInt i = 0; i < dim; ++i)
        for (PetscInt j = 0; j < dim; ++j) gnn += n[i] * G[i * dim + j] * n[j];
      for (PetscInt i = 0; i < dim; ++i) R[i] += gnn * n[i];
    }
    for (PetscInt i = 0; i < dim; ++i) Rn += R[i] * n[i];
    for (PetscInt i = 0; i < dim; ++i) Rt += PetscSqr(R[i] - Rn * n[i]);
    rn += wq * Rn * Rn;
    rt += wq * Rt;
  }
  eta2[ESTIMATE_CONTACT_NORMAL] += face->diameter * rn / w->m_normal;
  eta2[ESTIMATE_CONTACT_TANGENTIAL] += face->diameter * rt / w->m_shear;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* t - sigma(u_h) n on a loaded, free or slip face of cell c (the slip's fixed components carry the support's reaction);
   with weak data t - (sigma(u_h) - Pi_0 G) n, the face's datum G n being inside (G, eps(v)). Constant on the face. */
static PetscErrorCode NeumannFace(EstimateWork *w, PetscInt c, const EstimateCell *cell, const EstimateFace *face, PetscInt kind, PetscReal eta2[])
{
  const PetscInt           dim      = w->dim;
  const BoundaryCondition *bc       = kind >= 0 ? &w->scene->bcs.bc[kind] : NULL;
  PetscBool                fixed[3] = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE};
  PetscReal                t0[3]    = {0.0, 0.0, 0.0}, sigma[9], sn[3], R[3];

  PetscFunctionBeginUser;
  if (bc && bc->kind == BC_CLAMP) PetscFunctionReturn(PETSC_SUCCESS);
  if (bc && bc->kind == BC_SLIP)
    for (PetscInt k = 0; k < bc->ncomp; ++k) fixed[bc->comps[k]] = PETSC_TRUE;
  if (bc && bc->kind == BC_TRACTION)
    for (PetscInt d = 0; d < dim; ++d) t0[d] = bc->value[d];
  if (bc && bc->kind == BC_PRESSURE)
    for (PetscInt d = 0; d < dim; ++d) t0[d] = -bc->value[0] * face->normal[d];
  CellStress(w, cell, c, sigma);
  for (PetscInt i = 0; i < dim; ++i) {
    sn[i] = 0.0;
    for (PetscInt j = 0; j < dim; ++j) sn[i] += sigma[i * dim + j] * face->normal[j];
  }
  for (PetscInt d = 0; d < dim; ++d) R[d] = fixed[d] ? 0.0 : t0[d] - sn[d];
  eta2[ESTIMATE_NEUMANN] += face->diameter * face->measure * WeightedSquare(w, R, face->normal);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Faces: the jumps of the interior ones (their geometry from the cell pass), the boundary terms of the others (from
   the cell holding them); a clamped face has none. */
static PetscErrorCode FaceTerms(EstimateWork *w, PetscInt pStart)
{
  const PetscInt dim = w->dim;

  PetscFunctionBeginUser;
  for (PetscInt f = w->fStart; f < w->fEnd; ++f) {
    const PetscReal *s    = &w->face_sum[(f - pStart) * (dim + 1)];
    const PetscReal *geom = &w->face_geom[(f - w->fStart) * (dim + 2)];
    const PetscInt   kind = w->face_kind[f - w->fStart];
    const PetscInt  *support;
    PetscInt         ns;

    PetscCall(DMPlexGetSupportSize(w->dm, f, &ns));
    if (!ns) continue; /* a face of no local cell */
    PetscCall(DMPlexGetSupport(w->dm, f, &support));
    if (s[dim] > 1.5) { /* interior: [sigma n] is constant on the face; half of the face's term to each cell */
      const PetscReal eta2 = 0.5 * geom[1] * geom[0] * WeightedSquare(w, s, &geom[2]);

      for (PetscInt k = 0; k < ns; ++k) w->eta2[(support[k] - w->cStart) * ESTIMATE_NUM_PARTS + ESTIMATE_JUMP] += eta2;
    } else if (kind == ESTIMATE_FACE_CONTACT || kind == ESTIMATE_FACE_FREE || w->scene->bcs.bc[kind].kind != BC_CLAMP) {
      PetscReal   *eta2 = &w->eta2[(support[0] - w->cStart) * ESTIMATE_NUM_PARTS];
      EstimateCell cell;
      EstimateFace face;

      PetscCall(EstimateCellLoad(w, support[0], &cell));
      PetscCall(EstimateFaceOfCell(w, &cell, f, &face));
      if (kind == ESTIMATE_FACE_CONTACT)
        PetscCall(ContactFace(w, support[0], &cell, &face, eta2));
      else
        PetscCall(NeumannFace(w, support[0], &cell, &face, kind, eta2));
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode EstimateResidualTerms(EstimateWork *w)
{
  const PetscInt dim = w->dim;
  PetscInt       pStart, pEnd;
  PetscSF        sf;
  PetscInt       nroots;
  MPI_Datatype   unit;

  PetscFunctionBeginUser;
  PetscCall(DMPlexGetChart(w->dm, &pStart, &pEnd));
  PetscCall(PetscCalloc1((pEnd - pStart) * (dim + 1), &w->face_sum));
  PetscCall(PetscMalloc1((w->fEnd - w->fStart) * (dim + 2), &w->face_geom));
  if (w->scene->weak_data) PetscCall(PetscMalloc1((w->cEnd - w->cStart) * dim * dim, &w->load_mean));
  PetscCall(CellTerms(w, pStart));
  /* the faces a rank shares: their owners sum the contributions, then send the sums back */
  PetscCall(DMGetPointSF(w->dm, &sf));
  PetscCall(PetscSFGetGraph(sf, &nroots, NULL, NULL, NULL));
  if (nroots >= 0) { /* a graph: a distributed mesh */
    PetscCallMPI(MPI_Type_contiguous((PetscMPIInt)(dim + 1), MPIU_REAL, &unit));
    PetscCallMPI(MPI_Type_commit(&unit));
    PetscCall(PetscSFReduceBegin(sf, unit, w->face_sum, w->face_sum, MPI_SUM));
    PetscCall(PetscSFReduceEnd(sf, unit, w->face_sum, w->face_sum, MPI_SUM));
    PetscCall(PetscSFBcastBegin(sf, unit, w->face_sum, w->face_sum, MPI_REPLACE));
    PetscCall(PetscSFBcastEnd(sf, unit, w->face_sum, w->face_sum, MPI_REPLACE));
    PetscCallMPI(MPI_Type_free(&unit));
  }
  PetscCall(FaceTerms(w, pStart));
  PetscCall(PetscFree(w->face_sum));
  PetscCall(PetscFree(w->face_geom));
  PetscCall(PetscFree(w->load_mean));
  PetscFunctionReturn(PETSC_SUCCESS);
}
