"""PSS/E's PSS2B (pss_con type 6): PSS2A (:mod:`~stabctl.models.pss.pss2a`, whose kernel
it runs) with its inputs limited to [VS1MIN, VS1MAX] and [VS2MIN, VS2MAX] and a third
lead-lag (1 + s T10)/(1 + s T11).  Source: PSS/E Model Library PSS2B; IEEE Std 421.5-2005
section 8.2; OpenIPSL ``Electrical.Controls.PSSE.PSS.PSS2B`` (the same CONs, in PSS/E's
order).
"""

from __future__ import annotations

from stabctl.models.declaration import DyrModel, Limits
from stabctl.models.pss import pss2a

PSS2B = 6
KINDS = {PSS2B: "PSS/E PSS2B"}
#: the third lead time constant T10 (column T5) >= 0 and the input limits ordered (PSS/E
#: Model Library PSS2B; IEEE Std 421.5-2016 PSS2B)
LIMITS = Limits(
    "IEEE Std 421.5 PSS2B",
    nonnegative=("T5",),
    ordered=(("VS1MAX", "VS1MIN"), ("VS2MAX", "VS2MIN")),
)
#: the family refuses a washout T_w below 1e-3 s (`stabctl.models.pss.pss_params`)
NEEDS_TW = True
#: pss_con input1, input2 are PSS/E input codes (else read as 0)
PSSE_INPUTS = True
#: reads the input limits VS1MIN .. VS2MAX (else -inf, +inf)
INPUT_LIMITS = True
#: PSS2B's CONs after PSS2A's first fifteen: the third lead-lag, the input limits, the
#: output limits
MORE = ("T10", "T11", "VS1MAX", "VS1MIN", "VS2MAX", "VS2MIN", "VSTMAX", "VSTMIN")
COPY = {
    **pss2a.COPY,
    "T5": "T10",
    "T6": "T11",
    **{n: n for n in ("VS1MAX", "VS1MIN", "VS2MAX", "VS2MIN")},
}
DYR = (DyrModel("PSS2B", pss2a.ICONS + pss2a.CONS + MORE, COPY, kind=PSS2B),)

S = pss2a.S
STATE_NAMES = {PSS2B: S._fields[: S.leadlag4 + 1]}
check, has_state, time_constants = pss2a.check, pss2a.has_state, pss2a.time_constants
signals, initialise, output = pss2a.signals, pss2a.initialise, pss2a.output
