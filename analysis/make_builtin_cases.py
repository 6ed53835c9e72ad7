"""Regenerate the built-in cases stabctl/case/data/*.json from the PSTess data in shared/.

Run from the repository root (development only; the package never reads shared/):

    /work/venv/bin/python analysis/make_builtin_cases.py [path/to/shared/data/pstess]

Writes stabctl/case/data/kundur.json (from d2asbegp.m, checked against Octave's d2asbegp.json)
and stabctl/case/data/miniwecc.json (from d_minniWECC_base.json: the .m file computes its
matrices, so the Octave-evaluated JSON is the source), and copies PSTess's LICENSE and NOTICE.
"""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

from stabctl.io import pst as pstio

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "stabctl" / "case" / "data"
LICENCE = (
    "MIT. Data from PSTess 1.1 (Sandia National Laboratories, sandialabs/snl-pstess; "
    "(c) 2021 NTESS), which derives from the Power System Toolbox (PST, (c) Joe Chow / Cherry "
    "Tree Scientific Software, MIT-style licence). See LICENSE and NOTICE next to this file."
)

CASES = {
    "kundur": (
        "d2asbegp.m",
        "Kundur two-area 4-machine system (PSTess d2asbegp): subtransient machines, static "
        "exciters, speed PSS, governors, 50% constant-current P load; 13 buses, 60 Hz; "
        "PSTess's bus numbers: Kundur's book (Example 12.6) buses 1-11 are 1, 2, 11, 12, 10, "
        "20, 3, 101, 13, 120, 110, and 4, 14 are PSTess's 115 kV load buses",
    ),
    "miniwecc": (
        "d_minniWECC_base.json",
        "miniWECC 34-machine reduced WECC (PSTess d_minniWECC_base): ST3 exciters, speed PSS, "
        "21 governors, PDCI/Intermountain HVDC as fixed loads; 122 buses, 60 Hz",
    ),
}


def convert(src_dir: Path, name: str, filename: str, description: str) -> Path:
    """Import one PSTess file and write it in stabctl's own format; returns the output path."""
    src = src_dir / filename
    case = pstio.read_any(src)
    if src.suffix == ".m":  # the literal .m must equal Octave's evaluation of it
        evaluated = pstio.read_pstess_json(src.with_suffix(".json"))
        assert case.replace(name=evaluated.name).equals(evaluated), f"{src}: .m != .json"
    case = case.replace(
        name=name,
        description=description,
        source=f"PSTess 1.1 data file {filename} (sandialabs/snl-pstess), "
        "converted by analysis/make_builtin_cases.py",
    )
    return pstio.write_case_json(case, OUT / f"{name}.json", licence=LICENCE)


def main(argv: list[str]) -> None:
    src_dir = Path(argv[1]) if len(argv) > 1 else ROOT.parent / "shared" / "data" / "pstess"
    OUT.mkdir(exist_ok=True)
    for name, (filename, description) in CASES.items():
        print("wrote", convert(src_dir, name, filename, description))
    for f in ("LICENSE", "NOTICE"):
        shutil.copyfile(src_dir / f, OUT / f)


if __name__ == "__main__":
    main(sys.argv)
