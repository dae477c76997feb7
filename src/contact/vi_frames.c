/* The rotated frames of SNESVI (the Contact type vi): SNESVI bounds single unknowns, and the constraint u . n <= g
   acts on one unknown only where n is a coordinate axis. At every other contact node the free components of u are
   written in an orthonormal frame (e_n, t_1, t_2) of their own, e_n along the normal's free part, as Norma.jl does at
   inclined contact nodes:
     u_free = R w_free,  R = [e_n t_1 t_2] orthogonal,  so  u . n = |n_free| w_n + (fixed components) . n,
   and u . n <= g becomes the bound w_n <= (g - fixed . n) / |n_free| on the one unknown w_n.
   Over the whole vector u = Q w with Q block diagonal and orthogonal (Q^-1 = Q^T, the identity away from those nodes).
   The SNES solves for w: F_w(w) = Q^T F(Q w), with the Jacobian Q^T K Q (K is constant: one product per frame set),
   whose near-null space is Q^T times the rigid-body modes. Every norm is the same in both frames, so the tolerances
   mean what they meant. Everything outside the SNES sees u (src/solver/solver.c, SolverIterateDisplacement()).
   A node whose normal's free part lies along one axis keeps that axis (its bound is on that component): a scene whose
   normals are all axes solves exactly as without frames. */
#include "contact_impl.h"

/* The constraint of contact node i as coef * x[dof[i * dim + comp]] <= rhs on the node's own (axis or frame) unknown:
   on an axis, comp the one free component the normal meets and coef the normal's part along it (signed); in a frame,
   comp the node's first free component, whose place holds the frame's normal unknown w_n (FrameOfNode()), and coef
   |n_free|; rotate says whether the node needs a frame; comp = -1 when no free component meets the normal. */
void ViNodeConstraint(const ContactSet *cs, PetscInt dim, PetscInt i, PetscInt *comp, PetscReal *coef, PetscReal *rhs, PetscBool *rotate)
{
  const PetscReal *n     = &cs->normal[i * dim];
  PetscInt         count = 0, first = -1, first_free = -1;
  PetscReal        len2 = 0.0, fixed_n = 0.0;

  for (PetscInt c = 0; c < dim; ++c) {
    if (cs->dof[i * dim + c] < 0) {
      fixed_n += cs->fixed[i * dim + c] * n[c];
      continue;
    }
    if (first_free < 0) first_free = c;
    if (PetscAbsReal(n[c]) <= 1e-12) continue;
    if (first < 0) first = c;
    ++count;
    len2 += n[c] * n[c];
  }
  *comp   = count > 1 ? first_free : first;
  *rotate = (PetscBool)(count > 1);
  *coef   = count > 1 ? PetscSqrtReal(len2) : first >= 0 ? n[first] : 0.0;
  *rhs    = cs->gap[i] - fixed_n;
}

/* R (row-major [3][3], over the node's free components in their order) with column 0 along the normal's free part
   and the other columns completing it to an orthonormal basis. */
static void FrameOfNode(const ContactSet *cs, PetscInt dim, PetscInt i, PetscInt *m, PetscInt slot[3], PetscReal R[9])
{
  PetscReal e[3] = {0, 0, 0}, t[3] = {0, 0, 0}, len = 0.0;

  *m = 0;
  for (PetscInt c = 0; c < dim; ++c)
    if (cs->dof[i * dim + c] >= 0) {
      slot[*m] = cs->dof[i * dim + c];
      e[*m]    = cs->normal[i * dim + c];
      ++(*m);
    }
  for (PetscInt a = 0; a < *m; ++a) len += e[a] * e[a];
  len = PetscSqrtReal(len);
  for (PetscInt a = 0; a < *m; ++a) e[a] /= len;
  for (PetscInt k = 0; k < 9; ++k) R[k] = 0.0;
  for (PetscInt a = 0; a < *m; ++a) R[a * 3 + 0] = e[a];
  if (*m == 2) {
    R[0 * 3 + 1] = -e[1];
    R[1 * 3 + 1] = e[0];
  } else if (*m == 3) {
    PetscInt  k    = 0;
    PetscReal tlen = 0.0;

    for (PetscInt a = 1; a < 3; ++a)
      if (PetscAbsReal(e[a]) < PetscAbsReal(e[k])) k = a; /* the axis farthest from the normal: t_1 from it is well conditioned */
    for (PetscInt a = 0; a < 3; ++a) t[a] = (a == k ? 1.0 : 0.0) - e[k] * e[a];
    for (PetscInt a = 0; a < 3; ++a) tlen += t[a] * t[a];
    tlen = PetscSqrtReal(tlen);
    for (PetscInt a = 0; a < 3; ++a) R[a * 3 + 1] = t[a] / tlen;
    R[0 * 3 + 2] = e[1] * R[2 * 3 + 1] - e[2] * R[1 * 3 + 1]; /* t_2 = e_n x t_1 */
    R[1 * 3 + 2] = e[2] * R[0 * 3 + 1] - e[0] * R[2 * 3 + 1];
    R[2 * 3 + 2] = e[0] * R[1 * 3 + 1] - e[1] * R[0 * 3 + 1];
  }
}

/* Whether any node of any rank needs a frame; if so, the nodes that may carry one (two or more free components) and
   Q's pattern: their full blocks (the identity where the normal is an axis now), so that Q keeps its pattern when a
   load path moves the obstacle and the normals. */
PetscErrorCode ViFramesSetUp(MPI_Comm comm, const ContactSet *cs, PetscInt dim, Vec like, ViFrames *fr)
{
  PetscInt local = 0, nloc, rstart;

  PetscFunctionBeginUser;
  PetscCall(PetscMemzero(fr, sizeof(*fr)));
  for (PetscInt i = 0; i < cs->n; ++i) {
    PetscInt  comp;
    PetscReal coef, rhs;
    PetscBool rotate;

    ViNodeConstraint(cs, dim, i, &comp, &coef, &rhs, &rotate);
    local += rotate;
  }
  PetscCall(MPIU_Allreduce(&local, &fr->nrotated, 1, MPIU_INT, MPI_SUM, comm));
  if (!fr->nrotated) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscMalloc1(cs->n, &fr->node));
  for (PetscInt i = 0; i < cs->n; ++i) {
    PetscInt free_comps = 0;

    for (PetscInt c = 0; c < dim; ++c) free_comps += cs->dof[i * dim + c] >= 0;
    if (free_comps > 1) fr->node[fr->n++] = i;
  }
  PetscCall(PetscMalloc1(9 * fr->n, &fr->R));
  PetscCall(VecGetLocalSize(like, &nloc));
  PetscCall(VecGetOwnershipRange(like, &rstart, NULL));
  PetscCall(MatCreateAIJ(comm, nloc, nloc, PETSC_DETERMINE, PETSC_DETERMINE, dim, NULL, 0, NULL, &fr->Q));
  PetscCall(MatSetOption(fr->Q, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_TRUE));
  for (PetscInt r = rstart; r < rstart + nloc; ++r) PetscCall(MatSetValue(fr->Q, r, r, 1.0, INSERT_VALUES));
  for (PetscInt j = 0; j < fr->n; ++j) { /* the blocks' pattern, zero off the diagonal for now */
    PetscInt  m, slot[3];
    PetscReal R[9];

    FrameOfNode(cs, dim, fr->node[j], &m, slot, R);
    for (PetscInt a = 0; a < m; ++a)
      for (PetscInt b = 0; b < m; ++b)
        if (a != b) PetscCall(MatSetValue(fr->Q, rstart + slot[a], rstart + slot[b], 0.0, INSERT_VALUES));
  }
  PetscCall(MatAssemblyBegin(fr->Q, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(fr->Q, MAT_FINAL_ASSEMBLY));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The frames of the set's current normals, into R and Q (at set-up and after each change of the gaps and normals). */
PetscErrorCode ViFramesUpdate(const ContactSet *cs, PetscInt dim, ViFrames *fr)
{
  PetscInt rstart;

  PetscFunctionBeginUser;
  if (!fr->nrotated) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(MatGetOwnershipRange(fr->Q, &rstart, NULL));
  for (PetscInt j = 0; j < fr->n; ++j) {
    const PetscInt i = fr->node[j];
    PetscInt       m, slot[3], comp;
    PetscReal     *R = &fr->R[9 * j], coef, rhs;
    PetscBool      rotate;

    FrameOfNode(cs, dim, i, &m, slot, R);
    ViNodeConstraint(cs, dim, i, &comp, &coef, &rhs, &rotate);
    if (!rotate) /* an axis, or no normal over the free components: the identity */
      for (PetscInt k = 0; k < 9; ++k) R[k] = k % 4 == 0 ? 1.0 : 0.0;
    for (PetscInt a = 0; a < m; ++a)
      for (PetscInt b = 0; b < m; ++b) PetscCall(MatSetValue(fr->Q, rstart + slot[a], rstart + slot[b], R[a * 3 + b], INSERT_VALUES));
  }
  PetscCall(MatAssemblyBegin(fr->Q, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(fr->Q, MAT_FINAL_ASSEMBLY));
  fr->state++;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* v <- Q^T v (to_solver: from u to w) or v <- Q v (from w to u), node by node in place. */
PetscErrorCode ViFramesApply(const ContactSet *cs, PetscInt dim, const ViFrames *fr, Vec v, PetscBool to_solver)
{
  PetscScalar *x;

  PetscFunctionBeginUser;
  if (!fr->nrotated) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(VecGetArray(v, &x));
  for (PetscInt j = 0; j < fr->n; ++j) {
    const PetscInt   i = fr->node[j];
    const PetscReal *R = &fr->R[9 * j];
    PetscInt         m = 0, slot[3];
    PetscScalar      in[3], out[3] = {0, 0, 0};

    for (PetscInt c = 0; c < dim; ++c)
      if (cs->dof[i * dim + c] >= 0) slot[m++] = cs->dof[i * dim + c];
    for (PetscInt a = 0; a < m; ++a) in[a] = x[slot[a]];
    for (PetscInt a = 0; a < m; ++a)
      for (PetscInt b = 0; b < m; ++b) out[a] += (to_solver ? R[b * 3 + a] : R[a * 3 + b]) * in[b];
    for (PetscInt a = 0; a < m; ++a) x[slot[a]] = out[a];
  }
  PetscCall(VecRestoreArray(v, &x));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Kw = Q^T K Q, made or refreshed for the current frames, with K's near-null space carried into the frames. */
PetscErrorCode ViFramesOperator(const ContactSet *cs, PetscInt dim, ViFrames *fr, Mat K, Mat *Kw)
{
  MatNullSpace nsp;

  PetscFunctionBeginUser;
  PetscCall(MatPtAP(K, fr->Q, *Kw ? MAT_REUSE_MATRIX : MAT_INITIAL_MATRIX, PETSC_DEFAULT, Kw));
  PetscCall(MatGetNearNullSpace(K, &nsp));
  if (nsp) {
    const Vec   *modes;
    Vec         *rotated;
    PetscInt     n;
    PetscBool    has_const;
    MatNullSpace nw;

    PetscCall(MatNullSpaceGetVecs(nsp, &has_const, &n, &modes));
    PetscCall(PetscMalloc1(n, &rotated));
    for (PetscInt k = 0; k < n; ++k) {
      PetscCall(VecDuplicate(modes[k], &rotated[k]));
      PetscCall(VecCopy(modes[k], rotated[k]));
      PetscCall(ViFramesApply(cs, dim, fr, rotated[k], PETSC_TRUE)); /* Q orthogonal: still orthonormal */
    }
    PetscCall(MatNullSpaceCreate(PetscObjectComm((PetscObject)K), has_const, n, rotated, &nw));
    PetscCall(MatSetNearNullSpace(*Kw, nw));
    PetscCall(MatNullSpaceDestroy(&nw));
    for (PetscInt k = 0; k < n; ++k) PetscCall(VecDestroy(&rotated[k]));
    PetscCall(PetscFree(rotated));
  }
  fr->operator_state = fr->state;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode ViFramesDestroy(ViFrames *fr)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree(fr->node));
  PetscCall(PetscFree(fr->R));
  PetscCall(MatDestroy(&fr->Q));
  PetscCall(PetscMemzero(fr, sizeof(*fr)));
  PetscFunctionReturn(PETSC_SUCCESS);
}
