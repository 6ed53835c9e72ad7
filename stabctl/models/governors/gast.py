"""PSS/E's GAST (tg_con type 6): the gas turbine.

min(P_ref + (w_f - omega)/R, AT + KT (AT - y_3)) -> 1/(1 + s T1) non-windup on [VMIN,
VMAX] -> 1/(1 + s T2) = y_2 -> minus D_turb (omega - 1); y_3 = y_2/(1 + s T3), the load
limit's feedback.  Source: PSS/E Model Library GAST; ANDES 2.0
``andes/models/governor/gast.py``; docs/pst_models.md 4.4.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.errors import refuse_initial
from stabctl.models.blocks import LBND, lag, nonwindup_lag
from stabctl.models.declaration import DyrModel, Limits, beyond, states
from stabctl.models.governors.table import AT_LIMIT, AT_RATED_SPEED, G

if TYPE_CHECKING:
    from stabctl.models.governors import GovernorParams

GAST = 6
KINDS = {GAST: "GAST"}
#: the speed set point w_f (`table.AT_RATED_SPEED`) and GAST's load-limit feedback lag T3
#: >= 0 (PSS/E Model Library GAST)
LIMITS = (AT_RATED_SPEED, Limits("PSS/E Model Library GAST", nonnegative=("T3",)))
#: the time constants that must be >= 1e-3 s (declared tg_con fields)
NEEDS = ("Ts",)
#: the family refuses a start-up order (`initialise`'s order) outside [Tmin, Tmax]:
#: the valve limits VMAX, VMIN on the power order
ORDER_LIMITS = True
DYR = (
    # GAST -> type 6: invR = 1/R is computed; T1 the valve (Ts), T2 the power lag (Tc), T3
    # the load-limit feedback lag
    DyrModel(
        "GAST",
        ("R", "T1", "T2", "T3", "AT", "KT", "VMAX", "VMIN", "Dturb"),
        {
            "Ts": "T1",
            "Tc": "T2",
            "T3": "T3",
            "AT": "AT",
            "KT": "KT",
            "Tmax": "VMAX",
            "Tmin": "VMIN",
            "Dt": "Dturb",
        },
        kind=GAST,
        andes=("GAST",),
    ),
)

#: the states: the valve (non-windup), the power lag T2's, the load-limit lag T3's
S = states("GASTStates", ("valve", "T2lag", "T3lag"))
STATE_NAMES = {GAST: S._fields}


def has_state(p: GovernorParams):
    """Which slots of `S` are states: the valve, each lag with T >= 1e-3 s."""
    return (True, p.Tc >= LBND, p.T3 >= LBND)


def time_constants(p: GovernorParams):
    """The declared time constants that set a state's speed: field -> where."""
    return {"Ts": True, "Tc": p.Tc >= LBND, "T3": p.T3 >= LBND}


def initialise(p: GovernorParams, r, pmech0, order, x):
    """GAST at rest on rows r: every state at pmech0 (the power order); returns P_ref on
    r.

    Raises CaseError (`refuse_initial`) when the initial power is above the load limit AT
    + KT (AT - Pm0) (PSS/E's own GAST run starts on it, AT = Pm0 = 1), beyond
    `START_LIMIT_TOL` (stabctl.models.declaration)."""
    refuse_initial(
        "tg_con",
        r & beyond(pmech0, -np.inf, p.AT + p.KT * (p.AT - pmech0)),
        lambda k: (
            f"tg_con row {k + 1}: GAST's load limit AT + KT (AT - Pm0) is below its "
            f"initial power {pmech0[k]:.4f} pu"
        ),
    )
    x[S.valve, r] = pmech0[r]
    x[S.T2lag, r] = order[r]
    x[S.T3lag, r] = order[r]
    return order[r]


@kernel(inline="always")
def pmech(P, x, k, omega):
    """GAST: the power lag's output minus D_turb (omega - 1)."""
    return lag(x[S.valve, k], x[S.T2lag, k], P[k, G.TC])[0] - P[k, G.DT] * (omega - 1.0)


@kernel(inline="always")
def derivatives(P, x, k, omega, pe, dx):
    """GAST (docs/pst_models.md 4.4): min(P_ref + (w_f - omega)/R, AT + KT (AT - y_3))
    through the valve (Ts = T1), y_2 its lag T2 (Tc), y_3 the lag T3 of y_2 (a lag below
    1e-3 s passes its input)."""
    y2, dx[S.T2lag, k] = lag(x[S.valve, k], x[S.T2lag, k], P[k, G.TC])
    y3, dx[S.T3lag, k] = lag(y2, x[S.T3lag, k], P[k, G.T3])
    order = P[k, G.PREF] + (P[k, G.WF] - omega) * P[k, G.INVR]
    limit = P[k, G.AT] + P[k, G.KT] * (P[k, G.AT] - y3)
    x[S.valve, k], dx[S.valve, k] = nonwindup_lag(
        min(order, limit), x[S.valve, k], P[k, G.TS], P[k, G.TMIN], P[k, G.TMAX], AT_LIMIT, 0.0
    )
