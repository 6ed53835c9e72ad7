"""Linear and sign feedback laws of the paper's Section 3 for a storage device at the generator.

The device absorbs P_eC (pu, + absorbs) computed from the rotor speed deviation
omega = d(delta)/dt (rad/s) and acceleration a = d2(delta)/dt2 (rad/s^2):

    linear laws (paper eq. 12-13):   P_eC = Kv * omega + Ka * a
    fourth law  (paper eq. 14):      P_eC = Ka * |a| * sgn(omega)

Equation (14) is garbled in the source text; we read it as Ka*|d2delta/dt2|*sgn(d delta/dt),
the reading consistent with the paper's description (it stabilises the 15-cycle case and
gives the smallest speed swing and the fastest settling of the four laws).

The laws that use the acceleration form an algebraic loop with the swing equation
M*a = f - P_eC (f = Pm - Pe - D*omega, the uncontrolled accelerating power).  We resolve it
exactly:

    linear:  a = (f - Kv*omega) / (M + Ka)                 (needs M + Ka > 0)
    fourth:  a = (f - Kv*omega) / (M + Ka*sgn(omega)*sgn(f - Kv*omega))   (needs M > |Ka|)

so that Ka < 0 acts as a lower effective inertia while the machine decelerates and the
fourth law always draws energy from the swing (P_eC * omega >= 0).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from stabctl.errors import InputError, check_fields


@dataclass(frozen=True)
class FeedbackLaw:
    """Speed/acceleration feedback law for a storage device (paper Section 3).

    Attributes:
        name: label for tables and figures.
        Ka: acceleration gain (pu*s^2/rad).
        Kv: speed gain (pu*s/rad).
        sign_law: False for P = Kv*omega + Ka*a; True for eq. (14),
            P = Ka*|a|*sgn(omega) + Kv*omega.

    Raises:
        WrongTypeError: a gain not a number, sign_law not a bool (`check_fields`).
    """

    name: str
    Ka: float = 0.0
    Kv: float = 0.0
    sign_law: bool = False

    def __post_init__(self) -> None:
        check_fields(self)  # Ka="0.1" failed in arithmetic, sign_law="no" was the sign law

    def check(self, M: float) -> None:
        """Raise InputError when the algebraic loop has no unique solution for inertia M."""
        if (self.sign_law and abs(self.Ka) >= M) or (not self.sign_law and M + self.Ka <= 0):
            raise InputError(
                f"law {self.name!r}: acceleration gain Ka = {self.Ka} makes the algebraic loop "
                f"singular for M = {M:.5g} (need M + Ka > 0, or |Ka| < M for the sign law)"
            )

    def __call__(self, f: float, omega: float, M: float) -> tuple[float, float]:
        """Resolve the loop: returns (acceleration rad/s^2, P_eC pu) for accelerating power f."""
        g = f - self.Kv * omega
        if self.sign_law:
            a = g / (M + self.Ka * np.sign(omega) * np.sign(g))
            return a, self.Kv * omega + self.Ka * abs(a) * np.sign(omega)
        a = g / (M + self.Ka)
        return a, self.Kv * omega + self.Ka * a


#: The four laws the paper applies to the 15-cycle case (Section 3, Fig. 7).
PAPER_LAWS = (
    FeedbackLaw("acceleration (Ka=-0.004)", Ka=-0.004),
    FeedbackLaw("speed (Kv=0.02)", Kv=0.02),
    FeedbackLaw("speed+acceleration (Ka=-0.004, Kv=0.02)", Ka=-0.004, Kv=0.02),
    FeedbackLaw("sign law eq.(14) (Ka=0.007)", Ka=0.007, sign_law=True),
)


def settling_time(t: np.ndarray, omega: np.ndarray, t_from: float, band: float = 0.05) -> float:
    """Time after t_from (s) at which |omega| enters and stays within band * max|omega|.

    Returns inf when the speed is still outside the band at the last sample (an undamped
    swing never settles).
    """
    sel = t >= t_from
    tt, w = t[sel], np.abs(omega[sel])
    outside = np.nonzero(w > band * w.max())[0]
    if outside.size == 0:
        return 0.0
    last = outside[-1]
    return float("inf") if last == w.size - 1 else float(tt[last + 1] - t_from)
