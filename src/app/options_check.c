/* Checks of option values shared by the modules' *GetOptions: every real option must be a finite number
   (PETSc parses "inf" and "nan" as reals, which would run a whole solve into NaN without naming the option). */
#define _POSIX_C_SOURCE 200809L /* strtok_r, getcwd under -std=c99 */
#include <unistd.h>
#include <string.h>

#include "app.h"

/* The options the project reads (every "-name" string of src/, listed at build time into build/known_options.inc by the
   Makefile) and PETSc's below: the names a misspelling is compared with. */
static const char *const project_options[] = {
#include "known_options.inc"
};
/* PETSc's options a run of this solver commonly gives, and whether each takes a value (PETSc ignores one given without
   its value; the others are flags). */
static const struct {
  const char *name;
  PetscBool   value;
} petsc_options[] = {
    {"-snes_rtol", PETSC_TRUE},
    {"-snes_atol", PETSC_TRUE},
    {"-snes_stol", PETSC_TRUE},
    {"-snes_max_it", PETSC_TRUE},
    {"-snes_type", PETSC_TRUE},
    {"-snes_monitor", PETSC_FALSE},
    {"-snes_converged_reason", PETSC_FALSE},
    {"-snes_view", PETSC_FALSE},
    {"-snes_linesearch_type", PETSC_TRUE},
    {"-snes_linesearch_monitor", PETSC_FALSE},
    {"-snes_ksp_ew", PETSC_FALSE},
    {"-snes_ksp_ew_version", PETSC_TRUE},
    {"-snes_vi_zero_tolerance", PETSC_FALSE},
    {"-snes_test_jacobian", PETSC_FALSE},
    {"-ksp_type", PETSC_TRUE},
    {"-ksp_rtol", PETSC_TRUE},
    {"-ksp_atol", PETSC_TRUE},
    {"-ksp_max_it", PETSC_TRUE},
    {"-ksp_monitor", PETSC_FALSE},
    {"-ksp_converged_reason", PETSC_FALSE},
    {"-ksp_view", PETSC_FALSE},
    {"-ksp_norm_type", PETSC_TRUE},
    {"-ksp_initial_guess_nonzero", PETSC_FALSE},
    {"-ksp_gmres_restart", PETSC_TRUE},
    {"-pc_type", PETSC_TRUE},
    {"-pc_factor_mat_solver_type", PETSC_TRUE},
    {"-pc_gamg_threshold", PETSC_TRUE},
    {"-pc_gamg_agg_nsmooths", PETSC_TRUE},
    {"-pc_gamg_square_graph", PETSC_FALSE},
    {"-pc_gamg_reuse_interpolation", PETSC_FALSE},
    {"-pc_hypre_type", PETSC_TRUE},
    {"-pc_mg_levels", PETSC_TRUE},
    {"-pc_mg_galerkin", PETSC_FALSE},
    {"-mg_levels_ksp_type", PETSC_TRUE},
    {"-mg_levels_pc_type", PETSC_TRUE},
    {"-mg_levels_ksp_max_it", PETSC_TRUE},
    {"-mg_coarse_pc_type", PETSC_TRUE},
    {"-mg_coarse_ksp_type", PETSC_TRUE},
    {"-mat_mumps_icntl_14", PETSC_TRUE},
    {"-dm_plex_filename", PETSC_TRUE},
    {"-dm_plex_dim", PETSC_TRUE},
    {"-dm_plex_simplex", PETSC_FALSE},
    {"-dm_plex_box_faces", PETSC_TRUE},
    {"-dm_plex_box_lower", PETSC_TRUE},
    {"-dm_plex_box_upper", PETSC_TRUE},
    {"-dm_refine", PETSC_TRUE},
    {"-dm_view", PETSC_FALSE},
    {"-dm_mat_type", PETSC_TRUE},
    {"-displacement_petscspace_degree", PETSC_TRUE},
    {"-petscpartitioner_type", PETSC_TRUE},
    {"-log_view", PETSC_FALSE},
    {"-options_file", PETSC_TRUE},
    {"-options_left", PETSC_FALSE},
    {"-help", PETSC_FALSE},
    {"-malloc_debug", PETSC_FALSE},
    {"-malloc_dump", PETSC_FALSE},
    {"-error_verbose", PETSC_FALSE},
};

/* The project's options that are flags (read with PetscOptionsBool(), listed at build time into build/flag_options.inc),
   which may be given without a value; every other option of the project takes one. */
static const char *const flag_options[] = {
#include "flag_options.inc"
};

static PetscBool InList(const char name[], const char *const list[], size_t n)
{
  for (size_t k = 0; k < n; ++k)
    if (!strcmp(name, list[k])) return PETSC_TRUE;
  return PETSC_FALSE;
}

/* Whether the option (with its dash) needs a value: every face-set option (-bc_...), the project's own options but its
   flags, and PETSc's options of petsc_options that take one (known_options.inc also holds PETSc names the sources
   mention, some of them flags: those go by petsc_options alone). */
static PetscBool TakesValue(const char name[])
{
  const char *const petsc_prefixes[] = {"-snes_",   "-ksp_",   "-pc_",     "-mg_",  "-dm_",   "-mat_",          "-log", "-malloc",
                                        "-options", "-memory", "-objects", "-help", "-petsc", "-displacement_", "-name"};

  if (!strncmp(name, "-bc_", 4)) return PETSC_TRUE;
  for (size_t k = 0; k < sizeof(petsc_options) / sizeof(petsc_options[0]); ++k)
    if (!strcmp(name, petsc_options[k].name)) return petsc_options[k].value;
  for (size_t k = 0; k < sizeof(petsc_prefixes) / sizeof(petsc_prefixes[0]); ++k)
    if (!strncmp(name, petsc_prefixes[k], strlen(petsc_prefixes[k]))) return PETSC_FALSE;
  if (InList(name, flag_options, sizeof(flag_options) / sizeof(flag_options[0]))) return PETSC_FALSE;
  return InList(name, project_options, sizeof(project_options) / sizeof(project_options[0]));
}

/* Refuses an option that needs a value and was given without one (`-young_modulus` alone, or `young_modulus:` empty in
   a YAML file): PETSc's readers leave the default then, and the run would go on as if the option were not there. The
   token after an option is its value unless it is itself an option name (PetscOptionsValidKey(), as PETSc's parser
   decides: `-inf` and `-1` are values). Before any module reads its options. */
PetscErrorCode OptionsCheckValuesGiven(MPI_Comm comm)
{
  char *all, *tok, missing[1024] = "";

  PetscFunctionBeginUser;
  PetscCall(PetscOptionsGetAll(NULL, &all)); /* "-name value -name -name value ..." */
  tok = all;
  while (*tok == ' ') ++tok;
  while (*tok) {
    char     *next = tok + strcspn(tok, " ");
    PetscBool key, next_key = PETSC_TRUE;

    if (*next) *next++ = 0;
    while (*next == ' ') ++next;
    PetscCall(PetscOptionsValidKey(tok, &key));
    if (*next) {
      char *end = next + strcspn(next, " "), saved = *end;

      *end = 0; /* the next token alone, then back as it was */
      PetscCall(PetscOptionsValidKey(next, &next_key));
      *end = saved;
    }
    if (key && next_key && TakesValue(tok) && strlen(missing) + strlen(tok) + 2 < sizeof(missing)) {
      PetscCall(PetscStrlcat(missing, " ", sizeof(missing)));
      PetscCall(PetscStrlcat(missing, tok, sizeof(missing)));
    }
    tok = next;
  }
  PetscCall(PetscFree(all));
  PetscCheck(!missing[0], comm, PETSC_ERR_USER_INPUT,
             "option(s) given without a value:%s (a value is needed: a number, a list a,b,c or a name, see -help; in a YAML file, "
             "`name: value`)",
             missing);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The edit distance of a and b (insertions, deletions, substitutions and transpositions of neighbours, each 1). */
static PetscInt EditDistance(const char a[], const char b[])
{
  PetscInt la = (PetscInt)strlen(a), lb = (PetscInt)strlen(b), d[3][80];

  if (la >= 79 || lb >= 79) return PETSC_MAX_INT;
  for (PetscInt j = 0; j <= lb; ++j) d[0][j] = j;
  for (PetscInt i = 1; i <= la; ++i) {
    PetscInt *cur = d[i % 3], *prev = d[(i + 2) % 3], *prev2 = d[(i + 1) % 3];

    cur[0] = i;
    for (PetscInt j = 1; j <= lb; ++j) {
      const PetscInt cost = a[i - 1] != b[j - 1];

      cur[j] = PetscMin(PetscMin(prev[j] + 1, cur[j - 1] + 1), prev[j - 1] + cost);
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) cur[j] = PetscMin(cur[j], prev2[j - 2] + 1);
    }
  }
  return d[la % 3][lb];
}

/* Appends to list " -name" and, when a known option is close to it, " (did you mean -known?)". name without its dash. */
static PetscErrorCode AppendWithSuggestion(const char name[], char list[], size_t len)
{
  char        dashed[256];
  const char *best   = NULL;
  PetscInt    best_d = PETSC_MAX_INT, limit;

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(dashed, sizeof(dashed), "-%s", name));
  limit = PetscMax(2, (PetscInt)strlen(dashed) / 5);
  for (size_t k = 0; k < sizeof(project_options) / sizeof(project_options[0]) + sizeof(petsc_options) / sizeof(petsc_options[0]); ++k) {
    const size_t      np    = sizeof(project_options) / sizeof(project_options[0]);
    const char *const known = k < np ? project_options[k] : petsc_options[k - np].name;
    const PetscInt    d     = EditDistance(dashed, known);

    if (d < best_d) {
      best_d = d;
      best   = known;
    }
  }
  PetscCall(PetscStrlcat(list, " ", len));
  PetscCall(PetscStrlcat(list, dashed, len));
  if (best && best_d > 0 && best_d <= limit) {
    PetscCall(PetscStrlcat(list, " (did you mean ", len));
    PetscCall(PetscStrlcat(list, best, len));
    PetscCall(PetscStrlcat(list, "?)", len));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Refuses a value of the enum option name (or, with array, an item of its comma-separated list) that is not one of
   PETSc's enum list's names, before PETSc's reader sees it: that reader cuts the value at the longest name's length
   ("Unknown option plane,cylind") and lists no nearest name ("Unknown enum value 'contact_forse'"). The message gives
   the whole value, the names, and the nearest one; a list given to a single-valued option is said to be one. */
PetscErrorCode OptionsCheckEnum(MPI_Comm comm, const char name[], const char *const list[], PetscBool array)
{
  char      value[1024], names[512] = "", *item, *save = NULL;
  PetscBool set;
  PetscInt  n = 0;

  PetscFunctionBeginUser;
  PetscCall(PetscOptionsGetString(NULL, NULL, name, value, sizeof(value), &set));
  if (!set || !value[0]) PetscFunctionReturn(PETSC_SUCCESS);
  while (list[n]) ++n;
  n -= 2; /* PETSc's enum list ends with the type's name, its prefix and NULL */
  for (PetscInt k = 0; k < n; ++k) {
    PetscCall(PetscStrlcat(names, k ? ", " : "", sizeof(names)));
    PetscCall(PetscStrlcat(names, list[k], sizeof(names)));
  }
  PetscCheck(array || !strchr(value, ','), comm, PETSC_ERR_USER_INPUT, "%s %s: %s takes one value (one of %s), not a list", name, value, name, names);
  for (item = strtok_r(value, ",", &save); item; item = strtok_r(NULL, ",", &save)) {
    PetscBool   found  = PETSC_FALSE;
    const char *best   = NULL;
    PetscInt    best_d = PETSC_MAX_INT;

    for (PetscInt k = 0; k < n && !found; ++k) {
      const PetscInt d = EditDistance(item, list[k]);

      PetscCall(PetscStrcasecmp(item, list[k], &found));
      if (d < best_d) best_d = d, best = list[k];
    }
    if (found) continue;
    if (!(best && best_d <= PetscMax(2, (PetscInt)strlen(item) / 3))) { /* no close spelling: the one name holding it ("force") */
      PetscInt holding = 0;

      for (PetscInt k = 0; k < n; ++k)
        if (strstr(list[k], item)) ++holding, best = list[k];
      if (holding == 1) best_d = 0;
    }
    if (best && best_d <= PetscMax(2, (PetscInt)strlen(item) / 3))
      SETERRQ(comm, PETSC_ERR_USER_INPUT, "%s: unknown value '%s' (did you mean %s?); the values are %s", name, item, best, names);
    SETERRQ(comm, PETSC_ERR_USER_INPUT, "%s: unknown value '%s'; the values are %s", name, item, names);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* For a message about a file given by an option: where a relative path was looked for ("" for an absolute one). PETSc
   takes a path in an options file, as on the command line, from the working directory, not from the options file's
   directory, which a user who keeps a mesh beside its options file may expect. */
PetscErrorCode OptionsPathWhere(const char path[], char where[], size_t len)
{
  char cwd[PETSC_MAX_PATH_LEN];

  PetscFunctionBeginUser;
  where[0] = '\0';
  if (path[0] == '/' || !getcwd(cwd, sizeof(cwd))) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscSNPrintf(where, len, " (a relative path, taken from the working directory %s, also in an options file)", cwd));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode OptionsCheckFinite(MPI_Comm comm, const char name[], PetscReal value)
{
  PetscFunctionBeginUser;
  PetscCheck(!PetscIsInfOrNanReal(value), comm, PETSC_ERR_USER_INPUT, "%s must be a finite number, got %g", name, (double)value);
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode OptionsCheckFiniteArray(MPI_Comm comm, const char name[], PetscInt n, const PetscReal values[])
{
  PetscFunctionBeginUser;
  for (PetscInt i = 0; i < n; ++i)
    PetscCheck(!PetscIsInfOrNanReal(values[i]), comm, PETSC_ERR_USER_INPUT, "%s must be a list of finite numbers, got %g as value %" PetscInt_FMT,
               name, (double)values[i], i + 1);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Number of comma-separated values of a list option as given (0 if not given), so that a list of any length is read
   whole: PetscOptionsRealArray() silently drops the values beyond the array it is given. */
PetscErrorCode OptionsCountListValues(const char name[], PetscInt *n)
{
  const char *value;
  PetscBool   set;

  PetscFunctionBeginUser;
  *n = 0;
  PetscCall(PetscOptionsFindPair(NULL, NULL, name, &value, &set));
  if (!set || !value) PetscFunctionReturn(PETSC_SUCCESS);
  *n = 1;
  for (const char *c = value; *c; ++c) *n += *c == ',';
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Refuses options that start with one of the space-separated prefixes (with their dash) and were never read: once a
   module has read all of its options, those are misspellings (-bc_clamp_3_tanslate), named before any solve. */
PetscErrorCode OptionsCheckPrefixesUsed(MPI_Comm comm, const char prefixes[])
{
  PetscInt N, nbad = 0;
  char   **names, **values, list[2048] = "";

  PetscFunctionBeginUser;
  PetscCall(PetscOptionsLeftGet(NULL, &N, &names, &values));
  for (PetscInt i = 0; i < N; ++i) {
    char        buf[256];
    const char *rest = prefixes;

    while (*rest) { /* one prefix at a time */
      size_t    len = strcspn(rest, " ");
      PetscBool match;

      PetscCall(PetscStrncpy(buf, rest + 1, PetscMin(len, sizeof(buf)))); /* without the dash: the names below have none */
      PetscCall(PetscStrbeginswith(names[i], buf, &match));
      if (match) {
        PetscCall(AppendWithSuggestion(names[i], list, sizeof(list)));
        ++nbad;
        break;
      }
      rest += len;
      while (*rest == ' ') ++rest;
    }
  }
  PetscCall(PetscOptionsLeftRestore(NULL, &N, &names, &values));
  PetscCheck(nbad == 0, comm, PETSC_ERR_USER_INPUT,
             "%" PetscInt_FMT " option(s) given but never used (misspelled, or for a face set or obstacle not in use? see -help):%s", nbad, list);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Whether an option not read by the end of the set-up may still be read by the solve: PETSc reads its viewers and
   monitors when an object is viewed or solved, the options of a multigrid's levels, of the sub-solvers and of a
   factorization package when the preconditioner is built, and the project reads those of the coarser boxes
   (-contact_coarse_) and of the finest smoother (-mg_fine_) when they exist, and those of the error norms' dual-norm
   solve (-dual_) after the solve. */
static PetscBool ReadDuringTheSolve(const char name[])
{
  const char *const later[] = {"mg_levels_", "mg_coarse_",       "mg_fine_",   "sub_",           "contact_coarse_", "mat_", "pc_gamg_",   "pc_mg_",
                               "pc_hypre_",  "snes_linesearch_", "snes_test_", "ksp_chebyshev_", "fieldsplit_",     "vec_", "pc_factor_", "ksp_",
                               "dual_"};

  if (strstr(name, "view") || strstr(name, "monitor") || strstr(name, "converged_reason") || strstr(name, "log")) return PETSC_TRUE;
  for (size_t k = 0; k < sizeof(later) / sizeof(later[0]); ++k)
    if (!strncmp(name, later[k], strlen(later[k]))) return PETSC_TRUE;
  return PETSC_FALSE;
}

/* Refuses the options given and never read, each with the nearest known option when one is close. before_solve: at the
   end of the set-up (every module and the SNES have read their options), leaving those the solve may still read; then
   again at the end of the run, for all of them. */
PetscErrorCode OptionsCheckAllUsed(MPI_Comm comm, PetscBool before_solve)
{
  const char *read_at_finalize[] = {"-options_left", "-malloc_dump", "-memory_view", "-objects_dump"};
  PetscInt    N, nleft = 0;
  char      **names, **values, list[2048] = "";

  PetscFunctionBeginUser;
  for (size_t i = 0; i < sizeof(read_at_finalize) / sizeof(read_at_finalize[0]); ++i) {
    PetscBool set;
    PetscCall(PetscOptionsHasName(NULL, NULL, read_at_finalize[i], &set)); /* marks them used */
  }
  PetscCall(PetscOptionsLeftGet(NULL, &N, &names, &values));
  for (PetscInt i = 0; i < N; ++i) {
    if (before_solve && ReadDuringTheSolve(names[i])) continue;
    PetscCall(AppendWithSuggestion(names[i], list, sizeof(list)));
    ++nleft;
  }
  PetscCall(PetscOptionsLeftRestore(NULL, &N, &names, &values));
  PetscCheck(nleft == 0, comm, PETSC_ERR_USER_INPUT, "%" PetscInt_FMT " option(s) given but never used (misspelled? see -help):%s", nleft, list);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* -NAME as exactly dim finite reals (a point, a vector), inside the caller's PetscOptionsBegin() block; v keeps its value
   when the option is not given. A longer list is refused, not cut to the array as PetscOptionsRealArray() would. */
PetscErrorCode OptionsReadVector(CompatOptionItems PetscOptionsObject, MPI_Comm comm, const char name[], const char help[], PetscInt dim,
                                 PetscReal v[], PetscBool *set)
{
  PetscInt n;

  PetscFunctionBeginUser;
  PetscCall(OptionsCountListValues(name, &n));
  PetscCheck(n <= dim, comm, PETSC_ERR_USER_INPUT, "%s needs %" PetscInt_FMT " comma-separated values (one per coordinate), got %" PetscInt_FMT, name,
             dim, n);
  n = dim;
  PetscCall(PetscOptionsRealArray(name, help, NULL, v, &n, set));
  if (*set) {
    PetscCheck(n == dim, comm, PETSC_ERR_USER_INPUT, "%s needs %" PetscInt_FMT " comma-separated values (one per coordinate), got %" PetscInt_FMT,
               name, dim, n);
    PetscCall(OptionsCheckFiniteArray(comm, name, dim, v));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}
