"""PSS/E's ST8C (stabctl.models.exciters.st8c): PSS/E's ThreeBus case with its GENROU on
ST8C, imported as a user imports it, initialises to PowerSimulationsDynamics.jl's states
and its linearisation has that program's eigenvalues (its test 61,
tests/data/psse_runs/ST8C/README.md); the rest point is the closed form of the block
diagram; the options stabctl does not model are refused by name."""

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
from stabctl.models.exciters.st8c import S
from stabctl.smallsignal.linearise import linearise

DATA = Path(__file__).parents[1] / "data" / "psse_runs" / "ST8C"
PSID = json.loads((DATA / "psid_test61.json").read_text())


def imported():
    """The run's case as ``stabctl import-psse RAW DYR`` builds it (constant-impedance
    loads, as the Julia test converts them)."""
    return load_psse(DATA / "ThreeBusMulti.raw", DATA / "ThreeBus_ST8C.dyr")


@pytest.fixture(scope="module")
def sim():
    return Simulator(imported(), background_compile=False)


def test_record_fills_the_shared_and_its_own_columns(sim):
    e = sim.case.exciters
    assert e.type[0] == 17
    got = [e.TR[0], e.Kpid_P[0], e.Kpid_I[0], e.VPmax[0], e.VPmin[0], e.KPA[0], e.KIA[0]]
    assert got == [0.01, 5.0, 5.0, 99.99, 0.0, 4.0, 0.1]
    got = [e.VAmax[0], e.VAmin[0], e.KA[0], e.TA[0], e.Vrmax[0], e.Vrmin[0]]
    assert got == [99.9962, -99.866, 1.35, 0.003, 99.3449, -99.1691]
    got = [e.KF_ifd[0], e.TF_ifd[0], e.KC[0], e.KP[0], e.VB1max[0], e.SW1[0], e.KI2[0]]
    assert got == [0.5, 0.005, 0.1, 4.0, 99.0, 0.0, 0.0]


def test_initial_states_are_psid_s(sim):
    """PSID's initial point: its bus voltages, its GENROU's states (stabctl's E'd and
    psi_kq in PST's sign) and its ST8C's (V_m, x_a1 .. x_a4; stabctl's PI integrals are
    K_IR x_a1 and K_IA x_a2), within 1e-9 (the power flow's round-off)."""
    ref = PSID["x0"]
    m = sim.model
    psid = assert_start_is_psids(sim, ref, machine=1)  # bus 102's GENROU (101: the GENCLS)
    xe = m.layout.view(m.x0, "exc")[:, 0]
    got = [xe[S.VTR], xe[S.PIi] / 5.0, xe[S.PIa] / 0.1, xe[S.VR], xe[S.VF]]
    np.testing.assert_allclose(got, psid[6:], rtol=0, atol=1e-9)


def _gaps(case) -> dict:
    """PSID's eigenvalue -> its distance to stabctl's nearest (1/s)."""
    psid = np.array([complex(*v) for v in PSID["eigvals"]])
    lam = np.linalg.eigvals(np.asarray(linearise(Simulator(case, background_compile=False)).A))
    assert lam.size == psid.size  # 11: GENROU, ST8C
    return {z: float(np.min(np.abs(lam - z))) for z in psid}


def test_eigenvalues_are_psid_s_with_its_held_torque():
    """PSID's spectrum (GENROU, ST8C, the infinite bus; 11 eigenvalues) is stabctl's, each
    within 1e-6 1/s (measured 4.0e-8), once the machine, which has no governor, holds its
    torque as PSID's does (`psid.torque_held`).  As imported (PSS/E's held power,
    the torque P_m/omega) the electromechanical pair is 0.034 1/s and the -1.590 mode
    0.0083 from PSID's."""
    assert max(_gaps(torque_held(imported())).values()) < 1e-6


# -- the exciter alone at rest (kundur's machine 1, the run's record)

EFD0, VT0 = 1.5883, 1.02


def _row(**changed):
    e = imported().exciters
    out = [float(getattr(e, name)[0]) for name in e.columns()]
    for name, value in changed.items():
        out[exc.EXCITER.col(name) - 1] = value
    out[1] = 1  # kundur's machine 1
    return out


def _started(row):
    case = load_case("kundur").replace(exciters=ExciterTable.from_matrix([row]))
    x, Vref, p = exc.initialise(exc.exciter_params(case), np.array([EFD0]), np.array([VT0]))
    return p.packed(Vref), x, Vref


def test_rest_point_is_the_closed_form():
    """At rest I_fd = Efd0: V_F = I_fdref = K_F Efd0, V_R = Efd0 / (K_P (1 - 0.577 K_C1
    Efd0 / K_P)) (F_EX on its first segment), the field current PI's integral V_R / K_A,
    V_ref = V_t0; every derivative is 0 and the field voltage is Efd0."""
    P, x, Vref = _started(_row())
    VR = EFD0 / (4.0 * (1 - 0.577 * 0.1 * EFD0 / 4.0))
    assert x[S.VF, 0] == pytest.approx(0.5 * EFD0, rel=1e-15)
    assert x[S.PIi, 0] == pytest.approx(0.5 * EFD0, rel=1e-15)
    assert x[S.VR, 0] == pytest.approx(VR, rel=1e-14)
    assert x[S.PIa, 0] == pytest.approx(VR / 1.35, rel=1e-14)
    assert Vref[0] == VT0
    efd = exc.field_voltage_at(P, x, 0, VT0, 0.0, 1.0, EFD0, True)
    assert efd == pytest.approx(EFD0, rel=1e-14)
    dx = np.full_like(x, np.nan)
    exc.derivatives(P, x, 0, VT0, VT0, 0.0, efd, EFD0, 1.0, dx, True, 0.0)
    assert np.abs(dx).max() < 1e-12


@pytest.mark.parametrize(
    "name, value, match",
    [
        ("SW1", 1.0, "SW1"),
        ("KI2", 0.2, "KI2"),
        ("KIA", 0.0, "KIA"),
        ("TF_ifd", 0.0, "TF"),
    ],
)
def test_options_it_does_not_model_are_refused(name, value, match):
    with pytest.raises(CaseError, match=match):
        _started(_row(**{name: value}))
