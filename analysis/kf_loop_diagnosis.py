"""Why the baseline KF used to lose 5 cycles of CCT in the loop (docs/estimation.md 2.1).

    PYTHONPATH=. python analysis/kf_loop_diagnosis.py

Kundur, 20-cycle fault at bus 3 (line 3-101), 20 % ESDs, PMU noise seed 0: the KF whose
forecast extrapolates its ROCOF state over the 50 ms latency (the previous baseline,
rebuilt here) against the baseline as it is (forecast held) and the ideal controller.
Prints the verdict, the number of ESD switchings and, for the first 0.2 s after the
clearing, the relative speed the controller acted on against the truth (mHz).
"""

import numpy as np

from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.events import fault_with_clearing
from stabctl.estimation import closed_loop as cl
from stabctl.estimation.filters import FrequencyKF
from stabctl.estimation.models import relative_speeds
from stabctl.io import load_case
from stabctl.studies.cases import CASE1


class ExtrapolatingKF(FrequencyKF):
    """The previous baseline: speed + horizon * ROCOF state."""

    def forecast(self, horizon):
        speed, var = self._output()
        return speed + horizon * self.x[:, 1] / self.f0, var


def run(sim, events, estimator, extrapolate=False):
    make = cl._make_filter
    if extrapolate:
        cl._make_filter = lambda e, m, s: ExtrapolatingKF(m.pmu, s, f0=m.f0)
    try:
        return cl.run_closed_loop(sim, events, 6.0, cl.LoopOptions(20, estimator, seed=0))
    finally:
        cl._make_filter = make


def main():
    case = load_case("kundur")
    sim = Simulator(case)
    events = [fault_with_clearing(case, CASE1.bus, CASE1.far_bus, CASE1.fault.t_fault, 20)]
    t_clear = max(events[0].times())
    for label, est, ext in (
        ("ideal", "ideal", False),
        ("kf, ROCOF extrapolated", "kf", True),
        ("kf, held (baseline)", "kf", False),
    ):
        r = run(sim, events, est, ext)
        d, res = r.diagnostics, r.result
        print(
            f"{label}: stable {res.stable}, {len(res.meta['switchings'])} switchings, "
            f"run end {res.t[-1]:.2f} s"
        )
        true = res.speed_at(np.minimum(d.t + d.latency, res.t[-1]))
        rel = relative_speeds(true, true, res.inertia, d.coi)[0] * d.f0
        for k in np.flatnonzero((d.t > t_clear) & (d.t < t_clear + 0.2)):
            print(
                f"  t {d.t[k]:.3f} s  acted on {np.round(d.rel[k] * 1e3).astype(int)}  "
                f"true {np.round(rel[k] * 1e3).astype(int)}  modes {d.modes[k]}"
            )


if __name__ == "__main__":
    main()
