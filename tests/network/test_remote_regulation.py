"""Remote voltage regulation in the power flow (PSS/E's IREG and RMPCT, POM Generator
Data): a plant holds another bus's voltage at its VS, its own terminal voltage floats, the
plants regulating one bus share its reactive power in proportion to their RMPCT, and a
plant at a Q limit leaves the group (the regulated bus then floats).  The references are
those definitions and the bus power balance (conservation), on a four-bus RAW written
here."""

import numpy as np
import pytest

from stabctl.errors import CaseError
from stabctl.io.psse import import_psse
from stabctl.network.powerflow import solve_powerflow

#: swing 1 -- load bus 2 -- plants at 3 and 4 (both regulating bus 2 unless said)
RAW = """0,   100.00, 33, 0, 1, 60.00     / PSS(R)E 33 RAW
REMOTE REGULATION TEST
FOUR BUSES
    1,'SWING',230.0,3,1,1,1,1.02000,0.0
    2,'LOAD', 230.0,1,1,1,1,1.00000,0.0
    3,'GEN3',  20.0,2,1,1,1,1.00000,0.0
    4,'GEN4',  20.0,2,1,1,1,1.00000,0.0
0 / END OF BUS DATA, BEGIN LOAD DATA
    2,'1 ',1,1,1,300.0,50.0,0,0,0,0,1,1,0
0 / END OF LOAD DATA, BEGIN FIXED SHUNT DATA
0 / END OF FIXED SHUNT DATA, BEGIN GENERATOR DATA
    1,'1 ',0.0,0.0,999.0,-999.0,1.02,0,500.0,0,0.25,0,0,1.0,1,100.0,999.0,-999.0,1,1.0
    3,'1 ',100.0,0.0,{QT3},-50.0,{VS},{IREG3},200.0,0,0.2,0,0,1.0,1,{RM3},200.0,0.0,1,1.0
    4,'1 ',100.0,0.0,200.0,-50.0,{VS},{IREG4},200.0,0,0.2,0,0,1.0,1,{RM4},200.0,0.0,1,1.0
0 / END OF GENERATOR DATA, BEGIN BRANCH DATA
    1,2,'1 ',0.01,0.10,0.02,100,100,100,0,0,0,0,1,1,10.0,1,1.0
    3,2,'1 ',0.00,0.08,0.00,100,100,100,0,0,0,0,1,1,10.0,1,1.0
    4,2,'1 ',0.00,0.12,0.00,100,100,100,0,0,0,0,1,1,10.0,1,1.0
0 / END OF BRANCH DATA, BEGIN TRANSFORMER DATA
0 / END OF TRANSFORMER DATA
Q
"""


def case_of(tmp_path, *, vs=1.03, ireg3=2, ireg4=2, rm3=60.0, rm4=20.0, qt3=200.0):
    raw = tmp_path / "remote.raw"
    raw.write_text(RAW.format(VS=vs, IREG3=ireg3, IREG4=ireg4, RM3=rm3, RM4=rm4, QT3=qt3))
    return import_psse(raw)


def gen_q(pf, case, bus):
    return float(pf.qgen[case.bus_index(bus)])


def test_the_plants_hold_the_regulated_bus_and_share_by_rmpct(tmp_path):
    imp = case_of(tmp_path)
    case = imp.case
    rr = case.remote_regulation
    assert rr.bus.tolist() == [3, 4] and rr.regulated.tolist() == [2, 2]
    assert rr.share == pytest.approx([0.75, 0.25])  # 60 / (60 + 20), 20 / 80
    pf = solve_powerflow(case)
    v = dict(zip(case.buses.number.astype(int), pf.vmag))
    assert v[2] == pytest.approx(1.03, abs=1e-10)  # held at VS
    assert abs(v[3] - 1.03) > 1e-3 and abs(v[4] - 1.03) > 1e-3  # the terminals float
    assert gen_q(pf, case, 3) / gen_q(pf, case, 4) == pytest.approx(3.0, rel=1e-9)
    assert pf.kind[case.bus_index(3)] == 2 and not pf.q_limited.any()
    assert pf.max_mismatch < 1e-8


def test_a_plant_at_its_limit_leaves_the_group(tmp_path):
    """Bus 3's QT of 10 Mvar binds: it stays at 10 Mvar and bus 4 alone holds bus 2."""
    case = case_of(tmp_path, qt3=10.0).case
    pf = solve_powerflow(case)
    assert pf.q_limited[case.bus_index(3)] and not pf.q_limited[case.bus_index(4)]
    assert gen_q(pf, case, 3) == pytest.approx(0.10, abs=1e-10)
    assert pf.vmag[case.bus_index(2)] == pytest.approx(1.03, abs=1e-10)
    free = solve_powerflow(case, q_limits=False)  # without limits the shares hold again
    assert gen_q(free, case, 3) / gen_q(free, case, 4) == pytest.approx(3.0, rel=1e-9)


def test_every_plant_at_its_limit_lets_the_bus_float(tmp_path):
    """VS 1.15 asks more than both plants can give: both at QT, bus 2 below 1.15."""
    case = case_of(tmp_path, vs=1.15, qt3=10.0).case
    pf = solve_powerflow(case)
    assert pf.q_limited[case.bus_indices([3, 4])].all()
    assert pf.vmag[case.bus_index(2)] < 1.15 - 1e-3


def test_a_generator_bus_as_ireg_means_own_regulation_and_is_said(tmp_path):
    """IREG naming a generator bus: PSS/E regulates the plant's own bus; the import says so."""
    imp = case_of(tmp_path, ireg3=4, ireg4=0)
    assert len(imp.case.remote_regulation) == 0
    assert any("IREG bus 4 is a generator bus" in c for c in imp.changed)
    pf = solve_powerflow(imp.case)
    assert pf.vmag[imp.case.bus_index(3)] == pytest.approx(1.03, abs=1e-10)


def test_bad_remote_data_is_refused_by_name(tmp_path):
    """An IREG bus that is not there; an RMPCT that is not > 0 (POM: RMPCT must be
    positive), whether the plant shares a remote bus or not."""
    with pytest.raises(CaseError, match="IREG bus 9 is not in the bus data"):
        case_of(tmp_path, ireg3=9)
    with pytest.raises(CaseError, match=r"RMPCT 0\.0 must be > 0"):
        case_of(tmp_path, rm3=0.0, rm4=0.0)
    with pytest.raises(CaseError, match=r"RMPCT -5\.0 must be > 0"):
        case_of(tmp_path, rm3=-5.0)
    with pytest.raises(CaseError, match=r"RMPCT -5\.0 must be > 0"):
        case_of(tmp_path, rm3=-5.0, ireg3=0)


def test_the_case_file_keeps_the_regulation(tmp_path):
    from stabctl.io.pst import case_from_dict, case_to_dict

    case = case_of(tmp_path).case
    again = case_from_dict(case_to_dict(case))
    assert again.remote_regulation.equals(case.remote_regulation)
    pf0, pf1 = solve_powerflow(case), solve_powerflow(again)
    assert np.array_equal(pf0.vmag, pf1.vmag)
