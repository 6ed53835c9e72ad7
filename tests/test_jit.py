"""Where stabctl's compiled kernels are cached, that a change of a kernel source clears
them, and how they compile (`stabctl._jit`)."""

import inspect
import os
from pathlib import Path

import numba
import pytest
from numba.core.caching import InTreeCacheLocator, UserProvidedCacheLocator

from stabctl._jit import cache as jc
from stabctl.storage import control


def _numba_dir(locator):
    f = control.desired_mode.py_func
    return locator.from_function(f, inspect.getfile(f)).get_cache_path()


def test_cache_dirs_are_where_numba_puts_the_kernels(tmp_path, monkeypatch):
    """In the package's __pycache__ without NUMBA_CACHE_DIR (whatever the environment
    running the tests sets), under NUMBA_CACHE_DIR with it."""
    monkeypatch.setattr(numba.config, "CACHE_DIR", "")
    assert _numba_dir(InTreeCacheLocator) in map(str, jc.cache_dirs())
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path))
    assert _numba_dir(UserProvidedCacheLocator) in map(str, jc.cache_dirs())


def test_a_source_change_clears_the_kernels_under_numba_cache_dir(tmp_path, monkeypatch):
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path))
    kernels = jc.cache_dirs()[3]
    kernels.mkdir(parents=True)
    (kernels / "f-1.py311.nbi").write_text("stale")
    stamp = jc.cache_dirs()[0] / "numba-sources.sha256"
    stamp.parent.mkdir(parents=True, exist_ok=True)
    stamp.write_text("a digest of other sources")
    jc.ensure_fresh_cache()
    assert not (kernels / "f-1.py311.nbi").exists()
    assert stamp.read_text() == "a digest of other sources"  # written with the first kernel
    jc.stamp_cache()
    assert stamp.read_text() == jc.source_digest()
    (kernels / "f-1.py311.nbi").write_text("fresh")
    jc.ensure_fresh_cache()  # same sources: kept
    assert (kernels / "f-1.py311.nbi").exists()


def test_a_stamp_that_is_no_regular_file_is_out_of_date_and_never_waited_on(tmp_path, monkeypatch):
    """A FIFO (a plain read of it waits for a writer for ever) or an
    oversized file where the cache key belongs: read as stale (the kernels cleared, as
    for a changed source), and replaced by a regular file with the first kernel."""
    import os
    import threading

    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path))
    stamp = jc.cache_dirs()[0] / "numba-sources.sha256"
    stamp.parent.mkdir(parents=True, exist_ok=True)
    kernels = jc.cache_dirs()[3]
    kernels.mkdir(parents=True, exist_ok=True)
    for plant in (lambda: os.mkfifo(stamp), lambda: stamp.write_text("0" * 100_000)):
        (kernels / "f-1.py311.nbi").write_text("stale")
        plant()
        done = threading.Thread(target=jc.ensure_fresh_cache, daemon=True)
        done.start()
        done.join(20)
        assert not done.is_alive(), "ensure_fresh_cache waits on the stamp"
        assert not (kernels / "f-1.py311.nbi").exists()
        writer = threading.Thread(target=jc.stamp_cache, daemon=True)
        writer.start()
        writer.join(20)
        assert not writer.is_alive(), "stamp_cache waits on the stamp"
        assert stamp.is_file() and stamp.read_text() == jc.source_digest()
        stamp.unlink()


def test_the_cache_key_hashes_the_kernel_sources_only(tmp_path):
    # the modules declaring kernels and what they import; not the CLI, the driver, reports
    import shutil

    pkg = tmp_path / "stabctl"
    shutil.copytree(jc._PKG, pkg, ignore=shutil.ignore_patterns("__pycache__"))
    names = {str(f.relative_to(pkg)) for f in jc.kernel_sources(pkg)}
    assert {
        "_jit/arrays.py",
        "_jit/decorators.py",
        "dynamics/integrator.py",
        "dynamics/switching.py",
        "dynamics/model.py",
        "storage/control.py",
        "network/solution.py",
        "models/machines.py",
        "models/blocks.py",
        "models/exciters/__init__.py",
        "models/exciters/table.py",
        "models/exciters/ac8b.py",
        "models/exciters/dc.py",
        "models/governors/__init__.py",
        "models/governors/table.py",
        *(f"models/governors/{t}.py" for t in ("tg", "tgov1", "ieeeg1", "hygov", "ieesgo")),
        *(f"models/governors/{t}.py" for t in ("gast", "tg2", "hygov4")),
        "models/pss/__init__.py",
        "models/pss/table.py",
        *(f"models/pss/{t}.py" for t in ("pst", "ieeest", "stab2a", "pss2a", "pss2c")),
        "errors.py",
    } <= names
    assert not names & {
        "cli/simulate.py",
        "dynamics/driver.py",
        "dynamics/grid.py",
        "_jit/cache.py",
        "_jit/notify.py",
    }
    assert not any(n.startswith(("cli/", "placement/", "plotting/")) for n in names)

    def edited(path, old, new):
        f = pkg / path
        f.write_text(f.read_text().replace(old, new, 1))
        return jc.source_digest(pkg)

    key = jc.source_digest(pkg)
    assert edited("cli/simulate.py", "Nonlinear", "Non-linear") == key  # a help string
    assert edited("dynamics/driver.py", "class Simulator", "class Simulator ") == key
    assert edited("errors.py", '"""', '""" ') != key  # imported by kernels
    key = jc.source_digest(pkg)
    assert (
        edited(
            "dynamics/integrator.py",
            "SPEED_BAND, EST_TOL, EST_STEPS = 0.5",
            "SPEED_BAND, EST_TOL, EST_STEPS = 0.4",
        )
        != key
    )
    key = jc.source_digest(pkg)
    assert edited("cli/simulate.py", "\n\n\n", "\n\n\n@kernel\ndef f():\n    pass\n\n\n") != key
    assert "cli/simulate.py" in {str(f.relative_to(pkg)) for f in jc.kernel_sources(pkg)}


def test_simulator_cached_reads_numbas_own_index_of_the_integrator():
    # the parent of a sweep compiles the simulator (`compile_here`) so that its workers load
    # it: afterwards the index numba wrote for `integrate` is the one `simulator_cached` finds
    from pathlib import Path

    from stabctl.dynamics.driver import simulator_cached
    from stabctl.dynamics.integrator import integrate
    from stabctl.stability.cct import compile_here

    cache = integrate._cache
    assert Path(cache._cache_path) in jc.cache_dirs()
    compile_here("kundur")
    assert (Path(cache._cache_path) / cache._cache_file._index_name).exists()
    assert simulator_cached()


def test_a_kernel_for_compiled_callers_answers_python_through_a_trampoline():
    # `kernel` drops the CPython wrapper; a Python call goes through a compiled trampoline
    # (a direct call would jump into missing code) and gives the kernel's value
    import numpy as np

    from stabctl.storage.control import coi_value

    assert coi_value(np.array([1.0, 3.0]), np.array([1.0, 3.0])) == pytest.approx(2.5)
    with pytest.raises(TypeError, match="keyword"):
        coi_value(np.ones(1), inertia=np.ones(1))


def test_the_probe_types_are_those_of_runs_with_storage_and_commands():
    # the child process compiles `integrate` for `run_argument_types`; a run with storage or
    # an estimator's commands must call that same compiled version, not compile another
    import numpy as np
    from numba import typeof

    from stabctl.dynamics.driver import Simulator, _Run
    from stabctl.dynamics.grid import time_grid
    from stabctl.dynamics.model import StageConfig
    from stabctl.io import load_case
    from stabctl.stability.cct import storage_fleet
    from stabctl.storage import devices

    sim = Simulator(load_case("kundur"), background_compile=False)
    fleet = storage_fleet(sim.case, 5.0)
    m = sim.model_for(fleet.buses)
    sa = devices.pack(fleet, sim.case, m.nc_idx)
    for n_commands in (0, 3):
        nets = [m.network(StageConfig()), m.network(StageConfig(faults=((2, 1e7j),)))]
        run = _Run(
            sim,
            m,
            sa,
            time_grid([0.0, 1.0], 2.0, sim.default_h),
            nets,
            True,
            np.pi,
            True,
            n_commands=n_commands,
        )
        assert [typeof(a) for a in run.arguments(5)] == sim.run_argument_types()


def test_assign_writes_views_as_numpys_slice_assignment_does():
    # `assign` stands for dst[...] = src in kernels: rows, column blocks, 1-D tails
    import numpy as np

    from stabctl._jit.arrays import assign
    from stabctl.estimation.filters import _store

    rng = np.random.default_rng(1)
    x, P = rng.normal(size=(3, 5)), rng.normal(size=(3, 5, 5))
    xk, Pk = rng.normal(size=5), rng.normal(size=(5, 5))
    want_x, want_P = x.copy(), P.copy()
    want_x[1], want_P[1] = xk, Pk
    _store(x, P, 1, xk, Pk)
    assert np.array_equal(x, want_x) and np.array_equal(P, want_P)
    F, A = np.zeros((5, 5)), rng.normal(size=(2, 2))
    assign(F[3:, 3:], A)  # a block that is not contiguous
    want = np.zeros((5, 5))
    want[3:, 3:] = A
    assert np.array_equal(F, want)


def test_matvec_and_dot_are_the_products_on_both_sides_of_the_blas_threshold():
    # the loop (small matrices: Kundur's reduced network) and BLAS (miniWECC's Y11, R)
    import numpy as np

    from stabctl._jit.arrays import SMALL_MATVEC, dot, matvec

    rng = np.random.default_rng(2)
    small = int(np.sqrt(SMALL_MATVEC))
    for m, n in ((1, 1), (2, 2), (13, 6), (small, small), (small + 1, small), (40, 7)):
        A = rng.normal(size=(m, n)) + 1j * rng.normal(size=(m, n))
        x = rng.normal(size=n) + 1j * rng.normal(size=n)
        out = np.full(m, np.nan, complex)
        matvec(A, x, out)
        assert np.allclose(out, A @ x, rtol=1e-14, atol=1e-14 * n), (m, n)
    out = np.full(3, np.nan, complex)
    matvec(np.zeros((3, 0), complex), np.zeros(0, complex), out)  # no kept bus
    assert np.array_equal(out, np.zeros(3))
    for n in (1, 13, SMALL_MATVEC, SMALL_MATVEC + 1, 400):  # a machine's row of R
        a = rng.normal(size=n) + 1j * rng.normal(size=n)
        b = rng.normal(size=n) + 1j * rng.normal(size=n)
        assert abs(dot(a, b) - a @ b) < 1e-13 * n, n


def test_a_kernel_called_by_address_returns_raises_and_checks_its_types():
    # `by_address`: the callee's value and exceptions come through; an argument of
    # another type than the address was compiled for is refused when typing the caller
    import numba
    import numpy as np
    from numba import typeof, types

    from stabctl._jit.address import address_of, by_address

    @numba.njit
    def callee(x, k, flag):
        x[0] += k
        if flag:
            raise ValueError("boom")
        return k + 1

    vector = typeof(np.zeros(2))
    call = by_address("call_callee", ("x", "k", "flag"), lambda: (vector, None, types.boolean))

    @numba.njit
    def caller(address, x, k, flag):
        return call(address, x, k, flag)

    address = address_of(callee, (vector, types.int64, types.boolean))
    x = np.zeros(2)
    assert caller(address, x, 2, np.bool_(False)) == 3 and x[0] == 2.0
    with pytest.raises(ValueError, match="boom"):
        caller(address, x, 2, np.bool_(True))
    with pytest.raises(numba.core.errors.TypingError, match="x must be"):
        caller(address, np.zeros(2, np.int64), 2, np.bool_(False))


def _fresh_process(code: str, cache_dir, **env):
    import os
    import subprocess
    import sys

    return subprocess.run(
        [sys.executable, "-c", code],
        env={**os.environ, "NUMBA_CACHE_DIR": str(cache_dir), **env},
        capture_output=True,
        text=True,
        timeout=600,
    )


_LOAD = (
    "from stabctl.models.blocks import rectifier_loading as f\nprint(f(0.5), f.stats.cache_hits)\n"
)


def test_a_cache_that_cannot_be_written_compiles_in_memory_with_one_warning(tmp_path):
    """Round 38: a cache on a full disk (here ``ulimit -f 1``: EFBIG as ENOSPC) failed
    every command that compiled a kernel ("error: File too large", a traceback from the
    API).  The kernel now runs, compiled for this process only, with one warning naming
    the cache and why; nothing of it is saved."""
    import os
    import resource
    import subprocess
    import sys

    from stabctl.models.blocks import rectifier_loading

    code = _LOAD + "from stabctl.models.blocks import clip\nprint(clip(2.0, 0.0, 1.0))\n"
    child = subprocess.run(
        [sys.executable, "-W", "default", "-c", code],
        env={**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)},
        capture_output=True,
        text=True,
        timeout=600,
        preexec_fn=lambda: resource.setrlimit(resource.RLIMIT_FSIZE, (1, 1)),
    )
    assert child.returncode == 0, child.stderr
    out = child.stdout.split()
    assert float(out[0]) == rectifier_loading(0.5) and out[-1] == "1.0"  # two kernels
    said = [line for line in child.stderr.splitlines() if "numba cache:" in line]
    assert len(said) == 1 and "cannot be written (File too large): kernels are compiled" in said[0]
    assert not list(tmp_path.rglob("*.nbi")) and not list(tmp_path.rglob("*.nbc"))


def test_a_damaged_cache_entry_is_compiled_again(tmp_path):
    """A kernel's cache index truncated or garbage (the finding: `simulate` died with an
    UnpicklingError): the next process compiles the kernel again and answers."""
    first = _fresh_process(_LOAD, tmp_path)
    assert first.returncode == 0, first.stderr
    index = next(tmp_path.rglob("blocks.rectifier_loading-*.nbi"))
    assert _fresh_process(_LOAD, tmp_path).stdout.split()[1] != "Counter()"  # a cache hit
    for damage in (index.read_bytes()[:10], b"garbage, not a pickle"):
        index.write_bytes(damage)
        again = _fresh_process(_LOAD, tmp_path)
        assert again.returncode == 0, again.stderr
        assert again.stdout.split()[0] == first.stdout.split()[0]  # sqrt(0.75 - 0.25)


def test_a_directory_in_place_of_a_cache_entry_is_compiled_around(tmp_path):
    """A directory where a kernel's index belongs (the finding: the command stopped with
    "Is a directory", exit 2): it is not loaded, never removed, the kernel compiled for
    the process and not saved, a warning naming the entry."""
    first = _fresh_process(_LOAD, tmp_path)
    assert first.returncode == 0, first.stderr
    index = next(tmp_path.rglob("blocks.rectifier_loading-*.nbi"))
    index.unlink()
    (index / "kept").mkdir(parents=True)
    again = _fresh_process(_LOAD, tmp_path)
    assert again.returncode == 0, again.stderr
    assert again.stdout.split()[0] == first.stdout.split()[0]  # sqrt(0.75 - 0.25)
    assert f"numba cache: {index} is not a regular file; not loaded" in again.stderr
    assert f"numba cache: {index} cannot be replaced (Is a directory)" in again.stderr
    assert (index / "kept").is_dir()


class _Planted:
    """A pickle that makes the directory `path` when it is unpickled."""

    def __init__(self, path):
        self.path = str(path)

    def __reduce__(self):
        import os

        return os.mkdir, (self.path,)


def _plant(path, planted):
    """Write into `path` an index numba would unpickle to the end: its version, then the
    `_Planted` pickle making `planted`."""
    import pickle

    path.write_bytes(pickle.dumps(numba.__version__) + pickle.dumps(_Planted(planted)))


@pytest.mark.parametrize("unsafe", ["index 666", "index of nobody", "index link", "data 666"])
def test_a_cache_file_others_may_write_is_never_unpickled(tmp_path, unsafe):
    """A kernel's index or data file writable by others, owned by another user or a link
    (the finding: user nobody wrote a pickle into a chmod 666 index inside root's 0755
    cache directory, and root's next `simulate` ran it): not unpickled; a warning names
    the file and why, the entry is compiled again and rewritten writable by its owner
    only, and the next process loads it."""
    import os

    cache = tmp_path / "cache"
    first = _fresh_process(_LOAD, cache)
    assert first.returncode == 0, first.stderr
    index = next(cache.rglob("blocks.rectifier_loading-*.nbi"))
    [data] = index.parent.glob(index.stem + ".*.nbc")
    planted = tmp_path / "planted"
    target, why = index, "is writable by others than its owner"
    if unsafe == "data 666":
        target = data
        data.write_bytes(__import__("pickle").dumps(_Planted(planted)))
        data.chmod(0o666)
    elif unsafe == "index link":
        elsewhere = tmp_path / "elsewhere.nbi"
        _plant(elsewhere, planted)
        index.unlink()
        index.symlink_to(elsewhere)
        why = "is not a regular file"
    else:
        _plant(index, planted)
        if unsafe == "index 666":
            index.chmod(0o666)
        else:
            if os.geteuid() != 0:
                pytest.skip("giving a file to another user takes root")
            os.chown(index, 65534, 65534)
            why = "belongs to user 65534"
    again = _fresh_process(_LOAD, cache)
    assert again.returncode == 0, again.stderr
    assert not planted.exists()
    assert f"numba cache: {target} {why}; not loaded" in again.stderr
    assert again.stdout.split()[0] == first.stdout.split()[0]
    assert again.stdout.split()[1] == "Counter()"  # compiled, not loaded
    for f in (index, data):
        st = f.lstat()
        assert f.is_file() and not f.is_symlink() and not st.st_mode & 0o022, oct(st.st_mode)
        assert st.st_uid == os.geteuid()
    last = _fresh_process(_LOAD, cache)
    assert last.stdout.split()[1] != "Counter()" and "numba cache" not in last.stderr


def test_kernels_make_their_cache_directories_only_when_compiled(tmp_path):
    """A process that declares kernels but compiles none makes nothing in an empty
    NUMBA_CACHE_DIR (the finding: numba made each kernel's directory as it was declared,
    13 of them for `stabctl compile --check`, and stabctl wrote its cache key); the first
    kernel compiled makes its directory and the key, and the next process loads it."""
    cache = tmp_path / "cache"
    cache.mkdir()
    declared = _fresh_process("import stabctl.dynamics.integrator, stabctl.models.blocks", cache)
    assert declared.returncode == 0, declared.stderr
    assert list(cache.iterdir()) == []
    first = _fresh_process(_LOAD, cache)
    assert first.returncode == 0, first.stderr
    assert len(list(cache.rglob("blocks.rectifier_loading-*.nbi"))) == 1
    assert len(list(cache.rglob("numba-sources.sha256"))) == 1
    assert _fresh_process(_LOAD, cache).stdout.split()[1] != "Counter()"  # a cache hit


def test_a_cache_others_may_write_into_is_not_used(tmp_path):
    """NUMBA_CACHE_DIR writable by everyone (the finding: a pickle planted there ran in
    every stabctl process): not used; the kernels go to this user's own directory (mode
    0700) with a warning naming why, when a kernel is first loaded or saved (at import it
    came before the CLI reads warnings, as Python's raw text with a source line: the CLI
    test of it is `tests/cli/test_bad_input.py`); a directory of this user's alone is
    used."""
    shared = tmp_path / "shared"
    shared.mkdir(mode=0o777)
    shared.chmod(0o777)
    home = tmp_path / "home"
    code = (
        "import warnings\n"
        "warnings.simplefilter('always')\n"
        "import numba\n"
        "import stabctl.models.blocks\n"
        "print(numba.config.CACHE_DIR)\n"
    )
    run = _fresh_process(code, shared, XDG_CACHE_HOME=str(home))
    assert run.returncode == 0, run.stderr
    assert "numba cache" not in run.stderr  # no kernel used: nothing to say
    run = _fresh_process(code + _LOAD, shared, XDG_CACHE_HOME=str(home))
    assert run.returncode == 0, run.stderr
    said = f"numba cache: {shared} is writable by others than its owner"
    assert run.stderr.count(said) == 1
    check = "from stabctl._jit.cache import cached\nfrom stabctl.models import blocks\n"
    read = _fresh_process(code + check + "cached(blocks.rectifier_loading)\n", shared)
    assert read.stderr.count(said) == 1  # `compile --check` reads the cache: said there too
    assert run.stdout.split()[0] == str(home / "stabctl-numba")
    assert (home / "stabctl-numba").stat().st_mode & 0o777 == 0o700
    assert not list(shared.iterdir())
    shared.chmod(0o700)
    run = _fresh_process(code, shared, XDG_CACHE_HOME=str(home))
    assert run.stdout.strip() == str(shared) and "numba cache" not in run.stderr


def test_an_unsafe_cache_with_no_private_one_possible_caches_for_the_run(tmp_path):
    """Round 32: NUMBA_CACHE_DIR writable by others and a private cache that cannot be made
    (XDG_CACHE_HOME a file; a read-only home alike): every command, `--version`
    included, failed at import with a traceback.  The kernels are now cached for the run
    in a directory of its own, removed at exit, and the warning says so."""
    shared = tmp_path / "shared"
    shared.mkdir(mode=0o777)
    shared.chmod(0o777)
    afile = tmp_path / "afile"
    afile.write_text("")
    code = "import warnings\nwarnings.simplefilter('always')\nimport numba\n" + _LOAD
    code += "print(numba.config.CACHE_DIR)\n"
    run = _fresh_process(code, shared, XDG_CACHE_HOME=str(afile))
    assert run.returncode == 0, run.stderr
    assert f"numba cache: {shared} is writable by others than its owner" in run.stderr
    assert f"({afile / 'stabctl-numba'} cannot be made: Not a directory; for this run" in (
        run.stderr
    )
    used = Path(run.stdout.split()[-1])
    assert used.name.startswith("stabctl-numba.") and not used.exists()  # removed at exit
    assert not list(shared.iterdir())


def test_cache_directories_are_made_private_whatever_the_umask(tmp_path):
    """Round 30: under umask 000 the first run made NUMBA_CACHE_DIR and its kernels'
    directories 0777; the next run found them writable by others, moved the cache away
    and compiled everything again.  A directory that exists keeps its mode."""
    kept = tmp_path / "kept"
    kept.mkdir(mode=0o755)
    os.chmod(kept, 0o755)
    old = os.umask(0)
    try:
        jc.make_private_dirs(kept / "nb" / "dynamics_0a1b")
    finally:
        os.umask(old)
    modes = [
        oct(p.stat().st_mode & 0o777) for p in (kept, kept / "nb", kept / "nb" / "dynamics_0a1b")
    ]
    assert modes == ["0o755", "0o700", "0o700"]
    assert jc.unsafe_reason(kept / "nb") == ""


def test_a_compiling_child_dies_with_its_parent():
    """A background compile's child started by a parent that is then SIGKILLed (the
    finding: the child outlived it): the kernel kills the child with its parent (prctl
    PR_SET_PDEATHSIG); here a child whose parent is already gone exits at once."""
    import subprocess
    import sys

    child = subprocess.run(
        [sys.executable, "-m", "stabctl._jit.background", "x", "y", "1"],
        input=b"",
        capture_output=True,
        timeout=60,
    )
    assert child.returncode == 1 and child.stderr == b""  # told its parent is pid 1: gone


def test_the_cache_check_takes_no_fifo_device_or_damaged_overload_for_an_entry(tmp_path):
    """`compile --check` called a cache warm whose entry of a loaded kernel had one data
    file damaged (another overload's whole), a FIFO for an index (whose read blocks) or
    a device (whose read never ends): each is no entry; nothing is unpickled."""
    import pickle

    from stabctl._jit.cache import _whole_data, _whole_pickles

    whole, cut = tmp_path / "a.1.nbc", tmp_path / "a.2.nbc"
    whole.write_bytes(pickle.dumps((1, 2)))
    cut.write_bytes(pickle.dumps((1, 2))[:-3])
    assert _whole_data([whole]) and not _whole_data([whole, cut]) and not _whole_data([])
    fifo = tmp_path / "a.nbi"
    os.mkfifo(fifo)
    assert not _whole_pickles(fifo, 2)  # returns at once
    assert not _whole_pickles(Path("/dev/zero"), 2)


def test_a_cache_dir_this_process_may_not_write_is_said(tmp_path):
    """A read-only NUMBA_CACHE_DIR (a read-only mount, /proc/self) was passed over by
    numba without a word (the kernels cached elsewhere or compiled in every run): each
    command says it; a writable or unset one says nothing, a file is refused apart."""
    from stabctl._jit.environment import cache_dir_note, environment_problem

    note = cache_dir_note({"NUMBA_CACHE_DIR": "/proc/self/stabctl"})
    assert note.startswith("NUMBA_CACHE_DIR='/proc/self/stabctl' in the environment: this ")
    assert "may not write in /proc/self, so numba does not use it" in note
    assert cache_dir_note({"NUMBA_CACHE_DIR": str(tmp_path / "new")}) == ""
    # a leading blank (round 29): a relative path, the cache under each working directory
    blank = cache_dir_note({"NUMBA_CACHE_DIR": f" {tmp_path}"})
    assert "has blanks around it" in blank and "under the directory each command" in blank
    assert cache_dir_note({}) == ""
    assert cache_dir_note({"NUMBA_CACHE_DIR": "/dev/null"}) == ""  # refused instead:
    assert "is not a directory" in environment_problem({"NUMBA_CACHE_DIR": "/dev/null"})
