"""Input files and JSON text read strictly, for every reader of stabctl.

Every input file is a regular file of at most :data:`MAX_INPUT_BYTES` (`input_file`).
In JSON text an object that gives one key twice is refused instead of keeping its last
value, and an integer of more digits than Python converts (4300, its
``sys.get_int_max_str_digits``) is refused naming the file instead of escaping as
Python's ValueError (`parse_json`), for every JSON file stabctl reads (case files,
records files, ANDES JSON).  It sits low in the layers, just above `stabctl.errors`, so
that the sweep records (`stabctl.parallel`) and the case readers (`stabctl.io`, which
gives both under `stabctl.io.inputs`) read files alike.
"""

from __future__ import annotations

import json
import os
import stat
import sys
from pathlib import Path
from typing import Any

from stabctl.errors import InputError

__all__ = ["MAX_INPUT_BYTES", "MAX_JSON_BYTES", "input_file", "parse_json", "wide_unicode"]

#: largest input file read, bytes (the largest case shipped, ACTIVSg2000's RAW, is 0.7 MB)
MAX_INPUT_BYTES = 256 * 2**20
#: largest file of JSON text read whole into Python objects (a case file, a records file,
#: an ANDES json case), bytes: its objects take 6-8 times its bytes (round 44: a 250 MiB
#: case file peaked at 1.4 GiB, a 223 MiB records file at 1.8 GiB); ACTIVSg2000's case
#: file is about 5 MB, its N-1 screening's records about 15 MB
MAX_JSON_BYTES = 64 * 2**20


def input_file(path: str | os.PathLike, what: str, limit: int = MAX_INPUT_BYTES) -> Path:
    """``path`` after checking that it is a regular file of at most ``limit`` bytes
    (links followed).

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    what : str
        What it is, for messages (``"fault list"``).
    limit : int, optional
        Its largest size, bytes: MAX_INPUT_BYTES (default), MAX_JSON_BYTES for JSON text
        read whole.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    InputError
        Empty, missing or unreadable, not a regular file (a device, a pipe, a directory),
        or too large; the message names ``what`` and the path.
    """
    if not str(os.fspath(path)).strip():  # Path("") is "." (the directory)
        raise InputError(f"{what}: an empty path; give a file")
    path = Path(path)
    try:
        st = os.stat(path)
    except OSError as exc:
        raise InputError(f"{what} {path}: {exc.strerror or exc}") from None
    if not stat.S_ISREG(st.st_mode):
        raise InputError(
            f"{what} {path}: not a regular file (a device, a pipe or a directory); give a file"
        )
    if st.st_size > limit:
        kind = "an input file" if limit == MAX_INPUT_BYTES else "a file of JSON text read whole"
        raise InputError(
            f"{what} {path}: {st.st_size / 2**20:.0f} MiB, above the "
            f"{limit / 2**20:.0f} MiB {kind} may have"
        )
    return path


class _KeyTwice(ValueError):
    """A JSON object giving one key twice (`_unique_keys`), caught by `parse_json`."""

    def __init__(self, key: str, first, last):
        super().__init__(key)
        self.key, self.first, self.last = key, first, last


class _LongInt(ValueError):
    """An integer literal of more digits than Python converts (`_integer`), caught by
    `parse_json`."""

    def __init__(self, digits: str):
        super().__init__(digits)
        self.digits = digits


def wide_unicode(head: bytes) -> bool:
    """Whether a text file's first bytes are UTF-16 or UTF-32 (an editor's "Unicode"
    save): a byte-order mark, or NUL bytes as a quarter or more of them (ASCII text in
    UTF-16 is half NULs, in UTF-32 three quarters).  The one test of the readers that
    take text only as ASCII or UTF-8 (`stabctl.io.inputs.case_text`, the records files
    of `stabctl.parallel`).

    Parameters
    ----------
    head : bytes
        The file's first bytes (its first 4096, or fewer).

    Returns
    -------
    bool
    """
    return head[:2] in (b"\xff\xfe", b"\xfe\xff") or head.count(0) * 4 >= max(len(head), 1)


def _integer(digits: str) -> int:
    """``parse_int`` of `parse_json`: ``int(digits)``, or `_LongInt` when Python refuses
    the conversion (more than ``sys.get_int_max_str_digits()`` digits)."""
    try:
        return int(digits)
    except ValueError:
        raise _LongInt(digits) from None


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
    last value without a word: a case's ``base_mva`` given 100 then 50 was read as 50) and
    an integer of more digits than Python converts (json raised Python's own ValueError,
    "Exceeds the limit (4300 digits)", naming no file).

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
        ``error`` for a key given twice, naming ``where``, the key and both values; or
        for an integer of too many digits, naming ``where`` (and the line of a text of
        several lines) and how many digits.
    json.JSONDecodeError
        Not JSON (as json.loads).
    RecursionError
        Nested too deeply (as json.loads).
    """
    try:
        return json.loads(text, object_pairs_hook=_unique_keys, parse_int=_integer)
    except _KeyTwice as exc:
        raise error(
            f"{where}: key {json.dumps(exc.key)} given twice in one object "
            f"({_shown(exc.first)}, then {_shown(exc.last)}): give each key once (JSON "
            "readers keep the last without a word)"
        ) from None
    except _LongInt as exc:
        line = text.count("\n", 0, text.find(exc.digits)) + 1
        raise error(
            f"{where}: an integer of {len(exc.digits.lstrip('-'))} digits"
            + (f" at line {line}" if "\n" in text.strip() else "")
            + f", more than Python converts ({sys.get_int_max_str_digits()}): give the number "
            "in fewer digits"
        ) from None
