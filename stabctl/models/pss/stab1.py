"""PSS/E's STAB1 (read as PST's `pss` type 1, :mod:`~stabctl.models.pss.pst`).

STAB1: the speed deviation through K s/(1 + s T) (the record gives the high-frequency
gain K/T), lead-lags (1 + s T1)/(1 + s T3) and (1 + s T2)/(1 + s T4) (the record gives
T1/T3 and T2/T4), limited to [-HLIM, HLIM].  That is PST's pss on the speed exactly
(washout K_Tw s/(1 + s T_w) with K_Tw = (K/T) T, T_w = T; its lead-lags T1/T2 and T3/T4
of pss_con are STAB1's (T1/T3) T3 over T3 and (T2/T4) T4 over T4): the mapper in
`stabctl.io.dyr` computes those columns, and the run is PST's kernel.  Source: PSS/E
Model Library STAB1; PowerSimulationsDynamics.jl ``pss_models.jl`` (the same
equations).  This module holds the record only: it claims no pss_con type.
"""

from __future__ import annotations

from stabctl.models.declaration import DyrModel
from stabctl.models.pss.pst import PST_SPEED

KINDS: dict[int, str] = {}
#: STAB1 -> PST pss type 1: K_Tw, T1, T3 and ymin computed by the mapper
DYR = (
    DyrModel(
        "STAB1",
        ("K_T", "T", "T1_T3", "T3", "T2_T4", "T4", "HLIM"),
        {"Tw": "T", "T2": "T3", "T4": "T4", "ymax": "HLIM"},
        kind=PST_SPEED,
    ),
)
STATE_NAMES: dict[int, tuple[str, ...]] = {}
