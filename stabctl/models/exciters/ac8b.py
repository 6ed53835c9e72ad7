"""AC8B (exc_con type 10): IEEE 421.5-2005 AC8B as ANDES 2.0 ``ac8b.py`` and PowerWorld's
AC8B record.

A PID with tracking anti-windup on the voltage error (`blocks.pid_track_aw`, ANDES's
PIDTrackAW: ys = K_P u + x_i + K_D (u - x_d)/T_D, y = ys clipped to [VPmin, VPmax],
dx_i/dt = K_I (u - k_s (ys - y)), k_s = 2, T_D dx_d/dt = u - x_d); K_A/(1 + s T_A)
non-windup on [Vrmin, Vrmax] -> V_R; the exciter as EXAC1's (`exac1.exciter`, V_E >= 0).
VFEMAX and VEMIN are not modelled (ANDES neither).  docs/pst_models.md 2.7.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.models.blocks import nonwindup_lag, pid_track_aw
from stabctl.models.declaration import DyrModel, Limits, states
from stabctl.models.exciters.exac1 import exciter, exciter_feedback, initial_exciter, rectified
from stabctl.models.exciters.table import IEEE_RULE, PID_TRACKING, REGULATOR_GAIN, E, upper

if TYPE_CHECKING:
    from stabctl.models.exciters import ExciterParams

AC8B = 10
KINDS = {AC8B: "AC8B (IEEE 421.5 AC8B, PID regulator)"}
#: AC8B's saturation point E2 and exciter time constant T_E >= 0, its PID output limits
#: ordered (IEEE Std 421.5-2016 AC8B)
LIMITS = (
    Limits("IEEE Std 421.5 AC8B", nonnegative=("E2", "TE"), ordered=(("VPmax", "VPmin"),)),
    REGULATOR_GAIN,
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
NEEDS: tuple[tuple[str, str], ...] = (("TA", "TA"), ("TE", "TE"))

#: AC8B's exciter field-voltage limits, not modelled (IEEE 421.5 AC8B; ANDES 2.0's ac8b.py
#: leaves them out too): their values of no limit (ANDES's defaults)
UNMODELLED = {"VFEMAX": 999.0, "VEMIN": -999.0}


def without_effect(name: str, value: float) -> str:
    """What an import says of AC8B's `name` (a key of UNMODELLED) given as `value`: "" at
    its value of no limit, else that it has no effect (round 41: VFEMAX 1 and VEMIN 0.5
    ran as 999 and -999 without a word).  Both import routes say it (`stabctl.io.dyr`,
    `stabctl.io.andes_case`)."""
    none = UNMODELLED[name]
    return "" if value == none else f"{name} = {value:g} has no effect: not modelled (as {none:g})"


DYR = (
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
        upper(
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
        kind=AC8B,
        andes=("AC8B",),
    ),
)

#: the states: transducer, the PID's integral and derivative (washout), the regulator
#: V_R, the exciter's V_E
S = states("AC8BStates", ("VTR", "PIDi", "VR", "VE", "PIDd"))
STATE_NAMES = {AC8B: S._fields}


def has_state(p: ExciterParams):
    """Which of the slots of `S` are states (a block whose time constant is below 1e-3 s,
    or a feedback whose gain is 0, has none), boolean arrays (n_exc,) in slot order, read
    on this type's rows by `stabctl.models.exciters.ExciterParams.has_state`."""
    on = np.ones(p.n, bool)
    return (p.has_TR, on, p.has_TA, on, p.has_pid_d)


def time_constants(p: ExciterParams):
    """The time constants of this type that set a state's speed besides the family's T_R,
    T_A, T_B and rate feedback T_F (`stabctl.models.exciters.ExciterParams.time_constants`):
    the exciter T_E, the PID's derivative lag T_D; label -> (values, where)."""
    return {"exc_con T_E": (p.TE, True), "exc_con T_D": (p.Td, p.has_pid_d)}


def initialise(p: ExciterParams, r, vex, eterm, VB, x):
    """AC8B at rest on rows r (a mask): the exciter as EXAC1's (`exac1.initial_exciter`;
    the PID's output V_R0/K_A must be inside [VPmin, VPmax]), the PID's integral its
    output V_R0/K_A, its derivative washout 0, no error; writes x, returns (V_ref - V_TR
    = 0, p)."""
    VE, VFE = initial_exciter(
        p,
        r,
        vex,
        lambda i: "AC8B",
        lambda i: [("V_R/K_A", "VPmin, VPmax", p.VPmin[i] * p.KA[i], p.VPmax[i] * p.KA[i])],
    )
    x[S.PIDi, r] = VFE[r] / p.KA[r]
    x[S.VR, r] = VFE[r]
    x[S.VE, r] = VE[r]
    return np.zeros(np.count_nonzero(r)), p


@kernel(inline="always")
def field_voltage(P, x, i, VTR_alg, pss_out, VB, ifd, ieee):
    """AC8B: the AC exciter's output (`exac1.rectified`)."""
    return rectified(P, i, x[S.VE, i], ifd)


@kernel(inline="always")
def derivatives(P, x, i, err, eterm, efd, ifd, pss_out, VB, dx, ieee, reach):
    """AC8B (docs/pst_models.md 2.7): the PID on the voltage error (states PIDi, PIDd),
    the regulator lag V_R, the exciter V_E."""
    y, dx[S.PIDi, i], dx[S.PIDd, i] = pid_track_aw(
        err,
        x[S.PIDi, i],
        x[S.PIDd, i],
        P[i, E.KPID_P],
        P[i, E.KPID_I],
        P[i, E.KPID_D],
        P[i, E.TD],
        P[i, E.VPMIN],
        P[i, E.VPMAX],
        PID_TRACKING,
    )
    x[S.VR, i], dx[S.VR, i] = nonwindup_lag(
        P[i, E.KA] * y, x[S.VR, i], P[i, E.TA], P[i, E.VRMIN], P[i, E.VRMAX], IEEE_RULE, 0.0
    )
    VFE = exciter_feedback(P, i, x[S.VE, i], ifd)
    x[S.VE, i], dx[S.VE, i] = exciter(P, i, x[S.VE, i], x[S.VR, i], VFE)
