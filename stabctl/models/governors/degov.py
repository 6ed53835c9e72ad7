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

The engine's transport delay TD (PSS/E: the torque e^(-s TD) later, a table of its past
values): its Pade approximant of order n = min(1 + int(TD / 0.1 s), 8) (`pade_order`;
the closed form, as python-control's ``pade``), n states (``delay1`` ...) realised in
controllable canonical form in time scaled by TD and by the approximant's constant term,
so that at rest every delay state but the first is 0 and the first equals the torque.
The order grows with the delay, so that the approximant's phase holds through the
governor's frequencies and its fastest pole, 2 / TD at order 1 to 13.9 / TD at order 8,
stays slower than the machines' subtransients (declared as a time constant,
`delay_time_constant`: 29-72 ms for TD 0.1-1 s).  On the torque of PSS/E's run with TD =
1 s the approximant of order 2, 4, 6 is within 3.5e-3, 5.0e-4, 5.0e-5 pu of the exact
delay (a swing of 4.1e-3 pu) and order 8 within 1.8e-5; the run
(tests/data/psse_runs/DEGOV_DELAY, PSID's DDE within 3.1e-5 pu of speed) is within its
tolerance.  TD below 1e-3 s: no delay.

A block whose lag is below 1e-3 s is absent: T1 (with T2) the control box's, T5 and T6
the actuator's (the second-order lag falls to the one left).  Refused by name (`check`):
a lead T3 without the control box's lag T1 or a lead T4 without an actuator lag
(improper); TMAX < TMIN by the tg_con table (every governor's limits).  DEGOV1 shares
the chain and the delay (`delayed`).

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

#: the highest order of the transport delay's Pade approximant (`pade_order`)
PADE_MAX = 8
#: the delay's length per order step (s): order 1 below 0.1 s, 2 below 0.2 s, ...
PADE_STEP_S = 0.1
#: the slack of the order's floor: a TD written as a multiple of PADE_STEP_S (0.3, 0.6, 0.7
#: s) takes that multiple's order, not the one below it that binary division gives
PADE_ROUND = 1e-9
#: the states the chain of DEGOV and DEGOV1 share (DEGOV1's begin with these): the electric
#: control box's two, the actuator's two, the torque (the actuator's integrator,
#: non-windup)
CHAIN = ("ecb1", "ecb2", "act1", "act2", "torque")
#: DEGOV's states: the chain's, then the transport delay's Pade states (`pade_order` of
#: them states, the rest unused)
S = states("DEGOVStates", (*CHAIN, *(f"delay{i + 1}" for i in range(PADE_MAX))))
STATE_NAMES = {DEGOV: S._fields}
#: `delayed`'s arguments as numpy scalars (the kernel coding rules: one compilation for
#: every value): read only, or write the derivatives; DEGOV's first delay slot
READ, WRITE = np.bool_(False), np.bool_(True)
DELAY1 = np.int64(S.delay1)


def _pade_coefficients():
    """(den, num), each (PADE_MAX, PADE_MAX + 1): row n - 1 the Pade approximant of order
    n of e^(-s), the denominator made monic, coefficients by ascending power (a_0 .. a_n,
    b_0 .. b_n; unused entries 0): the closed form c_k = (2n - k)! n! / ((2n)! k! (n - k)!),
    the denominator's c_k, the numerator's (-1)^k c_k (python-control's ``pade``, which
    the tests compare with, computes the same; importing it here cost 1.8 s at start-up)."""
    from math import factorial as f

    den = np.zeros((PADE_MAX, PADE_MAX + 1))
    num = np.zeros((PADE_MAX, PADE_MAX + 1))
    for n in range(1, PADE_MAX + 1):
        c = np.array([f(2 * n - k) * f(n) / (f(2 * n) * f(k) * f(n - k)) for k in range(n + 1)])
        den[n - 1, : n + 1] = c / c[n]
        num[n - 1, : n + 1] = c * (-1.0) ** np.arange(n + 1) / c[n]
    return den, num


#: the Pade coefficients (`_pade_coefficients`), module constants folded into the kernels
PADE_DEN, PADE_NUM = _pade_coefficients()
#: the fastest pole's magnitude of each order's approximant of e^(-s) (1/s per 1/TD)
PADE_FASTEST = np.array(
    [np.abs(np.roots(PADE_DEN[n - 1, : n + 1][::-1])).max() for n in range(1, PADE_MAX + 1)]
)


@kernel(inline="always")
def pade_order(TD):
    """The order of the transport delay TD's Pade approximant (s): 0 (no delay) below
    1e-3 s, else min(1 + floor(TD / PADE_STEP_S), PADE_MAX), the quotient's floor taken
    with `PADE_ROUND` of slack (0.3 / 0.1 is 2.9999999999999996 in binary: order 4)."""
    if TD < LBND:
        return 0
    return min(1 + int(TD / PADE_STEP_S + PADE_ROUND), PADE_MAX)


def pade_orders(TD) -> np.ndarray:
    """`pade_order` of each delay of the array TD (s), int array."""
    TD = np.asarray(TD, float)
    steps = (TD / PADE_STEP_S + PADE_ROUND).astype(int)
    return np.where(TD < LBND, 0, np.minimum(1 + steps, PADE_MAX))


def delay_time_constant(TD) -> np.ndarray:
    """The fastest time constant of each transport delay TD (s; TD over its approximant's
    fastest pole, `PADE_FASTEST`; inf without a delay), (n,)."""
    order = pade_orders(TD)
    fastest = PADE_FASTEST[np.maximum(order, 1) - 1]
    return np.where(order > 0, np.asarray(TD, float) / fastest, np.inf)


def has_state(p: GovernorParams):
    """Which slots of `S` are states: the control box's with T1 (its second with T2 too),
    the actuator's with T5 or T6 (its second with both), the torque always, the first
    `pade_order` delay states."""
    t1, t2, t5, t6 = (v >= LBND for v in (p.Tc, p.Ts, p.T5, p.T6))
    order = pade_orders(p.Teng)
    return (t1, t1 & t2, t5 | t6, t5 & t6, True, *(order > i for i in range(PADE_MAX)))


def time_constants(p: GovernorParams):
    """The declared time constants that set a state's speed: field -> where (the delay's
    fastest, `delay_time_constant`, as ``delay_tc``)."""
    t1 = p.Tc >= LBND
    return {
        "Tc": t1,
        "Ts": t1 & (p.Ts >= LBND),
        "T5": p.T5 >= LBND,
        "T6": p.T6 >= LBND,
        "delay_tc": np.isfinite(p.delay_tc),
    }


def check(g, r: int, model: str = "DEGOV") -> str | None:
    """The first DEGOV option of tg_con row r (0-based) stabctl does not model (module
    docstring), with the reason, or None; ``model`` the name in the message (DEGOV1, which
    shares the chain)."""
    if g.Tc[r] < LBND and abs(g.T3[r]) >= LBND:
        return (
            f"field 'T3': {model}'s control-box lead T3 needs its lag T1 (field 'Tc') >= {LBND} s"
        )
    if g.T5[r] < LBND and g.T6[r] < LBND and abs(g.T4[r]) >= LBND:
        return f"field 'T4': {model}'s actuator lead T4 needs T5 or T6 >= {LBND} s"
    return None  # TMAX below TMIN: the tg_con table's check (the family's limits)


def initialise(p: GovernorParams, r, pmech0, order, x):
    """DEGOV at rest on rows r: the torque at pmech0 (rated speed; the family refuses it
    outside [TMIN, TMAX]), its transport delay's first state too (`delayed`), the other
    states 0; returns P_ref = 0 on r."""
    x[S.torque, r] = pmech0[r]
    x[S.delay1, r] = np.where(p.Teng[r] >= LBND, pmech0[r], 0.0)
    return np.zeros(int(np.count_nonzero(r)))


@kernel(inline="always")
def _lag(T):
    """A lag's time constant, 0 where the block is absent (below LBND)."""
    return T if T >= LBND else 0.0


@kernel(inline="always")
def pmech(P, x, k, omega):
    """DEGOV: the engine's torque TD later (`delayed`), handed to the machine as its P_m
    (module docstring)."""
    return delayed(P, x, k, x, READ, DELAY1)


@kernel(inline="always")
def derivatives(P, x, k, omega, pe, dx):
    """DEGOV (module docstring): P_ref - (omega - 1) through `chain`, the torque into its
    transport delay."""
    chain(P, x, k, P[k, G.PREF] - (omega - 1.0), dx)
    delayed(P, x, k, dx, WRITE, DELAY1)


@kernel(inline="always")
def delayed(P, x, k, dx, write, d1):
    """The torque of governor k through its transport delay's Pade approximant (module
    docstring; the torque itself without one), its states from slot d1 on (DEGOV's, or
    DEGOV1's after its measured power), their derivatives written into dx when write.  In
    time scaled by TD the approximant (b_0 + ... + b_n s^n)/(a_0 + ... + s^n) is z1' = z2,
    ..., zn' = -(a_0 z1 + ... + a_n-1 zn) + u in controllable canonical form, y = sum
    (b_i - b_n a_i) z_i+1 + b_n u; the states here are w = a_0 z, so that at rest w1 = u
    (b_0 = a_0) and the others 0."""
    u = x[S.torque, k]
    TD = P[k, G.TENG]
    n = pade_order(TD)
    if n == 0:
        return u
    a, b = PADE_DEN[n - 1], PADE_NUM[n - 1]
    y = b[n] * u
    for i in range(n):
        y += (b[i] - b[n] * a[i]) * x[d1 + i, k] / a[0]
    if write:
        back = 0.0
        for i in range(n):
            back += a[i] * x[d1 + i, k]
        for i in range(n - 1):
            dx[d1 + i, k] = x[d1 + i + 1, k] / TD
        dx[d1 + n - 1, k] = (a[0] * u - back) / TD
    return y


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
