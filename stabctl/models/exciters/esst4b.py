"""ESST4B (exc_con type 12): IEEE 421.5-2005 ST4B as PSS/E ESST4B and ANDES 2.0
``esst4b.py``, no OEL/UEL.

The regulator PI K_PR + K_IR/s with tracking anti-windup on [Vrmin, Vrmax] (state PIi),
the lag 1/(1 + s T_A) (state V_M), the inner-loop PI K_PM + K_IM/s on V_M - min(K_G Efd,
VGmax), tracking anti-windup on [VMmin, VMmax] (state PIMi), both `blocks.pi_track_aw`
(ANDES's PITrackAW); Efd = V_B times the inner PI's output, V_B = min(V_E F_EX, VBmax).
PSS/E's reading (exc_con ``psse_st1`` 1, set by import-psse): both PIs with non-windup
limits (`blocks.pi_nonwindup`; IEEE 421.5-2016 ST4B and E.6; OpenIPSL's PSS/E-verified
``ESST4B.mo`` and OPAL-RT's hold their integrals at the limits): ANDES's tracking drove
the regulator's integral to -1.3 pu while its output rode Vrmax through a fault, Efd then
-0.68 pu 0.85 s after clearing where both PSS/E libraries give 2.8 (round 53, AO11).
The feedback K_G Efd closes an algebraic loop, solved exactly (`field_voltage`).
docs/pst_models.md 2.10.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel, njit
from stabctl.errors import refuse_initial
from stabctl.models.blocks import LBND, clip, lag, pi_nonwindup, pi_track_aw, rectifier_loading
from stabctl.models.declaration import DyrModel, Limits, beyond, states
from stabctl.models.exciters.table import PID_TRACKING, E, potential_source, upper

if TYPE_CHECKING:
    from stabctl.models.exciters import ExciterParams

ST4B = 12
KINDS = {ST4B: "ESST4B (IEEE 421.5 ST4B, PI regulators)"}
#: ST4B's inner-loop PI limits ordered (IEEE Std 421.5-2016 ST4B)
LIMITS = Limits("IEEE Std 421.5 ST4B", ordered=(("VMmax", "VMmin"),))
#: reads the machine's field current (`stabctl.models.exciters.field_current`)
READS_IFD = True
#: has a rate feedback s K_F/(1 + s T_F) from exc_con columns 21-22 (KF, TF)
RATE_FEEDBACK = False
#: fed by a potential (and compound) source V_B (its ``source_voltage``)
SOURCE = True
#: how it reads exc_con columns 10-15 (K_E, T_E, E1, SE1, E2, SE2; `exciter_params`): "dc"
#: PST's DC exciter (saturation fit by dc_sat, K_E computed where 0), "quadratic" K_E,
#: T_E and PSS/E's quadratic saturation, "linear" K_E and T_E alone, "" not at all
EXCITER_COLUMNS = ""
#: the time constants that must be >= 1e-3 s: (name in messages, declared field)
NEEDS: tuple[tuple[str, str], ...] = ()  # T_A = 0: no lag (PSS/E), `field_voltage`

DYR = (
    # ESST4B -> type 12 (IEEE 421.5 ST4B); VGmax, which PSS/E's record lacks, is set
    # by its mapper
    DyrModel(
        "ESST4B",
        (
            "TR",
            "KPR",
            "KIR",
            "VRMAX",
            "VRMIN",
            "TA",
            "KPM",
            "KIM",
            "VMMAX",
            "VMMIN",
            "KG",
            "KP",
            "KI",
            "VBMAX",
            "KC",
            "XL",
            "THETAP",
        ),
        upper(
            "TR",
            "Vrmax",
            "Vrmin",
            "TA",
            "KPM",
            "KIM",
            "VMmax",
            "VMmin",
            "KG",
            "KP",
            "KI",
            "VBmax",
            "KC",
            "XL",
            "thetaP",
            Kpid_P="KPR",
            Kpid_I="KIR",
        ),
        kind=ST4B,
        andes=("ESST4B",),
    ),
)

#: the states: transducer, the regulator PI's integral, the lag V_M, the inner PI's
#: integral
S = states("ESST4BStates", ("VTR", "PIi", "VM", "PIMi"))
STATE_NAMES = {ST4B: S._fields}


def has_state(p: ExciterParams):
    """Which of the slots of `S` are states (a block whose time constant is below 1e-3 s,
    or a feedback whose gain is 0, has none), boolean arrays (n_exc,) in slot order, read
    on this type's rows by `stabctl.models.exciters.ExciterParams.has_state`."""
    return (p.has_TR, p.has_TB | (p.Kpid_I != 0), p.has_TA, p.KIM != 0)


def time_constants(p: ExciterParams):
    """The time constants of this type that set a state's speed besides the family's T_R,
    T_A, T_B and rate feedback T_F (`stabctl.models.exciters.ExciterParams.time_constants`):
    none beyond the shared ones; label -> (values, where)."""
    return {}


def initialise(p: ExciterParams, r, vex, eterm, VB, x):
    """ESST4B at rest on rows r (a mask, `initial_regulators`): each PI's integral its
    output, the lag V_G0, no error; writes x, returns (V_ref - V_TR = 0, p)."""
    VG, VM = initial_regulators(p, r, vex, VB)
    x[S.PIi, r] = VG[r]  # the regulator PI's integral: its output at rest
    x[S.VM, r] = VG[r]
    x[S.PIMi, r] = VM[r]
    return np.zeros(np.count_nonzero(r)), p  # a PI at rest: no error


def initial_regulators(p: ExciterParams, r, Efd, VB):
    """ESST4B at rest (ANDES 2.0 ``esst4b.py``): the regulator PI's output V_G0 = min(K_G
    Efd0, VGmax) (the inner loop's input is 0) and the inner PI's V_M0 = Efd0 / V_B0,
    arrays (n_exc,); raises CaseError if on a row of r (a mask) V_B0 <= 0, V_G0 is outside
    [Vrmin, Vrmax] or V_M0 outside [VMmin, VMmax]."""
    VG = np.minimum(p.KG * Efd, p.VGmax)
    VM = Efd / np.where(VB > 0, VB, 1.0)
    bad = r & ((VB <= 0) | beyond(VG, p.Vrmin, p.Vrmax) | beyond(VM, p.VMmin, p.VMmax))
    refuse_initial(
        "exc_con",
        bad,
        lambda i: (
            f"exc_con row {i + 1}: ESST4B at rest: source V_B = {VB[i]:.4f} pu (must "
            f"be > 0), regulator output V_G = {VG[i]:.4f} pu (in [Vrmin, Vrmax] = "
            f"[{p.Vrmin[i]:.4f}, {p.Vrmax[i]:.4f}]), inner-loop output V_M = {VM[i]:.4f} pu "
            f"(in [VMmin, VMmax] = [{p.VMmin[i]:.4f}, {p.VMmax[i]:.4f}])"
        ),
    )
    return VG, VM


@njit
def source_voltage(KP, KI, XL, KC, cap, machine, init):
    """ESST4B's source V_B = V_E F_EX(K_C I_fd / V_E) (`blocks.rectifier_loading`, IEEE Std
    421.5-2016 annex D), at most cap (VBmax); V_E `table.potential_source`."""
    VE = potential_source(KP, KI, XL, machine)
    IN = KC * machine.fldcur / VE if VE > 0 else 0.0
    return min(VE * rectifier_loading(IN), cap)


@kernel(inline="always")
def _pi(P, i, u, xi, KP, KI, lo, hi):
    """One of ESST4B's PIs: non-windup under PSS/E's reading (exc_con ``psse_st1`` 1,
    `blocks.pi_nonwindup`), else ANDES's tracking (`blocks.pi_track_aw`): (output, the
    integral's derivative)."""
    if P[i, E.PSSE_ST1] == 1.0:
        return pi_nonwindup(u, xi, KP, KI, lo, hi)
    return pi_track_aw(u, xi, KP, KI, lo, hi, PID_TRACKING)


@kernel(inline="always")
def regulator(P, x, i, err):
    """ESST4B's regulator PI K_PR err + PIi on [Vrmin, Vrmax] (`_pi`): (output, the
    integral's derivative)."""
    return _pi(P, i, err, x[S.PIi, i], P[i, E.KPID_P], P[i, E.KPID_I], P[i, E.VRMIN], P[i, E.VRMAX])


@kernel(inline="always")
def field_voltage(P, x, i, VTR_alg, pss_out, VB, ifd, ieee):
    """ESST4B: Efd = V_B clip(K_PM (V_M - min(K_G Efd, VGmax)) + PIMi, VMmin, VMmax),
    solved for Efd (ANDES solves it with its algebraic equations): the right side does
    not rise with Efd (K_PM K_G >= 0, V_B >= 0), so there is one solution, on the
    feedback's limit if its candidate there reaches it, else V_B clip(y, VMmin, VMmax)
    with y = (K_PM V_M + PIMi)/(1 + V_B K_PM K_G) the unclipped loop's output.  V_M is
    the lag's state, or with T_A = 0 (PSS/E: no lag) the regulator's output itself."""
    VM = x[S.VM, i]
    if P[i, E.TA] < LBND:
        err = P[i, E.VREF] - lag(VTR_alg, x[S.VTR, i], P[i, E.TR])[0] + pss_out
        VM = regulator(P, x, i, err)[0]
    KPM, KG, VGmax = P[i, E.KPM], P[i, E.KG], P[i, E.VGMAX]
    lo, hi = P[i, E.VMMIN], P[i, E.VMMAX]
    on_limit = VB * clip(KPM * (VM - VGmax) + x[S.PIMi, i], lo, hi)
    if KG * on_limit >= VGmax:
        return on_limit
    return VB * clip((KPM * VM + x[S.PIMi, i]) / (1.0 + VB * KPM * KG), lo, hi)


@kernel(inline="always")
def derivatives(P, x, i, err, eterm, efd, ifd, pss_out, VB, dx, ieee, reach):
    """ESST4B (docs/pst_models.md 2.10): both PI regulators with ANDES's tracking
    anti-windup, dx_i/dt = K_I (u - k_s (ys - y)) (k_s = `table.PID_TRACKING`), and the
    lag T_A; efd the field voltage (`field_voltage`)."""
    y, dx[S.PIi, i] = regulator(P, x, i, err)
    VM, dx[S.VM, i] = lag(y, x[S.VM, i], P[i, E.TA])
    u = VM - min(P[i, E.KG] * efd, P[i, E.VGMAX])
    dx[S.PIMi, i] = _pi(
        P, i, u, x[S.PIMi, i], P[i, E.KPM], P[i, E.KIM], P[i, E.VMMIN], P[i, E.VMMAX]
    )[1]
