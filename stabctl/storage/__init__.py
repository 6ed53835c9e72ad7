"""Energy-storage devices and their control laws (paper Sections 3 and 5)."""

from stabctl.storage.control import BangBangCOI, ControlLaw, ExternalCommands, LinearFeedback
from stabctl.storage.devices import StorageDevice, StorageFleet, hv_bus, uniform_fleet

__all__ = [
    "BangBangCOI",
    "ControlLaw",
    "ExternalCommands",
    "LinearFeedback",
    "StorageDevice",
    "StorageFleet",
    "hv_bus",
    "uniform_fleet",
]
