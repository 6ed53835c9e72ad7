"""Shared fixtures and markers of the test suite.

Session fixtures load each built-in case and build each Simulator once for the whole run
(a Simulator is immutable after construction: its runs never change it).

Markers (registered in pyproject.toml):

* ``slow``  -- long runs (the property-based fuzzing profile, the early verdicts on miniWECC's
  whole screening), deselected by default (``-m slow`` runs them);
* ``andes`` -- cross-validation against ANDES (needs the ``andes`` extra; skipped without).
  ANDES's runs are stored (tests/andes_refs.py, tests/data/andes_refs/): by default no ANDES
  time simulation runs; ``STABCTL_ANDES_REFS=live`` (CI) adds the live smoke tests, which
  check the stored traces against fresh ANDES runs;
* ``dask``  -- sweeps on a Dask cluster (needs ``distributed``; skipped without);
* ``heavy`` -- a minute or more of a core (`pytest_collection_modifyitems` runs them first).

A quick run: ``python -m pytest -m "not andes and not dask"``.

On several processes (pytest-xdist ``-n``) the controller first fills the compiled-kernel
cache (``stabctl compile``, `pytest_configure`), so that no test meets a cold cache while
the others load every core: a first compile then takes minutes, and a command's output
carries its compile notice.  The commands a test starts import the stabctl the tests import
(`pytest_configure` puts it first on PYTHONPATH): run from the project root after a plain
``pip install .``, they would import the installed copy from their own working directory,
whose cache that compile never filled.
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import tempfile

import pytest

import stabctl
from stabctl.dynamics.driver import Simulator
from stabctl.io import load_case


@pytest.fixture(autouse=True)
def _signal_dispositions_restored():
    """Each test leaves SIGINT, SIGTERM and SIGHUP as it found them: a command run in the
    test's process ends by ignoring a signal that comes after it (`stabctl.__main__`,
    `stabctl.cli.options.reports_errors`: right for a process about to exit), and a Dask
    worker started in it ignores SIGINT; left so, they made later tests of the same
    worker process and the children they start ignore the signals under test."""
    kept = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)}
    yield
    for sig, handler in kept.items():
        if signal.getsignal(sig) is not handler and handler is not None:
            signal.signal(sig, handler)


@pytest.hookimpl(tryfirst=True)
def pytest_xdist_auto_num_workers(config):
    """``-n auto``: one worker more than the cores (at least 3).  About a fifth of the
    suite's wall time is waiting, not computing (servers and plants started as processes,
    streams paced or timed out, examples run as commands), during which the extra worker
    computes; PYTEST_XDIST_AUTO_NUM_WORKERS (pytest-xdist's) still sets the number."""
    if os.environ.get("PYTEST_XDIST_AUTO_NUM_WORKERS"):
        return None
    return max(3, (os.cpu_count() or 1) + 1)


def pytest_configure(config):
    """Under pytest-xdist, in the controller before the workers start: ``stabctl compile``
    (every built-in case's argument types into the shared on-disk cache; a warm cache
    only loads, about a second).  Before it, in every process: the folder of the stabctl
    under test first on PYTHONPATH, for that compile and every command the tests start;
    and, in the controller (the workers inherit it), XDG_CACHE_HOME a new directory of the
    run, so that the work a `place` or `estimate cct` keeps (`stabctl.locking.kept_paths`)
    is the run's own: kept in the user's ~/.cache by one test (a plan refused or
    interrupted), it was read by another's same plan, whose lines then differed (CI,
    2026-12-01)."""

    root = os.path.dirname(os.path.dirname(os.path.abspath(stabctl.__file__)))
    path = os.environ.get("PYTHONPATH", "")
    if path.split(os.pathsep)[0] != root:
        os.environ["PYTHONPATH"] = os.pathsep.join(filter(None, [root, path]))
    if not hasattr(config, "workerinput"):
        config.stabctl_kept_work = tempfile.mkdtemp(prefix="stabctl-tests-cache.")
        os.environ["XDG_CACHE_HOME"] = config.stabctl_kept_work
    if getattr(config.option, "numprocesses", None) and not hasattr(config, "workerinput"):
        subprocess.run(
            [sys.executable, "-m", "stabctl.cli", "compile"], capture_output=True, timeout=1200
        )


def pytest_unconfigure(config):
    """The run's XDG_CACHE_HOME (`pytest_configure`) removed with what it holds."""
    kept = getattr(config, "stabctl_kept_work", None)
    if kept:
        shutil.rmtree(kept, ignore_errors=True)


def pytest_collection_modifyitems(config, items):
    """The ``heavy`` tests first (in their order, the others after in theirs): pytest-xdist
    hands out tests in collection order, so the longest start at once on every worker
    instead of keeping one worker busy after the others have run out of tests."""
    items.sort(key=lambda item: item.get_closest_marker("heavy") is None)


@pytest.fixture(scope="session")
def kundur_case():
    """The built-in Kundur two-area case (PSTess d2asbegp)."""
    return load_case("kundur")


@pytest.fixture(scope="session")
def miniwecc_case():
    """The built-in miniWECC case (PSTess d_minniWECC_base)."""
    return load_case("miniwecc")


@pytest.fixture(scope="session")
def kundur(kundur_case):
    """Simulator of Kundur under the default (ieee) conventions."""
    return Simulator(kundur_case)


@pytest.fixture(scope="session")
def kundur_pstess(kundur_case):
    """Simulator of Kundur under the PSTess 1.1 conventions."""
    return Simulator(kundur_case, conventions="pstess")


@pytest.fixture(scope="session")
def wecc(miniwecc_case):
    """Simulator of the miniWECC under the default (ieee) conventions."""
    return Simulator(miniwecc_case)


@pytest.fixture(scope="session")
def wecc_pstess(miniwecc_case):
    """Simulator of the miniWECC under the PSTess 1.1 conventions."""
    return Simulator(miniwecc_case, conventions="pstess")


@pytest.fixture(scope="session")
def psse_omib(tmp_path_factory):
    """PSS/E's OMIB run's case (tests/data/psse_runs/OMIB_GENCLS: a GENCLS machine, bus
    102, against an infinite bus, a GENCLS of H = 0 at bus 101, over two lines) imported
    as a user does (`stabctl import-psse RAW DYR`); its file name."""
    from click.testing import CliRunner

    from stabctl.cli import main

    d = os.path.join(os.path.dirname(__file__), "data", "psse_runs", "OMIB_GENCLS")
    out = str(tmp_path_factory.mktemp("omib") / "omib.json")
    args = ["import-psse", f"{d}/OMIB.raw", f"{d}/OMIB.dyr", "-o", out]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    return out
