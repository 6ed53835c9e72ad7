"""The storage devices inside the compiled integrator: their state, what they see, their
set-points and powers, energy accounting, scheduled commands and the location of bang-bang
switchings within a step.

What the devices' energies count is the power the network takes (`delivered`): a device
at a bus below PST's low-voltage switch is dropped by the network solution, and neither
its recorded power nor its state of charge counts its command there.

Bang-bang devices (paper Table 3): a mode change within a step has its instant located
(`locate_switching`, `stabctl.storage.control.crossing`) and the step is re-integrated in
two parts (`stabctl.dynamics.integrator`); each device switches at most once per step.
Externally commanded devices: each command of the schedule takes effect at its exact time
(`apply_commands`, `substep_length`).  Every switching is counted and logged
(`log_switching`) in the run's `stabctl.dynamics.integrator.Recording`.

What the devices see (`observe`): each device's machine's speed relative to the centre of
inertia of its island in the current network stage (`stabctl.dynamics.partition`; the
stage's islands and weights in `stabctl.dynamics.integrator.RunOptions`), not of the
islands before the disturbance.  Once a stage cuts a machine off the main grid, its device
follows the COI of the machine's own island (a machine alone: relative speed 0, the device
idles), and the devices of the main grid the COI of the main grid without it; the device
of a tripped machine sees 0 and idles (`stabctl.storage.control.relative_speeds`).  The
islands change at the grid point where the stage starts (events are grid points); a step
is observed at both ends with the islands of its own stage.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.network.solution import constant_power_on
from stabctl.storage import control as law
from stabctl.storage import devices as st


class DeviceState(NamedTuple):
    """Controller and device state carried across `stabctl.dynamics.integrator.integrate`
    calls (n_dev entries): mode (-1, 0, +1; an external set-point in units of the rating),
    power P (pu), power target, energy content e (pu*s); the command schedule of externally
    commanded devices: cmd_t (n_cmd,) times (s, inf until scheduled), cmd_mode (n_cmd, n_dev)
    set-points, and its next entry cmd_next[0]."""

    mode: np.ndarray
    P: np.ndarray
    target: np.ndarray
    e: np.ndarray
    cmd_next: np.ndarray
    cmd_t: np.ndarray
    cmd_mode: np.ndarray


def device_state(sa, n_commands: int = 0) -> DeviceState:
    """Initial device state: idle, no power, the initial energy sa.e0.

    Parameters
    ----------
    sa : stabctl.storage.devices.StorageArrays
        The packed fleet (n_dev devices).
    n_commands : int
        Room in the command schedule.

    Returns
    -------
    DeviceState
    """
    nd = sa.pmax.size
    return DeviceState(
        np.zeros(nd),
        np.zeros(nd),
        np.zeros(nd),
        sa.e0.copy(),
        np.zeros(1, np.int64),
        np.full(n_commands, np.inf),
        np.zeros((n_commands, nd)),
    )


class Seen(NamedTuple):
    """What the devices see at one point (n_dev each): speed relative to the COI r (pu),
    bus voltage v (pu), relative acceleration acc (pu/s)."""

    r: np.ndarray
    v: np.ndarray
    acc: np.ndarray


@kernel
def log_switching(rec, d, time_, mode, r):
    """Count a switching of device d and log it (time s, device, new mode, rel. speed)."""
    row = int(rec.stats[:, 0].sum())
    rec.stats[d, 0] += 1
    if row < rec.log.shape[0]:
        rec.log[row, 0], rec.log[row, 1], rec.log[row, 2], rec.log[row, 3] = time_, d, mode, r


@kernel
def inject(sa, P, S, x):
    """The devices' powers P (absorbing is +) into the state x to be evaluated: an ideal
    device's drawn at its kept bus (S, complex power per kept bus), a WECC battery's as
    its plant's P reference (-P written to its converter's slot, `sa.xslot`)."""
    S[:] = 0.0
    for d in range(P.size):
        if sa.xslot[d] >= 0:
            x[sa.xslot[d]] = -P[d]
        else:
            S[sa.pos[d]] += P[d]


# -- device control and energy accounting --------------------------------------------------


@kernel
def targets(sa, mode, r, v, accel, out):
    """Device power set-points: bang-bang modes times ratings, or the linear law."""
    for d in range(out.size):
        if sa.kind == law.BANG_BANG:
            out[d] = mode[d] * sa.pmax[d]
        elif sa.kind == law.EXTERNAL:
            out[d] = mode[d] * sa.pmax[d] if v[d] >= sa.vgate else 0.0
        elif v[d] < sa.vgate:
            out[d] = 0.0
        else:
            out[d] = min(max(sa.Kv * r[d] + sa.Ka * accel[d], -sa.pmax[d]), sa.pmax[d])


@kernel
def powers_now(sa, ds):
    """Device powers at once on their targets (ideal devices; lags and ramps keep them);
    returns whether any changed."""
    changed = False
    for d in range(ds.P.size):
        Pn = st.device_power(sa, d, ds.target[d], ds.P[d], ds.e[d], 0.0)
        changed = changed or Pn != ds.P[d]
        ds.P[d] = Pn
    return changed


@kernel
def powers_after(sa, P, target, e, hh):
    """Device powers after hh seconds from P following their targets (`device_power`,
    with the energy content e at the start: e is not changed)."""
    Pn = np.empty_like(P)
    for d in range(P.size):
        Pn[d] = st.device_power(sa, d, target[d], P[d], e[d], hh)
    return Pn


@kernel
def delivered(sa, P, kept, out):
    """The powers the network takes from the devices (out, n_dev; + absorbs) with their
    powers P injected and the kept buses `kept` (`stabctl.dynamics.model.KeptBuses`) as the
    network solution left them: P, except at a bus below PST's low-voltage switch (or held
    at its impedance model), where the network drops the device's power entirely
    (`stabctl.network.solution.constant_power_on`): 0.  A WECC battery's power is its
    converter's (a current drawn at every voltage): P, its plant's reference."""
    for d in range(P.size):
        i = sa.pos[d]
        if sa.xslot[d] >= 0 or constant_power_on(kept.V[i], kept.held[i]):
            out[d] = P[d]
        else:
            out[d] = 0.0


@kernel
def account(sa, Pa, Pb, e, hh, stats):
    """Energy over a sub-step of hh seconds from the delivered powers Pa at its start and
    Pb at its end (`delivered`; pu): the energy content e (pu*s) and the energy absorbed
    and delivered (stats columns 1, 2) by trapezoid, and the extremes of the SOC relative
    to its start (columns 3, 4).  Sub-steps end at every located switching, so for ideal
    devices (power constant within a sub-step, the SOC linear) these extremes are exact,
    not sampled at grid points.  A device dropped by the network at both ends keeps its
    SOC."""
    for d in range(Pa.size):
        e[d] += 0.5 * hh * (Pa[d] + Pb[d])
        stats[d, 1] += 0.5 * hh * (max(Pa[d], 0.0) + max(Pb[d], 0.0))
        stats[d, 2] += 0.5 * hh * (max(-Pa[d], 0.0) + max(-Pb[d], 0.0))
        soc = e[d] - sa.e0[d]
        stats[d, 3] = max(stats[d, 3], soc)
        stats[d, 4] = min(stats[d, 4], soc)


@kernel
def observe(x, dx, nm, opts, s, sa, V_nc, seen):
    """What the devices see (module docstring): relative speeds, bus voltages and relative
    accelerations.

    Parameters
    ----------
    x, dx : ndarray, shape (n_state,)
        Flat state and its derivatives.
    nm : int
        Machines.
    opts : stabctl.dynamics.integrator.RunOptions
        Each stage's islands and COI weights, (n_stage, n_mac).
    s : int
        The network stage whose islands the devices observe.
    sa : stabctl.storage.devices.StorageArrays
        The devices.
    V_nc : ndarray of complex, shape (n_kept,)
        Kept-bus voltages, pu.
    seen : Seen
        Written: r (pu) and acc (pu/s) against the COI of the machine's island in stage s
        (`stabctl.storage.control.relative_speeds`; 0 for a tripped machine or one alone
        in its island), v (pu).
    """
    law.relative_speeds(x, nm, opts.inertia[s], opts.island[s], sa, seen.r)
    law.relative_speeds(dx, nm, opts.inertia[s], opts.island[s], sa, seen.acc)
    for d in range(seen.r.size):
        seen.v[d] = abs(V_nc[sa.pos[d]])


# -- commands ------------------------------------------------------------------------------


@kernel
def apply_commands(ds, t_now, rec, r):
    """Apply every scheduled command due by t_now (externally commanded devices); a
    change of the set-point's sign (idle, absorb, inject) is logged as a switching."""
    while ds.cmd_next[0] < ds.cmd_t.size and ds.cmd_t[ds.cmd_next[0]] <= t_now + 1e-12:
        c = ds.cmd_next[0]
        for d in range(ds.mode.size):
            if np.sign(ds.cmd_mode[c, d]) != np.sign(ds.mode[d]):
                log_switching(rec, d, ds.cmd_t[c], np.sign(ds.cmd_mode[c, d]), r[d])
            ds.mode[d] = ds.cmd_mode[c, d]
        ds.cmd_next[0] += 1


@kernel
def substep_length(t_end, kind, cmd_t, cmd_next, rem):
    """Length of the next sub-step of a step ending at t_end (s) with rem seconds left:
    the rest, or for externally commanded devices (kind, `law.EXTERNAL`) up to the next
    scheduled command (cmd_t, cmd_next: `DeviceState`) if one falls inside."""
    if kind == law.EXTERNAL and cmd_next[0] < cmd_t.size and cmd_t[cmd_next[0]] < t_end - 1e-12:
        return max(cmd_t[cmd_next[0]] - (t_end - rem), 0.0)
    return rem


@kernel(inline="always")
def locate_switching(kn, grid, sa, ds, opts, w, x_b, k):
    """First bang-bang switching inside the step from grid index k (state x_b and w.dx_j at
    its end): (fraction of the step, device), (2.0, -1) if none.  A device switches at most
    once per step; a voltage-gate jump at an event is taken at the grid point, and so is
    a change of the islands (both ends are observed with the islands of the step's stage,
    grid.interval[k]: the relative speeds jump at the grid point where the stage starts,
    `observe` there)."""
    observe(x_b, w.dx_j, kn.p.n_mac, opts, grid.interval[k], sa, kn.kept.V, w.b)
    at_event = grid.interval[k + 1] != grid.interval[k]
    theta, first_d = 2.0, -1
    for d in range(sa.pmax.size):
        if w.switched[d]:  # one switching per device and step: no chattering loop
            continue
        want = law.desired_mode(sa, d, ds.mode[d], w.b.r[d], w.b.v[d])
        gate_jump = (w.a.v[d] >= sa.vgate) != (w.b.v[d] >= sa.vgate)
        if want != ds.mode[d] and not (at_event and gate_jump):  # events: at t_k+1
            th, _ = law.crossing(sa, ds.mode[d], want, w.a.r[d], w.b.r[d], w.a.v[d], w.b.v[d])
            if th < theta:
                theta, first_d = th, d
    return theta, first_d


@kernel
def switch_located(sa, ds, w, rec, first_d, t_now):
    """At the located instant t_now: switch device first_d, and any other whose crossing
    falls there too (within 1e-9 of the step)."""
    for d in range(sa.pmax.size):
        want = law.desired_mode(sa, d, ds.mode[d], w.b.r[d], w.b.v[d])
        if want != ds.mode[d] and not w.switched[d]:
            th, new = law.crossing(sa, ds.mode[d], want, w.a.r[d], w.b.r[d], w.a.v[d], w.b.v[d])
            if d == first_d or th <= 1e-9:
                ds.mode[d] = new
                w.switched[d] = True
                log_switching(rec, d, t_now, new, w.a.r[d])
