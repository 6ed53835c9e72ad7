"""A run's compiled loop pauses every quarter second or so of wall time (signals handled,
progress shown: `stabctl.dynamics.driver.Pieces`): a run paused at every few steps is
the run integrated in one piece, bit for bit."""

import signal
import threading

import numpy as np
import pytest

from stabctl.dynamics import driver
from stabctl.dynamics.driver import Pieces, Simulator
from stabctl.progress import run_progress, runs_shown
from stabctl.stability.cct import LineFault
from stabctl.storage.devices import uniform_fleet

QUANTITIES = ("t", "speed", "angle", "pelect", "pmech", "efd", "vmag", "vang", "pesd")


def _run(case, steps, **kw):
    """The run of a fault on line 3-101 cleared at 0.2 s (unstable), in pieces of
    `steps` steps, on a new simulator (its quiet start its own)."""
    sim = Simulator(case)
    sim._pieces.steps = lambda: steps  # type: ignore[method-assign]
    return sim.run(LineFault(3, 101).events(0.2), 4.0, **kw)


@pytest.mark.parametrize("esd", [False, True])
@pytest.mark.parametrize("stop", [False, True])
def test_a_run_paused_every_few_steps_equals_the_run_in_one_piece(kundur, esd, stop):
    kw = {"stop_at_separation": stop}
    if esd:
        kw["storage"] = uniform_fleet(kundur.case, 5)
    whole = _run(kundur.case, 10**9, **kw)
    for steps in (1, 7, 64):
        paused = _run(kundur.case, steps, **kw)
        for q in QUANTITIES:
            np.testing.assert_array_equal(getattr(paused, q), getattr(whole, q), err_msg=q)
        assert paused.separated == whole.separated and paused.stable == whole.stable
        assert paused.t_separation == whole.t_separation
        if esd:
            assert paused.meta["switchings"] == whole.meta["switchings"]


def test_the_pieces_follow_the_measured_cost_per_step(monkeypatch):
    monkeypatch.setattr(driver, "PAUSE_EVERY_S", 0.25)
    p = Pieces()
    assert p.steps() == driver.FIRST_PIECE_STEPS
    p.took(1.0, 32)  # a first piece slowed by loading the code: 1 step at a time
    assert p.steps() == 8
    p.took(0.0008, 8)
    assert p.steps() == 2500
    p.took(0.5, 3)  # the few steps at a run's end say little: kept only if cheaper
    assert p.steps() == 2500
    p.took(0.0, 0)
    assert p.steps() == 2500


def test_a_signal_handler_runs_during_a_long_run(kundur):
    """A handler (Ctrl-C's KeyboardInterrupt) ran only once the whole compiled loop ended:
    a long run now stops within its piece."""
    sim = Simulator(kundur.case)
    sim.run(LineFault(3, 101).events(0.1), 1.0)  # loaded, the cost per step measured
    sim._pieces.steps = lambda: 50  # type: ignore[method-assign]
    hits = []

    def handler(signum, frame):
        hits.append(signum)
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGUSR1, handler)
    timer = threading.Timer(0.05, signal.raise_signal, (signal.SIGUSR1,))
    try:
        timer.start()
        with pytest.raises(KeyboardInterrupt):
            sim.run(LineFault(3, 101).events(0.1), 3600.0, voltages=False)
    finally:
        timer.cancel()
        signal.signal(signal.SIGUSR1, previous)
    assert hits == [signal.SIGUSR1]


def test_a_run_is_shown_only_when_asked(capsys):
    assert run_progress(0.0, 10.0) is None
    with runs_shown(after_s=0.0):
        bar = run_progress(0.0, 10.0)
        assert bar is not None
        bar(5.0)
        bar.close()
    assert "simulated 5.00 of 10 s" in capsys.readouterr().err
    assert run_progress(0.0, 10.0) is None


def test_commanded_wecc_batteries_in_pieces_of_one_step_keep_their_cct(monkeypatch):
    """Converters commanded frame by frame (an estimator's WECC batteries) continued at
    every step: Kundur line 3-101 at 5 % storage, exact measurements, has its CCT at 11.5
    cycles as in one piece (docs/storage.md)."""
    from stabctl.estimation import closed_loop as cl

    monkeypatch.setattr(Pieces, "steps", lambda self: 1)
    job = {
        "case": "kundur", "bus": 3, "far_bus": 101, "esd_pct": 5.0, "estimator": "ideal",
        "seed": 0, "esd_model": "wecc",
    }  # fmt: skip
    assert cl.cct_job(job)["cct_cycles"] == pytest.approx(11.5)
