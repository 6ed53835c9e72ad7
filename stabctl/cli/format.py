"""Text and JSON output of the `stabctl` commands, in one place.

Every function here formats; none computes a result.
"""

from __future__ import annotations

import json

import click

from stabctl.errors import SimulationError, StabctlError, counted


def one_line(exc) -> str:
    """The error message on one line; a diverged run also says where it stopped.

    Parameters
    ----------
    exc : Exception

    Returns
    -------
    str
    """
    msg = " ".join(undecoded(str(exc)).split())
    res = getattr(exc, "result", None)
    if isinstance(exc, SimulationError) and res is not None and len(res.t) and "t = " not in msg:
        msg += f" (run stopped; last computed point t = {float(res.t[-1]):.4f} s)"
    return msg


def undecoded(text: str) -> str:
    """`text` with the bytes of a name that is not UTF-8 (which Python holds as lone
    surrogates, ``'x\\udcff.raw'``) shown as escapes of those bytes, ``x\\xff.raw``:
    every message names such a file one way (round 44: ``x\\udcff.raw`` in one,
    ``b'z\\xff.csv'`` in another).

    Parameters
    ----------
    text : str

    Returns
    -------
    str
    """
    return text.encode("utf-8", "surrogateescape").decode("utf-8", "backslashreplace")


def shown(path) -> str:
    """A file's name as a line of output shows it: as it is, or quoted with its control
    characters escaped (``'o\\nut.csv'``) when it has any, so that the line stays one
    (``wrote o`` and ``ut.csv`` were two).

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    str
    """
    text = str(path)
    if text.isprintable():
        return text
    text = undecoded(text)
    return text if text.isprintable() else repr(text)


def print_json(obj) -> None:
    """Print ``obj`` as indented JSON (numpy numbers as floats).

    Parameters
    ----------
    obj : JSON-able object
    """
    click.echo(json.dumps(obj, indent=2, default=float))


def describe_sw_con(case) -> str | None:
    """One line for the data file's own disturbance (what --pstess-default runs).

    Parameters
    ----------
    case : stabctl.case.Case

    Returns
    -------
    str or None
        None when the case has no sw_con.
    """
    from stabctl.dynamics.events import from_sw_con

    if case.sw_con is None:
        return None
    try:
        evs = from_sw_con(case)
    except StabctlError as exc:
        return f"unsupported ({exc})"
    what = "; ".join(map(str, evs)) or "no disturbance"
    return f"{what}; {float(case.sw_con[-1, 0]):g} s, data-file step {float(case.sw_con[0, 6]):g} s"


def step_text(h: float) -> str:
    """An integration step for a person: in ms to four significant digits (0.00634328 s ->
    '6.343 ms', 1/120 s -> '8.333 ms'); JSON keeps the step in s, whole."""
    return f"{1000 * h:.4g} ms"


def plot_writer(result, title: str, case):
    """The writer of a run's plot (stabctl.plotting.figures.simulation_overview) for
    `stabctl.parallel.atomic_writes`, which writes it with the command's other outputs.

    Parameters
    ----------
    result : SimulationResult
    title : str
    case : Case
        The run's case: its machines named by number and bus (`Case.machine_name`), its
        system base (MVA) for the device powers.

    Returns
    -------
    callable
        ``write(path)``.
    """
    from stabctl.plotting.figures import simulation_overview

    def write(tmp):
        simulation_overview(result, tmp, title=title, base_mva=case.base_mva, case=case)

    return write


#: what `describe_esd` and `print_cct` call the devices of each storage model
_ESD_NAMES = {"ideal": "ESDs", "wecc": "WECC batteries"}


def describe_esd(esd: dict, short: bool = False) -> str:
    """One line on the storage of `simulate --esd-pct` (short: for a plot title).

    Parameters
    ----------
    esd : dict
        The ``esd`` settings of `simulate --json`.
    short : bool

    Returns
    -------
    str
    """
    where = "" if short else " at the generator HV buses"
    control = "bang-bang COI control" if short else esd["control"]
    return (
        f"storage: {esd['devices']} {_ESD_NAMES[esd.get('model', 'ideal')]} of "
        f"{esd['pct_of_machine_mva']:g} % of machine MVA{where}, {control}, "
        f"deadband {esd['deadband_hz']:g} Hz, "
        f"{'gate' if short else 'voltage gate'} {esd['v_gate_pu']:g} pu, {esd['coi']} COI"
        + (f", hysteresis {esd['hysteresis_hz']:g} Hz" if esd["hysteresis_hz"] else "")
        + (
            f"; none at the infinite bus(es) {', '.join(esd['none_at'])} (H = 0)"
            if esd.get("none_at") and not short
            else ""
        )
    )


def print_storage(esd: dict, result) -> None:
    """Print the storage lines of `simulate`'s text output: settings, totals, devices.

    Parameters
    ----------
    esd : dict
        The ``esd`` settings of `simulate --json`.
    result : SimulationResult
    """
    info = result.meta.get("storage", [])
    active = [d for d in info if d["switchings"] > 0]
    click.echo(f"  {describe_esd(esd)}")
    click.echo(
        f"  {counted(sum(d['switchings'] for d in info), 'switching')}, {len(active)} of "
        f"{counted(len(info), 'device')} acted; absorbed "
        f"{sum(d['energy_absorbed_mj'] for d in info):.1f} MJ, delivered "
        f"{sum(d['energy_delivered_mj'] for d in info):.1f} MJ" + _chattering(info)
    )
    if active:
        click.echo(
            f"  {'device':>6} {'bus':>6} {'machine':>7} {'MW':>7} {'switchings':>10} "
            f"{'absorbed MJ':>11} {'delivered MJ':>12} {'peak MW':>8}"
        )
    for d in active:
        click.echo(
            f"  {d['device']:6d} {d['bus']:6d} {'G' + str(d['machine']):>7} "
            f"{d['pmax_mw']:7.1f} {d['switchings']:10d} {d['energy_absorbed_mj']:11.1f} "
            f"{d['energy_delivered_mj']:12.1f} {d['peak_power_mw']:8.1f}"
        )
    for d in info:
        if d.get("commanded_idle_s", 0.0) > 0:
            click.echo(
                f"  device {d['device']} (bus {d['bus']}): the network took none of its power "
                f"for {d['commanded_idle_s']:.3g} s of the {d['commanded_s']:.3g} s it was "
                "commanded (its bus below the 0.5 pu low-voltage switch, or its energy at "
                "a limit)"
            )


def _chattering(info: list) -> str:
    """The storage summary's words for chattering (switchings within CHATTER_S of the
    device's previous one, `stabctl.dynamics.driver.CHATTER_S`; the JSON's per device):
    the text never said it, though 8 of a run's 18 switchings chattered."""
    from stabctl.dynamics.driver import CHATTER_S

    n = sum(d.get("chattering", 0) for d in info)
    if not n:
        return ""
    return (
        f"; {n} of the switchings chattering (within {CHATTER_S * 1e3:g} ms of the device's "
        "previous one)"
    )


def machine_list(case, numbers) -> str:
    """Machines named for a reader, ``"G1 (bus 1), G2 (bus 2)"`` (`Case.machine_name`).

    Parameters
    ----------
    case : Case
    numbers : iterable of int
        Machine numbers of the case.

    Returns
    -------
    str
    """
    return ", ".join(case.machine_name(m) for m in numbers)


def islanding_lines(case, islanded, tripped=(), timed: bool = True) -> list[str]:
    """The islanding and trips of a run or a search, one line each, in time order.

    Parameters
    ----------
    case : Case
        The case (its machines named by number and bus, its base for the load shed).
    islanded : sequence of dict
        ``SimulationResult.meta["islanded"]`` (`stabctl.dynamics.driver.islanding_log`):
        buses cut from every machine (``load_shed_pu``) or an island apart from the main
        grid (``machines``).
    tripped : sequence of dict, optional
        ``SimulationResult.meta["tripped"]``: machines tripped (``t_s``, ``machines``).
    timed : bool, optional
        Each line starts with its time (default); False: without (a CCT search's
        islanding, whose time is its probes' clearing instant).

    Returns
    -------
    list of str
    """
    lines = []
    for entry in sorted([*islanded, *tripped], key=lambda e: e["t_s"]):
        at = f"at t = {entry['t_s']:g} s " if timed else ""
        if "load_shed_pu" in entry:
            P, Q = entry["load_shed_pu"]
            lines.append(
                f"{at}bus(es) {entry['buses']} islanded from every generator: de-energised, "
                + _shed(P * case.base_mva, Q * case.base_mva)
            )
        elif "buses" in entry:
            lines.append(
                f"{at}bus(es) {entry['buses']} islanded with machine(s) "
                f"{machine_list(case, entry['machines'])} apart from the main grid: "
                "lost, out of the loss-of-synchronism criterion"
            )
        else:
            lines.append(
                f"{at}machine(s) {machine_list(case, entry['machines'])} tripped: out of "
                "the loss-of-synchronism criterion"
            )
    return lines


def time_decimals(tol_s: float | None) -> int:
    """Decimals that print every multiple of a CCT search's tolerance apart (its clearing
    times are multiples of it): 3 for 1 ms and above, 4 for 0.1 ms, 5 for 0.25 ms (a fixed
    3 printed ``stable at 0.154 s, unstable at 0.154 s`` at 0.1 ms).

    Parameters
    ----------
    tol_s : float or None
        The tolerance, s; None: 3 decimals.

    Returns
    -------
    int
        At least 3, at most 9.
    """
    if tol_s is None or not tol_s > 0:
        return 3
    for d in range(3, 10):
        scaled = tol_s * 10**d
        if abs(scaled - round(scaled)) <= 1e-6 * scaled:
            return d
    return 9


def cycle_decimals(tol_s: float | None) -> int:
    """Decimals of a time in cycles at a tolerance `tol_s` (`time_decimals`): 2 for 1 ms
    and above, one fewer than the seconds' beyond (a cycle is 16.7-20 ms)."""
    return max(2, time_decimals(tol_s) - 1)


def end_note(t_s: float, concerns) -> str:
    """What a stable run ends with off a normal operating point, said as `simulate`,
    `cct` and `screen` say it.

    Parameters
    ----------
    t_s : float
        The run's end, s.
    concerns : sequence of str
        `stabctl.dynamics.results.SimulationResult.end_concerns`, at least one.

    Returns
    -------
    str
    """
    from stabctl.dynamics.results import END_FREQUENCY_HZ, END_VOLTAGE_PU

    return (
        f"at the end (t = {t_s:g} s) {' and '.join(concerns)}: stable by the angle "
        f"criterion, yet no normal operating point (below {END_VOLTAGE_PU:g} pu, or beyond "
        f"+-{END_FREQUENCY_HZ:g} Hz)"
    )


def q_limits_text(on: bool) -> str:
    """The Q-limit setting of the runs in words, for a settings line: a CCT moves with it
    (IEEE 14's 1-2: 0.252 s with the PV buses' Q limits, 0.203 s without), and the text
    outputs did not say which (round 39).

    Parameters
    ----------
    on : bool
        Whether the power flow held the PV buses' Q limits (`--no-q-limits` off).

    Returns
    -------
    str
    """
    return "PV Q limits held" if on else "no PV Q limits (--no-q-limits)"


#: said of a CCT searched with storage none of whose devices switched in any of the
#: search's runs (`CCTResult.storage_acted`)
NO_DEVICE_ACTED = (
    "note: no storage device switched in any of the search's runs (their deadband or "
    "voltage gate kept them idle): this CCT is the one without storage"
)


def print_cct(case, rating, d) -> None:
    """Print the `cct` result as text.

    Parameters
    ----------
    case : Case
        The case searched (its name; its machines named by number and bus).
    rating : float or None
        Storage rating (% of machine MVA), None: no storage.
    d : dict
        `CCTResult.to_dict()` with the command's fields.
    """
    f = d["fault"]
    circ = f" (circuit {f['circuit']})" if f["circuit"] != 1 else ""
    trips = ", ".join(f"{a}-{b}" for a, b in f["trips"])
    where = (  # (round 46: "cleared without loss of a line, 3-101 also opened")
        f"fault at bus {f['bus']} at {f['t_fault_s']:g} s, cleared "
        + (f"by opening {trips}" if trips else "without loss of a line")
        if f["far_bus"] is None
        else f"fault at bus {f['bus']} on line {f['bus']}-{f['far_bus']}{circ} at "
        f"{f['t_fault_s']:g} s, cleared at both ends, line tripped"
        + (f", {trips} also opened" if trips else "")
    )
    click.echo(
        f"case {case.name}: {where}"
        + (
            "; no storage"
            if rating is None
            else f"; storage {rating:g} % of machine MVA"
            + (", WECC batteries" if d.get("esd_model") == "wecc" else "")
        )
    )
    n, c = time_decimals(d["tol_s"]), cycle_decimals(d["tol_s"])
    click.echo(
        f"CCT {d['cct_s']:.{n}f} s = {d['cct_cycles']:.{c}f} cycles (stable at "
        f"{d['t_stable_s']:.{n}f} s, unstable at {d['t_unstable_s']:.{n}f} s = "
        f"{d['t_unstable_cycles']:.{c}f} cycles; tolerance {1000 * d['tol_s']:g} ms, "
        + (f"search limit {d['t_max_s']:g} s, " if "t_max_s" in d else "")
        + f"step {step_text(d['step_s'])}"
        + (
            f" ({step_text(d['stiff_step_s'])} in intervals where a machine's subtransient "
            "time constant is shorter)"
            if d.get("stiff_step_s")
            else ""
        )
        + (
            f" with {d['sub_stepped_exciters']} exciter(s) in sub-intervals"
            if d.get("sub_stepped_exciters")
            else ""
        )
        + f", {d['conventions']} conventions"
        + (f", {q_limits_text(d['q_limits'])})" if "q_limits" in d else ")")
    )
    if d["numerical_error_s"] is not None:
        click.echo(
            f"numerical error {1000 * d['numerical_error_s']:.{max(n - 3, 0)}f} ms (CCT at "
            f"half the step {d['cct_half_step_s']:.{n}f} s)"
        )
    if rc := d.get("run_end_check"):
        click.echo(run_end_line(rc, d["cct_s"], n))
    if d.get("storage_acted") is False:
        click.echo(NO_DEVICE_ACTED)
    if "critical_group" in d:
        click.echo(critical_group_line(case, d["critical_group"], n))
    for line in islanding_lines(case, d.get("islanded", []), timed=False):
        click.echo(f"the contingency's trip: {line}")
    if failure := d.get("unstable_end_failure"):  # before any machine separated
        click.echo(f"cleared at {d['t_unstable_s']:.{n}f} s the run fails: {failure}")
        if d.get("leading_machines"):
            click.echo(f"machine(s) leading its swing: {machine_list(case, d['leading_machines'])}")
    elif d["separated_machines"]:
        click.echo(
            f"machine(s) {machine_list(case, d['separated_machines'])} lose "
            f"synchronism when cleared at {d['t_unstable_s']:.{n}f} s"
        )
    if d.get("end_concerns"):
        click.echo(f"note: cleared at the CCT, {end_note(d['end_t_s'], d['end_concerns'])}")
    click.echo(
        f"{counted(d['n_simulations'], 'simulation')} ({d['n_simulations_half_step']} at "
        "half the step, "
        f"{d['early_stops']} ended at an early verdict; {d['search']} search), "
        f"wall {d['wall_time_s']:.2f} s"
    )


def run_end_line(check: dict, cct_s: float, n: int, again: str = "with a later --tf") -> str:
    """The line of a CCT whose run's end was checked (`stabctl.stability.cct.
    _run_end_check`: its unstable end separated late in its run).

    Parameters
    ----------
    check : dict
        ``t_end_s`` (the longer run's end, s) and ``t_separation_s`` (s, or None).
    cct_s : float
        The CCT (s).
    n : int
        Decimals of its times.
    again : str, optional
        How to search again (`screen` has no --tf: `cct` does).

    Returns
    -------
    str
    """
    if check["t_separation_s"] is None:
        return (
            f"run's end checked: the unstable end separated late in its run; cleared at the "
            f"CCT the run stays stable to t = {check['t_end_s']:g} s"
        )
    return (
        f"NOT CONVERGED IN THE RUN'S END: cleared at the CCT ({cct_s:.{n}f} s) the run to "
        f"t = {check['t_end_s']:g} s loses synchronism at {check['t_separation_s']:.2f} s "
        "(a slow separation, e.g. of what a trip leaves: the unstable end separated late in "
        f"its run); for a longer study the CCT is lower: search again {again}"
    )


def sweep_line(key, rec) -> str:
    """One line of the `sweep-cct` table.

    Parameters
    ----------
    key : str
        The job key.
    rec : dict
        Its record.

    Returns
    -------
    str
    """
    from stabctl.stability.screening import ABOVE, INSECURE, verdict

    if rec["status"] != "ok":
        if verdict(rec) == ABOVE:
            return f"{key:<34} above the search limit t_max = {rec['inputs']['t_max']:g} s (robust)"
        if verdict(rec) == INSECURE:
            return f"{key:<34} {0.0:7.3f} {0.0:8.2f}  {insecure_said(rec.get('reason', ''))}"
        return f"{key:<34} failed: {rec['error']}"
    r, wall = rec["result"], rec.get("wall_time_s")  # none in a reproducible copy
    n, c = time_decimals(r.get("tol_s")), cycle_decimals(r.get("tol_s"))
    err = r.get("numerical_error_s")
    err = "-" if err is None else f"{1000 * err:.{max(n - 3, 0)}f}"
    line = (
        f"{key:<34} {r['cct_s']:7.{n}f} {r['cct_cycles']:8.{c}f} {err:>6} "
        f"{r['n_simulations']:5d} " + ("      -" if wall is None else f"{wall:7.2f}")
    )
    from stabctl.stability.cct import run_end_lost

    if run_end_lost(rc := r.get("run_end_check")):
        line += f"\n{'':<34} {run_end_line(rc, r['cct_s'], n)}"  # round 41: said by cct only
    if r.get("storage_acted") is False:
        line += f"\n{'':<34} {NO_DEVICE_ACTED}"
    if failure := r.get("unstable_end_failure"):  # none separated there (round 45)
        line += f"\n{'':<34} cleared at {r['t_unstable_s']:.{n}f} s the run fails: {failure}"
    if r.get("end_concerns") and r.get("end_t_s") is not None:  # (round 45: cct's, screen's)
        line += f"\n{'':<34} note: cleared at the CCT, {end_note(r['end_t_s'], r['end_concerns'])}"
    return line


def insecure_said(reason: str) -> str:
    """An N-1 insecure row's words, with the caveat of its record's ``reason`` where the
    verdict is not monotone in the clearing time (stable at some later clearing in
    `cct`'s window).

    Parameters
    ----------
    reason : str
        The record's reason ("" if none).

    Returns
    -------
    str
    """
    insecure = "N-1 insecure: unstable even when cleared at once"
    if "; yet stable when cleared at" in reason:
        insecure += "; " + reason.split("; ", 1)[1].split(":", 1)[0]
    return insecure


def print_sweep(rep, n_jobs: int, case=None) -> None:
    """Print the `sweep-cct` table and its summary line, then, if jobs recorded as failed
    before were not run again, how many and that ``--retry-failed`` reruns them.  Each
    job whose contingency islands buses or machines says so above its row, as `screen`
    does, and the summary counts them (round 39: only the records said so).

    Parameters
    ----------
    rep : stabctl.parallel.SweepReport
    n_jobs : int
        Jobs in the sweep.
    case : Case or None, optional
        The case swept (its machines named, its base for the load shed); None: the
        islanding is not shown.
    """
    click.echo(f"{'job':<34} {'CCT s':>7} {'cycles':>8} {'err ms':>6} {'sims':>5} {'wall s':>7}")
    n_load = n_machines = 0
    for key, rec in rep.records.items():
        islanded = (rec.get("result") or rec).get("islanded") or []
        n_load += any("load_shed_pu" in e for e in islanded)
        n_machines += any(e.get("machines") for e in islanded)
        for line in islanding_lines(case, islanded, timed=False) if case is not None else ():
            click.echo(f"{key:<34} the contingency's trip: {line}")
        click.echo(sweep_line(key, rec))
    from stabctl.stability.cct import run_end_lost
    from stabctl.stability.screening import ABOVE, INSECURE, verdict

    verdicts = [verdict(r) for r in rep.records.values()]
    lost = sum(
        run_end_lost((r.get("result") or {}).get("run_end_check")) for r in rep.records.values()
    )
    islands = (
        f"; {n_load} job(s) islanding load buses (their load shed), {n_machines} job(s) "
        "islanding machines (lost; the verdicts judge the rest)"
        if n_load or n_machines
        else ""
    )
    click.echo(
        f"{n_jobs} job(s): {run_counts(rep.ran, rep.skipped, rep.out)}; "
        f"{verdicts.count('cct')} CCT(s) found{_not_converged(lost)}, "
        f"{verdicts.count(ABOVE)} above the search "
        f"limit (robust), {verdicts.count(INSECURE)} N-1 insecure (CCT 0), "
        f"{verdicts.count('failed')} failed{islands}; wall {rep.wall_time_s:.1f} s"
    )
    if rep.failed_before:
        click.echo(
            f"{rep.failed_before} job(s) recorded as failed before were not run again; "
            "--retry-failed reruns them"
        )


def _not_converged(n: int) -> str:
    """The summaries' words for the CCTs NOT CONVERGED IN THE RUN'S END among those found
    (round 45: counted without a word)."""
    return f" ({n} of them not converged in the run's end, said above)" if n else ""


def run_counts(ran: int, reused: int, out) -> str:
    """How many of a resumable command's jobs ran now and how many it read from its
    records file: ``"N run now, M already in FILE"`` (`sweep-cct`'s and `screen`'s
    summary lines).

    Parameters
    ----------
    ran : int
        Jobs run now.
    reused : int
        Jobs whose records were already in the file.
    out : str or pathlib.Path
        The records file.

    Returns
    -------
    str
    """
    return f"{ran} run now, {reused} already in {out}"


def _shed(p_mw: float, q_mvar: float) -> str:
    """What an island of de-energised buses loses: its load shed, or (negative load: net
    generation written as load) the infeed lost (round 42: bus 72 of WECC-179 said "load
    shed -1525.0 MW")."""
    if p_mw >= 0:
        return f"load shed {p_mw:.1f} MW, {q_mvar:.1f} Mvar"
    return f"infeed lost {-p_mw:.1f} MW, {-q_mvar:.1f} Mvar (negative load)"


def _islanding_counts(rows: list[dict], key: str, what: str, why: str, sep: str = "") -> str:
    """The screening summary's count of the faults whose rows name islanded `what` under
    `key`, and of those (distinct) in all (round 42: a row islanding two machines was
    counted as one "island machines"); "" when a later part (`sep` given) counts none."""
    faults = [r[key] for r in rows if r.get(key)]
    if not faults and sep:
        return ""
    n = len({x for names in faults for x in names})
    return f"{sep}{len(faults)} fault(s) island {what} ({n} in all; {why})"


def print_screening(case, rows, tol_s: float | None = None, out=None) -> None:
    """Print the `screen` table, one row per fault in the given order.

    Parameters
    ----------
    case : Case
        The case screened (its machines named by number and bus).
    rows : list of dict
        Screening rows (`stabctl.stability.screening.screen`).
    tol_s : float or None, optional
        The searches' tolerance, s: the CCTs with the decimals it needs
        (`time_decimals`); None (default): 3.
    out : str or pathlib.Path or None, optional
        The records file: the summary says how many searches ran now and how many were
        read from it (`run_counts`, from the rows' ``run_now``); None (default): not said.
    """
    n, c = time_decimals(tol_s), cycle_decimals(tol_s)
    from stabctl.dynamics.results import END_FREQUENCY_HZ, END_VOLTAGE_PU
    from stabctl.stability.cct import run_end_lost
    from stabctl.stability.screening import ABOVE, INSECURE, VERDICTS

    width = max([22, *(len(_fault_label(r)) for r in rows)])
    click.echo(f"{'fault':<{width}} {'CCT s':>7} {'cycles':>7} {'err ms':>6}  separated / reason")
    for r in rows:
        where = f"{_fault_label(r):<{width}}"
        if r.get("islanded"):
            click.echo(f"{where} islands bus(es) {r['islanded']} (their load shed):")
        if r.get("islanded_machines"):
            click.echo(
                f"{where} islands machine(s) {machine_list(case, r['islanded_machines'])}"
                f" with bus(es) {r['islanded_machine_buses']} (lost; the rest judged):"
            )
        if r["status"] == "ok":
            err = r["numerical_error_s"]
            err = "-" if err is None else f"{1000 * err:.{max(n - 3, 0)}f}"
            said = machine_list(case, r["separated"]) or "-"
            if r.get("unstable_end_failure"):  # none separated: the run above it failed
                said = "no separation: the run at its unstable end fails (cct names how)"
            click.echo(f"{where} {r['cct_s']:7.{n}f} {r['cct_cycles']:7.{c}f} {err:>6}  {said}")
        elif r["verdict"] == ABOVE:
            above = f">{r['t_max_s']:.{n}f}"
            click.echo(f"{where} {above:>7} {'-':>7} {'-':>6}  robust: stable when cleared there")
        elif r["verdict"] == INSECURE:
            said = insecure_said(r.get("reason", ""))  # (round 45: its caveat left out)
            click.echo(f"{where} {0.0:7.{n}f} {0.0:7.{c}f} {'-':>6}  {said}")
        else:
            said = f"{r['error'][:70]}" + (" (recorded before)" if r.get("failed_before") else "")
            click.echo(f"{where} {'-':>7} {'-':>7} {'-':>6}  {said}")
        if r.get("end_concerns"):  # after its row: of the run its verdict rests on
            click.echo(
                f"{where} ends off a normal operating point: {' and '.join(r['end_concerns'])}"
                f" at t = {r['end_t_s']:g} s"
            )
        if run_end_lost(rc := r.get("run_end_check")):
            again = "with `stabctl cct` and a later --tf"
            click.echo(f"{where} {run_end_line(rc, r['cct_s'], n, again)}")
    counts = {v: sum(r["verdict"] == v for r in rows) for v in VERDICTS}
    n_off = sum(bool(r.get("end_concerns")) for r in rows)
    ran = sum(bool(r.get("run_now")) for r in rows)
    reused = "" if out is None else f"{run_counts(ran, len(rows) - ran, out)}; "
    lost = sum(run_end_lost(r.get("run_end_check")) for r in rows)
    click.echo(
        f"{len(rows)} fault(s): {reused}{counts['cct']} CCT(s) found{_not_converged(lost)}, "
        f"{counts[ABOVE]} above the "
        f"search limit (robust), {counts[INSECURE]} N-1 insecure (CCT 0), "
        f"{counts['failed']} failed; "
        + _islanding_counts(
            rows, "islanded", "load bus(es)", "their load shed, counted in the verdicts above"
        )
        + _islanding_counts(
            rows, "islanded_machines", "machine(s)", "lost; the verdicts judge the rest", ", "
        )
        + (
            f"; {n_off} stable by the angle criterion ending off a normal operating point "
            f"(below {END_VOLTAGE_PU:g} pu or beyond +-{END_FREQUENCY_HZ:g} Hz: see their rows)"
            if n_off
            else ""
        )
    )
    if before := sum(bool(r.get("failed_before")) for r in rows):
        click.echo(
            f"{before} search(es) recorded as failed before were not run again; "
            "--retry-failed reruns them"
        )
    if stiff := [r["stiff_step_s"] for r in rows if r.get("stiff_step_s")]:
        click.echo(  # as `cct` says it (round 41: the settings line gave the step alone)
            f"{len(stiff)} search(es) cut the step to as little as {step_text(min(stiff))} in "
            "intervals where a machine's subtransient time constant is shorter"
        )


def _fault_label(row: dict) -> str:
    """A screening row's fault: 'bus 3', 'bus 3 line to 101', 'bus 3 line to 101 #2' (a
    circuit other than the first)."""
    label = f"bus {row['bus']}"
    if row["far_bus"]:
        label += f" line to {row['far_bus']}"
        if row.get("circuit", 1) != 1:
            label += f" #{row['circuit']}"
    return label


def print_modes(st, no_pss: bool) -> None:
    """Print the electromechanical modes of an `eig` study, by frequency.

    Parameters
    ----------
    st : stabctl.studies.eigenvalues study
        :func:`stabctl.studies.eigenvalues.eig_study`'s result.
    no_pss : bool
        The case was analysed without its PSS.
    """
    ma = st.ma
    click.echo(
        f"case {st.case.name}{' without PSS' if no_pss else ''}: {st.sys.nstates} "
        f"states; linearised in {st.t_linearise:.2f} s (the model's set-up and its kernels' "
        f"loading included), analysed in {st.t_analyse:.2f} s"
    )
    ref = ma.reference_values()
    if not ref:
        click.echo("no angle-reference mode: an infinite bus (H = 0) holds the angles")
    else:
        click.echo(f"angle-reference mode {ref} (excluded from damping statistics)")
    click.echo(ma.table(st.case.machine_name))


def _source_line(src: dict, seed: int) -> str:
    """What a received stream brought (`estimate rmse --source`)."""
    from stabctl.estimation.sources import Unsent, unused_values

    return (
        f"frames from {src['address']}: {src['frames']} time stamps, {src['data_frames']} "
        f"data frames from {src['streams']} stream(s), "
        f"{unused_values(src['flagged']) or 'no PMU value flagged unusable by its STAT'}, "
        f"{src['missing']} missing (labelled seed {seed})"
        + "".join(f"; {Unsent(**unsent)}" for unsent in src["unsent"])
    )


def _source_compare(src: dict, figures: dict) -> None:
    """The received stream's relative-speed RMSE beside the same seed's in process."""
    click.echo(
        "relative-speed RMSE (mHz), received / in process through the frame codec / "
        "in process as drawn:"
    )
    for name, fig in figures.items():
        got, wire, drawn = (
            "-" if x is None else f"{x:.4f}"  # none: no relative speed formed (round 39)
            for x in (
                fig["rel_rmse_mhz"]["mean"],
                src["on_wire"][name]["rel_rmse_mhz"],
                src["in_process"][name]["rel_rmse_mhz"],
            )
        )
        click.echo(f"  {name:9}{got} / {wire} / {drawn}")


def print_estimate(d) -> None:
    """Print the `estimate rmse` report as text.

    Parameters
    ----------
    d : dict
        The report (`estimate rmse --json`).
    """
    f, p = d["fault"], d["pmu"]
    click.echo(
        f"case {d['case']}: fault at bus {f['bus']} on line {f['bus']}-{f['far_bus']} "
        f"at {f['t_fault_s']:g} s, cleared after {f['clear_cycles']:g} cycles"
        + (
            ""
            if d["esd_pct"] is None
            else f"; storage {d['esd_pct']:g} %"
            + (", WECC batteries" if d.get("esd_model") == "wecc" else "")
            + " (true speeds)"
        )
        + ("" if d["stable"] else "; the run loses synchronism")
    )
    click.echo(
        f"PMUs at the {p['at']} buses: {p['rate']:g} frames/s, TVE {100 * p['tve']:g} %, "
        f"FE {p['fe_hz']:g} Hz, RFE {p['rfe_hz_s']:g} Hz/s ({p['k_sigma']:g} sigma), "
        f"frequency window {p['window_cycles']:g} cycles, latency {1000 * p['latency_s']:g} ms, "
        f"frames lost with probability {p['drop_prob']:g}"  # (round 44: "lost 0", "8 missing")
        + ("; " if d.get("source") is None else " in the in-process comparison; ")
        + (
            f"{counted(d['runs'], 'run')}, seeds {d['seed']}..{d['seed'] + d['runs'] - 1}"
            if d.get("source") is None
            else _source_line(d["source"], d["seed"])
        )
    )
    w = d["window_s"]
    click.echo(f"errors in mHz from {w[0]:.3f} s to {w[1]:g} s, mean +- std over the runs:")
    cols = (
        ("speed", "speed_rmse_mhz"),
        ("COI", "coi_rmse_mhz"),
        ("relative", "rel_rmse_mhz"),
        ("rel. max", "rel_max_mhz"),
        ("at arrival", "rel_arrival_rmse_mhz"),
        ("forecast", "rel_forecast_rmse_mhz"),
        ("NIS in 95%", "nis_inside"),
    )
    figs = d["estimators"]
    click.echo(
        _table(
            ["estimator", *(c for c, _ in cols)],
            [[name, *(_mean_std(fig[k]) for _, k in cols)] for name, fig in figs.items()],
        )
    )
    if any(
        fig[k]["mean"] is not None and fig[k]["std"] is None
        for fig in figs.values()
        for _, k in cols
    ):
        click.echo("n/a: no spread, one run gave the figure")
    if any(fig[k]["mean"] is None for fig in d["estimators"].values() for _, k in cols[:-1]):
        click.echo(
            "-: no error to take (a COI or relative speed needs an estimate of every "
            "machine at one time; a machine none of whose frames arrived has none)"
        )
    if d.get("source") is not None:
        _source_compare(d["source"], d["estimators"])
    if d["false_actions"] is not None:
        a = d["ambient"]
        click.echo(
            f"no fault, {counted(a['runs'], 'run')} of {a['t_s']:g} s, ambient load {a['pct']:g} % "
            f"(tau {a['tau_s']:g} s), deadband {1000 * a['deadband_hz']:g} mHz: false ESD "
            "actions per run (largest |f_i - f_COI|, largest std of f_i - f_COI; mHz)"
        )
        for name, fig in d["false_actions"].items():
            act, mx, sd = (fig[k]["mean"] for k in ("actions", "max_rel_mhz", "std_rel_mhz"))
            click.echo(f"  {name:5} {_or_dash(act, '8.2f')}  ({_or_dash(mx)}, {_or_dash(sd)})")
        if any(f[k]["mean"] is None for f in d["false_actions"].values() for k in f):
            click.echo("-: no run to take it from (no estimate of every machine at one time)")


def _mean_std(fig: dict) -> tuple[str, str]:
    """A figure's mean and its ``+-`` spread as text: '-' for no mean, 'n/a' for no
    spread (fewer than two runs gave it)."""
    if fig["mean"] is None:
        return "-", ""
    return f"{fig['mean']:.3f}", "+-" + ("n/a" if fig["std"] is None else f"{fig['std']:.3f}")


def _table(head: list, rows: list) -> str:
    """A text table, each column as wide as its widest cell and two spaces apart: the
    first column left-aligned, the others right-aligned; a cell given as a (mean,
    spread) pair is aligned on both parts within its column."""
    body = []
    for k in range(len(head)):
        cells = [row[k] for row in rows]
        if cells and isinstance(cells[0], tuple):
            wm, ws = (max(len(c[j]) for c in cells) for j in (0, 1))
            cells = [f"{m:>{wm}} {sd:<{ws}}" if ws else f"{m:>{wm}}" for m, sd in cells]
        body.append(cells)
    widths = [max(len(str(head[k])), *(len(c) for c in body[k])) for k in range(len(head))]
    lines = [
        "  ".join(
            f"{cell:<{widths[0]}}" if k == 0 else f"{cell:>{widths[k]}}"
            for k, cell in enumerate(line)
        ).rstrip()
        for line in [head, *zip(*body)]
    ]
    return "\n".join(lines)


def _or_dash(value, spec: str = ".2f") -> str:
    """A figure formatted by spec, or '-' (right-aligned to its width) for None (no run
    gave it)."""
    if value is None:
        width = spec.split(".")[0]
        return f"{'-':>{width}}" if width else "-"
    return format(value, spec)


def machine_buses(case, numbers) -> list[int]:
    """The buses of the given machines, in their order: the JSON's bus numbers beside the
    machine numbers (the text names both, `Case.machine_name`).

    Parameters
    ----------
    case : stabctl.case.Case
    numbers : iterable of int
        Machine numbers.

    Returns
    -------
    list of int
    """
    return [int(case.machines.bus[case.machine_index(m)]) for m in numbers]


def _buses_of_sites(d: dict) -> str:
    """`` on 1 bus`` when a plan's sites (one per machine) share buses, else nothing."""
    n = d.get("n_buses", d["n_sites"])
    return "" if n == d["n_sites"] else f" on {counted(n, 'bus', 'buses')}"


def print_placement(case_name, d) -> None:
    """Print the `place` result as text.

    Parameters
    ----------
    case_name : str
    d : dict
        The result (`place --json`).
    """
    click.echo(
        f"case {case_name}: {d['total_mw']:.1f} MW of storage at {d['n_sites']} "
        f"site(s); {'VERIFIED' if d['verified'] else 'NOT verified'} by simulation "
        f"({d['message']})"
    )
    click.echo(f"{'bus':>6} {'machine':>8} {'MW':>9}")
    for r in d["allocation"]:
        click.echo(f"{r['bus']:>6} {r['machine']:>8} {r['mw']:9.1f}")
    click.echo(f"{'contingency':<16} {'no ESD s':>9} {'target s':>9} {'with s':>8}  met")
    for c in d["contingencies"]:
        click.echo(
            f"{c['name']:<16} {c['cct_no_storage_s']:9.3f} {c['target_cct_s']:9.3f} "
            f"{c['cct_s']:8.3f}  {'yes' if c['met'] else 'NO'}"
        )
    for m in d.get("damping", []):
        click.echo(f"mode {m['freq_hz']:.3f} Hz: damping ratio {m['damping_ratio']:.4f}")
    solve = max(d["solve_times_s"], default=0.0)
    click.echo(
        f"{len(d['iterations'])} allocation(s) simulated, wall {d['wall_time_s']:.1f} s, "
        f"longest convex solve {1000 * solve:.1f} ms"
    )


def _plan_verdict(d) -> str:
    """The plan's label: VERIFIED, NOT verified, or NOTHING TO PLACE when every
    contingency was set aside as infeasible (a verdict on the contingencies, not a plan
    verified on them; the plan's message, printed after it, says so); VERIFIED in the
    checks' window (e.g. "VERIFIED in the 5-s window") when a check run longer lost
    synchronism (`stabctl.placement.plan.PlanResult.run_end`)."""
    aside = d["set_aside"] or d.get("not_simulable") or d.get("n1_insecure")
    if d["verified"] and aside and not d["n_met"]:
        return "NOTHING TO PLACE"
    run_end = d.get("run_end") or {}
    if d["verified"] and run_end.get("not_converged"):
        return f"VERIFIED in the {run_end['window_s']:g}-s window"
    return "VERIFIED" if d["verified"] else "NOT verified"


def _run_end_lines(d: dict) -> list:
    """The plan's lines on its runs' end, one per contingency in question: its CCT
    without storage (and with the allocation) NOT CONVERGED IN THE RUN'S END, as `cct`
    says (`run_end_line`), and its check run T_AFTER_FAULT s longer with the allocation
    (`stabctl.placement.plan._run_end`)."""
    from stabctl.stability.cct import run_end_lost

    again = "with `stabctl cct` and a later --tf"
    window = (d.get("run_end") or {}).get("window_s")
    out = []
    for r in d["contingencies"]:
        for key, what, cct in (
            ("cct_no_storage_run_end_check", "CCT without storage", r["cct_no_storage_s"]),
            ("cct_run_end_check", "CCT with the allocation", r["cct_s"]),
        ):
            rc = r.get(key)
            if run_end_lost(rc) and cct is not None:
                out.append(f"  {r['name']}: {what}: {run_end_line(rc, cct, 3, again)}")
        rc = r.get("run_end_check")
        if not rc:
            continue
        at = f"cleared at its required {r['required_s']:.3f} s with the allocation"
        if rc["t_separation_s"] is None:
            out.append(
                f"  {r['name']}: run's end checked: {at}, the run stays stable to t = "
                f"{rc['t_end_s']:g} s"
            )
        else:
            out.append(
                f"  {r['name']}: NOT CONVERGED IN THE RUN'S END: {at}, the run to t = "
                f"{rc['t_end_s']:g} s loses synchronism at {rc['t_separation_s']:.2f} s "
                f"(verified in the {window:g}-s window only)"
            )
    return out


#: how a plan's header names a law other than the paper's (`place --coi`)
_LAWS = {
    "rest": ", each device on the COI of the other machines (--coi rest)",
    "critical": ", each device on the COI of the other group, the group each contingency's "
    "critical machines without storage (--coi critical)",
}


def _law_named(d: dict) -> str:
    """The plan header's words for its law: none for the paper's (the system's COI, a
    100 mHz deadband, a 0.8 pu gate, no hysteresis); a plan sized for another deadband,
    gate or hysteresis printed like the paper's."""
    law = d.get("settings", {}).get("controller", {})
    words = _LAWS.get(law.get("coi", "system"), "")
    for key, paper, text in _LAW_SETTINGS:
        if key in law and law[key] != paper:
            words += text.format(law[key])
    return words


#: the bang-bang law's settings a plan header names when they are not the paper's:
#: (JSON key, the paper's value, the header's words)
_LAW_SETTINGS = (
    ("deadband_hz", 0.1, ", deadband {:g} Hz (--deadband-hz)"),
    ("v_gate_pu", 0.8, ", voltage gate {:g} pu (--v-gate)"),
    ("hysteresis_hz", 0.0, ", hysteresis {:g} Hz (--hysteresis-hz)"),
)


def critical_group_line(case, group: dict, decimals: int = 3) -> str:
    """The text of `cct --coi critical`'s group (its JSON ``critical_group``).

    Parameters
    ----------
    case : stabctl.case.Case
    group : dict
        ``machines``, ``cct_without_storage_s``, ``separated`` (False: the run at the
        search's unstable end failed before any machine separated, the machines leading
        its swing taken; absent in JSON from before round 44: True).
    decimals : int, optional
        Decimals of the CCT in s.

    Returns
    -------
    str
    """
    how = (
        "separate without storage"
        if group.get("separated", True)
        else "lead the swing without storage, where the run fails before any machine "
        "separates (no separation to take the group from)"
    )
    return (
        f"storage on the critical group's COI: machines {machine_list(case, group['machines'])} "
        f"{how} (CCT {group['cct_without_storage_s']:.{decimals}f} s); their "
        "devices brake them against the other machines' COI, the other devices drive theirs "
        "after them"
    )


def _half_step_line(hs: dict) -> str:
    """The plan's check at half the step (`stabctl.placement.references.half_step`): its
    contingencies' verdicts at their required time, CCTs and energies."""
    from stabctl.placement.energy import energy_note

    rows = hs["rows"]
    stable = sum(r["stable_half"] for r in rows)
    ccts = any(r["cct_s"] is not None for r in rows)
    return (
        f"half the step ({step_text(hs['h_s'] / 2)}): {stable} of "
        f"{counted(len(rows), 'contingency', 'contingencies')} stable at their required time"
        + ("" if stable == len(rows) else " (NOT all: the plan depends on the step)")
        + (f"; CCTs within {1000 * hs['max_cct_diff_s']:.0f} ms" if ccts else "")
        + energy_note(hs)
    )


def print_plan(case, d) -> None:
    """Print the `place` result as text: the plan's line, its sites (each at its bus,
    beside its machine, named as every output names machines: `Case.machine_name`; no
    table when nothing is placed) and each contingency.

    Parameters
    ----------
    case : Case
        The case planned for.
    d : dict
        The result (`place --json`, `stabctl.placement.plan.PlanResult.to_dict`).
    """
    from stabctl.placement.energy import MJ_PER_MWH

    c = d["cost"]
    click.echo(
        f"case {case.name} ({d['requirement']}; load levels "
        f"{', '.join(f'{x:g}' for x in d['load_levels'])}; "
        f"{_ESD_NAMES[d.get('esd_model', 'ideal')]}{_law_named(d)}): {d['total_mw']:.1f} MW, "
        f"{d['total_mwh']:.2f} MWh at {d['n_sites']} site(s){_buses_of_sites(d)}, "
        f"cost {c['total']:.1f} "
        f"in the --cost-* options' unit (MW {c['mw']:.1f}, MWh {c['mwh']:.1f}, "
        f"sites {c['site']:.1f}); {_plan_verdict(d)} ({d['message']})"
    )
    if d["allocation"]:
        click.echo(
            f"{'bus':>6} {'MW':>9} {'MWh':>8} {'absorbed MWh':>13} {'delivered MWh':>14}  beside"
        )
    for r in d["allocation"]:
        click.echo(
            f"{r['bus']:>6} {r['mw']:9.1f} {r['mwh']:8.2f} "
            f"{r.get('absorbed_mj', 0.0) / MJ_PER_MWH:13.3f} "
            f"{r.get('delivered_mj', 0.0) / MJ_PER_MWH:14.3f}  {case.machine_name(r['machine'])}"
        )
    aside = [
        f"{n} more set aside as {why}"
        for n, why in (
            (len(d.get("set_aside") or []), "infeasible"),
            (len(d.get("not_simulable") or {}), "not simulable"),
            (len(d.get("n1_insecure") or {}), "N-1 insecure"),
        )
        if n
    ]
    click.echo(
        f"{d['n_met']} of {counted(d['n_contingencies'], 'contingency', 'contingencies')} "
        "stable at their required clearing time"
        + (f" ({', '.join(aside)}, below)" if aside else "")
        + f"; solved for: {', '.join(d['active']) or 'none'}"
    )
    rows = [r for r in d["contingencies"] if not (r["cct_s"] is None and r["met"])]
    if rows:  # none when every contingency is set aside (each said below)
        click.echo(f"{'contingency':<18} {'required s':>10} {'no ESD s':>9} {'with s':>8}  met")
    for r in rows:
        f = lambda x: "-" if x is None else f"{x:.3f}"  # noqa: E731
        click.echo(
            f"{r['name']:<18} {r['required_s']:10.3f} {f(r['cct_no_storage_s']):>9} "
            f"{f(r['cct_s']):>8}  {'yes' if r['met'] else 'NO'}"
        )
    left = {
        *(d.get("set_aside") or []),
        *(d.get("not_simulable") or {}),
        *(d.get("n1_insecure") or {}),
    }
    met_before = [
        r["name"]
        for r in d["contingencies"]
        if r["cct_s"] is None and r["met"] and r["name"] not in left
    ]
    if met_before:  # (round 45: left out of the table without a word)
        click.echo(
            "met without storage (their CCT without storage at or above the required "
            f"time, nothing to solve for): {', '.join(met_before)}"
        )
    if d.get("half_step"):
        click.echo(_half_step_line(d["half_step"]))
    for line in _run_end_lines(d):
        click.echo(line)
    for r in d["contingencies"]:
        for line in islanding_lines(case, r.get("islanded") or [], timed=False):
            click.echo(f"  {r['name']}: the contingency's trip: {line}")
        if r.get("critical_group"):
            click.echo(f"  {r['name']}: the law armed on {machine_list(case, r['critical_group'])}")
        if r.get("chattering"):
            click.echo(
                f"  {r['name']}: at its required time, {r['switchings']} switchings"
                + _chattering([r])
            )
    if d.get("out_of_scope"):
        click.echo("out of scope (unstable when cleared at once): " + ", ".join(d["out_of_scope"]))
    for proof in d.get("infeasible") or []:
        click.echo("set aside as " + proof)
    for name, why in (d.get("not_simulable") or {}).items():
        click.echo(f"set aside as not simulable without storage: {name}: {why}")
    for name, why in (d.get("n1_insecure") or {}).items():
        click.echo(f"set aside as N-1 insecure: {name}: {why}")
    u = d.get("uniform")
    if u and u.get("pct") is not None:
        click.echo(
            f"least uniform fleet: {u['pct']:g} % of every MVA = {u['total_mw']:.0f} MW,"
            f" {u['mwh']:.2f} MWh, cost {u['cost']['total']:.1f}"
        )
    for a in d.get("alone") or []:
        mw = "infeasible" if a["total_mw"] is None else f"{a['total_mw']:.1f} MW"
        click.echo(f"fault {a['fault']} alone: {mw}")
    click.echo(f"{counted(d['n_simulations'], 'run')} simulated, wall {d['wall_time_s']:.1f} s")


def estimator_cct_lines(
    table: dict,
    bus: int,
    far_bus: int,
    esd_pct: float,
    settings,
    runs: int,
    seed: int,
    esd_model: str = "ideal",
    freq_hz: float = 60.0,
) -> list:
    """The text lines of `estimate cct`.

    Parameters
    ----------
    table : dict
        Estimator -> CCT statistics (cycles), `stabctl.studies.estimate.estimator_ccts`.
    bus, far_bus : int
    esd_pct : float
    settings : stabctl.estimation.settings.PMUSettings
    runs, seed : int
    esd_model : {"ideal", "wecc"}, optional
        The storage devices' model (named in the first line).
    freq_hz : float, optional
        The case's nominal frequency (Hz), whose quarter cycle the searches resolve
        (`stabctl.estimation.closed_loop.cct_tol`); default 60.

    Returns
    -------
    list of str
    """
    from stabctl.estimation.closed_loop import cct_tol

    rate, lat = settings.rate, settings.latency_s
    lines = [
        f"CCT of line {bus}-{far_bus}, {_ESD_NAMES[esd_model]} {esd_pct:g} %, {rate:g} "
        f"frames/s, latency "
        f"{1000 * lat:g} ms, frequency window {settings.window_cycles:g} cycles, "
        f"{counted(runs, 'seed')} from {seed} (cycles, each found on a "
        f"{1000 * cct_tol(freq_hz):.2f} ms grid, 1/4 cycle: coarser than stabctl cct's 1 ms):"
    ]
    lines += [
        f"  {e:5} "
        + (
            "failed"
            if s["mean"] is None
            else f"{s['mean']:7.2f}"
            + (" +- n/a (one run)" if s["std"] is None else f" +- {s['std']:.2f}")
            + f" ({s['min']:.2f}..{s['max']:.2f})"
        )
        + f"  runs {s['runs']}, failed {s['failed']}"
        + "".join(f"\n        failed: {why}" for why in s.get("errors", ()))
        for e, s in table.items()
    ]
    return lines


def closed_loop_lines(
    rows: dict,
    bus: int,
    far_bus: int,
    esd_pct: float,
    seed: int,
    esd_model: str = "ideal",
    law: dict | None = None,
) -> list:
    """The text lines of `estimate closed-loop` (and `pmu plant`).

    Parameters
    ----------
    rows : dict
        Estimator -> verdict, `stabctl.studies.estimate.closed_loop_verdicts` (a remote
        controller's row, `pmu plant`'s, has no ``frames``: the plant does not see what
        the controller formed).
    bus, far_bus : int
    esd_pct : float
    seed : int
    esd_model : str, optional
        The ESDs' model ("ideal" or "wecc").
    law : dict, optional
        The controller's settings (`control_record`), named on the first line.

    Returns
    -------
    list of str
    """
    said = "" if law is None else f", {law_text(law)}"
    head = (
        f"closed loop, fault at bus {bus} line {bus}-{far_bus}, "
        f"{_ESD_NAMES[esd_model]} {esd_pct:g} %{said}, seed {seed}:"
    )
    return [head] + [
        f"  {e:5} {'stable' if r['stable'] else 'UNSTABLE':8} mode commands "
        f"{r['mode_commands']:5d}  false actions {r['false_actions']}"
        + (_frames_used(r) if "frames" in r else "")
        + _link_text(r.get("link"))
        for e, r in rows.items()
    ]


def control_record(deadband_hz, v_gate, coi, hysteresis_hz) -> dict:
    """The storage controller's settings as a `--json` record (the paper's law, Table 3:
    `stabctl.storage.control.BangBangCOI`).

    Parameters
    ----------
    deadband_hz, v_gate, coi, hysteresis_hz : float, float, str, float
        The options' values (Hz, pu, "system" or "rest", Hz).

    Returns
    -------
    dict
    """
    return {
        "deadband_hz": deadband_hz,
        "v_gate_pu": v_gate,
        "coi": coi,
        "hysteresis_hz": hysteresis_hz,
    }


def law_text(law: dict) -> str:
    """A `control_record` in words: ``deadband 0.1 Hz, hysteresis 0 Hz, v-gate 0.8 pu,
    COI system`` (the settings it holds)."""
    words = (
        ("deadband_hz", "deadband {:g} Hz"),
        ("hysteresis_hz", "hysteresis {:g} Hz"),
        ("v_gate_pu", "v-gate {:g} pu"),
        ("coi", "COI {}"),
    )
    return ", ".join(w.format(law[k]) for k, w in words if k in law)


def _frames_used(row: dict) -> str:
    """How many of the frames due the controller used (every machine's speed estimated),
    and that the rest were lost or incomplete."""
    used, due = row["frames_formed"], row["frames"]
    rest = "" if used == due else f" ({due - used} lost or incomplete: devices idle there)"
    return f"  frames used {used} of {due}{rest}"


def _link_text(link) -> str:
    """The C37.118.2 loop's figures of a closed-loop row (empty in process)."""
    if link is None:
        return ""
    rt = link["round_trip_ms"]
    return (
        f"  over TCP: {counted(link['frames'], 'frame')}, round trip median {rt['median']:.2f} ms, "
        f"99th percentile {rt['p99']:.2f} ms, largest {rt['max']:.2f} ms, "
        f"{link['late']} later than the latency"
        + "".join(f"\n  dropped peer {p}" for p in link.get("dropped_peers", ()))
    )
