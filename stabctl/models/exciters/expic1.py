"""EXPIC1 (exc_con type 15): PSS/E's proportional-integral excitation system EXPIC1 (PSS/E
Model Library; the same record and diagram in PowerWorld's EXPIC1 and OPAL-RT's PSS/E
library ``EXPIC1.mo``).

The error less the rate feedback into a PI K_A (1 + s T_A1)/s, non-windup on [VR2, VR1]
(`blocks.pi_nonwindup`); (1 + s T_A3)/((1 + s T_A2)(1 + s T_A4)) (a lead-lag T_A3/T_A4
and a lag T_A2) clipped to [VRMAX, VRMIN] -> V_R; E_0 = V_B V_R clipped to [EFDMIN,
EFDMAX], V_B = V_E F_EX(K_C I_fd/V_E) with V_E = |K_P V_t + j K_I I_t| (V_B = 1 where K_P =
K_I = 0); with T_E the exciter T_E dEfd/dt = E_0 - (K_E + S_E(Efd)) Efd (PSS/E's
quadratic saturation), without it Efd = E_0.  The rate feedback s K_F/((1 + s
T_F1)(1 + s T_F2)) of V_R.  ANDES 2.0 has no EXPIC1.

Columns: T_A2, T_A3, T_A4 are exc_con's T_A, T_C, T_B (the lag and the lead-lag), VR1,
VR2 its VAmax, VAmin, T_F1 its T_F; T_A1, T_F2, EFDMIN, K_P, K_I columns 58-62 (K_P, K_I
replace the ST3's complex K_P and K_I for this type, `ExciterParams`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel, njit
from stabctl.errors import CaseError, refuse_initial
from stabctl.models.blocks import (
    GAIN_OVER_T,
    LBND,
    clip,
    lag,
    leadlag_input_state,
    pi_nonwindup,
    washout,
)
from stabctl.models.declaration import DyrModel, Limits, beyond, states
from stabctl.models.exciters.dc import dc_feedback
from stabctl.models.exciters.esst4b import source_voltage as rectified_source
from stabctl.models.exciters.table import LEAD_LAG, REGULATOR_GAIN, E, upper

if TYPE_CHECKING:
    from stabctl.models.exciters import ExciterParams

PIC1 = 15
KINDS = {PIC1: "EXPIC1 (PSS/E proportional-integral exciter)"}
#: EXPIC1's saturation point E2 and T_E >= 0, its PI (VR1, VR2) and E_0 limits ordered
#: (PSS/E Model Library EXPIC1)
LIMITS = (
    Limits(
        "PSS/E Model Library EXPIC1",
        nonnegative=("E2", "TE"),
        ordered=(("VAmax", "VAmin"), ("Efdmax", "Efdmin")),
    ),
    REGULATOR_GAIN,
    LEAD_LAG,
)
#: reads the machine's field current (`stabctl.models.exciters.field_current`)
READS_IFD = True
#: has a rate feedback s K_F/(1 + s T_F) from exc_con columns 21-22 (KF, TF)
RATE_FEEDBACK = True
#: fed by a potential (and compound) source V_B (its ``source_voltage``)
SOURCE = True
#: how it reads exc_con columns 10-15 (K_E, T_E, E1, SE1, E2, SE2; `exciter_params`): "dc"
#: PST's DC exciter (saturation fit by dc_sat, K_E computed where 0), "quadratic" K_E,
#: T_E and PSS/E's quadratic saturation, "linear" K_E and T_E alone, "" not at all
EXCITER_COLUMNS = "quadratic"
#: the time constants that must be >= 1e-3 s: (name in messages, declared field)
NEEDS: tuple[tuple[str, str], ...] = ()

DYR = (
    # EXPIC1 -> type 15; T_A2, T_A3, T_A4 into the lag T_A and the lead-lag T_C/T_B
    DyrModel(
        "EXPIC1",
        (
            "TR",
            "KA",
            "TA1",
            "VR1",
            "VR2",
            "TA2",
            "TA3",
            "TA4",
            "VRMAX",
            "VRMIN",
            "KF",
            "TF1",
            "TF2",
            "EFDMAX",
            "EFDMIN",
            "KE",
            "TE",
            "E1",
            "SE1",
            "E2",
            "SE2",
            "KP",
            "KI",
            "KC",
        ),
        {
            **upper("TR", "KA", "TA1", "Vrmax", "Vrmin", "KF", "Efdmax", "KE", "TE"),
            **upper("E1", "SE1", "E2", "SE2", "KC", "Efdmin"),
            "VAmax": "VR1",
            "VAmin": "VR2",
            "TA": "TA2",
            "TC": "TA3",
            "TB": "TA4",
            "TF": "TF1",
            "TF_2": "TF2",
            "KP_pic": "KP",
            "KI_pic": "KI",
        },
        kind=PIC1,
    ),
)

#: the states: transducer, the PI's integral, the lead-lag T_A3/T_A4, the lag T_A2, the
#: exciter's Efd (with T_E), the rate feedback's washout T_F1 and lag T_F2
S = states("EXPIC1States", ("VTR", "PIi", "VLL", "VRl", "Efd", "Rf1", "Rf2"))
STATE_NAMES = {PIC1: S._fields}


def has_state(p: ExciterParams):
    """Which of the slots of `S` are states (a block whose time constant is below 1e-3 s,
    or a feedback whose gain is 0, has none), boolean arrays (n_exc,) in slot order, read
    on this type's rows by `stabctl.models.exciters.ExciterParams.has_state`."""
    on = np.ones(p.n, bool)
    rf = p.KF != 0
    return (p.has_TR, on, p.has_TB, p.has_TA, p.TE >= LBND, rf, rf & (p.TF_2 >= LBND))


def time_constants(p: ExciterParams):
    """The time constants of this type that set a state's speed besides the family's T_R,
    T_A, T_B and rate feedback T_F (`stabctl.models.exciters.ExciterParams.time_constants`):
    the exciter T_E and the rate feedback's second lag T_F2, each where it exists; label ->
    (values, where)."""
    return {
        "exc_con T_E (EXPIC1)": (p.TE, p.TE >= LBND),
        "exc_con T_F2 (EXPIC1)": (p.TF_2, p.TF_2 >= LBND),
    }


def initialise(p: ExciterParams, r, vex, eterm, VB, x):
    """EXPIC1 at rest on rows r (a mask): E_0 = (K_E + S_E(Efd0)) Efd0 with T_E (Efd0
    without), V_R0 = E_0/V_B0 (VB the source voltages, `source_voltage`), the PI's
    integral, the lead-lag, the lag and the washout at V_R0; writes x, returns (V_ref -
    V_TR = 0, p).

    Raises
    ------
    CaseError
        K_F != 0 with neither T_A2 nor T_F2 (the rate feedback an algebraic loop).
    InitialLimitError
        V_B0 <= 0, E_0 outside [EFDMIN, EFDMAX], V_R0 outside [VRMIN, VRMAX] or [VR2, VR1].
    """
    for i in np.nonzero(r & (p.KF != 0) & (p.TA < LBND) & (p.TF_2 < LBND))[0]:
        raise CaseError(
            f"exc_con row {i + 1}, fields 'TA' (T_A2, column 5), 'TF_2' (column 59): EXPIC1 "
            "with a rate feedback (K_F != 0) needs T_A2 or T_F2 >= 1e-3 s"
        )
    with_te = p.TE >= LBND
    E0 = np.array(
        [
            dc_feedback(p.KE[i], p.Asat[i], p.Bsat[i], 1.0, vex[i]) if with_te[i] else vex[i]
            for i in range(p.n)
        ]
    )
    VR = E0 / np.where(VB > 0, VB, 1.0)
    bad = r & (
        (VB <= 0)
        | beyond(E0, p.Efdmin, p.Efdmax)
        | beyond(VR, p.Vrmin, p.Vrmax)
        | beyond(VR, p.VAmin, p.VAmax)
    )
    refuse_initial(
        "exc_con",
        bad,
        lambda i: (
            f"exc_con row {i + 1}: EXPIC1 at rest: source V_B = {VB[i]:.4f} pu (must be "
            f"> 0), E_0 = {E0[i]:.4f} pu (in [EFDMIN, EFDMAX] = [{p.Efdmin[i]:.4f}, "
            f"{p.Efdmax[i]:.4f}]), regulator output V_R = {VR[i]:.4f} pu (in [VRMIN, VRMAX] "
            f"= [{p.Vrmin[i]:.4f}, {p.Vrmax[i]:.4f}] and the PI's [VR2, VR1] = "
            f"[{p.VAmin[i]:.4f}, {p.VAmax[i]:.4f}])"
        ),
    )
    for slot in (S.PIi, S.VLL, S.VRl, S.Rf1):
        x[slot, r] = VR[r]
    x[S.Efd, r] = vex[r]
    return np.zeros(np.count_nonzero(r)), p


@njit
def source_voltage(KP, KI, XL, KC, cap, machine, init):
    """EXPIC1's source V_B: `esst4b.source_voltage` (V_E F_EX(K_C I_fd/V_E), V_E = |K_P V_t
    + j K_I I_t| with X_L = 0 and K_P real: the real part of the complex KP the family
    hands every source type), 1 where K_P = K_I = 0 (PSS/E Model Library)."""
    kp = KP.real
    if kp == 0 and KI == 0:
        return 1.0
    return rectified_source(kp, KI, XL, KC, cap, machine, init)


@kernel(inline="always")
def _feedback(P, x, i):
    """The rate feedback's output where it is a state's function: the T_F2 lag's state,
    else (K_F/T_F1) (V_R - R_f1) with V_R the clipped T_A2 lag state; 0 without K_F."""
    if P[i, E.KF] == 0:
        return 0.0
    if P[i, E.TF_2] >= LBND:
        return x[S.Rf2, i]
    VR = clip(x[S.VRl, i], P[i, E.VRMIN], P[i, E.VRMAX])
    return P[i, E.KF] / P[i, E.TF] * (VR - x[S.Rf1, i])


@kernel(inline="always")
def regulator(P, x, i, err):
    """The PI, the lead-lag T_A3/T_A4 and the lag T_A2 on err less the rate feedback:
    (V_R clipped to [VRMIN, VRMAX], the PI integral's, the lead-lag's and the lag's
    derivatives)."""
    u = err - _feedback(P, x, i)
    KA = P[i, E.KA]
    y, dpi = pi_nonwindup(u, x[S.PIi, i], KA * P[i, E.TA1], KA, P[i, E.VAMIN], P[i, E.VAMAX])
    w, dll = leadlag_input_state(y, x[S.VLL, i], P[i, E.TCTB], P[i, E.TB])
    v, dlag = lag(w, x[S.VRl, i], P[i, E.TA])
    return clip(v, P[i, E.VRMIN], P[i, E.VRMAX]), dpi, dll, dlag


@kernel(inline="always")
def exciter_input(P, i, VR, VB):
    """E_0 = V_B V_R clipped to [EFDMIN, EFDMAX]."""
    return clip(VB * VR, P[i, E.EFDMIN], P[i, E.EFDMAX])


@kernel(inline="always")
def field_voltage(P, x, i, VTR_alg, pss_out, VB, ifd, ieee):
    """EXPIC1: the exciter's state Efd with T_E, else E_0 from the regulator
    (`regulator`, on the error of the transducer's output for VTR_alg, pu)."""
    if P[i, E.TE] >= LBND:
        return x[S.Efd, i]
    err = P[i, E.VREF] - lag(VTR_alg, x[S.VTR, i], P[i, E.TR])[0] + pss_out
    return exciter_input(P, i, regulator(P, x, i, err)[0], VB)


@kernel(inline="always")
def derivatives(P, x, i, err, eterm, efd, ifd, pss_out, VB, dx, ieee, reach):
    """EXPIC1 (docs/pst_models.md 2.14): the regulator (`regulator`), the rate feedback
    of V_R (washout T_F1 with gain K_F, lag T_F2), the exciter T_E dEfd/dt = E_0 - (K_E +
    S_E(Efd)) Efd with T_E."""
    VR, dx[S.PIi, i], dx[S.VLL, i], dx[S.VRl, i] = regulator(P, x, i, err)
    if P[i, E.KF] != 0:
        w, dx[S.Rf1, i] = washout(VR, x[S.Rf1, i], P[i, E.TF], P[i, E.KF], GAIN_OVER_T)
        dx[S.Rf2, i] = lag(w, x[S.Rf2, i], P[i, E.TF_2])[1]
    if P[i, E.TE] >= LBND:
        Efd = x[S.Efd, i]
        VFE = dc_feedback(P[i, E.KE], P[i, E.ASAT], P[i, E.BSAT], P[i, E.SATQ], Efd)
        dx[S.Efd, i] = (exciter_input(P, i, VR, VB) - VFE) / P[i, E.TE]
