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
from . import storage as st
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
        self._models: dict[frozenset, DynamicModel] = {}
        self.model = self.model_for(injection_buses)
        self.inertia = self.model.mp.H * case.machines.mva

    def model_for(self, buses=()) -> DynamicModel:
        """The dynamic model keeping `buses` (bus numbers) in the reduced network (cached);
        storage devices need their buses kept."""
        key = frozenset(int(b) for b in buses)
        if key not in self._models:
            self._models[key] = DynamicModel(self.case, self.op, sorted(key))
        return self._models[key]

    def run(self, events=(), t_end: float = 5.0, h: float | None = None,
            semantics: str = "pst", separation_limit: float = np.pi,
            stop_at_separation: bool = False, storage=None) -> SimulationResult:
        """Simulate `events` (see `stabctl.events`) from t = 0 to t_end (s) with step h.

        storage: a `stabctl.storage.StorageFleet` (devices and controller) or None.

        Raises:
            InputError, UnknownBusError, CaseError: bad events or step;
            SimulationError: divergence (carries the partial result as `.result`).
        """
        if semantics not in ("pst", "exact"):
            raise InputError(f"semantics must be 'pst' or 'exact', got {semantics!r}")
        events = list(events)
        ev_.validate(self.case, events, t_end)
        h = default_step(self.case) if h is None else h
        m = self.model_for(storage.buses if storage is not None else ())
        sa = st.pack(storage, self.case, m.nc_idx)
        check_step(m, h)
        grid = time_grid([t for e in events for t in e.times()], t_end, h)
        nets = [m.network(ev_.configuration(self.case, events, s, self.op.V))
                for s in grid.starts]
        stack = lambda name: np.ascontiguousarray(np.stack([getattr(n, name) for n in nets]))  # noqa: E731
        N, nm, nb = grid.t.size, m.mp.n, self.case.n_bus
        rec = Recording(speed=np.zeros((N, nm)), angle=np.zeros((N, nm)), pelect=np.zeros((N, nm)),
                        pmech=np.zeros((N, nm)), efd=np.zeros((N, nm)),
                        V=np.zeros((N, nb), np.complex128))
        first = np.r_[False, np.diff(grid.interval) > 0]
        P_rec = np.zeros((N, sa.pmax.size))
        stats = np.zeros((sa.pmax.size, 3))
        wall = time.perf_counter()
        log = np.full((4096, 4), np.nan)
        status, k_end = integrate(
            m.x0.copy(), m.V_nc0.copy(), grid.t, grid.interval, grid.h, first, semantics == "pst",
            stack("Y11"), stack("Y12"), stack("Y21"), stack("Y22"), stack("Z22"), stack("R"), m.params,
            m.layout.n_mac, m.layout.n_exc, m.layout.n_pss, m.layout.n_tg, sa,
            self.inertia, separation_limit, stop_at_separation, rec, P_rec, stats, log)
        res = self._result(grid.t, rec, k_end + 1, time.perf_counter() - wall,
                           separation_limit)
        if storage is not None:
            _attach_storage(res, storage, P_rec[:k_end + 1], stats, self.case.base_mva,
                            log[~np.isnan(log[:, 0])], self.case.freq_hz)
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


def _attach_storage(res: SimulationResult, fleet, P, stats, base_mva, log, f0) -> None:
    """Device powers and per-device figures: switchings, energy absorbed and delivered
    (MJ), peak power actually used (MW); the switching log (time s, device number, new
    mode, relative speed Hz) in res.meta["switchings"]."""
    res.devices = np.arange(1, len(fleet.devices) + 1)
    res.pesd = P
    res.meta["switchings"] = [(float(t), int(d) + 1, int(m), float(r * f0)) for t, d, m, r in log]
    res.meta["storage"] = [
        {"device": i + 1, "bus": d.bus, "machine": d.machine, "pmax_mw": d.pmax_mw,
         "switchings": int(stats[i, 0]), "energy_absorbed_mj": float(stats[i, 1] * base_mva),
         "energy_delivered_mj": float(stats[i, 2] * base_mva),
         "peak_power_mw": float(np.abs(P[:, i]).max() * base_mva) if P.size else 0.0}
        for i, d in enumerate(fleet.devices)]


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
def _log(log, stats, d, time_, mode, r):
    """Count a switching of device d and log it (time s, device, new mode, rel. speed)."""
    row = int(stats[:, 0].sum())
    stats[d, 0] += 1
    if row < log.shape[0]:
        log[row, 0], log[row, 1], log[row, 2], log[row, 3] = time_, d, mode, r


@njit(cache=True)
def _inject(sa, P, S):
    """Complex power drawn at the kept buses by the devices (absorbing is +)."""
    S[:] = 0.0
    for d in range(P.size):
        S[sa.pos[d]] += P[d]


@njit(cache=True)
def _targets(sa, mode, r, v, accel, out):
    """Device power set-points: bang-bang modes times ratings, or the linear law."""
    for d in range(out.size):
        if sa.kind == st.BANG_BANG:
            out[d] = mode[d] * sa.pmax[d]
        elif v[d] < sa.vgate:
            out[d] = 0.0
        else:
            out[d] = min(max(sa.Kv * r[d] + sa.Ka * accel[d], -sa.pmax[d]), sa.pmax[d])


@njit(cache=True)
def _advance(sa, P, target, e, hh, stats):
    """Device powers after hh seconds; energy (SOC, absorbed, delivered) by trapezoid."""
    Pn = np.empty_like(P)
    for d in range(P.size):
        Pn[d] = st.device_power(sa, d, target[d], P[d], e[d], hh)
        e[d] += 0.5 * hh * (P[d] + Pn[d])
        stats[d, 1] += 0.5 * hh * (max(P[d], 0.0) + max(Pn[d], 0.0))
        stats[d, 2] += 0.5 * hh * (max(-P[d], 0.0) + max(-Pn[d], 0.0))
    return Pn


@njit(cache=True)
def _device_state(x, nm, inertia, sa, V_nc, dx, r, v, accel):
    """Relative speeds, bus voltages and relative accelerations seen by the devices."""
    st.relative_speeds(x, nm, inertia, sa, r)
    st.relative_speeds(dx, nm, inertia, sa, accel)
    for d in range(r.size):
        v[d] = abs(V_nc[sa.pos[d]])


@njit(cache=True)
def integrate(x, V_nc, t, interval, h, first, pst, Y11, Y12, Y21, Y22, Z22, R, p, nm, ne, nps,
              ng, sa, inertia, limit, stop, rec, P_rec, stats, log):
    """PST's predictor-corrector over the whole grid (see the module docstring), with the
    storage devices `sa` (stabctl.storage.StorageArrays).

    Stage matrices are stacked by interval.  Stores the predictor-stage outputs, the states
    and the device powers at every index (rec, P_rec).  A bang-bang device whose mode
    changes within a step has its switching instant located (`storage.crossing`) and the
    step is re-integrated in two parts; stats[d] = (switchings, energy absorbed, energy
    delivered in pu*s); log rows (time, device, new mode, relative speed pu) record the
    switchings while there is room.  Returns (status, last stored index): status OK, SEPARATED
    (stopped at loss of synchronism), DIVERGED or NO_LOAD_FLOW.
    """
    n, nd = interval.size, sa.pmax.size
    dx_k, dx_j = np.empty_like(x), np.empty_like(x)
    cur = np.empty(nm, np.complex128)
    pel, qel, et, efd, pm = np.empty(nm), np.empty(nm), np.empty(nm), np.empty(nm), np.empty(nm)
    V_bus = np.zeros(R.shape[1], np.complex128)
    S = np.zeros(V_nc.size, np.complex128)
    P, target, e = np.zeros(nd), np.zeros(nd), sa.e0.copy()
    mode = np.zeros(nd, np.int64)
    r, v, acc = np.zeros(nd), np.zeros(nd), np.zeros(nd)
    rb, vb, accb = np.zeros(nd), np.zeros(nd), np.zeros(nd)
    M = inertia.sum()

    def ev(xx, st_, want, dx):
        return evaluate_kernel(xx, nm, ne, nps, ng, p, Y11[st_], Y12[st_], Y21[st_], Y22[st_],
                               Z22[st_], R[st_], V_nc, S, want, dx, cur, pel, qel, et, efd, pm,
                               V_bus)

    for k in range(n - 1):
        s = interval[k]
        j = interval[k + 1] if pst else s
        _inject(sa, P, S)
        if first[k] and pst:   # PSTess computes this step twice; the first pass's clamps stay
            V_keep = V_nc.copy()
            ev(x, s, False, dx_k)
            V_nc[:] = V_keep
        if ev(x, s, True, dx_k) < 0:
            return NO_LOAD_FLOW, max(k - 1, 0)
        if nd > 0:   # controller at the grid point (events make voltages jump here)
            _device_state(x, nm, inertia, sa, V_nc, dx_k, r, v, acc)
            for d in range(nd):
                want = st.desired_mode(sa, d, mode[d], r[d], v[d])
                if sa.kind == st.BANG_BANG and want != mode[d]:
                    mode[d] = want
                    _log(log, stats, d, t[k], want, r[d])
            _targets(sa, mode, r, v, acc, target)
            changed = False
            for d in range(nd):
                Pn = st.device_power(sa, d, target[d], P[d], e[d], 0.0)
                changed = changed or Pn != P[d]
                P[d] = Pn
            if changed:
                _inject(sa, P, S)
                ev(x, s, True, dx_k)
        _store(rec, k, x, nm, pel, pm, efd, V_bus)
        if nd > 0:
            P_rec[k] = P
        x_a, dx_a, rem = x, dx_k, h[s]
        for _split in range(8):
            Pb = _advance(sa, P, target, e.copy(), rem, np.zeros((nd, 3)))
            _inject(sa, Pb, S)
            xp = x_a + rem * dx_a
            if ev(xp, j, k == n - 2, dx_j) < 0:
                return NO_LOAD_FLOW, k
            x_b = x_a + 0.5 * rem * (dx_a + dx_j)
            if nd == 0 or sa.kind != st.BANG_BANG:
                break
            _device_state(x_b, nm, inertia, sa, V_nc, dx_j, rb, vb, accb)
            theta, first_d = 2.0, -1
            at_event = interval[k + 1] != s
            for d in range(nd):
                want = st.desired_mode(sa, d, mode[d], rb[d], vb[d])
                gate_jump = (v[d] >= sa.vgate) != (vb[d] >= sa.vgate)
                if want != mode[d] and not (at_event and gate_jump):  # events switch at t_k+1
                    th, _ = st.crossing(sa, mode[d], want, r[d], rb[d], v[d], vb[d])
                    if th < theta:
                        theta, first_d = th, d
            if first_d < 0:
                break
            hh = theta * rem           # re-integrate up to the first switching instant
            Pm = _advance(sa, P, target, e, hh, stats)
            _inject(sa, Pm, S)
            if ev(x_a + hh * dx_a, s, False, dx_j) < 0:
                return NO_LOAD_FLOW, k
            x_a = x_a + 0.5 * hh * (dx_a + dx_j)
            rem -= hh
            P = Pm
            _device_state(x_a, nm, inertia, sa, V_nc, dx_j, r, v, acc)
            for d in range(nd):
                want = st.desired_mode(sa, d, mode[d], rb[d], vb[d])
                if want != mode[d]:
                    th, new = st.crossing(sa, mode[d], want, r[d], rb[d], v[d], vb[d])
                    if d == first_d or th <= 1e-9:
                        mode[d] = new
                        _log(log, stats, d, t[k + 1] - rem, new, r[d])
            _targets(sa, mode, r, v, acc, target)
            for d in range(nd):
                P[d] = st.device_power(sa, d, target[d], P[d], e[d], 0.0)
            _inject(sa, P, S)
            dx_a = np.empty_like(x)
            if ev(x_a, s, False, dx_a) < 0:
                return NO_LOAD_FLOW, k
        if nd > 0:
            P = _advance(sa, P, target, e, rem, stats)
        x = x_b
        if not np.all(np.isfinite(x)):
            return DIVERGED, k
        if stop:
            coi = (x[:nm] * inertia).sum() / M
            if np.max(np.abs(x[:nm] - coi)) > limit:
                _store(rec, k + 1, x, nm, pel, pm, efd, V_bus)
                if nd > 0:
                    P_rec[k + 1] = P
                return SEPARATED, k + 1
    _store(rec, n - 1, x, nm, pel, pm, efd, V_bus)
    if nd > 0:
        P_rec[n - 1] = P
    return OK, n - 1
