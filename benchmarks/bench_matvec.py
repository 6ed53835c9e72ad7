"""The complex matrix-vector product of the network solution inside a kernel: numba's
``A @ x`` (a BLAS zgemv call) against a compiled loop, by matrix order (not a test).

Where `stabctl._jit.arrays.matvec` switches from the loop to BLAS (SMALL_MATVEC elements):
the reduced networks' products (Y11 psi, Y12 V, Y21 psi, Z22 F in every chord step, R z)
are 2 x 2 to 6 x 13 on Kundur, where the BLAS call's fixed cost is most of an evaluation's
network solution.  BLAS limited to one thread (as the simulator's runs).

Run: python benchmarks/bench_matvec.py [--orders 2 4 8 16 32 64 256]
"""

from __future__ import annotations

import argparse
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np
from _timing import best_of
from numba import njit

from stabctl._jit.arrays import SMALL_MATVEC, matvec


@njit
def _blas(A, x, out, n):
    for _ in range(n):
        out[:] = A @ x
    return out[0]


@njit
def _matvec(A, x, out, n):
    for _ in range(n):
        matvec(A, x, out)
    return out[0]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--orders", type=int, nargs="+", default=[2, 4, 8, 16, 32, 64, 256])
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    print(f"ns per product (best of 5), complex128, SMALL_MATVEC = {SMALL_MATVEC} elements")
    print(f"{'order':>6} {'BLAS':>10} {'matvec':>10} {'matvec path':>12}")
    for m in args.orders:
        A = rng.standard_normal((m, m)) + 1j * rng.standard_normal((m, m))
        x = rng.standard_normal(m) + 1j * rng.standard_normal(m)
        n = max(20, int(2e6 / m**2))
        row = []
        for f in (_blas, _matvec):
            out = np.empty(m, complex)
            f(A, x, out, 2)
            wall, _ = best_of(lambda f=f, out=out: f(A, x, out, n), 5, warm_up=False)
            row.append(wall / n * 1e9)
        ref, got = A @ x, np.empty(m, complex)
        matvec(A, x, got)
        assert np.allclose(got, ref, rtol=1e-13, atol=1e-13 * m)
        path = "loop" if m * m <= SMALL_MATVEC else "BLAS"
        print(f"{m:>6} {row[0]:>10.0f} {row[1]:>10.0f} {path:>12}")


if __name__ == "__main__":
    main()
