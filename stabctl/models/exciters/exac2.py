"""EXAC2 (exc_con type 13): IEEE 1981 AC2 as PSS/E EXAC2 (PSS/E Model Library; the same
record and diagram in PowerWorld's EXAC2, OPAL-RT's PSS/E library ``EXAC2.mo`` and ANDES
2.0 ``exac2.py``): EXAC1's regulator and AC exciter with the exciter field current
feedback K_H V_FE and limiter K_L (V_LR - V_FE) of the high-initial-response alternator.

Rate feedback s K_F/(1 + s T_F) of V_FE subtracted from the error, lead-lag T_C/T_B,
K_A/(1 + s T_A) non-windup on [VAmax, VAmin] -> V_A; V_H = V_A - K_H V_FE and V_L = K_L
(V_LR - V_FE) into a low-value gate, times K_B, clipped to [Vrmin, Vrmax] -> V_R; the
exciter T_E dV_E/dt = V_R - V_FE (`exac1.exciter`, no limit on V_E as EXAC1's), V_FE =
K_E V_E + S_E(V_E) V_E + K_D I_fd (PSS/E's quadratic saturation), Efd = V_E F_EX(K_C
I_fd/V_E).

At rest V_R0 = V_FE0 and V_A0 = V_FE0 (1/K_B + K_H), the gate passing V_H: a start where
K_B K_L (V_LR - V_FE0) < V_FE0 (the limiter would hold the exciter) is refused by name
(PSS/E: "initial conditions suspect"), as V_R0 or V_A0 outside their limits.  ANDES 2.0
differs twice (docs/pst_models.md 2.12): its V_ref is V_t + (K_L + 1/K_B) V_FE0/K_A (K_L
where the diagram has K_H) and it raises V_LR to V_FE0 (1 + 1/(K_L K_B)) where the gate
would pass V_L at the start.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.errors import CaseError
from stabctl.models.blocks import (
    GAIN_OVER_T,
    clip,
    leadlag_input_state,
    nonwindup_lag,
    washout,
)
from stabctl.models.declaration import DyrModel, Limits, states
from stabctl.models.exciters.exac1 import exciter, exciter_feedback, initial_exciter, rectified
from stabctl.models.exciters.table import IEEE_RULE, LEAD_LAG, REGULATOR_GAIN, E, upper

if TYPE_CHECKING:
    from stabctl.models.exciters import ExciterParams

AC2 = 13
KINDS = {AC2: "EXAC2 (IEEE AC2)"}
#: AC2's saturation point E2 and T_E >= 0, its V_A limits ordered (PSS/E Model Library
#: EXAC2; IEEE Std 421.5 AC2A)
LIMITS = (
    Limits("PSS/E Model Library EXAC2", nonnegative=("E2", "TE"), ordered=(("VAmax", "VAmin"),)),
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
EXCITER_COLUMNS = "quadratic"
#: the time constants that must be >= 1e-3 s: (name in messages, declared field)
NEEDS: tuple[tuple[str, str], ...] = (("TE", "TE"),)

#: the record's parameters, PSS/E Model Library order (ANDES psse-dyr.yaml's the same)
_FIELDS = (
    "TR", "TB", "TC", "KA", "TA", "VAMAX", "VAMIN", "KB", "VRMAX", "VRMIN", "TE", "KL", "KH",
    "KF", "TF", "KC", "KD", "KE", "VLR", "E1", "SE1", "E2", "SE2",
)  # fmt: skip

DYR = (
    # EXAC2 -> type 13 (IEEE 1981 AC2); saturation: PSS/E's quadratic through the points
    DyrModel(
        "EXAC2",
        _FIELDS,
        upper(
            "TR",
            "TB",
            "TC",
            "KA",
            "TA",
            "VAmax",
            "VAmin",
            "KB",
            "Vrmax",
            "Vrmin",
            "TE",
            "KL",
            "KH",
            "KF",
            "TF",
            "KC",
            "KD",
            "KE",
            "VLR",
            "E1",
            "SE1",
            "E2",
            "SE2",
        ),
        kind=AC2,
        andes=("EXAC2",),
    ),
)

#: the states: transducer, lead-lag, regulator V_A, the exciter's V_E, the rate
#: feedback's washout R_f
S = states("EXAC2States", ("VTR", "VAs", "VA", "VE", "Rf"))
STATE_NAMES = {AC2: S._fields}


def has_state(p: ExciterParams):
    """Which of the slots of `S` are states (a block whose time constant is below 1e-3 s,
    or a feedback whose gain is 0, has none), boolean arrays (n_exc,) in slot order, read
    on this type's rows by `stabctl.models.exciters.ExciterParams.has_state`."""
    return (p.has_TR, p.has_TB, p.has_TA, np.ones(p.n, bool), p.has_Rf)


def time_constants(p: ExciterParams):
    """The time constants of this type that set a state's speed besides the family's T_R,
    T_A, T_B and rate feedback T_F (`stabctl.models.exciters.ExciterParams.time_constants`):
    the exciter T_E; label -> (values, where)."""
    return {"exc_con T_E": (p.TE, True)}


#: the fast loop `inner_loop_time_constants` measures, named where it sets the step
INNER_LOOP = (
    "EXAC2 regulator and exciter loop K_A/(1 + s T_A), 1/(s T_E) with its rate feedback "
    "s K_F/(1 + s T_F) (half Heun's largest stable step)"
)


def inner_loop_time_constants(p: ExciterParams, r, VB0, efd0):
    """Per EXAC2 of rows r, half the largest step at which Heun's method keeps its
    regulator and exciter loop (`loop_matrix`) stable (`heun_step_limit`), s, (n_exc,);
    inf for the other rows: the "time constant" that `check_step`'s h < 2 T and the
    default step's 0.5 T read (for a real mode 1/|lambda| itself).  efd0 the field
    voltages at rest (pu): V_E0 as `exac1.initial_exciter` solves it; VB0 unused."""
    tau = np.full(p.n, np.inf)
    VE, _ = initial_exciter(p, r, efd0, lambda i: "EXAC2", None, lambda i, v: [])
    for i in np.nonzero(r)[0]:
        lam = np.linalg.eigvals(loop_matrix(p, i, VE[i]))
        tau[i] = 0.5 * heun_step_limit(lam)
    return tau


def initialise(p: ExciterParams, r, vex, eterm, VB, x):
    """EXAC2 at rest on rows r (a mask): `exac1.initial_exciter`'s V_E0 and V_FE0 = V_R0,
    V_A0 = V_FE0 (1/K_B + K_H) (the gate passing V_H), the lead-lag V_A0/K_A, the washout
    V_FE0; writes x, returns (V_ref - V_TR, p).

    Raises
    ------
    CaseError
        K_B <= 0 (exc_con column 49).
    InitialLimitError
        V_R0 outside [Vrmin, Vrmax], V_A0 outside [VAmin, VAmax], or the low-value gate
        passing V_L at the start: K_B K_L (V_LR - V_FE0) < V_FE0.
    """
    for i in np.nonzero(r & (p.KB <= 0))[0]:
        raise CaseError(f"exc_con row {i + 1}, field 'KB' (column 49): EXAC2 needs K_B > 0")

    def checks(i, vfe):
        va = vfe * (1.0 / p.KB[i] + p.KH[i])
        return [
            ("V_R", "Vrmin, Vrmax", vfe, p.Vrmin[i], p.Vrmax[i]),
            ("V_A", "VAmin, VAmax", va, p.VAmin[i], p.VAmax[i]),
            ("K_B V_L", "V_FE0, inf", p.KB[i] * p.KL[i] * (p.VLR[i] - vfe), vfe, np.inf),
        ]

    VE, VFE = initial_exciter(p, r, vex, lambda i: "EXAC2", None, checks)
    VA = VFE[r] * (1.0 / p.KB[r] + p.KH[r])
    x[S.VAs, r] = VA / p.KA[r]
    x[S.VA, r] = VA
    x[S.VE, r] = VE[r]
    x[S.Rf, r] = VFE[r]
    return VA / p.KA[r], p


@kernel(inline="always")
def field_voltage(P, x, i, VTR_alg, pss_out, VB, ifd, ieee):
    """EXAC2: the AC exciter's output (`exac1.rectified`)."""
    return rectified(P, i, x[S.VE, i], ifd)


@kernel(inline="always")
def derivatives(P, x, i, err, eterm, efd, ifd, pss_out, VB, dx, ieee, reach):
    """EXAC2 (docs/pst_models.md 2.12): the rate feedback of V_FE (state R_f, with K_F !=
    0) subtracted from the error, the lead-lag T_C/T_B, the regulator lag V_A non-windup
    on [VAmin, VAmax], V_R = K_B min(V_A - K_H V_FE, K_L (V_LR - V_FE)) clipped to [Vrmin,
    Vrmax], the exciter T_E dV_E/dt = V_R - V_FE."""
    VFE = exciter_feedback(P, i, x[S.VE, i], ifd)
    if P[i, E.KF] != 0:
        VF, dx[S.Rf, i] = washout(VFE, x[S.Rf, i], P[i, E.TF], P[i, E.KF], GAIN_OVER_T)
        err = err - VF
    u, dx[S.VAs, i] = leadlag_input_state(err, x[S.VAs, i], P[i, E.TCTB], P[i, E.TB])
    x[S.VA, i], dx[S.VA, i] = nonwindup_lag(
        P[i, E.KA] * u, x[S.VA, i], P[i, E.TA], P[i, E.VAMIN], P[i, E.VAMAX], IEEE_RULE, 0.0
    )
    gate = min(x[S.VA, i] - P[i, E.KH] * VFE, P[i, E.KL] * (P[i, E.VLR] - VFE))
    VR = clip(P[i, E.KB] * gate, P[i, E.VRMIN], P[i, E.VRMAX])
    x[S.VE, i], dx[S.VE, i] = exciter(P, i, x[S.VE, i], VR, VFE)


def heun_step_limit(lam: np.ndarray) -> float:
    """The largest step h (s) at which Heun's predictor-corrector (the explicit
    integrator, stability function R(z) = 1 + z + z^2/2) keeps every mode ``lam`` (1/s,
    complex, shape (n,)) from growing, |R(lam h)| <= 1: 2/|lam| for a real negative lam,
    less for a lightly damped pair (R grows along the imaginary axis); inf when no mode
    has Re(lam) < 0.  Bisection on h, relative accuracy 1e-9."""
    lam = lam[lam.real < 0]
    if lam.size == 0:
        return np.inf

    def grows(h):
        z = lam * h
        return bool(np.any(np.abs(1 + z + z * z / 2) > 1 + 1e-12))

    hi = 2.0 / np.max(np.abs(lam))  # the real axis' limit bounds every mode's
    if not grows(hi):
        return float(hi)
    lo = 0.0
    while hi - lo > 1e-9 * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if grows(mid) else (mid, hi)
    return float(lo)


def loop_matrix(p: ExciterParams, i: int, VE0: float) -> np.ndarray:
    """The state matrix (1/s) of EXAC2 row i's regulator and exciter at rest, limits
    inactive, the gate passing V_H, the terminal voltage and field current held: states
    (those that exist) the lead-lag V_As, the regulator V_A, the exciter V_E, the rate
    feedback's washout R_f; V_FE's slope g = K_E + d(S_E V_E)/dV_E at V_E0 (PSS/E's
    quadratic).  Its fast pair is the rate feedback's loop through T_E: with ACTIVSg2000's
    K_A = 1000, T_A = 0.05 s, K_F = 0.49, T_E = 0.55 s and saturated exciters, -12 +-
    184j 1/s (bus 1079), which Heun's method at half a cycle does not keep stable.

    Returns
    -------
    ndarray, shape (n, n)
        n the number of those states, in that order.
    """
    g = p.KE[i] + (2 * p.Bsat[i] * (VE0 - p.Asat[i]) if VE0 > p.Asat[i] else 0.0)
    on = [p.has_TB[i], p.has_TA[i], True, p.KF[i] != 0]

    def rhs(z):
        VAs, VA, VE, Rf = z
        err = -(p.KF[i] / p.TF[i] * (g * VE - Rf) if on[3] else 0.0)
        u = p.tc_tb[i] * err + (1 - p.tc_tb[i]) * VAs if on[0] else err
        if not on[1]:
            VA = p.KA[i] * u
        VR = p.KB[i] * (VA - p.KH[i] * g * VE)
        d = [
            (err - VAs) / p.TB[i] if on[0] else 0.0,
            (p.KA[i] * u - VA) / p.TA[i] if on[1] else 0.0,
            (VR - g * VE) / p.TE[i],
            (g * VE - Rf) / p.TF[i] if on[3] else 0.0,
        ]
        return np.array(d)

    keep = [k for k in range(4) if on[k]]
    J = np.column_stack([rhs(np.eye(4)[k]) for k in keep])
    return J[keep]
