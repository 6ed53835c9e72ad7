"""stabctl's PSS/E stabiliser (pss_con type 3): PSS/E's IEEEST, ST2CUT and PSS1A.

Input lags K_i/(1 + s Tr_i) on one or two PSS/E inputs (speed deviation or electrical
power) summed, the filter (1 + A5 s + A6 s^2)/((1 + A1 s + A2 s^2)(1 + A3 s + A4 s^2)),
washout K_w s/(1 + s T_w), three lead-lags, output limits [LSMIN, LSMAX], the output
cut off (0) while the terminal voltage is outside [VCL, VCU] (IEEEST, PSS1A) or [VT0 +
VCL, VT0 + VCU] (ST2CUT, VT0 the initial terminal voltage; pss_con column 45
``cut_relative``), a 0 limit none.  Source: PSS/E
Model Library IEEEST (IEEE Std 421.5 PSS1A-type with its filter) and ST2CUT (as ANDES
``andes/models/pss/ieeest.py``, ``st2cut.py``), docs/pst_models.md 3.1.  An IEEEST
without filter whose lead-lags have their lags is PST's `pss` (types 1, 2; the mapper
in `stabctl.io.dyr` chooses).

PSS/E's PSS1A (IEEE Std 421.5-2005 PSS1A) is this model with parameters mapped: its
transducer 1/(1 + s T6) the first input lag (K1 = 1, Tr1 = T6), its washout K_S s
T5/(1 + s T5) the washout (K_w = K_S T5, T_w = T5), its filter 1/(1 + A1 s + A2 s^2) the
filter's first factor (A3..A6 = 0), its lead-lags T1/T2 and T3/T4 the first two, its
output limits and cut-off [VCL, VCU] the same columns.  The blocks are linear up to the
output limit, where both models limit, so their order (PSS1A's washout before the
filter) does not change the output.  Record: ICS A1 A2 T1 T2 T3 T4 T5 T6 KS LSMAX LSMIN
VCU VCL (PowerWorld's PSS1A, InterPSS's PSS/E DYR reader); IEEE Std 421.5-2005 section
8.1 and InterPSS's ``Ieee1992PSS1AStabilizer`` for the blocks.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.arrays import zero_column
from stabctl._jit.decorators import kernel
from stabctl.errors import CaseError
from stabctl.models.blocks import GAIN_BEFORE, LBND, clip, lag, leadlag, washout
from stabctl.models.declaration import DyrModel, Limits, Param, states
from stabctl.models.pss.table import POWER, SPEED, C, signal

if TYPE_CHECKING:
    from stabctl.models.pss import PssParams

PSSE = 3
KINDS = {PSSE: "PSS/E IEEEST, ST2CUT"}
#: the third lead time constant T5 >= 0 (PSS/E Model Library IEEEST, ST2CUT)
LIMITS = Limits("PSS/E Model Library IEEEST", nonnegative=("T5",))
#: the family refuses a washout T_w below 1e-3 s (`stabctl.models.pss.pss_params`)
NEEDS_TW = True
#: pss_con input1, input2 are PSS/E input codes (else read as 0)
PSSE_INPUTS = True
#: the type's own pss_con column: how its cut-off VCU, VCL reads the terminal voltage
PARAMS = (
    Param(
        "cut_relative",
        "code",
        45,
        choices=(0, 1),
        doc="type 3: 1 the output cut-off VCU, VCL offsets from the initial terminal "
        "voltage (PSS/E ST2CUT: VT0 + VCL < VT < VT0 + VCU; OPAL-RT's Output_Limiter_2, "
        "ANDES st2cut.py), 0 terminal voltages (IEEEST, PSS1A)",
    ),
)
#: reads the input limits VS1MIN .. VS2MAX (else -inf, +inf)
INPUT_LIMITS = False
DYR = (
    # IEEEST -> PST pss (types 1, 2) when exactly equivalent, else type 3; the mapper
    # chooses the type and computes K_Tw = KS T5
    DyrModel(
        "IEEEST",
        ("ICS", "IB", "A1", "A2", "A3", "A4", "A5", "A6", "T1", "T2", "T3", "T4", "T5", "T6")
        + ("KS", "LSMAX", "LSMIN", "VCU", "VCL"),
        {"Tw": "T6", "ymax": "LSMAX", "ymin": "LSMIN", "VCU": "VCU", "VCL": "VCL"},
        andes=("IEEEST",),
    ),
    DyrModel(
        "ST2CUT",
        ("MODE", "BUSR", "MODE2", "BUSR2", "K1", "K2", "T1", "T2", "T3", "T4", "T5", "T6")
        + ("T7", "T8", "T9", "T10", "LSMAX", "LSMIN", "VCU", "VCL"),
        {
            "input1": "MODE",
            "K1": "K1",
            "Tr1": "T1",
            "input2": "MODE2",
            "K2": "K2",
            "Tr2": "T2",
            "KTw": "T3",
            "Tw": "T4",
            "T1": "T5",
            "T2": "T6",
            "T3": "T7",
            "T4": "T8",
            "T5": "T9",
            "T6": "T10",
            "ymax": "LSMAX",
            "ymin": "LSMIN",
            "VCU": "VCU",
            "VCL": "VCL",
        },
        kind=PSSE,
        andes=("ST2CUT",),
    ),
    # PSS1A -> type 3 (module docstring); the mapper computes K_w = KS T5, sets K1 = 1
    DyrModel(
        "PSS1A",
        ("ICS", "A1", "A2", "T1", "T2", "T3", "T4", "T5", "T6", "KS")
        + ("LSMAX", "LSMIN", "VCU", "VCL"),
        {
            "input1": "ICS",
            "A1": "A1",
            "A2": "A2",
            "T1": "T1",
            "T2": "T2",
            "T3": "T3",
            "T4": "T4",
            "Tw": "T5",
            "Tr1": "T6",
            "ymax": "LSMAX",
            "ymin": "LSMIN",
            "VCU": "VCU",
            "VCL": "VCL",
        },
        kind=PSSE,
    ),
)

#: the states: the input lags, the filter's (controllable canonical form, consecutive
#: slots), the washout's, the three lead-lags' (consecutive slots)
S = states(
    "IeeestStates",
    (
        "lag1",
        "lag2",
        "filter1",
        "filter2",
        "filter3",
        "filter4",
        "washout",
        "leadlag1",
        "leadlag2",
        "leadlag3",
    ),
)
STATE_NAMES = {PSSE: S._fields}


def check(s, r) -> str | None:
    """Why pss_con row r (0-based) cannot be this type, or None: an input code other
    than 1 (speed) or 3 (power; input2 may be 0), a washout below 1e-3 s, a lead-lag
    with a lead but no lag."""
    if s.input1[r] not in (SPEED, POWER) or s.input2[r] not in (0, SPEED, POWER):
        return (
            "fields 'input1', 'input2': PSS/E input codes 1 (speed) or 3 (electrical "
            "power) only (input2 may be 0)"
        )
    for lead_name, lag_name in (("T1", "T2"), ("T3", "T4"), ("T5", "T6")):
        if getattr(s, lag_name)[r] < LBND and getattr(s, lead_name)[r] != 0:
            return f"fields '{lag_name}', '{lead_name}': a lead without its lag"
    return None


def filters(s):
    """IEEEST filter N(s)/D(s), N = 1 + A5 s + A6 s^2, D = (1 + A1 s + A2 s^2)(1 + A3 s +
    A4 s^2), in controllable canonical form (DC gain 1) on the type-3 rows of the
    pss_con table s: order nf (n,), monic denominator coefficients fa (n, 4), output
    coefficients fc (n, 4), feedthrough fe (n,); 0 (fe 1) on the other rows.

    Raises CaseError (pss_con row, fields 'A5', 'A6') for a numerator of higher order
    than the denominator."""
    n = len(s)
    nf, fa, fc, fe = np.zeros(n, int), np.zeros((n, 4)), np.zeros((n, 4)), np.ones(n)
    for r in np.nonzero(s.type == PSSE)[0]:
        den = np.polymul([s.A4[r], s.A3[r], 1.0], [s.A2[r], s.A1[r], 1.0])[::-1]  # ascending
        num = np.array([1.0, s.A5[r], s.A6[r]])
        order = int(np.max(np.nonzero(den)[0]))
        if np.any(num[order + 1 :] != 0):
            raise CaseError(
                f"pss_con row {r + 1}, fields 'A5', 'A6': filter numerator of "
                f"higher order than its denominator ({order})"
            )
        if order == 0:
            continue
        a, b = den[:order] / den[order], np.append(num, np.zeros(3))[: order + 1] / den[order]
        nf[r], fe[r] = order, b[order]
        fa[r, :order] = a
        fc[r, :order] = b[:order] - b[order] * a
    return nf, fa, fc, fe


def has_state(p: PssParams):
    """Which slots of `S` are states: each input lag with Tr_i >= 1e-3 s (the second
    with an input), the filter's nf, the washout, each lead-lag with its lag."""
    return (
        p.Tr1 >= LBND,
        (p.input2 != 0) & (p.Tr2 >= LBND),
        *(p.nf >= r for r in range(1, 5)),
        True,
        *(T >= LBND for T in (p.T2, p.T4, p.T6)),
    )


def time_constants(p: PssParams):
    """The declared time constants that set a state's speed: field -> where."""
    return {
        "Tw": True,
        "T2": p.T2 >= LBND,
        "T4": p.T4 >= LBND,
        "T6": p.T6 >= LBND,
        "Tr1": p.Tr1 >= LBND,
        "Tr2": (p.input2 != 0) & (p.Tr2 >= LBND),
    }


def signals(p: PssParams, r, omega, pe):
    """(u1, u2) on rows r at the initial point: the PSS/E inputs (speed deviation or
    power; 0 for no second input)."""
    u1 = np.where(p.input1[r] == SPEED, omega[r] - 1.0, pe[r])
    u2 = np.where(p.input2[r] == SPEED, omega[r] - 1.0, np.where(p.input2[r] == POWER, pe[r], 0.0))
    return u1, u2


def initialise(p: PssParams, r, u1, u2, pe0, x):
    """At rest on rows r: the input lags at K_i u_i, filter state 1 at its input times
    the denominator's leading coefficient (controllable form, zero derivative), the
    washout's state at the filter's input, the others 0."""
    y1 = np.where(p.Tr1[r] >= LBND, p.K1[r] * u1[r], 0.0)
    y2 = np.where(p.Tr2[r] >= LBND, p.K2[r] * u2[r], 0.0)
    v = p.K1[r] * u1[r] + p.K2[r] * u2[r]
    x[S.lag1, r] = y1
    x[S.lag2, r] = y2
    nf = p.nf[r]
    x[S.filter1, r] = np.where(nf >= 1, v / np.where(nf >= 1, p.fa[r, 0], 1.0), 0.0)
    x[S.washout, r] = v


@kernel(inline="always")
def output(P, x, k, omega, pe, dx):
    """PSS/E stabiliser: input lags K_i/(1 + s Tr_i) summed, filter N/D, washout
    K_w s/(1 + s T_w), three lead-lags, output limits (docs 3.1)."""
    zero_column(dx, k)
    v = 0.0
    for r, code, K, T in ((S.lag1, C.IN1, C.K1, C.TR1), (S.lag2, C.IN2, C.K2, C.TR2)):
        u, dx[r, k] = lag(P[k, K] * signal(P[k, code], omega, pe), x[r, k], P[k, T])
        v += u
    nf = int(P[k, C.NF])
    w = P[k, C.FE] * v
    if nf > 0:
        acc = v
        for i in range(nf):
            w += P[k, C.FC0 + i] * x[S.filter1 + i, k]
            acc -= P[k, C.FA0 + i] * x[S.filter1 + i, k]
            if i < nf - 1:
                dx[S.filter1 + i, k] = x[S.filter2 + i, k]
        dx[S.filter1 + nf - 1, k] = acc
    y, dx[S.washout, k] = washout(w, x[S.washout, k], P[k, C.TW], P[k, C.KTW], GAIN_BEFORE)
    for j, lead, lag_ in ((0, C.T1, C.T2), (1, C.T3, C.T4), (2, C.T5, C.T6)):
        y, dx[S.leadlag1 + j, k] = leadlag(y, x[S.leadlag1 + j, k], P[k, lead], P[k, lag_])
    return clip(y, P[k, C.MIN], P[k, C.MAX])
