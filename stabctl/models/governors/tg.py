"""PST's ``tg`` (tg_con type 1): the power order through a servo, a transient-gain
lead-lag and a turbine lead-lag.

demand = clip(P_ref + (w_f - omega)/R, Tmin, T_max) -> 1/(1 + s T_s) -> (1 + s T_3)/(1 +
s T_c) -> (1 + s T_4)/(1 + s T_5) -> pmech (machine base); T_4 may be negative (hydro).
Source: PSTess 1.1 `tg_indx.m`, `tg.m`; docs/pst_models.md section 4.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.models.blocks import LBND, clip, lag, leadlag
from stabctl.models.declaration import DyrModel, Limits, states
from stabctl.models.governors.table import AT_RATED_SPEED, G

if TYPE_CHECKING:
    from stabctl.models.governors import GovernorParams

TG = 1
KINDS = {TG: "PST tg"}
#: the speed set point w_f (`table.AT_RATED_SPEED`); the transient-gain lead T_3 (which
#: the table's column bounds for no type) a time constant, >= 0 (round 42: a negative one
#: ran as given); the turbine's lead T_4 may be negative (a hydro unit's water column)
LIMITS = (
    AT_RATED_SPEED,
    Limits("PSTess tg.m: the transient-gain lead-lag (1 + s T_3)/(1 + s T_c)", nonnegative=("T3",)),
)
#: the time constants that must be >= 1e-3 s (declared tg_con fields)
NEEDS = ("Ts", "Tc", "T5")
#: the family refuses a start-up order (`initialise`'s order) outside [Tmin, Tmax]:
#: PST tg's check: the power order
ORDER_LIMITS = True
#: no PSS/E record: tg rows come from PST data files
DYR: tuple[DyrModel, ...] = ()

#: the states: the servo, the transient-gain lead-lag's, the turbine lead-lag's
S = states("TGStates", ("servo", "transient", "turbine"))
STATE_NAMES = {TG: S._fields}


def has_state(p: GovernorParams):
    """Which slots of `S` are states, in slot order (all three), read on this type's rows
    by `stabctl.models.governors.GovernorParams.has_state`."""
    return (True, True, True)


def time_constants(p: GovernorParams):
    """The declared time constants that set a state's speed: field -> where (this type's
    rows are selected by the family)."""
    return {"Ts": True, "Tc": True, "T5": True}


def initialise(p: GovernorParams, r, pmech0, order, x):
    """tg at rest on rows r (a mask): the servo at the order, each lead-lag state at (1 -
    T_lead/T_lag) times its input; writes x, returns P_ref (the power order) on r."""
    tc = np.where(p.Tc[r] >= LBND, p.Tc[r], 1.0)
    x[S.servo, r] = pmech0[r]
    x[S.transient, r] = (1 - p.T3[r] / tc) * pmech0[r]
    x[S.turbine, r] = (1 - p.T4[r] / p.T5[r]) * pmech0[r]
    return order[r]


@kernel(inline="always")
def pmech(P, x, k, omega):
    """tg: (1 + s T_4)/(1 + s T_5) of the output of (1 + s T_3)/(1 + s T_c)."""
    y2 = leadlag(x[S.servo, k], x[S.transient, k], P[k, G.T3], P[k, G.TC])[0]
    return leadlag(y2, x[S.turbine, k], P[k, G.T4], P[k, G.T5])[0]


@kernel(inline="always")
def derivatives(P, x, k, omega, pe, dx):
    """tg: the order P_ref + (w_f - omega)/R clipped to [Tmin, Tmax] through the servo
    1/(1 + s T_s), then the two lead-lags."""
    order = P[k, G.PREF] + (P[k, G.WF] - omega) * P[k, G.INVR]
    dx[S.servo, k] = lag(clip(order, P[k, G.TMIN], P[k, G.TMAX]), x[S.servo, k], P[k, G.TS])[1]
    y2, dx[S.transient, k] = leadlag(x[S.servo, k], x[S.transient, k], P[k, G.T3], P[k, G.TC])
    dx[S.turbine, k] = leadlag(y2, x[S.turbine, k], P[k, G.T4], P[k, G.T5])[1]
