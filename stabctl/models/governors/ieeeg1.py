"""PSS/E's IEEEG1 (tg_con type 3): the IEEE Committee Report 1973 steam turbine.

K (1 + s T2)/(1 + s T1) on the speed deviation, the gate servo 1/T3 with rate limits
[Uc, Uo] and position limits [PMIN, PMAX] (non-windup), four lags T4..T7 in series, the
power fractions K1..K8 of their outputs (HP + LP summed: one shaft; a cross-compound
unit hands K2, K4, K6, K8 to its LP machine, tg_con column 27).  Source: PSS/E Model
Library IEEEG1; ANDES 2.0 ``andes/models/governor/ieeeg1.py``; docs/pst_models.md 4.2.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.models.blocks import LBND, clip, lag, leadlag, nonwindup
from stabctl.models.declaration import DyrModel, Limits, states
from stabctl.models.governors.table import AT_LIMIT, G, fractions

if TYPE_CHECKING:
    from stabctl.models.governors import GovernorParams

IEEEG1 = 3
KINDS = {IEEEG1: "IEEEG1"}
#: IEEEG1's steam chest time constant T4 >= 0 (PSS/E Model Library IEEEG1), and its lead
#: T2 (tg_con T3, which has no bound of its own; round 42: T2 = -0.5 was run as given)
LIMITS = Limits(
    "PSS/E Model Library IEEEG1: the lead-lag K (1 + s T2)/(1 + s T1)",
    nonnegative=("T4", "T3"),
    leads=(("T3", "Tc"),),  # DYR T2 over T1 (round 41: T2 without T1 had no effect)
)
#: the time constants that must be >= 1e-3 s (declared tg_con fields)
NEEDS = ("Ts",)
#: the family refuses a start-up order (`initialise`'s order) outside [Tmin, Tmax]:
#: the gate's non-windup limits PMAX, PMIN on the start-up gate
ORDER_LIMITS = True
DYR = (
    DyrModel(
        "IEEEG1",
        ("JBUS", "M", "K", "T1", "T2", "T3", "Uo", "Uc", "PMAX", "PMIN", "T4", "K1", "K2")
        + ("T5", "K3", "K4", "T6", "K5", "K6", "T7", "K7", "K8"),
        {
            "invR": "K",
            "Tc": "T1",
            "T3": "T2",
            "Ts": "T3",
            "Uo": "Uo",
            "Uc": "Uc",
            "Tmax": "PMAX",
            "Tmin": "PMIN",
            "T4": "T4",
            "T5": "T5",
            "T6": "T6",
            "T7": "T7",
            **{f"K{k}": f"K{k}" for k in range(1, 9)},
        },
        kind=IEEEG1,
        andes=("IEEEG1",),
    ),
)

#: the states: the lead-lag's, the gate, the lags T4..T7 (consecutive slots)
S = states("IEEEG1States", ("leadlag", "gate", "T4lag", "T5lag", "T6lag", "T7lag"))
STATE_NAMES = {IEEEG1: S._fields}


def has_state(p: GovernorParams):
    """Which slots of `S` are states: the lead-lag with T1 >= 1e-3 s, the gate, each lag
    whose time constant is >= 1e-3 s."""
    return (p.Tc >= LBND, True, *(T >= LBND for T in (p.T4, p.T5, p.T6, p.T7)))


def time_constants(p: GovernorParams):
    """The declared time constants that set a state's speed: field -> where."""
    return {"Ts": True, **{n: getattr(p, n) >= LBND for n in ("Tc", "T4", "T5", "T6", "T7")}}


def start_order(p: GovernorParams, r, pmech0, total):
    """IEEEG1's start-up order on rows r: the gate, total (its machine's power, or a
    cross-compound unit's two machines', `stabctl.models.governors.initialise`) over the
    sum of its power fractions K1..K8."""
    return total[r] / (p.K.sum(axis=1) + p.K_lp.sum(axis=1))[r]


def initialise(p: GovernorParams, r, pmech0, gate, x):
    """IEEEG1 at rest on rows r: the lead-lag at 0 (no speed deviation), the gate and every
    lag at the gate position (pmech0 / sum K, from the family); returns P_ref = the gate."""
    x[S.leadlag, r] = 0.0
    for slot in (S.gate, S.T4lag, S.T5lag, S.T6lag, S.T7lag):
        x[slot, r] = gate[r]
    return gate[r]


@kernel(inline="always")
def lags(P, x, k, dx=None):
    """Outputs (4,) of the IEEEG1 lags T4..T7 in series on the gate (a lag below 1e-3 s
    passes its input) and, given dx, their derivatives."""
    y = np.empty(4)
    u = x[S.gate, k]
    for r in range(4):
        u, d = lag(u, x[S.T4lag + r, k], P[k, (G.T4, G.T5, G.T6, G.T7)[r]])
        if dx is not None:
            dx[S.T4lag + r, k] = d
        y[r] = u
    return y


@kernel(inline="always")
def pmech(P, x, k, omega):
    """IEEEG1: the lags' outputs times their (HP or summed) fractions."""
    return fractions(P, k, lags(P, x, k))


@kernel(inline="always")
def pmech_lp(P, x, k):
    """The LP machine's power of a cross-compound IEEEG1 k (its machine's base): the
    lags' outputs times K2, K4, K6, K8, in the HP machine's base times LP_BASE."""
    y = lags(P, x, k)
    return P[k, G.LP_BASE] * (
        P[k, G.KLA] * y[0] + P[k, G.KLB] * y[1] + P[k, G.KLC] * y[2] + P[k, G.KLD] * y[3]
    )


@kernel(inline="always")
def derivatives(P, x, k, omega, pe, dx):
    """IEEEG1: K (1 + s T_2)/(1 + s T_1) on the speed deviation, the gate's rate
    (P_ref - that - gate)/T_3 limited to [Uc, Uo], position [PMIN, PMAX] non-windup."""
    u, dx[S.leadlag, k] = leadlag(
        P[k, G.INVR] * (omega - 1.0), x[S.leadlag, k], P[k, G.T3], P[k, G.TC]
    )
    rate = clip((P[k, G.PREF] - u - x[S.gate, k]) / P[k, G.TS], P[k, G.UC], P[k, G.UO])
    x[S.gate, k], dx[S.gate, k] = nonwindup(
        x[S.gate, k], rate, P[k, G.TMIN], P[k, G.TMAX], AT_LIMIT, 0.0
    )
    lags(P, x, k, dx)
