/* Private to src/estimate/: the work space of one estimate and the geometry of a P1 simplex and its faces. */
#pragma once
#include "contact.h"
#include "estimate.h"
#include "mesh.h"

/* One P1 simplex: its vertices, the gradients of its barycentric coordinates, and grad u_h and sigma(u_h), constant. */
typedef struct {
  PetscInt  nv, vert[4], off[4]; /* vertices (points), and their offsets in the local displacement vector */
  PetscReal x[12];               /* [nv][dim] coordinates */
  PetscReal u[12];               /* [nv][dim] displacement (Dirichlet values inserted) */
  PetscReal dl[12];              /* [nv][dim] gradients of the barycentric coordinates */
  PetscReal volume, diameter;
  PetscReal grad[9], sigma[9]; /* grad[i*dim+j] = du_i/dx_j, and the stress */
} EstimateCell;

/* A face of a cell: which of the cell's vertices it holds, its outward unit normal, measure and diameter. */
typedef struct {
  PetscInt  nv, local[3]; /* the cell's vertex indices of the face's vertices */
  PetscReal normal[3], measure, diameter;
} EstimateFace;

/* A quadrature rule on the reference simplex in barycentric coordinates, weights summing to 1. */
typedef struct {
  PetscInt   n, nb; /* points, barycentric coordinates per point (dim + 1) */
  PetscReal *bary, *w;
} EstimateRule;

typedef struct {
  DM                   dm;
  const Scene         *scene; /* the loads, the boundary conditions and Gamma_C, the obstacle */
  const Material      *mat;
  const VerifyOptions *verify; /* the accurate rule of a weak-data scene's load */
  Contact              contact;
  PetscInt             dim, cStart, cEnd, fStart, fEnd;
  MeshClosure          mc;
  PetscSection         lsec, csec;
  const PetscScalar   *xc, *lu;   /* local coordinates, local displacement with the Dirichlet values */
  const PetscScalar   *lp;        /* the nodal contact pressure as p n (the nodal rule and SNESVI), NULL for the pointwise law */
  ContactPressureForm  pressure;  /* how the contact pressure follows from u_h (ContactGetPressureForm()) */
  const PetscScalar   *constants; /* the kernels' constants[] */
  PetscInt             nconstants;
  PetscReal            m_normal;  /* lambda + 2 mu: the normal tractions' and the body force's squares are divided by it */
  PetscReal            m_shear;   /* 2 mu: the tangential tractions' squares are divided by it */
  EstimateRule         cell_rule; /* for the body force (a weak-data scene's G takes the load's own rule) */
  EstimateRule         face_rule; /* for the boundary terms */
  PetscReal           *eta2;      /* [ncells][ESTIMATE_NUM_PARTS] the squared indicators */
  PetscReal           *volume;    /* [ncells] */
  PetscReal            norm2;     /* the local cells' sum of sigma(u_h) : grad u_h |T|, the square of u_h's energy norm */
  PetscInt            *face_kind; /* [fEnd - fStart]: ESTIMATE_FACE_* or the index of the face's clamp/slip/load in the scene */
  PetscReal           *face_sum;  /* [chart][dim + 1]: sum over a face's cells of sigma n_out, and their number */
  PetscReal           *face_geom; /* [fEnd - fStart][dim + 2]: each face's measure, diameter and unit normal */
  PetscReal           *load_mean; /* [ncells][dim * dim]: Pi_0 G, the cells' means of a weak-data scene's G = sigma(u_exact); unused otherwise */
} EstimateWork;

enum { ESTIMATE_FACE_FREE = -1, ESTIMATE_FACE_CONTACT = -2 };

/* estimate_geometry.c */
PetscErrorCode EstimateCellLoad(EstimateWork *w, PetscInt c, EstimateCell *cell);
PetscErrorCode EstimateFaceOfCell(EstimateWork *w, const EstimateCell *cell, PetscInt f, EstimateFace *face);
void           EstimateFacePoint(const EstimateWork *w, const EstimateCell *cell, const EstimateFace *face, PetscInt q, PetscReal x[], PetscReal u[],
                                 PetscReal *weight);
/* estimate_residual.c */
PetscErrorCode EstimateResidualTerms(EstimateWork *w);
/* estimate_penalty.c */
PetscErrorCode EstimatePenaltyTerm(EstimateWork *w);
