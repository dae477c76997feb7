/* The penalty term on Gamma_C: (1/eps) int [u . n - g]_+ v . n and its generalized Jacobian (1/eps) H(u . n - g) n n^T,
   with the obstacle's gap g and normal n at the undeformed position (include/obstacle.h): the Contact type "penalty".
   gauss: the face Gauss rule (the paper's L2 product), in closed form on P1 simplices with -assembly p1
          (penalty_faces.c), otherwise by PetscFE's boundary integration of the same kernels;
   nodal: the same term with the vertex rule, node by node with the lumped boundary mass.
   The Jacobian is made in K itself (bulk_rows.c).
   The Contact type "al", the augmented Lagrangian, is the nodal rule's term with a multiplier lambda >= 0 at each
   contact node: (1/eps)[u . n - g + eps lambda]_+, updated between solves by Uzawa's rule
   lambda <- [lambda + (1/eps)(u . n - g)]_+ (ContactAugment(), driven by -contact_penetration_tol,
   src/drivers/penetration_tol.c) with eps kept. The shift s = eps lambda, a length, is what is stored:
   s <- [u . n - g + s]_+. At a fixed point u . n - g <= 0 wherever lambda > 0 is the pressure, and the penetration
   goes to zero with the updates while eps, and the conditioning, stay at h/E. Only the nodal rule: the Gauss rule's
   points over-constrain P1 (two points a face in 2D for one unknown a node), and Uzawa on them stalled at a largest
   penetration of 4e-5 on the 64 x 64 square where the nodal rule reached 1e-7 (ContactSetFromOptions() refuses it). */
#include "mesh.h"
#include "penalty.h"
#include "penalty_kernels.h"

enum { PENALTY_PART_TERM, PENALTY_PART_ENERGY }; /* parts of the penalty weak form */

typedef struct {
  PetscReal      *shift; /* [set.n]: the type "al": the nodal rule's eps lambda at each contact node (NULL before the first update) */
  PetscWeakForm   wf;    /* the penalty term on Gamma_C, kept out of the bulk weak form (PETSc's integration) */
  PenaltyFaces    faces; /* the same term in closed form (the Gauss rule on P1 simplices with -assembly p1) */
  ContactBulkRows rows;  /* K's own values in the contact rows, while K holds the penalty Jacobian */
} Contact_Penalty;

/* The argument of the nodal rule's [.]_+ at contact node i: u . n - g, plus the augmented Lagrangian's shift. */
static inline PetscReal NodeArgument(const Contact_Penalty *pen, const ContactSet *cs, PetscInt dim, PetscInt i, const PetscScalar x[])
{
  return ContactNodePenetration(cs, dim, i, x) + (pen->shift ? pen->shift[i] : 0.0);
}

/* PETSc integrates the Gauss rule (its boundary integration), or the closed form of penalty_faces.c does. */
static PetscBool UseFE(Contact ct)
{
  return (PetscBool)(ct->assembly != ASSEMBLY_P1);
}

/* The local eps of the Gauss rule: 1 / ContactEpsFactor() of the cell at each contact face, a cellwise constant
   auxiliary field that PETSc hands to the boundary kernels of the penalty weak form (and 1 on every other cell). */
static PetscErrorCode PenaltySetUpLocalEps(Contact ct, DM dm)
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
  for (PetscInt s = 0; s < ct->nids; ++s) {
    PetscInt *faces, nf;

    PetscCall(MeshGetBoundaryFaces(dm, ct->ids[s], &nf, &faces));
    for (PetscInt i = 0; i < nf; ++i) {
      const PetscInt *support;
      PetscInt        off;
      PetscReal       diam;

      PetscCall(DMPlexGetSupport(dm, faces[i], &support));
      PetscCall(MeshCellSize(dm, support[0], &diam));
      PetscCall(PetscSectionGetOffset(sec, support[0], &off));
      a[off] = 1.0 / ContactEpsFactor(ct, diam);
    }
    PetscCall(PetscFree(faces));
  }
  PetscCall(VecRestoreArray(loc_a, &a));
  for (PetscInt s = 0; s < ct->nids; ++s)
    for (PetscInt part = PENALTY_PART_TERM; part <= PENALTY_PART_ENERGY; ++part)
      PetscCall(DMSetAuxiliaryVec(dm, ct->face_sets, ct->ids[s], part, loc_a));
  PetscCall(VecDestroy(&loc_a));
  PetscCall(DMDestroy(&dm_aux));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode ContactSetUp_Penalty(Contact ct, DM dm)
{
  Contact_Penalty *pen = (Contact_Penalty *)ct->data;

  PetscFunctionBeginUser;
  /* a graded mesh: eps varies along Gamma_C; PETSc's boundary integration needs it as an auxiliary field (the closed form
     has its own, penalty_faces.c), which -assembly_check compares with */
  if (ct->opt.quadrature == PENALTY_QUADRATURE_GAUSS && ct->eps_local && (UseFE(ct) || ct->assembly_check)) PetscCall(PenaltySetUpLocalEps(ct, dm));
  PetscCall(PetscWeakFormCreate(ct->comm, &pen->wf));
  PetscCall(PetscWeakFormSetNumFields(pen->wf, 1));
  for (PetscInt i = 0; i < ct->nids; ++i) {
    const PetscInt id = ct->ids[i];

    PetscCall(PetscWeakFormSetIndexBdResidual(pen->wf, ct->face_sets, id, 0, PENALTY_PART_TERM, 0, f0_bd_penalty, 0, NULL));
    PetscCall(PetscWeakFormSetIndexBdResidual(pen->wf, ct->face_sets, id, 0, PENALTY_PART_ENERGY, 0, f0_bd_penalty_energy, 0, NULL));
    PetscCall(PetscWeakFormSetIndexBdJacobian(pen->wf, ct->face_sets, id, 0, 0, PENALTY_PART_TERM, 0, g0_bd_penalty, 0, NULL, 0, NULL, 0, NULL));
  }
  if (ct->opt.quadrature == PENALTY_QUADRATURE_NODAL) {
    PetscInt bad = 0, nbad;

    for (PetscInt i = 0; i < ct->set.n; ++i) bad += ct->set.weight[i] <= 0.0;
    PetscCall(MPIU_Allreduce(&bad, &nbad, 1, MPIU_INT, MPI_SUM, ct->comm));
    PetscCheck(!nbad, ct->comm, PETSC_ERR_USER_INPUT,
               "-penalty_quadrature nodal needs a positive lumped boundary mass at every node of Gamma_C; %" PetscInt_FMT
               " nodes have none (use degree 1 or gauss)",
               nbad);
  }
  PetscCall(PenaltyFacesSetUp(ct, dm, &pen->faces)); /* the closed form of the Gauss rule, with -assembly p1 */
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode ContactReset_Penalty(Contact ct)
{
  Contact_Penalty *pen = (Contact_Penalty *)ct->data;

  PetscFunctionBeginUser;
  PetscCall(PetscWeakFormDestroy(&pen->wf));
  PetscCall(PenaltyFacesDestroy(&pen->faces));
  PetscCall(PetscFree(pen->shift));
  PetscCall(BulkRowsFree(&pen->rows));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The Gauss rule's term (locF) or energy (this rank's part): by PETSc (use_fe) or in closed form. */
static PetscErrorCode GaussTermLocal(Contact ct, DM dm, PetscBool use_fe, Vec X, Vec locF, PetscReal *energy)
{
  Contact_Penalty *pen = (Contact_Penalty *)ct->data;
  Vec              locX;

  PetscFunctionBeginUser;
  PetscCall(ContactGetLocalSolution(ct, dm, X, &locX));
  if (use_fe) {
    PetscCall(VecZeroEntries(locF));
    PetscCall(ContactComputeBdResidual(ct, dm, pen->wf, energy ? PENALTY_PART_ENERGY : PENALTY_PART_TERM, locX, locF));
    if (energy) {
      PetscScalar e;

      PetscCall(VecSum(locF, &e)); /* the entries of a face's energy residual sum to its integral (partition of unity) */
      *energy = PetscRealPart(e);
    }
  } else if (energy)
    PetscCall(PenaltyFacesEnergy(&pen->faces, dm, locX, energy));
  else {
    PetscCall(VecZeroEntries(locF));
    PetscCall(PenaltyFacesResidual(&pen->faces, dm, locX, locF));
  }
  PetscCall(DMRestoreLocalVector(dm, &locX));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* J += the Gauss rule's Jacobian, by PETSc or in closed form. */
static PetscErrorCode GaussJacobian(Contact ct, DM dm, PetscBool use_fe, Vec X, Mat J)
{
  Contact_Penalty *pen = (Contact_Penalty *)ct->data;
  Vec              locX;

  PetscFunctionBeginUser;
  PetscCall(ContactGetLocalSolution(ct, dm, X, &locX));
  if (use_fe)
    PetscCall(CompatComputeBdJacobianSingle(dm, pen->wf, ct->face_sets, ct->nids, ct->ids, locX, J));
  else
    PetscCall(PenaltyFacesJacobian(&pen->faces, dm, locX, J));
  PetscCall(DMRestoreLocalVector(dm, &locX));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode ContactResidual_Penalty(Contact ct, DM dm, Vec X, Vec F)
{
  const ContactSet *cs  = &ct->set;
  const PetscInt    dim = ct->dim;

  PetscFunctionBeginUser;
  if (ct->opt.quadrature == PENALTY_QUADRATURE_GAUSS) {
    Vec locF;

    PetscCall(DMGetLocalVector(dm, &locF));
    PetscCall(GaussTermLocal(ct, dm, UseFE(ct), X, locF, NULL));
    PetscCall(DMLocalToGlobal(dm, locF, ADD_VALUES, F));
    PetscCall(DMRestoreLocalVector(dm, &locF));
  } else {
    const PetscScalar *x;
    PetscScalar       *f;

    PetscCall(VecGetArrayRead(X, &x));
    PetscCall(VecGetArray(F, &f));
    for (PetscInt i = 0; i < cs->n; ++i) {
      const PetscReal d = NodeArgument((Contact_Penalty *)ct->data, cs, dim, i, x);
      if (d <= 0.0) continue;
      for (PetscInt c = 0; c < dim; ++c)
        if (cs->dof[i * dim + c] >= 0) f[cs->dof[i * dim + c]] += cs->weight[i] * d / ContactNodeEps(cs, ct->eps, i) * cs->normal[i * dim + c];
    }
    PetscCall(VecRestoreArray(F, &f));
    PetscCall(VecRestoreArrayRead(X, &x));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Whether the penalty term is active at the same points at X and Y (on every rank): the contact nodes with the nodal
   rule, the Gauss points of the contact faces with the Gauss rule; PETSC_FALSE where the points are PETSc's (the Gauss
   rule without the P1 closed form), which are not looked at. */
static PetscErrorCode ContactSameActivity_Penalty(Contact ct, DM dm, Vec X, Vec Y, PetscBool *same)
{
  Contact_Penalty *pen = (Contact_Penalty *)ct->data;
  const PetscInt   dim = ct->dim;

  PetscFunctionBeginUser;
  *same = PETSC_TRUE;
  if (ct->opt.quadrature == PENALTY_QUADRATURE_GAUSS) {
    Vec locX, locY;

    if (UseFE(ct))
      *same = PETSC_FALSE;
    else {
      PetscCall(ContactGetLocalSolution(ct, dm, X, &locX));
      PetscCall(ContactGetLocalSolution(ct, dm, Y, &locY));
      PetscCall(PenaltyFacesSameActivity(&pen->faces, dm, locX, locY, same));
      PetscCall(DMRestoreLocalVector(dm, &locX));
      PetscCall(DMRestoreLocalVector(dm, &locY));
    }
  } else {
    const ContactSet  *cs = &ct->set;
    const PetscScalar *x, *y;

    PetscCall(VecGetArrayRead(X, &x));
    PetscCall(VecGetArrayRead(Y, &y));
    for (PetscInt i = 0; i < cs->n && *same; ++i)
      *same = (PetscBool)((NodeArgument(pen, cs, dim, i, x) > 0.0) == (NodeArgument(pen, cs, dim, i, y) > 0.0));
    PetscCall(VecRestoreArrayRead(X, &x));
    PetscCall(VecRestoreArrayRead(Y, &y));
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, same, 1, MPIU_BOOL, MPI_LAND, ct->comm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Adds the penalty Jacobian to J (ADD_VALUES); the caller assembles J. */
static PetscErrorCode PenaltyAddJacobian(Contact ct, DM dm, Vec X, Mat J)
{
  const ContactSet *cs  = &ct->set;
  const PetscInt    dim = ct->dim;

  PetscFunctionBeginUser;
  if (ct->opt.quadrature == PENALTY_QUADRATURE_GAUSS) {
    PetscCall(GaussJacobian(ct, dm, UseFE(ct), X, J));
  } else {
    const PetscScalar *x;
    PetscInt           rstart, rows[3];
    PetscScalar        block[9];

    PetscCall(MatGetOwnershipRange(J, &rstart, NULL));
    PetscCall(VecGetArrayRead(X, &x));
    for (PetscInt i = 0; i < cs->n; ++i) {
      PetscInt nfree = 0, comp[3];

      if (NodeArgument((Contact_Penalty *)ct->data, cs, dim, i, x) <= 0.0) continue;
      for (PetscInt c = 0; c < dim; ++c)
        if (cs->dof[i * dim + c] >= 0) {
          comp[nfree]   = c;
          rows[nfree++] = rstart + cs->dof[i * dim + c];
        }
      for (PetscInt a = 0; a < nfree; ++a)
        for (PetscInt b = 0; b < nfree; ++b)
          block[a * nfree + b] = cs->weight[i] / ContactNodeEps(cs, ct->eps, i) * cs->normal[i * dim + comp[a]] * cs->normal[i * dim + comp[b]];
      PetscCall(MatSetValues(J, nfree, rows, nfree, rows, block, ADD_VALUES));
    }
    PetscCall(VecRestoreArrayRead(X, &x));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* P = K + the penalty Jacobian at X. P is K itself (one matrix): K's contact rows are put back and the penalty term
   added; or P is a copy of K (SBAIJ, which has no row access). */
static PetscErrorCode ContactJacobian_Penalty(Contact ct, DM dm, Vec X, Mat K, Mat P)
{
  Contact_Penalty *pen = (Contact_Penalty *)ct->data;

  PetscFunctionBeginUser;
  if (P == K) {
    PetscCall(BulkRowsRestore(&pen->rows, K, MAT_FLUSH_ASSEMBLY)); /* INSERT_VALUES before the ADD_VALUES of the penalty */
    PetscCall(PenaltyAddJacobian(ct, dm, X, K));
    PetscCall(MatAssemblyBegin(K, MAT_FINAL_ASSEMBLY));
    PetscCall(MatAssemblyEnd(K, MAT_FINAL_ASSEMBLY));
    pen->rows.jacobian_in_K = PETSC_TRUE;
  } else {
    PetscCall(MatCopy(K, P, SAME_NONZERO_PATTERN));
    PetscCall(PenaltyAddJacobian(ct, dm, X, P));
    PetscCall(MatAssemblyBegin(P, MAT_FINAL_ASSEMBLY));
    PetscCall(MatAssemblyEnd(P, MAT_FINAL_ASSEMBLY));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode ContactPrepareOperator_Penalty(Contact ct, DM dm, Mat K)
{
  Contact_Penalty *pen = (Contact_Penalty *)ct->data;

  PetscFunctionBeginUser;
  PetscCall(BulkRowsSave(&pen->rows, &ct->set, ct->dim, K));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode ContactBulkMult_Penalty(Contact ct, Mat K, Vec X, Vec R)
{
  Contact_Penalty *pen = (Contact_Penalty *)ct->data;

  PetscFunctionBeginUser;
  PetscCall(BulkRowsMult(&pen->rows, K, X, R));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A new matrix equal to the bulk operator: K referenced, or a copy of K with its own contact rows back; K unchanged. */
static PetscErrorCode ContactBulkOperator_Penalty(Contact ct, Mat K, Mat *Kb)
{
  Contact_Penalty *pen = (Contact_Penalty *)ct->data;

  PetscFunctionBeginUser;
  if (!pen->rows.jacobian_in_K) {
    PetscCall(PetscObjectReference((PetscObject)K));
    *Kb = K;
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  PetscCall(MatDuplicate(K, MAT_COPY_VALUES, Kb));
  {
    ContactBulkRows rows = pen->rows; /* the saved rows written into the copy; the object's flag stays */

    PetscCall(BulkRowsRestore(&rows, *Kb, MAT_FINAL_ASSEMBLY));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* (1/2eps) int [u_n - g]_+^2 with the quadrature of the penalty term. */
static PetscErrorCode ContactEnergy_Penalty(Contact ct, DM dm, Vec X, PetscReal *energy)
{
  const ContactSet *cs  = &ct->set;
  const PetscInt    dim = ct->dim;

  PetscFunctionBeginUser;
  *energy = 0.0;
  if (ct->opt.quadrature == PENALTY_QUADRATURE_GAUSS) {
    Vec       locE;
    PetscReal e;

    /* each face is integrated on one rank only, so the local sums add up to the integral */
    PetscCall(DMGetLocalVector(dm, &locE));
    PetscCall(GaussTermLocal(ct, dm, UseFE(ct), X, locE, &e));
    PetscCall(DMRestoreLocalVector(dm, &locE));
    PetscCall(MPIU_Allreduce(&e, energy, 1, MPIU_REAL, MPIU_SUM, ct->comm));
  } else {
    const PetscScalar *x;
    PetscReal          e = 0.0;

    PetscCall(VecGetArrayRead(X, &x));
    for (PetscInt i = 0; i < cs->n; ++i) {
      const PetscReal d = NodeArgument((Contact_Penalty *)ct->data, cs, dim, i, x);
      if (d > 0.0) e += 0.5 / ContactNodeEps(cs, ct->eps, i) * cs->weight[i] * d * d;
    }
    PetscCall(VecRestoreArrayRead(X, &x));
    PetscCall(MPIU_Allreduce(&e, energy, 1, MPIU_REAL, MPIU_SUM, ct->comm));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* -assembly_check with the Gauss rule in closed form: the penalty residual, Jacobian and energy at X by PETSc's boundary
   integration and in closed form, and their relative differences, printed. */
static PetscErrorCode ContactCheck_Penalty(Contact ct, DM dm, Vec X)
{
  MPI_Comm  comm = ct->comm;
  Vec       Ffe, Fp1, locF;
  Mat       Jfe, Jp1;
  PetscReal e[2], eg[2], nf, nd, jf, jd;

  PetscFunctionBeginUser;
  if (!ct->assembly_check || ct->opt.quadrature != PENALTY_QUADRATURE_GAUSS || UseFE(ct)) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(DMGetLocalVector(dm, &locF));
  PetscCall(DMCreateGlobalVector(dm, &Ffe));
  PetscCall(DMCreateGlobalVector(dm, &Fp1));
  for (PetscInt k = 0; k < 2; ++k) {
    Vec F = k ? Fp1 : Ffe;

    PetscCall(GaussTermLocal(ct, dm, (PetscBool)!k, X, locF, NULL));
    PetscCall(VecZeroEntries(F));
    PetscCall(DMLocalToGlobal(dm, locF, ADD_VALUES, F));
    PetscCall(GaussTermLocal(ct, dm, (PetscBool)!k, X, locF, &e[k]));
  }
  PetscCall(DMRestoreLocalVector(dm, &locF));
  PetscCall(MPIU_Allreduce(e, eg, 2, MPIU_REAL, MPIU_SUM, comm));
  PetscCall(VecNorm(Ffe, NORM_2, &nf));
  PetscCall(VecAXPY(Fp1, -1.0, Ffe));
  PetscCall(VecNorm(Fp1, NORM_2, &nd));
  PetscCall(DMCreateMatrix(dm, &Jfe));
  PetscCall(DMCreateMatrix(dm, &Jp1));
  PetscCall(GaussJacobian(ct, dm, PETSC_TRUE, X, Jfe));
  PetscCall(GaussJacobian(ct, dm, PETSC_FALSE, X, Jp1));
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
static PetscErrorCode ContactActs_Penalty(Contact ct, DM dm, Vec X, PetscBool acts[], PetscReal *dmax)
{
  Contact_Penalty   *pen = (Contact_Penalty *)ct->data;
  const ContactSet  *cs  = &ct->set;
  const PetscInt     dim = ct->dim;
  Vec                P;
  const PetscScalar *p;
  PetscReal          d = -PETSC_MAX_REAL;

  PetscFunctionBeginUser;
  PetscCall(VecDuplicate(X, &P));
  PetscCall(VecZeroEntries(P));
  PetscCall(ContactResidual_Penalty(ct, dm, X, P));
  PetscCall(VecGetArrayRead(P, &p));
  for (PetscInt i = 0; i < cs->n; ++i) {
    PetscReal pn = 0.0;

    for (PetscInt c = 0; c < dim; ++c)
      if (cs->dof[i * dim + c] >= 0) pn += PetscRealPart(p[cs->dof[i * dim + c]]) * cs->normal[i * dim + c];
    acts[i] = (PetscBool)(pn > 0.0);
  }
  PetscCall(VecRestoreArrayRead(P, &p));
  PetscCall(VecDestroy(&P));
  if (ct->opt.quadrature == PENALTY_QUADRATURE_GAUSS && !UseFE(ct)) {
    Vec locX;

    PetscCall(ContactGetLocalSolution(ct, dm, X, &locX));
    PetscCall(PenaltyFacesMaxPenetration(&pen->faces, dm, locX, &d));
    PetscCall(DMRestoreLocalVector(dm, &locX));
  }
  PetscCall(MPIU_Allreduce(&d, dmax, 1, MPIU_REAL, MPIU_MAX, ct->comm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode ContactView_Penalty(Contact ct, PetscViewer viewer)
{
  PetscFunctionBeginUser;
  PetscCall(PetscViewerASCIIPrintf(viewer, " (%s quadrature, eps = %g", PenaltyQuadratures[ct->opt.quadrature], (double)ct->eps));
  if (ct->eps_local)
    PetscCall(PetscViewerASCIIPrintf(viewer, ", local %g to %g", (double)(ct->eps * ct->eps_factor_min), (double)(ct->eps * ct->eps_factor_max)));
  PetscCall(PetscViewerASCIIPrintf(viewer, ")"));
  PetscFunctionReturn(PETSC_SUCCESS);
}

const ContactBulkRows *ContactBulkRowsOf(Contact ct)
{
  return ct->has_penalty ? &((Contact_Penalty *)ct->data)->rows : NULL;
}

/* The round-off of the penalty's gap term in the residual at u, squared: the sum over the penetrating nodes of
   ((1/eps) g w)^2, which is large where the obstacle is far from the origin or the indentation deep. */
PetscErrorCode ContactRoundoffTerm(Contact ct, Vec u, PetscReal *sum_sq)
{
  const ContactSet  *cs = &ct->set;
  const PetscScalar *x;
  PetscReal          gap = 0.0;

  PetscFunctionBeginUser;
  *sum_sq = 0.0;
  if (!ct->has_penalty) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(VecGetArrayRead(u, &x));
  for (PetscInt i = 0; i < cs->n; ++i)
    if (NodeArgument((Contact_Penalty *)ct->data, cs, ct->dim, i, x) > 0.0)
      gap += PetscSqr(cs->weight[i] * cs->gap[i] / ContactNodeEps(cs, ct->eps, i));
  PetscCall(VecRestoreArrayRead(u, &x));
  PetscCall(MPIU_Allreduce(&gap, sum_sq, 1, MPIU_REAL, MPIU_SUM, ct->comm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode ContactCreate_Penalty(Contact ct)
{
  Contact_Penalty *pen;

  PetscFunctionBeginUser;
  PetscCall(PetscNew(&pen));
  ct->data        = pen;
  ct->has_penalty = PETSC_TRUE;
  /* J = K + the penalty's rank-one terms in the contact rows: an earlier J's factorization preconditions CG on the next,
     and an inexact Newton is as accurate; its active set can cycle, and nested iteration starts each box near the next */
  ct->defaults.reuse_factorization = PETSC_TRUE;
  ct->defaults.inexact_newton      = PETSC_TRUE;
  ct->defaults.nested_iteration    = PETSC_TRUE;
  ct->defaults.multigrid           = PETSC_TRUE;
  ct->defaults.active_set_cycles   = PETSC_TRUE;
  ct->ops.setup                    = ContactSetUp_Penalty;
  ct->ops.reset                    = ContactReset_Penalty;
  ct->ops.residual                 = ContactResidual_Penalty;
  ct->ops.jacobian                 = ContactJacobian_Penalty;
  ct->ops.prepare_operator         = ContactPrepareOperator_Penalty;
  ct->ops.bulk_mult                = ContactBulkMult_Penalty;
  ct->ops.bulk_operator            = ContactBulkOperator_Penalty;
  ct->ops.energy                   = ContactEnergy_Penalty;
  ct->ops.acts                     = ContactActs_Penalty;
  ct->ops.same_activity            = ContactSameActivity_Penalty;
  ct->ops.check                    = ContactCheck_Penalty;
  ct->ops.view                     = ContactView_Penalty;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Uzawa's update of the augmented Lagrangian at u: s <- [u . n - g + s]_+ at every contact node (s = eps lambda), made
   if apply; *change: the largest |s_new - s| over the ranks, a length. It bounds the penetration (s_new - s = u . n - g
   wherever that is positive) and the gap where the multiplier pushes (s_new - s = -s where the node left the obstacle
   by more than s): at most d, the penetration is at most d and no node carrying force stands off by more than d. */
static PetscErrorCode ContactAugment_AL(Contact ct, DM dm, Vec X, PetscBool apply, PetscReal *change)
{
  Contact_Penalty   *pen = (Contact_Penalty *)ct->data;
  const PetscScalar *x;
  PetscReal          local = 0.0;

  PetscFunctionBeginUser;
  if (!pen->shift) PetscCall(PetscCalloc1(ct->set.n + 1, &pen->shift));
  PetscCall(VecGetArrayRead(X, &x));
  for (PetscInt i = 0; i < ct->set.n; ++i) {
    const PetscReal next = PetscMax(0.0, NodeArgument(pen, &ct->set, ct->dim, i, x));

    local = PetscMax(local, PetscAbsReal(next - pen->shift[i]));
    if (apply) pen->shift[i] = next;
  }
  PetscCall(VecRestoreArrayRead(X, &x));
  PetscCall(MPIU_Allreduce(&local, change, 1, MPIU_REAL, MPIU_MAX, ct->comm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The multipliers of a zero load: the solution u = 0 holds lambda = 0 at every node (the shifts kept from the last load
   state would push the body off the obstacle, and Uzawa would take them down by a constant factor an update). */
static PetscErrorCode ContactForget_AL(Contact ct)
{
  Contact_Penalty *pen = (Contact_Penalty *)ct->data;

  PetscFunctionBeginUser;
  if (pen->shift) PetscCall(PetscArrayzero(pen->shift, ct->set.n + 1));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode ContactCreate_AL(Contact ct)
{
  PetscFunctionBeginUser;
  PetscCall(ContactCreate_Penalty(ct));
  ct->ops.augment = ContactAugment_AL;
  ct->ops.forget  = ContactForget_AL;
  PetscFunctionReturn(PETSC_SUCCESS);
}
