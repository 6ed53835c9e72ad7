"""DERA1, PSS/E's WECC aggregated distributed energy resources model (DER_A): its DYR
record, its named states, its initial point and its derivatives (docs/ibr.md).

A current source at its bus, in the bus voltage's frame (as a PVD1, `PV`): the active
current Ip and reactive current Iq lag their commands through Tg; the commands are the
power and reactive references over the measured voltage, within the current limits.  Its
parameters are ibr_con columns 214-227 (:mod:`.table`) and the table's ``pqflag``.

Modelled: FreqFlag 0 (the active power reference held: no frequency droop, no power PI),
PfFlag 0 and 1, PQFlag 0 and 1, GenFlag 0 and 1, as PowerSimulationsDynamics.jl's
``AggregateDistributedGenerationA`` (src/models/device.jl, ``_mdl_ode_...`` with
``Val{0}``; src/models/saturation_models.jl ``current_limit_logic``; initialisation
src/initialization/init_device.jl).  Per device (system base; the table's device-base
currents converted by `converter_params`), with Vm = max(Vmeas, 0.01):

* Vmeas = |V| through 1/(1 + s Trv); Pmeas = Pref through 1/(1 + s Tp) (PSID filters
  the reference; the WECC specification the terminal power: equal at rest);
* Q_V = Qref/Vm (PfFlag 0) or tan(pfaref) Pmeas/Vm (PfFlag 1) through 1/(1 + s Tiq);
* Iqv = Kqv dbd(Vref - Vmeas) within [Iql1, Iqh1] (deadband [dbd1, dbd2]);
* current limits on the current states: PQFlag 1 (P priority) Ipmax = Imax, Iqmax =
  sqrt(Imax^2 - Ip^2); PQFlag 0 (Q priority) Iqmax = Imax, Ipmax = sqrt(Imax^2 - Iq^2);
  Iqmin = -Iqmax, Ipmin = 0 (GenFlag 1) or -Ipmax (GenFlag 0);
* dIq/dt = (clip(Iqv + Q_V, Iqmin, Iqmax) - Iq)/Tg; dIp/dt = (clip(Pref/Vm, Ipmin,
  Ipmax) - Ip)/Tg, its rise (Ip >= 0) or fall (Ip < 0) at most rrpwr per s;
* injected current (Ip - j Iq) V/|V|: P = Ip |V|, Q = Iq |V|.

At the power-flow point: Ip = P0/|V0|, Iq = Q0/|V0|, Vmeas = |V0|, Pref = Pmeas = P0; Vref
= Vref0, or |V0| where Vref0 = 0 (PSS/E's note); Q_V = Iq - Iqv0, and Qref = Q_V |V0|
(PfFlag 0) or tan(pfaref) = Q_V |V0|/P0 (PfFlag 1).

Not modelled, refused at import naming the record and field (:mod:`stabctl.io.dyr_converters`):
FreqFlag 1, VtripFlag 1 and FtripFlag 1 (the voltage and frequency tripping with partial
reconnection Vrfrac, whose multiplier then is 1 and its lag Tv has no effect; PSID holds it
at 1 as well).
"""

from __future__ import annotations

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.models.blocks import clip, deadband, lag
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
#: the DERA1's fields read into its ibr_con columns (``da_`` and PQFlag's ``pqflag``); the
#: others are the refused controls' (`REFUSED_FLAGS`)
COPIED = (
    *("PfFlag", "GenFlag", "Trv", "dbd1", "dbd2", "Kqv", "Vref0", "Tp", "Tiq", "Imax"),
    *("Tg", "rrpwr", "Iqh1", "Iql1"),
)
DYR = (DyrModel("DERA1", (*FLAGS, *CONS), {"pqflag": "PQFlag"} | {f"da_{n}": n for n in COPIED}),)
#: the flags a DERA1 must have 0 (their value 1 is not modelled), with what 1 would switch on
REFUSED_FLAGS = {
    "FreqFlag": "the active power-frequency control (droop, power PI, Pord lag)",
    "VtripFlag": "the voltage tripping with partial reconnection",
    "FtripFlag": "the frequency tripping",
}
#: the least |P0| (pu, system base) of a DERA1 holding its power factor (PfFlag 1): below
#: it tan(pfaref) = Q0/P0 is the power flow's round-off (a generator at PG 0 solves to
#: |P0| ~ 1e-12 pu), refused
MIN_P_PF = 1e-6
#: the DERA1's lags (each >= LBND: Iq and Ip would otherwise follow the voltage at once)
LAGS = ("da_Trv", "da_Tp", "da_Tiq", "da_Tg")

#: the DERA1's slots: its current lags (a PVD1's `PV.Ip`, `PV.Iq`: the injected current is
#: read alike), the voltage and power measurements, the reactive current reference
DA = slots("DERA1Slots", ("Ip", "Iq", "Vmeas", "Pmeas", "Q_V"))


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
def derivatives(P, x, k, V, dx):
    """Write the derivatives of DERA1 k (its slots `DA` in column k of dx) at bus voltage V
    (complex pu) and return its injected complex power P + j Q (pu, system base)."""
    v = abs(V)
    Vmeas, dx[DA.Vmeas, k] = lag(v, x[DA.Vmeas, k], P[k, C.DA_TRV])
    vm = max(Vmeas, 0.01)
    Pref = P[k, C.P0]
    Pmeas, dx[DA.Pmeas, k] = lag(Pref, x[DA.Pmeas, k], P[k, C.DA_TP])
    if P[k, C.DA_PFFLAG] == 1.0:
        q = P[k, C.DA_TANPF] * Pmeas / vm
    else:
        q = P[k, C.DA_QREF] / vm
    Q_V, dx[DA.Q_V, k] = lag(q, x[DA.Q_V, k], P[k, C.DA_TIQ])
    err = deadband(P[k, C.DA_VREF] - Vmeas, P[k, C.DA_DBD1], P[k, C.DA_DBD2])
    Iqv = clip(P[k, C.DA_KQV] * err, P[k, C.DA_IQL1], P[k, C.DA_IQH1])
    Ip, Iq = x[DA.Ip, k], x[DA.Iq, k]
    Ipmin, Ipmax, Iqmax = _limits(P, k, Ip, Iq)
    _, dx[DA.Iq, k] = lag(clip(Iqv + Q_V, -Iqmax, Iqmax), Iq, P[k, C.DA_TG])
    _, dIp = lag(clip(Pref / vm, Ipmin, Ipmax), Ip, P[k, C.DA_TG])
    rate = P[k, C.DA_RRPWR]
    dx[DA.Ip, k] = min(dIp, rate) if Ip >= 0.0 else max(dIp, -rate)
    return v * Ip + 1j * v * Iq


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


def initial(cp, x: np.ndarray, v: np.ndarray) -> None:
    """Write the DERA1s' measurement states into x (N_STATES, n_ibr) in place at the
    initial bus voltage magnitudes v (n_ibr,): Vmeas = |V0|, Pmeas = P0, Q_V = Q_V0 (its
    current slots are a PVD1's, written with them: Ip = P0/|V0|, Iq = Q0/|V0|)."""
    dera = cp.type == DERA1
    x[DA.Vmeas, dera] = v[dera]
    x[DA.Pmeas, dera] = cp.P0[dera]
    x[DA.Q_V, dera] = cp.da_Qref[dera] / v[dera]
