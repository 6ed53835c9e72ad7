"""A governor alone at its machine's rest point, for the governor types' closed-form tests
(tests/models/test_degov1.py, test_pidgov.py): started from one tg_con row, and settled at
a held speed by a stiff integration of its own derivatives."""

import numpy as np
from scipy.integrate import solve_ivp

from stabctl.case import GovernorTable
from stabctl.io import load_case
from stabctl.models import governors as gov


def started(row, pm0: float):
    """(params, states, P_ref) of the tg_con row on Kundur's machine 1 at mechanical power
    pm0 (machine base)."""
    case = load_case("kundur").replace(governors=GovernorTable.from_matrix([row]))
    p = gov.governor_params(case)
    x, Pref = gov.initialise(p, np.array([pm0]))
    return p, x, Pref


def settled(P, x0, omega: float, t: float):
    """The governor's states after t s at speed omega (packed parameters P, states x0), its
    electrical power at its mechanical power (LSODA, rtol 1e-10)."""

    def f(_, y):
        x = y.reshape(x0.shape).copy()
        dx = np.zeros_like(x)
        gov.derivatives(P, x, 0, omega, gov.pmech(P, x, 0, omega), dx)
        return dx.ravel()

    sol = solve_ivp(f, (0, t), x0.ravel(), method="LSODA", rtol=1e-10, atol=1e-12)
    return sol.y[:, -1].reshape(x0.shape)
