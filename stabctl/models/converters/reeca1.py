"""REECA1 and REECB1, the WECC renewable energy electrical controls (REEC_A, REEC_B; ANDES
2.0 ``renewable/reeca1.py``, ``reecb1.py``) of a REGCA1 (ibr_con ``reec`` 1, 2): their DYR
records, named slots, initial services and states, and the control kernel (docs/ibr.md 6).

The control filters the voltage (Trv) and the electrical power (Tp), runs the reactive
power or power-factor reference through the Q and V PIs (PITrackAWFreeze) or the Q lag
(Tiq), adds the reactive current injection Iqinj of a voltage dip, orders the power through
the rate-limited filter Tpfilt and the lag Tpord, and limits both current commands (the
VDL curves, Imax, the priority PQFLAG); while the voltage is outside [Vdip, Vup] it is
frozen.  With ``storage`` 1 (a battery, WECC REEC_C) the active current runs in [-Ipmax,
Ipmax] and its state of charge (slot ``SOC``) bounds it.  Its parameters are ibr_con
columns 54-104 (:mod:`.table`).  REECD1 (WECC REEC_D, :mod:`.reecd1`) runs this control
with its own voltage, current-limit curves, charging range and blocking.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.models.blocks import anti_windup, clip, deadband, lag, pi_track_aw_freeze
from stabctl.models.converters.table import NO_REEC, REECA1, REECB1, REECD1, C
from stabctl.models.declaration import DyrModel, slots

if TYPE_CHECKING:
    from stabctl.models.converters import ConverterParams


#: the ICONs of PSS/E's REECB1 record (REECA1 adds PFLAG before PQFLAG)
_REEC_ICONS = ("IREG", "PFFLAG", "VFLAG", "QFLAG", "PQFLAG")
#: REECB1's CONs in PSS/E order (REECA1 adds Iqfrz, Thld, Thld2 after Vref0, Vref1 after
#: Kvi, and its VDL curves)
_REEC_CONS = (
    *("Vdip", "Vup", "Trv", "dbd1", "dbd2", "Kqv", "Iqh1", "Iql1", "Vref0", "Tp", "QMax"),
    *("QMin", "VMAX", "VMIN", "Kqp", "Kqi", "Kvp", "Kvi", "Tiq", "dPmax", "dPmin", "PMAX"),
    *("PMIN", "Imax", "Tpord"),
)
#: REECA1's ICONs and CONs in PSS/E order
_REECA1_DYR = (
    *_REEC_ICONS[:4],
    *("PFLAG", "PQFLAG"),
    *_REEC_CONS[:9],
    *("Iqfrz", "Thld", "Thld2"),
    *_REEC_CONS[9:18],
    "Vref1",
    *_REEC_CONS[18:],
    *(f"{v}{j}" for pair in (("Vq", "Iq"), ("Vp", "Ip")) for j in range(1, 5) for v in pair),
)


def _reec_copies(fields: tuple[str, ...]) -> dict[str, str]:
    """ibr_con field <- DYR field of a REECA1 or REECB1 record: all but IREG (the
    regulated bus, read by the import), under the same name but PQFLAG (``pqflag``) and
    Tiq (``tiq``)."""
    rename = {"PQFLAG": "pqflag", "Tiq": "tiq"}
    return {rename.get(f, f): f for f in fields if f != "IREG"}


DYR = (
    #: REEC_A: ICONs IREG (0: own bus), PFFLAG, VFLAG, QFLAG, PFLAG, PQFLAG; 45 CONs
    DyrModel(
        "REECA1",
        _REECA1_DYR,
        _reec_copies(_REECA1_DYR),
    ),
    #: REEC_B: ICONs IREG (0: own bus), PFFLAG, VFLAG, QFLAG, PQFLAG; 25 CONs
    DyrModel("REECB1", _REEC_ICONS + _REEC_CONS, _reec_copies(_REEC_ICONS + _REEC_CONS)),
)

#: REECA1's slots (a REGCA1 with ``reec`` 1): its states, then its memory (`MEMORY_SLOTS`)
REECA1_SLOTS = (
    *("Vt_filter", "Pe_filter", "PIQ", "Iq_filter", "Pref_filter", "Pord", "PIV"),
    *("Iqinj_timer", "Ipmax_timer", "Ipmax_held", "PIQ_held", "PIV_held", "Ipcmd_last"),
)
#: the named slots: a battery's state of charge (``storage`` 1, WECC REEC_C; the slot of an
#: ESD1's), then `REECA1_SLOTS`
RE = slots("REECA1Slots", ("SOC", *REECA1_SLOTS), first=4)
#: the slots of REECA1's memory (`MEMORY_SLOTS` of the package): its timers, the held
#: Ipmax and PI outputs, the last Ipcmd
MEMORY = tuple(range(int(RE.Iqinj_timer), int(RE.Ipcmd_last) + 1))


def services(vals: dict, reec, P0, Q0, v0, Ipcmd0, vc0) -> dict[str, np.ndarray]:
    """REECA1's and REECB1's initial services (ANDES reeca1.py, reecb1.py ConstServices;
    `ConverterParams`) from the system-base fields ``vals``, for the rows with an
    electrical control ``reec`` (0 elsewhere); a REECD1's the same but its Q reference
    (Q0, or with QFLAG 1 and VFLAG 0 vc0 - Vbias, vc0 the voltage its voltage control
    compares, `reecd1.initial_voltage`; |V0| of the others; a REECA1's read as PSS/E's,
    ``psse`` 1, the same as a REECD1's) and the point counts nVDL1,
    nVDL2 of its ten-point curves (`_table_points`)."""

    # qref0 (reeca1.py 412): QFLAG (v - Vref1), else Iqcmd0 vp (vp = v above 0.01 pu);
    # REECB1's -Q0 (reecb1.py 304)
    vp0 = np.where(v0 <= 0.01, 0.01, v0)
    qref0 = np.where(vals["QFLAG"] == 1, vc0 - vals["Vref1"], -Q0 / v0 * vp0)
    qref0 = np.where(reec == REECB1, -Q0, qref0)
    # REECD1 (PSS/E's diagram): Q0 the Q PI's reference, or with QFLAG 1, VFLAG 0 the
    # offset Vc0 - Vbias that puts Vsel = Vbias + Qref at its compensated voltage vc0; a
    # REECA1 read as PSS/E's (``psse`` 1) the same (OpenIPSL REECA1.mo: Q0 the Q PI's
    # reference, and Vsel = V0 at the start, its ``Vmod = V0 - PFsel``)
    offset = (vals["QFLAG"] == 1) & (vals["VFLAG"] == 0)
    psse = (reec == REECD1) | ((reec == REECA1) & (vals["psse"] == 1))
    qref0 = np.where(psse, np.where(offset, vals["Vref1"] - vc0, -Q0), qref0)
    with np.errstate(divide="ignore", invalid="ignore"):
        tanpf = np.where(P0 != 0, Q0 / np.where(P0 != 0, P0, 1.0), 0.0)
    on = {
        "Vref0r": np.where(vals["Vref0"] == 0, v0, vals["Vref0"]),
        "Qref": -qref0,
        "tanpf": tanpf,
        "Ipoff": Ipcmd0 - P0 / v0,
        "Imaxr": np.where(vals["Imax"] <= 0, 1e8, vals["Imax"]),
        "zVDL1": has_curve(vals, "Vq", "Iq").astype(float),
        "zVDL2": has_curve(vals, "Vp", "Ip").astype(float),
        "nVDL1": np.where(reec == REECD1, _table_points(vals, "Vq", "Iq"), 0.0),
        "nVDL2": np.where(reec == REECD1, _table_points(vals, "Vp", "Ip"), 0.0),
    }
    return {name: np.where(reec != NO_REEC, value, 0.0) for name, value in on.items()}


def has_curve(vals: dict, v_name: str, i_name: str) -> np.ndarray:
    """Where a REECA1's four-point VDL curve (voltages ``v_name``1..4, currents
    ``i_name``1..4 of ``vals``, scalars or per-device arrays) has a point not 0: all 0 is
    no curve, Imax alone (as a REECD1's table of no points); its voltages rise
    (`stabctl.models.converters.rules`), its currents may fall, as PSS/E's.

    Parameters
    ----------
    vals : dict
        Field name -> value or array of values.
    v_name, i_name : str
        The curve's voltage and current field stems ("Vq", "Iq" of VDL1).

    Returns
    -------
    numpy.ndarray
        bool, one per device (0-d for scalars).
    """
    pts = np.array([vals[f"{c}{j}"] for c in (v_name, i_name) for j in (1, 2, 3, 4)])
    return np.any(pts != 0, axis=0)


def _table_points(vals: dict, v_name: str, i_name: str) -> np.ndarray:
    """The points a REECD1's ten-point VDL curve uses (PSS/E's and InterPSS's
    ``tablePointCount``): 0 if all its voltages and currents are 0 (no curve), else the
    first point and each next one while its voltage is not 0 and above the one before."""
    v = np.array([vals[f"{v_name}{j}"] for j in range(1, 11)])
    i = np.array([vals[f"{i_name}{j}"] for j in range(1, 11)])
    rising = (v[1:] != 0) & (v[1:] > v[:-1])
    n = 1 + np.cumprod(rising, axis=0).sum(axis=0)
    return np.where(np.any((v != 0) | (i != 0), axis=0), n, 0).astype(float)


def initial(cp: ConverterParams, x: np.ndarray, v: np.ndarray) -> None:
    """REECA1's initial states in x (N_STATES, n_ibr), in place, at the voltage
    magnitudes v (ANDES reeca1.py v_str): the filters at |V0|, P0, P0, P0; the Q filter
    at PFsel/vp (Qref, or Q0 with PFFLAG); the V PI's integrator at QFLAG Q0/|V0| (its
    x0 -QFLAG Iqcmd0), the Q PI's at 0 (ANDES's; PSS/E's reading, ``psse`` 1, with VFLAG
    and QFLAG 1: at |V0|, its output the V PI's voltage reference, OpenIPSL REECB1.mo,
    REECA1.mo ``y_start=V0``); the last Ipcmd the REGCA1's Ipcmd0."""
    ree = cp.reec != NO_REEC
    vp = np.where(v <= 0.01, 0.01, v)
    pfsel = np.where(cp.PFFLAG == 1, cp.Q0, cp.Qref)
    init = {
        RE.Vt_filter: v,
        RE.Pe_filter: cp.P0,
        RE.Iq_filter: pfsel / vp,
        RE.Pref_filter: cp.P0,
        RE.Pord: cp.P0,
        RE.PIV: cp.QFLAG * cp.Q0 / v,
        RE.Ipcmd_last: cp.Ipcmd0,
    }
    for slot, value in init.items():
        x[slot] = np.where(ree, value, 0.0)
    psse_q = ree & (cp.psse == 1) & (cp.VFLAG == 1) & (cp.QFLAG == 1)
    x[RE.PIQ] = np.where(psse_q, v, x[RE.PIQ])


@kernel
def extended_event(x, dx, slot, k, on, t_ext):
    """An event flag extended by t_ext s after its input ``on`` falls (ANDES
    ExtendedEvent, andes/core/service.py): while on, the timer slot is set to t_ext in
    place; after, it runs down at 1/s to 0.  Returns 1.0 while the timer runs (the
    extension, on or after the event), else 0.0."""
    dx[slot, k] = 0.0
    if on:
        x[slot, k] = t_ext
    elif x[slot, k] > 0.0:
        dx[slot, k] = -1.0
    else:
        x[slot, k] = 0.0
    return 1.0 if x[slot, k] > 0.0 else 0.0


@kernel
def _vdl(P, k, c, u):
    """REECA1's voltage-dependent current limit (ANDES Piecewise VDL1/VDL2) of device k at
    filtered voltage u: the four voltages in columns c..c+3, the currents c+4..c+7."""
    if u <= P[k, c]:
        return P[k, c + 4]
    for j in range(1, 4):
        if u <= P[k, c + j]:
            v0, v1, i0, i1 = P[k, c + j - 1], P[k, c + j], P[k, c + j + 3], P[k, c + j + 4]
            return (u - v0) * ((i1 - i0) / (v1 - v0)) + i0
    return P[k, c + 7]


#: REECA1's VDL curves as (flag column, first point column; a REECD1's point count column,
#: its points 5-10's first voltage and current columns), numpy scalars
_VDL1 = tuple(np.int64(c) for c in (C.ZVDL1, C.VQ1, C.NVDL1, C.VQ5, C.IQ5))
_VDL2 = tuple(np.int64(c) for c in (C.ZVDL2, C.VP1, C.NVDL2, C.VP5, C.IP5))


@kernel
def _table_point(P, k, curve, j):
    """(voltage, current) of point j (from 0) of device k's VDL curve (`_VDL1`, `_VDL2`):
    points 0-3 REECA1's columns, 4-9 a REECD1's."""
    _, c, _, v5, i5 = curve
    if j < 4:
        return P[k, c + j], P[k, c + 4 + j]
    return P[k, v5 + j - 4], P[k, i5 + j - 4]


@kernel
def _vdl_table(P, k, curve, u):
    """A REECD1's VDL curve of device k at filtered voltage u: linear between its points
    (the count in the curve's column), its first current below them, its last above."""
    v0 = i0 = 0.0
    for j in range(int(P[k, curve[2]])):
        v1, i1 = _table_point(P, k, curve, j)
        if u <= v1:
            return i1 if j == 0 else (u - v0) * ((i1 - i0) / (v1 - v0)) + i0
        v0, i0 = v1, i1
    return i0


@kernel
def _vdl_limit(P, k, curve, u):
    """REECA1's VDL limit of device k at filtered voltage u: min(VDL(u), Imaxr) (`_vdl`,
    columns c) if it has a curve (flag column z: not all its points 0), else Imaxr (no
    curve, as a REECD1's table of no points); curve `_VDL1` or `_VDL2`.  A REECB1 has no
    curves: Imaxr (ANDES reecb1.py Ipmax, Iqmax).  A REECD1: min(its ten-point curve,
    Imaxr) (`_vdl_table`; Imaxr without a curve, InterPSS's ``currentLimits``)."""
    z, c = curve[0], curve[1]
    if P[k, C.REEC] == REECB1:
        return P[k, C.IMAXR]
    if P[k, C.REEC] == REECD1:
        if P[k, curve[2]] == 0.0:
            return P[k, C.IMAXR]
        return min(_vdl_table(P, k, curve, u), P[k, C.IMAXR])
    if P[k, z] == 0.0:
        return P[k, C.IMAXR]
    return min(_vdl(P, k, c, u), P[k, C.IMAXR])


@kernel
def _room(P, k, other):
    """The current room sqrt(max(Imax^2 - other^2, 0)) the other command leaves (a
    REECB1's and a REECD1's Imaxr: ANDES reecb1.py Ipmax2sq, Iqmax2sq)."""
    limited = P[k, C.REEC] == REECB1 or P[k, C.REEC] == REECD1
    Imax = P[k, C.IMAXR] if limited else P[k, C.IMAX]
    return np.sqrt(max(Imax**2 - other**2, 0.0))


@kernel
def _iq_command(P, x, k, u, s4, Iqinj, Iqmax, frz, dx):
    """REECA1's reactive current command IqHL of device k: the V PI (ANDES PITrackAWFreeze,
    `blocks.pi_track_aw_freeze`: input u, limits +-Iqmax, its output held in slot PIV_held)
    with QFLAG, else the filtered Q command s4, plus Iqinj, limited to +-Iqmax."""
    piv, dx[RE.PIV, k] = pi_track_aw_freeze(
        u,
        x[RE.PIV, k],
        x[RE.PIV_held, k],
        P[k, C.KVP],
        P[k, C.KVI],
        -Iqmax,
        Iqmax,
        P[k, C.KVS],
        frz,
    )
    x[RE.PIV_held, k] = piv
    Qsel = piv if P[k, C.QFLAG] == 1.0 else s4
    return clip(Qsel + Iqinj, -Iqmax, Iqmax)


@kernel
def _ip_command(P, x, k, Ip_order, Ipmax, hold):
    """REECA1's active current command IpHL = clip(Ip_order, 0, Ipmax) of device k (a
    battery, ``storage`` 1: clip(Ip_order, -Ipmax, Ipmax), WECC REEC_C, whose state of
    charge, with a finite En, stops discharging at SOCmin and charging at SOCmax; a
    REECD1: clip(Ip_order, -Ke Ipmax, Ipmax), its state of charge as a battery's), Ipmax
    held at its value before ``hold`` (1.0 for Thld2 s after a dip; ANDES VarHold
    Ipmaxh), tracked in place otherwise."""
    if hold:
        Ipmax = x[RE.Ipmax_held, k]
    else:
        x[RE.Ipmax_held, k] = Ipmax
    share = P[k, C.RD_KE] if P[k, C.REEC] == REECD1 else P[k, C.STORAGE]
    lo, hi = -share * Ipmax, Ipmax
    if P[k, C.KSOC] > 0.0:
        if x[RE.SOC, k] <= P[k, C.SOCMIN]:
            hi = 0.0
        if x[RE.SOC, k] >= P[k, C.SOCMAX]:
            lo = 0.0
    return clip(Ip_order, lo, hi)


@kernel
def _p_order(P, x, k, Pref, wg, frz, dx):
    """REECA1's power order Pord of device k: the reference Pref through the rate-limited
    filter Tpfilt, times the speed wg with PFLAG (Psel), then the lag Tpord frozen in a dip
    with the anti-windup limits [PMIN, PMAX] (LagAWFreeze; `blocks.anti_windup`, the state
    reset to a limit in place).  The rate limits dPmin, dPmax: read as PSS/E's (ibr_con
    ``psse``), the filter's rate in pu/s (PSS/E REEC_A/B/D: Pref's slew rate, Dynawo's
    ``BaseREEC`` SlewRateLimiter; the filter, Tpfilt 0.02 s, stands for the limiter's
    tracking); read as ANDES's, on its right-hand side Pref - state (ANDES LagRate: the rate
    dPmax/Tpfilt)."""
    d = Pref - x[RE.Pref_filter, k]
    if P[k, C.PSSE] == 1.0:
        dx[RE.Pref_filter, k] = clip(d / P[k, C.TPFILT], P[k, C.DPMIN], P[k, C.DPMAX])
    else:
        dx[RE.Pref_filter, k] = clip(d, P[k, C.DPMIN], P[k, C.DPMAX]) / P[k, C.TPFILT]
    Psel = wg * x[RE.Pref_filter, k] if P[k, C.PFLAG] == 1.0 else x[RE.Pref_filter, k]
    e = 0.0 if frz else Psel - x[RE.Pord, k]
    x[RE.Pord, k], e = anti_windup(x[RE.Pord, k], e, P[k, C.PMIN], P[k, C.PMAX])
    dx[RE.Pord, k] = e / P[k, C.TPORD]
    return x[RE.Pord, k]


@kernel
def _iq_injection(P, k, vt, frz, extended):
    """REECA1's Iqinj of device k at filtered voltage vt: Kqv times the deadbanded error
    Vref0r - vt (DeadBand1, strict) in a dip; for |Thld| s after it (``extended``) the
    same (Thld < 0) or Iqfrz (Thld > 0); limited to [Iql1, Iqh1] (ANDES leaves the limits
    out).  A REECB1's at all times (its GainLimiter, no hold)."""
    Iqv = deadband(P[k, C.VREF0R] - vt, P[k, C.DBD1], P[k, C.DBD2]) * P[k, C.KQV]
    Iqinj = 0.0
    if frz or (extended and P[k, C.THLD] < 0.0) or P[k, C.REEC] == REECB1:
        Iqinj = Iqv
    elif extended and P[k, C.THLD] > 0.0:
        Iqinj = P[k, C.IQFRZ]
    return clip(Iqinj, P[k, C.IQL1], P[k, C.IQH1])


@kernel
def control(P, x, k, v, S, ref, wg, vc, dx):
    """REECA1 (ANDES 2.0 reeca1.py; docs/ibr.md 6) driving REGCA1 k at voltage magnitude v
    with its injected power S = Pe + j Qe, its references ref = Pref + j Qext (Pref: P0,
    or its wind turbine's, plus its plant control's Pext; Qext the plant control's Q
    increment, 0 without one), its speed wg (1 without a wind turbine) and the voltage
    vc its voltage control compares (its filtered voltage, the slot Vt_filter; a
    REECD1's compensated voltage, `reecd1.control`): the derivatives of its slots
    written, its memory (`MEMORY_SLOTS`) updated in place; returns the commands (IpHL,
    IqHL), pu.  Frozen (Volt_dip) while v < Vdip or v > Vup
    (strict).  A REECB1 (ANDES reecb1.py) the same but: the V PI's input the selected
    Vsel (the Q PI's output with VFLAG, else 0), no VDL curves, Iqinj at all times, no
    holds (its Thld, Thld2 0) and no PFLAG (0).

    PSS/E's reading (``psse`` 1, import-psse's default; PSS/E Model Library REECB1,
    REECA1, as OpenIPSL's PSS/E-verified ``REECB1.mo``, ``REECA1.mo``): with QFLAG 1 the V
    PI's input is clip(VFLAG ? the Q PI's output : Vref0r (REECB1; REECA1 Vref1 + PFsel),
    VMIN, VMAX) - vc, the Q PI started at |V0| (`initial`), where ANDES 2.0's REECB1 feeds
    clip(VFLAG Q PI, VMIN, VMAX) with no reference and no voltage (and its REECA1 no
    voltage with VFLAG 1)."""
    ext = ref - P[k, C.P0]
    frz = v < P[k, C.VDIP] or v > P[k, C.VUP]
    extended = extended_event(x, dx, RE.Iqinj_timer, k, frz, abs(P[k, C.THLD]))
    hold = extended_event(x, dx, RE.Ipmax_timer, k, frz, P[k, C.THLD2])
    if frz:  # the Ipmax hold runs after the dip only (ExtendedEvent extend_only)
        hold = 0.0
    vt, dx[RE.Vt_filter, k] = lag(v, x[RE.Vt_filter, k], P[k, C.TRV])
    pe, dx[RE.Pe_filter, k] = lag(
        S.real, x[RE.Pe_filter, k], P[k, C.TP]
    )  # Tp < LBND: no filter (PSS/E 0)
    psse = P[k, C.PSSE] == 1.0
    # PSS/E divides Pord and Qext by the Trv-filtered voltage (GridPACK reeca1.cpp
    # Vt_filter_lowcap_out, Dynawo UFilteredPu, OpenIPSL REECA1.mo); ANDES by |V|
    vp = max(vt if psse else v, 0.01)
    # reactive power reference: Q, or the power factor of the filtered Pe (Q0 at P0 = 0)
    PFsel = P[k, C.QREF] + ext.imag
    if P[k, C.PFFLAG] == 1.0:
        PFsel = pe * P[k, C.TANPF] if P[k, C.P0] != 0.0 else P[k, C.Q0]
    Qerr = clip(PFsel, P[k, C.QMIN], P[k, C.QMAX]) - S.imag
    vflag = P[k, C.VFLAG]
    lo, hi = P[k, C.VMIN], P[k, C.VMAX]
    piq = 0.0  # the Q PI drives Iq with VFLAG and QFLAG 1 only (ANDES's drifts unread)
    dx[RE.PIQ, k] = 0.0
    if vflag == 1.0 and P[k, C.QFLAG] == 1.0:
        piq, dx[RE.PIQ, k] = pi_track_aw_freeze(
            Qerr,
            x[RE.PIQ, k],
            x[RE.PIQ_held, k],
            P[k, C.KQP],
            P[k, C.KQI],
            lo,
            hi,
            P[k, C.KQS],
            frz,
        )
        x[RE.PIQ_held, k] = piq
    if P[k, C.REEC] == REECB1 and psse:  # PSS/E: the V PI regulates Vt_filter
        u = P[k, C.QFLAG] * (clip(P[k, C.VREF0R] if vflag == 0.0 else piq, lo, hi) - vc)
    elif P[k, C.REEC] == REECB1:  # ANDES 2.0's reecb1.py: no reference, no voltage
        u = P[k, C.QFLAG] * clip(vflag * piq, lo, hi)
    else:
        Vsel = clip(P[k, C.VREF1] + PFsel if vflag == 0.0 else piq, lo, hi)
        # ANDES's REECA1 compares no voltage with VFLAG 1; PSS/E's always does
        seen = 1.0 if P[k, C.REEC] == REECD1 or psse else 1.0 - vflag
        u = P[k, C.QFLAG] * (Vsel - vc * seen)
    s4 = x[RE.Iq_filter, k]
    dx[RE.Iq_filter, k] = 0.0 if frz else (PFsel / vp - s4) / P[k, C.TIQ]
    Iqinj = _iq_injection(P, k, vt, frz, extended)
    Ip_order = _p_order(P, x, k, ref.real, wg, frz, dx) / vp
    # PSS/E caps the lower-priority current by its own VDL curve too (GridPACK's
    # CurrentLimitLogic, Dynawo's CurrentLimitsCalculationA, OpenIPSL's
    # CurrentLimitLogicREECA: min(VDL, the room left)); ANDES by the room alone
    if P[k, C.PQFLAG] == 0.0:  # Q priority
        Iqmax = _vdl_limit(P, k, _VDL1, vt)
        IqHL = _iq_command(P, x, k, u, s4, Iqinj, Iqmax, frz, dx)
        Ipmax = _room(P, k, IqHL)
        if psse:
            Ipmax = min(Ipmax, _vdl_limit(P, k, _VDL2, vt))
        IpHL = _ip_command(P, x, k, Ip_order, Ipmax, hold)
    else:
        IpHL = _ip_command(P, x, k, Ip_order, _vdl_limit(P, k, _VDL2, vt), hold)
        Iqmax = _room(P, k, IpHL)
        if psse:
            Iqmax = min(Iqmax, _vdl_limit(P, k, _VDL1, vt))
        IqHL = _iq_command(P, x, k, u, s4, Iqinj, Iqmax, frz, dx)
    return IpHL, IqHL
