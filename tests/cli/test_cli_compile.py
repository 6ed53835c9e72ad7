"""`stabctl compile`: on an empty cache it compiles every part and exits 0; `--check` says
cold (exit 1) before and warm (exit 0) after, compiling nothing; a second call loads all."""

import os
import subprocess
import sys

PARTS = ("model evaluation", "filters", "linearisation", "integrator")


def _stabctl(*args, cache):
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
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


def test_compile_warms_an_empty_cache_and_check_reports_it(tmp_path):
    cold = _stabctl("compile", "--check", cache=tmp_path)
    assert cold.returncode == 1, cold.stdout + cold.stderr
    assert "kernel cache cold" in cold.stdout and "not cached" in cold.stdout
    assert not list(tmp_path.rglob("*.nbi"))  # --check compiles nothing

    first = _stabctl("compile", "kundur", cache=tmp_path)
    assert first.returncode == 0, first.stdout + first.stderr
    assert _parts(first.stdout) == dict.fromkeys(PARTS, "compiled"), first.stdout
    assert "kernel cache warm" in first.stdout

    warm = _stabctl("compile", "--check", cache=tmp_path)
    assert warm.returncode == 0, warm.stdout + warm.stderr
    assert "not cached" not in warm.stdout and "kernel cache warm" in warm.stdout

    again = _stabctl("compile", "kundur", cache=tmp_path)
    assert again.returncode == 0, again.stdout + again.stderr
    assert _parts(again.stdout) == dict.fromkeys(PARTS, "loaded"), again.stdout
