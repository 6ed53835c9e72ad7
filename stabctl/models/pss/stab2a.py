"""PSS/E's STAB2A (pss_con type 4): the ASEA power sensitive stabilising unit.

Electrical power (machine base) through -(K_2 T_2 s/(1 + s T_2))^3, then K_3/(1 + s T_3)
+ K_4, then (K_5/(1 + s T_5))^2, limited to +-HLIM (a lag below 1e-3 s passes its
input).  Source: PSS/E Model Library STAB2A; block diagram as OpenIPSL
``OpenIPSL.Electrical.Controls.PSSE.PSS.STAB2A``; docs/pst_models.md 3.1.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.arrays import zero_column
from stabctl._jit.decorators import kernel
from stabctl.models.blocks import GAIN_AFTER, LBND, clip, lag, washout
from stabctl.models.declaration import DyrModel, states
from stabctl.models.pss.table import C

if TYPE_CHECKING:
    from stabctl.models.pss import PssParams

STAB2A = 4
KINDS = {STAB2A: "PSS/E STAB2A"}
#: the family refuses a washout T_w below 1e-3 s (`stabctl.models.pss.pss_params`)
NEEDS_TW = True
#: pss_con input1, input2 are PSS/E input codes (else read as 0)
PSSE_INPUTS = False
#: reads the input limits VS1MIN .. VS2MAX (else -inf, +inf)
INPUT_LIMITS = False
DYR = (
    # STAB2A -> type 4: three washouts K2 T2 s/(1 + s T2) (KTw = K2 T2 computed), K3/(1 +
    # s T3) + K4, two lags K5/(1 + s T5), output limits +-HLIM
    DyrModel(
        "STAB2A",
        ("K2", "T2", "K3", "T3", "K4", "K5", "T5", "HLIM"),
        {
            "Tw": "T2",
            "K1": "K3",
            "Tr1": "T3",
            "K2": "K4",
            "K5": "K5",
            "T6": "T5",
            "ymax": "HLIM",
        },
        kind=STAB2A,
    ),
)

#: the states: the three washouts' (consecutive slots), the T_3 lag's, the two T_5 lags'
S = states("Stab2aStates", ("washout1", "washout2", "washout3", "lag3", "lag5a", "lag5b"))
STATE_NAMES = {STAB2A: S._fields}


def check(s, r) -> str | None:
    """Nothing beyond the washout every PSS/E type needs (checked by the family)."""
    return None


def has_state(p: PssParams):
    """Which slots of `S` are states: the washouts, the T_3 lag with T_3 >= 1e-3 s, the
    T_5 lags with T_5 >= 1e-3 s."""
    return (True, True, True, p.Tr1 >= LBND, p.T6 >= LBND, p.T6 >= LBND)


def time_constants(p: PssParams):
    """The declared time constants that set a state's speed: field -> where."""
    return {"Tw": True}


def signals(p: PssParams, r, omega, pe):
    """(u1, u2) on rows r at the initial point: the power, 0."""
    return pe[r], np.zeros(np.count_nonzero(r))


def initialise(p: PssParams, r, u1, u2, pe0, x):
    """At rest on rows r: the first washout's state at the power u1, the others 0."""
    x[S.washout1, r] = u1[r]


@kernel(inline="always")
def output(P, x, k, omega, pe, dx):
    """STAB2A: -(K_Tw s/(1 + s T_w))^3 on pe (K_Tw = K_2 T_2, T_w = T_2), then
    K_3/(1 + s T_3) + K_4 (columns K1, Tr1, K2), then (K_5/(1 + s T_5))^2 (columns K5 = T5,
    T6), limited to [ymin, ymax]."""
    zero_column(dx, k)
    y = pe
    for r in range(3):
        y, dx[S.washout1 + r, k] = washout(
            y, x[S.washout1 + r, k], P[k, C.TW], P[k, C.KTW], GAIN_AFTER
        )
    y = -y
    y3, dx[S.lag3, k] = lag(P[k, C.K1] * y, x[S.lag3, k], P[k, C.TR1])
    y = y3 + P[k, C.K2] * y
    for r in (S.lag5a, S.lag5b):
        y, dx[r, k] = lag(P[k, C.T5] * y, x[r, k], P[k, C.T6])
    return clip(y, P[k, C.MIN], P[k, C.MAX])
