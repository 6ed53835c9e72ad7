"""The DG protection of a PVD1 or ESD1 (ibr_con ``relay``): ANDES 2.0's DGPRCT1 (on its bus
voltage) and DGPRCTExt (on the voltage held at its initial value), ``distributed/dgprct.py``
after IEEE 1547-2018's ride-through categories: its named slots and kernels (docs/ibr.md
10).  Its parameters are ibr_con columns 188-213 (``pr_``, :mod:`.table`).
"""

from __future__ import annotations

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.models.blocks import nonwindup
from stabctl.models.converters.pvd1 import PV
from stabctl.models.converters.reeca1 import extended_event
from stabctl.models.converters.table import DGPRCTEXT, C
from stabctl.models.declaration import slots

#: a PVD1's or ESD1's DG protection (``relay``; ANDES DGPRCT1): its nine timers
#: (IntegratorAntiWindup IAWfl1 ... IAWVu2), the reset extension (ExtendedEvent ``res``) and
#: the trip flag (``lock``) in slots 5-15, the memory of its discrete logic (`protection`)
RELAY_SLOTS = (
    *("fl1_timer", "fl2_timer", "fu1_timer", "fu2_timer"),
    *("vl1_timer", "vl2_timer", "vl3_timer", "vu1_timer", "vu2_timer"),
    *("reset_timer", "trip"),
)
#: the named slots, after the PVD1's own (where a REGCA1 has its electrical control's)
PR = slots("RelaySlots", RELAY_SLOTS, first=int(PV[-1]) + 1)

#: the protection timers' limit rule: the IEEE 421.5 annex's (`blocks.nonwindup`), a numpy
#: bool so that the block compiles once for it and a variable (the kernel coding rules)
_ANNEX_RULE = np.bool_(True)


@kernel
def _relay_timer(x, dx, slot, k, e, upper):
    """One protection timer of device k (ANDES IntegratorAntiWindup, T = K = 1, limits
    [0, upper]): the non-windup integrator `blocks.nonwindup` of dy/dt = e, its state held
    in place; returns ANDES's flag zu = (y >= upper and e >= 0) as a float."""
    x[slot, k], dx[slot, k] = nonwindup(x[slot, k], e, 0.0, upper, _ANNEX_RULE, 0.0)
    return 1.0 if x[slot, k] >= upper and e >= 0.0 else 0.0


@kernel
def protection(P, x, k, fHz, v, dx):
    """ANDES 2.0's DGPRCT1 / DGPRCTExt of device k (``distributed/dgprct.py``) at its
    measured frequency fHz (Hz) and bus voltage v (pu; the initial one for DGPRCTExt):
    True while it trips (``lock``).  Each timer integrates its band's flag (`_relay_sum`)
    and runs down at T/Tres while ``res``, the Tres s after a trip ends (ExtendedEvent
    extend_only), from the evaluation where the trip ends; the reset extension and the
    trip flag are the memory slots PR.reset_timer, PR.trip."""
    if P[k, C.RELAY] == DGPRCTEXT:
        v = P[k, C.PR_V0]
    tripped = x[PR.trip, k] == 1.0
    res = 1.0 if x[PR.reset_timer, k] > 0.0 and not tripped else 0.0
    lock = _relay_sum(P, x, k, fHz, v, res, dx) > 0.8  # ANDES: Limiter of dsum at 0.8
    if tripped and not lock:  # the trip ends here: the reset runs from now
        _relay_sum(P, x, k, fHz, v, 1.0, dx)
    tres = P[k, C.PR_TRES]
    extended_event(x, dx, PR.reset_timer, k, lock, tres)
    x[PR.trip, k] = 1.0 if lock else 0.0
    dx[PR.trip, k] = 0.0
    return lock


@kernel
def _relay_sum(P, x, k, fHz, v, res, dx):
    """The protection's timers of device k (derivatives into dx) and ANDES's ``dsum``: over
    the enabled timers, (at T) x (still in its band).  Band flags zi = lower <= u <= upper
    (Limiter equal=False); a timer's input is its band's flag, or -T/Tres while res.  As
    ANDES: the fu2 timer integrates the (fl3, fl2) flag and the vl3 timer the (vl4, vl2)
    flag up to Tvl2 (their gates in the sum are their own bands)."""
    tres = P[k, C.PR_TRES]
    f_lo, f_hi = P[k, C.PR_FL3], P[k, C.PR_FU3]
    v_lo, v_hi = P[k, C.PR_VL4], P[k, C.PR_VU3]
    zf = (
        1.0 if f_lo <= fHz <= P[k, C.PR_FL1] else 0.0,
        1.0 if f_lo <= fHz <= P[k, C.PR_FL2] else 0.0,
        1.0 if P[k, C.PR_FU1] <= fHz <= f_hi else 0.0,
        1.0 if P[k, C.PR_FU2] <= fHz <= f_hi else 0.0,
    )
    zv = (
        1.0 if v_lo <= v <= P[k, C.PR_VL1] else 0.0,
        1.0 if v_lo <= v <= P[k, C.PR_VL2] else 0.0,
        1.0 if v_lo <= v <= P[k, C.PR_VL3] else 0.0,
        1.0 if P[k, C.PR_VU1] <= v <= v_hi else 0.0,
        1.0 if P[k, C.PR_VU2] <= v <= v_hi else 0.0,
    )
    Tf = (P[k, C.PR_TFL1], P[k, C.PR_TFL2], P[k, C.PR_TFU1], P[k, C.PR_TFU2])
    Tv = (P[k, C.PR_TVL1], P[k, C.PR_TVL2], P[k, C.PR_TVL2], P[k, C.PR_TVU1], P[k, C.PR_TVU2])
    fed_f = (zf[0], zf[1], zf[2], zf[1])  # ANDES's IAWfu2 reads Lfl2_zi
    fed_v = (zv[0], zv[1], zv[1], zv[3], zv[4])  # its IAWVl3 reads LVl2_zi, up to Tvl2
    dsum = 0.0
    for j in range(4):
        e = fed_f[j] * (1.0 - res) - Tf[j] / tres * res
        dsum += P[k, C.PR_FEN] * _relay_timer(x, dx, PR.fl1_timer + j, k, e, Tf[j]) * zf[j]
    for j in range(5):
        e = fed_v[j] * (1.0 - res) - Tv[j] / tres * res
        dsum += P[k, C.PR_VEN] * _relay_timer(x, dx, PR.fl1_timer + 4 + j, k, e, Tv[j]) * zv[j]
    return dsum
