"""The public API's entry points refuse an argument of the wrong kind with a TypeError
naming the function and the argument: a case's name where a `Case` is needed failed deep
inside ("'str' object has no attribute 'branches'")."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import stabctl
from stabctl.errors import CaseError, InputError, UnknownBusError
from stabctl.stability.cct import SearchOptions


@pytest.fixture(scope="module")
def kundur():
    return stabctl.load_case("kundur")


@pytest.mark.parametrize(
    "call, said",
    [
        (lambda c: stabctl.Simulator("kundur"), r"Simulator\(case\): a stabctl Case is needed"),
        (lambda c: stabctl.Simulator(None), r"Simulator\(case\): .* got NoneType$"),
        (lambda c: stabctl.solve_powerflow("kundur"), r"solve_powerflow\(case\): .* got str"),
        (lambda c: stabctl.linearise("kundur"), r"linearise\(target\): a stabctl Case or Sim"),
        (lambda c: stabctl.uniform_fleet("kundur", 5), r"uniform_fleet\(case\)"),
        (lambda c: stabctl.uniform_fleet(c, "5"), r"uniform_fleet\(pct\): a number of %"),
        (lambda c: stabctl.modal_analysis(c.branches.x), r"modal_analysis\(sys\): a control"),
        (
            lambda c: stabctl.critical_clearing_time(c, stabctl.LineFault(3, 101)),
            r"critical_clearing_time\(sim\): a Simulator is needed .* got Case",
        ),
    ],
)
def test_an_argument_of_the_wrong_kind_is_named(kundur, call, said):
    with pytest.raises(TypeError, match=said):
        call(kundur)


def test_a_case_s_name_is_pointed_to_load_case():
    with pytest.raises(TypeError, match=r"load it first: stabctl.load_case\('kundur'\)"):
        stabctl.Simulator("kundur")


def test_a_cct_search_names_a_fault_of_the_wrong_kind(kundur):
    sim = stabctl.Simulator(kundur)
    with pytest.raises(TypeError, match=r"critical_clearing_time\(fault\): a LineFault"):
        stabctl.critical_clearing_time(sim, "3-101")


def test_coi_speed_is_the_inertia_weighted_mean_and_refuses_weights_that_are_none():
    """Paper eq. 40; all-zero weights divided by zero, a negative one gave a COI speed
    outside every machine's, a weight per wrong axis broadcast or failed in numpy."""
    import numpy as np

    speed = np.array([[1.0, 1.01], [0.99, 1.0]])
    np.testing.assert_allclose(stabctl.coi_speed(speed, np.array([1.0, 3.0])), [1.0075, 0.9975])
    for weights, said in (
        ([0.0, 0.0], "not all 0"),
        ([1.0, -1.0], ">= 0"),
        ([1.0, np.nan], "finite"),
        ([1.0, 1.0, 1.0], "one weight per machine"),
    ):
        with pytest.raises(ValueError, match=said):
            stabctl.coi_speed(speed, np.array(weights))


@pytest.mark.parametrize("field", ["H", "Pm", "Pmax_pre", "Pmax_post", "D", "f0"])
def test_an_omib_parameter_that_is_not_a_number_is_refused(field):
    """NaN compared false with every bound: an OMIB with Pm NaN was made, and failed
    later, in its CCT."""
    given = dict(H=3.0, Pm=0.5, Pmax_pre=1.0, Pmax_fault=0.0, Pmax_post=1.0)
    given[field] = float("nan")
    with pytest.raises(stabctl.errors.InputError, match=f"not a finite number: {field} = nan"):
        stabctl.OMIB(**given)


@pytest.mark.parametrize("kw", [{"max_iter": 0}, {"max_iter": 2.5}, {"tol": 0.0}, {"tol": 5.0}])
def test_a_power_flow_s_settings_out_of_range_are_named(kundur, kw):
    """`max_iter=0` was reported as a power flow that did not converge."""
    with pytest.raises(stabctl.errors.InputError, match=r"tol must be in .* max_iter an int"):
        stabctl.solve_powerflow(kundur, **kw)


@pytest.mark.parametrize(
    "kw, said",
    [
        ({"events": "3"}, r"run\(events\): a list of events .* got '3' \(str\)"),
        ({"events": [None]}, r"run\(events\): .* got NoneType None"),
        ({"storage": "5%"}, r"run\(storage\): a StorageFleet is needed .* got str"),
    ],
)
def test_a_run_names_events_and_storage_of_the_wrong_kind(kundur, kw, said):
    """A str or None among the events failed on ``.times()``, a str for the storage on
    ``.model``: AttributeErrors from inside the simulator."""
    with pytest.raises(TypeError, match=said):
        stabctl.Simulator(kundur).run(t_end=0.2, **kw)


def test_an_omib_parameter_that_is_no_number_is_named():
    with pytest.raises(TypeError, match="OMIB: not a number: H = '3'"):
        stabctl.OMIB(H="3", Pm=0.5, Pmax_pre=1.0, Pmax_fault=0.0, Pmax_post=1.0)


def test_an_omib_whose_fault_raises_the_transfer_capability_is_refused():
    """Pmax_fault 2.0 above Pmax_pre 1.5 was accepted (round 29): no fault does that."""
    with pytest.raises(InputError, match=r"Pmax_fault = 2\.0 pu above Pmax_pre = 1\.5 pu"):
        stabctl.OMIB(H=3.5, Pm=0.8, Pmax_pre=1.5, Pmax_fault=2.0, Pmax_post=1.2)


def test_a_file_that_is_no_result_is_named_not_read_as_a_pickle(tmp_path):
    """`SimulationResult.from_npz` of a text file gave numpy's "contains pickled (object)
    data ... load it unsafely" (round 29), inviting allow_pickle, naming no file."""
    from stabctl.dynamics.results import SimulationResult

    text, array = tmp_path / "r.npz", tmp_path / "a.npy"
    text.write_text("hello")
    np.save(array, np.arange(3))
    for path, why in ((text, "not an npz archive"), (array, "one .npy array")):
        with pytest.raises(InputError, match=rf"{path.name}: not a result .* \({why}"):
            SimulationResult.from_npz(path)


def test_a_result_file_with_other_arrays_a_pickle_or_a_bomb_is_refused_by_name(tmp_path):
    """Round 34: an npz holding an object (pickled) array raised numpy's words ("Object
    arrays cannot be loaded when allow_pickle=False"), one with an array `to_npz` does not
    write or without those it writes a TypeError of the class, and a 2 MB file whose
    array unpacks to 2 GiB was read whole.  Each is an InputError naming the file."""
    import zipfile

    from stabctl.dynamics import results
    from stabctl.dynamics.results import SimulationResult

    base = dict(t=np.arange(3.0), verdict=np.array([1.0, np.nan]), separated=np.array([], int))
    obj = tmp_path / "obj.npz"
    np.savez(obj, **base, extra=np.array([{"a": 1}], dtype=object))
    with pytest.raises(InputError, match=r"obj.npz: array 'extra' holds Python objects"):
        SimulationResult.from_npz(obj)
    odd = tmp_path / "odd.npz"
    np.savez(odd, **base, zzz=np.arange(2))
    with pytest.raises(InputError, match=r"odd.npz: .*arrays it does not write: zzz; no angle,"):
        SimulationResult.from_npz(odd)
    bomb = tmp_path / "bomb.npz"
    with zipfile.ZipFile(bomb, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("t.npy", bytes(1 << 20))  # 1 MiB of zeros packs into about 1 kB
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(results, "BOMB_BYTES", 1 << 19)
        with pytest.raises(InputError, match=r"bomb.npz: its arrays unpack to 1048576 bytes"):
            SimulationResult.from_npz(bomb)


@pytest.mark.parametrize(
    "change, said",
    [
        (lambda z: z.update(verdict=np.array([1.0])), r"'verdict' has shape \(1,\)"),
        (lambda z: z.update(t=np.array("abc")), r"'t' is not a time axis"),
        (lambda z: z.update(speed=z["speed"][:, :3]), r"'speed' has shape \(\d+, 3\), not"),
        (lambda z: z.update(verdict=np.array([np.nan, np.nan])), r"'verdict' holds \[nan, nan\]"),
        (lambda z: z.update(t=z["t"][::-1].copy()), r"'t' is not a time axis"),
    ],
    ids=["verdict short", "t a text", "a machine short", "verdict NaN", "t backwards"],
)
def test_a_result_file_whose_arrays_are_damaged_is_refused_by_name(kundur, tmp_path, change, said):
    """Round 45: `from_npz` checked the arrays' names, not their contents: a short verdict
    or a text time axis raised numpy's errors from deep inside, a machine's column cut
    away, a NaN verdict or a time axis backwards were read as a run and its verdict."""
    from stabctl.dynamics.results import SimulationResult

    res = stabctl.Simulator(kundur).run([], t_end=0.2)
    z = dict(np.load(res.to_npz(tmp_path / "ok.npz")))
    change(z)
    np.savez(tmp_path / "bad.npz", **z)
    with pytest.raises(InputError, match=r"bad.npz: array " + said):
        SimulationResult.from_npz(tmp_path / "bad.npz")


@pytest.mark.parametrize(
    "call, said",
    [
        # a text is true to Python: "no" turned the Q limits and the stop on
        (lambda c, s: stabctl.Simulator(c, q_limits="no"), r"Simulator\(q_limits\) must be True"),
        (
            lambda c, s: s.run([], t_end=1.0, stop_at_separation="no"),
            r"run\(stop_at_separation\) must be True or False, got 'no'",
        ),
        # "13" recorded buses 1 and 3
        (lambda c, s: s.run([], t_end=1.0, voltages="13"), r"got the text '13'"),
        # any other value than "hv" put the devices at the terminals
        (lambda c, s: stabctl.uniform_fleet(c, 5, at="foo"), r"'hv' or 'terminal', got 'foo'"),
        # a Simulator keeps its own conventions, but "foo" is none
        (lambda c, s: stabctl.linearise(s, conventions="foo"), r"conventions must be one of"),
        (
            lambda c, s: stabctl.StorageDevice(3, None, float("inf")),
            r"rating must be a finite number > 0 MW, got inf",
        ),
        # a text bus list was read one character a bus, True as bus 1
        (
            lambda c, s: stabctl.linearise(s, esd_buses="13"),
            r"linearise\(esd_buses\): bus numbers, got the text '13'",
        ),
        (
            lambda c, s: stabctl.Simulator(c, injection_buses="13"),
            r"Simulator\(injection_buses\): bus numbers, got the text '13'",
        ),
        (
            lambda c, s: s.run([stabctl.Fault(True, 1.0, 1.1)], t_end=2.0),
            r"Fault\(bus\): a whole number is needed, got True \(bool\)",
        ),
        # "a run to nan s needs nan steps, more than the limit"
        (lambda c, s: s.run([], t_end=float("nan")), r"run\(t_end\): a finite time in s"),
    ],
)
def test_a_value_that_would_mean_something_else_is_refused(kundur, call, said):
    """Values taken without a word though they meant another setting than the one given."""
    with pytest.raises(InputError, match=said):
        call(kundur, stabctl.Simulator(kundur))


def test_modal_weights_must_be_one_finite_weight_per_machine(kundur):
    """NaN among the weights went on into the area momentum (NaN eta); too few broadcast
    in numpy."""
    import numpy as np

    sys_ = stabctl.linearise(stabctl.Simulator(kundur))
    for weights in (np.array([1.0, np.nan, 1.0, 1.0]), np.ones(2), -np.ones(4)):
        with pytest.raises(InputError, match=r"4 finite weights >= 0"):
            stabctl.modal_analysis(sys_, inertia=weights)
    ma = stabctl.modal_analysis(sys_, inertia=np.ones(4))
    assert ma.kind[ma.electromechanical[0]] == "inter-area"  # Kundur's 0.61 Hz mode


def _sim(kundur):
    return stabctl.Simulator(kundur, background_compile=False)


@pytest.mark.parametrize(
    "call, said",
    [
        # a text where a number goes: failed in numpy or in a comparison, unnamed
        (lambda c: stabctl.solve_powerflow(c, tol="1e-8"), r"solve_powerflow\(tol\): a number"),
        (lambda c: stabctl.Simulator(c, step="0.005"), r"Simulator\(step\): a number of s"),
        (lambda c: stabctl.Fault(3, "1.0"), r"Fault\(t\): a number"),
        (lambda c: stabctl.LineFault(3, 101, "1.0"), r"LineFault\(t_fault\): a number"),
        (lambda c: stabctl.StorageDevice(3, None, "5"), r"StorageDevice\(pmax_mw\): a number"),
        (lambda c: SearchOptions(tol="0.001"), r"SearchOptions\(tol\): a number"),
        (lambda c: stabctl.BangBangCOI(deadband_hz="0.1"), r"BangBangCOI\(deadband_hz\)"),
        (
            lambda c: stabctl.fault_with_clearing(c, 3, 101, 1.0, "6"),
            r"fault_with_clearing\(clear_cycles\): a number of cycles",
        ),
        (lambda c: stabctl.coi_speed("x", [1.0]), r"coi_speed: speed and inertia must be"),
        # a text where a bus number goes: Fault('3', ...) ran as bus 3
        (lambda c: stabctl.Fault("3", 1.0, 1.1), r"Fault\(bus\): a whole number is needed"),
        (lambda c: stabctl.Fault(3.5, 1.0, 1.1), r"Fault\(bus\): a whole number .* 3.5"),
        (lambda c: stabctl.LineFault(3, "101"), r"LineFault\(far_bus\): a whole number"),
        (lambda c: stabctl.StorageDevice("3", None, 5.0), r"StorageDevice\(bus\): a whole"),
        (lambda c: stabctl.LineTrip(3, 101, None), r"LineTrip\(t\): a number .* \(NoneType\)"),
        # a number or a text where a list goes
        (lambda c: stabctl.solve_powerflow(c, drop=5), r"solve_powerflow\(drop\): a list of"),
        (lambda c: stabctl.solve_powerflow(c, drop="3-101"), r"solve_powerflow\(drop\): a list"),
        (
            lambda c: stabctl.solve_powerflow(c, drop=[(3, 101)]),
            r"solve_powerflow\(drop\): 0-based rows .* case.circuit_row",
        ),
        (lambda c: stabctl.LineFault(3, 101, trips="1-2"), r"LineFault\(trips\): a list of"),
        (lambda c: stabctl.LineFault(3, 101, trips=[(1, 2, 3)]), r"LineFault\(trips\): each"),
        (lambda c: stabctl.StorageFleet(devices=(1, 2)), r"StorageFleet\(devices\): each a"),
        (lambda c: stabctl.StorageFleet(devices=5), r"StorageFleet\(devices\): a list of"),
        (lambda c: stabctl.BangBangCOI(coi="critical", critical="12"), r"BangBangCOI\(critical\)"),
        # another object where a settings object or a function goes
        (lambda c: stabctl.Simulator(c, op="x"), r"Simulator\(op\): an OperatingPoint"),
        (lambda c: stabctl.StorageFleet(controller="bangbang"), r"StorageFleet\(controller\)"),
        (lambda c: stabctl.uniform_fleet(c, 5, controller="x"), r"uniform_fleet\(controller\)"),
        (lambda c: SearchOptions(criterion=5), r"SearchOptions\(criterion\): a func"),
        (lambda c: stabctl.fault_with_clearing("kundur", 3, 101, 1.0, 6), r"\(case\): a stab"),
    ],
)
def test_an_argument_of_another_type_is_refused_naming_it(kundur, call, said):
    """A text where a number goes, a number where a list goes, another object where a
    settings object goes: each refused naming its function or class and the argument
    (round-27 probes; before, numpy's or Python's own words, or a silent run)."""
    with pytest.raises(TypeError, match=said) as caught:
        call(kundur)
    assert isinstance(caught.value, InputError)  # the CLI's clean exit too


def test_a_run_and_a_search_name_their_arguments_of_another_type(kundur):
    sim = _sim(kundur)
    fault = stabctl.Fault(3, 1.0, 1.1, far_bus=101)
    with pytest.raises(TypeError, match=r"run\(events\): a list of events"):
        sim.run(5, t_end=2)
    with pytest.raises(TypeError, match=r"run\(monitor\): a function or None"):
        sim.run([fault], t_end=2, monitor=5)
    with pytest.raises(TypeError, match=r"run\(h\): a number of s"):
        sim.run([fault], t_end=2, h="0.005")
    with pytest.raises(TypeError, match=r"critical_clearing_time\(search\): SearchOptions"):
        stabctl.critical_clearing_time(sim, stabctl.LineFault(3, 101), "bisection")


def test_fault_with_clearing_checks_its_fault_against_the_case(kundur):
    """It takes the case: an unknown bus, a missing circuit or a time that is not finite
    was accepted there and refused only when a run started."""
    with pytest.raises(UnknownBusError, match="999"):
        stabctl.fault_with_clearing(kundur, 999, 101, 1.0, 6)
    with pytest.raises(UnknownBusError, match="999"):
        stabctl.fault_with_clearing(kundur, 3, 999, 1.0, 6)
    with pytest.raises(CaseError, match="circuit 9"):
        stabctl.fault_with_clearing(kundur, 3, 101, 1.0, 6, circuit=9)
    with pytest.raises(InputError, match="clear_cycles"):
        stabctl.fault_with_clearing(kundur, 3, 101, 1.0, float("nan"))
    with pytest.raises(InputError, match="not a finite number"):
        stabctl.fault_with_clearing(kundur, 3, 101, float("nan"), 6)
    # as the CLI refuses them (round 29): a fault of no length, a circuit of a bus fault
    with pytest.raises(InputError, match="a fault of no length would do nothing"):
        stabctl.fault_with_clearing(kundur, 3, 101, 1.0, 0)
    with pytest.raises(InputError, match=r"circuit 2 given without far_bus"):
        stabctl.fault_with_clearing(kundur, 3, None, 1.0, 6, circuit=2)
    fault = stabctl.fault_with_clearing(kundur, 3, 101, 1.0, 6, far_clear_cycles=9)
    assert (fault.clear_near, fault.clear_far) == pytest.approx((1.1, 1.15))  # 60 Hz


def test_bus_numbers_held_as_floats_by_the_case_tables_stay_accepted(kundur):
    """The case tables hold bus numbers as float64: a fault built from them is bus 3, held
    and shown as an integer ("bus 3.0" and "line 3.0-101" were shown, round 29)."""
    bus = kundur.buses.number[kundur.bus_indices([3])[0]]
    assert isinstance(bus, float) or bus.dtype.kind == "f"
    fault = stabctl.LineFault(bus, np.float64(101), trips=[(13.0, 14.0)])
    assert fault.describe() == "fault at bus 3 on line 3-101 at 1 s, 13-14 also opened"
    assert [type(v) for v in (fault.bus, fault.far_bus, *fault.trips[0])] == [int] * 4
    event = stabctl.fault_with_clearing(kundur, 3.0, 101.0, 1.0, 5)
    assert str(event).startswith("3-phase fault at bus 3 at 1 s on line 3-101 (circuit 1)")


@pytest.mark.parametrize(
    "call, error, said",
    [
        # round-28 probes: numpy's scalars and arrays, NaN, values out of their range
        (lambda c, s: s.run([], t_end=1.0, separation_limit="3.14"), TypeError, "a number of rad"),
        (
            lambda c, s: s.run([], t_end=1.0, separation_limit=np.bool_(True)),
            TypeError,
            r"separation limit \(separation_limit\): a number",
        ),
        (
            lambda c, s: stabctl.StorageDevice(3, None, 10.0, lag_s=float("nan")),
            InputError,
            "lag >= 0",
        ),
        (lambda c, s: stabctl.LineFault(3, 101, float("nan")), InputError, r"LineFault\(t_fault\)"),
        (
            lambda c, s: stabctl.linearise(s, esd_buses=np.array(3)),
            TypeError,
            r"linearise\(esd_buses\): bus numbers \(one row\)",
        ),
        (
            lambda c, s: stabctl.linearise(s, esd_buses=[10, 20.5]),
            TypeError,
            r"linearise\(esd_buses\): bus numbers, got 20.5 \(float\) among them",
        ),
        (
            lambda c, s: s.run([], t_end=1.0, voltages=[3.5]),
            TypeError,
            r"run\(voltages\): True, False or bus numbers, got 3.5",
        ),
        (
            lambda c, s: stabctl.modal_analysis(None, n_areas=np.bool_(True)),
            TypeError,
            r"modal_analysis\(n_areas\): a whole number",
        ),
        (lambda c, s: stabctl.modal_analysis(None, areas="1,2"), TypeError, r"\(areas\): a dict"),
        (lambda c, s: stabctl.OMIB(3.5, 0.8, 1.5, 0.0, 1.2, k_C=-1), InputError, r"k_C must be"),
        (lambda c, s: stabctl.load_case(b"/x.json"), TypeError, r"load_case\(name_or_path\)"),
        (
            lambda c, s: stabctl.Playback(1, np.zeros((2, 2)), (0, 0), (0, 0)),
            TypeError,
            r"Playback\(at\): a number",
        ),
        (lambda c, s: stabctl.Playback(1, "abc", "abc", "abc"), TypeError, r"Playback\(at\)"),
        (
            lambda c, s: stabctl.Playback(1, (0.0, 1.0, 0.5), (0, 0, 0), (0, 0, 0)),
            InputError,
            r"the times \(at\) must rise",
        ),
        (
            lambda c, s: stabctl.Playback(1, (0.0, 1.0), (0.0,), (0.0, 0.0)),
            InputError,
            r"one dV and one df per time, at least one \(at 2, dV 1, df 2\)",
        ),
    ],
)
def test_numpy_scalars_nan_and_ranges_are_refused_naming_the_argument(kundur, call, error, said):
    with pytest.raises(error, match=said):
        call(kundur, stabctl.Simulator(kundur, background_compile=False))


def test_a_fleet_built_for_another_case_is_refused(kundur):
    """A fleet carried no case: Kundur's uniform fleet ran on miniWECC without a word, its
    devices on miniWECC's buses 10, 20, 110 and 120 driven by its machines 1-4 (round
    29).  Its machines' buses are kept (`StorageFleet.machines_at`) and checked."""
    wecc = stabctl.load_case("miniwecc")
    fault = stabctl.fault_with_clearing(wecc, 83, 33, 1.0, 6)
    with pytest.raises(CaseError, match=r"fleet built for a case whose machine 2 is at bus 2"):
        stabctl.Simulator(wecc).run([fault], t_end=1.2, storage=stabctl.uniform_fleet(kundur, 5))
    own = stabctl.uniform_fleet(wecc, 5)
    assert own.machines_at[:2] == ((1, 1), (2, 3))
    assert stabctl.Simulator(wecc).run([fault], t_end=1.2, storage=own).stable


def test_a_run_ending_with_its_fault_still_on_is_warned_of(kundur):
    """`run(t_end=1.05)` of a fault cleared at 1.1 s reported "stable" without a word, a
    verdict of the fault held on (round 29; the CLI refuses it).  A warning says so; a
    fault never cleared (no clearing time) is meant so and is not warned of."""
    sim = stabctl.Simulator(kundur)
    with pytest.warns(RuntimeWarning, match=r"run ends at 1\.05 s with a fault still on"):
        sim.run([stabctl.fault_with_clearing(kundur, 3, 101, 1.0, 6)], t_end=1.05)
    held = stabctl.Fault(bus=3, t=1.0)  # never cleared
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sim.run([held], t_end=1.05)


# -- the studies' settings and the screening (probe round 31) ---------------------------


@pytest.mark.parametrize(
    "kw, said",
    [
        ({"workers": 2.5}, r"RunnerOptions\(workers\): a whole number"),  # ran on 2
        ({"workers": float("nan")}, r"RunnerOptions\(workers\)"),
        ({"workers": True}, r"RunnerOptions\(workers\)"),
        ({"workers": "2"}, r"RunnerOptions\(workers\)"),
        ({"workers": 0}, r"RunnerOptions\(workers\): workers must be >= 1"),
        ({"scheduler": 8786}, r"RunnerOptions\(scheduler\): an address"),
        ({"progress": "no"}, r"RunnerOptions\(progress\): True \(a bar\)"),  # drew a bar
    ],
)
def test_runner_options_refuse_what_cannot_be_meant(kw, said):
    from stabctl.parallel import RunnerOptions

    with pytest.raises(InputError, match=said):
        RunnerOptions(**kw)


def test_runner_options_hold_a_whole_float_as_a_count():
    from stabctl.parallel import RunnerOptions

    assert RunnerOptions(workers=2.0).workers == 2
    assert type(RunnerOptions(workers=np.int64(3)).workers) is int
    assert RunnerOptions(progress=lambda done, total: None).workers is None


@pytest.mark.parametrize(
    "kw, said",
    [
        ({"max_iter": 0}, r"PlaceOptions\(max_iter\): must be >= 1"),
        ({"max_iter": 2.5}, r"PlaceOptions\(max_iter\): a whole number"),
        ({"max_sites": -1}, r"PlaceOptions\(max_sites\)"),
        ({"zeta_min": float("nan")}, r"PlaceOptions\(zeta_min\)"),
        ({"amplitude_hz": 0.0}, r"PlaceOptions\(amplitude_hz\): the amplitude must be > 0"),
        ({"rtol": -0.1}, r"PlaceOptions\(rtol\)"),  # ran, as 0 would
        ({"safety_s": -0.01}, r"PlaceOptions\(safety_s\)"),
    ],
)
def test_place_options_are_checked_when_made(kw, said):
    from stabctl.placement.loop import PlaceOptions

    with pytest.raises(InputError, match=said):
        PlaceOptions(**kw)


@pytest.mark.parametrize(
    "kw, said",
    [
        ({"load_levels": ()}, r"load_levels: load levels must be numbers > 0, got \[\]"),
        ({"load_levels": (float("nan"),)}, r"load levels must be numbers > 0"),
        ({"load_levels": "1.0"}, r"load_levels: a list of load levels"),
        ({"n_active": 0}, r"PlanOptions\(n_active\): must be >= 1"),
        ({"max_rounds": 0}, r"PlanOptions\(max_rounds\): must be >= 1"),
        ({"half_step_n": -1}, r"PlanOptions\(half_step_n\)"),
        ({"margins_tol": 0.0}, r"PlanOptions\(margins_tol\): must be > 0 s"),
        ({"place": 6}, r"PlanOptions\(place\): PlaceOptions"),
    ],
)
def test_plan_options_are_checked_when_made(kw, said):
    from stabctl.placement.plan import PlanOptions

    with pytest.raises(InputError, match=said):
        PlanOptions(**kw)


def test_plan_options_hold_each_load_level_once_as_a_float():
    from stabctl.placement.plan import PlanOptions

    assert PlanOptions(load_levels=[1, 1.0, np.float32(0.5)]).load_levels == (1.0, 0.5)


@pytest.mark.parametrize(
    "kw, said",
    [
        ({"buses": "13"}, r"screen\(buses\): bus numbers, got the text '13'"),  # buses 1, 3
        ({"buses": [True]}, r"screen\(buses\): bus numbers, got True"),  # bus 1
        ({"buses": [3, 3]}, r"screen\(buses\): bus 3 given twice"),
        ({"buses": []}, r"nothing to screen \(buses=\[\] and lines=False\)"),
        ({"buses": [3], "lines": "no"}, r"screen\(lines\) must be True or False"),  # ran lines
        ({"buses": [3], "retry_failed": 1}, r"screen\(retry_failed\)"),
        ({"buses": [3], "search": {"tol": 0.001}}, r"screen\(search\): SearchOptions"),
        ({"buses": [3], "runner": 1}, r"screen\(runner\): RunnerOptions"),
    ],
)
def test_screen_refuses_arguments_it_cannot_mean_before_any_run(tmp_path, kw, said):
    from stabctl.stability.screening import screen

    out = tmp_path / "s.jsonl"
    with pytest.raises(InputError, match=said):
        screen("kundur", out, **kw)
    assert not out.exists()


def test_screen_refuses_an_output_that_is_no_path():
    from stabctl.stability.screening import screen

    with pytest.raises(TypeError, match=r"screen\(out\): a file path is needed, got None"):
        screen("kundur", None, buses=[3])


def test_a_search_criterion_must_say_true_or_false(kundur):
    """A criterion returning None was read as unstable at every clearing: "N-1 insecure,
    CCT 0" for Kundur's fault 3-101, whose CCT is 0.154 s (the paper's Table 4)."""
    sim = stabctl.Simulator(kundur)
    fault = stabctl.LineFault(3, 101, 1.0)
    with pytest.raises(TypeError, match=r"SearchOptions\(criterion\): <lambda> returned None"):
        stabctl.critical_clearing_time(sim, fault, SearchOptions(criterion=lambda r: None))
    said = SearchOptions(criterion=lambda r: np.bool_(r.stable))  # numpy's bool is a bool
    assert stabctl.critical_clearing_time(sim, fault, said).cct_s == 0.154


def test_a_zero_dimensional_array_is_a_number(kundur):
    fleet = stabctl.uniform_fleet(kundur, np.asarray(5.0))
    assert [float(d.pmax_mw) for d in fleet.devices] == [45.0] * 4
    assert type(SearchOptions(t_max=np.asarray(0.5)).t_max) is float
    with pytest.raises(TypeError, match=r"uniform_fleet\(pct\): a number of %"):
        stabctl.uniform_fleet(kundur, np.array([5.0]))


@pytest.mark.parametrize(
    "kw, said",
    [
        ({"search": None}, r"Study\(search\): SearchOptions\(...\) is needed"),
        ({"runner": 2}, r"Study\(runner\): RunnerOptions"),
        ({"controller": 5}, r"Study\(controller\): BangBangCOI\(...\) or None"),
        ({"esd_model": "WECC"}, r"Study\(esd_model\): one of ideal, wecc"),
        ({"critical_reference": "yes"}, r"Study\(critical_reference\) must be True or False"),
    ],
)
def test_a_placement_study_is_checked_when_made(kw, said):
    from stabctl.placement.loop import Study

    with pytest.raises(InputError, match=said):
        Study(**kw)


@pytest.mark.parametrize(
    "kw, said",
    [
        ({"seed": 1.5}, r"LoopOptions\(seed\): a whole number"),  # failed in numpy
        ({"seed": True}, r"LoopOptions\(seed\)"),  # ran as seed 1
        ({"pmu": None}, r"LoopOptions\(pmu\): PMUSettings"),
        ({"control": None}, r"LoopOptions\(control\): BangBangCOI"),
        ({"fleet_pct": "5"}, r"LoopOptions\(fleet_pct\): a number"),
    ],
)
def test_closed_loop_options_are_checked_when_made(kw, said):
    from stabctl.estimation.closed_loop import LoopOptions

    with pytest.raises(InputError, match=said):
        LoopOptions(**{"fleet_pct": 5.0, "estimator": "ekf", **kw})


def test_a_feedback_law_is_checked_when_made():
    from stabctl.smib.feedback import FeedbackLaw

    with pytest.raises(TypeError, match=r"FeedbackLaw\(sign_law\) must be True or False"):
        FeedbackLaw("eq. 14", Ka=0.1, sign_law="no")
    with pytest.raises(TypeError, match=r"FeedbackLaw\(Kv\): a number"):
        FeedbackLaw("speed", Kv="0.5")


@pytest.mark.parametrize(
    "ratings, said",
    [
        ([5, 5], r"cct_jobs\(ratings\): rating 5 given twice"),  # two jobs of one key
        ([], r"cct_jobs\(ratings\): no rating given"),
        ([float("nan")], r"a rating must be in \(0, 100\] %"),  # recorded as a job
        ([-5], r"a rating must be in \(0, 100\] % of machine MVA, got -5"),
        (["5"], r"cct_jobs\(ratings\): a rating is a number of % or None, got '5'"),
        ([True], r"a rating is a number of % or None, got True"),  # ran as 1 %
        ("5", r"cct_jobs\(ratings\): a list of ratings"),
    ],
)
def test_cct_jobs_refuse_a_rating_they_cannot_run(ratings, said):
    from stabctl.stability.cct import cct_jobs

    with pytest.raises(InputError, match=said):
        cct_jobs("kundur", [stabctl.LineFault(3, 101, 1.0)], ratings)


@pytest.mark.parametrize(
    "kw, said",
    [
        ({"esd_pct": float("nan")}, r"cct_study\(ratings\): a rating must be in"),  # a failed run
        ({"seed": -1}, r"cct_study\(seed\): a whole number >= 0"),  # a failed run
        ({"settings": None}, r"estimator_ccts\(settings\): PMUSettings"),  # no attribute 'rate'
        ({"runs": 0}, r"cct_study\(runs\): need at least one run, got 0"),
    ],
)
def test_estimator_ccts_refuse_before_any_run(kw, said):
    from stabctl.estimation.settings import PMUSettings
    from stabctl.studies.estimate import estimator_ccts

    given = {"esd_pct": 5.0, "runs": 1, "seed": 0, "settings": PMUSettings(), **kw}
    with pytest.raises(InputError, match=said):
        estimator_ccts("kundur", 3, 101, **given)


@pytest.mark.parametrize("stem", ["", "../../escape", ".md", "a/b"])
def test_an_eigenvalue_report_s_stem_is_a_file_name(tmp_path, stem):
    """'' wrote '.md'; '../../escape' wrote outside the folder (or failed on a missing one)."""
    from stabctl.studies.eigenvalues import eig_study, write_report

    with pytest.raises(InputError, match=r"write_report\(stem\): .* is no file name"):
        write_report(eig_study(stabctl.load_case("kundur")), tmp_path, stem=stem)
    assert not list(tmp_path.iterdir())


def test_a_whole_float_area_count_is_a_count():
    """n_areas=2.0 failed as a slice index (modal_analysis took it as whole)."""
    from stabctl.studies.eigenvalues import eig_study

    two = eig_study(stabctl.load_case("kundur"), n_areas=2.0)
    assert sorted(set(np.asarray(two.ma.areas).tolist())) == [0, 1]


def test_a_study_s_case_digest_goes_to_its_evaluations():
    """A plan puts the digest of the case as it first read it in every round's jobs
    (Study.case_digest), so a file edited mid-plan stops it rather than mixing contents."""
    from stabctl.placement.loop import Study

    kundur = stabctl.load_case("kundur")
    beta = np.zeros((4, 0))
    assert Study(case_digest="0123").evaluator(None, "kundur", (), beta).case_digest == "0123"
    assert Study().evaluator(None, "kundur", (), beta).case_digest == kundur.digest()


def test_the_api_takes_the_cli_s_ranges_of_the_separation_limit_and_the_deadband():
    """separation_limit=180 (degrees meant) called a run stable whose machines slipped
    87 rad, and deadband_hz=100 (mHz meant) left every device idle, where the CLI refuses
    both: the library holds the bounds, the CLI's ranges are the same."""
    import math

    from stabctl.cli.options import _RANGES
    from stabctl.dynamics.driver import MAX_SEPARATION_LIMIT_RAD
    from stabctl.storage.control import MAX_DEADBAND_HZ, MAX_V_GATE_PU, BangBangCOI

    assert _RANGES["--separation-limit"][:2] == (0, MAX_SEPARATION_LIMIT_RAD)
    assert _RANGES["--deadband-hz"][:2] == (0, MAX_DEADBAND_HZ)
    assert _RANGES["--hysteresis-hz"][:2] == (0, MAX_DEADBAND_HZ)
    assert _RANGES["--v-gate"][:2] == (0, MAX_V_GATE_PU)
    sim = stabctl.Simulator(stabctl.load_case("kundur"))
    for bad in (180, math.inf):
        with pytest.raises(InputError, match=r"must be in \(0, 100\] rad.*pi, not 180"):
            sim.run([], t_end=0.1, separation_limit=bad)
    with pytest.raises(InputError, match=r"0 <= deadband <= 10 Hz \(in Hz: 0.1 is 100 mHz\)"):
        BangBangCOI(deadband_hz=100)
    assert BangBangCOI(deadband_hz=10).deadband_hz == 10


def test_api_findings_of_round_36_are_refused_by_name(tmp_path):
    """A bus fault given far_clear_cycles (the CLI refuses --far-clear-cycles without
    --far-bus; the API dropped it), screen() given a loaded Case (blamed load_case),
    SimulationResult.machine('1') ('not in the result') and speed_at(1.5) (numpy's
    AxisError)."""
    from stabctl.errors import WrongTypeError
    from stabctl.stability.screening import screen

    case = stabctl.load_case("kundur")
    with pytest.raises(InputError, match=r"fault_with_clearing\(far_clear_cycles\): 8 cycles"):
        stabctl.fault_with_clearing(case, 3, None, 1.0, 6, far_clear_cycles=8)
    assert stabctl.fault_with_clearing(case, 3, None, 1.0, 6, far_clear_cycles=6).clear_far == (
        pytest.approx(1.1)
    )
    with pytest.raises(WrongTypeError, match=r"screen\(case_name\): .*got Case"):
        screen(case, tmp_path / "s.jsonl", buses=[3])
    r = stabctl.Simulator(case).run([], t_end=1.0)
    with pytest.raises(WrongTypeError, match=r"machine\(number\): a machine number, got '1'"):
        r.machine("1")
    assert r.machine(2) == 1
    assert r.speed_at(0.5) == pytest.approx(r.speed_at(np.array([0.5]))[0])
    assert r.speed_at(0.5).shape == (4,)


def test_writing_a_result_over_a_directory_names_it(kundur, tmp_path):
    """Round 45: `to_npz` / `to_csv` of a directory's path ended in "Is a directory: 'd'
    -> None" (the temporary file's rename); the directory is named before anything is
    written, and left as it is."""
    res = stabctl.Simulator(kundur).run([], t_end=0.1)
    (tmp_path / "d").mkdir()
    for write in (res.to_npz, res.to_csv):
        with pytest.raises(IsADirectoryError, match=r"a directory, not a file to write: '.*d'$"):
            write(tmp_path / "d")
    assert list((tmp_path / "d").iterdir()) == [] and list(tmp_path.iterdir()) == [tmp_path / "d"]


def test_wrong_arguments_raise_stabctl_s_own_errors(kundur):
    """Round 45: these gave Python's TypeError or ValueError with stabctl's words, so an
    `except StabctlError` (the CLI's) missed them; each is a WrongTypeError or InputError
    (still a TypeError or ValueError as Python has them), a Fraction a number to OMIB."""
    from fractions import Fraction

    from stabctl.dynamics.coi import coi_speed
    from stabctl.errors import StabctlError, WrongTypeError

    sim = stabctl.Simulator(kundur)
    with pytest.raises(WrongTypeError, match=r"run\(storage\): a StorageFleet is needed"):
        sim.run([], t_end=0.5, storage="x")
    with pytest.raises(WrongTypeError, match=r"run\(events\): each event is"):
        sim.run(np.ones((2, 2)), t_end=0.5)
    with pytest.raises(WrongTypeError, match="OMIB: not a number: H = '5'"):
        stabctl.OMIB("5", 0.8, 2.0, 0.5, 1.5)
    with pytest.raises(StabctlError, match=r"coi_speed: inertia of shape \(\)"):
        coi_speed(np.ones((3, 2)), "5")
    assert stabctl.OMIB(Fraction(1, 3), 0.2, 2.0, 0.5, 1.5).H == Fraction(1, 3)


def test_a_case_name_too_long_for_a_file_is_an_unknown_case():
    """Round 45: `load_case('x' * 5000)` raised OSError "File name too long" naming the
    package's data folder (the CLI printed a 5069-character line); it is an unknown case,
    its name shortened."""
    from stabctl.errors import CaseError

    with pytest.raises(CaseError, match=r"^unknown case 'x{40}\.\.\. \(5000 characters\)': built"):
        stabctl.load_case("x" * 5000)


def test_a_result_s_speeds_and_end_take_numbers_only(kundur):
    """Round 45: `speed_at('1')` and `speed_at(None)` gave numpy's casting errors and
    `speed_at(nan)` NaN speeds; `end_state` took a frequency of NaN, 0 or -60 Hz and
    returned it times the speed (and '60' failed with "can't multiply sequence")."""
    res = stabctl.Simulator(kundur).run([], t_end=0.2)
    for t in ("1", None, float("nan"), np.ones((2, 2))):
        with pytest.raises(InputError, match=r"speed_at\(t\): finite times in s"):
            res.speed_at(t)
    for f in (float("nan"), 0, -60, "60"):
        with pytest.raises(InputError, match=r"end_state\(freq_hz\): a frequency in \[1, 1000\]"):
            res.end_state(f)
    assert res.speed_at(0.1).shape == (4,) and res.end_state(60.0)["frequency_hz"] > 59


def test_a_case_s_replace_and_circuit_row_read_their_arguments_as_the_case_does(kundur):
    """Round 45: `Case.replace(foo=1)` gave dataclasses' "unexpected keyword argument";
    `circuit_row('3', 101)` said "no branch between bus 3 and bus 101" where two circuits
    are, though `bus_index('3')` reads the text bus."""
    from stabctl.errors import WrongTypeError

    with pytest.raises(WrongTypeError, match=r"Case.replace: foo not a field of a Case"):
        kundur.replace(foo=1)
    assert kundur.circuit_row("3", 101, 2) == kundur.circuit_row(3, 101, 2)


def test_a_storage_device_beyond_any_plant_is_refused():
    """Round 45: a StorageDevice of 1e308 MW ran 'stable', moving 0 MJ (its bus below the
    low-voltage switch); a rating above MAX_DEVICE_MW (100 GW) is refused by name."""
    from stabctl.storage.devices import MAX_DEVICE_MW

    with pytest.raises(
        InputError, match=r"storage at bus 10: rating 1e\+308 MW is above 100000 MW"
    ):
        stabctl.StorageDevice(10, 1, 1e308)
    assert stabctl.StorageDevice(10, 1, MAX_DEVICE_MW).pmax_mw == MAX_DEVICE_MW
