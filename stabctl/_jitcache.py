"""Keep numba's on-disk cache of the compiled kernels consistent.

numba invalidates a cached function only when its own source file changes, not when a
function it inlines from another module does (numba documentation, "Cache invalidation").
Our kernels call across modules, so we hash every stabctl source file and clear the cached
kernels of this package whenever the hash differs from the one they were compiled with.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

_PKG = Path(__file__).resolve().parent


def ensure_fresh_cache() -> None:
    """Delete stabctl's numba cache files (*.nbi, *.nbc) if any source file changed."""
    digest = hashlib.sha256()
    for f in sorted(_PKG.glob("*.py")):
        digest.update(f.name.encode())
        digest.update(f.read_bytes())
    stamp_dir = _PKG / "__pycache__"
    stamp = stamp_dir / "numba-sources.sha256"
    now = digest.hexdigest()
    try:
        if stamp.exists() and stamp.read_text() == now:
            return
        for f in list(stamp_dir.glob("*.nbi")) + list(stamp_dir.glob("*.nbc")):
            f.unlink(missing_ok=True)
        stamp_dir.mkdir(exist_ok=True)
        stamp.write_text(now)
    except OSError:  # read-only installation: numba then compiles in memory
        pass
