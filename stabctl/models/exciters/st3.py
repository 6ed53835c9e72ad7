"""exc_st3 (exc_con type 3): IEEE ST3, PST's exc_st3, also PSS/E's ESST3A.

V_I limited, K_J, lead-lag, non-windup K_A/(1 + s T_A) with the inner loop feedback
min(V_Gmax, K_G Efd); output min(V_R V_B, Efdmax), V_B the potential/compound source
V_E F_EX(I_N).  ESST3A's regulator lag 1/(1 + s T_A) on [VRMIN, VRMAX] (exc_con columns
44, 28-29) sits between the lead-lag and the inner loop.  Source: PSTess 1.1 `exc_st3.m`
(PST manual 3.13 Table 3); PSS/E Model Library ESST3A (IEEE 421.5 ST3A; ANDES 2.0
``esst3a.py``); docs/pst_models.md 2.4.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel, njit
from stabctl.errors import refuse_initial
from stabctl.models import machines as mac
from stabctl.models.blocks import LBND, clip, leadlag_input_state, nonwindup_lag
from stabctl.models.declaration import DyrModel, Limits, beyond, states
from stabctl.models.exciters.table import IEEE_RULE, LEAD_LAG, REGULATOR_GAIN, E, potential_source

if TYPE_CHECKING:
    from stabctl.models.exciters import ExciterParams

ST3 = 3
KINDS = {ST3: "ST3 (exc_st3)"}
#: the ST3's field voltage ceiling Efdmax >= 0 and its V_I and (ESST3A) V_R limits
#: ordered (PST manual 3.13 Table 3; IEEE Std 421.5-2016 ST3A)
LIMITS = (
    Limits(
        "PST exc_st3; IEEE Std 421.5 ST3A",
        nonnegative=("Efdmax",),
        ordered=(("VImax", "VImin"), ("VAmax", "VAmin")),
    ),
    REGULATOR_GAIN,
    LEAD_LAG,
)
#: reads the machine's field current (`stabctl.models.exciters.field_current`)
READS_IFD = False
#: has a rate feedback s K_F/(1 + s T_F) from exc_con columns 21-22 (KF, TF)
RATE_FEEDBACK = False
#: fed by a potential (and compound) source V_B (its ``source_voltage``)
SOURCE = True
#: how it reads exc_con columns 10-15 (K_E, T_E, E1, SE1, E2, SE2; `exciter_params`): "dc"
#: PST's DC exciter (saturation fit by dc_sat, K_E computed where 0), "quadratic" K_E,
#: T_E and PSS/E's quadratic saturation, "linear" K_E and T_E alone, "" not at all
EXCITER_COLUMNS = ""
#: the time constants that must be >= 1e-3 s: (name in messages, declared field)
NEEDS: tuple[tuple[str, str], ...] = ()

DYR = (
    # ESST3A -> exc_st3: its KA is PST's K_J, its inner loop KM/(1 + s TM) limited
    # [VMMIN, VMMAX] PST's K_A/(1 + s T_A); VBMAX limits V_B (column 33); its
    # regulator lag 1/(1 + s TA) on [VRMIN, VRMAX] columns 44, 28-29 (none for TA
    # = 0); Efdmax = VBMAX VMMAX is computed
    DyrModel(
        "ESST3A",
        (
            "TR",
            "VIMAX",
            "VIMIN",
            "KM",
            "TC",
            "TB",
            "KA",
            "TA",
            "VRMAX",
            "VRMIN",
            "KG",
            "KP",
            "KI",
            "VBMAX",
            "KC",
            "XL",
            "VGMAX",
            "THETAP",
            "TM",
            "VMMAX",
            "VMMIN",
        ),
        {
            "TR": "TR",
            "KA": "KM",
            "TA": "TM",
            "TB": "TB",
            "TC": "TC",
            "Vrmax": "VMMAX",
            "Vrmin": "VMMIN",
            "VImax": "VIMAX",
            "VImin": "VIMIN",
            "KJ": "KA",
            "KP": "KP",
            "thetaP": "THETAP",
            "KI": "KI",
            "XL": "XL",
            "KC": "KC",
            "KG": "KG",
            "VGmax": "VGMAX",
            "VBmax": "VBMAX",
            "TA_st3a": "TA",
            "VAmax": "VRMAX",
            "VAmin": "VRMIN",
        },
        kind=ST3,
        andes=("ESST3A",),
    ),
)

#: the states: transducer, lead-lag, the inner loop's V_R, ESST3A's regulator lag V_A
#: (a state only with TA_st3a)
S = states("ST3States", ("VTR", "VAs", "VR", "VA"))
STATE_NAMES = {ST3: S._fields}


def has_state(p: ExciterParams):
    """Which of the slots of `S` are states (a block whose time constant is below 1e-3 s,
    or a feedback whose gain is 0, has none), boolean arrays (n_exc,) in slot order, read
    on this type's rows by `stabctl.models.exciters.ExciterParams.has_state`."""
    return (p.has_TR, p.has_TB, np.ones(p.n, bool), p.has_TA3A)


def time_constants(p: ExciterParams):
    """The time constants of this type that set a state's speed besides the family's T_R,
    T_A, T_B and rate feedback T_F (`stabctl.models.exciters.ExciterParams.time_constants`):
    ESST3A's regulator lag T_A; label -> (values, where)."""
    return {"exc_con TA_st3a": (p.TA_st3a, p.has_TA3A)}


#: the fast loop `inner_loop_time_constants` measures, named where it sets the step
INNER_LOOP = "ST3 inner loop T_A/(1 + K_A K_G V_B)"


def inner_loop_time_constants(p: ExciterParams, r, VB0, efd0):
    """The ST3's inner loop (ESST3A's K_M, T_M; PST exc_st3) on rows r, (n_exc,): T_A
    dV_R/dt = K_A (V_A - K_G E_fd) - V_R with E_fd = V_B V_R closes the pole -(1 + K_A
    K_G V_B)/T_A: T_A / (1 + K_A K_G V_B0) where the feedback is below VGmax (K_G E_fd0 <
    VGmax) and T_A > 0, inf elsewhere (VB0, efd0 the source and field voltages at rest,
    pu).  ANDES's kundur_esst3a: K_M = 500, T_M = 0.1 s, V_B = 4.3, 4.6e-5 s where T_M
    suggests 0.1 s."""
    loop = r & (p.TA > 0) & (p.KG * efd0 < p.VGmax)
    gain = 1.0 + p.KA * p.KG * VB0
    return np.where(loop, p.TA / np.where(loop, gain, 1.0), np.inf)


def initialise(p: ExciterParams, r, vex, eterm, VB, x):
    """exc_st3 at rest on rows r (a mask): V_R0 = Efd0/V_B0, the lead-lag's V_A0 = V_R0/K_A
    + min(VGmax, K_G Efd0), V_ref - V_TR = V_I0 = V_A0/K_J; raises CaseError when Efd0
    exceeds Efdmax or V_I0 leaves [VImin, VImax] (ESST3A: or V_A0 [VAmin, VAmax]) by more
    than `START_LIMIT_TOL`.  Writes x, returns (V_ref - V_TR, p)."""
    VR = vex / np.where(r, VB, 1.0)
    VA = VR / p.KA + np.minimum(p.VGmax, p.KG * vex)
    VI = VA / np.where(p.KJ == 0, 1.0, p.KJ)
    ta3a = r & (p.TA_st3a >= LBND)
    bad = r & (beyond(vex, -np.inf, p.Efdmax) | beyond(VI, p.VImin, p.VImax))
    bad |= ta3a & beyond(VA, p.VAmin, p.VAmax)
    refuse_initial(
        "exc_con",
        bad,
        lambda i: (
            f"exc_con row {i + 1}: initial field voltage {vex[i]:.3f} pu outside "
            "the ST3 limits (Efdmax, the VI range or ESST3A's [VRMIN, VRMAX])"
        ),
    )
    x[S.VAs, r] = VA[r]
    x[S.VR, r] = VR[r]
    x[S.VA, r] = np.where(ta3a, VA, 0.0)[r]
    return VI[r], p


@kernel
def _fex(IN, init):
    """Rectifier loading factor F_EX(I_N) of the ST3 (PST, with its initialisation quirk:
    sqrt(0.75 - I_N^0.2) and 1.708 in flag 0)."""
    if IN < 0.433:
        return 1.0 - 0.5771 * IN
    if 0.433 < IN < 0.75:
        return np.sqrt(max(0.75 - (IN**0.2 if init else IN * IN), 0.0))
    if IN > 0.75:
        return max(0.0, (1.708 if init else 1.732) * (1.0 - IN))
    return 0.0


@njit
def st3_source_voltage(KP, KI, XL, KC, machine, init):
    """V_B = V_E F_EX of the ST3 potential/compound source (PST exc_st3 flag 0/1); KP is
    the complex K_P exp(j theta_P), KI, XL, KC the exciter's other source parameters (pu),
    machine the `ST3Machine` quantities (pelect, qelect on the system base), init PST's
    flag 0 (its F_EX quirk, `_fex`)."""
    VE = potential_source(KP, KI, XL, machine)
    IN = KC * machine.fldcur / VE if VE > 0 else 0.0
    return VE * _fex(IN, init)


@njit
def source_voltage(KP, KI, XL, KC, cap, machine, init):
    """The ST3's source term: `st3_source_voltage`, at most cap (VBmax)."""
    return min(st3_source_voltage(KP, KI, XL, KC, machine, init), cap)


@kernel(inline="always")
def field_current(P, i, MP, xm, cur, rot, m):
    """The field current of exciter i's source (ST3, machine m): exc_st3's own estimate
    (`machines.st3_field_current`) or, with ifd_machine, the machine's (ANDES
    ``esst3a.py``); MP, xm, cur, rot as `stabctl.models.exciters.stator`."""
    if P[i, E.IFDM] > 0:
        return mac.field_current(MP, xm, cur, rot, m)
    return mac.st3_field_current(MP, xm, cur, rot, m)


@kernel(inline="always")
def field_voltage(P, x, i, VTR_alg, pss_out, VB, ifd, ieee):
    """exc_st3: min(V_R V_B, Efdmax) (ieee: V_R clipped to [Vrmin, Vrmax])."""
    VR = clip(x[S.VR, i], P[i, E.VRMIN], P[i, E.VRMAX]) if ieee else x[S.VR, i]
    return min(VR * VB, P[i, E.EFDMAX])


@kernel(inline="always")
def derivatives(P, x, i, err, eterm, efd, ifd, pss_out, VB, dx, ieee, reach):
    """exc_st3: V_R clamped and its derivative zeroed when it pushes outward
    (`blocks.nonwindup`); with TA_st3a ESST3A's regulator lag (state V_A, non-windup on
    [VAmin, VAmax], IEEE 421.5's rule) between the lead-lag and the inner loop."""
    u = P[i, E.KJ] * clip(err, P[i, E.VIMIN], P[i, E.VIMAX])
    VA, dx[S.VAs, i] = leadlag_input_state(u, x[S.VAs, i], P[i, E.TCTB], P[i, E.TB])
    if P[i, E.TA_ST3A] >= LBND:  # ESST3A's regulator lag (no PST counterpart)
        x[S.VA, i], dx[S.VA, i] = nonwindup_lag(
            VA, x[S.VA, i], P[i, E.TA_ST3A], P[i, E.VAMIN], P[i, E.VAMAX], IEEE_RULE, 0.0
        )
        VA = x[S.VA, i]
    x[S.VR, i], dx[S.VR, i] = nonwindup_lag(
        P[i, E.KA] * (VA - min(P[i, E.VGMAX], P[i, E.KG] * efd)),
        x[S.VR, i],
        P[i, E.TA],
        P[i, E.VRMIN],
        P[i, E.VRMAX],
        ieee,
        0.0,
    )
