"""The DC commutator exciters: PST's exc_dc12 (exc_con types 1 DC1 and 2 DC2) and PSS/E's
IEEET2 (type 5: the rate feedback s K_F/((1 + s T_F1)(1 + s T_F2)) of the regulator
output V_R, where DC1 feeds back Efd).  One file for the three: their equations are one
family (rate feedback, lead-lag, non-windup K_A/(1 + s T_A) -> V_R, the exciter field
T_E dEfd/dt = V_R - V_FE(Efd)); DC2 only scales the V_R limits by the terminal voltage,
IEEET2 feeds back V_R through a second lag (IEEE Committee Report 1968, Type 2: the
rotating rectifier's Efd is not measured; OpenIPSL's PSS/E-verified IEEET2 alike).

Source: PSTess 1.1 `exc_dc12.m` (PST manual 3.11 Table 2); PSS/E Model Library IEEET1,
IEEET2 (IEEE Committee Report 1968), IEEEX1, ESDC1A, ESDC2A, EXDC2; docs/pst_models.md
2.2-2.3.  The saturation fits are the family's (`stabctl.models.exciters._dc_saturation`).
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel, njit
from stabctl.errors import refuse_initial
from stabctl.models.blocks import (
    GAIN_OVER_T,
    LBND,
    lag,
    leadlag_input_state,
    nonwindup,
    nonwindup_lag,
    washout,
)
from stabctl.models.declaration import DyrModel, Limits, Param, beyond, states
from stabctl.models.exciters.table import IEEE_RULE, LEAD_LAG, REGULATOR_GAIN, E, col, own

if TYPE_CHECKING:
    from stabctl.models.exciters import ExciterParams

DC1, DC2, T2 = 1, 2, 5
KINDS = {DC1: "DC1", DC2: "DC2 (exc_dc12)", T2: "IEEET2 (DC1 with a two-lag V_R feedback)"}
#: the DC exciters' saturation point E2, T_E and (IEEET2) T_F2 >= 0 (IEEE Std 421.5-2016
#: DC1A, DC2A; PSS/E Model Library IEEET2); K_E may be negative (self-excited)
LIMITS = {
    DC1: (Limits("IEEE Std 421.5 DC1A", nonnegative=("E2", "TE")), REGULATOR_GAIN, LEAD_LAG),
    DC2: (Limits("IEEE Std 421.5 DC2A", nonnegative=("E2", "TE")), REGULATOR_GAIN, LEAD_LAG),
    T2: (
        Limits("PSS/E Model Library IEEET2", nonnegative=("E2", "TE", "TF2")),
        REGULATOR_GAIN,
        LEAD_LAG,
    ),
}
#: a Vrmax at or above this is "no upper limit" (a DYR's VRMAX = 0, `stabctl.io.dyr`)
VRMAX_NO_LIMIT = 999.0
#: reads the machine's field current (`stabctl.models.exciters.field_current`)
READS_IFD = False
#: has a rate feedback s K_F/(1 + s T_F) from exc_con columns 21-22 (KF, TF)
RATE_FEEDBACK = False
#: fed by a potential (and compound) source V_B (its ``source_voltage``)
SOURCE = False
#: how it reads exc_con columns 10-15 (K_E, T_E, E1, SE1, E2, SE2; `exciter_params`): "dc"
#: PST's DC exciter (saturation fit by dc_sat, K_E computed where 0), "quadratic" K_E,
#: T_E and PSS/E's quadratic saturation, "linear" K_E and T_E alone, "" not at all
EXCITER_COLUMNS = "dc"
#: the time constants that must be >= 1e-3 s: (name in messages, declared field)
NEEDS: tuple[tuple[str, str], ...] = (("TE", "TE"), ("TF", "TF_dc"))  # no T_A: PST's algebraic V_R

#: the DC exciters' own exc_con column
PARAMS = (
    Param(
        "efd_floor",
        "code",
        75,
        choices=(0, 1),
        doc="DC1/2: 1 Efd held at >= 0, non-windup (PSS/E's ESDC1A, ESDC2A: OpenIPSL's "
        "RotatingExciterLimited), 0 unlimited (PST's exc_dc12, IEEEX1, EXDC2, IEEET1)",
    ),
)
#: the packed columns of `PARAMS`: P[i, O.EFD_FLOOR]
O = own("DCColumns", PARAMS)

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

DYR = (
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
        for name, kind in (("IEEEX1", DC1), ("EXDC2", DC2), ("ESDC2A", DC2), ("ESDC1A", DC1))
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
        kind=DC1,
        andes=("IEEET1",),
    ),
    # IEEET2 -> DC1 (type 5) with the rate feedback s KF/((1 + s TF1)(1 + s TF2)) of V_R
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
        kind=T2,
    ),
)

#: the states: transducer, lead-lag, regulator V_R, the exciter's Efd, the rate feedback's
#: washout R_f (of Efd; IEEET2's of V_R) and IEEET2's second feedback lag V_F
S = states("DCStates", ("VTR", "VAs", "VR", "Efd", "Rf", "VF"))
STATE_NAMES = {DC1: S._fields[: S.VF], DC2: S._fields[: S.VF], T2: S._fields}


def has_state(p: ExciterParams):
    """Which of the slots of `S` are states (a block whose time constant is below 1e-3 s,
    or a feedback whose gain is 0, has none), boolean arrays (n_exc,) in slot order, read
    on this type's rows by `stabctl.models.exciters.ExciterParams.has_state`."""
    on = np.ones(p.n, bool)
    return (p.has_TR, p.has_TB, p.has_TA, on, on, p.has_VF)


def time_constants(p: ExciterParams):
    """The time constants of this type that set a state's speed besides the family's T_R,
    T_A, T_B and rate feedback T_F (`stabctl.models.exciters.ExciterParams.time_constants`):
    the exciter T_E, the rate feedback's T_F (exc_con column 17, always a state) and
    IEEET2's second rate-feedback lag T_F2; label -> (values, where)."""
    return {
        "exc_con T_E": (p.TE, True),
        "exc_con T_F": (p.TF, True),
        "exc_con T_F2": (p.TF2, p.has_VF),
    }


def check(e, r: int) -> str | None:
    """Why exc_con row r (0-based) of a DC exciter is not modelled, or None: Vrmax = 0,
    PST's 'compute it from E2'; an IEEET2 with T_A and T_F2 both below 1e-3 s (its rate
    feedback of V_R would be an algebraic loop)."""
    if e.Vrmax[r] == 0:
        return "field 'Vrmax': 0 (PST computes it from E2) is not supported; give the limit"
    if int(e.type[r]) == T2 and max(e.TA[r], e.Efdmax[r]) < LBND:
        rule = (
            f"IEEET2 needs TA or TF2 >= {LBND} s (its rate feedback of V_R would be an "
            "algebraic loop)"
        )
        got = f"got TA = {e.TA[r]:g}, TF2 = {e.Efdmax[r]:g}"
        e._fail(r, "TF2", f"{rule}, {got}", col("TF2"), fields=("TA", "TF2"), rule=rule)
    return None


@njit
def dc_feedback(KE, Asat, Bsat, quadratic, Efd):
    """V_FE of a DC exciter: (K_E + S_E(Efd)) Efd with S_E = sign(Efd) Asat exp(Bsat |Efd|)
    (PST), or with quadratic > 0: K_E Efd + Bsat (Efd - Asat)^2 above Asat (PSS/E)."""
    if quadratic > 0:
        return KE * Efd + (Bsat * (Efd - Asat) ** 2 if Efd > Asat else 0.0)
    SE = np.sign(Efd) * Asat * np.exp(Bsat * abs(Efd))
    return (KE + SE) * Efd


def initialise(p: ExciterParams, r, vex, eterm, VB, x):
    """The DC exciters at rest on rows r (`initial_regulator`): V_R0 the exciter's feedback
    at Efd0, the lead-lag V_R0/K_A, the rate feedback's washout at its input (Efd0; IEEET2
    V_R0), IEEET2's second lag 0; writes x, returns (V_ref - V_TR, p with K_E resolved)."""
    p, VR = initial_regulator(p, r, vex, eterm)
    VA = VR / p.KA[r]
    x[S.VAs, r] = VA
    x[S.VR, r] = VR
    x[S.Efd, r] = vex[r]
    x[S.Rf, r] = np.where(p.kind[r] == T2, VR, vex[r])
    x[S.VF, r] = 0.0
    return VA, p


def initial_regulator(p: ExciterParams, r, Efd, eterm):
    """DC exciters on rows r (a mask): KE resolved where 0 (unless ke_given) and V_R0 the
    exciter feedback at Efd0 (`dc_feedback`), checked against [Vrmin, Vrmax] times 1 (DC1)
    or eterm (DC2, bus fed); returns (p, V_R0 of rows r).  K_E = 0 is resolved so that
    V_R starts at Vrmax/10 with PSS/E's quadratic saturation (PSS/E's self-excited exciter,
    its rheostat set for a tenth of the regulator's ceiling: PAG 15.2.4 as OpenIPSL's
    ``calculate_dc_exciter_params`` and OPAL-RT's PSS/E DC exciters read it; round 50: V_R
    started at 0), and at 0 with PST's exponential one (or a Vrmax read as no limit)."""
    KE, VR = p.KE.copy(), np.zeros(p.n)
    for k in np.nonzero(r)[0]:
        sat = (p.Asat[k], p.Bsat[k], float(p.sat_quadratic[k]), Efd[k])
        if KE[k] == 0 and not p.ke_given[k] and Efd[k] != 0:
            psse = p.sat_quadratic[k] and p.Vrmax[k] < VRMAX_NO_LIMIT
            KE[k] = ((p.Vrmax[k] / 10 if psse else 0.0) - dc_feedback(0.0, *sat)) / Efd[k]
        VR[k] = dc_feedback(KE[k], *sat)
    mult = np.where(p.kind == DC2, eterm, 1.0)
    refuse_initial(
        "exc_con",
        r & beyond(VR, p.Vrmin * mult, p.Vrmax * mult),
        lambda i: (
            f"exc_con row {i + 1}: initial DC regulator output V_R = {VR[i]:.4f} pu "
            f"outside [Vrmin, Vrmax] = [{p.Vrmin[i] * mult[i]:.4f}, "
            f"{p.Vrmax[i] * mult[i]:.4f}]"
        ),
    )
    return replace(p, KE=KE), VR[r]


@kernel(inline="always")
def field_voltage(P, x, i, VTR_alg, pss_out, VB, ifd, ieee):
    """The DC exciters: the Efd state."""
    return x[S.Efd, i]


@kernel(inline="always")
def recorded_efd(P, x, i, efd_alg):
    """Efd as PST records it: the Efd state."""
    return x[S.Efd, i]


@kernel(inline="always")
def derivatives(P, x, i, err, eterm, efd, ifd, pss_out, VB, dx, ieee, reach):
    """exc_dc12 flag 2: the rate feedback K_F/T_F (Efd - R_f) = s K_F/(1 + s T_F) Efd,
    subtracted from the error; IEEET2: s K_F/(1 + s T_F1) of V_R, then the lag 1/(1 + s
    T_F2) (state V_F; without it V_R is a state, `check`); V_R non-windup (DC2: limits
    times eterm, held within `reach`); T_E dEfd/dt = V_R - V_FE(Efd) (`dc_feedback`),
    Efd >= 0 non-windup where `efd_floor` (PSS/E's ESDC1A, ESDC2A)."""
    kind = P[i, E.KIND]
    if kind == T2:  # the fed-back V_R: V_F's state, or V_R's state through the washout
        VF = x[S.VF, i]
        if P[i, E.TF2] < LBND:
            VF = P[i, E.KF] / P[i, E.TF] * (x[S.VR, i] - x[S.Rf, i])
    else:
        VF, dx[S.Rf, i] = washout(x[S.Efd, i], x[S.Rf, i], P[i, E.TF], P[i, E.KF], GAIN_OVER_T)
    VA, dx[S.VAs, i] = leadlag_input_state(err - VF, x[S.VAs, i], P[i, E.TCTB], P[i, E.TB])
    mult = eterm if kind == DC2 else 1.0
    x[S.VR, i], dx[S.VR, i] = nonwindup_lag(
        P[i, E.KA] * VA,
        x[S.VR, i],
        P[i, E.TA],
        P[i, E.VRMIN] * mult,
        P[i, E.VRMAX] * mult,
        ieee,
        reach if kind == DC2 else 0.0,
    )
    if kind == T2:
        W, dx[S.Rf, i] = washout(x[S.VR, i], x[S.Rf, i], P[i, E.TF], P[i, E.KF], GAIN_OVER_T)
        _, dx[S.VF, i] = lag(W, x[S.VF, i], P[i, E.TF2])
    dx[S.Efd, i] = (
        x[S.VR, i] - dc_feedback(P[i, E.KE], P[i, E.ASAT], P[i, E.BSAT], P[i, E.SATQ], x[S.Efd, i])
    ) / P[i, E.TE]
    if P[i, O.EFD_FLOOR] > 0:  # PSS/E's ESDC1A, ESDC2A
        x[S.Efd, i], dx[S.Efd, i] = nonwindup(
            x[S.Efd, i], dx[S.Efd, i], 0.0, np.inf, IEEE_RULE, 0.0
        )
