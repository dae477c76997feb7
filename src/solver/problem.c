/* The discrete problem on one mesh: everything that depends on the mesh, set up and destroyed as a unit
   (the grid sequencing sets up one per level). */
#include "contact.h"
#include "discretization.h"
#include "mesh.h"
#include "physics.h"
#include "solver_impl.h"

PetscErrorCode ProblemSetUp(DM dm, AppCtx *user, SNES *snes)
{
  PetscLogDouble t0, t1;

  PetscFunctionBeginUser;
  PetscCall(PetscTime(&t0));
  for (PetscInt i = 0; i < user->scene.bcs.ncontact; ++i) PetscCall(MeshCheckContactBoundary(dm, user->scene.bcs.contact_ids[i]));
  PetscCall(BoundaryCheckFaceSets(dm, &user->scene));
  PetscCall(DMGetLabel(dm, "Face Sets", &user->prob.face_sets));
  PetscCall(MeshGetMaxCellDiameter(dm, &user->prob.h));
  PetscCall(ElasticitySetUpDiscretization(dm, &user->scene, user->opt->degree));
  PetscCall(BoundaryAddDirichlet(dm, &user->scene, user->prob.face_sets)); /* Gamma_D, before anything builds the section */
  PetscCall(ElasticityUpdateConstants(dm, &user->opt->material, &user->scene));
  PetscCall(SectionSetUpP1(dm, user->opt->degree, user->opt->section_check)); /* P1/Q1: the local section without PETSc's cell-type lookups */
  PetscCall(BoundaryCheckRigidMotions(dm, &user->scene));
  PetscCall(DMCreateLocalVector(dm, &user->prob.loc_bc)); /* the Dirichlet values, zero elsewhere */
  PetscCall(DMCreateGlobalVector(dm, &user->prob.r0));    /* F(0), assembled below; the set-up's global vectors duplicate it */
  PetscCall(VecZeroEntries(user->prob.loc_bc));
  PetscCall(BoundaryInsertDirichlet(dm, &user->scene, user->prob.face_sets, user->opt->degree, user->prob.loc_bc));
  /* -assembly auto: fe or p1 for this mesh */
  PetscCall(AssemblyResolve(dm, user->opt->assembly, user->opt->degree, user->opt->assembly_check, &user->prob.assembly));
  {
    ContactProblem cp;

    cp.bcs            = &user->scene.bcs;
    cp.obstacle       = &user->scene.obstacle;
    cp.material       = &user->opt->material;
    cp.degree         = user->opt->degree;
    cp.assembly       = user->prob.assembly; /* resolved above */
    cp.assembly_check = user->opt->assembly_check;
    cp.loc_bc         = user->prob.loc_bc;
    cp.like           = user->prob.r0;
    PetscCall(MeshGetMaxCellSize(dm, user->prob.h, &cp.h)); /* h, or the mesh's own sizes (the bars' levels, grid_sequence.c) */
    PetscCall(ContactSetUp(user->contact, dm, &cp));        /* the contact set, eps, the penalty's faces or SNESVI's bounds */
  }
  PetscCall(SolverAssembleBulk(dm, user->opt, &user->prob));
  PetscCall(SolverAssembleLoad(dm, user->opt, &user->scene, &user->prob));
  PetscCall(SolverCtxCreate(user->prob.K, user->prob.r0, user->contact, &user->opt->solver, &user->rec.stats, &user->prob.sctx));
  PetscCall(SolverComputeScales(dm, user->contact, &user->prob));
  PetscCall(SolverCreateSNES(dm, user->contact, &user->opt->solver, &user->prob, user->mg, &user->box, snes));
  PetscCall(PetscTime(&t1));
  user->prob.setup_time = t1 - t0;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode ProblemDestroy(AppCtx *user, SNES *snes)
{
  PetscFunctionBeginUser;
  PetscCall(SNESDestroy(snes));
  PetscCall(MatDestroy(&user->prob.K));
  PetscCall(VecDestroy(&user->prob.r0));
  PetscCall(VecDestroy(&user->prob.loc_r0));
  PetscCall(VecDestroy(&user->prob.loc_bc));
  PetscCall(ContactReset(user->contact));
  PetscCall(SolverCtxDestroy(&user->prob.sctx));
  PetscFunctionReturn(PETSC_SUCCESS);
}
