"""PSS/E's quadratic and exponential saturation, shared by the DC exciters and the PSS/E
machines (GENROU, GENSAL as ANDES reads them; GENROE, GENSAE).

Quadratic: S(E) E = B (E - A)^2 for E > A, else 0, through two points (E1, S(E1)), (E2,
S(E2)) (PSS/E Model Library; ANDES 2.0 ``andes/models/exciter/saturation.py``
``ExcQuadSat``, whose ``A``, ``B`` services are these formulas); exponential: S(E) = B E^A
through the same points (PSS/E Model Library GENROE, GENSAE).
"""

from __future__ import annotations

import numpy as np

from stabctl.errors import CaseError


def quadratic_fit(E1, SE1, E2, SE2, rows, what: str):
    """A, B of S(E) E = B (E - A)^2 with S(E1) = SE1, S(E2) = SE2, arrays of shape (n,).

    Rows outside ``rows`` (bool mask) or with a point 0 get (0, 0): no saturation.
    Raises CaseError naming ``what`` (e.g. "exc_con row 3: DC exciter saturation points
    (E1, SE1, E2, SE2)", with ``{row}`` replaced by the 1-based row) when the points allow
    no fit (E1 = E2, SE1 E1 = SE2 E2, or of opposite signs)."""
    off = (E1 * SE1 * E2 * SE2 == 0) | ~rows
    with np.errstate(divide="ignore", invalid="ignore"):
        a = np.sqrt(SE1 * E1 / (SE2 * E2))
        A = E2 - (E1 - E2) / (a - 1)
        B = SE2 * E2 * (a - 1) ** 2 / (E1 - E2) ** 2
    bad = np.nonzero(~off & ~np.isfinite(A + B))[0]
    if bad.size:
        raise CaseError(
            what.format(row=bad[0] + 1) + " give no quadratic fit (need E1 != E2, "
            "SE1 E1 != SE2 E2, same sign)"
        )
    return np.where(off, 0.0, A), np.where(off, 0.0, B)


def exponential_fit(E1, SE1, E2, SE2, rows, what: str):
    """A, B of S(E) = B E^A with S(E1) = SE1, S(E2) = SE2, arrays of shape (n,): PSS/E's
    exponential saturation (GENROE, GENSAE: A = ln(SE2 / SE1) / ln(E2 / E1), B = SE1
    E1^-A).

    Rows outside ``rows`` (bool mask) or with both SE1, SE2 = 0 get (0, 0): no
    saturation.  Raises CaseError naming ``what`` (``{row}`` replaced by the 1-based row)
    when the points allow no fit (a point <= 0 with the other > 0, or E1 = E2)."""
    off = ((SE1 == 0) & (SE2 == 0)) | ~rows
    with np.errstate(divide="ignore", invalid="ignore"):
        A = np.log(SE2 / SE1) / np.log(E2 / E1)
        B = SE1 * np.power(E1, -A)
    bad = np.nonzero(~off & ~(np.isfinite(A + B) & (SE1 > 0) & (SE2 > 0)))[0]
    if bad.size:
        raise CaseError(
            what.format(row=bad[0] + 1) + " give no exponential fit (need S(1.0), S(1.2) "
            "both > 0, or both 0 for none)"
        )
    return np.where(off, 0.0, A), np.where(off, 0.0, B)
