"""A stabctl case from any case ANDES can load, read through ANDES's own parser.

ANDES 2.0 (CURENT, the optional ``andes`` extra) reads its xlsx and json cases, PSS/E RAW
(+ DYR) and MATPOWER files into one ``System``; :func:`import_andes` maps that system onto
stabctl's case tables, so that a case whose dynamic data exist only in ANDES's formats (IEEE
39's ``ieee39_full.xlsx``) can be simulated, linearised and screened here.

Network (ANDES's values after set-up, pu on the system base):

* ``Bus``: number (its ``idx``, which must be an integer), ``Vn`` (kV), ``v0``, ``a0``
  (``vmax``, ``vmin`` are not limits of ANDES's power flow: the bus table's are left at
  PST's 1.5, 0.5);
* ``PQ``: ``p0 + j q0`` into the bus load (constant impedance in dynamic runs: ANDES's
  default ``PQ.config.p2z = q2z = 1``, stabctl's default);
* ``Shunt``: ``g + j b`` into the bus shunt;
* ``VSCShunt`` on a DC network of ``Node``, ``Ground`` and ``R``: a fixed injection
  (``case.injections``) of its power-flow P + j Q (converters controlling P and Q, or the
  DC voltage and Q);
* ``ShuntSw``: a row of the switched-shunt table (``swsh_con``,
  :mod:`stabctl.network.switched_shunts`) with its system-base ``g``, ``b`` (start), ``bs``,
  ``gs``, ``ns`` (at most four groups), ``vref``, ``dv``, ``dt``;
* ``ZIP`` (replaces its ``PQ`` in dynamic runs, ``andes/models/dynload/zip.py``: ``P =
  p0 (kpp + kpi V/V0 + kpz V^2/V0^2)/100``, Q alike): PST's non-conforming load
  (``load_con``) at its bus, the constant-power and constant-current fractions the
  ZIPs' shares of the bus load (the bus's other PQs constant impedance); percentages of
  P (or of Q) that do not add up to 100 (ANDES warns, and its load then starts off its
  power flow) are scaled to 100, a change that ``on_unsupported="skip"`` keeps and names;
* ``FLoad`` (replaces its ``PQ`` in dynamic runs, ``andes/models/dynload/fload.py``: ``P =
  kp/100 p0 (V/V0)^ap f^bp``, Q alike with kq, aq, bq): a ZIP of one kind, constant power,
  current or impedance for the exponent 0, 1 or 2, where it has no frequency dependence
  (bp = bq = 0) and keeps its PQ's power (kp = kq = 100); any other is refused with the
  parameter named (a load that is not PST's);
* ``PV`` / ``Slack``: ``p0``, ``q0``, ``v0``, ``qmax``, ``qmin`` (added up per bus; the
  bus becomes PV or swing); machines on one bus share its generation as their static
  generators do in ANDES's power flow (its ``p``, ``q``); a ``Slack`` without machine,
  held at ``v0``, ``a0`` in ANDES's run (``andes/models/static/slack.py``), becomes an
  infinite bus (GENCLS, H = 0, behind :data:`INFINITE_BUS_X`); a machine whose static
  generator is out of service is left out with its controls (one warning: ANDES starts it
  from the generator's ``p0`` and fails to initialise); a machine at another bus than its
  static generator's is refused (ANDES fails to initialise it);
* ``Line`` (lines and transformers): ``r``, ``x``, tap ``tap`` on the from side, phase
  ``phi`` (PST's phase is its opposite, :mod:`stabctl.network.ybus`), and the shunts as
  ANDES's ``Line`` equations apply them: ``g1 + g/2 + j (b1 + b/2)`` at both ends, the
  from end behind the tap (ANDES 2.0 ignores ``g2``, ``b2``), i.e. stabctl's charging
  ``b + 2 b1``, ``g_from = (g1 + g/2)/tap^2`` and ``g_to = g1 + g/2``; a line of zero
  impedance (r = x = 0, which ANDES runs at x = 1e-8) is refused, as import-psse refuses
  it.

Values are read as the file gives them (:func:`read_andes_case` raises for a value ANDES
would replace by its default, a formula without a stored value, a status ``u`` other than
0 or 1, a sheet that is no ANDES model; names a column that is no parameter of its model
and a parameter left out, run at ANDES's default), and ANDES's own log is never printed:
what it says of a case it cannot read is the error's message.

Dynamic models: each ANDES model whose parameters are PSS/E's (ANDES's
``andes/io/psse-dyr.yaml`` maps every PSS/E parameter of the model onto one ANDES parameter)
is turned back into its PSS/E record through that file and mapped by the DYR mappers of
:mod:`stabctl.io.dyr` (each parameter declared once, :mod:`stabctl.models.declaration`, with
the ANDES models read as it, ``DyrModel.andes``; :data:`MAPPED_MODELS` lists them).
ANDES's TGOV1N, TGOV1 with the reference after the droop, is read as TGOV1: the same
dynamics at a constant reference.  Values are ANDES's inputs (``vin``: machine data on
the machine base ``Sn``, as PSS/E).  Machine ``k`` of the case is the ``k``-th synchronous
generator in the order of ANDES's static generators (``PV`` rows, then ``Slack``), the
infinite buses after them.

Converter-interfaced devices (:mod:`stabctl.models.converters`, docs/ibr.md): ``PVD1``,
``ESD1``, ``REGCA1`` and ``REGCP1`` (a REGCA1 whose angle may come from a PLL) become rows
of the converter table (``ibr_con``, :data:`stabctl.models.converters.CONVERTER`) with
their inputs (``vin``, device base ``Sn``), ``gammap``/``gammaq`` as the fractions of
their static generator's power, and (PVD1, ESD1) the time constants of the ``BusFreq``
device each reads (ANDES creates one with its defaults when ``busf`` is empty).  A
REGCA1's controls are read into its row: its electrical control ``REECA1`` or ``REECB1``,
that control's plant control ``REPCA1`` and wind turbine (drive train ``WTDTA1`` or
``WTDS``, then ``WTARA1``, ``WTPTA1``, ``WTTQA1``, each naming the one before; a REECA1's
only), a REGCP1's ``PLL1``.  Refused, naming the device: a REGCA1 driven by another
electrical control (REECA1E) or by two, a REGCP1 whose PLL is a PLL2, measures another
bus or runs at another frequency, a remote bus ``igreg`` or ``busr``, a nominal frequency
other than the system's, a wind chain with a missing link or a second drive train, or a
static generator sharing its bus with another.  A machine on a converter's static
generator takes its ``gammap``/``gammaq`` of it; a share outside [0, 1], converters taking
more than all of their static generator's P or Q, and converters and machines taking
other than all of it are refused (CaseError: ANDES drops the rest of a replaced
generator's power and starts off its power flow), but for converters alone on a bus
without machine taking less than all of it, kept with a change named in the summary from the written
tables: their ``pfrac``, ``qfrac`` and the rest of the bus's generation, which a run nets
into the bus's load.

Models with no effect on the network and machines are ignored: ``Summary`` (the case's
notes, ``andes/models/info.py``), ``Area``, ``COI`` (the centre-of-inertia calculation,
``coi.py``: generators name it, no equation reads it), and the
measurements ``BusFreq``, ``BusROCOF``, ``ACEc``, ``PMU``, ``PLL1``, ``PLL2``, ``FreqDiv``
(read by no model stabctl maps, but a REGCP1's PLL1, read into its row; ANDES resolves a
converter's or plant control's frequency measurement to a BusFreq at its bus, even where
``busf`` names a FreqDiv).  Every
other model is refused by name (:class:`~stabctl.errors.InputError` listing each with its
device count), disturbances (``Toggle``, ``Fault``, ``Alter``, ``TimeSeries``) included,
events of a run for `simulate` to take (`stabctl.dynamics.events`), or left out with
``on_unsupported="skip"``.

Source: ANDES 2.0 documentation (``andes.load``; model reference of ``Bus``, ``PQ``,
``PV``, ``Slack``, ``Line``, ``Shunt``, ``GENROU``, ``GENCLS``, the exciters, stabilisers
and governors above) and its ``psse-dyr.yaml``; PSS/E Model Library for the parameters.
"""

from __future__ import annotations

import json
import math
import re
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from stabctl.case import PQ, PV, SWING, Case
from stabctl.case.params import FAMILIES
from stabctl.case.system import SWITCHED_GROUPS
from stabctl.errors import CaseError, InputError, advice
from stabctl.io.andes import _andes, _andes_log, _andes_said
from stabctl.io.dyr import (
    CONVENTIONS,
    DYR_MODELS,
    DyrRecord,
    dyr_origin,
    dyr_tables,
)
from stabctl.io.inputs import number_ranges, parse_json
from stabctl.io.provenance import Origin, locate
from stabctl.io.pst import case_from_matrices
from stabctl.models.converters import (
    CONVERTER,
    DGPRCT1,
    DGPRCTEXT,
    ESD1,
    PLL1,
    PVD1,
    REECA1,
    REECA1_FIELDS,
    REECB1,
    REGCA1,
    RELAY_FIELDS,
    REPCA1,
    REPCA1_FIELDS,
    WIND_FIELDS,
    WTDS,
    WTDTA1,
)
from stabctl.models.converters.rules import RULES as CONVERTER_RULES
from stabctl.models.converters.rules import SHARES, share_sums
from stabctl.models.exciters import ac8b
from stabctl.models.machines import MACHINE
from stabctl.models.motors import MOTOR
from stabctl.models.shafts import SHAFT

__all__ = [
    "AndesImport",
    "import_andes",
    "read_andes_case",
    "MAPPED_MODELS",
    "IGNORED_MODELS",
    "CONVERTER_MODELS",
]

#: ANDES model -> the PSS/E model its parameters are read as (declared with the record,
#: ``DyrModel.andes`` in the model modules)
MAPPED_MODELS = {name: m.name for m in DYR_MODELS.values() for name in m.andes}
#: ANDES models with no effect on the network or the machines (``Summary``: notes only,
#: ``andes/models/info.py``, "not used in DAE calculations"; ``COI``: an output no
#: equation reads; the measurements, read by no model mapped here)
IGNORED_MODELS = (
    "Area",
    "BusFreq",
    "BusROCOF",
    "ACEc",
    "Summary",
    "COI",
    "PMU",
    "PLL1",
    "PLL2",
    "FreqDiv",
)
#: ANDES converter models -> the converter type of stabctl.models.converters.CONVERTER
CONVERTER_MODELS = {"PVD1": PVD1, "ESD1": ESD1, "REGCA1": REGCA1, "REGCP1": REGCA1}
#: ANDES controls read into their converter's row (a REGCA1's REECA1 or REECB1, ibr_con
#: ``reec``)
CONVERTER_CONTROLS = ("REECA1", "REECB1", "REPCA1", "WTDTA1", "WTDS", "WTARA1", "WTPTA1", "WTTQA1")
#: ANDES's DG protections, read into their PVD1's or ESD1's row (ibr_con ``relay``)
PROTECTIONS = {"DGPRCT1": DGPRCT1, "DGPRCTExt": DGPRCTEXT}
#: ANDES's DC network with its static AC/DC converters, read as the converters' fixed
#: injections (`_dc_links`)
DC_MODELS = ("Node", "Ground", "R", "VSCShunt")
#: ANDES's induction motors, read into the motor table (mot_con, `stabctl.models.motors`)
MOTOR_MODELS = ("Motor5",)
#: ANDES's disturbance records, read into the case's own events (`Case.events`,
#: `_disturbances`)
EVENT_MODELS = ("Toggle", "Fault", "Alter")
#: ANDES Alter targets read as reference steps: (model group, source) -> event kind; a
#: TGOV1's ``paux0`` enters its order as (paux - dw) / R: a PREF step of d / R
ALTERED = {("Exciter", "vref0"): "VrefStep", ("TGOV1", "paux0"): "PrefStep"}
#: ANDES's torsional shafts, read into the shaft table (shaft_con, `stabctl.models.shafts`)
SHAFT_MODELS = ("SHAFT5",)
#: ANDES's wind drive trains (group RenGovernor) -> ibr_con ``wind``
DRIVE_TRAINS = {"WTDTA1": WTDTA1, "WTDS": WTDS}
#: the wind models after the drive train: (ANDES model, its parent's parameter, ibr_con
#: flag, column prefix); each names the one before it (WTTQA1 -> WTPTA1 -> WTARA1)
WIND_CHAIN = (
    ("WTARA1", "rego", "aero", "wa_"),
    ("WTPTA1", "rea", "pitch", "wp_"),
    ("WTTQA1", "rep", "torque", "wq_"),
)
_NO_MACHINE = "no synchronous machine model (GENROU, GENCLS)"
#: source reactance (pu, system base) of the infinite bus an ANDES Slack without machine
#: becomes: ANDES holds the bus voltage exactly; 10 pu of current move it by 1e-5 pu
INFINITE_BUS_X = 1e-6
_NETWORK = ("Bus", "PQ", "PV", "Slack", "Line", "Shunt", "ShuntSw", "ZIP", "FLoad")
_MACHINES = ("GENROU", "GENCLS")
#: ANDES parameters outside PSS/E's data that must keep the value stabctl's models have
_FIXED = {
    "GENROU": {"kp": 0.0, "kw": 0.0},
    "GENCLS": {"kp": 0.0, "kw": 0.0},
    **{g: {"wref0": 1.0} for g in ("TGOV1", "TGOV1N", "IEEEG1", "HYGOV", "IEESGO", "GAST")},
    "ESST4B": {"VGMAX": 20.0},  # not in PSS/E's record: ANDES's default, as read
    "HYGOV4": {"Hdam": 1.0},  # the head at the dam of stabctl's HYGOV4 (and HYGOV)
    "HYGOVDB": {"wref0": 1.0, "dbL": 0.0, "dbU": 0.0},  # HYGOV: no speed deadband
}


@dataclass(frozen=True, eq=False)
class AndesImport:
    """The result of :func:`read_andes_case`.

    Attributes
    ----------
    case : Case
        The stabctl case.
    left_out : tuple of str
        What was left out (``on_unsupported="skip"``): ``"MODEL (count)"`` per ANDES model,
        then each column of an xlsx or json file that is no parameter of its model (``SHEET
        column 'NAME': why``: ANDES ignores it), then each refused device with why
        (``MODEL idx: why``, a DYR-level refusal as ``file:row MODEL (bus B, id I): why``).
    ignored : tuple of str
        ANDES models ignored as without effect, ``"MODEL (count)"``.
    pf_bus, pf_vmag, pf_vang : numpy.ndarray
        ANDES's own power flow: bus numbers, |V| (pu), angle (rad), each shape (n_bus,),
        in the case's bus order (None when ANDES's power flow did not converge).
    changed : tuple of str
        Devices kept with a change (``on_unsupported="skip"``), ``"MODEL (n: idx, ...):
        what"`` per model and change: a machine's rated frequency ``fn`` read as the
        system's (N44 read from PSS/E files: ANDES's DYR reader leaves ``fn`` at 60 Hz in a
        50 Hz system), GENROU's ``xq2`` read as ``xd2``, a DYR parameter ANDES replaced
        by its default (``file:line MODEL (bus B, id I): NAME = v read by ANDES as w``),
        converters alone on a bus without machine taking other than all of its generation
        (``"MODEL idx (converter n), ...: take gammap p, gammaq q (summed: ...) of the
        generation of bus B, which has no machine; the rest, ..."``, from the written
        converter table), a
        parameter of a machine or its controls that ANDES requires non-zero or of one sign
        left empty in an xlsx or json file (``NAME left empty, run at ANDES's default d``);
        from a RAW file, what ANDES's RAW reader makes of it otherwise than PSS/E reads it
        (`_raw_unlike_andes`: branches, shunts, unsupported records, isolated buses, held
        controls, remote regulation, wind Q limits); a DYR record read with another value
        (``stabctl.io.dyr.DyrTables.changed``: a stabiliser of gain 0).
    unlike_andes : tuple of str
        DYR values stabctl keeps as the file gives them where ANDES replaces them (the
        infinite bus, a GENCLS of H = 0, which ANDES runs with its default H = 3 s).
    defaulted : tuple of str
        Converter, plant-control, wind and battery parameters, and those of the machines
        and their controls, that an xlsx or json case file leaves out (no column, an empty
        cell, NaN), run with ANDES's default: ``"MODEL NAME = default (rows ...: how)"``
        per model, parameter and how the file leaves it out ("not in the file", "empty in
        the file", "NaN in the file"); a default that is no number is what ANDES uses
        instead, its ``NumSelect`` fallback (``REPCA1 Rc = r, ...``) (`_file_inputs`).
    data_solution : numpy.ndarray or None
        The RAW file's own power-flow solution, shape (n, 3): bus number, VM (pu), VA
        (degrees) (ANDES's ``Bus.v0``, ``a0``); None unless the case is a PSS/E RAW.
    out_of_service : tuple of str
        Each device the file puts out of service (``u = 0``), left out of the case as
        ANDES leaves it out of its run: ``"file: MODEL row R (idx I): out of service (u =
        0)"`` (`_switched_off`).
    """

    case: Case
    left_out: tuple[str, ...]
    ignored: tuple[str, ...]
    pf_bus: np.ndarray | None
    pf_vmag: np.ndarray | None
    pf_vang: np.ndarray | None
    changed: tuple[str, ...] = ()
    unlike_andes: tuple[str, ...] = ()
    data_solution: np.ndarray | None = None
    defaulted: tuple[str, ...] = ()
    out_of_service: tuple[str, ...] = ()


def import_andes(
    path: str | Path,
    conventions: str = "andes",
    on_unsupported: str = "error",
    dyr: str | Path | None = None,
) -> Case:
    """Read a case through ANDES's own parser into a :class:`~stabctl.case.Case`.

    Parameters
    ----------
    path : str or pathlib.Path
        Any case ANDES 2.0 loads: ``.xlsx``, ``.json``, PSS/E ``.raw``, MATPOWER ``.m``.
    conventions : {"andes", "psse", "pst"}, optional
        How the PSS/E models are read (:func:`stabctl.io.dyr.dyr_tables`): ``"andes"``
        (default) as ANDES 2.0 solves them, so that both tools solve the same equations;
        ``"psse"`` as the PSS/E Model Library states them; ``"pst"`` as PST's models.
        (``stabctl import-andes`` reads a RAW + DYR pair with ``"psse"`` by default.)
    on_unsupported : {"error", "skip"}, optional
        Refuse models (and model options) stabctl lacks, or leave them out with one
        :class:`UserWarning` listing them.
    dyr : str or pathlib.Path, optional
        A PSS/E DYR file ANDES adds to a RAW case (its ``addfile``).  Note that ANDES's
        PSS/E reader builds a different network from the RAW's when SBASE is not 100 MVA
        or lines have line-end shunts (:mod:`stabctl.io.andes`);
        :func:`stabctl.io.psse.load_psse` reads the RAW's.

    Returns
    -------
    Case
        Named after the file; units as :mod:`stabctl.case`.

    Raises
    ------
    InputError
        ANDES is not installed, ANDES cannot read the file (with ANDES's own first error:
        its log is never printed), a json file not in ANDES's layout (a stabctl case, a
        PSTess matrix file: named so) or giving a key twice, an xlsx sheet (json key) that
        is no ANDES model, a bad option value, or (``on_unsupported="error"``) models
        stabctl lacks: one message naming every such ANDES model with its device count,
        every refused model option and every column that is no parameter of its model
        (ANDES ignores it).
    CaseError
        Data stabctl's tables refuse (a bus ``idx`` that is not an integer, a generator
        without machine model, a value out of range), a value stabctl reads that an xlsx
        or json file leaves out or gives as other than a number (ANDES would run with its
        default: :data:`_REQUIRED_INPUTS`), a value of any model ANDES would replace by its
        default (its declaration: non-zero, non-negative, ...; a GENROU M of 0), in an
        xlsx or json file or (network data) a RAW or MATPOWER file, a formula cell without
        a stored value, a status ``u`` other than 0 or 1, a line of zero impedance (r = x =
        0, as :func:`stabctl.io.psse.load_psse`), an event time not finite and >= 0, a
        machine at a bus other than its static generator's, machines whose shares of their
        static generator do not add up to 1 (a duplicated record) or, with converters on
        it, whose and the converters' shares do not, naming the devices.

    Source: ANDES 2.0 documentation and ``psse-dyr.yaml`` (see module doc).
    """
    return read_andes_case(path, conventions, on_unsupported, dyr).case


def read_andes_case(
    path: str | Path,
    conventions: str = "andes",
    on_unsupported: str = "error",
    dyr: str | Path | None = None,
) -> AndesImport:
    """:func:`import_andes` with what was left out, what was ignored and ANDES's power
    flow (:class:`AndesImport`). Same arguments and errors."""
    if conventions not in CONVENTIONS:
        raise InputError(f"conventions must be one of {CONVENTIONS}, got {conventions!r}")
    if on_unsupported not in ("error", "skip"):
        raise InputError(f"on_unsupported must be 'error' or 'skip', got {on_unsupported!r}")
    with _andes_log() as said:  # ANDES's own log is not shown: its failures are said here
        return _read(Path(path), conventions, on_unsupported, dyr, said)


def _read(path: Path, conventions: str, on_unsupported: str, dyr, said: list) -> AndesImport:
    """`read_andes_case`'s work, ANDES's log records collected in ``said``."""
    if path.suffix.lower() == ".json" and path.is_file():
        _check_json_layout(path)  # before ANDES reads another layout without sense
    ss = _load(path, dyr, said)
    if not ss.Line.n:  # else named by the matrix reader: "the data defines no 'line' matrix"
        raise CaseError(
            f"{path.name}: no Line record (ANDES's lines and transformers): a network "
            "without branches cannot be simulated"
        )
    given = _file_inputs(path, ss)
    _corrections(path.name, ss)
    _set_up(ss, path, said, dyr)
    counts = {name: m.n for name, m in ss.models.items() if m.n}
    lacking = [
        f"{name} ({n})"
        for name, n in counts.items()
        if name not in _NETWORK
        and name not in MAPPED_MODELS
        and name not in IGNORED_MODELS
        and name not in CONVERTER_MODELS
        and name not in CONVERTER_CONTROLS
        and name not in SHAFT_MODELS
        and name not in PROTECTIONS
        and name not in MOTOR_MODELS
        and name not in DC_MODELS
        and name not in EVENT_MODELS
        and name != "PLBVFU1"
    ]
    ignored = tuple(f"{name} ({counts[name]})" for name in IGNORED_MODELS if name in counts)
    mats, numbers = _network(ss, path.name)
    pf_bus, pf_vmag, pf_vang = _powerflow(ss, numbers)  # its generators' P, Q: shares
    mats["load_con"], zip_changed = _zip_loads(ss, numbers, mats["bus"])
    ibr_con, ibr_refused, with_converter, ibr_labels, ibr_origins = _converters(
        ss, numbers, path.name
    )
    dropped, by_device, unchecked = ([], {}, []) if dyr is None else _dyr_against_andes(ss, dyr)
    gens, records, refused, changed, unlike, by_record = _dynamic_records(
        ss, path.name, numbers, with_converter, by_device
    )
    origins: dict[str, list] = {"ibr_con": ibr_origins}
    changed += unchecked + _grouped(_dc_changes(ss))
    refused = dropped + refused
    changed += _grouped(zip_changed + given.changed + _unused_by_andes(ss, numbers))
    refused += ibr_refused
    motor_numbers: dict = {}
    read_as: list[str] = []
    for key, (rows, why) in (  # stabctl's own tables of the devices ANDES has
        ("shaft_con", _shafts(ss, gens)),
        ("inj_con", _dc_links(ss, numbers)),
        ("swsh_con", _switched_shunts(ss, numbers)),
        ("mot_con", _motors(ss, numbers, motor_numbers)),
    ):
        refused += why
        if rows:
            mats[key] = np.array(rows, float)
    if ibr_con:
        mats["ibr_con"] = np.array(ibr_con, float)
    if records:
        tables = dyr_tables(records, gens, on_unsupported="skip", conventions=conventions)
        refused += [f"{r.label()}: {why}" for r, why in zip(tables.unsupported, tables.why)]
        read_as = list(tables.changed)  # named, as import-psse names them (round 59 BD18)
        origins.update(
            {table: [by_record.get(r) for r in recs] for table, recs in tables.records.items()}
        )
        mats.update(
            {
                k: getattr(tables, k)
                for k in ("mac_con", "exc_con", "pss_con", "tg_con")
                if getattr(tables, k) is not None
            }
        )
        _mark_playback(mats, gens)
    if ibr_con:  # from the tables written, machines' included
        changed += _netted_shares(mats, ibr_labels)
    events, ev_refused, ev_off = _disturbances(ss, path.name, numbers, gens, mats, motor_numbers)
    refused += ev_refused
    ignored += tuple(ev_off)
    left_out = tuple(lacking + given.unknown + refused)
    if left_out or changed:
        listing = "; ".join(
            ([f"ANDES models stabctl lacks (devices): {', '.join(lacking)}"] if lacking else [])
            + ([f"columns ANDES ignores: {'; '.join(given.unknown)}"] if given.unknown else [])
            + ([f"devices refused: {'; '.join(refused)}"] if refused else [])
        )
        kept = f"kept with a change: {'; '.join(changed)}" if changed else ""
        bare = [r for r in refused if r.endswith(_NO_MACHINE)]
        if on_unsupported == "error":
            skippable = len(left_out) > len(bare) or changed
            raise InputError(
                f"{path.name}: "
                + "; ".join(t for t in (listing, kept.replace("kept with", "to keep with")) if t)
                + " ("
                + "; ".join(
                    ([_skip_advice(bool(bare), bool(changed))] if skippable else [])
                    + (
                        [f"a static generator cannot be left out: {_bare_advice(len(bare), path)}"]
                        if bare
                        else []
                    )
                )
                + ")"
            )
        if bare:
            raise CaseError(
                f"{path.name}: a static generator cannot be left out without "
                f"changing the power flow: {'; '.join(bare)} ({_bare_advice(len(bare), path)})"
            )
        text = "; ".join(t for t in ((f"left out {listing}" if listing else ""), kept) if t)
        warnings.warn(f"{path.name}: {text}", UserWarning, stacklevel=4)
    try:
        case = case_from_matrices(
            mats,
            path.stem,
            description=f"ANDES case {path.name}",
            source=f"ANDES case {path.name}, imported by stabctl.io.andes_case.import_andes",
        ).replace(events=tuple(events))
    except CaseError as exc:  # the device and parameters the table's row came from
        located = locate(exc, origins, {f.table: f for f in FAMILIES.values()})
        raise (located if located is not exc else exc.relocated(f"{path.name}: {exc}")) from None
    solution = None
    if path.suffix.lower() == ".raw":
        on = _in_service(ss.Bus)
        solution = np.column_stack(
            (
                [numbers[ss.Bus.idx.v[k]] for k in on],
                np.asarray(ss.Bus.v0.v, float)[on],
                np.rad2deg(np.asarray(ss.Bus.a0.v, float)[on]),
            )
        )
        changed += _raw_unlike_andes(path, case)
    elif path.suffix.lower() == ".m":
        changed += _matpower_unlike_andes(path)
    return AndesImport(
        case,
        left_out,
        ignored,
        pf_bus,
        pf_vmag,
        pf_vang,
        tuple(changed + read_as),
        tuple(unlike),
        solution,
        tuple(given.defaulted),
        _switched_off(ss, path.name),
    )


#: relative difference of a branch's or a bus shunt's value between ANDES's reading of a
#: RAW file and the file's (`_raw_unlike_andes`) named as a change
RAW_BRANCH_TOL = 1e-6


#: the record `read_raw` names an isolated bus by (its ``switched_off``)
_ISOLATED = re.compile(r"bus (\d+): isolated \(IDE 4\)")


def _raw_unlike_andes(path: Path, case: Case) -> list[str]:
    """What ANDES's RAW reader makes of a RAW file otherwise than PSS/E (and ``import-psse``,
    stabctl's own reading, `stabctl.io.psse_raw.read_raw`) reads it, each record named with
    both readings and kept as ANDES reads it: the branches (`_branches_unlike_raw`), the
    buses' shunts, the records PSS/E leaves out or stabctl cannot represent, the isolated
    (IDE 4) buses ANDES keeps, the controls held at their RAW setting, remote voltage
    regulation and the Q limits of wind machines (round 59 BD01-BD08, BD14: each went
    without a word).  Nothing when stabctl cannot read the file itself (``import-psse``
    names why)."""
    from stabctl.io.psse_raw import read_raw

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            raw = read_raw(path)
    except (CaseError, InputError):
        return []
    file, ours = path.name, set(case.buses.number.tolist())
    return [
        *_branches_unlike_raw(file, raw, case),
        *_shunts_unlike_raw(file, raw, case),
        *(
            f"{s} (import-psse: unsupported; not in ANDES's reading as PSS/E has it)"
            for s in raw.unsupported
        ),
        *(
            f"{s}, which PSS/E leaves out with the records at it: ANDES's reading keeps it"
            for s in raw.switched_off
            if (m := _ISOLATED.fullmatch(s.record)) and int(m.group(1)) in ours
        ),
        *(f"{h.source} (ANDES's reading holds it too)" for h in raw.held),
        *(
            f"{file}: generator at bus {int(g)} regulates bus {int(r)}'s voltage at VS {vs:g} "
            f"(IREG): ANDES's reading holds bus {int(g)}'s own"
            for g, r, vs, _ in raw.vreg_con
        ),
        *(f"{s}: ANDES's reading keeps QT and QB" for s in raw.changed if "WPF" in s.record),
    ]


def _matpower_unlike_andes(path: Path) -> list[str]:
    """What ANDES's MATPOWER reader (``andes.io.matpower``) makes of a ``.m`` file otherwise
    than MATPOWER: a branch of TAP 0 (ratio 1) with a SHIFT, which MATPOWER's ``makeYbus``
    applies and ANDES drops; buses of BASE_KV 0 (not given), which ANDES reads as 110 kV
    (round 59 BD15-16: both without a word)."""
    from andes.io.matpower import m2mpc

    try:
        mpc = m2mpc(str(path))
        branch, bus = np.asarray(mpc["branch"], float), np.asarray(mpc["bus"], float)
    except (OSError, ValueError, KeyError, IndexError):  # ANDES read it: nothing to name
        return []
    found = [
        f"{path.name} branch {int(b[0])}-{int(b[1])} (row {k + 1}): SHIFT {b[9]:g} deg with "
        "TAP 0 (MATPOWER: ratio 1, the shift applied): ANDES's MATPOWER reader drops the shift"
        for k, b in enumerate(branch)
        if b.size > 9 and b[8] == 0 and b[9] != 0
    ]
    unknown = [int(b[0]) for b in bus if b.size > 9 and b[9] == 0]
    if unknown:
        found.append(
            f"{path.name}: {len(unknown)} bus(es) of BASE_KV 0 (not given: "
            f"{_row_list(unknown)}): ANDES's MATPOWER reader reads them as 110 kV"
        )
    return found


def _branches_unlike_raw(file: str, raw, case: Case) -> list[str]:
    """The branches ANDES's RAW reader reads otherwise than the RAW file states them
    (``raw``, stabctl's reading): ratio, phase, r, x, charging b and line-end shunts, named
    each with both readings: a two-winding transformer's WINDV2, which ANDES drops (PSS/E's
    TVC system: ratio 1 for 0.96154), Nordic 44's transformers, whose reactances ANDES
    reads ten times the file's, a line's GI/BI/GJ/BJ, which ANDES drops, a transformer's
    magnetising admittance, which ANDES reads as line charging."""
    br = case.branches
    rows: dict[tuple[int, int], list[int]] = {}
    for k, (f, t) in enumerate(zip(br.from_bus, br.to_bus)):
        rows.setdefault((int(f), int(t)), []).append(k)
    seen: dict[tuple[int, int], int] = {}
    found = []
    for row in raw.line:
        pair = (int(row[0]), int(row[1]))
        n = seen[pair] = seen.get(pair, 0) + 1
        if len(rows.get(pair, [])) < n:
            continue
        k = rows[pair][n - 1]
        ends = tuple(row[10:14]) if row.size > 10 else (0.0,) * 4
        given = (row[5] or 1.0, row[6], row[2], row[3], row[4], *ends)
        andes = (
            br.tap[k] or 1.0,
            br.phase_deg[k],
            br.r[k],
            br.x[k],
            br.b[k],
            br.g_from[k],
            br.b_from[k],
            br.g_to[k],
            br.b_to[k],
        )
        if all(abs(a - b) <= RAW_BRANCH_TOL * max(1.0, abs(b)) for a, b in zip(andes, given)):
            continue
        found.append(
            f"{file} branch {pair[0]}-{pair[1]} (circuit {n}): {_branch_text(andes)} as "
            f"ANDES's RAW reader reads it; the file states {_branch_text(given)} (import-psse "
            "reads it as the file states)"
        )
    return found


def _branch_text(v) -> str:
    """ratio, phase, r, x, b and the line-end shunts of a branch (pu, deg) for a message."""
    ends = (
        ""
        if not any(v[5:])
        else (
            f", line-end shunts g, b {v[5]:.5g}, {v[6]:.5g} (from) {v[7]:.5g}, {v[8]:.5g} (to) pu"
        )
    )
    return (
        f"ratio {v[0]:.5g}, phase {v[1] + 0.0:g} deg, r {v[2]:.5g}, x {v[3]:.5g}, "
        f"b {v[4]:.5g} pu{ends}"
    )


def _shunts_unlike_raw(file: str, raw, case: Case) -> list[str]:
    """The buses whose fixed shunt g, b (pu) ANDES's RAW reader reads otherwise than
    stabctl's reading of the file (``raw``): a transformer's magnetising conductance, which
    ANDES drops, for one."""
    b = case.buses
    at = {int(n): (g, s) for n, g, s in zip(b.number, b.gshunt, b.bshunt)}
    found = []
    for row in raw.bus:
        num = int(row[0])
        if num not in at:
            continue
        given, andes = (row[7], row[8]), at[num]
        if all(abs(a - g) <= RAW_BRANCH_TOL * max(1.0, abs(g)) for a, g in zip(andes, given)):
            continue
        found.append(
            f"{file} bus {num}: shunt g {andes[0]:.5g}, b {andes[1]:.5g} pu as ANDES's RAW "
            f"reader reads it; the file gives g {given[0]:.5g}, b {given[1]:.5g} pu (import-psse)"
        )
    return found


#: parameters stabctl reads that ANDES fills with its default when the case file leaves
#: them out (an empty cell, NaN, no column): refused instead (`_file_inputs`)
_REQUIRED_INPUTS = {
    "Line": ("r", "x"),
    "PQ": ("p0", "q0"),
    "PV": ("p0", "v0"),
    "Slack": ("v0",),
    "GENCLS": ("M", "xd1"),
    "GENROU": ("M", "xd", "xq", "xd1", "xq1", "xd2", "Td10", "Tq10", "Td20", "Tq20"),
}
#: ANDES's groups of the machines and their controls (`_file_inputs`): a parameter the
#: file leaves out is named with the default ANDES runs; one ANDES declares non-zero or
#: of one sign (`_SIGNED`) is a change, refused unless on_unsupported="skip"
_DYNAMIC_GROUPS = ("SynGen", "Exciter", "TurbineGov", "PSS")
#: ANDES's NumParam flags for a value it replaces by its default (``NumParam.add``)
_SIGNED = ("non_zero", "non_negative", "non_positive")
#: columns of a model's rows that are not its parameters: ANDES's row number ``uid`` (the
#: xlsx files it writes) and ``idx`` (a parameter of some models only)
_ROW_COLUMNS = ("uid", "idx")
_ZERO_IMPEDANCE = (
    "a zero impedance, refused as import-psse refuses R + jX = 0 (merge the two buses, "
    "or give the line its impedance)"
)


class _Formula(str):
    """The text of a spreadsheet formula whose value the file does not hold (saved by a
    program that does not compute formulas): read by pandas, and so ANDES, as empty."""


class _ErrorCell(str):
    """A spreadsheet cell holding an error value (``#VALUE!``, ``#DIV/0!``, ``#N/A``, ...:
    a formula that failed): read by pandas, and so ANDES, as empty."""


#: the error values a spreadsheet cell can hold (openpyxl's ``ERROR_CODES``)
_ERROR_VALUES = frozenset(
    ("#NULL!", "#DIV/0!", "#VALUE!", "#REF!", "#NAME?", "#NUM!", "#N/A", "#GETTING_DATA")
)


class _NaText(float):
    """A spreadsheet cell holding text that pandas, and so ANDES, reads as NaN ("NaN",
    "N/A", "null", ...): NaN, with the text kept to say so (`_how_left_out`)."""

    text: str

    def __new__(cls, text: str) -> _NaText:
        obj = super().__new__(cls, float("nan"))
        obj.text = text
        return obj


@dataclass(frozen=True)
class _Given:
    """What `_file_inputs` found in the rows of a case file."""

    #: parameters left out, run at ANDES's default (``AndesImport.defaulted``)
    defaulted: list[str]
    #: (sheet, idx, why) of the required ones left out in the machines and their controls
    changed: list[tuple[str, str, str]]
    #: "SHEET column 'NAME': why" of the columns that are no parameter of their model
    unknown: list[str]


def _json_data(path: Path) -> Any:
    """The parsed content of a json case file, None if it is not JSON text (ANDES's own
    reading names what is wrong).

    Raises
    ------
    InputError
        An object giving a key twice (`stabctl.jsontext.parse_json`: ANDES would read
        the last model sheet of that name only).
    """
    try:
        return parse_json(path.read_text(encoding="utf-8"), path.name)
    except InputError:
        raise
    except (OSError, ValueError, RecursionError):  # UnicodeDecodeError is a ValueError
        return None


#: what import_andes reads of a json file, for messages
_ANDES_JSON = (
    "an ANDES json case is an object of ANDES model names (Bus, Line, GENROU, ...), each a "
    "list of device records (objects of parameter -> value)"
)


def _first_text_byte(f) -> bytes:
    """The first byte of open binary file ``f`` that is not JSON white space (b"" if
    none), read in 64 KiB blocks."""
    while block := f.read(1 << 16):
        text = block.lstrip(b" \t\r\n")
        if text:
            return text[:1]
    return b""


def _check_json_layout(path: Path) -> None:
    """InputError for a json file that is not in ANDES's layout (`_ANDES_JSON`), naming
    what it is (a stabctl case, a PSTess matrix file) or the key that breaks the layout:
    ANDES read a stabctl case's ``"version": 1`` as model rows and failed with
    "'int' object is not iterable".  A key given twice is refused (`_json_data`), and a
    byte-order mark (ANDES's reader fails on it), and a file whose first character
    cannot start JSON text (NULs, a spreadsheet renamed, ...), before it is read whole;
    other text that is not JSON is left to ANDES, whose message names it."""
    from stabctl.io.pst import FORMAT
    from stabctl.jsontext import MAX_JSON_BYTES, input_file

    input_file(path, "case file", MAX_JSON_BYTES)  # read whole below (and by ANDES)
    with open(path, "rb") as f:
        if f.read(3) == b"\xef\xbb\xbf":
            raise InputError(
                f"{path.name}: the file starts with a byte-order mark (a UTF-8 BOM, written "
                "by some Windows editors), which ANDES's json reader cannot read: save it "
                "as UTF-8 without one"
            )
        f.seek(0)
        first = _first_text_byte(f)
    if not first or first not in b'{["-0123456789tfn':  # (round 42: 200 MB of NULs was
        # read whole three times, 1 GiB, before ANDES said "Expecting value")
        said = "nothing but white space" if not first else f"it starts with the byte {first!r}"
        raise InputError(f"{path.name}: not JSON text ({said}): {_ANDES_JSON}")
    data = _json_data(path)
    if data is None:
        return
    own = "stabctl's commands read it as it is (simulate, cct, eig, ...: CASE)"
    if isinstance(data, dict) and data.get("format") == FORMAT:
        raise InputError(
            f'{path.name}: a stabctl case file ("format": "{FORMAT}"), not an ANDES case: '
            f"{own}; import-andes converts a case ANDES reads ({_ANDES_JSON}; xlsx, PSS/E "
            "RAW [+ DYR], MATPOWER)"
        )
    bus = data.get("bus") if isinstance(data, dict) else None
    if isinstance(bus, list) and bus and all(isinstance(r, list) for r in bus):
        raise InputError(
            f"{path.name}: a PSTess matrix file (its 'bus' a matrix), not an ANDES case: "
            f"{own}; {_ANDES_JSON}"
        )
    if not isinstance(data, dict):
        raise InputError(f"{path.name}: holds {_json_kind(data)}, not an ANDES case: {_ANDES_JSON}")
    for key, value in data.items():
        if isinstance(value, list) and len(value) > MAX_MODEL_ROWS:
            raise InputError(
                f"{path.name}: {key} holds {len(value)} records, more than {MAX_MODEL_ROWS} "
                "(a planning case of 100 000 buses has a few 100 000): not read"
            )
        bad = (
            value
            if not isinstance(value, list)
            else next((v for v in value if not isinstance(v, dict)), None)
        )
        if key != "_config" and (not isinstance(value, list) or bad is not None):
            what = (
                _json_kind(value)
                if not isinstance(value, list)
                else f"a list holding {_json_kind(bad)}"
            )
            raise InputError(
                f"{path.name}: key {key!r} holds {what}, not a list of device records: not "
                f"an ANDES case ({_ANDES_JSON})"
            )
        if key != "_config":
            _check_texts(path, key, value)


#: the longest text of a field of an ANDES json case read (a name or idx is a few tens of
#: characters): round 42, a Bus idx of 266 million characters took 2 GB in ANDES's copies
MAX_FIELD_TEXT = 1024


def _check_texts(path: Path, key: str, rows: list[dict]) -> None:
    """InputError for a field of `key`'s device records (`rows`) holding a text longer
    than MAX_FIELD_TEXT characters, naming its row (1-based) and field, before ANDES
    copies it."""
    for k, row in enumerate(rows, 1):
        for name, v in row.items():
            if isinstance(v, str) and len(v) > MAX_FIELD_TEXT:
                raise InputError(
                    f"{path.name}: {key} row {k}: {name} holds a text of {len(v)} characters,"
                    f" more than {MAX_FIELD_TEXT} (no name or parameter is so long): not read"
                )


def _json_kind(value) -> str:
    """What a JSON value is, for a message."""
    if isinstance(value, dict):
        return "an object"
    if isinstance(value, list):
        return "a list"
    if isinstance(value, str):
        return f"the text {json.dumps(value[:40])}"
    return f"the value {json.dumps(value)}"


def _input_rows(path: Path) -> tuple[dict, dict[str, list[int]]]:
    """ANDES model -> the rows (dicts) of an xlsx or json case file as written, before
    ANDES fills its defaults ({} for other formats, whose own readers give defaults); an
    xlsx formula cell without a stored value is a `_Formula`.  And for an xlsx file,
    sheet -> each row's number in the spreadsheet (its header is row 1)."""
    if path.suffix.lower() == ".json":
        data = _json_data(path)
        rows = {k: v for k, v in data.items() if isinstance(v, list)}
        return (rows if isinstance(data, dict) else {}), {}
    if path.suffix.lower() == ".xlsx":
        import pandas as pd  # type: ignore[import-untyped]  # ANDES reads xlsx with it

        try:
            sheets = pd.read_excel(path, sheet_name=None)
            texts = _cell_texts(path)
        except Exception as exc:  # noqa: BLE001 - any reader's failure, named
            # ANDES read the file (before these checks): a workbook stabctl cannot read
            # as written (an external link openpyxl cannot follow) would run unchecked
            raise InputError(
                f"{path.name}: ANDES reads the workbook, but stabctl cannot read it as "
                "written to check its rows before ANDES fills its defaults "
                f"({type(exc).__name__}: {' '.join(str(exc).split())[:200]}): refused"
            ) from None
        kept = {  # rows with a value, or a cell pandas read as NaN that holds something
            name: df[df.notna().any(axis=1) | df.index.isin([i for i, _ in texts.get(name, {})])]
            for name, df in sheets.items()
        }
        rows = {}
        for name, df in kept.items():
            rows[name] = df.to_dict("records")
            at = {int(i): k for k, i in enumerate(df.index)}
            for (i, col), text in texts.get(name, {}).items():
                row = rows[name][at[i]] if i in at else {}
                if col in row and pd.isna(row[col]):  # pandas kept no value of it
                    row[col] = (
                        _Formula(text)
                        if text.startswith("=")
                        else _ErrorCell(text)
                        if text in _ERROR_VALUES
                        else _NaText(text)
                    )
        return rows, {name: [int(i) + 2 for i in df.index] for name, df in kept.items()}
    return {}, {}


#: the texts pandas's read_excel reads as NaN (its default ``na_values``), but for ''
_NA_TEXTS = frozenset(
    [
        "#N/A",
        "#N/A N/A",
        "#NA",
        "-1.#IND",
        "-1.#QNAN",
        "-NaN",
        "-nan",
        "1.#IND",
        "1.#QNAN",
        "<NA>",
        "N/A",
        "NA",
        "NULL",
        "NaN",
        "None",
        "n/a",
        "nan",
        "null",
    ]
)


def _cell_texts(path: Path) -> dict[str, dict[tuple[int, Any], str]]:
    """Sheet -> {(row from 0 below the header, column name): text} of the cells of an
    xlsx file that pandas reads as NaN though they hold something: a formula (pandas
    reads the value the file holds: NaN where it holds none), or text pandas takes for
    NaN ("NaN", "N/A", "null", ...)."""
    import openpyxl  # type: ignore[import-untyped]  # ANDES reads xlsx with it (pandas)

    # links to other workbooks not followed, as pandas and ANDES read it
    book = openpyxl.load_workbook(path, read_only=True, data_only=False, keep_links=False)
    try:
        found = {}
        for sheet in book.worksheets:
            sheet.reset_dimensions()  # read-only sheets may give no size
            rows = sheet.iter_rows(values_only=True)
            header = next(rows, ())
            found[sheet.title] = {
                (i, col): v
                for i, row in enumerate(rows)
                for col, v in zip(header, row)
                if isinstance(v, str)
                and (v.startswith("=") or v in _NA_TEXTS or v in _ERROR_VALUES)
            }
        return found
    finally:
        book.close()


def _file_inputs(path: Path, ss) -> _Given:
    """The rows of an xlsx or json case file as written, checked before ANDES fills its
    defaults (nothing for other formats, whose readers give their own).

    Refused, naming file, sheet, row, idx, parameter and value: a sheet (json key) that
    is no ANDES model (InputError: ANDES skips it); CaseError for a formula without a
    stored value; a link to a device the case does not hold (`_check_references`); a
    json ``true``/``false``, list or object where ANDES reads a number (it reads true as
    1; a list failed in its set-up, naming nothing of the file); a status ``u`` other
    than 0 or 1; a line of zero impedance (r = x = 0); a share ``gammap``/``gammaq``
    outside [0, 1] (`stabctl.models.converters.rules.SHARES`);
    a value of :data:`_REQUIRED_INPUTS` left out or other than a number; in any model
    stabctl reads, a value ANDES would replace by its default (`_violated`: 0 where its
    declaration says non-zero, a sign it must not have, a PVD1 current limit of 0 or -1.1
    run at 1.3, a GENROU M of 0 or -13 at H = 3 s) or an infinite one; converter data that
    cannot be (`stabctl.models.converters.rules.RULES`, the ibr_con table's: REECA1 Imax <=
    0, Vdip >= Vup, ESD1 SOC limits, En <= 0, REGCA1's Iq rate limits, ...); machine,
    exciter and governor data that cannot be (:data:`_DYNAMIC_LIMITS`: M <= 0, D < 0, a
    negative time constant, a zero one the model does not bypass, a droop R <= 0).

    Returned (`_Given`): the parameters of the converter family and of the machines and
    their controls that the file leaves out (no column, an empty cell), run at ANDES's
    default, one line per model and parameter; those of the machines and their controls
    that ANDES declares non-zero or signed as changes; the columns that are no parameter
    of their model (ANDES ignores them).  The values ANDES copies from a linked device
    (its ``ExtParam``: a REECA1's bus and Sn from its REGCA1, a REPCA1's monitored line's
    r and x) are not parameters of the file."""
    from andes.core.param import ExtParam, NumParam

    missing: dict[tuple[str, str, str, str], list[int]] = {}
    given = _Given([], [], [])
    all_rows, sheet_rows = _input_rows(path)
    for sheet, rows in all_rows.items():
        if sheet == "_config":  # ANDES's settings, in the files it writes
            continue
        m = ss.models.get(sheet)
        m = ss.model_aliases.get(sheet) if m is None else m  # Toggler: Toggle
        if m is None:
            what = "sheet" if path.suffix.lower() == ".xlsx" else "key"
            raise InputError(
                f"{path.name}: {what} {sheet!r} is no ANDES model (ANDES would skip its "
                f"{len(rows)} row(s))"
            )
        model = m.class_name
        given.unknown.extend(
            f"{sheet} column {c!r}: no parameter of ANDES's {model}"
            for c in dict.fromkeys(c for row in rows for c in row)
            if c not in m.params and c not in _ROW_COLUMNS
        )
        # a Fault's rf, xf too (round 48: ieee14_fault's, left empty, ran at ANDES's unsaid)
        dynamic = m.group in _DYNAMIC_GROUPS or model == "Fault"
        lines = sheet_rows.get(sheet, [])
        _check_unique_idx(path.name, sheet, rows, lines)
        for k, row in enumerate(rows, start=1):
            line = f"; spreadsheet row {lines[k - 1]}" if k <= len(lines) else ""
            where = f"{path.name}: {sheet} row {k} (idx {row.get('idx')}{line})"
            _check_row(where, model, row)
            _check_references(where, m, row, ss)
            values = {}
            for name, p in m.params.items():
                if not isinstance(p, NumParam) or isinstance(p, ExtParam):
                    continue  # an ExtParam is copied from a linked device, not a default
                v = row.get(name)
                empty = v is None or (isinstance(v, float) and v != v)
                number = not empty and isinstance(v, (int, float)) and not isinstance(v, bool)
                if isinstance(v, (bool, list, dict)) and p.vtype is float:
                    read = f"reads it as {int(v)}" if isinstance(v, bool) else "cannot read it"
                    raise CaseError(
                        f"{where}: {name} = {json.dumps(v)}: not a number (ANDES {read})"
                    )
                if name in _REQUIRED_INPUTS.get(model, ()) and not (number and np.isfinite(v)):
                    raise CaseError(
                        f"{where}: {name} "
                        + (
                            f"= {v!r}: not a finite number"
                            if not empty
                            else f"= {v.text!r} (read as NaN): missing"
                            if isinstance(v, _NaText)
                            else "missing"
                        )
                        + f" (ANDES would run with its default {p.default!r})"
                    )
                if (model, name) in _UNREAD:  # never "run at ANDES's default": not run
                    if not empty and (why := ac8b.without_effect(name, v)):
                        given.changed.append((sheet, str(row.get("idx")), why))
                    continue
                if empty:
                    values[name] = p.default
                    if dynamic and any(p.get_property(f) for f in _SIGNED):
                        why = f"{name} left empty, run at ANDES's default {p.default!r}"
                        given.changed.append((sheet, str(row.get("idx")), f"{why} ({_must(p)})"))
                    elif dynamic or model in _CONVERTER_FAMILY:
                        key = (model, name, _default_text(m, p), _how_left_out(path, row, name))
                        missing.setdefault(key, []).append(k)
                    continue
                if not number:
                    if isinstance(v, str) and p.vtype is float and not _reads_as_number(v):
                        raise CaseError(
                            f"{where}: {name} = {v!r}: not a number (ANDES cannot read it)"
                        )
                    continue  # a number in text ANDES reads, or another kind it names
                values[name] = v
                rule = _violated(p, v) if model not in IGNORED_MODELS else ""
                if rule:
                    raise CaseError(
                        f"{where}: {name} = {v:g} ({rule}: ANDES would run with its "
                        f"default {p.default!r})"
                    )
            shares = (law for law in SHARES if law.names[0] in m.params)  # machines' too
            for law in (*CONVERTER_RULES.get(model, ()), *shares):  # the ibr_con table's own
                if all(n in values for n in law.names) and not law.holds(values):
                    shown = ", ".join(f"{n} = {values[n]:g}" for n in law.names)
                    raise CaseError(f"{where}: {shown}: it must be {law.what}")
            _check_limits(where, model, values)
    given.defaulted.extend(
        f"{model} {name} = {default} (row{'s' * (len(rows) > 1)} {_row_list(rows)}: {how})"
        for (model, name, default, how), rows in missing.items()
    )
    _check_group_idx(path.name, all_rows, sheet_rows, ("PV", "Slack"), "StaticGen")
    _check_one_per_machine(path.name, all_rows, sheet_rows, ss)
    return given


#: (model, parameter) of the ANDES models stabctl maps that no run reads (a given value is
#: named by the mapping, `stabctl.models.exciters.ac8b.without_effect`)
_UNREAD = frozenset(("AC8B", name) for name in ac8b.UNMODELLED)

#: ANDES groups of which a machine (a stabiliser: an exciter) has one device at most, and
#: the parameter linking a device to it
_ONE_PER = {"Exciter": ("syn", "exciter"), "TurbineGov": ("syn", "turbine governor")}
_ONE_PER |= {"PSS": ("avr", "stabiliser")}


def _check_one_per_machine(file: str, all_rows: dict, sheet_rows: dict, ss) -> None:
    """CaseError for a second exciter, turbine governor or stabiliser of one machine
    (exciter), naming both rows: ANDES said only "Your input data may be inconsistent"
    for two TGOV1 of one GENROU (round 40), where a DYR's are named
    (`stabctl.io.dyr`)."""
    first: dict = {}
    for sheet, rows in all_rows.items():
        m = ss.models.get(sheet)
        m = ss.model_aliases.get(sheet) if m is None else m  # (a model of no device is falsy)
        if m is None or m.group not in _ONE_PER:
            continue
        link, what = _ONE_PER[m.group]
        lines = sheet_rows.get(sheet, [])
        for k, row in enumerate(rows, start=1):
            to = row.get(link)
            if to is None or (isinstance(to, float) and to != to):
                continue
            key = (m.group, int(to) if isinstance(to, float) and to.is_integer() else to)
            line = f"; spreadsheet row {lines[k - 1]}" if k <= len(lines) else ""
            here = f"{sheet} row {k} (idx {row.get('idx')}{line})"
            if key in first:
                raise CaseError(
                    f"{file}: {here}: a second {what} of {link} {key[1]!r} (the first: "
                    f"{first[key]}); ANDES cannot read such a case"
                )
            first[key] = here


def _reads_as_number(text: str) -> bool:
    """Whether ANDES reads ``text``, the cell of a parameter of ``vtype`` float, as a
    number (its float()); a parameter of another type (Alter's ``method``, ShuntSw's
    lists) holds text."""
    try:
        float(text)
    except ValueError:
        return False
    return True


def _how_left_out(path: Path, row: dict, name: str) -> str:
    """How a case file's row leaves parameter ``name`` out, for the summary: no such key
    or column, an empty cell (xlsx: pandas reads it as NaN) or JSON null, a JSON NaN."""
    if name not in row:
        return "not in the file"
    v = row[name]
    if path.suffix.lower() == ".json" and isinstance(v, float) and v != v:
        return "NaN in the file"
    if isinstance(v, _NaText):
        return f"the text {v.text!r} in the file, read as NaN"
    return "empty in the file"


def _default_text(m, p) -> str:
    """What ANDES runs parameter ``p`` of model ``m`` at where a file leaves it out: its
    default, or where that is no number (None, NaN) the value its ``NumSelect`` takes
    instead (REPCA1's Rc: its line's r; WTTQA1's Tn: its generator's Sn)."""
    from andes.core.service import NumSelect

    d = p.default
    if d is not None and not (isinstance(d, float) and d != d):
        return repr(d)
    for svc in vars(m).values():  # ANDES keeps its NumSelect services as attributes
        if isinstance(svc, NumSelect) and svc.optional is p:
            fallback = getattr(svc.fallback, "name", svc.fallback)
            return f"{fallback}, ANDES's value where {p.name} is not given ({svc.info})"
    return f"{d!r}, unset"


def _check_references(where: str, m, row: dict, ss) -> None:
    """CaseError for a row naming a device that the case does not hold, before ANDES links
    the devices (its set-up's message names neither sheet nor row, at times another model):
    a device its model finds by idx (ANDES's ``DeviceFinder``: a PVD1's, ESD1's or REPCA1's
    ``busf``, a frequency measurement), for which ANDES would add a BusFreq with its defaults
    at the device's bus instead; every idx it takes values of that device by (the indexer
    of an ``Ext*`` value: a converter's ``gen``, a REECA1's ``reg``, a WTARA1's ``rego``,
    ...); and every other idx of a model or group (an ``IdxParam``'s: a converter's
    ``bus``) the case has devices of (a Bus's ``area`` where it has no Area is left to
    ANDES, which does not need it)."""
    from andes.core.param import IdxParam
    from andes.core.service import DeviceFinder

    finders = {}
    links: dict[str, str] = {}
    for name, p in m.params.items():  # of a model or group the case has (a Bus's area)
        if isinstance(p, IdxParam) and isinstance(p.model, str) and _holds(ss, p.model):
            links[name] = p.model
    for svc in vars(m).values():  # ANDES keeps its services and Ext* values as attributes
        if isinstance(svc, DeviceFinder):
            finders[svc.u.name] = svc
        indexer, model = getattr(svc, "indexer", None), getattr(svc, "model", None)
        if isinstance(indexer, IdxParam) and indexer.name in m.params and isinstance(model, str):
            links.setdefault(indexer.name, model)
    for name, target in {**links, **{n: f.model for n, f in finders.items()}}.items():
        v = row.get(name)
        if v is None or (isinstance(v, float) and v != v):
            continue  # none named: ANDES finds or adds one (busf), or none is needed
        # ANDES looks it up in the parameter's model or group (busf: any FreqMeasurement)
        if target in ss.models:
            known, what = ss.models[target].idx.v, target
        elif target in ss.groups:
            group = ss.groups[target]
            known = group.get_all_idxes()
            members = ", ".join(n for n, k in group.models.items() if k.n)
            what = f"{target} ({members or 'none in the case'})"
        else:
            continue
        if v in known:
            continue
        shown = int(v) if isinstance(v, float) and v.is_integer() else v
        if name in finders:
            raise CaseError(
                f"{where}: {name} = {shown!r}: no {target} of that idx in the case (ANDES "
                f"would add a {finders[name].default_model} with its defaults at the "
                "device's bus instead)"
            )
        raise CaseError(
            f"{where}: {name} = {shown!r}: no {what} of that idx in the case (ANDES cannot "
            "link the device to it)"
        )


def _holds(ss, name: str) -> bool:
    """Whether ANDES's ``ss`` holds devices of model or group ``name``."""
    if name in ss.models:
        return ss.models[name].n > 0
    return name in ss.groups and any(k.n for k in ss.groups[name].models.values())


def _check_unique_idx(file: str, sheet: str, rows: list, lines: list) -> None:
    """CaseError for an idx two rows of one sheet give: ANDES renames the second (with a
    warning) and a device linked to that idx (a Toggle's line, a control's machine) then
    reaches the first, whichever the file meant."""
    seen: dict = {}
    for k, row in enumerate(rows, start=1):
        key = _idx_key(row.get("idx"))
        if key is None:
            continue
        if key in seen:
            at = [_row_at(j, lines) for j in (seen[key], k)]
            raise CaseError(
                f"{file}: {sheet} {at[0]} and {at[1]} both give idx {key!r}: ANDES would "
                "rename the second, and a device linked to that idx reach the first"
            )
        seen[key] = k


def _idx_key(idx):
    """A row's idx as its devices are told apart (a whole float as the integer it is), or
    None for none (absent, empty: NaN)."""
    if idx is None or (isinstance(idx, float) and idx != idx):
        return None
    return int(idx) if isinstance(idx, float) and idx.is_integer() else idx


def _row_at(k: int, lines: list) -> str:
    """``"row K (spreadsheet row N)"``, row K of a sheet whose rows lie on `lines`."""
    return f"row {k}" + (f" (spreadsheet row {lines[k - 1]})" if k <= len(lines) else "")


def _check_group_idx(file: str, all_rows: dict, sheet_rows: dict, sheets, group: str) -> None:
    """CaseError for an idx that rows of two sheets of one ANDES group give (a PV's and a
    Slack's, both StaticGen): a device linked to it by the group (a machine's ``gen``)
    reaches either (round 48: refused only through its consequence, two machines taking
    one static generator's power twice)."""
    seen: dict = {}
    for sheet in sheets:
        lines = sheet_rows.get(sheet, [])
        for k, row in enumerate(all_rows.get(sheet, ()), start=1):
            key = _idx_key(row.get("idx"))
            if key is None:
                continue
            at = f"{sheet} {_row_at(k, lines)}"
            if key in seen and not seen[key].startswith(f"{sheet} "):
                raise CaseError(
                    f"{file}: {seen[key]} and {at} both give idx {key!r}: ANDES's {group} "
                    "group holds both, and a device linked to that idx reaches either"
                )
            seen.setdefault(key, at)


def _check_row(where: str, model: str, row: dict) -> None:
    """CaseError for a formula without a stored value or a spreadsheet error value
    (`_ErrorCell`) in any column of a case file's row, a connection status ``u`` other
    than 0 or 1 (ANDES multiplies by it), or a Line of zero impedance."""
    for name, v in row.items():
        if isinstance(v, _Formula):
            raise CaseError(
                f"{where}: {name} is a formula ({v}) whose value the file does not hold "
                "(saved without computing it: ANDES would read it as empty)"
            )
        if isinstance(v, _ErrorCell):
            raise CaseError(
                f"{where}: {name} is the spreadsheet error {v} (a formula that failed: "
                "ANDES would read it as empty and run its default)"
            )
    u = row.get("u")
    if u is not None and u == u and u not in (0, 1):
        raise CaseError(f"{where}: u = {u!r}: the connection status must be 0 or 1")
    if model == "Line" and row.get("r") == 0 and row.get("x") == 0:
        buses = f"buses {row.get('bus1')} and {row.get('bus2')}"
        raise CaseError(f"{where}: r = x = 0 between {buses}: {_ZERO_IMPEDANCE}")


def _corrections(file: str, ss) -> None:
    """CaseError for network data ANDES replaced by its defaults as it added the devices
    (its ``Model._param_corrections``: a value 0 where its declaration says non-zero or
    of a sign it must not have, a RAW file's branch of zero reactance run at x = 1e-8):
    a RAW or MATPOWER file's; an xlsx or json file's values were checked before
    (`_file_inputs`), the DYR records' are after (`_against_dyr`)."""
    shown = {"non_zero": "= 0", "non_negative": "< 0", "non_positive": "> 0"}
    for name in _NETWORK:
        m = ss.models[name]
        for (param, violation), idxes in getattr(m, "_param_corrections", {}).items():
            k = m.uid[idxes[0]]
            where = f"{file}: {name} {idxes[0]}"
            if name == "Line":
                where += f" (buses {m.bus1.v[k]}-{m.bus2.v[k]})"
                if param == "x" and m.r.v[k] == 0:
                    raise CaseError(f"{where}: r = x = 0: {_ZERO_IMPEDANCE}")
            raise CaseError(
                f"{where}: {param} {shown.get(violation, violation)} (ANDES would run with "
                f"its default {m.params[param].default!r})"
            )


def _must(p) -> str:
    """What ANDES's NumParam ``p`` declares its value must be ("> 0", ">= 0", ...)."""
    non_zero, non_negative, non_positive = (p.get_property(f) for f in _SIGNED)
    sign = ">" if non_negative else "<" if non_positive else ""
    return f"it must be {sign}{'' if non_zero else '='} 0" if sign else "it must not be 0"


#: the converter family's models whose input rows are checked before ANDES fills its
#: defaults (`_file_inputs`)
_CONVERTER_FAMILY = (
    "REGCA1", "REGCP1", "REECA1", "REECA1E", "REECB1", "REPCA1", "PVD1", "ESD1",
    "WTDTA1", "WTDS", "WTARA1", "WTPTA1", "WTTQA1",
)  # fmt: skip

#: the synchronous machines', exciters' and governors' values that cannot be, refused
#: before ANDES runs them (`_file_inputs`, `_check_limits`): ANDES model -> (parameters
#: that must be > 0, parameters that must be >= 0, rate feedback (TF, KF): TF > 0 where
#: KF != 0).  Machines: M = 2H > 0, damping D >= 0; GENROU's T'do and T''do > 0, its
#: T'qo and T''qo >= 0 (0: no such q-axis winding, kept as PST keeps it; stabctl's
#: mac_con check).  Controls: every time constant >= 0 (0 bypasses its block, a negative
#: one is no lag); > 0 those the model cannot bypass, each type module's ``NEEDS``
#: (`stabctl.models.exciters`, `stabctl.models.governors`: TGOV1 T1 and T3, the DC
#: exciters' TE and TF, ...) and HYGOV's r, Tr, TW (`stabctl.io.dyr`); a droop R that
#: divides (TGOV1, GAST, TG2: 1/R) > 0, one that multiplies (HYGOV's R, HYGOV4's Rperm
#: and Rtemp: 0 isochronous) >= 0.  Sources: PSS/E Model Library (GENROU, TGOV1, HYGOV),
#: ANDES 2.0 ``andes/models`` (its parameters' names; a LeadLag with T2 = 0 bypassed).
_DYNAMIC_LIMITS: dict[str, tuple[tuple[str, ...], tuple[str, ...], tuple[str, ...]]] = {
    "GENROU": (("M", "Td10", "Td20"), ("D", "Tq10", "Tq20"), ()),
    "GENCLS": (("M",), ("D",), ()),
    "ESST3A": ((), ("TR", "TC", "TB", "TA", "TM"), ()),
    **{
        dc: (("TE", "TF1"), ("TR", "TA", "TB", "TC"), ())
        for dc in ("IEEEX1", "EXDC2", "ESDC2A", "ESDC1A")
    },
    "IEEET1": (("TE", "TF"), ("TR", "TA"), ()),
    "EXST1": (("TA",), ("TR", "TC", "TB"), ("TF", "KF")),
    "ESST1A": (("TA",), ("TR", "TB", "TC", "TB1", "TC1"), ("TF", "KF")),
    "EXAC4": (("TA",), ("TR", "TC", "TB"), ()),
    "EXAC1": (("TA", "TE"), ("TR", "TB", "TC"), ("TF", "KF")),
    "ESAC1A": (("TA", "TE"), ("TR", "TB", "TC"), ("TF", "KF")),
    "AC8B": (("TA", "TE"), ("TR", "Td"), ()),
    "IEEET3": (("TA", "TE"), ("TR",), ("TF", "KF")),
    "ESST4B": ((), ("TR", "TA"), ()),
    "EXAC2": (("TE",), ("TR", "TB", "TC", "TA"), ("TF", "KF")),
    "SEXS": ((), ("TATB", "TB", "TE"), ()),
    **{tg: (("R", "T1", "T3"), ("T2",), ()) for tg in ("TGOV1", "TGOV1N")},
    "IEEEG1": (("T3",), ("T1", "T2", "T4", "T5", "T6", "T7"), ()),
    **{hy: (("r", "Tr", "Tf", "Tg", "Tw"), ("R",), ()) for hy in ("HYGOV", "HYGOVDB")},
    "IEESGO": ((), ("T1", "T2", "T3", "T4", "T5", "T6"), ()),
    "GAST": (("R", "T1"), ("T2", "T3"), ()),
    "TG2": (("R", "T2"), ("T1",), ()),
    "HYGOV4": (("Tp", "Tg", "Tr", "Tw"), ("Rperm", "Rtemp"), ()),
}


def _check_limits(where: str, model: str, values: dict) -> None:
    """CaseError naming ``where`` (file, sheet, row, idx), the parameter and its value for
    a machine's, exciter's or governor's value :data:`_DYNAMIC_LIMITS` refuses; a value
    the row does not hold as a number is left to ANDES's own reading."""
    positive, non_negative, rate = _DYNAMIC_LIMITS.get(model, ((), (), ()))
    for names, ok, must, lag in (
        (
            positive,
            lambda v: v > 0,
            "> 0",
            "a time constant whose block the model has no bypass for",
        ),
        (non_negative, lambda v: v >= 0, ">= 0", "a time constant: 0 bypasses its block"),
    ):
        for name in names:
            if name in values and not ok(values[name]):
                what = _WHAT.get(name, lag)
                raise CaseError(f"{where}: {name} = {values[name]:g}: it must be {must} ({what})")
    if rate:
        tf, kf = rate
        if tf in values and kf in values and values[kf] != 0 and not values[tf] > 0:
            raise CaseError(
                f"{where}: {tf} = {values[tf]:g} with {kf} = {values[kf]:g}: it must be > 0 "
                f"(the rate feedback's time constant, where {kf} != 0)"
            )


#: what a parameter of :data:`_DYNAMIC_LIMITS` that is no time constant is, for messages
_WHAT = {
    "M": "M = 2H, the inertia",
    "D": "the damping",
    "R": "the droop",
    "r": "the temporary droop",
    "Rperm": "the permanent droop",
    "Rtemp": "the temporary droop",
    "TATB": "TA/TB, the ratio of two time constants",
}


def _violated(p, v: float) -> str:
    """Why ANDES would replace a given value v of NumParam p by its default ('' if not)."""
    v = float(v)  # (an int read from a sheet may be beyond int64: 1e30 as 10**30)
    if not math.isfinite(v):
        return "not a finite number"
    if v == 0 and p.get_property("non_zero"):
        return "must not be 0"
    if v > 0 and p.get_property("non_positive"):
        return "must not be positive"
    if v < 0 and p.get_property("non_negative"):
        return "must not be negative"
    return ""


#: the rows a sheet of an xlsx case (the records a model of a json case) may hold, and
#: the bytes of a sheet's XML unpacked: a planning case of 100 000 buses has a few 100 000
#: rows and tens of MB; a sheet of 3 million empty rows (78 MB of XML packed into 0.2 MB)
#: kept pandas and ANDES busy for minutes before any check, as did 1.5 million json Bus
#: records (50 MB)
MAX_MODEL_ROWS = 1_000_000
MAX_XLSX_SHEET_BYTES = 1 << 30
#: the bytes all the parts of an xlsx case unpack to: its sheets, shared strings, styles
#: (a 1.56 GB shared-strings part packed into 3.8 MB took 3.4 GB and minutes to fail)
MAX_XLSX_BYTES = 1 << 30
#: a row's start tag, with a namespace prefix or without (``<row``, ``<x:row``)
_ROW_TAG = re.compile(rb"<(?:[A-Za-z_][\w.-]{0,63}:)?row[\s/>]")
#: bytes of one part kept from one chunk to the next, so that no tag is split unseen
_TAIL = 256


def check_xlsx_size(path: Path) -> None:
    """Refuse an xlsx case beyond the sizes a case has, before any reader parses it:
    every part is read as it unpacks (nothing parsed), wherever the workbook places it.

    Bounds: MAX_XLSX_BYTES unpacked over all parts and MAX_XLSX_SHEET_BYTES for one;
    MAX_MODEL_ROWS rows in a part, counted as row tags (``<row``, or with a namespace
    prefix, ``<x:row``) and as the numbers rows and cells are given (``r="30000000"``,
    ``r="A30000000"``, a dimension ``ref="A1:B30000000"``: readers fill every row up to
    such a number; the header is row 1).

    Parameters
    ----------
    path : pathlib.Path
        The xlsx file.

    Raises
    ------
    InputError
        A part beyond a bound, named with the file, the part and its size or its row; a
        file that is no zip archive (an xlsx is one).
    """
    import zipfile

    numbered = re.compile(
        rb'\b(?:r|ref)="(?:[A-Z]{0,3}\d+:)?[A-Z]{0,3}(\d{%d,})"' % len(str(MAX_MODEL_ROWS))
    )
    try:
        with zipfile.ZipFile(path) as z:
            infos = z.infolist()
            total = sum(info.file_size for info in infos)
            if total > MAX_XLSX_BYTES:
                raise InputError(
                    f"{path.name}: its parts unpack to {total} bytes, more than a case's "
                    f"workbook holds (at most {MAX_XLSX_BYTES} bytes): refused before reading it"
                )
            for info in infos:
                if info.file_size > MAX_XLSX_SHEET_BYTES:
                    raise InputError(
                        f"{path.name}: {info.filename} unpacks to {info.file_size} bytes, more "
                        f"than a case's sheet holds (at most {MAX_XLSX_SHEET_BYTES} bytes)"
                    )
                _check_part_rows(path, z, info, numbered)
    except (zipfile.BadZipFile, OSError) as exc:
        raise InputError(
            f"{path.name}: not an xlsx workbook (an xlsx is a zip archive: {exc})"
        ) from None


def _check_part_rows(path: Path, z, info, numbered: re.Pattern) -> None:
    """`check_xlsx_size`'s count of one part's rows as it unpacks."""
    rows, tail = 0, b""
    with z.open(info) as part:
        while chunk := part.read(1 << 20):
            text = tail + chunk
            rows += len(_ROW_TAG.findall(text)) - len(_ROW_TAG.findall(tail))
            far = max((int(m) for m in numbered.findall(text)), default=0)
            if rows > MAX_MODEL_ROWS or far > MAX_MODEL_ROWS + 1:
                what = (
                    f"numbers a row {far}, beyond {MAX_MODEL_ROWS} rows"
                    if far > MAX_MODEL_ROWS + 1
                    else f"holds more than {MAX_MODEL_ROWS} rows"
                )
                raise InputError(
                    f"{path.name}: {info.filename} {what}, more than any case's sheet (a "
                    "planning case of 100 000 buses holds a few 100 000): refused before "
                    "reading it"
                )
            tail = text[-_TAIL:]


def _row_list(rows: list[int]) -> str:
    """1, 2, 3, 7 -> '1-3, 7'."""
    return ", ".join(f"{a}" if a == b else f"{a}-{b}" for a, b in number_ranges(rows))


def _load(path: Path, dyr, said: list):
    """ANDES's ``System`` of ``path`` (+ ``dyr``), parsed, not set up; InputError if ANDES
    cannot read it, with what ANDES said (``said``: its log records)."""
    from stabctl.jsontext import input_file

    andes = _andes()
    for file, what in ((path, "case file"), (dyr, "DYR file")):
        if file is not None:  # missing, a pipe, a device, a directory or too large: named
            input_file(file, what)
    if path.suffix.lower() == ".xlsx":
        check_xlsx_size(path)
    kw = {} if dyr is None else {"addfile": str(dyr)}
    try:
        with warnings.catch_warnings():  # ANDES's own deprecation notices
            warnings.simplefilter("ignore")
            ss = andes.load(str(path), setup=False, no_output=True, default_config=True, **kw)
    except MemoryError:  # no reading of the file: the machine's memory (the CLI says so)
        raise
    except Exception as exc:  # noqa: BLE001 - ANDES raises many kinds for a file it cannot parse
        why = _dyr_unmatched(path, dyr) or _twice_on_a_machine(path)
        raise why or _unreadable(path, said, exc) from None
    if ss is None:
        raise _dyr_unmatched(path, dyr) or _twice_on_a_machine(path) or _unreadable(path, said)
    return ss


def _twice_on_a_machine(path: Path) -> CaseError | None:
    """Why ANDES cannot parse an xlsx or json case whose machine has two exciters,
    turbine governors or stabilisers (`_check_one_per_machine`, its models' groups from
    an empty ANDES System); None if none has, or the file's rows cannot be read so."""
    if path.suffix.lower() not in (".xlsx", ".json"):
        return None
    try:
        all_rows, sheet_rows = _input_rows(path)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            bare = _andes().System(no_output=True, default_config=True)
        _check_one_per_machine(path.name, all_rows, sheet_rows, bare)
    except CaseError as exc:
        return exc
    except Exception:  # noqa: BLE001 - unreadable so: ANDES's message is the better one
        return None
    return None


def _dyr_unmatched(path: Path, dyr) -> InputError | None:
    """Why ANDES cannot read a RAW file with its DYR file when a DYR record names a
    generator the RAW file lacks (ANDES says only "references to unsupported models") or
    is a second model of one kind for a generator (ANDES: "Your input data may be
    inconsistent"): the records, by file:line, with the ids at their buses
    (`stabctl.io.dyr`'s reading of both files); a DYR file that is none (a JSON case
    given as the DYR: ANDES said "smib.raw: ... 'int' object is not iterable", naming
    the RAW file, round 55 AS) by `stabctl.io.dyr`'s words, which name it and its line;
    None if no record is such, the files are not RAW + DYR, or the RAW file cannot be
    read so (ANDES's message is then the better one)."""
    from stabctl.io.dyr import _KIND, machine_id, no_generator, read_dyr
    from stabctl.io.psse_raw import read_raw

    if dyr is None or path.suffix.lower() != ".raw":
        return None
    try:
        gens = {(g.bus, machine_id(g.id)): g for g in read_raw(path).generators}
    except (InputError, CaseError):
        return None
    try:
        records = read_dyr(dyr)
    except (InputError, CaseError) as exc:
        return InputError(f"ANDES cannot read the DYR file: {exc}")
    first: dict = {}
    for r in records:
        kind = _KIND.get(r.model)
        if kind is not None and (r.bus, r.id, kind) in first:
            was = first[r.bus, r.id, kind]
            return InputError(
                f"{path.name}: ANDES cannot read the case: {r.label()}: second {kind} model "
                f"for this generator (first at {was.where()}, {was.model})"
            )
        first.setdefault((r.bus, r.id, kind), r)
    unmatched = [r for r in records if (r.bus, r.id) not in gens and r.bus != 0]
    if not unmatched:
        return None
    more = f" and {len(unmatched) - 3} more" if len(unmatched) > 3 else ""
    named = "; ".join(f"{r.label()}: {no_generator(r, gens)}" for r in unmatched[:3])
    return InputError(f"{path.name}: ANDES cannot read the case: {named}{more}")


def _set_up(ss, path: Path, said: list, dyr=None) -> None:
    """ANDES's set-up of the parsed ``ss`` (its devices linked: a device naming one that
    does not exist fails here); InputError with what ANDES said if it fails (with a DYR
    file, the records `_dyr_unmatched` names first)."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ss.setup()
    except Exception as exc:  # noqa: BLE001 - as _load
        raise _dyr_unmatched(path, dyr) or _unreadable(path, said, exc) from None
    if not ss.is_setup:
        raise _dyr_unmatched(path, dyr) or _unreadable(path, said)


def _unreadable(path: Path, said: list, exc: BaseException | None = None) -> InputError:
    """The InputError of a case ANDES cannot read or set up: ANDES's first logged error
    (its words name the model and device; its exception often does not), else ``exc``."""
    why = _andes_said(said, exc) or (
        "its parser or set-up failed; run `andes run` on it for ANDES's own message"
    )
    return InputError(f"{path.name}: ANDES cannot read the case: {why}")


def _network(ss, file: str) -> tuple[dict, dict]:
    """PST ``bus`` and ``line`` matrices and the bases; bus idx -> bus number (ANDES's
    idx; a bus idx 0, which ANDES allows and PSS/E and stabctl do not, takes the first
    number above the largest, with a warning naming both)."""
    numbers = {}
    for k, idx in enumerate(ss.Bus.idx.v):
        number = _integer(idx)
        if number is None or number < 0:
            raise CaseError(
                f"{file}: Bus row {k + 1} idx {idx!r} is not a non-negative integer "
                "(stabctl numbers buses)"
            )
        numbers[idx] = number
    zero = [idx for idx, number in numbers.items() if number == 0]
    if zero:
        numbers[zero[0]] = max(numbers.values()) + 1
        warnings.warn(
            f"{file}: Bus idx {zero[0]!r} is numbered {numbers[zero[0]]} (stabctl numbers "
            "buses from 1)",
            UserWarning,
            stacklevel=5,
        )
    b = ss.Bus
    on = _in_service(b)
    _warn_out_of_service(ss, file, [b.idx.v[k] for k in range(b.n) if k not in on], numbers)
    bus = np.zeros((len(on), 15))
    bus[:, 0] = [numbers[b.idx.v[k]] for k in on]
    bus[:, 1], bus[:, 2] = np.asarray(b.v0.v)[on], np.rad2deg(np.asarray(b.a0.v)[on])
    bus[:, 9] = PQ
    bus[:, 12] = np.asarray(b.Vn.v)[on]
    # ANDES's Bus vmax, vmin are not limits of its power flow (its Newton does not clip; the
    # case's voltages may lie beyond them, WECC-179's up to 1.167 pu against 1.1): columns
    # 13, 14 are left 0, PST's clip to [0.5, 1.5], as for a PSS/E RAW file
    row = {b.idx.v[k]: r for r, k in enumerate(on)}
    for m, cols in ((ss.PQ, ((5, "p0"), (6, "q0"))), (ss.Shunt, ((7, "g"), (8, "b")))):
        for k in _in_service(m):
            for col, name in cols:
                bus[row[m.bus.v[k]], col] += getattr(m, name).v[k]
    if ss.Slack.n and not _in_service(ss.Slack):  # (round 48: "no row with field 'kind' = 1")
        why = "; ".join(
            f"Slack {ss.Slack.idx.v[k]} {_off_why(ss.Slack, k)}" for k in range(ss.Slack.n)
        )
        raise CaseError(f"{file}: no Slack in service, so no swing bus: {why}")
    held: dict = {}  # bus row -> the first PV or Slack holding it: (name, idx, v0)
    for m, kind in ((ss.PV, PV), (ss.Slack, SWING)):
        for k in _in_service(m):
            r = row[m.bus.v[k]]
            first = held.setdefault(r, (m.class_name, m.idx.v[k], m.v0.v[k]))
            if first[2] != m.v0.v[k]:  # round 59 BD09: the last one's v0 was taken
                raise CaseError(
                    f"{file}: {first[0]} {first[1]} and {m.class_name} {m.idx.v[k]} both hold "
                    f"bus {numbers[m.bus.v[k]]}, at v0 {first[2]:g} and {m.v0.v[k]:g} pu: one "
                    "bus has one voltage (ANDES's power flow does not converge; give both "
                    "the same v0)"
                )
            bus[r, 1], bus[r, 9] = m.v0.v[k], kind
            if kind == SWING:
                bus[r, 2] = np.rad2deg(m.a0.v[k])
            for col, name in ((3, "p0"), (4, "q0"), (10, "qmax"), (11, "qmin")):
                bus[r, col] += getattr(m, name).v[k]
    ln = ss.Line
    lines = []
    for k in _in_service(ln):
        tap = ln.tap.v[k] or 1.0
        gh, bh = ln.g1.v[k] + ln.g.v[k] / 2, ln.b1.v[k] + ln.b.v[k] / 2
        lines.append(
            [
                numbers[ln.bus1.v[k]],
                numbers[ln.bus2.v[k]],
                ln.r.v[k],
                ln.x.v[k],
                2 * bh,
                tap,
                -np.rad2deg(ln.phi.v[k]),
                0,
                0,
                0,
                gh / tap**2,
                0,
                gh,
                0,
            ]
        )
    line = np.array(lines, float).reshape(-1, 14)
    if not np.any(line[:, 10:14]):
        line = line[:, :10]
    return (
        {
            "bus": bus,
            "line": line,
            "basmva": float(ss.config.mva),
            "sys_freq": float(ss.config.freq),
        },
        numbers,
    )


def _unused_by_andes(ss, numbers: dict) -> list[tuple[str, str, str]]:
    """(model, idx, what) of the data ANDES 2.0's equations leave unused, run as ANDES runs
    it (round 59 BD10, BD17: without a word): a Line's to-end shunt g2, b2 other than its
    from-end g1, b1 (ANDES's Line applies g1 + g/2, b1 + b/2 at both ends), a PV's or
    Slack's remote bus ``busr`` (its power flow holds the device's own bus)."""
    ln, out = ss.Line, []
    for k in _in_service(ln):
        g1, b1, g2, b2 = (float(getattr(ln, p).v[k]) for p in ("g1", "b1", "g2", "b2"))
        if (g2, b2) != (g1, b1):
            out.append(
                (
                    "Line",
                    str(ln.idx.v[k]),
                    f"to-end shunt g2 {g2:g}, b2 {b2:g} run as the from-end g1 {g1:g}, b1 "
                    f"{b1:g} (ANDES 2.0's Line applies g1, b1 at both ends)",
                )
            )
    for sg in (ss.PV, ss.Slack):
        for k in _in_service(sg):
            busr = sg.busr.v[k]
            if _remote(busr, sg.bus.v[k]):
                bus = numbers.get(busr, busr)
                out.append(
                    (
                        sg.class_name,
                        str(sg.idx.v[k]),
                        f"busr {bus} (remote voltage control) unused: its bus holds v0 itself, "
                        "as ANDES 2.0's power flow runs it",
                    )
                )
    return out


def _zip_loads(ss, numbers: dict, bus: np.ndarray) -> tuple[np.ndarray, list]:
    """PST ``load_con`` rows (bus, P and Q constant-power fractions, P and Q constant-
    current fractions) of the buses with a ZIP or FLoad in service (module doc; an FLoad
    as `_fload_shares`), and the ZIPs kept
    with a change, ``(model, idx, why)``: percentages that do not add up to 100 scaled to
    100 (ANDES only warns, and its load then starts off its power flow)."""
    parts: dict = {}  # bus number -> [Pp, Qp, Pi, Qi] of its ZIPs, pu
    changed = []
    shares = []
    for name, of in (("ZIP", _zip_shares), ("FLoad", _fload_shares)):
        m = ss.models.get(name)
        on = _in_service(m) if m is not None else ()
        shares += [(name, str(m.idx.v[k]), m.pq.v[k], of(m, k)) for k in on]
    for name, idx, pq_idx, pct in shares:
        for what in "pq":
            names = [f"k{what}{c}" for c in "piz"]
            total = sum(pct[n] for n in names)
            if total <= 0:
                raise CaseError(f"{name} {idx}: {' + '.join(names)} = {total:g} %")
            if abs(total - 100.0) > 1e-9:
                was = ", ".join(f"{n} {pct[n]:g}" for n in names)
                pct.update({n: pct[n] * 100.0 / total for n in names})
                now = ", ".join(f"{pct[n]:.4g}" for n in names)
                why = f"{was} (sum {total:g} %) scaled to 100 %: {now}"
                changed.append((name, idx, why))
        pq = list(ss.PQ.idx.v).index(pq_idx)
        p0, q0 = ss.PQ.p0.v[pq], ss.PQ.q0.v[pq]
        acc = parts.setdefault(numbers[ss.PQ.bus.v[pq]], [0.0] * 4)
        for i, v in enumerate((p0 * pct["kpp"], q0 * pct["kqp"], p0 * pct["kpi"], q0 * pct["kqi"])):
            acc[i] += v / 100.0
    rows = []
    for number, (pp, qp, pi, qi) in parts.items():
        r = np.nonzero(bus[:, 0] == number)[0][0]
        p, q = bus[r, 5], bus[r, 6]
        rows.append([number, pp / p if p else 0.0, qp / q if q else 0.0])
        rows[-1] += [pi / p if p else 0.0, qi / q if q else 0.0]
    return np.array(rows, float).reshape(-1, 5), changed


def _zip_shares(zip_, k: int) -> dict:
    """ZIP device k's percentages kpp, kpi, kpz, kqp, kqi, kqz."""
    return {n: float(getattr(zip_, n).v[k]) for n in ("kpp", "kpi", "kpz", "kqp", "kqi", "kqz")}


def _fload_shares(fl, k: int) -> dict:
    """FLoad device k as ZIP percentages: 100 % constant power, current or impedance for
    its voltage exponent 0, 1 or 2; CaseError for a frequency exponent other than 0, a
    share of its PQ other than 100 % or another voltage exponent (not PST's loads)."""
    v = {n: float(getattr(fl, n).v[k]) for n in ("kp", "kq", "ap", "aq", "bp", "bq")}
    bad = [
        f"{n} = {v[n]:g} ({why})"
        for n, want, why in (
            ("bp", (0.0,), "frequency dependence"),
            ("bq", (0.0,), "frequency dependence"),
            ("kp", (100.0,), "a share of its PQ's power"),
            ("kq", (100.0,), "a share of its PQ's power"),
            ("ap", (0.0, 1.0, 2.0), "a voltage exponent other than 0, 1, 2"),
            ("aq", (0.0, 1.0, 2.0), "a voltage exponent other than 0, 1, 2"),
        )
        if v[n] not in want
    ]
    if bad:
        raise CaseError(f"FLoad {fl.idx.v[k]}: {'; '.join(bad)}: not one of PST's loads")
    pct = {f"k{w}{c}": 0.0 for w in "pq" for c in "piz"}
    for w in "pq":
        pct[f"k{w}{'piz'[int(v['a' + w])]}"] = 100.0
    return pct


def _in_service(model) -> list[int]:
    """Rows of the devices in service: ANDES's effective status ``ue`` (0 also for a
    device at a bus out of service), ``u`` for a model without one."""
    status = model.ue if hasattr(model, "ue") else model.u
    return [k for k in range(model.n) if status.v[k]]


def _switched_off(ss, file: str) -> tuple[str, ...]:
    """Each device of ``ss`` out of service (the models ignored as without effect aside),
    named as its file holds it: left out of the case as ANDES leaves it out of its run
    (`_in_service`), never silently.  Its own status ``u = 0``, or ANDES's effective status
    ``ue = 0`` with ``u = 1``: a control of a machine out of service (an exciter,
    stabiliser or governor of a GENROU whose generator is off), a device at a bus out
    of service."""
    return tuple(
        f"{_device_where(ss, file, name, k)}: {why}"
        for name, m in ss.models.items()
        if m.n and name not in IGNORED_MODELS and name not in EVENT_MODELS and hasattr(m, "u")
        for k in range(m.n)
        if (why := _off_why(m, k))
    )


def _off_why(model, k: int) -> str:
    """Why device ``k`` of ``model`` is out of service, or "" when it is in service."""
    if model.u.v[k] == 0:
        return "out of service (u = 0)"
    if hasattr(model, "ue") and not model.ue.v[k]:
        return (
            "out of service with the device it serves or its bus (u = 1, ANDES's effective "
            "status ue = 0)"
        )
    return ""


def _warn_out_of_service(ss, file: str, buses: list, numbers: dict) -> None:
    """One warning naming the buses out of service (u = 0) and how many devices ANDES
    takes out with them (its ``ue``): stabctl leaves them out of the case as ANDES does."""
    if not buses:
        return
    gone = sum(
        1
        for m in ss.models.values()
        if m.n and m.class_name != "Bus" and hasattr(m, "ue")
        for k in range(m.n)
        if m.u.v[k] and not m.ue.v[k]
    )
    warnings.warn(
        f"{file}: bus(es) {', '.join(str(numbers[i]) for i in buses)} out of service (u = 0) "
        f"left out with the {gone} device(s) connected to them (ANDES's effective status)",
        UserWarning,
        stacklevel=5,
    )


def _warn_generator_off(file: str, machines: set) -> None:
    """One warning naming the machines left out because their static generator is out of
    service (u = 0): the power flow gives them no power.  PSS/E ignores the records of a
    generator out of service; ANDES 2.0 starts them from their generator's ``p0`` and its
    initialisation then fails (a mismatch of that power at their bus)."""
    if machines:
        warnings.warn(
            f"{file}: machine(s) {', '.join(sorted(map(str, machines)))} left out with their "
            "controls: their static generator is out of service (u = 0)",
            UserWarning,
            stacklevel=5,
        )


def _integer(value) -> int | None:
    try:
        v = float(value)
    except (TypeError, ValueError):
        return None
    return int(v) if np.isfinite(v) and v.is_integer() else None


def _converters(ss, numbers: dict, file: str):
    """The converter table's rows (``ibr_con``, :data:`stabctl.models.converters.CONVERTER`
    order) of ANDES's PVD1, ESD1 and REGCA1 devices in service (a REGCA1 only without an
    electrical control: :data:`RENEWABLE_CONTROLS`), the devices refused (with why),
    the static generators the mapped converters replace, each row's device (converter
    number -> ``"MODEL idx"``) and each row's origin (`stabctl.io.provenance.Origin`: the
    device and the ANDES parameter of each column).  CaseError (naming ``file``) for a
    static generator whose converters take more than all of its P or Q, or whose machines
    and converters together take other than all of it: the rest would be lost at a
    machine's bus (`stabctl.models.converters.rules.share_sums`, a case's check of its
    tables; `_netted_shares` names the rest a bus without machine nets)."""
    rows, refused, replaced, protected = [], [], set(), set()
    origins: list[Origin] = []
    share: dict = {}
    labels: dict[int, str] = {}
    sg_bus: dict = {}
    for m in (ss.PV, ss.Slack):
        for k in _in_service(m):
            sg_bus.setdefault(m.bus.v[k], []).append(m.idx.v[k])
    number = 0
    for name, kind in CONVERTER_MODELS.items():
        m = ss.models.get(name)
        if m is None:
            continue
        for k in _in_service(m):
            where = f"{name} {m.idx.v[k]}"
            gen = m.gen.v[k]
            sg = ss.PV if gen in ss.PV.idx.v else ss.Slack  # one of them: `_check_references`
            bus = sg.bus.v[list(sg.idx.v).index(gen)]
            if kind != REGCA1 and m.busfreq.v[k] not in ss.BusFreq.idx.v:
                raise CaseError(
                    f"{_device_where(ss, file, name, k)}: its BusFreq {m.busfreq.v[k]!r} "
                    "is not in the case"
                )
            bf = 0 if kind == REGCA1 else list(ss.BusFreq.idx.v).index(m.busfreq.v[k])
            why = _converter_refusal(ss, m, k, bus, len(sg_bus.get(bus, ())) > 1, bf)
            if why == "shared":
                why = f"its static generator {gen} shares bus {numbers[bus]} with another"
            if why:
                refused.append(f"{where}: {why}")
                continue
            number += 1
            v = {p.name: p.default for p in CONVERTER.params}
            v.update(number=number, bus=numbers[bus], type=kind, mva=m.Sn.v[k])
            v.update(pfrac=m.gammap.v[k], qfrac=m.gammaq.v[k])
            src = {"mva": (name, k, "Sn"), "pfrac": (name, k, "gammap")}
            src["qfrac"] = (name, k, "gammaq")
            if kind != REGCA1:
                v.update(plim=m.config.plim, Tfm=ss.BusFreq.Tf.v[bf], Twm=ss.BusFreq.Tw.v[bf])
            for p in CONVERTER.params[6:]:
                if p.name in m.params and p.name != "pll":  # REGCP1's pll: the PLL's idx
                    v[p.name] = float(m.params[p.name].vin[k])
                    src[p.name] = (name, k, p.name)
            if kind == REGCA1:
                v.update(_reeca1_values(ss, m.idx.v[k], numbers, src))
                v.update(_pll_values(ss, m, k, src))
            else:
                v.update(_protection_values(ss, m, k, refused, src))
                protected.add(m.idx.v[k])
            rows.append([float(v[p.name]) for p in CONVERTER.params])
            origins.append(_device_origin(ss, file, src, (name, k)))
            labels[number] = where
            got = share.setdefault(gen, [0.0, 0.0, [], False])
            got[0] += m.gammap.v[k]
            got[1] += m.gammaq.v[k]
            got[2].append(where)
            replaced.add(gen)
    for name in PROTECTIONS:
        r = ss.models.get(name)
        for j in _in_service(r) if r is not None else ():
            if r.dev.v[j] not in protected:
                refused.append(f"{name} {r.idx.v[j]}: its device {r.dev.v[j]} is not mapped")
    for name in _MACHINES:
        m = ss.models[name]
        for k in _in_service(m):
            if m.gen.v[k] in share:
                share[m.gen.v[k]][0] += m.gammap.v[k]
                share[m.gen.v[k]][1] += m.gammaq.v[k]
                share[m.gen.v[k]][2].append(f"{name} {m.idx.v[k]}")
                share[m.gen.v[k]][3] = True
    for gen, (gp, gq, devs, machine) in share.items():
        _, why = share_sums({"gammap": gp, "gammaq": gq}, machine)
        if why:
            raise CaseError(
                f"{file}: static generator {gen}: its {'machines and ' * machine}converters "
                f"({', '.join(devs)}) {why}; ANDES starts off its power flow"
            )
    return rows, refused, replaced, labels, origins


def _device_origin(ss, file: str, src: dict, device: tuple[str, int]) -> Origin:
    """The `Origin` of a converter's ibr_con row: ``device`` (ANDES model, row) its
    source, each column's ANDES parameter (``src``: field -> (model, row, parameter)) as
    given, named in its own device (``file: REECA1 row 1 (idx REECA1_1)``) where that is
    another."""
    params: dict[int, tuple[tuple[str, float], ...]] = {}
    places: dict[int, str] = {}
    for fld, (model, j, param) in src.items():
        k = CONVERTER.col(fld)
        params[k] = ((param, float(ss.models[model].params[param].vin[j])),)
        if (model, j) != device:
            places[k] = _device_where(ss, file, model, j)
    return Origin(_device_where(ss, file, *device), params, places=places)


def _device_where(ss, file: str, model: str, j: int) -> str:
    """``file: MODEL row R (idx I)``, ANDES device row j (0-based) of ``model``, as the
    case file's sheet (json key) holds it (rows in device order)."""
    return f"{file}: {model} row {j + 1} (idx {ss.models[model].idx.v[j]})"


def _netted_shares(mats: dict, labels: dict[int, str]) -> list[str]:
    """What the written case holds at each bus without machine whose converters take
    other than all of its generation: their shares (``ibr_con`` ``pfrac``, ``qfrac``
    summed) and the rest of the bus's power-flow generation, which a run nets into the
    bus's load (`stabctl.dynamics.model`: the generation of a bus without machine), read
    from the tables the case is made of (``mac_con``, ``ibr_con``), so that the import's
    summary states what the case holds.  ``labels``: converter number -> ANDES device.
    ANDES drops that rest (its run starts off its power flow)."""
    ibr = mats["ibr_con"]
    with_machine = set(mats["mac_con"][:, 1].astype(int)) if "mac_con" in mats else set()
    col = {n: CONVERTER.col(n) - 1 for n in ("number", "bus", "pfrac", "qfrac")}
    out = []
    for b in dict.fromkeys(ibr[:, col["bus"]].astype(int)):
        rows = ibr[ibr[:, col["bus"]].astype(int) == b]
        fp, fq = rows[:, col["pfrac"]].sum(), rows[:, col["qfrac"]].sum()
        if b in with_machine or (abs(fp - 1) <= 1e-9 and abs(fq - 1) <= 1e-9):
            continue
        devs = ", ".join(f"{labels[int(n)]} (converter {int(n)})" for n in rows[:, col["number"]])
        out.append(
            f"{devs}: take gammap {fp:.12g}, gammaq {fq:.12g} (summed: ibr_con pfrac, "
            f"qfrac) of the generation of bus {b}, "
            f"which has no machine; the rest, {1 - fp:.12g} of its P and {1 - fq:.12g} of "
            "its Q (power flow), netted into the bus's load in runs (ANDES drops it)"
        )
    return out


def _protection_values(ss, m, k, refused: list, src: dict) -> dict[str, float]:
    """The ibr_con ``relay`` columns of PVD1/ESD1 device ``k`` of model ``m`` from the
    DGPRCT1 or DGPRCTExt in service on it (its parameters by name, as given), {} without;
    a second one, or one reading another BusFreq than its device, is appended to
    ``refused`` with why.  ``src`` gets each column's (ANDES model, row, parameter)."""
    vals: dict[str, float] = {}
    for name, code in PROTECTIONS.items():
        r = ss.models.get(name)
        for j in _in_service(r) if r is not None else ():
            if r.dev.v[j] != m.idx.v[k]:
                continue
            where = f"{name} {r.idx.v[j]}"
            if vals:
                refused.append(f"{where}: a second protection of {m.class_name} {m.idx.v[k]}")
            elif r.busfreq.v[j] != m.busfreq.v[k]:
                refused.append(
                    f"{where}: reads BusFreq {r.busfreq.v[j]}, its device BusFreq "
                    f"{m.busfreq.v[k]} (stabctl: one frequency measurement per device)"
                )
            else:
                vals = {f: float(r.params[f[3:]].vin[j]) for f in RELAY_FIELDS[1:]}
                vals["relay"] = code
                src.update({f: (name, j, f[3:]) for f in RELAY_FIELDS[1:]})
    return vals


def _converter_refusal(ss, m, k, bus, shared: bool, bf: int) -> str:
    """Why ANDES converter device ``k`` of model ``m`` cannot be mapped (empty if it can):
    its bus not its static generator's ``bus``, that generator sharing its bus
    (``shared``: the reason is then "shared", worded by the caller, which numbers the
    buses), a REGCA1 driven by an electrical control, a PVD1/ESD1
    regulating a remote bus, with a nominal frequency other than the system's or whose
    BusFreq (row ``bf``) has no washout."""
    regca1 = m.class_name in ("REGCA1", "REGCP1")
    if not regca1 and _remote(m.igreg.v[k], bus):
        return f"remote bus igreg = {m.igreg.v[k]} (stabctl: the device's own bus)"
    if m.bus.v[k] != bus:
        return f"bus {m.bus.v[k]} differs from its static generator's ({bus})"
    if shared:
        return "shared"
    if m.class_name == "REGCP1" and m.pll.v[k] is not None:
        why = _pll_refusal(ss, m.pll.v[k], bus)
        if why:
            return f"its angle comes from PLL {m.pll.v[k]}: {why}"
    if regca1:
        return _electrical_control_refusal(ss, m.idx.v[k], bus)
    if m.fn.v[k] != ss.config.freq:  # fHz = fn f: its trip points, in Hz, read at fn
        return f"fn = {m.fn.v[k]:g} Hz differs from the system frequency {ss.config.freq:g} Hz"
    if ss.BusFreq.fn.v[bf] != ss.config.freq:
        return f"its BusFreq's fn {ss.BusFreq.fn.v[bf]:g} Hz differs from the system frequency"
    if ss.BusFreq.Tw.v[bf] <= 0:
        return f"its BusFreq {m.busfreq.v[k]} has Tw = 0"
    return ""


def _pll_refusal(ss, pll, bus) -> str:
    """Why PLL ``pll`` (its idx) cannot give a REGCP1 on ``bus`` its angle (empty if it
    can: an in-service PLL1 on that bus at the system frequency)."""
    m = ss.models["PLL1"]
    if pll not in m.idx.v:
        return "stabctl models PLL1 (ANDES PLL2's SRF loop is not)"
    j = list(m.idx.v).index(pll)
    if not m.u.v[j]:
        return "it is out of service"
    if m.bus.v[j] != bus:
        return f"it measures bus {m.bus.v[j]}, not the converter's"
    if m.fn.v[j] != ss.config.freq:
        return f"its fn {m.fn.v[j]:g} Hz differs from the system frequency"
    return ""


def _pll_values(ss, m, k, src: dict) -> dict[str, float]:
    """The ibr_con fields of REGCP1 row k's PLL1 (none without one; `_pll_refusal` has
    passed): ``pll`` 1 and its gains and lags as given; ``src`` gets each field's (ANDES
    model, row, parameter)."""
    if m.class_name != "REGCP1" or m.pll.v[k] is None:
        return {}
    pll = ss.PLL1
    j = list(pll.idx.v).index(m.pll.v[k])
    v = {"pll": float(PLL1)}
    v.update({f"pll_{n}": float(pll.params[n].vin[j]) for n in ("Kp", "Ki", "Tf", "Tp")})
    src.update({f"pll_{n}": ("PLL1", j, n) for n in ("Kp", "Ki", "Tf", "Tp")})
    return v


#: ANDES's electrical controls of a renewable generator (group RenExciter, parameter reg)
RENEWABLE_CONTROLS = ("REECA1", "REECA1E", "REECB1")
#: the electrical controls stabctl models -> ibr_con ``reec``
MAPPED_CONTROLS = {"REECA1": REECA1, "REECB1": REECB1}
#: ibr_con fields named otherwise in ANDES's REECA1, REECB1 (their PQFLAG, Tiq; config kqs,
#: kvs, tpfilt)
_REECA1_NAMES = {"pqflag": "PQFLAG", "tiq": "Tiq"}
_REECA1_CONFIG = {"Kqs": "kqs", "Kvs": "kvs", "Tpfilt": "tpfilt"}


def _remote(busr, bus) -> bool:
    """Whether a device's regulated bus ``busr`` (None: its own) is another than its own
    ``bus`` (round 43: a busr naming the device's own bus was refused as remote; ANDES
    regulates that same bus either way, as PSS/E's IREG of its own bus or 0)."""
    if busr is None:
        return False
    try:
        return float(busr) != float(bus)
    except (TypeError, ValueError):  # a text idx
        return str(busr) != str(bus)


def _electrical_control_refusal(ss, regc, bus) -> str:
    """Why renewable generator ``regc``'s electrical control cannot be mapped (empty if
    it has none or one REECA1 or REECB1 regulating its own ``bus``)."""
    drivers = _electrical_controls(ss, regc)
    if len(drivers) > 1 or any(name not in MAPPED_CONTROLS for name, _ in drivers):
        labels = ", ".join(f"{name} {ss.models[name].idx.v[j]}" for name, j in drivers)
        return (
            f"its current commands come from {labels}; stabctl models one REECA1 or "
            "REECB1 (or none)"
        )
    if not drivers:
        return ""
    name, j = drivers[0]
    ree = ss.models[name]
    if _remote(ree.busr.v[j], bus):
        return f"its {name} regulates remote bus busr = {ree.busr.v[j]} (stabctl: its own)"
    plants = _plant_controls(ss, ree.idx.v[j])
    if len(plants) > 1:
        return f"its {name} takes references from {len(plants)} REPCA1 (stabctl: one)"
    for p in plants:
        m = ss.REPCA1
        if _remote(m.busr.v[p], bus):
            return f"its REPCA1 {m.idx.v[p]} regulates remote bus busr = {m.busr.v[p]}"
    if name == "REECB1" and _wind_links(ss, ree.idx.v[j]):
        return f"its REECB1 {ree.idx.v[j]} drives a wind turbine (stabctl: a REECA1's only)"
    return _wind_refusal(ss, ree.idx.v[j])


def _wind_refusal(ss, reec) -> str:
    """Why the wind turbine of REECA1 ``reec`` cannot be mapped (empty if it has at most
    one model at each link of the chain drive train -> WTARA1 -> WTPTA1 -> WTTQA1)."""
    links = _wind_links(ss, reec)
    for n, link in enumerate(links):
        if len(link) > 1:
            found = ", ".join(f"{name} {ss.models[name].idx.v[j]}" for name, j in link)
            if n == 0:
                return f"its REECA1 has {len(link)} drive trains ({found}; stabctl: one)"
            return f"its wind turbine has {len(link)} {link[0][0]} ({found}; stabctl: one)"
    return ""


def _wind_links(ss, reec) -> list[list[tuple[str, int]]]:
    """The wind turbine of REECA1 ``reec`` (its idx) as ANDES chains it, one list of
    (model, in-service row) per link: the drive trains naming ``reec`` (WTDTA1, WTDS),
    then each model of `WIND_CHAIN` naming the first device of the link before; empty
    links end it (none without a drive train)."""
    links = [[(n, j) for n in DRIVE_TRAINS for j in _children(ss, n, "ree", reec)]]
    for chained, field, _, _ in WIND_CHAIN:
        name, j = links[-1][0] if links[-1] else (None, None)
        rows = [] if name is None else _children(ss, chained, field, ss.models[name].idx.v[j])
        links.append([(chained, r) for r in rows])
    return [link for link in links if link]


def _plant_controls(ss, reec) -> list[int]:
    """The rows of the in-service REPCA1 whose electrical control is ``reec`` (its idx)."""
    m = ss.models.get("REPCA1")
    return [j for j in _in_service(m) if m.ree.v[j] == reec] if m is not None else []


def _repca1_values(ss, j: int, numbers: dict, src: dict) -> dict[str, float]:
    """The ibr_con fields of REPCA1 row j: its parameters as given (``vin``; the
    compensation Rc, Xc the monitored line's where not given, ANDES NumSelect), config
    kqs, ksg and freeze, its line's end buses (numbered as stabctl's) and impedance (0
    buses: no line) and its frequency measurement's time constants (its BusFreq's, or
    the one ANDES adds at its bus); ``src`` gets each parameter's (ANDES model, row,
    parameter)."""
    m = ss.REPCA1
    f = list(ss.BusFreq.idx.v).index(m.busfreq.v[j])  # its own or the one ANDES added
    v: dict[str, float] = {"repc": float(REPCA1)}
    v.update(Tfm=ss.BusFreq.Tf.v[f], Twm=ss.BusFreq.Tw.v[f])
    config = {"pc_Kqs": m.config.kqs, "pc_Ksg": m.config.ksg, "pc_freeze": m.config.freeze}
    line = m.line.v[j]
    ends = {"pc_bus1": 0.0, "pc_bus2": 0.0, "pc_r": 1.0, "pc_x": 1.0}
    if line is not None:
        k = list(ss.Line.idx.v).index(line)
        b1, b2 = ss.Line.bus1.v[k], ss.Line.bus2.v[k]
        ends = {"pc_bus1": numbers[b1], "pc_bus2": numbers[b2]}
        ends.update(pc_r=ss.Line.r.v[k], pc_x=ss.Line.x.v[k])
    for field in REPCA1_FIELDS:
        name = field[3:]
        if field in config:
            v[field] = float(config[field])
        elif field in ends:
            v[field] = float(ends[field])
        else:
            v[field] = float(m.params[name].vin[j])
            src[field] = ("REPCA1", j, name)
    for field, given in (("pc_Rc", m.Rc.v[j]), ("pc_Xc", m.Xc.v[j])):
        if given is None or not np.isfinite(given):
            v[field] = v["pc_r" if field == "pc_Rc" else "pc_x"]
    return v


def _reeca1_values(ss, regc, numbers: dict, src: dict) -> dict[str, float]:
    """The ibr_con fields of renewable generator ``regc``'s REECA1 or REECB1 (none without
    one): its parameters as given (``vin``, before ANDES's base change) and its config
    (a REECB1's fields REECA1 alone has keep their defaults: no hold, no PFLAG), and its
    REPCA1's (`_repca1_values`); ``src`` gets each parameter's (ANDES model, row,
    parameter)."""
    drivers = _electrical_controls(ss, regc)
    if not drivers:
        return {}
    name, j = drivers[0]
    m = ss.models[name]
    v: dict[str, float] = {"reec": float(MAPPED_CONTROLS[name])}
    for field in REECA1_FIELDS:
        given = _REECA1_NAMES.get(field, field)
        if field in _REECA1_CONFIG:
            v[field] = float(getattr(m.config, _REECA1_CONFIG[field]))
        elif given in m.params:
            v[field] = float(m.params[given].vin[j])
            src[field] = (name, j, given)
    for plant in _plant_controls(ss, m.idx.v[j]):
        v.update(_repca1_values(ss, plant, numbers, src))
    v.update(_wind_values(ss, m.idx.v[j], src))
    return v


def _children(ss, name: str, parent_field: str, parent) -> list[int]:
    """The in-service rows of ANDES model ``name`` whose ``parent_field`` is ``parent``."""
    m = ss.models.get(name)
    if m is None or not m.n:
        return []
    return [j for j in _in_service(m) if m.params[parent_field].v[j] == parent]


def _wind_values(ss, reec, src: dict) -> dict[str, float]:
    """The ibr_con fields of the wind turbine of REECA1 ``reec`` (its idx; none without
    one): its drive train (WTDTA1 or WTDS, ``wt_``: WTDS's D read as ``wt_DAMP``) and the
    models chained after it (`WIND_CHAIN`), parameters as given (``vin``, device base;
    WTTQA1's Tn 0 where not given); ``src`` gets each parameter's (ANDES model, row,
    parameter)."""
    links = _wind_links(ss, reec)
    if not links:
        return {}
    name, j = links[0][0]
    m = ss.models[name]
    v: dict[str, float] = {"wind": float(DRIVE_TRAINS[name])}
    alias = {"wt_DAMP": "D"} if name == "WTDS" else {}
    for field in WIND_FIELDS[1:]:
        given = alias.get(field, field[3:])
        if field.startswith("wt_") and given in m.params:
            v[field] = float(m.params[given].vin[j])
            src[field] = (name, j, given)
    for link, (_, _, flag, prefix) in zip(links[1:], WIND_CHAIN):
        name, j = link[0]
        v[flag] = 1.0
        for field in WIND_FIELDS:
            if field.startswith(prefix):
                src[field] = (name, j, field[3:])
                value = float(ss.models[name].params[field[3:]].vin[j])
                v[field] = 0.0 if field == "wq_Tn" and not np.isfinite(value) else value
    return v


def _electrical_controls(ss, regc) -> list[tuple[str, int]]:
    """The in-service ANDES electrical controls (RENEWABLE_CONTROLS) of renewable generator
    ``regc`` (its idx), as (model name, row)."""
    found = []
    for name in RENEWABLE_CONTROLS:
        m = ss.models.get(name)
        if m is not None and m.n:
            found += [(name, j) for j in _in_service(m) if m.reg.v[j] == regc]
    return found


def _skip_advice(bare: bool, changed: bool) -> str:
    """What leaving out does for the refused devices but the static generators without a
    machine (``bare``: there are such): leaves them out, and keeps those ``changed``."""
    return (
        advice("on_unsupported='skip' leaves", "--skip-unsupported leaves")
        + (" the others" if bare else " them")
        + " out"
        + (" or keeps them changed" if changed else "")
    )


def _bare_advice(count: int, path: Path) -> str:
    """What imports ``count`` static generators without a synchronous machine: they cannot
    be left out (their power would leave the power flow), so a machine model or a
    converter for each in the case data, or, for a RAW file, PSS/E's reader netting them."""
    each = "it" if count == 1 else "each"
    text = (
        f"give {each} a machine model ({', '.join(_MACHINES)}) or a converter "
        f"({', '.join(CONVERTER_MODELS)}) in the data"
    )
    if path.suffix.lower() == ".raw":
        text += advice(
            ", or read the RAW + DYR with stabctl.io.psse.import_psse(..., unmodelled='net'), "
            "which nets it as a negative load",
            ", or import the RAW + DYR with import-psse --net-unmodelled, which nets it as a "
            "negative load",
        )
    return text


def _dynamic_records(ss, file: str, numbers: dict, with_converter=frozenset(), by_device=None):
    """The generators (dicts for :func:`stabctl.io.dyr.dyr_tables`), the PSS/E records of
    the mapped ANDES devices, the devices refused here (with why), those kept with a
    change, the DYR values kept unlike ANDES and each record's origin (record ->
    `stabctl.io.provenance.Origin`: the ANDES device, its parameters' ANDES names); static
    generators in
    ``with_converter`` are replaced by converters, not machines.  ``by_device``: the
    DYR record of each ANDES device read from a DYR file (`_dyr_against_andes`), whose
    values ANDES's own are checked against (`_against_dyr`)."""
    dyr = _psse_yaml()
    static = [(m, k) for m in (ss.PV, ss.Slack) for k in range(m.n)]
    position = {m.idx.v[k]: n for n, (m, k) in enumerate(static)}
    on = {(sg.class_name, k) for sg in (ss.PV, ss.Slack) for k in _in_service(sg)}
    gen_on = {sg.idx.v[k] for sg in (ss.PV, ss.Slack) for k in _in_service(sg)}
    machines, refused, changed, off = [], [], [], set()
    unlike: list[str] = []
    for name in _MACHINES:
        m = ss.models[name]
        for k in _in_service(m):
            if m.gen.v[k] in position and m.gen.v[k] not in gen_on:
                off.add(m.idx.v[k])
            else:
                machines.append((position.get(m.gen.v[k], len(static)), name, k))
    machines.sort()
    _warn_generator_off(file, off)
    _check_shares(ss, file, machines, with_converter)
    with_machine = {ss.models[name].gen.v[k] for _, name, k in machines}
    playback = ss.models.get("PLBVFU1")
    played = list(_in_service(playback)) if playback is not None else []
    with_machine |= {playback.gen.v[k] for k in played}
    bare = [
        (f"{sg.class_name} {sg.idx.v[k]} (bus {numbers[sg.bus.v[k]]})", sg, k)
        for sg, k in static
        if (sg.class_name, k) in on
        and sg.idx.v[k] not in with_machine
        and sg.idx.v[k] not in with_converter
    ]
    if machines:
        refused += [f"{b}: {_NO_MACHINE}" for b, sg, _ in bare if sg is not ss.Slack]
    gens, by_syn = [], {}
    for number, (_, name, k) in enumerate(machines, 1):
        m = ss.models[name]
        sg = ss.PV if m.gen.v[k] in ss.PV.idx.v else ss.Slack
        j = list(sg.idx.v).index(m.gen.v[k])
        if sg.bus.v[j] != m.bus.v[k]:
            there = [f"{s.class_name} {s.idx.v[i]}" for s, i in static if s.bus.v[i] == m.bus.v[k]]
            raise CaseError(
                f"{file}: {name} {m.idx.v[k]} is at bus {numbers[m.bus.v[k]]}, its static "
                f"generator {sg.class_name} {m.gen.v[k]} at bus {numbers[sg.bus.v[j]]} (bus "
                f"{numbers[m.bus.v[k]]} has {', '.join(there) or 'no PV or Slack'}): a machine "
                "takes its generator's power flow at its own bus (ANDES fails to initialise it)"
            )
        gid = str(m.idx.v[k])
        gens.append(
            {
                "number": number,
                "bus": numbers[m.bus.v[k]],
                "id": gid,
                "mbase": float(m.Sn.v[k]),
                "ra": float(m.ra.vin[k]),
                "xsource": float(m.xd1.vin[k]),
                "pg": float(m.gammap.v[k] * _pf_power(sg, "p", j)),
                "qg": float(m.gammaq.v[k] * _pf_power(sg, "q", j)),
                "sbase": float(ss.config.mva),
            }
        )
        if m.gen.v[k] in with_converter:  # converters take the rest of its generator
            gens[-1].update(pfrac=float(m.gammap.v[k]), qfrac=float(m.gammaq.v[k]))
        by_syn[m.idx.v[k]] = gens[-1]
        if m.fn.v[k] != ss.config.freq:
            changed.append(
                (
                    name,
                    str(m.idx.v[k]),
                    f"fn = {m.fn.v[k]:g} Hz read as the system frequency "
                    f"{ss.config.freq:g} Hz (one frequency in stabctl)",
                )
            )
        if name == "GENROU" and m.xq2.vin[k] != m.xd2.vin[k]:
            changed.append(
                (
                    name,
                    str(m.idx.v[k]),
                    f"xq2 = {m.xq2.vin[k]:g} read as xd2 = {m.xd2.vin[k]:g} (PSS/E's "
                    "GENROU has one subtransient reactance)",
                )
            )
    records = []
    origins: dict[DyrRecord, Origin] = {}
    for k in played:  # a playback source: a classical machine of H = 0 behind xs
        gens.append(_playback_source(ss, k, len(gens) + 1, numbers))
        records.append(
            DyrRecord(file, k + 1, gens[-1]["bus"], "GENCLS", gens[-1]["id"], (0.0, 0.0))
        )
        origins[records[-1]] = Origin(_device_where(ss, file, "PLBVFU1", k))
    if machines:  # a Slack without machine holds its bus's voltage: an infinite bus
        for k in (k for _, sg, k in bare if sg is ss.Slack):
            gens.append(_infinite_bus(ss, k, len(gens) + 1, numbers))
            records.append(
                DyrRecord(file, k + 1, gens[-1]["bus"], "GENCLS", gens[-1]["id"], (0.0, 0.0))
            )
            origins[records[-1]] = Origin(_device_where(ss, file, "Slack", k))
    avr_syn = {}
    for name, psse in MAPPED_MODELS.items():
        m = ss.models.get(name)
        if m is None or psse in _MACHINES:
            continue
        for k in _in_service(m):
            if "syn" in m.params:
                avr_syn[m.idx.v[k]] = m.syn.v[k]
    for name, psse in MAPPED_MODELS.items():
        m = ss.models.get(name)
        if m is None or not m.n:
            continue
        for k in _in_service(m):
            syn = (
                m.idx.v[k]
                if psse in _MACHINES
                else (m.syn.v[k] if "syn" in m.params else avr_syn.get(m.avr.v[k]))
            )
            if syn in off:  # out of service with its machine
                continue
            gen = by_syn.get(syn)
            why = _fixed_differs(m, name, k)
            if gen is None or why:
                refused.append(f"{name} {m.idx.v[k]}: " + (why or "its machine is not mapped"))
                continue
            fields = DYR_MODELS[psse].fields
            if psse in dyr:
                params = _psse_params(ss, m, dyr[psse], fields, k)
                names = _andes_names(dyr[psse])
            else:  # ANDES's own model (TG2, HYGOV4): its parameters by name, as given
                params = tuple(float(m.params[f].vin[k]) for f in fields)
                names = {}
            rec = (by_device or {}).get((name, k))
            decl = None if rec is None else DYR_MODELS.get(rec.model)
            if rec is not None and decl is not None and len(rec.params) == len(decl.fields):
                params = _against_dyr(rec, psse, params, changed, unlike)
            elif rec is not None:
                why = (
                    f"{len(rec.params)} parameters, not {rec.model}'s {len(decl.fields)}"
                    if decl is not None
                    else f"model {rec.model} has no PSS/E declaration in stabctl"
                )
                changed.append(
                    (
                        rec.model,
                        f"{rec.where()} (bus {rec.bus}, id {rec.id})",
                        "not checked: " + why,
                    )
                )
            src, line = (file, k + 1) if rec is None else (rec.file, rec.line)  # the DYR's
            records.append(DyrRecord(src, line, gen["bus"], psse, gen["id"].upper(), params))
            where = _device_where(ss, file, name, k)
            origins[records[-1]] = dyr_origin(records[-1], names, where)
    return gens, records, refused, _grouped(changed), unlike, origins


def _andes_names(spec: dict) -> dict[str, str]:
    """PSS/E field -> the ANDES parameter it is (``psse-dyr.yaml``'s ``outputs``
    inverted, as `_psse_params` reads them; H as ``M/2``)."""
    names: dict[str, str] = {}
    for param, expr in spec["outputs"].items():
        given = expr.split(";")[0].split(".")[-1].strip() if isinstance(expr, str) else expr
        names.setdefault(str(given), "M/2" if param == "M" else param)
    return names


def _dyr_against_andes(ss, dyr) -> tuple[list[str], dict, list[str]]:
    """The records of the DYR file ANDES's reader left out (``file:line MODEL (bus B, id
    I): why``: a model its ``psse-dyr.yaml`` lacks, which ANDES skips with only a log
    line), {(ANDES model, device k): DyrRecord} of those it read: ANDES adds the
    records of each PSS/E model in file order, model after model in its dependency order
    (``andes/io/psse.py`` ``read_add``), so the k-th device of a model is the k-th record
    so added, and, where the counts do not agree, one line per ANDES model whose values
    are therefore not checked against the file (reported with the changes)."""
    from andes.io.psse import sort_psse_models

    from stabctl.io.dyr import read_dyr
    from stabctl.io.dyr_converters import converter_plants

    spec = _psse_yaml()
    order = [m for m in sort_psse_models(spec, ss) if m in spec]
    records = read_dyr(dyr)  # its model names upper case; ANDES's Toggle, Fault are not
    converter_plants(records)  # a second record of a model for one plant: refused
    known = {m.upper() for m in order}
    dropped = [
        f"{r.label()}: model {r.model} is not read by ANDES's DYR reader (not in its "
        "psse-dyr.yaml): left out"
        for r in records
        if r.model not in known
    ]
    by_dest: dict[str, list] = {}
    for model in order:
        by_dest.setdefault(spec[model]["destination"], []).extend(
            r for r in records if r.model == model.upper()
        )
    by_device, unchecked = {}, []
    for dest, recs in by_dest.items():
        n = ss.models[dest].n if dest in ss.models else 0
        if n == len(recs):
            by_device.update({(dest, k): rec for k, rec in enumerate(recs)})
        elif recs:
            models = ", ".join(sorted({r.model for r in recs}))
            unchecked.append(
                f"{dest} ({n} devices): values not checked against the DYR file's "
                f"{len(recs)} {models} record(s) (ANDES built another number of devices, "
                "so a device cannot be matched to its record); run as ANDES read them"
            )
    return dropped, by_device, unchecked


def _against_dyr(rec, psse: str, params, changed: list, unlike: list) -> tuple[float, ...]:
    """``params`` (ANDES's values of ``rec``'s device as PSS/E model ``psse``, in its
    order) checked by name against the DYR record's own: values ANDES replaced (its
    default for a zero it refuses, SEXS's defaults for an SCRX record) or read from
    another position (its ``psse-dyr.yaml`` lists ESAC1A's and ESST1A's parameters in
    another order than the PSS/E record's) are named in ``changed`` and kept as ANDES
    runs them, except the infinite bus (GENCLS H = 0), kept at H = 0 and named in
    ``unlike``."""
    fields, given = DYR_MODELS[psse].fields, DYR_MODELS[rec.model].values(rec.params)
    out, differ = list(params), []
    for i, name in enumerate(fields):
        mine = given.get(name)
        if mine is None or np.isclose(mine, params[i], rtol=1e-9, atol=1e-12):
            continue
        if psse == "GENCLS" and name == "H" and mine == 0:
            out[i] = 0.0
            unlike.append(
                f"{rec.label()}: H = 0, PSS/E's infinite bus, kept (ANDES replaces M = 0 "
                f"by its default, H = {params[i]:g} s)"
            )
            continue
        differ.append(f"{name} = {mine:g} read by ANDES as {params[i]:g}")
    if rec.model != psse:  # read as another model: its own parameters are not read
        differ += [f"{name} = {v:g} not read" for name, v in given.items() if name not in fields]
    if differ:
        order = _psse_yaml()[rec.model]["inputs"][2:]
        if rec.model != psse:
            why = f"ANDES reads the record as its {psse}, with that model's defaults"
        elif list(order) != list(fields):
            why = (
                f"ANDES reads the record in its psse-dyr.yaml order ({' '.join(order)}), "
                "not the PSS/E Model Library's"
            )
        else:
            why = "ANDES's defaults for values it refuses"
        where = f"{rec.where()} (bus {rec.bus}, id {rec.id})"
        changed.append((rec.model, where, f"{', '.join(differ)}: {why}"))
    return tuple(out)


def _dc_links(ss, numbers: dict) -> tuple[list[list[float]], list[str]]:
    """The fixed injections (``case.injections``) of ANDES's static AC/DC converters
    (VSCShunt, in service) at their power-flow point (ANDES's psh + j qsh, injected: run
    its power flow first), and the converters refused with why: one holding its AC bus
    voltage (control 1 or 3: its Q is not fixed), or a DC network with more than nodes,
    grounds and resistances (ANDES's L, C, ... have dynamics).  Converters controlling P
    and Q (control 0) inject their set points in a run as ANDES's; one controlling its DC
    voltage and Q (control 2) supplies what the DC network takes, which ANDES's run varies
    with the other converter's losses (by 1.4e-3 pu on kundur_vsc's 0.1 pu in a fault)."""
    m = ss.models.get("VSCShunt")
    rows: list[list[float]] = []
    refused: list[str] = []
    if m is None or not m.n:
        return rows, refused
    dynamic = [
        f"{n} ({d.n})"
        for n, d in ss.models.items()
        if d.group == "DCLink" and d.n and n not in DC_MODELS
    ]
    for k in _in_service(m):
        why = ""
        if dynamic:
            why = f"its DC network holds {', '.join(dynamic)} (stabctl: resistances only)"
        elif m.control.v[k] in (1, 3):
            why = f"control {int(m.control.v[k])} holds its AC bus voltage (Q not fixed)"
        if why:
            refused.append(f"VSCShunt {m.idx.v[k]}: {why}")
            continue
        rows.append([numbers[m.bus.v[k]], float(m.psh.v[k]), float(m.qsh.v[k])])
    return rows, refused


def _dc_changes(ss) -> list[tuple[str, str, str]]:
    """The changes `_dc_links` makes to the AC/DC converters it keeps, (model, idx, why):
    one controlling its DC voltage (control 2) is held at its power-flow P, which ANDES's
    run varies with the DC network's losses; and the DC network's devices (Node, Ground,
    R), read only through those injections."""
    m = ss.models.get("VSCShunt")
    if m is None or not m.n:
        return []
    kept = [k for k in _in_service(m) if m.control.v[k] not in (1, 3)]
    out = [
        (
            "VSCShunt",
            str(m.idx.v[k]),
            "control 2 (DC voltage and Q) held at its power-flow P + j Q as a fixed "
            "injection: ANDES's run varies its P with the DC network's losses",
        )
        for k in kept
        if m.control.v[k] == 2
    ]
    for name in ("Node", "Ground", "R") if kept else ():
        d = ss.models.get(name)
        out += [
            (
                name,
                str(d.idx.v[j]),
                "the DC network: read only through its converters' power-flow injections",
            )
            for j in (range(d.n) if d is not None else ())
        ]
    return out


def _switched_shunts(ss, numbers: dict) -> tuple[list[list[float]], list[str]]:
    """The swsh_con rows of ANDES's ShuntSw devices in service (system-base values, its
    block lists as groups), and those refused with why (more groups than the table has,
    reactor steps, a nominal frequency other than the system's)."""
    m = ss.models.get("ShuntSw")
    rows: list[list[float]] = []
    refused: list[str] = []
    for k in _in_service(m) if m is not None else ():
        ns, bs, gs = (
            np.atleast_1d(np.asarray(m.params[f].v[k], float)) for f in ("ns", "bs", "gs")
        )
        why = ""
        if ns.size > SWITCHED_GROUPS:
            why = f"{ns.size} block groups (stabctl: at most {SWITCHED_GROUPS})"
        elif np.any(bs < 0):
            why = "reactor steps (bs < 0): ANDES's starting level assumes rising levels"
        elif m.fn.v[k] != ss.config.freq:
            why = f"fn = {m.fn.v[k]:g} Hz, not the system's {ss.config.freq:g} Hz"
        if why:
            refused.append(f"ShuntSw {m.idx.v[k]}: {why}")
            continue
        groups = [0.0] * (3 * SWITCHED_GROUPS)
        for j, (n, b) in enumerate(zip(ns, bs)):
            groups[3 * j : 3 * j + 3] = [n, b, gs[j] if j < gs.size else 0.0]
        rows.append(
            [
                len(rows) + 1,
                numbers[m.bus.v[k]],
                *(float(m.params[f].v[k]) for f in ("b", "g", "vref", "dv", "dt")),
                *groups,
            ]
        )
    return rows, refused


def _motors(ss, numbers: dict, kept: dict) -> tuple[list[list[float]], list[str]]:
    """The mot_con rows of ANDES's Motor5 devices (number, bus, in service 0, Sn, then the
    impedances on the motor base at the bus's voltage base, ANDES's system-base values
    times Sn/Sb, Hm and c1-c3 as given), and those refused with why: in service at the
    start (ANDES's power flow holds it at its initial slip, not an equilibrium), another
    frequency, c1-c3 on a base other than the system's (ANDES reads them on the system
    base, stabctl on the motor's).  ``kept`` is filled with motor idx -> number."""
    m = ss.models.get("Motor5")
    rows: list[list[float]] = []
    refused: list[str] = []
    sb = ss.config.mva
    for k in range(m.n if m is not None else 0):
        where = f"Motor5 {m.idx.v[k]}"
        why = ""
        if m.u.v[k] != 0:
            why = "in service at the start (stabctl switches a motor on by a MotorSwitch)"
        elif m.fn.v[k] != ss.config.freq:
            why = f"fn = {m.fn.v[k]:g} Hz, not the system's {ss.config.freq:g} Hz"
        elif m.Sn.v[k] != sb and any(m.params[c].v[k] != 0 for c in ("c1", "c2", "c3")):
            why = f"Sn = {m.Sn.v[k]:g} MVA: ANDES reads its torque c1-c3 on the system base"
        if why:
            refused.append(f"{where}: {why}")
            continue
        z = [float(m.params[f].v[k]) * m.Sn.v[k] / sb for f in MOTOR.names[4:11]]
        rest = [float(m.params[f].vin[k]) for f in MOTOR.names[11:]]
        rows.append([len(rows) + 1, numbers[m.bus.v[k]], 0.0, float(m.Sn.v[k]), *z, *rest])
        kept[m.idx.v[k]] = len(rows)
    return rows, refused


def _disturbances(ss, file: str, numbers: dict, gens: list, mats: dict, motor_numbers: dict):
    """The case's own events (`Case.events` records) from ANDES's Toggle, Fault and Alter
    devices in service, those refused (``"MODEL idx: why"``) and those off (u = 0: ANDES
    does not run them either).

    Toggle (a flip of a device's ``u``, in time order per device): of a Line, a LineTrip,
    then a LineClose, alternately; of a machine (GENROU, GENCLS), a GeneratorTrip (a
    second, reconnecting it, is refused); of a PQ (or StaticLoad), a LoadStep of its power
    (P, Q at the power flow's voltage: ANDES's PQ in a run is a constant impedance), minus
    when it goes out of service, plus when it comes in, at a bus whose load is all
    constant impedance;
    of a Motor5, a MotorSwitch on, then off.  Fault: a Fault through rf + j xf from tf to
    tc (none: never cleared), without loss of a line.  Alter (``+``, ``-``, ``=``; ``*``,
    ``/`` of a known value) of an exciter's ``vref0``: a VrefStep; of a TGOV1's
    ``paux0`` (0 at the start): a PrefStep of the change / R (machine base).  Any other
    target is refused with the device and attribute.  CaseError (naming ``file``) for an
    event time (t, tf, tc) that is not finite and >= 0 (ANDES's Toggle t defaults to -1)."""
    events: list = []
    refused: list = []
    off: list = []
    machine_of = {g["id"]: g["number"] for g in gens}
    have = {
        key: set(np.asarray(mats[key])[:, col].astype(int).tolist()) if key in mats else set()
        for key, col in (("mac_con", 0), ("exc_con", 1), ("tg_con", 1))
    }
    line_rows = {ss.Line.idx.v[k]: r for r, k in enumerate(_in_service(ss.Line))}
    line = np.asarray(mats["line"])
    non_conforming = set(np.asarray(mats["load_con"])[:, 0].astype(int).tolist())
    timed = []
    for name in EVENT_MODELS:
        m = ss.models.get(name)
        for k in range(m.n if m is not None else 0):
            if m.u.v[k] == 0:
                off.append(f"{name} {m.idx.v[k]} (u = 0: not run, as in ANDES)")
                continue
            t = float(m.tf.v[k] if name == "Fault" else m.t.v[k])
            for what, when in (("tf" if name == "Fault" else "t", t), ("tc", _clearing(m, k))):
                if when is not None and not (np.isfinite(when) and when >= 0):
                    raise CaseError(
                        f"{file}: {name} {m.idx.v[k]}: {what} = {when:g} s: an event time "
                        "must be finite and >= 0"
                    )
            if (tc := _clearing(m, k)) is not None and tc < t:  # (round 48: run refused it)
                raise CaseError(
                    f"{file}: Fault {m.idx.v[k]}: tc = {tc:g} s before tf = {t:g} s: a fault "
                    "is cleared after it starts"
                )
            timed.append((t, name, k))
    state: dict = {}
    for t, name, k in sorted(timed, key=lambda e: e[0]):
        m = ss.models[name]
        where = f"{name} {m.idx.v[k]}"
        rec: dict = {}
        why = ""
        if name == "Fault":
            rec = {
                "kind": "Fault",
                "bus": numbers[m.bus.v[k]],
                "t": t,
                "clear_near": _clearing(m, k),
                "r": float(m.rf.v[k]),
                "x": float(m.xf.v[k]),
            }
        elif name == "Toggle":
            model, dev = m.model.v[k], m.dev.v[k]
            n = state[(model, dev)] = state.get((model, dev), 0) + 1
            if model == "Line" and dev in line_rows:
                a, b = int(line[line_rows[dev], 0]), int(line[line_rows[dev], 1])
                same = [r for r in range(line_rows[dev] + 1) if {*line[r, :2]} == {a, b}]
                kind = "LineTrip" if n % 2 else "LineClose"
                rec = {"kind": kind, "from_bus": a, "to_bus": b, "t": t, "circuit": len(same)}
            elif model == "Line":
                why = f"Line {dev} is out of service at the start (not in the case)"
            elif model in _MACHINES and machine_of.get(str(dev)) in have["mac_con"]:
                if n > 1:
                    why = f"reconnects machine {dev} (stabctl trips a machine for good)"
                rec = {"kind": "GeneratorTrip", "machine": machine_of[str(dev)], "t": t}
            elif model in ("PQ", "StaticLoad") and dev in ss.PQ.idx.v:
                j = list(ss.PQ.idx.v).index(dev)
                bus = numbers[ss.PQ.bus.v[j]]
                on = (ss.PQ.u.v[j] != 0) != (n % 2 == 1)  # in service after this toggle
                sign = 1.0 if on else -1.0
                if bus in non_conforming:
                    why = f"PQ {dev} at bus {bus}, whose load is not all constant impedance"
                rec = {
                    "kind": "LoadStep",
                    "bus": bus,
                    "t": t,
                    "P": sign * float(ss.PQ.p0.v[j]),
                    "Q": sign * float(ss.PQ.q0.v[j]),
                }
            elif model == "Motor5" and dev in motor_numbers:
                rec = {"kind": "MotorSwitch", "motor": motor_numbers[dev], "t": t, "on": n % 2 == 1}
            else:
                why = f"a Toggle of {model} {dev}, which stabctl does not switch or has not kept"
        else:
            rec, why = _alter(ss, m, k, t, state, machine_of, have)
        if why or not rec:
            refused.append(f"{where}: {why}")
        else:
            events.append({**rec, "source": where})
    return events, refused, off


def _clearing(m, k: int) -> float | None:
    """A Fault's clearing time ``tc`` (s; None for none: never cleared), else None."""
    tc = m.tc.v[k] if m.class_name == "Fault" else None
    return None if tc is None else float(tc)


def _alter(ss, m, k, t: float, state: dict, machine_of: dict, have: dict):
    """The event record of Alter row k (`_disturbances`) and why it is refused ("" if
    not); state holds each altered value known so far, (model, dev, src) -> value."""
    model, dev, src = m.model.v[k], m.dev.v[k], m.src.v[k]
    target = ss.models.get(model)
    group = getattr(target, "group", "")
    kind = ALTERED.get((group, src)) or ALTERED.get((model, src))
    what = f"{model} {dev} {src}"
    if target is None or kind is None:
        return {}, f"alters {what}, which stabctl does not map (mapped: exciter vref0, TGOV1 paux0)"
    if dev not in target.idx.v:  # (round 48: a traceback, "'NOPE_9' is not in list")
        return {}, f"alters {what}: the case has no {model} {dev} (Alter field dev)"
    j = list(target.idx.v).index(dev)
    number = machine_of.get(str(target.syn.v[j]))
    table = "exc_con" if kind == "VrefStep" else "tg_con"
    if number not in have[table]:
        return {}, f"alters {what}, whose machine or controller is not in the case"
    key = (model, dev, src)
    old = state.get(key, 0.0 if src == "paux0" else None)
    amount, method = float(m.amount.v[k]), str(m.method.v[k])
    ops = {"+": lambda v: v + amount, "-": lambda v: v - amount}
    ops.update({"*": lambda v: v * amount, "/": lambda v: v / amount, "=": lambda v: amount})
    if method not in ops:
        return {}, f"alters {what} by method {method!r} (ANDES: +, -, *, /, =)"
    if old is None and method not in "+-":
        return {}, f"alters {what} by {method!r}: its value at the start is ANDES's own"
    new = ops[method](0.0 if old is None else old)
    change = new - (0.0 if old is None else old)
    state[key] = new if old is not None else None
    if kind == "VrefStep":
        return {"kind": kind, "machine": number, "t": t, "dV": change}, ""
    return {"kind": kind, "machine": number, "t": t, "dP": change / float(target.R.vin[j])}, ""


def _shafts(ss, gens: list[dict]) -> tuple[list[list[float]], list[str]]:
    """The shaft_con rows of ANDES's SHAFT5 devices in service (machine number, then its
    parameters by name, as given: machine base), and the devices refused (their machine
    not mapped), with why."""
    m = ss.models.get("SHAFT5")
    number = {g["id"]: g["number"] for g in gens}
    rows, refused = [], []
    for k in _in_service(m) if m is not None else ():
        machine = number.get(str(m.syn.v[k]))
        if machine is None:
            refused.append(f"SHAFT5 {m.idx.v[k]}: its machine {m.syn.v[k]} is not mapped")
            continue
        rows.append([machine, *(float(m.params[f].vin[k]) for f in SHAFT.names[1:])])
    return rows, refused


def _mark_playback(mats: dict, gens: list[dict]) -> None:
    """Set the mac_con playback columns (26-28: 1, Tv, Tf) of the playback sources' rows."""
    marked = [g for g in gens if "playback" in g]
    if not marked:
        return
    mac = mats["mac_con"]
    width = MACHINE.col("pb_Tf")
    if mac.shape[1] < width:  # the omitted columns at their declared defaults
        pad = [p.default for p in MACHINE.params[mac.shape[1] : width]]
        mac = np.hstack([mac, np.tile(pad, (mac.shape[0], 1))])
    for g in marked:
        r = int(np.flatnonzero(mac[:, 0] == g["number"])[0])
        mac[r, MACHINE.col("playback") - 1 : width] = (1.0, *g["playback"])
    mats["mac_con"] = mac


def _playback_source(ss, k: int, number: int, numbers: dict) -> dict:
    """The generator of ANDES's PLBVFU1 ``k`` (a dict for :func:`stabctl.io.dyr.dyr_tables`,
    with ``playback`` (Tv, Tf) for the mac_con playback columns): E' behind ``xs`` with
    its static generator's power-flow power; its TimeSeries is a run's Playback event."""
    m = ss.PLBVFU1
    sg = ss.PV if m.gen.v[k] in ss.PV.idx.v else ss.Slack
    j = list(sg.idx.v).index(m.gen.v[k])
    return {
        "number": number,
        "bus": numbers[m.bus.v[k]],
        "id": f"PLB{m.idx.v[k]}",
        "mbase": float(m.Sn.v[k]),
        # on its Sn at the bus's voltage base: ANDES's system-base values (its Vn may differ)
        "ra": float(m.ra.v[k] * m.Sn.v[k] / ss.config.mva),
        "xsource": float(m.xs.v[k] * m.Sn.v[k] / ss.config.mva),
        "pg": float(sg.p.v[j]),
        "qg": float(sg.q.v[j]),
        "sbase": float(ss.config.mva),
        "playback": (float(m.Tv.v[k]), float(m.Tf.v[k])),
    }


def _infinite_bus(ss, k: int, number: int, numbers: dict) -> dict:
    """The generator (a dict for :func:`stabctl.io.dyr.dyr_tables`) of Slack ``k`` without
    a machine: in ANDES's time domain it keeps its equations ``a = a0``, ``v = v0``
    (``andes/models/static/slack.py``), an ideal source, here a GENCLS of H = 0 behind
    :data:`INFINITE_BUS_X` with the power its power flow gives it."""
    sg = ss.Slack
    return {
        "number": number,
        "bus": numbers[sg.bus.v[k]],
        "id": f"SLACK{sg.idx.v[k]}",
        "mbase": float(ss.config.mva),
        "ra": 0.0,
        "xsource": INFINITE_BUS_X,
        "pg": float(sg.p.v[k]),
        "qg": float(sg.q.v[k]),
        "sbase": float(ss.config.mva),
    }


def _check_shares(ss, file: str, machines, with_converter) -> None:
    """CaseError for a static generator whose machines' shares ``gammap``/``gammaq`` do not
    add up to 1 (a duplicated machine record doubled its generation; ANDES runs it)."""
    shares: dict = {}
    for _, name, k in machines:
        m = ss.models[name]
        acc = shares.setdefault(m.gen.v[k], [0.0, 0.0, []])
        acc[0] += float(m.gammap.v[k])
        acc[1] += float(m.gammaq.v[k])
        acc[2].append(f"{name} {m.idx.v[k]}")
    for gen, (p, q, names) in shares.items():
        if gen not in with_converter and (abs(p - 1) > 1e-9 or abs(q - 1) > 1e-9):
            raise CaseError(
                f"{file}: static generator {gen}: its machines ({', '.join(names)}) take "
                f"gammap {p:g} and gammaq {q:g} of its power, not 1 (a duplicated record?)"
            )


def _grouped(changed) -> list[str]:
    """``"MODEL (n: idx, ...): why"`` per model and reason of the devices kept with a
    change, in first-seen order (five idx named)."""
    groups: dict[tuple[str, str], list[str]] = {}
    for name, idx, why in changed:
        groups.setdefault((name, why), []).append(idx)
    return [
        f"{name} ({len(ids)}: {', '.join(ids[:5])}{', ...' if len(ids) > 5 else ''}): {why}"
        for (name, why), ids in groups.items()
    ]


def _fixed_differs(m, name: str, k: int) -> str:
    """Why device ``k`` cannot be mapped: a parameter outside PSS/E's data away from the
    value stabctl's model has (empty if none)."""
    for p, want in _FIXED.get(name, {}).items():
        if m.params[p].vin[k] != want:
            return f"{p} = {m.params[p].vin[k]:g} (stabctl's model has {want:g})"
    tn = m.params.get("Tn")
    if tn is not None and tn.vin[k] not in (0.0, m.Sg.v[k]):
        return f"turbine rating Tn = {tn.vin[k]:g} MW differs from the machine's"
    return ""


def _psse_yaml() -> dict:
    """ANDES's PSS/E DYR mapping (``andes/io/psse-dyr.yaml``)."""
    import andes.io
    import yaml

    with open(Path(andes.io.__file__).parent / "psse-dyr.yaml", encoding="utf-8") as fh:
        return yaml.safe_load(fh)


def _psse_params(ss, m, spec: dict, fields, k: int) -> tuple[float, ...]:
    """The PSS/E record's numbers (``fields`` order) of ANDES device ``k`` of model ``m``,
    inverting the model's ``outputs`` of ``psse-dyr.yaml`` (its ``inputs`` matched to
    ``fields`` by name where the names agree, else by position: ANDES lists ESST1A's
    in its own order, TB before TC): a parameter copied from a PSS/E
    input gives it back; H is M/2 (``M: "H; lambda x: 2 * x"``); remote buses None -> 0;
    EXDC2's and IEEEX1's Switch, which ANDES lacks, is 0; IEEEG1's second machine (JBUS)
    is its bus number (0 without one); a stabiliser's input code left empty (NaN: ANDES's
    input switch matches no option and the signal is 0) is 0, PSS/E's "no input"."""
    inputs = spec["inputs"][2:]
    if len(inputs) != len(fields):
        raise InputError(
            f"ANDES's psse-dyr.yaml gives {len(inputs)} {m.class_name} "
            f"parameters, the PSS/E Model Library {len(fields)}"
        )
    source: dict[str, Any] = {}
    for param, expr in spec["outputs"].items():
        if isinstance(expr, str) and ";" in expr:
            source.setdefault(expr.split(";")[0].split(".")[-1].strip(), param)
        else:
            source.setdefault(expr, param)
    values = []
    for name in inputs:
        param = source.get(name)
        if name == "H" and param == "M":
            values.append(m.M.vin[k] / 2)
        elif param is not None and param in m.params:
            v = m.params[param]
            values.append(_number(v.vin[k] if hasattr(v, "vin") else v.v[k]))
            if name in _INPUT_CODES and np.isnan(values[-1]):
                values[-1] = 0.0
        elif name == "BUS2":
            syn2 = m.syn2.v[k] if "syn2" in m.params else None
            values.append(0.0 if syn2 is None else float(ss.SynGen.get("bus", syn2)))
        else:  # Switch, ID2: not in ANDES's model
            values.append(0.0)
    if sorted(inputs) == sorted(fields):  # same names: the Model Library's order
        return tuple(values[inputs.index(name)] for name in fields)
    return tuple(values)


#: the stabilisers' input-code fields (PSS/E Model Library: IEEEST ICS, ST2CUT MODE, MODE2)
_INPUT_CODES = frozenset({"ICS", "MODE", "MODE2"})


def _number(v) -> float:
    return 0.0 if v is None else float(v)


def _powerflow(ss, numbers: dict):
    """ANDES's power flow (tolerance 1e-12) in the case's bus order (the buses in
    service); Nones if it fails."""
    ss.PFlow.config.tol = 1e-12
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if not ss.PFlow.run():
            return None, None, None
    on = _in_service(ss.Bus)
    return (
        np.array([numbers[ss.Bus.idx.v[k]] for k in on]),
        np.array(ss.Bus.v.v, float)[on],
        np.array(ss.Bus.a.v, float)[on],
    )


def _pf_power(sg, name: str, j: int) -> float:
    """Static generator ``sg``'s row ``j`` P (``name`` "p") or Q ("q") of ANDES's power
    flow, pu on the system base; its data p0 or q0 when that power flow did not converge
    (round 59 BD09: the last iterate's Q made machine shares of +5e7 and -5e7)."""
    if getattr(getattr(sg.system, "PFlow", None), "converged", True):
        return float(getattr(sg, name).v[j])
    return float(getattr(sg, f"{name}0").v[j])
