"""PVD1 and ESD1, ANDES 2.0's distributed models (ibr_con types 1, 2): PVD1 (WECC
distributed PV) and ESD1 (PVD1 with a state of charge), with the ANDES bus-frequency
measurement (BusFreq) each reads: their named slots and kernels.  Their parameters are
ibr_con columns 1-38 (:mod:`.table`); their DG protection is :mod:`.relays`.

Sources: ANDES 2.0 ``andes/models/distributed/pvd1.py`` (PVD1Model, lines 235-517),
``esd1.py`` (ESD1Model, lines 54-87), ``andes/models/measurement/busfreq.py`` (lines
48-84), blocks ``andes/core/block.py`` (Lag, Washout, GainLimiter, DeadBand1, Integrator)
and flags ``andes/core/discrete.py`` (Limiter: ``zu = u >= upper``, ``zl = u <= lower``;
DeadBand and LessThan strict).  Equations, parameters and the ANDES agreement in
docs/ibr.md.

Per device (system base; the table's device-base values converted by `converter_params`):

* frequency: L = (a - a0) through 1/(1 + s Tfm), washout y = (L - x_w)/(2 pi fn Twm),
  f = 1 + y (pu), fHz = fn f; the angle a continuous (unwrapped), as ANDES's;
* power order: Psum = pref0 + ddn dbd(fn - fHz) (droop only beyond fdbd, over-frequency),
  limited to [pmn, pmx] (plim), Ipul = Psum/vp (vp = max(|V|, 0.01); below pmn: 0);
* reactive order: Qsum = qref0 + Qdrp(Vcomp), Vcomp = |V + j xc (Ip + j Iq)|, Iqul =
  Qsum/vp;
* current limits: P priority (pqflag 1) Ipmax = ialim, Iqmax = sqrt(ialim^2 - Ipcmd^2);
  Q priority (0) Iqmax = ialim, Ipmax = sqrt(ialim^2 - Iqcmd^2); ESD1 Ipmax 0 at SOCmin,
  Ipmin = -ialim-type bound, 0 at SOCmax; commands R clip(., lower, upper) with R the
  product of the voltage and frequency trip curves (recflag);
* output lags Ip, Iq (tip, tiq): the current injected at the bus is (Ip - j Iq) V/|V|,
  so P = Ip |V|, Q = Iq |V|;
* ESD1: dSOC/dt = Sb/(3600 En Tf) (-EtaC P if P < 0 else -P/EtaD).

States per device (`PV`): Ip, Iq, the measurement lag and washout, the SOC
(ESD1; 0 for PVD1).
"""

from __future__ import annotations

import numpy as np

from stabctl._jit.decorators import kernel, njit
from stabctl.models.blocks import GAIN_BEFORE, LBND, clip, lag, washout
from stabctl.models.converters.table import ESD1, C
from stabctl.models.declaration import slots

#: the named slots of a PVD1 or ESD1: its current lags, the frequency measurement's lag and
#: washout, the state of charge (ESD1)
PV = slots("PVD1Slots", ("Ip", "Iq", "f_lag", "f_washout", "SOC"))


@kernel
def bus_frequency(P, x, k, V, sl, sw):
    """ANDES's bus frequency measurement (BusFreq, andes/models/measurement/busfreq.py) of
    device k at bus voltage V, its states in slots sl (lag Tfm of a - a0) and sw
    (washout Twm, gain 1/(2 pi fn)): returns (f pu, d lag/dt, d washout/dt).  The angle
    is ANDES's continuous one: a - a0 taken within pi of the filter's state (the lag's,
    else the washout's, which follow it within T x its rate), not wrapped to (-pi, pi]."""
    ref = x[sl, k] if P[k, C.TFM] >= LBND else x[sw, k]
    a0 = np.arctan2(P[k, C.SIN_A0], P[k, C.COS_A0]) + ref
    a = ref + np.angle(V * np.exp(-1j * a0))
    L, dL = lag(a, x[sl, k], P[k, C.TFM])
    w, dW = washout(L, x[sw, k], P[k, C.TWM], 1.0 / (2.0 * np.pi * P[k, C.FN]), GAIN_BEFORE)
    return 1.0 + w, dL, dW


@kernel
def _band(u, lower, upper):
    """ANDES Limiter flags (equal=True): (zl, zi, zu) as floats, zl = u <= lower,
    zu = u >= upper."""
    zu = 1.0 if u >= upper else 0.0
    zl = 1.0 if u <= lower else 0.0
    zi = 1.0 - max(zu, zl)
    return zl, zi, zu


@kernel
def algebraic(P, x, k, V):
    """ANDES's algebraic chain of device k at bus voltage V with the states x: the current
    commands (Ipcmd, Iqcmd) and the SOC derivative's input, and the frequency block's
    derivatives (dL, dW)."""
    v = abs(V)
    f, dL, dW = bus_frequency(P, x, k, V, PV.f_lag, PV.f_washout)
    fn = P[k, C.FN]
    fHz = fn * f
    # trip curves (ANDES Limiter flags), R the product of the four
    zl, zi, zu = _band(fHz, P[k, C.FT0], P[k, C.FT1])
    Ffl = zi * (1.0 / (P[k, C.FT1] - P[k, C.FT0])) * (fHz - P[k, C.FT0]) + zu
    zl, zi, zu = _band(fHz, P[k, C.FT2], P[k, C.FT3])
    Ffh = zl + zi * (1.0 + (1.0 / (P[k, C.FT3] - P[k, C.FT2])) * (P[k, C.FT2] - fHz))
    zl, zi, zu = _band(v, P[k, C.VT0], P[k, C.VT1])
    Fvl = zi * (1.0 / (P[k, C.VT1] - P[k, C.VT0])) * (v - P[k, C.VT0]) + zu
    zl, zi, zu = _band(v, P[k, C.VT2], P[k, C.VT3])
    Fvh = zl + zi * (1.0 + (1.0 / (P[k, C.VT3] - P[k, C.VT2])) * (P[k, C.VT2] - v))
    rec = P[k, C.RECFLAG]
    R = Fvl * Fvh * Ffl * Ffh * rec + (1.0 - rec)
    vp = 0.01 if v <= 0.01 else v
    # active power order: deadband droop (DeadBand1, strict flags), limiter PHL
    Fdev = fn - fHz
    db = 0.0
    if Fdev > 999.0:
        db = Fdev - 999.0
    elif Fdev < P[k, C.FDBD]:
        db = Fdev - P[k, C.FDBD]
    Psum = P[k, C.P0] + P[k, C.DDN] * db
    if P[k, C.PLIM] != 0.0:
        zl, zi, zu = _band(Psum, P[k, C.PMN], P[k, C.PMX])
        Ipul = (Psum * zi + P[k, C.PMX] * zu) / vp
    else:
        Ipul = Psum / vp
    # reactive power order: Q-V droop on the compensated voltage
    Vcomp = abs(V + 1j * P[k, C.XC] * (x[PV.Ip, k] + 1j * x[PV.Iq, k]))
    qmx, qmn, dqdv = P[k, C.QMX], P[k, C.QMN], P[k, C.DQDV]
    l1, i1, _u1 = _band(Vcomp, P[k, C.VQL], P[k, C.V0])
    _l2, i2, u2 = _band(Vcomp, P[k, C.V1], P[k, C.VQU])
    Qdrp = (
        l1 * qmx
        + u2 * qmn
        + i1 * (qmx + dqdv * (P[k, C.VQU] - Vcomp))
        + i2 * (dqdv * (P[k, C.V1] - Vcomp))
    )
    Iqul = (P[k, C.Q0] + Qdrp) / vp
    # current limits (priority pqflag), ESD1's state-of-charge bounds
    ialim = P[k, C.IALIM]
    esd = P[k, C.TYPE] == ESD1
    up_ok, lo_ok = 1.0, 1.0
    if esd:
        up_ok = 0.0 if x[PV.SOC, k] <= P[k, C.SOCMIN] else 1.0
        lo_ok = 0.0 if x[PV.SOC, k] >= P[k, C.SOCMAX] else 1.0
    if P[k, C.PQFLAG] == 1.0:
        Ipmax = up_ok * ialim
        Ipmin = -lo_ok * ialim if esd else 0.0
        Ipcmd = R * clip(Ipul, Ipmin, Ipmax)
        Iqmax = np.sqrt(max(ialim**2 - Ipcmd**2, 0.0))
        Iqcmd = R * clip(Iqul, -Iqmax, Iqmax)
    else:
        Iqcmd = R * clip(Iqul, -ialim, ialim)
        room = np.sqrt(max(ialim**2 - Iqcmd**2, 0.0))
        Ipmin = -lo_ok * room if esd else 0.0
        Ipcmd = R * clip(Ipul, Ipmin, up_ok * room)
    return Ipcmd, Iqcmd, dL, dW, fHz


@kernel
def soc_rate(P, k, pe):
    """dSOC/dt of device k injecting pe (pu, system base): Ksoc (-EtaC pe) charging, Ksoc
    (-pe/EtaD) discharging (ANDES 2.0 esd1.py; WECC REEC_C's SOC integrator with its
    efficiencies); 0 without a state of charge (Ksoc 0)."""
    if P[k, C.KSOC] == 0.0:
        return 0.0
    return P[k, C.KSOC] * (-pe * P[k, C.ETAC] if pe < 0.0 else -pe / P[k, C.ETAD])


@njit(cache=True)
def commands(P, x, V):
    """The current commands (Ipcmd, Iqcmd) of every device, each (n_ibr,), at bus
    voltages V (n_ibr,) complex with the states x (N_STATES, n_ibr); P the packed
    parameters (the initialisation check of `initialise`)."""
    n = V.size
    Ip, Iq = np.empty(n), np.empty(n)
    for k in range(n):
        Ip[k], Iq[k], _, _, _ = algebraic(P, x, k, V[k])
    return Ip, Iq
