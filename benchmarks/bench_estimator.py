"""Time per PMU frame of the speed estimators for miniWECC's 34 machines (not a test).

One 10 s run of the paper's Case 2 fault (bus 83, line 83-33, 4 cycles so that it is
stable), PMU frames at 60 frames/s with C37.118.1 noise and 5 % dropped frames; each
estimator is fed every frame once after a warm-up pass (compilation excluded), pinned to
one core.  Per frame: `SwingEKF.step` (model-based, compiled) and the relative speeds with
variances each ESD controller needs (`relative_speeds`), `FrequencyKF.step` (baseline), and
the filterpy reference of the EKF for comparison.
Target: at least 100 times faster than real time at 60 frames/s, i.e. < 167 us
per frame for all 34 machines.
Run: python benchmarks/bench_estimator.py
"""

import os
import time

from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.events import fault_with_clearing
from stabctl.estimation import pmu
from stabctl.estimation.filters import FrequencyKF, SwingEKF
from stabctl.estimation.models import machine_models, relative_speeds
from stabctl.estimation.reference import SwingEKFReference
from stabctl.io import load_case
from stabctl.studies.cases import CASE2

RATE = 60.0
TARGET_US = 1e6 / RATE / 100


def per_frame_us(make, frames, consume=lambda out: None) -> float:
    """Mean wall time (us) of step + consume over all frames, after a warm-up pass."""
    for warm in (True, False):
        est = make()
        t = time.perf_counter()
        for fr in frames:
            consume(est.step(fr))
        if not warm:
            return (time.perf_counter() - t) / len(frames) * 1e6


def main():
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    case = load_case("miniwecc")
    fault = fault_with_clearing(
        case, CASE2.bus, CASE2.far_bus, CASE2.fault.t_fault, CASE2.cycles["estimation"]
    )
    res = Simulator(case).run([fault], t_end=10.0)
    pmus = pmu.machine_pmus(case)
    settings = pmu.PMUSettings(rate=RATE, drop_prob=0.05)
    frames = list(pmu.measure(pmu.phasor_truth(case, res, pmus), settings, seed=1))
    models = machine_models(case, pmus)
    relative = lambda out: relative_speeds(*out, models.inertia)  # noqa: E731
    rows = [
        ("SwingEKF + relative speeds", lambda: SwingEKF(models, settings), relative),
        ("FrequencyKF + relative speeds", lambda: FrequencyKF(models.pmu, settings), relative),
        (
            "SwingEKFReference (filterpy)",
            lambda: SwingEKFReference(models, settings),
            lambda out: None,
        ),
    ]
    print(
        f"miniWECC, {models.n} machines, {len(frames)} frames at {RATE:g} frames/s; "
        f"target < {TARGET_US:.0f} us per frame (100x real time)"
    )
    print(f"{'estimator':32} {'us/frame':>9} {'x real time':>12}")
    for label, make, consume in rows:
        us = per_frame_us(make, frames, consume)
        ok = "ok" if us < TARGET_US else "MISSED"
        print(f"{label:32} {us:9.1f} {1e6 / RATE / us:12.0f}  {ok}")


if __name__ == "__main__":
    main()
