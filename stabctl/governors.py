"""Turbine-governor: PST `tg` (type 1): servo, transient-gain lead-lag, turbine lead-lag.

Source: PSTess 1.1 `tg_indx.m`, `tg.m`; docs/pst_models.md section 4.
demand = clip(P_ref + (w_f - omega)/R, 0, T_max) -> 1/(1 + s T_s) -> (1 + s T_3)/(1 + s T_c)
-> (1 + s T_4)/(1 + s T_5) -> pmech (machine base).  T_4 may be negative (hydro).  States
(3 per governor): tg1, tg2, tg3.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from .case import Case
from .errors import CaseError

STATE_NAMES = ("servo", "transient", "turbine")
(G_MAC, G_WF, G_INVR, G_TMAX, G_TS, G_TC, G_T3, G_T4, G_T5, G_PREF, G_NCOL) = range(11)


@dataclass(frozen=True, eq=False)
class GovernorParams:
    """Governor data, arrays of shape (n_tg,); `mac` is the machine index."""

    mac: np.ndarray
    wf: np.ndarray
    invR: np.ndarray
    Tmax: np.ndarray
    Ts: np.ndarray
    Tc: np.ndarray
    T3: np.ndarray
    T4: np.ndarray
    T5: np.ndarray

    @property
    def n(self) -> int:
        return self.mac.size

    def packed(self, Pref: np.ndarray) -> np.ndarray:
        """Parameter matrix (n_tg, G_NCOL) for the compiled kernels, with P_ref."""
        cols = (self.mac, self.wf, self.invR, self.Tmax, self.Ts, self.Tc, self.T3, self.T4,
                self.T5, Pref)
        return np.column_stack([np.asarray(c, float) for c in cols]).reshape(self.n, G_NCOL)


def governor_params(case: Case) -> GovernorParams:
    """Governor parameters; raises CaseError for zero T_s, T_c or T_5 (PST divides by them)."""
    c = case.governors.matrix()
    for k, name in ((5, "Ts"), (6, "Tc"), (9, "T5")):
        bad = np.nonzero(c[:, k] == 0)[0]
        if bad.size:
            raise CaseError(f"tg_con row {bad[0] + 1}, field '{name}': must be non-zero")
    return GovernorParams(mac=np.array([case.machine_index(m) for m in c[:, 1]], int),
                          wf=c[:, 2], invR=c[:, 3], Tmax=c[:, 4], Ts=c[:, 5], Tc=c[:, 6],
                          T3=c[:, 7], T4=c[:, 8], T5=c[:, 9])


def initialise(p: GovernorParams, pmech0):
    """States (3, n_tg) and P_ref from the initial mechanical power (machine base).

    Raises CaseError when pmech0 is outside [0, T_max] (PST's check)."""
    bad = np.nonzero((pmech0 > p.Tmax) | (pmech0 < 0))[0]
    if bad.size:
        raise CaseError(f"tg_con row {bad[0] + 1}: initial mechanical power "
                        f"{pmech0[bad[0]]:.4f} pu outside [0, Tmax]")
    x = np.vstack([pmech0, (1 - p.T3 / p.Tc) * pmech0, (1 - p.T4 / p.T5) * pmech0])
    return x, pmech0.copy()


@njit(cache=True)
def pmech(P, x, k):
    """Mechanical power of governor k from its states (machine base), PST flag 1."""
    y2 = x[1, k] + P[k, G_T3] / P[k, G_TC] * x[0, k]
    return x[2, k] + P[k, G_T4] / P[k, G_T5] * y2


@njit(cache=True)
def derivatives(P, x, k, omega, dx):
    """Derivatives of governor k into dx[:, k] for its machine speed omega (pu), flag 2."""
    demand = min(max(P[k, G_PREF] + (P[k, G_WF] - omega) * P[k, G_INVR], 0.0), P[k, G_TMAX])
    y2 = x[1, k] + P[k, G_T3] / P[k, G_TC] * x[0, k]
    dx[0, k] = (demand - x[0, k]) / P[k, G_TS]
    dx[1, k] = ((1 - P[k, G_T3] / P[k, G_TC]) * x[0, k] - x[1, k]) / P[k, G_TC]
    dx[2, k] = ((1 - P[k, G_T4] / P[k, G_T5]) * y2 - x[2, k]) / P[k, G_T5]
