"""The case model: one power system's static and dynamic data (:class:`Case`) and its
tables, plus the built-in cases shipped in ``stabctl/case/data`` (read them with
:func:`stabctl.io.load_case`).  The lowest layer of stabctl: it imports nothing above it.
"""

from stabctl.case.system import (
    CASE_DIR,
    PQ,
    PV,
    START_LIMIT_TOL,
    SWING,
    TABLES,
    BranchTable,
    BusTable,
    Case,
    ConverterTable,
    ExciterTable,
    GovernorTable,
    InjectionTable,
    LoadTable,
    MachineTable,
    PssTable,
    Table,
    beyond,
)

__all__ = [
    "CASE_DIR",
    "PQ",
    "PV",
    "START_LIMIT_TOL",
    "SWING",
    "TABLES",
    "BranchTable",
    "BusTable",
    "Case",
    "ConverterTable",
    "ExciterTable",
    "GovernorTable",
    "InjectionTable",
    "LoadTable",
    "MachineTable",
    "PssTable",
    "Table",
    "beyond",
]
