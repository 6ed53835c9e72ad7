"""PSS/E's DEGOV (tg_con type 10): the Woodward diesel governor, isochronous.

P_ref - (omega - 1) -> electric control box (1 + s T3)/(1 + s T1 + s^2 T1 T2) ->
actuator (1 + s T4)/((1 + s T5)(1 + s T6)) -> K/s, non-windup on [TMIN, TMAX] = the
engine's torque T_m, handed to the machine as its mechanical power P_m.
PowerSimulationsDynamics.jl's DEGOV (within 4.7e-5 pu of speed of the published run)
forms P_m = T_m omega and its shaft divides it by omega again: the shaft receives T_m.
The run's machine is a GENCLS, whose swing equation takes P_m as it is (PSS/E's run
OMIB_GENCLS, `stabctl.io.dyr`): with P_m = T_m the run agrees within 4.6e-5 pu, with
T_m omega it is 8.5e-5 off (measured, tests/data/psse_runs/DEGOV).  On a machine whose
swing equation divides P_m by the speed (PSS/E's GENROU, mac_con psse_swing 1) the
shaft then receives T_m/omega, not T_m: a difference of the order of the speed
deviation.

The integrator holds the load: at rest T_m = Pm0 and every other state is 0, with P_ref
= 0.  DEGOV has no load reference of its own; P_ref (moved by a `PrefStep`) enters at
the speed summing junction, where DEGOV1 (the droop version) takes its reference, so a
step dP makes the isochronous unit hold its speed at 1 + dP.  The limits act on the
integrator (the torque), the only block whose output equals Pm0 at rest (PowerWorld's
DEGOV widens TMAX/TMIN to the initial Pmech, i.e. they bound the power order).

A block whose lag is below 1e-3 s is absent: T1 (with T2) the control box's, T5 and T6
the actuator's (the second-order lag falls to the one left).  Refused by name (`check`):
the engine's transport delay TD > 0 (an ODE model has no delay; PSS/E's run "nodelay"
is TD = 0), a lead T3 without the control box's lag T1 or a lead T4 without an actuator
lag (improper); TMAX < TMIN by the tg_con table (every governor's limits).

The DYR record (PSS/E Model Library DEGOV; PowerWorld's DEGOV, the same ten CONs): T1
T2 T3 K T4 T5 T6 TD TMAX TMIN, stored in the shared tg_con columns T1 -> Tc, T2 -> Ts,
T3, K -> invR, T4, T5, T6, TD -> Teng, TMAX -> Tmax, TMIN -> Tmin.  Sources: PSS/E
Model Library DEGOV; PowerSimulationsDynamics.jl ``tg_models.jl`` (DEGOV) and
``test_case57_degov.jl``; PowerWorld's DEGOV help page.  ANDES 2.0 has no DEGOV.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.models.blocks import LBND, leadlag2, nonwindup
from stabctl.models.declaration import DyrModel, Limits, states
from stabctl.models.governors.table import AT_LIMIT, G

if TYPE_CHECKING:
    from stabctl.models.governors import GovernorParams

DEGOV = 10
KINDS = {DEGOV: "DEGOV"}
#: the time constants that must be >= 1e-3 s (declared tg_con fields): none, an absent
#: lag drops its block
NEEDS: tuple[str, ...] = ()
#: the leads T3 (control box) and T4 (actuator) are time constants, >= 0: tg_con T3 and T4
#: have no bound of their own (round 42: T3 = -0.018 and T4 = -5.1 were run as given)
LIMITS = Limits("PSS/E Model Library DEGOV: the leads T3, T4", nonnegative=("T3", "T4"))
#: the family refuses a start-up order (`initialise`'s order) outside [Tmin, Tmax]:
#: the torque limits TMAX, TMIN on the start-up torque
ORDER_LIMITS = True
DYR = (
    DyrModel(
        "DEGOV",
        ("T1", "T2", "T3", "K", "T4", "T5", "T6", "TD", "TMAX", "TMIN"),
        {
            "Tc": "T1",
            "Ts": "T2",
            "T3": "T3",
            "invR": "K",
            "T4": "T4",
            "T5": "T5",
            "T6": "T6",
            "Teng": "TD",
            "Tmax": "TMAX",
            "Tmin": "TMIN",
        },
        kind=DEGOV,
    ),
)

#: the states: the electric control box's two, the actuator's two, the torque (the
#: actuator's integrator, non-windup)
S = states("DEGOVStates", ("ecb1", "ecb2", "act1", "act2", "torque"))
STATE_NAMES = {DEGOV: S._fields}


def has_state(p: GovernorParams):
    """Which slots of `S` are states: the control box's with T1 (its second with T2 too),
    the actuator's with T5 or T6 (its second with both), the torque always."""
    t1, t2, t5, t6 = (v >= LBND for v in (p.Tc, p.Ts, p.T5, p.T6))
    return (t1, t1 & t2, t5 | t6, t5 & t6, True)


def time_constants(p: GovernorParams):
    """The declared time constants that set a state's speed: field -> where."""
    t1 = p.Tc >= LBND
    return {"Tc": t1, "Ts": t1 & (p.Ts >= LBND), "T5": p.T5 >= LBND, "T6": p.T6 >= LBND}


def check(g, r: int, model: str = "DEGOV") -> str | None:
    """The first DEGOV option of tg_con row r (0-based) stabctl does not model (module
    docstring), with the reason, or None; ``model`` the name in the message (DEGOV1, which
    shares the chain)."""
    if g.Teng[r] != 0:
        return (
            f"field 'Teng' ({model}'s TD): the engine's transport delay is not modelled; "
            "only TD = 0"
        )
    if g.Tc[r] < LBND and abs(g.T3[r]) >= LBND:
        return (
            f"field 'T3': {model}'s control-box lead T3 needs its lag T1 (field 'Tc') >= {LBND} s"
        )
    if g.T5[r] < LBND and g.T6[r] < LBND and abs(g.T4[r]) >= LBND:
        return f"field 'T4': {model}'s actuator lead T4 needs T5 or T6 >= {LBND} s"
    return None  # TMAX below TMIN: the tg_con table's check (the family's limits)


def initialise(p: GovernorParams, r, pmech0, order, x):
    """DEGOV at rest on rows r: the torque at pmech0 (rated speed; the family refuses it
    outside [TMIN, TMAX]), the other states 0; returns P_ref = 0 on r."""
    x[S.torque, r] = pmech0[r]
    return np.zeros(int(np.count_nonzero(r)))


@kernel(inline="always")
def _lag(T):
    """A lag's time constant, 0 where the block is absent (below LBND)."""
    return T if T >= LBND else 0.0


@kernel(inline="always")
def pmech(P, x, k, omega):
    """DEGOV: the engine's torque, handed to the machine as its P_m (module docstring)."""
    return x[S.torque, k]


@kernel(inline="always")
def derivatives(P, x, k, omega, pe, dx):
    """DEGOV (module docstring): P_ref - (omega - 1) through `chain`."""
    chain(P, x, k, P[k, G.PREF] - (omega - 1.0), dx)


@kernel(inline="always")
def chain(P, x, k, u, dx):
    """The control box and the actuator of governor k into the integrator K/s (clamps the
    torque in x) from the speed junction's output u: DEGOV's, and DEGOV1's, whose states
    begin with these five in `S`'s order."""
    t1 = _lag(P[k, G.TC])
    a2 = t1 * P[k, G.TS] if P[k, G.TS] >= LBND else 0.0
    y1, dx[S.ecb1, k], dx[S.ecb2, k] = leadlag2(u, x[S.ecb1, k], x[S.ecb2, k], P[k, G.T3], t1, a2)
    t5, t6 = _lag(P[k, G.T5]), _lag(P[k, G.T6])
    y2, dx[S.act1, k], dx[S.act2, k] = leadlag2(
        y1, x[S.act1, k], x[S.act2, k], P[k, G.T4], t5 + t6, t5 * t6
    )
    x[S.torque, k], dx[S.torque, k] = nonwindup(
        x[S.torque, k], P[k, G.INVR] * y2, P[k, G.TMIN], P[k, G.TMAX], AT_LIMIT, 0.0
    )
