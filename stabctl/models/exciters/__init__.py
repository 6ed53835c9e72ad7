"""Exciter models (exc_con), one module per type, and this package: the registry of the
types, the exc_con table they fill (`EXCITER`), their parameters (`ExciterParams`,
packed for the kernels as :data:`PACKED`, columns `E`, then each type's own), the
compiled kernels (`field_voltage`, `derivatives`, `recorded_efd`; their dispatch on the
type, `field_voltage_at`, `type_derivatives`, `type_recorded_efd`, and the source
voltage's, `source_voltage_of`, generated from the registry into ``_dispatch.py`` by
``python -m stabctl.models.dispatch``) and the initialisation (`initialise`).

The types (exc_con column 1) are the modules of the registry `MODULES` (one line each;
their codes and names their ``KINDS``, listed by the exc_con ``type`` column's help), each
holding its DYR/ANDES records, its own exc_con columns if any (``PARAMS``), its named
states (``S``, read by its kernels as ``x[S.VE, i]``), its initialisation and its kernels
``field_voltage(P, x, i, VTR_alg, pss_out, VB, ifd, ieee)``, ``derivatives(P, x, i, err,
eterm, efd, ifd, pss_out, VB, dx, ieee, reach)`` and, where PST records another Efd than
the algebraic one, ``recorded_efd(P, x, i, efd_alg)``.

Source: PSTess 1.1 `exc_indx.m`, `smpexc.m`, `exc_dc12.m`, `exc_st3.m` (PST manual 3.11
Table 2, 3.13 Table 3); PSS/E Model Library; IEEE Std 421.5; ANDES 2.0
``andes/models/exciter``; equations, limits and PST's quirks in docs/pst_models.md
section 2, how to add a type in docs/models.md.  A time constant below 1e-3 s means the
block is absent (no state).  States, named per type in STATE_NAMES (each type's ``S``).
Units: pu on the machine base; times in s.

The kernels read the packed parameters by name (`E`, from :data:`PACKED`), are built of
the control blocks of `stabctl.models.blocks`; the family computes the machine
quantities a type needs (the source voltage of the types in :data:`SOURCE_KINDS`,
`source_voltage`; the field current of the types in :data:`READS_IFD`,
`field_current`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.arrays import magnitude, zero_column
from stabctl._jit.borrow import borrowed
from stabctl._jit.decorators import kernel
from stabctl.errors import CaseError
from stabctl.models import machines as mac
from stabctl.models.blocks import LBND, lag
from stabctl.models.declaration import (
    Declared,
    DyrModel,
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
from stabctl.models.exciters import st3
from stabctl.models.exciters._dispatch import (
    field_voltage_at,
    source_voltage_of,
    type_derivatives,
    type_recorded_efd,
)
from stabctl.models.exciters.ac8b import AC8B
from stabctl.models.exciters.dc import DC1, DC2, T2, dc_feedback
from stabctl.models.exciters.esst1a import ST1A, st1a_regulator_output
from stabctl.models.exciters.expic1 import PIC1
from stabctl.models.exciters.exst1 import ST1
from stabctl.models.exciters.ieeet3 import T3
from stabctl.models.exciters.sexs import SMP
from stabctl.models.exciters.st3 import ST3, st3_source_voltage
from stabctl.models.exciters.table import (
    PACKED,
    PARAMS,
    PID_TRACKING,
    RUNNING,
    TABLE_FIELDS,
    VTR,
    E,
    ST3Machine,
    StatorQuantities,
    potential_source,
    unit_phasor,
)
from stabctl.models.saturation import quadratic_fit

if TYPE_CHECKING:
    from stabctl.case import Case

__all__ = [
    "EXCITER",
    "TYPES",
    "STATE_NAMES",
    "ExciterParams",
    "exciter_params",
    "initialise",
    "initial_source_voltage",
    "field_voltage",
    "field_voltage_at",
    "derivatives",
    "recorded_efd",
    "field_current",
    "source_voltage",
    "stator",
    "source_voltage_of",
    "compensated",
    "E",
    "PACKED",
    "OWN_PARAMS",
    "N_OWN",
    "MODULES",
    "TABLE_FIELDS",
    "SATURATED_EXCITERS",
    "PID_TRACKING",
    "ST3Machine",
    "StatorQuantities",
    "potential_source",
    "unit_phasor",
    "st3_source_voltage",
    "dc_feedback",
    "st1a_regulator_output",
    # the type codes read through the package (its own code, stabctl.dynamics, the
    # tests); a type's code is its module's, and a new type is not imported here
    "SMP", "DC1", "DC2", "ST3", "ST1", "T2", "ST1A", "AC8B", "T3", "PIC1",
]  # fmt: skip

# --------------------------------------------------------------------------------------
# the registry: one line per type module, in the order their start-up checks run
# (`initialise`); a module serves the exc_con types of its KINDS
# --------------------------------------------------------------------------------------

MODULES = type_modules(
    __name__,
    "st3",
    "exst1",
    "esst1a",
    "exac4",
    "exac1",
    "ac8b",
    "ieeet3",
    "esst4b",
    "exac2",
    "esac6a",
    "expic1",
    "st6b",
    "st8c",
    "sexs",
    "dc",  # last: its own exc_con column (75) after the others' (67-74)
)
#: exc_con type -> the module of its equations; -> its state names, in slot order (``S``)
TYPES, STATE_NAMES = model_types(MODULES, "exc_con")
if any(names[VTR] != "VTR" for names in STATE_NAMES.values()):
    raise ValueError("every exciter type's first state is its transducer V_TR")

#: the exc_con columns only one type reads, each type's module's ``PARAMS`` in registry
#: order (columns after `table.PARAMS`'s); packed after :data:`PACKED` (`table.own`)
OWN_PARAMS = own_params(MODULES)
#: the packed columns after :data:`PACKED`: the most own parameters of a type
N_OWN = max(len(getattr(mod, "PARAMS", ())) for mod in MODULES)

EXCITER = typed_family(
    "exc_con",
    9,
    "exciter type",
    TYPES,
    PARAMS + OWN_PARAMS,
    (
        # IEEEVC (the IEEE 1981 load compensator, a record of its own beside the machine's
        # exciter record): R_C, X_C into that exciter's row (stabctl.io.dyr COMPENSATORS)
        DyrModel("IEEEVC", ("RC", "XC"), {"Rcomp": "RC", "Xcomp": "XC"}, andes=("IEEEVC",)),
        *(model for m in MODULES for model in m.DYR),
    ),
    # every type limits its regulator's output V_R to [Vrmin, Vrmax] (IEEE Std 421.5-2016;
    # PST manual 3.11, 3.13, 3.38)
    common=Limits(
        "IEEE Std 421.5: an upper limit at or above its lower", ordered=(("Vrmax", "Vrmin"),)
    ),
)

#: the types whose equations read the machine's field current (`field_current`)
READS_IFD = tuple(kind for kind, m in TYPES.items() if m.READS_IFD)
#: the types with a rate feedback s K_F/(1 + s T_F) from exc_con columns 21-22 (the DC
#: exciters read theirs from columns 16-17): EXST1, ESST1A, EXAC1, ESAC1A, IEEET3
RATE_FEEDBACK = tuple(kind for kind, m in TYPES.items() if m.RATE_FEEDBACK)
#: the types fed by a potential (and compound) source V_B computed from the machine's
#: terminal voltage and current (`source_voltage`): ST3, IEEET3, ESST4B
SOURCE_KINDS = tuple(kind for kind, m in TYPES.items() if m.SOURCE)
#: the types reading K_E, T_E and PSS/E's quadratic saturation from exc_con columns
#: 10-15 (their modules' ``EXCITER_COLUMNS``): the AC exciters and EXPIC1 (its exciter
#: T_E dEfd/dt = E_0 - (K_E + S_E) Efd)
QUAD_KINDS = tuple(k for k, m in TYPES.items() if m.EXCITER_COLUMNS == "quadratic")
#: the most state slots of a type (EXPIC1's 7)
MAX_SLOTS = max(len(names) for names in STATE_NAMES.values())
#: the DC exciters (their saturation fits, K_E computed): DC1, DC2, IEEET2
DC_KINDS = tuple(k for k, m in TYPES.items() if m.EXCITER_COLUMNS == "dc")
#: the types reading K_E and T_E (exc_con columns 10-11): those above and IEEET3
KE_KINDS = tuple(k for k, m in TYPES.items() if m.EXCITER_COLUMNS)
#: the types with the saturation points E1, SE(E1), E2, SE(E2) (exc_con columns 12-15): the
#: DC exciters and those with PSS/E's quadratic saturation
SATURATED_EXCITERS = tuple(k for k, m in TYPES.items() if m.EXCITER_COLUMNS in ("dc", "quadratic"))
#: the machine's speed among its states (``efd_speed``)
_OMEGA = mac.STATE_NAMES.index("omega")


@params_class(("kind", "mac"), TABLE_FIELDS + tuple(p.name for p in OWN_PARAMS))
class ExciterParams(Declared):
    """Exciter data of a case, arrays of shape (n_exc,): ``kind`` the exc_con type,
    ``mac`` the machine's row (index), then the exc_con fields :data:`TABLE_FIELDS` under
    their declared names (stabctl.models.exciters.EXCITER; KP the complex K_P exp(j
    theta_P), KA = 0 read as 1 for the regulated types), then the derived fields below.
    DC exciters (types 1, 2): KE, TE and the saturation SE(E) = Asat exp(Bsat |E|), or
    with sat_quadratic SE(E) E = Bsat (E - Asat)^2 above Asat (0 for the other types);
    ke_given: KE used as given (else 0 means computed at initialisation); KF, TF: rate
    feedback of the DC exciters and EXST1; ifd_machine: ST3 whose I_N takes the machine's
    field current, not PST exc_st3's estimate (exc_con column 25); VB_cap: the ST3 source
    voltage's upper limit (exc_con column 33, VBmax; inf where 0 or not ST3)."""

    KE: np.ndarray
    TE: np.ndarray
    Asat: np.ndarray
    Bsat: np.ndarray
    KF: np.ndarray
    TF: np.ndarray
    sat_quadratic: np.ndarray
    ke_given: np.ndarray
    ifd_machine: np.ndarray
    VB_cap: np.ndarray

    @property
    def n(self) -> int:
        return self.kind.size

    def packed(self, Vref: np.ndarray) -> np.ndarray:
        """Parameter matrix (n_exc, len(PACKED) + N_OWN) for the compiled kernels, with
        Vref: columns as :data:`PACKED`, then on each row its type's own parameters (its
        module's ``PARAMS``, `table.own`)."""
        return np.hstack([pack(self, PACKED, Vref=Vref), pack_own(self, MODULES)])

    @property
    def has_TR(self):
        return self.TR >= LBND

    @property
    def has_TB(self):
        return self.TB >= LBND

    @property
    def has_pid_d(self):
        """AC8B with the PID's derivative branch (K_D != 0, T_D >= 1e-3 s)."""
        return (self.kind == AC8B) & (self.Kpid_D != 0) & (self.Td >= LBND)

    @property
    def has_TA(self):
        return self.TA >= LBND

    @property
    def is_dc(self):
        """DC exciters: DC1, DC2 and IEEET2."""
        return np.isin(self.kind, DC_KINDS)

    @property
    def has_VF(self):
        """IEEET2 with a second rate-feedback lag (T_F2 >= 1e-3 s, exc_con column 18)."""
        return self.TF2 >= LBND

    @property
    def TF2(self):
        """IEEET2's second rate-feedback time constant T_F2 (s; exc_con column 18, read
        as Efdmax by the other types), 0 for the other types."""
        return np.where(self.kind == T2, self.Efdmax, 0.0)

    @property
    def tc_tb(self):
        """T_C/T_B where the lead-lag exists, 1 otherwise (PST exc_pot column 5)."""
        return np.where(self.has_TB, self.TC / np.where(self.has_TB, self.TB, 1.0), 1.0)

    @property
    def has_TB1(self):
        """ESST1A's second lead-lag exists (T_B1 >= 1e-3 s)."""
        return (self.kind == ST1A) & (self.TB1 >= LBND)

    @property
    def tc1_tb1(self):
        """ESST1A's T_C1/T_B1 where its second lead-lag exists, 1 otherwise."""
        return np.where(self.has_TB1, self.TC1 / np.where(self.has_TB1, self.TB1, 1.0), 1.0)

    def n_slots(self) -> int:
        """State slots per exciter: the most any exciter of the case uses (3 if none; an ST3
        uses its fourth, ESST3A's regulator lag, only with T_A)."""
        used = [len(STATE_NAMES[int(k)]) for k in self.kind]
        return max(
            [3, *(u - (k == ST3 and not a) for u, k, a in zip(used, self.kind, self.has_TA3A))]
        )

    @property
    def has_TA3A(self):
        """ST3 with ESST3A's regulator lag (T_A >= 1e-3 s, exc_con column 44)."""
        return (self.kind == ST3) & (self.TA_st3a >= LBND)

    def has_state(self) -> np.ndarray:
        """Boolean (n_slots, n_exc): the slots that are states (docs/modal.md)."""
        act = np.zeros((MAX_SLOTS, self.n), bool)
        for module in MODULES:
            rows = np.isin(self.kind, tuple(module.KINDS))
            for slot, on in enumerate(module.has_state(self)):
                act[slot] |= rows & on
        return act[: self.n_slots()]

    @property
    def has_Rf(self):
        """The rate-feedback state exists: DC exciters, and :data:`RATE_FEEDBACK` types with
        K_F != 0."""
        return self.is_dc | (np.isin(self.kind, RATE_FEEDBACK) & (self.KF != 0))

    def time_constants(self):
        """(label, values, mask) of every time constant that sets a state's speed: the
        transducer T_R, the regulator T_A and the lead-lag T_B every type may have, the
        rate feedback T_F of the :data:`RATE_FEEDBACK` types with K_F != 0, then each type
        module's ``time_constants`` (label -> (values, where)) on its rows; a label names
        one array, its rows gathered from every type that gives it."""
        found = {
            "exc_con T_R": (self.TR, self.has_TR),
            "exc_con T_A": (self.TA, self.has_TA),
            "exc_con T_B": (self.TB, self.has_TB),
            "exc_con T_F": (self.TF, np.isin(self.kind, RATE_FEEDBACK) & (self.KF != 0)),
        }
        for module in MODULES:
            rows = np.isin(self.kind, tuple(module.KINDS))
            for label, (values, on) in module.time_constants(self).items():
                before = found[label][1] if label in found else False
                found[label] = (values, before | (rows & on))
        return tuple((label, values, mask) for label, (values, mask) in found.items())

    def inner_loop_time_constants(self, VB0: np.ndarray, efd0: np.ndarray) -> np.ndarray:
        """The time constant of each exciter's fast closed loop at the operating point (s),
        (n_exc,), which no single time constant of its data shows: each type module's
        ``inner_loop_time_constants(p, rows, VB0, efd0)`` on its rows, where it has one
        (its ``INNER_LOOP`` names the loop, `inner_loop`); inf elsewhere.  ST3: T_A/(1 +
        K_A K_G V_B0) (`st3.inner_loop_time_constants`); EXST1, ESST1A: the regulator
        closed through its rate feedback (`exst1.inner_loop_time_constants`); EXAC2: its
        regulator, exciter and rate feedback loop, as Heun's method sees it
        (`exac2.inner_loop_time_constants`).

        Parameters
        ----------
        VB0 : ndarray, shape (n_exc,)
            The source voltages at the operating point (`initial_source_voltage`), pu.
        efd0 : ndarray, shape (n_exc,)
            The field voltages at the operating point, pu.

        Returns
        -------
        ndarray, shape (n_exc,)
        """
        tau = np.full(self.n, np.inf)
        for module in MODULES:
            loop = getattr(module, "inner_loop_time_constants", None)
            rows = np.isin(self.kind, tuple(module.KINDS))
            if loop is not None and rows.any():
                tau = np.where(rows, loop(self, rows, VB0, efd0), tau)
        return tau

    def inner_loop(self, i: int) -> str:
        """The fast loop `inner_loop_time_constants` measures for exciter i (0-based): its
        type module's ``INNER_LOOP``.

        Parameters
        ----------
        i : int
            The exciter.

        Returns
        -------
        str
        """
        return TYPES[int(self.kind[i])].INNER_LOOP


check_packed(ExciterParams, PACKED, ("Vref",))


def _dc_saturation(e, rows=None) -> tuple[np.ndarray, np.ndarray]:
    """(Asat, Bsat) of the DC exciters' saturation from exc_con columns 12-15 (of the rows
    of the boolean mask ``rows`` only, default all; the others 0).

    dc_sat 0, PST exc_dc12's SE(E) = Asat exp(Bsat |E|): E2 (column 14) = 0 means columns
    13, 15 are Asat, Bsat themselves; otherwise PST's fit through (E1, SE1), (E2, SE2) --
    **QUIRK**: Bsat = ln(SE2 E2 / (SE1 E1)) / (E2 - E1), Asat = SE1 exp(-Bsat E1), so
    SE(E1) = SE1 but SE(E2) = SE2 E2 / E1 (docs 2.3).  dc_sat 1, and EXAC1/ESAC1A always, the
    quadratic SE(E) E = Bsat (E - Asat)^2 through both points (PSS/E; ANDES
    `ExcQuadSat`)."""
    rows = np.ones(len(e), bool) if rows is None else rows
    A, B = _exponential_fit(e, rows)
    quad = ((e.dc_sat == 1) | np.isin(e.type, QUAD_KINDS)) & rows
    if quad.any():
        Aq, Bq = quadratic_fit(
            *_dc_points(e),
            quad,
            "exc_con row {row}: DC exciter saturation points (E1, SE1, E2, SE2)",
        )
        A, B = np.where(quad, Aq, A), np.where(quad, Bq, B)
    return A, B


def _dc(e, name: str) -> np.ndarray:
    """exc_con column of a DC exciter quantity by its PST manual 3.11 Table 2 name (the
    declaration's ``alt`` name: KE, TE, E1, SE1, E2, SE2, KF_dc, TF_dc)."""
    return e.col(EXCITER.col(name))


def _dc_points(e):
    """The DC exciters' saturation points E1, SE1, E2, SE2 (exc_con columns 12-15)."""
    return tuple(_dc(e, name) for name in ("E1", "SE1", "E2", "SE2"))


def _exponential_fit(e, rows):
    E1, SE1, E2, SE2 = _dc_points(e)
    fit = (E2 != 0) & (e.dc_sat == 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        B = np.where(fit, np.log(SE2 * E2 / (SE1 * E1)) / (E2 - E1), SE2)
        A = np.where(fit, SE1 / np.exp(B * E1), SE1)
    bad = np.nonzero(np.isin(e.type, DC_KINDS) & (e.dc_sat == 0) & rows)[0]
    bad = bad[~np.isfinite(A[bad] + B[bad])]
    if bad.size:
        raise CaseError(
            f"exc_con row {bad[0] + 1}: DC exciter saturation points (E1, SE1, E2, "
            "SE2) give no exponential fit (need E1 != E2, SE1 E1 > 0, SE2 E2 > 0)"
        )
    return A, B


def check_table(e) -> None:
    """Refuse an exc_con row stabctl does not model, as the table is made (CaseError
    naming the row and field, the table's `_fail`): a time constant its type's ``NEEDS``
    lists (and T_F with a :data:`RATE_FEEDBACK` type's K_F != 0) below 1e-3 s, a row its
    type module's ``check`` refuses (where it has one), saturation points that give no
    fit (`_dc_saturation`: E1 = E2, ...).

    Parameters
    ----------
    e : stabctl.case.ExciterTable
        The table being made.

    Raises
    ------
    CaseError
        For the first such row.
    """
    for r in range(len(e)):
        kind = int(e.type[r])
        module = TYPES[kind]
        extra = (("TF", "TF"),) if module.RATE_FEEDBACK and e.KF[r] != 0 else ()
        for name, declared in module.NEEDS + extra:
            k = EXCITER.col(declared)
            if e.col(k)[r] < LBND:
                what = f"exciter type {kind} needs {name} >= {LBND} s"
                if extra and name == "TF":
                    what += " where KF != 0 (the rate feedback)"
                    fields: tuple[str, ...] = (declared, "KF")
                else:
                    fields = (declared,)
                e._fail(r, name, f"{what}, got {e.col(k)[r]:g}", k, fields=fields, rule=what)
        check = getattr(module, "check", None)
        problem = check(e, r) if check is not None else None
        if problem:
            e._refuse(r, problem)
    try:
        _dc_saturation(e)
    except CaseError:  # the first row whose points give no fit, named
        for r in range(len(e)):
            try:
                _dc_saturation(e, np.arange(len(e)) == r)
            except CaseError as exc:
                why = str(exc).split(": ", 1)[-1]
                e._fail(r, "E1", why, fields=("E1", "SE1", "E2", "SE2"), rule=why)
        raise


def exciter_params(case: Case) -> ExciterParams:
    """Exciter parameters (the table refused the types and options stabctl does not
    model as it was made, `check_table`)."""
    e = case.exciters
    A, B = _dc_saturation(e)
    dc = np.isin(e.type, DC_KINDS)
    ac = np.isin(e.type, QUAD_KINDS)
    ke = np.isin(e.type, KE_KINDS)
    pic = e.type == PIC1
    KA = np.where((e.type != SMP) & (e.KA == 0), 1.0, e.KA)
    given = {n: getattr(e, n).copy() for n in TABLE_FIELDS + tuple(p.name for p in OWN_PARAMS)}
    given.update(
        KA=KA,
        KP=np.where(pic, e.KP_pic, e.KP * np.exp(1j * np.deg2rad(e.thetaP))),
        KI=np.where(pic, e.KI_pic, e.KI),
    )
    return ExciterParams(
        kind=e.type.astype(int),
        mac=np.array([case.machine_index(m) for m in e.machine], int),
        **given,
        KE=np.where(ke, _dc(e, "KE"), 0.0),
        TE=np.where(ke, _dc(e, "TE"), 0.0),
        Asat=np.where(dc | ac, A, 0.0),
        Bsat=np.where(dc | ac, B, 0.0),
        KF=np.where(dc, _dc(e, "KF_dc"), np.where(np.isin(e.type, RATE_FEEDBACK), e.KF, 0.0)),
        TF=np.where(dc, _dc(e, "TF_dc"), np.where(np.isin(e.type, RATE_FEEDBACK), e.TF, 0.0)),
        sat_quadratic=(dc & (e.dc_sat == 1)) | ac,
        ke_given=dc & (e.ke_given == 1),
        ifd_machine=(e.type == ST3) & (e.ifd_machine == 1),
        VB_cap=np.where(np.isin(e.type, SOURCE_KINDS) & (e.VBmax > 0), e.VBmax, np.inf),
    )


def initial_source_voltage(p: ExciterParams, mp, V_mac, S_mac, vex):
    """The source term V_B (`source_voltage_of`; PST exc_st3 flag 0 for the ST3 read as PST
    reads it, its `ExciterParams.ifd_machine` False) of every
    exciter of :data:`SOURCE_KINDS` at the initial point (1 for the other types), (n_exc,):
    V_mac the complex terminal voltages, S_mac the machines' complex generation (system
    base), vex their field voltages (= field currents at rest), all (n_mac,); mp the
    MachineParams."""
    eterm = np.abs(V_mac)
    VB = np.ones(p.n)
    for i in np.nonzero(np.isin(p.kind, SOURCE_KINDS))[0]:
        m = p.mac[i]
        machine = ST3Machine(
            eterm[m], unit_phasor(V_mac[m]), S_mac.real[m], S_mac.imag[m], mp.mac_pot[m], vex[m]
        )
        pst = not p.ifd_machine[i]  # PST's F_EX quirk at its flag 0 (`st3._fex`): its reading
        VB[i] = source_voltage_of(
            p.kind[i], p.KP[i], p.KI[i], p.XL[i], p.KC[i], p.VB_cap[i], machine, pst
        )
    return VB


def initialise(p: ExciterParams, vex, eterm, VB=None, vc=None):
    """States (n_slots, n_exc), Vref (n_exc,) and the parameters with PSS/E's computed KE
    (DC exciters with KE = 0 get KE = -SE(Efd0), so that V_R starts at 0) from the
    machines' field voltage vex and terminal voltage eterm; VB is the ST3 source voltage
    (`initial_source_voltage`; needed for type 3); vc the voltage the transducers measure
    (`compensated`; default eterm).  Every transducer starts at vc; each type's module
    sets its other states on its rows and gives V_ref - vc (its ``initialise``), in the
    registry's order.  Raises CaseError when the initial point violates a limit PST
    checks (ST3: Efdmax or the V_I range; DC: the V_R limits) by more than
    `START_LIMIT_TOL` (stabctl.models.declaration)."""
    x = np.zeros((MAX_SLOTS, p.n))
    vc = eterm if vc is None else vc
    x[VTR] = vc
    VB = np.ones(p.n) if VB is None else VB
    ref = np.zeros(p.n)
    for module in MODULES:
        rows = np.isin(p.kind, tuple(module.KINDS))
        if rows.any():
            ref[rows], p = module.initialise(p, rows, vex, eterm, VB, x)
    return x[: p.n_slots()], vc + ref, p


# -- compiled runtime kernels: P is ExciterParams.packed(), x the exciter block of the
# -- state vector (n_slots, n_exc), i the exciter; each type's kernels are its module's,
# -- dispatched on kind by `field_voltage_at`, `derivatives` and `recorded_efd` (one line
# -- per type)


@kernel(inline="always")
def field_current(P, i, ifd):
    """The field current (pu on the machine base) of exciter i's machine where its type's
    equations read it (:data:`READS_IFD`), 0 for the other types; ifd (n_mac,) every
    machine's (`stabctl.models.machines.field_currents`)."""
    if P[i, E.KIND] in READS_IFD:
        return ifd[int(P[i, E.MAC])]
    return 0.0


@kernel(inline="always")
def stator(MP, xm, cur, rot, m, vt):
    """Machine m's terminal quantities as PST exc_st3 flag 1 recomputes them
    (`StatorQuantities`, `machines.stator_without_speed`), computed once per exciter and
    evaluation for `source_voltage`, `field_voltage` and `frozen_inputs`.

    Parameters
    ----------
    MP, xm, cur : ndarray
        The machines' packed parameters (machines.PACKED), states (6, n_mac) and network
        currents (n_mac,) complex, system base.
    rot : ndarray, shape (n_mac,)
        Each machine's exp(j delta) (`machines.internal_voltage`).
    m : int
        The machine.
    vt : complex
        Its terminal bus voltage, pu (its angle sets an ST3 source phasor).
    """
    ed, eq, cd, cq = mac.stator_without_speed(MP, xm, cur, rot, m)
    return StatorQuantities(ed, eq, cd, cq, magnitude(ed, eq), vt)


@kernel(inline="always")
def source_voltage(P, i, MP, xm, cur, rot, stator, ifd):
    """The source term V_B of exciter i (`source_voltage_of`; :data:`SOURCE_KINDS`), 1 for
    the other types: from its machine's terminal quantities `stator` (`stator`: as PST
    exc_st3 flag 1 recomputes them, with the terminal bus voltage, whose angle sets the
    source phasor), ifd the field current (`field_current`; the ST3 reads its own,
    `st3.field_current`, from MP, xm, cur, rot as `stator`); at most VBmax (PSS/E ESST3A's
    and ESST4B's ``VB`` limiter; inf without)."""
    kind = P[i, E.KIND]
    if kind not in SOURCE_KINDS:
        return 1.0
    m = int(P[i, E.MAC])
    fld = st3.field_current(P, i, MP, xm, cur, rot, m) if kind == ST3 else ifd
    return source_voltage_of(
        kind,
        P[i, E.KPR] + 1j * P[i, E.KPI],
        P[i, E.KI],
        P[i, E.XL],
        P[i, E.KC],
        P[i, E.VBCAP],
        _source_machine(MP, m, stator, fld),
        RUNNING,
    )


@kernel(inline="always")
def _source_machine(MP, m, stator, fld):
    """`ST3Machine` of machine m from its `StatorQuantities` and field current fld."""
    ed, eq, cd, cq, et, vt = stator
    pot = MP[m, mac.K.POT]
    return ST3Machine(et, unit_phasor(vt), eq * cq + ed * cd, eq * cd - ed * cq, pot, fld)


@kernel(inline="always")
def field_voltage(P, x, i, xm, et, pss_out, ifd, VB, ieee):
    """Field voltage exciter i hands its machine (PST flag 1), pu on the machine base:
    `field_voltage_at` with its machine's terminal voltage (times its speed with
    exc_con column 45, ``efd_speed``, = 1).

    Parameters
    ----------
    P, x, i : ndarray, ndarray, int
        The exciters' packed parameters, states (n_slots, n_exc), the exciter.
    xm : ndarray, shape (6, n_mac)
        The machines' states.
    et : float
        The machine's terminal voltage V_t, pu (`stator`: PST exc_st3's speed-free
        stator equations, `machines.stator_without_speed`).
    pss_out : float
        The output of the machine's PSS (0 without).
    ifd : float
        The machine's field current, `field_current`.
    VB : float
        The source term, `source_voltage`.
    ieee : bool
        The IEEE 421.5 convention (limited states are read clipped to their limits).
    """
    m = int(P[i, E.MAC])
    efd = field_voltage_at(P, x, i, et, pss_out, VB, ifd, ieee)
    return efd * xm[_OMEGA, m] if P[i, E.EFD_SPEED] == 1 else efd


@kernel
def compensated(P, i, vt, it):
    """The voltage exciter i's transducer measures: abs(V_t + (R_C + j X_C) I_t) (IEEE
    421.5 load compensator), for the terminal voltage vt and the machine's current it
    (complex, one frame, machine base); abs(vt) without compensation."""
    return abs(vt + complex(P[i, E.RCOMP], P[i, E.XCOMP]) * it)


@kernel
def derivatives(P, x, i, vc, eterm, pss_out, efd, ifd, VB, dx, ieee, reach):
    """Derivatives of exciter i into dx[:, i] (PST flag 2); clamps its limited state in x.

    Every type: the voltage transducer lag T_R on vc (pu; the terminal voltage eterm, or
    the load-compensated voltage `compensated`) and the error V_ref - V_TR + pss_out;
    then its type module's ``derivatives``.  efd is the field voltage `field_voltage`
    gave, ifd the field current `field_current` gave, VB the source term
    `source_voltage` gave; reach (s): DC2's V_t-scaled V_R limits (on eterm) hold a state
    within that reach (`blocks.nonwindup`; the run's step, 0 in the linearisation).
    """
    zero_column(dx, i)
    vtr, dx[VTR, i] = lag(vc, x[VTR, i], P[i, E.TR])
    err = P[i, E.VREF] - vtr + pss_out
    type_derivatives(P, x, i, err, eterm, efd, ifd, pss_out, VB, dx, ieee, reach)


@kernel
def recorded_efd(P, x, i, efd_alg):
    """Efd as PST records it: the (clamped) smpexc state, the DC Efd state, or the ST3
    (and bus-fed smpexc) algebraic value efd_alg (`field_voltage`); efd_alg, the
    machine's, with ``efd_speed``."""
    if P[i, E.EFD_SPEED] == 1:
        return efd_alg
    return type_recorded_efd(P, x, i, efd_alg)


#: the inputs an exciter integrated in sub-intervals holds over a step (`frozen_inputs`,
#: `advance_frozen`), columns of a row: its machine's stator voltage (`field_voltage`'s
#: V_t), the speed factor of efd_speed, the PSS output, the field current, the source
#: term, the transducer's input, the terminal voltage and V_ref
(U_VT, U_SPEED, U_PSS, U_IFD, U_VB, U_VC, U_ETERM, U_VREF) = range(8)
N_FROZEN = 8
#: the one exciter of `advance_frozen`'s one-row arrays, a numpy integer (a Python literal
#: passed to a kernel compiles it once per value: tests/test_jit_rules.py)
_ROW = np.int64(0)


@kernel(inline="always")
def frozen_inputs(P, i, xm, et, pss_out, ifd, VB, vc, eterm, u):
    """Write exciter i's inputs of this evaluation into the row u (N_FROZEN,): what
    `field_voltage` and `derivatives` read besides its own states (their arguments of the
    same names), for `advance_frozen`."""
    m = int(P[i, E.MAC])
    u[U_VT] = et
    u[U_SPEED] = xm[_OMEGA, m] if P[i, E.EFD_SPEED] == 1 else 1.0
    u[U_PSS], u[U_IFD], u[U_VB], u[U_VC], u[U_ETERM] = pss_out, ifd, VB, vc, eterm
    u[U_VREF] = P[i, E.VREF]


@kernel
def advance_frozen(P, x, i, u, hh, n, ieee, reach, out, work):
    """Exciter i's states over hh (s) in n steps of Heun's method of hh/n each, its inputs
    held at u (`frozen_inputs`): PowerWorld's sub-interval integration of a fast exciter
    (its Transient Stability "sub-interval" option), so that a loop faster than the
    network step (ACTIVSg2000's EXAC2 regulators, `inner_loop_time_constants`) is
    integrated stably while the network is solved at the step.  Each sub-step evaluates
    `field_voltage_at` and `derivatives` (which clamp the limited states, as a step of the
    whole model does).

    Parameters
    ----------
    P : ndarray, shape (n_exc, n_cols)
        The exciters' packed parameters (V_ref taken from u).
    x : ndarray, shape (n_slots, n_exc)
        The exciters' states at the step's start (not changed).
    i : int
        The exciter.
    u : ndarray, shape (N_FROZEN,)
        Its inputs held over the step.
    hh : float
        The step, s.
    n : int
        The number of sub-steps (>= 1).
    ieee : bool
        The IEEE 421.5 convention.
    reach : float
        The limiters' reach of the whole step (s), shared out over the sub-steps.
    out : ndarray, shape (n_slots,)
        Written with the states at the step's end.
    work : tuple of 5 ndarray
        Scratch (`frozen_work`), overwritten: one allocation for every exciter of a
        step instead of five per exciter (18 such exciters on ACTIVSg2000).
    """
    P1, xs = work[0], work[1]
    for c in range(P.shape[1]):
        P1[0, c] = P[i, c]
    P1[0, E.VREF] = u[U_VREF]
    rows = x.shape[0]
    for r in range(rows):
        xs[r, 0] = x[r, i]
    _heun_substeps(P1, u, hh / n, n, ieee, reach / n, work[1:])
    for r in range(rows):
        out[r] = xs[r, 0]


@kernel
def frozen_work(n_cols, rows):
    """`advance_frozen`'s scratch for exciters of n_cols packed parameters and rows state
    slots: one parameter row (1, n_cols), then the states, the predictor and the
    derivatives at both (rows, 1) each (every slot written before it is read: the
    derivatives zero their column first)."""
    return (
        np.empty((1, n_cols)),
        np.empty((rows, 1)),
        np.empty((rows, 1)),
        np.zeros((rows, 1)),
        np.zeros((rows, 1)),
    )


@kernel
def _heun_substeps(P1, u, hs, n, ieee, reach, work):
    """`advance_frozen`'s n Heun steps of hs (s) on the one exciter of P1, its states
    work[0] (n_slots, 1) updated in place; work = (states, predictor, derivatives at both).
    A kernel of its own so that it can borrow its arrays (`stabctl._jit.borrow`): the
    caller owns them for the whole call."""
    P1, u, (xs, xq, d1, d2) = borrowed((P1, u, work))
    rows = xs.shape[0]
    for _ in range(n):
        _held_derivatives(P1, xs, u, d1, ieee, reach)
        for r in range(rows):
            xq[r, 0] = xs[r, 0] + hs * d1[r, 0]
        _held_derivatives(P1, xq, u, d2, ieee, reach)
        for r in range(rows):
            xs[r, 0] = xs[r, 0] + 0.5 * hs * (d1[r, 0] + d2[r, 0])


@kernel(inline="always")
def _held_derivatives(P1, x1, u, d, ieee, reach):
    """The one exciter of P1 (one row) at its states x1 (n_slots, 1) with the inputs u held
    (`frozen_inputs`): its field voltage, then its derivatives into d (n_slots, 1)."""
    efd = field_voltage_at(P1, x1, _ROW, u[U_VT], u[U_PSS], u[U_VB], u[U_IFD], ieee)
    derivatives(
        P1, x1, _ROW, u[U_VC], u[U_ETERM], u[U_PSS], efd * u[U_SPEED], u[U_IFD], u[U_VB], d,
        ieee, reach,
    )  # fmt: skip
