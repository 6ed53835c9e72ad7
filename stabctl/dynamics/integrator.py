"""The compiled predictor-corrector loop (`integrate`) and the data it reads and fills.

Integrator (PSTess 1.1 `s_simu.m`, docs/pst_models.md 7): explicit Heun (modified Euler),
each state advanced by x_j = x_k + h/2 (f(x_k) + f(x_k + h f(x_k))) with the network solved
at both stages, on the grid of `stabctl.dynamics.grid` (every event time a grid point).
Event semantics (`RunOptions.pst`):

- "exact": each step uses the network of the interval it lies in;
- "pst": PSTess's own, so that trajectories match PSTess bit for bit: the corrector of the
  step ending at an event already uses the post-event network, and the first step of each
  interval after the first is evaluated once more before it is taken (its limiter clamps
  persist).

Numerical health is checked after every step (`_healthy`): a non-finite state, the speed of
a machine the stage judges outside [1 - SPEED_BAND, 1 + SPEED_BAND] pu or Heun's local
error estimate above EST_TOL for more than EST_STEPS steps in a row (the signature of an
explicit method beyond its stability region) stops the run (UNSTABLE_STEP), so that a loss
of synchronism (an angle more than `RunOptions.limit` rad from the centre of inertia, eq.
40) is only ever judged on a numerically healthy run. Both the loss of synchronism and the
storage devices' relative speeds use the islands of the current network stage
(`RunOptions`, from `stabctl.dynamics.partition`): after a trip or a split the machines the
stage's partition does not judge never stop a run, and each device follows its machine's
island as it is now. The storage devices are advanced by `stabctl.dynamics.switching`."""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from stabctl._jit.arrays import assign
from stabctl._jit.borrow import borrowed
from stabctl._jit.decorators import kernel, njit
from stabctl.dynamics import subinterval as sub
from stabctl.dynamics import switching as sw
from stabctl.dynamics.coi import island_coi
from stabctl.dynamics.model import (
    NO_BUS_VOLTAGES,
    KeptBuses,
    KernelNetwork,
    KernelOutputs,
    call_evaluate,
    kernel_outputs,
)
from stabctl.dynamics.partition import criterion_inertia
from stabctl.storage import control as law

if TYPE_CHECKING:
    from stabctl.dynamics.grid import TimeGrid


class Recording(NamedTuple):
    """Preallocated buffers filled by `integrate` (`recording`): speed, angle, pelect,
    pmech, efd (n_t, n_mac) and V (n_t, n_bus) complex at every grid index (the predictor
    stage's outputs; V (n_t, 0): the run solves only the machine buses' voltages, the
    others are not computed); the powers the network takes from the devices P (n_t, n_dev) pu
    (`stabctl.dynamics.switching.delivered`); per device stats (n_dev, 5) =
    (switchings, energy absorbed, energy delivered, highest and lowest stored energy
    relative to the start, all in pu*s, of the power the network takes;
    `stabctl.dynamics.switching.account`); the
    switching log (rows: time s, device, new mode, relative speed pu; NaN rows unused);
    the converters' injected P + j Q, S_ibr (n_t, n_ibr) complex pu (system base); the
    machines' reactive power qelect (n_t, n_mac) pu (system base)."""

    speed: np.ndarray
    angle: np.ndarray
    pelect: np.ndarray
    pmech: np.ndarray
    efd: np.ndarray
    V: np.ndarray
    P: np.ndarray
    stats: np.ndarray
    log: np.ndarray
    S_ibr: np.ndarray
    qelect: np.ndarray


#: rows of the switching log of a run (switchings beyond it are counted, not logged)
LOG_ROWS = 4096


def recording(n_t: int, nm: int, nb: int, nd: int, ni: int = 0) -> Recording:
    """Zeroed buffers for a run.

    Parameters
    ----------
    n_t : int
        Grid points.
    nm, nb, nd : int
        Machines, buses, storage devices.
    ni : int, optional
        Converters; default 0.

    Returns
    -------
    Recording
    """
    return Recording(
        speed=np.zeros((n_t, nm)),
        angle=np.zeros((n_t, nm)),
        pelect=np.zeros((n_t, nm)),
        pmech=np.zeros((n_t, nm)),
        efd=np.zeros((n_t, nm)),
        V=np.zeros((n_t, nb), np.complex128),
        P=np.zeros((n_t, nd)),
        stats=np.zeros((nd, 5)),
        log=np.full((LOG_ROWS, 4), np.nan),
        S_ibr=np.zeros((n_t, ni), np.complex128),
        qelect=np.zeros((n_t, nm)),
    )


OK, SEPARATED, NO_LOAD_FLOW, UNSTABLE_STEP = 0, 1, -1, -3

#: Numerical health (`_healthy`): a non-finite state, a speed more than SPEED_BAND pu from
#: synchronous, or Heun's local error estimate (`_local_error`) above EST_TOL for more than
#: EST_STEPS steps in a row marks a run that left the integrator's stability region.  On
#: the paper's faults healthy runs stay above 0.1 for at most 6 steps (a field voltage
#: reaching its ceiling inside a step); Kundur at h = 0.019 s (h/T_R = 1.9) sits above it
#: from 1.5 s on at a spurious fixed point of the method (Efd at its ceiling, 0.3-9).
SPEED_BAND, EST_TOL, EST_STEPS = 0.5, 0.1, 50


def symptom(value: float, q: int, nm: int) -> str:
    """Why `_healthy` stopped a run at state q (value its value, nm machines): a phrase
    for the NumericalInstabilityError."""
    if not np.isfinite(value):
        return "not finite"
    if nm <= q < 2 * nm and abs(value - 1.0) > SPEED_BAND:
        return f"speed more than {SPEED_BAND} pu from synchronous"
    return f"the largest local error estimate, above {EST_TOL} for {EST_STEPS} steps in a row"


class Health(NamedTuple):
    """Numerical-health trackers of a run (`_healthy`): the local error estimate of the
    step ending at each grid index (n_t,), the state it is largest in (1,), the number of
    steps in a row above EST_TOL (1,), the offending state index (1,)."""

    est: np.ndarray
    worst: np.ndarray
    n_big: np.ndarray
    bad: np.ndarray


class StepGrid(NamedTuple):
    """The grid as `integrate` reads it (`TimeGrid`): t (n_t,) s, interval (n_t,) stage
    index of each point, h (n_stage,) step of each interval (s), first (n_t,) whether the
    step from a point is the first of an interval after the first."""

    t: np.ndarray
    interval: np.ndarray
    h: np.ndarray
    first: np.ndarray


def step_grid(grid: TimeGrid) -> StepGrid:
    """The kernel view of a `TimeGrid`.

    Parameters
    ----------
    grid : TimeGrid

    Returns
    -------
    StepGrid
    """
    return StepGrid(grid.t, grid.interval, grid.h, np.r_[False, np.diff(grid.interval) > 0])


class RunOptions(NamedTuple):
    """Settings of a run (`run_options`).

    Attributes
    ----------
    pst : bool
        PSTess's event semantics (module docstring).
    inertia : ndarray, shape (n_stage, n_mac)
        COI weights H * MVA (MW s, `stabctl.dynamics.coi.coi_inertia`) of each network
        stage (grid interval), within its islands.
    island : ndarray of int, shape (n_stage, n_mac)
        Each machine's island in each stage, labels 0, 1, ...: a machine's COI is its
        island's (`stabctl.dynamics.partition.Partition.island`).  A tripped machine is
        alone in an island of its own: it weighs in no other machine's COI, and its
        device sees relative speed 0 (`stabctl.storage.control.relative_speeds`).
    judged : ndarray of bool, shape (n_stage, n_mac)
        The machines the loss-of-synchronism check judges in each stage
        (`stabctl.dynamics.partition.Partition.judged`).
    judging : ndarray, shape (n_stage, n_mac)
        The COI weights of that check (`stabctl.dynamics.partition.criterion_inertia`:
        `inertia` but in a faulted stage whose clearing loses machines).
    limit : float
        Separation limit, rad.
    stop : bool
        End the run when a judged machine's angle leaves its island's COI by more than
        `limit` (`_separated`).

    Without partitions (no stage trips a machine or splits an island) every row is the
    islands before the disturbance, every machine judged: the run computes as it did with
    one row.  The storage devices observe the islands of the stage whose network a grid
    point or a step is evaluated with (`stabctl.dynamics.switching.observe`), the check
    judges a grid point against the stage that starts at or before its time, the later
    of a zero-length interval's (`_judged_stage`, as
    `stabctl.dynamics.partition.judged_relative`).
    """

    pst: bool
    inertia: np.ndarray
    island: np.ndarray
    judged: np.ndarray
    judging: np.ndarray
    limit: float
    stop: bool


def run_options(
    pst: bool,
    inertia: np.ndarray,
    island: np.ndarray,
    partitions,
    n_stage: int,
    limit: float,
    stop: bool,
) -> RunOptions:
    """The options of a run whose network has `n_stage` stages.

    Parameters
    ----------
    pst : bool
        PSTess's event semantics.
    inertia : ndarray, shape (n_mac,)
        COI weights before the disturbance, MW s (`stabctl.dynamics.coi.coi_inertia`).
    island : ndarray of int, shape (n_mac,)
        Islands before the disturbance (`stabctl.network.topology.machine_islands`).
    partitions : sequence of Partition
        The run's partitions, one per stage (`stabctl.dynamics.partition.stage_partitions`);
        empty: every stage has the islands before the disturbance.
    n_stage : int
        Network stages (grid intervals).
    limit : float
        Separation limit, rad.
    stop : bool
        Stop at separation.

    Returns
    -------
    RunOptions
        Arrays C-contiguous, float64, int64 and bool (one compiled signature).
    """
    if partitions:
        rows = [(p.inertia, p.island, p.judged) for p in partitions]
    else:
        rows = [(inertia, island, np.ones(np.size(island), bool))] * n_stage
    return RunOptions(
        pst=pst,
        inertia=np.ascontiguousarray([r[0] for r in rows], np.float64),
        island=np.ascontiguousarray([r[1] for r in rows], np.int64),
        judged=np.ascontiguousarray([r[2] for r in rows], np.bool_),
        judging=np.ascontiguousarray([criterion_inertia(*r) for r in rows], np.float64),
        limit=limit,
        stop=stop,
    )


class Carry(NamedTuple):
    """What `integrate` updates in place, so that a run can be continued: the flat state x
    (n_state,), the kept buses (`KeptBuses`: voltages, held loads, device injections),
    held_stage[0] the network stage the held loads belong to (they are cleared when it
    changes), the devices (`stabctl.dynamics.switching.DeviceState`) and the numerical
    health (`Health`)."""

    x: np.ndarray
    kept: KeptBuses
    held_stage: np.ndarray
    devices: sw.DeviceState
    health: Health


class _Kernel(NamedTuple):
    """What one network evaluation inside `integrate` needs (`_evaluate`)."""

    p: object
    nets: KernelNetwork
    kept: KeptBuses
    held_stage: np.ndarray
    out: KernelOutputs
    #: machine-code address of the model's evaluation (`stabctl.dynamics.model.call_evaluate`)
    evaluate: int


class _Workspace(NamedTuple):
    """Scratch arrays of `integrate`: derivatives at the step start (dx_k) and at the
    predictor (dx_j), what the devices see at the sub-step start (a) and end (b), which
    devices switched in the current step, and the powers the network takes from the
    devices at the sub-step start (P_a) and end (P_b) (`stabctl.dynamics.switching.delivered`);
    for exciters integrated in sub-intervals (`stabctl.dynamics.subinterval`): whether
    there are any, their states' slots (left out of the local error estimate), their
    inputs at the step's start u_a and their states Phi(x_a, u_a), Phi(x_a, u_p); the
    predictor's state xp."""

    dx_k: np.ndarray
    dx_j: np.ndarray
    a: sw.Seen
    b: sw.Seen
    switched: np.ndarray
    P_a: np.ndarray
    P_b: np.ndarray
    sub: bool
    sub_mask: np.ndarray
    u_a: np.ndarray
    phi_a: np.ndarray
    phi_p: np.ndarray
    xp: np.ndarray


class _SplitPoint(NamedTuple):
    """Where the step from grid index k is split (`_resume`): rem (s) before t_k+1, at the
    located switching of device first_d, or at a scheduled command (first_d -1)."""

    k: int
    rem: float
    first_d: int


@kernel
def _workspace(x, nd, p, u):
    mask = sub.sub_state_mask(p, x.size)
    return _Workspace(
        np.zeros_like(x),
        np.zeros_like(x),  # slots no kernel writes stay 0
        sw.Seen(np.zeros(nd), np.zeros(nd), np.zeros(nd)),
        sw.Seen(np.zeros(nd), np.zeros(nd), np.zeros(nd)),
        np.zeros(nd, np.bool_),
        np.zeros(nd),
        np.zeros(nd),
        mask.any(),
        mask,
        np.zeros_like(u),
        x.copy(),
        x.copy(),
        np.empty_like(x),
    )


# -- health and separation -----------------------------------------------------------------

#: `_local_error`'s pre-test margin: num > e den (1 - 1e-14) holds wherever the rounded
#: num / den > e, so the divisions it skips cannot change the result
_BELOW = 1.0 - 1e-14


@kernel
def _local_error(x, f_k, f_j, hh, where, skip):
    """Heun's local error estimate (the corrector minus the Euler predictor, hh/2 |f_j -
    f_k|), largest over the states relative to 1 + |x| but those in skip (bool, the
    states of sub-stepped exciters); its state index in where[0]."""
    e, c = 0.0, 0.5 * hh
    for q in range(x.size):
        if skip[q]:
            continue
        num, den = c * abs(f_j[q] - f_k[q]), 1.0 + abs(x[q])
        if num > e * den * _BELOW:  # divide only where the ratio may pass e (every NaN
            eq = num / den  # and infinity as before: skipped, or infinite)
            if eq > e:
                e, where[0] = eq, q
    return e


@kernel
def _healthy(x, est, nm, health, judged):
    """Numerical health after a step with local error estimate est (module docstring);
    returns False with the offending state index in health.bad[0].  The speed band holds
    for the machines the stage judges (judged, bool (n_mac,)): one tripped or cut off from
    the main grid may run up with no load on it (miniWECC's G4, alone on line 9-10 and
    without a governor, passes 1.5 pu 15 s after that line opens)."""
    n_bad = 0
    for q in range(x.size):  # a count, which vectorises; the first sought only if any
        n_bad += not np.isfinite(x[q])
    if n_bad:
        for q in range(x.size):
            if not np.isfinite(x[q]):
                health.bad[0] = q
                return False
    for i in range(nm):
        if judged[i] and abs(x[nm + i] - 1.0) > SPEED_BAND:
            health.bad[0] = nm + i
            return False
    health.n_big[0] = health.n_big[0] + 1 if est > EST_TOL else 0
    if health.n_big[0] > EST_STEPS:
        health.bad[0] = health.worst[0]
        return False
    return True


@kernel
def _judged_stage(grid, k):
    """The stage that judges grid index k: the last one started at or before t_k (the
    later of a zero-length interval's, whose start time repeats), as
    `stabctl.dynamics.partition.stage_at`."""
    n = grid.t.size
    while k + 1 < n and grid.t[k + 1] == grid.t[k]:
        k += 1
    return grid.interval[k]


@kernel
def _separated(x, nm, opts, s):
    """Whether the rotor angle of a machine that stage s judges (opts.judged[s]) is more
    than opts.limit from its island's COI angle (eq. 40, the islands of stage s, the
    criterion's weights opts.judging[s]): a machine tripped or cut off from the main grid
    never stops a run."""
    coi = island_coi(x[:nm], opts.judging[s], opts.island[s])[0]
    judged = opts.judged[s]
    for i in range(nm):
        if judged[i] and abs(x[i] - coi[i]) > opts.limit:
            return True
    return False


# -- recording -------------------------------------------------------------------------------


@kernel
def _record(rec, k, x, out, P):
    """Store grid index k: angles and speeds of x, the evaluation outputs, device powers P
    (those the network takes, `stabctl.dynamics.switching.delivered`)."""
    nm = out.pelect.size
    for i in range(nm):
        rec.angle[k, i] = x[i]
        rec.speed[k, i] = x[nm + i]
    assign(rec.pelect[k], out.pelect)
    assign(rec.qelect[k], out.qelect)
    assign(rec.pmech[k], out.pmech)
    assign(rec.efd[k], out.efd)
    if rec.V.shape[1] > 0:  # a run that records the bus voltages (`Simulator.run`)
        assign(rec.V[k], out.V_bus)
    if P.size > 0:
        assign(rec.P[k], P)
    if out.S_ibr.size > 0:
        assign(rec.S_ibr[k], out.S_ibr)


# -- network solution ----------------------------------------------------------------------


@kernel
def _stage(nets, s):
    """The matrices of network stage s from the stacked ones."""
    return KernelNetwork(
        nets.Y11[s],
        nets.Y12[s],
        nets.Y21[s],
        nets.Y22[s],
        nets.Z22[s],
        nets.R[s],
        nets.R_mac[s],
        nets.Z_mac[s],
        nets.switched_on[s],
        nets.targets[s],
        nets.steps[s],
    )


# The stages that evaluate the model are inlined into `integrate` at numba IR level
# (inline="always").  They call the model by address (`call_evaluate`), so none links it;
# compiled as functions of their own they still took longer: `integrate` alone compiled in
# 19.4 s instead of 17.4 s on a cold cache.  The compiled arithmetic, and so every result,
# is the same.
@kernel(inline="always")
def _evaluate(kn, x, stage, want, dx):
    """`evaluate_kernel` with the network of `stage`; the held loads are released when
    the stage changes.  Returns its iteration count (< 0: no convergence)."""
    if stage != kn.held_stage[0]:
        kn.kept.held[:] = False
        kn.held_stage[0] = stage
    return call_evaluate(kn.evaluate, x, kn.p, _stage(kn.nets, stage), kn.kept, want, dx, kn.out)


# -- the controller at a grid point and at a split point -----------------------------------


@kernel(inline="always")
def _control_at_grid_point(kn, grid, sa, ds, opts, w, rec, x, k):
    """The controller at grid index k (events make voltages jump here): commands due,
    Table 3 modes, targets and powers; the network is solved again if a power changed."""
    sw.observe(x, w.dx_k, kn.p.n_mac, opts, grid.interval[k], sa, kn.kept.V, w.a)
    if sa.kind == law.EXTERNAL:
        sw.apply_commands(ds, grid.t[k], rec, w.a.r)
    for d in range(sa.pmax.size):
        want = law.desired_mode(sa, d, ds.mode[d], w.a.r[d], w.a.v[d])
        if sa.kind == law.BANG_BANG and want != ds.mode[d]:
            ds.mode[d] = want
            w.switched[d] = True
            sw.log_switching(rec, d, grid.t[k], want, w.a.r[d])
    sw.targets(sa, ds.mode, w.a.r, w.a.v, w.a.acc, ds.target)
    if sw.powers_now(sa, ds):
        sw.inject(sa, ds.P, kn.kept.S_extra, x)
        _evaluate(kn, x, grid.interval[k], rec.V.shape[1] > 0, w.dx_k)


@kernel(inline="always")
def _resume(kn, grid, sa, ds, opts, w, rec, x_a, at):
    """The controller at a split point `at` of the step from grid index at.k (a switching
    or a command, at.rem seconds before t_k+1; `_SplitPoint`) with the state x_a there:
    commands, switchings, targets, powers, then the derivatives there and the powers the
    network takes (w.P_a).  Returns (network solved, derivatives)."""
    k, rem, first_d = at
    t_now = grid.t[k + 1] - rem
    sw.observe(x_a, w.dx_j, kn.p.n_mac, opts, grid.interval[k], sa, kn.kept.V, w.a)
    if sa.kind == law.EXTERNAL:
        sw.apply_commands(ds, t_now, rec, w.a.r)
    if first_d >= 0:
        sw.switch_located(sa, ds, w, rec, first_d, t_now)
    sw.targets(sa, ds.mode, w.a.r, w.a.v, w.a.acc, ds.target)
    sw.powers_now(sa, ds)
    sw.inject(sa, ds.P, kn.kept.S_extra, x_a)
    # slots no kernel writes (the converters' memory, a model's unused slots) must stay 0:
    # uninitialised, they fed whatever the memory held into x_b, xp and the error test
    dx_a = np.zeros_like(x_a)
    ok = _evaluate(kn, x_a, grid.interval[k], NO_BUS_VOLTAGES, dx_a) >= 0
    sw.delivered(sa, ds.P, kn.kept, w.P_a)
    return ok, dx_a


# -- the step ------------------------------------------------------------------------------


@kernel(inline="always")
def _heun(kn, sa, ds, w, x_a, dx_a, hh, stage, want, dx_j):
    """Heun's predictor-corrector over hh from x_a (derivatives dx_a; the last evaluation
    was at x_a), the devices' powers advanced (their energy left as it is), the exciters
    of `stabctl.dynamics.subinterval` in sub-steps: (network solved, corrected state);
    dx_j is written with the derivatives at the predictor (network of `stage`)."""
    xp = w.xp  # (loops: numba's array expressions cost 5-10 % of an ACTIVSg2000 run)
    for q in range(x_a.size):
        xp[q] = x_a[q] + hh * dx_a[q]
    if w.sub:
        sub.sub_heun_start(kn.p, x_a, kn.out.exc_in, w.u_a, w.phi_a, hh, xp)
    if sa.pmax.size > 0:  # (a call passing the devices' arrays costs even without devices)
        Pb = sw.powers_after(sa, ds.P, ds.target, ds.e, hh)
        sw.inject(sa, Pb, kn.kept.S_extra, xp)
    if _evaluate(kn, xp, stage, want, dx_j) < 0:
        return False, x_a
    x_b = np.empty_like(x_a)  # (a loop: numba's array expression cost 5 % of a run)
    for q in range(x_a.size):
        x_b[q] = x_a[q] + 0.5 * hh * (dx_a[q] + dx_j[q])
    if w.sub:
        sub.sub_heun_end(kn.p, x_a, kn.out.exc_in, w.phi_a, w.phi_p, hh, x_b)
    return True, x_b


@kernel(inline="always")
def _substeps(kn, grid, sa, ds, opts, w, rec, health, x, k):
    """The step from grid index k, split at located switchings and scheduled commands
    (each device switches at most once per step, commands are finite: it ends).  Returns
    (status, index, state after the step; x itself when the network failed)."""
    s = grid.interval[k]
    j = grid.interval[k + 1] if opts.pst else s
    last = k == grid.interval.size - 2
    x_a, dx_a, rem = x, w.dx_k, grid.h[s]
    x_b = x
    while True:
        hh = sw.substep_length(grid.t[k + 1], sa.kind, ds.cmd_t, ds.cmd_next, rem)
        want = last and hh == rem and rec.V.shape[1] > 0  # the end point's bus voltages
        ok, x_b = _heun(kn, sa, ds, w, x_a, dx_a, hh, j if hh == rem else s, want, w.dx_j)
        if not ok:
            return NO_LOAD_FLOW, k, x
        if hh == rem:
            health.est[k + 1] = _local_error(x_b, dx_a, w.dx_j, hh, health.worst, w.sub_mask)
        theta, first_d = 2.0, -1
        if sa.kind == law.BANG_BANG and hh == rem:
            theta, first_d = sw.locate_switching(kn, grid, sa, ds, opts, w, x_b, k)
        if hh == rem and first_d < 0:
            break
        if first_d >= 0:  # re-integrate up to the first switching instant
            hh = theta * rem
        Pm = sw.powers_after(sa, ds.P, ds.target, ds.e, hh)
        if first_d >= 0:
            xm = x_a + hh * dx_a
            if w.sub:  # (w.u_a: the inputs at x_a, kept by _heun)
                sub.sub_heun_start(kn.p, x_a, w.u_a, w.u_a, w.phi_a, hh, xm)
            sw.inject(sa, Pm, kn.kept.S_extra, xm)
            if _evaluate(kn, xm, s, NO_BUS_VOLTAGES, w.dx_j) < 0:
                return NO_LOAD_FLOW, k, x
            x_next = x_a + 0.5 * hh * (dx_a + w.dx_j)
            if w.sub:
                sub.sub_heun_end(kn.p, x_a, kn.out.exc_in, w.phi_a, w.phi_p, hh, x_next)
            x_a = x_next
        else:  # up to the scheduled command (the predictor drew Pm)
            x_a = x_b
        sw.delivered(sa, Pm, kn.kept, w.P_b)
        sw.account(sa, w.P_a, w.P_b, ds.e, hh, rec.stats)
        rem -= hh
        assign(ds.P, Pm)
        ok, dx_a = _resume(kn, grid, sa, ds, opts, w, rec, x_a, _SplitPoint(k, rem, first_d))
        if not ok:
            return NO_LOAD_FLOW, k, x
        x_b = x_a
        if rem <= 1e-15:
            break
    if sa.pmax.size > 0 and rem > 1e-15:  # the predictor drew these powers
        Pn = sw.powers_after(sa, ds.P, ds.target, ds.e, rem)
        sw.delivered(sa, Pn, kn.kept, w.P_b)
        sw.account(sa, w.P_a, w.P_b, ds.e, rem, rec.stats)
        assign(ds.P, Pn)
    return OK, k, x_b


@kernel(inline="always")
def _step(kn, grid, sa, ds, opts, w, rec, health, x, k):
    """One step from grid index k: the network at t_k (PSTess evaluates an interval's first
    step twice; the first pass's clamps stay), the controller there, the record of t_k,
    then the sub-steps.  Returns (status, index, state)."""
    s = grid.interval[k]
    if sa.pmax.size > 0:
        sw.inject(sa, ds.P, kn.kept.S_extra, x)
    if grid.first[k] and opts.pst:
        V_keep = kn.kept.V.copy()
        _evaluate(kn, x, s, NO_BUS_VOLTAGES, w.dx_k)
        assign(kn.kept.V, V_keep)
    if _evaluate(kn, x, s, rec.V.shape[1] > 0, w.dx_k) < 0:
        return NO_LOAD_FLOW, max(k - 1, 0), x
    w.switched[:] = False
    if sa.pmax.size > 0:
        _control_at_grid_point(kn, grid, sa, ds, opts, w, rec, x, k)
        sw.delivered(sa, ds.P, kn.kept, w.P_a)
    _record(rec, k, x, kn.out, w.P_a)
    return _substeps(kn, grid, sa, ds, opts, w, rec, health, x, k)


@kernel(inline="always")
def _after_step(kn, grid, sa, ds, opts, w, rec, health, x, k):
    """Numerical health and loss of synchronism after the step from k (the state at
    k + 1, judged by its stage, `_judged_stage`): (status, index)."""
    stage = _judged_stage(grid, k + 1)
    if not _healthy(x, health.est[k + 1], kn.p.n_mac, health, opts.judged[stage]):
        return UNSTABLE_STEP, k
    if opts.stop and _separated(x, kn.p.n_mac, opts, stage):
        sw.delivered(sa, ds.P, kn.kept, w.P_b)
        _record(rec, k + 1, x, kn.out, w.P_b)
        return SEPARATED, k + 1
    return OK, k


@kernel(inline="always")
def _record_paused(kn, grid, sa, ds, rec, w, x, k1):
    """Store the outputs at k1 where a run pauses, from copies (the next call evaluates it
    for real)."""
    V_keep, held_keep, stage_keep = kn.kept.V.copy(), kn.kept.held.copy(), kn.held_stage[0]
    xc = x.copy()
    sw.inject(sa, ds.P, kn.kept.S_extra, xc)
    _evaluate(kn, xc, grid.interval[k1], rec.V.shape[1] > 0, w.dx_k)
    sw.delivered(sa, ds.P, kn.kept, w.P_b)
    assign(kn.kept.V, V_keep)
    assign(kn.kept.held, held_keep)
    kn.held_stage[0] = stage_keep
    _record(rec, k1, x, kn.out, w.P_b)


@njit
def integrate(c, k0, k1, grid, nets, p, sa, opts, rec, evaluate):
    """PST's predictor-corrector from grid index k0 to k1 (module docstring).

    Parameters
    ----------
    c : Carry
        State, kept buses, devices and health; updated in place, so that a run can be
        continued.
    k0, k1 : int
        First and last grid index.
    grid : StepGrid
        The grid (`step_grid`).
    nets : KernelNetwork
        Network matrices stacked by interval (`stabctl.dynamics.model.stacked_networks`).
    p : stabctl.dynamics.model.KernelParams
        Model parameters.
    sa : stabctl.storage.devices.StorageArrays
        The storage devices.  Bang-bang devices: a mode change within a step has its
        instant located (`stabctl.storage.control.crossing`) and the step is
        re-integrated in two parts.  Externally commanded devices: each command of the
        schedule (c.devices.cmd_t sorted) takes effect at its exact time, splitting the
        step.
    opts : RunOptions
        Event semantics, each stage's islands, COI weights and judged machines (the
        devices' relative speeds and the separation check), separation limit and stop.
    rec : Recording
        Filled at every index with the predictor-stage outputs, the states, the device
        powers, their switching and energy statistics and the switching log.
    evaluate : int
        Machine-code address of `stabctl.dynamics.model.evaluate_kernel` for these
        arguments (`stabctl.dynamics.model.evaluate_address`).

    Returns
    -------
    status : int
        OK, SEPARATED (stopped at loss of synchronism), UNSTABLE_STEP (`_healthy` failed
        after the step from the index), NO_LOAD_FLOW.
    k : int
        The last stored grid index.
    """
    c, grid, nets, p, sa, opts, rec = borrowed((c, grid, nets, p, sa, opts, rec))
    n = grid.interval.size
    out = kernel_outputs(p.n_mac, nets.R.shape[1], p.n_ibr, p.n_exc)
    kn = _Kernel(p, nets, c.kept, c.held_stage, out, evaluate)
    w = _workspace(c.x, sa.pmax.size, p, out.exc_in)
    x = c.x.copy()
    for k in range(k0, min(k1, n - 1)):
        status, k_end, x = _step(kn, grid, sa, c.devices, opts, w, rec, c.health, x, k)
        if status == OK:
            status, k_end = _after_step(kn, grid, sa, c.devices, opts, w, rec, c.health, x, k)
        if status != OK:
            assign(c.x, x)
            return status, k_end
    assign(c.x, x)
    if k1 >= n - 1:
        sw.delivered(sa, c.devices.P, kn.kept, w.P_b)
        _record(rec, n - 1, x, kn.out, w.P_b)
        return OK, n - 1
    _record_paused(kn, grid, sa, c.devices, rec, w, x, k1)
    return OK, k1
