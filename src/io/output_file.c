/* Safe replacement of the output files. Every file is written under a unique temporary name in the target's
   directory and renamed over the target only when complete, the XDMF file before the HDF5 file (so no new .h5 ever
   stands without its .xdmf), under a lock of the directory (so two runs writing the same output leave the pair of
   one run) and with SIGTERM/SIGINT deferred until both are renamed (so a signal leaves the old pair or the new one). A failure, an exit on
   error or a signal removes the temporaries (a failure or an exit also the files MPI-IO made beside them). A target that exists and is not a regular
   file (a directory, a device, a FIFO, a symbolic link) is refused before the solve. */
#define _DEFAULT_SOURCE /* POSIX and BSD calls (mkstemp, lstat, sigaction, flock) under -std=c99 */
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <pthread.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>
#include "io.h"

#define OUTPUT_MAX_TEMPS 2
static char         output_temps[OUTPUT_MAX_TEMPS][PETSC_MAX_PATH_LEN]; /* temporaries to remove on failure, exit or signal */
static mode_t       output_mode      = 0644;                            /* mode of a new file under the process's umask */
static const int    output_signals[] = {SIGTERM, SIGINT, SIGHUP, SIGQUIT};
static const size_t output_nsignals  = sizeof(output_signals) / sizeof(output_signals[0]);

static void OutputFileRemoveTemps(void)
{
  for (int i = 0; i < OUTPUT_MAX_TEMPS; ++i)
    if (output_temps[i][0]) (void)unlink(output_temps[i]); /* async-signal-safe */
}

/* The files MPI-IO makes beside a file it opens, named after it: Open MPI's shared file pointer keeps there a lock file
   (NAME-JOB-PID.lock, its sharedfp component "lockedfile") or a data and a metadata file per rank (NAME.data.R and
   NAME.metadata.R, "individual"), and removes them when the file is closed. Open MPI takes "sm", which keeps none,
   unless it cannot (its file in Open MPI's session directory cannot be made: the test suite's isolated singletons once
   took that directory from under each other); a write that fails on a full disk then ends without that close, and
   they would stay in the output's directory. A temporary's name is
   unique (mkstemp()), so every entry whose name extends it with '-' or '.' is one of them. At exit and after a
   failure, not from a signal handler: opendir() is not async-signal-safe. */
static void OutputFileRemoveCompanions(void)
{
  for (int i = 0; i < OUTPUT_MAX_TEMPS; ++i) {
    char           dir[PETSC_MAX_PATH_LEN], *slash;
    const char    *base;
    size_t         n;
    DIR           *d;
    struct dirent *e;

    if (!output_temps[i][0]) continue;
    memcpy(dir, output_temps[i], sizeof(dir));
    slash = strrchr(dir, '/'); /* always there: "DIR/.signorini-XXXXXX" */
    if (!slash) continue;
    *slash = '\0';
    base   = slash + 1;
    n      = strlen(base);
    if (!(d = opendir(dir))) continue;
    while ((e = readdir(d)))
      if (!strncmp(e->d_name, base, n) && (e->d_name[n] == '-' || e->d_name[n] == '.')) (void)unlinkat(dirfd(d), e->d_name, 0);
    (void)closedir(d);
  }
}

static void OutputFileCleanUpAtExit(void)
{
  OutputFileRemoveCompanions();
  OutputFileRemoveTemps();
}

/* The termination signals may be delivered to any thread of the process (Open MPI, PMIx and OpenBLAS start threads of
   their own), so they cannot be held back by a signal mask; the handler sends them on to the main thread. While the
   main thread creates the temporaries or renames the pair, a signal is only recorded; it takes effect when the main
   thread leaves that critical section. */
static volatile sig_atomic_t output_critical = 0; /* the main thread is creating temporaries or renaming the pair */
static volatile sig_atomic_t output_pending  = 0; /* a termination signal that arrived meanwhile */

/* What a termination signal says before the process dies of it, on rank 0: which output the run leaves (an adaptive run
   that wrote its last finished cycle, adapt.c). The note is staged before a write and becomes the one said when the
   write's files are in place (OutputFileCommit()), so that it always names what the output holds. */
static char   output_note[1024], output_note_staged[1024];
static size_t output_note_len = 0;

static void OutputFileDie(int sig)
{
  if (output_note_len) (void)!write(STDERR_FILENO, output_note, output_note_len); /* async-signal-safe */
  OutputFileRemoveTemps();
  (void)signal(sig, SIG_DFL);
  (void)raise(sig); /* die of the signal, as without the handler */
}

/* The thread that writes the output (the one that installed the handler). A signal delivered to another thread is sent
   on to it: a handler on another thread would remove the temporaries while the main thread goes on writing, and the
   main thread could create a temporary again (HDF5 opens it with O_CREAT) in the moment before the process dies, which
   would leave it behind. On the main thread the write is interrupted while the handler runs. */
static pthread_t output_main_thread;

static void OutputFileSignalHandler(int sig)
{
  if (!pthread_equal(pthread_self(), output_main_thread)) { /* pthread_self() and pthread_kill() are async-signal-safe */
    (void)pthread_kill(output_main_thread, sig);
    return;
  }
  if (output_critical)
    output_pending = sig;
  else
    OutputFileDie(sig);
}

static void OutputFileEnterCritical(void)
{
  output_critical = 1;
  __sync_synchronize();
}

static void OutputFileLeaveCritical(void)
{
  __sync_synchronize();
  output_critical = 0;
  __sync_synchronize();
  if (output_pending) OutputFileDie(output_pending);
}

/* Installs the clean-up of the temporaries at exit (also after an error in main) and on the usual termination signals
   (in place of PETSc's handler for these signals, which would abort without it). */
PetscErrorCode OutputFileInstallCleanup(void)
{
  struct sigaction sa;
  mode_t           mask;

  PetscFunctionBeginUser;
  mask        = umask(0);
  output_mode = 0666 & ~mask;
  (void)umask(mask);
  PetscCheck(atexit(OutputFileCleanUpAtExit) == 0, PETSC_COMM_SELF, PETSC_ERR_SYS, "atexit() failed");
  output_main_thread = pthread_self();
  memset(&sa, 0, sizeof(sa));
  sa.sa_handler = OutputFileSignalHandler;
  sigemptyset(&sa.sa_mask);
  for (size_t i = 0; i < output_nsignals; ++i)
    PetscCheck(sigaction(output_signals[i], &sa, NULL) == 0, PETSC_COMM_SELF, PETSC_ERR_SYS, "sigaction() failed");
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Stages the note a termination signal prints once the next output is in place (rank 0 keeps it; "" says nothing). */
PetscErrorCode OutputFileStageSignalNote(MPI_Comm comm, const char note[])
{
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  if (rank == 0) PetscCall(PetscStrncpy(output_note_staged, note, sizeof(output_note_staged)));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* dir and base of path ("." when it has no directory part). */
PetscErrorCode OutputFileSplitPath(const char path[], char dir[], size_t dlen, char base[], size_t blen)
{
  const char *slash = strrchr(path, '/');

  PetscFunctionBeginUser;
  if (!slash) {
    PetscCall(PetscStrncpy(dir, ".", dlen));
    PetscCall(PetscStrncpy(base, path, blen));
  } else {
    PetscCheck((size_t)(slash - path) < dlen, PETSC_COMM_SELF, PETSC_ERR_USER_INPUT, "Path too long: %s", path);
    if (slash == path)
      PetscCall(PetscStrncpy(dir, "/", dlen));
    else {
      memcpy(dir, path, (size_t)(slash - path));
      dir[slash - path] = '\0';
    }
    PetscCall(PetscStrncpy(base, slash + 1, blen));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The XDMF file beside FILE.h5: FILE.xdmf (FILE.h5 without the .h5 suffix: FILE.h5.xdmf). */
PetscErrorCode OutputFileXdmfName(const char h5[], char xdmf[], size_t len)
{
  size_t n;

  PetscFunctionBeginUser;
  PetscCall(PetscStrlen(h5, &n));
  PetscCheck(n + 6 <= len, PETSC_COMM_SELF, PETSC_ERR_USER_INPUT, "Output path too long: %s", h5);
  PetscCall(PetscStrncpy(xdmf, h5, len));
  if (n > 3 && !strcmp(xdmf + n - 3, ".h5")) xdmf[n - 3] = '\0';
  PetscCall(PetscStrlcat(xdmf, ".xdmf", len));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* What the existing path is, when it is not a regular file ("" when it is one or does not exist). */
static const char *OutputFileKind(const char path[])
{
  struct stat st;

  if (lstat(path, &st) != 0) return "";
  if (S_ISREG(st.st_mode)) return "";
  if (S_ISLNK(st.st_mode)) return "a symbolic link";
  if (S_ISDIR(st.st_mode)) return "a directory";
  if (S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode)) return "a device";
  if (S_ISFIFO(st.st_mode)) return "a FIFO";
  if (S_ISSOCK(st.st_mode)) return "a socket";
  return "not a regular file";
}

/* Everything about -output that can be checked before the solve: the directory exists (the default one is created)
   and is writable, the names of FILE.h5 and FILE.xdmf fit the file system, and each is absent or a regular file. */
PetscErrorCode OutputFileCheckTarget(MPI_Comm comm, const char path[], PetscBool create_dir)
{
  char        dir[PETSC_MAX_PATH_LEN], base[PETSC_MAX_PATH_LEN], xdmf[PETSC_MAX_PATH_LEN], xbase[PETSC_MAX_PATH_LEN];
  struct stat st;
  long        name_max;
  size_t      len;

  PetscFunctionBeginUser;
  PetscCall(PetscStrlen(path, &len));
  PetscCheck(len > 0, comm, PETSC_ERR_USER_INPUT, "-output needs a file name");
  PetscCheck(len < PETSC_MAX_PATH_LEN - 8, comm, PETSC_ERR_USER_INPUT, "-output: the path is longer than the %d characters a path may have",
             PETSC_MAX_PATH_LEN - 8);
  PetscCall(OutputFileSplitPath(path, dir, sizeof(dir), base, sizeof(base)));
  PetscCheck(base[0] && strcmp(base, ".") && strcmp(base, ".."), comm, PETSC_ERR_USER_INPUT, "-output %s names a directory, not a file", path);
  if (create_dir && stat(dir, &st) != 0) PetscCall(PetscMkdir(dir));
  PetscCheck(stat(dir, &st) == 0 && S_ISDIR(st.st_mode) && access(dir, W_OK | X_OK) == 0, comm, PETSC_ERR_USER_INPUT,
             "Output directory '%s' (-output %s) does not exist or is not writable", dir, path);
  PetscCall(OutputFileXdmfName(path, xdmf, sizeof(xdmf)));
  PetscCall(OutputFileSplitPath(xdmf, dir, sizeof(dir), xbase, sizeof(xbase)));
  errno    = 0;
  name_max = pathconf(dir, _PC_NAME_MAX);
  if (name_max > 0) {
    PetscCheck(strlen(base) <= (size_t)name_max, comm, PETSC_ERR_USER_INPUT,
               "-output: the file name '%s' has %d characters, more than the %ld the file system of '%s' accepts", base, (int)strlen(base), name_max,
               dir);
    PetscCheck(strlen(xbase) <= (size_t)name_max, comm, PETSC_ERR_USER_INPUT,
               "-output: the XDMF file beside it, '%s', would have %d characters, more than the %ld the file system of '%s' accepts", xbase,
               (int)strlen(xbase), name_max, dir);
  }
  PetscCheck(!OutputFileKind(path)[0], comm, PETSC_ERR_USER_INPUT, "-output %s is %s: only a regular file (or a new name) is replaced", path,
             OutputFileKind(path));
  PetscCheck(!OutputFileKind(xdmf)[0], comm, PETSC_ERR_USER_INPUT, "The XDMF file of -output %s, %s, is %s: only a regular file is replaced", path,
             xdmf, OutputFileKind(xdmf));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Creates n new empty files with unique names in dir (rank 0) and registers them for removal; every rank gets the names. */
PetscErrorCode OutputFileCreateTemps(MPI_Comm comm, const char dir[], PetscInt n, char temps[][PETSC_MAX_PATH_LEN])
{
  PetscMPIInt rank;
  int         err = 0;

  PetscFunctionBeginUser;
  PetscCheck(n <= OUTPUT_MAX_TEMPS, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Too many temporary files");
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  if (rank == 0) {
    OutputFileEnterCritical(); /* no temporary created and not yet registered */
    for (PetscInt i = 0; i < n && !err; ++i) {
      int fd;

      (void)snprintf(temps[i], PETSC_MAX_PATH_LEN, "%s/.signorini-XXXXXX", dir);
      fd = mkstemp(temps[i]);
      if (fd < 0)
        err = errno;
      else {
        (void)fchmod(fd, output_mode);
        (void)close(fd);
        memcpy(output_temps[i], temps[i], PETSC_MAX_PATH_LEN);
      }
    }
    OutputFileLeaveCritical();
  }
  PetscCallMPI(MPI_Bcast(&err, 1, MPI_INT, 0, comm));
  if (err) PetscCall(OutputFileDiscardTemps(comm));
  PetscCheck(!err, comm, PETSC_ERR_FILE_WRITE, "Cannot create a file in the output directory '%s': %s", dir, strerror(err));
  PetscCallMPI(MPI_Bcast(temps, (PetscMPIInt)(n * PETSC_MAX_PATH_LEN), MPI_CHAR, 0, comm));
  if (rank)
    for (PetscInt i = 0; i < n; ++i) memcpy(output_temps[i], temps[i], PETSC_MAX_PATH_LEN);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Removes the registered temporaries (after a failure). */
PetscErrorCode OutputFileDiscardTemps(MPI_Comm comm)
{
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  OutputFileEnterCritical();
  if (rank == 0) {
    OutputFileRemoveCompanions();
    OutputFileRemoveTemps();
  }
  memset(output_temps, 0, sizeof(output_temps));
  OutputFileLeaveCritical();
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Renames the n temporaries over their targets, in order, as one step: under an exclusive lock of the directory and
   with the termination signals deferred until both are renamed. */
PetscErrorCode OutputFileCommit(MPI_Comm comm, const char dir[], PetscInt n, char temps[][PETSC_MAX_PATH_LEN], const char *targets[])
{
  PetscMPIInt rank;
  int         err = 0, failed = -1;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  if (rank == 0) {
    int dfd;

    OutputFileEnterCritical();
    dfd = open(dir, O_RDONLY | O_DIRECTORY);
    if (dfd >= 0) (void)flock(dfd, LOCK_EX);
    for (PetscInt i = 0; i < n && !err; ++i) {
      if (rename(temps[i], targets[i]) != 0) {
        err    = errno;
        failed = (int)i;
      } else
        output_temps[i][0] = '\0';
    }
    if (dfd >= 0) {
      (void)flock(dfd, LOCK_UN);
      (void)close(dfd);
    }
    if (!err) { /* the files in place: the note staged for them is the one a signal says from now on */
      memcpy(output_note, output_note_staged, sizeof(output_note));
      output_note_len = strnlen(output_note, sizeof(output_note) - 1);
    }
    output_note_staged[0] = '\0';
    OutputFileLeaveCritical();
  }
  PetscCallMPI(MPI_Bcast(&err, 1, MPI_INT, 0, comm));
  PetscCallMPI(MPI_Bcast(&failed, 1, MPI_INT, 0, comm));
  if (err)
    PetscCall(OutputFileDiscardTemps(comm));
  else
    memset(output_temps, 0, sizeof(output_temps));
  PetscCheck(!err, comm, PETSC_ERR_FILE_WRITE, "Cannot replace %s: %s", targets[failed], strerror(err));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Makes the directory of path the working directory and gives the file's name in it: an HDF5 file is opened by its
   short name, because Open MPI 4.1's MPI-IO copies the name into a 256-byte buffer (a longer path crashed it).
   *cwd keeps the previous working directory for OutputFileLeaveDirectory(). */
PetscErrorCode OutputFileEnterDirectory(const char path[], int *cwd, char base[], size_t len)
{
  char dir[PETSC_MAX_PATH_LEN];

  PetscFunctionBeginUser;
  PetscCall(OutputFileSplitPath(path, dir, sizeof(dir), base, len));
  *cwd = open(".", O_RDONLY | O_DIRECTORY);
  PetscCheck(*cwd >= 0, PETSC_COMM_SELF, PETSC_ERR_SYS, "Cannot open the working directory: %s", strerror(errno));
  PetscCheck(chdir(dir) == 0, PETSC_COMM_SELF, PETSC_ERR_FILE_OPEN, "Cannot enter the directory '%s' of %s: %s", dir, path, strerror(errno));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode OutputFileLeaveDirectory(int cwd)
{
  PetscFunctionBeginUser;
  PetscCheck(fchdir(cwd) == 0, PETSC_COMM_SELF, PETSC_ERR_SYS, "Cannot return to the working directory: %s", strerror(errno));
  (void)close(cwd);
  PetscFunctionReturn(PETSC_SUCCESS);
}
