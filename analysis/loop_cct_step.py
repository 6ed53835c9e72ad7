"""Step sensitivity of a CCT with the estimator in the loop: `closed_loop.cct_study` of one
rating and estimator at several integration steps, over the same noise seeds (records in
--records, reused on a rerun).

Run: python analysis/loop_cct_step.py miniwecc 83 33 20 raw 0.005 0.0025 --runs 20
"""

import argparse

from stabctl.dynamics.options import ModelOptions
from stabctl.estimation import closed_loop as cl
from stabctl.parallel import RunnerOptions
from stabctl.stability.cct import LineFault


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("case")
    ap.add_argument("bus", type=int)
    ap.add_argument("far_bus", type=int)
    ap.add_argument("esd_pct", type=float)
    ap.add_argument("estimator", choices=cl.ESTIMATORS)
    ap.add_argument("steps", nargs="+", type=float, help="integration steps (s)")
    ap.add_argument("--runs", type=int, default=20)
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--records", default="loop_cct_step.jsonl")
    a = ap.parse_args(argv)
    print(
        f"{a.case}, fault {a.bus}-{a.far_bus}, {a.esd_pct:g} % ESDs, {a.estimator}, "
        f"{a.runs} seeds: CCT (cycles)"
    )
    print("| step (ms) | mean | std | min | max | values |")
    print("|---|---|---|---|---|---|")
    for h in a.steps:
        r = cl.cct_study(
            a.case,
            LineFault(a.bus, a.far_bus),
            [a.esd_pct],
            a.runs,
            a.records,
            estimators=(a.estimator,),
            model=ModelOptions(h=h),
            runner=RunnerOptions(a.workers, progress=False),
        )[a.esd_pct][a.estimator]
        print(
            f"| {h * 1e3:.4g} | {r['mean']:.3f} | {r['std']:.3f} | {r['min']:.2f} | "
            f"{r['max']:.2f} | {' '.join(f'{v:g}' for v in r['values'])} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
