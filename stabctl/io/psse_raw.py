"""PSS/E RAW power-flow data (versions 32 to 36) as stabctl's PST tables.

Source of the record layouts: PSS/E Program Operation Manual (POM), chapter "Power Flow
Raw Data File Contents" of versions 32 and 33 (sections "Case Identification Data", "Bus
Data", "Load Data", "Fixed Shunt Data", "Generator Data", "Non-Transformer Branch Data",
"Transformer Data", "Switched Shunt Data"); for versions 34, 35 and 36 the column
headings (``@!`` lines) PSS/E writes above each section of its RAW exports (rawd34,
rawd35, PSS/E Xplore 36.1); MATPOWER's ``psse_convert_xfmr`` for the transformer base
conversions.

Versions: v34 adds the system-wide data (before the buses), the system switching devices
(after the branches), the substations (last), a NAME and 12 ratings in branches and
transformer windings, DGENP, DGENQ, DGENM at the end of loads, NREG at the end of
generators and switched shunts and NOD at the end of transformer windings. v35 keeps
v34's sections and moves NREG after IREG (generators, which also gain BASLOD after PB)
and after SWREG (switched shunts, which also gain their ID after I: several per bus, and
a status per block), NOD after CONT (transformer windings); loads gain LOADTYPE at their
end. From v34 on, ``@!`` lines may precede the case identification and strings may be
in double quotes. v36 adds the sections voltage droop control (after the fixed
shunts), switching device rating sets (after the generators), load types, interfaces and
interface elements (before the substations), NAME fields at the end of loads, fixed
shunts and generators (after WMOD, WPF, DROOPNAME) and after the switched shunt's BINIT.
The case identification is IC, SBASE, REV, XFRRAT, NXFRAT, BASFRQ in every version.

Read (everything in per unit on the system base ``SBASE`` after conversion):

* case identification: SBASE, version, BASFRQ (60 Hz when absent), the two title lines;
* buses: number, BASKV, IDE (1 load, 2 generator, 3 swing; 4 isolated buses are dropped
  with every record at them, as PSS/E leaves them out of the solution), VM, VA; the
  records dropped so, and those out of service (status 0), are each named with why
  (:attr:`RawData.switched_off`); an IDE 2 bus without a generator in service is a load
  bus (PSS/E's type 1), named in :attr:`RawData.load_buses`;
* loads (in service): PL + jQL constant power, IP + jIQ constant current (MW/Mvar at
  1 pu), YP + jYQ constant admittance (MW/Mvar at 1 pu, YQ < 0 inductive). The admittance
  part is exact as a bus shunt ``G + jB = (YP + jYQ) / SBASE``. The constant-current part
  enters the bus load at the bus's RAW voltage VM (``IP * VM``), as PST and ANDES do. In
  the dynamic run (PSS/E converts loads with CONL before dynamics; the RAW file does not
  say how): ``loads="impedance"`` (default) makes every bus load constant impedance (no
  ``load_con`` rows: PST's default, ANDES's default ``p2z = q2z = 1``); ``loads="raw"``
  keeps the RAW composition in PST's non-conforming load model (``load_con``):
  ``p_power = PL / (PL + IP*VM)``, ``p_current = IP*VM / (PL + IP*VM)`` (Q alike). PST's
  network solution can fail under deep voltage dips with constant-power loads (PSS/E
  switches them to constant impedance below PQBRAK; stabctl does not);
* fixed shunts (in service): GL + jBL (MW/Mvar at 1 pu) into the bus shunt;
* generators (in service): PG, QG, QT, QB, VS, IREG, MBASE, ZSORCE = ZR + jZX (pu on
  MBASE). Several generators at one bus add up; the bus is PV (IDE 2) or swing (IDE 3) at
  VS, with Q limits the sums of QT and QB (a sum of exactly 0 is a limit at 0 in PSS/E
  but "no limit" in PST's bus table: it is written as +-1e-9 pu, :data:`ZERO_Q_LIMIT`).
  An IDE 2 bus without generator in service is a load bus. A wind machine's Q limits
  come from PG and WPF (POM Generator Data): WMOD 2 +-|PG| tan(acos |WPF|), WMOD 3 both
  PG tan(acos |WPF|) with the sign of WPF (a fixed Q), named in ``changed``; QT and QB
  are not used then. Generators the caller nets
  (``net``: those without a machine model in the DYR data, PSS/E's netting) are a
  negative constant-power load PG + jQG at their bus instead (its composition in the
  dynamic run as the bus's loads, above), and leave the bus's Q limits;
* remote voltage regulation (IREG of a load bus, IDE 1): the plant holds that bus at VS
  and its own bus floats (PSS/E's power flow; `stabctl.case.RegulationTable`, one row per
  plant bus, its share the plant's RMPCT over the sum of the plants regulating the bus);
  an IREG naming a generator bus, an isolated bus or given at the swing bus is PSS/E's
  own-bus regulation, listed in ``changed``; the machines of one bus take one IREG;
* non-transformer branches (in service): R, X, B; line shunts GI + jBI, GJ + jBJ at their
  ends (``line`` columns 11-14, switched with the branch; the ``line`` matrix has these
  columns only when a branch has them);
* two-winding transformers (in service): CW 1 (pu of bus base kV), 2 (kV), 3 (pu of
  NOMV); CZ 1 (system base), 2 (SBASE1-2 and NOMV1 base), 3 (load loss W and |Z|);
  WINDV1, WINDV2, ANG1. The circuit bus I - ideal t1:1 - Z - ideal 1:t2 - bus J is PST's
  branch with tap t1/t2 on the I side and impedance Z*t2^2 (MATPOWER's convention when
  t2 = 1); the phase is PST's, the opposite sign of ANG1 (:mod:`stabctl.network.ybus`). Taps
  stay at WINDV (automatic adjustment COD is not modelled, as ANDES; a winding with COD
  > 0, which PSS/E would adjust, is named in :attr:`RawData.held`); the magnetizing
  admittance is a shunt at the winding-1 bus, switched with the transformer (``line``
  columns 11-12; MATPOWER's ``psse_convert_xfmr`` puts it at that bus too): CM 1, MAG1 +
  jMAG2 in pu on SBASE; CM 2, the no-load loss MAG1 (W) and exciting current MAG2 (pu on
  SBASE1-2 at NOMV1), G = MAG1/(1e6 SBASE) and B = -sqrt(|Y|^2 - G^2) with |Y| = MAG2
  SBASE1-2/SBASE, both times (BASKV1/NOMV1)^2 (POM Transformer Data); impedance correction
  tables (TAB1) are unsupported;
* three-winding transformers (STAT 1 all windings in service; 2, 3, 4 winding 2, 3, 1
  out; 0 all out): PSS/E's star equivalent (POM "Three-Winding Transformer Data"; MATPOWER's
  ``psse_convert_xfmr``, powsybl's PSS/E converter): a star-point bus numbered above every
  bus of the file (in file order of the transformers, PQ, no base kV, at VMSTAR/ANSTAR) and
  per winding w a branch bus w - ideal t_w:1 - Z_w - star point, with t_w from CW, WINDV_w,
  NOMV_w as for two windings, phase -ANG_w, and the star impedances from the measured
  pair impedances (each on its SBASE and winding base by CZ, as above):
  ``Z1 = (Z12 + Z31 - Z23)/2``, ``Z2 = (Z12 + Z23 - Z31)/2``, ``Z3 = (Z23 + Z31 - Z12)/2``,
  so that the impedance measured between two windings' buses with the third open is the
  RAW's. The magnetizing admittance (CM 1 or 2) is at the winding-1 bus, as for two windings;
* switched shunts (in service): fixed at BINIT (Mvar at 1 pu) into the bus shunt; one
  with MODSW other than 0, which PSS/E would switch, is named in :attr:`RawData.held`.

Read without use, counted by section in :attr:`RawData.unused` (the import's summary
names them): area, zone, owner and inter-area transfer data, multi-section line
groupings (their sections are branch records, read as such), substations without
node-breaker data (a name and a place), v36 switching device rating sets, load types,
interfaces and interface elements (names, ratings and monitoring definitions).  Skipped
without a word: the system-wide data
(v34 and later: solution settings GENERAL, GAUSS, NEWTON, ADJUST, TYSL, SOLVER and
rating-set names RATING, SWDRATNAM, which do not change the case; each record must start
with its keyword, so a file without the ``0 /`` record that ends them is refused rather
than read with its buses taken for settings). Unsupported, reported as
``file:line record: what it is: what a run lacks`` (a dc line with its name, buses and
setting, a FACTS device with its buses): dc lines, FACTS, GNE devices (POM v33 "GNE Device
Data": one record of 'NAME', 'MODEL', NTERM, BUS1 to BUSNTERM, NREAL, NINTG, NCHAR, then
STATUS, OWNER, NMETR, then the NREAL REAL, NINTG INTG and NCHAR CHAR values, each kind on
lines of up to ten; named with their model and buses), induction machines, system
switching devices and substations with node-breaker data (nodes, switching devices,
terminals; v34 and later), v36 voltage droop controls, loads with distributed generation
in service (v34 and later: DGENM 1 with DGENP or DGENQ not 0), generators with a step-up
transformer in the record (RT, XT) or an IREG other than the first generator's of their
bus, and the transformer features above.

Refused as ``file:line record: what``, the field by its POM name with its value as the
file writes it: a status other than 0 (out of service) or 1 (in service) of a load, fixed
shunt, generator, branch, two-winding transformer or switched shunt (a three-winding
transformer's STAT: 0 to 4), a bus number I outside PSS/E's 1 to :data:`MAX_BUS` (the
other records' buses must be in the bus data), and the codes and limits outside the POM's
ranges, read by stabctl or not: a transformer's CW, CZ, CM, NMETR, ZCOD, COD and under
control its CONT bus, RMA/RMI and VMA/VMI (:func:`_check_transformer`), a branch's MET, a
generator's GTAP, RMPCT, PT/PB, ownership fractions, WMOD and WPF
(:func:`_check_generator`), a switched shunt's MODSW, ADJM, BINIT against its blocks and
under control VSWHI/VSWLO and its regulated bus (:func:`_check_switched_shunt`). A record
of several lines names the file
line of the field at fault and which line of the record it is (``(line 3 of the
record)``).

Bus numbers stay as in the RAW file. Branch rows: lines in file order, then transformers
(a three-winding one as its windings' branches, winding 1 first); ``--circuit K`` of
stabctl's commands is the K-th record of a bus pair in that order.
"""

from __future__ import annotations

import builtins
import math
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import NamedTuple, NoReturn, cast

import numpy as np

from stabctl.case import PQ, PV, SWING
from stabctl.errors import CaseError, advice
from stabctl.io.inputs import case_text, input_file, plain_float

__all__ = ["RawSource", "Held", "Generator", "RawData", "read_raw", "split_fields"]

_SECTIONS: dict[int, tuple[str, ...]] = {
    32: (
        "bus",
        "load",
        "fixed shunt",
        "generator",
        "branch",
        "transformer",
        "area",
        "two-terminal dc line",
        "vsc dc line",
        "impedance correction table",
        "multi-terminal dc line",
        "multi-section line",
        "zone",
        "inter-area transfer",
        "owner",
        "facts device",
        "switched shunt",
        "gne device",
    ),
}
_SECTIONS[33] = _SECTIONS[32] + ("induction machine",)
_SECTIONS[34] = (
    (
        "system-wide data",
        "bus",
        "load",
        "fixed shunt",
        "generator",
        "branch",
        "system switching device",
        "transformer",
    )
    + _SECTIONS[32][6:]
    + ("induction machine", "substation")
)
_SECTIONS[35] = _SECTIONS[34]
_SECTIONS[36] = (
    (
        "system-wide data",
        "bus",
        "load",
        "fixed shunt",
        "voltage droop control",
        "generator",
        "switching device rating set",
        "branch",
        "system switching device",
        "transformer",
    )
    + _SECTIONS[32][6:]
    + ("induction machine", "load type", "interface", "interface element", "substation")
)

_SKIPPED = {
    "multi-section line",  # its sections are branch records, read as such
    "area",
    "zone",
    "inter-area transfer",
    "owner",
    "impedance correction table",
    "switching device rating set",
    "load type",
    "interface",
    "interface element",
}
#: what the summary adds to a count of records read without use
_UNUSED_NOTE = {
    "multi-section line": ": groupings of branch records, whose sections are read as the "
    "branches they are (a trip names one section, not the grouping's '&' id)",
}
#: first words of the system-wide data records (v34: GENERAL to RATING; v36 adds SWDRATNAM)
_SYSTEM_WIDE = ("GENERAL", "GAUSS", "NEWTON", "ADJUST", "TYSL", "SOLVER", "RATING", "SWDRATNAM")
_IDE_ISOLATED = 4
#: the largest bus number PSS/E takes (POM Bus Data: I, 1 to 999997)
MAX_BUS = 999997
#: largest magnitude of a RAW number (bus numbers, MW, kV, pu alike are far below)
_LARGEST = 1e12
_TOKEN = re.compile(r"'[^']*'?|/|,|[^,\s'/]+")
#: v34 and later: character data in single or double quotes (rawd34 and later write the
#: names of dc lines, FACTS devices and the rating sets of the system-wide data in double
#: quotes)
_TOKEN_34 = re.compile(r"'[^']*'?|\"[^\"]*\"?|/|,|[^,\s'\"/]+")


@dataclass(frozen=True)
class RawSource:
    """Where a record is: file, 1-based line, record name (``"generator at bus 3 '1'"``)."""

    file: str
    line: int
    record: str

    def __str__(self) -> str:
        return f"{self.file}:{self.line} {self.record}"


class Held(NamedTuple):
    """A record a summary names by kind and place (:func:`stabctl.io.psse.held_lines`):
    ``kind`` (``"switched shunt"`` or ``"transformer"`` held at its RAW setting, its
    automatic control not modelled; ``"IDE 2 bus"`` read as a load bus), ``at`` (its bus,
    or its buses joined by ``-``) and ``source`` (:class:`RawSource`, the record named
    with why)."""

    kind: str
    at: str
    source: RawSource


@dataclass(frozen=True)
class Generator:
    """One in-service generator of the RAW file (RAW order).

    Attributes: number (1-based position, the machine number of ``mac_con``), bus, id
    (the RAW ID, stripped), mbase (MVA), ra and xsource (ZSORCE, pu on MBASE), pg and qg
    (MW, Mvar, as in the RAW), source (:class:`RawSource`).
    """

    number: int
    bus: int
    id: str
    mbase: float
    ra: float
    xsource: float
    pg: float
    qg: float
    source: RawSource

    def as_dyr(self) -> dict:
        """The dict ``stabctl.io.dyr.dyr_tables`` takes for this generator (pg and qg split
        a bus's generation among its machines; ``zsorce``: its xsource is a RAW's ZSORCE,
        which a subtransient machine's X''d should equal)."""
        return {
            "number": self.number,
            "bus": self.bus,
            "id": self.id,
            "mbase": self.mbase,
            "ra": self.ra,
            "xsource": self.xsource,
            "zsorce": True,
            "pg": self.pg,
            "qg": self.qg,
        }


@dataclass(frozen=True, eq=False)
class RawData:
    """A RAW file as PST matrices.

    Attributes:
        name: case name (file stem); title: the two title lines joined by " / ".
        version: RAW version (32 to 36); base_mva: SBASE (MVA); freq_hz: BASFRQ (Hz).
        bus: PST ``bus`` matrix, shape (n_bus, 15) (:class:`stabctl.case.BusTable`).
        line: PST ``line`` matrix, shape (n_branch, 10), or (n_branch, 14) when a branch
            has line-end shunts (:class:`stabctl.case.BranchTable` columns 11-14).
        load_con: PST ``load_con`` rows, shape (n, 5) (empty unless ``loads="raw"``).
        generators: in-service generators in RAW order (the netted ones left out).
        unsupported: records that could not be represented, in file order.
        netted: the in-service generators netted as negative loads (``read_raw``'s
            ``net``), in file order, each record named with the reason.
        out_of_service: (bus, ID) of the generators out of service (STAT 0) or at an
            isolated bus: PSS/E ignores their dynamic records.
        switched_off: the records PSS/E leaves out of the network, in file order, each
            named with why: the isolated buses (IDE 4), the records at them, and the
            loads, shunts, generators, branches and transformers out of service (status
            0; a three-winding transformer with fewer than two windings in service).
        solution: the file's own power-flow solution, shape (n, 3): bus number, VM (pu),
            VA (degrees) of each bus record not isolated, in file order (the ``bus``
            matrix holds VS at generator buses instead; no three-winding star points).
        vreg_con: remote voltage regulation (:class:`stabctl.case.RegulationTable`
            rows: generator bus, regulated bus, VS, share), shape (n, 4).
        changed: records read otherwise than they say, each named with the reason
            (a plant whose IREG bus is a generator bus regulates its own bus, a wind
            machine's Q limits come from WMOD and WPF, as PSS/E).
        netted_ids: (bus, ID) of the generators in ``netted``.
        held: the records in the network whose control PSS/E would adjust and stabctl
            holds at their RAW setting (:class:`Held`), in file order: switched shunts
            with MODSW other than 0 at BINIT, transformers with a winding's COD > 0 at
            their ratio and angle.
        load_buses: the IDE 2 buses without a generator in service (none, or all
            netted), read as load buses as PSS/E reads them (:class:`Held`, kind
            ``"IDE 2 bus"``), in file order.
        circuit_order: the pairs of buses whose parallel branches' CKT ids are not '1',
            '2', ... in file order, each with which id the commands' circuit K is
            (``"1-4 (in file order :1 is 'A', :2 is '7')"``).
    """

    name: str
    title: str
    version: int
    base_mva: float
    freq_hz: float
    bus: np.ndarray
    line: np.ndarray
    load_con: np.ndarray
    generators: tuple[Generator, ...]
    unsupported: tuple[RawSource, ...]
    netted: tuple[RawSource, ...] = ()
    out_of_service: frozenset[tuple[int, str]] = frozenset()
    switched_off: tuple[RawSource, ...] = ()
    solution: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    vreg_con: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)))
    changed: tuple[RawSource, ...] = ()
    #: records kept as written though they look wrong, each named with why (a bus's
    #: voltage limits inverted, which stabctl does not use; a branch of negative R, as a
    #: network equivalent's; a branch at or below PSS/E's zero-impedance threshold,
    #: `THRSHZ`, kept as its impedance): PSS/E reads them too (round 41: without a word)
    noted: tuple[RawSource, ...] = ()
    #: the records of each section read but of no use to a run (area, zone, owner and
    #: inter-area transfer data, ...: `_SKIPPED`), one text a section: "N area record(s)
    #: (FILE:a-b)" (round 42: left out without a word)
    unused: tuple[str, ...] = ()
    netted_ids: frozenset[tuple[int, str]] = frozenset()
    held: tuple[Held, ...] = ()
    load_buses: tuple[Held, ...] = ()
    circuit_order: tuple[str, ...] = ()
    #: how the loads are read for the dynamic run, where it is not the RAW's composition
    #: ("" where nothing changes): the loads with constant-power or constant-current
    #: parts made constant impedance (``loads="impedance"``)
    load_model: str = ""

    def matrices(self) -> dict:
        """PST matrices by name (``bus``, ``line``, ``load_con``, ``basmva``, ``sys_freq``,
        ``vreg_con`` when a plant regulates a remote bus) for
        :func:`stabctl.io.pst.case_from_matrices`."""
        return {
            "bus": self.bus,
            "line": self.line,
            "load_con": self.load_con,
            "basmva": self.base_mva,
            "sys_freq": self.freq_hz,
            **({"vreg_con": self.vreg_con} if len(self.vreg_con) else {}),
        }


# --------------------------------------------------------------------------------------
# tokens and records
# --------------------------------------------------------------------------------------


def split_fields(text: str, double_quotes: bool = False) -> list[str]:
    """Fields of one RAW data line (POM "Power Flow Raw Data File Contents"): separated by
    commas or blanks, ``'...'`` strings kept whole (quotes removed, blanks inside kept),
    a ``/`` outside quotes starts a comment; two commas in a row give an empty field (the
    PSS/E default value). ``double_quotes`` (RAW v34 and later) also keeps ``"..."``
    strings whole."""
    fields, expect_value = [], True
    for tok in (_TOKEN_34 if double_quotes else _TOKEN).findall(text):
        if tok == "/":
            break
        if tok == ",":
            if expect_value:
                fields.append("")
            expect_value = True
        else:
            quoted = tok[0] == "'" or (double_quotes and tok[0] == '"')
            fields.append(tok[1:].removesuffix(tok[0]) if quoted else tok)
            expect_value = False
    return fields


def unclosed_quote(text: str, double_quotes: bool = False) -> int | None:
    """The 0-based column of a quote that opens a string and is not closed before the end
    of the line (or of its data, at a ``/`` comment), None if every string is closed:
    such a name runs to the end of the line and takes the fields after it with it.

    Parameters
    ----------
    text : str
        One RAW data line.
    double_quotes : bool, optional
        RAW v34 and later: ``"..."`` strings too (as `split_fields`).

    Returns
    -------
    int or None
    """
    quotes = "'\"" if double_quotes else "'"
    for m in (_TOKEN_34 if double_quotes else _TOKEN).finditer(text):
        tok = m.group()
        if tok == "/":
            return None
        if tok[0] in quotes and (len(tok) == 1 or tok[-1] != tok[0]):
            return m.start()
    return None


_INTEGER = re.compile(r"[+-]?\d+")


@dataclass
class _Rec:
    """One RAW record: its lines' fields, the file and its first line number; ``at``: the
    file line of each record line, ``names``: the POM names of each line's fields
    (:data:`_NAMES`, set once the record is complete) to name a field in messages."""

    file: str
    line: int
    lines: list[list[str]]
    section: str = ""
    at: list[int] = field(default_factory=list)
    names: Sequence[Sequence[str | None]] = ()

    def name(self, row: int, k: int) -> str:
        """The POM name of field ``k`` (0-based) of line ``row``, else ``field {k + 1}``."""
        names = self.names[row] if row < len(self.names) else ()
        return (names[k] if k < len(names) else None) or f"field {k + 1}"

    def index(self, name: str, row: int = 0) -> int | None:
        """The 0-based position of the field the POM names ``name`` on line ``row``, None
        when the line is too short to hold it or the version's layout has no such field."""
        names = self.names[row] if row < len(self.names) else ()
        k = list(names).index(name) if name in names else None
        return k if k is not None and k < len(self.lines[row]) else None

    def written(self, row: int, k: int) -> str:
        """Field ``k`` of line ``row`` as the file writes it (stripped; '' if absent)."""
        vals = self.lines[row]
        return vals[k].strip() if k < len(vals) else ""

    def num(self, row: int, k: int, default: float | None = None) -> float:
        """Field ``k`` (0-based) of the record's line ``row`` as a float; a missing or
        empty field takes ``default`` (an error when None).  Errors name the field as the
        POM does (``VM``, ``RMA1``) with its text as written, at the line it is on."""
        vals = self.lines[row]
        if k >= len(vals) or vals[k] == "":
            if default is None:
                self.fail(f"{self.name(row, k)} missing", row)
            return float(default)
        what = (
            f"{self.name(row, k)} = '{vals[k].strip()}'"
            if vals[k].strip()
            else (f"{self.name(row, k)} blank")
        )
        try:
            v = plain_float(vals[k], fortran=True)
        except ValueError:
            self.fail(f"{what}: not a number (ASCII digits, no '_')", row)
        if not math.isfinite(v):
            self.fail(f"{what}: not a finite number", row)
        if abs(v) > _LARGEST:
            self.fail(f"{what}: out of range (|value| <= {_LARGEST:g})", row)
        return v

    def int(
        self, row: builtins.int, k: builtins.int, default: builtins.int | None = None
    ) -> builtins.int:
        """Field ``k`` of line ``row`` as an integer (see :meth:`num`): written as one,
        digits with an optional sign (PSS/E reads "3.0" in an integer field as an error)."""
        v = self.num(row, k, default)
        written = self.written(row, k)
        if written and not _INTEGER.fullmatch(written):
            self.fail(f"{self.name(row, k)} = '{written}': not an integer", row)
        return int(v)

    def text(self, row: builtins.int, k: builtins.int, default: str = "1") -> str:
        """Field ``k`` of line ``row`` as a stripped string (an ID)."""
        vals = self.lines[row]
        return vals[k].strip() if k < len(vals) and vals[k].strip() else default

    def shown(self, row: builtins.int, k: builtins.int, value: float) -> str:
        """Field ``k`` of line ``row`` as the file writes it, for a message about the
        value read from it; a field not given: ``blank (taken as {value})``."""
        return self.written(row, k) or f"blank (taken as {value:g})"

    def given(self, row: builtins.int, *ks: builtins.int) -> str:
        """``NAME = text, ...`` of fields ``ks`` of line ``row`` as the file writes them."""
        return ", ".join(f"{self.name(row, k)} = {self.written(row, k) or '(empty)'}" for k in ks)

    def source(self, what: str) -> RawSource:
        return RawSource(self.file, self.line, what)

    def fail(self, what: str, row: builtins.int = 0, whole: bool = False) -> NoReturn:
        """CaseError ``file:line section record: what`` at the file line of the record's
        line ``row``; a record of several lines (:data:`_MULTI_LINE`) also names which
        (``(line 3 of the record)``), whatever the line, unless the error is about the
        ``whole`` record (one cut short).  A record holding double quotes its version
        does not read as quotes is said to."""
        line = self.at[row] if row < len(self.at) else self.line + row
        multi = self.section in _MULTI_LINE and not whole
        which = f" (line {row + 1} of the record)" if multi else ""
        quotes = any('"' in f for fields in self.lines for f in fields)  # not read as quotes
        hint = (
            " (the record holds double quotes: before v34 a RAW file quotes its names "
            "with ' only, so a double-quoted name is split at its blanks)"
            if quotes
            else ""
        )
        raise CaseError(f"{self.file}:{line} {self.section} record{which}: {what}{hint}")


#: the sections whose records take several lines: their errors name the record's line
_MULTI_LINE = frozenset(
    {
        "transformer",
        "two-terminal dc line",
        "vsc dc line",
        "multi-terminal dc line",
        "substation",
        "gne device",
    }
)
#: the POM names of the first line of a multi-terminal dc line record
_MTDC = ("NAME", "NCONV", "NDCBS", "NDCLN", "MDC", "VCONV", "VCMOD", "VCONVN")
#: the POM names of the first fields of a GNE device record
_GNE_FIRST = ("NAME", "MODEL", "NTERM")


def _header(lines: list[str], path: Path) -> tuple[float, int, float, int, list]:
    """(SBASE, version, BASFRQ, index of its line, the defaults taken) from the case
    identification record: IC, SBASE, REV, XFRRAT, NXFRAT, BASFRQ (the same six fields in
    v32-v36), after the ``@!`` column-heading lines PSS/E 35 and later write above it.  IC
    must be 0 (a new case): 1 is a change file, which PSS/E adds to the case in its
    working memory.  A blank REV (read as 33) or BASFRQ (60 Hz) is named (RawSource, for
    ``changed``; round 43: taken without a word)."""
    first = next((i for i, t in enumerate(lines) if not t.lstrip().startswith("@!")), len(lines))
    if len(lines) < first + 3:
        raise CaseError(
            f"{path}:{first + 1} case identification: a RAW file starts with three lines "
            "(after its '@!' column headings)"
        )
    rec = _Rec(path.name, first + 1, [split_fields(lines[first])], "case identification")
    rec.names = (("IC", "SBASE", "REV", "XFRRAT", "NXFRAT", "BASFRQ"),)
    sbase, rev, freq = rec.num(0, 1), rec.int(0, 2, 33), rec.num(0, 5, 60.0)
    ic = rec.int(0, 0, 0)
    if ic != 0:
        rec.fail(
            f"IC {rec.written(0, 0)}: "
            + (
                "the file holds changes to add to a case in PSS/E's working memory (IC 1), "
                "not a whole case: import the base case (IC 0)"
                if ic == 1
                else "not a change code of the POM (0: a new case, 1: changes to a case)"
            )
        )
    if rev not in _SECTIONS:
        rec.fail(f"RAW version {rev} is not supported (32, 33, 34, 35 or 36)")
    if sbase <= 0 or freq <= 0:
        rec.fail(f"SBASE {rec.written(0, 1)} MVA and BASFRQ {rec.shown(0, 5, freq)} Hz must be > 0")
    fields = rec.lines[0]
    defaults = [
        rec.source(f"case identification: {name} not given: read as {value}")
        for k, name, value in ((2, "REV", "version 33"), (5, "BASFRQ", "60 Hz (the POM's default)"))
        if k >= len(fields) or not fields[k].strip()
    ]
    return sbase, rev, freq, first, defaults


def _record_lines(sec: str, first: list[str], rec_file: str, lineno: int) -> int:
    """Lines of a record that starts with ``first`` in section ``sec``; 0 for a substation
    (v34 and later), whose record is followed by its node, switching device and terminal
    data, each ending with a ``0`` record (the record holds them all).  A multi-terminal
    dc line ('NAME', NCONV, NDCBS, NDCLN, ...) is followed by its NCONV converter, NDCBS
    dc bus and NDCLN dc link lines (POM Multi-Terminal DC Transmission Line Data): one
    record, not one per line."""
    if sec == "transformer":
        k = _Rec(rec_file, lineno, [first], sec).int(0, 2, 0)
        return 5 if k != 0 else 4
    if sec == "multi-terminal dc line":
        rec = _Rec(rec_file, lineno, [first], sec, [lineno], (_MTDC,))
        counts = [rec.int(0, k) for k in (1, 2, 3)]
        for k, n in zip((1, 2, 3), counts):
            if n < 0:
                rec.fail(f"{_MTDC[k]} {rec.written(0, k)} must be >= 0")
        return 1 + sum(counts)
    if sec == "gne device":
        return _gne_lines(_Rec(rec_file, lineno, [first], sec, [lineno]))
    return {"two-terminal dc line": 3, "vsc dc line": 3, "substation": 0}.get(sec, 1)


#: values per GNE value line (POM GNE Device Data: up to 10 REAL, INTG or CHAR values a line)
_GNE_PER_LINE = 10
#: the kinds of a GNE record's value lines, in order
_GNE_VALUES = ("REAL", "INTG", "CHAR")


def _gne_counts(rec: _Rec) -> tuple[int, tuple[int, int, int]]:
    """NTERM and (NREAL, NINTG, NCHAR) of a GNE record's first line ('NAME', 'MODEL',
    NTERM, BUS1 ... BUSNTERM, NREAL, NINTG, NCHAR); CaseError naming the field for a
    count that is not an integer >= 0 (NTERM >= 1) or a line too short to hold them."""
    head = _Rec(rec.file, rec.line, rec.lines[:1], rec.section, rec.at[:1], (_GNE_FIRST,))
    nterm = head.int(0, 2)
    if nterm < 1:
        head.fail(f"NTERM {head.written(0, 2)} must be >= 1 (the buses the device connects)")
    head.names = (_gne_first(nterm),)
    if len(head.lines[0]) != 6 + nterm:
        head.fail(
            f"{len(head.lines[0])} field(s), its NTERM {nterm} needs {6 + nterm} ('NAME', "
            f"'MODEL', NTERM, {nterm} bus(es), NREAL, NINTG, NCHAR): a cut or merged line"
        )
    counts = tuple(head.int(0, 3 + nterm + k) for k in range(3))
    for k, n in enumerate(counts):
        if n < 0:
            head.fail(f"N{_GNE_VALUES[k]} {head.written(0, 3 + nterm + k)} must be >= 0")
    return nterm, (counts[0], counts[1], counts[2])


def _gne_first(nterm: int) -> tuple[str, ...]:
    """The POM names of a GNE record's first line with ``nterm`` buses."""
    return (*_GNE_FIRST, *(f"BUS{k}" for k in range(1, nterm + 1)), "NREAL", "NINTG", "NCHAR")


def _gne_lines(rec: _Rec) -> int:
    """Lines of a GNE record (POM GNE Device Data): its first line, STATUS, OWNER, NMETR,
    then its NREAL, NINTG and NCHAR values, each kind on lines of up to 10."""
    _, counts = _gne_counts(rec)
    return 2 + sum(-(-n // _GNE_PER_LINE) for n in counts)


def _gne_names(rec: _Rec) -> tuple[tuple[str, ...], ...]:
    """The POM names of each line of the complete GNE record ``rec``."""
    nterm, counts = _gne_counts(rec)
    lines = [_gne_first(nterm), ("STATUS", "OWNER", "NMETR")]
    for kind, n in zip(_GNE_VALUES, counts):
        names = [f"{kind}{k}" for k in range(1, n + 1)]
        lines += [tuple(names[k : k + _GNE_PER_LINE]) for k in range(0, n, _GNE_PER_LINE)]
    return tuple(lines)


#: data blocks after a substation record (node, switching device, terminal data), each
#: ending with a ``0`` record
_SUBSTATION_BLOCKS = 3


def _complete(rec: _Rec, need: int) -> bool:
    """True when ``rec`` has its ``need`` lines (0: its substation blocks' ``0`` records)."""
    if need:
        return len(rec.lines) == need
    return sum(line[:1] == ["0"] for line in rec.lines[1:]) == _SUBSTATION_BLOCKS


#: Fields per record line of the sections stabctl reads: (fewest, most), keyed by the
#: first version of each layout (it holds until the next key). The fewest are the fields
#: up to the last one the reader uses (a shorter line would silently take PSS/E defaults
#: for data that are in every file PSS/E writes); the most are the POM record layouts
#: (with ownership data), so that a record of another section is not read as one of this
#: section. v34: NREG at the end of generators and switched shunts (PSS/E's rawd34); v35:
#: NREG moved after IREG (and BASLOD after PB) in generators, after SWREG in switched
#: shunts, which also gain their ID (field 2) and a status per block; v36: a NAME at the
#: end of the fixed shunt, DROOPNAME and NAME at the end of the generator, a NAME after
#: the switched shunt's BINIT (the column headings PSS/E 36 writes), and one field more
#: after the branch's STAT than its heading shows (PSS/E Xplore 36.1's branch records).
_FIELDS: dict[str, dict[int, tuple[int, int]]] = {
    "bus": {32: (9, 13)},
    "load": {32: (11, 15), 34: (11, 20)},
    "fixed shunt": {32: (5, 5), 36: (5, 6)},
    "generator": {32: (15, 28), 34: (15, 29), 35: (16, 30), 36: (16, 32)},
    "branch": {32: (14, 24), 34: (24, 34), 36: (24, 35)},
    "switched shunt": {32: (10, 26), 34: (10, 27), 35: (12, 36), 36: (12, 37)},
}
#: transformer record lines (line 1, 2, 3, 4) of a two-winding transformer: (fewest, most)
_XFMR_FIELDS = {
    32: ((12, 23), (2, 3), (3, 18), (2, 2)),
    34: ((12, 24), (2, 3), (3, 28), (2, 2)),
}
#: record lines (1 to 5) of a three-winding transformer: (fewest, most)
_XFMR3_FIELDS = {v: (two[0], (11, 11), two[2], two[2], two[2]) for v, two in _XFMR_FIELDS.items()}


_OWNERS = ("O1", "F1", "O2", "F2", "O3", "F3", "O4", "F4")
_LOAD = ("I", "ID", "STATUS", "AREA", "ZONE", "PL", "QL", "IP", "IQ", "YP", "YQ", "OWNER")
_GEN = ("I", "ID", "PG", "QG", "QT", "QB", "VS", "IREG")
_GEN_TAIL = ("MBASE", "ZR", "ZX", "RT", "XT", "GTAP", "STAT", "RMPCT", "PT", "PB")
_BRANCH_34 = (
    ("I", "J", "CKT", "R", "X", "B", "NAME")
    + tuple(f"RATE{n}" for n in range(1, 13))
    + ("GI", "BI", "GJ", "BJ", "STAT")
)
_SWSH = ("MODSW", "ADJM")
_SWSH_REG = ("VSWHI", "VSWLO", "SWREG")
_BANKS = tuple(f"{x}{n}" for n in range(1, 9) for x in ("N", "B"))
_BANKS_35 = tuple(f"{x}{n}" for n in range(1, 9) for x in ("S", "N", "B"))
_XFMR1 = ("I", "J", "K", "CKT", "CW", "CZ", "CM", "MAG1", "MAG2", "NMETR", "NAME", "STAT")
_XFMR2 = ("R1-2", "X1-2", "SBASE1-2", "R2-3", "X2-3", "SBASE2-3", "R3-1", "X3-1", "SBASE3-1")


def _winding(w: int, version: int) -> tuple[str, ...]:
    """The POM names of a transformer's winding-``w`` line (WINDVw, NOMVw, ANGw, ...)."""
    if version >= 34:
        rates = tuple(f"RATE{w}-{n}" for n in range(1, 13))
    else:
        rates = tuple(f"{r}{w}" for r in ("RATA", "RATB", "RATC"))
    cont = ("COD", "CONT", "NOD") if version >= 35 else ("COD", "CONT")
    tail = ("RMA", "RMI", "VMA", "VMI", "NTP", "TAB", "CR", "CX", "CNXA")
    return (f"WINDV{w}", f"NOMV{w}", f"ANG{w}", *rates, *(f"{n}{w}" for n in cont + tail))


#: POM names of each record line's fields, keyed by the first version of each layout (as
#: :data:`_FIELDS`): to name a field in messages, and to check that every field that is a
#: number is written as one (:func:`_check_numbers`), read or not (a field past the names,
#: whose layout the POM leaves open, is not checked).  Character data: :data:`_TEXT`.
_NAMES: dict[str, dict[int, tuple[tuple[str, ...], ...]]] = {
    "bus": {
        32: (("I", "NAME", "BASKV", "IDE", "AREA", "ZONE", "OWNER", "VM", "VA")
             + ("NVHI", "NVLO", "EVHI", "EVLO"),),
    },
    "load": {
        32: (_LOAD + ("SCALE", "INTRPT"),),
        34: (_LOAD + ("SCALE", "INTRPT", "DGENP", "DGENQ", "DGENM"),),
        35: (_LOAD + ("SCALE", "INTRPT", "DGENP", "DGENQ", "DGENM", "LOADTYPE"),),
        36: (_LOAD + ("SCALE", "INTRPT", "DGENP", "DGENQ", "DGENM", "LOADTYPE", "NAME"),),
    },
    "fixed shunt": {
        32: (("I", "ID", "STATUS", "GL", "BL"),),
        36: (("I", "ID", "STATUS", "GL", "BL", "NAME"),),
    },
    "generator": {
        32: (_GEN + _GEN_TAIL + _OWNERS + ("WMOD", "WPF"),),
        34: (_GEN + _GEN_TAIL + _OWNERS + ("WMOD", "WPF", "NREG"),),
        35: (_GEN + ("NREG",) + _GEN_TAIL + ("BASLOD",) + _OWNERS + ("WMOD", "WPF"),),
        36: (
            _GEN + ("NREG",) + _GEN_TAIL + ("BASLOD",) + _OWNERS
            + ("WMOD", "WPF", "DROOPNAME", "NAME"),
        ),
    },
    "branch": {
        32: (
            ("I", "J", "CKT", "R", "X", "B", "RATEA", "RATEB", "RATEC", "GI", "BI", "GJ", "BJ")
            + ("ST", "MET", "LEN") + _OWNERS,
        ),
        34: (_BRANCH_34 + ("MET", "LEN") + _OWNERS,),
        #: v36: a field more after STAT than PSS/E's heading shows (MET, LEN, the owners
        #: or that field first): the rest named by position, each a number
        36: (_BRANCH_34 + tuple(f"field {n} (after STAT)" for n in range(25, 36)),),
    },
    "switched shunt": {
        32: (
            ("I",) + _SWSH + ("STAT", "VSWHI", "VSWLO", "SWREM", "RMPCT", "RMIDNT", "BINIT")
            + _BANKS,
        ),
        34: (
            ("I",) + _SWSH + ("STAT",) + _SWSH_REG + ("RMPCT", "RMIDNT", "BINIT") + _BANKS
            + ("NREG",),
        ),
        35: (
            ("I", "ID") + _SWSH + ("ST",) + _SWSH_REG + ("NREG", "RMPCT", "RMIDNT", "BINIT")
            + _BANKS_35,
        ),
        36: (
            ("I", "ID") + _SWSH + ("ST",) + _SWSH_REG
            + ("NREG", "RMPCT", "RMIDNT", "BINIT", "NAME") + _BANKS_35,
        ),
    },
}  # fmt: skip
#: the fields of :data:`_NAMES` that are character data, not numbers (and a GNE record's
#: CHAR values)
_TEXT = frozenset({"NAME", "ID", "CKT", "RMIDNT", "LOADTYPE", "DROOPNAME", "VECGRP", "MODEL"})


def _names(rec: _Rec, version: int) -> tuple[tuple[str, ...], ...]:
    """The POM names of each line of the complete record ``rec`` (() for a section
    stabctl does not read)."""
    if rec.section == "transformer":
        first = _XFMR1 + _OWNERS + ("VECGRP",) + (("ZCOD",) if version >= 34 else ())
        if len(rec.lines) == 4:
            return (first, _XFMR2[:3], _winding(1, version), ("WINDV2", "NOMV2"))
        lines = (first, _XFMR2 + ("VMSTAR", "ANSTAR"))
        return lines + tuple(_winding(w, version) for w in (1, 2, 3))
    if rec.section in _NAMES:
        return _layout(_NAMES[rec.section], version)
    if rec.section == "gne device":
        return _gne_names(rec)
    return ()


def _check_numbers(rec: _Rec) -> None:
    """CaseError naming the line, the field (:data:`_NAMES`) and its text for a field of
    ``rec`` that should be a number and is written otherwise (``1.1OOOO`` in RMA1), read
    or not (after the record's own reading, whose errors say more)."""
    for row, names in enumerate(rec.names[: len(rec.lines)]):
        for k, name in enumerate(names[: len(rec.lines[row])]):
            if name not in _TEXT and not (name or "").startswith("CHAR"):
                rec.num(row, k, 0.0)


def _layout(table: dict, version: int):
    """The entry of ``table`` (keyed by the first version of a layout) for ``version``."""
    return table[max(v for v in table if v <= version)]


def _check_fields(rec: _Rec, version: int) -> None:
    """CaseError naming file:line when a record line has fewer or more fields than its
    section's layout (a cut or merged line, or a record of another section)."""
    if rec.section in _FIELDS:
        limits: Sequence[tuple[int, int]] = [_layout(_FIELDS[rec.section], version)]
    elif rec.section == "transformer":
        limits = _layout(_XFMR_FIELDS if len(rec.lines) == 4 else _XFMR3_FIELDS, version)
    elif rec.section == "gne device":  # STATUS (OWNER, NMETR), then each line's values
        limits = [(len(n), len(n)) for n in _gne_names(rec)]
        limits[1] = (1, 3)
    else:
        return
    for row, ((lo, hi), vals) in enumerate(zip(limits, rec.lines)):
        if not lo <= len(vals) <= hi:
            want = f"{lo}" if lo == hi else f"{lo} to {hi}"
            rec.fail(
                f"{len(vals)} field(s), the v{version} layout has {want}: a "
                "cut or merged line, or a missing '0 /' section terminator",
                row,
            )


def _records(lines: list[str], path: Path, version: int, start: int):
    """Yield records (``_Rec``, with ``section``) of the data sections, in file order,
    from ``lines[start]`` on (the line after the two title lines).

    A record whose first field is ``0`` ends a section, ``Q`` ends the data wherever a
    record may start (PSS/E POM "Power Flow Raw Data File Contents": the sections not yet
    read are empty, e.g. a RAW ending with ``Q`` right after the transformer data), ``@!``
    lines (v34 and later: column headings) and blank lines are skipped. A file without
    ``Q`` must end after the last section's ``0`` record: a file cut short is refused
    (CaseError naming file:line), never read as a smaller case. Each record line must have
    its section's field count (:data:`_FIELDS`).
    """
    sections = _SECTIONS[version]
    k, pending, need, last = 0, None, 0, start
    for lineno, text in enumerate(lines[start:], start=start + 1):
        if not text.strip() or text.lstrip().startswith("@!"):
            continue
        last = lineno
        fields = split_fields(text, double_quotes=version >= 34)
        col = unclosed_quote(text, double_quotes=version >= 34)
        if col is not None:
            raise CaseError(
                f"{path.name}:{lineno}: the quote {text[col]} at column {col + 1} is not "
                f"closed (a name or ID would take the rest of the line): {text.strip()[:72]!r}"
            )
        if pending is not None:
            pending.lines.append(fields)
            pending.at.append(lineno)
            if _complete(pending, need):
                _check_fields(pending, version)
                pending.names = _names(pending, version)
                yield pending
                pending = None
            continue
        head = fields[0].strip() if fields else ""
        if head.upper() == "Q":
            return  # PSS/E: the sections not yet read are empty
        if k >= len(sections):
            raise CaseError(
                f"{path.name}:{lineno}: data after the last section "
                f"({sections[-1]}) and no 'Q' record"
            )
        if head == "0":
            k += 1
            continue
        pending = _Rec(path.name, lineno, [fields], sections[k], [lineno])
        need = _record_lines(sections[k], fields, path.name, lineno)
        if _complete(pending, need):
            _check_fields(pending, version)
            pending.names = _names(pending, version)
            yield pending
            pending = None
    if pending is not None:
        pending.fail(
            f"file ends inside the record ({len(pending.lines)} of {need} lines)"
            if need
            else "file ends inside the record (its node, switching device and terminal "
            "data must each end with a '0 /' record)",
            whole=True,
        )
    if k < len(sections):
        raise CaseError(
            f"{path.name}:{last}: the file ends in the {sections[k]} data, "
            "without its '0 /' terminator and the 'Q' record: the file is cut "
            "short (nothing imported)"
        )


# --------------------------------------------------------------------------------------
# building the tables
# --------------------------------------------------------------------------------------


@dataclass
class _Builder:
    """Accumulates the PST tables while the records are read."""

    version: int
    base: float
    loads: str
    buses: dict = field(default_factory=dict)  # number -> bus row (list of 15)
    load_src: dict = field(default_factory=dict)  # bus -> its first load record
    load_model: str = ""  # the loads' change of model for the dynamic run (`_load_con`)
    isolated: set = field(default_factory=set)
    load_parts: dict = field(default_factory=dict)  # bus -> [Pp, Qp, Pi, Qi]
    branches: list = field(default_factory=list)
    circuits: list = field(default_factory=list)  # the CKT of each row of branches
    gens: list = field(default_factory=list)
    gen_vs: dict = field(default_factory=dict)
    gen_ireg: dict = field(default_factory=dict)  # bus -> IREG of its first generator
    unsupported: list = field(default_factory=list)
    net: Callable[[int, str], str | None] | None = None  # (bus, id) -> why netted, or None
    netted: list = field(default_factory=list)  # (bus, RawSource) of netted generators
    netted_ids: list = field(default_factory=list)  # (bus, ID) of netted generators
    out_of_service: list = field(default_factory=list)  # (bus, ID) of generators
    switched_off: list = field(default_factory=list)  # RawSource of records out of the network
    seen: dict = field(default_factory=dict)  # (section, ids) -> first line
    stars: int = 0  # star-point buses of three-winding transformers so far
    base_kv: dict = field(default_factory=dict)  # bus number -> BASKV (isolated ones too)
    solution: dict = field(default_factory=dict)  # bus number -> (VM, VA deg) of the file
    #: generator bus -> [IREG, VS, sum of RMPCT, first record] of a plant regulating a
    #: remote bus
    remote: dict = field(default_factory=dict)
    changed: list = field(default_factory=list)  # RawSource of records read otherwise
    noted: list = field(default_factory=list)  # RawSource of records kept that look wrong
    held: list = field(default_factory=list)  # Held: controls not modelled, at their setting
    load_buses: list = field(default_factory=list)  # Held: IDE 2 buses read as load buses
    bus_src: dict = field(default_factory=dict)  # bus number -> its record's RawSource
    #: section -> the lines of its records read but without use in a run (`_SKIPPED`)
    unused: dict = field(default_factory=dict)

    def once(self, rec: _Rec, key: tuple, what: str):
        """CaseError when a record with the same identity came before (a duplicated
        record: PSS/E refuses it, and a parallel circuit needs its own CKT id)."""
        first = self.seen.setdefault((rec.section, *key), rec.line)
        if first != rec.line:
            rec.fail(f"{what} appears twice (first at line {first})")

    def skip(self, rec: _Rec, what: str):
        self.unsupported.append(rec.source(what))

    def out(self, rec: _Rec, what: str, buses: tuple, status: int) -> bool:
        """Whether the record ``what`` is out of the network, as PSS/E leaves it: at an
        isolated bus among ``buses``, or its status field (0-based field ``status`` of
        line 1; blank: 1) 0; such a record is named in ``switched_off``.  A status other
        than 0 or 1 is refused naming the field and its text: the POM gives loads, fixed
        shunts, generators, branches, two-winding transformers and switched shunts 1 for
        in service and 0 for out of service, nothing else (v32 to v36)."""
        code = rec.int(0, status, 1)
        if code not in (0, 1):
            rec.fail(f"{what}: {rec.name(0, status)} {rec.written(0, status)} must be 0 or 1")
        isolated = [n for n in buses if n in self.isolated]
        if isolated:
            why = f"at isolated bus {isolated[0]} (IDE 4)"
        elif code == 0:
            why = f"out of service ({rec.name(0, status)} 0)"
        else:
            return False
        self.switched_off.append(rec.source(f"{what}: {why}"))
        return True

    def bus_row(self, rec: _Rec, number: int, role: str):
        """The bus row of ``number``, None for an isolated bus; CaseError if unknown."""
        if number in self.isolated:
            return None
        if number not in self.buses:
            rec.fail(f"{role} bus {number} is not in the bus data")
        return self.buses[number]

    def v0(self, number: int) -> float:
        return self.buses[number][1]


def _bus(b: _Builder, rec: _Rec):
    """Bus: I, 'NAME', BASKV, IDE, AREA, ZONE, OWNER, VM, VA (POM Bus Data)."""
    num, ide = rec.int(0, 0), rec.int(0, 3, 1)
    if not 1 <= num <= MAX_BUS:
        rec.fail(f"I {rec.written(0, 0)}: a bus number must be within 1 to {MAX_BUS}")
    b.once(rec, (num,), f"bus {num}")
    b.base_kv[num] = rec.num(0, 2, 0.0)
    if b.base_kv[num] < 0:
        rec.fail(f"bus {num}: BASKV {rec.written(0, 2)} kV must be >= 0 (0: not given)")
    if ide == _IDE_ISOLATED:
        b.isolated.add(num)
        b.switched_off.append(rec.source(f"bus {num}: isolated (IDE 4)"))
        return
    if ide not in (1, 2, 3):
        rec.fail(f"bus {num}: IDE {rec.written(0, 3)} must be 1, 2, 3 or 4")
    vm = rec.num(0, 7, 1.0)
    if vm <= 0:
        rec.fail(f"bus {num}: VM {rec.written(0, 7)} must be > 0")
    kind = {1: PQ, 2: PV, 3: SWING}[ide]
    for hi, lo, k in (("NVHI", "NVLO", 9), ("EVHI", "EVLO", 11)):
        if rec.num(0, k, 1.1) < rec.num(0, k + 1, 0.9):
            b.noted.append(
                rec.source(
                    f"bus {num}: {hi} {rec.written(0, k)} below {lo} {rec.written(0, k + 1)} "
                    "(voltage limits stabctl does not use: kept)"
                )
            )
    b.bus_src[num] = rec.source(f"bus {num}")
    b.solution[num] = (vm, rec.num(0, 8, 0.0))
    b.buses[num] = [
        num,
        vm,
        rec.num(0, 8, 0.0),
        0,
        0,
        0,
        0,
        0,
        0,
        kind,
        0,
        0,
        rec.num(0, 2, 0.0),
        0,
        0,
    ]


def _system_wide(b: _Builder, rec: _Rec):
    """System-wide data (v34 and later): solution parameters (GENERAL, GAUSS, NEWTON,
    ADJUST, TYSL, SOLVER) and rating-set names (RATING; v36 SWDRATNAM). They do not change
    the case (stabctl's power flow has its own settings): each record is checked to start
    with its keyword, then skipped."""
    key = rec.text(0, 0, "")
    if not key[:1].isalpha():
        rec.fail(
            f"'{key}' where a record starts with its keyword ({', '.join(_SYSTEM_WIDE)}): "
            "the '0 / END OF SYSTEM-WIDE DATA' record is missing"
        )


def _substation(b: _Builder, rec: _Rec):
    """Substation (v34 and later): I, 'NAME', LATI, LONG, SRG, then its node, switching
    device and terminal data (node-breaker topology). A substation without them is
    skipped; one with them is unsupported (stabctl reads the bus-branch records only)."""
    data = [line for line in rec.lines[1:] if line and line[:1] != ["0"]]
    if not data:  # a name and a place
        b.unused.setdefault(rec.section, []).append(rec.line)
    else:
        what = f"substation {rec.int(0, 0)} '{rec.text(0, 1, '')}'"
        b.skip(
            rec,
            f"{what}: node-breaker data ({len(data)} node, switching device and terminal records)",
        )


def _gne_device(b: _Builder, rec: _Rec):
    """GNE device (POM GNE Device Data): 'NAME', 'MODEL', NTERM, its buses, NREAL, NINTG,
    NCHAR; STATUS, OWNER, NMETR; its REAL, INTG and CHAR values (their lines counted by
    :func:`_gne_lines`). PSS/E's generic network element runs a user-written model
    stabctl does not have: the record is unsupported, named with its model and buses."""
    nterm, counts = _gne_counts(rec)
    status = rec.int(1, 0, 1)
    if status not in (0, 1):
        rec.fail(f"STATUS {rec.written(1, 0)} must be 0 or 1", 1)
    for row, names in enumerate(rec.names[2:], start=2):
        for k, name in enumerate(names):
            if (name or "").startswith("INTG"):
                rec.int(row, k)
    buses = ", ".join(str(rec.int(0, 3 + k)) for k in range(nterm))
    b.skip(
        rec,
        f"gne device '{rec.text(0, 0, '')}' (model '{rec.text(0, 1, '')}', bus(es) {buses}; "
        f"{counts[0]} REAL, {counts[1]} INTG, {counts[2]} CHAR values): PSS/E's generic "
        "network element runs a user-written model, which stabctl does not have",
    )


def _load(b: _Builder, rec: _Rec):
    """Load: I, ID, STATUS, AREA, ZONE, PL, QL, IP, IQ, YP, YQ, [OWNER, SCALE, INTRPT,
    DGENP, DGENQ, DGENM (v34), LOADTYPE (v35), NAME (v36)] (POM Load Data)."""
    num = rec.int(0, 0)
    what = f"load at bus {num} '{rec.text(0, 1)}'"
    b.once(rec, (num, rec.text(0, 1)), what)
    row = b.bus_row(rec, num, "load")
    if b.out(rec, what, (num,), 2) or row is None:
        return
    if b.version >= 34 and rec.int(0, 16, 0) == 1 and (rec.num(0, 14, 0.0) or rec.num(0, 15, 0.0)):
        return b.skip(rec, f"{what}: distributed generation in service (DGENM 1, DGENP, DGENQ)")
    pl, ql, ip, iq, yp, yq = (rec.num(0, k, 0.0) for k in range(5, 11))
    v0 = b.v0(num)
    b.load_src.setdefault(num, rec)
    parts = b.load_parts.setdefault(num, [0.0, 0.0, 0.0, 0.0])
    for i, v in enumerate((pl, ql, ip * v0, iq * v0)):
        parts[i] += v / b.base
    row[7] += yp / b.base
    row[8] += yq / b.base


def _fixed_shunt(b: _Builder, rec: _Rec):
    """Fixed shunt: I, ID, STATUS, GL, BL (POM Fixed Shunt Data)."""
    num = rec.int(0, 0)
    what = f"fixed shunt at bus {num} '{rec.text(0, 1)}'"
    b.once(rec, (num, rec.text(0, 1)), what)
    row = b.bus_row(rec, num, "fixed shunt")
    if not b.out(rec, what, (num,), 2) and row is not None:
        row[7] += rec.num(0, 3, 0.0) / b.base
        row[8] += rec.num(0, 4, 0.0) / b.base


def _nreg_offset(version: int) -> int:
    """Shift of the generator fields after IREG (MBASE, ZR, ZX, RT, XT, GTAP, STAT, RMPCT)
    and of the switched shunt's after SWREG: v35 inserts NREG there (v34 writes it at
    the end of the record, where stabctl does not read)."""
    return 1 if version >= 35 else 0


def _generator(b: _Builder, rec: _Rec):
    """Generator: I, ID, PG, QG, QT, QB, VS, IREG, [NREG (v35)], MBASE, ZR, ZX, RT, XT,
    GTAP, STAT, RMPCT (POM Generator Data)."""
    num, gid = rec.int(0, 0), rec.text(0, 1)
    what = f"generator at bus {num} '{gid}'"
    b.once(rec, (num, gid), what)
    row = b.bus_row(rec, num, "generator")
    o = _nreg_offset(b.version)
    off = b.out(rec, what, (num,), 14 + o)  # its status first: a shifted record shows there
    wind = _check_generator(rec, what, o)
    if off or row is None:
        b.out_of_service.append((num, gid))
        return
    if not rec.num(0, 6, 1.0) > 0:  # a scheduled voltage, pu
        rec.fail(f"{what}: {rec.given(0, 6)}: VS must be > 0")
    if wind is None and rec.num(0, 4, 9999.0) < rec.num(0, 5, -9999.0):
        rec.fail(f"{what}: {rec.given(0, 4, 5)}: QT must be >= QB")
    pg, pt, pb = rec.num(0, 2, 0.0), rec.num(0, 16 + o, 9999.0), rec.num(0, 17 + o, -9999.0)
    if not pb <= pg <= pt:  # PSS/E solves it as dispatched too (round 42: without a word)
        b.noted.append(
            rec.source(
                f"{what}: PG {rec.written(0, 2)} MW {'above PT' if pg > pt else 'below PB'} "
                f"{rec.written(0, 16 + o if pg > pt else 17 + o)} MW (dispatched outside its "
                "power limits: kept, as PSS/E solves it)"
            )
        )
    why = None if b.net is None else b.net(num, gid)
    if why:
        b.netted_ids.append((num, gid))
        return _net_generator(b, rec, num, f"{what}: {why}")
    if rec.num(0, 11 + o, 0.0) != 0 or rec.num(0, 12 + o, 0.0) != 0:
        return b.skip(rec, f"{what}: step-up transformer in the generator record (RT, XT)")
    if row[9] == PQ:
        return b.skip(rec, f"{what}: generator at a load bus (IDE 1)")
    vs = rec.num(0, 6, 1.0)
    if b.gen_vs.setdefault(num, vs) != vs:
        return b.skip(
            rec, f"{what}: VS {rec.written(0, 6)} differs from bus {num}'s first generator"
        )
    ireg = rec.int(0, 7, 0) or num
    first = b.gen_ireg.setdefault(num, ireg)
    if first != ireg:
        return b.skip(rec, f"{what}: IREG {ireg} differs from bus {num}'s first generator's")
    if ireg != num:
        b.remote.setdefault(num, [ireg, vs, 0.0, rec])[2] += rec.num(0, 15 + o, 100.0)
    _add_generator(b, rec, row, vs if ireg == num else row[1], o, gid, wind)


def _check_generator(rec: _Rec, what: str, o: int) -> tuple[float, float] | None:
    """CaseError naming the field for a generator value outside the POM's range (Generator
    Data), used by stabctl or not: GTAP and RMPCT not > 0, PT below PB, an ownership
    fraction Fi below 0, WMOD other than 0 to 3, and where WMOD is 2 or 3 a WPF whose
    magnitude is not within 0 (excluded) to 1.  Returns the Q limits (QT, QB) in Mvar
    PSS/E derives from PG and WPF for WMOD 2 (+-|PG| tan(acos |WPF|)) and 3 (both
    PG tan(acos |WPF|), of the sign of PG times that of WPF: a fixed Q), else None."""
    for k, name in ((13 + o, "GTAP"), (15 + o, "RMPCT")):
        if not rec.num(0, k, 1.0) > 0:
            rec.fail(f"{what}: {name} {rec.written(0, k)} must be > 0")
    if rec.num(0, 16 + o, 9999.0) < rec.num(0, 17 + o, -9999.0):
        rec.fail(f"{what}: {rec.given(0, 16 + o, 17 + o)}: PT must be >= PB")
    for name in ("F1", "F2", "F3", "F4"):
        kf = rec.index(name)
        if kf is not None and rec.num(0, kf, 1.0) < 0:
            rec.fail(f"{what}: {name} {rec.written(0, kf)} must be >= 0 (an ownership fraction)")
    wmod = _code(rec, 0, "WMOD", range(4), what, 0)
    if wmod not in (2, 3):
        return None
    kw = rec.index("WPF")
    wpf = 1.0 if kw is None else rec.num(0, kw, 1.0)
    if not 0 < abs(wpf) <= 1:
        shown = "blank" if kw is None else rec.shown(0, kw, wpf)
        rec.fail(f"{what}: WPF {shown} must be within -1 to 1 and not 0 (WMOD {wmod})")
    q = abs(rec.num(0, 2, 0.0)) * math.tan(math.acos(abs(wpf)))
    if wmod == 2:
        return q, -q + 0.0  # no -0
    q *= math.copysign(1.0, wpf) * math.copysign(1.0, rec.num(0, 2, 0.0))
    return q + 0.0, q + 0.0


def _code(rec: _Rec, row: int, name: str, allowed: Sequence[int], what: str, default: int) -> int:
    """The integer field the POM names ``name`` on line ``row`` (``default`` when blank or
    not in the version's layout), refused naming the field and its text when not one of
    ``allowed``."""
    k = rec.index(name, row)
    code = default if k is None else rec.int(row, k, default)
    if code not in allowed:
        values = [str(v) for v in allowed]
        want = (
            f"within {values[0]} to {values[-1]}"
            if len(values) > 3
            else f"{', '.join(values[:-1])} or {values[-1]}"
        )
        rec.fail(f"{what}: {name} {rec.written(row, cast(int, k))} must be {want}", row)
    return code


def _net_generator(b: _Builder, rec: _Rec, num: int, what: str):
    """A generator as a negative constant-power load PG + jQG at its bus."""
    b.load_src.setdefault(num, rec)
    parts = b.load_parts.setdefault(num, [0.0, 0.0, 0.0, 0.0])
    parts[0] -= rec.num(0, 2, 0.0) / b.base
    parts[1] -= rec.num(0, 3, 0.0) / b.base
    b.netted.append((num, rec.source(what)))


def _add_generator(
    b: _Builder, rec: _Rec, row: list, vs: float, o: int, gid: str, wind: tuple | None
):
    """The generator into its bus row (PG, QG, VS, Q limits: QT and QB, or ``wind``'s,
    named in ``changed``) and the generator list."""
    pg, qg = rec.num(0, 2, 0.0), rec.num(0, 3, 0.0)
    qt, qb = wind or (rec.num(0, 4, 9999.0), rec.num(0, 5, -9999.0))
    if wind is not None:
        wmod, k = _code(rec, 0, "WMOD", range(4), "", 0), rec.index("WPF")
        b.changed.append(
            rec.source(
                f"generator at bus {row[0]} '{gid}': Q limits QT {qt:.6g}, QB {qb:.6g} Mvar from "
                f"PG {rec.written(0, 2)} and WPF {rec.shown(0, k, 1.0) if k else 'blank'} "
                f"(WMOD {wmod}, PSS/E's rule) instead of QT {rec.written(0, 4)}, "
                f"QB {rec.written(0, 5)}"
            )
        )
    row[1] = vs
    row[3] += pg / b.base
    row[4] += qg / b.base
    row[10] += qt / b.base
    row[11] += qb / b.base
    mbase = rec.num(0, 8 + o, b.base)
    if mbase <= 0:
        rec.fail(f"generator at bus {row[0]} '{gid}': MBASE {rec.written(0, 8 + o)} must be > 0")
    b.gens.append(
        Generator(
            number=len(b.gens) + 1,
            bus=int(row[0]),
            id=gid,
            mbase=mbase,
            ra=rec.num(0, 9 + o, 0.0),
            xsource=rec.num(0, 10 + o, 1.0),
            pg=pg,
            qg=qg,
            source=rec.source(f"generator at bus {row[0]} '{gid}'"),
        )
    )


def _ends(b: _Builder, rec: _Rec, i: int, j: int, what: str):
    """Both end rows of a branch, or None if one end is an isolated bus."""
    fi, tj = b.bus_row(rec, i, f"{what} from"), b.bus_row(rec, j, f"{what} to")
    if i == j:
        rec.fail(f"{what} joins bus {i} to itself")
    return None if fi is None or tj is None else (fi, tj)


#: PSS/E's default zero-impedance threshold (pu): a non-transformer branch of R 0 and |X| at
#: or below it is a zero-impedance line there (POM, Zero Impedance Lines), `_branch`
THRSHZ = 1e-4


def _branch(b: _Builder, rec: _Rec):
    """Non-transformer branch: I, J, CKT, R, X, B, [NAME (v34)], ratings, GI, BI, GJ, BJ,
    ST (POM Non-Transformer Branch Data; J < 0 marks the metered end)."""
    i, j, ckt = rec.int(0, 0), abs(rec.int(0, 1)), rec.text(0, 2)
    what = f"branch {i}-{j} '{ckt}'"
    b.once(rec, (min(i, j), max(i, j), ckt), what)
    _ends(b, rec, i, j, "branch")
    _code(rec, 0, "MET", (1, 2), what, 1)  # the metered end (v36: not in the heading)
    k = 19 if b.version >= 34 else 9  # GI
    if b.out(rec, what, (i, j), k + 4):
        return
    r, x, bc = rec.num(0, 3), rec.num(0, 4), rec.num(0, 5, 0.0)
    gi, bi, gj, bj = (rec.num(0, k + n, 0.0) for n in range(4))
    if r == 0 and x == 0:
        rec.fail(f"{what}: R + jX must not be 0")
    if r == 0 and abs(x) <= THRSHZ:  # round 59 BB11: kept without a word
        b.noted.append(
            rec.source(
                f"{what}: R 0, X {rec.written(0, 4)} pu, at or below PSS/E's zero-impedance "
                f"threshold THRSHZ {THRSHZ:g} (PSS/E: a zero-impedance line, its two buses "
                "one; kept as the impedance it is)"
            )
        )
    if r < 0:  # allowed, named: network equivalents carry it
        b.noted.append(
            rec.source(
                f"{what}: R {rec.written(0, 3)} pu, negative (kept, as a network equivalent's)"
            )
        )
    if gi == 0 and gj == 0 and bi == bj:  # a symmetric susceptance: part of the charging
        b.branches.append([i, j, r, x, bc + bi + bj, 0, 0, 0, 0, 0])
    else:
        b.branches.append([i, j, r, x, bc, 0, 0, 0, 0, 0, gi, bi, gj, bj])
    b.circuits.append(ckt)


def _transformer(b: _Builder, rec: _Rec):
    """Transformer (POM Transformer Data): line 1 I, J, K, CKT, CW, CZ, CM, MAG1, MAG2,
    NMETR, 'NAME', STAT; line 2 R1-2, X1-2, SBASE1-2 (three windings: then R2-3, X2-3,
    SBASE2-3, R3-1, X3-1, SBASE3-1, VMSTAR, ANSTAR); per winding a line WINDV, NOMV, ANG,
    ..., TAB (field 14; v34: field 23, after 12 ratings; v35: field 24, NOD moved before
    it) (two windings: line 4 WINDV2, NOMV2 only)."""
    i, j, k3, ckt = rec.int(0, 0), rec.int(0, 1), rec.int(0, 2, 0), rec.text(0, 3)
    what = f"transformer {i}-{j}" + (f"-{k3}" if k3 else "") + f" '{ckt}'"
    b.once(rec, (*sorted((i, j, k3)), ckt), what)
    if k3 != 0:
        return _three_winding(b, rec, (i, j, k3), f"three-winding {what}")
    ends = _ends(b, rec, i, j, "transformer")
    controls = _check_transformer(b, rec, (2,), what)
    if b.out(rec, what, (i, j), 11) or ends is None:
        return
    if not _modelled(b, rec, (2,), what):
        return
    _hold_transformer(b, rec, controls, f"{i}-{j}", what)
    g_mag, b_mag = _magnetizing(b, rec, ends[0][12], i, what)
    t1, t2 = (_ratio(rec, row, e[12], e[0], what) for row, e in ((2, ends[0]), (3, ends[1])))
    z = _impedance(b, rec, (0, 2), ends[0][12], ends[0][0], what)
    r2, x2 = z.real * t2**2, z.imag * t2**2
    if r2 == 0 and x2 == 0:
        rec.fail(f"{what}: {rec.given(1, 0, 1)}: R1-2 + jX1-2 must not be 0", 1)
    ang = _angle(rec, 2, what)
    row = [i, j, r2, x2, 0, t1 / t2, -ang if ang else 0.0, 0, 0, 0]
    b.branches.append(row + ([g_mag, b_mag, 0.0, 0.0] if g_mag or b_mag else []))
    b.circuits.append(rec.text(0, 3))


def _modelled(b: _Builder, rec: _Rec, rows: tuple, what: str) -> bool:
    """False (the record reported unsupported) for an impedance correction table (TAB) on
    a winding line of ``rows``."""
    tab = {32: 13, 33: 13, 34: 22}.get(b.version, 23)
    if any(rec.int(row, tab, 0) != 0 for row in rows):
        b.skip(rec, f"{what}: impedance correction table (TAB)")
        return False
    return True


def _magnetizing(b: _Builder, rec: _Rec, kv: float, bus: int, what: str) -> tuple:
    """The magnetizing admittance (G, B) in pu on the system base and the base voltage
    ``kv`` of winding-1 bus ``bus``, from MAG1, MAG2 by CM (POM Transformer Data): CM 1,
    (MAG1, MAG2) as given; CM 2, the no-load loss MAG1 (W) and the exciting current MAG2
    (pu on SBASE1-2 and NOMV1, >= 0): G = MAG1/(1e6 SBASE), |Y| = MAG2 SBASE1-2/SBASE,
    B = -sqrt(|Y|^2 - G^2), both scaled by (kv/NOMV1)^2.  A CM 2 current below its loss
    (|Y| < G) or a negative MAG1 or MAG2 is refused naming the fields."""
    g, bm = rec.num(0, 7, 0.0), rec.num(0, 8, 0.0)
    if rec.int(0, 6, 1) == 1 or (g == 0 and bm == 0):  # CM 1 or 2 (_check_transformer)
        return g, bm
    if g < 0 or bm < 0:
        rec.fail(f"{what}: {rec.given(0, 7, 8)}: CM 2 gives a loss (W) and a current (pu), >= 0")
    sbase = rec.num(1, 2, b.base)
    if sbase <= 0:
        rec.fail(f"{what}: SBASE1-2 {rec.written(1, 2)} MVA must be > 0", 1)
    nomv = _nominal(rec, 2, kv, bus, 1, what)
    scale = (kv / nomv if nomv != kv else 1.0) ** 2 / b.base
    g, y = g / 1e6 * scale, bm * sbase * scale
    if y < g:
        rec.fail(
            f"{what}: {rec.given(0, 7, 8)}: exciting current {y:g} pu below the no-load loss "
            f"{g:g} pu (CM 2; pu on the system base)"
        )
    return g, -math.sqrt(y * y - g * g)


#: STAT of a three-winding transformer -> its windings in service (POM)
_WINDINGS_IN = {1: (0, 1, 2), 2: (0, 2), 3: (0, 1), 4: (1, 2)}


def _three_winding(b: _Builder, rec: _Rec, buses: tuple, what: str):
    """A three-winding transformer as its star equivalent (module doc)."""
    if len(rec.lines) != 5:
        rec.fail(f"{what}: {len(rec.lines)} record lines, a three-winding one has 5")
    rows = [b.bus_row(rec, n, f"{what} winding {w + 1}") for w, n in enumerate(buses)]
    if len(set(buses)) != 3:
        rec.fail(f"{what}: its three windings must be at three different buses")
    controls = _check_transformer(b, rec, (2, 3, 4), what)
    stat = rec.int(0, 11, 1)
    if stat not in (0, *_WINDINGS_IN):
        rec.fail(f"{what}: STAT {rec.written(0, 11)} must be 0, 1, 2, 3 or 4")
    windings = [w for w in _WINDINGS_IN.get(stat, ()) if rows[w] is not None]
    if len(windings) < 2:
        why = (
            "out of service (STAT 0)"
            if stat == 0
            else f"fewer than two windings in service (STAT {stat}, isolated buses)"
        )
        b.switched_off.append(rec.source(f"{what}: {why}"))
        return
    if not _modelled(b, rec, (2, 3, 4), what):
        return
    for w in sorted(set(range(3)) - set(windings)):  # (round 43: left out without a word)
        why = "at an isolated bus" if rows[w] is None else f"out of service (STAT {stat})"
        b.switched_off.append(rec.source(f"{what}: winding {w + 1} (bus {buses[w]}) {why}"))
    in_service = [2 + w for w in windings]
    held = [(row, cod) for row, cod in controls if row in in_service]
    _hold_transformer(b, rec, held, "-".join(map(str, buses)), what)
    kvs = [b.base_kv[n] for n in buses]
    z12, z23, z31 = (_impedance(b, rec, (3 * p, 2 + p), kvs[p], buses[p], what) for p in range(3))
    if 0 in (z12, z23, z31):
        rec.fail(f"{what}: the pair impedances must not be 0 ({rec.given(1, *range(9))})", 1)
    star_z = ((z12 + z31 - z23) / 2, (z12 + z23 - z31) / 2, (z23 + z31 - z12) / 2)
    b.stars += 1
    star = max(b.base_kv) + b.stars  # above every bus of the file
    vm = rec.num(1, 9, 1.0)
    if vm <= 0:
        rec.fail(f"{what}: VMSTAR {rec.written(1, 9)} must be > 0", 1)
    b.buses[star] = [star, vm, rec.num(1, 10, 0.0), *[0] * 6, PQ, 0, 0, 0.0, 0, 0]
    g_mag, b_mag = _magnetizing(b, rec, kvs[0], buses[0], what)
    for w in windings:
        z, ang = star_z[w], _angle(rec, 2 + w, what)
        row = [buses[w], star, z.real, z.imag, 0, _ratio(rec, 2 + w, kvs[w], buses[w], what)]
        row += [-ang if ang else 0.0, 0, 0, 0]
        mag = w == 0 and (g_mag or b_mag)
        b.branches.append(row + ([g_mag, b_mag, 0.0, 0.0] if mag else []))
        b.circuits.append(rec.text(0, 3))  # each winding alone between its bus and the star


#: the POM's transformer control modes (COD; negative: the same control, switched off)
_COD = {
    1: "voltage",
    2: "reactive power flow",
    3: "active power flow",
    4: "dc line",
    5: "asymmetric active power flow",
}


def _check_transformer(b: _Builder, rec: _Rec, rows: tuple, what: str) -> list:
    """CaseError naming the field for a transformer code outside the POM's range (Transformer
    Data), used by stabctl or not: CW, CZ (1 to 3), CM, NMETR (1 or 2), ZCOD (v34 and
    later: 0 or 1), and on each winding line of ``rows`` COD (-5 to 5); for a winding
    under control (COD not 0) a CONT bus that is not in the bus data, RMA below RMI or VMA
    below VMI.  Returns (line, COD) of the windings whose control is on (COD > 0)."""
    for name, allowed, default in (
        ("CW", (1, 2, 3), 1),
        ("CZ", (1, 2, 3), 1),
        ("CM", (1, 2), 1),
        ("NMETR", (1, 2), 2),
        ("ZCOD", (0, 1), 0),
    ):
        _code(rec, 0, name, allowed, what, default)
    controls = []
    for row in rows:
        w = row - 1
        cod = _code(rec, row, f"COD{w}", range(-5, 6), what, 0)
        if cod == 0:
            continue
        k = rec.index(f"CONT{w}", row)
        cont = 0 if k is None else abs(rec.int(row, k, 0))
        if cont and cont not in b.base_kv:
            rec.fail(
                f"{what}: CONT{w} {rec.written(row, cast(int, k))}: bus {cont} is not in the "
                "bus data",
                row,
            )
        for hi, lo in ((f"RMA{w}", f"RMI{w}"), (f"VMA{w}", f"VMI{w}")):
            khi, klo = rec.index(hi, row), rec.index(lo, row)
            if (
                khi is not None
                and klo is not None
                and rec.num(row, khi, 1.1) < rec.num(row, klo, 0.9)
            ):
                rec.fail(
                    f"{what}: {rec.given(row, khi, klo)}: {hi} must be >= {lo} (COD{w} {cod})", row
                )
        if cod > 0:
            controls.append((row, cod))
    return controls


def _hold_transformer(b: _Builder, rec: _Rec, controls: list, at: str, what: str):
    """Name in ``held`` a transformer in the network whose windings of ``controls`` ((line,
    COD) from :func:`_check_transformer`) PSS/E adjusts: stabctl holds their RAW ratio and
    angle."""
    if not controls:
        return
    modes = []
    for row, cod in controls:
        k = rec.index(f"CONT{row - 1}", row)
        cont = 0 if k is None or cod != 1 else abs(rec.int(row, k, 0))
        of = f" of bus {cont}" if cont else ""
        modes.append(f"COD{row - 1} {cod}: {_COD[cod]} control{of}")
    b.held.append(
        Held(
            "transformer",
            at,
            rec.source(
                f"{what}: held at its RAW ratio and angle ({'; '.join(modes)}, not modelled "
                "in the power flow or the dynamics)"
            ),
        )
    )


def _ratio(rec: _Rec, row: int, kv: float, bus: int, what: str) -> float:
    """Turns ratio in pu of the base voltage ``kv`` (BASKV, 0: not given) of bus ``bus``,
    the winding's on line ``row`` (CW, WINDVw, NOMVw; POM Transformer Data: WINDV blank is
    1.0 under CW 1 and 3, NOMV under CW 2; NOMV 0 or blank is the bus base voltage).  A
    WINDV or NOMV that is not > 0 (NOMV: >= 0), or kV given where the bus has no base
    voltage, is refused naming the field."""
    cw = rec.int(0, 4, 1)  # 1 to 3 (_check_transformer)
    w = row - 1
    nomv = _nominal(rec, row, kv, bus, w, what)
    windv = rec.num(row, 0, nomv if cw == 2 else 1.0)
    if not windv > 0:
        rec.fail(f"{what}: WINDV{w} {rec.shown(row, 0, windv)} must be > 0", row)
    if cw == 1 or (cw == 3 and nomv == kv):
        return windv
    if not kv > 0:
        rec.fail(f"{what}: CW {cw} gives WINDV{w} in kV, but bus {bus} has no BASKV", row)
    return windv / kv if cw == 2 else windv * nomv / kv


def _angle(rec: _Rec, row: int, what: str) -> float:
    """The winding's phase shift ANGw (degrees, line ``row``), within PSS/E's -180 to 180
    (POM Transformer Data)."""
    ang = rec.num(row, 2, 0.0)
    if not -180 <= ang <= 180:
        rec.fail(
            f"{what}: ANG{row - 1} {rec.written(row, 2)} degrees must be within -180 to 180", row
        )
    return ang


def _nominal(rec: _Rec, row: int, kv: float, bus: int, w: int, what: str) -> float:
    """NOMVw (kV) on line ``row``: blank or 0 is the base voltage ``kv`` of bus ``bus``."""
    nomv = rec.num(row, 1, 0.0)
    if nomv < 0:
        rec.fail(
            f"{what}: NOMV{w} {rec.written(row, 1)} kV must be >= 0 (0: bus {bus}'s BASKV)", row
        )
    return nomv or kv


def _impedance(b: _Builder, rec: _Rec, at: tuple, kv: float, bus: int, what: str) -> complex:
    """A measured winding-pair impedance R + jX (R, X, SBASE from field ``at[0]`` of line
    2) on the system base and the base voltage ``kv`` of the pair's first winding's bus
    ``bus`` (its NOMV on line ``at[1]``) by CZ."""
    cz = rec.int(0, 5, 1)
    r, x = rec.num(1, at[0]), rec.num(1, at[0] + 1)
    if cz == 1:  # 1 to 3 (_check_transformer)
        return complex(r, x)
    sbase = rec.num(1, at[0] + 2, b.base)
    if sbase <= 0:
        name = rec.name(1, at[0] + 2)
        rec.fail(f"{what}: {name} {rec.written(1, at[0] + 2)} MVA must be > 0", 1)
    if cz == 3:  # R is the load loss in W, X the impedance magnitude
        r = r / 1e6 / sbase
        if x < r:
            rec.fail(
                f"{what}: {rec.given(1, at[0], at[0] + 1)}: |Z| {rec.written(1, at[0] + 1)} pu "
                f"below the loss resistance {r:g} pu (CZ 3)",
                1,
            )
        x = math.sqrt(x * x - r * r)
    nomv = _nominal(rec, at[1], kv, bus, at[1] - 1, what)
    if nomv != kv and not kv > 0:
        rec.fail(
            f"{what}: NOMV{at[1] - 1} {rec.written(at[1], 1)} kV given, but bus {bus} has no BASKV",
            at[1],
        )
    return complex(r, x) * (b.base / sbase) * (nomv / kv if nomv != kv else 1.0) ** 2


def _switched_shunt(b: _Builder, rec: _Rec):
    """Switched shunt at its initial susceptance: I, [ID (v35)], MODSW, ADJM, STAT, VSWHI,
    VSWLO, SWREG, [NREG (v35; v34 writes it at the end)], RMPCT, 'RMIDNT', BINIT (POM
    Switched Shunt Data); v32/v33 have one per bus, v35 and later one per bus and ID."""
    num = rec.int(0, 0)
    what = f"switched shunt at bus {num}"
    if b.version < 34:
        b.once(rec, (num,), what)
    elif b.version >= 35:
        what += f" '{rec.text(0, 1)}'"
        b.once(rec, (num, rec.text(0, 1)), what)
    row = b.bus_row(rec, num, "switched shunt")
    o = 1 if b.version >= 35 else 0  # v35 inserts ID after I
    off = b.out(rec, what, (num,), 3 + o)  # its status first: a shifted record shows there
    modsw = _check_switched_shunt(b, rec, what)
    if off or row is None:
        return
    k = cast(int, rec.index("BINIT"))
    row[8] += rec.num(0, k) / b.base
    if modsw != 0:
        held = (
            f"{what}: held at BINIT {rec.written(0, k)} Mvar (MODSW {modsw}: not switched in "
            "the power flow or the dynamics)"
        )
        b.held.append(Held("switched shunt", str(num), rec.source(held)))


def _check_switched_shunt(b: _Builder, rec: _Rec, what: str) -> int:
    """CaseError naming the field for a switched shunt value outside the POM's range
    (Switched Shunt Data), used by stabctl or not: MODSW other than 0 to 6, ADJM other
    than 0 or 1, a BINIT outside the range its blocks in service reach (the sum of the
    negative Ni Bi to that of the positive), and under control (MODSW not 0) VSWHI below
    VSWLO or a regulated bus (SWREM; v34 and later SWREG) not in the bus data.  Returns
    MODSW."""
    modsw = _code(rec, 0, "MODSW", range(7), what, 1)
    _code(rec, 0, "ADJM", (0, 1), what, 0)
    if modsw != 0:
        khi, klo = cast(int, rec.index("VSWHI")), cast(int, rec.index("VSWLO"))
        if rec.num(0, khi, 1.0) < rec.num(0, klo, 1.0):
            rec.fail(f"{what}: {rec.given(0, khi, klo)}: VSWHI must be >= VSWLO (MODSW {modsw})")
        name = "SWREM" if b.version < 34 else "SWREG"
        k = cast(int, rec.index(name))
        reg = rec.int(0, k, 0)
        if reg and reg not in b.base_kv:
            rec.fail(f"{what}: {name} {rec.written(0, k)}: bus {reg} is not in the bus data")
    low = high = 0.0
    blocks = []
    for n in range(1, 9):
        kn, kb, ks = rec.index(f"N{n}"), rec.index(f"B{n}"), rec.index(f"S{n}")
        if kn is None or (ks is not None and rec.int(0, ks, 1) == 0):
            continue
        steps, mvar = rec.int(0, kn, 0), 0.0 if kb is None else rec.num(0, kb, 0.0)
        if steps < 0:
            rec.fail(f"{what}: N{n} {rec.written(0, kn)} must be >= 0")
        if steps and mvar:
            blocks.append(rec.given(0, kn, cast(int, kb)))
            low, high = low + min(steps * mvar, 0.0), high + max(steps * mvar, 0.0)
    k = cast(int, rec.index("BINIT"))
    binit = rec.num(0, k)
    slack = 1e-6 * max(1.0, abs(binit))
    if not low - slack <= binit <= high + slack:
        given = ", ".join(blocks) or "none"
        rec.fail(
            f"{what}: BINIT {rec.written(0, k)} Mvar is outside the {low:g} to {high:g} Mvar "
            f"its blocks in service reach ({given})"
        )
    return modsw


_HANDLERS = {
    "system-wide data": _system_wide,
    "bus": _bus,
    "load": _load,
    "fixed shunt": _fixed_shunt,
    "generator": _generator,
    "branch": _branch,
    "transformer": _transformer,
    "switched shunt": _switched_shunt,
    "substation": _substation,
    "gne device": _gne_device,
}


def _load_con(b: _Builder) -> np.ndarray:
    """Bus loads into the bus rows and the PST ``load_con`` fractions (see module doc)."""
    rows = []
    converted = []
    for num, (pp, qp, pi, qi) in b.load_parts.items():
        bus = b.buses[num]
        bus[5], bus[6] = pp + pi, qp + qi
        if b.loads != "raw":
            converted += [num] if pp or qp or pi or qi else []
            continue
        fp, fq = _fraction(pp, pi), _fraction(qp, qi)
        if fp is None or fq is None:
            b.skip(
                b.load_src[num],
                f"loads at bus {num}: constant-power and constant-"
                "current parts of opposite sign (no load_con fractions)",
            )
        else:
            rows.append([num, fp, fq, 1.0 - fp, 1.0 - fq])
    if converted:  # (round 49: the change of model was said in the docs alone)
        first = b.load_src[converted[0]]
        default, raw = (
            advice("loads='impedance'", "--loads impedance"),
            advice("loads='raw'", "--loads raw"),
        )
        b.load_model = (
            f"the loads at {len(converted)} bus(es) (from {first.file}:{first.line} on): "
            "their constant-power (PL, QL) and constant-current (IP, IQ) parts run as "
            f"constant impedance at the power-flow voltage ({default}, the default; {raw} "
            "keeps the RAW's composition)"
        )
    return np.array(rows, dtype=float).reshape(-1, 5)


def _fraction(power: float, current: float) -> float | None:
    """Constant-power share of ``power + current``; None if the two differ in sign."""
    if power * current < 0:
        return None
    total = power + current
    return 1.0 if total == 0 else power / total


#: a generator bus's Q limit of exactly 0 (PSS/E: Q held at 0) as written in the bus
#: table, where PST reads 0 as "no limit", pu
ZERO_Q_LIMIT = 1e-9


def _zero_q_limits(b: _Builder):
    """PSS/E's Q limits of exactly 0 at generator buses as +-:data:`ZERO_Q_LIMIT`."""
    for num in {g.bus for g in b.gens}:
        row = b.buses[num]
        row[10] = row[10] or ZERO_Q_LIMIT
        row[11] = row[11] or -ZERO_Q_LIMIT


def _remote_regulation(b: _Builder) -> np.ndarray:
    """``vreg_con`` rows of the plants regulating a remote bus (share: the plant's RMPCT
    over its group's); a plant whose IREG bus is not a load bus regulates its own bus, as
    PSS/E (POM Generator Data, IREG), listed in ``changed``; CaseError for an IREG bus not
    in the bus data."""
    with_gen = {g.bus for g in b.gens}
    rows = []
    for num, (ireg, vs, rmpct, rec) in b.remote.items():
        if num not in with_gen:  # netted: a load, no control
            continue
        if ireg not in b.buses and ireg not in b.isolated:
            rec.fail(f"generator at bus {num}: IREG bus {ireg} is not in the bus data")
        if b.buses[num][9] == SWING:
            why = f"the swing bus holds its own voltage at VS {vs:g}, not bus {ireg}'s"
        elif ireg in b.isolated or b.buses[ireg][9] != PQ:
            kind = "isolated" if ireg in b.isolated else "a generator bus"
            why = f"IREG bus {ireg} is {kind}, so bus {num} regulates its own voltage at VS {vs:g}"
        else:
            rows.append([num, ireg, vs, rmpct])
            continue
        b.changed.append(rec.source(f"generator at bus {num}: {why} (PSS/E)"))
        b.buses[num][1] = vs
    out = np.array(rows, float).reshape(-1, 4)
    for r in np.unique(out[:, 1]):  # RMPCT > 0 (_check_generator): a positive sum
        grp = out[:, 1] == r
        out[grp, 3] /= out[grp, 3].sum()
    return out


def _demote_idle_pv(b: _Builder):
    """IDE 2 buses without an in-service generator are load buses (PSS/E's type 1), each
    named in ``load_buses`` (with its generators netted, or none in service)."""
    with_gen = {g.bus for g in b.gens}
    netted = {bus for bus, _ in b.netted_ids}
    for num, row in b.buses.items():
        if row[9] == PV and num not in with_gen:
            row[9] = PQ
            why = "its generators netted" if num in netted else "no generator in service"
            src = b.bus_src[num]
            said = RawSource(src.file, src.line, f"{src.record}: IDE 2, {why}: a load bus (PSS/E)")
            b.load_buses.append(Held("IDE 2 bus", str(num), said))


def _check_swing_generators(b: _Builder):
    """CaseError for a swing bus without a generator in service (PSS/E's type 3 bus has
    at least one, POM "Bus Data"), or left without one by netting."""
    with_gen = {g.bus for g in b.gens}
    for bus, src in b.netted:
        if b.buses[bus][9] == SWING and bus not in with_gen:
            raise CaseError(
                f"{src}: swing bus {bus} has no generator left once netted (give its "
                "generator a machine model in the DYR data)"
            )
    for num, row in b.buses.items():
        if row[9] == SWING and num not in with_gen:
            raise CaseError(
                f"{b.bus_src[num]}: swing bus {num} (IDE 3) has no generator in service "
                "(PSS/E's swing bus holds at least one: put one in service or make "
                "another bus the swing bus)"
            )


def read_raw(
    path: str | Path,
    loads: str = "impedance",
    net: Callable[[int, str], str | None] | None = None,
) -> RawData:
    """Read a PSS/E RAW file (version 32, 33, 34, 35 or 36) into PST matrices.

    Args:
        path: the ``.raw`` file.
        loads: ``"impedance"`` makes every load constant impedance in the dynamic run;
            ``"raw"`` keeps each load's PSS/E composition there (``load_con``).
        net: called with each in-service generator's bus number and ID (stripped); a
            generator it returns a reason for (a non-empty str, e.g. "no machine model
            record in the DYR data") is netted: a negative constant-power load PG + jQG
            at its bus (PSS/E's ``GNET``), not a generator (see module doc), listed in
            ``netted`` as ``file:line generator at bus B 'ID': reason``.

    Returns:
        :class:`RawData` (bus, line, load_con matrices in pu on SBASE, the generators,
        the unsupported records).

    Raises:
        CaseError: unreadable file, unsupported version, a malformed record (a field that
            is not a number, a bus number not in the bus data, a zero impedance, ...),
            naming ``file:line`` and the record; no swing bus; a swing bus without a
            generator in service, or whose every generator is netted.

    Source: PSS/E POM v32-v34 "Power Flow Raw Data File Contents"; v35 and v36: PSS/E's
    own column headings in its RAW exports (see module doc).
    """
    if loads not in ("raw", "impedance"):
        raise CaseError(f"loads must be 'raw' or 'impedance', got {loads!r}")
    path = input_file(path, "RAW file")
    try:
        lines = case_text(path, "RAW file").splitlines()
    except OSError as exc:
        raise CaseError(f"cannot read {path}: {exc}") from None
    base, version, freq, first, defaults = _header(lines, path)
    b = _Builder(version, base, loads, net=net)
    b.changed += defaults
    for rec in _records(lines, path, version, first + 3):
        _dispatch(b, rec)
    return _finish(b, path, lines[first + 1 : first + 3], version, freq)


def _dispatch(b: _Builder, rec: _Rec):
    handler = _HANDLERS.get(rec.section)
    if handler is not None:
        try:
            handler(b, rec)
        except (OverflowError, ZeroDivisionError) as exc:  # values no case can hold
            rec.fail(f"the values give no finite per-unit data ({exc})")
        _check_numbers(rec)
    elif rec.section in _SKIPPED:
        b.unused.setdefault(rec.section, []).append(rec.line)
    else:
        b.skip(rec, _unmodelled(rec))


def _dc_line(rec: _Rec) -> str:
    """A two-terminal dc line as its record says: name, rectifier and inverter buses
    (first fields of lines 2 and 3), control mode MDC and setting SETVL."""
    mdc, setvl = rec.int(0, 1, 0), rec.num(0, 3, 0.0)
    mode = {0: "blocked (MDC 0)", 1: f"SETVL {setvl:g} MW", 2: f"SETVL {setvl:g} A"}
    return (
        f"two-terminal dc line '{rec.text(0, 0, '')}' from bus {rec.int(1, 0)} to bus "
        f"{rec.int(2, 0)}, {mode.get(mdc, f'MDC {mdc}')}"
    )


def _facts(rec: _Rec) -> str:
    """A FACTS device as its record says: name, its bus I and the far bus J of a series
    part (0: none)."""
    j = rec.int(0, 2, 0)
    series = f" in series to bus {j}" if j else ""
    return f"FACTS device '{rec.text(0, 0, '')}' at bus {rec.int(0, 1)}{series}"


#: the unmodelled sections: what a record is (from its first fields) and what a run
#: without it lacks
_UNMODELLED = {
    "two-terminal dc line": (_dc_line, "dc lines are not modelled: the power it carries is lost"),
    "vsc dc line": (
        lambda rec: (
            f"VSC dc line '{rec.text(0, 0, '')}' between buses {rec.int(1, 0)} and {rec.int(2, 0)}"
        ),
        "dc lines are not modelled: the power it carries and its converters' reactive "
        "power are lost",
    ),
    "multi-terminal dc line": (
        lambda rec: (
            f"multi-terminal dc line '{rec.text(0, 0, '')}' ({rec.int(0, 1, 0)} converters)"
        ),
        "dc lines are not modelled: the power it carries is lost",
    ),
    "facts device": (_facts, "FACTS devices are not modelled: its compensation is lost"),
    "induction machine": (
        lambda rec: f"induction machine at bus {rec.int(0, 0)} '{rec.text(0, 1, '')}'",
        "induction machines in the RAW are not modelled (give motors in the case's "
        "motor table): its power is lost",
    ),
}


def _unmodelled(rec: _Rec) -> str:
    """What an unsupported record of an unmodelled section is and why it matters
    (:data:`_UNMODELLED`; a record whose first fields do not read: its section alone)."""
    describe, lost = _UNMODELLED.get(rec.section, (None, "not modelled"))
    try:
        what = describe(rec) if describe else f"{rec.section} record"
    except (CaseError, IndexError):  # the fields read for the name are malformed
        what = f"{rec.section} record"
    return f"{what}: {lost}"


def _finish(b: _Builder, path: Path, titles, version: int, freq: float) -> RawData:
    if not b.buses:
        raise CaseError(f"{path.name}: no bus data")
    _demote_idle_pv(b)
    vreg_con = _remote_regulation(b)
    _zero_q_limits(b)
    _check_swing_generators(b)
    load_con = _load_con(b)
    bus = np.array(list(b.buses.values()), dtype=float)
    if not np.any(bus[:, 9] == SWING):
        raise CaseError(f"{path.name}: no swing bus (IDE 3) in the bus data")
    width = max([10, *(len(row) for row in b.branches)])
    line = np.array([row + [0.0] * (width - len(row)) for row in b.branches], dtype=float).reshape(
        -1, width
    )
    title = " / ".join(t.strip() for t in titles if t.strip())
    return RawData(
        name=path.stem,
        title=title,
        version=version,
        base_mva=b.base,
        freq_hz=freq,
        bus=bus,
        line=line,
        load_con=load_con,
        generators=tuple(b.gens),
        unsupported=tuple(sorted(b.unsupported, key=lambda s: s.line)),
        netted=tuple(src for _, src in b.netted),
        out_of_service=frozenset(b.out_of_service),
        switched_off=tuple(b.switched_off),
        solution=np.array([[n, *vm_va] for n, vm_va in b.solution.items()], float).reshape(-1, 3),
        vreg_con=vreg_con,
        changed=tuple(b.changed),
        noted=tuple(b.noted),
        unused=tuple(
            f"{len(lines)} {section} record(s) ({path.name}:{_line_span(lines)})"
            + _UNUSED_NOTE.get(section, "")
            for section, lines in b.unused.items()
        ),
        netted_ids=frozenset(b.netted_ids),
        held=tuple(sorted(b.held, key=lambda h: h.source.line)),
        load_buses=tuple(b.load_buses),
        circuit_order=_circuit_order(b),
        load_model=b.load_model,
    )


def _line_span(lines: list[int]) -> str:
    """Line numbers in order as "a" or "a-b" (one section's records are consecutive)."""
    return str(lines[0]) if len(lines) == 1 else f"{lines[0]}-{lines[-1]}"


def _circuit_order(b: _Builder) -> tuple[str, ...]:
    """One line per pair of buses whose parallel branches' CKT ids are not '1', '2', ...
    in file order: the commands number parallel circuits by their order in the branch
    table (`stabctl.case.Case.branch_rows`: ``--trip A B:K``, ``--circuit K``), which is
    the file's, so that there ``:1`` is not PSS/E's circuit '1'."""
    pairs: dict[tuple[int, int], list[str]] = {}
    for row, ckt in zip(b.branches, b.circuits):
        pairs.setdefault((min(row[0], row[1]), max(row[0], row[1])), []).append(ckt)
    out = []
    for (i, j), ids in pairs.items():
        if len(ids) > 1 and ids != [str(k) for k in range(1, len(ids) + 1)]:
            given = ", ".join(f":{k} is '{c}'" for k, c in enumerate(ids, 1))
            out.append(f"{int(i)}-{int(j)} (in file order {given})")
    return tuple(out)
