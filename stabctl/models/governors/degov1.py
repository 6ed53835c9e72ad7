"""PSS/E's DEGOV1 (tg_con type 11): the Woodward diesel governor with droop.

DEGOV (:mod:`~stabctl.models.governors.degov`) with a permanent droop R fed back at the
speed summing junction: P_ref - (omega - 1) - R f -> electric control box (1 + s T3)/(1
+ s T1 + s^2 T1 T2) -> actuator (1 + s T4)/((1 + s T5)(1 + s T6)) -> K/s, non-windup on
[TMIN, TMAX] = the engine's torque T_m; the mechanical power P_m = T_m omega (PSS/E's
block diagram; PowerSimulationsDynamics.jl's DEGOV1 forms the same P_m and hands its
shaft P_m / omega = T_m, as stabctl's PSS/E machines, mac_con psse_swing 1, divide it).
The droop's feedback f (the ICON M, the droop control flag): 0 the throttle, T_m itself;
1 the machine's electrical power through 1/(1 + s TE) (absent below 1e-3 s: the power
itself).

At rest every state but the torque (at Pm0) and the measured power (at the electrical
power, Pm0 at rated speed) is 0, with P_ref = R Pm0: after a step dP of P_ref the unit
settles where P_ref - (omega - 1) = R f, its droop line.

The engine's transport delay TD as DEGOV's (its Pade approximant, `degov.delayed`; its
states after the measured power); the droop's throttle feedback (flag 0) is the torque
before it.  A block whose lag is below 1e-3 s is absent, as DEGOV's.  Refused by name
(`check`): a lead without its lag; TMAX < TMIN by the tg_con table.

The DYR record (PSS/E Model Library DEGOV1; PowerSystems.jl's DEGOV1): ICON M, then T1
T2 T3 K T4 T5 T6 TD TMAX TMIN DROOP TE; T1 .. TMIN in DEGOV's tg_con columns, M, DROOP
and TE in DEGOV1's own (``PARAMS``).  Sources: PSS/E Model Library DEGOV1;
PowerSimulationsDynamics.jl ``tg_models.jl`` (DEGOV1), ``init_tg.jl`` and
``test_case63_degov1.jl``.  ANDES 2.0 has no DEGOV1.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.models.blocks import LBND, lag
from stabctl.models.declaration import DyrModel, Limits, Param, states
from stabctl.models.governors import degov
from stabctl.models.governors.table import G, own

if TYPE_CHECKING:
    from stabctl.models.governors import GovernorParams

DEGOV1 = 11
KINDS = {DEGOV1: "DEGOV1"}
#: the time constants that must be >= 1e-3 s (declared tg_con fields): none, an absent
#: lag drops its block
NEEDS: tuple[str, ...] = ()
#: the leads T3 (control box) and T4 (actuator) are time constants, >= 0: tg_con T3 and T4
#: have no bound of their own (round 42: T3 = -0.018 and T4 = -5.1 were run as given)
LIMITS = Limits("PSS/E Model Library DEGOV1: the leads T3, T4", nonnegative=("T3", "T4"))
#: the family refuses a start-up order (`initialise`'s order) outside [Tmin, Tmax]:
#: the torque limits TMAX, TMIN on the start-up torque
ORDER_LIMITS = True
#: DEGOV1's own tg_con columns
PARAMS = (
    Param(
        "droop_flag",
        "code",
        60,
        integer=True,
        choices=(0.0, 1.0),
        label="DEGOV1's droop_flag",
        doc="DEGOV1: droop feedback (ICON M): 0 the throttle (torque), 1 the electrical power",
    ),
    Param("droop", "pu", 61, lo=0.0, doc="DEGOV1: permanent droop R, pu speed / pu power"),
    Param("Te", "s", 62, lo=0.0, doc="DEGOV1: electrical power transducer time constant TE"),
)
#: the packed columns of `PARAMS`: P[k, O.DROOP]
O = own("DEGOV1Columns", PARAMS)
DYR = (
    DyrModel(
        "DEGOV1",
        ("M", *degov.DYR[0].fields, "DROOP", "TE"),
        {"droop_flag": "M", **degov.DYR[0].copy, "droop": "DROOP", "Te": "TE"},
        kind=DEGOV1,
    ),
)

#: the states: DEGOV's five (its `chain` writes them), then the measured electrical
#: power (droop flag 1)
S = states(
    "DEGOV1States",
    (*degov.CHAIN, "pelec", *(f"delay{i + 1}" for i in range(degov.PADE_MAX))),
)
STATE_NAMES = {DEGOV1: S._fields}
#: the first delay slot, a numpy scalar (`degov.delayed`; the kernel coding rules)
_DELAY1 = np.int64(S.delay1)


def has_state(p: GovernorParams):
    """Which slots of `S` are states: DEGOV's chain's five, the measured power with droop
    flag 1 and TE, then the transport delay's (`degov.has_state`)."""
    chain = degov.has_state(p)
    n = len(degov.CHAIN)
    return (*chain[:n], (p.droop_flag == 1) & (p.Te >= LBND), *chain[n:])


def time_constants(p: GovernorParams):
    """The declared time constants that set a state's speed: field -> where."""
    return {**degov.time_constants(p), "Te": (p.droop_flag == 1) & (p.Te >= LBND)}


def check(g, r: int) -> str | None:
    """The first DEGOV1 option of tg_con row r (0-based) stabctl does not model (DEGOV's,
    `degov.check`), with the reason, or None."""
    return degov.check(g, r, "DEGOV1")


def initialise(p: GovernorParams, r, pmech0, order, x):
    """DEGOV1 at rest on rows r: the torque and the measured power at pmech0 (rated
    speed; the family refuses it outside [TMIN, TMAX]), the other states 0; returns
    P_ref = R pmech0 on r."""
    x[S.torque, r] = pmech0[r]
    x[S.pelec, r] = np.where(p.droop_flag[r] == 1, pmech0[r], 0.0)
    x[S.delay1, r] = np.where(p.Teng[r] >= LBND, pmech0[r], 0.0)  # `degov.delayed`
    return p.droop[r] * pmech0[r]


@kernel(inline="always")
def pmech(P, x, k, omega):
    """DEGOV1: the engine's torque TD later (`degov.delayed`) times the speed (module
    docstring)."""
    return degov.delayed(P, x, k, x, degov.READ, _DELAY1) * omega


@kernel(inline="always")
def derivatives(P, x, k, omega, pe, dx):
    """DEGOV1 (module docstring): P_ref - (omega - 1) - R f through the control box and
    the actuator into the integrator K/s (clamps the torque in x); f the torque (flag 0)
    or the electrical power pe through TE (flag 1)."""
    if P[k, O.DROOP_FLAG] == 1.0:
        feedback, dx[S.pelec, k] = lag(pe, x[S.pelec, k], P[k, O.TE])
    else:
        feedback = x[S.torque, k]
    degov.chain(P, x, k, P[k, G.PREF] - (omega - 1.0) - P[k, O.DROOP] * feedback, dx)
    degov.delayed(P, x, k, dx, degov.WRITE, _DELAY1)
