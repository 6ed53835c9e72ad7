"""Wall time of the whole Table 4 sweep (CCT at 0..30 % ESD ratings), per case (not a test).

Runs the sweep into a temporary directory with the default local workers (one per core).
Run: python benchmarks/bench_table4.py
"""

import tempfile
import time
from pathlib import Path

from stabctl.studies.paper_storage import CASES, RATINGS_PCT, table4


def main():
    with tempfile.TemporaryDirectory() as tmp:
        for key, (name, fault) in CASES.items():
            t = time.perf_counter()
            res = table4(key, Path(tmp), progress=False)
            wall = time.perf_counter() - t
            sims = sum(r["n_simulations"] for r in res.values())
            print(
                f"{name:9} {fault.describe():40} {len(RATINGS_PCT) + 1} CCT searches, "
                f"{sims} simulations, {wall:.1f} s wall"
            )


if __name__ == "__main__":
    main()
