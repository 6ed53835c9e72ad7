"""`stabctl cases`, `stabctl import-psse` and `stabctl import-andes`: the cases and their
files."""

from __future__ import annotations

from pathlib import Path
from typing import cast

import click

from stabctl.cli.checks import check_suffix
from stabctl.cli.format import describe_sw_con, print_json, shown
from stabctl.cli.options import (
    AliasedOption,
    json_option,
    note_written,
    refuse_given,
    reports_errors,
)
from stabctl.errors import InputError, PowerFlowError, StabctlError, counted

#: the tables a case may hold beside its machines and controls, as summaries count them
#: (only where the case has any): key, noun, plural
_OTHER_TABLES = (
    ("converters", "converter", "converters"),
    ("shafts", "torsional shaft", "torsional shafts"),
    ("svcs", "static var compensator", "static var compensators"),
    ("motors", "induction motor", "induction motors"),
    ("switched_shunts", "switched shunt", "switched shunts"),
    ("injections", "fixed injection", "fixed injections"),
)


def other_tables(case) -> dict[str, int]:
    """The numbers of the case's converters, torsional shafts, static var compensators,
    induction motors, switched shunts and fixed injections, those it has any of (the
    summaries of `cases` and of an import)."""
    return {key: len(getattr(case, key)) for key, *_ in _OTHER_TABLES if len(getattr(case, key))}


def other_tables_text(counts: dict[str, int]) -> str:
    """``", 10 converters, 2 fixed injections"`` for `other_tables`' counts."""
    return "".join(
        f", {counted(counts[key], noun, plural)}"
        for key, noun, plural in _OTHER_TABLES
        if key in counts
    )


def _case_info(name: str) -> dict:
    from stabctl.io import load_case

    case = load_case(name)
    return {
        "name": name,
        "description": case.description,
        "buses": case.n_bus,
        "branches": len(case.branches),
        "machines": len(case.machines),
        "exciters": len(case.exciters),
        "pss": len(case.pss),
        "governors": len(case.governors),
        **other_tables(case),
        "nonconforming_loads": len(case.loads),
        "base_mva": case.base_mva,
        "freq_hz": case.freq_hz,
        "sw_con": describe_sw_con(case),
    }


@click.command()
@click.argument("case_name", metavar="[CASE]", required=False)
@click.option(
    "--bus-table",
    "buses",
    is_flag=True,
    help="List CASE's buses (number, type, kV, V and angle as its data gives them, "
    "generation, load and shunt in MW and Mvar, machines and converters).  V_data_pu "
    "of a PV or swing bus is its set point, which the power flow every command solves "
    "holds unless a Q limit binds (then lower or higher: simulate --out FILE.csv "
    "records the solved voltages from t = 0).",
)
@click.option(
    "--line-table",
    "lines",
    is_flag=True,
    help="List CASE's branches (from, to, circuit as --circuit counts it, r, x, b, tap).",
)
@json_option("the list")
@reports_errors
def cases(case_name, buses, lines, as_json):
    """List the built-in cases (usable as CASE in `stabctl simulate`), or one case.

    For each: name, description, numbers of buses, branches (every circuit counted),
    machines, exciters, PSS, governors, the converters, torsional shafts, static var
    compensators, induction motors, switched shunts and fixed injections it has, and
    non-conforming load buses, the base (MVA) and
    frequency (Hz), and the data file's own disturbance (PST sw_con, run by
    `simulate --pstess-default`).  With CASE (a built-in or a case file): that case, and
    with --bus-table / --line-table its buses and branches, to choose --fault, --far-bus
    and --circuit (bus numbers are the data file's: PST numbering).

    \b
    Example:
      stabctl cases kundur --line-table
    """
    from stabctl.io import list_cases

    if case_name is not None and not case_name.strip():  # '' listed every case
        raise InputError(
            f"CASE {case_name!r}: an empty case name; give a built-in "
            f"({', '.join(list_cases())}) or a case file, or no CASE to list the built-ins"
        )
    if case_name is None and (buses or lines):
        raise InputError("--bus-table and --line-table list one case's: give CASE")
    rows = [_case_info(name) for name in ([case_name] if case_name else list_cases())]
    tables = {}
    if case_name and (buses or lines):
        from stabctl.io import load_case

        case = load_case(case_name)
        tables = {
            **({"buses": _bus_rows(case)} if buses else {}),
            **({"lines": _line_rows(case)} if lines else {}),
        }
    if as_json:
        print_json({**rows[0], **tables} if case_name else rows)
        return
    for r in rows:
        click.echo(
            f"{r['name']}: {r['buses']} buses, {r['branches']} branches, "
            f"{r['machines']} machines, {r['exciters']} exciters, {r['pss']} PSS, "
            f"{r['governors']} governors{other_tables_text(r)}, "
            f"{r['nonconforming_loads']} non-conforming load "
            f"buses, {r['base_mva']:g} MVA base, {r['freq_hz']:g} Hz"
        )
        if r["description"].strip():  # a case without one (an import's own) prints none
            click.echo(f"    {r['description']}")
        if r["sw_con"]:
            click.echo(f"    data file disturbance: {r['sw_con']}")
    for name, table in tables.items():
        click.echo(f"\n{name}:")
        widths = [max(8, len(k)) for k in table[0]] if table else []
        click.echo(
            "  ".join(f"{k:>{w}}" for k, w in zip(table[0], widths)) if table else "  (none)"
        )
        for row in table:
            click.echo("  ".join(_cell(v, w) for v, w in zip(row.values(), widths)))


def _cell(v, width: int) -> str:
    if isinstance(v, float):
        return f"{v:>{width}.4g}"
    return f"{'-' if v is None else v!s:>{width}}"


def _bus_rows(case) -> list[dict]:
    """One dict per bus: number, type, kV, |V| (a PV or swing bus's set point) and angle
    of the data (``V_data_pu``, ``angle_data_deg``: not the solved power flow),
    generation, load and shunt in MW and Mvar (the shunt's at 1 pu, capacitive positive,
    as PSS/E's bus data), the machines there named as every output names them (``G3``),
    and in a case with converters theirs (``C17``: the ``pibr_pu.C17`` columns of
    `simulate --out`)."""
    from stabctl.case import PQ, PV, SWING

    b, kinds, base = case.buses, {SWING: "swing", PV: "PV", PQ: "PQ"}, case.base_mva
    at: dict[int, list[str]] = {}
    for k, bus in enumerate(case.machines.bus):
        at.setdefault(int(bus), []).append(f"G{int(case.machines.number[k])}")
    ibr: dict[int, list[str]] = {}
    for k, bus in enumerate(case.converters.bus):
        ibr.setdefault(int(bus), []).append(f"C{int(case.converters.number[k])}")
    return [
        {
            "bus": int(b.number[i]),
            "type": kinds.get(int(b.kind[i]), "?"),
            "kV": float(b.kv[i]),
            "V_data_pu": float(b.vmag[i]),
            "angle_data_deg": float(b.vang_deg[i]),
            "P_gen_MW": float(b.pgen[i] * base),
            "Q_gen_Mvar": float(b.qgen[i] * base),
            "P_load_MW": float(b.pload[i] * base),
            "Q_load_Mvar": float(b.qload[i] * base),
            "G_shunt_MW": float(b.gshunt[i] * base),
            "B_shunt_Mvar": float(b.bshunt[i] * base),
            "machines": ",".join(at.get(int(b.number[i]), [])) or None,
            **(
                {"converters": ",".join(ibr.get(int(b.number[i]), [])) or None}
                if len(case.converters)
                else {}
            ),
        }
        for i in range(case.n_bus)
    ]


def _line_rows(case) -> list[dict]:
    """One dict per branch row: from, to, circuit (the k-th row of its bus pair, as
    --circuit counts), r, x, b (pu), tap."""
    br = case.branches
    seen: dict[tuple[int, int], int] = {}
    out: list[dict] = []
    for k in range(len(br)):
        a, c = int(br.from_bus[k]), int(br.to_bus[k])
        n = seen[(min(a, c), max(a, c))] = seen.get((min(a, c), max(a, c)), 0) + 1
        out.append(
            {
                "from": a,
                "to": c,
                "circuit": n,
                "r_pu": float(br.r[k]),
                "x_pu": float(br.x[k]),
                "b_pu": float(br.b[k]),
                "tap": float(br.tap[k]) or 1.0,
            }
        )
    return out


def _refuse_swapped(first, dyr, name: str) -> None:
    """Refuse a DYR file given where the RAW goes (with the RAW after it, or alone): the RAW
    reader's "malformed record" at line 1 did not say that the files were swapped."""
    if Path(first).suffix.lower() != ".dyr":
        return
    if dyr is not None and Path(dyr).suffix.lower() == ".raw":
        raise InputError(
            f"{name} {first} is a DYR file and DYR {dyr} a RAW file: give the RAW first, "
            "then the DYR"
        )
    if dyr is None:
        raise InputError(f"{name} {first} is a DYR file: give the RAW file first, then it")


def _dyr_and_out(func):
    """The optional DYR argument and the --out option of the import commands."""
    func = click.option(
        "--out",
        "-o",
        "out_path",
        required=True,
        metavar="CASE.json",
        type=click.Path(dir_okay=False),
        help="Output file: the stabctl case to write.",
    )(func)
    return click.argument(
        "dyr_path", metavar="[DYR]", required=False, type=click.Path(dir_okay=False)
    )(func)


def _static_option(func):
    """--static: accept a case without machines (a power-flow-only case)."""
    return click.option(
        "--static",
        is_flag=True,
        help="Write a power-flow-only case when the files have no dynamic data (no "
        "machine model); without it such an import is refused (nothing written), and "
        "with it one with machines.",
    )(func)


def _islands_option(func):
    """--leave-out-islands: disconnect islands without a swing bus, each named."""
    return click.option(
        "--leave-out-islands",
        is_flag=True,
        help="Leave out the islands without a swing bus (PSS/E's isolated buses: their "
        "buses, branches, loads and machines with their controls), each named, instead "
        "of writing a case whose power flow is refused.",
    )(func)


def _solved_as(q_limits: bool) -> str:
    """How the import solves the case's power flow, for its messages: Q limits on, as
    simulate solves it (import-psse), or off, as ANDES and simulate --no-q-limits do
    (import-andes)."""
    if q_limits:
        return "Q limits on, as simulate solves it"
    return "Q limits off, as ANDES and simulate --no-q-limits solve it"


def _unsolved_option(q_limits: bool):
    """--keep-unsolved: write a case whose power flow (solved as `_solved_as` says) does
    not converge, instead of refusing it."""
    return click.option(
        "--keep-unsolved",
        is_flag=True,
        help=f"Write the case even when stabctl's power flow of it ({_solved_as(q_limits)}) "
        "does not converge, with a warning; every analysis command refuses such a case.  "
        "Without it such an import is refused naming the worst mismatch and its bus "
        "(exit status 2, nothing written).",
    )


def _leave_out_islands(case, asked: bool):
    """(case, lines): the case without its dead islands when asked (each line echoed as a
    warning), else as it is."""
    if not asked:
        return case, ()
    from stabctl.network.topology import without_dead_islands

    case, lines = without_dead_islands(case)
    for line in lines:
        click.echo(f"warning: left out the {line}", err=True)
    return case, lines


def _check_dynamic(case, source: str, static: bool) -> None:
    """Refuse a case without machines unless --static asked for one, and --static for a
    case with machines (it would change nothing); warn of a case whose machines are all
    infinite buses (`stabctl.case.Case.none_can_swing`)."""
    import warnings

    from stabctl.errors import InputError

    if len(case.machines) == 0 and not static:
        raise InputError(
            f"{source}: no dynamic data: the case would have no machines (give the DYR "
            "file, or --static for a power-flow-only case)"
        )
    if len(case.machines) and static:
        raise InputError(
            f"--static given for {source} with dynamic data ({len(case.machines)} "
            "machine(s)): it only lets a case without machines be written; leave it out"
        )
    why = case.none_can_swing()
    if why:
        warnings.warn(f"{source}: {why}", UserWarning, stacklevel=2)


def _imported(case, out) -> tuple[dict, str]:
    """The summary of an imported case written to ``out``: (JSON fields, text)."""
    summary = {
        "case": str(out),
        "name": case.name,
        "buses": case.n_bus,
        "branches": len(case.branches),
        "machines": len(case.machines),
        "exciters": len(case.exciters),
        "pss": len(case.pss),
        "governors": len(case.governors),
    }
    text = (
        f"wrote {shown(out)}: {counted(case.n_bus, 'bus', 'buses')}, "
        f"{counted(len(case.branches), 'branch', 'branches')}, "
        f"{counted(len(case.machines), 'machine')}, {counted(len(case.exciters), 'exciter')}, "
        f"{len(case.pss)} PSS, {counted(len(case.governors), 'governor')}"
    )
    others = other_tables(case)  # a case without any is summarised as before
    summary.update(others)
    text += other_tables_text(others)
    if case.events:  # the case's own disturbance (simulate --case-events runs it)
        from stabctl.dynamics.events import from_case

        named = [f"{e} ({rec['source']})" for e, rec in zip(from_case(case), case.events)]
        summary["events"] = named
        text += "; its own events (simulate --case-events): " + "; ".join(named)
    return summary, text


@click.command("import-psse")
@click.argument("raw_path", metavar="RAW", type=click.Path(dir_okay=False))
@_dyr_and_out
@click.option(
    "--skip-unsupported",
    is_flag=True,
    help="Leave out records stabctl cannot represent (listed as warnings) "
    "instead of refusing the files.",
)
@click.option(
    "--loads",
    type=click.Choice(["impedance", "raw"]),
    default="impedance",
    show_default=True,
    help="Load model in dynamic runs: all constant impedance, or the RAW "
    "composition (constant power, current, admittance; PST's network "
    "solution may fail with constant power under deep voltage dips).  Refused for a "
    "case without machines (no dynamic run).",
)
@click.option(
    "--dyr-conventions",
    "--conventions",
    "conventions",
    cls=AliasedOption,
    type=click.Choice(["psse", "pst", "andes"]),
    default="psse",
    show_default=True,
    help="How to read the DYR models: PSS/E's (its Model Library's machines: stator "
    "at rated speed, Pm and D divided by speed, each model's saturation), PST's "
    "(machines with speed effects and no saturation, EXDC2 limits times the "
    "terminal voltage) or ANDES 2.0's (to compare with ANDES like for like); "
    "docs/pst_models.md section 12.  Only with a DYR file.",
)
@click.option(
    "--net-unmodelled",
    is_flag=True,
    help="Net the generators the DYR file gives no machine model (PSS/E's netting: "
    "each a negative constant-power load PG + jQG at its bus, listed as a warning) "
    "instead of refusing the files.  Only with a DYR file.",
)
@click.option(
    "--leave-out-infeasible",
    is_flag=True,
    help="Leave out the exciters (with their PSS) and governors whose initial point, at "
    "the power flow simulate solves (Q limits on), lies outside their own limits "
    "(PSS/E: 'initial conditions suspect'), each named, instead of writing a case that "
    "simulate refuses (without it, each such control is named in a warning).",
)
@_unsolved_option(True)
@_islands_option
@_static_option
@json_option("the summary")
@reports_errors
def import_psse(
    raw_path,
    dyr_path,
    out_path,
    skip_unsupported,
    loads,
    conventions,
    net_unmodelled,
    leave_out_infeasible,
    keep_unsolved,
    leave_out_islands,
    static,
    as_json,
):
    """Convert a PSS/E RAW file (v32-36) and optionally a DYR file to a stabctl case.

    The case (stabctl's JSON format) is usable as CASE by simulate, cct, eig and screen.
    Unsupported records are named as FILE:LINE RECORD with the reason; without
    --skip-unsupported they stop the import (exit status 2, nothing written). A RAW file
    without DYR (no machines) is refused unless --static asks for a power-flow-only case.
    Generators without a machine model in the DYR file are refused by name, or netted as
    negative loads with --net-unmodelled (synthetic grids such as ACTIVSg2000 give their
    wind and solar plants no dynamic data). Exciters and governors that cannot start within
    their own limits make simulate refuse the case; --leave-out-infeasible leaves them out,
    each named. A case whose power flow (Q limits on) does not converge, from the RAW's
    voltages nor from a flat start (tried next, with a warning), is refused naming
    the worst mismatch and its bus (every analysis command would refuse it); --keep-unsolved
    writes it all the same, with a warning. The summary names each record left out, out of
    the network (isolated buses and what is at them, equipment out of service: left out as
    PSS/E leaves them), generator netted and record read otherwise than written (an IDE 2
    bus without generator in service is a load bus, a wind machine's Q limits come from
    WMOD and WPF, as PSS/E) with why, the switched shunts (MODSW not 0) held at BINIT and
    the transformers (COD > 0) held at their ratio and angle (their control is not
    modelled; one line per kind with their buses when more than 5), and compares the power
    flow (Q limits on) with the RAW's own solution (the largest voltage and angle
    differences and their buses; a warning above 1e-3).

    \b
    Example (ANDES's cases/kundur files; their TOGGLE record, a disturbance, is left out):
      stabctl import-psse kundur.raw kundur_full.dyr --skip-unsupported -o kundur_psse.json
      stabctl simulate kundur_psse.json --fault 7 --far-bus 8 --tf 5
    """
    from stabctl.io.psse import import_psse as run_import

    out = cast(Path, check_suffix(out_path, (".json",), "--out"))  # --out is required
    _refuse_swapped(raw_path, dyr_path, "RAW")
    if dyr_path is None:
        refuse_given(
            ("conventions", "net_unmodelled"),
            "without a DYR file (no dynamic models to read, no generator to net)",
        )
    imported = run_import(
        raw_path,
        dyr_path,
        "skip" if skip_unsupported else "error",
        loads,
        conventions,
        "net" if net_unmodelled else "error",
    )
    _check_dynamic(imported.case, Path(raw_path).name, static)
    if len(imported.case.machines) == 0:
        refuse_given(
            ("loads", "leave_out_infeasible"),
            "for a power-flow-only case (no machines: no dynamic run, no control)",
        )
    case, islands = _leave_out_islands(imported.case, leave_out_islands)
    unsolved = None if keep_unsolved else Path(raw_path).name
    if len(case.machines):
        against_raw = _raw_gap(case, imported.solution, q_limits=True, unsolved=unsolved)
    else:  # a power-flow-only case: its power flow must converge all the same
        against_raw = None
        _solution_gap(case, imported.solution, True, unsolved=unsolved)
    case, infeasible = _leave_out_infeasible(case, leave_out_infeasible)
    _write_case_atomically(case, out)
    summary, text = _imported(case, out)
    summary.update(
        nonconforming_loads=len(case.loads),
        left_out=list(imported.left_out),
        out_of_service=list(imported.out_of_service),
        netted=list(imported.netted),
        netted_controls=list(imported.netted_controls),
        changed=list(imported.changed),
        held=list(imported.held),
        unused=list(imported.unused),
        # (a case without machines has no dynamic run to change its loads for)
        load_model=imported.load_model if len(case.machines) else "",
        infeasible=list(infeasible),
        islands=list(islands),
        powerflow_against_raw=against_raw,
    )
    if as_json:
        print_json(summary)
        return
    _echo_psse_import(text, imported, infeasible, islands, summary["load_model"])
    _echo_raw_gap(against_raw, "Q limits on, as simulate solves it")


def _leave_out_infeasible(case, asked: bool, q_limits: bool = True) -> tuple:
    """(case, lines): with --leave-out-infeasible the case without its controls that
    cannot start inside their limits at its power flow (``q_limits`` as said; each line
    echoed as a warning), else as it is, each such control named in a warning (every run
    refuses the case as written)."""
    from stabctl.dynamics.infeasible import leave_out_infeasible

    if asked:
        case, infeasible = leave_out_infeasible(case, q_limits)
        for line in infeasible:
            click.echo(f"warning: left out the {line}", err=True)
        return case, infeasible
    if len(case.machines):
        try:
            _, found = leave_out_infeasible(case, q_limits)
        except StabctlError:  # another refusal: a run names it, as for any case
            found = ()
        for line in found:
            click.echo(
                f"warning: the {line}: every run refuses the case as written "
                "(--leave-out-infeasible leaves such a control out, named)",
                err=True,
            )
    return case, ()


def _echo_psse_import(text: str, imported, infeasible, islands, load_model: str) -> None:
    """import-psse's summary lines: the counts, then each record left out, out of the
    network, netted or changed, and the controls held at their RAW setting (each, or one
    line per kind when many: `stabctl.io.psse.held_lines`), and the loads' model where
    the dynamic run changes it (``load_model``, '' none)."""
    click.echo(
        f"{text}; {len(imported.left_out)} record(s) left out, "
        f"{len(imported.out_of_service)} out of the network (as PSS/E), "
        f"{len(imported.netted)} generator(s) netted"
        + (
            f" ({len(imported.netted_controls)} control record(s) left out with them)"
            if imported.netted_controls
            else ""
        )
        + ", "
        f"{len(infeasible)} control(s) outside their limits left out"
        + (f", {len(islands)} island(s) without a swing bus left out" if islands else "")
        + (f", {len(imported.held)} control(s) held at their RAW setting" if imported.held else "")
    )
    for what, items in (
        ("left out", imported.left_out),
        ("out of the network", imported.out_of_service),
        ("netted", imported.netted),
        ("left out with its netted generator", imported.netted_controls),
        ("changed", imported.changed_summary),
        ("held", imported.held_summary),
        ("read, of no use to a run (names, schedules, ratings)", imported.unused),
        ("load model", [load_model] if load_model else []),
    ):
        for item in items:
            click.echo(f"  {what}: {item}")


@click.command("import-andes")
@click.argument("case_path", metavar="CASE", type=click.Path(dir_okay=False))
@_dyr_and_out
@click.option(
    "--skip-unsupported",
    is_flag=True,
    help="Leave out the ANDES models stabctl lacks and the columns ANDES ignores, and "
    "keep the devices stabctl keeps only with a change (a converter taking less than all "
    "of its generator's power, a value read otherwise), each listed as a warning, instead "
    "of refusing the case: without it either stops the import.",
)
@click.option(
    "--dyr-conventions",
    "--conventions",
    "conventions",
    cls=AliasedOption,
    type=click.Choice(["psse", "pst", "andes"]),
    default=None,
    help="How to read the PSS/E models: as ANDES 2.0 solves them (the same "
    "equations as ANDES: machines without speed effects, ...), as PSS/E's Model "
    "Library states them or as PST's.  [default: psse for RAW + DYR files, andes "
    "otherwise]",
)
@click.option(
    "--leave-out-infeasible",
    is_flag=True,
    help="Leave out the exciters (with their PSS) and governors whose initial point, at "
    "the power flow ANDES solves (Q limits off: the commands' --no-q-limits), lies "
    "outside their own limits (PSS/E: 'initial conditions suspect'), each named, instead "
    "of writing a case that every run refuses (without it, each such control is named in "
    "a warning).",
)
@_unsolved_option(False)
@_islands_option
@_static_option
@json_option("the summary")
@reports_errors
def import_andes(
    case_path,
    dyr_path,
    out_path,
    skip_unsupported,
    conventions,
    leave_out_infeasible,
    keep_unsolved,
    leave_out_islands,
    static,
    as_json,
):
    """Convert any case ANDES 2.0 loads (xlsx, json, PSS/E RAW [+ DYR], MATPOWER) to a
    stabctl case.

    The case is read by ANDES's own parser (the optional `andes` extra: pip install
    "stabctl[andes]") and written in stabctl's JSON format, usable as CASE by simulate,
    cct, eig and screen (with --no-q-limits to solve ANDES's power flow). ANDES models
    stabctl lacks are named with their device counts, and devices stabctl keeps only
    with a change (converters taking less than all of their generator's power) named
    with the change; without --skip-unsupported either stops the import (exit status 2,
    nothing written), as does a case without machine models unless --static asks for a
    power-flow-only case. DYR records ANDES's reader
    skips are left out by name, values ANDES holds other than the DYR's are named as
    changes (PSS/E's infinite bus keeps H = 0). Values are read as the file gives them:
    one ANDES would replace by its default (an M of 0), a formula without a stored value,
    a status u other than 0 or 1, a line of zero impedance, a sheet that is no ANDES model
    stop the import; columns ANDES ignores too, or are left out by name with
    --skip-unsupported. A case whose power flow (Q limits off, as ANDES solves it) does
    not converge is refused naming the worst mismatch and its bus (every analysis
    command would refuse it); --keep-unsolved writes it all the same, with a warning.
    The power flow of the case is compared
    with ANDES's (PV Q limits off in both) and, for a RAW file, with the RAW's own
    solution, and the largest differences reported.

    \b
    Example:
      stabctl import-andes ieee39_full.xlsx -o ieee39.json --skip-unsupported
      stabctl simulate ieee39.json --fault 16 --no-q-limits --tf 5
    """
    from stabctl.io.andes_case import read_andes_case

    out = cast(Path, check_suffix(out_path, (".json",), "--out"))  # --out is required
    _refuse_swapped(case_path, dyr_path, "CASE")
    if static:
        refuse_given(
            ("conventions", "leave_out_infeasible"),
            "with --static (a power-flow-only case has no models)",
        )
    if conventions is None:
        conventions = "psse" if dyr_path is not None else "andes"
    imported = read_andes_case(
        case_path, conventions, "skip" if skip_unsupported else "error", dyr_path
    )
    _check_dynamic(imported.case, Path(case_path).name, static)
    case, islands = _leave_out_islands(imported.case, leave_out_islands)
    dv, da = _powerflow_gap(imported, case, None if keep_unsolved else Path(case_path).name)
    against_raw = (
        None if imported.data_solution is None else _raw_gap(case, imported.data_solution, True)
    )
    case, infeasible = _leave_out_infeasible(case, leave_out_infeasible, q_limits=False)
    _write_case_atomically(case, out)
    summary, text = _imported(case, out)
    summary.update(
        left_out=list(imported.left_out),
        out_of_service=list(imported.out_of_service),
        infeasible=list(infeasible),
        changed=list(imported.changed),
        unlike_andes=list(imported.unlike_andes),
        defaulted=list(imported.defaulted),
        ignored=list(imported.ignored),
        islands=list(islands),
        powerflow_vmag_diff_pu=dv,
        powerflow_angle_diff_rad=da,
        powerflow_against_raw=against_raw,
    )
    if as_json:
        print_json(summary)
        return
    click.echo(
        f"{text}; {len(imported.left_out)} left out, "
        f"{len(imported.out_of_service)} out of service (u = 0, or with their device)"
        + (f"; {len(infeasible)} control(s) outside their limits left out" if infeasible else "")
        + (f"; {len(islands)} island(s) without a swing bus left out" if islands else "")
        + (f"; {len(imported.changed)} kept with a change" if imported.changed else "")
        + (
            f"; ignored (no effect on the dynamics): {', '.join(imported.ignored)}"
            if imported.ignored
            else ""
        )
    )
    for what, items in (
        ("left out", imported.left_out),
        ("out of service", imported.out_of_service),
        ("changed", imported.changed),
        ("kept as the file gives, unlike ANDES", imported.unlike_andes),
        ("not given in the file, run at ANDES's", imported.defaulted),
    ):
        for item in items:
            click.echo(f"  {what}: {item}")
    if dv is not None:
        click.echo(
            f"power flow against ANDES's (PV Q limits off in both, as ANDES solves it; the "
            f"commands' --no-q-limits): max |dV| {dv:.1e} pu, max |d angle| {da:.1e} rad"
        )
    _echo_raw_gap(against_raw, "Q limits on, as PSS/E solved it")


#: largest difference (pu, rad) between a case's power flow and the RAW file's own
#: solution accepted without a warning: the RAW's VM, VA are written to 4-5 decimals,
#: a solved ACTIVSg2000 lands within 5e-5 pu
RAW_AGREEMENT = 1e-3


def _raw_gap(case, solution, q_limits: bool, unsolved: str | None = None) -> dict | None:
    """The largest |V| (pu) and angle (rad) differences, with their buses, between
    stabctl's power flow of ``case`` (``q_limits`` as said) and the RAW file's own
    solution ``solution`` (bus number, VM pu, VA degrees; :attr:`RawData.solution`) at
    the buses the case keeps; a warning when either exceeds :data:`RAW_AGREEMENT` or the
    power flow does not converge (then None).  Generator buses whose RAW generation QG
    lies outside their own limits QB, QT (a RAW solved with those limits ignored) are
    named, with the gap of a power flow without Q limits beside it.  ``unsolved``: see
    `_solution_gap`."""
    import warnings

    gap = _solution_gap(case, solution, q_limits, unsolved=unsolved)
    if gap is None or max(gap["vmag_diff_pu"], gap["angle_diff_rad"]) <= RAW_AGREEMENT:
        return gap
    outside = _raw_q_outside(case) if q_limits else []
    if outside:
        gap["raw_q_outside_limits"] = outside
        gap["without_q_limits"] = _solution_gap(case, solution, False)
    free = gap.get("without_q_limits")
    warnings.warn(
        f"the power flow differs from the RAW file's own solution by up to "
        f"{gap['vmag_diff_pu']:.1e} pu (bus {gap['vmag_bus']}), "
        f"{gap['angle_diff_rad']:.1e} rad (bus {gap['angle_bus']}): the case does not "
        "start where the RAW file says ("
        + (
            "the RAW's generation lies outside its Q limits at "
            + ", ".join(
                f"bus {o['bus']} ({o['qgen_mvar']:.1f} Mvar, limits "
                f"[{o['qmin_mvar']:.1f}, {o['qmax_mvar']:.1f}])"
                for o in outside
            )
            + ": it was solved with those limits ignored"
            + (
                f"; without Q limits (simulate/cct --no-q-limits) the gap is "
                f"{max(free['vmag_diff_pu'], free['angle_diff_rad']):.1e}"
                if free
                else ""
            )
            if outside
            else "network data read otherwise, or a RAW file whose voltages are not its "
            "solved power flow"
        )
        + ")",
        stacklevel=2,
    )
    return gap


def _solution_gap(
    case, solution, q_limits: bool, against: str = "the RAW's", unsolved: str | None = None
) -> dict | None:
    """The largest |V| (pu) and angle (rad) differences, with their buses, between
    stabctl's power flow of ``case`` and a solution (bus number, VM pu, VA degrees, shape
    (n, 3)) at the buses the case keeps, without a warning on their size; None (and a
    warning naming ``against``) when the power flow does not converge, or, with
    ``unsolved``, a PowerFlowError (`_solved`)."""
    import numpy as np

    pf = _solved(case, q_limits, against, unsolved)
    if pf is None:
        return None
    kept = np.isin(solution[:, 0], case.buses.number)
    buses, rows = solution[kept, 0], case.bus_indices(solution[kept, 0])
    dv = np.abs(pf.vmag[rows] - solution[kept, 1])
    da = np.abs(pf.vang[rows] - np.deg2rad(solution[kept, 2]))
    return {
        "vmag_diff_pu": float(dv.max()),
        "vmag_bus": int(buses[dv.argmax()]),
        "angle_diff_rad": float(da.max()),
        "angle_bus": int(buses[da.argmax()]),
    }


def _solved(case, q_limits: bool, against: str, unsolved: str | None):
    """stabctl's power flow of ``case`` (``q_limits`` as said), or, when it does not
    converge, None with a warning that it is not compared with ``against`` solution, or,
    with ``unsolved`` (the source file's name), a PowerFlowError naming that file, how the
    power flow was solved (`_solved_as`), its worst mismatch and its bus and the imports'
    --keep-unsolved."""
    import warnings

    from stabctl.network.powerflow import solve_powerflow

    try:
        return solve_powerflow(case, q_limits=q_limits, tol=1e-10)
    except PowerFlowError as exc:
        if unsolved is not None:
            raise PowerFlowError(
                f"{unsolved}: stabctl's power flow of the case ({_solved_as(q_limits)}) "
                f"does not converge, so every analysis command would refuse it: {exc}; "
                "nothing written (--keep-unsolved writes it all the same)"
            ) from None
        warnings.warn(
            f"stabctl's power flow of the case did not converge: not compared with "
            f"{against} solution: {exc}",
            stacklevel=4,
        )
        return None


def _raw_q_outside(case) -> list[dict]:
    """PV buses whose data generation QG (the RAW's solution) lies outside [qmin, qmax]
    by more than 0.01 Mvar."""
    import numpy as np

    from stabctl.case import PV

    b = case.buses
    tol = 1e-4 * 0.1 / case.base_mva * 100  # 0.01 Mvar in pu
    qmax = np.where(b.qmax == 0, np.inf, b.qmax)
    qmin = np.where(b.qmin == 0, -np.inf, b.qmin)
    bad = (b.kind == PV) & ((b.qgen > qmax + tol) | (b.qgen < qmin - tol))
    mva = case.base_mva
    return [
        {
            "bus": int(b.number[i]),
            "qgen_mvar": float(b.qgen[i] * mva),
            "qmin_mvar": float(qmin[i] * mva),
            "qmax_mvar": float(qmax[i] * mva),
        }
        for i in np.flatnonzero(bad)
    ]


def _echo_raw_gap(gap: dict | None, how: str) -> None:
    if gap is None:
        return
    for label, g in ((how, gap), ("Q limits off", gap.get("without_q_limits"))):
        if g:
            click.echo(
                f"power flow against the RAW's solution ({label}): max |dV| "
                f"{g['vmag_diff_pu']:.1e} pu at bus {g['vmag_bus']}, max |d angle| "
                f"{g['angle_diff_rad']:.1e} rad at bus {g['angle_bus']}"
            )


#: largest power-flow difference to ANDES's (pu, rad) accepted without a warning
_PF_AGREEMENT = 1e-4


def _powerflow_gap(imported, case, unsolved: str | None) -> tuple[float | None, float | None]:
    """Largest |V| (pu) and angle (rad) differences between stabctl's power flow of the
    imported case (Q limits off, as ANDES's default; `case`, its dead islands perhaps left
    out) and ANDES's at the buses `case` keeps (`_solution_gap`); a warning when either
    exceeds 1e-4 or one of the two does not converge; ``unsolved``: see `_solved`."""
    import warnings

    import numpy as np

    if imported.pf_bus is None:
        warnings.warn("ANDES's power flow of the case did not converge: not compared", stacklevel=2)
        _solved(case, False, "ANDES's", unsolved)
        return None, None
    andes = np.column_stack([imported.pf_bus, imported.pf_vmag, np.rad2deg(imported.pf_vang)])
    try:
        gap = _solution_gap(case, andes, False, "ANDES's", unsolved=unsolved)
    except PowerFlowError as exc:  # ANDES's converged (round 48: not said, nor what was out)
        off = imported.out_of_service
        said = f"; {len(off)} device(s) out of service left out, as ANDES leaves them: " + (
            "; ".join(off[:3]) + ("; ..." if len(off) > 3 else "")
        )
        raise PowerFlowError(
            f"{exc} (ANDES's own power flow of the file converges{said if off else ''})"
        ) from None
    if gap is None:
        return None, None
    dv, da = gap["vmag_diff_pu"], gap["angle_diff_rad"]
    if max(dv, da) > _PF_AGREEMENT:
        warnings.warn(
            f"the power flow differs from ANDES's by up to {dv:.1e} pu, {da:.1e} "
            "rad: check the network data",
            stacklevel=2,
        )
    return dv, da


def _write_case_atomically(case, path: Path) -> None:
    """Write the case JSON to a temporary file beside ``path``, then rename it (noted:
    an interrupt after it says the case was written, `note_written`)."""
    from stabctl.io.pst import write_case_json
    from stabctl.parallel import atomic_write

    atomic_write(path, lambda tmp: write_case_json(case, tmp), mode=None)
    note_written(path)
