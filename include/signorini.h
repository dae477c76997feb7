/* Penalty and SNESVI solver for the frictionless Signorini problem (Chouly & Hild 2013). */
#pragma once
#include <petscdmplex.h>
#include <petscds.h>
#include <petscsnes.h>

#include "compat.h"

/* Index map of constants[] as every pointwise kernel sees it. */
typedef enum {
  CONST_LAMBDA,          /* first Lame parameter */
  CONST_MU,              /* shear modulus */
  CONST_PENALTY,         /* 1/eps (0 when there is no penalty term) */
  CONST_NORMAL_X,        /* outward unit normal of the rigid foundation plane, */
  CONST_NORMAL_Y,        /*   seen from the body: u_n = u . n */
  CONST_NORMAL_Z,        /*   (3rd component unused in 2D) */
  CONST_OBSTACLE_OFFSET, /* foundation plane {x : x . n = offset}; gap g(x) = offset - x . n */
  CONST_SCENE,           /* first of the scene's own constants */
  CONST_SCENE_MAX = CONST_SCENE + 8
} ConstantIndex;

typedef enum { CONTACT_PENALTY, CONTACT_VI, CONTACT_NONE } ContactMethod;
extern const char *const ContactMethods[];
typedef enum { PENALTY_QUADRATURE_GAUSS, PENALTY_QUADRATURE_NODAL } PenaltyQuadrature;
extern const char *const PenaltyQuadratures[];

typedef struct {
  PetscReal young_modulus, poisson_ratio;
  PetscReal lambda, mu;
} Material;

/* Pointwise function with PETSc's signature for boundary values and exact solutions. */
typedef PetscErrorCode (*ScenePointFn)(PetscInt dim, PetscReal t, const PetscReal x[], PetscInt Nc, PetscScalar u[], void *ctx);

/* What a scene (a problem set-up) provides; filled by its SceneCreate_* function. */
typedef struct {
  char           name[64];
  PetscInt       contact_id;    /* "Face Sets" value of Gamma_C */
  PetscInt       num_dirichlet; /* "Face Sets" values of Gamma_D (clamped or prescribed) */
  PetscInt       dirichlet_ids[6];
  ScenePointFn   dirichlet_value; /* NULL: clamped, u = 0; called with ctx = constants */
  PetscPointFunc f0_body;         /* volume residual term, -f; NULL: no body force */
  PetscReal      obstacle_normal[3];
  PetscReal      obstacle_offset;
  ScenePointFn   exact;         /* exact solution, NULL if none; called with ctx = constants */
  PetscInt       num_constants; /* scene constants, stored from constants[CONST_SCENE] on */
  PetscScalar    constants[CONST_SCENE_MAX - CONST_SCENE];
} Scene;

typedef PetscErrorCode (*SceneCreateFn)(DM dm, const Material *mat, Scene *scene);

/* Options of the contact treatment and the penalty parameter. */
typedef struct {
  ContactMethod     method;
  PenaltyQuadrature quadrature;
  PetscReal         eps0, eps_power, eps_fixed; /* eps = eps0 h^power / E, or eps_fixed when > 0 */
  PetscBool         monitor;
} ContactOptions;

/* The nodes of Gamma_C owned by this rank and free to move: the unknowns the contact acts on. */
typedef struct {
  PetscInt   n;
  PetscInt  *point;      /* DMPlex point holding the node */
  PetscInt  *global_off; /* offset of its first component in the global vector (ownership start subtracted) */
  PetscBool *is_vertex;
  PetscReal *gap;      /* g = offset - x . n at the node */
  PetscReal *weight;   /* lumped boundary mass, the integral of the node's basis function over Gamma_C */
  PetscBool *active;   /* active set at the last monitor call */
  PetscReal *pressure; /* contact pressure -sigma_n at the node, after the solve */
} ContactSet;

typedef struct {
  PetscInt            newton_its, ksp_its;
  PetscBool           converged;
  SNESConvergedReason reason;
  PetscReal           residual_norm;
  PetscReal           time_setup, time_solve, time_total;
  PetscInt            active_vertices;
  PetscReal           max_penetration, contact_force, energy;
} RunStats;

typedef struct {
  char           scene_name[64];
  char           output[PETSC_MAX_PATH_LEN];
  Scene          scene;
  Material       material;
  ContactOptions contact;
  PetscReal      h, eps;
  PetscInt       degree;
  ContactSet     cset;
  DMLabel        face_sets;
  PetscWeakForm  wf_penalty; /* the penalty term on Gamma_C, kept out of the bulk weak form */
  Mat            K;          /* bulk elastic operator, assembled once */
  Vec            r0;         /* bulk residual at u = 0 (loads and Dirichlet lifting) */
  Vec            xl, xu;     /* SNESVI bounds */
  RunStats       stats;
} AppCtx;

/* scenes/registry.c */
PetscErrorCode SceneRegisterAll(void);
PetscErrorCode SceneFinalize(void);
PetscErrorCode SceneCreate(const char name[], DM dm, const Material *mat, Scene *scene);
PetscErrorCode SceneGetOptions(MPI_Comm comm, char name[], size_t len);
PetscErrorCode SceneCreate_Square(DM, const Material *, Scene *);
PetscErrorCode SceneCreate_Patch(DM, const Material *, Scene *);

/* mesh.c, mesh_box_simplex.c */
PetscErrorCode MeshCreate(MPI_Comm comm, DM *dm);
PetscErrorCode MeshCreateSimplexBox(MPI_Comm comm, PetscInt dim, const PetscInt faces[], const PetscReal lower[], const PetscReal upper[], DM *dm);
PetscErrorCode MeshLabelBoxFaces(DM dm, const PetscReal lower[], const PetscReal upper[]);
PetscErrorCode MeshGetMaxCellDiameter(DM dm, PetscReal *h);
PetscErrorCode MeshCheckContactBoundary(DM dm, PetscInt contact_id);

/* elasticity.c */
PetscErrorCode ElasticityGetOptions(MPI_Comm comm, Material *mat);
PetscErrorCode ElasticitySetUpDiscretization(DM dm, AppCtx *user);
PetscErrorCode ElasticityUpdateConstants(DM dm, AppCtx *user);

/* contact_options.c, contact_set.c */
PetscErrorCode ContactGetOptions(MPI_Comm comm, ContactOptions *opts);
PetscErrorCode ContactComputeEps(AppCtx *user);
PetscErrorCode ContactSetCreate(DM dm, AppCtx *user, ContactSet *cs);
PetscErrorCode ContactSetDestroy(ContactSet *cs);

/* Penetration u_n - g of contact node i, from the owned part x[] of a global vector. */
static inline PetscReal ContactNodePenetration(const AppCtx *user, PetscInt dim, PetscInt i, const PetscScalar x[])
{
  PetscReal un = 0.0;

  for (PetscInt c = 0; c < dim; ++c) un += PetscRealPart(x[user->cset.global_off[i] + c]) * user->scene.obstacle_normal[c];
  return un - user->cset.gap[i];
}

/* penalty.c */
PetscErrorCode PenaltySetUp(DM dm, AppCtx *user);
PetscErrorCode PenaltyAddResidual(DM dm, AppCtx *user, Vec X, Vec F);
PetscErrorCode PenaltyAddJacobian(DM dm, AppCtx *user, Vec X, Mat J);
PetscErrorCode PenaltyEnergy(DM dm, AppCtx *user, Vec X, PetscReal *energy);

/* vi_bounds.c */
PetscErrorCode VICreateBounds(DM dm, AppCtx *user);

/* solver.c */
PetscErrorCode SolverAssembleBulk(DM dm, AppCtx *user);
PetscErrorCode SolverCreateSNES(DM dm, AppCtx *user, SNES *snes);
PetscErrorCode SolverSolve(SNES snes, AppCtx *user, Vec u);
PetscErrorCode SolverBulkResidual(AppCtx *user, Vec X, Vec R);

/* contact_monitor.c */
PetscErrorCode ContactMonitor(SNES snes, PetscInt it, PetscReal fnorm, void *ctx);
PetscErrorCode ContactCountActive(AppCtx *user, Vec X, PetscBool update, PetscInt *active, PetscInt *entered, PetscInt *left);

/* postprocess.c */
PetscErrorCode PostprocessContact(DM dm, AppCtx *user, Vec u);

/* output_hdf5.c */
PetscErrorCode OutputGetOptions(MPI_Comm comm, AppCtx *user);
PetscErrorCode OutputWriteHDF5(DM dm, AppCtx *user, Vec u);
