/* Boundary conditions by face label: the scene's defaults, then -contact_faces, -bc_clamp, -bc_slip, -bc_traction,
   -bc_pressure (with their per-face options) and -body_force, read once. A face set is named by its "Face Sets" value or,
   on a Gmsh mesh, by the name of its physical group (a label of that name carries the value, mesh/mesh_gmsh_names.c). */
#include <ctype.h>
#include "app.h"
#include "scenes.h"

const char *const BoundaryKinds[] = {"clamp", "slip", "traction", "pressure", "BoundaryKind", "BC_", NULL};

/* A default of a scene: a boundary condition of this kind on face set id (fn: the scene's displacement for a clamp). */
PetscErrorCode SceneAddBoundary(Scene *scene, BoundaryKind kind, PetscInt id, ScenePointFn fn)
{
  BoundaryCondition *bc;

  PetscFunctionBeginUser;
  PetscCheck(scene->bcs.n < BOUNDARY_MAX, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Scene %s: more than %d boundary conditions", scene->name, BOUNDARY_MAX);
  bc = &scene->bcs.bc[scene->bcs.n++];
  PetscCall(PetscMemzero(bc, sizeof(*bc)));
  bc->kind = kind;
  bc->id   = id;
  bc->fn   = fn;
  PetscCall(PetscSNPrintf(bc->token, sizeof(bc->token), "%" PetscInt_FMT, id));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A default of a scene: face set id is (part of) Gamma_C. */
PetscErrorCode SceneAddContactFaces(Scene *scene, PetscInt id)
{
  PetscFunctionBeginUser;
  PetscCheck(scene->bcs.ncontact < BOUNDARY_MAX, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Scene %s: too many contact face sets", scene->name);
  scene->bcs.contact_ids[scene->bcs.ncontact] = id;
  PetscCall(PetscSNPrintf(scene->bcs.contact_tokens[scene->bcs.ncontact], 64, "%" PetscInt_FMT, id));
  scene->bcs.ncontact++;
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscBool IsInteger(const char s[])
{
  if (*s == '-' || *s == '+') ++s;
  if (!*s) return PETSC_FALSE;
  for (; *s; ++s)
    if (!isdigit((unsigned char)*s)) return PETSC_FALSE;
  return PETSC_TRUE;
}

/* The "Face Sets" value that token names: a number, or the name of a label (a Gmsh physical group) with one value. */
static PetscErrorCode ResolveFaceSet(DM dm, const char option[], const char token[], PetscInt *id)
{
  MPI_Comm  comm = PetscObjectComm((PetscObject)dm);
  PetscBool has;
  DMLabel   label;
  IS        values;
  PetscInt  n, range[2] = {PETSC_MAX_INT, PETSC_MIN_INT}, lo, hi;

  PetscFunctionBeginUser;
  if (IsInteger(token)) {
    *id = (PetscInt)strtol(token, NULL, 10);
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  PetscCall(DMHasLabel(dm, token, &has));
  PetscCheck(
      has, comm, PETSC_ERR_USER_INPUT,
      "%s: '%s' is neither a \"Face Sets\" value nor the name of a physical group of faces of the mesh (names are read from a Gmsh .msh file's "
      "$PhysicalNames)",
      option, token);
  PetscCall(DMGetLabel(dm, token, &label));
  PetscCall(DMLabelGetValueIS(label, &values));
  PetscCall(ISGetLocalSize(values, &n));
  if (n) {
    const PetscInt *v;

    PetscCall(ISGetIndices(values, &v));
    for (PetscInt i = 0; i < n; ++i) {
      range[0] = PetscMin(range[0], v[i]);
      range[1] = PetscMax(range[1], v[i]);
    }
    PetscCall(ISRestoreIndices(values, &v));
  }
  PetscCall(ISDestroy(&values));
  PetscCall(MPIU_Allreduce(&range[0], &lo, 1, MPIU_INT, MPI_MIN, comm));
  PetscCall(MPIU_Allreduce(&range[1], &hi, 1, MPIU_INT, MPI_MAX, comm));
  PetscCheck(lo <= hi, comm, PETSC_ERR_USER_INPUT, "%s: the physical group '%s' has no face", option, token);
  PetscCheck(lo == hi, comm, PETSC_ERR_USER_INPUT, "%s: the label '%s' is not one face set: it has values %" PetscInt_FMT " to %" PetscInt_FMT,
             option, token, lo, hi);
  *id = lo;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The per-face options of a boundary condition: translations, components, loads. */
static PetscErrorCode ReadFaceOptions(CompatOptionItems PetscOptionsObject, MPI_Comm comm, PetscInt dim, BoundaryCondition *bc)
{
  char      name[128];
  PetscBool set;

  PetscFunctionBeginUser;
  switch (bc->kind) {
    case BC_CLAMP:
      bc->ncomp = dim;
      for (PetscInt c = 0; c < dim; ++c) bc->comps[c] = c;
      PetscCall(PetscSNPrintf(name, sizeof(name), "-bc_clamp_%s_translate", bc->token));
      PetscCall(
          OptionsReadVector(PetscOptionsObject, comm, name, "Prescribed displacement of the clamped face set (default 0)", dim, bc->value, &set));
      if (set) bc->fn = NULL; /* the translation replaces a scene's own displacement */
      break;
    case BC_SLIP: {
      PetscInt n = 3;

      PetscCall(PetscSNPrintf(name, sizeof(name), "-bc_slip_%s_components", bc->token));
      PetscCall(OptionsCountListValues(name, &n));
      PetscCheck(n < dim, comm, PETSC_ERR_USER_INPUT, "%s: a slip face fixes fewer than %" PetscInt_FMT " components (fixing all is -bc_clamp)", name,
                 dim);
      n = 3;
      PetscCall(PetscOptionsIntArray(name, "Components (0-based) fixed on the slip face set; the others are free", NULL, bc->comps, &n, &set));
      PetscCheck(set && n > 0, comm, PETSC_ERR_USER_INPUT, "-bc_slip %s needs %s c,... (the fixed components, 0-based)", bc->token, name);
      PetscCheck(n < dim, comm, PETSC_ERR_USER_INPUT, "%s: a slip face fixes fewer than %" PetscInt_FMT " components (fixing all is -bc_clamp)", name,
                 dim);
      PetscCall(PetscSortRemoveDupsInt(&n, bc->comps));
      for (PetscInt k = 0; k < n; ++k)
        PetscCheck(bc->comps[k] >= 0 && bc->comps[k] < dim, comm, PETSC_ERR_USER_INPUT,
                   "%s: component %" PetscInt_FMT " is outside 0..%" PetscInt_FMT, name, bc->comps[k], dim - 1);
      bc->ncomp = n;
      PetscCall(PetscSNPrintf(name, sizeof(name), "-bc_slip_%s_translate", bc->token));
      PetscCall(OptionsReadVector(PetscOptionsObject, comm, name, "Prescribed values of the fixed components (a vector of dim values; default 0)",
                                  dim, bc->value, &set));
    } break;
    case BC_TRACTION:
      PetscCall(PetscSNPrintf(name, sizeof(name), "-bc_traction_%s", bc->token));
      PetscCall(OptionsReadVector(PetscOptionsObject, comm, name, "Surface load on the face set, force per unit area", dim, bc->value, &set));
      PetscCheck(set, comm, PETSC_ERR_USER_INPUT, "-bc_traction %s needs %s tx,ty%s (force per unit area)", bc->token, name, dim == 3 ? ",tz" : "");
      break;
    case BC_PRESSURE:
      PetscCall(PetscSNPrintf(name, sizeof(name), "-bc_pressure_%s", bc->token));
      PetscCall(PetscOptionsReal(name, "Normal pressure p on the face set (load -p n)", NULL, bc->value[0], &bc->value[0], &set));
      PetscCall(OptionsCheckFinite(comm, name, bc->value[0]));
      PetscCheck(set, comm, PETSC_ERR_USER_INPUT, "-bc_pressure %s needs %s p", bc->token, name);
      break;
    default:
      SETERRQ(comm, PETSC_ERR_PLIB, "Unknown boundary condition kind %d", (int)bc->kind);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Replaces the scene's defaults of the families given on the command line, then reads every face's options. */
PetscErrorCode SceneBoundaryGetOptions(DM dm, Scene *scene)
{
  MPI_Comm     comm = PetscObjectComm((PetscObject)dm);
  BoundarySet *bcs  = &scene->bcs;
  PetscInt     dim;
  char        *tokens[BOUNDARY_MAX];

  PetscFunctionBeginUser;
  PetscCall(DMGetDimension(dm, &dim));
  PetscOptionsBegin(comm, NULL, "Boundary conditions by face set (\"Face Sets\" value or Gmsh physical group name)", "Signorini");
  {
    PetscInt  n = BOUNDARY_MAX;
    PetscBool set;

    PetscCall(PetscOptionsStringArray("-contact_faces", "Face sets of Gamma_C (default: the scene's)", NULL, tokens, &n, &set));
    if (set) {
      PetscCheck(n > 0, comm, PETSC_ERR_USER_INPUT, "-contact_faces needs one or more face sets");
      bcs->ncontact = n;
      for (PetscInt i = 0; i < n; ++i) {
        PetscCall(PetscStrncpy(bcs->contact_tokens[i], tokens[i], sizeof(bcs->contact_tokens[i])));
        PetscCall(ResolveFaceSet(dm, "-contact_faces", tokens[i], &bcs->contact_ids[i]));
        PetscCall(PetscFree(tokens[i]));
      }
    }
  }
  for (PetscInt kind = 0; kind < BC_NUM_KINDS; ++kind) {
    char      name[64], help[128];
    PetscInt  n = BOUNDARY_MAX, kept = 0;
    PetscBool set;

    PetscCall(PetscSNPrintf(name, sizeof(name), "-bc_%s", BoundaryKinds[kind]));
    PetscCall(PetscSNPrintf(help, sizeof(help), "Face sets with a %s condition (default: the scene's)", BoundaryKinds[kind]));
    PetscCall(PetscOptionsStringArray(name, help, NULL, tokens, &n, &set));
    if (!set) continue;
    for (PetscInt i = 0; i < bcs->n; ++i) /* the scene's defaults of this family are replaced */
      if (bcs->bc[i].kind != (BoundaryKind)kind) bcs->bc[kept++] = bcs->bc[i];
    bcs->n = kept;
    PetscCheck(bcs->n + n <= BOUNDARY_MAX, comm, PETSC_ERR_USER_INPUT, "%s: at most %d boundary conditions in all", name, BOUNDARY_MAX);
    for (PetscInt i = 0; i < n; ++i) {
      BoundaryCondition *bc = &bcs->bc[bcs->n++];

      PetscCall(PetscMemzero(bc, sizeof(*bc)));
      bc->kind = (BoundaryKind)kind;
      PetscCall(PetscStrncpy(bc->token, tokens[i], sizeof(bc->token)));
      PetscCall(PetscFree(tokens[i]));
      PetscCall(ResolveFaceSet(dm, name, bc->token, &bc->id));
    }
  }
  for (PetscInt i = 0; i < bcs->n; ++i) PetscCall(ReadFaceOptions(PetscOptionsObject, comm, dim, &bcs->bc[i]));
  {
    PetscBool set;
    PetscReal f[3] = {0.0, 0.0, 0.0};

    for (PetscInt c = 0; c < dim; ++c) f[c] = bcs->body_force[c];
    PetscCall(OptionsReadVector(PetscOptionsObject, comm, "-body_force", "Constant body force, force per unit volume", dim, f, &set));
    for (PetscInt c = 0; c < dim; ++c) bcs->body_force[c] = f[c];
  }
  PetscOptionsEnd();
  PetscCheck(bcs->ncontact > 0, comm, PETSC_ERR_USER_INPUT, "Scene %s has no contact boundary: give its face sets with -contact_faces ID,...",
             scene->name);
  /* The same face set twice is refused here; a face carrying two listed values is refused on the mesh (BoundaryCheckFaceSets). */
  for (PetscInt i = 0; i < bcs->n + bcs->ncontact; ++i) {
    const PetscInt id_i = i < bcs->n ? bcs->bc[i].id : bcs->contact_ids[i - bcs->n];
    for (PetscInt j = i + 1; j < bcs->n + bcs->ncontact; ++j) {
      const PetscInt id_j = j < bcs->n ? bcs->bc[j].id : bcs->contact_ids[j - bcs->n];
      PetscCheck(id_i != id_j, comm, PETSC_ERR_USER_INPUT,
                 "Face set %" PetscInt_FMT " is listed twice: in -%s%s and in -%s%s (a face belongs to one family, or to none: traction-free)", id_i,
                 i < bcs->n ? "bc_" : "contact_faces", i < bcs->n ? BoundaryKinds[bcs->bc[i].kind] : "", j < bcs->n ? "bc_" : "contact_faces",
                 j < bcs->n ? BoundaryKinds[bcs->bc[j].kind] : "");
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}
