/* The rigid obstacle: the scene's default, then -obstacle plane | sphere | cylinder | cone | punch and its geometry, read once. */
#include "app.h"
#include "scenes.h"

const char *const ObstacleTypes[] = {"plane", "sphere", "cylinder", "cone", "punch", "ObstacleType", "OBSTACLE_", NULL};

/* A default of a scene: the plane through point with unit normal n (from the body into the obstacle). */
PetscErrorCode SceneSetObstaclePlane(Scene *scene, const PetscReal point[], const PetscReal n[])
{
  PetscFunctionBeginUser;
  PetscCall(PetscMemzero(&scene->obstacle, sizeof(scene->obstacle)));
  scene->obstacle.type = OBSTACLE_PLANE;
  for (PetscInt c = 0; c < 3; ++c) {
    scene->obstacle.point[c]     = point[c];
    scene->obstacle.direction[c] = n[c];
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A default of a scene: the foundation plane x_d = 0 below the body (normal -e_d), the built-in scenes' one. */
PetscErrorCode SceneSetFoundation(Scene *scene, PetscInt dim)
{
  const PetscReal origin[3] = {0.0, 0.0, 0.0};
  PetscReal       n[3]      = {0.0, 0.0, 0.0};

  PetscFunctionBeginUser;
  n[dim - 1] = -1.0;
  PetscCall(SceneSetObstaclePlane(scene, origin, n));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* -NAME as dim reals (OptionsReadVector); required: refuse its absence (what: the option that needs it). */
static PetscErrorCode ReadVector(CompatOptionItems PetscOptionsObject, MPI_Comm comm, const char name[], const char help[], PetscInt dim,
                                 PetscBool required, const char what[], PetscReal v[])
{
  PetscBool set;

  PetscFunctionBeginUser;
  PetscCall(OptionsReadVector(PetscOptionsObject, comm, name, help, dim, v, &set));
  PetscCheck(set || !required, comm, PETSC_ERR_USER_INPUT, "%s needs %s (%" PetscInt_FMT " comma-separated values)", what, name, dim);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Scales v (dim entries) to unit length; refuses a zero vector. */
static PetscErrorCode Normalize(MPI_Comm comm, const char name[], PetscInt dim, PetscReal v[])
{
  PetscReal len = 0.0;

  PetscFunctionBeginUser;
  for (PetscInt c = 0; c < dim; ++c) len += v[c] * v[c];
  len = PetscSqrtReal(len);
  PetscCheck(len > 0.0, comm, PETSC_ERR_USER_INPUT, "%s must not be the zero vector", name);
  for (PetscInt c = 0; c < dim; ++c) v[c] /= len;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Whether -name is on the command line itself (not in an options file it names). */
static PetscErrorCode OnCommandLine(const char name[], PetscBool *on)
{
  int    argc;
  char **args;

  PetscFunctionBeginUser;
  *on = PETSC_FALSE;
  PetscCall(PetscGetArgs(&argc, &args));
  for (int i = 1; i < argc && !*on; ++i) PetscCall(PetscStrcmp(args[i], name, on));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The geometry options of the obstacle types other than the one in use, in dim, where the command line's -obstacle
   overrides an options file's (later options override earlier ones): the file's cylinder options under the command
   line's -obstacle plane. The type in use does not read them, so that the typo check would refuse them; they are
   instead marked read and named in one line, as PETSc leaves a KSP type's options unused under another type. Another
   type's option given on the command line itself (-obstacle plane -obstacle_radius 1), or in a file whose type the
   command line does not override, is still refused as unused, and so is a name no type reads in dim (-obstacle_axis
   in 2D). */
static PetscErrorCode OtherTypesGetOptions(MPI_Comm comm, ObstacleType type, PetscInt dim)
{
  const struct {
    const char *name;
    PetscInt    min_dim[5]; /* the smallest dimension in which plane, sphere, cylinder, cone, punch reads it (4: never) */
  } geometry[] = {
      {"-obstacle_point", {2, 4, 4, 2, 2}},       {"-obstacle_normal", {2, 4, 4, 4, 4}}, {"-obstacle_center", {4, 2, 2, 4, 4}},
      {"-obstacle_radius", {4, 2, 2, 4, 2}},      {"-obstacle_axis", {4, 4, 3, 2, 2}},   {"-obstacle_half_angle", {4, 4, 4, 2, 4}},
      {"-obstacle_edge_radius", {4, 4, 4, 4, 2}},
  };
  char      list[256] = "";
  PetscBool overridden;

  PetscFunctionBeginUser;
  PetscCall(OnCommandLine("-obstacle", &overridden));
  for (size_t k = 0; k < sizeof(geometry) / sizeof(geometry[0]) && overridden; ++k) {
    PetscBool set, given_here;
    PetscInt  lowest = 4; /* the smallest dimension in which any type reads it */

    for (PetscInt j = 0; j < 5; ++j) lowest = PetscMin(lowest, geometry[k].min_dim[j]);
    if (dim >= geometry[k].min_dim[type] || dim < lowest) continue;
    PetscCall(OnCommandLine(geometry[k].name, &given_here));
    if (given_here) continue;
    PetscCall(PetscOptionsHasName(NULL, NULL, geometry[k].name, &set)); /* marks it read */
    if (!set) continue;
    PetscCall(PetscStrlcat(list, " ", sizeof(list)));
    PetscCall(PetscStrlcat(list, geometry[k].name, sizeof(list)));
  }
  if (list[0])
    PetscCall(PetscPrintf(comm,
                          "note: -obstacle %s does not use%s (another obstacle type's options, from an options file whose -obstacle the command line "
                          "overrides): ignored\n",
                          ObstacleTypes[type], list));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode SceneObstacleGetOptions(DM dm, Scene *scene)
{
  MPI_Comm   comm = PetscObjectComm((PetscObject)dm);
  Obstacle  *obs  = &scene->obstacle;
  PetscInt   dim;
  PetscBool  type_set;
  const char what[] = "-obstacle";

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscCall(OptionsCheckEnum(comm, "-obstacle", ObstacleTypes, PETSC_FALSE)); /* one obstacle per run, named in full */
  PetscOptionsBegin(comm, NULL, "Rigid obstacle", "Signorini");
  PetscCall(PetscOptionsEnum(
      "-obstacle",
      "Rigid obstacle: plane, sphere (the body stays outside a ball), cylinder (in 2D a disk), cone (in 2D a wedge), punch (a flat punch)", NULL,
      ObstacleTypes, (PetscEnum)obs->type, (PetscEnum *)&obs->type, &type_set));
  switch (obs->type) {
    case OBSTACLE_PLANE:
      PetscCall(ReadVector(PetscOptionsObject, comm, "-obstacle_point", "A point of the plane", dim, PETSC_FALSE, what, obs->point));
      PetscCall(ReadVector(PetscOptionsObject, comm, "-obstacle_normal", "Normal of the plane, from the body into the obstacle", dim, PETSC_FALSE,
                           what, obs->direction));
      PetscCall(Normalize(comm, "-obstacle_normal", dim, obs->direction));
      break;
    case OBSTACLE_SPHERE:
    case OBSTACLE_CYLINDER: {
      const PetscBool required = (PetscBool)(type_set && scene->obstacle.radius <= 0.0);
      const char     *kind     = obs->type == OBSTACLE_SPHERE ? "-obstacle sphere" : "-obstacle cylinder";
      PetscBool       set;

      PetscCall(ReadVector(PetscOptionsObject, comm, "-obstacle_center", "Center of the sphere or a point of the cylinder's axis", dim, required,
                           kind, obs->point));
      PetscCall(PetscOptionsReal("-obstacle_radius", "Radius of the sphere or cylinder", NULL, obs->radius, &obs->radius, &set));
      PetscCall(OptionsCheckFinite(comm, "-obstacle_radius", obs->radius));
      PetscCheck(obs->radius > 0.0, comm, PETSC_ERR_USER_INPUT, "%s needs a positive -obstacle_radius, got %g", kind, (double)obs->radius);
      if (obs->type == OBSTACLE_CYLINDER && dim == 3) {
        PetscCall(ReadVector(PetscOptionsObject, comm, "-obstacle_axis", "Direction of the cylinder's axis", dim, required, kind, obs->direction));
        PetscCall(Normalize(comm, "-obstacle_axis", dim, obs->direction));
      }
    } break;
    case OBSTACLE_CONE: {
      const char kind[] = "-obstacle cone";
      PetscBool  set;

      PetscCall(ReadVector(PetscOptionsObject, comm, "-obstacle_point", "The cone's apex", dim, type_set, kind, obs->point));
      PetscCall(ReadVector(PetscOptionsObject, comm, "-obstacle_axis", "The cone's axis, from its apex into it (away from the body)", dim, type_set,
                           kind, obs->direction));
      PetscCall(Normalize(comm, "-obstacle_axis", dim, obs->direction));
      PetscCall(PetscOptionsReal("-obstacle_half_angle", "The cone's half-angle, between its axis and its surface, in degrees", NULL, obs->half_angle,
                                 &obs->half_angle, &set));
      PetscCheck(set || !type_set, comm, PETSC_ERR_USER_INPUT, "%s needs -obstacle_half_angle (degrees, in (0, 90))", kind);
      PetscCall(OptionsCheckFinite(comm, "-obstacle_half_angle", obs->half_angle));
      PetscCheck(obs->half_angle > 0.0 && obs->half_angle < 90.0, comm, PETSC_ERR_USER_INPUT,
                 "-obstacle_half_angle must lie in (0, 90) degrees (a cone between a needle and a plane), got %g", (double)obs->half_angle);
    } break;
    case OBSTACLE_PUNCH: {
      const char kind[] = "-obstacle punch";
      PetscBool  set;

      PetscCall(ReadVector(PetscOptionsObject, comm, "-obstacle_point", "The center of the punch's flat end", dim, type_set, kind, obs->point));
      PetscCall(ReadVector(PetscOptionsObject, comm, "-obstacle_axis", "The punch's axis, from its flat end into it (away from the body)", dim,
                           type_set, kind, obs->direction));
      PetscCall(Normalize(comm, "-obstacle_axis", dim, obs->direction));
      PetscCall(
          PetscOptionsReal("-obstacle_radius", "The radius of the punch's flat end (in 2D its half-width)", NULL, obs->radius, &obs->radius, &set));
      PetscCall(OptionsCheckFinite(comm, "-obstacle_radius", obs->radius));
      PetscCheck(obs->radius > 0.0, comm, PETSC_ERR_USER_INPUT, "%s needs a positive -obstacle_radius (its flat end's), got %g", kind,
                 (double)obs->radius);
      PetscCall(PetscOptionsReal("-obstacle_edge_radius", "The radius of the fillet round the punch's edge (0: a sharp edge)", NULL, obs->edge_radius,
                                 &obs->edge_radius, NULL));
      PetscCall(OptionsCheckFinite(comm, "-obstacle_edge_radius", obs->edge_radius));
      PetscCheck(obs->edge_radius >= 0.0, comm, PETSC_ERR_USER_INPUT, "-obstacle_edge_radius must be >= 0 (0: a sharp edge), got %g",
                 (double)obs->edge_radius);
    } break;
  }
  PetscCall(ReadVector(PetscOptionsObject, comm, "-obstacle_translate", "Rigid translation of the obstacle (an indenter driven by displacement)", dim,
                       PETSC_FALSE, what, obs->translate));
  {
    PetscBool set;
    PetscReal len = 0.0;

    PetscCall(PetscOptionsReal("-obstacle_force", "Drive the obstacle along -obstacle_translate's direction until it presses with this force", NULL,
                               obs->force, &obs->force, &set));
    if (set) {
      PetscCall(OptionsCheckFinite(comm, "-obstacle_force", obs->force));
      PetscCheck(obs->force > 0.0, comm, PETSC_ERR_USER_INPUT, "-obstacle_force must be positive (the obstacle can only press on the body), got %g",
                 (double)obs->force);
      for (PetscInt c = 0; c < dim; ++c) len += obs->translate[c] * obs->translate[c];
      PetscCheck(len > 0.0, comm, PETSC_ERR_USER_INPUT,
                 "-obstacle_force needs -obstacle_translate to give the direction the obstacle moves in (its length is the first position tried)");
    }
  }
  PetscOptionsEnd();
  PetscCall(OtherTypesGetOptions(comm, obs->type, dim));
  PetscFunctionReturn(PETSC_SUCCESS);
}
