"""Critical clearing time (CCT) of a line fault, searched on the clearing time.

The fault (`LineFault`) is a bolted three-phase fault at `bus` on the line `bus`-`far_bus`
from `t_fault`, cleared at both ends at once after a clearing time tc (s, counted from the
fault start), the line staying out (PST's sw_con fault type 0 with equal near and far
clearing, `stabctl.dynamics.events.Fault`).  The CCT is the longest tc for which the system stays
stable; `critical_clearing_time` brackets it between a stable and an unstable tc at most
`tol` apart (Kundur, Power System Stability and Control, 1994, sec. 13.3; Pai, Energy
Function Analysis for Power System Stability, 1989, ch. 1, for the time-domain definition).

Stability criterion (default `no_separation`): no machine's rotor angle leaves the centre of
inertia (paper eq. 40, weights H*MVA) by more than `separation_limit` (pi rad) before
`t_end` (default fault time + 5 s); the runs stop at separation to save time, and (with
`SearchOptions.early_stop`) as soon as SIME makes their verdict certain
(`stabctl.stability.sime.EarlyVerdict`, tested against the full runs on the screenings of
Kundur and miniWECC).  Any callable(SimulationResult) -> bool (True = stable) can replace
it (its runs then go to the end).

Islanding: a fault whose clearing cuts a machine, or a group of machines, off the main
grid (a generator's step-up transformer opened, a system split) has the CCT of the rest
of the system: the longest clearing time for which the machines left in the main grid
stay in synchronism, the islanded machines counted as lost (as PSS/E trips a generator
whose breaker opened; `stabctl.dynamics.partition`) and named with their island's buses
in `CCTResult.islanded` (and a verdict's ``islanded``); they are lost from the fault's
start (their own slip while the fault is on does not count); N-1 insecure then means that
the main grid loses synchronism even when the fault is cleared at once.

Two searches (`SearchOptions.method`), both on the lattice below:

- "bisection" (the default): stable at t_lo, the upper bound doubled from 0.1 s while
  stable, bisection;
- "sime": the first probe at t_max (stable there with every machine within 1.5 rad of
  its angle to the COI before the fault: robust in one run), then at 0.1 s (doubled
  while stable), stable at t_lo checked only when a probe is unstable before any is
  stable (a probe found stable above t_lo is
  taken to make t_lo stable too: the verdict is assumed monotone below it), then the
  probes placed where SIME's unstable margin (`stabctl.stability.sime.probe_margin`,
  close to linear in the clearing time) extrapolated from two unstable probes
  vanishes, on both sides of it, bisection only to finish (`_sime_search`).

Both end in the same cell where the verdict is monotone in the clearing time (every fault
of Kundur's screening and every fourth of miniWECC's, `benchmarks/bench_cct.py`).
"sime" takes fewer runs there (Kundur 13.6 against 14.8 per CCT, 11.4 against 12.6 at the
step h; miniWECC 14.2 against 14.6, 11.9 against 12.4 at h: the run at t_max costs about
one run a CCT and saves the doubling's three for a robust fault) and less time on a
sample of ACTIVSg2000's N-1, where most faults are robust at t_max 0.5 s (1.02 s a search
against 1.45, 6.2 runs a search against 8.4, the same counts of CCTs and verdicts;
`benchmarks/bench_cct.py --activsg-sample`), but assumes the verdict monotone below a
stable probe and below a gentle run at t_max, so bisection stays the default.
Neither comes near 5 runs per CCT: the two ends of the final cell and their reruns at
h/2 make 4, and the margins of runs far from the CCT (those of the doubling) place no
probe within a cell of it.

A guess (`SearchOptions.guess_s`, e.g. the CCT of the same fault without its line trip,
as `stabctl screen --lines` gives each branch fault): its cell and the neighbouring one
probed first, then 2 and 4 cells further out (`_around_guess`); a cell found that way is
bisected (the stable end confirmed as above), else the search runs as without the guess,
the verdicts already found read again instead of run (`_Probes.reuse`), so that a guess
far off never leads it to another end of a verdict not monotone.

Provisional stable probes (`SearchOptions.provisional_s`, default PROVISIONAL_S): only the
stable end of the final cell needs its run to t_end to be trusted; a probe is first run
to provisional_s after its clearing (`stabctl.dynamics.driver.Simulator.start`).
Separated by then, it is unstable, as its whole run (the same trajectory, stopped at the
same separation); swung GENTLE_SWING or more (`largest_swing`), it runs on to t_end at
once (runs near the CCT swing wide and may separate late); else provisionally stable, its
run kept (at most KEPT_RUNS, the highest below the lowest unstable probe).  When the
search closes a cell on a provisionally stable end, that run is continued to t_end, bit
for bit the whole run: still stable, the cell is the search's; separated, that end is
unstable, the search goes on below it (its next stable end confirmed alike) and its
further probes run whole.  Without the swing test and that switch, a window of 1.5 s took
25.9 runs a search on the ACTIVSg2000 sample of docs/scale.md instead of 5.9, probing
cell by cell through the late separations above the CCT.  Where the verdict is monotone
in the clearing time every provisional probe below a confirmed stable end is stable too,
so the search ends in the cell of the searches whose runs all go to t_end.  Where it is
not, a probe that separates late with gentle swings can be taken as stable: ACTIVSg2000's
bus 5367, unstable cleared at 0.082-0.15 s (separated 3.5-5 s after the clearing) and
stable at 0.2 s, gets a CCT of 0.261 s instead of 0.081 s with a window of 1 s (with
2 s, the default, its probe at 0.1 s has swung 1 rad and runs whole).  The runs that
decide a verdict (the check at t_lo, N-1 insecure; the probe at t_max, above the limit or
robust in one run), those at h/2 and those of a custom criterion or of early verdicts go
to t_end.

Grid: the simulator's grid lands on every event time (`stabctl.dynamics.grid.time_grid`), so a
clearing time is never rounded to a multiple of the step h: the fault-on interval of length
tc gets fix(tc/h) equal steps (each in [h, 2h)) and the post-fault interval restarts at the
clearing instant.  Both searches probe only clearing times k*tol (k integer), so results
are reproducible to the last digit and the final bracket is one lattice cell, exactly tol
wide.  A tol far below h resolves the discretised model, not the physics.

Numerical error bar: once bracketed at step h, the two ends of the bracket are run again
at h/2; where a verdict changes, the search continues at h/2 (expanding away from the
changed end, then bisecting) to the CCT at h/2.  `numerical_error_s` = |CCT(h/2) -
CCT(h)|, resolved to tol (0: halving the step moves the CCT by less than tol).  Under the
ieee conventions the default step keeps it below tol on the paper's faults
(docs/conventions.md); under pstess it is the step artefact of PSTess's limiter.

Sweeps of many faults or ratings (`cct_jobs`, `cct_job`) run through `stabctl.parallel`.
"""

from __future__ import annotations

import functools
import math
import os
import socket
import time
import warnings
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Protocol

import numpy as np

from stabctl.case import Case
from stabctl.dynamics.coi import machine_inertia
from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.events import Fault, LineTrip
from stabctl.dynamics.options import ModelOptions
from stabctl.dynamics.partition import judged_at, judged_relative
from stabctl.dynamics.results import SimulationResult
from stabctl.errors import (
    AboveSearchLimit,
    CaseError,
    InputError,
    InsecureContingency,
    NumericalInstabilityError,
    SimulationError,
    UnsharedCaseError,
    Verdict,
    WrongTypeError,
    advice,
    check_fields,
    is_number,
    is_whole_number,
    require_items,
)
from stabctl.io.inputs import CsvRow, iter_csv, number
from stabctl.network.ybus import circuit_row
from stabctl.stability.sime import (
    EarlyVerdict,
    critical_machines,
    probe_margin,
)

#: Default search settings (s): lower bound, first upper bound (doubled until unstable, up
#: to the limit), the limit, tolerance, and the run length after the fault.
T_LO, T_HI, T_MAX, TOL, T_AFTER_FAULT = 0.0, 0.1, 1.0, 1e-3, 5.0
#: the finest tolerance, s (1 us: a bisection from 1 s takes 20 runs; a finer one, far
#: below any run's numerical error, took runs without end at 1e-300 s)
MIN_TOL = 1e-6
#: how long a probe runs after its clearing before it is judged provisionally stable, s
#: (`SearchOptions.provisional_s`)
PROVISIONAL_S = 2.0
#: the least time a search's runs go on after its latest clearing (fault time + t_max), s.
#: A probe cleared past the CCT must have separated (pi rad from the COI) before its run
#: ends, else it reads stable and the CCT comes out high, or "above t_max" (line 3-101
#: with t_end 1.5 s and t_max 0.3 s: its CCT is 0.154 s).  The first swing can take far
#: longer than a second near the CCT: Kundur's DEFAULT faults cleared 1 ms past their CCT
#: pass pi rad 2.41 s (3-101) and 3.28 s (13-101) after the clearing, 13-101 cleared at
#: 0.6 s 2.88 s after it; with 3 s after t_max line 13-101's CCT read 0.409 s instead of
#: 0.408 s, with 2 s "above t_max" at a t_max of 0.6 s.  The default run end (the fault
#: start + T_AFTER_FAULT) leaves 4 s after the default t_max.
MIN_AFTER_CLEARING_S = 3.5


class Runner(Protocol):
    """What `critical_clearing_time` needs of a simulator: a `Simulator`, or anything
    that runs the case's events the same way (e.g. the estimator-in-the-loop runner,
    `stabctl.estimation.closed_loop.LoopRunner`)."""

    @property
    def case(self): ...

    @property
    def conventions(self) -> str: ...

    @property
    def default_h(self) -> float: ...

    def run(
        self, events, t_end, *, h=None, separation_limit=np.pi, stop_at_separation=True
    ) -> SimulationResult: ...


@dataclass(frozen=True)
class LineFault:
    """A three-phase fault at `bus` on circuit `circuit` of line `bus`-`far_bus`, starting
    at `t_fault` (s), cleared at both ends at the same instant (the line stays out).

    The clearing time is not part of the fault: it is the unknown of
    :func:`critical_clearing_time` (see :meth:`events`).

    Attributes
    ----------
    bus : int
        Faulted bus number (the near end of the line).
    far_bus : int or None
        Far-end bus number of the faulted line; None: a bus fault cleared without loss of
        a line (PST sw_con type 7).
    t_fault : float, optional
        Fault start, s (absolute run time, >= 0); default 1.0 s.
    circuit : int, optional
        Circuit number of the faulted line between `bus` and `far_bus` (1 = the first
        branch row joining them); default 1.
    trips : tuple of (int, int), optional
        Further lines (from_bus, to_bus), circuit 1 of each, opened at the clearing
        instant; default none.  Both circuits of a double line: ``circuit=2`` and
        ``trips=((bus, far_bus),)``.

    Raises
    ------
    WrongTypeError
        A field of another type: a bus or circuit that is no whole number, a time that is
        no number, `trips` not a list of bus pairs (`stabctl.errors.check_fields`).
    InputError
        A fault time that is negative or not finite.
    """

    bus: int
    far_bus: int | None
    t_fault: float = 1.0
    circuit: int = 1
    trips: tuple[tuple[int, int], ...] = ()

    def __post_init__(self):
        check_fields(self)  # LineFault('3', 101) searched bus 3; a text time failed in numpy
        if not 0 <= self.t_fault < math.inf:
            raise InputError(f"LineFault(t_fault): a fault time >= 0 s, got {self.t_fault}")
        trips = require_items(self.trips, "LineFault(trips)", "a list of (from_bus, to_bus)")
        for pair in trips:
            if not (
                hasattr(pair, "__len__")
                and not isinstance(pair, (str, bytes))
                and len(pair) == 2
                and all(is_whole_number(b) for b in pair)
            ):
                raise WrongTypeError(
                    f"LineFault(trips): each a (from_bus, to_bus) pair of bus numbers, got {pair!r}"
                )
        object.__setattr__(self, "trips", tuple((int(a), int(b)) for a, b in trips))

    def events(self, t_clear: float) -> list:
        """The run's events for one clearing time.

        Parameters
        ----------
        t_clear : float
            Clearing time, s after the fault start (>= 0); both ends open at
            ``t_fault + t_clear``.

        Returns
        -------
        list
            A :class:`~stabctl.dynamics.events.Fault` (equal near and far clearing, PST
            sw_con type 0, or 7 for a bus fault) followed by one
            :class:`~stabctl.dynamics.events.LineTrip` per entry of `trips`, all at the
            clearing instant.
        """
        tc = self.t_fault + t_clear
        fault = Fault(
            bus=self.bus,
            t=self.t_fault,
            clear_near=tc,
            clear_far=tc,
            far_bus=self.far_bus,
            circuit=self.circuit,
        )
        return [fault] + [LineTrip(a, b, tc) for a, b in self.trips]

    def describe(self) -> str:
        """One line naming the fault, for messages and reports.

        Returns
        -------
        str
            E.g. ``"fault at bus 7 on line 7-8 (circuit 2) at 1 s, 8-9 also opened"``.
        """
        circ = f" (circuit {self.circuit})" if self.circuit != 1 else ""
        extra = "".join(f", {a}-{b} also opened" for a, b in self.trips)
        where = "" if self.far_bus is None else f" on line {self.bus}-{self.far_bus}{circ}"
        return f"fault at bus {self.bus}{where} at {self.t_fault:g} s{extra}"


def no_separation(result: SimulationResult) -> bool:
    """Default criterion: True if no rotor angle left the COI by more than the run's
    separation limit and some machine is left in service (`SimulationResult.stable`: a
    clearing that de-energises the system is no stable one)."""
    return result.stable


@dataclass(frozen=True)
class CCTResult:
    """Outcome of a CCT search.  Times are clearing times in s after the fault start.

    t_stable, t_unstable: the closest stable and unstable clearing times found
    (t_unstable - t_stable = tol); the CCT is t_stable (the conservative end).
    search_bracket: the (stable, unstable) interval the bisection started from, after the
    bound checks and expansion.  probes: every (clearing time s, stable) simulated, in
    order.  separated: machines that lose synchronism when cleared at t_unstable (empty if
    the criterion failed without separation; where that run failed first,
    ``unstable_end_failure`` says how, and these are the machines leading its swing).
    islanded: the islanding of the first probe that islands
    (`stabctl.dynamics.driver.islanding_log`: buses cut from every machine, their load
    shed, or an island with machines apart from the main grid, those machines lost and
    the CCT that of the rest; empty: none).  step_s: integration step h; wall_time_s: the
    whole search.  cct_half_step_s: the CCT at h/2 (module docstring; None when the
    check was not asked for), half_step_probes: its runs; conventions: the model's.
    n_simulations: every run of the search (probes and half_step_probes; a provisional
    probe continued to t_end counts once, a run started again because its provisional one
    was not kept twice); early_stops: those ended by an early verdict
    (`stabctl.stability.sime.EarlyVerdict`); method: the search's (`SearchOptions.method`).
    A provisionally stable probe never continued is listed stable in probes (implied by
    the confirmed stable end above it when the verdict is monotone).
    """

    fault: LineFault
    t_stable: float
    t_unstable: float
    search_bracket: tuple[float, float]
    tol_s: float
    step_s: float
    freq_hz: float
    n_simulations: int
    wall_time_s: float
    criterion: str
    probes: tuple[tuple[float, bool], ...] = field(repr=False)
    separated: tuple[int, ...] = ()
    islanded: tuple = ()
    #: what ended the run cleared at t_unstable when it failed (the network's voltage
    #: collapse, a diverging state) before any machine separated; None: it separated
    unstable_end_failure: str | None = None
    cct_half_step_s: float | None = None
    half_step_probes: tuple[tuple[float, bool], ...] = field(default=(), repr=False)
    conventions: str = "ieee"
    method: str = "bisection"
    early_stops: int = 0
    #: exciters integrated in sub-intervals at the step (`stabctl.dynamics.subinterval`)
    sub_stepped: int = 0
    #: the search's longest clearing time tried (`SearchOptions.t_max`, s); None: not given
    t_max_s: float | None = None
    #: time steps of the search's runs, each counted from t = 0 (a quiet start copied from
    #: an earlier run too, `stabctl.dynamics.prefix`), a continued run's once
    n_steps: int = 0
    #: provisionally stable probes continued to t_end (`SearchOptions.provisional_s`), and
    #: those of them that separated there
    resumed: int = 0
    overturned: int = 0
    #: the run cleared at the CCT ending off a normal operating point, stable by the angle
    #: criterion yet with a bus below 0.8 pu or the machines it judges beyond +-0.6 Hz (a
    #: system split whose rest lacks generation: `SimulationResult.end_concerns`, a
    #: phrase each), and the time it ended, s (its end or an early verdict's); empty and
    #: None: none
    end_concerns: tuple[str, ...] = ()
    end_t_s: float | None = None
    #: the shortest step of the runs at the step h, s, where an interval was cut for a
    #: machine's short subtransient time constant (`Simulator.stiff_substeps`); None: none
    stiff_step_s: float | None = None
    #: the run's end checked (`_run_end_check`): (the longer run's end, s; when the run
    #: cleared at the CCT separated in it, s, or None: it stayed stable); None: the
    #: unstable end separated early enough that the end was not in question
    run_end_check: tuple[float, float | None] | None = None
    #: with storage, whether any device switched in any of the search's runs (False: the
    #: CCT is the one without storage, round 42: a gate of 1.5 pu or a 5 Hz deadband
    #: printed the CCT without storage as the one with it); None: no storage
    storage_acted: bool | None = None

    @property
    def numerical_error_s(self) -> float | None:
        """|CCT(h/2) - CCT(h)| (s), resolved to tol_s; None without the check."""
        if self.cct_half_step_s is None:
            return None
        return round(abs(self.cct_half_step_s - self.t_stable), 12)

    @property
    def cct_s(self) -> float:
        """Critical clearing time (s): the longest clearing time found stable."""
        return self.t_stable

    @property
    def cct_cycles(self) -> float:
        """CCT in cycles of the case frequency (to 1e-9 cycle: 0.515 s at 60 Hz gave
        30.900000000000002)."""
        return round(self.t_stable * self.freq_hz, 9)

    @property
    def bracket(self) -> tuple[float, float]:
        """(stable, unstable) clearing times (s) that bound the CCT."""
        return self.t_stable, self.t_unstable

    def to_dict(self) -> dict:
        """JSON-ready summary (times in s, cycles of the case frequency)."""
        return {
            "fault": _fault_dict(self.fault),
            "cct_s": self.cct_s,
            "cct_cycles": self.cct_cycles,
            "numerical_error_s": self.numerical_error_s,
            "cct_half_step_s": self.cct_half_step_s,
            "conventions": self.conventions,
            "t_stable_s": self.t_stable,
            "t_unstable_s": self.t_unstable,
            "t_unstable_cycles": round(self.t_unstable * self.freq_hz, 9),
            "search_bracket_s": list(self.search_bracket),
            "tol_s": self.tol_s,
            "t_max_s": self.t_max_s,
            "step_s": self.step_s,
            "n_simulations": self.n_simulations,
            "n_simulations_half_step": len(self.half_step_probes),
            "n_steps": self.n_steps,
            "early_stops": self.early_stops,
            "sub_stepped_exciters": self.sub_stepped,
            "search": self.method,
            "wall_time_s": self.wall_time_s,
            "criterion": self.criterion,
            # a run that failed before any machine separated: none separated, the
            # machines leading its swing apart (round 44)
            "separated_machines": [] if self.unstable_end_failure else list(self.separated),
            "unstable_end_failure": self.unstable_end_failure,
            "leading_machines": list(self.separated) if self.unstable_end_failure else [],
            "islanded": list(self.islanded),
            "end_concerns": list(self.end_concerns),
            "end_t_s": self.end_t_s,
            "stiff_step_s": self.stiff_step_s,
            "run_end_check": (
                None if self.run_end_check is None else dict(zip(RUN_END_KEYS, self.run_end_check))
            ),
            "storage_acted": self.storage_acted,
            "probes": [[t, ok] for t, ok in self.probes],
            "half_step_probes": [[t, ok] for t, ok in self.half_step_probes],
        }


def _fault_dict(fault: LineFault) -> dict:
    """A fault as records and `--json` give it: its fields, ``t_fault`` as ``t_fault_s``,
    a bus fault's circuit None (it opens no line: as `screen --json` gives it)."""
    d = asdict(fault)
    d["t_fault_s"] = d.pop("t_fault")  # its unit in its name, as every time's
    if fault.far_bus is None:
        d["circuit"] = None
    return d


@dataclass(frozen=True)
class SearchOptions:
    """Settings of a CCT search (`critical_clearing_time`, module docstring).

    Attributes
    ----------
    tol : float
        Width of the final bracket, s (>= `MIN_TOL`, 1e-6 s); default 1e-3 s.
    t_lo : float
        Clearing time that must be stable, s (>= 0; 0 = the line trip alone); default 0.
    t_hi : float or None
        First upper bound, s (default min(0.1 s, t_max)); doubled (capped at t_max) while
        it is still stable.
    t_max : float
        Largest clearing time tried, s; default 1.0 s.
    t_end : float or None
        Run end, s (absolute; default t_fault + 5 s; must exceed t_fault + t_max).
    separation_limit : float
        Angle from the centre of inertia (paper eq. 40) beyond which a machine has
        separated, rad; default pi.
    criterion : callable or None
        ``callable(SimulationResult) -> bool``, True if stable; default `no_separation`.
    stop_at_separation : bool or None
        Stop runs at separation; default True for the default criterion, False for a
        custom one (which then sees whole trajectories).
    error_check : bool
        Also search the CCT at h/2 from the final bracket
        (`CCTResult.numerical_error_s`, module docstring); default True.
    method : {"bisection", "sime"}
        How the bracket is found (module docstring): "bisection" (default), the bound
        checks, doubling and bisection; "sime", from SIME's margins of the runs,
        confirmed on both sides, bisection only to finish, t_lo run only when no probe
        above it was found stable first (it is then assumed stable).  Both end in the
        same lattice cell when the verdict is monotone in the clearing time.
    early_stop : bool
        End each run as soon as SIME makes its verdict certain
        (`stabctl.stability.sime.EarlyVerdict`; the default criterion and a `Simulator`
        only); default False: with the gates that keep every verdict equal to the full
        run's, the runs end less than 10 % sooner and the monitor costs more than that
        (`benchmarks/bench_cct.py`).
    provisional_s : float or None
        A probe at the step runs this long after its clearing, s (> 0), and is judged
        provisionally stable if no machine separated by then; its run is kept and
        continued to t_end when the search closes a cell on it (module docstring);
        default PROVISIONAL_S.  None: every probe runs to t_end.  Only with the default
        criterion, without early_stop, on a runner that starts runs it can continue.
    guess_s : float or None
        A clearing time expected near the CCT, s (>= 0), e.g. the CCT of the same fault
        cleared without its line trip (`stabctl.stability.screening.screen`): the search
        probes that cell and the next first, then widens outwards by 2 and 4 cells
        (`_around_guess`); a cell found that way is bisected, else the search runs as
        without the guess (the verdicts it has read again, not run).  It ends in the
        same cell as without a guess wherever the verdict is monotone in the clearing
        time; bisection still checks t_lo first.  Default None: no guess.

    A sweep (`cct_jobs`) records tol, t_max, t_end and error_check (when off) in each
    job's inputs, and method, early_stop and provisional_s when not their defaults
    (`to_inputs`); the other fields must keep their defaults there.
    """

    tol: float = TOL
    t_lo: float = T_LO
    t_hi: float | None = None
    t_max: float = T_MAX
    t_end: float | None = None
    separation_limit: float = np.pi
    criterion: Callable[[SimulationResult], bool] | None = None
    stop_at_separation: bool | None = None
    error_check: bool = True
    method: str = "bisection"
    early_stop: bool = False
    provisional_s: float | None = PROVISIONAL_S
    guess_s: float | None = None

    def __post_init__(self):
        check_fields(self)  # SearchOptions(tol='0.001') failed in the search, unnamed
        if self.criterion is not None and not callable(self.criterion):
            raise WrongTypeError(
                f"SearchOptions(criterion): a function of a SimulationResult or None, got "
                f"{self.criterion!r}"
            )

    def to_inputs(self) -> dict:
        """Fields of a sweep job's recorded inputs: tol, t_max, t_end, error_check when
        off, method when not the default, early_stop when on, provisional_s when not the
        default, guess_s when given.  Raises InputError when a
        field a record cannot hold is not its default."""
        default = SearchOptions()
        for name in ("t_lo", "t_hi", "separation_limit", "criterion", "stop_at_separation"):
            if getattr(self, name) != getattr(default, name):
                raise InputError(
                    f"a CCT sweep records tol, t_max, t_end and error_check "
                    f"only; {name} must keep its default"
                )
        return {
            "tol": self.tol,
            "t_max": self.t_max,
            "t_end": self.t_end,
            **({} if self.error_check else {"error_check": False}),
            **({} if self.method == default.method else {"method": self.method}),
            **({"early_stop": True} if self.early_stop else {}),
            **(
                {} if self.provisional_s == PROVISIONAL_S else {"provisional_s": self.provisional_s}
            ),
            **({} if self.guess_s is None else {"guess_s": self.guess_s}),
        }

    @classmethod
    def from_inputs(cls, inputs) -> SearchOptions:
        """The settings recorded in a job's inputs (`to_inputs`; absent fields default)."""
        return cls(
            tol=inputs.get("tol", TOL),
            t_max=inputs.get("t_max", T_MAX),
            t_end=inputs.get("t_end"),
            error_check=inputs.get("error_check", True),
            method=inputs.get("method", "bisection"),
            early_stop=inputs.get("early_stop", False),
            provisional_s=inputs.get("provisional_s", PROVISIONAL_S),
            guess_s=inputs.get("guess_s"),
        )


def critical_clearing_time(
    sim: Runner,
    fault: LineFault,
    search: SearchOptions | None = None,
    *,
    h: float | None = None,
    storage=None,
) -> CCTResult:
    """CCT of `fault` on `sim`'s case, searched on the clearing time (see module doc).

    Parameters
    ----------
    sim : Runner
        The simulator of the case (its power flow is solved once), a `Simulator` or a
        runner like it.
    fault : LineFault
        The fault; its clearing time is the unknown.
    search : SearchOptions or None, optional
        Search settings (tolerance, bounds, run end, criterion, half-step check); default
        `SearchOptions()`.
    h : float or None, optional
        Integration step, s (default `sim.default_h`).
    storage : StorageFleet or None, optional
        Passed untouched to `Simulator.run` (a `stabctl.storage.devices.StorageFleet`).

    Returns
    -------
    CCTResult
        The bracket ``(t_stable, t_unstable)`` (s after the fault start, exactly `tol`
        apart; the CCT is ``t_stable``), the probes, the separated machines and, with
        `error_check`, the CCT at h/2.

    Raises
    ------
    InputError
        Bad settings (among them a run end less than MIN_AFTER_CLEARING_S after the
        latest clearing, `check_run_end`, or a separation limit some machine's angle
        from the COI reaches before the fault, `Simulator.check_separation_limit`);
        unstable at t_lo > 0.
    InsecureContingency
        Unstable even when cleared at once (t_lo = 0): N-1 insecure, CCT 0 (an
        InputError, a verdict).
    AboveSearchLimit
        Still stable at t_max: the CCT is above it (an InputError, a verdict).
    UnknownBusError, CaseError
        No such bus or line.
    NumericalInstabilityError
        The step is too large: a numerically unstable run is never a verdict, it is
        raised.
    SimulationError
        The network fails while the fault is on.
    TypeError
        `sim` not a simulator (a `Simulator`, `cached_simulator`'s), `fault` not a
        `LineFault`, `search` not `SearchOptions` (`stabctl.errors.WrongTypeError`).

    Notes
    -----
    A run whose network has no solution after a machine has separated or after the fault
    is cleared counts as unstable (voltage collapse).  Sources: Kundur, Power System
    Stability and Control, 1994, sec. 13.3; Pai, Energy Function Analysis for Power System
    Stability, 1989, ch. 1.

    Examples
    --------
    The paper's Case 1 (Kundur, line 3-101), without storage and with 5 % ESDs:

    >>> import stabctl
    >>> case = stabctl.load_case("kundur")
    >>> sim = stabctl.Simulator(case)
    >>> fault = stabctl.LineFault(3, 101, 1.0)
    >>> stabctl.critical_clearing_time(sim, fault).cct_s
    0.154
    >>> fleet = stabctl.uniform_fleet(case, 5)
    >>> stabctl.critical_clearing_time(sim, fault, storage=fleet).cct_s
    0.199
    """
    if not isinstance(fault, LineFault):
        raise TypeError(
            "critical_clearing_time(fault): a LineFault is needed (LineFault(bus=3, "
            f"far_bus=101, t_fault=1.0)), got {type(fault).__name__}"
        )
    if search is not None and not isinstance(search, SearchOptions):
        raise WrongTypeError(
            "critical_clearing_time(search): SearchOptions(...) or None is needed (the "
            f"method as SearchOptions(method='sime')), got {search!r}"
        )
    o = SearchOptions() if search is None else search
    t_end = fault.t_fault + T_AFTER_FAULT if o.t_end is None else o.t_end
    t_hi = _first_upper(o)
    _check_settings(fault, o, t_hi, t_end)
    if o.provisional_s is not None and not o.provisional_s > 0:
        raise InputError(f"provisional_s must be > 0 s or None, got {o.provisional_s:g}")
    if o.guess_s is not None and not 0 <= o.guess_s < math.inf:
        raise InputError(f"guess_s must be a clearing time >= 0 s or None, got {o.guess_s:g}")
    if not (hasattr(sim, "run") and hasattr(sim, "case")):  # the settings checked first
        raise TypeError(
            "critical_clearing_time(sim): a Simulator is needed (stabctl.Simulator(case)), "
            f"got {type(sim).__name__}"
        )
    check_trips(sim.case, fault)
    if hasattr(sim, "check_separation_limit"):  # a Simulator: before any run
        sim.check_separation_limit(o.separation_limit)
    if o.method not in METHODS:
        raise InputError(f"CCT search method must be one of {METHODS}, got {o.method!r}")
    h = sim.default_h if h is None else h
    bounds = _lattice_bounds(o.tol, o.t_lo, t_hi, o.t_max)
    probe = _Probes(sim, fault, o, h, t_end, storage, (bounds[0], bounds[2]))
    wall = time.perf_counter()
    try:
        k_lo, k_hi, start = _search(probe, bounds)
    except Verdict as exc:  # robust or N-1 insecure: the islanding and runs go with it
        exc.islanded = tuple(probe.islanded)
        exc.n_simulations = probe.n_runs()
        if isinstance(exc, AboveSearchLimit):  # its stable run at the limit
            exc.end_t_s, exc.end_concerns = probe.ends.get(bounds[2], (None, ()))
        raise
    probe.held.clear()  # the bracket is confirmed: no run is continued any more
    run_end = _run_end_check(probe, k_lo, k_hi)
    half = None
    if o.error_check:
        stable_half = functools.partial(probe.stable_at, step=h / 2)
        half = _lattice(_half_step_cct(stable_half, k_lo, k_hi, bounds[2]), o.tol)
    return CCTResult(
        fault=fault,
        t_stable=_lattice(k_lo, o.tol),
        t_unstable=_lattice(k_hi, o.tol),
        search_bracket=(_lattice(start[0], o.tol), _lattice(start[1], o.tol)),
        tol_s=o.tol,
        t_max_s=o.t_max,
        step_s=h,
        freq_hz=sim.case.freq_hz,
        n_simulations=probe.n_runs(),
        wall_time_s=time.perf_counter() - wall,
        criterion=getattr(probe.crit, "__name__", repr(probe.crit)),
        probes=tuple(probe.probes[h]),
        separated=probe.separated.get(k_hi, ()),
        unstable_end_failure=probe.failed_at.get(k_hi),
        islanded=tuple(probe.islanded),
        stiff_step_s=probe.stiff_step,
        end_t_s=probe.ends.get(k_lo, (None, ()))[0],
        end_concerns=probe.ends.get(k_lo, (None, ()))[1],
        cct_half_step_s=half,
        half_step_probes=tuple(probe.probes[h / 2]),
        conventions=sim.conventions,
        method=o.method,
        early_stops=len(probe.early_stops),
        sub_stepped=sim.sub_stepped(h) if hasattr(sim, "sub_stepped") else 0,
        n_steps=probe.n_steps,
        resumed=probe.resumed,
        overturned=probe.overturned,
        run_end_check=run_end,
        storage_acted=probe.storage_acted,
    )


#: the keys of a run's-end check as a dict (`CCTResult.to_dict`'s ``run_end_check``,
#: `run_end_check`): the longer run's end and when it separated (None: stable), s
RUN_END_KEYS = ("t_end_s", "t_separation_s")


def run_end_lost(check: dict | None) -> bool:
    """Whether a run's-end check (a dict of `RUN_END_KEYS`, None: none was run) found the
    longer run losing synchronism: the CCT is not converged in the run's end.

    Parameters
    ----------
    check : dict or None
        ``run_end_check`` of a CCT result's dict or record, or of a plan's row.

    Returns
    -------
    bool
    """
    return check is not None and check.get("t_separation_s") is not None


#: an unstable end of the bracket that separated later than this share of its run after
#: its clearing has the stable end run again T_AFTER_FAULT s longer (`_run_end_check`)
LATE_SEPARATION = 0.8


def _run_end_check(probe: _Probes, k_lo: int, k_hi: int) -> tuple[float, float | None] | None:
    """Whether the CCT depends on the run's end: when the bracket's unstable end separated
    late in its run (`_separated_late`), the stable end is run again to t_end +
    T_AFTER_FAULT (one run more, counted); (that end, when it separated there, s, or
    None) then, else None.  Round 41: Kundur's 1-10, whose trip islands G1 and leaves the
    rest drifting out of step 5-10 s after the fault, had its CCT 0.440 s with the default
    end, 0.337 s run to 10 s, 0.001 s to 20 s, and a printed error bar of 1 ms."""
    if not _separated_late(probe, k_hi):
        return None
    return _longer_run(probe, k_lo)


def _separated_late(probe: _Probes, k: int) -> bool:
    """Whether the unstable probe k separated past LATE_SEPARATION of the time from its
    clearing to t_end (a slow separation the run's end may have cut short at a lower
    clearing time)."""
    t_sep = probe.separated_at.get(k)
    cleared = probe.fault.t_fault + _lattice(k, probe.o.tol)
    return t_sep is not None and t_sep - cleared >= LATE_SEPARATION * (probe.t_end - cleared)


def _longer_run(probe: _Probes, k: int) -> tuple[float, float | None]:
    """The probe cleared at k run to t_end + T_AFTER_FAULT (counted): (that end, when it
    separated, s, or None: stable)."""
    return _longer_at(probe, _lattice(k, probe.o.tol))


def _longer_at(probe: _Probes, t_clear: float) -> tuple[float, float | None]:
    """`_longer_run` at a clearing time t_clear (s after the fault start)."""
    longer = probe.t_end + T_AFTER_FAULT
    res, diverged = probe._whole(t_clear, probe.h, t_end=longer)
    probe.reruns += 1
    probe.n_steps += _steps(res)
    if not diverged and probe._said(res):
        return (longer, None)
    at = getattr(res, "t_separation", None)
    return (longer, float(res.t[-1]) if at is None else float(at))


def run_end_check(
    sim: Runner,
    fault: LineFault,
    t_clear: float,
    search: SearchOptions | None = None,
    *,
    h: float | None = None,
    storage=None,
) -> dict:
    """The check `critical_clearing_time` makes of a CCT whose unstable end separated late
    in its run (`CCTResult.run_end_check`), made of one clearing time: the run cleared at
    `t_clear` run T_AFTER_FAULT s past the search's run end, stopped at separation, judged
    by the search's criterion (one run).  For a verdict taken in the search's window (e.g.
    a placement's check run at a required clearing time) whose CCT search flagged its
    run's end.

    Parameters
    ----------
    sim : Runner
        The simulator.
    fault : LineFault
        The fault.
    t_clear : float
        Clearing time, s after the fault start.
    search : SearchOptions or None, optional
        The search whose window is extended (its ``t_end``, None: the fault start +
        T_AFTER_FAULT; its criterion and separation limit); default `SearchOptions()`.
    h : float or None, optional
        Integration step, s (default `sim.default_h`).
    storage : StorageFleet or None, optional
        Passed to the run.

    Returns
    -------
    dict
        ``t_end_s`` (the longer run's end, s) and ``t_separation_s`` (when it separated,
        s, or None: stable there), as `CCTResult.to_dict`'s ``run_end_check``.

    Raises
    ------
    SimulationError
        The network fails while the fault is on.
    """
    o = SearchOptions() if search is None else search
    t_end = fault.t_fault + T_AFTER_FAULT if o.t_end is None else o.t_end
    h = sim.default_h if h is None else h
    probe = _Probes(sim, fault, o, h, t_end, storage, ())
    return dict(zip(RUN_END_KEYS, _longer_at(probe, float(t_clear))))


def _window_stable(probe: _Probes, k: int) -> bool:
    """An insecure fault's window run at k (`_lower_bound_unstable`): stable to t_end,
    and, when the run cleared at once separated late in its run, to T_AFTER_FAULT s later
    too (round 41: Kundur's 2-20, "yet stable when cleared at 0.017 s", separates at
    6.3 s run to 20 s: the trip alone separates 4.4 s after it)."""
    if not probe.stable_whole(k):
        return False
    return not _separated_late(probe, 0) or _longer_run(probe, k)[1] is None


def _search(probe: _Probes, bounds) -> tuple[int, int, tuple[int, int]]:
    """The search of `probe`'s options (`SearchOptions.method`) on the lattice bounds
    (k_lo, k_hi, k_max): (k_stable, k_unstable = k_stable + 1, the first (stable,
    unstable) pair found), the stable end confirmed by a whole run."""
    k_lo, k_hi, k_max = bounds
    fault, tol, freq = probe.fault, probe.o.tol, probe.sim.case.freq_hz
    sime, guess = probe.o.method == "sime", probe.o.guess_s
    if guess is not None and k_max - k_lo >= 2:  # room for a guessed cell and its neighbours
        if not sime and not probe.stable_at(k_lo):  # bisection's own check
            _lower_bound_unstable(
                k_lo, fault, tol, functools.partial(_window_stable, probe), k_max, freq
            )
        found = _around_guess(probe, bounds, round(guess / tol))
        if found is not None:
            return (*_bisect_confirmed(probe, *found), found)
        probe.reuse()  # the search without the guess, its verdicts read again
    if sime:
        return _sime_search(probe, bounds, fault, tol, freq)
    k_lo, k_hi = _bracket(probe, k_lo, k_hi, k_max, fault, tol, freq)
    return (*_bisect_confirmed(probe, k_lo, k_hi), (k_lo, k_hi))


#: widening steps from a guessed cell (`_around_guess`): 2 reach 7 cells beyond the
#: guess's neighbour
GUESS_GALLOPS = 2


def _around_guess(probe: _Probes, bounds, k_guess: int) -> tuple[int, int] | None:
    """A (stable, unstable) lattice bracket near a guessed cell (`SearchOptions.guess_s`),
    or None.

    The guess k (kept within (k_lo, k_max)) is probed, then k + 1 when stable there (k - 1
    when not): a verdict that changes closes the cell.  Stable at both: the probe at k_max
    (as the search without a guess starts; stable there: None), then GUESS_GALLOPS steps
    of 2, 4 ... cells above k + 1 until one is unstable; unstable at both, as many below
    k - 1 (k_lo at most) until one is stable.  None when none is: the search then runs as
    without the guess, so that a guess far off (a trip that moves the CCT, a verdict not
    monotone) never leads it elsewhere.  A verdict the search already has is not run
    again.
    """
    k_lo, _, k_max = bounds

    def stable_at(k: int) -> bool:
        return probe.verdicts[k] if k in probe.verdicts else probe.stable_at(k)

    k = min(max(k_guess, k_lo + 1), k_max - 1)
    up = stable_at(k)
    j = k + 1 if up else k - 1
    if stable_at(j) != up:
        return (k, j) if up else (j, k)
    if up and (j == k_max or stable_at(k_max)):
        return None
    gap = 2
    for _ in range(GUESS_GALLOPS):
        nxt = min(j + gap, k_max) if up else max(j - gap, k_lo)
        if nxt == j:
            return None
        if stable_at(nxt) != up:
            return (j, nxt) if up else (nxt, j)
        j, gap = nxt, 2 * gap
    return None


#: the provisional stable runs a search keeps to continue (`_Probes.held`): the highest
#: below its lowest unstable probe (ACTIVSg2000: 9.8 MB each, its recording to t_end of
#: the machines only; the stages are shared)
KEPT_RUNS = 3


class _Probes:
    """The runs of one CCT search (`critical_clearing_time`) and what it keeps of them.

    A probe at the step h with the default criterion (no early verdicts) on a simulator
    that starts runs it can continue (`stabctl.dynamics.driver.Simulator.start`) is
    integrated to `SearchOptions.provisional_s` after the clearing only: separated by
    then, it is unstable as the whole run; swung GENTLE_SWING or more, run on to t_end;
    else provisionally stable, its run kept (`held`, at most KEPT_RUNS) until the search
    closes a cell on it, then continued to t_end (`confirm`; found unstable, the
    search's later probes run whole).  The runs at the search's bounds (k_lo: N-1
    insecure; k_max: above the limit, robust in one run) and at h/2 are whole runs.

    Parameters
    ----------
    sim : Runner
        The simulator.
    fault : LineFault
        The fault.
    o : SearchOptions
        The search's settings.
    h : float
        The step, s.
    t_end : float
        The runs' end, s (absolute).
    storage : StorageFleet or None
        Passed to the runs.
    whole : tuple of int
        The lattice indices whose runs are whole at the step (k_lo, k_max).
    """

    def __init__(self, sim, fault: LineFault, o: SearchOptions, h, t_end, storage, whole):
        self.sim, self.fault, self.o, self.h, self.t_end, self.whole = (
            sim, fault, o, h, t_end, whole,
        )  # fmt: skip
        self.crit = no_separation if o.criterion is None else o.criterion
        self.stop = o.criterion is None if o.stop_at_separation is None else o.stop_at_separation
        self.extra = {} if storage is None else {"storage": storage}
        #: with storage, whether a device switched in any run so far (None: no storage)
        self.storage_acted: bool | None = None if storage is None else False
        if o.criterion is None and getattr(sim, "takes_monitor", False):
            self.extra["voltages"] = False  # the default criterion reads the machines only
        self.early = o.early_stop and o.criterion is None and getattr(sim, "takes_monitor", False)
        usable = o.criterion is None and not self.early and hasattr(sim, "start")
        #: how long a probe runs after its clearing before it is judged provisionally, s
        self.window = o.provisional_s if usable else None
        self.probes: dict[float, list] = {h: [], h / 2: []}
        self.separated: dict = {}
        #: the time each unstable probe at the step separated, s (`_run_end_check`)
        self.separated_at: dict[int, float] = {}
        #: unstable probes whose run failed before any machine separated: what ended it
        self.failed_at: dict[int, str] = {}
        self.margins: dict = {}
        self.swings: dict = {}
        self.early_stops: list = []
        self.islanded: list = []
        #: the whole stable runs at the step ending off a normal operating point, by
        #: lattice index: (end time s, `SimulationResult.end_concerns`)
        self.ends: dict[int, tuple[float, tuple[str, ...]]] = {}
        #: the shortest step of an interval cut in the runs at the step (None: none)
        self.stiff_step: float | None = None
        #: the step's verdicts by lattice index; the provisional ones; their runs kept
        #: (handle, grid points reached)
        self.verdicts: dict[int, bool] = {}
        self.provisional: set[int] = set()
        self.held: dict[int, tuple] = {}
        self.n_steps = self.reruns = self.resumed = self.overturned = 0
        #: verdicts at the step read again instead of run (`reuse`): (verdict, margin,
        #: swing) by lattice index
        self.reusable: dict[int, tuple] = {}

    def reuse(self) -> None:
        """Let the search start again (a guess that found no cell, `_around_guess`): each
        verdict found so far at the step is given again, with its margin and swing, when
        the search asks for it, instead of being run; the others are run."""
        self.reusable = {
            k: (ok, self.margins.pop(k, _ABSENT), self.swings.pop(k, _ABSENT))
            for k, ok in self.verdicts.items()
        }

    def n_runs(self) -> int:
        """The simulations run so far (at the step and at h/2; a provisional run continued
        counts once, one run again whole twice)."""
        return len(self.probes[self.h]) + len(self.probes[self.h / 2]) + self.reruns

    def stable_at(self, k: int, step: float | None = None) -> bool:
        """The verdict at clearing time k*tol (s) and step `step` (s; default h):
        provisional when the probe is (class docstring)."""
        step = self.h if step is None else step
        if step == self.h and k in self.reusable:
            ok, margin, swing = self.reusable.pop(k)
            if margin is not _ABSENT:
                self.margins[k] = margin
            if swing is not _ABSENT:
                self.swings[k] = swing
            return ok
        t_clear = _lattice(k, self.o.tol)
        pause = self.fault.t_fault + t_clear + (self.window or 0.0)
        if step != self.h or self.window is None or k in self.whole or pause >= self.t_end:
            res, diverged = self._whole(t_clear, step)
            self.n_steps += _steps(res)
            return self._judged(k, step, res, diverged, provisional=False)
        started: list = []
        res, diverged = _outcome(
            self.fault, t_clear, functools.partial(self._started, t_clear, pause, started)
        )
        self.n_steps += _steps(res)
        ok = self._judged(k, step, res, diverged, provisional=bool(started) and not started[0].done)
        if k in self.provisional:
            self._keep(k, (started[0], len(res.t)))
        return ok

    def stable_whole(self, k: int) -> bool:
        """The verdict at clearing time k*tol (s) of a run to t_end (a provisionally
        stable probe confirmed)."""
        return self.stable_at(k) and self.confirm(k)

    def confirm(self, k: int) -> bool:
        """Whether the stable end k of a closed cell stays stable to t_end: a
        provisionally stable probe's run continued (or, when it was not kept, run again
        whole); the other verdicts as they are."""
        if k not in self.provisional:
            return self.verdicts[k]
        self.provisional.discard(k)
        t_clear = _lattice(k, self.o.tol)
        if k in self.held:
            handle, n_t = self.held.pop(k)
            self.resumed += 1
            res, diverged = _outcome(
                self.fault, t_clear, functools.partial(_continued, handle, self.t_end)
            )
            self.n_steps += len(res.t) - n_t
        else:
            self.reruns += 1
            res, diverged = self._whole(t_clear, self.h)
            self.n_steps += _steps(res)
        i = self.probes[self.h].index((t_clear, True))
        ok = self._judged(k, self.h, res, diverged, provisional=False, record=False)
        if not ok:  # late separations near here: the search's other probes run whole
            self.overturned += 1
            self.probes[self.h][i] = (t_clear, False)
            self.window = None
        return ok

    def stable_below(self, k: int) -> int:
        """The highest lattice index below k found stable at the step (provisionally or
        not)."""
        return max(j for j, ok in self.verdicts.items() if ok and j < k)

    def _whole(
        self, t_clear: float, step: float, t_end: float | None = None
    ) -> tuple[SimulationResult, bool]:
        """A whole run (to t_end or its stop), with its early verdict's monitor when the
        search ends runs early; given `t_end` (s, a run longer than the search's,
        `_longer_run`), without early verdicts and stopped at separation."""
        extra, stop = self.extra, self.stop
        if t_end is not None:
            stop = True
        elif self.early:
            t_cl, case = self.fault.t_fault + t_clear, self.sim.case
            monitor = EarlyVerdict(t_cl, self.t_end, case.freq_hz, self.o.separation_limit)
            extra = {**extra, "monitor": monitor}
        run = functools.partial(
            self.sim.run,
            self.fault.events(t_clear),
            self.t_end if t_end is None else t_end,
            h=step,
            separation_limit=self.o.separation_limit,
            stop_at_separation=stop,
            **extra,
        )
        return _outcome(self.fault, t_clear, run)

    def _started(self, t_clear: float, pause: float, started: list) -> SimulationResult:
        """A run started to t_end (appended to `started`), advanced to `pause` (s), its
        result there."""
        handle = self.sim.start(
            self.fault.events(t_clear),
            self.t_end,
            h=self.h,
            separation_limit=self.o.separation_limit,
            stop_at_separation=self.stop,
            **self.extra,
        )
        started.append(handle)
        handle.advance_to(pause)
        res = handle.result()
        if res.stable and largest_swing(res) >= GENTLE_SWING:  # may still separate
            handle.advance_to(self.t_end)
            res = handle.result()
        return res

    def _judged(self, k, step, res, diverged, provisional: bool, record: bool = True) -> bool:
        """A run's verdict, recorded with what the search reads of it: the separated
        machines and SIME's margin of an unstable run, the swing of a stable whole one."""
        o, case = self.o, self.sim.case
        t_clear = _lattice(k, o.tol)
        verdict = res.meta.get("early_verdict") if self.early and not diverged else None
        if verdict:
            self.early_stops.append(t_clear)
        # no machine left in service (de-energised): no stable clearing, whatever an early
        # verdict on the machines left judged (none) or a custom criterion says
        dead = getattr(res, "de_energised_s", None) is not None  # a stand-in result: none
        ok = not diverged and not dead and (verdict == "stable" if verdict else self._said(res))
        if record:
            self.probes[step].append((t_clear, ok))
        if self.storage_acted is False:
            devices = getattr(res, "meta", {}).get("storage", ())
            self.storage_acted = any(d["switchings"] for d in devices)
        if not self.islanded:
            self.islanded.extend(res.meta.get("islanded", []))
        if step != self.h:
            return ok
        for cut in getattr(res, "meta", {}).get("stiff_intervals", ()):
            self.stiff_step = min(cut["step_s"], self.stiff_step or np.inf)
        self.verdicts[k] = ok
        if ok and provisional:
            self.provisional.add(k)
        ends = getattr(res, "end_concerns", None)  # a stand-in result: none
        if ok and not provisional and ends is not None and (concerns := ends(case.freq_hz)):
            self.ends[k] = (float(res.t[-1]), tuple(concerns))
        if not ok:
            self._trim()
            self.separated[k] = tuple(int(m) for m in (res.separated or critical_machines(res)))
            if getattr(res, "t_separation", None) is not None:
                self.separated_at[k] = float(res.t_separation)
            elif diverged:  # (round 44: said to "lose synchronism")
                self.failed_at[k] = res.meta.get("diverged", "the run failed")
        if o.method == "sime" and not ok and not dead:
            t_cl = self.fault.t_fault + t_clear
            self.margins[k] = probe_margin(
                res, t_cl, case.base_mva, case.freq_hz, machine_inertia(case)
            )
        if o.method == "sime" and ok and not provisional:
            self.swings[k] = largest_swing(res)
        return ok

    def _said(self, res: SimulationResult) -> bool:
        """The criterion's verdict on `res`: True (stable) or False, numpy's too; anything
        else is refused (a criterion returning None was read as unstable: N-1 insecure)."""
        said = self.crit(res)
        if not isinstance(said, (bool, np.bool_)):
            raise WrongTypeError(
                f"SearchOptions(criterion): {getattr(self.crit, '__name__', 'the criterion')} "
                f"returned {said!r} ({type(said).__name__}); it must return True (stable) or "
                "False (unstable)"
            )
        return bool(said)

    def _keep(self, k: int, held: tuple) -> None:
        """Keep a provisional run (`_trim`)."""
        self.held[k] = held
        self._trim()

    def _trim(self) -> None:
        """Drop the kept runs no search closes a cell on (above an unstable probe) and,
        past KEPT_RUNS, the lowest."""
        u = min((j for j, ok in self.verdicts.items() if not ok), default=math.inf)
        for j in [j for j in self.held if j > u]:
            del self.held[j]
        while len(self.held) > KEPT_RUNS:
            del self.held[min(self.held)]


#: a margin or swing a verdict read again does not have (`_Probes.reuse`)
_ABSENT = object()


def _steps(res) -> int:
    """A run's time steps from t = 0 (0 for a stand-in result without times)."""
    return max(len(getattr(res, "t", ())) - 1, 0)


def _continued(handle, t_end: float) -> SimulationResult:
    """A kept run (`stabctl.dynamics.driver.RunHandle`) continued to t_end (s), its
    result."""
    handle.advance_to(t_end)
    return handle.result()


def _bisect_confirmed(probe: _Probes, k_lo: int, k_hi: int) -> tuple[int, int]:
    """Bisect a (stable, unstable) bracket to adjacent cells whose stable end is
    confirmed (`_Probes.confirm`): an end that separates when continued is unstable, and
    the search goes on from the next stable probe below it."""
    while True:
        k_lo, k_hi = _bisect(probe.stable_at, k_lo, k_hi)
        if probe.confirm(k_lo):
            return k_lo, k_hi
        k_lo, k_hi = probe.stable_below(k_lo), k_lo


#: the CCT search methods (`SearchOptions.method`)
METHODS = ("sime", "bisection")


def _sime_search(probe: _Probes, bounds, fault: LineFault, tol, freq):
    """The "sime" search on the lattice: returns (k_stable, k_unstable = k_stable + 1,
    the first (stable, unstable) pair found), the stable end confirmed
    (`_Probes.confirm`: a provisional stable end that separates when continued is
    unstable, and the search goes on below it).

    The first probe is at k_max (when above k_hi): stable there with no machine swung
    ROBUST_SWING rad or more from its angle to the centre of inertia before the fault
    (`largest_swing`, ``probe.swings`` filled for each whole stable run), the fault is
    robust in one run (AboveSearchLimit).  The verdicts below such a gentle run are taken
    to be stable too: a shorter fault swings the machines less, and the non-monotone
    verdicts seen come with wide swings (ACTIVSg2000's bus 5370, stable cleared at 0.6 s
    and 1.0 s but unstable at 0.8 s, swings 1.6 rad when cleared at 0.5 s).  Of
    ACTIVSg2000's bus and line faults (a random sample, seed 7: 150 bus faults and about
    100 line faults) the 178 found stable at 0.1 s and at 0.5 s were stable at 0.2 and
    0.4 s too (the doubling's probes), 146 of them within 1 rad; of its whole N-1 (5 206
    faults, t_max 0.5 s) the 867 stable at 0.5 s with a swing of 1 rad or more, every
    machine counted (those cut off too: 1.0-38.8 rad, 368 below 1.5), were stable at 0.1,
    0.2 and 0.4 s, every one (`benchmarks/bench_screening.py`).  Any other outcome at
    k_max leaves the search below exactly as it would be without that probe: its verdict
    and margin are used only once the doubling reaches k_max (a run there that fails
    while the fault is on, SimulationError, is left to the doubling, which may never
    reach it).  Its margin used at once saved 0.4 runs a CCT on Kundur, but on
    ACTIVSg2000's bus 4162, unstable cleared at 0.224-0.3 s and stable at 0.392 s,
    extrapolated from 0.4 and 0.5 s straight to a CCT of 0.392 s above that instability
    (the doubling's 0.3 s probe finds 0.223 s).

    SIME's unstable margin is close to linear in the clearing time (`probe_margin`), so
    two unstable probes extrapolate to the CCT (`_margin_zero`).  After the probe at
    k_max the search starts at k_hi, doubled while stable (as the bisection's bracket: a
    jump from a stable k_hi straight to k_max and a bisection from there was tried and
    dropped: it found other ends of non-monotone verdicts than the doubling, e.g.
    ACTIVSg2000's bus 1050, 0.172 s against 0.121 s); the check at k_lo (as `_bracket`)
    is run only when an unstable probe comes before any stable one, i.e. it is assumed
    that a probe found stable above k_lo makes k_lo stable too (a verdict monotone below
    the first stable probe).  That is not always so: Kundur's fault at bus 3 on line 3-4
    is unstable when cleared within 0-10 ms and stable at 30-67 ms; its verdict (N-1
    insecure) equals the bisection's because its probes at k_max and at 0.1 s are
    unstable, but a first probe (t_hi) in 30-67 ms would give a CCT there. Then
    bisection until two unstable probes have a margin.  Then, up to SIME_GUIDED times,
    the zero x of the margin extrapolated from the two unstable probes closest to it
    sets the probe: more than SIME_NEAR cells below the unstable end, at ceil(x) (the
    margin bends towards 0 near the CCT, so the zero extrapolated from above mostly
    lands on the unstable side, and the next extrapolation is short); within SIME_NEAR
    cells, at x rounded (the cell above the stable end when floor(x) is that end, the
    cell below the unstable end when x is above it); below the stable end, a quarter of
    the bracket above it.  Two guided probes in a row that moved the same end by at most
    2 cells (the bracket creeping) are followed by a bisection step; after SIME_GUIDED
    guided probes, bisection.  A probe at k_max found stable raises AboveSearchLimit.
    ``probe.margins`` (lattice index -> margin or None) is filled for each unstable
    probe."""
    k_lo, k_hi, k_max = bounds
    stable_at, margins, swings = probe.stable_at, probe.margins, probe.swings
    known: dict[int, bool] = {}
    at_max: dict[int, bool] = {}
    held: dict = {}
    if k_max > k_hi:  # robust in one run when gentle there; else reused by the doubling
        try:
            at_max[k_max] = stable_at(k_max)
        except SimulationError:  # a long fault the doubling may never reach: left to it
            pass
        if at_max.get(k_max) and swings[k_max] < ROBUST_SWING:
            _above_limit(k_max, fault, tol, freq)
        if k_max in margins:  # used once the doubling gets there, as its own probe's
            held[k_max] = margins.pop(k_max)
    start = None
    n_guided, guided, ends, last = 0, None, (k_lo, k_max), None
    k: int | None = k_hi
    while True:
        creeping = False
        if k is not None:  # None: a stable end just found unstable, no new probe
            if k in at_max:
                known[k] = at_max.pop(k)
                margins.update(held)
            else:
                known[k] = stable_at(k)
            if k == k_max and known[k]:
                _above_limit(k_max, fault, tol, freq)
            moved = None
            if k == guided:  # the cells the bracket's end moved, and whether it creeps
                moved = (known[k], k - ends[0] if known[k] else ends[1] - k)
                creeping = last is not None and last[0] == moved[0] and max(last[1], moved[1]) <= 2
            last = moved
        u = min((j for j, ok in known.items() if not ok), default=None)
        if u is not None and not any(ok for j, ok in known.items() if j < u):
            if not stable_at(k_lo):  # no stable probe yet: the check at k_lo
                _lower_bound_unstable(
                    k_lo, fault, tol, functools.partial(_window_stable, probe), k_max, freq
                )
            known[k_lo] = True
        s = max(j for j, ok in known.items() if ok and (u is None or j < u))
        if u is None:  # stable so far (s the last probe): double
            k = min(2 * s, k_max)
            continue
        start = start or (s, u)
        if u - s == 1:
            if probe.confirm(s):
                return s, u, start
            known[s], k, last = False, None, None
            continue
        zero = _margin_zero(margins, u) if n_guided < SIME_GUIDED else None
        if zero is None or creeping:
            k, guided, last = (s + u) // 2, None, None
            continue
        kf = math.floor(zero)
        if kf < s:
            k = s + max(1, (u - s) // 4)
        elif kf == s:
            k = s + 1
        elif u - zero <= SIME_NEAR:
            k = max(round(zero), s + 1)
        else:
            k = math.ceil(zero)
        k = guided = min(k, u - 1)
        ends = (s, u)
        n_guided += 1


#: swing (rad, `largest_swing`) from which a provisionally stable probe runs on to t_end
#: at once (`_Probes`; ACTIVSg2000's bus 5367 needs it at 1 rad with a 2 s window)
GENTLE_SWING = 1.0
#: swing (rad) below which a stable run at t_max makes a fault robust in one run
#: (`_sime_search`); bus 5370's 1.6 rad at 0.5 s stays above it
ROBUST_SWING = 1.5


def largest_swing(result: SimulationResult) -> float:
    """The largest move (rad) of a machine's angle to its centre of inertia from its value
    at the start of the run, over the machines the loss-of-synchronism criterion judges
    at each time (`stabctl.dynamics.partition.judged_relative`: with `partitions`, the
    judged machines of the island of the stage at each time; a machine tripped or cut
    off the main grid is lost, its own slip not a swing)."""
    rel = judged_relative(result.angle, result.t, result.inertia, result.island, result.partitions)
    moved = np.abs(rel - rel[0])
    if result.partitions:
        moved *= judged_at(result.t, result.partitions)
    return float(moved.max())


#: probes placed from SIME's margins before the "sime" search bisects what is left; the
#: distance (lattice cells) below the unstable end within which the probe goes to the
#: extrapolated zero rounded
SIME_GUIDED, SIME_NEAR = 8, 3


def _margin_zero(margins: dict, u: int) -> float | None:
    """The lattice position (real) where SIME's unstable margin vanishes, extrapolated
    through the two unstable probes with a negative margin closest to the boundary (at
    or above u); None without two, or with a slope that does not fall (then
    `_sime_search` bisects)."""
    have = sorted(k for k, m in margins.items() if k >= u and m is not None and m < 0)
    if len(have) < 2:
        return None
    a, b = have[:2]
    slope = (margins[b] - margins[a]) / (b - a)
    return a - margins[a] / slope if slope < 0 else None


def _bisect(stable_at, k_lo: int, k_hi: int) -> tuple[int, int]:
    """Bisect a (stable, unstable) lattice bracket down to adjacent cells."""
    while k_hi - k_lo > 1:
        mid = (k_lo + k_hi) // 2
        k_lo, k_hi = (mid, k_hi) if stable_at(mid) else (k_lo, mid)
    return k_lo, k_hi


def _half_step_cct(stable_half, k_lo: int, k_hi: int, k_max: int) -> int:
    """Lattice index of the CCT at half the step, from the bracket (k_lo, k_hi = k_lo + 1)
    found at the full step: the unstable end rerun first (stable at h/2, the stable end
    is taken to be stable too: the verdict monotone), else the stable end; an end whose
    verdict changed is pushed away (distance doubled each time, within [0, k_max]) until
    the verdict is restored, then the new bracket is bisected.  An end pushed to the
    limit of the range is returned as is (the CCT at h/2 lies beyond it)."""
    if stable_half(k_hi):
        step, k_lo = 1, k_hi
        while k_hi < k_max:
            k_lo, k_hi = k_hi, min(k_hi + step, k_max)
            step *= 2
            if not stable_half(k_hi):
                return _bisect(stable_half, k_lo, k_hi)[0]
        return k_max
    if not stable_half(k_lo):
        step, k_hi = 1, k_lo
        while k_lo > 0:
            k_hi, k_lo = k_lo, max(k_lo - step, 0)
            step *= 2
            if stable_half(k_lo):
                return _bisect(stable_half, k_lo, k_hi)[0]
        return 0
    return k_lo


def _check_settings(fault: LineFault, o: SearchOptions, t_hi, t_end) -> None:
    if not o.tol >= MIN_TOL:
        raise InputError(f"CCT tolerance must be >= {MIN_TOL:g} s (1 us), got {o.tol:g}")
    if not 0 <= o.t_lo < t_hi <= o.t_max:
        given = (
            ""
            if o.t_hi is not None
            else f" (t_hi not given: its default, min({T_HI:g}, t_max); give one above t_lo)"
        )
        raise InputError(
            "CCT search bounds need 0 <= t_lo < t_hi <= t_max, got "
            f"t_lo {o.t_lo:g}, t_hi {t_hi:g}{given}, t_max {o.t_max:g} s"
        )
    if fault.t_fault < 0:
        raise InputError(f"fault time must be >= 0 s, got {fault.t_fault:g}")
    problem = _run_end_problem(fault.t_fault, o.t_max, t_end, o.t_end is not None)
    if problem is not None:
        raise InputError(problem)


def _run_end_problem(t_fault: float, t_max: float, t_end: float, given: bool) -> str | None:
    """What is wrong with a search's run end `t_end` (s, absolute; `given`: set, else the
    default fault time + T_AFTER_FAULT) for a fault at `t_fault` cleared as late as
    t_max: less than MIN_AFTER_CLEARING_S after that latest clearing; None if nothing."""
    latest = t_fault + t_max
    left = t_end - latest
    if left >= MIN_AFTER_CLEARING_S - 1e-9:
        return None
    where = f"only {left:g} s after" if left > 0 else "at" if left == 0 else f"{-left:g} s before"
    end = (
        f"run end {t_end:g} s (t_end, --tf)"
        if given
        else f"default run end {t_end:g} s (the fault start + {T_AFTER_FAULT:g} s)"
    )
    fixes = [f"a t_end (--tf) of at least {latest + MIN_AFTER_CLEARING_S:g} s"]
    most = t_end - t_fault - MIN_AFTER_CLEARING_S
    if most > 0:
        fixes.insert(given, f"a t_max (--t-max) of at most {most:g} s")
    return (
        f"{end} is {where} the latest clearing (fault at {t_fault:g} s + t_max "
        f"{t_max:g} s = {latest:g} s); the runs must go on at least "
        f"{MIN_AFTER_CLEARING_S:g} s after it, the time a probe cleared past the CCT can "
        "take to separate (one that has not separated reads stable: the CCT comes out "
        f"high, or above t_max): give {' or '.join(fixes)}"
    )


def check_run_end(fault: LineFault, search: SearchOptions) -> None:
    """Refuse a search whose runs end less than MIN_AFTER_CLEARING_S after its latest
    clearing (the fault time + t_max), before any run: a probe cleared past the CCT might
    not have separated by then and would read stable (`critical_clearing_time` refuses
    it so too; the sweeps check every fault first).

    Parameters
    ----------
    fault : LineFault
        The fault (its start time).
    search : SearchOptions
        ``t_max`` and ``t_end`` (s; None: the fault start + T_AFTER_FAULT).

    Raises
    ------
    InputError
        Naming the run end, the fault time, t_max, the minimum and what to change.
    """
    t_end = fault.t_fault + T_AFTER_FAULT if search.t_end is None else search.t_end
    problem = _run_end_problem(fault.t_fault, search.t_max, t_end, search.t_end is not None)
    if problem is not None:
        raise InputError(f"{fault.describe()}: {problem}")


def check_search_range(search: SearchOptions) -> None:
    """Refuse, before any run, a search whose range from t_lo to t_max holds no whole
    lattice cell (a t_max below the tolerance): every search with these settings would
    fail, whatever the fault; and one whose tolerance is not below t_max: its one cell
    spans the whole range, so every search would report a CCT of 0 (or above t_max),
    whatever the fault; one whose t_max is not a multiple of the tolerance (the search
    clears on those multiples: its last run would lie below t_max, and a fault stable
    there be reported robust up to t_max); and, with the default run end (``t_end``
    None: the fault start + T_AFTER_FAULT), a t_max that leaves less than
    MIN_AFTER_CLEARING_S after it (a given t_end is checked per fault, `check_run_end`).
    The sweeps (`cct_jobs`) and the CLI's searches check their settings so;
    `critical_clearing_time` takes such a one-cell bracket (a caller that already knows
    its upper end unstable).

    Parameters
    ----------
    search : SearchOptions
        The settings; ``0 <= t_lo < t_hi <= t_max`` already checked.

    Raises
    ------
    InputError
        A tolerance below `MIN_TOL`, the range narrower than the tolerance (the search's
        own rule and message), the tolerance not below t_max, a t_max off the tolerance's
        multiples, or a t_max too close to the default run end.
    """
    if not search.tol >= MIN_TOL:
        raise InputError(f"CCT tolerance must be >= {MIN_TOL:g} s (1 us), got {search.tol:g}")
    _lattice_bounds(search.tol, search.t_lo, _first_upper(search), search.t_max)
    cells = search.t_max / search.tol
    if abs(cells - round(cells)) > 1e-6:  # its last run would be below t_max, unsaid
        below, above = (
            _lattice(math.floor(cells), search.tol),
            _lattice(math.ceil(cells), search.tol),
        )
        raise InputError(
            f"t_max {search.t_max:g} s is not a multiple of the CCT tolerance "
            f"{search.tol:g} s: the search clears on multiples of it, so its last run would "
            f"be at {below:g} s and a fault stable there reported robust up to "
            f"{search.t_max:g} s; give {advice('t_max', '--t-max')} {below:g} or {above:g} s"
        )
    if not search.tol < search.t_max:
        raise InputError(
            f"the CCT tolerance {search.tol:g} s is not below t_max {search.t_max:g} s: one "
            "step would span the whole search, whose CCT would read 0 (or above t_max) "
            "whatever the fault"
        )
    if search.t_end is None and T_AFTER_FAULT - search.t_max < MIN_AFTER_CLEARING_S - 1e-9:
        raise InputError(default_run_end_problem(search.t_max, "t_max", "t_end"))


def default_run_end_problem(t_max: float, t_max_name: str, t_end_name: str | None) -> str:
    """The refusal of a t_max too close to the default run end (the fault start +
    T_AFTER_FAULT): it leaves less than MIN_AFTER_CLEARING_S after the latest clearing.

    Parameters
    ----------
    t_max : float
        The search limit, s.
    t_max_name : str
        What t_max is called (``"t_max"``, the CLI's ``"--t-max"``).
    t_end_name : str or None
        What the run end is called (``"t_end"``, ``"--tf"``), None where it cannot be
        given (the message then offers a lower t_max only).

    Returns
    -------
    str
        The message: t_max, the run end, the minimum and what to change.
    """
    later = (
        ""
        if t_end_name is None
        else f", or a {t_end_name} of at least the fault start + {t_max + MIN_AFTER_CLEARING_S:g} s"
    )
    return (
        f"{t_max_name} {t_max:g} s: the runs end {T_AFTER_FAULT:g} s after the fault start "
        f"(the default), only {T_AFTER_FAULT - t_max:g} s after the latest clearing; they "
        f"must go on at least {MIN_AFTER_CLEARING_S:g} s after it, the time a probe "
        "cleared past the CCT can take to separate (one that has not separated reads "
        f"stable: the CCT comes out high, or above t_max): give a {t_max_name} of at most "
        f"{T_AFTER_FAULT - MIN_AFTER_CLEARING_S:g} s{later}"
    )


def _first_upper(o: SearchOptions) -> float:
    """The first upper bound of a search, s: t_hi, default min(T_HI, t_max)."""
    return min(T_HI, o.t_max) if o.t_hi is None else o.t_hi


def check_trips(case, fault: LineFault, name: str = "trip") -> None:
    """Refuse a further trip of the faulted circuit itself (the fault's clearing opens
    it: the trip would do nothing).

    Parameters
    ----------
    case : stabctl.case.Case
        The case.
    fault : LineFault
        The fault and its further trips.
    name : str, optional
        What a trip is called in the message (the CLI's ``--trip``).

    Raises
    ------
    InputError
        A trip of the faulted circuit, naming `name`, the trip and the fault.
    CaseError
        A trip or faulted circuit not in the case.
    """
    if not fault.trips or fault.far_bus is None:  # a bus fault opens no circuit of its own
        return
    faulted = circuit_row(case, fault.bus, fault.far_bus, fault.circuit)
    for a, b in fault.trips:
        if circuit_row(case, a, b) == faulted:
            raise InputError(
                f"{name} {a} {b}: {a}-{b} is the faulted circuit itself (line "
                f"{fault.bus}-{fault.far_bus} circuit {fault.circuit}, which the fault's "
                "clearing opens); to open both circuits fault circuit 2 and trip circuit 1"
            )


def _lattice(k: int, tol: float) -> float:
    """Clearing time k*tol (s), rounded to 1e-12 s so that printed values are exact."""
    return round(k * tol, 12)


def _lattice_bounds(tol, t_lo, t_hi, t_max) -> tuple[int, int, int]:
    """Lattice indices: t_lo rounded down, t_hi up, t_max down (within 1e-9 of a cell)."""
    k_lo = math.floor(t_lo / tol + 1e-9)
    k_max = math.floor(t_max / tol + 1e-9)
    k_hi = min(max(math.ceil(t_hi / tol - 1e-9), k_lo + 1), k_max)
    if k_hi <= k_lo:
        raise InputError(
            f"CCT search range {t_lo:g}-{t_max:g} s is narrower than the tolerance {tol:g} s"
        )
    return k_lo, k_hi, k_max


def _bracket(probe, k_lo, k_hi, k_max, fault: LineFault, tol, freq) -> tuple[int, int]:
    """Check stable at k_lo, then double k_hi (up to k_max) until it is unstable."""
    stable_at = probe.stable_at
    if not stable_at(k_lo):
        _lower_bound_unstable(
            k_lo, fault, tol, functools.partial(_window_stable, probe), k_max, freq
        )
    while stable_at(k_hi):
        if k_hi == k_max:
            _above_limit(k_max, fault, tol, freq)
        k_lo, k_hi = k_hi, min(2 * k_hi, k_max)
    return k_lo, k_hi


#: clearing times (cycles) a fault unstable when cleared at once is also run at, so that
#: its N-1 insecure verdict names a stable window above (Kundur's 3-4, whose trip islands
#: bus 4: unstable cleared at once or after 6 cycles, stable after 1 to 3)
INSECURE_WINDOW_CYCLES = (1, 2, 3, 6)


def _lower_bound_unstable(k_lo: int, fault: LineFault, tol, stable_at=None, k_max=0, freq=60.0):
    """Raise for a search whose lower bound is unstable: InsecureContingency at 0, naming
    the clearing times of INSECURE_WINDOW_CYCLES (below the search limit k_max) at which
    the fault is stable all the same (a verdict not monotone in the clearing time;
    `stable_at` runs them)."""
    if k_lo == 0:
        window = []
        if stable_at is not None:
            cells = sorted({round(c / freq / tol) for c in INSECURE_WINDOW_CYCLES})
            window = [k for k in cells if 0 < k < k_max and _said_stable(stable_at, k)]
        also = ""
        if window:
            at = ", ".join(f"{_lattice(k, tol):g}" for k in window)
            also = (
                f"; yet stable when cleared at {at} s: a verdict not monotone in the "
                "clearing time (simulate those clearings to see it)"
            )
        raise InsecureContingency(
            f"{fault.describe()}: unstable even when cleared instantly "
            "(the line trip alone loses synchronism, or leaves no machine in service): "
            f"N-1 insecure, CCT 0{also}"
        )
    raise InputError(
        f"{fault.describe()}: unstable already at the lower bound "
        f"{_lattice(k_lo, tol):g} s; lower it"
    )


def _said_stable(stable_at, k: int) -> bool:
    """`stable_at(k)`, a run that fails (the fault on beyond what the model solves) taken
    as not stable: the insecure window's runs only inform its verdict, never replace it
    with a failure."""
    try:
        return stable_at(k)
    except SimulationError:
        return False


def _above_limit(k_max: int, fault: LineFault, tol, freq):
    """Raise AboveSearchLimit: still stable at the search limit."""
    t = _lattice(k_max, tol)
    raise AboveSearchLimit(
        f"{fault.describe()}: the CCT is above the search limit t_max = {t:g} s "
        f"({t * freq:.4g} cycles): still stable when cleared there"
    )


def _outcome(fault: LineFault, t_clear: float, call) -> tuple[SimulationResult, bool]:
    """One probe's run, ``call()`` (its SimulationResult): (result, diverged).  A run that
    diverged after a machine separated, or whose network has no solution after the fault
    is cleared (voltage collapse), gives its partial result and True (unstable); a failure
    while the fault is on is raised, naming the fault and the clearing time (the model's
    limit, not a verdict)."""
    try:
        return call(), False
    except NumericalInstabilityError as exc:
        raise NumericalInstabilityError(
            f"{fault.describe()}, cleared after {t_clear:g} s: {exc}", result=exc.result
        ) from exc
    except SimulationError as exc:
        res = exc.result
        t = getattr(res, "t", None)
        cleared = t is not None and len(t) > 0 and t[-1] >= fault.t_fault + t_clear
        if res is not None and (not res.stable or cleared):
            res.meta["diverged"] = str(exc)  # what ended it (`CCTResult.unstable_end_failure`)
            return res, True
        raise SimulationError(
            f"{fault.describe()}, cleared after {t_clear:g} s: {exc}", result=exc.result
        ) from exc


def fault_on_failure(sim, fault: LineFault, t_on: float) -> str | None:
    """Why a fault cannot be simulated without storage while it is on, or None.

    One run with the fault on for ``t_on`` s (the longest a CCT search up to that limit
    holds it on), up to its clearing: every shorter clearing shares this run's faulted
    stretch, so a search's probe can fail while the fault is on (its model's limit, e.g.
    a current source beside a bolted fault: `stabctl.network.solution`) only if this run
    does.  A run whose machines separate first, or that fails after they did, is
    simulable (its probes are unstable, `_outcome`).

    Parameters
    ----------
    sim : Simulator
    fault : LineFault
    t_on : float
        How long the fault is on, s (> 0).

    Returns
    -------
    str or None
        The failure's message, naming the fault; None when the run reaches the clearing.
    """
    t_end = fault.t_fault + t_on + sim.default_h
    try:
        with warnings.catch_warnings():  # the fault held on to its clearing, on purpose
            warnings.filterwarnings("ignore", "run ends at .* still on", RuntimeWarning)
            _outcome(
                fault, t_on, lambda: sim.run(fault.events(t_on), t_end, stop_at_separation=True)
            )
    except SimulationError as exc:
        return str(exc)
    return None


# -- CCT sweeps (jobs for stabctl.parallel) -------------------------------------------------


def storage_fleet(case, esd_pct: float | None):
    """:func:`stabctl.storage.uniform_fleet` of ``esd_pct`` % at every generator's HV bus,
    or None for no storage (``esd_pct`` None)."""
    if esd_pct is None:
        return None
    from stabctl.storage import devices as storage

    return storage.uniform_fleet(case, esd_pct)


def require_case_name(value, name: str) -> None:
    """Refuse a sweep's case that is not a name or a path: its jobs load the case in each
    worker by name, so a loaded `Case` cannot be given (it was refused as "load_case
    (name_or_path): ...", naming a function the caller never called).

    Parameters
    ----------
    value : object
        What was given.
    name : str
        The argument, as the message names it (``"screen(case_name)"``).

    Raises
    ------
    WrongTypeError
        `value` not a str or os.PathLike.
    """
    if not isinstance(value, (str, os.PathLike)):
        raise WrongTypeError(
            f"{name}: a built-in case name or a case file's path (each job loads it in its "
            f"worker), got {type(value).__name__}; give the name or file the case was loaded "
            "from"
        )


def job_case(case_name: str, digest: str | None = None) -> Case:
    """The case a job names, read where the job runs (once per process and content,
    `_read_case`), and checked to be the one its client read (the digest of its content,
    `stabctl.case.Case.digest`, that the client put in the job): a relative path read by
    a Dask worker in another working directory is another file, or none; a file edited
    since the client read it is another content.

    Parameters
    ----------
    case_name : str
        A built-in case name or case file (`stabctl.io.load_case`).
    digest : str or None, optional
        The client's digest of it; None: not checked.

    Returns
    -------
    Case

    Raises
    ------
    UnsharedCaseError
        With a digest: the case cannot be read here, or its content is not the client's
        (naming this host and working directory).
    CaseError
        Without one: as `stabctl.io.load_case`.
    """
    return _checked_case(_identity(case_name), case_name, digest)


def _checked_case(identity: tuple, case_name: str, digest: str | None) -> Case:
    """`job_case` of the case read as `identity` (`_identity`, asked once by the caller)."""
    try:
        case = _read_case(identity, case_name)
    except CaseError as exc:
        if digest is None:
            raise
        raise _unshared(case_name, f"cannot be read on the worker {{where}}: {exc}") from None
    if digest is not None and (here := _digest(identity, case)) != digest:
        raise _unshared(
            case_name,
            f"on the worker {{where}} is not the client's: its content differs (digest {here} "
            f"there, {digest} on the client: another file of that name, or the file changed "
            "since the client read it)",
        )
    return case


def _unshared(case_name: str, what: str) -> UnsharedCaseError:
    """The error of a job whose case is not its client's here (`what`: with ``{where}``,
    this host, pid and working directory, asked only then)."""
    where = f"{socket.gethostname()} (pid {os.getpid()}, working directory {os.getcwd()})"
    return UnsharedCaseError(
        f"case '{case_name}' {what.replace('{where}', where)}; the job was not run; give the case "
        "as a built-in name or an absolute path to a file every worker reads the same"
    )


def _identity(case_name: str) -> tuple:
    """Which case a name reads in this process now: a file's absolute path, modification
    time and size (a relative name asked in another folder, or a file edited since it was
    read, is another case: read again), else the name (a built-in case)."""
    try:
        st = os.stat(case_name)
    except (OSError, ValueError):
        return (case_name,)
    return (os.path.abspath(case_name), st.st_mtime_ns, st.st_size)


@functools.lru_cache(maxsize=8)
def _read_case(identity: tuple, case_name: str) -> Case:
    """`stabctl.io.load_case` of `case_name`, once per `_identity`."""
    from stabctl.io import load_case

    return load_case(case_name)


@functools.lru_cache(maxsize=8)
def _digest(identity: tuple, case: Case) -> str:
    """`case.digest()` once per `_identity` (3 ms for ACTIVSg2000, asked by every job)."""
    return case.digest()


def cached_simulator(
    case_name: str,
    model: ModelOptions = ModelOptions(),
    load: float = 1.0,
    digest: str | None = None,
) -> Simulator:
    """One Simulator per case (a file by its absolute path, time and size: `_identity`),
    model settings and load level per process (the power flow is solved once per
    worker).

    Parameters
    ----------
    case_name : str
        A built-in case name or case file (`stabctl.io.load_case`).
    model : ModelOptions, optional
        Conventions, step (None: the default) and power-flow Q limits.
    load : float, optional
        Fraction of the base load (`stabctl.network.powerflow.scale_load`: loads and
        dispatch scaled, power flow re-solved).
    digest : str or None, optional
        The digest of the case the job's client read (a worker's job, `job_case`); None:
        not checked.

    Returns
    -------
    Simulator

    Raises
    ------
    PowerFlowError, CaseError
        The scaled case has no power flow or no valid initial state (naming the load
        level).
    UnsharedCaseError
        The case read here is not the client's (`job_case`).
    """
    identity = _identity(case_name)
    _checked_case(identity, case_name, digest)  # read (once), checked with a digest
    return _simulator(identity, case_name, model, float(load))


#: simulators a process keeps (`cached_simulator`): a plan's load levels of one case
SIMULATORS_KEPT = 64


@functools.lru_cache(maxsize=SIMULATORS_KEPT)
def _simulator(identity: tuple, case_name: str, model: ModelOptions, load: float) -> Simulator:
    """`cached_simulator`'s Simulator of the case read as `identity`."""
    from stabctl.network.powerflow import scale_load

    case = _read_case(identity, case_name)
    if load == 1.0:
        return model.simulator(case)
    scaled = scale_load(case, load, q_limits=model.q_limits)
    try:
        return model.simulator(scaled)
    except CaseError as exc:
        raise CaseError(f"load level {load:g} of case '{case_name}': {exc}") from None


def compile_here(case_name: str, model: ModelOptions = ModelOptions()) -> None:
    """Compile the simulator's kernels in this process (a 0.1 s run of the case) unless
    they are cached (`stabctl.dynamics.driver.simulator_cached`), so that the workers a sweep
    starts next load them instead of each compiling them at the same time, silently.

    Parameters
    ----------
    case_name : str
    model : ModelOptions, optional
        As `cached_simulator` (the run's simulator is kept there).
    """
    from stabctl.dynamics.driver import simulator_cached

    if not simulator_cached():
        cached_simulator(case_name, model).run((), t_end=0.1)


def fault_of_inputs(inputs) -> LineFault:
    """The fault recorded in a sweep job's inputs (bus, far_bus, t_fault, circuit, trips;
    `fault_inputs`)."""
    far = inputs["far_bus"]
    return LineFault(
        int(inputs["bus"]),
        None if far is None else int(far),
        float(inputs.get("t_fault", 1.0)),
        int(inputs.get("circuit", 1)),
        tuple((int(a), int(b)) for a, b in inputs.get("trips", ())),
    )


def fault_inputs(fault: LineFault) -> dict:
    """A fault as a sweep job records it (`fault_of_inputs` reads it back)."""
    return {
        "bus": fault.bus,
        "far_bus": fault.far_bus,
        "t_fault": fault.t_fault,
        "circuit": fault.circuit,
        "trips": [list(t) for t in fault.trips],
    }


def cct_job(inputs: dict) -> dict:
    """Worker entry of a CCT sweep: the CCT of one fault at one storage rating, with its
    numerical error bar (unless error_check is off, e.g. a coarse screening).

    Parameters
    ----------
    inputs : dict
        The job's JSON-able recorded inputs (`cct_jobs`): case and case_digest (the
        client's, `job_case`); the fault (bus, far_bus, t_fault, circuit, trips);
        esd_pct (storage rating in %, None = no storage); the search settings
        (`SearchOptions.to_inputs`) and model settings (`ModelOptions.to_inputs`).

    Returns
    -------
    dict
        `CCTResult.to_dict()`.

    Raises
    ------
    InputError, SimulationError
        As `critical_clearing_time` and `storage_fleet`.
    """
    model = ModelOptions.from_inputs(inputs)
    sim = cached_simulator(inputs["case"], model, digest=inputs.get("case_digest"))
    return searched_job(sim, inputs, storage_fleet(sim.case, inputs.get("esd_pct")))


def searched_job(sim, inputs: dict, storage, **own) -> dict:
    """A sweep job's CCT search (`cct_job`, `stabctl.studies.sweeps.controlled_cct_job`):
    `CCTResult.to_dict()` with the rating it answers (``esd_pct``) and `own` (the
    controller, the devices' model), which a resumed sweep checks against the record's
    inputs (`_REPEATED`); a verdict (robust, N-1 insecure) raised with the same and its
    fault (`stabctl.parallel.run_job` records them)."""
    fault = fault_of_inputs(inputs)
    searched = {"esd_pct": inputs.get("esd_pct"), **own}
    try:
        res = critical_clearing_time(sim, fault, SearchOptions.from_inputs(inputs), storage=storage)
    except Verdict as exc:
        exc.searched = {"fault": _fault_dict(fault), **searched}
        raise
    return {**res.to_dict(), **searched}


def cct_record_problem(rec: dict) -> str | None:
    """The schema of a CCT sweep's records (`cct_job`, `stabctl.parallel.Job.check`):
    what makes a record one no CCT search can have written, or None.

    A search's guess (``inputs.guess_s``, `SearchOptions.guess_s`) is a clearing time within
    [0, t_max].  A CCT found holds its CCT and the unstable end of its bracket as finite
    clearing times with 0 <= cct_s < t_unstable_s <= the search's limit t_max (of the
    record's inputs; `T_MAX` without one), the CCT in cycles, the numerical error (None or
    >= 0), the number of simulations (an integer >= 1) and the separated machines (a list of
    machine numbers); a verdict is one a search gives (`AboveSearchLimit`,
    `InsecureContingency`), its number of simulations, if any, an integer >= 1; an
    islanding log (``islanded``, of a CCT or a verdict) is a list of stages, each with its
    buses (and machines) as lists of numbers.  The kinds of the fields of any record (an
    object as result, texts as verdict and error) are checked before (`stabctl.parallel`).

    Parameters
    ----------
    rec : dict
        A sweep record of a CCT job (status ok, verdict or failed).

    Returns
    -------
    str or None
        What is wrong, naming the field and its value; None for a record a search can
        have written.
    """
    from stabctl.parallel import is_number, shown

    given = (rec.get("inputs") or {}).get("t_max", T_MAX)
    if not (is_number(given) and given > 0):
        return f"inputs.t_max {shown(given)} is not a time in s"
    guess = (rec.get("inputs") or {}).get("guess_s")
    if guess is not None and not (is_number(guess) and 0 <= guess <= given):
        return f"inputs.guess_s {shown(guess)} is not a clearing time in [0, {given:g}] s"
    t_max = given
    slack = 1e-9 * max(1.0, t_max)  # the bracket's rounding
    status = rec["status"]
    if status == "verdict" and rec["verdict"] not in (
        AboveSearchLimit.label,
        InsecureContingency.label,
    ):
        return (
            f"verdict {shown(rec['verdict'])} is none of a CCT search's "
            f"({AboveSearchLimit.label!r}, {InsecureContingency.label!r})"
        )
    if status == "verdict" and "n_simulations" in rec and not _count(rec["n_simulations"]):
        return f"n_simulations {shown(rec['n_simulations'])} is not a count >= 1"
    r: dict = rec["result"] if status == "ok" else {}
    if status == "ok":
        cct, t_u = r.get("cct_s"), r.get("t_unstable_s")
        if not (is_number(cct) and 0 <= cct <= t_max + slack):
            return f"result.cct_s {shown(cct)} is not a clearing time in [0, {t_max:g}] s"
        if not (is_number(t_u) and cct < t_u <= t_max + slack):
            return (
                f"result.t_unstable_s {shown(t_u)} is not a clearing time in ({cct:g}, {t_max:g}] s"
            )
        for name in ("cct_cycles", "t_stable_s", "numerical_error_s", "cct_half_step_s"):
            v = r.get(name)
            if v is not None and not (is_number(v) and v >= 0):
                return f"result.{name} {shown(v)} is not a number >= 0"
        if "cct_cycles" not in r:
            return "result without cct_cycles"
        n = r.get("n_simulations")
        if not _count(n):
            return f"result.n_simulations {shown(n)} is not a count >= 1"
        if not _numbers(r.get("separated_machines")):
            return (
                f"result.separated_machines {shown(r.get('separated_machines'))} is not a "
                "list of machine numbers"
            )
        if other := _unlike_its_bracket(r, slack):
            return other
    ended = r if status == "ok" else rec
    where = "result." if status == "ok" else ""
    if status != "failed" and (other := _other_search(rec.get("inputs") or {}, ended, where)):
        return other
    concerns, t_end = ended.get("end_concerns"), ended.get("end_t_s")
    if concerns is not None and not (
        isinstance(concerns, list) and all(isinstance(c, str) for c in concerns)
    ):
        return f"end_concerns {shown(concerns)} is not a list of phrases"
    if concerns and not (is_number(t_end) and t_end >= 0):
        return f"end_t_s {shown(t_end)} is not a time in s"
    islanded = r.get("islanded") if status == "ok" else rec.get("islanded")
    if islanded is not None and not (
        isinstance(islanded, list)
        and all(
            isinstance(e, dict)
            and _numbers(e.get("buses"))
            and ("machines" not in e or _numbers(e["machines"]))
            for e in islanded
        )
    ):
        field = "result.islanded" if status == "ok" else "islanded"
        return f"{field} {shown(islanded)} is not a list of islanding stages with their buses"
    return None


def _unlike_its_bracket(r: dict, slack: float) -> str | None:
    """What of a CCT result `r` (its numbers checked) disagrees with its own bracket, or
    None: its t_stable_s and cct_s differ, its bracket is not tol_s wide, its cycles are
    not its seconds at the frequency its unstable end gives (rounded to 0.01 cycle), or
    its probes lack a stable run at its CCT or an unstable one at its unstable end (a
    record edited by hand: a search writes them together, `CCTResult.to_dict`).  A field
    a record of older code lacks is not compared."""
    from stabctl.parallel import is_number

    cct, t_u, tol = r["cct_s"], r["t_unstable_s"], r.get("tol_s")
    t_s = r.get("t_stable_s")
    if t_s is not None and abs(t_s - cct) > slack:
        return f"result.cct_s {cct!r} is not its t_stable_s {t_s!r}"
    if is_number(tol) and abs(t_u - cct - tol) > slack:
        return f"result bracket {cct!r}-{t_u!r} s is not its tol_s {tol!r} wide"
    u_cycles = r.get("t_unstable_cycles")
    if is_number(u_cycles) and abs(r["cct_cycles"] - cct * u_cycles / t_u) > 0.005 + slack:
        return (
            f"result.cct_cycles {r['cct_cycles']!r} is not its cct_s {cct!r} at "
            f"{u_cycles / t_u:g} Hz (its t_unstable_cycles)"
        )
    probes = r.get("probes")
    if isinstance(probes, list) and probes:
        ran = [p for p in probes if isinstance(p, list) and len(p) == 2 and is_number(p[0])]
        for t, ok, end in ((cct, True, "stable"), (t_u, False, "unstable")):
            if not any(abs(p[0] - t) <= slack and p[1] is ok for p in ran):
                return f"result.probes have no {end} run at {t!r} s, the bracket's {end} end"
    return None


#: a CCT result's (or a verdict record's) fields that repeat its job's inputs (its name,
#: the inputs' name)
_REPEATED = (
    ("esd_pct", "esd_pct"),
    ("controller", "controller"),
    ("esd_model", "esd_model"),
    ("fault.bus", "bus"),
    ("fault.far_bus", "far_bus"),
    ("fault.circuit", "circuit"),
    ("fault.t_fault_s", "t_fault"),
    ("tol_s", "tol"),
    ("t_max_s", "t_max"),
)


def _other_search(inputs: dict, r: dict, where: str) -> str | None:
    """What of a CCT result (or a verdict record) `r` says it answers other inputs than
    its record's (a record relabelled or edited by hand: another fault's CCT or verdict
    shown as this one's, another storage rating's, a 20 ms bracket taken for a 10 ms
    search), or None; `where` prefixes the fields' names (``"result."``).  A field a
    record of older code lacks is not compared."""
    for name, given in _REPEATED:
        head, _, tail = name.partition(".")
        value = (r.get(head) or {}).get(tail, _ABSENT) if tail else r.get(head, _ABSENT)
        if name == "fault.circuit" and value is None and inputs.get("far_bus") is None:
            continue  # a bus fault's: none in its result, 1 in its job's inputs
        if given in inputs and value is not _ABSENT and value != inputs[given]:
            return (
                f"{where}{name} {value!r} is not the record's inputs.{given} "
                f"{inputs[given]!r}: the answer of another search"
            )
    return None


def _count(n) -> bool:
    """Whether a record's value is a count of runs (an integer >= 1)."""
    return isinstance(n, int) and not isinstance(n, bool) and n >= 1


def _numbers(v) -> bool:
    """Whether a record's value is a list of integers (bus or machine numbers)."""
    return isinstance(v, list) and all(isinstance(x, int) and not isinstance(x, bool) for x in v)


def cct_key(
    case: str, fault: LineFault, esd_pct: float | None, model: ModelOptions = ModelOptions()
) -> str:
    """Sweep key, e.g. 'kundur/3-101/t1/esd-none' or 'kundur/3-101#2+13-101/t1/esd20';
    '/pstess', '/h<step>' and '/no-q-limits' are appended for the pstess conventions, a
    given step and a power flow without PV Q limits (`ModelOptions.key_suffix`)."""
    line = (
        f"bus{fault.bus}"
        if fault.far_bus is None
        else f"{fault.bus}-{fault.far_bus}" + (f"#{fault.circuit}" if fault.circuit != 1 else "")
    )
    line += "".join(f"+{a}-{b}" for a, b in fault.trips)
    rating = "none" if esd_pct is None else f"{esd_pct:g}"
    return (
        f"{case}/{line}/t{fault.t_fault:g}/esd{'-' if esd_pct is None else ''}{rating}"
        f"{model.key_suffix()}"
    )


def cct_jobs(
    case_name: str,
    faults,
    ratings=(None,),
    *,
    search: SearchOptions = SearchOptions(),
    model: ModelOptions = ModelOptions(),
) -> list:
    """One `stabctl.parallel.Job` per (fault, storage rating %, None = no storage) pair.

    Each job's inputs record the case, the digest of its content (``case_digest``,
    `stabctl.case.Case.digest`: a sweep resumed after the case file changed is refused,
    `stabctl.parallel.check_records_case`), the fault, the rating, the search settings
    (`SearchOptions.to_inputs`: error_check only when off) and the model settings
    (`ModelOptions.to_inputs`: q_limits only when off).

    Checks the search settings (`check_search_range`: InputError), the ratings (each
    None or in (0, 100] %, each once: InputError, WrongTypeError), every fault's bus and
    line against the case (UnknownBusError, CaseError) and its run end (`check_run_end`)
    first so that bad input fails before any job runs, then compiles the simulator's
    kernels in this process if they are not cached (`compile_here`).
    """
    from stabctl.dynamics.events import validate
    from stabctl.parallel import Job

    check_search_range(search)
    require_case_name(case_name, "cct_jobs(case_name)")
    ratings = checked_ratings(ratings)
    case = job_case(case_name)  # the content its jobs run on in this process, and digest
    faults = list(faults)
    for f in faults:
        validate(case, f.events(0.0), 0.0)
        check_run_end(f, search)
    recorded = search.to_inputs()  # the records' field order, kept since v0.1:
    checked = {"error_check": recorded.pop("error_check")} if "error_check" in recorded else {}
    settings = {**recorded, **model.to_inputs(), **checked}
    compile_here(case_name, model)
    digest = case.digest()
    return [
        Job(
            key=cct_key(case_name, f, p, model),
            func=cct_job,
            check=cct_record_problem,
            compared=compared_inputs,
            inputs={
                "case": case_name,
                "case_digest": digest,
                **fault_inputs(f),
                "esd_pct": p,
                **settings,
            },
        )
        for f in faults
        for p in ratings
    ]


def checked_ratings(ratings, name: str = "cct_jobs(ratings)", none: bool = True) -> list:
    """Storage ratings of a sweep, checked: each a number in (0, MAX_ESD_PCT] % (or None,
    no storage, where `none`), each once (``"5"`` failed in a format, ``nan`` and ``-5``
    were recorded as jobs, ``True`` ran as 1 %).

    Parameters
    ----------
    ratings : sequence of float or None
        The ratings, % of each generator's MVA.
    name : str, optional
        The argument, as messages name it.
    none : bool, optional
        Whether None (no storage) is one.

    Returns
    -------
    list of float or None

    Raises
    ------
    WrongTypeError
        Not a list, or an item not a number (nor None where `none`).
    InputError
        No rating, one out of range, or one given twice.
    """
    from stabctl.storage.devices import MAX_ESD_PCT

    what = "a number of % or None" if none else "a number of %"
    items = require_items(ratings, name, f"a list of ratings ({what})")
    if not items:
        raise InputError(f"{name}: no rating given" + (" ([None]: no storage)" if none else ""))
    out: list[float | None] = []
    for p in items:
        if not (is_number(p) or (none and p is None)):
            raise WrongTypeError(f"{name}: a rating is {what}, got {p!r} ({type(p).__name__})")
        p = None if p is None else float(p)
        if p is not None and not 0 < p <= MAX_ESD_PCT:
            raise InputError(
                f"{name}: a rating must be in (0, {MAX_ESD_PCT:g}] % of machine MVA, got {p:g}"
                + (" (None: no storage)" if none else "")
            )
        if p in out:
            raise InputError(f"{name}: rating {p:g} given twice")
        out.append(p)
    return out


def compared_inputs(inputs: dict) -> dict:
    """A CCT job's recorded inputs as a resumed sweep compares them (`Job.compared` of
    `stabctl.parallel`): t_end None (the default run end) read as the run end it stands
    for, the fault time + T_AFTER_FAULT, so that records made without --tf and a rerun
    with that same --tf (or the reverse) are the same job; a guess (``guess_s``,
    `SearchOptions.guess_s`) left out, as it only sets where the search starts.

    Parameters
    ----------
    inputs : dict
        The inputs (`cct_jobs`), as they read back from a records file.

    Returns
    -------
    dict
        A copy, t_end the effective run end (s, rounded to 1e-9 s) where the fault time
        is a number, without guess_s.
    """
    out = dict(inputs)
    out.pop("guess_s", None)
    t_fault, t_end = out.get("t_fault", 1.0), out.get("t_end")
    if isinstance(t_fault, (int, float)) and not isinstance(t_fault, bool):
        if t_end is None:
            t_end = t_fault + T_AFTER_FAULT
        if isinstance(t_end, (int, float)) and not isinstance(t_end, bool):
            out["t_end"] = round(float(t_end), 9)
    return out


#: the columns of a fault list (`read_faults`): required, then optional; the last three
#: are a contingency's own clearing requirement, read by `stabctl place`
#: (`stabctl.placement.requirements.read_requirements`)
FAULT_COLUMNS = (
    ("bus", "far_bus"),
    ("t_fault", "circuit", "required_clearing_cycles", "target_cct_gain", "target_cct_s"),
)
#: latest fault start a run takes, s (the CLI's --t-fault range)
T_FAULT_MAX_S = 1000.0


def read_faults(path: str | Path) -> list[LineFault]:
    """Faults from a CSV file (a strict table, `stabctl.io.inputs.iter_csv`, of
    :data:`FAULT_COLUMNS`): bus, far_bus (empty: a bus fault cleared without a trip)
    [, t_fault (s, default 1, at most T_FAULT_MAX_S)][, circuit (default 1; empty in a
    bus fault's row)], one fault per row; an empty t_fault or circuit cell takes the
    default, as without the column.

    Raises
    ------
    InputError
        A row or header the table refuses, a value out of range, a circuit given for a
        bus fault, a line from a bus to itself, a fault listed twice; naming file:line.
    """
    return [fault for fault, _ in read_fault_rows(path)]


def read_fault_rows(path: str | Path) -> list[tuple[LineFault, int]]:
    """`read_faults` with the line of each fault, for messages about a fault that name
    its ``file:line`` (a bus or line the case lacks).  The file is read a row at a time,
    up to its first error; only the faults are kept.

    Parameters
    ----------
    path : str or pathlib.Path
        The fault list.

    Returns
    -------
    list of (LineFault, int)
        In file order: each fault and its line in the file (1-based).

    Raises
    ------
    InputError
        As `read_faults`.
    """
    faults: dict[LineFault, int] = {}
    for row in iter_csv(path, "fault list", *FAULT_COLUMNS):
        fault = _fault_row(row)
        if fault in faults:
            name = f"{fault.bus}" if fault.far_bus is None else f"{fault.bus}-{fault.far_bus}"
            raise InputError(
                f"{row.where()}: fault {name} listed twice (first at line "
                f"{faults[fault]}; each fault once)"
            )
        faults[fault] = row.line
    return list(faults.items())


def _fault_row(row: CsvRow) -> LineFault:
    far = row.values["far_bus"]
    if not far and row.values.get("circuit"):
        raise InputError(
            f"{row.where()}: circuit {row.values['circuit']} given for a bus fault (far_bus "
            "empty): a circuit names a line; give its far_bus, or leave circuit empty"
        )
    bus = int(number(row, "bus", 1, _LARGEST_BUS, integer=True))
    far_bus = int(number(row, "far_bus", 1, _LARGEST_BUS, integer=True)) if far else None
    if far_bus == bus:
        raise InputError(
            f"{row.where()}: far_bus {far} is the fault's bus: a line joins two buses; give "
            "the line's other end, or leave far_bus empty for a bus fault"
        )
    return LineFault(
        bus=bus,
        far_bus=far_bus,
        t_fault=number(row, "t_fault", 0.0, T_FAULT_MAX_S, default=1.0),
        circuit=int(number(row, "circuit", 1, 999, integer=True, default=1)),
    )


_LARGEST_BUS = 2**31 - 1  # bus numbers are int32 in the tables
