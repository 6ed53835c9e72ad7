"""Memory of `stabctl estimate track` on a long recording (not a test): the largest
resident set of the command on a recording of N frames of Kundur's four machine PMUs at
60 frames/s, beside its resident set on a recording of 100 frames (the interpreter, the
case and the estimators), and the difference per frame.  The recording is a flat stream
(every PMU at 1 pu and 60 Hz), written with `stabctl.estimation.c37.record`.

    python benchmarks/bench_track_memory.py [--frames 300000] [--estimator ekf]
"""

from __future__ import annotations

import argparse
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import stabctl
from stabctl.estimation import c37
from stabctl.estimation import pmu as pm

RATE = 60


def recording(path: Path, n_frames: int) -> int:
    """Write a flat recording of n_frames of Kundur's machine PMUs; its size, bytes."""
    case = stabctl.load_case("kundur")
    pmus = pm.machine_pmus(case)
    n = len(pmus)
    one, zero = np.ones(n, complex), np.zeros(n)
    frames = (
        pm.Frame(k / RATE, np.ones(n, bool), one, one, zero + case.freq_hz, zero)
        for k in range(n_frames)
    )
    c37.record(path, c37.stream_config(case, pmus, RATE), frames)
    return path.stat().st_size


def largest_rss_mib(args: list[str]) -> tuple[float, float]:
    """(largest resident set of `stabctl ARGS` in a child process, MiB; its wall, s)."""
    t0 = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "stabctl", *args], capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"stabctl {' '.join(args)}: exit {done.returncode}: {done.stderr}")
    # ru_maxrss of the children waited for so far (KiB on Linux): run smallest first
    return resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024, time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=300_000)
    ap.add_argument("--estimator", default="ekf", choices=("raw", "kf", "ekf"))
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        small, large = Path(tmp) / "small.c37", Path(tmp) / "large.c37"
        recording(small, 100)
        size = recording(large, args.frames)
        rows = []
        for path in (small, large):
            cmd = ["estimate", "track", "kundur", "--source", str(path)]
            cmd += ["--estimator", args.estimator, "--out", str(Path(tmp) / "t.csv")]
            rows.append(largest_rss_mib(cmd))
    (base, _), (rss, wall) = rows
    print(f"stabctl {stabctl.__version__}, estimator {args.estimator}, Kundur's 4 PMUs, {RATE} fps")
    print(f"recording: {args.frames} frames, {size / 2**20:.1f} MiB")
    print(
        f"largest resident set: {rss:.0f} MiB ({base:.0f} MiB with 100 frames); wall {wall:.1f} s"
    )
    print(f"per frame: {(rss - base) * 2**20 / args.frames:.0f} bytes")


if __name__ == "__main__":
    main()
