"""PSS/E's IEEEG2 (tg_con type 14): the IEEE Committee Report 1973 simplified hydro
governor-turbine.

The speed error w_f - omega through K (1 + s T2)/((1 + s T1)(1 + s T3)) (the governor's
lead-lag and its gate actuator's lag), added to P_ref, is the gate, clamped to [PMIN,
PMAX]; the water column (1 - s T4)/(1 + s T4/2) gives the mechanical power.  At rest the
speed error is 0: the lead-lag's and the lag's states are 0, the gate is P_ref = Pm0
(refused outside [PMIN, PMAX] by `stabctl.models.governors.initialise`), the water
column's state 3 Pm0 (`blocks.leadlag`'s (1 - r) Pm0, r = -2).  A lag below 1e-3 s drops
its block (T1: the lead-lag is the gain K; T4/2: no water column).  The DYR record K T1
T2 T3 PMAX PMIN T4 (PowerWorld's IEEEG2; the CIM's GovHydroIEEE0) in the shared columns
invR, Tc (lag T1), T3 (lead T2), Ts (lag T3), Tmax, Tmin, T4.  Sources: PSS/E Model
Library IEEEG2; IEEE Committee Report, "Dynamic Models for Steam and Hydro Turbines in
Power System Studies", IEEE Trans. PAS-92 (1973) p. 1904; docs/pst_models.md 4.11.
ANDES 2.0 has no IEEEG2.
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

IEEEG2 = 14
KINDS = {IEEEG2: "IEEEG2"}
#: the speed set point w_f (`table.AT_RATED_SPEED`) and the water time constant T_W >= 0
#: (PSS/E Model Library IEEEG2); the lead T2 (tg_con T3, no bound of its own) >= 0 (round
#: 42: T2 = -0.5 was run as given)
LIMITS = (AT_RATED_SPEED, Limits("PSS/E Model Library IEEEG2", nonnegative=("Tw", "T3")))
#: the time constants that must be >= 1e-3 s (declared tg_con fields): none (each lag
#: may be absent)
NEEDS: tuple[str, ...] = ()
#: the family refuses a start-up order (`initialise`'s order) outside [Tmin, Tmax]:
#: PMAX, PMIN on the power order (P_ref)
ORDER_LIMITS = True
DYR = (
    DyrModel(
        "IEEEG2",
        ("K", "T1", "T2", "T3", "PMAX", "PMIN", "T4"),
        {
            "invR": "K",
            "Tc": "T1",
            "T3": "T2",
            "Ts": "T3",
            "Tmax": "PMAX",
            "Tmin": "PMIN",
            "T4": "T4",
        },
        kind=IEEEG2,
    ),
)

#: the states: the lead-lag's (lag T1), the gate actuator's lag T3, the water column's
S = states("IEEEG2States", ("leadlag", "actuator", "water"))
STATE_NAMES = {IEEEG2: S._fields}


def has_state(p: GovernorParams):
    """Which slots of `S` are states: each block whose lag is >= 1e-3 s."""
    return (p.Tc >= LBND, p.Ts >= LBND, p.T4 / 2 >= LBND)


def time_constants(p: GovernorParams):
    """The declared time constants that set a state's speed: field -> where."""
    return {"Tc": p.Tc >= LBND, "Ts": p.Ts >= LBND, "T4": p.T4 / 2 >= LBND}


def check(g, r: int) -> str | None:
    """The first IEEEG2 option of tg_con row r (0-based) stabctl does not model, with the
    reason, or None: a lead T2 without its lag T1 (PMAX below PMIN is the tg_con table's
    check, the family's limits)."""
    if g.T3[r] != 0 and g.Tc[r] < LBND:
        return "fields 'T3', 'Tc': IEEEG2's lead T2 needs its lag T1 >= 1e-3 s"
    return None


def initialise(p: GovernorParams, r, pmech0, order, x):
    """IEEEG2 at rest on rows r (module docstring): the water column's state 3 pmech0
    where it exists (the others stay 0); returns P_ref, the power order (pmech0), on r."""
    x[S.water, r] = np.where(p.T4[r] / 2 >= LBND, 3.0 * pmech0[r], 0.0)
    return order[r]


@kernel(inline="always")
def _chain(P, x, k, omega):
    """The lead-lag K (1 + s T2)/(1 + s T1) on w_f - omega and the actuator's lag T3:
    the lead-lag's derivative, the actuator's output and derivative."""
    y, d_leadlag = leadlag(
        P[k, G.WF] - omega, x[S.leadlag, k], P[k, G.T3], P[k, G.TC], P[k, G.INVR]
    )
    a, d_actuator = lag(y, x[S.actuator, k], P[k, G.TS])
    return d_leadlag, a, d_actuator


@kernel(inline="always")
def _water(P, x, k, omega):
    """The water column (1 - s T4)/(1 + s T4/2) on the gate P_ref + the actuator's output,
    clamped to [PMIN, PMAX]: its output, its state's derivative."""
    a = _chain(P, x, k, omega)[1]
    gate = clip(P[k, G.PREF] + a, P[k, G.TMIN], P[k, G.TMAX])
    tw = P[k, G.T4]
    return leadlag(gate, x[S.water, k], -tw, tw / 2.0)


@kernel(inline="always")
def pmech(P, x, k, omega):
    """IEEEG2: the water column's output (module docstring)."""
    return _water(P, x, k, omega)[0]


@kernel(inline="always")
def derivatives(P, x, k, omega, pe, dx):
    """IEEEG2 (module docstring): the lead-lag K (1 + s T2)/(1 + s T1) on w_f - omega, the
    actuator's lag T3, the water column."""
    dx[S.leadlag, k], _, dx[S.actuator, k] = _chain(P, x, k, omega)
    dx[S.water, k] = _water(P, x, k, omega)[1]
