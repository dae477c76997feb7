/* The scene's part of /run: its name, the material, the obstacle as the run left it (a load path's or force control's
   last translation), the problem's fingerprint that -reference compares, and the scene's own parameters scene_0, ... */
#include "app.h"
#include "scenes.h"

PetscErrorCode SceneWrite(const Scene *scene, const Material *mat, PetscInt dim, PetscViewer v)
{
  char problem[SCENE_FINGERPRINT_LEN];

  PetscFunctionBeginUser;
  PetscCall(RunAttrString(v, scene->name, "scene"));
  PetscCall(RunAttrReal(v, mat->young_modulus, "young_modulus"));
  PetscCall(RunAttrReal(v, mat->poisson_ratio, "poisson_ratio"));
  PetscCall(RunAttrString(v, ObstacleTypes[scene->obstacle.type], "obstacle"));
  for (PetscInt c = 0; c < dim; ++c) PetscCall(RunAttrReal(v, scene->obstacle.translate[c], "obstacle_translate_%c", "xyz"[c]));
  if (SceneForceControlled(scene))
    PetscCall(RunAttrReal(v, scene->obstacle.force, "obstacle_force")); /* the target (the last step's: 0 at the factor 0) */
  PetscCall(SceneFingerprint(scene, mat, dim, problem, sizeof(problem)));
  PetscCall(RunAttrString(v, problem, "problem"));
  for (PetscInt i = 0; i < scene->num_constants; ++i) PetscCall(RunAttrReal(v, PetscRealPart(scene->constants[i]), "scene_%" PetscInt_FMT, i));
  PetscFunctionReturn(PETSC_SUCCESS);
}
