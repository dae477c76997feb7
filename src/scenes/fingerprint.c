/* The problem a run solves, as one string (/run attribute "problem"): the scene, the material, the boundary families
   with their face sets and values, the body force, the obstacle and the scene's own constants. A -reference run must
   solve the same problem (on a finer mesh, by any method, with any eps): its string must equal this run's. Reals are
   written with 17 digits, so that equal strings mean equal data. */
#include "scenes.h"

static PetscErrorCode AppendVector(char buf[], size_t len, const char name[], PetscInt n, const PetscReal v[])
{
  char item[96];

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(item, sizeof(item), " %s=", name));
  PetscCall(PetscStrlcat(buf, item, len));
  for (PetscInt k = 0; k < n; ++k) {
    PetscCall(PetscSNPrintf(item, sizeof(item), "%s%.17g", k ? "," : "", (double)v[k]));
    PetscCall(PetscStrlcat(buf, item, len));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Items separated by "; ", in a fixed order (the families in the order of their kinds, the face sets sorted). */
PetscErrorCode SceneFingerprint(const Scene *scene, const Material *mat, PetscInt dim, char buf[], size_t len)
{
  const BoundarySet *bcs = &scene->bcs;
  const Obstacle    *ob  = &scene->obstacle;
  char               item[256];
  PetscInt           ids[BOUNDARY_MAX];

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(buf, len, "scene %s; dim %" PetscInt_FMT "; E %.17g; nu %.17g", scene->name, dim, (double)mat->young_modulus,
                          (double)mat->poisson_ratio));
  for (PetscInt i = 0; i < bcs->ncontact; ++i) ids[i] = bcs->contact_ids[i];
  PetscCall(PetscSortInt(bcs->ncontact, ids));
  PetscCall(PetscStrlcat(buf, "; contact", len));
  for (PetscInt i = 0; i < bcs->ncontact; ++i) {
    PetscCall(PetscSNPrintf(item, sizeof(item), " %" PetscInt_FMT, ids[i]));
    PetscCall(PetscStrlcat(buf, item, len));
  }
  for (PetscInt kind = 0; kind < BC_NUM_KINDS; ++kind) {
    PetscInt n = 0, order[BOUNDARY_MAX];

    for (PetscInt i = 0; i < bcs->n; ++i)
      if (bcs->bc[i].kind == (BoundaryKind)kind) {
        ids[n]   = bcs->bc[i].id;
        order[n] = i;
        ++n;
      }
    PetscCall(PetscSortIntWithArray(n, ids, order));
    for (PetscInt k = 0; k < n; ++k) {
      const BoundaryCondition *bc = &bcs->bc[order[k]];

      PetscCall(PetscSNPrintf(item, sizeof(item), "; %s %" PetscInt_FMT, BoundaryKinds[kind], bc->id));
      PetscCall(PetscStrlcat(buf, item, len));
      if (bc->kind == BC_SLIP) {
        PetscReal comps[3];

        for (PetscInt c = 0; c < bc->ncomp; ++c) comps[c] = (PetscReal)bc->comps[c];
        PetscCall(AppendVector(buf, len, "components", bc->ncomp, comps));
      }
      if (bc->kind == BC_PRESSURE)
        PetscCall(AppendVector(buf, len, "p", 1, bc->value));
      else if (bc->fn)
        PetscCall(PetscStrlcat(buf, " value=scene", len));
      else
        PetscCall(AppendVector(buf, len, "value", dim, bc->value));
    }
  }
  PetscCall(PetscStrlcat(buf, "; body force", len));
  PetscCall(AppendVector(buf, len, "", dim, bcs->body_force));
  PetscCall(PetscSNPrintf(item, sizeof(item), "; obstacle %s", ObstacleTypes[ob->type]));
  PetscCall(PetscStrlcat(buf, item, len));
  PetscCall(AppendVector(buf, len, "point", dim, ob->point));
  if (ob->type != OBSTACLE_SPHERE) PetscCall(AppendVector(buf, len, "direction", dim, ob->direction));
  if (ob->type == OBSTACLE_SPHERE || ob->type == OBSTACLE_CYLINDER) PetscCall(AppendVector(buf, len, "radius", 1, &ob->radius));
  if (ob->type == OBSTACLE_CONE) PetscCall(AppendVector(buf, len, "half_angle", 1, &ob->half_angle));
  if (ob->type == OBSTACLE_PUNCH) {
    PetscCall(AppendVector(buf, len, "radius", 1, &ob->radius));
    PetscCall(AppendVector(buf, len, "edge_radius", 1, &ob->edge_radius));
  }
  PetscCall(AppendVector(buf, len, "translate", dim, ob->translate));
  if (scene->num_constants) {
    PetscReal c[CONST_SCENE_MAX - CONST_SCENE];

    for (PetscInt k = 0; k < scene->num_constants; ++k) c[k] = PetscRealPart(scene->constants[k]);
    PetscCall(PetscStrlcat(buf, "; scene constants", len));
    PetscCall(AppendVector(buf, len, "", scene->num_constants, c));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}
