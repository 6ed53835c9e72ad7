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

__all__ = ["OPEN_X", "bus_islands", "machine_islands"]

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
