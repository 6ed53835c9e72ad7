"""The quiet start of runs, integrated once: runs of one simulator that share their model,
step and settings share their trajectory from the power-flow point up to the grid point
before their first event, so that stretch is integrated by the first of them and copied
into the others.

A CCT search (`stabctl.stability.cct`) runs one fault a dozen times with other clearing
times, and a screening runs every fault of a case, each from t = 0 with the fault at 1 s:
on ACTIVSg2000 that second is a fifth of a CCT search's steps.  The copy is the
trajectory the run would have integrated, bit for bit: the grid up to the stop is the
same (an interval's steps depend on its own length only, `stabctl.dynamics.grid`), the
network is the same pre-event stage, the limiters' reach is the run's nominal step
(`reach`), and a paused run continues from its carry exactly
(`stabctl.dynamics.integrator.integrate`).  The stop is the point before the first event,
not the event itself: under PSTess's semantics the step ending at an event already uses
the next network.

Runs with storage devices under a feedback law share it too when their fleets pack alike
(`fleet_key`: the devices' state and statistics are copied with it).  Runs with commands
(`stabctl.dynamics.driver.Simulator.run_commanded`) or a monitor integrate their whole
trajectory: their commands and monitor act from t = 0.
"""

from __future__ import annotations

import weakref
from typing import NamedTuple

import numpy as np

#: prefixes kept per simulator (one per step, settings and storage-free model; a CCT
#: search with its half-step check uses two)
PREFIXES_KEPT = 4


class Prefix(NamedTuple):
    """A run's state at grid index k, the point before its first event, and what it
    recorded up to there: weak references to the model and pre-event network it was
    integrated with (told by identity; a prefix keeps neither alive once the simulator's
    caches drop them), the grid times t (k + 1,), the carry's arrays and the recording's
    rows (`stabctl.dynamics.integrator.Carry`, `Recording`); None fields when the run
    stopped before k (nothing to reuse)."""

    model: weakref.ref
    net0: weakref.ref
    t: np.ndarray
    k: int
    carry: tuple | None
    rows: tuple | None


def quiet_end(interval: np.ndarray) -> int:
    """The grid index before the first event (the last point of the first interval whose
    next step stays in it), 0 when the run has no event or starts with one.

    Parameters
    ----------
    interval : ndarray, shape (n_t,), int
        The grid's interval id of each point (`stabctl.dynamics.grid.TimeGrid`).

    Returns
    -------
    int
    """
    later = np.flatnonzero(interval > 0)
    return max(int(later[0]) - 1, 0) if later.size else 0


def reach(h: np.ndarray, step: float) -> float:
    """The limiters' reach of a run (s; `stabctl.models.blocks.nonwindup`): its nominal
    step when no step exceeds it by more than round-off (the ieee grid: then runs with
    other events share one reach, and their prefix), else its longest step (PSTess's grid,
    steps up to twice the nominal one).

    Parameters
    ----------
    h : ndarray, shape (n_interval,)
        The step of each interval, s.
    step : float
        The nominal step, s.

    Returns
    -------
    float
    """
    longest = float(np.max(h))
    return float(step) if longest <= step * (1 + 1e-9) else longest


def fleet_key(sa) -> tuple:
    """What identifies a packed fleet (`stabctl.storage.devices.StorageArrays`) for a
    prefix: every field, arrays by their bytes.

    Parameters
    ----------
    sa : StorageArrays
        The packed fleet (possibly without devices).

    Returns
    -------
    tuple
        Hashable.
    """
    return tuple(
        (v.dtype.str, v.shape, v.tobytes()) if isinstance(v, np.ndarray) else v for v in sa
    )


def integrate_from_cache(run, cache, k1: int) -> None:
    """Advance `run` (a fresh `stabctl.dynamics.driver._Run` without commands or monitor)
    to grid index `k1`, its quiet start copied from `cache` (a
    `stabctl.dynamics.bounded.BoundedCache`) or integrated and stored there when `k1`
    reaches past it.

    Parameters
    ----------
    run : stabctl.dynamics.driver._Run
        The run, not advanced yet.
    cache : BoundedCache
        The simulator's prefixes (`PREFIXES_KEPT`).
    k1 : int
        The grid index to stop at (the run's last: to its end).
    """
    k = quiet_end(run.grid.interval)
    if not 1 <= k <= k1:
        run.advance(k1)
        return
    net0 = run.nets_list[0]
    key = (
        id(run.m),
        id(net0),
        k,
        float(run.grid.t[k]),
        run.opts.pst,
        None if run.bus_rows is None else run.bus_rows.tobytes(),
        run.params.reach,
        run.params.exc_hmax.tobytes(),
        run.opts.limit,
        run.opts.stop,
        fleet_key(run.sa),
    )
    prefix = cache.get(key, lambda: _integrated(run, k, net0))
    if run.k == 0 and _fits(prefix, run, net0, k):
        _restore(run, prefix)
    run.advance(k1)


def _fits(prefix: Prefix, run, net0, k: int) -> bool:
    """Whether `prefix` is this run's quiet start (the ids in the key can be reused by new
    objects: the identities and the grid are checked)."""
    return (
        prefix.carry is not None
        and prefix.model() is run.m
        and prefix.net0() is net0
        and prefix.k == k
        and np.array_equal(prefix.t, run.grid.t[: k + 1])
    )


def _integrated(run, k: int, net0) -> Prefix:
    """Advance `run` to k and copy what it holds there."""
    run.advance(k)
    t = run.grid.t[: k + 1].copy()
    if run.status != 0 or run.k != k:  # stopped before: nothing to reuse
        return Prefix(weakref.ref(run.m), weakref.ref(net0), t, k, None, None)
    c, n, d = run.carry, k + 1, run.carry.devices
    carry = (
        c.x.copy(),
        c.kept.V.copy(),
        c.kept.held.copy(),
        c.kept.S_extra.copy(),
        c.held_stage.copy(),
        c.health.est[:n].copy(),
        c.health.worst.copy(),
        c.health.n_big.copy(),
        c.health.bad.copy(),
        d.mode.copy(),
        d.P.copy(),
        d.target.copy(),
        d.e.copy(),
        run.rec.stats.copy(),
        run.rec.log.copy(),
    )
    rows = tuple(a[:n].copy() for a in _rows(run.rec))
    return Prefix(weakref.ref(run.m), weakref.ref(net0), t, k, carry, rows)


def _restore(run, prefix: Prefix) -> None:
    """Put `prefix` into the fresh `run`: its carry (devices included), recording rows,
    device statistics and switching log, and grid index."""
    c, n, d = run.carry, prefix.k + 1, run.carry.devices
    x, V, held, S_extra, held_stage, est, worst, n_big, bad, *devices = prefix.carry
    mode, P, target, e, stats, log = devices
    for dst, src in (
        (d.mode, mode),
        (d.P, P),
        (d.target, target),
        (d.e, e),
        (run.rec.stats, stats),
        (run.rec.log, log),
        (c.x, x),
        (c.kept.V, V),
        (c.kept.held, held),
        (c.kept.S_extra, S_extra),
        (c.held_stage, held_stage),
        (c.health.worst, worst),
        (c.health.n_big, n_big),
        (c.health.bad, bad),
    ):
        dst[:] = src
    c.health.est[:n] = est
    for dst, src in zip(_rows(run.rec), prefix.rows):
        dst[:n] = src
    run.k, run.stored = prefix.k, True


def _rows(rec) -> tuple:
    """The per-grid-point arrays of a `stabctl.dynamics.integrator.Recording`."""
    return (
        rec.speed, rec.angle, rec.pelect, rec.qelect, rec.pmech, rec.efd, rec.V, rec.P,
        rec.S_ibr,
    )  # fmt: skip
