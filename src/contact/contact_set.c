/* The nodes of Gamma_C: where the contact acts, their gap and their lumped boundary mass. */
#include <petscsf.h>
#include "contact_impl.h"
#include "mesh.h"

static void f0_bd_one(PetscInt dim, PetscInt Nf, PetscInt NfAux, const PetscInt uOff[], const PetscInt uOff_x[], const PetscScalar u[],
                      const PetscScalar u_t[], const PetscScalar u_x[], const PetscInt aOff[], const PetscInt aOff_x[], const PetscScalar a[],
                      const PetscScalar a_t[], const PetscScalar a_x[], PetscReal t, const PetscReal x[], const PetscReal n[], PetscInt numConstants,
                      const PetscScalar constants[], PetscScalar f0[])
{
  for (PetscInt c = 0; c < dim; ++c) f0[c] = 1.0;
}

/* locF += the boundary residual of the part of wf over every contact face set (Gamma_C may be several). */
PetscErrorCode ContactComputeBdResidual(Contact ct, DM dm, PetscWeakForm wf, PetscInt part, Vec locX, Vec locF)
{
  PetscFunctionBeginUser;
  for (PetscInt i = 0; i < ct->nids; ++i) {
    PetscFormKey key;

    key.label = ct->face_sets;
    key.value = ct->ids[i];
    key.field = 0;
    key.part  = part;
    PetscCall(CompatComputeBdResidualSingle(dm, wf, key, locX, locF));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* m_i = integral over Gamma_C of the basis function of node i, in the global vector M. */
static PetscErrorCode ContactLumpedMass(Contact ct, DM dm, Vec M)
{
  PetscWeakForm wf;
  Vec           locX, locM;

  PetscFunctionBeginUser;
  PetscCall(PetscWeakFormCreate(PetscObjectComm((PetscObject)dm), &wf));
  PetscCall(PetscWeakFormSetNumFields(wf, 1));
  PetscCall(DMGetLocalVector(dm, &locX));
  PetscCall(DMGetLocalVector(dm, &locM));
  PetscCall(VecZeroEntries(locX));
  PetscCall(VecZeroEntries(locM));
  for (PetscInt i = 0; i < ct->nids; ++i) PetscCall(PetscWeakFormSetIndexBdResidual(wf, ct->face_sets, ct->ids[i], 0, 0, 0, f0_bd_one, 0, NULL));
  PetscCall(ContactComputeBdResidual(ct, dm, wf, 0, locX, locM));
  PetscCall(VecZeroEntries(M));
  PetscCall(DMLocalToGlobal(dm, locM, ADD_VALUES, M));
  PetscCall(DMRestoreLocalVector(dm, &locX));
  PetscCall(DMRestoreLocalVector(dm, &locM));
  PetscCall(PetscWeakFormDestroy(&wf));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* eps at a local size h_local over eps at h: (h_local / h)^power (1 for a fixed -penalty_eps or -penalty_eps_local 0). */
PetscReal ContactEpsFactor(Contact ct, PetscReal h_local)
{
  if (ct->opt.eps_fixed > 0.0 || !ct->opt.eps_local || h_local <= 0.0) return 1.0;
  return PetscPowReal(h_local / ct->h, ct->opt.eps_power);
}

/* The nodes of Gamma_C owned by this rank with a free component, and the eps factors of its faces and nodes. */
PetscErrorCode ContactSetBuild(Contact ct, DM dm, Vec like)
{
  ContactSet        *cs   = &ct->set;
  MPI_Comm           comm = PetscObjectComm((PetscObject)dm);
  PetscSection       lsec, gsec;
  PetscInt           dim, npts = 0, *pts = NULL, rstart;
  Vec                M;
  const PetscScalar *m, *hn;
  Vec                H;
  PetscReal          face_range[2] = {PETSC_MAX_REAL, PETSC_MAX_REAL}; /* min and -max of the eps factors of the contact faces */

  PetscFunctionBeginUser;
  PetscCall(PetscMemzero(cs, sizeof(*cs)));
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMGetLocalSection(dm, &lsec));
  PetscCall(DMGetGlobalSection(dm, &gsec));
  /* A node belongs to Gamma_C if it lies in the closure of a Gamma_C face on some rank; its owner may have no such face
     (the faces around it can all be on the other rank), so the marks are summed into the global vector first. */
  {
    Vec                locI, mark, locH;
    PetscScalar       *lh;
    const PetscScalar *ind;
    PetscInt          *faces, nf, pStart, pEnd;

    PetscCall(DMGetLocalVector(dm, &locI));
    PetscCall(VecDuplicate(like, &mark));
    PetscCall(VecZeroEntries(locI));
    PetscCall(DMGetLocalVector(dm, &locH));
    PetscCall(VecZeroEntries(locH));
    PetscCall(VecGetArray(locH, &lh));
    for (PetscInt s = 0; s < ct->nids; ++s) {
      PetscCall(MeshGetBoundaryFaces(dm, ct->ids[s], &nf, &faces));
      for (PetscInt i = 0; i < nf; ++i) {
        PetscInt *closure = NULL, ncl;

        const PetscInt *support;
        PetscReal       diam;

        PetscCall(DMPlexGetSupport(dm, faces[i], &support));
        PetscCall(MeshCellSize(dm, support[0], &diam));
        face_range[0] = PetscMin(face_range[0], ContactEpsFactor(ct, diam));
        face_range[1] = PetscMin(face_range[1], -ContactEpsFactor(ct, diam));
        PetscCall(DMPlexGetTransitiveClosure(dm, faces[i], PETSC_TRUE, &ncl, &closure));
        for (PetscInt j = 0; j < ncl; ++j) {
          PetscInt dof, off;

          PetscCall(PetscSectionGetDof(lsec, closure[2 * j], &dof));
          PetscCall(PetscSectionGetOffset(lsec, closure[2 * j], &off));
          for (PetscInt d = 0; d < dof; ++d) {
            PetscCall(VecSetValue(locI, off + d, 1.0, INSERT_VALUES));
            lh[off + d] = PetscMax(PetscRealPart(lh[off + d]), diam);
          }
        }
        PetscCall(DMPlexRestoreTransitiveClosure(dm, faces[i], PETSC_TRUE, &ncl, &closure));
      }
      PetscCall(PetscFree(faces));
    }
    PetscCall(VecDuplicate(like, &H)); /* the largest cell at each node's contact faces, over all ranks */
    PetscCall(VecZeroEntries(H));
    {
      PetscSF      sf;
      PetscScalar *h;

      PetscCall(DMGetSectionSF(dm, &sf)); /* local to global dofs; DMLocalToGlobal() has no MAX_VALUES */
      PetscCall(VecGetArray(H, &h));
      PetscCall(PetscSFReduceBegin(sf, MPIU_SCALAR, lh, h, MPIU_MAX));
      PetscCall(PetscSFReduceEnd(sf, MPIU_SCALAR, lh, h, MPIU_MAX));
      PetscCall(VecRestoreArray(H, &h));
    }
    PetscCall(VecRestoreArray(locH, &lh));
    PetscCall(DMRestoreLocalVector(dm, &locH));
    PetscCall(VecAssemblyBegin(locI));
    PetscCall(VecAssemblyEnd(locI));
    PetscCall(VecZeroEntries(mark));
    PetscCall(DMLocalToGlobal(dm, locI, ADD_VALUES, mark));
    PetscCall(VecGetOwnershipRange(mark, &rstart, NULL));
    if (ct->degree == 1)
      PetscCall(DMPlexGetDepthStratum(dm, 0, &pStart, &pEnd)); /* P1/Q1: the nodes are the vertices */
    else
      PetscCall(DMPlexGetChart(dm, &pStart, &pEnd));
    PetscCall(PetscMalloc1(PetscMax(pEnd - pStart, 1), &pts));
    PetscCall(VecGetArrayRead(mark, &ind));
    for (PetscInt p = pStart; p < pEnd; ++p) {
      PetscInt gdof, cdof, goff;

      PetscCall(PetscSectionGetDof(gsec, p, &gdof));
      PetscCall(PetscSectionGetConstraintDof(lsec, p, &cdof));
      if (gdof - cdof <= 0) continue; /* not owned (gdof < 0), no unknowns, or every component fixed by clamps or slips */
      PetscCall(PetscSectionGetOffset(gsec, p, &goff));
      if (PetscRealPart(ind[goff - rstart]) > 0.0) pts[npts++] = p;
    }
    PetscCall(VecRestoreArrayRead(mark, &ind));
    PetscCall(VecDestroy(&mark));
    PetscCall(DMRestoreLocalVector(dm, &locI));
  }

  PetscCall(VecDuplicate(like, &M));
  PetscCall(ContactLumpedMass(ct, dm, M));
  PetscCall(VecGetOwnershipRange(M, &rstart, NULL));
  PetscCall(VecGetArrayRead(M, &m));
  PetscCall(VecGetArrayRead(H, &hn));
  PetscCall(PetscMalloc4(npts, &cs->point, npts, &cs->global_off, npts * dim, &cs->dof, npts, &cs->is_vertex));
  PetscCall(PetscMalloc3(npts * dim, &cs->fixed, npts * dim, &cs->normal, npts, &cs->eps_factor));
  PetscCall(PetscMalloc4(npts, &cs->gap, npts, &cs->weight, npts, &cs->active, npts, &cs->pressure));
  PetscCall(PetscCalloc1(npts, &cs->reaction));
  for (PetscInt i = 0; i < npts; ++i) {
    const PetscInt  p    = pts[i];
    const PetscInt *cind = NULL;
    PetscInt        dof, cdof, gdof, goff, depth, k = 0;

    PetscCall(PetscSectionGetDof(lsec, p, &dof));
    PetscCall(PetscSectionGetConstraintDof(lsec, p, &cdof));
    PetscCall(PetscSectionGetDof(gsec, p, &gdof));
    PetscCheck(dof == dim, comm, PETSC_ERR_SUP,
               "Contact needs one node per mesh point on Gamma_C (Lagrange degree 1 or 2); point %" PetscInt_FMT " has %" PetscInt_FMT " dofs", p,
               dof);
    if (gdof - cdof <= 0) continue; /* every component fixed, or owned by another rank */
    if (cdof) PetscCall(PetscSectionGetConstraintIndices(lsec, p, &cind));
    PetscCall(PetscSectionGetOffset(gsec, p, &goff));
    PetscCall(DMPlexGetPointDepth(dm, p, &depth));
    for (PetscInt c = 0; c < dim; ++c) { /* the free components are numbered in order, after the fixed ones are skipped */
      if (k < cdof && cind[k] == c) {
        cs->dof[cs->n * dim + c] = -1;
        ++k;
      } else
        cs->dof[cs->n * dim + c] = goff - rstart + c - k;
      cs->fixed[cs->n * dim + c] = 0.0; /* a fixed component's value: ContactSetUpdateData(), below */
    }
    cs->point[cs->n]      = p;
    cs->global_off[cs->n] = goff - rstart;
    cs->is_vertex[cs->n]  = (PetscBool)(depth == 0);
    cs->eps_factor[cs->n] = ContactEpsFactor(ct, PetscRealPart(hn[goff - rstart]));
    cs->weight[cs->n]     = PetscRealPart(m[goff - rstart]);
    cs->active[cs->n]     = PETSC_FALSE;
    cs->pressure[cs->n]   = 0.0;
    cs->n++;
  }
  PetscCall(VecRestoreArrayRead(H, &hn));
  PetscCall(ContactSetUpdateData(ct, dm)); /* the fixed components' values, the gaps and the normals */
  PetscCall(VecDestroy(&H));
  {
    PetscReal range[2] = {PETSC_MAX_REAL, PETSC_MAX_REAL}, grange[2];

    if (ct->opt.quadrature == PENALTY_QUADRATURE_GAUSS) { /* eps of each face */
      range[0] = face_range[0];
      range[1] = face_range[1];
    } else /* eps of each node */
      for (PetscInt i = 0; i < cs->n; ++i) {
        range[0] = PetscMin(range[0], cs->eps_factor[i]);
        range[1] = PetscMin(range[1], -cs->eps_factor[i]);
      }
    PetscCall(MPIU_Allreduce(range, grange, 2, MPIU_REAL, MPIU_MIN, comm));
    ct->eps_factor_min = grange[0];
    ct->eps_factor_max = -grange[1];
    /* the cells of a uniform mesh differ in diameter by rounding (a 3D Kuhn box by 1e-16): one eps there */
    ct->eps_local = (PetscBool)(ct->eps_factor_max - ct->eps_factor_min > 1e-12 * ct->eps_factor_max);
  }
  PetscCall(VecRestoreArrayRead(M, &m));
  PetscCall(VecDestroy(&M));
  PetscCall(PetscFree(pts));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The set's gaps and normals from the packed obstacle, and the values of its fixed components from loc_bc, as
   ContactSetBuild() computes them: again after the obstacle or the Dirichlet values changed (ContactSetLoad()). */
PetscErrorCode ContactSetUpdateData(Contact ct, DM dm)
{
  ContactSet        *cs  = &ct->set;
  const PetscInt     dim = ct->dim;
  PetscSection       lsec;
  const PetscScalar *bcv;

  PetscFunctionBeginUser;
  PetscCall(DMGetLocalSection(dm, &lsec));
  PetscCall(VecGetArrayRead(ct->loc_bc, &bcv));
  for (PetscInt i = 0; i < cs->n; ++i) {
    PetscInt  loff;
    PetscReal x[3] = {0.0, 0.0, 0.0};

    PetscCall(PetscSectionGetOffset(lsec, cs->point[i], &loff));
    PetscCall(MeshPointPosition(dm, cs->point[i], x));
    for (PetscInt c = 0; c < dim; ++c)
      if (cs->dof[i * dim + c] < 0) cs->fixed[i * dim + c] = PetscRealPart(bcv[loff + c]);
    ObstacleGapNormal(dim, ct->obstacle_packed, x, &cs->normal[i * dim], &cs->gap[i]);
  }
  PetscCall(VecRestoreArrayRead(ct->loc_bc, &bcv));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode ContactSetFree(ContactSet *cs)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree4(cs->point, cs->global_off, cs->dof, cs->is_vertex));
  PetscCall(PetscFree3(cs->fixed, cs->normal, cs->eps_factor));
  PetscCall(PetscFree4(cs->gap, cs->weight, cs->active, cs->pressure));
  PetscCall(PetscFree(cs->reaction));
  cs->n = 0;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A vertex of Gamma_C is active when it penetrates (penalty) or sits on its bound (vi: within tol_scale * 1e-10, tol_scale
   the size of the displacement); no vertex is active without contact. With update, the active flags are stored and the
   vertices that entered and left are counted. */
PetscErrorCode ContactCountActive(Contact ct, Vec X, PetscReal tol_scale, PetscBool update, PetscInt *active, PetscInt *entered, PetscInt *left)
{
  ContactSet        *cs  = &ct->set;
  const PetscReal    tol = ct->has_bounds ? 1e-10 * tol_scale : 0.0;
  const PetscBool    any = (PetscBool)(ct->has_penalty || ct->has_bounds);
  const PetscScalar *x;
  PetscInt           local[3] = {0, 0, 0}, global[3];

  PetscFunctionBeginUser;
  PetscCall(VecGetArrayRead(X, &x));
  for (PetscInt i = 0; i < cs->n; ++i) {
    PetscBool on;

    if (!cs->is_vertex[i]) continue;
    on = (PetscBool)(any && ContactNodePenetration(cs, ct->dim, i, x) > -tol);
    local[0] += on;
    local[1] += on && !cs->active[i];
    local[2] += !on && cs->active[i];
    if (update) cs->active[i] = on;
  }
  PetscCall(VecRestoreArrayRead(X, &x));
  PetscCall(MPIU_Allreduce(local, global, 3, MPIU_INT, MPI_SUM, ct->comm));
  *active = global[0];
  if (entered) *entered = global[1];
  if (left) *left = global[2];
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* An order-independent hash of the penetrating vertices of Gamma_C, the same on any number of ranks. */
PetscErrorCode ContactPenetrationHash(Contact ct, Vec X, PetscInt64 *hash)
{
  const ContactSet  *cs = &ct->set;
  const PetscScalar *x;
  PetscInt           rstart;
  PetscInt64         local = 0;

  PetscFunctionBeginUser;
  PetscCall(VecGetOwnershipRange(X, &rstart, NULL));
  PetscCall(VecGetArrayRead(X, &x));
  for (PetscInt i = 0; i < cs->n; ++i) {
    const unsigned long long g = (unsigned long long)(rstart + cs->global_off[i]);

    if (cs->is_vertex[i] && ContactNodePenetration(cs, ct->dim, i, x) > 0.0)
      local = (PetscInt64)((unsigned long long)local + ((g + 1) * 0x9E3779B97F4A7C15ULL ^ (g << 17)) % 0x7FFFFFFFFFFFULL);
  }
  PetscCall(VecRestoreArrayRead(X, &x));
  PetscCall(MPIU_Allreduce(&local, hash, 1, MPIU_INT64, MPI_SUM, ct->comm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The largest penetration u . n - g over the contact nodes of every rank (0 if none penetrates). */
PetscErrorCode ContactMaxNodePenetration(Contact ct, Vec u, PetscReal *dmax)
{
  const PetscScalar *x;
  PetscReal          pen = 0.0;

  PetscFunctionBeginUser;
  PetscCall(VecGetArrayRead(u, &x));
  for (PetscInt i = 0; i < ct->set.n; ++i) pen = PetscMax(pen, ContactNodePenetration(&ct->set, ct->dim, i, x));
  PetscCall(VecRestoreArrayRead(u, &x));
  PetscCall(MPIU_Allreduce(&pen, dmax, 1, MPIU_REAL, MPIU_MAX, ct->comm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Local solution with the Dirichlet values inserted, for the boundary integrals: the values are copied from the vector
   the problem filled once, not projected again over Gamma_D at every call. */
PetscErrorCode ContactGetLocalSolution(Contact ct, DM dm, Vec X, Vec *locX)
{
  PetscFunctionBeginUser;
  PetscCall(DMGetLocalVector(dm, locX));
  PetscCall(VecCopy(ct->loc_bc, *locX));
  PetscCall(DMGlobalToLocal(dm, X, INSERT_VALUES, *locX));
  PetscFunctionReturn(PETSC_SUCCESS);
}
