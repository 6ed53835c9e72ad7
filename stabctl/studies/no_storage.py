"""The paper's Cases 1 and 2 without storage: verdict, who separates, a clearing-time scan
(Case 1) and the overview figure (speeds, angles from the COI, bus voltages).

Used by ``sims/case1_kundur_no_storage.py`` and ``sims/case2_miniwecc_no_storage.py``.
Expected (PSTess): Case 1, 21 cycles: area 1 (machines 1 and 2) loses synchronism with
area 2; Case 2, 6 cycles: machine 14 (Colstrip, bus 32) separates alone (the paper names
machines 13 and 14).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.events import fault_with_clearing
from stabctl.io import load_case
from stabctl.outdir import output_directory
from stabctl.plotting.figures import simulation_overview
from stabctl.studies.cases import CASE1, CASE2, PaperCase


def _run(pc: PaperCase, cycles: float, t_end: float, **kw):
    case = load_case(pc.case)
    sim = Simulator(case)
    ev = fault_with_clearing(case, pc.bus, pc.far_bus, pc.fault.t_fault, cycles)
    return case, sim, sim.run([ev], t_end=t_end, **kw)


def _verdict(case, res) -> str:
    if res.stable:
        return f"  verdict: stable (largest angle from the COI {res.max_angle_from_coi:.3f} rad)"
    return (
        f"  verdict: loss of synchronism at t = {res.t_separation:.4f} s; machine(s) "
        f"{', '.join(case.machine_name(m) for m in res.separated)} separate from the rest"
    )


def _cct_scan(pc: PaperCase, cycles: int, t_end: float) -> list[str]:
    """Verdicts for clearing after 6 ... `cycles` cycles and the CCT bracket they give."""
    lines = ["  clearing-time scan (cycles: verdict):"]
    last_stable = first_unstable = None
    for cyc in range(6, cycles + 1):
        case, _, r = _run(pc, cyc, t_end, stop_at_separation=True)
        lines.append(
            f"    {cyc:3d}: "
            + (
                "stable"
                if r.stable
                else f"machine(s) {', '.join(case.machine_name(m) for m in r.separated)} separate "
                f"at {r.t_separation:.3f} s"
            )
        )
        if r.stable:
            last_stable = cyc
        elif first_unstable is None:
            first_unstable = cyc
    if last_stable is not None and first_unstable is not None:
        lines.append(
            f"  critical clearing time between {last_stable} and {first_unstable} "
            f"cycles ({last_stable / case.freq_hz:.3f}-"
            f"{first_unstable / case.freq_hz:.3f} s)"
        )
    return lines


def _excursions(case, res) -> list[str]:
    """How far each machine strays from the COI of the machines that did not separate."""
    keep = [j for j, m in enumerate(res.machines) if int(m) not in res.separated]
    w = res.inertia[keep]
    coi = res.angle[:, keep] @ w / w.sum()
    dev = np.abs(res.angle - coi[:, None]).max(axis=0)
    order = np.argsort(dev)[::-1][:4]
    j13 = res.machine(13)
    return [
        "  largest excursions from the COI of the remaining machines: "
        + ", ".join(f"{case.machine_name(res.machines[j])} {dev[j]:.2f} rad" for j in order),
        f"  {case.machine_name(13)}: at most {dev[j13]:.2f} rad from that COI -> "
        + ("stays in synchronism" if dev[j13] < np.pi else "separates too"),
    ]


def no_storage_report(pc: PaperCase, out_dir: Path, t_end: float = 5.0) -> list[str]:
    """Run a paper case without storage at its paper clearing; write
    ``out_dir/<case1|case2>_no_storage.png``.

    Parameters
    ----------
    pc : PaperCase
        :data:`~stabctl.studies.cases.CASE1` or :data:`~stabctl.studies.cases.CASE2`.
    out_dir : Path
        Directory of the figure (created).
    t_end : float
        End time of the run (s).

    Returns
    -------
    list of str
        The printed lines: the run, its verdict, and for Case 1 a clearing-time scan, for
        Case 2 the largest excursions from the COI.
    """
    cycles = pc.cycles["paper"]
    case, _, res = _run(pc, cycles, t_end)
    key = pc.label.lower().replace(" ", "")
    lines = [
        f"{pc.label} (no storage): {case.name}, {cycles}-cycle fault at bus {pc.bus} on "
        f"line {pc.bus}-{pc.far_bus} at {pc.fault.t_fault} s, line tripped; {t_end:g} s",
        _verdict(case, res),
    ]
    lines += _cct_scan(pc, int(cycles), t_end) if pc is CASE1 else _excursions(case, res)
    path = out_dir / f"{key}_no_storage.png"
    with output_directory(out_dir):  # removed again if the figure is not written
        simulation_overview(
            res,
            path,
            title=f"{pc.label}, no storage: {case.name}, {cycles}-cycle "
            f"fault at bus {pc.bus}, line {pc.bus}-{pc.far_bus} tripped",
            case=case,
        )
    return lines + [f"  wrote {path}"]


__all__ = ["no_storage_report", "CASE1", "CASE2"]
