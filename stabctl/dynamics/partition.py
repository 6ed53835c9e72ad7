"""The machines' islands stage by stage: which machines a run's loss-of-synchronism
criterion judges, and against which centre of inertia, once its events trip machines or
cut the network apart.

Before the disturbance each machine swings against the centre of inertia (COI, paper eq.
40) of its island (`stabctl.network.topology.machine_islands`).  A stage of a run
(`stabctl.dynamics.events.stages`) can take machines out of that picture:

- a tripped machine (`GeneratorTrip`) is out of service: its angle says nothing about the
  system, so it leaves the criterion and every COI (it is alone in an island of its own);
- a trip that cuts a machine, or a group of machines, off the rest of its island (a
  generator's step-up transformer opened, a system split) leaves it in an island apart
  from the main grid.  The machine is lost to the system, as PSS/E trips a generator whose
  breaker opened: it leaves the criterion, which judges the main grid, and the result
  names it and its island's buses (`machine_islands_log`).  The island keeps running in
  the simulation, against its own COI (`SimulationResult.relative_angle`).

A machine that the stage clearing a fault cuts off or trips (the first stage after the
fault's without a fault on: a generator whose step-up transformer or only line is the
faulted one, a split by the clearing's trips) is lost from the fault's start: while the
fault is on it is not judged, and the criterion's COI of its island leaves it out
(`criterion_inertia`), so that its own pole slip before its breakers open, or the swing of
an area about to be split off, does not make the rest of the system unstable.  The
stage's islands and COI weights are kept for the storage devices, which see the machine
connected until the clearing.

The main grid of an island before the disturbance is the part, in the stage's network,
that holds its infinite bus (a machine with H = 0), else the part that serves the most
load (sum of the buses' active load: where the customers are, so that generators cut off
with little or no load are the ones lost), on a tie the one with the largest inertia (sum
of H * MVA), then the one with more buses (more of the network), then the one holding the
machine first in the data.  Each part has its own COI weights
(`stabctl.dynamics.coi.coi_inertia` over the stage's islands).

The compiled loop takes each stage's islands, weights and judged machines too
(`stabctl.dynamics.integrator.run_options`, from the grid point where the stage starts):
its stop at separation judges the machines `judged` does, against the stage's COI, so a
machine tripped or cut off never stops a run; and each storage device watches its machine
against the COI of the machine's island in the current stage
(`stabctl.dynamics.switching.observe`): a device whose machine is cut off follows the COI
of the machine's own island (a machine alone: relative speed 0, the device idles), the
devices of the main grid the COI of the main grid without it, and the device of a tripped
machine sees 0 and idles.

A run none of whose stages trips a machine or splits an island has no partitions (an
empty tuple): its criterion is the one of the islands before the disturbance, computed as
it always was, and so are its devices' relative speeds.

The Kundur check: tripping G4 at 1 s leaves G1-G3 within 0.95 rad of their COI (stable,
G4 listed as tripped); a fault at bus 1 cleared by opening G1's step-up transformer 1-10
islands G1 at bus 1, and G2-G4 then follow, to 1e-6 rad, the trajectories of the same
fault cleared without the line and G1 tripped at the clearing instant
(tests/dynamics/test_islands.py).  With a storage fleet G1's device idles from the
clearing on and G2-G4's follow the run with G1 tripped, and a tripped machine's device
does nothing after the trip (tests/storage/test_islands_esd.py).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from stabctl.dynamics.coi import coi_inertia, coi_of_islands

__all__ = [
    "Partition",
    "stage_partitions",
    "stage_at",
    "relative_to_islands",
    "judged_at",
    "judged_relative",
    "criterion_inertia",
    "machine_islands_log",
    "tripped_log",
]


@dataclass(frozen=True, eq=False)
class Partition:
    """The machines' islands from a stage's start on (module docstring).

    Attributes
    ----------
    t_s : float
        Start of the stage, s (absolute run time).
    island : ndarray of int, shape (n_mac,)
        Each machine's island in the stage's network, labels 0, 1, ... in the order of the
        machines' first appearance; a tripped machine alone in its own.
    inertia : ndarray, shape (n_mac,)
        COI weights within those islands (`stabctl.dynamics.coi.coi_inertia`).
    judged : ndarray of bool, shape (n_mac,)
        The machines the loss-of-synchronism criterion judges: in service and in the main
        grid of their island before the disturbance.
    tripped : ndarray of bool, shape (n_mac,)
        The machines out of service in this stage.
    """

    t_s: float
    island: np.ndarray
    inertia: np.ndarray
    judged: np.ndarray
    tripped: np.ndarray


def stage_partitions(
    starts,
    machine_island,
    bus_island,
    base_island: np.ndarray,
    H: np.ndarray,
    mva: np.ndarray,
    load: np.ndarray,
    faulted=None,
) -> tuple[Partition, ...]:
    """The partition of every stage of a run, or none when no stage trips a machine or
    splits an island of the network before the disturbance.

    Parameters
    ----------
    starts : sequence of float
        Each stage's start, s (the first 0).
    machine_island : sequence of ndarray of int, each shape (n_mac,)
        Each stage's island label of each machine's bus, -1 for a tripped machine
        (`stabctl.network.solution.ReducedNetwork.machine_island`).
    bus_island : sequence of ndarray of int, each shape (n_bus,)
        Each stage's bus island labels, in the labels of `machine_island`
        (`stabctl.network.solution.ReducedNetwork.bus_island`).
    base_island : ndarray of int, shape (n_mac,)
        Each machine's island before the disturbance
        (`stabctl.network.topology.machine_islands`).
    H, mva : ndarray, shape (n_mac,)
        Inertia constants (s, machine base; 0: an infinite bus) and machine bases (MVA).
    load : ndarray, shape (n_bus,)
        Each bus's active load, pu (the case's bus table, in the order of `bus_island`).
    faulted : sequence of bool or None, optional
        Whether a fault is on in each stage (None: in none).  A machine that the stage
        clearing a fault (the first after it without one) cuts off or trips is not judged
        while the fault is on either (module docstring).

    Returns
    -------
    tuple of Partition
        One per stage, in order; empty when every stage keeps the machines as before the
        disturbance.
    """
    labels = [np.asarray(m, np.int64) for m in machine_island]
    base = np.asarray(base_island, np.int64)
    if all(_same_partition(lab, base) for lab in labels):
        return ()
    H, mva, load = np.asarray(H, float), np.asarray(mva, float), np.asarray(load, float)
    parts = [
        _partition(float(t), lab, np.asarray(buses), base, H, mva, load)
        for t, lab, buses in zip(starts, labels, bus_island)
    ]
    on = [False] * len(parts) if faulted is None else [bool(f) for f in faulted]
    for s in range(len(parts) - 2, -1, -1):  # backwards: a fault on over several stages
        if on[s]:  # the machines the next stage loses are lost while the fault is on
            parts[s] = replace(parts[s], judged=parts[s].judged & parts[s + 1].judged)
    return tuple(parts)


def criterion_inertia(inertia: np.ndarray, island: np.ndarray, judged: np.ndarray) -> np.ndarray:
    """The COI weights the loss-of-synchronism criterion uses (module docstring): in an
    island whose judged machines weigh, those machines' weights only; elsewhere `inertia`.
    That is `inertia` wherever an island's machines are all judged or none is: in every
    stage without a fault on (short of a reclosure that joins part of one island to the
    main grid of another).

    Parameters
    ----------
    inertia : ndarray, shape (n_mac,)
        A stage's COI weights (`Partition.inertia`).
    island : ndarray of int, shape (n_mac,)
        Its islands.
    judged : ndarray of bool, shape (n_mac,)
        The machines its criterion judges.

    Returns
    -------
    ndarray, shape (n_mac,)
    """
    inertia, island = np.asarray(inertia, float), np.asarray(island)
    kept = np.bincount(island, np.where(judged, inertia, 0.0), minlength=island.max() + 1)
    return np.where((kept[island] > 0) & ~judged, 0.0, inertia)


def _same_partition(stage: np.ndarray, base: np.ndarray) -> bool:
    """Whether a stage's labels (-1: tripped) group the machines as the base labels do."""
    if np.any(stage < 0):
        return False
    pairs = set(zip(stage.tolist(), base.tolist()))
    return len(pairs) == len(set(stage.tolist())) == len(set(base.tolist()))


def _partition(t_s, stage, buses, base, H, mva, load) -> Partition:
    tripped = stage < 0
    size = {
        int(k): (float(np.sum(np.abs(load[buses == k]))), int(np.sum(buses == k)))
        for k in np.unique(stage[~tripped])
    }
    lab = stage.copy()
    lab[tripped] = stage.max() + 1 + np.arange(int(tripped.sum()))  # each alone
    _, first, inverse = np.unique(lab, return_index=True, return_inverse=True)
    island = np.argsort(np.argsort(first))[inverse].astype(np.int64)
    judged = np.zeros(stage.size, bool)
    for b in np.unique(base):
        online = np.flatnonzero((base == b) & ~tripped)
        if online.size:
            main = _main_part(online, stage, size, H, mva)
            judged[online[stage[online] == main]] = True
    return Partition(t_s, island, coi_inertia(H, mva, island), judged, tripped)


def _main_part(machines: np.ndarray, stage: np.ndarray, size: dict, H, mva) -> int:
    """The stage island (label of `stage`) of the main grid among those of `machines`
    (module docstring: an infinite bus's, else the most load, else the largest inertia,
    else the most buses (`size`: (load pu, buses) per label), else the first)."""
    best, rank = -1, (False, -1.0, -1.0, -1)
    labels = stage[machines]
    _, first = np.unique(labels, return_index=True)
    for k in labels[np.sort(first)].tolist():  # in the data's order: a tie keeps the first
        here = machines[labels == k]
        infinite = bool(np.any(H[here] == 0))
        here_rank = (infinite, size[k][0], float(np.sum(H[here] * mva[here])), size[k][1])
        if here_rank > rank:
            best, rank = k, here_rank
    return best


def stage_at(t: np.ndarray, partitions) -> np.ndarray:
    """The partition of each time: the last one started at or before it.

    Parameters
    ----------
    t : ndarray, shape (n_t,)
        Times, s.
    partitions : sequence of Partition
        A run's partitions (non-empty).

    Returns
    -------
    ndarray of int, shape (n_t,)
        Indices into `partitions`.
    """
    starts = np.array([p.t_s for p in partitions])
    return np.maximum(np.searchsorted(starts, np.asarray(t, float), side="right") - 1, 0)


def relative_to_islands(values, t, inertia, island, partitions) -> np.ndarray:
    """Each machine's value less its island's COI value, the islands those of the stage at
    each time (`Partition`), or, without partitions, those before the disturbance.

    Parameters
    ----------
    values : ndarray, shape (n_t, n_mac)
        Rotor angles (rad) or speeds (pu).
    t : ndarray, shape (n_t,)
        Their times, s.
    inertia : ndarray, shape (n_mac,)
        COI weights before the disturbance (`stabctl.dynamics.coi.coi_inertia`).
    island : ndarray of int, shape (n_mac,)
        Islands before the disturbance.
    partitions : sequence of Partition
        The run's partitions; empty: none.

    Returns
    -------
    ndarray, shape (n_t, n_mac)
        0 for a tripped machine.
    """
    if not partitions:
        return values - coi_of_islands(values, inertia, island)
    out = np.empty_like(values)
    which = stage_at(t, partitions)
    for s in np.unique(which):
        rows, p = which == s, partitions[s]
        out[rows] = values[rows] - coi_of_islands(values[rows], p.inertia, p.island)
    return out


def judged_at(t: np.ndarray, partitions) -> np.ndarray:
    """Whether the loss-of-synchronism criterion judges each machine at each time
    (`Partition.judged` of the stage at that time).

    Parameters
    ----------
    t : ndarray, shape (n_t,)
        Times, s.
    partitions : sequence of Partition
        A run's partitions (not empty).

    Returns
    -------
    ndarray of bool, shape (n_t, n_mac)
    """
    return np.stack([p.judged for p in partitions])[stage_at(t, partitions)]


def judged_relative(angle, t, inertia, island, partitions) -> np.ndarray:
    """delta_i - delta_COI of each machine the loss-of-synchronism criterion judges at
    each time, against the COI of the judged machines of its island, 0 for the others
    (module docstring).

    Parameters
    ----------
    angle : ndarray, shape (n_t, n_mac)
        Rotor angles, rad.
    t : ndarray, shape (n_t,)
        Their times, s.
    inertia, island : ndarray, shape (n_mac,)
        COI weights and islands before the disturbance.
    partitions : sequence of Partition
        The run's partitions; empty: every machine judged against its island before the
        disturbance.

    Returns
    -------
    ndarray, shape (n_t, n_mac)
        rad.
    """
    if not partitions:
        return relative_to_islands(angle, t, inertia, island, partitions)
    judging = [
        replace(p, inertia=criterion_inertia(p.inertia, p.island, p.judged)) for p in partitions
    ]
    return relative_to_islands(angle, t, inertia, island, judging) * judged_at(t, partitions)


def machine_islands_log(
    partitions, bus_islands, machine_rows, bus_numbers, machine_numbers
) -> list[dict]:
    """The islands apart from the main grid that each stage newly forms with machines in
    them (module docstring).

    Parameters
    ----------
    partitions : sequence of Partition
        The run's partitions (empty: none).
    bus_islands : sequence of ndarray of int, each shape (n_bus,)
        Each stage's bus island labels (`stabctl.network.solution.ReducedNetwork.bus_island`).
    machine_rows : ndarray of int, shape (n_mac,)
        Each machine's bus, 0-based row of the bus table.
    bus_numbers, machine_numbers : ndarray of int
        The case's bus and machine numbers.

    Returns
    -------
    list of dict
        One per island, in stage order: ``t_s`` (the stage's start, s), ``buses`` (its bus
        numbers) and ``machines`` (its machine numbers, out of the criterion: lost).
    """
    out: list[dict] = []
    seen: set = set()
    for p, buses in zip(partitions, bus_islands):
        now = set()
        main = np.isin(p.island, p.island[p.judged])  # a fault's lost machines are still in
        lost = np.flatnonzero(~p.judged & ~p.tripped & ~main)  # it: not an island yet
        for k in dict.fromkeys(p.island[lost].tolist()):
            here = lost[p.island[lost] == k]
            key = tuple(int(m) for m in machine_numbers[here])
            now.add(key)
            if key in seen:
                continue
            label = buses[int(machine_rows[here[0]])]
            out.append(
                {
                    "t_s": float(p.t_s),
                    "buses": [int(b) for b in bus_numbers[buses == label]],
                    "machines": list(key),
                }
            )
        seen = now
    return out


def tripped_log(partitions, machine_numbers) -> list[dict]:
    """The machines each stage newly takes out of service.

    Parameters
    ----------
    partitions : sequence of Partition
        The run's partitions (empty: none).
    machine_numbers : ndarray of int
        The case's machine numbers.

    Returns
    -------
    list of dict
        One per stage that trips machines: ``t_s`` (its start, s) and ``machines``
        (numbers).
    """
    out, before = [], None
    for p in partitions:
        new = p.tripped if before is None else p.tripped & ~before
        if new.any():
            out.append({"t_s": float(p.t_s), "machines": [int(m) for m in machine_numbers[new]]})
        before = p.tripped
    return out
