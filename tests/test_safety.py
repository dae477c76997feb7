"""Output safety (make test): a run killed by SIGTERM or SIGINT at any point (set-up, solve, write), on 1 or 2 ranks,
leaves either the old output or the new one, complete, and nothing else; two runs writing the same output at once
leave the pair of files of one of them, whole.
"""
import os
import re
import shutil
import signal
import subprocess
import time
import xml.etree.ElementTree as ET

import h5py
import numpy as np
import pytest

from harness import BIN, ENV, OUT, ROOT, load, run, sorted_by_position

SAFETY = os.path.join(OUT, "safety")
OLD = ["-dm_plex_box_faces", "8,8"]
NEW = ["-dm_plex_box_faces", "96,96", "-penalty_eps0", 0.1, "-contact_monitor"]  # about a second of set-up and solve
LONG = ["-dm_plex_box_faces", "192,192", "-penalty_eps0", 0.01, "-contact_monitor"]  # a few seconds on 2 ranks


def xdmf_cells(path):
    root = ET.parse(path).getroot()
    return int(next(root.iter("Topology")).get("NumberOfElements"))


def pair_is_complete(h5, xdmf):
    """The .h5 reads back and the .xdmf beside it describes it (same cell count, every dataset present)."""
    with h5py.File(h5, "r") as f:
        n_cells = int(f["run"].attrs["n_cells"])
        for item in ET.parse(xdmf).getroot().iter("DataItem"):
            path = item.text.strip().split(":")[1]
            assert path in f, f"{xdmf} points at {path}, missing from {h5}"
    assert xdmf_cells(xdmf) == n_cells, f"{xdmf} has {xdmf_cells(xdmf)} cells, {h5} has {n_cells}"
    return n_cells


def xdmf_points_at_its_h5(h5, xdmf):
    """Every DataItem of the .xdmf names the .h5 beside it by its final name (not the temporary .signorini-XXXXXX it
    was written under) and gives the shape of the dataset it points at in that file."""
    with h5py.File(h5, "r") as f:
        for item in ET.parse(xdmf).getroot().iter("DataItem"):
            name, path = item.text.strip().split(":")
            assert name == os.path.basename(h5), f"{xdmf} points at file {name}, not {os.path.basename(h5)}"
            dims = tuple(int(v) for v in item.get("Dimensions").split())
            assert f[path].shape == dims, f"{xdmf}: {path} has Dimensions {dims}, the dataset {f[path].shape}"


def prepare(name):
    d = os.path.join(SAFETY, name)
    shutil.rmtree(d, ignore_errors=True)
    os.makedirs(d)
    _, h5 = run(OLD, f"safety/{name}/result")
    with open(h5, "rb") as fh:
        old = fh.read()
    return d, h5, old


def check_old_or_new(d, h5, old, label):
    names = sorted(os.listdir(d))
    assert names == ["result.h5", "result.xdmf"], f"{label}: the directory holds {names}"
    with open(h5, "rb") as fh:
        now = fh.read()
    n_cells = pair_is_complete(h5, h5[:-3] + ".xdmf")
    if now == old:
        return "old"
    assert n_cells in (2 * 96 * 96, 2 * 192 * 192), f"{label}: a new output of {n_cells} cells"
    a, _ = load(h5)
    assert a["converged"] == 1, label
    return "new"


def start(d, np_=1, direct=True, new=NEW):
    args = [str(a) for a in new] + ["-output", os.path.join(d, "result.h5")]
    cmd = ([BIN] if direct else ["mpiexec", "-n", str(np_), BIN]) + args
    return subprocess.Popen(cmd, cwd=ROOT, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, bufsize=1)


def wait_for_handler(p, sig, timeout=60):
    """Waits until the process catches sig (its bit in SigCgt of /proc/PID/status): the solver installs its handler
    after PetscInitialize, at the start of its set-up. A signal sent before that (a fixed 0.05 s after the start) could
    land in Open MPI's start-up, which ignored a SIGINT in 2 of some 20 full runs."""
    t0 = time.time()
    while time.time() - t0 < timeout and p.poll() is None:
        try:
            with open(f"/proc/{p.pid}/status") as fh:
                caught = next(int(line.split()[1], 16) for line in fh if line.startswith("SigCgt:"))
        except (OSError, StopIteration):
            return False
        if caught >> (int(sig) - 1) & 1:
            return True
        time.sleep(0.001)
    return False


def wait_for_line(p, pattern, timeout=60):
    t0 = time.time()
    for line in p.stdout:
        if re.search(pattern, line):
            return True
        if time.time() - t0 > timeout:
            break
    return False


def wait_for_temporary(p, d, timeout=60):
    t0 = time.time()
    while time.time() - t0 < timeout and p.poll() is None:
        if any(n.startswith(".signorini-") for n in os.listdir(d)):
            return True
        time.sleep(0.0005)
    return False


def finish(p):
    p.stdout.read()
    return p.wait(timeout=120)


@pytest.mark.slow
def test_sigterm_during_set_up_solve_and_write():
    """SIGTERM (and SIGINT) sent to the solver in its set-up, in its Newton steps, and inside the write (the process is
    stopped when its temporary file appears, signalled, then continued): the old output is untouched, nothing is left."""
    outcomes = []
    for sig in (signal.SIGTERM, signal.SIGINT):
        for stage in ("set-up", "solve", "write"):
            d, h5, old = prepare(f"{stage}_{sig.name}")
            p = start(d)
            if stage == "set-up":
                assert wait_for_handler(p, sig), "the solver never installed its signal handler"
                p.send_signal(sig)
            elif stage == "solve":
                assert wait_for_line(p, r"^\s+1 contact: \|F\|"), "no Newton step seen"
                p.send_signal(sig)
            else:
                assert wait_for_temporary(p, d), "no temporary output seen"
                p.send_signal(signal.SIGSTOP)
                p.send_signal(sig)
                p.send_signal(signal.SIGCONT)
            rc = finish(p)
            assert rc == -sig, f"{stage}, {sig.name}: exit status {rc}, expected death by the signal"
            outcomes.append(check_old_or_new(d, h5, old, f"{stage} {sig.name}"))
    assert outcomes == ["old"] * 6, outcomes


@pytest.mark.slow
def test_sigterm_at_spread_times_leaves_old_or_new():
    """SIGTERM at 10 times spread over a whole run: each leaves the old pair or the new one, complete, and nothing else."""
    d, h5, old = prepare("spread_timing")
    t0 = time.time()
    p = start(d)
    assert finish(p) == 0
    duration = time.time() - t0
    seen = set()
    for k in range(10):
        d, h5, old = prepare(f"spread_{k}")
        p = start(d)
        time.sleep(duration * (k + 0.5) / 10)
        p.send_signal(signal.SIGTERM)
        finish(p)
        seen.add(check_old_or_new(d, h5, old, f"SIGTERM at {k + 0.5}/10 of the run"))
    assert "old" in seen, seen


@pytest.mark.slow
def test_sigterm_to_mpiexec_with_two_ranks():
    """mpiexec forwards SIGTERM to both ranks. In the solve: the old output stays. In the write: mpiexec forwards the
    signal late enough that the write may have ended, so the old pair or the new one, complete; nothing else either way."""
    for stage in ("solve", "write"):
        d, h5, old = prepare(f"mpiexec_{stage}")
        p = start(d, np_=2, direct=False, new=LONG)
        if stage == "solve":
            assert wait_for_line(p, r"^\s+1 contact: \|F\|"), "no Newton step seen"
        else:
            assert wait_for_temporary(p, d), "no temporary output seen"
        p.send_signal(signal.SIGTERM)
        rc = finish(p)
        assert rc != 0, f"{stage}: exit status 0 after SIGTERM"
        outcome = check_old_or_new(d, h5, old, f"mpiexec {stage}")
        assert stage == "write" or outcome == "old", f"{stage}: the run was not stopped by SIGTERM"


def test_concurrent_runs_leave_one_whole_pair():
    """Two runs (24x24 and 32x32 cells) write the same output at once, 6 times over: both succeed, and the .h5 and .xdmf
    left are both of one run, equal to that run's solution computed alone."""
    configs = {2 * 24 * 24: ["-dm_plex_box_faces", "24,24"], 2 * 32 * 32: ["-dm_plex_box_faces", "32,32"]}
    alone = {}
    os.makedirs(SAFETY, exist_ok=True)
    for n_cells, args in configs.items():
        _, f = load(run(args, f"safety/alone_{n_cells}")[1])
        alone[n_cells] = sorted_by_position(f, "displacement")
    d = os.path.join(SAFETY, "concurrent")
    shutil.rmtree(d, ignore_errors=True)
    os.makedirs(d)
    target = os.path.join(d, "result.h5")
    for rep in range(6):
        procs = [subprocess.Popen(["mpiexec", "-n", "1", BIN] + [str(a) for a in args] + ["-output", target], cwd=ROOT, env=ENV,
                                  stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True) for args in configs.values()]
        for p in procs:
            out, _ = p.communicate(timeout=120)
            assert p.returncode == 0, out[-2000:]
        assert sorted(os.listdir(d)) == ["result.h5", "result.xdmf"], os.listdir(d)
        n_cells = pair_is_complete(target, target[:-3] + ".xdmf")
        _, f = load(target)
        u = sorted_by_position(f, "displacement")
        assert np.abs(u - alone[n_cells]).max() <= 1e-12 * np.abs(alone[n_cells]).max(), f"repetition {rep}: not the run's own solution"
        xdmf_points_at_its_h5(target, target[:-3] + ".xdmf")
