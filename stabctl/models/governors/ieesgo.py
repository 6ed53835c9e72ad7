"""PSS/E's IEESGO (tg_con type 5): the IEEE standard steam governor.

K_1 (omega - 1) through 1/(1 + s T_1) and (1 + s T_2)/(1 + s T_3), P_ref minus it limited
to [PMIN, PMAX], lags T_4, T_5, T_6, pmech = (1 - K_2) y_4 + (1 - K_3) K_2 y_5 + K_2 K_3
y_6 (the IEEEG1 fraction columns K1, K3, K5).  Source: PSS/E Model Library IEESGO; ANDES
2.0 ``andes/models/governor/ieesgo.py``; docs/pst_models.md 4.3.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.models.blocks import LBND, clip, lag, leadlag
from stabctl.models.declaration import DyrModel, Limits, states
from stabctl.models.governors.table import G, fractions

if TYPE_CHECKING:
    from stabctl.models.governors import GovernorParams

IEESGO = 5
KINDS = {IEESGO: "IEESGO"}
#: the time constants that must be >= 1e-3 s (declared tg_con fields): none
NEEDS: tuple[str, ...] = ()
#: the lead-lag (1 + s T2)/(1 + s T3) (tg_con T3 over Ts): a lead without its lag is
#: refused (round 41: T2 without T3 had no effect on the run); the lead T2 (tg_con T3)
#: and the lags T4, T5, T6 are time constants, >= 0 (round 42: T4 = -0.3 ran as T4 = 0,
#: the lag bypassed; tg_con T4 has no bound of its own, hydro types read it otherwise)
LIMITS = Limits(
    "PSS/E Model Library IEESGO: the lead-lag (1 + s T2)/(1 + s T3)",
    nonnegative=("T3", "T4"),  # T5, T6: tg_con columns bounded >= 0 for every type
    leads=(("T3", "Ts"),),
)
#: the family refuses a start-up order (`initialise`'s order) outside [Tmin, Tmax]:
#: the power limits on the start-up gate
ORDER_LIMITS = True
DYR = (
    # IEESGO -> type 5: K1 (speed gain), lag T1, lead-lag T2/T3, limits, lags T4-T6;
    # the power fractions after T4, T5, T6 (1 - K2, (1 - K3) K2, K2 K3) computed
    DyrModel(
        "IEESGO",
        ("T1", "T2", "T3", "T4", "T5", "T6", "K1", "K2", "K3", "PMAX", "PMIN"),
        {
            "Tc": "T1",
            "T3": "T2",
            "Ts": "T3",
            "T4": "T4",
            "T5": "T5",
            "T6": "T6",
            "invR": "K1",
            "Tmax": "PMAX",
            "Tmin": "PMIN",
        },
        kind=IEESGO,
        andes=("IEESGO",),
    ),
)

#: the states: the speed lag, the lead-lag's, the lags T4, T5, T6 (consecutive slots)
S = states("IEESGOStates", ("lag", "leadlag", "T4lag", "T5lag", "T6lag"))
STATE_NAMES = {IEESGO: S._fields}


def has_state(p: GovernorParams):
    """Which slots of `S` are states: each block whose time constant is >= 1e-3 s."""
    return tuple(T >= LBND for T in (p.Tc, p.Ts, p.T4, p.T5, p.T6))


def time_constants(p: GovernorParams):
    """The declared time constants that set a state's speed: field -> where."""
    return {n: getattr(p, n) >= LBND for n in ("Ts", "Tc", "T4", "T5", "T6")}


def start_order(p: GovernorParams, r, pmech0, total):
    """IEESGO's start-up order on rows r: the gate, its machine's power total over the sum
    of its power fractions."""
    return total[r] / (p.K.sum(axis=1) + p.K_lp.sum(axis=1))[r]


def initialise(p: GovernorParams, r, pmech0, gate, x):
    """IEESGO at rest on rows r: the speed path at 0, the lags at the gate (pmech0 / sum
    of the fractions, from the family); returns P_ref = the gate."""
    x[S.lag, r] = 0.0
    x[S.leadlag, r] = 0.0
    for slot in (S.T4lag, S.T5lag, S.T6lag):
        x[slot, r] = gate[r]
    return gate[r]


@kernel(inline="always")
def lags(P, x, k, omega, dx=None):
    """IEESGO: outputs (4,) of the lags T4, T5, T6 (the fourth 0; a time constant below
    1e-3 s passes its input) and, given dx, the derivatives of its five states."""
    u, d0 = lag(P[k, G.INVR] * (omega - 1.0), x[S.lag, k], P[k, G.TC])
    u, d1 = leadlag(u, x[S.leadlag, k], P[k, G.T3], P[k, G.TS])
    if dx is not None:
        dx[S.lag, k], dx[S.leadlag, k] = d0, d1
    u = clip(P[k, G.PREF] - u, P[k, G.TMIN], P[k, G.TMAX])
    y = np.zeros(4)
    for r in range(3):
        u, d = lag(u, x[S.T4lag + r, k], P[k, (G.T4, G.T5, G.T6)[r]])
        if dx is not None:
            dx[S.T4lag + r, k] = d
        y[r] = u
    return y


@kernel(inline="always")
def pmech(P, x, k, omega):
    """IEESGO: the lags' outputs times their fractions."""
    return fractions(P, k, lags(P, x, k, omega))


@kernel(inline="always")
def derivatives(P, x, k, omega, pe, dx):
    """IEESGO: the derivatives of its five states into dx[:, k]."""
    lags(P, x, k, omega, dx)
