"""Estimation study: estimator RMSE, false ESD actions under ambient load fluctuation and CCT
with the estimator in the loop for Kundur Case 1 and miniWECC Case 2 ->
reports/estimation_{kundur,miniwecc}.md (+ estimation_cct_<case>.jsonl, whose finished CCT
jobs are reused: delete it after a change of the loop).

Usage: python sims/estimation_study.py [RUNS] [CCT_RUNS] [--workers N]
       [--case kundur|miniwecc ...]
RUNS: RMSE Monte-Carlo runs (20); CCT_RUNS: noise seeds per CCT row (default: the paper's
confidence-interval rule, `stabctl.estimation.closed_loop.SeedRule`).
"""

import argparse

from stabctl.estimation.closed_loop import SeedRule
from stabctl.studies.estimation_report import CASES, write_estimation_report

if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="?", type=int, default=20)
    ap.add_argument("cct_runs", nargs="?", type=int, default=None)
    ap.add_argument("--workers", type=int, default=None, help="CCT sweep processes")
    ap.add_argument("--case", action="append", choices=list(CASES), help="default: both")
    a = ap.parse_args()
    cct_runs = SeedRule() if a.cct_runs is None else a.cct_runs
    for p in write_estimation_report(
        "reports",
        a.runs,
        cct_runs,
        a.workers,
        tuple(a.case or CASES),
        generated_by="python sims/estimation_study.py",
    ):
        print(f"wrote {p}")
