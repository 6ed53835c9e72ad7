"""PSS/E's TGOV1 (tg_con type 2): the steam turbine-governor.

P_ref + (w_f - omega)/R -> 1/(1 + s T1) non-windup on [VMIN, VMAX] -> (1 + s T2)/(1 + s
T3) -> minus Dt (omega - 1).  Source: PSS/E Model Library TGOV1; ANDES 2.0
``andes/models/governor/tgov1.py``; docs/pst_models.md 4.1.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.models.blocks import LBND, leadlag, nonwindup_lag
from stabctl.models.declaration import DyrModel, Limits, states
from stabctl.models.governors.table import AT_LIMIT, AT_RATED_SPEED, G

if TYPE_CHECKING:
    from stabctl.models.governors import GovernorParams

TGOV1 = 2
KINDS = {TGOV1: "TGOV1"}
#: the speed set point w_f (`table.AT_RATED_SPEED`); the lead T2 (tg_con T3, which has
#: no bound of its own) a time constant, >= 0 (round 42: T2 = -0.3 was run as given)
LIMITS = (
    AT_RATED_SPEED,
    Limits("PSS/E Model Library TGOV1: the lead-lag (1 + s T2)/(1 + s T3)", nonnegative=("T3",)),
)
#: the time constants that must be >= 1e-3 s (declared tg_con fields)
NEEDS = ("Ts", "Tc")
#: the family refuses a start-up order (`initialise`'s order) outside [Tmin, Tmax]:
#: the valve's non-windup limits VMAX, VMIN on the power order
ORDER_LIMITS = True
DYR = (
    # TGOV1: invR = 1/R is computed
    DyrModel(
        "TGOV1",
        ("R", "T1", "VMAX", "VMIN", "T2", "T3", "Dt"),
        {"Tmax": "VMAX", "Tmin": "VMIN", "Ts": "T1", "Tc": "T3", "T3": "T2", "Dt": "Dt"},
        kind=TGOV1,
        andes=("TGOV1", "TGOV1N"),
    ),
)

#: the states: the valve (lag T1, non-windup), the lead-lag T2/T3's
S = states("TGOV1States", ("valve", "leadlag"))
STATE_NAMES = {TGOV1: S._fields}


def has_state(p: GovernorParams):
    """Which slots of `S` are states, in slot order (both)."""
    return (True, True)


def time_constants(p: GovernorParams):
    """The declared time constants that set a state's speed: field -> where."""
    return {"Ts": True, "Tc": True}


def initialise(p: GovernorParams, r, pmech0, order, x):
    """TGOV1 at rest on rows r: the valve at pmech0, the lead-lag state at (1 - T2/T3)
    pmech0; writes x, returns P_ref (the power order) on r."""
    tc = np.where(p.Tc[r] >= LBND, p.Tc[r], 1.0)
    x[S.valve, r] = pmech0[r]
    x[S.leadlag, r] = (1 - p.T3[r] / tc) * pmech0[r]
    return order[r]


@kernel(inline="always")
def pmech(P, x, k, omega):
    """TGOV1: the lead-lag (1 + s T_2)/(1 + s T_3) output minus D_t (omega - 1)."""
    y = leadlag(x[S.valve, k], x[S.leadlag, k], P[k, G.T3], P[k, G.TC])[0]
    return y - P[k, G.DT] * (omega - 1.0)


@kernel(inline="always")
def derivatives(P, x, k, omega, pe, dx):
    """TGOV1: the order P_ref + (w_f - omega)/R through the non-windup valve 1/(1 + s T_1)
    on [VMIN, VMAX] (clamps the valve state in x), then the lead-lag."""
    order = P[k, G.PREF] + (P[k, G.WF] - omega) * P[k, G.INVR]
    x[S.valve, k], dx[S.valve, k] = nonwindup_lag(
        order, x[S.valve, k], P[k, G.TS], P[k, G.TMIN], P[k, G.TMAX], AT_LIMIT, 0.0
    )
    dx[S.leadlag, k] = leadlag(x[S.valve, k], x[S.leadlag, k], P[k, G.T3], P[k, G.TC])[1]
