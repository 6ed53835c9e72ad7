"""Network solution of the dynamic simulation: Kron-reduced admittance matrices per network
stage and the non-conforming (constant-P / constant-I) load iteration.

Source: PSTess 1.1 `red_ybus.m`, `i_simu.m`, `nc_load.m`; docs/pst_models.md sections 5-6.
Each machine is an internal node (voltage psi from `stabctl.machines.internal_voltage`)
behind its admittance; constant-impedance loads sit in Ybus; buses with non-conforming load
or an injection (storage) are kept, all other buses are eliminated:

    I_mac = Y11 psi + Y12 V_nc,      I_nc(V_nc) = Y21 psi + Y22 V_nc,
    V_bus = R @ [psi; V_nc]          (every original bus),

with I_nc the current injected at the kept buses by their loads and devices.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as la

from .case import Case
from .errors import SimulationError
from .network import build_ybus

V_SWITCH = 0.5  # below this voltage PST turns non-conforming loads into impedances


@dataclass(frozen=True, eq=False)
class ReducedNetwork:
    """Reduced matrices of one network stage (dense complex, pu on the system base).

    Y11 (n_mac, n_mac), Y12 (n_mac, n_nc), Y21 (n_nc, n_mac), Y22 (n_nc, n_nc); R (n_bus,
    n_mac + n_nc) gives every original bus voltage from [psi; V_nc].
    """

    Y11: np.ndarray
    Y12: np.ndarray
    Y21: np.ndarray
    Y22: np.ndarray
    R: np.ndarray


def reduce_network(case: Case, y_shunt: np.ndarray, y_mac: np.ndarray, mac_bus: np.ndarray,
                   mac_online: np.ndarray, nc_idx: np.ndarray, n_bus_orig: int) -> ReducedNetwork:
    """Kron-reduce the network of `case` (a stage variant, possibly with extra fault buses).

    Args:
        case: the stage's case (branches and bus shunts as modified for the stage).
        y_shunt: extra shunt admittance per bus of `case` (constant-impedance loads), (n_bus,).
        y_mac: machine internal admittances (system base), (n_mac,); mac_bus their bus indices.
        mac_online: False for tripped machines (their node is disconnected).
        nc_idx: indices of the kept buses; n_bus_orig: number of buses of the base case
            (buses beyond it are stage-only fault nodes, not reported).
    Raises:
        SimulationError: the eliminated part of the network is singular (an island with no
            path to ground or a machine).
    """
    n_mac, n_bus = y_mac.size, case.n_bus
    Y = build_ybus(case).toarray()
    Y[np.diag_indices(n_bus)] += y_shunt
    y = np.where(mac_online, y_mac, 0.0)
    np.add.at(Y, (mac_bus, mac_bus), y)
    N = n_mac + n_bus
    full = np.zeros((N, N), complex)
    full[n_mac:, n_mac:] = Y
    full[np.arange(n_mac), np.arange(n_mac)] = y
    full[np.arange(n_mac), n_mac + mac_bus] = -y
    full[n_mac + mac_bus, np.arange(n_mac)] = -y
    if not np.all(mac_online):  # keep the matrix regular: isolated node to ground
        off = np.nonzero(~mac_online)[0]
        full[off, off] = 1.0
    keep = np.concatenate([np.arange(n_mac), n_mac + np.asarray(nc_idx, int)])
    elim = np.setdiff1d(np.arange(N), keep)
    Ykk, Yke = full[np.ix_(keep, keep)], full[np.ix_(keep, elim)]
    Yek, Yee = full[np.ix_(elim, keep)], full[np.ix_(elim, elim)]
    try:
        lu = la.lu_factor(Yee, check_finite=True)
        rec = -la.lu_solve(lu, Yek)            # eliminated voltages from kept ones
    except (la.LinAlgError, ValueError) as exc:
        raise SimulationError(f"singular network in stage of case '{case.name}': {exc}") from exc
    if not np.all(np.isfinite(rec)):
        raise SimulationError(f"singular network (island without a source) in case '{case.name}'")
    Yred = Ykk + Yke @ rec
    R = np.zeros((n_bus, keep.size), complex)
    R[np.asarray(nc_idx, int), n_mac + np.arange(len(nc_idx))] = 1.0
    bus_elim = elim[elim >= n_mac] - n_mac
    R[bus_elim] = rec[elim >= n_mac]
    return ReducedNetwork(Y11=Yred[:n_mac, :n_mac], Y12=Yred[:n_mac, n_mac:],
                          Y21=Yred[n_mac:, :n_mac], Y22=Yred[n_mac:, n_mac:],
                          R=R[:n_bus_orig])


@dataclass(frozen=True, eq=False)
class NonConformingLoads:
    """Non-conforming part of the loads at the kept buses (PST `nc_load` flag 0), (n_nc,).

    S_P: constant-power part (complex pu); I0: constant-current part as power per pu
    voltage (load power = I0 |V|); Y_low: admittance used below 0.5 pu, (S_P + S_I)*/V0^2.
    """

    S_P: np.ndarray
    I0: np.ndarray
    Y_low: np.ndarray


def solve_nc(net: ReducedNetwork, psi, loads: NonConformingLoads, V_guess, S_extra=None,
             tol: float = 1e-10, max_iter: int = 50):
    """Kept-bus voltages V_nc by Newton's method in rectangular coordinates (PST nc_load).

    Solves Y21 psi + Y22 V + I_load(V) = 0 with I_load = conj((S_P + S_extra + I0 |V|)/V)
    above 0.5 pu and conj(Y_low) V below (PST's low-voltage switch; S_extra, e.g. storage
    power, is dropped below 0.5 pu together with the rest).  Returns V_nc (n_nc,).

    Raises:
        SimulationError: no convergence in max_iter iterations (names the worst bus index).
    """
    n = V_guess.size
    if n == 0:
        return V_guess
    b = net.Y21 @ psi
    S = loads.S_P if S_extra is None else loads.S_P + S_extra
    V = V_guess.astype(complex)
    Yr, Yi = net.Y22.real, net.Y22.imag
    for _ in range(max_iter):
        m = np.abs(V)
        high = m > V_SWITCH
        Vc = np.conj(V)
        g = np.where(high, np.conj(S + loads.I0 * m) / Vc, np.conj(loads.Y_low) * V)
        F = b + net.Y22 @ V + g
        err = np.abs(F)
        if err.max() < tol:
            return V
        # Wirtinger derivatives of g: dg = A dV + B conj(dV)
        A = np.where(high, np.conj(loads.I0) / (2 * m), np.conj(loads.Y_low))
        B = np.where(high, -np.conj(S) / Vc ** 2 - np.conj(loads.I0) * m / (2 * Vc ** 2), 0.0)
        ApB, AmB = A + B, A - B
        J = np.empty((2 * n, 2 * n))
        J[:n, :n] = Yr + np.diag(ApB.real)
        J[:n, n:] = -Yi - np.diag(AmB.imag)
        J[n:, :n] = Yi + np.diag(ApB.imag)
        J[n:, n:] = Yr + np.diag(AmB.real)
        d = np.linalg.solve(J, -np.concatenate([F.real, F.imag]))
        V = V + d[:n] + 1j * d[n:]
    raise SimulationError(f"non-conforming load iteration did not converge in {max_iter} "
                          f"iterations (worst kept bus index {int(np.argmax(err))})")
