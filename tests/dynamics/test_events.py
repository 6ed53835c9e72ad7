"""The events of a PSS/E study (`stabctl.dynamics.events`): a line closed again after a trip
or a fault's clearing, and steps of an exciter's VREF and of a governor's PREF, against
closed forms.

* A reclosed line returns the network to its pre-trip configuration: the last stage's
  configuration and reduced matrices are the initial ones, and a run settles back at the
  initial bus voltages.
* Kundur's exciters (PST's simple exciter, type 0: K_A / (1 + s T_A) on V_ref - V_t) settle
  with delta E_fd = K_A (delta V_ref - delta V_t) after a VREF step; the governors (PST's tg:
  P_ref + (1 - omega) / R through lags of unit gain) settle on the droop line delta P_m =
  delta P_ref - delta omega / R after a PREF step or a load step, at one common speed.
  Kundur's PSS washes out in T_w = 10 s: 120 s runs settle within 1e-6 pu.
"""

import numpy as np
import pytest

from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.events import (
    Fault,
    LineClose,
    LineTrip,
    LoadStep,
    PrefStep,
    VrefStep,
    stages,
)
from stabctl.dynamics.model import StageConfig
from stabctl.errors import CaseError, InputError
from stabctl.io import load_case
from stabctl.io.psse import load_psse
from tests.dynamics.test_infinite_bus import DYR, RAW

T_SETTLE = 120.0  # s: Kundur's PSS washout (10 s) decays to 6e-6 of its input
KA, INV_R = 200.0, 25.0  # Kundur's exc_con column 4 and tg_con column 4 (1 / R)


@pytest.fixture(scope="module")
def kundur():
    return Simulator(load_case("kundur"))


@pytest.fixture(scope="module")
def flat(kundur):
    return kundur.run([], t_end=T_SETTLE)


@pytest.mark.parametrize(
    "opening",
    [LineTrip(3, 101, 1.0), Fault(bus=3, t=1.0, clear_near=1.1, clear_far=1.15, far_bus=101)],
    ids=["trip", "fault"],
)
def test_a_reclosed_line_restores_the_initial_network(kundur, opening):
    events = [opening, LineClose(101, 3, 1.5)]
    starts, configs = stages(kundur.case, events, 3.0, kundur.op.V)
    assert configs[0] == StageConfig() and configs[-1] == StageConfig()
    assert configs[-2] != StageConfig()  # the line was out
    assert starts[-1] == 1.5
    model = kundur.model
    first = model.network(configs[0])
    last = model._reduce(configs[-1])  # built afresh, not the cached first stage
    for name in ("Y11", "Y12", "Y22", "R"):
        assert np.array_equal(getattr(first, name), getattr(last, name)), name


def test_a_trip_and_reclose_settles_back_at_the_initial_voltages(kundur, flat):
    res = kundur.run([LineTrip(3, 101, 1.0), LineClose(3, 101, 1.2)], t_end=T_SETTLE)
    assert np.abs(res.vmag[int(1.1 / (res.t[1] - res.t[0]))] - flat.vmag[0]).max() > 1e-3
    assert np.abs(res.vmag[-1] - flat.vmag[-1]).max() < 1e-6
    assert np.abs(res.speed[-1] - 1.0).max() < 1e-6


def test_vref_step_settles_at_the_exciter_gain(kundur, flat):
    dv = 0.01
    res = kundur.run([VrefStep(1, 1.0, dv)], t_end=T_SETTLE)
    d_efd = res.efd[-1, 0] - flat.efd[-1, 0]
    d_vt = res.vmag[-1, res.bus(1)] - flat.vmag[-1, res.bus(1)]
    assert d_efd > 0.01  # the step moved the field (0.017 pu)
    assert d_efd == pytest.approx(KA * (dv - d_vt), rel=2e-3)
    # two half steps are one step
    halves = kundur.run([VrefStep(1, 1.0, dv / 2), VrefStep(1, 1.0, dv / 2)], t_end=3.0)
    whole = kundur.run([VrefStep(1, 1.0, dv)], t_end=3.0)
    assert np.abs(halves.efd - whole.efd).max() < 1e-12


@pytest.mark.parametrize(
    "event, dpref",
    [(PrefStep(1, 1.0, 0.05), [0.05, 0, 0, 0]), (LoadStep(3, 1.0, 0.5), [0, 0, 0, 0])],
    ids=["pref", "load"],
)
def test_governors_settle_on_their_droop_line(kundur, flat, event, dpref):
    res = kundur.run([event], t_end=T_SETTLE)
    dw = res.speed[-1] - flat.speed[-1]
    assert np.ptp(dw) < 1e-8  # one speed
    assert abs(dw[0]) > 4e-4  # about dP / (4 / R) = 5e-4 pu
    assert np.sign(dw[0]) == (1 if isinstance(event, PrefStep) else -1)
    d_pm = res.pmech[-1] - flat.pmech[-1]
    np.testing.assert_allclose(d_pm, np.array(dpref) - dw * INV_R, atol=1e-6)


def test_reference_steps_need_the_controller():
    sim = Simulator(load_psse(RAW, DYR))  # GENCLS machines, no exciter or governor
    with pytest.raises(CaseError, match=r"machine 1 has no exciter"):
        sim.run([VrefStep(1, 0.5, 0.01)], t_end=1.0)
    with pytest.raises(CaseError, match=r"machine 1 has no governor"):
        sim.run([PrefStep(1, 0.5, 0.01)], t_end=1.0)


@pytest.mark.parametrize(
    "events, needle",
    [
        ([LineClose(3, 101, 1.0)], "closes it while it is not open"),
        ([LineTrip(3, 101, 1.0), LineClose(3, 101, 1.0)], "at or before"),
        (
            [
                Fault(bus=3, t=1.0, clear_near=1.1, clear_far=1.3, far_bus=101),
                LineClose(3, 101, 1.2),
            ],
            "at or before",
        ),
        (
            [LineTrip(3, 101, 1.0), LineClose(3, 101, 1.5), LineClose(3, 101, 2.0)],
            "closes it while it is not open",
        ),
        ([LineTrip(3, 101, 1.0), LineClose(3, 101, 1.5), LineTrip(3, 101, 2.0)], None),
    ],
)
def test_line_switchings_must_alternate(kundur, events, needle):
    if needle is None:  # open, close, open again: fine
        kundur.run(events, t_end=2.5)
        return
    with pytest.raises(InputError, match=needle):
        kundur.run(events, t_end=2.5)


def test_events_read_as_words_in_messages():
    """A message naming events shows them as the CLI's summary does, not as Python
    reprs: a line trip, a generator trip, a fault with its clearing, one never cleared
    and one cleared at the far end later."""
    from stabctl.dynamics.events import Fault, GeneratorTrip, LineTrip

    assert str(LineTrip(3, 101, 1.0)) == "line 3-101 (circuit 1) tripped at 1 s"
    assert str(GeneratorTrip(2, 1.5)) == "machine 2 tripped at 1.5 s"
    assert str(Fault(3, 1.0, 1.1, far_bus=101)) == (
        "3-phase fault at bus 3 at 1 s on line 3-101 (circuit 1), cleared at 1.1 s "
        "(after 100.0 ms), line tripped"
    )
    assert str(Fault(7, 1.0)) == "3-phase fault at bus 7 at 1 s, never cleared"
    assert str(Fault(3, 1.0, 1.1, 1.15, far_bus=101, circuit=2)) == (
        "3-phase fault at bus 3 at 1 s on line 3-101 (circuit 2), cleared at 1.1 s "
        "(after 100.0 ms) near / at 1.15 s (after 150.0 ms) far end, line tripped"
    )


def test_step_sizes_are_bounded_where_the_events_are_checked():
    """A run's steps are checked as the options' and a case file's are (one check,
    `stabctl.case.events.check_event` and `check_totals`): a VREF step of 1e9 pu (its
    exciter held at its ceiling, the run the same as one of 0.3 pu), a load of 1e6 pu, a
    step of 0 and PREF steps adding up beyond the machine's rating are refused when the
    run starts, naming the bound."""
    from stabctl.case.events import step_limit
    from stabctl.dynamics.events import validate

    case = load_case("kundur")
    assert step_limit(case, LoadStep(4, 1.0, 1.0)) == 36.0  # four 900 MVA machines
    assert step_limit(case, VrefStep(1, 1.0, 0.1)) == 1.0
    assert step_limit(case, PrefStep(1, 1.0, 0.1)) == 1.0  # tg_con Tmax 1
    for events, needle in (
        ([VrefStep(1, 1.0, 1e9)], r"1e\+09 pu is beyond 1 pu, the terminal voltage's"),
        ([LoadStep(4, 1.0, 1e6)], r"1e\+06 pu \(1e\+08 MVA\) is beyond 36 pu"),
        ([PrefStep(2, 1.0, 0.0)], "a step of 0 would do nothing"),
        # NaN compared false with the bound: the run went on into a "voltage collapse"
        ([LoadStep(4, 1.0, float("nan"))], "a step that is not a finite number"),
        ([VrefStep(1, 1.0, float("inf"))], "a step that is not a finite number"),
        (
            [PrefStep(2, 1.0, 0.6), PrefStep(2, 1.0, 0.6)],
            r"the PREF steps of machine 2 add up to \+1.2 pu at 1 s, beyond 1 pu",
        ),
    ):
        with pytest.raises(InputError, match=needle):
            validate(case, events, 2.0)
    validate(case, [PrefStep(2, 1.0, 0.6), PrefStep(2, 1.5, -0.6)], 2.0)  # back: fine


@pytest.mark.parametrize(
    "r, x", [(0.0, -0.05), (0.0, -1e-3), (0.0, np.inf), (np.nan, 0.0), (-0.01, 0.05)]
)
def test_a_fault_impedance_that_is_no_impedance_is_refused_by_name(kundur, r, x):
    """`Fault(3, 1.0, 1.1, x=-0.05)` stopped with ZeroDivisionError (its docstring read a
    negative x as 0 but its admittance divided by j0), and x = inf ran as no fault at
    all, without a word: r and x must be finite and >= 0 (r = x = 0 is bolted)."""
    with pytest.raises(InputError, match=r"fault impedance r = .* each must be a finite number"):
        kundur.run([Fault(3, 1.0, 1.1, r=r, x=x)], t_end=1.5)
    # an impedance fault is a fault: bus 3 sags to r + jx's share (about 0.4 pu)
    run = kundur.run([Fault(3, 1.0, 1.1, x=0.05)], t_end=1.5)
    k = np.searchsorted(run.t, 1.05)
    assert 0.05 < run.vmag[k, run.bus(3)] < 0.9


def test_a_tripped_converter_injects_nothing_from_its_trip():
    """PSS/E's MultiGen case (nine units at bus 102, two REGCA1 plants): converter 2 (the
    plant 'SW', 664 MW) tripped at 1 s (`ConverterTrip`, PSS/E's dist_machine_trip; the
    PSS/E run MULTIGEN_GEN_TRIP, tests/psse_reference.py).  Before the trip the run is
    flat at the power flow's 6.64 pu; from the trip the converter's recorded P and Q are 0
    and its states stand still, while the other plant goes on; the machines and that plant
    deliver the load at every step (a lossless network).  Tripping it twice
    or tripping a converter the case lacks is refused by name."""
    import warnings
    from pathlib import Path

    from stabctl.dynamics.events import ConverterTrip, validate
    from stabctl.io.psse import load_psse

    d = Path(__file__).resolve().parents[1] / "data" / "psse_runs" / "MULTIGEN_GEN_TRIP"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # bus 103's IDE 2 read as a load bus: named
        case = load_psse(d / "FourBusMulti.raw", d / "FourBus_multigen.dyr")
    sim = Simulator(case)
    r = sim.run([ConverterTrip(2, 1.0)], 2.0, h=0.005)
    before, after = r.t < 1.0, r.t >= 1.0
    assert np.allclose(r.ibr_p[before, 1], 6.64, atol=1e-6)
    assert np.all(r.ibr_p[after, 1] == 0.0) and np.all(r.ibr_q[after, 1] == 0.0)
    assert abs(r.ibr_p[after, 0].mean() - 2.21) < 0.05  # the other plant goes on
    # a lossless network (R = 0 everywhere, ra = 0): the machines and the plant left
    # deliver the constant-impedance load at bus 104, 47 pu at the power flow's 1.01634 pu
    v104 = r.vmag[:, list(case.buses.number).index(104)]
    load = 47.0 * (v104 / 1.01634) ** 2
    assert np.max(np.abs(r.pelect.sum(axis=1) + r.ibr_p.sum(axis=1) - load)) < 1e-3
    twice = r"converter 2 is tripped twice.*\(give each converter once\)"  # round 55 AQ04
    with pytest.raises(InputError, match=twice):
        validate(case, [ConverterTrip(2, 1.0), ConverterTrip(2, 1.5)], 2.0)
    with pytest.raises(CaseError, match="converter 9 is not in case"):
        validate(case, [ConverterTrip(9, 1.0)], 2.0)
