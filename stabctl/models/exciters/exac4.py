"""EXAC4 (exc_con type 8): IEEE 1981 AC4 as PSS/E EXAC4 and ANDES 2.0 ``exac4.py``.

V_I limited, lead-lag, K_A/(1 + s T_A) (no limit on the lag); output limited to [Vrmin -
K_C I_fd, Vrmax - K_C I_fd].  docs/pst_models.md 2.8.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from stabctl._jit.decorators import kernel
from stabctl.models.blocks import clip, lag, leadlag_input_state
from stabctl.models.declaration import DyrModel, Limits, states
from stabctl.models.exciters.exst1 import check_start
from stabctl.models.exciters.table import LEAD_LAG, REGULATOR_GAIN, E, upper

if TYPE_CHECKING:
    from stabctl.models.exciters import ExciterParams

AC4 = 8
KINDS = {AC4: "EXAC4 (IEEE AC4)"}
#: AC4's V_I limits ordered (PSS/E Model Library EXAC4; IEEE Std 421.5 AC4A)
LIMITS = (
    Limits("PSS/E Model Library EXAC4", ordered=(("VImax", "VImin"),)),
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
EXCITER_COLUMNS = ""
#: the time constants that must be >= 1e-3 s: (name in messages, declared field)
NEEDS: tuple[tuple[str, str], ...] = (("TA", "TA"),)

DYR = (
    # EXAC4 -> type 8 (IEEE 1981 AC4)
    DyrModel(
        "EXAC4",
        ("TR", "VIMAX", "VIMIN", "TC", "TB", "KA", "TA", "VRMAX", "VRMIN", "KC"),
        upper("TR", "VImax", "VImin", "TC", "TB", "KA", "TA", "Vrmax", "Vrmin", "KC"),
        kind=AC4,
        andes=("EXAC4",),
    ),
)

#: the states: transducer, lead-lag, regulator V_R
S = states("EXAC4States", ("VTR", "VAs", "VR"))
STATE_NAMES = {AC4: S._fields}


def has_state(p: ExciterParams):
    """Which of the slots of `S` are states (a block whose time constant is below 1e-3 s,
    or a feedback whose gain is 0, has none), boolean arrays (n_exc,) in slot order, read
    on this type's rows by `stabctl.models.exciters.ExciterParams.has_state`."""
    return (p.has_TR, p.has_TB, p.has_TA)


def time_constants(p: ExciterParams):
    """The time constants of this type that set a state's speed besides the family's T_R,
    T_A, T_B and rate feedback T_F (`stabctl.models.exciters.ExciterParams.time_constants`):
    none beyond the shared ones; label -> (values, where)."""
    return {}


def initialise(p: ExciterParams, r, vex, eterm, VB, x):
    """EXAC4 at rest on rows r (a mask): V_R0 = Efd0 within [Vrmin - K_C I_fd0, Vrmax - K_C
    I_fd0] (`exst1.check_start`), the lead-lag Efd0/K_A; writes x, returns (V_ref - V_TR,
    p)."""
    check_start(p, r, "EXAC4", vex, p.Vrmin - p.KC * vex, p.Vrmax - p.KC * vex, vex)
    VA = vex[r] / p.KA[r]
    x[S.VAs, r] = VA
    x[S.VR, r] = vex[r]
    return VA, p


@kernel(inline="always")
def field_voltage(P, x, i, VTR_alg, pss_out, VB, ifd, ieee):
    """EXAC4: V_R clipped to [Vrmin - K_C I_fd, Vrmax - K_C I_fd]."""
    drop = P[i, E.KC] * ifd
    return clip(x[S.VR, i], P[i, E.VRMIN] - drop, P[i, E.VRMAX] - drop)


@kernel(inline="always")
def derivatives(P, x, i, err, eterm, efd, ifd, pss_out, VB, dx, ieee, reach):
    """EXAC4 (docs/pst_models.md 2.8): the error limited to [VImin, VImax], the lead-lag
    T_C/T_B, the lag K_A/(1 + s T_A)."""
    u, dx[S.VAs, i] = leadlag_input_state(
        clip(err, P[i, E.VIMIN], P[i, E.VIMAX]), x[S.VAs, i], P[i, E.TCTB], P[i, E.TB]
    )
    dx[S.VR, i] = lag(P[i, E.KA] * u, x[S.VR, i], P[i, E.TA])[1]
