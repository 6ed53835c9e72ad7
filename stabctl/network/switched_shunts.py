"""Switched shunts (the case's ``switched_shunts``, ``swsh_con``): their levels, the level
they start at and the power flow's discrete control.

A shunt's levels are 0, then group 1's step b1 + j g1 added n1 times, then group 2's n2
times, ...: the cumulative sums.  It starts at the level of its initial susceptance b0,
rounded up between two levels (ANDES 2.0 ``SwBlock.find_sel``); above the last level it
starts at the last, below 0 at 0.  The power flow steps every shunt whose bus voltage is
outside vref +- dv by one level toward the band and solves again until none is (ANDES's
``ShuntAdjust`` in its power flow: one level per Newton iteration once the mismatch is
below 0.01; the same end point, one level at a time).  A dynamic run holds the level the
power flow solved (ANDES switches in its run only on a Newton iteration count its
trapezoidal steps seldom reach: docs/pst_models.md section 15).

Source: ANDES 2.0 ``andes/models/shunt/shuntsw.py``, ``andes/core/service.py`` (SwBlock),
``andes/core/discrete.py`` (ShuntAdjust).
"""

from __future__ import annotations

import numpy as np

from stabctl.case import Case
from stabctl.case.system import SWITCHED_GROUPS, SwitchedShuntTable

__all__ = ["levels", "initial_levels", "admittances", "step", "bus_admittances"]

#: power-flow solutions allowed for the switched shunts to reach their bands
MAX_ROUNDS = 50


def levels(t: SwitchedShuntTable, k: int) -> np.ndarray:
    """The admittance levels g + j b of shunt row k, complex (1 + n1 + ... + n4,)."""
    steps = [0j]
    for j in range(1, SWITCHED_GROUPS + 1):
        n = int(getattr(t, f"n{j}")[k])
        steps += [complex(getattr(t, f"g{j}")[k], getattr(t, f"b{j}")[k])] * n
    return np.cumsum(steps)


def initial_levels(t: SwitchedShuntTable) -> np.ndarray:
    """The level each shunt starts at, int (n,): its b0 rounded up to a level (the last
    above it, 0 below 0)."""
    out = np.zeros(len(t), int)
    for k in range(len(t)):
        b = levels(t, k).imag
        out[k] = min(int(np.searchsorted(b, t.b0[k] - 1e-12 * max(1.0, abs(t.b0[k])))), b.size - 1)
    return out


def admittances(t: SwitchedShuntTable, sel: np.ndarray) -> np.ndarray:
    """g + j b of each shunt at levels ``sel``, complex (n,)."""
    return np.array([levels(t, k)[sel[k]] for k in range(len(t))], complex)


def step(t: SwitchedShuntTable, sel: np.ndarray, v_bus: np.ndarray) -> bool:
    """One level toward the band for every shunt whose bus voltage magnitude (``v_bus``,
    at each shunt's bus, (n,)) is outside vref +- dv and that can move (``sel`` changed in
    place).  Returns True if any moved."""
    top = np.array([levels(t, k).size - 1 for k in range(len(t))], int)
    up = (v_bus < t.vref - t.dv) & (sel < top)
    down = (v_bus > t.vref + t.dv) & (sel > 0)
    sel += up.astype(int) - down.astype(int)
    return bool(np.any(up | down))


def bus_admittances(case: Case, sel: np.ndarray | None = None) -> np.ndarray:
    """The switched shunts' admittance per bus at levels ``sel`` (default: the initial
    ones), complex (n_bus,), system base."""
    t = case.switched_shunts
    y = np.zeros(case.n_bus, complex)
    if len(t):
        sel = initial_levels(t) if sel is None else sel
        np.add.at(y, case.bus_indices(t.bus), admittances(t, sel))
    return y
