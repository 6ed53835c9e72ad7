"""PSS/E's IEEEG3 (tg_con type 15): the IEEE Committee Report 1973 hydro governor-turbine
with a mechanical-hydraulic (dashpot) governor.

The speed error w_f - omega, plus P_ref, minus the permanent droop SIGMA g and the
transient droop's washout DELTA TR s/(1 + s TR) of the gate g, through 1/TG and the pilot
valve's lag 1/(1 + s TP) is the gate's velocity, non-windup on [Uc, Uo]; its integral
is the gate g, non-windup on [PMIN, PMAX]; the water column (A23 + s TW (A11 A23 - A13
A21))/(1 + s A11 TW) of g is the mechanical power.  Where the limits sit (both
non-windup: the velocity on the pilot valve lag's output, the position on the gate
integrator) is the PSS/E Model Library's IEEEG3 block diagram as the OPAL-RT ePHASORSIM
Modelica library implements it (``OpalRT.Electrical.Control.TurbineGovernor.IEEEG3``:
``Lag_NonWindupLimit`` [Uc, Uo], ``Integrator_NonWindupLimit`` [PMIN, PMAX]); not
checked against a PSS/E run.

At rest the velocity is 0, the gate g_0 = Pm0/A23 (the start-up order, refused outside
[PMIN, PMAX] by `stabctl.models.governors.initialise`), the transient droop's state g_0
(its output 0), the water column's state (1 - r) Pm0 (`blocks.leadlag` with K = A23, r =
TW (A11 A23 - A13 A21)/A23 over A11 TW), and P_ref = SIGMA g_0 (PSS/E's reference at the
summing junction, in gate units times SIGMA; a P_ref step dP settles at Pm0 + A23 dP/SIGMA).
A pilot valve lag TP below 1e-3 s drops its block (the velocity is the clamped input), a
TR below 1e-3 s the transient droop, an A11 TW below 1e-3 s the water column's dynamics
(the power A23 g).

The DYR record TG TP Uo Uc PMAX PMIN SIGMA DELTA TR TW A11 A13 A21 A23 (PSS/E Model
Library IEEEG3; PowerWorld's IEEEG3; the CIM's GovHydroIEEE2 without its gate table):
TG, TP, Uo, Uc, PMAX, PMIN, TW in the shared columns Ts, Tc, Uo, Uc, Tmax, Tmin, T4; the
others in IEEEG3's own (``PARAMS``).  Sources: PSS/E Model Library IEEEG3; IEEE Committee
Report, "Dynamic Models for Steam and Hydro Turbines in Power System Studies", IEEE
Trans. PAS-92 (1973) p. 1904; docs/pst_models.md 4.12.  ANDES 2.0 has no IEEEG3.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.models.blocks import LBND, lag, leadlag, nonwindup, nonwindup_lag
from stabctl.models.declaration import DyrModel, Limits, Param, states
from stabctl.models.governors.table import AT_LIMIT, AT_RATED_SPEED, G, own

if TYPE_CHECKING:
    from stabctl.models.governors import GovernorParams

IEEEG3 = 15
KINDS = {IEEEG3: "IEEEG3"}
#: the speed set point w_f (`table.AT_RATED_SPEED`), the water time constant T_W >= 0 and
#: the gate's power A23 > 0 (PSS/E Model Library IEEEG3)
LIMITS = (
    AT_RATED_SPEED,
    Limits("PSS/E Model Library IEEEG3", nonnegative=("Tw",), positive=("a23",)),
)
#: the time constants that must be >= 1e-3 s (declared tg_con fields): the gate
#: servomotor TG (its gain 1/TG)
NEEDS: tuple[str, ...] = ("Ts",)
#: the family refuses a start-up order (`initialise`'s order) outside [Tmin, Tmax]:
#: PMAX, PMIN on the start-up gate Pm0/A23
ORDER_LIMITS = True
#: IEEEG3's own tg_con columns
PARAMS = (
    Param("sigma", "pu", 80, lo=0.0, doc="IEEEG3: permanent droop SIGMA"),
    Param("delta", "pu", 81, lo=0.0, doc="IEEEG3: transient droop DELTA"),
    Param("Tr", "s", 82, lo=0.0, doc="IEEEG3: transient droop (dashpot) time constant TR"),
    Param("a11", "pu", 83, lo=0.0, doc="IEEEG3: water column coefficient A11"),
    Param("a13", "pu", 84, doc="IEEEG3: water column coefficient A13"),
    Param("a21", "pu", 85, doc="IEEEG3: water column coefficient A21"),
    Param("a23", "pu", 86, doc="IEEEG3: water column coefficient A23 (> 0)"),
)
#: the packed columns of `PARAMS`: P[k, O.SIGMA]
O = own("IEEEG3Columns", PARAMS)
DYR = (
    DyrModel(
        "IEEEG3",
        (
            "TG",
            "TP",
            "Uo",
            "Uc",
            "PMAX",
            "PMIN",
            "SIGMA",
            "DELTA",
            "TR",
            "TW",
            "A11",
            "A13",
            "A21",
            "A23",
        ),
        {
            "Ts": "TG",
            "Tc": "TP",
            "Uo": "Uo",
            "Uc": "Uc",
            "Tmax": "PMAX",
            "Tmin": "PMIN",
            "sigma": "SIGMA",
            "delta": "DELTA",
            "Tr": "TR",
            "T4": "TW",
            "a11": "A11",
            "a13": "A13",
            "a21": "A21",
            "a23": "A23",
        },
        kind=IEEEG3,
    ),
)

#: the states: the pilot valve (the gate's velocity), the gate, the transient droop's
#: lag of the gate, the water column's
S = states("IEEEG3States", ("velocity", "gate", "droop", "water"))
STATE_NAMES = {IEEEG3: S._fields}


def _water_lag(p: GovernorParams):
    """The water column's lag A11 TW (s), per row."""
    return p.a11 * p.T4


def has_state(p: GovernorParams):
    """Which slots of `S` are states: the pilot valve with TP, the gate, the transient
    droop with TR, the water column with A11 TW (each >= 1e-3 s)."""
    return (p.Tc >= LBND, np.ones(p.n, bool), p.Tr >= LBND, _water_lag(p) >= LBND)


def time_constants(p: GovernorParams):
    """The declared time constants that set a state's speed: field -> where (the water
    column's lag is A11 TW; its declared field TW, T4, stands for it)."""
    return {"Tc": p.Tc >= LBND, "Tr": p.Tr >= LBND, "T4": _water_lag(p) >= LBND}


def start_order(p: GovernorParams, r, pmech0, total):
    """IEEEG3's start-up order on rows r: the gate Pm0/A23."""
    return total[r] / p.a23[r]


def initialise(p: GovernorParams, r, pmech0, gate, x):
    """IEEEG3 at rest on rows r (module docstring): the velocity 0, the gate and the
    transient droop's lag at the gate g_0 (from the family), the water column's state
    (1 - r) A23 g_0; returns P_ref = SIGMA g_0 on r."""
    lag_w = _water_lag(p)[r]
    ratio = np.where(lag_w >= LBND, p.T4[r] * (p.a11[r] * p.a23[r] - p.a13[r] * p.a21[r]), 0.0)
    ratio = ratio / np.where(lag_w >= LBND, p.a23[r] * lag_w, 1.0)
    x[S.velocity, r] = 0.0
    x[S.gate, r] = gate[r]
    x[S.droop, r] = np.where(p.Tr[r] >= LBND, gate[r], 0.0)
    x[S.water, r] = np.where(lag_w >= LBND, (1.0 - ratio) * p.a23[r] * gate[r], 0.0)
    return p.sigma[r] * gate[r]


@kernel(inline="always")
def _water(P, x, k):
    """The water column (A23 + s TW (A11 A23 - A13 A21))/(1 + s A11 TW) of the gate: its
    output, its state's derivative."""
    a23, tw = P[k, O.A23], P[k, G.T4]
    lead = tw * (P[k, O.A11] * a23 - P[k, O.A13] * P[k, O.A21]) / a23
    return leadlag(x[S.gate, k], x[S.water, k], lead, P[k, O.A11] * tw, a23)


@kernel(inline="always")
def pmech(P, x, k, omega):
    """IEEEG3: the water column's output (module docstring)."""
    return _water(P, x, k)[0]


@kernel(inline="always")
def derivatives(P, x, k, omega, pe, dx):
    """IEEEG3 (module docstring): w_f - omega + P_ref - SIGMA g - DELTA TR s/(1 + s TR) g
    over TG through the pilot valve's lag TP, non-windup on [Uc, Uo], into the gate's
    integrator, non-windup on [PMIN, PMAX] (clamps the gate in x); the water column."""
    g = x[S.gate, k]
    tr = P[k, O.TR]
    transient = 0.0
    if tr >= LBND:
        _, d_droop = lag(g, x[S.droop, k], tr)
        transient = P[k, O.DELTA] * tr * d_droop
        dx[S.droop, k] = d_droop
    u = (P[k, G.WF] - omega + P[k, G.PREF] - P[k, O.SIGMA] * g - transient) / P[k, G.TS]
    if P[k, G.TC] >= LBND:
        x[S.velocity, k], dx[S.velocity, k] = nonwindup_lag(
            u, x[S.velocity, k], P[k, G.TC], P[k, G.UC], P[k, G.UO], AT_LIMIT, 0.0
        )
        v = x[S.velocity, k]
    else:
        v = min(max(u, P[k, G.UC]), P[k, G.UO])
    x[S.gate, k], dx[S.gate, k] = nonwindup(g, v, P[k, G.TMIN], P[k, G.TMAX], AT_LIMIT, 0.0)
    dx[S.water, k] = _water(P, x, k)[1]
