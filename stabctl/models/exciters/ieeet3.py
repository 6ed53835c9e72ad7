"""IEEET3 (exc_con type 11): IEEE 1968 type 3 as PSS/E IEEET3 and ANDES 2.0 ``ieeet3.py``.

Non-windup K_A/(1 + s T_A) on the error less the rate feedback s K_F/(1 + s T_F) of Efd ->
V_R; the compound source V_B = sqrt(V_E^2 - (0.78 I_fd)^2) added, V_B + V_R limited to
[0, VBmax]; the exciter T_E dEfd/dt = V_B + V_R - K_E Efd.  PSTess has no type 3: IEEE
421.5's non-windup rule in both conventions.  docs/pst_models.md 2.9.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel, njit
from stabctl.errors import refuse_initial
from stabctl.models.blocks import GAIN_OVER_T, clip, nonwindup_lag, washout
from stabctl.models.declaration import DyrModel, Limits, beyond, states
from stabctl.models.exciters.table import IEEE_RULE, REGULATOR_GAIN, E, potential_source, upper

if TYPE_CHECKING:
    from stabctl.models.exciters import ExciterParams

T3 = 11
KINDS = {T3: "IEEET3 (IEEE 1968 type 3, compound source)"}
#: IEEET3's exciter time constant T_E >= 0 (PSS/E Model Library IEEET3)
LIMITS = (
    Limits("PSS/E Model Library IEEET3", nonnegative=("TE",)),
    REGULATOR_GAIN,
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
EXCITER_COLUMNS = "linear"
#: the time constants that must be >= 1e-3 s: (name in messages, declared field)
NEEDS: tuple[tuple[str, str], ...] = (("TA", "TA"), ("TE", "TE"))

DYR = (
    # IEEET3 -> type 11 (IEEE 1968 type 3), PSS/E's CON order (ANDES's psse-dyr.yaml
    # lists VBMAX and KE elsewhere; its inputs are matched by name)
    DyrModel(
        "IEEET3",
        ("TR", "KA", "TA", "VRMAX", "VRMIN", "TE", "KF", "TF", "KP", "KI", "VBMAX", "KE"),
        upper(
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
        kind=T3,
        andes=("IEEET3",),
    ),
)

#: the states: transducer, an unused slot (V_As of the other types), regulator V_R, the
#: exciter's Efd, the rate feedback's washout R_f
S = states("IEEET3States", ("VTR", "VAs", "VR", "Efd", "Rf"))
STATE_NAMES = {T3: S._fields}


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


def initialise(p: ExciterParams, r, vex, eterm, VB, x):
    """IEEET3 at rest on rows r (a mask): V_R0 = K_E Efd0 - V_B0 (`initial_regulator`),
    the exciter and the rate feedback's washout Efd0; writes x, returns (V_ref - V_TR, p)."""
    VR = initial_regulator(p, r, vex, VB)
    x[S.VAs, r] = vex[r] / p.KA[r]  # unused: the slot the other types' lead-lag takes
    x[S.VR, r] = VR[r]
    x[S.Efd, r] = vex[r]
    x[S.Rf, r] = vex[r]  # the rate feedback's washout at rest
    return VR[r] / p.KA[r], p


def initial_regulator(p: ExciterParams, r, Efd, VB):
    """IEEET3 at rest: V_R0 = K_E Efd0 - V_B0 (ANDES 2.0 ``ieeet3.py`` ``VR0``), (n_exc,);
    raises CaseError if on a row of r (a mask) V_R0 is outside [Vrmin, Vrmax] or V_B0 +
    V_R0 outside [0, VBmax]."""
    VR = p.KE * Efd - VB
    bad = r & (beyond(VR, p.Vrmin, p.Vrmax) | beyond(VB + VR, np.zeros(p.n), p.VB_cap))
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


@njit
def source_voltage(KP, KI, XL, KC, cap, machine, init):
    """IEEET3's compound source V_B = sqrt(V_E^2 - (0.78 I_fd)^2), 0 where that is negative
    (IEEE 1968 type 3, ANDES 2.0 ``ieeet3.py``; its cap applies to V_B + V_R, in
    `derivatives`); V_E `table.potential_source`."""
    VE = potential_source(KP, KI, XL, machine)
    SQE = VE * VE - (0.78 * machine.fldcur) ** 2
    return np.sqrt(SQE) if SQE > 0 else 0.0


@kernel(inline="always")
def field_voltage(P, x, i, VTR_alg, pss_out, VB, ifd, ieee):
    """IEEET3: the Efd state."""
    return x[S.Efd, i]


@kernel(inline="always")
def recorded_efd(P, x, i, efd_alg):
    """Efd as PST records it: the Efd state."""
    return x[S.Efd, i]


@kernel(inline="always")
def derivatives(P, x, i, err, eterm, efd, ifd, pss_out, VB, dx, ieee, reach):
    """IEEET3 (docs/pst_models.md 2.9): the rate feedback (state R_f, with K_F != 0), the
    regulator V_R non-windup on [Vrmin, Vrmax], the exciter Efd fed by V_B + V_R clipped
    to [0, VBmax] (VB the source term, `source_voltage`)."""
    if P[i, E.KF] != 0:
        VF, dx[S.Rf, i] = washout(x[S.Efd, i], x[S.Rf, i], P[i, E.TF], P[i, E.KF], GAIN_OVER_T)
        err = err - VF
    x[S.VR, i], dx[S.VR, i] = nonwindup_lag(
        P[i, E.KA] * err, x[S.VR, i], P[i, E.TA], P[i, E.VRMIN], P[i, E.VRMAX], IEEE_RULE, 0.0
    )
    dx[S.Efd, i] = (clip(VB + x[S.VR, i], 0.0, P[i, E.VBCAP]) - P[i, E.KE] * x[S.Efd, i]) / P[
        i, E.TE
    ]
