"""pytest fixtures of the test suite: the build of bin/signorini, the output root tests/out (wiped once per session),
a directory of its own under it for a test, and the MPI environment of the programs the tests start."""
import os
import re
import shutil
import subprocess

import pytest

from harness import BIN, ENV, OUT, OUT_ROOT, ROOT


def pytest_configure(config):
    """Once per session, before any test, in the process that leads it (pytest-xdist's controller, which starts its
    workers after this, or pytest alone): builds bin/signorini as `make test` does before pytest, so that `python3 -m
    pytest tests` works on its own, and deletes and makes anew tests/out, the root of every test's output. A worker
    (config.workerinput) does neither: two builds at once would race, and a worker's wipe would delete the files of
    the tests the other worker is running. Nor does --collect-only, which runs nothing."""
    if hasattr(config, "workerinput") or config.option.collectonly:
        return
    p = subprocess.run(["make", "--no-print-directory", "bin/signorini"], cwd=ROOT, env=ENV, stdout=subprocess.PIPE,
                       stderr=subprocess.STDOUT, text=True)
    if p.returncode != 0:
        pytest.exit(f"make bin/signorini failed:\n{p.stdout[-3000:]}", returncode=1)
    shutil.rmtree(OUT_ROOT, ignore_errors=True)
    os.makedirs(OUT_ROOT)


@pytest.fixture(scope="session", autouse=True)
def solver():
    """bin/signorini, built by pytest_configure()."""
    assert os.access(BIN, os.X_OK), f"{BIN} not built"
    return BIN


@pytest.fixture(scope="session", autouse=True)
def out_root():
    """tests/out (made anew by pytest_configure()), or a worker's own directory under it."""
    os.makedirs(OUT, exist_ok=True)
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
