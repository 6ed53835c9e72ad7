"""A stabctl case from PSS/E data: a RAW power-flow file and optionally a DYR file.

The RAW part (:mod:`stabctl.io.psse_raw`) gives the PST ``bus``, ``line`` and ``load_con``
matrices and the in-service generators; the DYR part (:mod:`stabctl.io.dyr`) gives
``mac_con``, ``exc_con``, ``pss_con`` and ``tg_con`` for those generators (machine ``k``
is the k-th in-service generator of the RAW file); where several machines share a bus,
each takes the share PG_k / sum(PG) of the bus generation and QG_k / sum(QG) of its Q
(``mac_con`` columns 22, 23).

A generator with a ``REGCA1`` record is a converter plant, a row of ``ibr_con`` with its
``REECA1``/``REECB1``, ``REPCA1`` and wind records (:mod:`stabctl.io.dyr_converters`),
not a machine; one with a ``CSVGN1`` record is a static var compensator, a row of
``svc_con`` (:func:`stabctl.io.dyr.compensator_rows`); machines are numbered in RAW order
without them.

Generators without a machine model in the DYR file are refused (``unmodelled="error"``)
or netted (``"net"``, PSS/E's netting: a negative constant-power load at their bus,
:func:`stabctl.io.psse_raw.read_raw`), listed in one warning; wind and solar plants of
synthetic grids (ACTIVSg) often come without dynamic data.

The records PSS/E leaves out of the network (isolated buses and the records at them,
equipment out of service) are left out too, each named in one warning and in
``PsseImport.out_of_service``; so are the dynamic records of generators out of service,
as PSS/E ignores them. The switched shunts and transformers whose automatic control
stabctl does not model (MODSW not 0; a winding's COD > 0) stay at their RAW setting
(BINIT; ratio and angle), named in one warning and in ``PsseImport.held``. Records
that stabctl cannot represent are collected from both files and either refused together
(``on_unsupported="error"``: one :class:`~stabctl.errors.CaseError` listing every one as
``file:line record``) or left out with one warning listing them (``"skip"``).
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import NamedTuple

import numpy as np

from stabctl.case import Case
from stabctl.errors import CaseError, advice
from stabctl.io.psse_raw import Held, RawData, read_raw
from stabctl.io.pst import case_from_matrices

__all__ = ["load_psse", "import_psse", "PsseImport", "held_lines"]

_MODES = ("error", "skip")
_UNMODELLED = ("error", "net")


class PsseImport(NamedTuple):
    """What :func:`import_psse` gives: the case, the records left out and the generators
    netted, each as ``"file:line record: why"`` text, the RAW file's own power-flow
    solution (:attr:`stabctl.io.psse_raw.RawData.solution`: bus number, VM pu, VA
    degrees; shape (n, 3)) to compare the case's power flow with, the DYR records
    read with a value other than the file's (:attr:`stabctl.io.dyr.DyrTables.changed`),
    and the records left out of the network as PSS/E leaves them (isolated buses and what
    is at them, equipment out of service, the DYR records of generators out of service:
    :attr:`stabctl.io.psse_raw.RawData.switched_off`), and the DYR records of the netted
    generators' controls, left out with them; the records whose control stabctl holds at
    their RAW setting (:attr:`stabctl.io.psse_raw.RawData.held`), each, and as the lines
    that name them in a summary (:func:`held_lines`); ``changed`` as a summary names them
    (the IDE 2 buses read as load buses, :attr:`stabctl.io.psse_raw.RawData.load_buses`,
    by :func:`held_lines`)."""

    case: Case
    left_out: tuple[str, ...]
    netted: tuple[str, ...]
    solution: np.ndarray
    changed: tuple[str, ...] = ()
    out_of_service: tuple[str, ...] = ()
    netted_controls: tuple[str, ...] = ()
    held: tuple[str, ...] = ()
    held_summary: tuple[str, ...] = ()
    changed_summary: tuple[str, ...] = ()
    #: the RAW's records of no use to a run, one text a section
    #: (:attr:`stabctl.io.psse_raw.RawData.unused`)
    unused: tuple[str, ...] = ()
    #: how the loads run in the dynamic run where not as the RAW composes them
    #: (:attr:`stabctl.io.psse_raw.RawData.load_model`; "" none)
    load_model: str = ""


def load_psse(
    raw_path: str | Path,
    dyr_path: str | Path | None = None,
    on_unsupported: str = "error",
    loads: str = "impedance",
    conventions: str = "psse",
    unmodelled: str = "error",
) -> Case:
    """Build a :class:`~stabctl.case.Case` from a PSS/E RAW (v32-36) and a DYR file.

    Args:
        raw_path: the ``.raw`` power-flow file.
        dyr_path: the ``.dyr`` dynamic data file, or None for a static case (buses,
            branches, loads only: a power flow, no dynamic run).
        on_unsupported: ``"error"`` refuses records stabctl cannot represent, ``"skip"``
            leaves them out and warns (:class:`UserWarning`) with the list.
        loads: ``"impedance"`` makes all loads constant impedance in the dynamic run,
            ``"raw"`` keeps the PSS/E load composition (see :mod:`stabctl.io.psse_raw`).
        conventions: ``"psse"`` (default) reads the machines as the PSS/E Model Library
            states them (stator at rated speed, P_m and D divided by speed, GENROU's and
            GENROE's saturation of the air-gap flux, GENSAL's and GENSAE's of E'q; the
            other models as ``"pst"``); ``"pst"`` maps the DYR models onto PST's as they
            are (machines with speed effects and no saturation, EXDC2 limits scaled by
            the terminal voltage); ``"andes"`` follows ANDES 2.0's reading for
            like-for-like comparisons (no speed effects in GENROU/GENSAL, EXDC2 limits
            constant; :func:`stabctl.io.dyr.dyr_tables`; docs/pst_models.md 12).
        unmodelled: ``"error"`` refuses generators without a machine model record in the
            DYR file, ``"net"`` nets them (negative constant-power loads PG + jQG at their
            buses, listed in a :class:`UserWarning`).

    Returns:
        the case, named after the RAW file, described by the RAW title lines; units as
        :mod:`stabctl.case` (pu on SBASE, machine data pu on MBASE).

    Raises:
        CaseError: a malformed record (``file:line record: what``), unsupported records
            with ``on_unsupported="error"`` (every one listed), a generator without machine
            model with ``unmodelled="error"`` (every one listed), a swing bus left without
            generator by netting, a bad mode, or data the case model refuses.

    Source: PSS/E POM "Power Flow Raw Data File Contents" and "Dynamics Data" (PSS/E
    Model Library for the DYR records); PST manual section 3.22 for ``mac_con``.
    """
    return import_psse(raw_path, dyr_path, on_unsupported, loads, conventions, unmodelled)[0]


def import_psse(
    raw_path: str | Path,
    dyr_path: str | Path | None = None,
    on_unsupported: str = "error",
    loads: str = "impedance",
    conventions: str = "psse",
    unmodelled: str = "error",
) -> PsseImport:
    """:func:`load_psse` that also returns the records left out (empty unless
    ``on_unsupported="skip"``), the generators netted (empty unless
    ``unmodelled="net"``) and the records out of the network (`PsseImport`). Same
    arguments and errors."""
    from stabctl.io.dyr import UnmodelledError, read_dyr

    if on_unsupported not in _MODES:
        raise CaseError(f"on_unsupported must be 'error' or 'skip', got {on_unsupported!r}")
    if unmodelled not in _UNMODELLED:
        raise CaseError(f"unmodelled must be 'error' or 'net', got {unmodelled!r}")
    records = None if dyr_path is None else read_dyr(dyr_path)
    net = None if records is None or unmodelled == "error" else _without_machine(records)
    raw = read_raw(raw_path, loads=loads, net=net)
    mats = raw.matrices()
    unsupported = [str(s) for s in raw.unsupported]
    changed: tuple[str, ...] = ()
    origins: dict = {}
    ids: dict[int, str] = {}
    lost: list[str] = []
    off_network = [str(s) for s in raw.switched_off]
    with_netted: list[str] = []
    if records is not None:
        records, ignored = _in_service(records, raw.out_of_service)
        off_network += ignored
        records, with_netted = _of_netted(records, raw.netted_ids)
        try:
            dyn, dyr_unsupported, lost, changed, origins, ids = _dynamic_tables(
                raw, records, conventions
            )
        except UnmodelledError as exc:
            raise exc.relocated(f"{exc}{_net_advice(exc.unreadable)}") from None
        mats.update(dyn)
        unsupported += dyr_unsupported
    where = _files(raw_path, dyr_path)
    _report(unsupported, on_unsupported, where)
    if records is not None and lost:
        raise CaseError(
            f"{where}: generator(s) left without a model, their converter records left "
            f"out (listed above): {', '.join(lost)}"
        )
    _say_off_network(off_network, where)
    netted = tuple(str(s) for s in raw.netted)
    if netted:
        also = (
            f"; left out with them their {len(with_netted)} control record(s): "
            + "; ".join(with_netted)
            if with_netted
            else ""
        )
        warnings.warn(
            f"{where}: netted {len(netted)} generator(s) without a (supported) machine "
            f"model as negative loads: {'; '.join(netted)}{also}",
            UserWarning,
            stacklevel=3,
        )
    try:
        case = case_from_matrices(
            mats, raw.name, source=_source(raw_path, dyr_path), description=raw.title
        )
    except CaseError as exc:  # the record and parameters the table's row came from
        raise _located(exc, origins, where) from None
    case = case.replace(machine_ids=ids)
    changed = (
        *(str(c) for c in raw.changed),
        *(str(h.source) for h in raw.load_buses),
        *changed,
    )
    if changed:
        warnings.warn(
            f"{where}: read {len(changed)} record(s) with a value other than the file's: "
            + "; ".join(changed),
            UserWarning,
            stacklevel=3,
        )
    if raw.noted:
        warnings.warn(
            f"{where}: {len(raw.noted)} record(s) kept as written that look wrong: "
            + "; ".join(str(n) for n in raw.noted),
            UserWarning,
            stacklevel=3,
        )
    if raw.circuit_order:
        warnings.warn(
            f"{where}: parallel circuits are numbered in file order ("
            + advice("LineFault and LineTrip's circuit", "--trip A B:K, --circuit K")
            + "), which is not their CKT id here: "
            + "; ".join(raw.circuit_order),
            UserWarning,
            stacklevel=3,
        )
    held = held_lines(raw.held)
    if held:
        warnings.warn(
            f"{where}: {len(raw.held)} control(s) held at their RAW setting: " + "; ".join(held),
            UserWarning,
            stacklevel=3,
        )
    return PsseImport(
        case,
        tuple(unsupported),
        netted,
        raw.solution,
        changed,
        tuple(off_network),
        tuple(with_netted),
        tuple(str(h.source) for h in raw.held),
        tuple(held),
        (
            *(str(c) for c in changed[: len(raw.changed)]),
            *held_lines(raw.load_buses),
            *changed[len(raw.changed) + len(raw.load_buses) :],
        ),
        raw.unused,
        raw.load_model,
    )


#: records of one kind named one by one in :func:`held_lines` up to this many
HELD_ONE_BY_ONE = 5
#: what a summary line of many records of a kind (:func:`held_lines`) says of them
_HELD_MANY = {
    "switched shunt": "switched shunts held at BINIT (MODSW not 0: not switched in the "
    "power flow or the dynamics)",
    "transformer": "transformers held at their RAW ratio and angle (COD > 0: their tap or "
    "phase control not modelled in the power flow or the dynamics)",
    "IDE 2 bus": "IDE 2 buses without a generator in service (none, or netted) read as "
    "load buses (PSS/E)",
}


def held_lines(held: Sequence[Held]) -> list[str]:
    """Lines naming records by kind (:class:`stabctl.io.psse_raw.Held`: the controls held
    at their RAW setting, the IDE 2 buses read as load buses), per kind in file order:
    each record (``file:line record: why``) when a kind has at most
    :data:`HELD_ONE_BY_ONE`, else one line with their count, why and their buses (a
    transformer's joined by ``-``)."""
    lines: list[str] = []
    for kind in dict.fromkeys(h.kind for h in held):
        of_kind = [h for h in held if h.kind == kind]
        if len(of_kind) <= HELD_ONE_BY_ONE:
            lines += [str(h.source) for h in of_kind]
        else:
            at = ", ".join(h.at for h in of_kind)
            lines.append(f"{len(of_kind)} {_HELD_MANY[kind]}, at buses {at}")
    return lines


def _located(exc: CaseError, origins: dict, where: str) -> CaseError:
    """A case table's error naming the DYR record and parameters its row came from
    (`stabctl.io.provenance.locate`), or, for a row of no record (the RAW data's), the
    files ``where``."""
    from stabctl.case.params import FAMILIES
    from stabctl.io.provenance import locate

    located = locate(exc, origins, {f.table: f for f in FAMILIES.values()})
    return located if located is not exc else exc.relocated(f"{where}: {exc}")


def _net_advice(unreadable: bool) -> str:
    """How to import generators without a machine model all the same: netted."""
    skip = ("on_unsupported='skip'", "--skip-unsupported")
    net = ("unmodelled='net'", "--net-unmodelled")
    (lib, cli) = (
        f" ({n} nets them as negative loads"
        + (f", with {s} leaving out the records it cannot read)" if unreadable else ")")
        for n, s in zip(net, skip)
    )
    return advice(lib, cli)


def _of_netted(records, netted_ids) -> tuple[list, list[str]]:
    """The DYR records but the controls of the generators netted for want of a (supported)
    machine model, and those controls named: they leave with their generator (its
    machine and converter records stay, reported as they are)."""
    from stabctl.io.dyr import is_control, machine_id

    netted = {(bus, machine_id(gid)) for bus, gid in netted_ids}
    gone = [r for r in records if (r.bus, r.id) in netted and is_control(r)]
    left = [f"{r.label()}: left out with its generator, netted (no machine model)" for r in gone]
    ids = {id(r) for r in gone}
    return [r for r in records if id(r) not in ids], left


def _in_service(records, out_of_service) -> tuple[list, list[str]]:
    """The DYR records of the generators in service, and the others named (PSS/E ignores
    the dynamic records of a generator out of service or at an isolated bus)."""
    from stabctl.io.dyr import machine_id

    off = {(bus, machine_id(gid)) for bus, gid in out_of_service}
    ignored = [
        f"{r.label()}: its generator is out of the network (out of service or at an isolated bus)"
        for r in records
        if (r.bus, r.id) in off
    ]
    return [r for r in records if (r.bus, r.id) not in off], ignored


def _say_off_network(records: list[str], where: str) -> None:
    """One warning naming the records left out of the network, as PSS/E leaves them."""
    if records:
        warnings.warn(
            f"{where}: left out {len(records)} record(s) out of the network, as PSS/E "
            f"leaves them (isolated buses, equipment out of service): {'; '.join(records)}",
            UserWarning,
            stacklevel=4,
        )


def _without_machine(records):
    """``net`` for :func:`read_raw`: for a (bus, ID) that no DYR machine record stabctl
    maps names, the reason it is netted: no source record at all, or only records of a
    generator model stabctl does not support (named ``file:line MODEL``; they are
    reported unsupported, so left out only with ``on_unsupported="skip"``); else None."""
    from stabctl.io.dyr import SVC_DYR, has_machine_model, machine_id, maps_machine

    modelled = {(r.bus, r.id) for r in records if maps_machine(r) or r.model in SVC_DYR}
    sources: dict = {}
    for r in records:
        if has_machine_model(r):
            sources.setdefault((r.bus, r.id), []).append(f"{r.where()} {r.model}")

    def net(bus, gid):
        key = (bus, machine_id(gid))
        if key in modelled:
            return None
        if key not in sources:
            return "no machine model record in the DYR data"
        return f"its machine record {', '.join(sources[key])} is not supported (left out)"

    return net


def _refuse_second_source(records, taken: frozenset) -> None:
    """CaseError for a machine model record (GENCLS, GENROU, ...) of a generator that a
    converter or compensator record already models (`taken`: their (bus, id)): PSS/E
    gives a generator one source model.  Without it the machine record read as one for
    no generator in service (the converter had taken it)."""
    from stabctl.io.dyr import has_machine_model, maps_machine

    first: dict = {}
    for r in sorted(records, key=lambda r: not has_machine_model(r)):  # REGCA1 before REECA1
        if (r.bus, r.id) in taken and not maps_machine(r):
            first.setdefault((r.bus, r.id), r)
    for r in records:
        if maps_machine(r) and (r.bus, r.id) in first:
            other = first[(r.bus, r.id)]
            raise CaseError(
                f"{r.label()}: second source model for this generator (first at "
                f"{other.where()}, {other.model}): PSS/E models a generator by one machine, "
                "converter or compensator model"
            )


def _dynamic_tables(
    raw: RawData, records, conventions
) -> tuple[dict, list[str], list[str], tuple, dict, dict[int, str]]:
    """PST dynamic matrices from the DYR records (the converter table ``ibr_con`` from
    the converter records, :mod:`stabctl.io.dyr_converters`; the machines, numbered 1, 2,
    ... in RAW order, the other generators), the unsupported records (as text), the
    generators whose REGCA1 plant or DERA1 was left out (``bus B 'ID'``), the records
    read with a value other than the file's, each table's row origins (table name ->
    `stabctl.io.provenance.Origin` per row) and the machines' RAW IDs (machine number ->
    ID, `stabctl.case.Case.machine_ids`)."""
    from stabctl.io.dyr import SVC_DYR, compensator_rows, dyr_origin, dyr_tables, machine_id
    from stabctl.io.dyr_converters import CONVERTER_RECORDS, converter_rows, shares

    gens = [{**g.as_dyr(), "sbase": raw.base_mva} for g in raw.generators]
    conv = converter_rows(records, gens, raw.line, conventions)
    svc = compensator_rows(records, gens)
    keys = [(int(g["bus"]), machine_id(g["id"])) for g in gens]
    lost = {(r.bus, r.id) for r, _ in conv.skipped if r.model in ("REGCA1", "DERA1")} & set(keys)
    plant_buses = {bus for bus, _ in conv.replaced | svc.replaced}
    for g in gens:  # a machine sharing its bus with a plant: its own share (PSS/E's)
        if int(g["bus"]) in plant_buses:
            g["pfrac"], g["qfrac"] = shares(gens, g)
    _refuse_second_source(records, conv.replaced | svc.replaced)
    gens = [g for g, key in zip(gens, keys) if key not in conv.replaced | lost | svc.replaced]
    for number, g in enumerate(gens, 1):
        g["number"] = number
    records = [r for r in records if r.model not in CONVERTER_RECORDS and r.model not in SVC_DYR]
    tables = dyr_tables(
        records,
        gens,
        on_unsupported="skip",
        conventions=conventions,
        strays=(*conv.skipped, *svc.skipped),
    )
    mats: dict = {"ibr_con": np.array(conv.rows, float)} if conv.rows else {}
    if svc.rows:
        mats["svc_con"] = np.array(svc.rows, float)
    for key in ("mac_con", "exc_con", "pss_con", "tg_con"):
        if getattr(tables, key) is not None:
            mats[key] = getattr(tables, key)
    skipped = sorted(
        [*conv.skipped, *svc.skipped, *zip(tables.unsupported, tables.why)],
        key=lambda item: (item[0].file, item[0].line),
    )
    origins = {table: [dyr_origin(r) for r in recs] for table, recs in tables.records.items()}
    origins["ibr_con"] = list(conv.origins)
    return (
        mats,
        [_dyr_text(r, why) for r, why in skipped],
        [f"bus {b} '{i}'" for b, i in sorted(lost)],
        tables.changed,
        origins,
        {int(g["number"]): machine_id(g["id"]) for g in gens},
    )


def _dyr_text(rec, why: str) -> str:
    """``file:line MODEL at bus B 'ID': why`` of a record left out."""
    at = f" at bus {rec.bus}" if rec.bus else ""
    return f"{rec.file}:{rec.line} {rec.model}{at} '{rec.id}': {why}"


def _report(unsupported: list[str], mode: str, where: str) -> None:
    if not unsupported:
        return
    listing = "; ".join(unsupported)
    if mode == "error":
        how = advice("on_unsupported='skip' leaves", "--skip-unsupported leaves")
        raise CaseError(
            f"{where}: {len(unsupported)} unsupported record(s) ({how} them out): {listing}"
        )
    warnings.warn(
        f"{where}: left out {len(unsupported)} unsupported record(s): {listing}",
        UserWarning,
        stacklevel=4,
    )


def _files(raw_path, dyr_path) -> str:
    return Path(raw_path).name + ("" if dyr_path is None else f" + {Path(dyr_path).name}")


def _source(raw_path, dyr_path) -> str:
    return f"PSS/E data {_files(raw_path, dyr_path)}, imported by stabctl.io.psse.load_psse"
