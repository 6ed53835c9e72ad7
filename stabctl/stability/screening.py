"""Contingency screening: the CCT of a three-phase fault at every bus (cleared without loss
of a line) and, optionally, at the from-end of every branch with that branch tripped (N-1),
run as a resumable parallel sweep (`stabctl.parallel`, local processes or Dask).

Each job is one `stabctl.stability.cct` search; the results file keeps every finished search, so an
interrupted screening resumes where it stopped, and a search that fails is recorded with
its reason (never dropped).

With lines, the bus faults are searched first; each branch fault at a bus whose fault has a
CCT then starts from that CCT (`SearchOptions.guess_s`, recorded in its job's inputs as
``guess_s``): the branch trip mostly leaves it in the same 1 ms cell (ACTIVSg2000: 854 such
branch faults with a CCT, half in the bus fault's cell, 86 % within 5 ms), so the search
closes its cell in a few runs instead of bracketing from 0.1 s.  A guess changes no cell
where the verdict is monotone in the clearing time (`benchmarks/bench_cct.py
--activsg-guess`).  A branch fault whose trip cuts machines off each other (a generator's
step-up transformer, a radial tie) gets none: its bus fault kept those machines.
"""

from __future__ import annotations

import dataclasses
import os
from contextlib import nullcontext
from pathlib import Path

from stabctl import parallel
from stabctl.case import Case
from stabctl.dynamics.options import ModelOptions
from stabctl.errors import (
    AboveSearchLimit,
    InputError,
    InsecureContingency,
    WrongTypeError,
    bus_numbers,
    require_flag,
    require_instance,
)
from stabctl.io import load_case
from stabctl.network.topology import splits_machines
from stabctl.parallel import RunnerOptions
from stabctl.stability.cct import (
    LineFault,
    SearchOptions,
    cct_jobs,
    fault_of_inputs,
    require_case_name,
)


def _whose(rec: dict, jobs=()) -> str:
    """Whose a CCT record of none of a screening's jobs is: one of `jobs`' faults screened
    with other inputs (named: conventions, step, search settings ...) when its fault,
    storage rating and case are a job's; else a sweep-cct's when its fault has trips, a
    storage rating or a fault time no screening gives, else a sweep-cct's or another
    screening's (of other buses or lines)."""
    inputs = rec.get("inputs") or {}
    same = _same_fault(inputs, jobs)
    if same is not None:
        differ = parallel.input_differences(inputs, same.inputs, same.compared)
        return f"the same fault screened with other inputs ({differ or 'none named'})"
    if inputs.get("trips") or inputs.get("esd_pct") is not None or inputs.get("t_fault") != T_FAULT:
        return "a sweep-cct record (trips, a storage rating or a fault time no screening has)"
    return "a sweep-cct record or another screening's (of other buses or lines)"


def _same_fault(inputs: dict, jobs):
    """The job of `jobs` whose case, fault and storage rating a record's `inputs` have, or
    None (inputs that do not read as a fault have none)."""
    try:
        fault = fault_of_inputs(inputs)
    except (KeyError, TypeError, ValueError):
        return None
    for j in jobs:
        if (
            fault_of_inputs(j.inputs) == fault
            and j.inputs.get("esd_pct") == inputs.get("esd_pct")
            and j.inputs.get("case") == inputs.get("case")
        ):
            return j
    return None


def _cct(rec: dict) -> float | None:
    """The CCT of a search's record (s), None for a verdict or a failure."""
    return rec["result"]["cct_s"] if rec["status"] == "ok" else None


def _guessed(job: parallel.Job, guess: float | None) -> parallel.Job:
    """A branch fault's job starting from its bus fault's CCT (none: as it is)."""
    if guess is None:
        return job
    return dataclasses.replace(job, inputs={**job.inputs, "guess_s": guess})


def _guess(case: Case, fault: LineFault, bus_cct: float | None) -> float | None:
    """A branch fault's guess: its bus fault's CCT, None when its clearing cuts machines
    off each other (`stabctl.network.topology.splits_machines`): the bus fault kept
    them, the branch fault loses them, so its CCT says nothing of this one's (ACTIVSg2000:
    237 such faults robust at t_max where their bus faults' CCTs were 0.04-0.35 s)."""
    if bus_cct is None:
        return None
    opened = [case.circuit_row(fault.bus, fault.far_bus, fault.circuit)]
    opened += [case.circuit_row(a, b) for a, b in fault.trips]
    return None if splits_machines(case, opened) else bus_cct


#: when every fault of a screening starts, s
T_FAULT = 1.0


def _checked(out, buses, lines, guess, retry_failed, search, model, runner) -> tuple:
    """`screen`'s arguments checked: (buses as ints or None, search, model, runner with
    None as their defaults); WrongTypeError or InputError naming the argument."""
    if not isinstance(out, (str, os.PathLike)):
        raise WrongTypeError(f"screen(out): a file path is needed, got {out!r}")
    for name, flag in (("lines", lines), ("guess", guess), ("retry_failed", retry_failed)):
        require_flag(flag, f"screen({name})")
    if buses is not None:
        buses = bus_numbers(buses, "screen(buses)")
        twice = next((b for i, b in enumerate(buses) if b in buses[:i]), None)
        if twice is not None:
            raise InputError(f"screen(buses): bus {twice} given twice")
        if not buses and not lines:
            raise InputError("screen: nothing to screen (buses=[] and lines=False)")
    given = []
    for name, value, kind in (
        ("search", search, SearchOptions),
        ("model", model, ModelOptions),
        ("runner", runner, RunnerOptions),
    ):
        require_instance(value, kind, f"screen({name})", none=True)
        given.append(kind() if value is None else value)
    return buses, *given


def screening_faults(
    case: Case, buses=None, lines: bool = False, t_fault: float = T_FAULT
) -> list[LineFault]:
    """Bus faults at `buses` (default all) and, with `lines`, a fault at the from-end of
    every branch (first circuit of parallel ones once each) with the branch tripped."""
    buses = case.buses.number if buses is None else buses
    faults = [LineFault(int(b), None, t_fault) for b in buses]
    if lines:
        seen: set[tuple[int, int, int]] = set()
        for f, t in zip(case.branches.from_bus, case.branches.to_bus):
            key = (int(f), int(t))
            circuit = sum(1 for k in seen if k[:2] == key) + 1
            seen.add((*key, circuit))
            faults.append(LineFault(int(f), int(t), t_fault, circuit))
    return faults


#: the verdict of a search still stable at its upper limit (a robust fault)
ABOVE = AboveSearchLimit.label
#: the verdict of a fault unstable even when cleared at once (CCT 0)
INSECURE = InsecureContingency.label
#: every verdict of a CCT record, in the order summaries count them
VERDICTS = ("cct", ABOVE, INSECURE, "failed")


def verdict(rec: dict) -> str:
    """A CCT record's verdict: "cct" (found), :data:`ABOVE` (still stable at the search's
    upper limit: the CCT is above it, `stabctl.errors.AboveSearchLimit`), :data:`INSECURE`
    (unstable even when cleared at once: N-1 insecure, CCT 0,
    `stabctl.errors.InsecureContingency`) or "failed" (no verdict: the reason is in the
    record).  Records written before verdicts had their own status (status "failed" with
    the exception's name) are read the same."""
    if rec["status"] == "ok":
        return "cct"
    if rec["status"] == "verdict":
        return rec["verdict"]
    error = rec.get("error") or ""
    if error.startswith("AboveSearchLimit") or "still stable" in error:
        return ABOVE
    return INSECURE if "unstable even when cleared instantly" in error else "failed"


def _islanding(rec: dict) -> list[dict]:
    """A CCT record's islanding log (`stabctl.dynamics.driver.islanding_log`), from a CCT
    found or a verdict; empty when there is none or the search failed."""
    return rec.get("islanded") or (rec.get("result") or {}).get("islanded") or []


def islanded_buses(rec: dict) -> list[int]:
    """The buses a CCT record's contingency islands from every generator (their load shed,
    as PSS/E does; `stabctl.dynamics.driver.islanding_log`), from a CCT found or a verdict;
    empty when it islands none or the search failed."""
    return sorted({b for e in _islanding(rec) if "machines" not in e for b in e["buses"]})


def islanded_machines(rec: dict) -> tuple[list[int], list[int]]:
    """The machines a CCT record's contingency cuts off, in islands apart from the main
    grid, and those islands' buses (`stabctl.dynamics.partition`: the machines lost, the
    CCT or verdict that of the rest of the system).

    Parameters
    ----------
    rec : dict
        A CCT record (a CCT found or a verdict).

    Returns
    -------
    machines : list of int
        Machine numbers, sorted; empty when the contingency islands none or the search
        failed.
    buses : list of int
        The islands' bus numbers, sorted.
    """
    log = [e for e in _islanding(rec) if "machines" in e]
    return (
        sorted({m for e in log for m in e["machines"]}),
        sorted({b for e in log for b in e["buses"]}),
    )


def screen(
    case_name: str,
    out: str | Path,
    *,
    buses=None,
    lines: bool = False,
    guess: bool = True,
    search: SearchOptions | None = SearchOptions(),
    model: ModelOptions | None = ModelOptions(),
    runner: RunnerOptions | None = RunnerOptions(),
    retry_failed: bool = False,
) -> list[dict]:
    """Run the screening.

    Parameters
    ----------
    case_name : str
        Built-in case name or case file.
    out : str or Path
        The JSON-lines record (resumed if it exists).
    buses : sequence of int or None, optional
        Faulted buses (default all).
    lines : bool, optional
        Also every branch fault with the branch tripped (`screening_faults`).
    guess : bool, optional
        With `lines`, search the bus faults first and start each branch fault at a
        screened bus from its bus fault's CCT (module docstring); default True.
    search, model, runner : SearchOptions, ModelOptions, RunnerOptions, optional
        The CCT search (tol, t_max; recorded), the model conventions, step and Q limits of
        every run, and where the runs go.
    retry_failed : bool, optional
        Run again the searches `out` records as failed (`stabctl.parallel.run_sweep`);
        else they are shown as recorded, each row marked ``failed_before``.

    Returns
    -------
    list of dict
        One row per fault: key, bus, far_bus, circuit (None for a bus fault), status,
        whether this call searched it
        (``run_now``; False: its record read from `out`), verdict (`verdict`; with
        :data:`ABOVE` the search's limit ``t_max_s``; with :data:`INSECURE` CCT 0 and the
        reason), the buses it islands from every generator (``islanded``) and the
        machines it cuts off the main grid with their islands' buses
        (``islanded_machines``, ``islanded_machine_buses``: `islanded_machines`), what
        the stable run the verdict rests on (cleared at the CCT, or at the limit) ends with
        off a normal operating point and when (``end_concerns``, ``end_t_s``: empty and
        None when nothing, or in a record written before they were kept), CCT (s
        and cycles) with its numerical error (s), separated machines, simulations
        (``n_simulations``, a verdict's too: None in a record written before verdicts
        counted them), or the error and whether an earlier run recorded it
        (``failed_before``, not run again).

    Raises
    ------
    InputError, UnknownBusError
        As `stabctl.stability.cct.cct_jobs` and `stabctl.parallel.run_sweep`; a bus
        given twice; nothing to screen (``buses=[]`` without `lines`).
    WrongTypeError
        An argument of another type (`buses` a text or a number, a flag not a bool, `out`
        not a path, `search`, `model` or `runner` not their options; None is the
        default of each of those three).

    Warns
    -----
    UserWarning
        `out` holds records of none of the screening's jobs (a wider screening's, a
        sweep-cct's, or its own faults' screened with other inputs, those named:
        `stabctl.parallel.warn_others`), named (the first OTHERS_SHOWN): kept in the
        file, left out of the table.
    """
    require_case_name(case_name, "screen(case_name)")
    buses, search, model, runner = _checked(
        out, buses, lines, guess, retry_failed, search, model, runner
    )
    case = load_case(case_name)
    faults = screening_faults(case, buses, lines)
    jobs = cct_jobs(case_name, faults, search=search, model=model)
    faulted = {f.bus for f in faults if f.far_bus is None}
    later = [guess and f.far_bus is not None and f.bus in faulted for f in faults]
    parallel.warn_others(
        out,
        jobs,
        lambda r: _whose(r, jobs),
        f"this screening's {len(jobs)} fault(s)",
        "left out of its table",
    )
    workers = runner.workers or parallel.default_workers()
    local = runner.scheduler is None and workers > 1 and any(later)
    with parallel.pooled(workers) if local else nullcontext() as pool:  # one pool for both

        def sweep(some: list, stage: str | None) -> parallel.SweepReport:
            return parallel.run_sweep(  # looked up at call time (a test may patch it)
                some,
                out,
                workers=workers,
                scheduler=runner.scheduler,
                progress=runner.progress,
                retry_failed=retry_failed,
                pool=pool,
                stage=stage,
            )

        staged = any(later)
        first = [j for j, x in zip(jobs, later) if not x]
        reports = [sweep(first, f"1 of 2: {len(first)} searches" if staged else None)]
        if staged:
            bus_cct = {
                f.bus: _cct(reports[0].records[j.key])
                for f, j in zip(faults, jobs)
                if f.far_bus is None
            }
            second = [
                _guessed(j, _guess(case, f, bus_cct[f.bus]))
                for f, j, x in zip(faults, jobs, later)
                if x
            ]
            reports.append(sweep(second, f"2 of 2: {len(second)} branch faults"))
    records = {k: rec for r in reports for k, rec in r.records.items()}
    before = {k for r in reports for k in r.failed_before_keys}
    ran = {k for r in reports for k in r.ran_keys}
    rows = []
    for fault, rec in zip(faults, (records[j.key] for j in jobs)):
        row = {
            "key": rec["key"],
            "bus": fault.bus,
            "far_bus": fault.far_bus,
            "circuit": None if fault.far_bus is None else fault.circuit,
            "status": rec["status"],
            "run_now": rec["key"] in ran,
        }
        row["verdict"] = verdict(rec)
        row["islanded"] = islanded_buses(rec)
        row["islanded_machines"], row["islanded_machine_buses"] = islanded_machines(rec)
        ended = rec.get("result") or rec  # a CCT's stable end, or a robust fault's run
        row["end_concerns"], row["end_t_s"] = ended.get("end_concerns", []), ended.get("end_t_s")
        if row["verdict"] == ABOVE:
            row["t_max_s"] = search.t_max
        if row["verdict"] == INSECURE:
            row.update(cct_s=0.0, cct_cycles=0.0)
        if rec["status"] == "ok":
            r = rec["result"]
            row.update(
                cct_s=r["cct_s"],
                cct_cycles=r["cct_cycles"],
                numerical_error_s=r.get("numerical_error_s"),
                separated=r["separated_machines"],
                # its unstable end failed before any machine separated (None: it did not;
                # records from before round 44 have none)
                unstable_end_failure=r.get("unstable_end_failure"),
                n_simulations=r["n_simulations"],
                # the search's step cut for short subtransient time constants, and its
                # run's end checked (round 41: `cct` said them, `screen` did not)
                stiff_step_s=r.get("stiff_step_s"),
                run_end_check=r.get("run_end_check"),
            )
        elif rec["status"] == "verdict":
            row["reason"] = rec.get("reason", "")
            row["n_simulations"] = rec.get("n_simulations")  # None in a record from before
        else:
            row["error"] = rec.get("error", "")
            row["failed_before"] = rec["key"] in before  # recorded by an earlier run
        rows.append(row)
    return rows
