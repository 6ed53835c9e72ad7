"""A stabctl case from PSS/E data: a RAW power-flow file and optionally a DYR file.

The RAW part (:mod:`stabctl.io.psse_raw`) gives the PST ``bus``, ``line`` and ``load_con``
matrices and the in-service generators; the DYR part (:mod:`stabctl.io.dyr`) gives
``mac_con``, ``exc_con``, ``pss_con`` and ``tg_con`` for those generators (machine ``k``
is the k-th in-service generator of the RAW file); where several machines share a bus,
each takes the share PG_k / sum(PG) of the bus generation and QG_k / sum(QG) of its Q
(``mac_con`` columns 22, 23).

Records that stabctl cannot represent are collected from both files and either refused
together (``on_unsupported="error"``: one :class:`~stabctl.errors.CaseError` listing every
one as ``file:line record``) or left out with one warning listing them (``"skip"``).
"""

from __future__ import annotations

import warnings
from pathlib import Path

from stabctl.case import Case
from stabctl.errors import CaseError
from stabctl.io.psse_raw import RawData, read_raw
from stabctl.io.pst import case_from_matrices

__all__ = ["load_psse", "import_psse"]

_MODES = ("error", "skip")


def load_psse(
    raw_path: str | Path,
    dyr_path: str | Path | None = None,
    on_unsupported: str = "error",
    loads: str = "impedance",
    conventions: str = "pst",
) -> Case:
    """Build a :class:`~stabctl.case.Case` from a PSS/E RAW (v32-34) and a DYR file.

    Args:
        raw_path: the ``.raw`` power-flow file.
        dyr_path: the ``.dyr`` dynamic data file, or None for a static case (buses,
            branches, loads only: a power flow, no dynamic run).
        on_unsupported: ``"error"`` refuses records stabctl cannot represent, ``"skip"``
            leaves them out and warns (:class:`UserWarning`) with the list.
        loads: ``"impedance"`` makes all loads constant impedance in the dynamic run,
            ``"raw"`` keeps the PSS/E load composition (see :mod:`stabctl.io.psse_raw`).
        conventions: ``"pst"`` maps the DYR models onto PST's as they are (machines with
            speed effects, EXDC2 limits scaled by the terminal voltage); ``"andes"``
            follows ANDES 2.0's reading for like-for-like comparisons (no speed effects
            in GENROU/GENSAL, EXDC2 limits constant; :func:`stabctl.io.dyr.dyr_tables`).

    Returns:
        the case, named after the RAW file, described by the RAW title lines; units as
        :mod:`stabctl.case` (pu on SBASE, machine data pu on MBASE).

    Raises:
        CaseError: a malformed record (``file:line record: what``), unsupported records
            with ``on_unsupported="error"`` (every one listed), a bad mode, or data the
            case model refuses.

    Source: PSS/E POM "Power Flow Raw Data File Contents" and "Dynamics Data" (PSS/E
    Model Library for the DYR records); PST manual section 3.22 for ``mac_con``.
    """
    return import_psse(raw_path, dyr_path, on_unsupported, loads, conventions)[0]


def import_psse(
    raw_path: str | Path,
    dyr_path: str | Path | None = None,
    on_unsupported: str = "error",
    loads: str = "impedance",
    conventions: str = "pst",
) -> tuple[Case, tuple[str, ...]]:
    """:func:`load_psse` that also returns the records left out, each as
    ``"file:line record"`` (empty unless ``on_unsupported="skip"``). Same arguments and
    errors."""
    if on_unsupported not in _MODES:
        raise CaseError(f"on_unsupported must be 'error' or 'skip', got {on_unsupported!r}")
    raw = read_raw(raw_path, loads=loads)
    mats = raw.matrices()
    unsupported = [str(s) for s in raw.unsupported]
    if dyr_path is not None:
        dyn, dyr_unsupported = _dynamic_tables(raw, dyr_path, conventions)
        mats.update(dyn)
        unsupported += dyr_unsupported
    _report(unsupported, on_unsupported, _files(raw_path, dyr_path))
    case = case_from_matrices(
        mats, raw.name, source=_source(raw_path, dyr_path), description=raw.title
    )
    return case, tuple(unsupported)


def _dynamic_tables(raw: RawData, dyr_path, conventions) -> tuple[dict, list[str]]:
    """PST dynamic matrices from the DYR file and its unsupported records (as text)."""
    from stabctl.io.dyr import dyr_tables, read_dyr

    gens = [{**g.as_dyr(), "sbase": raw.base_mva} for g in raw.generators]
    tables = dyr_tables(read_dyr(dyr_path), gens, on_unsupported="skip", conventions=conventions)
    mats = {}
    for key in ("mac_con", "exc_con", "pss_con", "tg_con"):
        if getattr(tables, key) is not None:
            mats[key] = getattr(tables, key)
    return mats, [_dyr_text(r, why) for r, why in zip(tables.unsupported, tables.why)]


def _dyr_text(rec, why: str) -> str:
    """``file:line MODEL at bus B 'ID': why`` of a record left out."""
    at = f" at bus {rec.bus}" if rec.bus else ""
    return f"{rec.file}:{rec.line} {rec.model}{at} '{rec.id}': {why}"


def _report(unsupported: list[str], mode: str, where: str) -> None:
    if not unsupported:
        return
    listing = "; ".join(unsupported)
    if mode == "error":
        raise CaseError(
            f"{where}: {len(unsupported)} unsupported record(s) (use "
            f"on_unsupported='skip' / --skip-unsupported to leave them out): "
            f"{listing}"
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
