/* Physics: linear elasticity, the boundary conditions, the contact quantities after the solve and their checks
   (src/physics/); the contact treatment itself is the Contact object (include/contact.h, src/contact/). */
#pragma once
#include "contact.h"
#include "mesh.h"

/* elasticity.c */
PetscErrorCode ElasticityGetOptions(MPI_Comm comm, Material *mat, PetscInt *degree, PetscBool *section_check);
PetscErrorCode ElasticitySetUpDiscretization(DM dm, const Scene *scene, PetscInt degree);
PetscErrorCode ElasticityUpdateConstants(DM dm, const Material *mat, const Scene *scene);
PetscErrorCode ElasticityRigidBodyModesP1(DM dm, Vec like, MatNullSpace *nullspace);

/* weak_data.c: the load of a scene with an exact solution, L(v) = a(u_exact, v) - int_Gamma_C sigma_n(u_exact) v_n */
PetscErrorCode WeakDataAddToResidual(DM dm, const Scene *scene, const Material *mat, const VerifyOptions *quad, Vec loc_bc, Vec r0, PetscReal *lift);
PetscErrorCode WeakDataExactStress(const Scene *scene, const Material *mat, PetscInt dim, const PetscReal x[], PetscReal sigma[]);
PetscErrorCode WeakDataExactNormalStress(const Scene *scene, const Material *mat, PetscInt dim, const PetscReal x[], PetscReal *sn);

/* postprocess.c */
PetscErrorCode PostprocessContact(DM dm, Contact contact, const Problem *prob, const BoundarySet *bcs, const Material *mat, Vec u,
                                  SolutionQuantities *sq);
PetscErrorCode PostprocessLiftEnergy(DM dm, const Material *mat, const Problem *prob, PetscReal weak_lift, PetscReal *energy);
PetscErrorCode PostprocessPenetration(const ErrorNorms *errors, SolutionQuantities *sq);
PetscErrorCode PostprocessView(MPI_Comm comm, const SolutionQuantities *sq);                                       /* the summary's line */
PetscErrorCode PostprocessWrite(const SolutionQuantities *s, const BoundarySet *bcs, PetscInt dim, PetscViewer v); /* the quantities in /run */
PetscReal      PostprocessForceMagnitude(const Quantities *q, PetscInt dim);
/* contact_zone.c */
PetscErrorCode PostprocessContactSize(DM dm, Contact contact, const BoundarySet *bcs, const Material *mat, Vec u, PetscReal *size, PetscReal *band);
PetscErrorCode PostprocessPressureStep(DM dm, Contact contact, const BoundarySet *bcs, PetscReal pressure_max, PetscReal *step);
PetscErrorCode PostprocessContactEdgeFaces(DM dm, Contact contact, const BoundarySet *bcs, const Material *mat, Vec u, PetscInt *n, PetscInt **faces);
/* pressure_peak.c */
PetscErrorCode PostprocessPressurePeak(DM dm, Contact contact, PetscReal pressure_max, PetscReal step, PetscReal *peak, PetscReal *resolution);

/* contact_checks.c */
/* What the checks before the solve read */
typedef struct {
  Contact         contact;
  const Scene    *scene;            /* Gamma_C's face sets and the obstacle */
  const Material *material;         /* a nearly incompressible body, */
  PetscInt        degree;           /*   of P1/Q1 */
  const MeshBox  *box;              /* a mesh file's curved boundary, refined box->refine times by -dm_refine, */
  PetscInt        grid_refinements; /*   and this many by the solver on its chords (-contact_grid_sequence; 0 where a model remeshes) */
} ContactChecksGeometryInputs;
PetscErrorCode ContactChecksGeometry(DM dm, const ContactChecksGeometryInputs *in, ContactChecks *ck);
PetscErrorCode ContactChecksResolution(DM dm, Contact contact, const BoundarySet *bcs, const PetscReal force_vector[3], Vec u, ContactChecks *ck);
PetscErrorCode ContactChecksWarnings(MPI_Comm comm, const ContactChecks *ck, PetscBool print, PetscInt *nwarnings);
PetscErrorCode ContactChecksWrite(MPI_Comm comm, const ContactChecks *ck, PetscViewer v); /* their part of /run */

/* elasticity.c: sigma(grad u) = lambda tr(eps) I + 2 mu eps, grad[i*dim+j] = du_i/dx_j */
void ElasticStress(PetscInt dim, const Material *mat, const PetscReal grad[], PetscReal sigma[]);

/* boundary.c */
PetscErrorCode BoundaryAddDirichlet(DM dm, const Scene *scene, DMLabel face_sets);
PetscErrorCode BoundaryInsertDirichlet(DM dm, const Scene *scene, DMLabel face_sets, PetscInt degree, Vec loc);
PetscErrorCode BoundaryAddLoads(DM dm, const BoundarySet *bcs, DMLabel face_sets, Vec loc_r0, Vec r0);
PetscErrorCode BoundaryAddLoadsLocal(DM dm, const BoundarySet *bcs, DMLabel face_sets, Vec locF);
PetscErrorCode BoundaryComputeReactions(DM dm, const BoundarySet *bcs, const Material *mat, const Problem *prob, Vec u, PetscReal reaction[][3]);
PetscErrorCode BoundaryCheckFaceSets(DM dm, const Scene *scene);
PetscErrorCode BoundaryCheckRigidMotions(DM dm, const Scene *scene);
