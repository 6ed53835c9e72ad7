"""ESD sizing and placement study: writes reports/placement_<case>.md (+ JSON,
figures) per case with `stabctl.studies.placement.placement_study`.

Run: python analysis/placement_study.py [kundur] [miniwecc] [--out reports] [--workers 2]
Takes ~2 min (Kundur) and ~20 min (miniWECC, of which ~10 min screening, resumed from
reports/placement_miniwecc_screening.jsonl) on two cores.
"""

import argparse
import logging

from stabctl.studies.placement import placement_study


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cases", nargs="*", default=["kundur", "miniwecc"])
    ap.add_argument("--out", default="reports")
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(message)s")  # progress on stderr
    for name in args.cases:
        path = placement_study(
            name, args.out, args.workers, generated_by="python analysis/placement_study.py"
        )
        print(f"wrote {path}")


if __name__ == "__main__":
    main()
