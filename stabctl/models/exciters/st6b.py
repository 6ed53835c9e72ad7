"""ST6B (exc_con type 16): IEEE 421.5-2005 ST6B as PSS/E ST6B (PSS/E Model Library; the
record and equations of PowerSimulationsDynamics.jl's ``ST6B``, OPAL-RT's PSS/E library
``ST6B.mo``): a static exciter behind a PID and an inner field voltage loop.

The PID K_PA + K_IA/s + s K_DA/(1 + s T_DA) on the voltage error, non-windup on [VAmin,
VAmax] (`blocks.pi_nonwindup` on the sum) -> V_A; the inner loop's V_R2 = clip(K_M (V_A -
V_G) + K_FF V_A, Vrmin, Vrmax) and the field current limiter's V_R1 = max(K_LR (K_CI I_LR -
I_fd), Vrmin) into a low-value gate -> V_R; Efd = V_R V_t; V_G = K_G Efd lagged by T_G.
The record's OEL flag (its ICON) selects where an over-excitation limiter's signal
enters: stabctl has none, so the signal is 0 either way.  No PSS/E run of it is
published (docs/pst_models.md 2.15).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.errors import CaseError, refuse_initial
from stabctl.models.blocks import GAIN_BEFORE, LBND, clip, lag, pi_nonwindup, washout
from stabctl.models.declaration import DyrModel, Limits, beyond, states
from stabctl.models.exciters.table import E, upper

if TYPE_CHECKING:
    from stabctl.models.exciters import ExciterParams

ST6B = 16
KINDS = {ST6B: "ST6B (IEEE 421.5 ST6B)"}
#: ST6B's V_A limits ordered (IEEE Std 421.5-2016 ST6B)
LIMITS = Limits("IEEE Std 421.5 ST6B", ordered=(("VAmax", "VAmin"),))
#: reads the machine's field current (`stabctl.models.exciters.field_current`)
READS_IFD = True
#: has a rate feedback s K_F/(1 + s T_F) from exc_con columns 21-22 (KF, TF)
RATE_FEEDBACK = False
#: fed by a potential (and compound) source V_B (its ``source_voltage``)
SOURCE = False
#: how it reads exc_con columns 10-15 (K_E, T_E, E1, SE1, E2, SE2; `exciter_params`): "dc"
#: PST's DC exciter (saturation fit by dc_sat, K_E computed where 0), "quadratic" K_E,
#: T_E and PSS/E's quadratic saturation, "linear" K_E and T_E alone, "" not at all
EXCITER_COLUMNS = ""
#: the time constants that must be >= 1e-3 s: (name in messages, declared field)
NEEDS: tuple[tuple[str, str], ...] = (("TG", "TG"),)

DYR = (
    # ST6B -> type 16; ICON OEL, then the CONs in PSS/E Model Library order
    DyrModel(
        "ST6B",
        (
            "OEL",
            "TR",
            "KPA",
            "KIA",
            "KDA",
            "TDA",
            "VAMAX",
            "VAMIN",
            "KFF",
            "KM",
            "KCI",
            "KLR",
            "ILR",
            "VRMAX",
            "VRMIN",
            "KG",
            "TG",
        ),
        {
            **upper("TR", "Vrmax", "Vrmin", "KFF", "KM", "KCI", "KLR", "ILR", "KG", "TG"),
            "VAmax": "VAMAX",
            "VAmin": "VAMIN",
            "Kpid_P": "KPA",
            "Kpid_I": "KIA",
            "Kpid_D": "KDA",
            "Td": "TDA",
        },
        kind=ST6B,
    ),
)

#: the states: transducer, the PID's integral and derivative washout, the feedback lag V_G
S = states("ST6BStates", ("VTR", "PIi", "PIDd", "VG"))
STATE_NAMES = {ST6B: S._fields}


def has_state(p: ExciterParams):
    """Which of the slots of `S` are states (the integral with K_IA != 0, the derivative
    with K_DA != 0 and T_DA >= 1e-3 s), boolean arrays (n_exc,) in slot order, read on this
    type's rows by `stabctl.models.exciters.ExciterParams.has_state`."""
    return (
        p.has_TR,
        p.Kpid_I != 0,
        (p.Kpid_D != 0) & (p.Td >= LBND),
        np.ones(p.n, bool),
    )


def time_constants(p: ExciterParams):
    """The time constants of this type that set a state's speed besides the family's T_R,
    T_A, T_B and rate feedback T_F (`stabctl.models.exciters.ExciterParams.time_constants`):
    the PID's derivative lag T_DA, the field current feedback's T_G; label -> (values, where)."""
    return {
        "exc_con T_DA (ST6B)": (p.Td, (p.Kpid_D != 0) & (p.Td >= LBND)),
        "exc_con T_G (ST6B)": (p.TG, True),
    }


def initialise(p: ExciterParams, r, vex, eterm, VB, x):
    """ST6B at rest on rows r (a mask): V_R0 = Efd0/V_t0, V_G0 = K_G Efd0, V_A0 = (V_R0 + K_M
    V_G0)/(K_M + K_FF), the integral V_A0 (with K_IA; else the error V_A0/K_PA); writes x,
    returns (V_ref - V_TR, p).

    Raises
    ------
    CaseError
        K_M + K_FF = 0, or K_IA = 0 with K_PA = 0 (no V_A0 has a rest point).
    InitialLimitError
        V_A0 outside [VAmin, VAmax], V_R0 outside [Vrmin, Vrmax], or the field current
        limiter's V_R1 below V_R0 at the start.
    """
    for i in np.nonzero(r & ((p.KFF + p.KM == 0) | ((p.Kpid_I == 0) & (p.Kpid_P == 0))))[0]:
        raise CaseError(
            f"exc_con row {i + 1}: ST6B needs K_M + K_FF != 0 (columns 63-64) and K_IA or "
            "K_PA != 0 (columns 34-35)"
        )
    VR = vex / eterm
    VG = p.KG * vex
    gain = np.where(p.KFF + p.KM != 0, p.KFF + p.KM, 1.0)
    VA = (VR + p.KM * VG) / gain
    VR1 = np.maximum(p.KLR * (p.KCI * p.ILR - vex), p.Vrmin)
    bad = r & (beyond(VA, p.VAmin, p.VAmax) | beyond(VR, p.Vrmin, p.Vrmax) | (VR1 < VR - 1e-9))
    refuse_initial(
        "exc_con",
        bad,
        lambda i: (
            f"exc_con row {i + 1}: ST6B at rest: regulator output V_A = {VA[i]:.4f} pu (in "
            f"[VAmin, VAmax] = [{p.VAmin[i]:.4f}, {p.VAmax[i]:.4f}]), V_R = {VR[i]:.4f} pu "
            f"(in [Vrmin, Vrmax] = [{p.Vrmin[i]:.4f}, {p.Vrmax[i]:.4f}] and below the field "
            f"current limiter's V_R1 = {VR1[i]:.4f} pu)"
        ),
    )
    integral = p.Kpid_I[r] != 0
    x[S.PIi, r] = np.where(integral, VA[r], 0.0)
    x[S.PIDd, r] = 0.0  # the derivative washout's state: the error, 0 at rest
    x[S.VG, r] = VG[r]
    kp = np.where(p.Kpid_P[r] != 0, p.Kpid_P[r], 1.0)
    return np.where(integral, 0.0, VA[r] / kp), p


@kernel(inline="always")
def regulator(P, x, i, err, ifd):
    """The PID (output V_A on [VAmin, VAmax]) and the gate: (V_R, the integral's and the
    derivative washout's derivatives)."""
    pd, dd = 0.0, 0.0
    if P[i, E.KPID_D] != 0 and P[i, E.TD] >= LBND:
        pd, dd = washout(err, x[S.PIDd, i], P[i, E.TD], P[i, E.KPID_D], GAIN_BEFORE)
    VA, di = pi_nonwindup(
        err, x[S.PIi, i] + pd, P[i, E.KPID_P], P[i, E.KPID_I], P[i, E.VAMIN], P[i, E.VAMAX]
    )
    ff = P[i, E.KM] * (VA - x[S.VG, i]) + P[i, E.KFF] * VA
    VR2 = clip(ff, P[i, E.VRMIN], P[i, E.VRMAX])
    VR1 = max(P[i, E.KLR] * (P[i, E.KCI] * P[i, E.ILR] - ifd), P[i, E.VRMIN])
    return min(VR1, VR2), di, dd


@kernel(inline="always")
def field_voltage(P, x, i, VTR_alg, pss_out, VB, ifd, ieee):
    """ST6B: Efd = V_R V_t (`regulator` on the error of the transducer's output for the
    terminal voltage VTR_alg, pu)."""
    err = P[i, E.VREF] - lag(VTR_alg, x[S.VTR, i], P[i, E.TR])[0] + pss_out
    return regulator(P, x, i, err, ifd)[0] * VTR_alg


@kernel(inline="always")
def derivatives(P, x, i, err, eterm, efd, ifd, pss_out, VB, dx, ieee, reach):
    """ST6B (docs/pst_models.md 2.15): the PID's integral and derivative, the feedback lag
    T_G dV_G/dt = K_G V_R V_t - V_G (eterm the terminal voltage, pu)."""
    VR, dx[S.PIi, i], dx[S.PIDd, i] = regulator(P, x, i, err, ifd)
    dx[S.VG, i] = lag(P[i, E.KG] * VR * eterm, x[S.VG, i], P[i, E.TG])[1]
