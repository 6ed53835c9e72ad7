"""Model conventions (docs/conventions.md): the IEEE Std 421.5 non-windup limiter of the
ieee conventions against PSTess's smpexc quirk, the grid and event semantics each one
uses, and the numerical-health check that turns a too-large step into an error."""

import numpy as np
import pytest
from click.testing import CliRunner

from stabctl.cli import main
from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.events import fault_with_clearing
from stabctl.dynamics.grid import time_grid
from stabctl.errors import InputError, NumericalInstabilityError
from stabctl.io import load_case
from stabctl.models import exciters as exc


@pytest.fixture(scope="module")
def models():
    case = load_case("kundur")
    return {c: Simulator(case, conventions=c).model for c in ("ieee", "pstess")}


def smpexc_at_ceiling(model, error_pu):
    """Exciter 1's states at its ceiling (Efd = Vrmax = 5 pu) with a voltage error of
    error_pu (Vref - V_TR, no PSS): derivatives and the state after flag 2."""
    P = model.params.EP.copy()
    x = np.zeros((model.layout.exc_rows, P.shape[0]))
    x[0] = 1.0  # V_TR
    P[:, exc.E.VREF] = 1.0 + error_pu
    x[2] = P[:, exc.E.VRMAX]  # Efd at its ceiling
    dx = np.zeros_like(x)
    ieee = model.params.ieee
    vex = exc.field_voltage_at(P, x, 0, 1.0, 0.0, 1.0, 0.0, ieee)
    exc.derivatives(P, x, 0, 1.0, 1.0, 0.0, vex, 0.0, 1.0, dx, ieee, 0.0)
    return dx[2, 0], x[2, 0], P[0, exc.E.VRMAX]


def test_ieee_limiter_holds_the_state_at_the_ceiling(models):
    """IEEE 421.5 non-windup: driven outward (K_A V_A = 200 x 0.1 = 20 pu > 5 pu) the state
    stays at the limit with a zero derivative; PSTess keeps the derivative (the misspelt
    dEFD, docs/pst_models.md 2.1): (20 - 5) / T_A = 300 pu/s."""
    d, x, hi = smpexc_at_ceiling(models["ieee"], 0.1)
    assert d == 0.0 and x == hi == 5.0
    d, x, _ = smpexc_at_ceiling(models["pstess"], 0.1)
    assert d == pytest.approx((200 * 0.1 - 5.0) / 0.05)


def test_ieee_limiter_leaves_the_ceiling_when_the_input_reverses(models):
    d, _x, _ = smpexc_at_ceiling(models["ieee"], -0.01)  # K_A V_A = -2 pu < 5 pu
    assert d == pytest.approx((200 * -0.01 - 5.0) / 0.05) and d < 0


def test_machine_sees_the_clipped_field_voltage_under_ieee(models):
    """A state beyond its limit (a corrector overshoot) is handed to the machine clipped
    under ieee, as it is under PSTess (which hands it over unclipped)."""
    for conv, want in (("ieee", 5.0), ("pstess", 7.0)):
        m = models[conv]
        x = np.zeros((m.layout.exc_rows, m.params.EP.shape[0]))
        x[2] = 7.0
        assert exc.field_voltage_at(m.params.EP, x, 0, 1.0, 0.0, 1.0, 0.0, m.params.ieee) == want


def test_grids_of_the_two_conventions():
    """pstess: fix(length/h) steps per interval (Kundur's 50 ms fault interval at 10 ms in
    4 steps of 12.5 ms, as PSTess); ieee: ceil(length/h), never a step above h."""
    pst = time_grid([0.0, 0.1, 0.15], 0.2, 0.01, pstess=True)
    assert pst.h[1] == pytest.approx(0.0125)
    ieee = time_grid([0.0, 0.1, 0.15], 0.2, 0.01)
    assert np.all(ieee.h <= 0.01 + 1e-15) and ieee.h[1] == pytest.approx(0.01)
    odd = time_grid([0.0, 1.0], 1.0 + 1 / 60 * 7, 0.005)  # 7 cycles at 5 ms
    assert odd.h[1] <= 0.005 and np.diff(odd.t).max() <= 0.005 + 1e-15


def test_unknown_conventions_is_an_input_error():
    with pytest.raises(InputError, match="conventions must be one of ieee, pstess"):
        Simulator(load_case("kundur"), conventions="psse")


@pytest.mark.parametrize("conventions", ["ieee", "pstess"])
def test_too_large_a_step_is_an_error_not_a_verdict(conventions):
    """h = 0.0199 s (h/T_R = 1.99): PSTess's integrator reported a loss of synchronism at
    4.7 s with speeds of 0.04-0.08 pu, and 0.019 s 'stable' with the field voltage stuck
    at its ceiling; both are numerical failures naming the time and the state."""
    sim = Simulator(load_case("kundur"), conventions=conventions)
    for h in (0.0199, 0.019):
        with pytest.raises(
            NumericalInstabilityError,
            match=r"numerical instability in the step ending at t = .* s: "
            r"state (exc|mac)\..*use a smaller step",
        ) as info:
            sim.run([fault_with_clearing(sim.case, 3, 101, 1.0, 5)], t_end=9.0, h=h)
        assert info.value.result.t[-1] < 9.0


@pytest.mark.parametrize(
    "conventions, h", [("ieee", 0.005), ("ieee", 0.01), ("pstess", 0.01), ("pstess", 0.005)]
)
def test_health_check_is_silent_on_healthy_runs(conventions, h):
    """Stable (5 cycles) and unstable (21 cycles) Case-1 runs at usual steps, 9 s."""
    sim = Simulator(load_case("kundur"), conventions=conventions)
    for cycles, stable in ((5, True), (21, False)):
        res = sim.run([fault_with_clearing(sim.case, 3, 101, 1.0, cycles)], t_end=9.0, h=h)
        assert res.stable is stable and res.meta["conventions"] == conventions


def test_cli_reports_numerical_instability_with_exit_2():
    res = CliRunner().invoke(
        main,
        [
            "simulate",
            "kundur",
            "--fault",
            "3",
            "--far-bus",
            "101",
            "--clear-cycles",
            "5",
            "--step",
            "0.0199",
            "--tf",
            "9",
        ],
    )
    assert res.exit_code == 2, res.output
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ")
    assert "numerical instability" in lines[0] and "smaller step" in lines[0]
