/* The factor of a load path (-load_steps, -load_path): every datum a scene prescribes, scaled by one factor t. The
   problem is linear in its data but for the contact, so the bulk part of the residual at u = 0, r0 = K_fD u_D - f,
   scales with t too; the obstacle moves by t times its translation, and its initial gap does not scale. */
#include "app.h"
#include "scenes.h"

/* Whether the scene's data can be scaled: a scene that prescribes its solution (an exact displacement on Gamma_D, a
   load in weak form from it) is one load state. */
PetscErrorCode SceneCheckLoadPath(MPI_Comm comm, const Scene *scene, const char what[])
{
  PetscFunctionBeginUser;
  PetscCheck(!scene->weak_data, comm, PETSC_ERR_USER_INPUT,
             "%s change the loads and translations that the options give; the scene %s takes its load from its "
             "manufactured solution, one load state: use the scene general (or square)",
             what, scene->name);
  for (PetscInt i = 0; i < scene->bcs.n; ++i)
    PetscCheck(!scene->bcs.bc[i].fn, comm, PETSC_ERR_USER_INPUT,
               "%s change the loads and translations that the options give; the scene %s prescribes its own "
               "displacement on face set %s: give it by -bc_clamp_%s_translate, or use the scene general",
               what, scene->name, scene->bcs.bc[i].token, scene->bcs.bc[i].token);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Every prescribed datum at t times its value at the factor 1 (kept on the first call): the clamps' and slips'
   translations, the tractions and pressures, the body force, the scene's constants that are loads, and the obstacle's
   translation. */
PetscErrorCode SceneSetLoadFactor(Scene *scene, PetscReal t)
{
  const PetscInt nc = scene->num_constants;

  PetscFunctionBeginUser;
  if (!scene->full_load.kept) {
    for (PetscInt i = 0; i < scene->bcs.n; ++i)
      for (PetscInt c = 0; c < 3; ++c) scene->full_load.value[i][c] = scene->bcs.bc[i].value[c];
    for (PetscInt c = 0; c < 3; ++c) {
      scene->full_load.body_force[c] = scene->bcs.body_force[c];
      scene->full_load.translate[c]  = scene->obstacle.translate[c];
    }
    for (PetscInt k = 0; k < nc; ++k) scene->full_load.constants[k] = scene->constants[k];
    scene->full_load.force = scene->obstacle.force;
    scene->full_load.kept  = PETSC_TRUE;
  }
  for (PetscInt i = 0; i < scene->bcs.n; ++i)
    for (PetscInt c = 0; c < 3; ++c) scene->bcs.bc[i].value[c] = t * scene->full_load.value[i][c];
  for (PetscInt c = 0; c < 3; ++c) {
    scene->bcs.body_force[c]     = t * scene->full_load.body_force[c];
    scene->obstacle.translate[c] = t * scene->full_load.translate[c];
  }
  for (PetscInt k = 0; k < nc; ++k) scene->constants[k] = scene->load_constant[k] ? t * scene->full_load.constants[k] : scene->full_load.constants[k];
  scene->obstacle.force = t * scene->full_load.force;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Whether the obstacle is driven by a force (-obstacle_force), at any load factor: the factor 0 makes its target 0. */
PetscBool SceneForceControlled(const Scene *scene)
{
  return (PetscBool)((scene->full_load.kept ? scene->full_load.force : scene->obstacle.force) > 0.0);
}

/* The obstacle at the translation s times the unit direction of its full translation (force control, load_path.c;
   after SceneSetLoadFactor(), which keeps it). */
PetscErrorCode SceneSetObstaclePosition(Scene *scene, PetscReal s)
{
  PetscReal len = 0.0;

  PetscFunctionBeginUser;
  PetscCheck(scene->full_load.kept, PETSC_COMM_SELF, PETSC_ERR_ORDER, "SceneSetObstaclePosition() needs SceneSetLoadFactor() first");
  for (PetscInt c = 0; c < 3; ++c) len += PetscSqr(scene->full_load.translate[c]);
  len = PetscSqrtReal(len);
  PetscCheck(len > 0.0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "the obstacle has no direction to move in");
  for (PetscInt c = 0; c < 3; ++c) scene->obstacle.translate[c] = s * scene->full_load.translate[c] / len;
  PetscFunctionReturn(PETSC_SUCCESS);
}
