"""Turbine-governors: PST `tg` (type 1), the PSS/E models TGOV1 (type 2), IEEEG1
(type 3), HYGOV (type 4), IEESGO (type 5) and GAST (type 6), and ANDES's TG2 (type 7)
and HYGOV4 (type 8).

Sources: PSTess 1.1 `tg_indx.m`, `tg.m` (docs/pst_models.md section 4); PSS/E Model
Library `TGOV1`, `IEEEG1` (IEEE Committee Report 1973 steam turbine model), as
implemented in ANDES (`andes/models/governor/tgov1.py`, `ieeeg1.py`, `hygov.py`,
`ieesgo.py`, `gast.py`); equations in docs/pst_models.md section 4.1-4.4.

tg: demand = clip(P_ref + (w_f - omega)/R, Tmin, T_max) -> 1/(1 + s T_s)
-> (1 + s T_3)/(1 + s T_c) -> (1 + s T_4)/(1 + s T_5) -> pmech (machine base).  T_4 may
be negative (hydro).  TGOV1: P_ref + (w_f - omega)/R -> 1/(1 + s T1) non-windup [VMIN,
VMAX] -> (1 + s T2)/(1 + s T3) -> minus Dt (omega - 1).  IEEEG1: K (1 + s T2)/(1 + s T1)
on the speed deviation, gate servo 1/T3 with rate limits [Uc, Uo] and position limits
[PMIN, PMAX], four lags T4..T7, power fractions K1..K8 (HP + LP summed: one shaft).
HYGOV (machine base): filter T_f on e = P_ref - (omega - 1) - R c, desired gate c = x_g +
e/r with the gate integrator dx_g/dt = K_g e (PSS/E: K_g = 1/(r T_r)) rate-limited to
[-VELM, VELM] (ANDES: minus e/r) and held in [GMIN, GMAX], gate g = c/(1 + s T_g), water
column T_w dq/dt = 1 - (q/g)^2, pmech = A_t (q/g)^2 (q - q_NL) - D_turb (omega - 1) g.
IEESGO: K_1 (omega - 1) through 1/(1 + s T_1) and (1 + s T_2)/(1 + s T_3), P_ref minus it
limited to [PMIN, PMAX], lags T_4, T_5, T_6, pmech = (1 - K_2) y_4 + (1 - K_3) K_2 y_5 +
K_2 K_3 y_6 (the IEEEG1 fraction columns K1, K3, K5).  GAST: min(P_ref + (w_f - omega)/R,
AT + KT (AT - y_3)) -> 1/(1 + s T1) non-windup [VMIN, VMAX] -> 1/(1 + s T2) = y_2 ->
minus D_turb (omega - 1); y_3 = y_2/(1 + s T3).  TG2 (ANDES 2.0 ``governor/tg2.py``, not a
PSS/E model; its deadband off, ANDES's default): pmech = clip(P_ref + (1 + s T1)/(1 + s
T2) of (w_f - omega)/R, pmin, pmax), the limit on the output without windup (a hard
limiter).  HYGOV4 (ANDES 2.0 ``governor/hygov4.py``: PSS/E's HYGOV4 without its deadbands
and gate-power curve; machine base, head at the dam 1): the error P_ref - (omega - w_f) -
R_perm g - R_temp T_r s/(1 + s T_r) g (the dashpot) through the pilot servo 1/(1 + s T_p),
the gate speed 1/T_g times it limited to [U_C, U_O], the gate integrator non-windup on
[PMIN, PMAX]; water column and power as HYGOV's.
States: up to N_STATES slots per governor (the most any type present uses), named per
type in STATE_NAMES; slots a type does not use stay 0 (`has_state`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.errors import CaseError, refuse_initial
from stabctl.models.blocks import LBND, clip, lag, leadlag, nonwindup, nonwindup_lag
from stabctl.models.declaration import (
    Declared,
    DyrModel,
    Family,
    Param,
    beyond,
    check_packed,
    layout,
    pack,
    params_class,
)

if TYPE_CHECKING:
    from stabctl.case import Case


# --------------------------------------------------------------------------------------
# tg_con: turbine-governors (PST manual 3.45; PSS/E TGOV1, IEEEG1; docs section 4)
# --------------------------------------------------------------------------------------

#: tg_con columns 17-21 (IEEEG1's K1..K5) as HYGOV reads them: (alternative name, doc)
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

GOVERNOR = Family(
    table="tg_con",
    min_columns=10,
    key="machine",
    key_label="machine",
    params=(
        Param(
            "type",
            "code",
            1,
            integer=True,
            choices=(1, 2, 3, 4, 5, 6, 7, 8),
            label="governor type",
            doc="1 PST tg, 2 TGOV1, 3 IEEEG1, 4 HYGOV, 5 IEESGO, 6 GAST, 7 TG2 (ANDES), "
            "8 HYGOV4 (ANDES)",
        ),
        Param("machine", "code", 2, integer=True, doc="machine number"),
        Param("wf", "pu", 3, doc="speed set point"),
        Param("invR", "pu", 4, doc="steady-state gain 1/R (IEEEG1: K), on machine base"),
        Param("Tmax", "pu", 5, doc="maximum power order (TGOV1: VMAX, IEEEG1: PMAX)"),
        Param("Ts", "s", 6, lo=0.0, doc="servo time constant (TGOV1: T1; IEEEG1: T3, gate servo)"),
        Param("Tc", "s", 7, lo=0.0, doc="governor lag time constant (TGOV1: T3; IEEEG1: T1)"),
        Param("T3", "s", 8, doc="transient gain (lead) time constant (TGOV1, IEEEG1: T2)"),
        Param(
            "T4",
            "s",
            9,
            alt="Tw",
            doc="HP section time constant (IEEEG1: T4, steam "
            "chest); < 0 hydro | HYGOV: water time constant Tw",
        ),
        Param(
            "T5",
            "s",
            10,
            lo=0.0,
            alt="At",
            doc="reheater time constant (IEEEG1: T5) | HYGOV: turbine gain At",
        ),
        Param(
            "Tmin", "pu", 11, doc="minimum power order (tg: 0 as PST; TGOV1: VMIN; IEEEG1: PMIN)"
        ),
        Param("Dt", "pu", 12, doc="turbine damping (TGOV1), pu power / pu speed"),
        Param("T6", "s", 13, lo=0.0, doc="IEEEG1 third turbine time constant"),
        Param("T7", "s", 14, lo=0.0, doc="IEEEG1 fourth turbine time constant"),
        Param("Uo", "pu/s", 15, doc="IEEEG1 maximum valve opening rate"),
        Param("Uc", "pu/s", 16, doc="IEEEG1 maximum valve closing rate (< 0)"),
        *(
            Param(
                f"K{k}",
                "",
                16 + k,
                alt=_HYGOV_ALT.get(k, ("", ""))[0],
                doc=f"IEEEG1 fraction of power after T{3 + (k + 1) // 2} "
                f"({'HP' if k % 2 else 'LP'} shaft)" + _HYGOV_ALT.get(k, ("", ""))[1],
            )
            for k in range(1, 9)
        ),
        Param("AT", "pu", 25, doc="GAST ambient temperature load limit"),
        Param("KT", "", 26, doc="GAST temperature limiter gain"),
        Param(
            "machine2",
            "code",
            27,
            integer=True,
            doc="IEEEG1: machine number of the LP shaft of a cross-compound unit (PSS/E JBUS, "
            "M): K2, K4, K6, K8 drive it; 0 one shaft (every fraction on `machine`)",
        ),
    ),
    dyr=(
        # TGOV1: invR = 1/R is computed
        DyrModel(
            "TGOV1",
            ("R", "T1", "VMAX", "VMIN", "T2", "T3", "Dt"),
            {"Tmax": "VMAX", "Tmin": "VMIN", "Ts": "T1", "Tc": "T3", "T3": "T2", "Dt": "Dt"},
            kind=2,
            andes=("TGOV1", "TGOV1N"),
        ),
        DyrModel(
            "IEEEG1",
            (
                "JBUS",
                "M",
                "K",
                "T1",
                "T2",
                "T3",
                "Uo",
                "Uc",
                "PMAX",
                "PMIN",
                "T4",
                "K1",
                "K2",
                "T5",
                "K3",
                "K4",
                "T6",
                "K5",
                "K6",
                "T7",
                "K7",
                "K8",
            ),
            {
                "invR": "K",
                "Tc": "T1",
                "T3": "T2",
                "Ts": "T3",
                "Uo": "Uo",
                "Uc": "Uc",
                "Tmax": "PMAX",
                "Tmin": "PMIN",
                "T4": "T4",
                "T5": "T5",
                "T6": "T6",
                "T7": "T7",
                **{f"K{k}": f"K{k}" for k in range(1, 9)},
            },
            kind=3,
            andes=("IEEEG1",),
        ),
        # HYGOV -> type 4: Kg = 1/(r Tr) and Uc = -VELM computed
        DyrModel(
            "HYGOV",
            ("R", "r", "Tr", "Tf", "Tg", "VELM", "GMAX", "GMIN", "TW", "At", "Dturb", "qNL"),
            {
                "Rp": "R",
                "rt": "r",
                "T3": "Tr",
                "Tc": "Tf",
                "Ts": "Tg",
                "Uo": "VELM",
                "Tmax": "GMAX",
                "Tmin": "GMIN",
                "Tw": "TW",
                "At": "At",
                "Dt": "Dturb",
                "qNL": "qNL",
            },
            kind=4,
            # HYGOVDB: HYGOV with a speed deadband, read where the band is empty
            # (stabctl.io.andes_case refuses others)
            andes=("HYGOV", "HYGOVDB"),
        ),
        # IEESGO -> type 5: K1 (speed gain), lag T1, lead-lag T2/T3, limits, lags T4-T6;
        # the power fractions after T4, T5, T6 (1 - K2, (1 - K3) K2, K2 K3) computed
        DyrModel(
            "IEESGO",
            ("T1", "T2", "T3", "T4", "T5", "T6", "K1", "K2", "K3", "PMAX", "PMIN"),
            {
                "Tc": "T1",
                "T3": "T2",
                "Ts": "T3",
                "T4": "T4",
                "T5": "T5",
                "T6": "T6",
                "invR": "K1",
                "Tmax": "PMAX",
                "Tmin": "PMIN",
            },
            kind=5,
            andes=("IEESGO",),
        ),
        # GAST -> type 6: invR = 1/R is computed; T1 the valve (Ts), T2 the power lag (Tc), T3
        # the load-limit feedback lag
        DyrModel(
            "GAST",
            ("R", "T1", "T2", "T3", "AT", "KT", "VMAX", "VMIN", "Dturb"),
            {
                "Ts": "T1",
                "Tc": "T2",
                "T3": "T3",
                "AT": "AT",
                "KT": "KT",
                "Tmax": "VMAX",
                "Tmin": "VMIN",
                "Dt": "Dturb",
            },
            kind=6,
            andes=("GAST",),
        ),
        # TG2 (ANDES's own, read by name from ANDES; no PSS/E record of that name in the
        # Model Library) -> type 7: invR = 1/R, the lead-lag T1/T2, the output limits
        DyrModel(
            "TG2",
            ("R", "wref0", "pmax", "pmin", "T1", "T2"),
            {"wf": "wref0", "Tmax": "pmax", "Tmin": "pmin", "T3": "T1", "Tc": "T2"},
            kind=7,
            andes=("TG2",),
        ),
        # ANDES's HYGOV4 -> type 8, its parameters by name (ANDES maps no PSS/E record onto
        # it, and PSS/E's HYGOV4 record, with deadbands and a gate-power curve, is another
        # model: a DYR file's HYGOV4 is refused as not mapped); T_p the pilot servo (Tc),
        # T_g (Ts), T_r the dashpot (T3), T_w (T4), A_t (T5), gate limits (Tmin, Tmax)
        DyrModel(
            "ANDES_HYGOV4",
            ("wref0", "Rperm", "Rtemp", "UO", "UC", "PMAX", "PMIN", "Tp", "Tg", "Tr", "Tw")
            + ("At", "Dturb", "qNL"),
            {
                "wf": "wref0",
                "Rp": "Rperm",
                "rt": "Rtemp",
                "Uo": "UO",
                "Uc": "UC",
                "Tmax": "PMAX",
                "Tmin": "PMIN",
                "Tc": "Tp",
                "Ts": "Tg",
                "T3": "Tr",
                "Tw": "Tw",
                "At": "At",
                "Dt": "Dturb",
                "qNL": "qNL",
            },
            kind=8,
            andes=("HYGOV4",),
        ),
    ),
)

TG, TGOV1, IEEEG1, HYGOV, IEESGO, GAST, TG2, HYGOV4 = 1, 2, 3, 4, 5, 6, 7, 8
N_STATES = 6
STATE_NAMES = {
    TG: ("servo", "transient", "turbine"),
    TGOV1: ("valve", "leadlag"),
    IEEEG1: ("leadlag", "gate", "T4lag", "T5lag", "T6lag", "T7lag"),
    HYGOV: ("filter", "gate_integrator", "gate", "flow"),
    IEESGO: ("lag", "leadlag", "T4lag", "T5lag", "T6lag"),
    GAST: ("valve", "T2lag", "T3lag"),
    TG2: ("leadlag",),
    HYGOV4: ("pilot", "gate", "dashpot", "flow"),
}
#: HYGOV's fields in tg_con columns 17-21 (alternative names of K1..K5)
HYGOV_FIELDS = ("Rp", "rt", "qNL", "Kg", "velm_rel", "psse_gate")
#: tg_con fields (stabctl.models.governors.GOVERNOR) the kernels take as given: columns 3-16
#: and GAST's 25-26 (the IEEEG1 fractions K1..K8 enter summed per shaft stage, K)
TABLE_FIELDS = GOVERNOR.names[2:16] + GOVERNOR.names[24:26]
#: packed parameter matrix of the kernels, (column name, GovernorParams attribute) per
#: column: tg_con columns 1-16 in declared order, K's four columns, P_ref, HYGOV's fields
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
)
#: the kernels' column of each PACKED name: P[k, G.TS]
G = layout("GovernorColumns", PACKED)


@params_class(("kind", "mac"), TABLE_FIELDS)
class GovernorParams(Declared):
    """Governor data, arrays of shape (n_tg,): ``kind`` the tg_con type, ``mac`` the
    machine's row (index), the tg_con fields :data:`TABLE_FIELDS` under their declared
    names (stabctl.models.governors.GOVERNOR); K (n_tg, 4): IEEEG1 (and IEESGO) K1+K2, K3+K4,
    K5+K6, K7+K8, or a cross-compound IEEEG1's HP fractions K1, K3, K5, K7, whose LP
    fractions K2, K4, K6, K8 are K_lp (n_tg, 4; 0 otherwise) driving machine row mac2 (-1
    none) with its power times lp_base (the HP machine's MVA over the LP machine's); Rp,
    rt, qNL, Kg, velm_rel, psse_gate: HYGOV's columns 17-22 (0 for other types; T4 is its
    T_w, T5 its A_t)."""

    K: np.ndarray
    mac2: np.ndarray
    K_lp: np.ndarray
    lp_base: np.ndarray
    Rp: np.ndarray
    rt: np.ndarray
    qNL: np.ndarray
    Kg: np.ndarray
    velm_rel: np.ndarray
    psse_gate: np.ndarray

    @property
    def n(self) -> int:
        return self.mac.size

    def packed(self, Pref: np.ndarray) -> np.ndarray:
        """Parameter matrix (n_tg, len(PACKED)) for the compiled kernels, with P_ref, columns
        as :data:`PACKED`."""
        return pack(
            self,
            PACKED,
            Pref=Pref,
            **{f"K_{i}": self.K[:, i] for i in range(4)},
            **{f"K_lp_{i}": self.K_lp[:, i] for i in range(4)},
        )

    def n_slots(self) -> int:
        """State slots per governor: the most any governor of the case uses (3 if none)."""
        return max([2, *(len(STATE_NAMES[int(k)]) for k in self.kind)]) if self.n else 3

    def has_state(self) -> np.ndarray:
        """Boolean (n_slots, n_tg): the slots that are states of each governor."""
        act = np.zeros((N_STATES, self.n), bool)
        tg, t1, g1 = self.kind == TG, self.kind == TGOV1, self.kind == IEEEG1
        hy, sg = self.kind == HYGOV, self.kind == IEESGO
        act[:3] |= tg
        act[:2] |= t1
        act[0] |= g1 & (self.Tc >= LBND)
        act[1] |= g1
        for r, T in zip(range(2, 6), (self.T4, self.T5, self.T6, self.T7)):
            act[r] |= g1 & (T >= LBND)
        act[:4] |= hy | (self.kind == HYGOV4)
        act[0] |= sg & (self.Tc >= LBND)
        act[1] |= sg & (self.Ts >= LBND)
        for r, T in zip(range(2, 5), (self.T4, self.T5, self.T6)):
            act[r] |= sg & (T >= LBND)
        ga = self.kind == GAST
        act[0] |= ga
        act[1] |= ga & (self.Tc >= LBND)
        act[2] |= ga & (self.T3 >= LBND)
        act[0] |= self.kind == TG2
        return act[: self.n_slots()]

    def time_constants(self):
        """(label, values, mask) of every time constant that sets a state's speed."""
        tg, t1, g1 = self.kind == TG, self.kind == TGOV1, self.kind == IEEEG1
        hy, sg = self.kind == HYGOV, self.kind == IEESGO
        lag = {
            name: (g1 | sg) & (getattr(self, name) >= LBND)
            for name in ("Tc", "Ts", "T4", "T5", "T6", "T7")
        }
        ga, h4 = self.kind == GAST, self.kind == HYGOV4
        return (
            ("tg_con T_s", self.Ts, tg | t1 | g1 | hy | ga | lag["Ts"]),
            (
                "tg_con T_c",
                self.Tc,
                tg | t1 | hy | h4 | lag["Tc"] | (ga & (self.Tc >= LBND)) | (self.kind == TG2),
            ),
            ("tg_con T_3", self.T3, h4 | (ga & (self.T3 >= LBND))),
            ("tg_con T_5", self.T5, tg | lag["T5"]),
            ("tg_con T_4", self.T4, hy | h4 | lag["T4"]),
            ("tg_con T_6", self.T6, lag["T6"]),
            ("tg_con T_7", self.T7, lag["T7"] & g1),
        )


check_packed(
    GovernorParams,
    PACKED,
    ("Pref", *(f"K_{i}" for i in range(4)), *(f"K_lp_{i}" for i in range(4))),
)


def governor_params(case: Case) -> GovernorParams:
    """Governor parameters.

    Raises CaseError (tg_con row, field) for a time constant the model needs below 1e-3 s
    (tg: Ts, Tc, T5; TGOV1: T1 = Ts, T3 = Tc; IEEEG1: T3 = Ts; HYGOV: T_g = Ts, T_f = Tc,
    T_w = T4; TG2: T2 = Tc: a lag below it would be absent, `blocks.LBND`), a zero HYGOV
    r = K2, or an IEEEG1 without power fractions."""
    g = case.governors
    need = {
        TG: ("Ts", "Tc", "T5"),
        TGOV1: ("Ts", "Tc"),
        IEEEG1: ("Ts",),
        HYGOV: ("Ts", "Tc", "T4"),
        IEESGO: (),
        GAST: ("Ts",),
        TG2: ("Tc",),
        HYGOV4: ("Ts", "Tc", "T3", "T4"),
    }
    for r in range(len(g)):
        for name in need[int(g.type[r])]:
            if getattr(g, name)[r] < LBND:
                raise CaseError(
                    f"tg_con row {r + 1}, field '{name}': must be >= {LBND} s for "
                    f"governor type {int(g.type[r])}"
                )
        if g.type[r] == HYGOV and g.K2[r] == 0:
            raise CaseError(
                f"tg_con row {r + 1}, field 'K2': must be non-zero for governor type {HYGOV}"
            )
    K = np.column_stack([g.K1 + g.K2, g.K3 + g.K4, g.K5 + g.K6, g.K7 + g.K8]).reshape(len(g), 4)
    bad = np.nonzero((g.type == IEEEG1) & (K.sum(axis=1) <= 0))[0]
    cross = (g.type == IEEEG1) & (g.machine2 != 0)
    K_hp = np.column_stack([g.K1, g.K3, g.K5, g.K7]).reshape(len(g), 4)
    K_lp = np.column_stack([g.K2, g.K4, g.K6, g.K8]).reshape(len(g), 4)
    mac2 = _lp_machines(case, g, cross)
    mac = np.array([case.machine_index(m) for m in g.machine], int)
    mva = case.machines.mva
    if bad.size:
        raise CaseError(
            f"tg_con row {bad[0] + 1}, fields 'K1'..'K8': IEEEG1 power fractions must sum to > 0"
        )
    hy = (g.type == HYGOV) | (g.type == HYGOV4)
    return GovernorParams(
        kind=g.type.astype(int),
        mac=mac,
        **{n: getattr(g, n).copy() for n in TABLE_FIELDS},
        K=np.where(hy[:, None], 0.0, np.where(cross[:, None], K_hp, K)),
        mac2=mac2,
        K_lp=np.where(cross[:, None], K_lp, 0.0),
        lp_base=np.where(cross, mva[mac] / mva[np.maximum(mac2, 0)], 0.0),
        **{n: np.where(hy, g.col(17 + i), 0.0) for i, n in enumerate(HYGOV_FIELDS)},
    )


def _lp_machines(case: Case, g, cross) -> np.ndarray:
    """The LP machines' rows of the cross-compound IEEEG1 (-1 for the others); raises
    CaseError for an unknown machine, the unit's own machine, or one with a governor of
    its own."""
    mac2 = np.full(len(g), -1, int)
    own = set(int(m) for m in g.machine)
    for r in np.nonzero(cross)[0]:
        number = int(g.machine2[r])
        if number == int(g.machine[r]) or number in own:
            raise CaseError(
                f"tg_con row {r + 1}, field 'machine2': machine {number} is the unit's own "
                "or has a governor of its own"
            )
        mac2[r] = case.machine_index(number)
    return mac2


def initialise(p: GovernorParams, pmech0, pmech0_lp=None):
    """States (n_slots, n_tg) and P_ref (n_tg,) from the initial mechanical power pmech0
    (machine base) at rated speed: every lag at its input, lead-lag states at
    (1 - T_lead/T_lag) times their input.  P_ref is the power order (tg, TGOV1), the
    gate position (IEEEG1, IEESGO: pmech0 / sum K; a cross-compound IEEEG1: its two
    machines' power, pmech0_lp the LP machine's on its base, over the sum of all eight
    fractions) or R q_0 (HYGOV: flow, gate and gate integrator at q_0 = pmech0/A_t +
    q_NL, head 1; HYGOV4: R_perm q_0, its gate and flow at q_0).

    Raises CaseError when the initial power order is outside [Tmin, Tmax] (PST's check
    for tg, the non-windup limits for TGOV1 and IEEEG1), GAST's initial power above its
    load limit AT + KT (AT - Pm0) (PSS/E's own GAST run starts on it, AT = Pm0 = 1), or
    a cross-compound unit's machines do not share its power as its HP and LP fractions
    do (ANDES 2.0 ieeeg1.py's ``_Pc`` check), beyond `START_LIMIT_TOL`
    (stabctl.models.declaration)."""
    x = np.zeros((N_STATES, p.n))
    tc = np.where(p.Tc >= LBND, p.Tc, 1.0)
    hy, sg = (p.kind == HYGOV) | (p.kind == HYGOV4), p.kind == IEESGO
    cross = p.mac2 >= 0
    lp = np.zeros(p.n) if pmech0_lp is None else np.asarray(pmech0_lp, float)
    total = np.where(cross, pmech0 + lp / np.where(cross, p.lp_base, 1.0), pmech0)
    K_all = p.K.sum(axis=1) + p.K_lp.sum(axis=1)
    gate = total / np.where((p.kind == IEEEG1) | sg, K_all, 1.0)
    bad = np.nonzero(cross & beyond(pmech0, p.K.sum(axis=1) * gate, p.K.sum(axis=1) * gate))[0]
    if bad.size:
        r = bad[0]
        raise CaseError(
            f"tg_con row {r + 1}: the cross-compound unit's HP machine starts at "
            f"{pmech0[r]:.4f} pu, its fractions K1, K3, K5, K7 give "
            f"{p.K[r].sum() * gate[r]:.4f} pu of the two machines' power"
        )
    gate = np.where(hy, pmech0 / np.where(hy, p.T5, 1.0) + p.qNL, gate)
    refuse_initial(
        "tg_con",
        beyond(gate, p.Tmin, p.Tmax),
        lambda r: (
            f"tg_con row {r + 1}: initial power order {gate[r]:.4f} pu outside "
            f"[Tmin, Tmax] = [{p.Tmin[r]:.4f}, {p.Tmax[r]:.4f}]"
        ),
    )
    refuse_initial(
        "tg_con",
        (p.kind == GAST) & beyond(pmech0, -np.inf, p.AT + p.KT * (p.AT - pmech0)),
        lambda r: (
            f"tg_con row {r + 1}: GAST's load limit AT + KT (AT - Pm0) is below its "
            f"initial power {pmech0[r]:.4f} pu"
        ),
    )
    tg, t1, g1 = p.kind == TG, p.kind == TGOV1, p.kind == IEEEG1
    x[0] = np.where(g1, 0.0, pmech0)
    x[1] = np.where(tg | t1, (1 - p.T3 / tc) * pmech0, gate)
    x[2] = np.where(tg, (1 - p.T4 / np.where(tg, p.T5, 1.0)) * pmech0, gate)
    x[3:] = np.where(g1, gate, 0.0)
    x[:5] = np.where(sg, np.array([0.0, 0.0, 1.0, 1.0, 1.0])[:, None] * gate, x[:5])
    # HYGOV: filter 0, gate integrator, gate, flow; HYGOV4: pilot servo 0, gate, dashpot
    # at the gate (no output), flow: all at q_0 (head 1)
    x[:4] = np.where(hy, np.array([0.0, 1.0, 1.0, 1.0])[:, None] * gate, x[:4])
    x[:2] = np.where(p.kind == TG2, 0.0, x[:2])  # the lead-lag at its input, 0
    x = x[: p.n_slots()]
    x[2:] *= p.has_state()[2:] | tg
    return x, np.where(hy, p.Rp * gate, gate)


# -- compiled runtime kernels: P is GovernorParams.packed(), x the governor block of the
# -- state vector (n_slots, n_tg), k the governor; one function per type, dispatched on
# -- kind by `pmech` and `derivatives`

#: the governors' non-windup rule (`blocks.nonwindup`): at or beyond a limit, always, as
#: a numpy boolean (a Python True from compiled code is typed as a literal, a second
#: compile of the block)
_AT_LIMIT = np.bool_(True)


@kernel
def pmech(P, x, k, omega):
    """Mechanical power of governor k (machine base) at machine speed omega (pu), flag 1."""
    kind = P[k, G.KIND]
    if kind == TG:
        return _tg_pmech(P, x, k)
    if kind == TGOV1:
        return _tgov1_pmech(P, x, k, omega)
    if kind == IEEEG1:
        return _fractions(P, k, _ieeeg1_lags(P, x, k))
    if kind == HYGOV:
        return _hygov_pmech(P, x, k, omega, x[2, k])
    if kind == GAST:
        return lag(x[0, k], x[1, k], P[k, G.TC])[0] - P[k, G.DT] * (omega - 1.0)
    if kind == TG2:
        return _tg2(P, x, k, omega, None)
    if kind == HYGOV4:  # HYGOV's turbine, D_turb on omega - w_f
        return _hygov_pmech(P, x, k, omega - P[k, G.WF] + 1.0, x[1, k])
    return _fractions(P, k, _ieesgo_lags(P, x, k, omega))


@kernel
def pmech_lp(P, x, k):
    """Mechanical power (its machine's base) a cross-compound IEEEG1 k hands its LP
    machine (column MAC2): the lags' outputs times K2, K4, K6, K8, in the HP machine's
    base times LP_BASE."""
    y = _ieeeg1_lags(P, x, k)
    return P[k, G.LP_BASE] * (
        P[k, G.KLA] * y[0] + P[k, G.KLB] * y[1] + P[k, G.KLC] * y[2] + P[k, G.KLD] * y[3]
    )


@kernel
def derivatives(P, x, k, omega, dx):
    """Derivatives of governor k into dx[:, k] for its machine speed omega (pu), flag 2;
    clamps the limited TGOV1 valve, IEEEG1 and HYGOV gate states in x."""
    kind = P[k, G.KIND]
    dx[:, k] = 0.0
    if kind == TG or kind == TGOV1:
        _tg_derivatives(P, x, k, omega, dx)
    elif kind == IEEEG1:
        _ieeeg1_derivatives(P, x, k, omega, dx)
    elif kind == HYGOV:
        _hygov_derivatives(P, x, k, omega, dx)
    elif kind == GAST:
        _gast_derivatives(P, x, k, omega, dx)
    elif kind == TG2:
        _tg2(P, x, k, omega, dx)
    elif kind == HYGOV4:
        _hygov4_derivatives(P, x, k, omega, dx)
    else:
        _ieesgo_lags(P, x, k, omega, dx)


@kernel(inline="always")
def _fractions(P, k, y):
    """The IEEEG1/IEESGO shaft power: the lag outputs y (4,) times their fractions."""
    return P[k, G.KA] * y[0] + P[k, G.KB] * y[1] + P[k, G.KC] * y[2] + P[k, G.KD] * y[3]


# -- tg (PST tg.m) and TGOV1: power order, servo (tg: input limited; TGOV1: non-windup
# -- valve), lead-lag T_3/T_c; tg: then the lead-lag T_4/T_5; TGOV1: minus D_t (omega - 1)


@kernel(inline="always")
def _tg_pmech(P, x, k):
    """tg: (1 + s T_4)/(1 + s T_5) of the output of (1 + s T_3)/(1 + s T_c)."""
    y2 = leadlag(x[0, k], x[1, k], P[k, G.T3], P[k, G.TC])[0]
    return leadlag(y2, x[2, k], P[k, G.T4], P[k, G.T5])[0]


@kernel(inline="always")
def _tgov1_pmech(P, x, k, omega):
    """TGOV1: the lead-lag (1 + s T_2)/(1 + s T_3) output minus D_t (omega - 1)."""
    return leadlag(x[0, k], x[1, k], P[k, G.T3], P[k, G.TC])[0] - P[k, G.DT] * (omega - 1.0)


@kernel(inline="always")
def _tg_derivatives(P, x, k, omega, dx):
    """tg and TGOV1: the order P_ref + (w_f - omega)/R through the servo 1/(1 + s T_s)
    (tg: order clipped to [Tmin, Tmax]; TGOV1: non-windup valve), then the lead-lags."""
    order = P[k, G.PREF] + (P[k, G.WF] - omega) * P[k, G.INVR]
    lo, hi = P[k, G.TMIN], P[k, G.TMAX]
    if P[k, G.KIND] == TGOV1:
        x[0, k], dx[0, k] = nonwindup_lag(order, x[0, k], P[k, G.TS], lo, hi, _AT_LIMIT, 0.0)
    else:
        dx[0, k] = lag(clip(order, lo, hi), x[0, k], P[k, G.TS])[1]
    y2, dx[1, k] = leadlag(x[0, k], x[1, k], P[k, G.T3], P[k, G.TC])
    if P[k, G.KIND] == TG:
        dx[2, k] = leadlag(y2, x[2, k], P[k, G.T4], P[k, G.T5])[1]


# -- TG2 (ANDES 2.0 tg2.py): the droop through a lead-lag, then a hard output limit


@kernel(inline="always")
def _tg2(P, x, k, omega, dx=None):
    """TG2's mechanical power clip(P_ref + LL((w_f - omega)/R), pmin, pmax) (T3 = T1 the
    lead, Tc = T2 the lag; ANDES's HardLimiter: no windup, the lead-lag runs on); its
    state's derivative into dx when given."""
    y, d = leadlag((P[k, G.WF] - omega) * P[k, G.INVR], x[0, k], P[k, G.T3], P[k, G.TC])
    if dx is not None:
        dx[0, k] = d
    return clip(P[k, G.PREF] + y, P[k, G.TMIN], P[k, G.TMAX])


# -- GAST (PSS/E GAST, ANDES 2.0 gast.py): the droop order and the load limit AT + KT (AT
# -- - y3) through a low-value gate, the non-windup valve 1/(1 + s T1) on [VMIN, VMAX], the
# -- lag 1/(1 + s T2) to the power (minus D_t (omega - 1)), the lag T3 of the load limit


@kernel(inline="always")
def _gast_derivatives(P, x, k, omega, dx):
    """GAST (docs/pst_models.md 4.4): min(P_ref + (w_f - omega)/R, AT + KT (AT - y_3))
    through the valve (Ts = T1), y_2 its lag T2 (Tc), y_3 the lag T3 of y_2 (a lag below
    1e-3 s passes its input)."""
    y2, dx[1, k] = lag(x[0, k], x[1, k], P[k, G.TC])
    y3, dx[2, k] = lag(y2, x[2, k], P[k, G.T3])
    order = P[k, G.PREF] + (P[k, G.WF] - omega) * P[k, G.INVR]
    limit = P[k, G.AT] + P[k, G.KT] * (P[k, G.AT] - y3)
    x[0, k], dx[0, k] = nonwindup_lag(
        min(order, limit), x[0, k], P[k, G.TS], P[k, G.TMIN], P[k, G.TMAX], _AT_LIMIT, 0.0
    )


# -- IEEEG1: lead-lag on K (omega - 1), rate- and position-limited gate, lags T4..T7


@kernel(inline="always")
def _ieeeg1_lags(P, x, k, dx=None):
    """Outputs (4,) of the IEEEG1 lags T4..T7 in series on the gate (a lag below 1e-3 s
    passes its input) and, given dx, their derivatives."""
    y = np.empty(4)
    u = x[1, k]
    for r in range(4):
        u, d = lag(u, x[2 + r, k], P[k, (G.T4, G.T5, G.T6, G.T7)[r]])
        if dx is not None:
            dx[2 + r, k] = d
        y[r] = u
    return y


@kernel(inline="always")
def _ieeeg1_derivatives(P, x, k, omega, dx):
    """IEEEG1: K (1 + s T_2)/(1 + s T_1) on the speed deviation, the gate's rate
    (P_ref - that - gate)/T_3 limited to [Uc, Uo], position [PMIN, PMAX] non-windup."""
    u, dx[0, k] = leadlag(P[k, G.INVR] * (omega - 1.0), x[0, k], P[k, G.T3], P[k, G.TC])
    rate = clip((P[k, G.PREF] - u - x[1, k]) / P[k, G.TS], P[k, G.UC], P[k, G.UO])
    x[1, k], dx[1, k] = nonwindup(x[1, k], rate, P[k, G.TMIN], P[k, G.TMAX], _AT_LIMIT, 0.0)
    _ieeeg1_lags(P, x, k, dx)


# -- HYGOV (machine base): filter, gate integrator, gate servo, water column


@kernel
def _head(q, g):
    """HYGOV's head at the turbine, (q/g)^2 (0 with the gate closed)."""
    return (q / g) ** 2 if g > 0 else 0.0


@kernel(inline="always")
def _hygov_pmech(P, x, k, omega, g):
    """HYGOV and HYGOV4: A_t h (q - q_NL) - D_turb (omega - 1) g, for gate g."""
    q = x[3, k]
    return P[k, G.T5] * _head(q, g) * (q - P[k, G.QNL]) - P[k, G.DT] * (omega - 1.0) * g


@kernel(inline="always")
def _hygov_derivatives(P, x, k, omega, dx):
    """HYGOV: filter, rate- and position-limited gate integrator, gate servo, water column
    (module docstring; ANDES ``hygov.py``); psse_gate: the state is the desired gate c,
    d c/dt = (e + T_r de/dt)/(r T_r) (the PI whole) rate- and position-limited (PSS/E)."""
    e = x[0, k]
    psse = P[k, G.PSSE_GATE] == 1
    c = x[1, k] if psse else x[1, k] + e / P[k, G.RT]
    dx[0, k] = lag(P[k, G.PREF] - (omega - 1.0) - P[k, G.RP] * c, e, P[k, G.TC])[1]
    if psse:
        rate = clip(P[k, G.KG] * e + dx[0, k] / P[k, G.RT], P[k, G.UC], P[k, G.UO])
    else:
        shift = P[k, G.VELM_REL] * e / P[k, G.RT]
        rate = clip(P[k, G.KG] * e, P[k, G.UC] - shift, P[k, G.UO] - shift)
    x[1, k], dx[1, k] = nonwindup(x[1, k], rate, P[k, G.TMIN], P[k, G.TMAX], _AT_LIMIT, 0.0)
    dx[2, k] = lag(c, x[2, k], P[k, G.TS])[1]
    dx[3, k] = (1.0 - _head(x[3, k], x[2, k])) / P[k, G.T4]


@kernel(inline="always")
def _hygov4_derivatives(P, x, k, omega, dx):
    """HYGOV4 (module docstring; ANDES ``hygov4.py``): the dashpot R_temp T_r s/(1 + s T_r)
    on the gate (T3), the pilot servo T_p (Tc), the gate speed clip(y_p / T_g, U_C, U_O)
    (Ts) into the gate integrator non-windup on [PMIN, PMAX], the water column T_w (T4)."""
    g = x[1, k]
    dashpot = P[k, G.RT] * (g - x[2, k])
    dx[2, k] = (g - x[2, k]) / P[k, G.T3]
    error = P[k, G.PREF] - (omega - P[k, G.WF]) - P[k, G.RP] * g - dashpot
    dx[0, k] = lag(error, x[0, k], P[k, G.TC])[1]
    speed = clip(x[0, k] / P[k, G.TS], P[k, G.UC], P[k, G.UO])
    x[1, k], dx[1, k] = nonwindup(g, speed, P[k, G.TMIN], P[k, G.TMAX], _AT_LIMIT, 0.0)
    dx[3, k] = (1.0 - _head(x[3, k], x[1, k])) / P[k, G.T4]


# -- IEESGO: K_1 (omega - 1) through 1/(1 + s T_1), (1 + s T_2)/(1 + s T_3); the order
# -- limited to [PMIN, PMAX] through the lags T_4, T_5, T_6


@kernel(inline="always")
def _ieesgo_lags(P, x, k, omega, dx=None):
    """IEESGO: outputs (4,) of the lags T4, T5, T6 (the fourth 0; a time constant below
    1e-3 s passes its input) and, given dx, the derivatives of its five states."""
    u, d0 = lag(P[k, G.INVR] * (omega - 1.0), x[0, k], P[k, G.TC])
    u, d1 = leadlag(u, x[1, k], P[k, G.T3], P[k, G.TS])
    if dx is not None:
        dx[0, k], dx[1, k] = d0, d1
    u = clip(P[k, G.PREF] - u, P[k, G.TMIN], P[k, G.TMAX])
    y = np.zeros(4)
    for r in range(3):
        u, d = lag(u, x[2 + r, k], P[k, (G.T4, G.T5, G.T6)[r]])
        if dx is not None:
            dx[2 + r, k] = d
        y[r] = u
    return y
