"""Time-domain simulation: PST's predictor-corrector on a grid that lands on every event.

Integrator (PSTess 1.1 `s_simu.m`, docs/pst_models.md 7): explicit Heun (modified Euler),
each state advanced by x_j = x_k + h/2 (f(x_k) + f(x_k + h f(x_k))) with the network solved
at both stages.  Event times are grid points: each interval between events is divided into
fix(length/h) equal steps, so the run restarts exactly at every event.  Two semantics:

- ``"pst"`` (default): PSTess's own, so that trajectories match PSTess; the corrector of the
  step ending at an event already uses the post-event network, and the first step of each
  interval after the first is evaluated once more before it is taken (its limiter clamps
  persist), as PSTess does.
- ``"exact"``: each step uses the network of the interval it lies in.

Loss of synchronism: a machine's angle leaves the centre of inertia (eq. 40, weights H*MVA)
by more than `separation_limit` rad; the separated machines are the smaller coherent group
(`separated_group`); the run can stop there.  A run that produces
non-finite values or meets a singular network raises SimulationError carrying the
trajectory up to that point.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from . import events as ev_
from .case import Case
from .dynamic import DynamicModel, OperatingPoint
from .errors import InputError, SimulationError
from .results import SimulationResult


@dataclass(frozen=True)
class TimeGrid:
    """Integration grid: t (N+1,), interval id of each point (a point at an event belongs to
    the interval that starts there), step h of each interval, and the interval start times."""

    t: np.ndarray
    interval: np.ndarray
    h: np.ndarray
    starts: np.ndarray


def time_grid(switch_times, t_end: float, h: float) -> TimeGrid:
    """PST's grid: intervals between switching times, fix(length/h) steps each (>= 1).

    Raises InputError for a non-positive step or end time.
    """
    if not (h > 0 and t_end > 0):
        raise InputError(f"need a positive step and end time, got h={h}, t_end={t_end}")
    pts = sorted({0.0, float(t_end), *[float(s) for s in switch_times if 0 < s < t_end]})
    ts, ids, hs = [], [], []
    for s, (a, b) in enumerate(zip(pts[:-1], pts[1:])):
        n = max(1, int(np.trunc((b - a) / h)))
        hs.append((b - a) / n)
        ts.append(a + hs[-1] * np.arange(n))
        ids.append(np.full(n, s))
    t = np.concatenate(ts + [[pts[-1]]])
    interval = np.concatenate(ids + [[len(pts) - 2]])
    return TimeGrid(t=t, interval=interval, h=np.array(hs), starts=np.array(pts[:-1]))


def default_step(case: Case) -> float:
    """The data file's own step (sw_con row 1, col 7), else 1/120 s (half a 60 Hz cycle)."""
    sw = case.sw_con
    if sw is not None and sw[0, 6] > 0:
        return float(sw[0, 6])
    return 0.5 / case.freq_hz


class Simulator:
    """Runs disturbances on one case from its solved power flow.

    Args:
        case: the case; op: its operating point (default: solved by `stabctl.powerflow`);
        injection_buses: buses kept for device injections (storage).
    """

    def __init__(self, case: Case, op: OperatingPoint | None = None, injection_buses=()):
        if op is None:
            from .powerflow import solve_powerflow
            op = OperatingPoint.from_bus_matrix(solve_powerflow(case).bus_matrix())
        self.case, self.op = case, op
        self.model = DynamicModel(case, op, injection_buses)
        mp = self.model.mp
        self.inertia = mp.H * case.machines.mva

    def run(self, events=(), t_end: float = 5.0, h: float | None = None,
            semantics: str = "pst", separation_limit: float = np.pi,
            stop_at_separation: bool = False, injection=None) -> SimulationResult:
        """Simulate `events` (see `stabctl.events`) from t = 0 to t_end (s) with step h.

        injection: optional callable (t, x, outputs) -> complex power drawn at the kept buses
            (n_nc,), evaluated at every stage (storage devices; see `stabctl.storage`).
        Raises:
            InputError, UnknownBusError, CaseError: bad events or step;
            SimulationError: divergence (carries the partial result as `.result`).
        """
        if semantics not in ("pst", "exact"):
            raise InputError(f"semantics must be 'pst' or 'exact', got {semantics!r}")
        events = list(events)
        ev_.validate(self.case, events, t_end)
        h = default_step(self.case) if h is None else h
        grid = time_grid([t for e in events for t in e.times()], t_end, h)
        m = self.model
        nets = [m.network(ev_.configuration(self.case, events, s, self.op.V))
                for s in grid.starts]
        rec = _Recorder(grid.t.size, m)
        x, V_nc = m.x0.copy(), m.V_nc0.copy()
        wall = time.perf_counter()
        first_of_interval = np.r_[False, np.diff(grid.interval) > 0]
        S = (lambda t, x, out: None) if injection is None else injection
        out = None
        try:
            for k in range(grid.t.size - 1):
                iv = grid.interval[k]
                net_k = nets[iv]
                hk = grid.h[iv]
                S_k = S(grid.t[k], x, out)
                if first_of_interval[k] and semantics == "pst":
                    m.evaluate(x, net_k, V_nc, S_k)        # PSTess's repeated step: clamps stay
                f_k, out = m.evaluate(x, net_k, V_nc, S_k)
                rec.store(k, x, out)
                xp = x + hk * f_k
                net_j = nets[grid.interval[k + 1]] if semantics == "pst" else net_k
                S_j = S(grid.t[k + 1], xp, out)
                f_j, out = m.evaluate(xp, net_j, out.V_nc, S_j)
                x = x + 0.5 * hk * (f_k + f_j)
                V_nc = out.V_nc
                if not np.all(np.isfinite(x)):
                    raise SimulationError(f"non-finite state at t = {grid.t[k + 1]:.4f} s")
                if rec.check_separation(k + 1, x, self.inertia, separation_limit, grid.t) \
                        and stop_at_separation:
                    rec.store(k + 1, x, out)
                    return rec.result(self, grid.t, k + 2, time.perf_counter() - wall)
            rec.store(grid.t.size - 1, x, out)
        except SimulationError as exc:
            res = rec.result(self, grid.t, max(rec.n_stored, 1), time.perf_counter() - wall)
            raise SimulationError(f"case '{self.case.name}': {exc}", result=res) from exc
        return rec.result(self, grid.t, grid.t.size, time.perf_counter() - wall)


def separated_group(delta: np.ndarray, inertia: np.ndarray) -> np.ndarray:
    """Machines that lost synchronism: split the rotor angles at their largest gap into two
    coherent groups and return the indices of the group with the smaller inertia (the
    leading group on a tie), sorted."""
    order = np.argsort(delta)
    cut = int(np.argmax(np.diff(delta[order]))) + 1
    lagging, leading = order[:cut], order[cut:]
    m_lag, m_lead = inertia[lagging].sum(), inertia[leading].sum()
    group = leading if m_lead <= m_lag * (1 + 1e-9) else lagging
    return np.sort(group)


class _Recorder:
    """Preallocated trajectories (PST stores the predictor-stage outputs at each index)."""

    def __init__(self, n, m: DynamicModel):
        nm, nb = m.mp.n, m.case.n_bus
        self.m = m
        self.speed, self.angle = np.zeros((n, nm)), np.zeros((n, nm))
        self.pelect, self.pmech, self.efd = np.zeros((n, nm)), np.zeros((n, nm)), np.zeros((n, nm))
        self.V = np.zeros((n, nb), complex)
        self.n_stored = 0
        self.t_sep, self.separated = None, []

    def store(self, k, x, out):
        xm = self.m.layout.view(x, "mac")
        self.angle[k], self.speed[k] = xm[0], xm[1]
        self.pelect[k], self.pmech[k], self.efd[k] = out.pelect, out.pmech, out.efd
        self.V[k] = out.V_bus
        self.n_stored = max(self.n_stored, k + 1)

    def check_separation(self, k, x, inertia, limit, t) -> bool:
        if self.t_sep is not None:
            return True
        delta = self.m.layout.view(x, "mac")[0]
        if np.max(np.abs(delta - delta @ inertia / inertia.sum())) <= limit:
            return False
        self.t_sep = float(t[k])
        group = separated_group(delta, inertia)
        self.separated = [int(n) for n in self.m.case.machines.number[group]]
        return True

    def result(self, sim: Simulator, t, n, wall) -> SimulationResult:
        c = sim.case
        return SimulationResult(
            t=t[:n].copy(), machines=c.machines.number.astype(int), buses=c.buses.number.astype(int),
            speed=self.speed[:n], angle=self.angle[:n], pelect=self.pelect[:n],
            pmech=self.pmech[:n], efd=self.efd[:n], vmag=np.abs(self.V[:n]),
            vang=np.angle(self.V[:n]), inertia=sim.inertia, stable=self.t_sep is None,
            t_separation=self.t_sep, separated=self.separated,
            meta={"case": c.name, "wall_time_s": wall})
