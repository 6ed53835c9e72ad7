"""ANDES's TG2 (tg_con type 7; ANDES 2.0 ``andes/models/governor/tg2.py``, not a PSS/E
model; its deadband off, ANDES's default).

pmech = clip(P_ref + (1 + s T1)/(1 + s T2) of (w_f - omega)/R, pmin, pmax), the limit on
the output without windup (a hard limiter; the lead-lag runs on).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from stabctl._jit.decorators import kernel
from stabctl.models.blocks import clip, leadlag
from stabctl.models.declaration import DyrModel, Limits, states
from stabctl.models.governors.table import AT_RATED_SPEED, G

if TYPE_CHECKING:
    from stabctl.models.governors import GovernorParams

TG2 = 7
KINDS = {TG2: "TG2 (ANDES)"}
#: the speed set point w_f (`table.AT_RATED_SPEED`); the lead T1 (tg_con T3, no bound of
#: its own) >= 0 (round 42: T1 = -0.2 was run as given)
LIMITS = (
    AT_RATED_SPEED,
    Limits("ANDES 2.0 TG2: the lead-lag (1 + s T1)/(1 + s T2)", nonnegative=("T3",)),
)
#: the time constants that must be >= 1e-3 s (declared tg_con fields)
NEEDS = ("Tc",)
#: the family refuses a start-up order (`initialise`'s order) outside [Tmin, Tmax]:
#: the power limits on the power order
ORDER_LIMITS = True
DYR = (
    # TG2 (ANDES's own, read by name from ANDES; no PSS/E record of that name in the
    # Model Library) -> type 7: invR = 1/R, the lead-lag T1/T2, the output limits
    DyrModel(
        "TG2",
        ("R", "wref0", "pmax", "pmin", "T1", "T2"),
        {"wf": "wref0", "Tmax": "pmax", "Tmin": "pmin", "T3": "T1", "Tc": "T2"},
        kind=TG2,
        andes=("TG2",),
    ),
)

#: the state: the lead-lag's
S = states("TG2States", ("leadlag",))
STATE_NAMES = {TG2: S._fields}


def has_state(p: GovernorParams):
    """Which slots of `S` are states (the one)."""
    return (True,)


def time_constants(p: GovernorParams):
    """The declared time constants that set a state's speed: field -> where."""
    return {"Tc": True}


def initialise(p: GovernorParams, r, pmech0, order, x):
    """TG2 at rest on rows r: the lead-lag at its input, 0; returns P_ref = pmech0."""
    x[S.leadlag, r] = 0.0
    return order[r]


@kernel(inline="always")
def _output(P, x, k, omega, dx=None):
    """TG2's mechanical power clip(P_ref + LL((w_f - omega)/R), pmin, pmax) (T3 = T1 the
    lead, Tc = T2 the lag; ANDES's HardLimiter: no windup, the lead-lag runs on); its
    state's derivative into dx when given."""
    y, d = leadlag((P[k, G.WF] - omega) * P[k, G.INVR], x[S.leadlag, k], P[k, G.T3], P[k, G.TC])
    if dx is not None:
        dx[S.leadlag, k] = d
    return clip(P[k, G.PREF] + y, P[k, G.TMIN], P[k, G.TMAX])


@kernel(inline="always")
def pmech(P, x, k, omega):
    """TG2's mechanical power (`_output`)."""
    return _output(P, x, k, omega, None)


@kernel(inline="always")
def derivatives(P, x, k, omega, pe, dx):
    """TG2's lead-lag state's derivative into dx (`_output`)."""
    _output(P, x, k, omega, dx)
