/* Physics: linear elasticity, the boundary conditions, the contact quantities after the solve and their checks
   (src/physics/); the contact treatment itself is the Contact object (include/contact.h, src/contact/). */
#pragma once
#include "contact.h"
#include "mesh.h"

/* elasticity.c */
PetscErrorCode ElasticityGetOptions(MPI_Comm comm, Material *mat, PetscInt *degree, PetscBool *section_check);
PetscErrorCode ElasticitySetUpDiscretization(DM dm, AppCtx *user);
PetscErrorCode ElasticityUpdateConstants(DM dm, AppCtx *user);
PetscErrorCode ElasticityRigidBodyModesP1(DM dm, Vec like, MatNullSpace *nullspace);

/* weak_data.c: the load of a scene with an exact solution, L(v) = a(u_exact, v) - int_Gamma_C sigma_n(u_exact) v_n */
PetscErrorCode WeakDataAddToResidual(DM dm, AppCtx *user, Vec r0, PetscReal *lift);
PetscErrorCode WeakDataExactStress(const AppCtx *user, PetscInt dim, const PetscReal x[], PetscReal sigma[]);
PetscErrorCode WeakDataExactNormalStress(const AppCtx *user, PetscInt dim, const PetscReal x[], PetscReal *sn);

/* postprocess.c */
PetscErrorCode PostprocessContact(DM dm, AppCtx *user, Vec u);
PetscErrorCode PostprocessLiftEnergy(DM dm, const AppCtx *user, PetscReal weak_lift, PetscReal *energy);
PetscErrorCode PostprocessPenetration(AppCtx *user);
void           PostprocessGetQuantities(const AppCtx *user, Quantities *q);
PetscReal      PostprocessForceMagnitude(const Quantities *q, PetscInt dim);
/* contact_zone.c */
PetscErrorCode PostprocessContactSize(DM dm, AppCtx *user, Vec u, PetscReal *size, PetscReal *band);
PetscErrorCode PostprocessPressureStep(DM dm, AppCtx *user, PetscReal pressure_max, PetscReal *step);
PetscErrorCode PostprocessContactEdgeFaces(DM dm, AppCtx *user, Vec u, PetscInt *n, PetscInt **faces);
/* pressure_peak.c */
PetscErrorCode PostprocessPressurePeak(DM dm, AppCtx *user, PetscReal pressure_max, PetscReal step, PetscReal *peak, PetscReal *resolution);

/* contact_checks.c */
PetscErrorCode ContactChecksGeometry(DM dm, AppCtx *user);
PetscErrorCode ContactChecksResolution(DM dm, AppCtx *user, Vec u);
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
