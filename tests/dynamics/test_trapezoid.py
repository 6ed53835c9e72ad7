"""The implicit trapezoid (`stabctl.dynamics.trapezoid`, ``Simulator.run(method=
"trapezoid")``): it converges to the same trajectory as Heun, at second order; it keeps
the power-flow point; its non-windup limits hold a state exactly on its limit (IEEE 421.5
E.5, ANDES's AntiWindup); what it does not implement is refused.  Its agreement with ANDES,
step for step, is in tests/io/test_andes.py."""

from pathlib import Path

import numpy as np
import pytest

from stabctl.dynamics import trapezoid
from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.events import Fault, fault_with_clearing
from stabctl.errors import InputError, NumericalInstabilityError
from stabctl.io.psse import load_psse
from stabctl.storage.devices import uniform_fleet
from stabctl.studies.cases import CASE1

#: Kundur (built-in, ieee conventions): a bolted fault at bus 3, 1.0-1.1 s, 3 s
FAULT = [Fault(3, 1.0, 1.1)]
PSSE = Path(__file__).parents[1] / "data" / "psse"


def speed_error(res, ref) -> float:
    """Largest speed gap (pu) of res to ref on ref's grid."""
    return max(
        float(np.max(np.abs(np.interp(ref.t, res.t, res.speed[:, j]) - ref.speed[:, j])))
        for j in range(ref.speed.shape[1])
    )


@pytest.fixture(scope="module")
def heun_reference(kundur):
    """Heun at 0.25 ms: its own step error is (0.25/5)^2 of its 5 ms error (1.6e-5 pu),
    4e-8 pu, below what the trapezoid's steps are compared by."""
    return kundur.run(FAULT, 3.0, h=0.00025)


def test_trapezoid_converges_to_the_same_trajectory_at_second_order(kundur, heun_reference):
    """Both methods solve the same equations: the trapezoid's speeds approach Heun's
    fine-step run as the step shrinks, faster than the step (10, 5, 2.5 ms measured
    1.1e-5, 4.5e-6, 8.3e-7 pu: 13x for a quarter of the step), and at 5 ms it is closer
    than Heun at 5 ms (1.6e-5: its error constant is half Heun's on a linear loop)."""
    err = {
        h: speed_error(kundur.run(FAULT, 3.0, h=h, method="trapezoid"), heun_reference)
        for h in (0.01, 0.005, 0.0025)
    }
    print(f"\ntrapezoid speed error vs Heun 0.25 ms: {err}")
    assert err[0.01] > err[0.005] > err[0.0025]
    assert err[0.01] / err[0.0025] > 8  # second order: 16 (measured 13)
    assert err[0.005] < 1e-5
    assert err[0.005] < speed_error(kundur.run(FAULT, 3.0, h=0.005), heun_reference)


def test_trapezoid_keeps_the_power_flow_point(kundur):
    """A flat 10 s run at 10 ms stays where it starts (f(x0) = 0 is a fixed point of the
    rule): speeds and angles move by less than 1e-9."""
    res = kundur.run([], 10.0, h=0.01, method="trapezoid")
    assert np.max(np.abs(res.speed - 1.0)) < 1e-9
    assert np.max(np.abs(res.angle - res.angle[0])) < 1e-9


def test_trapezoid_holds_the_field_voltage_exactly_on_its_ceiling(kundur, kundur_case):
    """In the fault every machine's field voltage runs into its ceiling V_Rmax = 5 pu
    (smpexc, K_A = 200): the non-windup limit holds it there, never beyond, and lets it
    go when the regulator's input turns (IEEE 421.5 E.5; ANDES's AntiWindup)."""
    res = kundur.run(FAULT, 3.0, h=0.005, method="trapezoid")
    ceiling = kundur_case.exciters.Vrmax
    assert np.all(np.max(res.efd, axis=0) == ceiling)
    on = res.efd == ceiling
    assert np.all(on.sum(axis=0) >= 3)  # held for several steps
    assert np.all(res.efd[-1] < ceiling)  # and released


def test_trapezoid_reaches_heuns_verdict_on_the_papers_case_1(kundur, kundur_case):
    """The paper's Case 1 (bus-3 fault on line 3-101, 21 cycles: unstable without storage)
    at 5 ms: machines 1 and 2 separate at the same instant in both methods (1.96 s), and
    the trapezoid runs on through the pole slip, where a load bus swings across PST's 0.5
    pu switch: a load held at its impedance model at one iterate stays held for the step
    (without that lock it alternated between its two models at every iterate, and Newton
    did not converge at 2.995 s)."""
    fault = [fault_with_clearing(kundur_case, CASE1.bus, CASE1.far_bus, 1.0, 21)]
    heun = kundur.run(fault, 5.0, h=0.005)
    trap = kundur.run(fault, 5.0, h=0.005, method="trapezoid")
    assert not heun.stable and not trap.stable and trap.t[-1] == 5.0
    assert trap.t_separation == heun.t_separation and trap.separated == heun.separated == [1, 2]


def test_trapezoid_refuses_what_it_does_not_implement(kundur, kundur_pstess, kundur_case):
    """Storage devices (their switching instants are located inside Heun's steps), the PSTess
    event semantics, and an unknown method: InputError naming the reason."""
    fleet = uniform_fleet(kundur_case, 5.0)
    with pytest.raises(InputError, match="no storage devices"):
        kundur.run(FAULT, 2.0, method="trapezoid", storage=fleet)
    with pytest.raises(InputError, match="'exact' event semantics only"):
        kundur_pstess.run(FAULT, 2.0, method="trapezoid")
    with pytest.raises(InputError, match="method must be 'heun' or 'trapezoid'"):
        kundur.run(FAULT, 2.0, method="rk4")


def test_trapezoids_sparse_path_solves_the_same_steps(kundur, heun_reference, monkeypatch):
    """Above `SPARSE_ABOVE` active states (ACTIVSg2000's 6467) the chord matrix is factorised
    sparse with its entries below `SPARSE_DROP` left out and kept from one network stage
    into the next: only the iteration changes, not the equation each step solves.  Forced
    onto Kundur's fault, the 5 ms run is as close to Heun's fine-step run as the dense
    path's (below 1e-5 pu, the second-order test's bound) and equals the dense path's to
    well within that (each step converged to `TOL`)."""
    from stabctl.dynamics import trapezoid

    dense = kundur.run(FAULT, 3.0, h=0.005, method="trapezoid")
    monkeypatch.setattr(trapezoid, "SPARSE_ABOVE", 0)
    sparse = kundur.run(FAULT, 3.0, h=0.005, method="trapezoid")
    gap = float(np.max(np.abs(sparse.speed - dense.speed)))
    print(
        f"\nsparse path: {speed_error(sparse, heun_reference):.2e} pu from Heun, "
        f"{gap:.2e} from the dense path"
    )
    assert speed_error(sparse, heun_reference) < 1e-5
    assert gap < 1e-7


def test_trapezoid_holds_a_regulator_pushed_past_its_limit(monkeypatch):
    """smib_v33.raw's machine with ACTIVSg2000's bus-2024 GENROU and EXAC2 (K_A 1000, T_A
    0.05 s, VAMAX 11.7471), a fault at its terminal through j1e-4 pu (1.0-1.1 s), 1/60 s
    steps.  In the step ending at 1.0833 s V_A starts at 8.26 rising at 1042 1/s: the
    rule's update lies past VAMAX, where the evaluation clamps it and its derivative
    points back inside (-251 1/s, the rate feedback K_F), so the equation has no
    solution on [VAMIN, VAMAX]; before the hold of such a state (`trapezoid._pushed`)
    Newton stalled there and the step was halved.  Now it takes the grid's step
    (no halving allowed: HALVINGS = 0) and agrees with Heun at 1/4800 s within twice
    its own step-halving difference (the first-order Richardson estimate of its error:
    the step that crosses the limit's kink is first order; measured 2.2e-3 rad and
    1.6e-5 pu against the 1/120 s run's 1.5e-3 and 1.1e-5)."""
    sim = Simulator(load_psse(PSSE / "smib_v33.raw", PSSE / "smib_exac2.dyr"))
    fault = [Fault(1, 1.0, 1.1, x=1e-4)]
    monkeypatch.setattr(trapezoid, "HALVINGS", 0)
    coarse = sim.run(fault, 3.0, h=1 / 60, method="trapezoid")
    fine = sim.run(fault, 3.0, h=1 / 120, method="trapezoid")
    ref = sim.run(fault, 3.0, h=1 / 4800)

    def gaps(res, other):
        """Largest angle (rad) and speed (pu) gaps at the grid times the runs share."""
        _, i, j = np.intersect1d(
            np.round(res.t * 4800), np.round(other.t * 4800), return_indices=True
        )
        assert i.size >= 150  # every 1/60 s point, and the fault's
        angle = np.max(np.abs(res.angle[i] - other.angle[j]))
        return angle, np.max(np.abs(res.speed[i] - other.speed[j]))

    error, halving = gaps(coarse, ref), gaps(coarse, fine)
    print(f"\n1/60 s against Heun: {error}; against 1/120 s: {halving}")
    assert error[0] < 2 * halving[0] and error[1] < 2 * halving[1]
    monkeypatch.setattr(trapezoid, "_pushed", lambda y_in, y, r: np.zeros(y.size, bool))
    with pytest.raises(NumericalInstabilityError, match=r"1\.0833 s: state exc\.VA"):
        sim.run(fault, 3.0, h=1 / 60, method="trapezoid")


def test_trapezoids_grouped_jacobian_is_the_column_by_column_one(kundur, monkeypatch):
    """On the sparse path the exciters', stabilisers' and governors' columns of distinct
    machines are differenced in one evaluation each (`trapezoid._column_groups`): forced
    onto Kundur's fault at 5 ms, every matrix the run forms equals the one differenced a
    column at a time, entry for entry (the network's solution, the only coupling between
    machines, does not move when a control's state does)."""
    monkeypatch.setattr(trapezoid, "SPARSE_ABOVE", 0)
    factorise, checked = trapezoid._Step.factorise, []

    def both(step, x, f_x, stage, h, held=None, side=None):
        base = step.f(x.copy(), stage, kept=step.f.kept_copy())
        grouped = step.f.jacobian(x, base, stage, step.act, step.groups)
        assert sum(cols.size for cols, _ in step.groups) == 32  # of Kundur's 56 states
        checked.append(np.array_equal(grouped, step.f.jacobian(x, base, stage, step.act)))
        factorise(step, x, f_x, stage, h, held, side)

    monkeypatch.setattr(trapezoid._Step, "factorise", both)
    kundur.run(FAULT, 3.0, h=0.005, method="trapezoid")
    assert len(checked) >= 3 and all(checked)


def test_trapezoids_sparse_solve_takes_the_held_rows_out():
    """Sparse, the chord matrix is kept while the held states change under it: a held
    state's correction is 0 and the other rows are solved exactly, the matrix's rows of
    the held states replaced by the identity's (what the dense path's zeroed rows of A
    give, I - h/2 A with row i of A 0), through the factors of the whole matrix bordered
    by the held columns (`trapezoid._Step.solve`).  Checked against a direct solve of the
    row-replaced matrix (a random well-conditioned one) to rounding."""
    rng = np.random.default_rng(52)
    n = 40
    M = np.eye(n) + 0.3 * rng.standard_normal((n, n)) * (rng.random((n, n)) < 0.2)
    step = trapezoid._Step.__new__(trapezoid._Step)
    step.sparse = True
    step.lu = trapezoid.spla.splu(trapezoid.sp.csc_matrix(M)).solve
    step.border = {}
    r = rng.standard_normal(n)
    for rows in ([], [3], [0, 7, 21, 39], [3]):
        held = np.zeros(n, bool)
        held[rows] = True
        r_held = np.where(held, 0.0, r)  # the iteration's residual of a held state is 0
        replaced = M.copy()
        replaced[held] = np.eye(n)[held]
        dy = step.solve(r_held, held)
        assert np.allclose(dy, np.linalg.solve(replaced, r_held), rtol=0, atol=1e-12)
        assert np.all(np.abs(dy[held]) < 1e-14)
    assert len(step.border) == 2  # one bordering per held set, kept
