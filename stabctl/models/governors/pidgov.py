"""PSS/E's PIDGOV (tg_con type 12) and WPIDHY (type 13): the hydro turbine governors
with a PID controller, the same droop, PID, gate table and water column.

P_ref - f through the permanent droop Rperm/(1 + s TREG), minus the speed deviation
omega - 1, is the PID's input e: the PI Kp + Ki/s through 1/(1 + s TA), plus the
derivative s Kd/(1 + s TA), both summed through a second 1/(1 + s TA) into the gate
servo, an integrator with its rate (that sum minus the gate)/TB limited to [VELMIN,
VELMAX] and the gate non-windup on [GMIN, GMAX].  The gate gives the turbine's power
through PSS/E's three-level table, the straight lines through (G0, 0), (G1, P1), (G2,
P2), (1, P3) (0 below G0), then the water column (1 - s Tz)/(1 + s Tz/2), Tz = ATW TW;
the mechanical power P_m = that minus DTURB (omega - 1), which stabctl's PSS/E machines
(mac_con psse_swing 1) divide by the speed, as PowerSimulationsDynamics.jl hands its
shaft P_m / omega.  The feedback f (the feedback flag): 0 the electrical power (PSS/E's
PELEC; PowerSimulationsDynamics.jl's air-gap torque, equal at rest), 1 the gate position.

At rest (rated speed) the gate is the table's inverse at Pm0, the PI's integral, both
TA lags and the gate at it, the droop lag and the derivative 0, the water column's state
3 Pm0 (`blocks.leadlag`'s, (1 - r) Pm0 with r = -2); P_ref = Pm0 (flag 0) or the gate
(flag 1), so that after a step dP of P_ref the unit settles where P_ref - f = (omega -
1)/Rperm, its droop line.  The PI's state is its output part (`blocks.pi`):
PowerSimulationsDynamics.jl's x_g2 times Ki.

TREG or Tz/2 below 1e-3 s drops its block; TA and TB must be >= 1e-3 s (``NEEDS``); the
feedback flag is 0 or 1 (its column's choices).  Refused by name (`check`): a gate table
whose gates G0 < G1 < G2 < 1 or powers 0 < P1 < P2 < P3 do not rise (its inverse gives
the start-up gate), VELMAX <= 0 or VELMIN >= 0; by the tg_con table, GMAX < GMIN and
WPIDHY's PMAX < PMIN (``LIMITS``); by `initialise`, a start-up gate outside [GMIN, GMAX].

WPIDHY (the Woodward PID hydro governor) differs in its gate: the PID's output is the
gate's velocity, not its position.  The droop REG/(1 + s TREG) on P_e - P_ref (PSS/E's
REG is negative: Rperm = -REG, a positive REG refused by name) minus omega - 1 is e;
(Kp + Ki/s + s Kd)/(1 + s TA)^2 of it, realised as PowerSimulationsDynamics.jl does
with three states (the PI Kp' + Ki/s with Kp' = Kp - TA Ki, the washout s Kd'/(1 + s
TA) with Kd' = Kd - TA Kp + TA^2 Ki, their sum through one TA lag), through 1/(1 + s
TB), limited to [VELMIN, VELMAX], is integrated into the gate, non-windup on [GATMN,
GATMX] (PowerSimulationsDynamics.jl integrates it with windup: the same within the
limits).  The gate table and the water column (1 - s TW)/(1 + s TW/2) are PIDGOV's
(ATW = 1), the column's output limited to [PMIN, PMAX], P_m = that minus D (omega -
1).  At rest the velocity is 0: every state but the gate (the table's inverse of Pm0)
and the water column's (3 Pm0) is 0 and P_ref = Pm0; `initialise` refuses a start-up
gate outside [GATMN, GATMX] and a Pm0 outside [PMIN, PMAX].

The DYR record (PSS/E Model Library PIDGOV; PowerSystems.jl's PIDGOV, PowerWorld's
PIDGOV): ICON feedback flag, then RPERM TREG KP KI KD TA TB DTURB G0 G1 P1 G2 P2 P3 GMAX
GMIN ATW TW VELMAX VELMIN; GMAX, GMIN in the shared Tmax, Tmin columns, DTURB in Dt, TW
in T4 (HYGOV's Tw), VELMAX, VELMIN in Uo, Uc, the rest in PIDGOV's own (``PARAMS``).
WPIDHY's (PSS/E Model Library WPIDHY; PowerSystems.jl's psse_dynamic_mapping.yaml):
TREG REG KP KI KD TA TB VELMX VELMN GATMX GATMN TW PMAX PMIN D G0 G1 P1 G2 P2 P3 into
the same columns (TB in Tgate, GATMX, GATMN in Tmax, Tmin, D in Dt, PMAX, PMIN in its
own Pmax, Pmin; REG as Rperm = -REG, feedback flag 0 and ATW 1 set by
`stabctl.io.dyr`'s mapper).
Sources: PSS/E Model Library PIDGOV, WPIDHY; PowerSimulationsDynamics.jl
``tg_models.jl`` (PIDGOV, WPIDHY), ``common_controls.jl`` (the gate table),
``init_tg.jl``, ``test_case58_pidgov.jl`` and ``test_case60_wpidhy.jl``.  ANDES 2.0
has neither.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.errors import refuse_initial
from stabctl.models.blocks import GAIN_OVER_T, LBND, clip, lag, leadlag, nonwindup, pi, washout
from stabctl.models.declaration import DyrModel, Limits, Param, beyond, states
from stabctl.models.governors.table import AT_LIMIT, G, own

if TYPE_CHECKING:
    from stabctl.models.governors import GovernorParams

PIDGOV, WPIDHY = 12, 13
KINDS = {PIDGOV: "PIDGOV", WPIDHY: "WPIDHY"}
#: the water time constant T_W >= 0 and WPIDHY's power limits ordered (PSS/E Model Library
#: PIDGOV, WPIDHY)
LIMITS = {
    PIDGOV: Limits("PSS/E Model Library PIDGOV", nonnegative=("Tw",)),
    WPIDHY: Limits("PSS/E Model Library WPIDHY", nonnegative=("Tw",), ordered=(("Pmax", "Pmin"),)),
}
#: the time constants that must be >= 1e-3 s (declared tg_con fields): the TA lags (the
#: derivative's among them) and the gate servo (WPIDHY: the velocity lag TB)
NEEDS: tuple[str, ...] = ("Ta", "Tgate")
#: not the family's start-up check of the order against [Tmin, Tmax]: `initialise`
#: checks the table's start-up gate, against [GMIN, GMAX]
ORDER_LIMITS = False
#: PIDGOV's own tg_con columns
PARAMS = (
    Param(
        "feedback_flag",
        "code",
        63,
        integer=True,
        choices=(0.0, 1.0),
        label="PIDGOV's feedback_flag",
        doc="PIDGOV: droop feedback: 0 the electrical power, 1 the gate position",
    ),
    Param("Rperm", "pu", 64, lo=0.0, doc="PIDGOV: permanent droop RPERM"),
    Param("Treg", "s", 65, lo=0.0, doc="PIDGOV: droop input time constant TREG"),
    Param("Kp", "pu", 66, doc="PIDGOV: proportional gain KP"),
    Param("Ki", "1/s", 67, doc="PIDGOV: integral gain KI"),
    Param("Kd", "s", 68, doc="PIDGOV: derivative gain KD"),
    Param("Ta", "s", 69, lo=0.0, doc="PIDGOV: controller time constant TA"),
    Param("Tgate", "s", 70, lo=0.0, doc="PIDGOV: gate servo time constant TB"),
    Param("G0", "pu", 71, doc="PIDGOV: gate opening at speed no load"),
    Param("G1", "pu", 72, doc="PIDGOV: intermediate gate opening G1"),
    Param("P1", "pu", 73, doc="PIDGOV: power at gate opening G1"),
    Param("G2", "pu", 74, doc="PIDGOV: intermediate gate opening G2"),
    Param("P2", "pu", 75, doc="PIDGOV: power at gate opening G2"),
    Param("P3", "pu", 76, doc="PIDGOV: power at full gate"),
    Param("Atw", "pu", 77, lo=0.0, doc="PIDGOV: factor ATW of the water time constant"),
    Param("Pmax", "pu", 78, doc="WPIDHY: maximum power PMAX"),
    Param("Pmin", "pu", 79, doc="WPIDHY: minimum power PMIN"),
)
#: the packed columns of `PARAMS`: P[k, O.KP]
O = own("PIDGOVColumns", PARAMS)
#: the gate-power table's fields, under the same names in both records and in tg_con
TABLE = ("G0", "G1", "P1", "G2", "P2", "P3")
DYR = (
    DyrModel(
        "PIDGOV",
        (
            "IFLAG",
            "RPERM",
            "TREG",
            "KP",
            "KI",
            "KD",
            "TA",
            "TB",
            "DTURB",
            *TABLE,
            "GMAX",
            "GMIN",
            "ATW",
            "TW",
            "VELMAX",
            "VELMIN",
        ),
        {
            "feedback_flag": "IFLAG",
            "Rperm": "RPERM",
            "Treg": "TREG",
            "Kp": "KP",
            "Ki": "KI",
            "Kd": "KD",
            "Ta": "TA",
            "Tgate": "TB",
            "Dt": "DTURB",
            **{f: f for f in TABLE},
            "Tmax": "GMAX",
            "Tmin": "GMIN",
            "Atw": "ATW",
            "T4": "TW",
            "Uo": "VELMAX",
            "Uc": "VELMIN",
        },
        kind=PIDGOV,
    ),
    DyrModel(
        "WPIDHY",
        (
            "TREG",
            "REG",
            "KP",
            "KI",
            "KD",
            "TA",
            "TB",
            "VELMX",
            "VELMN",
            "GATMX",
            "GATMN",
            "TW",
            "PMAX",
            "PMIN",
            "D",
            *TABLE,
        ),
        {
            "Treg": "TREG",
            "Kp": "KP",
            "Ki": "KI",
            "Kd": "KD",
            "Ta": "TA",
            "Tgate": "TB",
            "Uo": "VELMX",
            "Uc": "VELMN",
            "Tmax": "GATMX",
            "Tmin": "GATMN",
            "T4": "TW",
            "Pmax": "PMAX",
            "Pmin": "PMIN",
            "Dt": "D",
            **{f: f for f in TABLE},
        },
        kind=WPIDHY,
    ),
)

#: the states: the droop lag, the PI's integral, the PI's TA lag, the derivative's
#: (its input lagged by TA), the second TA lag, the gate, the water column's lead-lag
S = states("PIDGOVStates", ("droop", "integral", "pi_lag", "deriv", "pid_lag", "gate", "water"))
#: WPIDHY's: the droop lag, the PI's integral, the TA lag of the PID, the derivative's,
#: the TB lag (the gate's velocity), the gate, the water column's (in
#: PowerSimulationsDynamics.jl's order, x_g1..x_g7)
W = states("WPIDHYStates", ("droop", "integral", "pid_lag", "deriv", "velocity", "gate", "water"))
STATE_NAMES = {PIDGOV: S._fields, WPIDHY: W._fields}


def _tz(p: GovernorParams):
    """The water column's lead Tz = ATW TW (s)."""
    return p.Atw * p.T4


def has_state(p: GovernorParams):
    """Which slots of `S` are states: the droop lag with TREG, the water column with
    Tz/2, the others always."""
    return (p.Treg >= LBND, True, True, True, True, True, _tz(p) / 2 >= LBND)


def time_constants(p: GovernorParams):
    """The declared time constants that set a state's speed: field -> where."""
    return {"Treg": p.Treg >= LBND, "Ta": True, "Tgate": True, "T4": _tz(p) / 2 >= LBND}


def check(g, r: int) -> str | None:
    """The first PIDGOV or WPIDHY option of tg_con row r (0-based) stabctl does not model
    (module docstring), with the reason, or None (the messages name PIDGOV's DYR fields;
    WPIDHY's GATMX, GATMN, VELMX, VELMN are the same columns)."""
    gates = (g.G0[r], g.G1[r], g.G2[r], 1.0)
    powers = (0.0, g.P1[r], g.P2[r], g.P3[r])
    if not all(a < b for a, b in zip(gates, gates[1:])):
        return "fields 'G0', 'G1', 'G2': PIDGOV's gate table needs G0 < G1 < G2 < 1"
    if not all(a < b for a, b in zip(powers, powers[1:])):
        return "fields 'P1', 'P2', 'P3': PIDGOV's gate table needs 0 < P1 < P2 < P3"
    if g.Uo[r] <= 0 or g.Uc[r] >= 0:
        return "fields 'Uo', 'Uc': PIDGOV's gate velocity limits need VELMAX > 0 > VELMIN"
    return None  # GMAX below GMIN, WPIDHY's PMAX below PMIN: the tg_con table's (LIMITS)


def gate_at(p: GovernorParams, r, power):
    """The gate (pu) whose table power is `power` on rows r: the inverse of the table
    (`check` makes it rise), G0 at or below 0 power, the last line beyond P3."""
    g = np.column_stack([p.G0[r], p.G1[r], p.G2[r], np.ones(np.count_nonzero(r))])
    q = np.column_stack([np.zeros(np.count_nonzero(r)), p.P1[r], p.P2[r], p.P3[r]])
    seg = np.clip((power[:, None] > q[:, 1:3]).sum(axis=1), 0, 2)
    i = np.arange(seg.size)
    slope = (g[i, seg + 1] - g[i, seg]) / (q[i, seg + 1] - q[i, seg])
    return np.where(power <= 0, g[:, 0], g[i, seg] + slope * (power - q[i, seg]))


def initialise(p: GovernorParams, r, pmech0, order, x):
    """PIDGOV and WPIDHY at rest on rows r (module docstring): the gate at the table's
    inverse of pmech0, refused outside [GMIN, GMAX]; returns P_ref, pmech0 (flag 0,
    WPIDHY) or the gate (flag 1), on r.

    Raises CaseError when the start-up gate is outside [GMIN, GMAX] or a WPIDHY's pmech0
    outside [PMIN, PMAX]."""
    pm = pmech0[r]
    gate = np.zeros(p.n)
    gate[r] = gate_at(p, r, pm)
    refuse_initial(
        "tg_con",
        r & beyond(gate, p.Tmin, p.Tmax),
        lambda k: (
            f"tg_con row {k + 1}: PIDGOV's start-up gate {gate[k]:.4f} pu outside "
            f"[GMIN, GMAX] = [{p.Tmin[k]:.4f}, {p.Tmax[k]:.4f}]"
        ),
    )
    w = r & (p.kind == WPIDHY)
    refuse_initial(
        "tg_con",
        w & beyond(pmech0, p.Pmin, p.Pmax),
        lambda k: (
            f"tg_con row {k + 1}: WPIDHY's start-up power {pmech0[k]:.4f} pu outside "
            f"[PMIN, PMAX] = [{p.Pmin[k]:.4f}, {p.Pmax[k]:.4f}]"
        ),
    )
    pid = r & ~w
    for slot in (S.integral, S.pi_lag, S.pid_lag):
        x[slot, pid] = gate[pid]
    x[S.gate, r] = gate[r]
    x[S.water, r] = np.where(_tz(p)[r] / 2 >= LBND, 3.0 * pm, 0.0)
    return np.where(p.feedback_flag[r] == 1, gate[r], pm)


@kernel(inline="always")
def _power(P, k, gate):
    """The turbine's power at `gate`: PSS/E's three-level gate table (module docstring)."""
    g0, g1, g2 = P[k, O.G0], P[k, O.G1], P[k, O.G2]
    p1, p2, p3 = P[k, O.P1], P[k, O.P2], P[k, O.P3]
    if gate <= g0:
        return 0.0
    if gate <= g1:
        return p1 / (g1 - g0) * (gate - g0)
    if gate <= g2:
        return (p2 - p1) / (g2 - g1) * (gate - g1) + p1
    return (p3 - p2) / (1.0 - g2) * (gate - g2) + p2


@kernel(inline="always")
def _water(P, x, k):
    """The water column (1 - s Tz)/(1 + s Tz/2) on the table's power: its output, its
    state's derivative."""
    tz = P[k, O.ATW] * P[k, G.T4]
    power = _power(P, k, clip(x[S.gate, k], P[k, G.TMIN], P[k, G.TMAX]))
    return leadlag(power, x[S.water, k], -tz, tz / 2.0)


@kernel(inline="always")
def pmech(P, x, k, omega):
    """PIDGOV: the water column's output minus DTURB (omega - 1); WPIDHY: the output
    limited to [PMIN, PMAX], minus D (omega - 1) (module docstring)."""
    power = _water(P, x, k)[0]
    if P[k, G.KIND] == WPIDHY:
        power = clip(power, P[k, O.PMIN], P[k, O.PMAX])
    return power - P[k, G.DT] * (omega - 1.0)


@kernel(inline="always")
def derivatives(P, x, k, omega, pe, dx):
    """PIDGOV and WPIDHY (module docstring): the droop, the PID, the gate servo (clamps
    the gate in x) and the water column; the feedback the electrical power pe (flag 0)
    or the gate (flag 1)."""
    feedback = x[S.gate, k] if P[k, O.FEEDBACK_FLAG] == 1.0 else pe
    droop, dx[S.droop, k] = lag(
        P[k, O.RPERM] * (P[k, G.PREF] - feedback), x[S.droop, k], P[k, O.TREG]
    )
    e = droop - (omega - 1.0)
    ta = P[k, O.TA]
    if P[k, G.KIND] == WPIDHY:
        _wpidhy_gate(P, x, k, e, dx)
        dx[W.water, k] = _water(P, x, k)[1]
        return
    y_pi, dx[S.integral, k] = pi(e, x[S.integral, k], P[k, O.KP], P[k, O.KI])
    _, dx[S.pi_lag, k] = lag(y_pi, x[S.pi_lag, k], ta)
    y_d, dx[S.deriv, k] = washout(e, x[S.deriv, k], ta, P[k, O.KD], GAIN_OVER_T)
    _, dx[S.pid_lag, k] = lag(x[S.pi_lag, k] + y_d, x[S.pid_lag, k], ta)
    rate = clip((x[S.pid_lag, k] - x[S.gate, k]) / P[k, O.TGATE], P[k, G.UC], P[k, G.UO])
    x[S.gate, k], dx[S.gate, k] = nonwindup(
        x[S.gate, k], rate, P[k, G.TMIN], P[k, G.TMAX], AT_LIMIT, 0.0
    )
    dx[S.water, k] = _water(P, x, k)[1]


@kernel(inline="always")
def _wpidhy_gate(P, x, k, e, dx):
    """WPIDHY's PID on e, its velocity lag and the gate's integrator (module docstring):
    writes their derivatives into dx (clamps the gate in x)."""
    ta, kp, ki = P[k, O.TA], P[k, O.KP], P[k, O.KI]
    y_pi, dx[W.integral, k] = pi(e, x[W.integral, k], kp - ta * ki, ki)
    kd = P[k, O.KD] - ta * kp + ta * ta * ki
    y_d, dx[W.deriv, k] = washout(e, x[W.deriv, k], ta, kd, GAIN_OVER_T)
    _, dx[W.pid_lag, k] = lag(y_pi + y_d, x[W.pid_lag, k], ta)
    _, dx[W.velocity, k] = lag(x[W.pid_lag, k], x[W.velocity, k], P[k, O.TGATE])
    rate = clip(x[W.velocity, k], P[k, G.UC], P[k, G.UO])
    x[W.gate, k], dx[W.gate, k] = nonwindup(
        x[W.gate, k], rate, P[k, G.TMIN], P[k, G.TMAX], AT_LIMIT, 0.0
    )
