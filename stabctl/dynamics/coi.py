"""Centre of inertia (paper eq. 40): the inertia-weighted mean of the machines' rotor
angles or speeds, weights M_i = H_i * MVA_i.

The one implementation of the COI for the layers from `stabctl.dynamics` up (results,
simulation, SIME, linearisation, estimation).  The compiled loop's counterparts,
`coi_value` and `island_coi`, live in the storage layer, the lowest that needs them (its
controller kernels), and are re-exported here.

A network of several islands has one COI per island (`coi_of_islands`): a machine swings
against the machines it is connected to, so its loss of synchronism and the relative
speed its storage device acts on are judged there.
"""

from __future__ import annotations

import numpy as np

from stabctl.errors import InputError, WrongTypeError
from stabctl.storage.control import coi_value, island_coi

__all__ = [
    "coi_inertia",
    "machine_inertia",
    "coi_weights",
    "coi_angle",
    "coi_speed",
    "coi_of_rest",
    "coi_of_islands",
    "coi_value",
    "island_coi",
]


def machine_inertia(case) -> np.ndarray:
    """H * MVA of each machine of `case` (MW s, (n_mac,)): 0 for an infinite bus (H = 0),
    where `coi_inertia`'s weights are 1 for it and 0 for the island's other machines.

    Parameters
    ----------
    case : Case
        The case.

    Returns
    -------
    ndarray, shape (n_mac,)
        The machines' stored energies at rated speed, MW s (MJ).
    """
    return np.asarray(case.machines.H, float) * np.asarray(case.machines.mva, float)


def coi_inertia(H: np.ndarray, mva: np.ndarray, island: np.ndarray | None = None) -> np.ndarray:
    """The machines' COI weights M_i = H_i * MVA_i (MW s, paper eq. 40); in an island that
    holds infinite buses (H = 0, `stabctl.case.system.MachineTable`), theirs: 1 each, 0 for
    the island's others (an infinite bus is a machine of infinite inertia, the reference
    the others swing against, as in the paper's Section 2).

    Parameters
    ----------
    H : ndarray, shape (n_mac,)
        Inertia constants (s, machine base), >= 0.
    mva : ndarray, shape (n_mac,)
        Machine bases (MVA).
    island : ndarray of int, shape (n_mac,), or None, optional
        Each machine's island (`stabctl.network.topology.machine_islands`); default: one.

    Returns
    -------
    ndarray, shape (n_mac,)
        The weights (MW s, or 0/1 in an island with infinite buses).
    """
    H = np.asarray(H, float)
    M = H * np.asarray(mva, float)
    island = np.zeros(H.size, int) if island is None else np.asarray(island)
    for k in np.unique(island[H == 0]):
        here = island == k
        M[here] = (H[here] == 0).astype(float)
    return M


def coi_of_islands(values: np.ndarray, inertia: np.ndarray, island: np.ndarray) -> np.ndarray:
    """Each machine's own island's COI value (eq. 40 over the machines of its island; the
    system's COI, repeated, in a connected network).

    Parameters
    ----------
    values : ndarray, shape (..., n_mac)
        Rotor angles (rad) or speeds (pu), machines on the last axis.
    inertia : ndarray, shape (n_mac,)
        Weights M_i (`coi_inertia`).
    island : ndarray of int, shape (n_mac,)
        Each machine's island (`stabctl.network.topology.machine_islands`).

    Returns
    -------
    ndarray, shape (..., n_mac)
        The COI of machine i's island in column i.
    """
    labels, of = np.unique(np.asarray(island), return_inverse=True)
    M = np.asarray(inertia, float)
    W = np.zeros((M.size, labels.size))  # column j: island j's weights (a product with
    W[np.arange(M.size), of] = M  # n_mac x n_islands, not n_mac x n_mac: ACTIVSg2000's
    W /= W.sum(axis=0)  # 5 s probe in 0.2 ms instead of 12)
    return (values @ W)[..., of]


def coi_weights(inertia: np.ndarray) -> np.ndarray:
    """Normalised COI weights w_i = M_i / sum(M) (paper eq. 40).

    Parameters
    ----------
    inertia : ndarray, shape (n_mac,)
        M_i = H_i * MVA_i (MW s), or any quantity proportional to it.

    Returns
    -------
    ndarray, shape (n_mac,)
        The weights, summing to 1.
    """
    return inertia / inertia.sum()


def coi_angle(angle: np.ndarray, inertia: np.ndarray) -> np.ndarray:
    """COI angle delta_COI = sum(M_i delta_i) / sum(M_i) (paper eq. 40).

    Parameters
    ----------
    angle : ndarray, shape (..., n_mac)
        Rotor angles (rad), machines on the last axis.
    inertia : ndarray, shape (n_mac,)
        Weights M_i = H_i * MVA_i.

    Returns
    -------
    ndarray, shape (...)
        The COI angle (rad).
    """
    return angle @ inertia / inertia.sum()


def coi_speed(speed: np.ndarray, inertia: np.ndarray) -> np.ndarray:
    """COI speed omega_COI = sum(M_i omega_i) / sum(M_i) (paper eq. 40).

    Parameters
    ----------
    speed : ndarray, shape (..., n_mac)
        Rotor speeds (pu), machines on the last axis.
    inertia : ndarray, shape (n_mac,)
        Weights M_i = H_i * MVA_i.

    Returns
    -------
    ndarray, shape (...)
        The COI speed (pu).

    Raises
    ------
    InputError
        `inertia` not one finite weight >= 0 per machine of `speed`'s last axis, or all 0
        (a zero total divided by zero; a negative weight gave a speed outside the
        machines').
    WrongTypeError
        `speed` or `inertia` not numbers (a text; a TypeError and a ValueError).
    """
    try:
        speed, inertia = np.asarray(speed, float), np.asarray(inertia, float)
    except (TypeError, ValueError) as exc:  # a text: "could not convert string to float"
        raise WrongTypeError(
            f"coi_speed: speed and inertia must be arrays of numbers ({exc})"
        ) from None
    if inertia.ndim != 1 or speed.shape[-1:] != inertia.shape:
        raise InputError(
            f"coi_speed: inertia of shape {inertia.shape} for speeds of shape {speed.shape}: "
            "one weight per machine (the speeds' last axis) is needed"
        )
    if not (np.all(np.isfinite(inertia) & (inertia >= 0)) and inertia.sum() > 0):
        raise InputError(
            f"coi_speed: the inertia weights must be finite, >= 0 and not all 0, got {inertia}"
        )
    return coi_angle(speed, inertia)


def coi_of_rest(values: np.ndarray, inertia: np.ndarray, idx, island=None) -> np.ndarray:
    """COI of all machines but one, for each machine of idx: (sum_j M_j x_j - M_i x_i) /
    (sum_j M_j - M_i) (the "rest" COI of `stabctl.storage.BangBangCOI`), j over the
    machines of i's island.

    Parameters
    ----------
    values : ndarray, shape (n_t, n_mac)
        Rotor speeds (pu) or angles (rad).
    inertia : ndarray, shape (n_mac,)
        Weights M_i = H_i * MVA_i.
    idx : array of int, shape (k,)
        Machine indices.
    island : ndarray of int, shape (n_mac,), or None, optional
        Each machine's island (`stabctl.network.topology.machine_islands`); default: one.

    Returns
    -------
    ndarray, shape (n_t, k)
    """
    idx = np.asarray(idx, int)
    island = np.zeros(inertia.size, int) if island is None else np.asarray(island)
    W = (island[idx][:, None] == island[None, :]) * inertia[None, :]  # (k, n_mac)
    return (values @ W.T - values[:, idx] * inertia[idx]) / (W.sum(axis=1) - inertia[idx])
