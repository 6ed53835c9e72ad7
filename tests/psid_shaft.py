"""PowerSimulationsDynamics.jl's shaft for a machine without a governor, for the tests that
compare a PSS/E case without one with that program's eigenvalues (tests/models/test_scrx.py,
test_st8c.py)."""

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
