"""`stabctl place`: least-cost storage sites, MW and MWh meeting clearing-time or CCT
requirements on every fault, at every load level, verified by simulation."""

from __future__ import annotations

import json
import sys
import warnings
from dataclasses import replace

import click

from stabctl.cli.checks import check_suffix, model_settings, search_settings
from stabctl.cli.format import print_json, print_plan
from stabctl.cli.options import (
    FLOAT,
    INT,
    AliasedOption,
    comma_list,
    controller,
    esd_model_option,
    faults_option,
    json_option,
    keep_until_end,
    model_options,
    named_option,
    out_file_option,
    parallel_options,
    q_limits_option,
    read_fault_list,
    refuse_given,
    reports_errors,
    storage_options,
    tol_options,
)
from stabctl.errors import InputError


@click.command()
@click.argument("case_name", metavar="CASE")
@faults_option
@click.option(
    "--required-clearing-cycles",
    type=FLOAT,
    default=None,
    metavar="N",
    help="Every contingency stable when cleared after N cycles (cycles).",
)
@click.option(
    "--target-cct-gain",
    type=FLOAT,
    default=None,
    metavar="PCT",
    help="Required CCT of every contingency: its CCT without storage raised by PCT (%).",
)
@click.option(
    "--target-cct-s",
    type=FLOAT,
    default=None,
    metavar="S",
    help="Required CCT of every contingency (s).  Any mix of the three: the "
    "strictest wins; a --faults CSV may override them per fault (columns "
    "required_clearing_cycles, target_cct_gain, target_cct_s).",
)
@click.option(
    "--load-levels",
    default="1",
    show_default=True,
    metavar="LIST",
    help="Load levels, comma-separated fractions of the base load (e.g. "
    "0.9,1.0,1.1; each in [0.1, 10]): loads and dispatch scaled, power flow re-solved; every "
    "contingency is verified at each.",
)
@click.option(
    "--cost-mw",
    type=FLOAT,
    default=1.0,
    show_default=True,
    metavar="C",
    help="Cost per MW of rating.",
)
@click.option(
    "--cost-mwh",
    type=FLOAT,
    default=0.0,
    show_default=True,
    metavar="C",
    help="Cost per MWh of usable energy (sized from the verifying runs).",
)
@click.option(
    "--cost-site",
    "--site-cost",
    "cost_site",
    cls=AliasedOption,
    type=FLOAT,
    default=0.0,
    show_default=True,
    metavar="C",
    help="Cost per site used.",
)
@click.option(
    "--site-costs",
    type=click.Path(dir_okay=False),
    default=None,
    metavar="FILE",
    help="Per-site costs: CSV with a machine column and any of cost_mw, cost_mwh, cost_site.",
)
@click.option(
    "--zeta-min",
    type=FLOAT,
    default=None,
    metavar="Z",
    help="Least damping ratio of every electromechanical mode (bang-bang ESDs "
    "as their describing-function gain at --amplitude-hz).",
)
@click.option(
    "--max-sites", type=INT, default=None, metavar="N", help="At most N sites (greedy elimination)."
)
@click.option(
    "--max-site-pct",
    type=FLOAT,
    default=50.0,
    show_default=True,
    metavar="P",
    help="Largest rating per site (% of its generator's MVA).",
)
@click.option(
    "--amplitude-hz",
    type=FLOAT,
    default=0.2,
    show_default=True,
    help="Relative-speed amplitude at which the damping is required (Hz).",
)
@click.option(
    "--uniform-reference",
    is_flag=True,
    help="Also the least uniform fleet (same % at every generator, bisection) "
    "meeting the same requirements.",
)
@click.option("--alone", is_flag=True, help="Also each binding fault's own least allocation.")
@click.option(
    "--screening",
    type=click.Path(dir_okay=False, exists=True),
    default=None,
    metavar="FILE.jsonl",
    help="Records of a screening without storage (`stabctl screen --out`): its "
    "CCT brackets are reused (faults known stable at the requirement are "
    "not simulated again, CCT searches start there, the most binding are "
    "ranked by them).",
)
@click.option(
    "--set-aside-infeasible",
    is_flag=True,
    help="A contingency that storage at the candidate sites cannot make meet its "
    "requirement (proven by simulation with every site at its bound), or whose "
    "fault cannot be simulated without storage while it is on (in a case with "
    "converters each is held on for --t-max first, one short run), or that is N-1 "
    "insecure (its CCT search without storage: unstable even when cleared at once), is "
    "listed under its own label and the others are planned for "
    "(default: error, exit 2).",
)
@storage_options(with_rating=False, critical=True)
@esd_model_option
@tol_options(
    t_max_help="a fault still stable there is a verdict: CCT above it, robust; a CCT "
    "target at or above it is refused"
)
@click.option(
    "--max-iter",
    type=INT,
    default=10,
    show_default=True,
    help="Allocations simulated at most per round of constraint generation.",
)
@click.option(
    "--max-rounds",
    type=INT,
    default=6,
    show_default=True,
    help="Rounds of constraint generation at most (solve, check every "
    "contingency, add those that fail).",
)
@parallel_options
@model_options
@q_limits_option
@out_file_option(metavar="FILE.json", help="The result as JSON (written when done).")
@json_option()
@reports_errors
def place(
    case_name,
    faults_src,
    required_clearing_cycles,
    target_cct_gain,
    target_cct_s,
    load_levels,
    cost_mw,
    cost_mwh,
    cost_site,
    site_costs,
    zeta_min,
    max_sites,
    max_site_pct,
    amplitude_hz,
    uniform_reference,
    alone,
    screening,
    set_aside_infeasible,
    deadband_hz,
    v_gate,
    coi,
    hysteresis_hz,
    esd_model,
    tol_ms,
    t_max,
    max_iter,
    max_rounds,
    workers,
    scheduler,
    conventions,
    step,
    q_limits,
    out_path,
    as_json,
):
    """Least-cost energy storage (sites, MW and MWh) such that every contingency meets its
    requirement at every load level, verified by nonlinear simulation.

    \b
    Candidate sites: every generator's HV bus, the ESD driven by that generator (the
    paper's bang-bang law). Constraint generation: the most binding few contingencies
    are solved for (a trust-region loop of linear programs, cvxpy + Clarabel, whose
    constraints are CCTs linearised in the ratings and verified by simulation), every
    contingency is then simulated cleared at its required time, those that fail are
    added, and so on. Each device's energy (MWh) is sized from the state of charge
    along the verifying runs and checked by simulation (docs/placement.md).
    --coi critical (not the paper's law): the law armed per contingency, each device on
    the COI of the other group, the group the machines that contingency's fault
    separates without storage (docs/placement.md section 8).

    \b
    Examples:
      stabctl place kundur --faults DEFAULT --target-cct-gain 10
      stabctl place miniwecc --faults faults.csv --required-clearing-cycles 5 \\
          --load-levels 0.9,1.0,1.1 --cost-mw 1 --cost-mwh 0.3 --uniform-reference

    \b
    The run's end: the checks are judged 5 s after the fault start, the CCT search's
    window. A contingency whose CCT search separated late in it (as `cct` checks) has its
    check run 5 s longer with the allocation; one that loses synchronism there is named
    NOT CONVERGED IN THE RUN'S END and the plan is "VERIFIED in the 5-s window" (exit 0:
    a verdict on the window, said in the text and the JSON's run_end).

    Exit status: 0 verified; 1 not verified within --max-rounds/--max-iter; 2 bad input
    or infeasible (the `error:` line names the contingency and its load level), or N-1
    insecure without --set-aside-infeasible.
    """
    from stabctl.io import load_case
    from stabctl.parallel import RunnerOptions, atomic_write, default_workers
    from stabctl.placement.loop import PlaceOptions, Study
    from stabctl.placement.plan import PlanOptions, plan
    from stabctl.placement.program import candidate_sites
    from stabctl.placement.requirements import (
        CostModel,
        Requirement,
        read_requirements,
        read_site_costs,
        screening_brackets,
    )

    search = search_settings(tol_ms, t_max, None, tf_option=False)
    if workers is not None and workers < 1:
        raise InputError(f"--workers must be >= 1, got {workers}")
    if max_sites is not None and max_sites < 1:
        raise InputError(f"--max-sites must be >= 1, got {max_sites}")
    if zeta_min is not None and not 0 <= zeta_min < 1:
        raise InputError(f"--zeta-min must be in [0, 1), got {zeta_min:g}")
    if zeta_min is None:
        refuse_given(("amplitude_hz",), "without --zeta-min (no damping is required)")
    if max_rounds < 1:
        raise InputError(f"--max-rounds must be >= 1, got {max_rounds}")
    if all(v is None for v in (required_clearing_cycles, target_cct_gain, target_cct_s)):
        raise InputError(
            "give a requirement: --required-clearing-cycles, --target-cct-gain or --target-cct-s"
        )
    for opt, v in (
        ("--required-clearing-cycles", required_clearing_cycles),
        ("--target-cct-gain", target_cct_gain),
        ("--target-cct-s", target_cct_s),
    ):
        if v is not None and not v > 0:
            raise InputError(f"{opt} must be > 0, got {v:g}")
    req = Requirement(required_clearing_cycles, target_cct_gain, target_cct_s)
    levels = _load_levels(load_levels)
    check_suffix(out_path, (".json",), "--out")
    case = load_case(case_name)
    n_mac = len(case.machines.bus)
    with named_option("--site-costs"):  # the file's refusals with the option (round 55)
        by_site = read_site_costs(site_costs, n_mac, case.infinite_buses()) if site_costs else {}
    cost = CostModel(cost_mw, cost_mwh, cost_site, by_site)
    model = model_settings(conventions, step, q_limits)
    with named_option("--screening"):
        brackets = (
            screening_brackets(
                screening, case_name, case.digest(), {**model.to_inputs(), "t_end": search.t_end}
            )
            if screening
            else None
        )
    faults = read_fault_list(case, case_name, faults_src)
    overrides = read_requirements(faults_src) if faults_src != "DEFAULT" else {}
    sites = candidate_sites(case, max_site_pct)
    n = min(workers or default_workers(), len(faults) * len(levels))
    # without --json the progress lines go to the log, which the CLI shows on stderr
    options = PlanOptions(
        load_levels=levels,
        overrides=overrides,
        cost=cost,
        brackets=brackets,
        max_rounds=max_rounds,
        uniform=uniform_reference,
        alone=alone,
        drop_infeasible=set_aside_infeasible,
        half_step_verdicts=True,  # a plan's verdicts shown converged in the step
        place=PlaceOptions(
            zeta_min=zeta_min, amplitude_hz=amplitude_hz, max_sites=max_sites, max_iter=max_iter
        ),
    )
    armed = coi == "critical"  # the law armed per contingency: its group found by the workers
    study = Study(
        sites=sites,
        controller=controller(deadband_hz, v_gate, "system" if armed else coi, hysteresis_hz),
        critical_reference=armed,
        search=search,
        model=model,
        runner=RunnerOptions(n, scheduler),
        esd_model=esd_model,
    )
    # an interrupted plan run again simulates only the rest: its memo is named by what
    # the plan's results depend on (not by its workers)
    memo = _memo(case, (faults, req, options, replace(study, runner=RunnerOptions())))
    options = replace(options, memo=memo)
    result = _kept_plan(
        memo,
        lambda: plan(
            case_name, faults, req, options, study, progress=(lambda msg: None) if as_json else None
        ),
    )
    out = {"case": case.name, "esd_model": esd_model, "settings": _settings(study, case_name)}
    out.update(result.to_dict())
    if as_json:
        print_json(out)
    else:
        print_plan(case, out)
    if out_path:  # after the plan is shown: a full disk does not lose the run
        atomic_write(out_path, lambda f: json.dump(out, f, indent=1, default=float))
    if not result.verified:
        sys.exit(1)


def _memo(case, plan_inputs):
    """The `stabctl.placement.memo.Memo` of a plan of `case` (this user's
    `stabctl.locking.kept_path`, named by the case's digest and the plan's inputs,
    `plan_inputs`: another plan of the case has its own), telling on stderr how many
    finished simulations of an interrupted plan it holds; None, with a warning, where it
    cannot be kept (the plan runs all the same)."""
    import hashlib

    from stabctl.locking import kept_paths, remove_old_kept
    from stabctl.placement.memo import Memo, MemoHeld

    name = hashlib.sha256(f"{case.digest()}\n{plan_inputs!r}".encode()).hexdigest()[:32]
    why = []
    for path in kept_paths("stabctl-place", f"{name}.jsonl"):
        try:
            memo = Memo(path)
            break
        except MemoHeld as exc:  # the same plan running: this one must not run on alone
            warnings.warn(
                f"{exc} (the same command, started before): this plan's simulations are not kept",
                stacklevel=2,
            )
            return None
        except InputError as exc:  # the next place, or none
            why.append(str(exc))
    else:
        warnings.warn(
            f"{'; '.join(why)}: the plan's finished simulations are not kept (an "
            "interrupted plan starts again from the beginning)",
            stacklevel=2,
        )
        return None
    remove_old_kept(memo.path.parent)  # plans refused or never run again, long ago
    if memo.n_read or memo.n_damaged:
        damaged = (
            f" ({memo.n_damaged} line(s) not as written passed over)" if memo.n_damaged else ""
        )
        click.echo(
            f"{memo.n_read} finished simulation job(s) of an interrupted plan of this case "
            f"read from {memo.path}{damaged}: those of this plan are not run again",
            err=True,
        )
    return memo


def _kept_plan(memo, run):
    """`run()` (the plan), its memo kept when it is interrupted, its output is not
    written or its workers were lost (the same command then simulates only the rest),
    removed once the command has ended (`keep_until_end`)."""
    if memo is None:
        return run()
    keep_until_end(memo.kept, memo.remove, memo.close)
    result = run()
    if memo.n_reused:  # an earlier plan's jobs only: a repeat within this plan is no news
        click.echo(
            f"{memo.n_reused} simulation job(s) taken from the interrupted plan "
            f"({memo.path}), not run again",
            err=True,
        )
    return result


def _settings(study, case_name: str) -> dict:
    """The plan's numerical and control settings, as its JSON records them (names with
    their units, as `cct --json`'s): the model (conventions, the step of the runs in s,
    the case's default when none is given, Q limits, multi-rate exciters), the CCT search
    (tolerance, t_max and run end in s, None: the fault start + 5 s) and the devices' law
    (``coi`` "critical" with ``critical`` None: each contingency's group, found without
    storage)."""
    from dataclasses import asdict

    from stabctl.stability.cct import cached_simulator

    m, s, c = study.model, study.search, study.controller
    step = cached_simulator(case_name, m).default_h if m.h is None else m.h
    law = asdict(c)
    if study.critical_reference:
        law.update(coi="critical", critical=None)
    return {
        "conventions": m.conventions,
        "step_s": step,
        "q_limits": m.q_limits,
        "subintervals": m.subintervals,
        "tol_s": s.tol,
        "t_max_s": s.t_max,
        "t_end_s": s.t_end,
        "controller": law,
    }


#: the load levels place takes, fractions of the base load: from a tenth of it to ten
#: times it (1e9 or 1e-9 was refused only when its power flow failed, seconds later)
LOAD_LEVELS = (0.1, 10.0)


def _load_levels(text: str) -> tuple:
    """The --load-levels list: numbers in LOAD_LEVELS.  Raises InputError."""
    levels = tuple(comma_list(text, "--load-levels", float, "a number"))
    lo, hi = LOAD_LEVELS
    bad = [x for x in levels if not lo <= x <= hi]
    if bad:
        raise InputError(
            f"--load-levels {text}: {bad[0]:g} is outside [{lo:g}, {hi:g}] (fractions of the "
            f"base load: from {lo:g} to {hi:g} times it)"
        )
    return levels
