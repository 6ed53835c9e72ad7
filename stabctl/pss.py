"""Power system stabiliser: PST `pss` (speed or power input, washout, two lead-lags, output
limits).

Source: PSTess 1.1 `pss_indx.m`, `pss.m`; docs/pst_models.md section 3.  Column 3 of
pss_con is the gain times the washout time constant (K*T_w).  States (3 per PSS): washout
pss1, lead-lag pss2, lead-lag pss3 (present only when T_4 >= 1e-3).  Output in pu, added to
the exciter summing junction of the same machine.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .case import Case

LBND = 1e-3
STATE_NAMES = ("washout", "leadlag1", "leadlag2")


@dataclass(frozen=True, eq=False)
class PssParams:
    """PSS data, arrays of shape (n_pss,); `mac` is the machine index, `power_input` marks
    type 2 (electrical power on the machine base) instead of speed."""

    mac: np.ndarray
    power_input: np.ndarray
    KTw: np.ndarray
    Tw: np.ndarray
    T1: np.ndarray
    T2: np.ndarray
    T3: np.ndarray
    T4: np.ndarray
    vmax: np.ndarray
    vmin: np.ndarray

    @property
    def n(self) -> int:
        return self.mac.size

    @property
    def has_T4(self):
        return self.T4 >= LBND


def pss_params(case: Case) -> PssParams:
    """PSS parameters of a case."""
    s = case.pss
    c = s.matrix()
    return PssParams(mac=np.array([case.machine_index(m) for m in c[:, 1]], int),
                     power_input=c[:, 0] == 2, KTw=c[:, 2], Tw=c[:, 3], T1=c[:, 4], T2=c[:, 5],
                     T3=c[:, 6], T4=c[:, 7], vmax=c[:, 8], vmin=c[:, 9])


def pss_input(p: PssParams, omega, pelect, mac_pot):
    """Input signal: speed (pu) or electrical power on the machine base."""
    return np.where(p.power_input, pelect[p.mac] * mac_pot[p.mac], omega[p.mac])


def initialise(p: PssParams, u0):
    """States (3, n_pss) from the initial input u0 (washout state = input, others 0)."""
    x = np.zeros((3, p.n))
    x[0] = u0
    return x


def output_and_derivatives(p: PssParams, x, u):
    """(pss_out (n_pss,), dx (3, n_pss)) for input u (PST flag 1/2)."""
    var1 = (u - x[0]) / p.Tw
    r12 = p.T1 / p.T2
    var2 = r12 * p.KTw * var1 + x[1]
    T4 = np.where(p.has_T4, p.T4, 1.0)
    r34 = p.T3 / T4
    var3 = np.where(p.has_T4, r34 * var2 + x[2], var2)
    dx = np.empty_like(x)
    dx[0] = var1
    dx[1] = ((1 - r12) * p.KTw * var1 - x[1]) / p.T2
    dx[2] = np.where(p.has_T4, ((1 - r34) * var2 - x[2]) / T4, 0.0)
    return np.clip(var3, p.vmin, p.vmax), dx
