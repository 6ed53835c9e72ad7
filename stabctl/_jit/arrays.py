"""Array helpers for kernels, written as loops so that a kernel using them does not compile
numba's generic implementation (and its error-message code) of the numpy idiom."""

from __future__ import annotations

from stabctl._jit.decorators import kernel


@kernel
def assign(dst, src) -> None:
    """``dst[...] = src`` inside a kernel, element by element (arrays of one size, any
    layout; no check).  numba's slice assignment from an array compiles a formatter for
    its shape-mismatch message (f-strings, ``str.join``, integer reprs): about 2-3 s of
    a cold first call in every process that compiles one.  Kernels use this instead.

    Parameters
    ----------
    dst : ndarray
        Written in place (a view, e.g. ``x[k]`` or ``F[3:, 3:]``).
    src : ndarray
        Same size and element order (C order for more than one dimension).
    """
    for j in range(dst.size):
        dst.flat[j] = src.flat[j]


@kernel
def max_abs(a) -> float:
    """``np.max(np.abs(a))`` inside a kernel, without compiling numba's generic reduction
    (``np.max`` with its ``take`` helpers: about 0.3-0.4 s of every cold process that
    compiles one).  NaN propagates as in numpy: the first NaN is returned.

    Parameters
    ----------
    a : ndarray
        1-D, real or complex, not empty (numpy raises on an empty array; this returns 0).

    Returns
    -------
    float
        The largest magnitude, or NaN.
    """
    m = 0.0
    for j in range(a.size):
        v = abs(a[j])
        if v != v:
            return v
        if v > m:
            m = v
    return m
