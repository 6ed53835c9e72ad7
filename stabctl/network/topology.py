"""Network topology: the islands of a case (connected components of its closed branches).

One place for what the power flow (buses without a path to a swing bus), the dynamic
model (a disturbance that islands buses from every generator) and the simulator (each
machine's island, whose centre of inertia it swings against) ask of the graph.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from stabctl.case import Case
from stabctl.errors import CaseError

__all__ = [
    "OPEN_X",
    "bus_islands",
    "dead_buses",
    "machine_islands",
    "splits_machines",
    "without_dead_islands",
]

#: PST opens a branch by giving it this reactance (its charging stays); a branch at a
#: tenth of it or more is open for the topology
OPEN_X = 1e7


def bus_islands(case: Case, keep: np.ndarray | None = None) -> np.ndarray:
    """Island label of each bus: the connected components of the branches in service.

    Parameters
    ----------
    case : Case
        The network (buses and branches).
    keep : ndarray of bool, shape (n_branch,), or None, optional
        Branches that join their buses; default: those with x below OPEN_X / 10 (a branch
        PST opened by giving it OPEN_X is not).

    Returns
    -------
    ndarray of int, shape (n_bus,)
        Labels 0, 1, ... in the bus table's order; equal labels share an island.
    """
    br = case.branches
    if keep is None:
        keep = br.x < OPEN_X / 10
    f, t = case.bus_indices(br.from_bus[keep]), case.bus_indices(br.to_bus[keep])
    n = case.n_bus
    graph = sp.coo_matrix((np.ones(f.size), (f, t)), shape=(n, n))
    return connected_components(graph, directed=False)[1]


def machine_islands(case: Case) -> np.ndarray:
    """Island of each machine in the case's network (`bus_islands`): the machines each one
    can swing against, whose centre of inertia its loss of synchronism is judged by.

    Parameters
    ----------
    case : Case
        The network and its machines.

    Returns
    -------
    ndarray of int, shape (n_mac,)
        Labels 0, 1, ... numbered in the order of the machines' first appearance (machine
        1's island is 0); all 0 in a connected network.
    """
    label = bus_islands(case)[case.bus_indices(case.machines.bus)]
    _, first, inverse = np.unique(label, return_index=True, return_inverse=True)
    rank = np.argsort(np.argsort(first))
    return rank[inverse].astype(np.int64)


def splits_machines(case: Case, opened) -> bool:
    """Whether opening branch rows `opened` cuts machines off each other: some machines
    that share an island of the case's network (`machine_islands`) no longer do.

    Parameters
    ----------
    case : Case
        The network and its machines.
    opened : sequence of int
        0-based branch rows opened (e.g. a fault's cleared circuit and its further trips).

    Returns
    -------
    bool
    """
    keep = case.branches.x < OPEN_X / 10
    keep[np.asarray(opened, np.int64)] = False
    before = bus_islands(case)[case.bus_indices(case.machines.bus)]
    after = bus_islands(case, keep)[case.bus_indices(case.machines.bus)]
    return np.unique(after).size > np.unique(before).size


def dead_buses(case: Case, keep: np.ndarray | None = None) -> np.ndarray:
    """The buses with no path to a swing bus over the branches in service (`bus_islands`).

    Parameters
    ----------
    case : Case
        The network (buses, their kinds, branches).
    keep : ndarray of bool, shape (n_branch,), or None, optional
        Branches that join their buses (`bus_islands`).

    Returns
    -------
    ndarray of int
        Their 0-based rows in the bus table (empty when every island has a swing bus).
    """
    label = bus_islands(case, keep)
    return np.flatnonzero(~np.isin(label, label[case.swing_index]))


def without_dead_islands(case: Case) -> tuple[Case, tuple[str, ...]]:
    """The case without its islands that have no swing bus, and without everything on them.

    A bus with no path to a swing bus has nothing to hold its voltage and angle: the power
    flow refuses it (`stabctl.network.powerflow.solve_powerflow`).  PSS/E's practice is to
    disconnect such islands (bus type 4, "isolated") before solving; this does the same:
    it removes their buses, every branch touching them (open ones included), their loads,
    injections, converters, motors and switched shunts, their machines with each machine's
    exciter, stabiliser, governor and shaft.  The user asks for it (``--leave-out-islands``
    of the import commands); a case is never cut silently.

    Parameters
    ----------
    case : Case
        The case.

    Returns
    -------
    (Case, tuple of str)
        The case (the same object when every island has a swing bus) and one line per
        island left out, naming its buses and what stood on them.

    Raises
    ------
    CaseError
        A device that stays refers to a bus or machine that goes: a converter's plant
        controller measuring a line at a dead bus (``pc_bus1``/``pc_bus2``), a
        cross-compound governor or an exciter reading a machine across the cut, or a PST
        switching matrix (``sw_con``) naming a dead bus.

    Source: PSS/E Program Operation Manual, "Bus type codes" (type 4: disconnected).
    """
    rows = dead_buses(case)
    if rows.size == 0:
        return case, ()
    gone = case.buses.number[rows]
    macs, br = case.machines, case.branches
    mac_gone = macs.number[np.isin(macs.bus, gone)]
    _check_cut(case, gone, mac_gone)
    changes = {
        "buses": case.buses.select(~np.isin(case.buses.number, gone)),
        "branches": br.select(~(np.isin(br.from_bus, gone) | np.isin(br.to_bus, gone))),
        "machines": macs.select(~np.isin(macs.number, mac_gone)),
    }
    for name in ("loads", "injections", "converters", "motors", "svcs", "switched_shunts"):
        table = getattr(case, name)
        changes[name] = table.select(~np.isin(table.bus, gone))
    for name in ("exciters", "pss", "governors", "shafts"):
        table = getattr(case, name)
        changes[name] = table.select(~np.isin(table.machine, mac_gone))
    label = bus_islands(case)[rows]
    lines = []
    for island in np.unique(label):
        buses = gone[label == island]
        on = [
            f"{n} {what}"
            for what, n in (
                ("machine(s)", int(np.isin(macs.bus, buses).sum())),
                ("load(s)", int(np.isin(case.loads.bus, buses).sum())),
                ("converter(s)", int(np.isin(case.converters.bus, buses).sum())),
                ("motor(s)", int(np.isin(case.motors.bus, buses).sum())),
                ("compensator(s)", int(np.isin(case.svcs.bus, buses).sum())),
            )
            if n
        ]
        lines.append(
            f"island of bus(es) {', '.join(str(int(b)) for b in buses)} without a swing bus"
            + (f" ({', '.join(on)})" if on else "")
        )
    return case.replace(**changes), tuple(lines)


def _check_cut(case: Case, gone: np.ndarray, mac_gone: np.ndarray) -> None:
    """CaseError if a device that stays refers to a dead bus or a removed machine."""
    conv = case.converters
    live_conv = ~np.isin(conv.bus, gone)
    for col in ("pc_bus1", "pc_bus2"):
        bad = np.flatnonzero(live_conv & np.isin(getattr(conv, col), gone))
        if bad.size:
            raise CaseError(
                f"converter {int(conv.number[bad[0]])}: its plant controller measures at "
                f"bus {int(getattr(conv, col)[bad[0]])} ({col}), in an island left out"
            )
    refs = (
        ("exciters", "ifd_machine", "exciter of machine"),
        ("governors", "machine2", "governor of machine"),
    )
    for name, col, what in refs:
        table = getattr(case, name)
        bad = np.flatnonzero(
            ~np.isin(table.machine, mac_gone) & np.isin(getattr(table, col), mac_gone)
        )
        if bad.size:
            raise CaseError(
                f"{what} {int(table.machine[bad[0]])}: reads machine "
                f"{int(getattr(table, col)[bad[0]])} ({col}), in an island left out"
            )
    if case.sw_con is not None and np.isin(case.sw_con[:, 1:3], gone).any():
        raise CaseError("sw_con names a bus in an island left out")
