"""Words of the messages and reports, one way everywhere: a count with its noun."""

from __future__ import annotations

__all__ = ["counted"]


def counted(n: int, noun: str, plural: str | None = None) -> str:
    """A count and its noun, singular for one: ``"1 frame"``, ``"181 frames"``.

    Parameters
    ----------
    n : int
        The count.
    noun : str
        The noun for one.
    plural : str, optional
        The noun for any other count; default `noun` + "s".

    Returns
    -------
    str
    """
    return f"{n} {noun if n == 1 else plural or noun + 's'}"
