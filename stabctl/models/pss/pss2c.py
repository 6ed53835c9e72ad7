"""PSS/E's PSS2C (pss_con type 7): PSS2B (:mod:`~stabctl.models.pss.pss2b`) with a fourth
lead-lag (1 + s T12)/(1 + s T13) and the output logic: the output is switched off when
the machine's electrical power (machine base) falls to PSSOFF or below and on again
when it reaches PSSON (hysteresis; held between the two), on at the start unless the
initial power is at or below PSSOFF.  The switch is a state slot (`S.switch`, 1 on, 0
off; derivative 0) the kernel sets from the power.  XCOMP and TCOMP (the compensated
frequency input) are read and not used: that input is refused.  Source: PSS/E Model
Library PSS2C; IEEE Std 421.5-2016 section 9.4 (P_PSSon, P_PSSoff); PSID's
``pss_models.jl`` (the same switch on the power).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.models.declaration import DyrModel, Limits
from stabctl.models.pss import pss2a, pss2b
from stabctl.models.pss.table import C

if TYPE_CHECKING:
    from stabctl.models.pss import PssParams

PSS2C = 7
KINDS = {PSS2C: "PSS/E PSS2C"}
#: PSS2B's limits, and the output logic's switching-on power at or above its switching-off
#: power (a hysteresis; PSS/E Model Library PSS2C; IEEE Std 421.5-2016 PSS2C)
LIMITS = Limits(
    "IEEE Std 421.5 PSS2C",
    nonnegative=("T5",),
    ordered=(("VS1MAX", "VS1MIN"), ("VS2MAX", "VS2MIN"), ("PSSON", "PSSOFF")),
)
#: the family refuses a washout T_w below 1e-3 s (`stabctl.models.pss.pss_params`)
NEEDS_TW = True
#: pss_con input1, input2 are PSS/E input codes (else read as 0)
PSSE_INPUTS = True
#: reads the input limits VS1MIN .. VS2MAX (else -inf, +inf)
INPUT_LIMITS = True
#: PSS2C's CONs after PSS2B's: the fourth lead-lag, the output logic's powers, the
#: compensated frequency's reactance and time constant
MORE = ("T12", "T13", "PSSON", "PSSOFF", "XCOMP", "TCOMP")
COPY = {**pss2b.COPY, **{n: n for n in MORE}}
DYR = (DyrModel("PSS2C", pss2a.ICONS + pss2a.CONS + pss2b.MORE + MORE, COPY, kind=PSS2C),)

S = pss2a.S
STATE_NAMES = {PSS2C: S._fields}
check, has_state, time_constants = pss2a.check, pss2a.has_state, pss2a.time_constants
signals = pss2a.signals


def initialise(p: PssParams, r, u1, u2, pe0, x):
    """PSS2A's rest (`pss2a.initialise`) and the switch: on unless the initial power
    pe0 (machine base) is at or below PSSOFF."""
    pss2a.initialise(p, r, u1, u2, pe0, x)
    x[S.switch, r] = np.where(pe0[r] <= p.PSSOFF[r], 0.0, 1.0)


@kernel(inline="always")
def output(P, x, k, omega, pe, dx):
    """PSS2C: the PSS2 chain (`pss2a.output`) times the switch, which turns off at pe <=
    PSSOFF and on at pe >= PSSON (its state in x set here, derivative 0)."""
    y = pss2a.output(P, x, k, omega, pe, dx)
    if pe >= P[k, C.PSSON]:
        x[S.switch, k] = 1.0
    elif pe <= P[k, C.PSSOFF]:
        x[S.switch, k] = 0.0
    dx[S.switch, k] = 0.0
    return y * x[S.switch, k]
