/* The discrete problem on one mesh: everything that depends on the mesh, set up and destroyed as a unit
   (the grid sequencing sets up one per level). */
#include "contact.h"
#include "discretization.h"
#include "mesh.h"
#include "physics.h"
#include "solver_impl.h"

PetscErrorCode ProblemSetUp(DM dm, Solver s, const Scene *scene, SNES *snes)
{
  PetscLogDouble t0, t1;

  PetscFunctionBeginUser;
  PetscCall(PetscTime(&t0));
  for (PetscInt i = 0; i < scene->bcs.ncontact; ++i) PetscCall(MeshCheckContactBoundary(dm, scene->bcs.contact_ids[i]));
  PetscCall(BoundaryCheckFaceSets(dm, scene));
  PetscCall(DMGetLabel(dm, "Face Sets", &s->prob.face_sets));
  PetscCall(MeshGetMaxCellDiameter(dm, &s->prob.h));
  PetscCall(ElasticitySetUpDiscretization(dm, scene, s->opt->degree));
  PetscCall(BoundaryAddDirichlet(dm, scene, s->prob.face_sets)); /* Gamma_D, before anything builds the section */
  PetscCall(ElasticityUpdateConstants(dm, &s->opt->material, scene));
  PetscCall(SectionSetUpP1(dm, s->opt->degree, s->opt->section_check)); /* P1/Q1: the local section without PETSc's cell-type lookups */
  PetscCall(BoundaryCheckRigidMotions(dm, scene));
  PetscCall(DMCreateLocalVector(dm, &s->prob.loc_bc)); /* the Dirichlet values, zero elsewhere */
  PetscCall(DMCreateGlobalVector(dm, &s->prob.r0));    /* F(0), assembled below; the set-up's global vectors duplicate it */
  PetscCall(VecZeroEntries(s->prob.loc_bc));
  PetscCall(BoundaryInsertDirichlet(dm, scene, s->prob.face_sets, s->opt->degree, s->prob.loc_bc));
  /* -assembly auto: fe or p1 for this mesh */
  PetscCall(AssemblyResolve(dm, s->opt->assembly, s->opt->degree, s->opt->assembly_check, &s->prob.assembly));
  {
    ContactProblem cp;

    cp.bcs            = &scene->bcs;
    cp.obstacle       = &scene->obstacle;
    cp.material       = &s->opt->material;
    cp.degree         = s->opt->degree;
    cp.assembly       = s->prob.assembly; /* resolved above */
    cp.assembly_check = s->opt->assembly_check;
    cp.loc_bc         = s->prob.loc_bc;
    cp.like           = s->prob.r0;
    PetscCall(MeshGetMaxCellSize(dm, s->prob.h, &cp.h)); /* h, or the mesh's own sizes (the bars' levels, grid_sequence.c) */
    PetscCall(ContactSetUp(s->contact, dm, &cp));        /* the contact set, eps, the penalty's faces or SNESVI's bounds */
  }
  PetscCall(SolverAssembleBulk(dm, s->opt, &s->prob));
  PetscCall(SolverAssembleLoad(dm, s->opt, scene, &s->prob));
  PetscCall(SolverCtxCreate(s->prob.K, s->prob.r0, s->contact, &s->opt->solver, &s->stats, &s->prob.sctx));
  PetscCall(SolverComputeScales(dm, s->contact, &s->prob));
  PetscCall(SolverCreateSNES(dm, s->contact, &s->opt->solver, &s->prob, s->mg, s->box, snes));
  PetscCall(PetscTime(&t1));
  s->prob.setup_time = t1 - t0;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode ProblemDestroy(Solver s, SNES *snes)
{
  PetscFunctionBeginUser;
  PetscCall(SNESDestroy(snes));
  PetscCall(MatDestroy(&s->prob.K));
  PetscCall(VecDestroy(&s->prob.r0));
  PetscCall(VecDestroy(&s->prob.loc_r0));
  PetscCall(VecDestroy(&s->prob.loc_bc));
  PetscCall(ContactReset(s->contact));
  PetscCall(SolverCtxDestroy(&s->prob.sctx));
  PetscFunctionReturn(PETSC_SUCCESS);
}
