"""Switched shunts in a run: the discrete control of ANDES 2.0's ``ShuntSw``
(``andes/core/discrete.py`` ShuntAdjust) on the levels of `stabctl.network.switched_shunts`.

Each shunt keeps two memory slots (`SLOTS`): its level (an index into its levels) and the
delay left before it may step again (s).  At every evaluation, from its bus voltage
magnitude in the network solution: below vref - dv it steps one level up (if it can),
above vref + dv one down, when no delay is left (the network is then solved again with
it); a step sets the delay to dt, which then runs down at 1/s.  The network carries the
shunt's admittance at the level the power flow solved; the kernel draws the difference
(y(level) - y(level0)) V at its kept bus.
As ANDES, except that a run starts with no delay left (ANDES counts the first from t = 0):
a shunt at rest moves no memory.  docs/pst_models.md section 15.
"""

from __future__ import annotations

from stabctl._jit.decorators import kernel
from stabctl.models.declaration import layout, states

__all__ = ["SLOTS", "N_STATES", "M", "PACKED", "S", "switch", "extra_admittance"]

#: the memory slots of a shunt: its level and the delay left (s)
SLOTS = ("level", "delay")
N_STATES = len(SLOTS)
#: the named memory slots, read by the kernels as ``x[M.level, k]``
M = states("ShuntSlots", SLOTS)
#: the packed columns: the bus's position among the kept buses, the band, dt, the top
#: level and the level of the network's admittance (the power flow's)
PACKED = ("POS", "VLO", "VHI", "DT", "TOP", "LEVEL0")
#: the kernels' column of each PACKED name: P[k, S.VLO]
S = layout("ShuntColumns", [(c, c.lower()) for c in PACKED])


@kernel
def switch(P, x, k, v, dx):
    """Shunt k's discrete control at its bus voltage magnitude v (pu): its level stepped
    in place as the module says; dx (N_STATES, n) written (the delay's rate)."""
    lev, left = x[M.level, k], x[M.delay, k]
    if left <= 0.0:
        step = 0.0
        if v < P[k, S.VLO] and lev < P[k, S.TOP]:
            step = 1.0
        elif v > P[k, S.VHI] and lev > 0.0:
            step = -1.0
        if step != 0.0:
            x[M.level, k] = lev + step
            x[M.delay, k] = P[k, S.DT]
    if x[M.delay, k] <= 0.0:
        x[M.delay, k] = 0.0
    dx[M.level, k] = 0.0
    dx[M.delay, k] = -1.0 if x[M.delay, k] > 0.0 else 0.0


@kernel
def extra_admittance(P, Y, x, k):
    """The admittance shunt k draws beyond the network's (its level's less the power
    flow's), complex pu; Y (n, n_levels) its levels."""
    return Y[k, int(x[M.level, k])] - Y[k, int(P[k, S.LEVEL0])]
