/* The Contact object: the registry of its types, its options, eps, and the operations every type shares, each of
   which calls the type's own where it has one (contact_impl.h). */
#include "app.h"
#include "contact_impl.h"

const char *const PenaltyQuadratures[] = {"gauss", "nodal", "PenaltyQuadrature", "PENALTY_QUADRATURE_", NULL};
const char *const PenaltyModuli[]      = {"young", "pwave", "PenaltyModulus", "PENALTY_MODULUS_", NULL};

static PetscFunctionList contact_list       = NULL;
static PetscBool         contact_registered = PETSC_FALSE;

/* Adds a type: -contact_method NAME then calls create, which fills the operations of the object. */
PetscErrorCode ContactRegister(const char name[], PetscErrorCode (*create)(Contact))
{
  PetscFunctionBeginUser;
  PetscCall(PetscFunctionListAdd(&contact_list, name, create));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode ContactRegisterAll(void)
{
  PetscFunctionBeginUser;
  if (contact_registered) PetscFunctionReturn(PETSC_SUCCESS);
  contact_registered = PETSC_TRUE;
  PetscCall(ContactRegister(CONTACTPENALTY, ContactCreate_Penalty));
  PetscCall(ContactRegister(CONTACTAL, ContactCreate_AL));
  PetscCall(ContactRegister(CONTACTVI, ContactCreate_VI));
  PetscCall(ContactRegister(CONTACTNONE, ContactCreate_None));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode ContactFinalizePackage(void)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFunctionListDestroy(&contact_list));
  contact_registered = PETSC_FALSE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode ContactCreate(MPI_Comm comm, Contact *ct)
{
  PetscFunctionBeginUser;
  PetscCall(ContactRegisterAll());
  PetscCall(PetscNew(ct));
  (*ct)->comm = comm;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* -contact_method and the penalty parameter, read once before any set-up; the type's create function runs here. */
PetscErrorCode ContactSetFromOptions(Contact ct)
{
  MPI_Comm        comm              = ct->comm;
  ContactOptions *opts              = &ct->opt;
  PetscErrorCode (*create)(Contact) = NULL;
  PetscBool eps_set, sweep_set, tol_set, quadrature_set, accuracy;

  PetscFunctionBeginUser;
  PetscOptionsBegin(comm, NULL, "Contact on Gamma_C", "Signorini");
  PetscCall(PetscStrncpy(opts->method, CONTACTPENALTY, sizeof(opts->method)));
  PetscCall(PetscOptionsFList(
      "-contact_method",
      "Contact treatment: penalty, al (augmented Lagrangian, with -contact_penetration_tol), vi (SNESVI reference), none (no contact)",
      "ContactRegister", contact_list, opts->method, opts->method, sizeof(opts->method), NULL));
  opts->quadrature = PENALTY_QUADRATURE_GAUSS;
  PetscCall(PetscOptionsEnum("-penalty_quadrature", "Quadrature of the penalty term: gauss (L2 product) or nodal (lumped, vertex rule)", NULL,
                             PenaltyQuadratures, (PetscEnum)opts->quadrature, (PetscEnum *)&opts->quadrature, &quadrature_set));
  /* eps = h by default; with -accuracy, eps = h/10 on the adaptive meshes, where the penalty's error at eps = h holds
     the zone's width back (docs/decisions.md, "-accuracy's eps") */
  PetscCall(PetscOptionsHasName(NULL, NULL, "-accuracy", &accuracy));
  opts->eps0 = accuracy ? 0.1 : 1.0;
  PetscCall(PetscOptionsReal("-penalty_eps0", "eps = eps0 h^power / M (M: -penalty_eps_modulus, E by default): the factor eps0", NULL, opts->eps0,
                             &opts->eps0, NULL));
  opts->eps_power = 1.0;
  PetscCall(
      PetscOptionsReal("-penalty_eps_power", "eps = eps0 h^power / M: the power of h, in [0, 4]", NULL, opts->eps_power, &opts->eps_power, NULL));
  opts->eps_local = PETSC_TRUE;
  PetscCall(PetscOptionsBool("-penalty_eps_local",
                             "eps from the local h: the diameter of the cell at each contact face (gauss) or the largest at each node (nodal)", NULL,
                             opts->eps_local, &opts->eps_local, NULL));
  opts->modulus = PENALTY_MODULUS_YOUNG;
  PetscCall(PetscOptionsEnum("-penalty_eps_modulus",
                             "Stiffness M of eps = eps0 h^power / M: young (E) or pwave (lambda + 2 mu, for nearly incompressible bodies)", NULL,
                             PenaltyModuli, (PetscEnum)opts->modulus, (PetscEnum *)&opts->modulus, NULL));
  opts->eps_fixed = 0.0;
  PetscCall(PetscOptionsReal("-penalty_eps", "Set eps directly (overrides eps0 and power)", NULL, opts->eps_fixed, &opts->eps_fixed, &eps_set));
  opts->continuation = PETSC_TRUE;
  PetscCall(PetscOptionsBool("-penalty_continuation", "Reach an eps below h/M through the sequence h/M, h/M f, h/M f^2, ... (warm starts)", NULL,
                             opts->continuation, &opts->continuation, NULL));
  opts->continuation_factor = 1e-2;
  PetscCall(PetscOptionsReal("-penalty_continuation_factor", "Ratio f of two consecutive eps of the continuation, in (0, 1)", NULL,
                             opts->continuation_factor, &opts->continuation_factor, NULL));
  PetscCall(OptionsCountListValues("-penalty_eps0_sweep", &opts->n_sweep));
  PetscCall(PetscCalloc1(opts->n_sweep + 1, &opts->eps0_sweep)); /* zeros: -help shows the first as the default */
  PetscCall(PetscOptionsRealArray("-penalty_eps0_sweep", "eps0 values solved in turn on the final mesh, each from the last solution", NULL,
                                  opts->eps0_sweep, &opts->n_sweep, &sweep_set));
  if (!sweep_set) opts->n_sweep = 0;
  opts->penetration_tol = 0.0;
  PetscCall(PetscOptionsReal("-contact_penetration_tol",
                             "Largest penetration allowed, a length: eps is lowered from the measured penetration until it is reached "
                             "(src/drivers/penetration_tol.c)",
                             NULL, opts->penetration_tol, &opts->penetration_tol, &tol_set));
  PetscOptionsEnd();
  {
    const char *names[]  = {"-penalty_eps0", "-penalty_eps_power", "-penalty_eps", "-penalty_continuation_factor", "-contact_penetration_tol"};
    PetscReal   values[] = {opts->eps0, opts->eps_power, opts->eps_fixed, opts->continuation_factor, opts->penetration_tol};

    for (size_t i = 0; i < sizeof(values) / sizeof(values[0]); ++i) PetscCall(OptionsCheckFinite(comm, names[i], values[i]));
    PetscCall(OptionsCheckFiniteArray(comm, "-penalty_eps0_sweep", opts->n_sweep, opts->eps0_sweep));
  }
  PetscCall(PetscFunctionListFind(contact_list, opts->method, &create));
  PetscCheck(create, comm, PETSC_ERR_USER_INPUT, "Unknown option %s for -contact_method: the registered types are penalty, al, vi and none",
             opts->method);
  PetscCall(PetscStrncpy(ct->type, opts->method, sizeof(ct->type)));
  PetscCall((*create)(ct));
  PetscCheck(!sweep_set || opts->n_sweep > 0, comm, PETSC_ERR_USER_INPUT, "-penalty_eps0_sweep needs a comma-separated list of values");
  for (PetscInt k = 0; k < opts->n_sweep; ++k)
    PetscCheck(opts->eps0_sweep[k] > 0.0, comm, PETSC_ERR_USER_INPUT, "-penalty_eps0_sweep: every value must be positive, got %g",
               (double)opts->eps0_sweep[k]);
  PetscCheck(!(sweep_set && eps_set), comm, PETSC_ERR_USER_INPUT, "-penalty_eps0_sweep cannot be given together with -penalty_eps");
  PetscCheck(!sweep_set || ct->has_penalty, comm, PETSC_ERR_USER_INPUT, "-penalty_eps0_sweep needs -contact_method penalty");
  PetscCheck(!tol_set || opts->penetration_tol > 0.0, comm, PETSC_ERR_USER_INPUT, "-contact_penetration_tol must be positive, got %g",
             (double)opts->penetration_tol);
  PetscCheck(!tol_set || ct->has_penalty, comm, PETSC_ERR_USER_INPUT,
             "-contact_penetration_tol needs -contact_method penalty or al (SNESVI's penetration is zero at the nodes already)");
  if (ct->ops.augment && !quadrature_set) opts->quadrature = PENALTY_QUADRATURE_NODAL; /* the augmented Lagrangian's multipliers are nodal */
  PetscCheck(!ct->ops.augment || opts->quadrature == PENALTY_QUADRATURE_NODAL, comm, PETSC_ERR_USER_INPUT,
             "-contact_method al has its multipliers at the contact nodes (the nodal rule): the Gauss rule's points over-constrain P1 elements, "
             "and Uzawa's updates stall there; give -penalty_quadrature nodal or leave it out");
  PetscCheck(tol_set || !ct->ops.augment, comm, PETSC_ERR_USER_INPUT,
             "-contact_method al needs -contact_penetration_tol: the largest penetration its multipliers' updates are to reach");
  PetscCheck(!(tol_set && sweep_set), comm, PETSC_ERR_USER_INPUT,
             "-contact_penetration_tol and -penalty_eps0_sweep both choose the values of eps: give one of them");
  if (opts->n_sweep) opts->eps0 = opts->eps0_sweep[0]; /* the sweep starts with its first value, in place of -penalty_eps0 */
  PetscCheck(opts->continuation_factor > 0.0 && opts->continuation_factor < 1.0, comm, PETSC_ERR_USER_INPUT,
             "-penalty_continuation_factor must lie in (0, 1), got %g", (double)opts->continuation_factor);
  PetscCheck(opts->eps0 > 0.0, comm, PETSC_ERR_USER_INPUT, "-penalty_eps0 must be positive, got %g", (double)opts->eps0);
  PetscCheck(opts->eps_power >= 0.0 && opts->eps_power <= 4.0, comm, PETSC_ERR_USER_INPUT, "-penalty_eps_power must lie in [0, 4], got %g",
             (double)opts->eps_power);
  PetscCheck(!eps_set || opts->eps_fixed > 0.0, comm, PETSC_ERR_USER_INPUT, "-penalty_eps must be positive, got %g", (double)opts->eps_fixed);
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode ContactReset(Contact ct)
{
  PetscFunctionBeginUser;
  if (!ct) PetscFunctionReturn(PETSC_SUCCESS);
  if (ct->ops.reset) PetscCall((*ct->ops.reset)(ct));
  PetscCall(ContactSetFree(&ct->set));
  PetscCall(VecDestroy(&ct->loc_bc));
  ct->set_up = PETSC_FALSE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode ContactDestroy(Contact *ct)
{
  PetscFunctionBeginUser;
  if (!*ct) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(ContactReset(*ct));
  if ((*ct)->ops.destroy)
    PetscCall((*(*ct)->ops.destroy)(*ct));
  else
    PetscCall(PetscFree((*ct)->data)); /* data with nothing to free inside */
  PetscCall(PetscFree((*ct)->opt.eps0_sweep));
  PetscCall(PetscFree(*ct));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode ContactGetType(Contact ct, ContactType *type)
{
  PetscFunctionBeginUser;
  *type = ct->type;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode ContactGetOptions(Contact ct, const ContactOptions **opt)
{
  PetscFunctionBeginUser;
  *opt = &ct->opt;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscBool ContactHasPenalty(Contact ct)
{
  return ct->has_penalty;
}

PetscErrorCode ContactGetSolverDefaults(Contact ct, const ContactSolverDefaults **defaults)
{
  PetscFunctionBeginUser;
  *defaults = &ct->defaults;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* none: no pressure; vi: its reaction, a force per node; the penalty: its law, by faces (Gauss) or nodes (nodal). */
PetscErrorCode ContactGetPressureForm(Contact ct, ContactPressureForm *form)
{
  PetscFunctionBeginUser;
  form->acts  = (PetscBool)(ct->has_penalty || ct->has_bounds);
  form->law   = ct->has_penalty;
  form->nodal = (PetscBool)(ct->has_bounds || (ct->has_penalty && ct->opt.quadrature != PENALTY_QUADRATURE_GAUSS));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode ContactActivityFloor(Contact ct, PetscReal *floor)
{
  PetscFunctionBeginUser;
  *floor = 0.0;
  if (!ct->has_bounds) PetscFunctionReturn(PETSC_SUCCESS);
  for (PetscInt i = 0; i < ct->set.n; ++i) *floor = PetscMax(*floor, ct->set.pressure[i]);
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, floor, 1, MPIU_REAL, MPIU_MAX, ct->comm));
  *floor *= 1e-10;
  PetscFunctionReturn(PETSC_SUCCESS);
}

ContactEpsScaling ContactGetEpsScaling(Contact ct)
{
  if (!ct->has_penalty) return CONTACT_EPS_NONE;
  return ct->opt.eps_fixed > 0.0 || ct->opt.eps_power == 0.0 ? CONTACT_EPS_FIXED : CONTACT_EPS_MESH;
}

/* M of eps = eps0 h^power / M: E, or the P-wave modulus lambda + 2 mu, which grows without bound as nu -> 1/2. */
static PetscReal ContactModulus(Contact ct)
{
  return ct->opt.modulus == PENALTY_MODULUS_PWAVE ? ct->material.lambda + 2.0 * ct->material.mu : ct->material.young_modulus;
}

/* eps = eps0 h^power / M (Corollary 3.3 takes eps = h), or the fixed -penalty_eps, on the mesh of the set-up. */
PetscErrorCode ContactEpsFromFactor(Contact ct, PetscReal eps0, PetscReal *eps)
{
  PetscFunctionBeginUser;
  *eps = ct->opt.eps_fixed > 0.0 ? ct->opt.eps_fixed : eps0 * PetscPowReal(ct->h, ct->opt.eps_power) / ContactModulus(ct);
  /* the penalty term multiplies by 1/eps: an eps that underflows (eps0 = 1e-320) or overflows would make it inf or 0 */
  PetscCheck(!ct->has_penalty || (*eps >= 1e-290 && *eps <= 1e290), ct->comm, PETSC_ERR_USER_INPUT,
             "eps = %g (-penalty_eps0 %g, -penalty_eps %g, h = %g, modulus %g) is outside [1e-290, 1e290]: the penalty 1/eps would overflow "
             "or vanish in double precision; give another -penalty_eps0 or -penalty_eps",
             (double)*eps, (double)eps0, (double)ct->opt.eps_fixed, (double)ct->h, (double)ContactModulus(ct));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* eps of the continuation's first solve, h/M: the penalty problem that Newton solves from zero without trouble. */
PetscErrorCode ContactGetPenaltyScale(Contact ct, PetscReal *eps_start)
{
  PetscFunctionBeginUser;
  *eps_start = ct->has_penalty ? ct->h / ContactModulus(ct) : 0.0;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The one place eps changes: the object's eps, which the nodal rule reads, and constants[CONST_PENALTY] = 1/eps, which the
   Gauss rule's kernels read (0 without a penalty term). */
PetscErrorCode ContactSetEps(Contact ct, DM dm, PetscReal eps)
{
  PetscDS            ds;
  const PetscScalar *c0;
  PetscScalar        c[CONST_SCENE_MAX];
  PetscInt           nc;

  PetscFunctionBeginUser;
  ct->eps = ct->has_penalty ? eps : 0.0; /* no eps without a penalty (include/contact.h) */
  PetscCall(DMGetDS(dm, &ds));
  PetscCall(PetscDSGetConstants(ds, &nc, &c0));
  PetscCheck(nc > CONST_PENALTY && nc <= CONST_SCENE_MAX, ct->comm, PETSC_ERR_PLIB, "the constants of the kernels are not set");
  PetscCall(PetscArraycpy(c, c0, nc));
  c[CONST_PENALTY] = ct->has_penalty ? 1.0 / eps : 0.0;
  PetscCall(PetscDSSetConstants(ds, nc, c));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode ContactGetEps(Contact ct, PetscReal *eps)
{
  PetscFunctionBeginUser;
  *eps = ct->eps;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The smallest and largest eps of the faces (gauss) or nodes (nodal), and whether they differ (a graded mesh). */
PetscErrorCode ContactGetEpsRange(Contact ct, PetscReal *eps_min, PetscReal *eps_max, PetscBool *local)
{
  PetscFunctionBeginUser;
  if (eps_min) *eps_min = ct->eps * ct->eps_factor_min;
  if (eps_max) *eps_max = ct->eps * ct->eps_factor_max;
  if (local) *local = ct->eps_local;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* eps of the Gauss rule at a contact face whose cell has the given diameter: the run's eps, scaled to the cell where eps
   is local (a graded mesh); the penalty law there is p = [u_n - g]_+ / eps. */
PetscErrorCode ContactFaceEps(Contact ct, PetscReal cell_diameter, PetscReal *eps)
{
  PetscFunctionBeginUser;
  *eps = ct->eps_local ? ct->eps * ContactEpsFactor(ct, cell_diameter) : ct->eps;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode ContactGetSet(Contact ct, const ContactSet **cs)
{
  PetscFunctionBeginUser;
  *cs = &ct->set;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* On a mesh: the contact set, eps and the type's own state (the penalty's faces and weak form, the SNESVI bounds). */
PetscErrorCode ContactSetUp(Contact ct, DM dm, const ContactProblem *pb)
{
  PetscReal eps;

  PetscFunctionBeginUser;
  PetscCall(ContactReset(ct));
  PetscCall(DMGetDimension(dm, &ct->dim));
  ct->degree = pb->degree;
  ct->nids   = pb->bcs->ncontact;
  for (PetscInt i = 0; i < ct->nids; ++i) ct->ids[i] = pb->bcs->contact_ids[i];
  PetscCall(DMGetLabel(dm, "Face Sets", &ct->face_sets));
  ct->obstacle = *pb->obstacle;
  ObstaclePack(&ct->obstacle, ct->obstacle_packed);
  ct->material       = *pb->material;
  ct->h              = pb->h;
  ct->assembly       = pb->assembly;
  ct->assembly_check = pb->assembly_check;
  PetscCall(PetscObjectReference((PetscObject)pb->loc_bc));
  ct->loc_bc = pb->loc_bc;
  PetscCall(ContactEpsFromFactor(ct, ct->opt.eps0, &eps));
  PetscCall(ContactSetEps(ct, dm, eps));
  PetscCall(ContactSetBuild(ct, dm, pb->like));
  if (ct->ops.setup) PetscCall((*ct->ops.setup)(ct, dm));
  ct->set_up = PETSC_TRUE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A new load state on the same mesh (a step of a load path): the obstacle at its new translation, and the Dirichlet
   values that loc_bc (referenced at ContactSetUp()) now holds. The contact set's gaps, normals and fixed values follow;
   the Gauss rule's kernels read the obstacle from constants[], which ElasticityUpdateConstants() rewrote. The bounds of
   SNESVI would have to follow too: it is refused with a load path (LoadPathSetUp()). */
PetscErrorCode ContactSetLoad(Contact ct, DM dm, const Obstacle *obstacle)
{
  PetscFunctionBeginUser;
  PetscCheck(ct->set_up, ct->comm, PETSC_ERR_ORDER, "ContactSetLoad() needs ContactSetUp() first");
  ct->obstacle = *obstacle;
  ObstaclePack(&ct->obstacle, ct->obstacle_packed);
  PetscCall(ContactSetUpdateData(ct, dm));
  if (ct->ops.load) PetscCall((*ct->ops.load)(ct, dm)); /* what the type made of the gaps: SNESVI's bounds */
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The type and its parameters, as the run's summary line shows them: "method penalty (gauss quadrature, eps = ...)". */
PetscErrorCode ContactView(Contact ct, PetscViewer viewer)
{
  PetscFunctionBeginUser;
  PetscCall(PetscViewerASCIIPrintf(viewer, "method %s", ct->type));
  if (ct->ops.view) PetscCall((*ct->ops.view)(ct, viewer));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode ContactAddResidual(Contact ct, DM dm, Vec u, Vec F)
{
  PetscFunctionBeginUser;
  if (ct->ops.residual) PetscCall((*ct->ops.residual)(ct, dm, u, F));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* P = K + the contact Jacobian at u; P may be K itself (the penalty then keeps K's own rows, ContactBulkMult()). */
PetscErrorCode ContactComputeJacobian(Contact ct, DM dm, Vec u, Mat K, Mat P)
{
  PetscFunctionBeginUser;
  if (ct->ops.jacobian) PetscCall((*ct->ops.jacobian)(ct, dm, u, K, P));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode ContactPrepareOperator(Contact ct, DM dm, Mat K)
{
  PetscFunctionBeginUser;
  if (ct->ops.prepare_operator) PetscCall((*ct->ops.prepare_operator)(ct, dm, K));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* *J: the matrix the SNES's Jacobian is made in, for the caller to destroy. The Jacobian is K itself: for the penalty
   method K + P in the contact rows (ContactComputeJacobian()), whose own rows the type keeps
   (ContactPrepareOperator()); a symmetric block matrix gives no access to its rows below the diagonal, so there the
   penalty Jacobian is a copy of K, with K's near null space. Without bounds K and K + the penalty Jacobian are
   symmetric positive definite (semi-definite at worst; CG needs it anyway): PETSc then estimates eigenvalues by CG
   (Lanczos) rather than GMRES, as GAMG's Chebyshev smoothers do on the finest level, without GMRES's 10 vectors of the
   finest size. */
PetscErrorCode ContactCreateJacobian(Contact ct, DM dm, Mat K, Mat *J)
{
  PetscBool sbaij, is_aij;

  PetscFunctionBeginUser;
  PetscCall(PetscObjectTypeCompareAny((PetscObject)K, &sbaij, MATSEQSBAIJ, MATMPISBAIJ, ""));
  if (ct->has_penalty && sbaij) {
    MatNullSpace rigid;

    PetscCall(MatDuplicate(K, MAT_COPY_VALUES, J));
    PetscCall(MatGetNearNullSpace(K, &rigid));
    PetscCall(MatSetNearNullSpace(*J, rigid));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  *J = K;
  PetscCall(PetscObjectReference((PetscObject)K));
  PetscCall(PetscObjectTypeCompareAny((PetscObject)K, &is_aij, MATSEQAIJ, MATMPIAIJ, ""));
  if (!ct->has_bounds && is_aij) { /* (BAIJ in 3.18 refuses MAT_SPD_ETERNAL) */
    PetscCall(MatSetOption(K, MAT_SPD, PETSC_TRUE));
    PetscCall(MatSetOption(K, MAT_SPD_ETERNAL, PETSC_TRUE));
  }
  PetscCall(ContactPrepareOperator(ct, dm, K)); /* the penalty keeps K's own contact rows */
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* After SNESSetFromOptions(): whether the SNES type and the matrix K suit the method. SNESVI's types need the bounds
   and the other types none; SNESVI takes the rows and columns of single components out of the Jacobian, which a block
   matrix refuses. */
PetscErrorCode ContactCheckSNES(Contact ct, SNES snes, Mat K)
{
  MPI_Comm    comm = PetscObjectComm((PetscObject)snes);
  PetscBool   is_vi, block;
  SNESType    type;
  ContactType ctype;
  MatType     mtype;

  PetscFunctionBeginUser;
  PetscCall(PetscObjectTypeCompareAny((PetscObject)snes, &is_vi, SNESVINEWTONRSLS, SNESVINEWTONSSLS, ""));
  PetscCall(SNESGetType(snes, &type));
  PetscCall(ContactGetType(ct, &ctype));
  PetscCheck(is_vi == ct->has_bounds, comm, PETSC_ERR_USER_INPUT,
             "-snes_type %s does not fit -contact_method %s: use vinewtonrsls or vinewtonssls with vi, and a non-VI type otherwise", type, ctype);
  PetscCall(PetscObjectTypeCompareAny((PetscObject)K, &block, MATSEQBAIJ, MATMPIBAIJ, MATSEQSBAIJ, MATMPISBAIJ, ""));
  PetscCall(MatGetType(K, &mtype));
  PetscCheck(!(block && ct->has_bounds), comm, PETSC_ERR_USER_INPUT,
             "-contact_method vi cannot use the block matrix %s (-dm_mat_type): SNESVI's reduced system takes single components out of it; use aij",
             mtype);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* R = K X with K the bulk elastic operator, also while K holds the penalty Jacobian (whose rows it leaves alone). */
PetscErrorCode ContactBulkMult(Contact ct, Mat K, Vec X, Vec R)
{
  PetscFunctionBeginUser;
  if (ct->ops.bulk_mult)
    PetscCall((*ct->ops.bulk_mult)(ct, K, X, R));
  else
    PetscCall(MatMult(K, X, R));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* *Kb: a matrix equal to the bulk elastic operator, for the caller to destroy; K itself (referenced) when it holds no
   penalty Jacobian, else a copy with K's own contact rows. K is not changed. */
PetscErrorCode ContactBulkOperator(Contact ct, Mat K, Mat *Kb)
{
  PetscFunctionBeginUser;
  if (ct->ops.bulk_operator)
    PetscCall((*ct->ops.bulk_operator)(ct, K, Kb));
  else {
    PetscCall(PetscObjectReference((PetscObject)K));
    *Kb = K;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The SNES for the type: SNESVI's with its bounds, or by default semismooth Newton with the critical-point line search.
   The penalty problem is the minimization of a convex energy, and the search along the energy's derivative keeps
   Newton converging for small eps, where backtracking on |F| stalls; no convergence on a small step, which at small
   eps is no sign of the solution. */
PetscErrorCode ContactSetUpSNES(Contact ct, DM dm, SNES snes)
{
  SNESLineSearch ls;

  PetscFunctionBeginUser;
  if (ct->ops.setup_snes) {
    PetscCall((*ct->ops.setup_snes)(ct, dm, snes));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  PetscCall(SNESSetType(snes, SNESNEWTONLS));
  PetscCall(SNESGetLineSearch(snes, &ls));
  PetscCall(SNESLineSearchSetType(ls, SNESLINESEARCHCP));
  PetscCall(SNESSetTolerances(snes, PETSC_DEFAULT, PETSC_DEFAULT, 0.0, PETSC_DEFAULT, PETSC_DEFAULT));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* SNESVI's bounds times s (the SNES iterates on u/U); nothing for the other types. */
PetscErrorCode ContactScaleBounds(Contact ct, PetscReal s)
{
  PetscFunctionBeginUser;
  if (ct->ops.scale_bounds) PetscCall((*ct->ops.scale_bounds)(ct, s));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The SNES's unknowns: v <- Q^T v (to_solver) or v <- Q v, Q the orthogonal change to the frames of vi_frames.c where
   the type has them, the identity otherwise. */
PetscErrorCode ContactSolverFrame(Contact ct, Vec v, PetscBool to_solver)
{
  PetscFunctionBeginUser;
  if (ct->has_frames && ct->ops.frame) PetscCall((*ct->ops.frame)(ct, v, to_solver));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode ContactSolverDisplacement(Contact ct, Vec X, Vec work, Vec *u)
{
  PetscFunctionBeginUser;
  *u = X;
  if (!ct->has_frames) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(VecCopy(X, work));
  PetscCall(ContactSolverFrame(ct, work, PETSC_FALSE));
  *u = work;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscBool ContactCanAugment(Contact ct)
{
  return (PetscBool)(ct->ops.augment != NULL);
}

PetscErrorCode ContactAugment(Contact ct, DM dm, Vec u, PetscBool apply, PetscReal *change)
{
  PetscFunctionBeginUser;
  PetscCheck(ct->ops.augment, ct->comm, PETSC_ERR_ARG_WRONGSTATE, "the contact type %s has no multipliers to update", ct->type);
  PetscCall((*ct->ops.augment)(ct, dm, u, apply, change));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode ContactForgetMultipliers(Contact ct)
{
  PetscFunctionBeginUser;
  if (ct->ops.forget) PetscCall((*ct->ops.forget)(ct));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode ContactSameActivity(Contact ct, DM dm, Vec X, Vec Y, PetscBool *same)
{
  PetscFunctionBeginUser;
  *same = PETSC_TRUE;
  if (ct->ops.same_activity) PetscCall((*ct->ops.same_activity)(ct, dm, X, Y, same));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The largest penetration u . n - g at u over the contact nodes and the points of the penalty's rule (where they are
   at hand: ContactPostProcess()'s "max penetration"), on every rank. */
PetscErrorCode ContactMaxPenetration(Contact ct, DM dm, Vec u, PetscReal *dmax)
{
  PetscReal drule = -PETSC_MAX_REAL;

  PetscFunctionBeginUser;
  PetscCall(ContactMaxNodePenetration(ct, u, dmax));
  if (ct->ops.acts) {
    PetscBool *acts;

    PetscCall(PetscMalloc1(ct->set.n + 1, &acts));
    PetscCall((*ct->ops.acts)(ct, dm, u, acts, &drule));
    PetscCall(PetscFree(acts));
  }
  *dmax = PetscMax(*dmax, drule);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The contact term's energy at u: (1/2eps) int [u_n - g]_+^2 with the rule of the penalty term, 0 for the others. */
PetscErrorCode ContactEnergy(Contact ct, DM dm, Vec u, PetscReal *energy)
{
  PetscFunctionBeginUser;
  *energy = 0.0;
  if (ct->ops.energy) PetscCall((*ct->ops.energy)(ct, dm, u, energy));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The contact outputs, every one from the force the rule exerts, for every type, rule and obstacle:
   - the reaction of the obstacle at node i is -R_i . n with R = K u + r0 the bulk residual (the caller's, K the bulk
     operator, not the penalty Jacobian): the nodal contact force
     (the penalty term's at a converged penalty solve, the multiplier of SNESVI's bound);
   - the pressure is that reaction over the lumped boundary mass (the area the node stands for), where the contact acts
     (penalty: where the rule's force is positive, exactly zero elsewhere; SNESVI: everywhere), so that the sum of
     pressure times contact_area is the contact force up to the reactions of the nodes where nothing acts, round-off
     with a direct solver, the linear solver's tolerance with an iterative one. With the Gauss rule it is the face integral of
     (1/eps)[u_n - g]_+ against the node's basis function over that of the basis function: a curved obstacle touching
     the faces between their vertices has a pressure where it pushes, not the nodal penalty law's zero;
   - the active vertices are those where the rule acts (the penalty term's nodal force is positive: a Gauss point of
     one of its faces penetrates, or the node itself with the nodal rule; on the bound with SNESVI);
   - the penetration is the largest of the nodes' and the rule's points';
   - SNESVI's active vertices are those within 1e-10 tol_scale of their bound (tol_scale: the size of the displacement).
   The pressure and the reaction of each node are kept in the contact set, for the output. */
PetscErrorCode ContactPostProcess(Contact ct, DM dm, Vec R, Vec u, PetscReal tol_scale, ContactResult *res)
{
  ContactSet        *cs  = &ct->set;
  const PetscInt     dim = ct->dim;
  const PetscScalar *x, *r;
  PetscReal          local[5] = {0.0, 0.0, 0.0, 0.0, 0.0}, global[5], drule = -PETSC_MAX_REAL;
  PetscBool         *acts;
  PetscInt           nacts = 0;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc1(cs->n + 1, &acts));
  for (PetscInt i = 0; i < cs->n; ++i) acts[i] = PETSC_TRUE;
  if (ct->ops.acts) PetscCall((*ct->ops.acts)(ct, dm, u, acts, &drule));
  PetscCall(VecGetArrayRead(u, &x));
  PetscCall(VecGetArrayRead(R, &r));
  for (PetscInt i = 0; i < cs->n; ++i) {
    const PetscReal d        = ContactNodePenetration(cs, dim, i, x);
    PetscReal       reaction = 0.0; /* along the free components: a fixed one takes its reaction from its boundary condition */

    for (PetscInt c = 0; c < dim; ++c)
      if (cs->dof[i * dim + c] >= 0) {
        reaction -= PetscRealPart(r[cs->dof[i * dim + c]]) * cs->normal[i * dim + c];
        local[2 + c] += PetscRealPart(r[cs->dof[i * dim + c]]); /* the obstacle's force on the body: R = K u + r0 */
      }
    cs->reaction[i] = reaction;
    cs->pressure[i] = acts[i] && cs->weight[i] > 0.0 ? reaction / cs->weight[i] : 0.0;
    nacts += acts[i] && cs->is_vertex[i];
    local[0] = PetscMax(local[0], d);
    local[1] += reaction;
  }
  PetscCall(VecRestoreArrayRead(R, &r));
  PetscCall(VecRestoreArrayRead(u, &x));
  PetscCall(MPIU_Allreduce(&local[0], &global[0], 1, MPIU_REAL, MPIU_MAX, ct->comm));
  PetscCall(MPIU_Allreduce(&local[1], &global[1], 4, MPIU_REAL, MPIU_SUM, ct->comm));
  for (PetscInt c = 0; c < 3; ++c) res->force_vector[c] = global[2 + c];
  res->force           = global[1];
  res->max_penetration = PetscMax(global[0], drule);
  if (ct->ops.acts)
    PetscCall(MPIU_Allreduce(&nacts, &res->active_vertices, 1, MPIU_INT, MPI_SUM, ct->comm));
  else
    PetscCall(ContactCountActive(ct, u, tol_scale, PETSC_FALSE, &res->active_vertices, NULL, NULL));
  PetscCall(PetscFree(acts));
  PetscCall(ContactEnergy(ct, dm, u, &res->energy));
  if (ct->ops.check) PetscCall((*ct->ops.check)(ct, dm, u));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The contact the mesh does not see: the nodes of Gamma_C that penetrate the obstacle while the rule exerts (almost) no
   force on them, after ContactPostProcess(). On a mesh coarse against the contact zone the Gauss rule's points fall
   outside the zone (a rigid cylinder indenting a block meshed at h = 0.5 by 0.001: a zone 0.017 wide, the nearest
   point 0.1 from the axis): the discrete problem has no contact there, its solution and its error estimate are zero.
   A node the rule sees has the penalty's pressure d / eps_i at its penetration d, or more; an unseen one has less than
   CONTACT_UNSEEN_FRACTION of it. unseen[i] (NULL: not asked) flags this rank's nodes, *count is over all ranks.
   *force (NULL: not asked) is the force the penalty law would put on them, the sum of w_i d_i / eps_i (w_i the node's
   lumped area): what the solution misses there, to first order. That weighs an unseen node: on the coarse block it is
   the whole force (the rule's force is zero); at the edge of a resolved zone, where a node penetrates by a hundredth of
   the largest penetration between two of the rule's points, it is a negligible part (docs/decisions.md, "The nodes
   the rule does not see"). SNESVI and no contact see every node: none. */
#define CONTACT_UNSEEN_FRACTION 1e-2

PetscErrorCode ContactUnseenNodes(Contact ct, Vec u, PetscBool unseen[], PetscInt *count, PetscReal *force)
{
  const ContactSet  *cs = &ct->set;
  const PetscScalar *x;
  PetscInt           local       = 0;
  PetscReal          local_force = 0.0;

  PetscFunctionBeginUser;
  for (PetscInt i = 0; i < cs->n && unseen; ++i) unseen[i] = PETSC_FALSE;
  if (ct->has_penalty) {
    PetscCall(VecGetArrayRead(u, &x));
    for (PetscInt i = 0; i < cs->n; ++i) {
      const PetscReal d = ContactNodePenetration(cs, ct->dim, i, x), eps = ContactNodeEps(cs, ct->eps, i);

      if (!(d > 0.0) || cs->pressure[i] >= CONTACT_UNSEEN_FRACTION * d / eps) continue;
      ++local;
      local_force += cs->weight[i] * d / eps;
      if (unseen) unseen[i] = PETSC_TRUE;
    }
    PetscCall(VecRestoreArrayRead(u, &x));
  }
  if (force) PetscCall(MPIU_Allreduce(&local_force, force, 1, MPIU_REAL, MPIU_SUM, ct->comm));
  PetscCall(MPIU_Allreduce(&local, count, 1, MPIU_INT, MPI_SUM, ct->comm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The method's part of /run: its type, rule and eps modulus, eps and its range over Gamma_C (0 for the types without
   eps), the contact nodes (the free nodes of Gamma_C, each counted once), and -contact_penetration_tol where given. */
PetscErrorCode ContactWrite(Contact ct, PetscViewer v)
{
  PetscReal eps_min, eps_max;
  PetscInt  n = ct->set.n, ntotal;

  PetscFunctionBeginUser;
  PetscCall(ContactGetEpsRange(ct, &eps_min, &eps_max, NULL));
  PetscCall(RunAttrString(v, ct->type, "method"));
  PetscCall(RunAttrString(v, PenaltyQuadratures[ct->opt.quadrature], "penalty_quadrature"));
  PetscCall(RunAttrString(v, PenaltyModuli[ct->opt.modulus], "penalty_eps_modulus"));
  PetscCall(RunAttrReal(v, ct->eps, "eps"));
  PetscCall(RunAttrReal(v, eps_min, "eps_min"));
  PetscCall(RunAttrReal(v, eps_max, "eps_max"));
  PetscCall(MPIU_Allreduce(&n, &ntotal, 1, MPIU_INT, MPI_SUM, ct->comm));
  PetscCall(RunAttrInt(v, ntotal, "contact_nodes"));
  if (ct->opt.penetration_tol > 0.0) PetscCall(RunAttrReal(v, ct->opt.penetration_tol, "penetration_tol"));
  PetscFunctionReturn(PETSC_SUCCESS);
}
