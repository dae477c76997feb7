/* The boundary conditions of the scene on the mesh: the Dirichlet ones (clamp, slip) as PETSc essential conditions, the
   surface loads (traction, pressure) in the residual of the load, and the checks that the face sets exist, do not
   overlap, and fix every rigid motion. */
#include <petscbt.h>
#include "mesh.h"
#include "physics.h"
#include "discretization.h"

/* u = the constant vector ctx (a clamp's or slip's prescribed displacement; a slip uses its fixed components only). */
static PetscErrorCode ConstantVector(PetscInt dim, PetscReal t, const PetscReal x[], PetscInt Nc, PetscScalar u[], void *ctx)
{
  const PetscReal *v = (const PetscReal *)ctx;

  for (PetscInt c = 0; c < Nc; ++c) u[c] = v[c];
  return PETSC_SUCCESS;
}

/* Residual term of a traction t (constants[CONST_LOAD..]): -t . v. */
static void f0_bd_traction(PetscInt dim, PetscInt Nf, PetscInt NfAux, const PetscInt uOff[], const PetscInt uOff_x[], const PetscScalar u[],
                           const PetscScalar u_t[], const PetscScalar u_x[], const PetscInt aOff[], const PetscInt aOff_x[], const PetscScalar a[],
                           const PetscScalar a_t[], const PetscScalar a_x[], PetscReal t, const PetscReal x[], const PetscReal n[],
                           PetscInt numConstants, const PetscScalar constants[], PetscScalar f0[])
{
  for (PetscInt c = 0; c < dim; ++c) f0[c] = -constants[CONST_LOAD + c];
}

/* Residual term of a pressure p (constants[CONST_LOAD]): the load is -p n with n the outward normal, so +p n . v. */
static void f0_bd_pressure(PetscInt dim, PetscInt Nf, PetscInt NfAux, const PetscInt uOff[], const PetscInt uOff_x[], const PetscScalar u[],
                           const PetscScalar u_t[], const PetscScalar u_x[], const PetscInt aOff[], const PetscInt aOff_x[], const PetscScalar a[],
                           const PetscScalar a_t[], const PetscScalar a_x[], PetscReal t, const PetscReal x[], const PetscReal n[],
                           PetscInt numConstants, const PetscScalar constants[], PetscScalar f0[])
{
  for (PetscInt c = 0; c < dim; ++c) f0[c] = constants[CONST_LOAD] * n[c];
}

/* The clamps and slips as essential conditions, one per face set. PETSc inserts them in this order, the later value
   winning at a node two face sets share: the slips first, then the clamps, so a clamp's value holds at its edge. */
/* The k-th essential condition in that order (k < 2 n: the slips, then the clamps), NULL if the k-th slot holds another
   kind, with its value function and context. */
static PetscErrorCode DirichletInOrder(const Scene *scene, PetscInt k, const BoundaryCondition **bc, ScenePointFn *fn, void **ctx)
{
  const BoundarySet *bcs = &scene->bcs;

  PetscFunctionBeginUser;
  *bc = &bcs->bc[k % bcs->n];
  if ((*bc)->kind != (k < bcs->n ? BC_SLIP : BC_CLAMP))
    *bc = NULL;
  else {
    *fn  = (*bc)->fn ? (*bc)->fn : ConstantVector;
    *ctx = (*bc)->fn ? (void *)scene->constants : (void *)(*bc)->value;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The scene's clamps and slips as essential conditions on their face sets of the label face_sets, in that order. */
PetscErrorCode BoundaryAddDirichlet(DM dm, const Scene *scene, DMLabel face_sets)
{
  PetscFunctionBeginUser;
  for (PetscInt k = 0; k < 2 * scene->bcs.n; ++k) {
    const BoundaryCondition *bc;
    ScenePointFn             fn;
    void                    *ctx;
    char                     name[96];

    PetscCall(DirichletInOrder(scene, k, &bc, &fn, &ctx));
    if (!bc) continue;
    PetscCall(PetscSNPrintf(name, sizeof(name), "%s %s", BoundaryKinds[bc->kind], bc->token));
    PetscCall(DMAddBoundary(dm, DM_BC_ESSENTIAL, name, face_sets, 1, &bc->id, 0, bc->kind == BC_SLIP ? bc->ncomp : 0,
                            bc->kind == BC_SLIP ? bc->comps : NULL, (void (*)(void))fn, NULL, ctx, NULL));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The Dirichlet values into the local vector loc (other entries untouched), as DMPlexInsertBoundaryValues() inserts
   them: face set after face set in the order of BoundaryAddDirichlet(), each writing its fixed components at every
   vertex of its faces' closures. With P1/Q1 displacements (unknowns at the vertices only) this is the value of the
   condition at the vertex, which PETSc's projection computes through each face's reference map (the same up to
   round-off in the position); it avoids that projection's three passes over the cell-type label. Higher
   degrees take DMPlexInsertBoundaryValues(). The scene's conditions on the face sets of face_sets, displacements of this
   degree. */
PetscErrorCode BoundaryInsertDirichlet(DM dm, const Scene *scene, DMLabel face_sets, PetscInt degree, Vec loc)
{
  PetscSection       lsec, csec;
  Vec                coords;
  const PetscScalar *xc;
  PetscScalar       *a;
  MeshClosure        mc;
  PetscInt           dim;

  PetscFunctionBeginUser;
  if (degree != 1) {
    PetscCall(DMPlexInsertBoundaryValues(dm, PETSC_TRUE, loc, 0.0, NULL, NULL, NULL));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMGetLocalSection(dm, &lsec));
  PetscCall(DMGetCoordinateSection(dm, &csec));
  PetscCall(DMGetCoordinatesLocal(dm, &coords));
  PetscCall(MeshClosureCreate(dm, &mc));
  PetscCall(VecGetArrayRead(coords, &xc));
  PetscCall(VecGetArray(loc, &a));
  for (PetscInt k = 0; k < 2 * scene->bcs.n; ++k) {
    const PetscInt           all[3] = {0, 1, 2};
    const BoundaryCondition *bc;
    const PetscInt          *comps, *points;
    ScenePointFn             fn;
    void                    *ctx;
    IS                       is;
    PetscInt                 n, ncomp;

    PetscCall(DirichletInOrder(scene, k, &bc, &fn, &ctx)); /* the order of BoundaryAddDirichlet() */
    if (!bc || !face_sets) continue;
    comps = bc->kind == BC_SLIP ? bc->comps : all;
    ncomp = bc->kind == BC_SLIP ? bc->ncomp : dim;
    PetscCall(DMLabelGetStratumIS(face_sets, bc->id, &is));
    if (!is) continue;
    PetscCall(ISGetLocalSize(is, &n));
    PetscCall(ISGetIndices(is, &points));
    for (PetscInt i = 0; i < n; ++i) {
      const PetscInt *cl;
      PetscInt        ncl;

      PetscCall(MeshClosureGet(&mc, points[i], PETSC_TRUE, &ncl, &cl));
      for (PetscInt j = 0; j < ncl; ++j) {
        const PetscInt v = cl[2 * j];
        PetscInt       off, coff, dof;
        PetscReal      x[3] = {0, 0, 0};
        PetscScalar    u[3];

        if (v < mc.vstart || v >= mc.vend) continue;
        PetscCall(PetscSectionGetDof(lsec, v, &dof));
        if (dof < dim) continue;
        PetscCall(PetscSectionGetOffset(lsec, v, &off));
        PetscCall(PetscSectionGetOffset(csec, v, &coff));
        for (PetscInt d = 0; d < dim; ++d) x[d] = PetscRealPart(xc[coff + d]);
        PetscCall(fn(dim, 0.0, x, dim, u, ctx));
        for (PetscInt c = 0; c < ncomp; ++c) a[off + comps[c]] = u[comps[c]];
      }
    }
    PetscCall(ISRestoreIndices(is, &points));
    PetscCall(ISDestroy(&is));
  }
  PetscCall(VecRestoreArray(loc, &a));
  PetscCall(VecRestoreArrayRead(coords, &xc));
  PetscCall(MeshClosureDestroy(&mc));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Adds the surface loads to the local residual locF: -int t . v on each traction face set and int p n . v on each
   pressure face set of bcs (of the label face_sets), each with its own value in constants[CONST_LOAD..] while it is
   integrated. */
PetscErrorCode BoundaryAddLoadsLocal(DM dm, const BoundarySet *bcs, DMLabel face_sets, Vec locF)
{
  PetscDS            ds;
  PetscWeakForm      wf;
  Vec                locX;
  PetscInt           nc, nloads = 0;
  const PetscScalar *c0;
  PetscScalar        c[CONST_SCENE_MAX];

  PetscFunctionBeginUser;
  for (PetscInt i = 0; i < bcs->n; ++i) nloads += bcs->bc[i].kind == BC_TRACTION || bcs->bc[i].kind == BC_PRESSURE;
  if (!nloads) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(DMGetDS(dm, &ds));
  PetscCall(PetscDSGetConstants(ds, &nc, &c0));
  for (PetscInt k = 0; k < nc; ++k) c[k] = c0[k];
  PetscCall(PetscWeakFormCreate(PetscObjectComm((PetscObject)dm), &wf));
  PetscCall(PetscWeakFormSetNumFields(wf, 1));
  PetscCall(DMGetLocalVector(dm, &locX));
  PetscCall(VecZeroEntries(locX));
  for (PetscInt i = 0; i < bcs->n; ++i) {
    const BoundaryCondition *bc = &bcs->bc[i];
    PetscFormKey             key;

    if (bc->kind != BC_TRACTION && bc->kind != BC_PRESSURE) continue;
    key.label = face_sets;
    key.value = bc->id;
    key.field = 0;
    key.part  = 0;
    PetscCall(PetscWeakFormSetIndexBdResidual(wf, key.label, key.value, 0, 0, 0, bc->kind == BC_TRACTION ? f0_bd_traction : f0_bd_pressure, 0, NULL));
    for (PetscInt k = 0; k < 3; ++k) c[CONST_LOAD + k] = bc->value[k];
    PetscCall(PetscDSSetConstants(ds, nc, c));
    PetscCall(CompatComputeBdResidualSingle(dm, wf, key, locX, locF));
  }
  for (PetscInt k = 0; k < 3; ++k) c[CONST_LOAD + k] = 0.0;
  PetscCall(PetscDSSetConstants(ds, nc, c));
  PetscCall(DMRestoreLocalVector(dm, &locX));
  PetscCall(PetscWeakFormDestroy(&wf));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Adds the surface loads of bcs to the residual at u = 0: the global r0 and, when it exists (not NULL), its local copy
   loc_r0. */
PetscErrorCode BoundaryAddLoads(DM dm, const BoundarySet *bcs, DMLabel face_sets, Vec loc_r0, Vec r0)
{
  Vec locF;

  PetscFunctionBeginUser;
  PetscCall(DMGetLocalVector(dm, &locF));
  PetscCall(VecZeroEntries(locF));
  PetscCall(BoundaryAddLoadsLocal(dm, bcs, face_sets, locF));
  if (loc_r0) PetscCall(VecAXPY(loc_r0, 1.0, locF));
  PetscCall(DMLocalToGlobal(dm, locF, ADD_VALUES, r0));
  PetscCall(DMRestoreLocalVector(dm, &locF));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* locF = loc_r0 + K (u - u_D), exact on the fixed components: the closed-form stiffness of the P1 simplices that have
   a fixed component times the free part of u (zero on the fixed components). Cheap: the cells at Gamma_D only, not
   the whole residual by PetscFE. */
static PetscErrorCode AddFixedRowsP1(DM dm, const Material *mat, Vec loc_r0, Vec u, Vec locF)
{
  Vec locU;

  PetscFunctionBeginUser;
  PetscCall(VecCopy(loc_r0, locF));
  PetscCall(DMGetLocalVector(dm, &locU));
  PetscCall(VecZeroEntries(locU));
  PetscCall(DMGlobalToLocal(dm, u, INSERT_VALUES, locU));
  PetscCall(ElementP1AddFixedCellsStiffness(dm, mat, locU, locF));
  PetscCall(DMRestoreLocalVector(dm, &locU));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The reaction of each clamp and slip face set, the force its support exerts on the body: the sum, over the fixed
   components of the points of its faces, of the residual K u - f (bulk and loads), which the support balances. Each cell adds to the local residual
   of one rank only, so the local sums add up over the ranks. A set's reaction has only the components it fixes: a point on two such face sets (the
   edge between two symmetry planes of a 3D quarter model, x = 0 fixing u_x and y = 0 fixing u_y) gives each component of its residual to the
   first listed set that fixes that component, so that whatever the order the plane x = 0 pushes along x only. A component two sets fix there (a
   clamp and a slip) counts for the first listed. reaction[i][c]: of the i-th boundary condition of bcs (zero for the
   loads). The residual is the problem's (its assembly, loc_r0, loc_bc and face sets) in the material; PetscFE's needs no
   context, its kernels read constants[] alone. */
PetscErrorCode BoundaryComputeReactions(DM dm, const BoundarySet *bcs, const Material *mat, const Problem *prob, Vec u, PetscReal reaction[][3])
{
  MPI_Comm           comm = PetscObjectComm((PetscObject)dm);
  PetscSection       lsec;
  Vec                locX, locF;
  const PetscScalar *f;
  PetscBT            seen;
  PetscInt           pStart, pEnd, dim;
  PetscReal          local[BOUNDARY_MAX][3];

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMGetLocalSection(dm, &lsec));
  PetscCall(PetscSectionGetChart(lsec, &pStart, &pEnd));
  PetscCall(DMGetLocalVector(dm, &locX));
  PetscCall(DMGetLocalVector(dm, &locF));
  if (prob->assembly == ASSEMBLY_P1) /* r0 with its fixed rows, and K (u - u_D) on the cells at a fixed component */
    PetscCall(AddFixedRowsP1(dm, mat, prob->loc_r0, u, locF));
  else { /* the whole residual, by PetscFE */
    PetscCall(VecCopy(prob->loc_bc, locX));
    PetscCall(DMGlobalToLocal(dm, u, INSERT_VALUES, locX));
    PetscCall(VecZeroEntries(locF));
    PetscCall(DMPlexSNESComputeResidualFEM(dm, locX, locF, NULL));
    PetscCall(BoundaryAddLoadsLocal(dm, bcs, prob->face_sets, locF));
  }
  PetscCall(PetscBTCreate(3 * (pEnd - pStart), &seen)); /* a point's component given to a set already */
  PetscCall(VecGetArrayRead(locF, &f));
  for (PetscInt i = 0; i < bcs->n; ++i) {
    PetscInt *faces, nf;

    PetscBool fixes[3] = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE};

    for (PetscInt c = 0; c < 3; ++c) local[i][c] = 0.0;
    if (bcs->bc[i].kind != BC_CLAMP && bcs->bc[i].kind != BC_SLIP) continue;
    for (PetscInt m = 0; m < bcs->bc[i].ncomp; ++m) fixes[bcs->bc[i].comps[m]] = PETSC_TRUE;
    if (bcs->bc[i].kind == BC_CLAMP) fixes[0] = fixes[1] = fixes[2] = PETSC_TRUE;
    PetscCall(MeshGetBoundaryFaces(dm, bcs->bc[i].id, &nf, &faces));
    for (PetscInt k = 0; k < nf; ++k) {
      PetscInt *closure = NULL, ncl;

      PetscCall(DMPlexGetTransitiveClosure(dm, faces[k], PETSC_TRUE, &ncl, &closure));
      for (PetscInt j = 0; j < ncl; ++j) {
        const PetscInt  p = closure[2 * j];
        const PetscInt *cind;
        PetscInt        cdof, off;

        PetscCall(PetscSectionGetConstraintDof(lsec, p, &cdof));
        if (!cdof) continue;
        PetscCall(PetscSectionGetConstraintIndices(lsec, p, &cind));
        PetscCall(PetscSectionGetOffset(lsec, p, &off));
        for (PetscInt m = 0; m < cdof; ++m)
          if (fixes[cind[m]] && !PetscBTLookupSet(seen, 3 * (p - pStart) + cind[m])) local[i][cind[m]] += PetscRealPart(f[off + cind[m]]);
      }
      PetscCall(DMPlexRestoreTransitiveClosure(dm, faces[k], PETSC_TRUE, &ncl, &closure));
    }
    PetscCall(PetscFree(faces));
  }
  PetscCall(VecRestoreArrayRead(locF, &f));
  PetscCall(PetscBTDestroy(&seen));
  PetscCall(DMRestoreLocalVector(dm, &locX));
  PetscCall(DMRestoreLocalVector(dm, &locF));
  PetscCall(MPIU_Allreduce(local, reaction, 3 * bcs->n, MPIU_REAL, MPIU_SUM, comm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static const char *FamilyOption(const BoundarySet *bcs, PetscInt i)
{
  static const char *const options[] = {"-bc_clamp", "-bc_slip", "-bc_traction", "-bc_pressure"};
  return i < bcs->n ? options[bcs->bc[i].kind] : "-contact_faces";
}

/* Every face set named exists on the mesh, and no face carries two face sets of different families. */
PetscErrorCode BoundaryCheckFaceSets(DM dm, const Scene *scene)
{
  MPI_Comm           comm = PetscObjectComm((PetscObject)dm);
  const BoundarySet *bcs  = &scene->bcs;
  const PetscInt     nall = bcs->n + bcs->ncontact;
  PetscInt          *nf, **faces;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc2(nall, &nf, nall, &faces));
  for (PetscInt i = 0; i < nall; ++i) {
    const PetscInt id    = i < bcs->n ? bcs->bc[i].id : bcs->contact_ids[i - bcs->n];
    const char    *token = i < bcs->n ? bcs->bc[i].token : bcs->contact_tokens[i - bcs->n];
    PetscInt       total;

    PetscCall(MeshGetBoundaryFaces(dm, id, &nf[i], &faces[i]));
    PetscCall(PetscSortInt(nf[i], faces[i]));
    PetscCall(MPIU_Allreduce(&nf[i], &total, 1, MPIU_INT, MPI_SUM, comm));
    PetscCheck(total > 0, comm, PETSC_ERR_USER_INPUT, "%s %s: no face of the mesh carries \"Face Sets\" value %" PetscInt_FMT " (scene %s)",
               FamilyOption(bcs, i), token, id, scene->name);
    PetscCall(MeshCountInteriorFaces(dm, nf[i], faces[i], &total));
    PetscCheck(total == 0, comm, PETSC_ERR_USER_INPUT,
               "%s %s: %" PetscInt_FMT " face(s) of face set %" PetscInt_FMT
               " are interior faces, with a cell on each side: a boundary condition or a contact acts on the boundary of the body. Put only "
               "boundary faces in the physical group (Gmsh: a line or surface embedded in the body is interior)",
               FamilyOption(bcs, i), token, total, id);
  }
  for (PetscInt i = 0; i < nall; ++i)
    for (PetscInt j = i + 1; j < nall; ++j) {
      const PetscInt fi = i < bcs->n ? (PetscInt)bcs->bc[i].kind : BC_NUM_KINDS, fj = j < bcs->n ? (PetscInt)bcs->bc[j].kind : BC_NUM_KINDS;
      PetscInt       common = 0, total, a = 0, b = 0;

      if (fi == fj) continue; /* two face sets of one family may share faces */
      while (a < nf[i] && b < nf[j]) {
        if (faces[i][a] == faces[j][b]) {
          ++common;
          ++a;
          ++b;
        } else if (faces[i][a] < faces[j][b])
          ++a;
        else
          ++b;
      }
      PetscCall(MPIU_Allreduce(&common, &total, 1, MPIU_INT, MPI_SUM, comm));
      PetscCheck(total == 0, comm, PETSC_ERR_USER_INPUT,
                 "%" PetscInt_FMT " face(s) of the mesh carry both face set %s (%s) and face set %s (%s): a face belongs to one family", total,
                 i < bcs->n ? bcs->bc[i].token : bcs->contact_tokens[i - bcs->n], FamilyOption(bcs, i),
                 j < bcs->n ? bcs->bc[j].token : bcs->contact_tokens[j - bcs->n], FamilyOption(bcs, j));
    }
  for (PetscInt i = 0; i < nall; ++i) PetscCall(PetscFree(faces[i]));
  PetscCall(PetscFree2(nf, faces));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Eigenvalues w (ascending) and eigenvectors (V[m*n ..], one per row) of the symmetric n x n matrix A (destroyed), by
   cyclic Jacobi rotations: n <= 6 here. */
static void SymmetricEigen(PetscInt n, PetscReal A[], PetscReal w[], PetscReal V[])
{
  for (PetscInt i = 0; i < n * n; ++i) V[i] = (i / n == i % n) ? 1.0 : 0.0;
  for (PetscInt sweep = 0; sweep < 100; ++sweep) {
    PetscReal off = 0.0, total = 0.0;

    for (PetscInt i = 0; i < n; ++i)
      for (PetscInt j = 0; j < n; ++j) {
        total += A[i * n + j] * A[i * n + j];
        if (i != j) off += A[i * n + j] * A[i * n + j];
      }
    if (off <= 1e-30 * total) break;
    for (PetscInt p = 0; p < n; ++p)
      for (PetscInt q = p + 1; q < n; ++q) {
        const PetscReal apq = A[p * n + q];
        PetscReal       theta, t, c, s;

        if (apq == 0.0) continue;
        theta = (A[q * n + q] - A[p * n + p]) / (2.0 * apq);
        t     = (theta >= 0.0 ? 1.0 : -1.0) / (PetscAbsReal(theta) + PetscSqrtReal(theta * theta + 1.0));
        c     = 1.0 / PetscSqrtReal(t * t + 1.0);
        s     = t * c;
        for (PetscInt k = 0; k < n; ++k) { /* A <- A J (columns p, q) */
          const PetscReal akp = A[k * n + p], akq = A[k * n + q];
          A[k * n + p] = c * akp - s * akq;
          A[k * n + q] = s * akp + c * akq;
        }
        for (PetscInt k = 0; k < n; ++k) { /* A <- J^T A (rows p, q) */
          const PetscReal apk = A[p * n + k], aqk = A[q * n + k];
          A[p * n + k] = c * apk - s * aqk;
          A[q * n + k] = s * apk + c * aqk;
        }
        for (PetscInt k = 0; k < n; ++k) { /* the eigenvectors, as rows of V */
          const PetscReal vp = V[p * n + k], vq = V[q * n + k];
          V[p * n + k] = c * vp - s * vq;
          V[q * n + k] = s * vp + c * vq;
        }
      }
  }
  for (PetscInt i = 0; i < n; ++i) w[i] = A[i * n + i];
  for (PetscInt i = 0; i < n; ++i) /* sort ascending, rows of V with them */
    for (PetscInt j = i + 1; j < n; ++j)
      if (w[j] < w[i]) {
        PetscReal t = w[i];
        w[i]        = w[j];
        w[j]        = t;
        for (PetscInt k = 0; k < n; ++k) {
          t            = V[i * n + k];
          V[i * n + k] = V[j * n + k];
          V[j * n + k] = t;
        }
      }
}

/* Refuses a set-up whose Dirichlet conditions leave a rigid motion free: its stiffness matrix is singular, and only the
   contact (whose stiffness is zero until it touches) would hold the body. The rigid motions (translations and
   rotations about the center of the mesh's bounding box, lengths scaled by its size) are evaluated at every fixed
   component; they are all fixed when the Gram matrix of those values has full rank. */
PetscErrorCode BoundaryCheckRigidMotions(DM dm, const Scene *scene)
{
  MPI_Comm     comm = PetscObjectComm((PetscObject)dm);
  PetscSection lsec, gsec;
  PetscInt     dim, nmodes, pStart, pEnd, nfree = 0;
  PetscReal    lo[3], hi[3], center[3] = {0, 0, 0}, size = 0.0, G[36], Gsum[36], w[6], V[36];
  char         which[256] = "";

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  nmodes = dim == 2 ? 3 : 6;
  PetscCall(DMGetBoundingBox(dm, lo, hi));
  for (PetscInt d = 0; d < dim; ++d) {
    center[d] = 0.5 * (lo[d] + hi[d]);
    size      = PetscMax(size, hi[d] - lo[d]);
  }
  PetscCall(DMGetLocalSection(dm, &lsec));
  PetscCall(DMGetGlobalSection(dm, &gsec));
  PetscCall(PetscSectionGetChart(lsec, &pStart, &pEnd));
  for (PetscInt k = 0; k < 36; ++k) G[k] = 0.0;
  for (PetscInt p = pStart; p < pEnd; ++p) {
    const PetscInt *cind;
    PetscInt        cdof, gdof;
    PetscReal       x[3] = {0, 0, 0}, y[3] = {0, 0, 0};

    PetscCall(PetscSectionGetConstraintDof(lsec, p, &cdof));
    PetscCall(PetscSectionGetDof(gsec, p, &gdof));
    if (!cdof || gdof < 0) continue; /* nothing fixed, or owned by another rank */
    PetscCall(PetscSectionGetConstraintIndices(lsec, p, &cind));
    PetscCall(MeshPointPosition(dm, p, x));
    for (PetscInt d = 0; d < dim; ++d) y[d] = (x[d] - center[d]) / size;
    for (PetscInt k = 0; k < cdof; ++k) {
      const PetscInt c = cind[k];
      PetscReal      r[6];

      for (PetscInt m = 0; m < dim; ++m) r[m] = m == c ? 1.0 : 0.0; /* translations */
      if (dim == 2)
        r[2] = c == 0 ? -y[1] : y[0]; /* rotation (-y, x) */
      else {                          /* rotations about x, y, z */
        const PetscReal rx[3] = {0.0, -y[2], y[1]}, ry[3] = {y[2], 0.0, -y[0]}, rz[3] = {-y[1], y[0], 0.0};
        r[3] = rx[c];
        r[4] = ry[c];
        r[5] = rz[c];
      }
      for (PetscInt a = 0; a < nmodes; ++a)
        for (PetscInt b = 0; b < nmodes; ++b) G[a * nmodes + b] += r[a] * r[b];
    }
  }
  PetscCall(MPIU_Allreduce(G, Gsum, 36, MPIU_REAL, MPIU_SUM, comm));
  SymmetricEigen(nmodes, Gsum, w, V);
  for (PetscInt m = 0; m < nmodes; ++m) { /* eigenvalues in ascending order, eigenvector m in V[m * nmodes ..] */
    const char *names2[] = {"translation along x", "translation along y", "rotation"};
    const char *names3[] = {"translation along x", "translation along y", "translation along z",
                            "rotation about x",    "rotation about y",    "rotation about z"};
    PetscInt    dominant = 0;

    if (w[m] > 1e-10 * PetscMax(w[nmodes - 1], 1.0)) break;
    ++nfree;
    for (PetscInt a = 1; a < nmodes; ++a)
      if (PetscAbsReal(V[m * nmodes + a]) > PetscAbsReal(V[m * nmodes + dominant])) dominant = a;
    PetscCall(PetscStrlcat(which, nfree > 1 ? ", " : "", sizeof(which)));
    PetscCall(PetscStrlcat(which, dim == 2 ? names2[dominant] : names3[dominant], sizeof(which)));
  }
  PetscCheck(nfree == 0, comm, PETSC_ERR_USER_INPUT,
             "Scene %s: the Dirichlet conditions leave %" PetscInt_FMT
             " rigid motion(s) free (mostly: %s). The body would be held by the contact "
             "alone, whose stiffness is zero until it touches, so the operator is singular: fix them with -bc_clamp or -bc_slip (a symmetry plane, "
             "a prescribed displacement of the loaded face instead of a load)",
             scene->name, nfree, which);
  PetscFunctionReturn(PETSC_SUCCESS);
}
