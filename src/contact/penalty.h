/* The penalty type's inside (src/contact/penalty.c, penalty_faces.c). */
#pragma once
#include "contact_impl.h"

/* The contact faces of this rank for the Gauss rule of the penalty term in closed form (P1 simplices, penalty_faces.c):
   PETSc's face quadrature, mapped once. */
typedef struct {
  PetscInt   n, nv, nq;  /* faces, vertices per face (dim), quadrature points per face */
  PetscInt  *loff;       /* [n][nv]: offset of each vertex's displacement in the local vector */
  PetscInt  *gidx;       /* [n][nv][dim]: global index of each component, -1 if fixed */
  PetscReal *x, *w;      /* [n][nq][dim] the quadrature points, [n][nq] their weights (face Jacobian included) */
  PetscReal *inv_factor; /* [n]: 1 / the eps factor of the face's cell (local eps), NULL if eps is uniform */
  PetscReal *lambda;     /* [nq][nv]: the face's P1 basis (barycentric coordinates) at the points */
} PenaltyFaces;

PetscErrorCode PenaltyFacesSetUp(Contact ct, DM dm, PenaltyFaces *pf);
PetscErrorCode PenaltyFacesDestroy(PenaltyFaces *pf);
PetscErrorCode PenaltyFacesResidual(const PenaltyFaces *pf, DM dm, Vec locX, Vec locF);
PetscErrorCode PenaltyFacesJacobian(const PenaltyFaces *pf, DM dm, Vec locX, Mat J);
PetscErrorCode PenaltyFacesEnergy(const PenaltyFaces *pf, DM dm, Vec locX, PetscReal *energy);
PetscErrorCode PenaltyFacesSameActivity(const PenaltyFaces *pf, DM dm, Vec locA, Vec locB, PetscBool *same);
PetscErrorCode PenaltyFacesMaxPenetration(const PenaltyFaces *pf, DM dm, Vec locX, PetscReal *dmax);

/* bulk_rows.c: the penalty Jacobian in K itself */
PetscErrorCode BulkRowsSave(ContactBulkRows *br, const ContactSet *cs, PetscInt dim, Mat K);
PetscErrorCode BulkRowsFree(ContactBulkRows *br);
PetscErrorCode BulkRowsRestore(ContactBulkRows *br, Mat K, MatAssemblyType type);
PetscErrorCode BulkRowsMult(const ContactBulkRows *br, Mat K, Vec X, Vec R);
