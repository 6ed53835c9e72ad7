"""The definition of a verified plan, by independent simulation (tests/placement/)."""

from stabctl.dynamics.driver import Simulator
from stabctl.storage.control import BangBangCOI
from stabctl.storage.devices import StorageDevice, StorageFleet


def stable_when_cleared(case, fault, t_clear, rows) -> bool:
    """The fault cleared t_clear after its start, simulated 5 s on `case` (a `Case`) with
    the devices of `rows` (dicts of bus, machine, mw; the paper's law) or without storage
    (rows empty): stable?"""
    fleet = (
        StorageFleet(
            tuple(StorageDevice(r["bus"], r["machine"], r["mw"]) for r in rows), BangBangCOI()
        )
        if rows
        else None
    )
    return (
        Simulator(case)
        .run(fault.events(t_clear), fault.t_fault + 5.0, storage=fleet, stop_at_separation=True)
        .stable
    )
