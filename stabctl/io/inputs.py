"""Input files as a user gives them: regular files of bounded size, and strict CSV tables.

Every file a command reads (a case, a fault list, site costs, screening records) must be a
regular file no larger than :data:`MAX_INPUT_BYTES`: ``/dev/zero``, a pipe, a directory
or a link to one is refused before a byte is read (reading one had no end).

A CSV table (:func:`read_csv`) is UTF-8 text (a byte-order mark allowed) with a header
naming its columns: every column must be one the table knows (a misspelt column is an
error, not ignored), none twice, the required ones present; every row must have exactly
the header's number of fields (a row cut short is an error, not a row with missing
values); blank lines are skipped, values stripped.  A table is read a row at a time
(:func:`iter_csv`); a header of more columns than the table has is refused with its count,
a line longer than a row of its columns can be by its length, before the line is split.
Errors name ``file:line`` and what is wrong; :func:`number` parses one field the same way
(finite, in range, an integer where one is needed).

A JSON input (:func:`parse_json`) is refused when one object gives a key twice: Python's
json module keeps the last value without a word.
"""

from __future__ import annotations

import csv
import math
import os
import re
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass

from stabctl.errors import CaseError, InputError
from stabctl.jsontext import MAX_INPUT_BYTES, input_file, parse_json, wide_unicode

__all__ = [
    "MAX_INPUT_BYTES",
    "CsvRow",
    "input_file",
    "iter_csv",
    "number",
    "parse_json",
    "plain_float",
    "plain_integer",
    "plain_number",
    "read_csv",
]


def case_text(path, what: str) -> str:
    """The text of a PSS/E RAW or DYR file (`path`, checked by `input_file`): ASCII or
    UTF-8 (a byte-order mark dropped; bytes that are neither read as U+FFFD, which no
    number or name check takes).

    Parameters
    ----------
    path : pathlib.Path
        The file.
    what : str
        What it is, for messages (``"RAW file"``).

    Returns
    -------
    str

    Raises
    ------
    CaseError
        A file in UTF-16 or UTF-32 (its byte-order mark, or NUL bytes as a quarter or more
        of its first 4096 bytes: an editor's "Unicode" save, read as "SBASE = ' ': not a
        number"), naming the file and what to do; a NUL byte elsewhere (a damaged file),
        naming the file and its line.
    OSError
        The file cannot be read.
    """
    data = path.read_bytes()
    if wide_unicode(data[:4096]):
        raise CaseError(
            f"{path}: the {what} is in UTF-16 or UTF-32 (a byte-order mark or NUL bytes at its "
            "start), not text PSS/E reads: save it as ASCII or UTF-8"
        )
    if (at := data.find(0)) >= 0:  # (round 46: one NUL was read as UTF-16, no line named)
        line = data.count(b"\n", 0, at) + 1
        raise CaseError(
            f"{path}:{line}: the {what} holds a NUL byte (byte {at}): a damaged file, not "
            "text PSS/E reads"
        )
    return data.decode("utf-8-sig", errors="replace")


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
    """The data rows of a strict CSV table (module doc), as a list (`iter_csv`).

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
        As `iter_csv`.
    """
    return list(iter_csv(path, what, required, optional))


def iter_csv(
    path: str | os.PathLike, what: str, required: tuple[str, ...], optional: tuple[str, ...] = ()
) -> Iterator[CsvRow]:
    """The data rows of a strict CSV table (module doc), one at a time: a caller that stops
    at its first error has read the file no further, and keeps no row it does not keep
    itself.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    what : str
        What it is, for messages (``"fault list"``).
    required, optional : tuple of str
        The columns it must have, and the others it may have.

    Yields
    ------
    CsvRow
        In file order; at least one.

    Raises
    ------
    InputError
        Not a regular file of bounded size, not UTF-8, a field beyond the csv module's
        limit, a line longer than a row of the table's columns can be, a header with more
        columns than the table has or with an unknown, duplicated or missing column, a row
        with another number of fields than the header, or no data row; naming
        ``file:line``.
    """
    path = input_file(path, what)
    name, header, found = path.name, None, False
    try:
        with path.open(newline="", encoding="utf-8-sig") as f:
            lines = _Lines(f, what, name, required, optional)
            reader = csv.reader(lines)
            for fields in reader:
                if not any(s.strip() for s in fields):
                    continue
                if header is None:
                    where = f"{what} {name}:{reader.line_num}"
                    header = _header(fields, what, where, required, optional)
                    lines.header_read = True
                    continue
                if len(fields) != len(header):
                    raise InputError(
                        f"{what} {name}:{reader.line_num}: {len(fields)} field(s), the header "
                        f"has {len(header)} ({','.join(header)}): a row cut short or with "
                        "extra fields"
                    )
                found = True
                yield CsvRow(
                    name,
                    reader.line_num,
                    dict(zip(header, (s.strip() for s in fields), strict=True)),
                )
    except UnicodeDecodeError as exc:
        raise InputError(
            f"{what} {path}: not UTF-8 text (byte {exc.start}: {exc.reason}); save it as UTF-8"
        ) from None
    except csv.Error as exc:
        raise InputError(f"{what} {name}:{reader.line_num}: {exc}") from None
    except OSError as exc:
        raise InputError(f"{what} {path}: {exc.strerror or exc}") from None
    if not found:
        raise InputError(
            f"{what} {path}: needs a header ({_columns(required, optional)}) and at least one row"
        )


def _columns(required, optional) -> str:
    """A table's columns for messages: ``bus,far_bus[,t_fault]``."""
    return ",".join(required) + "".join(f"[,{c}]" for c in optional)


class _Lines:
    """The lines of a CSV file for `csv.reader`, each read at most to the length a row of
    the table can have: the csv module splits a whole line into a list of fields, so a line
    of millions of fields took gigabytes.  Before the header, a line without quotes whose
    commas give more columns than the table has is refused with its count (the rest of a
    long line read in bounded pieces); any line longer than a row of the table's columns
    can be (each at most the csv module's field limit, quoted) is refused by its length."""

    def __init__(self, f, what: str, name: str, required, optional):
        self.f, self.what, self.name = f, what, name
        self.required, self.optional = required, optional
        self.n, self.header_read = 0, False
        self.cap = (len(required) + len(optional)) * (2 * csv.field_size_limit() + 3)

    def __iter__(self):
        return self

    def __next__(self) -> str:
        line = self.f.readline(self.cap + 1)
        if not line:
            raise StopIteration
        self.n += 1
        long = len(line) > self.cap and line[-1] not in "\r\n"
        if self.header_read and not long:
            return line
        n_chars, commas, quoted, text = len(line), line.count(","), '"' in line, _text(line)
        while long and line[-1] not in "\r\n":  # the rest of the line, in bounded pieces
            line = self.f.readline(1 << 20)
            if not line:
                break
            n_chars += len(line)
            commas += line.count(",")
            quoted = quoted or '"' in line
            text = text or _text(line)
        where = f"{self.what} {self.name}:{self.n}"
        if not self.header_read and text and not quoted:
            _check_count(commas + 1, where, self.what, self.required, self.optional)
        if long:
            raise InputError(
                f"{where}: a line of {n_chars} characters, longer than a row of "
                f"{_columns(self.required, self.optional)} can be (at most {self.cap})"
            )
        return line


def _text(line: str) -> bool:
    """Whether a line has more than commas and blanks (else csv reads a blank row)."""
    return bool(line.replace(",", "").strip())


def _check_count(count: int, where: str, what: str, required, optional) -> None:
    """Refuse a header of more columns than the table has."""
    known = len(required) + len(optional)
    if count > known:
        raise InputError(
            f"{where}: a header of {count} columns, more than the {known} a {what} has "
            f"({_columns(required, optional)})"
        )


def _header(fields: list[str], what: str, where: str, required, optional) -> list[str]:
    """The stripped column names of a header line, checked against the table's columns."""
    _check_count(len(fields), where, what, required, optional)
    names = [s.strip() for s in fields]
    known = (*required, *optional)
    twice = sorted(n for n, k in Counter(names).items() if k > 1)
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


_SIGNED_DIGITS = re.compile(r"[+-]?[0-9]+")


def plain_integer(text: str, most: int) -> int | None:
    """`text` as an integer when it is ASCII digits with an optional sign, of at most `most`
    digits leading zeros aside; None otherwise.  Python's int() refuses a string of more
    than 4300 digits with a ValueError of its own (``sys.get_int_max_str_digits``); a
    field's count of digits is checked before, so such a field is refused by its reader,
    naming it, as any other malformed one (round 58: an IDCODE, a case file's machine
    number and a DYR bus of 5000 digits escaped as that ValueError with a traceback).

    Parameters
    ----------
    text : str
        The field as written (stripped by the caller).
    most : int
        The most digits a value of the field can have (a PSS/E bus number 6, an IDCODE 5).

    Returns
    -------
    int or None
    """
    if not _SIGNED_DIGITS.fullmatch(text):
        return None
    digits = text.lstrip("+-").lstrip("0")
    return int(text) if len(digits) <= most else None


def shown_field(text: str, most: int = 24) -> str:
    """A field as written, for a message: cut after `most` characters with its length said
    (a field of 5000 digits is not echoed whole).

    Parameters
    ----------
    text : str
    most : int

    Returns
    -------
    str
    """
    return text if len(text) <= most else f"{text[:most]}... ({len(text)} characters)"


#: why a number below the smallest float is refused (`underflows`)
UNDERFLOW = "too small for a float (it would be read as 0)"


def underflows(text: str, value) -> bool:
    """Whether a number written as ``text`` was read as 0 though it is not (``1e-400``).

    Parameters
    ----------
    text : str
        The number as given.
    value : float
        What it was read as.

    Returns
    -------
    bool
    """
    return value == 0 and re.search(r"[1-9]", re.split("[eEdD]", text)[0]) is not None


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
    if underflows(text, v):
        raise InputError(f"{row.where()}: {column} {text} is {UNDERFLOW}")
    if not math.isfinite(v) or not lo <= v <= hi:
        raise InputError(f"{row.where()}: {column} {text} is outside [{lo:g}, {hi:g}]")
    if integer and not text.lstrip("+-").isdigit():  # 3.0, 3e0: a measured value, not a label
        raise InputError(f"{row.where()}: {column} {text} is not an integer (write it as digits)")
    return v
