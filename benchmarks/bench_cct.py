"""Simulations and wall time per CCT search, the bisection against SIME's search (not a test).

Per system, the CCT of every fault of a screening sample at the defaults of
`stabctl.stability.cct.critical_clearing_time` (1 ms bracket, t_end = fault + 5 s, runs
stopped at separation, the half-step error bar, ieee conventions, the case's default
step), pinned to one core after a warm-up run (compilation and the power flow excluded):

* ``bisection``: SearchOptions(method="bisection", early_stop=False), the search before
  SIME's (check at 0, doubling from 0.1 s, bisection; every run to its end or to
  separation);
* ``sime``: SearchOptions(method="sime"), SIME's unstable margins extrapolated to
  the CCT, bisection to finish, the check at 0 only when no stable probe came first;
* ``sime-early``: the same search, its runs ended at SIME's certain verdicts
  (early_stop=True).

Systems: kundur (every bus and line fault), miniwecc (every --every-th of its bus and
line faults), activsg2000 (with --activsg: the line fault 2021-2002 and the bus fault
2021 of the project's tests, imported from tests/data/activsg as docs/cli.md does; a
few minutes).  Prints per system: faults searched, CCTs found (the others: verdicts N-1
insecure or above t_max, counted apart), the mean simulations per CCT (all, and at
the step only), the wall time per CCT, and whether every CCT and half-step CCT of
"sime" equals the bisection's (same 1 ms bracket).  ``--paper`` adds the paper's two
faults under both conventions, with and without the error bar (the earlier table).
For ACTIVSg2000 it also prints the N-1 projection: the bus and line screening's 5 206 CCT
searches (2 000 buses, 3 206 line-end faults) at the measured wall per
search, on 2 cores with perfect scaling, against the 30 min target.
``--activsg-sample N`` searches a random sample of ACTIVSg2000's N-1 (N bus faults, N line
faults, seed 53) at ``--t-max`` (default 0.5 s, `stabctl screen`'s) with both methods and
prints the verdicts, simulations per search (verdicts included) and per CCT, the wall per
search with each fault's network stages built as a screening builds them, the N-1
projection from that mean (and from the CPU time per search, which other work on the
machine inflates less) and how many faults end with the same verdict, cell and
half-step CCT in both (the two-fault projection above counts CCT searches only).
``--activsg-guess N`` searches N random line faults of ACTIVSg2000 whose bus fault has a
CCT (seed 53; the bus fault searched first, as `stabctl screen` does) without and with
that CCT as the guess (`SearchOptions.guess_s`, the screening's start for such a fault)
by the sime search at ``--t-max``, and prints the simulations per CCT, the CPU time per
search of each and how many end with the same verdict, cell and half-step CCT.
``--activsg-stages N`` times the network stages of N new bus and N new line faults of
ACTIVSg2000 (a first run of a fault less a second), updated from the pre-event network's
reduction (`stabctl.network.lowrank`) and factorised anew.
Run: python benchmarks/bench_cct.py [--every 4] [--activsg] [--activsg-sample 20]
         [--activsg-guess 20] [--activsg-stages 15] [--paper] [--systems kundur miniwecc]
"""

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

from stabctl.dynamics.driver import Simulator
from stabctl.errors import InputError
from stabctl.io import load_case
from stabctl.stability.cct import LineFault, SearchOptions, critical_clearing_time
from stabctl.stability.screening import screening_faults
from stabctl.studies.cases import CASE1, CASE2

METHODS = {
    "bisection": SearchOptions(method="bisection", early_stop=False),
    "sime": SearchOptions(method="sime"),
    "sime-early": SearchOptions(method="sime", early_stop=True),
}


def activsg2000():
    """ACTIVSg2000 as bench_scale.py imports it."""
    sys.path.insert(0, str(Path(__file__).parent))
    from bench_scale import _activsg2000

    with tempfile.TemporaryDirectory() as work:
        return _activsg2000(work)


def compare(label, case, faults):
    """Search every fault with both methods; print one line per method."""
    t = time.perf_counter()
    sim = Simulator(case)
    build = time.perf_counter() - t
    sim.run(faults[0].events(0.05), t_end=faults[0].t_fault + 1.0)  # warm-up (compilation)
    out: dict = {m: [] for m in METHODS}
    walls: dict = {}
    for f in faults:
        for m, opts in METHODS.items():
            try:
                out[m].append(critical_clearing_time(sim, f, opts))
            except InputError as exc:  # verdicts (N-1 insecure, above t_max) and failures
                out[m].append(type(exc).__name__)
    same = sum(
        1
        for a, b in zip(out["bisection"], out["sime"])
        if (isinstance(a, str) and a == b)
        or (
            not isinstance(a, str)
            and not isinstance(b, str)
            and a.bracket == b.bracket
            and a.cct_half_step_s == b.cct_half_step_s
        )
    )
    for m, res in out.items():
        found = [r for r in res if not isinstance(r, str)]
        walls[m] = sum(r.wall_time_s for r in found) / max(len(found), 1)
        n = max(len(found), 1)
        sims = sum(r.n_simulations for r in found) / n
        at_h = sum(len(r.probes) for r in found) / n
        wall = sum(r.wall_time_s for r in found) / n
        early = sum(r.early_stops for r in found) / n
        print(
            f"{label:12} {len(faults):6d} {len(found):5d} {m:9} {sims:8.2f} {at_h:8.2f} "
            f"{early:7.2f} {wall:9.3f} {build:7.2f} {same:4d}/{len(faults)}",
            flush=True,
        )
    return walls


def n1_projection(walls: dict) -> None:
    """ACTIVSg2000's bus and line N-1 screening projected from the wall per search."""
    print(f"\nACTIVSg2000 N-1 projection: {N1_SEARCHES} CCT searches on 2 cores (target 30 min)")
    for m, w in walls.items():
        print(f"  {m:10} {w:7.1f} s per search -> {N1_SEARCHES * w / 2 / 3600:6.1f} h")


#: CCT searches of ACTIVSg2000's bus and line N-1 screening (2 000 buses, 3 206 line ends)
N1_SEARCHES = 5206


def n1_sample(case, n: int, t_max: float, seed: int = 53) -> None:
    """A random sample of ACTIVSg2000's N-1 (n bus faults, n line faults with the line
    tripped; `random.Random(seed)`), searched as `stabctl screen` does (t_max, tol 1 ms,
    half-step error bar) by each method: verdicts, simulations and wall per search over
    every search (verdicts included, each at its own cost: a robust fault's runs are all
    stable, an N-1 insecure one's two are short) and the N-1 projection from that mean."""
    import random

    rng = random.Random(seed)
    lines = [f for f in screening_faults(case, lines=True) if f.far_bus is not None]
    faults = rng.sample(screening_faults(case), n) + rng.sample(lines, n)
    sim = Simulator(case)
    sim.run(faults[0].events(0.05), t_end=faults[0].t_fault + 1.0)  # warm-up (compilation)
    print(
        f"\nACTIVSg2000 N-1 sample: {n} bus + {n} line faults (seed {seed}), t_max {t_max:g} s "
        "(stabctl screen's default), tol 1 ms, half-step error bar; each fault's network "
        "stages built in its search, as in a screening"
    )
    print(
        f"{'method':10} {'CCTs':>5} {'robust':>6} {'insec':>5} {'sims/search':>11} "
        f"{'sims/CCT':>8} {'wall/search':>11} {'N-1 on 2 cores':>14} {'CPU/search':>10} "
        f"{'N-1 from CPU':>12}"
    )
    runs = [0]
    run = sim.run

    def counted(*a, **k):
        runs[0] += 1
        return run(*a, **k)

    sim.run = counted  # type: ignore[method-assign]  # every search's runs, verdicts' too
    outcomes: dict = {}
    for m in ("bisection", "sime"):
        opts = SearchOptions(method=m, t_max=t_max)
        found, kinds, t0, runs[0] = [], [], time.perf_counter(), 0
        c0 = time.process_time()
        for f in faults:  # each fault's stages evicted by the 8 faults after it
            try:
                res = critical_clearing_time(sim, f, opts)
                found.append(res.n_simulations)
                kinds.append("cct")
                outcomes.setdefault(m, []).append((res.bracket, res.cct_half_step_s))
            except InputError as exc:
                kinds.append(type(exc).__name__)
                outcomes.setdefault(m, []).append(type(exc).__name__)
        wall = (time.perf_counter() - t0) / len(faults)
        cpu = (time.process_time() - c0) / len(faults)  # a measure that a busy machine
        print(  # inflates less than the wall time (one BLAS thread: CPU time of one core)
            f"{m:10} {kinds.count('cct'):5d} {kinds.count('AboveSearchLimit'):6d} "
            f"{kinds.count('InsecureContingency'):5d} {runs[0] / len(faults):11.2f} "
            f"{sum(found) / max(len(found), 1):8.2f} {wall:11.2f} "
            f"{N1_SEARCHES * wall / 2 / 3600:12.2f} h {cpu:10.2f} "
            f"{N1_SEARCHES * cpu / 2 / 3600:10.2f} h",
            flush=True,
        )
    same = sum(a == b for a, b in zip(outcomes["bisection"], outcomes["sime"]))
    print(f"same verdict, 1 ms cell and half-step CCT in both: {same}/{len(faults)}")


def guessed_sample(case, n: int, t_max: float, seed: int = 53) -> None:
    """N line faults (`random.Random(seed)`) whose bus fault has a CCT, searched by sime
    without and with that CCT as the guess: simulations per CCT, CPU per search, and how
    many end alike (verdict, 1 ms cell and half-step CCT)."""
    import random

    rng = random.Random(seed)
    lines = [f for f in screening_faults(case, lines=True) if f.far_bus is not None]
    rng.shuffle(lines)
    sim = Simulator(case)
    sim.run(lines[0].events(0.05), t_end=lines[0].t_fault + 1.0)  # warm-up (compilation)
    print(
        f"\nACTIVSg2000 line faults searched from their bus fault's CCT: {n} (seed {seed}), "
        f"sime, t_max {t_max:g} s, tol 1 ms, half-step error bar"
    )
    stats: dict = {"none": [[], 0.0], "guess": [[], 0.0]}
    same = done = 0
    bus_cct: dict = {}
    for f in lines:
        if done == n:
            break
        if f.bus not in bus_cct:
            bus = _searched(sim, LineFault(f.bus, None), SearchOptions(method="sime", t_max=t_max))
            bus_cct[f.bus] = bus[0].cct_s if not isinstance(bus[0], str) else None
        if bus_cct[f.bus] is None:
            continue
        outs = []
        for name, guess in (("none", None), ("guess", bus_cct[f.bus])):
            res, cpu = _searched(sim, f, SearchOptions(method="sime", t_max=t_max, guess_s=guess))
            stats[name][1] += cpu
            if not isinstance(res, str):
                stats[name][0].append(res.n_simulations)
                res = (res.bracket, res.cct_half_step_s)
            outs.append(res)
        same += outs[0] == outs[1]
        done += 1
    for name, (runs, cpu) in stats.items():
        print(
            f"  {name:6} {sum(runs) / max(len(runs), 1):6.2f} sims/CCT ({len(runs)} CCTs) "
            f"{cpu / max(done, 1):6.2f} CPU-s/search"
        )
    print(f"  same verdict, 1 ms cell and half-step CCT: {same}/{done}")


def _searched(sim, fault, opts):
    """(the result or the verdict's name, CPU s) of one search."""
    c0 = time.process_time()
    try:
        res = critical_clearing_time(sim, fault, opts)
    except InputError as exc:
        res = type(exc).__name__
    return res, time.process_time() - c0


def paper_table():
    """The paper's two faults, both conventions, without and with the error bar."""
    print(
        f"\n{'case':9} {'conv':7} {'h ms':>6} {'err bar':>7} {'method':9} {'CCT s':>7} "
        f"{'sims':>5} {'wall s':>7}"
    )
    for name, fault in (("miniwecc", CASE2.fault), ("kundur", CASE1.fault)):
        for conv in ("pstess", "ieee"):
            sim = Simulator(load_case(name), conventions=conv)
            sim.run(fault.events(0.05), t_end=fault.t_fault + 1.0)
            for check in (False, True):
                for m, opts in METHODS.items():
                    o = SearchOptions(**{**opts.__dict__, "error_check": check})
                    res = min(
                        (critical_clearing_time(sim, fault, o) for _ in range(3)),
                        key=lambda r: r.wall_time_s,
                    )
                    print(
                        f"{name:9} {conv:7} {1000 * res.step_s:6.3g} "
                        f"{'yes' if check else 'no':>7} {m:9} {res.cct_s:7.3f} "
                        f"{res.n_simulations:5d} {res.wall_time_s:7.2f}",
                        flush=True,
                    )


def stage_builds(case, n: int, seed: int = 5) -> None:
    """Mean and median time (ms) of the network stages of n new bus and n new line faults
    (random, `random.Random(seed)`): a first short run of each fault less a second, with
    the stages updated from the pre-event reduction and factorised anew."""
    import random

    import numpy as np

    rng = random.Random(seed)
    buses = rng.sample(screening_faults(case), n)
    lines = rng.sample([f for f in screening_faults(case, lines=True) if f.far_bus], n)
    sim = Simulator(case)
    model = sim.model

    def run(f):
        t = time.perf_counter()
        sim.run(f.events(0.05), f.t_fault + 0.06, voltages=False)
        return time.perf_counter() - t

    run(buses[0])  # warm-up (compilation)
    print(f"\nACTIVSg2000 network stages of a new fault ({n} bus, {n} line faults, seed {seed})")
    for label in ("updated", "anew"):
        if label == "anew":
            model._pre_event_factor = lambda config: None  # type: ignore[method-assign]
        for kind, faults in (("bus", buses), ("line", lines)):
            model._stage_cache._entries.clear()
            ms = [1e3 * (run(f) - run(f)) for f in faults]
            print(
                f"  {label:8} {kind:4} faults: mean {np.mean(ms):6.1f} ms, "
                f"median {np.median(ms):6.1f} ms"
            )


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--every", type=int, default=4, help="miniWECC: every N-th fault")
    ap.add_argument("--activsg", action="store_true", help="also ACTIVSg2000 (minutes)")
    ap.add_argument("--paper", action="store_true", help="also the paper's two faults")
    ap.add_argument(
        "--activsg-sample",
        type=int,
        default=0,
        metavar="N",
        help="also a random sample of ACTIVSg2000's N-1: N bus and N line faults",
    )
    ap.add_argument(
        "--activsg-guess",
        type=int,
        default=0,
        metavar="N",
        help="also N ACTIVSg2000 line faults searched from their bus fault's CCT",
    )
    ap.add_argument("--t-max", type=float, default=0.5, help="t_max of the N-1 sample (s)")
    ap.add_argument(
        "--activsg-stages",
        type=int,
        default=0,
        metavar="N",
        help="also time ACTIVSg2000's stages of N new bus and N new line faults",
    )
    ap.add_argument(
        "--systems", nargs="*", default=["kundur", "miniwecc"], choices=["kundur", "miniwecc"]
    )
    args = ap.parse_args(argv)
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    print(
        "settings: tol 1 ms, t_max 1 s, t_end fault + 5 s, stop at separation, half-step "
        "error bar, ieee conventions, default step; early stops in sime-early only"
    )
    print(
        f"{'system':12} {'faults':>6} {'CCTs':>5} {'method':9} {'sims/CCT':>8} {'at step':>8} "
        f"{'early':>7} {'wall/CCT':>9} {'build s':>7} same"
    )
    if "kundur" in args.systems:
        kundur = load_case("kundur")
        compare("kundur", kundur, screening_faults(kundur, lines=True))
    if "miniwecc" in args.systems:
        mini = load_case("miniwecc")
        compare(f"miniwecc/{args.every}", mini, screening_faults(mini, lines=True)[:: args.every])
    if args.activsg or args.activsg_sample or args.activsg_stages or args.activsg_guess:
        case = activsg2000()
    if args.activsg_stages:
        stage_builds(case, args.activsg_stages)
    if args.activsg:
        faults = [LineFault(2021, 2002), LineFault(2021, None)]
        n1_projection(compare("activsg2000", case, faults))
    if args.activsg_sample:
        n1_sample(case, args.activsg_sample, args.t_max)
    if args.activsg_guess:
        guessed_sample(case, args.activsg_guess, args.t_max)
    if args.paper:
        paper_table()


if __name__ == "__main__":
    main()
