"""Array helpers for kernels, written as loops so that a kernel using them does not compile
numba's generic implementation (and its error-message code) of the numpy idiom."""

from __future__ import annotations

import numpy as np

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


@kernel(inline="always")
def zero_column(a, j) -> None:
    """``a[:, j] = 0`` inside a kernel, as a loop.  numba's slice assignment builds a
    strided view and iterates it generically: the exciters' and governors' ``dx[:, i] =
    0.0`` at the top of their derivatives took about 9 % of an ACTIVSg2000 run.

    Parameters
    ----------
    a : ndarray, shape (m, n)
        Written in place.
    j : int
        Column, 0 <= j < n.
    """
    for r in range(a.shape[0]):
        a[r, j] = 0


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


#: up to this many matrix elements `matvec` loops instead of calling BLAS: numba's BLAS
#: call costs about 0.1 us whatever the size (complex 2 x 2: 109 ns against 34 ns for the
#: loop; equal near 14 x 14, BLAS 1.2 x faster at 16 x 16: benchmarks/bench_matvec.py)
SMALL_MATVEC = 196


@kernel
def matvec(A, x, out) -> None:
    """``out[:] = A @ x`` for complex A and x inside a kernel: a loop for small A
    (`SMALL_MATVEC`), BLAS above.

    Parameters
    ----------
    A : ndarray, shape (m, n), complex
        C-contiguous.
    x : ndarray, shape (n,), complex
    out : ndarray, shape (m,), complex
        Written in place; not x.
    """
    if A.size > SMALL_MATVEC:
        assign(out, A @ x)
        return
    for i in range(A.shape[0]):
        acc = 0j
        for j in range(A.shape[1]):
            acc += A[i, j] * x[j]
        out[i] = acc


@kernel
def dot(a, b):
    """``a @ b`` for complex 1-D a and b inside a kernel: a loop up to `SMALL_MATVEC`
    elements, BLAS above (no temporary either way).

    Parameters
    ----------
    a, b : ndarray, shape (n,), complex

    Returns
    -------
    complex
    """
    if a.size > SMALL_MATVEC:
        return a @ b
    acc = 0j
    for j in range(a.size):
        acc += a[j] * b[j]
    return acc


@kernel(inline="always")
def magnitude(a, b):
    """sqrt(a^2 + b^2): the magnitude of a phasor from its two parts (per unit: no
    overflow).  libm's hypot (numba's ``abs`` of a complex), which guards against
    overflow and rounds correctly, cost 5-10 % of an ACTIVSg2000 run in the machines',
    exciters' and stabilisers' per-evaluation magnitudes; this differs from it in the last
    bit at most."""
    return np.sqrt(a * a + b * b)
