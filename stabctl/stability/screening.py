"""Contingency screening: the CCT of a three-phase fault at every bus (cleared without loss
of a line) and, optionally, at the from-end of every branch with that branch tripped (N-1),
run as a resumable parallel sweep (`stabctl.parallel`, local processes or Dask).

Each job is one `stabctl.stability.cct` search; the results file keeps every finished search, so an
interrupted screening resumes where it stopped, and a search that fails is recorded with
its reason (never dropped).
"""

from __future__ import annotations

from pathlib import Path

from stabctl.case import Case
from stabctl.io import load_case
from stabctl.stability.cct import T_MAX, TOL, LineFault, cct_jobs
from stabctl.parallel import run_sweep


def screening_faults(case: Case, buses=None, lines: bool = False,
                     t_fault: float = 1.0) -> list[LineFault]:
    """Bus faults at `buses` (default all) and, with `lines`, a fault at the from-end of
    every branch (first circuit of parallel ones once each) with the branch tripped."""
    buses = case.buses.number if buses is None else buses
    faults = [LineFault(int(b), None, t_fault) for b in buses]
    if lines:
        seen = set()
        for f, t in zip(case.branches.from_bus, case.branches.to_bus):
            key = (int(f), int(t))
            circuit = sum(1 for k in seen if k[:2] == key) + 1
            seen.add((*key, circuit))
            faults.append(LineFault(int(f), int(t), t_fault, circuit))
    return faults


def screen(case_name: str, out: str | Path, *, buses=None, lines: bool = False,
           tol: float = TOL, t_max: float = T_MAX, workers: int | None = None,
           scheduler: str | None = None, progress: bool = True, conventions: str = "ieee",
           h: float | None = None, q_limits: bool = True) -> list[dict]:
    """Run the screening; returns one row per fault: key, bus, far_bus, status, CCT (s and
    cycles) with its numerical error (s), separated machines, simulations, or the failure
    reason.  `out` is the JSON-lines record (resumed if it exists); conventions, h: the
    model conventions and step of every run; q_limits: PV Q limits in the power flow.  Raises as `stabctl.parallel.run_sweep`."""
    case = load_case(case_name)
    faults = screening_faults(case, buses, lines)
    report = run_sweep(cct_jobs(case_name, faults, tol=tol, t_max=t_max,
                                conventions=conventions, h=h, q_limits=q_limits), out,
                       workers=workers, scheduler=scheduler, progress=progress)
    rows = []
    for fault, rec in zip(faults, report.records.values()):
        row = {"key": rec["key"], "bus": fault.bus, "far_bus": fault.far_bus,
               "status": rec["status"]}
        if rec["status"] == "ok":
            r = rec["result"]
            row.update(cct_s=r["cct_s"], cct_cycles=r["cct_cycles"],
                       numerical_error_s=r.get("numerical_error_s"),
                       separated=r["separated_machines"], n_simulations=r["n_simulations"])
        else:
            row["error"] = rec.get("error", "")
        rows.append(row)
    return rows
