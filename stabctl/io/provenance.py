"""Where each row of an imported case's tables came from, to name it in errors.

A case table refuses a value naming its own table, row and field (``exc_con row 1
(machine 1), field 'TC'``), with the fields its rule reads, their values and the rule as
attributes of the :class:`~stabctl.errors.CaseError`.  An importer knows the source of
each row it writes -- a DYR record (``file:line MODEL (bus B, id I)``) or an ANDES device
(``file: MODEL row R (idx I)``) -- and which of the source's parameters each column holds,
as the user wrote them (``X''d``, ``TA/TB``, ANDES's ``dbd1``).  :func:`locate` turns the
table's error into one naming that source and those parameters with their values as
written, the rule after them.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

from stabctl.errors import CaseError

__all__ = ["Origin", "Written", "locate", "shown"]


class Written(float):  # arguments of __new__: numpydoc ignore=PR02
    """A number read from a data file that keeps its text as the file writes it
    (``-1.508E-01``, ``1.5D0``), for messages: ``str()``, ``repr()`` and an f-string
    without a format give that text, arithmetic a plain float.

    Parameters
    ----------
    value : float
        The number.
    text : str
        Its text in the file.
    """

    __slots__ = ("text",)
    text: str

    def __new__(cls, value: float, text: str) -> Written:
        self = super().__new__(cls, value)
        self.text = text
        return self

    def __str__(self) -> str:
        return self.text

    __repr__ = __str__

    def __format__(self, spec: str) -> str:
        return self.text if not spec else format(float(self), spec)

    def __reduce__(self):
        return (Written, (float(self), self.text))


@dataclass(frozen=True)
class Origin:  # fields of a dataclass: numpydoc ignore=PR02
    """The source of one table row.

    Parameters
    ----------
    where : str
        The source record as messages name it (``"d.dyr:4 SEXS (bus 1, id 1)"``).
    params : Mapping[int, tuple of (str, float)]
        Table column (1-based) -> the source's parameters it holds, each (name as
        written, value as written); a column absent: none of the source's (stabctl's
        own, from the power-flow data, or a default).
    derived : frozenset of int
        The columns computed from their parameters (a product, ratio, unit change), not
        copies: named with the value the table holds.
    places : Mapping[int, str]
        Column -> its own source where it is not ``where`` (a converter row's REECA1 and
        REPCA1 columns, from their devices).
    """

    where: str
    params: Mapping[int, tuple[tuple[str, float], ...]] = field(default_factory=dict)
    derived: frozenset[int] = frozenset()
    places: Mapping[int, str] = field(default_factory=dict)


def shown(value: float) -> str:
    """A value as a data file writes it: its own text where it was read with it
    (`Written`), else an integer without a decimal point, else the shortest text that
    reads back as the number (``0.2426``, ``-0.1``).

    Parameters
    ----------
    value : float
        The value.

    Returns
    -------
    str
        Its text.
    """
    if isinstance(value, Written):
        return value.text
    v = float(value)
    return str(int(v)) if v.is_integer() and abs(v) < 1e15 else repr(v)


def locate(exc: CaseError, origins: Mapping[str, Sequence[Origin | None]], families) -> CaseError:
    """The error ``exc`` of a case table, naming the source of its row instead.

    Parameters
    ----------
    exc : CaseError
        Raised by a table (`stabctl.case.system.Table`): its ``table``, ``row``,
        ``fields``, ``values`` and ``rule``.
    origins : Mapping[str, sequence of Origin or None]
        Table name (``"mac_con"``) -> the origin of each row (None: a row of no source).
    families : Mapping[str, object]
        Table name -> its declaration (`stabctl.models.declaration.Family`: ``col`` of a
        field), for the tables ``origins`` names.

    Returns
    -------
    CaseError
        ``"{where}: {name} = {value}, ...: {rule}"`` with the source's parameter names
        and values as written (a derived column's table value added, ``(giving exc_con
        'TC' = -1)``; a column of no source parameter as ``{table} '{field}' = {value}``);
        ``exc`` itself when its row has no origin.
    """
    rows = origins.get(exc.table or "")
    if exc.row is None or not rows or exc.row >= len(rows) or rows[exc.row] is None:
        return exc
    origin = rows[exc.row]
    assert origin is not None
    family = families[exc.table]
    named: list[str] = []
    seen: set = set()  # the columns and source parameters named
    first_place = None
    for name, value in zip(exc.fields, exc.values):
        try:
            col = family.col(name)
        except KeyError:
            col = None
        place = origin.places.get(col, origin.where) if col is not None else origin.where
        given = origin.params.get(col, ()) if col is not None else ()
        key = (place, given) if given else col
        if key in seen:
            continue
        seen.add(key)
        first_place = first_place or place
        if not given:
            text = f"{exc.table} '{name}' = {shown(value)}"
        else:
            text = ", ".join(f"{n} = {shown(v)}" for n, v in given)
            if col in origin.derived and all(v != value for _, v in given):
                text += f" (giving {exc.table} '{name}' = {shown(value)})"
        if place != first_place:
            text += f" ({place})"
        named.append(text)
    where = first_place or origin.where
    rule = exc.rule or str(exc)
    return exc.relocated(f"{where}: {', '.join(named)}: {rule}" if named else f"{where}: {rule}")
