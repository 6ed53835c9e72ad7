"""Step convergence of the ambient false-actions figures (reports/estimation_<case>.md):
the mean over runs of the largest |f_i - f_COI| (mHz) of every estimate, and the false
actions per run, at several integration steps
(`stabctl.studies.estimation_report.ambient_figures`, the report's runs).

Run: python analysis/ambient_step.py kundur 0.005 0.0041666666666666667 0.0020833333333333333
0.0010416666666666667
     python analysis/ambient_step.py miniwecc 0.005 0.0025 [--runs N] [--seconds S]
"""

import argparse

from stabctl.io import load_case
from stabctl.studies.estimation_report import AMBIENT_RUNS, AMBIENT_S, ambient_figures


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("case")
    ap.add_argument("steps", nargs="+", type=float, help="integration steps (s)")
    ap.add_argument("--runs", type=int, default=AMBIENT_RUNS)
    ap.add_argument("--seconds", type=float, default=AMBIENT_S)
    a = ap.parse_args(argv)
    case = load_case(a.case)
    print(
        f"{a.case}, {a.runs} runs of {a.seconds:g} s: mean (max) over runs of the largest "
        "|f_i - f_COI| (mHz); false actions per run"
    )
    print("| step (ms) | true | raw | kf | ekf | actions raw / kf / ekf |")
    print("|---|---|---|---|---|---|")
    for h in a.steps:
        fig = ambient_figures(case, h=h, runs=a.runs, t_end=a.seconds)
        cell = lambda e: f"{fig[e]['max_rel_mhz']['mean']:.2f} ({fig[e]['max_rel_mhz']['max']:.2f})"
        acts = " / ".join(f"{fig[e]['actions']['mean']:.2f}" for e in ("raw", "kf", "ekf"))
        print(
            f"| {h * 1e3:.3f} | {cell('true')} | {cell('raw')} | {cell('kf')} | "
            f"{cell('ekf')} | {acts} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
