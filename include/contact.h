/* The contact treatment on Gamma_C as one object with registered types, in the manner of PETSc's KSP and PC
   (src/contact/): -contact_method picks the type by name, and a new method is one file that registers itself.

   Types:
     penalty  (1/eps) int [u . n - g]_+ v . n, with the Gauss rule (the paper's L2 product) or the nodal rule
              (-penalty_quadrature), eps = eps0 h^power / M (Chouly & Hild 2013, eps = h in Corollary 3.3);
     al       the penalty term with a multiplier at each point of its rule, (1/eps)[u . n - g + eps lambda]_+, lambda
              updated by Uzawa's rule between solves until -contact_penetration_tol is met (the augmented Lagrangian);
     vi       the exact constraint u . n <= g as bounds of SNESVI, the reference for the penalty;
     none     no contact: the linear elastic problem.

   The object owns what the contact needs on one mesh: the contact set (the nodes of Gamma_C, their gaps, normals and
   lumped masses), eps with its local factors, the penalty's faces and weak form, the rows of K that the penalty
   Jacobian changes, and the SNESVI bounds. It is created and read from the options once, set up on each mesh of the
   run (ContactSetUp()), reset when the mesh changes, destroyed at the end. */
#pragma once
#include "signorini.h"

typedef const char *ContactType;
#define CONTACTPENALTY "penalty"
#define CONTACTAL "al"
#define CONTACTVI "vi"
#define CONTACTNONE "none"

/* What the contact needs of the problem on one mesh, given to ContactSetUp() (read during the call; loc_bc is kept
   with a reference). */
typedef struct {
  const BoundarySet *bcs;            /* Gamma_C: the face sets of -contact_faces */
  const Obstacle    *obstacle;       /* the rigid obstacle */
  const Material    *material;       /* M of eps = eps0 h^power / M */
  PetscInt           degree;         /* of the displacement */
  PetscReal          h;              /* the largest cell diameter of the mesh */
  AssemblyType       assembly;       /* how K is assembled on this mesh (fe or p1): p1 with the Gauss rule is its closed form */
  PetscBool          assembly_check; /* -assembly_check: the closed form compared with PETSc's integration */
  Vec                loc_bc;         /* local vector of the Dirichlet values, zero elsewhere */
  Vec                like;           /* a global vector of the mesh */
} ContactProblem;

/* The contact quantities after a solve (ContactPostProcess()), summed over the ranks. */
typedef struct {
  PetscReal max_penetration; /* over the nodes and the rule's points */
  PetscReal force;           /* the obstacle's normal force, the sum of the nodal reactions */
  PetscReal force_vector[3]; /* the obstacle's force on the body: the sum of R = K u + r0 over the contact nodes */
  PetscInt  active_vertices; /* where the rule's force acts (penalty), or on the bound (vi) */
  PetscReal energy;          /* the contact term's energy: (1/2eps) int [u_n - g]_+^2 for the penalty, 0 otherwise */
} ContactResult;

/* contact.c: the object and its registry */
PetscErrorCode ContactRegister(const char name[], PetscErrorCode (*create)(Contact));
PetscErrorCode ContactFinalizePackage(void);
PetscErrorCode ContactCreate(MPI_Comm comm, Contact *ct);
PetscErrorCode ContactSetFromOptions(Contact ct);
PetscErrorCode ContactDestroy(Contact *ct);
PetscErrorCode ContactGetType(Contact ct, ContactType *type);
PetscErrorCode ContactGetOptions(Contact ct, const ContactOptions **opt);
PetscErrorCode ContactSetUp(Contact ct, DM dm, const ContactProblem *pb);
PetscErrorCode ContactReset(Contact ct);
PetscErrorCode ContactSetLoad(Contact ct, DM dm, const Obstacle *obstacle);
PetscErrorCode ContactView(Contact ct, PetscViewer viewer);
PetscErrorCode ContactWrite(Contact ct, PetscViewer v); /* the method's part of /run */

/* What the solver around the contact does by default for its type, stated by the type at its creation, as a PETSc KSP
   type states the norms it supports: solver.c, newton.c, contact_monitor.c and grid_sequence.c apply it where the
   options say nothing. */
typedef struct {
  PetscBool reuse_factorization; /* J = K plus terms in the contact rows only (the penalty): an earlier J's factorization
                                    preconditions CG on the next (src/linear/pc_reuse.c), which the default linear solver is */
  PetscBool inexact_newton;      /* Eisenstat-Walker's forcing terms with an iterative preconditioner (the penalty) */
  PetscBool linear;              /* the problem is linear (none): one Newton step, CG on the true residual's norm */
  PetscBool nested_iteration;    /* the grid sequence's coarser boxes by default on P1: each starts Newton near the next (the penalty) */
  PetscBool multigrid;           /* a multigrid preconditioner can follow J: not SNESVI's reduced system (vinewtonrsls) */
  PetscBool active_set_cycles;   /* semismooth Newton's active set can cycle between steps: detected, damped (the penalty) */
} ContactSolverDefaults;
PetscErrorCode ContactGetSolverDefaults(Contact ct, const ContactSolverDefaults **defaults);

/* How the contact pressure p on Gamma_C follows from a discrete solution, which the error estimate, the error norms and
   the checks of the contact zone evaluate:
     acts   a contact pressure acts at all (none: Gamma_C is a free boundary, p = 0);
     law    p = [u . n - g]_+ / eps at every point, the penalty law, with the eps of ContactFaceEps() (the penalty, either rule);
     nodal  the discrete force is one force per contact node, p that force over the node's lumped area (SNESVI's reaction,
            the nodal rule's force); otherwise the law's face integrals (the Gauss rule). */
typedef struct {
  PetscBool acts, law, nodal;
} ContactPressureForm;
PetscErrorCode ContactGetPressureForm(Contact ct, ContactPressureForm *form);

/* Whether the answer depends on an eps: the penalty term (1/eps)[u . n - g]_+. Asked only by a driver that solves the
   same problem again at another eps or moves its data along a penalty's solution path (the bars' and the cycles'
   penalty part, a load path's secant, force control), each saying why; the rest of the code asks the operations. */
PetscBool ContactHasPenalty(Contact ct);

/* eps: computed from the options on each mesh (ContactSetUp()), changed by the continuation and the sweep through
   ContactSetEps(), which also updates the kernels' constants[CONST_PENALTY] = 1/eps; every reader of eps reads it here.
   A type without a penalty has no eps: ContactGetEps(), ContactGetEpsRange() and ContactGetPenaltyScale() give 0 and
   ContactSetEps() keeps it 0, so that a driver that scales eps (a sweep, a continuation, a load path's reset) leaves
   such a type as it was. How eps follows the mesh: */
typedef enum {
  CONTACT_EPS_NONE,  /* no eps (vi, none) */
  CONTACT_EPS_FIXED, /* -penalty_eps, or -penalty_eps_power 0: the same eps on every mesh */
  CONTACT_EPS_MESH   /* eps0 h^power / M, power > 0: eps falls with the cells */
} ContactEpsScaling;
ContactEpsScaling ContactGetEpsScaling(Contact ct);
PetscErrorCode    ContactEpsFromFactor(Contact ct, PetscReal eps0, PetscReal *eps);
PetscErrorCode    ContactSetEps(Contact ct, DM dm, PetscReal eps);
PetscErrorCode    ContactGetEps(Contact ct, PetscReal *eps);
PetscErrorCode    ContactGetEpsRange(Contact ct, PetscReal *eps_min, PetscReal *eps_max, PetscBool *local);
PetscErrorCode    ContactFaceEps(Contact ct, PetscReal cell_diameter, PetscReal *eps);
PetscErrorCode    ContactGetPenaltyScale(Contact ct, PetscReal *eps_start);
PetscErrorCode    ContactGetSet(Contact ct, const ContactSet **cs);
PetscErrorCode    ContactUnseenNodes(Contact ct, Vec u, PetscBool unseen[], PetscInt *count,
                                     PetscReal *force); /* penetrating with no force from the rule */

/* The terms of the nonlinear problem: F(u) = K u + r0 + (contact term), J = K + (contact Jacobian). */
PetscErrorCode ContactAddResidual(Contact ct, DM dm, Vec u, Vec F);
PetscErrorCode ContactComputeJacobian(Contact ct, DM dm, Vec u, Mat K, Mat P);
PetscErrorCode ContactPrepareOperator(Contact ct, DM dm, Mat K);
PetscErrorCode ContactBulkMult(Contact ct, Mat K, Vec X, Vec R);
PetscErrorCode ContactBulkOperator(Contact ct, Mat K, Mat *Kb);
PetscErrorCode ContactEnergy(Contact ct, DM dm, Vec u, PetscReal *energy);
PetscErrorCode ContactSetUpSNES(Contact ct, DM dm, SNES snes);
PetscErrorCode ContactCreateJacobian(Contact ct, DM dm, Mat K, Mat *J); /* K itself (referenced), or a copy the penalty's Jacobian is made in */
PetscErrorCode ContactCheckSNES(Contact ct, SNES snes, Mat K);          /* after SNESSetFromOptions(): the SNES type and K suit the method */
PetscErrorCode ContactScaleBounds(Contact ct, PetscReal s);
PetscErrorCode ContactRoundoffTerm(Contact ct, Vec u, PetscReal *sum_sq);
PetscErrorCode ContactSameActivity(Contact ct, DM dm, Vec X, Vec Y, PetscBool *same);
/* The SNES's own unknowns: SNESVI iterates on w = Q^T u, Q orthogonal, rotating the free components of the contact nodes
   whose normal is not an axis into (normal, tangents) so that u . n <= g bounds one unknown (src/contact/vi_frames.c).
   v <- Q^T v (to_solver) or v <- Q v; the identity for the other types and where every normal is an axis. */
PetscErrorCode ContactSolverFrame(Contact ct, Vec v, PetscBool to_solver);
/* The displacement Q X of the SNES's iterate X: *u = X itself without frames, else work = Q X and *u = work. */
PetscErrorCode ContactSolverDisplacement(Contact ct, Vec X, Vec work, Vec *u);
/* The augmented Lagrangian (type al): whether the type has multipliers, and their update at u (Uzawa), made if apply;
   *change is the largest change of eps lambda it makes (a length: the penetration, or the stand-off of a node whose
   multiplier pushes). */
PetscBool      ContactCanAugment(Contact ct);
PetscErrorCode ContactAugment(Contact ct, DM dm, Vec u, PetscBool apply, PetscReal *change);
PetscErrorCode ContactForgetMultipliers(Contact ct); /* all multipliers zero: the state of a zero load (nothing for the other types) */

/* The state of the contact nodes at an iterate (contact_set.c) */
PetscErrorCode ContactCountActive(Contact ct, Vec X, PetscReal tol_scale, PetscBool update, PetscInt *active, PetscInt *entered, PetscInt *left);
PetscErrorCode ContactPenetrationHash(Contact ct, Vec X, PetscInt64 *hash);
PetscErrorCode ContactMaxNodePenetration(Contact ct, Vec u, PetscReal *dmax);
PetscErrorCode ContactMaxPenetration(Contact ct, DM dm, Vec u, PetscReal *dmax); /* the nodes' and the rule's points' */
/* The smallest nodal pressure that counts as acting: SNESVI's active set tolerance, 1e-10 times the largest pressure
   over the ranks, below which its reaction is round-off; 0 for the other types, whose force is exact zero off contact. */
PetscErrorCode ContactActivityFloor(Contact ct, PetscReal *floor);

/* After the solve: the pressure and the reaction at each node (kept in the contact set), the force, the active set, the energy */
PetscErrorCode ContactPostProcess(Contact ct, DM dm, Vec R, Vec u, PetscReal tol_scale, ContactResult *res);

/* The rows of K that the penalty Jacobian changes (penalty.c, bulk_rows.c): read by the GAMG updates (src/linear/pc_reuse.c) */
typedef struct {
  PetscInt     n;                 /* owned rows of the contact dofs */
  PetscInt    *rows, *ptr, *cols; /* their global numbers, and their columns in CSR form */
  PetscScalar *vals;              /* K's own values there */
  PetscInt    *diag;              /* each row's diagonal entry (ptr numbering) */
  PetscInt    *lcols;             /* each column's place in x */
  VecScatter   scatter;           /* the displacement at those columns (any rank's) into x */
  Vec          x;
  PetscBool    jacobian_in_K; /* K holds K + the penalty Jacobian in those rows */
} ContactBulkRows;
const ContactBulkRows *ContactBulkRowsOf(Contact ct); /* NULL without a penalty term; rows->ptr NULL before they are saved */
PetscErrorCode         ContactCopyRows(Mat A, PetscInt n, const PetscInt rows[], PetscInt **ptr, PetscInt **cols, PetscScalar **vals);

/* Penetration u . n - g of contact node i, from the owned part x[] of a global vector (fixed components: their values). */
static inline PetscReal ContactNodePenetration(const ContactSet *cs, PetscInt dim, PetscInt i, const PetscScalar x[])
{
  PetscReal un = 0.0;

  for (PetscInt c = 0; c < dim; ++c) {
    const PetscInt k = cs->dof[i * dim + c];
    un += (k >= 0 ? PetscRealPart(x[k]) : cs->fixed[i * dim + c]) * cs->normal[i * dim + c];
  }
  return un - cs->gap[i];
}

/* The penalty parameter of contact node i: the run's eps scaled to the node's local mesh size. */
static inline PetscReal ContactNodeEps(const ContactSet *cs, PetscReal eps, PetscInt i)
{
  return eps * cs->eps_factor[i];
}
