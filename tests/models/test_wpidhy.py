"""PSS/E's WPIDHY (stabctl.models.governors.pidgov, type 13): PSS/E's ThreeBus case with
its GENROU on SEXS and WPIDHY, imported as a user imports it, initialises to
PowerSimulationsDynamics.jl's states and its linearisation has that program's
eigenvalues (its test 60, tests/data/psse_runs/WPIDHY/README.md); after a step of P_ref
the gate integrates until P_ref - P_e = (omega - 1)/Rperm, the droop line."""

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

DATA = Path(__file__).parents[1] / "data" / "psse_runs" / "WPIDHY"
RAW, DYR = DATA / "ThreeBusMulti.raw", DATA / "ThreeBus_WPIDHY.dyr"
PSID = json.loads((DATA / "psid_test60.json").read_text())


def imported():
    """The run's case as ``stabctl import-psse RAW DYR`` builds it (constant-impedance
    loads, as the Julia test converts them)."""
    return load_psse(RAW, DYR)


@pytest.fixture(scope="module")
def sim():
    return Simulator(imported(), background_compile=False)


def test_record_fills_the_shared_and_its_own_columns(sim):
    """The DYR record (PSS/E order TREG REG KP KI KD TA TB VELMX VELMN GATMX GATMN TW
    PMAX PMIN D G0 G1 P1 G2 P2 P3, as PowerSystems.jl reads it): Rperm = -REG, the
    feedback the electrical power, ATW 1."""
    g = sim.case.governors
    assert g.type[0] == 13 and g.feedback_flag[0] == 0 and g.Atw[0] == 1
    own = [g.Treg[0], g.Rperm[0], g.Kp[0], g.Ki[0], g.Kd[0], g.Ta[0], g.Tgate[0]]
    assert own == [0.01, 0.05, 3.0, 0.5, 3.0, 0.02, 0.01]
    assert [g.Uo[0], g.Uc[0], g.Tmax[0], g.Tmin[0], g.T4[0]] == [0.025, -0.025, 1.0, 0.2, 3.25]
    assert [g.Pmax[0], g.Pmin[0], g.Dt[0]] == [52001.0, 0.0, 0.0]
    table = [g.G0[0], g.G1[0], g.P1[0], g.G2[0], g.P2[0], g.P3[0]]
    assert table == [0.12, 0.545, 0.4, 0.827, 0.83, 1.0]


def test_initial_states_are_psid_s(sim):
    """PSID's initial point: its bus voltages, its GENROU's states (E'q, E'd, psi_kd,
    psi_kq, the angle from bus 101's, the speed; stabctl's E'd and psi_kq in PST's sign)
    and its WPIDHY's x_g1..x_g7 (0 but the gate, the table's inverse of tau_m0 = 0.7,
    and the water column, 3 tau_m0), within 1e-9 (measured 3.9e-12: PSID's own
    nonlinear solve leaves 3.9e-12 on its PI, lag and velocity states, which are 0 at
    rest); P_ref the initial power.  (PSID's SEXS states, x 6-7, are another
    realisation than stabctl's.)"""
    ref = PSID["x0"]
    m = sim.model
    psid = assert_start_is_psids(sim, ref, machine=m.gp.mac[0])  # the governor's, bus 102
    xg = m.layout.view(m.x0, "tg")[:, 0]
    np.testing.assert_allclose(xg[: len(gov.pidgov.W)], psid[8:], rtol=0, atol=1e-9)
    assert m.Pref[0] == pytest.approx(psid[14] / 3, abs=1e-9)  # x_g7 = 3 tau_m0


def test_eigenvalues_are_psid_s(sim):
    """The whole spectrum of PSID's linearisation (GENROU, SEXS, WPIDHY and the infinite
    bus, loads at constant impedance: 15 eigenvalues) is stabctl's, each within 1e-6
    1/s (measured 1.8e-8: stabctl's central differences err by O(h^2); PSID's values are
    its automatic differentiation's)."""
    psid = np.array([complex(*v) for v in PSID["eigvals"]])
    lam = np.linalg.eigvals(np.asarray(linearise(sim).A))
    assert lam.size == psid.size == 15
    for z in psid:
        assert np.min(np.abs(lam - z)) < 1e-6, (z, lam[np.argmin(np.abs(lam - z))])


# -- closed forms: the governor alone, its machine's electrical power at the governor's
# -- mechanical power (a machine at rest)

PM0 = 0.7  # on the table's second line: gate 0.545 + 0.3 (0.827 - 0.545)/0.43
RPERM = 0.05
#: the time the closed-form tests let the governor settle (s)
T_SETTLE = 600.0


def _row():
    """The WPIDHY tg_con row of PSS/E's run."""
    g = imported().governors
    return [float(getattr(g, name)[0]) for name in g.columns()]


def test_initial_point_is_an_equilibrium():
    """At rest the gate is the table's inverse of Pm0 and every derivative is 0."""
    p, x, Pref = started(_row(), PM0)
    P = p.packed(Pref)
    dx = np.full_like(x, np.nan)
    gov.derivatives(P, x, 0, 1.0, gov.pmech(P, x, 0, 1.0), dx)
    assert gov.pmech(P, x, 0, 1.0) == pytest.approx(PM0, abs=1e-15)
    assert x[gov.pidgov.W.gate, 0] == pytest.approx(0.545 + 0.3 * 0.282 / 0.43, abs=1e-15)
    assert np.abs(dx).max() < 1e-14


def test_pref_step_settles_with_the_power_raised_by_the_step():
    """At rated speed the gate's integrator stops only where the droop's input is 0: a
    step dP of P_ref raises the power by dP."""
    p, x, Pref = started(_row(), PM0)
    dP = 0.002
    P = p.packed(Pref + dP)
    x = settled(P, x, 1.0, T_SETTLE)
    assert gov.pmech(P, x, 0, 1.0) == pytest.approx(PM0 + dP, rel=1e-8)


def test_speed_held_off_rated_settles_on_the_droop_line():
    """The speed held d above rated: Rperm (P_ref - P_e) = d, the power falls by
    d / Rperm."""
    p, x, Pref = started(_row(), PM0)
    d = 1e-3
    P = p.packed(Pref)
    x = settled(P, x, 1.0 + d, T_SETTLE)
    assert gov.pmech(P, x, 0, 1.0 + d) == pytest.approx(PM0 - d / RPERM, rel=1e-8)


def test_options_it_does_not_model_are_refused():
    """PMAX below PMIN, a start-up power beyond PMAX, a start-up gate below GATMN (the
    PIDGOV checks of the shared columns apply as well: test_pidgov.py)."""
    row = _row()
    for changes, match in (
        ({"Pmax": -1.0}, r"field 'Pmax': must be >= Pmin = 0 \(governor type 13, WPIDHY"),
        ({"Pmax": 0.6}, "WPIDHY's start-up power 0.7000 pu outside"),
        ({"Tmin": 0.8}, "start-up gate 0.7417 pu outside"),
        ({"Uc": 0.01}, r"field 'Uc': must be <= 0, got 0.01"),
    ):
        changed = list(row)
        for name, value in changes.items():
            changed[gov.GOVERNOR.col(name) - 1] = value
        with pytest.raises(CaseError, match=match):
            started(changed, PM0)


def test_a_positive_reg_is_refused_by_name(tmp_path):
    """PSS/E's REG is the gain on P_e - P_ref, negative for a droop: a positive one is
    refused, naming the record and the field."""
    text = DYR.read_text().replace("-0.50000E-01", "0.50000E-01")
    bad = tmp_path / "ThreeBus_WPIDHY.dyr"
    bad.write_text(text)
    with pytest.raises(
        CaseError, match=r"ThreeBus_WPIDHY.dyr:\d+ WPIDHY .*REG = 0.05 must be <= 0"
    ):
        load_psse(RAW, bad)
