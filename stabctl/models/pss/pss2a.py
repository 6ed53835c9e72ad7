"""PSS/E's PSS2A (pss_con type 5): the IEEE 421.5 dual-input stabiliser, and the block
chain its successors PSS2B (:mod:`~stabctl.models.pss.pss2b`) and PSS2C
(:mod:`~stabctl.models.pss.pss2c`) share.

Input 1 (PSS/E code ICS1: 1 speed deviation, 3 electrical power on the machine base)
limited to [VS1MIN, VS1MAX] (PSS2B, PSS2C; none for PSS2A), washouts s Tw1/(1 + s Tw1)
and s Tw2/(1 + s Tw2) (the second absent for Tw2 < 1e-3 s), lag 1/(1 + s T6); input 2
(ICS2; 0 none) likewise on [VS2MIN, VS2MAX] through washouts Tw3, Tw4 and the lag
KS2/(1 + s T7).  The ramp-tracking filter [(1 + s T8)/(1 + s T9)^M]^N (N = 0: none) of
input 1's branch plus KS3 times input 2's, minus input 2's branch, times KS1, then the
lead-lags (1 + s T1)/(1 + s T2), (1 + s T3)/(1 + s T4) (PSS2B, PSS2C: and (1 + s T10)/(1 +
s T11); PSS2C: and (1 + s T12)/(1 + s T13)), output limits [VSTMIN, VSTMAX].  A lag or
lead-lag whose lag is below 1e-3 s passes its input (times its gain).  Sources: PSS/E
Model Library PSS2A, PSS2B, PSS2C; IEEE Std 421.5-2016 section 9.2-9.4 (PSS2A/B/C);
public statements of the same equations: OpenIPSL ``Electrical.Controls.PSSE.PSS.PSS2A``,
``PSS2B``, PowerSimulationsDynamics.jl ``pss_models.jl``.

pss_con columns: Tw (Tw1), T1-T4, ymax/ymin (VSTMAX/VSTMIN), T5/T6 (T10/T11), input1,
K1 (KS1), Tr1 (T6), input2, K2 (KS2), Tr2 (T7), and 27-44 (Tw2, Tw3, Tw4, KS3, T8, T9, M,
N, VS1MAX .. VS2MIN, T12, T13, PSSON, PSSOFF, XCOMP, TCOMP).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.arrays import zero_column
from stabctl._jit.decorators import kernel
from stabctl.models.blocks import GAIN_OVER_T, LBND, clip, lag, leadlag, washout
from stabctl.models.declaration import DyrModel, states
from stabctl.models.pss.table import POWER, SPEED, C, signal

if TYPE_CHECKING:
    from stabctl.models.pss import PssParams

PSS2A = 5
KINDS = {PSS2A: "PSS/E PSS2A"}
#: the family refuses a washout T_w below 1e-3 s (`stabctl.models.pss.pss_params`)
NEEDS_TW = True
#: pss_con input1, input2 are PSS/E input codes (else read as 0)
PSSE_INPUTS = True
#: reads the input limits VS1MIN .. VS2MAX (else -inf, +inf)
INPUT_LIMITS = False
#: the PSS2 family's ICONs and its first CONs, PSS/E order (PSS2A's whole record)
ICONS = ("ICS1", "IB1", "ICS2", "IB2", "M", "N")
CONS = ("TW1", "TW2", "T6", "TW3", "TW4", "T7", "KS2", "KS3", "T8", "T9", "KS1")
CONS += ("T1", "T2", "T3", "T4")
#: the copies every PSS2 record makes (pss_con field <- DYR field)
COPY = {
    "input1": "ICS1",
    "input2": "ICS2",
    "M": "M",
    "N": "N",
    "Tw": "TW1",
    "Tw2": "TW2",
    "Tr1": "T6",
    "Tw3": "TW3",
    "Tw4": "TW4",
    "Tr2": "T7",
    "K2": "KS2",
    "Ks3": "KS3",
    "T8": "T8",
    "T9": "T9",
    "K1": "KS1",
    "T1": "T1",
    "T2": "T2",
    "T3": "T3",
    "T4": "T4",
    "ymax": "VSTMAX",
    "ymin": "VSTMIN",
}
DYR = (DyrModel("PSS2A", ICONS + CONS + ("VSTMAX", "VSTMIN"), COPY, kind=PSS2A),)

#: most ramp-tracking filter lags, M N (PSS/E, IEEE 421.5: M N <= 8)
RTF_MAX = 8
#: the states: input 1's washouts and lag, input 2's, the ramp-tracking filter's lags
#: (consecutive slots, stage by stage), the four lead-lags', PSS2C's output switch (1 on)
S = states(
    "Pss2States",
    (
        "washout1",
        "washout2",
        "lag1",
        "washout3",
        "washout4",
        "lag2",
        *(f"rtf{i}" for i in range(1, RTF_MAX + 1)),
        "leadlag1",
        "leadlag2",
        "leadlag3",
        "leadlag4",
        "switch",
    ),
)
#: the two input branches' slots (washout, second washout, lag) as numpy scalars: the
#: `branch` kernel takes them as arguments (one compile for both branches)
_W1, _W2, _L1 = np.int64(S.washout1), np.int64(S.washout2), np.int64(S.lag1)
_W3, _W4, _L2 = np.int64(S.washout3), np.int64(S.washout4), np.int64(S.lag2)
#: state names of each PSS2 type: PSS2A and PSS2B without the switch (their kernel is
#: PSS2C's chain: the lead-lags they do not have, T10/T11 and T12/T13 0, are never states)
STATE_NAMES = {PSS2A: S._fields[: S.leadlag4 + 1]}


def check(s, r) -> str | None:
    """Why pss_con row r (0-based) cannot be a PSS2 type, or None: an input code other
    than 1 (speed) or 3 (power; input 2 may be 0), a first washout of an input below 1e-3
    s, a ramp-tracking filter with N > 0 and M = 0 (an improper filter), M N above 8 or a
    lag T9 below 1e-3 s, a lead-lag with a lead but no lag."""
    if s.input1[r] not in (SPEED, POWER) or s.input2[r] not in (0, SPEED, POWER):
        return (
            "fields 'input1', 'input2': PSS/E input codes 1 (speed) or 3 (electrical "
            "power) only (input2 may be 0; remote buses, frequency and the compensated "
            "frequency are not modelled)"
        )
    if s.input2[r] != 0 and s.Tw3[r] < LBND:
        return f"field 'Tw3': the second input's washout needs Tw3 >= {LBND} s"
    M, N = int(s.M[r]), int(s.N[r])
    if N > 0 and (M < 1 or M * N > RTF_MAX or s.T9[r] < LBND):
        return (
            f"fields 'M', 'N', 'T9': a ramp-tracking filter (N = {N}) needs 1 <= M, "
            f"M N <= {RTF_MAX} and T9 >= {LBND} s (M = {M}, T9 = {s.T9[r]:g})"
        )
    for lead, lag_ in (("T1", "T2"), ("T3", "T4"), ("T5", "T6"), ("T12", "T13")):
        if getattr(s, lag_)[r] < LBND and getattr(s, lead)[r] != 0:
            return f"fields '{lag_}', '{lead}': a lead without its lag"
    return None


def has_state(p: PssParams):
    """Which slots of `S` are states: the first washouts (the second input's with an
    input), second washouts and lags with time constants >= 1e-3 s, the filter's M N
    lags, each lead-lag with its lag, the switch (PSS2C)."""
    two = p.input2 != 0
    rtf = np.where(p.N > 0, p.M * p.N, 0)
    return (
        True,
        p.Tw2 >= LBND,
        p.Tr1 >= LBND,
        two,
        two & (p.Tw4 >= LBND),
        two & (p.Tr2 >= LBND),
        *(rtf > i for i in range(RTF_MAX)),
        *(T >= LBND for T in (p.T2, p.T4, p.T6, p.T13)),
        p.kind == 7,
    )


def time_constants(p: PssParams):
    """The declared time constants that set a state's speed: field -> where."""
    two = p.input2 != 0
    return {
        "Tw": True,
        "Tw2": p.Tw2 >= LBND,
        "Tr1": p.Tr1 >= LBND,
        "Tw3": two,
        "Tw4": two & (p.Tw4 >= LBND),
        "Tr2": two & (p.Tr2 >= LBND),
        "T9": p.N > 0,
        **{T: getattr(p, T) >= LBND for T in ("T2", "T4", "T6", "T13")},
    }


def signals(p: PssParams, r, omega, pe):
    """(u1, u2) on rows r at the initial point: the PSS/E inputs (speed deviation or
    power; 0 for no second input), before their limits."""
    u1 = np.where(p.input1[r] == SPEED, omega[r] - 1.0, pe[r])
    u2 = np.where(p.input2[r] == SPEED, omega[r] - 1.0, np.where(p.input2[r] == POWER, pe[r], 0.0))
    return u1, u2


def initialise(p: PssParams, r, u1, u2, pe0, x):
    """At rest on rows r: each input's first washout state at the limited input, every
    other block at 0 (the washouts' outputs are 0).  PSS2C's switch is set by
    `pss2c.initialise`."""
    x[S.washout1, r] = np.clip(u1[r], p.in1_lo[r], p.in1_hi[r])
    x[S.washout3, r] = np.where(p.input2[r] != 0, np.clip(u2[r], p.in2_lo[r], p.in2_hi[r]), 0.0)


@kernel(inline="always")
def branch(x, k, u, lo, hi, w1, w2, lg, Tw1, Tw2, K, T, dx):
    """One input's branch: u limited to [lo, hi], washout s Tw1/(1 + s Tw1), washout s
    Tw2/(1 + s Tw2) (none for Tw2 < 1e-3 s), lag K/(1 + s T); slots w1, w2, lg."""
    y, dx[w1, k] = washout(clip(u, lo, hi), x[w1, k], Tw1, Tw1, GAIN_OVER_T)
    if Tw2 >= LBND:
        y, dx[w2, k] = washout(y, x[w2, k], Tw2, Tw2, GAIN_OVER_T)
    y, dx[lg, k] = lag(K * y, x[lg, k], T)
    return y


@kernel(inline="always")
def output(P, x, k, omega, pe, dx):
    """The PSS2 chain before PSS2C's switch: both inputs' branches, the ramp-tracking
    filter, KS1, the lead-lags (T10/T11 in columns T5/T6, T12/T13; 0 passes), limits
    [VSTMIN, VSTMAX]; derivatives into dx[:, k] (0 where no block)."""
    zero_column(dx, k)
    u1 = signal(P[k, C.IN1], omega, pe)
    y1 = branch(
        x, k, u1, P[k, C.IN1_LO], P[k, C.IN1_HI], _W1, _W2, _L1,
        P[k, C.TW], P[k, C.TW2], 1.0, P[k, C.TR1], dx,
    )  # fmt: skip
    y2 = 0.0
    if P[k, C.IN2] != 0:
        u2 = signal(P[k, C.IN2], omega, pe)
        y2 = branch(
            x, k, u2, P[k, C.IN2_LO], P[k, C.IN2_HI], _W3, _W4, _L2,
            P[k, C.TW3], P[k, C.TW4], P[k, C.K2], P[k, C.TR2], dx,
        )  # fmt: skip
    y = y1 + P[k, C.KS3] * y2
    j = S.rtf1
    for _ in range(int(P[k, C.N])):
        for _ in range(int(P[k, C.M]) - 1):
            y, dx[j, k] = lag(y, x[j, k], P[k, C.T9])
            j += 1
        y, dx[j, k] = leadlag(y, x[j, k], P[k, C.T8], P[k, C.T9])
        j += 1
    y = P[k, C.K1] * (y - y2)
    for i, lead, lag_ in ((0, C.T1, C.T2), (1, C.T3, C.T4), (2, C.T5, C.T6), (3, C.T12, C.T13)):
        y, dx[S.leadlag1 + i, k] = leadlag(y, x[S.leadlag1 + i, k], P[k, lead], P[k, lag_])
    return clip(y, P[k, C.MIN], P[k, C.MAX])
