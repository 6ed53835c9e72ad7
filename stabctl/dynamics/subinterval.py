"""Sub-interval integration of fast exciter loops: the network and every other model at
the run's step, an exciter whose closed loop is faster than that step in sub-steps of its
own, its inputs held over the step (PowerWorld Simulator's Transient Stability
"sub-interval" option for exciters, governors and stabilisers).

Why: an explicit method's step is bounded by the fastest loop of the model.  On
ACTIVSg2000 the 31 EXAC2 regulators (K_A = 1000, T_A = 0.05 s with their rate feedback
through T_E) close loops of 2.4-6.6 ms (`stabctl.models.exciters.ExciterParams.
inner_loop_time_constants`), which no single time constant of the data shows, and they
alone held the whole 2000-bus model to a 1.2 ms step while every time constant of the
data allows half a cycle (8.3 ms, its fastest a GGOV1 actuator's 17 ms).

How (`sub_heun_start`, `sub_heun_end`, inside `stabctl.dynamics.integrator`'s Heun step
from x_a over hh): the step's evaluation at x_a gives each such exciter's inputs u_a
(terminal and compensated voltage, field current, PSS output, source term, V_ref:
`stabctl.models.exciters.frozen_inputs`); its states at the predictor are Phi(x_a, u_a),
n Heun sub-steps of hh/n from x_a with u_a held (`stabctl.models.exciters.advance_frozen`),
n = ceil(hh / hmax); the predictor's evaluation gives u_p; the states at the step's end are
(Phi(x_a, u_a) + Phi(x_a, u_p)) / 2, the inputs' trapezoid as Heun's corrector takes the
other states'.  A linear loop driven by inputs that move linearly over the step is then
integrated to second order, as the rest of the model, and stably whatever its speed
against the step.  The exciter's states take no part in Heun's local error estimate of the
step (`sub_state_mask`): their own sub-steps are stable by construction.

Which exciters (`stabctl.dynamics.grid.exciter_hmax`): under the ieee conventions, with
sub-intervals on (the default), those whose inner loop time constant T_loop has
STEP_PER_TIME_CONSTANT * T_loop below the run's nominal step, each sub-stepped at hmax =
STEP_PER_TIME_CONSTANT * T_loop (the rule `stabctl.dynamics.grid.default_step` applies to
the whole model);
the default step is then set by the data's time constants alone.  Never under pstess
(PSTess has no sub-intervals: its runs stay bit for bit), and not in the implicit
trapezoid, the linearisation or the storage switching's location (`Simulator` option
``subintervals=False`` for the old single-rate rule).
"""

from __future__ import annotations

import math

import numpy as np

from stabctl._jit.arrays import assign
from stabctl._jit.borrow import borrowed
from stabctl._jit.decorators import kernel
from stabctl.models import exciters as exc


@kernel
def sub_state_mask(p, n_state):
    """Which slots of the flat state (n_state,) are states of exciters integrated in
    sub-intervals (KernelParams p, its ``exc_hmax``), bool (n_state,)."""
    mask = np.zeros(n_state, np.bool_)
    xe = _exciter_states(p, mask)
    for i in range(p.n_exc):
        if p.exc_hmax[i] < np.inf:
            xe[:, i] = True
    return mask


@kernel(inline="always")
def _exciter_states(p, x):
    """The exciters' block of the flat state x as (exc_rows, n_exc) (a view)."""
    o, ne = 6 * p.n_mac, p.n_exc
    return x[o : o + p.exc_rows * ne].reshape(p.exc_rows, ne)


@kernel
def _advance(p, x_a, u, hh, out):
    """Every sub-stepped exciter's states over hh from x_a with the inputs u (n_exc,
    N_FROZEN) held, into out's exciter block (other slots untouched)."""
    p, x_a, u, out = borrowed((p, x_a, u, out))
    xe, oe = _exciter_states(p, x_a), _exciter_states(p, out)
    work = exc.frozen_work(p.EP.shape[1], xe.shape[0])
    for i in range(p.n_exc):
        if p.exc_hmax[i] < np.inf:
            n = max(1, math.ceil(hh / p.exc_hmax[i] - 1e-9))
            exc.advance_frozen(p.EP, xe, i, u[i], hh, n, p.ieee, p.reach, oe[:, i], work)


@kernel
def sub_heun_start(p, x_a, u_now, u_a, phi_a, hh, xp):
    """Before the predictor's evaluation of a Heun step over hh from x_a: keep the inputs
    of the evaluation at x_a (u_now, copied into u_a), integrate the sub-stepped exciters
    with them (Phi(x_a, u_a) into phi_a) and set the predictor xp's exciter states to it
    (V_ref, which a stage may step, is among the inputs)."""
    p, x_a, u_now, u_a, phi_a, xp = borrowed((p, x_a, u_now, u_a, phi_a, xp))
    assign(u_a, u_now)
    _advance(p, x_a, u_a, hh, phi_a)
    xe, pe = _exciter_states(p, xp), _exciter_states(p, phi_a)
    for i in range(p.n_exc):
        if p.exc_hmax[i] < np.inf:
            for r in range(p.exc_rows):
                xe[r, i] = pe[r, i]


@kernel
def sub_heun_end(p, x_a, u_p, phi_a, phi_p, hh, x_new):
    """After the predictor's evaluation (its inputs u_p): the sub-stepped exciters' states
    at the step's end, (Phi(x_a, u_a) + Phi(x_a, u_p)) / 2, into x_new."""
    p, x_a, u_p, phi_a, phi_p, x_new = borrowed((p, x_a, u_p, phi_a, phi_p, x_new))
    _advance(p, x_a, u_p, hh, phi_p)
    xe, pa, pp = _exciter_states(p, x_new), _exciter_states(p, phi_a), _exciter_states(p, phi_p)
    for i in range(p.n_exc):
        if p.exc_hmax[i] < np.inf:
            for r in range(p.exc_rows):
                xe[r, i] = 0.5 * (pa[r, i] + pp[r, i])
