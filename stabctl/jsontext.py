"""JSON text read strictly: an object that gives one key twice is refused instead of
keeping its last value (`parse_json`), for every JSON file stabctl reads (case files,
records files, ANDES JSON).  It sits low in the layers, just above
`stabctl.errors`, so that the sweep records (`stabctl.parallel`) and the case readers
(`stabctl.io`) read JSON alike.
"""

from __future__ import annotations

import json
from typing import Any

from stabctl.errors import InputError

__all__ = ["parse_json"]


class _KeyTwice(ValueError):
    """A JSON object giving one key twice (`_unique_keys`), caught by `parse_json`."""

    def __init__(self, key: str, first, last):
        super().__init__(key)
        self.key, self.first, self.last = key, first, last


def _unique_keys(pairs: list[tuple[str, Any]]) -> dict:
    """``object_pairs_hook`` of `parse_json`: the object's dict, a key given twice refused."""
    out: dict = {}
    for key, value in pairs:
        if key in out:
            raise _KeyTwice(key, out[key], value)
        out[key] = value
    return out


def _shown(value) -> str:
    """A JSON value for a message: a scalar as written, an object or list by its kind."""
    if isinstance(value, dict):
        return "an object"
    if isinstance(value, list):
        return "a list"
    text = json.dumps(value)
    return text if len(text) <= 40 else text[:37] + "..."


def parse_json(text: str, where: str, error: type[Exception] = InputError) -> Any:
    """``json.loads(text)``, refusing an object that gives one key twice (json keeps the
    last value without a word: a case's ``base_mva`` given 100 then 50 was read as 50).

    Parameters
    ----------
    text : str
        The JSON text.
    where : str
        The file (and line) it comes from, named first in the message.
    error : type, optional
        The exception raised for a key given twice (InputError; a case file's reader
        gives CaseError).

    Returns
    -------
    object
        The parsed value.

    Raises
    ------
    Exception
        ``error`` for a key given twice, naming ``where``, the key and both values.
    json.JSONDecodeError
        Not JSON (as json.loads).
    RecursionError
        Nested too deeply (as json.loads).
    """
    try:
        return json.loads(text, object_pairs_hook=_unique_keys)
    except _KeyTwice as exc:
        raise error(
            f"{where}: key {json.dumps(exc.key)} given twice in one object "
            f"({_shown(exc.first)}, then {_shown(exc.last)}): give each key once (JSON "
            "readers keep the last without a word)"
        ) from None
