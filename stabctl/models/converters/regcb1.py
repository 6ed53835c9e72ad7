"""REGCB1, the WECC second-generation generator/converter interface REGC_B (PSS/E Model
Library REGCB1; a type-3 device with ibr_con ``regc`` 1): its DYR record, its named
states, its output currents and its derivatives (docs/ibr.md 14).

The converter lags its current commands (Ipcmd, Iqcmd: constant, or its electrical
control's, :mod:`.reeca1`) through Tg, the active one with the rate limit Rrpwr on the
current (RateFlag 0) or on the power Ipcmd Vf (RateFlag 1, Vf the voltage filtered
through Tfltr, at least 0.01 pu), the reactive one with the rate limits Iqrmax (Q0 > 0)
or Iqrmin (Q0 < 0).  The lagged currents Ip - j Iq (in the frame of the bus voltage V,
Iq positive injecting Q) set the target v + Z (Ip - j Iq) of an internal voltage E = Ed
+ j Eq behind the source impedance Z = Rsource + j Xsource (the RAW generator's ZSORCE),
lagged through Te; the output current is (E - v)/Z, limited to Imax with the priority
PQFlag.  At rest E sits on its target and the output current is the lagged one; a step of
v moves the output current by -dv/Z at once, which E's lag takes back within Te (a
voltage source for a few Te).  Te below 1e-3 s: no internal voltage, the output current
the lagged one (a current source).

Sources, where they differ: the block diagram and parameter order are the PSS/E Model
Library's REGCB1 (ICONs RateFlag, PQFlag; CONs Tg, Tfltr, Iqrmax, Iqrmin, Rrpwr, Te,
Imax), as InterPSS's ``Regcb1Data`` and GridPACK's ``regcb1.cpp`` read it; the rate limits
bound dy/dt (GridPACK's ``setdxlimits``, InterPSS's ``directionalActiveRate``), Rrpwr
the rise of |Ip| (|P|) by the sign of the command (GridPACK); Imax limits the output
current (InterPSS ``physicalCurrent``; GridPACK reads Imax and does not apply it); the
internal voltage lag and its target are both tools' (``Ed_blk``, ``Eq_blk``).  Its
parameters are ibr_con columns 228-237 (``regc``, ``gb_``; Tg and Tfltr are the
REGCA1's columns 39 and 49, :mod:`.table`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.models.blocks import LBND, clip, lag, magnitude_rate
from stabctl.models.converters.pll import PL
from stabctl.models.converters.regca1 import RG
from stabctl.models.converters.table import REGC_B, C
from stabctl.models.declaration import DyrModel, slots

if TYPE_CHECKING:
    from stabctl.models.converters import ConverterParams

DYR = (
    #: REGC_B (PSS/E Model Library "REGCB1"): ICONs RateFlag, PQFlag; 7 CONs
    DyrModel(
        "REGCB1",
        ("RateFlag", "PQFlag", "Tg", "Tfltr", "Iqrmax", "Iqrmin", "Rrpwr", "Te", "Imax"),
        {"Tg": "Tg", "Tfltr": "Tfltr"}
        | {f"gb_{n}": n for n in ("RateFlag", "PQFlag", "Iqrmax", "Iqrmin", "Rrpwr", "Te")}
        | {"gb_Imax": "Imax"},
    ),
)

#: REGCB1's internal voltage (pu, in the frame of its bus voltage), after the PLL's slots;
#: its current lags and voltage filter are the REGCA1's slots `regca1.RG` (Ip holds the
#: active power with RateFlag 1)
GB = slots("REGCB1Slots", ("Ed", "Eq"), first=int(PL[-1]) + 1)
#: the smallest filtered voltage REGCB1 divides by (pu; GridPACK's Vt_filter floor)
V_FLOOR = 0.01


@kernel
def _lagged_current(P, x, k):
    """REGCB1 k's lagged active current: the Ip state, or with RateFlag 1 the lagged power
    over the filtered voltage (at least `V_FLOOR`)."""
    if P[k, C.GB_RATEFLAG] == 1.0:
        return x[RG.Ip, k] / max(x[RG.V_filter, k], V_FLOOR)
    return x[RG.Ip, k]


@kernel
def _source_impedance(P, k):
    """REGCB1 k's source impedance Rsource + j Xsource (pu, system base)."""
    return P[k, C.GB_RSOURCE] + 1j * P[k, C.GB_XSOURCE]


@kernel
def currents(P, x, k, v):
    """REGCB1's output currents (Ipout, Iqout) of device k at voltage magnitude v, in the
    frame of its bus voltage (Iqout positive injecting Q): (E - v)/Z = Ipout - j Iqout
    with Te, the lagged currents without; then limited to Imax, the priority current
    (PQFlag 1 active, 0 reactive) to +-Imax, the other to the room sqrt(Imax^2 - Ipri^2)."""
    Ip, Iq = _lagged_current(P, x, k), x[RG.Iq, k]
    if P[k, C.GB_TE] >= LBND:
        out = (x[GB.Ed, k] + 1j * x[GB.Eq, k] - v) / _source_impedance(P, k)
        Ip, Iq = out.real, -out.imag
    Imax = P[k, C.GB_IMAX]
    if P[k, C.GB_PQFLAG] == 1.0:
        Ip = clip(Ip, -Imax, Imax)
        room = np.sqrt(max(Imax**2 - Ip**2, 0.0))
        return Ip, clip(Iq, -room, room)
    Iq = clip(Iq, -Imax, Imax)
    room = np.sqrt(max(Imax**2 - Iq**2, 0.0))
    return clip(Ip, -room, room), Iq


@kernel
def derivatives(P, x, k, v, Ipcmd, Iq_target, dx):
    """REGCB1's state derivatives of device k at voltage magnitude v toward its commands
    Ipcmd and Iq_target = -Iqcmd, its slots `RG` and `GB` of column k of dx: the voltage
    filter; the Ip lag Tg of Ipcmd (RateFlag 1: of Ipcmd times the filtered voltage) with
    dIp/dt at most Rrpwr for a command >= 0, at least -Rrpwr for one < 0; the Iq lag Tg
    with dIq/dt at most Iqrmax (Q0 > 0) or at least Iqrmin (Q0 < 0); the internal voltage
    (Te, without: derivatives 0) toward v + Z (Ip - j Iq)."""
    vf, dx[RG.V_filter, k] = lag(v, x[RG.V_filter, k], P[k, C.TFLTR])
    Tg = P[k, C.TG]
    u = Ipcmd * max(vf, V_FLOOR) if P[k, C.GB_RATEFLAG] == 1.0 else Ipcmd
    dx[RG.Ip, k] = magnitude_rate((u - x[RG.Ip, k]) / Tg, u, P[k, C.GB_RRPWR])
    d = (Iq_target - x[RG.Iq, k]) / Tg
    if P[k, C.Q0] > 0.0:
        d = min(d, P[k, C.GB_IQRMAX])
    elif P[k, C.Q0] < 0.0:
        d = max(d, P[k, C.GB_IQRMIN])
    dx[RG.Iq, k] = d
    dx[GB.Ed, k] = dx[GB.Eq, k] = 0.0
    Te = P[k, C.GB_TE]
    if Te >= LBND:
        E = v + _source_impedance(P, k) * (_lagged_current(P, x, k) - 1j * x[RG.Iq, k])
        dx[GB.Ed, k] = (E.real - x[GB.Ed, k]) / Te
        dx[GB.Eq, k] = (E.imag - x[GB.Eq, k]) / Te


def initial(cp: ConverterParams, x: np.ndarray, v: np.ndarray) -> None:
    """REGCB1's initial states in x (N_STATES, n_ibr), in place, at the voltage magnitudes
    v (the current lags, Ip = Ipcmd0 and Iq = Q0/|V|, and the voltage filter |V| already
    there, as a REGCA1's): Ip the power Ipcmd0 |V| with RateFlag 1; with Te the internal
    voltage at its target |V| + Z (Ipcmd0 - j Q0/|V|)."""
    gb = cp.regc == REGC_B
    x[RG.Ip] = np.where(gb & (cp.gb_RateFlag == 1), cp.Ipcmd0 * v, x[RG.Ip])
    E = v + (cp.gb_Rsource + 1j * cp.gb_Xsource) * (cp.Ipcmd0 - 1j * cp.Q0 / v)
    on = gb & (cp.gb_Te >= LBND)
    x[GB.Ed] = np.where(on, E.real, 0.0)
    x[GB.Eq] = np.where(on, E.imag, 0.0)
