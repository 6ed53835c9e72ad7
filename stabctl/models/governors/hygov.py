"""PSS/E's HYGOV (tg_con type 4): the hydro turbine-governor, machine base.

Filter T_f on e = P_ref - (omega - 1) - R c, desired gate c = x_g + e/r with the gate
integrator dx_g/dt = K_g e (PSS/E: K_g = 1/(r T_r)) rate-limited to [-VELM, VELM] (ANDES:
minus e/r) and held in [GMIN, GMAX], gate g = c/(1 + s T_g), water column T_w dq/dt = 1 -
(q/g)^2, pmech = A_t (q/g)^2 (q - q_NL) - D_turb (omega - 1) g.  With ``psse_gate`` the
state is the desired gate c itself (PSS/E's PI whole, OpenIPSL's PSSE.TG.HYGOV).  Source:
PSS/E Model Library HYGOV; ANDES 2.0 ``andes/models/governor/hygov.py``;
docs/pst_models.md 4.3.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from stabctl._jit.decorators import kernel
from stabctl.models.blocks import clip, lag, nonwindup
from stabctl.models.declaration import DyrModel, Limits, states
from stabctl.models.governors.table import AT_LIMIT, G

if TYPE_CHECKING:
    from stabctl.models.governors import GovernorParams

HYGOV = 4
KINDS = {HYGOV: "HYGOV"}
#: HYGOV's temporary droop r > 0 (the desired gate is e/r), its turbine gain A_t > 0 (the
#: start-up flow is P_m0/A_t + q_NL) and its filter time constant T_r >= 0 (PSS/E Model
#: Library HYGOV)
LIMITS = Limits("PSS/E Model Library HYGOV", positive=("rt", "At"), nonnegative=("T3",))
#: the time constants that must be >= 1e-3 s (declared tg_con fields: T_g, T_f, T_w)
NEEDS = ("Ts", "Tc", "T4")
#: the family refuses a start-up order (`initialise`'s order) outside [Tmin, Tmax]:
#: the gate limits on the start-up flow q_0
ORDER_LIMITS = True
DYR = (
    # HYGOV -> type 4: Kg = 1/(r Tr) and Uc = -VELM computed
    DyrModel(
        "HYGOV",
        ("R", "r", "Tr", "Tf", "Tg", "VELM", "GMAX", "GMIN", "TW", "At", "Dturb", "qNL"),
        {
            "Rp": "R",
            "rt": "r",
            "T3": "Tr",
            "Tc": "Tf",
            "Ts": "Tg",
            "Uo": "VELM",
            "Tmax": "GMAX",
            "Tmin": "GMIN",
            "Tw": "TW",
            "At": "At",
            "Dt": "Dturb",
            "qNL": "qNL",
        },
        kind=HYGOV,
        # HYGOVDB: HYGOV with a speed deadband, read where the band is empty
        # (stabctl.io.andes_case refuses others)
        andes=("HYGOV", "HYGOVDB"),
    ),
)

#: the states: the filter's, the gate integrator (psse_gate: the desired gate), the gate,
#: the water flow
S = states("HYGOVStates", ("filter", "gate_integrator", "gate", "flow"))
STATE_NAMES = {HYGOV: S._fields}


def has_state(p: GovernorParams):
    """Which slots of `S` are states (all four)."""
    return (True, True, True, True)


def time_constants(p: GovernorParams):
    """The declared time constants that set a state's speed: field -> where."""
    return {"Ts": True, "Tc": True, "T4": True}


def start_order(p: GovernorParams, r, pmech0, total):
    """HYGOV's (and HYGOV4's) start-up order on rows r: the flow q_0 = pmech0/A_t + q_NL
    at head 1 (A_t in T5)."""
    return pmech0[r] / p.T5[r] + p.qNL[r]


def initialise(p: GovernorParams, r, pmech0, q0, x):
    """HYGOV (and HYGOV4) at rest on rows r: the filter (pilot servo) at 0, the other
    three states at the flow q_0 = pmech0/A_t + q_NL (head 1, from the family); returns
    P_ref = R q_0 on r."""
    x[S.filter, r] = 0.0
    for slot in (S.gate_integrator, S.gate, S.flow):
        x[slot, r] = q0[r]
    return p.Rp[r] * q0[r]


@kernel
def head(q, g):
    """HYGOV's head at the turbine, (q/g)^2 (0 with the gate closed)."""
    return (q / g) ** 2 if g > 0 else 0.0


@kernel(inline="always")
def turbine(P, k, q, omega, g):
    """HYGOV and HYGOV4: A_t h (q - q_NL) - D_turb (omega - 1) g, for flow q and gate g."""
    return P[k, G.T5] * head(q, g) * (q - P[k, G.QNL]) - P[k, G.DT] * (omega - 1.0) * g


@kernel(inline="always")
def pmech(P, x, k, omega):
    """HYGOV's mechanical power (`turbine` at its gate)."""
    return turbine(P, k, x[S.flow, k], omega, x[S.gate, k])


@kernel(inline="always")
def derivatives(P, x, k, omega, pe, dx):
    """HYGOV: filter, rate- and position-limited gate integrator, gate servo, water column
    (module docstring; ANDES ``hygov.py``); psse_gate: the state is the desired gate c,
    d c/dt = (e + T_r de/dt)/(r T_r) (the PI whole) rate- and position-limited (PSS/E)."""
    e = x[S.filter, k]
    psse = P[k, G.PSSE_GATE] == 1
    c = x[S.gate_integrator, k] if psse else x[S.gate_integrator, k] + e / P[k, G.RT]
    dx[S.filter, k] = lag(P[k, G.PREF] - (omega - 1.0) - P[k, G.RP] * c, e, P[k, G.TC])[1]
    if psse:
        rate = clip(P[k, G.KG] * e + dx[S.filter, k] / P[k, G.RT], P[k, G.UC], P[k, G.UO])
    else:
        shift = P[k, G.VELM_REL] * e / P[k, G.RT]
        rate = clip(P[k, G.KG] * e, P[k, G.UC] - shift, P[k, G.UO] - shift)
    x[S.gate_integrator, k], dx[S.gate_integrator, k] = nonwindup(
        x[S.gate_integrator, k], rate, P[k, G.TMIN], P[k, G.TMAX], AT_LIMIT, 0.0
    )
    dx[S.gate, k] = lag(c, x[S.gate, k], P[k, G.TS])[1]
    dx[S.flow, k] = (1.0 - head(x[S.flow, k], x[S.gate, k])) / P[k, G.T4]
