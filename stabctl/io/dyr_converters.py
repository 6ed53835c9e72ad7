"""PSS/E DYR converter records to rows of the converter table (``ibr_con``).

A RAW generator with a ``REGCA1`` record is a WECC second-generation renewable plant, the
converter of :data:`stabctl.models.converters.REGCA1` (docs/ibr.md), the same row
:mod:`stabctl.io.andes_case` builds from ANDES's devices: its electrical control
``REECA1``, ``REECB1`` or ``REECD1`` (WECC REEC_D, no IREG), that control's plant control
``REPCA1`` and (a REECA1's) wind turbine, drive train ``WTDTA1`` then ``WTARA1``,
``WTPTA1``, ``WTTQA1``, each a record of the same generator (bus, id). A ``REGCB1`` record
in place of the REGCA1 is the same plant with the WECC REGC_B interface (ibr_con ``regc``
1, :mod:`stabctl.models.converters.regcb1`), its source impedance the RAW generator's
ZSORCE (on MBASE). Parameter order (ICONs first) and the ``ibr_con`` field each is copied
to are declared with the table (``CONVERTER.dyr``, :mod:`stabctl.models.converters`);
values as given (device base MBASE, as PSS/E's), the rest of the row the table's defaults
(ANDES 2.0's: its REECA1/REPCA1 configuration kqs = kvs = ksg = 2, tpfilt 0.02 s, freeze
1, and the BusFreq of a REPCA1's frequency, Tf 0.02 s, Tw 0.1 s).

A RAW generator with a ``DERA1`` record (WECC DER_A, aggregated distributed energy
resources) is a converter of :data:`stabctl.models.converters.DERA1`, alone (no other
converter record of that generator): its flags and parameters copied
(:mod:`stabctl.models.converters.dera1`, every flag modelled), values as given on MBASE.

PSS/E's conventions where ANDES's reading of the same record differs: IREG = 0 (REECx,
REPCA1) is the plant's own bus (ANDES reads it as bus 0); REECx's Tp = 0 is no filter (a
lag below :data:`stabctl.models.blocks.LBND` is bypassed); REPCA1's Pmax, Pmin bound the
plant's P reference (PSS/E's block diagram, GridPACK's ``repca1.cpp``: the PI starts at the
dispatch), where ANDES's bound the increment Pext that the table holds, so the table gets
Pmax - P0, Pmin - P0 (P0 = PG / MBASE; ``conventions="andes"`` keeps ANDES's reading);
and the row's ``psse`` 1, the models' own PSS/E readings (``conventions="andes"``: 0,
ANDES 2.0's): REECB1 with QFLAG 1 regulates the filtered voltage, its V PI on clip(VFLAG ?
the Q PI's output : Vref0, VMIN, VMAX) - Vt_filt, the Q PI starting at |V0| (OpenIPSL's
PSS/E-verified ``REECB1.mo``; ANDES 2.0's reecb1.py feeds the V PI clip(VFLAG Q PI) with
no reference and no voltage: with VFLAG 0 no voltage control, with VMIN > 0 no start), and
REECA1 with VFLAG and QFLAG 1 likewise, with QFLAG 1 and VFLAG 0 its Q reference |V0| -
Vref1 (``REECA1.mo``: Vsel = V0 at the start; ANDES's Vref1 - |V0|); WTDTA1's Freq1 is in
Hz, Kshaft = 2 Ht Hg (2 pi Freq1)^2/(H w0) on the shaft angle (``WTDTA1.mo``; ANDES reads
it as rad/s: a 1.8 Hz mode at 0.27 Hz); WTARA1's theta is the pitch angle in degrees, Pm =
Pm0 - Ka theta (theta - theta0), at rest at theta0, WTPTA1's pitch starting there (ANDES
mixes rad(Theta0) with degrees: no start with Theta0 not 0); WTPTA1's speed PI acts on wt
- wref, WTTQA1's speed reference (ANDES: the constant w0 = 1), its rate limits RTetaMax,
RTetaMin on dtheta/dt (ANDES: on Tp dtheta/dt).  PSS/E gives every value on MBASE; the
values the table holds on the system base as ANDES reads them (REGCA1's Rrpwr, Lvpl1, Khv,
REECx's Kqv, Iqh1, Iql1, Iqfrz, the Q and V PIs' gains and tracking gains, REPCA1's Kc,
Rc, Xc, Qmax, Qmin, droops, P error limits, its PI's gains and, with RefFlag 0, its error
limits and deadband) are converted by MBASE/SBASE (`_to_table_bases`), so that a plant
runs the same on any system base and split into any number of units.
REPCA1's monitored branch
(BUS1, BUS2, CKTID; 0 0: none) is the RAW branch between those buses (its r, x on the
system base).  REGCA1's Accel (the network solution's acceleration factor) is not a model
parameter and is not read.

Left out, with why (`ConverterRows.skipped`): a plant regulating a remote bus (IREG not 0
nor its own bus), a monitored branch that is not one in-service RAW branch, a wind turbine
of a REECB1 or with a link missing, and every record of a plant left out; a control
record without a REGCA1 or REGCB1; a DERA1 with other converter records of its generator.  A plant
sharing its bus with other generators (machines or plants) takes its own PG, QG of the
bus's generation (ibr_con pfrac, qfrac), as they do.

Source: PSS/E Model Library (REGCA1, REGCB1, REECA1, REECB1, REPCA1, WTDTA1, WTARA1, WTPTA1,
WTTQA1 ICONs and CONs); ANDES 2.0 ``andes/io/psse-dyr.yaml`` for the same orders.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from stabctl.errors import CaseError
from stabctl.io.dyr import CONVERTER_DYR, DyrRecord, bus_shares, machine_id, no_generator
from stabctl.io.provenance import Origin
from stabctl.models.converters import (
    CONVERTER,
    DERA1,
    REECA1,
    REECB1,
    REECD1,
    REGC_A,
    REGC_B,
    REGCA1,
    REPCA1,
    WTDTA1,
)
from stabctl.models.converters.reeca1 import has_curve

__all__ = ["ConverterRows", "converter_rows", "shares", "CONVERTER_RECORDS"]

#: the DYR records read into the converter table
CONVERTER_RECORDS = tuple(CONVERTER_DYR)
#: converter interface record -> ibr_con ``regc`` code
_REGC = {"REGCA1": REGC_A, "REGCB1": REGC_B}
#: electrical control record -> ibr_con ``reec`` code
_REEC = {"REECA1": REECA1, "REECB1": REECB1, "REECD1": REECD1}
#: the wind turbine's records after the drive train, in chain order, with the ibr_con
#: flag each sets
_WIND_CHAIN = (("WTARA1", "aero"), ("WTPTA1", "pitch"), ("WTTQA1", "torque"))


@dataclass(frozen=True)
class ConverterRows:
    """What `converter_rows` gives.

    Attributes
    ----------
    rows : list of list of float
        ``ibr_con`` rows (:data:`stabctl.models.converters.CONVERTER` column order), one
        per plant, numbered 1, 2, ... in RAW generator order.
    replaced : frozenset of (int, str)
        The (bus, machine id) of the generators the rows model (not machines).
    skipped : tuple of (DyrRecord, str)
        The converter records left out, each with why, in file order.
    origins : tuple of Origin
        Each row's records (`stabctl.io.provenance`): the REGCA1's (DERA1's) as the
        row's, each column its record's parameter as written.
    """

    rows: list[list[float]]
    replaced: frozenset[tuple[int, str]]
    skipped: tuple[tuple[DyrRecord, str], ...]
    origins: tuple[Origin, ...] = ()


class _Refused(Exception):
    """A plant stabctl cannot represent: the reason."""


def converter_rows(records, generators, branches, conventions: str = "psse") -> ConverterRows:
    """The converter table's rows of the REGCA1 (or REGCB1) and DERA1 plants of a DYR file.

    Parameters
    ----------
    records : sequence of DyrRecord
        The DYR file's records (:func:`stabctl.io.dyr.read_dyr`); records of other
        models are ignored.
    generators : sequence of dict
        The RAW file's in-service generators in RAW order, keys ``"bus"``, ``"id"``,
        ``"mbase"`` (MVA), ``"pg"``, ``"qg"`` (MW, Mvar), as
        :func:`stabctl.io.dyr.dyr_tables` takes them.
    branches : numpy.ndarray
        The RAW file's PST ``line`` matrix, shape (n_branch, >= 4): from bus, to bus, r,
        x (pu, system base), for a REPCA1's monitored branch.
    conventions : str, optional
        ``"psse"`` (default): a REPCA1's Pmax, Pmin bound its P reference, as PSS/E's
        (and GridPACK's) REPCA1, so the table's bounds of the increment Pext are
        Pmax - P0 and Pmin - P0 with P0 = PG / MBASE the plant's dispatch, and the row's
        ``psse`` 1 (PSS/E's REECB1/REECA1 voltage loop, WTDTA1, WTARA1 and WTPTA1: the
        module's docstring); ``"andes"`` or ``"pst"``: as given (ANDES 2.0's REPCA1
        bounds the increment itself) and ``psse`` 0, ANDES 2.0's readings.

    Returns
    -------
    ConverterRows
        The rows, the generators they model and the records left out with why.

    Raises
    ------
    CaseError
        Naming file:line, model and (bus, id): a record with the wrong number of
        parameters, a flag (ICON) not among its choices, two records of one model for a
        generator.
    """
    plants = converter_plants(records)
    gens = {(int(g["bus"]), machine_id(g["id"])): g for g in generators}
    rows: list[list[float]] = []
    origins: list[Origin] = []
    replaced: set[tuple[int, str]] = set()
    skipped: list[tuple[DyrRecord, str]] = []
    for key in sorted(plants, key=lambda k: list(gens).index(k) if k in gens else len(gens)):
        plant = plants[key]
        try:
            if "DERA1" in plant and len(plant) > 1:
                others = ", ".join(sorted(set(plant) - {"DERA1"}))
                raise _Refused(f"a DERA1 with other converter records ({others})")
            regc = [name for name in _REGC if name in plant]
            if len(regc) > 1:
                raise _Refused("two converter interfaces (REGCA1 and REGCB1; stabctl: one)")
            if not regc and "DERA1" not in plant:
                raise _Refused("no REGCA1 or REGCB1 record for its generator")
            gen = gens.get(key)
            if gen is None:
                raise _Refused(no_generator(next(iter(plant.values())), gens))
            if "DERA1" in plant:
                row = _dera1_row(plant["DERA1"], gen, len(rows) + 1)
            else:
                row = _plant_row(plant, gen, len(rows) + 1, branches, conventions)
            row[CONVERTER.col("pfrac") - 1], row[CONVERTER.col("qfrac") - 1] = shares(
                generators, gen
            )
        except _Refused as why:
            skipped += [(rec, str(why)) for rec in plant.values()]
            continue
        rows.append(row)
        origins.append(_plant_origin(plant))
        replaced.add(key)
    skipped.sort(key=lambda item: (item[0].file, item[0].line))
    return ConverterRows(rows, frozenset(replaced), tuple(skipped), tuple(origins))


def converter_plants(records) -> dict[tuple[int, str], dict[str, DyrRecord]]:
    """The converter records of a DYR file (:data:`stabctl.io.dyr.CONVERTER_DYR`'s models)
    by generator: (bus, id) -> model -> record.

    Parameters
    ----------
    records : sequence of DyrRecord
        The DYR file's records (:func:`stabctl.io.dyr.read_dyr`); records of other
        models are ignored.

    Returns
    -------
    dict

    Raises
    ------
    CaseError
        Naming file:line, model and (bus, id): a record with the wrong number of
        parameters, or a second record of one model for a generator (PSS/E takes one of
        each; which one a reader keeps decides the plant).
    """
    plants: dict[tuple[int, str], dict[str, DyrRecord]] = {}
    for rec in records:
        if rec.model not in CONVERTER_DYR:
            continue
        want = len(CONVERTER_DYR[rec.model].fields)
        if len(rec.params) != want:
            raise CaseError(
                f"{rec.label()}: needs {want} parameters after the id, got {len(rec.params)}"
            )
        plant = plants.setdefault((rec.bus, rec.id), {})
        if rec.model in plant:
            raise CaseError(
                f"{rec.label()}: second {rec.model} record for this generator (first at "
                f"{plant[rec.model].where()})"
            )
        plant[rec.model] = rec
    return plants


def _plant_origin(plant: dict[str, DyrRecord]) -> Origin:
    """The `Origin` of a plant's ibr_con row: its REGCA1's (REGCB1's, DERA1's) record,
    each column copied from a record (`DyrModel.copy`) with that record's parameter."""
    main = next(plant[m] for m in (*_REGC, "DERA1", *plant) if m in plant)
    params: dict[int, tuple[tuple[str, float], ...]] = {}
    places: dict[int, str] = {}
    for rec in plant.values():
        values = CONVERTER_DYR[rec.model].values(rec.params)
        for name, src in CONVERTER_DYR[rec.model].copy.items():
            k = CONVERTER.col(name)
            params[k] = ((src, values[src]),)
            if rec is not main:
                places[k] = rec.label()
    return Origin(main.label(), params, places=places)


def shares(generators, gen) -> tuple[float, float]:
    """The share of generator ``gen`` in its bus's P and Q generation, PG / sum(PG) and QG /
    sum(QG) over the ``generators`` at its bus (keys "bus", "pg", "qg";
    `stabctl.io.dyr.bus_shares`; 1, 1 alone on its bus): as PSS/E's generators, each keeps
    its own PG, QG of the RAW's power flow."""
    at = [g for g in generators if int(g["bus"]) == int(gen["bus"])]
    if len(at) == 1:
        return 1.0, 1.0
    k = at.index(gen)
    return bus_shares(at, "pg")[k], bus_shares(at, "qg")[k]


def _plant_row(
    plant: dict[str, DyrRecord], gen: dict, number: int, branches, conventions: str
) -> list[float]:
    """The ibr_con row of one plant's records (`_Refused` for what stabctl lacks); a
    REPCA1's P bounds as ``conventions`` (`converter_rows`)."""
    v = {p.name: p.default for p in CONVERTER.params}
    v.update(number=number, bus=int(gen["bus"]), type=REGCA1, mva=float(gen["mbase"]))
    (interface,) = (name for name in _REGC if name in plant)
    v["regc"] = _REGC[interface]
    _copy(plant[interface], v)
    if interface == "REGCB1":  # its source impedance, ZSORCE on MBASE
        v["gb_Rsource"], v["gb_Xsource"] = float(gen["ra"]), float(gen["xsource"])
    reec = [plant[name] for name in _REEC if name in plant]
    if len(reec) > 1:
        names = " and ".join(r.model for r in reec)
        raise _Refused(f"two electrical controls ({names}; stabctl: one)")
    if reec:
        rec = reec[0]
        _own_bus(rec)
        v["reec"] = _REEC[rec.model]
        _copy(rec, v)
        if rec.model == "REECA1":
            _no_curve_noted(rec, v)
    v["psse"] = 1.0 if conventions == "psse" else 0.0  # the models' readings
    if "REPCA1" in plant:
        rec = plant["REPCA1"]
        if not reec:
            raise _Refused("a REPCA1 without an electrical control (REECA1, REECB1 or REECD1)")
        _own_bus(rec)
        v["repc"] = REPCA1
        _copy(rec, v)
        v.update(_monitored_branch(rec, int(gen["bus"]), branches))
        if conventions == "psse":  # bounds of the P reference -> of its increment Pext
            p0 = float(gen["pg"]) / float(gen["mbase"])
            v["pc_Pmax"], v["pc_Pmin"] = v["pc_Pmax"] - p0, v["pc_Pmin"] - p0
    _wind(plant, reec[0] if reec else None, v)
    if conventions == "psse":
        _to_table_bases(v, float(gen["mbase"]) / float(gen.get("sbase", 100.0)))
    return [float(v[p.name]) for p in CONVERTER.params]


#: ibr_con fields the table holds on the system base (ANDES's reading, which does not
#: convert them) that PSS/E gives on MBASE: (field, power of MBASE/SBASE that converts
#: them), `_to_table_bases`
_SYSTEM_BASE_FIELDS = (
    *(("Rrpwr", 1), ("Lvpl1", 1), ("Khv", 1)),  # REGCA1: dIp/dt, a current, Iq per V
    *(("Kqv", 1), ("Iqh1", 1), ("Iql1", 1), ("Iqfrz", 1)),  # REECx: V -> Iqinj, currents
    *(("Kvp", 1), ("Kvi", 1), ("Kqp", -1), ("Kqi", -1)),  # V -> Iq; Q -> V
    # the PIs' tracking gains (error per output, `stabctl.models.blocks.pi_track_aw`)
    *(("Kvs", -1), ("Kqs", 1)),
    *(("pc_Qmax", 1), ("pc_Qmin", 1), ("pc_Kc", -1), ("pc_Rc", -1), ("pc_Xc", -1)),
    *(("pc_Ddn", 1), ("pc_Dup", 1), ("pc_femax", 1), ("pc_femin", 1)),  # f -> P; P
)
#: REPCA1's fields of its error (V with RefFlag 1, Q with 0): the power of MBASE/SBASE for
#: each RefFlag (the PI's gains turn the error into Q; its tracking gain, Q into error)
_REPC_ERROR_FIELDS = (
    *(("pc_Kp", 1, 0), ("pc_Ki", 1, 0), ("pc_Kqs", -1, 0)),
    *(("pc_emax", 0, 1), ("pc_emin", 0, 1), ("pc_dbd1", 0, 1), ("pc_dbd2", 0, 1)),
)


def _to_table_bases(v: dict, s: float) -> None:
    """Convert a PSS/E plant's values on its MBASE (PSS/E Model Library: REGC_A, REEC_A/B/D,
    REPC_A parameters in pu on MBASE) to the bases of the table (``v``, in place), whose
    kernels run on the system base: the fields the table takes as ANDES reads them, on
    the system base (`_SYSTEM_BASE_FIELDS`; the table's device-base fields are converted by
    `stabctl.models.converters.converter_params`), times ``s`` = MBASE/SBASE to a power
    (round 59 BB16-17: a plant's Q 0.21 pu off at SBASE 200, and a plant split in two
    halves differed so; PSS/E's results do not depend on SBASE)."""
    has = {"reec": bool(v["reec"]), "pc": bool(v["repc"])}
    for name, power in _SYSTEM_BASE_FIELDS:
        if name in ("Rrpwr", "Lvpl1", "Khv") or has["pc" if name.startswith("pc_") else "reec"]:
            v[name] *= s**power
    ref = v["pc_RefFlag"] == 1.0
    for name, on_v, on_q in _REPC_ERROR_FIELDS if has["pc"] else ():
        v[name] *= s ** (on_v if ref else on_q)


def _no_curve_noted(rec: DyrRecord, v: dict) -> None:
    """Warn of a REECA1 VDL curve whose points are all 0: read as no curve, the current
    limited by Imax alone (as a REECD1's table of no points; round 43: every run of it
    was refused at a current limit 0, without a word at import)."""
    for volts, amps, curve in (("Vq", "Iq", "VDL1"), ("Vp", "Ip", "VDL2")):
        if not has_curve(v, volts, amps):
            warnings.warn(
                f"{rec.label()}: {curve} ({volts}1..{amps}4) all 0: read as no curve, "
                f"{amps} limited by Imax alone (a table of no points, as REECD1's)",
                UserWarning,
                stacklevel=2,
            )


def _dera1_row(rec: DyrRecord, gen: dict, number: int) -> list[float]:
    """The ibr_con row of a DERA1 record (every field copied, `dera1.DYR`)."""
    v = {p.name: p.default for p in CONVERTER.params}
    v.update(number=number, bus=int(gen["bus"]), type=DERA1, mva=float(gen["mbase"]))
    _copy(rec, v)
    return [float(v[p.name]) for p in CONVERTER.params]


def _copy(rec: DyrRecord, v: dict) -> None:
    """The declared copies of ``rec`` into ``v``; CaseError for a flag not among its
    column's choices."""
    model = CONVERTER_DYR[rec.model]
    values = model.values(rec.params)
    for name, src in model.copy.items():
        p = CONVERTER.param(name)
        if p.choices and values[src] not in p.choices:
            raise CaseError(
                f"{rec.label()}: {src} = {values[src]:g} must be one of "
                f"{', '.join(f'{c:g}' for c in p.choices)}"
            )
        v[name] = values[src]


def _own_bus(rec: DyrRecord) -> None:
    """`_Refused` when ``rec`` regulates a remote bus (IREG neither 0 nor its own bus; a
    record without IREG, REECD1, regulates its own)."""
    ireg = CONVERTER_DYR[rec.model].values(rec.params).get("IREG", 0)
    if ireg not in (0, rec.bus):
        raise _Refused(f"{rec.model} regulates remote bus IREG = {ireg:g} (stabctl: its own)")


def _monitored_branch(rec: DyrRecord, bus: int, branches) -> dict[str, float]:
    """ibr_con pc_bus1, pc_bus2, pc_r, pc_x of a REPCA1's monitored branch (BUS1 BUS2 0 0:
    none, the table's defaults): the one RAW branch between those buses."""
    vals = CONVERTER_DYR["REPCA1"].values(rec.params)
    b1, b2 = int(vals["BUS1"]), int(vals["BUS2"])
    if b1 == 0 and b2 == 0:
        return {}
    ends = np.asarray(branches)[:, :2].astype(int)
    found = np.flatnonzero(
        ((ends[:, 0] == b1) & (ends[:, 1] == b2)) | ((ends[:, 0] == b2) & (ends[:, 1] == b1))
    )
    if found.size != 1:
        raise _Refused(
            f"REPCA1 monitors branch {b1}-{b2} circuit {rec.text[0]!r}: {found.size} "
            "in-service RAW branches join those buses (stabctl: one)"
        )
    if bus not in (b1, b2):
        raise _Refused(f"REPCA1 monitors branch {b1}-{b2}, which does not end at bus {bus}")
    r, x = (float(branches[found[0], c]) for c in (2, 3))
    return {"pc_bus1": b1, "pc_bus2": b2, "pc_r": r, "pc_x": x}


def _wind(plant: dict[str, DyrRecord], reec: DyrRecord | None, v: dict) -> None:
    """The wind turbine's columns into ``v``: its drive train WTDTA1 and each record of
    `_WIND_CHAIN` after it; `_Refused` for a link missing or a REECB1's turbine."""
    chain = [name for name, _ in _WIND_CHAIN if name in plant]
    if "WTDTA1" not in plant and not chain:
        return
    if reec is None or reec.model != "REECA1":
        raise _Refused("a wind turbine without a REECA1 (stabctl: a REECA1's only)")
    links = ["WTDTA1", *(name for name, _ in _WIND_CHAIN)]
    present = [name in plant for name in links]
    if present != sorted(present, reverse=True):
        missing = links[present.index(False)]
        raise _Refused(f"its wind turbine lacks {missing}, which the next record needs")
    v["wind"] = WTDTA1
    _copy(plant["WTDTA1"], v)
    for name, flag in _WIND_CHAIN:
        if name in plant:
            v[flag] = 1.0
            _copy(plant[name], v)
