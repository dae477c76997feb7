/* The Contact object's inside, seen by its types only (src/contact/): the operations a type provides, and the state
   every type shares. The rest of the code uses include/contact.h. */
#pragma once
#include "contact.h"
#include "obstacle.h"

typedef struct {
  PetscErrorCode (*setup)(Contact, DM);                                              /* after the contact set is built: the type's own state */
  PetscErrorCode (*reset)(Contact);                                                  /* frees the state of the mesh */
  PetscErrorCode (*destroy)(Contact);                                                /* frees data (NULL: PetscFree(data)) */
  PetscErrorCode (*residual)(Contact, DM, Vec u, Vec F);                             /* F += the contact term at u (NULL: none) */
  PetscErrorCode (*jacobian)(Contact, DM, Vec u, Mat K, Mat P);                      /* P = K + the contact Jacobian at u (NULL: P = K) */
  PetscErrorCode (*prepare_operator)(Contact, DM, Mat K);                            /* once K is assembled, before the first Jacobian */
  PetscErrorCode (*bulk_mult)(Contact, Mat K, Vec X, Vec R);                         /* R = K X with K's own values (NULL: MatMult) */
  PetscErrorCode (*bulk_operator)(Contact, Mat K, Mat *Kb);                          /* a new matrix equal to the bulk K (NULL: K itself) */
  PetscErrorCode (*energy)(Contact, DM, Vec u, PetscReal *);                         /* the contact term's energy (NULL: 0) */
  PetscErrorCode (*acts)(Contact, DM, Vec u, PetscBool[], PetscReal *);              /* where the force acts (NULL: everywhere) */
  PetscErrorCode (*same_activity)(Contact, DM, Vec, Vec, PetscBool *);               /* the force acts at the same points (NULL: true) */
  PetscErrorCode (*setup_snes)(Contact, DM, SNES);                                   /* the SNES type and bounds (NULL: Newton, ContactSetUpSNES()) */
  PetscErrorCode (*check)(Contact, DM, Vec u);                                       /* -assembly_check after the solve (NULL: none) */
  PetscErrorCode (*scale_bounds)(Contact, PetscReal);                                /* the bounds times a factor (NULL: none) */
  PetscErrorCode (*load)(Contact, DM);                                               /* after the set's gaps changed, ContactSetLoad() (NULL: none) */
  PetscErrorCode (*frame)(Contact, Vec, PetscBool to_solver);                        /* v <- Q^T v or Q v, the SNES's own frame (NULL: none) */
  PetscErrorCode (*augment)(Contact, DM, Vec u, PetscBool apply, PetscReal *change); /* the multipliers' update at u (NULL: none) */
  PetscErrorCode (*forget)(Contact);                                                 /* the multipliers set to zero (NULL: none) */
  PetscErrorCode (*view)(Contact, PetscViewer);                                      /* the type's part of the summary line */
} ContactOps;

struct _p_Contact {
  MPI_Comm              comm;
  char                  type[64];
  ContactOps            ops;
  void                 *data;        /* the type's own state */
  PetscBool             has_penalty; /* set by the type's create function */
  PetscBool             has_bounds;
  PetscBool             has_frames; /* the SNES iterates in frames of its own at some nodes (vi on this mesh; ops.frame) */
  ContactSolverDefaults defaults;   /* the type's, set by its create function */
  ContactOptions        opt;        /* read once by ContactSetFromOptions() */

  /* on the mesh of ContactSetUp() */
  PetscBool    set_up;
  PetscInt     dim, degree;
  PetscInt     nids;              /* Gamma_C: the face sets */
  PetscInt     ids[BOUNDARY_MAX]; /*   their "Face Sets" values */
  DMLabel      face_sets;
  Obstacle     obstacle;
  PetscScalar  obstacle_packed[OBSTACLE_NUM_PARAMS];
  Material     material;
  PetscReal    h;                              /* the mesh's largest cell diameter */
  PetscReal    eps;                            /* eps of the run; a node's or a face's is eps times its factor */
  PetscReal    eps_factor_min, eps_factor_max; /* over the contact nodes (nodal) or faces (gauss), all ranks */
  PetscBool    eps_local;                      /* the factors differ by more than rounding: eps per face or node */
  AssemblyType assembly;
  PetscBool    assembly_check;
  Vec          loc_bc; /* the Dirichlet values (referenced) */
  ContactSet   set;
};

/* contact_set.c */
PetscErrorCode ContactSetBuild(Contact ct, DM dm, Vec like);
PetscErrorCode ContactSetUpdateData(Contact ct, DM dm);
PetscErrorCode ContactSetFree(ContactSet *cs);
PetscReal      ContactEpsFactor(Contact ct, PetscReal h_local);
PetscErrorCode ContactComputeBdResidual(Contact ct, DM dm, PetscWeakForm wf, PetscInt part, Vec locX, Vec locF);
PetscErrorCode ContactGetLocalSolution(Contact ct, DM dm, Vec X, Vec *locX);

/* vi_frames.c: the rotated frames of SNESVI at the contact nodes whose normal is not an axis */
typedef struct {
  PetscInt         nrotated;       /* nodes of all ranks whose normal needs a frame now (0: no frames, the SNES iterates on u) */
  PetscInt         n;              /* this rank's nodes that may carry a frame (two or more free components) */
  PetscInt        *node;           /*   their index in the contact set */
  PetscReal       *R;              /*   [n][3][3] row-major: u_free = R w_free, column 0 along the normal's free part */
  Mat              Q;              /* u = Q w: block diagonal, orthogonal */
  PetscObjectState state;          /* of the frames, counted by ViFramesUpdate() */
  PetscObjectState operator_state; /* of the frames Q^T K Q was made for */
} ViFrames;
void           ViNodeConstraint(const ContactSet *cs, PetscInt dim, PetscInt i, PetscInt *comp, PetscReal *coef, PetscReal *rhs, PetscBool *rotate);
PetscErrorCode ViFramesSetUp(MPI_Comm comm, const ContactSet *cs, PetscInt dim, Vec like, ViFrames *fr);
PetscErrorCode ViFramesUpdate(const ContactSet *cs, PetscInt dim, ViFrames *fr);
PetscErrorCode ViFramesApply(const ContactSet *cs, PetscInt dim, const ViFrames *fr, Vec v, PetscBool to_solver);
PetscErrorCode ViFramesOperator(const ContactSet *cs, PetscInt dim, ViFrames *fr, Mat K, Mat *Kw);
PetscErrorCode ViFramesDestroy(ViFrames *fr);

/* the types */
PetscErrorCode ContactCreate_Penalty(Contact ct);
PetscErrorCode ContactCreate_AL(Contact ct);
PetscErrorCode ContactCreate_VI(Contact ct);
PetscErrorCode ContactCreate_None(Contact ct);
