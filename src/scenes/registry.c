/* Scenes are registered by name; -scene NAME picks one. */
#include "app.h"
#include "scenes.h"

static PetscFunctionList scene_list = NULL;

PetscErrorCode SceneRegisterAll(void)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFunctionListAdd(&scene_list, "square", SceneCreate_Square));
  PetscCall(PetscFunctionListAdd(&scene_list, "patch", SceneCreate_Patch));
  PetscCall(PetscFunctionListAdd(&scene_list, "mms", SceneCreate_MMS));
  PetscCall(PetscFunctionListAdd(&scene_list, "general", SceneCreate_General));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode SceneFinalize(void)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFunctionListDestroy(&scene_list));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Reads -scene (listed by -help) into name. */
PetscErrorCode SceneGetOptions(MPI_Comm comm, char name[], size_t len)
{
  PetscFunctionBeginUser;
  PetscOptionsBegin(comm, NULL, "Scene", "Signorini");
  PetscCall(PetscStrncpy(name, "square", len));
  PetscCall(PetscOptionsFList("-scene", "Problem set-up", NULL, scene_list, name, name, len, NULL));
  PetscOptionsEnd();
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode SceneCreate(const char name[], DM dm, const Material *mat, Scene *scene)
{
  SceneCreateFn create;

  PetscFunctionBeginUser;
  PetscCall(PetscFunctionListFind(scene_list, name, &create));
  PetscCheck(create, PetscObjectComm((PetscObject)dm), PETSC_ERR_USER_INPUT,
             "Unknown scene '%s' (-scene); run with -help to list the registered scenes", name);
  PetscCall(PetscMemzero(scene, sizeof(*scene)));
  PetscCall(PetscStrncpy(scene->name, name, sizeof(scene->name)));
  PetscCall((*create)(dm, mat, scene)); /* the scene's own options and its defaults of the ones below */
  PetscCall(SceneBoundaryGetOptions(dm, scene));
  PetscCall(SceneObstacleGetOptions(dm, scene));
  PetscCall(OptionsCheckPrefixesUsed(PetscObjectComm((PetscObject)dm), "-bc_ -obstacle -contact_faces -body_force")); /* typos, before the solve */
  PetscFunctionReturn(PETSC_SUCCESS);
}
