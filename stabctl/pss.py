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
from numba import njit

from .case import Case

LBND = 1e-3
STATE_NAMES = ("washout", "leadlag1", "leadlag2")
(S_MAC, S_PWR, S_KTW, S_TW, S_T1, S_T2, S_T3, S_T4, S_MAX, S_MIN, S_NCOL) = range(11)


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

    def packed(self) -> np.ndarray:
        """Parameter matrix (n_pss, S_NCOL) for the compiled kernels."""
        cols = (self.mac, self.power_input, self.KTw, self.Tw, self.T1, self.T2, self.T3,
                self.T4, self.vmax, self.vmin)
        return np.column_stack([np.asarray(c, float) for c in cols]).reshape(self.n, S_NCOL)

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


@njit(cache=True)
def output_and_derivatives(P, x, k, u, dx):
    """Output of PSS k for input u (PST flag 1/2); its derivatives into dx[:, k]."""
    var1 = (u - x[0, k]) / P[k, S_TW]
    r12 = P[k, S_T1] / P[k, S_T2]
    var2 = r12 * P[k, S_KTW] * var1 + x[1, k]
    dx[0, k] = var1
    dx[1, k] = ((1 - r12) * P[k, S_KTW] * var1 - x[1, k]) / P[k, S_T2]
    if P[k, S_T4] >= LBND:
        r34 = P[k, S_T3] / P[k, S_T4]
        var3 = r34 * var2 + x[2, k]
        dx[2, k] = ((1 - r34) * var2 - x[2, k]) / P[k, S_T4]
    else:
        var3 = var2
        dx[2, k] = 0.0
    return min(max(var3, P[k, S_MIN]), P[k, S_MAX])
