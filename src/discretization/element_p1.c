/* The P1 simplex in closed form: the gradients of its barycentric coordinates, its element stiffness of linear
   elasticity, its vertices in closure order, and K_T u_T on the cells at Gamma_D. Shared by the closed-form assembly
   (assembly_p1.c, assembly_p1_csr.c), the supports' reactions and the Dirichlet lifting (src/physics/) and the estimate's
   geometry (src/estimate/). */
#include <petscbt.h>
#include "mesh.h"
#include "discretization.h"

/* The gradients g[a][d] of the barycentric coordinates (the P1 basis functions) of a simplex with vertices x[(dim+1)*dim],
   and its volume: with J[i][k] = d x_i / d xi_k = x_{k+1,i} - x_{0,i}, grad phi_{k+1} is row k of J^-1 and grad phi_0
   minus the sum of the others. */
PetscErrorCode ElementP1Gradients(PetscInt dim, const PetscReal x[], PetscReal g[][3], PetscReal *volume)
{
  PetscReal J[9], inv[9], det;

  PetscFunctionBeginUser;
  for (PetscInt i = 0; i < dim; ++i)
    for (PetscInt k = 0; k < dim; ++k) J[i * dim + k] = x[(k + 1) * dim + i] - x[i];
  if (dim == 2) {
    det     = J[0] * J[3] - J[1] * J[2];
    inv[0]  = J[3] / det;
    inv[1]  = -J[1] / det;
    inv[2]  = -J[2] / det;
    inv[3]  = J[0] / det;
    *volume = PetscAbsReal(det) / 2.0;
  } else {
    det     = J[0] * (J[4] * J[8] - J[5] * J[7]) - J[1] * (J[3] * J[8] - J[5] * J[6]) + J[2] * (J[3] * J[7] - J[4] * J[6]);
    inv[0]  = (J[4] * J[8] - J[5] * J[7]) / det;
    inv[1]  = (J[2] * J[7] - J[1] * J[8]) / det;
    inv[2]  = (J[1] * J[5] - J[2] * J[4]) / det;
    inv[3]  = (J[5] * J[6] - J[3] * J[8]) / det;
    inv[4]  = (J[0] * J[8] - J[2] * J[6]) / det;
    inv[5]  = (J[2] * J[3] - J[0] * J[5]) / det;
    inv[6]  = (J[3] * J[7] - J[4] * J[6]) / det;
    inv[7]  = (J[1] * J[6] - J[0] * J[7]) / det;
    inv[8]  = (J[0] * J[4] - J[1] * J[3]) / det;
    *volume = PetscAbsReal(det) / 6.0;
  }
  PetscCheck(det != 0.0, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG, "Degenerate cell (zero volume)");
  for (PetscInt d = 0; d < dim; ++d) {
    g[0][d] = 0.0;
    for (PetscInt k = 0; k < dim; ++k) {
      g[k + 1][d] = inv[k * dim + d];
      g[0][d] -= inv[k * dim + d];
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Element stiffness of a P1 simplex with vertices x[(dim+1)*dim], dofs ordered vertex by vertex:
   Ke[(a,c),(b,e)] = |T| (mu (g_a . g_b) delta_ce + mu g_a[e] g_b[c] + lambda g_a[c] g_b[e]), g_a = grad phi_a. */
PetscErrorCode ElementP1Stiffness(PetscInt dim, PetscReal lambda, PetscReal mu, const PetscReal x[], PetscScalar Ke[])
{
  const PetscInt nv = dim + 1, n = nv * dim;
  PetscReal      vol, g[4][3];

  PetscFunctionBeginUser;
  PetscCall(ElementP1Gradients(dim, x, g, &vol));
  for (PetscInt a = 0; a < nv; ++a)
    for (PetscInt b = 0; b < nv; ++b) {
      PetscReal gab = 0.0;

      for (PetscInt d = 0; d < dim; ++d) gab += g[a][d] * g[b][d];
      for (PetscInt c = 0; c < dim; ++c)
        for (PetscInt e = 0; e < dim; ++e)
          Ke[(a * dim + c) * n + b * dim + e] = vol * ((c == e ? mu * gab : 0.0) + mu * g[a][e] * g[b][c] + lambda * g[a][c] * g[b][e]);
    }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The vertices of cell c in closure order: their coordinates x[nv][dim] (from the local coordinates xc laid out by
   csec) and their offsets off[nv] in the local section lsec. */
PetscErrorCode ElementP1CellVertices(MeshClosure *mc, PetscSection csec, PetscSection lsec, const PetscScalar xc[], PetscInt c, PetscReal x[],
                                     PetscInt off[], PetscInt *nv)
{
  const PetscInt dim = mc->dim;
  PetscInt       verts[4];

  PetscFunctionBeginUser;
  PetscCall(MeshClosureVertices(mc, c, 4, nv, verts)); /* a simplex */
  for (PetscInt k = 0; k < *nv; ++k) {
    PetscInt coff;

    PetscCall(PetscSectionGetOffset(csec, verts[k], &coff));
    PetscCall(PetscSectionGetOffset(lsec, verts[k], &off[k]));
    for (PetscInt d = 0; d < dim; ++d) x[k * dim + d] = PetscRealPart(xc[coff + d]);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* locF += K_T u_T on every P1 simplex T that has a fixed component (the cells at Gamma_D), with the closed-form element
   stiffness: the lifting K u_D of the Dirichlet data when locU holds u_D (zero elsewhere), or the fixed rows of K u when it
   holds the free part of u (zero on the fixed components). Only the star of the fixed vertices is visited. */
PetscErrorCode ElementP1AddFixedCellsStiffness(DM dm, const Material *mat, Vec locU, Vec locF)
{
  PetscSection       lsec, csec;
  DM                 cdm;
  Vec                coords;
  PetscInt           dim, vStart, vEnd, cStart, cEnd;
  PetscBT            done;
  MeshClosure        mc;
  const PetscScalar *lu, *xc;
  PetscScalar       *f;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMGetLocalSection(dm, &lsec));
  PetscCall(DMGetCoordinateDM(dm, &cdm));
  PetscCall(DMGetLocalSection(cdm, &csec));
  PetscCall(DMGetCoordinatesLocal(dm, &coords));
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  PetscCall(PetscBTCreate(cEnd - cStart, &done));
  PetscCall(MeshClosureCreate(dm, &mc));
  PetscCall(VecGetArrayRead(locU, &lu));
  PetscCall(VecGetArrayRead(coords, &xc));
  PetscCall(VecGetArray(locF, &f));
  for (PetscInt v = vStart; v < vEnd; ++v) {
    const PetscInt *star;
    PetscInt        nstar, cdof, *cells;

    PetscCall(PetscSectionGetConstraintDof(lsec, v, &cdof));
    if (!cdof) continue;
    PetscCall(MeshClosureGet(&mc, v, PETSC_FALSE, &nstar, &star));
    PetscCall(DMGetWorkArray(dm, nstar, MPIU_INT, &cells)); /* the star's buffer serves the cells' closures below */
    for (PetscInt s = 0; s < nstar; ++s) cells[s] = star[2 * s];
    for (PetscInt s = 0; s < nstar; ++s) {
      const PetscInt c = cells[s];
      PetscInt       nv, off[4];
      PetscReal      x[12];
      PetscScalar    ue[12], Ke[144];

      if (c < cStart || c >= cEnd || PetscBTLookupSet(done, c - cStart)) continue;
      PetscCall(ElementP1CellVertices(&mc, csec, lsec, xc, c, x, off, &nv));
      for (PetscInt a = 0; a < nv; ++a)
        for (PetscInt d = 0; d < dim; ++d) ue[a * dim + d] = lu[off[a] + d];
      PetscCall(ElementP1Stiffness(dim, mat->lambda, mat->mu, x, Ke));
      for (PetscInt i = 0; i < nv * dim; ++i) {
        PetscScalar sum = 0.0;

        for (PetscInt j = 0; j < nv * dim; ++j) sum += Ke[i * nv * dim + j] * ue[j];
        f[off[i / dim] + i % dim] += sum;
      }
    }
    PetscCall(DMRestoreWorkArray(dm, nstar, MPIU_INT, &cells));
  }
  PetscCall(VecRestoreArray(locF, &f));
  PetscCall(VecRestoreArrayRead(coords, &xc));
  PetscCall(VecRestoreArrayRead(locU, &lu));
  PetscCall(PetscBTDestroy(&done));
  PetscCall(MeshClosureDestroy(&mc));
  PetscFunctionReturn(PETSC_SUCCESS);
}
