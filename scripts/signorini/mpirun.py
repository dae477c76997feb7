"""Running bin/signorini under mpiexec: the MPI environment, a time limit, the console log, and the
tail or the telling line of a failed run's output."""
import os
import re
import signal
import statistics
import subprocess
import time
from dataclasses import dataclass
from typing import Optional

from .paths import ROOT

# mpiexec as root, and more ranks than cores
MPI_ENV = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
           "OMPI_MCA_rmaps_base_oversubscribe": "1"}
# The benches' environment: one BLAS and OpenMP thread per MPI rank (the ranks already use the cores), and the same
# last bits from run to run: OpenBLAS's threads change those of LAPACK's eigenvalue estimates for the Chebyshev
# smoothers, and with them a few iteration counts (docs/solvers.md, the eps sweep of issue 35).
BENCH_ENV = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
LOG_TAIL_LINES = 40  # lines of solver output shown when a run fails without output


@dataclass
class MpiResult:
    """What came back from one mpiexec: exit status, console output (stdout and stderr merged),
    wall time in seconds, and whether it was killed at the time limit."""
    returncode: Optional[int]
    output: str
    wall: float
    timed_out: bool


def _kill_group(proc, sig):
    try:
        os.killpg(proc.pid, sig)
    except ProcessLookupError:
        pass


def run_mpi(cmd, log=None, timeout=None, env=None, header=""):
    """Run `cmd` in ROOT with the MPI environment (plus `env`), stdout and stderr merged.

    The process runs in its own session, so that at the time limit `timeout` (seconds, None: no
    limit) mpiexec and its ranks are stopped together (SIGTERM, then SIGKILL after 10 s). The
    console output, preceded by `header`, is written to the file `log` when given.
    """
    t0 = time.monotonic()
    proc = subprocess.Popen(cmd, cwd=ROOT, env={**os.environ, **MPI_ENV, **(env or {})},
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            start_new_session=True)
    timed_out = False
    try:
        try:
            text, _ = proc.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            timed_out = True
            _kill_group(proc, signal.SIGTERM)  # its own session: mpiexec and its ranks
            try:
                text, _ = proc.communicate(timeout=10)
            except subprocess.TimeoutExpired:
                _kill_group(proc, signal.SIGKILL)
                text, _ = proc.communicate()
    except BaseException:  # e.g. Ctrl-C: do not leave the ranks running
        _kill_group(proc, signal.SIGKILL)
        proc.wait()
        raise
    wall = time.monotonic() - t0
    if log is not None:
        with open(log, "w") as fh:
            fh.write(header + text)
    return MpiResult(proc.returncode, text, wall, timed_out)


def timed_or_exit(cmd):
    """Runs cmd from the project's root in the benches' environment and returns its wall time; exits with its output's
    tail if it fails (the studies' runs, which must all succeed)."""
    t0 = time.perf_counter()
    p = subprocess.run(cmd, cwd=ROOT, env={**os.environ, **MPI_ENV, **BENCH_ENV}, capture_output=True, text=True)
    if p.returncode:
        raise SystemExit(f"{' '.join(cmd)} failed:\n{p.stdout[-2000:]}")
    return time.perf_counter() - t0


def paired_medians(cmd, other, pairs, once=None):
    """The median wall times of cmd and of other (None: none) over `pairs` alternated runs, side by side so that the
    machine's noise falls on both; NaN for a missing other. pairs 0: (once, NaN), cmd's time already measured once
    (a run too long to repeat)."""
    if pairs == 0:
        return once, float("nan")
    t, t_other = [], []
    for _ in range(pairs):
        t.append(timed_or_exit(cmd))
        if other:
            t_other.append(timed_or_exit(other))
    return statistics.median(t), statistics.median(t_other) if other else float("nan")


def timing_text(pairs):
    """How paired_medians() timed: for a report's text."""
    return f"medians of {pairs} alternated pairs, whole processes" if pairs else "one run of the adaptive process, not paired"


def tail(text, n=LOG_TAIL_LINES):
    """The last `n` lines of `text` (trailing blank space removed)."""
    return "\n".join(text.rstrip().splitlines()[-n:])


def error_line(text):
    """The most telling line of a failed run's output: the solver's refusal of its input, else PETSc's error message if any."""
    lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
    for ln in lines:
        if ln.startswith("signorini: error"):
            return ln.split(": ", 2)[-1]
    for ln in lines:
        if "PETSC ERROR" in ln and not re.search(r"-{5}|Error Message|See https", ln):
            msg = ln.split("PETSC ERROR:", 1)[-1].strip()
            if msg and not msg.startswith(("Missing or incorrect", "#", "Petsc Release")):
                return msg
    for ln in reversed(lines):
        if "ERROR" in ln:
            return ln
    return lines[-1] if lines else "(no output)"


def run_timed(cmd, env=None, ok_codes=(0,)):
    """(wall seconds, peak resident set in MiB, stdout+stderr) of one whole process, by /usr/bin/time -v; an exit code
    outside ok_codes raises."""
    p = subprocess.run(["/usr/bin/time", "-v"] + [str(c) for c in cmd], cwd=ROOT, env={**os.environ, **MPI_ENV, **(env or {})}, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                       text=True)
    if p.returncode not in ok_codes:
        raise RuntimeError(f"{' '.join(map(str, cmd))} failed ({p.returncode}):\n{p.stdout[-3000:]}")
    wall = mem = None
    for line in p.stdout.splitlines():
        line = line.strip()
        if line.startswith("Elapsed (wall clock) time"):
            parts = line.split(": ", 1)[1].split(":")
            wall = sum(float(v) * 60 ** k for k, v in enumerate(reversed(parts)))
        elif line.startswith("Maximum resident set size"):
            mem = float(line.split(":")[1]) / 1024.0
    return wall, mem, p.stdout
