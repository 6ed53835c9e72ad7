"""The integration grid and the step policy: where the steps of a run fall and how long
they may be.

Event times are grid points, so the run restarts exactly at every event.  The model
conventions (`stabctl.dynamics.model.CONVENTIONS`, docs/conventions.md) set the grid:

- ``"ieee"`` (default): each interval between events gets ceil(length/h) equal steps (never
  longer than h).
- ``"pstess"``: PSTess's own, fix(length/h) steps per interval (steps in [h, 2h)).

The default step comes from the case (`default_step`); a step is refused when the explicit
predictor-corrector would be unstable with it (`check_step`) or a run would take more than
MAX_STEPS steps or record more than MAX_RECORD_BYTES (`check_step_count`).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from stabctl.case import Case
from stabctl.dynamics.model import check_conventions
from stabctl.errors import InputError, advice


@dataclass(frozen=True)
class TimeGrid:
    """Integration grid: t (N+1,), interval id of each point (a point at an event belongs to
    the interval that starts there; a time repeats after a zero-length interval), step h
    of each interval (0 for a zero-length one), the interval start times, and the nominal
    step it was built with (s)."""

    t: np.ndarray
    interval: np.ndarray
    h: np.ndarray
    starts: np.ndarray
    step: float


def time_grid(starts, t_end: float, h: float, pstess: bool = False, h_max=None) -> TimeGrid:
    """The grid: intervals between consecutive start times (the first 0, non-decreasing,
    all below t_end), each divided into equal steps, at least one (so a zero-length
    interval gets one step of h = 0 and its start time appears twice, as in PSTess).
    pstess: fix(length/h) steps (PSTess, steps in [h, 2h)); else ceil(length/h') (steps at
    most h' = min(h, h_max of the interval); a length within 1e-9 of a multiple of h'
    takes that multiple).  h_max: the longest step of each interval (s; None or inf: h;
    `stiff_step`), not with pstess.

    Raises InputError for a non-positive or non-finite step or end time.
    """
    if not (0 < h < np.inf and 0 < t_end < np.inf):
        raise InputError(f"need a positive step and end time, got h={h}, t_end={t_end}")
    pts = [float(x) for x in starts] + [float(t_end)]
    bound = [h] * (len(pts) - 1) if h_max is None else [min(h, float(x)) for x in h_max]
    ts, ids, hs = [], [], []
    for s, (a, b) in enumerate(zip(pts[:-1], pts[1:])):
        hh = bound[s]
        n = max(1, int(np.trunc((b - a) / h) if pstess else np.ceil((b - a) / hh - 1e-9)))
        hs.append((b - a) / n)
        ts.append(a + hs[-1] * np.arange(n))
        ids.append(np.full(n, s))
    t = np.concatenate(ts + [[pts[-1]]])
    interval = np.concatenate(ids + [[len(pts) - 2]])
    return TimeGrid(
        t=t, interval=interval, h=np.array(hs), starts=np.array(pts[:-1]), step=float(h)
    )


#: ieee default step: at most this fraction of the fastest time constant (`default_step`).
STEP_PER_TIME_CONSTANT = 0.5


def default_step(
    case: Case, conventions: str = "ieee", fastest: tuple[float, str] | None = None
) -> float:
    """Default integration step (s).

    pstess: the data file's own step (sw_con row 1, col 7), else half a cycle of the case
    frequency (1/120 s at 60 Hz), as PSTess.  ieee: from the model, not from a PSTess run
    setting: half a cycle, capped at STEP_PER_TIME_CONSTANT times the case's fastest time
    constant, the largest step whose CCTs agree with a converged (step-halved) run within
    the 1 ms CCT tolerance on the paper's faults (docs/conventions.md, convergence table;
    docs/simulator.md, default step).  Kundur 5 ms either way (T_R = 0.01 s); miniWECC
    5 ms instead of its data file's 1/480 s (fastest 0.01 s: a governor's T_5), whose CCTs
    are the same to the millisecond (docs/simulator.md).  fastest: the case's
    `fastest_time_constant`, if already known.
    """
    sw = case.sw_con
    half_cycle = 0.5 / case.freq_hz
    if check_conventions(conventions) == "pstess":
        return float(sw[0, 6]) if sw is not None and sw[0, 6] > 0 else half_cycle
    T, _ = fastest_time_constant(case) if fastest is None else fastest
    return min(half_cycle, STEP_PER_TIME_CONSTANT * T)


def exciter_hmax(loops: np.ndarray, step: float) -> np.ndarray:
    """The longest sub-step (s) of each exciter in runs of nominal step `step` (s): at most
    STEP_PER_TIME_CONSTANT times its inner loop's time constant where that bound is below
    the step, inf (no sub-intervals) elsewhere.

    Parameters
    ----------
    loops : ndarray, shape (n_exc,)
        Each exciter's inner-loop time constant, s (inf where it has none;
        `stabctl.models.exciters.ExciterParams.inner_loop_time_constants`).
    step : float
        The run's nominal step, s (> 0).

    Returns
    -------
    ndarray, shape (n_exc,)
    """
    bound = STEP_PER_TIME_CONSTANT * np.asarray(loops, float)
    return np.where(bound < step, bound, np.inf)


def fastest_time_constant(case: Case) -> tuple[float, str]:
    """Smallest time constant among the states of the case's models (s) and where it is
    (table, field, row); a torsional shaft's fastest mode w counts as 0.1 / w
    (`stabctl.models.shafts.ShaftParams.time_constants`).  Raises CaseError for models
    stabctl does not have."""
    from stabctl.models import converters, exciters, governors, machines, motors, pss, shafts, svcs

    cands = []
    mp, ep = machines.machine_params(case), exciters.exciter_params(case)
    pp, gp = pss.pss_params(case), governors.governor_params(case)
    cp = converters.converter_params(case)
    for name, arr, sel in (
        ('mac_con T"do', mp.Tdopp, mp.kind == 2),
        ('mac_con T"qo', mp.Tqopp, mp.kind == 2),
        ("mac_con T'do", mp.Tdop, mp.kind >= 1),
        ("mac_con T'qo", mp.Tqop, mp.kind >= 1),
        ("mac_con pb_Tv", mp.pb_Tv, mp.playback == 1),
        ("mac_con pb_Tf", mp.pb_Tf, mp.playback == 1),
        *pp.time_constants(),
        *ep.time_constants(),
        *gp.time_constants(),
        *cp.time_constants(),
        *shafts.shaft_params(case).time_constants(mp.basrad),
        *motors.motor_params(case).time_constants(),
        *svcs.time_constants(case),
    ):
        if np.any(sel):
            k = int(np.argmin(np.where(sel, np.abs(arr), np.inf)))
            cands.append((float(abs(arr[k])), f"{name} row {k + 1}"))
    return min(cands) if cands else (np.inf, "")


#: largest trapezoid step run without a warning, in cycles of the case's frequency (one:
#: 1/60 s at 60 Hz, 0.02 s at 50 Hz; PSS/E's default is half a cycle, ANDES's two).  The
#: trapezoid is A-stable, so a larger step runs, but a 1-2 Hz swing is then sampled a few
#: dozen times a period or less and a verdict near the CCT is the step's (Kundur's bus-3
#: fault cleared in 6 cycles, stable, is unstable at 0.25 s: angles of 13-26 rad; cleared
#: in 9.2 cycles, 1.2 ms below its CCT, it is stable at 5 and 10 ms and unstable at 20 ms).
TRAPEZOID_TRUSTED_CYCLES = 1.0


def _compare() -> str:
    """The advice of a step warning, in the caller's words (`advice`): ``cct`` has no
    --check-step (it reruns its cell at h/2 by itself), so the command line names both."""
    return advice(
        "halve the step and compare",
        "halve the step and compare (simulate --check-step; cct, screen and sweep-cct rerun "
        "their final cell at h/2 by themselves)",
    )


def check_step(
    fastest: tuple[float, str], h: float, explicit: bool = True, freq_hz: float = 60.0
) -> None:
    """Raise InputError when h is not a positive finite step or, for the explicit
    predictor-corrector (explicit), exceeds twice the fastest time constant
    (`fastest_time_constant`): it is unstable there (its stability interval is h/T < 2).
    The implicit trapezoid (explicit False) is A-stable: above TRAPEZOID_TRUSTED_CYCLES
    cycles of `freq_hz` (Hz, the case's) it runs with a warning (UserWarning) to halve
    the step and compare.  The predictor-corrector between once and twice the fastest
    time constant runs with such a warning too: a lag alone is stable there, but a fast
    loop closed around it (an exciter's high gain) can swing at the step's own period, and
    a run then ends in a separation that is the step's (Kundur's bus-3 fault at 0.0185 s,
    stable at 1 ms)."""
    T, where = fastest
    if not 0 < h < np.inf:
        where = advice("run(h), Simulator(step)", "--step")
        raise InputError(f"the step ({where}) must be a positive number of seconds, got {h}")
    if explicit and h >= 2 * T:
        raise InputError(
            f"step {h} s is too large (--step): the fastest time constant is {T} s "
            f"({where}); the predictor-corrector needs h < {2 * T} s"
        )
    if explicit and h > T * (1 + 1e-9):
        warnings.warn(
            f"step {h:g} s is above the fastest time constant {T:g} s ({where}): the "
            "predictor-corrector is near its stability limit there, where a fast control "
            "loop can oscillate at the step's own period and a verdict be the step's; "
            f"{_compare()}",
            stacklevel=3,
        )
    trusted = TRAPEZOID_TRUSTED_CYCLES / freq_hz
    if not explicit and h > trusted * (1 + 1e-9):
        warnings.warn(
            f"trapezoid step {h:g} s is above {trusted:.4g} s (one cycle at {freq_hz:g} Hz): "
            f"the swings are sampled too coarsely to trust the verdict; {_compare()}",
            stacklevel=3,
        )


#: growth of an undamped swing's amplitude over a run (a fraction) from which a Heun run
#: warns (`check_heun_growth`)
HEUN_GROWTH_WARNED = 0.01


def check_heun_growth(case: Case, y_own: np.ndarray, h: float, t_end: float) -> None:
    """Warn (UserWarning) when the predictor-corrector's step h (s) lets an undamped or
    lightly damped swing grow by more than `HEUN_GROWTH_WARNED` over a run to t_end (s).

    Heun's method (second-order Runge-Kutta) multiplies an undamped oscillation of angular
    frequency w by sqrt(1 + (w h)^4 / 4) a step: over a time T the amplitude grows by exp(T
    w^4 h^3 / 8), a negative damping ratio of -(w h)^3 / 8 that physical damping hides and a
    lossless case shows (a classical machine, H = 0.5 s, 20 s at 8.3 ms: the largest angle
    31 % above its converged value, with no word; the trapezoid method is free of it).
    Classical machines (no field or damper circuit) are judged, their own damping D0
    counted: a swing that decays at D0 / (4 H) 1/s and that Heun grows at w^4 h^3 / 8 1/s
    grows by exp(T (w^4 h^3 / 8 - D0 / (4 H))) over the run, its later swings then above its
    first (round 58 BA95-97: D0 of 0.01-0.1 turned the warning off, the largest angle 42-140
    % off at 10 ms, a net growth of a factor 1.9-4.7 by this rule; from D0 = 0.2 the decay
    wins and the error is 1 %); a damper's damping ratio, some 0.05-0.2, dwarfs Heun's (WECC
    240's fastest swing, 3.3 Hz, at 8.3 ms: -7e-4).  w is each machine's swing against the
    rest held fixed, sqrt(2 pi f0 |Y_ii| / (2 H_i)), Y_ii the admittance at its internal
    node with the other machines' shorted (system base, E' taken 1): that H = 0.5 s machine
    3.2 Hz (3.9 Hz measured).
    Parameters
    ----------
    case : Case
        Its machines' H (s, machine base), MVA, model (x_d 0: classical) and damping, its
        base and frequency.
    y_own : numpy.ndarray, shape (n_mac,)
        |Y_ii| (pu, system base): the diagonal of the reduced network at the machines'
        internal nodes before any event (`stabctl.network.solution.ReducedNetwork.Y11`).
    h : float
        The step, s.
    t_end : float
        The run's end, s (the run from 0).
    """
    m = case.machines
    H = np.asarray(m.H, float)
    M = H * np.asarray(m.mva, float) / case.base_mva  # 2 H: M / 2
    ok = (M > 0) & (y_own > 0) & (np.asarray(m.xd) == 0)
    if not ok.any():
        return
    w2 = np.zeros(M.size)
    np.divide(2 * np.pi * case.freq_hz * y_own, 2 * M, out=w2, where=ok)
    decay = np.zeros(M.size)  # the swing's own decay rate, 1/s
    np.divide(np.asarray(m.D0, float), 4 * H, out=decay, where=ok)
    net = np.where(ok, w2**2 * h**3 / 8 - decay, 0.0)  # Heun's growth less the decay, 1/s
    i = int(np.argmax(net))
    w, growth = math.sqrt(w2[i]), math.expm1(min(max(net[i], 0.0) * t_end, 50.0))
    if growth > HEUN_GROWTH_WARNED:
        name = case.machine_name(case.machines.number[i])
        damped = m.D0[i] > 0
        kind = "a lightly damped" if damped else "an undamped"
        whose = (
            f"{name}'s swing against the others, its damping D0 {m.D0[i]:g}"
            if damped
            else f"{name}'s, the fastest undamped machine's swing against the others"
        )
        of = " net of its damping" if damped else ""
        warnings.warn(
            f"heun's step {h:g} s lets {kind} swing grow: one of about "
            f"{w / (2 * np.pi):.2g} Hz ({whose}) by about {_growth_text(growth)}{of} over "
            f"the {t_end:g} s run (heun's error, as h^3; physical damping hides it): the "
            "largest angle and a verdict late in the run then depend on the step; use the "
            "trapezoid (method 'trapezoid', --method trapezoid), which is free of it, or a "
            f"smaller step; {_compare()}",
            stacklevel=3,
        )


def _growth_text(growth: float) -> str:
    """A growth fraction as text: '31 %', or 'a factor 12' beyond 100 %."""
    return f"{growth * 100:.2g} %" if growth < 1 else f"a factor {1 + growth:.3g}"


#: most memory the recorded trajectory of one run may take, bytes (`check_step_count`): a
#: smaller step (or a longer run) is refused at once instead of filling the memory with it
#: (miniWECC, 5.3 kB per step: about 190 000 steps; Kundur, 0.6 kB: 1.7 million)
MAX_RECORD_BYTES = 1_000_000_000
#: most integration steps of one run whatever its size: a run is refused at once instead
#: of running silently for minutes (Kundur: about 25 us per step)
MAX_STEPS = 2_000_000


def recorded_bytes_per_step(case: Case, n_buses: int | None = None) -> int:
    """Bytes one grid point of a run of `case` records: per machine its speed, angle, P_e,
    P_m and E_fd (5 x 8), per recorded bus (n_buses; None: every bus) its complex voltage
    and the result's magnitude and angle (16 + 16), per converter its complex power
    (16)."""
    n_buses = case.n_bus if n_buses is None else n_buses
    return 40 * len(case.machines) + 32 * n_buses + 16 * len(case.converters)


def check_step_count(
    t_end: float, h: float, case: Case, n_buses: int | None = None, n_steps: int | None = None
) -> None:
    """Raise InputError when a run of `case` to t_end (s) with step h (s) needs more steps
    (t_end / h, or `n_steps` when given: a grid with intervals of shorter steps,
    `stiff_step`) than MAX_STEPS or than its recording may take in MAX_RECORD_BYTES
    (`recorded_bytes_per_step`; n_buses the buses whose voltages the run records, None:
    every bus)."""
    if not 0 < h < float("inf"):
        raise InputError(f"step must be a finite number > 0 s, got {h}")
    n = t_end / h if n_steps is None else n_steps
    limit = min(MAX_STEPS, MAX_RECORD_BYTES // recorded_bytes_per_step(case, n_buses))
    if not n <= limit:
        raise InputError(
            f"step {h:g} s: a run to {t_end:g} s needs {n:.3g} steps, more than "
            f"the limit {limit} for case '{case.name}' (stabctl.dynamics.grid.MAX_STEPS, "
            "MAX_RECORD_BYTES of recording); use a larger step (--step) or a shorter run "
            "(--tf)"
        )


#: the longest step of an interval, at most this many times the shortest subtransient
#: time constant of a machine in that interval's network (`stiff_step`): the explicit
#: predictor-corrector's stability interval is h/T < 2, and `check_step` trusts h <= T
STIFF_STEP_PER_TIME_CONSTANT = 1.0


def stiff_step(T: np.ndarray) -> float:
    """The longest step of an interval whose machines' subtransient time constants in
    that interval's network are `T` (s; `DynamicModel.subtransient_time_constants`):
    `STIFF_STEP_PER_TIME_CONSTANT` times the shortest, inf without one.

    A machine's subtransient time constant depends on the reactance it sees: with a fault
    at its terminal it is T"do x"d / x'd, which data with a tiny x"d make far shorter than
    any open-circuit time constant (ANDES's IEEE 39: x"d 0.0057 pu, T"do 0.03 s: 0.13 ms;
    a run at 8.3 ms diverges in its first fault-on step, and a step merely below the
    stability limit gives the wrong swing), so the step policy of `default_step` cannot
    see it.  Only the intervals where it is shorter than the step are stepped finer.

    Parameters
    ----------
    T : ndarray
        Time constants, s (inf where none).

    Returns
    -------
    float
    """
    T = np.asarray(T, float)
    return STIFF_STEP_PER_TIME_CONSTANT * float(T.min()) if T.size else np.inf
