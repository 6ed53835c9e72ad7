"""Wall time of the main job, `stabctl paper`, per section (not a test).

Runs `stabctl paper --out DIR [--only PART ...]` in a fresh process (interpreter start,
imports and numba compilation included, as a user sees it) into an empty directory (no
earlier sweep records reused), then prints the total wall time and the seconds of every
section from the run log the command writes (DIR/run_log.json: each section timed from
its start to its return, its sweep records with the number of jobs and their summed job
time).  `--cold` first deletes stabctl's cached compiled kernels (as after a fresh
install); without it the cache is used as it is.  One run: the main job takes minutes,
so it is not repeated; other users of the machine make the time an upper bound.

Run: python benchmarks/bench_paper.py [--only analytic cases table4 estimation placement]
     [--cold] [--keep DIR]
"""

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from stabctl.studies.paper import run_summary

PARTS = ("analytic", "cases", "table4", "estimation", "placement")


def _clear_cache() -> int:
    """Clear the compiled kernels of the stabctl that `run`'s subprocess imports (from the
    working directory when it holds a source tree, else the installed one), as after a
    fresh installation; the number of files deleted."""
    code = "from stabctl._jit.cache import clear_cache; print(clear_cache())"
    return int(
        subprocess.run(
            [sys.executable, "-c", code], check=True, text=True, stdout=subprocess.PIPE
        ).stdout
    )


def run(parts, out: Path) -> tuple[float, dict]:
    """Run `stabctl paper` into out; (wall s, run log)."""
    cmd = [sys.executable, "-m", "stabctl.cli", "paper", "--out", str(out)]
    for p in parts:
        cmd += ["--only", p]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        sys.exit(f"stabctl paper failed ({proc.returncode}):\n{proc.stdout[-3000:]}")
    return wall, json.loads((out / "run_log.json").read_text())


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", nargs="+", choices=PARTS, default=list(PARTS))
    ap.add_argument(
        "--cold",
        action="store_true",
        help="delete stabctl's compiled-kernel cache first (as a fresh install)",
    )
    ap.add_argument(
        "--keep",
        type=Path,
        default=None,
        metavar="DIR",
        help="write the reports to DIR (must be empty or absent) and keep them",
    )
    args = ap.parse_args()
    if args.keep is not None and args.keep.exists() and any(args.keep.iterdir()):
        sys.exit(f"--keep {args.keep}: not empty (the run must not reuse earlier records)")
    cleared = _clear_cache() if args.cold else None
    tmp = None if args.keep else tempfile.mkdtemp(prefix="bench-paper-")
    out = args.keep or Path(tmp)
    try:
        wall, log = run(args.only, out)
    finally:
        if tmp:
            shutil.rmtree(tmp, ignore_errors=True)
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    print(
        f"stabctl paper --only {' '.join(args.only)}: {wall:.1f} s wall on {cores} cores "
        f"(kernel cache {'cleared: ' + str(cleared) + ' files' if args.cold else 'as found'};"
        f" one run, fresh output directory)"
    )
    print(run_summary(log))
    inside = sum(s["seconds"] for s in log["sections"])
    print(f"{wall - inside:.1f} s start-up, imports and file moves outside the sections")
    for name, r in log["records"].items():
        print(
            f"records {name}: job time summed {r['job_wall_s']} s, longest {r['longest_job_s']} s"
        )
    gaps = [b[0] - a[0] for a, b in zip(log["progress"], log["progress"][1:])]
    if gaps:
        print(f"longest stretch between two progress lines: {max(gaps):.0f} s")


if __name__ == "__main__":
    main()
