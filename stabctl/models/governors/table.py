"""The ``tg_con`` table every governor type reads: its columns (PST manual 3.45; PSS/E
TGOV1, IEEEG1, HYGOV, IEESGO, GAST, GGOV1, DEGOV; ANDES TG2, HYGOV4; docs/pst_models.md
section 4), the packed parameter layout of the compiled kernels (`PACKED`, its named
columns `G`) and the pieces several types share (the shaft power of the power
fractions, `fractions`; the blocks' numpy-boolean non-windup flag, `AT_LIMIT`).

The ``type`` column, the DYR records and the columns only one type reads (its module's
``PARAMS``, after these; packed after `PACKED`, `own`) are declared by the types
themselves (one module per type, :mod:`stabctl.models.governors`); this module is
imported by every one of them.  Many tg_con columns are read under another name by
another type (HYGOV reads IEEEG1's K1..K6 as its R, r, q_NL, K_g, ...), so the columns
are declared here once.
"""

from __future__ import annotations

import functools

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.models.declaration import Limits, Param, layout, own_columns

#: tg_con columns 17-22 (IEEEG1's K1..K6) as HYGOV reads them: (alternative name, doc)
_HYGOV_ALT = {
    1: ("Rp", " | HYGOV: permanent droop R, pu"),
    2: ("rt", " | HYGOV: temporary droop r, pu"),
    3: ("qNL", " | HYGOV: no-load flow qNL, pu"),
    4: ("Kg", " | HYGOV: gate integrator gain, 1/s (PSS/E: 1/(r Tr))"),
    5: ("velm_rel", " | HYGOV: 1 gate rate limits [-VELM, VELM] - e/r (ANDES), 0 [-VELM, VELM]"),
    6: (
        "psse_gate",
        " | HYGOV: 1 PSS/E's desired gate: the PI (1 + s Tr)/(r Tr s) of e whole, its rate "
        "limited to [-VELM, VELM] and its position non-windup on [GMIN, GMAX] (OpenIPSL's "
        "PSSE.TG.HYGOV), 0 the integral part x_g alone (c = x_g + e/r, ANDES hygov.py)",
    ),
}

#: tg_con columns 2-59 (column 1, the type, is declared by the registry from the types).
#: Bounds (PSS/E Model Library TGOV1, IEEEG1, HYGOV, GAST, IEESGO, DEGOV; PSTess tg.m):
#: the gain 1/R (or K) >= 0, the turbine damping >= 0, the lag time constants >= 0 (the
#: lead constants T3, T4 may be negative: miniWECC's hydro units use T4 = -1), the power
#: fractions K1..K8 (HYGOV's droops, no-load flow and integrator gain) >= 0, GAST's load
#: limit and its gain >= 0, the gate's opening rate Uo >= 0 and closing rate Uc <= 0 (at
#: rest the gate's rate, 0, lies between them; PSS/E IEEEG1: Uo > 0, Uc < 0).  What one
#: type's equations need of columns others read otherwise is its module's ``LIMITS``
#: (`stabctl.models.declaration.Limits`; the speed set point, `AT_RATED_SPEED`); Tmax >=
#: Tmin every type's (the family's common limits, `stabctl.models.governors`)
PARAMS = (
    Param("machine", "code", 2, integer=True, doc="machine number"),
    Param("wf", "pu", 3, doc="speed set point"),
    Param(
        "invR",
        "pu",
        4,
        lo=0.0,
        doc="steady-state gain 1/R (IEEEG1: K; DEGOV: the actuator gain K), on machine base",
    ),
    Param("Tmax", "pu", 5, doc="maximum power order (TGOV1: VMAX, IEEEG1: PMAX, DEGOV: TMAX)"),
    Param(
        "Ts",
        "s",
        6,
        lo=0.0,
        doc="servo time constant (TGOV1: T1; IEEEG1: T3, gate servo; DEGOV: T2)",
    ),
    Param(
        "Tc", "s", 7, lo=0.0, doc="governor lag time constant (TGOV1: T3; IEEEG1: T1; DEGOV: T1)"
    ),
    Param(
        "T3",
        "s",
        8,
        doc="transient gain (lead) time constant (TGOV1, IEEEG1: T2; DEGOV: control-box lead T3)",
    ),
    Param(
        "T4",
        "s",
        9,
        alt="Tw",
        doc="HP section time constant (IEEEG1: T4, steam "
        "chest); < 0 hydro | HYGOV, PIDGOV: water time constant Tw | DEGOV: actuator "
        "lead T4",
    ),
    Param(
        "T5",
        "s",
        10,
        lo=0.0,
        alt="At",
        doc="reheater time constant (IEEEG1: T5; DEGOV: actuator lag T5) | HYGOV: turbine gain At",
    ),
    Param(
        "Tmin",
        "pu",
        11,
        doc="minimum power order (tg: 0 as PST; TGOV1: VMIN; IEEEG1: PMIN; DEGOV: TMIN)",
    ),
    Param("Dt", "pu", 12, lo=0.0, doc="turbine damping (TGOV1), pu power / pu speed"),
    Param("T6", "s", 13, lo=0.0, doc="IEEEG1 third turbine time constant; DEGOV actuator lag T6"),
    Param("T7", "s", 14, lo=0.0, doc="IEEEG1 fourth turbine time constant"),
    Param("Uo", "pu/s", 15, lo=0.0, doc="IEEEG1 maximum valve opening rate"),
    Param("Uc", "pu/s", 16, hi=0.0, doc="IEEEG1 maximum valve closing rate (< 0)"),
    *(
        Param(
            f"K{k}",
            "",
            16 + k,
            lo=0.0,
            alt=_HYGOV_ALT.get(k, ("", ""))[0],
            doc=f"IEEEG1 fraction of power after T{3 + (k + 1) // 2} "
            f"({'HP' if k % 2 else 'LP'} shaft)" + _HYGOV_ALT.get(k, ("", ""))[1],
        )
        for k in range(1, 9)
    ),
    Param("AT", "pu", 25, lo=0.0, doc="GAST ambient temperature load limit"),
    Param("KT", "", 26, lo=0.0, doc="GAST temperature limiter gain"),
    Param(
        "machine2",
        "code",
        27,
        integer=True,
        doc="IEEEG1: machine number of the LP shaft of a cross-compound unit (PSS/E JBUS, "
        "M): K2, K4, K6, K8 drive it; 0 one shaft (every fraction on `machine`)",
    ),
    *(
        # GGOV1's bounds (PSS/E Model Library GGOV1; GE's and WECC's GGOV1 documentation):
        # time constants, gains, droop, rating and deadband >= 0, the opening rates >= 0 and
        # the closing rates <= 0 (a rest point, rate 0, lies between them); "+" marks >= 0,
        # "-" <= 0
        Param(
            name,
            unit,
            28 + i,
            lo=0.0 if sign == "+" else None,
            hi=0.0 if sign == "-" else None,
            doc="GGOV1: " + doc,
        )
        for i, (name, unit, sign, doc) in enumerate(
            (
                (
                    "Rselect",
                    "code",
                    "",
                    "droop feedback: 1 electrical power, 0 none, -1 fuel valve stroke",
                ),
                ("Flag", "code", "", "1 fuel flow proportional to speed, 0 independent of it"),
                ("Rdroop", "pu", "+", "permanent droop R"),
                ("Tpelec", "s", "+", "electrical power transducer time constant"),
                ("maxerr", "pu", "", "maximum speed error"),
                ("minerr", "pu", "", "minimum speed error"),
                ("Kpgov", "pu", "+", "governor proportional gain"),
                ("Kigov", "1/s", "+", "governor integral gain"),
                ("Kdgov", "s", "+", "governor derivative gain"),
                ("Tdgov", "s", "+", "governor derivative time constant"),
                ("Tact", "s", "+", "actuator time constant"),
                ("Kturb", "pu", "+", "turbine gain"),
                ("Wfnl", "pu", "+", "no-load fuel flow"),
                ("Tb", "s", "+", "turbine lag time constant (the lead is Tc, column 7)"),
                ("Teng", "s", "+", "transport delay of a diesel engine (GGOV1 0; DEGOV's TD)"),
                ("Tfload", "s", "+", "load limiter time constant"),
                ("Kpload", "pu", "+", "load limiter proportional gain"),
                ("Kiload", "1/s", "+", "load limiter integral gain"),
                ("Ldref", "pu", "", "load limiter reference"),
                ("Dm", "pu", "+", "speed damping (>= 0)"),
                ("Ropen", "pu/s", "+", "maximum valve opening rate"),
                ("Rclose", "pu/s", "-", "maximum valve closing rate (<= 0)"),
                ("Kimw", "1/s", "", "supplementary load controller gain (0 only)"),
                ("Aset", "pu/s", "", "acceleration limiter set point"),
                ("Kacc", "pu", "+", "acceleration limiter gain Ka"),
                ("Tacc", "s", "+", "acceleration limiter time constant Ta"),
                ("Trate", "MW", "+", "turbine rating (0: the machine's MVA)"),
                ("db", "pu", "+", "speed deadband"),
                ("Tsa", "s", "+", "temperature detection lead time constant"),
                ("Tsb", "s", "+", "temperature detection lag time constant"),
                ("Rup", "pu/s", "+", "maximum rate of the load limit's increase"),
                ("Rdown", "pu/s", "-", "maximum rate of the load limit's decrease (<= 0)"),
            )
        )
    ),
)

_NAMES = tuple(p.name for p in PARAMS)

#: the limits of the types whose speed error is w_f - omega (tg, TGOV1, GAST, TG2, HYGOV4,
#: IEEEG2, IEEEG3): every governor starts at rated speed, omega = 1, with P_ref its
#: initial power order (`stabctl.models.governors.initialise`; PSTess tg.m the same), so a
#: speed set point w_f other than 1 pu starts it off its rest point
AT_RATED_SPEED = Limits(
    "every governor starts at rated speed with P_ref its initial power (PSTess tg.m)",
    one=("wf",),
)
#: HYGOV's fields in tg_con columns 17-22 (alternative names of K1..K6)
HYGOV_FIELDS = ("Rp", "rt", "qNL", "Kg", "velm_rel", "psse_gate")
#: tg_con fields the kernels take as given: columns 3-16 and GAST's 25-26 (the IEEEG1
#: fractions K1..K8 enter summed per shaft stage, K)
TABLE_FIELDS = _NAMES[1:15] + _NAMES[23:25]
#: GGOV1's tg_con fields (columns 28-59)
GGOV1_FIELDS = _NAMES[26:58]
#: packed parameter matrix of the kernels, (column name, GovernorParams attribute) per
#: column: tg_con columns 1-16 in declared order, K's four columns, P_ref, HYGOV's fields,
#: GGOV1's fields and its turbine rating over the machine's MVA
PACKED = (
    ("KIND", "kind"),
    ("MAC", "mac"),
    *((n.upper(), n) for n in TABLE_FIELDS),
    *((f"K{s}", f"K_{i}") for i, s in enumerate("ABCD")),
    ("MAC2", "mac2"),
    *((f"KL{s}", f"K_lp_{i}") for i, s in enumerate("ABCD")),
    ("LP_BASE", "lp_base"),
    ("PREF", "Pref"),
    *((n.upper(), n) for n in HYGOV_FIELDS),
    *((n.upper(), n) for n in GGOV1_FIELDS),
    ("TSCALE", "turbine_scale"),
)
#: the kernels' column of each PACKED name: P[k, G.TS]
G = layout("GovernorColumns", PACKED)


#: a type's own packed columns (its module's ``PARAMS``, the columns no other type reads),
#: ``own("NAMEColumns", PARAMS)``, read by its kernels as ``P[k, O.NAME]``: after the shared
#: `PACKED`, where every type's own columns start (`own_columns`)
own = functools.partial(own_columns, first=len(PACKED))


#: the governors' non-windup rule (`blocks.nonwindup`): at or beyond a limit, always, as
#: a numpy boolean (a Python True from compiled code is typed as a literal, a second
#: compile of the block)
AT_LIMIT = np.bool_(True)


@kernel(inline="always")
def fractions(P, k, y):
    """The IEEEG1/IEESGO shaft power: the lag outputs y (4,) times their fractions."""
    return P[k, G.KA] * y[0] + P[k, G.KB] * y[1] + P[k, G.KC] * y[2] + P[k, G.KD] * y[3]
