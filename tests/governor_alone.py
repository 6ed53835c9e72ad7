"""A governor alone at its machine's rest point, for the governor types' closed-form tests
(tests/models/test_degov1.py, test_pidgov.py, test_wpidhy.py, test_ieeeg2.py,
test_ieeeg3.py): started from one tg_con row, and settled at a held speed by a stiff
integration of its own derivatives; and PSS/E's ThreeBus case with a governor record
instead of its WPIDHY, for the types checked against their block diagram's closed form."""

from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from stabctl.case import GovernorTable
from stabctl.dynamics.driver import Simulator
from stabctl.io import load_case
from stabctl.io.psse import load_psse
from stabctl.models import governors as gov


def governor_row(case, **changed) -> list:
    """The first governor row of `case` (gov_con values, in column order) with the fields
    `changed` (by name) replaced."""
    g = case.governors
    row = [float(getattr(g, name)[0]) for name in g.columns()]
    for name, value in changed.items():
        row[gov.GOVERNOR.col(name) - 1] = value
    return row


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


def frequency_response(P, x0, freqs_hz):
    """The governor's response of P_m to the speed at each frequency (Hz) and its
    steady-state gain: its derivatives and output linearised at x0 by central differences
    (exact for linear blocks), H(s) = C (sI - A)^-1 B + D; P packed parameters."""
    n, h = x0.shape[0], 1e-7

    def f(x, omega):
        dx = np.zeros_like(x)
        gov.derivatives(P, x, 0, omega, gov.pmech(P, x, 0, omega), dx)
        return dx[:, 0], gov.pmech(P, x, 0, omega)

    A, C = np.zeros((n, n)), np.zeros(n)
    for j in range(n):
        xp, xm = x0.copy(), x0.copy()
        xp[j, 0] += h
        xm[j, 0] -= h
        (fp, yp), (fm, ym) = f(xp, 1.0), f(xm, 1.0)
        A[:, j], C[j] = (fp - fm) / (2 * h), (yp - ym) / (2 * h)
    (fp, yp), (fm, ym) = f(x0.copy(), 1.0 + h), f(x0.copy(), 1.0 - h)
    B, D = (fp - fm) / (2 * h), (yp - ym) / (2 * h)
    H = [C @ np.linalg.solve(2j * np.pi * fr * np.eye(n) - A, B) + D for fr in freqs_hz]
    return np.array(H), -C @ np.linalg.solve(A, B) + D


#: PSS/E's ThreeBus WPIDHY run (its RAW, and its DYR as the base of `threebus_dyr`)
WPIDHY = Path(__file__).parent / "data" / "psse_runs" / "WPIDHY"


def threebus_dyr(tmp_path, record: str, values: dict) -> Path:
    """PSS/E's ThreeBus WPIDHY run's DYR with governor `record` (its CONs `values` in
    order) instead of the WPIDHY, written under tmp_path."""
    text = (WPIDHY / "ThreeBus_WPIDHY.dyr").read_text()
    head = text[: text.index("    102 'WPIDHY'")]
    path = tmp_path / f"ThreeBus_{record}.dyr"
    cons = " ".join(f"{x:g}" for x in values.values())
    path.write_text(f"{head}    102 '{record}' 1 {cons} /\n")
    return path


def threebus_fixture(record: str, values: dict):
    """A module-scoped fixture ``imported``: PSS/E's ThreeBus WPIDHY run's RAW with
    `threebus_dyr`'s DYR (governor `record`, its CONs `values` in order), loaded by
    `load_psse`; assign it to ``imported`` in the test module."""

    @pytest.fixture(scope="module", name="imported")
    def imported(tmp_path_factory):
        dyr = threebus_dyr(tmp_path_factory.mktemp(record.lower()), record, values)
        return load_psse(WPIDHY / "ThreeBusMulti.raw", dyr)

    return imported


def initial_residual(case):
    """The whole case's largest derivative at its initial point and where it is (the
    simulator's ``model.initial_residual``): 0 at rest."""
    return Simulator(case, background_compile=False).model.initial_residual


#: the frequencies (Hz) of the closed-form frequency-response tests, 0.01 to 10 Hz
FREQS = (0.01, 0.1, 0.5, 1.0, 3.0, 10.0)


def response_at_rest(case, pm0: float, freqs=FREQS):
    """`frequency_response` at freqs (Hz) of the first governor row of `case` started at
    mechanical power pm0 (`started`, P_ref its rest value): (H, steady-state gain)."""
    p, x0, Pref = started(governor_row(case), pm0)
    return frequency_response(p.packed(Pref), x0, freqs)
