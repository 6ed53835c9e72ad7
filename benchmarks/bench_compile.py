"""First-call compile time of each simulating command: the command run cold (an empty
numba cache, as after a fresh installation) and then warm (the kernels loaded from that
cache); compilation = cold - warm.  Each run is a fresh `stabctl` process; wall time of the
whole process, imports included.  Target: compilation at most 20 s on this 2-core machine.

    python benchmarks/bench_compile.py [--only NAME ...]

Prints one row per command with its cold, warm and compile seconds, the CPU seconds of the
cold run (this process and its children: the integrator compiles in a child process), and
the longest stretch without a line on stderr or stdout during the cold run (the notice
and heartbeat while compiling).
"""

from __future__ import annotations

import argparse
import itertools
import os
import resource
import subprocess
import sys
import tempfile
import threading
import time

COMMANDS = {
    "simulate": ["simulate", "kundur", "--fault", "3", "--far-bus", "101", "--clear-cycles", "6"],
    "simulate-esd": [
        "simulate",
        "kundur",
        "--fault",
        "3",
        "--far-bus",
        "101",
        "--clear-cycles",
        "21",
        "--esd-pct",
        "5",
    ],
    "cct": ["cct", "kundur", "--fault", "3", "--far-bus", "101", "--tol-ms", "10"],
    "eig": ["eig", "kundur"],
    "estimate-rmse": [
        "estimate",
        "rmse",
        "kundur",
        "--fault",
        "3",
        "--far-bus",
        "101",
        "--runs",
        "1",
        "--ambient-s",
        "5",
        "--ambient-runs",
        "1",
    ],
    "estimate-closed-loop": [
        "estimate",
        "closed-loop",
        "kundur",
        "--fault",
        "3",
        "--far-bus",
        "101",
        "--esd-pct",
        "5",
    ],
}


def run(argv: list[str], cache: str) -> tuple[float, float, float, int]:
    """(wall s, CPU s of it and its children, longest silence s, exit code) of one
    `stabctl` process with NUMBA_CACHE_DIR=cache."""
    env = dict(os.environ, NUMBA_CACHE_DIR=cache)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.Popen(
        [sys.executable, "-m", "stabctl.cli", *argv],
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
    )
    stamps = [t0]

    def read():
        for _ in proc.stdout:
            stamps.append(time.perf_counter())

    reader = threading.Thread(target=read)
    reader.start()
    code = proc.wait()
    reader.join()
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    stamps.append(t0 + wall)
    silence = max(b - a for a, b in itertools.pairwise(stamps))
    return wall, cpu, silence, code


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", nargs="+", choices=sorted(COMMANDS), help="commands to time")
    args = ap.parse_args()
    print(
        f"python {sys.version.split()[0]}, {os.cpu_count()} cores; each row: a fresh "
        "process on an empty numba cache (cold), then again on that cache (warm)"
    )
    print(
        f"{'command':22s} {'cold s':>7s} {'warm s':>7s} {'compile s':>9s} "
        f"{'cold CPU s':>10s} {'longest silence s':>17s}  exit"
    )
    for name in args.only or list(COMMANDS):
        with tempfile.TemporaryDirectory() as cache:
            cold, cpu, silence, code = run(COMMANDS[name], cache)
            warm, _, _, code_w = run(COMMANDS[name], cache)
        print(
            f"{name:22s} {cold:7.1f} {warm:7.1f} {cold - warm:9.1f} {cpu:10.1f} "
            f"{silence:17.1f}  {code}/{code_w}",
            flush=True,
        )


if __name__ == "__main__":
    main()
