"""The ``pss_con`` table every stabiliser type reads: its columns (PST manual 3.30 Table
13; PSS/E IEEEST, ST2CUT, STAB2A, PSS2A, PSS2B, PSS2C; docs/pst_models.md section 3), the
packed parameter layout of the compiled kernels (`PACKED`, its named columns `C`) and
the pieces several types share (the PSS/E input codes and their signal, `signal`).

The ``type`` column, the DYR records and the columns only one type reads (its module's
``PARAMS``, after these; packed after `PACKED`, `own`) are declared by the types
themselves (one module per type, :mod:`stabctl.models.pss`); this module is imported by
every one of them.  Many pss_con columns are read under another name by another type
(STAB2A reads K1, Tr1, K2 as its K3, T3, K4; the PSS2 family reads Tr1, Tr2 as its input
lags T6, T7), so the columns are declared here once.
"""

from __future__ import annotations

import functools

from stabctl._jit.decorators import kernel
from stabctl.models.declaration import Param, layout, own_columns

#: PSS/E input codes (IEEEST ICS, ST2CUT MODE, PSS2A/B/C ICS1, ICS2): rotor speed
#: deviation, generator electrical power (machine base)
SPEED, POWER = 1, 3

#: pss_con columns 2-44 (column 1, the type, is declared by the registry from the types).
#: Bounds: every lead and lag time constant >= 0 (IEEE Std 421.5-2016 PSS1A, PSS2A-C;
#: PSS/E Model Library IEEEST, STAB2A), the denominator coefficients A1..A4 of IEEEST's
#: filter >= 0 (a second-order factor 1 + a s + b s^2 with a coefficient below 0 has a pole
#: in the right half plane: the filter is unstable); the gains take either sign (a power
#: input stabiliser's is negative: PST's pss type 2).  What one type's equations need of
#: columns others read otherwise is its module's ``LIMITS``
#: (`stabctl.models.declaration.Limits`), ymax >= ymin every type's (`stabctl.models.pss`)
PARAMS = (
    Param("machine", "code", 2, integer=True, doc="machine number"),
    Param("KTw", "", 3, doc="gain times washout time constant (K*Tw); type 3: washout gain K_w"),
    Param("Tw", "s", 4, lo=0.0, doc="washout time constant (PSS2A/B/C: Tw1)"),
    Param("T1", "s", 5, lo=0.0, doc="first lead time constant"),
    Param("T2", "s", 6, lo=0.0, doc="first lag time constant"),
    Param("T3", "s", 7, lo=0.0, doc="second lead time constant"),
    Param("T4", "s", 8, lo=0.0, doc="second lag time constant"),
    Param("ymax", "pu", 9, doc="maximum output (PSS2A/B/C: VSTMAX)"),
    Param("ymin", "pu", 10, doc="minimum output (PSS2A/B/C: VSTMIN)"),
    Param(
        "T5",
        "s",
        11,
        alt="K5",
        doc="type 3: third lead time constant; PSS2B/C: T10 | type 4: output lag gain K5",
    ),
    Param("T6", "s", 12, lo=0.0, doc="type 3: third lag time constant; PSS2B/C: T11"),
    Param(
        "input1",
        "code",
        13,
        integer=True,
        doc="types 3, 5-7: first input, PSS/E code (1 speed deviation, 3 electrical power)",
    ),
    Param("K1", "", 14, doc="type 3: first input gain; PSS2A/B/C: KS1"),
    Param(
        "Tr1",
        "s",
        15,
        lo=0.0,
        doc="type 3: first input transducer time constant; PSS2A/B/C: T6",
    ),
    Param(
        "input2",
        "code",
        16,
        integer=True,
        doc="types 3, 5-7: second input, PSS/E code (0 none)",
    ),
    Param("K2", "", 17, doc="type 3: second input gain; PSS2A/B/C: KS2"),
    Param(
        "Tr2",
        "s",
        18,
        lo=0.0,
        doc="type 3: second input transducer time constant; PSS2A/B/C: T7",
    ),
    *(
        Param(
            f"A{k}",
            "s" if k % 2 else "s^2",
            18 + k,
            lo=0.0 if k <= 4 else None,
            doc=f"type 3: filter (1 + A5 s + A6 s^2)/((1 + A1 s + A2 s^2)(1 + A3 s + "
            f"A4 s^2)), A{k}",
        )
        for k in range(1, 7)
    ),
    Param(
        "VCU",
        "pu",
        25,
        doc="output cut-off: the output is 0 while the terminal voltage is above VCU "
        "(PSS/E IEEEST, PSS1A VCU; ST2CUT: above VT0 + VCU, cut_relative; 0 none)",
    ),
    Param(
        "VCL",
        "pu",
        26,
        doc="output cut-off: the output is 0 while the terminal voltage is below VCL "
        "(PSS/E IEEEST, PSS1A VCL; ST2CUT: below VT0 + VCL, cut_relative; 0 none)",
    ),
    *(
        Param(name, unit, 27 + i, lo=lo, integer=integer, doc="PSS2A/B/C: " + doc)
        for i, (name, unit, lo, integer, doc) in enumerate(
            (
                ("Tw2", "s", 0.0, False, "second washout of input 1 (< 1e-3 s: none)"),
                ("Tw3", "s", 0.0, False, "first washout of input 2"),
                ("Tw4", "s", 0.0, False, "second washout of input 2 (< 1e-3 s: none)"),
                ("Ks3", "", None, False, "gain of input 2 into the ramp-tracking filter"),
                ("T8", "s", 0.0, False, "ramp-tracking filter lead time constant"),
                ("T9", "s", 0.0, False, "ramp-tracking filter lag time constant"),
                ("M", "", 0.0, True, "ramp-tracking filter: lags per stage"),
                ("N", "", 0.0, True, "ramp-tracking filter: stages (0: no filter)"),
                ("VS1MAX", "pu", None, False, "PSS2B/C: input 1 maximum"),
                ("VS1MIN", "pu", None, False, "PSS2B/C: input 1 minimum"),
                ("VS2MAX", "pu", None, False, "PSS2B/C: input 2 maximum"),
                ("VS2MIN", "pu", None, False, "PSS2B/C: input 2 minimum"),
                ("T12", "s", 0.0, False, "PSS2C: fourth lead time constant"),
                ("T13", "s", 0.0, False, "PSS2C: fourth lag time constant"),
                ("PSSON", "pu", None, False, "PSS2C: power (machine base) switching on"),
                ("PSSOFF", "pu", None, False, "PSS2C: power (machine base) switching off"),
                ("XCOMP", "pu", None, False, "PSS2C: compensated frequency's reactance"),
                ("TCOMP", "s", 0.0, False, "PSS2C: compensated frequency's time constant"),
            )
        )
    ),
)

_NAMES = tuple(p.name for p in PARAMS)
#: pss_con fields the kernels take as given: columns 3-18 (type 3's filter A1..A6 enters
#: as its canonical form nf, fe, fa, fc), then the PSS2 family's columns 27-42 (its input
#: limits enter as in_lo_1 .. in_hi_2: infinite for PSS2A)
TABLE_FIELDS = _NAMES[1:17]
#: the PSS2 family's pss_con fields the kernels take (columns 27-42 but the input limits)
PSS2_FIELDS = _NAMES[25:33] + _NAMES[37:41]
#: packed parameter matrix of the kernels, (column name, PssParams attribute) per
#: column: pss_con columns 1-18 in declared order, the filter (a_0..a_3, c_0..c_3), the
#: output cut-off, then the PSS2 family's columns and input limits
_SUFFIX = {"ymax": "MAX", "ymin": "MIN", "input1": "IN1", "input2": "IN2"}
PACKED = (
    ("KIND", "kind"),
    ("MAC", "mac"),
    *((_SUFFIX.get(n, n.upper()), n) for n in TABLE_FIELDS),
    ("NF", "nf"),
    ("FE", "fe"),
    *((f"FA{i}", f"fa_{i}") for i in range(4)),
    *((f"FC{i}", f"fc_{i}") for i in range(4)),
    ("VCUT_HI", "v_cut_high"),
    ("VCUT_LO", "v_cut_low"),
    *((n.upper(), n) for n in PSS2_FIELDS),
    ("IN1_LO", "in1_lo"),
    ("IN1_HI", "in1_hi"),
    ("IN2_LO", "in2_lo"),
    ("IN2_HI", "in2_hi"),
)
#: the kernels' column of each PACKED name: P[k, C.TW]
C = layout("PssColumns", PACKED)


#: a type's own packed columns (its module's ``PARAMS``, the columns no other type reads),
#: ``own("NAMEColumns", PARAMS)``, read by its kernels as ``P[k, O.NAME]``: after the shared
#: `PACKED`, where every type's own columns start (`own_columns`)
own = functools.partial(own_columns, first=len(PACKED))


@kernel
def signal(code, omega, pe):
    """A PSS/E stabiliser input: speed deviation (pu) or electrical power (code 3), else 0."""
    if code == SPEED:
        return omega - 1.0
    if code == POWER:
        return pe
    return 0.0
