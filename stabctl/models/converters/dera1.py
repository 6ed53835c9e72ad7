"""DERA1, PSS/E's WECC aggregated distributed energy resources model (DER_A): its DYR
record, its named states, its initial point and its derivatives (docs/ibr.md section 13).

A current source at its bus, in the bus voltage's frame (as a PVD1, `PV`): the active
current Ip and reactive current Iq lag their commands through Tg; the commands are the
power order and reactive reference over the measured voltage, within the current limits,
times the trip multiplier.  Its parameters are ibr_con columns 214-227 and 271-302
(:mod:`.table`) and the table's ``pqflag``.

Modelled: every flag: PfFlag, PQFlag, GenFlag 0 and 1 and FreqFlag 0 as
PowerSimulationsDynamics.jl's ``AggregateDistributedGenerationA`` (src/models/device.jl,
``_mdl_ode_...`` with ``Val{0}``; src/models/saturation_models.jl
``current_limit_logic``; initialisation src/initialization/init_device.jl); FreqFlag 1,
VtripFlag 1 and FtripFlag 1 after the WECC DER_A specification (PSS/E Model Library
DERA1), read against PSID's ``Val{1}`` and Dynawo's ``der_a`` (readings below).  Per
device (system base; the table's device-base powers and currents converted by
`converter_params`), with Vm = max(Vmeas, 0.01):

* Vmeas = |V| through 1/(1 + s Trv);
* Q_V = Qref/Vm (PfFlag 0) or tan(pfaref) Pmeas/Vm (PfFlag 1) through 1/(1 + s Tiq);
* Iqv = Kqv dbd(Vref - Vmeas) within [Iql1, Iqh1] (deadband [dbd1, dbd2]);
* current limits on the current states: PQFlag 1 (P priority) Ipmax = Imax, Iqmax =
  sqrt(Imax^2 - Ip^2); PQFlag 0 (Q priority) Iqmax = Imax, Ipmax = sqrt(Imax^2 - Iq^2);
  Iqmin = -Iqmax, Ipmin = 0 (GenFlag 1) or -Ipmax (GenFlag 0);
* dIq/dt = (Mult clip(Iqv + Q_V, Iqmin, Iqmax) - Iq)/Tg; dIp/dt = (Mult clip(Pord/Vm,
  Ipmin, Ipmax) - Ip)/Tg, its rise (Ip >= 0) or fall (Ip < 0) at most rrpwr per s;
* injected current (Ip - j Iq) V/|V|: P = Ip |V|, Q = Iq |V|.

FreqFlag 0: Pord = Pref and Pmeas = Pref through 1/(1 + s Tp) (PSID filters the
reference; equal to the terminal power at rest).

FreqFlag 1 (the active power-frequency control):

* Fmeas, the bus frequency (pu) through 1/(1 + s Trf): one state, the angle theta_f
  with d theta_f/dt = w/Trf, w = angle(V exp(-j theta_f)), and Fmeas = 1 + w/(2 pi fn
  Trf): the lag of 1 + (d angle(V)/dt)/(2 pi fn), the frequency of the bus voltage in
  the network's synchronous frame;
* Pmeas = P (the terminal power, Ip |V|) through 1/(1 + s Tp): the WECC specification's
  "Pgen" (PSS/E's Tp, the transducer of the electrical power);
* ferr = dbd(1 - Fmeas, fdbd1, fdbd2); the PI's error e = clip(Pref + Ddn min(ferr, 0) +
  Dup max(ferr, 0) - Pmeas, femin, femax) (Ddn acts on over-frequency, Dup on
  under-frequency);
* the power PI Kpg + Kig/s with non-windup limits [Pmin, Pmax] (`blocks.pi_nonwindup`,
  state PowerPI its integral), its output u;
* Pord: dPord/dt = clip((u - Pord)/Tpord, dPmin, dPmax), non-windup within [Pmin, Pmax]
  (the rate limit on the lag's rate, as Dynawo's ``RateLimFirstOrderFreeze``).

At rest the PI's error is 0, and a frequency held at f settles with P = Pref + Ddn
min(ferr, 0) + Dup max(ferr, 0) within [Pmin, Pmax] (and the current limits).  Not as
PSID's ``Val{1}``, whose Pmeas lags the constant Pref (its PI then integrates the droop
term to Pmin or Pmax instead of settling at the droop) and whose rate limit bounds the
integral's rate only (its dPord state drops the proportional path); its Fmeas lags the
system frequency (1 in its test 42 with an infinite bus), stabctl's the bus's.

VtripFlag 1 (the voltage tripping with partial reconnection), a multiplier on the
current commands with timers, on the terminal voltage v = |V|; the low side:

* v below vl0 for tvl0 s: all trip, for good (multiplier 0);
* v below vl1, for less than tvl1 s: the output lowered with the voltage, m_pre (v -
  vl0)/(vl1 - vl0) (clipped to [0, 1]), nothing tripped: back above vl1 it is m_pre
  again; m_pre is the multiplier before the dip (1 at the start);
* v below vl1 for tvl1 s: a share trips: with vmin the lowest v from then on (within
  [vl0, vl1]), the multiplier is m_pre ((vmin - vl0) + Vrfrac (v - vmin))/(vl1 - vl0)
  (clipped to [0, 1]): m_pre (vmin - vl0)/(vl1 - vl0) at the lowest voltage, rising
  with the share Vrfrac of the voltage's recovery;
* when v returns above vl1 after such a trip, the share Vrfrac of those tripped
  reconnects: m_pre becomes m + Vrfrac (m_pre - m), m = m_pre (vmin - vl0)/(vl1 - vl0);
* the high side alike with vh1, vh0, tvh1, tvh0 and the highest v: (vh0 - vmax)/(vh0 -
  vh1); the multiplier is the product of the two sides'.

This is the WECC DER_A specification's partial tripping as PowerWorld's DER_A page
states it (vl0, vl1 the voltages of multipliers 0 and 1; beyond tvl1 the multiplier
"tracks a depressed curve according to Vrfrac and an internally tracked value of the
minimum voltage") and InterPSS's ``DER_A_PosSeqImpl`` (written from PowerWorld's
pseudocode) and Dynawo's ``der_a`` LVRT/OVRT code it: both lower the output linearly
before tvl1 (a momentary reduction), and take the minimum from the trip on (Dynawo: the
voltage when tvl1 expires).  Until round 54 (AM03) stabctl lowered nothing before tvl1
and took the lowest voltage since the dip began.

FtripFlag 1 (the frequency tripping): Fmeas below fl for tfl s, or above fh for tfh s,
while Vmeas >= Vpr (below Vpr the frequency trip is blocked): all trip, for good (the
multiplier 0; the specification has no partial frequency trip).

The multiplier Mult is the product of the voltage and frequency multipliers through
1/(1 + s Tv) (a state where VtripFlag or FtripFlag is 1, else 1; PSID holds it at 1).
The timers, extremes and the multipliers before a dip are memory (`DA_MEMORY`) written
in place: a timer runs at 1 per s while its band holds and is set to 0 when it ends.

At the power-flow point: Ip = P0/|V0|, Iq = Q0/|V0|, Vmeas = |V0|, Pref = Pmeas = P0; Vref
= Vref0, or |V0| where Vref0 = 0 (PSS/E's note); Q_V = Iq - Iqv0, and Qref = Q_V |V0|
(PfFlag 0) or tan(pfaref) = Q_V |V0|/P0 (PfFlag 1); FreqFlag 1: theta_f the bus angle,
PowerPI = Pord = P0; Mult = 1.
"""

from __future__ import annotations

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.models.blocks import clip, deadband, lag, magnitude_rate, nonwindup, pi_nonwindup
from stabctl.models.converters.table import DERA1, C
from stabctl.models.declaration import DyrModel, slots

#: the PSS/E Model Library DERA1 record: 6 ICONs then 41 CONs (the WECC DER_A
#: specification's order, as TDcoSim writes the record for PSS/E's ``dyre_add``)
FLAGS = ("PfFlag", "FreqFlag", "PQFlag", "GenFlag", "VtripFlag", "FtripFlag")
CONS = (
    *("Trv", "Trf", "dbd1", "dbd2", "Kqv", "Vref0", "Tp", "Tiq", "Ddn", "Dup"),
    *("fdbd1", "fdbd2", "femax", "femin", "Pmax", "Pmin", "dPmax", "dPmin", "Tpord"),
    *("Kpg", "Kig", "Imax", "vl0", "vl1", "vh0", "vh1", "tvl0", "tvl1", "tvh0", "tvh1"),
    *("Vrfrac", "fl", "fh", "tfl", "tfh", "Tg", "rrpwr", "Tv", "Vpr", "Iqh1", "Iql1"),
)
#: the DERA1's fields read into its ibr_con columns (``da_`` and PQFlag's ``pqflag``):
#: every field of the record
COPIED = tuple(n for n in (*FLAGS, *CONS) if n != "PQFlag")
DYR = (DyrModel("DERA1", (*FLAGS, *CONS), {"pqflag": "PQFlag"} | {f"da_{n}": n for n in COPIED}),)
#: the least |P0| (pu, system base) of a DERA1 holding its power factor (PfFlag 1): below
#: it tan(pfaref) = Q0/P0 is the power flow's round-off (a generator at PG 0 solves to
#: |P0| ~ 1e-12 pu), refused
MIN_P_PF = 1e-6
#: the DERA1's lags (each >= LBND: Iq and Ip would otherwise follow the voltage at once)
LAGS = ("da_Trv", "da_Tp", "da_Tiq", "da_Tg")
#: the lags of its controls, with the flags that switch them on (each >= LBND where on)
SWITCHED_LAGS = (
    ("da_Trf", ("da_FreqFlag", "da_FtripFlag")),
    ("da_Tpord", ("da_FreqFlag",)),
    ("da_Tv", ("da_VtripFlag", "da_FtripFlag")),
)

#: the DERA1's states: its current lags (a PVD1's `PV.Ip`, `PV.Iq`: the injected current
#: is read alike), the voltage and power measurements, the reactive current reference, the
#: frequency measurement's angle and the power PI's integral and power order (FreqFlag 1),
#: the trip multiplier (VtripFlag or FtripFlag 1)
DA_STATES = ("Ip", "Iq", "Vmeas", "Pmeas", "Q_V", "theta_f", "PowerPI", "Pord", "Mult")
#: its memory (the tripping's, written in place): per voltage side (low, high) the timers
#: of bands 1 and 0, the extreme voltage of the dip (stored as s v: s = 1 low, -1 high)
#: and the multiplier before it; the frequency trip's timers and its latch
DA_MEMORY = (
    *("tl1", "tl0", "vext_l", "mpre_l", "th1", "th0", "vext_h", "mpre_h"),
    *("tfl_timer", "tfh_timer", "ftrip"),
)
DA = slots("DERA1Slots", (*DA_STATES, *DA_MEMORY))
#: the slots of the memory
MEMORY = tuple(range(int(DA.tl1), int(DA.ftrip) + 1))

#: the non-windup rule of the Pord limits: the IEEE 421.5 annex's (a numpy bool so that
#: the block compiles once for it, the kernel coding rules)
_ANNEX_RULE = np.bool_(True)


@kernel
def _limits(P, k, Ip, Iq):
    """(Ipmin, Ipmax, Iqmax) of device k at its current states Ip, Iq (PSID's
    ``current_limit_logic``): PQFlag 1 P priority, 0 Q priority; Ipmin 0 (GenFlag 1) or
    -Ipmax (GenFlag 0)."""
    imax = P[k, C.DA_IMAX]
    if P[k, C.PQFLAG] == 1.0:
        Ipmax = imax
        Iqmax = min(np.sqrt(max(imax * imax - Ip * Ip, 0.0)), imax)
    else:
        Iqmax = imax
        Ipmax = min(np.sqrt(max(imax * imax - Iq * Iq, 0.0)), imax)
    Ipmin = 0.0 if P[k, C.DA_GENFLAG] == 1.0 else -Ipmax
    return Ipmin, Ipmax, Iqmax


@kernel
def frequency(P, x, k, V):
    """(Fmeas pu, d theta_f/dt) of DERA1 k at bus voltage V: the bus frequency through
    1/(1 + s Trf), from its angle state theta_f (the module's FreqFlag 1)."""
    w = np.angle(V * np.exp(-1j * x[DA.theta_f, k]))
    T = P[k, C.DA_TRF]
    return 1.0 + w / (2.0 * np.pi * P[k, C.FN] * T), w / T


@kernel
def _tripped_share(ext, u, u1, u0, frac):
    """The multiplier left after a partial voltage trip at the extreme ext (from the
    trip on) and voltage u, both as `_voltage_side`'s: ((e - u0) + Vrfrac (u - e))/(u1 -
    u0) with e = ext within [u0, u1], clipped to [0, 1]: (e - u0)/(u1 - u0) at the
    extreme, rising with slope Vrfrac toward the reconnected share at u1 (InterPSS's
    ``DER_A_PosSeqImpl``, PowerWorld's DER_A pseudocode; Dynawo's ``LVRT.mo`` takes e as
    the voltage when tvl1 expires)."""
    e = clip(ext, u0, u1)
    return clip(((e - u0) + frac * (u - e)) / (u1 - u0), 0.0, 1.0)


@kernel
def _voltage_side(x, k, dx, u, u1, u0, t1, t0, frac, s1, s0, sext, spre):
    """One side of the voltage tripping of device k (the module's VtripFlag 1) at u = s
    v (s = 1 the low side, -1 the high side; u1 = s vl1, u0 = s vl0 or the high side's):
    its timers s1 (below u1), s0 (below u0), extreme sext (since the s1 trip) and
    multiplier before the dip spre updated in place (the timers' rates into dx); returns
    the side's multiplier."""
    dx[s1, k] = dx[s0, k] = dx[sext, k] = dx[spre, k] = 0.0
    if u < u0:
        if x[s0, k] >= t0:
            x[spre, k] = 0.0  # all tripped, for good
        else:
            dx[s0, k] = 1.0
    else:
        x[s0, k] = 0.0
    pre = x[spre, k]
    if u < u1:
        if x[s1, k] < t1:  # before the trip: the output lowered with the voltage
            dx[s1, k] = 1.0
            return pre * clip((u - u0) / (u1 - u0), 0.0, 1.0)
        x[sext, k] = min(x[sext, k], u)
        return pre * _tripped_share(x[sext, k], u, u1, u0, frac)
    if x[s1, k] >= t1 and x[sext, k] < u1:  # back after a trip: a share reconnects
        pre = pre * _tripped_share(x[sext, k], u1, u1, u0, frac)
        x[spre, k] = pre
    x[s1, k] = 0.0
    x[sext, k] = u1
    return pre


@kernel
def _frequency_timer(x, k, dx, on, t, slot):
    """A frequency trip timer of device k: runs while ``on``, set to 0 when it ends;
    returns True once it has run t s while on (the trip)."""
    dx[slot, k] = 0.0
    if not on:
        x[slot, k] = 0.0
        return False
    if x[slot, k] >= t:
        return True
    dx[slot, k] = 1.0
    return False


@kernel
def trip_multiplier(P, x, k, v, vmeas, fmeas, dx):
    """The trip multiplier (before its lag Tv) of DERA1 k at bus voltage magnitude v,
    measured voltage vmeas and frequency fmeas (pu): the voltage sides' product (VtripFlag
    1) times 0 once the frequency has tripped (FtripFlag 1); its memory updated in place,
    the timers' rates into dx."""
    m = 1.0
    if P[k, C.DA_VTRIPFLAG] == 1.0:
        frac = P[k, C.DA_VRFRAC]
        m = _voltage_side(
            x, k, dx, v, P[k, C.DA_VL1], P[k, C.DA_VL0], P[k, C.DA_TVL1], P[k, C.DA_TVL0],
            frac, DA.tl1, DA.tl0, DA.vext_l, DA.mpre_l,
        )  # fmt: skip
        m *= _voltage_side(
            x, k, dx, -v, -P[k, C.DA_VH1], -P[k, C.DA_VH0], P[k, C.DA_TVH1],
            P[k, C.DA_TVH0], frac, DA.th1, DA.th0, DA.vext_h, DA.mpre_h,
        )  # fmt: skip
    if P[k, C.DA_FTRIPFLAG] == 1.0:
        armed = vmeas >= P[k, C.DA_VPR]
        low = _frequency_timer(
            x, k, dx, armed and fmeas < P[k, C.DA_FL], P[k, C.DA_TFL], DA.tfl_timer
        )
        high = _frequency_timer(
            x, k, dx, armed and fmeas > P[k, C.DA_FH], P[k, C.DA_TFH], DA.tfh_timer
        )
        if low or high:
            x[DA.ftrip, k] = 1.0
        dx[DA.ftrip, k] = 0.0
        m *= 1.0 - x[DA.ftrip, k]
    return m


@kernel
def power_order(P, x, k, S, fmeas, dx):
    """The power order Pord of DERA1 k (the module's FreqFlag 1) injecting S (complex pu)
    at measured frequency fmeas (pu): Pmeas, PowerPI and Pord's derivatives into dx, Pord
    (clamped to its limits in place) returned."""
    Pmeas, dx[DA.Pmeas, k] = lag(S.real, x[DA.Pmeas, k], P[k, C.DA_TP])
    ferr = deadband(1.0 - fmeas, P[k, C.DA_FDBD1], P[k, C.DA_FDBD2])
    droop = P[k, C.DA_DDN] * min(ferr, 0.0) + P[k, C.DA_DUP] * max(ferr, 0.0)
    e = clip(P[k, C.P0] + droop - Pmeas, P[k, C.DA_FEMIN], P[k, C.DA_FEMAX])
    pmin, pmax = P[k, C.DA_PMIN], P[k, C.DA_PMAX]
    u, dx[DA.PowerPI, k] = pi_nonwindup(
        e, x[DA.PowerPI, k], P[k, C.DA_KPG], P[k, C.DA_KIG], pmin, pmax
    )
    rate = clip((u - x[DA.Pord, k]) / P[k, C.DA_TPORD], P[k, C.DA_DPMIN], P[k, C.DA_DPMAX])
    x[DA.Pord, k], dx[DA.Pord, k] = nonwindup(x[DA.Pord, k], rate, pmin, pmax, _ANNEX_RULE, 0.0)
    return x[DA.Pord, k]


@kernel
def derivatives(P, x, k, V, dx):
    """Write the derivatives of DERA1 k (its slots `DA` in column k of dx) at bus voltage V
    (complex pu) and return its injected complex power P + j Q (pu, system base); its
    memory (`MEMORY`) and a Pord at a limit are written in place."""
    v = abs(V)
    Vmeas, dx[DA.Vmeas, k] = lag(v, x[DA.Vmeas, k], P[k, C.DA_TRV])
    vm = max(Vmeas, 0.01)
    Ip, Iq = x[DA.Ip, k], x[DA.Iq, k]
    S = v * Ip + 1j * v * Iq
    fmeas = 1.0
    dx[DA.theta_f, k] = 0.0
    if P[k, C.DA_FREQFLAG] == 1.0 or P[k, C.DA_FTRIPFLAG] == 1.0:
        fmeas, dx[DA.theta_f, k] = frequency(P, x, k, V)
    if P[k, C.DA_FREQFLAG] == 1.0:
        Pord = power_order(P, x, k, S, fmeas, dx)
    else:
        Pord = P[k, C.P0]
        _, dx[DA.Pmeas, k] = lag(Pord, x[DA.Pmeas, k], P[k, C.DA_TP])
        dx[DA.PowerPI, k] = dx[DA.Pord, k] = 0.0
    Pmeas = x[DA.Pmeas, k]
    if P[k, C.DA_PFFLAG] == 1.0:
        q = P[k, C.DA_TANPF] * Pmeas / vm
    else:
        q = P[k, C.DA_QREF] / vm
    Q_V, dx[DA.Q_V, k] = lag(q, x[DA.Q_V, k], P[k, C.DA_TIQ])
    mult = 1.0
    dx[DA.Mult, k] = 0.0
    for j in range(DA.tl1, DA.ftrip + 1):
        dx[j, k] = 0.0
    if P[k, C.DA_VTRIPFLAG] == 1.0 or P[k, C.DA_FTRIPFLAG] == 1.0:
        target = trip_multiplier(P, x, k, v, Vmeas, fmeas, dx)
        mult, dx[DA.Mult, k] = lag(target, x[DA.Mult, k], P[k, C.DA_TV])
    err = deadband(P[k, C.DA_VREF] - Vmeas, P[k, C.DA_DBD1], P[k, C.DA_DBD2])
    Iqv = clip(P[k, C.DA_KQV] * err, P[k, C.DA_IQL1], P[k, C.DA_IQH1])
    Ipmin, Ipmax, Iqmax = _limits(P, k, Ip, Iq)
    _, dx[DA.Iq, k] = lag(mult * clip(Iqv + Q_V, -Iqmax, Iqmax), Iq, P[k, C.DA_TG])
    _, dIp = lag(mult * clip(Pord / vm, Ipmin, Ipmax), Ip, P[k, C.DA_TG])
    dx[DA.Ip, k] = magnitude_rate(dIp, Ip, P[k, C.DA_RRPWR])
    return S


def services(vals: dict, kind: np.ndarray, P0, Q0, v0) -> dict[str, np.ndarray]:
    """The DERA1's initial references (ConverterParams ``da_Vref``, ``da_Qref``,
    ``da_tanpf``; 0 for the other types) at the power-flow point.

    Parameters
    ----------
    vals : dict of str to ndarray
        The ibr_con fields on the system base (`converter_params`), each (n_ibr,).
    kind : ndarray of int, shape (n_ibr,)
        The devices' types; the rows of `DERA1` get values.
    P0, Q0, v0 : ndarray, shape (n_ibr,)
        Initial P, Q (pu, system base) and bus voltage magnitude (pu).

    Returns
    -------
    dict of str to ndarray
        ``da_Vref``: Vref0, or |V0| where Vref0 = 0; ``da_Qref``: Q_V0 |V0| with Q_V0 =
        Q0/|V0| less the voltage control's initial Iqv (PfFlag 0); ``da_tanpf``: tan(pfaref)
        = Q_V0 |V0|/P0 (PfFlag 1; 0 where P0 = 0).
    """
    dera = kind == DERA1
    vref = np.where(vals["da_Vref0"] == 0.0, v0, vals["da_Vref0"])
    db = np.vectorize(deadband.py_func, otypes=[float])(
        vref - v0, vals["da_dbd1"], vals["da_dbd2"]
    )  # the voltage control's deadband, as `derivatives` applies it
    Iqv0 = np.clip(vals["da_Kqv"] * db, vals["da_Iql1"], vals["da_Iqh1"])
    with np.errstate(divide="ignore", invalid="ignore"):
        qref = (Q0 / v0 - Iqv0) * v0
        tanpf = np.where(P0 != 0.0, qref / np.where(P0 != 0.0, P0, 1.0), 0.0)
    return {
        "da_Vref": np.where(dera, vref, 0.0),
        "da_Qref": np.where(dera, qref, 0.0),
        "da_tanpf": np.where(dera, tanpf, 0.0),
    }


def switched_on(t, flags) -> np.ndarray:
    """The DERA1 rows of ``t`` (an ibr_con table or `ConverterParams`) with any of the
    ``flags`` (ibr_con field names) at 1, (n_ibr,) bool."""
    on = np.zeros(len(t.type), bool)
    for flag in flags:
        on |= getattr(t, flag) == 1
    return (t.type == DERA1) & on


def check(t) -> None:
    """Refuse DERA1 trip bands out of order in the ibr_con table ``t``: with VtripFlag 1,
    vl0 < vl1 <= vh1 < vh0 (the shares tripped are linear between them); with FtripFlag
    1, fl < fh.

    Parameters
    ----------
    t : ConverterTable
        The case's converters.

    Raises
    ------
    CaseError
        Naming the row and field (through the table's ``_fail``).
    """
    vt = switched_on(t, ("da_VtripFlag",))
    for lower, name, bad in (
        ("da_vl0", "da_vl1", vt & ~(t.da_vl0 < t.da_vl1)),
        ("da_vl1", "da_vh1", vt & ~(t.da_vl1 <= t.da_vh1)),
        ("da_vh1", "da_vh0", vt & ~(t.da_vh1 < t.da_vh0)),
        ("da_fl", "da_fh", switched_on(t, ("da_FtripFlag",)) & ~(t.da_fl < t.da_fh)),
    ):
        rows = np.flatnonzero(bad)
        if rows.size:
            why = "the DERA1's trip bands must be vl0 < vl1 <= vh1 < vh0, fl < fh"
            t._fail(rows[0], name, why, fields=(lower, name))


def initial(cp, x: np.ndarray, V: np.ndarray) -> None:
    """Write the DERA1s' states and memory into x (N_STATES, n_ibr) in place at the
    initial bus voltages V (n_ibr,) complex: Vmeas = |V0|, Pmeas = P0, Q_V = Q_V0;
    FreqFlag 1: theta_f = angle(V0), PowerPI = Pord = P0; Mult = 1 (VtripFlag or
    FtripFlag 1); the trip memory at rest (timers 0, the extremes at vl1 and vh1, the
    multipliers before a dip 1).  Its current slots are a PVD1's, written with them: Ip =
    P0/|V0|, Iq = Q0/|V0|."""
    dera = cp.type == DERA1
    v = np.abs(V)
    x[DA.Vmeas, dera] = v[dera]
    x[DA.Pmeas, dera] = cp.P0[dera]
    x[DA.Q_V, dera] = cp.da_Qref[dera] / v[dera]
    measured = switched_on(cp, ("da_FreqFlag", "da_FtripFlag"))
    x[DA.theta_f, measured] = np.angle(V[measured])
    freq = switched_on(cp, ("da_FreqFlag",))
    x[DA.PowerPI, freq] = x[DA.Pord, freq] = cp.P0[freq]
    trip = switched_on(cp, ("da_VtripFlag", "da_FtripFlag"))
    x[DA.Mult, trip] = 1.0
    vt = switched_on(cp, ("da_VtripFlag",))
    x[DA.vext_l, vt], x[DA.vext_h, vt] = cp.da_vl1[vt], -cp.da_vh1[vt]
    x[DA.mpre_l, vt] = x[DA.mpre_h, vt] = 1.0
