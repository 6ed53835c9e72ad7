"""Reading and writing cases: PST/PSTess data files and stabctl's own JSON format.

Three inputs give a :class:`~stabctl.case.Case`:

* PSTess evaluated-matrix JSON (``{"bus": [[...]], "line": [[...]], "mac_con": ...}``),
  one key per matrix the data file defines (as written by GNU Octave from a PSTess ``.m``);
* PST ``.m`` data files made only of literal matrices (``name = [ ... ];`` with ``...``
  continuations, ``%`` comments, ``;`` or newline row separators, ``disp(...)`` lines);
  anything computed (expressions, variables, loops, ``if``) is refused with the line;
* stabctl's own JSON case format (:func:`write_case_json` / :func:`read_case_json`):
  named columns per table, a format version, the source and the licence note.

PST matrix names mapped to tables: ``bus`` -> buses, ``line`` -> branches, ``mac_con`` ->
machines, ``exc_con`` -> exciters, ``pss_con`` -> pss, ``tg_con`` -> governors,
``load_con`` -> loads; ``sw_con`` is kept as ``Case.sw_con``; the data matrices stabctl does
not model (:data:`EXTRA_MATRICES`: ``lmod_con``, ``PDC``, ...) go to ``Case.extra``, and any
other variable is left out with a warning naming it. Bus and machine numbers stay as in the
data. ``basmva`` and ``sys_freq`` are read when the file defines them (PST defaults 100 MVA,
60 Hz otherwise). Source: PST manual sections 1.3 and 2.1 (data file structure).
"""

from __future__ import annotations

import json
import re
import warnings
from array import array
from collections.abc import Iterator, Mapping
from contextlib import contextmanager, nullcontext
from pathlib import Path
from typing import Any

import numpy as np

from stabctl.case import TABLES, Case
from stabctl.case.events import check_case_events
from stabctl.case.system import tables_named
from stabctl.errors import CaseError
from stabctl.io.inputs import input_file, parse_json, plain_float, plain_integer, shown_field
from stabctl.jsontext import MAX_JSON_BYTES

__all__ = [
    "FORMAT",
    "FORMAT_VERSION",
    "PST_TABLES",
    "case_from_matrices",
    "parse_m",
    "read_pst_m",
    "read_pstess_json",
    "read_any",
    "write_case_json",
    "read_case_json",
    "read_case_header",
    "case_to_dict",
    "case_from_dict",
]

#: Identifier and version of stabctl's own JSON case format.
FORMAT = "stabctl-case"
FORMAT_VERSION = 1

#: PST matrix name -> Case table field.
PST_TABLES: Mapping[str, str] = {
    "bus": "buses",
    "line": "branches",
    "mac_con": "machines",
    "exc_con": "exciters",
    "pss_con": "pss",
    "tg_con": "governors",
    "load_con": "loads",
    "ibr_con": "converters",  # stabctl's converter table (ANDES PVD1, ESD1), no PST matrix
    "shaft_con": "shafts",  # stabctl's torsional shafts (ANDES SHAFT5), no PST matrix
    "mot_con": "motors",  # stabctl's induction motors (ANDES Motor5), no PST matrix
    "svc_con": "svcs",  # stabctl's static var compensators (PSS/E CSVGN1), no PST matrix
    "swsh_con": "switched_shunts",  # stabctl's switched shunts (ANDES ShuntSw), no PST matrix
    "inj_con": "injections",  # stabctl's fixed injections (HVDC set points), no PST matrix
    "vreg_con": "remote_regulation",  # stabctl's remote voltage regulation, no PST matrix
}

_SCALARS = {"basmva": "base_mva", "sys_freq": "freq_hz"}
_DEFAULT_BASE_MVA = 100.0
_DEFAULT_FREQ_HZ = 60.0
_DEFAULTS = {"base_mva": _DEFAULT_BASE_MVA, "freq_hz": _DEFAULT_FREQ_HZ}
_UNITS = {"base_mva": "MVA", "freq_hz": "Hz"}

#: the data matrices of PST 3.0 (``pst_var.m``) and PSTess 1.1 that stabctl keeps as given
#: without modelling them (``Case.extra``), and the shipped miniWECC data file's own
#: (``PDC``, ``TCSC_Gen``, ``pssGen``, ``pssType``); a PST file's other variables are left
#: out with a warning, and a case file's other ``extra`` names refused
EXTRA_MATRICES = frozenset(
    (
        "lmod_con",
        "rlmod_con",
        "lmon_con",
        "ibus_con",
        "ind_con",
        "mld_con",
        "igen_con",
        "tcsc_con",
        "dpw_con",
        "dcsp_con",
        "dcl_con",
        "dcc_con",
        "scr_con",
        "netg_con",
        "stab_con",
        "pwrmod_con",
        "ivm_con",
        "ess_con",
        "lsc_con",
        "PDC",
        "TCSC_Gen",
        "pssGen",
        "pssType",
    )
)


# --------------------------------------------------------------------------------------
# PST matrices -> Case
# --------------------------------------------------------------------------------------


def case_from_matrices(
    mats: Mapping[str, Any],
    name: str,
    *,
    source: str = "",
    description: str = "",
    where: str = "",
) -> Case:
    """Build a Case from PST matrices by PST name (``bus``, ``line``, ``mac_con``, ...).

    ``mats`` values are nested lists or arrays (rows x columns); ``bus`` and ``line`` are
    required. ``basmva``/``sys_freq`` scalars set the bases. Raises :class:`CaseError`
    for a missing ``bus``/``line`` or any invalid table (see :mod:`stabctl.case`), its
    message starting with ``where`` (the file read) when given, else (a missing matrix)
    with ``name``.
    """
    for key in ("bus", "line"):
        if key not in mats or _is_empty(mats[key]):
            raise CaseError(f"{where or name}: the data defines no '{key}' matrix")
    with _located(where) if where else nullcontext():
        return _case_of_matrices(mats, name, source, description)


def _case_of_matrices(mats: Mapping[str, Any], name: str, source: str, description: str) -> Case:
    """`case_from_matrices`'s Case, ``bus`` and ``line`` given."""
    tables: dict[str, Any] = {
        field: TABLES[field].from_matrix(mats[key])
        for key, field in PST_TABLES.items()
        if key in mats
    }
    bases = {field: _scalar(mats[key], key) for key, field in _SCALARS.items() if key in mats}
    for key, field in _SCALARS.items():
        if field not in bases:  # PST data files leave the bases to the calling script
            default = _DEFAULTS[field]
            warnings.warn(
                f"{name}: the data defines no '{key}': {field} = {default:g} "
                f"{_UNITS[field]} (PST's default)",
                UserWarning,
                stacklevel=3,
            )
    return Case(
        name=name,
        base_mva=bases.get("base_mva", _DEFAULT_BASE_MVA),
        freq_hz=bases.get("freq_hz", _DEFAULT_FREQ_HZ),
        sw_con=mats.get("sw_con"),
        extra=_extra_matrices(mats, name),
        source=source,
        description=description,
        **tables,
    )


def _extra_matrices(mats: Mapping[str, Any], name: str) -> dict:
    """The non-empty numeric matrices of :data:`EXTRA_MATRICES` among ``mats``; the
    file's other variables (neither a table, a base, ``sw_con`` nor such a matrix) are
    left out with a warning naming them."""
    others = {
        k: v
        for k, v in mats.items()
        if k not in PST_TABLES and k not in _SCALARS and k != "sw_con" and not _is_empty(v)
    }
    kept = {k: v for k, v in others.items() if k in EXTRA_MATRICES and _is_numeric(v)}
    left_out = sorted(set(others) - set(kept))
    if left_out:
        warnings.warn(
            f"{name}: variable(s) {', '.join(left_out)} left out: no PST data matrix "
            "stabctl keeps (a data file's own working variables)",
            UserWarning,
            stacklevel=4,
        )
    return kept


def _is_empty(v) -> bool:
    return np.asarray(v, dtype=object).size == 0


def _is_numeric(v) -> bool:
    try:
        arr = np.asarray(v, dtype=float)
    except (TypeError, ValueError):
        return False
    return arr.ndim <= 2


def _scalar(v, key: str) -> float:
    try:
        arr = np.asarray(v, dtype=float).ravel()
    except (TypeError, ValueError):
        raise CaseError(f"{key}: expected a number, got {_short(repr(v))}") from None
    if arr.size != 1:
        raise CaseError(f"{key}: expected a scalar, got {arr.size} values")
    return float(arr[0])


def read_pstess_json(path: str | Path, name: str | None = None, description: str = "") -> Case:
    """Read a PSTess evaluated-matrix JSON file (``shared/data/pstess/*.json`` form).

    Args:
        path: the ``.json`` file; top-level object of matrix name -> nested list.
        name: case name (default: the file stem).
        description: one line for :func:`stabctl.case.list_cases`.

    Raises :class:`CaseError` if the file is not such an object or a table is invalid.
    """
    path = Path(path)
    data = _load_json(path)
    if not isinstance(data, dict) or "bus" not in data:
        raise CaseError(f"{path}: not a PSTess matrix JSON (no 'bus' key)")
    return case_from_matrices(
        data,
        name or path.stem,
        source=f"PSTess data {path.name}",
        description=description,
        where=str(path),
    )


def read_pst_m(path: str | Path, name: str | None = None, description: str = "") -> Case:
    """Read a PST ``.m`` data file of literal matrices (see :func:`parse_m`).

    Raises :class:`CaseError` naming the line of the first statement that is not a
    literal assignment, or any invalid table.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise CaseError(f"cannot read {path}: {exc}") from None
    mats = parse_m(text, str(path))
    return case_from_matrices(
        mats,
        name or path.stem,
        source=f"PST data file {path.name}",
        description=description,
        where=str(path),
    )


def read_any(path: str | Path) -> Case:
    """Read a case file of any supported kind, told apart by suffix and content.

    ``.m`` -> :func:`read_pst_m`; ``.json`` with ``"format": "stabctl-case"`` ->
    :func:`read_case_json`, with a ``bus`` key -> :func:`read_pstess_json`. Raises
    :class:`CaseError` otherwise, pointing an ANDES JSON case (a ``Bus`` list), an ANDES
    xlsx or a PSS/E RAW file to its importer.
    """
    path = Path(path)
    if path.suffix == ".m":
        return read_pst_m(path)
    if path.suffix == ".json":
        data = _load_json(path)
        if isinstance(data, dict) and data.get("format") == FORMAT:
            return case_from_dict(data, str(path))
        if isinstance(data, dict) and "bus" in data:
            return read_pstess_json(path)
        if isinstance(data, dict) and isinstance(data.get("Bus"), list):
            raise CaseError(
                f"{path}: an ANDES JSON case (its model tables Bus, Line, ...), not a stabctl "
                f"case: convert it first with `stabctl import-andes {path} -o case.json`"
            )
        raise CaseError(f"{path}: neither a stabctl case nor a PSTess matrix JSON")
    hint = _IMPORTERS.get(path.suffix.lower(), "").format(path=path, stem=path.with_suffix(""))
    raise CaseError(f"{path}: unknown case file type (expected .json or .m){hint}")


#: a file suffix of another tool's case -> how to convert it (`read_any`'s hint)
_IMPORTERS = {
    ".raw": "; a PSS/E RAW file: convert it with its DYR, `stabctl import-psse {path} "
    "{stem}.dyr -o case.json`",
    ".xlsx": "; an ANDES xlsx case: convert it with `stabctl import-andes {path} -o case.json`",
}


def _load_json(path: Path):
    path = input_file(path, "case file", MAX_JSON_BYTES)
    try:
        # a byte-order mark (Windows editors write one) read as the start of UTF-8 text
        return parse_json(path.read_text(encoding="utf-8-sig"), str(path), CaseError)
    except OSError as exc:
        raise CaseError(f"cannot read {path}: {exc}") from None
    except RecursionError:
        raise CaseError(f"{path}: JSON nested too deeply to be a case") from None
    except UnicodeDecodeError as exc:
        raise CaseError(
            f"{path}: not UTF-8 text (byte {exc.start}: {exc.reason}), so not a JSON case"
        ) from None
    except json.JSONDecodeError as exc:
        raise CaseError(f"{path}: invalid JSON at line {exc.lineno}: {exc.msg}") from None


# --------------------------------------------------------------------------------------
# .m parser (literal matrices only)
# --------------------------------------------------------------------------------------

_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eEdD][+-]?\d+)?\Z", re.ASCII)
_ASSIGN = re.compile(r"([A-Za-z]\w*)\s*=\s*(.*)\Z", re.S)
_DISP = re.compile(r"(?:disp|fprintf)\s*\(.*\)\s*;?\s*\Z")


def _strip_comment(line: str) -> str:
    """Drop a ``%`` comment, ignoring ``%`` inside single-quoted strings."""
    quote = False
    for i, ch in enumerate(line):
        if ch == "'" and (quote or i == 0 or not (line[i - 1].isalnum() or line[i - 1] in ")]_.'")):
            quote = not quote
        elif ch == "%" and not quote:
            return line[:i]
    return line


def _logical_lines(text: str):
    """Yield (first line number, statement text) with ``...`` continuations joined.

    Newlines inside brackets are kept (they separate matrix rows), each tagged with its
    line number through a ``\\n<lineno>\\n`` marker understood by :func:`_parse_matrix`.
    """
    buf: list[str] = []
    start = 0
    depth = 0
    block = False  # inside a %{ ... %} block comment
    for lineno, raw in enumerate(text.splitlines(), start=1):
        stripped = raw.strip()
        if stripped in ("%{", "%}") or block:
            block = (stripped == "%{") or (block and stripped != "%}")
            continue
        if not buf and (stripped.startswith("%") or not stripped):
            continue
        if not buf and _DISP.match(stripped):
            continue
        line = _strip_comment(raw)
        cont = "..." in line
        if cont:
            line = line[: line.index("...")]
        if not buf:
            start = lineno
        buf.append(f"\x00{lineno}\x00{line}")
        depth += line.count("[") - line.count("]")
        if cont or depth > 0:
            if not cont:
                buf.append(";")  # a newline inside brackets ends a row
            continue
        yield start, " ".join(buf)
        buf, depth = [], 0
    if buf:
        raise CaseError(f"line {start}: unterminated matrix (missing ']')")


def parse_m(text: str, where: str = "<m-file>") -> dict[str, np.ndarray]:
    """Parse a PST data file made only of literal assignments.

    Accepted statements: ``name = [ rows ];`` (numbers separated by blanks or commas,
    rows by ``;`` or newlines, ``...`` continuations), ``name = [];``, ``name = number;``;
    ``%`` comments, ``%{ ... %}`` block comments, blank lines and ``disp(...)`` lines are
    skipped. Returns name -> 2-D
    float array (a scalar as shape (1, 1)); a later assignment replaces an earlier one.

    Raises :class:`CaseError` naming ``where`` and the line of the first statement or
    token that is not a literal (expressions such as ``22-2`` or ``PDC(1)``, variables,
    ``if``/``for``/``function``, transposes, ragged rows).
    """
    out: dict[str, np.ndarray] = {}
    for start, stmt in _logical_lines(text):
        clean = re.sub(r"\x00\d+\x00", "", stmt).strip()
        m = _ASSIGN.match(clean)
        if not m:
            raise CaseError(f"{where} line {start}: not a literal assignment: {_short(clean)}")
        name = m.group(1)
        body = stmt[stmt.index("=") + 1 :]
        out[name] = _parse_value(body, start, where, name)
    return out


def _short(s: str, n: int = 60) -> str:
    s = " ".join(s.split())
    return s if len(s) <= n else s[: n - 3] + "..."


def _parse_value(body: str, start: int, where: str, name: str) -> np.ndarray:
    """A literal scalar or ``[ ... ]`` matrix, with its trailing ``;``."""
    clean = re.sub(r"\x00\d+\x00", "", body).strip()
    clean = clean[:-1].rstrip() if clean.endswith(";") else clean
    if _NUMBER.match(clean):
        return np.array([[_to_float(clean)]])
    if not (clean.startswith("[") and clean.endswith("]")):
        raise CaseError(
            f"{where} line {start}: '{name}' is not a literal matrix or number: {_short(clean)}"
        )
    return _parse_matrix(body, start, where, name)


#: a token of a matrix body: a line mark, a row end, or a run of other characters
_TOKEN = re.compile(r"\x00\d+\x00|;|[^\x00;,\s]+")


def _parse_matrix(body: str, start: int, where: str, name: str) -> np.ndarray:
    """A ``[ ... ]`` matrix's rows, read token by token (the tokens never held at once:
    a 60 MB matrix took 2.2 GB as a list of them); each row kept as packed floats."""
    inner = body[body.index("[") + 1 : body.rindex("]")]
    rows: list[array[float]] = []
    row_lines: list[int] = []
    row: array[float] = array("d")
    lineno = start
    for match in _TOKEN.finditer(inner):
        tok = match.group()
        if tok.startswith("\x00"):
            lineno = int(tok.strip("\x00"))
        elif tok == ";":
            if row:
                rows.append(row)
                row_lines.append(lineno)
            row = array("d")
        elif _NUMBER.match(tok):
            row.append(_to_float(tok))
        else:
            hint = (
                "a number is written in ASCII digits"
                if not tok.isascii()
                else "only literal matrices are read; evaluate the file with Octave first"
            )
            raise CaseError(f"{where} line {lineno}: '{name}': '{tok}' is not a number ({hint})")
    if row:
        rows.append(row)
        row_lines.append(lineno)
    if not rows:
        return np.zeros((0, 0))
    lengths = [len(r) for r in rows]
    if len(set(lengths)) != 1:  # the row that differs from the most rows, not from row 1
        count = max(set(lengths), key=lambda n: (lengths.count(n), -lengths.index(n)))
        k = next(k for k, n in enumerate(lengths) if n != count)
        raise CaseError(
            f"{where} line {row_lines[k]}: '{name}': row {k + 1} has {lengths[k]} columns, "
            f"{lengths.count(count)} other row(s) have {count}"
        )
    return np.array([np.frombuffer(r, dtype=float) for r in rows], dtype=float)


def _to_float(tok: str) -> float:
    return plain_float(tok, fortran=True)


# --------------------------------------------------------------------------------------
# stabctl's own JSON format
# --------------------------------------------------------------------------------------

_LICENCE_DEFAULT = ""


#: tables written only when they have rows (a case without converters, shafts, motors,
#: compensators, switched shunts or remote regulation is written as before those tables
#: existed)
_OPTIONAL_TABLES = (
    "converters",
    "shafts",
    "motors",
    "svcs",
    "switched_shunts",
    "remote_regulation",
)


def case_to_dict(case: Case, licence: str = "") -> dict:
    """The own-format dict of a case (see :func:`write_case_json` for the layout)."""
    tables = {
        field: {"columns": list(cls.columns()), "rows": getattr(case, field).matrix().tolist()}
        for field, cls in TABLES.items()
        if field not in _OPTIONAL_TABLES or len(getattr(case, field))
    }
    return {
        "format": FORMAT,
        "version": FORMAT_VERSION,
        "name": case.name,
        "description": case.description,
        "source": case.source,
        "licence": licence,
        "base_mva": case.base_mva,
        "freq_hz": case.freq_hz,
        "tables": tables,
        "sw_con": None if case.sw_con is None else case.sw_con.tolist(),
        **({"events": [dict(e) for e in case.events]} if case.events else {}),
        "extra": {k: v.tolist() for k, v in case.extra.items()},
        **(
            {"machine_ids": {str(k): v for k, v in case.machine_ids.items()}}
            if case.machine_ids
            else {}
        ),
    }


#: the own format's scalar keys, written first in this order (`write_case_json`)
_HEAD_KEYS = (
    "format",
    "version",
    "name",
    "description",
    "source",
    "licence",
    "base_mva",
    "freq_hz",
)
#: every top-level key of the own format
_CASE_KEYS = frozenset((*_HEAD_KEYS, "tables", "sw_con", "events", "extra", "machine_ids"))


def case_from_dict(data: Mapping, where: str = "<dict>") -> Case:
    """A Case from the own-format dict.

    Each table gives at least the columns a PST matrix must (its first ``MIN_COLUMNS``);
    a later column left out takes its default (``DEFAULTS``, else 0) with a warning naming
    it.

    Parameters
    ----------
    data : Mapping
        The parsed case file (:func:`write_case_json`'s layout).
    where : str, optional
        The file, named first in every error.

    Returns
    -------
    Case

    Raises
    ------
    CaseError
        A wrong format or version; an unknown top-level key, table, table key, column or
        ``extra`` matrix (not in :data:`EXTRA_MATRICES`); a column the model needs left
        out; invalid data (the file, table, row and field named; a PSS on a machine without
        exciter, `Case.check_stabilisers`); an event of the case's
        own that names a bus, line, machine or motor the case lacks (the file, the record,
        the event and what is missing named; UnknownBusError for a bus).
    """
    if data.get("format") != FORMAT:
        raise CaseError(f"{where}: not a stabctl case (format is {data.get('format')!r})")
    if data.get("version") != FORMAT_VERSION:
        raise CaseError(
            f"{where}: case format version {data.get('version')!r} not supported "
            f"(this stabctl reads version {FORMAT_VERSION})"
        )
    unknown_keys = set(data) - _CASE_KEYS
    if unknown_keys:
        raise CaseError(
            f"{where}: unknown key(s) {sorted(unknown_keys)} (a case holds "
            f"{', '.join(sorted(_CASE_KEYS))}; nothing else is read)"
        )
    for key in ("name", "description", "source", "licence"):
        if key in data and not isinstance(data[key], str):
            raise CaseError(f"{where}: '{key}' must be text, got {data[key]!r}")
    raw_tables = data.get("tables")
    if not isinstance(raw_tables, Mapping):
        raise CaseError(
            f"{where}: no 'tables' object (the case's tables by name: "
            f"{', '.join(TABLES)}; at least buses and branches)"
        )
    unknown = set(raw_tables) - set(TABLES)
    if unknown:
        raise CaseError(f"{where}: unknown table(s) {sorted(unknown)}; known: {list(TABLES)}")
    for required in ("buses", "branches"):
        if required not in raw_tables:
            raise CaseError(f"{where}: tables: no '{required}' table")
    with tables_named(_FILE_TABLES):  # errors name the tables as the file does
        return _case_of_dict(data, raw_tables, where)


#: PST table name -> the own format's name of it (a `Case` field), as its errors name it
_FILE_TABLES: Mapping[str, str] = {cls.TABLE: field for field, cls in TABLES.items()}


def _case_of_dict(data: Mapping, raw_tables: Mapping, where: str) -> Case:
    """`case_from_dict`'s Case, its header and table names checked."""
    tables = {
        field: _table_from_json(field, raw_tables[field], where)
        for field in TABLES
        if field in raw_tables
    }
    extra = _extra_field(data.get("extra"), where)
    events = _events_field(data.get("events"), where)
    machine_ids = _machine_ids_field(data.get("machine_ids"), where)
    with _located(where):
        case = Case(
            name=str(data.get("name", Path(where).stem)),
            base_mva=_field_number(data, "base_mva", where),
            freq_hz=_field_number(data, "freq_hz", where),
            sw_con=data.get("sw_con"),
            events=events,
            extra=extra,
            machine_ids=machine_ids,
            source=str(data.get("source", "")),
            description=str(data.get("description", "")),
            **tables,
        )
        check_case_events(case)  # a stored event of a bus or line the case lacks
        case.check_stabilisers()  # what a run refuses, refused naming the file
    return case


@contextmanager
def _located(where: str) -> Iterator[None]:
    """A CaseError raised inside, its message prefixed with the file ``where``."""
    try:
        yield
    except CaseError as exc:
        raise exc.relocated(f"{where}: {exc}") from None


def _extra_field(extra, where: str) -> Mapping:
    """The ``extra`` matrices of a case file: numeric matrices named in
    :data:`EXTRA_MATRICES` (absent: none)."""
    extra = extra or {}
    if not isinstance(extra, Mapping):
        raise CaseError(f"{where}: 'extra' must be an object of matrices by name")
    for key, value in extra.items():
        if key not in EXTRA_MATRICES:
            raise CaseError(
                f"{where}: extra: unknown matrix '{key}' (extra keeps PST data matrices "
                f"stabctl does not model: {', '.join(sorted(EXTRA_MATRICES))})"
            )
        if not _is_numeric(value):
            raise CaseError(f"{where}: extra matrix '{key}' is not a numeric matrix")
    return extra


def _machine_ids_field(ids, where: str) -> dict[int, str]:
    """The ``machine_ids`` of a case file: an object of machine number (text of a positive
    integer) -> ID (text), or absent (none); the IDs themselves are checked by `Case`."""
    if ids is None:
        return {}
    if not isinstance(ids, Mapping):
        raise CaseError(f"{where}: 'machine_ids' must be an object of machine number -> ID")
    out = {}
    for key, ident in ids.items():
        number = plain_integer(key, 9) if isinstance(key, str) and key.isdigit() else None
        if number is None or number <= 0:
            raise CaseError(f"{where}: machine_ids: {shown_field(str(key))!r} is no machine number")
        if not isinstance(ident, str):
            raise CaseError(f"{where}: machine_ids: machine {key}: ID {ident!r} is no text")
        out[number] = ident
    return out


def _field_number(data: Mapping, key: str, where: str) -> float:
    """A required positive finite number of the own format (base_mva, freq_hz): no silent
    default."""
    what = {"base_mva": "system base, MVA", "freq_hz": "nominal frequency, Hz"}[key]
    if key not in data:
        raise CaseError(f"{where}: no '{key}' ({what}, a number > 0)")
    value = data[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise CaseError(f"{where}: '{key}' must be a number > 0 ({what}), got {value!r}")
    return float(value)


#: the keys of a table of the own format
_TABLE_KEYS = ("columns", "rows")


def _table_from_json(field: str, raw: Mapping, where: str):
    """Table ``field`` of a case file (``raw``: its ``columns`` and ``rows``), every error
    naming the file ``where`` and the table as the file names it."""
    cls = TABLES[field]
    if not isinstance(raw, Mapping):
        raise CaseError(f"{where}: table '{field}' must be an object with 'columns' and 'rows'")
    unknown = sorted(set(raw) - set(_TABLE_KEYS))
    if unknown:
        raise CaseError(
            f"{where}: table '{field}' has unknown key(s) {unknown} (a table holds "
            "'columns' and 'rows'; nothing else is read)"
        )
    cols = raw.get("columns")
    rows = raw.get("rows", [])
    if not isinstance(cols, list) or not all(isinstance(c, str) for c in cols):
        raise CaseError(f"{where}: table '{field}' has no 'columns' list of names")
    twice = sorted({c for c in cols if cols.count(c) > 1}, key=cols.index)
    if twice:
        places = "; ".join(
            f"'{c}' at positions {', '.join(str(k + 1) for k, n in enumerate(cols) if n == c)}"
            for c in twice
        )
        raise CaseError(f"{where}: table '{field}' names a column twice in its 'columns': {places}")
    if not isinstance(rows, list) or not all(isinstance(r, list) for r in rows):
        raise CaseError(f"{where}: table '{field}': 'rows' must be a list of rows")
    known = cls.columns()
    bad = [c for c in cols if c not in known]
    if bad:
        raise CaseError(
            f"{where}: table '{field}' has unknown column(s) {bad}; known: {list(known)}"
        )
    _check_numbers(rows, cols, f"{where}: table '{field}'")
    for i, row in enumerate(rows, start=1):  # each row against the columns named
        if len(row) != len(cols):
            raise CaseError(
                f"{where}: table '{field}' row {i}: {len(row)} value(s), the table "
                f"names {len(cols)} columns (wrong column count)"
            )
    from stabctl.case.system import _as_matrix

    mat = _as_matrix(rows, f"{where}: table '{field}'")
    if mat.shape[0] == 0:
        return cls.empty()
    n = mat.shape[0]
    _check_missing(cls, field, cols, where)
    data = {
        c: mat[:, cols.index(c)] if c in cols else np.full(n, float(cls.DEFAULTS.get(c, 0.0)))
        for c in known
    }
    with _located(where):
        return cls(**data)


def _check_missing(cls, field: str, cols: list, where: str) -> None:
    """CaseError naming the columns of ``cls`` among its first ``MIN_COLUMNS`` (those a
    PST matrix must give: no default) that ``cols`` leaves out; a warning naming the
    later ones it leaves out, which take their documented defaults (``DEFAULTS``, else
    0)."""
    known = cls.columns()
    missing = [c for c in known if c not in cols]
    needed = [c for c in missing if known.index(c) < cls.MIN_COLUMNS]
    if needed:
        raise CaseError(
            f"{where}: table '{field}' has no column(s) {needed}: the model needs its "
            f"first {cls.MIN_COLUMNS} columns ({known[0]} to {known[cls.MIN_COLUMNS - 1]}); "
            "only later ones have defaults"
        )
    if missing:
        by_value: dict[float, list[str]] = {}
        for c in missing:
            by_value.setdefault(float(cls.DEFAULTS.get(c, 0.0)), []).append(c)
        taken = "; ".join(f"{', '.join(c)} = {v:g}" for v, c in by_value.items())
        warnings.warn(
            f"{where}: table '{field}' gives no column(s) {', '.join(missing)}: taken "
            f"at their defaults ({taken})",
            UserWarning,
            stacklevel=5,
        )


def _check_numbers(rows: list, cols: list, where: str) -> None:
    """CaseError naming the row and column of the first value that is not a JSON number
    (``true`` is not 1, ``"1"`` is not 1, ``null`` is no value)."""
    for i, row in enumerate(rows, start=1):
        for k, v in enumerate(row):
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                col = cols[k] if k < len(cols) else f"value {k + 1}"
                raise CaseError(f"{where} row {i}, column '{col}': {json.dumps(v)} is not a number")


def _dump_matrix(rows: list, indent: str) -> str:
    """One JSON row per line, integers without a decimal point."""
    if not rows:
        return "[]"
    lines = [indent + "  " + json.dumps([_num(v) for v in r]) for r in rows]
    return "[\n" + ",\n".join(lines) + "\n" + indent + "]"


def _num(v: float):
    v = float(v)
    return int(v) if v.is_integer() and abs(v) < 2**53 else v


def write_case_json(case: Case, path: str | Path, licence: str = "") -> Path:
    """Write ``case`` in stabctl's own JSON format; returns the path.

    Layout: ``format`` ("stabctl-case"), ``version`` (1), ``name``, ``description``,
    ``source``, ``licence``, ``base_mva`` (MVA), ``freq_hz`` (Hz), ``tables`` (table field
    -> ``{"columns": [names in PST order], "rows": [[...], ...]}``, one row per line),
    ``sw_con`` (PST rows or null), ``events`` (the case's own disturbance records, one
    per line; only when it has some), ``extra`` (name -> rows), ``machine_ids``
    (machine number -> ID; only when the case has some).  Floats are written with
    Python's shortest round-trip repr, so reading gives back identical values.
    """
    d = case_to_dict(case, licence)
    head = {k: d[k] for k in _HEAD_KEYS}
    parts = ["{"]
    for k, v in head.items():
        parts.append(f"  {json.dumps(k)}: {json.dumps(v)},")
    parts.append('  "tables": {')
    tparts = []
    for field, t in d["tables"].items():
        tparts.append(
            f'    {json.dumps(field)}: {{\n      "columns": {json.dumps(t["columns"])},\n'
            f'      "rows": {_dump_matrix(t["rows"], "      ")}\n    }}'
        )
    parts.append(",\n".join(tparts))
    parts.append("  },")
    sw = "null" if d["sw_con"] is None else _dump_matrix(d["sw_con"], "  ")
    parts.append(f'  "sw_con": {sw},')
    if "events" in d:
        ev = ",\n".join(f"    {json.dumps(e)}" for e in d["events"])
        parts.append(f'  "events": [\n{ev}\n  ],')
    eparts = [f"    {json.dumps(k)}: {_dump_matrix(v, '    ')}" for k, v in d["extra"].items()]
    ids = f',\n  "machine_ids": {json.dumps(d["machine_ids"])}' if "machine_ids" in d else ""
    parts.append(
        '  "extra": {' + ("\n" + ",\n".join(eparts) + "\n  " if eparts else "") + "}" + ids
    )
    parts.append("}")
    path = Path(path)
    path.write_text("\n".join(parts) + "\n", encoding="utf-8")
    return path


def _events_field(events, where: str) -> tuple:
    """The ``events`` of a case file: a list of records (objects), or absent."""
    if events is None:
        return ()
    if not isinstance(events, list):
        raise CaseError(f"{where}: 'events' must be a list of event records")
    return tuple(events)


def read_case_json(path: str | Path) -> Case:
    """Read a case in stabctl's own JSON format. Raises :class:`CaseError` if invalid."""
    path = Path(path)
    return case_from_dict(_load_json(path), str(path))


def read_case_header(path: str | Path) -> dict:
    """The scalar header of an own-format case file (name, description, source, ...)."""
    data = _load_json(Path(path))
    return {
        k: v
        for k, v in data.items()
        if k not in ("tables", "sw_con", "events", "extra", "machine_ids")
    }
