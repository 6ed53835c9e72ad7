"""The ``exc_con`` table every exciter type reads: its columns (PST manual 3.11 Table 2,
3.13 Table 3, 3.38 Table 15; stabctl's extension columns, docs/pst_models.md 2), the
packed parameter layout of the compiled kernels (`PACKED`, its named columns `E`) and
the pieces several types share (the state every type starts with, `VTR`; the
potential/compound source `potential_source`; the blocks' numpy-boolean flags).

The ``type`` column, the DYR records and the columns only one type reads (its module's
``PARAMS``, after these; packed after `PACKED`, `own`) are declared by the types
themselves (one module per type, :mod:`stabctl.models.exciters`); this module is
imported by every one of them.  Many exc_con columns are read under another name by
another type (the ``alt`` names of PST's Table 2: columns 10-17 are K_E, T_E, ... of the
DC exciters), so the columns are declared here once, not per type.
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import numpy as np

from stabctl._jit.arrays import magnitude
from stabctl._jit.decorators import njit
from stabctl.models.declaration import Limits, Param, layout, own_columns


def upper(*names: str, **renamed: str) -> dict[str, str]:
    """DYR copies of table fields whose PSS/E name is theirs in upper case (``"Vrmax"`` <-
    ``"VRMAX"``), and of ``renamed`` fields (table field=DYR name)."""
    return {**{n: n.upper() for n in names}, **renamed}


#: exc_con columns 2-66 (column 1, the type, is declared by the registry from the types).
#: Bounds: every time constant >= 0 (0 bypasses its block; a lead as a lag) and every gain
#: >= 0 (the regulators, rectifier loading, feedbacks, potential and current sources,
#: field current limiters), under every name a type reads the column by (columns 12-20:
#: the DC and AC exciters' saturation points E1, SE(E1), SE(E2), their K_F, T_F, all >= 0):
#: the parameter tables of IEEE Std 421.5-2016 and the PSS/E Model Library.  K_E (column
#: 10) may be negative (a self-excited DC exciter, IEEE 421.5 DC1A), theta_P (14) and the
#: compensation R_C, X_C (46, 47) take either sign.  What one type's equations need of
#: columns others read otherwise is its module's ``LIMITS``
#: (`stabctl.models.declaration.Limits`)
PARAMS = (
    Param("machine", "code", 2, integer=True, doc="machine number"),
    Param("TR", "s", 3, lo=0.0, doc="input filter time constant"),
    Param("KA", "", 4, lo=0.0, doc="voltage regulator gain"),
    Param("TA", "s", 5, lo=0.0, doc="voltage regulator time constant"),
    Param("TB", "s", 6, lo=0.0, doc="transient gain reduction time constant"),
    Param("TC", "s", 7, lo=0.0, doc="transient gain reduction time constant"),
    Param("Vrmax", "pu", 8, doc="maximum regulator output"),
    Param("Vrmin", "pu", 9, doc="minimum regulator output"),
    Param(
        "VImax",
        "pu",
        10,
        alt="KE",
        doc="ST3, EXST1: max internal signal | DC1/2, EXAC1/ESAC1A, IEEET3: KE exciter constant",
    ),
    Param(
        "VImin",
        "pu",
        11,
        alt="TE",
        doc="ST3, EXST1: min internal signal | DC1/2, EXAC1/ESAC1A, IEEET3: TE exciter time "
        "constant, s",
    ),
    Param(
        "KJ",
        "",
        12,
        alt="E1",
        lo=0.0,
        doc="ST3: first stage regulator gain | DC1/2, EXAC1/ESAC1A: E1, pu",
    ),
    Param(
        "KP",
        "",
        13,
        alt="SE1",
        lo=0.0,
        doc="ST3, IEEET3, ESST4B: potential circuit gain | DC1/2, EXAC1/ESAC1A: SE(E1)",
    ),
    Param(
        "thetaP",
        "deg",
        14,
        alt="E2",
        doc="ST3, ESST4B: potential circuit angle | DC1/2, EXAC1/ESAC1A: E2, pu",
    ),
    Param(
        "KI",
        "",
        15,
        alt="SE2",
        lo=0.0,
        doc="ST3, IEEET3, ESST4B: current circuit gain | DC1/2, EXAC1/ESAC1A: SE(E2)",
    ),
    Param(
        "XL",
        "pu",
        16,
        alt="KF_dc",
        lo=0.0,
        doc="ST3, ESST4B: potential source reactance | DC1/2: KF stabilizer gain",
    ),
    Param(
        "KC",
        "",
        17,
        alt="TF_dc",
        lo=0.0,
        doc="ST3, EXST1, ESST1A, EXAC1, EXAC4, ESAC1A, ESST4B: rectifier loading factor "
        "| DC1/2: TF stabilizer time constant, s",
    ),
    Param(
        "Efdmax",
        "pu",
        18,
        alt="TF2",
        doc="ST3: maximum field voltage | IEEET2: second rate feedback time constant TF2, s",
    ),
    Param(
        "KG",
        "",
        19,
        alt="bus_fed",
        lo=0.0,
        doc="ST3, ESST4B: inner loop feedback constant | smpexc: 1 the output times the "
        "terminal voltage (bus-fed SCRX), 0 not",
    ),
    Param(
        "VGmax",
        "pu",
        20,
        alt="vos_after_va",
        lo=0.0,
        doc="ST3, ESST4B: maximum inner loop feedback | ESST1A: 1 the stabiliser output "
        "added after V_A (PSS/E VOS = 2), 0 at the voltage error (VOS = 1)",
    ),
    Param("KF", "", 21, lo=0.0, doc="EXST1, ESST1A, EXAC1, ESAC1A, IEEET3: rate feedback gain"),
    Param(
        "TF",
        "s",
        22,
        lo=0.0,
        doc="EXST1, ESST1A, EXAC1, ESAC1A, IEEET3: rate feedback time constant",
    ),
    Param(
        "dc_sat",
        "code",
        23,
        choices=(0, 1),
        doc="DC1/2 saturation through (E1, SE1), (E2, SE2): 0 PST's exponential, "
        "1 PSS/E's quadratic",
    ),
    Param(
        "ke_given",
        "code",
        24,
        choices=(0, 1),
        doc="DC1/2: 0 K_E = 0 computed so that V_R starts at 0 (PST), 1 as given (ANDES)",
    ),
    Param(
        "ifd_machine",
        "code",
        25,
        choices=(0, 1),
        doc="ST3: field current of I_N = K_C I_fd / V_E, 0 PST exc_st3's own estimate "
        "E_Isat(E'q) + p6 (E'q - psi_kd) + p7 i_d, 1 the machine's (IEEE 421.5 "
        "I_FD; ANDES esst3a.py XadIfd)",
    ),
    Param("TC1", "s", 26, lo=0.0, doc="ESST1A: second lead time constant"),
    Param("TB1", "s", 27, lo=0.0, doc="ESST1A: second lag time constant"),
    Param(
        "VAmax",
        "pu",
        28,
        doc="ESST1A, ESAC1A: maximum regulator output V_A | ST3: ESST3A's VRMAX on "
        "its regulator lag (with TA_st3a)",
    ),
    Param(
        "VAmin",
        "pu",
        29,
        doc="ESST1A, ESAC1A: minimum regulator output V_A | ST3: ESST3A's VRMIN on "
        "its regulator lag (with TA_st3a)",
    ),
    Param("KLR", "", 30, lo=0.0, doc="ESST1A: field current limiter gain"),
    Param("ILR", "pu", 31, lo=0.0, doc="ESST1A: field current limiter pick-up (machine base)"),
    Param("KD", "", 32, lo=0.0, doc="EXAC1, ESAC1A: demagnetising factor of the field current"),
    Param(
        "VBmax",
        "pu",
        33,
        lo=0.0,
        doc="ST3, ESST4B: upper limit of the source voltage V_B = V_E F_EX (PSS/E "
        "ESST3A, ESST4B VBMAX); IEEET3: of V_B + V_R; 0 none (PST exc_st3)",
    ),
    Param("Kpid_P", "", 34, lo=0.0, doc="AC8B: PID proportional gain | ESST4B: K_PR"),
    Param("Kpid_I", "1/s", 35, lo=0.0, doc="AC8B: PID integral gain | ESST4B: K_IR"),
    Param("Kpid_D", "s", 36, lo=0.0, doc="AC8B: PID derivative gain"),
    Param("Td", "s", 37, lo=0.0, doc="AC8B: PID derivative time constant"),
    Param("VPmax", "pu", 38, doc="AC8B: PID output upper limit"),
    Param("VPmin", "pu", 39, doc="AC8B: PID output lower limit"),
    Param("KPM", "", 40, lo=0.0, doc="ESST4B: inner-loop PI proportional gain"),
    Param("KIM", "1/s", 41, lo=0.0, doc="ESST4B: inner-loop PI integral gain"),
    Param("VMmax", "pu", 42, doc="ESST4B: inner-loop PI output upper limit"),
    Param("VMmin", "pu", 43, doc="ESST4B: inner-loop PI output lower limit"),
    Param(
        "TA_st3a",
        "s",
        44,
        lo=0.0,
        doc="ST3: ESST3A's regulator lag 1/(1 + s T_A) before the inner loop, non-windup "
        "on [VAmin, VAmax] (below 1e-3 s: none, as PST exc_st3)",
    ),
    Param(
        "efd_speed",
        "code",
        45,
        choices=(0, 1),
        doc="1: the field voltage is the exciter's output times the rotor speed (pu), "
        "ANDES 2.0's EXDC2 (exdc2.py vout = omega vp); 0 (default): the output",
    ),
    Param(
        "Rcomp",
        "pu",
        46,
        doc="load compensation resistance R_C, machine base: the voltage transducer's "
        "input is V_C = abs(V_t + (R_C + j X_C) I_t) (IEEE 421.5 load compensator; "
        "PSS/E and ANDES IEEEVC); 0 with X_C: V_t",
    ),
    Param("Xcomp", "pu", 47, doc="load compensation reactance X_C, machine base"),
    Param(
        "psse_st1",
        "code",
        48,
        choices=(0, 1),
        doc="the PSS/E Model Library's reading (import-psse's) of EXST1 and ESST4B: 1 "
        "EXST1's output limits [V_t VRMIN - K_C I_fd, V_t VRMAX - K_C I_fd] and rate "
        "feedback of V_R before them (OpenIPSL's PSSE.ES.EXST1, "
        "PowerSimulationsDynamics.jl), ESST4B's two PIs with non-windup limits, the "
        "integral held while the output is at a limit and driven beyond it (IEEE "
        "421.5-2016 ST4B and E.6; OpenIPSL's PSS/E-verified ESST4B, OPAL-RT's); 0 "
        "(default) EXST1's lower limit V_t VRMIN and the feedback of the field voltage, "
        "ESST4B's tracking anti-windup (ANDES 2.0's PITrackAW, k_s 2)",
    ),
    Param("KB", "", 49, lo=0.0, doc="EXAC2: second stage regulator gain K_B (> 0)"),
    Param("KL", "", 50, lo=0.0, doc="EXAC2: gain of the exciter field current limit signal V_L"),
    Param("KH", "", 51, lo=0.0, doc="EXAC2, ESAC6A: exciter field current feedback gain K_H"),
    Param("VLR", "pu", 52, doc="EXAC2: exciter field current limit reference V_LR"),
    Param(
        "TK",
        "s",
        53,
        lo=0.0,
        doc="ESAC6A: lead time constant of the regulator K_A (1 + s T_K)/(1 + s T_A)",
    ),
    Param("VFELIM", "pu", 54, doc="ESAC6A: exciter field current limit reference"),
    Param(
        "VHMAX", "pu", 55, lo=0.0, doc="ESAC6A: upper limit of the field current limiter signal V_H"
    ),
    Param("TH", "s", 56, lo=0.0, doc="ESAC6A: lag time constant of the field current limiter"),
    Param("TJ", "s", 57, lo=0.0, doc="ESAC6A: lead time constant of the field current limiter"),
    Param(
        "TA1", "s", 58, lo=0.0, doc="EXPIC1: the PI regulator K_A (1 + s T_A1)/s's time constant"
    ),
    Param(
        "TF_2",
        "s",
        59,
        lo=0.0,
        doc="EXPIC1: second lag of the rate feedback s K_F/((1 + s T_F1)(1 + s T_F2))",
    ),
    Param("Efdmin", "pu", 60, doc="EXPIC1: lower limit of E_0 = V_B V_R (Efdmax: column 18)"),
    Param(
        "KP_pic",
        "",
        61,
        lo=0.0,
        doc="EXPIC1: potential circuit gain K_P (real; 0 with K_I: V_B = 1)",
    ),
    Param("KI_pic", "", 62, lo=0.0, doc="EXPIC1: current circuit gain K_I"),
    Param("KFF", "", 63, lo=0.0, doc="ST6B: feed-forward gain of the regulator output V_A"),
    Param("KM", "", 64, lo=0.0, doc="ST6B: gain of the inner loop K_M (V_A - V_G)"),
    Param("KCI", "", 65, lo=0.0, doc="ST6B: field current limiter's current reference factor"),
    Param("TG", "s", 66, lo=0.0, doc="ST6B: lag of the inner loop's field voltage feedback"),
)

#: exc_con field names in column order, the type first
NAMES = ("type", *(p.name for p in PARAMS))


def col(name: str) -> int:
    """1-based exc_con column of field (or alternative name) ``name``."""
    return next(p.col for p in PARAMS if name in (p.name, p.alt))


#: the tracking anti-windup gain of AC8B's PID and ESST4B's two PI regulators (ANDES 2.0
#: ac8b.py config ``ks``, esst4b.py ``ksr``, ``ksm``)
PID_TRACKING = 2.0

#: exc_con fields (stabctl.models.exciters.EXCITER) the kernels take as the table gives them:
#: columns 3-20 (ST3 naming; KP, thetaP are taken as the complex K_P exp(j theta_P)) and
#: 26-32 (ESST1A, EXAC1, ESAC1A), 34-39 (AC8B's PID) and 40-43 (ESST4B's inner loop)
TABLE_FIELDS = tuple(n for n in NAMES[2:20] + NAMES[25:32] + NAMES[33:] if n != "thetaP")

#: the packed parameter matrix of the compiled kernels, (column name, ExciterParams
#: attribute) per column: exc_con columns 1-20 in declared order (the machine's row for
#: the machine number, K_P exp(j theta_P) as its real and imaginary parts), then the
#: derived parameters (IEEET2's T_F2 under its own name) and V_ref
PACKED = (
    ("KIND", "kind"),
    ("MAC", "mac"),
    *((n.upper(), n) for n in TABLE_FIELDS[: TABLE_FIELDS.index("KP")]),
    ("KPR", "KP.real"),
    ("KPI", "KP.imag"),
    *((n.upper(), n) for n in TABLE_FIELDS[TABLE_FIELDS.index("KP") + 1 :]),
    ("TCTB", "tc_tb"),
    ("TC1TB1", "tc1_tb1"),
    ("KE", "KE"),
    ("TE", "TE"),
    ("ASAT", "Asat"),
    ("BSAT", "Bsat"),
    ("KF", "KF"),
    ("TF", "TF"),
    ("TF2", "TF2"),
    ("VREF", "Vref"),
    ("SATQ", "sat_quadratic"),
    ("IFDM", "ifd_machine"),
    ("VBCAP", "VB_cap"),
)
#: the kernels' column of each PACKED name: P[i, E.KA]
E = layout("ExciterColumns", PACKED)


#: a type's own packed columns (its module's ``PARAMS``, the columns no other type reads),
#: ``own("NAMEColumns", PARAMS)``, read by its kernels as ``P[k, O.NAME]``: after the shared
#: `PACKED`, where every type's own columns start (`own_columns`)
own = functools.partial(own_columns, first=len(PACKED))


#: the state slot of the voltage transducer T_R, every type's first state (``S.VTR`` of
#: each type's layout)
VTR = 0

#: ``init=False`` of the source voltage kernels as a numpy boolean: a Python False passed
#: from compiled code is typed as a literal, a second compile of it
RUNNING = np.bool_(False)
#: ``ieee=True`` of the blocks for the models PSTess lacks (ESST1A), a numpy boolean for
#: the same reason
IEEE_RULE = np.bool_(True)


class ST3Machine(NamedTuple):
    """The quantities of an ST3 exciter's machine its source voltage is computed from
    (`st3_source_voltage`), floats but unit: eterm the terminal voltage magnitude (pu),
    unit exp(j theta) of its angle theta (complex, `unit_phasor`), pelect, qelect the
    electrical power (pu on the system base), mac_pot the system base / machine base
    ratio, fldcur the field current (pu on the machine base)."""

    eterm: float
    unit: complex
    pelect: float
    qelect: float
    mac_pot: float
    fldcur: float


@njit
def potential_source(KP, KI, XL, machine):
    """The potential/compound source's V_E = |K_P V_t + j (K_I + K_P X_L) I_t| (IEEE Std
    421.5-2016 ST3A, ST4B; IEEE 1968 type 3 with X_L = 0 and K_P real), pu: KP the complex
    K_P exp(j theta_P), KI, XL (pu), machine the `ST3Machine` quantities (pelect, qelect
    on the system base; I_t on the machine base)."""
    eterm, unit, pelect, qelect, mac_pot, _ = machine
    vt = eterm * unit
    i_t = (pelect - 1j * qelect) / np.conj(vt) * mac_pot
    ve = KP * vt + 1j * (KI + KP * XL) * i_t
    return magnitude(ve.real, ve.imag)


@njit
def unit_phasor(v):
    """exp(j angle(v)) of a complex voltage v, v / |v| (1 for v = 0, as angle(0) = 0):
    the terminal voltage's direction an ST3-type source is built on (`ST3Machine`),
    without the arctangent and the sine and cosine of its angle."""
    m = magnitude(v.real, v.imag)
    return v / m if m > 0.0 else 1.0 + 0.0j


class StatorQuantities(NamedTuple):
    """A machine's terminal quantities as PST exc_st3 flag 1 recomputes them
    (`machines.stator_without_speed`, floats but vt): ed, eq the d, q terminal voltages
    (pu), cd, cq the d, q currents (pu on the system base), et = |ed + j eq| the
    terminal voltage magnitude (pu), vt the terminal bus voltage (complex pu; its angle
    sets the ST3 source phasor)."""

    ed: float
    eq: float
    cd: float
    cq: float
    et: float
    vt: complex


#: the regulator gain K_A > 0 of the types whose start divides by it (the regulator's
#: input at rest V_R0/K_A sets V_ref = V_t + V_R0/K_A: a gain of 0 holds no field
#: voltage; IEEE Std 421.5-2016, PSS/E Model Library: K_A is a regulator gain, > 0)
#: the lead-lag (1 + s T_C)/(1 + s T_B) of every type that has one: a lead without its lag
#: (T_B = 0, T_C > 0) is refused, as IEEEST's and PSS2A's are, rather than bypassed without
#: a word (round 40: EXST1's T_C of 10 s had no effect on the run)
LEAD_LAG = Limits(
    "PSS/E Model Library, IEEE Std 421.5: the regulator's lead-lag (1 + s TC)/(1 + s TB)",
    leads=(("TC", "TB"),),
)
#: ESST1A's second lead-lag (1 + s T_C1)/(1 + s T_B1), as the first
SECOND_LEAD_LAG = Limits(
    "IEEE Std 421.5 ST1A: the second lead-lag (1 + s TC1)/(1 + s TB1)", leads=(("TC1", "TB1"),)
)
#: the regulator gain K_A > 0 of the types whose start divides by it (see above)
REGULATOR_GAIN = Limits(
    "IEEE Std 421.5: the regulator's input at rest is V_R0/K_A", positive=("KA",)
)
