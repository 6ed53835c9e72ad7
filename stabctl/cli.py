"""The `stabctl` command line: one subcommand per study, `--json` where figures come out.

Errors in the input (stabctl.errors.StabctlError) are printed as one line naming what and
where, with exit status 2; nothing is written in that case.
"""

from __future__ import annotations

import functools
import json
import os
import sys
import tempfile
import warnings
from pathlib import Path

import click

from .errors import InputError, SimulationError, StabctlError


def _reports_errors(func):
    """Turn stabctl errors into a one-line message and exit status 2.

    Python warnings raised meanwhile are held back: on success they are printed as
    `warning:` lines on stderr, on error only the `error:` line is printed."""
    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("default")
            try:
                out = func(*args, **kwargs)
            except StabctlError as exc:
                click.echo(f"error: {_one_line(exc)}", err=True)
                sys.exit(2)
        for w in caught:
            click.echo(f"warning: {' '.join(str(w.message).split())}", err=True)
        return out
    return wrapper


def _one_line(exc) -> str:
    """The error message on one line; a diverged run also says where it stopped."""
    msg = " ".join(str(exc).split())
    res = getattr(exc, "result", None)
    if isinstance(exc, SimulationError) and res is not None and len(res.t) and "t = " not in msg:
        msg += f" (run stopped; last computed point t = {float(res.t[-1]):.4f} s)"
    return msg


def _print_json(obj) -> None:
    click.echo(json.dumps(obj, indent=2, default=float))


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="stabctl")
def main():
    """stabctl: transient-stability control with distributed energy storage."""


@main.command()
@click.option("--fault-cycles", "-c", type=float, multiple=True,
              help="Fault durations in cycles: `--fault-cycles 6 12 15` (default 6 12 15).")
@click.argument("more_cycles", nargs=-1, type=float)
@click.option("--H", "H", type=float, default=3.0, show_default=True, help="Inertia constant (s).")
@click.option("--pm", type=float, default=0.5, show_default=True, help="Mechanical power (pu).")
@click.option("--delta0", type=float, default=0.4950, show_default=True,
              help="Pre-fault angle (rad); sets Pmax = Pm/sin(delta0).")
@click.option("--pmax", type=float, default=None,
              help="Pre/post-fault Pmax (pu) instead of deriving it from delta0.")
@click.option("--f0", type=float, default=60.0, show_default=True, help="Frequency (Hz).")
@click.option("--json", "as_json", is_flag=True, help="Machine-readable output.")
@_reports_errors
def omib(fault_cycles, more_cycles, H, pm, delta0, pmax, f0, as_json):
    """One-machine infinite bus: clearing state per fault duration and the EAC CCT.

    Defaults are the paper's Section 2 case (H = 3 s, Pm = 0.5 pu, delta0 = 0.4950 rad,
    bolted fault at the generator bus, post-fault network = pre-fault).
    """
    from .omib import OMIB, clearing_table, eac_summary

    if pmax is None:
        system = OMIB.from_operating_point(H=H, Pm=pm, delta0=delta0, f0=f0)
    else:
        system = OMIB(H=H, Pm=pm, Pmax_pre=pmax, Pmax_fault=0.0, Pmax_post=pmax, f0=f0)
    cycles = tuple(fault_cycles) + tuple(more_cycles) or (6.0, 12.0, 15.0)
    out = {"cases": clearing_table(system, cycles), "eac": eac_summary(system)}
    if as_json:
        _print_json(out)
        return
    click.echo(f"{'cycles':>7} {'delta_cl rad':>13} {'omega_cl rad/s':>15}  verdict")
    for r in out["cases"]:
        click.echo(f"{r['cycles']:7.2f} {r['delta_cl_rad']:13.4f} {r['omega_cl_rad_s']:15.4f}  "
                   f"{'stable' if r['stable'] else 'unstable'}")
    e = out["eac"]
    click.echo(f"EAC: critical clearing angle {e['delta_cr_rad']:.4f} rad, CCT {e['t_cr_s']:.4f} s "
               f"({e['t_cr_cycles']:.2f} cycles); bisection {e['t_cr_bisection_s']:.4f} s")


@main.command()
@click.option("--out", "out_dir", default="reports", show_default=True,
              type=click.Path(file_okay=False), help="Report directory.")
@_reports_errors
def paper(out_dir):
    """Reproduce the paper's tables and figures into OUT/paper.md (+ PNG figures)."""
    from .paper import write_paper_report

    path = write_paper_report(out_dir, progress=lambda msg: click.echo(msg, err=True))
    click.echo(f"wrote {path}")


# -- multi-machine simulator ------------------------------------------------------------

def _case_info(name: str) -> dict:
    from .case import load_case

    case = load_case(name)
    return {"name": name, "description": case.description,
            "buses": case.n_bus, "branches": len(case.branches),
            "machines": len(case.machines), "exciters": len(case.exciters),
            "pss": len(case.pss), "governors": len(case.governors),
            "nonconforming_loads": len(case.loads), "base_mva": case.base_mva,
            "freq_hz": case.freq_hz, "sw_con": _describe_sw_con(case)}


def _describe_sw_con(case) -> str | None:
    """One line for the data file's own disturbance (what --pstess-default runs)."""
    from .events import from_sw_con
    from .simulation import default_step

    if case.sw_con is None:
        return None
    try:
        evs = from_sw_con(case)
    except StabctlError as exc:
        return f"unsupported ({exc})"
    what = "; ".join(_describe_event(e) for e in evs) or "no disturbance"
    return f"{what}; {float(case.sw_con[-1, 0]):g} s, step {default_step(case):g} s"


def _describe_event(ev) -> str:
    from .events import Fault, GeneratorTrip, LineTrip, LoadStep

    if isinstance(ev, Fault):
        s = f"3-phase fault at bus {ev.bus} at {ev.t:g} s"
        if ev.clear_near is None:
            return s + ", never cleared"
        if ev.far_bus is None:
            return s + f", cleared at {ev.clear_near:g} s without loss of a line"
        return (s + f" on line {ev.bus}-{ev.far_bus} (circuit {ev.circuit}), cleared at "
                f"{ev.clear_near:g} s near / {ev.far_clear:g} s far end, line tripped")
    if isinstance(ev, LineTrip):
        return f"line {ev.from_bus}-{ev.to_bus} (circuit {ev.circuit}) tripped at {ev.t:g} s"
    if isinstance(ev, GeneratorTrip):
        return f"machine {ev.machine} tripped at {ev.t:g} s"
    if isinstance(ev, LoadStep):
        return f"load step {ev.P:g}{ev.Q:+g}j pu at bus {ev.bus} at {ev.t:g} s"
    return repr(ev)


@main.command()
@click.option("--json", "as_json", is_flag=True, help="Machine-readable output (a list).")
@_reports_errors
def cases(as_json):
    """List the built-in cases (usable as CASE in `stabctl simulate`).

    For each: name, description, numbers of buses, branches (every circuit counted),
    machines, exciters, PSS, governors and non-conforming load buses, the base (MVA) and
    frequency (Hz), and the data file's own disturbance (PST sw_con, run by
    `simulate --pstess-default`).
    """
    from .case import list_cases

    rows = [_case_info(name) for name in list_cases()]
    if as_json:
        _print_json(rows)
        return
    for r in rows:
        click.echo(f"{r['name']}: {r['buses']} buses, {r['branches']} branches, "
                   f"{r['machines']} machines, {r['governors']} governors, "
                   f"{r['base_mva']:g} MVA base, {r['freq_hz']:g} Hz")
        click.echo(f"    {r['description']}")
        if r["sw_con"]:
            click.echo(f"    data file disturbance: {r['sw_con']}")


_OUT_SUFFIXES = (".csv", ".npz")
_PLOT_SUFFIXES = (".png", ".pdf", ".svg")


def _check_suffix(path, allowed, option) -> Path | None:
    if path is None:
        return None
    p = Path(path)
    if p.suffix.lower() not in allowed:
        raise InputError(f"{option} {path}: the file name must end in {' or '.join(allowed)}")
    if p.exists() and p.is_dir():
        raise InputError(f"{option} {path} is a directory")
    return p


def _save_plot_atomically(result, path: Path, title: str) -> None:
    from .plotting import simulation_overview

    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=path.suffix)
    os.close(fd)
    try:
        simulation_overview(result, tmp, title=title)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _build_events(case, fault, far_bus, t_fault, clear_cycles, far_clear_cycles, circuit,
                  trips, t_trips, pstess_default):
    from .events import LineTrip, fault_with_clearing, from_sw_con

    events = list(from_sw_con(case)) if pstess_default else []
    if fault is None:
        given = {"--far-bus": far_bus, "--far-clear-cycles": far_clear_cycles}
        stray = [k for k, v in given.items() if v is not None]
        if stray:
            raise InputError(f"{', '.join(stray)} given without --fault")
    else:
        if clear_cycles < 0:
            raise InputError(f"--clear-cycles must be >= 0, got {clear_cycles:g}")
        if far_clear_cycles is not None and far_clear_cycles < 0:
            raise InputError(f"--far-clear-cycles must be >= 0, got {far_clear_cycles:g}")
        if t_fault < 0:
            raise InputError(f"--t-fault must be >= 0 s, got {t_fault:g}")
        events.append(fault_with_clearing(case, fault, far_bus, t_fault, clear_cycles,
                                          far_clear_cycles, circuit=circuit))
    if trips:
        times = list(t_trips) or [1.0]
        if len(times) == 1:
            times = times * len(trips)
        if len(times) != len(trips):
            raise InputError(f"{len(trips)} --trip but {len(t_trips)} --t-trip: give one "
                             "--t-trip for all or one per --trip")
        for (a, b), t in zip(trips, times):
            if t < 0:
                raise InputError(f"--t-trip must be >= 0 s, got {t:g}")
            events.append(LineTrip(a, b, t))
    elif t_trips:
        raise InputError("--t-trip given without --trip")
    return events


@main.command()
@click.argument("case_name", metavar="CASE")
@click.option("--fault", type=int, default=None, metavar="BUS",
              help="Three-phase (bolted) fault at bus BUS (bus number as in the data).")
@click.option("--far-bus", type=int, default=None, metavar="BUS",
              help="Far end of the faulted line: clearing trips the line BUS-FAR_BUS. "
                   "Without it the fault is cleared without loss of a line.")
@click.option("--circuit", type=int, default=1, show_default=True, metavar="K",
              help="Which of parallel circuits BUS-FAR_BUS (in data order) is faulted.")
@click.option("--t-fault", type=float, default=1.0, show_default=True, metavar="S",
              help="Fault start time (s).")
@click.option("--clear-cycles", type=float, default=6.0, show_default=True, metavar="N",
              help="Near-end clearing after N cycles of the case frequency.")
@click.option("--far-clear-cycles", type=float, default=None, metavar="M",
              help="Far-end clearing after M cycles from fault start (default: N).")
@click.option("--trip", type=(int, int), multiple=True, metavar="FROM TO",
              help="Trip one circuit of line FROM-TO without fault (repeatable).")
@click.option("--t-trip", type=float, multiple=True, metavar="S",
              help="Trip time (s): once for all trips or once per --trip (default 1.0).")
@click.option("--pstess-default", is_flag=True,
              help="Run the case file's own PST sw_con disturbance (with any of the above "
                   "added); --tf then defaults to its end time.")
@click.option("--tf", type=float, default=None, metavar="S",
              help="End time (s); default 5 s, or the sw_con end with --pstess-default.")
@click.option("--step", type=float, default=None, metavar="H",
              help="Integration step (s); default the data file's (sw_con) step, else half "
                   "a cycle. Each interval between events gets fix(length/H) equal steps. "
                   "The method is explicit (PST's Heun): H near twice the smallest time "
                   "constant (Kundur T_R = 0.01 s) makes the run numerically unstable.")
@click.option("--separation-limit", type=float, default=3.141592653589793,
              show_default="pi", metavar="RAD",
              help="Loss of synchronism: a rotor angle more than RAD from the centre of "
                   "inertia.")
@click.option("--stop-at-separation", is_flag=True,
              help="Stop the run at loss of synchronism.")
@click.option("--out", "out_path", type=click.Path(dir_okay=False), default=None,
              metavar="FILE.csv|FILE.npz", help="Write the trajectories (CSV or numpy .npz).")
@click.option("--plot", "plot_path", type=click.Path(dir_okay=False), default=None,
              metavar="FILE.png", help="Plot speeds, angles from the COI and bus voltages.")
@click.option("--json", "as_json", is_flag=True, help="Print the run summary as JSON.")
@_reports_errors
def simulate(case_name, fault, far_bus, circuit, t_fault, clear_cycles, far_clear_cycles, trip,
             t_trip, pstess_default, tf, step, separation_limit, stop_at_separation, out_path,
             plot_path, as_json):
    """Nonlinear multi-machine time-domain simulation (PSTess models and integrator).

    CASE is a built-in name (see `stabctl cases`) or a case file (.json, PST .m). The run
    starts from the solved power flow. With no disturbance option the run is flat (no
    disturbance); --pstess-default runs the data file's own sw_con.

    \b
    Fault (as PST's sw_con, y_switch): a bolted three-phase fault at BUS from --t-fault;
    after N cycles the near end of line BUS-FAR_BUS opens (the far end keeps feeding the
    fault through the line), after M cycles the far end opens too and the line stays out.

    \b
    Units: times s, cycles of the case frequency (60 Hz: 1 cycle = 16.67 ms), speeds pu,
    angles rad (absolute, synchronous frame, as PSTess), pelect pu on the system base,
    pmech pu on the machine base, efd pu, bus voltages pu and rad.

    \b
    CSV columns: t, speed_pu.G<k>, angle_rad.G<k>, pelect_pu.G<k>, pmech_pu.G<k>,
    efd_pu.G<k> per machine k, vmag_pu.B<n>, vang_rad.B<n> per bus n.

    \b
    Examples:
      stabctl simulate kundur --pstess-default --out kundur.csv
      stabctl simulate kundur --fault 3 --far-bus 101 --t-fault 1 --clear-cycles 21 --json
      stabctl simulate miniwecc --trip 40 44 --t-trip 1 --tf 10 --plot wecc.png

    Bad input (unknown case or bus, no such line, negative cycles, power flow not
    converging) and a run that diverges exit with status 2 and one `error:` line; no file
    is written then (a diverged run reports where it stopped).
    """
    from .case import load_case
    from .simulation import Simulator, default_step

    out_p = _check_suffix(out_path, _OUT_SUFFIXES, "--out")
    plot_p = _check_suffix(plot_path, _PLOT_SUFFIXES, "--plot")
    if step is not None and not step > 0:
        raise InputError(f"--step must be > 0 s, got {step:g}")
    if not separation_limit > 0:
        raise InputError(f"--separation-limit must be > 0 rad, got {separation_limit:g}")
    case = load_case(case_name)
    events = _build_events(case, fault, far_bus, t_fault, clear_cycles, far_clear_cycles,
                           circuit, trip, t_trip, pstess_default)
    if tf is None:
        tf = float(case.sw_con[-1, 0]) if pstess_default and case.sw_con is not None else 5.0
    if not tf > 0:
        raise InputError(f"--tf must be > 0 s, got {tf:g}")
    late = [e for e in events if min(e.times()) >= tf]
    if late:
        raise InputError(f"{_describe_event(late[0])}: starts at or after the end of the run "
                         f"(--tf {tf:g} s)")
    h = default_step(case) if step is None else step
    sim = Simulator(case)
    result = sim.run(events, t_end=tf, h=h, separation_limit=separation_limit,
                     stop_at_separation=stop_at_separation)
    written = []
    if plot_p is not None:
        _save_plot_atomically(result, plot_p, title=f"{case.name}: "
                              + ("; ".join(_describe_event(e) for e in events) or "flat run"))
        written.append(str(plot_p))
    if out_p is not None:
        if out_p.suffix.lower() == ".npz":
            result.to_npz(out_p)
        else:
            result.to_csv(out_p)
        written.insert(0, str(out_p))
    summary = result.summary()
    if as_json:
        _print_json({**summary, "step_s": h,
                     "events": [_describe_event(e) for e in events], "files": written})
        return
    click.echo(f"case {case.name}: {len(case.machines)} machines, {case.n_bus} buses; "
               f"0-{float(result.t[-1]):g} s, {summary['n_steps']} steps (h = {h:g} s), "
               f"wall {summary.get('wall_time_s', float('nan')):.2f} s")
    for e in events or ["flat run (no disturbance)"]:
        click.echo(f"  {e if isinstance(e, str) else _describe_event(e)}")
    if result.stable:
        click.echo(f"stable: largest angle from the COI {summary['max_angle_spread_rad']:.4f} rad")
    else:
        machines = ", ".join(str(m) for m in result.separated)
        click.echo(f"loss of synchronism at t = {result.t_separation:.4f} s: machine(s) "
                   f"{machines} separate" + (" (run stopped)" if stop_at_separation else ""))
    for w in written:
        click.echo(f"wrote {w}")


if __name__ == "__main__":  # pragma: no cover
    main()
