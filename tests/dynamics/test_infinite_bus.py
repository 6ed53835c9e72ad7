"""An infinite bus (PSS/E's GENCLS with H = 0) in the multi-machine simulator: the paper's
Section 2 machine (H = 3 s, Pm = 0.5 pu, no damping) against an infinite bus, written as a
PSS/E case (tests/data/psse/smib_v33.raw, smib.dyr; delta0 = 0.455 rad from its
reactances), against the closed forms of `stabctl.smib.omib`: the equal-area CCT (paper
Section 2) and the small-signal swing frequency sqrt(omega_s Pmax cos(delta0) / 2H)."""

from pathlib import Path

import numpy as np
import pytest

from stabctl import Simulator, linearise, modal_analysis
from stabctl.dynamics.coi import coi_inertia
from stabctl.errors import CaseError
from stabctl.io.psse import load_psse
from stabctl.smib.omib import OMIB
from stabctl.stability.cct import LineFault, critical_clearing_time

DATA = Path(__file__).parents[1] / "data" / "psse"
RAW, DYR = DATA / "smib_v33.raw", DATA / "smib.dyr"
H, PM = 3.0, 0.5  # the DYR's machine (s, 100 MVA) and the RAW's dispatch (pu)


@pytest.fixture(scope="module")
def sim():
    return Simulator(load_psse(RAW, DYR))


def omib_of(sim) -> OMIB:
    """The OMIB of the simulated operating point: Pmax from Pm and the angle between the
    machine's and the infinite bus's internal voltages (paper eq. 1)."""
    delta = sim.model.x0[:2]  # the machines' rotor angles, rad
    return OMIB.from_operating_point(H=H, Pm=PM, delta0=float(delta[0] - delta[1]))


def test_infinite_bus_holds_its_angle_and_speed_and_is_the_coi(sim):
    assert list(sim.case.machines.H) == [H, 0.0]
    assert list(coi_inertia(sim.case.machines.H, sim.case.machines.mva)) == [0.0, 1.0]
    res = sim.run(LineFault(1, None).events(0.2), 3.0)
    assert np.ptp(res.speed[:, 0]) > 1e-3  # the machine swings
    assert np.ptp(res.speed[:, 1]) == 0.0 and np.ptp(res.angle[:, 1]) == 0.0
    assert np.all(res.speed[:, 1] == 1.0)


def test_cct_equals_the_equal_area_criterion(sim):
    """Bolted fault at the machine's bus, cleared without loss of the line: Pmax_fault =
    0 and the closed form t_cr = sqrt(2 M (delta_cr - delta0) / Pm)."""
    cct = critical_clearing_time(sim, LineFault(1, None))
    t_eac = omib_of(sim).critical_clearing_time()  # 0.2564 s
    assert cct.t_stable <= t_eac < cct.t_unstable  # [0.256, 0.257) s against 0.25639 s
    assert cct.separated == (1,)  # the machine leaves the infinite bus


def test_swing_mode_equals_the_closed_form(sim):
    """One mode, lambda = +-j sqrt(omega_s Pmax cos(delta0) / 2H), and no angle-reference
    mode: the infinite bus's angle is the reference, not a state."""
    sys = linearise(sim)
    assert sys.nstates == 2
    ma = modal_analysis(sys)
    assert ma.reference_mode is None
    o = omib_of(sim)
    w = np.sqrt(o.omega_s * o.Pmax_pre * np.cos(o.delta0) / (2 * H))  # rad/s
    (lam,) = ma.eigenvalues
    assert abs(lam - 1j * w) < 1e-7 * w  # measured 8.4e-10 (central differences)


def test_an_infinite_bus_must_be_classical_with_a_source_reactance(tmp_path):
    raw = tmp_path / "smib.raw"
    raw.write_text(RAW.read_text().replace("1.00000E-2, 0.00000E+0", "0.00000E+0, 0.00000E+0"))
    with pytest.raises(CaseError, match=r"infinite bus \(H = 0\) needs its source reactance"):
        load_psse(raw, DYR)
    dyr = tmp_path / "smib.dyr"
    dyr.write_text(
        DYR.read_text().replace(
            "2 'GENCLS' 1   0.0  0.0 /",
            "2 'GENROU' 1 8.0 0.03 0.4 0.05 0.0 0.0 1.8 1.7 0.3 0.55 0.25 0.06 0.0 0.0 /",
        )
    )
    with pytest.raises(CaseError, match=r"GENROU.*H = 0.0: a machine of this model needs H > 0"):
        load_psse(RAW, dyr)
