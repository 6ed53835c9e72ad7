"""ESAC6A (exc_con type 14): IEEE 421.5-2005 AC6A as PSS/E ESAC6A (PSS/E Model Library;
the same record and diagram in PowerWorld's ESAC6A, OPAL-RT's PSS/E library
``ESAC6A.mo`` and InterPSS's ``Esac6aExciter``): a regulator lead-lag K_A (1 + s
T_K)/(1 + s T_A) and a lead-lag T_C/T_B whose output V_A is clipped to [VAmin, VAmax],
the exciter field current limiter V_H subtracted, V_R limited to [V_t Vrmin, V_t Vrmax]
(an alternator fed from the terminals), the AC exciter as EXAC1's with V_E >= 0.

V_H = (1 + s T_J)/(1 + s T_H) of K_H (V_FE - V_FELIM) clipped to [0, V_HMAX]; V_FE = K_E
V_E + S_E(V_E) V_E + K_D I_fd (PSS/E's quadratic saturation), Efd = V_E F_EX(K_C
I_fd/V_E).  ANDES 2.0 has no AC6A.  The V_A limits are a clip of the second lead-lag's
output, as InterPSS's and PowerWorld's diagram (OPAL-RT's library makes them
non-windup on that lead-lag); none is reached at rest.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.models.blocks import LBND, clip, leadlag, leadlag_input_state
from stabctl.models.declaration import DyrModel, Limits, states
from stabctl.models.exciters.exac1 import exciter, exciter_feedback, initial_exciter, rectified
from stabctl.models.exciters.table import LEAD_LAG, REGULATOR_GAIN, E, upper

if TYPE_CHECKING:
    from stabctl.models.exciters import ExciterParams

AC6A = 14
KINDS = {AC6A: "ESAC6A (IEEE 421.5 AC6A)"}
#: AC6A's saturation point E2 and T_E >= 0, its V_A limits ordered (IEEE Std 421.5 AC6A)
LIMITS = (
    Limits("IEEE Std 421.5 AC6A", nonnegative=("E2", "TE"), ordered=(("VAmax", "VAmin"),)),
    REGULATOR_GAIN,
    LEAD_LAG,
)
#: reads the machine's field current (`stabctl.models.exciters.field_current`)
READS_IFD = True
#: has a rate feedback s K_F/(1 + s T_F) from exc_con columns 21-22 (KF, TF)
RATE_FEEDBACK = False
#: fed by a potential (and compound) source V_B (its ``source_voltage``)
SOURCE = False
#: how it reads exc_con columns 10-15 (K_E, T_E, E1, SE1, E2, SE2; `exciter_params`): "dc"
#: PST's DC exciter (saturation fit by dc_sat, K_E computed where 0), "quadratic" K_E,
#: T_E and PSS/E's quadratic saturation, "linear" K_E and T_E alone, "" not at all
EXCITER_COLUMNS = "quadratic"
#: the time constants that must be >= 1e-3 s: (name in messages, declared field)
NEEDS: tuple[tuple[str, str], ...] = (("TE", "TE"),)

DYR = (
    # ESAC6A -> type 14 (IEEE 421.5 AC6A); saturation: PSS/E's quadratic through the points
    DyrModel(
        "ESAC6A",
        (
            "TR",
            "KA",
            "TA",
            "TK",
            "TB",
            "TC",
            "VAMAX",
            "VAMIN",
            "VRMAX",
            "VRMIN",
            "TE",
            "VFELIM",
            "KH",
            "VHMAX",
            "TH",
            "TJ",
            "KC",
            "KD",
            "KE",
            "E1",
            "SE1",
            "E2",
            "SE2",
        ),
        upper(
            "TR",
            "KA",
            "TA",
            "TK",
            "TB",
            "TC",
            "VAmax",
            "VAmin",
            "Vrmax",
            "Vrmin",
            "TE",
            "VFELIM",
            "KH",
            "VHMAX",
            "TH",
            "TJ",
            "KC",
            "KD",
            "KE",
            "E1",
            "SE1",
            "E2",
            "SE2",
        ),
        kind=AC6A,
    ),
)

#: the states: transducer, the K_A lead-lag, the T_C/T_B lead-lag, the exciter's V_E, the
#: field current limiter's lead-lag
S = states("ESAC6AStates", ("VTR", "VK", "VAs", "VE", "VHs"))
STATE_NAMES = {AC6A: S._fields}


def has_state(p: ExciterParams):
    """Which of the slots of `S` are states (a block whose time constant is below 1e-3 s
    has none), boolean arrays (n_exc,) in slot order, read on this type's rows by
    `stabctl.models.exciters.ExciterParams.has_state`."""
    return (p.has_TR, p.has_TA, p.has_TB, np.ones(p.n, bool), p.TH >= LBND)


def time_constants(p: ExciterParams):
    """The time constants of this type that set a state's speed besides the family's T_R,
    T_A, T_B and rate feedback T_F (`stabctl.models.exciters.ExciterParams.time_constants`):
    the exciter T_E, the limiter's lag T_H; label -> (values, where)."""
    return {"exc_con T_E": (p.TE, True), "exc_con T_H": (p.TH, p.TH >= LBND)}


def limiter_input(KH, VFE, VFELIM, VHMAX):
    """The field current limiter's input clip(K_H (V_FE - V_FELIM), 0, V_HMAX), pu."""
    return np.clip(KH * (VFE - VFELIM), 0.0, VHMAX)


def initialise(p: ExciterParams, r, vex, eterm, VB, x):
    """ESAC6A at rest on rows r (a mask): `exac1.initial_exciter`'s V_E0 and V_FE0 = V_R0,
    the limiter V_H0 = `limiter_input`, V_A0 = V_FE0 + V_H0, the lead-lags at rest on
    V_A0/K_A and V_H0; writes x, returns (V_ref - V_TR = V_A0/K_A, p).

    Raises
    ------
    InitialLimitError
        V_R0 outside [V_t0 Vrmin, V_t0 Vrmax] or V_A0 outside [VAmin, VAmax].
    """

    def checks(i, vfe):
        va = vfe + limiter_input(p.KH[i], vfe, p.VFELIM[i], p.VHMAX[i])
        return [
            ("V_R", "V_t Vrmin, V_t Vrmax", vfe, eterm[i] * p.Vrmin[i], eterm[i] * p.Vrmax[i]),
            ("V_A", "VAmin, VAmax", va, p.VAmin[i], p.VAmax[i]),
        ]

    VE, VFE = initial_exciter(p, r, vex, lambda i: "ESAC6A", None, checks)
    VH = limiter_input(p.KH[r], VFE[r], p.VFELIM[r], p.VHMAX[r])
    VA = VFE[r] + VH
    lead_k = np.where(p.TA[r] >= LBND, p.TK[r] / np.where(p.TA[r] >= LBND, p.TA[r], 1.0), 1.0)
    lead_h = np.where(p.TH[r] >= LBND, p.TJ[r] / np.where(p.TH[r] >= LBND, p.TH[r], 1.0), 1.0)
    x[S.VK, r] = (1.0 - lead_k) * VA  # `blocks.leadlag` at rest: (1 - T_K/T_A) K_A u
    x[S.VAs, r] = VA
    x[S.VE, r] = VE[r]
    x[S.VHs, r] = (1.0 - lead_h) * VH
    return VA / p.KA[r], p


@kernel(inline="always")
def field_voltage(P, x, i, VTR_alg, pss_out, VB, ifd, ieee):
    """ESAC6A: the AC exciter's output (`exac1.rectified`)."""
    return rectified(P, i, x[S.VE, i], ifd)


@kernel(inline="always")
def derivatives(P, x, i, err, eterm, efd, ifd, pss_out, VB, dx, ieee, reach):
    """ESAC6A (docs/pst_models.md 2.13): K_A (1 + s T_K)/(1 + s T_A) on the error, the
    lead-lag T_C/T_B, V_A clipped to [VAmin, VAmax], V_R = V_A - V_H clipped to [eterm
    Vrmin, eterm Vrmax] (eterm the terminal voltage, pu), the exciter T_E dV_E/dt = V_R -
    V_FE with V_E >= 0 non-windup; V_H the lead-lag T_J/T_H of the limiter's input."""
    VFE = exciter_feedback(P, i, x[S.VE, i], ifd)
    y, dx[S.VK, i] = leadlag(err, x[S.VK, i], P[i, E.TK], P[i, E.TA], P[i, E.KA])
    u, dx[S.VAs, i] = leadlag_input_state(y, x[S.VAs, i], P[i, E.TCTB], P[i, E.TB])
    VA = clip(u, P[i, E.VAMIN], P[i, E.VAMAX])
    uh = clip(P[i, E.KH] * (VFE - P[i, E.VFELIM]), 0.0, P[i, E.VHMAX])
    VH, dx[S.VHs, i] = leadlag(uh, x[S.VHs, i], P[i, E.TJ], P[i, E.TH])
    VR = clip(VA - VH, eterm * P[i, E.VRMIN], eterm * P[i, E.VRMAX])
    x[S.VE, i], dx[S.VE, i] = exciter(P, i, x[S.VE, i], VR, VFE)
