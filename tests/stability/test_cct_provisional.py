"""Provisional stable probes (`SearchOptions.provisional_s`): a probe run only some time
past its clearing, continued to t_end when the search closes its cell on it, ends every
search in the cell, verdict and half-step CCT of the searches whose probes all run to
t_end; and a run paused and continued (`Simulator.start`) is the whole run bit for bit."""

import numpy as np
import pytest

from stabctl.dynamics.driver import Simulator
from stabctl.errors import InputError
from stabctl.io import load_case
from stabctl.stability.cct import LineFault, SearchOptions, critical_clearing_time
from stabctl.stability.screening import screening_faults

#: a window short enough that some provisionally stable probes separate later (s)
SHORT_S = 0.05


def outcome(sim, fault: LineFault, options: SearchOptions):
    """A search's outcome (the result, or the verdict's name) and its outcome tuple."""
    try:
        res = critical_clearing_time(sim, fault, options)
    except InputError as exc:
        return None, type(exc).__name__
    return res, (res.bracket, res.cct_half_step_s, res.separated)


@pytest.mark.heavy
@pytest.mark.parametrize("method", ["sime", "bisection"])
def test_provisional_probes_keep_every_outcome_of_kundurs_screening(kundur, method):
    """Every bus and line fault of Kundur: the same verdicts, cells, half-step CCTs and
    separated machines with whole runs, provisional ones (the default window) and a
    window so short that stable ends found provisionally separate when continued."""
    overturned, steps = 0, {}
    for fault in screening_faults(kundur.case, lines=True):
        ref, want = outcome(kundur, fault, SearchOptions(method=method, provisional_s=None))
        for window in (SearchOptions.provisional_s, SHORT_S):
            res, got = outcome(kundur, fault, SearchOptions(method=method, provisional_s=window))
            assert got == want, (fault, window)
            if res is not None:
                overturned += window == SHORT_S and res.overturned
                steps[window] = steps.get(window, 0) + res.n_steps
                assert res.resumed <= 1 + res.overturned
        if ref is not None:
            steps[None] = steps.get(None, 0) + ref.n_steps
            assert ref.resumed == ref.overturned == 0
    assert overturned > 0  # the confirm-and-continue path taken
    assert steps[SearchOptions.provisional_s] < steps[None]


def test_a_provisional_probe_found_unstable_when_continued_on_miniwecc():
    """A miniWECC bus fault whose provisional stable ends separate past the short
    window: the search goes on below them and ends in the whole runs' cell."""
    sim = Simulator(load_case("miniwecc"))
    fault = LineFault(61, None)
    _, want = outcome(sim, fault, SearchOptions(method="sime", provisional_s=None))
    res, got = outcome(sim, fault, SearchOptions(method="sime", provisional_s=SHORT_S))
    assert got == want and res.overturned > 0 and res.resumed > 0
    assert dict(res.probes)[res.t_unstable] is False


@pytest.mark.parametrize("stop", [False, True])
def test_a_run_paused_and_continued_is_the_whole_run_bit_for_bit(kundur, stop):
    fault = LineFault(3, 101)
    events, t_end = fault.events(0.2 if stop else 0.1), 6.0
    whole = kundur.run(events, t_end, stop_at_separation=stop, voltages=False)
    handle = kundur.start(events, t_end, stop_at_separation=stop, voltages=False)
    handle.advance_to(1.7)
    early = handle.result()
    assert 1.7 <= early.t[-1] < 1.7 + kundur.default_h and not handle.done
    for t in (2.33, 4.0, t_end):
        handle.advance_to(t)
    res = handle.result()
    assert handle.done and res.stable == whole.stable and res.t.size == whole.t.size
    for name in ("t", "angle", "speed", "pelect", "pmech", "efd"):
        assert np.array_equal(getattr(res, name), getattr(whole, name)), name
        assert np.array_equal(getattr(early, name), getattr(whole, name)[: early.t.size])


def test_the_window_is_checked_and_recorded_when_not_the_default(kundur):
    with pytest.raises(InputError, match="provisional_s must be > 0 s"):
        critical_clearing_time(kundur, LineFault(3, 101), SearchOptions(provisional_s=0.0))
    assert "provisional_s" not in SearchOptions().to_inputs()
    for window in (None, 1.0):
        recorded = SearchOptions(provisional_s=window).to_inputs()
        assert SearchOptions.from_inputs(recorded).provisional_s == window
