"""Eigenvalue study of a case (`stabctl eig`): linearise, analyse, and report the
electromechanical modes as Markdown with figures, or every mode as JSON.

Files: `<out>/eig_<case>[_nopss].md` with `eig_<case>[_nopss]_{eigs,shapes,pf}.png`, all
written to temporary files first and renamed only when every one is complete.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from stabctl.case import Case, PssTable
from stabctl.dynamics.coi import machine_inertia
from stabctl.errors import InputError, WrongTypeError, counted
from stabctl.outdir import output_directory
from stabctl.parallel import atomic_writes
from stabctl.smallsignal.linearise import linearise
from stabctl.smallsignal.modal import (
    COMMON_SHARE,
    ModalAnalysis,
    ModeSensitivity,
    modal_analysis,
    mode_sensitivity,
)

N_FIGURE_MODES = 6  # EM modes drawn in the compass and bar charts


@dataclass(frozen=True, eq=False)
class EigStudy:
    """A linearised case and its modes: `sys` (control.StateSpace), `ma`, `sens` (ESD
    power inputs to relative speeds), `no_pss`, timings in s (`t_linearise`, `t_analyse`)."""

    case: Case
    no_pss: bool
    sys: Any  # control.StateSpace (untyped)
    ma: ModalAnalysis
    sens: ModeSensitivity
    t_linearise: float
    t_analyse: float

    @property
    def stem(self) -> str:
        return f"eig_{self.case.name}" + ("_nopss" if self.no_pss else "")


def eig_study(
    case: Case,
    no_pss: bool = False,
    n_areas: int | None = None,
    conventions: str = "ieee",
    q_limits: bool = True,
    limits: str = "auto",
) -> EigStudy:
    """Linearise `case` (with its pss_con emptied if no_pss) under the model conventions,
    from a power flow with or without PV Q limits, limits active at the operating point
    taken as `linearise`'s `limits` says, and analyse its modes."""
    if no_pss:
        case = case.replace(pss=PssTable.empty())
    t0 = time.perf_counter()
    sys = linearise(case, conventions=conventions, q_limits=q_limits, limits=limits)
    t1 = time.perf_counter()
    ma = modal_analysis(sys, inertia=machine_inertia(case)[case.machines.H > 0], n_areas=n_areas)
    sens = mode_sensitivity(sys, ma)
    return EigStudy(case, no_pss, sys, ma, sens, t1 - t0, time.perf_counter() - t1)


def best_esd(st: EigStudy, i: int) -> tuple[str, float]:
    """ESD input with the largest residue magnitude in mode i (over the relative-speed
    outputs) and that magnitude (pu speed per pu power per s)."""
    r = np.abs(st.sens.residues[i]).max(axis=0)
    j = int(np.argmax(r))
    return st.sens.inputs[j].removeprefix("P_esd_"), float(r[j])


def study_json(st: EigStudy) -> dict:
    """Every mode (`ModalAnalysis.mode_record`) plus the model summary, JSON-ready."""
    ma = st.ma
    modes = [ma.mode_record(i) for i in range(ma.eigenvalues.size)]
    for i in ma.electromechanical:
        bus, r = best_esd(st, i)
        modes[i].update(best_esd_bus=bus, best_esd_residue=r)
    return {
        "case": st.case.name,
        "pss": not st.no_pss,
        "n_states": st.sys.nstates,
        "inputs": list(st.sys.input_labels),
        "reference_mode": ma.reference_mode,
        # one per island of machines (round 49: an islanded case's second was "other")
        "reference_modes": list(ma.reference_modes),
        # the machine numbers the modes' machine lists hold, named with their buses
        "machine_names": {str(int(k)): st.case.machine_name(int(k)) for k in ma.machines},
        "areas": _areas(ma),
        "damping_statistics": ma.damping_statistics(),
        # every mode of positive real part, whatever its band (round 41: an exciter's
        # unstable 3.7 Hz modes were in no output but --json's full list)
        "small_signal_stable": not ma.unstable_modes().size,
        "unstable_modes": [int(i) for i in ma.unstable_modes()],
        "electromechanical_modes": [int(i) for i in ma.electromechanical],
        "time_linearise_s": st.t_linearise,
        "time_analyse_s": st.t_analyse,
        "modes": modes,
    }


def _areas(ma: ModalAnalysis) -> dict:
    return {
        f"area {a + 1}": [int(k) for k in ma.machines[ma.areas == a]] for a in np.unique(ma.areas)
    }


def figure_modes(ma: ModalAnalysis) -> list[int]:
    """Up to N_FIGURE_MODES electromechanical modes, by frequency: the inter-area ones
    first, then the least-damped local ones."""
    em = ma.electromechanical
    order = np.lexsort((ma.damping[em], ma.kind[em] != "inter-area"))
    pick = em[order[:N_FIGURE_MODES]]
    return [int(i) for i in pick[np.argsort(ma.freq_hz[pick])]]


def write_report(
    st: EigStudy, out_dir, stem: str | None = None, command: str | None = None
) -> Path:
    """Write the Markdown report and its three figures into out_dir atomically (a
    directory created for them is removed again if the writing is interrupted or fails,
    `stabctl.outdir.output_directory`); returns the report path.  `stem`: the files' name
    before ``.md`` and ``_eigs.png``, ... (None: `EigStudy.stem`); `command`: the command
    the report says made it (None: ``stabctl eig CASE [--no-pss] --report``)."""
    from stabctl.plotting.figures import eigenvalue_plot, mode_shape_compass, participation_bars

    stem = st.stem if stem is None else _file_stem(stem)
    names = {k: f"{stem}_{k}.png" for k in ("eigs", "shapes", "pf")}
    title = f"{st.case.name}" + (" without PSS" if st.no_pss else "")
    modes = figure_modes(st.ma)
    with output_directory(out_dir) as out:
        md = out / f"{stem}.md"
        text = report_markdown(st, names, bool(modes), command)
        figures = [
            (out / names["eigs"], lambda p: eigenvalue_plot(st.ma, p, title)),
            (out / names["shapes"], lambda p: mode_shape_compass(st.ma, modes, p)),
            (out / names["pf"], lambda p: participation_bars(st.ma, modes, p)),
        ]
        atomic_writes(
            [
                *(figures if modes else figures[:1]),
                (md, lambda p: Path(p).write_text(text, "utf-8")),
            ]
        )
    return md


def _file_stem(stem) -> str:
    """`write_report`'s stem when it names files in its folder: InputError for an empty
    one ('.md' was written), a path ('../../escape' wrote outside the folder) or a dot
    name; WrongTypeError for another type than a text."""
    if not isinstance(stem, str):
        raise WrongTypeError(f"write_report(stem): a file name is needed, got {stem!r}")
    if not stem.strip() or stem.startswith(".") or Path(stem).name != stem or "\\" in stem:
        raise InputError(
            f"write_report(stem): {stem!r} is no file name (a name without a folder, not "
            "empty, not starting with '.': the report is STEM.md in the output folder)"
        )
    return stem


def _nothing_against(kind: str, quadrature: bool = False) -> str:
    """The report's word for a mode without machines swinging against its largest (one
    with machines in quadrature: none, they are named)."""
    if kind == "common":
        return "none, all in phase"
    return "none" if quadrature else "others, each < 0.2"


def _machines(numbers, most: int = 8, none: str = "-", name=None) -> str:
    """'G1 (bus 1), G2 (bus 2), ...' (at most `most` machines; `name` the case's
    `machine_name`, default 'G<k>'), `none` for none."""
    named = name or (lambda k: f"G{k}")
    text = ", ".join(named(int(k)) for k in numbers[:most]) or none
    return text + (" ..." if len(numbers) > most else "")


def report_markdown(
    st: EigStudy, figures: dict, with_mode_figures: bool, command: str | None = None
) -> str:
    """The report text (electromechanical-mode table, areas, statistics, figures);
    `command` as `write_report`'s."""
    ma, sys = st.ma, st.sys
    named = st.case.machine_name
    ref = ma.reference_values()
    ref = f"lambda = {ref}" if ref else "none: an infinite bus (H = 0) holds the angles"
    stats = ma.damping_statistics()
    em = ma.electromechanical
    n_inter = int(np.sum(ma.kind[em] == "inter-area"))
    n_common = int(np.sum(ma.kind[em] == "common"))
    common = f", {n_common} common (every machine in phase)" if n_common else ""
    lines = [
        f"# Small-signal modes: {st.case.name}" + (" without PSS" if st.no_pss else ""),
        "",
        "Generated by `"
        + (command or f"stabctl eig {st.case.name}{' --no-pss' if st.no_pss else ''} --report")
        + "` (stabctl.smallsignal.linearise, stabctl.smallsignal.modal; method in "
        "docs/modal.md).",
        "",
        "- Linearised at the power-flow point by central differences of the simulator's own "
        "equations (PSTess svm_mgen's perturbation 1e-4, shown converged against 1e-5 in "
        "stabctl's reports/eig_validation.md, 'Perturbation error'"
        + (", for the case with its PSS" if st.no_pss else "")
        + f"): {sys.nstates} states, "
        f"{sys.ninputs} inputs, {sys.noutputs} outputs (timings: `stabctl eig` prints them; "
        "the report holds no run-dependent values).",
        f"- Angle-reference mode (common rotation of all rotor angles, excluded from damping "
        f"statistics): {ref}.",
        f"- {em.size} electromechanical modes ({n_inter} inter-area{common}, "
        f"{em.size - n_inter - n_common} local): "
        f"0.1-2.5 Hz, rotor angle/speed the largest participating state group.",
    ]
    if "electromechanical" in stats:
        s = stats["electromechanical"]
        lines.append(
            f"- Least-damped electromechanical mode: {s['freq_hz']:.3f} Hz, "
            f"damping ratio {s['damping_ratio']:.4f}"
            + (" (unstable)" if s["damping_ratio"] < 0 else "")
            + "."
        )
    bad = ma.unstable_modes()
    lines.append(
        "- Small-signal stable: every mode's real part is negative."
        if not bad.size
        else f"- **Small-signal unstable**: {counted(bad.size, 'mode')} with a positive real "
        "part: "
        + "; ".join(
            f"mode {i}, {ma.freq_hz[i]:.3f} Hz, {ma.eigenvalues[i].real:+.4g} 1/s "
            f"({ma.kind[i] if i in em else ma.dominant_states(int(i), 1)[0][0]})"
            for i in bad
        )
        + "."
    )
    outside = ma.rotor_modes_above_band()
    if outside.size:
        lines.append(
            "- Rotor modes above 2.5 Hz (a machine's own swing, left out above): "
            + "; ".join(
                f"{ma.freq_hz[i]:.3f} Hz, damping ratio {ma.damping[i]:.4f} "
                f"({', '.join(named(k) for k in ma.dominant_machines(int(i)))})"
                for i in outside
            )
            + "."
        )
    lines += [
        "",
        "## Coherent areas",
        "",
        "Slow coherency on the rigid-body direction and the slowest electromechanical "
        "mode shapes (docs/modal.md); a mode is inter-area when it moves the areas' "
        "centres of inertia against each other (area-momentum fraction eta > 0.5) at "
        "1 Hz or below (above it a swing of neighbours across an area boundary is local: "
        "Kundur 12.1 puts local plant modes at 0.8-2 Hz).",
        "",
    ]
    lines += [
        f"- {area}: " + _machines(ks, most=len(ks), name=named) for area, ks in _areas(ma).items()
    ]
    lines += [
        "",
        "## Electromechanical modes",
        "",
        "| # | eigenvalue (1/s) | f (Hz) | damping | kind | eta | areas | dominant machines | "
        "swing together | against | best ESD bus (abs residue) |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for i in em[np.argsort(ma.freq_hz[em])]:
        lam = ma.eigenvalues[i]
        g1, g2 = ma.groups(i)
        quad = ma.quadrature(i)
        bus, r = best_esd(st, i)
        lines.append(
            f"| {i} | {lam.real:.4f} ± j{lam.imag:.4f} | {ma.freq_hz[i]:.4f} | "
            f"{ma.damping[i]:.4f} | {ma.kind[i]} | {ma.eta[i]:.2f} | {ma.area_sides(i)} | "
            f"{_machines(ma.dominant_machines(i), name=named)} | "
            f"{_machines(g1, name=named)} | "
            f"{_machines(g2, none=_nothing_against(ma.kind[i], bool(quad)), name=named)}"
            + (f" (in quadrature: {_machines(quad, name=named)})" if quad else "")
            + " | "
            f"{bus} ({r:.2e}) |"
        )
    lines += [
        "",
        "#: the mode's number among all the model's modes (one per conjugate pair, by "
        "frequency), the `mode` of `stabctl eig --json`. Areas: for an inter-area mode, the "
        "areas whose momentum (M times the speed shape, summed over the area) is at least "
        "0.2 of the largest area's, in phase with it vs against it. "
        "Dominant machines: participation at least half the largest machine's "
        "(states and controls of a machine summed). Groups: speed mode-shape components "
        "of at least 0.2 of the largest, within 60 degrees of it (together) or of its "
        "opposite (against), the others 'in quadrature', on neither side; "
        "'others, each < 0.2' when the machines swinging against it each move less "
        "(a single machine against the system, or a heavy area against a light one); "
        "'none, all in phase' for a common mode, the centre of inertia itself swinging "
        f"(the centre of inertia's share of the mode's kinetic energy above {COMMON_SHARE:g}: "
        "a mode of the system's "
        "frequency). "
        "Best ESD bus: the ESD power input with the largest residue to the "
        "relative speeds.",
        "",
        "## Figures",
        "",
        f"![eigenvalues]({figures['eigs']})",
        "",
    ]
    if with_mode_figures:
        lines += [
            f"Mode shapes and participations of {min(N_FIGURE_MODES, em.size)} "
            "electromechanical modes (the inter-area ones, then the least-damped local "
            "ones):",
            "",
            f"![mode shapes]({figures['shapes']})",
            "",
            f"![participation]({figures['pf']})",
            "",
        ]
    return "\n".join(lines)
