/* The penalty term on Gamma_C: (1/eps) int [u . n - g]_+ v . n and its generalized Jacobian (1/eps) H(u . n - g) n n^T,
   with the obstacle's gap g and normal n at the undeformed position (include/obstacle.h).
   gauss: the face Gauss rule (the paper's L2 product), in closed form on P1 simplices with -assembly p1
          (src/physics/penalty_faces.c), otherwise by PetscFE's boundary integration of the same kernels;
   nodal: the same term with the vertex rule, node by node with the lumped boundary mass. */
#include "mesh.h"
#include "penalty_kernels.h"
#include "physics.h"

enum { PENALTY_PART_TERM, PENALTY_PART_ENERGY }; /* parts of the penalty weak form */

/* The local eps of the Gauss rule: 1 / ContactEpsFactor() of the cell at each contact face, a cellwise constant
   auxiliary field that PETSc hands to the boundary kernels of the penalty weak form (and 1 on every other cell). */
static PetscErrorCode PenaltySetUpLocalEps(DM dm, AppCtx *user)
{
  MPI_Comm     comm = PetscObjectComm((PetscObject)dm);
  DM           dm_aux;
  PetscFE      fe;
  PetscSection sec;
  Vec          loc_a;
  PetscScalar *a;
  PetscInt     dim;
  PetscBool    simplex;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(DMPlexIsSimplex(dm, &simplex));
  PetscCall(DMClone(dm, &dm_aux));
  PetscCall(PetscFECreateLagrange(comm, dim, 1, simplex, 0, PETSC_DETERMINE, &fe));
  PetscCall(PetscObjectSetName((PetscObject)fe, "inverse_eps_factor"));
  {
    PetscObject disp;

    PetscCall(DMGetField(dm, 0, NULL, &disp));
    PetscCall(PetscFECopyQuadrature((PetscFE)disp, fe)); /* PETSc tabulates both at the same points */
  }
  PetscCall(DMSetField(dm_aux, 0, NULL, (PetscObject)fe));
  PetscCall(PetscFEDestroy(&fe));
  PetscCall(DMCreateDS(dm_aux));
  PetscCall(DMCreateLocalVector(dm_aux, &loc_a));
  PetscCall(VecSet(loc_a, 1.0));
  PetscCall(DMGetLocalSection(dm_aux, &sec));
  PetscCall(VecGetArray(loc_a, &a));
  for (PetscInt s = 0; s < user->scene.bcs.ncontact; ++s) {
    PetscInt *faces, nf;

    PetscCall(MeshGetBoundaryFaces(dm, user->scene.bcs.contact_ids[s], &nf, &faces));
    for (PetscInt i = 0; i < nf; ++i) {
      const PetscInt *support;
      PetscInt        off;
      PetscReal       diam;

      PetscCall(DMPlexGetSupport(dm, faces[i], &support));
      PetscCall(MeshCellDiameter(dm, support[0], &diam));
      PetscCall(PetscSectionGetOffset(sec, support[0], &off));
      a[off] = 1.0 / ContactEpsFactor(user, diam);
    }
    PetscCall(PetscFree(faces));
  }
  PetscCall(VecRestoreArray(loc_a, &a));
  for (PetscInt s = 0; s < user->scene.bcs.ncontact; ++s)
    for (PetscInt part = PENALTY_PART_TERM; part <= PENALTY_PART_ENERGY; ++part)
      PetscCall(DMSetAuxiliaryVec(dm, user->prob.face_sets, user->scene.bcs.contact_ids[s], part, loc_a));
  PetscCall(VecDestroy(&loc_a));
  PetscCall(DMDestroy(&dm_aux));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PenaltySetUp(DM dm, AppCtx *user)
{
  PetscFunctionBeginUser;
  /* a graded mesh: eps varies along Gamma_C; PETSc's boundary integration needs it as an auxiliary field (the closed form
     of the P1 assembly has its own, penalty_faces.c), which -assembly_check compares with */
  if (user->opt.contact.quadrature == PENALTY_QUADRATURE_GAUSS && user->prob.eps_local &&
      (user->prob.assembly != ASSEMBLY_P1 || user->opt.assembly_check))
    PetscCall(PenaltySetUpLocalEps(dm, user));
  PetscCall(PetscWeakFormCreate(PetscObjectComm((PetscObject)dm), &user->prob.wf_penalty));
  PetscCall(PetscWeakFormSetNumFields(user->prob.wf_penalty, 1));
  for (PetscInt i = 0; i < user->scene.bcs.ncontact; ++i) {
    const PetscInt id = user->scene.bcs.contact_ids[i];

    PetscCall(PetscWeakFormSetIndexBdResidual(user->prob.wf_penalty, user->prob.face_sets, id, 0, PENALTY_PART_TERM, 0, f0_bd_penalty, 0, NULL));
    PetscCall(
        PetscWeakFormSetIndexBdResidual(user->prob.wf_penalty, user->prob.face_sets, id, 0, PENALTY_PART_ENERGY, 0, f0_bd_penalty_energy, 0, NULL));
    PetscCall(PetscWeakFormSetIndexBdJacobian(user->prob.wf_penalty, user->prob.face_sets, id, 0, 0, PENALTY_PART_TERM, 0, g0_bd_penalty, 0, NULL, 0,
                                              NULL, 0, NULL));
  }
  if (user->opt.contact.quadrature == PENALTY_QUADRATURE_NODAL) {
    PetscInt bad = 0, nbad;

    for (PetscInt i = 0; i < user->prob.cset.n; ++i) bad += user->prob.cset.weight[i] <= 0.0;
    PetscCall(MPIU_Allreduce(&bad, &nbad, 1, MPIU_INT, MPI_SUM, PetscObjectComm((PetscObject)dm)));
    PetscCheck(!nbad, PetscObjectComm((PetscObject)dm), PETSC_ERR_USER_INPUT,
               "-penalty_quadrature nodal needs a positive lumped boundary mass at every node of Gamma_C; %" PetscInt_FMT
               " nodes have none (use degree 1 or gauss)",
               nbad);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Local solution with the Dirichlet values inserted, for the boundary integrals. The values come from user->prob.loc_bc,
   filled once in PenaltySetUp(): inserting them is a projection over Gamma_D that cost more than the whole boundary
   integral (0.1 s per call at 512x512). */
static PetscErrorCode GetLocalSolution(DM dm, AppCtx *user, Vec X, Vec *locX)
{
  PetscFunctionBeginUser;
  PetscCall(DMGetLocalVector(dm, locX));
  PetscCall(VecCopy(user->prob.loc_bc, *locX));
  PetscCall(DMGlobalToLocal(dm, X, INSERT_VALUES, *locX));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* locF = the local boundary residual of one part of the penalty weak form (Gauss rule), over every contact face set,
   by PETSc's boundary integration. */
static PetscErrorCode ComputePenaltyPartLocal(DM dm, AppCtx *user, PetscInt part, Vec X, Vec locF)
{
  Vec locX;

  PetscFunctionBeginUser;
  PetscCall(GetLocalSolution(dm, user, X, &locX));
  PetscCall(VecZeroEntries(locF));
  PetscCall(ContactComputeBdResidual(dm, user, user->prob.wf_penalty, part, locX, locF));
  PetscCall(DMRestoreLocalVector(dm, &locX));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The Gauss rule's term (locF) or energy (this rank's part): in closed form with the P1 assembly, otherwise by PETSc
   (closed form: use_fe false). */
static PetscErrorCode GaussTermLocal(DM dm, AppCtx *user, PetscBool use_fe, Vec X, Vec locF, PetscReal *energy)
{
  PetscFunctionBeginUser;
  if (use_fe) {
    PetscCall(ComputePenaltyPartLocal(dm, user, energy ? PENALTY_PART_ENERGY : PENALTY_PART_TERM, X, locF));
    if (energy) {
      PetscScalar e;

      PetscCall(VecSum(locF, &e)); /* the entries of a face's energy residual sum to its integral (partition of unity) */
      *energy = PetscRealPart(e);
    }
  } else {
    Vec locX;

    PetscCall(GetLocalSolution(dm, user, X, &locX));
    if (energy)
      PetscCall(PenaltyFacesEnergy(dm, user, locX, energy));
    else {
      PetscCall(VecZeroEntries(locF));
      PetscCall(PenaltyFacesResidual(dm, user, locX, locF));
    }
    PetscCall(DMRestoreLocalVector(dm, &locX));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* J += the Gauss rule's Jacobian, in closed form or by PETSc. */
static PetscErrorCode GaussJacobian(DM dm, AppCtx *user, PetscBool use_fe, Vec X, Mat J)
{
  Vec locX;

  PetscFunctionBeginUser;
  PetscCall(GetLocalSolution(dm, user, X, &locX));
  if (use_fe)
    PetscCall(CompatComputeBdJacobianSingle(dm, user->prob.wf_penalty, user->prob.face_sets, user->scene.bcs.ncontact, user->scene.bcs.contact_ids,
                                            locX, J));
  else
    PetscCall(PenaltyFacesJacobian(dm, user, locX, J));
  PetscCall(DMRestoreLocalVector(dm, &locX));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PenaltyAddResidual(DM dm, AppCtx *user, Vec X, Vec F)
{
  const ContactSet *cs = &user->prob.cset;
  PetscInt          dim;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  if (user->opt.contact.quadrature == PENALTY_QUADRATURE_GAUSS) {
    Vec locF;

    PetscCall(DMGetLocalVector(dm, &locF));
    PetscCall(GaussTermLocal(dm, user, (PetscBool)(user->prob.assembly != ASSEMBLY_P1), X, locF, NULL));
    PetscCall(DMLocalToGlobal(dm, locF, ADD_VALUES, F));
    PetscCall(DMRestoreLocalVector(dm, &locF));
  } else {
    const PetscScalar *x;
    PetscScalar       *f;

    PetscCall(VecGetArrayRead(X, &x));
    PetscCall(VecGetArray(F, &f));
    for (PetscInt i = 0; i < cs->n; ++i) {
      const PetscReal d = ContactNodePenetration(cs, dim, i, x);
      if (d <= 0.0) continue;
      for (PetscInt c = 0; c < dim; ++c)
        if (cs->dof[i * dim + c] >= 0) f[cs->dof[i * dim + c]] += cs->weight[i] * d / ContactNodeEps(cs, user->prob.eps, i) * cs->normal[i * dim + c];
    }
    PetscCall(VecRestoreArray(F, &f));
    PetscCall(VecRestoreArrayRead(X, &x));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Whether the penalty term is active at the same points at X and Y (on every rank): the contact nodes with the nodal
   rule, the Gauss points of the contact faces with the Gauss rule; PETSC_FALSE where the points are PETSc's (the Gauss
   rule without the P1 closed form), which are not looked at. */
PetscErrorCode PenaltySameActivity(DM dm, AppCtx *user, Vec X, Vec Y, PetscBool *same)
{
  PetscInt dim;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  *same = PETSC_TRUE;
  if (user->opt.contact.quadrature == PENALTY_QUADRATURE_GAUSS) {
    Vec locX, locY;

    if (user->prob.assembly != ASSEMBLY_P1)
      *same = PETSC_FALSE;
    else {
      PetscCall(GetLocalSolution(dm, user, X, &locX));
      PetscCall(GetLocalSolution(dm, user, Y, &locY));
      PetscCall(PenaltyFacesSameActivity(dm, user, locX, locY, same));
      PetscCall(DMRestoreLocalVector(dm, &locX));
      PetscCall(DMRestoreLocalVector(dm, &locY));
    }
  } else {
    const ContactSet  *cs = &user->prob.cset;
    const PetscScalar *x, *y;

    PetscCall(VecGetArrayRead(X, &x));
    PetscCall(VecGetArrayRead(Y, &y));
    for (PetscInt i = 0; i < cs->n && *same; ++i)
      *same = (PetscBool)((ContactNodePenetration(cs, dim, i, x) > 0.0) == (ContactNodePenetration(cs, dim, i, y) > 0.0));
    PetscCall(VecRestoreArrayRead(X, &x));
    PetscCall(VecRestoreArrayRead(Y, &y));
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, same, 1, MPIU_BOOL, MPI_LAND, PetscObjectComm((PetscObject)dm)));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Adds the penalty Jacobian to J (ADD_VALUES); the caller assembles J. */
PetscErrorCode PenaltyAddJacobian(DM dm, AppCtx *user, Vec X, Mat J)
{
  const ContactSet *cs = &user->prob.cset;
  PetscInt          dim;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  if (user->opt.contact.quadrature == PENALTY_QUADRATURE_GAUSS) {
    PetscCall(GaussJacobian(dm, user, (PetscBool)(user->prob.assembly != ASSEMBLY_P1), X, J));
  } else {
    const PetscScalar *x;
    PetscInt           rstart, rows[3];
    PetscScalar        block[9];

    PetscCall(MatGetOwnershipRange(J, &rstart, NULL));
    PetscCall(VecGetArrayRead(X, &x));
    for (PetscInt i = 0; i < cs->n; ++i) {
      PetscInt nfree = 0, comp[3];

      if (ContactNodePenetration(cs, dim, i, x) <= 0.0) continue;
      for (PetscInt c = 0; c < dim; ++c)
        if (cs->dof[i * dim + c] >= 0) {
          comp[nfree]   = c;
          rows[nfree++] = rstart + cs->dof[i * dim + c];
        }
      for (PetscInt a = 0; a < nfree; ++a)
        for (PetscInt b = 0; b < nfree; ++b)
          block[a * nfree + b] =
              cs->weight[i] / ContactNodeEps(cs, user->prob.eps, i) * cs->normal[i * dim + comp[a]] * cs->normal[i * dim + comp[b]];
      PetscCall(MatSetValues(J, nfree, rows, nfree, rows, block, ADD_VALUES));
    }
    PetscCall(VecRestoreArrayRead(X, &x));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* (1/2eps) int [u_n - g]_+^2 with the quadrature of the penalty term. */
PetscErrorCode PenaltyEnergy(DM dm, AppCtx *user, Vec X, PetscReal *energy)
{
  const ContactSet *cs = &user->prob.cset;
  PetscInt          dim;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  *energy = 0.0;
  if (user->opt.contact.method != CONTACT_PENALTY) PetscFunctionReturn(PETSC_SUCCESS);
  if (user->opt.contact.quadrature == PENALTY_QUADRATURE_GAUSS) {
    Vec       locE;
    PetscReal e;

    /* each face is integrated on one rank only, so the local sums add up to the integral */
    PetscCall(DMGetLocalVector(dm, &locE));
    PetscCall(GaussTermLocal(dm, user, (PetscBool)(user->prob.assembly != ASSEMBLY_P1), X, locE, &e));
    PetscCall(DMRestoreLocalVector(dm, &locE));
    PetscCall(MPIU_Allreduce(&e, energy, 1, MPIU_REAL, MPIU_SUM, PetscObjectComm((PetscObject)dm)));
  } else {
    const PetscScalar *x;
    PetscReal          e = 0.0;

    PetscCall(VecGetArrayRead(X, &x));
    for (PetscInt i = 0; i < cs->n; ++i) {
      const PetscReal d = ContactNodePenetration(cs, dim, i, x);
      if (d > 0.0) e += 0.5 / ContactNodeEps(cs, user->prob.eps, i) * cs->weight[i] * d * d;
    }
    PetscCall(VecRestoreArrayRead(X, &x));
    PetscCall(MPIU_Allreduce(&e, energy, 1, MPIU_REAL, MPIU_SUM, PetscObjectComm((PetscObject)dm)));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A's values in the rows rows[0 .. n-1] (global numbers, owned), in CSR arrays allocated together (PetscFree3(*ptr,
   *cols, *vals)): row i's columns and values at ptr[i] .. ptr[i + 1] - 1. The contact rows of K here, and those of the
   finest GAMG prolongator (src/solver/pc_reuse.c). */
PetscErrorCode PenaltyCopyRows(Mat A, PetscInt n, const PetscInt rows[], PetscInt **ptr, PetscInt **cols, PetscScalar **vals)
{
  PetscInt nnz = 0;

  PetscFunctionBeginUser;
  for (PetscInt r = 0; r < n; ++r) {
    PetscInt ncols;

    PetscCall(MatGetRow(A, rows[r], &ncols, NULL, NULL));
    nnz += ncols;
    PetscCall(MatRestoreRow(A, rows[r], &ncols, NULL, NULL));
  }
  PetscCall(PetscMalloc3(n + 1, ptr, nnz, cols, nnz, vals));
  (*ptr)[0] = 0;
  for (PetscInt r = 0; r < n; ++r) {
    const PetscInt    *c;
    const PetscScalar *v;
    PetscInt           ncols;

    PetscCall(MatGetRow(A, rows[r], &ncols, &c, &v));
    PetscCall(PetscArraycpy(&(*cols)[(*ptr)[r]], c, ncols));
    PetscCall(PetscArraycpy(&(*vals)[(*ptr)[r]], v, ncols));
    (*ptr)[r + 1] = (*ptr)[r] + ncols;
    PetscCall(MatRestoreRow(A, rows[r], &ncols, &c, &v));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* One matrix for the bulk operator and the penalty Jacobian: J = K + P differs from K only in the rows of the contact
   dofs (P couples contact dofs only), so K's values in those rows are kept (a few hundred rows) and J is made in K
   itself: those rows put back, P added. The residual computes K u with K's own rows there (PenaltyBulkMult()), and
   the uses of K after the solve ask for it through PenaltyBulkOperator(), which puts the rows back when K holds J.
   (A second matrix cost 90 MB at 512 x 512.) */
PetscErrorCode PenaltySaveBulkRows(DM dm, AppCtx *user)
{
  const ContactSet *cs = &user->prob.cset;
  Problem          *pb = &user->prob;
  PetscInt          dim, rstart, n = 0, nnz;

  PetscFunctionBeginUser;
  PetscCall(PenaltyFreeBulkRows(user));
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(MatGetOwnershipRange(pb->K, &rstart, NULL));
  for (PetscInt i = 0; i < cs->n * dim; ++i) n += cs->dof[i] >= 0;
  PetscCall(PetscMalloc1(n, &pb->bulk_rows));
  n = 0;
  for (PetscInt i = 0; i < cs->n * dim; ++i)
    if (cs->dof[i] >= 0) pb->bulk_rows[n++] = rstart + cs->dof[i];
  PetscCall(PenaltyCopyRows(pb->K, n, pb->bulk_rows, &pb->bulk_ptr, &pb->bulk_cols, &pb->bulk_vals));
  nnz = pb->bulk_ptr[n];
  PetscCall(PetscMalloc1(n, &pb->bulk_diag));
  for (PetscInt r = 0; r < n; ++r) { /* the diagonal entry of each row */
    for (pb->bulk_diag[r] = pb->bulk_ptr[r]; pb->bulk_diag[r] < pb->bulk_ptr[r + 1] && pb->bulk_cols[pb->bulk_diag[r]] != pb->bulk_rows[r];
         ++pb->bulk_diag[r]) {
    }
    PetscCheck(pb->bulk_diag[r] < pb->bulk_ptr[r + 1], PETSC_COMM_SELF, PETSC_ERR_PLIB, "K's pattern has no diagonal in contact row %" PetscInt_FMT,
               pb->bulk_rows[r]);
  }
  /* the columns, once each, and a scatter of the displacement there (on any rank) */
  {
    PetscInt *cols, ncols = nnz;
    IS        is;
    Vec       g;

    PetscCall(PetscMalloc1(nnz, &cols));
    PetscCall(PetscArraycpy(cols, pb->bulk_cols, nnz));
    PetscCall(PetscSortRemoveDupsInt(&ncols, cols));
    PetscCall(PetscMalloc1(nnz, &pb->bulk_lcols));
    for (PetscInt k = 0; k < nnz; ++k) PetscCall(PetscFindInt(pb->bulk_cols[k], ncols, cols, &pb->bulk_lcols[k]));
    PetscCall(ISCreateGeneral(PETSC_COMM_SELF, ncols, cols, PETSC_OWN_POINTER, &is));
    PetscCall(VecCreateSeq(PETSC_COMM_SELF, ncols, &pb->bulk_x));
    PetscCall(MatCreateVecs(pb->K, &g, NULL));
    PetscCall(VecScatterCreate(g, is, pb->bulk_x, NULL, &pb->bulk_scatter));
    PetscCall(VecDestroy(&g));
    PetscCall(ISDestroy(&is));
  }
  pb->nbulk_rows    = n;
  pb->jacobian_in_K = PETSC_FALSE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PenaltyFreeBulkRows(AppCtx *user)
{
  Problem *pb = &user->prob;

  PetscFunctionBeginUser;
  PetscCall(PetscFree(pb->bulk_rows));
  PetscCall(PetscFree3(pb->bulk_ptr, pb->bulk_cols, pb->bulk_vals));
  PetscCall(PetscFree(pb->bulk_lcols));
  PetscCall(PetscFree(pb->bulk_diag));
  PetscCall(VecScatterDestroy(&pb->bulk_scatter));
  PetscCall(VecDestroy(&pb->bulk_x));
  pb->nbulk_rows    = 0;
  pb->jacobian_in_K = PETSC_FALSE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* K's own values back in the rows of the contact dofs (collective: every rank holds the same jacobian_in_K). */
static PetscErrorCode PenaltyRestoreBulkRows(AppCtx *user, MatAssemblyType type)
{
  Problem *pb = &user->prob;

  PetscFunctionBeginUser;
  for (PetscInt r = 0; r < pb->nbulk_rows; ++r)
    PetscCall(MatSetValues(pb->K, 1, &pb->bulk_rows[r], pb->bulk_ptr[r + 1] - pb->bulk_ptr[r], &pb->bulk_cols[pb->bulk_ptr[r]],
                           &pb->bulk_vals[pb->bulk_ptr[r]], INSERT_VALUES));
  PetscCall(MatAssemblyBegin(pb->K, type));
  PetscCall(MatAssemblyEnd(pb->K, type));
  pb->jacobian_in_K = PETSC_FALSE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* K becomes the penalty Jacobian at X: its contact rows put back, the penalty term added. */
PetscErrorCode PenaltyJacobianInK(DM dm, AppCtx *user, Vec X)
{
  PetscFunctionBeginUser;
  PetscCall(PenaltyRestoreBulkRows(user, MAT_FLUSH_ASSEMBLY)); /* INSERT_VALUES before the ADD_VALUES of the penalty */
  PetscCall(PenaltyAddJacobian(dm, user, X, user->prob.K));
  PetscCall(MatAssemblyBegin(user->prob.K, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(user->prob.K, MAT_FINAL_ASSEMBLY));
  user->prob.jacobian_in_K = PETSC_TRUE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* K as the bulk elastic operator (its contact rows put back if it holds the penalty Jacobian). */
PetscErrorCode PenaltyBulkOperator(AppCtx *user, Mat *K)
{
  PetscFunctionBeginUser;
  if (user->prob.jacobian_in_K) PetscCall(PenaltyRestoreBulkRows(user, MAT_FINAL_ASSEMBLY));
  *K = user->prob.K;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* R = K X with K the bulk operator, whether K holds the penalty Jacobian or not: the rows of the contact dofs are
   recomputed from K's own values, so that K is not touched (a residual evaluated between a Jacobian and its use, as by
   -snes_test_jacobian or a line search, must leave the Jacobian alone). Exact: no subtraction of the penalty term,
   which at small eps would cancel K's digits. */
PetscErrorCode PenaltyBulkMult(AppCtx *user, Vec X, Vec R)
{
  Problem *pb = &user->prob;

  PetscFunctionBeginUser;
  PetscCall(MatMult(pb->K, X, R));
  if (pb->jacobian_in_K) {
    const PetscScalar *x;
    PetscScalar       *r;
    PetscInt           rstart;

    PetscCall(VecScatterBegin(pb->bulk_scatter, X, pb->bulk_x, INSERT_VALUES, SCATTER_FORWARD));
    PetscCall(VecScatterEnd(pb->bulk_scatter, X, pb->bulk_x, INSERT_VALUES, SCATTER_FORWARD));
    PetscCall(VecGetOwnershipRange(R, &rstart, NULL));
    PetscCall(VecGetArrayRead(pb->bulk_x, &x));
    PetscCall(VecGetArray(R, &r));
    for (PetscInt i = 0; i < pb->nbulk_rows; ++i) {
      PetscScalar sum = 0.0;

      for (PetscInt k = pb->bulk_ptr[i]; k < pb->bulk_ptr[i + 1]; ++k) sum += pb->bulk_vals[k] * x[pb->bulk_lcols[k]];
      r[pb->bulk_rows[i] - rstart] = sum;
    }
    PetscCall(VecRestoreArray(R, &r));
    PetscCall(VecRestoreArrayRead(pb->bulk_x, &x));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* -assembly_check with the Gauss rule: the penalty residual, Jacobian and energy at X by PETSc's boundary integration
   and in closed form, and their relative differences. */
PetscErrorCode PenaltyCheckClosedForm(DM dm, AppCtx *user, Vec X)
{
  MPI_Comm  comm = PetscObjectComm((PetscObject)dm);
  Vec       Ffe, Fp1, locF;
  Mat       Jfe, Jp1;
  PetscReal e[2], eg[2], nf, nd, jf, jd;

  PetscFunctionBeginUser;
  if (user->opt.contact.method != CONTACT_PENALTY || user->opt.contact.quadrature != PENALTY_QUADRATURE_GAUSS || user->prob.assembly != ASSEMBLY_P1)
    PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(DMGetLocalVector(dm, &locF));
  PetscCall(DMCreateGlobalVector(dm, &Ffe));
  PetscCall(DMCreateGlobalVector(dm, &Fp1));
  for (PetscInt k = 0; k < 2; ++k) {
    Vec F = k ? Fp1 : Ffe;

    PetscCall(GaussTermLocal(dm, user, (PetscBool)!k, X, locF, NULL));
    PetscCall(VecZeroEntries(F));
    PetscCall(DMLocalToGlobal(dm, locF, ADD_VALUES, F));
    PetscCall(GaussTermLocal(dm, user, (PetscBool)!k, X, locF, &e[k]));
  }
  PetscCall(DMRestoreLocalVector(dm, &locF));
  PetscCall(MPIU_Allreduce(e, eg, 2, MPIU_REAL, MPIU_SUM, comm));
  PetscCall(VecNorm(Ffe, NORM_2, &nf));
  PetscCall(VecAXPY(Fp1, -1.0, Ffe));
  PetscCall(VecNorm(Fp1, NORM_2, &nd));
  PetscCall(DMCreateMatrix(dm, &Jfe));
  PetscCall(DMCreateMatrix(dm, &Jp1));
  PetscCall(GaussJacobian(dm, user, PETSC_TRUE, X, Jfe));
  PetscCall(GaussJacobian(dm, user, PETSC_FALSE, X, Jp1));
  PetscCall(MatAssemblyBegin(Jfe, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(Jfe, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyBegin(Jp1, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(Jp1, MAT_FINAL_ASSEMBLY));
  PetscCall(MatNorm(Jfe, NORM_FROBENIUS, &jf));
  PetscCall(MatAXPY(Jp1, -1.0, Jfe, SAME_NONZERO_PATTERN));
  PetscCall(MatNorm(Jp1, NORM_FROBENIUS, &jd));
  PetscCall(PetscPrintf(comm,
                        "  penalty check: |F_p1 - F_fe|/|F_fe| = %.3e (|F_fe| = %.3e); ||J_p1 - J_fe||_F/||J_fe||_F = %.3e (%.3e); energy %.15e (p1) "
                        "%.15e (fe)\n",
                        (double)(nf > 0.0 ? nd / nf : nd), (double)nf, (double)(jf > 0.0 ? jd / jf : jd), (double)jf, (double)eg[1], (double)eg[0]));
  PetscCall(VecDestroy(&Ffe));
  PetscCall(VecDestroy(&Fp1));
  PetscCall(MatDestroy(&Jfe));
  PetscCall(MatDestroy(&Jp1));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Where the penalty term acts: acts[i] for each contact node of this rank, its nodal force (the rule's, at X) has a
   positive normal component. With the Gauss rule that is a node of a face with a penetrating Gauss point, with the
   nodal rule a penetrating node. *dmax: the largest penetration at the Gauss points of the P1 closed form over all
   ranks (-PETSC_MAX_REAL with the nodal rule, and where PETSc integrates, whose points are not at hand). */
PetscErrorCode PenaltyRuleActs(DM dm, AppCtx *user, Vec X, PetscBool acts[], PetscReal *dmax)
{
  const ContactSet  *cs = &user->prob.cset;
  Vec                P;
  const PetscScalar *p;
  PetscInt           dim;
  PetscReal          d = -PETSC_MAX_REAL;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(VecDuplicate(X, &P));
  PetscCall(VecZeroEntries(P));
  PetscCall(PenaltyAddResidual(dm, user, X, P));
  PetscCall(VecGetArrayRead(P, &p));
  for (PetscInt i = 0; i < cs->n; ++i) {
    PetscReal pn = 0.0;

    for (PetscInt c = 0; c < dim; ++c)
      if (cs->dof[i * dim + c] >= 0) pn += PetscRealPart(p[cs->dof[i * dim + c]]) * cs->normal[i * dim + c];
    acts[i] = (PetscBool)(pn > 0.0);
  }
  PetscCall(VecRestoreArrayRead(P, &p));
  PetscCall(VecDestroy(&P));
  if (user->opt.contact.quadrature == PENALTY_QUADRATURE_GAUSS && user->prob.assembly == ASSEMBLY_P1) {
    Vec locX;

    PetscCall(GetLocalSolution(dm, user, X, &locX));
    PetscCall(PenaltyFacesMaxPenetration(dm, user, locX, &d));
    PetscCall(DMRestoreLocalVector(dm, &locX));
  }
  PetscCall(MPIU_Allreduce(&d, dmax, 1, MPIU_REAL, MPIU_MAX, PetscObjectComm((PetscObject)dm)));
  PetscFunctionReturn(PETSC_SUCCESS);
}
