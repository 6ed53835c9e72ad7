"""ANDES's HYGOV4 (tg_con type 8; ANDES 2.0 ``andes/models/governor/hygov4.py``: PSS/E's
HYGOV4 without its deadbands and gate-power curve; machine base, head at the dam 1).

The error P_ref - (omega - w_f) - R_perm g - R_temp T_r s/(1 + s T_r) g (the dashpot)
through the pilot servo 1/(1 + s T_p), the gate speed 1/T_g times it limited to [U_C,
U_O], the gate integrator non-windup on [PMIN, PMAX]; water column and power as HYGOV's
(`stabctl.models.governors.hygov.turbine`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from stabctl._jit.decorators import kernel
from stabctl.models.blocks import clip, lag, nonwindup
from stabctl.models.declaration import DyrModel, states
from stabctl.models.governors import hygov
from stabctl.models.governors.table import AT_LIMIT, AT_RATED_SPEED, G

if TYPE_CHECKING:
    from stabctl.models.governors import GovernorParams

HYGOV4 = 8
KINDS = {HYGOV4: "HYGOV4 (ANDES)"}
#: the speed set point w_f (`table.AT_RATED_SPEED`)
LIMITS = AT_RATED_SPEED
#: the time constants that must be >= 1e-3 s (declared tg_con fields: T_g, T_p, T_r, T_w)
NEEDS = ("Ts", "Tc", "T3", "T4")
#: the family refuses a start-up order (`initialise`'s order) outside [Tmin, Tmax]:
#: the gate limits on the start-up flow q_0
ORDER_LIMITS = True
DYR = (
    # ANDES's HYGOV4 -> type 8, its parameters by name (ANDES maps no PSS/E record onto
    # it, and PSS/E's HYGOV4 record, with deadbands and a gate-power curve, is another
    # model: a DYR file's HYGOV4 is refused as not mapped); T_p the pilot servo (Tc),
    # T_g (Ts), T_r the dashpot (T3), T_w (T4), A_t (T5), gate limits (Tmin, Tmax)
    DyrModel(
        "ANDES_HYGOV4",
        ("wref0", "Rperm", "Rtemp", "UO", "UC", "PMAX", "PMIN", "Tp", "Tg", "Tr", "Tw")
        + ("At", "Dturb", "qNL"),
        {
            "wf": "wref0",
            "Rp": "Rperm",
            "rt": "Rtemp",
            "Uo": "UO",
            "Uc": "UC",
            "Tmax": "PMAX",
            "Tmin": "PMIN",
            "Tc": "Tp",
            "Ts": "Tg",
            "T3": "Tr",
            "Tw": "Tw",
            "At": "At",
            "Dt": "Dturb",
            "qNL": "qNL",
        },
        kind=HYGOV4,
        andes=("HYGOV4",),
    ),
)

#: the states: the pilot servo's, the gate, the dashpot's, the water flow
S = states("HYGOV4States", ("pilot", "gate", "dashpot", "flow"))
STATE_NAMES = {HYGOV4: S._fields}


def has_state(p: GovernorParams):
    """Which slots of `S` are states (all four)."""
    return (True, True, True, True)


def time_constants(p: GovernorParams):
    """The declared time constants that set a state's speed: field -> where."""
    return {"Tc": True, "T3": True, "T4": True}


#: the start-up order: HYGOV's flow q_0 = pmech0/A_t + q_NL
start_order = hygov.start_order


def initialise(p: GovernorParams, r, pmech0, q0, x):
    """HYGOV4 at rest on rows r: the pilot servo at 0, the gate, the dashpot (no output)
    and the flow at q_0 (head 1, from the family); returns P_ref = R_perm q_0 on r."""
    x[S.pilot, r] = 0.0
    for slot in (S.gate, S.dashpot, S.flow):
        x[slot, r] = q0[r]
    return p.Rp[r] * q0[r]


@kernel(inline="always")
def pmech(P, x, k, omega):
    """HYGOV4: HYGOV's turbine at its gate, D_turb on omega - w_f."""
    return hygov.turbine(P, k, x[S.flow, k], omega - P[k, G.WF] + 1.0, x[S.gate, k])


@kernel(inline="always")
def derivatives(P, x, k, omega, pe, dx):
    """HYGOV4 (module docstring; ANDES ``hygov4.py``): the dashpot R_temp T_r s/(1 + s T_r)
    on the gate (T3), the pilot servo T_p (Tc), the gate speed clip(y_p / T_g, U_C, U_O)
    (Ts) into the gate integrator non-windup on [PMIN, PMAX], the water column T_w (T4)."""
    g = x[S.gate, k]
    dashpot = P[k, G.RT] * (g - x[S.dashpot, k])
    dx[S.dashpot, k] = (g - x[S.dashpot, k]) / P[k, G.T3]
    error = P[k, G.PREF] - (omega - P[k, G.WF]) - P[k, G.RP] * g - dashpot
    dx[S.pilot, k] = lag(error, x[S.pilot, k], P[k, G.TC])[1]
    speed = clip(x[S.pilot, k] / P[k, G.TS], P[k, G.UC], P[k, G.UO])
    x[S.gate, k], dx[S.gate, k] = nonwindup(g, speed, P[k, G.TMIN], P[k, G.TMAX], AT_LIMIT, 0.0)
    dx[S.flow, k] = (1.0 - hygov.head(x[S.flow, k], x[S.gate, k])) / P[k, G.T4]
