"""Eigenvalue studies: the `stabctl eig` reports for Kundur (with and without PSS) and
miniWECC, and the validation of the linearisation behind them
(`stabctl.studies.eig_validation`): reports/eig_kundur.md, eig_kundur_nopss.md,
eig_miniwecc.md (with their figures) and reports/eig_validation.md.

Run: python analysis/eig_studies.py
"""

import logging
from pathlib import Path

from stabctl.studies.eig_validation import write_validation

#: PSTess svm_mgen eigenvalues of Kundur (with and without PSS), kept with the tests
REF = Path(__file__).resolve().parent.parent / "tests" / "data" / "pstess"

if __name__ == "__main__":
    logging.basicConfig(level=logging.INFO, format="%(message)s")  # the files written
    write_validation("reports", REF)
