"""Simulation-based evaluation of a contingency at an ESD allocation: its CCT and the
gradient of that CCT in the rating of every candidate site (docs/placement.md, section 3).

The CCT comes from `stabctl.stability.cct.critical_clearing_time` (bisection), with storage after a
scan for the first unstable clearing time (`scanned_cct`); the gradient from the run
cleared just beyond it (SIME, `stabctl.stability.sime`):

    d CCT / d P_j = - (d eta / d P_j) / (d eta / d t_clear)     (s/MW)

where eta is the SIME unstable margin, d eta / d P_j its first-order change from the
trajectory (`sime.storage_integrals`, weights `OmibEquivalent.group_weights`) and
d eta / d t_clear a difference over `EPS_S` of clearing time (a second run).  Evaluations
are JSON-able jobs run in parallel worker processes (`stabctl.parallel.worker_pool`, `verify`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from stabctl.dynamics.coi import machine_inertia
from stabctl.dynamics.options import ModelOptions
from stabctl.errors import AboveSearchLimit, InputError, InsecureContingency, SimulationError
from stabctl.placement.program import CCTCut
from stabctl.stability.cct import (
    T_AFTER_FAULT,
    LineFault,
    SearchOptions,
    cached_simulator,
    critical_clearing_time,
    fault_inputs,
    fault_of_inputs,
    fault_on_failure,
    run_end_check,
)
from stabctl.stability.sime import (
    clearing_energy_rate,
    critical_machines,
    device_modes,
    omib_equivalent,
    storage_integrals,
    unstable_margin,
    unstable_point,
)
from stabctl.storage.control import BangBangCOI
from stabctl.storage.devices import StorageDevice, StorageFleet, model_inputs

EPS_S = 0.005  # clearing-time step of d eta / d t_clear (s)
SCAN_S = 0.005  # clearing-time grid of the first-unstable scan (s)


@dataclass(frozen=True)
class Contingency:
    """A fault (`LineFault`, cleared at both ends, line tripped, plus its trips), the CCT
    it must reach (s after the fault start) and the load level it is simulated at
    (fraction of the base load, `stabctl.network.powerflow.scale_load`; default 1)."""

    fault: LineFault
    target_cct_s: float
    load: float = 1.0

    @property
    def fault_name(self) -> str:
        """The fault's short name (e.g. ``83-33``), without the load level."""
        f = self.fault
        where = f"{f.bus}" if f.far_bus is None else f"{f.bus}-{f.far_bus}"
        return (
            where
            + (f"#{f.circuit}" if f.circuit != 1 else "")
            + "".join(f"+{a}-{b}" for a, b in f.trips)
        )

    @property
    def name(self) -> str:
        """Unique name: the fault's, with ``@<load> %`` when not at the base load."""
        return self.fault_name + ("" if self.load == 1.0 else f"@{100 * self.load:g}%")

    def describe(self) -> str:
        """How messages name it: ``contingency 3-101 (fault at bus 3 on line 3-101 at 1
        s, load 90 % of the base)``, the load only when not the base load."""
        load = "" if self.load == 1.0 else f", load {100 * self.load:g} % of the base"
        return f"contingency {self.name} ({self.fault.describe()}{load})"

    def met_by(self, cct_s: float | None) -> bool:
        """Whether a CCT (s; None: not known) reaches the target, within 1e-9 s (the
        lattice's rounding)."""
        return cct_s is not None and cct_s >= self.target_cct_s - TARGET_SLACK_S


#: slack of `Contingency.met_by`, s: a CCT on the 1 ms lattice equal to its target counts
TARGET_SLACK_S = 1e-9


# -- one contingency at one allocation (runs in a worker) ------------------------------


def evaluate(job: dict) -> dict:
    """CCT of one contingency with ESDs and the gradient of that CCT in the rating of
    every candidate site (a worker job of `verify`; JSON-able in and out).

    Parameters
    ----------
    job : dict
        case (str) and case_digest (the client's, optional: `job_simulator`); fault
        (`fault_inputs`); devices ([bus, machine, MW] each); sites
        ([bus, machine] each); beta (distribution factors, n_mac x n_sites,
        `sime.distribution_factors`); controller (BangBangCOI fields); tol, t_max (s, the
        search); conventions, h (model conventions and step, None: the default); load
        (load level, `cached_simulator`, default 1).  Optional: scan_from, scan_to,
        scan_s (without scan_from the CCT is the bisection of `stabctl.stability.cct`;
        with it `scanned_cct`: the first unstable clearing time on a scan_s grid from
        scan_from up to scan_to, then bisection); eps_s (the gradient's clearing-time
        difference); bracket ([stable, unstable] clearing times, s, known from a coarser
        search of the same fault and fleet, e.g. the screening: the bisection starts
        there, both ends simulated again; a stable end found unstable falls back to the
        bisection from 0, an unstable end found stable is pushed up as
        `critical_clearing_time` does); check_s (a required clearing time, s: the run
        cleared there is also simulated, `check`); gradient (False: a CCT only, the
        gradient zero); insecure_verdict (True: a fault N-1 insecure, unstable even when
        cleared at once, is returned as a verdict instead of raised).

    Returns
    -------
    dict
        {"cct_s", "t_unstable_s", "n_simulations", "separated", "critical", "margin",
        "dmargin_dtc", "gradient_s_per_mw" (n_sites,), "above_t_max", "run_end_check"
        (the CCT search's check of its run's end, `CCTResult.to_dict`'s: None, or
        {"t_end_s", "t_separation_s"} when its unstable end separated late in its run),
        "islanded" (the search's islanding log, `CCTResult.islanded`: the buses and
        machines the fault's trip cuts off, [] if none)}
        and with check_s the keys of `check`; a CCT above t_max is returned as t_max with
        a zero gradient.  With insecure_verdict, an N-1 insecure fault gives
        {"n1_insecure" (the verdict's message), "cct_s" 0, "n_simulations", "islanded"}.
        Runs repeated within one evaluation (the scan's and the bisection's bracket
        ends, the gradient's run beyond the CCT) are simulated once (`_Memo`);
        n_simulations counts the runs simulated.

    Raises
    ------
    InputError
        Unstable at zero clearing (`InsecureContingency`, but with insecure_verdict),
        bad fault.
    SimulationError
        The network fails while the fault is on.
    """
    sim = _Memo(
        job_simulator(job),
        [site[0] for site in job["sites"]],
    )
    f, sites, tol, t_max = fault_of_inputs(job["fault"]), job["sites"], job["tol"], job["t_max"]
    ctrl = _law(job, sim, f)
    fleet = _fleet(job, ctrl)
    check_s = job.get("check_s")
    checked = {} if check_s is None else _check_run(sim, f, fleet, float(check_s), sites, ctrl)
    try:
        if job.get("scan_from") is None:
            res = _bisection(sim, f, fleet, tol, t_max, job.get("bracket"))
        else:
            res, _ = scanned_cct(
                sim,
                f,
                fleet,
                tol=tol,
                t_max=t_max,
                start=job["scan_from"],
                stop=job.get("scan_to"),
                step=job.get("scan_s", SCAN_S),
            )
    except InsecureContingency as exc:
        if not job.get("insecure_verdict"):
            raise
        return {
            "n1_insecure": str(exc),
            "cct_s": 0.0,
            "n_simulations": sim.n_runs,
            "islanded": list(exc.islanded),
        }
    except AboveSearchLimit as exc:
        return {
            "islanded": list(exc.islanded),
            "cct_s": t_max,
            "t_unstable_s": None,
            "n_simulations": sim.n_runs,
            "separated": [],
            "critical": [],
            "margin": None,
            "dmargin_dtc": None,
            "above_t_max": True,
            "run_end_check": None,
            "gradient_s_per_mw": [0.0] * len(sites),
            **checked,
        }
    if not job.get("gradient", True):
        return {
            "islanded": list(res.islanded),
            "cct_s": res.cct_s,
            "t_unstable_s": res.t_unstable,
            "n_simulations": sim.n_runs,
            "separated": list(res.separated),
            "above_t_max": False,
            "run_end_check": res.to_dict()["run_end_check"],
            "critical": [],
            "margin": None,
            "dmargin_dtc": None,
            "gradient_s_per_mw": [0.0] * len(sites),
            **checked,
        }
    try:
        grad = cct_gradient(
            sim,
            f,
            res.t_unstable,
            fleet,
            sites,
            np.asarray(job["beta"]),
            ctrl,
            job.get("eps_s", EPS_S),
        )
    except NoMarginSlope:  # the margin does not fall beyond the CCT: difference the CCT
        grad = cct_difference_gradient(sim, f, job, ctrl, res)
    grad.pop("n_runs")
    return {
        "islanded": list(res.islanded),
        "cct_s": res.cct_s,
        "t_unstable_s": res.t_unstable,
        "n_simulations": sim.n_runs,
        "separated": list(res.separated),
        "above_t_max": False,
        "run_end_check": res.to_dict()["run_end_check"],
        **grad,
        **checked,
    }


def check(job: dict) -> dict:
    """One run of a fault cleared at a required clearing time with ESDs: the
    verification of that clearing time, and the energy each device (and each candidate
    site) moves over the run (a worker job; JSON-able in and out).

    Parameters
    ----------
    job : dict
        case, fault (`fault_inputs`), devices ([bus, machine, MW] each, or [bus, machine,
        MW, usable energy MJ] for a device of finite energy started half full), sites
        ([bus, machine] each), controller (BangBangCOI fields), t_clear (s after the
        fault start), conventions, h (None: the default), load (load level, default 1).

    Returns
    -------
    dict
        {"stable_at_check" (bool), "check_s", "n_simulations" (1), "energy_mj" (per
        device: [absorbed, delivered, highest, lowest state of charge relative to the
        start], MJ, as the simulator integrates them between located switchings:
        `SimulationResult.meta["storage"]`), "site_excursion_s" (per site: the largest
        state-of-charge excursion per MW of rating, s = MJ/MW, of a device at that site
        along this run's modes, `stabctl.stability.sime.device_modes`)}.

    Raises
    ------
    SimulationError
        The network fails while the fault is on.
    """
    sim = _Memo(
        job_simulator(job),
        [site[0] for site in job["sites"]],
    )
    fault = fault_of_inputs(job["fault"])
    ctrl = _law(job, sim, fault)
    fleet = _fleet(job, ctrl)
    out = _check_run(sim, fault, fleet, float(job["t_clear"]), job["sites"], ctrl)
    return {**out, "n_simulations": sim.n_runs}


def run_end(job: dict) -> dict:
    """A `check` run again T_AFTER_FAULT s longer (`stabctl.stability.cct.run_end_check`,
    one run): for a contingency whose CCT search found its unstable end separating late
    in the window the checks are judged in (a worker job; JSON-able in and out).

    Parameters
    ----------
    job : dict
        As `check`'s (case, fault, devices, sites, controller, t_clear in s after the
        fault start, conventions, h, load).

    Returns
    -------
    dict
        {"t_end_s" (the longer run's end, s), "t_separation_s" (when it separated, s, or
        None: stable there), "n_simulations" (1)}.

    Raises
    ------
    SimulationError
        The network fails while the fault is on.
    """
    sim = _Memo(job_simulator(job), [site[0] for site in job["sites"]])
    fault = fault_of_inputs(job["fault"])
    fleet = _fleet(job, _law(job, sim, fault))
    out = run_end_check(sim, fault, float(job["t_clear"]), storage=fleet)
    return {**out, "n_simulations": sim.n_runs}


def simulable(job: dict) -> dict:
    """Whether a contingency can be simulated without storage: its fault held on for the
    search limit, to its clearing (`stabctl.stability.cct.fault_on_failure`; a worker
    job, JSON-able in and out).

    Parameters
    ----------
    job : dict
        case, fault (`fault_inputs`), t_max (s: how long the fault is held on),
        conventions, h (None: the default), load (load level, default 1).

    Returns
    -------
    dict
        {"failure": the failure's message or None, "n_simulations": 1}.
    """
    sim = job_simulator(job)
    failure = fault_on_failure(sim, fault_of_inputs(job["fault"]), float(job["t_max"]))
    return {"failure": failure, "n_simulations": 1}


#: the critical groups a worker has found (`_law`), by case content (at its load level),
#: model, fault and search
_GROUPS: dict[str, tuple[int, ...]] = {}


def job_simulator(job: dict):
    """The simulator of a placement job's case (``case``, checked against the client's
    ``case_digest``: `stabctl.stability.cct.job_case`), model settings and load level."""
    model = ModelOptions.from_inputs(job)
    return cached_simulator(
        job["case"], model, load=job.get("load", 1.0), digest=job.get("case_digest")
    )


def _law(job: dict, sim, fault: LineFault) -> BangBangCOI:
    """The ESDs' law of a job (`controller_dict`).  Armed per contingency (coi
    "critical" with a ``critical_search`` instead of machines): the machines the fault
    separates when cleared just after its CCT without storage (the search of
    `critical_clearing_time` with the job's tol and t_max, on ``sim``, once per worker;
    as `stabctl cct --coi critical` finds them).  Raises InputError for a fault with no
    such group (N-1 insecure or stable up to t_max without storage)."""
    law = dict(job["controller"])
    search = law.pop("critical_search", None)
    if search is not None:
        key = repr(  # the case by content: a worker outlives an edit of its file
            (sim.case.digest(), ModelOptions.from_inputs(job), job["fault"], search)
        )
        if key not in _GROUPS:
            o = SearchOptions(tol=search["tol"], t_max=search["t_max"], error_check=False)
            try:
                _GROUPS[key] = tuple(critical_clearing_time(sim, fault, o).separated)
            except (InsecureContingency, AboveSearchLimit) as exc:
                raise InputError(
                    f"--coi critical: {fault.describe()} has no critical group without "
                    f"storage ({exc}); the law needs the machines that separate when the "
                    "fault is cleared just too late"
                ) from None
        law["critical"] = _GROUPS[key]
    return BangBangCOI(**law)


def _fleet(job: dict, ctrl) -> StorageFleet | None:
    """The storage of a job: its ``devices`` rows (bus, machine, MW[, usable MJ]) driven
    by ctrl, of its ``esd_model`` (default "ideal"); None without devices."""
    if not job["devices"]:
        return None
    devices = tuple(
        StorageDevice(
            int(d[0]), int(d[1]), float(d[2]), **({"energy_mj": float(d[3])} if len(d) > 3 else {})
        )
        for d in job["devices"]
    )
    return StorageFleet(devices, ctrl, model=job.get("esd_model", "ideal"))


def _check_run(sim, f: LineFault, fleet, t_clear: float, sites, ctrl) -> dict:
    """The run of `check` (on a `_Memo` simulator, shared with the CCT search)."""
    from stabctl.storage.devices import energy_excursion

    r = _run(sim, f, t_clear, fleet)
    energy = [
        [d["energy_absorbed_mj"], d["energy_delivered_mj"], d["soc_high_mj"], d["soc_low_mj"]]
        for d in (r.meta.get("storage", []) if fleet else [])
    ]
    per_mw = []
    if sites:
        modes = device_modes(
            r, [s[0] for s in sites], [s[1] for s in sites], ctrl, sim.case.freq_hz
        )
        for j in range(modes.shape[1]):
            e = energy_excursion(r.t, modes[:, j].astype(float))
            per_mw.append(max(e["soc_high_mj"], -e["soc_low_mj"]))
    devices = r.meta.get("storage", []) if fleet else []
    return {
        "stable_at_check": bool(r.stable),
        "check_s": t_clear,
        "energy_mj": energy,
        "site_excursion_s": per_mw,
        # switchings within CHATTER_S of the device's previous one, and the group the law
        # was armed on (coi "critical"): a plan reported neither
        "switchings": sum(d["switchings"] for d in devices),
        "chattering": sum(d["chattering"] for d in devices),
        "critical_group": list(ctrl.critical) if ctrl.coi == "critical" else None,
    }


def _bisection(sim, fault: LineFault, fleet, tol: float, t_max: float, bracket):
    """`critical_clearing_time` from 0, or from a known [stable, unstable] bracket (the
    whole search again from 0 if its stable end is not stable)."""
    if bracket is not None:
        lo, hi = (float(t) for t in bracket)
        if 0 < lo < hi <= t_max:
            try:
                return critical_clearing_time(
                    sim,
                    fault,
                    SearchOptions(tol=tol, t_lo=lo, t_hi=hi, t_max=t_max, error_check=False),
                    storage=fleet,
                )
            except InputError as exc:
                if "unstable already at the lower bound" not in str(exc):
                    raise
    return critical_clearing_time(
        sim, fault, SearchOptions(tol=tol, t_max=t_max, error_check=False), storage=fleet
    )


class _Memo:
    """A Simulator whose `run` simulates each distinct call once (events, end, step,
    separation settings, fleet) and counts the runs simulated (`n_runs`); a run that
    raised is not kept (its caller may mark the partial result).  The simulator is
    deterministic: a repeated run would give the same trajectory.  Its runs record the
    voltages of the candidate sites' buses (`buses`) whatever a caller asks
    (`Simulator.run`'s ``voltages``): the placement's own checks read them
    (`stabctl.stability.sime.device_modes`) on the runs it shares with the CCT search,
    which reads none."""

    def __init__(self, sim, buses=()):
        self._sim, self._done, self.n_runs = sim, {}, 0
        self._buses = sorted({int(b) for b in buses})

    def __getattr__(self, name):
        if name == "start":  # no paused runs: a CCT search on it runs its probes whole
            raise AttributeError(name)
        return getattr(self._sim, name)

    def run(
        self,
        events=(),
        t_end: float = 5.0,
        h: float | None = None,
        semantics=None,
        separation_limit: float = np.pi,
        stop_at_separation: bool = False,
        storage=None,
        monitor=None,
        voltages: bool = True,  # the sites' recorded always (class docstring)
    ):
        h = self._sim.default_h if h is None else h
        key = (
            repr(list(events)),
            round(t_end, 12),
            h,
            semantics,
            separation_limit,
            stop_at_separation,
            id(storage),
            monitor,
        )
        if key not in self._done:
            self.n_runs += 1
            self._done[key] = self._sim.run(
                events,
                t_end,
                h=h,
                semantics=semantics,
                separation_limit=separation_limit,
                stop_at_separation=stop_at_separation,
                storage=storage,
                monitor=monitor,
                voltages=self._buses,
            )
        return self._done[key]


def scanned_cct(
    sim,
    fault: LineFault,
    fleet,
    *,
    tol: float,
    t_max: float,
    start: float,
    stop: float | None,
    step: float,
):
    """CCT as the FIRST unstable clearing time: runs cleared at start, start + step, ...
    (up to stop, default t_max) until one is unstable, then `critical_clearing_time`
    bisects between it and the last stable one (from 0 if `start` itself is unstable);
    when all are stable it bisects upward from the last one.  Bisection alone can land in
    a stable island above an unstable window (stability is not always monotonic in the
    clearing time with bang-bang storage), which this scan rules out on its grid.
    Clearing times below `start` are taken as stable (the caller passes a CCT without
    storage).  The bisection's range is at least `tol` wide: with a step under `tol` the
    last stable and the first unstable clearing time can lie in one lattice cell, which is
    then searched up to its upper end.  Returns (CCTResult, scan runs).  Raises as
    critical_clearing_time (InputError "above the search limit" when stable up to t_max).
    """
    limit = t_max if stop is None else min(stop, t_max)
    prev, t, runs = None, round(start, 12), 0
    while t <= limit + 1e-12:
        runs += 1
        if not _run(sim, fault, t, fleet).stable:
            lo = prev or 0.0
            res = critical_clearing_time(
                sim,
                fault,
                SearchOptions(tol=tol, t_lo=lo, t_hi=t, error_check=False, t_max=max(t, lo + tol)),
                storage=fleet,
            )
            return res, runs
        prev, t = t, round(t + step, 12)
    if prev is None or prev >= t_max:
        raise AboveSearchLimit(
            f"{fault.describe()}: the CCT is above the search limit t_max = {t_max:g} s"
        )
    res = critical_clearing_time(
        sim,
        fault,
        SearchOptions(
            tol=tol, t_lo=prev, error_check=False, t_hi=min(prev + 4 * step, t_max), t_max=t_max
        ),
        storage=fleet,
    )
    return res, runs


def cct_gradient(
    sim,
    fault: LineFault,
    t_clear: float,
    fleet,
    sites,
    beta: np.ndarray,
    controller: BangBangCOI,
    eps_s: float = EPS_S,
) -> dict:
    """Gradient of the CCT in the site ratings (s/MW) from the run cleared at t_clear (just
    beyond the CCT) and a later unstable one (t_clear + eps_s, the step doubled up to 3
    times while that run is stable or the margin does not fall).  When no later run gives
    a falling margin (a run-away from rest on a later swing has margin 0 at every
    clearing time), d eta / d t_clear is taken as minus the OMIB's kinetic energy rate at
    clearing (`sime.clearing_energy_rate`): what one more second of fault adds.

    Returns {"gradient_s_per_mw", "margin" (pu*rad), "dmargin_dtc" (pu*rad/s),
    "slope_from" ("difference" or "clearing energy"), "critical" (machine numbers),
    "n_runs"}.  Raises NoMarginSlope (an InputError) when neither slope is negative
    (`evaluate` then differences the CCT itself, `cct_difference_gradient`).
    """
    case = sim.case
    r1 = _run(sim, fault, t_clear, fleet)
    crit = critical_machines(r1)
    eta1, eq, ku = _margin(r1, crit, fault.t_fault + t_clear, case)
    buses, macs = [s[0] for s in sites], [s[1] for s in sites]
    modes = device_modes(r1, buses, macs, controller, case.freq_hz)
    deta_dp = eq.group_weights(beta) * storage_integrals(eq, modes, ku) / case.base_mva
    slope, how, runs = 0.0, "difference", 1
    for k in range(4):
        eps = eps_s * 2**k
        runs += 1
        r2 = _run(sim, fault, t_clear + eps, fleet)
        if not r2.stable:
            slope = (_margin(r2, crit, fault.t_fault + t_clear + eps, case)[0] - eta1) / eps
            if slope < 0:
                break
    if not slope < 0:
        slope, how = -clearing_energy_rate(eq, fault.t_fault + t_clear), "clearing energy"
    if not slope < 0:
        raise NoMarginSlope(
            f"{fault.describe()}: no SIME margin slope in the clearing time near {t_clear:g} s"
        )
    return {
        "gradient_s_per_mw": (-deta_dp / slope).tolist(),
        "margin": eta1,
        "dmargin_dtc": slope,
        "slope_from": how,
        "critical": crit,
        "n_runs": runs,
    }


class NoMarginSlope(InputError):
    """SIME's margin gives no slope in the clearing time near the CCT (`cct_gradient`)."""


#: the rating added along the fleet's direction by `cct_difference_gradient`: this
#: fraction of the fleet's total, at least DIFF_MIN_MW
DIFF_FRACTION, DIFF_MIN_MW = 0.25, 50.0


def cct_difference_gradient(sim, fault: LineFault, job: dict, ctrl, res) -> dict:
    """Gradient of the CCT in the site ratings (s/MW) when SIME's margin gives none: the
    CCT again with DIFF_FRACTION of the fleet's total rating (at least DIFF_MIN_MW) added
    in proportion to the present ratings (every site alike without storage), by bisection
    below and above the present CCT; the difference over the MW added is the derivative
    along that direction, given to every site (a cut exact along the fleet's own
    direction).  Never raises for a missing slope: the placement loop goes on.

    Parameters
    ----------
    sim : Simulator
        The job's (memoised) simulator.
    fault : LineFault
        The contingency's fault.
    job : dict
        The `evaluate` job (sites, devices, tol, t_max, esd_model).
    ctrl : BangBangCOI
        The devices' controller.
    res : CCTResult
        The present CCT search.

    Returns
    -------
    dict
        As `cct_gradient`, with "slope_from" "CCT difference", "margin" and
        "dmargin_dtc" None, "added_mw" the rating added.
    """
    sites = job["sites"]
    have = {(int(d[0]), int(d[1])): float(d[2]) for d in job["devices"]}
    mw = np.array([have.get((int(b), int(m)), 0.0) for b, m in sites])
    direction = mw / mw.sum() if mw.sum() > 0 else np.full(len(sites), 1.0 / len(sites))
    added = max(DIFF_FRACTION * mw.sum(), DIFF_MIN_MW)
    more = {**job, "devices": devices_of_pairs(sites, mw + added * direction)}
    fleet = _fleet(more, ctrl)
    before = sim.n_runs
    try:
        cct2 = critical_clearing_time(
            sim,
            fault,
            SearchOptions(
                tol=job["tol"],
                t_lo=0.0,
                t_hi=res.t_unstable,
                t_max=job["t_max"],
                error_check=False,
            ),
            storage=fleet,
        ).cct_s
    except AboveSearchLimit:
        cct2 = float(job["t_max"])
    slope = (cct2 - res.cct_s) / added
    return {
        "gradient_s_per_mw": [slope] * len(sites),
        "margin": None,
        "dmargin_dtc": None,
        "slope_from": "CCT difference",
        "critical": list(res.separated),
        "added_mw": added,
        "n_runs": sim.n_runs - before,
    }


def devices_of_pairs(sites, mw) -> list:
    """[bus, machine, MW] of every [bus, machine] site with a rating > 0."""
    return [[int(b), int(m), float(p)] for (b, m), p in zip(sites, mw) if p > 0]


def _margin(result, crit, t_clear_abs: float, case):
    """(SIME margin, OMIB equivalent, index of the unstable point) of one run."""
    eq = omib_equivalent(result, crit, case.base_mva, case.freq_hz, machine_inertia(case))
    k_u = unstable_point(eq, t_clear_abs)
    return unstable_margin(eq, k_u), eq, k_u


def _run(sim, fault: LineFault, t_clear: float, fleet):
    """A run to the fault start + T_AFTER_FAULT (5 s, the CCT search's default window)
    stopped at separation; after a divergence (voltage collapse or a machine lost) its
    partial trajectory."""
    try:
        return sim.run(
            fault.events(t_clear),
            fault.t_fault + T_AFTER_FAULT,
            storage=fleet,
            stop_at_separation=True,
        )
    except SimulationError as exc:
        if exc.result is None or len(exc.result.t) < 3:
            raise
        exc.result.stable = False
        return exc.result


# -- parallel evaluation ---------------------------------------------------------------


def devices_of(sites, mw) -> list:
    """[bus, machine, MW] of every site with a rating > 0."""
    return [[s.bus, s.machine, float(p)] for s, p in zip(sites, mw) if p > 0]


@dataclass(frozen=True)
class VerifyOptions:
    """How `verify` evaluates the contingencies at one allocation.

    Attributes
    ----------
    base : dict or None
        Evaluations without storage (name -> `evaluate` dict).  With storage and base the
        CCT is scanned (`scanned_cct`) from the contingency's CCT without storage (or its
        target, the lesser): up to its target (scan="target") or to t_max (scan="full",
        the first unstable clearing time however far); scan="none" or no storage:
        bisection only.
    scan : {"target", "full", "none"}
    brackets : dict or None
        Name -> [stable, unstable] clearing times (s) of a coarser search at the same
        ratings, where a bisection starts (`evaluate`).
    check : bool
        Also the run cleared at each target (`check`).
    gradient : bool
        False for CCTs only.
    insecure_verdict : bool
        An N-1 insecure contingency (unstable even when cleared at once) returned as a
        verdict (`evaluate`'s insecure_verdict) instead of raised.

    Raises
    ------
    InputError
        Another scan value.
    """

    base: dict | None = None
    scan: str = "target"
    brackets: dict | None = None
    check: bool = False
    gradient: bool = True
    insecure_verdict: bool = False

    def __post_init__(self) -> None:
        if self.scan not in ("target", "full", "none"):
            raise InputError(f"scan must be 'target', 'full' or 'none', got {self.scan!r}")


@dataclass(frozen=True)
class Evaluator:
    """What every evaluation of one study shares (`verify`).

    Attributes
    ----------
    run_map : callable
        ``run_map(func, jobs) -> results`` (`stabctl.parallel.worker_pool`).
    case : str
        Case name or file (workers load it by name).
    sites : sequence of Site
        Candidate sites.
    beta : ndarray, shape (n_mac, n_sites)
        Distribution factors (`sime.distribution_factors`).
    controller : BangBangCOI
        The ESDs' law.
    search : SearchOptions
        CCT tolerance and search limit (``tol``, ``t_max``).
    model : ModelOptions
        Conventions and step of the runs (each contingency at its own load level).
    scan_s : float
        Clearing-time grid of the first-unstable scan (s).
    esd_model : {"ideal", "wecc"}
        The devices' model (`Study.esd_model`).
    critical_reference : bool
        The law armed per contingency (`Study.critical_reference`).
    case_digest : str or None
        The digest of the case's content as the study read it, put in every job (checked
        where it runs: `stabctl.stability.cct.job_case`); None: not checked.
    """

    run_map: Any
    case: str
    sites: tuple
    beta: np.ndarray
    controller: BangBangCOI
    search: SearchOptions = SearchOptions()
    model: ModelOptions = ModelOptions()
    scan_s: float = SCAN_S
    esd_model: str = "ideal"
    critical_reference: bool = False
    case_digest: str | None = None


def verify(ev: Evaluator, contingencies, mw, opts: VerifyOptions = VerifyOptions()) -> dict:
    """`evaluate` every contingency at ratings mw (MW per site), in parallel through
    ``ev.run_map``.

    Parameters
    ----------
    ev : Evaluator
    contingencies : sequence of Contingency
    mw : array_like, shape (n_sites,)
        Ratings (MW).
    opts : VerifyOptions, optional
        Scan, brackets, check runs, gradients.

    Returns
    -------
    dict
        Name -> evaluation dict.  The jobs are submitted longest scan first (so that the
        pool's last jobs are short).
    """
    devices = devices_of(ev.sites, mw)
    t_max, base, scan = ev.search.t_max, opts.base, opts.scan
    common = {
        "case": ev.case,
        "case_digest": ev.case_digest,
        "devices": devices,
        "sites": [[s.bus, s.machine] for s in ev.sites],
        "beta": np.asarray(ev.beta).tolist(),
        "controller": controller_dict(
            ev.controller, {"tol": ev.search.tol, "t_max": t_max} if ev.critical_reference else None
        ),
        "tol": ev.search.tol,
        "t_max": t_max,
        "scan_s": ev.scan_s,
        **ev.model.to_inputs(),
        **model_inputs(ev.esd_model),
    }
    scanning = devices and base is not None and scan != "none"
    base = base or {}
    brackets = opts.brackets or {}
    jobs = [
        {
            **common,
            "fault": fault_inputs(c.fault),
            "load": c.load,
            "gradient": opts.gradient,
            **({"insecure_verdict": True} if opts.insecure_verdict else {}),
            **({"check_s": c.target_cct_s} if opts.check else {}),
            "scan_from": min(base[c.name]["cct_s"], c.target_cct_s) if scanning else None,
            "scan_to": c.target_cct_s if scan == "target" else None,
            **({"bracket": list(brackets[c.name])} if c.name in brackets and not scanning else {}),
        }
        for c in contingencies
    ]
    spans = [
        (j["scan_to"] or t_max) - j["scan_from"] if j["scan_from"] is not None else 0.0
        for j in jobs
    ]
    order = sorted(range(len(jobs)), key=lambda i: -spans[i])
    done = dict(zip(order, ev.run_map(evaluate, [jobs[i] for i in order])))
    return {c.name: done[i] for i, c in enumerate(contingencies)}


def controller_dict(controller: BangBangCOI, critical_search: dict | None = None) -> dict:
    """The fields of a bang-bang law as a JSON-able dict (a worker job's `controller`).

    Parameters
    ----------
    controller : BangBangCOI
        The law (its ``critical`` machines are not carried: a law on a critical group
        is armed per contingency).
    critical_search : dict or None, optional
        {"tol", "t_max"} (s): the law armed per contingency (``place --coi critical``):
        each job's devices take the COI of the other group, the group being the
        machines its fault separates without storage, found by the worker (`_law`).

    Returns
    -------
    dict
        deadband_hz, v_gate_pu, coi, hysteresis_hz (and critical_search).
    """
    out = {
        "deadband_hz": controller.deadband_hz,
        "v_gate_pu": controller.v_gate_pu,
        "coi": controller.coi,
        "hysteresis_hz": controller.hysteresis_hz,
    }
    if critical_search is not None:
        out.update(coi="critical", critical_search=dict(critical_search))
    return out


def cuts_from(contingencies, evaluations: dict, mw) -> list[CCTCut]:
    """One CCTCut per contingency from its evaluation at ratings mw."""
    return [
        CCTCut(
            contingency=c.name,
            target_s=c.target_cct_s,
            cct_s=evaluations[c.name]["cct_s"],
            gradient=np.asarray(evaluations[c.name]["gradient_s_per_mw"], float),
            at_mw=np.asarray(mw, float),
        )
        for c in contingencies
    ]
