"""`stabctl omib`: the one-machine infinite bus of the paper's Sections 2-4."""

from __future__ import annotations

import math
from typing import Any

import click

from stabctl.cli.format import print_json
from stabctl.cli.options import _RANGES, FLOAT, interval, json_option, refuse_given, reports_errors
from stabctl.errors import InputError
from stabctl.smib.omib import TABLE_T_END


@click.command()
@click.option(
    "--fault-cycles",
    "-c",
    type=FLOAT,
    multiple=True,
    help="Fault durations in cycles: `--fault-cycles 6 12 15` (default 6 12 15), tabled "
    "shortest first however given; each "
    f"cleared before the run's end, {TABLE_T_END:g} s (at 60 Hz: fewer than "
    f"{TABLE_T_END * 60:g} cycles).",
)
@click.argument("more_cycles", nargs=-1, type=FLOAT)
@click.option("--H", "H", type=FLOAT, default=3.0, show_default=True, help="Inertia constant (s).")
@click.option("--pm", type=FLOAT, default=0.5, show_default=True, help="Mechanical power (pu).")
@click.option(
    "--delta0",
    type=FLOAT,
    default=0.4950,
    show_default=True,
    help="Pre-fault angle (rad); sets Pmax = Pm/sin(delta0).",
)
@click.option(
    "--pmax",
    type=FLOAT,
    default=None,
    help="Pre/post-fault Pmax (pu) instead of deriving it from delta0.",
)
@click.option("--f0", type=FLOAT, default=60.0, show_default=True, help="Frequency (Hz).")
@json_option("the clearing table and the EAC summary")
@reports_errors
def omib(fault_cycles, more_cycles, H, pm, delta0, pmax, f0, as_json):
    """One-machine infinite bus: clearing state per fault duration and the EAC CCT.

    Defaults are the paper's Section 2 case (H = 3 s, Pm = 0.5 pu, delta0 = 0.4950 rad,
    bolted fault at the generator bus, post-fault network = pre-fault).

    \b
    Example:
      stabctl omib --fault-cycles 6 12 15 --H 3.5
    """
    from stabctl.smib.omib import BISECTION_T_MAX, OMIB, clearing_table, eac_summary

    if pmax is not None:
        refuse_given(("delta0",), "with --pmax (Pmax is given; delta0 follows from it)")
    if pmax is None:
        lo, hi = _RANGES["--pmax"][:2]
        implied = pm / math.sin(delta0)  # delta0 in (0, pi/2): 1e-320 gives inf, named
        if not lo < implied <= hi:  # before the model's own checks (round 55 AS)
            raise InputError(
                f"--delta0 {delta0:g} with --pm {pm:g}: Pmax = Pm/sin(delta0) = "
                f"{implied:g} pu, outside the --pmax range {interval(_RANGES['--pmax'])}"
            )
        system = OMIB.from_operating_point(H=H, Pm=pm, delta0=delta0, f0=f0)
    else:
        system = OMIB(H=H, Pm=pm, Pmax_pre=pmax, Pmax_fault=0.0, Pmax_post=pmax, f0=f0)
    cycles = tuple(fault_cycles) + tuple(more_cycles) or (6.0, 12.0, 15.0)
    _check_before_end([("--fault-cycles", c) for c in (*fault_cycles, *more_cycles)], f0)
    twice = [c for k, c in enumerate(cycles) if c in cycles[:k]]
    if twice:
        raise InputError(f"--fault-cycles: {twice[0]:g} given twice (each duration once)")
    cycles = tuple(sorted(cycles))  # a table of clearing times reads shortest first
    out: dict[str, Any] = {"cases": clearing_table(system, cycles), "eac": eac_summary(system)}
    if as_json:
        print_json(out)
        return
    click.echo(f"{'cycles':>7} {'delta_cl rad':>13} {'omega_cl rad/s':>15}  verdict")
    for r in out["cases"]:
        click.echo(
            f"{r['cycles']:7.2f} {r['delta_cl_rad']:13.4f} {r['omega_cl_rad_s']:15.4f}  "
            f"{'stable' if r['stable'] else 'unstable'}"
        )
    e = out["eac"]
    bisection = (
        f"bisection {e['t_cr_bisection_s']:.4f} s"
        if e["t_cr_bisection_s"] is not None
        else f"bisection not run (it tries clearings up to {BISECTION_T_MAX:g} s)"
    )
    long = e["t_cr_s"] >= 1e5  # a Pm near 0: the machine barely accelerates
    click.echo(
        f"EAC: critical clearing angle {e['delta_cr_rad']:.4f} rad, CCT "
        f"{e['t_cr_s']:{'.4g' if long else '.4f'}} s "
        f"({e['t_cr_cycles']:{'.4g' if long else '.2f'}} cycles); {bisection}"
    )


def _check_before_end(given, f0: float) -> None:
    """InputError naming the first of ``given`` ((option, cycles) pairs) whose fault has no
    length (0 cycles, as `simulate` refuses one) or lasts until or past the end of each run
    (`stabctl.smib.omib.TABLE_T_END`): the option, the duration in cycles and s at --f0,
    the end and the most cycles that fit."""
    for option, cyc in given:
        if cyc == 0:  # as simulate refuses --clear-cycles 0
            raise InputError(
                f"{option} 0: cleared as it starts: a fault of no length would do nothing: "
                f"give {option} > 0"
            )
        if cyc / f0 >= TABLE_T_END:
            raise InputError(
                f"{option} {cyc:g}: {cyc:g} cycles = {cyc / f0:g} s at --f0 {f0:g} Hz, not "
                f"cleared before the end of each run, {TABLE_T_END:g} s (omib's fixed run "
                f"length): give fewer than {TABLE_T_END * f0:g} cycles"
            )
