"""Single-machine equivalent (SIME) of a multi-machine trajectory and the first-order effect
of storage on its transient-stability margin (docs/placement.md, sections 2-3).

SIME (Pavella, Ernst, Ruiz-Vega, Transient Stability of Power Systems: A Unified Approach
to Assessment and Control, Kluwer 2000, ch. 2-3) maps a simulated multi-machine run onto
the paper's OMIB (Sections 2-4): the machines that lose synchronism (critical group C)
against the rest (N), each group lumped at its centre of inertia (paper eq. 40, weights
M_k = 2 H_k S_k / (S_base omega_s), pu*s^2/rad),

    delta = sigma (delta_C - delta_N),   omega = d(delta)/dt,   M = M_C M_N / (M_C + M_N),

sigma = +1 when C runs ahead, -1 when it falls behind, so that the run-away is always in
+delta.  The OMIB obeys M d(omega)/dt = P_a(t) (its accelerating power); an ESD j drawing
P_j s_j(t) (s_j in {-1, 0, +1}: the bang-bang mode; pu) changes it by
-sigma g_j P_j s_j(t) with g_j = M (sum_C beta_kj / M_C - sum_N beta_kj / M_N), where
beta_kj is the share of machine k in a power drawn at the ESD bus (`distribution_factors`).

Unstable margin (SIME's): on the swing where synchronism is lost, omega passes through a
positive minimum at the OMIB's unstable angle delta_u, where P_a = 0; the margin is the
kinetic energy left there, eta = -M omega(t_u)^2 / 2 (pu*rad, the equal-area excess of
the accelerating over the decelerating area).  First order in the ratings (trajectory and
switching held, the shift of t_u is second order because P_a(t_u) = 0):

    d eta / d P_j = g_j * integral_{t_0}^{t_u} s_j(t) sigma omega(t) dt    (rad)

from the start of the run: the ESD's absorbed power adds g_j P_j to the decelerating power
of the critical group while it is on, i.e. g_j P_j times the angle it is on for, on every
swing up to the one that runs away (exact for a conservative OMIB whose unstable angle
stays put; the first swing alone for a first-swing instability).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from stabctl.dynamics.coi import (
    coi_angle,
    coi_of_islands,
    coi_of_rest,
    coi_speed,
)
from stabctl.dynamics.results import SimulationResult
from stabctl.errors import InputError
from stabctl.storage.control import group_reference


@dataclass(frozen=True)
class OmibEquivalent:
    """The OMIB of one run: t (n_t,) s; delta (n_t,) rad and omega (n_t,) electrical rad/s
    oriented so that the critical group runs away in +delta; M (pu*s^2/rad); critical:
    machine numbers of C; sigma: +1 if C leads N, -1 if it lags; in_critical (n_mac,) bool;
    M_machine (n_mac,) pu*s^2/rad of every machine; in_rest (n_mac,) bool, the machines of
    N, or None: every machine not in C (none tripped nor islanded apart from the main
    grid, `omib_equivalent`)."""

    t: np.ndarray
    delta: np.ndarray
    omega: np.ndarray
    M: float
    critical: tuple
    sigma: int
    in_critical: np.ndarray
    M_machine: np.ndarray
    in_rest: np.ndarray | None = None

    def group_weights(self, beta: np.ndarray) -> np.ndarray:
        """g (n_dev,): effect of 1 pu drawn by each ESD on the OMIB accelerating power
        (dimensionless; beta (n_mac, n_dev) as `distribution_factors`); a group that holds
        an infinite bus does not accelerate: its term is 0."""
        C, Mk = self.in_critical, self.M_machine
        N = ~C if self.in_rest is None else self.in_rest

        def accel(g: np.ndarray):
            return 0.0 if (g & (Mk == 0)).any() else beta[g].sum(axis=0) / Mk[g].sum()

        return self.M * (accel(C) - accel(N))


def critical_machines(result: SimulationResult) -> list[int]:
    """Machines that lost synchronism (`result.separated`); after a divergence without
    separation, the smaller coherent group at the last computed point (largest angle gap,
    as `stabctl.dynamics.driver.separated_group`), among the machines the criterion judges
    there (`SimulationResult.judged`: not tripped nor islanded apart from the main grid);
    none when no machine is judged there (the system de-energised)."""
    if result.separated:
        return [int(k) for k in result.separated]
    from stabctl.dynamics.driver import judged_group, separated_group

    last = result.last_partition()
    if last is not None and not last.judged.any():  # no machine left in service
        return []
    if last is not None:
        return [int(k) for k in result.machines[judged_group(result.angle[-1], last)]]
    return [int(k) for k in result.machines[separated_group(result.angle[-1], result.inertia)]]


def omib_equivalent(
    result: SimulationResult, critical, base_mva: float, freq_hz: float, inertia=None
) -> OmibEquivalent:
    """The OMIB of `result` for the critical machines `critical` (numbers), against the
    rest of the machines the criterion judges at the end of the run
    (`SimulationResult.judged`: every machine, but those tripped or islanded apart from
    the main grid).

    `inertia` (n_mac,) is each machine's H * MVA (MW s, `machine_inertia`); None: the
    run's COI weights (`SimulationResult.inertia`), which are those unless an island holds
    an infinite bus (then 1 for it and 0 for the island's other machines).  A group that
    holds an infinite bus (a machine of H = 0, `stabctl.case.system.MachineTable`) has
    infinite inertia: its centre of inertia is its infinite buses' (their mean), and the
    OMIB's M is the other group's (the paper's Section 2 OMIB against an infinite bus).

    Raises InputError when the critical group is empty or holds every judged machine, or
    when both groups hold an infinite bus (no OMIB moves).
    """
    C = np.isin(result.machines, list(critical))
    judged = result.judged
    N = ~C & judged
    if not C.any() or not N.any():
        raise InputError(
            f"critical group {list(critical)} must be a proper, non-empty subset of the machines"
        )
    ws = 2 * np.pi * freq_hz
    Mk = 2 * np.asarray(result.inertia if inertia is None else inertia, float) / (base_mva * ws)
    (dC, wC, MC), (dN, wN, MN) = (_group_coi(result, Mk, g) for g in (C, N))
    if MC == MN == np.inf:
        raise InputError(
            f"critical group {list(critical)} and the rest each hold an infinite bus: "
            "no equivalent machine swings between them"
        )
    delta, omega = dC - dN, ws * (wC - wN)
    sigma = 1 if delta[-1] >= delta[0] else -1
    return OmibEquivalent(
        t=result.t,
        delta=sigma * delta,
        omega=sigma * omega,
        M=MN if MC == np.inf else MC if MN == np.inf else MC * MN / (MC + MN),
        critical=tuple(int(k) for k in critical),
        sigma=sigma,
        in_critical=C,
        M_machine=Mk,
        in_rest=None if judged.all() else N,
    )


def _group_coi(result: SimulationResult, Mk: np.ndarray, group: np.ndarray) -> tuple:
    """(COI angle (n_t,) rad, COI speed (n_t,) pu, inertia M pu*s^2/rad) of the machines
    `group` (bool, (n_mac,)); with an infinite bus (M_k = 0) among them, the mean of the
    infinite buses' and M = inf."""
    fixed = group & (Mk == 0)
    sel, w = (fixed, np.ones(int(fixed.sum()))) if fixed.any() else (group, Mk[group])
    M = np.inf if fixed.any() else float(Mk[group].sum())
    return coi_angle(result.angle[:, sel], w), coi_speed(result.speed[:, sel], w), M


def unstable_point(eq: OmibEquivalent, t_clear: float) -> int:
    """Grid index k_u of the OMIB's unstable angle (P_a = 0) on the swing that runs away.

    That swing is the last stretch of omega > 0 after clearing.  Going back from the end
    over a final fall to the last speed peak, then over the rise before it to the last
    local minimum: if that rise exceeds the final fall, the run-away dominates and k_u is
    that minimum (the clearing instant when omega only rises: all of the swing
    accelerates); otherwise the run ended (machines judged separated from the centre of
    inertia, or a run stopped at the unstable angle) while the OMIB was still slowing
    down, and k_u is the last point: the kinetic energy left there bounds the margin.
    """
    w = eq.omega
    k_cl = int(np.searchsorted(eq.t, t_clear - 1e-9))
    rest = np.nonzero(w[:-1] <= 0)[0]
    k_a = min(max(k_cl, int(rest[-1]) + 1 if rest.size else 0), w.size - 1)
    k = w.size - 1
    while k > k_a and w[k - 1] >= w[k]:
        k -= 1
    k_pk = k
    while k > k_a and w[k - 1] <= w[k]:
        k -= 1
    return int(k) if w[k_pk] - w[k] > w[k_pk] - w[-1] else w.size - 1


def unstable_margin(eq: OmibEquivalent, k_u: int) -> float:
    """SIME unstable margin -M max(omega(t_u), 0)^2 / 2 (pu*rad, <= 0)."""
    return -0.5 * eq.M * max(float(eq.omega[k_u]), 0.0) ** 2


def clearing_energy_rate(eq: OmibEquivalent, t_clear: float) -> float:
    """M omega dw/dt just before clearing (pu*rad/s): the OMIB kinetic energy that one more
    second of fault adds; 0 when clearing is at the first point."""
    k = int(np.searchsorted(eq.t, t_clear - 1e-9))
    if k < 2:
        return 0.0
    dw = (eq.omega[k - 1] - eq.omega[k - 2]) / (eq.t[k - 1] - eq.t[k - 2])
    return float(eq.M * eq.omega[k - 1] * dw)


def storage_integrals(eq: OmibEquivalent, modes: np.ndarray, k_u: int) -> np.ndarray:
    """integral of s_j(t) * sigma * omega(t) dt from the start of the run to t_u per device
    (n_dev,), rad; modes (n_t, n_dev) in {-1, 0, +1}, each held over the step that starts
    at its grid point (as the simulator holds a device's mode), omega by the trapezoid
    rule.  Over every swing up to the one that runs away: a device absorbing while its
    group runs ahead and injecting while it falls behind removes energy on each swing."""
    if k_u <= 0:
        return np.zeros(modes.shape[1])
    w = eq.sigma * eq.omega[: k_u + 1]
    area = 0.5 * (w[1:] + w[:-1]) * np.diff(eq.t[: k_u + 1])
    return area @ modes[:k_u]


def device_modes(
    result: SimulationResult, buses, machines, controller, freq_hz: float
) -> np.ndarray:
    """The paper's Table 3 mode (+1 absorb, -1 inject, 0 idle) that a bang-bang ESD at each
    of `buses`, driven by the matching machine of `machines`, would take along `result`
    (whether or not it is installed), on the run's grid: (n_t, n_dev).

    controller: `stabctl.storage.devices.BangBangCOI` (deadband, voltage gate, system, rest
    or critical-group COI, hysteresis); freq_hz: the case frequency.  Switching instants
    are those of the grid (the simulator locates them inside the step; the difference is
    below one step).
    """
    idx = np.array([result.machine(int(k)) for k in machines], int)
    w, Mk = result.speed, np.asarray(result.inertia, float)
    if controller.coi == "rest":
        rel = (w[:, idx] - coi_of_rest(w, Mk, idx, result.island)) * freq_hz
    elif controller.coi == "critical":
        group = np.zeros(w.shape[1], np.int64)
        group[[result.machine(int(k)) for k in controller.critical]] = 1
        island = np.asarray(result.island, np.int64)
        ref = np.array([group_reference(wk, Mk, island, group) for wk in w])
        rel = (w[:, idx] - ref[:, idx]) * freq_hz
    else:  # each machine's island's COI, as the simulator's controllers
        rel = result.relative_speed[:, idx] * freq_hz
    v = result.vmag[:, [result.bus(int(b)) for b in buses]]
    return _table3(rel, v >= controller.v_gate_pu, controller.deadband_hz, controller.hysteresis_hz)


def _table3(rel_hz: np.ndarray, gate: np.ndarray, db: float, hyst: float) -> np.ndarray:
    """Modes along the grid: outside +-db switch on, back inside +-(db - hyst) switch off,
    idle below the voltage gate (stateful only when hyst > 0)."""
    on = np.sign(rel_hz) * (np.abs(rel_hz) > db)
    if hyst == 0:
        return np.where(gate, on, 0).astype(int)
    out = np.zeros(rel_hz.shape, int)
    mode = np.zeros(rel_hz.shape[1], int)
    for k in range(rel_hz.shape[0]):
        keep = ((mode == 1) & (rel_hz[k] > db - hyst)) | ((mode == -1) & (rel_hz[k] < hyst - db))
        mode = np.where(gate[k], np.where(keep, mode, on[k]), 0).astype(int)
        out[k] = mode
    return out


def distribution_factors(sys, buses, machines, inertia, base_mva: float) -> np.ndarray:
    """beta (n_mac, n_dev): share of each machine's electrical power in 1 pu drawn at each
    bus of `buses`, at the operating point, from a linearised model
    (`stabctl.smallsignal.linearise`, ESD inputs at those buses; or its ESD columns alone,
    `stabctl.smallsignal.linearise.esd_columns`): beta_kj = -(2 H_k S_k /
    S_base) B[omega_k, P_esd_j] (B in pu speed/s per pu; inertia = H_k S_k in MJ, machines:
    numbers, in that order). Columns sum to ~1 (less the change of losses and voltage-dependent
    loads).

    An infinite bus (inertia 0: its speed held, no state) gets a row of 0: what it
    takes moves no machine's speed.

    Raises InputError when a bus has no ESD input in the model.
    """
    states, inputs = list(sys.state_labels), list(sys.input_labels)
    inertia = np.asarray(inertia, float)
    held = inertia == 0
    rows = [states.index(f"mac_omega_G{int(k)}") for k, h in zip(machines, held) if not h]
    missing = [int(b) for b in buses if f"P_esd_B{int(b)}" not in inputs]
    if missing:
        raise InputError(f"the linearised model has no ESD input at bus(es) {missing}")
    cols = [inputs.index(f"P_esd_B{int(b)}") for b in buses]
    beta = np.zeros((inertia.size, len(cols)))
    beta[~held] = -(2 * inertia[~held] / base_mva)[:, None] * np.asarray(sys.B)[np.ix_(rows, cols)]
    return beta


# -- early verdicts and the margin of a probe (the CCT search, `stabctl.stability.cct`) ------


@dataclass(frozen=True)
class EarlyVerdict:
    """A run monitor (`stabctl.dynamics.driver.Simulator.run`) that ends a run as soon as
    SIME's criteria make its verdict certain (Pavella, Ernst, Ruiz-Vega 2000, ch. 2).

    After the clearing instant `t_clear` (s, absolute), the machines are split at the
    largest gap of their rotor angles (`stabctl.dynamics.driver.separated_group`) into a
    candidate critical group and the rest, and their OMIB (module docstring) is followed:

    - unstable: on the swing since the OMIB last stood still, its speed passed through a
      positive minimum (the unstable angle, where the accelerating power turns positive)
      and has risen ever since, for at least `confirm_s` s (a numerical wiggle never
      passes for it), a machine has moved more than `min_excursion` rad from its
      pre-fault angle to the centre of inertia (swings of several machine groups pass
      through such minima and still turn back: on miniWECC up to 1.6 rad), and the
      machine farthest from it, moving on at its present speed without accelerating
      further, would pass `limit` within `horizon_s` and within half the time left
      before `t_end` (a slow drift that the full run might still judge stable at its
      end is left to it: on miniWECC a machine 2.94 rad from the centre of inertia,
      moving out at 0.36 rad/s on the unstable side of its OMIB, turned back at 3.05);
    - stable: the OMIB of the group split at the instant of the largest excursion from
      the centre of inertia has come to rest (its speed changed sign, a return point
      below the unstable angle) `returns` times, its last swing (between the last two
      return points) was no wider than the one before (no growing oscillation), and the
      machines have settled: over the last `settle_s` s no machine's speed left its
      island's centre of inertia by more than `settle_pu` (the return points alone are
      not enough: on miniWECC a machine whose swings died down can still drift out of
      step 1-2 s later).

    Attributes
    ----------
    t_clear : float
        Clearing instant, s (absolute run time).
    t_end : float
        End of the run, s (absolute).
    freq_hz : float
        The case frequency, Hz.
    limit : float, optional
        The run's separation limit (angle from the centre of inertia), rad; default pi.
    horizon_s : float, optional
        Longest time to `limit` at the present speed of an unstable verdict, s; default
        0.2.
    returns : int, optional
        Return points before a stable verdict (>= 2); default 3.
    confirm_s : float, optional
        Time the OMIB speed must rise after its positive minimum, s; default 0.05.
    min_excursion : float, optional
        Move of a machine's angle to the centre of inertia since before the fault that
        an unstable verdict needs, rad; default 2.
    settle_pu : float, optional
        Largest speed from the centre of inertia of a settled machine, pu; default 3e-4
        (0.018 Hz at 60 Hz).
    settle_s : float, optional
        How long the machines must have stayed settled, s; default 0.5.
    """

    t_clear: float
    t_end: float
    freq_hz: float
    limit: float = np.pi
    horizon_s: float = 0.2
    returns: int = 3
    confirm_s: float = 0.05
    min_excursion: float = 2.0
    settle_pu: float = 3e-4
    settle_s: float = 0.5

    def __call__(self, result: SimulationResult) -> str | None:
        """ "unstable", "stable" or None (not certain yet) for the trajectory so far.

        A run whose events trip machines or cut islands apart (`result.partitions`) is
        judged as its criterion judges it: on the machines in service in the main grid,
        against the COI of their islands, from the start of the last stage on (or the
        clearing, if later); None while fewer than two machines are judged."""
        t = result.t
        k_cl = max(int(np.searchsorted(t, self.t_clear + 1e-9)) - 1, 0)
        if t[-1] - self.t_clear < 2 * self.confirm_s:
            return None
        inertia, island = np.asarray(result.inertia, float), result.island
        every_angle, every_speed = result.angle, result.speed
        last = result.last_partition()
        if last is not None:  # the machines judged now, since their islands were formed
            on = np.flatnonzero(last.judged)
            k_cl = max(k_cl, int(np.searchsorted(t, last.t_s)))
            if on.size < 2 or t[-1] - t[k_cl] < 2 * self.confirm_s:
                return None
            inertia, island = last.inertia[on], last.island[on]
            every_angle, every_speed = result.angle[:, on], result.speed[:, on]
        angle, speed = every_angle[k_cl:], every_speed[k_cl:]
        from stabctl.dynamics.driver import separated_group

        # the cheap tests first (the last point, the last settle_s): most calls stop there
        rel = angle[-1] - coi_of_islands(angle[-1], inertia, island)
        pre = every_angle[0] - coi_of_islands(every_angle[0], inertia, island)
        rel_speed = speed[-1] - coi_of_islands(speed[-1], inertia, island)
        if np.abs(rel - pre).max() > self.min_excursion and self._runs_away(
            rel, rel_speed, float(t[-1])
        ):
            group = separated_group(angle[-1], inertia, island)
            now = _omib_motion(angle, speed, inertia, group)
            if now is not None and _passed_unstable_angle(t[k_cl:], now[0], now[1], self.confirm_s):
                return "unstable"
        recent = speed[t[k_cl:] >= t[-1] - self.settle_s]
        if np.abs(recent - coi_of_islands(recent, inertia, island)).max() > self.settle_pu:
            return None
        dev = np.abs(angle - coi_of_islands(angle, inertia, island)).max(axis=1)
        k_far = int(np.argmax(dev))
        first = _omib_motion(angle, speed, inertia, separated_group(angle[k_far], inertia, island))
        if first is not None and _swings_died_down(first[0], first[1], self.returns):
            return "stable"
        return None

    def _runs_away(self, rel, rel_speed, t_now: float) -> bool:
        """Whether the machine farthest from its centre of inertia (rel: angles from it
        now, rad; rel_speed: speeds from it now, pu) reaches `limit` at its present
        speed within `horizon_s` and half the time left before `t_end`."""
        i = int(np.argmax(np.abs(rel)))
        outward = np.sign(rel[i]) * rel_speed[i] * 2 * np.pi * self.freq_hz  # rad/s
        within = min(self.horizon_s, 0.5 * (self.t_end - t_now))
        return bool(outward > 0 and self.limit - abs(rel[i]) < outward * within)


def _omib_motion(angle, speed, inertia, group):
    """(delta, omega) of the OMIB of `group` (indices) against the rest, unoriented (rad,
    pu speed difference); None when either side has no inertia weight."""
    C = np.zeros(inertia.size, bool)
    C[group] = True
    if not (inertia[C].sum() > 0 and inertia[~C].sum() > 0):
        return None
    delta = coi_angle(angle[:, C], inertia[C]) - coi_angle(angle[:, ~C], inertia[~C])
    omega = coi_speed(speed[:, C], inertia[C]) - coi_speed(speed[:, ~C], inertia[~C])
    return delta, omega


def _passed_unstable_angle(t, delta, omega, confirm_s: float) -> bool:
    """SIME's instability: oriented so that the group runs away in +delta, the OMIB speed
    had a positive minimum since it last stood still and rose for confirm_s s since."""
    w = omega if delta[-1] >= delta[0] else -omega
    rest = np.nonzero(w <= 0)[0]
    j0 = int(rest[-1]) + 1 if rest.size else 0
    k = w.size - 1
    while k > j0 and w[k - 1] < w[k]:
        k -= 1
    return j0 < k < w.size - 1 and w[k] > 0 and t[-1] - t[k] >= confirm_s


def _swings_died_down(delta, omega, returns: int) -> bool:
    """At least `returns` return points (sign changes of the OMIB speed), the swing
    between the last two no wider than the one before."""
    s = np.sign(omega)
    turns = np.nonzero(s[1:] * s[:-1] < 0)[0] + 1
    if turns.size < returns:
        return False
    ext = np.r_[delta[0], delta[turns]]
    return abs(ext[-1] - ext[-2]) <= abs(ext[-2] - ext[-3])


def probe_margin(
    result: SimulationResult, t_clear: float, base_mva, freq_hz, inertia=None
) -> float | None:
    """SIME's unstable margin of an unstable probe of a CCT search.

    Parameters
    ----------
    result : SimulationResult
        An unstable run (stopped early or at separation, or complete).
    t_clear : float
        Clearing instant, s (absolute run time).
    base_mva, freq_hz : float
        The case's base (MVA) and frequency (Hz).
    inertia : ndarray, shape (n_mac,), or None, optional
        The machines' H * MVA, MW s (`machine_inertia`; `omib_equivalent`).

    Returns
    -------
    float or None
        `unstable_margin` (pu*rad, <= 0) at the unstable point (`unstable_point`) of the
        OMIB of the critical machines (`critical_machines`); None when that group is not
        a proper subset of the machines.  Close to linear in the clearing time near the
        CCT (Pavella, Ernst, Ruiz-Vega 2000, ch. 3), so that two unstable probes
        extrapolate to it.
    """
    try:
        eq = omib_equivalent(result, critical_machines(result), base_mva, freq_hz, inertia)
    except InputError:
        return None
    return unstable_margin(eq, unstable_point(eq, t_clear))
