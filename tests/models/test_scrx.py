"""PSS/E's SCRX (stabctl.models.exciters.sexs, smpexc type 0, with its negative field
current logic): PSS/E's ThreeBus case with its GENROU on SCRX (solid fed, bus fed, bus
fed with rc/rfd = 1), imported as a user imports it, initialises to
PowerSimulationsDynamics.jl's states (its test 47, tests/data/psse_runs/SCRX/README.md)
and, with PSID's shaft for a machine without a governor, has its eigenvalues; the
negative field current logic is the closed form of PSS/E's block diagram; bad values are
refused by name."""

import json
from pathlib import Path

import numpy as np
import pytest
from psid import assert_start_is_psids, torque_held

from stabctl.case import ExciterTable
from stabctl.dynamics.driver import Simulator
from stabctl.errors import CaseError
from stabctl.io import load_case
from stabctl.io.psse import load_psse
from stabctl.models import exciters as exc
from stabctl.models.exciters.sexs import S
from stabctl.smallsignal.linearise import linearise

DATA = Path(__file__).parents[1] / "data" / "psse_runs" / "SCRX"
RAW = DATA / "ThreeBusMulti.raw"
PSID = json.loads((DATA / "psid_test47.json").read_text())
#: PSID's run -> (its DYR, CSWITCH, rc/rfd)
RUNS = {
    "plain": ("ThreeBus_SCRX.dyr", 1.0, 0.0),
    "switch": ("ThreeBus_SCRX_withSwitch.dyr", 0.0, 0.0),
    "rcrfd": ("ThreeBus_SCRX_withRcRfd.dyr", 0.0, 1.0),
}
TA_TB = 0.4  # the records' TA/TB


def imported(run):
    """The run's case as ``stabctl import-psse RAW DYR`` builds it (constant-impedance
    loads, as the Julia test converts them)."""
    return load_psse(RAW, DATA / RUNS[run][0])


@pytest.fixture(scope="module", params=tuple(RUNS))
def run(request):
    return request.param, Simulator(imported(request.param), background_compile=False)


def test_record_fills_smpexc_and_its_column(run):
    """SCRX TA/TB TB K TE EMIN EMAX CSWITCH rc/rfd: smpexc with T_C = (TA/TB) TB, bus fed
    (column 19) when CSWITCH = 0, rc/rfd in column 74."""
    name, sim = run
    e = sim.case.exciters
    _, cswitch, rc_rfd = RUNS[name]
    assert e.type[0] == 0 and e.rc_rfd[0] == rc_rfd and e.KG[0] == float(cswitch == 0)
    assert [e.TC[0], e.TB[0], e.KA[0], e.TA[0], e.Vrmin[0], e.Vrmax[0]] == [
        2.0,
        5.0,
        20.0,
        1.0,
        -50.0,
        50.0,
    ]


def test_initial_states_are_psid_s(run):
    """PSID's initial point: its bus voltages, its GENROU's states (stabctl's E'd and
    psi_kq in PST's sign) and its SCRX's: Vr1, the lead-lag's state ((1 - TA/TB) times
    stabctl's, the lagged input), Vr2 (the regulator's output before the bus-fed
    product), within 1e-9 (measured 4.2e-12)."""
    name, sim = run
    ref = PSID[f"x0_{name}"]
    m = sim.model
    psid = assert_start_is_psids(sim, ref, machine=1)  # bus 102's GENROU (101: the GENCLS)
    xe = m.layout.view(m.x0, "exc")[:, 0]
    got = [(1 - TA_TB) * xe[S.VAs], xe[S.Efd]]
    np.testing.assert_allclose(got, psid[6:], rtol=0, atol=1e-9)


def _gaps(case, name) -> dict:
    """PSID's eigenvalue -> its distance to stabctl's nearest (1/s)."""
    psid = np.array([complex(*v) for v in PSID[f"eigvals_{name}"]])
    lam = np.linalg.eigvals(np.asarray(linearise(Simulator(case, background_compile=False)).A))
    assert lam.size == psid.size == 8  # GENROU, SCRX
    return {z: float(np.min(np.abs(lam - z))) for z in psid}


@pytest.mark.parametrize("name", tuple(RUNS))
def test_eigenvalues_are_psid_s_with_its_held_torque(name):
    """PSID's spectrum (GENROU, SCRX, the infinite bus; 8 eigenvalues) is stabctl's, each
    within 1e-6 1/s (measured 4.1e-8), once the machine, which has no governor, holds its
    torque as PSID's does (`torque_held`).  As imported (PSS/E's held power) the
    electromechanical pair is 0.042 1/s better damped than PSID's: the torque P_m/omega
    falls as the speed rises."""
    assert max(_gaps(torque_held(imported(name)), name).values()) < 1e-6


def test_rc_rfd_leaves_the_linearisation_while_the_field_current_is_positive():
    """At rest I_fd = Efd0 > 0, where PSS/E's logic passes the regulator's output: PSID's
    rc/rfd = 1 run has its bus-fed run's initial point and eigenvalues, and so has
    stabctl's."""
    assert PSID["x0_rcrfd"] == PSID["x0_switch"]
    assert PSID["eigvals_rcrfd"] == PSID["eigvals_switch"]
    a = [
        np.asarray(linearise(Simulator(imported(r), background_compile=False)).A)
        for r in ("switch", "rcrfd")
    ]
    np.testing.assert_array_equal(a[0], a[1])


# -- the exciter alone at rest (kundur's machine 1, the rc/rfd run's record)

EFD0, VT0 = 2.0, 1.02


def _row(**changed):
    e = imported("rcrfd").exciters
    out = [float(getattr(e, name)[0]) for name in e.columns()]
    for name, value in changed.items():
        out[exc.EXCITER.col(name) - 1] = value
    out[1] = 1  # kundur's machine 1
    return out


def _started(row, efd0=EFD0):
    case = load_case("kundur").replace(exciters=ExciterTable.from_matrix([row]))
    x, Vref, p = exc.initialise(exc.exciter_params(case), np.array([efd0]), np.array([VT0]))
    return p.packed(Vref), x


@pytest.mark.parametrize("ieee", (True, False))
def test_negative_field_current_meets_the_discharge_resistor(ieee):
    """PSS/E's SCRX: with rc/rfd != 0 the field voltage is -rc/rfd I_fd while I_fd <= 0,
    the regulator's output (bus fed: times V_t) while I_fd > 0; with rc/rfd = 0 the
    regulator's output whatever I_fd."""
    for rc in (1.0, 2.5):
        P, x = _started(_row(rc_rfd=rc))
        assert exc.field_voltage_at(P, x, 0, VT0, 0.0, 1.0, EFD0, ieee) == pytest.approx(
            EFD0, rel=1e-14
        )
        assert exc.field_voltage_at(P, x, 0, VT0, 0.0, 1.0, -0.3, ieee) == rc * 0.3
        assert exc.field_voltage_at(P, x, 0, VT0, 0.0, 1.0, 0.0, ieee) == 0.0
    P, x = _started(_row(rc_rfd=0.0))
    efd = exc.field_voltage_at(P, x, 0, VT0, 0.0, 1.0, -0.3, ieee)
    assert efd == pytest.approx(EFD0, rel=1e-14)


def test_bad_values_are_refused_by_name(tmp_path):
    """A negative rc/rfd (DYR: naming the record; exc_con: the field), and a start-up
    field current <= 0 with rc/rfd != 0 (no rest point on the regulator's output)."""
    text = (DATA / "ThreeBus_SCRX_withRcRfd.dyr").read_text().replace("1.0/", "-1.0/")
    bad = tmp_path / "ThreeBus_SCRX_withRcRfd.dyr"
    bad.write_text(text)
    with pytest.raises(CaseError, match=r"_withRcRfd.dyr:\d+ SCRX .*rc/rfd = -1 must be >= 0"):
        load_psse(RAW, bad)
    with pytest.raises(CaseError, match="rc_rfd"):
        _started(_row(rc_rfd=-1.0))
    with pytest.raises(CaseError, match=r"SCRX's start-up field current -0.1000 pu"):
        _started(_row(), efd0=-0.1)


def test_a_cswitch_other_than_0_or_1_is_refused(tmp_path):
    """CSWITCH 2 (PSS/E Model Library SCRX: 0 bus fed, 1 solid fed) was read as solid fed
    and ran without a word: refused naming the record, CSWITCH and its value."""
    dyr = tmp_path / "cswitch2.dyr"
    text = (DATA / RUNS["plain"][0]).read_text()
    dyr.write_text(text.replace("50.0     1     0.0/", "50.0     2     0.0/"))
    with pytest.raises(CaseError, match=r"SCRX.*CSWITCH = 2 must be 0 \(bus fed\) or 1"):
        load_psse(RAW, dyr)


@pytest.mark.parametrize("conventions", ["ieee", "pstess"])
def test_sexs_without_te_holds_efd_within_its_limits_under_pss_e_s_reading(tmp_path, conventions):
    """SEXS with TE = 0 (Efd = K times the lead-lag's output) and EMIN -2, EMAX 4 on the
    GENROU at bus 102 of PSS/E's ThreeBus case, a bolted fault at bus 102 for 0.15 s: PSS/E's
    reading (ieee, import-psse's) clips Efd to [EMIN, EMAX] (OpenIPSL's SimpleLagLim,
    OPAL-RT's Lag_NonWindupLimit; round 53, AO05: it reached 24.9 pu), so the field
    voltage rides at EMAX = 4 through the fault; PSTess's smpexc without T_A has no limit
    (docs/pst_models.md 2.1): above 4."""
    from stabctl.case.events import Fault

    dyr = tmp_path / "sexs_te0.dyr"
    dyr.write_text(
        "101 'GENCLS' 1 0 0 /\n"
        "102 'GENROU' 1 8.0 0.03 0.4 0.05 6.175 0.05 1.8 1.7 0.3 0.55 0.25 0.2 0.1 0.8 /\n"
        "102 'SEXS' 1 0.2 5.0 100.0 0.0 -2.0 4.0 /\n"
    )
    case = load_psse(RAW, dyr)
    r = Simulator(case, conventions=conventions).run(
        [Fault(102, 1.0, clear_near=1.15)], 1.5, h=1e-3
    )
    efd = r.efd[:, list(case.machines.bus).index(102)]
    if conventions == "ieee":
        assert efd.max() == pytest.approx(4.0, abs=1e-12) and efd.min() >= -2.0 - 1e-12
    else:
        assert efd.max() > 10.0
