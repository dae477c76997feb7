/* Checks of option values shared by the modules' *GetOptions: every real option must be a finite number
   (PETSc parses "inf" and "nan" as reals, which would run a whole solve into NaN without naming the option). */
#include "app.h"

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
  char   **names, **values, list[1024] = "";

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
        PetscCall(PetscStrlcat(list, " -", sizeof(list)));
        PetscCall(PetscStrlcat(list, names[i], sizeof(list)));
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
