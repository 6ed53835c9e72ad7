"""The on-disk cache of stabctl's kernels: where it is, what its key hashes, clearing it.

numba invalidates a cached function only when its own source file changes, not when a
function it inlines or calls from another module does (numba documentation, "Cache
invalidation").  Our kernels call across modules and subpackages, so before the first
kernel is declared (`stabctl._jit.decorators` calls `ensure_fresh_cache`) we hash the
*kernel sources* and delete the cached kernels of the whole package whenever the hash
differs from the one they were compiled with.

The kernel sources (`kernel_sources`) are found by a scan, not listed: every module of the
package that declares a compiled function (a line decorated with `kernel`, `njit`, numba's
``intrinsic`` ...; `KERNEL_DECORATORS`) and every stabctl module those import at module
level (what numba compiles, inlines or freezes as a constant: the kernels they call, the
constants and NamedTuple argument types they read).  Editing any other module (a CLI help
string, a report) keeps the compiled kernels.

Safety: a cached kernel's index is a pickle, so whoever can write into the cache directory
can run code in every process that loads a kernel.  A cache directory (NUMBA_CACHE_DIR, or a
``__pycache__`` of the package) owned by another user than this one or root, or writable
by others than its owner, is not used: the kernels are cached in this user's own
directory instead, with a warning (`ensure_safe_cache`).  So is each file of an entry,
checked (one ``lstat``) just before numba unpickles it: an index (``*.nbi``) or data
(``*.nbc``) file that is not a regular file (a symbolic link), belongs to another user than
this one or root, or is writable by others than its owner (`unsafe_entry_reason`) is never
unpickled: a warning names the file and why, and the entry is deleted and the kernel
compiled again, as a damaged entry (truncated, garbage) is (`GuardedCache`).  The files
stabctl writes are writable by their owner only, whatever the umask.
"""

from __future__ import annotations

import atexit
import contextlib
import errno
import functools
import hashlib
import os
import re
import stat
import warnings
from pathlib import Path
from typing import ClassVar

import numba
from numba.core.caching import CompileResultCacheImpl, FunctionCache, IndexDataCacheFile

from stabctl.locking import temp_dir, unsafe_entry_reason, unsafe_reason

_PKG = Path(__file__).resolve().parents[1]

#: decorators that make numba compile the function below them (`kernel_sources`)
KERNEL_DECORATORS = (
    "kernel",
    "njit",
    "jit",
    "intrinsic",
    "overload",
    "overload_method",
    "register_jitable",
    "cfunc",
    "vectorize",
    "guvectorize",
)
_DECORATOR = re.compile(rf"@(?:[\w.]+\.)?(?:{'|'.join(KERNEL_DECORATORS)})\b")


def _dotted(root: Path, source: Path) -> str:
    """The module name of a source file under the package root (a package's own name for
    its ``__init__.py``)."""
    parts = (root.name, *source.relative_to(root).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _import_statements(text: str):
    """The module-level import statements of a source (those starting at column 0, a
    parenthesised name list joined onto one line): ``(module or "", listed names)`` for
    ``from module import names``, ``("", modules)`` for ``import modules``.  Textual: an
    ``ast.parse`` of the kernel modules took 0.25 s of every process."""
    lines = iter(text.split("\n"))
    for line in lines:
        if not line.startswith(("from ", "import ")):
            continue
        while "(" in line and ")" not in line:
            line += " " + next(lines, ")")
        line = re.sub(r"#.*", "", line).replace("(", " ").replace(")", " ")
        if line.startswith("import "):
            yield "", line[len("import ") :]
        else:
            module, _, listed = line[len("from ") :].partition(" import ")
            yield module.strip(), listed


def _names(listed: str) -> list[str]:
    """The imported names of ``a as x, b``."""
    return [part.split()[0] for part in listed.split(",") if part.strip()]


def _imported_modules(modules: dict[str, Path], name: str, text: str) -> set[Path]:
    """The package's modules (`modules`: source file by module name) that the source
    `text` of module `name` imports at module level (``import stabctl.a``, ``from
    stabctl.a import b``: b's own file when b is a submodule, else a's; relative imports
    resolved in the package of `name`)."""
    package = name.split(".") if modules[name].name == "__init__.py" else name.split(".")[:-1]
    imported: list[str] = []
    for base, listed in _import_statements(text):
        if not base:
            imported += _names(listed)
            continue
        dots = len(base) - len(base.lstrip("."))
        if dots:
            base = ".".join([*package[: len(package) - dots + 1], *filter(None, [base[dots:]])])
        imported += [f"{base}.{n}" if f"{base}.{n}" in modules else base for n in _names(listed)]
    return {modules[n] for n in imported if n in modules}


def _declares_kernels(text: str) -> bool:
    """Whether a source has a line that is a kernel decorator (`KERNEL_DECORATORS`): a
    match with nothing but indentation before it (a regular expression anchored at every
    line of every file took 20 ms)."""
    for hit in _DECORATOR.finditer(text):
        line_start = text.rfind("\n", 0, hit.start()) + 1
        if not text[line_start : hit.start()].strip():
            return True
    return False


def _sources(root: Path) -> tuple[dict[str, Path], dict[str, str]]:
    """Every module of the package: its file and its text, by module name."""
    modules = {_dotted(root, f): f for f in root.rglob("*.py")}
    return modules, {name: f.read_text("utf-8") for name, f in modules.items()}


def declaring_modules(root: Path = _PKG) -> list[str]:
    """Names of the package's modules that declare a kernel (`KERNEL_DECORATORS`).

    Parameters
    ----------
    root : Path
        The package directory (default: stabctl's).

    Returns
    -------
    list of str
        Sorted dotted names, e.g. ``"stabctl.dynamics.integrator"``.
    """
    _, texts = _sources(root)
    return sorted(name for name, text in texts.items() if _declares_kernels(text))


def kernel_sources(root: Path = _PKG) -> list[Path]:
    """The source files whose contents the compiled kernels depend on (module docstring):
    the modules declaring a kernel and the package modules they import at module level.

    Parameters
    ----------
    root : Path
        The package directory (default: stabctl's).

    Returns
    -------
    list of Path
        Sorted, each once.
    """
    modules, texts = _sources(root)
    files = set()
    for name, text in texts.items():
        if _declares_kernels(text):
            files |= {modules[name], *_imported_modules(modules, name, text)}
    return sorted(files)


def _files_digest(root: Path, files: list[Path]) -> str:
    """SHA-256 (hex) over the names (relative to `root`) and contents of `files`."""
    digest = hashlib.sha256()
    for f in files:
        digest.update(str(f.relative_to(root)).encode())
        digest.update(f.read_bytes())
    return digest.hexdigest()


def source_digest(root: Path = _PKG) -> str:
    """SHA-256 over the relative names and contents of the `kernel_sources`: the key of the
    on-disk cache (hex)."""
    return _files_digest(root, kernel_sources(root))


@functools.cache
def package_digest(root: Path = _PKG) -> str:
    """Which stabctl a process runs: SHA-256 over the relative names and contents of the
    package's modules (``*.py``) and the cases shipped with them (``*.json``), taken once
    per process.  A Dask sweep refuses a worker whose digest is not the
    client's (`stabctl.parallel`): an uncommitted edit on one machine, another version.

    Parameters
    ----------
    root : Path
        The package directory (default: stabctl's).

    Returns
    -------
    str
        The digest, hex.
    """
    return _files_digest(root, sorted([*root.rglob("*.py"), *root.rglob("*.json")]))


def cache_dirs() -> list[Path]:
    """The directories numba keeps stabctl's compiled kernels in: each source directory's
    ``__pycache__``, or, when ``NUMBA_CACHE_DIR`` is set, its ``<dir name>_<sha1 of the
    directory path>`` directory there (numba's ``UserProvidedCacheLocator``)."""
    sources = sorted({f.parent for f in _PKG.rglob("*.py")})
    root = numba.config.CACHE_DIR
    if not root:
        return [d / "__pycache__" for d in sources]
    return [
        Path(root) / f"{d.name}_{hashlib.sha1(os.path.abspath(d).encode()).hexdigest()}"
        for d in sources
    ]


def clear_cache() -> int:
    """Delete stabctl's compiled kernels (``*.nbi``, ``*.nbc`` in `cache_dirs`), as after
    a fresh installation; returns how many files."""
    files = [f for d in cache_dirs() for f in (*d.glob("*.nbi"), *d.glob("*.nbc"))]
    for f in files:
        f.unlink(missing_ok=True)
    return len(files)


def cached(dispatcher) -> bool:
    """Whether a kernel has a whole entry in the on-disk cache (numba's index file of it
    and a data file, each whole pickles: `_whole_pickles`), i.e. a new process loads it
    instead of compiling it (for the argument types it was compiled for; stale entries
    are gone, `ensure_fresh_cache`).  An empty, cut or garbled file is no entry: the
    kernel compiles again (numba drops such an entry), and ``compile --check`` says so
    instead of calling the cache warm.  numba names the entry after the source file, so
    a kernel of a package's ``__init__.py`` is ``__init__.<name>-...``.  A cache moved
    from an unsafe place is said here too (`_say_moved`): ``compile --check`` reads it."""
    _say_moved()
    py = dispatcher.py_func
    stem = f"{Path(py.__code__.co_filename).stem}.{py.__qualname__}-"
    return any(
        _whole_pickles(index, 2)  # numba's version, then (source stamp, overloads)
        and _whole_data(sorted(index.parent.glob(f"{index.stem}.*.nbc")))
        for index in Path(dispatcher.stats.cache_path).glob(stem + "*.nbi")
    )


def _whole_data(files: list[Path]) -> bool:
    """Whether an index's data files (one per overload) are there and each is one whole
    pickle: a damaged overload is compiled again when it is called."""
    return bool(files) and all(_whole_pickles(d, 1) for d in files)


def _whole_pickles(path: Path, count: int) -> bool:
    """Whether the file holds `count` whole pickles one after the other and nothing
    more, read as opcodes (`pickletools.genops`: nothing is unpickled, no code runs)."""
    import pickletools

    if not path.is_file():  # a FIFO would block the read, a device never end
        return False
    try:
        with open(path, "rb") as f:
            for _ in range(count):
                for _op in pickletools.genops(f):
                    pass
            return f.read(1) == b""
    except (OSError, ValueError, EOFError):  # unreadable, cut, or not pickle opcodes
        return False


def _could_make(directory: str) -> None:
    """Raise the OSError that making `directory` (``os.makedirs``) and writing into it
    would raise, without making it: its nearest existing ancestor is not a directory, or
    this process may not write there."""
    path = Path(directory)
    while not path.exists() and path.parent != path:
        if path.is_symlink():  # a dangling link: makedirs fails on it
            raise FileExistsError(errno.EEXIST, os.strerror(errno.EEXIST), str(path))
        path = path.parent
    if not path.is_dir():
        raise NotADirectoryError(errno.ENOTDIR, os.strerror(errno.ENOTDIR), str(path))
    if not os.access(path, os.W_OK | os.X_OK):
        raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), str(path))


def make_private_dirs(directory) -> None:
    """Make the missing directories of `directory` (and it) with mode 0700 whatever the
    umask: numba's own ``os.makedirs`` gives them the umask's mode (0777 under umask
    000), which `unsafe_reason` then refuses, moving the cache away and compiling again.
    Directories that exist are left as they are.

    Parameters
    ----------
    directory : str or Path
        The directory.

    Raises
    ------
    OSError
        As ``os.mkdir``: a parent that is no directory, no permission.
    """
    path, missing = Path(directory), []
    while not path.exists() and path.parent != path:
        missing.append(path)
        path = path.parent
    for made in reversed(missing):
        with contextlib.suppress(FileExistsError):  # made by another process meanwhile
            made.mkdir(mode=0o700)
            os.chmod(made, 0o700)


class _LooksFirst:
    """Mixin of a numba cache locator whose first ``ensure_cache_path`` (numba's choice of
    a locator when a kernel is declared) only checks that the cache directory could be
    made and written (`_could_make`), and whose later ones (before a kernel is saved)
    make it: declaring a kernel creates no directory, only compiling one does (numba
    made every kernel's directory as the kernel was declared, so that ``stabctl --help``
    or ``compile --check`` filled an empty NUMBA_CACHE_DIR)."""

    def ensure_cache_path(self):
        """Check (the first call) or make (later ones) the cache directory."""
        if self.__dict__.get("_chosen"):
            make_private_dirs(self.get_cache_path())  # type: ignore[attr-defined]
            return super().ensure_cache_path()  # type: ignore[misc]
        self._chosen = True
        _could_make(self.get_cache_path())  # type: ignore[attr-defined]
        return None


class _LazyCacheImpl(CompileResultCacheImpl):
    """numba's cache implementation of a compiled function, with numba's locators in
    numba's order, each making its directory only when a kernel is saved (`_LooksFirst`)."""

    _locator_classes: ClassVar[list] = [
        type(cls.__name__, (_LooksFirst, cls), {"__doc__": cls.__doc__})
        for cls in CompileResultCacheImpl._locator_classes
    ]


class _UnsafeEntry(Exception):
    """A cache file numba must not unpickle (`unsafe_entry_reason`, the message)."""


class _CheckedCacheFile(IndexDataCacheFile):
    """numba's index and data files of one kernel, each checked (`unsafe_entry_reason`)
    before it is unpickled (`_UnsafeEntry` if unsafe), and written writable by their owner
    only (numba's are as the umask leaves them, group-writable under umask 002)."""

    def _load_index(self):
        _check_entry(self._index_path)
        return super()._load_index()

    def _load_data(self, name):
        _check_entry(self._data_path(name))
        return super()._load_data(name)

    @contextlib.contextmanager
    def _open_for_write(self, filepath):
        with super()._open_for_write(filepath) as f:
            mode = stat.S_IMODE(os.fstat(f.fileno()).st_mode)
            os.fchmod(f.fileno(), mode & ~(stat.S_IWGRP | stat.S_IWOTH))
            yield f


def _check_entry(path: str) -> None:
    """`_UnsafeEntry` naming why if numba must not unpickle the cache file `path`."""
    why = unsafe_entry_reason(Path(path))
    if why:
        raise _UnsafeEntry(why)


class GuardedCache(FunctionCache):
    """numba's on-disk cache of one kernel, whose load survives a damaged or unsafe entry:
    an index or data file that does not unpickle (truncated, garbage) is deleted and the
    kernel compiled again, instead of the run stopping with an UnpicklingError; so is one
    that is unsafe to unpickle (`unsafe_entry_reason`, checked before numba reads it), with
    a RuntimeWarning naming the file and why.  Its directory is made only when the kernel
    is first saved (`_LooksFirst`), and the cache's key (`stamp_cache`) written before."""

    _impl_class = _LazyCacheImpl

    def __init__(self, py_func):
        super().__init__(py_func)
        self._cache_file = _CheckedCacheFile(
            cache_path=self._cache_path,
            filename_base=self._impl.filename_base,
            source_stamp=self._impl.locator.get_source_stamp(),
        )

    def load_overload(self, sig, target_context):
        """The cached kernel for sig, or None (compile it) if none, damaged or unsafe."""
        _say_moved()
        try:
            return super().load_overload(sig, target_context)
        except Exception as exc:  # noqa: BLE001 - whatever a damaged pickle raises
            if isinstance(exc, _UnsafeEntry):
                warnings.warn(
                    f"numba cache: {exc}; not loaded: the entry is deleted and its kernel "
                    "compiled again",
                    RuntimeWarning,
                    stacklevel=2,
                )
            cache_file = self._cache_file
            index = Path(cache_file._index_path)
            for path in (index, *index.parent.glob(index.stem + "*.nbc")):
                try:
                    path.unlink(missing_ok=True)
                except OSError as err:  # a directory in its place: never removed
                    self._kept_out = f"{path} cannot be replaced ({err.strerror})"
                    warnings.warn(
                        f"numba cache: {self._kept_out}: the kernel is compiled for this "
                        "process only, not saved",
                        RuntimeWarning,
                        stacklevel=2,
                    )
            return None

    #: why this kernel is not saved (an entry that cannot be replaced), '' if it is
    _kept_out = ""

    def save_overload(self, sig, data):
        """Save a compiled kernel, the cache's key (`stamp_cache`) first; not if an entry
        in its place cannot be replaced (`load_overload`), nor where the cache cannot be
        written (a full disk, a quota, ``ulimit -f``: the kernel is used all the same,
        compiled for this process only, with one RuntimeWarning a process; every command
        that compiled a kernel failed with "error: File too large")."""
        _say_moved()
        if self._kept_out:
            return None
        try:
            stamp_cache()
            return super().save_overload(sig, data)
        except OSError as exc:
            self._kept_out = f"{self._cache_path} cannot be written ({exc.strerror or exc})"
            if exc.errno not in _UNWRITABLE_SAID:
                _UNWRITABLE_SAID.add(exc.errno)
                warnings.warn(
                    f"numba cache: {self._kept_out}: kernels are compiled for this process "
                    "only, not saved (each run compiles them again until the cache can be "
                    "written: free space, or set NUMBA_CACHE_DIR elsewhere)",
                    RuntimeWarning,
                    stacklevel=2,
                )
            return None


#: the errors (errno) of a cache that cannot be written already warned of in this process
_UNWRITABLE_SAID: set = set()


def guard(dispatcher):
    """`dispatcher` with an on-disk cache, a `GuardedCache` (returned).

    Parameters
    ----------
    dispatcher : numba dispatcher
        Declared without numba's own cache (``cache=False``: numba's would make its
        directory at once) or with it (replaced).

    Returns
    -------
    numba dispatcher
        The same dispatcher.
    """
    dispatcher._cache = GuardedCache(dispatcher.py_func)
    return dispatcher


def private_cache_dir() -> tuple[Path, str]:
    """This user's own cache directory (``~/.cache/stabctl-numba``, mode 0700), used
    instead of an unsafe one (`unsafe_reason`), and what to add to the warning.  Where it
    cannot be made (a read-only home, XDG_CACHE_HOME a file: every command, --help
    included, failed at import with a traceback), a new directory of this process under
    the temporary directory (mode 0700, removed at exit): kernels are then compiled
    again by each run, which the warning says."""
    path = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "stabctl-numba"
    try:
        path.mkdir(parents=True, exist_ok=True, mode=0o700)
        os.chmod(path, 0o700)
        return path, ""
    except OSError as exc:
        held = temp_dir("stabctl-numba.")
        atexit.register(held.remove)
        return Path(held.path), (
            f" ({path} cannot be made: {exc.strerror}; for this run only, every run "
            "compiling them again: set NUMBA_CACHE_DIR to a directory of your own)"
        )


def ensure_safe_cache() -> None:
    """Point numba's cache at `private_cache_dir` if NUMBA_CACHE_DIR or one of stabctl's
    cache directories is unsafe (`unsafe_reason`); a RuntimeWarning names why when the
    cache is first read (a kernel loaded or saved, `cached`; `_say_moved`): at import it
    came before the CLI reads warnings, as Python's raw text with a source line."""
    root = numba.config.CACHE_DIR
    places = ([Path(root)] if root else []) + cache_dirs()
    why = next((r for r in map(unsafe_reason, places) if r), "")
    if why:
        path, note = private_cache_dir()
        numba.config.CACHE_DIR = str(path)
        _MOVED[:] = [f"numba cache: {why}; stabctl's kernels are cached in {path} instead{note}"]


#: why the cache was moved (`ensure_safe_cache`), said once (`_say_moved`)
_MOVED: list[str] = []


def _say_moved() -> None:
    """The RuntimeWarning of `ensure_safe_cache`, once, when the cache is first used."""
    while _MOVED:
        warnings.warn(_MOVED.pop(), RuntimeWarning, stacklevel=3)


#: the cache key `stamp_cache` is to write (None: the stamp is up to date)
_STAMP_DUE: str | None = None


def _stamp() -> Path:
    return cache_dirs()[0] / "numba-sources.sha256"


#: the longest cache stamp read (bytes): a digest is 64 hex digits; a longer file is damaged
STAMP_MAX_BYTES = 4096


def _read_stamp(path: Path) -> str | None:
    """The cache key in the stamp `path`, or None if there is none that can be trusted:
    missing, not a regular file (a FIFO, which a plain read waits on for ever, a device,
    a symbolic link, a directory), larger than `STAMP_MAX_BYTES` or not text.  Opened
    without following a link and without waiting (O_NONBLOCK), and checked on the open
    file itself, so what is read is what was checked."""
    flags = os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0)
    try:
        fd = os.open(path, flags)
    except OSError:
        return None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode) or st.st_size > STAMP_MAX_BYTES:
            return None
        return os.read(fd, STAMP_MAX_BYTES + 1).decode("ascii")
    except (OSError, UnicodeDecodeError):
        return None
    finally:
        os.close(fd)


def ensure_fresh_cache() -> None:
    """Delete stabctl's compiled kernels (`clear_cache`) if a kernel source changed since
    they were written (`source_digest`; the stamp sits in the first cache directory).
    The new stamp is written when the first kernel is saved (`stamp_cache`), not here: a
    process that compiles nothing makes nothing (``stabctl compile --check``).  A
    stamp that is not a regular file or is larger than `STAMP_MAX_BYTES` is read as out
    of date (`_read_stamp`: never waited on), as a damaged kernel file is.  A read-only
    installation is left alone (numba then compiles in memory)."""
    global _STAMP_DUE
    ensure_safe_cache()
    now = source_digest()
    try:
        if _read_stamp(_stamp()) == now:
            return
        clear_cache()
    except OSError:
        return
    _STAMP_DUE = now


def stamp_cache() -> None:
    """Write the cache's key (`source_digest`) that `ensure_fresh_cache` found missing or
    out of date, making its directory, before a kernel is saved (`GuardedCache`) or
    compiled in a child process (`stabctl._jit.background`); nothing when it is up to
    date.  Written to a file of its own, then renamed over the stamp: whatever is there
    (a FIFO, which an open for writing waits on, a link) is replaced, not written
    through.  A directory that cannot be written is left alone."""
    global _STAMP_DUE
    if _STAMP_DUE is None:
        return
    stamp = _stamp()
    tmp = stamp.with_name(f".{stamp.name}.{os.getpid()}.tmp")
    try:
        make_private_dirs(stamp.parent)
        flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0)
        fd = os.open(tmp, flags, 0o644)
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(_STAMP_DUE)
        os.replace(tmp, stamp)
    except OSError:
        with contextlib.suppress(OSError):
            tmp.unlink()
    _STAMP_DUE = None
