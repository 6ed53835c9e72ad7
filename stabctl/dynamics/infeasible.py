"""Controls whose initial point lies outside their own limits, left out of a case.

Large planning cases carry exciters and governors whose power-flow operating point puts
a limited state outside its own limits (a governor dispatched above its Tmax, an ESST4B
whose inner loop would start above VMmax).  PSS/E reports such records as "initial
conditions suspect" and runs on (the state then jumps to its limit at the first step);
stabctl refuses the case by default (`stabctl.errors.InitialLimitError`: a run must start
at rest), runs on as PSS/E when asked (`Simulator(suspect_starts="run")`, ``simulate
--suspect-starts run``, each listed), or :func:`leave_out_infeasible` gives the case
without those controls -- each
exciter with its stabiliser (the machine keeps its initial field voltage), each governor
(the machine keeps its initial mechanical power) -- and names every one, so that a user
decides with the list in hand; it is the explicit ``--leave-out-infeasible`` of the
import commands, never a silent default.
"""

from __future__ import annotations

import numpy as np

from stabctl.case import Case
from stabctl.errors import CaseError, InitialLimitError

__all__ = ["leave_out_infeasible", "offenders"]

#: at most this many passes (each pass removes every offender its model build reports;
#: an exciter's removal can only reveal offenders of the other kind)
MAX_PASSES = 8


def leave_out_infeasible(
    case: Case, q_limits: bool = True, conventions: str = "ieee"
) -> tuple[Case, tuple[str, ...]]:
    """The case without the exciters and governors that cannot start within their limits.

    Parameters
    ----------
    case : Case
        The case; its power flow is solved (`stabctl.network.powerflow.solve_powerflow`).
    q_limits : bool, optional
        PV buses switch to PQ at their Q limits in that power flow (default, as
        ``simulate``).
    conventions : {"ieee", "pstess"}, optional
        The model conventions whose initialisation is checked.

    Returns
    -------
    (Case, tuple of str)
        The case (the same object when nothing is left out) and one line per control left
        out: ``"exciter of GM (bus B[, id I]): <the limit and the value>"`` (its stabiliser
        with it) or ``"governor of GM (bus B[, id I]): ..."``.

    Raises
    ------
    CaseError
        Any other refusal of the dynamic model (it is not about limits at the initial
        point); offenders still reported after `MAX_PASSES` passes.
    PowerFlowError
        The power flow does not converge.

    Source: PSS/E Program Operation Manual, "Dynamic Simulation Initialization" (initial
    conditions suspect); the checks themselves are the models' own initialisations.
    """
    from stabctl.dynamics.model import DynamicModel, OperatingPoint
    from stabctl.network.powerflow import solve_powerflow

    pf = solve_powerflow(case, q_limits=q_limits)
    op = OperatingPoint.from_bus_matrix(pf.bus_matrix())
    left: list[str] = []
    for _ in range(MAX_PASSES):
        try:
            DynamicModel(case, op, conventions=conventions)
        except InitialLimitError as err:
            case = _without(case, err, left)
            continue
        return case, tuple(left)
    raise CaseError(
        f"controls still outside their limits after {MAX_PASSES} passes: {'; '.join(left[-3:])}"
    )


#: the control tables a leave-out removes rows of: (what a row is, the case's table)
LEFT_OUT = {"exc_con": ("exciter", "exciters"), "tg_con": ("governor", "governors")}


def offenders(case: Case, err: InitialLimitError) -> list[str]:
    """One line per row `err` names, the device by its machine or bus as outputs name
    them (``"governor of G1 (bus 1, id '1'): initial power order 1.2415 pu outside
    [Tmin, Tmax] = [0.3000, 1.0500]"``), instead of the table's row number.

    Parameters
    ----------
    case : Case
        The case whose model build raised `err`.
    err : InitialLimitError
        Its table (``exc_con``, ``tg_con`` or ``svc_con``), rows and messages.

    Returns
    -------
    list of str
        The lines, in the order of ``err.rows``.
    """
    lines = []
    for r, message in zip(err.rows, err.messages):
        what = message.split(": ", 1)[-1]
        if err.table in LEFT_OUT:
            kind, table = LEFT_OUT[err.table]
            device = f"{kind} of {case.machine_name(int(getattr(case, table).machine[r]))}"
        else:  # a static var compensator (svc_con): named by its bus
            device = f"static var compensator at bus {int(case.svcs.bus[r])}"
        lines.append(f"{device}: {what}")
    return lines


def _without(case: Case, err: InitialLimitError, left: list[str]) -> Case:
    """``case`` without the rows ``err`` names (an exciter's stabiliser with it); each
    appended to ``left`` as text.  A compensator is not left out: its reactive power is
    the power flow's at its bus (CaseError)."""
    if err.table not in LEFT_OUT:
        raise CaseError(
            f"{'; '.join(offenders(case, err))}: a compensator is not left out (its "
            "reactive power is the power flow's at its bus); change its limits or the "
            "power flow's voltage there"
        )
    table = LEFT_OUT[err.table][1]
    left.extend(offenders(case, err))
    rows = getattr(case, table)
    keep = np.ones(len(rows), bool)
    keep[list(err.rows)] = False
    changes = {table: rows.select(keep)}
    if table == "exciters":
        gone = rows.machine[~keep]
        changes["pss"] = case.pss.select(~np.isin(case.pss.machine, gone))
    return case.replace(**changes)
