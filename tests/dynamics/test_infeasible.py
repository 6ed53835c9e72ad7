"""Controls whose power-flow point lies outside their own limits: refused by the model with
every offender of a check named (`stabctl.errors.InitialLimitError`), or left out by name
(`stabctl.dynamics.infeasible.leave_out_infeasible`), on Kundur's case with limits moved
below its operating point."""

import numpy as np
import pytest

from stabctl.case import ExciterTable
from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.infeasible import leave_out_infeasible
from stabctl.errors import CaseError, InitialLimitError
from stabctl.io import load_case

from model_rows import EXST1


@pytest.fixture(scope="module")
def crowded():
    """Kundur with governors 1 and 3 limited to Tmax = 0.5 pu (they start at 0.8068 pu,
    the swing machine's 7.26 pu of PSTess's power flow on 900 MVA, and 0.7778 = 700/900
    pu, its dispatch) and machine 2's exciter an EXST1 whose Vrmax = 1 pu is below its initial
    field voltage."""
    case = load_case("kundur")
    tg = case.governors
    tmax = np.where(np.isin(tg.machine, (1, 3)), 0.5, tg.Tmax)
    rows = case.exciters.matrix()
    st1 = np.zeros(rows.shape[1])
    st1[: len(EXST1)] = EXST1
    st1[1], st1[7] = 2, 1.0  # machine 2, Vrmax
    rows[case.exciters.machine == 2] = st1
    return case.replace(governors=tg.replace(Tmax=tmax), exciters=ExciterTable.from_matrix(rows))


def test_the_model_names_every_offender_of_a_check(crowded):
    no_exciter = crowded.replace(exciters=crowded.exciters.select(crowded.exciters.machine != 2))
    no_exciter = no_exciter.replace(pss=crowded.pss.select(crowded.pss.machine != 2))
    with pytest.raises(InitialLimitError) as err:
        Simulator(no_exciter, background_compile=False)
    assert (err.value.table, err.value.rows) == ("tg_con", (0, 2))
    said = str(err.value)  # each named as outputs name machines, not by its table row
    assert said.startswith("the governor of G1 (bus 1): initial power order 0.8068 pu outside")
    assert "; the governor of G3 (bus 11): initial power order" in said


def test_leave_out_removes_and_names_them(crowded):
    """The EXST1 goes with its stabiliser, both governors go; the rest stays, and the case
    now starts at rest."""
    case, left = leave_out_infeasible(crowded)
    assert left[0].startswith("exciter of G2 (bus 2): EXST1 initial field voltage")
    assert left[1:] == (
        "governor of G1 (bus 1): initial power order 0.8068 pu outside [Tmin, Tmax] "
        "= [0.0000, 0.5000]",
        "governor of G3 (bus 11): initial power order 0.7778 pu outside [Tmin, Tmax] "
        "= [0.0000, 0.5000]",
    )
    assert list(case.exciters.machine) == [1, 3, 4] and list(case.pss.machine) == [1, 3, 4]
    assert list(case.governors.machine) == [2, 4]
    sim = Simulator(case, background_compile=False)
    assert sim.model.initial_residual[0] < 1e-8


def test_a_feasible_case_is_returned_as_it_is():
    case = load_case("kundur")
    assert leave_out_infeasible(case) == (case, ())


def test_a_simple_exciter_whose_output_limit_is_below_its_field_voltage_is_named():
    """A SEXS (smpexc, exc_con type 0) whose EMAX (Vrmax) = 0.5 pu is below the field
    voltage its machine starts at passed the start checks: every run then stopped at
    "the initial point is not an equilibrium ... a model's initialisation disagrees with
    its dynamics", and --leave-out-infeasible left nothing out.  Refused naming the
    limit and the value, and left out by name."""
    case = load_case("kundur")
    exc = case.exciters
    assert set(exc.type) == {0} and (exc.TA >= 1e-3).all()
    case = case.replace(exciters=exc.replace(Vrmax=np.where(exc.machine == 2, 0.5, exc.Vrmax)))
    with pytest.raises(InitialLimitError) as err:
        Simulator(case, background_compile=False)
    assert (err.value.table, err.value.rows) == ("exc_con", (1,))
    assert str(err.value).startswith(
        "the exciter of G2 (bus 2): Vrmax (SEXS's, SCRX's EMAX) = 0.5 below the initial field "
        "voltage E_fd0 = "
    )
    assert " pu: the regulator's output limit cannot deliver it: the run cannot" in str(err.value)
    kept, left = leave_out_infeasible(case)
    assert len(left) == 1 and left[0].startswith(
        "exciter of G2 (bus 2): Vrmax (SEXS's, SCRX's EMAX) = 0.5 below the initial field "
        "voltage E_fd0"
    )
    assert list(kept.exciters.machine) == [1, 3, 4]
    assert Simulator(kept, background_compile=False).model.initial_residual[0] < 1e-8


def test_a_start_outside_a_limit_is_named_by_the_state_the_limiter_clamped():
    """Run on from such a start (PSS/E's 'initial conditions suspect'), the first
    evaluation clamps the exciter's E_fd to its EMAX: the equilibrium check names that
    state, its start and the limit, not "a model's initialisation disagrees with its
    dynamics" (which would point at stabctl's model)."""
    case = load_case("kundur")
    exc = case.exciters
    case = case.replace(exciters=exc.replace(Vrmax=np.where(exc.machine == 2, 0.5, exc.Vrmax)))
    with pytest.warns(UserWarning, match="not an equilibrium"):
        sim = Simulator(case, background_compile=False, suspect_starts="run")
    (clamp,) = sim.model.initial_clamps
    assert clamp.startswith("exc.Efd.G2 = 1.96") and clamp.endswith(", clamped to 0.5")
    with pytest.raises(CaseError) as err:
        sim.model.check_equilibrium()
    assert f"limited state(s) start outside their limits: {clamp}" in str(err.value)
    assert "initialisation disagrees" not in str(err.value)
    flat = Simulator(load_case("kundur"), background_compile=False).model
    assert flat.initial_clamps == ()
