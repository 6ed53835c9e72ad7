"""A screening on a Dask cluster of separately started processes (not a test): its wall
time on 1 worker and on 2, the speed-up, and a run with one of 2 workers killed mid-sweep.

The cluster is what `docs/cli.md` tells a user to start: ``dask scheduler`` and ``dask
worker tcp://host:8786 --nthreads 1 --no-nanny`` (here ``python -m
distributed.cli.dask_scheduler`` / ``dask_worker`` on loopback, free ports), one cluster
per run, its workers connected before the sweep starts; each wall time is
`stabctl.parallel.run_sweep`'s from an empty record file, the workers' loading of the case
and of the compiled kernels (cached on disk, compiled here first) included.

The kill run SIGKILLs the worker of the record written when a third of the jobs are in
(it has begun its next job) and counts, from a line each job's function appends at its
start and its end: jobs lost (not in the record file, or recorded failed), recorded jobs
run again (their record from the killed worker: none expected), and the jobs Dask ran again
elsewhere: the one the kill cut short, and any that had ended on that worker with its
result not yet fetched (lost with it: a window of milliseconds).
Its verdicts and CCTs are compared with the other runs'.  Each run also prints its job
walls summed (the workers' busy time: on a machine shared with other jobs, the sign of
contention is a longer wall per job with 2 workers than with 1) and the load average.

Run: python benchmarks/bench_dask.py [--case miniwecc] [--every 4] [--tol-ms 1]
                                     [--t-max 0.5] [--error-check] [--search bisection]
                                     [--pool]
(--case: a case name or a case file, e.g. ACTIVSg2000 imported by `stabctl import-psse`;
--pool: also a local process pool of 1 and 2 processes, for comparison)
(not pinned: the 2-worker run needs two cores)
"""

import argparse
import collections
import json
import os
import signal
import sys
import tempfile
import time
from pathlib import Path

from stabctl.io import load_case
from stabctl.parallel import Job, read_records, run_sweep
from stabctl.stability.cct import SearchOptions, cct_job, cct_jobs
from stabctl.stability.screening import screening_faults

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))
from dask_cluster import separate_cluster  # noqa: E402 - tests/dask_cluster.py


def counted(inputs):
    """`cct_job`, its start and end (result or raised verdict) appended to $BENCH_DASK_RUNS
    (a line each: start|end, the worker's pid, the inputs as JSON)."""
    tag = json.dumps(inputs, sort_keys=True)
    with open(os.environ["BENCH_DASK_RUNS"], "a") as f:
        f.write(f"start {os.getpid()} {tag}\n")
    try:
        return cct_job(inputs)
    finally:  # a verdict (robust, N-1 insecure) is raised: its job has ended too
        with open(os.environ["BENCH_DASK_RUNS"], "a") as f:
            f.write(f"end {os.getpid()} {tag}\n")


def sweep(jobs, workers: int, tmp: Path, name: str, kill_at: int | None = None) -> dict:
    """One run on a new cluster; returns its wall time, records, execution marks and the
    1-minute load average before and after (other users' jobs on the cores)."""
    out, runs = tmp / f"{name}.jsonl", tmp / f"{name}.runs"
    killed: list[int] = []
    with separate_cluster(workers, {"BENCH_DASK_RUNS": str(runs)}, (HERE,)) as (address, _, _):

        def progress(done, total):
            if done == kill_at:
                last = out.read_text().splitlines()[-1]
                pid = int(json.loads(last)["worker"].rsplit(":", 1)[1])
                os.kill(pid, signal.SIGKILL)
                killed.append(pid)

        load = os.getloadavg()[0]
        t = time.perf_counter()
        report = run_sweep(jobs, out, scheduler=address, progress=progress if kill_at else False)
        wall = time.perf_counter() - t
        load = (load, os.getloadavg()[0])
    marks = [line.split(" ", 2) for line in runs.read_text().splitlines()]
    return {
        "wall": wall,
        "report": report,
        "lines": [json.loads(s) for s in out.read_text().splitlines()],
        "records": read_records(out),
        "marks": marks,
        "killed": killed,
        "load": load,
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", default="miniwecc")
    ap.add_argument("--every", type=int, default=4, help="every N-th line fault")
    ap.add_argument("--tol-ms", type=float, default=1.0)
    ap.add_argument("--t-max", type=float, default=0.5)
    ap.add_argument("--error-check", action="store_true", help="half-step check on")
    ap.add_argument("--search", choices=("bisection", "sime"), default="bisection")
    ap.add_argument(
        "--pool",
        action="store_true",
        help="also time a local process pool (no Dask) of 1 and 2 processes (1: in this process)",
    )
    args = ap.parse_args(argv)
    sys.path.insert(0, str(HERE))
    from bench_dask import counted as job_function  # by this name on the workers

    faults = screening_faults(load_case(args.case), buses=[], lines=True)[:: args.every]
    search = SearchOptions(
        tol=args.tol_ms / 1000,
        t_max=args.t_max,
        error_check=args.error_check,
        method=args.search,
    )
    plain = cct_jobs(args.case, faults, search=search)
    jobs = [Job(j.key, job_function, j.inputs) for j in plain]
    print(
        f"settings: case {args.case}, every {args.every}th line fault ({len(jobs)} jobs), "
        f"tol {args.tol_ms:g} ms, t_max {args.t_max:g} s, error_check {args.error_check}, "
        f"search {args.search}, "
        f"workers 1 and 2 (dask worker --nthreads 1 --no-nanny, separate processes), "
        f"{os.cpu_count()} cores"
    )
    with tempfile.TemporaryDirectory() as tmp:
        runs = {
            "1 worker": sweep(jobs, 1, Path(tmp), "one"),
            "2 workers": sweep(jobs, 2, Path(tmp), "two"),
            "2 workers, one killed": sweep(
                jobs, 2, Path(tmp), "kill", kill_at=max(1, len(jobs) // 3)
            ),
        }
    if args.pool:
        with tempfile.TemporaryDirectory() as tmp:
            for n in (1, 2):
                out = Path(tmp) / f"pool{n}.jsonl"
                load = os.getloadavg()[0]
                t = time.perf_counter()
                report = run_sweep(plain, out, workers=n, progress=False)
                runs[f"process pool of {n}"] = {
                    "wall": time.perf_counter() - t,
                    "records": report.records,
                    "load": (load, os.getloadavg()[0]),
                }
    for name, run in runs.items():
        status = collections.Counter(r["status"] for r in run["records"].values())
        busy = sum(r["wall_time_s"] for r in run["records"].values())
        print(
            f"{name}: {run['wall']:.1f} s, {dict(status)}; job walls {busy:.1f} s in all "
            f"({busy / len(jobs):.2f} s a job), {busy / run['wall']:.2f} workers busy on "
            f"average; load average {run['load'][0]:.1f} before, {run['load'][1]:.1f} after"
        )
    t1, t2 = runs["1 worker"]["wall"], runs["2 workers"]["wall"]
    print(f"speed-up 1 -> 2 workers: {t1 / t2:.2f} (ideal 2)")
    kill = runs["2 workers, one killed"]
    keys = [j.key for j in jobs]
    lines = [r["key"] for r in kill["lines"]]
    lost = len(set(keys) - set(lines)) + sum(
        r["status"] == "failed" for r in kill["records"].values()
    )
    repeats = collections.Counter(_repeats(kill, jobs).values())
    answers = [
        [(run["records"][k]["status"], (run["records"][k].get("result") or {}).get("cct_s"))
         for k in keys]
        for run in runs.values()
    ]  # fmt: skip
    same = all(a == answers[0] for a in answers)
    print(
        f"kill run (worker pid {kill['killed'][0] if kill['killed'] else '-'} SIGKILLed at "
        f"record {max(1, len(jobs) // 3)}): jobs lost {lost}, recorded twice "
        f"{len(lines) - len(set(lines))}, recorded jobs run again {repeats['recorded']}; "
        f"run again elsewhere: cut by the kill {repeats['cut']}, finished but their result "
        f"lost with the worker before it was fetched {repeats['unfetched']}; verdicts and "
        f"CCTs the same in every run: {'yes' if same else 'NO'}"
    )


def _repeats(run: dict, jobs) -> dict:
    """The jobs of a kill run that ran more than once: key -> "recorded" (its record came
    from the killed worker, yet it ran again: a repeat), "unfetched" (it ended on the
    killed worker, its result never fetched: run again elsewhere) or "cut" (the kill cut
    it short)."""
    key = {json.dumps(j.inputs, sort_keys=True): j.key for j in jobs}
    starts = collections.Counter(key[tag] for what, _, tag in run["marks"] if what == "start")
    killed = {str(pid) for pid in run["killed"]}
    ended_there = {key[tag] for what, pid, tag in run["marks"] if what == "end" and pid in killed}
    out = {}
    for k, n in starts.items():
        if n > 1:
            by = run["records"][k]["worker"].rsplit(":", 1)[1]
            out[k] = "recorded" if by in killed else "unfetched" if k in ended_there else "cut"
    return out


if __name__ == "__main__":
    main()
