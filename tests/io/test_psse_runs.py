"""PSS/E's own runs (tests/data/psse_runs, PowerSimulationsDynamics.jl's PSS/E results,
BSD-3) repeated as a user runs them: ``stabctl import-psse RAW DYR`` with no option, then
``stabctl simulate`` with the run's line trip (the stabiliser runs: its VREF step); every
quantity within the tolerance of the Julia test that reads the run
(tests/psse_reference.py; the table: docs/psse_runs.md).

Runs still short are strict expected failures with the measured reason, so that each
flips to a failure ("XPASS(strict)") when it comes within tolerance: then remove it from
`SHORT`."""

import numpy as np
import pytest
from psse_reference import BY_NAME, DATA, RUNS, compare, psse_channels
from runs import flat_run

from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.events import LineTrip
from stabctl.errors import InputError
from stabctl.io.psse import load_psse
from stabctl.models.pss import PSS

#: run -> why it is short today (measured with benchmarks/psse_runs.py)
SHORT: dict[str, str] = {}


def _param(run):
    marks = [pytest.mark.xfail(strict=True, reason=SHORT[run.name])] if run.name in SHORT else []
    return pytest.param(run, id=run.name, marks=marks)


@pytest.mark.parametrize("run", [_param(r) for r in RUNS])
def test_run_within_the_julia_tests_tolerance(run):
    out = compare(run)
    assert not out.error, out.error
    assert out.ok(), out.shortfall()


def test_short_lists_only_runs_of_the_table():
    assert set(SHORT) <= set(BY_NAME)


def test_psse_event_rows_drop_the_pre_event_value():
    """PSS/E writes the pre-event row first at the trip (t = 0.999999 twice, V102 1.02 then
    0.989953, SEXS_RESULTS.csv); EXST1's CSV has only the pre-event row at 1 s: both
    pre-event rows are left out, the post-event one kept."""
    t, m = psse_channels(BY_NAME["SEXS"])
    assert np.count_nonzero(t == 1.0) == 1
    assert m[t == 1.0, 1] == pytest.approx(0.989953)
    t, m = psse_channels(BY_NAME["EXST1"])
    assert 1.0 not in t and 0.995 in t and 1.005 in t
    assert np.all(np.diff(t) > 0)


def test_esst1a_regulator_loop_sets_the_step():
    """PSS/E's ESST1A run: its regulator closed through the rate feedback (K_A = 200, T_A
    = 0.1 s, K_F = T_F = 0.01 s) has its pole at -1109 1/s (9.0e-4 s,
    `exst1.inner_loop_time_constants`): the case's fastest time constant, so
    without sub-intervals Heun's default step is 4.5e-4 s and PSS/E's 5 ms is refused at
    once, naming the loop, where it diverged at 0.33 s before.  With them (the default,
    `stabctl.dynamics.subinterval`) the ESST1A takes sub-steps of 4.5e-4 s within the
    data's 5 ms step, and the line trip's voltages are those of the single-rate run at
    4.5e-4 s within 2e-4 pu."""
    d = DATA / "ESST1A"
    case = load_psse(d / "TVC_System_32.raw", d / "TVC_System.dyr")
    sim = Simulator(case, subintervals=False)
    assert sim.fastest[0] == pytest.approx(1 / 1109.1, rel=1e-3)
    assert "regulator loop" in sim.fastest[1]
    trip = [LineTrip(1, 4, 1.0)]
    with pytest.raises(InputError, match=r"step 0.005 s is too large.*regulator loop"):
        sim.run(trip, 2.0, h=0.005)
    sub = Simulator(case)
    assert sub.default_h == pytest.approx(0.005)
    assert np.nanmin(sub.exciter_hmax(sub.model, 0.005)) == pytest.approx(sim.default_h)
    fine, coarse = sim.run(trip, 2.0), sub.run(trip, 2.0)
    away = np.abs(coarse.t - 1.0) > 0.01  # not across the trip's jump
    gap = max(
        np.max(np.abs(np.interp(coarse.t, fine.t, fine.vmag[:, b]) - coarse.vmag[:, b])[away])
        for b in range(case.n_bus)
    )
    print(f"\nESST1A line trip at 5 ms in sub-intervals: bus voltages {gap:.3g} pu from 4.5e-4 s")
    assert gap < 2e-4


#: the stabiliser runs: pss_con row of the machine at bus 1, as imported (type, fields)
STABILISERS = {
    # STAB1 K/T = 6, T = 1.5, T1/T3 = T2/T4 = 13.3, T3 = T4 = 0.0447, HLIM = 0.2: PST's
    # pss on the speed with K_Tw = 6 * 1.5 and leads 13.3 * 0.0447
    "STAB1": dict(type=1, KTw=9.0, Tw=1.5, T1=13.3 * 0.0447, T2=0.0447, T3=13.3 * 0.0447,
                  T4=0.0447, ymax=0.2, ymin=-0.2),
    "PSS2A": dict(type=5, input1=1, input2=3, M=5, N=1, Tw=1.5, Tw2=1.5, Tr1=0.0, Tw3=1.5,
                  Tw4=0.0, Tr2=1.5, K2=0.1875, Ks3=1.0, K1=2.0, ymax=0.1, ymin=-0.1),
    "PSS2B": dict(type=6, T5=1.0, T6=1.0, VS1MAX=0.00035, VS1MIN=-0.00055, VS2MAX=0.915,
                  VS2MIN=0.895),
    "PSS2C": dict(type=7, T12=1.0, T13=1.0, PSSON=0.895, PSSOFF=0.885, XCOMP=1.0,
                  TCOMP=1.0),
}  # fmt: skip


@pytest.mark.parametrize("name", sorted(STABILISERS))
def test_stabiliser_record_is_read_into_its_columns(name):
    """Each stabiliser run's record lands in the pss_con fields of its type (the PSS2
    records in PSS/E's order; STAB1's ratios multiplied out)."""
    run = BY_NAME[name]
    pss = load_psse(DATA / name / run.raw, DATA / name / run.dyr).pss
    assert len(pss) == 1
    for field, v in STABILISERS[name].items():
        assert pss.col(PSS.col(field))[0] == pytest.approx(v, rel=1e-15), field


@pytest.mark.parametrize("name", sorted(STABILISERS))
def test_stabiliser_run_starts_flat(name):
    """The stabiliser runs' cases at rest: no state moves by 1e-8 in 10 s without the
    VREF step (the PSS2 washouts at the initial speed and power, PSS2B's limited power
    inside [0.895, 0.915], PSS2C's switch on at 0.9 pu)."""
    run = BY_NAME[name]
    drift, _ = flat_run(load_psse(DATA / name / run.raw, DATA / name / run.dyr), t_end=10.0)
    assert drift < 1e-8


def test_st6b_record_imports_and_runs_flat():
    """PSS/E's ST6B run's DYR (tests/data/psse_runs/ST6B, no PSS/E trajectory published):
    its ST6B record imports as type 16 in the PSS/E Model Library's order (K_PA 50.038,
    K_IA 45.094, V_A on [-3.85, 4.81], K_CI 1.0577, K_LR 17.33, I_LR 2.15, T_G 0.02).  Its
    power flow starts the field current limiter's branch K_LR (K_CI I_LR - I_fd0) = 2.0959
    pu below the inner loop's V_R0 = Efd0/V_t0 = 2.1109: the start is refused by name
    (PSS/E: "initial conditions suspect"); with I_LR = 2.2 the limiter stays off and a 10 s
    run without disturbance stays at rest."""
    from runs import flat_run

    from stabctl.errors import InitialLimitError

    folder = DATA / "ST6B"
    case = load_psse(folder / "ThreeBusMulti.raw", folder / "ThreeBus_ST6B.dyr")
    e = case.exciters
    assert list(e.type) == [16]
    assert (e.Kpid_P[0], e.Kpid_I[0], e.VAmax[0], e.VAmin[0]) == (50.038, 45.094, 4.81, -3.85)
    assert (e.KCI[0], e.KLR[0], e.ILR[0], e.TG[0], e.TR[0]) == (1.0577, 17.33, 2.15, 0.02, 0.012)
    with pytest.raises(InitialLimitError, match=r"V_R = 2\.1109 .* V_R1 = 2\.0959"):
        Simulator(case, background_compile=False)
    drift, _ = flat_run(case.replace(exciters=e.replace(ILR=np.array([2.2]))), 10.0, step=0.005)
    assert drift < 1e-10
