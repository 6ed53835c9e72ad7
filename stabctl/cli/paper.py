"""`stabctl paper`: the paper's tables and figures."""

from __future__ import annotations

import json

import click

from stabctl.cli.checks import check_writable
from stabctl.cli.format import shown
from stabctl.cli.options import out_dir_option, reports_errors
from stabctl.errors import InputError


@click.command()
@out_dir_option("The report directory (paper.md, figures, records).")
@click.option(
    "--resume",
    is_flag=True,
    help="Continue the sweeps (Table 4 and estimator CCT sweeps, placement "
    "screening) from the records of an interrupted run in OUT_DIR/.paper-work, "
    "or else from the records in OUT_DIR; by default they are recomputed.",
)
@click.option(
    "--only",
    multiple=True,
    type=click.Choice(
        ["analytic", "cases", "convergence", "table4", "wecc", "estimation", "placement"]
    ),
    help="Build only these parts (repeatable, each part once; wall times on 2 quiet cores, "
    "kernels compiled (`stabctl compile`, once)): analytic = "
    "Sections 2-4 (seconds); cases = Cases 1 and 2 (under a minute, with the "
    "first compilation); table4 = CCT sweeps (15 s); wecc = Case 2 and Table 4 with "
    "WECC batteries beside ideal ESDs; estimation = "
    "estimator Monte Carlo and in-the-loop CCTs (under 2 minutes); placement = "
    "the planner's ESD sizing and placement studies (about 4.5 minutes); "
    "convergence = CCT against the step under both conventions (half a "
    "minute).  All: about 8 minutes (7.6 min, 10.3 CPU-min, measured 2026-11-30). "
    "Default: all; with --only, paper.md holds only those parts.",
)
@reports_errors
def paper(out_dir, resume, only):
    """Reproduce the paper's tables and figures into OUT_DIR/paper.md (+ PNG figures).

    The Table 4 and estimator CCT sweeps and the placement screening record each finished
    search in OUT_DIR/.paper-work as it completes (an interrupted run continues from there
    with --resume). Only when every section has succeeded are the reports moved into OUT_DIR
    and the records written to OUT_DIR/table4_<case>.jsonl, OUT_DIR/estimation_cct_<case>.jsonl
    and OUT_DIR/placement_<case>_screening.jsonl, replacing the old ones; reports and records
    hold no timings or other run-dependent values (two runs on one machine give identical
    files; another machine's libm moves the storage energies in their third or fourth
    digit), those go to OUT_DIR/run_log.json (seconds per section, every progress line).

    \b
    Example:
      stabctl paper --out-dir reports/paper --only analytic
    """
    from stabctl.studies.paper import RUN_LOG, run_summary, write_paper_report

    twice = [p for k, p in enumerate(only) if p in only[:k]]
    if twice:  # as a repeated item of a list option
        raise InputError(f"--only: {twice[0]} given twice (each part once)")
    check_writable(out_dir, "--out-dir", directory=True)
    path = write_paper_report(out_dir, resume=resume, only=only)
    click.echo(run_summary(json.loads((path.parent / RUN_LOG).read_text("utf-8"))))
    click.echo(f"wrote {shown(path)}")
