"""REPCA1, the WECC renewable energy plant control (REPC_A; ANDES 2.0
``renewable/repca1.py``) of a REECA1 (ibr_con ``repc`` 1): its DYR record, named slots,
line services and initial references, and its kernels (docs/ibr.md 7).

The reactive path: the compensated voltage (or the monitored line's Q) filtered through
Tfltr, its error through the deadband and limits (held below Vfrz), the tracking PI in
[Qmin, Qmax] and the lead-lag Tft/Tfv give Qext; the frequency path: the droop of the bus
frequency (ANDES BusFreq, `pvd1.bus_frequency`) beyond its deadband plus the line P error,
the tracking PI in [Pmin, Pmax] and the lag Tg give Pext (both PIs ANDES's PITrackAW,
`blocks.pi_track_aw`).  Its parameters are ibr_con columns 106-143 (``pc_``,
:mod:`.table`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel, njit
from stabctl.models.blocks import clip, deadband, lag, leadlag_input_state, pi_track_aw
from stabctl.models.converters import pvd1
from stabctl.models.converters.reeca1 import RE
from stabctl.models.converters.table import REPCA1, C
from stabctl.models.declaration import DyrModel, slots

if TYPE_CHECKING:
    from stabctl.case import Case
    from stabctl.models.converters import ConverterParams


#: REPCA1's CONs in PSS/E order
_REPC_CONS = (
    *("Tfltr", "Kp", "Ki", "Tft", "Tfv", "Vfrz", "Rc", "Xc", "Kc", "emax", "emin", "dbd1"),
    *("dbd2", "Qmax", "Qmin", "Kpg", "Kig", "Tp", "fdbd1", "fdbd2", "femax", "femin"),
    *("Pmax", "Pmin", "Tg", "Ddn", "Dup"),
)

DYR = (
    #: REPC_A: ICONs IREG (0: own bus), the monitored branch's from and to buses and
    #: circuit id (a string, NaN among the numbers), VCFlag, RefFlag, Fflag; 27 CONs
    DyrModel(
        "REPCA1",
        ("IREG", "BUS1", "BUS2", "CKTID", "VCFlag", "RefFlag", "Fflag") + tuple(_REPC_CONS),
        {f"pc_{n}": n for n in ("VCFlag", "RefFlag", "Fflag", *_REPC_CONS)},
    ),
)

#: REPCA1's slots (``repc`` 1): its states, then its memory (the held error, and the plant
#: P reference's increment a storage controller commands, written by the simulator:
#: `stabctl.storage.devices`, ANDES's Plant_pref - Pline0)
REPCA1_SLOTS = (
    *("Vc_filter", "Qline_filter", "PI_plant", "LeadLag_plant"),
    *("f_lag_plant", "f_washout_plant", "Pline_filter", "PI_P_plant", "Pext_lag", "e_held"),
    "Plant_pref_command",
)
#: the named slots, after the electrical control's
PC = slots("REPCA1Slots", REPCA1_SLOTS, first=int(RE[-1]) + 1)
#: the plant P reference's commanded increment (pu, system base, injection +)
PLANT_PREF_SLOT = PC.Plant_pref_command
#: the slots of REPCA1's memory (`MEMORY_SLOTS` of the package)
MEMORY = (PC.e_held, PC.Plant_pref_command)


def services(case: Case, idx: np.ndarray) -> dict[str, np.ndarray]:
    """REPCA1's line services (`ConverterParams`) of the devices on bus rows idx; without
    a line (bus1 = bus2 = 0) both ends the device's bus and isign 0 (`line_measures`:
    ANDES's no-line patch, no line current; PSS/E's reading, the device's own output)."""
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
        "isign": np.where(pc & ~line, 0.0, np.where(b1 == idx, 1.0, -1.0)),
        "pc_Vref0": np.zeros(len(t)),  # `references`
        "pc_Qline0": np.zeros(len(t)),
        "pc_Pline0": np.zeros(len(t)),
    }


def references(cp: ConverterParams, V0: np.ndarray) -> None:
    """REPCA1's initial references in place: pc_Vref0 the selected voltage VCsel,
    pc_Qline0 and pc_Pline0 the line's Q and P at the power-flow voltages V0 (n_bus,)
    (`line_measures`)."""
    P = cp.packed()
    for k in np.flatnonzero(cp.repc == REPCA1):
        ends = (V0[cp.bus_idx[k]], V0[cp.bus1_idx[k]], V0[cp.bus2_idx[k]])
        S0 = complex(P[k, C.P0], P[k, C.Q0])  # the device's output at the power flow
        cp.pc_Vref0[k], Sline = line_measures(P, k, *ends, S0)
        cp.pc_Qline0[k], cp.pc_Pline0[k] = Sline.imag, Sline.real


def initial(cp: ConverterParams, x: np.ndarray) -> None:
    """REPCA1's initial states in x (N_STATES, n_ibr), in place: the filters at VCsel and
    the line's Q and P, its PIs, lead-lag and frequency path at rest at 0."""
    pc = cp.repc == REPCA1
    x[PC.Vc_filter] = np.where(pc, cp.pc_Vref0, 0.0)  # the filters at VCsel, Qline; PI, lead-lag 0
    x[PC.Qline_filter] = np.where(pc, cp.pc_Qline0, 0.0)
    x[PC.Pline_filter] = np.where(pc, cp.pc_Pline0, 0.0)  # the frequency path at rest at 0


@njit(cache=True)
def line_measures(P, k, V, V1, V2, S):
    """REPCA1 k's measured signals at its bus voltage V and its line's end voltages V1,
    V2 (complex pu; ANDES repca1.py Iline, Vcomp, Pline, Qline): the line current from
    the device's bus Iline = isign (V1 - V2)/(r + j x); returns (VCsel, Sline) with Sline
    = Pline + j Qline = isign V1 conj((V1 - V2)/(r + j x)) and VCsel = |V - (Rc + j Xc)
    Iline| (VCFlag 1) or Kc Qline + |V| (VCFlag 0).  Without a monitored line (isign 0):
    PSS/E's reading (``psse`` 1) measures the device's own output S (complex pu, system
    base), Sline = S, Iline = conj(S/V) (GridPACK's plant control fed the generator's
    P, Q, V; Dynawo's WECC plant measuring its terminal; round 52, AL13), where ANDES's
    no-line patch measures nothing (Iline = Sline = 0: a frequency droop then integrates
    to the deadband's edge, a Q control holds Q at nothing)."""
    s = P[k, C.ISIGN]
    if s == 0.0:
        if P[k, C.PSSE] == 1.0:
            Sline = S
            Iline = np.conj(S / V)
        else:
            Sline = Iline = 0.0j
    else:
        Z = P[k, C.PC_R] + 1j * P[k, C.PC_X]
        Iline = s * (V1 - V2) / Z
        Sline = s * V1 * np.conj((V1 - V2) / Z)
    if P[k, C.PC_VCFLAG] == 1.0:
        return abs(V - (P[k, C.PC_RC] + 1j * P[k, C.PC_XC]) * Iline), Sline
    return Sline.imag * P[k, C.PC_KC] + abs(V), Sline


@kernel
def control(P, x, k, V, V_nc, S, dx):
    """REPCA1 (ANDES 2.0 repca1.py, reactive path; docs/ibr.md 7) of device k at its bus
    voltage V with the kept-bus voltages V_nc (its line's ends at columns POS1, POS2): the
    derivatives of its slots written, the held error updated in place; returns ext =
    Pext + j Qext, the increments of its REECA1's P and Q references (pu; `_frequency_path`)."""
    V1, V2 = V_nc[int(P[k, C.POS1])], V_nc[int(P[k, C.POS2])]
    VCsel, Sline = line_measures(P, k, V, V1, V2, S)
    T = P[k, C.PC_TFLTR]
    s0, dx[PC.Vc_filter, k] = lag(VCsel, x[PC.Vc_filter, k], T)
    s1, dx[PC.Qline_filter, k] = lag(Sline.imag, x[PC.Qline_filter, k], T)
    ref = P[k, C.PC_VREF0] - s0 if P[k, C.PC_REFFLAG] == 1.0 else P[k, C.PC_QLINE0] - s1
    db = deadband(ref, P[k, C.PC_DBD1], P[k, C.PC_DBD2])
    enf = clip(db, P[k, C.PC_EMIN], P[k, C.PC_EMAX])
    if abs(V) < P[k, C.PC_VFRZ] and P[k, C.PC_FREEZE] == 1.0:  # held (ANDES VarHold)
        enf = x[PC.e_held, k]
    x[PC.e_held, k] = enf
    y, dx[PC.PI_plant, k] = pi_track_aw(
        enf,
        x[PC.PI_plant, k],
        P[k, C.PC_KP],
        P[k, C.PC_KI],
        P[k, C.PC_QMIN],
        P[k, C.PC_QMAX],
        P[k, C.PC_KQS],
    )
    dx[PC.e_held, k] = 0.0
    Tfv = P[k, C.PC_TFV]
    Qext, dx[PC.LeadLag_plant, k] = leadlag_input_state(
        y, x[PC.LeadLag_plant, k], P[k, C.PC_TFT] / Tfv, Tfv
    )
    return _frequency_path(P, x, k, V, Sline.real, dx) + 1j * Qext


@kernel
def _frequency_path(P, x, k, V, Pline, dx):
    """REPCA1's frequency path of device k (ANDES repca1.py s4-s6): the frequency error
    1 - f (pu; `pvd1.bus_frequency` at its bus) through the deadband [fdbd1, fdbd2] times Ddn
    (negative) or Dup, plus with PLflag Plant_pref - lag(Pline, Tp), Plant_pref = Pline0
    plus the commanded increment in slot `PC.Plant_pref_command` (0 unless a storage controller
    writes it); limited to [femin,
    femax], the tracking PI (Kpg, Kig, ksg) in [Pmin, Pmax] and the lag Tg; returns
    Pext (the increment of its REECA1's P reference), 0 with Fflag 0."""
    f, dx[PC.f_lag_plant, k], dx[PC.f_washout_plant, k] = pvd1.bus_frequency(
        P, x, k, V, PC.f_lag_plant, PC.f_washout_plant
    )
    db = deadband(1.0 - f, P[k, C.PC_FDBD1], P[k, C.PC_FDBD2])
    droop = db * (P[k, C.PC_DDN] if db < 0.0 else P[k, C.PC_DUP])
    s4, dx[PC.Pline_filter, k] = lag(Pline, x[PC.Pline_filter, k], P[k, C.PC_TP])
    e = clip(
        droop + P[k, C.PC_PLFLAG] * (P[k, C.PC_PLINE0] + x[PC.Plant_pref_command, k] - s4),
        P[k, C.PC_FEMIN],
        P[k, C.PC_FEMAX],
    )
    dx[PC.Plant_pref_command, k] = 0.0
    y, dx[PC.PI_P_plant, k] = pi_track_aw(
        e,
        x[PC.PI_P_plant, k],
        P[k, C.PC_KPG],
        P[k, C.PC_KIG],
        P[k, C.PC_PMIN],
        P[k, C.PC_PMAX],
        P[k, C.PC_KSG],
    )
    Pext, dx[PC.Pext_lag, k] = lag(y, x[PC.Pext_lag, k], P[k, C.PC_TG])
    return P[k, C.PC_FFLAG] * Pext
