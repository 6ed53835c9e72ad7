"""What the model parameter classes and packed kernel matrices take from the parameter
declarations of :mod:`stabctl.case.params`.

Each model family (exciters, PSS, governors, machines) lists, once, which declared
table fields its kernels take as given (``TABLE_FIELDS``) and the layout of its packed
parameter matrix (``PACKED``: column name and attribute per column).  From these,
:func:`params_class` gives the parameter dataclass its fields, :func:`layout` the
kernels' named column indices (``E.KA``, ``S.TW``, ...; each name spelled once, in
``PACKED``), :func:`check_packed` that every column's attribute exists, and :func:`pack`
the matrix.
"""

from __future__ import annotations

import dataclasses
from collections import namedtuple
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from stabctl.case.params import array_dataclass


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
