"""The ``ibr_con`` table every converter component reads: its columns (the device's own,
then each component's: REECA1 54-104, REPCA1 105-143, the wind turbine 145-182, the PLL1
183-187, the DG protection 188-213, the DERA1 214-227 and 271-302, the REGCB1 228-237, the
REECD1 238-270, the reading ``psse`` 303; ANDES 2.0's and PSS/E's parameters,
docs/ibr.md), the codes that switch the components on, and the packed parameter layout of
the compiled kernels (`PACKED`, its named columns `C`).

The columns are declared here, once, not in the component modules of
:mod:`stabctl.models.converters`: every kernel reads the packed matrix by the names of `C`,
which is made from all of them, so the components import this module and it imports none
of them.  The DYR records that fill the columns are the components' (their ``DYR``).
"""

from __future__ import annotations

from typing import Any

from stabctl.models.declaration import Param, layout

#: the converter types: ANDES's PVD1 (WECC distributed PV), ESD1 (PVD1 with a state of
#: charge), REGCA1 (WECC second-generation renewable generator/converter, REGC_A); PSS/E's
#: DERA1 (WECC aggregated distributed energy resources, DER_A)
PVD1, ESD1, REGCA1, DERA1 = 1, 2, 3, 4

_DEV_PU: dict[str, Any] = dict(unit="pu")  # on the device base mva (ANDES ``power=True``)
_FLAG: dict[str, Any] = dict(unit="code", choices=(0.0, 1.0))  # a 0/1 switch


def _columns(
    col: int, rows: list[tuple[str, dict[str, Any]]], prefix: str = "", model: str = ""
) -> tuple[Param, ...]:
    """A component's consecutive ibr_con columns from ``col`` on (1-based), one `Param` per
    (name, `Param` keywords) of `rows`, in order: named `prefix` + name, and documented
    "`model`: " + doc where `model` is given (else doc as it stands)."""
    label = f"{model}: " if model else ""
    return tuple(
        Param(prefix + name, col=col + j, **{**kw, "doc": label + kw["doc"]})
        for j, (name, kw) in enumerate(rows)
    )


#: REGCA1's electrical control (ibr_con ``reec``): none, REECA1 (WECC REEC_A), REECB1 (WECC
#: REEC_B: REECA1's columns without its VDL curves, Iqinj hold, PFLAG and Vref1; ANDES 2.0
#: ``renewable/reecb1.py``), REECD1 (WECC REEC_D, PSS/E REECD1: REECA1's columns, its Vref1
#: PSS/E's Vbias, ten-point VDL curves and the ``rd_`` columns, :mod:`.reecd1`)
NO_REEC, REECA1, REECB1, REECD1 = 0, 1, 2, 3


def _reeca1_params(col: int) -> tuple[Param, ...]:
    """REECA1's columns from ``col`` on (ANDES 2.0 ``renewable/reeca1.py`` REECA1Data and
    its config kqs, kvs, tpfilt; PQFLAG is the table's ``pqflag``).  Powers and currents
    on the device base where ANDES converts them (``power``/``current`` True); the gains
    Kqv, Kqp, Kqi, Kvp, Kvi and the currents Iqh1, Iql1, Iqfrz on the system base, as
    ANDES reads them (``import-psse`` converts PSS/E's values on MBASE to them:
    `stabctl.io.dyr_converters`)."""
    rows: list[tuple[str, dict[str, Any]]] = [
        ("PFFLAG", dict(_FLAG, doc="REECA1: 1 power-factor control, 0 Q control")),
        ("VFLAG", dict(_FLAG, doc="REECA1: 1 Q control (PI), 0 voltage control")),
        ("QFLAG", dict(_FLAG, doc="REECA1: 1 voltage/Q control (PI), 0 constant PF or Q")),
        ("PFLAG", dict(_FLAG, doc="REECA1: 1 P order times the speed (1 here), 0 not")),
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
        ("Kqp", dict(unit="pu", default=1.0, lo=0.0, doc="REECA1: Q PI proportional gain")),
        ("Kqi", dict(unit="1/s", default=0.1, lo=0.0, doc="REECA1: Q PI integral gain")),
        ("Kvp", dict(unit="pu", default=1.0, lo=0.0, doc="REECA1: V PI proportional gain")),
        ("Kvi", dict(unit="1/s", default=0.1, lo=0.0, doc="REECA1: V PI integral gain")),
        ("Vref1", dict(unit="pu", default=1.0, doc="REECA1: voltage reference (VFLAG 0)")),
        (
            "dPmax",
            dict(
                _DEV_PU,
                default=999.0,
                doc="REECA1: upper P reference rate (pu/s read as PSS/E's; ANDES: x Tpfilt)",
            ),
        ),
        ("dPmin", dict(_DEV_PU, default=-999.0, doc="REECA1: lower P reference rate (as dPmax)")),
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
    return _columns(col, rows)


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
    rows: list[tuple[str, dict[str, Any]]] = [
        ("VCFlag", dict(_FLAG, default=1.0, doc="1 compensated voltage, 0 V + Kc Qline")),
        ("RefFlag", dict(_FLAG, default=1.0, doc="1 voltage control, 0 line Q control")),
        ("Fflag", dict(_FLAG, doc="1 the frequency path's Pext on, 0 off")),
        ("PLflag", dict(_FLAG, default=1.0, doc="1 the line P error in the P path, 0 not")),
        ("bus1", dict(unit="code", integer=True, doc="monitored line's from bus (0: none)")),
        ("bus2", dict(unit="code", integer=True, doc="monitored line's to bus (0: none)")),
        ("r", dict(unit="pu", default=1.0, doc="monitored line resistance")),
        ("x", dict(unit="pu", default=1.0, doc="monitored line reactance")),
        ("Rc", dict(unit="pu", doc="line drop compensation resistance")),
        ("Xc", dict(unit="pu", doc="line drop compensation reactance")),
        ("Kc", dict(unit="pu", doc="reactive droop gain (VCFlag 0)")),
        ("Tfltr", dict(unit="s", default=0.02, lo=0.0, doc="voltage and Q filters")),
        ("Kp", dict(unit="pu", default=1.0, lo=0.0, doc="PI proportional gain")),
        ("Ki", dict(unit="1/s", default=0.1, lo=0.0, doc="PI integral gain")),
        ("Kqs", dict(unit="", default=2.0, lo=0.0, doc="PI tracking gain (kqs)")),
        ("Tft", dict(unit="s", default=1.0, lo=0.0, doc="lead time constant")),
        ("Tfv", dict(unit="s", default=1.0, lo=0.0, doc="lag time constant")),
        ("Vfrz", dict(unit="pu", default=0.8, doc="voltage below which the error is held")),
        ("freeze", dict(_FLAG, default=1.0, doc="1 the hold below Vfrz on, 0 off")),
        ("emax", dict(unit="pu", default=999.0, doc="upper error limit")),
        ("emin", dict(unit="pu", default=-999.0, doc="lower error limit")),
        ("dbd1", dict(unit="pu", default=-0.1, hi=0.0, doc="lower error deadband")),
        ("dbd2", dict(unit="pu", default=0.1, lo=0.0, doc="upper error deadband")),
        ("Qmax", dict(unit="pu", default=999.0, doc="upper Q command (system base)")),
        ("Qmin", dict(unit="pu", default=-999.0, doc="lower Q command (system base)")),
        ("Kpg", dict(unit="pu", default=1.0, lo=0.0, doc="P PI proportional gain")),
        ("Kig", dict(unit="1/s", default=0.1, lo=0.0, doc="P PI integral gain")),
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
    return _columns(col, rows, "pc_", "REPCA1")


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
        ("aero", dict(_FLAG, doc="WTARA1 aerodynamics: 1 on (Pm falls with the pitch), 0 off")),
        ("wa_Ka", dict(unit="pu/deg", default=1.0, lo=0.0, doc="WTARA1: aerodynamic gain")),
        ("wa_theta0", dict(unit="deg", doc="WTARA1: initial pitch angle")),
        ("pitch", dict(_FLAG, doc="WTPTA1 pitch control: 1 on, 0 off (needs aero)")),
        ("wp_Kiw", dict(unit="1/s", default=0.1, lo=0.0, doc="WTPTA1: speed PI integral gain")),
        ("wp_Kpw", dict(unit="pu", lo=0.0, doc="WTPTA1: speed PI proportional gain")),
        ("wp_Kic", dict(unit="1/s", default=0.1, lo=0.0, doc="WTPTA1: power PI integral gain")),
        ("wp_Kpc", dict(unit="pu", lo=0.0, doc="WTPTA1: power PI proportional gain")),
        ("wp_Kcc", dict(unit="pu", lo=0.0, doc="WTPTA1: power error gain in the speed PI")),
        ("wp_Tp", dict(unit="s", default=0.3, lo=0.0, doc="WTPTA1: blade response lag")),
        ("wp_thmax", dict(unit="deg", default=30.0, doc="WTPTA1: maximum pitch angle")),
        ("wp_thmin", dict(unit="deg", doc="WTPTA1: minimum pitch angle")),
        ("wp_dthmax", dict(unit="deg", default=5.0, doc="WTPTA1: upper rate of Tp dtheta/dt")),
        ("wp_dthmin", dict(unit="deg", default=-5.0, doc="WTPTA1: lower rate of Tp dtheta/dt")),
        ("torque", dict(_FLAG, doc="WTTQA1 torque control: 1 on, 0 off (needs pitch)")),
        ("wq_Kip", dict(unit="1/s", default=0.1, lo=0.0, doc="WTTQA1: PI integral gain")),
        ("wq_Kpp", dict(unit="pu", lo=0.0, doc="WTTQA1: PI proportional gain")),
        ("wq_Tp", dict(unit="s", default=0.05, lo=0.0, doc="WTTQA1: Pe filter")),
        ("wq_Twref", dict(unit="s", default=30.0, lo=0.0, doc="WTTQA1: speed reference lag")),
        ("wq_Temax", dict(_DEV_PU, default=1.2, doc="WTTQA1: maximum electric torque")),
        ("wq_Temin", dict(_DEV_PU, doc="WTTQA1: minimum electric torque")),
        ("wq_Tflag", dict(_FLAG, doc="WTTQA1: 1 power error, 0 speed error")),
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
    return _columns(col, rows)


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
    rows: list[tuple[str, dict[str, Any]]] = [
        ("pr_fen", dict(_FLAG, default=1.0, doc="DGPRCT: frequency protection 1 on, 0 off")),
        ("pr_Ven", dict(_FLAG, doc="DGPRCT: voltage protection 1 on, 0 off")),
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
    return _columns(col, rows)


_RELAY_PARAMS = _relay_params(189)


def _dera1_params(col: int) -> tuple[Param, ...]:
    """DERA1's columns from ``col`` on, prefixed ``da_`` (PSS/E Model Library DERA1, the
    WECC DER_A specification; its PQFlag is the table's ``pqflag``): the flags, the
    voltage and power measurements, the voltage control and the current limits and lags
    its FreqFlag 0 reads.  Currents and gains on the device base, as PSS/E's; the
    defaults are the typical values of the WECC DER_A specification."""
    rows: list[tuple[str, dict[str, Any]]] = [
        ("PfFlag", dict(_FLAG, default=1.0, doc="1 constant power factor, 0 constant Q")),
        ("GenFlag", dict(_FLAG, default=1.0, doc="1 a generator (Ip >= 0), 0 storage")),
        ("Trv", dict(unit="s", default=0.02, lo=0.0, doc="voltage measurement lag")),
        ("dbd1", dict(unit="pu", default=-99.0, hi=0.0, doc="lower voltage deadband")),
        ("dbd2", dict(unit="pu", default=99.0, lo=0.0, doc="upper voltage deadband")),
        (
            "Kqv",
            dict(_DEV_PU, default=0.0, lo=0.0, doc="Iq per pu voltage error beyond the deadband"),
        ),
        ("Vref0", dict(unit="pu", doc="voltage reference (0: the initial voltage)")),
        ("Tp", dict(unit="s", default=0.02, lo=0.0, doc="power measurement lag")),
        ("Tiq", dict(unit="s", default=0.02, lo=0.0, doc="reactive current reference lag")),
        ("Imax", dict(_DEV_PU, default=1.2, lo=0.0, doc="apparent current limit")),
        ("Tg", dict(unit="s", default=0.02, lo=0.0, doc="current control lag")),
        ("rrpwr", dict(_DEV_PU, default=99.0, lo=0.0, doc="upper rate of |Ip| (1/s)")),
        ("Iqh1", dict(_DEV_PU, default=1.0, doc="upper limit of the voltage control's Iq")),
        ("Iql1", dict(_DEV_PU, default=-1.0, doc="lower limit of the voltage control's Iq")),
    ]
    return _columns(col, rows, "da_", "DERA1")


_DERA1_PARAMS = _dera1_params(214)


def _dera1_control_params(col: int) -> tuple[Param, ...]:
    """DERA1's columns from ``col`` on, prefixed ``da_`` (PSS/E Model Library DERA1, the
    WECC DER_A specification): the active power-frequency control (FreqFlag 1) and the
    voltage and frequency tripping (VtripFlag 1, FtripFlag 1), :mod:`.dera1`.  Powers
    (droop gains, the error, power and ramp limits) on the device base, as PSS/E's;
    frequencies in pu of the nominal; the defaults are PowerSimulationsDynamics.jl's
    test 42 values (tests/data/psse_runs/DERA_FREQFLAG0/README.md)."""
    rows: list[tuple[str, dict[str, Any]]] = [
        ("FreqFlag", dict(_FLAG, doc="1 the power-frequency control (droop, PI), 0 P held")),
        ("VtripFlag", dict(_FLAG, doc="1 the voltage tripping, 0 none")),
        ("FtripFlag", dict(_FLAG, doc="1 the frequency tripping, 0 none")),
        ("Trf", dict(unit="s", default=0.02, lo=0.0, doc="frequency measurement lag")),
        ("Ddn", dict(_DEV_PU, default=20.0, doc="droop, P per pu frequency above fdbd2")),
        ("Dup", dict(_DEV_PU, default=0.0, doc="droop, P per pu frequency below fdbd1")),
        ("fdbd1", dict(unit="pu", default=-0.0006, hi=0.0, doc="lower frequency deadband")),
        ("fdbd2", dict(unit="pu", default=0.0006, lo=0.0, doc="upper frequency deadband")),
        ("femax", dict(_DEV_PU, default=99.0, doc="upper limit of the power PI's error")),
        ("femin", dict(_DEV_PU, default=-99.0, doc="lower limit of the power PI's error")),
        ("Pmax", dict(_DEV_PU, default=1.1, doc="upper limit of the PI output and Pord")),
        ("Pmin", dict(_DEV_PU, default=0.0, doc="lower limit of the PI output and Pord")),
        ("dPmax", dict(_DEV_PU, default=0.5, doc="upper rate of Pord (1/s)")),
        ("dPmin", dict(_DEV_PU, default=-0.5, doc="lower rate of Pord (1/s)")),
        ("Tpord", dict(unit="s", default=0.02, lo=0.0, doc="power order lag")),
        ("Kpg", dict(unit="pu", default=0.1, lo=0.0, doc="power PI proportional gain")),
        ("Kig", dict(unit="1/s", default=10.0, lo=0.0, doc="power PI integral gain")),
        ("vl0", dict(unit="pu", default=0.44, doc="voltage below which all trip")),
        ("vl1", dict(unit="pu", default=0.49, doc="voltage below which a share trips")),
        ("vh0", dict(unit="pu", default=1.2, doc="voltage above which all trip")),
        ("vh1", dict(unit="pu", default=1.15, doc="voltage above which a share trips")),
        ("tvl0", dict(unit="s", default=0.16, lo=0.0, doc="time below vl0 to trip all")),
        ("tvl1", dict(unit="s", default=0.16, lo=0.0, doc="time below vl1 to trip a share")),
        ("tvh0", dict(unit="s", default=0.16, lo=0.0, doc="time above vh0 to trip all")),
        ("tvh1", dict(unit="s", default=0.16, lo=0.0, doc="time above vh1 to trip a share")),
        (
            "Vrfrac",
            dict(unit="", default=0.7, lo=0.0, hi=1.0, doc="share of the tripped that reconnects"),
        ),
        ("fl", dict(unit="pu", default=0.0, doc="frequency below which all trip")),
        ("fh", dict(unit="pu", default=2.0, doc="frequency above which all trip")),
        ("tfl", dict(unit="s", default=99.0, lo=0.0, doc="time below fl to trip")),
        ("tfh", dict(unit="s", default=99.0, lo=0.0, doc="time above fh to trip")),
        ("Tv", dict(unit="s", default=0.02, lo=0.0, doc="lag of the trip multiplier")),
        ("Vpr", dict(unit="pu", default=0.8, doc="voltage below which no frequency trip")),
    ]
    return _columns(col, rows, "da_", "DERA1")


_DERA1_CONTROL_PARAMS = _dera1_control_params(271)

#: the WECC generator/converter interface of a type-3 device (ibr_con ``regc``): REGC_A
#: (PSS/E REGCA1, ANDES 2.0's REGCA1) or REGC_B (PSS/E REGCB1, :mod:`.regcb1`)
REGC_A, REGC_B = 0, 1


def _regcb1_params(col: int) -> tuple[Param, ...]:
    """REGCB1's columns from ``col`` on, prefixed ``gb_`` (PSS/E Model Library REGCB1, the
    WECC REGC_B specification; its Tg and Tfltr are the table's): its flags, the rate
    limits of its current lags (dy/dt, device base, as PSS/E's: not ANDES's Tg dy/dt of a
    REGCA1's Rrpwr, Iqrmax, Iqrmin), the lag Te of its internal voltage, its current
    limit and the source impedance it sits behind (the RAW generator's ZSORCE)."""
    rows: list[tuple[str, dict[str, Any]]] = [
        ("RateFlag", dict(_FLAG, doc="1 Rrpwr bounds the active power, 0 the active current")),
        ("PQFlag", dict(_FLAG, doc="output current limit priority: 1 active, 0 reactive")),
        ("Rrpwr", dict(_DEV_PU, unit="pu/s", default=10.0, lo=0.0, doc="rate of |Ip| (or |P|)")),
        ("Iqrmax", dict(_DEV_PU, unit="pu/s", default=999.0, doc="upper rate of Iq (Q0 > 0)")),
        ("Iqrmin", dict(_DEV_PU, unit="pu/s", default=-999.0, doc="lower rate of Iq (Q0 < 0)")),
        ("Te", dict(unit="s", default=0.02, lo=0.0, doc="internal voltage lag (< 1e-3: none)")),
        ("Imax", dict(_DEV_PU, default=999.0, lo=0.0, doc="output current limit")),
        ("Rsource", dict(unit="pu", lo=0.0, doc="source resistance (device base)")),
        ("Xsource", dict(unit="pu", default=0.2, doc="source reactance (device base)")),
    ]
    return _columns(col, rows, "gb_", "REGCB1")


_REGCB1_PARAMS = _regcb1_params(229)


def _reecd1_params(col: int) -> tuple[Param, ...]:
    """REECD1's columns from ``col`` on (PSS/E Model Library REECD1, the WECC REEC_D
    specification; the rest of its record is REECA1's columns): the compensated voltage
    (``rd_``), the charging share Ke of the active current range, the blocking band, and
    points 5-10 of its voltage-dependent current limits (points 1-4 are REECA1's).
    Impedances, droop and currents on the device base, as PSS/E's."""
    rows: list[tuple[str, dict[str, Any]]] = [
        ("rd_VCMPFLAG", dict(_FLAG, doc="1 |V - (Rc + j Xc) I|, 0 |V| + Kc Q (compensated V)")),
        ("rd_Rc", dict(unit="pu", doc="compensation resistance (device base)")),
        ("rd_Xc", dict(unit="pu", doc="compensation reactance (device base)")),
        ("rd_Tr1", dict(unit="s", lo=0.0, doc="compensated voltage filter (< 1e-3: none)")),
        ("rd_Kc", dict(unit="pu", doc="reactive droop gain (VCMPFLAG 0; device base)")),
        (
            "rd_Ke",
            dict(unit="", lo=0.0, hi=1.0, doc="lower active current limit -Ke Ipmax (1: storage)"),
        ),
        ("rd_Vblkl", dict(unit="pu", default=-99.0, doc="blocked below this filtered voltage")),
        ("rd_Vblkh", dict(unit="pu", default=99.0, doc="blocked above this filtered voltage")),
        ("rd_Tblk", dict(unit="s", lo=0.0, doc="blocking held after the voltage returns")),
        *(
            (f"{a}{j}", dict(unit="pu", doc=f"{curve} point {j}, voltage (0: unused)"))
            for a, curve in (("Vq", "VDL1, Iq limit"), ("Vp", "VDL2, Ip limit"))
            for j in range(5, 11)
        ),
        *(
            (f"{a}{j}", dict(_DEV_PU, doc=f"{curve} point {j}, current"))
            for a, curve in (("Iq", "VDL1, Iq limit"), ("Ip", "VDL2, Ip limit"))
            for j in range(5, 11)
        ),
    ]
    return _columns(col, rows, model="REECD1")


_REECD1_PARAMS = _reecd1_params(238)
#: the ibr_con fields a DG protection sets (``relay`` and its columns)
RELAY_FIELDS = ("relay", *(p.name for p in _RELAY_PARAMS))
#: the ibr_con fields a wind turbine sets (``wind`` and its models' columns)
WIND_FIELDS = ("wind", *(p.name for p in _WIND_PARAMS))
#: the ibr_con fields a REPCA1 sets (``pc_`` and ANDES's name)
REPCA1_FIELDS = tuple(p.name for p in _REPCA1_PARAMS)
#: the ibr_con fields a REECA1 sets (its own columns, its PQFLAG and its Iq filter Tiq)
REECA1_FIELDS = ("pqflag", "tiq", *(p.name for p in _REECA1_PARAMS))


#: every ibr_con column, in column order (the type is a REGCA1, PVD1, ESD1 or DERA1; the codes
#: reec, repc, wind, pll, relay switch the components on)
PARAMS = (
    Param("number", "code", 1, integer=True, doc="converter number"),
    Param("bus", "code", 2, integer=True, doc="bus number"),
    Param(
        "type",
        "code",
        3,
        integer=True,
        choices=(PVD1, ESD1, REGCA1, DERA1),
        label="converter type",
        doc="1 PVD1 (ANDES distributed PV), 2 ESD1 (PVD1 with a state of charge), "
        "3 REGCA1 (WECC renewable generator/converter, constant current commands), "
        "4 DERA1 (WECC aggregated distributed energy resources, PSS/E's DER_A)",
    ),
    Param("mva", "MVA", 4, default=100.0, doc="device base Sn (> 0)"),
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
        choices=(NO_REEC, REECA1, REECB1, REECD1),
        doc="REGCA1's electrical control: 0 none (constant current commands), 1 REECA1, 2 REECB1, "
        "3 REECD1",
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
    *_DERA1_PARAMS,
    Param(
        "regc",
        "code",
        228,
        choices=(REGC_A, REGC_B),
        doc="a REGCA1's (type 3) generator/converter interface: 0 REGC_A (REGCA1), 1 REGC_B "
        "(PSS/E REGCB1: rate-limited current lags, a voltage source behind gb_Rsource + j "
        "gb_Xsource lagged by gb_Te, the output current limit gb_Imax)",
    ),
    *_REGCB1_PARAMS,
    *_REECD1_PARAMS,
    *_DERA1_CONTROL_PARAMS,
    Param(
        "psse",
        "code",
        303,
        choices=(0.0, 1.0),
        doc="the reading of the REEC_A/REEC_B voltage loop and the wind turbine: 0 ANDES 2.0's "
        "(import-andes), 1 PSS/E's Model Library (import-psse's default; OpenIPSL "
        "REECB1.mo, REECA1.mo, WTDTA1.mo): QFLAG 1's V PI on clip(VFLAG ? Q PI (started "
        "at |V0|) : Vref0 (REECB1), Vmin, Vmax) - Vt_filter (REECA1's VFLAG 0 Q reference "
        "|V0| - Vref1), WTDTA1's Freq1 in Hz, WTARA1's pitch theta in degrees (theta0 at "
        "rest), WTPTA1's speed error wt - WTTQA1's wref and its rates on dtheta/dt "
        "(docs/ibr.md 6, 8, 11)",
    ),
)

#: the ibr_con fields the kernels take as given (pu quantities after the base change)
TABLE_FIELDS = tuple(p.name for p in PARAMS if p.name not in ("number", "bus", "mva"))
#: REECA1's lag time constants (each must be >= LBND; its Iq filter is ``tiq``); its Pe
#: filter Tp may also be 0, no filter (PSS/E's reading of Tp = 0)
REECA1_LAGS = ("Trv", "tiq", "Tpfilt", "Tpord")
#: REPCA1's (its lead time constant pc_Tft may be 0)
REPCA1_LAGS = ("pc_Tfltr", "pc_Tfv", "pc_Tp", "pc_Tg", "Twm")
#: fields on the device base that are powers and currents (times Sn/Sb)
POWER_FIELDS = (
    *("qmx", "qmn", "pmx", "dqdv", "ddn", "ialim", "Iolim", "Iqrmax", "Iqrmin"),
    *("QMax", "QMin", "dPmax", "dPmin", "PMAX", "PMIN", "Imax", "pc_Pmax", "pc_Pmin"),
    *(f"{a}{j}" for a in ("Iq", "Ip") for j in range(1, 5)),
    *("wt_H", "wt_DAMP", "wt_Dshaft"),
    *("da_Kqv", "da_Imax", "da_rrpwr", "da_Iqh1", "da_Iql1"),
    *("da_Ddn", "da_Dup", "da_femax", "da_femin", "da_Pmax", "da_Pmin", "da_dPmax"),
    "da_dPmin",
    *("gb_Rrpwr", "gb_Iqrmax", "gb_Iqrmin", "gb_Imax"),
    *(f"{a}{j}" for a in ("Iq", "Ip") for j in range(5, 11)),
)
#: fields that are impedances on the device base (times Sb/Sn): the Q-droop's coupling
#: reactance, REGCB1's source impedance, REECD1's compensation impedance and droop (Q on the
#: device base per pu voltage)
IMPEDANCE_FIELDS = ("xc", "gb_Rsource", "gb_Xsource", "rd_Rc", "rd_Xc", "rd_Kc")
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
    ("NVDL1", "nVDL1"),
    ("NVDL2", "nVDL2"),
    ("POS1", "pos1"),
    ("POS2", "pos2"),
    ("ISIGN", "isign"),
    ("PC_VREF0", "pc_Vref0"),
    ("PC_QLINE0", "pc_Qline0"),
    ("PC_PLINE0", "pc_Pline0"),
    ("PR_V0", "pr_v0"),
    ("DA_VREF", "da_Vref"),
    ("DA_QREF", "da_Qref"),
    ("DA_TANPF", "da_tanpf"),
)
#: the kernels' column of each PACKED name: P[k, C.IALIM]
C = layout("ConverterColumns", PACKED)
