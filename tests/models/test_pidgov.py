"""PSS/E's PIDGOV (stabctl.models.governors.pidgov): PSS/E's ThreeBus case with its
GENROU on SEXS and PIDGOV (both feedback flags), imported as a user imports it,
initialises to PowerSimulationsDynamics.jl's states and its linearisation has that
program's eigenvalues (its test 58, tests/data/psse_runs/PIDGOV/README.md); the droop's
steady state after a step of P_ref is the closed form P_ref - f = (omega - 1)/Rperm."""

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

DATA = Path(__file__).parents[1] / "data" / "psse_runs" / "PIDGOV"
PSID = json.loads((DATA / "psid_test58.json").read_text())
#: the feedback flag -> PSID's run: 0 the electrical power, 1 the gate position
RUNS = {0: "PowerFlag", 1: "GateFlag"}


def imported(flag):
    """The run's case as ``stabctl import-psse RAW DYR`` builds it (constant-impedance
    loads, as the Julia test converts them)."""
    return load_psse(DATA / "ThreeBusMulti.raw", DATA / f"ThreeBus_PIDGOV_{RUNS[flag]}.dyr")


@pytest.fixture(scope="module", params=tuple(RUNS), ids=lambda f: f"flag{f}")
def run(request):
    flag = request.param
    sim = Simulator(imported(flag), background_compile=False)
    return flag, sim


def test_record_fills_the_shared_and_its_own_columns(run):
    """The DYR record: GMAX, GMIN, DTURB, TW, VELMAX, VELMIN in shared columns, the rest
    in PIDGOV's own."""
    flag, sim = run
    g = sim.case.governors
    assert g.type[0] == 12 and g.feedback_flag[0] == flag
    own = [g.Rperm[0], g.Treg[0], g.Kp[0], g.Ki[0], g.Kd[0], g.Ta[0], g.Tgate[0]]
    assert own == [0.05, 0.01, 5.0, 1.0, 0.1, 0.5, 0.99]
    table = [g.G0[0], g.G1[0], g.P1[0], g.G2[0], g.P2[0], g.P3[0]]
    assert table == [0.1, 0.7, 0.3, 0.9, 0.5, 0.9]
    shared = [g.Dt[0], g.Tmax[0], g.Tmin[0], g.Atw[0], g.T4[0], g.Uo[0], g.Uc[0]]
    assert shared == [0.001, 1.0, 0.05, 1.0, 0.6, 0.04, -0.04]


def test_initial_states_are_psid_s(run):
    """PSID's initial point: its bus voltages, its GENROU's states (E'q, E'd, psi_kd,
    psi_kq, the angle from bus 101's, the speed; stabctl's E'd and psi_kq in PST's sign)
    and its PIDGOV's x_g1..x_g7 (droop lag and derivative 0, the PI's integral -- PSID's
    x_g2 times Ki, here 1 --, both TA lags and the gate at the table's inverse of tau_m0,
    the water column 3 tau_m0), within 1e-9 (measured 7.1e-13: the power flow's
    round-off); P_ref the initial power (flag 0) or gate (flag 1), its init_tg.jl's
    solution.  (PSID's SEXS states, x 6-7, are another realisation than stabctl's.)"""
    flag, sim = run
    ref = PSID[f"x0_flag{flag}"]
    m = sim.model
    psid = assert_start_is_psids(sim, ref, machine=m.gp.mac[0])  # the governor's, bus 102
    xg = m.layout.view(m.x0, "tg")[:, 0]
    np.testing.assert_allclose(xg[: len(gov.pidgov.S)], psid[8:], rtol=0, atol=1e-9)
    tau_m0, gate0 = psid[14] / 3, psid[13]  # x_g7 = 3 tau_m0, x_g6 the gate
    assert m.Pref[0] == pytest.approx(gate0 if flag else tau_m0, abs=1e-9)


def test_eigenvalues_are_psid_s(run):
    """The whole spectrum of PSID's linearisation (GENROU, SEXS, PIDGOV and the infinite
    bus, loads at constant impedance: 15 eigenvalues) is stabctl's, each within 1e-6
    1/s: stabctl's central differences (relative step 1e-4) err by O(h^2), measured
    7.4e-9 at most (PSID's values are its automatic differentiation's, to double
    precision)."""
    flag, sim = run
    psid = np.array([complex(*v) for v in PSID[f"eigvals_flag{flag}"]])
    lam = np.linalg.eigvals(np.asarray(linearise(sim).A))
    assert lam.size == psid.size == 15
    for z in psid:
        assert np.min(np.abs(lam - z)) < 1e-6, (z, lam[np.argmin(np.abs(lam - z))])


# -- closed forms of the droop: the governor alone, its machine's electrical power at
# -- the governor's mechanical power (a machine at rest)

PM0 = 0.7  # on the table's last line: gate 0.95, slope (P3 - P2)/(1 - G2) = 4
RPERM, SLOPE = 0.05, 4.0


def _row(flag):
    """A PIDGOV tg_con row: PSS/E's run's values, feedback flag `flag`."""
    g = imported(flag).governors
    return [float(getattr(g, name)[0]) for name in g.columns()]


#: the time the closed-form tests let the governor settle (s)
T_SETTLE = 600.0


@pytest.mark.parametrize("flag", tuple(RUNS))
def test_initial_point_is_an_equilibrium(flag):
    """At rest the gate is the table's inverse of Pm0 (0.9 + (0.7 - 0.5)/4 = 0.95)."""
    p, x, Pref = started(_row(flag), PM0)
    P = p.packed(Pref)
    dx = np.full_like(x, np.nan)
    gov.derivatives(P, x, 0, 1.0, gov.pmech(P, x, 0, 1.0), dx)
    assert gov.pmech(P, x, 0, 1.0) == pytest.approx(PM0, abs=1e-15)
    assert x[gov.pidgov.S.gate, 0] == pytest.approx(0.95, abs=1e-15)
    assert np.abs(dx).max() < 1e-14


@pytest.mark.parametrize("flag", tuple(RUNS))
def test_pref_step_settles_on_the_droop_line(flag):
    """At rated speed a step dP of P_ref settles where P_ref + dP = f: the power rises
    by dP (flag 0), or the gate by dP and the power by the table's slope times dP
    (flag 1)."""
    p, x, Pref = started(_row(flag), PM0)
    dP = 0.002
    P = p.packed(Pref + dP)
    x = settled(P, x, 1.0, T_SETTLE)
    rise = SLOPE * dP if flag else dP
    assert gov.pmech(P, x, 0, 1.0) == pytest.approx(PM0 + rise, rel=1e-8)


def test_speed_held_off_rated_settles_on_the_droop_line():
    """Flag 0, the speed held d above rated: Rperm (P_ref - P_e) = d, the power falls by
    d / Rperm."""
    p, x, Pref = started(_row(0), PM0)
    d = 1e-3
    P = p.packed(Pref)
    x = settled(P, x, 1.0 + d, T_SETTLE)
    assert gov.pmech(P, x, 0, 1.0 + d) == pytest.approx(PM0 - d / RPERM, rel=1e-8)


def test_options_it_does_not_model_are_refused():
    """A gate table that does not rise, GMAX below GMIN, a gate velocity limit of the
    wrong sign, a feedback flag other than 0 or 1, a start-up gate beyond GMAX."""
    row = _row(0)
    for changes, match in (
        ({"G1": 0.95}, "G0 < G1 < G2 < 1"),
        ({"P2": 0.2}, "0 < P1 < P2 < P3"),
        ({"Tmin": 2.0}, r"field 'Tmax': must be >= Tmin = 2 \(governor type 12, PIDGOV"),
        ({"Uo": 0.0}, "VELMAX > 0 > VELMIN"),
        ({"feedback_flag": 2.0}, "feedback_flag must be 0 or 1"),
        ({"Tmax": 0.9}, "start-up gate 0.9500 pu outside"),
    ):
        changed = list(row)
        for name, value in changes.items():
            changed[gov.GOVERNOR.col(name) - 1] = value
        with pytest.raises(CaseError, match=match):
            started(changed, PM0)
