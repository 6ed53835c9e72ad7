"""`stabctl place`: least-MW storage sites and ratings for target CCTs."""

from __future__ import annotations

import sys

import click

from stabctl.errors import InputError
from stabctl.cli.format import print_json, print_placement
from stabctl.cli.checks import cct_settings
from stabctl.cli.options import (controller, faults_option, json_option, model_options,
                                 parallel_options, read_fault_list, reports_errors,
                                 storage_options, tol_options)


@click.command()
@click.argument("case_name", metavar="CASE")
@faults_option
@click.option("--target-cct-gain", type=float, required=True, metavar="PCT",
              help="Required CCT of every contingency: its CCT without storage raised by "
                   "PCT (%).")
@click.option("--zeta-min", type=float, default=None, metavar="Z",
              help="Least damping ratio of every electromechanical mode (bang-bang ESDs "
                   "as their describing-function gain at --amplitude-hz).")
@click.option("--max-sites", type=int, default=None, metavar="N",
              help="At most N sites (reweighted l1, then the N largest).")
@click.option("--max-site-pct", type=float, default=50.0, show_default=True, metavar="P",
              help="Largest rating per site (% of its generator's MVA).")
@click.option("--site-cost", type=float, default=0.0, show_default=True, metavar="C",
              help="Cost of each site in MW-equivalents (fewer, larger sites).")
@click.option("--amplitude-hz", type=float, default=0.2, show_default=True,
              help="Relative-speed amplitude at which the damping is required (Hz).")
@storage_options(with_rating=False)
@tol_options()
@click.option("--max-iter", type=int, default=10, show_default=True,
              help="Allocations simulated at most.")
@parallel_options
@model_options
@json_option()
@reports_errors
def place(case_name, faults_src, target_cct_gain, zeta_min, max_sites, max_site_pct,
          site_cost, amplitude_hz, deadband_hz, v_gate, coi, hysteresis_hz, tol_ms, t_max,
          max_iter, workers, scheduler, conventions, step, as_json):
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
      stabctl place kundur --faults DEFAULT --target-cct-gain 10
      stabctl place miniwecc --faults faults.csv --target-cct-gain 40 --max-sites 3

    Exit status: 0 verified; 1 not verified within --max-iter; 2 bad input or infeasible
    (the `error:` line names the contingency).
    """
    from stabctl.io import load_case
    from stabctl.placement.program import candidate_sites
    from stabctl.placement.loop import baseline, place as run_place, with_gain
    from stabctl.parallel import default_workers

    settings = cct_settings(tol_ms, t_max, None)
    if workers is not None and workers < 1:
        raise InputError(f"--workers must be >= 1, got {workers}")
    if max_sites is not None and max_sites < 1:
        raise InputError(f"--max-sites must be >= 1, got {max_sites}")
    if zeta_min is not None and not 0 <= zeta_min < 1:
        raise InputError(f"--zeta-min must be in [0, 1), got {zeta_min:g}")
    if not target_cct_gain > 0:
        raise InputError(f"--target-cct-gain must be > 0 %, got {target_cct_gain:g}")
    case = load_case(case_name)
    faults = read_fault_list(case_name, faults_src)
    sites = candidate_sites(case, max_site_pct)
    ctrl = controller(deadband_hz, v_gate, coi, hysteresis_hz)
    n = min(workers or default_workers(), len(faults))
    kw = {"sites": sites, "tol": settings["tol"], "t_max": settings["t_max"], "workers": n,
          "scheduler": scheduler, "controller": ctrl, "conventions": conventions, "h": step}
    say = (lambda msg: None) if as_json else (lambda msg: click.echo(msg, err=True))
    base = baseline(case_name, faults, **kw)
    result = run_place(case_name, with_gain(faults, base, target_cct_gain, settings["tol"]),
                       zeta_min=zeta_min, max_sites=max_sites, site_cost=site_cost,
                       amplitude_hz=amplitude_hz, max_iter=max_iter, base=base,
                       progress=say, **kw)
    out = {"case": case.name, "target_cct_gain_pct": target_cct_gain, **result.to_dict()}
    if as_json:
        print_json(out)
    else:
        print_placement(case.name, out)
    if not result.verified:
        sys.exit(1)
