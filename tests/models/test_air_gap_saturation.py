"""PSS/E's GENROU saturation of the air-gap flux (mac_con column 25, docs/pst_models.md
1.6a; ANDES 2.0 ``genrou.py``), on the Kundur case with IEEE 14's machine saturation
(S(1.0) = 0.09, S(1.2) = 0.38) and no speed effects: the initialisation is an
equilibrium, and its field voltage and rotor angle are ANDES's closed forms (``vf0``,
``delta0``) evaluated here from the power-flow point."""

import numpy as np
import pytest

from stabctl.dynamics.driver import Simulator
from stabctl.errors import CaseError
from stabctl.io import load_case

S10, S12 = 0.09, 0.38


def saturated(psse_sat: float = 1.0, s10: float = S10, s12: float = S12):
    case = load_case("kundur")
    n = len(case.machines)
    full = np.full
    return case.replace(
        machines=case.machines.replace(
            S10=full(n, s10),
            S12=full(n, s12),
            speed_effects=full(n, 0.0),
            psse_sat=full(n, psse_sat),
        )
    )


def andes_closed_forms(case, model):
    """ANDES genrou.py lines 75-135: ExcQuadSat's A, B through (1.0, S10), (1.2, S12),
    psi20 = v + (ra + j xd2) I, Se0, delta0, vf0 = (1 + Se0) psi2d0 + (xd - xd2) Id0."""
    m = case.machines
    a = np.sqrt(S10 * 1.0 / (S12 * 1.2))
    A = 1.2 - (1.0 - 1.2) / (a - 1)
    B = S12 * 1.2 * (a - 1) ** 2 / (1.0 - 1.2) ** 2
    mp, op = model.mp, model.op
    V = op.V[mp.bus_idx]
    I = np.conj(op.S_gen[mp.bus_idx] / V) * mp.mac_pot
    psi20 = V + (m.ra + 1j * m.xdpp) * I
    Se0 = np.where(np.abs(psi20) >= A, (np.abs(psi20) - A) ** 2 * B / np.abs(psi20), 0.0)
    gqd = (m.xq - m.xl) / (m.xd - m.xl)
    _a, _b = np.abs(psi20) * (1 + Se0 * gqd), np.abs(I) * (m.xdpp - m.xq)
    th = np.angle(psi20) - np.angle(I)
    delta0 = np.arctan(_b * np.cos(th) / (_b * np.sin(th) - _a)) + np.angle(psi20)
    Tdq = np.cos(delta0) - 1j * np.sin(delta0)
    psi2d0, Id0 = (psi20 * Tdq).real, np.conj(I * Tdq).imag  # lines 113-125
    return delta0, (Se0 + 1) * psi2d0 + (m.xd - m.xdpp) * Id0, Se0


def test_saturated_initial_point_is_an_equilibrium_at_andes_field_voltage_and_angle():
    case = saturated()
    model = Simulator(case).model_for(())
    delta0, vf0, Se0 = andes_closed_forms(case, model)
    assert np.all(Se0 > 0.01)  # saturated operating points
    n = len(case.machines)
    np.testing.assert_allclose(model.x0[:n], delta0, atol=1e-12)
    np.testing.assert_allclose(model.vex0, vf0, rtol=1e-12)
    assert model.initial_residual[0] < 1e-9
    # read without it (PST's mac_sub) the same machines need a lower field voltage
    plain = Simulator(saturated(psse_sat=0.0)).model_for(())
    assert np.all(plain.vex0 < model.vex0 - 0.05)
    assert plain.initial_residual[0] < 1e-9


def test_saturation_points_0_mean_none_and_column_25_is_a_code():
    a = Simulator(saturated(s10=0.0)).model_for(())
    b = Simulator(saturated(psse_sat=0.0, s10=0.0)).model_for(())
    np.testing.assert_array_equal(a.vex0, b.vex0)
    with pytest.raises(CaseError, match="psse_sat"):
        saturated(psse_sat=0.5)
