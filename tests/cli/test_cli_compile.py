"""`stabctl compile`: on an empty cache it compiles every part and exits 0; `--check` says
cold (exit 1) before and warm (exit 0) after, compiling nothing; a second call loads all.

The cold compile is also where no kernel may compile numba's slice-assignment message (the
point of `stabctl._jit.arrays.assign`: numba's shape-mismatch formatter costs 2-3 s of a
cold first call): a ``sitecustomize`` on the commands' PYTHONPATH watches numba's
``fancy_setslice`` in every process, the integrator's compile child included (one cold
compile serves both checks; each costs a minute or two of a core)."""

import os
import subprocess
import sys

import pytest

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


def _stabctl(*args, cache, spy=None):
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    if spy is not None:
        spy.mkdir(exist_ok=True)
        (spy / "sitecustomize.py").write_text(_SPY)
        path = os.pathsep.join(filter(None, (str(spy), env.get("PYTHONPATH"))))
        env.update(PYTHONPATH=path, STABCTL_TEST_SETSLICE=str(spy / "seen.txt"))
    return subprocess.run(
        [sys.executable, "-m", "stabctl.cli", *args],
        env=env,
        capture_output=True,
        text=True,
        timeout=900,
    )


def _parts(stdout: str) -> dict[str, str]:
    """Part -> 'compiled' or 'loaded', from the per-part lines of kundur."""
    return {
        p: line.split()[len(p.split()) + 1]
        for line in stdout.splitlines()
        for p in PARTS
        if line.startswith("kundur") and p in line
    }


@pytest.mark.heavy
def test_compile_warms_an_empty_cache_without_numbas_slice_message_and_check_says_so(tmp_path):
    cache = tmp_path / "cache"
    cold = _stabctl("compile", "--check", cache=cache)
    assert cold.returncode == 1, cold.stdout + cold.stderr
    assert "kernel cache cold" in cold.stdout and "not cached" in cold.stdout
    assert not list(tmp_path.rglob("*.nbi"))  # --check compiles nothing

    spy = tmp_path / "spy"
    first = _stabctl("compile", "kundur", cache=cache, spy=spy)
    assert first.returncode == 0, first.stdout + first.stderr
    assert _parts(first.stdout) == dict.fromkeys(PARTS, "compiled"), first.stdout
    # the watch ran in the command and in its integrator's compile child ...
    assert len(set((spy / "seen.txt.pids").read_text().split())) >= 2
    # ... and no kernel compiled numba's slice-assignment message
    seen = (spy / "seen.txt").read_text().split() if (spy / "seen.txt").exists() else []
    assert seen == [], seen
    assert "kernel cache warm" in first.stdout

    warm = _stabctl("compile", "--check", cache=cache)
    assert warm.returncode == 0, warm.stdout + warm.stderr
    assert "not cached" not in warm.stdout and "kernel cache warm" in warm.stdout

    again = _stabctl("compile", "kundur", cache=cache)
    assert again.returncode == 0, again.stdout + again.stderr
    assert _parts(again.stdout) == dict.fromkeys(PARTS, "loaded"), again.stdout
