"""PSS/E's quadratic saturation, shared by the DC exciters and GENROU as ANDES reads them.

S(E) E = B (E - A)^2 for E > A, else 0, through two points (E1, S(E1)), (E2, S(E2))
(PSS/E Model Library; ANDES 2.0 ``andes/models/exciter/saturation.py`` ``ExcQuadSat``,
whose ``A``, ``B`` services are these formulas).
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
