"""Power system stabilisers (pss_con), one module per type, and this package: the registry
of the types, the pss_con table they fill (`PSS`), their parameters (`PssParams`, packed
for the kernels as :data:`PACKED`, columns `C`, then each type's own), the compiled
kernel (`output_and_derivatives`: the type's ``output``, dispatched on the type by
``_dispatch.py``, generated from the registry by ``python -m stabctl.models.dispatch``,
then the output cut-off) and the initialisation (`initialise`).

The types (pss_con column 1) are the modules of the registry `MODULES` (one line each;
their codes and names their ``KINDS``, listed by the pss_con ``type`` column's help),
each holding its DYR records, its own pss_con columns if any (``PARAMS``), its named
states (``S``, read by its kernel as ``x[S.washout, k]``), its initialisation and its
kernel ``output(P, x, k, omega, pe, dx)`` (a module may run another's: PSS2B PSS2A's;
one may claim no type and hold a record only: STAB1, read as PST's type 1).

Sources: PSTess 1.1 `pss_indx.m`, `pss.m` (docs/pst_models.md section 3); PSS/E Model
Library; IEEE Std 421.5; how to add a type in docs/simulator.md.  States: up to N_STATES
slots per PSS (the most any type present uses), named per type in STATE_NAMES; slots a
type does not use stay 0 (`has_state`).  A time constant below 1e-3 s means the block is
absent (no state).  Output in pu, added to the exciter summing junction of the same
machine; 0 while the terminal voltage is outside [VCL, VCU] (pss_con columns 25-26,
PSS/E's output cut-off; 0 none).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.models.blocks import LBND
from stabctl.models.declaration import (
    Declared,
    Limits,
    check_packed,
    model_types,
    own_params,
    pack,
    pack_own,
    params_class,
    type_modules,
    typed_family,
)
from stabctl.models.pss import ieeest
from stabctl.models.pss._dispatch import output
from stabctl.models.pss.pss2c import PSS2C
from stabctl.models.pss.table import (
    PACKED,
    PARAMS,
    POWER,
    PSS2_FIELDS,
    SPEED,
    TABLE_FIELDS,
    C,
)

if TYPE_CHECKING:
    from stabctl.case import Case

__all__ = [
    "PSS",
    "TYPES",
    "STATE_NAMES",
    "N_STATES",
    "PssParams",
    "pss_params",
    "pss_inputs",
    "initialise",
    "output_and_derivatives",
    "C",
    "S",
    "PACKED",
    "TABLE_FIELDS",
    "PSS2_FIELDS",
    "OWN_PARAMS",
    "N_OWN",
    "MODULES",
    "SPEED",
    "POWER",
    "W_PSSE",
    "LL_PSSE",
    # the type codes read through the package (its own code); a type's code is its
    # module's, and a new type is not imported here
    "PSS2C",
]  # fmt: skip

# --------------------------------------------------------------------------------------
# the registry: one line per type module; a module serves the pss_con types of its KINDS
# (the order of the DYR records)
# --------------------------------------------------------------------------------------

MODULES = type_modules(
    __name__,
    "pst",
    "ieeest",
    "stab2a",
    "stab1",
    "pss2a",
    "pss2b",
    "pss2c",
)
#: pss_con type -> the module of its equations; -> its state names, in slot order (``S``)
TYPES, STATE_NAMES = model_types(MODULES, "pss_con")
#: state slots of the widest type
N_STATES = max(len(names) for names in STATE_NAMES.values())
#: the types whose inputs are PSS/E input codes (pss_con input1, input2; their modules'
#: ``PSSE_INPUTS``)
PSSE_INPUTS = tuple(k for k, m in TYPES.items() if m.PSSE_INPUTS)
#: the types that read the input limits VS1MIN .. VS2MAX (``INPUT_LIMITS``)
INPUT_LIMITED = tuple(k for k, m in TYPES.items() if m.INPUT_LIMITS)
#: the types whose washout T_w must be >= 1e-3 s (``NEEDS_TW``)
NEEDS_TW = tuple(k for k, m in TYPES.items() if m.NEEDS_TW)

#: the pss_con columns only one type reads, each type's module's ``PARAMS`` in registry
#: order (columns after `table.PARAMS`'s); packed after :data:`PACKED` (`table.own`)
OWN_PARAMS = own_params(MODULES)
#: the packed columns after :data:`PACKED`: the most own parameters of a type
N_OWN = max(len(getattr(mod, "PARAMS", ())) for mod in MODULES)

PSS = typed_family(
    "pss_con",
    10,
    "pss type",
    TYPES,
    PARAMS + OWN_PARAMS,
    tuple(m for mod in MODULES for m in mod.DYR),
    sep="; ",
    # every type limits its output to [ymin, ymax] (IEEE Std 421.5-2016 PSS1A, PSS2A-C;
    # PST manual 3.30 Table 13; STAB2A's [-HLIM, HLIM])
    common=Limits(
        "IEEE Std 421.5: an upper limit at or above its lower", ordered=(("ymax", "ymin"),)
    ),
)

#: the kernels' column of each PACKED name, under the name it had before the package
#: (pss.S.TW): the same layout as `C`
S = C
#: type 3's washout and first lead-lag slots (`ieeest.S`)
W_PSSE, LL_PSSE = ieeest.S.washout, ieeest.S.leadlag1

#: the labels of `PssParams.time_constants`, by declared field, in reporting order
_TIME_CONSTANT_LABELS = {
    "Tw": "pss_con T_w",
    "T2": "pss_con T_2",
    "T4": "pss_con T_4",
    "T6": "pss_con T_6",
    "Tr1": "pss_con Tr1",
    "Tr2": "pss_con Tr2",
    **{n: f"pss_con {n}" for n in ("Tw2", "Tw3", "Tw4", "T9", "T13")},
}
_LIMITS = ("in1_lo", "in1_hi", "in2_lo", "in2_hi")


@params_class(("kind", "mac"), TABLE_FIELDS + PSS2_FIELDS + tuple(p.name for p in OWN_PARAMS))
class PssParams(Declared):
    """PSS data, arrays of shape (n_pss,): ``kind`` the pss_con type, ``mac`` the machine's
    row (index), the pss_con fields :data:`TABLE_FIELDS` and :data:`PSS2_FIELDS` under
    their declared names (stabctl.models.pss.PSS; input1, input2 0 for the types without
    PSS/E inputs).  Type 3: the filter in controllable canonical form of order nf (<= 4):
    fa (n, 4) the monic denominator coefficients a_0..a_3, fc (n, 4) output
    coefficients, fe the feedthrough.  Every type: v_cut_high, v_cut_low the output
    cut-off's terminal voltages (pu; VCU, VCL with 0 read as none: +inf, -inf; plus the
    initial terminal voltage where ``cut_relative``).  PSS2B,
    PSS2C: in1_lo, in1_hi, in2_lo, in2_hi the input limits VS1MIN .. VS2MAX (pu; -inf,
    +inf for the other types); then every type's own fields (:data:`OWN_PARAMS`)."""

    nf: np.ndarray
    fa: np.ndarray
    fc: np.ndarray
    fe: np.ndarray
    v_cut_high: np.ndarray
    v_cut_low: np.ndarray
    in1_lo: np.ndarray
    in1_hi: np.ndarray
    in2_lo: np.ndarray
    in2_hi: np.ndarray

    @property
    def n(self) -> int:
        return self.mac.size

    def packed(self) -> np.ndarray:
        """Parameter matrix (n_pss, len(PACKED) + N_OWN) for the compiled kernels:
        columns as :data:`PACKED`, then on each row its type's own parameters (its
        module's ``PARAMS``, `table.own`)."""
        shared = pack(
            self,
            PACKED,
            **{f"fa_{i}": self.fa[:, i] for i in range(4)},
            **{f"fc_{i}": self.fc[:, i] for i in range(4)},
        )
        return np.hstack([shared, pack_own(self, MODULES)])

    @property
    def has_T4(self):
        return self.T4 >= LBND

    def n_slots(self) -> int:
        """State slots per PSS: the most any PSS of the case uses (3 if none)."""
        return max([3, *(len(STATE_NAMES[int(k)]) for k in self.kind)])

    def has_state(self) -> np.ndarray:
        """Boolean (n_slots, n_pss): the slots that are states of each PSS (each type
        module's ``has_state`` on its rows)."""
        act = np.zeros((N_STATES, self.n), bool)
        for module in MODULES:
            rows = np.isin(self.kind, tuple(module.KINDS))
            if module.KINDS:
                for slot, on in enumerate(module.has_state(self)):
                    act[slot] |= rows & on
        return act[: self.n_slots()]

    def time_constants(self):
        """(label, values, mask) of every time constant that sets a state's speed (each
        type module's ``time_constants`` on its rows)."""
        masks = {name: np.zeros(self.n, bool) for name in _TIME_CONSTANT_LABELS}
        for module in MODULES:
            rows = np.isin(self.kind, tuple(module.KINDS))
            if module.KINDS:
                for name, on in module.time_constants(self).items():
                    masks[name] |= rows & on
        return tuple(
            (label, getattr(self, name), masks[name])
            for name, label in _TIME_CONSTANT_LABELS.items()
        )


check_packed(PssParams, PACKED, (*(f"fa_{i}" for i in range(4)), *(f"fc_{i}" for i in range(4))))


def check_table(s) -> None:
    """Refuse a pss_con row stabctl does not model, as the table is made (CaseError naming
    the row and field, the table's `_fail`): a type of :data:`NEEDS_TW` (the PSS/E types
    3-7) whose washout is below 1e-3 s, or a row its type module's ``check`` refuses: a
    PST pss (types 1, 2) whose first lead-lag has no lag (T_2 below 1e-3 s; PST has no
    such case); a type-3 or PSS2 lead-lag with a lead but no lag, an input code other
    than 1 (speed) or 3 (power); an improper type-3 filter (A6 without a second-order
    denominator); a PSS2 ramp-tracking filter with N > 0 and M = 0, M N > 8 or T9 below
    1e-3 s.

    Parameters
    ----------
    s : stabctl.case.PssTable
        The table being made.

    Raises
    ------
    CaseError
        For the first such row.
    """
    for r in range(len(s)):
        kind = int(s.type[r])
        if kind in NEEDS_TW and s.Tw[r] < LBND:
            what = f"washout needs Tw >= {LBND} s"
            s._fail(r, "Tw", f"{what}, got {s.Tw[r]:g}", rule=what)
        problem = TYPES[kind].check(s, r)
        if problem:
            s._refuse(r, problem)


def pss_params(case: Case, vt0: np.ndarray | None = None) -> PssParams:
    """PSS parameters of a case (the table refused the types and options stabctl does not
    model as it was made, `check_table`).

    Parameters
    ----------
    case : Case
        The case.
    vt0 : numpy.ndarray or None, optional
        Initial terminal voltage magnitude of each machine (pu), shape (n_mac,): the
        origin of the cut-off of a row with ``cut_relative`` (ST2CUT's VT0 + VCU, VT0 +
        VCL).  None: such a cut-off is left at VCU, VCL (for what does not run the
        model, e.g. its time constants).

    Returns
    -------
    PssParams
        The stabilisers.
    """
    s = case.pss
    nf, fa, fc, fe = ieeest.filters(s)
    e = np.isin(s.type, PSSE_INPUTS)
    limited = np.isin(s.type, INPUT_LIMITED)
    own = tuple(p.name for p in OWN_PARAMS)
    given = {n: getattr(s, n).copy() for n in TABLE_FIELDS + PSS2_FIELDS + own}
    given.update(input1=np.where(e, s.input1, 0), input2=np.where(e, s.input2, 0))
    inf = np.full(len(s), np.inf)
    mac = np.array([case.machine_index(m) for m in s.machine], int)
    origin = np.zeros(len(s))
    if vt0 is not None:
        origin = np.where(s.cut_relative == 1, np.asarray(vt0, float)[mac], 0.0)
    return PssParams(
        kind=s.type.astype(int),
        mac=mac,
        **given,
        nf=nf,
        fa=fa,
        fc=fc,
        fe=fe,
        v_cut_high=np.where(s.VCU == 0, np.inf, origin + s.VCU),
        v_cut_low=np.where(s.VCL == 0, -np.inf, origin + s.VCL),
        in1_lo=np.where(limited, s.VS1MIN, -inf),
        in1_hi=np.where(limited, s.VS1MAX, inf),
        in2_lo=np.where(limited, s.VS2MIN, -inf),
        in2_hi=np.where(limited, s.VS2MAX, inf),
    )


def pss_inputs(p: PssParams, omega, pe_machine):
    """Signals 1 and 2 of each PSS at the initial point, shape (n_pss,) each.

    Parameters
    ----------
    p : PssParams
        The stabilisers.
    omega : numpy.ndarray
        Machine speeds (pu), shape (n_mac,).
    pe_machine : numpy.ndarray
        Electrical power of each machine on its own base (pu), shape (n_mac,): the air-gap
        power ``Re(psi conj(I))`` of the internal voltage the network sees, the signal
        :func:`output_and_derivatives` is given in a run (at the initial point the
        mechanical power, terminal power plus ``r_a |I|^2``).  ANDES's IEEEST takes the
        same (``sig``: ``tm0`` at initialisation, ``te`` after, ``andes/models/pss/
        ieeest.py``); with the terminal power here a machine with ``r_a`` started off
        equilibrium (IEEE 39 G6: 0.015 on ``pss.leadlag1``).

    Returns
    -------
    u1 : numpy.ndarray
        PST types: speed (pu) or the power; types 3, 5-7: the first PSS/E input (speed
        deviation or power, before any input limit); type 4: the power.
    u2 : numpy.ndarray
        Types 3, 5-7: the second PSS/E input (0 none); the other types: 0.
    """
    w, pe = omega[p.mac], pe_machine[p.mac]
    u1, u2 = np.zeros(p.n), np.zeros(p.n)
    for module in MODULES:
        rows = np.isin(p.kind, tuple(module.KINDS))
        if rows.any():
            u1[rows], u2[rows] = module.signals(p, rows, w, pe)
    return u1, u2


def initialise(p: PssParams, u1, u2, pe0=None):
    """States (n_slots, n_pss) from the initial inputs (`pss_inputs`), each type module's
    ``initialise`` on its rows: every washout input state at its input, input lags at K
    u, type 3's filter state 1 at its input times the denominator's leading coefficient
    (controllable form, zero derivative), PSS2C's switch from the initial power, others 0.

    Parameters
    ----------
    p : PssParams
        The stabilisers.
    u1, u2 : numpy.ndarray
        Their inputs at the initial point, shape (n_pss,) each (`pss_inputs`).
    pe0 : numpy.ndarray, optional
        Each PSS's machine's initial electrical power (machine base), shape (n_pss,);
        needed where a PSS2C is (its output logic).

    Returns
    -------
    numpy.ndarray
        The states, shape (n_slots, n_pss).

    Raises
    ------
    ValueError
        A PSS2C without pe0.
    """
    if pe0 is None:
        if np.any(p.kind == PSS2C):
            raise ValueError("initialise: a PSS2C needs its machine's initial power pe0")
        pe0 = np.zeros(p.n)
    x = np.zeros((N_STATES, p.n))
    for module in MODULES:
        rows = np.isin(p.kind, tuple(module.KINDS))
        if rows.any():
            module.initialise(p, rows, u1, u2, np.asarray(pe0, float), x)
    return x[: p.n_slots()]


# -- compiled runtime kernel: P is PssParams.packed(), x the PSS block of the state
# -- vector (n_slots, n_pss), k the PSS; each type's kernel is its module's ``output``,
# -- dispatched on the type by the generated `output` (`_dispatch`)


@kernel
def output_and_derivatives(P, x, k, omega, pe, vt, dx):
    """Output of PSS k (pu, to its exciter's summing junction) at machine speed omega (pu),
    electrical power pe (machine base) and terminal voltage magnitude vt (pu), PST flag
    1/2; its derivatives into dx[:, k].  The output is 0 while vt is outside [VCL, VCU]
    (PSS/E IEEEST, ST2CUT; ANDES 2.0 ``ieeest.py`` ``OLIM``); the states move on."""
    y = output(P, x, k, omega, pe, dx)
    return y if P[k, C.VCUT_LO] <= vt <= P[k, C.VCUT_HI] else 0.0
