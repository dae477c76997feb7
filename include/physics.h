/* Physics: linear elasticity, the contact set, the penalty term, the SNESVI bounds, the contact quantities after the solve (src/physics/). */
#pragma once
#include "signorini.h"
#include "mesh.h" /* MeshClosure */

/* section.c */
PetscErrorCode SectionSetUpP1(DM dm, const AppCtx *user);
PetscErrorCode SectionSetUpGlobalP1(DM dm, PetscBool check);

/* elasticity.c */
PetscErrorCode ElasticityGetOptions(MPI_Comm comm, Material *mat, PetscInt *degree, PetscBool *section_check);
PetscErrorCode ElasticitySetUpDiscretization(DM dm, AppCtx *user);
PetscErrorCode ElasticityUpdateConstants(DM dm, AppCtx *user);
PetscErrorCode ElasticityRigidBodyModesP1(DM dm, Vec like, MatNullSpace *nullspace);
PetscErrorCode ElasticityP1ElementStiffness(PetscInt dim, PetscReal lambda, PetscReal mu, const PetscReal x[], PetscScalar Ke[]);
PetscErrorCode ElasticityP1CellVertices(MeshClosure *mc, PetscSection csec, PetscSection lsec, const PetscScalar xc[], PetscInt c, PetscReal x[],
                                        PetscInt off[], PetscInt *nv);
PetscErrorCode ElasticityP1AddFixedCellsStiffness(DM dm, const Material *mat, Vec locU, Vec locF);

/* contact_options.c, contact_set.c */
PetscErrorCode ContactGetOptions(MPI_Comm comm, ContactOptions *opts);
PetscErrorCode ContactOptionsDestroy(ContactOptions *opts);
PetscErrorCode ContactComputeEps(AppCtx *user);
PetscReal      ContactPenaltyModulus(const AppCtx *user);
PetscErrorCode ContactSetCreate(DM dm, AppCtx *user, ContactSet *cs);
PetscErrorCode ContactSetDestroy(ContactSet *cs);
PetscErrorCode ContactComputeBdResidual(DM dm, const AppCtx *user, PetscWeakForm wf, PetscInt part, Vec locX, Vec locF);
PetscReal      ContactEpsFactor(const AppCtx *user, PetscReal h_local);
PetscErrorCode ContactCountActive(AppCtx *user, Vec X, PetscBool update, PetscInt *active, PetscInt *entered, PetscInt *left);

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

/* penalty.c */
PetscErrorCode PenaltySetUp(DM dm, AppCtx *user);
PetscErrorCode PenaltyAddResidual(DM dm, AppCtx *user, Vec X, Vec F);
PetscErrorCode PenaltyAddJacobian(DM dm, AppCtx *user, Vec X, Mat J);
PetscErrorCode PenaltySameActivity(DM dm, AppCtx *user, Vec X, Vec Y, PetscBool *same);
PetscErrorCode PenaltyCopyRows(Mat A, PetscInt n, const PetscInt rows[], PetscInt **ptr, PetscInt **cols, PetscScalar **vals);
PetscErrorCode PenaltySaveBulkRows(DM dm, AppCtx *user);
PetscErrorCode PenaltyFreeBulkRows(AppCtx *user);
PetscErrorCode PenaltyJacobianInK(DM dm, AppCtx *user, Vec X);
PetscErrorCode PenaltyBulkOperator(AppCtx *user, Mat *K);
PetscErrorCode PenaltyBulkMult(AppCtx *user, Vec X, Vec R);
PetscErrorCode PenaltyEnergy(DM dm, AppCtx *user, Vec X, PetscReal *energy);
PetscErrorCode PenaltyCheckClosedForm(DM dm, AppCtx *user, Vec X);
PetscErrorCode PenaltyRuleActs(DM dm, AppCtx *user, Vec X, PetscBool acts[], PetscReal *dmax);

/* penalty_faces.c: the Gauss rule on P1 simplices in closed form */
PetscErrorCode PenaltyFacesSetUp(DM dm, AppCtx *user);
PetscErrorCode PenaltyFacesDestroy(PenaltyFaces *pf);
PetscErrorCode PenaltyFacesResidual(DM dm, AppCtx *user, Vec locX, Vec locF);
PetscErrorCode PenaltyFacesJacobian(DM dm, AppCtx *user, Vec locX, Mat J);
PetscErrorCode PenaltyFacesEnergy(DM dm, AppCtx *user, Vec locX, PetscReal *energy);
PetscErrorCode PenaltyFacesSameActivity(DM dm, AppCtx *user, Vec locA, Vec locB, PetscBool *same);
PetscErrorCode PenaltyFacesMaxPenetration(DM dm, AppCtx *user, Vec locX, PetscReal *dmax);

/* vi_bounds.c */
PetscErrorCode VICreateBounds(DM dm, AppCtx *user);

/* postprocess.c */
PetscErrorCode PostprocessContact(DM dm, AppCtx *user, Vec u);
PetscErrorCode PostprocessPenetration(AppCtx *user);

/* contact_checks.c */
PetscErrorCode ContactChecksGeometry(DM dm, AppCtx *user);
PetscErrorCode ContactChecksResolution(DM dm, AppCtx *user);
PetscErrorCode ContactChecksWarnings(MPI_Comm comm, const ContactChecks *ck, PetscBool print, PetscInt *nwarnings);

/* elasticity.c: sigma(grad u) = lambda tr(eps) I + 2 mu eps, grad[i*dim+j] = du_i/dx_j */
void ElasticStress(PetscInt dim, const Material *mat, const PetscReal grad[], PetscReal sigma[]);

/* boundary.c */
PetscErrorCode BoundaryAddDirichlet(DM dm, AppCtx *user);
PetscErrorCode BoundaryInsertDirichlet(DM dm, const AppCtx *user, Vec loc);
PetscErrorCode BoundaryAddLoads(DM dm, AppCtx *user, Vec r0);
PetscErrorCode BoundaryAddLoadsLocal(DM dm, AppCtx *user, Vec locF);
PetscErrorCode BoundaryComputeReactions(DM dm, AppCtx *user, Vec u, PetscReal reaction[][3]);
PetscErrorCode BoundaryCheckFaceSets(DM dm, const Scene *scene);
PetscErrorCode BoundaryCheckRigidMotions(DM dm, const Scene *scene);
