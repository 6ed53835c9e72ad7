"""Input files as a user gives them: regular files of bounded size, and strict CSV tables.

Every file a command reads (a case, a fault list, site costs, screening records) must be a
regular file no larger than :data:`MAX_INPUT_BYTES`: ``/dev/zero``, a pipe, a directory
or a link to one is refused before a byte is read (reading one had no end).

A CSV table (:func:`read_csv`) is UTF-8 text (a byte-order mark allowed) with a header
naming its columns: every column must be one the table knows (a misspelt column is an
error, not ignored), none twice, the required ones present; every row must have exactly
the header's number of fields (a row cut short is an error, not a row with missing
values); blank lines are skipped, values stripped.  Errors name ``file:line`` and what is
wrong; :func:`number` parses one field the same way (finite, in range, an integer where
one is needed).

A JSON input (:func:`parse_json`) is refused when one object gives a key twice: Python's
json module keeps the last value without a word.
"""

from __future__ import annotations

import csv
import math
import os
from dataclasses import dataclass

from stabctl.errors import InputError
from stabctl.jsontext import MAX_INPUT_BYTES, input_file, parse_json

__all__ = [
    "MAX_INPUT_BYTES",
    "CsvRow",
    "input_file",
    "number",
    "parse_json",
    "plain_float",
    "plain_number",
    "read_csv",
]


def number_ranges(numbers) -> list[tuple[int, int]]:
    """Consecutive integers as (first, last) ranges, in the given order: 1, 2, 3, 7 ->
    [(1, 3), (7, 7)] (a list of rows, of ports, for a message).

    Parameters
    ----------
    numbers : iterable of int
        The integers.

    Returns
    -------
    list of (int, int)
        The ranges.
    """
    runs: list[list[int]] = []
    for n in numbers:
        if runs and runs[-1][1] + 1 == n:
            runs[-1][1] = n
        else:
            runs.append([n, n])
    return [(a, b) for a, b in runs]


@dataclass(frozen=True)
class CsvRow:
    """One data row of a CSV table: its 1-based line in the file and its values (column ->
    stripped text; every column of the header present)."""

    file: str
    line: int
    values: dict[str, str]

    def where(self) -> str:
        """``file:line`` for messages."""
        return f"{self.file}:{self.line}"


def read_csv(
    path: str | os.PathLike, what: str, required: tuple[str, ...], optional: tuple[str, ...] = ()
) -> list[CsvRow]:
    """The data rows of a strict CSV table (module doc).

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    what : str
        What it is, for messages (``"fault list"``).
    required, optional : tuple of str
        The columns it must have, and the others it may have.

    Returns
    -------
    list of CsvRow
        In file order; at least one.

    Raises
    ------
    InputError
        Not a regular file of bounded size, not UTF-8, a field beyond the csv module's
        limit, a header with an unknown, duplicated or missing column, a row with another
        number of fields than the header, or no data row; naming ``file:line``.
    """
    path = input_file(path, what)
    name, rows, header = path.name, [], None
    try:
        with path.open(newline="", encoding="utf-8-sig") as f:
            reader = csv.reader(f)
            for fields in reader:
                if not any(s.strip() for s in fields):
                    continue
                if header is None:
                    header = _header(fields, f"{what} {name}:{reader.line_num}", required, optional)
                    continue
                if len(fields) != len(header):
                    raise InputError(
                        f"{what} {name}:{reader.line_num}: {len(fields)} field(s), the header "
                        f"has {len(header)} ({','.join(header)}): a row cut short or with "
                        "extra fields"
                    )
                values = dict(zip(header, (s.strip() for s in fields), strict=True))
                rows.append(CsvRow(name, reader.line_num, values))
    except UnicodeDecodeError as exc:
        raise InputError(
            f"{what} {path}: not UTF-8 text (byte {exc.start}: {exc.reason}); save it as UTF-8"
        ) from None
    except csv.Error as exc:
        raise InputError(f"{what} {name}:{reader.line_num}: {exc}") from None
    except OSError as exc:
        raise InputError(f"{what} {path}: {exc.strerror or exc}") from None
    if not rows:
        columns = ",".join(required) + "".join(f"[,{c}]" for c in optional)
        raise InputError(f"{what} {path}: needs a header ({columns}) and at least one row")
    return rows


def _header(fields: list[str], where: str, required, optional) -> list[str]:
    """The stripped column names of a header line, checked against the table's columns."""
    names = [s.strip() for s in fields]
    known = (*required, *optional)
    twice = sorted({n for n in names if names.count(n) > 1})
    unknown = [n for n in names if n not in known]
    missing = [n for n in required if n not in names]
    for bad, why in ((twice, "twice"), (unknown, "unknown"), (missing, "missing")):
        if bad:
            raise InputError(
                f"{where}: column(s) {', '.join(repr(n) for n in bad)} {why}; the columns are "
                f"{', '.join(required)} (required) and {', '.join(optional) or 'no other'}"
            )
    return names


def plain_number(text: str) -> bool:
    """Whether `text` spells a number with ASCII characters only and no ``_``: Python's
    int() and float() also read ``1_5`` as 15 and fullwidth digits (U+FF13) as 3, which
    nobody types meaning them.

    Parameters
    ----------
    text : str

    Returns
    -------
    bool
    """
    return text.isascii() and "_" not in text


def plain_float(text: str, fortran: bool = False) -> float:
    """``float(text)`` for a `plain_number` spelling, -0 read as 0 (a time of -0 s is
    printed as 0 s).

    Parameters
    ----------
    text : str
        The number as written.
    fortran : bool, optional
        Also read ``D`` as the exponent letter (``1.5D0``, as PSS/E and MATLAB files may
        write it).

    Returns
    -------
    float
        Its value (inf and nan as float() reads them: the caller bounds it).

    Raises
    ------
    ValueError
        Not a number, or written with other than ASCII characters or with ``_``.
    """
    if not plain_number(text):
        raise ValueError(f"{text!r}: write numbers in ASCII digits, without '_'")
    if fortran:
        text = text.replace("D", "E").replace("d", "e")
    return float(text) + 0.0


def number(
    row: CsvRow,
    column: str,
    lo: float = -math.inf,
    hi: float = math.inf,
    *,
    integer: bool = False,
    default: float | None = None,
) -> float:
    """The value of ``column`` in ``row`` as a finite number in [lo, hi] (an integer if
    ``integer``); an empty field gives ``default``.

    Raises
    ------
    InputError
        Empty without a default, not a number, not finite, out of range, or not an
        integer; naming ``file:line`` and the column.
    """
    text = row.values.get(column, "")
    if not text:
        if default is None:
            raise InputError(f"{row.where()}: {column} is empty")
        return default
    try:
        v = plain_float(text)
    except ValueError:
        raise InputError(
            f"{row.where()}: {column} '{text}' is not a number (ASCII digits, no '_')"
        ) from None
    if not math.isfinite(v) or not lo <= v <= hi:
        raise InputError(f"{row.where()}: {column} {text} is outside [{lo:g}, {hi:g}]")
    if integer and not text.lstrip("+-").isdigit():  # 3.0, 3e0: a measured value, not a label
        raise InputError(f"{row.where()}: {column} {text} is not an integer (write it as digits)")
    return v
