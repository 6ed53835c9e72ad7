"""numba's reference counting inside a run: the atomic increments per integration step
(not a test).

Every array a kernel passes to another kernel in a per-element loop used to be counted
(``NRT_incref`` / ``NRT_decref``, an atomic operation each): on ACTIVSg2000 about 11 000
increments per model evaluation, half of a run's time under ``perf``.  The kernels now
borrow their arrays there (`stabctl._jit.borrow`, rule 8 of `stabctl._jit`).  This counts
what is left: a child process runs one fault with ``NUMBA_DEBUG_NRT=1`` (numba's runtime
then prints each increment; the compiled kernels are the cached ones), and the
increments between two marks are divided by the run's steps.  A regression shows as
hundreds or thousands per step again.

Run: python benchmarks/bench_refcounts.py [--activsg]   (ACTIVSg2000: about a minute)
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import textwrap

_CHILD = textwrap.dedent(
    """
    import os, sys
    import stabctl
    from stabctl.stability.cct import LineFault
    case = stabctl.load_case(sys.argv[1])
    sim = stabctl.Simulator(case)
    fleet = stabctl.uniform_fleet(case, 5) if sys.argv[4] == "esd" else None
    fault = LineFault(int(sys.argv[2]), int(sys.argv[3]), 1.0)
    def run():
        return sim.run(fault.events(0.1), 3.0, h=sim.default_h, storage=fleet)
    run()
    sys.stdout.flush(); os.write(1, b"=====MARK=====\\n")
    steps = len(run().t)
    sys.stdout.flush(); os.write(1, b"=====END=====\\n")
    print("steps", steps)
    """
)


def increments(case: str, bus: int, far_bus: int, storage: bool) -> tuple[int, int]:
    """(increments during one 3 s run, its grid points) for a fault cleared after 0.1 s."""
    env = {**os.environ, "NUMBA_DEBUG_NRT": "1"}
    with tempfile.TemporaryFile("w+") as out:
        args = [case, str(bus), str(far_bus), "esd" if storage else "none"]
        subprocess.run(
            [sys.executable, "-c", _CHILD, *args], stdout=out, env=env, check=True, text=True
        )
        out.seek(0)
        text = out.read()
    marked = text.split("=====MARK=====")[1].split("=====END=====")
    return marked[0].count("NRT_Incref"), int(marked[1].split("steps")[1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--activsg", action="store_true", help="also ACTIVSg2000 (its import)")
    args = ap.parse_args()
    runs = [
        ("kundur", 3, 101, False),
        ("miniwecc", 83, 33, False),
        ("miniwecc", 83, 33, True),
    ]
    if args.activsg:
        from bench_scale import _activsg2000

        from stabctl.io.pst import write_case_json

        work = tempfile.mkdtemp()
        path = os.path.join(work, "activsg2000.json")
        write_case_json(_activsg2000(work), path)
        runs.append((path, 2021, 2002, False))
    print(f"{'case':24} {'storage':>8} {'steps':>6} {'increments':>11} {'per step':>9}")
    for case, bus, far, esd in runs:
        n, steps = increments(case, bus, far, esd)
        name = os.path.basename(case)
        print(f"{name:24} {'5 %' if esd else '-':>8} {steps:6d} {n:11d} {n / steps:9.1f}")


if __name__ == "__main__":
    main()
