"""The package's layers (pyproject.toml [tool.importlinter]) hold: a layer imports only
the layers below it, and ``import stabctl`` has no side effects."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_import_linter_contract_is_kept():
    exe = shutil.which("lint-imports") or str(Path(sys.executable).with_name("lint-imports"))
    if not Path(exe).exists():
        pytest.skip("import-linter not installed (the test extra installs it)")
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    res = subprocess.run(
        [exe, "--config", str(ROOT / "pyproject.toml")],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
    )
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-2000:]
    assert "1 kept, 0 broken" in res.stdout


def test_import_stabctl_leaves_environment_and_files_alone(tmp_path):
    """``import stabctl`` sets no environment variable, imports no numerics and compiles
    nothing (the public names load on first use)."""
    code = (
        "import os, sys, json; before = dict(os.environ); import stabctl; "
        "print(json.dumps([dict(os.environ) == before, 'numpy' in sys.modules, "
        "'numba' in sys.modules, sorted(stabctl.__all__)]))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=tmp_path
    ).stdout
    same_env, numpy_loaded, numba_loaded, names = json.loads(out)
    assert same_env and not numpy_loaded and not numba_loaded
    assert {"Simulator", "load_case", "critical_clearing_time", "linearise"} <= set(names)


def test_at_most_eight_top_level_modules():
    modules = sorted(p.name for p in (ROOT / "stabctl").glob("*.py"))
    assert len(modules) <= 8, modules


def test_compile_notice_once_and_only_when_a_stabctl_kernel_compiles():
    """`on_first_compile` (the CLI's one-line compile notice): called once, when the first
    stabctl kernel compiles; compiling code of other packages does not count."""
    import numba

    from stabctl._jit.notify import on_first_compile

    def kernel(x):
        return x + 1

    def other(x):
        return x - 1

    kernel.__module__ = "stabctl.kernel_for_the_test"
    calls = []
    on_first_compile(lambda: calls.append(1))
    assert numba.njit(other)(1) == 0 and calls == []  # not stabctl
    assert numba.njit(kernel)(1) == 2 and calls == [1]
    assert numba.njit(kernel)(2.0) == 3.0 and calls == [1]  # once only
    stop = on_first_compile(lambda: calls.append(2))
    stop()  # the command ended
    assert numba.njit(kernel)(3j) == 1 + 3j and calls == [1]


def test_a_long_compile_is_announced_again_while_it_lasts():
    """`on_first_compile(still=...)`: while compiling lasts, `still` hears the seconds
    since the notice at every interval; nothing once the compile is over; a later compile
    goes on counting from the first ("10 s" then "6 s" read as a count going backwards)."""
    import time

    import numba

    from stabctl._jit.notify import on_first_compile

    def slow(x):
        return x + 1

    slow.__module__ = "stabctl.kernel_for_the_test"
    heard = []
    kernels = set()

    def still(seconds, kernel, kernel_s):
        heard.append(seconds)
        kernels.add(kernel)
        assert 0 <= kernel_s <= seconds + 1e-9

    stop = on_first_compile(lambda: None, still=still, every_s=0.05)
    from numba.core import event

    real_start = event.start_event

    def stretched(kind, data=None):  # make each compile take 0.3 s
        real_start(kind, data)
        if kind == "numba:compile":
            time.sleep(0.3)

    event.start_event = stretched
    try:
        numba.njit(slow)(1)
    finally:
        event.start_event = real_start
    time.sleep(0.2)
    n = len(heard)
    time.sleep(0.6)
    assert n >= 2 and heard == sorted(heard) and heard[0] >= 0.05
    assert len(heard) == n  # quiet once compiling is over
    before = heard[-1]
    event.start_event = stretched  # a later compile: the count goes on, never back
    try:
        numba.njit(slow)(2.0)
    finally:
        event.start_event = real_start
    stop()
    assert len(heard) > n and heard == sorted(heard) and heard[n] > before + 0.5
    assert kernels == {"slow"}  # the function compiling named


def test_a_long_compile_says_what_compiles_and_its_time_left():
    """Round 57 AV: a cold `stabctl compile` said "stabctl: still compiling (N s)" every
    10 s for 108 s, no fraction or time left.  The line names the kernel compiling and,
    by the seconds it took on the reference machine, its share and the time left, or
    that it is past them."""
    from stabctl._jit.notify import REFERENCE_S, still_line

    ref = REFERENCE_S["evaluate_kernel"][1]
    assert still_line(42.4, "evaluate_kernel", 30.0) == (
        f"stabctl: still compiling (42 s): the model's evaluation, 30 s of about {ref:.0f} s "
        f"on the 2-core reference machine ({30 / ref:.0%}), about {ref - 30:.0f} s left"
    )
    assert "past the" in still_line(200, "evaluate_kernel", ref + 5)
    assert still_line(12, "_other", 3) == "stabctl: still compiling (12 s): _other, 3 s"


def test_model_files_stay_small_and_read_states_by_name():
    """The model library's two rules: no file in stabctl/models over 800 lines, and no
    kernel reading a state slot by its number (``x[2, k]``): states are read by name
    (``x[S.eqp, i]``, `stabctl.models.declaration.states`)."""
    import re

    literal = re.compile(r"\bd?x\[\d+, *[a-z_]\w*\]")
    long, literal_reads = [], []
    for path in sorted((ROOT / "stabctl" / "models").rglob("*.py")):
        lines = path.read_text().splitlines()
        if len(lines) > 800:
            long.append(f"{path.relative_to(ROOT)}: {len(lines)} lines")
        literal_reads += [
            f"{path.relative_to(ROOT)}:{n}"
            for n, line in enumerate(lines, 1)
            if literal.search(line)
        ]
    assert long == [] and literal_reads == []
