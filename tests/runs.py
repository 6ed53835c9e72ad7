"""Runs the test modules share (tests/io, tests/dynamics): each written once.

Importable from any test module (``tests/`` is on ``sys.path``, as ``model_rows``)."""

import numpy as np

from stabctl.dynamics.driver import Simulator, _Run


def flat_run(case, t_end=10.0, step=0.005, q_limits=False):
    """(largest drift of any state over the run, result) of ``case`` without disturbance,
    from its power flow (``q_limits`` as `Simulator`), at ``step`` s."""
    sim = Simulator(case, q_limits=q_limits)
    m, sa, grid, nets = sim._prepare([], t_end, step, None, "exact")
    run = _Run(sim, m, sa, grid, nets, False, np.pi, False)
    run.advance(grid.t.size - 1)
    res = run.finish(None)
    return np.max(np.abs(run.x - m.x0)), res
