"""Sub-interval integration of fast exciter loops (`stabctl.dynamics.subinterval`): the
network at the run's step, an EXAC2 whose regulator loop is faster than that step in
sub-steps of its own with its inputs held."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.events import Fault
from stabctl.dynamics.grid import STEP_PER_TIME_CONSTANT, exciter_hmax
from stabctl.errors import InputError
from stabctl.io.psse import load_psse

PSSE = Path(__file__).parents[1] / "data" / "psse"
FAULT = [Fault(1, 1.0, 1.1, x=1e-4)]


@pytest.fixture(scope="module")
def smib_exac2():
    """ACTIVSg2000's bus-2024 GENROU with its EXAC2 (K_A 1000, T_A 0.05 s, rate feedback
    K_F 0.49 through T_E 0.55 s) against PSS/E's infinite bus: its regulator loop's time
    constant, 3.7 ms, is below half a cycle."""
    return load_psse(PSSE / "smib_v33.raw", PSSE / "smib_exac2.dyr")


def _gaps(res, other):
    """Largest angle (rad), speed (pu) and field voltage (pu) gaps at shared grid times."""
    _, i, j = np.intersect1d(np.round(res.t * 4800), np.round(other.t * 4800), return_indices=True)
    assert i.size >= 150
    return tuple(
        float(np.max(np.abs(getattr(res, k)[i] - getattr(other, k)[j])))
        for k in ("angle", "speed", "efd")
    )


def test_the_default_step_follows_the_data_and_the_fast_loop_is_sub_stepped(smib_exac2):
    """With sub-intervals (the default) the default step is half a cycle, the data's own
    bound, and the EXAC2 is sub-stepped at half its loop's time constant; without them
    the loop sets the whole model's step (half its time constant) and half a cycle is
    refused as unstable for Heun's method (h >= 2 T)."""
    on = Simulator(smib_exac2, background_compile=False)
    off = Simulator(smib_exac2, background_compile=False, subintervals=False)
    loop = float(on.model.inner_loops[0])
    assert 3e-3 < loop < 4e-3
    assert on.default_h == pytest.approx(1 / 120)
    assert off.default_h == pytest.approx(STEP_PER_TIME_CONSTANT * loop)
    assert on.exciter_hmax(on.model, 1 / 120)[0] == pytest.approx(STEP_PER_TIME_CONSTANT * loop)
    assert np.isinf(on.exciter_hmax(on.model, 1e-3)[0])  # a short step needs none
    with pytest.raises(InputError, match="too large"):
        off.run(FAULT, 2.0, h=1 / 120)
    pstess = Simulator(smib_exac2, background_compile=False, conventions="pstess", step=1e-3)
    assert not pstess.subintervals  # PSTess has none: its half cycle is refused here
    with pytest.raises(InputError, match="too large"):
        Simulator(smib_exac2, background_compile=False, conventions="pstess")
    assert np.all(np.isinf(exciter_hmax(np.array([np.inf, 1.0]), 0.1)))


def test_a_sub_stepped_fault_run_converges_to_the_single_rate_one(smib_exac2):
    """The bus fault (1.0-1.1 s) with the EXAC2 sub-stepped at 1/120 s agrees with the
    whole model at 1/4800 s (no sub-steps there) within twice its own step-halving
    difference (Richardson's estimate of its error), in angle, speed and field voltage,
    and halving the step shrinks the error at least threefold (second order: measured
    5.6e-4 -> 5.7e-5 rad, 5.5e-6 -> 8.4e-7 pu speed, 3.6e-2 -> 1.2e-2 pu efd)."""
    on = Simulator(smib_exac2, background_compile=False)
    ref = Simulator(smib_exac2, background_compile=False, subintervals=False).run(
        FAULT, 3.0, h=1 / 4800
    )
    coarse, fine = on.run(FAULT, 3.0, h=1 / 120), on.run(FAULT, 3.0, h=1 / 240)
    error, halving, finer = _gaps(coarse, ref), _gaps(coarse, fine), _gaps(fine, ref)
    print(f"\n1/120 s against 1/4800 s: {error}; against 1/240 s: {halving}; 1/240: {finer}")
    for e, d, f in zip(error, halving, finer):
        assert e < 2 * d
        assert f < e / 3
    assert error[0] < 1e-3 and error[1] < 1e-5


def test_the_commands_say_how_many_exciters_take_sub_steps(tmp_path, smib_exac2):
    """`simulate` and `cct` name the exciters integrated in sub-intervals at their step (as
    many as the simulator's `exciter_hmax` makes finite: the SMIB's one EXAC2 at half a
    cycle, none at 1 ms), in their text and JSON; with ``--single-rate`` none, at the
    single-rate simulator's default step."""
    import json

    from click.testing import CliRunner

    from stabctl.cli import main

    def run(*args):
        out = CliRunner().invoke(main, [str(a) for a in args])
        assert out.exit_code == 0, out.output
        return out.output

    case = tmp_path / "smib.json"
    run("import-psse", PSSE / "smib_v33.raw", PSSE / "smib_exac2.dyr", "-o", case)
    sim = Simulator(smib_exac2, background_compile=False)
    n = int(np.isfinite(sim.exciter_hmax(sim.model, sim.default_h)).sum())
    assert n == 1
    d = json.loads(run("simulate", case, "--fault", 1, "--clear-cycles", 3, "--tf", 2, "--json"))
    assert d["sub_stepped_exciters"] == n
    text = run("simulate", case, "--fault", 1, "--clear-cycles", 3, "--tf", 2)
    assert f"with {n} exciter(s) in sub-intervals" in text
    fine = run("simulate", case, "--fault", 1, "--clear-cycles", 3, "--tf", 2, "--step", 1e-3)
    assert "sub-intervals" not in fine
    d = json.loads(run("cct", case, "--fault", 1, "--t-max", 0.4, "--json"))
    assert d["sub_stepped_exciters"] == n
    single = Simulator(smib_exac2, background_compile=False, subintervals=False)
    args = ("--fault", 1, "--clear-cycles", 3, "--tf", 2, "--json", "--single-rate")
    d = json.loads(run("simulate", case, *args))
    assert d["sub_stepped_exciters"] == 0 and d["step_s"] == single.default_h
    d = json.loads(run("cct", case, "--fault", 1, "--t-max", 0.4, "--json", "--single-rate"))
    assert d["sub_stepped_exciters"] == 0 and d["step_s"] == single.default_h


def test_model_options_carry_the_choice_into_sweeps(smib_exac2):
    """`ModelOptions.subintervals` reaches the simulator, a sweep's key and its recorded
    inputs (absent when on, so that earlier records resume unchanged)."""
    from stabctl.dynamics.options import ModelOptions

    off = ModelOptions(subintervals=False)
    assert not off.simulator(smib_exac2, background_compile=False).subintervals
    assert off.key_suffix() == "/single-rate" and ModelOptions().key_suffix() == ""
    assert ModelOptions.from_inputs(off.to_inputs()) == off
    assert "subintervals" not in ModelOptions().to_inputs()
