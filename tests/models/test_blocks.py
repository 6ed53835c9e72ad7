"""The control blocks (stabctl.models.blocks) against their closed forms: the step
responses of a lag, a lead-lag and a washout, and the non-windup limiter's rules (IEEE
Std 421.5-2016 annex E.5 and PSTess's)."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from stabctl.models import blocks as b


def step_response(block, x0, t, *args):
    """Output of a one-state block at time t (s) after its input steps from 0 to 1 at
    t = 0 with the state x0 at rest."""
    sol = solve_ivp(lambda _, x: [block(1.0, x[0], *args)[1]], (0, t), [x0], rtol=1e-12, atol=1e-14)
    return block(1.0, sol.y[0, -1], *args)[0]


def test_lag_step_response_is_one_minus_exp():
    """1/(1 + s T): y(T) = 1 - e^-1 (IEEE 421.5 E.2)."""
    T = 0.3
    assert step_response(b.lag, 0.0, T, T) == pytest.approx(1 - np.exp(-1), rel=1e-6)


def test_a_lag_below_the_threshold_is_absent():
    assert b.lag(0.7, 5.0, 0.999e-3) == (0.7, 0.0)
    assert b.leadlag(0.7, 5.0, 1.0, 0.5e-3, 2.0) == (1.4, 0.0)
    assert b.leadlag_input_state(0.7, 5.0, 3.0, 0.0) == (0.7, 0.0)


@pytest.mark.parametrize(
    "block, x_rest, ratio", [(b.leadlag, 0.0, 4.0), (b.leadlag_input_state, 0.0, 4.0)]
)
def test_leadlag_jumps_by_tlead_over_tlag_then_settles(block, x_rest, ratio):
    """(1 + s T_lead)/(1 + s T_lag) after a unit step: y(0+) = T_lead/T_lag, y(t) = 1 -
    (1 - T_lead/T_lag) e^(-t/T_lag) (IEEE 421.5 E.3), in both realisations."""
    T_lead, T_lag = 2.0, 0.5
    args = (T_lead, T_lag) if block is b.leadlag else (T_lead / T_lag, T_lag)
    assert block(1.0, x_rest, *args)[0] == ratio
    t = 0.7
    assert step_response(block, x_rest, t, *args) == pytest.approx(
        1 - (1 - ratio) * np.exp(-t / T_lag), rel=1e-8
    )


def test_second_order_leadlag_step_response_is_its_two_exponentials():
    """(1 + s T_3)/(1 + s T_1 + s^2 T_1 T_2) = (1 + s T_3)/((1 + s a)(1 + s b)), a + b =
    T_1, a b = T_1 T_2: after a unit step y(t) = 1 - (a - T_3)/(a - b) e^(-t/a) - (b -
    T_3)/(b - a) e^(-t/b) (partial fractions); A2 = 0 is the first-order lead-lag; A1 below
    the threshold passes the input."""
    T1, T2, T3, t = 0.5, 0.1, 0.2, 0.3
    a, bb = (T1 + np.sqrt(T1 * T1 - 4 * T1 * T2)) / 2, (T1 - np.sqrt(T1 * T1 - 4 * T1 * T2)) / 2
    sol = solve_ivp(
        lambda _, x: b.leadlag2(1.0, x[0], x[1], T3, T1, T1 * T2)[1:],
        (0, t),
        [0.0, 0.0],
        rtol=1e-12,
        atol=1e-14,
    )
    y = b.leadlag2(1.0, sol.y[0, -1], sol.y[1, -1], T3, T1, T1 * T2)[0]
    exact = 1 - (a - T3) / (a - bb) * np.exp(-t / a) - (bb - T3) / (bb - a) * np.exp(-t / bb)
    assert y == pytest.approx(exact, rel=1e-8)
    assert b.leadlag2(0.7, 0.2, 9.0, 2.0, 0.5, 0.0) == (
        *b.leadlag_input_state(0.7, 0.2, 4.0, 0.5),
        0.0,
    )
    assert b.leadlag2(0.7, 0.2, 9.0, 2.0, 0.5e-3, 0.0) == (0.7, 0.0, 0.0)


def test_leadlag_gain_multiplies_the_response_and_one_is_exact():
    """K (1 + s T_lead)/(1 + s T_lag): K times the plain response; K = 1 bit for bit."""
    u, x = 0.123456789, -0.0987654321
    y, d = b.leadlag(u, x, 0.3, 0.7)
    assert b.leadlag(u, x, 0.3, 0.7, 1.0) == (y, d)
    yK, dK = b.leadlag(u, x, 0.3, 0.7, 2.5)
    assert yK == pytest.approx(0.3 / 0.7 * 2.5 * u + x, rel=1e-15)
    assert dK == pytest.approx(((1 - 0.3 / 0.7) * 2.5 * u - x) / 0.7, rel=1e-14)


@pytest.mark.parametrize("form", [b.GAIN_AFTER, b.GAIN_BEFORE, b.GAIN_OVER_T])
def test_washout_step_response_is_exp(form):
    """K s/(1 + s T) (K the output gain on the state derivative): after a unit step
    y(t) = (K/T) e^(-t/T) (IEEE 421.5 E.4), each gain spelling to rounding."""
    K, T, t = 3.0, 0.4, 0.25
    assert step_response(b.washout, 0.0, t, T, K, form) == pytest.approx(
        K / T * np.exp(-t / T), rel=1e-8
    )
    assert b.washout(2.0, 2.0, T, K, form) == (0.0, 0.0)  # at rest: no output


def test_clip_is_a_windup_limit():
    assert [b.clip(v, -1.0, 2.0) for v in (-3.0, 0.5, 9.0)] == [-1.0, 0.5, 2.0]


@pytest.mark.parametrize("ieee", [True, False])
def test_nonwindup_state_stays_at_its_limit_while_driven_outward(ieee):
    """IEEE 421.5 E.5: beyond its limit and driven outward, the state is clamped to it
    with a zero derivative (both rules); driven inward it keeps its derivative."""
    assert b.nonwindup(2.5, 4.0, -1.0, 2.0, ieee, 0.0) == (2.0, 0.0)
    assert b.nonwindup(-1.5, -4.0, -1.0, 2.0, ieee, 0.0) == (-1.0, 0.0)
    assert b.nonwindup(2.0, -4.0, -1.0, 2.0, ieee, 0.0) == (2.0, -4.0)
    assert b.nonwindup(-1.0, 4.0, -1.0, 2.0, ieee, 0.0) == (-1.0, 4.0)
    assert b.nonwindup(0.5, 4.0, -1.0, 2.0, ieee, 0.0) == (0.5, 4.0)


def test_nonwindup_at_the_limit_ieee_holds_pstess_does_not():
    """At (not beyond) the limit and driven outward: IEEE 421.5 E.5 holds the state
    (derivative 0); PSTess (exc_st3, exc_dc12) only acts beyond it."""
    assert b.nonwindup(2.0, 4.0, -1.0, 2.0, True, 0.0) == (2.0, 0.0)
    assert b.nonwindup(2.0, 4.0, -1.0, 2.0, False, 0.0) == (2.0, 4.0)


def test_nonwindup_reach_holds_a_state_it_would_reach_within_it():
    """ieee with reach r: a state within r d of the limit is set on it, derivative 0."""
    assert b.nonwindup(1.99, 4.0, -1.0, 2.0, True, 0.01) == (2.0, 0.0)
    assert b.nonwindup(1.9, 4.0, -1.0, 2.0, True, 0.01) == (1.9, 4.0)


def test_nonwindup_lag_against_windup_lag():
    """A lag limited at hi = 1 driven by u = 3 for 1 s, then u = 0: the non-windup state
    leaves the limit at once, y(t) = e^(-t/T) after the reversal; the windup lag's
    unlimited state (3 - 3 e^(-1/T) at the reversal, clipped only at the output) decays
    from there, its output held at the limit for T ln(x_rev) s (IEEE 421.5 E.5 against E.7)."""
    T, lo, hi = 0.5, -9.0, 1.0

    def run(u, x0, t, nonwindup):
        def f(_, x):
            return [
                b.nonwindup_lag(u, x[0], T, lo, hi, True, 0.0)[1]
                if nonwindup
                else b.lag(u, x[0], T)[1]
            ]

        return solve_ivp(f, (0, t), [x0], rtol=1e-12, atol=1e-14).y[0, -1]

    x_nw = run(3.0, 0.0, 1.0, True)
    x_w = run(3.0, 0.0, 1.0, False)
    assert x_nw == pytest.approx(hi, rel=1e-6)
    assert x_w == pytest.approx(3 - 3 * np.exp(-1 / T), rel=1e-9)
    t = 0.2
    assert run(0.0, x_nw, t, True) == pytest.approx(np.exp(-t / T), rel=1e-6)
    x_w_t = run(0.0, x_w, t, False)
    assert x_w_t == pytest.approx(x_w * np.exp(-t / T), rel=1e-8) and b.clip(x_w_t, lo, hi) == hi


def test_rectifier_loading_segments_and_continuity():
    """F_EX(I_N) of IEEE 421.5 annex D: its four segments, continuous to the rounding of
    the standard's coefficients at 0.433, 0.75 and 1."""
    f = b.rectifier_loading
    assert f(-0.1) == f(0.0) == 1.0
    assert f(0.2) == pytest.approx(1 - 0.577 * 0.2, rel=1e-15)
    assert f(0.6) == pytest.approx(np.sqrt(0.75 - 0.36), rel=1e-15)
    assert f(0.9) == pytest.approx(1.732 * 0.1, rel=1e-14)
    assert f(1.2) == 0.0
    for edge in (0.433, 0.75, 1.0):
        assert abs(f(edge - 1e-12) - f(edge + 1e-12)) < 3e-4


def test_anti_windup_resets_at_a_limit_with_an_outward_or_zero_rate():
    """ANDES 2.0 AntiWindup: at or beyond a limit with a rate outward or 0, the state is
    set to the limit and stopped; driven back inside it is left where it is (no clamp,
    unlike IEEE 421.5 E.5's `nonwindup`)."""
    assert b.anti_windup(2.5, 4.0, -1.0, 2.0) == (2.0, 0.0)
    assert b.anti_windup(2.0, 0.0, -1.0, 2.0) == (2.0, 0.0)
    assert b.anti_windup(-1.5, -4.0, -1.0, 2.0) == (-1.0, 0.0)
    assert b.anti_windup(2.5, -4.0, -1.0, 2.0) == (2.5, -4.0)
    assert b.anti_windup(0.5, 4.0, -1.0, 2.0) == (0.5, 4.0)


def test_pi_ramps_at_its_integral_gain():
    """K_P + K_I/s after a unit step from rest: y(t) = K_P + K_I t (ANDES PIController)."""
    KP, KI, t = 0.7, 3.0, 0.4
    assert step_response(b.pi, 0.0, t, KP, KI) == pytest.approx(KP + KI * t, rel=1e-9)


def test_pi_aw_hard_limit_holds_its_integrator_at_the_limit():
    """ANDES PIAWHardLimit, unit step from rest, limits [-1, 2]: the integrator ramps at
    K_I until it reaches 2 at t = 2/K_I and stays there (reset, derivative 0); the output
    K_P + K_I t clipped to 2 meanwhile; after the input reverses the integrator leaves
    the limit at once (no windup), y(t) = K_P u + 2 + K_I u t."""
    KP, KI, lo, hi = 0.5, 4.0, -1.0, 2.0
    y, x, d = b.pi_aw_hard_limit(1.0, 0.3, KP, KI, lo, hi)
    assert (y, x, d) == (pytest.approx(KP + 0.3), 0.3, KI)
    assert b.pi_aw_hard_limit(1.0, 1.8, KP, KI, lo, hi)[0] == hi  # output clipped
    assert b.pi_aw_hard_limit(1.0, 2.3, KP, KI, lo, hi)[1:] == (hi, 0.0)
    y, x, d = b.pi_aw_hard_limit(-1.0, hi, KP, KI, lo, hi)
    assert (y, x, d) == (pytest.approx(hi - KP), hi, -KI)


def test_pi_track_aw_settles_where_the_tracking_balances_the_input():
    """ANDES PITrackAW with a constant input u beyond the limit hi: at rest u = ks (ys -
    hi), so the integral settles at x = hi + u/ks - K_P u (closed form of dx/dt = 0)."""
    u, KP, KI, lo, hi, ks = 0.5, 2.0, 3.0, -1.0, 1.0, 2.0
    x_rest = hi + u / ks - KP * u
    y, d = b.pi_track_aw(u, x_rest, KP, KI, lo, hi, ks)
    assert y == hi and d == pytest.approx(0.0, abs=1e-15)


def test_pi_track_aw_freeze_holds_its_output_and_stops_its_integrator():
    """ANDES PITrackAWFreeze: frozen, the output is the held value and dx/dt = 0;
    unfrozen, PITrackAW."""
    args = (2.0, 3.0, -1.0, 1.0, 2.0)
    assert b.pi_track_aw_freeze(0.2, 0.1, 0.77, *args, True) == (0.77, 0.0)
    assert b.pi_track_aw_freeze(0.2, 0.1, 0.77, *args, False) == b.pi_track_aw(0.2, 0.1, *args)
