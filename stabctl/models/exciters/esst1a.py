"""ESST1A (exc_con type 6): IEEE 421.5-2016 ST1A as PSS/E and ANDES 2.0 ``esst1a.py`` read
it, no UEL/OEL.

V_I limited, two lead-lags, non-windup K_A/(1 + s T_A) limited [VAmin, VAmax] minus the
field current limiter K_LR max(0, I_fd - I_LR); output limited to [V_t Vrmin, V_t Vrmax -
K_C I_fd]; rate feedback s K_F/(1 + s T_F) of the output before that limit.  PSTess has
no ST1A, so there is no quirk to keep: both conventions use IEEE 421.5's non-windup rule
(E.5) and read V_A within its limits.  Source: IEEE Std 421.5-2016 ST1A; PSS/E Model
Library ESST1A; docs/pst_models.md 2.6.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.models.blocks import GAIN_OVER_T, clip, leadlag_input_state, nonwindup_lag, washout
from stabctl.models.declaration import DyrModel, Limits, states
from stabctl.models.exciters import exst1
from stabctl.models.exciters.exst1 import check_start
from stabctl.models.exciters.table import (
    IEEE_RULE,
    LEAD_LAG,
    REGULATOR_GAIN,
    SECOND_LEAD_LAG,
    E,
    upper,
)

if TYPE_CHECKING:
    from stabctl.models.exciters import ExciterParams

ST1A = 6
KINDS = {ST1A: "ESST1A (IEEE 421.5 ST1A)"}
#: ST1A's V_I and V_A limits ordered (IEEE Std 421.5-2016 ST1A)
LIMITS = (
    Limits("IEEE Std 421.5 ST1A", ordered=(("VImax", "VImin"), ("VAmax", "VAmin"))),
    REGULATOR_GAIN,
    LEAD_LAG,
    SECOND_LEAD_LAG,
)
#: reads the machine's field current (`stabctl.models.exciters.field_current`)
READS_IFD = True
#: has a rate feedback s K_F/(1 + s T_F) from exc_con columns 21-22 (KF, TF)
RATE_FEEDBACK = True
#: fed by a potential (and compound) source V_B (its ``source_voltage``)
SOURCE = False
#: how it reads exc_con columns 10-15 (K_E, T_E, E1, SE1, E2, SE2; `exciter_params`): "dc"
#: PST's DC exciter (saturation fit by dc_sat, K_E computed where 0), "quadratic" K_E,
#: T_E and PSS/E's quadratic saturation, "linear" K_E and T_E alone, "" not at all
EXCITER_COLUMNS = ""
#: the time constants that must be >= 1e-3 s: (name in messages, declared field)
NEEDS: tuple[tuple[str, str], ...] = (("TA", "TA"),)

DYR = (
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
        upper(
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
        kind=ST1A,
        andes=("ESST1A",),
    ),
)

#: the states: transducer, first lead-lag, regulator V_A, the rate feedback's washout R_f,
#: second lead-lag
S = states("ESST1AStates", ("VTR", "VAs", "VA", "Rf", "VAs1"))
STATE_NAMES = {ST1A: S._fields}


def has_state(p: ExciterParams):
    """Which of the slots of `S` are states (a block whose time constant is below 1e-3 s,
    or a feedback whose gain is 0, has none), boolean arrays (n_exc,) in slot order, read
    on this type's rows by `stabctl.models.exciters.ExciterParams.has_state`."""
    return (p.has_TR, p.has_TB, p.has_TA, p.has_Rf, p.has_TB1)


def time_constants(p: ExciterParams):
    """The time constants of this type that set a state's speed besides the family's T_R,
    T_A, T_B and rate feedback T_F (`stabctl.models.exciters.ExciterParams.time_constants`):
    the second lead-lag's T_B1; label -> (values, where)."""
    return {"exc_con T_B1": (p.TB1, p.has_TB1)}


def st1a_regulator_output(p: ExciterParams, Efd):
    """ESST1A's regulator output V_A at rest, (n_exc,): Efd0 plus the field current
    limiter's K_LR max(0, I_fd0 - I_LR) with I_fd0 = Efd0 (the field current at rest; ANDES
    ``esst1a.py`` ``VA0``); Efd0 for the other types."""
    return np.where(p.kind == ST1A, Efd + p.KLR * np.maximum(Efd - p.ILR, 0.0), Efd)


#: the regulator loop through the rate feedback, EXST1's (with the second lead-lag)
INNER_LOOP, inner_loop_time_constants = exst1.INNER_LOOP, exst1.inner_loop_time_constants


def initialise(p: ExciterParams, r, vex, eterm, VB, x):
    """ESST1A at rest on rows r (a mask): V_A0 `st1a_regulator_output` within its limits
    (`exst1.check_start`), both lead-lags V_A0/K_A, the washout Efd0 (with K_F != 0);
    writes x, returns (V_ref - V_TR, p)."""
    VR = st1a_regulator_output(p, vex)
    check_start(p, r, "ESST1A", vex, eterm * p.Vrmin, eterm * p.Vrmax - p.KC * vex, VR, True)
    VA = VR[r] / p.KA[r]
    x[S.VAs, r] = VA
    x[S.VA, r] = VR[r]
    x[S.Rf, r] = np.where(p.KF[r] != 0, vex[r], 0.0)
    x[S.VAs1, r] = VA
    return VA, p


@kernel(inline="always")
def regulator(P, x, i, ifd, pss_out):
    """ESST1A: V_A clipped to [VAmin, VAmax] minus K_LR max(0, I_fd - I_LR); plus the
    stabiliser output pss_out with VOS = 2 (exc_con column 20 ``vos_after_va`` = 1)."""
    VA = clip(x[S.VA, i], P[i, E.VAMIN], P[i, E.VAMAX])
    after = pss_out if P[i, E.VGMAX] == 1 else 0.0
    return VA - P[i, E.KLR] * max(ifd - P[i, E.ILR], 0.0) + after


@kernel(inline="always")
def field_voltage(P, x, i, VTR_alg, pss_out, VB, ifd, ieee):
    """ESST1A: `regulator` clipped to [V_t Vrmin, V_t Vrmax - K_C I_fd]."""
    return clip(
        regulator(P, x, i, ifd, pss_out),
        VTR_alg * P[i, E.VRMIN],
        VTR_alg * P[i, E.VRMAX] - P[i, E.KC] * ifd,
    )


@kernel(inline="always")
def derivatives(P, x, i, err, eterm, efd, ifd, pss_out, VB, dx, ieee, reach):
    """ESST1A (docs/pst_models.md 2.6): the rate feedback of `regulator` (state R_f, only
    with K_F != 0) subtracted before the V_I limits, the lead-lags T_C/T_B (state V_As) and
    T_C1/T_B1 (state V_As1), V_A non-windup; with VOS = 2 the stabiliser output pss_out
    (in err) moves to the regulator output."""
    if P[i, E.VGMAX] == 1:
        err = err - pss_out
    if P[i, E.KF] != 0:
        VF, dx[S.Rf, i] = washout(
            regulator(P, x, i, ifd, pss_out),
            x[S.Rf, i],
            P[i, E.TF],
            P[i, E.KF],
            GAIN_OVER_T,
        )
        err = err - VF
    u, dx[S.VAs, i] = leadlag_input_state(
        clip(err, P[i, E.VIMIN], P[i, E.VIMAX]), x[S.VAs, i], P[i, E.TCTB], P[i, E.TB]
    )
    u, dx[S.VAs1, i] = leadlag_input_state(u, x[S.VAs1, i], P[i, E.TC1TB1], P[i, E.TB1])
    x[S.VA, i], dx[S.VA, i] = nonwindup_lag(
        P[i, E.KA] * u, x[S.VA, i], P[i, E.TA], P[i, E.VAMIN], P[i, E.VAMAX], IEEE_RULE, 0.0
    )
