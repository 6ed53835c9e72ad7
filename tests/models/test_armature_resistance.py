"""Armature resistance r_a: a flat start stays flat for every machine model.

The machines' initialisation (PST flag 0: E = v + (r_a + j x) I, pmech = P + r_a |I|^2 on the
machine base) and their stator equations work on the machine base; the network sees each
machine behind (r_a + j x) mac_pot on the system base (PST red_ybus).  With r_a left on the
machine base in the network, Kundur with r_a = 0.003 drifted 4e-4 pu in speed within 1 s.
The shipped cases all have r_a = 0, so the PSTess comparisons (test_simulation.py) do not see
r_a; PSS/E imports usually do (ZSORCE R).
"""

import numpy as np
import pytest

from stabctl.dynamics.driver import Simulator
from stabctl.io import load_case
from stabctl.models.machines import EM, SUB, TRA, machine_params

RA = 0.003
KINDS = {"mac_sub": SUB, "mac_tra": TRA, "mac_em": EM}


def kundur_with_ra(kind: str):
    """Kundur with r_a = 0.003 on every machine, as subtransient (as shipped), transient
    (x"_d = 0) or classical (x_d = 0) machines."""
    case = load_case("kundur")
    m = case.machines
    changes = {"ra": np.full(m.ra.shape, RA)}
    if kind == "mac_tra":
        changes["xdpp"] = np.zeros_like(m.xdpp)
    elif kind == "mac_em":
        changes["xd"] = np.zeros_like(m.xd)
    case = case.replace(machines=m.replace(**changes))
    assert np.all(machine_params(case).kind == KINDS[kind])
    return case


@pytest.fixture(scope="module", params=list(KINDS))
def sim(request):
    return Simulator(kundur_with_ra(request.param))


def test_network_current_is_the_power_flow_current(sim):
    """At t = 0 the reduced network returns each machine's power-flow terminal current, and
    every derivative is zero."""
    model = sim.model_for()
    dx, out = model.evaluate(model.x0.copy(), model.network(), model.V_nc0)
    mp, op = model.mp, model.op
    S = op.S_gen[mp.bus_idx]
    I_pf = np.conj((S.real * mp.pfrac + 1j * S.imag * mp.qfrac) / op.V[mp.bus_idx])
    np.testing.assert_allclose(out.cur, I_pf, rtol=0, atol=1e-10)
    np.testing.assert_allclose(out.V_bus, op.V, rtol=0, atol=1e-10)
    assert np.abs(dx).max() < 1e-9, model.state_name(int(np.argmax(np.abs(dx))))
    assert model.initial_residual[0] < 1e-9


def test_flat_run_does_not_drift(sim, record_property):
    res = sim.run([], t_end=5.0)
    assert res.stable and res.t[-1] == 5.0
    drift = float(np.abs(res.speed - 1.0).max())
    record_property("ra_flat_5s_speed_drift", f"{drift:.3g}")
    assert drift < 1e-9
    assert np.abs(res.angle - res.angle[0]).max() < 1e-9
    assert np.abs(res.vmag - res.vmag[0]).max() < 1e-9


def test_ra_enters_the_network_on_the_system_base():
    """PST red_ybus: y = 1/((r_a + j x) mac_pot); the machine-base r_a makes the flat start
    drift (the defect).  Classical machines have no r_a in their equations (PST mac_em), so
    the network puts them behind j x'_d only."""
    case = kundur_with_ra("mac_sub")
    mp = machine_params(case)
    np.testing.assert_allclose(1.0 / mp.y_internal, (RA + 1j * mp.xdpp) * mp.mac_pot)
    # losses: the turbine supplies the stator loss r_a |I|^2 (machine base)
    model = Simulator(case).model_for()
    S = model.op.S_gen[mp.bus_idx]
    I = np.abs(S / model.op.V[mp.bus_idx]) * mp.mac_pot
    np.testing.assert_allclose(model.pmech0, S.real * mp.mac_pot + RA * I**2, rtol=1e-12)
    em = machine_params(kundur_with_ra("mac_em"))
    np.testing.assert_allclose(1.0 / em.y_internal, 1j * em.xdp * em.mac_pot)
