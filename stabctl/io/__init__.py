"""Readers and writers of case data: PST/PSTess (``.m``, evaluated JSON, stabctl JSON),
PSS/E RAW and DYR, and ANDES's cases (cross-validation).

:func:`load_case` is the one entry point for a case by name or path.
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path

from stabctl.case import CASE_DIR, Case
from stabctl.errors import CaseError, InputError, WrongTypeError
from stabctl.io import pst as pstio
from stabctl.io.inputs import input_file

__all__ = ["load_case", "list_cases"]


def list_cases() -> dict[str, str]:
    """The built-in cases.

    Returns
    -------
    dict[str, str]
        Case name (as :func:`load_case` takes it) -> one-line description, read from the
        packaged JSON files, sorted by name.
    """
    out = {}
    for path in sorted(CASE_DIR.glob("*.json")):
        out[path.stem] = pstio.read_case_header(path).get("description", "")
    return out


def load_case(name_or_path: str | Path) -> Case:
    """Load a case: a built-in by name (``"kundur"``, ``"miniwecc"``) or a file path.

    Parameters
    ----------
    name_or_path : str or pathlib.Path
        A built-in case name (see :func:`list_cases`), or the path of a file: ``.json`` in
        stabctl's own format or PSTess's evaluated-matrix JSON (told apart by content), or
        a PST ``.m`` data file of literal matrices.  A text with a path separator or a
        ``.json``/``.m`` suffix is always taken as a path, another text as a path when it
        names no built-in but an existing file (refused as a file of another kind).

    Returns
    -------
    Case
        The validated case (units as in :class:`~stabctl.case.Case`).

    Raises
    ------
    CaseError
        The name is neither a built-in nor an existing file, the path is not a regular
        file of bounded size (`stabctl.io.inputs.input_file`), or the file is malformed.
    WrongTypeError
        `name_or_path` neither a str nor a path (bytes, a number).

    Warns
    -----
    UserWarning
        Every machine of the case is an infinite bus (H = 0,
        :meth:`~stabctl.case.Case.none_can_swing`): no run of it can lose stability.

    Examples
    --------
    >>> from stabctl.io import load_case
    >>> case = load_case("kundur")
    >>> case.n_bus, len(case.machines), case.base_mva, case.freq_hz
    (13, 4, 100.0, 60.0)
    """
    if not isinstance(name_or_path, (str, os.PathLike)):  # bytes: "should be a str object"
        raise WrongTypeError(
            f"load_case(name_or_path): a case name or a path (str or pathlib.Path), got "
            f"{name_or_path!r}"
        )
    case = _read_case(name_or_path)
    why = case.none_can_swing()
    if why:
        warnings.warn(f"case '{name_or_path}': {why}", UserWarning, stacklevel=2)
    return case


def _is_file(path: Path) -> bool:
    """Whether `path` is a file; False where it cannot be one (round 45: a name of 5000
    characters raised "File name too long" from the built-in cases' folder)."""
    try:
        return path.is_file()
    except OSError:
        return False


def _read_case(name_or_path: str | Path) -> Case:
    """`load_case`'s case, read."""
    text = str(name_or_path)
    builtin = CASE_DIR / f"{text}.json"
    if "/" not in text and "\\" not in text and not text.endswith((".json", ".m")):
        if _is_file(builtin):
            return pstio.read_case_json(builtin)
        if not _is_file(Path(text)):  # a file of another kind is named as such (read_any)
            shown = text if len(text) <= 60 else f"{text[:40]}... ({len(text)} characters)"
            raise CaseError(
                f"unknown case '{shown}': built-ins are {', '.join(list_cases()) or 'none'}"
            )
    path = Path(name_or_path)
    if not path.exists():
        if path.is_symlink():  # a link that is broken or loops: "not found" misled
            try:
                path.stat()
            except FileNotFoundError:
                raise CaseError(
                    f"case file not found: {path} is a symbolic link to "
                    f"{os.readlink(path)}, which does not exist"
                ) from None
            except OSError as exc:
                raise CaseError(f"case file {path}: {exc.strerror}") from None
        raise CaseError(f"case file not found: {path}")
    try:
        input_file(path, "case file")
    except InputError as exc:
        raise CaseError(str(exc)) from None
    return pstio.read_any(path)
