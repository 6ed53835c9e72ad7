"""Figures for the reports (matplotlib, non-interactive Agg backend).

Each function draws one figure from library results and saves it as PNG; none computes
model quantities of its own.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import control as ct
import matplotlib.pyplot as plt
import numpy as np

from stabctl.smallsignal.modal import SIGNIFICANT
from stabctl.stability.cct import run_end_lost

#: the savefig metadata of each format that would otherwise stamp the time of writing
#: (the PDF's /CreationDate, the SVG's <dc:date>, PostScript's %%CreationDate): left out,
#: so that one figure written twice gives the same bytes; matplotlib's own stamp
#: (Software, Producer, Creator: its version) stays
_UNDATED = {
    "pdf": {"CreationDate": None},
    "svg": {"Date": None},
    "ps": {"CreationDate": None},
    "eps": {"CreationDate": None},
}

#: the salt of the SVG element ids (matplotlib's ``svg.hashsalt``; unset, each write
#: draws a random one, and every clip path and glyph id differs from write to write)
_SVG_SALT = "stabctl"


def save_figure(fig, path) -> None:
    """Save a figure as the reports do (tight layout, 110 dpi, format from the suffix) and
    close it.  The one figure-saving helper of stabctl.

    The file is reproducible: the same figure written twice, at any time and whatever
    ``SOURCE_DATE_EPOCH`` says, gives the same bytes (PNG, PDF, SVG, PS): no date of
    writing is stored (:data:`_UNDATED`) and the SVG ids are salted with a constant
    (:data:`_SVG_SALT`).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    path : str or Path
        The image file; its suffix chooses the format (matplotlib's ``savefig.format``,
        PNG, without one).
    """
    fmt = Path(path).suffix.lower().lstrip(".") or matplotlib.rcParams["savefig.format"]
    fig.tight_layout()
    with matplotlib.rc_context({"svg.hashsalt": _SVG_SALT}):
        fig.savefig(  # legends placed outside the axes: tight bounding box
            path, dpi=110, bbox_inches="tight", metadata=_UNDATED.get(fmt)
        )
    plt.close(fig)


def omib_phase_plane(system, runs: dict, path: Path) -> None:
    """Phase plane (delta, d(delta)/dt): streamlines of the post-fault system (python-control
    phase_plane_plot), the stability boundary through delta_u, and one run per fault."""
    fig, ax = plt.subplots(figsize=(7, 5))
    f = system.rhs("post")
    ct.phase_plane_plot(
        lambda t, x: np.array(f(t, x)),
        [-1.0, 4.0, -12.0, 12.0],
        1.0,
        ax=ax,
        plot_separatrices=False,
        plot_equilpoints=False,
        plot_streamplot={"color": "0.8"},
    )
    d = np.linspace(-1.0, system.delta_u, 600)
    w = system.separatrix(d)
    ax.plot(d, w, "k--", lw=1.5, label="stability boundary")
    ax.plot(d, -w, "k--", lw=1.5)
    for cyc, run in runs.items():
        ax.plot(
            run.delta,
            run.omega,
            lw=1.8,
            label=f"{cyc} cycles ({'stable' if run.stable else 'unstable'})",
        )
        ax.plot(run.delta_cl, run.omega_cl, "o", color=ax.lines[-1].get_color())
    ax.plot([system.delta_s, system.delta_u], [0, 0], "kx")
    ax.set(
        xlim=(-1, 4),
        ylim=(-12, 12),
        xlabel="delta (rad)",
        ylabel="d(delta)/dt (rad/s)",
        title="OMIB phase plane (paper Figs. 4-5)",
    )
    ax.legend(loc="lower left", fontsize=8)
    save_figure(fig, path)


def omib_equal_area(system, run, path: Path) -> None:
    """Power-angle curves with the accelerating and available decelerating areas."""
    fig, ax = plt.subplots(figsize=(7, 4))
    d = np.linspace(0, np.pi, 400)
    ax.plot(d, system.pe(d, "post"), label="Pe pre/post-fault")
    ax.plot(d, system.pe(d, "fault"), label="Pe fault-on")
    ax.axhline(system.Pm, color="k", lw=1, label="Pm")
    d1 = np.linspace(system.delta0, run.delta_cl, 100)
    ax.fill_between(d1, system.pe(d1, "fault"), system.Pm, alpha=0.4, label="A1 (accelerating)")
    d2 = np.linspace(run.delta_cl, system.delta_u, 100)
    ax.fill_between(d2, system.Pm, system.pe(d2, "post"), alpha=0.4, label="A2 available")
    ax.axvline(system.critical_clearing_angle(), color="r", ls=":", label="critical clearing angle")
    ax.set(
        xlabel="delta (rad)",
        ylabel="power (pu)",
        title=f"Equal-area criterion, clearing at {run.t_clear * 60:.0f} cycles",
    )
    ax.legend(fontsize=8)
    save_figure(fig, path)


def feedback_phase_plane(system, runs: dict, path: Path) -> None:
    """Phase-plane comparison of the feedback laws (paper Fig. 7) and speed versus time."""
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.5))
    d = np.linspace(-1.0, system.delta_u, 400)
    ax1.plot(d, system.separatrix(d), "k--", lw=1, label="stability boundary without control")
    ax1.plot(d, -system.separatrix(d), "k--", lw=1)
    for name, run in runs.items():
        ax1.plot(run.delta, run.omega, lw=1.3, label=name)
        ax2.plot(run.t, run.omega, lw=1.1, label=name)
    ax1.set(
        xlim=(-1, 3.5),
        ylim=(-12, 12),
        xlabel="delta (rad)",
        ylabel="d(delta)/dt (rad/s)",
        title="15-cycle fault: feedback laws (paper Fig. 7)",
    )
    ax2.set(xlim=(0, 6), ylim=(-12, 12), xlabel="t (s)", ylabel="d(delta)/dt (rad/s)")
    ax1.legend(fontsize=7, loc="lower left")
    save_figure(fig, path)


def min_time_figures(system, x_release, sols: dict, states_path: Path, costates_path: Path) -> None:
    """States with the minimum-time pulse versus no storage (Fig. 10) and co-states (Fig. 11)."""
    from stabctl.smib.optimal import time_to_zero_speed

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.5))
    T0, sol0 = time_to_zero_speed(system, x_release, 0.0)
    t0 = np.linspace(0, T0, 200)
    x0 = sol0.sol(t0)
    ax1.plot(t0, x0[1], "k", label="no storage")
    ax2.plot(x0[0], x0[1], "k", label="no storage")
    for pc, s in sols.items():
        ax1.plot(s.t, s.x2, label=f"P_Cmax = {pc} pu (T = {s.T:.4f} s)")
        ax2.plot(s.x1, s.x2, label=f"P_Cmax = {pc} pu")
    ax1.set(
        xlabel="time after release (s)",
        ylabel="x2 = d(delta)/dt (rad/s)",
        title="Minimum-time control: speed (paper Fig. 10)",
    )
    ax2.set(xlabel="x1 = delta (rad)", ylabel="x2 (rad/s)", title="phase plane")
    ax1.legend(fontsize=8)
    save_figure(fig, states_path)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.5))
    for pc, s in sols.items():
        ax1.plot(s.t, s.l1, label=f"P_Cmax = {pc} pu")
        ax2.plot(s.t, s.l2, label=f"P_Cmax = {pc} pu")
    ax1.set(xlabel="time after release (s)", ylabel="lambda1", title="co-state lambda1 (Fig. 11)")
    ax2.axhline(0, color="k", lw=0.8)
    ax2.set(
        xlabel="time after release (s)",
        ylabel="lambda2",
        title="co-state lambda2 > 0: P_C = P_Cmax throughout",
    )
    ax1.legend(fontsize=8)
    save_figure(fig, costates_path)


def simulation_overview(
    result,
    path,
    title: str | None = None,
    max_labels: int = 10,
    base_mva: float = 100.0,
    *,
    case,
) -> None:
    """Panels versus time for a `stabctl.dynamics.results.SimulationResult`: machine speeds (pu),
    rotor angles relative to the centre of inertia (rad, the result's own COI with H*MVA
    weights), bus voltage magnitudes (pu) and, when the run had storage, the device powers
    (MW on `base_mva`, + absorbs).  Loss of synchronism, if any, is marked by a vertical
    line.  Machines keep one colour in every panel; with more than `max_labels` machines
    each has a distinct colour and line style and only the separated ones are drawn thick
    and named (legend and a label at the end of the trace), the legend saying how many
    others there are; with more than `max_labels` buses the three whose voltage falls
    lowest are named, the others drawn thin grey.  Machines are named by number and bus,
    ``G14 (bus 3)``, from the run's `case` (`Case.machine_name`)."""
    t = result.t
    storage = result.pesd is not None and result.devices.size > 0
    fig, axes = plt.subplots(
        4 if storage else 3, 1, figsize=(9, 11.5 if storage else 9), sharex=True
    )
    rel = result.relative_angle  # against each machine's island's COI, as the verdict
    lost = set(int(m) for m in result.separated)
    mstyles = _machine_styles(result.machines, case, lost, max_labels)
    series = (
        (axes[0], result.speed, "G", result.machines, "speed (pu)"),
        (axes[1], rel, "G", result.machines, "angle - COI angle (rad)"),
        (axes[2], result.vmag, "B", result.buses, "bus voltage (pu)"),
    )
    for ax, data, prefix, numbers, ylabel in series:
        many = data.shape[1] > max_labels
        for j, n in enumerate(numbers):
            if prefix == "G":
                st = mstyles[j]
                ax.plot(t, data[:, j], **st)
                if many and st["label"]:
                    _end_label(ax, t, data[:, j], st["label"], st["color"])
            elif not many:
                ax.plot(t, data[:, j], lw=1.2, label=f"B{int(n)}")
        if prefix == "B" and many:
            _deepest_buses(ax, t, data, numbers)
        quiet = sum(1 for st in mstyles if not st["label"])
        if prefix == "G" and quiet:
            ax.plot([], [], color="0.5", lw=0.7, label=_others_label(quiet, len(numbers)))
        if result.t_separation is not None:
            ax.axvline(result.t_separation, color="r", ls=":", lw=1.2, label="loss of synchronism")
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, ncol=min(5, data.shape[1] + 1) if not many else 1, loc="best")
    if storage:
        ax = axes[3]
        info = result.meta.get("storage", [])
        active = [i for i, d in enumerate(info) if d.get("switchings", 1) > 0]
        colour = {int(n): st["color"] for n, st in zip(result.machines, mstyles)}
        for i in range(result.devices.size):
            d = info[i] if i < len(info) else {}
            named = i in active[:max_labels]
            mach = d.get("machine")
            ax.plot(
                t,
                result.pesd[:, i] * base_mva,
                lw=1.0,
                color=colour.get(int(mach)) if mach is not None and not many else None,
                label=(
                    f"ESD {int(result.devices[i])} at bus {d.get('bus')} (G{mach})"
                    if named and d
                    else None
                ),
            )
        ax.set_ylabel("ESD power (MW, + absorbs)")
        ax.grid(True, alpha=0.3)
        idle = result.devices.size - len(active)
        ax.set_title(
            f"{result.devices.size} storage devices, {len(active)} switched"
            + (f", {idle} stayed idle" if idle else ""),
            fontsize=9,
        )
        if active:
            ax.legend(fontsize=7, ncol=2, loc="best")
    axes[-1].set_xlabel("t (s)")
    if result.t_separation is None and result.de_energised_s is not None:
        verdict = f"de-energised at {result.de_energised_s:g} s: no machine left in service"
    else:
        verdict = (
            "stable"
            if result.stable
            else f"loss of synchronism at {result.t_separation:.3f} s, machine(s) "
            + ", ".join(case.machine_name(m) for m in result.separated)
        )
    head = title or str(result.meta.get("case", "simulation"))
    axes[0].set_title(f"{head}\n{verdict}", fontsize=9)
    save_figure(fig, Path(path))


def _end_label(ax, t, y, text: str, color) -> None:
    """Name a trace at its last point, in its colour."""
    ax.annotate(
        text,
        (t[-1], y[-1]),
        fontsize=8,
        color=color,
        xytext=(2, 0),
        textcoords="offset points",
        va="center",
    )


def _deepest_buses(ax, t, vmag, numbers, n: int = 3) -> None:
    """Bus voltages of a large case: every bus thin and grey, the n buses whose voltage
    falls lowest over the run (the faulted bus and its neighbours) in colour, named in the
    legend and at the end of their trace."""
    deepest = np.argsort(vmag.min(axis=0))[:n]
    for j in range(vmag.shape[1]):
        if j not in deepest:
            ax.plot(t, vmag[:, j], color="0.6", lw=0.5)
    ax.plot([], [], color="0.6", lw=0.5, label=f"other {vmag.shape[1] - n} buses (thin)")
    for j in deepest:
        name = f"B{int(numbers[j])}"
        line = ax.plot(t, vmag[:, j], lw=1.3, label=f"{name} (min {vmag[:, j].min():.2f} pu)")
        _end_label(ax, t, vmag[:, j], name, line[0].get_color())


def _others_label(quiet: int, total: int) -> str:
    """The legend entry of the machines drawn thin and not named: how many, and that
    they are the ones that did not separate (each in its own colour and line style)."""
    return (
        f"{'other ' if quiet < total else ''}{quiet} machine{'s' if quiet != 1 else ''} "
        "not separated (thin, one colour each)"
    )


def _machine_styles(numbers, case, highlight=(), max_labels: int = 10) -> list[dict]:
    """Plot style per machine: up to max_labels machines each a tab10 colour and a legend
    entry; more machines each a distinct colour and line style (thin, unlabelled) except
    the `highlight`ed ones (thick, black/red/..., labelled).  Labels name the machines
    by number and bus (`Case.machine_name` of their `case`)."""
    numbers = [int(n) for n in numbers]
    if len(numbers) <= max_labels:
        return [
            {
                "color": plt.get_cmap("tab10")(j % 10),
                "lw": 1.2,
                "ls": "-",
                "label": case.machine_name(n),
                "zorder": 2,
            }
            for j, n in enumerate(numbers)
        ]
    cmap, styles = plt.get_cmap("tab20"), ("-", "--", ":")
    loud = ("k", "tab:red", "tab:blue", "tab:green", "tab:purple")
    shown = [n for n in numbers if n in set(int(h) for h in highlight)]
    out = []
    for j, n in enumerate(numbers):
        if n in shown:
            out.append(
                {
                    "color": loud[shown.index(n) % len(loud)],
                    "lw": 2.2,
                    "ls": "-",
                    "label": case.machine_name(n),
                    "zorder": 3,
                }
            )
        else:
            out.append(
                {
                    "color": cmap(j % 20),
                    "lw": 0.7,
                    "ls": styles[(j // 20) % 3],
                    "label": None,
                    "zorder": 2,
                    "alpha": 0.8,
                }
            )
    return out


def _speed_panel(ax, res, styles, label: str) -> None:
    """Machine speeds of one run with the given styles; highlighted machines named at the
    end of their trace, and in the legend said "not separated" where they did not
    separate in this run (thick is the highlight, not the verdict); a legend (with how
    many others when some are unlabelled)."""
    separated = {int(m) for m in res.separated}
    for j, st in enumerate(styles):
        shown = st
        if st["label"] and len(styles) > 10 and int(res.machines[j]) not in separated:
            shown = {**st, "label": f"{st['label']}, not separated"}
        ax.plot(res.t, res.speed[:, j], **shown)
        if st["label"] and len(styles) > 10:
            _end_label(ax, res.t, res.speed[:, j], st["label"], st["color"])
    if len(styles) > 10:  # room for the names at the end of the traces
        ax.set_xlim(res.t[0], res.t[-1] + 0.1 * (res.t[-1] - res.t[0]))
    quiet = sum(1 for st in styles if not st["label"])
    if quiet:
        ax.plot([], [], color="0.5", lw=0.7, label=_others_label(quiet, len(styles)))
    if res.t_separation is not None:
        ax.axvline(res.t_separation, color="r", ls=":", lw=1.0, label="loss of synchronism")
    ax.set(xlabel="t (s)", ylabel="speed (pu)", title=f"machine speeds, {label}")
    ax.legend(fontsize=7, ncol=2 if len(styles) <= 10 else 1, loc="best")


def storage_case_figure(without, with_, path: Path, title: str, *, case, highlight=()) -> None:
    """Speeds without and with storage control, and the device powers (paper Figs. 14-19).

    Every machine keeps its colour in both speed panels; with many machines the separated
    ones (in either run) and `highlight` are drawn thick and named, the others thin in
    distinct colours and line styles.  Device powers use their machine's colour.  Machines
    are named by number and bus from the runs' `case` (`Case.machine_name`)."""
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.6))
    marked = [int(m) for m in (*without.separated, *with_.separated, *highlight)]
    styles = _machine_styles(without.machines, case, dict.fromkeys(marked))
    colour = {int(n): st["color"] for n, st in zip(without.machines, styles)}
    for ax, res, label in ((axes[0], without, "without control"), (axes[1], with_, "with control")):
        _speed_panel(ax, res, styles, label)
    active = [i for i, d in enumerate(with_.meta["storage"]) if d["switchings"] > 0]
    many = len(styles) > 10
    for i in active[:12]:
        d = with_.meta["storage"][i]
        named = not many or int(d["machine"]) in marked
        axes[2].plot(
            with_.t,
            with_.pesd[:, i] * 100,
            lw=1,
            color=colour.get(int(d["machine"])) if named else None,
            label=f"ESD at bus {d['bus']} (G{d['machine']})",
        )
    axes[2].set(
        xlabel="t (s)",
        ylabel="ESD power (MW, + absorbs)",
        title="device powers"
        + (f" ({min(len(active), 12)} of {len(active)} that switched)" if len(active) > 12 else ""),
    )
    if active:
        axes[2].legend(fontsize=7)
    for ax in axes[:2]:
        ax.set_ylim(
            min(a.speed.min() for a in (without, with_)) - 0.002,
            max(a.speed.max() for a in (without, with_)) + 0.002,
        )
    fig.suptitle(title)
    save_figure(fig, path)


def cct_versus_rating(
    results: dict,
    ratings,
    path: Path,
    paper_row: dict | None = None,
    paper_label: str = "paper Table 4",
) -> None:
    """CCT increase (%) versus ESD rating (% of machine MVA) per case (Table 4), with the
    paper's printed row (rating % -> increase %) as its own series when given."""
    fig, ax = plt.subplots(figsize=(6.5, 4.2))
    for key, res in results.items():
        base = res[None]["cct_s"]
        gains = [0] + [100 * (res[p]["cct_s"] / base - 1) for p in ratings]
        ax.plot([0, *ratings], gains, "o-", label=f"{key.replace('case', 'Case ')} (stabctl)")
    if paper_row:
        x = sorted(paper_row)
        ax.plot(x, [paper_row[p] for p in x], "ks--", mfc="none", ms=7, label=paper_label)
    ax.set(
        xlabel="ESD rating (% of machine MVA)",
        ylabel="CCT increase (%)",
        title="Table 4: CCT gain versus storage rating",
    )
    ax.legend(fontsize=8)
    save_figure(fig, path)


# -- modal analysis (stabctl.smallsignal.modal) ------------------------------------------

_KIND_STYLE = {
    "inter-area": ("tab:red", "s"),
    "local": ("tab:blue", "o"),
    "common": ("tab:green", "^"),
    "other": ("0.6", "."),
    "angle reference": ("k", "x"),
}


def eigenvalue_plot(ma, path, title: str, dampings=(0.03, 0.05, 0.1, 0.2)) -> None:
    """Eigenvalues of a `stabctl.smallsignal.modal.ModalAnalysis`: the whole spectrum (left) and the
    electromechanical region (right, frequency in Hz) with lines of constant damping ratio
    zeta (sigma = -zeta omega_n, f = omega_n sqrt(1 - zeta^2) / 2 pi); markers by kind."""
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 5))
    lam = ma.eigenvalues
    for kind, (color, marker) in _KIND_STYLE.items():
        sel = ma.kind == kind
        if sel.any():
            z = lam[sel]
            ax1.plot(z.real, z.imag / (2 * np.pi), marker, color=color, ls="", label=kind)
            ax2.plot(z.real, z.imag / (2 * np.pi), marker, color=color, ls="", label=kind, ms=7)
    fmax = 2.6
    sig_min = min(-0.5, 1.2 * float(np.min(lam[ma.electromechanical].real, initial=-1.0)))
    for zeta in dampings:
        wn = np.linspace(0, 2 * np.pi * fmax / np.sqrt(1 - zeta**2), 50)
        ax2.plot(-zeta * wn, wn * np.sqrt(1 - zeta**2) / (2 * np.pi), "k:", lw=0.8)
        f_end = min(fmax, -sig_min * np.sqrt(1 - zeta**2) / (2 * np.pi * zeta))
        ax2.annotate(
            f"{zeta:.0%}",
            (-zeta * 2 * np.pi * f_end / np.sqrt(1 - zeta**2), f_end),
            fontsize=7,
            ha="right",
        )
    for ax in (ax1, ax2):
        ax.axvline(0, color="k", lw=0.8)
        ax.grid(True, alpha=0.3)
        ax.set(xlabel="real part (1/s)", ylabel="frequency (Hz)")
    ax1.set_xscale("symlog", linthresh=1.0)
    ax1.set_title("all modes (one per conjugate pair)")
    ax2.set(
        xlim=(sig_min, 0.25 * abs(sig_min)),
        ylim=(0, fmax),
        title="electromechanical region, dotted: constant damping ratio",
    )
    ax2.legend(fontsize=8, loc="upper left")
    fig.suptitle(title)
    save_figure(fig, Path(path))


def _mode_title(ma, i) -> str:
    return f"{ma.freq_hz[i]:.3f} Hz, zeta {ma.damping[i]:.3f}, {ma.kind[i]}"


def _grid(n: int):
    cols = min(3, n)
    rows = (n + cols - 1) // cols
    return rows, cols


def _area_legend(fig, ma) -> None:
    """One legend for the figure: the colour of each coherent area and its machines."""
    from matplotlib.patches import Patch

    colors = plt.get_cmap("tab10")
    handles = [
        Patch(color=colors(a % 10), label=f"area {a + 1} ({n} machine{'s' if n > 1 else ''})")
        for a, n in zip(*np.unique(ma.areas, return_counts=True))
    ]
    fig.legend(
        handles=handles,
        loc="upper center",
        bbox_to_anchor=(0.5, 0.0),
        ncol=len(handles),
        fontsize=8,
        title="colour = coherent area",
        title_fontsize=8,
    )


def mode_shape_compass(ma, modes, path, max_labels: int = 6) -> None:
    """Compass plots of the speed mode shapes (normalised, largest = 1 at 0 deg) of the
    given modes, one arrow per machine coloured by coherent area (legend below); the
    largest machines are labelled inside the circle, clear of the angle ticks."""
    rows, cols = _grid(len(modes))
    fig = plt.figure(figsize=(4.2 * cols, 4.2 * rows))
    colors = plt.get_cmap("tab10")
    for n, i in enumerate(modes):
        ax = fig.add_subplot(rows, cols, n + 1, projection="polar")
        s = ma.speed_shape[:, i]
        for k in np.argsort(np.abs(s)):
            ax.annotate(
                "",
                xy=(np.angle(s[k]), abs(s[k])),
                xytext=(0, 0),
                arrowprops=dict(arrowstyle="->", color=colors(ma.areas[k] % 10), lw=1.2),
            )
        for k in np.argsort(-np.abs(s))[:max_labels]:
            if abs(s[k]) >= SIGNIFICANT:
                ax.text(
                    np.angle(s[k]),
                    abs(s[k]) + 0.12,
                    f"G{int(ma.machines[k])}",
                    fontsize=7,
                    ha="center",
                    va="center",
                )
        ax.set_ylim(0, 1.35)
        ax.set_yticklabels([])
        ax.set_xticks(np.radians([0, 90, 180, 270]), ["0°", "90°", "180°", "270°"], fontsize=8)
        ax.set_title(_mode_title(ma, i), fontsize=9)
    fig.suptitle(f"speed mode shapes (machines of at least {SIGNIFICANT} of the largest named)")
    _area_legend(fig, ma)
    save_figure(fig, Path(path))


def participation_bars(ma, modes, path, n_bars: int = 12) -> None:
    """Bar charts of the participation of each machine (its states and controls summed)
    in the given modes, largest n_bars machines per mode, coloured by area (legend below)."""
    rows, cols = _grid(len(modes))
    fig, axes = plt.subplots(rows, cols, figsize=(4.6 * cols, 3.4 * rows), squeeze=False)
    colors = plt.get_cmap("tab10")
    for ax, i in zip(axes.flat, modes):
        p = ma.machine_participation(i)
        k = np.argsort(-p)[:n_bars]
        ax.bar(range(k.size), p[k], color=[colors(ma.areas[j] % 10) for j in k])
        ax.set_xticks(
            range(k.size), [f"G{int(ma.machines[j])}" for j in k], fontsize=7, rotation=90
        )
        ax.set(ylabel="participation", title=_mode_title(ma, i))
        ax.title.set_fontsize(9)
    for ax in axes.flat[len(modes) :]:
        ax.set_visible(False)
    fig.suptitle("participation factors per machine (each mode sums to 1)")
    _area_legend(fig, ma)
    save_figure(fig, Path(path))


#: a screening of at most this many buses has every one labelled and, when it covers under
#: SUBSET_ZOOM of the case's buses, the map zoomed to them
LABEL_ALL, SUBSET_ZOOM = 40, 0.25


def screening_map(case, rows, path: Path) -> None:
    """Network drawn with `stabctl.plotting.layout.spectral_layout`, each bus coloured by the CCT
    of a fault there (circles) and each branch fault by its CCT at its branch's middle
    (squares; round 42: branch faults were left off the map, their N-1 insecure verdicts
    and islanding trips shown nowhere), on one colour scale; open markers: CCT above the
    search limit (robust); red crosses: N-1 insecure (CCT 0); grey crosses: failed search;
    a magenta ring: a CCT not converged in the run's end (`stabctl.stability.cct.
    run_end_lost`); a legend below the map (inside, it could cover a marker); bus numbers
    on the most critical buses.  A screening of some buses only
    (``stabctl screen --buses``) shows the others as small grey points, labels every
    screened bus when they are at most LABEL_ALL, zooms to the screened faults when they
    are under SUBSET_ZOOM of the buses, and says "k of n buses" in its title.

    Parameters
    ----------
    case : Case
        The case screened.
    rows : list of dict
        The screening's rows (`stabctl.stability.screening`): ``bus``, ``far_bus`` (None:
        a bus fault), ``verdict``, ``cct_s`` (s), ``t_max_s`` (s, robust rows).
    path : Path
        The figure's file.
    """
    from matplotlib.colors import Normalize

    from stabctl.plotting.layout import spectral_layout

    xy = spectral_layout(case)
    fig, ax = plt.subplots(figsize=(8, 6.5))
    f, t = case.bus_indices(case.branches.from_bus), case.bus_indices(case.branches.to_bus)
    for a, b in zip(f, t):
        ax.plot(xy[[a, b], 0], xy[[a, b], 1], color="0.8", lw=0.7, zorder=1)
    bus_rows = [r for r in rows if r["far_bus"] is None]
    branch_rows = [r for r in rows if r["far_bus"] is not None]
    idx = case.bus_indices([r["bus"] for r in bus_rows])
    ends = [case.bus_indices([r["bus"], r["far_bus"]]) for r in branch_rows]
    mid = np.array([xy[e].mean(axis=0) for e in ends]).reshape(-1, 2)
    subset = len(idx) < case.n_bus
    if subset:
        rest = np.setdiff1d(np.arange(case.n_bus), idx)
        ax.scatter(xy[rest, 0], xy[rest, 1], c="0.6", s=4, zorder=1, label="not screened")
    ccts = [r["cct_s"] for r in rows if r.get("verdict") == "cct"] or [0.0]
    norm = Normalize(min(ccts) * case.freq_hz, max(ccts) * case.freq_hz)
    sc = _verdict_markers(ax, case, xy[idx], bus_rows, norm, "o", 40, "")
    _verdict_markers(ax, case, mid, branch_rows, norm, "s", 22, " (branch fault)")
    _not_converged_rings(ax, np.vstack([xy[idx], mid]), bus_rows + branch_rows)
    handles = ax.get_legend_handles_labels()[0]
    if handles:  # below the axes: inside, it could cover a marker (round 45)
        ax.legend(
            loc="upper center", bbox_to_anchor=(0.5, -0.02), fontsize=8, ncol=1 + (len(handles) > 3)
        )
    cct = np.array([r["cct_s"] if r.get("verdict") == "cct" else np.inf for r in bus_rows])
    labelled = len(idx) if len(idx) <= LABEL_ALL else 10
    screened = np.vstack([xy[idx], mid])
    zoom = subset and len(screened) and len(screened) < SUBSET_ZOOM * case.n_bus
    shown = screened if zoom else xy
    order = np.argsort(cct, kind="stable")[:labelled]
    for at, names in _label_groups(xy[idx[order]], case.buses.number[idx[order]], shown):
        ax.annotate(names, at, fontsize=7, xytext=(3, 3), textcoords="offset points")
    fig.colorbar(sc, ax=ax, label="CCT of the fault (cycles)")
    where = f"each of {len(idx)} of {case.n_bus} buses" if subset else "each bus"
    title = f"{case.name}: critical clearing time of a fault at {where}"
    if branch_rows:
        title += f"\nand of {len(branch_rows)} branch fault(s) (squares, mid-branch)"
    ax.set(title=title, xticks=[], yticks=[])
    if zoom:
        lo, hi = screened.min(axis=0), screened.max(axis=0)
        pad = 0.15 * np.maximum(hi - lo, 0.05 * np.ptp(xy, axis=0))
        ax.set(xlim=(lo[0] - pad[0], hi[0] + pad[0]), ylim=(lo[1] - pad[1], hi[1] + pad[1]))
    save_figure(fig, path)


def _not_converged_rings(ax, at, rows) -> None:
    """A magenta ring around each marker of `rows` (positions `at`, (n, 2)) whose CCT is
    not converged in the run's end: cleared at it, a longer run loses synchronism (round
    45: such rows were drawn as any CCT)."""
    lost = np.array([run_end_lost(r.get("run_end_check")) for r in rows], bool)
    if lost.any():
        ax.scatter(
            at[lost, 0], at[lost, 1], s=160, facecolors="none", edgecolors="magenta",
            linewidths=1.2, zorder=4,
            label="CCT not converged in the run's end (a longer run loses synchronism)",
        )  # fmt: skip


def _verdict_markers(ax, case, at, rows, norm, marker, size, what):
    """The screening map's markers of `rows` at positions `at` (n, 2): CCTs coloured on
    `norm` (cycles), robust open, N-1 insecure red crosses, failed grey crosses, each
    kind in the legend once with `what` after it; returns the CCTs' scatter."""
    verdicts = np.array([r.get("verdict") for r in rows], dtype=object)
    kinds = {"cct": verdicts == "cct", "above": verdicts == "above t_max"}
    kinds["insecure"] = verdicts == "N-1 insecure"
    kinds["failed"] = ~(kinds["cct"] | kinds["above"] | kinds["insecure"])
    ok = kinds["cct"]
    cct = np.array([r["cct_s"] * case.freq_hz for r, k in zip(rows, ok) if k])
    sc = ax.scatter(
        at[ok, 0], at[ok, 1], c=cct, cmap="RdYlGn", norm=norm, s=size, zorder=2,
        marker=marker, edgecolors="k", linewidths=0.3,
    )  # fmt: skip
    if kinds["above"].any():
        t_max = max(r["t_max_s"] for r, k in zip(rows, kinds["above"]) if k)
        ax.scatter(
            at[kinds["above"], 0], at[kinds["above"], 1], facecolors="none",
            edgecolors="darkgreen", s=size, zorder=2, marker=marker,
            label=f"CCT above the search limit {t_max:g} s (robust){what}",
        )  # fmt: skip
    for kind, color, label in (
        ("insecure", "red", "N-1 insecure: unstable even when cleared at once (CCT 0)"),
        ("failed", "0.5", "search failed (no verdict)"),
    ):
        if kinds[kind].any():
            ax.scatter(
                at[kinds[kind], 0], at[kinds[kind], 1], c=color, s=size, zorder=3,
                marker="x", label=label + what,
            )  # fmt: skip
    return sc


#: buses closer than this fraction of the drawing's extent share one label (`_label_groups`)
LABEL_MERGE = 0.03


def _label_groups(points: np.ndarray, numbers, shown: np.ndarray) -> list[tuple]:
    """The labels of `points` (k, 2) with their bus `numbers`, in order: those within
    LABEL_MERGE of the extent of `shown` (the points drawn) of an earlier one join its
    label ("1002, 1032"), which two numbers drawn on one another made unreadable.

    Returns
    -------
    list of (ndarray, str)
        Each label's anchor (the first point of its group) and its text.
    """
    tol = LABEL_MERGE * max(float(np.ptp(shown, axis=0).max()), 1e-12)
    groups: list[tuple[np.ndarray, list[str]]] = []
    for p, n in zip(points, numbers):
        near = next((g for g in groups if np.hypot(*(g[0] - p)) < tol), None)
        if near is None:
            groups.append((p, [str(int(n))]))
        else:
            near[1].append(str(int(n)))
    return [(p, ", ".join(names)) for p, names in groups]
