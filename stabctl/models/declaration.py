"""Parameter declarations of the dynamic models, and what the models derive from them:
:class:`Param`, :class:`DyrModel`, :class:`Family`; the parameter dataclasses
(:func:`params_class`), the packed kernel matrices (:func:`layout`, :func:`pack`) and the
start-up limit check (:func:`beyond`).

Each model module declares its family beside its kernels (``MACHINE`` in
:mod:`stabctl.models.machines`, ``EXCITER`` in :mod:`stabctl.models.exciters`, ``PSS``,
``GOVERNOR``, ``CONVERTER``): every parameter of a PST dynamic-data matrix (``mac_con``,
``exc_con``, ``pss_con``, ``tg_con``; stabctl's ``ibr_con``) once, with its table field
name, unit, PST column, default for an omitted trailing column, bounds and meaning.
Everything else is derived from it:

* the case tables of :mod:`stabctl.case.system` (fields in column order, ``DEFAULTS``,
  ``INTEGER``, the bound and choice checks, the column table of the docstring), through
  the registry :data:`stabctl.case.params.FAMILIES`;
* the models' parameter classes and packed kernel columns (field names are the table
  names; each family lists the fields its kernels take, ``TABLE_FIELDS``, and its packed
  layout, ``PACKED``: column name and attribute per column; :func:`layout` gives the
  kernels' named column indices ``E.KA``, ``S.TW``, ...);
* the PSS/E DYR import of :mod:`stabctl.io.dyr` (each DYR model's parameter order and the
  table field each of its parameters is copied to) and the ANDES models read as a record
  (:attr:`DyrModel.andes`, :mod:`stabctl.io.andes_case`).

Adding a model parameter is one :class:`Param` line; adding a DYR model one
:class:`DyrModel` (plus a mapper in :mod:`stabctl.io.dyr` for values it computes);
adding a model type is its declaration and kernel in its family's module (an exciter type:
its own module of the package :mod:`stabctl.models.exciters`, with its named states,
:func:`states`).

Sources: PST manual (Power System Toolbox 3.0, Rogers & Chow) section 3.22 Table 10
(``mac_con``), 3.11 Table 2 and 3.13 Table 3 (``exc_con``), 3.30 Table 13 (``pss_con``),
3.45 (``tg_con``); PSS/E Model Library (DYR parameter order, as ANDES
``andes/io/psse-dyr.yaml``); docs/pst_models.md for stabctl's extension columns.
"""

from __future__ import annotations

import dataclasses
import importlib
import inspect
from collections import namedtuple
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

import numpy as np

__all__ = [
    "Param",
    "DyrModel",
    "Limits",
    "LEAD_LAG_MIN",
    "Family",
    "choices_message",
    "array_dataclass",
    "START_LIMIT_TOL",
    "beyond",
    "Declared",
    "params_class",
    "layout",
    "states",
    "slots",
    "own_columns",
    "own_params",
    "pack_own",
    "type_modules",
    "check_packed",
    "pack",
]


@dataclass(frozen=True)
class Param:  # fields of a dataclass: numpydoc ignore=PR02
    """One column of a PST dynamic-data matrix, declared once.

    Parameters
    ----------
    name : str
        Table field name (``ExciterTable.KA``); also the name in the models' parameter
        classes and in messages (``field 'KA'``).
    unit : str
        Unit: ``"pu"`` (machine base unless said otherwise), ``"s"``, ``"deg"``,
        ``"MVA"``, ``""`` (dimensionless) or ``"code"`` (an integer selector).
    col : int
        1-based PST column (the PST manual's numbering).
    default : float, optional
        Value of the column when a PST matrix omits it (trailing columns), default 0.
    lo, hi : float or None, optional
        Inclusive bounds checked when a table is built; a value outside raises
        :class:`~stabctl.errors.CaseError` "``{table} row {r} ({key} {k}), field
        '{name}': must be >= {lo}, got {v}``".  None: unbounded.
    doc : str, optional
        Meaning, one line (goes into the table's docstring).
    integer : bool, optional
        The column must hold integers (numbers, codes).
    choices : tuple of float, optional
        Allowed values (checked at construction), e.g. the model types.
    label : str, optional
        What the choices message calls the field ("exciter type must be 0, 1 or 2");
        default the field name.
    alt : str, optional
        The column's name where another model reads it differently (``exc_con`` columns
        10-17 for the DC exciters, PST manual 3.11 Table 2: ``KE``, ``TE``, ...).
    """

    name: str
    unit: str
    col: int
    default: float = 0.0
    lo: float | None = None
    hi: float | None = None
    doc: str = ""
    integer: bool = False
    choices: tuple[float, ...] = ()
    label: str = ""
    alt: str = ""


@dataclass(frozen=True)
class DyrModel:  # fields of a dataclass: numpydoc ignore=PR02
    """How one PSS/E dynamic model's DYR record fills a table row.

    Parameters
    ----------
    name : str
        PSS/E model name (upper case), e.g. ``"SEXS"``.
    fields : tuple of str
        The numbers after the machine id, ICONs then CONs, in PSS/E Model Library order
        (their count is the record's required length).
    copy : Mapping[str, str]
        Table field <- DYR field for the parameters copied as given.  Table fields may be
        a column's ``alt`` name.  Values the importer computes (unit changes, products,
        saturation fits) are set by its mapper in :mod:`stabctl.io.dyr`.
    kind : int or None
        Value of the table's ``type`` column (None: the mapper chooses it, or the table
        has none).
    andes : tuple of str
        The ANDES 2.0 models whose parameters are this record's (ANDES's
        ``andes/io/psse-dyr.yaml`` maps each onto one ANDES parameter), read back as this
        record by :mod:`stabctl.io.andes_case`; empty when ANDES has no such model.

    Notes
    -----
    A record whose row is its copies and the machine number (no unit change, product or
    fit) needs no mapper of its own: :mod:`stabctl.io.dyr` maps it with its family's
    default, so adding such a model is this declaration and its model's kernel.
    """

    name: str
    fields: tuple[str, ...]
    copy: Mapping[str, str] = field(default_factory=dict)
    kind: int | None = None
    andes: tuple[str, ...] = ()

    def __post_init__(self):
        unknown = set(self.copy.values()) - set(self.fields)
        if unknown:
            raise ValueError(f"DYR model {self.name}: copies unknown fields {sorted(unknown)}")
        object.__setattr__(self, "copy", MappingProxyType(dict(self.copy)))

    def values(self, params) -> dict[str, float]:
        """DYR field name -> value of one record's numbers ``params`` (in ``fields`` order)."""
        return dict(zip(self.fields, params))


#: the lag time constant below which a lead-lag block is bypassed (`Limits.leads`; the
#: kernels' ``stabctl.models.blocks.LBND``, s)
LEAD_LAG_MIN = 1e-3


@dataclass(frozen=True)
class Limits:  # fields of a dataclass: numpydoc ignore=PR02
    """The values a model type's equations cannot take, refused by name when a case table
    is made (`stabctl.case.system`), beyond the bounds its columns declare for every type
    (`Param.lo`, `Param.hi`): the columns a table shares are read under other names and
    meanings by other types (exc_con column 11 is one type's VImin, another's T_E).

    Parameters
    ----------
    source : str
        Where the limits come from (the model's standard or library, or the physics), said
        in the messages.
    nonnegative : tuple of str, optional
        Fields (or ``alt`` names) that must be >= 0: gains a negative of which the model
        cannot have, time constants (0 bypasses the block).
    positive : tuple of str, optional
        Fields that must be > 0 (the model divides by them, no bypass).
    ordered : tuple of (str, str), optional
        (upper, lower) pairs of limits: upper >= lower.
    one : tuple of str, optional
        Fields that must be 1 (a set point the model's start takes as 1).
    leads : tuple of (str, str), optional
        (lead, lag) time constants of a lead-lag (1 + s lead)/(1 + s lag): the lead must
        be 0 where the lag is below `LEAD_LAG_MIN` (the block is then bypassed: a lead
        without its lag is a derivative no lead-lag has).
    """

    source: str
    nonnegative: tuple[str, ...] = ()
    positive: tuple[str, ...] = ()
    ordered: tuple[tuple[str, str], ...] = ()
    one: tuple[str, ...] = ()
    leads: tuple[tuple[str, str], ...] = ()

    def names(self) -> tuple[str, ...]:
        """Every field the limits name, in their order."""
        pairs = (n for pair in (*self.ordered, *self.leads) for n in pair)
        return (*self.nonnegative, *self.positive, *pairs, *self.one)


@dataclass(frozen=True)
class Family:  # fields of a dataclass: numpydoc ignore=PR02
    """The declaration of one PST dynamic-data matrix and the DYR models that fill it.

    Parameters
    ----------
    table : str
        PST matrix name (``"exc_con"``), used in messages.
    params : tuple of Param
        Every column, in PST column order (``params[k].col == k + 1``).
    min_columns : int
        Fewest columns a PST matrix may give (the rest take ``Param.default``).
    key, key_label : str
        Field identifying a row in messages, and what messages call it (``"machine"``).
    dyr : tuple of DyrModel, optional
        The PSS/E models imported into this table.
    limits : Mapping[int, tuple of Limits], optional
        Type code (the ``type`` column) -> the `Limits` of its rows, checked when a table
        is made; empty by default.
    type_names : Mapping[int, str], optional
        Type code -> how messages name a row's type ("exciter type 3, ST3 (exc_st3)").

    Raises
    ------
    ValueError
        If columns are not 1, 2, ... in order, a name or alternative name repeats, or a
        `Limits` names a field the table has not.
    """

    table: str
    params: tuple[Param, ...]
    min_columns: int
    key: str
    key_label: str
    dyr: tuple[DyrModel, ...] = ()
    limits: Mapping[int, tuple[Limits, ...]] = field(default_factory=dict)
    type_names: Mapping[int, str] = field(default_factory=dict)

    def __post_init__(self):
        for k, p in enumerate(self.params):
            if p.col != k + 1:
                raise ValueError(
                    f"{self.table}: parameter {p.name} declared as column {p.col}, "
                    f"is column {k + 1}"
                )
        names = [p.name for p in self.params] + [p.alt for p in self.params if p.alt]
        if len(set(names)) != len(names):
            raise ValueError(f"{self.table}: a parameter name or alternative name repeats")
        for kind, limits in self.limits.items():
            unknown = {n for lim in limits for n in lim.names()} - set(names)
            if unknown:
                raise ValueError(f"{self.table} type {kind}: limits of unknown {sorted(unknown)}")

    @property
    def names(self) -> tuple[str, ...]:
        """Field names in PST column order."""
        return tuple(p.name for p in self.params)

    @property
    def defaults(self) -> Mapping[str, float]:
        """Field -> value of an omitted trailing column, for the non-zero defaults."""
        return MappingProxyType({p.name: p.default for p in self.params if p.default != 0})

    @property
    def integer(self) -> tuple[str, ...]:
        """Fields that must hold integers."""
        return tuple(p.name for p in self.params if p.integer)

    def param(self, name: str) -> Param:
        """The declaration of field ``name`` or of the column whose ``alt`` name it is.

        Raises
        ------
        KeyError
            If no column has that name.
        """
        for p in self.params:
            if name in (p.name, p.alt):
                return p
        raise KeyError(f"{self.table} has no parameter {name!r}")

    def col(self, name: str) -> int:
        """1-based PST column of field (or alternative name) ``name``."""
        return self.param(name).col

    def dyr_model(self, name: str) -> DyrModel:
        """The DYR model ``name`` of this family (KeyError if not declared)."""
        for m in self.dyr:
            if m.name == name:
                return m
        raise KeyError(name)

    def dyr_row(self, model: DyrModel, params, **computed) -> list[float]:
        """One table row (all columns, zeros where nothing is given) from a DYR record.

        Parameters
        ----------
        model : DyrModel
            The record's model.
        params : sequence of float
            The record's numbers after the id, in ``model.fields`` order.
        **computed : float
            Table fields (or alternative names) set by the importer, applied after the
            copied fields (and after ``model.kind``).

        Returns
        -------
        list of float
            The row, one value per declared column, PST column order.
        """
        row = [0.0] * len(self.params)
        vals = model.values(params)
        if model.kind is not None:
            row[0] = float(model.kind)
        for name, src in model.copy.items():
            row[self.col(name) - 1] = float(vals[src])
        for name, v in computed.items():
            row[self.col(name) - 1] = float(v)
        return row

    def rst_table(self) -> str:
        """The column table of the table class's docstring (reStructuredText)."""
        width = max(len(p.name) for p in self.params)
        units = [p.unit if p.unit != "code" else "" for p in self.params]
        uw = max(4, *(len(u) for u in units))
        rule = f"    ==  {'=' * width}  {'=' * uw}  {'=' * 60}"
        lines = [rule, f"    {'':<2}  {'name':<{width}}  {'unit':<{uw}}  meaning", rule]
        for p, unit in zip(self.params, units):
            lines.append(f"    {p.col:<2}  {p.name:<{width}}  {unit:<{uw}}  {p.doc}")
        lines.append(rule)
        return "\n".join(lines)


def model_types(modules, table: str) -> tuple[dict, dict]:
    """A model family's registry from its type modules (each with ``KINDS``, type code ->
    name, and ``STATE_NAMES``, type code -> its state names in slot order).

    Parameters
    ----------
    modules : sequence of module
        The family's type modules.
    table : str
        The family's table (``exc_con``), for the error.

    Returns
    -------
    types : dict
        Type code -> its module, in code order.
    state_names : dict
        Type code -> its state names.

    Raises
    ------
    ValueError
        A type code claimed by two modules.
    """
    types = dict(sorted((kind, m) for m in modules for kind in m.KINDS))
    if len(types) != sum(len(m.KINDS) for m in modules):
        raise ValueError(f"a {table} type is claimed by two modules")
    return types, {kind: m.STATE_NAMES[kind] for kind, m in types.items()}


def type_modules(package: str, *names: str) -> tuple:
    """A family's registry: its type modules ``package.name``, imported, in the order
    given (the order of the DYR records and of the generated dispatch).

    Parameters
    ----------
    package : str
        The family's package (``stabctl.models.governors``).
    *names : str
        The type modules' names in it.

    Returns
    -------
    tuple of module
        The modules.
    """
    return tuple(importlib.import_module(f"{package}.{name}") for name in names)


def typed_family(
    table: str,
    min_columns: int,
    label: str,
    types,
    params,
    dyr,
    sep: str = ", ",
    common: Limits | None = None,
) -> Family:
    """The `Family` of a machine's controller table (keyed by machine, column 1 its type
    from `model_types`), with `params` after the type and the DYR records `dyr`; each
    type's `Limits` its module's ``LIMITS`` (one `Limits` for all its types, or type code
    -> its `Limits`, each one `Limits` or a tuple of them), and `common`.

    Parameters
    ----------
    table : str
        The table (``tg_con``).
    min_columns : int
        Columns a row must have.
    label : str
        The type column's label (``governor type``).
    types : dict
        Type code -> its module (`model_types`).
    params : sequence of Param
        The parameters after the type.
    dyr : tuple of DyrModel
        The DYR records read into the table.
    sep : str, optional
        Separator of the types in the type column's doc (default ", ").
    common : Limits, optional
        The limits of every type (the columns all of them read alike).

    Returns
    -------
    Family
        The declaration.
    """
    kind = Param(
        "type",
        "code",
        1,
        integer=True,
        choices=tuple(types),
        label=label,
        doc=sep.join(f"{k} {m.KINDS[k]}" for k, m in types.items()),
    )
    limits = {}
    for k, m in types.items():
        own = getattr(m, "LIMITS", ())
        own = own.get(k, ()) if isinstance(own, Mapping) else own
        own = (own,) if isinstance(own, Limits) else tuple(own)
        limits[k] = (*(() if common is None else (common,)), *own)
    return Family(
        table=table,
        min_columns=min_columns,
        key="machine",
        key_label="machine",
        params=(kind, *params),
        dyr=dyr,
        limits=MappingProxyType(limits),
        type_names=MappingProxyType({k: f"{label} {k}, {m.KINDS[k]}" for k, m in types.items()}),
    )


def _choices_text(values) -> str:
    """'0, 1, 2 or 3' for the choices message."""
    txt = [str(int(v)) if float(v).is_integer() else repr(v) for v in values]
    return txt[0] if len(txt) == 1 else ", ".join(txt[:-1]) + " or " + txt[-1]


def choices_message(p: Param) -> str:
    """The message of a value not in ``p.choices``: '{label} must be 0, 1 or 2'."""
    return f"{p.label or p.name} must be {_choices_text(p.choices)}"


def array_dataclass(cls, names):
    """``cls`` as a frozen dataclass whose fields are one ``np.ndarray`` per name in
    `names`, then the class's own annotated fields (the case tables and the models'
    parameter classes, whose fields come from the declarations).

    Parameters
    ----------
    cls : type
        The class to decorate.
    names : iterable of str
        Field names, in order.

    Returns
    -------
    type
        The dataclass.
    """
    own = dict(inspect.get_annotations(cls))
    cls.__annotations__ = {**{n: "np.ndarray" for n in names}, **own}
    return dataclass(frozen=True, eq=False)(cls)


#: tolerance of every start-up limit check (pu): an initial value this close to a limit,
#: outside it by round-off of the power flow (solved to 1e-8 by default, 1e-12 when
#: compared with ANDES), is at the limit, not beyond it (IEEE 14's bus-6 unit: Pm0 = 0.3
#: exactly at TGOV1's lower limit lands at 0.3 - 3e-17)
START_LIMIT_TOL = 1e-6


def beyond(value, lo, hi, tol: float = START_LIMIT_TOL):
    """Boolean array: ``value`` outside ``[lo, hi]`` by more than ``tol`` (pu; relative to
    the limit's size above 1) -- the start-up limit checks of the dynamic models."""
    value, lo, hi = (np.asarray(a, float) for a in (value, lo, hi))
    return (value > hi + tol * np.maximum(1.0, np.abs(hi))) | (
        value < lo - tol * np.maximum(1.0, np.abs(lo))
    )


class Declared:
    """Base of the model parameter classes (`params_class`): their declared fields are
    made at run time, so for a type checker every attribute is an array."""

    if TYPE_CHECKING:

        def __getattr__(self, name: str) -> np.ndarray: ...


def params_class(leading: tuple[str, ...], declared: tuple[str, ...]) -> Callable[[type], Any]:
    """Class decorator: a frozen dataclass whose fields are ``leading`` (model-side
    fields such as ``kind``, ``mac``), then ``declared`` (table fields under their
    declared names), then the class's own annotated fields.

    Parameters
    ----------
    leading, declared : tuple of str
        Field names, all holding numpy arrays of shape (n,).

    Returns
    -------
    callable
        The decorator (its class is typed ``Any`` for mypy: the fields are made at run
        time from the declarations).
    """
    return lambda cls: array_dataclass(cls, (*leading, *declared))


def layout(name: str, packed):
    """The named column indices of a packed layout: a namedtuple instance whose field
    ``N`` is the column of the pair (``N``, attribute) in `packed`, e.g. ``E.KA``.  A
    module-global instance is a compile-time constant to numba (its fields fold into
    the kernels like literal integers, and the kernels cache).

    Parameters
    ----------
    name : str
        The namedtuple's type name (e.g. ``"ExciterColumns"``).
    packed : sequence of (str, str)
        (column name, attribute) per column.

    Returns
    -------
    namedtuple
        Fields: the column names in order, values 0 .. len(packed) - 1.

    Raises
    ------
    ValueError
        A column name given twice or not an identifier (namedtuple's own check).
    """
    names = [column for column, _ in packed]
    return namedtuple(name, names)(*range(len(names)))


def states(name: str, names: Sequence[str]) -> Any:
    """The named slots of a model type's states, as `layout` names packed columns: a
    namedtuple instance whose field ``N`` is the slot of state ``N``, e.g. ``S.VE``
    (a compile-time constant to numba, as a layout is), read by the kernels as
    ``x[S.VE, i]``.

    Parameters
    ----------
    name : str
        The namedtuple's type name (e.g. ``"AC8BStates"``).
    names : sequence of str
        The state names in slot order.

    Returns
    -------
    namedtuple
        Fields: the state names in order, values 0 .. len(names) - 1.
    """
    return layout(name, [(n, n) for n in names])


def slots(name: str, names: Sequence[str], first: int = 0) -> Any:
    """The named slots of a component's states in a state vector that several components
    share (the converters: one column per device, each component its own run of slots),
    as `states` names a model type's: a namedtuple instance whose field ``N`` is the slot
    of state ``N``, here from `first` on and numpy int64 (so that a kernel given a slot as
    an argument compiles once for every slot, the kernel coding rules).

    Parameters
    ----------
    name : str
        The namedtuple's type name (e.g. ``"REECA1Slots"``).
    names : sequence of str
        The state names in slot order; an empty name is a slot the component leaves
        unused (no field).
    first : int, optional
        The slot of ``names[0]`` (default 0).

    Returns
    -------
    namedtuple
        Fields: the non-empty names, values ``first + j`` (numpy int64) for ``names[j]``.
    """
    named = [(n, np.int64(first + j)) for j, n in enumerate(names) if n]
    return namedtuple(name, [n for n, _ in named])(*(j for _, j in named))


def own_columns(name: str, params: Sequence[Param], first: int) -> Any:
    """The packed columns of a type's own parameters (those no other type of its family
    reads), as `layout` names a family's: a namedtuple instance whose field ``N`` (the
    parameter's name, upper case) is column ``first + j`` for ``params[j]``.  The own
    columns of every type of a family start at the same column `first` (the end of the
    shared layout): a row holds one type, whose own parameters fill them.

    Parameters
    ----------
    name : str
        The namedtuple's type name (e.g. ``"DEGOV1Columns"``).
    params : sequence of Param
        The type's own parameters, in column order.
    first : int
        The first own column (the shared layout's width).

    Returns
    -------
    namedtuple
        Fields: the upper-case names, values ``first .. first + len(params) - 1``.
    """
    return namedtuple(name, [p.name.upper() for p in params])(*range(first, first + len(params)))


def own_params(modules) -> tuple[Param, ...]:
    """The parameters a family's type modules declare as their own (each module's
    ``PARAMS``, in registry order): the table's columns after its shared ones.

    Parameters
    ----------
    modules : sequence of module
        The family's type modules (its ``MODULES``).

    Returns
    -------
    tuple of Param
        The parameters.
    """
    return tuple(p for module in modules for p in getattr(module, "PARAMS", ()))


def pack_own(obj, modules) -> np.ndarray:
    """The own columns of a family's packed matrix (`own_columns`): on each row its
    type's own parameters (its module's ``PARAMS``), in order, 0 beyond them.

    Parameters
    ----------
    obj : object
        The parameter dataclass, ``obj.n`` rows, with ``kind`` and a field per own
        parameter.
    modules : sequence of module
        The family's type modules (each with ``KINDS``).

    Returns
    -------
    numpy.ndarray
        float64, shape (obj.n, the most own parameters of a module).
    """
    width = max((len(getattr(m, "PARAMS", ())) for m in modules), default=0)
    own = np.zeros((obj.n, width))
    for module in modules:
        rows = np.isin(obj.kind, tuple(module.KINDS))
        for j, param in enumerate(getattr(module, "PARAMS", ())):
            own[rows, j] = getattr(obj, param.name)[rows]
    return own


def check_packed(cls, packed, values=()) -> None:
    """Check that every column of a packed layout reads an attribute `cls` has: a field
    of the dataclass, a property or attribute of the class (the first part of a dotted
    name such as ``KP.real``), or one of `values` (set points `pack` takes separately).

    Raises
    ------
    AttributeError
        Names the first column whose attribute `cls` does not have.
    """
    have = {f.name for f in dataclasses.fields(cls)} | set(dir(cls)) | set(values)
    for column, attr in packed:
        if attr.split(".")[0] not in have:
            raise AttributeError(
                f"{cls.__name__}: packed column {column} reads '{attr}', which it does not have"
            )


def pack(obj, layout, **values) -> np.ndarray:
    """Packed parameter matrix (n, len(layout)) of a parameter object.

    Parameters
    ----------
    obj : object
        The parameter dataclass; ``obj.n`` rows.
    layout : sequence of (str, str)
        (column name, attribute) per column; an attribute may be dotted (``KP.real``)
        or name one of ``values``.
    **values : array_like
        Columns not held by ``obj`` (set points such as ``Vref``).

    Returns
    -------
    numpy.ndarray
        float64, shape (obj.n, len(layout)).
    """

    def value(attr):
        if attr in values:
            return values[attr]
        v = obj
        for part in attr.split("."):
            v = getattr(v, part)
        return v

    cols = [np.asarray(value(attr), float) for _, attr in layout]
    return np.column_stack(cols).reshape(obj.n, len(layout))
