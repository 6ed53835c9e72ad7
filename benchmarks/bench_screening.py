"""Contingency screening of a whole case: the CCT (1 ms) of a three-phase fault at every
bus and, with --lines, at the from-end of every branch with the branch tripped, in
parallel (not a test).

Targets: miniWECC, all 122 bus faults in under 5 minutes of wall time on a 2-core
machine; ACTIVSg2000 (a case file named activsg2000.json, imported as docs/cli.md says),
its whole N-1 (``--lines``: 2 000 bus and 3 206 branch faults) in 30 minutes on 2 cores,
judged on the CPU time of the command and its workers divided by the workers (the wall
time moves with other work on the machine).  Each run starts from an empty records file
(nothing resumed); the times include starting the workers and loading their kernels.
Printed: the settings, the verdicts, the simulations a CCT (bus and branch faults apart,
the branch faults searched from their bus fault's CCT apart again), the bus faults'
probes after their first bracket beside a plain bisection's of it, the simulations a
search with the verdicts' runs counted too (a robust fault's one run) and, with --compare,
how many faults have the same verdict, 1 ms cell and half-step CCT as an earlier records
file (matched by key).

Run: python benchmarks/bench_screening.py [--case miniwecc] [--lines] [--search sime]
         [--t-max 0.5] [--no-guess] [--workers 2] [--scheduler local|processes|tcp://...]
         [--out FILE] [--compare RECORDS]
"""

import argparse
import os
import resource
import statistics
import tempfile
import time
from collections import Counter
from pathlib import Path

# one BLAS thread a process, as the `stabctl` command sets (before numpy is imported)
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

from stabctl.parallel import RunnerOptions, read_records  # noqa: E402
from stabctl.stability.cct import T_AFTER_FAULT, SearchOptions  # noqa: E402
from stabctl.stability.screening import screen  # noqa: E402

#: (case name or file stem, branch faults too): the target and what it is judged on
TARGETS = {
    ("miniwecc", False): (300.0, "wall"),
    ("activsg2000", True): (1800.0, "CPU time / workers"),
}


def _cpu_s() -> float:
    """User + system time of this process and its reaped children (the workers), s."""
    own, kids = (
        resource.getrusage(resource.RUSAGE_SELF),
        resource.getrusage(resource.RUSAGE_CHILDREN),
    )
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def _outcome(rec: dict) -> tuple:
    """What a fault's search concluded: its verdict, 1 ms cell and half-step CCT."""
    if rec.get("status") != "ok":
        return (rec.get("status"), rec.get("verdict"))
    r = rec["result"]
    return ("ok", r["t_stable_s"], r["t_unstable_s"], r.get("cct_half_step_s"))


def _runs(recs: list) -> str:
    """Simulations a CCT (mean) and how many CCTs."""
    n = [r["result"]["n_simulations"] for r in recs]
    return f"{statistics.mean(n):.2f} ({len(n)} CCTs)" if n else "-"


def _full_runs(recs: list) -> str:
    """A CCT's cost in whole runs at its step (mean): its searches' time steps (a run cut
    short by a verdict counts its steps only, one at half the step twice its steps)
    over the steps of one run from 0 to the search's run end."""
    n = []
    for r in recs:
        res, inputs = r["result"], r["inputs"]
        t_end = inputs.get("t_end") or inputs.get("t_fault", 1.0) + T_AFTER_FAULT
        n.append(res["n_steps"] / round(t_end / res["step_s"]))
    return f"{statistics.mean(n):.2f}" if n else "-"


def _runs_a_search(recs: list) -> str:
    """Simulations a search (mean), verdicts (robust, N-1 insecure) counted with the runs
    that reached them, over the searches whose records count them."""
    n = [
        r["result"]["n_simulations"] if r["status"] == "ok" else r.get("n_simulations")
        for r in recs
        if r["status"] != "failed"
    ]
    n = [k for k in n if k is not None]
    return f"{statistics.mean(n):.2f} ({len(n)} searches)" if n else "-"


def _refining(recs: list) -> str:
    """Probes at the step a CCT's search ran after its first (stable, unstable) bracket
    (mean), beside the probes a plain bisection of that bracket to the same 1 ms cell
    would run (counted from the CCT found, verdicts taken to be monotone in the clearing
    time): what SIME's margins save or cost once the doubling has bracketed the CCT."""
    ran, bisected = [], []
    for rec in recs:
        r = rec["result"]
        tol, probes = r["tol_s"], [round(t / r["tol_s"]) for t, _ in r["probes"]]
        lo, hi = (round(t / tol) for t in r["search_bracket_s"])
        cct = round(r["t_stable_s"] / tol)
        if lo not in probes or hi not in probes:  # a bracket closed from a guess
            continue
        ran.append(len(probes) - 1 - max(probes.index(lo), probes.index(hi)))
        n = 0
        while hi - lo > 1:
            mid, n = (lo + hi) // 2, n + 1
            lo, hi = (mid, hi) if mid <= cct else (lo, mid)
        bisected.append(n)
    if not ran:
        return "-"
    return (
        f"{statistics.mean(ran):.2f} after the bracket against {statistics.mean(bisected):.2f} "
        f"by bisection ({len(ran)} CCTs)"
    )


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", default="miniwecc", help="built-in case name or case file")
    ap.add_argument("--lines", action="store_true", help="also every branch fault")
    ap.add_argument("--search", default="sime", choices=("sime", "bisection"))
    ap.add_argument("--t-max", type=float, default=0.5, help="search limit (s)")
    ap.add_argument("--no-guess", action="store_true", help="branch faults without guesses")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument(
        "--scheduler",
        default="processes",
        help="'processes' (a process pool, no Dask; the CLI's default), 'local' (Dask "
        "LocalCluster) or a Dask scheduler address",
    )
    ap.add_argument("--out", help="records file to write (default a temporary one)")
    ap.add_argument("--compare", help="an earlier records file of the same faults")
    args = ap.parse_args(argv)
    scheduler = None if args.scheduler == "processes" else args.scheduler
    search = SearchOptions(t_max=args.t_max, method=args.search)
    name = Path(args.case).stem
    print(
        f"{name}: bus faults{' and branch faults' if args.lines else ''}; search "
        f"{search.method}, tol {1000 * search.tol:g} ms, t_max {search.t_max:g} s, half-step "
        f"error bar {'on' if search.error_check else 'off'}, the case's default step; branch "
        f"faults from their bus fault's CCT: {'no' if args.no_guess or not args.lines else 'yes'}; "
        f"{args.workers} workers ({args.scheduler}); OPENBLAS_NUM_THREADS="
        f"{os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}"
    )
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(args.out) if args.out else Path(tmp) / "screen.jsonl"
        if out.exists():
            raise SystemExit(f"error: {out} exists: a benchmark starts from no records")
        cpu, wall = _cpu_s(), time.perf_counter()
        rows = screen(
            args.case,
            out,
            lines=args.lines,
            guess=not args.no_guess,
            search=search,
            runner=RunnerOptions(args.workers, scheduler),
        )
        wall, cpu = time.perf_counter() - wall, _cpu_s() - cpu
        recs = read_records(out, whole="the screening's records")
    verdicts = Counter(r["verdict"] for r in rows)
    ok = [recs[r["key"]] for r in rows if r["status"] == "ok"]
    bus = [r for r in ok if r["inputs"]["far_bus"] is None]
    guessed = [r for r in ok if r["inputs"].get("guess_s") is not None]
    other = [r for r in ok if r["inputs"]["far_bus"] is not None and r not in guessed]
    print(f"{len(rows)} faults: {dict(verdicts)}")
    print(
        f"simulations a CCT: {_runs(ok)} in all; bus faults {_runs(bus)}; branch faults "
        f"from their bus fault's CCT {_runs(guessed)}, the others {_runs(other)}"
    )
    print(
        f"whole runs' worth of steps a CCT: {_full_runs(ok)} in all (bus faults "
        f"{_full_runs(bus)}): runs ended by their verdict count their steps, the half-step "
        "reruns twice theirs"
    )
    print(f"bus faults' probes at the step {_refining(bus)}")
    every = [recs[r["key"]] for r in rows]
    print(
        f"simulations a search, verdicts included: {_runs_a_search(every)}; bus faults "
        f"{_runs_a_search([r for r in every if r['inputs']['far_bus'] is None])}"
    )
    on_cores = cpu / args.workers
    print(
        f"wall {wall / 60:.1f} min; CPU {cpu:.0f} s (this process and its workers), "
        f"{on_cores / 60:.1f} min on {args.workers} cores"
    )
    target = TARGETS.get((name, args.lines))
    if target:
        limit, judged = target
        value = wall if judged == "wall" else on_cores
        print(
            f"target {limit / 60:.0f} min ({judged}): {value / 60:.1f} min, "
            f"{'met' if value <= limit else 'NOT met'}"
        )
    if args.compare:
        before = read_records(args.compare, whole="--compare")
        keys = [r["key"] for r in rows if r["key"] in before]
        same = sum(_outcome(before[k]) == _outcome(recs[k]) for k in keys)
        print(
            f"same verdict, cell and half-step CCT as {args.compare}: {same} of {len(keys)} "
            f"faults it has ({len(rows) - len(keys)} not in it)"
        )
    worst = sorted((r for r in rows if r["status"] == "ok"), key=lambda r: r["cct_s"])[:5]
    print("most critical: " + ", ".join(f"{_label(r)} {1000 * r['cct_s']:.0f} ms" for r in worst))


def _label(row: dict) -> str:
    """A fault's short name: bus b, or line b-f (#circuit beyond the first)."""
    if row["far_bus"] is None:
        return f"bus {row['bus']}"
    circuit = f" #{row['circuit']}" if row["circuit"] != 1 else ""
    return f"line {row['bus']}-{row['far_bus']}{circuit}"


if __name__ == "__main__":
    main()
