"""Step convergence of the critical clearing time under both model conventions.

The CCT of a fault searched (`stabctl.stability.cct.critical_clearing_time`, 1 ms bisection) at a
series of steps h under "ieee" and "pstess" conventions (docs/conventions.md): under ieee
successive halvings converge as a second-order method should (once the step resolves
the fastest time constant); under pstess PSTess's smpexc limiter makes the model itself
depend on the step.  Used by `stabctl paper` (section 9) and docs/conventions.md.
"""

from __future__ import annotations

from stabctl.io import load_case
from stabctl.stability.cct import LineFault, critical_clearing_time
from stabctl.dynamics.model import CONVENTIONS
from stabctl.dynamics.simulation import Simulator
from stabctl.studies.cases import PAPER_CASES

#: Steps of the convergence table (s): 10, 5, 2.5, 1 and 0.5 ms.
STEPS = (0.01, 0.005, 0.0025, 0.001, 0.0005)
#: The paper's Case-1 (Kundur) and Case-2 (miniWECC) faults.
PAPER_FAULTS = {name: pc.fault for name, pc in PAPER_CASES.items()}


def cct_versus_step(case_name: str, fault: LineFault, steps=STEPS,
                    conventions=CONVENTIONS, tol: float = 1e-3, progress=None) -> dict:
    """{conventions: {"default_h": s, "rows": [(h s, CCT s, n runs), ...]}} for each step
    and the convention's default step.  Raises as `critical_clearing_time`."""
    case = load_case(case_name)
    out = {}
    for conv in conventions:
        sim = Simulator(case, conventions=conv)
        rows = []
        for h in sorted({*steps, sim.default_h}, reverse=True):
            if progress:
                progress(f"convergence: {case_name}, {conv}, h = {1000 * h:g} ms")
            r = critical_clearing_time(sim, fault, h=h, tol=tol, error_check=False)
            rows.append((h, r.cct_s, r.n_simulations))
        out[conv] = {"default_h": sim.default_h, "rows": rows}
    return out


def markdown_table(case_name: str, table: dict, freq_hz: float) -> list[str]:
    """Rows h | CCT per conventions (ms, cycles) | change from the previous step (ms);
    the default step of each convention marked."""
    convs = list(table)
    head = "| step h (ms) | " + " | ".join(
        f"{c} CCT ms (cycles) | {c} change ms" for c in convs) + " |"
    lines = [head, "|---|" + "---|---|" * len(convs)]
    by_h = {c: {h: cct for h, cct, _ in table[c]["rows"]} for c in convs}
    steps = sorted({h for c in convs for h in by_h[c]}, reverse=True)
    prev = {c: None for c in convs}
    for h in steps:
        cells = []
        for c in convs:
            cct = by_h[c].get(h)
            if cct is None:
                cells += ["-", "-"]
                continue
            mark = " (default)" if abs(h - table[c]["default_h"]) < 1e-12 else ""
            change = "" if prev[c] is None else f"{1000 * (cct - prev[c]):+.0f}"
            cells += [f"{1000 * cct:.0f} ({cct * freq_hz:.2f}){mark}", change]
            prev[c] = cct
        lines.append(f"| {1000 * h:g} | " + " | ".join(cells) + " |")
    return lines
