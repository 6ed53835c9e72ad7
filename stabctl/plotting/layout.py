"""Coordinates for drawing a network: buses placed by the spectrum of the weighted graph."""

from __future__ import annotations

import numpy as np

from stabctl.case import Case


def spectral_layout(case: Case) -> np.ndarray:
    """Bus coordinates (n_bus, 2) for drawing: the two Laplacian eigenvectors after the
    constant one, of the graph weighted by branch susceptance magnitude (electrically close
    buses are drawn close)."""
    n = case.n_bus
    f, t = case.bus_indices(case.branches.from_bus), case.bus_indices(case.branches.to_bus)
    w = 1.0 / np.maximum(np.abs(case.branches.x), 1e-4)
    W = np.zeros((n, n))
    np.add.at(W, (f, t), w)
    np.add.at(W, (t, f), w)
    L = np.diag(W.sum(axis=1)) - W
    D = np.sqrt(np.maximum(W.sum(axis=1), 1e-12))
    _, vec = np.linalg.eigh(L / D[:, None] / D[None, :])
    return vec[:, 1:3] / D[:, None]
