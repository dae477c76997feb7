/* Penalty and SNESVI solver for the frictionless Signorini problem (Chouly & Hild 2013): the shared types (the
   constants[] index map, options, scene, contact set, run statistics, AppCtx). Each module declares its functions in
   its own header: app.h, scenes.h, mesh.h, physics.h, solver.h, verify.h, io.h. */
#pragma once
#include <petscdmplex.h>
#include <petscds.h>
#include <petscsnes.h>

#include "compat.h"

/* Parameters of the rigid obstacle, packed in this order (constants[CONST_OBSTACLE + k], ObstaclePack() in obstacle.h). */
enum {
  OBSTACLE_TYPE,  /* ObstacleType */
  OBSTACLE_POINT, /* plane: a point of it; sphere, cylinder: the center; cone: the apex (x, y, z), translation included */
  OBSTACLE_DIRECTION =
      OBSTACLE_POINT + 3, /* plane: unit normal from the body into the obstacle; cylinder: unit axis; cone: unit axis from the apex into it */
  OBSTACLE_RADIUS = OBSTACLE_DIRECTION + 3,
  OBSTACLE_CONE_SIN, /* cone: the sine and cosine of its half-angle */
  OBSTACLE_CONE_COS,
  OBSTACLE_EDGE_RADIUS, /* punch: the radius of the fillet that rounds its edge (0: a sharp edge) */
  OBSTACLE_NUM_PARAMS
};

/* Index map of constants[] as every pointwise kernel sees it. */
typedef enum {
  CONST_LAMBDA,                                            /* first Lame parameter */
  CONST_MU,                                                /* shear modulus */
  CONST_PENALTY,                                           /* 1/eps (0 when there is no penalty term) */
  CONST_OBSTACLE,                                          /* the obstacle's parameters, OBSTACLE_NUM_PARAMS of them */
  CONST_BODY_FORCE = CONST_OBSTACLE + OBSTACLE_NUM_PARAMS, /* constant body force (x, y, z), -body_force */
  CONST_LOAD       = CONST_BODY_FORCE + 3,                 /* the surface load being assembled: traction (x, y, z), or pressure p */
  CONST_SCENE      = CONST_LOAD + 3,                       /* first of the scene's own constants */
  CONST_SCENE_MAX  = CONST_SCENE + 8
} ConstantIndex;

#define CONTACT_HISTORY 256 /* Newton steps whose active sets are kept for the cycle detection */
typedef enum { PENALTY_QUADRATURE_GAUSS, PENALTY_QUADRATURE_NODAL } PenaltyQuadrature;
extern const char *const PenaltyQuadratures[];
typedef enum { ASSEMBLY_AUTO, ASSEMBLY_FE, ASSEMBLY_P1 } AssemblyType; /* -assembly: how the bulk matrix K is assembled */
extern const char *const AssemblyTypes[];
typedef enum { PENALTY_MODULUS_YOUNG, PENALTY_MODULUS_PWAVE } PenaltyModulus; /* the stiffness M of eps = eps0 h^power / M */
extern const char *const PenaltyModuli[];

typedef struct {
  PetscReal young_modulus, poisson_ratio;
  PetscReal lambda, mu;
} Material;

/* Pointwise function with PETSc's signature for boundary values and exact solutions. */
typedef PetscErrorCode (*ScenePointFn)(PetscInt dim, PetscReal t, const PetscReal x[], PetscInt Nc, PetscScalar u[], void *ctx);

/* Boundary conditions by "Face Sets" value (-bc_clamp, -bc_slip, -bc_traction, -bc_pressure). */
typedef enum { BC_CLAMP, BC_SLIP, BC_TRACTION, BC_PRESSURE, BC_NUM_KINDS } BoundaryKind;
extern const char *const BoundaryKinds[];
#define BOUNDARY_MAX 32 /* face sets per family, and boundary conditions in all */
typedef struct {
  BoundaryKind kind;
  PetscInt     id;              /* "Face Sets" value */
  char         token[64];       /* as given: the number, or the name of the Gmsh physical group */
  PetscInt     ncomp, comps[3]; /* clamp, slip: the fixed components */
  PetscReal    value[3];        /* clamp, slip: the prescribed displacement; traction: force per unit area; pressure: p = value[0] */
  ScenePointFn fn;              /* clamp: the scene's own displacement instead of value (NULL: value); called with ctx = constants */
} BoundaryCondition;

typedef struct {
  PetscInt          n;
  BoundaryCondition bc[BOUNDARY_MAX];
  PetscInt          ncontact; /* Gamma_C: one or more face sets (-contact_faces) */
  PetscInt          contact_ids[BOUNDARY_MAX];
  char              contact_tokens[BOUNDARY_MAX][64];
  PetscReal         body_force[3]; /* -body_force */
} BoundarySet;

/* The rigid obstacle (-obstacle plane | sphere | cylinder | cone | punch). */
typedef enum { OBSTACLE_PLANE, OBSTACLE_SPHERE, OBSTACLE_CYLINDER, OBSTACLE_CONE, OBSTACLE_PUNCH } ObstacleType;
extern const char *const ObstacleTypes[];
typedef struct {
  ObstacleType type;
  PetscReal    point[3];     /* plane: a point of it; sphere, cylinder: the center; cone: the apex */
  PetscReal    direction[3]; /* plane: unit normal from the body into the obstacle; cylinder: unit axis (3D); cone: unit axis from the apex into it */
  PetscReal    radius;
  PetscReal    half_angle;   /* cone: the angle between its axis and its surface, in degrees (in 2D a wedge) */
  PetscReal    edge_radius;  /* punch: the fillet's radius at the edge of its flat end of radius `radius` (0: a sharp edge) */
  PetscReal    translate[3]; /* rigid translation of the obstacle (-obstacle_translate) */
  PetscReal    force;        /* -obstacle_force: the force it presses with along the translation's direction (0: driven by the translation) */
} Obstacle;

/* What a scene (a problem set-up) provides: its defaults of the boundary and obstacle options, filled by its
   SceneCreate_* function, then the options themselves (scenes/boundary_options.c, scenes/obstacle_options.c). */
typedef struct {
  char           name[64];
  BoundarySet    bcs;
  Obstacle       obstacle;
  PetscPointFunc f0_body;        /* volume residual term, -f, if not constant; it adds the -body_force of constants[] */
  ScenePointFn   exact;          /* exact solution, NULL if none; called with ctx = constants */
  ScenePointFn   exact_gradient; /* its gradient, G[i*dim+j] = du_i/dx_j (Nc = dim*dim); needed for the error norms */
  PetscBool      weak_data;      /* load from the exact solution: L(v) = a(u_exact, v) - int_Gamma_C sigma_n(u_exact) v_n */
  PetscBool      has_kink;       /* the exact solution is not smooth across the plane {x . kink_normal = kink_offset}: */
  PetscReal      kink_normal[3]; /*   the cells it cuts get the refined quadrature rule */
  PetscReal      kink_offset;
  PetscInt       num_constants; /* scene constants, stored from constants[CONST_SCENE] on */
  PetscScalar    constants[CONST_SCENE_MAX - CONST_SCENE];
  PetscBool      load_constant[CONST_SCENE_MAX - CONST_SCENE]; /* the scene's constants that are loads (a body force's size) */
  struct {                                                     /* the prescribed data at the factor 1, kept by SceneSetLoadFactor() */
    PetscBool   kept;
    PetscReal   value[BOUNDARY_MAX][3], body_force[3], translate[3], force;
    PetscScalar constants[CONST_SCENE_MAX - CONST_SCENE];
  } full_load;
} Scene;

typedef PetscErrorCode (*SceneCreateFn)(DM dm, const Material *mat, Scene *scene);

/* Options of the contact treatment and the penalty parameter (read by ContactSetFromOptions(), include/contact.h). */
typedef struct {
  char              method[64]; /* the Contact type, -contact_method */
  PenaltyQuadrature quadrature;
  PetscReal         eps0, eps_power, eps_fixed; /* eps = eps0 h^power / M, or eps_fixed when > 0 */
  PetscBool         eps_local;                  /* h of each contact face (Gauss) or node (nodal), not of the whole mesh */
  PenaltyModulus    modulus;                    /* M = E (young) or lambda + 2 mu (pwave) */
  PetscBool         continuation;               /* reach an eps below h/M through a sequence of larger ones */
  PetscReal         continuation_factor;        /* ratio of two consecutive eps of the sequence, in (0, 1) */
  PetscReal        *eps0_sweep;                 /* eps0 values solved in turn on the final mesh, each from the last solution (any number) */
  PetscInt          n_sweep;
  PetscReal         penetration_tol; /* the largest penetration allowed: eps lowered from the measured one until then (0: none) */
} ContactOptions;

/* PETSc's own options whose presence changes the project's defaults ("where the options say nothing"), read with the
   rest in the options phase (SolverGetOptions()), for each options prefix the solver's objects can have: the solve's
   KSP (no prefix) and the coarser boxes' KSP ("contact_coarse_", src/linear/multigrid.c). */
#define SOLVER_KSP_PREFIXES 2
#define MULTIGRID_MAX_LEVELS 16 /* levels of a multigrid preconditioner the solver follows */
typedef struct {
  PetscBool mat_type;                               /* -mat_type */
  PetscBool snes_ksp_ew, snes_ksp_ew_rtolmax;       /* -snes_ksp_ew, -snes_ksp_ew_rtolmax */
  PetscBool pc_type_given;                          /* -pc_type, */
  char      pc_type[64];                            /*   its value */
  PetscBool ksp_norm_type[SOLVER_KSP_PREFIXES];     /* -ksp_norm_type */
  PetscBool use_initial_rnorm[SOLVER_KSP_PREFIXES]; /* -ksp_converged_use_initial_residual_norm */
  PetscBool pc_mg_levels[SOLVER_KSP_PREFIXES];      /* -pc_mg_levels */
  PetscBool pc_mg_galerkin[SOLVER_KSP_PREFIXES];    /* -pc_mg_galerkin */
  PetscBool fine_ksp_type[SOLVER_KSP_PREFIXES];     /* -mg_fine_ksp_type */
  PetscBool fine_pc_type[SOLVER_KSP_PREFIXES];      /* -mg_fine_pc_type */
  /* -ksp_chebyshev_esteig of each multigrid smoother's prefix: mg_fine_, and mg_levels_N_ (PETSc's name of level N, which
     also finds -mg_levels_ksp_chebyshev_esteig), under each KSP prefix */
  char      esteig_prefix[SOLVER_KSP_PREFIXES * (MULTIGRID_MAX_LEVELS + 1)][48];
  PetscInt  esteig_n[SOLVER_KSP_PREFIXES * (MULTIGRID_MAX_LEVELS + 1)]; /* how many values (0: not given) */
  PetscReal esteig[SOLVER_KSP_PREFIXES * (MULTIGRID_MAX_LEVELS + 1)][4];
} SolverGiven;

/* Options of the nonlinear solve around the contact (SolverGetOptions(), src/linear/solver_options.c). */
typedef struct {
  SolverGiven given;
  PetscBool   monitor;
  PetscBool   condition_estimate; /* estimate the 1-norm condition number of the final Jacobian */
  PetscBool   cycle_damping;      /* damp the Newton step when the active set cycles */
  PetscBool   pc_reuse;           /* reuse the preconditioner/factorization while few contact nodes change */
  PetscInt    pc_reuse_changes;   /*   at most this many changed nodes since the build */
  PetscBool   pc_recovery;        /* go on after a preconditioner breakdown (pc_recovery.c) */
  PetscBool   pc_update;          /* multigrid (GAMG): the coarse operators follow the Jacobian instead of rebuilds */
  PetscBool   pc_update_check;    /*   and each update is compared with the full Galerkin products */
  PetscBool   pc_update_esteig;   /*   and the finest smoother estimates its eigenvalues again at each update */
  PetscReal   pc_update_truncate; /*   and the coarse spaces leave out the contact dofs whose penalty exceeds this times K's diagonal (0: none) */
  PetscInt    pc_update_changes;  /*   and the coarse operators stay while at most this many contact nodes changed since they followed (0: never) */
  PetscInt    grid_sequence;      /* solve on the mesh and on this many uniform refinements of it, each from the last */
  PetscInt    coarse_levels;      /* nested iteration to the mesh: this many coarser boxes solved first (-1: automatic) */
  PetscReal   coarse_rtol;        /*   Newton's relative tolerance there */
  PetscBool   coarse_mg;          /*   -contact_coarse_mg as given; whether it applies is GridSequenceCoarseRequest()'s answer */
  PetscReal   ew_guard;           /* Eisenstat-Walker's terms no smaller than this times Newton's target / |F| */
  PetscReal   load_rtol;          /* Newton also stops when |F| <= load_rtol ||F(0)||: the residual is at round-off for the load */
} SolverOptions;

/* The nodes of Gamma_C owned by this rank with at least one free component: the unknowns the contact acts on. */
typedef struct {
  PetscInt   n;
  PetscInt  *point;      /* DMPlex point holding the node */
  PetscInt  *global_off; /* offset of its first free component in the global vector (ownership start subtracted) */
  PetscInt  *dof;        /* [n][dim]: offset of each component in the global vector (ownership start subtracted), -1 if fixed */
  PetscReal *fixed;      /* [n][dim]: the prescribed value of each fixed component (0 for the free ones) */
  PetscReal *normal;     /* [n][dim]: unit normal from the body into the obstacle at the node's undeformed position */
  PetscBool *is_vertex;
  PetscReal *gap;        /* g: distance from the node to the obstacle along the normal (negative: initial penetration) */
  PetscReal *eps_factor; /* the node's eps over the run's eps: (h_node / h)^power, h_node the largest cell at its contact faces */
  PetscReal *weight;     /* lumped boundary mass, the integral of the node's basis function over Gamma_C */
  PetscBool *active;     /* active set at the last monitor call */
  PetscReal *pressure;   /* contact pressure -sigma_n at the node, after the solve */
  PetscReal *reaction;   /* normal reaction force of the obstacle on the node, -R . n with R = K u + r0, after the solve */
} ContactSet;

/* Accurate integration for the verification: Gauss points per direction, and how many times the reference
   cell is refined for the composite rule on the cells cut by a scene's kink. */
typedef struct {
  PetscInt  quad_points, quad_refine;
  char      reference[PETSC_MAX_PATH_LEN]; /* -reference FILE.h5, "" if none */
  PetscBool dmsnes_check;
} VerifyOptions;

/* Error norms of a run against the exact solution or a reference solution (NaN: not computed). */
typedef struct {
  PetscReal l2, h1_semi, h1, energy;         /* of u - u_h over Omega */
  PetscReal pressure_l2, pressure_weighted;  /* of R = sigma_n(u) + p_h on Gamma_C; weighted by eps^1/2 (h^1/2 for vi) */
  PetscReal pressure_dual;                   /* H^-1/2(Gamma_C) dual norm of R, by one elastic solve */
  PetscReal penetration_l2, penetration_max; /* of [u_h,n - g]_+ on Gamma_C */
} ErrorNorms;

/* The a posteriori estimate of the energy-norm error of a run (src/estimate/), by part: each part is the square root
   of the sum over the cells of its squared indicators, and the total that of the sum of the parts' squares. */
typedef enum {
  ESTIMATE_BULK,               /* h_T ||f + div sigma(u_h)||_T: the body force left unbalanced inside the cells */
  ESTIMATE_JUMP,               /* h_F^1/2 ||[sigma(u_h) n]||_F: the stress jumps across the interior faces */
  ESTIMATE_NEUMANN,            /* h_F^1/2 ||t - sigma(u_h) n||_F on the loaded and free faces (the free components of a slip) */
  ESTIMATE_CONTACT_NORMAL,     /* h_F^1/2 ||sigma_n(u_h) + p_h||_F on Gamma_C, p_h the contact pressure of the method */
  ESTIMATE_CONTACT_TANGENTIAL, /* h_F^1/2 ||sigma_t(u_h)||_F on Gamma_C (frictionless) */
  ESTIMATE_PENALTY,            /* the penalty's consistency error, from the penetration [u_h,n - g]_+ = eps p_h */
  ESTIMATE_NUM_PARTS
} EstimatePart;
extern const char *const EstimateParts[];
typedef struct {
  PetscBool  computed;
  char       unavailable[160]; /* why there is no estimate ("" if computed or not asked for) */
  PetscReal  total, part[ESTIMATE_NUM_PARTS];
  PetscReal  norm;    /* the energy norm of u_h, a(u_h, u_h)^1/2, the scale of the relative estimate total / norm */
  PetscInt   ncells;  /* the local cells, */
  PetscReal *cell;    /*   the indicator eta_T of each: the square root of the sum of its parts' squares */
  PetscReal *density; /*   and eta_T / |T|^1/2, the error's level per unit volume, comparable across cells of any size */
  PetscReal  time;
} ErrorEstimate;

/* The mesh of the options as MeshCreate() made it: the simplex box, when it is one (the grid sequence builds its finer
   levels directly), or a file and what its boundary is. */
typedef struct {
  PetscBool is_box;        /* a simplex box (2D or 3D) not refined by -dm_refine, on one rank or in slabs of rows that nest */
  PetscInt  dim, faces[3]; /* faces: of the mesh built first, the coarsest box when coarse_levels > 0 */
  PetscInt  coarse_levels; /* the mesh of the options is this many box doublings above the one built first */
  PetscInt  slab_rows;     /* several ranks: each box's slabs are whole rows of the box built first, of this many rows (0: one rank) */
  PetscReal lower[3], upper[3];
  PetscBool from_file;     /* the mesh of the options was read from a file (-dm_plex_filename) */
  PetscInt  refine;        /*   refined this many times by -dm_refine */
  PetscInt  curved_ridges; /*   whose boundary turns by a small angle at this many ridges: a curved boundary's chords (MeshCountCurvedRidges()) */
  PetscReal curved_x[3];   /*   one of them */
  PetscBool petsc_read;    /* -mesh_remeshed_petsc_read: each remeshed mesh written by Gmsh, read by PETSc's reader (mesh_gmsh_build.c) */
} MeshBox;

/* How the mesh is distributed over the ranks (-partitioner), and the quality of the partition. */
typedef enum { MESH_PARTITIONER_PTSCOTCH, MESH_PARTITIONER_METIS, MESH_PARTITIONER_SIMPLE, MESH_PARTITIONER_BOX } MeshPartitionerType;
extern const char *const MeshPartitionerTypes[];
typedef struct {
  MeshPartitionerType partitioner;
  PetscInt            edge_cut;  /* interior faces whose two cells are on different ranks (-1: uninterpolated mesh) */
  PetscReal           imbalance; /* max cells per rank / mean cells per rank (1: perfect, and on one rank) */
  PetscInt            cells_max; /* cells on the most loaded rank */
} MeshPartitionStats;

/* -perf_bandwidth (src/solver/bandwidth.c): achieved memory bandwidths in GB/s, summed over ranks. */
typedef struct {
  PetscBool measured;
  PetscReal triad_gbs;              /* STREAM-like triad */
  PetscReal matmult_gbs, matmult_s; /* MatMult with the final Jacobian, and its time */
  PetscReal vcycle_gbs, vcycle_s;   /* one application of its preconditioner (a PCMG; NaN otherwise) */
} Bandwidth;

/* Checks of the contact set-up and of the contact zone's resolution (src/physics/contact_checks.c): warnings only. */
#define CONTACT_CHECK_OVERLAP_CELLS 1.0 /* an initial overlap deeper than this many cells */
#define CONTACT_CHECK_OVERLAP_RATIO 0.1 /*   and than this part of the overlapped part's width is warned of */
#define CONTACT_CHECK_OVERLAP_CONE 2.5  /*   a cone's: this many times the ratio its own indentation gives (a quarter model doubles it) */
#define CONTACT_CHECK_ZONE_CELLS_2D 4.0 /* a contact zone spanning fewer cells is warned of (bench/zone_resolution.md) */
#define CONTACT_CHECK_ZONE_CELLS_3D 6.0 /*   in 3D (bench/zone_resolution_3d.md) */
#define CONTACT_CHECK_STRIP_ASPECT 3.0  /* a 3D zone this many times longer than wide is a strip, a line contact: the 2D threshold */
#define CONTACT_CHECK_UNSEEN_SHARE 1e-3 /* unseen contact is warned of where the penalty law would put this part of the force on it */
#define MESH_CURVED_RIDGES_MIN 3        /* a mesh file's boundary turning by a small angle at this many ridges is curved (MeshCountCurvedRidges()) */
#define CONTACT_CHECK_LOCKING_NU 0.45   /* P1/Q1 with a Poisson ratio from this one on is warned of (scripts/incompressible.py) */
typedef struct {
  PetscBool geometry_checked, resolution_checked;
  PetscReal overlap_cells;       /* largest initial overlap -g/h at Gamma_C's vertices, h the diameter of the face's cell */
  PetscReal overlap_fraction;    /* part of Gamma_C's area whose faces start inside the obstacle (g < 0 at the centroid) */
  PetscReal overlap_ratio;       /* largest initial overlap -g over the width of that part: its length in 2D, 2 sqrt(area / pi) in 3D */
  PetscReal overlap_ratio_limit; /* a larger ratio is warned of: CONTACT_CHECK_OVERLAP_RATIO, or more for a cone (ContactChecksGeometry()) */
  PetscReal away_fraction;       /* part of Gamma_C's area where the obstacle's normal points into the body */
  PetscInt  zone_faces;          /* faces of Gamma_C whose every node carries contact force */
  PetscReal zone_cells;          /* cells across the contact zone: zone_faces in 2D, sqrt(2 zone_faces / pi) in 3D */
  PetscReal zone_limit;          /* fewer cells are warned of: CONTACT_CHECK_ZONE_CELLS_2D or _3D */
  PetscReal zone_width_cells;    /* 3D: the zone's narrowest width in cells (a strip's), from its faces' second moments */
  PetscBool zone_pressed;        /* some node of Gamma_C carries contact force (the zone may span no whole face) */
  PetscBool zone_strip;          /* 3D: the zone is CONTACT_CHECK_STRIP_ASPECT times longer than wide, a line contact */
  PetscInt  unseen_nodes;        /* contact nodes that penetrate while the rule exerts no force on them (ContactUnseenNodes()), */
  PetscReal unseen_force;        /*   the force the penalty law would put on them, */
  PetscReal unseen_share;        /*   and its part of the force's magnitude (PETSC_INFINITY where the force is zero) */
  PetscInt  curved_refined;      /* a mesh file's curved boundary (MeshBox.curved_ridges) that the solver refined on its chords: its ridges, */
  PetscInt  curved_refinements;  /*   the refinements (-dm_refine and -contact_grid_sequence), */
  PetscReal curved_x[3];         /*   and one of the ridges */
  PetscReal locking_nu;          /* the Poisson ratio of a P1/Q1 body from CONTACT_CHECK_LOCKING_NU on (0: none), */
  PetscReal locking_eps_ratio;   /*   and with the penalty's eps from E, (lambda + 2 mu) / E (0 otherwise) */
} ContactChecks;

/* The quantities users read of a solution (PostprocessContact()), whose error bars -bars estimates (src/estimate/bars.c). */
typedef struct {
  PetscReal force[3];                  /* the obstacle's force on the body */
  PetscReal pressure_max;              /* the largest nodal contact pressure */
  PetscReal contact_size;              /* the contact zone's measure on Gamma_C: its width in 2D, its area in 3D */
  PetscReal contact_size_band;         /* the measure of the one-cell strip along the zone's edge: the size's resolution */
  PetscReal pressure_max_step;         /* the largest change of the nodal pressure from the largest's node to a neighbour on
                                          Gamma_C: the largest pressure's resolution */
  PetscReal pressure_peak;             /* the largest pressure recovered by a local quadratic fit (src/physics/pressure_peak.c) */
  PetscReal pressure_peak_resolution;  /*   and its resolution: the fit's standard error or its step to the top's neighbours */
  PetscReal penetration_max;           /* the largest penetration */
  PetscReal energy;                    /* 1/2 a(u,u) - L(u) + the contact term's energy */
  PetscReal reaction[BOUNDARY_MAX][3]; /* the force of each clamp or slip face set's support on the body */
} Quantities;

/* The solution's quantities after a solve (PostprocessContact(), src/physics/postprocess.c): the quantities users read,
   where the rule acts, the sum of the nodal normal reactions (q.force is the obstacle's force vector), and whether the
   largest penetration is the finer quadrature's, between the rule's points (PostprocessPenetration()). */
typedef struct {
  Quantities q;
  PetscInt   active_vertices;
  PetscReal  contact_force;
  PetscBool  penetration_between;
} SolutionQuantities;

typedef struct {
  PetscInt            newton_its, ksp_its;             /* of the last solve (the finest mesh, the last eps) */
  PetscInt            newton_its_total, ksp_its_total; /* of all solves: grid sequence levels, continuation, eps sweep */
  PetscBool           converged;                       /* PETSc's reason is a convergence and the residual fell as asked (residual_reduced) */
  PetscBool           residual_reduced;                /* |F| <= rtol |F0|, or at round-off for the load, or below -snes_atol */
  PetscBool           roundoff_stop;                   /* or Newton stalled at the round-off of the terms the residual sums */
  SNESConvergedReason reason;
  PetscReal           residual_norm;
  PetscReal           residual_start;           /* |F| at the start of the last Newton solve */
  PetscInt            continuation_stages;      /* solves of the eps sequence before the target eps (0: none) */
  PetscInt            force_control_its;        /* positions of the obstacle solved by force control (-obstacle_force), all steps */
  PetscBool           force_control_failed;     /*   the target not reached, though every solve converged */
  PetscInt            penetration_tol_solves;   /* solves at the values of eps of -contact_penetration_tol (0 without it) */
  PetscReal           penetration_tol_measured; /*   the largest penetration at the nodes and the rule's points it ended with */
  PetscInt            active_set_cycles;        /* active-set cycles detected (and damped) in the Newton iterations */
  PetscInt            pc_builds;                /* preconditioner (factorization) builds of the Newton steps */
  PetscInt            pc_updates;               /* updates of a GAMG hierarchy's coarse operators instead of builds (-contact_pc_update) */
  PetscInt            pc_finest_updates;        /*   and of its finest level only (-contact_pc_update_changes) */
  PetscBool           coarse_mg;                /* the coarser boxes solved with the geometric multigrid of the boxes below, if any */
  PetscBool           default_mg;               /* the linear solver: the boxes' geometric multigrid, by default (no -pc_type; 3D box) */
  PetscInt            pc_breakdowns;            /* preconditioner breakdowns recovered from (pc_recovery.c), */
  char                pc_recovery[512];         /*   and what was done, "; "-separated */
  PetscBool           ksp_ew;                   /* Eisenstat-Walker linear tolerances (-snes_ksp_ew) */
  PetscReal           condition_1norm;          /* estimate of cond_1 of the final Jacobian, NaN if not computed */
  PetscReal           peak_memory_mb, peak_memory_total_mb; /* resident set size: maximum over ranks, and summed */
  PetscReal           time_setup, time_solve, time_total;
} RunStats;

/* Error bars of the quantities users read (-bars, src/estimate/bars.c): the mesh's part from the solutions on the three
   finest nested meshes (Richardson extrapolation with the observed order, Roache's grid convergence index), the penalty's
   from a second solve at eps / BARS_EPS_RATIO on the level below the final one (BARS_EPS_LEVEL, an index of level[]). */
#define BARS_LEVELS 3
#define BARS_EPS_RATIO 10.0
#define BARS_EPS_LEVEL (BARS_LEVELS - 2)
#define BARS_MAX (8 + 3 * BOUNDARY_MAX)
typedef struct {
  PetscInt   nlevels; /* the two levels below the final mesh recorded, coarsest first (the final's are the run's) */
  Quantities level[BARS_LEVELS - 1];
  PetscReal  level_h[BARS_LEVELS - 1];
  PetscBool  eps_done;           /* the second eps was solved (the penalty method) */
  PetscBool  remeshed;           /* the levels are the Gmsh model meshed again at halved sizes (-adapt_model), not nested */
  PetscReal  eps_levels;         /*   and then the one eps of all three levels (0: the nested levels' rule) */
  PetscReal  eps, eps_second;    /* the run's eps on level[BARS_EPS_LEVEL] and the second one */
  Quantities eps_level;          /* that level's quantities at eps_second */
  PetscInt   n;                  /* the quantities, after BarsCompute(): */
  char       name[BARS_MAX][64]; /*   contact_force_x, ..., pressure_max, contact_size, penetration_max, energy, reaction_* */
  PetscReal  value[BARS_MAX];    /*   on the final mesh */
  PetscReal  bar[BARS_MAX];      /*   bar_mesh + bar_eps, NaN where there is none */
  PetscReal  bar_mesh[BARS_MAX], bar_eps[BARS_MAX], order[BARS_MAX];
  char       note[BARS_MAX][128]; /*   why there is no bar ("" if there is one) */
  PetscReal *pressure_levels[2];  /* from the 2h level on, at the current mesh's vertices (v - vStart): the 2h level's nodal
                                     pressure and its change at eps / R, carried to the finer meshes by interpolation */
  PetscBool  pressure_recorded;   /* pressure_levels hold the 2h level's values (on every rank alike) */
  PetscBool  pressure_band;       /* after BarsCompute(): the band was computed (on every rank alike), */
  PetscInt   npressure;           /*   over the contact set's nodes of the final mesh, */
  PetscReal *pressure_bar;        /*   the band of the nodal pressure at each (contact_pressure_bar), NaN without one */
} ErrorBars;

/* A load path (-load_steps, -load_path): the factors of the prescribed data, solved in turn on the final mesh. */
#define LOAD_PATH_MAX 1000
typedef struct {
  PetscInt  n; /* 0: no path (the one solve at the full load) */
  PetscReal factor[LOAD_PATH_MAX];
} LoadPathOptions;

/* Adaptive refinement (-adapt_cycles, src/drivers/adapt.c): the cycles of estimate, mark, refine and solve after the
   first solve, and the fraction of the estimate's square the marked cells hold (Doerfler's theta). */
typedef enum { ACCURACY_ENERGY, ACCURACY_FORCE, ACCURACY_PRESSURE, ACCURACY_SIZE, ACCURACY_PEAK, ACCURACY_NUM } AccuracyQuantity;
extern const char *const AccuracyQuantities[];
/* Why the cycles stopped (/run adapt_stop): -accuracy reached, the cycles of -adapt_cycles done, the mesh at
   -adapt_max_dofs, a failed solve, nothing left to refine (a zero estimate), a fixed eps whose penalty part of a bar
   is above the tolerance (no refinement lowers it), the next cycle past -adapt_max_memory, or a tolerance whose bar
   falls too slowly to reach it within that memory (AdaptOutOfReach()); "interrupted" in the output each finished cycle
   writes while the run goes on, which stays where a signal ends the run. */
typedef enum {
  ADAPT_STOP_ACCURACY,
  ADAPT_STOP_CYCLES,
  ADAPT_STOP_MAX_DOFS,
  ADAPT_STOP_SOLVE_FAILED,
  ADAPT_STOP_NOTHING_MARKED,
  ADAPT_STOP_INTERRUPTED,
  ADAPT_STOP_FIXED_EPS,
  ADAPT_STOP_MAX_MEMORY,
  ADAPT_STOP_OUT_OF_REACH
} AdaptStop;
extern const char *const AdaptStops[];
typedef struct {
  PetscInt  cycles;                    /* 0: no adaptive refinement; with -accuracy, the most cycles */
  PetscBool run_to_budget;             /* -adapt_cycles or -adapt_max_dofs given: no stop for a tolerance out of reach */
  PetscReal fraction;                  /* -adapt_fraction (0: the default, AdaptSolve()'s) */
  PetscReal accuracy;                  /* -accuracy: the relative error asked for (0: none), */
  PetscBool target[ACCURACY_NUM];      /*   of these quantities (-accuracy_quantity; all false: the default, AdaptTargets()) */
  char      model[PETSC_MAX_PATH_LEN]; /* -adapt_model: the Gmsh model remeshed at each cycle ("": the mesh refined) */
  PetscReal newton_fraction;           /* -accuracy_newton_fraction: Newton stops at this fraction of the error (0: never) */
  PetscBool mark_edge;                 /* -adapt_mark_edge: with -accuracy on the size, refine along the zone's edge too */
  PetscBool monitor;                   /* -adapt_monitor: a line for each cycle as it ends */
  PetscInt  max_dofs;                  /* -adapt_max_dofs: no mesh with this many unknowns or more is refined (0: no limit) */
  PetscReal max_memory;                /* -adapt_max_memory: the run's memory over all ranks, MB, that no cycle is predicted past */
  PetscBool max_memory_given;          /*   given, or the default (AdaptDefaultMemory()) */
} AdaptOptions;

/* One cycle of the adaptive refinement (/cycles in the output): the mesh, the estimate of its solution and the true
   energy-norm error where the scene knows the exact solution (NaN otherwise), the cells marked for the next cycle, and
   the solve on it. */
typedef struct {
  PetscInt   n_dofs, n_cells, marked;
  PetscInt   marked_edge;                /* the cells along the zone's edge marked too (EstimateMarkContactEdge()) */
  PetscReal  estimate, estimate_penalty; /* the estimate and its penalty part, */
  PetscReal  norm;                       /*   and the energy norm of the solution, its scale */
  PetscReal  error_energy;
  Quantities q;                       /* the quantities users read on the cycle's mesh */
  PetscReal  value[ACCURACY_NUM];     /* -accuracy's quantities (the energy: the solution's energy norm; the force: its magnitude) */
  PetscReal  bar[ACCURACY_NUM];       /*   and their error bars (the energy: the estimate), NaN where there is none */
  PetscReal  value_eps[ACCURACY_NUM]; /* the quantities at eps / CYCLE_EPS_RATIO on the same mesh (the tangent's), NaN without them */
  PetscReal  eps, eps_scale;          /* the penalty's eps on the cycle and its scale h/M (h: the smallest contact cell), NaN without it */
  PetscInt   unseen;                  /* contact nodes the rule does not see (EstimateMarkUnseenContact()), */
  PetscReal  unseen_force;            /*   and the force the penalty law would put on them */
  PetscBool  accurate;                /* every quantity asked for within -accuracy */
  PetscInt   newton_its, ksp_its;
  PetscReal  time_solve;
  PetscReal  time_mesh;  /* s: this cycle's mesh from the last (refined or remeshed) and its problem's set-up (0 for the first) */
  PetscReal  time_cycle; /* s: the whole cycle, its mesh, solve, estimate and marking (cycle 0: the first solve on) */
  PetscReal  memory_mb;  /* the run's resident memory at this cycle's end, MB summed over the ranks */
  PetscBool  converged;
} CycleRecord;

/* One step of a load path (/steps in the output): its factor, the obstacle's translation, the quantities, the solve. */
typedef struct {
  PetscReal  factor, obstacle_translate[3];
  PetscReal  contact_force; /* the sum of the nodal normal reactions, as /run's contact_force */
  Quantities q;
  PetscInt   newton_its, ksp_its;
  PetscReal  time; /* of the step's solve */
  PetscBool  converged;
} StepRecord;

/* One solve of a run: a level of the grid sequence or an eps of the sweep (/solves in the output). */
typedef struct {
  PetscInt  level, n_dofs;
  PetscReal h, eps;
  PetscInt  newton_its, ksp_its, pc_builds;
  PetscBool converged;
  PetscReal time_setup, time_solve; /* set-up of the mesh's problem (first solve on it only), and the solve */
  PetscReal max_penetration;
} SolveRecord;

/* The options of the run, read once before any set-up (each module's *GetOptions fills its part), read-only after. */
typedef struct {
  char            scene_name[64];
  Material        material;
  PetscInt        degree;        /* of the displacement, -displacement_petscspace_degree */
  PetscBool       section_check; /* -section_check: the P1 section compared with PETSc's */
  SolverOptions   solver;
  VerifyOptions   verify;
  AssemblyType    assembly;                 /* -assembly as given (auto, fe, p1) */
  PetscBool       assembly_check;           /* -assembly_check: assemble K both ways and compare */
  PetscBool       perf_bandwidth;           /* -perf_bandwidth: measure the memory bandwidths after the solve */
  PetscBool       estimate, estimate_given; /* -estimate: the a posteriori error estimate after the solve (and whether it was given) */
  PetscBool       bars;                     /* -bars: error bars of the quantities from the nested meshes and a second eps */
  LoadPathOptions load_path;                /* -load_steps, -load_path */
  AdaptOptions    adapt;                    /* -adapt_cycles, -adapt_fraction */
  char            output[PETSC_MAX_PATH_LEN];
  PetscBool       output_dmview; /* -output_dmview: the mesh written by DMView() instead of OutputViewMesh() */
} RunOptions;

typedef struct _n_SolverCtx *SolverCtx; /* private to src/solver/ */

/* The discrete problem on one mesh: created by ProblemSetUp(), destroyed by ProblemDestroy(), one per grid level. */
typedef struct {
  PetscInt     level;      /* grid sequence level of the mesh (0: the mesh built first) */
  PetscReal    setup_time; /* set-up time of this problem, counted with its first solve */
  PetscReal    h;          /* the largest cell diameter */
  DMLabel      face_sets;
  Vec          loc_bc;             /* local vector holding the Dirichlet values, zero elsewhere */
  AssemblyType assembly;           /* how K is assembled: fe or p1 (-assembly auto resolved) */
  Mat          K;                  /* bulk elastic operator, assembled once */
  Vec          r0;                 /* bulk residual at u = 0 (loads and Dirichlet lifting) */
  Vec          loc_r0;             /* the same, local, with the rows of the fixed components (for the supports' reactions) */
  PetscReal    lift_energy;        /* J(u_D) = 1/2 a(u_D, u_D) - L(u_D) of the Dirichlet lift, part of the energy (postprocess.c) */
  PetscReal    load_norm;          /* ||F(0)||_2, the size of the load (loads, Dirichlet lifting, initial penetration) */
  PetscReal    displacement_scale; /* U, a power of 2: the SNES solves for u/U with the residual F/U (unit-free tolerances) */
  SolverCtx    sctx;               /* the SNES's callbacks' context and the solver's own state (src/solver/solver_impl.h) */
} Problem;

/* The state of a run, as a few handles and the diagnostics' results: its options, the Contact, the mesh's box, the
   scene, the nested meshes' multigrid, the Newton core (which owns the problem on the current mesh, the run's
   statistics and the table of solves), the drivers (each with its results: the cycles, the steps), and the results
   of the diagnostics after the solve, each of its module's type. */
typedef struct _p_Contact   *Contact;   /* include/contact.h */
typedef struct _n_Multigrid *Multigrid; /* the nested meshes' interpolations, private to src/linear/ (linear_impl.h) */
typedef struct _n_Solver    *Solver;    /* the nonlinear core (include/solver.h), private to src/solver/ (solver_impl.h) */
typedef struct _n_Drivers   *Drivers;   /* the outer strategies (include/drivers.h), private to src/drivers/ */
typedef struct {
  const RunOptions  *opt;     /* read once before any set-up, then read only */
  Contact            contact; /* created and read from the options once, set up on the mesh of each problem */
  MeshBox            box;     /* the simplex box of the mesh options, if the mesh is one (MeshCreate()) */
  Scene              scene;
  Multigrid          mg;                       /* the interpolations between the nested meshes solved so far */
  Solver             solver;                   /* the nonlinear core: the problem, the statistics, the table of solves */
  Drivers            drivers;                  /* the grid sequence, the adaptive cycles, the eps sweep, ..., the load path */
  SolutionQuantities quantities;               /* of the last solution (src/physics/postprocess.c) */
  ContactChecks      checks;                   /* the set-up's and the contact zone's warnings (src/physics/contact_checks.c) */
  MeshPartitionStats partition;                /* the partitioner and the final mesh's cut (src/mesh/mesh_partition.c) */
  Bandwidth          bandwidth;                /* -perf_bandwidth (src/solver/bandwidth.c) */
  ErrorNorms         errors;                   /* against the scene's exact solution (src/verify/error_norms.c) */
  ErrorNorms         ref_errors;               /* against the -reference solution (src/verify/reference.c) */
  ErrorEstimate      estimate;                 /* the a posteriori estimate of the error (src/estimate/) */
  ErrorBars          bars;                     /* the error bars of the quantities (-bars, src/estimate/bars.c) */
  char               diagnostics_failed[1024]; /* the diagnostics that failed after the solve, with their messages ("" if none) */
} AppCtx;

/* The writer of the run's output (src/main.c's, through io/output_hdf5.c's OutputWriteHDF5()), which main() hands to the adaptive cycles */
typedef PetscErrorCode (*OutputWriter)(DM, const AppCtx *, Vec);
