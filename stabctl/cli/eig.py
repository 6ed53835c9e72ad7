"""`stabctl eig`: small-signal modes of a case."""

from __future__ import annotations

import shlex
from pathlib import Path

import click

from stabctl.cli.checks import check_writable
from stabctl.cli.format import print_json, print_modes, shown
from stabctl.cli.options import (
    INT,
    conventions_option,
    json_option,
    out_dir_option,
    q_limits_option,
    refuse_given,
    reports_errors,
)
from stabctl.errors import InputError


@click.command()
@click.argument("case_name", metavar="CASE")
@click.option(
    "--no-pss", is_flag=True, help="Analyse the case with its PSS removed (pss_con empty)."
)
@click.option(
    "--areas",
    "n_areas",
    type=INT,
    default=None,
    metavar="N",
    help="Number of coherent areas for the local/inter-area classification "
    "(default: from a gap in the electromechanical frequencies, docs/modal.md).",
)
@click.option(
    "--report",
    is_flag=True,
    help="Write OUT_DIR/eig_<CASE>[_nopss][_areasN][_pstess][_noqlimits][_limits-X].md "
    "(CASE as given, a file's own name; the settings other than their defaults) with the "
    "eigenvalue plot, mode-shape compass plots and participation bar charts (PNG); its "
    "header gives the command that made it.",
)
@out_dir_option("The report directory (with --report).")
@conventions_option
@q_limits_option
@click.option(
    "--limits",
    type=click.Choice(["auto", "hold", "free", "refuse"]),
    default="auto",
    show_default=True,
    help="A limit active at the operating point (a valve at VMIN, a pitch at its minimum): "
    "free when reached, held when driven into (auto), always held, always free, or "
    "refuse (docs/modal.md, Limiters).",
)
@json_option("every mode")
@reports_errors
def eig(case_name, no_pss, n_areas, report, out_dir, conventions, q_limits, limits, as_json):
    """Small-signal modes: linearise CASE at its power flow and list its modes.

    The simulator's own equations are linearised by central differences (PSTess svm_mgen's
    method; docs/modal.md). Printed: the electromechanical modes (0.1-2.5 Hz, dominated by
    rotor angle and speed states) with frequency (Hz), damping ratio, dominant machines,
    and local / inter-area by their mode shapes; --json prints every mode (eigenvalue,
    frequency, damping, kind, dominant states, and for electromechanical modes the
    coherent groups, speed mode shape and the ESD bus with the largest residue).
    Under either --conventions the linear model is the same (a point inside every
    limit; docs/conventions.md).

    \b
    Examples:
      stabctl eig kundur --report
      stabctl eig kundur --no-pss --json
      stabctl eig miniwecc --areas 3 --report

    Bad input (unknown case, --areas out of range, --out-dir a file) exits with status 2 and
    one `error:` line; nothing is written then.
    """
    from stabctl.io import load_case
    from stabctl.smallsignal.modal import AreaCountError
    from stabctl.studies.eigenvalues import eig_study, study_json, write_report

    if not report:
        refuse_given(("out_dir",), "without --report (nothing is written)")
    if Path(out_dir).exists() and not Path(out_dir).is_dir():
        raise InputError(f"--out-dir {out_dir} is not a directory")
    if report:
        check_writable(out_dir, "--out-dir", directory=True)
    case = load_case(case_name)
    if no_pss and not len(case.pss):  # it changed nothing, the report named "_nopss"
        raise InputError(f"--no-pss: case '{case.name}' has no stabiliser (PSS) to leave out")
    if n_areas is not None and n_areas > len(case.machines):
        raise InputError(
            f"--areas {n_areas}: case '{case.name}' has {len(case.machines)} machine(s), "
            "and each area at least one"
        )
    from stabctl import progress

    beat = progress.Heartbeat(
        lambda line: click.echo(line, err=True), "eig: {}".format, progress.HEARTBEAT_S
    )
    beat.note(  # said every 8 s of a long linearisation (a planning case: about a minute)
        f"still linearising and analysing case {case.name} ({len(case.machines)} machines)"
    )
    try:
        with beat:
            st = eig_study(
                case,
                no_pss=no_pss,
                n_areas=n_areas,
                conventions=conventions,
                q_limits=q_limits,
                limits=limits,
            )
    except AreaCountError as exc:  # fewer electromechanical modes than machines - 1
        raise InputError(f"--areas {n_areas}: {exc}") from None
    written = []
    if report:
        stem, command = _report_name(
            case_name, no_pss, n_areas, out_dir, conventions, q_limits, limits
        )
        replaced = (Path(out_dir) / f"{stem}.md").exists()
        path = write_report(st, out_dir, stem, command)
        written.append(str(path) + (" (the report there replaced)" if replaced else ""))
    if as_json:
        print_json(
            {**study_json(st), "conventions": conventions, "q_limits": q_limits, "files": written}
        )
        return
    print_modes(st, no_pss)
    for w in written:
        click.echo(f"wrote {shown(w)}")


def _report_name(case_name, no_pss, n_areas, out_dir, conventions, q_limits, limits):
    """(file stem, command) of a report: named after CASE as given (a case file's own
    name, not the name inside it: two cases imported from one RAW file are two reports)
    and the settings that change the modes, other than their defaults; the command the
    report says made it, those settings and --out-dir as given."""
    settings = [
        ("--no-pss", "nopss", no_pss),
        (f"--areas {n_areas}", f"areas{n_areas}", n_areas is not None),
        (f"--conventions {conventions}", conventions, conventions != "ieee"),
        ("--no-q-limits", "noqlimits", not q_limits),
        (f"--limits {limits}", f"limits-{limits}", limits != "auto"),
    ]
    stem = "_".join([f"eig_{Path(case_name).stem}", *(tag for _, tag, on in settings if on)])
    given = [option for option, _, on in settings if on]
    default = str(out_dir) == "reports"  # the option's default
    where = [] if default else [f"--out-dir {shlex.quote(str(out_dir))}"]
    command = " ".join(["stabctl eig", shlex.quote(case_name), *given, "--report", *where])
    return stem, command
