"""Controls whose initial point lies outside their own limits: refused by name, or run on
as PSS/E runs on from its "initial conditions suspect" (the limiter takes the state to its
limit at the first step).  The reference: PSS/E's TGOV1 run (tests/data/psse_runs/TGOV1)
with VMAX set below the machine's dispatch, whose mechanical power must settle at VMAX
against the infinite bus (TGOV1 with Dt = 0: Pm = the valve, held at VMAX)."""

import glob
import warnings
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from stabctl.cli import main
from stabctl.dynamics.driver import Simulator
from stabctl.errors import InitialLimitError, InputError
from stabctl.io.psse import load_psse
from stabctl.io.pst import write_case_json

RUN = str(Path(__file__).parents[1] / "data" / "psse_runs" / "TGOV1") + "/"
VMAX = 0.9  # the machine is dispatched at 1.0 pu of its 100 MVA


@pytest.fixture(scope="module")
def case():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        c = load_psse(glob.glob(RUN + "*.raw")[0], glob.glob(RUN + "*.dyr")[0])
    return c.replace(governors=c.governors.replace(Tmax=np.array([VMAX])))


def test_a_suspect_start_is_refused_by_name(case):
    with pytest.raises(InitialLimitError, match=r"initial power order 1.0000 pu outside") as err:
        Simulator(case, background_compile=False)
    assert err.value.table == "tg_con" and err.value.rows == (0,)
    # the machine named as outputs name it (tg_con's row 1 is G2's), and what to do
    assert str(err.value).startswith("the governor of G2 (bus 102, id '1'): initial power")
    assert "leave_out_infeasible(case) leaves such controls out" in str(err.value)


def test_run_on_takes_the_valve_to_its_limit(case):
    with pytest.warns(UserWarning, match="not an equilibrium"):
        sim = Simulator(case, suspect_starts="run")
    assert sim.suspect == (
        "governor of G2 (bus 102, id '1'): initial power order 1.0000 pu outside [Tmin, "
        "Tmax] = [0.1000, 0.9000]",
    )
    res = sim.run([], t_end=8.0)
    assert res.meta["suspect_starts"] == list(sim.suspect)
    assert res.pmech[0, 1] == pytest.approx(1.0, abs=1e-6)  # starts at the dispatch
    assert res.pmech[-1, 1] == pytest.approx(VMAX, abs=1e-3)  # and ends at VMAX
    with pytest.raises(InputError, match="suspect_starts must be"):
        Simulator(case, suspect_starts="maybe")


def test_simulate_lists_what_it_runs_on(case, tmp_path):
    path = tmp_path / "tgov1.json"
    write_case_json(case, path)
    refused = CliRunner().invoke(main, ["simulate", str(path), "--tf", "1"])
    assert refused.exit_code == 2 and "initial power order" in refused.output
    assert "the import's --leave-out-infeasible leaves such controls out" in refused.output
    ran = CliRunner().invoke(main, ["simulate", str(path), "--tf", "1", "--suspect-starts", "run"])
    assert ran.exit_code == 0, ran.output
    said = "initial condition suspect, run on: governor of G2 (bus 102, id '1'): initial power"
    assert said in ran.output
