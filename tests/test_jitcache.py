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
