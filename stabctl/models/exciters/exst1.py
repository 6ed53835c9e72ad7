"""EXST1 (exc_con type 4): PSS/E's IEEE ST1 simplified.

Rate feedback s K_F/(1 + s T_F) of Efd (psse_st1: of V_R) subtracted from the error, V_I
limited, lead-lag, K_A/(1 + s T_A); output limited to [V_t Vrmin, V_t Vrmax - K_C I_fd]
(psse_st1: [V_t Vrmin - K_C I_fd, V_t Vrmax - K_C I_fd]).  Source: PSS/E Model Library
EXST1 (IEEE Std 421.5 ST1A simplified); docs/pst_models.md 2.4.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.errors import refuse_initial
from stabctl.models.blocks import GAIN_OVER_T, LBND, clip, lag, leadlag_input_state, washout
from stabctl.models.declaration import DyrModel, Limits, beyond, states
from stabctl.models.exciters.table import LEAD_LAG, REGULATOR_GAIN, E, upper

if TYPE_CHECKING:
    from stabctl.models.exciters import ExciterParams

ST1 = 4
KINDS = {ST1: "EXST1"}
#: EXST1's V_I limits ordered (PSS/E Model Library EXST1)
LIMITS = (
    Limits("PSS/E Model Library EXST1", ordered=(("VImax", "VImin"),)),
    REGULATOR_GAIN,
    LEAD_LAG,
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
    DyrModel(
        "EXST1",
        ("TR", "VIMAX", "VIMIN", "TC", "TB", "KA", "TA", "VRMAX", "VRMIN", "KC", "KF", "TF"),
        upper("TR", "KA", "TA", "TB", "TC", "Vrmax", "Vrmin", "VImax", "VImin", "KC", "KF", "TF"),
        kind=ST1,
        andes=("EXST1",),
    ),
)

#: the states: transducer, lead-lag, regulator V_R, the rate feedback's washout R_f
S = states("EXST1States", ("VTR", "VAs", "VR", "Rf"))
STATE_NAMES = {ST1: S._fields}


def has_state(p: ExciterParams):
    """Which of the slots of `S` are states (a block whose time constant is below 1e-3 s,
    or a feedback whose gain is 0, has none), boolean arrays (n_exc,) in slot order, read
    on this type's rows by `stabctl.models.exciters.ExciterParams.has_state`."""
    return (p.has_TR, p.has_TB, p.has_TA, p.has_Rf)


def time_constants(p: ExciterParams):
    """The time constants of this type that set a state's speed besides the family's T_R,
    T_A, T_B and rate feedback T_F (`stabctl.models.exciters.ExciterParams.time_constants`):
    none beyond the shared ones; label -> (values, where)."""
    return {}


#: the fast loop `inner_loop_time_constants` measures, named where it sets the step
INNER_LOOP = "regulator loop K_A/(1 + s T_A) with its rate feedback s K_F/(1 + s T_F)"


def inner_loop_time_constants(p: ExciterParams, r, VB0, efd0):
    """The fastest pole of the EXST1 (and ESST1A) regulator loops of rows r (s),
    (n_exc,); inf for the other rows and where T_A or T_F is below 1e-3 s or K_F = 0 (VB0,
    efd0 unused).

    The lead-lags T_C/T_B (and ESST1A's T_C1/T_B1) feed the lag K_A/(1 + s T_A)
    (state V_R, V_A), whose output returns through s K_F/(1 + s T_F) (state R_f) to
    the voltage error: the linear loop of those states (limits inactive, the terminal
    voltage and field current held), whose fastest eigenvalue's time constant is
    returned.  PSID's ESST1A run of PSS/E's (K_A = 200, T_A = 0.1 s, K_F = T_F =
    0.01 s, lead-lags 14.1/20 s): 9.0e-4 s where T_F suggests 0.01 s, and Heun at
    5 ms diverges."""
    tau = np.full(p.n, np.inf)
    loop = r & p.has_Rf & p.has_TA & (p.TF >= LBND)
    for i in np.nonzero(loop)[0]:
        lags = [(ratio[i], T[i]) for ratio, T, on in ((p.tc_tb, p.TB, p.has_TB),
                (p.tc1_tb1, p.TB1, p.has_TB1)) if on[i]]  # fmt: skip
        n = len(lags)
        A = np.zeros((n + 2, n + 2))  # lead-lag states, V_A, R_f
        kf = p.KF[i] / p.TF[i]
        u = np.zeros(n + 2)  # the voltage error: -K_F/T_F (V_A - R_f)
        u[n], u[n + 1] = -kf, kf
        for k, (ratio, T) in enumerate(lags):  # PST form: y = r u + (1 - r) x
            A[k] = u / T
            A[k, k] -= 1.0 / T
            u = ratio * u
            u[k] += 1.0 - ratio
        A[n] = p.KA[i] * u / p.TA[i]
        A[n, n] -= 1.0 / p.TA[i]
        A[n + 1, n], A[n + 1, n + 1] = 1.0 / p.TF[i], -1.0 / p.TF[i]
        tau[i] = 1.0 / np.max(-np.linalg.eigvals(A).real)
    return tau


def initialise(p: ExciterParams, r, vex, eterm, VB, x):
    """EXST1 at rest on rows r (a mask): V_R0 = Efd0 within its output limits
    (`check_start`), the lead-lag Efd0/K_A, the washout Efd0 (with K_F != 0); writes x,
    returns (V_ref - V_TR, p)."""
    drop = np.where(p.psse_st1 == 1, p.KC * vex, 0.0)
    lo, hi = eterm * p.Vrmin - drop, eterm * p.Vrmax - p.KC * vex
    check_start(p, r, "EXST1", vex, lo, hi, vex)
    VA = vex[r] / p.KA[r]
    x[S.VAs, r] = VA
    x[S.VR, r] = vex[r]
    x[S.Rf, r] = np.where(p.KF[r] != 0, vex[r], 0.0)
    return VA, p


def check_start(p: ExciterParams, r, name, Efd, lo, hi, VA, VA_limits=False):
    """Raise CaseError for the rows r (a mask) of an exciter whose output is limited to
    [lo, hi] (EXST1, ESST1A, EXAC4) where Efd0 is outside them, or the regulator input
    VA/K_A outside [VImin, VImax], or with VA_limits (ESST1A) VA outside [VAmin, VAmax];
    name is the type's in the message; arrays over all exciters."""
    extra = beyond(VA, p.VAmin, p.VAmax) if VA_limits else False
    bad = r & (beyond(Efd, lo, hi) | beyond(VA / p.KA, p.VImin, p.VImax) | extra)
    refuse_initial(
        "exc_con",
        bad,
        lambda i: (
            f"exc_con row {i + 1}: {name} initial field voltage "
            f"{Efd[i]:.4f} pu outside its output limits or regulator input outside [VImin, "
            "VImax]" + (" or V_A outside [VAmin, VAmax]" if VA_limits else "")
        ),
    )


@kernel(inline="always")
def field_voltage(P, x, i, VTR_alg, pss_out, VB, ifd, ieee):
    """EXST1: V_R clipped to [V_t Vrmin, V_t Vrmax - K_C I_fd] (ifd the machine's field
    current); psse_st1: to [V_t Vrmin - K_C I_fd, V_t Vrmax - K_C I_fd] (PSS/E)."""
    drop = P[i, E.KC] * ifd
    lo = VTR_alg * P[i, E.VRMIN] - (drop if P[i, E.PSSE_ST1] == 1 else 0.0)
    return clip(x[S.VR, i], lo, VTR_alg * P[i, E.VRMAX] - drop)


@kernel(inline="always")
def derivatives(P, x, i, err, eterm, efd, ifd, pss_out, VB, dx, ieee, reach):
    """EXST1 (PSS/E; docs/pst_models.md 2.4): the rate feedback (state R_f, only with
    K_F != 0) of the field voltage efd (psse_st1: of V_R, before the output limits)
    subtracted before the V_I limits."""
    if P[i, E.KF] != 0:
        fed = x[S.VR, i] if P[i, E.PSSE_ST1] == 1 else efd
        VF, dx[S.Rf, i] = washout(fed, x[S.Rf, i], P[i, E.TF], P[i, E.KF], GAIN_OVER_T)
        err = err - VF
    VA, dx[S.VAs, i] = leadlag_input_state(
        clip(err, P[i, E.VIMIN], P[i, E.VIMAX]), x[S.VAs, i], P[i, E.TCTB], P[i, E.TB]
    )
    dx[S.VR, i] = lag(P[i, E.KA] * VA, x[S.VR, i], P[i, E.TA])[1]
