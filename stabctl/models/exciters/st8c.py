"""ST8C (exc_con type 17): IEEE 421.5-2016 ST8C as PSS/E ST8C (PSS/E Model Library; the
record and equations of PowerSimulationsDynamics.jl's ``ST8C``): a static exciter whose
voltage regulator sets the reference of an inner field current regulator.

The voltage PI K_PR + K_IR/s on the voltage error, non-windup on [VPImin, VPImax]
(`blocks.pi_nonwindup`) -> the field current reference I_fdref; the field current PI K_PA
+ K_IA/s on I_fdref - V_F, non-windup on [VAmin, VAmax]; the controlled rectifier's lag
K_A/(1 + s T_A), non-windup on [Vrmin, Vrmax] -> V_R; the field current feedback V_F = K_F
I_fd lagged by T_F.  Efd = V_B1 V_R + V_B2 with V_B1 = min(V_E F_EX(K_C1 I_fd / V_E),
VB1max) (`blocks.rectifier_loading`).

The power source as PowerSimulationsDynamics.jl reads the record: SW1 = 0 gives V_E = K_P,
independent of the terminal quantities (so K_I1, X_L and theta_P have no effect), and the
terminal current feed-forward V_B2 is 0 (K_I2 = 0).  SW1 = 1 and K_I2 != 0 are refused
by name (`check`).  The record's OEL, UEL and SCL flags (ICONs) select where those
limiters' signals enter: stabctl has none of them, so their signals are 0 wherever they
enter.  States: the transducer, both PIs' integrals (as stabctl's PIs hold them, K_I
times PSID's ``x_a1``, ``x_a2``), V_R (PSID's ``x_a3``) and V_F (``x_a4``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.errors import refuse_initial
from stabctl.models.blocks import clip, lag, nonwindup_lag, pi_nonwindup, rectifier_loading
from stabctl.models.declaration import DyrModel, Limits, Param, beyond, states
from stabctl.models.exciters.table import REGULATOR_GAIN, E, own, upper

if TYPE_CHECKING:
    from stabctl.models.exciters import ExciterParams

ST8C = 17
KINDS = {ST8C: "ST8C (IEEE 421.5 ST8C, field current regulator)"}
#: ST8C's V_A and voltage PI limits ordered (IEEE Std 421.5-2016 ST8C)
LIMITS = (
    Limits("IEEE Std 421.5 ST8C", ordered=(("VAmax", "VAmin"), ("VPmax", "VPmin"))),
    REGULATOR_GAIN,
)
#: reads the machine's field current (`stabctl.models.exciters.field_current`)
READS_IFD = True
#: has a rate feedback s K_F/(1 + s T_F) from exc_con columns 21-22 (KF, TF)
RATE_FEEDBACK = False
#: fed by a potential (and compound) source V_B (its ``source_voltage``): V_E = K_P here
SOURCE = False
#: how it reads exc_con columns 10-15 (K_E, T_E, E1, SE1, E2, SE2; `exciter_params`): "dc"
#: PST's DC exciter (saturation fit by dc_sat, K_E computed where 0), "quadratic" K_E,
#: T_E and PSS/E's quadratic saturation, "linear" K_E and T_E alone, "" not at all
EXCITER_COLUMNS = ""
#: the time constants that must be >= 1e-3 s: (name in messages, declared field)
NEEDS: tuple[tuple[str, str], ...] = (("TA", "TA"), ("TF", "TF_ifd"))
#: ST8C's own exc_con columns
PARAMS = (
    Param("KPA", "", 67, lo=0.0, doc="ST8C: field current regulator proportional gain K_PA"),
    Param("KIA", "1/s", 68, lo=0.0, doc="ST8C: field current regulator integral gain K_IA (!= 0)"),
    Param("KF_ifd", "", 69, lo=0.0, doc="ST8C: field current feedback gain K_F"),
    Param("TF_ifd", "s", 70, lo=0.0, doc="ST8C: field current feedback time constant T_F"),
    Param("VB1max", "pu", 71, lo=0.0, doc="ST8C: upper limit of the source V_B1"),
    Param(
        "SW1",
        "code",
        72,
        integer=True,
        choices=(0.0, 1.0),
        label="ST8C's SW1",
        doc="ST8C: power source selector SW1 (ICON); 0 V_E = K_P (1 is refused)",
    ),
    Param("KI2", "", 73, doc="ST8C: terminal current feed-forward gain K_I2 (0; else refused)"),
)
#: the packed columns of `PARAMS`: P[i, O.KPA]
O = own("ST8CColumns", PARAMS)

DYR = (
    # ST8C -> type 17; ICONs OEL, UEL, SCL, SW1, then the CONs in PSS/E Model Library order
    DyrModel(
        "ST8C",
        (
            "OEL",
            "UEL",
            "SCL",
            "SW1",
            "TR",
            "KPR",
            "KIR",
            "VPIMAX",
            "VPIMIN",
            "KPA",
            "KIA",
            "VAMAX",
            "VAMIN",
            "KA",
            "TA",
            "VRMAX",
            "VRMIN",
            "KF",
            "TF",
            "KC1",
            "KP",
            "KI1",
            "XL",
            "THETAP",
            "VB1MAX",
            "KC2",
            "KI2",
            "VB2MAX",
        ),
        {
            **upper("TR", "KA", "TA", "Vrmax", "Vrmin", "KP", "KPA", "KIA", "SW1", "KI2"),
            "VAmax": "VAMAX",
            "VAmin": "VAMIN",
            "Kpid_P": "KPR",
            "Kpid_I": "KIR",
            "VPmax": "VPIMAX",
            "VPmin": "VPIMIN",
            "KF_ifd": "KF",
            "TF_ifd": "TF",
            "KC": "KC1",
            "VB1max": "VB1MAX",
        },
        kind=ST8C,
    ),
)

#: the states: transducer, the voltage PI's integral, the field current PI's integral,
#: the rectifier's lag V_R, the field current feedback V_F
S = states("ST8CStates", ("VTR", "PIi", "PIa", "VR", "VF"))
STATE_NAMES = {ST8C: S._fields}


def has_state(p: ExciterParams):
    """Which of the slots of `S` are states (the voltage PI's integral with K_IR != 0; T_A,
    T_F and K_IA are required), boolean arrays (n_exc,) in slot order, read on this type's
    rows by `stabctl.models.exciters.ExciterParams.has_state`."""
    on = np.ones(p.n, bool)
    return (p.has_TR, p.Kpid_I != 0, on, on, on)


def time_constants(p: ExciterParams):
    """The time constants of this type that set a state's speed besides the family's T_R,
    T_A, T_B and rate feedback T_F (`stabctl.models.exciters.ExciterParams.time_constants`):
    the field current feedback's T_F; label -> (values, where)."""
    return {"exc_con T_F (ST8C)": (p.TF_ifd, True)}


def check(e, r: int) -> str | None:
    """The first ST8C option of exc_con row r (0-based) stabctl does not model, with the
    reason, or None: SW1 = 1 (a source fed by the terminal voltage), K_I2 != 0 (the
    terminal current feed-forward V_B2), K_IA = 0, K_IR = K_PR = 0, or K_P <= 0."""
    KP = e.KP[r] * np.exp(1j * np.deg2rad(e.thetaP[r]))
    for bad, field in (
        (e.SW1[r] != 0, "SW1: 1 (the power source fed by the terminal voltage)"),
        (e.KI2[r] != 0, "KI2: the terminal current feed-forward V_B2"),
        (e.KIA[r] == 0, "KIA: 0 (the field current regulator needs its integral)"),
        (e.Kpid_I[r] == 0 and e.Kpid_P[r] == 0, "Kpid_P, Kpid_I (K_PR, K_IR): both 0"),
        (KP.real <= 0 or KP.imag != 0, "KP: V_E = K_P must be real and > 0"),
    ):
        if bad:
            return f"ST8C field {field} is not modelled"
    return None


def source(p: ExciterParams, ifd):
    """V_B1 = min(K_P F_EX(K_C1 I_fd / K_P), VB1max) for the field currents ifd (pu),
    (n_exc,) (rows with K_P <= 0 read as K_P = 1; `check` refuses them on ST8C rows)."""
    VE = np.where(p.KP.real > 0, p.KP.real, 1.0)
    fex = np.array([rectifier_loading(v) for v in p.KC * ifd / VE])
    return np.minimum(VE * fex, p.VB1max)


def initialise(p: ExciterParams, r, vex, eterm, VB, x):
    """ST8C at rest on rows r (a mask): I_fd0 = Efd0 (the machine at rest), V_R0 = Efd0 /
    V_B1(I_fd0), V_F0 = I_fdref0 = K_F I_fd0, the field current PI's integral V_R0 / K_A,
    the voltage PI's integral I_fdref0 (with K_IR; else the error I_fdref0 / K_PR); writes
    x, returns (V_ref - V_TR, p).

    Raises
    ------
    InitialLimitError
        V_B1 <= 0, I_fdref0 outside [VPImin, VPImax], V_R0 / K_A outside [VAmin, VAmax] or
        V_R0 outside [Vrmin, Vrmax].
    """
    VB1 = source(p, vex)
    VR = vex / np.where(VB1 > 0, VB1, 1.0)
    VA = VR / p.KA
    ref = p.KF_ifd * vex
    bad = r & (
        (VB1 <= 0)
        | beyond(ref, p.VPmin, p.VPmax)
        | beyond(VA, p.VAmin, p.VAmax)
        | beyond(VR, p.Vrmin, p.Vrmax)
    )
    refuse_initial(
        "exc_con",
        bad,
        lambda i: (
            f"exc_con row {i + 1}: ST8C at rest: source V_B1 = {VB1[i]:.4f} pu (must be > 0), "
            f"field current reference {ref[i]:.4f} pu (in [VPImin, VPImax] = "
            f"[{p.VPmin[i]:.4f}, {p.VPmax[i]:.4f}]), field current regulator output "
            f"{VA[i]:.4f} pu (in [VAmin, VAmax] = [{p.VAmin[i]:.4f}, {p.VAmax[i]:.4f}]), V_R "
            f"= {VR[i]:.4f} pu (in [Vrmin, Vrmax] = [{p.Vrmin[i]:.4f}, {p.Vrmax[i]:.4f}])"
        ),
    )
    integral = p.Kpid_I[r] != 0
    x[S.PIi, r] = np.where(integral, ref[r], 0.0)
    x[S.PIa, r] = VA[r]
    x[S.VR, r] = VR[r]
    x[S.VF, r] = ref[r]
    kp = np.where(p.Kpid_P[r] != 0, p.Kpid_P[r], 1.0)
    return np.where(integral, 0.0, ref[r] / kp), p


@kernel(inline="always")
def field_voltage(P, x, i, VTR_alg, pss_out, VB, ifd, ieee):
    """ST8C: Efd = V_B1 V_R, V_R the rectifier lag's state clipped to [Vrmin, Vrmax], V_B1
    = min(K_P F_EX(K_C1 I_fd / K_P), VB1max) on the field current ifd (pu)."""
    VE = P[i, E.KPR]
    VB1 = min(VE * rectifier_loading(P[i, E.KC] * ifd / VE), P[i, O.VB1MAX])
    return VB1 * clip(x[S.VR, i], P[i, E.VRMIN], P[i, E.VRMAX])


@kernel(inline="always")
def derivatives(P, x, i, err, eterm, efd, ifd, pss_out, VB, dx, ieee, reach):
    """ST8C: the voltage PI -> the field current reference, the field current PI on its
    difference from V_F, the rectifier's non-windup lag T_A dV_R/dt = K_A V_A - V_R, the
    feedback T_F dV_F/dt = K_F I_fd - V_F (ifd the field current, pu)."""
    ref, dx[S.PIi, i] = pi_nonwindup(
        err, x[S.PIi, i], P[i, E.KPID_P], P[i, E.KPID_I], P[i, E.VPMIN], P[i, E.VPMAX]
    )
    VA, dx[S.PIa, i] = pi_nonwindup(
        ref - x[S.VF, i], x[S.PIa, i], P[i, O.KPA], P[i, O.KIA], P[i, E.VAMIN], P[i, E.VAMAX]
    )
    x[S.VR, i], dx[S.VR, i] = nonwindup_lag(
        P[i, E.KA] * VA, x[S.VR, i], P[i, E.TA], P[i, E.VRMIN], P[i, E.VRMAX], ieee, reach
    )
    dx[S.VF, i] = lag(P[i, O.KF_IFD] * ifd, x[S.VF, i], P[i, O.TF_IFD])[1]
