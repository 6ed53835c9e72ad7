"""One-machine infinite-bus (OMIB) swing equation, energy function and equal-area criterion.

The paper's Section 2 (eqs. 1-4, 10-11): a generator of inertia constant H behind a reactance
to an infinite bus,

    M * d2(delta)/dt2 = Pm - Pmax_k * sin(delta) - P_C,      M = 2 H / omega_s,

with Pmax_k the peak transfer of network stage k (pre-fault, fault-on, post-fault), P_C the
power absorbed by an energy-storage device at the generator bus (+ absorbs, as the paper),
omega = d(delta)/dt the rotor speed deviation in electrical rad/s and omega_s = 2*pi*f0.

Units: per unit on the system base for powers, s for H and time, rad for angles, rad/s for
omega, Hz for f0.  M is in pu*s^2/rad.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from numbers import Real

import numpy as np
from scipy.integrate import solve_ivp

from stabctl.errors import InputError, WrongTypeError

CYCLE_S_60HZ = 1.0 / 60.0


@dataclass(frozen=True)
class OMIB:
    """OMIB system with three network stages (paper eqs. 1-4).

    Attributes
    ----------
    H : float
        Inertia constant, s (on the system base), > 0.
    Pm : float
        Mechanical power, pu, 0 <= Pm < Pmax_post.
    Pmax_pre, Pmax_fault, Pmax_post : float
        Peak electrical power E*V/X of the pre-fault, fault-on and post-fault network, pu
        (>= 0); Pmax_fault = 0 for a bolted fault at the generator bus.
    f0 : float, optional
        Nominal frequency, Hz, > 0; default 60.
    D : float, optional
        Damping, pu power per rad/s of speed deviation (>= 0); 0 in the paper.
    k_C : float, optional
        Share of the storage power that acts on this angle: 1 for the OMIB, and
        H_rest / (H1 + H_rest) for the two-machine COI equivalent (`stabctl.smib.coi`).

    Raises
    ------
    InputError
        A parameter that is not a finite number, H or f0 not positive, Pm, D or a Pmax
        negative, k_C outside [0, 1], Pm >= Pmax of the pre- or post-fault network (no
        equilibrium), or Pmax_fault above Pmax_pre.
    TypeError
        A parameter that is no number (a str).
    """

    H: float
    Pm: float
    Pmax_pre: float
    Pmax_fault: float
    Pmax_post: float
    f0: float = 60.0
    D: float = 0.0
    k_C: float = 1.0

    def __post_init__(self):
        given = {k: getattr(self, k) for k in ("H", "Pm", "Pmax_pre", "Pmax_fault", "Pmax_post")}
        given.update(f0=self.f0, D=self.D, k_C=self.k_C)
        text = [f"{k} = {v!r}" for k, v in given.items() if not isinstance(v, Real)]
        if text:
            raise WrongTypeError(f"OMIB: not a number: {', '.join(text)}")
        odd = [f"{k} = {v}" for k, v in given.items() if not np.isfinite(float(v))]
        if odd:  # NaN compares false with every bound below
            raise InputError(f"OMIB: not a finite number: {', '.join(odd)}")
        if not self.H > 0:
            raise InputError(f"inertia constant H must be positive, got H = {self.H} s")
        if not self.f0 > 0:
            raise InputError(f"nominal frequency must be positive, got f0 = {self.f0} Hz")
        if self.Pm < 0:
            raise InputError(f"mechanical power must be >= 0, got Pm = {self.Pm} pu")
        if not 0 <= self.k_C <= 1:
            raise InputError(
                f"storage share k_C must be in [0, 1] (1 for the OMIB, H_rest / (H1 + H_rest) "
                f"for the two-machine equivalent), got k_C = {self.k_C}"
            )
        if min(self.Pmax_pre, self.Pmax_post, self.Pmax_fault) < 0 or self.D < 0:
            raise InputError("Pmax of every stage and damping D must be >= 0")
        if self.Pmax_fault > self.Pmax_pre:
            raise InputError(
                f"Pmax_fault = {self.Pmax_fault} pu above Pmax_pre = {self.Pmax_pre} pu: a fault "
                "lowers the transfer capability, it never raises it"
            )
        for stage in ("pre", "post"):
            pmax = getattr(self, f"Pmax_{stage}")
            if self.Pm >= pmax:
                raise InputError(
                    f"no equilibrium: Pm = {self.Pm} pu is not below Pmax_{stage} = {pmax} pu"
                )

    @classmethod
    def from_operating_point(
        cls,
        H: float,
        Pm: float,
        delta0: float,
        V0: float = 1.0,
        V1: float = 1.0,
        fault_ratio: float = 0.0,
        post_ratio: float = 1.0,
        f0: float = 60.0,
    ) -> OMIB:
        """Build the OMIB from the pre-fault operating point (paper Section 2).

        Pmax_pre = Pm / sin(delta0) (so that Pe = Pm at delta0, i.e. X = V0*V1/Pmax_pre);
        the fault-on and post-fault peaks are fault_ratio and post_ratio times Pmax_pre.

        Parameters
        ----------
        H : float
            Inertia constant, s (on the system base), > 0.
        Pm : float
            Mechanical power = pre-fault electrical power, pu.
        delta0 : float
            Pre-fault rotor angle, rad, in (0, pi/2).
        V0, V1 : float, optional
            Generator internal and infinite-bus voltage magnitudes, pu, > 0; default 1.
            They fix the implied reactance X only; the model uses Pmax.
        fault_ratio : float, optional
            Pmax_fault / Pmax_pre; default 0 (bolted fault at the generator bus).
        post_ratio : float, optional
            Pmax_post / Pmax_pre; default 1 (post-fault network = pre-fault).
        f0 : float, optional
            Nominal frequency, Hz; default 60.

        Returns
        -------
        OMIB
            The system, D = 0 and k_C = 1.

        Raises
        ------
        InputError
            delta0 outside (0, pi/2) (no stable pre-fault equilibrium), a voltage not
            positive, or the parameters rejected by :class:`OMIB`.
        """
        if not 0 < delta0 < np.pi / 2:
            raise InputError(f"delta0 = {delta0} rad is not a stable equilibrium angle (0, pi/2)")
        if not (V0 > 0 and V1 > 0):
            raise InputError("voltages V0 and V1 must be positive")
        pmax = Pm / np.sin(delta0)
        return cls(
            H=H,
            Pm=Pm,
            Pmax_pre=pmax,
            Pmax_fault=fault_ratio * pmax,
            Pmax_post=post_ratio * pmax,
            f0=f0,
        )

    # -- constants of the model -------------------------------------------------------
    @property
    def omega_s(self) -> float:
        """Synchronous speed 2*pi*f0 (electrical rad/s)."""
        return 2 * np.pi * self.f0

    @property
    def M(self) -> float:
        """Inertia coefficient M = 2H/omega_s (pu*s^2/rad), paper eq. (1)."""
        return 2 * self.H / self.omega_s

    @property
    def X(self) -> float:
        """Pre-fault transfer reactance for V0 = V1 = 1 (pu)."""
        return 1.0 / self.Pmax_pre

    @property
    def delta0(self) -> float:
        """Pre-fault stable equilibrium angle (rad)."""
        return float(np.arcsin(self.Pm / self.Pmax_pre))

    @property
    def delta_s(self) -> float:
        """Post-fault stable equilibrium angle (rad)."""
        return float(np.arcsin(self.Pm / self.Pmax_post))

    @property
    def delta_u(self) -> float:
        """Post-fault unstable equilibrium angle pi - delta_s (rad)."""
        return float(np.pi - self.delta_s)

    def pe(self, delta, stage: str = "post"):
        """Electrical power Pmax_stage * sin(delta), paper eq. (1).

        Parameters
        ----------
        delta : float or array_like
            Rotor angle, rad, any shape.
        stage : {'pre', 'fault', 'post'}, optional
            Network stage; default 'post'.

        Returns
        -------
        float or numpy.ndarray
            Pe, pu, of the shape of `delta`.
        """
        return getattr(self, f"Pmax_{stage}") * np.sin(delta)

    def accelerating_power(self, delta, omega=0.0, stage: str = "post"):
        """Pm - Pe - D*omega, the right-hand side of eq. (1) without storage.

        Parameters
        ----------
        delta : float or array_like
            Rotor angle, rad.
        omega : float or array_like, optional
            Rotor speed deviation, electrical rad/s; default 0.  Broadcasts with `delta`.
        stage : {'pre', 'fault', 'post'}, optional
            Network stage; default 'post'.

        Returns
        -------
        float or numpy.ndarray
            Accelerating power, pu, of the broadcast shape of `delta` and `omega`.
        """
        return self.Pm - self.pe(delta, stage) - self.D * omega

    def rhs(self, stage: str, P_C: float = 0.0):
        """Right-hand side of eq. (1) of one stage with a constant storage power P_C.

        Parameters
        ----------
        stage : {'pre', 'fault', 'post'}
            Network stage.
        P_C : float, optional
            Storage power at the generator bus, pu (+ absorbs, as the paper), scaled by
            `k_C`; default 0.

        Returns
        -------
        callable
            ``f(t, x)`` for x = [delta (rad), omega (rad/s)], returning
            [d(delta)/dt (rad/s), d(omega)/dt (rad/s^2)] (scipy ``solve_ivp`` form).
        """
        M = self.M

        def f(t, x):
            return [x[1], (self.accelerating_power(x[0], x[1], stage) - self.k_C * P_C) / M]

        return f

    # -- energy function and equal-area criterion ---------------------------------------
    def energy(self, delta, omega):
        """Transient energy function of the post-fault system, paper eq. (10).

        V = M*omega^2/2 - Pm*(delta - delta_s) - Pmax_post*(cos(delta) - cos(delta_s));
        constant along undamped, uncontrolled post-fault trajectories; zero at the stable
        equilibrium.

        Parameters
        ----------
        delta : float or array_like
            Rotor angle, rad.
        omega : float or array_like
            Rotor speed deviation, electrical rad/s; broadcasts with `delta`.

        Returns
        -------
        float or numpy.ndarray
            V, pu*s (pu power times rad), of the broadcast shape.
        """
        ds = self.delta_s
        return (
            0.5 * self.M * np.asarray(omega) ** 2
            - self.Pm * (np.asarray(delta) - ds)
            - self.Pmax_post * (np.cos(delta) - np.cos(ds))
        )

    @property
    def critical_energy(self) -> float:
        """Energy at the unstable equilibrium, V(delta_u, 0): the stability-region level."""
        return float(self.energy(self.delta_u, 0.0))

    def separatrix(self, delta):
        """Upper branch of the stability-region boundary through delta_u.

        The level set V(delta, omega) = V(delta_u, 0) of the undamped post-fault system
        (paper eq. 10).  The lower branch is its negative.

        Parameters
        ----------
        delta : float or array_like
            Rotor angle, rad, any shape.

        Returns
        -------
        float or numpy.ndarray
            Speed deviation omega on the boundary, rad/s, of the shape of `delta`; NaN
            where the level set has no real speed.
        """
        ds = self.delta_s
        kinetic = (
            self.critical_energy
            + self.Pm * (np.asarray(delta) - ds)
            + self.Pmax_post * (np.cos(delta) - np.cos(ds))
        )
        with np.errstate(invalid="ignore"):
            return np.sqrt(2 * kinetic / self.M)

    def accelerating_area(self, delta_cl: float) -> float:
        """Accelerating area of the equal-area criterion, paper eq. (11).

        A1 = integral of (Pm - Pmax_fault sin d) dd from delta0 to delta_cl.

        Parameters
        ----------
        delta_cl : float
            Clearing angle, rad.

        Returns
        -------
        float
            A1, pu*rad.
        """
        d0 = self.delta0
        return self.Pm * (delta_cl - d0) + self.Pmax_fault * (np.cos(delta_cl) - np.cos(d0))

    def decelerating_area(self, delta_cl: float) -> float:
        """Available decelerating area of the equal-area criterion.

        A2 = integral of (Pmax_post sin d - Pm) dd from delta_cl to delta_u.

        Parameters
        ----------
        delta_cl : float
            Clearing angle, rad.

        Returns
        -------
        float
            A2, pu*rad.
        """
        du = self.delta_u
        return self.Pmax_post * (np.cos(delta_cl) - np.cos(du)) - self.Pm * (du - delta_cl)

    def critical_clearing_angle(self) -> float:
        """Critical clearing angle from A1 = A2, closed form (equal-area criterion).

        cos(delta_cr) = [Pm (delta_u - delta0) + Pmax_post cos(delta_u)
                         - Pmax_fault cos(delta0)] / (Pmax_post - Pmax_fault).

        Returns
        -------
        float
            delta_cr, rad.

        Raises
        ------
        InputError
            The fault-on network is at least as strong as the post-fault one, or no
            clearing angle satisfies the criterion (always/never stable).
        """
        d0, du = self.delta0, self.delta_u
        den = self.Pmax_post - self.Pmax_fault
        if den <= 0:
            raise InputError("Pmax_fault >= Pmax_post: the equal-area criterion gives no angle")
        c = (self.Pm * (du - d0) + self.Pmax_post * np.cos(du) - self.Pmax_fault * np.cos(d0)) / den
        if not -1 <= c <= 1:
            raise InputError(f"no critical clearing angle: cos(delta_cr) = {c:.4f}")
        return float(np.arccos(c))

    def critical_clearing_time(self) -> float:
        """Critical clearing time from the critical clearing angle.

        Closed form t_cr = sqrt(2 M (delta_cr - delta0) / Pm) when Pmax_fault = 0 and
        D = 0 (constant fault-on acceleration); otherwise the time the fault-on trajectory
        reaches delta_cr (located by an integration event).

        Returns
        -------
        float
            t_cr, s after the fault start.

        Raises
        ------
        InputError
            No critical clearing angle (see :meth:`critical_clearing_angle`), Pm = 0 (the
            fault does not accelerate the machine), or the fault-on trajectory never
            reaches the critical angle.
        """
        dcr = self.critical_clearing_angle()
        if self.Pm == 0:
            raise InputError(
                "Pm = 0: the fault does not accelerate the machine, there is no "
                "critical clearing time"
            )
        if self.Pmax_fault == 0 and self.D == 0:
            return float(np.sqrt(2 * self.M * (dcr - self.delta0) / self.Pm))
        event = lambda t, x: x[0] - dcr  # noqa: E731
        event.terminal, event.direction = True, 1  # type: ignore[attr-defined]  # scipy's
        sol = solve_ivp(
            self.rhs("fault"), (0, 10.0), [self.delta0, 0.0], events=event, rtol=1e-11, atol=1e-12
        )
        if not sol.t_events[0].size:
            raise InputError("the fault-on trajectory never reaches the critical angle")
        return float(sol.t_events[0][0])


#: The paper's Section 2 case: V0 = V1 = 1, H = 3 s, 60 Hz, Pm = Pe = 0.5 pu,
#: delta0 = 0.4950 rad, bolted fault at the generator bus, post-fault network = pre-fault.
PAPER_OMIB = OMIB.from_operating_point(H=3.0, Pm=0.5, delta0=0.4950)


def cycles_to_seconds(cycles: float, f0: float = 60.0) -> float:
    """Fault duration in cycles of the nominal frequency to seconds."""
    return cycles / f0


def clearing_state_closed_form(system: OMIB, t_clear: float) -> tuple[float, float]:
    """(delta, omega) at clearing for a bolted fault (Pmax_fault = 0): constant acceleration.

    delta = delta0 + a t^2/2, omega = a t with a = Pm/M (paper Section 2).

    Raises:
        InputError: Pmax_fault is not zero.
    """
    if system.Pmax_fault != 0:
        raise InputError("closed-form clearing state needs Pmax_fault = 0")
    a = system.Pm / system.M
    return system.delta0 + 0.5 * a * t_clear**2, a * t_clear


#: A post-fault control law: (f, omega, M) -> (acceleration rad/s^2, P_C pu), where f is the
#: uncontrolled accelerating power Pm - Pe - D*omega.  It resolves its own algebraic loop
#: when P_C depends on the acceleration (see `stabctl.smib.feedback`).
ControlLaw = Callable[[float, float, float], tuple[float, float]]


@dataclass
class OMIBRun:
    """An OMIB simulation: fault at t = 0, cleared at t_clear.

    Attributes:
        t: times (s), shape (n,); delta (rad), omega (rad/s), P_C (pu, + absorbs): shape (n,).
        stable: False when the angle passed the post-fault UEP delta_u before t_end.
        t_unstable: time it did so (s), or None.
        delta_cl, omega_cl: state at clearing.
    """

    t: np.ndarray
    delta: np.ndarray
    omega: np.ndarray
    P_C: np.ndarray
    stable: bool
    t_unstable: float | None
    t_clear: float
    delta_cl: float
    omega_cl: float


def _unstable_event(system: OMIB):
    """Loss of synchronism: the angle passes the post-fault UEP delta_u upward (terminal)."""
    du = system.delta_u

    def event(t, x):
        return x[0] - du

    event.terminal, event.direction = True, 1  # type: ignore[attr-defined]  # scipy's
    return event


def simulate(
    system: OMIB,
    t_clear: float,
    t_end: float = 3.0,
    law: ControlLaw | None = None,
    max_step: float = 1e-3,
    rtol: float = 1e-9,
) -> OMIBRun:
    """Simulate a fault at t = 0 cleared at t_clear (s), then the post-fault network.

    The control law (if any) acts only after clearing, as in the paper's Section 3.  The
    integration restarts exactly at the clearing instant (scipy solve_ivp, RK45).  The run
    stops when the angle passes delta_u (loss of synchronism).

    Raises:
        InputError: t_clear < 0, t_end <= t_clear, or either not finite (round 43: NaN
            or inf gave solve_ivp a span it never ended).
    """
    if not (math.isfinite(t_clear) and math.isfinite(t_end)) or t_clear < 0 or t_end <= t_clear:
        raise InputError(f"need 0 <= t_clear < t_end, got t_clear={t_clear}, t_end={t_end}")
    x0 = [system.delta0, 0.0]
    if t_clear > 0:
        on = solve_ivp(
            system.rhs("fault"), (0, t_clear), x0, max_step=max_step, rtol=rtol, atol=1e-10
        )
        t1, x1 = on.t, on.y
    else:
        t1, x1 = np.array([0.0]), np.array(x0, float).reshape(2, 1)
    xcl = x1[:, -1]
    post = _post_rhs(system, law)
    off = solve_ivp(
        post,
        (t_clear, t_end),
        xcl,
        max_step=max_step,
        rtol=rtol,
        atol=1e-10,
        events=_unstable_event(system),
    )
    t = np.concatenate([t1, off.t[1:]])
    y = np.concatenate([x1, off.y[:, 1:]], axis=1)
    P_C = np.zeros_like(t)
    if law is not None:
        k = t1.size
        f = system.accelerating_power(y[0, k:], y[1, k:], "post")
        P_C[k:] = [law(fi, wi, system.M)[1] for fi, wi in zip(f, y[1, k:])]
    lost = off.t_events[0].size > 0 or xcl[0] >= system.delta_u
    return OMIBRun(
        t=t,
        delta=y[0],
        omega=y[1],
        P_C=P_C,
        stable=not lost,
        t_unstable=_first_event(off, t_clear) if lost else None,
        t_clear=t_clear,
        delta_cl=float(xcl[0]),
        omega_cl=float(xcl[1]),
    )


def _first_event(sol, t_clear: float) -> float:
    """Time of the loss-of-synchronism event (the clearing time if cleared beyond delta_u)."""
    return float(sol.t_events[0][0]) if sol.t_events[0].size else t_clear


def _post_rhs(system: OMIB, law: ControlLaw | None):
    """Post-fault right-hand side, with the control law's acceleration when given."""
    if law is None:
        return system.rhs("post")
    M = system.M

    def f(t, x):
        return [x[1], law(system.accelerating_power(x[0], x[1], "post"), x[1], M)[0]]

    return f


def critical_clearing_time_bisection(
    system: OMIB, tol: float = 1e-4, t_max: float = 1.0, t_end: float = 5.0
) -> tuple[float, int]:
    """CCT by bisection on time-domain simulations: (CCT in s, number of runs).

    Stability criterion: the run does not pass delta_u within t_end (see `simulate`).
    The bracket is checked first (stable at 0, unstable at t_max).

    Raises:
        InputError: the bracket [0, t_max] does not contain the CCT (unstable when
        cleared at once, or still stable when cleared at t_max), saying which.
    """

    def stable(tc):
        return simulate(system, tc, t_end=t_end, max_step=5e-3).stable

    if not stable(0.0):
        raise InputError("unstable even when the fault is cleared at once: no CCT")
    if stable(t_max):
        raise InputError(f"still stable when cleared at {t_max:g} s: the CCT is above it")
    lo, hi, runs = 0.0, t_max, 2
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        runs += 1
        lo, hi = (mid, hi) if stable(mid) else (lo, mid)
    return 0.5 * (lo + hi), runs


#: end of each run of `clearing_table` (s): the fault must be cleared before it
TABLE_T_END = 3.0


def clearing_table(system: OMIB, fault_cycles, t_end: float = TABLE_T_END) -> list[dict]:
    """Per fault duration: clearing time, delta and speed at clearing, stable or not.

    The paper's Table 1 for PAPER_OMIB and 6, 12, 15 cycles.  Returns one dict per case with
    keys cycles, t_clear_s, delta_cl_rad, omega_cl_rad_s, stable.  Each fault (cycles of
    ``system.f0``) must be cleared before `t_end` (s; :data:`TABLE_T_END` by default),
    else InputError (`simulate`).
    """
    rows = []
    for cyc in fault_cycles:
        if cyc < 0:
            raise InputError(f"fault duration must be >= 0 cycles, got {cyc}")
        run = simulate(system, cycles_to_seconds(cyc, system.f0), t_end=t_end)
        rows.append(
            {
                "cycles": float(cyc),
                "t_clear_s": run.t_clear,
                "delta_cl_rad": run.delta_cl,
                "omega_cl_rad_s": run.omega_cl,
                "stable": run.stable,
            }
        )
    return rows


#: the latest clearing `eac_summary`'s bisection tries, s (its runs end 4 s later)
BISECTION_T_MAX = 10.0


def eac_summary(system: OMIB) -> dict:
    """Equal-area critical clearing angle and time, closed form and by bisection.

    The bisection searches [0, max(1 s, twice the closed form's CCT)], each run going on
    4 s past that (a small Pm accelerates the machine slowly: its CCT, 1.7 s at Pm = 0.01
    pu, lay beyond a fixed 1 s), and is not run when twice the CCT passes
    `BISECTION_T_MAX` (``t_cr_bisection_s`` None, ``bisection_runs`` 0).
    """
    t_cr = system.critical_clearing_time()
    t_max = max(1.0, 2.0 * t_cr)
    t_bis, runs = None, 0
    if t_max <= BISECTION_T_MAX:
        t_bis, runs = critical_clearing_time_bisection(system, t_max=t_max, t_end=t_max + 4.0)
    return {
        "delta_cr_rad": system.critical_clearing_angle(),
        "t_cr_s": t_cr,
        "t_cr_cycles": t_cr * system.f0,
        "t_cr_bisection_s": t_bis,
        "bisection_runs": runs,
        "delta_u_rad": system.delta_u,
    }
