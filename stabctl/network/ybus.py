"""The bus admittance matrix Ybus: the one place it is built.

Branch model (PST ``y_sparse``/``y_switch``, PST manual section 1.3 and 3.48): series
admittance ``y = 1/(r + jx)``, total charging ``b`` split half at each end, and an ideal
transformer of complex ratio ``t = tap * exp(j*phase)`` on the from side (tap 0 means 1),
the from-end charging sitting behind it. With ``V_f``, ``V_t`` the end voltages and
``I_f``, ``I_t`` the currents injected into the branch at each end::

    [I_f]   [ (y + jb/2)/|t|^2    -y/t     ] [V_f]
    [I_t] = [ -y/conj(t)           y + jb/2 ] [V_t]

This is PST's matrix ``C_from*chrg*C_from' + C_to*chrg*C_to' + C_line*y*C_line'`` with
``C_from`` holding ``1/t`` and ``'`` the conjugate transpose (PSTess ``y_sparse.m``). For a
real tap it is the textbook off-nominal-tap model; for a phase shifter PST's convention
is the textbook one (e.g. MATPOWER's) with the sign of the phase reversed, and we follow
PST. Line-end shunts ``y_f = g_from + j b_from``, ``y_t = g_to + j b_to`` (PSS/E's GI + jBI,
GJ + jBJ; ANDES ``Line`` g1 + jb1, g2 + jb2) add to ``(y + jb/2)/|t|^2`` and ``y + jb/2``,
at the bus side of the tap. Bus shunts ``gshunt + j*bshunt`` (pu at 1 pu voltage) add to
the diagonal.

The dynamic simulator reuses :func:`build_ybus` / :class:`Network` and adds generator,
load and fault admittances with :func:`add_shunts`; a line trip is ``drop=[row]`` or
:meth:`Network.without`, with :func:`circuit_row` finding one circuit of parallel lines.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from stabctl.case import Case
from stabctl.errors import CaseError, WrongTypeError, is_whole_number

__all__ = [
    "BranchAdmittances",
    "Network",
    "branch_admittances",
    "build_ybus",
    "branch_stamp",
    "add_shunts",
    "find_branches",
    "circuit_row",
    "branch_flows",
    "kept_rows",
]


@dataclass(frozen=True, eq=False)
class BranchAdmittances:
    """Two-port admittances of branches, all arrays of shape (n_branches,).

    ``f``, ``t``: 0-based bus indices of the from/to ends; ``yff``, ``yft``, ``ytf``,
    ``ytt``: complex pu on the system base, so that ``I_f = yff V_f + yft V_t`` and
    ``I_t = ytf V_f + ytt V_t``; ``rows``: the branch-table rows they come from.
    """

    rows: np.ndarray
    f: np.ndarray
    t: np.ndarray
    yff: np.ndarray
    yft: np.ndarray
    ytf: np.ndarray
    ytt: np.ndarray


def kept_rows(case: Case, drop: Iterable[int] = ()) -> np.ndarray:
    """0-based branch rows left after removing ``drop`` (0-based rows of ``case.branches``).

    Raises :class:`CaseError` if a dropped row does not exist (negative included),
    `stabctl.errors.WrongTypeError` if one is no whole number (1.5, a text, None).
    """
    n = len(case.branches)
    given = list(drop)
    odd = [d for d in given if not is_whole_number(d)]
    if odd:  # (a 1.5 was truncated to row 1, a "3" or None a bare numpy error)
        raise WrongTypeError(
            f"line: branch rows to remove are 0-based whole-number indices, got {odd[0]!r}"
        )
    drop = np.unique(np.asarray(given, dtype=int))
    if drop.size and drop[0] < 0:  # (-1 was named "row 0")
        raise CaseError(
            f"line: cannot remove branch index {drop[0]}: indices are 0-based, 0 to {n - 1}"
        )
    bad = drop[drop >= n]
    if bad.size:
        raise CaseError(f"line: cannot remove row {bad[0] + 1}, the case has {n} branches")
    keep = np.ones(n, dtype=bool)
    keep[drop] = False
    return np.flatnonzero(keep)


def complex_taps(case: Case, taps: np.ndarray | None = None) -> np.ndarray:
    """Complex ratio ``t = tap * exp(j phase)`` per branch, shape (n_branches,); tap 0 -> 1.

    ``taps`` overrides ``case.branches.tap`` (the power flow's tap changer uses it).
    """
    br = case.branches
    tap = np.array(br.tap if taps is None else taps, dtype=float)
    tap[tap == 0] = 1.0
    return tap * np.exp(1j * np.deg2rad(br.phase_deg))


def branch_admittances(
    case: Case, rows: Iterable[int] | None = None, taps: np.ndarray | None = None
) -> BranchAdmittances:
    """Two-port admittances of ``rows`` (default all) of ``case.branches``; see module doc.

    ``taps``: optional tap ratios for all branches, shape (n_branches,). Raises
    :class:`UnknownBusError` if a branch names a bus not in the case (cannot happen for a
    validated case).
    """
    br = case.branches
    rows = np.arange(len(br)) if rows is None else np.asarray(list(rows), dtype=int)
    y = 1.0 / (br.r[rows] + 1j * br.x[rows])
    half_b = 0.5j * br.b[rows]
    t = complex_taps(case, taps)[rows]
    yff, ytt = (y + half_b) / (t * np.conj(t)).real, y + half_b
    ends = (
        (br.g_from[rows] != 0)
        | (br.b_from[rows] != 0)
        | (br.g_to[rows] != 0)
        | (br.b_to[rows] != 0)
    )
    if ends.any():
        yff = yff + (br.g_from[rows] + 1j * br.b_from[rows])
        ytt = ytt + (br.g_to[rows] + 1j * br.b_to[rows])
    return BranchAdmittances(
        rows=rows,
        f=case.bus_indices(br.from_bus[rows]),
        t=case.bus_indices(br.to_bus[rows]),
        yff=yff,
        yft=-y / t,
        ytf=-y / np.conj(t),
        ytt=ytt,
    )


def _stamp(ba: BranchAdmittances, n_bus: int, sign: float = 1.0) -> sp.csr_matrix:
    rows = np.concatenate([ba.f, ba.f, ba.t, ba.t])
    cols = np.concatenate([ba.f, ba.t, ba.f, ba.t])
    vals = sign * np.concatenate([ba.yff, ba.yft, ba.ytf, ba.ytt])
    return sp.csr_matrix((vals, (rows, cols)), shape=(n_bus, n_bus), dtype=complex)


def build_ybus(
    case: Case,
    *,
    drop: Iterable[int] = (),
    shunts: bool = True,
    taps: np.ndarray | None = None,
) -> sp.csr_matrix:
    """Bus admittance matrix, complex CSR of shape (n_bus, n_bus), pu on the system base.

    Row/column ``i`` is bus ``case.buses.number[i]`` (``case.bus_index(number)``).

    Args:
        case: the case.
        drop: 0-based rows of ``case.branches`` to leave out (tripped circuits).
        shunts: include the bus G/B shunts (``buses.gshunt + j*buses.bshunt``).
        taps: tap ratios overriding ``branches.tap``, shape (n_branches,).

    Raises :class:`CaseError` for a dropped row that does not exist.
    Source: PST ``y_sparse.m`` (PSTess), PST manual section 3.48 (``y_switch``).
    """
    ba = branch_admittances(case, kept_rows(case, drop), taps)
    y = _stamp(ba, case.n_bus)
    if shunts:
        y = y + sp.diags(case.buses.gshunt + 1j * case.buses.bshunt, format="csr")
    y.sum_duplicates()
    return y.tocsr()


def branch_stamp(case: Case, rows: Iterable[int], taps: np.ndarray | None = None) -> sp.csr_matrix:
    """Contribution of branch ``rows`` to Ybus, complex CSR (n_bus, n_bus).

    ``build_ybus(case) - branch_stamp(case, rows)`` equals ``build_ybus(case, drop=rows)``.
    """
    return _stamp(branch_admittances(case, rows, taps), case.n_bus)


def add_shunts(ybus: sp.spmatrix, index, y) -> sp.csr_matrix:
    """``ybus`` plus shunt admittances ``y`` (complex pu) at 0-based bus ``index``.

    ``index`` and ``y`` broadcast to shape (k,); repeated indices add. Returns a new CSR
    matrix (the simulator adds generator, load and fault admittances this way).
    """
    index, y = np.broadcast_arrays(np.asarray(index, dtype=int), np.asarray(y, dtype=complex))
    n = ybus.shape[0]
    extra = sp.csr_matrix((y.ravel(), (index.ravel(), index.ravel())), shape=(n, n))
    return (ybus + extra).tocsr()


def find_branches(case: Case, bus_a, bus_b) -> np.ndarray:
    """0-based rows of all branches joining buses ``bus_a`` and ``bus_b`` (either direction),
    in table order (row order defines the circuit numbers 1, 2, ... of parallel lines):
    `Case.branch_rows`.

    Raises :class:`UnknownBusError` for a bus not in the case.
    """
    return case.branch_rows(bus_a, bus_b)


def circuit_row(case: Case, bus_a, bus_b, circuit: int = 1) -> int:
    """0-based branch row of circuit ``circuit`` (1-based) between ``bus_a`` and ``bus_b``:
    `Case.circuit_row`.

    PST's ``sw_con`` trips the first line found between the fault bus and the far bus,
    i.e. circuit 1. Raises :class:`CaseError` if there is no such branch or circuit,
    :class:`UnknownBusError` for an unknown bus.
    """
    return case.circuit_row(bus_a, bus_b, circuit)


def branch_flows(
    case: Case, v: np.ndarray, *, drop: Iterable[int] = (), taps: np.ndarray | None = None
) -> Mapping[str, np.ndarray]:
    """Complex power flows of the in-service branches for bus voltages ``v``.

    Args:
        v: complex bus voltages, pu, shape (n_bus,).
    Returns:
        ``rows`` (0-based branch rows), ``s_from`` (power leaving the from bus into the
        branch), ``s_to`` (power leaving the to bus), ``loss`` (s_from + s_to), complex pu,
        shapes (k,). Source: PST ``loadflow.m`` line-flow section.
    """
    ba = branch_admittances(case, kept_rows(case, drop), taps)
    vf, vt = v[ba.f], v[ba.t]
    s_from = vf * np.conj(ba.yff * vf + ba.yft * vt)
    s_to = vt * np.conj(ba.ytf * vf + ba.ytt * vt)
    return {"rows": ba.rows, "s_from": s_from, "s_to": s_to, "loss": s_from + s_to}


@dataclass(frozen=True, eq=False)
class Network:
    """A case's Ybus with the branches in service.

    Attributes:
        case: the case.
        ybus: complex CSR (n_bus, n_bus), pu on the system base.
        in_service: 0-based branch rows included, int array.
    """

    case: Case
    ybus: sp.csr_matrix
    in_service: np.ndarray

    @classmethod
    def from_case(cls, case: Case, drop: Iterable[int] = ()) -> Network:
        """Build the network of ``case`` without branch rows ``drop`` (0-based)."""
        drop = list(drop)
        return cls(case, build_ybus(case, drop=drop), kept_rows(case, drop))

    @property
    def bus_map(self) -> Mapping[int, int]:
        """Bus number -> 0-based row/column of ``ybus``."""
        return self.case.bus_map

    def without(self, rows: Iterable[int]) -> Network:
        """The network with branch ``rows`` (0-based) also out of service, by subtracting
        their stamps (no rebuild). Raises :class:`CaseError` if a row is already out."""
        rows = np.unique(np.asarray(list(rows), dtype=int))
        out = rows[~np.isin(rows, self.in_service)]
        if out.size:
            raise CaseError(f"line row {out[0] + 1} is not in service")
        y = (self.ybus - branch_stamp(self.case, rows)).tocsr()
        y.eliminate_zeros()
        return Network(self.case, y, np.setdiff1d(self.in_service, rows))
