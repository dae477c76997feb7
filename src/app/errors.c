/* Errors a user can read. A refusal of the user's input (PETSC_ERR_USER_INPUT, a file that cannot be opened or read, a
   value PETSc's option parser cannot read) is printed as one paragraph on the first rank, without PETSc's error block
   (version, configure line, stack) and without its list of "options not used", which after a refusal lists the valid
   options of the run as if they were typos; the run then exits with status 2 and writes nothing (the output is written
   last, into a temporary first). Any other error is an internal one and gets PETSc's whole block, as does every error
   with -error_verbose.

   The run itself is a function (main.c's Run()), so that an error returns to main() instead of PETSc's abort at the
   level of main(). A refusal checked on every rank (a communicator of all the ranks) ends every rank cleanly; one
   checked on one rank alone aborts the others. */
#define _DEFAULT_SOURCE /* usleep() */
#include <ctype.h>
#include <unistd.h>
#include "app.h"

typedef struct {
  PetscBool      verbose;    /* -error_verbose: PETSc's error block for every error */
  PetscBool      recorded;   /* the first error of this rank is recorded below */
  PetscBool      user;       /*   a refusal of the user's input */
  PetscBool      collective; /*   raised on a communicator of all the ranks */
  PetscErrorCode code;
  char           message[4096];
} AppError;

static AppError app_error;

/* PETSc's option parser (PetscOptionsStringToReal(), PetscOptionsGetEList(), ...) raises argument errors on values it
   cannot read: the user's input too. */
static PetscBool IsOptionsParserError(const char fun[])
{
  PetscBool options = PETSC_FALSE;

  if (fun) (void)PetscStrbeginswith(fun, "PetscOptions", &options);
  return options;
}

static PetscBool IsUserInputError(PetscErrorCode n, const char fun[])
{
  return (PetscBool)(n == PETSC_ERR_USER_INPUT || n == PETSC_ERR_FILE_OPEN || n == PETSC_ERR_FILE_READ || n == PETSC_ERR_FILE_UNEXPECTED ||
                     IsOptionsParserError(fun));
}

/* Whether the comma-separated list has item as one of its items (a list option's values are parsed one by one). */
static PetscBool ListHasItem(const char list[], const char item[])
{
  const size_t n = strlen(item);

  for (const char *c = list; c; c = strchr(c, ',') ? strchr(c, ',') + 1 : NULL)
    if (!strncmp(c, item, n) && (c[n] == ',' || c[n] == 0)) return PETSC_TRUE;
  return PETSC_FALSE;
}

/* PETSc's parser names the value it cannot read ("Input string 1,2 has no numeric value", "Unknown logical value:
   maybe"), not the option: the options given with that value are added to the message. */
static void NameOptionsWithValue(const char mess[], char out[], size_t len)
{
  const char *patterns[][2] = {
      {"Input string ", " has no"},
      {"Unknown logical value: ", NULL},
  };
  char value[256] = "", *all = NULL, names[512] = "";

  for (size_t k = 0; k < sizeof(patterns) / sizeof(patterns[0]) && !value[0]; ++k) {
    const char *start = strstr(mess, patterns[k][0]), *end;

    if (!start) continue;
    start += strlen(patterns[k][0]);
    end = patterns[k][1] ? strstr(start, patterns[k][1]) : start + strcspn(start, " \n");
    if (end && end > start && (size_t)(end - start) < sizeof(value)) {
      memcpy(value, start, (size_t)(end - start));
      value[end - start] = 0;
    }
  }
  (void)PetscSNPrintf(out, len, "%s", mess);
  if (!value[0] || PetscOptionsGetAll(NULL, &all) || !all) return;
  /* "-name value -name value ...": a name is a word that starts with '-' and a letter, its value the words up to the
     next name, spaces kept ("-young_modulus 210 GPa": the value "210 GPa", which a split at every space missed) */
  for (char *c = all; *c;) {
    char *name, *val, *next;

    while (*c == ' ') ++c;
    if (!(c[0] == '-' && isalpha((unsigned char)c[1]))) {
      c += strcspn(c, " ");
      continue;
    }
    name = c;
    c += strcspn(c, " ");
    if (*c) *c++ = 0;
    val = c;
    for (next = c; *next; next += strcspn(next, " ")) {
      while (*next == ' ') ++next;
      if (next[0] == '-' && isalpha((unsigned char)next[1])) break;
    }
    c = next;
    if (next > val && next[-1] == ' ') { /* the value ends before the spaces that lead to the next name */
      char *e = next;

      while (e > val && e[-1] == ' ') --e;
      *e = 0;
    }
    if (ListHasItem(val, value) || !strcmp(val, value)) {
      if (names[0]) (void)PetscStrlcat(names, " and ", sizeof(names));
      (void)PetscStrlcat(names, name, sizeof(names));
    }
  }
  (void)PetscFree(all);
  if (names[0]) (void)PetscSNPrintf(out, len, "%s %s: %s", names, value, mess);
}

static PetscErrorCode AppErrorHandler(MPI_Comm comm, int line, const char *fun, const char *file, PetscErrorCode n, PetscErrorType p,
                                      const char *mess, void *ctx)
{
  if (p == PETSC_ERROR_INITIAL && !app_error.recorded) {
    PetscMPIInt size = 1, world = 1;

    app_error.recorded = PETSC_TRUE;
    app_error.code     = n;
    app_error.user     = (PetscBool)(!app_error.verbose && IsUserInputError(n, fun));
    if (comm != MPI_COMM_NULL) (void)MPI_Comm_size(comm, &size);
    (void)MPI_Comm_size(PETSC_COMM_WORLD, &world);
    /* PETSc's parser raises on PETSC_COMM_SELF, but every rank holds the same options and raises alike */
    app_error.collective = (PetscBool)(size == world || IsOptionsParserError(fun));
    NameOptionsWithValue(mess ? mess : "", app_error.message, sizeof(app_error.message));
  }
  if (app_error.user) return n;
  return PetscTraceBackErrorHandler(comm, line, fun, file, n, p, mess, ctx);
}

/* Installs the handler; reads -error_verbose. Right after PetscInitialize(). */
PetscErrorCode AppErrorPushHandler(void)
{
  PetscFunctionBeginUser;
  PetscCall(PetscMemzero(&app_error, sizeof(app_error)));
  PetscCall(PetscOptionsGetBool(NULL, NULL, "-error_verbose", &app_error.verbose, NULL));
  PetscCall(PetscPushErrorHandler(AppErrorHandler, NULL));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Ends the run after the error ierr came back to main(): returns the exit status, or does not return (MPI_Abort). A
   refusal on every rank: the paragraph on the first rank, every rank waits for the others (at most a minute, then
   aborts: a rank elsewhere in the run never comes), MPI ends, status 2. */
int AppErrorExit(PetscErrorCode ierr)
{
  PetscMPIInt rank = 0;

  (void)MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (!app_error.recorded || !app_error.user) {
    (void)MPI_Abort(MPI_COMM_WORLD, (int)ierr); /* PETSc's block was printed by its handler */
    return (int)ierr;
  }
  if (!app_error.collective) {
    fprintf(stderr, "signorini: error (rank %d): %s\n", (int)rank, app_error.message);
    fflush(stderr);
    (void)MPI_Abort(MPI_COMM_WORLD, 2);
    return 2;
  }
  if (rank == 0) {
    fprintf(stderr, "signorini: error: %s\n(-error_verbose prints PETSc's error report)\n", app_error.message);
    fflush(stderr);
  }
  {
    MPI_Request req;
    int         done = 0;

    (void)MPI_Ibarrier(MPI_COMM_WORLD, &req);
    for (int waited = 0; !done && waited < 60000; waited += 10) {
      (void)MPI_Test(&req, &done, MPI_STATUS_IGNORE);
      if (!done) (void)usleep(10000);
    }
    if (!done) (void)MPI_Abort(MPI_COMM_WORLD, 2);
  }
  (void)MPI_Finalize(); /* not PetscFinalize(): the run's objects were not destroyed, and -malloc_dump would list them */
  return 2;
}

/* A diagnostic after the solve (the error norms, the -reference comparison) must not lose the solve: an error in it is
   caught (PETSc's return handler, not the run's), its message kept in failed[] ("" if none), and the run goes on to
   write its output without it (fn(ctx): the diagnostic with what it reads and writes). Every rank learns whether any rank failed; a rank that fails
   while the others wait for it inside the diagnostic would leave them there, so the agreement waits a minute at most and then aborts. */
PetscErrorCode AppDiagnosticRun(const char name[], PetscErrorCode (*fn)(void *ctx), void *ctx, char failed[], size_t len)
{
  PetscErrorCode ierr;
  int            mine, any = 0, done = 0;
  MPI_Request    req;

  PetscFunctionBeginUser;
  failed[0] = 0;
  PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  ierr = fn(ctx);
  PetscCall(PetscPopErrorHandler());
  mine = ierr ? 1 : 0;
  PetscCallMPI(MPI_Iallreduce(&mine, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD, &req));
  for (int waited = 0; !done && waited < 60000; waited += 10) {
    PetscCallMPI(MPI_Test(&req, &done, MPI_STATUS_IGNORE));
    if (!done) (void)usleep(10000);
  }
  if (!done) {
    fprintf(stderr, "signorini: error: the diagnostic %s failed on some ranks and not on others; aborting\n", name);
    (void)MPI_Abort(MPI_COMM_WORLD, 4);
  }
  if (any) {
    const char *text     = NULL;
    char       *specific = NULL;

    if (ierr) PetscCall(PetscErrorMessage(ierr, &text, &specific));
    PetscCall(PetscSNPrintf(failed, len, "%s: %s", name, ierr ? (specific && specific[0] ? specific : text) : "failed on another rank"));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}
