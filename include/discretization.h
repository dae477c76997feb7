/* The discretization of the displacement beside PetscFE's (src/discretization/): the local and global sections of
   P1/Q1 displacements built as PETSc builds them, without its lookups per mesh point, and the assembly of the bulk
   operator K and of r0 for P1 simplices in closed form, into K's own CSR arrays on one rank or many; and the accurate
   (composite) quadrature that the weak data of manufactured solutions and the error norms integrate with. */
#pragma once
#include "signorini.h"
#include "mesh.h" /* MeshClosure */

/* element_p1.c: the P1 simplex in closed form */
PetscErrorCode ElementP1Gradients(PetscInt dim, const PetscReal x[], PetscReal g[][3], PetscReal *volume);
PetscErrorCode ElementP1Stiffness(PetscInt dim, PetscReal lambda, PetscReal mu, const PetscReal x[], PetscScalar Ke[]);
PetscErrorCode ElementP1CellVertices(MeshClosure *mc, PetscSection csec, PetscSection lsec, const PetscScalar xc[], PetscInt c, PetscReal x[],
                                     PetscInt off[], PetscInt *nv);
PetscErrorCode ElementP1AddFixedCellsStiffness(DM dm, const Material *mat, Vec locU, Vec locF);

/* section.c */
PetscErrorCode SectionSetUpP1(DM dm, PetscInt degree, PetscBool check);
PetscErrorCode SectionSetUpGlobalP1(DM dm, PetscBool check);

/* assembly.c: the bulk terms by the mesh's assembly (fe or p1): K, F_bulk, K u_D. What the P1 assembly of K reads:
   the material, and whether -mat_type was given (K of the options' type, which the CSR paths may not build) */
typedef struct {
  const Material *material;
  PetscBool       mat_type_given;
} AssemblyP1Inputs;
PetscErrorCode AssemblyCreateOperator(DM dm, AssemblyType assembly, const AssemblyP1Inputs *p1, PetscBool check, Vec locX, Mat *K);
PetscErrorCode AssemblyResidual(DM dm, AssemblyType assembly, const Material *mat, Vec locX, Vec locF);
PetscErrorCode AssemblyLiftStiffness(DM dm, AssemblyType assembly, const Material *mat, Vec loc_bc, Vec locA);

/* assembly_p1.c */
PetscErrorCode AssemblyGetOptions(MPI_Comm comm, AssemblyType *requested, PetscBool *check);
PetscErrorCode AssemblyResolve(DM dm, AssemblyType requested, PetscInt degree, PetscBool check, AssemblyType *assembly);
PetscErrorCode AssemblyP1CreateMatrix(DM dm, const AssemblyP1Inputs *in, Mat *K);
PetscErrorCode AssemblyP1Check(DM dm, const AssemblyP1Inputs *in, Vec locX);
PetscErrorCode AssemblyP1Residual(DM dm, const Material *mat, Vec locX, Vec locF);

/* assembly_p1_csr.c */
PetscErrorCode AssemblyP1BlockPattern(DM dm, PetscInt bs, PetscInt nb, const PetscInt vidx[], PetscInt **bptr, PetscInt **bcol);
PetscErrorCode AssemblyP1CreateSeqAIJ(DM dm, const AssemblyP1Inputs *in, PetscInt nlocal, PetscInt bs, const PetscInt vidx[], const PetscInt cverts[],
                                      Mat *K, PetscBool *done);
PetscErrorCode AssemblyP1CSRAllocated(Mat K, PetscLogDouble *nz);
PetscErrorCode AssemblyP1CSRApplies(DM dm, PetscInt bs, PetscBool mat_type_given, PetscBool *applies);
PetscErrorCode AssemblyP1CellCoordinates(PetscSection csection, const PetscScalar xa[], PetscInt dim, const PetscInt verts[], PetscReal x[]);
/* the cell loop for one rank and many: adds the block Kab (row stride ld) of local vertices va (row) and vb (column) */
typedef void (*AssemblyP1AddBlock)(void *ctx, PetscInt va, PetscInt vb, const PetscScalar *Kab, PetscInt ld);
PetscErrorCode AssemblyP1CellLoop(DM dm, const Material *mat, const PetscInt cverts[], AssemblyP1AddBlock add, void *ctx);
PetscErrorCode AssemblyP1CSRCompose(Mat K, PetscInt *i, PetscInt *j, PetscScalar *a, PetscInt *oi, PetscInt *oj, PetscScalar *oa);

/* assembly_p1_mpiaij.c */
PetscErrorCode AssemblyP1CreateMPIAIJ(DM dm, const AssemblyP1Inputs *in, PetscInt nlocal, PetscInt bs, const PetscInt vidx[], const PetscInt cverts[],
                                      Mat *K, PetscBool *done);

/* cell_quadrature.c: basis functions at the points of an accurate rule, cell by cell or on faces */
typedef struct {
  PetscInt         dim, Nb, Nc; /* space dimension, basis functions, components */
  PetscInt         Nq;          /* points of the current cell or face */
  const PetscReal *x;           /* [Nq][dim] physical points */
  const PetscReal *w;           /* [Nq] weights times the Jacobian determinant */
  const PetscReal *B;           /* [Nq][Nb][Nc] basis values */
  const PetscReal *D;           /* [Nq][Nb][Nc][dim] physical basis gradients (cells only): point q's at CellQuadratureGradientPoint(q) */
  PetscBool        D_uniform;   /* the cell's physical gradients the same at every point (P1, affine): D holds the first's alone */
  PetscInt         cell;        /* the cell whose basis is tabulated (the support cell of a face) */
  /* private */
  DM              dm;
  PetscFE         fe;
  const Scene    *scene;
  PetscQuadrature cell_rule[2], face_rule[2]; /* plain and refined */
  PetscTabulation cell_tab[2], face_tab;
  PetscBool       grad_const[2]; /* the rule's reference gradients the same at every point (P1): one product per affine cell */
  PetscReal      *xbuf, *wbuf, *dbuf, *J, *invJ, *detJ, *refbuf;
} CellQuadrature;
PetscErrorCode CellQuadratureCreate(DM dm, const Scene *scene, const VerifyOptions *opts, CellQuadrature *cq);
PetscErrorCode CellQuadratureSetCell(CellQuadrature *cq, PetscInt cell);
PetscErrorCode CellQuadratureSetFace(CellQuadrature *cq, PetscInt face);
PetscErrorCode CellQuadratureDestroy(CellQuadrature *cq);
PetscErrorCode CellQuadratureInterpolate(const CellQuadrature *cq, const PetscScalar closure[], PetscInt q, PetscReal u[], PetscReal grad[]);
/* The row of D that holds point q's physical gradients */
static inline PetscInt CellQuadratureGradientPoint(const CellQuadrature *cq, PetscInt q)
{
  return cq->D_uniform ? 0 : q;
}
