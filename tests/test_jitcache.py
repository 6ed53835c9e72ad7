"""Where stabctl's compiled kernels are cached, and that a source change clears them."""

import inspect

import numba
from numba.core.caching import InTreeCacheLocator, UserProvidedCacheLocator

from stabctl import _jitcache
from stabctl.storage import control


def _numba_dir(locator):
    f = control.desired_mode.py_func
    return locator.from_function(f, inspect.getfile(f)).get_cache_path()


def test_cache_dirs_are_where_numba_puts_the_kernels(tmp_path, monkeypatch):
    assert _numba_dir(InTreeCacheLocator) in map(str, _jitcache.cache_dirs())
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path))
    assert _numba_dir(UserProvidedCacheLocator) in map(str, _jitcache.cache_dirs())


def test_a_source_change_clears_the_kernels_under_numba_cache_dir(tmp_path, monkeypatch):
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path))
    kernels = _jitcache.cache_dirs()[3]
    kernels.mkdir(parents=True)
    (kernels / "f-1.py311.nbi").write_text("stale")
    stamp = _jitcache.cache_dirs()[0] / "numba-sources.sha256"
    stamp.parent.mkdir(parents=True, exist_ok=True)
    stamp.write_text("a digest of other sources")
    _jitcache.ensure_fresh_cache()
    assert not (kernels / "f-1.py311.nbi").exists()
    assert stamp.read_text() == _jitcache.source_digest()
    (kernels / "f-1.py311.nbi").write_text("fresh")
    _jitcache.ensure_fresh_cache()                      # same sources: kept
    assert (kernels / "f-1.py311.nbi").exists()


def test_simulator_cached_reads_numbas_own_index_of_the_integrator():
    # the parent of a sweep compiles the simulator (`compile_here`) so that its workers load
    # it: afterwards the index numba wrote for `integrate` is the one `simulator_cached` finds
    from pathlib import Path

    from stabctl.dynamics.simulation import integrate
    from stabctl.stability.cct import compile_here

    cache = integrate._cache
    assert Path(cache._cache_path) in _jitcache.cache_dirs()
    compile_here("kundur")
    assert (Path(cache._cache_path) / cache._cache_file._index_name).exists()
    assert _jitcache.simulator_cached()
