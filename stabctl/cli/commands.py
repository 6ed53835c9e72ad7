"""The `stabctl` command line: one subcommand per study, `--json` where figures come out.

Errors in the input (stabctl.errors.StabctlError) are printed as one line naming what and
where, with exit status 2; nothing is written in that case.
"""

from __future__ import annotations

import functools
import json
import math
import os
import shlex
import sys
import tempfile
import warnings
from pathlib import Path

import click

from stabctl.errors import InputError, SimulationError, StabctlError


def _reports_errors(func):
    """Turn stabctl errors into a one-line message and exit status 2.

    Numeric options are checked first (:func:`_check_numbers`: finite, in range).
    Python warnings raised meanwhile are held back: on success they are printed as
    `warning:` lines on stderr, on error only the `error:` line is printed."""
    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("default")
            try:
                _check_numbers(kwargs)
                out = func(*args, **kwargs)
            except StabctlError as exc:
                click.echo(f"error: {_one_line(exc)}", err=True)
                sys.exit(2)
            except KeyboardInterrupt:
                click.echo(_interrupted(kwargs), err=True)
                sys.exit(130)
        for w in caught:
            click.echo(f"warning: {' '.join(str(w.message).split())}", err=True)
        return out
    return wrapper


# -- numeric options checked at the edge -------------------------------------------------

_INF = float("inf")
#: allowed range of each numeric option: (low, high, low included, high included, unit).
#: Every float option, listed or not, must also be finite (no nan, inf). The OMIB ranges
#: (H, Pmax, f0) keep the swing frequency below about 25 Hz, so that the CCT bisection's
#: runs stay short (H = 0.001 s, f0 = 1000 Hz ran for many minutes).
_RANGES = {
    "--fault-cycles": (0, 600, True, True, "cycles"),
    "MORE_CYCLES": (0, 600, True, True, "cycles"),
    "--H": (0.5, 50, True, True, "s"),
    "--pm": (0, 10, False, True, "pu"),
    "--delta0": (0, 1.5707963267948966, False, False, "rad"),
    "--pmax": (0, 10, False, True, "pu"),
    "--f0": (10, 400, True, True, "Hz"),
    "--t-fault": (0, 1000, True, True, "s"),
    "--clear-cycles": (0, 600, True, True, "cycles"),
    "--far-clear-cycles": (0, 600, True, True, "cycles"),
    "--t-trip": (0, 1000, True, True, "s"),
    "--tf": (0, 3600, False, True, "s"),
    "--step": (0, 1, False, True, "s"),
    "--separation-limit": (0, 100, False, True, "rad"),
    "--esd-pct": (0, 100, False, True, "% of machine MVA"),
    "--deadband-hz": (0, 10, True, True, "Hz"),
    "--v-gate": (0, 2, True, True, "pu"),
    "--hysteresis-hz": (0, 10, True, True, "Hz"),
    "--tol-ms": (0, 1000, False, True, "ms"),
    "--t-max": (0, 100, False, True, "s"),
    "--workers": (1, 1024, True, True, ""),
    "--circuit": (1, 99, True, True, ""),
    "--areas": (1, 1000, True, True, ""),
    "--target-cct-gain": (0, 1000, False, True, "%"),
    "--zeta-min": (0, 1, True, False, ""),
    "--max-sites": (1, 100000, True, True, ""),
    "--max-site-pct": (0, 100, False, True, "% of machine MVA"),
    "--site-cost": (0, 1e6, True, True, "MW"),
    "--amplitude-hz": (0, 10, False, True, "Hz"),
    "--max-iter": (1, 1000, True, True, ""),
    "--rate": (1, 1000, True, True, "frames/s"),
    "--latency-ms": (0, 10000, True, True, "ms"),
    "--drop": (0, 1, True, False, ""),
    "--tve-pct": (0, 100, True, True, "%"),
    "--fe-hz": (0, 10, True, True, "Hz"),
    "--rfe-hz-s": (0, 100, True, True, "Hz/s"),
    "--k-sigma": (0, 100, False, True, ""),
    "--runs": (1, 100000, True, True, ""),
    "--seed": (0, 2**32 - 1, True, True, ""),
    "--settle-ms": (0, 100000, True, True, "ms"),
    "--ambient-s": (0, 36000, True, True, "s"),
    "--ambient-pct": (0, 100, True, True, "%"),
    "--ambient-tau-s": (0, 3600, False, True, "s"),
    "--ambient-runs": (1, 10000, True, True, ""),
}


def _interval(spec) -> str:
    lo, hi, lo_in, hi_in, unit = spec
    return (f"{'[' if lo_in else '('}{lo:g}, {hi:g}{']' if hi_in else ')'}"
            + (f" {unit}" if unit else ""))


def check_number(label: str, value) -> None:
    """InputError unless ``value`` is finite and inside the range of option ``label``
    (:data:`_RANGES`); the message names the option, the value and the allowed range."""
    spec = _RANGES.get(label)
    allowed = f" in {_interval(spec)}" if spec else ""
    if isinstance(value, float) and not math.isfinite(value):
        raise InputError(f"{label} {value}: must be a finite number{allowed}")
    if spec is None:
        return
    lo, hi, lo_in, hi_in, _ = spec
    if not ((value >= lo if lo_in else value > lo) and (value <= hi if hi_in else value < hi)):
        raise InputError(f"{label} {value:g}: must be{allowed}")


def _check_numbers(kwargs) -> None:
    """Check every numeric option of the running command (:func:`check_number`)."""
    ctx = click.get_current_context(silent=True)
    if ctx is None:
        return
    for param in ctx.command.params:
        if param.name not in kwargs:
            continue
        label = next((o for o in param.opts if o.startswith("--")), None) or \
            param.human_readable_name
        for value in _numbers(kwargs[param.name]):
            check_number(label, value)


def _numbers(value):
    if isinstance(value, (tuple, list)):
        for v in value:
            yield from _numbers(v)
    elif isinstance(value, (int, float)) and not isinstance(value, bool):
        yield value


#: what an interrupted command keeps, by command (default: nothing)
_KEPT = {
    "sweep-cct": "finished jobs are in {out}; they are skipped",
    "screen": "finished searches are in {out}; they are skipped",
    "paper": "finished sweep records in {out} are kept with --resume",
}


def _interrupted(kwargs) -> str:
    """The one line printed on Ctrl-C (SIGINT) by every command: what was kept and the
    command that resumes (paper: with --resume)."""
    ctx = click.get_current_context(silent=True)
    name = ctx.info_name if ctx is not None else ""
    argv = ["stabctl", *sys.argv[1:]]
    if name == "paper" and "--resume" not in argv:
        argv.append("--resume")
    out = kwargs.get("out_path") or kwargs.get("out_dir") or ""
    if name in ("sweep-cct", "screen") and out:
        from stabctl.parallel import read_records
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            out = f"{out} ({len(read_records(out))} recorded)"
    kept = _KEPT.get(name, "nothing is kept; the work starts again").format(out=out)
    return f"interrupted: {kept}; resume with: {shlex.join(argv)}"


def _one_line(exc) -> str:
    """The error message on one line; a diverged run also says where it stopped."""
    msg = " ".join(str(exc).split())
    res = getattr(exc, "result", None)
    if isinstance(exc, SimulationError) and res is not None and len(res.t) and "t = " not in msg:
        msg += f" (run stopped; last computed point t = {float(res.t[-1]):.4f} s)"
    return msg


def _print_json(obj) -> None:
    click.echo(json.dumps(obj, indent=2, default=float))


def _line_fault_options(func):
    """--fault BUS --far-bus BUS [--t-fault S]: a bolted fault on line BUS-FAR_BUS (cct,
    estimate)."""
    for opt in reversed((
            click.option("--fault", type=int, required=True, metavar="BUS",
                         help="Three-phase (bolted) fault at bus BUS."),
            click.option("--far-bus", type=int, required=True, metavar="BUS",
                         help="Far end of the faulted line BUS-FAR_BUS, tripped at clearing."),
            click.option("--t-fault", type=float, default=1.0, show_default=True, metavar="S",
                         help="Fault start time (s)."))):
        func = opt(func)
    return func


def _model_options(func):
    """--conventions and --step, the same on every command that simulates or linearises."""
    func = click.option("--step", type=float, default=None, metavar="H",
                        help="Integration step (s); default: the case's data-file step, "
                             "under ieee capped at half its fastest time constant (Kundur "
                             "5 ms, miniWECC 1/480 s; pstess: Kundur 10 ms).")(func)
    return click.option("--conventions", type=click.Choice(["ieee", "pstess"]),
                        default="ieee", show_default=True,
                        help="Model conventions: ieee (IEEE 421.5 limiters, results converge "
                             "with the step) or pstess (PSTess 1.1 bit for bit, quirks "
                             "included); docs/conventions.md.")(func)


def _q_limits_option(func):
    """--q-limits/--no-q-limits on every command that starts a run or linearises."""
    return click.option("--q-limits/--no-q-limits", "q_limits", default=True,
                        show_default=True,
                        help="Power flow: PV buses switch to PQ at their reactive limits "
                             "(PST's chq_lim) or keep their voltage without limits (ANDES's "
                             "default, for comparisons with ANDES).")(func)


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="stabctl")
def main():
    """stabctl: transient-stability control with distributed energy storage."""
    # The simulator works on many small dense matrices: multi-threaded BLAS only adds
    # overhead there and oversubscribes the cores when sweeps run one simulation per
    # process.  Set before any command imports numpy; a user's own setting wins.
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")


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
    from stabctl.smib.omib import OMIB, clearing_table, eac_summary

    if pmax is None:
        system = OMIB.from_operating_point(H=H, Pm=pm, delta0=delta0, f0=f0)
        lo, hi = _RANGES["--pmax"][:2]
        if not lo < system.Pmax_pre <= hi:
            raise InputError(f"--delta0 {delta0:g} with --pm {pm:g}: Pmax = Pm/sin(delta0) = "
                             f"{system.Pmax_pre:g} pu, outside the --pmax range "
                             f"{_interval(_RANGES['--pmax'])}")
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
@click.option("--resume", is_flag=True,
              help="Continue the sweeps (Table 4 and estimator CCT sweeps, placement "
                   "screening) from the records of an interrupted run in OUT/.paper-work, "
                   "or else from the records in OUT; by default they are recomputed.")
@click.option("--only", multiple=True,
              type=click.Choice(["analytic", "cases", "convergence", "table4", "estimation",
                                 "placement"]),
              help="Build only these parts (repeatable): analytic = Sections 2-4 (seconds); "
                   "cases = Cases 1 and 2; convergence = CCT against the step under both "
                   "conventions (2 minutes); table4 = CCT sweeps (minutes); estimation = "
                   "estimator Monte Carlo (about 10 minutes on 2 cores); placement = ESD "
                   "sizing and placement studies (about 30 minutes). Default: all; "
                   "with --only, paper.md holds only those parts.")
@_reports_errors
def paper(out_dir, resume, only):
    """Reproduce the paper's tables and figures into OUT/paper.md (+ PNG figures).

    The Table 4 and estimator CCT sweeps and the placement screening record each finished
    search in OUT/.paper-work as it completes (an interrupted run continues from there
    with --resume). Only when every section has succeeded are the reports moved into OUT
    and the records written to OUT/table4_<case>.jsonl, OUT/estimation_cct_<case>.jsonl
    and OUT/placement_<case>_screening.jsonl, replacing the old ones; reports and records
    hold no timings or other run-dependent values (two runs give identical files), those
    go to OUT/run_log.json (seconds per section, every progress line).
    """
    from stabctl.studies.paper import write_paper_report

    check_writable(out_dir, "--out", directory=True)
    path = write_paper_report(out_dir, progress=lambda msg: click.echo(msg, err=True),
                              resume=resume, only=only)
    click.echo(f"wrote {path}")


# -- multi-machine simulator ------------------------------------------------------------

def _case_info(name: str) -> dict:
    from stabctl.io import load_case

    case = load_case(name)
    return {"name": name, "description": case.description,
            "buses": case.n_bus, "branches": len(case.branches),
            "machines": len(case.machines), "exciters": len(case.exciters),
            "pss": len(case.pss), "governors": len(case.governors),
            "nonconforming_loads": len(case.loads), "base_mva": case.base_mva,
            "freq_hz": case.freq_hz, "sw_con": _describe_sw_con(case)}


def _describe_sw_con(case) -> str | None:
    """One line for the data file's own disturbance (what --pstess-default runs)."""
    from stabctl.dynamics.events import from_sw_con

    if case.sw_con is None:
        return None
    try:
        evs = from_sw_con(case)
    except StabctlError as exc:
        return f"unsupported ({exc})"
    what = "; ".join(_describe_event(e) for e in evs) or "no disturbance"
    return f"{what}; {float(case.sw_con[-1, 0]):g} s, data-file step {float(case.sw_con[0, 6]):g} s"


def _describe_event(ev) -> str:
    from stabctl.dynamics.events import Fault, GeneratorTrip, LineTrip, LoadStep

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
    from stabctl.io import list_cases

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
    check_writable(p, option)
    return p


def check_writable(path, option: str, directory: bool = False) -> None:
    """InputError (before any work) unless ``path`` can be written: a file in an existing
    directory where a file can be created (tried with a temporary file, removed at once),
    not itself a directory and, if it exists, writable. ``directory``: ``path`` is an
    output directory, which may be created, inside an existing one."""
    p = Path(path)
    if directory:
        if p.exists() and not p.is_dir():
            raise InputError(f"{option} {path}: not a directory")
        where = p if p.is_dir() else p.parent
    else:
        if p.is_dir():
            raise InputError(f"{option} {path} is a directory")
        where = p.parent
    where = where if str(where) else Path(".")
    if not where.is_dir():
        raise InputError(f"{option} {path}: directory {where} does not exist (create it "
                         "first; it is not created for you)")
    try:
        fd, tmp = tempfile.mkstemp(dir=where, prefix=".stabctl-write-test.")
        os.close(fd)
        os.unlink(tmp)
    except OSError as exc:
        raise InputError(f"{option} {path}: cannot write in {where} "
                         f"({exc.strerror or exc})") from None
    if not directory and p.exists() and not os.access(p, os.W_OK):
        raise InputError(f"{option} {path}: the file is not writable")


def _save_plot_atomically(result, path: Path, title: str, base_mva: float = 100.0) -> None:
    from stabctl.parallel import atomic_write
    from stabctl.plotting.figures import simulation_overview

    atomic_write(path, lambda tmp: simulation_overview(result, tmp, title=title,
                                                       base_mva=base_mva), mode=None)


def _describe_esd(esd: dict, short: bool = False) -> str:
    """One line on the storage of `simulate --esd-pct` (short: for a plot title)."""
    where = "" if short else " at the generator HV buses"
    control = "bang-bang COI control" if short else esd["control"]
    return (f"storage: {esd['devices']} ESDs of {esd['pct_of_machine_mva']:g} % of machine MVA"
            f"{where}, {control}, deadband {esd['deadband_hz']:g} Hz, "
            f"{'gate' if short else 'voltage gate'} {esd['v_gate_pu']:g} pu, {esd['coi']} COI"
            + (f", hysteresis {esd['hysteresis_hz']:g} Hz" if esd["hysteresis_hz"] else ""))


def _print_storage(esd: dict, result) -> None:
    """The storage lines of `simulate`'s text output: settings, totals, active devices."""
    info = result.meta.get("storage", [])
    active = [d for d in info if d["switchings"] > 0]
    click.echo(f"  {_describe_esd(esd)}")
    click.echo(f"  {sum(d['switchings'] for d in info)} switchings, {len(active)} of "
               f"{len(info)} devices acted; absorbed "
               f"{sum(d['energy_absorbed_mj'] for d in info):.1f} MJ, delivered "
               f"{sum(d['energy_delivered_mj'] for d in info):.1f} MJ")
    if active:
        click.echo(f"  {'device':>6} {'bus':>6} {'machine':>7} {'MW':>7} {'switchings':>10} "
                   f"{'absorbed MJ':>11} {'delivered MJ':>12} {'peak MW':>8}")
    for d in active:
        click.echo(f"  {d['device']:6d} {d['bus']:6d} {'G' + str(d['machine']):>7} "
                   f"{d['pmax_mw']:7.1f} {d['switchings']:10d} {d['energy_absorbed_mj']:11.1f} "
                   f"{d['energy_delivered_mj']:12.1f} {d['peak_power_mw']:8.1f}")


def _build_events(case, fault, far_bus, t_fault, clear_cycles, far_clear_cycles, circuit,
                  trips, t_trips, pstess_default):
    from stabctl.dynamics.events import LineTrip, fault_with_clearing, from_sw_con

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
@_model_options
@_q_limits_option
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
@click.option("--esd-pct", type=float, default=None, metavar="P",
              help="ESD of P % of each generator's MVA at its HV bus, paper's bang-bang "
                   "COI control (Table 3).")
@click.option("--deadband-hz", type=float, default=0.1, show_default=True,
              help="ESD controller deadband on f_i - f_COI (Hz).")
@click.option("--v-gate", type=float, default=0.8, show_default=True,
              help="ESDs act only while their bus voltage is at least this (pu).")
@click.option("--coi", type=click.Choice(["system", "rest"]), default="system",
              show_default=True, help="COI of the whole system or of the rest of it.")
@click.option("--hysteresis-hz", type=float, default=0.0, show_default=True,
              help="A running ESD stops only inside deadband - hysteresis (Hz).")
@click.option("--json", "as_json", is_flag=True, help="Print the run summary as JSON.")
@_reports_errors
def simulate(case_name, fault, far_bus, circuit, t_fault, clear_cycles, far_clear_cycles, trip,
             t_trip, pstess_default, tf, conventions, step, q_limits, separation_limit,
             stop_at_separation, out_path, plot_path, esd_pct, deadband_hz, v_gate, coi,
             hysteresis_hz, as_json):
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
    efd_pu.G<k> per machine k, vmag_pu.B<n>, vang_rad.B<n> per bus n, and with
    --esd-pct pesd_pu.D<d> per device (+ absorbs); --json then also gives the storage
    settings (`esd`), per device switchings, energy absorbed and delivered (MJ) and peak
    power used (MW) (`storage`), and every switching as {t_s, device, bus, machine, mode
    (absorb, idle, inject), mode_code (+1, 0, -1), rel_speed_hz (machine minus COI speed
    seen by the controller)} (`switchings`).

    \b
    Examples:
      stabctl simulate kundur --pstess-default --out kundur.csv
      stabctl simulate kundur --fault 3 --far-bus 101 --t-fault 1 --clear-cycles 21 --json
      stabctl simulate miniwecc --trip 40 44 --t-trip 1 --tf 10 --plot wecc.png
      stabctl simulate miniwecc --fault 83 --far-bus 33 --clear-cycles 6 --esd-pct 5 --json

    Bad input (unknown case or bus, no such line, negative cycles, power flow not
    converging) and a run that diverges exit with status 2 and one `error:` line; no file
    is written then (a diverged run reports where it stopped).
    """
    from stabctl.io import load_case
    from stabctl.dynamics.simulation import Simulator

    out_p = _check_suffix(out_path, _OUT_SUFFIXES, "--out")
    plot_p = _check_suffix(plot_path, _PLOT_SUFFIXES, "--plot")
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
    fleet = None
    if esd_pct is not None:
        from stabctl.storage.devices import BangBangCOI, uniform_fleet
        fleet = uniform_fleet(case, esd_pct, BangBangCOI(deadband_hz, v_gate, coi, hysteresis_hz))
    sim = Simulator(case, conventions=conventions, q_limits=q_limits)
    h = sim.default_h if step is None else step
    result = sim.run(events, t_end=tf, h=h, separation_limit=separation_limit,
                     stop_at_separation=stop_at_separation, storage=fleet)
    esd = None if esd_pct is None else {
        "pct_of_machine_mva": esd_pct, "devices": len(fleet.devices),
        "control": "bang-bang COI (paper Table 3)", "deadband_hz": deadband_hz,
        "v_gate_pu": v_gate, "coi": coi, "hysteresis_hz": hysteresis_hz}
    written = []
    if plot_p is not None:
        title = f"{case.name}: " + ("; ".join(_describe_event(e) for e in events) or "flat run")
        if esd is not None:
            title += "\n" + _describe_esd(esd, short=True)
        _save_plot_atomically(result, plot_p, title=title, base_mva=case.base_mva)
        written.append(str(plot_p))
    if out_p is not None:
        if out_p.suffix.lower() == ".npz":
            result.to_npz(out_p)
        else:
            result.to_csv(out_p)
        written.insert(0, str(out_p))
    summary = result.summary()
    if esd is not None:
        summary["switchings"] = result.switching_records()
    if as_json:
        _print_json({**summary, "step_s": h, "conventions": conventions, "q_limits": q_limits,
                     "esd": esd,
                     "events": [_describe_event(e) for e in events], "files": written})
        return
    click.echo(f"case {case.name}: {len(case.machines)} machines, {case.n_bus} buses; "
               f"0-{float(result.t[-1]):g} s, {summary['n_steps']} steps (h = {h:g} s, "
               f"{conventions} conventions), "
               f"wall {summary.get('wall_time_s', float('nan')):.2f} s")
    for e in events or ["flat run (no disturbance)"]:
        click.echo(f"  {e if isinstance(e, str) else _describe_event(e)}")
    if esd is not None:
        _print_storage(esd, result)
    if result.stable:
        click.echo(f"stable: largest angle from the COI {summary['max_angle_spread_rad']:.4f} rad")
    else:
        machines = ", ".join(str(m) for m in result.separated)
        click.echo(f"loss of synchronism at t = {result.t_separation:.4f} s: machine(s) "
                   f"{machines} separate" + (" (run stopped)" if stop_at_separation else ""))
    for w in written:
        click.echo(f"wrote {w}")



# -- critical clearing time and sweeps --------------------------------------------------

def _cct_settings(tol_ms, t_max, tf) -> dict:
    if not tol_ms > 0:
        raise InputError(f"--tol-ms must be > 0, got {tol_ms:g}")
    if not t_max > 0:
        raise InputError(f"--t-max must be > 0 s, got {t_max:g}")
    if tf is not None and not tf > 0:
        raise InputError(f"--tf must be > 0 s, got {tf:g}")
    return {"tol": tol_ms / 1000.0, "t_max": t_max, "t_end": tf}


def _print_cct(case_name, rating, d) -> None:
    f = d["fault"]
    circ = f" (circuit {f['circuit']})" if f["circuit"] != 1 else ""
    click.echo(f"case {case_name}: fault at bus {f['bus']} on line {f['bus']}-{f['far_bus']}"
               f"{circ} at {f['t_fault']:g} s, cleared at both ends, line tripped"
               + "".join(f", {a}-{b} also opened" for a, b in f["trips"])
               + ("; no storage" if rating is None else f"; storage {rating:g} % of machine MVA"))
    click.echo(f"CCT {d['cct_s']:.3f} s = {d['cct_cycles']:.2f} cycles (stable at "
               f"{d['t_stable_s']:.3f} s, unstable at {d['t_unstable_s']:.3f} s = "
               f"{d['t_unstable_cycles']:.2f} cycles; tolerance {1000 * d['tol_s']:g} ms, "
               f"step {d['step_s']:g} s, {d['conventions']} conventions)")
    if d["numerical_error_s"] is not None:
        click.echo(f"numerical error {1000 * d['numerical_error_s']:g} ms (CCT at half the "
                   f"step {d['cct_half_step_s']:.3f} s)")
    if d["separated_machines"]:
        click.echo(f"machine(s) {', '.join(map(str, d['separated_machines']))} lose "
                   f"synchronism when cleared at {d['t_unstable_s']:.3f} s")
    click.echo(f"{d['n_simulations']} simulations, wall {d['wall_time_s']:.2f} s")


@main.command()
@click.argument("case_name", metavar="CASE")
@_line_fault_options
@click.option("--circuit", type=int, default=1, show_default=True, metavar="K",
              help="Which of parallel circuits BUS-FAR_BUS is faulted.")
@click.option("--trip", type=(int, int), multiple=True, metavar="FROM TO",
              help="Also open circuit 1 of line FROM-TO at the clearing instant "
                   "(repeatable); both circuits of a double line: --circuit 2 --trip "
                   "BUS FAR_BUS.")
@click.option("--esd-pct", type=float, default=None, metavar="P",
              help="Storage of P % of each generator's MVA at its HV bus "
                   "(stabctl.storage.devices.uniform_fleet, paper's bang-bang COI control).")
@click.option("--tol-ms", type=float, default=1.0, show_default=True, metavar="MS",
              help="Width of the final bracket (ms).")
@click.option("--t-max", type=float, default=1.0, show_default=True, metavar="S",
              help="Longest clearing time tried (s); a CCT above it is an error.")
@click.option("--tf", type=float, default=None, metavar="S",
              help="End of each run (s); default fault time + 5 s.")
@_model_options
@_q_limits_option
@click.option("--json", "as_json", is_flag=True, help="Print the result as JSON.")
@_reports_errors
def cct(case_name, fault, far_bus, circuit, t_fault, trip, esd_pct, tol_ms, t_max, tf,
        conventions, step, q_limits, as_json):
    """Critical clearing time of a line fault by bisection on the clearing time.

    The fault at BUS on line BUS-FAR_BUS starts at --t-fault and is cleared at both ends
    at once after the clearing time (s after the fault start); the line stays out.

    \b
    Criterion: unstable if a rotor angle leaves the centre of inertia (H*MVA weights) by
    more than pi rad before --tf (default fault time + 5 s); runs stop at separation.
    The search checks stability at zero clearing (the line trip alone), doubles the upper
    bound from 0.1 s while stable (up to --t-max), then bisects on multiples of --tol-ms.
    The CCT printed is the stable end of the final bracket (conservative).  Its numerical
    error bar: the bracket's ends rerun at half the step (the search continued there if a
    verdict changes); numerical_error_s = |CCT(h/2) - CCT(h)| (0: below the tolerance).
    \b
    Examples:
      stabctl cct kundur --fault 3 --far-bus 101
      stabctl cct miniwecc --fault 83 --far-bus 33 --json

    Bad input (unknown bus or line, unstable at zero clearing, CCT above --t-max, storage
    not available) exits with status 2 and one `error:` line.
    """
    from stabctl.io import load_case
    from stabctl.stability.cct import LineFault, critical_clearing_time, storage_fleet
    from stabctl.dynamics.simulation import Simulator

    settings = _cct_settings(tol_ms, t_max, tf)
    case = load_case(case_name)
    storage = storage_fleet(case, esd_pct)
    line_fault = LineFault(fault, far_bus, t_fault, circuit, tuple(trip))
    res = critical_clearing_time(Simulator(case, conventions=conventions, q_limits=q_limits),
                                 line_fault,
                                 storage=storage, h=step, **settings)
    out = {"case": case.name, "esd_pct": esd_pct, **res.to_dict(), "q_limits": q_limits}
    if as_json:
        _print_json(out)
    else:
        _print_cct(case.name, esd_pct, out)



def _ratings(values) -> list:
    """--esd-pct values (repeatable, comma-separated, 'none' = no storage) -> list."""
    out = []
    for v in values or ("none",):
        for item in str(v).split(","):
            item = item.strip().lower()
            try:
                out.append(None if item == "none" else float(item))
            except ValueError:
                raise InputError(f"--esd-pct {item!r}: not a number or 'none'") from None
            if out[-1] is not None:
                check_number("--esd-pct", out[-1])
    return list(dict.fromkeys(out))


def _sweep_line(key, rec) -> str:
    if rec["status"] != "ok":
        return f"{key:<34} failed: {rec['error']}"
    r, wall = rec["result"], rec.get("wall_time_s")    # none in a reproducible copy
    err = r.get("numerical_error_s")
    err = "-" if err is None else f"{1000 * err:g}"
    return (f"{key:<34} {r['cct_s']:7.3f} {r['cct_cycles']:8.2f} {err:>6} "
            f"{r['n_simulations']:5d} " + ("      -" if wall is None else f"{wall:7.2f}"))


@main.command("sweep-cct")
@click.argument("case_name", metavar="CASE")
@click.option("--faults", "faults_src", required=True, metavar="FILE.csv|DEFAULT",
              help="CSV with a header bus,far_bus[,t_fault,circuit], one fault per row; "
                   "DEFAULT: the built-in list (kundur: 3-101, 13-101; miniwecc: 83-33, "
                   "40-44; faults at 1 s).")
@click.option("--esd-pct", multiple=True, metavar="P",
              help="Storage ratings, % of machine MVA: repeat or comma-separate; 'none' "
                   "= no storage (the default). Every fault runs at every rating.")
@click.option("--out", "out_path", type=click.Path(dir_okay=False), default="results.jsonl",
              show_default=True, help="JSON-lines file, one line per finished job; "
                                      "rerunning with it skips the jobs already there.")
@click.option("--workers", type=int, default=None, metavar="N",
              help="Local worker processes (default: the available cores).")
@click.option("--scheduler", default=None, metavar="ADDRESS",
              help="Dask distributed scheduler (tcp://host:8786) to run on instead, or "
                   "'local' for a local Dask cluster of --workers processes (needs pip "
                   "install 'stabctl[dask]').")
@click.option("--retry-failed", is_flag=True, help="Rerun the jobs recorded as failed.")
@click.option("--tol-ms", type=float, default=1.0, show_default=True, metavar="MS",
              help="Width of each final bracket (ms).")
@click.option("--t-max", type=float, default=1.0, show_default=True, metavar="S",
              help="Longest clearing time tried (s).")
@click.option("--tf", type=float, default=None, metavar="S",
              help="End of each run (s); default fault time + 5 s.")
@_model_options
@_q_limits_option
@click.option("--json", "as_json", is_flag=True, help="Print every record as JSON.")
@_reports_errors
def sweep_cct(case_name, faults_src, esd_pct, out_path, workers, scheduler, retry_failed,
              tol_ms, t_max, tf, conventions, step, q_limits, as_json):
    """CCT of every (fault, storage rating) pair, in parallel, resumable.

    Each job is one `stabctl cct` search; its line in --out holds its key
    (CASE/BUS-FAR/tT_FAULT/esdP), inputs and result, or `failed` with the reason (e.g. a
    diverging run). Lines are written as jobs finish, so an interrupted sweep (Ctrl-C)
    keeps them; rerun the same command to finish it. A progress bar goes to stderr.
    Criterion and search as `stabctl cct` (see its --help).
    \b
    Examples:
      stabctl sweep-cct kundur --faults DEFAULT --esd-pct none,5,10 --out kundur.jsonl
      stabctl sweep-cct miniwecc --faults faults.csv --scheduler tcp://10.0.0.5:8786
    """
    from stabctl.io import load_case
    from stabctl.stability.cct import cct_jobs, default_faults, read_faults, storage_fleet
    from stabctl.parallel import run_sweep

    settings = _cct_settings(tol_ms, t_max, tf)
    if workers is not None and workers < 1:
        raise InputError(f"--workers must be >= 1, got {workers}")
    check_writable(out_path, "--out")
    case = load_case(case_name)
    ratings = _ratings(esd_pct)
    for p in ratings:
        storage_fleet(case, p)
    faults = default_faults(case_name) if faults_src == "DEFAULT" else read_faults(faults_src)
    jobs = cct_jobs(case_name, faults, ratings, conventions=conventions, h=step,
                    q_limits=q_limits, **settings)
    rep = run_sweep(jobs, out_path, workers=workers, scheduler=scheduler,
                    retry_failed=retry_failed)      # Ctrl-C: _reports_errors, exit 130
    if as_json:
        _print_json({"out": str(rep.out), "ran": rep.ran, "skipped": rep.skipped,
                     "failed": rep.failed, "wall_time_s": rep.wall_time_s,
                     "records": list(rep.records.values())})
        return
    click.echo(f"{'job':<34} {'CCT s':>7} {'cycles':>8} {'err ms':>6} {'sims':>5} "
               f"{'wall s':>7}")
    for key, rec in rep.records.items():
        click.echo(_sweep_line(key, rec))
    n_bad = sum(r["status"] != "ok" for r in rep.records.values())
    click.echo(f"{len(jobs)} job(s): {rep.ran} run now, {rep.skipped} already in {rep.out}; "
               f"{n_bad} failed; wall {rep.wall_time_s:.1f} s")


@main.command()
@click.argument("case_name", metavar="CASE")
@click.option("--buses", default=None, metavar="B1,B2,...",
              help="Buses to fault (default: every bus).")
@click.option("--lines", is_flag=True,
              help="Also fault the from-end of every branch with the branch tripped (N-1).")
@click.option("--tol-ms", type=float, default=1.0, show_default=True, metavar="MS",
              help="Width of each CCT bracket (ms).")
@click.option("--t-max", type=float, default=0.5, show_default=True, metavar="S",
              help="Longest clearing time tried (s); a CCT above it is recorded as failed.")
@click.option("--out", "out_path", type=click.Path(dir_okay=False), default="screening.jsonl",
              show_default=True, help="JSON-lines record, one line per finished search "
                                      "(rerunning resumes).")
@click.option("--plot", "plot_path", type=click.Path(dir_okay=False), default=None,
              metavar="FILE.png", help="Network map with buses coloured by CCT.")
@click.option("--workers", type=int, default=None, metavar="N",
              help="Local worker processes (default: the available cores).")
@click.option("--scheduler", default=None, metavar="ADDRESS",
              help="Dask distributed scheduler (tcp://host:8786), or 'local' for a local "
                   "Dask cluster of --workers processes.")
@_model_options
@_q_limits_option
@click.option("--json", "as_json", is_flag=True, help="Print every row as JSON.")
@_reports_errors
def screen(case_name, buses, lines, tol_ms, t_max, out_path, plot_path, workers, scheduler,
           conventions, step, q_limits, as_json):
    """Contingency screening: CCT of a three-phase fault at every bus (and with --lines of
    every branch fault with the branch tripped), in parallel and resumable.

    Bus faults are cleared without loss of a line (PST sw_con type 7); the CCT search and
    its stability criterion are `stabctl cct`'s. Rows are sorted by CCT, most critical
    first; a failed search (e.g. voltage collapse during the fault) is listed with its
    reason.
    """
    from stabctl.io import load_case
    from stabctl.stability.screening import screen as run_screen

    case = load_case(case_name)
    bus_list = None if buses is None else _bus_list(buses)
    plot_p = _check_suffix(plot_path, _PLOT_SUFFIXES, "--plot")
    check_writable(out_path, "--out")
    settings = _cct_settings(tol_ms, t_max, None)
    rows = run_screen(case_name, out_path, buses=bus_list, lines=lines, tol=settings["tol"],
                      t_max=t_max, workers=workers, scheduler=scheduler,
                      conventions=conventions, h=step, q_limits=q_limits)
    rows.sort(key=lambda r: r.get("cct_s", float("inf")))
    if plot_p is not None:
        from stabctl.plotting import figures as plotting
        plotting.screening_map(case, rows, plot_p)
    if as_json:
        _print_json(rows)
        return
    click.echo(f"{'fault':<22} {'CCT s':>7} {'cycles':>7} {'err ms':>6}  separated / reason")
    for r in rows:
        where = f"bus {r['bus']}" + (f" line to {r['far_bus']}" if r["far_bus"] else "")
        if r["status"] == "ok":
            err = "-" if r["numerical_error_s"] is None else f"{1000 * r['numerical_error_s']:g}"
            click.echo(f"{where:<22} {r['cct_s']:7.3f} {r['cct_cycles']:7.2f} {err:>6}  "
                       f"{r['separated']}")
        else:
            click.echo(f"{where:<22} {'-':>7} {'-':>7}  {r['error'][:70]}")


def _bus_list(text: str) -> list[int]:
    """--buses B1,B2,...: bus numbers (InputError naming the first that is not one)."""
    out = []
    for item in (b.strip() for b in text.split(",")):
        if item:
            try:
                out.append(int(item))
            except ValueError:
                raise InputError(f"--buses {item!r}: not a bus number") from None
    if not out:
        raise InputError("--buses: no bus number given")
    return out


# -- small-signal modes ------------------------------------------------------------------

@main.command()
@click.argument("case_name", metavar="CASE")
@click.option("--no-pss", is_flag=True,
              help="Analyse the case with its PSS removed (pss_con empty).")
@click.option("--areas", "n_areas", type=int, default=None, metavar="N",
              help="Number of coherent areas for the local/inter-area classification "
                   "(default: from a gap in the electromechanical frequencies, docs/modal.md).")
@click.option("--report", is_flag=True,
              help="Write OUT/eig_<case>[_nopss].md with the eigenvalue plot, mode-shape "
                   "compass plots and participation bar charts (PNG).")
@click.option("--out", "out_dir", default="reports", show_default=True, metavar="DIR",
              help="Report directory (with --report).")
@click.option("--conventions", type=click.Choice(["ieee", "pstess"]), default="ieee",
              show_default=True, help="Model conventions (docs/conventions.md); the same "
                                      "linear model at a point inside every limit.")
@_q_limits_option
@click.option("--json", "as_json", is_flag=True, help="Print every mode as JSON.")
@_reports_errors
def eig(case_name, no_pss, n_areas, report, out_dir, conventions, q_limits, as_json):
    """Small-signal modes: linearise CASE at its power flow and list its modes.

    The simulator's own equations are linearised by central differences (PSTess svm_mgen's
    method; docs/modal.md). Printed: the electromechanical modes (0.1-2.5 Hz, dominated by
    rotor angle and speed states) with frequency (Hz), damping ratio, dominant machines,
    and local / inter-area by their mode shapes; --json prints every mode (eigenvalue,
    frequency, damping, kind, dominant states, and for electromechanical modes the
    coherent groups, speed mode shape and the ESD bus with the largest residue).
    \b
    Examples:
      stabctl eig kundur --report
      stabctl eig kundur --no-pss --json
      stabctl eig miniwecc --areas 3 --report

    Bad input (unknown case, --areas out of range, --out a file) exits with status 2 and
    one `error:` line; nothing is written then.
    """
    import numpy as np

    from stabctl.io import load_case
    from stabctl.studies.eigenvalues import eig_study, study_json, write_report

    if Path(out_dir).exists() and not Path(out_dir).is_dir():
        raise InputError(f"--out {out_dir} is not a directory")
    if report:
        check_writable(out_dir, "--out", directory=True)
    st = eig_study(load_case(case_name), no_pss=no_pss, n_areas=n_areas, conventions=conventions,
                   q_limits=q_limits)
    written = [str(write_report(st, out_dir))] if report else []
    if as_json:
        _print_json({**study_json(st), "files": written})
        return
    ma = st.ma
    click.echo(f"case {st.case.name}{' without PSS' if no_pss else ''}: {st.sys.nstates} "
               f"states; linearised in {st.t_linearise:.2f} s, analysed in {st.t_analyse:.2f} s")
    click.echo(f"angle-reference mode {ma.eigenvalues[ma.reference_mode].real:.2e} 1/s "
               "(excluded from damping statistics)")
    click.echo(f"{'mode':>5} {'f Hz':>7} {'damping':>8}  {'kind':<10} machines")
    em = ma.electromechanical
    for i in em[np.argsort(ma.freq_hz[em])]:
        g1, g2 = ma.groups(i)
        against = " ".join(f"G{k}" for k in g2[:6]) or "-"
        click.echo(f"{i:5d} {ma.freq_hz[i]:7.3f} {ma.damping[i]:8.4f}  {ma.kind[i]:<10} "
                   f"{' '.join(f'G{k}' for k in g1[:6])} vs {against}")
    for w in written:
        click.echo(f"wrote {w}")


# -- speed estimation from PMU data ------------------------------------------------------

@main.command()
@click.argument("case_name", metavar="CASE")
@_line_fault_options
@click.option("--clear-cycles", type=float, default=6.0, show_default=True, metavar="N",
              help="Clearing after N cycles, both ends.")
@click.option("--tf", type=float, default=10.0, show_default=True, metavar="S",
              help="End of the fault run (s).")
@click.option("--rate", type=float, default=60.0, show_default=True, metavar="FPS",
              help="PMU reporting rate (frames/s): 10, 12, 15, 20, 30, 60 or 120.")
@click.option("--latency-ms", type=float, default=50.0, show_default=True, metavar="MS",
              help="Delay from a frame's time stamp to its arrival (ms).")
@click.option("--drop", type=float, default=0.0, show_default=True, metavar="P",
              help="Probability that a frame is lost.")
@click.option("--tve-pct", type=float, default=1.0, show_default=True,
              help="Total vector error limit (%), C37.118.1 Table 3.")
@click.option("--fe-hz", type=float, default=0.005, show_default=True,
              help="Frequency error limit (Hz), C37.118.1 Table 4.")
@click.option("--rfe-hz-s", type=float, default=0.01, show_default=True,
              help="ROCOF error limit (Hz/s), C37.118.1 Table 4.")
@click.option("--k-sigma", type=float, default=3.0, show_default=True,
              help="The limits are this many standard deviations of the errors.")
@click.option("--pmu-at", type=click.Choice(["terminal", "hv"]), default="terminal",
              show_default=True, help="PMU of each generator at its terminal or HV bus.")
@click.option("--esd-pct", type=float, default=None, metavar="P",
              help="Storage of P % of each generator's MVA at its HV bus in the fault run, "
                   "controlled on the true speeds (paper's Table 3).")
@click.option("--runs", type=int, default=20, show_default=True, metavar="N",
              help="Monte-Carlo runs (PMU noise seeds S, S+1, ..., S+N-1).")
@click.option("--seed", type=int, default=0, show_default=True, metavar="S",
              help="Seed of the first run.")
@click.option("--settle-ms", type=float, default=100.0, show_default=True, metavar="MS",
              help="Errors are taken from this long after the clearing to the end.")
@click.option("--ambient-s", type=float, default=60.0, show_default=True, metavar="S",
              help="Length of the runs without fault for the false ESD actions (0: skip).")
@click.option("--ambient-pct", type=float, default=1.0, show_default=True, metavar="P",
              help="Ambient load fluctuation in the runs without fault: standard deviation "
                   "of every load's P (%; 0: PMU noise only).")
@click.option("--ambient-tau-s", type=float, default=2.0, show_default=True, metavar="T",
              help="Correlation time of the ambient load fluctuation (s).")
@click.option("--ambient-runs", type=int, default=5, show_default=True, metavar="N",
              help="Runs without fault (load and PMU noise seeds S..S+N-1).")
@click.option("--deadband-hz", type=float, default=0.1, show_default=True,
              help="ESD deadband on f_i - f_COI for the false actions (Hz).")
@click.option("--coi", type=click.Choice(["system", "rest"]), default="system",
              show_default=True, help="COI of the whole system or of the rest of it.")
@click.option("--closed-loop", is_flag=True,
              help="Instead: simulate the fault with the ESDs (--esd-pct) commanded by each "
                   "estimator in the loop (ideal, raw, kf, ekf; seed S) and report the "
                   "verdict, switchings and false actions.")
@click.option("--cct", is_flag=True,
              help="Instead: CCT of the fault line with each estimator in the loop at "
                   "--esd-pct over --runs seeds, in parallel; mean and spread (cycles).")
@_model_options
@click.option("--json", "as_json", is_flag=True, help="Print the figures as JSON.")
@_reports_errors
def estimate(case_name, fault, far_bus, t_fault, clear_cycles, tf, rate, latency_ms, drop,
             tve_pct, fe_hz, rfe_hz_s, k_sigma, pmu_at, esd_pct, runs, seed, settle_ms,
             ambient_s, ambient_pct, ambient_tau_s, ambient_runs, deadband_hz, coi,
             closed_loop, cct, conventions, step, as_json):
    """Machine and COI speed estimation from simulated PMU data, against the truth.

    The fault run is simulated once (with --esd-pct, storage acts on the true speeds);
    then, per Monte-Carlo run, every generator's PMU stream is drawn (IEEE C37.118.1
    noise limits read as k-sigma bounds, latency, lost frames) and fed frame by frame to
    the raw PMU frequency, the baseline Kalman filter on frequency/ROCOF (kf) and the
    swing-equation EKF (ekf).

    \b
    Printed per estimator, mean +- standard deviation over the runs (mHz): RMSE of the
    machine speeds, of the COI speed and of the relative speeds f_i - f_COI the ESD
    controllers use, at the frame time stamps from --settle-ms after the clearing to
    --tf; the relative-speed RMSE at each frame's arrival (latency included), as
    delivered and forecast to the arrival; the fraction of normalised innovations
    squared inside their 95 % chi-square interval (consistency: about 0.95).  Then, on
    --ambient-runs runs without fault of --ambient-s with ambient load fluctuation (every
    load's P an Ornstein-Uhlenbeck process of --ambient-pct standard deviation and
    --ambient-tau-s correlation time, stabctl.estimation.ambient), the number of ESD actions (Table 3
    rule with --deadband-hz) each estimate would trigger (all are false), the largest
    |f_i - f_COI| and the largest standard deviation of f_i - f_COI (true: the ambient
    spread).
    """
    from dataclasses import replace

    from stabctl.estimation import ambient as am
    from stabctl.studies import estimation as study
    from stabctl.io import load_case
    from stabctl.dynamics.events import fault_with_clearing
    from stabctl.estimation.pmu import PMUSettings
    from stabctl.dynamics.simulation import Simulator
    from stabctl.storage.devices import BangBangCOI, uniform_fleet

    for name, value in (("--tf", tf), ("--runs", runs), ("--deadband-hz", deadband_hz)):
        if not value > 0:
            raise InputError(f"{name} must be > 0, got {value:g}")
    if min(settle_ms, ambient_s, seed) < 0 or ambient_runs < 1:
        raise InputError("--settle-ms, --ambient-s and --seed must be >= 0, --ambient-runs >= 1")
    ambient = am.AmbientLoad(ambient_pct, ambient_tau_s, seed)
    settings = PMUSettings(rate=rate, tve=tve_pct / 100, fe_hz=fe_hz, rfe_hz_s=rfe_hz_s,
                           k_sigma=k_sigma, latency_s=latency_ms / 1000, drop_prob=drop)
    case = load_case(case_name)
    ev = fault_with_clearing(case, fault, far_bus, t_fault, clear_cycles)
    if closed_loop or cct:
        if esd_pct is None:
            raise InputError("--closed-loop and --cct need --esd-pct")
        out = _estimate_loop(case, ev, fault, far_bus, t_fault, tf, settings, esd_pct, runs,
                             seed, deadband_hz, coi, cct, conventions, step)
        click.echo(json.dumps(out, indent=1) if as_json else "\n".join(out["lines"]))
        return
    window = (max(ev.times()) + settle_ms / 1000, tf)
    if not window[0] < tf:
        raise InputError(f"--tf {tf:g} s ends before the errors start ({window[0]:g} s)")
    fleet = None if esd_pct is None else uniform_fleet(case, esd_pct)
    sim = Simulator(case, injection_buses=() if fleet is None else fleet.buses,
                    conventions=conventions)
    res = sim.run([ev], t_end=tf, storage=fleet, h=step)
    figures = study.monte_carlo(case, res, settings, runs, seed, window, pmu_at, coi)
    actions = None
    if ambient_s > 0:
        flat = [am.simulate(sim, ambient_s, replace(ambient, seed=seed + r), rate)
                for r in range(ambient_runs)]
        actions = study.false_actions(case, flat, settings, seed,
                                      BangBangCOI(deadband_hz=deadband_hz, coi=coi), pmu_at)
    out = {"case": case.name, "fault": {"bus": fault, "far_bus": far_bus, "t_fault_s": t_fault,
                                        "clear_cycles": clear_cycles},
           "esd_pct": esd_pct, "pmu": {**settings.__dict__, "at": pmu_at}, "runs": runs,
           "seed": seed, "window_s": list(window), "stable": res.stable,
           "estimators": figures, "false_actions": actions,
           "ambient": {"t_s": ambient_s, "deadband_hz": deadband_hz, "pct": ambient_pct,
                       "tau_s": ambient_tau_s, "runs": ambient_runs}}
    if as_json:
        _print_json(out)
        return
    _print_estimate(out)


def _estimate_loop(case, ev, fault, far_bus, t_fault, tf, settings, esd_pct, runs, seed,
                   deadband_hz, coi, cct, conventions, step) -> dict:
    """`estimate --closed-loop` / `--cct`: figures and text lines."""
    from stabctl.estimation import closed_loop as cl
    from stabctl.dynamics.simulation import Simulator
    from stabctl.storage.devices import BangBangCOI

    rate, lat = settings.rate, settings.latency_s
    if cct:
        with tempfile.TemporaryDirectory() as tmp:
            table = cl.cct_study(case.name, fault, far_bus, [esd_pct], runs, Path(tmp) / "cct.jsonl",
                                 seed=seed, rate=rate, latency=lat, conventions=conventions,
                                 h=step)[esd_pct]
        lines = [f"CCT of line {fault}-{far_bus}, ESD {esd_pct:g} %, {rate:g} frames/s, latency "
                 f"{1000 * lat:g} ms, {runs} seeds from {seed} (cycles):"]
        lines += [f"  {e:5} " + ("failed" if s["mean"] is None else
                                 f"{s['mean']:7.2f} +- {s['std']:.2f} ({s['min']:.2f}..{s['max']:.2f})")
                  + f"  runs {s['runs']}, failed {s['failed']}" for e, s in table.items()]
        return {"cct_cycles": table, "lines": lines}
    sim, rows, lines = Simulator(case, conventions=conventions), {}, []
    control = BangBangCOI(deadband_hz=deadband_hz, coi=coi)
    for e in cl.ESTIMATORS:
        run = cl.run_closed_loop(sim, [ev], tf, esd_pct, e, rate, lat, seed,
                                 settings=settings, control=control, h=step)
        rows[e] = {"stable": run.result.stable,
                   "switchings": len(run.result.meta.get("switchings", [])),
                   "false_actions": cl.false_actions(run, deadband_hz)}
        lines.append(f"  {e:5} {'stable' if rows[e]['stable'] else 'UNSTABLE':8} switchings "
                     f"{rows[e]['switchings']:5d}  false actions {rows[e]['false_actions']}")
    head = f"closed loop, fault at bus {fault} line {fault}-{far_bus}, ESD {esd_pct:g} %, seed {seed}:"
    return {"closed_loop": rows, "lines": [head, *lines]}


def _print_estimate(d) -> None:
    """The `estimate` report as text."""
    f, p = d["fault"], d["pmu"]
    click.echo(f"case {d['case']}: fault at bus {f['bus']} on line {f['bus']}-{f['far_bus']} "
               f"at {f['t_fault_s']:g} s, cleared after {f['clear_cycles']:g} cycles"
               + ("" if d["esd_pct"] is None else f"; storage {d['esd_pct']:g} % (true speeds)")
               + ("" if d["stable"] else "; the run loses synchronism"))
    click.echo(f"PMUs at the {p['at']} buses: {p['rate']:g} frames/s, TVE {100 * p['tve']:g} %, "
               f"FE {p['fe_hz']:g} Hz, RFE {p['rfe_hz_s']:g} Hz/s ({p['k_sigma']:g} sigma), "
               f"latency {1000 * p['latency_s']:g} ms, lost {p['drop_prob']:g}; "
               f"{d['runs']} runs, seeds {d['seed']}..{d['seed'] + d['runs'] - 1}")
    w = d["window_s"]
    click.echo(f"errors in mHz from {w[0]:.3f} s to {w[1]:g} s, mean +- std over the runs:")
    cols = (("speed", "speed_rmse_mhz"), ("COI", "coi_rmse_mhz"), ("relative", "rel_rmse_mhz"),
            ("rel. max", "rel_max_mhz"), ("at arrival", "rel_arrival_rmse_mhz"),
            ("forecast", "rel_forecast_rmse_mhz"), ("NIS in 95%", "nis_inside"))
    click.echo(f"{'estimator':9}" + "".join(f"{c:>17}" for c, _ in cols))
    for name, fig in d["estimators"].items():
        cells = [f"{'-':>17}" if fig[k]["mean"] is None else
                 f"{fig[k]['mean']:>10.3f} +-{fig[k]['std']:<5.3f}" for _, k in cols]
        click.echo(f"{name:9}" + "".join(cells))
    if d["false_actions"] is not None:
        a = d["ambient"]
        click.echo(f"no fault, {a['runs']} runs of {a['t_s']:g} s, ambient load {a['pct']:g} % "
                   f"(tau {a['tau_s']:g} s), deadband {1000 * a['deadband_hz']:g} mHz: false ESD "
                   "actions per run (largest |f_i - f_COI|, largest std of f_i - f_COI; mHz)")
        for name, fig in d["false_actions"].items():
            click.echo(f"  {name:5} {fig['actions']['mean']:8.2f}  "
                       f"({fig['max_rel_mhz']['mean']:.2f}, {fig['std_rel_mhz']['mean']:.2f})")

# -- storage placement -------------------------------------------------------------------

def _print_placement(case_name, d) -> None:
    click.echo(f"case {case_name}: {d['total_mw']:.1f} MW of storage at {d['n_sites']} "
               f"site(s); {'VERIFIED' if d['verified'] else 'NOT verified'} by simulation "
               f"({d['message']})")
    click.echo(f"{'bus':>6} {'machine':>8} {'MW':>9}")
    for r in d["allocation"]:
        click.echo(f"{r['bus']:>6} {r['machine']:>8} {r['mw']:9.1f}")
    click.echo(f"{'contingency':<16} {'no ESD s':>9} {'target s':>9} {'with s':>8}  met")
    for c in d["contingencies"]:
        click.echo(f"{c['name']:<16} {c['cct_no_storage_s']:9.3f} {c['target_cct_s']:9.3f} "
                   f"{c['cct_s']:8.3f}  {'yes' if c['met'] else 'NO'}")
    for m in d.get("damping", []):
        click.echo(f"mode {m['freq_hz']:.3f} Hz: damping {m['damping']:.4f}")
    solve = max(d["solve_times_s"], default=0.0)
    click.echo(f"{len(d['iterations'])} allocation(s) simulated, wall {d['wall_time_s']:.1f} s, "
               f"longest convex solve {1000 * solve:.1f} ms")


@main.command()
@click.argument("case_name", metavar="CASE")
@click.option("--contingencies", "faults_src", required=True, metavar="FILE.csv|DEFAULT",
              help="CSV with a header bus,far_bus[,t_fault,circuit], one line fault per "
                   "row (cleared at both ends, line tripped); DEFAULT: the built-in list "
                   "of `stabctl sweep-cct`.")
@click.option("--target-cct-gain", type=float, required=True, metavar="PCT",
              help="Required CCT of every contingency: its CCT without storage raised by "
                   "PCT %.")
@click.option("--zeta-min", type=float, default=None, metavar="Z",
              help="Least damping ratio of every electromechanical mode (bang-bang ESDs "
                   "as their describing-function gain at --amplitude-hz).")
@click.option("--max-sites", type=int, default=None, metavar="N",
              help="At most N sites (reweighted l1, then the N largest).")
@click.option("--max-site-pct", type=float, default=50.0, show_default=True, metavar="P",
              help="Largest rating per site, % of its generator's MVA.")
@click.option("--site-cost", type=float, default=0.0, show_default=True, metavar="C",
              help="Cost of each site in MW-equivalents (fewer, larger sites).")
@click.option("--amplitude-hz", type=float, default=0.2, show_default=True,
              help="Relative-speed amplitude at which the damping is required (Hz).")
@click.option("--hysteresis-hz", type=float, default=0.0, show_default=True,
              help="ESD controller hysteresis (Hz); deadband 100 mHz, gate 0.8 pu.")
@click.option("--tol-ms", type=float, default=1.0, show_default=True, metavar="MS",
              help="CCT tolerance (ms).")
@click.option("--max-iter", type=int, default=10, show_default=True,
              help="Allocations simulated at most.")
@click.option("--workers", type=int, default=None, metavar="N",
              help="Worker processes (default: the available cores, at most one per "
                   "contingency).")
@_model_options
@click.option("--json", "as_json", is_flag=True, help="Print the result as JSON.")
@_reports_errors
def place(case_name, faults_src, target_cct_gain, zeta_min, max_sites, max_site_pct,
          site_cost, amplitude_hz, hysteresis_hz, tol_ms, max_iter, workers, conventions, step,
          as_json):
    """Least-MW energy storage (sites and ratings) that raises the CCT of every contingency
    by --target-cct-gain, verified by nonlinear simulation.

    \b
    Candidate sites: every generator's HV bus, the ESD driven by that generator (the
    paper's bang-bang law). Each iteration solves a linear program (cvxpy, Clarabel)
    whose constraints are the CCTs linearised in the ratings (SIME margin of simulated
    runs), then simulates the CCT of every contingency at the proposed allocation (in
    parallel) and updates the constraints from those runs (docs/placement.md).
    \b
    Examples:
      stabctl place kundur --contingencies DEFAULT --target-cct-gain 10
      stabctl place miniwecc --contingencies faults.csv --target-cct-gain 40 --max-sites 3

    Exit status: 0 verified; 1 not verified within --max-iter; 2 bad input or infeasible
    (the `error:` line names the contingency).
    """
    from stabctl.io import load_case
    from stabctl.stability.cct import default_faults, read_faults
    from stabctl.placement.program import candidate_sites
    from stabctl.placement.loop import baseline, place as run_place, with_gain
    from stabctl.storage.devices import BangBangCOI
    from stabctl.parallel import default_workers

    settings = _cct_settings(tol_ms, 1.0, None)
    if workers is not None and workers < 1:
        raise InputError(f"--workers must be >= 1, got {workers}")
    if max_sites is not None and max_sites < 1:
        raise InputError(f"--max-sites must be >= 1, got {max_sites}")
    if zeta_min is not None and not 0 <= zeta_min < 1:
        raise InputError(f"--zeta-min must be in [0, 1), got {zeta_min:g}")
    if not target_cct_gain > 0:
        raise InputError(f"--target-cct-gain must be > 0 %, got {target_cct_gain:g}")
    case = load_case(case_name)
    faults = default_faults(case_name) if faults_src == "DEFAULT" else read_faults(faults_src)
    sites = candidate_sites(case, max_site_pct)
    ctrl = BangBangCOI(hysteresis_hz=hysteresis_hz)
    n = min(workers or default_workers(), len(faults))
    kw = {"sites": sites, "tol": settings["tol"], "workers": n, "controller": ctrl,
          "conventions": conventions, "h": step}
    say = (lambda msg: None) if as_json else (lambda msg: click.echo(msg, err=True))
    base = baseline(case_name, faults, **kw)
    result = run_place(case_name, with_gain(faults, base, target_cct_gain, settings["tol"]),
                       zeta_min=zeta_min, max_sites=max_sites, site_cost=site_cost,
                       amplitude_hz=amplitude_hz, max_iter=max_iter, base=base,
                       progress=say, **kw)
    out = {"case": case.name, "target_cct_gain_pct": target_cct_gain, **result.to_dict()}
    if as_json:
        _print_json(out)
    else:
        _print_placement(case.name, out)
    if not result.verified:
        sys.exit(1)


# -- PSS/E import -------------------------------------------------------------------------

@main.command("import-psse")
@click.argument("raw_path", metavar="RAW", type=click.Path(dir_okay=False))
@click.argument("dyr_path", metavar="[DYR]", required=False, type=click.Path(dir_okay=False))
@click.option("-o", "--out", "out_path", required=True, metavar="CASE.json",
              type=click.Path(dir_okay=False), help="The stabctl case file to write.")
@click.option("--skip-unsupported", is_flag=True,
              help="Leave out records stabctl cannot represent (listed as warnings) "
                   "instead of refusing the files.")
@click.option("--loads", type=click.Choice(["impedance", "raw"]), default="impedance",
              show_default=True,
              help="Load model in dynamic runs: all constant impedance, or the RAW "
                   "composition (constant power, current, admittance; PST's network "
                   "solution may fail with constant power under deep voltage dips).")
@click.option("--conventions", type=click.Choice(["pst", "andes"]), default="pst",
              show_default=True,
              help="How to read the DYR models: PST's (machines with speed effects, "
                   "EXDC2 limits times the terminal voltage) or ANDES 2.0's (neither), "
                   "to compare with ANDES like for like.")
@click.option("--json", "as_json", is_flag=True, help="Print the summary as JSON.")
@_reports_errors
def import_psse(raw_path, dyr_path, out_path, skip_unsupported, loads, conventions, as_json):
    """Convert a PSS/E RAW file (v32-34) and optionally a DYR file to a stabctl case.

    The case (stabctl's JSON format) is usable as CASE by simulate, cct, eig and screen.
    Unsupported records are named as FILE:LINE RECORD; without --skip-unsupported they
    stop the import (exit status 2, nothing written).

    \b
    Example:
      stabctl import-psse kundur.raw kundur_full.dyr -o kundur_psse.json
      stabctl simulate kundur_psse.json --fault 7 --far-bus 8 --tf 5
    """
    from stabctl.io.psse import import_psse as run_import

    out = _check_suffix(out_path, (".json",), "--out")
    case, left_out = run_import(raw_path, dyr_path,
                                "skip" if skip_unsupported else "error", loads, conventions)
    _write_case_atomically(case, out)
    summary = {"case": str(out), "name": case.name, "buses": case.n_bus,
               "branches": len(case.branches), "machines": len(case.machines),
               "exciters": len(case.exciters), "pss": len(case.pss),
               "governors": len(case.governors), "nonconforming_loads": len(case.loads),
               "left_out": list(left_out)}
    if as_json:
        _print_json(summary)
        return
    click.echo(f"wrote {out}: {case.n_bus} buses, {len(case.branches)} branches, "
               f"{len(case.machines)} machines, {len(case.exciters)} exciters, "
               f"{len(case.pss)} PSS, {len(case.governors)} governors; "
               f"{len(left_out)} record(s) left out")


def _write_case_atomically(case, path: Path) -> None:
    """Write the case JSON to a temporary file beside ``path``, then rename it."""
    from stabctl.io.pst import write_case_json
    from stabctl.parallel import atomic_write

    atomic_write(path, lambda tmp: write_case_json(case, tmp), mode=None)


if __name__ == "__main__":  # pragma: no cover
    main()
