"""Minimum-time optimal storage control after fault release (paper eqs. 27-39).

From the state at fault release x(tr) = (x1, x2) = (delta, d(delta)/dt), find the storage
power 0 <= P_C <= P_Cmax (+ absorbs) that brings the speed to zero in minimum time T:

    minimise T   s.t.  x1' = x2,   x2' = (Pm - Pmax sin x1 - k_C P_C) / M,   x2(tr+T) = 0.

Pontryagin's minimum principle with Hamiltonian H = 1 + l1*x2 + l2*x2' gives the co-states

    l1' = -dH/dx1 = l2 * Pmax cos(x1) / M,      l2' = -dH/dx2 = -l1,

the switching law P_C = P_Cmax where l2 > 0 (H is linear in P_C with slope -k_C*l2/M), and,
the final angle and time being free, the transversality conditions l1(tr+T) = 0 and
H(tr+T) = 0 (H is then zero on the whole interval, the system being autonomous).

`solve_min_time` solves this two-point boundary-value problem with free final time by
scipy's collocation solver (time scaled to [0, 1], T an unknown parameter) under the
hypothesis P_C = P_Cmax throughout, then checks the hypothesis: l2 > 0 on the whole interval
means the full absorbing pulse satisfies the minimum principle.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_bvp, solve_ivp

from stabctl.errors import InputError
from stabctl.smib.omib import OMIB


@dataclass
class MinTimeSolution:
    """Result of the minimum-time problem.

    Attributes:
        T: minimum time from release to zero speed (s).
        t: times from release (s), shape (n,); x1 (rad), x2 (rad/s), l1, l2 (co-states),
            hamiltonian (should be 0), P_C (pu): shape (n,).
        lambda2_positive: l2 > 0 on the whole interval (bang-bang with P_C = P_Cmax).
        T_pulse: time for a simulated constant P_Cmax pulse to stop the swing (s).
        T_uncontrolled: the same without storage (s), inf if the swing never stops.
        bvp_residual: largest collocation residual reported by solve_bvp.
    """

    T: float
    t: np.ndarray
    x1: np.ndarray
    x2: np.ndarray
    l1: np.ndarray
    l2: np.ndarray
    hamiltonian: np.ndarray
    P_C: np.ndarray
    lambda2_positive: bool
    T_pulse: float
    T_uncontrolled: float
    bvp_residual: float


def time_to_zero_speed(system: OMIB, x_start, P_C: float, t_max: float = 5.0):
    """Simulate the post-fault swing with a constant storage power until d(delta)/dt = 0.

    Returns (T in s, solve_ivp solution); T = inf when the speed does not reach zero
    within t_max (loss of synchronism).
    """

    def stop(t, x):
        return x[1]

    stop.terminal, stop.direction = True, -1  # type: ignore[attr-defined]  # scipy's
    sol = solve_ivp(
        system.rhs("post", P_C),
        (0, t_max),
        list(x_start),
        events=stop,
        rtol=1e-11,
        atol=1e-12,
        dense_output=True,
    )
    return (float(sol.t_events[0][0]) if sol.t_events[0].size else float("inf")), sol


def solve_min_time(system: OMIB, x_start, P_Cmax: float, n_nodes: int = 200) -> MinTimeSolution:
    """Solve the minimum-time boundary-value problem (paper eqs. 27-39).

    Args:
        system: post-fault OMIB (or the two-machine COI equivalent, whose k_C scales P_C).
        x_start: (x1, x2) at fault release (rad, rad/s), x2 > 0.
        P_Cmax: storage rating (pu, > 0).
        n_nodes: initial collocation mesh size.

    Raises:
        InputError: non-positive rating or speed, or the pulse cannot stop the swing.
        RuntimeError: the collocation solver did not converge.
    """
    x1_0, x2_0 = map(float, x_start)
    if P_Cmax <= 0 or x2_0 <= 0:
        raise InputError("need P_Cmax > 0 and a positive speed at fault release")
    T_pulse, pulse = time_to_zero_speed(system, x_start, P_Cmax)
    if not np.isfinite(T_pulse):
        raise InputError(f"a {P_Cmax} pu pulse does not stop the swing: no finite minimum time")
    T_unc, _ = time_to_zero_speed(system, x_start, 0.0)
    M, Pm, Pmax, u = system.M, system.Pm, system.Pmax_post, system.k_C * P_Cmax

    def ode(tau, y, p):
        x1, x2, l1, l2 = y
        return p[0] * np.vstack(
            [x2, (Pm - Pmax * np.sin(x1) - u) / M, l2 * Pmax * np.cos(x1) / M, -l1]
        )

    def hamiltonian(y):
        return 1 + y[2] * y[1] + y[3] * (Pm - Pmax * np.sin(y[0]) - u) / M

    def bc(ya, yb, p):
        return np.array([ya[0] - x1_0, ya[1] - x2_0, yb[1], yb[2], hamiltonian(yb)])

    tau = np.linspace(0, 1, n_nodes)
    xg = pulse.sol(tau * T_pulse)
    l2_T = M / (Pmax * np.sin(xg[0, -1]) + u - Pm)  # from H(T) = 0 with l1(T) = 0
    guess = np.vstack([xg, np.zeros(n_nodes), np.full(n_nodes, l2_T)])
    res = solve_bvp(ode, bc, tau, guess, p=[T_pulse], tol=1e-8, max_nodes=100000)
    if not res.success:
        raise RuntimeError(f"minimum-time BVP did not converge: {res.message}")
    T = float(res.p[0])
    tau_f = np.linspace(0, 1, 400)
    y = res.sol(tau_f)
    return MinTimeSolution(
        T=T,
        t=tau_f * T,
        x1=y[0],
        x2=y[1],
        l1=y[2],
        l2=y[3],
        hamiltonian=hamiltonian(y),
        P_C=np.where(y[3] > 0, P_Cmax, 0.0),
        lambda2_positive=bool(np.all(y[3] > 0)),
        T_pulse=T_pulse,
        T_uncontrolled=T_unc,
        bvp_residual=float(np.max(res.rms_residuals)),
    )
