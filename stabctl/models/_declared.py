"""What the model parameter classes and packed kernel matrices take from the parameter
declarations of :mod:`stabctl.case.params`.

Each model family (exciters, PSS, governors, machines) lists, once, which declared
table fields its kernels take as given (``TABLE_FIELDS``) and the layout of its packed
parameter matrix (``PACKED``: constant suffix and attribute per column).  From these,
:func:`params_class` gives the parameter dataclass its fields, :func:`columns`
the kernels' column constants (``E_KA``, ``S_TW``, ...) and :func:`pack` the matrix.
"""

from __future__ import annotations

import numpy as np

from stabctl.case.params import array_dataclass


def params_class(leading: tuple[str, ...], declared: tuple[str, ...]):
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
        The decorator.
    """
    return lambda cls: array_dataclass(cls, (*leading, *declared))


def columns(layout, *suffixes: str) -> tuple[int, ...]:
    """Column of each named constant suffix in a packed layout of (suffix, attribute)
    pairs: the kernels' column constants (numba reads module globals as compile-time
    constants).

    Raises
    ------
    KeyError
        A suffix the layout does not hold.
    """
    index = {suffix: k for k, (suffix, _) in enumerate(layout)}
    return tuple(index[s] for s in suffixes)


def pack(obj, layout, **values) -> np.ndarray:
    """Packed parameter matrix (n, len(layout)) of a parameter object.

    Parameters
    ----------
    obj : object
        The parameter dataclass; ``obj.n`` rows.
    layout : sequence of (str, str)
        (constant suffix, attribute) per column; an attribute may be dotted (``KP.real``)
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
