"""PLL1, the phase-locked loop whose angle a REGCA1 reads (ibr_con ``pll`` 1; ANDES 2.0
``measurement/pll.py`` PLL1, with ``renewable/regcp1.py``): its named slots, initial
states and kernels (docs/ibr.md 9).  Its parameters are ibr_con columns 184-187
(``pll_``, :mod:`.table`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.models.blocks import pi
from stabctl.models.converters.table import NO_PLL, PLL1, C
from stabctl.models.converters.wind import WT
from stabctl.models.declaration import slots

if TYPE_CHECKING:
    from stabctl.models.converters import ConverterParams


#: the PLL1's slots (``pll`` 1; ANDES measurement/pll.py): the filtered bus angle, the PI's
#: integrator, the estimated angle and the measured angle (rad)
PLL_SLOTS = ("af_pll", "PI_pll", "ae_pll", "am_pll")
#: the named slots, after the wind turbine's
PL = slots("PLLSlots", PLL_SLOTS, first=int(WT[-1]) + 1)


def initial(cp: ConverterParams, x: np.ndarray, V: np.ndarray) -> None:
    """The PLL1s' initial states in x (N_STATES, n_ibr), in place, at their bus voltages V
    (n_ibr,) complex: the angles at the bus's, the PI at 0."""
    for slot in (PL.af_pll, PL.ae_pll, PL.am_pll):  # the PLL's angles at the bus's, its PI at 0
        x[slot] = np.where(cp.pll == PLL1, np.angle(V), 0.0)


@kernel
def frame(P, x, k, V):
    """exp(j (a - am)) of device k at its bus voltage V: the rotation from the PLL1's
    frame (measured angle am) to the bus's (angle a); 1 without a PLL (ANDES regcp1.py:
    Vd = |V| cos(a - am), Vq = -|V| sin(a - am))."""
    if P[k, C.PLL] == NO_PLL:
        return 1.0 + 0.0j
    v = abs(V)
    if v == 0.0:
        return 1.0 + 0.0j
    return V / v * np.exp(-1j * x[PL.am_pll, k])


@kernel
def derivatives(P, x, k, V, dx):
    """PLL1's derivatives of device k at its bus voltage V (ANDES 2.0 measurement/pll.py
    PLL1): the bus angle a through the lag Tf (af), the PI on af - am (Kp, Ki; ANDES's
    PIController, `blocks.pi`), the estimated angle ae' = 2 pi fn PI_y and the measured
    angle am the lag Tp of ae; a taken within pi of am (ANDES's bus angle is not wrapped);
    nothing without a PLL."""
    for j in range(len(PLL_SLOTS)):
        dx[PL.af_pll + j, k] = 0.0
    if P[k, C.PLL] == NO_PLL:
        return
    am = x[PL.am_pll, k]
    a = am + np.angle(V * np.exp(-1j * am)) if V != 0.0 else x[PL.af_pll, k]
    dx[PL.af_pll, k] = (a - x[PL.af_pll, k]) / P[k, C.PLL_TF]
    e = x[PL.af_pll, k] - am
    y, dx[PL.PI_pll, k] = pi(e, x[PL.PI_pll, k], P[k, C.PLL_KP], P[k, C.PLL_KI])
    dx[PL.ae_pll, k] = 2.0 * np.pi * P[k, C.FN] * y
    dx[PL.am_pll, k] = (x[PL.ae_pll, k] - am) / P[k, C.PLL_TP]
