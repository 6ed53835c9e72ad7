"""Newton-Raphson AC power flow with PST's ``loadflow`` conventions.

Polar coordinates, sparse Jacobian, sparse LU solve. Conventions (PSTess ``loadflow.m``,
``calc.m``, ``chq_lim.m``, ``lftap.m``; PST manual section 1.4):

* start values are the bus table's ``vmag`` and ``vang_deg`` (not a flat start); the
  swing bus keeps its magnitude and angle; PV buses keep their magnitude; when that
  does not converge (a bus added with a voltage far from any solution), the flow is
  solved again from a flat start with a warning (`_from_flat_start`; PST has no such
  retry: cases that converge solve exactly as PST);
* specified injection ``Pg - Pl`` (and ``Qg - Ql`` at PQ buses), loads at PV and swing
  buses are kept as given; bus shunts are constant admittances in Ybus;
* convergence when ``max|dP| + max|dQ| <= tol`` over non-swing (P) and PQ (Q) buses;
* after each update the magnitudes are clipped to [vmin, vmax] (0 means 0.5 / 1.5), so a
  solution with a voltage outside its limits does not converge unless a tap moves;
* remote regulation (``case.remote_regulation``, PSS/E's IREG and RMPCT): the
  regulated bus is held at ``vset`` while the generator buses regulating it float, their
  reactive generation the group's total (one more unknown per group) shared by
  ``share``; a generator bus at a Q limit leaves its group (the others take its share),
  and with none left the regulated bus floats (PSS/E's remote control, POM 6.3);
* Q limits: after each iteration a PV bus whose ``Q + Ql`` leaves [qmin, qmax] (0 means
  no limit, i.e. +-9999) becomes PQ with its generation fixed at the limit (PST
  ``chq_lim``); once converged, a bus held at qmax with its voltage above its set point,
  or at qmin below it, returns to PV and the iterations go on (PSS/E's back-off, which
  PST lacks: without it a bus switched by an early iterate stays switched, and
  ACTIVSg2000's solution is missed by 0.017 pu); cases where no held bus ends on the
  wrong side solve exactly as PST;
* on-load tap changers (branches with ``tapmax != 0``): after a solution, a bus at or
  beyond its voltage limit moves the tap of the branches whose to-bus it is, in steps of
  ``tapstep`` within [tapmin, tapmax], and the flow is solved again from the start values
  (at most 10 times); an inner solve that ran out of iterations is not an error while a
  tap still moves;
* the solved bus matrix (:meth:`PowerFlowResult.bus_matrix`) follows ``bus_sol``:
  generation at PV and swing buses and loads at PQ buses are recomputed from the
  solution, limited generators are listed as PQ buses with ``qgen`` at the limit.

Fixed injections (``case.injections``) add to the specified generation and are not part
of the reported ``pgen``/``qgen``.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from numbers import Integral

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from stabctl.case import PQ, PV, SWING, Case, require_case
from stabctl.errors import (
    InputError,
    PowerFlowError,
    WrongTypeError,
    advice,
    is_whole_number,
    require_items,
    require_number,
)
from stabctl.network import switched_shunts as sws
from stabctl.network.topology import OPEN_X, bus_islands, dead_buses
from stabctl.network.ybus import add_shunts, branch_flows, build_ybus

__all__ = ["PowerFlowResult", "solve_powerflow", "power_injections", "jacobian"]

_NO_LIMIT = 9999.0
_TAP_ITER_MAX = 10
#: releases of wrong-side Q-limited buses per solve, and the voltage margin (pu) beyond
#: the set point that counts as the wrong side (`_release_wrong_side`)
_BACKOFF_ROUNDS = 20
_BACKOFF_DV = 1e-6
#: the Newton state's kind of a generator bus holding another bus's voltage (reported as PV)
_REMOTE = 4


@dataclass(frozen=True, eq=False)
class PowerFlowResult:
    """A solved power flow. Arrays have shape (n_bus,) in ``case.buses`` order, pu on the
    system base.

    Attributes:
        case: the case solved (its bus table holds the data, not the solution).
        vmag: voltage magnitude, pu.
        vang: voltage angle, rad.
        pgen, qgen: generation per bus (PST's ``bus_sol`` columns 4, 5).
        pload, qload: load per bus (columns 6, 7).
        kind: bus type after Q-limit switching (1 swing, 2 PV, 3 PQ).
        q_limited: True where a PV bus was switched to PQ at a Q limit.
        iterations: Newton iterations of the last solve.
        max_mismatch: ``max|dP| + max|dQ|`` at the solution, pu.
        taps: branch tap ratios used (after tap changing), shape (n_branches,).
        tap_iterations: outer tap-changer iterations (1 when no tap moved).
        dropped: 0-based branch rows left out of the network.
        shunt_levels: the switched shunts' levels (`stabctl.network.switched_shunts`),
            int (n_switched,).
    """

    case: Case
    vmag: np.ndarray
    vang: np.ndarray
    pgen: np.ndarray
    qgen: np.ndarray
    pload: np.ndarray
    qload: np.ndarray
    kind: np.ndarray
    q_limited: np.ndarray
    iterations: int
    max_mismatch: float
    taps: np.ndarray
    tap_iterations: int = 1
    dropped: tuple[int, ...] = field(default=())
    shunt_levels: np.ndarray = field(default_factory=lambda: np.zeros(0, int))

    @property
    def v(self) -> np.ndarray:
        """Complex bus voltages, pu, shape (n_bus,)."""
        return self.vmag * np.exp(1j * self.vang)

    @property
    def vang_deg(self) -> np.ndarray:
        """Voltage angles in degrees, shape (n_bus,)."""
        return np.rad2deg(self.vang)

    def bus_matrix(self) -> np.ndarray:
        """PST's solved bus matrix ``bus_sol``, shape (n_bus, 15).

        Columns as :class:`~stabctl.case.BusTable`; column 3 in degrees, column 10 the
        final bus type, columns 11-15 with PST's defaults for zero entries (Q limits
        +-9999, kV 1, vmax 1.5, vmin 0.5). Source: PSTess ``loadflow.m``.
        """
        b = self.case.buses
        qmax, qmin, vmax, vmin = _limits(self.case)
        kv = np.where(b.kv == 0, 1.0, b.kv)
        return np.column_stack(
            [
                b.number,
                self.vmag,
                self.vang_deg,
                self.pgen,
                self.qgen,
                self.pload,
                self.qload,
                b.gshunt,
                b.bshunt,
                self.kind,
                qmax,
                qmin,
                kv,
                vmax,
                vmin,
            ]
        )

    def solved_case(self) -> Case:
        """The case with its bus table replaced by :meth:`bus_matrix` and the final taps
        (what PST's drivers do before a dynamic run: ``bus = bus_sol``)."""
        buses = type(self.case.buses).from_matrix(self.bus_matrix())
        branches = self.case.branches.replace(tap=self.taps)
        return self.case.replace(buses=buses, branches=branches)

    def branch_flows(self):
        """Branch power flows at the solution; see :func:`stabctl.network.ybus.branch_flows`."""
        return branch_flows(self.case, self.v, drop=self.dropped, taps=self.taps)


def _limits(case: Case):
    """PST's defaults for zero entries: Q limits +-9999, voltage limits 1.5 / 0.5."""
    b = case.buses
    qmax = np.where(b.qmax == 0, _NO_LIMIT, b.qmax)
    qmin = np.where(b.qmin == 0, -_NO_LIMIT, b.qmin)
    vmax = np.where(b.vmax == 0, 1.5, b.vmax)
    vmin = np.where(b.vmin == 0, 0.5, b.vmin)
    return qmax, qmin, vmax, vmin


def power_injections(ybus: sp.spmatrix, v: np.ndarray) -> np.ndarray:
    """Complex power injected into the network at each bus, ``V * conj(Ybus V)``, shape (n,)."""
    return v * np.conj(ybus @ v)


def jacobian(
    ybus: sp.csr_matrix,
    v: np.ndarray,
    ang_idx: np.ndarray,
    mag_idx: np.ndarray,
    q_idx: np.ndarray | None = None,
):
    """Sparse power-flow Jacobian d(P[ang_idx], Q[q_idx]) / d(angle[ang_idx], |V|[mag_idx]).

    Args:
        ybus: complex CSR (n, n); v: complex voltages (n,); ang_idx: buses whose angle is
        unknown (non-swing); mag_idx: buses whose magnitude is unknown (PQ); q_idx: buses
        whose Q balance is an equation (default ``mag_idx``; remote regulation holds a
        regulated bus's magnitude while its Q balance stays).
    Returns:
        CSC matrix of shape (len(ang_idx) + len(q_idx), len(ang_idx) + len(mag_idx)).
    """
    q_idx = mag_idx if q_idx is None else q_idx
    i = ybus @ v
    vn = v / np.abs(v)
    dv = sp.diags(v)
    ds_dang = 1j * dv @ np.conj(sp.diags(i) - ybus @ dv)
    ds_dmag = dv @ np.conj(ybus @ sp.diags(vn)) + np.conj(sp.diags(i)) @ sp.diags(vn)
    ds_dang = ds_dang.tocsr()
    ds_dmag = ds_dmag.tocsr()
    j11 = ds_dang[ang_idx][:, ang_idx].real
    j12 = ds_dmag[ang_idx][:, mag_idx].real
    j21 = ds_dang[q_idx][:, ang_idx].imag
    j22 = ds_dmag[q_idx][:, mag_idx].imag
    return sp.bmat([[j11, j12], [j21, j22]], format="csc")


@dataclass
class _State:
    """Mutable Newton state (PST's working vectors)."""

    vmag: np.ndarray
    vang: np.ndarray
    pg: np.ndarray
    qg: np.ndarray
    pl: np.ndarray
    ql: np.ndarray
    kind: np.ndarray
    #: +1 held at qmax, -1 at qmin, 0 not held (`_apply_q_limits`)
    held: np.ndarray
    #: remote regulation groups (empty arrays without)
    remote: _Remote


@dataclass
class _Remote:
    """Remote regulation in a solve: member generator buses (rows ``gen``, of group
    ``group``, RMPCT ``share``) and per group the regulated bus row ``reg``, its set point
    ``vset`` and the unknown reactive generation ``q`` (pu) the members share."""

    gen: np.ndarray
    group: np.ndarray
    share: np.ndarray
    reg: np.ndarray
    vset: np.ndarray
    q: np.ndarray

    @classmethod
    def of(cls, case: Case) -> _Remote:
        """The groups of ``case.remote_regulation``, ``q`` started at the members' data."""
        rr = case.remote_regulation
        regulated, group = np.unique(rr.regulated, return_inverse=True)
        gen = case.bus_indices(rr.bus) if len(rr) else np.zeros(0, int)
        q = np.zeros(regulated.size)
        np.add.at(q, group, case.buses.qgen[gen])
        vset = np.zeros(regulated.size)
        vset[group] = rr.vset
        reg = case.bus_indices(regulated) if regulated.size else np.zeros(0, int)
        return cls(gen, group, rr.share.copy(), reg, vset, q)

    def active(self, kind: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(members still regulating, groups with a member still regulating), bool."""
        on = kind[self.gen] == _REMOTE
        groups = np.zeros(self.reg.size, bool)
        groups[self.group[on]] = True
        return on, groups

    def shares(self, on: np.ndarray) -> np.ndarray:
        """Each regulating member's share among its group's regulating members."""
        total = np.zeros(self.reg.size)
        np.add.at(total, self.group[on], self.share[on])
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(on, self.share / total[self.group], 0.0)


def _hold_remote(st: _State) -> None:
    """Regulated buses of active groups at their set points, members' Q from the groups."""
    r = st.remote
    on, groups = r.active(st.kind)
    st.vmag[r.reg[groups]] = r.vset[groups]
    st.qg[r.gen[on]] = (r.shares(on) * r.q[r.group])[on]


def _mismatch(ybus, st: _State):
    """(dP, dQ, S) with dP zero at swing buses and dQ zero at swing and PV buses."""
    s = power_injections(ybus, st.vmag * np.exp(1j * st.vang))
    dp = st.pg - st.pl - s.real
    dq = st.qg - st.ql - s.imag
    dp[st.kind == SWING] = 0.0
    dq[(st.kind != PQ) & (st.kind != _REMOTE)] = 0.0
    return dp, dq, s


def _norm(dp, dq) -> float:
    return float(np.max(np.abs(dp), initial=0.0) + np.max(np.abs(dq), initial=0.0))


def _apply_q_limits(st: _State, s, qmax, qmin) -> bool:
    """PST ``chq_lim``: PV buses outside [qmin, qmax] become PQ at the limit (a remote
    regulating bus likewise leaves its group). True if any."""
    pv = st.kind == PV
    st.qg[pv] = s.imag[pv] + st.ql[pv]
    gen = pv | (st.kind == _REMOTE)
    over = gen & (st.qg > qmax)
    under = gen & (st.qg < qmin)
    for mask, lim, side in ((over, qmax, 1), (under, qmin, -1)):
        st.qg[mask] = 0.0
        st.ql[mask] -= lim[mask]
        st.kind[mask] = PQ
        st.held[mask] = side
    return bool(np.any(over | under))


def _release_wrong_side(case: Case, st: _State) -> bool:
    """Buses held at a Q limit whose voltage ended on the side the limit cannot explain
    (at qmax above, at qmin below the set point) become PV again at their set point
    (PSS/E's and PowerWorld's back-off; PST's ``chq_lim`` switches once, for good).
    True if any did."""
    b = case.buses
    r = st.remote
    vset, v = b.vmag.copy(), st.vmag.copy()  # a remote member's set point is its group's
    vset[r.gen], v[r.gen] = r.vset[r.group], st.vmag[r.reg[r.group]]
    back = ((st.held == 1) & (v > vset + _BACKOFF_DV)) | (
        (st.held == -1) & (v < vset - _BACKOFF_DV)
    )
    remote = np.zeros(back.size, bool)
    remote[r.gen] = True
    st.kind[back] = np.where(remote[back], _REMOTE, PV)
    st.held[back] = 0
    st.ql[back] = b.qload[back]
    st.qg[back] = b.qgen[back]
    local = back & ~remote
    st.vmag[local] = b.vmag[local]
    _hold_remote(st)
    return bool(back.any())


def _newton(case, ybus, st: _State, tol, max_iter, q_limits):
    """Newton iterations in place on ``st``.

    Returns (iterations, mismatch norm, S, converged, dP, dQ). A singular Jacobian or a
    non-finite step raises :class:`PowerFlowError` at once; running out of iterations
    does not (PST then tries its tap changer before giving up).  With ``q_limits``, a
    converged solution whose held buses sit on the wrong side of their set points
    releases them and iterates on (`_release_wrong_side`, at most `_BACKOFF_ROUNDS`).
    """
    limits = _limits(case)
    it = 0
    for _ in range(_BACKOFF_ROUNDS + 1):
        it, dp, dq, s = _iterate(case, ybus, st, tol, max_iter, q_limits, it, limits)
        if _norm(dp, dq) > tol or not q_limits or not _release_wrong_side(case, st):
            break
    mism = _norm(dp, dq)
    return it, mism, s, mism <= tol, dp, dq


def _iterate(case, ybus, st: _State, tol, max_iter, q_limits, it: int, limits):
    """Newton steps in place on ``st`` until converged or ``max_iter`` in all, ``limits``
    as `_limits`; returns (iterations so far, dP, dQ, S)."""
    qmax, qmin, vmax, vmin = limits
    _hold_remote(st)
    dp, dq, s = _mismatch(ybus, st)
    while _norm(dp, dq) > tol and it < max_iter:
        it += 1
        ang_idx, mag_idx, q_idx, groups = _unknowns(st)
        jac = _remote_columns(
            jacobian(ybus, st.vmag * np.exp(1j * st.vang), ang_idx, mag_idx, q_idx),
            st,
            ang_idx.size,
            q_idx,
            groups,
        )
        rhs = np.concatenate([dp[ang_idx], dq[q_idx]])
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("error", spla.MatrixRankWarning)
                dx = spla.splu(jac).solve(rhs)
        except (RuntimeError, spla.MatrixRankWarning):
            _fail(case, it, dp, dq, "singular Jacobian (islanded bus or voltage collapse)")
        if not np.all(np.isfinite(dx)):
            _fail(case, it, dp, dq, "non-finite Newton step")
        n_va = ang_idx.size + mag_idx.size
        st.vang[ang_idx] += dx[: ang_idx.size]
        st.vmag[mag_idx] += dx[ang_idx.size : n_va]
        st.remote.q[groups] += dx[n_va:]
        np.clip(st.vmag, vmin, vmax, out=st.vmag)
        _hold_remote(st)
        dp, dq, s = _mismatch(ybus, st)
        if q_limits and _apply_q_limits(st, s, qmax, qmin):
            _hold_remote(st)
            dp, dq, s = _mismatch(ybus, st)
    return it, dp, dq, s


def _unknowns(st: _State):
    """(angle buses, magnitude buses, Q-balance buses, active remote groups): a regulated
    bus of an active group keeps its Q balance but not its magnitude (the group's Q takes
    its place)."""
    ang_idx = np.flatnonzero(st.kind != SWING)
    q_buses = (st.kind == PQ) | (st.kind == _REMOTE)
    _, groups = st.remote.active(st.kind)
    fixed = np.zeros(q_buses.size, bool)
    fixed[st.remote.reg[groups]] = True
    return ang_idx, np.flatnonzero(q_buses & ~fixed), np.flatnonzero(q_buses), groups


def _remote_columns(jac, st: _State, n_ang: int, q_idx, groups):
    """The Jacobian with one column per active remote group: d(mismatch)/d(group Q) is
    minus each regulating member's share in its Q-balance row."""
    if not groups.any():
        return jac
    r = st.remote
    on, _ = r.active(st.kind)
    row_of = np.full(st.kind.size, -1)
    row_of[q_idx] = n_ang + np.arange(q_idx.size)
    col_of = np.cumsum(groups) - 1
    rows = row_of[r.gen[on]]
    extra = sp.csc_matrix(
        (-r.shares(on)[on], (rows, col_of[r.group[on]])), shape=(jac.shape[0], int(groups.sum()))
    )
    return sp.hstack([jac, extra], format="csc")


def _fail(case, it, dp, dq, what):
    worst = int(np.argmax(np.maximum(np.abs(dp), np.abs(dq))))
    raise PowerFlowError(
        f"power flow of case '{case.name}' {what} after {it} iteration(s): "
        f"worst mismatch {max(abs(dp[worst]), abs(dq[worst])):.3g} pu at bus "
        f"{int(case.buses.number[worst])} (max|dP|+max|dQ| = {_norm(dp, dq):.3g})"
    )


def _branch_rows(case: Case, drop) -> tuple:
    """`drop` as a tuple of ints: 0-based rows of ``case.branches`` (WrongTypeError for a
    text, a number or an item that is no whole number, such as a (from, to) pair)."""
    rows = require_items(drop, "solve_powerflow(drop)", "a list of 0-based branch rows")
    odd = [r for r in rows if not is_whole_number(r)]
    if odd:
        raise WrongTypeError(
            f"solve_powerflow(drop): 0-based rows of the branch table (ints; a line by its "
            f"buses: case.circuit_row(from_bus, to_bus)), got {odd[0]!r}"
        )
    return tuple(int(r) for r in rows)


def _check_islands(case: Case, drop=()) -> None:
    """PowerFlowError naming the buses without a path to a swing bus (an island of the
    case data, or left by the dropped branches): the Newton step would only report a
    singular Jacobian and the worst mismatch somewhere else."""
    keep = case.branches.x < OPEN_X / 10  # PST's opened branches join nothing
    keep[[d for d in drop if 0 <= d < keep.size]] = False
    dead = dead_buses(case, keep)
    if dead.size:
        nums = [int(b) for b in case.buses.number[dead]]
        listing = ", ".join(map(str, nums[:10])) + (
            f" and {len(nums) - 10} more" if len(nums) > 10 else ""
        )
        cause = (
            "the dropped branch(es)"
            if drop
            else "the case data (no branch joins them; the import commands' "
            "--leave-out-islands, stabctl.network.topology.without_dead_islands, "
            "disconnects such islands as PSS/E's isolated buses)"
        )
        raise PowerFlowError(
            f"power flow of case '{case.name}': bus(es) {listing} have no "
            f"path to a swing bus: an island left by {cause}"
        )


def _note_shared_swing(case: Case) -> None:
    """A UserWarning naming the swing buses that share an island of the case's network:
    the Newton step holds every swing bus at its magnitude and angle (no P or Q equation
    of its own), so each generates what balances the flow at its fixed angle, as PSS/E's
    power flow does with several type-3 buses in one island; legitimate, but seldom meant
    (one slack is the usual case), so said, never silent."""
    sw = case.swing_index
    if sw.size < 2:
        return
    label = bus_islands(case)[sw]
    for island in np.unique(label):
        nums = [int(b) for b in case.buses.number[sw[label == island]]]
        if len(nums) > 1:
            listed = ", ".join(map(str, nums[:-1])) + f" and {nums[-1]}"
            warnings.warn(
                f"case '{case.name}': buses {listed} are "
                + ("both" if len(nums) == 2 else "all")
                + " swing buses (kind 1) of one "
                "island: the power flow holds each at its voltage magnitude and angle, each "
                "generating what balances the flow there (as PSS/E does with several type-3 "
                "buses); make all but one PV buses (kind 2) for a single slack",
                UserWarning,
                stacklevel=3,
            )


def _move_taps(case: Case, vmag, taps) -> bool:
    """PST ``lftap``: step the taps of branches feeding a bus at a voltage limit.

    Returns True if a tap moved (PST also solves again when a voltage sits at a limit
    but no tap can move; that repeats the same solution, so we stop instead).
    """
    br = case.branches
    _, _, vmax, vmin = _limits(case)
    high = vmag >= vmax
    low = vmag <= vmin
    if not (high.any() or low.any()):
        return False
    old = taps.copy()
    to_idx = case.bus_indices(br.to_bus)
    adj = br.tapmax != 0
    for k in np.flatnonzero(adj & (high[to_idx] | low[to_idx])):
        i, step, tmin, tmax = to_idx[k], br.tapstep[k], br.tapmin[k], br.tapmax[k]
        if high[i]:
            err = (vmag[i] - vmax[i]) / vmax[i]
            tap = (
                taps[k] + step
                if err < step
                else (np.ceil((taps[k] + err - tmin) / step) * step + tmin)
            )
        else:
            err = (vmin[i] - vmag[i]) / vmin[i]
            tap = (
                taps[k] - step
                if err < step
                else (np.fix((taps[k] - err - tmin) / step) * step + tmin)
            )
        taps[k] = min(tmax, max(tap, tmin))
    return bool(np.any(taps != old))


def _initial_state(case: Case, start=None) -> tuple[_State, np.ndarray, np.ndarray]:
    """Start state from the bus table or `start` (voltage magnitudes, pu, and angles,
    rad: arrays of shape (n_bus,)), and the fixed injections per bus (P, Q)."""
    b = case.buses
    inj_p = np.zeros(case.n_bus)
    inj_q = np.zeros(case.n_bus)
    if len(case.injections):
        idx = case.bus_indices(case.injections.bus)
        np.add.at(inj_p, idx, case.injections.p)
        np.add.at(inj_q, idx, case.injections.q)
    return (
        _State(
            vmag=(b.vmag if start is None else start[0]).copy(),
            vang=np.deg2rad(b.vang_deg) if start is None else start[1].copy(),
            pg=b.pgen + inj_p,
            qg=b.qgen + inj_q,
            pl=b.pload.copy(),
            ql=b.qload.copy(),
            kind=_remote_kind(case),
            held=np.zeros(case.n_bus, int),
            remote=_Remote.of(case),
        ),
        inj_p,
        inj_q,
    )


def _remote_kind(case: Case) -> np.ndarray:
    """The bus table's kinds with remote regulating buses marked `_REMOTE`."""
    kind = case.buses.kind.astype(int)
    if len(case.remote_regulation):
        kind[case.bus_indices(case.remote_regulation.bus)] = _REMOTE
    return kind


def _report(case: Case, st: _State, s, inj_p, inj_q):
    """PST's end-of-loadflow bookkeeping: (pgen, qgen, pload, qload, q_limited)."""
    b = case.buses
    pg, qg, pl, ql = st.pg.copy(), st.qg.copy(), st.pl.copy(), st.ql.copy()
    gen = (st.kind == PV) | (st.kind == _REMOTE)
    pg[gen] = s.real[gen] + pl[gen]
    qg[gen] = s.imag[gen] + ql[gen]
    limited = (b.kind == PV) & ~gen
    qg[limited] -= ql[limited] - b.qload[limited]  # back to the limit value
    ql[limited] = b.qload[limited]
    load = st.kind == PQ
    pl[load] = pg[load] - s.real[load]
    ql[load] = qg[load] - s.imag[load]
    sw = st.kind == SWING
    pg[sw] = s.real[sw] + pl[sw]
    qg[sw] = s.imag[sw] + ql[sw]
    return pg - inj_p, qg - inj_q, pl, ql, limited


def solve_powerflow(
    case: Case,
    *,
    tol: float = 1e-8,
    max_iter: int = 50,
    q_limits: bool = True,
    tap_changing: bool = True,
    drop=(),
) -> PowerFlowResult:
    """Solve the AC power flow of ``case`` (Newton-Raphson, polar, PST conventions).

    Parameters
    ----------
    case : Case
        The case; start values from its bus table.
    tol : float, optional
        Convergence tolerance on ``max|dP| + max|dQ|``, pu on the system base (PSTess
        ``s_simu``: 1e-8).
    max_iter : int, optional
        Newton iterations allowed per solve (PSTess: 50).
    q_limits : bool, optional
        Apply PV -> PQ switching at generator Q limits (PST ``chq_lim``).
    tap_changing : bool, optional
        Move on-load taps of branches with ``tapmax != 0`` (PST ``lftap``).
    drop : iterable of int, optional
        0-based rows of ``case.branches`` out of service; empty by default.

    Returns
    -------
    PowerFlowResult
        The solution: bus voltages (pu, rad), generation and load per bus (pu on the
        system base), arrays of shape (n_bus,) in ``case.buses`` order.

    Raises
    ------
    PowerFlowError
        No convergence within ``max_iter`` iterations or a singular Jacobian (the message
        names the iteration count and the bus with the worst mismatch), or buses with no
        path to a swing bus (an island of the case data, or left by ``drop``).
    CaseError
        A dropped branch row does not exist.
    InputError
        ``tol`` not in (0, 1) or ``max_iter`` not an int >= 1.
    TypeError
        ``case`` is not a `Case` (`stabctl.case.require_case`); ``tol`` not a number or
        ``drop`` not a list of row numbers (`stabctl.errors.WrongTypeError`).

    Warns
    -----
    RuntimeWarning
        Voltages still at their limits after the last allowed tap-changer iteration; the
        flow solved from a flat start after failing from the case's voltages.

    Notes
    -----
    Switched shunts (``case.switched_shunts``) are stepped one level at a time toward
    their voltage bands, the flow solved again after each step
    (`stabctl.network.switched_shunts`; ANDES 2.0 ShuntSw), their levels in the result.

    Source: PSTess ``loadflow.m``, ``calc.m``, ``form_jac.m``, ``chq_lim.m``, ``lftap.m``;
    PST manual section 1.4.
    """
    case = require_case(case, "solve_powerflow(case)")
    require_number(tol, "solve_powerflow(tol)", "pu")
    if not (0 < tol < 1 and isinstance(max_iter, Integral) and max_iter >= 1):
        raise InputError(  # max_iter 0 was "no convergence within 0 iterations"
            f"solve_powerflow: tol must be in (0, 1) pu and max_iter an int >= 1, got tol "
            f"{tol!r}, max_iter {max_iter!r}"
        )
    drop = _branch_rows(case, drop)
    _check_islands(case, drop)
    _note_shared_swing(case)
    settings = (tol, max_iter, q_limits, tap_changing, drop)
    try:
        sol = _solve(case, settings)
    except PowerFlowError as exc:  # run again from a flat start
        sol = _from_flat_start(case, settings, exc)
    st, s, inj_p, inj_q, iters, mism, taps, tap_it, levels = sol
    if tap_changing and tap_it == _TAP_ITER_MAX and _move_taps(case, st.vmag, taps.copy()):
        warnings.warn(
            f"power flow of case '{case.name}': voltages still at limits after "
            f"{_TAP_ITER_MAX} tap iterations",
            RuntimeWarning,
            stacklevel=2,
        )
    pg, qg, pl, ql, limited = _report(case, st, s, inj_p, inj_q)
    return PowerFlowResult(
        case=case,
        vmag=st.vmag,
        vang=st.vang,
        pgen=pg,
        qgen=qg,
        pload=pl,
        qload=ql,
        kind=np.where(st.kind == _REMOTE, PV, st.kind),
        q_limited=limited,
        iterations=iters,
        max_mismatch=mism,
        taps=taps,
        tap_iterations=tap_it,
        dropped=drop,
        shunt_levels=levels,
    )


def _solve(case, settings: tuple, start=None) -> tuple:
    """Newton with the switched shunts' and the taps' outer loops, `settings` (tol,
    max_iter, q_limits, tap_changing, drop), from the bus table's voltages or `start`
    (`_initial_state`): (state, S, fixed injections P and Q,
    iterations, mismatch, taps, tap iterations, shunt levels).  Raises PowerFlowError
    when it does not converge."""
    tol, max_iter, q_limits, tap_changing, drop = settings
    taps = case.branches.tap.copy()
    taps[taps == 0] = 1.0
    sw = case.switched_shunts
    levels = sws.initial_levels(sw)
    sw_bus = case.bus_indices(sw.bus) if len(sw) else np.zeros(0, int)
    for tap_it in range(1, _TAP_ITER_MAX + 1):
        base = build_ybus(case, drop=drop, taps=taps)
        for _ in range(sws.MAX_ROUNDS):  # the switched shunts' steps: the branches as they are
            ybus = add_shunts(base, sw_bus, sws.admittances(sw, levels))
            st, inj_p, inj_q = _initial_state(case, start)
            iters, mism, s, converged, dp, dq = _newton(case, ybus, st, tol, max_iter, q_limits)
            if not (converged and sws.step(sw, levels, st.vmag[sw_bus])):
                break
        if not (tap_it < _TAP_ITER_MAX and tap_changing and _move_taps(case, st.vmag, taps)):
            break
    if not converged:
        _fail(case, iters, dp, dq, "did not converge")
    return st, s, inj_p, inj_q, iters, mism, taps, tap_it, levels


def _from_flat_start(case: Case, settings: tuple, failed: PowerFlowError) -> tuple:
    """`_solve` again, with the same settings, from a flat start (PQ buses at 1 pu, every
    angle the first swing bus's) after `failed` from the bus table's voltages (a bus
    added or reconnected with a voltage no solution is near, whose first iterate the
    magnitude limits then clip for good), with a warning that says so; failing again,
    the first failure with that said and the hint of `_without_limits_hint`."""
    b = case.buses
    _, _, q_limits, _, drop = settings
    flat = (np.where(b.kind == PQ, 1.0, b.vmag), _flat_angles(case, drop))
    try:
        sol = _solve(case, settings, flat)
    except PowerFlowError:
        raise PowerFlowError(
            f"{failed} (from the case's own voltages; from a flat start, 1 pu at the "
            f"swing bus's angle and the phase shifts, it did not converge either)"
            f"{_without_limits_hint(case, q_limits, drop)}"
        ) from None
    warnings.warn(
        f"{failed} from the case's own voltages; solved from a flat start instead (1 pu "
        "at the swing bus's angle and the phase shifts, PV buses at their set points)",
        RuntimeWarning,
        stacklevel=3,
    )
    return sol


def _flat_angles(case: Case, drop) -> np.ndarray:
    """A flat start's bus angles (n_bus,) rad: the first swing bus's, plus the phase
    shifts of the transformers on the way to each bus (a tree of the branches not in
    `drop`, breadth first from the swing buses; PSS/E's flat start "with phase shift
    angles").  Round 47: a radial 30-degree phase shifter's bus started 30 degrees off
    its solution, where Newton went to a spurious low-voltage one: refused as not
    converging, a case PSS/E solves."""
    from scipy.sparse.csgraph import breadth_first_order

    b, br = case.buses, case.branches
    swing = np.flatnonzero(b.kind == SWING)
    angles = np.full(case.n_bus, np.deg2rad(b.vang_deg[swing[:1]].sum()))
    shift = np.deg2rad(br.phase_deg)  # unloaded, V_to leads V_from by it (`build_ybus`)
    keep = np.ones(len(br), bool)
    keep[list(drop or ())] = False
    if not shift[keep].any():
        return angles
    f, t = case.bus_indices(br.from_bus)[keep], case.bus_indices(br.to_bus)[keep]
    step = {**dict(zip(zip(t, f), -shift[keep])), **dict(zip(zip(f, t), shift[keep]))}
    graph = sp.coo_matrix((np.ones(f.size), (f, t)), shape=(case.n_bus,) * 2).tocsr()
    seen = np.zeros(case.n_bus, bool)
    for root in swing:
        if seen[root]:
            continue
        order, pred = breadth_first_order(graph, root, directed=False)
        seen[order] = True
        for n in order[1:]:
            angles[n] = angles[pred[n]] + step[(pred[n], n)]
    return angles


def _without_limits_hint(case: Case, q_limits: bool, drop) -> str:
    """With Q limits on, whether the flow converges without them (ANDES solves its cases
    so, pv2pq = 0): said after the failure, not done in its place."""
    if not q_limits:
        return ""
    try:
        solve_powerflow(case, q_limits=False, drop=drop)
    except PowerFlowError:
        return ""
    return (
        "; with the PV buses' Q limits off it converges ("
        + advice("q_limits=False", "--no-q-limits of the commands that run a case")
        + ": ANDES's default, pv2pq = 0)"
    )


def scale_load(case: Case, factor: float, *, q_limits: bool = True) -> Case:
    """The case at another load level: every bus load (P and Q) and every generator's
    dispatch P scaled by `factor`, the power flow re-solved (the swing bus takes the
    losses).

    Parameters
    ----------
    case : Case
        The base case (its bus table's ``pload``, ``qload`` and ``pgen``, pu).
    factor : float
        Load level, fraction of the base load (e.g. 1.1 for 110 %), > 0.
    q_limits : bool, optional
        PV Q limits in the re-solved power flow (as `solve_powerflow`); default True.

    Returns
    -------
    Case
        A new case named ``"<name>@<factor>"`` with the scaled loads and dispatch, whose
        power flow was solved here (a `Simulator` built on it solves it again from the
        same data and starts from the scaled operating point).  ``factor == 1`` returns
        `case` unchanged.

    Raises
    ------
    InputError
        factor not > 0 (or not finite).
    PowerFlowError
        The scaled power flow does not converge; the message names the load level.

    Notes
    -----
    Dispatch: every PV bus's generation is scaled by `factor`, but no bus beyond the
    largest power order of its governors (``Tmax`` times the machine MVA, less 2 % for
    the losses); what a capped bus cannot take is shared by the others in proportion to
    their dispatch (the total scaled by `factor` whenever the headroom allows).  Fixed
    injections (`Case.injections`) and shunts are not scaled; a PST case that books an
    HVDC set point as a bus load (miniWECC's ``PDC``) scales it with the load.
    """
    from stabctl.errors import InputError

    factor = float(factor)
    if not (np.isfinite(factor) and factor > 0):
        raise InputError(f"load level must be a number > 0, got {factor:g}")
    if factor == 1.0:
        return case
    b = case.buses
    scaled = case.replace(
        name=f"{case.name}@{factor:g}",
        buses=b.replace(
            pload=b.pload * factor, qload=b.qload * factor, pgen=_dispatch(case, factor)
        ),
    )
    try:
        solve_powerflow(scaled, q_limits=q_limits)
    except PowerFlowError as exc:
        raise PowerFlowError(
            f"{advice('load level', '--load-levels')} {factor:g} ({100 * factor:g} % of the "
            f"base load of case '{case.name}'): {exc}"
        ) from None
    return scaled


def _dispatch(case: Case, factor: float) -> np.ndarray:
    """Generation P per bus (pu) scaled by factor, capped at the governors' power orders
    and the rest shared in proportion (`scale_load`)."""
    b = case.buses
    pg = b.pgen * factor
    cap = np.full(len(pg), np.inf)
    g, m = case.governors, case.machines
    for k, tmax in zip(g.machine, g.Tmax):
        i = case.bus_index(m.bus[case.machine_index(k)])
        mva = float(m.mva[case.machine_index(k)])
        cap[i] = (0.0 if not np.isfinite(cap[i]) else cap[i]) + 0.98 * tmax * mva / case.base_mva
    pv = b.kind == PV
    want = float(pg[pv].sum())
    for _ in range(len(pg)):
        over = pv & (pg > cap)
        if not over.any():
            break
        pg[over] = cap[over]
        free = pv & (pg < cap) & (pg > 0)
        short = want - float(pg[pv].sum())
        if not free.any() or short <= 0:
            break
        pg[free] += short * pg[free] / pg[free].sum()
    return pg
