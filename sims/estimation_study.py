"""Issue 7 study: estimator RMSE, false ESD actions and CCT with the estimator in the loop
for Kundur Case 1 and miniWECC Case 2 -> reports/estimation_{kundur,miniwecc}.md.

Usage: python sims/estimation_study.py [RUNS] [MINIWECC_CCT_RUNS]
"""

import sys

from stabctl.estimation_report import write_estimation_report

if __name__ == "__main__":
    runs = int(sys.argv[1]) if len(sys.argv) > 1 else 20
    mini = int(sys.argv[2]) if len(sys.argv) > 2 else runs
    for p in write_estimation_report("reports", runs, {"miniwecc": mini}):
        print(f"wrote {p}")
