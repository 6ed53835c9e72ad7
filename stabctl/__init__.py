"""stabctl: transient-stability control of power systems with distributed energy storage.

Per unit on the system base unless a name says otherwise; time in s; angles in rad;
frequencies in Hz.
"""

import os

# The simulator works on many small dense matrices: multi-threaded BLAS only adds overhead
# there, and oversubscribes the cores when sweeps run one simulation per process.  Users can
# still choose by setting these variables before importing stabctl.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

from ._jitcache import ensure_fresh_cache  # noqa: E402

ensure_fresh_cache()

__version__ = "0.1.0"
