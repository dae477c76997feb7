/* The nodes of Gamma_C: where the contact acts, their gap and their lumped boundary mass. */
#include "mesh.h"
#include "physics.h"

static void f0_bd_one(PetscInt dim, PetscInt Nf, PetscInt NfAux, const PetscInt uOff[], const PetscInt uOff_x[], const PetscScalar u[],
                      const PetscScalar u_t[], const PetscScalar u_x[], const PetscInt aOff[], const PetscInt aOff_x[], const PetscScalar a[],
                      const PetscScalar a_t[], const PetscScalar a_x[], PetscReal t, const PetscReal x[], const PetscReal n[], PetscInt numConstants,
                      const PetscScalar constants[], PetscScalar f0[])
{
  for (PetscInt c = 0; c < dim; ++c) f0[c] = 1.0;
}

/* m_i = integral over Gamma_C of the basis function of node i, in the global vector M. */
static PetscErrorCode ContactLumpedMass(DM dm, AppCtx *user, Vec M)
{
  PetscWeakForm wf;
  PetscFormKey  key;
  Vec           locX, locM;

  PetscFunctionBeginUser;
  PetscCall(PetscWeakFormCreate(PetscObjectComm((PetscObject)dm), &wf));
  PetscCall(PetscWeakFormSetNumFields(wf, 1));
  PetscCall(PetscWeakFormSetIndexBdResidual(wf, user->prob.face_sets, user->scene.contact_id, 0, 0, 0, f0_bd_one, 0, NULL));
  key.label = user->prob.face_sets;
  key.value = user->scene.contact_id;
  key.field = 0;
  key.part  = 0;
  PetscCall(DMGetLocalVector(dm, &locX));
  PetscCall(DMGetLocalVector(dm, &locM));
  PetscCall(VecZeroEntries(locX));
  PetscCall(VecZeroEntries(locM));
  PetscCall(CompatComputeBdResidualSingle(dm, wf, key, locX, locM));
  PetscCall(VecZeroEntries(M));
  PetscCall(DMLocalToGlobal(dm, locM, ADD_VALUES, M));
  PetscCall(DMRestoreLocalVector(dm, &locX));
  PetscCall(DMRestoreLocalVector(dm, &locM));
  PetscCall(PetscWeakFormDestroy(&wf));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Position of a node: the vertex itself, or the centroid of the edge/face that carries it (Lagrange P2/Q2). */
static PetscErrorCode NodePosition(DM dm, PetscInt p, PetscReal x[])
{
  PetscInt depth, cdim;

  PetscFunctionBeginUser;
  PetscCall(DMGetCoordinateDim(dm, &cdim));
  PetscCall(DMPlexGetPointDepth(dm, p, &depth));
  if (depth == 0) {
    DM                 cdm;
    PetscSection       cs;
    Vec                coords;
    PetscInt           off;
    const PetscScalar *a;

    PetscCall(DMGetCoordinateDM(dm, &cdm));
    PetscCall(DMGetLocalSection(cdm, &cs));
    PetscCall(DMGetCoordinatesLocal(dm, &coords));
    PetscCall(PetscSectionGetOffset(cs, p, &off));
    PetscCall(VecGetArrayRead(coords, &a));
    for (PetscInt d = 0; d < cdim; ++d) x[d] = PetscRealPart(a[off + d]);
    PetscCall(VecRestoreArrayRead(coords, &a));
  } else
    PetscCall(DMPlexComputeCellGeometryFVM(dm, p, NULL, x, NULL));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode ContactSetCreate(DM dm, AppCtx *user, ContactSet *cs)
{
  MPI_Comm           comm = PetscObjectComm((PetscObject)dm);
  PetscSection       lsec, gsec;
  PetscInt           dim, npts = 0, *pts = NULL, rstart;
  Vec                M;
  const PetscScalar *m;

  PetscFunctionBeginUser;
  PetscCall(PetscMemzero(cs, sizeof(*cs)));
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMGetLocalSection(dm, &lsec));
  PetscCall(DMGetGlobalSection(dm, &gsec));
  /* A node belongs to Gamma_C if it lies in the closure of a Gamma_C face on some rank; its owner may have no such face
     (the faces around it can all be on the other rank), so the marks are summed into the global vector first. */
  {
    Vec                locI, mark;
    const PetscScalar *ind;
    PetscInt          *faces, nf, pStart, pEnd;

    PetscCall(DMGetLocalVector(dm, &locI));
    PetscCall(DMGetGlobalVector(dm, &mark));
    PetscCall(VecZeroEntries(locI));
    PetscCall(MeshGetBoundaryFaces(dm, user->scene.contact_id, &nf, &faces));
    for (PetscInt i = 0; i < nf; ++i) {
      PetscInt *closure = NULL, ncl;

      PetscCall(DMPlexGetTransitiveClosure(dm, faces[i], PETSC_TRUE, &ncl, &closure));
      for (PetscInt j = 0; j < ncl; ++j) {
        PetscInt dof, off;

        PetscCall(PetscSectionGetDof(lsec, closure[2 * j], &dof));
        PetscCall(PetscSectionGetOffset(lsec, closure[2 * j], &off));
        for (PetscInt d = 0; d < dof; ++d) PetscCall(VecSetValue(locI, off + d, 1.0, INSERT_VALUES));
      }
      PetscCall(DMPlexRestoreTransitiveClosure(dm, faces[i], PETSC_TRUE, &ncl, &closure));
    }
    PetscCall(PetscFree(faces));
    PetscCall(VecAssemblyBegin(locI));
    PetscCall(VecAssemblyEnd(locI));
    PetscCall(VecZeroEntries(mark));
    PetscCall(DMLocalToGlobal(dm, locI, ADD_VALUES, mark));
    PetscCall(VecGetOwnershipRange(mark, &rstart, NULL));
    PetscCall(DMPlexGetChart(dm, &pStart, &pEnd));
    PetscCall(PetscMalloc1(PetscMax(pEnd - pStart, 1), &pts));
    PetscCall(VecGetArrayRead(mark, &ind));
    for (PetscInt p = pStart; p < pEnd; ++p) {
      PetscInt gdof, cdof, goff;

      PetscCall(PetscSectionGetDof(gsec, p, &gdof));
      PetscCall(PetscSectionGetConstraintDof(lsec, p, &cdof));
      if (gdof <= 0 || cdof > 0) continue; /* not owned, no unknowns, or clamped by Gamma_D */
      PetscCall(PetscSectionGetOffset(gsec, p, &goff));
      if (PetscRealPart(ind[goff - rstart]) > 0.0) pts[npts++] = p;
    }
    PetscCall(VecRestoreArrayRead(mark, &ind));
    PetscCall(DMRestoreGlobalVector(dm, &mark));
    PetscCall(DMRestoreLocalVector(dm, &locI));
  }

  PetscCall(DMGetGlobalVector(dm, &M));
  PetscCall(ContactLumpedMass(dm, user, M));
  PetscCall(VecGetOwnershipRange(M, &rstart, NULL));
  PetscCall(VecGetArrayRead(M, &m));
  PetscCall(PetscMalloc3(npts, &cs->point, npts, &cs->global_off, npts, &cs->is_vertex));
  PetscCall(PetscMalloc4(npts, &cs->gap, npts, &cs->weight, npts, &cs->active, npts, &cs->pressure));
  PetscCall(PetscCalloc1(npts, &cs->built_active));
  for (PetscInt i = 0; i < npts; ++i) {
    const PetscInt p = pts[i];
    PetscInt       dof, cdof, gdof, goff, depth;
    PetscReal      x[3] = {0.0, 0.0, 0.0}, xn = 0.0;

    PetscCall(PetscSectionGetDof(lsec, p, &dof));
    PetscCall(PetscSectionGetConstraintDof(lsec, p, &cdof));
    PetscCall(PetscSectionGetDof(gsec, p, &gdof));
    PetscCheck(dof == dim, comm, PETSC_ERR_SUP,
               "Contact needs one node per mesh point on Gamma_C (Lagrange degree 1 or 2); point %" PetscInt_FMT " has %" PetscInt_FMT " dofs", p,
               dof);
    if (cdof > 0 || gdof <= 0) continue; /* clamped by Gamma_D, or owned by another rank */
    PetscCall(PetscSectionGetOffset(gsec, p, &goff));
    PetscCall(DMPlexGetPointDepth(dm, p, &depth));
    PetscCall(NodePosition(dm, p, x));
    for (PetscInt d = 0; d < dim; ++d) xn += x[d] * user->scene.obstacle_normal[d];
    cs->point[cs->n]      = p;
    cs->global_off[cs->n] = goff - rstart;
    cs->is_vertex[cs->n]  = (PetscBool)(depth == 0);
    cs->gap[cs->n]        = user->scene.obstacle_offset - xn;
    cs->weight[cs->n]     = PetscRealPart(m[goff - rstart]);
    cs->active[cs->n]     = PETSC_FALSE;
    cs->pressure[cs->n]   = 0.0;
    cs->n++;
  }
  PetscCall(VecRestoreArrayRead(M, &m));
  PetscCall(DMRestoreGlobalVector(dm, &M));
  PetscCall(PetscFree(pts));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode ContactSetDestroy(ContactSet *cs)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree3(cs->point, cs->global_off, cs->is_vertex));
  PetscCall(PetscFree4(cs->gap, cs->weight, cs->active, cs->pressure));
  PetscCall(PetscFree(cs->built_active));
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
    on = (PetscBool)(user->opt.contact.method != CONTACT_NONE && ContactNodePenetration(user, dim, i, x) > -tol);
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
