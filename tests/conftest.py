"""pytest fixtures of the test suite: the build of bin/signorini, the output root tests/out (wiped once per session),
a directory of its own under it for a test, and the MPI environment of the programs the tests start."""
import os
import re
import shutil
import subprocess

import pytest

from harness import BIN, ENV, OUT, ROOT


@pytest.fixture(scope="session", autouse=True)
def solver():
    """Builds bin/signorini (as `make test` does before pytest), so that `python3 -m pytest tests` works on its own."""
    p = subprocess.run(["make", "--no-print-directory", "bin/signorini"], cwd=ROOT, env=ENV, stdout=subprocess.PIPE,
                       stderr=subprocess.STDOUT, text=True)
    assert p.returncode == 0, f"make bin/signorini failed:\n{p.stdout[-3000:]}"
    assert os.access(BIN, os.X_OK), f"{BIN} not built"
    return BIN


@pytest.fixture(scope="session", autouse=True)
def out_root():
    """tests/out, the root of every test's output, deleted and made anew once per session."""
    shutil.rmtree(OUT, ignore_errors=True)
    os.makedirs(OUT)
    return OUT


@pytest.fixture
def outdir(out_root, request):
    """A directory of the test's own under tests/out, named after the test (and its parameters), made empty."""
    d = os.path.join(out_root, re.sub(r"[^A-Za-z0-9_.-]+", "_", request.node.name).strip("_"))
    shutil.rmtree(d, ignore_errors=True)
    os.makedirs(d)
    return d


@pytest.fixture(scope="session", autouse=True)
def mpi_environment():
    """Open MPI as root and with more ranks than cores, also for the scripts the tests start without ENV (study.py and
    tradeoff.py by the tests of test_study.py and test_tradeoff.py, which used to run in a subprocess given ENV)."""
    keys = ("OMPI_ALLOW_RUN_AS_ROOT", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "OMPI_MCA_rmaps_base_oversubscribe")
    saved = {k: os.environ.get(k) for k in keys}
    os.environ.update({k: ENV[k] for k in keys})
    yield
    for k, v in saved.items():
        if v is None:
            os.environ.pop(k, None)
        else:
            os.environ[k] = v
