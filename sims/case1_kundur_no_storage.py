"""Paper Case 1 without storage (`stabctl.studies.no_storage`): the verdict at the paper's
clearing and the overview figure reports/case1_no_storage.png.

    python sims/case1_kundur_no_storage.py [--out reports] [--tf 5]
"""

import argparse
from pathlib import Path

from stabctl.studies.cases import CASE1
from stabctl.studies.no_storage import no_storage_report

if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("reports"), help="report directory")
    ap.add_argument("--tf", type=float, default=5.0, help="end time (s)")
    args = ap.parse_args()
    print("\n".join(no_storage_report(CASE1, args.out, args.tf)))
