"""smpexc (exc_con type 0): PST's simple static exciter, also PSS/E's SEXS and SCRX.

T_R, lead-lag T_C/T_B, K_A/(1 + s T_A) limited [Vrmin, Vrmax]; bus fed (SCRX, exc_con
column 19 ``bus_fed`` = 1): the output times the terminal voltage.  SCRX's negative
field current logic (its own exc_con column 74 ``rc_rfd``, PSS/E's rc/rfd, the field
discharge resistance over the field's): with rc/rfd != 0 the bridge blocks a negative
field current, so while the machine's field current I_fd (X_ad I_fd, pu) is <= 0 the
field voltage is -rc/rfd I_fd, the discharge resistor's, not the regulator's output;
rc/rfd = 0 (a bridge that conducts both ways) leaves the output as it is.  At rest I_fd =
Efd0, so `initialise` refuses Efd0 <= 0 with rc/rfd != 0 (no rest point on the
resistor).  Source: PSTess 1.1 `smpexc.m`; PSS/E Model Library SEXS, SCRX;
PowerSimulationsDynamics.jl ``avr_models.jl`` (SCRX); docs/pst_models.md 2.1, 2.5.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.errors import refuse_initial
from stabctl.models.blocks import LBND, clip, lag, leadlag_input_state, nonwindup_lag
from stabctl.models.declaration import DyrModel, Limits, Param, beyond, states
from stabctl.models.exciters.table import REGULATOR_GAIN, E, own

if TYPE_CHECKING:
    from stabctl.models.exciters import ExciterParams

SMP = 0
KINDS = {SMP: "simple (smpexc)"}
#: reads the machine's field current (`stabctl.models.exciters.field_current`): SCRX's
#: negative field current logic
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
NEEDS: tuple[tuple[str, str], ...] = ()
#: K_A > 0, and no lead T_C without its lag T_B: smpexc bypasses its lead-lag where T_B
#: is below 1e-3 s (PSTess smpexc.m: T_C is then not read), and PSS/E's SEXS and SCRX
#: give T_C = (TA/TB) TB, 0 with TB (PSS/E Model Library SEXS, SCRX)
LIMITS = (
    REGULATOR_GAIN,
    Limits("PSS/E Model Library SEXS: T_C = (TA/TB) TB", leads=(("TC", "TB"),)),
)
#: smpexc's own exc_con column
PARAMS = (
    Param(
        "rc_rfd",
        "",
        74,
        lo=0.0,
        doc="SCRX: rc/rfd, the field discharge resistance over the field resistance; "
        "!= 0: Efd = -rc/rfd I_fd while I_fd <= 0 (no negative field current), 0: none",
    ),
)
#: the packed columns of `PARAMS`: P[i, O.RC_RFD]
O = own("SEXSColumns", PARAMS)

DYR = (
    # SEXS -> smpexc: T_C = (TA/TB) TB is computed
    DyrModel(
        "SEXS",
        ("TA/TB", "TB", "K", "TE", "EMIN", "EMAX"),
        {"KA": "K", "TA": "TE", "TB": "TB", "Vrmax": "EMAX", "Vrmin": "EMIN"},
        kind=SMP,
        andes=("SEXS",),
    ),
    # SCRX -> smpexc: T_C = (TA/TB) TB computed; CSWITCH 0 (bus fed): bus_fed = 1
    DyrModel(
        "SCRX",
        ("TA/TB", "TB", "K", "TE", "EMIN", "EMAX", "CSWITCH", "rc/rfd"),
        {
            "KA": "K",
            "TA": "TE",
            "TB": "TB",
            "Vrmax": "EMAX",
            "Vrmin": "EMIN",
            "rc_rfd": "rc/rfd",
        },
        kind=SMP,
    ),
)

#: the states: the transducer, the lead-lag's, the regulator's output (the field voltage)
S = states("SEXSStates", ("VTR", "VAs", "Efd"))
STATE_NAMES = {SMP: S._fields}


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
    """smpexc at rest on rows r: the lead-lag holds the regulator's input Efd0/K_A, the
    lag Efd0 (bus fed: Efd0/V_t); writes x, returns (V_ref - V_TR, p).

    Raises CaseError (`refuse_initial`) for an SCRX with rc/rfd != 0 whose Efd0 (its
    field current at rest) is <= 0, and for output limits [Vrmin, Vrmax] (PSS/E's EMIN,
    EMAX; bus fed, times V_t) that do not hold Efd0: the lag T_A's, or without it (TE = 0)
    the output's, which PSS/E's reading clips too (`field_voltage`)."""
    refuse_initial(
        "exc_con",
        r & (p.rc_rfd != 0) & (vex <= 0),
        lambda k: (
            f"exc_con row {k + 1}: SCRX's start-up field current {vex[k]:.4f} pu is not "
            f"positive, where rc/rfd = {p.rc_rfd[k]:g} holds it on the discharge resistor"
        ),
    )
    # the Efd state, limited to [Vrmin, Vrmax] where T_A gives it (both conventions clip
    # it; without T_A the ieee conventions clip the output), must hold the field voltage
    # the machine needs: a limit short of it starts the run off its rest point (PSS/E:
    # "initial conditions suspect")
    state = np.where(p.KG == 1, vex / np.where(eterm != 0, eterm, 1.0), vex)
    refuse_initial(
        "exc_con",
        r & beyond(state, p.Vrmin, p.Vrmax),
        lambda k: (
            f"exc_con row {k + 1}: "
            + (
                f"Vrmax (SEXS's, SCRX's EMAX) = {p.Vrmax[k]:.4g} below"
                if state[k] > p.Vrmax[k]
                else f"Vrmin (SEXS's, SCRX's EMIN) = {p.Vrmin[k]:.4g} above"
            )
            + f" the initial field voltage E_fd0 = {state[k]:.4f} pu"
            + (" (over V_t, bus fed)" if p.KG[k] == 1 else "")
            + ": the regulator's output limit cannot deliver it"
        ),
    )
    bus_fed = p.KG[r] == 1
    efd = vex[r] / np.where(bus_fed, eterm[r], 1.0)  # SCRX bus fed: Efd = V_t x Efd state
    VA = efd / p.KA[r]
    x[S.VAs, r] = VA
    x[S.Efd, r] = efd
    return VA, p


@kernel(inline="always")
def field_voltage(P, x, i, VTR_alg, pss_out, VB, ifd, ieee):
    """smpexc: the Efd state when T_A exists (PSTess: unclamped, docs/pst_models.md 2.1;
    ieee: clipped to [Vrmin, Vrmax]), else K_A times the (lead-lag of the) error (PSTess:
    without limits; ieee: clipped to [Vrmin, Vrmax] too, as PSS/E's SEXS and SCRX with TE
    = 0: OpenIPSL's SimpleLagLim, OPAL-RT's Lag_NonWindupLimit; round 53, AO05); bus fed
    (SCRX, exc_con column 19 = 1): times the terminal voltage VTR_alg; SCRX with rc/rfd !=
    0 and the field current ifd <= 0: -rc/rfd ifd."""
    rc_rfd = P[i, O.RC_RFD]
    if rc_rfd != 0.0 and ifd <= 0.0:
        return -rc_rfd * ifd
    mult = VTR_alg if P[i, E.KG] == 1 else 1.0
    if P[i, E.TA] >= LBND:
        return (clip(x[S.Efd, i], P[i, E.VRMIN], P[i, E.VRMAX]) if ieee else x[S.Efd, i]) * mult
    VTR = lag(VTR_alg, x[S.VTR, i], P[i, E.TR])[0]
    err = P[i, E.VREF] - VTR + pss_out
    VA = leadlag_input_state(err, x[S.VAs, i], P[i, E.TCTB], P[i, E.TB])[0]
    efd = P[i, E.KA] * VA
    return (clip(efd, P[i, E.VRMIN], P[i, E.VRMAX]) if ieee else efd) * mult


@kernel(inline="always")
def recorded_efd(P, x, i, efd_alg):
    """The Efd PST records: the (clamped) state with T_A, not bus fed and rc/rfd = 0,
    else efd_alg."""
    if P[i, E.TA] >= LBND and P[i, E.KG] != 1 and P[i, O.RC_RFD] == 0.0:
        return x[S.Efd, i]
    return efd_alg


@kernel(inline="always")
def derivatives(P, x, i, err, eterm, efd, ifd, pss_out, VB, dx, ieee, reach):
    """smpexc: PSTess clamps the Efd state to [Vrmin, Vrmax] after its derivative is
    computed and keeps the derivative (a windup clamp; PST's misspelt dEFD,
    docs/pst_models.md 2.1); ieee: a non-windup limit as IEEE Std 421.5-2016 (SEXS/ST1A
    lag).  No T_A: no state (the output is algebraic)."""
    VA, dx[S.VAs, i] = leadlag_input_state(err, x[S.VAs, i], P[i, E.TCTB], P[i, E.TB])
    if P[i, E.TA] < LBND:
        return
    lo, hi = P[i, E.VRMIN], P[i, E.VRMAX]
    if ieee:
        x[S.Efd, i], dx[S.Efd, i] = nonwindup_lag(
            P[i, E.KA] * VA, x[S.Efd, i], P[i, E.TA], lo, hi, ieee, 0.0
        )
    else:
        dx[S.Efd, i] = lag(P[i, E.KA] * VA, x[S.Efd, i], P[i, E.TA])[1]
        x[S.Efd, i] = clip(x[S.Efd, i], lo, hi)
