"""A cold kernel cache, from empty to warm, in one cold compile (each costs a minute or two
of a core): `stabctl compile --check` says cold (exit 1) and compiles nothing; a first
simulation compiles the integrator in a child process while it compiles the model, then
loads the child's kernel and gives the trajectory of the kernels this process uses;
`stabctl compile` then loads what the run compiled and compiles the rest; `--check` says
warm (exit 0); a second `compile` loads every part.

Throughout, no kernel may compile numba's slice-assignment message (the point of
`stabctl._jit.arrays.assign`: numba's shape-mismatch formatter costs 2-3 s of a cold first
call): a ``sitecustomize`` on the commands' PYTHONPATH watches numba's ``fancy_setslice``
in every process, the integrator's compile child included."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.events import Fault
from stabctl.io import load_case

PARTS = ("model evaluation", "filters", "linearisation", "integrator")

#: imported by every Python process of the commands: records each kernel that compiles
#: numba's slice assignment of a buffer (its shape-mismatch message) into SEEN
_SPY = """
import os
import numba.np.arrayobj as ao
from numba.core import types
_orig = ao.fancy_setslice
with open(os.environ["STABCTL_TEST_SETSLICE"] + ".pids", "a") as f:
    f.write(str(os.getpid()) + "\\n")
def _spy(ctx, b, sig, args, it, ix):
    if isinstance(sig.args[2], types.Buffer):
        with open(os.environ["STABCTL_TEST_SETSLICE"], "a") as f:
            f.write(b.function.name + "\\n")
    return _orig(ctx, b, sig, args, it, ix)
ao.fancy_setslice = _spy
"""


#: a first simulation of Kundur on the cache, printing which kernels it started compiling
#: in the background, the integrator's cache hits and misses and the final speeds
_COLD_RUN = """
import json
from stabctl._jit import background
from stabctl.dynamics.events import Fault
from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.integrator import integrate
from stabctl.io import load_case
sim = Simulator(load_case("kundur"))
started = sorted(background._BACKGROUND)
res = sim.run([Fault(bus=3, t=1.0, clear_near=1.1, clear_far=1.1, far_bus=101)], t_end=3.0)
print(json.dumps({"started": started, "hits": sum(integrate.stats.cache_hits.values()),
                  "misses": sum(integrate.stats.cache_misses.values()),
                  "speed": res.speed[-1].tolist()}))
"""


def _python(*args, cache, spy=None):
    """Run ``python *args`` on the kernel cache ``cache``, watched by the spy in ``spy``."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    if spy is not None:
        spy.mkdir(exist_ok=True)
        (spy / "sitecustomize.py").write_text(_SPY)
        path = os.pathsep.join(filter(None, (str(spy), env.get("PYTHONPATH"))))
        env.update(PYTHONPATH=path, STABCTL_TEST_SETSLICE=str(spy / "seen.txt"))
    return subprocess.run(
        [sys.executable, *args],
        env=env,
        capture_output=True,
        text=True,
        timeout=900,
    )


def _stabctl(*args, cache, spy=None):
    return _python("-m", "stabctl.cli", *args, cache=cache, spy=spy)


def _parts(stdout: str) -> dict[str, str]:
    """Part -> 'compiled' or 'loaded', from the per-part lines of kundur."""
    return {
        p: line.split()[len(p.split()) + 1]
        for line in stdout.splitlines()
        for p in PARTS
        if line.startswith("kundur") and p in line
    }


@pytest.mark.heavy
def test_a_cold_cache_from_a_first_run_and_compile_to_warm(tmp_path):
    cache, spy = tmp_path / "cache", tmp_path / "spy"
    cold = _stabctl("compile", "--check", cache=cache)
    assert cold.returncode == 1, cold.stdout + cold.stderr
    assert "kernel cache cold" in cold.stdout and "not cached" in cold.stdout
    assert not list(tmp_path.rglob("*.nbi"))  # --check compiles nothing

    run = _python("-c", _COLD_RUN, cache=cache, spy=spy)
    assert run.returncode == 0, run.stderr
    got = json.loads(run.stdout.strip().splitlines()[-1])
    assert got["started"] == ["stabctl.dynamics.integrator.integrate"]
    assert (got["hits"], got["misses"]) == (1, 0)  # the child's kernel, loaded
    here = Simulator(load_case("kundur")).run(
        [Fault(bus=3, t=1.0, clear_near=1.1, clear_far=1.1, far_bus=101)], t_end=3.0
    )
    np.testing.assert_allclose(got["speed"], here.speed[-1], rtol=0, atol=1e-13)

    first = _stabctl("compile", "kundur", cache=cache, spy=spy)
    assert first.returncode == 0, first.stdout + first.stderr
    assert _parts(first.stdout) == {
        "model evaluation": "loaded",
        "filters": "compiled",
        "linearisation": "compiled",
        "integrator": "loaded",
    }, first.stdout
    assert "kernel cache warm" in first.stdout
    # it says it compiles as it starts, as every command does (round 40: silent for
    # minutes on a cold cache until its first part ended)
    assert first.stderr.startswith("stabctl: compiling the kernels of the simulator, "), (
        first.stderr
    )
    # the watch ran in the run, its integrator's compile child and the command ...
    assert len(set((spy / "seen.txt.pids").read_text().split())) >= 3
    # ... and no kernel compiled numba's slice-assignment message
    seen = (spy / "seen.txt").read_text().split() if (spy / "seen.txt").exists() else []
    assert seen == [], seen

    warm = _stabctl("compile", "--check", cache=cache)
    assert warm.returncode == 0, warm.stdout + warm.stderr
    assert "not cached" not in warm.stdout and "kernel cache warm" in warm.stdout

    again = _stabctl("compile", "kundur", cache=cache)
    assert again.returncode == 0, again.stdout + again.stderr
    assert _parts(again.stdout) == dict.fromkeys(PARTS, "loaded"), again.stdout
    assert "compiling" not in again.stderr  # loading is no compile


def test_compile_check_makes_nothing_in_an_empty_cache(tmp_path):
    """`compile --check` on an empty NUMBA_CACHE_DIR: cold, named as the place, and the
    directory still empty (numba made 13 kernel directories there, and stabctl its key,
    although --check compiles nothing)."""
    cache = tmp_path / "cache"
    cache.mkdir()
    check = _stabctl("compile", "--check", cache=cache)
    assert check.returncode == 1, check.stdout + check.stderr
    assert check.stdout.splitlines()[-1] == f"kernel cache cold ({cache})"
    assert list(cache.iterdir()) == []


def _with_env(*args, **env):
    return subprocess.run(
        [sys.executable, "-m", "stabctl.cli", *args],
        env={**os.environ, **env},
        capture_output=True,
        text=True,
        timeout=300,
    )


@pytest.mark.parametrize(
    "name,value,needle",
    [
        ("NUMBA_NUM_THREADS", "0", "numba needs a whole number of threads >= 1"),
        ("NUMBA_OPT", "x", "supported values are 0, 1, 2, 3, and 'max'"),
        ("NUMBA_CACHE_DIR", "FILE", "is not a directory"),
        ("NUMBA_DISABLE_JIT", "1", "stabctl's kernels run only compiled"),
    ],
)
@pytest.mark.parametrize("args", [["cases"], ["compile", "--check"]])
def test_a_numba_setting_numba_cannot_use_is_one_error_line(tmp_path, name, value, needle, args):
    """numba's variables in the environment: NUMBA_NUM_THREADS=0 stopped every command with
    a traceback (numba's ValueError, not naming the variable); NUMBA_OPT=x printed numba's
    warning with a whole traceback and ran; a NUMBA_CACHE_DIR that is a file was passed
    over by numba (the kernels cached in __pycache__) while `compile --check` called the
    file the cache; NUMBA_DISABLE_JIT=1 stopped every command with a TypeError from a
    kernel's declaration.  Each is one error line naming the variable, exit status 2."""
    if value == "FILE":
        value = str(tmp_path / "keep.csv")
        (tmp_path / "keep.csv").write_text("keep\n")
    run = _with_env(*args, **{name: value})
    assert run.returncode == 2, run.stdout + run.stderr
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: {name}="), run.stderr
    assert needle in lines[0] and run.stdout == ""


def test_the_library_refuses_numba_s_compiler_off_by_name():
    """`import stabctl` and a simulator with NUMBA_DISABLE_JIT=1: an ImportError naming
    the variable (it was a TypeError from a kernel's declaration); NUMBA_DISABLE_JIT=0
    runs."""

    def simulator_with(value: str) -> subprocess.CompletedProcess:
        return subprocess.run(
            [sys.executable, "-c", "import stabctl; stabctl.Simulator"],
            env={**os.environ, "NUMBA_DISABLE_JIT": value},
            capture_output=True,
            text=True,
            timeout=300,
        )

    off = simulator_with("1")
    assert off.returncode == 1
    assert "ImportError: NUMBA_DISABLE_JIT='1' in the environment" in off.stderr
    on = simulator_with("0")
    assert on.returncode == 0, on.stderr


def test_compile_check_names_the_cache_numba_really_uses(tmp_path):
    """A NUMBA_CACHE_DIR numba cannot write into (here immutable) is passed over by numba,
    which caches the kernels in the package's __pycache__ instead: `compile --check` says
    so, not that the kernels are cached in NUMBA_CACHE_DIR."""
    import shutil

    cache = tmp_path / "cache"
    cache.mkdir()
    chattr = shutil.which("chattr")
    if chattr is None or subprocess.run([chattr, "+i", str(cache)], capture_output=True).returncode:
        if os.access(cache, os.W_OK) and (cache.chmod(0o500) or os.access(cache, os.W_OK)):
            pytest.skip("no way to make a directory this user cannot write into")
        chattr = None
    try:
        check = _stabctl("compile", "--check", cache=cache)
    finally:
        if chattr is not None:
            subprocess.run([chattr, "-i", str(cache)], check=True)
        cache.chmod(0o700)
    assert check.returncode in (0, 1), check.stdout + check.stderr
    assert check.stdout.splitlines()[-1].endswith("(the package's __pycache__ directories)")
    assert list(cache.iterdir()) == []


@pytest.mark.parametrize("args", [["--check", "nocase"], ["kundur", "nocase"]])
def test_compile_names_an_unknown_case_before_anything(monkeypatch, args):
    """`compile --check nocase` reported the cache and exited 0, the case passed over;
    every case named is read first, so an unknown one is one error line naming it (as
    other commands do, exit 2), before any check or compiling."""
    from click.testing import CliRunner

    from stabctl.cli import compile as compile_cli
    from stabctl.cli import main

    def refuse(*a, **k):
        raise AssertionError("checked or compiled before the cases were read")

    monkeypatch.setattr(compile_cli, "_check", refuse)
    monkeypatch.setattr(compile_cli, "_warm_steps", refuse)
    res = CliRunner().invoke(main, ["compile", *args])
    assert res.exit_code == 2, (res.output, res.exception)
    assert res.stderr == "error: unknown case 'nocase': built-ins are kundur, miniwecc\n"
    assert res.stdout == ""
