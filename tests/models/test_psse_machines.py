"""The PSS/E reading of the machines (DYR conventions "psse", docs/pst_models.md 1.6b and
12): stator at rated speed, PSS/E's swing equation (P_m - D (omega - 1)) / omega - T_e
(mac_con psse_swing), GENROU's and GENROE's saturation of the air-gap flux, GENSAL's of
E'q, GENSAE's exponential one of the air-gap flux on both axes (mac_con psse_sat).
Checked by closed forms, by PSS/E's own initial rotor angles (tests/data/psse_runs, the
first row of each PSS/E channel) and by flat starts of PSS/E's cases; the trajectories
against PSS/E's runs are tests/io/test_psse_runs.py."""

import numpy as np
import pytest
from psse_reference import BY_NAME, DATA, psse_channels
from runs import flat_run

from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.model import StageConfig
from stabctl.errors import CaseError
from stabctl.io import load_case
from stabctl.io.dyr import dyr_tables, read_dyr
from stabctl.io.psse import load_psse
from stabctl.models.machines import MACHINE
from stabctl.models.saturation import exponential_fit

MACHINE_RUNS = ("OMIB_GENCLS", "GENROU", "GENROU_NO_SAT", "GENROE", "GENSAL", "GENSAE")


def psse_case(name, conventions="psse"):
    run = BY_NAME[name]
    loads = "raw" if "--loads" in run.import_options else "impedance"
    d = DATA / name
    return load_psse(d / run.raw, d / run.dyr, loads=loads, conventions=conventions)


@pytest.mark.parametrize("name", MACHINE_RUNS)
def test_initial_rotor_angle_is_psse_s(name):
    """delta G102 - delta G101 at t = 0: PSS/E's first CSV row (its 5-6 digits)."""
    model = Simulator(psse_case(name), q_limits=False).model_for(())
    delta = model.x0[1] - model.x0[0]
    _, m = psse_channels(BY_NAME[name])
    assert np.degrees(delta) == pytest.approx(m[0, 1], abs=2e-3)


@pytest.mark.parametrize("name", [*MACHINE_RUNS, "LOAD_CONST_P", "LOAD_CONST_I"])
def test_flat_start_of_each_psse_machine(name):
    drift, _ = flat_run(psse_case(name), t_end=10.0)
    assert drift < 1e-8


def test_gensae_saturates_the_q_axis_and_gensal_does_not():
    """PSS/E's GENSAE starts at 33.49 deg, 2 deg below the unsaturated 35.49 deg of its
    GENSAL twin (same data): its q axis saturates (gamma_qd S_e(|psi"|)); read as pst (no
    saturation) both start at GENSAL's angle."""
    angles = {}
    for name in ("GENSAL", "GENSAE"):
        for conv in ("psse", "pst"):
            x0 = Simulator(psse_case(name, conv), q_limits=False).model_for(()).x0
            angles[name, conv] = np.degrees(x0[1] - x0[0])
    assert angles["GENSAE", "psse"] == pytest.approx(33.4912, abs=2e-3)
    assert angles["GENSAL", "psse"] == pytest.approx(35.4891, abs=2e-3)
    assert angles["GENSAE", "pst"] == pytest.approx(angles["GENSAL", "psse"], abs=2e-3)


DW = 0.01  # speed offset of machine 1, pu


def test_psse_swing_divides_pm_and_d_by_speed():
    """Kundur with the stator at rated speed: a speed offset DW of machine 1 alone leaves
    its air-gap torque at P_m, so d omega / dt = ((P_m - D DW) / (1 + DW) - P_m) / 2H
    with psse_swing, and -D DW / 2H without."""
    case = load_case("kundur")
    n = len(case.machines)
    acc = {}
    for swing in (0.0, 1.0):
        c = case.replace(
            machines=case.machines.replace(
                speed_effects=np.zeros(n), psse_swing=np.full(n, swing), D0=np.full(n, 2.0)
            )
        )
        m = Simulator(c).model_for(())
        net = m.network(StageConfig())
        x = m.x0.copy()
        x[n] += DW
        acc[swing] = m.evaluate(x, net, m.V_nc0)[0][n]
    H, pm = m.mp.H[0], m.pmech0[0]
    assert acc[1.0] == pytest.approx(((pm - 2.0 * DW) / (1 + DW) - pm) / (2 * H), rel=1e-9)
    assert acc[0.0] == pytest.approx(-2.0 * DW / (2 * H), rel=1e-9)


def test_psse_swing_is_0_or_1_and_psse_sat_a_code():
    case = load_case("kundur")
    n = len(case.machines)
    with pytest.raises(CaseError, match="psse_swing"):
        case.machines.replace(psse_swing=np.full(n, 0.5))
    with pytest.raises(CaseError, match="psse_sat"):
        case.machines.replace(psse_sat=np.full(n, 5.0))


def test_exponential_fit_goes_through_both_points():
    """S(E) = B E^A through (1.0, 0.0392), (1.2, 0.2672) (the GENROE run's data)."""
    A, B = exponential_fit(1.0, np.array([0.0392]), 1.2, np.array([0.2672]), np.array([True]), "x")
    assert B[0] * 1.0 ** A[0] == pytest.approx(0.0392, rel=1e-12)
    assert B[0] * 1.2 ** A[0] == pytest.approx(0.2672, rel=1e-12)
    none = exponential_fit(1.0, np.zeros(1), 1.2, np.zeros(1), np.array([True]), "x")
    np.testing.assert_array_equal(none, 0.0)
    with pytest.raises(CaseError, match=r"row 1: .* no exponential fit"):
        exponential_fit(1.0, np.array([0.1]), 1.2, np.zeros(1), np.array([True]), "row {row}: ")


DYR = """\
1 'GENROU' 1 8 0.03 0.4 0.05 6.175 0.05 1.8 1.7 0.3 0.55 0.25 0.2 0.1 0.8 /
2 'GENROE' 1 8 0.03 0.4 0.05 6.175 0.05 1.8 1.7 0.3 0.55 0.25 0.2 0.0392 0.2672 /
3 'GENSAL' 1 5 0.05 0.2 5 0 1 0.75 0.4 0.25 0.1 0.11 0.62 /
4 'GENSAE' 1 5 0.05 0.2 5 0 1 0.75 0.4 0.25 0.1 0.11 0.62 /
5 'GENCLS' 1 3 2 /
"""


def generators():
    return [dict(number=k, bus=k, id="1", mbase=100.0, ra=0.0, xsource=0.25) for k in range(1, 6)]


def column(t, name):
    return t.mac_con[:, MACHINE.col(name) - 1]


def test_psse_reading_of_each_machine_model(tmp_path):
    """psse: stator at rated speed, the model's saturation code and PSS/E's swing (not
    GENCLS's); pst: speed effects, no saturation; every other column the same.  GENROE
    and GENSAE share GENROU's and GENSAL's rows but for the code."""
    f = tmp_path / "m.dyr"
    f.write_text(DYR)
    psse = dyr_tables(read_dyr(f), generators())
    pst = dyr_tables(read_dyr(f), generators(), conventions="pst")
    np.testing.assert_array_equal(column(psse, "psse_sat"), [1, 2, 3, 4, 0])
    np.testing.assert_array_equal(column(psse, "psse_swing"), [1, 1, 1, 1, 0])
    np.testing.assert_array_equal(column(psse, "speed_effects"), 0)
    np.testing.assert_array_equal(column(pst, "psse_sat"), 0)
    np.testing.assert_array_equal(column(pst, "psse_swing"), 0)
    np.testing.assert_array_equal(column(pst, "speed_effects"), 1)
    same = [c for c in MACHINE.names if c not in ("psse_sat", "psse_swing", "speed_effects")]
    idx = [MACHINE.col(c) - 1 for c in same]
    np.testing.assert_array_equal(psse.mac_con[:, idx], pst.mac_con[:, idx])
    skip = [c for c in same if c not in ("number", "bus", "col19", "S10", "S12")]
    k = [MACHINE.col(c) - 1 for c in skip]
    np.testing.assert_array_equal(pst.mac_con[0, k], pst.mac_con[1, k])  # GENROE: GENROU's
    np.testing.assert_array_equal(pst.mac_con[2, k], pst.mac_con[3, k])  # GENSAE: GENSAL's


def test_andes_reading_refuses_the_models_andes_lacks(tmp_path):
    f = tmp_path / "m.dyr"
    f.write_text(DYR)
    with pytest.raises(CaseError) as e:
        dyr_tables(read_dyr(f), generators(), conventions="andes")
    msg = str(e.value)
    assert "m.dyr:2 GENROE (bus 2, id 1): ANDES 2.0 has no GENROE" in msg
    assert "m.dyr:4 GENSAE (bus 4, id 1): ANDES 2.0 has no GENSAE" in msg
