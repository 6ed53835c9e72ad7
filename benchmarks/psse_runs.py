"""PSS/E's own runs repeated as a user runs them (tests/psse_reference.py): the table of
differences, printed or written as the docs page.

    python benchmarks/psse_runs.py                      # the table on stdout
    python benchmarks/psse_runs.py --markdown docs/psse_runs.md
    python benchmarks/psse_runs.py GENROU GENSAL        # some runs only
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import psse_reference as ref


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="*", help="run names (default: all)")
    ap.add_argument("--markdown", type=Path, help="write the docs page here")
    a = ap.parse_args(argv)
    unknown = [n for n in a.runs if n not in ref.BY_NAME]
    if unknown:
        ap.error(f"unknown run(s) {unknown}; known: {sorted(ref.BY_NAME)}")
    runs = [ref.BY_NAME[n] for n in a.runs] if a.runs else list(ref.RUNS)
    outcomes = []
    for run in runs:
        o = ref.compare(run)
        outcomes.append(o)
        print(f"{run.name}: {'ok' if o.ok() else 'SHORT: ' + o.shortfall()}", file=sys.stderr)
    page = ref.markdown(outcomes)
    if a.markdown:
        a.markdown.write_text(page)
    else:
        print(page)
    return 0


if __name__ == "__main__":
    sys.exit(main())
