"""A long -accuracy run ended by a signal (Ctrl-C, a scheduler's SIGTERM at its time limit) keeps a finished cycle: the
finished cycles write the output with /run adapt_stop = interrupted (each cycle once the cycles since the last write
took 20 times that write's time), which the final write replaces, and a signal says which cycle the output holds.
Before, an interrupted run left nothing, its finished cycles lost."""
import os
import signal
import subprocess
import time

import h5py
import numpy as np
import pytest

from harness import BIN, ROOT, SINGLETON_ENV, load, run
from signorini.mpirun import MPI_ENV

INDENT = ["-scene", "general", "-dm_plex_box_faces", "16,8", "-contact_faces", "3", "-bc_clamp", "1", "-obstacle", "cylinder", "-obstacle_center",
          "0.5,1.5", "-obstacle_radius", "0.5", "-obstacle_translate", "0,-0.01", "-contact_monitor", "0"]
CYCLES_BEFORE_SIGNAL = 6


def interrupted_run(h5, np_, sig):
    """Runs -accuracy 0.001 (about 14 cycles) and sends sig once the monitor's line of cycle CYCLES_BEFORE_SIGNAL is
    out; returns (exit status, console output)."""
    cmd = ([BIN] if np_ == 1 else ["mpiexec", "-n", str(np_), BIN]) + INDENT + ["-accuracy", "0.001", "-adapt_cycles", "40", "-output", h5]
    env = {**os.environ, **MPI_ENV, **(SINGLETON_ENV if np_ == 1 else {})}
    proc = subprocess.Popen(cmd, cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, start_new_session=True)
    lines, t0 = [], time.monotonic()
    for line in proc.stdout:
        lines.append(line)
        if line.startswith(f"  adapt cycle {CYCLES_BEFORE_SIGNAL}:"):
            os.kill(proc.pid, sig)  # the solver itself, or mpiexec, which passes it to the ranks
            break
        assert time.monotonic() - t0 < 300, "".join(lines)
    rest, _ = proc.communicate(timeout=300)
    return proc.returncode, "".join(lines) + rest


@pytest.mark.parametrize("np_,sig", [(1, signal.SIGINT), (2, signal.SIGTERM)], ids=["1rank_sigint", "2ranks_sigterm"])
def test_an_interrupted_accuracy_run_keeps_its_last_finished_cycle(outdir, np_, sig):
    """The signal comes while the cycle after CYCLES_BEFORE_SIGNAL is under way: the output holds the cycles up to the
    last one written (at least the first), flagged adapt_stop = interrupted and not reached, the run says which cycle
    the output holds, and each cycle's row equals that of the same run left to finish (the same mesh, force and bars)."""
    h5 = os.path.join(outdir, "interrupted.h5")
    rc, out = interrupted_run(h5, np_, sig)
    assert rc != 0, out[-2000:]
    assert "interrupted during adaptive cycle" in out and f"{h5} holds cycle" in out, out[-2000:]
    attrs, _ = load(h5)
    assert attrs["adapt_stop"] == "interrupted" and attrs["accuracy_reached"] == 0 and attrs["converged"] == 1
    with h5py.File(h5, "r") as f:
        got = {k: f["cycles"][k][:] for k in ("n_dofs", "contact_force_value", "contact_force_bar")}
    n = len(got["n_dofs"])
    assert n >= 1  # mpiexec passes its output and the signal on later: the ranks may be cycles further
    said = int(out.split(f"{h5} holds cycle ")[1].split()[0])
    assert said == n - 1, (said, n)
    _, full = run(INDENT + ["-accuracy", "0.001", "-adapt_max_dofs", str(int(got["n_dofs"][-1]))], "uninterrupted", np_=np_,
                  output=os.path.join(outdir, "full.h5"))
    with h5py.File(full, "r") as f:
        ref = {k: f["cycles"][k][:n] for k in got}
    assert list(ref["n_dofs"]) == list(got["n_dofs"])
    for k in ("contact_force_value", "contact_force_bar"):
        for a, b in zip(got[k], ref[k]):
            assert a == b or abs(a - b) <= 1e-9 * abs(b) or (np.isnan(a) and np.isnan(b)), (k, a, b)  # no bar before a coarser cycle


def test_a_finished_accuracy_run_replaces_its_checkpoint(outdir):
    """The run that ends by itself writes its own stop over the last cycle's checkpoint."""
    _, h5 = run(INDENT + ["-accuracy", "0.05"], "finished", output=os.path.join(outdir, "finished.h5"))
    attrs, _ = load(h5)
    assert attrs["adapt_stop"] == "accuracy" and attrs["accuracy_reached"] == 1
