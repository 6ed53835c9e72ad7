"""Static var compensators (stabctl.models.svcs, PSS/E CSVGN1): the import of PSS/E's
record, the initial point from the power flow, the regulator's and thyristor's closed
forms and limits, and the refusals."""

import numpy as np
import pytest
from psse_reference import DATA
from runs import flat_run
from scipy.integrate import solve_ivp

from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.infeasible import leave_out_infeasible
from stabctl.dynamics.model import OperatingPoint
from stabctl.errors import CaseError, InitialLimitError
from stabctl.io.psse import load_psse
from stabctl.models import svcs
from stabctl.network.powerflow import solve_powerflow

FOLDER = DATA / "CSVGN1"


def case():
    """PSS/E's CSVGN1 run (3 buses; the SVC at bus 3 as the Julia test builds it)."""
    return load_psse(FOLDER / "3_BUS_System_SVC.raw", FOLDER / "3_BUS_System_SVC.dyr")


def params(c=None):
    """(SvcParams, OperatingPoint) of the case at its power flow."""
    c = case() if c is None else c
    op = OperatingPoint.from_bus_matrix(solve_powerflow(c).bus_matrix())
    return svcs.svc_params(c, op.V, op.S_gen), op


def test_csvgn1_record_is_a_compensator_not_a_machine():
    """The record's CONs land in svc_con in PSS/E's order, RBASE the generator's MBASE
    (500), its share of bus 3's Q 1; its generator is no machine (one machine, the
    infinite bus)."""
    c = case()
    t = c.svcs
    assert len(t) == 1 and len(c.machines) == 1
    assert (t.bus[0], t.qfrac[0], t.mva[0], t.K[0], t.CBASE[0]) == (3, 1.0, 500.0, 20.0, 60.0)
    assert (t.T1[0], t.T2[0], t.T3[0], t.T4[0], t.T5[0]) == (0.0, 1.0, 0.154833, 1.0, 0.005167)
    assert (t.RMIN[0], t.VMAX[0], t.VMIN[0]) == (0.0, 1.0, 0.0)


def test_initial_susceptance_and_reference_from_the_power_flow():
    """B0 = Q0/|V|^2 of bus 3's generation, the thyristor at (CBASE/S_b - B0) S_b/RBASE
    and V_ref = |V| - y_R0/K; the susceptance the kernel gives at rest is B0."""
    p, op = params()
    q0, v0 = op.S_gen[2].imag, abs(op.V[2])
    assert p.B0[0] == pytest.approx(q0 / v0**2, rel=1e-14)
    y0 = (0.6 - p.B0[0]) / 5.0
    assert p.y0()[0] == pytest.approx(y0, rel=1e-14)
    assert p.Vref[0] == pytest.approx(v0 - y0 / 20.0, rel=1e-14)
    x = svcs.initialise(p)
    P = p.packed()
    assert svcs.susceptance(P, x, 0) == pytest.approx(p.B0[0], rel=1e-13)
    dx = np.full_like(x, np.nan)
    svcs.derivatives(P, x, 0, v0, dx)
    assert np.abs(dx).max() < 1e-13


def test_compensator_case_runs_flat():
    """No disturbance: no state moves by 1e-10 in 1 s (the SVC's B0 among the bus's
    shunts, its states at rest)."""
    drift, _ = flat_run(case(), t_end=1.0, step=1e-3)
    assert drift < 1e-10


def response(p, dv, t):
    """The thyristor's output after t s with the voltage held dv above its start."""
    P, x0 = p.packed(), svcs.initialise(p)
    v = abs(p.Vref[0] + p.y0()[0] / p.K[0]) + dv

    def f(_, y):
        x = y.reshape(x0.shape).copy()
        dx = np.zeros_like(x)
        svcs.derivatives(P, x, 0, v, dx)
        return dx.ravel()

    sol = solve_ivp(f, (0, t), x0.ravel(), method="Radau", rtol=1e-11, atol=1e-13)
    return sol.y.reshape(3, 1, -1)[2, 0, -1]


def test_regulator_and_thyristor_step_response_is_their_two_lags():
    """PSS/E's run's values (T1 0, T2 = T4 = 1: the regulator is K/(1 + s T3)), voltage
    held dv above its start: y_R = y_R0 + K dv [1 - (T3 e^(-t/T3) - T5 e^(-t/T5))/(T3 -
    T5)] (partial fractions of two lags)."""
    p, _ = params()
    dv, t, K, T3, T5 = 1e-3, 0.1, 20.0, 0.154833, 0.005167
    exact = p.y0()[0] + K * dv * (1 - (T3 * np.exp(-t / T3) - T5 * np.exp(-t / T5)) / (T3 - T5))
    assert response(p, dv, t) == pytest.approx(exact, rel=1e-8)


def test_thyristor_and_regulator_hold_their_limits():
    """Far above its reference the regulator stops at VMAX = 1 and the thyristor at 1
    (the reactor fully on: B = (CBASE - RBASE)/S_b), each non-windup."""
    p, _ = params()
    assert response(p, 0.5, 2.0) == pytest.approx(1.0, abs=1e-12)
    P, x = p.packed(), svcs.initialise(p)
    x[2, 0] = 1.2
    assert svcs.susceptance(P, x, 0) == pytest.approx(0.6 - 5.0, rel=1e-14)


def test_start_outside_the_reactor_range_is_refused():
    """CBASE 600 Mvar: the power flow's 22 Mvar needs the reactor at (6 - 0.21)/5 > 1."""
    c = case()
    c = c.replace(svcs=c.svcs.replace(CBASE=np.array([600.0])))
    with pytest.raises(InitialLimitError, match=r"svc_con row 1: .* outside \[RMIN/RBASE, 1\]"):
        params(c)
    bus = int(c.svcs.bus[0])
    with pytest.raises(InitialLimitError, match=rf"^the static var compensator at bus {bus}: "):
        Simulator(c, background_compile=False)  # named by its bus, not its table row
    with pytest.raises(CaseError, match=rf"compensator at bus {bus}: .* is not left out"):
        leave_out_infeasible(c)  # its Q is the power flow's: not a control to leave out


@pytest.mark.parametrize(
    "changed, field",
    [({"T3": 0.0}, "T1"), ({"T5": 0.0}, "T5"), ({"VMIN": 2.0}, "VMAX"), ({"K": 0.0}, "K")],
)
def test_options_it_cannot_model_are_refused(changed, field):
    c = case()  # its table as given runs
    if field == "T1":
        changed = {**changed, "T1": 0.1}
    with pytest.raises(CaseError, match=rf"svc_con row 1 \(compensator 1\), field '{field}'"):
        # refused as the table is made (so a case file's error names the file)
        c.svcs.replace(**{k: np.array([v]) for k, v in changed.items()})
