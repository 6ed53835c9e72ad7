"""PST's `pss` (pss_con types 1, speed input, and 2, electrical power input).

Washout K T_w s/(1 + s T_w) with K T_w given (column 3), lead-lag (1 + s T_1)/(1 + s T_2),
lead-lag (1 + s T_3)/(1 + s T_4) (absent for T_4 < 1e-3 s), output limits [ymin, ymax].
Source: PSTess 1.1 `pss_indx.m`, `pss.m` (docs/pst_models.md section 3).  PSS/E's STAB1
and an IEEEST without filter are read as this type (:mod:`~stabctl.models.pss.stab1`,
`stabctl.io.dyr`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.models.blocks import GAIN_AFTER, LBND, clip, leadlag, washout
from stabctl.models.declaration import states
from stabctl.models.pss.table import C

if TYPE_CHECKING:
    from stabctl.models.pss import PssParams

PST_SPEED, PST_POWER = 1, 2
KINDS = {PST_SPEED: "PST pss, speed input", PST_POWER: "PST pss, electrical power input"}
#: the family refuses a washout T_w below 1e-3 s (`stabctl.models.pss.pss_params`)
NEEDS_TW = False
#: pss_con input1, input2 are PSS/E input codes (else read as 0)
PSSE_INPUTS = False
#: reads the input limits VS1MIN .. VS2MAX (else -inf, +inf)
INPUT_LIMITS = False
#: PST's records are its .m data; PSS/E's IEEEST (declared with the PSS/E stabiliser,
#: `ieeest`) and STAB1 (`stab1`) map here when exactly equivalent
DYR = ()

#: the states: the washout's, the two lead-lags'
S = states("PstPssStates", ("washout", "leadlag1", "leadlag2"))
STATE_NAMES = {PST_SPEED: S._fields, PST_POWER: S._fields}


def check(s, r) -> str | None:
    """Why pss_con row r (0-based) cannot be this type, or None: the first lead-lag needs
    its lag (PST has no case without it); the second, bypassed without its lag, then has
    no lead (round 41: T3 = 0.05 s with T4 = 0 had no effect on the run)."""
    if s.T2[r] < LBND:
        return f"field 'T2': the first lead-lag needs T2 >= {LBND} s"
    if s.T4[r] < LBND and s.T3[r] != 0:
        return f"fields 'T4', 'T3': a lead without its lag (T4 below {LBND} s bypasses the block)"
    return None


def has_state(p: PssParams):
    """Which slots of `S` are states: the washout, the first lead-lag, the second where
    T_4 >= 1e-3 s."""
    return (True, True, p.T4 >= LBND)


def time_constants(p: PssParams):
    """The declared time constants that set a state's speed: field -> where."""
    return {"Tw": True, "T2": True, "T4": p.T4 >= LBND}


def initialise(p: PssParams, r, u1, u2, pe0, x):
    """At rest on rows r: the washout's state at its input u1 (speed or power), the
    lead-lags at 0."""
    x[S.washout, r] = u1[r]


def signals(p: PssParams, r, omega, pe):
    """(u1, u2) on rows r at the initial point: the speed (type 1) or the power, 0."""
    return np.where(p.kind[r] == PST_SPEED, omega[r], pe[r]), np.zeros(np.count_nonzero(r))


@kernel(inline="always")
def output(P, x, k, omega, pe, dx):
    """PST pss (pss.m): washout s T_w/(1 + s T_w) on u (the speed omega, type 1, or the
    electrical power pe, type 2), then K (1 + s T_1)/(1 + s T_2) (K T_w given, column 3),
    then (1 + s T_3)/(1 + s T_4) (absent for T_4 < 1e-3 s), output limits [ymin, ymax]."""
    u = pe if P[k, C.KIND] == PST_POWER else omega
    y, dx[S.washout, k] = washout(u, x[S.washout, k], P[k, C.TW], 1.0, GAIN_AFTER)
    y, dx[S.leadlag1, k] = leadlag(y, x[S.leadlag1, k], P[k, C.T1], P[k, C.T2], P[k, C.KTW])
    y, dx[S.leadlag2, k] = leadlag(y, x[S.leadlag2, k], P[k, C.T3], P[k, C.T4])
    return clip(y, P[k, C.MIN], P[k, C.MAX])
