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
from typing import NamedTuple

import numpy as np
from numba import njit

from . import events as ev_
from .case import Case
from .dynamic import DynamicModel, OperatingPoint, evaluate_kernel
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


_BLAS_LIMITED = False


def single_threaded_blas() -> None:
    """Limit BLAS/LAPACK to one thread in this process (once).

    The kernels solve many tiny dense systems; OpenBLAS threads make each solve 10-20 times
    slower and oversubscribe the cores when sweeps run one simulation per process.  The
    environment defaults set in `stabctl/__init__` do not reach a BLAS that numpy loaded
    before stabctl was imported, hence this run-time limit (threadpoolctl).
    """
    global _BLAS_LIMITED
    if not _BLAS_LIMITED:
        import scipy.linalg.cython_lapack  # noqa: F401  the LAPACK numba calls: load it first
        from threadpoolctl import threadpool_limits
        threadpool_limits(limits=1, user_api="blas")
        _BLAS_LIMITED = True


def fastest_time_constant(model: DynamicModel) -> tuple[float, str]:
    """Smallest time constant among the states of the model (s) and where it is."""
    from .exciters import LBND
    cands = []
    mp, ep, pp, gp = model.mp, model.ep, model.pp, model.gp
    for name, arr, rows, active in (
            ("mac_con T\"do", mp.Tdopp, mp.kind == 2, None), ("mac_con T\"qo", mp.Tqopp, mp.kind == 2, None),
            ("exc_con T_R", ep.TR, ep.has_TR, None), ("exc_con T_A", ep.TA, ep.has_TA, None),
            ("exc_con T_B", ep.TB, ep.has_TB, None), ("pss_con T_w", pp.Tw, None, None),
            ("pss_con T_2", pp.T2, None, None), ("pss_con T_4", pp.T4, pp.T4 >= LBND, None),
            ("tg_con T_s", gp.Ts, None, None), ("tg_con T_c", gp.Tc, None, None),
            ("tg_con T_5", gp.T5, None, None)):
        sel = np.ones(arr.size, bool) if rows is None else rows
        if np.any(sel):
            k = int(np.argmin(np.where(sel, np.abs(arr), np.inf)))
            cands.append((float(abs(arr[k])), f"{name} row {k + 1}"))
    return min(cands) if cands else (np.inf, "")


def check_step(model: DynamicModel, h: float) -> None:
    """Raise InputError when h exceeds twice the fastest time constant: the explicit
    predictor-corrector is unstable there (its stability interval is h/T < 2)."""
    T, where = fastest_time_constant(model)
    if h >= 2 * T:
        raise InputError(f"step {h} s is too large: the fastest time constant is {T} s "
                         f"({where}); the predictor-corrector needs h < {2 * T} s")


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
        single_threaded_blas()
        self.case, self.op = case, op
        self.model = DynamicModel(case, op, injection_buses)
        mp = self.model.mp
        self.inertia = mp.H * case.machines.mva

    def run(self, events=(), t_end: float = 5.0, h: float | None = None,
            semantics: str = "pst", separation_limit: float = np.pi,
            stop_at_separation: bool = False) -> SimulationResult:
        """Simulate `events` (see `stabctl.events`) from t = 0 to t_end (s) with step h.

        Raises:
            InputError, UnknownBusError, CaseError: bad events or step;
            SimulationError: divergence (carries the partial result as `.result`).
        """
        if semantics not in ("pst", "exact"):
            raise InputError(f"semantics must be 'pst' or 'exact', got {semantics!r}")
        events = list(events)
        ev_.validate(self.case, events, t_end)
        h = default_step(self.case) if h is None else h
        check_step(self.model, h)
        grid = time_grid([t for e in events for t in e.times()], t_end, h)
        m = self.model
        nets = [m.network(ev_.configuration(self.case, events, s, self.op.V))
                for s in grid.starts]
        stack = lambda name: np.ascontiguousarray(np.stack([getattr(n, name) for n in nets]))  # noqa: E731
        N, nm, nb = grid.t.size, m.mp.n, self.case.n_bus
        rec = Recording(speed=np.zeros((N, nm)), angle=np.zeros((N, nm)), pelect=np.zeros((N, nm)),
                        pmech=np.zeros((N, nm)), efd=np.zeros((N, nm)),
                        V=np.zeros((N, nb), np.complex128))
        first = np.r_[False, np.diff(grid.interval) > 0]
        S_extra = np.zeros(m.nc_idx.size, np.complex128)
        wall = time.perf_counter()
        status, k_end = integrate(
            m.x0.copy(), m.V_nc0.copy(), grid.interval, grid.h, first, semantics == "pst",
            stack("Y11"), stack("Y12"), stack("Y21"), stack("Y22"), stack("Z22"), stack("R"), m.params,
            m.layout.n_mac, m.layout.n_exc, m.layout.n_pss, m.layout.n_tg, S_extra,
            self.inertia, separation_limit, stop_at_separation, rec)
        res = self._result(grid.t, rec, k_end + 1, time.perf_counter() - wall,
                           separation_limit)
        if status < 0:
            why = "non-finite state" if status == DIVERGED else \
                "the network/load equations did not converge (voltage collapse)"
            t_fail = grid.t[min(k_end + 1, grid.t.size - 1)]
            raise SimulationError(f"case '{self.case.name}': {why} in the step ending at "
                                  f"t = {t_fail:.4f} s (trajectory kept up to "
                                  f"{grid.t[k_end]:.4f} s)", result=res)
        return res

    def _result(self, t, rec: "Recording", n, wall, limit) -> SimulationResult:
        c = self.case
        angle = rec.angle[:n]
        dev = np.abs(angle - (angle @ self.inertia / self.inertia.sum())[:, None])
        lost = np.nonzero(dev.max(axis=1) > limit)[0]
        t_sep, separated = None, []
        if lost.size:
            k = int(lost[0])
            t_sep = float(t[k])
            group = separated_group(angle[k], self.inertia)
            separated = [int(x) for x in c.machines.number[group]]
        return SimulationResult(
            t=t[:n].copy(), machines=c.machines.number.astype(int), buses=c.buses.number.astype(int),
            speed=rec.speed[:n], angle=angle, pelect=rec.pelect[:n], pmech=rec.pmech[:n],
            efd=rec.efd[:n], vmag=np.abs(rec.V[:n]), vang=np.angle(rec.V[:n]),
            inertia=self.inertia, stable=t_sep is None, t_separation=t_sep, separated=separated,
            meta={"case": c.name, "wall_time_s": wall,
                  "max_initial_derivative": self.model.initial_residual[0],
                  "max_initial_derivative_state": self.model.initial_residual[1]})


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


class Recording(NamedTuple):
    """Preallocated trajectories filled by `integrate` (n_t rows)."""

    speed: np.ndarray
    angle: np.ndarray
    pelect: np.ndarray
    pmech: np.ndarray
    efd: np.ndarray
    V: np.ndarray


OK, SEPARATED, DIVERGED, NO_LOAD_FLOW = 0, 1, -2, -1


@njit(cache=True)
def _store(rec, k, x, nm, pelect, pmech, efd, V_bus):
    for i in range(nm):
        rec.angle[k, i] = x[i]
        rec.speed[k, i] = x[nm + i]
    rec.pelect[k] = pelect
    rec.pmech[k] = pmech
    rec.efd[k] = efd
    rec.V[k] = V_bus


@njit(cache=True)
def integrate(x, V_nc, interval, h, first, pst, Y11, Y12, Y21, Y22, Z22, R, p, nm, ne, nps, ng,
              S_extra, inertia, limit, stop, rec):
    """PST's predictor-corrector over the whole grid (see the module docstring).

    Stage matrices are stacked by interval.  Stores the predictor-stage outputs and the
    states at every index into `rec`.  Returns (status, last stored index): status OK,
    SEPARATED (stopped at loss of synchronism), DIVERGED or NO_LOAD_FLOW.
    """
    n = interval.size
    nb = R.shape[1]
    dx_k, dx_j = np.empty_like(x), np.empty_like(x)
    cur = np.empty(nm, np.complex128)
    pel, qel, et, efd, pm = np.empty(nm), np.empty(nm), np.empty(nm), np.empty(nm), np.empty(nm)
    V_bus = np.zeros(R.shape[1], np.complex128)
    M = inertia.sum()
    for k in range(n - 1):
        s = interval[k]
        if first[k] and pst:   # PSTess computes this step twice; the first pass's clamps stay
            V_tmp = V_nc.copy()
            evaluate_kernel(x, nm, ne, nps, ng, p, Y11[s], Y12[s], Y21[s], Y22[s], Z22[s], R[s], V_tmp,
                            S_extra, False, dx_k, cur, pel, qel, et, efd, pm, V_bus)
        if evaluate_kernel(x, nm, ne, nps, ng, p, Y11[s], Y12[s], Y21[s], Y22[s], Z22[s], R[s], V_nc,
                           S_extra, True, dx_k, cur, pel, qel, et, efd, pm, V_bus) < 0:
            return NO_LOAD_FLOW, max(k - 1, 0)
        _store(rec, k, x, nm, pel, pm, efd, V_bus)
        xp = x + h[s] * dx_k
        j = interval[k + 1] if pst else s
        if evaluate_kernel(xp, nm, ne, nps, ng, p, Y11[j], Y12[j], Y21[j], Y22[j], Z22[j], R[j], V_nc,
                           S_extra, k == n - 2, dx_j, cur, pel, qel, et, efd, pm, V_bus) < 0:
            return NO_LOAD_FLOW, k
        x = x + 0.5 * h[s] * (dx_k + dx_j)
        if not np.all(np.isfinite(x)):
            return DIVERGED, k
        if stop:
            coi = (x[:nm] * inertia).sum() / M
            if np.max(np.abs(x[:nm] - coi)) > limit:
                _store(rec, k + 1, x, nm, pel, pm, efd, V_bus)
                return SEPARATED, k + 1
    _store(rec, n - 1, x, nm, pel, pm, efd, V_bus)
    return OK, n - 1
