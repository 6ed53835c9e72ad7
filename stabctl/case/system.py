"""stabctl's case model: the static and dynamic data of one power system.

A :class:`Case` holds the system base and one table per kind of data. Every table is a
small frozen dataclass of read-only 1-D numpy arrays, one array per PST column, named in
the field's terms (``case.buses.vmag``, ``case.machines.xdp``, ``case.exciters.KA``).
Row ``i`` of every array of a table is row ``i`` of the PST matrix. ``table.matrix()``
gives the PST matrix back (columns in PST order), so a PST model can be written against
either form.

Units: per unit on the system base (``Case.base_mva``) for network and load data, per unit
on the machine base (``machines.mva``) for machine and controller data, seconds for time
constants, kV for ``buses.kv``, degrees where a name ends in ``_deg`` (as in PST's data
files).

Values are PST's raw data: nothing is replaced by a model default (a T'qo of 0 stays 0, a
tap of 0 stays 0 and means 1 in :mod:`stabctl.network.ybus`, a Q limit of 0 stays 0 and means
"no limit" in :mod:`stabctl.network.powerflow`). Trailing columns that a PST matrix may omit are
filled with PST's own defaults (given per table below).

Source of the column lists: the PST manual (Power System Toolbox 3.0, Rogers & Chow,
``shared/reference/pstess/pst_man.pdf``): bus and line, section 1.3 and the ``loadflow``
description; ``mac_con`` section 3.22 Table 10; ``exc_con`` sections 3.38 Table 15 (type 0),
3.11 Table 2 (types 1, 2) and 3.13 Table 3 (type 3); ``pss_con`` section 3.30 Table 13;
``tg_con`` section 3.45; ``load_con`` section 3.29 Table 12; ``sw_con`` section 2.5; and the
comments of the PSTess data files (``d2asbegp.m``, ``d_minniWECC_base.m``).

Construction validates the data and raises :class:`~stabctl.errors.CaseError` naming the
table, the row (1-based, with its bus or machine number) and the field.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import re
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING, ClassVar, Self

import numpy as np

from stabctl.case.events import events_of_records
from stabctl.errors import CaseError, InputError, UnknownBusError, WrongTypeError, is_number
from stabctl.models import converters as _converters
from stabctl.models import exciters as _exciters
from stabctl.models import governors as _governors
from stabctl.models import motors as _motors
from stabctl.models import pss as _pss
from stabctl.models import shafts as _shafts
from stabctl.models import svcs as _svcs
from stabctl.models.converters import CONVERTER
from stabctl.models.converters.rules import COMPONENTS, share_sums
from stabctl.models.declaration import LEAD_LAG_MIN, Family, array_dataclass, choices_message
from stabctl.models.exciters import EXCITER, SATURATED_EXCITERS
from stabctl.models.governors import GOVERNOR
from stabctl.models.machines import MACHINE
from stabctl.models.motors import MOTOR
from stabctl.models.pss import PSS
from stabctl.models.shafts import SHAFT
from stabctl.models.svcs import SVC

__all__ = [
    "Table",
    "BusTable",
    "BranchTable",
    "MachineTable",
    "ExciterTable",
    "PssTable",
    "GovernorTable",
    "LoadTable",
    "InjectionTable",
    "ConverterTable",
    "ShaftTable",
    "SwitchedShuntTable",
    "MotorTable",
    "SvcTable",
    "RegulationTable",
    "Case",
    "require_case",
    "SWING",
    "PV",
    "PQ",
    "CASE_DIR",
    "table_label",
    "tables_named",
]

#: PST bus types (bus matrix column 10).
SWING, PV, PQ = 1, 2, 3


# --------------------------------------------------------------------------------------
# generic table
# --------------------------------------------------------------------------------------


#: the tables as the file being read names them: PST name -> the file's name (a stabctl
#: case JSON names its tables by `Case` field, ``"machines"``); None: PST's names
_FILE_TABLES: ContextVar[Mapping[str, str] | None] = ContextVar("stabctl_file_tables", default=None)


@contextmanager
def tables_named(names: Mapping[str, str]) -> Iterator[None]:
    """Within this block, errors name each table as a file names it (`table_label`).

    Parameters
    ----------
    names : Mapping[str, str]
        PST table name (``"mac_con"``, a table's ``TABLE``) -> the file's name of it
        (``"machines"``).

    Yields
    ------
    None
        Nothing: a block of errors naming the file's tables.
    """
    token = _FILE_TABLES.set(names)
    try:
        yield
    finally:
        _FILE_TABLES.reset(token)


def table_label(table: str) -> str:
    """A table as messages name it: ``table 'machines'`` inside `tables_named` (as the
    file read names it), else the PST name (``mac_con``).

    Parameters
    ----------
    table : str
        The table's PST name (``TABLE``).

    Returns
    -------
    str
        For messages.
    """
    names = _FILE_TABLES.get()
    return f"table '{names[table]}'" if names and table in names else table


def _where(table: str, row: int, key: str | None, value, fld: str, col: int | None = None) -> str:
    """Location prefix of an error: table (`table_label`), 1-based row, its bus/machine
    number, field (and its column, for a field named by another type's name of the
    column)."""
    ident = "" if key is None or value is None else f" ({key} {_fmt(value)})"
    where = f"{table_label(table)} row {row + 1}{ident}, field '{fld}'"
    return where + (f" (column {col})" if col else "")


#: a model check's problem text: the fields it names (quoted, or bare names after a model's
#: name: "ST8C field KIA: ..."), an aside in parentheses, then why
_NAME = r"(?:'[^']+'|[A-Za-z_]\w*)"
_PROBLEM = re.compile(
    rf"(?:\w+ )?fields? ({_NAME}(?:(?:, |\.\.){_NAME})*)( \([^)]*\))?: (.*)", re.S
)


def _fmt(x) -> str:
    x = float(x)
    return str(int(x)) if x.is_integer() else repr(x)


def _whole(number) -> int:
    """``int(number)``, refusing a number with a fraction (ValueError): ``int(3.5)`` is 3,
    so a fault at bus 3.5 ran at bus 3."""
    if isinstance(number, (float, np.floating)) and not float(number).is_integer():
        raise ValueError(f"{number} is not a whole number")
    return int(number)


def _listed(numbers: np.ndarray) -> str:
    """Device numbers for a message, the first five of more than six."""
    shown = [_fmt(n) for n in numbers]
    return ", ".join(shown) if len(shown) <= 6 else f"{', '.join(shown[:5])}, ... ({len(shown)})"


@dataclass(frozen=True, eq=False)
class Table:
    """Base of all case tables: one read-only float64 array per PST column.

    Subclasses declare their fields in PST column order and set:

    * ``TABLE`` -- the PST matrix name (used in error messages),
    * ``MIN_COLUMNS`` -- fewest columns a PST matrix may give,
    * ``DEFAULTS`` -- value of each omitted trailing column (by field name),
    * ``KEY`` -- field that identifies a row in messages (bus or machine number),
    * ``KEY_LABEL`` -- what that field is called in messages ("bus", "machine"),
    * ``INTEGER`` -- fields that must hold integers (numbers, types).

    The dynamic-data tables (machines, exciters, PSS, governors) get all of these, and
    their fields, from a :class:`~stabctl.models.declaration.Family` declaration (``FAMILY``,
    see :func:`_declared`), which also gives each column's bounds and allowed values.

    Raises :class:`CaseError` on construction if arrays differ in length, are not 1-D,
    hold non-finite values, an integer field holds a non-integer, or a declared bound or
    choice is violated.
    """

    TABLE: ClassVar[str] = "table"
    MIN_COLUMNS: ClassVar[int] = 0
    DEFAULTS: ClassVar[Mapping[str, float]] = {}
    KEY: ClassVar[str | None] = None
    KEY_LABEL: ClassVar[str] = ""
    INTEGER: ClassVar[tuple[str, ...]] = ()
    FAMILY: ClassVar[Family | None] = None

    if TYPE_CHECKING:
        # for mypy only: the declared tables (machines, exciters, PSS, governors) get
        # their column fields from their Family when the class is made (`_declared`)
        def __getattr__(self, name: str) -> np.ndarray: ...

    def __post_init__(self):
        n = None
        for name in self.columns():
            arr = np.array(getattr(self, name), dtype=float, copy=True)
            if arr.ndim == 0:
                arr = arr.reshape(1)
            if arr.ndim != 1:
                raise CaseError(
                    f"{table_label(self.TABLE)}: field '{name}' must be 1-D, has shape {arr.shape}"
                )
            if n is None:
                n = arr.size
            elif arr.size != n:
                raise CaseError(
                    f"{table_label(self.TABLE)}: field '{name}' has {arr.size} rows, expected {n}"
                )
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)
        for name in self.columns():
            arr = getattr(self, name)
            bad = np.flatnonzero(~np.isfinite(arr))
            if bad.size:
                self._fail(bad[0], name, f"non-finite value {arr[bad[0]]}")
            bad = np.flatnonzero(np.abs(arr) > LARGEST_VALUE)
            if bad.size:
                big = f"{arr[bad[0]]:g} is beyond +-{LARGEST_VALUE:g}: no datum is that large"
                self._fail(bad[0], name, big)
            if name in self.INTEGER:
                bad = np.flatnonzero(arr != np.round(arr))
                if bad.size:
                    self._fail(bad[0], name, f"must be an integer, got {arr[bad[0]]}")
        self._check_declared()
        self._check()

    # -- construction ---------------------------------------------------------------

    @classmethod
    def columns(cls) -> tuple[str, ...]:
        """Field names in PST column order (column k+1 of the PST matrix is ``columns()[k]``)."""
        return tuple(f.name for f in dataclasses.fields(cls))

    @classmethod
    def from_matrix(cls, matrix) -> Self:
        """Build the table from a PST matrix (rows x columns, PST column order).

        Omitted trailing columns (down to ``MIN_COLUMNS``) take ``DEFAULTS``; an empty
        matrix (``[]``) gives an empty table. Raises :class:`CaseError` on a wrong column
        count or a ragged matrix.
        """
        cols = cls.columns()
        mat = _as_matrix(matrix, cls.TABLE)
        nrow, ncol = mat.shape
        if nrow == 0:
            return cls(**{c: np.zeros(0) for c in cols})
        if not cls.MIN_COLUMNS <= ncol <= len(cols):
            want = (
                f"{len(cols)}"
                if cls.MIN_COLUMNS == len(cols)
                else f"{cls.MIN_COLUMNS} to {len(cols)}"
            )
            raise CaseError(
                f"{cls.TABLE}: wrong column count {ncol}, expected {want} ({', '.join(cols)})"
            )
        data = {c: mat[:, k] for k, c in enumerate(cols[:ncol])}
        for c in cols[ncol:]:
            data[c] = np.full(nrow, float(cls.DEFAULTS.get(c, 0.0)))
        return cls(**data)

    @classmethod
    def empty(cls) -> Self:
        """A table with no rows."""
        return cls.from_matrix(np.zeros((0, len(cls.columns()))))

    # -- access -----------------------------------------------------------------------

    def __len__(self) -> int:
        return int(getattr(self, self.columns()[0]).size)

    def matrix(self) -> np.ndarray:
        """The PST matrix, shape (rows, len(columns())), float64, a fresh writable copy."""
        return np.column_stack([getattr(self, c) for c in self.columns()]).reshape(
            len(self), len(self.columns())
        )

    def col(self, k: int) -> np.ndarray:
        """PST column ``k`` (1-based, as in the PST manual), read-only array of shape (rows,)."""
        cols = self.columns()
        if not 1 <= k <= len(cols):
            raise CaseError(f"{self.TABLE}: no column {k} (has 1..{len(cols)})")
        return getattr(self, cols[k - 1])

    def replace(self, **changes) -> Table:
        """A copy with some columns replaced (validated again)."""
        return dataclasses.replace(self, **changes)

    def select(self, rows) -> Table:
        """A copy holding only ``rows`` (index array or boolean mask)."""
        rows = np.asarray(rows)
        return type(self)(**{c: getattr(self, c)[rows] for c in self.columns()})

    def equals(self, other: Table) -> bool:
        """True if ``other`` is the same kind of table with identical values."""
        return type(self) is type(other) and all(
            np.array_equal(getattr(self, c), getattr(other, c)) for c in self.columns()
        )

    # -- validation helpers -----------------------------------------------------------

    def _key_value(self, row: int):
        if self.KEY is None:
            return None
        return getattr(self, self.KEY)[row]

    def _fail(
        self,
        row: int,
        fld: str,
        what: str,
        col: int | None = None,
        *,
        fields: tuple[str, ...] = (),
        rule: str = "",
    ):
        """Raise the CaseError of row ``row`` (0-based), field ``fld`` (or an ``alt`` name,
        its column ``col``): the message ``what``; its attributes (`CaseError`) the fields
        the rule reads (``fields``, default ``fld`` alone), their values on the row and
        the ``rule`` (default ``what``) for an importer to name its source."""
        row = int(row)
        names = tuple(fields) or (fld,)
        raise CaseError(
            f"{self._location(row, fld, col)}: {what}",
            table=self.TABLE,
            row=row,
            fields=names,
            values=tuple(self._value(n, row) for n in names),
            rule=rule or what,
        )

    def _location(self, row: int, fld: str, col: int | None) -> str:
        """Where an error is, for messages: table, row (0-based ``row``), its key and the
        field ``fld`` (or column ``col``)."""
        key = self._key_value(row) if len(self) else None
        return _where(self.TABLE, row, self.KEY_LABEL, key, fld, col)

    def _value(self, name: str, row: int) -> float:
        """The value of field (or ``alt`` name) ``name`` on ``row``; NaN for a name the
        table has not."""
        if name in self.columns() and row < len(self):
            return float(getattr(self, name)[row])
        if self.FAMILY is not None and row < len(self):
            try:
                return float(self._named(name)[0][row])
            except KeyError:
                pass
        return float("nan")

    def _refuse(self, row: int, problem: str):
        """Raise for row ``row`` (0-based) what a model's own check says of it:
        ``problem`` as the type modules' ``check`` give it, ``"field 'X': why"`` or
        ``"fields 'X', 'Y': why"`` (the fields named first, each quoted)."""
        m = _PROBLEM.match(problem)
        if m is None:
            raise CaseError(
                f"{table_label(self.TABLE)} row {int(row) + 1}, {problem}",
                table=self.TABLE,
                row=int(row),
            )
        names = tuple(a or b for a, b in re.findall(r"'([^']+)'|([A-Za-z_]\w*)", m.group(1)))
        why = (f"{m.group(2)[2:-1]}: " if m.group(2) else "") + m.group(3)
        self._fail(row, names[0], why, fields=names, rule=why)

    def _require(self, mask: np.ndarray, fld: str, what: str, fields: tuple[str, ...] = ()):
        """Raise for the first row where ``mask`` is False (``fields``: those the rule
        reads, ``fld`` first; default ``fld`` alone)."""
        bad = np.flatnonzero(~np.asarray(mask, dtype=bool))
        if bad.size:
            val = getattr(self, fld)[bad[0]]
            self._fail(bad[0], fld, f"{what}, got {_fmt(val)}", fields=fields, rule=what)

    def _require_row(self, mask: np.ndarray, fld: str, what, fields: tuple[str, ...] = ()):
        """Raise for the first row where ``mask`` is False, ``what(row)`` saying why
        (``fields`` as `_require`'s)."""
        bad = np.flatnonzero(~np.asarray(mask, dtype=bool))
        if bad.size:
            val = getattr(self, fld)[bad[0]]
            why = what(bad[0])
            self._fail(bad[0], fld, f"{why}, got {_fmt(val)}", fields=fields, rule=why)

    def _nonnegative(self, *fields: str):
        for f in fields:
            self._require(getattr(self, f) >= 0, f, "must be >= 0")

    def _positive(self, *fields: str):
        for f in fields:
            self._require(getattr(self, f) > 0, f, "must be > 0")

    def _unique(self, fld: str, what: str):
        vals = getattr(self, fld)
        _, _first, counts = np.unique(vals, return_index=True, return_counts=True)
        if np.any(counts > 1):
            seen: dict[float, int] = {}
            for i, v in enumerate(vals):
                if v in seen:
                    self._fail(i, fld, f"duplicate {what} {_fmt(v)} (first at row {seen[v] + 1})")
                seen[v] = i

    def _check_declared(self):
        """The declared choices and bounds of ``FAMILY``, in column order."""
        for p in self.FAMILY.params if self.FAMILY else ():
            arr = getattr(self, p.name)
            if p.choices:
                self._require(np.isin(arr, p.choices), p.name, choices_message(p))
            if p.lo is not None:
                self._require(arr >= p.lo, p.name, f"must be >= {_fmt(p.lo)}")
            if p.hi is not None:
                self._require(arr <= p.hi, p.name, f"must be <= {_fmt(p.hi)}")
        self._check_limits()

    def _named(self, name: str) -> tuple[np.ndarray, int | None]:
        """The column of field ``name``, or of the column another type reads as ``name``
        (a declared ``alt`` name) with its 1-based column number (None for a field)."""
        if name in self.columns():
            return getattr(self, name), None
        assert self.FAMILY is not None
        k = self.FAMILY.col(name)
        return self.col(k), k

    def _check_limits(self):
        """The `stabctl.models.declaration.Limits` of each row's type (``FAMILY.limits``):
        the first row of a type holding a value its type's equations cannot take, named
        with the type and the limits' source."""
        fam = self.FAMILY
        if fam is None or not fam.limits or not len(self):
            return
        for kind, limits in fam.limits.items():
            rows = self.type == kind
            if not rows.any():
                continue
            for lim in limits:
                tail = f"{fam.type_names.get(kind, f'type {kind}')}; {lim.source}"
                for names, ok, must in (
                    (lim.nonnegative, lambda v: v >= 0, ">= 0"),
                    (lim.positive, lambda v: v > 0, "> 0"),
                ):
                    for name in names:
                        v, col = self._named(name)
                        bad = np.flatnonzero(rows & ~ok(v))
                        if bad.size:
                            r = bad[0]
                            what = f"must be {must} ({tail})"
                            self._fail(r, name, f"{what}, got {_fmt(v[r])}", col, rule=what)
                for hi, lo in lim.ordered:
                    (a, col), (b, _) = self._named(hi), self._named(lo)
                    bad = np.flatnonzero(rows & ~(a >= b))
                    if bad.size:
                        r = bad[0]
                        what = f"must be >= {lo} = {_fmt(b[r])} ({tail}), got {_fmt(a[r])}"
                        rule = f"the upper limit must be >= the lower ({tail})"
                        self._fail(r, hi, what, col, fields=(hi, lo), rule=rule)
                for name in lim.one:
                    v, col = self._named(name)
                    bad = np.flatnonzero(rows & (v != 1))
                    if bad.size:
                        what = f"must be 1 ({tail})"
                        self._fail(bad[0], name, f"{what}, got {_fmt(v[bad[0]])}", col, rule=what)
                for lead, lag in lim.leads:
                    (a, col), (b, _) = self._named(lead), self._named(lag)
                    bad = np.flatnonzero(rows & (a != 0) & (b < LEAD_LAG_MIN))
                    if bad.size:
                        r = bad[0]
                        rule = (  # in no table's names: a DYR's message gives its own
                            f"a lead without its lag (a lag below {LEAD_LAG_MIN:g} s bypasses "
                            f"the lead-lag) ({tail})"
                        )
                        what = (
                            f"must be 0 where {lag} = {_fmt(b[r])} (below {LEAD_LAG_MIN:g} s: no "
                            f"lag, the lead-lag bypassed) ({tail}), got {_fmt(a[r])}"
                        )
                        self._fail(r, lead, what, col, fields=(lead, lag), rule=rule)

    def _check(self):
        """Table-local validation (subclasses)."""


def _declared(family: Family):
    """Class decorator: a frozen :class:`Table` dataclass whose fields, column order and
    class constants come from ``family``.

    Parameters
    ----------
    family : Family
        The declaration (:mod:`stabctl.models.declaration`): one ``np.ndarray`` field per
        :class:`~stabctl.models.declaration.Param` in column order; ``TABLE``, ``MIN_COLUMNS``,
        ``DEFAULTS``, ``KEY``, ``KEY_LABEL``, ``INTEGER`` and ``FAMILY`` set from it; the
        ``{columns}`` mark of the class docstring replaced by the declaration's column
        table.

    Returns
    -------
    callable
        The decorator.
    """

    def wrap(cls):
        cls.TABLE, cls.MIN_COLUMNS, cls.FAMILY = family.table, family.min_columns, family
        cls.DEFAULTS, cls.INTEGER = family.defaults, family.integer
        cls.KEY, cls.KEY_LABEL = family.key, family.key_label
        if cls.__doc__:
            cls.__doc__ = cls.__doc__.replace("{columns}", family.rst_table())
        return array_dataclass(cls, [p.name for p in family.params])

    return wrap


def _as_matrix(matrix, table: str) -> np.ndarray:
    """A 2-D float array from a nested list / array; [] -> shape (0, 0)."""
    if isinstance(matrix, np.ndarray) and matrix.ndim == 2:
        return matrix.astype(float)
    rows = list(matrix) if matrix is not None else []
    if not rows:
        return np.zeros((0, 0))
    if np.isscalar(rows[0]):  # a single row given flat
        rows = [rows]
    lengths = [len(r) for r in rows]
    if len(set(lengths)) != 1:  # the row that differs from the most rows, not from row 1
        count = max(set(lengths), key=lambda n: (lengths.count(n), -lengths.index(n)))
        i = next(i for i, n in enumerate(lengths) if n != count)
        others = lengths.count(count)
        raise CaseError(
            f"{table} row {i + 1}: {lengths[i]} columns, {others} other row(s) have {count}"
            + ("" if others > 1 else f" (row {lengths.index(count) + 1})")
        )
    try:
        return np.array(rows, dtype=float)
    except (TypeError, ValueError) as exc:
        raise CaseError(f"{table}: not a numeric matrix ({exc})") from None


# --------------------------------------------------------------------------------------
# the tables
# --------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class BusTable(Table):
    """Bus data: PST ``bus`` matrix, 15 columns (PST manual section 1.3, ``loadflow``).

    ==  ==========  ===============================================================
    1   number      bus number (PST numbering, any positive integers)
    2   vmag        voltage magnitude, pu (setpoint at PV/swing buses, start value else)
    3   vang_deg    voltage angle, degrees (fixed at the swing bus, start value else)
    4   pgen        generation P, pu on system base
    5   qgen        generation Q, pu
    6   pload       load P, pu
    7   qload       load Q, pu
    8   gshunt      shunt conductance G, pu (at 1 pu voltage)
    9   bshunt      shunt susceptance B, pu (capacitive > 0)
    10  kind        bus type: 1 swing, 2 generator (PV), 3 load (PQ)
    11  qmax        generator Q upper limit, pu (0: no limit, as PST's loadflow)
    12  qmin        generator Q lower limit, pu (0: no limit)
    13  kv          rated voltage, kV (0: 1, as PST's loadflow)
    14  vmax        upper voltage limit, pu (0: 1.5)
    15  vmin        lower voltage limit, pu (0: 0.5)
    ==  ==========  ===============================================================

    Omitted columns (PST's ``loadflow`` defaults): qmax 9999, qmin -9999, kv 1, vmax 1.5,
    vmin 0.5. Validation: unique positive integer numbers, kind in {1, 2, 3}, vmag > 0,
    qmax >= qmin and vmax >= vmin (0 read as above), kv >= 0.
    """

    number: np.ndarray
    vmag: np.ndarray
    vang_deg: np.ndarray
    pgen: np.ndarray
    qgen: np.ndarray
    pload: np.ndarray
    qload: np.ndarray
    gshunt: np.ndarray
    bshunt: np.ndarray
    kind: np.ndarray
    qmax: np.ndarray
    qmin: np.ndarray
    kv: np.ndarray
    vmax: np.ndarray
    vmin: np.ndarray

    TABLE: ClassVar[str] = "bus"
    MIN_COLUMNS: ClassVar[int] = 10
    DEFAULTS: ClassVar[Mapping[str, float]] = {
        "qmax": 9999.0,
        "qmin": -9999.0,
        "kv": 1.0,
        "vmax": 1.5,
        "vmin": 0.5,
    }
    KEY: ClassVar[str] = "number"
    KEY_LABEL: ClassVar[str] = "bus"
    INTEGER: ClassVar[tuple[str, ...]] = ("number", "kind")

    def _check(self):
        self._require(self.number > 0, "number", "bus number must be a positive integer")
        self._unique("number", "bus number")
        self._require(np.isin(self.kind, (SWING, PV, PQ)), "kind", "bus type must be 1, 2 or 3")
        self._require(self.vmag > 0, "vmag", "voltage magnitude must be > 0")
        qmax = np.where(self.qmax == 0, np.inf, self.qmax)  # 0: no limit (PST)
        qmin = np.where(self.qmin == 0, -np.inf, self.qmin)
        self._require(qmax >= qmin, "qmax", "generator Q limits: qmax must be >= qmin")
        vmax = np.where(self.vmax == 0, 1.5, self.vmax)
        vmin = np.where(self.vmin == 0, 0.5, self.vmin)
        self._require(vmax >= vmin, "vmax", "voltage limits: vmax must be >= vmin")
        # a rated voltage is a magnitude; 0 is "not given" (PST's loadflow reads it as 1,
        # PSS/E RAW's BASKV 0), which stabctl.estimation.c37 refuses for a PMU's bus
        self._require(self.kv >= 0, "kv", "rated voltage must be >= 0 kV (0: not given)")


@dataclass(frozen=True, eq=False)
class BranchTable(Table):
    """Branch (line and transformer) data: PST ``line`` matrix (PST manual section 1.3).

    ==  ==========  ===============================================================
    1   from_bus    from bus number (tap side)
    2   to_bus      to bus number
    3   r           series resistance, pu on system base
    4   x           series reactance, pu
    5   b           total line charging susceptance, pu (half at each end)
    6   tap         off-nominal tap ratio on the from side (0 means 1)
    7   phase_deg   phase shift, degrees (from side)
    8   tapmax      maximum tap (0: tap fixed in the power flow)
    9   tapmin      minimum tap
    10  tapstep     tap step size
    11  g_from      line-end shunt conductance at the from end, pu (PSS/E GI)
    12  b_from      line-end shunt susceptance at the from end, pu (PSS/E BI)
    13  g_to        line-end shunt conductance at the to end, pu (PSS/E GJ)
    14  b_to        line-end shunt susceptance at the to end, pu (PSS/E BJ)
    ==  ==========  ===============================================================

    Parallel circuits are separate rows. Omitted columns: tap 1, the rest 0 (the miniWECC
    ``line`` matrix has 5 columns, PST's 10).  Line-end shunts (columns 11-14, stabctl's)
    are switched with the branch, in addition to the charging ``b``. Validation: from/to are
    integers, the series impedance is not zero (r < 0 allowed: network equivalents carry
    it; x < 0: series capacitors), from != to, tap >= 0; a tap changer (tapmax != 0) has
    tapmin > 0, tapmax >= tapmin and tapstep > 0.  The phase shift and the shunts take
    any value."""

    from_bus: np.ndarray
    to_bus: np.ndarray
    r: np.ndarray
    x: np.ndarray
    b: np.ndarray
    tap: np.ndarray
    phase_deg: np.ndarray
    tapmax: np.ndarray
    tapmin: np.ndarray
    tapstep: np.ndarray
    g_from: np.ndarray
    b_from: np.ndarray
    g_to: np.ndarray
    b_to: np.ndarray

    TABLE: ClassVar[str] = "line"
    MIN_COLUMNS: ClassVar[int] = 5
    DEFAULTS: ClassVar[Mapping[str, float]] = {"tap": 1.0}
    KEY: ClassVar[str | None] = None
    INTEGER: ClassVar[tuple[str, ...]] = ("from_bus", "to_bus")

    def _location(self, row: int, fld: str, col: int | None) -> str:
        ident = f" ({_fmt(self.from_bus[row])}-{_fmt(self.to_bus[row])})" if len(self) else ""
        return f"{table_label(self.TABLE)} row {row + 1}{ident}, field '{fld}'"

    def _check(self):
        # r < 0 is allowed: network equivalents carry it (ANDES's EI_33, PSS/E's equivalencing)
        self._require((self.r != 0) | (self.x != 0), "x", "series impedance r+jx must not be 0")
        self._require(
            self.from_bus != self.to_bus, "to_bus", "branch must join two different buses"
        )
        # a ratio of turns is positive: a negative tap ran into a power flow that did not
        # converge (0 is PST's "no off-nominal tap", read as 1)
        self._require(self.tap >= 0, "tap", "off-nominal tap ratio must be > 0 (0 stands for 1)")
        ltc = self.tapmax != 0  # an on-load tap changer (PST lftap) steps within its limits
        self._require(~ltc | (self.tapmin > 0), "tapmin", "tap changer's lowest ratio must be > 0")
        self._require(
            ~ltc | (self.tapmax >= self.tapmin), "tapmax", "tap changer's tapmax must be >= tapmin"
        )
        self._require(
            ~ltc | (self.tapstep > 0), "tapstep", "tap changer's step must be > 0 (it divides)"
        )


#: the longest case name, characters: every message names the case (a 5 MB name made
#: each error line 5 MB)
LONGEST_NAME = 200

#: the least inertia constant of a machine that swings, s: no rotor is lighter (a small
#: motor's H is about 0.1 s); below it a run's first step already moves the rotor by
#: round-off (ANDES GENCLS M = 1e-9 imported, then refused as "not an equilibrium")
LIGHTEST_H_S = 1e-3


@_declared(MACHINE)
class MachineTable(Table):
    """Synchronous machine data: PST ``mac_con`` (PST manual section 3.22 Table 10), plus
        stabctl's column 24 ``speed_effects`` for subtransient machines: 1 (PST ``mac_sub``)
        the stator voltage is proportional to rotor speed and the torque is Pm/omega; 0 speed
        1 in both (ANDES's GENROU/GENSAL, which have no speed effects; docs/pst_models.md
        1.5-1.6), column 25 ``psse_sat``: PSS/E's saturation through S(1.0), S(1.2), 1
        GENROU's of the air-gap flux as ANDES solves it, 2 GENROE's, 3 GENSAL's (of E'q,
        d axis), 4 GENSAE's, 0 none (PST ``mac_sub``; docs 1.6a), and column 29
        ``psse_swing``: 1 PSS/E's swing equation (P_m - D (omega - 1)) / omega - T_e
        (docs 1.6b), 0 PST's.
        Columns (declared in :data:`stabctl.models.machines.MACHINE`; reactances on the
        machine base):

    {columns}

        Omitted columns: 0, except pfrac, qfrac and speed_effects 1 (PSTess ``mac_indx``).
        A classical machine (x_d = 0) with H = 0 is an infinite bus (PSS/E's GENCLS with H =
        0): its internal voltage E' and angle delta stay at their initial values, its speed at
        1 pu; where a case holds infinite buses they are its centre of inertia
        (:func:`stabctl.dynamics.coi.coi_inertia`).
        Validation: unique positive integer machine numbers, mva > 0, D0 >= 0, H > 0 (or 0 for a
        classical machine with x'd > 0), reactances and
        ra >= 0, T'do > 0 (x_d > 0) and T"do > 0 (x"d > 0), x_d >= x'd >= x"d (where given),
        a subtransient machine's x_l < x'd, x_l < x'q (x"d where T"qo = 0) and x'q <= x_q
        (T"qo > 0), 0 <= S(1.0) <= S(1.2) (x_d > 0), speed_effects and psse_swing 0 or 1,
        psse_sat 0 to 4.
    """

    def _check(self):
        self._require(self.number > 0, "number", "machine number must be a positive integer")
        self._unique("number", "machine number")
        self._require(self.mva > 0, "mva", "machine base must be > 0")
        self._require(
            (self.H >= LIGHTEST_H_S) | ((self.H == 0) & (self.xd == 0) & (self.xdp > 0)),
            "H",
            f"inertia constant must be >= {LIGHTEST_H_S:g} s (H = 0, an infinite bus, only "
            "for a classical machine, x_d = 0, with x'd > 0)",
        )
        # every machine is a source behind a reactance (x'd: classical and transient; x"d:
        # subtransient, and x"d <= x'd below): 0 makes the network singular
        self._require(
            self.xdp > 0,
            "xdp",
            "x'd must be > 0 pu: the machine's source reactance (0 would join its ideal "
            "source to the network: singular)",
        )
        # the open-circuit time constants a machine's model divides by (x_d = 0: classical,
        # none; x"d = 0: transient, T'do; else subtransient, T'do and T"do); T'qo, T"qo of 0
        # mean "no such circuit" (PST)
        self._require(
            (self.xd == 0) | (self.Tdop > 0),
            "Tdop",
            "T'do must be > 0 s for a transient or subtransient machine (x_d > 0)",
        )
        self._require(
            (self.xd == 0) | (self.xdpp == 0) | (self.Tdopp > 0),
            "Tdopp",
            'T"do must be > 0 s for a subtransient machine (x"d > 0)',
        )
        # the subtransient circuits are the faster (PSS/E Model Library, GENROU/GENSAL:
        # T'do > T"do, T'qo > T"qo; round 40: T'do 0.03 s with T"do 8 s was read), where
        # they act: x'd = x"d (x'q = x"d) leaves the subtransient circuit out, whatever its
        # time constant (PowerSimulationsDynamics.jl's PSS2A runs: T"do = T"qo = 999 s)
        self._require_row(
            ~((self.xd != 0) & (self.xdpp != 0) & (self.Tdopp > 0) & (self.xdp > self.xdpp))
            | (self.Tdop > self.Tdopp),
            "Tdopp",
            lambda r: (
                f"T\"do must be < T'do = {_fmt(self.Tdop[r])} s (a subtransient machine, "
                "x'd > x\"d)"
            ),
            ("Tdopp", "Tdop"),
        )
        self._require_row(
            ~((self.Tqop > 0) & (self.Tqopp > 0) & (self.xqp > self.xdpp))
            | (self.Tqop > self.Tqopp),
            "Tqopp",
            lambda r: f'T"qo must be < T\'qo = {_fmt(self.Tqop[r])} s (x\'q > x"q = x"d)',
            ("Tqopp", "Tqop"),
        )
        # the d-axis reactances as seen ever sooner after a disturbance can only fall
        # (PSS/E Model Library, GENROU/GENSAL: Xd >= X'd >= X"d)
        self._require(
            (self.xd == 0) | (self.xd >= self.xdp),
            "xd",
            "x_d must be >= x'd (a transient or subtransient machine)",
            ("xd", "xdp"),
        )
        self._require(
            (self.xd == 0) | (self.xdpp == 0) | (self.xdp >= self.xdpp),
            "xdp",
            "x'd must be >= x\"d (a subtransient machine)",
            ("xdp", "xdpp"),
        )
        # the subtransient model (PST mac_sub, PSS/E GENROU, GENSAL) splits the flux linkages
        # through x'd - x_l and x'q - x_l and divides by them (PST mac_pot columns 8, 13):
        # the stator leakage lies below both (the model's x'q is x"d where T"qo = 0).  PSS/E's
        # Xl < X"d is not required: ANDES's ieee39_full has Xl > X"d on two units and runs
        sub = (self.xd != 0) & (self.xdpp != 0)
        self._require_row(
            ~sub | (self.xl < self.xdp),
            "xl",
            lambda r: f"leakage x_l must be < x'd = {_fmt(self.xdp[r])} (a subtransient machine)",
            ("xl", "xdp"),
        )
        xqp = np.where(self.Tqopp == 0, self.xdpp, self.xqp)
        self._require_row(
            ~sub | (self.xl < xqp),
            "xl",
            lambda r: (
                f'leakage x_l must be < x\'q = {_fmt(xqp[r])} (x"d where T"qo = 0; a '
                "subtransient machine)"
            ),
            ("xl", "xqp"),
        )
        # the q-axis reactances as seen ever sooner after a disturbance can only fall, as
        # the d axis's (PSS/E Model Library GENROU: Xq >= X'q)
        self._require_row(
            ~sub | (self.Tqopp == 0) | (self.xq >= self.xqp),
            "xqp",
            lambda r: (
                f"x'q must be <= x_q = {_fmt(self.xq[r])} (a subtransient machine with T\"qo > 0)"
            ),
            ("xqp", "xq"),
        )
        # saturation grows with the flux: 0 <= S(1.0) <= S(1.2) (PSS/E Model Library GENROU,
        # GENSAL; PST mac_con columns 20-21) for every machine with a field winding
        field = self.xd != 0
        self._require(~field | (self.S10 >= 0), "S10", "saturation S(1.0) must be >= 0")
        self._require_row(
            ~field | (self.S12 >= self.S10),
            "S12",
            lambda r: (
                f"saturation S(1.2) must be >= S(1.0) = {_fmt(self.S10[r])} (it grows "
                "with the flux)"
            ),
            ("S12", "S10"),
        )


@_declared(EXCITER)
class ExciterTable(Table):
    """Exciter data: PST ``exc_con``, 20 columns, named as for ST3 (PST manual 3.13 Table 3),
        plus stabctl's columns 21, 22 for the PSS/E EXST1 (type 4, docs/pst_models.md 2.4) and
        23, 24 for the DC exciters' saturation and K_E as ANDES reads PSS/E data (2.3), 25 for
        the ST3's field current in I_N (2.2).
        Columns (declared in :data:`stabctl.models.exciters.EXCITER`):

    {columns}

        Columns 10-17 mean the DC quantities for types 1 and 2 (PST manual 3.11 Table 2; their
        names there are the declaration's ``alt`` names KE, TE, E1, SE1, E2, SE2, KF_dc,
        TF_dc); use ``col(k)`` for those.  IEEET2 (type 5) reads them as types 1, 2 do, and
        column 18 as its second rate feedback time constant TF2; a simple exciter (type 0)
        reads column 19 as ``bus_fed`` (PSS/E SCRX, output times V_t).  EXST1 (type 4) uses
        columns 3-11 and KC (17) as named, with Vrmax, Vrmin its output limits (times V_t) and
        KF, TF (21, 22).  Omitted trailing columns are 0 (a simple exciter needs 9). Validation:
        each column's declared range and codes (``type`` among the declared exciter types),
        each type's limits (its module's ``LIMITS``: Vrmax >= Vrmin and the other pairs of
        limits it reads, saturation points >= 0), a saturation that does not fall as the
        voltage rises (SE(E2) >= SE(E1) where E2 > E1), one exciter per machine (machine
        existence is checked by :class:`Case`), and what a run's models refuse
        (:func:`stabctl.models.exciters.check_table`: a time constant its type needs below
        1e-3 s, saturation points without a fit, ...).
    """

    def _check(self):
        self._unique("machine", "exciter on machine")
        # the DC and AC exciters' saturation SE(E) grows with the exciter voltage (IEEE Std
        # 421.5-2016's exciter saturation function: SE(E1) at E1 below SE(E2) at E2 > E1;
        # PSS/E Model Library, the same points)
        sat = np.isin(self.type, SATURATED_EXCITERS)
        E1, SE1, E2, SE2 = (self._named(n)[0] for n in ("E1", "SE1", "E2", "SE2"))
        lo, hi = np.where(E1 <= E2, SE1, SE2), np.where(E1 <= E2, SE2, SE1)
        bad = np.flatnonzero(sat & (E1 > 0) & (E2 > 0) & (E1 != E2) & (hi < lo))
        if bad.size:
            r = bad[0]
            self._fail(
                r,
                "SE2",
                f"saturation must grow with the voltage: SE(E1 = {_fmt(E1[r])}) = "
                f"{_fmt(SE1[r])}, SE(E2 = {_fmt(E2[r])}) = {_fmt(SE2[r])} (IEEE Std 421.5's "
                "exciter saturation)",
                EXCITER.col("SE2"),
                fields=("E1", "SE1", "E2", "SE2"),
                rule="saturation must grow with the voltage (IEEE Std 421.5's exciter saturation)",
            )
        _exciters.check_table(self)  # the models' own: what a run would refuse


@_declared(PSS)
class PssTable(Table):
    """Power system stabilizer data: PST ``pss_con``, 10 columns (PST manual 3.30 Table 13),
        extended by stabctl with type 3, the PSS/E stabilisers IEEEST and ST2CUT, and type 4,
        PSS/E's STAB2A (docs/pst_models.md 3.1-3.2).  Columns (declared in
        :data:`stabctl.models.pss.PSS`):

    {columns}

        Omitted columns are 0.  Validation: the declared types, one PSS per machine, the
        declared bounds (every time constant >= 0, IEEEST's filter denominator A1..A4 >= 0),
        ymax >= ymin and each type's limits (its module's ``LIMITS``), VCU > VCL where both
        cut-offs are given, Tw > 0, T2 > 0 for types 1 and 2, and what a run's models
        refuse (:func:`stabctl.models.pss.check_table`: input codes, M N > 8, ...).
    """

    def _check(self):
        self._unique("machine", "pss on machine")
        # the output is cut off above VCU and below VCL (0: no such cut-off): both given,
        # VCU <= VCL would cut it off at every voltage (PSS/E Model Library IEEEST, ST2CUT)
        both = (self.VCU != 0) & (self.VCL != 0)
        self._require_row(
            ~both | (self.VCU > self.VCL),
            "VCU",
            lambda r: (
                f"must be > VCL = {_fmt(self.VCL[r])} where both cut-offs are given (else "
                "the output is cut off at every voltage; PSS/E Model Library IEEEST)"
            ),
            ("VCU", "VCL"),
        )
        self._require(self.Tw > 0, "Tw", "washout time constant must be > 0 s")
        self._require(
            (self.type >= 3) | (self.T2 > 0),
            "T2",
            "first lag time constant must be > 0 s for PST's pss (types 1, 2)",
        )
        _pss.check_table(self)  # the models' own: what a run would refuse


@_declared(GOVERNOR)
class GovernorTable(Table):
    """Turbine-governor data: PST ``tg_con`` (PST manual 3.45, ``tg``), extended by stabctl
        with the PSS/E ``TGOV1``, ``IEEEG1``, ``HYGOV`` and ``IEESGO`` models (PSS/E Model
        Library; equations in docs/pst_models.md section 4).  Columns (declared in
        :data:`stabctl.models.governors.GOVERNOR`; powers on the machine base):

    {columns}

        PST files give 10 columns; the omitted ones are 0 (Tmin = 0 is PST tg's lower clip).
        Validation: the declared types, one governor per machine, the declared bounds (lag
        time constants >= 0, the lead constants T3, T4 may be negative: miniWECC's hydro units
        use T4 = -1; 1/R, the damping and the power fractions >= 0; Uo >= 0 >= Uc), Tmax >=
        Tmin, and each type's limits (its module's ``LIMITS``: the speed set point wf 1 where
        the speed error is wf - omega, ...), and what a run's models refuse
        (:func:`stabctl.models.governors.check_table`: a lag its type needs below 1e-3 s,
        IEEEG1 fractions summing to 0, ...).
    """

    def _check(self):
        self._unique("machine", "governor on machine")
        _governors.check_table(self)  # the models' own: what a run would refuse


@_declared(SHAFT)
class ShaftTable(Table):
    """Multi-mass torsional shafts: stabctl's ``shaft_con`` (ANDES 2.0 ``SHAFT5``; the model
        in :mod:`stabctl.models.shafts`, docs/pst_models.md section 13), one row per machine
        whose rotor is the generator mass of a five-mass chain HP-IP-LP-generator-exciter.
        Columns (declared in :data:`stabctl.models.shafts.SHAFT`; machine base):

    {columns}

        Omitted damping columns are 0.  Validation: inertias and stiffnesses > 0
        (:func:`stabctl.models.shafts.check_table`), one shaft per machine.
    """

    def _check(self):
        self._unique("machine", "shaft on machine")
        _shafts.check_table(self)  # the model's own: what a run would refuse


@_declared(MOTOR)
class MotorTable(Table):
    """Induction motors: stabctl's ``mot_con`` (ANDES 2.0 ``Motor5``; the model in
        :mod:`stabctl.models.motors`, docs/pst_models.md section 14), one row per motor, a
        dynamic load at its bus switched on by a ``MotorSwitch`` event.  Columns (declared
        in :data:`stabctl.models.motors.MOTOR`; motor base):

    {columns}

        Validation: numbers unique, in_service 0 (a motor starts out of service), and what
        the model refuses (:func:`stabctl.models.motors.check_table`: resistances, x_m, Hm
        and mva > 0).
    """

    def _check(self):
        self._unique("number", "motor number")
        _motors.check_table(self)  # the model's own: what a run would refuse


@_declared(SVC)
class SvcTable(Table):
    """Static var compensators: stabctl's ``svc_con`` (PSS/E CSVGN1; the model in
        :mod:`stabctl.models.svcs`, docs/pst_models.md section 18), one row per
        compensator, a susceptance at its bus whose initial value is its share of the
        bus's reactive generation in the power flow.  Columns (declared in
        :data:`stabctl.models.svcs.SVC`; the regulator in pu of the reactor rating):

    {columns}

        Validation: numbers unique, and what the model refuses
        (:func:`stabctl.models.svcs.check_table`: mva, K > 0, leads with their lags, ...).
    """

    def _check(self):
        self._unique("number", "compensator number")
        _svcs.check_table(self)  # the model's own: what a run would refuse


@dataclass(frozen=True, eq=False)
class LoadTable(Table):
    """Non-conforming load data: PST ``load_con``, 5 columns (PST manual 3.29 Table 12).

    ==  ==========  ===============================================================
    1   bus         bus number
    2   p_power     fraction of the bus P load that is constant power
    3   q_power     fraction of the bus Q load that is constant power
    4   p_current   fraction of the bus P load that is constant current
    5   q_current   fraction of the bus Q load that is constant current
    ==  ==========  ===============================================================

    The remainder (``p_impedance``, ``q_impedance``) is constant impedance; buses not
    listed are all constant impedance. Validation: one row per bus, fractions in [0, 1]
    with power + current <= 1.
    """

    bus: np.ndarray
    p_power: np.ndarray
    q_power: np.ndarray
    p_current: np.ndarray
    q_current: np.ndarray

    TABLE: ClassVar[str] = "load_con"
    MIN_COLUMNS: ClassVar[int] = 5
    KEY: ClassVar[str] = "bus"
    KEY_LABEL: ClassVar[str] = "bus"
    INTEGER: ClassVar[tuple[str, ...]] = ("bus",)

    @property
    def p_impedance(self) -> np.ndarray:
        """Constant-impedance fraction of P, 1 - p_power - p_current, shape (rows,)."""
        return 1.0 - self.p_power - self.p_current

    @property
    def q_impedance(self) -> np.ndarray:
        """Constant-impedance fraction of Q, 1 - q_power - q_current, shape (rows,)."""
        return 1.0 - self.q_power - self.q_current

    def _check(self):
        self._unique("bus", "load bus")
        for f in ("p_power", "q_power", "p_current", "q_current"):
            v = getattr(self, f)
            self._require((v >= 0) & (v <= 1), f, "fraction must be in [0, 1]")
        tol = 1e-12
        self._require(self.p_impedance >= -tol, "p_current", "p_power + p_current must be <= 1")
        self._require(self.q_impedance >= -tol, "q_current", "q_power + q_current must be <= 1")


#: the block groups a switched shunt may have (``swsh_con`` columns 8-19)
SWITCHED_GROUPS = 4

#: largest magnitude of any case value: beyond it a datum is no physical quantity (a
#: machine's H of 1e308 overflowed in the run), and the sentinels real files use (9999,
#: PST's -1e7 pu fault shunt, bus numbers below 2**31) stay far inside
LARGEST_VALUE = 1e15


@dataclass(frozen=True, eq=False)
class SwitchedShuntTable(Table):
    """Switched shunts: stabctl's ``swsh_con`` (ANDES 2.0 ``ShuntSw``; PSS/E's switched
    shunt), one row each, pu on the system base (susceptance capacitive > 0).

    ==  ==========  ===========================================================
    1   number      shunt number
    2   bus         bus number
    3   b0          initial susceptance (snapped to a level, `levels`)
    4   g0          initial conductance
    5   vref        voltage reference, pu
    6   dv          half band: the shunt steps while |V| is outside vref +- dv
    7   dt          s, the least time between two steps of it in a run
    8   n1          steps of the first block group
    9   b1          susceptance of one step of it
    10  g1          conductance of one step of it
    11  n2 ... 19   g4: the same for groups 2-4 (0 steps: no group)
    ==  ==========  ===========================================================

    Levels: 0, then b1 added n1 times, then b2 n2 times, ... (their conductances alike).
    The power flow steps every shunt outside its band by one level toward it and solves
    again until none is (`stabctl.network.switched_shunts`); a run steps it one level
    while its bus is outside the band, at most once every dt s
    (`stabctl.models.shunts`).
    Validation: numbers unique, dv > 0, steps >= 0, step susceptances >= 0 (capacitors:
    ANDES's starting rule assumes rising levels).
    """

    number: np.ndarray
    bus: np.ndarray
    b0: np.ndarray
    g0: np.ndarray
    vref: np.ndarray
    dv: np.ndarray
    dt: np.ndarray
    n1: np.ndarray
    b1: np.ndarray
    g1: np.ndarray
    n2: np.ndarray
    b2: np.ndarray
    g2: np.ndarray
    n3: np.ndarray
    b3: np.ndarray
    g3: np.ndarray
    n4: np.ndarray
    b4: np.ndarray
    g4: np.ndarray

    TABLE: ClassVar[str] = "swsh_con"
    MIN_COLUMNS: ClassVar[int] = 10
    KEY: ClassVar[str] = "number"
    KEY_LABEL: ClassVar[str] = "switched shunt"
    INTEGER: ClassVar[tuple[str, ...]] = ("number", "bus", "n1", "n2", "n3", "n4")

    def _check(self):
        self._unique("number", "switched shunt number")
        self._require(self.dv > 0, "dv", "half band must be > 0 pu")
        self._require(self.dt >= 0, "dt", "must be >= 0 s")
        for k in range(1, SWITCHED_GROUPS + 1):
            self._require(getattr(self, f"n{k}") >= 0, f"n{k}", "steps must be >= 0")
            self._require(getattr(self, f"b{k}") >= 0, f"b{k}", "capacitor steps (>= 0) only")


@dataclass(frozen=True, eq=False)
class InjectionTable(Table):
    """Fixed (constant-power) injections not in the bus table, e.g. storage or HVDC set points.

    ==  =====  =====================================================================
    1   bus    bus number
    2   p      injected P, pu on system base (generation > 0)
    3   q      injected Q, pu
    ==  =====  =====================================================================

    The power flow adds them to the bus generation; a run keeps them at their buses as
    constant power (below 0.5 pu as an admittance, as a constant-power load).  PST data
    files carry their fixed injections inside the bus loads (miniWECC's ``PDC`` is in
    ``bus`` column 6), so the PST importer leaves this table empty; ANDES's VSCShunt
    converters are read into it (docs/pst_models.md section 16).
    """

    bus: np.ndarray
    p: np.ndarray
    q: np.ndarray

    TABLE: ClassVar[str] = "injections"
    MIN_COLUMNS: ClassVar[int] = 2
    KEY: ClassVar[str] = "bus"
    KEY_LABEL: ClassVar[str] = "bus"
    INTEGER: ClassVar[tuple[str, ...]] = ("bus",)


@dataclass(frozen=True, eq=False)
class RegulationTable(Table):
    """Remote voltage regulation: generator buses that hold the voltage of another bus
    (PSS/E's IREG, shared by RMPCT; POM Generator Data), one row per generator bus.

    ==  =========  ====================================================================
    1   bus        generator bus number (a PV bus of the bus table)
    2   regulated  bus whose voltage it holds (a PQ bus)
    3   vset       voltage set point of the regulated bus, pu (PSS/E's VS)
    4   share      the bus's share of the reactive power that holds the regulated bus
                   (its machines' RMPCT over the sum of every regulating bus's), in (0, 1]
    ==  =========  ====================================================================

    The power flow (`stabctl.network.powerflow`) holds the regulated bus at ``vset`` and
    lets the generator bus's voltage float, the group's reactive power an unknown shared
    by ``share``; a bus at a Q limit leaves its group (the others go on; with none left the
    regulated bus floats).  In a run the exciters regulate their own terminals from their
    solved voltage, as PSS/E's exciter models do.  Validation: unique positive integer
    buses, regulated != bus, vset > 0, 0 < share <= 1; the case checks that every
    generator bus is PV, every regulated bus PQ, one ``vset`` per regulated bus and shares
    summing to 1.
    """

    bus: np.ndarray
    regulated: np.ndarray
    vset: np.ndarray
    share: np.ndarray

    TABLE: ClassVar[str] = "vreg_con"
    MIN_COLUMNS: ClassVar[int] = 4
    KEY: ClassVar[str] = "bus"
    KEY_LABEL: ClassVar[str] = "bus"
    INTEGER: ClassVar[tuple[str, ...]] = ("bus", "regulated")

    def _check(self):
        self._require(self.bus > 0, "bus", "bus number must be a positive integer")
        self._unique("bus", "regulating bus")
        self._require(self.regulated != self.bus, "regulated", "must differ from bus")
        self._require(self.vset > 0, "vset", "voltage set point must be > 0 pu")
        self._require((self.share > 0) & (self.share <= 1), "share", "must be in (0, 1]")


@_declared(CONVERTER)
class ConverterTable(Table):
    """Converter-interfaced devices (inverter-based resources): stabctl's ``ibr_con``,
        one row per device, as ANDES 2.0's distributed models PVD1 (WECC distributed PV)
        and ESD1 (PVD1 with a state of charge), and the renewable generator/converter
        REGCA1 (WECC REGC_A) have them, and PSS/E's DERA1 (WECC DER_A) (docs/ibr.md): a
        current source
        at its bus, whose initial P and Q are the fractions ``pfrac``, ``qfrac`` of the
        bus generation of the power flow.  Columns (declared in
        :data:`stabctl.models.converters.CONVERTER`; powers, currents and reactances on the
        device base ``mva``, as ANDES's inputs):

    {columns}

        Omitted columns take ANDES's defaults (as declared).  Validation: unique positive
        integer numbers, type 1, 2, 3 or 4, mva > 0, Twm > 0, tip, tiq, Tfm >= 0, ft0 < ft1 <=
        ft2 < ft3 and vt0 < vt1 <= vt2 < vt3 (the trip curves divide by the differences),
        dqdv < 0, and each component's rules
        (:data:`stabctl.models.converters.rules.RULES`, the same that ``import-andes`` checks
        in an ANDES file: PVD1, ESD1 ialim > 0; ESD1 En, Tf, EtaC, EtaD > 0 and 0 <= SOCmin <
        SOCmax <= 1, SOCinit between them (a REGCA1 battery's too), EtaC, EtaD <= 1; PVD1,
        ESD1 qmx >= qmn, v0 <= v1, pmx >= 0; REGCA1 Lvpnt0 < Lvpnt1, Volim > 0, (Lvplsw 1) Zerox <
        Brkpt (the piecewise gains divide by the differences), Iqrmin <= 0 <= Iqrmax; its
        REECA1's (REECB1's, REECD1's) Imax > 0, Vdip < Vup, limit pairs upper >= lower,
        dPmin <= 0 <= dPmax; its REPCA1's limit pairs, pc_Kc, pc_Vfrz >= 0; its wind
        turbine's damping >= 0, wt_Freq1, wt_w0 > 0, pitch and torque limit pairs, rising
        power points wq_p1..wq_p4, the initial pitch wa_theta0 within [wp_thmin, wp_thmax]),
        and what a run's models refuse (:func:`stabctl.models.converters.check_table`: a
        lag below 1e-3 s, a control on a device it cannot drive, ...).
    """

    def _check_declared(self):
        _converters.check_lags(self)  # first: a negative lag is told its bound, 1e-3 s
        super()._check_declared()

    def _check(self):
        self._require(self.number > 0, "number", "converter number must be a positive integer")
        self._unique("number", "converter number")
        self._require(self.mva > 0, "mva", "device base must be > 0")
        self._require(self.Twm > 0, "Twm", "washout time constant must be > 0 s")
        self._require(self.dqdv < 0, "dqdv", "Q-V droop must be < 0")
        for a, b, op in (
            ("vt0", "vt1", ">"),
            ("vt2", "vt3", ">"),
            ("ft0", "ft1", ">"),
            ("ft2", "ft3", ">"),
            ("vt1", "vt2", ">="),
            ("ft1", "ft2", ">="),
        ):
            lo, hi = getattr(self, a), getattr(self, b)
            self._require_row(
                hi > lo if op == ">" else hi >= lo,
                b,
                lambda r, a=a, op=op, lo=lo: f"must be {op} {a} = {_fmt(lo[r])}",
                fields=(b, a),
            )
        values = {c: getattr(self, c) for c in self.columns()}
        for model, has, rules in COMPONENTS:  # the limits import-andes checks, as it does
            rows = has(self)
            if not rows.any():
                continue
            for rule in rules:
                bad = np.flatnonzero(rows & ~np.asarray(rule.holds(values), dtype=bool))
                if bad.size:
                    r = bad[0]
                    shown = ", ".join(f"{n} = {_fmt(getattr(self, n)[r])}" for n in rule.names)
                    self._fail(
                        r,
                        rule.names[0],
                        f"{model}: {shown}: it must be {rule.what}",
                        fields=tuple(rule.names),
                        rule=f"it must be {rule.what}",
                    )
        _converters.check_table(self)  # the models' own: what a run would refuse


#: table field of Case -> table class, in file order
TABLES: Mapping[str, type[Table]] = MappingProxyType(
    {
        "buses": BusTable,
        "branches": BranchTable,
        "machines": MachineTable,
        "exciters": ExciterTable,
        "pss": PssTable,
        "governors": GovernorTable,
        "loads": LoadTable,
        "injections": InjectionTable,
        "converters": ConverterTable,
        "shafts": ShaftTable,
        "motors": MotorTable,
        "svcs": SvcTable,
        "switched_shunts": SwitchedShuntTable,
        "remote_regulation": RegulationTable,
    }
)


# --------------------------------------------------------------------------------------
# the case
# --------------------------------------------------------------------------------------


#: nominal frequencies a case may have (Hz): 16.7 Hz railway to 400 Hz aircraft and naval
#: grids, with room; 1e-300 Hz made every cycle 1e300 s long and ran
FREQ_HZ_RANGE = (1.0, 1000.0)


@dataclass(frozen=True, eq=False)
class Case:
    """One power system: bases, network, machines, controllers, loads.

    Attributes
    ----------
    name : str
        Short identifier (e.g. ``"kundur"``).
    base_mva : float
        System base, MVA; > 0.
    freq_hz : float
        Nominal frequency, Hz; > 0.
    buses : BusTable
        Bus data, one row per bus (PST ``bus``, manual section 1.3); per unit on the
        system base, kV for ``kv``.
    branches : BranchTable
        Line and transformer data, one row per branch (PST ``line``, section 1.3); per
        unit on the system base.
    machines, exciters, pss, governors : MachineTable, ExciterTable, PssTable, GovernorTable
        Dynamic data, one row per unit (PST ``mac_con``, ``exc_con``, ``pss_con``,
        ``tg_con``); per unit on the machine base, s for time constants (see their
        classes for columns and units).  Empty tables by default.
    loads : LoadTable
        Non-conforming load fractions, one row per bus (PST ``load_con``, manual 3.29
        Table 12); empty by default.
    injections : InjectionTable
        Fixed constant-power injections not in the bus table (storage or HVDC set
        points), one row each, pu on the system base; empty by default.
    converters : ConverterTable
        Converter-interfaced devices (ANDES PVD1, ESD1, REGCA1; PSS/E DERA1), one row
        each, pu on the device base (see the class for columns and units); empty by
        default.
    shafts : ShaftTable
        Multi-mass torsional shafts on machines (ANDES SHAFT5), one row each, machine
        base; empty by default.
    motors : MotorTable
        Induction motors (ANDES Motor5), one row each, motor base; empty by default.
    svcs : SvcTable
        Static var compensators (PSS/E CSVGN1), one row each; empty by default.
    switched_shunts : SwitchedShuntTable
        Switched shunts (ANDES ShuntSw), one row each, system base; empty by default.
    remote_regulation : RegulationTable
        Generator buses holding another bus's voltage (PSS/E's IREG, RMPCT), one row each;
        empty by default.
    sw_con : numpy.ndarray or None
        The data file's own switching (disturbance) matrix, shape (rows, 7), PST format
        (PST manual 2.5), read-only; None if the file has none.
    events : tuple of dict
        The case's own disturbance as imported (ANDES's Toggle, Fault and Alter records,
        `stabctl.io.andes_case`): each a dict with ``kind`` (the name of a
        `stabctl.case.events` class), that class's fields (s, pu on the system base,
        bus and machine numbers as in the data) and ``source`` (the record it came from);
        `stabctl.case.events.events_of_records` makes them events (a record it cannot
        make one of is refused when the case is made; a case file's record naming a bus,
        line, machine or motor the case lacks is refused when the file is read,
        `stabctl.case.events.check_case_events`).  Empty by default.
    extra : Mapping[str, numpy.ndarray]
        Other PST matrices of the data file kept as given (``lmod_con``, ``PDC``, ...),
        name -> read-only 2-D float array (units as in the file).
    machine_ids : Mapping[int, str]
        The machines' IDs in the data they came from (PSS/E's machine ID, unique at its
        bus), machine number -> ID, read-only; outputs name a machine by its number, bus
        and ID (`machine_name`).  Read by no run.  Empty by default (PST data has none).
    source : str
        Where the data came from (file, licence).
    description : str
        One line.

    Raises
    ------
    CaseError
        On construction: bus numbers referenced but not in ``buses`` (branches, machines,
        loads, injections, converters), controllers on machines not in ``machines``, a
        governor on an infinite bus (a classical machine
        of H = 0), no swing bus, a malformed ``sw_con``, a malformed event record, a table
        of the wrong class, or a non-positive base or frequency.  Its ``table``, ``row``
        and ``fields`` name the table row, as a table's own errors do.
    """

    name: str
    base_mva: float
    freq_hz: float
    buses: BusTable
    branches: BranchTable
    machines: MachineTable = field(default_factory=MachineTable.empty)
    exciters: ExciterTable = field(default_factory=ExciterTable.empty)
    pss: PssTable = field(default_factory=PssTable.empty)
    governors: GovernorTable = field(default_factory=GovernorTable.empty)
    loads: LoadTable = field(default_factory=LoadTable.empty)
    injections: InjectionTable = field(default_factory=InjectionTable.empty)
    converters: ConverterTable = field(default_factory=ConverterTable.empty)
    shafts: ShaftTable = field(default_factory=ShaftTable.empty)
    motors: MotorTable = field(default_factory=MotorTable.empty)
    svcs: SvcTable = field(default_factory=SvcTable.empty)
    switched_shunts: SwitchedShuntTable = field(default_factory=SwitchedShuntTable.empty)
    remote_regulation: RegulationTable = field(default_factory=RegulationTable.empty)
    sw_con: np.ndarray | None = None
    events: tuple = ()
    extra: Mapping[str, np.ndarray] = field(default_factory=dict)
    machine_ids: Mapping[int, str] = field(default_factory=dict)
    source: str = ""
    description: str = ""
    _bus_map: Mapping[int, int] = field(init=False, repr=False, compare=False)
    _mac_map: Mapping[int, int] = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        if not isinstance(self.name, str) or len(self.name) > LONGEST_NAME:
            shown = repr(self.name)[:40] + "..." if isinstance(self.name, str) else repr(self.name)
            raise CaseError(
                f"case name {shown}: a text of at most {LONGEST_NAME} characters is needed "
                "(every message names the case)"
                + (f", got {len(self.name)}" if isinstance(self.name, str) else "")
            )
        for fname, cls in TABLES.items():
            if not isinstance(getattr(self, fname), cls):
                raise CaseError(f"case '{self.name}': {fname} must be a {cls.__name__}")
        for scalar in ("base_mva", "freq_hz"):  # a text '100' failed in numpy, unnamed
            if not is_number(getattr(self, scalar)):
                raise CaseError(
                    f"case '{self.name}': {scalar} must be a number, got {getattr(self, scalar)!r}"
                )
        if not (np.isfinite(self.base_mva) and self.base_mva > 0):
            raise CaseError(f"case '{self.name}': base_mva must be > 0, got {self.base_mva}")
        lo, hi = FREQ_HZ_RANGE
        if not (np.isfinite(self.freq_hz) and lo <= self.freq_hz <= hi):
            raise CaseError(
                f"case '{self.name}': freq_hz must be a nominal frequency in [{lo:g}, {hi:g}] "
                f"Hz, got {self.freq_hz:g}"
            )
        object.__setattr__(self, "base_mva", float(self.base_mva))
        object.__setattr__(self, "freq_hz", float(self.freq_hz))
        object.__setattr__(
            self, "_bus_map", MappingProxyType({int(b): i for i, b in enumerate(self.buses.number)})
        )
        object.__setattr__(
            self,
            "_mac_map",
            MappingProxyType({int(m): i for i, m in enumerate(self.machines.number)}),
        )
        object.__setattr__(self, "sw_con", _check_sw_con(self.sw_con))
        object.__setattr__(self, "events", _check_events(self.events))
        object.__setattr__(self, "extra", _freeze_extra(self.extra))
        object.__setattr__(self, "machine_ids", self._checked_ids(self.machine_ids))
        self._check_references()
        self._check_shares()

    # -- validation -------------------------------------------------------------------

    def _checked_ids(self, ids: Mapping | None) -> Mapping[int, str]:
        """`machine_ids` read-only, keyed by the machines of the table (a machine left
        out of the case, e.g. at a dead bus, takes its ID with it); CaseError for an ID
        that is no text of 1 to 16 characters, or one that two machines of a bus share."""
        out: dict[int, str] = {}
        for number, ident in (ids or {}).items():
            if not isinstance(ident, str) or not 1 <= len(ident.strip()) <= 16:
                raise CaseError(
                    f"case '{self.name}': machine {number}: ID {ident!r} must be a text of 1 "
                    "to 16 characters"
                )
            if int(number) in self._mac_map:
                out[int(number)] = ident.strip()
        seen: dict[tuple[int, str], int] = {}
        for number, ident in out.items():
            bus = int(self.machines.bus[self._mac_map[number]])
            if (bus, ident) in seen:
                raise CaseError(
                    f"case '{self.name}': machines {seen[bus, ident]} and {number} at bus "
                    f"{bus} share the ID {ident!r}"
                )
            seen[bus, ident] = number
        return MappingProxyType(out)

    def _check_references(self):
        if not np.any(self.buses.kind == SWING):
            raise CaseError(f"{table_label('bus')}: no swing bus (no row with field 'kind' = 1)")
        known = self.buses.number
        self._check_buses(self.branches, "from_bus", known)
        self._check_buses(self.branches, "to_bus", known)
        self._check_buses(self.machines, "bus", known)
        self._check_buses(self.loads, "bus", known)
        self._check_buses(self.injections, "bus", known)
        self._check_buses(self.converters, "bus", known)
        self._check_buses(self.motors, "bus", known)
        self._check_buses(self.svcs, "bus", known)
        self._check_buses(self.switched_shunts, "bus", known)
        self._check_regulation()
        macs = self.machines.number
        for tab in (self.exciters, self.pss, self.governors, self.shafts):
            bad = np.flatnonzero(~np.isin(tab.machine, macs))
            if bad.size:
                tab._fail(
                    bad[0],
                    "machine",
                    f"machine {_fmt(tab.machine[bad[0]])} does not exist in "
                    f"{table_label('mac_con')}",
                )
        # an infinite bus (a classical machine of H = 0) keeps its speed: a governor on it
        # has no power to order (its start-up order is the bus's P, any sign)
        infinite = self.machines.number[(self.machines.H == 0) & (self.machines.xd == 0)]
        gov = self.governors
        bad = np.flatnonzero(np.isin(gov.machine, infinite))
        if bad.size:
            gov._fail(
                bad[0],
                "machine",
                f"machine {_fmt(gov.machine[bad[0]])} is an infinite bus (a classical machine "
                "of H = 0, its speed fixed): a governor has nothing to govern there",
            )

    def _check_shares(self):
        """The shares of the generation of each bus with converters (ibr_con ``pfrac``,
        ``qfrac``) summed with its machines' (mac_con's): at most 1, with a machine 1
        (`stabctl.models.converters.rules.share_sums`, import-andes's check of an ANDES
        file's ``gammap``, ``gammaq``); a converter's start above its bus's generation
        was refused only as the run started, for a limit it then met."""
        conv, mac = self.converters, self.machines
        if not len(conv):
            return
        at_conv, at_mac = self.bus_indices(conv.bus), self.bus_indices(mac.bus)
        for b in dict.fromkeys(at_conv.tolist()):
            rows, machines = np.flatnonzero(at_conv == b), at_mac == b
            sums = {
                f: float(getattr(conv, f)[rows].sum() + getattr(mac, f)[machines].sum())
                for f in ("pfrac", "qfrac")
            }
            fld, why = share_sums(sums, bool(machines.any()))
            if why:
                devs = f"converters {_listed(conv.number[rows])}"
                if machines.any():
                    devs += f" and machines {_listed(mac.number[machines])}"
                conv._fail(
                    rows[0], fld, f"bus {_fmt(self.buses.number[b])}'s {devs} {why}", rule=why
                )

    def _check_regulation(self):
        """Remote regulation: PV generator buses, PQ regulated buses, one set point and
        shares summing to 1 per regulated bus."""
        reg = self.remote_regulation
        if not len(reg):
            return
        self._check_buses(reg, "bus", self.buses.number)
        self._check_buses(reg, "regulated", self.buses.number)
        kind = self.buses.kind
        gen_kind = kind[self.bus_indices(reg.bus)]
        reg_kind = kind[self.bus_indices(reg.regulated)]
        reg._require(gen_kind == PV, "bus", "a regulating bus must be a PV bus (kind 2)")
        reg._require(reg_kind == PQ, "regulated", "a regulated bus must be a PQ bus (kind 3)")
        for r in np.unique(reg.regulated):
            rows = np.flatnonzero(reg.regulated == r)
            if np.ptp(reg.vset[rows]) > 0:
                reg._fail(
                    rows[-1],
                    "vset",
                    f"differs from bus {int(reg.bus[rows[0]])}'s set point for bus {int(r)}",
                )
            if abs(reg.share[rows].sum() - 1.0) > 1e-9:
                reg._fail(
                    rows[-1],
                    "share",
                    f"shares of bus {int(r)} sum to {reg.share[rows].sum():.12g}, not 1",
                )

    def check_stabilisers(self) -> None:
        """Refuse a PSS on a machine without exciter: its output is an input of its
        machine's exciter (PST ``pss``; a case being edited may hold one between two
        replacements, so this is checked where a case is read and where a run starts).

        Raises
        ------
        CaseError
            Naming the pss_con row and its machine (``table``, ``row``, ``fields`` set).
        """
        bad = np.flatnonzero(~np.isin(self.pss.machine, self.exciters.machine))
        if bad.size:
            self.pss._fail(
                bad[0],
                "machine",
                f"machine {_fmt(self.pss.machine[bad[0]])} has no exciter "
                f"({table_label('exc_con')}) for the PSS output",
            )

    def none_can_swing(self) -> str:
        """Why no machine of the case can swing, '' where one can: every machine is an
        infinite bus (a classical machine of H = 0, its angle and speed held), so every
        run stays stable and every CCT search ends above its limit.

        Returns
        -------
        str
            The infinite buses named (their machine numbers) and what follows, for a
            warning; '' for a case with a machine of H > 0 or without machines.
        """
        m = self.machines
        infinite = (m.H == 0) & (m.xd == 0)
        if len(m) == 0 or not infinite.all():
            return ""
        return (
            f"every machine is an infinite bus (H = 0: machine(s) {_listed(m.number)}): "
            "none can swing, so every run stays stable and every CCT lies above its search "
            "limit (give a machine H > 0 to study the case's stability)"
        )

    @staticmethod
    def _check_buses(tab: Table, fld: str, known: np.ndarray):
        vals = getattr(tab, fld)
        bad = np.flatnonzero(~np.isin(vals, known))
        if bad.size:
            missing = f"bus {_fmt(vals[bad[0]])} does not exist in {table_label('bus')}"
            tab._fail(bad[0], fld, missing)

    # -- lookup -----------------------------------------------------------------------

    def __repr__(self) -> str:
        """One line: name, sizes, base and frequency (the tables would print thousands of
        lines for a planning case; `stabctl cases CASE` and its tables show them)."""
        return (
            f"Case({self.name!r}: {self.n_bus} buses, {len(self.branches)} branches, "
            f"{len(self.machines)} machines, {len(self.exciters)} exciters, "
            f"{len(self.governors)} governors, {len(self.converters)} converters, "
            f"{self.base_mva:g} MVA, {self.freq_hz:g} Hz)"
        )

    @property
    def n_bus(self) -> int:
        """Number of buses."""
        return len(self.buses)

    @property
    def bus_map(self) -> Mapping[int, int]:
        """Read-only mapping bus number -> 0-based row of ``buses``."""
        return self._bus_map

    def bus_index(self, number) -> int:
        """0-based row of bus ``number`` in ``buses``.

        Parameters
        ----------
        number : int
            Bus number (PST bus matrix column 1), a scalar; anything ``int()`` accepts
            without dropping a fraction (3.5 is no bus).

        Returns
        -------
        int
            0-based row of the bus in ``buses`` (and in every per-bus array).

        Raises
        ------
        UnknownBusError
            The bus is not in the case (a :class:`CaseError` and ``KeyError``); the
            message names the bus.
        """
        try:
            return self._bus_map[_whole(number)]
        except (KeyError, ValueError, TypeError):
            raise UnknownBusError(self._unknown_bus(number)) from None

    def _unknown_bus(self, number) -> str:
        """The message of an unknown bus: the case's bus numbers (the first 20) and, where
        its description says how they map to a book's, that sentence."""
        nums = [int(b) for b in self.buses.number]
        shown = ", ".join(map(str, nums[:20])) + (
            f", ... ({len(nums)} in all)" if len(nums) > 20 else ""
        )
        mapping = [p.strip() for p in self.description.split(";") if "bus numbers" in p]
        return (
            f"bus {number} is not in case '{self.name}' (its buses: {shown}"
            + (f"; {mapping[0]}" if mapping else "")
            + ")"
        )

    def bus_indices(self, numbers) -> np.ndarray:
        """0-based rows of many bus numbers.

        Parameters
        ----------
        numbers : array_like of int
            Bus numbers (PST bus matrix column 1), any shape.

        Returns
        -------
        numpy.ndarray
            int array of the shape of ``numbers``: the 0-based row in ``buses`` of each.

        Raises
        ------
        UnknownBusError
            A number is not a bus of the case; the message names the first unknown bus.
        """
        numbers = np.asarray(numbers)
        flat = numbers.ravel()
        order = np.argsort(self.buses.number, kind="stable")
        sorted_nums = self.buses.number[order]
        pos = np.searchsorted(sorted_nums, flat)
        pos = np.clip(pos, 0, max(len(sorted_nums) - 1, 0))
        ok = sorted_nums[pos] == flat if len(sorted_nums) else np.zeros(flat.shape, bool)
        if not np.all(ok):
            self.bus_index(flat[np.flatnonzero(~ok)[0]])
        return order[pos].reshape(numbers.shape)

    def machine_index(self, number) -> int:
        """0-based row of machine ``number`` in ``machines``.

        Parameters
        ----------
        number : int
            Machine number (PST ``mac_con`` column 1), a scalar; anything ``int()`` accepts
            without dropping a fraction.

        Returns
        -------
        int
            0-based row of the machine in ``machines``.

        Raises
        ------
        CaseError
            The machine is not in the case; the message names it.
        """
        try:
            return self._mac_map[_whole(number)]
        except (KeyError, ValueError, TypeError):
            raise CaseError(f"machine {number} is not in case '{self.name}'") from None

    def infinite_buses(self) -> set[int]:
        """The machines that are infinite buses, by number: classical machines of H = 0
        (PSS/E's GENCLS holding the rest of the system; the table admits H = 0 only with
        x_d = 0), which keep their speed and are no ESD site.

        Returns
        -------
        set of int
            Machine numbers.
        """
        m = self.machines
        return {int(k) for k, h in zip(m.number, m.H) if h == 0}

    def require_machines(self, need: str) -> None:
        """Refuse a case without machines (a static case: `stabctl import-andes --static`,
        a RAW without DYR) for work that needs them.

        Parameters
        ----------
        need : str
            What needs them, completing the message ("a dynamic run or linearisation
            needs at least one").

        Raises
        ------
        InputError
            No machine: the message names the case and `need`.
        """
        if len(self.machines) == 0:
            raise InputError(f"case '{self.name}' has no machines (mac_con is empty): {need}")

    def machine_name(self, number) -> str:
        """How outputs name machine ``number``: its number and its bus, ``"G14 (bus 3)"``,
        and its ID where the data gave one (`machine_ids`: ``"G2 (bus 102, id '1')"``, as
        PSS/E names a machine by bus and ID).

        Every listing of machines (the CLI's text, the plots' legends) names them through
        this one function, so that a reader finds them in the case's machine table (the
        number) and on its network (the bus).

        Parameters
        ----------
        number : int
            Machine number (PST ``mac_con`` column 1), a scalar; anything ``int()`` accepts.

        Returns
        -------
        str
            ``"G<number> (bus <bus number>)"`` or ``"G<number> (bus <bus number>, id
            '<ID>')"``.

        Raises
        ------
        CaseError
            The machine is not in the case; the message names it.
        """
        k = self.machine_index(number)
        n = int(self.machines.number[k])
        ident = self.machine_ids.get(n)
        named = "" if ident is None else f", id {ident!r}"
        return f"G{n} (bus {int(self.machines.bus[k])}{named})"

    def motor_index(self, number) -> int:
        """0-based row of motor ``number`` in ``motors``.

        Parameters
        ----------
        number : int
            Motor number (``mot_con`` column 1), a scalar.

        Returns
        -------
        int
            0-based row of the motor in ``motors``.

        Raises
        ------
        CaseError
            The case has no such motor; the message names it.
        """
        hit = np.flatnonzero(self.motors.number == number)
        if hit.size == 0:
            raise CaseError(f"motor {number} does not exist in mot_con")
        return int(hit[0])

    def converter_index(self, number) -> int:
        """0-based row of converter ``number`` in ``converters``.

        Parameters
        ----------
        number : int
            Converter number (``ibr_con`` column 1), a scalar.

        Returns
        -------
        int
            0-based row of the converter in ``converters``.

        Raises
        ------
        CaseError
            The case has no such converter; the message names it.
        """
        hit = np.flatnonzero(np.asarray(self.converters.number) == number)
        if hit.size == 0:
            raise CaseError(f"converter {number} is not in case '{self.name}'")
        return int(hit[0])

    def branch_rows(self, bus_a, bus_b) -> np.ndarray:
        """0-based rows of every branch joining buses ``bus_a`` and ``bus_b``.

        Parameters
        ----------
        bus_a, bus_b : int
            Bus numbers (as in the data), in either order.

        Returns
        -------
        numpy.ndarray
            int array of the rows in ``branches`` joining them (either direction), in
            table order: the row order numbers the parallel circuits 1, 2, ...; empty if
            none does.

        Raises
        ------
        UnknownBusError
            A bus not in the case.
        """
        # as bus_index reads them (round 45: circuit_row('3', 101) found no branch)
        bus_a, bus_b = (int(self.buses.number[self.bus_index(b)]) for b in (bus_a, bus_b))
        br = self.branches
        hit = ((br.from_bus == bus_a) & (br.to_bus == bus_b)) | (
            (br.from_bus == bus_b) & (br.to_bus == bus_a)
        )
        return np.flatnonzero(hit)

    def circuit_row(self, bus_a, bus_b, circuit: int = 1) -> int:
        """0-based branch row of circuit ``circuit`` of the line ``bus_a``-``bus_b``.

        PST's ``sw_con`` trips the first line found between the fault bus and the far bus,
        i.e. circuit 1.

        Parameters
        ----------
        bus_a, bus_b : int
            Bus numbers (as in the data) of the line's ends, in either order.
        circuit : int, optional
            Which of the parallel circuits (1 = the first branch row joining them, as
            `branch_rows` orders them); default 1.

        Returns
        -------
        int
            0-based row in ``branches``.

        Raises
        ------
        UnknownBusError
            A bus not in the case.
        CaseError
            No branch joins the two buses, or fewer than ``circuit`` do.
        """
        rows = self.branch_rows(bus_a, bus_b)
        if rows.size == 0:
            raise CaseError(f"line: no branch between bus {bus_a} and bus {bus_b}")
        try:
            k = _whole(circuit)
        except (TypeError, ValueError):
            raise CaseError(
                f"line: circuit {circuit!r} between bus {bus_a} and bus {bus_b}: not a "
                "circuit number (1, 2, ...)"
            ) from None
        if not 1 <= k <= rows.size:
            raise CaseError(
                f"line: circuit {circuit} between bus {bus_a} and bus {bus_b} does not exist "
                f"({rows.size} circuit(s))"
            )
        return int(rows[k - 1])

    @property
    def swing_index(self) -> np.ndarray:
        """0-based rows of the swing bus(es), int array."""
        return np.flatnonzero(self.buses.kind == SWING)

    def replace(self, **changes) -> Case:
        """A copy with some fields replaced (validated again).

        Parameters
        ----------
        **changes : object
            Field name -> new value (any of the fields under Attributes of :class:`Case`,
            same types and units).

        Returns
        -------
        Case
            A new case; ``self`` is unchanged.

        Raises
        ------
        CaseError
            The new data fail the checks of construction (see :class:`Case`).
        WrongTypeError
            A name is not a field of :class:`Case` (a TypeError as Python has it).
        """
        unknown = sorted(set(changes) - {f.name for f in dataclasses.fields(self)})
        if unknown:  # (round 45: dataclasses' "unexpected keyword argument")
            raise WrongTypeError(
                f"Case.replace: {', '.join(unknown)} not a field of a Case (fields: "
                f"{', '.join(f.name for f in dataclasses.fields(self))})"
            )
        return dataclasses.replace(self, **changes)

    def digest(self) -> str:
        """A digest of the data a run of the case reads, to tell whether records made
        from a case were made from this content (`stabctl.parallel`).

        Returns
        -------
        str
            16 hex digits of the SHA-256 of the bases, every table (its columns, shape
            and float64 values), ``sw_con`` and the event records; the name,
            description, source, ``extra`` and ``machine_ids`` (read by no run) are not
            part of it.
        """
        h = hashlib.sha256(json.dumps([self.base_mva, self.freq_hz]).encode())
        for name in TABLES:
            table = getattr(self, name)
            mat = np.ascontiguousarray(table.matrix(), dtype="<f8")
            h.update(json.dumps([name, table.columns(), mat.shape]).encode())
            h.update(mat.tobytes())
        sw = np.zeros((0, 7)) if self.sw_con is None else self.sw_con
        h.update(np.ascontiguousarray(sw, dtype="<f8").tobytes())
        h.update(json.dumps(self.events, sort_keys=True).encode())
        return h.hexdigest()[:16]

    def equals(self, other: Case) -> bool:
        """Compare two cases value by value.

        Parameters
        ----------
        other : Case
            The case to compare with; anything else compares unequal.

        Returns
        -------
        bool
            True if the name, every table, base, frequency, ``sw_con``, the events,
            every extra matrix and the machine IDs are identical (exact float equality;
            ``source`` and ``description`` are not compared).
        """
        if not isinstance(other, Case):
            return False
        same_scalars = (self.name, self.base_mva, self.freq_hz) == (
            other.name,
            other.base_mva,
            other.freq_hz,
        )
        same_tables = all(getattr(self, t).equals(getattr(other, t)) for t in TABLES)
        same_sw = (self.sw_con is None and other.sw_con is None) or (
            self.sw_con is not None
            and other.sw_con is not None
            and np.array_equal(self.sw_con, other.sw_con)
        )
        same_extra = self.extra.keys() == other.extra.keys() and all(
            np.array_equal(self.extra[k], other.extra[k]) for k in self.extra
        )
        same_extra = same_extra and dict(self.machine_ids) == dict(other.machine_ids)
        same_events = self.events == other.events
        return same_scalars and same_tables and same_sw and same_extra and same_events


def require_case(case, where: str, also: str = "") -> Case:
    """`case` itself if it is a `Case`, else a TypeError naming `where` and what came (a
    case's name, ``'kundur'``, failed deep inside with "'str' object has no attribute
    'branches'").

    Parameters
    ----------
    case : object
        What the caller passed as the case.
    where : str
        The function and argument, ``"Simulator(case)"``, named in the error.
    also : str, optional
        What else the argument may be, said after "a stabctl Case" (``" or Simulator"``;
        the caller took that already).

    Returns
    -------
    Case

    Raises
    ------
    WrongTypeError
        `case` is not a `Case` (a TypeError); a str is pointed to `stabctl.io.load_case`.
    """
    if isinstance(case, Case):
        return case
    hint = f" (load it first: stabctl.load_case({case!r}))" if isinstance(case, str) else ""
    raise WrongTypeError(
        f"{where}: a stabctl Case{also} is needed, got {type(case).__name__}{hint}"
    )


def _check_events(events) -> tuple:
    """The event records as a tuple of dicts; CaseError for a malformed one
    (`stabctl.case.events.events_of_records`)."""
    records = tuple(events or ())
    events_of_records(records)
    return tuple(dict(rec) for rec in records)


def _check_sw_con(sw) -> np.ndarray | None:
    if sw is None:
        return None
    mat = _as_matrix(sw, "sw_con")
    if mat.size == 0:
        return None
    if mat.shape[1] != 7:
        raise CaseError(f"sw_con: wrong column count {mat.shape[1]}, expected 7")
    bad = np.argwhere(~np.isfinite(mat))
    if bad.size:
        raise CaseError(f"sw_con row {bad[0][0] + 1}, column {bad[0][1] + 1}: non-finite value")
    back = np.flatnonzero(np.diff(mat[:, 0]) < 0)
    if back.size:  # PST switches at each row's time in turn (PST manual, sw_con)
        r = int(back[0]) + 2
        raise CaseError(
            f"sw_con row {r}, column 1 (time): {mat[r - 1, 0]:g} s comes before row {r - 1}'s "
            f"{mat[r - 2, 0]:g} s: the switching times must not go backwards"
        )
    mat.setflags(write=False)
    return mat


def _freeze_extra(extra: Mapping | None) -> Mapping[str, np.ndarray]:
    out = {}
    for k, v in (extra or {}).items():
        arr = np.array(v, dtype=float)
        if arr.ndim < 2:
            arr = arr.reshape(-1, 1) if arr.size else arr.reshape(0, 0)
        arr.setflags(write=False)
        out[str(k)] = arr
    return MappingProxyType(out)


# --------------------------------------------------------------------------------------
# built-in cases
# --------------------------------------------------------------------------------------

#: directory of the built-in cases (stabctl JSON, converted from PSTess; MIT LICENSE, NOTICE)
CASE_DIR = Path(__file__).with_name("data")
