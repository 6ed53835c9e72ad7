"""REECD1, the WECC electrical control REEC_D (PSS/E Model Library REECD1; ibr_con ``reec``
3) of a REGCA1 or REGCB1: its DYR record, its named slots, its compensated voltage and its
control kernel (docs/ibr.md 15).

REEC_D is REEC_A (:mod:`.reeca1`, whose columns, blocks and kernel it runs) with: its
voltage control comparing the compensated voltage |V - (Rc + j Xc) I| (VCMPFLAG 1) or |V|
+ Kc Q (VCMPFLAG 0), filtered through Tr1, where REEC_A compares the filtered voltage,
and comparing it with VFLAG 1 too (the Q PI's output its voltage reference, PSS/E's
diagram; ANDES's REEC_A feeds that output to the V PI alone);
ten-point voltage-dependent current limits VDL1 (Iq) and VDL2 (Ip), each ending at its
first point whose voltage is 0 or not above the one before (none if all 0: Imax alone);
the active current range [-Ke Ipmax, Ipmax] (Ke 0 a generator, 1 storage); and blocking:
both commands 0 while the filtered voltage is below Vblkl or above Vblkh and for Tblk s
after.  PSS/E's Vbias is REEC_A's Vref1 (its column).

Sources, where they differ: the record's order is the PSS/E Model Library's as GridPACK's
``reecd1.hpp`` parser reads it (six ICONs PFFLAG, VFLAG, QFLAG, PFLAG, PQFLAG, VCMPFLAG, no
IREG; 77 CONs: REEC_A's 29 with Vbias in Vref1's place, the ten-point tables VDL1 then
VDL2 as (V, I) pairs, then Rc, Xc, Tr1, Kc, Ke, Vblkl, Vblkh, Tblk), InterPSS's
``Reecd1Data`` the same count; the compensation, the table's point count, the Imax bound
of the curves, Ke and the blocking are InterPSS's ``Reecd1Model`` (its blocking compares
with <=, >=; here strictly, as REEC_A's voltage dip).  The rest is REEC_A as stabctl runs
it (ANDES 2.0's reading).  Its own parameters are ibr_con columns 238-270 (``rd_`` and the
points 5-10 of Vq, Iq, Vp, Ip, :mod:`.table`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel, njit
from stabctl.models.blocks import lag
from stabctl.models.converters import reeca1
from stabctl.models.converters.reeca1 import RE, _reec_copies
from stabctl.models.converters.regcb1 import GB
from stabctl.models.converters.table import REECD1, C
from stabctl.models.declaration import DyrModel, slots

if TYPE_CHECKING:
    from stabctl.models.converters import ConverterParams

#: REECD1's ICONs (no IREG: its own bus)
_ICONS = ("PFFLAG", "VFLAG", "QFLAG", "PFLAG", "PQFLAG", "VCMPFLAG")
#: REECD1's CONs in PSS/E order
_CONS = (
    *("Vdip", "Vup", "Trv", "dbd1", "dbd2", "Kqv", "Iqh1", "Iql1", "Vref0", "Iqfrz", "Thld"),
    *("Thld2", "Tp", "QMax", "QMin", "VMAX", "VMIN", "Kqp", "Kqi", "Kvp", "Kvi", "Vbias"),
    *("Tiq", "dPmax", "dPmin", "PMAX", "PMIN", "Imax", "Tpord"),
    *(f"{v}{j}" for pair in (("Vq", "Iq"), ("Vp", "Ip")) for j in range(1, 11) for v in pair),
    *("Rc", "Xc", "Tr1", "Kc", "Ke", "Vblkl", "Vblkh", "Tblk"),
)
#: REECD1's own fields -> ibr_con columns
_OWN = {
    "Vbias": "Vref1",
    **{n: f"rd_{n}" for n in ("VCMPFLAG", "Rc", "Xc", "Tr1", "Kc", "Ke", "Vblkl", "Vblkh")},
    "Tblk": "rd_Tblk",
}

DYR = (
    #: REEC_D: 6 ICONs, 77 CONs
    DyrModel(
        "REECD1",
        _ICONS + _CONS,
        {col: f for col, f in _reec_copies(_ICONS + _CONS).items() if f not in _OWN}
        | {col: f for f, col in _OWN.items()},
    ),
)

#: REECD1's slots (``reec`` 3), after a REGCB1's: its compensated voltage filter, then
#: its memory, the blocking timer
RD = slots("REECD1Slots", ("Vcmp_filter", "Tblk_timer"), first=int(GB[-1]) + 1)
#: the slots of REECD1's memory (`MEMORY_SLOTS` of the package)
MEMORY = (RD.Tblk_timer,)


@njit(cache=True)
def compensated_voltage(flag, Rc, Xc, Kc, v, S):
    """REECD1's compensated voltage at voltage magnitude v with the injected power S = P +
    j Q (pu, system base; the current conj(S)/v in the voltage's frame): |v - (Rc + j Xc)
    conj(S)/v| with flag (VCMPFLAG) 1, v + Kc Q with 0 (v at least 0.01 pu where it
    divides)."""
    if flag == 1.0:
        return abs(v - (Rc + 1j * Xc) * np.conj(S) / max(v, 0.01))
    return v + Kc * S.imag


def initial_voltage(
    reec: np.ndarray, vals: dict, P0: np.ndarray, Q0: np.ndarray, v0: np.ndarray
) -> np.ndarray:
    """The voltage each device's electrical control compares at the start: a REECD1's
    compensated voltage (`compensated_voltage` at P0 + j Q0, |V0|; ``vals`` the
    system-base fields rd_VCMPFLAG, rd_Rc, rd_Xc, rd_Kc), |V0| for the others; arrays of
    shape (n_ibr,)."""
    out = np.asarray(v0, float).copy()
    for k in np.flatnonzero(reec == REECD1):
        args = (vals[f"rd_{n}"][k] for n in ("VCMPFLAG", "Rc", "Xc", "Kc"))
        out[k] = compensated_voltage(*args, v0[k], complex(P0[k], Q0[k]))
    return out


def initial(cp: ConverterParams, x: np.ndarray, v: np.ndarray) -> None:
    """REECD1's initial states in x (N_STATES, n_ibr), in place, at the voltage magnitudes
    v: the compensated voltage filter at its initial value (`initial_voltage`); with
    QFLAG and VFLAG 1 the Q PI's integrator there too (its output, the voltage reference,
    equal to the compensated voltage: the V PI at rest)."""
    vals = {f"rd_{n}": getattr(cp, f"rd_{n}") for n in ("VCMPFLAG", "Rc", "Xc", "Kc")}
    vc0 = initial_voltage(cp.reec, vals, cp.P0, cp.Q0, v)
    d = cp.reec == REECD1
    x[RD.Vcmp_filter] = np.where(d, vc0, 0.0)
    x[RE.PIQ] = np.where(d & (cp.QFLAG == 1) & (cp.VFLAG == 1), vc0, x[RE.PIQ])


@kernel
def control(P, x, k, v, S, ref, wg, dx):
    """REECD1 driving REGCA1 k (arguments and return as `reeca1.control`): the compensated
    voltage through Tr1 (slot Vcmp_filter), REEC_A's control comparing it, then both
    commands 0 while the filtered voltage (slot Vt_filter) is below Vblkl or above Vblkh
    (strict) and for Tblk s after (slot Tblk_timer, `reeca1.extended_event`)."""
    raw = compensated_voltage(
        P[k, C.RD_VCMPFLAG], P[k, C.RD_RC], P[k, C.RD_XC], P[k, C.RD_KC], v, S
    )
    vc, dx[RD.Vcmp_filter, k] = lag(raw, x[RD.Vcmp_filter, k], P[k, C.RD_TR1])
    Ip, Iq = reeca1.control(P, x, k, v, S, ref, wg, vc, dx)
    vt = x[RE.Vt_filter, k]
    out = vt < P[k, C.RD_VBLKL] or vt > P[k, C.RD_VBLKH]
    after = reeca1.extended_event(x, dx, RD.Tblk_timer, k, out, P[k, C.RD_TBLK])
    if out or after:
        return 0.0, 0.0
    return Ip, Iq
