"""Turbine-governor models (tg_con), one module per type, and this package: the registry
of the types, the tg_con table they fill (`GOVERNOR`), their parameters
(`GovernorParams`, packed for the kernels as :data:`PACKED`, columns `G`, then each
type's own), the compiled kernels (`pmech`, `derivatives`: the dispatch on the type
generated from the registry into ``_dispatch.py`` by ``python -m
stabctl.models.dispatch``; `pmech_lp`) and the initialisation (`initialise`).

The types (tg_con column 1) are the modules of the registry `MODULES` (one line each;
their codes and names their ``KINDS``, listed by the tg_con ``type`` column's help), each
holding its DYR/ANDES records, its own tg_con columns if any (``PARAMS``), its named
states (``S``, read by its kernels as ``x[S.gate, k]``), its initialisation and its
mechanical-power and derivative kernels, ``pmech(P, x, k, omega)`` and ``derivatives(P,
x, k, omega, pe, dx)``.

Sources: PSTess 1.1 `tg_indx.m`, `tg.m` (docs/pst_models.md section 4); PSS/E Model
Library; ANDES 2.0 ``andes/models/governor``; how to add a type in docs/simulator.md.
States: up to N_STATES slots per governor (the most any type present uses), named per
type in STATE_NAMES; slots a type does not use stay 0 (`has_state`).  A time constant
below 1e-3 s means the block is absent (no state).  Units: pu on the machine base; s.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.errors import CaseError, refuse_initial
from stabctl.models.blocks import LBND
from stabctl.models.declaration import (
    Declared,
    Limits,
    beyond,
    check_packed,
    model_types,
    own_params,
    pack,
    pack_own,
    params_class,
    type_modules,
    typed_family,
)
from stabctl.models.governors import degov, ggov1, ieeeg1
from stabctl.models.governors._dispatch import derivatives, pmech
from stabctl.models.governors.degov1 import DEGOV1
from stabctl.models.governors.ggov1 import GGOV1
from stabctl.models.governors.hygov import HYGOV
from stabctl.models.governors.hygov4 import HYGOV4
from stabctl.models.governors.ieeeg1 import IEEEG1
from stabctl.models.governors.table import (
    GGOV1_FIELDS,
    HYGOV_FIELDS,
    PACKED,
    PARAMS,
    TABLE_FIELDS,
    G,
)
from stabctl.models.governors.tg import TG

if TYPE_CHECKING:
    from stabctl.case import Case

__all__ = [
    "GOVERNOR",
    "TYPES",
    "STATE_NAMES",
    "N_STATES",
    "GovernorParams",
    "governor_params",
    "initialise",
    "pmech",
    "pmech_lp",
    "derivatives",
    "G",
    "PACKED",
    "TABLE_FIELDS",
    "HYGOV_FIELDS",
    "OWN_PARAMS",
    "N_OWN",
    "MODULES",
]

# --------------------------------------------------------------------------------------
# the registry: one line per type module; a module serves the tg_con types of its KINDS
# (the order of the DYR records)
# --------------------------------------------------------------------------------------

MODULES = type_modules(
    __name__,
    "tg",
    "tgov1",
    "ieeeg1",
    "hygov",
    "ieesgo",
    "gast",
    "tg2",
    "hygov4",
    "ggov1",
    "degov",
    "degov1",
    "pidgov",
    "ieeeg2",
    "ieeeg3",
)
#: tg_con type -> the module of its equations; -> its state names, in slot order (``S``)
TYPES, STATE_NAMES = model_types(MODULES, "tg_con")
#: state slots of the widest type
N_STATES = max(len(names) for names in STATE_NAMES.values())
#: the types whose start-up order `initialise` refuses outside [Tmin, Tmax] (their
#: modules' ``ORDER_LIMITS``; the others' ``initialise`` checks their own start)
ORDER_LIMITED = tuple(kind for kind, m in TYPES.items() if m.ORDER_LIMITS)

#: the tg_con columns only one type reads, each type's module's ``PARAMS`` in registry
#: order (columns after `table.PARAMS`'s); packed after :data:`PACKED` (`table.own`)
OWN_PARAMS = own_params(MODULES)
#: the packed columns after :data:`PACKED`: the most own parameters of a type
N_OWN = max(len(getattr(mod, "PARAMS", ())) for mod in MODULES)

GOVERNOR = typed_family(
    "tg_con",
    10,
    "governor type",
    TYPES,
    PARAMS + OWN_PARAMS,
    tuple(m for mod in MODULES for m in mod.DYR),
    # every type limits its power order, gate or valve to [Tmin, Tmax] (PSS/E Model
    # Library: VMIN/VMAX, PMIN/PMAX, GMIN/GMAX; PSTess tg.m)
    common=Limits(
        "PSS/E Model Library: an upper limit at or above its lower", ordered=(("Tmax", "Tmin"),)
    ),
)

#: the labels of `GovernorParams.time_constants`, by declared field, in reporting order
_TIME_CONSTANT_LABELS = {
    "Ts": "tg_con T_s",
    "Tc": "tg_con T_c",
    "T3": "tg_con T_3",
    "T5": "tg_con T_5",
    "T4": "tg_con T_4",
    "T6": "tg_con T_6",
    "T7": "tg_con T_7",
    **{n: f"tg_con {n}" for n in (*ggov1.NEEDS, "Tdgov")},
    **{p.name: f"tg_con {p.name}" for p in OWN_PARAMS if p.unit == "s"},
    "delay_tc": "tg_con Teng (DEGOV's TD over its Pade approximant's fastest pole)",
}


@params_class(("kind", "mac"), TABLE_FIELDS + GGOV1_FIELDS + tuple(p.name for p in OWN_PARAMS))
class GovernorParams(Declared):
    """Governor data, arrays of shape (n_tg,): ``kind`` the tg_con type, ``mac`` the
    machine's row (index), the tg_con fields :data:`TABLE_FIELDS` under their declared
    names (stabctl.models.governors.GOVERNOR); K (n_tg, 4): IEEEG1 (and IEESGO) K1+K2, K3+K4,
    K5+K6, K7+K8, or a cross-compound IEEEG1's HP fractions K1, K3, K5, K7, whose LP
    fractions K2, K4, K6, K8 are K_lp (n_tg, 4; 0 otherwise) driving machine row mac2 (-1
    none) with its power times lp_base (the HP machine's MVA over the LP machine's); Rp,
    rt, qNL, Kg, velm_rel, psse_gate: HYGOV's columns 17-22 (0 for other types; T4 is its
    T_w, T5 its A_t); GGOV1's fields :data:`GGOV1_FIELDS` (tg_con columns 28-59) and
    turbine_scale, its turbine rating Trate over its machine's MVA (1 where Trate = 0
    or another type); delay_tc, a DEGOV's or DEGOV1's transport delay's fastest time
    constant (s; `stabctl.models.governors.degov.delay_time_constant`, inf without one);
    then every type's own fields (:data:`OWN_PARAMS`)."""

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
    turbine_scale: np.ndarray
    delay_tc: np.ndarray

    @property
    def n(self) -> int:
        return self.mac.size

    def packed(self, Pref: np.ndarray) -> np.ndarray:
        """Parameter matrix (n_tg, len(PACKED) + N_OWN) for the compiled kernels, with
        P_ref: columns as :data:`PACKED`, then on each row its type's own parameters
        (its module's ``PARAMS``, `table.own`)."""
        shared = pack(
            self,
            PACKED,
            Pref=Pref,
            **{f"K_{i}": self.K[:, i] for i in range(4)},
            **{f"K_lp_{i}": self.K_lp[:, i] for i in range(4)},
        )
        return np.hstack([shared, pack_own(self, MODULES)])

    def n_slots(self) -> int:
        """State slots per governor: the most any governor of the case uses (3 if none)."""
        return max([2, *(len(STATE_NAMES[int(k)]) for k in self.kind)]) if self.n else 3

    def has_state(self) -> np.ndarray:
        """Boolean (n_slots, n_tg): the slots that are states of each governor (each type
        module's ``has_state`` on its rows)."""
        act = np.zeros((N_STATES, self.n), bool)
        for module in MODULES:
            rows = np.isin(self.kind, tuple(module.KINDS))
            for slot, on in enumerate(module.has_state(self)):
                act[slot] |= rows & on
        return act[: self.n_slots()]

    def time_constants(self):
        """(label, values, mask) of every time constant that sets a state's speed (each
        type module's ``time_constants`` on its rows)."""
        masks = {name: np.zeros(self.n, bool) for name in _TIME_CONSTANT_LABELS}
        for module in MODULES:
            rows = np.isin(self.kind, tuple(module.KINDS))
            for name, on in module.time_constants(self).items():
                masks[name] |= rows & on
        return tuple(
            (label, getattr(self, name), masks[name])
            for name, label in _TIME_CONSTANT_LABELS.items()
        )


check_packed(
    GovernorParams,
    PACKED,
    ("Pref", *(f"K_{i}" for i in range(4)), *(f"K_lp_{i}" for i in range(4))),
)


def check_table(g) -> None:
    """Refuse a tg_con row stabctl does not model, as the table is made (CaseError naming
    the row and field, the table's `_fail`): a time constant the type needs below 1e-3 s
    (each type module's ``NEEDS``; tg: Ts, Tc, T5; TGOV1: T1 = Ts, T3 = Tc; IEEEG1: T3 =
    Ts; HYGOV: T_g = Ts, T_f = Tc, T_w = T4; TG2: T2 = Tc: a lag below it would be absent,
    `blocks.LBND`), a row its module's ``check`` refuses (GGOV1's options, a DEGOV lead
    without its lag), or an IEEEG1 without power fractions (K1 + ... + K8 <= 0); the
    values no type can take are the table's declared bounds and limits.

    Parameters
    ----------
    g : stabctl.case.GovernorTable
        The table being made.

    Raises
    ------
    CaseError
        For the first such row.
    """
    for r in range(len(g)):
        module = TYPES[int(g.type[r])]
        for name in module.NEEDS:
            if getattr(g, name)[r] < LBND:
                what = f"must be >= {LBND} s for governor type {int(g.type[r])}"
                g._fail(r, name, f"{what}, got {getattr(g, name)[r]:g}", rule=what)
        check = getattr(module, "check", None)
        problem = check(g, r) if check is not None else None
        if problem:
            g._refuse(r, problem)
    fractions = tuple(f"K{i}" for i in range(1, 9))
    total = sum(getattr(g, k) for k in fractions) if len(g) else np.zeros(0)
    bad = np.nonzero((g.type == IEEEG1) & (total <= 0))[0]
    if bad.size:
        what = "IEEEG1 power fractions K1..K8 must sum to > 0 (no power reaches the shaft)"
        g._fail(bad[0], "K1", f"{what}, got {total[bad[0]]:g}", fields=fractions, rule=what)


def governor_params(case: Case) -> GovernorParams:
    """Governor parameters (the table refused the types and options stabctl does not
    model as it was made, `check_table`).

    Raises CaseError (tg_con row, field) for a cross-compound IEEEG1 whose LP machine is
    unknown, its own or governed by another."""
    g = case.governors
    K = np.column_stack([g.K1 + g.K2, g.K3 + g.K4, g.K5 + g.K6, g.K7 + g.K8]).reshape(len(g), 4)
    cross = (g.type == IEEEG1) & (g.machine2 != 0)
    K_hp = np.column_stack([g.K1, g.K3, g.K5, g.K7]).reshape(len(g), 4)
    K_lp = np.column_stack([g.K2, g.K4, g.K6, g.K8]).reshape(len(g), 4)
    mac2 = _lp_machines(case, g, cross)
    mac = np.array([case.machine_index(m) for m in g.machine], int)
    mva = case.machines.mva
    hy = (g.type == HYGOV) | (g.type == HYGOV4)
    return GovernorParams(
        kind=g.type.astype(int),
        mac=mac,
        **{n: getattr(g, n).copy() for n in TABLE_FIELDS + GGOV1_FIELDS},
        **{p.name: getattr(g, p.name).copy() for p in OWN_PARAMS},
        K=np.where(hy[:, None], 0.0, np.where(cross[:, None], K_hp, K)),
        mac2=mac2,
        K_lp=np.where(cross[:, None], K_lp, 0.0),
        lp_base=np.where(cross, mva[mac] / mva[np.maximum(mac2, 0)], 0.0),
        **{n: np.where(hy, g.col(17 + i), 0.0) for i, n in enumerate(HYGOV_FIELDS)},
        turbine_scale=np.where((g.type == GGOV1) & (g.Trate > 0), g.Trate / mva[mac], 1.0),
        delay_tc=np.where(
            np.isin(g.type, (degov.DEGOV, DEGOV1)), degov.delay_time_constant(g.Teng), np.inf
        ),
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
    q_NL, head 1; HYGOV4: R_perm q_0, its gate and flow at q_0).  The start-up order is
    each type module's ``start_order(p, rows, pmech0, total)`` on its rows (the gate, or
    q_0; total the unit's power, both machines' for a cross-compound unit), the power
    total itself where the module has none; the family checks it for the types of
    :data:`ORDER_LIMITED`; each type's module sets its states on its rows and checks its
    own start (its ``initialise``), in the registry's order.

    Raises CaseError when the initial power order of an :data:`ORDER_LIMITED` type is
    outside [Tmin, Tmax] (PST's check for tg, the non-windup limits for TGOV1 and
    IEEEG1), a cross-compound unit's machines do not share its power as its HP and LP
    fractions do (ANDES 2.0 ieeeg1.py's ``_Pc`` check), beyond `START_LIMIT_TOL`
    (stabctl.models.declaration), or a type's ``initialise`` refuses its start."""
    x = np.zeros((N_STATES, p.n))
    cross = p.mac2 >= 0
    lp = np.zeros(p.n) if pmech0_lp is None else np.asarray(pmech0_lp, float)
    total = np.where(cross, pmech0 + lp / np.where(cross, p.lp_base, 1.0), pmech0)
    gate = total.copy()
    for module in MODULES:
        rows = np.isin(p.kind, tuple(module.KINDS))
        start_order = getattr(module, "start_order", None)
        if start_order is not None and rows.any():
            gate[rows] = start_order(p, rows, pmech0, total)
    bad = np.nonzero(cross & beyond(pmech0, p.K.sum(axis=1) * gate, p.K.sum(axis=1) * gate))[0]
    if bad.size:
        r = bad[0]
        raise CaseError(
            f"tg_con row {r + 1}: the cross-compound unit's HP machine starts at "
            f"{pmech0[r]:.4f} pu, its fractions K1, K3, K5, K7 give "
            f"{p.K[r].sum() * gate[r]:.4f} pu of the two machines' power"
        )
    refuse_initial(
        "tg_con",
        beyond(gate, p.Tmin, p.Tmax) & np.isin(p.kind, ORDER_LIMITED),
        lambda r: (
            f"tg_con row {r + 1}: initial power order {gate[r]:.4f} pu outside "
            f"[Tmin, Tmax] = [{p.Tmin[r]:.4f}, {p.Tmax[r]:.4f}]"
        ),
    )
    Pref = np.zeros(p.n)
    for module in MODULES:
        rows = np.isin(p.kind, tuple(module.KINDS))
        if rows.any():
            Pref[rows] = module.initialise(p, rows, pmech0, gate, x)
    x = x[: p.n_slots()]
    x[2:] *= p.has_state()[2:] | (p.kind == TG)
    return x, Pref


# -- compiled runtime kernels: P is GovernorParams.packed(), x the governor block of the
# -- state vector (n_slots, n_tg), k the governor; `pmech` and `derivatives`, the dispatch
# -- on the type, are generated (`_dispatch`)


@kernel
def pmech_lp(P, x, k):
    """Mechanical power (its machine's base) a cross-compound IEEEG1 k hands its LP
    machine (column MAC2), `ieeeg1.pmech_lp`."""
    return ieeeg1.pmech_lp(P, x, k)
