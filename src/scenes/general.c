/* Scene "general": the whole problem from the options. It has no boundary condition of its own: -contact_faces names
   Gamma_C, -bc_clamp, -bc_slip, -bc_traction, -bc_pressure the other face sets, -body_force the load, -obstacle the
   foundation (by default the plane x_d = 0 below the body, as in the built-in scenes). */
#include "scenes.h"

PetscErrorCode SceneCreate_General(DM dm, const Material *mat, Scene *scene)
{
  PetscInt dim;

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(SceneSetFoundation(scene, dim));
  PetscFunctionReturn(PETSC_SUCCESS);
}
