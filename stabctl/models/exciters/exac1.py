"""EXAC1 (exc_con type 7, IEEE 1981 AC1 as PSS/E EXAC1 and ANDES 2.0 ``exac1.py``) and
ESAC1A (type 9, IEEE 421.5-2005 AC1A as ANDES 2.0 ``esac1a.py``, no UEL/OEL): one family
of equations, and the AC exciter (V_E, its feedback V_FE, the rectifier) AC8B shares.

Lead-lag, non-windup K_A/(1 + s T_A) -> V_R; T_E dV_E/dt = V_R - V_FE, V_FE = K_E V_E +
S_E(V_E) V_E + K_D I_fd (PSS/E's quadratic saturation); Efd = V_E F_EX(K_C I_fd/V_E); rate
feedback s K_F/(1 + s T_F) of V_FE.  ESAC1A: the lag's non-windup limits are [VAmin,
VAmax], V_R = V_A clipped to [Vrmin, Vrmax] and the exciter's V_E held at or above 0
(ANDES 2.0 esac1a.py leaves out this clip, the V_E limit and the rate feedback:
docs/pst_models.md 2.7).  PSTess has no AC1: IEEE 421.5's non-windup rule in both
conventions.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.errors import CaseError, refuse_initial
from stabctl.models.blocks import (
    GAIN_OVER_T,
    clip,
    leadlag_input_state,
    nonwindup,
    nonwindup_lag,
    rectifier_loading,
    washout,
)
from stabctl.models.declaration import DyrModel, Limits, beyond, states
from stabctl.models.exciters.dc import dc_feedback
from stabctl.models.exciters.table import IEEE_RULE, LEAD_LAG, REGULATOR_GAIN, E, upper

if TYPE_CHECKING:
    from stabctl.models.exciters import ExciterParams

AC1, AC1A = 7, 9
KINDS = {AC1: "EXAC1 (IEEE AC1)", AC1A: "ESAC1A (IEEE 421.5 AC1A)"}
#: AC1's and AC1A's saturation point E2 and T_E >= 0, AC1A's V_A limits ordered (IEEE Std
#: 421.5-2016 AC1A; PSS/E Model Library EXAC1)
LIMITS = {
    AC1: (Limits("PSS/E Model Library EXAC1", nonnegative=("E2", "TE")), REGULATOR_GAIN, LEAD_LAG),
    AC1A: (
        Limits("IEEE Std 421.5 AC1A", nonnegative=("E2", "TE"), ordered=(("VAmax", "VAmin"),)),
        REGULATOR_GAIN,
        LEAD_LAG,
    ),
}
#: reads the machine's field current (`stabctl.models.exciters.field_current`)
READS_IFD = True
#: has a rate feedback s K_F/(1 + s T_F) from exc_con columns 21-22 (KF, TF)
RATE_FEEDBACK = True
#: fed by a potential (and compound) source V_B (its ``source_voltage``)
SOURCE = False
#: how it reads exc_con columns 10-15 (K_E, T_E, E1, SE1, E2, SE2; `exciter_params`): "dc"
#: PST's DC exciter (saturation fit by dc_sat, K_E computed where 0), "quadratic" K_E,
#: T_E and PSS/E's quadratic saturation, "linear" K_E and T_E alone, "" not at all
EXCITER_COLUMNS = "quadratic"
#: the time constants that must be >= 1e-3 s: (name in messages, declared field)
NEEDS: tuple[tuple[str, str], ...] = (("TA", "TA"), ("TE", "TE"))

#: ESAC1A's record, every parameter a copy, in the PSS/E Model Library's order
_ESAC1A_COPY = upper(
    "TR", "TB", "TC", "KA", "TA", "VAmax", "VAmin", "TE", "KF", "TF", "KC", "KD", "KE", "E1",
    "SE1", "E2", "SE2", "Vrmax", "Vrmin",
)  # fmt: skip

DYR = (
    # EXAC1 -> type 7 (IEEE 1981 AC1); saturation: PSS/E's quadratic through the points
    DyrModel(
        "EXAC1",
        (
            "TR",
            "TB",
            "TC",
            "KA",
            "TA",
            "VRMAX",
            "VRMIN",
            "TE",
            "KF",
            "TF",
            "KC",
            "KD",
            "KE",
            "E1",
            "SE(E1)",
            "E2",
            "SE(E2)",
        ),
        upper(
            "TR",
            "TB",
            "TC",
            "KA",
            "TA",
            "Vrmax",
            "Vrmin",
            "TE",
            "KF",
            "TF",
            "KC",
            "KD",
            "KE",
            "E1",
            "E2",
            SE1="SE(E1)",
            SE2="SE(E2)",
        ),
        kind=AC1,
        andes=("EXAC1",),
    ),
    # ESAC1A -> type 9 (IEEE 421.5 AC1A): EXAC1 with V_A limited to [VAMIN, VAMAX] and
    # V_R to [VRMIN, VRMAX]; the saturation points named as ANDES's psse-dyr.yaml
    # names them (its inputs, in its own order, are matched by name)
    DyrModel(
        "ESAC1A",
        tuple(_ESAC1A_COPY.values()),
        _ESAC1A_COPY,
        kind=AC1A,
        andes=("ESAC1A",),
    ),
)

#: the states: transducer, lead-lag, regulator V_R (ESAC1A: its V_A, clipped to V_R), the
#: exciter's V_E, the rate feedback's washout R_f
S = states("EXAC1States", ("VTR", "VAs", "VR", "VE", "Rf"))
STATE_NAMES = {AC1: S._fields, AC1A: ("VTR", "VAs", "VA", "VE", "Rf")}


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
    """EXAC1 and ESAC1A at rest on rows r (a mask): `initial_exciter`'s V_E0 and V_FE0 =
    V_R0 (ESAC1A's V_A0), the lead-lag V_FE0/K_A, the washout V_FE0; writes x, returns
    (V_ref - V_TR, p)."""
    VE, VFE = initial_exciter(
        p,
        r,
        vex,
        lambda i: "ESAC1A" if p.kind[i] == AC1A else "EXAC1",
        lambda i: [("V_A", "VAmin, VAmax", p.VAmin[i], p.VAmax[i])] if p.kind[i] == AC1A else [],
    )
    VA = VFE[r] / p.KA[r]
    x[S.VAs, r] = VA
    x[S.VR, r] = VFE[r]
    x[S.VE, r] = VE[r]
    x[S.Rf, r] = VFE[r]
    return VA, p


def initial_exciter(p: ExciterParams, r, Efd, name, limits, checks=None):
    """The AC exciters (EXAC1, ESAC1A, AC8B, EXAC2, ESAC6A) at rest on rows r (a mask),
    arrays (n_exc,) (0 for the other rows): the exciter voltage V_E0 solving V_E
    F_EX(K_C I_fd0/V_E) = Efd0 (`blocks.rectifier_loading`, increasing in V_E; I_fd0 =
    Efd0) and V_FE0 = K_E V_E0 + S_E(V_E0) V_E0 + K_D I_fd0 (= V_R0); raises CaseError if
    V_R0 is outside [Vrmin, Vrmax] or the type's `limits` (row -> list of (what, limit
    names, lo, hi)) or V_R0/K_A has no V_E0; name(row) is the type's name in messages.
    ``checks`` (row, V_FE0 -> list of (what, limit names, value, lo, hi)), where given,
    replaces those two: the type's own start-up limits on the signals V_FE0 sets."""
    from scipy.optimize import brentq  # here: the case layer imports this module (0.5 s)

    VE, VFE = np.zeros(p.n), np.zeros(p.n)
    bad: dict[int, str] = {}  # row -> its limit violation
    for i in np.nonzero(r)[0]:
        efd0 = ifd0 = float(Efd[i])
        if efd0 <= 0:
            raise CaseError(
                f"exc_con row {i + 1}: {name(i)} initial field voltage {efd0:.4f} pu must be > 0"
            )
        KC = float(p.KC[i])

        def residual(v, KC=KC, ifd0=ifd0, efd0=efd0):
            return v * rectifier_loading(KC * ifd0 / v) - efd0

        VE[i] = brentq(residual, efd0, efd0 + KC * ifd0 + 1.0, xtol=1e-15, rtol=1e-15)
        VFE[i] = dc_feedback(p.KE[i], p.Asat[i], p.Bsat[i], 1.0, VE[i]) + p.KD[i] * ifd0
        if checks is None:
            own = [("V_R", "Vrmin, Vrmax", p.Vrmin[i], p.Vrmax[i]), *limits(i)]
            tests = [(what, names, VFE[i], lo, hi) for what, names, lo, hi in own]
        else:
            tests = checks(i, VFE[i])
        out = [
            f"{what} = {value:.4f} pu outside [{names}] = [{lo:.4f}, {hi:.4f}]"
            for what, names, value, lo, hi in tests
            if beyond(value, lo, hi)
        ]
        if out:
            bad[i] = f"exc_con row {i + 1}: {name(i)} initial regulator output " + "; ".join(out)
    refuse_initial("exc_con", [i in bad for i in range(p.n)], bad.get)
    return VE, VFE


@kernel(inline="always")
def rectified(P, i, VE, ifd):
    """The AC exciters' field voltage V_E F_EX(I_N), I_N = K_C I_fd / V_E
    (`blocks.rectifier_loading`); 0 for V_E <= 0."""
    return VE * rectifier_loading(P[i, E.KC] * ifd / VE) if VE > 0 else 0.0


@kernel(inline="always")
def exciter_feedback(P, i, VE, ifd):
    """V_FE = K_E V_E + S_E(V_E) V_E + K_D I_fd of the AC exciters (PSS/E's quadratic
    saturation, `dc.dc_feedback`)."""
    return dc_feedback(P[i, E.KE], P[i, E.ASAT], P[i, E.BSAT], P[i, E.SATQ], VE) + P[i, E.KD] * ifd


@kernel(inline="always")
def exciter(P, i, VE, VR, VFE):
    """The AC exciters' T_E dV_E/dt = V_R - V_FE with V_E >= 0, non-windup (the
    rectifier's diodes; every AC exciter: EXAC1, ESAC1A, EXAC2, AC8B, ESAC6A, as OpenIPSL's
    and OPAL-RT's PSS/E models; round 50: EXAC1's and EXAC2's V_E ran unlimited, to -17 pu
    after a 0.6 pu VREF pulse).

    Returns
    -------
    (float, float)
        V_E (clamped), its derivative.
    """
    return nonwindup(VE, (VR - VFE) / P[i, E.TE], 0.0, np.inf, IEEE_RULE, 0.0)


@kernel(inline="always")
def field_voltage(P, x, i, VTR_alg, pss_out, VB, ifd, ieee):
    """EXAC1, ESAC1A: `rectified` V_E."""
    return rectified(P, i, x[S.VE, i], ifd)


@kernel(inline="always")
def derivatives(P, x, i, err, eterm, efd, ifd, pss_out, VB, dx, ieee, reach):
    """EXAC1 and ESAC1A (docs/pst_models.md 2.7): the rate feedback of V_FE (state R_f,
    with K_F != 0) subtracted from the error, the lead-lag T_C/T_B, the regulator lag
    non-windup (EXAC1: V_R on [Vrmin, Vrmax]; ESAC1A: V_A on [VAmin, VAmax], then V_R = V_A
    clipped to [Vrmin, Vrmax]), the exciter T_E dV_E/dt = V_R - V_FE (V_E >= 0,
    non-windup: IEEE 421.5-2005 6.1, as OpenIPSL's and Dynawo's AC1A)."""
    VFE = exciter_feedback(P, i, x[S.VE, i], ifd)
    if P[i, E.KF] != 0:
        VF, dx[S.Rf, i] = washout(VFE, x[S.Rf, i], P[i, E.TF], P[i, E.KF], GAIN_OVER_T)
        err = err - VF
    u, dx[S.VAs, i] = leadlag_input_state(err, x[S.VAs, i], P[i, E.TCTB], P[i, E.TB])
    if P[i, E.KIND] == AC1A:
        lo, hi = P[i, E.VAMIN], P[i, E.VAMAX]
    else:
        lo, hi = P[i, E.VRMIN], P[i, E.VRMAX]
    x[S.VR, i], dx[S.VR, i] = nonwindup_lag(
        P[i, E.KA] * u, x[S.VR, i], P[i, E.TA], lo, hi, IEEE_RULE, 0.0
    )
    VR = clip(x[S.VR, i], P[i, E.VRMIN], P[i, E.VRMAX])
    x[S.VE, i], dx[S.VE, i] = exciter(P, i, x[S.VE, i], VR, VFE)
