"""Exciter models: PST `smpexc` (type 0, simple static), `exc_dc12` (types 1 and 2, IEEE
DC1 / DC2 dc commutator exciters), `exc_st3` (type 3, IEEE ST3), stabctl's PSS/E
`EXST1` (type 4, IEEE ST1 simplified), `IEEET2` (type 5: DC1 whose rate feedback has a
second lag, s K_F/((1 + s T_F1)(1 + s T_F2))), `ESST1A` (type 6, IEEE ST1A with its
field current limiter), `EXAC1` (type 7, IEEE AC1 with its rectifier regulation),
`EXAC4` (type 8, IEEE AC4) and `ESAC1A` (type 9, IEEE 421.5 AC1A: EXAC1 whose regulator
V_A and output V_R have limits of their own), `AC8B` (type 10, IEEE 421.5 AC8B: the AC
exciter behind a PID), `IEEET3` (type 11, IEEE 1968 type 3: the compound source added to
the regulator), `ESST4B` (type 12, IEEE 421.5 ST4B: two PI regulators and the
potential/compound source); smpexc also serves PSS/E's SCRX (bus fed:
the output times the terminal voltage, exc_con column 19 ``bus_fed``).

Source: PSTess 1.1 `exc_indx.m`, `smpexc.m`, `exc_dc12.m`, `exc_st3.m` (PST manual 3.11
Table 2, 3.13 Table 3); PSS/E Model Library EXST1 (IEEE Std 421.5 ST1A simplified),
IEEET2 (IEEE Committee Report 1968 type 2), ESST1A (IEEE Std 421.5-2016 ST1A; ANDES 2.0
``esst1a.py``), EXAC1 and EXAC4 (IEEE 1981 AC1, AC4; ANDES 2.0 ``exac1.py``,
``exac4.py``), ESAC1A (IEEE Std 421.5-2005 AC1A; ANDES 2.0 ``esac1a.py``), AC8B (ANDES
2.0 ``ac8b.py``), IEEET3 (ANDES 2.0 ``ieeet3.py``), ESST4B (IEEE Std 421.5-2005 ST4B;
ANDES 2.0 ``esst4b.py``) and SCRX
(bus-fed or solid-fed static exciter); equations, limits and PST's quirks in
docs/pst_models.md section 2.  A time constant below 1e-3 s means the block is
absent (no state).  States, named per type in STATE_NAMES: smpexc (V_TR, V_As, Efd);
exc_st3 (V_TR, V_As, V_R); exc_dc12 (V_TR, V_As, V_R, Efd, R_f); EXST1 (V_TR, V_As, V_R,
R_f); IEEET2 (exc_dc12's and V_F, the second feedback lag); ESST1A (V_TR, V_As, V_A, R_f,
V_As1); EXAC1 (V_TR, V_As, V_R, V_E, R_f); ESAC1A (V_TR, V_As, V_A, V_E, R_f); EXAC4
(V_TR, V_As, V_R); AC8B (V_TR, PID integral, V_R, V_E, PID derivative); IEEET3 (V_TR,
V_As unused, V_R, Efd, R_f); ESST4B (V_TR, PI integral, V_M, inner PI integral).  Units: pu on
the machine base; times in s.

The kernels read the packed parameters by name (`E`, from :data:`PACKED`), are built of
the control blocks of `stabctl.models.blocks`, and are one function per type behind the
family's dispatch on kind (`field_voltage`, `derivatives`, `recorded_efd`); the family
computes the machine quantities a type needs (the source voltage of the types in
:data:`SOURCE_KINDS`, `source_voltage`; the field current of the types in
:data:`READS_IFD`, `field_current`).
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from stabctl._jit.decorators import kernel, njit
from stabctl.errors import CaseError, refuse_initial
from stabctl.models import machines as mac
from stabctl.models.blocks import (
    GAIN_BEFORE,
    GAIN_OVER_T,
    LBND,
    clip,
    lag,
    leadlag_input_state,
    nonwindup,
    nonwindup_lag,
    rectifier_loading,
    washout,
)
from stabctl.models.declaration import (
    Declared,
    DyrModel,
    Family,
    Param,
    beyond,
    check_packed,
    layout,
    pack,
    params_class,
)
from stabctl.models.saturation import quadratic_fit

if TYPE_CHECKING:
    from stabctl.case import Case


# --------------------------------------------------------------------------------------
# exc_con: exciters (PST manual 3.38 Table 15, 3.11 Table 2, 3.13 Table 3; docs 2.3-2.4)
# --------------------------------------------------------------------------------------


def _upper(*names: str, **renamed: str) -> dict[str, str]:
    """DYR copies of table fields whose PSS/E name is theirs in upper case (``"Vrmax"`` <-
    ``"VRMAX"``), and of ``renamed`` fields (table field=DYR name)."""
    return {**{n: n.upper() for n in names}, **renamed}


#: the copies the IEEE 1968 DC records IEEET1 and IEEET2 share (PSS/E Model Library)
_IEEET_COPY = {
    "TR": "TR",
    "KA": "KA",
    "TA": "TA",
    "Vrmax": "VRMAX",
    "Vrmin": "VRMIN",
    "KE": "KE",
    "TE": "TE",
    "KF_dc": "KF",
}

#: ESAC1A's record, every parameter a copy, in the PSS/E Model Library's order
_ESAC1A_COPY = _upper(
    "TR", "TB", "TC", "KA", "TA", "VAmax", "VAmin", "TE", "KF", "TF", "KC", "KD", "KE", "E1",
    "SE1", "E2", "SE2", "Vrmax", "Vrmin",
)  # fmt: skip

EXCITER = Family(
    table="exc_con",
    min_columns=9,
    key="machine",
    key_label="machine",
    params=(
        Param(
            "type",
            "code",
            1,
            integer=True,
            choices=(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12),
            label="exciter type",
            doc="0 simple (smpexc), 1 DC1, 2 DC2 (exc_dc12), 3 ST3 (exc_st3), 4 EXST1, "
            "5 IEEET2 (DC1 with a two-lag rate feedback), 6 ESST1A (IEEE 421.5 ST1A), "
            "7 EXAC1 (IEEE AC1), 8 EXAC4 (IEEE AC4), 9 ESAC1A (IEEE 421.5 AC1A), 10 AC8B "
            "(IEEE 421.5 AC8B, PID regulator), 11 IEEET3 (IEEE 1968 type 3, compound "
            "source), 12 ESST4B (IEEE 421.5 ST4B, PI regulators)",
        ),
        Param("machine", "code", 2, integer=True, doc="machine number"),
        Param("TR", "s", 3, lo=0.0, doc="input filter time constant"),
        Param("KA", "", 4, doc="voltage regulator gain"),
        Param("TA", "s", 5, lo=0.0, doc="voltage regulator time constant"),
        Param("TB", "s", 6, lo=0.0, doc="transient gain reduction time constant"),
        Param("TC", "s", 7, doc="transient gain reduction time constant"),
        Param("Vrmax", "pu", 8, doc="maximum regulator output"),
        Param("Vrmin", "pu", 9, doc="minimum regulator output"),
        Param(
            "VImax",
            "pu",
            10,
            alt="KE",
            doc="ST3, EXST1: max internal signal | DC1/2, EXAC1/ESAC1A, IEEET3: KE exciter "
            "constant",
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
            doc="ST3: first stage regulator gain | DC1/2, EXAC1/ESAC1A: E1, pu",
        ),
        Param(
            "KP",
            "",
            13,
            alt="SE1",
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
            doc="ST3, IEEET3, ESST4B: current circuit gain | DC1/2, EXAC1/ESAC1A: SE(E2)",
        ),
        Param(
            "XL",
            "pu",
            16,
            alt="KF_dc",
            doc="ST3, ESST4B: potential source reactance | DC1/2: KF stabilizer gain",
        ),
        Param(
            "KC",
            "",
            17,
            alt="TF_dc",
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
            doc="ST3, ESST4B: inner loop feedback constant | smpexc: 1 the output times the "
            "terminal voltage (bus-fed SCRX), 0 not",
        ),
        Param(
            "VGmax",
            "pu",
            20,
            alt="vos_after_va",
            doc="ST3, ESST4B: maximum inner loop feedback | ESST1A: 1 the stabiliser output "
            "added after V_A (PSS/E VOS = 2), 0 at the voltage error (VOS = 1)",
        ),
        Param("KF", "", 21, doc="EXST1, ESST1A, EXAC1, ESAC1A, IEEET3: rate feedback gain"),
        Param(
            "TF", "s", 22, doc="EXST1, ESST1A, EXAC1, ESAC1A, IEEET3: rate feedback time constant"
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
        Param("TC1", "s", 26, doc="ESST1A: second lead time constant"),
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
        Param("KLR", "", 30, doc="ESST1A: field current limiter gain"),
        Param("ILR", "pu", 31, doc="ESST1A: field current limiter pick-up (machine base)"),
        Param("KD", "", 32, doc="EXAC1, ESAC1A: demagnetising factor of the field current"),
        Param(
            "VBmax",
            "pu",
            33,
            lo=0.0,
            doc="ST3, ESST4B: upper limit of the source voltage V_B = V_E F_EX (PSS/E "
            "ESST3A, ESST4B VBMAX); IEEET3: of V_B + V_R; 0 none (PST exc_st3)",
        ),
        Param("Kpid_P", "", 34, doc="AC8B: PID proportional gain | ESST4B: K_PR"),
        Param("Kpid_I", "1/s", 35, doc="AC8B: PID integral gain | ESST4B: K_IR"),
        Param("Kpid_D", "s", 36, doc="AC8B: PID derivative gain"),
        Param("Td", "s", 37, lo=0.0, doc="AC8B: PID derivative time constant"),
        Param("VPmax", "pu", 38, doc="AC8B: PID output upper limit"),
        Param("VPmin", "pu", 39, doc="AC8B: PID output lower limit"),
        Param("KPM", "", 40, doc="ESST4B: inner-loop PI proportional gain"),
        Param("KIM", "1/s", 41, doc="ESST4B: inner-loop PI integral gain"),
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
            doc="EXST1: 1 the PSS/E Model Library's output limits [V_t VRMIN - K_C I_fd, "
            "V_t VRMAX - K_C I_fd] and rate feedback of V_R before them (OpenIPSL's "
            "PSSE.ES.EXST1, PowerSimulationsDynamics.jl); 0 (default) the lower limit "
            "V_t VRMIN and the feedback of the field voltage",
        ),
    ),
    dyr=(
        # IEEEVC (the IEEE 1981 load compensator, a record of its own beside the machine's
        # exciter record): R_C, X_C into that exciter's row (stabctl.io.dyr COMPENSATORS)
        DyrModel("IEEEVC", ("RC", "XC"), {"Rcomp": "RC", "Xcomp": "XC"}, andes=("IEEEVC",)),
        # SEXS -> smpexc: T_C = (TA/TB) TB is computed
        DyrModel(
            "SEXS",
            ("TA/TB", "TB", "K", "TE", "EMIN", "EMAX"),
            {"KA": "K", "TA": "TE", "TB": "TB", "Vrmax": "EMAX", "Vrmin": "EMIN"},
            kind=0,
            andes=("SEXS",),
        ),
        *(
            DyrModel(
                name,
                (
                    "TR",
                    "KA",
                    "TA",
                    "TB",
                    "TC",
                    "VRMAX",
                    "VRMIN",
                    "KE",
                    "TE",
                    "KF",
                    "TF1",
                    "Switch",
                    "E1",
                    "SE(E1)",
                    "E2",
                    "SE(E2)",
                ),
                {
                    "TR": "TR",
                    "KA": "KA",
                    "TA": "TA",
                    "TB": "TB",
                    "TC": "TC",
                    "Vrmax": "VRMAX",
                    "Vrmin": "VRMIN",
                    "KE": "KE",
                    "TE": "TE",
                    "KF_dc": "KF",
                    "TF_dc": "TF1",
                },
                kind=kind,
                andes=(name,),
            )
            for name, kind in (("IEEEX1", 1), ("EXDC2", 2), ("ESDC2A", 2), ("ESDC1A", 1))
        ),
        # IEEET1 (IEEE 1968 type 1) -> DC1 (type 1) without the lead-lag (TB = TC = 0)
        DyrModel(
            "IEEET1",
            (
                "TR",
                "KA",
                "TA",
                "VRMAX",
                "VRMIN",
                "KE",
                "TE",
                "KF",
                "TF",
                "Switch",
                "E1",
                "SE(E1)",
                "E2",
                "SE(E2)",
            ),
            {**_IEEET_COPY, "TF_dc": "TF"},
            kind=1,
            andes=("IEEET1",),
        ),
        # IEEET2 -> DC1 (type 5) with the rate feedback s KF/((1 + s TF1)(1 + s TF2))
        DyrModel(
            "IEEET2",
            (
                "TR",
                "KA",
                "TA",
                "VRMAX",
                "VRMIN",
                "KE",
                "TE",
                "KF",
                "TF1",
                "TF2",
                "E1",
                "SE(E1)",
                "E2",
                "SE(E2)",
            ),
            {**_IEEET_COPY, "TF_dc": "TF1", "TF2": "TF2"},
            kind=5,
        ),
        # SCRX -> smpexc: T_C = (TA/TB) TB computed; CSWITCH 0 (bus fed): bus_fed = 1
        DyrModel(
            "SCRX",
            ("TA/TB", "TB", "K", "TE", "EMIN", "EMAX", "CSWITCH", "rc/rfd"),
            {"KA": "K", "TA": "TE", "TB": "TB", "Vrmax": "EMAX", "Vrmin": "EMIN"},
            kind=0,
        ),
        DyrModel(
            "EXST1",
            ("TR", "VIMAX", "VIMIN", "TC", "TB", "KA", "TA", "VRMAX", "VRMIN", "KC", "KF", "TF"),
            _upper(
                "TR", "KA", "TA", "TB", "TC", "Vrmax", "Vrmin", "VImax", "VImin", "KC", "KF", "TF"
            ),
            kind=4,
            andes=("EXST1",),
        ),
        # EXAC1 -> type 7 (IEEE 1981 AC1); saturation: PSS/E's quadratic through the points
        DyrModel(
            "EXAC1",
            (
                "TR",
                "TB",
                "TC",
                "KA",
                "TA",
                "VRMAX",
                "VRMIN",
                "TE",
                "KF",
                "TF",
                "KC",
                "KD",
                "KE",
                "E1",
                "SE(E1)",
                "E2",
                "SE(E2)",
            ),
            _upper(
                "TR",
                "TB",
                "TC",
                "KA",
                "TA",
                "Vrmax",
                "Vrmin",
                "TE",
                "KF",
                "TF",
                "KC",
                "KD",
                "KE",
                "E1",
                "E2",
                SE1="SE(E1)",
                SE2="SE(E2)",
            ),
            kind=7,
            andes=("EXAC1",),
        ),
        # EXAC4 -> type 8 (IEEE 1981 AC4)
        DyrModel(
            "EXAC4",
            ("TR", "VIMAX", "VIMIN", "TC", "TB", "KA", "TA", "VRMAX", "VRMIN", "KC"),
            _upper("TR", "VImax", "VImin", "TC", "TB", "KA", "TA", "Vrmax", "Vrmin", "KC"),
            kind=8,
            andes=("EXAC4",),
        ),
        # ESAC1A -> type 9 (IEEE 421.5 AC1A): EXAC1 with V_A limited to [VAMIN, VAMAX] and
        # V_R to [VRMIN, VRMAX]; the saturation points named as ANDES's psse-dyr.yaml
        # names them (its inputs, in its own order, are matched by name)
        DyrModel(
            "ESAC1A",
            tuple(_ESAC1A_COPY.values()),
            _ESAC1A_COPY,
            kind=9,
            andes=("ESAC1A",),
        ),
        # AC8B -> type 10 (IEEE 421.5 AC8B as PowerWorld's AC8B record and ANDES 2.0
        # ac8b.py): ANDES's parameter names and order; VFEMAX and VEMIN, which ANDES's
        # model leaves out, are not read
        DyrModel(
            "AC8B",
            (
                "TR",
                "kP",
                "kI",
                "kD",
                "Td",
                "VPMAX",
                "VPMIN",
                "VRMAX",
                "VRMIN",
                "VFEMAX",
                "VEMIN",
                "TA",
                "KA",
                "TE",
                "KC",
                "KD",
                "KE",
                "E1",
                "SE1",
                "E2",
                "SE2",
            ),
            _upper(
                "TR",
                "VPmax",
                "VPmin",
                "Vrmax",
                "Vrmin",
                "TA",
                "KA",
                "TE",
                "KC",
                "KD",
                "KE",
                "E1",
                "SE1",
                "E2",
                "SE2",
                Kpid_P="kP",
                Kpid_I="kI",
                Kpid_D="kD",
                Td="Td",
            ),
            kind=10,
            andes=("AC8B",),
        ),
        # IEEET3 -> type 11 (IEEE 1968 type 3), PSS/E's CON order (ANDES's psse-dyr.yaml
        # lists VBMAX and KE elsewhere; its inputs are matched by name)
        DyrModel(
            "IEEET3",
            ("TR", "KA", "TA", "VRMAX", "VRMIN", "TE", "KF", "TF", "KP", "KI", "VBMAX", "KE"),
            _upper(
                "TR",
                "KA",
                "TA",
                "Vrmax",
                "Vrmin",
                "KF",
                "TF",
                "KP",
                "KI",
                "VBmax",
                TE="TE",
                KE="KE",
            ),
            kind=11,
            andes=("IEEET3",),
        ),
        # ESST4B -> type 12 (IEEE 421.5 ST4B); VGmax, which PSS/E's record lacks, is set
        # by its mapper
        DyrModel(
            "ESST4B",
            (
                "TR",
                "KPR",
                "KIR",
                "VRMAX",
                "VRMIN",
                "TA",
                "KPM",
                "KIM",
                "VMMAX",
                "VMMIN",
                "KG",
                "KP",
                "KI",
                "VBMAX",
                "KC",
                "XL",
                "THETAP",
            ),
            _upper(
                "TR",
                "Vrmax",
                "Vrmin",
                "TA",
                "KPM",
                "KIM",
                "VMmax",
                "VMmin",
                "KG",
                "KP",
                "KI",
                "VBmax",
                "KC",
                "XL",
                "thetaP",
                Kpid_P="KPR",
                Kpid_I="KIR",
            ),
            kind=12,
            andes=("ESST4B",),
        ),
        # ESST1A -> type 6; UEL (no under-excitation limiter is modelled: no signal) and
        # VOS (1: the stabiliser at the voltage error) are checked by the mapper
        DyrModel(
            "ESST1A",
            (
                "UEL",
                "VOS",
                "TR",
                "VIMAX",
                "VIMIN",
                "TC",
                "TB",
                "TC1",
                "TB1",
                "KA",
                "TA",
                "VAMAX",
                "VAMIN",
                "VRMAX",
                "VRMIN",
                "KC",
                "KF",
                "TF",
                "KLR",
                "ILR",
            ),
            _upper(
                "TR",
                "VImax",
                "VImin",
                "TC",
                "TB",
                "TC1",
                "TB1",
                "KA",
                "TA",
                "VAmax",
                "VAmin",
                "Vrmax",
                "Vrmin",
                "KC",
                "KF",
                "TF",
                "KLR",
                "ILR",
            ),
            kind=6,
            andes=("ESST1A",),
        ),
        # ESST3A -> exc_st3: its KA is PST's K_J, its inner loop KM/(1 + s TM) limited
        # [VMMIN, VMMAX] PST's K_A/(1 + s T_A); VBMAX limits V_B (column 33); its
        # regulator lag 1/(1 + s TA) on [VRMIN, VRMAX] columns 44, 28-29 (none for TA
        # = 0); Efdmax = VBMAX VMMAX is computed
        DyrModel(
            "ESST3A",
            (
                "TR",
                "VIMAX",
                "VIMIN",
                "KM",
                "TC",
                "TB",
                "KA",
                "TA",
                "VRMAX",
                "VRMIN",
                "KG",
                "KP",
                "KI",
                "VBMAX",
                "KC",
                "XL",
                "VGMAX",
                "THETAP",
                "TM",
                "VMMAX",
                "VMMIN",
            ),
            {
                "TR": "TR",
                "KA": "KM",
                "TA": "TM",
                "TB": "TB",
                "TC": "TC",
                "Vrmax": "VMMAX",
                "Vrmin": "VMMIN",
                "VImax": "VIMAX",
                "VImin": "VIMIN",
                "KJ": "KA",
                "KP": "KP",
                "thetaP": "THETAP",
                "KI": "KI",
                "XL": "XL",
                "KC": "KC",
                "KG": "KG",
                "VGmax": "VGMAX",
                "VBmax": "VBMAX",
                "TA_st3a": "TA",
                "VAmax": "VRMAX",
                "VAmin": "VRMIN",
            },
            kind=3,
            andes=("ESST3A",),
        ),
    ),
)

SMP, DC1, DC2, ST3, ST1, T2, ST1A, AC1, AC4, AC1A, AC8B, T3, ST4B = range(13)
STATE_NAMES = {
    SMP: ("VTR", "VAs", "Efd"),
    ST3: ("VTR", "VAs", "VR", "VA"),
    DC1: ("VTR", "VAs", "VR", "Efd", "Rf"),
    DC2: ("VTR", "VAs", "VR", "Efd", "Rf"),
    ST1: ("VTR", "VAs", "VR", "Rf"),
    T2: ("VTR", "VAs", "VR", "Efd", "Rf", "VF"),
    ST1A: ("VTR", "VAs", "VA", "Rf", "VAs1"),
    AC1: ("VTR", "VAs", "VR", "VE", "Rf"),
    AC4: ("VTR", "VAs", "VR"),
    AC1A: ("VTR", "VAs", "VA", "VE", "Rf"),
    AC8B: ("VTR", "PIDi", "VR", "VE", "PIDd"),
    T3: ("VTR", "VAs", "VR", "Efd", "Rf"),
    ST4B: ("VTR", "PIi", "VM", "PIMi"),
}
#: the types whose equations read the machine's field current (`field_current`)
READS_IFD = (ST1, ST1A, AC1, AC4, AC1A, AC8B, T3, ST4B)
#: the types with a rate feedback s K_F/(1 + s T_F) from exc_con columns 21-22 (the DC
#: exciters read theirs from columns 16-17): EXST1, ESST1A, EXAC1, ESAC1A, IEEET3
RATE_FEEDBACK = (ST1, ST1A, AC1, AC1A, T3)
#: the types fed by a potential (and compound) source V_B computed from the machine's
#: terminal voltage and current (`source_voltage`): ST3, IEEET3, ESST4B
SOURCE_KINDS = (ST3, T3, ST4B)
#: the AC exciters with an exciter voltage V_E and PSS/E's quadratic saturation: EXAC1,
#: ESAC1A, AC8B
AC_KINDS = (AC1, AC1A, AC8B)
#: the tracking anti-windup gain of AC8B's PID and ESST4B's two PI regulators (ANDES 2.0
#: ac8b.py config ``ks``, esst4b.py ``ksr``, ``ksm``)
PID_TRACKING = 2.0

#: exc_con fields (stabctl.models.exciters.EXCITER) the kernels take as the table gives them:
#: columns 3-20 (ST3 naming; KP, thetaP are taken as the complex K_P exp(j theta_P)) and
#: 26-32 (ESST1A, EXAC1, ESAC1A), 34-39 (AC8B's PID) and 40-43 (ESST4B's inner loop)
TABLE_FIELDS = tuple(
    n for n in EXCITER.names[2:20] + EXCITER.names[25:32] + EXCITER.names[33:] if n != "thetaP"
)
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
DC_KINDS = (DC1, DC2, T2)


@params_class(("kind", "mac"), TABLE_FIELDS)
class ExciterParams(Declared):
    """Exciter data of a case, arrays of shape (n_exc,): ``kind`` the exc_con type,
    ``mac`` the machine's row (index), then the exc_con fields :data:`TABLE_FIELDS` under
    their declared names (stabctl.models.exciters.EXCITER; KP the complex K_P exp(j
    theta_P), KA = 0 read as 1 for the regulated types), then the derived fields below.
    DC exciters (types 1, 2): KE, TE and the saturation SE(E) = Asat exp(Bsat |E|), or
    with sat_quadratic SE(E) E = Bsat (E - Asat)^2 above Asat (0 for the other types);
    ke_given: KE used as given (else 0 means computed at initialisation); KF, TF: rate
    feedback of the DC exciters and EXST1; ifd_machine: ST3 whose I_N takes the machine's
    field current, not PST exc_st3's estimate (exc_con column 25); VB_cap: the ST3 source
    voltage's upper limit (exc_con column 33, VBmax; inf where 0 or not ST3)."""

    KE: np.ndarray
    TE: np.ndarray
    Asat: np.ndarray
    Bsat: np.ndarray
    KF: np.ndarray
    TF: np.ndarray
    sat_quadratic: np.ndarray
    ke_given: np.ndarray
    ifd_machine: np.ndarray
    VB_cap: np.ndarray

    @property
    def n(self) -> int:
        return self.kind.size

    def packed(self, Vref: np.ndarray) -> np.ndarray:
        """Parameter matrix (n_exc, len(PACKED)) for the compiled kernels, with Vref, columns
        as :data:`PACKED`."""
        return pack(self, PACKED, Vref=Vref)

    @property
    def has_TR(self):
        return self.TR >= LBND

    @property
    def has_TB(self):
        return self.TB >= LBND

    @property
    def has_pid_d(self):
        """AC8B with the PID's derivative branch (K_D != 0, T_D >= 1e-3 s)."""
        return (self.kind == AC8B) & (self.Kpid_D != 0) & (self.Td >= LBND)

    @property
    def has_TA(self):
        return self.TA >= LBND

    @property
    def is_dc(self):
        """DC exciters: DC1, DC2 and IEEET2."""
        return np.isin(self.kind, DC_KINDS)

    @property
    def has_VF(self):
        """IEEET2 with a second rate-feedback lag (T_F2 >= 1e-3 s, exc_con column 18)."""
        return self.TF2 >= LBND

    @property
    def TF2(self):
        """IEEET2's second rate-feedback time constant T_F2 (s; exc_con column 18, read
        as Efdmax by the other types), 0 for the other types."""
        return np.where(self.kind == T2, self.Efdmax, 0.0)

    @property
    def tc_tb(self):
        """T_C/T_B where the lead-lag exists, 1 otherwise (PST exc_pot column 5)."""
        return np.where(self.has_TB, self.TC / np.where(self.has_TB, self.TB, 1.0), 1.0)

    @property
    def is_ac(self):
        """AC exciters (EXAC1, ESAC1A): the exciter voltage V_E and the rectifier
        regulation."""
        return np.isin(self.kind, AC_KINDS)

    @property
    def has_TB1(self):
        """ESST1A's second lead-lag exists (T_B1 >= 1e-3 s)."""
        return (self.kind == ST1A) & (self.TB1 >= LBND)

    @property
    def tc1_tb1(self):
        """ESST1A's T_C1/T_B1 where its second lead-lag exists, 1 otherwise."""
        return np.where(self.has_TB1, self.TC1 / np.where(self.has_TB1, self.TB1, 1.0), 1.0)

    def n_slots(self) -> int:
        """State slots per exciter: the most any exciter of the case uses (3 if none; an ST3
        uses its fourth, ESST3A's regulator lag, only with T_A)."""
        used = [len(STATE_NAMES[int(k)]) for k in self.kind]
        return max(
            [3, *(u - (k == ST3 and not a) for u, k, a in zip(used, self.kind, self.has_TA3A))]
        )

    @property
    def has_TA3A(self):
        """ST3 with ESST3A's regulator lag (T_A >= 1e-3 s, exc_con column 44)."""
        return (self.kind == ST3) & (self.TA_st3a >= LBND)

    def has_state(self) -> np.ndarray:
        """Boolean (n_slots, n_exc): the slots that are states (docs/modal.md)."""
        act = np.zeros((6, self.n), bool)
        act[0], act[1] = self.has_TR, self.has_TB | (self.kind == AC8B)
        act[1] |= (self.kind == ST4B) & (self.Kpid_I != 0)  # the regulator PI's integral
        act[2] = (self.kind == ST3) | self.has_TA
        t3, st4b = self.kind == T3, self.kind == ST4B
        act[3] = self.has_Rf | self.is_ac | t3 | (st4b & (self.KIM != 0)) | self.has_TA3A
        act[4] = self.is_dc | self.has_TB1 | ((self.is_ac | t3) & self.has_Rf) | self.has_pid_d
        act[5] = self.has_VF
        return act[: self.n_slots()]

    @property
    def has_Rf(self):
        """The rate-feedback state exists: DC exciters, and :data:`RATE_FEEDBACK` types with
        K_F != 0."""
        return self.is_dc | (np.isin(self.kind, RATE_FEEDBACK) & (self.KF != 0))

    def time_constants(self):
        """(label, values, mask) of every time constant that sets a state's speed."""
        return (
            ("exc_con T_R", self.TR, self.has_TR),
            ("exc_con T_A", self.TA, self.has_TA),
            ("exc_con T_B", self.TB, self.has_TB),
            ("exc_con T_B1", self.TB1, self.has_TB1),
            ("exc_con TA_st3a", self.TA_st3a, self.has_TA3A),
            ("exc_con T_E", self.TE, self.is_dc | self.is_ac | (self.kind == T3)),
            ("exc_con T_F", self.TF, self.has_Rf),
            ("exc_con T_F2", self.TF2, self.has_VF),
            ("exc_con T_D", self.Td, self.has_pid_d),
        )

    def inner_loop_time_constants(self, VB0: np.ndarray, efd0: np.ndarray) -> np.ndarray:
        """The time constant of each exciter's fast closed loop at the operating point (s),
        (n_exc,), which no single time constant of its data shows; inf where there is none.

        * ST3 (ESST3A's K_M, T_M; PST exc_st3): T_A dV_R/dt = K_A (V_A - K_G E_fd) - V_R
          with E_fd = V_B V_R closes the pole -(1 + K_A K_G V_B)/T_A: T_A / (1 + K_A K_G
          V_B0) where the feedback is below VGmax (K_G E_fd0 < VGmax) and T_A > 0.
          ANDES's kundur_esst3a: K_M = 500, T_M = 0.1 s, V_B = 4.3, 4.6e-5 s where T_M
          suggests 0.1 s.
        * EXST1 and ESST1A with a rate feedback (`rate_feedback_time_constants`).

        Parameters
        ----------
        VB0 : ndarray, shape (n_exc,)
            The source voltages at the operating point (`initial_source_voltage`), pu.
        efd0 : ndarray, shape (n_exc,)
            The field voltages at the operating point, pu.

        Returns
        -------
        ndarray, shape (n_exc,)
        """
        loop = (self.kind == ST3) & (self.TA > 0) & (self.KG * efd0 < self.VGmax)
        gain = 1.0 + self.KA * self.KG * VB0
        st3 = np.where(loop, self.TA / np.where(loop, gain, 1.0), np.inf)
        return np.minimum(st3, self.rate_feedback_time_constants())

    def rate_feedback_time_constants(self) -> np.ndarray:
        """The fastest pole of the EXST1 and ESST1A regulator loops (s), (n_exc,); inf for
        the others and where T_A or T_F is below 1e-3 s or K_F = 0.

        The lead-lags T_C/T_B (and ESST1A's T_C1/T_B1) feed the lag K_A/(1 + s T_A)
        (state V_R, V_A), whose output returns through s K_F/(1 + s T_F) (state R_f) to
        the voltage error: the linear loop of those states (limits inactive, the terminal
        voltage and field current held), whose fastest eigenvalue's time constant is
        returned.  PSID's ESST1A run of PSS/E's (K_A = 200, T_A = 0.1 s, K_F = T_F =
        0.01 s, lead-lags 14.1/20 s): 9.0e-4 s where T_F suggests 0.01 s, and Heun at
        5 ms diverges.

        Returns
        -------
        ndarray, shape (n_exc,)
        """
        tau = np.full(self.n, np.inf)
        loop = np.isin(self.kind, (ST1, ST1A)) & self.has_Rf & self.has_TA & (self.TF >= LBND)
        for i in np.nonzero(loop)[0]:
            lags = [(r[i], T[i]) for r, T, on in ((self.tc_tb, self.TB, self.has_TB),
                    (self.tc1_tb1, self.TB1, self.has_TB1)) if on[i]]  # fmt: skip
            n = len(lags)
            A = np.zeros((n + 2, n + 2))  # lead-lag states, V_A, R_f
            kf = self.KF[i] / self.TF[i]
            u = np.zeros(n + 2)  # the voltage error: -K_F/T_F (V_A - R_f)
            u[n], u[n + 1] = -kf, kf
            for k, (r, T) in enumerate(lags):  # PST form: y = r u + (1 - r) x
                A[k] = u / T
                A[k, k] -= 1.0 / T
                u = r * u
                u[k] += 1.0 - r
            A[n] = self.KA[i] * u / self.TA[i]
            A[n, n] -= 1.0 / self.TA[i]
            A[n + 1, n], A[n + 1, n + 1] = 1.0 / self.TF[i], -1.0 / self.TF[i]
            tau[i] = 1.0 / np.max(-np.linalg.eigvals(A).real)
        return tau


check_packed(ExciterParams, PACKED, ("Vref",))


def _dc_saturation(e) -> tuple[np.ndarray, np.ndarray]:
    """(Asat, Bsat) of the DC exciters' saturation from exc_con columns 12-15.

    dc_sat 0, PST exc_dc12's SE(E) = Asat exp(Bsat |E|): E2 (column 14) = 0 means columns
    13, 15 are Asat, Bsat themselves; otherwise PST's fit through (E1, SE1), (E2, SE2) --
    **QUIRK**: Bsat = ln(SE2 E2 / (SE1 E1)) / (E2 - E1), Asat = SE1 exp(-Bsat E1), so
    SE(E1) = SE1 but SE(E2) = SE2 E2 / E1 (docs 2.3).  dc_sat 1, and EXAC1/ESAC1A always, the
    quadratic SE(E) E = Bsat (E - Asat)^2 through both points (PSS/E; ANDES
    `ExcQuadSat`)."""
    A, B = _exponential_fit(e)
    quad = (e.dc_sat == 1) | np.isin(e.type, AC_KINDS)
    if quad.any():
        Aq, Bq = quadratic_fit(
            *_dc_points(e),
            quad,
            "exc_con row {row}: DC exciter saturation points (E1, SE1, E2, SE2)",
        )
        A, B = np.where(quad, Aq, A), np.where(quad, Bq, B)
    return A, B


def _dc(e, name: str) -> np.ndarray:
    """exc_con column of a DC exciter quantity by its PST manual 3.11 Table 2 name (the
    declaration's ``alt`` name: KE, TE, E1, SE1, E2, SE2, KF_dc, TF_dc)."""
    return e.col(EXCITER.col(name))


def _dc_points(e):
    """The DC exciters' saturation points E1, SE1, E2, SE2 (exc_con columns 12-15)."""
    return tuple(_dc(e, name) for name in ("E1", "SE1", "E2", "SE2"))


def _exponential_fit(e):
    E1, SE1, E2, SE2 = _dc_points(e)
    fit = (E2 != 0) & (e.dc_sat == 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        B = np.where(fit, np.log(SE2 * E2 / (SE1 * E1)) / (E2 - E1), SE2)
        A = np.where(fit, SE1 / np.exp(B * E1), SE1)
    bad = np.nonzero(np.isin(e.type, DC_KINDS) & (e.dc_sat == 0))[0]
    bad = bad[~np.isfinite(A[bad] + B[bad])]
    if bad.size:
        raise CaseError(
            f"exc_con row {bad[0] + 1}: DC exciter saturation points (E1, SE1, E2, "
            "SE2) give no exponential fit (need E1 != E2, SE1 E1 > 0, SE2 E2 > 0)"
        )
    return A, B


def _check_dc(e) -> None:
    """DC exciter, EXST1 and ESST1A options stabctl does not model: raise CaseError naming
    row and field (T_E, T_F must exist, T_A but in the DC exciters; Vrmax = 0 is PST's
    'compute it')."""
    # (name in messages, declared); a DC regulator without T_A is PST's algebraic V_R
    dc = (("TE", "TE"), ("TF", "TF_dc"))
    need = {
        DC1: dc,
        DC2: dc,
        T2: dc,
        ST1: (("TA", "TA"),),
        ST1A: (("TA", "TA"),),
        AC1: (("TA", "TA"), ("TE", "TE")),
        AC4: (("TA", "TA"),),
        AC1A: (("TA", "TA"), ("TE", "TE")),
        AC8B: (("TA", "TA"), ("TE", "TE")),
        T3: (("TA", "TA"), ("TE", "TE")),
        ST4B: (),  # T_A = 0: no lag (PSS/E), `_st4b_field_voltage`
    }
    for r in np.nonzero(np.isin(e.type, (*DC_KINDS, *READS_IFD)))[0]:
        kind = int(e.type[r])
        extra = (("TF", "TF"),) if kind in RATE_FEEDBACK and e.KF[r] != 0 else ()
        for name, declared in need[kind] + extra:
            k = EXCITER.col(declared)
            if e.col(k)[r] < LBND:
                raise CaseError(
                    f"exc_con row {r + 1}, field '{name}' (column {k}): exciter "
                    f"type {kind} needs {name} >= {LBND} s"
                )
        if kind not in READS_IFD and e.Vrmax[r] == 0:
            raise CaseError(
                f"exc_con row {r + 1}, field 'Vrmax': 0 (PST computes it from E2) "
                "is not supported; give the limit"
            )


def exciter_params(case: Case) -> ExciterParams:
    """Exciter parameters; raises CaseError for a type or option stabctl does not model."""
    e = case.exciters
    _check_dc(e)
    A, B = _dc_saturation(e)
    dc = np.isin(e.type, DC_KINDS)
    ac = np.isin(e.type, AC_KINDS)
    t3 = e.type == T3
    KA = np.where((e.type != SMP) & (e.KA == 0), 1.0, e.KA)
    given = {n: getattr(e, n).copy() for n in TABLE_FIELDS}
    given.update(KA=KA, KP=e.KP * np.exp(1j * np.deg2rad(e.thetaP)))
    return ExciterParams(
        kind=e.type.astype(int),
        mac=np.array([case.machine_index(m) for m in e.machine], int),
        **given,
        KE=np.where(dc | ac | t3, _dc(e, "KE"), 0.0),
        TE=np.where(dc | ac | t3, _dc(e, "TE"), 0.0),
        Asat=np.where(dc | ac, A, 0.0),
        Bsat=np.where(dc | ac, B, 0.0),
        KF=np.where(dc, _dc(e, "KF_dc"), np.where(np.isin(e.type, RATE_FEEDBACK), e.KF, 0.0)),
        TF=np.where(dc, _dc(e, "TF_dc"), np.where(np.isin(e.type, RATE_FEEDBACK), e.TF, 0.0)),
        sat_quadratic=(dc & (e.dc_sat == 1)) | ac,
        ke_given=dc & (e.ke_given == 1),
        ifd_machine=(e.type == ST3) & (e.ifd_machine == 1),
        VB_cap=np.where(np.isin(e.type, SOURCE_KINDS) & (e.VBmax > 0), e.VBmax, np.inf),
    )


@kernel
def _fex(IN, init):
    """Rectifier loading factor F_EX(I_N) of the ST3 (PST, with its initialisation quirk:
    sqrt(0.75 - I_N^0.2) and 1.708 in flag 0)."""
    if IN < 0.433:
        return 1.0 - 0.5771 * IN
    if 0.433 < IN < 0.75:
        return np.sqrt(max(0.75 - (IN**0.2 if init else IN * IN), 0.0))
    if IN > 0.75:
        return max(0.0, (1.708 if init else 1.732) * (1.0 - IN))
    return 0.0


class ST3Machine(NamedTuple):
    """The quantities of an ST3 exciter's machine its source voltage is computed from
    (`st3_source_voltage`), floats: eterm the terminal voltage magnitude (pu), theta its
    angle (rad), pelect, qelect the electrical power (pu on the system base), mac_pot the
    system base / machine base ratio, fldcur the field current (pu on the machine
    base)."""

    eterm: float
    theta: float
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
    eterm, theta, pelect, qelect, mac_pot, _ = machine
    i_t = (pelect - 1j * qelect) / (eterm * np.exp(-1j * theta)) * mac_pot
    return np.abs(KP * eterm * np.exp(1j * theta) + 1j * (KI + KP * XL) * i_t)


@njit
def st3_source_voltage(KP, KI, XL, KC, machine, init):
    """V_B = V_E F_EX of the ST3 potential/compound source (PST exc_st3 flag 0/1); KP is
    the complex K_P exp(j theta_P), KI, XL, KC the exciter's other source parameters (pu),
    machine the `ST3Machine` quantities (pelect, qelect on the system base), init PST's
    flag 0 (its F_EX quirk, `_fex`)."""
    VE = potential_source(KP, KI, XL, machine)
    IN = KC * machine.fldcur / VE if VE > 0 else 0.0
    return VE * _fex(IN, init)


@njit
def source_voltage_of(kind, KP, KI, XL, KC, cap, machine, init):
    """The source term V_B of an exciter of type ``kind`` (:data:`SOURCE_KINDS`) from its
    machine's quantities (`ST3Machine`; fldcur the field current, pu on the machine base):
    ST3 `st3_source_voltage`, at most cap (VBmax); IEEET3 sqrt(V_E^2 - (0.78 I_fd)^2), 0
    where that is negative (IEEE 1968 type 3, ANDES 2.0 ``ieeet3.py``; its cap applies to
    V_B + V_R); ESST4B V_E F_EX(K_C I_fd / V_E) (`blocks.rectifier_loading`, IEEE Std
    421.5-2016 annex D), at most cap.  V_E: `potential_source`."""
    if kind == ST3:
        return min(st3_source_voltage(KP, KI, XL, KC, machine, init), cap)
    VE = potential_source(KP, KI, XL, machine)
    if kind == T3:
        SQE = VE * VE - (0.78 * machine.fldcur) ** 2
        return np.sqrt(SQE) if SQE > 0 else 0.0
    IN = KC * machine.fldcur / VE if VE > 0 else 0.0
    return min(VE * rectifier_loading(IN), cap)


def initial_source_voltage(p: ExciterParams, mp, V_mac, S_mac, vex):
    """The source term V_B (`source_voltage_of`; PST exc_st3 flag 0 for the ST3) of every
    exciter of :data:`SOURCE_KINDS` at the initial point (1 for the other types), (n_exc,):
    V_mac the complex terminal voltages, S_mac the machines' complex generation (system
    base), vex their field voltages (= field currents at rest), all (n_mac,); mp the
    MachineParams."""
    eterm, theta = np.abs(V_mac), np.angle(V_mac)
    VB = np.ones(p.n)
    for i in np.nonzero(np.isin(p.kind, SOURCE_KINDS))[0]:
        m = p.mac[i]
        machine = ST3Machine(
            eterm[m], theta[m], S_mac.real[m], S_mac.imag[m], mp.mac_pot[m], vex[m]
        )
        VB[i] = source_voltage_of(
            p.kind[i], p.KP[i], p.KI[i], p.XL[i], p.KC[i], p.VB_cap[i], machine, True
        )
    return VB


def initialise(p: ExciterParams, vex, eterm, VB=None, vc=None):
    """States (n_slots, n_exc), Vref (n_exc,) and the parameters with PSS/E's computed KE
    (DC exciters with KE = 0 get KE = -SE(Efd0), so that V_R starts at 0) from the
    machines' field voltage vex and terminal voltage eterm; VB is the ST3 source voltage
    (`initial_source_voltage`; needed for type 3); vc the voltage the transducers measure
    (`compensated`; default eterm).  Raises CaseError when the initial
    point violates a limit PST checks (ST3: Efdmax or the V_I range; DC: the V_R limits)
    by more than `START_LIMIT_TOL` (stabctl.models.declaration)."""
    x = np.zeros((6, p.n))
    vc = eterm if vc is None else vc
    x[0] = vc
    smp, st3, dc = p.kind == SMP, p.kind == ST3, p.is_dc
    bus_fed = smp & (p.KG == 1)
    vex_smp = vex / np.where(bus_fed, eterm, 1.0)  # SCRX bus fed: Efd = V_t x Efd state
    VA_smp = vex_smp / p.KA
    VB = np.ones(p.n) if VB is None else VB
    VR = vex / np.where(st3, VB, 1.0)
    VA_st3 = VR / p.KA + np.minimum(p.VGmax, p.KG * vex)
    VI = VA_st3 / np.where(p.KJ == 0, 1.0, p.KJ)
    bad = st3 & (beyond(vex, -np.inf, p.Efdmax) | beyond(VI, p.VImin, p.VImax))
    bad |= p.has_TA3A & beyond(VA_st3, p.VAmin, p.VAmax)
    refuse_initial(
        "exc_con",
        bad,
        lambda i: (
            f"exc_con row {i + 1}: initial field voltage {vex[i]:.3f} pu outside "
            "the ST3 limits (Efdmax, the VI range or ESST3A's [VRMIN, VRMAX])"
        ),
    )
    p, VR_dc = _dc_initial_regulator(p, vex, eterm)
    st1, st1a = p.kind == ST1, p.kind == ST1A
    VR_st1a = st1a_regulator_output(p, vex)
    _check_st1_initial(p, vex, eterm, np.where(st1a, VR_st1a, vex))
    VA = np.where(smp, VA_smp, np.where(dc, VR_dc, np.where(st1a, VR_st1a, vex)) / p.KA)
    VA = np.where(st3, VA_st3, VA)
    x[1] = VA
    x[2] = np.where(smp, vex_smp, np.where(st1, vex, np.where(dc, VR_dc, VR)))
    x[2] = np.where(st1a, VR_st1a, x[2])
    x[3] = np.where(p.has_Rf, vex, np.where(p.has_TA3A, VA_st3, 0.0))
    x[4] = np.where(dc, vex, np.where(st1a, VA, 0.0))
    if p.is_ac.any():
        VE, VFE = ac_initial_exciter(p, vex)
        ac = p.is_ac
        x[1] = np.where(ac, VFE / p.KA, x[1])
        x[2] = np.where(ac, VFE, x[2])
        x[3] = np.where(ac, VE, x[3])
        x[4] = np.where(ac & (p.kind != AC8B), VFE, x[4])  # AC8B: its PID's washout, 0
        VA = np.where(ac & (p.kind != AC8B), VFE / p.KA, np.where(ac, 0.0, VA))  # PID: 0
    t3, st4b = p.kind == T3, p.kind == ST4B
    if t3.any():
        VR_t3 = _t3_initial_regulator(p, vex, VB)
        x[2] = np.where(t3, VR_t3, x[2])
        x[3] = np.where(t3, vex, x[3])
        x[4] = np.where(t3, vex, x[4])  # the rate feedback's washout at rest
        VA = np.where(t3, VR_t3 / p.KA, VA)
    if st4b.any():
        VG, VM = _st4b_initial_regulators(p, vex, VB)
        x[1] = np.where(st4b, VG, x[1])  # the regulator PI's integral: its output at rest
        x[2] = np.where(st4b, VG, x[2])
        x[3] = np.where(st4b, VM, x[3])
        VA = np.where(st4b, 0.0, VA)  # a PI at rest: no error
    Vref = vc + np.where(st3, VI, VA)
    return x[: p.n_slots()], Vref, p


def _t3_initial_regulator(p: ExciterParams, Efd, VB):
    """IEEET3 at rest: V_R0 = K_E Efd0 - V_B0 (ANDES 2.0 ``ieeet3.py`` ``VR0``), (n_exc,);
    raises CaseError if V_R0 is outside [Vrmin, Vrmax] or V_B0 + V_R0 outside [0, VBmax]."""
    VR = p.KE * Efd - VB
    bad = (p.kind == T3) & (beyond(VR, p.Vrmin, p.Vrmax) | beyond(VB + VR, np.zeros(p.n), p.VB_cap))
    refuse_initial(
        "exc_con",
        bad,
        lambda i: (
            f"exc_con row {i + 1}: IEEET3 initial regulator output V_R = {VR[i]:.4f} "
            f"pu outside [Vrmin, Vrmax] = [{p.Vrmin[i]:.4f}, {p.Vrmax[i]:.4f}] or V_B + V_R = "
            f"{VB[i] + VR[i]:.4f} pu outside [0, VBmax]"
        ),
    )
    return VR


def _st4b_initial_regulators(p: ExciterParams, Efd, VB):
    """ESST4B at rest (ANDES 2.0 ``esst4b.py``): the regulator PI's output V_G0 = min(K_G
    Efd0, VGmax) (the inner loop's input is 0) and the inner PI's V_M0 = Efd0 / V_B0,
    arrays (n_exc,); raises CaseError if V_B0 <= 0, V_G0 is outside [Vrmin, Vrmax] or
    V_M0 outside [VMmin, VMmax]."""
    VG = np.minimum(p.KG * Efd, p.VGmax)
    VM = Efd / np.where(VB > 0, VB, 1.0)
    bad = (p.kind == ST4B) & (
        (VB <= 0) | beyond(VG, p.Vrmin, p.Vrmax) | beyond(VM, p.VMmin, p.VMmax)
    )
    refuse_initial(
        "exc_con",
        bad,
        lambda i: (
            f"exc_con row {i + 1}: ESST4B at rest: source V_B = {VB[i]:.4f} pu (must "
            f"be > 0), regulator output V_G = {VG[i]:.4f} pu (in [Vrmin, Vrmax] = "
            f"[{p.Vrmin[i]:.4f}, {p.Vrmax[i]:.4f}]), inner-loop output V_M = {VM[i]:.4f} pu "
            f"(in [VMmin, VMmax] = [{p.VMmin[i]:.4f}, {p.VMmax[i]:.4f}])"
        ),
    )
    return VG, VM


def st1a_regulator_output(p: ExciterParams, Efd):
    """ESST1A's regulator output V_A at rest, (n_exc,): Efd0 plus the field current
    limiter's K_LR max(0, I_fd0 - I_LR) with I_fd0 = Efd0 (the field current at rest; ANDES
    ``esst1a.py`` ``VA0``); Efd0 for the other types."""
    return np.where(p.kind == ST1A, Efd + p.KLR * np.maximum(Efd - p.ILR, 0.0), Efd)


def ac_initial_exciter(p: ExciterParams, Efd):
    """EXAC1 and ESAC1A at rest, arrays (n_exc,) (0 for the other types): the exciter
    voltage V_E0 solving V_E F_EX(K_C I_fd0/V_E) = Efd0 (`blocks.rectifier_loading`,
    increasing in V_E; I_fd0 = Efd0) and V_FE0 = K_E V_E0 + S_E(V_E0) V_E0 + K_D I_fd0 (=
    V_R0, and ESAC1A's V_A0); raises CaseError if V_R0 is outside [Vrmin, Vrmax] (ESAC1A:
    or V_A0 outside [VAmin, VAmax]; AC8B: or V_R0/K_A outside [VPmin, VPmax]) or V_R0/K_A
    has no V_E0."""
    from scipy.optimize import brentq  # here: the case layer imports this module (0.5 s)

    VE, VFE = np.zeros(p.n), np.zeros(p.n)
    bad: dict[int, str] = {}  # row -> its limit violation
    for i in np.nonzero(p.is_ac)[0]:
        name = {AC1: "EXAC1", AC1A: "ESAC1A", AC8B: "AC8B"}[int(p.kind[i])]
        efd0 = ifd0 = float(Efd[i])
        if efd0 <= 0:
            raise CaseError(
                f"exc_con row {i + 1}: {name} initial field voltage {efd0:.4f} pu must be > 0"
            )
        KC = float(p.KC[i])

        def residual(v, KC=KC, ifd0=ifd0, efd0=efd0):
            return v * rectifier_loading(KC * ifd0 / v) - efd0

        VE[i] = brentq(residual, efd0, efd0 + KC * ifd0 + 1.0, xtol=1e-15, rtol=1e-15)
        VFE[i] = dc_feedback(p.KE[i], p.Asat[i], p.Bsat[i], 1.0, VE[i]) + p.KD[i] * ifd0
        limits = [("V_R", "Vrmin, Vrmax", p.Vrmin[i], p.Vrmax[i])]
        if p.kind[i] == AC1A:
            limits.append(("V_A", "VAmin, VAmax", p.VAmin[i], p.VAmax[i]))
        if p.kind[i] == AC8B:  # the PID's output at rest, V_R0/K_A
            limits.append(("V_R/K_A", "VPmin, VPmax", p.VPmin[i] * p.KA[i], p.VPmax[i] * p.KA[i]))
        for what, names, lo, hi in limits:
            if beyond(VFE[i], lo, hi):
                bad[i] = (
                    f"exc_con row {i + 1}: {name} initial regulator output {what} = "
                    f"{VFE[i]:.4f} pu outside [{names}] = [{lo:.4f}, {hi:.4f}]"
                )
    refuse_initial("exc_con", [i in bad for i in range(p.n)], bad.get)
    return VE, VFE


def _check_st1_initial(p: ExciterParams, Efd, eterm, VA):
    """EXST1, ESST1A and EXAC4 at the initial point: Efd0 inside its output limits, [V_t
    Vrmin, V_t Vrmax - K_C I_fd0] (EXAC4: [Vrmin - K_C I_fd0, Vrmax - K_C I_fd0]; EXST1
    with psse_st1: [V_t Vrmin - K_C I_fd0, V_t Vrmax - K_C I_fd0]) with
    I_fd0 = Efd0, the regulator input VA/K_A inside [VImin, VImax] (VA: Efd0, or ESST1A's
    `st1a_regulator_output`), ESST1A's VA inside [VAmin, VAmax]; raises CaseError."""
    ac4 = p.kind == AC4
    drop = np.where(ac4 | ((p.kind == ST1) & (p.psse_st1 == 1)), p.KC * Efd, 0.0)
    lo = np.where(ac4, p.Vrmin, eterm * p.Vrmin) - drop
    hi = np.where(ac4, p.Vrmax, eterm * p.Vrmax) - p.KC * Efd
    bad = np.isin(p.kind, (ST1, ST1A, AC4)) & (
        beyond(Efd, lo, hi)
        | beyond(VA / p.KA, p.VImin, p.VImax)
        | ((p.kind == ST1A) & beyond(VA, p.VAmin, p.VAmax))
    )
    names = {ST1: "EXST1", ST1A: "ESST1A", AC4: "EXAC4"}
    refuse_initial(
        "exc_con",
        bad,
        lambda i: (
            f"exc_con row {i + 1}: {names[int(p.kind[i])]} initial field voltage "
            f"{Efd[i]:.4f} pu outside its output limits or regulator input outside [VImin, "
            "VImax]" + (" or V_A outside [VAmin, VAmax]" if p.kind[i] == ST1A else "")
        ),
    )


def _dc_initial_regulator(p: ExciterParams, Efd, eterm):
    """DC exciters: KE resolved (0 -> -SE(Efd0) unless ke_given) and V_R0 the exciter
    feedback at Efd0 (`dc_feedback`), checked against [Vrmin, Vrmax] times 1 (DC1) or
    eterm (DC2, bus fed)."""
    dc = p.is_dc
    KE, VR = p.KE.copy(), np.zeros(p.n)
    for r in np.nonzero(dc)[0]:
        sat = (p.Asat[r], p.Bsat[r], float(p.sat_quadratic[r]), Efd[r])
        if KE[r] == 0 and not p.ke_given[r] and Efd[r] != 0:  # V_R starts at 0
            KE[r] = -dc_feedback(0.0, *sat) / Efd[r]
        VR[r] = dc_feedback(KE[r], *sat)
    mult = np.where(p.kind == DC2, eterm, 1.0)
    refuse_initial(
        "exc_con",
        dc & beyond(VR, p.Vrmin * mult, p.Vrmax * mult),
        lambda i: (
            f"exc_con row {i + 1}: initial DC regulator output V_R = {VR[i]:.4f} pu "
            f"outside [Vrmin, Vrmax] = [{p.Vrmin[i] * mult[i]:.4f}, "
            f"{p.Vrmax[i] * mult[i]:.4f}]"
        ),
    )
    return replace(p, KE=KE), VR


# -- compiled runtime kernels: P is ExciterParams.packed(), x the exciter block of the
# -- state vector (n_slots, n_exc), i the exciter; one function per type, dispatched on
# -- kind by `field_voltage`, `derivatives` and `recorded_efd`

#: ``init=False`` of `st3_source_voltage` as a numpy boolean: a Python False passed from
#: compiled code is typed as a literal, a second compile of it
_RUNNING = np.bool_(False)
#: ``ieee=True`` of the blocks for the models PSTess lacks (ESST1A), a numpy boolean for
#: the same reason
_IEEE_RULE = np.bool_(True)


class StatorQuantities(NamedTuple):
    """A machine's terminal quantities as PST exc_st3 flag 1 recomputes them
    (`machines.stator_without_speed`, floats but vt): ed, eq the d, q terminal voltages
    (pu), cd, cq the d, q currents (pu on the system base), et = hypot(ed, eq) the
    terminal voltage magnitude (pu), vt the terminal bus voltage (complex pu; its angle
    sets the ST3 source phasor)."""

    ed: float
    eq: float
    cd: float
    cq: float
    et: float
    vt: complex


@kernel(inline="always")
def field_current(P, i, MP, xm, cur):
    """The field current (pu on the machine base) of exciter i's machine where its type's
    equations read it (:data:`READS_IFD`), 0 for the other types; MP, xm, cur as
    `field_voltage`."""
    kind = P[i, E.KIND]
    if kind in READS_IFD:
        return mac.field_current(MP, xm, cur, int(P[i, E.MAC]))
    return 0.0


@kernel(inline="always")
def source_voltage(P, i, MP, xm, cur, vt, ifd):
    """The source term V_B of exciter i (`source_voltage_of`; :data:`SOURCE_KINDS`), 1 for
    the other types: from its machine's terminal quantities as PST exc_st3 flag 1
    recomputes them (`machines.stator_without_speed`), vt the machine's terminal bus
    voltage (complex; its angle sets the source phasor), ifd the field current
    (`field_current`; the ST3 reads its own, `_st3_field_current`); at most VBmax (PSS/E
    ESST3A's and ESST4B's ``VB`` limiter; inf without); MP, xm, cur as `field_voltage`."""
    kind = P[i, E.KIND]
    if kind != ST3 and kind != T3 and kind != ST4B:
        return 1.0
    m = int(P[i, E.MAC])
    ed, eq, cd, cq = mac.stator_without_speed(MP, xm, cur, m)
    stator = StatorQuantities(ed, eq, cd, cq, np.hypot(ed, eq), vt)
    fld = _st3_field_current(P, i, MP, xm, cur, m) if kind == ST3 else ifd
    return source_voltage_of(
        kind,
        P[i, E.KPR] + 1j * P[i, E.KPI],
        P[i, E.KI],
        P[i, E.XL],
        P[i, E.KC],
        P[i, E.VBCAP],
        _source_machine(MP, m, stator, fld),
        _RUNNING,
    )


@kernel(inline="always")
def _source_machine(MP, m, stator, fld):
    """`ST3Machine` of machine m from its `StatorQuantities` and field current fld."""
    ed, eq, cd, cq, et, vt = stator
    return ST3Machine(et, np.angle(vt), eq * cq + ed * cd, eq * cd - ed * cq, MP[m, mac.K.POT], fld)


@kernel(inline="always")
def field_voltage(P, x, i, MP, xm, cur, pss_out, ifd, VB, ieee):
    """Field voltage exciter i hands its machine (PST flag 1), pu on the machine base:
    `field_voltage_at` with its machine's terminal voltage (times its speed with
    exc_con column 45, ``efd_speed``, = 1).

    Parameters
    ----------
    P, x, i : ndarray, ndarray, int
        The exciters' packed parameters, states (n_slots, n_exc), the exciter.
    MP, xm, cur : ndarray
        The machines' packed parameters (machines.PACKED), states (6, n_mac)
        and network currents (n_mac,) complex, system base: the terminal voltage V_t
        comes from them (PST exc_st3's speed-free stator equations,
        `machines.stator_without_speed`).
    pss_out : float
        The output of the machine's PSS (0 without).
    ifd : float
        The machine's field current, `field_current`.
    VB : float
        The source term, `source_voltage`.
    ieee : bool
        The IEEE 421.5 convention (limited states are read clipped to their limits).
    """
    m = int(P[i, E.MAC])
    ed, eq, _, _ = mac.stator_without_speed(MP, xm, cur, m)
    efd = field_voltage_at(P, x, i, np.hypot(ed, eq), pss_out, VB, ifd, ieee)
    return efd * xm[1, m] if P[i, E.EFD_SPEED] == 1 else efd


@kernel(inline="always")
def field_voltage_at(P, x, i, VTR_alg, pss_out, VB, ifd, ieee):
    """Field voltage of exciter i given its machine's terminal voltage VTR_alg (pu), the
    source term VB (`source_voltage`) and the field current ifd (`field_current`): per
    type `_smp_field_voltage`, `_st3_field_voltage`, `_st1_field_voltage`,
    `_st1a_field_voltage`, `_st4b_field_voltage`, the DC exciters' and IEEET3's Efd
    state."""
    kind = P[i, E.KIND]
    if kind == ST3:
        return _st3_field_voltage(P, x, i, VB, ieee)
    if kind == ST1:
        return _st1_field_voltage(P, x, i, VTR_alg, ifd)
    if kind == ST1A:
        return _st1a_field_voltage(P, x, i, VTR_alg, ifd, pss_out)
    if kind == AC1 or kind == AC1A or kind == AC8B:
        return _ac1_field_voltage(P, x, i, ifd)
    if kind == AC4:
        return clip(x[2, i], P[i, E.VRMIN] - P[i, E.KC] * ifd, P[i, E.VRMAX] - P[i, E.KC] * ifd)
    if kind == ST4B:
        return _st4b_field_voltage(P, x, i, VTR_alg, pss_out, VB)
    if kind == DC1 or kind == DC2 or kind == T2 or kind == T3:
        return x[3, i]
    return _smp_field_voltage(P, x, i, VTR_alg, pss_out, ieee)


@kernel
def compensated(P, i, vt, it):
    """The voltage exciter i's transducer measures: abs(V_t + (R_C + j X_C) I_t) (IEEE
    421.5 load compensator), for the terminal voltage vt and the machine's current it
    (complex, one frame, machine base); abs(vt) without compensation."""
    return abs(vt + complex(P[i, E.RCOMP], P[i, E.XCOMP]) * it)


@kernel
def derivatives(P, x, i, vc, eterm, pss_out, efd, ifd, VB, dx, ieee, reach):
    """Derivatives of exciter i into dx[:, i] (PST flag 2); clamps its limited state in x.

    Every type: the voltage transducer lag T_R on vc (pu; the terminal voltage eterm, or
    the load-compensated voltage `compensated`) and the error V_ref - V_TR + pss_out;
    efd is the field voltage `field_voltage` gave, ifd the field current `field_current`
    gave, VB the source term `source_voltage` gave; reach (s): DC2's V_t-scaled V_R limits
    (on eterm) hold a state within that reach (`blocks.nonwindup`; the run's step, 0 in
    the linearisation).
    """
    dx[:, i] = 0.0
    VTR, dx[0, i] = lag(vc, x[0, i], P[i, E.TR])
    err = P[i, E.VREF] - VTR + pss_out
    kind = P[i, E.KIND]
    if kind == SMP:
        _smp_derivatives(P, x, i, err, dx, ieee)
    elif kind == ST3:
        _st3_derivatives(P, x, i, err, efd, dx, ieee)
    elif kind == ST1:
        _st1_derivatives(P, x, i, err, efd, dx)
    elif kind == ST1A:
        _st1a_derivatives(P, x, i, err, ifd, pss_out, dx)
    elif kind == AC1 or kind == AC1A:
        _ac1_derivatives(P, x, i, err, ifd, dx)
    elif kind == AC8B:
        _ac8b_derivatives(P, x, i, err, ifd, dx)
    elif kind == AC4:
        _ac4_derivatives(P, x, i, err, dx)
    elif kind == T3:
        _t3_derivatives(P, x, i, err, VB, dx)
    elif kind == ST4B:
        _st4b_derivatives(P, x, i, err, efd, dx)
    else:
        _dc_derivatives(P, x, i, eterm, err, dx, ieee, reach)


@kernel
def recorded_efd(P, x, i, efd_alg):
    """Efd as PST records it: the (clamped) smpexc state, the DC Efd state, or the ST3
    (and bus-fed smpexc) algebraic value efd_alg (`field_voltage`); efd_alg, the
    machine's, with ``efd_speed``."""
    kind = P[i, E.KIND]
    if P[i, E.EFD_SPEED] == 1:
        return efd_alg
    if kind == DC1 or kind == DC2 or kind == T2 or kind == T3:
        return x[3, i]
    if kind == SMP and P[i, E.TA] >= LBND and P[i, E.KG] != 1:
        return x[2, i]
    return efd_alg


# -- smpexc (and SCRX): T_R, lead-lag T_C/T_B, K_A/(1 + s T_A) limited [Vrmin, Vrmax]


@kernel(inline="always")
def _smp_field_voltage(P, x, i, VTR_alg, pss_out, ieee):
    """smpexc: the Efd state when T_A exists (PSTess: unclamped, docs/pst_models.md 2.1;
    ieee: clipped to [Vrmin, Vrmax]), else K_A times the (lead-lag of the) error, without
    limits; bus fed (SCRX, exc_con column 19 = 1): times the terminal voltage VTR_alg."""
    mult = VTR_alg if P[i, E.KG] == 1 else 1.0
    if P[i, E.TA] >= LBND:
        return (clip(x[2, i], P[i, E.VRMIN], P[i, E.VRMAX]) if ieee else x[2, i]) * mult
    VTR = lag(VTR_alg, x[0, i], P[i, E.TR])[0]
    err = P[i, E.VREF] - VTR + pss_out
    VA = leadlag_input_state(err, x[1, i], P[i, E.TCTB], P[i, E.TB])[0]
    return P[i, E.KA] * VA * mult


@kernel(inline="always")
def _smp_derivatives(P, x, i, err, dx, ieee):
    """smpexc: PSTess clamps the Efd state to [Vrmin, Vrmax] after its derivative is
    computed and keeps the derivative (a windup clamp; PST's misspelt dEFD,
    docs/pst_models.md 2.1); ieee: a non-windup limit as IEEE Std 421.5-2016 (SEXS/ST1A
    lag).  No T_A: no state (the output is algebraic)."""
    VA, dx[1, i] = leadlag_input_state(err, x[1, i], P[i, E.TCTB], P[i, E.TB])
    if P[i, E.TA] < LBND:
        return
    lo, hi = P[i, E.VRMIN], P[i, E.VRMAX]
    if ieee:
        x[2, i], dx[2, i] = nonwindup_lag(P[i, E.KA] * VA, x[2, i], P[i, E.TA], lo, hi, ieee, 0.0)
    else:
        dx[2, i] = lag(P[i, E.KA] * VA, x[2, i], P[i, E.TA])[1]
        x[2, i] = clip(x[2, i], lo, hi)


# -- exc_st3: V_I limited, K_J, lead-lag, non-windup K_A/(1 + s T_A) with the inner loop
# -- feedback min(V_Gmax, K_G Efd); output min(V_R V_B, Efdmax)


@kernel(inline="always")
def _st3_field_current(P, i, MP, xm, cur, m):
    """The field current of exciter i's source (ST3, machine m): exc_st3's own estimate
    (`machines.st3_field_current`) or, with ifd_machine, the machine's (ANDES
    ``esst3a.py``); MP, xm, cur as `field_voltage`."""
    if P[i, E.IFDM] > 0:
        return mac.field_current(MP, xm, cur, m)
    return mac.st3_field_current(MP, xm, cur, m)


@kernel(inline="always")
def _st3_field_voltage(P, x, i, VB, ieee):
    """exc_st3: min(V_R V_B, Efdmax) (ieee: V_R clipped to [Vrmin, Vrmax])."""
    VR = clip(x[2, i], P[i, E.VRMIN], P[i, E.VRMAX]) if ieee else x[2, i]
    return min(VR * VB, P[i, E.EFDMAX])


@kernel(inline="always")
def _st3_derivatives(P, x, i, err, efd, dx, ieee):
    """exc_st3: V_R clamped and its derivative zeroed when it pushes outward
    (`blocks.nonwindup`); with TA_st3a ESST3A's regulator lag (state V_A, non-windup on
    [VAmin, VAmax], IEEE 421.5's rule) between the lead-lag and the inner loop."""
    u = P[i, E.KJ] * clip(err, P[i, E.VIMIN], P[i, E.VIMAX])
    VA, dx[1, i] = leadlag_input_state(u, x[1, i], P[i, E.TCTB], P[i, E.TB])
    if P[i, E.TA_ST3A] >= LBND:  # ESST3A's regulator lag (no PST counterpart)
        x[3, i], dx[3, i] = nonwindup_lag(
            VA, x[3, i], P[i, E.TA_ST3A], P[i, E.VAMIN], P[i, E.VAMAX], _IEEE_RULE, 0.0
        )
        VA = x[3, i]
    x[2, i], dx[2, i] = nonwindup_lag(
        P[i, E.KA] * (VA - min(P[i, E.VGMAX], P[i, E.KG] * efd)),
        x[2, i],
        P[i, E.TA],
        P[i, E.VRMIN],
        P[i, E.VRMAX],
        ieee,
        0.0,
    )


# -- EXST1: rate feedback s K_F/(1 + s T_F) on Efd, V_I limited, lead-lag, K_A/(1 + s T_A);
# -- output limited to [V_t Vrmin, V_t Vrmax - K_C I_fd]


@kernel(inline="always")
def _st1_field_voltage(P, x, i, VTR_alg, ifd):
    """EXST1: V_R clipped to [V_t Vrmin, V_t Vrmax - K_C I_fd] (ifd the machine's field
    current); psse_st1: to [V_t Vrmin - K_C I_fd, V_t Vrmax - K_C I_fd] (PSS/E)."""
    drop = P[i, E.KC] * ifd
    lo = VTR_alg * P[i, E.VRMIN] - (drop if P[i, E.PSSE_ST1] == 1 else 0.0)
    return clip(x[2, i], lo, VTR_alg * P[i, E.VRMAX] - drop)


@kernel(inline="always")
def _st1_derivatives(P, x, i, err, efd, dx):
    """EXST1 (PSS/E; docs/pst_models.md 2.4): the rate feedback (state R_f, only with
    K_F != 0) of the field voltage efd (psse_st1: of V_R, before the output limits)
    subtracted before the V_I limits."""
    if P[i, E.KF] != 0:
        fed = x[2, i] if P[i, E.PSSE_ST1] == 1 else efd
        VF, dx[3, i] = washout(fed, x[3, i], P[i, E.TF], P[i, E.KF], GAIN_OVER_T)
        err = err - VF
    VA, dx[1, i] = leadlag_input_state(
        clip(err, P[i, E.VIMIN], P[i, E.VIMAX]), x[1, i], P[i, E.TCTB], P[i, E.TB]
    )
    dx[2, i] = lag(P[i, E.KA] * VA, x[2, i], P[i, E.TA])[1]


# -- ESST1A (IEEE 421.5-2016 ST1A as PSS/E and ANDES esst1a.py read it, no UEL/OEL):
# -- V_I limited, two lead-lags, non-windup K_A/(1 + s T_A) limited [VAmin, VAmax] minus
# -- the field current limiter K_LR max(0, I_fd - I_LR); output limited to [V_t Vrmin,
# -- V_t Vrmax - K_C I_fd]; rate feedback s K_F/(1 + s T_F) of the output before that limit.
# -- PSTess has no ST1A, so there is no quirk to keep: both conventions use IEEE 421.5's
# -- non-windup rule (E.5) and read V_A within its limits


@kernel(inline="always")
def _st1a_regulator(P, x, i, ifd, pss_out):
    """ESST1A: V_A clipped to [VAmin, VAmax] minus K_LR max(0, I_fd - I_LR); plus the
    stabiliser output pss_out with VOS = 2 (exc_con column 20 ``vos_after_va`` = 1)."""
    VA = clip(x[2, i], P[i, E.VAMIN], P[i, E.VAMAX])
    after = pss_out if P[i, E.VGMAX] == 1 else 0.0
    return VA - P[i, E.KLR] * max(ifd - P[i, E.ILR], 0.0) + after


@kernel(inline="always")
def _st1a_field_voltage(P, x, i, VTR_alg, ifd, pss_out):
    """ESST1A: `_st1a_regulator` clipped to [V_t Vrmin, V_t Vrmax - K_C I_fd]."""
    return clip(
        _st1a_regulator(P, x, i, ifd, pss_out),
        VTR_alg * P[i, E.VRMIN],
        VTR_alg * P[i, E.VRMAX] - P[i, E.KC] * ifd,
    )


@kernel(inline="always")
def _st1a_derivatives(P, x, i, err, ifd, pss_out, dx):
    """ESST1A (docs/pst_models.md 2.6): the rate feedback of `_st1a_regulator` (state R_f,
    only with K_F != 0) subtracted before the V_I limits, the lead-lags T_C/T_B (state
    V_As) and T_C1/T_B1 (state V_As1), V_A non-windup; with VOS = 2 the stabiliser
    output pss_out (in err) moves to the regulator output."""
    if P[i, E.VGMAX] == 1:
        err = err - pss_out
    if P[i, E.KF] != 0:
        VF, dx[3, i] = washout(
            _st1a_regulator(P, x, i, ifd, pss_out),
            x[3, i],
            P[i, E.TF],
            P[i, E.KF],
            GAIN_OVER_T,
        )
        err = err - VF
    u, dx[1, i] = leadlag_input_state(
        clip(err, P[i, E.VIMIN], P[i, E.VIMAX]), x[1, i], P[i, E.TCTB], P[i, E.TB]
    )
    u, dx[4, i] = leadlag_input_state(u, x[4, i], P[i, E.TC1TB1], P[i, E.TB1])
    x[2, i], dx[2, i] = nonwindup_lag(
        P[i, E.KA] * u, x[2, i], P[i, E.TA], P[i, E.VAMIN], P[i, E.VAMAX], _IEEE_RULE, 0.0
    )


# -- EXAC1 (IEEE 1981 AC1 as PSS/E EXAC1 and ANDES 2.0 exac1.py): lead-lag, non-windup
# -- K_A/(1 + s T_A) -> V_R; T_E dV_E/dt = V_R - V_FE, V_FE = K_E V_E + S_E(V_E) V_E + K_D
# -- I_fd (PSS/E's quadratic saturation); Efd = V_E F_EX(K_C I_fd/V_E); rate feedback
# -- s K_F/(1 + s T_F) of V_FE.  ESAC1A (IEEE 421.5-2005 AC1A, no UEL/OEL): the lag's
# -- non-windup limits are [VAmin, VAmax], V_R = V_A clipped to [Vrmin, Vrmax] and the
# -- exciter's V_E held at or above 0 (ANDES 2.0 esac1a.py leaves out this clip, the V_E
# -- limit and the rate feedback: docs/pst_models.md 2.7).  PSTess has no AC1: IEEE
# -- 421.5's non-windup rule in both conventions


@kernel(inline="always")
def _ac1_field_voltage(P, x, i, ifd):
    """EXAC1: V_E F_EX(I_N), I_N = K_C I_fd / V_E (`blocks.rectifier_loading`)."""
    VE = x[3, i]
    return VE * rectifier_loading(P[i, E.KC] * ifd / VE) if VE > 0 else 0.0


@kernel(inline="always")
def _ac1_derivatives(P, x, i, err, ifd, dx):
    """EXAC1 and ESAC1A (docs/pst_models.md 2.7): the rate feedback of V_FE (state R_f,
    with K_F != 0) subtracted from the error, the lead-lag T_C/T_B, the regulator lag
    non-windup (EXAC1: V_R on [Vrmin, Vrmax]; ESAC1A: V_A on [VAmin, VAmax], then V_R = V_A
    clipped to [Vrmin, Vrmax]), the exciter T_E dV_E/dt = V_R - V_FE (ESAC1A: V_E >= 0,
    non-windup: IEEE 421.5-2005 6.1, as OpenIPSL's and Dynawo's AC1A)."""
    VFE = _ac_exciter_feedback(P, x, i, ifd)
    if P[i, E.KF] != 0:
        VF, dx[4, i] = washout(VFE, x[4, i], P[i, E.TF], P[i, E.KF], GAIN_OVER_T)
        err = err - VF
    u, dx[1, i] = leadlag_input_state(err, x[1, i], P[i, E.TCTB], P[i, E.TB])
    if P[i, E.KIND] == AC1A:
        lo, hi = P[i, E.VAMIN], P[i, E.VAMAX]
    else:
        lo, hi = P[i, E.VRMIN], P[i, E.VRMAX]
    x[2, i], dx[2, i] = nonwindup_lag(P[i, E.KA] * u, x[2, i], P[i, E.TA], lo, hi, _IEEE_RULE, 0.0)
    _ac_exciter(P, x, i, clip(x[2, i], P[i, E.VRMIN], P[i, E.VRMAX]), VFE, dx)


@kernel(inline="always")
def _ac_exciter_feedback(P, x, i, ifd):
    """V_FE = K_E V_E + S_E(V_E) V_E + K_D I_fd of the AC exciters (PSS/E's quadratic
    saturation, `dc_feedback`)."""
    return (
        dc_feedback(P[i, E.KE], P[i, E.ASAT], P[i, E.BSAT], P[i, E.SATQ], x[3, i])
        + P[i, E.KD] * ifd
    )


@kernel(inline="always")
def _ac_exciter(P, x, i, VR, VFE, dx):
    """The AC exciters' T_E dV_E/dt = V_R - V_FE; ESAC1A and AC8B hold V_E >= 0,
    non-windup (the rectifier's diodes)."""
    dx[3, i] = (VR - VFE) / P[i, E.TE]
    if P[i, E.KIND] != AC1:
        x[3, i], dx[3, i] = nonwindup(x[3, i], dx[3, i], 0.0, np.inf, _IEEE_RULE, 0.0)


# -- AC8B (IEEE 421.5-2005 AC8B as ANDES 2.0 ac8b.py, PowerWorld's AC8B record): a PID
# -- with tracking anti-windup, ys = K_P u + x_i + K_D (u - x_d)/T_D, y = ys clipped to
# -- [VPmin, VPmax], dx_i/dt = K_I (u - k_s (ys - y)) (k_s = 2, ANDES's PIDTrackAW),
# -- T_D dx_d/dt = u - x_d; K_A/(1 + s T_A) non-windup on [Vrmin, Vrmax] -> V_R; the
# -- exciter as EXAC1's (V_E >= 0).  VFEMAX and VEMIN are not modelled (ANDES neither)


@kernel(inline="always")
def _ac8b_derivatives(P, x, i, err, ifd, dx):
    """AC8B (docs/pst_models.md 2.7): the PID on the voltage error (states PIDi, PIDd),
    the regulator lag V_R, the exciter V_E."""
    ys = P[i, E.KPID_P] * err + x[1, i]
    if P[i, E.KPID_D] != 0 and P[i, E.TD] >= LBND:
        yd, dx[4, i] = washout(err, x[4, i], P[i, E.TD], P[i, E.KPID_D], GAIN_BEFORE)
        ys = ys + yd
    y = clip(ys, P[i, E.VPMIN], P[i, E.VPMAX])
    dx[1, i] = P[i, E.KPID_I] * (err - PID_TRACKING * (ys - y))
    x[2, i], dx[2, i] = nonwindup_lag(
        P[i, E.KA] * y, x[2, i], P[i, E.TA], P[i, E.VRMIN], P[i, E.VRMAX], _IEEE_RULE, 0.0
    )
    _ac_exciter(P, x, i, x[2, i], _ac_exciter_feedback(P, x, i, ifd), dx)


# -- EXAC4 (IEEE 1981 AC4 as PSS/E EXAC4 and ANDES 2.0 exac4.py): V_I limited, lead-lag,
# -- K_A/(1 + s T_A) (no limit on the lag); output limited to [Vrmin - K_C I_fd, Vrmax -
# -- K_C I_fd] (in `field_voltage_at`)


@kernel(inline="always")
def _ac4_derivatives(P, x, i, err, dx):
    """EXAC4 (docs/pst_models.md 2.8): the error limited to [VImin, VImax], the lead-lag
    T_C/T_B, the lag K_A/(1 + s T_A)."""
    u, dx[1, i] = leadlag_input_state(
        clip(err, P[i, E.VIMIN], P[i, E.VIMAX]), x[1, i], P[i, E.TCTB], P[i, E.TB]
    )
    dx[2, i] = lag(P[i, E.KA] * u, x[2, i], P[i, E.TA])[1]


# -- exc_dc12 (DC1, DC2) and IEEET2: rate feedback, lead-lag, non-windup K_A/(1 + s T_A)
# -- (DC2: limits times V_t), the exciter field T_E


@njit
def dc_feedback(KE, Asat, Bsat, quadratic, Efd):
    """V_FE of a DC exciter: (K_E + S_E(Efd)) Efd with S_E = sign(Efd) Asat exp(Bsat |Efd|)
    (PST), or with quadratic > 0: K_E Efd + Bsat (Efd - Asat)^2 above Asat (PSS/E)."""
    if quadratic > 0:
        return KE * Efd + (Bsat * (Efd - Asat) ** 2 if Efd > Asat else 0.0)
    SE = np.sign(Efd) * Asat * np.exp(Bsat * abs(Efd))
    return (KE + SE) * Efd


@kernel(inline="always")
def _dc_derivatives(P, x, i, eterm, err, dx, ieee, reach):
    """exc_dc12 flag 2 and IEEET2: the rate feedback K_F/T_F (Efd - R_f) = s K_F/(1 + s
    T_F) Efd (IEEET2: then the lag 1/(1 + s T_F2), state V_F), subtracted from the error;
    V_R non-windup (DC2: limits times eterm, held within `reach`);
    T_E dEfd/dt = V_R - V_FE(Efd) (`dc_feedback`)."""
    kind = P[i, E.KIND]
    VF, dx[4, i] = washout(x[3, i], x[4, i], P[i, E.TF], P[i, E.KF], GAIN_OVER_T)
    if kind == T2:
        VF, dx[5, i] = lag(VF, x[5, i], P[i, E.TF2])
    VA, dx[1, i] = leadlag_input_state(err - VF, x[1, i], P[i, E.TCTB], P[i, E.TB])
    mult = eterm if kind == DC2 else 1.0
    x[2, i], dx[2, i] = nonwindup_lag(
        P[i, E.KA] * VA,
        x[2, i],
        P[i, E.TA],
        P[i, E.VRMIN] * mult,
        P[i, E.VRMAX] * mult,
        ieee,
        reach if kind == DC2 else 0.0,
    )
    dx[3, i] = (
        x[2, i] - dc_feedback(P[i, E.KE], P[i, E.ASAT], P[i, E.BSAT], P[i, E.SATQ], x[3, i])
    ) / P[i, E.TE]


# -- IEEET3 (IEEE 1968 type 3 as PSS/E IEEET3 and ANDES 2.0 ieeet3.py): non-windup
# -- K_A/(1 + s T_A) on the error less the rate feedback s K_F/(1 + s T_F) of Efd -> V_R;
# -- the compound source V_B = sqrt(V_E^2 - (0.78 I_fd)^2) added, V_B + V_R limited to
# -- [0, VBmax]; the exciter T_E dEfd/dt = V_B + V_R - K_E Efd.  PSTess has no type 3:
# -- IEEE 421.5's non-windup rule in both conventions


@kernel(inline="always")
def _t3_derivatives(P, x, i, err, VB, dx):
    """IEEET3 (docs/pst_models.md 2.9): the rate feedback (state R_f, with K_F != 0), the
    regulator V_R non-windup on [Vrmin, Vrmax], the exciter Efd fed by V_B + V_R clipped
    to [0, VBmax] (VB the source term, `source_voltage`)."""
    if P[i, E.KF] != 0:
        VF, dx[4, i] = washout(x[3, i], x[4, i], P[i, E.TF], P[i, E.KF], GAIN_OVER_T)
        err = err - VF
    x[2, i], dx[2, i] = nonwindup_lag(
        P[i, E.KA] * err, x[2, i], P[i, E.TA], P[i, E.VRMIN], P[i, E.VRMAX], _IEEE_RULE, 0.0
    )
    dx[3, i] = (clip(VB + x[2, i], 0.0, P[i, E.VBCAP]) - P[i, E.KE] * x[3, i]) / P[i, E.TE]


# -- ESST4B (IEEE 421.5-2005 ST4B as PSS/E ESST4B and ANDES 2.0 esst4b.py, no OEL/UEL):
# -- the regulator PI K_PR + K_IR/s with tracking anti-windup on [Vrmin, Vrmax] (state
# -- PIi), the lag 1/(1 + s T_A) (state V_M), the inner-loop PI K_PM + K_IM/s on V_M -
# -- min(K_G Efd, VGmax), tracking anti-windup on [VMmin, VMmax] (state PIMi); Efd = V_B
# -- times the inner PI's output, V_B = min(V_E F_EX, VBmax).  The feedback K_G Efd closes
# -- an algebraic loop, solved exactly (`_st4b_field_voltage`)


@kernel(inline="always")
def _st4b_regulator(P, x, i, err):
    """ESST4B's regulator PI K_PR err + PIi: (unclipped, clipped to [Vrmin, Vrmax])."""
    ys = P[i, E.KPID_P] * err + x[1, i]
    return ys, clip(ys, P[i, E.VRMIN], P[i, E.VRMAX])


@kernel(inline="always")
def _st4b_field_voltage(P, x, i, VTR_alg, pss_out, VB):
    """ESST4B: Efd = V_B clip(K_PM (V_M - min(K_G Efd, VGmax)) + PIMi, VMmin, VMmax),
    solved for Efd (ANDES solves it with its algebraic equations): the right side does
    not rise with Efd (K_PM K_G >= 0, V_B >= 0), so there is one solution, on the
    feedback's limit if its candidate there reaches it, else V_B clip(y, VMmin, VMmax)
    with y = (K_PM V_M + PIMi)/(1 + V_B K_PM K_G) the unclipped loop's output.  V_M is
    the lag's state, or with T_A = 0 (PSS/E: no lag) the regulator's output itself."""
    VM = x[2, i]
    if P[i, E.TA] < LBND:
        err = P[i, E.VREF] - lag(VTR_alg, x[0, i], P[i, E.TR])[0] + pss_out
        VM = _st4b_regulator(P, x, i, err)[1]
    KPM, KG, VGmax = P[i, E.KPM], P[i, E.KG], P[i, E.VGMAX]
    lo, hi = P[i, E.VMMIN], P[i, E.VMMAX]
    on_limit = VB * clip(KPM * (VM - VGmax) + x[3, i], lo, hi)
    if KG * on_limit >= VGmax:
        return on_limit
    return VB * clip((KPM * VM + x[3, i]) / (1.0 + VB * KPM * KG), lo, hi)


@kernel(inline="always")
def _st4b_derivatives(P, x, i, err, efd, dx):
    """ESST4B (docs/pst_models.md 2.10): both PI regulators with ANDES's tracking
    anti-windup, dx_i/dt = K_I (u - k_s (ys - y)) (k_s = :data:`PID_TRACKING`), and the
    lag T_A; efd the field voltage (`_st4b_field_voltage`)."""
    ys, y = _st4b_regulator(P, x, i, err)
    dx[1, i] = P[i, E.KPID_I] * (err - PID_TRACKING * (ys - y))
    VM, dx[2, i] = lag(y, x[2, i], P[i, E.TA])
    u = VM - min(P[i, E.KG] * efd, P[i, E.VGMAX])
    ys = P[i, E.KPM] * u + x[3, i]
    y = clip(ys, P[i, E.VMMIN], P[i, E.VMMAX])
    dx[3, i] = P[i, E.KIM] * (u - PID_TRACKING * (ys - y))
