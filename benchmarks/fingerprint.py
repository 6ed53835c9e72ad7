"""Fingerprints of simulation results, for refactors that must leave results bit-identical
(not a test).

Runs a set of simulations and linearisations covering the machine models and every
converter component (PVD1, ESD1 and its state of charge, REGCA1 with REECA1 / REECB1,
REPCA1, the WECC wind models WTDTA1 / WTDS / WTARA1 / WTPTA1 / WTTQA1, the PLL1, the DG
protections DGPRCT1 / DGPRCTExt), the multi-mass shaft, the induction motor and the
switched shunts, and prints one sha256 per run of its result arrays
(time grid, speeds, angles, powers, field voltages, bus voltages, converter P and Q; the
state matrix A of a linearisation), then one over all of them.  Run it before and after a
change that must not change results and compare the lines.

Cases: the paper's Kundur and miniWECC (PST data, built in) with the paper's faults,
and ANDES 2.0's converter cases (read from the installed ``andes`` package's case
folder, imported by `stabctl.io.andes_case.import_andes`) with a 6-cycle fault through
j1e-3 pu, 5 ms step, 3 s.

Run: python benchmarks/fingerprint.py  (or with PYTHONPATH set to a worktree)
"""

from __future__ import annotations

import hashlib
import warnings

import numpy as np

from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.events import Fault, fault_with_clearing
from stabctl.errors import SimulationError
from stabctl.io import load_case
from stabctl.smallsignal.linearise import linearise
from stabctl.studies.cases import CASE1, CASE2

#: ANDES cases with converters (and three with a shaft, a motor, switched shunts): (case
#: file, fault bus, step s, linearise too)
ANDES_CASES = (
    ("kundur/kundur_reg.xlsx", 7, 0.005, True),
    ("kundur/kundur_wtdta1.xlsx", 7, 0.005, True),
    ("kundur/kundur_wtds.xlsx", 7, 0.005, False),
    ("ieee14/ieee14_solar.xlsx", 9, 0.005, True),
    ("ieee14/ieee14_wt3.xlsx", 9, 0.005, True),
    ("ieee14/ieee14_wt3n.xlsx", 9, 0.001, False),
    ("ieee14/ieee14_pvd1.xlsx", 9, 0.005, True),
    ("ieee14/ieee14_esd1.xlsx", 9, 0.005, True),
    ("ieee14/ieee14_dgprct1.xlsx", 4, 0.005, False),
    ("ieee14/ieee14_dgprctext.xlsx", 4, 0.005, False),
    ("ieee14/ieee14_regcp1.xlsx", 9, 0.005, False),
    ("ieee14/ieee14_reecb1.json", 9, 0.005, False),
    # the other models with states of their own: the multi-mass shaft, the induction
    # motor, the switched shunts
    ("ieee14/ieee14_shaft5.json", 9, 0.0004, True),
    ("kundur/kundur_motor.xlsx", 7, 0.005, False),
    ("ieee14/ieee14_shuntsw.xlsx", 9, 0.005, False),
)

#: the result arrays hashed (a `Result`'s fields)
FIELDS = ("t", "speed", "angle", "pelect", "pmech", "efd", "vmag", "vang", "ibr_p", "ibr_q")


def digest(*arrays) -> str:
    """sha256 (hex, first 16 digits) of the bytes of `arrays` (None skipped), each as a
    contiguous float64 / complex array with its shape."""
    h = hashlib.sha256()
    for a in arrays:
        if a is None:
            continue
        a = np.ascontiguousarray(a)
        h.update(str(a.shape).encode())
        h.update(a.tobytes())
    return h.hexdigest()[:16]


def result_digest(res) -> str:
    """`digest` of a `Result`'s arrays (`FIELDS`)."""
    return digest(*(getattr(res, name) for name in FIELDS))


def run_digest(sim, events, h, method) -> str:
    """`result_digest` of a 3 s run, or the digest of its error's message where it stops."""
    try:
        return result_digest(sim.run(events, 3.0, h=h, method=method))
    except SimulationError as err:
        return "stopped " + digest(np.frombuffer(str(err).encode(), np.uint8))


def runs():
    """(label, digest) of every run."""
    for pc in (CASE1, CASE2):
        case = load_case(pc.case)
        sim = Simulator(case)
        cyc = pc.cycles["paper"]
        fault = [fault_with_clearing(case, pc.bus, pc.far_bus, pc.fault.t_fault, cyc)]
        res = sim.run(fault, t_end=5.0, h=1 / 240)
        yield f"{pc.case} fault heun", result_digest(res)
        res = sim.run(fault, t_end=3.0, h=0.005, method="trapezoid")
        yield f"{pc.case} fault trapezoid", result_digest(res)
        yield f"{pc.case} linearise", digest(linearise(case).A)
    import andes

    from stabctl.io.andes_case import import_andes

    for name, bus, h, lin in ANDES_CASES:
        case = import_andes(andes.get_case(name), conventions="andes", on_unsupported="skip")
        sim = Simulator(case, q_limits=False)
        fault = [Fault(bus, 1.0, 1.1, x=1e-3)]
        for method in ("heun", "trapezoid"):
            yield f"{name} fault {method}", run_digest(sim, fault, h, method)
        if lin:
            A = linearise(sim).A
            yield f"{name} linearise", digest(A)


def main():
    warnings.simplefilter("ignore")
    total = hashlib.sha256()
    for label, d in runs():
        print(f"{d}  {label}", flush=True)
        total.update(d.encode())
    print(f"{total.hexdigest()[:16]}  all")


if __name__ == "__main__":
    main()
