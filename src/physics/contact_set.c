/* The nodes of Gamma_C: where the contact acts, their gap and their lumped boundary mass. */
#include <petscsf.h>
#include "mesh.h"
#include "obstacle.h"
#include "physics.h"

static void f0_bd_one(PetscInt dim, PetscInt Nf, PetscInt NfAux, const PetscInt uOff[], const PetscInt uOff_x[], const PetscScalar u[],
                      const PetscScalar u_t[], const PetscScalar u_x[], const PetscInt aOff[], const PetscInt aOff_x[], const PetscScalar a[],
                      const PetscScalar a_t[], const PetscScalar a_x[], PetscReal t, const PetscReal x[], const PetscReal n[], PetscInt numConstants,
                      const PetscScalar constants[], PetscScalar f0[])
{
  for (PetscInt c = 0; c < dim; ++c) f0[c] = 1.0;
}

/* locF += the boundary residual of the part of wf over every contact face set (Gamma_C may be several). */
PetscErrorCode ContactComputeBdResidual(DM dm, const AppCtx *user, PetscWeakForm wf, PetscInt part, Vec locX, Vec locF)
{
  PetscFunctionBeginUser;
  for (PetscInt i = 0; i < user->scene.bcs.ncontact; ++i) {
    PetscFormKey key;

    key.label = user->prob.face_sets;
    key.value = user->scene.bcs.contact_ids[i];
    key.field = 0;
    key.part  = part;
    PetscCall(CompatComputeBdResidualSingle(dm, wf, key, locX, locF));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* m_i = integral over Gamma_C of the basis function of node i, in the global vector M. */
static PetscErrorCode ContactLumpedMass(DM dm, AppCtx *user, Vec M)
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
  for (PetscInt i = 0; i < user->scene.bcs.ncontact; ++i)
    PetscCall(PetscWeakFormSetIndexBdResidual(wf, user->prob.face_sets, user->scene.bcs.contact_ids[i], 0, 0, 0, f0_bd_one, 0, NULL));
  PetscCall(ContactComputeBdResidual(dm, user, wf, 0, locX, locM));
  PetscCall(VecZeroEntries(M));
  PetscCall(DMLocalToGlobal(dm, locM, ADD_VALUES, M));
  PetscCall(DMRestoreLocalVector(dm, &locX));
  PetscCall(DMRestoreLocalVector(dm, &locM));
  PetscCall(PetscWeakFormDestroy(&wf));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* eps at a local size h_local over eps at h: (h_local / h)^power (1 for a fixed -penalty_eps or -penalty_eps_local 0). */
PetscReal ContactEpsFactor(const AppCtx *user, PetscReal h_local)
{
  if (user->opt.contact.eps_fixed > 0.0 || !user->opt.contact.eps_local || h_local <= 0.0) return 1.0;
  return PetscPowReal(h_local / user->prob.h, user->opt.contact.eps_power);
}

PetscErrorCode ContactSetCreate(DM dm, AppCtx *user, ContactSet *cs)
{
  MPI_Comm           comm = PetscObjectComm((PetscObject)dm);
  PetscSection       lsec, gsec;
  PetscInt           dim, npts = 0, *pts = NULL, rstart;
  Vec                M;
  const PetscScalar *m, *bcv, *hn;
  Vec                H;
  PetscScalar        obstacle[OBSTACLE_NUM_PARAMS];
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
    PetscCall(VecDuplicate(user->prob.r0, &mark));
    PetscCall(VecZeroEntries(locI));
    PetscCall(DMGetLocalVector(dm, &locH));
    PetscCall(VecZeroEntries(locH));
    PetscCall(VecGetArray(locH, &lh));
    for (PetscInt s = 0; s < user->scene.bcs.ncontact; ++s) {
      PetscCall(MeshGetBoundaryFaces(dm, user->scene.bcs.contact_ids[s], &nf, &faces));
      for (PetscInt i = 0; i < nf; ++i) {
        PetscInt *closure = NULL, ncl;

        const PetscInt *support;
        PetscReal       diam;

        PetscCall(DMPlexGetSupport(dm, faces[i], &support));
        PetscCall(MeshCellDiameter(dm, support[0], &diam));
        face_range[0] = PetscMin(face_range[0], ContactEpsFactor(user, diam));
        face_range[1] = PetscMin(face_range[1], -ContactEpsFactor(user, diam));
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
    PetscCall(VecDuplicate(user->prob.r0, &H)); /* the largest cell at each node's contact faces, over all ranks */
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
    if (user->opt.degree == 1)
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

  PetscCall(VecDuplicate(user->prob.r0, &M));
  PetscCall(ContactLumpedMass(dm, user, M));
  PetscCall(VecGetOwnershipRange(M, &rstart, NULL));
  PetscCall(VecGetArrayRead(M, &m));
  ObstaclePack(&user->scene.obstacle, obstacle);
  PetscCall(VecGetArrayRead(H, &hn));
  PetscCall(VecGetArrayRead(user->prob.loc_bc, &bcv));
  PetscCall(PetscMalloc4(npts, &cs->point, npts, &cs->global_off, npts * dim, &cs->dof, npts, &cs->is_vertex));
  PetscCall(PetscMalloc3(npts * dim, &cs->fixed, npts * dim, &cs->normal, npts, &cs->eps_factor));
  PetscCall(PetscMalloc4(npts, &cs->gap, npts, &cs->weight, npts, &cs->active, npts, &cs->pressure));
  PetscCall(PetscCalloc1(npts, &cs->built_active));
  PetscCall(PetscCalloc1(npts, &cs->reaction));
  for (PetscInt i = 0; i < npts; ++i) {
    const PetscInt  p    = pts[i];
    const PetscInt *cind = NULL;
    PetscInt        dof, cdof, gdof, goff, loff, depth, k = 0;
    PetscReal       x[3] = {0.0, 0.0, 0.0};

    PetscCall(PetscSectionGetDof(lsec, p, &dof));
    PetscCall(PetscSectionGetConstraintDof(lsec, p, &cdof));
    PetscCall(PetscSectionGetDof(gsec, p, &gdof));
    PetscCheck(dof == dim, comm, PETSC_ERR_SUP,
               "Contact needs one node per mesh point on Gamma_C (Lagrange degree 1 or 2); point %" PetscInt_FMT " has %" PetscInt_FMT " dofs", p,
               dof);
    if (gdof - cdof <= 0) continue; /* every component fixed, or owned by another rank */
    if (cdof) PetscCall(PetscSectionGetConstraintIndices(lsec, p, &cind));
    PetscCall(PetscSectionGetOffset(gsec, p, &goff));
    PetscCall(PetscSectionGetOffset(lsec, p, &loff));
    PetscCall(DMPlexGetPointDepth(dm, p, &depth));
    PetscCall(MeshPointPosition(dm, p, x));
    for (PetscInt c = 0; c < dim; ++c) { /* the free components are numbered in order, after the fixed ones are skipped */
      if (k < cdof && cind[k] == c) {
        cs->dof[cs->n * dim + c]   = -1;
        cs->fixed[cs->n * dim + c] = PetscRealPart(bcv[loff + c]);
        ++k;
      } else {
        cs->dof[cs->n * dim + c]   = goff - rstart + c - k;
        cs->fixed[cs->n * dim + c] = 0.0;
      }
    }
    ObstacleGapNormal(dim, obstacle, x, &cs->normal[cs->n * dim], &cs->gap[cs->n]);
    cs->point[cs->n]      = p;
    cs->global_off[cs->n] = goff - rstart;
    cs->is_vertex[cs->n]  = (PetscBool)(depth == 0);
    cs->eps_factor[cs->n] = ContactEpsFactor(user, PetscRealPart(hn[goff - rstart]));
    cs->weight[cs->n]     = PetscRealPart(m[goff - rstart]);
    cs->active[cs->n]     = PETSC_FALSE;
    cs->pressure[cs->n]   = 0.0;
    cs->n++;
  }
  PetscCall(VecRestoreArrayRead(user->prob.loc_bc, &bcv));
  PetscCall(VecRestoreArrayRead(H, &hn));
  PetscCall(VecDestroy(&H));
  {
    PetscReal range[2] = {PETSC_MAX_REAL, PETSC_MAX_REAL}, grange[2];

    if (user->opt.contact.quadrature == PENALTY_QUADRATURE_GAUSS) { /* eps of each face */
      range[0] = face_range[0];
      range[1] = face_range[1];
    } else /* eps of each node */
      for (PetscInt i = 0; i < cs->n; ++i) {
        range[0] = PetscMin(range[0], cs->eps_factor[i]);
        range[1] = PetscMin(range[1], -cs->eps_factor[i]);
      }
    PetscCall(MPIU_Allreduce(range, grange, 2, MPIU_REAL, MPIU_MIN, comm));
    user->prob.eps_factor_min = grange[0];
    user->prob.eps_factor_max = -grange[1];
    /* the cells of a uniform mesh differ in diameter by rounding (a 3D Kuhn box by 1e-16): one eps there */
    user->prob.eps_local = (PetscBool)(user->prob.eps_factor_max - user->prob.eps_factor_min > 1e-12 * user->prob.eps_factor_max);
  }
  PetscCall(VecRestoreArrayRead(M, &m));
  PetscCall(VecDestroy(&M));
  PetscCall(PetscFree(pts));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode ContactSetDestroy(ContactSet *cs)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree4(cs->point, cs->global_off, cs->dof, cs->is_vertex));
  PetscCall(PetscFree3(cs->fixed, cs->normal, cs->eps_factor));
  PetscCall(PetscFree4(cs->gap, cs->weight, cs->active, cs->pressure));
  PetscCall(PetscFree(cs->built_active));
  PetscCall(PetscFree(cs->reaction));
  cs->n = 0;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A vertex of Gamma_C is active when it penetrates (penalty) or sits on its bound (vi).
   With update, the active flags are stored and the vertices that entered and left are counted. */
PetscErrorCode ContactCountActive(AppCtx *user, Vec X, PetscBool update, PetscInt *active, PetscInt *entered, PetscInt *left)
{
  const PetscReal    tol = user->opt.contact.method == CONTACT_VI ? 1e-10 * user->prob.displacement_scale : 0.0; /* on the bound, for vi */
  const PetscScalar *x;
  PetscInt           dim, local[3] = {0, 0, 0}, global[3];
  DM                 dm;

  PetscFunctionBeginUser;
  PetscCall(VecGetDM(X, &dm));
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(VecGetArrayRead(X, &x));
  for (PetscInt i = 0; i < user->prob.cset.n; ++i) {
    PetscBool on;

    if (!user->prob.cset.is_vertex[i]) continue;
    on = (PetscBool)(user->opt.contact.method != CONTACT_NONE && ContactNodePenetration(&user->prob.cset, dim, i, x) > -tol);
    local[0] += on;
    local[1] += on && !user->prob.cset.active[i];
    local[2] += !on && user->prob.cset.active[i];
    if (update) user->prob.cset.active[i] = on;
  }
  PetscCall(VecRestoreArrayRead(X, &x));
  PetscCall(MPIU_Allreduce(local, global, 3, MPIU_INT, MPI_SUM, PetscObjectComm((PetscObject)dm)));
  *active = global[0];
  if (entered) *entered = global[1];
  if (left) *left = global[2];
  PetscFunctionReturn(PETSC_SUCCESS);
}
