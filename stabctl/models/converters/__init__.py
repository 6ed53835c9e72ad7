"""Converter-interfaced devices (inverter-based resources): ANDES 2.0's distributed models
PVD1 (type 1, WECC distributed PV) and ESD1 (type 2, PVD1 with a state of charge), with the
ANDES bus-frequency measurement (BusFreq) each reads.

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

States per device (`STATE_NAMES`): Ip, Iq, the measurement lag and washout, the SOC
(ESD1; 0 for PVD1).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from stabctl._jit.decorators import kernel, njit
from stabctl.errors import CaseError
from stabctl.models.blocks import (
    GAIN_BEFORE,
    LBND,
    clip,
    lag,
    leadlag_input_state,
    nonwindup,
    washout,
)
from stabctl.models.declaration import (
    Declared,
    DyrModel,
    Family,
    Param,
    check_packed,
    layout,
    pack,
    params_class,
)

if TYPE_CHECKING:
    from stabctl.case import Case


# --------------------------------------------------------------------------------------
# ibr_con: converter-interfaced devices (stabctl's table; ANDES 2.0 PVD1, ESD1, REGCA1)
# --------------------------------------------------------------------------------------

#: ANDES's converter types: PVD1 (WECC distributed PV), ESD1 (PVD1 with a state of charge),
#: REGCA1 (WECC second-generation renewable generator/converter, REGC_A)
PVD1, ESD1, REGCA1 = 1, 2, 3

_DEV_PU: dict[str, Any] = dict(unit="pu")  # on the device base mva (ANDES ``power=True``)

#: REGCA1's electrical control (ibr_con ``reec``): none, REECA1 (WECC REEC_A), REECB1 (WECC
#: REEC_B: REECA1's columns without its VDL curves, Iqinj hold, PFLAG and Vref1; ANDES 2.0
#: ``renewable/reecb1.py``)
NO_REEC, REECA1, REECB1 = 0, 1, 2


def _reeca1_params(col: int) -> tuple[Param, ...]:
    """REECA1's columns from ``col`` on (ANDES 2.0 ``renewable/reeca1.py`` REECA1Data and
    its config kqs, kvs, tpfilt; PQFLAG is the table's ``pqflag``).  Powers and currents
    on the device base where ANDES converts them (``power``/``current`` True); the gains
    Kqv, Kqp, Kqi, Kvp, Kvi and the currents Iqh1, Iql1, Iqfrz on the system base, as
    ANDES reads them."""
    flag: dict[str, Any] = dict(unit="code", choices=(0.0, 1.0))
    rows: list[tuple[str, dict[str, Any]]] = [
        ("PFFLAG", dict(flag, doc="REECA1: 1 power-factor control, 0 Q control")),
        ("VFLAG", dict(flag, doc="REECA1: 1 Q control (PI), 0 voltage control")),
        ("QFLAG", dict(flag, doc="REECA1: 1 voltage/Q control (PI), 0 constant PF or Q")),
        ("PFLAG", dict(flag, doc="REECA1: 1 P order times the speed (1 here), 0 not")),
        ("Vdip", dict(unit="pu", default=0.8, doc="REECA1: voltage below which it freezes")),
        ("Vup", dict(unit="pu", default=1.2, doc="REECA1: voltage above which it freezes")),
        ("Trv", dict(unit="s", default=0.02, lo=0.0, doc="REECA1: voltage filter")),
        ("dbd1", dict(unit="pu", default=-0.02, hi=0.0, doc="REECA1: lower voltage deadband")),
        ("dbd2", dict(unit="pu", default=0.02, lo=0.0, doc="REECA1: upper voltage deadband")),
        ("Kqv", dict(unit="pu", default=1.0, lo=0.0, doc="REECA1: Iqinj per pu voltage error")),
        ("Iqh1", dict(unit="pu", default=999.0, doc="REECA1: upper limit of Iqinj")),
        ("Iql1", dict(unit="pu", default=-999.0, doc="REECA1: lower limit of Iqinj")),
        ("Vref0", dict(unit="pu", default=1.0, doc="REECA1: Iqinj reference (0: initial V)")),
        ("Iqfrz", dict(unit="pu", doc="REECA1: Iqinj held for Thld > 0 after a dip")),
        ("Thld", dict(unit="s", doc="REECA1: Iqinj hold after a dip (> 0 Iqfrz, < 0 Kqv)")),
        ("Thld2", dict(unit="s", lo=0.0, doc="REECA1: Ipmax held after a dip")),
        ("Tp", dict(unit="s", default=0.02, lo=0.0, doc="REECA1: Pe filter")),
        ("QMax", dict(_DEV_PU, default=999.0, doc="REECA1: upper Q reference limit")),
        ("QMin", dict(_DEV_PU, default=-999.0, doc="REECA1: lower Q reference limit")),
        ("VMAX", dict(unit="pu", default=999.0, doc="REECA1: upper voltage control limit")),
        ("VMIN", dict(unit="pu", default=-999.0, doc="REECA1: lower voltage control limit")),
        ("Kqp", dict(unit="pu", default=1.0, doc="REECA1: Q PI proportional gain")),
        ("Kqi", dict(unit="1/s", default=0.1, doc="REECA1: Q PI integral gain")),
        ("Kvp", dict(unit="pu", default=1.0, doc="REECA1: V PI proportional gain")),
        ("Kvi", dict(unit="1/s", default=0.1, doc="REECA1: V PI integral gain")),
        ("Vref1", dict(unit="pu", default=1.0, doc="REECA1: voltage reference (VFLAG 0)")),
        ("dPmax", dict(_DEV_PU, default=999.0, doc="REECA1: upper P reference rate (x tpfilt)")),
        ("dPmin", dict(_DEV_PU, default=-999.0, doc="REECA1: lower P reference rate")),
        ("PMAX", dict(_DEV_PU, default=999.0, doc="REECA1: upper P order limit")),
        ("PMIN", dict(_DEV_PU, doc="REECA1: lower P order limit")),
        ("Imax", dict(_DEV_PU, default=999.0, doc="REECA1: apparent current limit")),
        ("Tpord", dict(unit="s", default=0.02, lo=0.0, doc="REECA1: P order lag")),
        *_vdl_params("VDL1, Iq limit", "Vq", "Iq", (2.0, 4.0, 8.0, 10.0)),
        *_vdl_params("VDL2, Ip limit", "Vp", "Ip", (2.0, 4.0, 8.0, 12.0)),
        ("Kqs", dict(unit="", default=2.0, lo=0.0, doc="REECA1: Q PI tracking gain (kqs)")),
        ("Kvs", dict(unit="", default=2.0, lo=0.0, doc="REECA1: V PI tracking gain (kvs)")),
        ("Tpfilt", dict(unit="s", default=0.02, lo=0.0, doc="REECA1: P reference filter")),
    ]
    return tuple(Param(name, col=col + j, **kw) for j, (name, kw) in enumerate(rows))


def _vdl_params(curve: str, v_name: str, i_name: str, currents) -> list[tuple[str, dict[str, Any]]]:
    """REECA1's voltage-dependent current limit ``curve``: four voltages (pu) and four
    currents (device base), ANDES's defaults."""
    volts = [
        (f"{v_name}{j}", dict(unit="pu", default=v, doc=f"REECA1: {curve} point {j}, voltage"))
        for j, v in enumerate((0.2, 0.4, 0.8, 1.0), 1)
    ]
    return volts + [
        (f"{i_name}{j}", dict(_DEV_PU, default=i, doc=f"REECA1: {curve} point {j}, current"))
        for j, i in enumerate(currents, 1)
    ]


_REECA1_PARAMS = _reeca1_params(54)

#: REECA1's plant control (ibr_con ``repc``): none, REPCA1 (WECC REPC_A)
NO_REPC, REPCA1 = 0, 1


def _repca1_params(col: int) -> tuple[Param, ...]:
    """REPCA1's columns from ``col`` on, prefixed ``pc_`` (ANDES 2.0
    ``renewable/repca1.py`` REPCA1Data; config kqs, freeze): its reactive power path.
    The monitored line's end buses and impedance (system base) and the compensation
    impedance (Rc, Xc or, where not given, the line's: ANDES NumSelect) are written by
    the import; its frequency measurement is the table's Tfm, Twm (ANDES BusFreq)."""
    flag: dict[str, Any] = dict(unit="code", choices=(0.0, 1.0))
    rows: list[tuple[str, dict[str, Any]]] = [
        ("VCFlag", dict(flag, default=1.0, doc="1 compensated voltage, 0 V + Kc Qline")),
        ("RefFlag", dict(flag, default=1.0, doc="1 voltage control, 0 line Q control")),
        ("Fflag", dict(flag, doc="1 the frequency path's Pext on, 0 off")),
        ("PLflag", dict(flag, default=1.0, doc="1 the line P error in the P path, 0 not")),
        ("bus1", dict(unit="code", integer=True, doc="monitored line's from bus (0: none)")),
        ("bus2", dict(unit="code", integer=True, doc="monitored line's to bus (0: none)")),
        ("r", dict(unit="pu", default=1.0, doc="monitored line resistance")),
        ("x", dict(unit="pu", default=1.0, doc="monitored line reactance")),
        ("Rc", dict(unit="pu", doc="line drop compensation resistance")),
        ("Xc", dict(unit="pu", doc="line drop compensation reactance")),
        ("Kc", dict(unit="pu", doc="reactive droop gain (VCFlag 0)")),
        ("Tfltr", dict(unit="s", default=0.02, lo=0.0, doc="voltage and Q filters")),
        ("Kp", dict(unit="pu", default=1.0, doc="PI proportional gain")),
        ("Ki", dict(unit="1/s", default=0.1, doc="PI integral gain")),
        ("Kqs", dict(unit="", default=2.0, lo=0.0, doc="PI tracking gain (kqs)")),
        ("Tft", dict(unit="s", default=1.0, lo=0.0, doc="lead time constant")),
        ("Tfv", dict(unit="s", default=1.0, lo=0.0, doc="lag time constant")),
        ("Vfrz", dict(unit="pu", default=0.8, doc="voltage below which the error is held")),
        ("freeze", dict(flag, default=1.0, doc="1 the hold below Vfrz on, 0 off")),
        ("emax", dict(unit="pu", default=999.0, doc="upper error limit")),
        ("emin", dict(unit="pu", default=-999.0, doc="lower error limit")),
        ("dbd1", dict(unit="pu", default=-0.1, hi=0.0, doc="lower error deadband")),
        ("dbd2", dict(unit="pu", default=0.1, lo=0.0, doc="upper error deadband")),
        ("Qmax", dict(unit="pu", default=999.0, doc="upper Q command (system base)")),
        ("Qmin", dict(unit="pu", default=-999.0, doc="lower Q command (system base)")),
        ("Kpg", dict(unit="pu", default=1.0, doc="P PI proportional gain")),
        ("Kig", dict(unit="1/s", default=0.1, doc="P PI integral gain")),
        ("Ksg", dict(unit="", default=2.0, lo=0.0, doc="P PI tracking gain (ksg)")),
        ("Tp", dict(unit="s", default=0.02, lo=0.0, doc="line P filter")),
        ("fdbd1", dict(unit="pu", default=-0.0002833, hi=0.0, doc="lower frequency deadband")),
        ("fdbd2", dict(unit="pu", default=0.0002833, lo=0.0, doc="upper frequency deadband")),
        ("femax", dict(unit="pu", default=0.05, doc="upper P error limit")),
        ("femin", dict(unit="pu", default=-0.05, doc="lower P error limit")),
        ("Pmax", dict(_DEV_PU, default=999.0, doc="upper P PI output")),
        ("Pmin", dict(_DEV_PU, default=-999.0, doc="lower P PI output")),
        ("Tg", dict(unit="s", default=0.02, lo=0.0, doc="Pext lag")),
        ("Ddn", dict(unit="pu", default=10.0, doc="droop gain, frequency above 1 pu")),
        ("Dup", dict(unit="pu", default=10.0, doc="droop gain, frequency below 1 pu")),
    ]
    return tuple(
        Param(f"pc_{name}", col=col + j, **{**kw, "doc": "REPCA1: " + kw["doc"]})
        for j, (name, kw) in enumerate(rows)
    )


_REPCA1_PARAMS = _repca1_params(106)

#: the wind turbine's drive train (ibr_con ``wind``, a REECA1's RenGovernor): none, WTDTA1
#: (two masses), WTDS (one mass)
NO_WIND, WTDTA1, WTDS = 0, 1, 2


def _wind_params(col: int) -> tuple[Param, ...]:
    """The wind turbine's columns from ``col`` on (ANDES 2.0 ``renewable/wtdta1.py``,
    ``wtds.py``, ``wtara1.py``, ``wtpta1.py``, ``wttqa1.py``): the drive train ``wt_``,
    the aerodynamics ``wa_``, the pitch control ``wp_`` and the torque control ``wq_``,
    each with its on/off code.  Inertias, damping, torque limits and the torque
    control's power points on the device base (``wq_Tn`` where given), as ANDES converts
    them; angles in degrees, as ANDES's pitch and aerodynamics read them."""
    flag: dict[str, Any] = dict(unit="code", choices=(0.0, 1.0))
    rows: list[tuple[str, dict[str, Any]]] = [
        (
            "wt_H",
            dict(_DEV_PU, unit="MWs/MVA", default=3.0, lo=0.0, doc="WTDTA1/WTDS: total inertia"),
        ),
        ("wt_DAMP", dict(_DEV_PU, doc="WTDTA1: generator damping (WTDS: D, on its speed)")),
        ("wt_Htfrac", dict(unit="", default=0.5, doc="WTDTA1: turbine inertia fraction")),
        ("wt_Freq1", dict(unit="pu", default=1.0, doc="WTDTA1: first shaft torsional frequency")),
        ("wt_Dshaft", dict(_DEV_PU, default=1.0, doc="WTDTA1: shaft damping")),
        ("wt_w0", dict(unit="pu", default=1.0, doc="WTDTA1/WTDS: speed without a torque control")),
        ("aero", dict(flag, doc="WTARA1 aerodynamics: 1 on (Pm falls with the pitch), 0 off")),
        ("wa_Ka", dict(unit="pu/deg", default=1.0, lo=0.0, doc="WTARA1: aerodynamic gain")),
        ("wa_theta0", dict(unit="deg", doc="WTARA1: initial pitch angle")),
        ("pitch", dict(flag, doc="WTPTA1 pitch control: 1 on, 0 off (needs aero)")),
        ("wp_Kiw", dict(unit="1/s", default=0.1, doc="WTPTA1: speed PI integral gain")),
        ("wp_Kpw", dict(unit="pu", doc="WTPTA1: speed PI proportional gain")),
        ("wp_Kic", dict(unit="1/s", default=0.1, doc="WTPTA1: power PI integral gain")),
        ("wp_Kpc", dict(unit="pu", doc="WTPTA1: power PI proportional gain")),
        ("wp_Kcc", dict(unit="pu", doc="WTPTA1: power error gain in the speed PI")),
        ("wp_Tp", dict(unit="s", default=0.3, lo=0.0, doc="WTPTA1: blade response lag")),
        ("wp_thmax", dict(unit="deg", default=30.0, doc="WTPTA1: maximum pitch angle")),
        ("wp_thmin", dict(unit="deg", doc="WTPTA1: minimum pitch angle")),
        ("wp_dthmax", dict(unit="deg", default=5.0, doc="WTPTA1: upper rate of Tp dtheta/dt")),
        ("wp_dthmin", dict(unit="deg", default=-5.0, doc="WTPTA1: lower rate of Tp dtheta/dt")),
        ("torque", dict(flag, doc="WTTQA1 torque control: 1 on, 0 off (needs pitch)")),
        ("wq_Kip", dict(unit="1/s", default=0.1, doc="WTTQA1: PI integral gain")),
        ("wq_Kpp", dict(unit="pu", doc="WTTQA1: PI proportional gain")),
        ("wq_Tp", dict(unit="s", default=0.05, lo=0.0, doc="WTTQA1: Pe filter")),
        ("wq_Twref", dict(unit="s", default=30.0, lo=0.0, doc="WTTQA1: speed reference lag")),
        ("wq_Temax", dict(_DEV_PU, default=1.2, doc="WTTQA1: maximum electric torque")),
        ("wq_Temin", dict(_DEV_PU, doc="WTTQA1: minimum electric torque")),
        ("wq_Tflag", dict(flag, doc="WTTQA1: 1 power error, 0 speed error")),
        *(
            pair
            for j, (p, sp) in enumerate(((0.2, 0.58), (0.4, 0.72), (0.6, 0.86), (0.8, 1.0)), 1)
            for pair in (
                (f"wq_p{j}", dict(_DEV_PU, default=p, doc=f"WTTQA1: power point {j}")),
                (f"wq_sp{j}", dict(unit="pu", default=sp, doc=f"WTTQA1: speed at point {j}")),
            )
        ),
        ("wq_Tn", dict(unit="MVA", lo=0.0, doc="WTTQA1: turbine rating (0: the device's mva)")),
    ]
    return tuple(Param(name, col=col + j, **kw) for j, (name, kw) in enumerate(rows))


_WIND_PARAMS = _wind_params(146)

#: the angle a REGCA1 reads (ibr_con ``pll``): its bus's (0; REGCA1, ANDES's REGCP1 without a
#: PLL), or a PLL1's (1; REGCP1 with a PLL1, ANDES 2.0 ``renewable/regcp1.py``)
NO_PLL, PLL1 = 0, 1

_PLL_PARAMS = (
    Param("pll_Kp", "pu", 184, default=0.1, doc="PLL1: PI proportional gain (rad/rad)"),
    Param("pll_Ki", "1/s", 185, default=0.1, doc="PLL1: PI integral gain"),
    Param("pll_Tf", "s", 186, default=0.05, lo=0.0, doc="PLL1: input angle filter"),
    Param("pll_Tp", "s", 187, default=0.05, lo=0.0, doc="PLL1: output angle lag"),
)
#: the DG protection of a PVD1 or ESD1 (ibr_con ``relay``): none, ANDES's DGPRCT1 (the bus
#: voltage), DGPRCTExt (the voltage held at its initial value)
NO_RELAY, DGPRCT1, DGPRCTEXT = 0, 1, 2


def _relay_params(col: int) -> tuple[Param, ...]:
    """The DG protection's columns from ``col`` on (ANDES 2.0
    ``distributed/dgprct.py``, DGPRCT1 and DGPRCTExt, after IEEE 1547-2018's ride-through
    categories), ANDES's defaults: its enables, then the frequency bands (Hz) and how long
    the frequency may stay in each, the voltage bands (pu) and their times."""
    flag: dict[str, Any] = dict(unit="code", choices=(0.0, 1.0))
    rows: list[tuple[str, dict[str, Any]]] = [
        ("pr_fen", dict(flag, default=1.0, doc="DGPRCT: frequency protection 1 on, 0 off")),
        ("pr_Ven", dict(flag, doc="DGPRCT: voltage protection 1 on, 0 off")),
        *(
            (f"pr_{n}", dict(unit="Hz", default=d, doc=f"DGPRCT: frequency point {n}"))
            for n, d in (("fl3", 50.0), ("fl2", 57.5), ("fl1", 59.2))
        ),
        *(
            (f"pr_{n}", dict(unit="Hz", default=d, doc=f"DGPRCT: frequency point {n}"))
            for n, d in (("fu1", 60.5), ("fu2", 61.5), ("fu3", 70.0))
        ),
        ("pr_Tfl1", dict(unit="s", default=300.0, lo=0.0, doc="DGPRCT: time in (fl3, fl1)")),
        ("pr_Tfl2", dict(unit="s", default=10.0, lo=0.0, doc="DGPRCT: time in (fl3, fl2)")),
        ("pr_Tfu1", dict(unit="s", default=300.0, lo=0.0, doc="DGPRCT: time in (fu1, fu3)")),
        ("pr_Tfu2", dict(unit="s", default=10.0, lo=0.0, doc="DGPRCT: time in (fu2, fu3)")),
        *(
            (f"pr_{n}", dict(unit="pu", default=d, doc=f"DGPRCT: voltage point {n}"))
            for n, d in (("vl4", 0.1), ("vl3", 0.45), ("vl2", 0.6), ("vl1", 0.88))
        ),
        *(
            (f"pr_{n}", dict(unit="pu", default=d, doc=f"DGPRCT: voltage point {n}"))
            for n, d in (("vu1", 1.1), ("vu2", 1.2), ("vu3", 2.0))
        ),
        ("pr_Tvl1", dict(unit="s", default=2.0, lo=0.0, doc="DGPRCT: time in (vl4, vl1)")),
        ("pr_Tvl2", dict(unit="s", default=1.0, lo=0.0, doc="DGPRCT: time in (vl4, vl2)")),
        (
            "pr_Tvl3",
            dict(
                unit="s",
                default=0.16,
                lo=0.0,
                doc="DGPRCT: time in (vl4, vl3) (ANDES's data; its vl3 timer runs to Tvl2)",
            ),
        ),
        ("pr_Tvu1", dict(unit="s", default=1.0, lo=0.0, doc="DGPRCT: time in (vu1, vu3)")),
        ("pr_Tvu2", dict(unit="s", default=0.16, lo=0.0, doc="DGPRCT: time in (vu2, vu3)")),
        ("pr_Tres", dict(unit="s", default=0.05, lo=1e-3, doc="DGPRCT: timers' reset time")),
    ]
    return tuple(Param(name, col=col + j, **kw) for j, (name, kw) in enumerate(rows))


_RELAY_PARAMS = _relay_params(189)
#: the ibr_con fields a DG protection sets (``relay`` and its columns)
RELAY_FIELDS = ("relay", *(p.name for p in _RELAY_PARAMS))
#: the ibr_con fields a wind turbine sets (``wind`` and its models' columns)
WIND_FIELDS = ("wind", *(p.name for p in _WIND_PARAMS))
#: the ibr_con fields a REPCA1 sets (``pc_`` and ANDES's name)
REPCA1_FIELDS = tuple(p.name for p in _REPCA1_PARAMS)
#: the ibr_con fields a REECA1 sets (its own columns, its PQFLAG and its Iq filter Tiq)
REECA1_FIELDS = ("pqflag", "tiq", *(p.name for p in _REECA1_PARAMS))

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


#: REPCA1's CONs in PSS/E order
_REPC_CONS = (
    *("Tfltr", "Kp", "Ki", "Tft", "Tfv", "Vfrz", "Rc", "Xc", "Kc", "emax", "emin", "dbd1"),
    *("dbd2", "Qmax", "Qmin", "Kpg", "Kig", "Tp", "fdbd1", "fdbd2", "femax", "femin"),
    *("Pmax", "Pmin", "Tg", "Ddn", "Dup"),
)

CONVERTER = Family(
    table="ibr_con",
    min_columns=8,
    key="number",
    key_label="converter",
    params=(
        Param("number", "code", 1, integer=True, doc="converter number"),
        Param("bus", "code", 2, integer=True, doc="bus number"),
        Param(
            "type",
            "code",
            3,
            integer=True,
            choices=(PVD1, ESD1, REGCA1),
            label="converter type",
            doc="1 PVD1 (ANDES distributed PV), 2 ESD1 (PVD1 with a state of charge), "
            "3 REGCA1 (WECC renewable generator/converter, constant current commands)",
        ),
        Param("mva", "MVA", 4, default=100.0, lo=0.0, doc="device base Sn"),
        Param("pfrac", "", 5, default=1.0, doc="fraction of the bus generation P (ANDES gammap)"),
        Param("qfrac", "", 6, default=1.0, doc="fraction of the bus generation Q (ANDES gammaq)"),
        Param(
            "xc",
            col=7,
            lo=0.0,
            doc="coupling reactance of the Q-droop's compensated voltage (device base)",
            **_DEV_PU,
        ),
        Param(
            "pqflag",
            "code",
            8,
            choices=(0.0, 1.0),
            doc="current-limit priority: 0 reactive (Q), 1 active (P)",
        ),
        Param("qmx", col=9, default=0.33, doc="maximum reactive power command", **_DEV_PU),
        Param("qmn", col=10, default=-0.33, doc="minimum reactive power command", **_DEV_PU),
        Param(
            "pmx",
            col=11,
            default=9999.0,
            doc="maximum active power command (ESD1: -pmx the minimum)",
            **_DEV_PU,
        ),
        Param("v0", "pu", 12, default=0.8, doc="lower voltage of the Q-droop deadband"),
        Param("v1", "pu", 13, default=1.1, doc="upper voltage of the Q-droop deadband"),
        Param("dqdv", col=14, default=-1.0, doc="Q-V droop (< 0), pu Q per pu V", **_DEV_PU),
        Param("fdbd", "Hz", 15, default=-0.017, hi=0.0, doc="frequency deadband (<= 0)"),
        Param(
            "ddn",
            "pu/Hz",
            16,
            lo=0.0,
            doc="P droop gain beyond the deadband, pu (device base) per Hz",
        ),
        Param("ialim", col=17, default=1.3, lo=0.0, doc="apparent current limit", **_DEV_PU),
        *(
            Param(f"vt{k}", "pu", 18 + k, default=d, lo=0.0, doc=f"voltage trip curve point {k}")
            for k, d in enumerate((0.88, 0.90, 1.1, 1.2))
        ),
        *(
            Param(f"ft{k}", "Hz", 22 + k, default=d, lo=0.0, doc=f"frequency trip curve point {k}")
            for k, d in enumerate((59.5, 59.7, 60.3, 60.5))
        ),
        Param("tip", "s", 26, default=0.02, lo=0.0, doc="active current lag time constant"),
        Param("tiq", "s", 27, default=0.02, lo=0.0, doc="reactive current lag time constant"),
        Param(
            "recflag",
            "code",
            28,
            default=1.0,
            choices=(0.0, 1.0),
            doc="1 the currents times the voltage and frequency trip curves, 0 without",
        ),
        Param(
            "plim",
            "code",
            29,
            default=1.0,
            choices=(0.0, 1.0),
            doc="1 the power order limited to [0, pmx] (ESD1 [-pmx, pmx]), 0 not (ANDES plim)",
        ),
        Param(
            "Tfm",
            "s",
            30,
            default=0.02,
            lo=0.0,
            doc="frequency measurement: angle filter time constant (ANDES BusFreq Tf)",
        ),
        Param(
            "Twm",
            "s",
            31,
            default=0.1,
            lo=0.0,
            doc="frequency measurement: washout time constant (ANDES BusFreq Tw, > 0)",
        ),
        Param(
            "Tf",
            "s",
            32,
            default=1.0,
            doc="ESD1, REGCA1 battery: state-of-charge integrator time constant",
        ),
        Param("SOCmin", "", 33, doc="ESD1, REGCA1 battery: minimum state of charge"),
        Param("SOCmax", "", 34, default=1.0, doc="ESD1, REGCA1 battery: maximum state of charge"),
        Param("SOCinit", "", 35, default=0.5, doc="ESD1, REGCA1 battery: initial state of charge"),
        Param(
            "En",
            "MWh",
            36,
            default=100.0,
            doc="ESD1, REGCA1 battery (``storage`` 1): rated energy (battery: 0 none, no state of "
            "charge)",
        ),
        Param("EtaC", "", 37, default=1.0, doc="ESD1, REGCA1 battery: charging efficiency"),
        Param("EtaD", "", 38, default=1.0, doc="ESD1, REGCA1 battery: discharging efficiency"),
        Param("Tg", "s", 39, default=0.1, lo=0.0, doc="REGCA1: converter time constant"),
        Param(
            "Rrpwr",
            "pu",
            40,
            default=10.0,
            lo=0.0,
            doc="REGCA1: LVPL rate limit of Tg dIp/dt (system base, as ANDES: not converted)",
        ),
        Param("Brkpt", "pu", 41, default=1.0, doc="REGCA1: LVPL breakpoint voltage"),
        Param("Zerox", "pu", 42, default=0.5, doc="REGCA1: LVPL zero-crossing voltage"),
        Param(
            "Lvplsw",
            "code",
            43,
            default=1.0,
            choices=(0.0, 1.0),
            doc="REGCA1: low-voltage power logic 1 on, 0 off",
        ),
        Param("Lvpl1", "pu", 44, default=1.0, doc="REGCA1: LVPL current limit at Brkpt"),
        Param("Volim", "pu", 45, default=1.2, doc="REGCA1: voltage of high-voltage Iq management"),
        Param("Lvpnt1", "pu", 46, default=0.8, doc="REGCA1: upper voltage of the Ip gain LVG"),
        Param("Lvpnt0", "pu", 47, default=0.4, doc="REGCA1: lower voltage of the Ip gain LVG"),
        Param(
            "Iolim",
            col=48,
            default=-1.5,
            doc="REGCA1: lower limit of the output Iq (high-voltage management)",
            **_DEV_PU,
        ),
        Param("Tfltr", "s", 49, default=0.1, lo=0.0, doc="REGCA1: LVPL voltage filter"),
        Param("Khv", "", 50, default=0.7, lo=0.0, doc="REGCA1: over-voltage Iq gain"),
        Param("Iqrmax", col=51, default=1.0, doc="REGCA1: upper rate of Tg dIq/dt", **_DEV_PU),
        Param("Iqrmin", col=52, default=-1.0, doc="REGCA1: lower rate of Tg dIq/dt", **_DEV_PU),
        Param(
            "reec",
            "code",
            53,
            choices=(NO_REEC, REECA1, REECB1),
            doc="REGCA1's electrical control: 0 none (constant current commands), 1 REECA1, "
            "2 REECB1",
        ),
        *_REECA1_PARAMS,
        Param(
            "repc",
            "code",
            105,
            choices=(NO_REPC, REPCA1),
            doc="REECA1's plant control: 0 none (constant references), 1 REPCA1",
        ),
        *_REPCA1_PARAMS,
        Param(
            "storage",
            "code",
            144,
            choices=(0.0, 1.0),
            doc="REECA1's active current range: 0 [0, Ipmax] (a generator, ANDES), "
            "1 [-Ipmax, Ipmax] (a battery, WECC REEC_C)",
        ),
        Param(
            "wind",
            "code",
            145,
            choices=(NO_WIND, WTDTA1, WTDS),
            doc="REECA1's wind turbine (ANDES RenGovernor): 0 none, 1 WTDTA1 (two-mass drive "
            "train), 2 WTDS (one mass); with WTARA1, WTPTA1, WTTQA1 (``aero``, ``pitch``, "
            "``torque``)",
        ),
        *_WIND_PARAMS,
        Param(
            "pll",
            "code",
            183,
            choices=(NO_PLL, PLL1),
            doc="REGCA1's angle: 0 its bus's, 1 a PLL1's (ANDES REGCP1 with a PLL1: its "
            "currents and the electrical control's voltage in the PLL's frame)",
        ),
        *_PLL_PARAMS,
        Param(
            "relay",
            "code",
            188,
            choices=(NO_RELAY, DGPRCT1, DGPRCTEXT),
            doc="a PVD1's or ESD1's DG protection: 0 none, 1 ANDES's DGPRCT1 (on its bus "
            "voltage), 2 DGPRCTExt (the voltage held at its initial value); it ceases the "
            "output while it trips (docs/ibr.md)",
        ),
        *_RELAY_PARAMS,
    ),
    dyr=(
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
        #: REEC_A: ICONs IREG (0: own bus), PFFLAG, VFLAG, QFLAG, PFLAG, PQFLAG; 45 CONs
        DyrModel(
            "REECA1",
            _REECA1_DYR,
            _reec_copies(_REECA1_DYR),
        ),
        #: REEC_B: ICONs IREG (0: own bus), PFFLAG, VFLAG, QFLAG, PQFLAG; 25 CONs
        DyrModel("REECB1", _REEC_ICONS + _REEC_CONS, _reec_copies(_REEC_ICONS + _REEC_CONS)),
        #: REPC_A: ICONs IREG (0: own bus), the monitored branch's from and to buses and
        #: circuit id (a string, NaN among the numbers), VCFlag, RefFlag, Fflag; 27 CONs
        DyrModel(
            "REPCA1",
            ("IREG", "BUS1", "BUS2", "CKTID", "VCFlag", "RefFlag", "Fflag") + tuple(_REPC_CONS),
            {f"pc_{n}": n for n in ("VCFlag", "RefFlag", "Fflag", *_REPC_CONS)},
        ),
        DyrModel(
            "WTDTA1",
            ("H", "DAMP", "Htfrac", "Freq1", "Dshaft"),
            {f"wt_{n}": n for n in ("H", "DAMP", "Htfrac", "Freq1", "Dshaft")},
        ),
        DyrModel("WTARA1", ("Ka", "Theta0"), {"wa_Ka": "Ka", "wa_theta0": "Theta0"}),
        DyrModel(
            "WTPTA1",
            ("Kiw", "Kpw", "Kic", "Kpc", "Kcc", "Tp", "TetaMax", "TetaMin", "RTetaMax", "RTetaMin"),
            {f"wp_{n}": n for n in ("Kiw", "Kpw", "Kic", "Kpc", "Kcc", "Tp")}
            | {"wp_thmax": "TetaMax", "wp_thmin": "TetaMin"}
            | {"wp_dthmax": "RTetaMax", "wp_dthmin": "RTetaMin"},
        ),
        #: WTTQ_A: ICON Tflag, then 15 CONs (TRATE: the turbine's MW rating, 0 its MBASE)
        DyrModel(
            "WTTQA1",
            ("Tflag", "Kpp", "Kip", "Tp", "Twref", "Temax", "Temin")
            + tuple(f"{v}{j}" for j in range(1, 5) for v in ("p", "spd"))
            + ("TRATE",),
            {f"wq_{n}": n for n in ("Tflag", "Kpp", "Kip", "Tp", "Twref", "Temax", "Temin")}
            | {f"wq_p{j}": f"p{j}" for j in range(1, 5)}
            | {f"wq_sp{j}": f"spd{j}" for j in range(1, 5)}
            | {"wq_Tn": "TRATE"},
        ),
    ),
)

__all__ = [
    "PVD1",
    "ESD1",
    "REGCA1",
    "NO_WIND",
    "WTDTA1",
    "WTDS",
    "NO_RELAY",
    "DGPRCT1",
    "DGPRCTEXT",
    "N_STATES",
    "STATE_NAMES",
    "ConverterParams",
    "converter_params",
    "initialise",
    "drawn_current",
    "derivatives",
    "commands",
    "derivatives_at",
    "at_power_flow",
]

#: REECA1's slots (a REGCA1 with ``reec`` 1): its states, then its memory (`MEMORY_SLOTS`)
REECA1_SLOTS = (
    *("Vt_filter", "Pe_filter", "PIQ", "Iq_filter", "Pref_filter", "Pord", "PIV"),
    *("Iqinj_timer", "Ipmax_timer", "Ipmax_held", "PIQ_held", "PIV_held", "Ipcmd_last"),
)
#: REPCA1's slots (``repc`` 1): its states, then its memory (the held error, and the plant
#: P reference's increment a storage controller commands, written by the simulator:
#: `stabctl.storage.devices`, ANDES's Plant_pref - Pline0)
REPCA1_SLOTS = (
    *("Vc_filter", "Qline_filter", "PI_plant", "LeadLag_plant"),
    *("f_lag_plant", "f_washout_plant", "Pline_filter", "PI_P_plant", "Pext_lag", "e_held"),
    "Plant_pref_command",
)
#: the wind turbine's slots (``wind`` 1 or 2): the drive train's turbine and generator
#: speeds and shaft torque (WTDS: its one speed in ``wt``), WTTQA1's Pe filter, speed
#: reference and PI, WTPTA1's two PIs and pitch angle (deg)
WIND_SLOTS = (
    *("wt", "wg", "Tshaft", "Pe_filter_tq", "wref_tq", "PI_tq"),
    *("PIc_pitch", "PIw_pitch", "theta_pitch"),
)
#: the PLL1's slots (``pll`` 1; ANDES measurement/pll.py): the filtered bus angle, the PI's
#: integrator, the estimated angle and the measured angle (rad)
PLL_SLOTS = ("af_pll", "PI_pll", "ae_pll", "am_pll")
# numpy scalars: a kernel's argument is then typed once (not as a literal per value)
_F_LAG, _F_WASHOUT = np.int64(2), np.int64(3)  # PVD1's, ESD1's frequency measurement
_VT, _PE, _PIQ, _S4, _PFILT, _PORD, _PIV = (np.int64(j) for j in range(5, 12))
_T_IQ, _T_IP, _IPMAX_H, _PIQ_H, _PIV_H, _IPCMD = (np.int64(j) for j in range(12, 18))
_PC_V, _PC_Q, _PC_PI, _PC_LL = (np.int64(j) for j in range(18, 22))
_PC_FL, _PC_FW, _PC_P, _PC_PIP, _PC_PEXT, _PC_E_H = (np.int64(j) for j in range(22, 28))
#: the plant P reference's commanded increment (pu, system base, injection +)
PLANT_PREF_SLOT = np.int64(28)
_WT, _WG, _TSH, _TQ_PE, _TQ_WREF, _TQ_PI = (np.int64(j) for j in range(29, 35))
_PT_C, _PT_W, _PT_TH = (np.int64(j) for j in range(35, 38))
_PLL_AF, _PLL_PI, _PLL_AE, _PLL_AM = (np.int64(j) for j in range(38, 42))
N_STATES = 5 + len(REECA1_SLOTS) + len(REPCA1_SLOTS) + len(WIND_SLOTS) + len(PLL_SLOTS)
#: state names per converter type (slots beyond a type's names, or that a device does not
#: use, `has_state`, are unused, 0)
#: a PVD1's or ESD1's DG protection (``relay``; ANDES DGPRCT1): its nine timers
#: (IntegratorAntiWindup IAWfl1 ... IAWVu2), the reset extension (ExtendedEvent ``res``) and
#: the trip flag (``lock``) in slots 5-15, the memory of its discrete logic (`_protection`)
RELAY_SLOTS = (
    *("fl1_timer", "fl2_timer", "fu1_timer", "fu2_timer"),
    *("vl1_timer", "vl2_timer", "vl3_timer", "vu1_timer", "vu2_timer"),
    *("reset_timer", "trip"),
)
_PR_T, _PR_RES, _PR_LOCK = np.int64(5), np.int64(14), np.int64(15)
STATE_NAMES = {
    PVD1: ("Ip", "Iq", "f_lag", "f_washout", "SOC", *RELAY_SLOTS),
    ESD1: ("Ip", "Iq", "f_lag", "f_washout", "SOC", *RELAY_SLOTS),
    REGCA1: (
        *("Ip", "Iq", "V_filter", "", "SOC"),
        *(*REECA1_SLOTS, *REPCA1_SLOTS, *WIND_SLOTS, *PLL_SLOTS),
    ),
}
#: slots that are not states but the memory of REECA1's discrete logic, written in place by
#: the kernel (ANDES's ExtendedEvent timers, its VarHold of Ipmax, the frozen PI outputs):
#: at rest they do not move; the linearisation leaves them out (`has_state`)
MEMORY_SLOTS = [*range(int(_T_IQ), int(_IPCMD) + 1), int(_PC_E_H), int(PLANT_PREF_SLOT)]
#: the slots that integrate energy (ESD1's and a battery's state of charge): at rest only
#: at zero output,
#: so the initial-point check leaves them out (unused, 0, in the other types)
ENERGY_SLOTS = [STATE_NAMES[ESD1].index("SOC")]
#: the ibr_con fields the kernels take as given (pu quantities after the base change)
TABLE_FIELDS = tuple(n for n in CONVERTER.names if n not in ("number", "bus", "mva"))
#: REECA1's lag time constants (each must be >= LBND; its Iq filter is ``tiq``); its Pe
#: filter Tp may also be 0, no filter (PSS/E's reading of Tp = 0)
REECA1_LAGS = ("Trv", "tiq", "Tpfilt", "Tpord")
#: REPCA1's (its lead time constant pc_Tft may be 0)
REPCA1_LAGS = ("pc_Tfltr", "pc_Tfv", "pc_Tp", "pc_Tg", "Twm")
#: fields on the device base: powers and currents (times Sn/Sb), the reactance (Sb/Sn)
POWER_FIELDS = (
    *("qmx", "qmn", "pmx", "dqdv", "ddn", "ialim", "Iolim", "Iqrmax", "Iqrmin"),
    *("QMax", "QMin", "dPmax", "dPmin", "PMAX", "PMIN", "Imax", "pc_Pmax", "pc_Pmin"),
    *(f"{a}{j}" for a in ("Iq", "Ip") for j in range(1, 5)),
    *("wt_H", "wt_DAMP", "wt_Dshaft"),
)
#: the torque control's fields on its turbine's base (``wq_Tn``, else the device's)
TORQUE_POWER_FIELDS = ("wq_Temax", "wq_Temin", *(f"wq_p{j}" for j in range(1, 5)))
#: the lag time constants of the models switched on by a code (wind models, PLL): (code,
#: its lags), each >= LBND where the model is on
SWITCHED_LAGS = (
    ("torque", ("wq_Tp", "wq_Twref")),
    ("pitch", ("wp_Tp",)),
    ("pll", ("pll_Tf", "pll_Tp")),
)
#: packed parameter matrix of the kernels, (column name, ConverterParams attribute)
PACKED = (
    ("POS", "pos"),
    *((n.upper(), n) for n in TABLE_FIELDS),
    ("PMN", "pmn"),
    ("P0", "P0"),
    ("Q0", "Q0"),
    ("COS_A0", "cos_a0"),
    ("SIN_A0", "sin_a0"),
    ("VQU", "Vqu"),
    ("VQL", "Vql"),
    ("KSOC", "Ksoc"),
    ("FN", "fn"),
    ("IPCMD0", "Ipcmd0"),
    ("IQCMD0", "Iqcmd0"),
    ("KLVG", "kLVG"),
    ("KLVPL", "kLVPL"),
    ("VREF0R", "Vref0r"),
    ("QREF", "Qref"),
    ("TANPF", "tanpf"),
    ("IPOFF", "Ipoff"),
    ("IMAXR", "Imaxr"),
    ("ZVDL1", "zVDL1"),
    ("ZVDL2", "zVDL2"),
    ("POS1", "pos1"),
    ("POS2", "pos2"),
    ("ISIGN", "isign"),
    ("PC_VREF0", "pc_Vref0"),
    ("PC_QLINE0", "pc_Qline0"),
    ("PC_PLINE0", "pc_Pline0"),
    ("PR_V0", "pr_v0"),
)
#: the kernels' column of each PACKED name: P[k, C.IALIM]
C = layout("ConverterColumns", PACKED)


@params_class(("pos", "bus_idx"), TABLE_FIELDS)
class ConverterParams(Declared):
    """Converter data on the system base, arrays of shape (n_ibr,): ``pos`` the device
    bus's position among the kept buses (set by the dynamic model), ``bus_idx`` its bus
    row, the ibr_con fields :data:`TABLE_FIELDS` (powers, currents, ``dqdv``, ``ddn``
    times Sn/Sb, ``xc`` times Sb/Sn), and the initial point: P0, Q0 (pref0, qref0, pu),
    cos_a0, sin_a0 (initial bus angle), Vqu, Vql (Q-droop bounds, ANDES's ConstServices),
    pmn (lower power order: 0 PVD1, -pmx ESD1), Ksoc = Sb/(3600 En Tf) (1/s per pu),
    fn (Hz); REGCA1: the constant current commands Ipcmd0 = P0/(|V0| LVG(|V0|)), Iqcmd0 =
    -Q0/|V0| (ANDES's Ipcmd0_LVG, Iqcmd0), the gains kLVG = 1/(Lvpnt1 - Lvpnt0), kLVPL =
    Lvplsw Lvpl1/(Brkpt - Zerox) (0 for the other types); REECA1 or REECB1 (``reec``,
    ANDES reeca1.py, reecb1.py): Vref0r (Vref0, the initial |V| where 0), Qref = -qref0
    (its Q reference: Q0, or with a REECA1's QFLAG Vref1 - |V0|), tanpf = Q0/P0 (the
    power-factor reference, 0 where P0 = 0: Qcpf held at Q0), Ipoff = Ipcmd0 - P0/|V0|
    (the REGCA1's Ipcmd less the REECA1's, ANDES's two initial commands summed), Imaxr
    (Imax, 1e8 where <= 0), zVDL1, zVDL2 (1 where the VDL curve's points rise: the curve
    applies); REPCA1 (``repc``,
    ANDES repca1.py): the monitored line's end buses (rows bus1_idx, bus2_idx; the
    device's own bus without a line) and their positions pos1, pos2 among the kept buses
    (set by the dynamic model), isign (1 if the device's bus is bus1, else -1: the line
    current counted from it), and the initial compensated voltage pc_Vref0 (its voltage
    reference, ANDES Vref0), line Q pc_Qline0 and P pc_Pline0 (0 elsewhere); pr_v0 the
    initial |V| of the bus (the voltage a DGPRCTExt protection reads)."""

    pmn: np.ndarray
    P0: np.ndarray
    Q0: np.ndarray
    cos_a0: np.ndarray
    sin_a0: np.ndarray
    Vqu: np.ndarray
    Vql: np.ndarray
    Ksoc: np.ndarray
    fn: np.ndarray
    Ipcmd0: np.ndarray
    Iqcmd0: np.ndarray
    kLVG: np.ndarray
    kLVPL: np.ndarray
    Vref0r: np.ndarray
    Qref: np.ndarray
    tanpf: np.ndarray
    Ipoff: np.ndarray
    Imaxr: np.ndarray
    zVDL1: np.ndarray
    zVDL2: np.ndarray
    pos1: np.ndarray
    pos2: np.ndarray
    bus1_idx: np.ndarray
    bus2_idx: np.ndarray
    isign: np.ndarray
    pc_Vref0: np.ndarray
    pc_Qline0: np.ndarray
    pc_Pline0: np.ndarray
    pr_v0: np.ndarray

    @property
    def n(self) -> int:
        return self.bus_idx.size

    def packed(self) -> np.ndarray:
        """Parameter matrix (n_ibr, len(PACKED)) for the compiled kernels."""
        return pack(self, PACKED)

    def time_constants(self):
        """(label, values, mask) of every time constant that sets a state's speed."""
        esd = self.type == ESD1
        pvd = self.type != REGCA1
        reg = ~pvd
        ree = self.reec != NO_REEC
        return (
            ("ibr_con tip", self.tip, pvd),
            ("ibr_con tiq", self.tiq, pvd | ree),
            ("ibr_con Tfm", self.Tfm, (pvd | (self.repc == REPCA1)) & (self.Tfm >= LBND)),
            ("ibr_con Twm", self.Twm, pvd),
            ("ibr_con Tf", self.Tf, esd),
            ("ibr_con Tg", self.Tg, reg),
            ("ibr_con Tfltr", self.Tfltr, reg),
            *((f"ibr_con {n}", getattr(self, n), ree) for n in REECA1_LAGS),
            ("ibr_con Tp", self.Tp, ree & (self.Tp >= LBND)),
            *((f"ibr_con {n}", getattr(self, n), self.repc == REPCA1) for n in REPCA1_LAGS),
            *(
                (f"ibr_con {n}", getattr(self, n), getattr(self, flag) == 1)
                for flag, names in SWITCHED_LAGS
                for n in names
            ),
        )

    @property
    def is_battery(self):
        """REGCA1 batteries with a state of charge (``storage`` 1, finite En; WECC
        REEC_C)."""
        return (self.type == REGCA1) & (self.storage == 1) & (self.Ksoc > 0)

    def has_state(self) -> np.ndarray:
        """Boolean (N_STATES, n_ibr): the slots that are states of each device."""
        act = np.ones((N_STATES, self.n), bool)
        reg = self.type == REGCA1
        act[2] = reg | (self.Tfm >= LBND)
        act[3] = ~reg
        act[4] = (self.type == ESD1) | self.is_battery
        # REECA1's slots; a PVD1's protection in the same slots is discrete logic, at rest
        # at 0: no state of the linear model
        act[5:_PC_V] = self.reec != NO_REEC
        act[_PE] &= self.Tp >= LBND  # Tp 0: no Pe filter
        act[_PIQ] &= (self.VFLAG == 1) & (self.QFLAG == 1)  # else out of the Iq path
        act[_PC_V:] = self.repc == REPCA1
        act[_PC_FL] &= self.Tfm >= LBND
        act[_WT:] = False
        wind = self.wind != NO_WIND
        act[_WT] = wind
        act[_WG] = act[_TSH] = self.wind == WTDTA1
        act[_TQ_PE : _TQ_PI + 1] = self.torque == 1
        act[_PT_C : _PT_TH + 1] = self.pitch == 1
        act[_PLL_AF : _PLL_AM + 1] = self.pll == PLL1
        act[MEMORY_SLOTS] = False
        return act


check_packed(ConverterParams, PACKED)


def converter_params(case: Case, V0=None, S_gen=None) -> ConverterParams:
    """Converter parameters on the system base, with the initial point of the power flow.

    Parameters
    ----------
    case : Case
        The case (its ``converters`` table).
    V0 : ndarray of complex, shape (n_bus,), optional
        Power-flow bus voltages, pu; None: the bus table's (flat) values.
    S_gen : ndarray of complex, shape (n_bus,), optional
        Power-flow bus generation, pu; None: the bus table's.

    Returns
    -------
    ConverterParams
        With ``pos`` -1 (set by the dynamic model).

    Raises
    ------
    CaseError
        A lag time constant tip, tiq (PVD1, ESD1), Tg, Tfltr (REGCA1) or REECA1's
        (:data:`REECA1_LAGS`; its Tp other than 0, no filter) below 1e-3 s (the current
        would be an algebraic function of the voltage inside the network solution); an
        electrical control ``reec`` on a device other than a REGCA1; naming the row and
        field.
    """
    t = case.converters
    n = len(t)
    reg = t.type == REGCA1
    ree = t.reec != NO_REEC
    bad = np.flatnonzero(ree & ~reg)
    if bad.size:
        t._fail(bad[0], "reec", "an electrical control drives a REGCA1 (type 3) only")
    bad = np.flatnonzero((t.pll != NO_PLL) & ~reg)
    if bad.size:
        t._fail(bad[0], "pll", "a PLL gives the angle of a REGCA1 (type 3) only")
    bad = np.flatnonzero((t.relay != NO_RELAY) & reg)
    if bad.size:
        t._fail(bad[0], "relay", "a DG protection trips a PVD1 or ESD1 (types 1, 2) only")
    lags = [("tip", ~reg), ("tiq", ~reg), ("Tg", reg), ("Tfltr", reg)]
    pc = t.repc == REPCA1
    bad = np.flatnonzero(pc & ~ree)
    if bad.size:
        t._fail(bad[0], "repc", "a plant control drives an electrical control (reec 1, 2) only")
    lags += [(name, ree) for name in REECA1_LAGS] + [(name, pc) for name in REPCA1_LAGS]
    lags += [("Tp", ree & (t.Tp != 0))]  # REECA1's Pe filter: 0 none
    _check_wind(t, t.reec == REECA1)
    lags += [(n, getattr(t, flag) == 1) for flag, names in SWITCHED_LAGS for n in names]
    for name, sel in lags:
        bad = np.flatnonzero(sel & (getattr(t, name) < LBND))
        if bad.size:
            t._fail(bad[0], name, f"must be >= {LBND:g} s (a lag of the converter)")
    b = case.buses
    if V0 is None:
        V0 = b.vmag * np.exp(1j * np.deg2rad(b.vang_deg))
    if S_gen is None:
        S_gen = b.pgen + 1j * b.qgen
    idx = case.bus_indices(t.bus) if n else np.zeros(0, int)
    scale = t.mva / case.base_mva
    vals = {name: getattr(t, name).copy() for name in TABLE_FIELDS}
    for name in POWER_FIELDS:
        vals[name] = vals[name] * scale
    vals["xc"] = vals["xc"] / scale
    for name in TORQUE_POWER_FIELDS:
        vals[name] = vals[name] * np.where(t.wq_Tn > 0, t.wq_Tn, t.mva) / case.base_mva
    P0 = t.pfrac * S_gen[idx].real
    Q0 = t.qfrac * S_gen[idx].imag
    a0 = np.angle(V0[idx])
    v0 = np.abs(V0[idx])
    with np.errstate(divide="ignore", invalid="ignore"):
        kLVG = np.where(reg, 1.0 / (t.Lvpnt1 - t.Lvpnt0), 0.0)
        kLVPL = np.where(reg, t.Lvplsw * t.Lvpl1 / (t.Brkpt - t.Zerox), 0.0)
        # LVG at the initial voltage, as `_lvg`
        LVG0 = np.where(v0 <= t.Lvpnt0, 0.0, np.where(v0 <= t.Lvpnt1, (v0 - t.Lvpnt0) * kLVG, 1.0))
        # ANDES's Ipcmd at an initial LVG of 0 is 1 (regca1.py 202); refused by initialise
        Ipcmd0 = np.where(LVG0 > 0, P0 / v0 / np.where(LVG0 > 0, LVG0, 1.0), 1.0)
    with np.errstate(divide="ignore"):
        soc = (t.type == ESD1) | ((t.type == REGCA1) & (t.storage == 1) & (t.En > 0))
        Ksoc = np.where(soc, case.base_mva / 3600.0 / t.En / t.Tf, 0.0)
    cp = ConverterParams(
        pos=np.full(n, -1, np.int64),
        bus_idx=np.asarray(idx, np.int64),
        **vals,
        pmn=np.where(t.type == ESD1, -vals["pmx"], 0.0),
        P0=P0,
        Q0=Q0,
        cos_a0=np.cos(a0),
        sin_a0=np.sin(a0),
        Vqu=vals["v1"] - (Q0 - vals["qmn"]) / vals["dqdv"],
        Vql=vals["v0"] + (vals["qmx"] - Q0) / vals["dqdv"],
        Ksoc=Ksoc,
        fn=np.full(n, case.freq_hz),
        Ipcmd0=np.where(reg, Ipcmd0, 0.0),
        Iqcmd0=np.where(reg, -Q0 / v0, 0.0),
        kLVG=kLVG,
        kLVPL=kLVPL,
        **_reeca1_services(vals, t.reec, P0, Q0, v0, np.where(reg, Ipcmd0, 0.0)),
        **_repca1_services(case, idx),
        pr_v0=v0,
    )
    _repca1_references(cp, V0)
    _torque_limits(cp)
    return cp


def _check_wind(t, ree) -> None:
    """Refuse a wind turbine that its models cannot run: one without a REECA1 (``ree``
    the rows with one), a pitch control without the aerodynamics, a torque control
    without the pitch control (ANDES chains them: WTTQA1 -> WTPTA1 -> WTARA1 -> the drive
    train), a WTDTA1 whose inertia split Htfrac is not inside (0, 1) (WTDS is the one-mass
    train), an inertia H not above 0."""
    wind = t.wind != NO_WIND
    rules = (
        ("wind", wind & ~ree, "a wind turbine drives a REECA1 (reec 1) only"),
        ("aero", (t.aero == 1) & ~wind, "the aerodynamics need a drive train (wind 1 or 2)"),
        ("pitch", (t.pitch == 1) & (t.aero != 1), "a pitch control needs the aerodynamics"),
        ("torque", (t.torque == 1) & (t.pitch != 1), "a torque control needs the pitch control"),
        ("wt_H", wind & (t.wt_H <= 0), "must be > 0 (the drive train's inertia)"),
        (
            "wt_Htfrac",
            (t.wind == WTDTA1) & ((t.wt_Htfrac <= 0) | (t.wt_Htfrac >= 1)),
            "must lie inside (0, 1) for a two-mass WTDTA1 (WTDS: one mass)",
        ),
    )
    for field, bad, why in rules:
        rows = np.flatnonzero(bad)
        if rows.size:
            t._fail(rows[0], field, why)


def _torque_limits(cp: ConverterParams) -> None:
    """WTTQA1's upper torque limit raised, in place, to its PI's initial output P0/fPe(P0)
    where that lies above it, as ANDES does when a limiter starts beyond its upper limit
    (andes/core/discrete.py Limiter ``allow_adjust``, ``adjust_upper``; kundur_wtds.xlsx:
    7 pu through a 100 MVA turbine against Temax 1.2)."""
    P = cp.packed()
    for k in np.flatnonzero(cp.torque == 1):
        torque0 = cp.P0[k] / _speed_curve.py_func(P, k, cp.P0[k])
        cp.wq_Temax[k] = max(cp.wq_Temax[k], torque0)


def _repca1_services(case: Case, idx: np.ndarray) -> dict[str, np.ndarray]:
    """REPCA1's line services (`ConverterParams`) of the devices on bus rows idx; without
    a line (bus1 = bus2 = 0) both ends the device's bus (no line current, ANDES's no-line
    patch)."""
    t = case.converters
    pc = t.repc == REPCA1
    line = pc & (t.pc_bus1 > 0)
    b1 = np.where(line, case.bus_indices(np.where(line, t.pc_bus1, t.bus)), idx)
    b2 = np.where(line, case.bus_indices(np.where(line, t.pc_bus2, t.bus)), idx)
    bad = np.flatnonzero(line & (b1 != idx) & (b2 != idx))
    if bad.size:
        t._fail(bad[0], "pc_bus1", "the monitored line must end at the device's bus")
    return {
        "pos1": np.full(len(t), -1, np.int64),
        "pos2": np.full(len(t), -1, np.int64),
        "bus1_idx": np.asarray(b1, np.int64),
        "bus2_idx": np.asarray(b2, np.int64),
        "isign": np.where(b1 == idx, 1.0, -1.0),
        "pc_Vref0": np.zeros(len(t)),  # `_repca1_references`
        "pc_Qline0": np.zeros(len(t)),
        "pc_Pline0": np.zeros(len(t)),
    }


def _repca1_references(cp: ConverterParams, V0: np.ndarray) -> None:
    """REPCA1's initial references in place: pc_Vref0 the selected voltage VCsel,
    pc_Qline0 and pc_Pline0 the line's Q and P at the power-flow voltages V0 (n_bus,)
    (`line_measures`)."""
    P = cp.packed()
    for k in np.flatnonzero(cp.repc == REPCA1):
        ends = (V0[cp.bus_idx[k]], V0[cp.bus1_idx[k]], V0[cp.bus2_idx[k]])
        cp.pc_Vref0[k], Sline = line_measures(P, k, *ends)
        cp.pc_Qline0[k], cp.pc_Pline0[k] = Sline.imag, Sline.real


def _reeca1_services(vals: dict, reec, P0, Q0, v0, Ipcmd0) -> dict[str, np.ndarray]:
    """REECA1's and REECB1's initial services (ANDES reeca1.py, reecb1.py ConstServices;
    `ConverterParams`) from the system-base fields ``vals``, for the rows with an
    electrical control ``reec`` (0 elsewhere)."""

    def rising(a: str, b: str):
        pts = [vals[f"{c}{j}"] for c in (a, b) for j in (1, 2, 3)]
        nxt = [vals[f"{c}{j}"] for c in (a, b) for j in (2, 3, 4)]
        return np.all(np.array(pts) <= np.array(nxt), axis=0)

    # qref0 (reeca1.py 412): QFLAG (v - Vref1), else Iqcmd0 vp (vp = v above 0.01 pu);
    # REECB1's -Q0 (reecb1.py 304)
    vp0 = np.where(v0 <= 0.01, 0.01, v0)
    qref0 = np.where(vals["QFLAG"] == 1, v0 - vals["Vref1"], -Q0 / v0 * vp0)
    qref0 = np.where(reec == REECB1, -Q0, qref0)
    with np.errstate(divide="ignore", invalid="ignore"):
        tanpf = np.where(P0 != 0, Q0 / np.where(P0 != 0, P0, 1.0), 0.0)
    on = {
        "Vref0r": np.where(vals["Vref0"] == 0, v0, vals["Vref0"]),
        "Qref": -qref0,
        "tanpf": tanpf,
        "Ipoff": Ipcmd0 - P0 / v0,
        "Imaxr": np.where(vals["Imax"] <= 0, 1e8, vals["Imax"]),
        "zVDL1": rising("Vq", "Iq").astype(float),
        "zVDL2": rising("Vp", "Ip").astype(float),
    }
    return {name: np.where(reec != NO_REEC, value, 0.0) for name, value in on.items()}


# -- compiled kernels ----------------------------------------------------------------------


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
    on = (P[:, C.TYPE] == REGCA1) & (np.abs(v0 - P[:, C.LVPNT1]) <= ON_BREAKPOINT)
    out = P.copy()
    out[on, C.LVPNT1] = v0[on] - BREAKPOINT_SHIFT
    return out, np.nonzero(on)[0]


@kernel
def _regca1_currents(P, x, k, v):
    """REGCA1's output currents (Ipout, Iqout) of device k at voltage magnitude v (ANDES
    regca1.py 258-278): Ipout = Ip LVG(v); Iqout = Iq - HVG, HVG = Khv (v - Volim) at or
    above 0 (GainLimiter, lower 0), Iqout held at Iolim at or below it."""
    Ipout = x[0, k] * _lvg(v, P[k, C.LVPNT0], P[k, C.LVPNT1], P[k, C.KLVG])
    HVG = P[k, C.KHV] * (v - P[k, C.VOLIM])
    if HVG <= 0.0:
        HVG = 0.0
    Iqout = x[1, k] - HVG
    if Iqout <= P[k, C.IOLIM]:
        Iqout = P[k, C.IOLIM]
    return Ipout, Iqout


@kernel
def _ipcmd(P, x, k):
    """REGCA1 k's active current command: Ipcmd0, or with a REECA1 its last command
    (slot ``Ipcmd_last``, ANDES's algebraic Ipcmd of the previous iterate, which its
    anti-windup check reads before the network solution)."""
    if P[k, C.REEC] != NO_REEC:
        return x[_IPCMD, k]
    return P[k, C.IPCMD0]


@kernel
def _regca1_ip_limits(P, x, k):
    """REGCA1's Ip lag S0 (ANDES regca1.py 238-256) at the states x: the LVPL upper limit
    (Piecewise, 242-249) of the filtered voltage S2 (x[2]) and the equation value e =
    Ipcmd - Ip after the rate limit Rrpwr (ANDES compares the right-hand side Tg dIp/dt,
    not dIp/dt: andes/core/discrete.py RateLimiter.check_eq)."""
    S2 = x[2, k]
    sw = P[k, C.LVPLSW]
    if S2 <= P[k, C.ZEROX]:
        LVPL = 9999.0 * (1.0 - sw)
    elif S2 <= P[k, C.BRKPT]:
        LVPL = (S2 - P[k, C.ZEROX]) * P[k, C.KLVPL] + 9999.0 * (1.0 - sw)
    else:
        LVPL = 9999.0
    e = _ipcmd(P, x, k) - x[0, k]
    if e > P[k, C.RRPWR]:
        e = P[k, C.RRPWR]
    return LVPL, e


@kernel
def _at_lvpl(P, x, k, reach):
    """Whether REGCA1 k's Ip is held on its LVPL limit: at or above it with a
    non-negative e, or driven into it within `reach` s (`blocks.nonwindup`'s rule for a
    moving limit: the LVPL rises with the filtered voltage after a dip, and a state left
    a hair below it at each step would alternate between the full derivative and 0).
    Returns (held, LVPL, e)."""
    LVPL, e = _regca1_ip_limits(P, x, k)
    held = e >= 0.0 and x[0, k] + reach * e / P[k, C.TG] >= LVPL
    return held, LVPL, e


@kernel
def clamp_states(P, x, k, reach):
    """Clamp device k's limited states in place before the network solution, as ANDES's
    AntiWindup does within its iteration (andes/core/discrete.py AntiWindup.check_eq):
    REGCA1's Ip at its LVPL limit when held there (`_at_lvpl`; reach 0: at or above it
    with a non-negative e).  Other types: nothing."""
    if P[k, C.TYPE] == REGCA1:
        held, LVPL, _ = _at_lvpl(P, x, k, reach)
        if held:
            x[0, k] = LVPL


@kernel
def _regca1_derivatives(P, x, k, v, Iq_target, reach, dx):
    """REGCA1's state derivatives of device k at voltage magnitude v (ANDES regca1.py
    219-256) toward its commands (`_ipcmd`, Iq_target = -Iqcmd), slots 0-4 of column k
    of dx (the Ip state clamped first, `clamp_states` with `reach`)."""
    _, dx[2, k] = lag(v, x[2, k], P[k, C.TFLTR])
    # S0: Ip lag with the rate limit, then the anti-windup upper limit LVPL
    clamp_states(P, x, k, reach)
    held, _, e = _at_lvpl(P, x, k, reach)
    if held:
        e = 0.0
    Tg = P[k, C.TG]
    dx[0, k] = e / Tg
    # S1: Iq lag (gain -1 on Iqcmd), rate limits enabled by the sign of Q0
    e = Iq_target - x[1, k]
    if P[k, C.Q0] < 0.0 and e < P[k, C.IQRMIN]:
        e = P[k, C.IQRMIN]
    if P[k, C.Q0] > 0.0 and e > P[k, C.IQRMAX]:
        e = P[k, C.IQRMAX]
    dx[1, k] = e / Tg
    dx[3, k] = 0.0
    dx[4, k] = 0.0


@kernel
def _timer(x, dx, slot, k, on, t_ext):
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
def _frozen_pi(P, x, k, u, gains, lo, hi, frz, dx):
    """ANDES's PITrackAWFreeze of device k: ys = kp u + xi, y = clip(ys, lo, hi), dxi/dt
    = ki (u - ks (ys - y)); frozen (frz 1) the output held and the integrator stopped.
    ``gains`` the columns (kp, ki, ks, state slot, held slot); returns y."""
    kp, ki, ks = P[k, gains[0]], P[k, gains[1]], P[k, gains[2]]
    slot, held = gains[3], gains[4]
    if frz:
        dx[slot, k] = 0.0
        return x[held, k]
    ys = kp * u + x[slot, k]
    y = clip(ys, lo, hi)
    dx[slot, k] = ki * (u - ks * (ys - y))
    x[held, k] = y
    return y


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


#: REECA1's VDL curves as (flag column, first point column), numpy scalars
_VDL1 = (np.int64(C.ZVDL1), np.int64(C.VQ1))
_VDL2 = (np.int64(C.ZVDL2), np.int64(C.VP1))


@kernel
def _vdl_limit(P, k, curve, u):
    """REECA1's VDL limit of device k at filtered voltage u: min(VDL(u), Imaxr) (`_vdl`,
    columns c) if the curve's points rise (flag column z), else 1e8 (ANDES Iqmax1,
    Ipmax1); curve = (z, c), `_VDL1` or `_VDL2`.  A REECB1 has no curves: Imaxr (ANDES
    reecb1.py Ipmax, Iqmax)."""
    z, c = curve
    if P[k, C.REEC] == REECB1:
        return P[k, C.IMAXR]
    if P[k, z] == 0.0:
        return 1e8
    return min(_vdl(P, k, c, u), P[k, C.IMAXR])


@kernel
def _room(P, k, other):
    """The current room sqrt(max(Imax^2 - other^2, 0)) the other command leaves (a
    REECB1's Imaxr: ANDES reecb1.py Ipmax2sq, Iqmax2sq)."""
    Imax = P[k, C.IMAXR] if P[k, C.REEC] == REECB1 else P[k, C.IMAX]
    return np.sqrt(max(Imax**2 - other**2, 0.0))


@kernel
def _iq_command(P, x, k, u, s4, Iqinj, Iqmax, frz, dx):
    """REECA1's reactive current command IqHL of device k: the V PI (`_frozen_pi`, input
    u, limits +-Iqmax) with QFLAG, else the filtered Q command s4, plus Iqinj, limited to
    +-Iqmax."""
    piv = _frozen_pi(P, x, k, u, (C.KVP, C.KVI, C.KVS, _PIV, _PIV_H), -Iqmax, Iqmax, frz, dx)
    Qsel = piv if P[k, C.QFLAG] == 1.0 else s4
    return clip(Qsel + Iqinj, -Iqmax, Iqmax)


@kernel
def _ip_command(P, x, k, Ip_order, Ipmax, hold):
    """REECA1's active current command IpHL = clip(Ip_order, 0, Ipmax) of device k (a
    battery, ``storage`` 1: clip(Ip_order, -Ipmax, Ipmax), WECC REEC_C, whose state of
    charge, with a finite En, stops discharging at SOCmin and charging at SOCmax), Ipmax
    held at its value before ``hold`` (1.0 for Thld2 s after a dip; ANDES VarHold
    Ipmaxh), tracked in place otherwise."""
    if hold:
        Ipmax = x[_IPMAX_H, k]
    else:
        x[_IPMAX_H, k] = Ipmax
    lo, hi = -P[k, C.STORAGE] * Ipmax, Ipmax
    if P[k, C.KSOC] > 0.0:
        if x[4, k] <= P[k, C.SOCMIN]:
            hi = 0.0
        if x[4, k] >= P[k, C.SOCMAX]:
            lo = 0.0
    return clip(Ip_order, lo, hi)


@kernel
def _p_order(P, x, k, Pref, wg, frz, dx):
    """REECA1's power order Pord of device k: the reference Pref through the rate-limited
    filter Tpfilt (ANDES LagRate, rates dPmin, dPmax on its right-hand side), times the
    speed wg with PFLAG (Psel), then the lag Tpord frozen in a dip with the anti-windup
    limits [PMIN, PMAX] (LagAWFreeze; the state reset to a limit in place)."""
    e = clip(Pref - x[_PFILT, k], P[k, C.DPMIN], P[k, C.DPMAX])
    dx[_PFILT, k] = e / P[k, C.TPFILT]
    Psel = wg * x[_PFILT, k] if P[k, C.PFLAG] == 1.0 else x[_PFILT, k]
    e = 0.0 if frz else Psel - x[_PORD, k]
    if x[_PORD, k] >= P[k, C.PMAX] and e >= 0.0:
        x[_PORD, k], e = P[k, C.PMAX], 0.0
    elif x[_PORD, k] <= P[k, C.PMIN] and e <= 0.0:
        x[_PORD, k], e = P[k, C.PMIN], 0.0
    dx[_PORD, k] = e / P[k, C.TPORD]
    return x[_PORD, k]


@kernel
def _iq_injection(P, k, vt, frz, extended):
    """REECA1's Iqinj of device k at filtered voltage vt: Kqv times the deadbanded error
    Vref0r - vt (DeadBand1, strict) in a dip; for |Thld| s after it (``extended``) the
    same (Thld < 0) or Iqfrz (Thld > 0); limited to [Iql1, Iqh1] (ANDES leaves the limits
    out).  A REECB1's at all times (its GainLimiter, no hold)."""
    err = P[k, C.VREF0R] - vt
    db = 0.0
    if err > P[k, C.DBD2]:
        db = err - P[k, C.DBD2]
    elif err < P[k, C.DBD1]:
        db = err - P[k, C.DBD1]
    Iqv = db * P[k, C.KQV]
    Iqinj = 0.0
    if frz or (extended and P[k, C.THLD] < 0.0) or P[k, C.REEC] == REECB1:
        Iqinj = Iqv
    elif extended and P[k, C.THLD] > 0.0:
        Iqinj = P[k, C.IQFRZ]
    return clip(Iqinj, P[k, C.IQL1], P[k, C.IQH1])


@kernel
def _reeca1(P, x, k, v, S, ref, wg, dx):
    """REECA1 (ANDES 2.0 reeca1.py; docs/ibr.md 6) driving REGCA1 k at voltage magnitude v
    with its injected power S = Pe + j Qe, its references ref = Pref + j Qext (Pref: P0,
    or its wind turbine's, plus its plant control's Pext; Qext the plant control's Q
    increment, 0 without one) and its speed wg (1 without a wind turbine): the
    derivatives of its slots written, its memory (`MEMORY_SLOTS`) updated in place;
    returns the commands (IpHL, IqHL), pu.  Frozen (Volt_dip) while v < Vdip or v > Vup
    (strict).  A REECB1 (ANDES reecb1.py) the same but: the V PI's input the selected
    Vsel (the Q PI's output with VFLAG, else 0), no VDL curves, Iqinj at all times, no
    holds (its Thld, Thld2 0) and no PFLAG (0)."""
    ext = ref - P[k, C.P0]
    frz = v < P[k, C.VDIP] or v > P[k, C.VUP]
    extended = _timer(x, dx, _T_IQ, k, frz, abs(P[k, C.THLD]))
    hold = _timer(x, dx, _T_IP, k, frz, P[k, C.THLD2])
    if frz:  # the Ipmax hold runs after the dip only (ExtendedEvent extend_only)
        hold = 0.0
    vt, dx[_VT, k] = lag(v, x[_VT, k], P[k, C.TRV])
    pe, dx[_PE, k] = lag(S.real, x[_PE, k], P[k, C.TP])  # Tp < LBND: no filter (PSS/E 0)
    vp = 0.01 if v <= 0.01 else v
    # reactive power reference: Q, or the power factor of the filtered Pe (Q0 at P0 = 0)
    PFsel = P[k, C.QREF] + ext.imag
    if P[k, C.PFFLAG] == 1.0:
        PFsel = pe * P[k, C.TANPF] if P[k, C.P0] != 0.0 else P[k, C.Q0]
    Qerr = clip(PFsel, P[k, C.QMIN], P[k, C.QMAX]) - S.imag
    vflag = P[k, C.VFLAG]
    lo, hi = P[k, C.VMIN], P[k, C.VMAX]
    piq = 0.0  # the Q PI drives Iq with VFLAG and QFLAG 1 only (ANDES's drifts unread)
    dx[_PIQ, k] = 0.0
    if vflag == 1.0 and P[k, C.QFLAG] == 1.0:
        piq = _frozen_pi(P, x, k, Qerr, (C.KQP, C.KQI, C.KQS, _PIQ, _PIQ_H), lo, hi, frz, dx)
    if P[k, C.REEC] == REECB1:
        u = P[k, C.QFLAG] * clip(vflag * piq, lo, hi)
    else:
        Vsel = clip(P[k, C.VREF1] + PFsel if vflag == 0.0 else piq, lo, hi)
        u = P[k, C.QFLAG] * (Vsel - vt * (1.0 - vflag))
    s4 = x[_S4, k]
    dx[_S4, k] = 0.0 if frz else (PFsel / vp - s4) / P[k, C.TIQ]
    Iqinj = _iq_injection(P, k, vt, frz, extended)
    Ip_order = _p_order(P, x, k, ref.real, wg, frz, dx) / vp
    if P[k, C.PQFLAG] == 0.0:  # Q priority
        Iqmax = _vdl_limit(P, k, _VDL1, vt)
        IqHL = _iq_command(P, x, k, u, s4, Iqinj, Iqmax, frz, dx)
        IpHL = _ip_command(P, x, k, Ip_order, _room(P, k, IqHL), hold)
    else:
        IpHL = _ip_command(P, x, k, Ip_order, _vdl_limit(P, k, _VDL2, vt), hold)
        IqHL = _iq_command(P, x, k, u, s4, Iqinj, _room(P, k, IpHL), frz, dx)
    return IpHL, IqHL


@njit(cache=True)
def line_measures(P, k, V, V1, V2):
    """REPCA1 k's measured signals at its bus voltage V and its line's end voltages V1,
    V2 (complex pu; ANDES repca1.py Iline, Vcomp, Pline, Qline): the line current from
    the device's bus Iline = isign (V1 - V2)/(r + j x); returns (VCsel, Sline) with Sline
    = Pline + j Qline = isign V1 conj((V1 - V2)/(r + j x)) and VCsel = |V - (Rc + j Xc)
    Iline| (VCFlag 1) or Kc Qline + |V| (VCFlag 0)."""
    Z = P[k, C.PC_R] + 1j * P[k, C.PC_X]
    s = P[k, C.ISIGN]
    Iline = s * (V1 - V2) / Z
    Sline = s * V1 * np.conj((V1 - V2) / Z)
    if P[k, C.PC_VCFLAG] == 1.0:
        return abs(V - (P[k, C.PC_RC] + 1j * P[k, C.PC_XC]) * Iline), Sline
    return Sline.imag * P[k, C.PC_KC] + abs(V), Sline


@kernel
def _repca1(P, x, k, V, V_nc, dx):
    """REPCA1 (ANDES 2.0 repca1.py, reactive path; docs/ibr.md 7) of device k at its bus
    voltage V with the kept-bus voltages V_nc (its line's ends at columns POS1, POS2): the
    derivatives of its slots written, the held error updated in place; returns ext =
    Pext + j Qext, the increments of its REECA1's P and Q references (pu; `_repca1_p`)."""
    VCsel, Sline = line_measures(P, k, V, V_nc[int(P[k, C.POS1])], V_nc[int(P[k, C.POS2])])
    T = P[k, C.PC_TFLTR]
    s0, dx[_PC_V, k] = lag(VCsel, x[_PC_V, k], T)
    s1, dx[_PC_Q, k] = lag(Sline.imag, x[_PC_Q, k], T)
    ref = P[k, C.PC_VREF0] - s0 if P[k, C.PC_REFFLAG] == 1.0 else P[k, C.PC_QLINE0] - s1
    db = 0.0
    if ref > P[k, C.PC_DBD2]:
        db = ref - P[k, C.PC_DBD2]
    elif ref < P[k, C.PC_DBD1]:
        db = ref - P[k, C.PC_DBD1]
    enf = clip(db, P[k, C.PC_EMIN], P[k, C.PC_EMAX])
    if abs(V) < P[k, C.PC_VFRZ] and P[k, C.PC_FREEZE] == 1.0:  # held (ANDES VarHold)
        enf = x[_PC_E_H, k]
    x[_PC_E_H, k] = enf
    ys = P[k, C.PC_KP] * enf + x[_PC_PI, k]
    y = clip(ys, P[k, C.PC_QMIN], P[k, C.PC_QMAX])
    dx[_PC_PI, k] = P[k, C.PC_KI] * (enf - P[k, C.PC_KQS] * (ys - y))
    dx[_PC_E_H, k] = 0.0
    Tfv = P[k, C.PC_TFV]
    Qext, dx[_PC_LL, k] = leadlag_input_state(y, x[_PC_LL, k], P[k, C.PC_TFT] / Tfv, Tfv)
    return _repca1_p(P, x, k, V, Sline.real, dx) + 1j * Qext


@kernel
def _repca1_p(P, x, k, V, Pline, dx):
    """REPCA1's frequency path of device k (ANDES repca1.py s4-s6): the frequency error
    1 - f (pu; `_bus_frequency` at its bus) through the deadband [fdbd1, fdbd2] times Ddn
    (negative) or Dup, plus with PLflag Plant_pref - lag(Pline, Tp), Plant_pref = Pline0
    plus the commanded increment in slot `PLANT_PREF_SLOT` (0 unless a storage controller
    writes it); limited to [femin,
    femax], the tracking PI (Kpg, Kig, ksg) in [Pmin, Pmax] and the lag Tg; returns
    Pext (the increment of its REECA1's P reference), 0 with Fflag 0."""
    f, dx[_PC_FL, k], dx[_PC_FW, k] = _bus_frequency(P, x, k, V, _PC_FL, _PC_FW)
    err = 1.0 - f
    db = 0.0
    if err > P[k, C.PC_FDBD2]:
        db = err - P[k, C.PC_FDBD2]
    elif err < P[k, C.PC_FDBD1]:
        db = err - P[k, C.PC_FDBD1]
    droop = db * (P[k, C.PC_DDN] if db < 0.0 else P[k, C.PC_DUP])
    s4, dx[_PC_P, k] = lag(Pline, x[_PC_P, k], P[k, C.PC_TP])
    e = clip(
        droop + P[k, C.PC_PLFLAG] * (P[k, C.PC_PLINE0] + x[PLANT_PREF_SLOT, k] - s4),
        P[k, C.PC_FEMIN],
        P[k, C.PC_FEMAX],
    )
    dx[PLANT_PREF_SLOT, k] = 0.0
    ys = P[k, C.PC_KPG] * e + x[_PC_PIP, k]
    y = clip(ys, P[k, C.PC_PMIN], P[k, C.PC_PMAX])
    dx[_PC_PIP, k] = P[k, C.PC_KIG] * (e - P[k, C.PC_KSG] * (ys - y))
    Pext, dx[_PC_PEXT, k] = lag(y, x[_PC_PEXT, k], P[k, C.PC_TG])
    return P[k, C.PC_FFLAG] * Pext


@kernel
def _bus_frequency(P, x, k, V, sl, sw):
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
def _algebraic(P, x, k, V):
    """ANDES's algebraic chain of device k at bus voltage V with the states x: the current
    commands (Ipcmd, Iqcmd) and the SOC derivative's input, and the frequency block's
    derivatives (dL, dW)."""
    v = abs(V)
    f, dL, dW = _bus_frequency(P, x, k, V, _F_LAG, _F_WASHOUT)
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
    Vcomp = abs(V + 1j * P[k, C.XC] * (x[0, k] + 1j * x[1, k]))
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
        up_ok = 0.0 if x[4, k] <= P[k, C.SOCMIN] else 1.0
        lo_ok = 0.0 if x[4, k] >= P[k, C.SOCMAX] else 1.0
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
def _wind_rest(P, k, dx):
    """Zero the derivatives of device k's wind slots (those its wind models do not write:
    all without a turbine)."""
    for j in range(len(WIND_SLOTS)):
        dx[_WT + j, k] = 0.0


@kernel
def _speeds(P, x, k):
    """The turbine and generator speeds (wt, wg) of device k's drive train, pu: WTDTA1's
    two masses, WTDS's one (both its speed)."""
    if P[k, C.WIND] == WTDS:
        return x[_WT, k], x[_WT, k]
    return x[_WT, k], x[_WG, k]


@kernel
def _speed_curve(P, k, u):
    """WTTQA1's speed reference fPe of device k at filtered power u (ANDES Piecewise of
    the points (p_j, sp_j), j = 1..4, flat beyond them)."""
    if u <= P[k, C.WQ_P1]:
        return P[k, C.WQ_SP1]
    if u <= P[k, C.WQ_P2]:
        kp = (P[k, C.WQ_SP2] - P[k, C.WQ_SP1]) / (P[k, C.WQ_P2] - P[k, C.WQ_P1])
        return P[k, C.WQ_SP1] + (u - P[k, C.WQ_P1]) * kp
    if u <= P[k, C.WQ_P3]:
        kp = (P[k, C.WQ_SP3] - P[k, C.WQ_SP2]) / (P[k, C.WQ_P3] - P[k, C.WQ_P2])
        return P[k, C.WQ_SP2] + (u - P[k, C.WQ_P2]) * kp
    if u <= P[k, C.WQ_P4]:
        kp = (P[k, C.WQ_SP4] - P[k, C.WQ_SP3]) / (P[k, C.WQ_P4] - P[k, C.WQ_P3])
        return P[k, C.WQ_SP3] + (u - P[k, C.WQ_P3]) * kp
    return P[k, C.WQ_SP4]


@kernel
def _windup_pi(x, k, slot, u, kp, ki, lo, hi, dx):
    """ANDES's PIAWHardLimit of device k: integrator xi (slot) with dxi/dt = ki u held in
    [lo, hi] (AntiWindup: at or beyond a limit with an outward rate, reset to it in
    place and stopped), output clip(kp u + xi, lo, hi)."""
    d = ki * u
    if x[slot, k] >= hi and d >= 0.0:
        x[slot, k], d = hi, 0.0
    elif x[slot, k] <= lo and d <= 0.0:
        x[slot, k], d = lo, 0.0
    dx[slot, k] = d
    return clip(kp * u + x[slot, k], lo, hi)


@kernel
def _wind_reference(P, x, k, Pe, dx):
    """The REECA1's speed and P reference from device k's wind turbine at its output Pe
    (pu): WTTQA1 (ANDES wttqa1.py) Pe through the lag Tp to the speed curve fPe, fPe
    through the lag Twref to wref, the PI (Kpp, Kip; windup and output limits [Temin,
    Temax]) of (Pe - P0)/wg (Tflag 1) or wref - wg (0), Pref = PI wg; the REECA1's speed
    1 + wg - fPe (ANDES's sum of the drive train's wg - 1 and the torque control's 1 -
    fPe).  Without a torque control: Pref = P0/wg, the speed wg.  Returns (speed, Pref,
    the drive train's speed reference wr0: fPe, or w0 without WTTQA1)."""
    _, wg = _speeds(P, x, k)
    if P[k, C.TORQUE] == 0.0:
        return wg, P[k, C.P0] / wg, P[k, C.WT_W0]
    Pef, dx[_TQ_PE, k] = lag(Pe, x[_TQ_PE, k], P[k, C.WQ_TP])
    fPe = _speed_curve(P, k, Pef)
    wref, dx[_TQ_WREF, k] = lag(fPe, x[_TQ_WREF, k], P[k, C.WQ_TWREF])
    Tsel = (Pe - P[k, C.P0]) / wg if P[k, C.WQ_TFLAG] == 1.0 else wref - wg
    lo, hi = P[k, C.WQ_TEMIN], P[k, C.WQ_TEMAX]
    y = _windup_pi(x, k, _TQ_PI, Tsel, P[k, C.WQ_KPP], P[k, C.WQ_KIP], lo, hi, dx)
    return 1.0 + wg - fPe, y * wg, fPe


@kernel
def _pitch_angle(P, x, k, wt, Pord, Pref, dx):
    """WTPTA1's pitch angle of device k (ANDES wtpta1.py, deg): the PI (Kpc, Kic) of
    Pord - Pref plus the PI (Kpw, Kiw) of Kcc (Pord - Pref) + wt - w0 (its speed
    reference: the drive train's w0, as ANDES initialises it), each limited to [thmin,
    thmax], through the lag Tp with the rate limits [dthmin, dthmax] on Tp dtheta/dt and
    the anti-windup limits [thmin, thmax] (LagAntiWindupRate)."""
    lo, hi = P[k, C.WP_THMIN], P[k, C.WP_THMAX]
    e = Pord - Pref
    yc = _windup_pi(x, k, _PT_C, e, P[k, C.WP_KPC], P[k, C.WP_KIC], lo, hi, dx)
    u = P[k, C.WP_KCC] * e + wt - P[k, C.WT_W0]
    yw = _windup_pi(x, k, _PT_W, u, P[k, C.WP_KPW], P[k, C.WP_KIW], lo, hi, dx)
    r = clip(yw + yc - x[_PT_TH, k], P[k, C.WP_DTHMIN], P[k, C.WP_DTHMAX])
    if x[_PT_TH, k] >= hi and r >= 0.0:
        x[_PT_TH, k], r = hi, 0.0
    elif x[_PT_TH, k] <= lo and r <= 0.0:
        x[_PT_TH, k], r = lo, 0.0
    dx[_PT_TH, k] = r / P[k, C.WP_TP]
    return x[_PT_TH, k]


@kernel
def _wind_mechanics(P, x, k, Pe, wg_ree, wr0, Pref, dx):
    """Device k's turbine (ANDES wtdta1.py, wtds.py, wtara1.py) at its output Pe, the
    REECA1's speed wg_ree and P reference Pref, the speed reference wr0: the aerodynamic
    power Pm = P0 - Ka theta (theta - theta0) (WTARA1; theta = rad(theta0) - theta0 plus
    the pitch angle, ANDES's mix of radians and degrees kept), P0 without; WTDTA1 2 Ht
    dwt/dt = Pm/wt - Tshaft - pd, 2 Hg dwg/dt = -Pe/wg + Tshaft - DAMP (wg - w0) + pd,
    dTshaft/dt = Kshaft (wt - wg), pd = Dshaft (wt - wg), Ht = Htfrac H, Hg = H - Ht,
    Kshaft = 2 Ht Hg Freq1^2/H; WTDS 2 H dw/dt = (Pm - Pe)/wg_ree - DAMP (w - wr0)."""
    wt, wg = _speeds(P, x, k)
    theta0 = P[k, C.WA_THETA0]
    theta = np.deg2rad(theta0)
    if P[k, C.PITCH] == 1.0:
        theta += _pitch_angle(P, x, k, wt, x[_PORD, k], Pref, dx) - theta0
    Pm = P[k, C.P0]
    if P[k, C.AERO] == 1.0:
        Pm += -(theta - theta0) * theta * P[k, C.WA_KA]
    H = P[k, C.WT_H]
    if P[k, C.WIND] == WTDS:
        d = (Pm - Pe) / wg_ree - P[k, C.WT_DAMP] * (wt - wr0)
        dx[_WT, k] = d / (2.0 * H)
        return
    Ht2 = 2.0 * (P[k, C.WT_HTFRAC] * H)
    Hg2 = 2.0 * H * (1.0 - P[k, C.WT_HTFRAC])
    pd = P[k, C.WT_DSHAFT] * (wt - wg)
    dx[_WT, k] = (Pm / wt - x[_TSH, k] - pd) / Ht2
    dx[_WG, k] = (-Pe / wg + x[_TSH, k] - P[k, C.WT_DAMP] * (wg - P[k, C.WT_W0]) + pd) / Hg2
    dx[_TSH, k] = Ht2 * Hg2 * 0.5 * P[k, C.WT_FREQ1] ** 2 / H * (wt - wg)


@kernel
def _frame(P, x, k, V):
    """exp(j (a - am)) of device k at its bus voltage V: the rotation from the PLL1's
    frame (measured angle am) to the bus's (angle a); 1 without a PLL (ANDES regcp1.py:
    Vd = |V| cos(a - am), Vq = -|V| sin(a - am))."""
    if P[k, C.PLL] == NO_PLL:
        return 1.0 + 0.0j
    v = abs(V)
    if v == 0.0:
        return 1.0 + 0.0j
    return V / v * np.exp(-1j * x[_PLL_AM, k])


@kernel
def drawn_current(P, x, k, v):
    """The current device k draws at its bus as (I_rel, I_fix) at bus voltage magnitude
    v, for the network solution (`stabctl.network.solution.L`): I_rel = -(Ip + j
    Iq) as complex power per pu voltage, so that the injected current is (Ip - j Iq)
    V/|V|; REGCA1 the same with its output currents Ipout, Iqout, which depend on v;
    with a PLL1 the current is set in the PLL's frame, not the bus's: I_fix = -(Ipout - j
    Iqout) exp(j am) drawn whatever V (ANDES regcp1.py), I_rel 0."""
    if P[k, C.TYPE] == REGCA1:
        Ipout, Iqout = _regca1_currents(P, x, k, v)
        if P[k, C.PLL] == PLL1:
            return 0.0j, -(Ipout - 1j * Iqout) * np.exp(1j * x[_PLL_AM, k])
        return -(Ipout + 1j * Iqout), 0.0j
    return -(x[0, k] + 1j * x[1, k]), 0.0j


@kernel
def voltage_dependent(P, k):
    """True if device k's drawn current depends on its bus voltage (REGCA1): the network
    solution is then repeated until the currents agree with the voltages."""
    return P[k, C.TYPE] == REGCA1


@kernel
def derivatives(P, x, k, V, V_nc, reach, dx):
    """Write the derivatives of device k (column k of dx) at bus voltage V (complex pu;
    V_nc the kept-bus voltages, where a REPCA1's line ends are) and return its injected
    complex power P + j Q (pu, system base); a REGCA1's Ip state is clamped in place at
    its LVPL limit (`clamp_states`; reach s: the simulator's step, 0 the limit alone),
    its controls' memory updated in place."""
    v = abs(V)
    if P[k, C.TYPE] == REGCA1:
        Ipout, Iqout = _regca1_currents(P, x, k, v)
        rot = _frame(P, x, k, V)
        S = v * rot * (Ipout + 1j * Iqout)  # Pe + j Qe (ANDES regcp1.py)
        _pll(P, x, k, V, dx)
        Iq_target = -P[k, C.IQCMD0]
        _wind_rest(P, k, dx)
        if P[k, C.REEC] != NO_REEC:
            ext = _repca1(P, x, k, V, V_nc, dx) if P[k, C.REPC] == REPCA1 else 0.0j
            wg, Pref, wr0 = 1.0, P[k, C.P0], 1.0
            if P[k, C.WIND] != NO_WIND:
                wg, Pref, wr0 = _wind_reference(P, x, k, S.real, dx)
            ref = Pref + ext
            # the electrical control reads Vd, the voltage in the PLL's frame (|V| without)
            Ipcmd, Iq_target = _reeca1(P, x, k, v * rot.real, S, ref, wg, dx)
            x[_IPCMD, k] = Ipcmd + P[k, C.IPOFF]
            if P[k, C.WIND] != NO_WIND:
                _wind_mechanics(P, x, k, S.real, wg, wr0, ref.real, dx)
        _regca1_derivatives(P, x, k, v, Iq_target, reach, dx)
        dx[4, k] = _soc_rate(P, k, S.real)
        return S
    Ipcmd, Iqcmd, dL, dW, fHz = _algebraic(P, x, k, V)
    if P[k, C.RELAY] != NO_RELAY and _protection(P, x, k, fHz, v, dx):
        Ipcmd = Iqcmd = 0.0  # ANDES: Psum, Qsum and the droop's fHz set to 0
    _, dx[0, k] = lag(Ipcmd, x[0, k], P[k, C.TIP])
    _, dx[1, k] = lag(Iqcmd, x[1, k], P[k, C.TIQ])
    dx[2, k] = dL
    dx[3, k] = dW
    dx[4, k] = _soc_rate(P, k, v * x[0, k])
    return v * x[0, k] + 1j * v * x[1, k]


@kernel
def _pll(P, x, k, V, dx):
    """PLL1's derivatives of device k at its bus voltage V (ANDES 2.0 measurement/pll.py
    PLL1): the bus angle a through the lag Tf (af), the PI on af - am (Kp, Ki), the
    estimated angle ae' = 2 pi fn PI_y and the measured angle am the lag Tp of ae; a
    taken within pi of am (ANDES's bus angle is not wrapped); nothing without a PLL."""
    for j in range(len(PLL_SLOTS)):
        dx[_PLL_AF + j, k] = 0.0
    if P[k, C.PLL] == NO_PLL:
        return
    am = x[_PLL_AM, k]
    a = am + np.angle(V * np.exp(-1j * am)) if V != 0.0 else x[_PLL_AF, k]
    dx[_PLL_AF, k] = (a - x[_PLL_AF, k]) / P[k, C.PLL_TF]
    e = x[_PLL_AF, k] - am
    dx[_PLL_PI, k] = P[k, C.PLL_KI] * e
    dx[_PLL_AE, k] = 2.0 * np.pi * P[k, C.FN] * (P[k, C.PLL_KP] * e + x[_PLL_PI, k])
    dx[_PLL_AM, k] = (x[_PLL_AE, k] - am) / P[k, C.PLL_TP]


#: the protection timers' limit rule: the IEEE 421.5 annex's (`blocks.nonwindup`), a numpy
#: bool so that the block compiles once for it and a variable (the kernel coding rules)
_ANNEX_RULE = np.bool_(True)


@kernel
def _relay_timer(x, dx, slot, k, e, upper):
    """One protection timer of device k (ANDES IntegratorAntiWindup, T = K = 1, limits
    [0, upper]): the non-windup integrator `blocks.nonwindup` of dy/dt = e, its state held
    in place; returns ANDES's flag zu = (y >= upper and e >= 0) as a float."""
    x[slot, k], dx[slot, k] = nonwindup(x[slot, k], e, 0.0, upper, _ANNEX_RULE, 0.0)
    return 1.0 if x[slot, k] >= upper and e >= 0.0 else 0.0


@kernel
def _protection(P, x, k, fHz, v, dx):
    """ANDES 2.0's DGPRCT1 / DGPRCTExt of device k (``distributed/dgprct.py``) at its
    measured frequency fHz (Hz) and bus voltage v (pu; the initial one for DGPRCTExt):
    True while it trips (``lock``).  Each timer integrates its band's flag (`_relay_sum`)
    and runs down at T/Tres while ``res``, the Tres s after a trip ends (ExtendedEvent
    extend_only), from the evaluation where the trip ends; the reset extension and the
    trip flag are the memory slots _PR_RES, _PR_LOCK."""
    if P[k, C.RELAY] == DGPRCTEXT:
        v = P[k, C.PR_V0]
    tripped = x[_PR_LOCK, k] == 1.0
    res = 1.0 if x[_PR_RES, k] > 0.0 and not tripped else 0.0
    lock = _relay_sum(P, x, k, fHz, v, res, dx) > 0.8  # ANDES: Limiter of dsum at 0.8
    if tripped and not lock:  # the trip ends here: the reset runs from now
        _relay_sum(P, x, k, fHz, v, 1.0, dx)
    tres = P[k, C.PR_TRES]
    _timer(x, dx, _PR_RES, k, lock, tres)
    x[_PR_LOCK, k] = 1.0 if lock else 0.0
    dx[_PR_LOCK, k] = 0.0
    return lock


@kernel
def _relay_sum(P, x, k, fHz, v, res, dx):
    """The protection's timers of device k (derivatives into dx) and ANDES's ``dsum``: over
    the enabled timers, (at T) x (still in its band).  Band flags zi = lower <= u <= upper
    (Limiter equal=False); a timer's input is its band's flag, or -T/Tres while res.  As
    ANDES: the fu2 timer integrates the (fl3, fl2) flag and the vl3 timer the (vl4, vl2)
    flag up to Tvl2 (their gates in the sum are their own bands)."""
    tres = P[k, C.PR_TRES]
    f_lo, f_hi = P[k, C.PR_FL3], P[k, C.PR_FU3]
    v_lo, v_hi = P[k, C.PR_VL4], P[k, C.PR_VU3]
    zf = (
        1.0 if f_lo <= fHz <= P[k, C.PR_FL1] else 0.0,
        1.0 if f_lo <= fHz <= P[k, C.PR_FL2] else 0.0,
        1.0 if P[k, C.PR_FU1] <= fHz <= f_hi else 0.0,
        1.0 if P[k, C.PR_FU2] <= fHz <= f_hi else 0.0,
    )
    zv = (
        1.0 if v_lo <= v <= P[k, C.PR_VL1] else 0.0,
        1.0 if v_lo <= v <= P[k, C.PR_VL2] else 0.0,
        1.0 if v_lo <= v <= P[k, C.PR_VL3] else 0.0,
        1.0 if P[k, C.PR_VU1] <= v <= v_hi else 0.0,
        1.0 if P[k, C.PR_VU2] <= v <= v_hi else 0.0,
    )
    Tf = (P[k, C.PR_TFL1], P[k, C.PR_TFL2], P[k, C.PR_TFU1], P[k, C.PR_TFU2])
    Tv = (P[k, C.PR_TVL1], P[k, C.PR_TVL2], P[k, C.PR_TVL2], P[k, C.PR_TVU1], P[k, C.PR_TVU2])
    fed_f = (zf[0], zf[1], zf[2], zf[1])  # ANDES's IAWfu2 reads Lfl2_zi
    fed_v = (zv[0], zv[1], zv[1], zv[3], zv[4])  # its IAWVl3 reads LVl2_zi, up to Tvl2
    dsum = 0.0
    for j in range(4):
        e = fed_f[j] * (1.0 - res) - Tf[j] / tres * res
        dsum += P[k, C.PR_FEN] * _relay_timer(x, dx, _PR_T + j, k, e, Tf[j]) * zf[j]
    for j in range(5):
        e = fed_v[j] * (1.0 - res) - Tv[j] / tres * res
        dsum += P[k, C.PR_VEN] * _relay_timer(x, dx, _PR_T + 4 + j, k, e, Tv[j]) * zv[j]
    return dsum


@kernel
def _soc_rate(P, k, pe):
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
        Ip[k], Iq[k], _, _, _ = _algebraic(P, x, k, V[k])
    return Ip, Iq


@njit(cache=True)
def derivatives_at(P, x, V, V_nc, dx):
    """`derivatives` of every device at bus voltages V (n_ibr,) complex: dx (N_STATES,
    n_ibr) written, the injected P + j Q (n_ibr,) complex returned (for tests and
    tools; the simulator calls `derivatives` inside its evaluation).  A REPCA1's line
    ends are read from V_nc at its positions pos1, pos2 (`at_power_flow`)."""
    S = np.empty(V.size, np.complex128)
    for k in range(V.size):
        S[k] = derivatives(P, x, k, V[k], V_nc, 0.0, dx)
    return S


def initialise(cp: ConverterParams, V0: np.ndarray) -> np.ndarray:
    """Initial states (N_STATES, n_ibr) at the power-flow voltages, checked against the
    power-flow point.

    Parameters
    ----------
    cp : ConverterParams
        The devices (with their P0, Q0).
    V0 : ndarray of complex, shape (n_bus,)
        Power-flow bus voltages, pu.

    Returns
    -------
    ndarray, shape (N_STATES, n_ibr)
        PVD1, ESD1: Ip = P0/|V|, Iq = Q0/|V|, the measurement states 0, SOC = SOCinit
        (ESD1).  REGCA1 (ANDES regca1.py 184-211): Ip = Ipcmd0, Iq = -Iqcmd0 = Q0/|V|,
        the voltage filter |V|; with a REECA1, its states (`_reeca1_initial`) and memory
        (the held outputs: their values at the start).

    Raises
    ------
    CaseError
        A device whose commands at the initial point are not its power-flow P0, Q0 (a
        current limit, a trip curve, the Q droop or the power-order limit active at the
        start); a REGCA1 that does not start at rest at P0, Q0 (LVG 0 at its voltage, Ip
        at the LVPL limit, the high-voltage management or Iolim active; its REECA1's
        references not at rest: a current limit, a frozen start, a PI input not 0),
        naming it and the fastest-moving state.
    """
    x = np.zeros((N_STATES, cp.n))
    V = V0[cp.bus_idx]
    v = np.abs(V)
    reg = cp.type == REGCA1
    x[0], x[1] = np.where(reg, cp.Ipcmd0, cp.P0 / v), cp.Q0 / v
    x[2] = np.where(reg, v, 0.0)
    x[4] = np.where((cp.type == ESD1) | cp.is_battery, cp.SOCinit, 0.0)
    P, Vc, V_nc = at_power_flow(cp, V0)
    if np.any(cp.reec != NO_REEC):
        _reeca1_initial(cp, x, v)
    if np.any(cp.wind != NO_WIND):
        _wind_initial(cp, x)
    pc = cp.repc == REPCA1
    x[_PC_V] = np.where(pc, cp.pc_Vref0, 0.0)  # the filters at VCsel, Qline; PI, lead-lag 0
    x[_PC_Q] = np.where(pc, cp.pc_Qline0, 0.0)
    x[_PC_P] = np.where(pc, cp.pc_Pline0, 0.0)  # the frequency path at rest at 0
    for slot in (_PLL_AF, _PLL_AE, _PLL_AM):  # the PLL's angles at the bus's, its PI at 0
        x[slot] = np.where(cp.pll == PLL1, np.angle(V), 0.0)
    if np.any(reg):
        _check_regca1(cp, P, x, Vc, V_nc)
    Ip, Iq = commands(P, x, Vc) if cp.n else ((), ())
    for k, (Ipcmd, Iqcmd) in enumerate(zip(Ip, Iq)):
        if reg[k]:
            continue
        if abs(Ipcmd - x[0, k]) > 1e-9 or abs(Iqcmd - x[1, k]) > 1e-9:
            raise CaseError(
                f"ibr_con row {k + 1}: the converter cannot start at its power-flow point "
                f"P0 = {cp.P0[k]:.6g}, Q0 = {cp.Q0[k]:.6g} pu at |V| = {v[k]:.6g} pu: its "
                f"commands there are Ip = {Ipcmd:.6g}, Iq = {Iqcmd:.6g} pu instead of "
                f"{x[0, k]:.6g}, {x[1, k]:.6g} (a current limit ialim, a trip curve, the "
                "Q droop or the power-order limit is active at the start)"
            )
    return x


def _reeca1_initial(cp: ConverterParams, x: np.ndarray, v: np.ndarray) -> None:
    """REECA1's initial states in x (N_STATES, n_ibr), in place, at the voltage
    magnitudes v (ANDES reeca1.py v_str): the filters at |V0|, P0, P0, P0; the Q filter
    at PFsel/vp (Qref, or Q0 with PFFLAG); the V PI's integrator at QFLAG Q0/|V0| (its
    x0 -QFLAG Iqcmd0), the Q PI's at 0; the last Ipcmd the REGCA1's Ipcmd0."""
    ree = cp.reec != NO_REEC
    vp = np.where(v <= 0.01, 0.01, v)
    pfsel = np.where(cp.PFFLAG == 1, cp.Q0, cp.Qref)
    init = {
        _VT: v,
        _PE: cp.P0,
        _S4: pfsel / vp,
        _PFILT: cp.P0,
        _PORD: cp.P0,
        _PIV: cp.QFLAG * cp.Q0 / v,
        _IPCMD: cp.Ipcmd0,
    }
    for slot, value in init.items():
        x[slot] = np.where(ree, value, 0.0)


def _wind_initial(cp: ConverterParams, x: np.ndarray) -> None:
    """The wind turbines' initial states in x (N_STATES, n_ibr), in place (ANDES's
    initialisation, the torque control's values set last): both speeds at fPe(P0) with
    a torque control (WTTQA1), else at w0; the shaft torque P0 over that speed (WTDTA1);
    WTTQA1's Pe filter at P0, its speed reference at fPe(P0), its PI's integrator at
    P0/fPe(P0); WTPTA1's integrators at 0 and its pitch angle at the PIs' outputs (the
    speed PI's clip(Kpw (w - w0), thmin, thmax))."""
    P = cp.packed()
    for k in np.flatnonzero(cp.wind != NO_WIND):
        w = _speed_curve.py_func(P, k, cp.P0[k]) if cp.torque[k] == 1 else cp.wt_w0[k]
        x[_WT, k] = w
        if cp.wind[k] == WTDTA1:
            x[_WG, k] = w
            x[_TSH, k] = cp.P0[k] / w
        if cp.torque[k] == 1:
            x[_TQ_PE, k], x[_TQ_WREF, k], x[_TQ_PI, k] = cp.P0[k], w, cp.P0[k] / w
        if cp.pitch[k] == 1:
            lo, hi = cp.wp_thmin[k], cp.wp_thmax[k]
            yw = np.clip(cp.wp_Kpw[k] * (w - cp.wt_w0[k]), lo, hi)
            x[_PT_TH, k] = yw + np.clip(0.0, lo, hi)


def at_power_flow(cp: ConverterParams, V0: np.ndarray):
    """The packed parameters and voltages for `derivatives_at` at the power-flow bus
    voltages V0 (n_bus,): (P with each REPCA1's line ends at positions n_ibr + k and
    2 n_ibr + k, the devices' bus voltages (n_ibr,), those and the line ends' (3 n_ibr,)),
    complex pu."""
    n = cp.n
    P = cp.packed()
    P[:, C.POS1] = n + np.arange(n)
    P[:, C.POS2] = 2 * n + np.arange(n)
    V_nc = V0[np.concatenate([cp.bus_idx, cp.bus1_idx, cp.bus2_idx])].astype(np.complex128)
    return P, V_nc[:n].copy(), V_nc


def _check_regca1(cp: ConverterParams, P, x: np.ndarray, Vc, V_nc) -> None:
    """Refuse a REGCA1 (with its controls) that does not start at rest at its power-flow
    point: x (N_STATES, n_ibr) the initial states, its controls' memory filled in place by
    a first evaluation; P, Vc, V_nc as `at_power_flow` gives them."""
    x0 = x.copy()
    dx = np.zeros_like(x)
    derivatives_at(P, x, Vc, V_nc, dx)  # the held outputs take their initial values
    x_in = x.copy()
    S = derivatives_at(P, x_in, Vc, V_nc, dx)
    act = cp.has_state()
    states = ~np.isin(np.arange(N_STATES), MEMORY_SLOTS)
    for k in np.flatnonzero(cp.type == REGCA1):
        speed = np.where(act[:, k], np.abs(dx[:, k]), 0.0)
        worst = int(np.argmax(speed))
        gap = abs(S[k] - (cp.P0[k] + 1j * cp.Q0[k]))
        clamped = np.any(x_in[:, k] != x[:, k]) or np.any((x[:, k] != x0[:, k])[states])
        if gap > 1e-9 or speed[worst] > 1e-9 or clamped:
            raise CaseError(
                f"ibr_con row {k + 1}: the REGCA1 cannot start at its power-flow point "
                f"P0 = {cp.P0[k]:.6g}, Q0 = {cp.Q0[k]:.6g} pu at |V| = {abs(Vc[k]):.6g} pu: "
                f"it injects {S[k].real:.6g} + j{S[k].imag:.6g} pu there, its states "
                f"moving at up to {speed[worst]:.3g} pu/s ({STATE_NAMES[REGCA1][worst]}; "
                "the low-voltage gain LVG 0, Ip at the LVPL limit, the high-voltage "
                "management Volim or the limit Iolim is active at the start, or its "
                "REECA1's current limits, voltage dip freeze or PI references)"
            )
