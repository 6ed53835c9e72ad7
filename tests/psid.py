"""Comparisons with PowerSimulationsDynamics.jl's (PSID's) stored references of PSS/E
cases (tests/data/psse_runs/*/psid_test*.json): its initial point of a bus-102 GENROU case,
and its shaft for a machine without a governor (tests/models/test_scrx.py, test_st8c.py,
test_degov1.py, test_pidgov.py, test_wpidhy.py, test_dera1.py)."""

import numpy as np


def torque_held(case):
    """The case with PSID's mechanical torque for its machines: PSID's ``TGFixed`` (no
    governor) holds the torque (tau_m = P_ref), where PSS/E, and stabctl's PSS/E machines
    (mac_con psse_swing 1), hold the mechanical power (the torque P_m/omega); with a
    governor PSID hands the shaft P_m/omega as stabctl does (test_pidgov.py,
    test_wpidhy.py).  psse_swing 0 holds the torque and changes nothing else at rated
    speed."""
    m = case.machines
    return case.replace(machines=m.replace(psse_swing=np.zeros_like(m.psse_swing)))


def assert_start_is_psids(sim, ref, machine=None, atol=1e-9):
    """PSID's initial point: its bus voltages (``V_R``, ``V_I``) and, with `machine` (a
    column of the machines' states), its GENROU's six states of generator-102-1 in PSID's
    order (stabctl's E'd and psi_kq in PST's sign), within atol (the power flow's
    round-off).  Returns PSID's state vector of generator-102-1 (the controls' states
    follow the machine's)."""
    m = sim.model
    np.testing.assert_allclose(sim.op.V.real, ref["V_R"], rtol=0, atol=atol)
    np.testing.assert_allclose(sim.op.V.imag, ref["V_I"], rtol=0, atol=atol)
    psid = np.array(ref.get("generator-102-1", []))
    if machine is not None:
        xm = m.layout.view(m.x0, "mac")[:, machine]
        mac = np.array([xm[2], -xm[4], xm[3], -xm[5], xm[0], xm[1]])
        np.testing.assert_allclose(mac, psid[:6], rtol=0, atol=atol)
    return psid
