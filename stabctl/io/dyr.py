"""PSS/E dynamic data (.dyr) to PST tables: machines, exciters, PSS and governors.

`read_dyr` parses the records of a DYR file; `dyr_tables` maps them, per generator of the
RAW file, to the PST matrices `mac_con`, `exc_con`, `pss_con`, `tg_con` that
`stabctl.case` accepts (MachineTable, ExciterTable, PssTable, GovernorTable).

Record syntax (PSS/E Program Operation Manual, "Dynamics Data File"): ``IBUS 'MODEL' ID
CON(J) ... CON(J+n) /`` over one or more lines, fields separated by blanks or commas;
ICONs of IEEEG1 (JBUS, M), IEEEST (ICS, IB), PSS1A (ICS) and ST2CUT (MODE, BUSR,
MODE2, BUSR2) come first among the numbers.  Parameter
order per model (PSS/E Model Library, as ANDES `andes/io/psse-dyr.yaml`) and the table
field each parameter is copied to are declared once, with the table columns, in the
model modules (`stabctl.models.declaration.DyrModel`); the mappers here only compute
what is not a copy
(unit changes, products, saturation fits, the PSS type).  Mapping and the known
modelling differences: docs/pst_models.md section 12.  The converter records (REGCA1 and
its controls, DERA1) are parsed here (`CONVERTER_DYR`) and mapped by
:mod:`stabctl.io.dyr_converters`.

Units: machine, exciter and governor data on the machine base `mbase` (MVA), as PSS/E.
"""

from __future__ import annotations

import math
import re
import warnings
from collections.abc import Mapping
from contextvars import ContextVar
from dataclasses import dataclass
from dataclasses import field as _field
from typing import NamedTuple

import numpy as np

from stabctl.errors import CaseError, advice
from stabctl.io.inputs import case_text, input_file, plain_float, plain_integer, shown_field
from stabctl.io.provenance import Origin, Written
from stabctl.models.converters import CONVERTER
from stabctl.models.declaration import DyrModel, Family
from stabctl.models.exciters import EXCITER, ac8b
from stabctl.models.exciters.dc import VRMAX_NO_LIMIT
from stabctl.models.governors import GOVERNOR
from stabctl.models.machines import MACHINE
from stabctl.models.pss import PSS
from stabctl.models.svcs import DYR as SVC_RECORDS
from stabctl.models.svcs import SVC

_TOKEN = re.compile(r"'[^']*'|/|[^\s,/']+")
#: the fields a record may have (bus, model, id and its parameters): PSS/E's largest
#: models have a few hundred (CMLDBLU2 about 130 CONs); a record of 10 million zeros was
#: held whole, some 900 MB, before its count was refused
MAX_RECORD_FIELDS = 2000
#: the line ends of `str.splitlines`, for reading a file's lines one at a time (a list of
#: ten million lines of one number each took about 1 GB)
_ENDS = "\n\r\x0b\x0c\x1c\x1d\x1e\x85\u2028\u2029"
_LINE = re.compile(f"[^{_ENDS}]*(?:\r\n|[{_ENDS}]|\\Z)")
#: table kind -> the declaration of its columns and DYR models (stabctl.models)
FAMILY: dict[str, Family] = {
    "machine": MACHINE,
    "exciter": EXCITER,
    "pss": PSS,
    "governor": GOVERNOR,
}
#: DYR model -> its declaration (parameter names and order, fields copied to the table)
DYR_MODELS: dict[str, DyrModel] = {m.name: m for f in FAMILY.values() for m in f.dyr}
#: DYR converter record -> its declaration (the converter table's, ibr_con; mapped by
#: `stabctl.io.dyr_converters`)
CONVERTER_DYR: dict[str, DyrModel] = {m.name: m for m in CONVERTER.dyr}
#: DYR compensator record -> its declaration (the compensator table's, svc_con;
#: `compensator_rows`)
SVC_DYR: dict[str, DyrModel] = {m.name: m for m in SVC_RECORDS}
#: numbers after the id per model (PSS/E Model Library: ICONs, then CONs)
N_PARAMS = {name: len(m.fields) for name, m in (DYR_MODELS | CONVERTER_DYR | SVC_DYR).items()}
#: the fields of a record that are strings (a branch's circuit id): NaN among the numbers,
#: the text kept in `DyrRecord.text`
TEXT_FIELDS = {"REPCA1": ("CKTID",)}


@dataclass(frozen=True)
class DyrRecord:
    """One DYR record: file and 1-based line where it starts, bus number, model name
    (upper case), machine id (quotes and blanks stripped, upper case), the numbers after
    the id (ICONs then CONs; NaN for a non-number of a model stabctl does not map, and
    for a string field of `TEXT_FIELDS`), and those string fields' text (quotes and
    blanks stripped, upper case), in order."""

    file: str
    line: int
    bus: int
    model: str
    id: str
    params: tuple[float, ...]
    text: tuple[str, ...] = ()

    def where(self) -> str:
        return f"{self.file}:{self.line}"

    def label(self) -> str:
        return f"{self.where()} {self.model} (bus {self.bus}, id {self.id})"


@dataclass(frozen=True)
class DyrTables:
    """PST matrices built from DYR records, rows in machine order, columns as the case
    tables (MachineTable, ExciterTable, PssTable, GovernorTable): mac_con (n_gen, 24),
    exc_con (n, 24), pss_con (n, 24), tg_con (n, 24) (None when no record of that kind);
    unsupported: the records skipped (`on_unsupported="skip"`), in file order; why: the
    reason each was skipped (same order), e.g. "model TOGGLE is not mapped"; changed: the
    records read with a value other than the file's, ``"file:line MODEL (bus B, id I):
    what"`` (a DC exciter's VRMAX = 0 computed as PSS/E computes it, or read as no upper
    limit with conventions "andes" and "pst"; with conventions="andes" an SCRX read as
    ANDES's SEXS with its defaults, and a model ANDES 2.0 lacks read as PSS/E's)."""

    mac_con: np.ndarray
    exc_con: np.ndarray | None
    pss_con: np.ndarray | None
    tg_con: np.ndarray | None
    unsupported: tuple[DyrRecord, ...]
    why: tuple[str, ...] = ()
    changed: tuple[str, ...] = ()
    #: table name ("mac_con", "exc_con", "pss_con", "tg_con") -> the record of each row
    records: Mapping[str, tuple[DyrRecord, ...]] = _field(default_factory=dict)


class _Unsupported(Exception):
    """A record of a model (or model option) stabctl does not represent."""


#: why a record of no generator is left out (`no_generator`)
NO_GENERATOR = "matches no generator in service of the RAW data"


def no_generator(rec: DyrRecord, gens: Mapping) -> str:
    """Why ``rec`` is left out: its (bus, id) is none of ``gens``', with the ids of the
    generators at its bus (a machine's, a converter's or a compensator's record alike).

    Parameters
    ----------
    rec : DyrRecord
        The record.
    gens : Mapping
        ``(bus, id) -> generator`` of the RAW's generators in service.

    Returns
    -------
    str
        `NO_GENERATOR` and where: ``(bus 3's: id '1', '2')`` or ``(none at bus 999)``.
    """
    ids = [f"'{gid}'" for bus, gid in gens if bus == rec.bus]
    at = f"bus {rec.bus}'s: id {', '.join(ids)}" if ids else f"none at bus {rec.bus}"
    return f"{NO_GENERATOR} ({at})"


class UnmodelledError(CaseError):
    """Generators without a (readable) machine model record: `dyr_tables` refuses them;
    ``unreadable``: some have a record of a model stabctl cannot read (the caller may
    advise how to net them or leave those records out)."""

    unreadable: bool = False


#: the records read with a value other than the file's, while `dyr_tables` maps them
_CHANGED: ContextVar[list[str]] = ContextVar("_CHANGED")


def _read_as(rec, what: str) -> None:
    """Name record ``rec`` as read with a value other than its file's (``what``) in the
    `DyrTables.changed` of the `dyr_tables` call mapping it."""
    _CHANGED.get().append(f"{rec.label()}: {what}")


# -- parsing ----------------------------------------------------------------------------------


def read_dyr(path) -> list[DyrRecord]:
    """Records of a PSS/E DYR file, in file order.

    Args:
        path: the .dyr file.
    Returns:
        list of DyrRecord.
    Raises:
        CaseError "{file}:{line}: ..." for an unreadable file, a quote not closed, a record
        not ended by '/' or without a quoted model name after the bus, a record after
        another's '/' on one line (a comment in PSS/E, so never read), and, for the models
        stabctl maps, a non-integer bus or a parameter that is not a number (other models'
        records are kept, with bus 0 and NaN parameters there, for the unsupported report);
        "{file}: ..." for a file without any record (empty, or comments only).
    """
    path = input_file(path, "DYR file")
    try:
        text = case_text(path, "DYR file")
    except OSError as exc:
        raise CaseError(f"{path}: cannot read DYR file: {exc.strerror or exc}") from None
    records: list = []
    tokens: list = []
    start = 0
    for n, line in enumerate(_lines(text), 1):
        col = _stray_quote(line)
        if col is not None:  # the tokens skip it: 'GENROU read as GENROU, unnamed
            raise CaseError(  # a comment whose record lacks its '/' is read as data
                f"{path.name}:{n}: the quote ' at column {col + 1} is not closed: "
                f"{line.strip()[:72]!r}; if it is in a comment, the record before it is "
                "not terminated by '/' (what follows a record's '/' is a comment)"
            )
        for m in _TOKEN.finditer(line):
            tok = m.group()
            if tok == "/":
                if tokens:
                    records.append(_record(path.name, start, tokens))
                tokens = []
                _refuse_record_in_comment(path.name, n, line[m.end() :])
                break  # the rest of the line after '/' is a comment
            if not tokens:
                start = n
            tokens.append(tok)
            if len(tokens) > MAX_RECORD_FIELDS:
                raise CaseError(
                    f"{path.name}:{start}: record {' '.join(tokens[:3])[:60]} ... has more "
                    f"than {MAX_RECORD_FIELDS} fields by line {n}, more than any PSS/E model "
                    "takes: its '/' is missing, or the file is no DYR file"
                )
    if tokens:
        raise CaseError(f"{path.name}:{start}: record not terminated by '/'")
    if not records:  # a DYR file given gives the dynamic models: none is a wrong file
        what = "is empty" if not text.strip() else "holds no record, only comments"
        raise CaseError(
            f"{path.name}: the DYR file {what}: no machine, exciter or governor model "
            "(records IBUS 'MODEL' ID ... /), every generator would be without a machine "
            "model; give the case's DYR file, or none for a power-flow case"
        )
    return records


def _lines(text: str):
    """The lines of `text` as ``text.splitlines()`` gives them, one at a time."""
    for m in _LINE.finditer(text):
        if m.start() == len(text):
            return
        yield m.group().rstrip(_ENDS)


def _stray_quote(line: str) -> int | None:
    """The 0-based column of a quote of a DYR line's data (before its '/' comment) that
    opens no closed string, None if every quote does."""
    quoted, end = [], len(line)
    for m in _TOKEN.finditer(line):
        if m.group() == "/":
            end = m.start()
            break
        if m.group()[0] == "'":
            quoted.append(m.span())
    for i in (i for i, ch in enumerate(line[:end]) if ch == "'"):
        if not any(a <= i < b for a, b in quoted):
            return i
    return None


#: a DYR record's start: a bus number and a quoted model name
_RECORD_START = re.compile(r"^\s*-?\d+\s*,?\s*'[^']+'")


def _refuse_record_in_comment(file: str, n: int, rest: str) -> None:
    """CaseError when ``rest``, what follows a record's '/' on line n (a comment, as in
    PSS/E), looks like a record: it would not be read."""
    if _RECORD_START.match(rest):
        raise CaseError(
            f"{file}:{n}: '{' '.join(rest.split())[:40]}' after '/' would be a comment "
            "(PSS/E reads one record up to '/'): put each record on its own line"
        )


def _record(file: str, line: int, tokens: list[str]) -> DyrRecord:
    if len(tokens) < 3 or not tokens[1].startswith("'"):
        raise CaseError(
            f"{file}:{line}: malformed record {' '.join(tokens)[:60]!r}: expected "
            "IBUS 'MODEL' ID parameters /"
        )
    model = tokens[1].strip("'").strip().upper()
    bus = _integer(tokens[0])
    written = shown_field(tokens[0])
    label = f"{file}:{line} {model} (bus {written}, id {machine_id(tokens[2])})"
    if bus is None or bus <= 0:
        if model in N_PARAMS:
            raise CaseError(
                f"{label}: "
                + (
                    f"IBUS = {written!r}: not an integer (ASCII digits, no '_'; a bus "
                    f"number has at most {BUS_DIGITS})"
                    if bus is None
                    else f"IBUS = {written}: a bus number must be a positive integer"
                )
            )
        bus = 0
    params, text = [], []
    strings = [_field_number(model, name) for name in TEXT_FIELDS.get(model, ())]
    for k, tok in enumerate(tokens[3:], 1):
        if k in strings:
            if not tok.startswith("'"):
                raise CaseError(f"{label}: {_param_name(model, k)} = {tok}: not a quoted id")
            params.append(float("nan"))
            text.append(machine_id(tok))
            continue
        try:
            value = plain_float(tok, fortran=True)
        except ValueError:
            if model in N_PARAMS:
                raise CaseError(
                    f"{label}: {_param_name(model, k)} = {tok!r}: not a number (ASCII "
                    "digits, no '_')"
                ) from None
            value = float("nan")  # e.g. USRMDL's quoted names: reported unsupported
        else:
            if model in N_PARAMS and not math.isfinite(value):
                raise CaseError(f"{label}: {_param_name(model, k)} = {tok}: not a finite number")
        params.append(Written(value, tok) if math.isfinite(value) else value)
    return DyrRecord(file, line, bus, model, machine_id(tokens[2]), tuple(params), tuple(text))


def _param_name(model: str, k: int) -> str:
    """The name of parameter ``k`` (1-based, after the id) of a record of ``model`` as
    the PSS/E Model Library writes it (``X''d``, ``TA/TB``), else ``parameter k``
    (beyond the model's count: refused later by its count)."""
    fields = (DYR_MODELS | CONVERTER_DYR | SVC_DYR)[model].fields
    return _SHOWN.get(fields[k - 1], fields[k - 1]) if k <= len(fields) else f"parameter {k}"


def _field_number(model: str, name: str) -> int:
    """1-based position of field ``name`` among ``model``'s numbers after the id."""
    return CONVERTER_DYR[model].fields.index(name) + 1


def machine_id(tok) -> str:
    """Machine id as compared between RAW and DYR: quotes and blanks stripped, upper case."""
    return str(tok).strip().strip("'").strip().upper()


#: PSS/E generator models (a machine or a converter: what makes a RAW generator dynamic),
#: mapped or not (PSS/E Model Library, "Generator Models" and "Renewable Generator Models")
_SOURCE_MODELS = frozenset(
    [
        "GENCLS",
        "GENROU",
        "GENSAL",
        "GENROE",
        "GENSAE",
        "GENTPJ1",
        "GENTPF",
        "GENQEC",
        "GENDCO",
        "CGEN1",
        "CIMTR1",
        "CIMTR2",
        "CIMTR3",
        "CIMTR4",
        "CSVGN1",
        "CSVGN3",
        "CSVGN4",
        "CSVGN5",
        "CSVGN6",
        "CSTCNT",
        "CSTATT",
        "FRECHG",
        "REGCA1",
        "REGCAU1",
        "REGCB1",
        "REGCC1",
        "REGFM_A1",
        "REGFM_B1",
        "WT1G1",
        "WT2G1",
        "WT3G1",
        "WT3G2",
        "WT4G1",
        "WT4G2",
        "PVGU1",
        "DERA1",
        "DERAU1",
        "PVD1",
    ]
)


def has_machine_model(rec: DyrRecord) -> bool:
    """Whether ``rec`` gives its generator a dynamic source model (a machine or a
    converter, mapped by stabctl or not): a generator without one is what PSS/E nets."""
    return rec.model in _SOURCE_MODELS or maps_machine(rec)


def is_control(rec: DyrRecord) -> bool:
    """Whether ``rec`` is a machine's control stabctl maps (an exciter, stabiliser,
    governor or load compensator): one that leaves with its generator."""
    return _KIND.get(rec.model) in ("exciter", "pss", "governor") or rec.model in COMPENSATORS


def maps_machine(rec: DyrRecord) -> bool:
    """Whether ``rec`` is a machine record stabctl maps (a ``mac_con`` row)."""
    return _KIND.get(rec.model) == "machine"


#: why a generator model stabctl lacks is left out (its generator has no machine then)
SOURCE_UNSUPPORTED = "generator model not supported by stabctl (yet)"


#: the most digits of a bus number (PSS/E's are 1-999997)
BUS_DIGITS = 6


def _integer(tok: str) -> int | None:
    """An integer field as PSS/E reads one: digits with an optional sign ("103.0" and
    "1.03E2" are errors to it, as the RAW reader's `stabctl.io.psse_raw` refuses them;
    round 46: a DYR's were read as bus 103), of at most `BUS_DIGITS` digits."""
    return plain_integer(tok.strip("'").strip(), BUS_DIGITS)


# -- mapping ------------------------------------------------------------------------------------


def dyr_tables(
    records, generators, on_unsupported: str = "error", conventions: str = "psse", strays=()
) -> DyrTables:
    """PST matrices for the generators of a RAW file from their DYR records.

    Args:
        records: DyrRecord sequence (`read_dyr`).
        generators: sequence of dicts in RAW order, keys "number" (1-based machine number,
            the row of mac_con), "bus", "id", "mbase" (MVA), "ra", "xsource" (ZSORCE on
            mbase, pu); optional "pg", "qg" (MW, Mvar) to split a bus's generation among
            several machines (mac_con columns 22, 23), "pfrac", "qfrac" (a machine's share
            of its bus's generation when converters take the rest, given for each machine
            of the bus; default 1),
            "sbase" (system base, MVA, default 100; used by conventions="andes").
        on_unsupported: "error" (raise, listing every unsupported record) or "skip" (leave
            those records out and return them in `unsupported`).
        strays: (record, why) of source records read elsewhere (converters,
            compensators) and left out: those of no generator (`no_generator`) are named
            with the generators without a machine model, as the likely cause (a REGCA1
            at a bus of no generator beside a generator without a record).
        conventions: "psse" (the PSS/E Model Library's machines, `_PSSE_MACHINE`: stator
            at rated speed, P_m and D divided by speed, each model's saturation; the
            controls of `_PSSE_MAPPERS` as PSS/E solves them, e.g. EXST1's output
            limits and rate feedback, the DC exciters' quadratic saturation; the other
            models as "pst"), "pst" (PST's models
            as they are: machines with speed effects and without saturation) or
            "andes" (ANDES 2.0's reading of the PSS/E models, for like-for-like
            comparisons: GENROU/GENSAL without speed
            effects, mac_con column 24 = 0, and with PSS/E's saturation of the air-gap flux
            through S(1.0), S(1.2) (column 25 = 1; ANDES ``genrou.py``); EXDC2's regulator
            limits not scaled by the terminal voltage, i.e. PST's DC1 instead of DC2, and
            IEEEX1's neither (DC1: its ``ieeex1.py`` computes VRMAX v but its limiter keeps
            VRMAX, see `_ANDES_MAPPERS`); DC exciters with PSS/E's quadratic saturation and K_E as
            given; ESST3A's source voltage from system-base currents (K_I, X_L times
            MBASE/SBASE) and its I_N from the machine's field current (exc_con column 25 =
            1); IEEEG1's gate rate limits
            Uo, Uc read on the system base, i.e. times SBASE/MBASE on the machine base).
    Returns:
        DyrTables.
    Raises:
        CaseError naming file:line, model and (bus, id): wrong parameter count, a value the
        model cannot take (R = 0, H = 0, ...), two records of one kind for a generator, a
        generator without machine model, or (on_unsupported="error") unsupported records:
        models or options not mapped, records for a generator not among `generators`.
    """
    if on_unsupported not in ("error", "skip"):
        raise CaseError(f"on_unsupported must be 'error' or 'skip', got {on_unsupported!r}")
    if conventions not in CONVENTIONS:
        raise CaseError(f"conventions must be one of {CONVENTIONS}, got {conventions!r}")
    token = _CHANGED.set([])
    try:
        rows, skipped = _map_records(records, generators, conventions)
        changed = tuple(_CHANGED.get())
    finally:
        _CHANGED.reset(token)
    if skipped and on_unsupported == "error":
        raise CaseError(
            "unsupported DYR records ("
            + advice("on_unsupported='skip' leaves", "--skip-unsupported leaves")
            + " them out):\n"
            + "\n".join(f"  {r.label()}: {why}" for r, why in skipped)
        )
    _check_machines(generators, rows["machine"], [*skipped, *strays], records)
    _set_fractions(generators, rows["machine"])
    tables = {k: _matrix(rows[k], width) for k, width in _WIDTH.items()}
    return DyrTables(
        mac_con=tables["machine"],  # type: ignore[arg-type]  # None: no machine
        exc_con=tables["exciter"],
        pss_con=tables["pss"],
        tg_con=tables["governor"],
        unsupported=tuple(r for r, _ in skipped),
        why=tuple(why for _, why in skipped),
        changed=changed,
        records={FAMILY[k].table: tuple(rows[k][n][0] for n in sorted(rows[k])) for k in FAMILY},
    )


#: the DYR fields written as PSS/E's DYR documentation names them, where the declaration
#: spells them otherwise (STAB1's ratios)
_SHOWN = {"K_T": "K/T", "T1_T3": "T1/T3", "T2_T4": "T2/T4"}
#: table field -> the DYR fields it is computed from, per model, for the columns a mapper
#: computes rather than copies (`dyr_origin`; the mappers below)
_DERIVED: dict[str, dict[str, tuple[str, ...]]] = {
    "GENROU": {"xqpp": ("X''d",)},
    "GENROE": {"xqpp": ("X''d",)},
    "GENSAL": {"xqp": ("Xq",), "xqpp": ("X''d",)},
    "GENSAE": {"xqp": ("Xq",), "xqpp": ("X''d",)},
    "SEXS": {"TC": ("TA/TB", "TB")},
    "SCRX": {"TC": ("TA/TB", "TB"), "bus_fed": ("CSWITCH",)},
    **{
        dc: dict.fromkeys(("E1", "SE1", "E2", "SE2"), ("E1", "SE(E1)", "E2", "SE(E2)"))
        for dc in ("IEEEX1", "EXDC2", "ESDC1A", "ESDC2A", "IEEET1", "IEEET2")
    },
    "ESST3A": {"Efdmax": ("VBMAX", "VMMAX")},
    "IEEEST": {
        "type": ("ICS",),
        "input1": ("ICS",),
        "KTw": ("KS", "T5"),
        **{t: (t,) for t in ("T1", "T2", "T3", "T4")},
        **{f"A{k}": (f"A{k}",) for k in range(1, 7)},
    },
    "PSS1A": {"KTw": ("KS", "T5")},
    "STAB2A": {"KTw": ("K2", "T2"), "ymin": ("HLIM",)},
    "STAB1": {
        "KTw": ("K_T", "T"),
        "T1": ("T1_T3", "T3"),
        "T3": ("T2_T4", "T4"),
        "ymin": ("HLIM",),
    },
    **{m: {"invR": ("R",)} for m in ("TGOV1", "GAST", "TG2")},
    "IEEEG1": {"invR": ("K",), "Tmax": ("PMAX",), "Tmin": ("PMIN",), "machine2": ("JBUS", "M")},
    "HYGOV": {"Uc": ("VELM",), "Kg": ("r", "Tr")},
    "IEESGO": {"K1": ("K2",), "K3": ("K2", "K3"), "K5": ("K2", "K3"), "invR": ("K1",)},
    "WPIDHY": {"Rperm": ("REG",)},
}


def dyr_origin(rec: DyrRecord, names=None, where: str | None = None) -> Origin:
    """The origin of the table row that record ``rec`` fills (`stabctl.io.provenance`):
    each column its declaration copies (`DyrModel.copy`) or its mapper computes
    (`_DERIVED`) with the DYR fields it holds, named as written and valued as read.

    Parameters
    ----------
    rec : DyrRecord
        A record of a model of :data:`DYR_MODELS`.
    names : Mapping[str, str], optional
        DYR field -> the name to give it (another format's name for the same parameter:
        ANDES's); default the DYR documentation's (:data:`_SHOWN`, else the field).
    where : str, optional
        How to name the record; default ``rec.label()``.

    Returns
    -------
    Origin
        Its ``where``, the columns' parameters and which of them are computed.
    """
    decl = DYR_MODELS[rec.model]
    family = FAMILY[_KIND[rec.model]]
    values = decl.values(rec.params)
    names = names or {}

    def given(fields) -> tuple[tuple[str, float], ...]:
        return tuple((names.get(f) or _SHOWN.get(f, f), values[f]) for f in fields if f in values)

    params: dict[int, tuple[tuple[str, float], ...]] = {}
    for col_name, src in decl.copy.items():
        params[family.col(col_name)] = given((src,))
    derived = set()
    for col_name, srcs in _DERIVED.get(rec.model, {}).items():
        k = family.col(col_name)
        if k not in params:
            params[k] = given(srcs)
            derived.add(k)
    return Origin(where or rec.label(), params, frozenset(derived))


def _map_records(records, generators, conventions):
    """Rows per kind {kind: {machine number: (record, row)}} and the unsupported records
    with their reasons, in file order; raises CaseError for malformed records."""
    andes = conventions == "andes"
    gens = {(int(g["bus"]), machine_id(g["id"])): g for g in generators}
    rows: dict[str, dict[int, tuple[DyrRecord, list]]] = {k: {} for k in FAMILY}
    skipped = []
    compensators = [r for r in records if r.model in COMPENSATORS]
    for rec in records:
        if rec.model in COMPENSATORS:
            continue
        kind = _KIND.get(rec.model)
        try:
            if kind is None:
                raise _Unsupported(
                    SOURCE_UNSUPPORTED
                    if rec.model in _SOURCE_MODELS
                    else f"model {rec.model} is not mapped"
                )
            _check_count(rec)
            gen = gens.get((rec.bus, rec.id))
            if gen is None:
                raise _Unsupported(no_generator(rec, gens))
            mapper = _CONVENTION_MAPPERS.get(conventions, {}).get(rec.model)
            if rec.model == "IEEEG1":  # its LP shaft may be another generator's
                row = (_ieeeg1_andes if andes else _ieeeg1)(rec, gen, _lp_generator(rec, gens))
            else:
                row = (mapper or _MAPPERS.get(rec.model) or _DEFAULT_ROW[kind])(rec, gen)
        except _Unsupported as why:
            skipped.append((rec, str(why)))
            continue
        if kind == "machine" and andes:
            row[MACHINE.col("speed_effects") - 1] = 0.0
            row[MACHINE.col("psse_sat") - 1] = 1.0
        elif kind == "machine" and conventions == "psse":
            _positive_time_constants(rec)
            row[MACHINE.col("speed_effects") - 1] = 0.0
            sat, swing = _PSSE_MACHINE[rec.model]
            row[MACHINE.col("psse_sat") - 1] = sat
            row[MACHINE.col("psse_swing") - 1] = swing
        number = int(gen["number"])
        if number in rows[kind]:
            raise CaseError(
                f"{rec.label()}: second {kind} model for this generator (first at "
                f"{rows[kind][number][0].where()})"
            )
        _saturation_noted(rec, conventions)
        if andes:
            _andes_lacks_noted(rec)
        rows[kind][number] = (rec, row)
    for number in [k for k in rows["exciter"] if _classical(rows["machine"].get(k))]:
        skipped.append((rows["exciter"].pop(number)[0], _NO_FIELD_WINDING))
    for number in [k for k in rows["pss"] if k not in rows["exciter"]]:
        skipped.append((rows["pss"].pop(number)[0], "its machine has no (supported) exciter"))
    skipped += _compensate(compensators, gens, rows["exciter"], andes)
    return rows, sorted(skipped, key=lambda item: (item[0].file, item[0].line))


#: why an exciter of a GENCLS is left out (round 47: imported, its field voltage moved
#: while every trajectory was the run's without it)
_NO_FIELD_WINDING = (
    "its machine is a GENCLS: a classical machine (constant E' behind X'd) has no field "
    "winding for an exciter to drive"
)


def _classical(machine: tuple | None) -> bool:
    """Whether a machine's (record, row) of `_map_records` is a GENCLS."""
    return machine is not None and machine[0].model == "GENCLS"


#: the saturation points of a DC or AC exciter's record (PSS/E Model Library)
_EXCITER_POINTS = ("E1", "SE(E1)", "E2", "SE(E2)")


def _saturation_noted(rec: DyrRecord, conventions: str) -> None:
    """Warn of a saturation value the model ignores (round 47: without a word): a
    GENROU's or GENSAL's S(1.2) > 0 with S(1.0) = 0 (PSS/E's quadratic through both
    points is off, the machine unsaturated; PST's curve through (0.8, 0.8) still fits
    one, `conventions` "pst"), an exciter's SE(E1) or SE(E2) with a point 0 (no curve)."""
    v = DYR_MODELS[rec.model].values(rec.params)
    quadratic = rec.model in ("GENROU", "GENSAL") and conventions != "pst"
    if quadratic and v["S(1.0)"] == 0 and v["S(1.2)"] != 0:
        warnings.warn(
            f"{rec.label()}: S(1.2) = {v['S(1.2)']:g} has no effect: with S(1.0) = 0 there is "
            "no saturation (PSS/E's curve goes through both points): the machine runs "
            "unsaturated",
            UserWarning,
            stacklevel=3,
        )
    points = [v.get(name) for name in _EXCITER_POINTS]
    if None not in points and 0 in points and (points[1] or points[3]):
        warnings.warn(
            f"{rec.label()}: saturation points (E1, SE(E1)) = ({points[0]:g}, {points[1]:g}) "
            f"and (E2, SE(E2)) = ({points[2]:g}, {points[3]:g}) have a 0: no saturation (a "
            "curve needs both points, as PSS/E): the exciter runs unsaturated",
            UserWarning,
            stacklevel=3,
        )


def _compensate(records, gens, exciters, andes) -> list:
    """Load compensators (IEEEVC) into their machine's exciter row (exc_con Rcomp, Xcomp,
    machine base); returns the records refused, with why.  andes: ANDES 2.0's IEEEVC
    (``vcomp/ieeevc.py``) takes its R_C, X_C with the machine's currents on the system
    base, read where the machine's MVA is the system base."""
    refused = []
    seen: dict = {}
    for rec in records:
        _check_count(rec)
        gen = gens.get((rec.bus, rec.id))
        number = None if gen is None else int(gen["number"])
        if number is not None and number in seen:
            raise CaseError(
                f"{rec.label()}: second compensator model for this generator (first at "
                f"{seen[number].where()})"
            )
        seen[number] = rec
        if number not in exciters:
            refused.append((rec, "its machine has no (supported) exciter"))
            continue
        if andes and gen["mbase"] != gen.get("sbase", 100.0):
            refused.append(
                (
                    rec,
                    f"machine base {gen['mbase']:g} MVA differs from the system base "
                    f"{gen.get('sbase', 100.0):g} MVA (ANDES's R_C, X_C are on the system base)",
                )
            )
            continue
        v = DYR_MODELS[rec.model].values(rec.params)
        row = exciters[number][1]
        for name, field in DYR_MODELS[rec.model].copy.items():
            row[EXCITER.col(name) - 1] = v[field]
    return refused


class Compensators(NamedTuple):
    """What `compensator_rows` gives: the svc_con rows, the generators (bus, ID) they
    are, and the records left out with why."""

    rows: list
    replaced: set
    skipped: list


def compensator_rows(records, generators) -> Compensators:
    """The svc_con rows (`stabctl.models.svcs.SVC`) of the static var compensator records
    (CSVGN1): a compensator is its generator in the RAW power flow (PSS/E attaches the
    record to a generator, P = 0), numbered 1, 2, ... in record order, its reactor rating
    RBASE the generator's MBASE, its share of the bus's reactive generation the
    generator's (`stabctl.io.dyr_converters.shares`).

    Args:
        records: DyrRecord sequence (`read_dyr`); those of other models are ignored.
        generators: the RAW's in-service generators (dicts: bus, id, mbase, pg, qg).

    Returns:
        `Compensators`; a record without its generator is skipped with the reason.

    Raises:
        CaseError: a record with the wrong number of parameters, or whose generator has
        PG != 0.
    """
    from stabctl.io.dyr_converters import shares

    by_key = {(int(g["bus"]), machine_id(g["id"])): g for g in generators}
    out = Compensators([], set(), [])
    for rec in records:
        model = SVC_DYR.get(rec.model)
        if model is None:
            continue
        _check_count(rec)
        gen = by_key.get((rec.bus, rec.id))
        if gen is None:
            out.skipped.append((rec, no_generator(rec, by_key)))
            continue
        if float(gen["pg"]) != 0.0:
            raise CaseError(
                f"{rec.label()}: its generator has PG = {float(gen['pg']):g} MW; a static "
                "var compensator's generator carries no real power (PG 0)"
            )
        v = model.values(rec.params)
        for field, name in model.copy.items():
            # the svc_con bounds, refused naming the record (round 42: a negative CSVGN1
            # time constant was refused naming "svc_con row 1 (compensator 1)" only)
            lo = SVC.param(field).lo
            if lo is not None and v[name] < lo:
                raise CaseError(f"{rec.label()}: {name} = {v[name]:g}: must be >= {lo:g}")
        row = {
            "number": len(out.rows) + 1,
            "bus": int(gen["bus"]),
            "qfrac": shares(generators, gen)[1],
            "mva": float(gen["mbase"]),
            **{field: v[name] for field, name in model.copy.items()},
        }
        out.rows.append([row[name] for name in SVC.names])
        out.replaced.add((rec.bus, rec.id))
    return out


def _check_count(rec: DyrRecord) -> None:
    want = N_PARAMS[rec.model]
    if len(rec.params) != want:
        raise CaseError(
            f"{rec.label()}: needs {want} parameters after the id, got {len(rec.params)}"
        )


def _check_machines(generators, machines, skipped, records=()) -> None:
    """`UnmodelledError` naming every generator without a machine row: without a source
    record in the DYR data (its other records named, ``file:line MODEL``, e.g. an
    exciter for a machine that has none), or whose source record is of a model stabctl
    does not support (that record named ``file:line MODEL``, with why); a machine record
    that matches no generator (a wrong id or bus, :data:`NO_GENERATOR`) named first."""
    missing = [g for g in generators if int(g["number"]) not in machines]
    if not missing:
        return
    refused: dict[tuple[int, str], list[str]] = {}
    for rec, why in skipped:
        if has_machine_model(rec):
            refused.setdefault((rec.bus, rec.id), []).append(f"{rec.where()} {rec.model}: {why}")
    bare = [g for g in missing if (int(g["bus"]), machine_id(g["id"])) not in refused]
    named = [g for g in missing if (int(g["bus"]), machine_id(g["id"])) in refused]
    # a machine record of no generator (a wrong id or bus) first: the likely cause
    strays = [
        f"{r.label()}: {why}"
        for r, why in skipped
        if why.startswith(NO_GENERATOR) and has_machine_model(r)
    ]
    parts = []
    if bare:
        parts.append(
            "generator(s) without a machine model record in the DYR data: "
            + ", ".join(
                f"machine {g['number']} (bus {g['bus']}, id {g['id']})" + _its_records(g, records)
                for g in bare
            )
        )
    if named:
        parts.append(
            "generator(s) whose machine model record stabctl cannot read: "
            + ", ".join(
                f"machine {g['number']} (bus {g['bus']}, id {g['id']}): "
                + "; ".join(refused[(int(g["bus"]), machine_id(g["id"]))])
                for g in named
            )
        )
    first = f"{'; '.join(strays)}; so " if strays else ""
    exc = UnmodelledError(first + "; ".join(parts))
    exc.unreadable = bool(named)
    raise exc


def _its_records(gen, records) -> str:
    """' (its DYR record(s): file:line MODEL, ...)' of generator gen, '' without any."""
    key = (int(gen["bus"]), machine_id(gen["id"]))
    mine = [f"{r.where()} {r.model}" for r in records if (r.bus, r.id) == key]
    return f" (its DYR record(s): {', '.join(mine)})" if mine else ""


def _set_fractions(generators, machines) -> None:
    """mac_con columns 22, 23: each machine's share of its bus's P and Q generation."""
    by_bus: dict[int, list] = {}
    for g in generators:
        by_bus.setdefault(int(g["bus"]), []).append(g)
    for bus, gs in by_bus.items():
        if len(gs) == 1 or all("pfrac" in g and "qfrac" in g for g in gs):
            continue  # a lone machine, or machines given their shares (mac_con by _mac_row)
        if any("pg" not in g or "qg" not in g for g in gs):
            raise CaseError(
                f"bus {bus} has {len(gs)} generators: give 'pg' and 'qg' of each to "
                "split the bus generation (mac_con pfrac, qfrac)"
            )
        for key, col in (("pg", MACHINE.col("pfrac") - 1), ("qg", MACHINE.col("qfrac") - 1)):
            for g, share in zip(gs, bus_shares(gs, key)):
                machines[int(g["number"])][1][col] = share


def bus_shares(gs: list[dict], key: str) -> list[float]:
    """Each generator's share of its bus's ``key`` (``"pg"`` MW or ``"qg"`` Mvar): its value
    over their sum, equal shares when every value is 0.

    Parameters
    ----------
    gs : list of dict
        The generators at one bus (keys "bus", "id" and ``key``).
    key : str
        ``"pg"`` or ``"qg"``.

    Returns
    -------
    list of float
        One share a generator, summing to 1.

    Raises
    ------
    CaseError
        Values that sum to 0 without all being 0 (+40 and -40 MW): stabctl gives each
        machine a share of the bus's total, and no share of 0 is their own values (round
        59 BD11: both ran at 0 MW, halves of 0, without a word).
    """
    values = [float(g[key]) for g in gs]
    total = sum(values)
    if total == 0 and any(values):
        listing = ", ".join(f"'{g['id']}' {v:g}" for g, v in zip(gs, values))
        raise CaseError(
            f"bus {gs[0]['bus']}: its generators' {key.upper()} ({listing}) sum to 0: a "
            "machine's share of its bus's generation cannot give each its own (stabctl "
            "splits the bus's total among its machines)"
        )
    return [v / total if total else 1.0 / len(values) for v in values]


def _matrix(rows: dict, width: int) -> np.ndarray | None:
    if not rows:
        return None
    return np.array([rows[k][1] for k in sorted(rows)], float).reshape(len(rows), width)


# -- machines (PST mac_con, MachineTable) -----------------------------------------------------


def _mac_row(rec, gen, **cols) -> list:
    """mac_con row of a machine record: the declared copies (stabctl.models.machines.MACHINE),
    the RAW data (number, bus, mbase, ra) and ``cols``."""
    cols.update(
        number=gen["number"],
        bus=gen["bus"],
        mva=gen["mbase"],
        ra=gen["ra"],
        col19=gen["number"],
        pfrac=gen.get("pfrac", 1.0),
        qfrac=gen.get("qfrac", 1.0),
        speed_effects=1.0,
    )
    return MACHINE.dyr_row(DYR_MODELS[rec.model], rec.params, **cols)


def _positive_time_constants(rec) -> None:
    """With the psse conventions, CaseError naming a machine record's open-circuit time
    constant (T'do, T''do, T'qo, T''qo) that is not > 0: the Model Library's GENROU, GENSAL,
    GENROE and GENSAE integrate each flux over its time constant (OpenIPSL's PSS/E-verified
    models divide by it), and PST's reading of 0 as "no such circuit" (the pst conventions)
    is not the limit of a time constant going to 0 (round 59 BD12-13: T'qo 0 ran as 999 s,
    E'd frozen; T''qo 0 ran x'q as x''d)."""
    v = DYR_MODELS[rec.model].values(rec.params)
    for name in ("T'do", "T''do", "T'qo", "T''qo"):
        if name in v and not v[name] > 0:
            raise CaseError(
                f"{rec.label()}: {name} = {v[name]:g} s must be > 0 (the Model Library's "
                f"{rec.model} has this circuit; a machine without it is another model)"
            )


def _leakage_noted(rec, v) -> None:
    """Warn of a subtransient machine record whose Xl lies above its X''d (but below X'd,
    which `stabctl.case.system` requires): PSS/E's Model Library wants Xl < X''d; the
    model runs with it (ANDES's ieee39_full has two such units), so it is kept as
    written, and named (round 42: without a word)."""
    xl, xdpp = v["Xl"], v["X''d"]
    if xdpp < xl < v["X'd"]:
        warnings.warn(
            f"{rec.label()}: Xl {xl:g} above X''d {xdpp:g} (PSS/E's Model Library "
            "wants Xl < X''d; the model runs with Xl < X'd): kept as written",
            UserWarning,
            stacklevel=2,
        )


#: relative difference of the RAW's ZSORCE X from the DYR's X''d taken as the files'
#: rounding (the DYR's four decimals against the RAW's five: 0.1937 and 0.19375, 2.6e-4)
ZSORCE_ROUNDING = 1e-3


def _zsorce_noted(rec, gen, xdpp: float) -> None:
    """Warn of a subtransient machine whose RAW ZSORCE X differs from its X''d: PSS/E's
    Model Library wants ZSORCE = R_a + j X''d for GENROU and GENSAL; the model's X''d is
    used (round 47: the RAW's value was left unused without a word).  Only a RAW's
    generator (``zsorce`` in its dict): an ANDES case's source reactance is its x'd.  A
    difference within ZSORCE_ROUNDING of X''d is the two files' rounding (Nordic 44: RAW
    0.19375, DYR 0.1937), not said (round 49)."""
    xs = float(gen.get("xsource", xdpp))
    if gen.get("zsorce") and abs(xs - xdpp) > ZSORCE_ROUNDING * max(abs(xdpp), 1e-3):
        warnings.warn(
            f"{rec.label()}: the RAW's ZSORCE X {xs:g} differs from X''d {xdpp:g} (PSS/E's "
            "Model Library wants ZSORCE = R_a + j X''d): the model runs with X''d",
            UserWarning,
            stacklevel=3,
        )


def _positive_h(rec, H) -> None:
    if H <= 0:
        raise CaseError(
            f"{rec.label()}: H = {H}: a machine of this model needs H > 0 (an infinite "
            "bus, PSS/E's H = 0, is a GENCLS)"
        )


def _genrou(rec, gen):
    """GENROU (and GENROE): T'do T''do T'qo T''qo H D Xd Xq X'd X'q X''d Xl S(1.0) S(1.2)
    -> mac_sub with x''q = x''d (as PSS/E)."""
    v = DYR_MODELS[rec.model].values(rec.params)
    _positive_h(rec, v["H"])
    _leakage_noted(rec, v)
    _zsorce_noted(rec, gen, v["X''d"])
    return _mac_row(rec, gen, xqpp=v["X''d"])


def _gensal(rec, gen):
    """GENSAL (and GENSAE): T'do T''do T''qo H D Xd Xq X'd X''d Xl S(1.0) S(1.2) -> mac_sub
    without the q-axis transient circuit: x'q = x_q, T'qo = 0 (E'd stays 0, docs 12.1)."""
    v = DYR_MODELS[rec.model].values(rec.params)
    _positive_h(rec, v["H"])
    _leakage_noted(rec, v)
    _zsorce_noted(rec, gen, v["X''d"])
    return _mac_row(rec, gen, xqp=v["Xq"], xqpp=v["X''d"], Tqop=0.0)


def _gencls(rec, gen):
    """GENCLS: H D -> PST classical mac_em (x_d = 0) behind x'd = ZSORCE X; H = 0 is PSS/E's
    infinite bus (constant internal voltage and angle, `stabctl.case.system.MachineTable`)."""
    H = DYR_MODELS["GENCLS"].values(rec.params)["H"]
    if H < 0:
        raise CaseError(f"{rec.label()}: H = {H} s must be >= 0 (0: an infinite bus)")
    if H == 0 and gen["xsource"] <= 0:
        raise CaseError(
            f"{rec.label()}: an infinite bus (H = 0) needs its source reactance ZSORCE X > 0 "
            f"(got {gen['xsource']})"
        )
    return _mac_row(rec, gen, xdp=gen["xsource"])


# -- exciters (PST exc_con, ExciterTable) ------------------------------------------------------


def _exc_row(rec, gen, model=None, **cols) -> list:
    """exc_con row of an exciter record: type and copies as declared for ``model`` (default
    the record's; stabctl.models.exciters.EXCITER), the machine number and ``cols`` (table
    names or the DC exciters' ``alt`` names)."""
    return EXCITER.dyr_row(
        model or DYR_MODELS[rec.model], rec.params, machine=gen["number"], **cols
    )


def _sexs(rec, gen):
    """SEXS: TA/TB TB K TE EMIN EMAX -> smpexc (type 0): lead-lag T_C = (TA/TB) TB over
    T_B, K_A = K, T_A = TE, limits [EMIN, EMAX] (PST's limiter, docs 12.2)."""
    v = DYR_MODELS["SEXS"].values(rec.params)
    return _exc_row(rec, gen, TC=v["TA/TB"] * v["TB"])


def exp_saturation(E1, SE1, E2, SE2) -> tuple[float, float]:
    """(Asat, Bsat) of SE(E) = Asat exp(Bsat E) through (E1, SE1), (E2, SE2); (0, 0) when a
    point is 0 (no saturation, as PSS/E and ANDES).  Raises CaseError for E1 = E2 or
    SE of opposite signs."""
    if 0 in (E1, SE1, E2, SE2):
        return 0.0, 0.0
    if E1 == E2 or SE1 * SE2 < 0:
        raise CaseError(f"saturation points ({E1}, {SE1}), ({E2}, {SE2}) give no exponential fit")
    B = np.log(SE2 / SE1) / (E2 - E1)
    return float(SE1 * np.exp(-B * E1)), float(B)


#: a VRMAX = 0 read as no upper limit (ANDES; conventions "andes" and "pst", and IEEET3)
VRMAX_UNLIMITED = VRMAX_NO_LIMIT


def _dc(model, zero_vrmax_unlimited=False, andes=False, psse=False):
    """Mapper of a DC exciter record read as DYR model ``model`` (its PST type)."""
    decl = DYR_MODELS[model]

    def mapper(rec, gen):
        """IEEEX1, ESDC1A (DC1, type 1) / EXDC2, ESDC2A (DC2, type 2): TR KA TA TB TC VRMAX VRMIN KE
        TE KF TF1 Switch E1 SE(E1) E2 SE(E2) -> exc_dc12; IEEET2 (type 5): TR KA TA VRMAX
        VRMIN KE TE KF TF1 TF2 E1 SE(E1) E2 SE(E2), DC1 without the lead-lag and with the
        rate feedback's second lag TF2 (exc_con column 18); saturation as Asat, Bsat (E2
        column 0); K_E = 0 is computed at initialisation (V_R0 = 0, docs 2.3; psse: V_R0 =
        VRMAX/10, below).  andes: the
        quadratic saturation through the points and K_E as given (exc_con columns 23, 24).
        psse: the quadratic saturation through the points, S_E(E) = B (E - A)^2 / E (the PSS/E
        Model Library's exciter saturation; OpenIPSL's ``NonElectrical.Functions.SE``), and
        K_E = 0 computed at initialisation as PSS/E does (V_R0 = VRMAX/10: PAG 15.2.4,
        OpenIPSL's ``calculate_dc_exciter_params``)."""
        v = decl.values(rec.params)
        cols = {}
        if psse and v["VRMAX"] == 0:
            cols["Vrmax"], cols["Vrmin"] = _psse_vrmax(rec, v)
        elif zero_vrmax_unlimited and v["VRMAX"] == 0:
            cols["Vrmax"] = _unlimited_vrmax(rec)
        if v.get("Switch", 0.0) != 0:
            raise _Unsupported(f"Switch = {v['Switch']} is not modelled (only 0)")
        points = (v["E1"], v["SE(E1)"], v["E2"], v["SE(E2)"])
        if psse and model in ("ESDC1A", "ESDC2A"):  # OpenIPSL's RotatingExciterLimited
            cols["efd_floor"] = 1
        if andes or psse:
            return _exc_row(
                rec,
                gen,
                decl,
                **cols,
                **dict(zip(("E1", "SE1", "E2", "SE2"), points)),
                dc_sat=1,
                ke_given=int(andes),
            )
        try:
            A, B = exp_saturation(*points)
        except CaseError as exc:
            raise CaseError(f"{rec.label()}: {exc}") from None
        return _exc_row(rec, gen, decl, **cols, SE1=A, E2=0.0, SE2=B)

    return mapper


def _scrx(rec, gen):
    """SCRX: TA/TB TB K TE EMIN EMAX CSWITCH rc/rfd -> smpexc (type 0) as SEXS, bus fed
    (output times the terminal voltage, exc_con column 19 = 1) when CSWITCH = 0; rc/rfd
    in smpexc's column 74 (the negative field current logic,
    stabctl.models.exciters.sexs; a negative rc/rfd refused by name)."""
    v = DYR_MODELS["SCRX"].values(rec.params)
    if v["rc/rfd"] < 0:
        raise CaseError(f"{rec.label()}: rc/rfd = {v['rc/rfd']:g} must be >= 0")
    if v["CSWITCH"] not in (0, 1):  # PSS/E Model Library SCRX: 0 bus fed, 1 solid fed
        raise CaseError(
            f"{rec.label()}: CSWITCH = {v['CSWITCH']:g} must be 0 (bus fed) or 1 (solid fed)"
        )
    return _exc_row(rec, gen, TC=v["TA/TB"] * v["TB"], bus_fed=float(v["CSWITCH"] == 0))


#: ANDES 2.0's SEXS defaults (``sexs.py``): TA/TB, TB, K, TE, EMIN, EMAX
ANDES_SEXS_DEFAULTS = (0.4, 5.0, 20.0, 1.0, -99.0, 99.0)


def _scrx_andes(rec, gen):
    """SCRX as ANDES 2.0 reads it: its ``psse-dyr.yaml`` makes an SCRX record a SEXS
    passing only the machine, so every parameter takes SEXS's default
    (:data:`ANDES_SEXS_DEFAULTS`), never bus fed; named as read so."""
    _read_as(
        rec,
        "read as ANDES 2.0 reads it, a SEXS with SEXS's defaults (TA/TB TB K TE EMIN EMAX "
        f"= {' '.join(f'{x:g}' for x in ANDES_SEXS_DEFAULTS)}), CSWITCH and rc/rfd not read",
    )
    return EXCITER.dyr_row(
        DYR_MODELS["SEXS"],
        ANDES_SEXS_DEFAULTS,
        machine=gen["number"],
        TC=ANDES_SEXS_DEFAULTS[0] * ANDES_SEXS_DEFAULTS[1],
    )


def _esst1a(rec, gen, andes=False, psse=False):
    """ESST1A: UEL VOS TR VIMAX VIMIN TC TB TC1 TB1 KA TA VAMAX VAMIN VRMAX VRMIN KC KF TF
    KLR ILR -> stabctl type 6 (columns as declared).  UEL, the under-excitation limiter's
    input location, is read for no limiter model feeds it, but must be one of PSS/E's
    codes 1, 2, 3.  VOS = 2 (the stabiliser after
    V_A) is not modelled (only 1, at the voltage error); andes: ANDES 2.0's ``esst1a.py``
    adds the stabiliser at the voltage error whatever VOS, and so does stabctl.  psse:
    VOS = 2 adds it to the regulator output after V_A (exc_con column 20
    ``vos_after_va`` = 1, PSS/E Model Library; PowerSimulationsDynamics.jl's ESST1A
    ``Va_sum``), VOS other than 1, 2 refused."""
    v = DYR_MODELS["ESST1A"].values(rec.params)
    vos = v["VOS"]
    if v["UEL"] not in (1, 2, 3):  # PSS/E Model Library ESST1A ICON UEL; ANDES's UELc 1-3
        raise CaseError(
            f"{rec.label()}: UEL = {v['UEL']:g} must be 1, 2 or 3 (the under-excitation "
            "limiter's input: the summing point, the HV gate, the LV gate)"
        )
    if psse and vos == 2:
        return _exc_row(rec, gen, vos_after_va=1.0)
    if vos != 1 and not andes:
        modelled = "1 or 2" if psse else "only 1; 2 with the psse conventions"
        raise _Unsupported(f"VOS = {vos:g}: not modelled ({modelled})")
    return _exc_row(rec, gen)


def _ac8b(rec, gen):
    """AC8B as declared (type 10), a VFEMAX or VEMIN that limits anything named as read
    without effect (`stabctl.models.exciters.ac8b.without_effect`)."""
    v = DYR_MODELS["AC8B"].values(rec.params)
    for name in ac8b.UNMODELLED:
        if said := ac8b.without_effect(name, v[name]):
            _read_as(rec, said)
    return _exc_row(rec, gen)


def _esst3a(rec, gen):
    """ESST3A: TR VIMAX VIMIN KM TC TB KA TA VRMAX VRMIN KG KP KI VBMAX KC XL VGMAX THETAP TM
    VMMAX VMMIN -> PST exc_st3 (type 3): ST3A's gain KA is PST's K_J, its inner loop KM/(1 +
    s TM) limited [VMMIN, VMMAX] is PST's K_A/(1 + s T_A) limited [Vrmin, Vrmax]; its
    regulator lag 1/(1 + s TA) non-windup on [VRMIN, VRMAX] is stabctl's (exc_con columns
    44, 28-29; TA = 0: none, and VRMAX/VRMIN unused, PST's exc_st3); VBMAX limits V_B
    (exc_con column 33, stabctl's, not PST's) and Efdmax = VBMAX VMMAX (docs 12.2)."""
    v = DYR_MODELS["ESST3A"].values(rec.params)
    return _exc_row(rec, gen, Efdmax=v["VBMAX"] * v["VMMAX"])


def _ieeet3(rec, gen):
    """IEEET3: TR KA TA VRMAX VRMIN TE KF TF KP KI VBMAX KE -> type 11; VRMAX = 0 read as
    no upper limit (ANDES ``ieeet3.py`` ``VRMAXc``)."""
    v = DYR_MODELS["IEEET3"].values(rec.params)
    return _exc_row(rec, gen, **({"Vrmax": _unlimited_vrmax(rec)} if v["VRMAX"] == 0 else {}))


def _psse_vrmax(rec, v) -> tuple[float, float]:
    """A DC exciter's VRMAX = 0 as PSS/E computes it (PAG 15.2.4, as OpenIPSL's
    ``calculate_dc_exciter_params`` reads it): the ceiling that holds Efd at E2 in steady
    state, VRMAX = (KE + SE(E2)) E2 with KE taken as 0 when it is 0 (computed later from
    VRMAX) or negative, and VRMIN = -VRMAX; named as read so.  OpenIPSL writes the KE > 0
    branch SE(E2) + KE, without the factor E2 its KE <= 0 branch has; stabctl keeps the
    factor (the steady-state ceiling at Efd = E2 in both).  Raises CaseError when that
    ceiling is not positive (no saturation point E2)."""
    ke = max(v["KE"], 0.0)
    vrmax = (ke + v["SE(E2)"]) * v["E2"]
    if not vrmax > 0:
        raise CaseError(
            f"{rec.label()}: VRMAX = 0 is computed as (KE + SE(E2)) E2 = {vrmax:g} "
            "(PSS/E PAG 15.2.4), not a ceiling: give VRMAX, or E2 and SE(E2)"
        )
    _read_as(
        rec,
        f"VRMAX = 0 computed as PSS/E does, (KE + SE(E2)) E2 = ({ke:g} + {v['SE(E2)']:g}) "
        f"{v['E2']:g} = {vrmax:.6g}, VRMIN = -VRMAX (PAG 15.2.4)",
    )
    return vrmax, -vrmax


def _unlimited_vrmax(rec) -> float:
    """:data:`VRMAX_UNLIMITED`, the upper limit a record's VRMAX = 0 is read as, named."""
    _read_as(rec, f"VRMAX = 0 read as no upper limit ({VRMAX_UNLIMITED:g})")
    return VRMAX_UNLIMITED


def _esst4b(rec, gen, vgmax=VRMAX_UNLIMITED, psse=1.0):
    """ESST4B: TR KPR KIR VRMAX VRMIN TA KPM KIM VMMAX VMMIN KG KP KI VBMAX KC XL THETAP ->
    type 12; the inner-loop feedback K_G Efd unlimited (PSS/E's record has no VGMAX):
    VGmax = ``vgmax``; its PIs non-windup (exc_con psse_st1 = ``psse`` 1: PSS/E's reading;
    ANDES's 0, tracking anti-windup)."""
    return _exc_row(rec, gen, VGmax=vgmax, psse_st1=psse)


def _source_on_system_base(mapper, names=("KI", "XL")):
    """An exciter's ``mapper`` as ANDES 2.0 solves its potential/compound source (ESST3A,
    ESST4B, IEEET3): ``V_E = |K_P e^(j theta_P) V_t + j (K_I + K_P X_L) I_t|`` with the
    stator current on the system base, i.e. K_I and X_L times MBASE/SBASE with the
    machine-base current."""

    def on_system_base(rec, gen):
        row = mapper(rec, gen)
        scale = gen["mbase"] / gen.get("sbase", 100.0)
        for name in names:
            row[EXCITER.col(name) - 1] *= scale
        return row

    return on_system_base


# -- PSS (PST pss_con, PssTable) ----------------------------------------------------------------


def _pss_row(rec, gen, **cols) -> list:
    """pss_con row of a PSS record: the declared copies (stabctl.models.pss.PSS), the
    machine number and ``cols``."""
    return PSS.dyr_row(DYR_MODELS[rec.model], rec.params, machine=gen["number"], **cols)


#: PSS/E's stabiliser input codes (IEEEST ICS, PSS1A ICS, ST2CUT MODE, PSS2A ICS1, ...:
#: PSS/E Model Library), 0 no input
INPUT_CODES = {
    0: "none",
    1: "rotor speed deviation",
    2: "bus frequency deviation",
    3: "generator electrical power",
    4: "generator accelerating power",
    5: "bus voltage",
    6: "derivative of the bus voltage",
}


def _local_inputs(rec, *pairs) -> None:
    """PSS/E input codes and remote buses (``pairs`` of the record's field names, code
    then bus, None for no bus): a code that is no input code (`INPUT_CODES`) refused as
    invalid data (CaseError naming the parameter and the codes); only local speed (1) or
    electrical power (3) supported."""
    v = DYR_MODELS[rec.model].values(rec.params)
    for name, _ in pairs:
        if v[name] not in INPUT_CODES:
            codes = ", ".join(f"{k} {what}" for k, what in INPUT_CODES.items())
            raise CaseError(
                f"{rec.label()}: {name} = {v[name]:g}: not a PSS/E input code (an integer "
                f"0 to 6: {codes})"
            )
    for code, bus in ((v[c], 0.0 if b is None else v[b]) for c, b in pairs):
        if code not in (0.0, 1.0, 3.0) or bus != 0:
            raise _Unsupported(
                f"input code {code:g} at bus {bus:g} (only local speed 1 or electrical power 3)"
            )


def _washout(rec, v, gain: str, lag: str) -> None:
    """Refuse a stabiliser washout (numerator ``v[gain]`` s/(1 + s ``v[lag]``)): a negative
    time constant as invalid data, naming it (CaseError); a numerator of 0 (a lag, not a
    washout) or a lag below 1e-3 s as unsupported, naming both with their values (an
    IEEEST's T6 of -4.2 was "unsupported", named neither)."""
    for name in dict.fromkeys((gain, lag)):
        if name in ("T", "T2", "T3", "T4", "T5", "T6") and v[name] < 0:
            raise CaseError(f"{rec.label()}: {name} = {v[name]:g}: must be >= 0 (a time constant)")
    if v[gain] == 0 or v[lag] < 1e-3:
        values = ", ".join(f"{n} = {v[n]:g}" for n in dict.fromkeys((gain, lag)))
        raise _Unsupported(
            f"washout {values}: a numerator of 0 (a lag instead) or a washout time constant "
            "below 1e-3 s"
        )


def _ieeest(rec, gen):
    """IEEEST: ICS IB A1..A6 T1..T6 KS LSMAX LSMIN VCU VCL -> PST pss (type 1 speed, 2
    power) when exactly equivalent (A1..A6 = 0, a lead-lag with lag >= 1e-3 s): washout
    KS sT5/(1 + sT6) = K_Tw s/(1 + s T_w), K_Tw = KS T5, T_w = T6; else stabctl's PSS/E
    stabiliser (type 3); VCU/VCL: the output cut-off (pss_con columns 25-26)."""
    v = DYR_MODELS["IEEEST"].values(rec.params)
    ics, A = v["ICS"], [v[f"A{k}"] for k in range(1, 7)]
    _local_inputs(rec, ("ICS", "IB"))
    _washout(rec, v, "T5", "T6")
    if ics == 0:
        raise _Unsupported("no input (ICS 0)")
    _no_gain(rec, v, "KS")
    for name in ("T1", "T2", "T3", "T4"):
        # refused here, by its own name: an empty first stage moves T3/T4 into pss_con's
        # T1/T2, where the table's bound named T1 (round 42: "T1 = 0.0 (giving pss_con 'T1'
        # = -0.5)" for T3 = -0.5)
        if v[name] < 0:
            raise CaseError(f"{rec.label()}: {name} = {v[name]:g}: must be >= 0 (a time constant)")
    KTw = v["KS"] * v["T5"]
    lead_lags = [(v[a], v[b]) for a, b in (("T1", "T2"), ("T3", "T4"))]
    stages = [(a, b) for a, b in lead_lags if a or b]
    if not any(A) and stages and all(b >= 1e-3 for _, b in stages):
        (a1, b1), (a2, b2) = (stages + [(0.0, 0.0)])[:2]
        return _pss_row(rec, gen, type={1.0: 1, 3.0: 2}[ics], KTw=KTw, T1=a1, T2=b1, T3=a2, T4=b2)
    (a1, b1), (a2, b2) = lead_lags
    return _pss_row(
        rec,
        gen,
        type=3,
        input1=ics,
        K1=1.0,
        KTw=KTw,
        T1=a1,
        T2=b1,
        T3=a2,
        T4=b2,
        **{f"A{k}": a for k, a in enumerate(A, 1)},
    )


def _pss1a(rec, gen):
    """PSS1A: ICS A1 A2 T1 T2 T3 T4 T5 T6 KS LSMAX LSMIN VCU VCL -> stabctl's PSS/E
    stabiliser (type 3, stabctl.models.pss.ieeest): the transducer 1/(1 + s T6) its
    input lag (K1 = 1), the washout KS s T5/(1 + s T5) as K_w = KS T5, T_w = T5; inputs
    1 (speed) and 3 (electrical power) only, a washout T5 below 1e-3 s unsupported."""
    v = DYR_MODELS["PSS1A"].values(rec.params)
    _local_inputs(rec, ("ICS", None))
    _washout(rec, v, "T5", "T5")
    if v["ICS"] == 0:
        raise _Unsupported("no input (ICS 0)")
    _no_gain(rec, v, "KS")
    return _pss_row(rec, gen, K1=1.0, KTw=v["KS"] * v["T5"])


def _st2cut(rec, gen):
    """ST2CUT: MODE BUSR MODE2 BUSR2 K1 K2 T1..T10 LSMAX LSMIN VCU VCL -> stabctl's PSS/E
    stabiliser (type 3): K1/(1 + sT1) + K2/(1 + sT2) inputs, washout sT3/(1 + sT4), lead-lags
    T5/T6, T7/T8, T9/T10; VCU/VCL: the output cut-off (pss_con columns 25-26), offsets
    from the initial terminal voltage (cut_relative, column 45: PSS/E's ST2CUT as
    OPAL-RT's and ANDES's read it)."""
    v = DYR_MODELS["ST2CUT"].values(rec.params)
    _local_inputs(rec, ("MODE", "BUSR"), ("MODE2", "BUSR2"))
    _washout(rec, v, "T3", "T4")
    if v["MODE"] == 0:
        raise _Unsupported("no first input (MODE 0)")
    if v["K1"] == 0 and v["K2"] == 0:  # round 59 BD18: counted a PSS without a word
        _read_as(rec, "K1 = K2 = 0: its output is always 0, no effect on the run")
    return _pss_row(rec, gen, cut_relative=1)


def _stab2a(rec, gen):
    """STAB2A: K2 T2 K3 T3 K4 K5 T5 HLIM -> type 4: washouts K_Tw s/(1 + s T_w) with K_Tw =
    K2 T2, T_w = T2; limits [-HLIM, HLIM]."""
    v = DYR_MODELS["STAB2A"].values(rec.params)
    return _pss_row(rec, gen, KTw=v["K2"] * v["T2"], ymin=-v["HLIM"])


def _stab1(rec, gen):
    """STAB1: K/T T T1/T3 T3 T2/T4 T4 HLIM -> PST pss type 1 (the same equations,
    stabctl.models.pss.stab1): washout K_Tw s/(1 + s T_w) with K_Tw = (K/T) T, T_w = T;
    lead-lags T1 = (T1/T3) T3 over T3 and (T2/T4) T4 over T4; limits [-HLIM, HLIM]."""
    v = DYR_MODELS["STAB1"].values(rec.params)
    _washout(rec, v, "K_T", "T")
    return _pss_row(
        rec,
        gen,
        KTw=v["K_T"] * v["T"],
        T1=v["T1_T3"] * v["T3"],
        T3=v["T2_T4"] * v["T4"],
        ymin=-v["HLIM"],
    )


def _pss2(rec, gen):
    """PSS2A, PSS2B, PSS2C: ICS1 IB1 ICS2 IB2 M N then the CONs -> pss_con types 5-7 (the
    copies of stabctl.models.pss.pss2a, pss2b, pss2c); only local inputs (IB1 = IB2 = 0)
    of speed (1) or electrical power (3)."""
    _local_inputs(rec, ("ICS1", "IB1"), ("ICS2", "IB2"))
    _no_gain(rec, DYR_MODELS[rec.model].values(rec.params), "KS1")
    return _pss_row(rec, gen)


def _no_gain(rec, v, gain: str) -> None:
    """Name a stabiliser whose gain `gain` is 0 (PSS/E reads it: its output is then 0
    whatever its input) as one without effect on the run (round 41: an IEEEST of KS 0 was
    counted "1 PSS" and the run was byte for byte the one without it)."""
    if v[gain] == 0:
        _read_as(rec, f"{gain} = 0: its output is always 0, no effect on the run")


# -- governors (PST tg_con, GovernorTable) ----------------------------------------------------


def _tg_row(rec, gen, **cols) -> list:
    """tg_con row of a governor record: type and copies as declared
    (stabctl.models.governors.GOVERNOR), the machine number, speed set point 1 (or
    ``cols``'s wf) and ``cols``."""
    return GOVERNOR.dyr_row(
        DYR_MODELS[rec.model], rec.params, machine=gen["number"], **{"wf": 1.0, **cols}
    )


def _droop(rec, gen):
    """TGOV1 (R T1 VMAX VMIN T2 T3 Dt -> tg_con type 2: valve T1 with non-windup [VMIN,
    VMAX], lead-lag T2/T3, damping Dt), GAST (R T1 T2 T3 AT KT VMAX VMIN Dturb -> type
    6) and ANDES's TG2 (R wref0 pmax pmin T1 T2 -> type 7): the declared copies and 1/R."""
    v = DYR_MODELS[rec.model].values(rec.params)
    if v["R"] <= 0:
        raise CaseError(f"{rec.label()}: droop R = {v['R']} must be > 0")
    return _tg_row(rec, gen, invR=1 / v["R"], **({"wf": v["wref0"]} if "wref0" in v else {}))


def _ieeeg1(rec, gen, lp=None):
    """IEEEG1: JBUS M K T1 T2 T3 Uo Uc PMAX PMIN T4 K1 K2 T5 K3 K4 T6 K5 K6 T7 K7 K8 ->
    tg_con type 3: HP and LP powers summed on the one shaft (JBUS 0), or a cross-compound
    unit with its LP shaft on generator ``lp`` (`_lp_generator`; tg_con column 27): its
    parameters on the turbine's base, the two machines' MBASE summed (as ANDES 2.0's
    ``ieeeg1.py`` with Tn 0), so K, PMAX, PMIN times (MBASE + MBASE_LP)/MBASE on the HP
    machine's base."""
    if lp is None:
        return _tg_row(rec, gen)
    scale = (gen["mbase"] + lp["mbase"]) / gen["mbase"]
    v = DYR_MODELS["IEEEG1"].values(rec.params)
    return _tg_row(
        rec,
        gen,
        machine2=lp["number"],
        invR=v["K"] * scale,
        Tmax=v["PMAX"] * scale,
        Tmin=v["PMIN"] * scale,
    )


def _lp_generator(rec, gens):
    """The generator of an IEEEG1's LP shaft (JBUS, M; None for JBUS 0): the one at JBUS
    with id M, or with M 0 the only one at JBUS (ANDES's records give no M); raises
    `_Unsupported` when there is none or M 0 leaves it ambiguous."""
    v = DYR_MODELS["IEEEG1"].values(rec.params)
    jbus, m = int(v["JBUS"]), v["M"]
    if jbus == 0:
        return None
    at = [g for (bus, _), g in gens.items() if bus == jbus]
    if m != 0:
        at = [g for g in at if machine_id(g["id"]) == machine_id(f"{m:g}")]
    if len(at) != 1:
        raise _Unsupported(
            f"cross-compound LP shaft at bus {jbus}, id {m:g}: {len(at)} generators match"
        )
    return at[0]


def _hygov(rec, gen, andes=False, psse=False):
    """HYGOV: R r Tr Tf Tg VELM GMAX GMIN TW At Dturb qNL -> type 4 with the gate integrator
    gain K_g = 1/(r Tr) and the rate limits [-VELM, VELM] (PSS/E).  andes: as ANDES 2.0
    solves it on the system base (``hygov.py``: the integrator without 1/(r Tr), the rate
    limits shifted by -e/r, the water column and D_turb power-scaled), on the machine base
    K_g = SBASE/MBASE, T_w and D_turb times MBASE/SBASE, rate limits relative.  psse: the
    PI's whole output is the desired gate, rate- and position-limited (tg_con
    psse_gate = 1; OpenIPSL's PSS/E-verified ``PSSE.TG.HYGOV``: the lead (1 + s T_r)/(r
    T_r) into a rate limiter and a limited integrator)."""
    v = DYR_MODELS["HYGOV"].values(rec.params)
    for name in ("r", "Tr", "TW"):
        if v[name] <= 0:
            raise CaseError(f"{rec.label()}: {name} = {v[name]} must be > 0")
    cols = dict(Uc=-v["VELM"], Kg=1 / (v["r"] * v["Tr"]))
    if andes:
        s = gen["mbase"] / gen.get("sbase", 100.0)
        cols.update(Kg=1 / s, velm_rel=1.0, Tw=v["TW"] * s, Dt=v["Dturb"] * s)
    if psse:
        cols["psse_gate"] = 1.0
    return _tg_row(rec, gen, **cols)


def _ieesgo(rec, gen, andes=False):
    """IEESGO: T1 T2 T3 T4 T5 T6 K1 K2 K3 PMAX PMIN -> type 5, the power after T4, T5, T6
    weighted 1 - K2, (1 - K3) K2, K2 K3 (tg_con K1, K3, K5).  andes: K1 on the system base
    as ANDES 2.0 (``ieesgo.py``, not power-scaled): times SBASE/MBASE on the machine base."""
    v = DYR_MODELS["IEESGO"].values(rec.params)
    K2, K3 = v["K2"], v["K3"]
    cols = dict(K1=1 - K2, K3=(1 - K3) * K2, K5=K2 * K3)
    if andes:
        cols["invR"] = v["K1"] * gen.get("sbase", 100.0) / gen["mbase"]
    return _tg_row(rec, gen, **cols)


def _wpidhy(rec, gen):
    """WPIDHY: TREG REG KP KI KD TA TB VELMX VELMN GATMX GATMN TW PMAX PMIN D G0 G1 P1 G2 P2
    P3 -> type 13 (stabctl.models.governors.pidgov): the declared copies, Rperm = -REG
    (PSS/E's REG, the gain on P_e - P_ref, is negative: a positive one refused), feedback
    flag 0 (the electrical power) and ATW 1 (the water column's lead is TW)."""
    reg = DYR_MODELS["WPIDHY"].values(rec.params)["REG"]
    if reg > 0:
        raise CaseError(
            f"{rec.label()}: REG = {reg:g} must be <= 0 (the droop gain on P_e - P_ref)"
        )
    return _tg_row(rec, gen, Rperm=-reg, feedback_flag=0.0, Atw=1.0)


def _andes_hygov4(rec, gen):
    """ANDES's HYGOV4 (`stabctl.models.governors`, type 8): the declared copies, where the
    machine's MVA is the system base (ANDES 2.0 solves it on the system base, scaling
    its flows, head and gate limits by the machine's MVA over it: ``NumParam(power=True)``,
    a head that would no longer be 1 at the dam)."""
    if gen["mbase"] != gen.get("sbase", 100.0):
        raise _Unsupported(
            f"machine base {gen['mbase']:g} MVA differs from the system base "
            f"{gen.get('sbase', 100.0):g} MVA: ANDES scales HYGOV4's flows and head by their "
            "ratio, which stabctl's HYGOV4 (head 1 at the dam) does not"
        )
    return _tg_row(rec, gen)


#: DYR model -> its mapper, for the records whose row is not only the declared copies
#: (unit changes, products, fits, options refused); the others take their family's
#: default, `_DEFAULT_ROW`
_MAPPERS = {
    "GENROU": _genrou,
    "GENROE": _genrou,
    "GENSAL": _gensal,
    "GENSAE": _gensal,
    "GENCLS": _gencls,
    "SEXS": _sexs,
    "IEEEX1": _dc("IEEEX1"),
    "EXDC2": _dc("EXDC2"),
    "ESDC2A": _dc("ESDC2A", zero_vrmax_unlimited=True),
    "ESDC1A": _dc("ESDC1A", zero_vrmax_unlimited=True),
    "ESST1A": _esst1a,
    "ESST3A": _esst3a,
    "AC8B": _ac8b,
    "IEEET3": _ieeet3,
    "ESST4B": _esst4b,
    "IEEET1": _dc("IEEET1", zero_vrmax_unlimited=True),
    "IEEET2": _dc("IEEET2"),
    "SCRX": _scrx,
    "IEEEST": _ieeest,
    "ST2CUT": _st2cut,
    "PSS1A": _pss1a,
    "STAB2A": _stab2a,
    "STAB1": _stab1,
    "PSS2A": _pss2,
    "PSS2B": _pss2,
    "PSS2C": _pss2,
    "TGOV1": _droop,
    "GAST": _droop,
    "TG2": _droop,
    "HYGOV": _hygov,
    "IEESGO": _ieesgo,
    "WPIDHY": _wpidhy,
    "ANDES_HYGOV4": _andes_hygov4,
}
#: records that complete another record's row: a load compensator the exciter's
COMPENSATORS = ("IEEEVC",)
#: table kind -> the row of a record that is its declared copies and the machine number
_DEFAULT_ROW = {"machine": _mac_row, "exciter": _exc_row, "pss": _pss_row, "governor": _tg_row}
#: DYR model -> its table kind
_KIND = {m.name: kind for kind, family in FAMILY.items() for m in family.dyr}


def _ieeeg1_andes(rec, gen, lp=None):
    """IEEEG1 as ANDES 2.0 reads it: Uo, Uc (pu/s) on the system base, not converted to
    the machine base as its K, PMAX, PMIN are (``NumParam(power=True)``)."""
    row = _ieeeg1(rec, gen, lp)
    scale = gen.get("sbase", 100.0) / gen["mbase"]
    for name in ("Uo", "Uc"):
        row[GOVERNOR.col(name) - 1] *= scale
    return row


def _times_speed(mapper):
    """An exciter's ``mapper`` whose field voltage is its output times the rotor speed:
    ANDES 2.0's EXDC2 (``exdc2.py``: ``vout = omega vp``; exc_con column 45 = 1)."""

    def times_speed(rec, gen):
        row = mapper(rec, gen)
        row[EXCITER.col("efd_speed") - 1] = 1.0
        return row

    return times_speed


def _without_tr(mapper):
    """An exciter's ``mapper`` with T_R = 0: ANDES 2.0's ESDC2A and EXAC1 take their
    voltage error from the bus voltage itself, not the transducer lag (``esdc2a.py``,
    ``exac1.py``: ``vi = vref - v - WF_y``)."""

    def without_tr(rec, gen):
        row = mapper(rec, gen)
        row[EXCITER.col("TR") - 1] = 0.0
        return row

    return without_tr


def _esst3a_psse(rec, gen):
    """ESST3A as the PSS/E Model Library states it: `_esst3a` with its rectifier loading
    ``I_N = K_C I_FD / V_E`` the machine's own field current (PSS/E's XadIfd; ANDES 2.0
    ``esst3a.py`` lines 190-191 alike), as at initialisation, not PST exc_st3's estimate
    (exc_con column 25 = 1): read with the estimate, ANDES's IEEE 14 DYR started off
    equilibrium (0.03 on a V_R derivative)."""
    row = _esst3a(rec, gen)
    row[EXCITER.col("ifd_machine") - 1] = 1.0
    return row


def _gensal_andes(rec, gen):
    """GENSAL as ANDES 2.0 reads it (``psse-dyr.yaml``): its GENROU with X'q = X'd,
    T'qo = T'do and X''q = X''d."""
    v = DYR_MODELS["GENSAL"].values(rec.params)
    _positive_h(rec, v["H"])
    _leakage_noted(rec, v)
    _zsorce_noted(rec, gen, v["X''d"])
    return _mac_row(rec, gen, xqp=v["X'd"], Tqop=v["T'do"], xqpp=v["X''d"])


def _andes_lacks_noted(rec) -> None:
    """With conventions="andes", a record of a model ANDES 2.0 lacks and no ANDES reading
    of stabctl's replaces (DEGOV, GGOV1, PSS2A, ...: `DyrModel.andes` empty, none of
    `_ANDES_MAPPERS`) is read as PSS/E's Model Library reads it: said in `DyrTables.changed`
    (round 55 AQ25: it was said of an SCRX read as ANDES's SEXS, not of these)."""
    if not DYR_MODELS[rec.model].andes and rec.model not in _ANDES_MAPPERS:
        _read_as(
            rec,
            f"ANDES 2.0 has no {rec.model}: read as PSS/E's Model Library reads it (no ANDES "
            "reading to compare like for like)",
        )


def _not_in_andes(rec, gen):
    """A PSS/E model ANDES 2.0 lacks (GENROE, GENSAE): nothing to compare like for like."""
    raise _Unsupported(
        f"ANDES 2.0 has no {rec.model} (read it with the psse or pst DYR conventions)"
    )


#: conventions="andes": ANDES 2.0's DC exciters (IEEEX1, EXDC2, ESDC2A) use the quadratic
#: saturation and keep K_E = 0; its EXDC2 limits V_R to [VRMIN, VRMAX], not scaled by the
#: terminal voltage as PSS/E's and IEEE DC2 (and times the rotor speed,
#: `_times_speed`), and so does its IEEEX1 (PST's DC1): ANDES
#: 2.0's ``ieeex1.py`` defines VRTMAX = VRMAX v and sets ``LA.upper``, ``LA.lower`` to
#: them after EXDC2's ``LagAntiWindup`` LA has built its ``AntiWindup`` limiter
#: ``LA.lim`` on VRMAX, VRMIN; the limiter keeps those (on NPCC ``LA.lim.upper.v`` =
#: VRMAX, e.g. 6.5 for bus 25, where VRTMAX = 6.89), so the scaled limits are never
#: applied (read as DC2, NPCC differed from ANDES by 6.2e-3 pu in speed); its ESDC2A and
#: EXAC1 bypass T_R;
#: its IEEEG1 rate limits are on the system base, its ESST3A forms V_E from system-base
#: stator currents and I_N from the machine's field current; its GENROU (and GENSAL)
#: saturates the air-gap flux (``genrou.py``, the machine rows' column 25, set in
#: `_map_records`); GENSAL is its GENROU, SCRX its SEXS; HYGOV
#: and IEESGO as ANDES solves them (``_hygov``, ``_ieesgo``); IEEET2, which ANDES lacks,
#: with the quadratic saturation of its other DC exciters
_ANDES_MAPPERS = {
    "IEEEX1": _dc("IEEEX1", andes=True),
    "EXDC2": _times_speed(_dc("IEEEX1", andes=True)),
    #: ESDC2A: also the quadratic saturation and K_E as given
    "ESDC2A": _without_tr(_dc("ESDC2A", zero_vrmax_unlimited=True, andes=True)),
    #: ESDC1A: ESDC2A with V_R limits not scaled by V_t (``esdc1a.py``), i.e. DC1
    "ESDC1A": _without_tr(_dc("ESDC1A", zero_vrmax_unlimited=True, andes=True)),
    "EXAC1": _without_tr(_exc_row),
    "ESST1A": lambda rec, gen: _esst1a(rec, gen, andes=True),
    #: ESST3A: PSS/E's (the machine's field current, `_esst3a_psse`) with its source
    #: voltage from the stator current on the system base, as ANDES 2.0 solves it
    #: (`_source_on_system_base`, ``esst3a.py``)
    "ESST3A": _source_on_system_base(_esst3a_psse),
    "IEEET3": _source_on_system_base(_ieeet3),
    #: ESST4B: ANDES's VGMAX, 20 (its default; stabctl.io.andes_case refuses others)
    "ESST4B": _source_on_system_base(lambda rec, gen: _esst4b(rec, gen, vgmax=20.0, psse=0.0)),
    "GENSAL": _gensal_andes,
    "GENROE": _not_in_andes,
    "GENSAE": _not_in_andes,
    "SCRX": _scrx_andes,
    "IEEET1": _dc("IEEET1", zero_vrmax_unlimited=True, andes=True),
    "IEEET2": _dc("IEEET2", andes=True),
    "HYGOV": lambda rec, gen: _hygov(rec, gen, andes=True),
    "IEESGO": lambda rec, gen: _ieesgo(rec, gen, andes=True),
}
#: conventions="psse": each machine's mac_con psse_sat and psse_swing
#: (stabctl.models.machines.MACHINE), with speed_effects 0 (stator at rated speed):
#: GENROU's quadratic, GENROE's and GENSAE's exponential saturation of the air-gap flux
#: |psi"| on both axes, GENSAL's quadratic saturation of E'q on the d axis only (PSS/E
#: Model Library; GENSAE's q-axis saturation, which GENSAL lacks, sets its initial rotor
#: angle: 33.49 deg in PSS/E's run tests/data/psse_runs/GENSAE, 35.49 without), with the
#: swing equation (P_m - D (omega - 1)) / omega - T_e; GENCLS neither: PSS/E's run
#: OMIB_GENCLS agrees with P_m - T_e - D (omega - 1) (1.1e-3 rad at a 1 ms step, 2.3e-3
#: rad with the divided form, the Julia test's tolerance being 2e-3)
_PSSE_MACHINE = {
    "GENROU": (1.0, 1.0),
    "GENROE": (2.0, 1.0),
    "GENSAL": (3.0, 1.0),
    "GENSAE": (4.0, 1.0),
    "GENCLS": (0.0, 0.0),
}


def _exst1_psse(rec, gen):
    """EXST1 as the PSS/E Model Library solves it (exc_con psse_st1 = 1): its output
    limits [V_t VRMIN - K_C I_fd, V_t VRMAX - K_C I_fd] and its rate feedback of V_R
    before them (OpenIPSL's PSS/E-verified ``PSSE.ES.EXST1``; PowerSimulationsDynamics.jl's
    EXST1, within 1e-3 pu of PSS/E's run tests/data/psse_runs/EXST1)."""
    return _exc_row(rec, gen, psse_st1=1.0)


#: conventions="psse": the controls whose PSS/E Model Library equations differ from
#: stabctl's own reading (the others as "pst"; docs/pst_models.md 12.6)
_PSSE_MAPPERS = {
    "IEEEX1": _dc("IEEEX1", psse=True),
    "EXDC2": _dc("EXDC2", psse=True),
    "ESDC2A": _dc("ESDC2A", zero_vrmax_unlimited=True, psse=True),
    "ESDC1A": _dc("ESDC1A", zero_vrmax_unlimited=True, psse=True),
    "IEEET1": _dc("IEEET1", zero_vrmax_unlimited=True, psse=True),
    "IEEET2": _dc("IEEET2", psse=True),
    "EXST1": _exst1_psse,
    "ESST1A": lambda rec, gen: _esst1a(rec, gen, psse=True),
    "ESST3A": _esst3a_psse,
    "HYGOV": lambda rec, gen: _hygov(rec, gen, psse=True),
}
#: conventions -> the mappers that replace `_MAPPERS`' for it
_CONVENTION_MAPPERS = {"andes": _ANDES_MAPPERS, "psse": _PSSE_MAPPERS}
CONVENTIONS = ("psse", "pst", "andes")
_WIDTH = {kind: len(family.params) for kind, family in FAMILY.items()}
