"""Network solution of the dynamic simulation: Kron-reduced admittance matrices per network
stage and the non-conforming (constant-P / constant-I) load iteration.

Source: PSTess 1.1 `red_ybus.m`, `i_simu.m`, `nc_load.m`; docs/pst_models.md sections 5-6.
Each machine is an internal node (voltage psi from `stabctl.models.machines.internal_voltage`)
behind its admittance; constant-impedance loads sit in Ybus; buses with non-conforming load
or an injection (storage) are kept, all other buses are eliminated:

    I_mac = Y11 psi + Y12 V_nc,      I_nc(V_nc) = Y21 psi + Y22 V_nc,
    V_bus = R @ [psi; V_nc]          (every original bus),

with I_nc the current injected at the kept buses by their loads and devices.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

import llvmlite.binding as llvm
import numpy as np
import scipy.linalg as la
import scipy.sparse.linalg as spla
from numba import types
from numba.extending import get_cython_function_address

from stabctl._jit.arrays import assign, matvec, max_abs
from stabctl._jit.decorators import kernel
from stabctl.case import Case
from stabctl.errors import SimulationError
from stabctl.network import lowrank
from stabctl.network.ybus import build_ybus

V_SWITCH = 0.5  # below this voltage PST turns non-conforming loads into impedances
V_RELEASE = V_SWITCH + 0.1  # a load held at its impedance model is released above this
#: chord iteration of the kept-bus voltages: converged when a step moves no voltage by
#: more than this (pu)
TOL_V = 1e-11
#: Newton fallback of the kept-bus solution (`_newton_nc`): largest mismatch (pu) and
#: iterations (PST nc_load's)
NEWTON_TOL, NEWTON_MAX_ITER = 1e-10, 50
#: with a converter current sloped in |V|, Newton first up to this many kept buses: its
#: dense LU of order 2 n costs about what 30 chord steps (n^2 each) do at n = 64
NEWTON_FIRST_MAX = 64

# LAPACK's dgesv (scipy's, `scipy.linalg.cython_lapack`) for the kernels, called by symbol
# name: numba links the symbol in each process that loads a kernel calling it, so they stay
# cacheable (a ctypes pointer would not).  np.linalg.solve in a kernel compiled numba's
# copy-in and shape-message code as well: about 3 s of a cold first call.
llvm.add_symbol("stabctl_dgesv", get_cython_function_address("scipy.linalg.cython_lapack", "dgesv"))
_INT, _F8 = types.CPointer(types.intc), types.CPointer(types.float64)
_dgesv = types.ExternalFunction(
    "stabctl_dgesv", types.void(_INT, _INT, _F8, _INT, _INT, _F8, _INT, _INT)
)


@dataclass(frozen=True, eq=False)
class ReducedNetwork:
    """Reduced matrices of one network stage (dense complex, pu on the system base).

    Y11 (n_mac, n_mac), Y12 (n_mac, n_nc), Y21 (n_nc, n_mac), Y22 (n_nc, n_nc); R (n_bus, n_mac
    + n_nc) gives every original bus voltage from [psi; V_nc] (a stage updated from the
    pre-event network's reduction keeps it as a `stabctl.network.lowrank.LowRankRows`,
    its rows formed when read); Z22 = inv(Y22), the chord of the
    load iteration; R_mac (n_mac, n_mac + n_nc), R's rows of the machines' buses (one per
    machine, in machine order: their terminal voltages); Z_mac (n_mac,) each machine's internal
    impedance 1 / y_mac in this stage (0 for a tripped machine), with which V_term = psi - Z_mac
    I_mac gives the same terminal voltages in O(n_mac). switched_on (n_dev,) float: 1.0 for each
    device switched by events (a motor, `stabctl.models.motors`, then a converter, tripped by a
    `ConverterTrip`) in service in this stage, else 0.0; targets (n_mac, 2) float: each
    playback source's targets of E' and speed in this stage
    (pu; `stabctl.models.machines`, the ``playback`` column); steps (n_exc + n_tg,) float: each
    exciter's VREF change (pu), then each governor's PREF change (pu on its machine's base) in
    this stage (VrefStep / PrefStep events; empty: none); islanded: (bus number, load P + jQ
    shed, pu system base) of each bus the stage cuts from every machine, de-energised (PSS/E's
    islanding: its load and shunts shed, its voltage 0); bus_island (n_bus,) int: each bus's
    island in this stage's network (`stabctl.network.topology.bus_islands`; empty: not
    computed); machine_island (n_mac,) int: the island of each machine's bus, -1 for a
    tripped machine (empty: not computed); faulted: whether a fault is on in this stage (a
    bus fault, or a line fault fed from an end still closed).
    """

    Y11: np.ndarray
    Y12: np.ndarray
    Y21: np.ndarray
    Y22: np.ndarray
    R: np.ndarray | lowrank.LowRankRows
    Z22: np.ndarray
    R_mac: np.ndarray
    Z_mac: np.ndarray
    switched_on: np.ndarray = field(default_factory=lambda: np.zeros(0))
    targets: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    steps: np.ndarray = field(default_factory=lambda: np.zeros(0))
    islanded: tuple = ()
    bus_island: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    machine_island: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    factor: lowrank.SparseReduction | None = None
    faulted: bool = False


def external_impedance(net: ReducedNetwork, rows: np.ndarray) -> np.ndarray:
    """The impedance (pu, system base) each machine of `rows` sees from its terminal in
    stage `net`, the other machines' internal voltages held (shorted): from the stage's
    driving-point admittance at its internal node, Y11 - Y12 Z22 Y21, its own internal
    impedance Z_mac taken off; 0 at a bolted fault at its terminal, nan for a tripped
    machine.

    Parameters
    ----------
    net : ReducedNetwork
        The stage.
    rows : ndarray of int
        Machine rows.

    Returns
    -------
    ndarray of complex, shape (len(rows),)
    """
    rows = np.asarray(rows, int)
    y = np.diag(net.Y11)[rows].astype(complex)
    if net.Y22.size:
        y = y - np.einsum("ij,ji->i", net.Y12[rows] @ net.Z22, net.Y21[:, rows])
    with np.errstate(divide="ignore", invalid="ignore"):
        z = 1.0 / y - net.Z_mac[rows]
    return np.where(net.Z_mac[rows] != 0, z, np.nan)


def reduce_network(
    case: Case,
    y_shunt: np.ndarray,
    y_mac: np.ndarray,
    mac_bus: np.ndarray,
    mac_online: np.ndarray,
    nc_idx: np.ndarray,
    n_bus_orig: int,
    base: lowrank.SparseReduction | None = None,
) -> ReducedNetwork:
    """Kron-reduce the network of `case` (a stage variant, possibly with extra fault buses).

    Args:
        case: the stage's case (branches and bus shunts as modified for the stage).
        y_shunt: extra shunt admittance per bus of `case` (constant-impedance loads), (n_bus,).
        y_mac: machine internal admittances (system base), (n_mac,); mac_bus their bus indices.
        mac_online: False for tripped machines (their node is disconnected).
        nc_idx: indices of the kept buses; n_bus_orig: number of buses of the base case
            (buses beyond it are stage-only fault nodes, not reported).
        base: above `DENSE_MAX`, the pre-event network's reduction (its
            `ReducedNetwork.factor`): a stage that changes a few of its nodes is updated
            from it (`stabctl.network.lowrank`) instead of factorised again.
    Raises:
        SimulationError: the eliminated part of the network is singular (an island with no
            path to ground or a machine).
    """
    n_mac, n_bus = y_mac.size, case.n_bus
    y = np.where(mac_online, y_mac, 0.0)
    N = n_mac + n_bus
    keep = np.concatenate([np.arange(n_mac), n_mac + np.asarray(nc_idx, int)])
    elim = np.setdiff1d(np.arange(N), keep)
    if N <= DENSE_MAX:  # LAPACK's dense LU: the reduction PSTess's red_ybus.m makes
        full = _augmented_dense(build_ybus(case).toarray(), y_shunt, y, mac_bus, mac_online)
        Ykk, Yke = full[np.ix_(keep, keep)], full[np.ix_(keep, elim)]
        Yek, Yee = full[np.ix_(elim, keep)], full[np.ix_(elim, elim)]
        try:
            lu = la.lu_factor(Yee, check_finite=True)
            rec = -la.lu_solve(lu, Yek)  # eliminated voltages from kept ones
        except (la.LinAlgError, ValueError) as exc:
            raise SimulationError(
                f"singular network in stage of case '{case.name}': {exc}"
            ) from exc
        Yred, factor = Ykk + Yke @ rec, None
    else:  # a sparse LU of the eliminated part: memory in the kept columns only
        full = _augmented(build_ybus(case), y_shunt, y, mac_bus, mac_online).tocsr()
        got = None if base is None else lowrank.updated(base, full, keep, elim)
        if got is None:
            factor = _sparse_reduction(full, keep, elim, case.name)
            rec, Yred = factor.rec, factor.Yred
        else:
            (rec, Yred), factor = got, None
    finite = rec.all_finite() if isinstance(rec, lowrank.LowRankRows) else np.isfinite(rec).all()
    if not finite:  # every path's check, before any stage is kept
        raise SimulationError(f"singular network (island without a source) in case '{case.name}'")
    if len(nc_idx):
        R = np.zeros((n_bus, keep.size), complex)
        R[np.asarray(nc_idx, int), n_mac + np.arange(len(nc_idx))] = 1.0
        R[elim - n_mac] = np.asarray(rec)  # every internal node is kept: the eliminated are buses
    else:  # every bus eliminated, in order: R is rec (10.7 MB on ACTIVSg2000, not copied;
        R = rec  # an updated stage's in low-rank form, `lowrank.LowRankRows`)
    c = np.ascontiguousarray
    Y22 = c(Yred[n_mac:, n_mac:])
    return ReducedNetwork(
        Y11=c(Yred[:n_mac, :n_mac]),
        Y12=c(Yred[:n_mac, n_mac:]),
        Y21=c(Yred[n_mac:, :n_mac]),
        Y22=Y22,
        R=R[:n_bus_orig] if isinstance(R, lowrank.LowRankRows) else c(R[:n_bus_orig]),
        Z22=c(np.linalg.inv(Y22)) if Y22.size else Y22.copy(),
        R_mac=c(R[np.asarray(mac_bus, int)]),  # formed rows of a LowRankRows
        Z_mac=np.divide(1.0, y, out=np.zeros(n_mac, complex), where=y != 0),
        factor=factor,
    )


def _sparse_reduction(full, keep, elim, name: str) -> lowrank.SparseReduction:
    """The sparse LU reduction of `full` (CSR) onto `keep` (SuperLU of the eliminated
    part); SimulationError when SuperLU finds that part singular (`reduce_network` checks
    the result for an island without a source)."""
    a_ke = full[keep][:, elim]
    try:
        lu = spla.splu(full[elim][:, elim].tocsc())
        rec = -lu.solve(full[elim][:, keep].toarray())
    except RuntimeError as exc:  # "Factor is exactly singular"
        raise SimulationError(f"singular network in stage of case '{name}': {exc}") from exc
    Yred = full[keep][:, keep].toarray() + a_ke @ rec
    return lowrank.SparseReduction(full, keep, elim, lu, rec, Yred, a_ke)


#: largest order (machines + buses) of a network reduced with a dense LU (LAPACK's, as
#: PSTess's red_ybus.m: Kundur, miniWECC and the ANDES cases stay bit for bit); above it
#: the eliminated part is factorised sparse (SuperLU): memory in the kept buses only (a
#: dense LU of order 10 400 took 1.7 GB) and a tenth of the time at planning size
#: (ACTIVSg2000, order 2 334: a fault's stages in 0.26 s instead of 2.5 s, trajectories
#: within 1.3e-13 rad of the dense reduction's; every CCT search and screening of a new
#: fault builds them).
DENSE_MAX = 1000


def _augmented_dense(Y, y_shunt, y, mac_bus, mac_online) -> np.ndarray:
    """`_augmented` as a dense array from the dense Ybus Y (changed in place), summed in
    PSTess's order (Ybus, then the shunts, then the machines)."""
    n_mac, n_bus = y.size, Y.shape[0]
    Y[np.diag_indices(n_bus)] += y_shunt
    np.add.at(Y, (mac_bus, mac_bus), y)
    full = np.zeros((n_mac + n_bus,) * 2, complex)
    full[n_mac:, n_mac:] = Y
    full[np.arange(n_mac), np.arange(n_mac)] = y
    full[np.arange(n_mac), n_mac + mac_bus] = -y
    full[n_mac + mac_bus, np.arange(n_mac)] = -y
    off = np.nonzero(~np.asarray(mac_online, bool))[0]
    full[off, off] = 1.0
    return full


def _augmented(ybus, y_shunt, y, mac_bus, mac_online):
    """The admittance matrix of the machines' internal nodes (first n_mac rows) and the
    buses, sparse (COO): Ybus with the shunts y_shunt, each machine's admittance y
    between its internal node and its bus; a tripped machine's node grounded (1 on its
    diagonal) so that the matrix stays regular."""
    import scipy.sparse as sp

    n_mac, n_bus = y.size, ybus.shape[0]
    m = np.arange(n_mac)
    off = ~np.asarray(mac_online, bool)
    rows = np.concatenate([m, m, n_mac + mac_bus, n_mac + mac_bus, n_mac + np.arange(n_bus)])
    cols = np.concatenate([m, n_mac + mac_bus, m, n_mac + mac_bus, n_mac + np.arange(n_bus)])
    vals = np.concatenate([np.where(off, 1.0, y), -y, -y, y, y_shunt]).astype(complex)
    extra = sp.coo_matrix((vals, (rows, cols)), shape=(n_mac + n_bus,) * 2)
    ybus = sp.coo_matrix(ybus)
    grid = sp.coo_matrix((ybus.data, (ybus.row + n_mac, ybus.col + n_mac)), shape=extra.shape)
    return (grid + extra).tocsr()


@dataclass(frozen=True, eq=False)
class NonConformingLoads:
    """Non-conforming part of the loads at the kept buses (PST `nc_load` flag 0), (n_nc,).

    S_P: constant-power part (complex pu); I0: constant-current part as power per pu
    voltage (load power = I0 |V|); Y_low: admittance used below 0.5 pu, (S_P + S_I)*/V0^2.
    """

    S_P: np.ndarray
    I0: np.ndarray
    Y_low: np.ndarray


class LoadRows(NamedTuple):
    """The rows of the kept-bus load array of one network solution (`solve_nc`,
    `kept_loads`), each (n_nc,) complex: the non-conforming loads S_P, I0, Y_low
    (`NonConformingLoads`), the extra constant power S_extra (e.g. storage, dropped below
    0.5 pu with the loads), the converters' currents, affine in the bus voltage magnitude
    |V| (their limits are piecewise linear in it): I_dev + G_dev |V| (power per pu
    voltage, drawn at every voltage at the bus voltage's angle) and I_fix + G_fix |V| (a
    current fixed in the network frame: a converter whose angle comes from a PLL), and
    V_release (real) the voltage above which a load held at its impedance model is released
    (V_RELEASE; `stabctl.dynamics.trapezoid` raises it within a step, so that a load held
    at one iterate stays held for the step).  One array, not a tuple of nine: a compiled
    call costs about 10 ns for every array it is passed (measured), and the load iteration
    calls its helpers every step."""

    S_P: int
    I0: int
    Y_low: int
    S_extra: int
    I_dev: int
    I_fix: int
    G_dev: int
    G_fix: int
    V_release: int


#: the row indices (a module-global constant: folded into the kernels)
L = LoadRows(*range(len(LoadRows._fields)))


def kept_loads(nc: NonConformingLoads) -> np.ndarray:
    """The kept-bus load array of `solve_nc` for the non-conforming loads nc: shape (9,
    n_nc) complex (rows `L`), S_extra and the converter rows 0, V_release V_RELEASE.
    Built once per model
    (`stabctl.dynamics.model.KernelParams.loads`); each evaluation copies it.

    Parameters
    ----------
    nc : NonConformingLoads
        The loads at the kept buses.

    Returns
    -------
    ndarray, shape (9, n_nc), complex
    """
    loads = np.zeros((len(L), nc.S_P.size), complex)
    loads[L.S_P], loads[L.I0], loads[L.Y_low] = nc.S_P, nc.I0, nc.Y_low
    loads[L.V_release] = V_RELEASE
    return loads


def no_solution_hint(case: Case, stage: ReducedNetwork) -> str:
    """Why the network/load equations (`solve_nc`) can lose their solution while a fault is
    on in a case with converters, for the message of a run stopped there; empty otherwise.

    Each converter is a current source whose angle follows its terminal voltage's
    (`kept_loads`' I_dev rows); facing a fault of almost no impedance near it, no terminal
    voltage is in phase with the current it drives through the network, so the equations
    have no solution (ANDES's TDS stops at the same faults: kundur_wtdta1 at buses 4, 9
    and 10).

    Parameters
    ----------
    case : Case
        The case run.
    stage : ReducedNetwork
        The network of the step that failed.

    Returns
    -------
    str
        ``"; ..."`` to append to the message, or ``""``.
    """
    if not len(case.converters) or not stage.faulted:
        return ""
    return (
        "; the case's converters are current sources turning with their terminal voltage, "
        "and facing a fault of almost no impedance near them the network equations can "
        "have no solution (ANDES stops there too): a fault through an impedance (simulate "
        "--bus-fault BUS:R:X T_ON T_OFF) can be run"
    )


@kernel
def constant_power_on(V, held):
    """Whether a kept bus's constant-power and constant-current rows (S_P, S_extra, I0 of
    `L`) apply at its voltage V (complex pu) and hold flag held (`solve_nc`): above
    V_SWITCH and not held.  Otherwise PST's low-voltage switch draws the bus's load as the
    impedance Y_low, and its extra power S_extra (e.g. a storage device's) is dropped
    entirely, none of it reaching the network (PSTess `nc_load`: below 0.5 pu the
    constant-impedance equivalents of the initial load replace the constant-power rows,
    the modulation included)."""
    return abs(V) > V_SWITCH and not held


@kernel
def _load_currents(V, loads, low, out):
    """Load currents drawn at the kept buses, I_load(V) of `solve_nc` (into out); loads
    (9, n_nc) the rows `L`."""
    for i in range(V.size):
        m = abs(V[i])
        if constant_power_on(V[i], low[i]):
            out[i] = np.conj(loads[L.S_P, i] + loads[L.S_extra, i] + loads[L.I0, i] * m) / np.conj(
                V[i]
            )
        else:
            out[i] = np.conj(loads[L.Y_low, i]) * V[i]
        c = loads[L.I_dev, i] + loads[L.G_dev, i] * m
        if c != 0.0:  # converters: current sources at every voltage
            out[i] += np.conj(c * m) / np.conj(V[i])
        out[i] += loads[L.I_fix, i] + loads[L.G_fix, i] * m


@kernel
def _load_mismatch(b, Y22, V, loads, F, low):
    """F = Y21 psi + Y22 V + I_load(V) (b = Y21 psi); returns max |F|.  Buses with low[i]
    are held at their low-voltage impedance model."""
    _load_currents(V, loads, low, F)
    YV = np.empty(V.size, np.complex128)
    matvec(Y22, V, YV)
    for i in range(F.size):
        F[i] += b[i] + YV[i]
    return max_abs(F)


@kernel
def _held_below(V, held, limit):
    """Whether |V| < limit (n_nc,) at every held bus (False at a NaN voltage)."""
    for i in range(V.size):
        if held[i] and not abs(V[i]) < limit[i].real:
            return False
    return True


@kernel
def solve_nc(Y21, Y22, Z22, psi, V, loads, held):
    """Kept-bus voltages (PST nc_load): solve Y21 psi + Y22 V + I_load(V) = 0.

    With loads (9, n_nc) the rows `L` (S_P, I0, Y_low, S_extra, I_dev, I_fix, G_dev, G_fix,
    V_release):
    I_load = conj((S_P + S_extra + I0 |V|)/V) above 0.5 pu and conj(Y_low) V below (PST's
    low-voltage switch; S_extra, e.g. storage power, is dropped below 0.5 pu with the rest),
    plus conj(c |V|/V) at every voltage with c = I_dev + G_dev |V|: the converters'
    currents (`stabctl.models.converters`), c complex power per pu voltage drawn, a current
    whose angle is the bus voltage's, and I_fix + G_fix |V|, a current drawn fixed in the
    network frame (both affine in |V|, as the converters' voltage-dependent limits are
    piecewise linear).  V (n_nc,) is the starting point and is updated in place.  First the
    chord iteration V <- V - Z22 F(V) (the loads are small beside the network admittance, so
    it contracts fast and costs one matrix-vector product per step); if that has not
    converged in 30 steps, Newton's method in rectangular coordinates (as PST).  A converter
    current with a slope in |V| (G_dev or G_fix not 0: on the sloped part of a limit, e.g.
    REGCA1's low-voltage gain, 11.7 pu per pu for Kundur's 7 pu wind turbine below 1 pu) is
    a conductance the chord does not see, with which it can stop contracting: then Newton's
    method straight away, up to NEWTON_FIRST_MAX kept buses (beyond, its dense Jacobian
    costs more than the chord's 30 steps: the chord first).  If Newton fails too, the
    switch has left the equations without a solution (a load at 0.5 pu draws twice as much
    just above the switch as just below; PSTess stops there): the loads within 0.05 pu of
    the switch (at any iterate) are then held at their impedance model.

    held (n_nc, bool, in/out) carries that hold between calls: a call that needed it sets
    it, and the next call first solves with the same loads held and keeps the answer while
    every held load stays below its row V_release, V_RELEASE = 0.6 pu (a 0.1 pu hysteresis
    band: held loads settle at 0.55-0.58 pu in a deep fault on miniWECC); otherwise it
    clears held and
    starts over as above.  Without it every evaluation through a deep fault would first spend
    a failing Newton run rediscovering that the switch has no solution.  The caller clears
    held when the network changes.  Returns the number of iterations, or -1 without
    convergence (the caller raises SimulationError).
    """
    n = V.size
    if n == 0:
        return 0
    b = np.empty(n, np.complex128)
    matvec(Y21, psi, b)
    F = np.empty(n, np.complex128)
    V_start = V.copy()
    vmin = np.abs(V_start)
    if held.any():
        it = _chord(b, Z22, V, loads, F, held, vmin)
        if it < 0:
            assign(V, V_start)
            it = _newton_nc(b, Y22, V, loads, held, vmin)
        if it >= 0 and _held_below(V, held, loads[L.V_release]):
            return it
        held[:] = False
        assign(V, V_start)
        assign(vmin, np.abs(V_start))
    sloped = max_abs(loads[L.G_dev]) > 0.0 or max_abs(loads[L.G_fix]) > 0.0
    it = -1 if sloped and n <= NEWTON_FIRST_MAX else _chord(b, Z22, V, loads, F, held, vmin)
    if it >= 0:
        return it
    assign(V, V_start)
    it = _newton_nc(b, Y22, V, loads, held, vmin)
    if it >= 0:
        return it
    low = vmin < V_SWITCH + 0.05  # every bus that came near the switch
    assign(V, V_start)
    it = _newton_nc(b, Y22, V, loads, low, vmin)
    if it >= 0:
        assign(held, low)
    return it


@kernel
def _chord(b, Z22, V, loads, F, low, vmin):
    """Up to 30 chord steps V <- V - Z22 F(V); the step count, or -1 if not converged.

    With F(V) = b + Y22 V + I_load(V) the step is V <- -Z22 (b + I_load(V)): one
    matrix-vector product per step instead of two (the network part cancels).  It stops
    when a step moves no voltage by more than TOL_V; the mismatch left, about |Y22 dV|,
    is then below the Newton fallback's 1e-10 pu on the built-in cases (measured:
    at most 8e-11 on miniWECC, 3e-11 on Kundur).
    """
    w = np.empty(V.size, np.complex128)
    matvec(Z22, b, w)
    ZF = np.empty(V.size, np.complex128)
    for it in range(30):
        _load_currents(V, loads, low, F)
        matvec(Z22, F, ZF)
        step = 0.0
        for i in range(V.size):
            v = -w[i] - ZF[i]
            d = abs(v - V[i])
            if d > step or d != d:  # a NaN stays: no convergence
                step = d
            V[i] = v
            vmin[i] = min(vmin[i], abs(v))
        if step < TOL_V:
            return it + 1
    return -1


@kernel
def _lapack_solve(A, b):
    """x with A x = b by LAPACK's dgesv (LU with partial pivoting), and dgesv's info (0:
    solved; > 0: A is exactly singular).  A (n, n), b (n,) float64, left unchanged."""
    n = A.shape[0]
    a = np.asfortranarray(A)
    x = b.copy()
    dims = np.array([n, 1, 0], np.intc)  # n (also the leading dimensions), nrhs, info
    ipiv = np.empty(n, np.intc)
    _dgesv(
        dims.ctypes,
        dims[1:].ctypes,
        a.ctypes,
        dims.ctypes,
        ipiv.ctypes,
        x.ctypes,
        dims.ctypes,
        dims[2:].ctypes,
    )
    return x, dims[2]


@kernel
def _newton_nc(b, Y22, V, loads, low, vmin, max_iter=NEWTON_MAX_ITER):
    """Newton's method for the kept-bus voltages (rectangular coordinates, PST nc_load);
    vmin keeps the smallest magnitude each bus reached.  Converged when the mismatch is
    below NEWTON_TOL (pu), within max_iter iterations (else -1)."""
    S_P, I0, Y_low, S_extra = loads[L.S_P], loads[L.I0], loads[L.Y_low], loads[L.S_extra]
    I_dev, G_dev, G_fix = loads[L.I_dev], loads[L.G_dev], loads[L.G_fix]
    n = V.size
    J = np.empty((2 * n, 2 * n))
    rhs = np.empty(2 * n)
    F = np.empty(n, np.complex128)
    for it in range(max_iter):
        if _load_mismatch(b, Y22, V, loads, F, low) < NEWTON_TOL:
            return it
        # Wirtinger derivatives: d(load current) = A dV + B conj(dV), A, B diagonal
        for r in range(n):
            for c in range(n):
                J[r, c] = Y22[r, c].real
                J[r, n + c] = -Y22[r, c].imag
                J[n + r, c] = Y22[r, c].imag
                J[n + r, n + c] = Y22[r, c].real
            m = abs(V[r])
            Vc = np.conj(V[r])
            if constant_power_on(V[r], low[r]):
                A = np.conj(I0[r]) / (2 * m)
                B = -np.conj(S_P[r] + S_extra[r]) / Vc**2 - np.conj(I0[r]) * m / (2 * Vc**2)
            else:
                A = np.conj(Y_low[r])
                B = 0.0 + 0.0j
            c = I_dev[r] + G_dev[r] * m
            if c != 0.0 or G_dev[r] != 0.0:  # the converters' current, as the I0 term
                A += np.conj(c) / (2 * m) + np.conj(G_dev[r]) / 2
                B += (np.conj(G_dev[r]) * m - np.conj(c)) * m / (2 * Vc**2)
            if G_fix[r] != 0.0:  # d(G_fix |V|)
                A += G_fix[r] * Vc / (2 * m)
                B += G_fix[r] * V[r] / (2 * m)
            J[r, r] += (A + B).real
            J[r, n + r] -= (A - B).imag
            J[n + r, r] += (A + B).imag
            J[n + r, n + r] += (A - B).real
            rhs[r] = -F[r].real
            rhs[n + r] = -F[r].imag
        d, info = _lapack_solve(J, rhs)
        if info != 0:
            return -1
        for i in range(n):
            V[i] += d[i] + 1j * d[n + i]
            vmin[i] = min(vmin[i], abs(V[i]))
    return -1


@kernel
def newton_step(Y21, Y22, psi, V, loads, held):
    """One step of Newton's method on the kept-bus equations of `solve_nc` (same arguments;
    V updated in place), for a caller that changes the loads' rows between steps: True if
    V already solves them (mismatch below NEWTON_TOL, V left as it is), else False (V
    moved by one step, or left as it is at a singular Jacobian)."""
    if V.size == 0:
        return True
    b = np.empty(V.size, np.complex128)
    matvec(Y21, psi, b)
    return _newton_nc(b, Y22, V, loads, held, np.abs(V), 1) == 0
