"""REGCA1, the WECC second-generation renewable generator/converter interface (REGC_A;
ANDES 2.0 ``renewable/regca1.py``, and ``regcp1.py`` for its PLL, :mod:`.pll`): its DYR
record, its named states, its output currents and its derivatives (docs/ibr.md).

The converter lags its current commands (Ipcmd, Iqcmd: constant, or its electrical
control's, :mod:`.reeca1`) through Tg with the rate limits Rrpwr (Ip) and Iqrmax, Iqrmin
(Iq; pu/s on the currents under PSS/E's reading, on Tg times them under ANDES's:
`rate_scale`), the Ip state held under the low-voltage power logic LVPL of the voltage filtered
through Tfltr; its output currents are Ip times the low-voltage gain LVG and Iq less the
high-voltage management.  Its parameters are ibr_con columns 39-52 (:mod:`.table`).
"""

from __future__ import annotations

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.models.blocks import lag, magnitude_rate
from stabctl.models.converters.reeca1 import RE
from stabctl.models.converters.table import NO_REEC, REGC_A, REGCA1, C
from stabctl.models.declaration import DyrModel, slots

DYR = (
    #: REGC_A (PSS/E Model Library "REGCA1"): ICON Lvplsw, then 14 CONs; Accel, the
    #: network solution's acceleration factor, is not a model parameter
    DyrModel(
        "REGCA1",
        (
            "Lvplsw",
            *("Tg", "Rrpwr", "Brkpt", "Zerox", "Lvpl1", "Volim", "Lvpnt1", "Lvpnt0"),
            *("Iolim", "Tfltr", "Khv", "Iqrmax", "Iqrmin", "Accel"),
        ),
        {n: n for n in ("Lvplsw", "Tg", "Rrpwr", "Brkpt", "Zerox", "Lvpl1", "Volim")}
        | {n: n for n in ("Lvpnt1", "Lvpnt0", "Iolim", "Tfltr", "Khv", "Iqrmax", "Iqrmin")},
    ),
)

#: the REGCA1's slots: its Ip and Iq lags and its voltage filter (its state of charge, with
#: a battery's electrical control, is the electrical control's slot ``SOC``, `reeca1.RE`)
RG = slots("REGCA1Slots", ("Ip", "Iq", "V_filter"))
#: the slot after them, a PVD1's washout: no state of a REGCA1 (its derivative 0)
SPARE = np.int64(len(RG))


@kernel
def _lvg(v, Lvpnt0, Lvpnt1, kLVG):
    """REGCA1's low-voltage active-current gain LVG (ANDES Piecewise, regca1.py 192-196):
    0 at v <= Lvpnt0, (v - Lvpnt0) kLVG up to Lvpnt1, 1 above."""
    if v <= Lvpnt0:
        return 0.0
    if v <= Lvpnt1:
        return (v - Lvpnt0) * kLVG
    return 1.0


#: a bus voltage within this of LVG's upper breakpoint Lvpnt1 sits on it (pu)
ON_BREAKPOINT = 1e-9
#: how far `flat_side_of_lvg` moves the breakpoint below such a voltage (pu): beyond any
#: voltage change of a linearisation's perturbation
BREAKPOINT_SHIFT = 1e-3


def flat_side_of_lvg(P: np.ndarray, v0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The packed parameters P (n, len(C)) with the low-voltage gain of each REGCA1 whose
    bus voltage v0 (n,) pu sits on its upper breakpoint Lvpnt1 (within ON_BREAKPOINT;
    ANDES's default Lvpnt1 = 1 at a bus held at 1 pu: kundur_wtdta1) flat around it:
    Lvpnt1 moved BREAKPOINT_SHIFT below v0, LVG = 1 there (kLVG, the ramp's slope, kept).
    LVG has no derivative at the breakpoint; a linearisation on its flat side is what
    ANDES 2.0's EIG gives (docs/modal.md).  Returns (the copy, the rows moved); P itself
    is not changed."""
    on = (
        (P[:, C.TYPE] == REGCA1)
        & (P[:, C.REGC] == REGC_A)
        & (np.abs(v0 - P[:, C.LVPNT1]) <= ON_BREAKPOINT)
    )
    out = P.copy()
    out[on, C.LVPNT1] = v0[on] - BREAKPOINT_SHIFT
    return out, np.nonzero(on)[0]


@kernel
def currents(P, x, k, v):
    """REGCA1's output currents (Ipout, Iqout) of device k at voltage magnitude v (ANDES
    regca1.py 258-278): Ipout = Ip LVG(v); Iqout = Iq - HVG, HVG = Khv (v - Volim) at or
    above 0 (GainLimiter, lower 0), Iqout held at Iolim at or below it.  PSS/E's reading
    (``psse`` 1): LVPL limits the output, min(Ip, LVPL), and not the state (`_at_lvpl`),
    so that a limit falling below an Ip that has reached its command binds and the lag
    runs on toward its command beneath it (Dynawo's ``REGCa.mo``: a VariableLimiter after
    the lag; OpenIPSL's ``REGCA1.mo``: its variableLimiter after the integrator), where
    ANDES's AntiWindup holds the state at the limit only while driven into it and the
    output is the state (round 52, AL08)."""
    Ip = x[RG.Ip, k]
    if P[k, C.PSSE] == 1.0:
        Ip = min(Ip, _ip_limits(P, x, k)[0])
    Ipout = Ip * _lvg(v, P[k, C.LVPNT0], P[k, C.LVPNT1], P[k, C.KLVG])
    HVG = P[k, C.KHV] * (v - P[k, C.VOLIM])
    if HVG <= 0.0:
        HVG = 0.0
    Iqout = x[RG.Iq, k] - HVG
    if Iqout <= P[k, C.IOLIM]:
        Iqout = P[k, C.IOLIM]
    return Ipout, Iqout


@kernel
def ipcmd(P, x, k):
    """REGCA1 k's active current command: Ipcmd0, or with a REECA1 its last command
    (slot ``Ipcmd_last``, ANDES's algebraic Ipcmd of the previous iterate, which its
    anti-windup check reads before the network solution)."""
    if P[k, C.REEC] != NO_REEC:
        return x[RE.Ipcmd_last, k]
    return P[k, C.IPCMD0]


@kernel
def rate_scale(P, k):
    """What REGCA1 k's rate limits Rrpwr, Iqrmax and Iqrmin bound, as a factor on them in
    the lag's equation value e = Tg dy/dt: Tg under PSS/E's reading (``psse`` 1: the
    Model Library's unit, pu/s, on dy/dt, as GridPACK's ``regca1.cpp`` ``setdxlimits``,
    InterPSS's ``Regca1Model`` and Dynawo's ``BaseREGC.mo`` bound it; round 54, AL09), 1
    under ANDES's (its RateLimiter compares the right-hand side Tg dy/dt, not dy/dt:
    andes/core/discrete.py RateLimiter.check_eq, as OpenIPSL's ``REGCA1.mo``)."""
    if P[k, C.PSSE] == 1.0:
        return P[k, C.TG]
    return 1.0


@kernel
def _ip_limits(P, x, k):
    """REGCA1's Ip lag S0 (ANDES regca1.py 238-256) at the states x: the LVPL upper limit
    (Piecewise, 242-249) of the filtered voltage S2 (slot V_filter) and the equation value e =
    Ipcmd - Ip after the rate limit Rrpwr (`rate_scale`): on its rise under ANDES's
    reading; under PSS/E's on the rise of |Ip|, the rise for a command >= 0 and the fall
    for one < 0 (a battery charging), as REGCB1's (:mod:`.regcb1`)."""
    S2 = x[RG.V_filter, k]
    sw = P[k, C.LVPLSW]
    if S2 <= P[k, C.ZEROX]:
        LVPL = 9999.0 * (1.0 - sw)
    elif S2 <= P[k, C.BRKPT]:
        LVPL = (S2 - P[k, C.ZEROX]) * P[k, C.KLVPL] + 9999.0 * (1.0 - sw)
    else:
        LVPL = 9999.0
    cmd = ipcmd(P, x, k)
    e = cmd - x[RG.Ip, k]
    cap = P[k, C.RRPWR] * rate_scale(P, k)
    if P[k, C.PSSE] == 1.0:
        return LVPL, magnitude_rate(e, cmd, cap)
    return LVPL, min(e, cap)


@kernel
def _at_lvpl(P, x, k, reach):
    """Whether REGCA1 k's Ip is held on its LVPL limit: at or above it with a
    non-negative e, or driven into it within `reach` s (`blocks.nonwindup`'s rule for a
    moving limit: the LVPL rises with the filtered voltage after a dip, and a state left
    a hair below it at each step would alternate between the full derivative and 0).
    Returns (held, LVPL, e)."""
    LVPL, e = _ip_limits(P, x, k)
    if P[k, C.PSSE] == 1.0:  # PSS/E: the limit on the output only (`currents`)
        return False, LVPL, e
    held = e >= 0.0 and x[RG.Ip, k] + reach * e / P[k, C.TG] >= LVPL
    return held, LVPL, e


@kernel
def clamp_states(P, x, k, reach):
    """Clamp device k's limited states in place before the network solution, as ANDES's
    AntiWindup does within its iteration (andes/core/discrete.py AntiWindup.check_eq):
    REGCA1's Ip at its LVPL limit when held there (`_at_lvpl`; reach 0: at or above it
    with a non-negative e).  Other types and a REGC_B (``regc`` 1): nothing."""
    if P[k, C.TYPE] == REGCA1 and P[k, C.REGC] == REGC_A:
        held, LVPL, _ = _at_lvpl(P, x, k, reach)
        if held:
            x[RG.Ip, k] = LVPL


@kernel
def derivatives(P, x, k, v, Iq_target, reach, dx):
    """REGCA1's state derivatives of device k at voltage magnitude v (ANDES regca1.py
    219-256) toward its commands (`ipcmd`, Iq_target = -Iqcmd), slots `RG` and `SPARE`
    of column k of dx (the Ip state clamped first, `clamp_states` with `reach`)."""
    _, dx[RG.V_filter, k] = lag(v, x[RG.V_filter, k], P[k, C.TFLTR])
    # S0: Ip lag with the rate limit, then the anti-windup upper limit LVPL
    clamp_states(P, x, k, reach)
    held, _, e = _at_lvpl(P, x, k, reach)
    if held:
        e = 0.0
    Tg = P[k, C.TG]
    dx[RG.Ip, k] = e / Tg
    # S1: Iq lag (gain -1 on Iqcmd), rate limits enabled by the sign of Q0 (`rate_scale`)
    e = Iq_target - x[RG.Iq, k]
    scale = rate_scale(P, k)
    if P[k, C.Q0] < 0.0 and e < P[k, C.IQRMIN] * scale:
        e = P[k, C.IQRMIN] * scale
    if P[k, C.Q0] > 0.0 and e > P[k, C.IQRMAX] * scale:
        e = P[k, C.IQRMAX] * scale
    dx[RG.Iq, k] = e / Tg
    dx[SPARE, k] = 0.0
