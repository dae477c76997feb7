/* Scenes: problem set-ups registered by name (src/scenes/). */
#pragma once
#include "signorini.h"

/* scenes/registry.c */
PetscErrorCode SceneRegisterAll(void);
PetscErrorCode SceneFinalize(void);
PetscErrorCode SceneCreate(const char name[], DM dm, const Material *mat, Scene *scene);
PetscErrorCode SceneGetOptions(MPI_Comm comm, char name[], size_t len);
PetscErrorCode SceneCreate_Square(DM, const Material *, Scene *);
PetscErrorCode SceneCreate_Patch(DM, const Material *, Scene *);
PetscErrorCode SceneCreate_MMS(DM, const Material *, Scene *);
PetscErrorCode SceneCreate_General(DM, const Material *, Scene *);

/* scenes/boundary_options.c, scenes/obstacle_options.c: the scenes' defaults, then the options */
PetscErrorCode SceneAddBoundary(Scene *scene, BoundaryKind kind, PetscInt id, ScenePointFn fn);
PetscErrorCode SceneAddContactFaces(Scene *scene, PetscInt id);
PetscErrorCode SceneSetObstaclePlane(Scene *scene, const PetscReal point[], const PetscReal n[]);
PetscErrorCode SceneSetFoundation(Scene *scene, PetscInt dim);
PetscErrorCode SceneBoundaryGetOptions(DM dm, Scene *scene);
PetscErrorCode SceneObstacleGetOptions(DM dm, Scene *scene);

/* scenes/load_factor.c: the factor of a load path on every prescribed datum */
PetscErrorCode SceneCheckLoadPath(MPI_Comm comm, const Scene *scene, const char what[]);
PetscErrorCode SceneSetLoadFactor(Scene *scene, PetscReal t);
PetscErrorCode SceneSetObstaclePosition(Scene *scene, PetscReal s);
PetscBool      SceneForceControlled(const Scene *scene);

/* scenes/fingerprint.c: the problem as one string, for -reference */
#define SCENE_FINGERPRINT_LEN 4096
PetscErrorCode SceneFingerprint(const Scene *scene, const Material *mat, PetscInt dim, char buf[], size_t len);
/* scene_write.c: the scene's part of /run */
PetscErrorCode SceneWrite(const Scene *scene, const Material *mat, PetscInt dim, PetscViewer v);
