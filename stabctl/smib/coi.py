"""Two-machine system and its centre-of-inertia (COI) equivalent (paper eqs. 15-24).

A generator (inertia H1, mechanical power Pm) is connected through a lossless network to
the rest of the system, lumped into one machine of inertia H_rest that absorbs Pm in steady
state.  With the COI angle delta_COI = (H1*delta1 + H_rest*delta2)/(H1 + H_rest) (eq. 40
for two machines), the relative angle delta = delta1 - delta2 obeys the OMIB equation

    (2H/omega_s) d2(delta)/dt2 = Pm - Pmax sin(delta) - k_C * P_C,
    H = H1*H_rest/(H1 + H_rest),   k_C = H_rest/(H1 + H_rest),

where P_C (pu, + absorbs) is a storage device at the generator bus; the COI itself only
accelerates by -omega_s*P_C/(2(H1 + H_rest)).  The speed the paper's controller sees,
omega1 - omega_COI, equals k_C * d(delta)/dt.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from stabctl.errors import InputError
from stabctl.smib.omib import OMIB


@dataclass(frozen=True)
class TwoMachineCOI:
    """A generator against the rest of the system (paper Section 4).

    Attributes:
        H1, H_rest: inertia constants (s, system base) of the generator and of the rest.
        Pm: generator mechanical power = power sent to the rest before the fault (pu).
        Pmax_pre, Pmax_fault, Pmax_post: peak transfer of each network stage (pu).
        f0: nominal frequency (Hz).

    Raises:
        InputError: a non-positive inertia, or the OMIB checks of the equivalent.
    """

    H1: float
    H_rest: float
    Pm: float
    Pmax_pre: float
    Pmax_fault: float
    Pmax_post: float
    f0: float = 60.0

    def __post_init__(self):
        if not (self.H1 > 0 and self.H_rest > 0):
            raise InputError(f"inertias must be positive, got H1={self.H1}, H_rest={self.H_rest}")
        self.equivalent()  # validates the operating point

    @property
    def H(self) -> float:
        """Equivalent inertia H1*H_rest/(H1 + H_rest) (s)."""
        return self.H1 * self.H_rest / (self.H1 + self.H_rest)

    @property
    def k_C(self) -> float:
        """Share of the storage power acting on the relative angle, H_rest/(H1 + H_rest)."""
        return self.H_rest / (self.H1 + self.H_rest)

    def equivalent(self) -> OMIB:
        """The OMIB in the relative angle delta1 - delta2 (paper eqs. 21-24)."""
        return OMIB(
            H=self.H,
            Pm=self.Pm,
            Pmax_pre=self.Pmax_pre,
            Pmax_fault=self.Pmax_fault,
            Pmax_post=self.Pmax_post,
            f0=self.f0,
            k_C=self.k_C,
        )

    def simulate_machines(
        self, t_clear: float, t_end: float, P_C: float = 0.0, t_on: float | None = None
    ) -> dict[str, np.ndarray]:
        """Integrate both machines separately (delta1, omega1, delta2, omega2).

        The fault is applied at t = 0 and cleared at t_clear; a constant storage power P_C
        acts from t_on (default: clearing) on.  Used to verify the equivalent: returns t and
        the four states (rad, rad/s, in the frame rotating at omega_s).
        """
        ws = 2 * np.pi * self.f0
        d0 = self.equivalent().delta0

        def rhs(stage, pc):
            pmax = getattr(self, f"Pmax_{stage}")

            def f(t, x):
                p_line = pmax * np.sin(x[0] - x[2])
                return [
                    x[1],
                    ws / (2 * self.H1) * (self.Pm - p_line - pc),
                    x[3],
                    ws / (2 * self.H_rest) * (-self.Pm + p_line),
                ]

            return f

        t_on = t_clear if t_on is None else t_on
        # machine angles placed so that the COI angle is zero before the fault
        x = [d0 * self.k_C, 0.0, -d0 * (1 - self.k_C), 0.0]
        segments, ts, xs = [(0, t_clear, "fault"), (t_clear, t_end, "post")], [], []
        for a, b, stage in segments:
            if b <= a:
                continue
            sol = solve_ivp(
                rhs(stage, P_C if a >= t_on else 0.0),
                (a, b),
                x,
                rtol=1e-10,
                atol=1e-12,
                max_step=1e-3,
            )
            ts.append(sol.t)
            xs.append(sol.y)
            x = sol.y[:, -1]
        t, y = np.concatenate(ts), np.concatenate(xs, axis=1)
        return {"t": t, "delta1": y[0], "omega1": y[1], "delta2": y[2], "omega2": y[3]}


#: The paper's Table 2 case.  Table 2 fixes only what the relative-angle dynamics depend on:
#: delta0 = pi/6 (Pm = 0.5 pu, Pmax = 1 pu), H = 6/7 s, a 6-cycle bolted fault
#: (x1(tr) = 1.0734 rad, x2(tr) = 10.9956 rad/s = 3.5*pi).  We split H as H1 = 1 s and
#: H_rest = 6 s; the split only matters for the storage share k_C = 6/7.
PAPER_TWO_MACHINE = TwoMachineCOI(
    H1=1.0, H_rest=6.0, Pm=0.5, Pmax_pre=1.0, Pmax_fault=0.0, Pmax_post=1.0
)
PAPER_TWO_MACHINE_T_RELEASE = 0.1  # s, 6 cycles at 60 Hz
