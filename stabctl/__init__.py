"""stabctl: transient-stability control of power systems with distributed energy storage.

Per unit on the system base unless a name says otherwise; time in s; angles in rad;
frequencies in Hz.

The names in ``__all__`` are the public entry points; they are imported on first use, so
``import stabctl`` is cheap and has no side effects (no environment variables set, no file
touched, nothing compiled).  Layers, lowest first: :mod:`stabctl.case`, :mod:`stabctl.io`
and :mod:`stabctl.network`, :mod:`stabctl.models`, :mod:`stabctl.storage`,
:mod:`stabctl.dynamics`, :mod:`stabctl.stability` and :mod:`stabctl.smallsignal`,
:mod:`stabctl.placement` and :mod:`stabctl.estimation`, :mod:`stabctl.studies`,
:mod:`stabctl.cli` (the import-linter contract in ``pyproject.toml``).
"""

from __future__ import annotations

import importlib

__version__ = "0.1.0"

_EXPORTS = {
    "Case": "stabctl.case",
    "load_case": "stabctl.io",
    "list_cases": "stabctl.io",
    "solve_powerflow": "stabctl.network.powerflow",
    "Simulator": "stabctl.dynamics.driver",
    "SimulationResult": "stabctl.dynamics.results",
    "Fault": "stabctl.dynamics.events",
    "LineTrip": "stabctl.dynamics.events",
    "GeneratorTrip": "stabctl.dynamics.events",
    "ConverterTrip": "stabctl.dynamics.events",
    "LoadStep": "stabctl.dynamics.events",
    "MotorSwitch": "stabctl.dynamics.events",
    "Playback": "stabctl.dynamics.events",
    "fault_with_clearing": "stabctl.dynamics.events",
    "coi_speed": "stabctl.dynamics.coi",
    "StorageDevice": "stabctl.storage",
    "StorageFleet": "stabctl.storage",
    "BangBangCOI": "stabctl.storage",
    "uniform_fleet": "stabctl.storage",
    "LineFault": "stabctl.stability.cct",
    "critical_clearing_time": "stabctl.stability.cct",
    "linearise": "stabctl.smallsignal.linearise",
    "modal_analysis": "stabctl.smallsignal.modal",
    "OMIB": "stabctl.smib.omib",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    """Import a public name from its module on first use (PEP 562)."""
    try:
        module = _EXPORTS[name]
    except KeyError:
        raise AttributeError(f"module 'stabctl' has no attribute {name!r}") from None
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
