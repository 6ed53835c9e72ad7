"""Converter-interfaced devices (inverter-based resources, ibr_con): one device per row,
built of components as ANDES 2.0 builds them (docs/ibr.md), one module each:

* :mod:`~stabctl.models.converters.pvd1`: PVD1 and ESD1 (types 1, 2; ANDES's distributed
  PV and its storage version), with the bus-frequency measurement;
* :mod:`~stabctl.models.converters.relays`: their DG protection DGPRCT1 / DGPRCTExt
  (``relay``);
* :mod:`~stabctl.models.converters.regca1`: REGCA1 (type 3), the WECC generator/converter
  interface REGC_A, and :mod:`~stabctl.models.converters.regcb1` its REGC_B (PSS/E
  REGCB1, ``regc`` 1) instead;
* :mod:`~stabctl.models.converters.reeca1`: its electrical control REECA1 / REECB1
  (``reec``; a battery's state of charge with ``storage``), and
  :mod:`~stabctl.models.converters.reecd1` REECD1 (WECC REEC_D, built on REECA1's);
* :mod:`~stabctl.models.converters.repca1`: their plant control REPCA1 (``repc``);
* :mod:`~stabctl.models.converters.wind`: the wind turbine's drive train WTDTA1 / WTDS,
  aerodynamics WTARA1, pitch control WTPTA1 and torque control WTTQA1 (``wind``, ``aero``,
  ``pitch``, ``torque``);
* :mod:`~stabctl.models.converters.pll`: the PLL1 whose angle a REGCA1 reads (``pll``);
* :mod:`~stabctl.models.converters.dera1`: DERA1 (type 4), PSS/E's WECC aggregated
  distributed energy resources (DER_A).

Each holds its DYR records (``DYR``), its named slots in the device's state column
(``RG``, ``RE``, ``PC``, ``WT``, ``PL``, ``PV``, ``PR``; read by the kernels as
``x[RE.Pord, k]``), its initialisation and its kernels; the ibr_con columns, the codes
that switch the components on and the packed kernel columns ``C`` are
:mod:`~stabctl.models.converters.table`'s.  This package is the registry: the table's
declaration `CONVERTER`, the state names per type (`STATE_NAMES`, made from the
components' slots), the parameters (`ConverterParams`, `converter_params`) and the
kernels that compose the components into a device (`derivatives`, `drawn_current`) and
initialise it (`initialise`).

Sources: ANDES 2.0 ``andes/models/distributed``, ``renewable``, ``measurement``; blocks
``andes/core/block.py`` and flags ``andes/core/discrete.py``.  Equations, parameters and
the ANDES agreement in docs/ibr.md.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel, njit
from stabctl.errors import CaseError
from stabctl.models.blocks import LBND, lag
from stabctl.models.converters import (
    dera1,
    pll,
    pvd1,
    reeca1,
    reecd1,
    regca1,
    regcb1,
    relays,
    repca1,
    wind,
)
from stabctl.models.converters.dera1 import DA
from stabctl.models.converters.pll import PL, PLL_SLOTS
from stabctl.models.converters.pvd1 import PV, commands
from stabctl.models.converters.reeca1 import RE, REECA1_SLOTS
from stabctl.models.converters.reecd1 import RD
from stabctl.models.converters.regca1 import RG, clamp_states, flat_side_of_lvg
from stabctl.models.converters.regcb1 import GB
from stabctl.models.converters.relays import PR, RELAY_SLOTS
from stabctl.models.converters.repca1 import PC, PLANT_PREF_SLOT, REPCA1_SLOTS, line_measures
from stabctl.models.converters.table import (
    DERA1,
    DGPRCT1,
    DGPRCTEXT,
    ESD1,
    IMPEDANCE_FIELDS,
    NO_PLL,
    NO_REEC,
    NO_RELAY,
    NO_REPC,
    NO_WIND,
    PACKED,
    PARAMS,
    PLL1,
    POWER_FIELDS,
    PVD1,
    REECA1,
    REECA1_FIELDS,
    REECA1_LAGS,
    REECB1,
    REECD1,
    REGC_A,
    REGC_B,
    REGCA1,
    RELAY_FIELDS,
    REPCA1,
    REPCA1_FIELDS,
    REPCA1_LAGS,
    SWITCHED_LAGS,
    TABLE_FIELDS,
    TORQUE_POWER_FIELDS,
    WIND_FIELDS,
    WTDS,
    WTDTA1,
    C,
)
from stabctl.models.converters.wind import WIND_SLOTS, WT
from stabctl.models.declaration import Declared, Family, check_packed, pack, params_class

if TYPE_CHECKING:
    from stabctl.case import Case

__all__ = [
    "CONVERTER",
    "PVD1",
    "ESD1",
    "REGCA1",
    "REGC_A",
    "REGC_B",
    "DERA1",
    "NO_REEC",
    "REECA1",
    "REECB1",
    "REECD1",
    "NO_REPC",
    "REPCA1",
    "NO_WIND",
    "WTDTA1",
    "WTDS",
    "NO_PLL",
    "PLL1",
    "NO_RELAY",
    "DGPRCT1",
    "DGPRCTEXT",
    "REECA1_FIELDS",
    "REPCA1_FIELDS",
    "WIND_FIELDS",
    "RELAY_FIELDS",
    "TABLE_FIELDS",
    "PACKED",
    "C",
    "N_STATES",
    "STATE_NAMES",
    "REECA1_SLOTS",
    "REPCA1_SLOTS",
    "WIND_SLOTS",
    "PLL_SLOTS",
    "RELAY_SLOTS",
    "PLANT_PREF_SLOT",
    "MEMORY_SLOTS",
    "ENERGY_SLOTS",
    "ConverterParams",
    "converter_params",
    "initialise",
    "at_power_flow",
    "drawn_current",
    "voltage_dependent",
    "regc_currents",
    "derivatives",
    "derivatives_at",
    "commands",
    "clamp_states",
    "flat_side_of_lvg",
    "line_measures",
]

# --------------------------------------------------------------------------------------
# the registry: the components, in the order of their DYR records and their slots
# --------------------------------------------------------------------------------------

#: the component modules (each with its ``DYR`` records)
MODULES = (regca1, regcb1, reeca1, reecd1, repca1, wind, dera1)

CONVERTER = Family(
    table="ibr_con",
    min_columns=8,
    key="number",
    key_label="converter",
    params=PARAMS,
    dyr=tuple(m for mod in MODULES for m in mod.DYR),
)


def _state_names(*layouts) -> tuple[str, ...]:
    """The state names of a type built of components with the slot layouts `layouts`
    (`declaration.slots`), in slot order: "" where no component has a slot.

    Raises
    ------
    ValueError
        Two components of the type claim one slot.
    """
    named: dict[int, str] = {}
    for lay in layouts:
        for name, slot in zip(lay._fields, lay):
            if int(slot) in named:
                raise ValueError(f"converter slot {int(slot)} is {named[int(slot)]} and {name}")
            named[int(slot)] = name
    return tuple(named.get(j, "") for j in range(max(named) + 1))


#: state names per converter type, in slot order (slots beyond a type's names, or that a
#: device does not use, `has_state`, are unused, 0): a PVD1's or ESD1's own slots then its
#: protection's; a REGCA1's, its electrical control's (the state of charge first), its plant
#: control's, its wind turbine's, its PLL's, a REGC_B's internal voltage, a REECD1's
STATE_NAMES = {
    PVD1: _state_names(PV, PR),
    ESD1: _state_names(PV, PR),
    REGCA1: _state_names(RG, RE, PC, WT, PL, GB, RD),
    DERA1: _state_names(DA),
}
N_STATES = max(len(names) for names in STATE_NAMES.values())
# the slots every type reads alike (the initialisation writes them for all devices at once)
if (RG.Ip, RG.Iq, RG.V_filter, regca1.SPARE, RE.SOC) != (
    PV.Ip,
    PV.Iq,
    PV.f_lag,
    PV.f_washout,
    PV.SOC,
):
    raise ValueError("a REGCA1's slots 0-4 must be a PVD1's: Ip, Iq, the filter, -, SOC")
if (DA.Ip, DA.Iq) != (PV.Ip, PV.Iq):
    raise ValueError("a DERA1's slots 0-1 must be a PVD1's: Ip, Iq (its injected current)")
#: slots that are not states but the memory of the discrete logic of REECA1 and REPCA1,
#: written in place by the kernels (ANDES's ExtendedEvent timers, its VarHold of Ipmax,
#: the frozen PI outputs, the held error, the plant P reference's commanded increment): at
#: rest they do not move; the linearisation leaves them out (`has_state`)
MEMORY_SLOTS = [int(s) for s in (*reeca1.MEMORY, *repca1.MEMORY, *reecd1.MEMORY)]
#: the slots that integrate energy (ESD1's and a battery's state of charge): at rest only
#: at zero output, so the initial-point check leaves them out (unused, 0, in the other types)
ENERGY_SLOTS = [STATE_NAMES[ESD1].index("SOC")]


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
    (its Q reference: Q0, or with a REECA1's QFLAG Vref1 - |V0|; read as PSS/E's, ``psse``
    1, with QFLAG 1 and VFLAG 0 |V0| - Vref1, else Q0, as a REECD1's), tanpf = Q0/P0 (the
    power-factor reference, 0 where P0 = 0: Qcpf held at Q0), Ipoff = Ipcmd0 - P0/|V0|
    (the REGCA1's Ipcmd less the REECA1's, ANDES's two initial commands summed; 0 for a
    REGC_B, whose Ipcmd0 is P0/|V0|: it has no LVG), Imaxr
    (Imax, 1e8 where <= 0), zVDL1, zVDL2 (1 where the VDL curve has a point not 0: the
    curve applies; all 0, no curve: Imax alone), nVDL1, nVDL2 (a REECD1's: the points its
    ten-point curves use, 0 none);
    REPCA1 (``repc``,
    ANDES repca1.py): the monitored line's end buses (rows bus1_idx, bus2_idx; the
    device's own bus without a line) and their positions pos1, pos2 among the kept buses
    (set by the dynamic model), isign (1 if the device's bus is bus1, else -1: the line
    current counted from it), and the initial compensated voltage pc_Vref0 (its voltage
    reference, ANDES Vref0), line Q pc_Qline0 and P pc_Pline0 (0 elsewhere); pr_v0 the
    initial |V| of the bus (the voltage a DGPRCTExt protection reads); DERA1: its voltage
    reference da_Vref, Q reference da_Qref and power factor da_tanpf = tan(pfaref)
    (`dera1.services`; 0 for the other types)."""

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
    nVDL1: np.ndarray
    nVDL2: np.ndarray
    pos1: np.ndarray
    pos2: np.ndarray
    bus1_idx: np.ndarray
    bus2_idx: np.ndarray
    isign: np.ndarray
    pc_Vref0: np.ndarray
    pc_Qline0: np.ndarray
    pc_Pline0: np.ndarray
    pr_v0: np.ndarray
    da_Vref: np.ndarray
    da_Qref: np.ndarray
    da_tanpf: np.ndarray

    @property
    def n(self) -> int:
        return self.bus_idx.size

    def packed(self) -> np.ndarray:
        """Parameter matrix (n_ibr, len(PACKED)) for the compiled kernels."""
        return pack(self, PACKED)

    def time_constants(self):
        """(label, values, mask) of every time constant that sets a state's speed."""
        esd = self.type == ESD1
        pvd = (self.type == PVD1) | esd
        reg = self.type == REGCA1
        ree = self.reec != NO_REEC
        return (
            *((f"ibr_con {n}", getattr(self, n), self.type == DERA1) for n in dera1.LAGS),
            *(
                (f"ibr_con {n}", getattr(self, n), dera1.switched_on(self, flags))
                for n, flags in dera1.SWITCHED_LAGS
            ),
            ("ibr_con tip", self.tip, pvd),
            ("ibr_con tiq", self.tiq, pvd | ree),
            ("ibr_con Tfm", self.Tfm, (pvd | (self.repc == REPCA1)) & (self.Tfm >= LBND)),
            ("ibr_con Twm", self.Twm, pvd),
            ("ibr_con Tf", self.Tf, esd),
            ("ibr_con Tg", self.Tg, reg),
            ("ibr_con Tfltr", self.Tfltr, reg),
            ("ibr_con gb_Te", self.gb_Te, reg & (self.regc == REGC_B) & (self.gb_Te >= LBND)),
            *((f"ibr_con {n}", getattr(self, n), ree) for n in REECA1_LAGS),
            ("ibr_con Tp", self.Tp, ree & (self.Tp >= LBND)),
            ("ibr_con rd_Tr1", self.rd_Tr1, (self.reec == REECD1) & (self.rd_Tr1 >= LBND)),
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
        act[PV.f_lag] = reg | (self.Tfm >= LBND)  # a REGCA1's voltage filter
        act[PV.f_washout] = ~reg
        act[PV.SOC] = (self.type == ESD1) | self.is_battery
        # REECA1's slots; a PVD1's protection in the same slots is discrete logic, at rest
        # at 0: no state of the linear model
        act[RE.Vt_filter : PC.Vc_filter] = self.reec != NO_REEC
        act[RE.Pe_filter] &= self.Tp >= LBND  # Tp 0: no Pe filter
        act[RE.PIQ] &= (self.VFLAG == 1) & (self.QFLAG == 1)  # else out of the Iq path
        act[PC.Vc_filter :] = self.repc == REPCA1
        act[PC.f_lag_plant] &= self.Tfm >= LBND
        act[WT.wt :] = False
        act[WT.wt] = self.wind != NO_WIND
        act[WT.wg] = act[WT.Tshaft] = self.wind == WTDTA1
        act[WT.Pe_filter_tq : WT.PI_tq + 1] = self.torque == 1
        act[WT.PIc_pitch : WT.theta_pitch + 1] = self.pitch == 1
        act[PL.af_pll : PL.am_pll + 1] = self.pll == PLL1
        act[GB.Ed : GB.Eq + 1] = reg & (self.regc == REGC_B) & (self.gb_Te >= LBND)
        act[RD.Vcmp_filter] = (self.reec == REECD1) & (self.rd_Tr1 >= LBND)
        act[MEMORY_SLOTS] = False
        dera = self.type == DERA1
        act[:, dera] = False
        for name in ("Ip", "Iq", "Vmeas", "Pmeas", "Q_V"):
            act[getattr(DA, name), dera] = True
        freq, trip = self.da_FreqFlag == 1, (self.da_VtripFlag == 1) | (self.da_FtripFlag == 1)
        act[DA.theta_f] |= dera & (freq | (self.da_FtripFlag == 1))
        act[DA.PowerPI] |= dera & freq
        act[DA.Pord] |= dera & freq
        act[DA.Mult] |= dera & trip
        return act


check_packed(ConverterParams, PACKED)


def check_table(t) -> None:
    """Refuse an ibr_con row stabctl does not model, as the table is made (CaseError
    naming the row and field, the table's `_fail`): a lag time constant tip, tiq (PVD1,
    ESD1), Tg, Tfltr (REGCA1), REECA1's (:data:`REECA1_LAGS`; its Tp other than 0, no
    filter), REPCA1's or a DERA1's (`dera1.LAGS`) below 1e-3 s (the current would be an
    algebraic function of the voltage inside the network solution); an electrical
    control ``reec`` or a REGC_B (``regc`` 1) on a device other than a REGCA1; a REGC_B
    with a PLL1, or with an internal voltage lag gb_Te and no source impedance
    (gb_Rsource = gb_Xsource = 0); a DERA1 lag of a control it switches on
    (`dera1.SWITCHED_LAGS`) below 1e-3 s or trip bands out of order (`dera1.check`); a
    wind turbine its models cannot run (`wind.check`).

    Parameters
    ----------
    t : stabctl.case.ConverterTable
        The table being made.

    Raises
    ------
    CaseError
        For the first such row.
    """
    reg = t.type == REGCA1
    ree = t.reec != NO_REEC
    bad = np.flatnonzero(ree & ~reg)
    if bad.size:
        t._fail(bad[0], "reec", "an electrical control drives a REGCA1 (type 3) only")
    bad = np.flatnonzero((t.pll != NO_PLL) & ~reg)
    if bad.size:
        t._fail(bad[0], "pll", "a PLL gives the angle of a REGCA1 (type 3) only")
    gb = t.regc == REGC_B
    bad = np.flatnonzero(gb & ~reg)
    if bad.size:
        t._fail(bad[0], "regc", "a REGC_B is the interface of a REGCA1 (type 3) only")
    bad = np.flatnonzero(gb & (t.pll != NO_PLL))
    if bad.size:
        t._fail(bad[0], "pll", "a REGC_B reads its bus's angle (no PLL1)")
    bad = np.flatnonzero(gb & (t.gb_Te >= LBND) & (t.gb_Rsource == 0) & (t.gb_Xsource == 0))
    if bad.size:
        t._fail(
            bad[0],
            "gb_Xsource",
            "a REGC_B with an internal voltage lag gb_Te needs a source impedance",
        )
    bad = np.flatnonzero((t.relay != NO_RELAY) & reg)
    if bad.size:
        t._fail(bad[0], "relay", "a DG protection trips a PVD1 or ESD1 (types 1, 2) only")
    dera1.check(t)
    bad = np.flatnonzero((t.repc == REPCA1) & ~ree)
    if bad.size:
        t._fail(bad[0], "repc", "a plant control drives an electrical control (reec 1, 2) only")
    wind.check(t, t.reec == REECA1)
    check_lags(t)


def check_lags(t) -> None:
    """Refuse a lag time constant below LBND (1e-3 s) in a row whose models use it: a
    PVD1/ESD1's tip, tiq; a REGCA1's Tg, Tfltr; its controls' lags (REECA1_LAGS,
    REPCA1_LAGS, the filters that 0 switches off when not 0, the lags their flags switch
    on); a DERA1's.  Run before the table's declared bounds (>= 0), so that a negative
    lag is told the bound it has.

    Parameters
    ----------
    t : ConverterTable

    Raises
    ------
    CaseError
        For the first such row, naming the field and the bound.
    """
    reg, ree = t.type == REGCA1, t.reec != NO_REEC
    pvd, pc = (t.type == PVD1) | (t.type == ESD1), (t.repc == REPCA1) & ree
    lags = [("tip", pvd), ("tiq", pvd), ("Tg", reg), ("Tfltr", reg)]
    lags += [(name, t.type == DERA1) for name in dera1.LAGS]
    lags += [(name, dera1.switched_on(t, flags)) for name, flags in dera1.SWITCHED_LAGS]
    lags += [(name, ree) for name in REECA1_LAGS] + [(name, pc) for name in REPCA1_LAGS]
    lags += [("Tp", ree & (t.Tp != 0))]  # REECA1's Pe filter: 0 none
    lags += [("rd_Tr1", (t.reec == REECD1) & (t.rd_Tr1 != 0))]  # REECD1's: 0 none
    lags += [(n, getattr(t, flag) == 1) for flag, names in SWITCHED_LAGS for n in names]
    for name, sel in lags:
        lag = f"must be >= {LBND:g} s (a lag of the converter)"
        t._require(~sel | (getattr(t, name) >= LBND), name, lag)


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
        A DERA1 holding its power factor (PfFlag 1) with |P0| below `dera1.MIN_P_PF`,
        naming the row and field (what the devices' data alone cannot be the table
        refused as it was made, `check_table`).
    """
    t = case.converters
    n = len(t)
    reg = t.type == REGCA1
    gb = t.regc == REGC_B
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
    for name in IMPEDANCE_FIELDS:
        vals[name] = vals[name] / scale
    for name in TORQUE_POWER_FIELDS:
        vals[name] = vals[name] * np.where(t.wq_Tn > 0, t.wq_Tn, t.mva) / case.base_mva
    P0 = t.pfrac * S_gen[idx].real
    Q0 = t.qfrac * S_gen[idx].imag
    a0 = np.angle(V0[idx])
    v0 = np.abs(V0[idx])
    da = dera1.services(vals, t.type, P0, Q0, v0)
    bad = np.flatnonzero((t.type == DERA1) & (t.da_PfFlag == 1) & (np.abs(P0) < dera1.MIN_P_PF))
    if bad.size:
        t._fail(
            bad[0],
            "da_PfFlag",
            f"a DERA1 holding its power factor (1) needs |P0| >= {dera1.MIN_P_PF:g} pu "
            f"(P0 = {P0[bad[0]]:.3g} pu: tan(pfaref) = Q0/P0)",
        )
    with np.errstate(divide="ignore", invalid="ignore"):
        kLVG = np.where(reg, 1.0 / (t.Lvpnt1 - t.Lvpnt0), 0.0)
        kLVPL = np.where(reg, t.Lvplsw * t.Lvpl1 / (t.Brkpt - t.Zerox), 0.0)
        # LVG at the initial voltage, as `regca1._lvg`
        LVG0 = np.where(v0 <= t.Lvpnt0, 0.0, np.where(v0 <= t.Lvpnt1, (v0 - t.Lvpnt0) * kLVG, 1.0))
        LVG0 = np.where(gb, 1.0, LVG0)  # a REGC_B has no LVG
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
        **reeca1.services(
            vals,
            t.reec,
            P0,
            Q0,
            v0,
            np.where(reg, Ipcmd0, 0.0),
            reecd1.initial_voltage(t.reec, vals, P0, Q0, v0),
        ),
        **repca1.services(case, idx),
        pr_v0=v0,
        **da,
    )
    repca1.references(cp, V0)
    wind.torque_limits(cp)
    return cp


@kernel
def drawn_current(P, x, k, v):
    """The current device k draws at its bus as (I_rel, I_fix) at bus voltage magnitude
    v, for the network solution (`stabctl.network.solution.L`): I_rel = -(Ip + j
    Iq) as complex power per pu voltage, so that the injected current is (Ip - j Iq)
    V/|V|; REGCA1 the same with its output currents Ipout, Iqout, which depend on v;
    with a PLL1 the current is set in the PLL's frame, not the bus's: I_fix = -(Ipout - j
    Iqout) exp(j am) drawn whatever V (ANDES regcp1.py), I_rel 0; a REGC_B's output
    currents (`regcb1.currents`, in its bus's frame)."""
    if P[k, C.TYPE] == REGCA1:
        Ipout, Iqout = regc_currents(P, x, k, v)
        if P[k, C.PLL] == PLL1:
            return 0.0j, -(Ipout - 1j * Iqout) * np.exp(1j * x[PL.am_pll, k])
        return -(Ipout + 1j * Iqout), 0.0j
    return -(x[PV.Ip, k] + 1j * x[PV.Iq, k]), 0.0j


@kernel
def regc_currents(P, x, k, v):
    """The output currents (Ipout, Iqout) of REGCA1 k's interface at voltage magnitude v:
    its REGC_A's (`regca1.currents`) or REGC_B's (`regcb1.currents`)."""
    if P[k, C.REGC] == REGC_B:
        return regcb1.currents(P, x, k, v)
    return regca1.currents(P, x, k, v)


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
    its LVPL limit (`regca1.clamp_states`; reach s: the simulator's step, 0 the limit alone),
    its controls' memory updated in place."""
    v = abs(V)
    if P[k, C.TYPE] == DERA1:
        return dera1.derivatives(P, x, k, V, dx)
    if P[k, C.TYPE] == REGCA1:
        Ipout, Iqout = regc_currents(P, x, k, v)
        rot = pll.frame(P, x, k, V)
        S = v * rot * (Ipout + 1j * Iqout)  # Pe + j Qe (ANDES regcp1.py)
        pll.derivatives(P, x, k, V, dx)
        Iq_target = -P[k, C.IQCMD0]
        wind.rest(P, k, dx)
        if P[k, C.REEC] != NO_REEC:
            ext = repca1.control(P, x, k, V, V_nc, S, dx) if P[k, C.REPC] == REPCA1 else 0.0j
            wg, Pref, wr0 = 1.0, P[k, C.P0], 1.0
            if P[k, C.WIND] != NO_WIND:
                wg, Pref, wr0 = wind.reference(P, x, k, S.real, dx)
            ref = Pref + ext
            # the electrical control reads Vd, the voltage in the PLL's frame (|V| without)
            if P[k, C.REEC] == REECD1:
                Ipcmd, Iq_target = reecd1.control(P, x, k, v * rot.real, S, ref, wg, dx)
            else:
                vt = x[RE.Vt_filter, k]  # its voltage control compares the filtered voltage
                Ipcmd, Iq_target = reeca1.control(P, x, k, v * rot.real, S, ref, wg, vt, dx)
            x[RE.Ipcmd_last, k] = Ipcmd + P[k, C.IPOFF]
            if P[k, C.WIND] != NO_WIND:
                wind.mechanics(P, x, k, S.real, wg, wr0, ref.real, dx)
        if P[k, C.REGC] == REGC_B:
            regcb1.derivatives(P, x, k, v, regca1.ipcmd(P, x, k), Iq_target, dx)
            dx[regca1.SPARE, k] = 0.0
        else:
            regca1.derivatives(P, x, k, v, Iq_target, reach, dx)
            dx[GB.Ed, k] = dx[GB.Eq, k] = 0.0
        dx[RE.SOC, k] = pvd1.soc_rate(P, k, S.real)
        return S
    Ipcmd, Iqcmd, dL, dW, fHz = pvd1.algebraic(P, x, k, V)
    if P[k, C.RELAY] != NO_RELAY and relays.protection(P, x, k, fHz, v, dx):
        Ipcmd = Iqcmd = 0.0  # ANDES: Psum, Qsum and the droop's fHz set to 0
    _, dx[PV.Ip, k] = lag(Ipcmd, x[PV.Ip, k], P[k, C.TIP])
    _, dx[PV.Iq, k] = lag(Iqcmd, x[PV.Iq, k], P[k, C.TIQ])
    dx[PV.f_lag, k] = dL
    dx[PV.f_washout, k] = dW
    dx[PV.SOC, k] = pvd1.soc_rate(P, k, v * x[PV.Ip, k])
    return v * x[PV.Ip, k] + 1j * v * x[PV.Iq, k]


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
        the voltage filter |V| (a REGC_B: `regcb1.initial`); with a REECA1, its states
        (`reeca1.initial`; a REECD1's, `reecd1.initial`) and memory (the held outputs:
        their values at the start).
        DERA1: Ip = P0/|V|, Iq = Q0/|V|, its measurements and controls
        (`dera1.initial`).

    Raises
    ------
    CaseError
        A device whose commands at the initial point are not its power-flow P0, Q0 (a
        current limit, a trip curve, the Q droop or the power-order limit active at the
        start); a REGCA1 that does not start at rest at P0, Q0 (LVG 0 at its voltage, Ip
        at the LVPL limit, the high-voltage management or Iolim active; its REECA1's
        references not at rest: a current limit, a frozen start, a PI input not 0); a
        DERA1 that does not start at rest (a current limit active), naming it and the
        fastest-moving state.
    """
    x = np.zeros((N_STATES, cp.n))
    V = V0[cp.bus_idx]
    v = np.abs(V)
    reg = cp.type == REGCA1
    x[PV.Ip], x[PV.Iq] = np.where(reg, cp.Ipcmd0, cp.P0 / v), cp.Q0 / v
    x[RG.V_filter] = np.where(reg, v, 0.0)
    x[PV.SOC] = np.where((cp.type == ESD1) | cp.is_battery, cp.SOCinit, 0.0)
    regcb1.initial(cp, x, v)
    P, Vc, V_nc = at_power_flow(cp, V0)
    if np.any(cp.reec != NO_REEC):
        reeca1.initial(cp, x, v)
        reecd1.initial(cp, x, v)
    if np.any(cp.wind != NO_WIND):
        wind.initial(cp, x)
    repca1.initial(cp, x)
    pll.initial(cp, x, V)
    dera = cp.type == DERA1
    if np.any(dera):
        dera1.initial(cp, x, V)
    for kind, why in ((REGCA1, _REGCA1_AT_REST), (DERA1, _DERA1_AT_REST)):
        if np.any(cp.type == kind):
            _check_at_rest(cp, P, x, Vc, V_nc, kind, why)
    Ip, Iq = commands(P, x, Vc) if cp.n else ((), ())
    for k, (Ipcmd, Iqcmd) in enumerate(zip(Ip, Iq)):
        if reg[k] or dera[k]:
            continue
        if abs(Ipcmd - x[PV.Ip, k]) > 1e-9 or abs(Iqcmd - x[PV.Iq, k]) > 1e-9:
            raise CaseError(
                f"ibr_con row {k + 1}: the converter cannot start at its power-flow point "
                f"P0 = {cp.P0[k]:.6g}, Q0 = {cp.Q0[k]:.6g} pu at |V| = {v[k]:.6g} pu: its "
                f"commands there are Ip = {Ipcmd:.6g}, Iq = {Iqcmd:.6g} pu instead of "
                f"{x[PV.Ip, k]:.6g}, {x[PV.Iq, k]:.6g} (a current limit ialim, a trip curve, the "
                "Q droop or the power-order limit is active at the start)",
                table="ibr_con",
                row=k,
            )
    return x


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


#: why a REGCA1 (with its controls) may not start at rest
_REGCA1_AT_REST = (
    "the low-voltage gain LVG 0, Ip at the LVPL limit, the high-voltage management Volim "
    "or the limit Iolim is active at the start (a REGC_B: its current limit gb_Imax), or "
    "its REECA1's current limits, voltage dip freeze or PI references (a REECD1: also its "
    "blocking band rd_Vblkl, rd_Vblkh)"
)
#: why a DERA1 may not start at rest
_DERA1_AT_REST = (
    "a current limit Imax (with its PQFlag, GenFlag), P0 outside [Pmin, Pmax] (FreqFlag 1) "
    "or a trip band (vl1, vh1, fl, fh) is active at the start"
)


def _check_at_rest(cp: ConverterParams, P, x: np.ndarray, Vc, V_nc, kind: int, why: str) -> None:
    """Refuse a device of type `kind` (REGCA1 with its controls, DERA1) that does not start
    at rest at its power-flow point: x (N_STATES, n_ibr) the initial states, its controls'
    memory filled in place by a first evaluation; P, Vc, V_nc as `at_power_flow` gives
    them; `why` the causes the message names."""
    x0 = x.copy()
    dx = np.zeros_like(x)
    derivatives_at(P, x, Vc, V_nc, dx)  # the held outputs take their initial values
    x_in = x.copy()
    S = derivatives_at(P, x_in, Vc, V_nc, dx)
    act = cp.has_state()
    states = ~np.isin(np.arange(N_STATES), MEMORY_SLOTS)
    name = {REGCA1: "REGCA1", DERA1: "DERA1"}[kind]
    for k in np.flatnonzero(cp.type == kind):
        speed = np.where(act[:, k], np.abs(dx[:, k]), 0.0)
        worst = int(np.argmax(speed))
        gap = abs(S[k] - (cp.P0[k] + 1j * cp.Q0[k]))
        clamped = np.any(x_in[:, k] != x[:, k]) or np.any((x[:, k] != x0[:, k])[states])
        if gap > 1e-9 or speed[worst] > 1e-9 or clamped:
            raise CaseError(
                f"ibr_con row {k + 1}: the {name} cannot start at its power-flow point "
                f"P0 = {cp.P0[k]:.6g}, Q0 = {cp.Q0[k]:.6g} pu at |V| = {abs(Vc[k]):.6g} pu: "
                f"it injects {S[k].real:.6g} + j{S[k].imag:.6g} pu there, its states "
                f"moving at up to {speed[worst]:.3g} pu/s ({STATE_NAMES[kind][worst]}; {why})",
                table="ibr_con",
                row=int(k),
            )
