"""ESD placement: SIME against the equal-area criterion, the convex program against the
OMIB closed form, cuts and sparsity on small programs with known answers, the describing
function and damping rows, infeasibility naming the contingency, and the verification loop
really simulating (counted Simulator.run calls, CCTs equal independent `stabctl.stability.cct`
runs). Simulation-based tests use Kundur only."""

import json
from types import SimpleNamespace

import numpy as np
import pytest
from click.testing import CliRunner

from stabctl.cli import main
from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.results import SimulationResult
from stabctl.errors import InputError
from stabctl.io import load_case
from stabctl.placement.evaluation import Contingency, VerifyOptions
from stabctl.placement.loop import PlaceOptions, Study, WarmStart, place
from stabctl.placement.program import (
    CCTCut,
    InfeasibleError,
    Site,
    candidate_sites,
    diagnose,
    solve_allocation,
    sparse_allocation,
)
from stabctl.smallsignal.damping import DampingModel, relay_df
from stabctl.smallsignal.linearise import linearise
from stabctl.smib.omib import PAPER_OMIB, clearing_state_closed_form, simulate
from stabctl.stability.cct import LineFault, SearchOptions, critical_clearing_time
from stabctl.stability.sime import (
    omib_equivalent,
    storage_integrals,
    unstable_margin,
    unstable_point,
)
from stabctl.storage.control import BangBangCOI
from stabctl.storage.devices import StorageDevice, StorageFleet

BASE_MVA, F0 = 100.0, 60.0
CASE1 = LineFault(3, 101)  # Kundur, paper Case 1 (CCT 0.269 s)


# -- SIME and the convex program against the OMIB equal-area criterion -------------------


def omib_as_result(run) -> SimulationResult:
    """An OMIB run as a two-machine result: machine 1 the generator (H on the system base),
    machine 2 an infinite bus (inertia 1e9 MJ, at rest)."""
    n = run.t.size
    z = np.zeros((n, 2))
    angle, speed = z.copy(), z.copy()
    angle[:, 0], speed[:, 0] = run.delta, run.omega / (2 * np.pi * F0)
    return SimulationResult(
        t=run.t,
        machines=np.array([1, 2]),
        buses=np.array([1]),
        speed=speed,
        angle=angle,
        pelect=z,
        pmech=z,
        efd=z,
        vmag=np.ones((n, 1)),
        vang=np.zeros((n, 1)),
        inertia=np.array([PAPER_OMIB.H * BASE_MVA, 1e9]),
    )


def sime_of_omib(t_clear):
    """(margin, d margin / d P_C per pu, clearing angle) of the OMIB cleared at t_clear,
    with the storage on from clearing (mode +1) and the generator taking all its power."""
    run = simulate(PAPER_OMIB, t_clear, t_end=3.0, max_step=2e-4)
    eq = omib_equivalent(omib_as_result(run), [1], BASE_MVA, F0)
    ku = unstable_point(eq, t_clear)
    modes = (run.t >= t_clear).astype(int)[:, None]
    g = eq.group_weights(np.array([[1.0], [0.0]]))
    return unstable_margin(eq, ku), float(g[0] * storage_integrals(eq, modes, ku)[0]), run.delta_cl


def test_sime_margin_of_the_omib_is_the_equal_area_excess_and_its_sensitivity_the_angle():
    t_clear = 15 / 60  # unstable (Table 1)
    eta, deta_dp, d_cl = sime_of_omib(t_clear)
    eac = PAPER_OMIB.decelerating_area(d_cl) - PAPER_OMIB.accelerating_area(d_cl)
    assert eta == pytest.approx(eac, rel=1e-4)  # energy conservation
    assert deta_dp == pytest.approx(PAPER_OMIB.delta_u - d_cl, rel=1e-4)


def test_convex_rating_equals_the_equal_area_closed_form():
    """Target clearing time 15 cycles (CCT without storage 14.6 cycles): the rating P_C
    absorbed after clearing that makes delta_cr = delta_tgt, with A2 grown by
    P_C (delta_u - delta_cl): P_C = (A1 - A2) / (delta_u - delta_tgt)."""
    t_tgt, eps = 15 / 60, 2e-3
    d_tgt, _ = clearing_state_closed_form(PAPER_OMIB, t_tgt)
    closed = (PAPER_OMIB.accelerating_area(d_tgt) - PAPER_OMIB.decelerating_area(d_tgt)) / (
        PAPER_OMIB.delta_u - d_tgt
    )
    eta, deta_dp, _ = sime_of_omib(t_tgt)
    slope = (sime_of_omib(t_tgt + eps)[0] - eta) / eps
    cut = CCTCut(
        "omib",
        target_s=t_tgt,
        cct_s=t_tgt + eta / -slope,
        gradient=np.array([deta_dp / -slope / BASE_MVA]),
        at_mw=np.zeros(1),
    )
    alloc = solve_allocation([Site(bus=1, machine=1, max_mw=100.0)], [cut])
    assert alloc.mw[0] / BASE_MVA == pytest.approx(closed, rel=1e-4)
    assert alloc.predicted_cct_s["omib"] == pytest.approx(t_tgt)
    # the closed form is sufficient: delta_u moves out as well when P_C is on
    hold = lambda P: lambda f, w, M: ((f - P) / M, P)  # noqa: E731
    assert simulate(PAPER_OMIB, t_tgt, 3.0, law=hold(closed)).stable
    assert not simulate(PAPER_OMIB, t_tgt, 3.0, law=hold(0.5 * closed)).stable


# -- the program on small cases with known answers ---------------------------------------

SITES = (Site(1, 1, 100.0), Site(2, 2, 100.0), Site(3, 3, 100.0))


def cut(name, grad, target=0.3, cct=0.2):
    return CCTCut(name, target, cct, np.asarray(grad, float) / 1000, np.zeros(3))


def test_program_takes_the_cheapest_ccts_per_mw_and_respects_costs_and_safety():
    # contingency a: 1 ms/MW at site 1, 2 ms/MW at site 2 -> 50 MW at site 2
    alloc = solve_allocation(SITES, [cut("a", [1, 2, 0])])
    np.testing.assert_allclose(alloc.mw, [0, 50, 0], atol=1e-5)
    dear = (Site(1, 1, 100.0), Site(2, 2, 100.0, cost=3.0), Site(3, 3, 100.0))
    np.testing.assert_allclose(
        solve_allocation(dear, [cut("a", [1, 2, 0])]).mw, [100, 0, 0], atol=1e-5
    )
    safe = solve_allocation(SITES, [cut("a", [1, 2, 0])], safety_s=0.002)
    assert safe.mw[1] == pytest.approx(51.0, abs=1e-5)


def test_the_allocation_does_not_depend_on_the_costs_scale():
    """Costs of 1e9 per MW (any currency) made the solver report the program unbounded:
    the objective is scaled before the solve, the plan is the same and its cost 1e9 times."""
    cuts = [cut("a", [1, 2, 0]), cut("b", [0, 1, 3])]
    base = solve_allocation(SITES, cuts)
    dear = tuple(Site(s.bus, s.machine, s.max_mw, cost=1e9) for s in SITES)
    big = solve_allocation(dear, cuts)
    np.testing.assert_allclose(big.mw, base.mw, atol=1e-5)
    assert big.objective == pytest.approx(1e9 * base.objective, rel=1e-6)


def test_infeasible_bounds_name_the_contingency():
    cuts = [cut("easy", [0, 0, 2]), cut("hard", [0.1, 0.1, 0])]  # hard needs 1000 MW
    assert diagnose(cuts, [s.max_mw for s in SITES]) == ["hard"]
    with pytest.raises(InfeasibleError, match="hard") as exc:
        solve_allocation(SITES, cuts)
    assert exc.value.contingencies == ("hard",)
    elastic = solve_allocation(SITES, cuts, cct_penalty=1e3)  # elastic rows solve
    assert elastic.cct_slack > 0


def test_max_sites_and_site_cost_keep_the_shared_site():
    # a and b are cheapest at their own sites (2 ms/MW: 50 MW each), site 3 serves both
    # at 0.9 ms/MW (111.1 MW alone)
    sites = tuple(Site(k, k, 200.0) for k in (1, 2, 3))
    cuts = [cut("a", [2, 0, 0.9]), cut("b", [0, 2, 0.9])]
    free = sparse_allocation(sites, cuts)
    np.testing.assert_allclose(free.mw, [50, 50, 0], atol=1e-4)
    one = sparse_allocation(sites, cuts, max_sites=1)
    np.testing.assert_allclose(one.mw, [0, 0, 100 / 0.9], atol=1e-3)
    assert sparse_allocation(sites, cuts, site_cost=50.0).n_sites == 1
    with pytest.raises(InfeasibleError, match="at most 1 site"):
        sparse_allocation(sites, cuts + [cut("d", [3, 0, 0])], max_sites=1)


def test_secant_correction_scales_the_gradient_and_fits_every_point():
    c = CCTCut("a", 0.3, 0.2, np.array([1e-3, 2e-3, 0.0]), np.zeros(3))
    once = c.through([(np.array([0, 10, 0]), 0.21)])  # measured half the slope
    np.testing.assert_allclose(once.gradient, [0.5e-3, 1e-3, 0], atol=1e-12)
    pts = [(np.array([0, 10, 0]), 0.21), (np.array([10, 0, 5]), 0.23)]
    both = c.through(pts)
    for p, v in pts:
        assert both.predicted(p) == pytest.approx(v)


# -- describing function and damping rows ------------------------------------------------


def test_describing_function_of_the_bang_bang_relay():
    d, A = 0.1 / F0, 0.25 / F0
    closed = 4 / (np.pi * A) * np.sqrt(1 - (d / A) ** 2)
    assert relay_df(0.1, 0.25, F0).real == pytest.approx(closed, rel=1e-3)  # 4000 points
    assert relay_df(0.1, 0.05, F0) == 0  # idle inside the band
    lagged = relay_df(0.1, 0.25, F0, hysteresis_hz=0.01)
    assert lagged.imag < 0 and abs(lagged.imag) < 0.1 * lagged.real


@pytest.fixture(scope="module")
def kundur_damping():
    case = load_case("kundur")
    sites = candidate_sites(case)
    sys = linearise(Simulator(case), esd_buses=[s.bus for s in sites])
    return DampingModel(sys, sites, relay_df(0.1, 0.2, F0).real, case.base_mva)


def test_damping_rows_predict_the_recomputed_eigenvalues_to_first_order(kundur_damping):
    dm, zmin = kundur_damping, 0.3
    rows = dm.rows(np.zeros(4), zmin)
    P = np.array([2.0, 0, 1.0, 0])  # MW, small
    kappa = zmin / np.sqrt(1 - zmin**2)
    ma = dm.modes(P)
    lam = ma.eigenvalues[ma.electromechanical]
    actual = (lam.real + kappa * lam.imag) / np.abs(lam)
    np.testing.assert_allclose(np.sort(rows.A @ P - rows.b), np.sort(actual), atol=2e-3)
    assert np.all(dm.em_damping(40 * P)[1].min() > dm.em_damping(np.zeros(4))[1].min())


# -- the verification loop on Kundur -------------------------------------------------------


@pytest.fixture(scope="module")
def counted_place():
    """place() on Kundur Case 1 for a 4 % CCT gain, with every Simulator.run counted."""
    calls = []
    original, started = Simulator.run, Simulator.start

    def run(self, *a, **kw):
        calls.append(kw.get("storage"))
        return original(self, *a, **kw)

    def start(self, *a, **kw):  # a CCT search's provisional probes
        calls.append(kw.get("storage"))
        return started(self, *a, **kw)

    Simulator.run, Simulator.start = run, start
    try:
        res = place("kundur", [Contingency(CASE1, 0.280)])
    finally:
        Simulator.run, Simulator.start = original, started
    return res, calls


def test_verification_runs_the_simulator_for_every_reported_simulation(counted_place):
    res, calls = counted_place
    reported = res.base["3-101"]["n_simulations"] + sum(r["n_simulations"] for r in res.iterations)
    assert len(calls) == reported > 20
    assert sum(c is not None for c in calls) >= len(res.iterations) * 5  # with storage


def test_verified_cct_equals_an_independent_cct_search(counted_place):
    res, _ = counted_place
    assert res.verified and res.allocation.total_mw > 0
    fleet = StorageFleet(
        tuple(StorageDevice(r["bus"], r["machine"], r["mw"]) for r in res.allocation.rows()),
        BangBangCOI(),
    )
    sim = Simulator(load_case("kundur"))
    independent = critical_clearing_time(sim, CASE1, storage=fleet)
    assert res.evaluations["3-101"]["cct_s"] == pytest.approx(independent.cct_s)
    assert independent.cct_s >= 0.280
    assert res.base["3-101"]["cct_s"] == pytest.approx(critical_clearing_time(sim, CASE1).cct_s)


def test_first_order_critical_site_rating_is_twice_their_share_when_ratings_follow_inertia():
    """With ratings proportional to H * MVA, the SIME weights M_nc/M_T (critical) and
    M_c/M_T (others) make the critical sites alone need twice their own uniform rating."""
    from stabctl.studies.placement import critical_only_mw

    case = load_case("kundur")
    sites = candidate_sites(case)
    inertia = np.asarray(case.machines.H * case.machines.mva, float)
    mw = np.array([0.01 * inertia[case.machine_index(s.machine)] for s in sites])
    for critical in ([1, 2], [3]):
        own = sum(p for p, s in zip(mw, sites) if s.machine in critical)
        assert critical_only_mw(case, sites, mw, inertia, critical) == pytest.approx(2 * own)


def test_a_feasible_uniform_start_is_only_ever_improved_and_verified():
    """From the uniform 5 % fleet (which meets a target set below its own CCT) the loop
    may only return a verified allocation costing at most that fleet."""
    case = load_case("kundur")
    sites = candidate_sites(case)
    uniform = 0.05 * np.array([case.machines.mva[case.machine_index(s.machine)] for s in sites])
    # the uniform 5 % fleet clears the Case-1 fault up to 0.199 s (ieee conventions)
    res = place(
        "kundur",
        [Contingency(CASE1, 0.195)],
        options=PlaceOptions(max_iter=4),
        warm=WarmStart(start=uniform),
    )
    assert res.verified
    assert res.allocation.total_mw <= uniform.sum() + 0.4
    assert res.evaluations["3-101"]["cct_s"] >= 0.195
    with pytest.raises(InputError, match="start"):
        place("kundur", [Contingency(CASE1, 0.195)], warm=WarmStart(start=uniform[:2]))


def test_infeasible_bounds_are_proven_by_simulation_and_name_the_contingency():
    sites = candidate_sites(load_case("kundur"), max_pct=0.5)  # 4.5 MW per site
    with pytest.raises(InfeasibleError, match="contingency 3-101") as exc:
        place("kundur", [Contingency(CASE1, 0.300)], Study(sites=sites))
    assert exc.value.contingencies == ("3-101",)
    assert "simulated" in str(exc.value)


def test_damping_target_is_confirmed_by_recomputed_eigenvalues():
    """A CCT target already met without storage: only zeta_min asks for storage."""
    res = place(
        "kundur", [Contingency(CASE1, 0.150)], options=PlaceOptions(zeta_min=0.15, max_iter=4)
    )
    assert res.verified
    assert res.allocation.total_mw > 0
    assert res.damping[1].min() >= 0.15 - 1e-4


# -- command line --------------------------------------------------------------------------


def test_cli_place_json_meets_the_gain_and_bad_input_exits_2():
    r = CliRunner().invoke(
        main,
        [
            "place",
            "kundur",
            "--faults",
            "DEFAULT",
            "--target-cct-gain",
            "3",
            "--workers",
            "1",
            "--json",
        ],
    )
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    assert d["verified"] and d["total_mw"] > 0 and d["n_sites"] == len(d["allocation"])
    for c in d["contingencies"]:
        assert c["met"]
        if c["cct_s"] is not None:  # solved for: its CCT was simulated
            assert c["cct_s"] >= c["required_s"] >= 1.03 * c["cct_no_storage_s"] - 1e-9
    for args in (
        ["--target-cct-gain", "0"],
        ["--target-cct-gain", "5", "--max-sites", "0"],
        ["--target-cct-gain", "5", "--zeta-min", "1"],
    ):
        bad = CliRunner().invoke(main, ["place", "kundur", "--contingencies", "DEFAULT", *args])
        assert bad.exit_code == 2
        assert bad.output.startswith("error:") and bad.output.count("\n") == 1


# -- warm starts and shared runs (the placement study's speed) ------------------------------


def test_bisection_warm_started_from_a_coarse_bracket_equals_the_cold_one():
    """The CCT without storage started from a 5 ms bracket (as the screening gives) equals
    the bisection from 0 to the 1 ms tolerance, on Kundur faults with and without a line
    trip, in fewer runs."""
    from stabctl.placement.loop import baseline

    sim = Simulator(load_case("kundur"))
    faults = [CASE1, LineFault(13, 101), LineFault(1, None), LineFault(110, None)]
    brackets = {}
    for f in faults:
        coarse = critical_clearing_time(
            sim, f, SearchOptions(tol=0.005, t_max=0.5, error_check=False)
        )
        brackets[Contingency(f, 1).name] = coarse.bracket
    cold = baseline("kundur", faults)
    warm = baseline("kundur", faults, opts=VerifyOptions(brackets=brackets))
    for name in cold:
        assert warm[name]["cct_s"] == pytest.approx(cold[name]["cct_s"], abs=1e-9)
        assert warm[name]["n_simulations"] < cold[name]["n_simulations"]
    assert cold["3-101"]["cct_s"] == pytest.approx(critical_clearing_time(sim, CASE1).cct_s)
    # a wrong bracket (stable end unstable) falls back to the search from 0
    bad = baseline("kundur", [CASE1], opts=VerifyOptions(brackets={"3-101": (0.3, 0.305)}))
    assert bad["3-101"]["cct_s"] == pytest.approx(cold["3-101"]["cct_s"])


class _ClearedBefore:
    """A stand-in simulator: stable iff the fault is cleared within `cct` s."""

    conventions, default_h = "ieee", 0.01

    def __init__(self, cct):
        self.case, self.cct = SimpleNamespace(freq_hz=50.0), cct

    def run(self, events, t_end, **kw):
        unstable = events[0].clear_near - events[0].t > self.cct
        return SimpleNamespace(stable=not unstable, separated=[7] if unstable else [], meta={})


def test_a_scan_finer_than_the_tolerance_ends_in_the_lattice_cell_of_the_cct():
    """With --tol-ms 20 the 5 ms scan found 0.205 s stable and 0.21 s unstable, one lattice
    cell, and the bisection between them failed (search range narrower than the
    tolerance), stopping `place`; the cell is searched up to its end.  With the default 1 ms
    tolerance the range is the scan's own, as before."""
    from stabctl.placement.evaluation import scanned_cct

    sim = _ClearedBefore(0.2073)
    coarse, runs = scanned_cct(
        sim, CASE1, None, tol=0.02, t_max=1.0, start=0.2, stop=None, step=0.005
    )
    assert coarse.bracket == (0.2, 0.22) and runs == 3
    fine, _ = scanned_cct(sim, CASE1, None, tol=0.001, t_max=1.0, start=0.2, stop=None, step=0.005)
    assert fine.bracket == (0.207, 0.208)


def test_a_start_already_evaluated_is_not_simulated_again():
    """place() from the uniform fleet with that fleet's first unstable clearing times
    (evaluations, scan="full") simulates the start no more and ends as from scratch."""
    from stabctl.placement.loop import evaluations

    case = load_case("kundur")
    sites = candidate_sites(case)
    uniform = 0.05 * np.array([case.machines.mva[case.machine_index(s.machine)] for s in sites])
    cons = [Contingency(CASE1, 0.195)]
    base = evaluations("kundur", cons)
    known = evaluations("kundur", cons, uniform, opts=VerifyOptions(base=base, scan="full"))
    calls = []
    original, started = Simulator.run, Simulator.start

    def run(self, *a, **kw):
        calls.append(1)
        return original(self, *a, **kw)

    def start(self, *a, **kw):  # a CCT search's provisional probes
        calls.append(1)
        return started(self, *a, **kw)

    Simulator.run, Simulator.start = run, start
    try:
        res = place(
            "kundur",
            cons,
            options=PlaceOptions(max_iter=2),
            warm=WarmStart(base=base, start=uniform, evaluations=known),
        )
    finally:
        Simulator.run, Simulator.start = original, started
    again = place(
        "kundur", cons, options=PlaceOptions(max_iter=2), warm=WarmStart(base=base, start=uniform)
    )
    assert len(calls) == sum(r["n_simulations"] for r in res.iterations)
    assert res.allocation.total_mw == pytest.approx(again.allocation.total_mw)
    assert res.evaluations["3-101"]["cct_s"] == pytest.approx(
        again.evaluations["3-101"]["cct_s"], abs=1e-9
    )


def test_the_paper_s_placement_leaves_faults_that_island_generators_out_of_scope(tmp_path):
    """Kundur's candidate line faults screened as the paper's placement screens them: a
    fault whose trip cuts generators off the main grid (10-20 and 20-10 leave G1 alone,
    3-20 and 20-3 G1 and G2, away from every load) loses them whatever the clearing time,
    so it is named out of scope and not planned for; the tie and the rest stay in scope.
    The islanded generators are those the topology gives."""
    from stabctl.studies.placement import in_scope, islanding, screen

    rows = screen("kundur", tmp_path, workers=1)
    named = set(islanding(rows))
    assert {"10-20", "20-10", "3-20", "20-3"} <= named
    assert not named & {"3-101", "101-3", "13-101", "101-13"}
    scoped = {Contingency(r["fault"], 1).name for r in in_scope(rows)}
    assert not scoped & named and "3-101" in scoped
