"""PSS/E's DEGOV1 (stabctl.models.governors.degov1): PSS/E's ThreeBus case with its
GENROU on DEGOV1 (both droop flags), imported as a user imports it, initialises to
PowerSimulationsDynamics.jl's states and its linearisation has that program's
eigenvalues (its test 63, tests/data/psse_runs/DEGOV1/README.md); the droop's steady
state after a step of P_ref is the closed form P_ref - (omega - 1) = R f."""

import json
from pathlib import Path

import numpy as np
import pytest
from governor_alone import settled, started
from psid import assert_start_is_psids

from stabctl.dynamics.driver import Simulator
from stabctl.errors import CaseError
from stabctl.io.psse import load_psse
from stabctl.models import governors as gov
from stabctl.smallsignal.linearise import linearise

DATA = Path(__file__).parents[1] / "data" / "psse_runs" / "DEGOV1"
PSID = json.loads((DATA / "psid_test63.json").read_text())
FLAGS = (0, 1)


def imported(flag):
    """The run's case as ``stabctl import-psse RAW DYR`` builds it (constant-impedance
    loads, as the Julia test converts them)."""
    return load_psse(DATA / "ThreeBusMulti.raw", DATA / f"ThreeBus_DEGOV1_nodelay_flag{flag}.dyr")


@pytest.fixture(scope="module", params=FLAGS, ids=lambda f: f"flag{f}")
def run(request):
    flag = request.param
    sim = Simulator(imported(flag), background_compile=False)
    return flag, sim


def test_record_fills_the_shared_and_its_own_columns(run):
    """The DYR record: M, T1 .. TMIN in DEGOV's columns, DROOP and TE in DEGOV1's own."""
    flag, sim = run
    g = sim.case.governors
    assert g.type[0] == 11 and g.droop_flag[0] == flag
    got = [g.Tc[0], g.Ts[0], g.T3[0], g.invR[0], g.T4[0], g.T5[0], g.T6[0], g.Teng[0]]
    assert got == [0.1905, 0.0476, 0.018, 1.0, 5.1, 0.322, 0.0, 0.0]
    assert (g.Tmax[0], g.Tmin[0], g.droop[0], g.Te[0]) == (99.99, -99.99, 0.07, 0.05)


def test_initial_states_are_psid_s(run):
    """PSID's initial point: its bus voltages, its GENROU's states (E'q, E'd, psi_kd,
    psi_kq, the angle from bus 101's, the speed; stabctl's E'd and psi_kq in PST's sign)
    and its DEGOV1's (control box and actuator 0; the torque and, flag 1, the measured
    power at tau_m0), within 1e-9 (measured 4.2e-12: the power flow's round-off); P_ref
    = R tau_m0 (its init_tg.jl)."""
    flag, sim = run
    ref = PSID[f"x0_flag{flag}"]
    m = sim.model
    psid = assert_start_is_psids(sim, ref, machine=m.gp.mac[0])  # the governor's, bus 102
    S = gov.degov1.S
    # PSID's x_g1..x_g5: the control box's two, the actuator's two, the torque; flag 1
    # x_g6: the measured power
    slots = (S.ecb1, S.ecb2, S.act1, S.act2, S.torque, S.pelec)[: psid.size - 6]
    xg = m.layout.view(m.x0, "tg")[:, 0]
    np.testing.assert_allclose(xg[list(slots)], psid[6:], rtol=0, atol=1e-9)
    assert m.Pref[0] == pytest.approx(0.07 * psid[10], abs=1e-9)


def test_eigenvalues_are_psid_s(run):
    """The whole spectrum of PSID's linearisation (GENROU, DEGOV1 and the infinite bus,
    loads at constant impedance; flag 0: 10 eigenvalues, T6 = 0 leaving the actuator one
    state; flag 1: 11) is stabctl's, each within 1e-6 1/s: stabctl's central
    differences (relative step 1e-4) err by O(h^2), measured 4.7e-8 at most (PSID's
    values are its automatic differentiation's, to double precision)."""
    flag, sim = run
    psid = np.array([complex(*v) for v in PSID[f"eigvals_flag{flag}"]])
    lam = np.linalg.eigvals(np.asarray(linearise(sim).A))
    assert lam.size == psid.size
    for z in psid:
        assert np.min(np.abs(lam - z)) < 1e-6, (z, lam[np.argmin(np.abs(lam - z))])


# -- closed forms of the droop: the governor alone at rated speed, its machine's
# -- electrical power at the governor's mechanical power (a machine at rest)

PM0 = 0.7


def _row(flag):
    """A DEGOV1 tg_con row: PSS/E's run's values, droop flag `flag`."""
    g = imported(flag).governors
    return [float(getattr(g, name)[0]) for name in g.columns()]


#: the time the closed-form tests let the governor settle (s)
T_SETTLE = 400.0


@pytest.mark.parametrize("flag", FLAGS)
def test_initial_point_is_an_equilibrium(flag):
    p, x, Pref = started(_row(flag), PM0)
    P = p.packed(Pref)
    dx = np.full_like(x, np.nan)
    gov.derivatives(P, x, 0, 1.0, gov.pmech(P, x, 0, 1.0), dx)
    assert gov.pmech(P, x, 0, 1.0) == PM0
    assert np.abs(dx).max() < 1e-14
    assert Pref[0] == pytest.approx(0.07 * PM0, rel=1e-15)


@pytest.mark.parametrize("flag", FLAGS)
def test_pref_step_settles_on_the_droop_line(flag):
    """At rated speed a step dP of P_ref settles where P_ref + dP = R f, f the torque
    (flag 0) or the electrical power, here the mechanical (flag 1): the torque rises by
    dP / R."""
    p, x, Pref = started(_row(flag), PM0)
    dP, R = 0.002, 0.07
    x = settled(p.packed(Pref + dP), x, 1.0, T_SETTLE)
    assert x[gov.degov1.S.torque, 0] == pytest.approx(PM0 + dP / R, rel=1e-8)


def test_speed_held_off_rated_settles_on_the_droop_line():
    """Flag 0, the speed held d above rated: the torque falls by d / R."""
    p, x, Pref = started(_row(0), PM0)
    d, R = 1e-3, 0.07
    x = settled(p.packed(Pref), x, 1.0 + d, T_SETTLE)
    assert x[gov.degov1.S.torque, 0] == pytest.approx(PM0 - d / R, rel=1e-8)


@pytest.mark.parametrize("flag", [0, 1])
def test_transport_delay_holds_the_droop_line_and_delays_the_torque(flag):
    """DEGOV1 with the engine delay TD = 0.5 s (DEGOV's Pade approximant, order 6, its
    states after the measured power): at rest every state is still and P_m is the
    torque; the speed held 1e-3 above rated settles the torque on the droop line as
    without the delay (flag 0 feeds the torque back before the delay), and P_m follows the
    torque."""
    row = _row(flag)
    row[gov.GOVERNOR.col("Teng") - 1] = 0.5
    p, x, Pref = started(row, PM0)
    P = p.packed(Pref)
    state = [k for k, on in enumerate(p.has_state()[:, 0]) if on]
    assert len(state) == len(_states(_row(flag))) + 6
    dx = np.zeros_like(x)
    gov.derivatives(P, x, 0, 1.0, PM0, dx)
    assert np.max(np.abs(dx[state])) < 1e-12
    assert gov.pmech(P, x, 0, 1.0) == pytest.approx(PM0, rel=1e-12)
    if flag == 0:
        d, R = 1e-3, 0.07
        x = settled(P, x, 1.0 + d, T_SETTLE)
        assert x[gov.degov1.S.torque, 0] == pytest.approx(PM0 - d / R, rel=1e-8)
        assert gov.pmech(P, x, 0, 1.0) == pytest.approx(PM0 - d / R, rel=1e-8)


def _states(row):
    p, _, _ = started(row, PM0)
    return [k for k, on in enumerate(p.has_state()[:, 0]) if on]


def test_options_it_does_not_model_are_refused():
    """A lead without its lag, TMAX below TMIN, a droop flag other than 0 or 1 (the
    engine delay TD is modelled, as DEGOV's)."""
    row = _row(0)
    for name, value, match in (
        ("Tmin", 100.0, "field 'Tmax': must be >= Tmin = 100"),
        ("droop_flag", 2.0, "droop_flag must be 0 or 1"),
    ):
        changed = list(row)
        changed[gov.GOVERNOR.col(name) - 1] = value
        with pytest.raises(CaseError, match=match):
            started(changed, PM0)
