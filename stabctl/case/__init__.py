"""The case model: one power system's static and dynamic data (:class:`Case`) and its
tables, plus the built-in cases shipped in ``stabctl/case/data`` (read them with
:func:`stabctl.io.load_case`).  It sits above the model declarations (:mod:`stabctl.models`), whose
parameter declarations its dynamic-data tables are built from.
"""

from stabctl.case.system import (
    CASE_DIR,
    PQ,
    PV,
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
    MotorTable,
    PssTable,
    RegulationTable,
    ShaftTable,
    SvcTable,
    SwitchedShuntTable,
    Table,
    require_case,
)

__all__ = [
    "CASE_DIR",
    "PQ",
    "PV",
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
    "MotorTable",
    "PssTable",
    "RegulationTable",
    "ShaftTable",
    "SvcTable",
    "SwitchedShuntTable",
    "Table",
    "require_case",
]
