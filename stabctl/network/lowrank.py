"""A network stage's Kron reduction from the pre-event network's, by a low-rank update.

A fault, a line trip or a machine trip changes a few entries of the augmented admittance
matrix A (machines' internal nodes and buses, `stabctl.network.solution`): A' = A + Delta,
Delta non-zero on a few nodes S only.  With A partitioned into kept (k) and eliminated (e)
nodes, the reduction Y_red = A_kk - A_ke A_ee^-1 A_ek and the eliminated voltages' map
rec = -A_ee^-1 A_ek of the stage follow from the pre-event network's and its sparse LU of
A_ee by the Woodbury identity (Golub and Van Loan, Matrix Computations, 4th ed., 2013,
sec. 2.1.4), with P the columns of the eliminated nodes in S (S_e), D = Delta[S_e, S_e],
E = Delta[S_e, k], E2 = Delta[k, S_e] and G = A_ee^-1 P (one solve per node of S_e):

    (A_ee + P D P^T)^-1 = A_ee^-1 - G D (I + P^T G D)^-1 P^T A_ee^-1,
    F = E + D (I + P^T G D)^-1 (P^T rec - P^T G E),
    rec' = rec - G F,
    Y_red' = Y_red + Delta[k, k] - (A_ke G) F + E2 P^T rec'.

A planning case's stage then costs a few sparse solves instead of one per kept node
(ACTIVSg2000: 334 right-hand sides, 42 ms of a bus fault's 60-100 ms stage).  rec' is
kept in that form (`LowRankRows`), its rows formed when read: a run reads those of the
machines' buses and of the buses it records (none in a CCT search), and ACTIVSg2000's
whole rec' is 10.7 MB, 9 ms to form (a tenth of a robust fault's search).  Nodes a
stage adds (fault nodes of a line cleared at one end) are isolated nodes of the
pre-event network, A = 1 on their diagonal.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

#: most nodes a stage may change for the update (else the full reduction): a bus fault
#: changes 1, a line trip 2, a line cleared at one end 3-4, a machine trip 2
MAX_CHANGED = 16
#: largest condition number of I + P^T G D accepted; above it (a stage close to singular,
#: an island) the full reduction decides
MAX_COND = 1e10


class SparseReduction(NamedTuple):
    """The sparse Kron reduction of one network stage, kept for the updates of others.

    Attributes
    ----------
    full : scipy.sparse.csr_matrix, shape (N, N)
        The augmented admittance matrix (machines' internal nodes first, then buses).
    keep, elim : ndarray of int
        Kept and eliminated nodes of `full`, ascending.
    lu : scipy.sparse.linalg.SuperLU
        LU factors of full[elim][:, elim].
    rec : ndarray, shape (elim.size, keep.size), complex
        -A_ee^-1 A_ek: the eliminated nodes' voltages from the kept ones.
    Yred : ndarray, shape (keep.size, keep.size), complex
        The reduced matrix A_kk + A_ke rec.
    a_ke : scipy.sparse.csr_matrix, shape (keep.size, elim.size)
        full[keep][:, elim].
    """

    full: sp.csr_matrix
    keep: np.ndarray
    elim: np.ndarray
    lu: spla.SuperLU
    rec: np.ndarray
    Yred: np.ndarray
    a_ke: sp.csr_matrix


class LowRankRows:
    """A matrix kept as ``top - G @ F`` (`updated`'s rec'): `top` the base's rec with zero
    rows below it for the nodes a stage adds, G (n_rows, r), F (r, m) complex; its rows
    formed when indexed.

    Parameters
    ----------
    top : ndarray, shape (n_top, m), complex
        The base's rows (not copied).
    G : ndarray, shape (n_rows, r), complex
        n_rows >= n_top.
    F : ndarray, shape (r, m), complex
    """

    def __init__(self, top: np.ndarray, G: np.ndarray, F: np.ndarray) -> None:
        self.top, self.G, self.F = top, G, F
        self.shape = (G.shape[0], top.shape[1])
        self.dtype = np.dtype(complex)

    def __getitem__(self, key) -> LowRankRows | np.ndarray:
        """Rows: a leading slice ``[:n]`` stays in this form; an array of row indices
        (ints, shape (k,)) gives them as an ndarray (k, m)."""
        if isinstance(key, slice) and key.start is None and key.step is None:
            n = self.shape[0] if key.stop is None else min(key.stop, self.shape[0])
            return LowRankRows(self.top[:n], self.G[:n], self.F)
        return self.rows(key)

    def rows(self, key) -> np.ndarray:
        """Rows `key` (int indices, shape (k,)) formed, shape (k, m); equal to the whole
        matrix's rows to rounding (a product of fewer rows may take another of BLAS's
        kernels)."""
        rows = np.asarray(key, int)
        out = np.zeros((rows.size, self.shape[1]), complex)
        inside = rows < self.top.shape[0]
        out[inside] = self.top[rows[inside]]
        return out - self.G[rows] @ self.F

    def __array__(self, dtype=None, copy=None) -> np.ndarray:
        """Every row (the whole matrix formed)."""
        whole = np.zeros(self.shape, complex)
        whole[: self.top.shape[0]] = self.top
        whole -= self.G @ self.F
        return whole if dtype is None else whole.astype(dtype)

    def all_finite(self) -> bool:
        """Whether every entry is finite (the base's rows are: G and F are checked)."""
        return bool(np.all(np.isfinite(self.G)) and np.all(np.isfinite(self.F)))


def updated(
    base: SparseReduction, full: sp.csr_matrix, keep: np.ndarray, elim: np.ndarray
) -> tuple[LowRankRows, np.ndarray] | None:
    """The reduction of a stage (rec, Yred) from `base`'s, or None when the stage changes
    more than `MAX_CHANGED` nodes, keeps other nodes, or is close to singular (then the
    caller reduces it in full).

    Parameters
    ----------
    base : SparseReduction
        The pre-event network's reduction (N0 nodes).
    full : scipy.sparse matrix, shape (N, N), N >= N0
        The stage's augmented matrix; nodes N0..N-1 are nodes the stage adds.
    keep, elim : ndarray of int
        The stage's kept and eliminated nodes, ascending (keep as `base.keep`).

    Returns
    -------
    tuple or None
        rec (elim.size, keep.size; a `LowRankRows`) and Yred (keep.size, keep.size),
        complex; None: not updated.
    """
    n0, n = base.full.shape[0], full.shape[0]
    if n < n0 or not np.array_equal(keep, base.keep):
        return None
    ext = base.full if n == n0 else sp.block_diag((base.full, sp.identity(n - n0)), format="csr")
    delta = sp.csr_matrix(full - ext)
    delta.eliminate_zeros()
    changed = np.union1d(*delta.nonzero())
    if changed.size > MAX_CHANGED:
        return None
    s_e = np.setdiff1d(changed, keep)
    pos = np.searchsorted(elim, s_e)  # their rows of the stage's rec
    D = delta[s_e][:, s_e].toarray()
    E = delta[s_e][:, keep].toarray()
    E2 = delta[keep][:, s_e].toarray()
    n_e0 = base.elim.size
    G = np.zeros((elim.size, s_e.size), complex)
    old = pos < n_e0
    if old.any():
        rhs = np.zeros((n_e0, int(old.sum())), complex)
        rhs[pos[old], np.arange(rhs.shape[1])] = 1.0
        G[:n_e0, old] = base.lu.solve(rhs)
    G[pos[~old], np.flatnonzero(~old)] = 1.0  # an added node: isolated, A = 1
    rec0 = np.zeros((s_e.size, keep.size), complex)  # the base's rows of S_e (0: added)
    rec0[old] = base.rec[pos[old]]
    C = np.eye(s_e.size) + G[pos] @ D
    if s_e.size and not np.linalg.cond(C) < MAX_COND:
        return None
    F = E + D @ np.linalg.solve(C, rec0 - G[pos] @ E) if s_e.size else E
    rec = LowRankRows(base.rec, G, F)
    Yred = base.Yred + delta[keep][:, keep].toarray() - (base.a_ke @ G[:n_e0]) @ F + E2 @ rec[pos]
    return rec, Yred
