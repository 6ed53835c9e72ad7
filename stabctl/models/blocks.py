"""Control blocks of the exciter, PSS and governor models, each written once.

Every block is a scalar kernel: it takes the block's input u, its state x (where it has
one) and its parameters, and returns its output and the state's derivative dx/dt; the
model writes the derivative into its slot.  Units are those of the caller (pu signals,
time constants in s).  A time constant below :data:`LBND` (1e-3 s) means the block is
absent: its input passes and the derivative is 0 (PST's ``*_idx`` convention, PST manual
3.11-3.30; docs/pst_models.md 2-4).  Where the models' sources spell one block with
different floating-point operations, the block keeps each spelling as a variant (a gain
argument or a `form`), so that every model computes exactly what it did.

Sources: PSTess 1.1 `smpexc.m`, `exc_dc12.m`, `exc_st3.m`, `pss.m`, `tg.m`; IEEE Std
421.5-2016 annex E (E.2 lag, E.3 lead-lag, E.4 washout, E.5 non-windup limits, E.7
windup limits) and annex D (rectifier regulation); PSS/E Model Library (the PSS/E
models' blocks); ANDES 2.0 ``andes/core/block.py`` and ``discrete.py`` (the PI/PID family
and AntiWindup of the converter models).
"""

from __future__ import annotations

import numpy as np

from stabctl._jit.decorators import kernel, njit

#: a time constant below this (s) means the block is absent
LBND = 1e-3

#: washout gain placement: K ((u - x)/T), (K (u - x))/T, (K/T) (u - x)
GAIN_AFTER, GAIN_BEFORE, GAIN_OVER_T = np.int64(0), np.int64(1), np.int64(2)


@kernel
def clip(v, lo, hi):
    """Windup limit (IEEE 421.5 E.7), also a rate limit or saturation of a signal:
    min(max(v, lo), hi) (hi wins if lo > hi)."""
    return min(max(v, lo), hi)


@kernel
def magnitude_rate(d, sign, rate):
    """A rate d of a signal bounded on its magnitude's rise (the WECC converters' Rrpwr:
    REGCA1, REGCB1, DERA1): at most rate where ``sign`` (the signal or its command) is >= 0,
    at least -rate where it is < 0; the fall of the magnitude is free."""
    return min(d, rate) if sign >= 0.0 else max(d, -rate)


@kernel
def deadband(u, lo, hi):
    """Deadband without offset (WECC's and PSS/E's ``dbd`` blocks, PowerSimulationsDynamics.jl's
    ``deadband_function``): 0 within [lo, hi], else the distance beyond the nearer edge
    (u - hi above, u - lo below)."""
    if u > hi:
        return u - hi
    if u < lo:
        return u - lo
    return 0.0


@kernel
def lag(u, x, T):
    """First-order lag 1/(1 + s T) (IEEE 421.5 E.2): output x, dx/dt = (u - x)/T;
    T < LBND: output u, derivative 0 (no state).

    Returns
    -------
    (float, float)
        Output, state derivative.
    """
    if T < LBND:
        return u, 0.0
    return x, (u - x) / T


@kernel
def leadlag(u, x, T_lead, T_lag, K=1.0):
    """Lead-lag K (1 + s T_lead)/(1 + s T_lag) in PST's realisation (pss.m, tg.m): with
    r = T_lead/T_lag the output is r K u + x and dx/dt = ((1 - r) K u - x)/T_lag, so
    that the state is the output minus its direct part; at rest x = (1 - r) K u.  The
    gain multiplies r (and 1 - r) before u, as PST's pss first lead-lag does; K = 1 is
    the plain lead-lag (bit for bit).  T_lag < LBND: output K u, derivative 0.

    Returns
    -------
    (float, float)
        Output, state derivative.
    """
    if T_lag < LBND:
        return K * u, 0.0
    r = T_lead / T_lag
    return r * K * u + x, ((1 - r) * K * u - x) / T_lag


@kernel
def leadlag_input_state(u, x, ratio, T_lag):
    """Lead-lag (1 + s T_lead)/(1 + s T_lag) in the exciters' realisation (PST
    smpexc.m, exc_dc12.m, exc_st3.m): the state is the lagged input, dx/dt = (u - x)/T_lag,
    and the output ratio u + (1 - ratio) x with ratio = T_lead/T_lag given (exc_pot
    column 5); at rest x = u (IEEE 421.5 E.3).  T_lag < LBND: output u, derivative 0.

    Returns
    -------
    (float, float)
        Output, state derivative.
    """
    if T_lag < LBND:
        return u, 0.0
    return ratio * u + (1 - ratio) * x, (u - x) / T_lag


@kernel
def leadlag2(u, x1, x2, T_lead, A1, A2):
    """Lead over a second-order lag, (1 + s T_lead)/(1 + s A1 + s^2 A2) (PSS/E DEGOV's
    electric control box and actuator; PowerSimulationsDynamics.jl's
    ``lead_lag_2nd_mass_matrix``), in controllable form: dx1/dt = x2, A2 dx2/dt = u - x1
    - A1 x2, output x1 + T_lead x2; at rest x1 = u, x2 = 0.  A2 = 0: the first-order
    lead-lag (1 + s T_lead)/(1 + s A1) with x1 the lagged input (`leadlag_input_state`;
    x2 no state, derivative 0); A1 < LBND too: output u, no state (the caller refuses a
    lead without a lag).

    Returns
    -------
    (float, float, float)
        Output, dx1/dt, dx2/dt.
    """
    if A1 < LBND:
        return u, 0.0, 0.0
    if A2 == 0.0:
        y, d1 = leadlag_input_state(u, x1, T_lead / A1, A1)
        return y, d1, 0.0
    return x1 + T_lead * x2, x2, (u - x1 - A1 * x2) / A2


@kernel
def washout(u, x, T, K, form):
    """Washout K s T/(1 + s T) (IEEE 421.5 E.4; K s/(1 + s T) with K the caller's
    gain): the state lags the input, dx/dt = (u - x)/T, and the output is the gain times
    dx/dt, computed as `form` says: GAIN_AFTER K ((u - x)/T) (PST pss, STAB2A; K = 1
    gives dx/dt itself), GAIN_BEFORE (K (u - x))/T (PSS/E IEEEST), GAIN_OVER_T (K/T)
    (u - x) (the exciters' rate feedback s K_F/(1 + s T_F)).  T must be >= LBND.

    Returns
    -------
    (float, float)
        Output, state derivative.
    """
    d = (u - x) / T
    if form == GAIN_BEFORE:
        return K * (u - x) / T, d
    if form == GAIN_OVER_T:
        return K / T * (u - x), d
    return K * d, d


@kernel
def nonwindup(x, d, lo, hi, ieee, reach):
    """Non-windup limit of a state x whose derivative is d (IEEE 421.5-2016 E.5 for a
    lag or an integrator): an outward derivative is zeroed, then the state is clamped to
    [lo, hi].

    ieee: the annex's rule, at or beyond a limit (a state held at its limit stays
    there), with `reach` (s, >= 0): a state that d drives into a limit within `reach`
    is held on it (set to the limit, derivative 0).  For a limit that moves with the
    terminal voltage (DC2) the simulator passes its step: the held state is otherwise
    left a hair inside the limit after each step, the derivative there is the full
    one, and the predictor-corrector alternates between it and zero (a false
    NumericalInstabilityError from its local error estimate).  reach = 0 is the plain
    annex E.5 limiter; as the step shrinks both converge to it.  Not ieee: PSTess's rule
    (exc_st3, exc_dc12), only beyond a limit.

    Returns
    -------
    (float, float)
        The clamped state, its derivative.
    """
    if ieee:
        if d > 0 and x + reach * d >= hi:
            x, d = hi, 0.0
        elif d < 0 and x + reach * d <= lo:
            x, d = lo, 0.0
    elif (x > hi and d > 0) or (x < lo and d < 0):
        d = 0.0
    return clip(x, lo, hi), d


@kernel
def nonwindup_lag(u, x, T, lo, hi, ieee, reach):
    """Non-windup limited lag 1/(1 + s T), limits [lo, hi] (IEEE 421.5 E.5):
    `nonwindup` of x with dx/dt = (u - x)/T; T < LBND: no lag, the input clamped to [lo,
    hi] and derivative 0 (PSTess exc_dc12 "no TA": V_R = KA V_A within its limits).

    Returns
    -------
    (float, float)
        The clamped state (the output), its derivative.
    """
    if T < LBND:
        return min(max(u, lo), hi), 0.0
    return nonwindup(x, (u - x) / T, lo, hi, ieee, reach)


@njit
def rectifier_loading(IN):
    """Rectifier regulation F_EX(I_N) of an AC exciter's output (IEEE Std 421.5-2016
    annex D, rectifier regulation): 1 for I_N <= 0, 1 - 0.577 I_N up to 0.433, sqrt(0.75
    - I_N^2) up to 0.75, 1.732 (1 - I_N) up to 1, 0 beyond (ANDES ``exac1.py`` ``FEX``).
    PST's exc_st3 spells it with 0.5771 and an initialisation quirk, kept as its own
    variant (`stabctl.models.exciters.st3._fex`) so that PSTess's results stay bit for bit.
    Callable from Python too (EXAC1's initialisation solves through it)."""
    if IN <= 0.0:
        return 1.0
    if IN <= 0.433:
        return 1.0 - 0.577 * IN
    if IN <= 0.75:
        return np.sqrt(0.75 - IN * IN)
    if IN <= 1.0:
        return 1.732 * (1.0 - IN)
    return 0.0


@kernel
def anti_windup(x, d, lo, hi):
    """Anti-windup limit of a state x whose derivative is d (ANDES 2.0 andes/core/discrete.py
    AntiWindup; the integrator of PIAWHardLimit, the lags of LagAntiWindupRate and
    LagAWFreeze): at or beyond hi with d >= 0, or at or beyond lo with d <= 0, the state is
    set to that limit and its derivative to 0; otherwise both pass (a state beyond a limit
    that d drives back inside is left where it is).  Unlike `nonwindup` the rate 0 at a
    limit also resets, and no clamp follows.

    Parameters
    ----------
    x : float
        The state.
    d : float
        Its derivative dx/dt (or any quantity of its sign: the lags pass their input error
        before the division by T).
    lo, hi : float
        The limits.

    Returns
    -------
    (float, float)
        The state (set to a limit where held), its derivative (0 where held).
    """
    if x >= hi and d >= 0.0:
        return hi, 0.0
    if x <= lo and d <= 0.0:
        return lo, 0.0
    return x, d


# -- the PI/PID family (ANDES 2.0 andes/core/block.py): the plain PI, the PI with an
# -- anti-windup integrator and a hard output limit, and the PI/PID with tracking
# -- anti-windup


@kernel
def pi(u, x, KP, KI):
    """PI K_P + K_I/s without limits (ANDES 2.0 PIController; the PLL1's PI): output K_P u +
    x, dx/dt = K_I u.

    Parameters
    ----------
    u : float
        The input (the error).
    x : float
        The integral state.
    KP, KI : float
        Proportional gain, integral gain (1/s).

    Returns
    -------
    (float, float)
        Output, the integral state's derivative.
    """
    return KP * u + x, KI * u


@kernel
def pi_aw_hard_limit(u, x, KP, KI, lo, hi):
    """PI K_P + K_I/s with an anti-windup integrator and a hard output limit (ANDES 2.0
    PIAWHardLimit, with the integrator's limits aw_lower, aw_upper equal to the output's
    lower, upper, as WTTQA1's torque PI and WTPTA1's two pitch PIs give them): dx/dt = K_I
    u through `anti_windup` on [lo, hi], output K_P u + x (the held state) clipped to [lo,
    hi].

    Parameters
    ----------
    u : float
        The input (the error).
    x : float
        The integral state.
    KP, KI : float
        Proportional gain, integral gain (1/s).
    lo, hi : float
        The limits of the integrator and of the output.

    Returns
    -------
    (float, float, float)
        Output, the integral state (set to a limit where held: the caller writes it back),
        its derivative.
    """
    x, d = anti_windup(x, KI * u, lo, hi)
    return clip(KP * u + x, lo, hi), x, d


# -- tracking anti-windup (ANDES 2.0 PITrackAW, PIDTrackAW, PITrackAWFreeze): the output
# -- is the unlimited sum ys clipped to [lo, hi], and the integrator is driven back by ks
# -- times the part of ys the limit cuts off, dx_i/dt = K_I (u - ks (ys - y)); at rest
# -- (u = 0, inside the limits) x_i is the output


@kernel
def _tracking(u, ys, KI, lo, hi, ks):
    """The tracking anti-windup of a PI/PID: (y = ys clipped to [lo, hi], dx_i/dt = K_I (u -
    ks (ys - y)))."""
    y = clip(ys, lo, hi)
    return y, KI * (u - ks * (ys - y))


@kernel
def pi_track_aw(u, x, KP, KI, lo, hi, ks):
    """PI K_P + K_I/s with tracking anti-windup (ANDES PITrackAW): ys = K_P u + x, output
    ys clipped to [lo, hi], dx/dt = K_I (u - ks (ys - y)) (ks the tracking gain; ESST4B's
    regulator and inner-loop PIs, ks = 2).

    Returns
    -------
    (float, float)
        Output, the integral state's derivative.
    """
    return _tracking(u, KP * u + x, KI, lo, hi, ks)


@kernel
def pi_nonwindup(u, x, KP, KI, lo, hi):
    """PI K_P + K_I/s with non-windup limits (IEEE 421.5-2016 E.6, as PSS/E's EXPIC1 and
    PowerSimulationsDynamics.jl's ``pi_block_nonwindup``): ys = K_P u + x, output ys
    clipped to [lo, hi]; the integral stops (dx/dt = 0) while ys is at or beyond a limit
    and u drives it further out, else dx/dt = K_I u.

    Returns
    -------
    (float, float)
        Output, the integral state's derivative.
    """
    ys = KP * u + x
    if (ys >= hi and u > 0) or (ys <= lo and u < 0):
        return clip(ys, lo, hi), 0.0
    return clip(ys, lo, hi), KI * u


@kernel
def pid_track_aw(u, xi, xd, KP, KI, KD, TD, lo, hi, ks):
    """PID K_P + K_I/s + s K_D/(1 + s T_D) with tracking anti-windup (ANDES PIDTrackAW;
    AC8B): ys = K_P u + xi + K_D (u - xd)/T_D (the derivative a washout, state xd, T_D
    dxd/dt = u - xd; absent, derivative 0, where K_D = 0 or T_D < LBND), output ys clipped
    to [lo, hi], dxi/dt = K_I (u - ks (ys - y)).

    Returns
    -------
    (float, float, float)
        Output, the integral's derivative, the derivative washout's derivative.
    """
    ys = KP * u + xi
    dxd = 0.0
    if KD != 0 and TD >= LBND:
        yd, dxd = washout(u, xd, TD, KD, GAIN_BEFORE)
        ys = ys + yd
    y, dxi = _tracking(u, ys, KI, lo, hi, ks)
    return y, dxi, dxd


@kernel
def pi_track_aw_freeze(u, x, held, KP, KI, lo, hi, ks, frz):
    """PI K_P + K_I/s with tracking anti-windup and freeze (ANDES 2.0 PITrackAWFreeze;
    REECA1's V and Q PIs, frozen in a voltage dip): unfrozen, `pi_track_aw`; frozen (frz
    true) the output held at its last unfrozen value and the integrator stopped.

    Parameters
    ----------
    u : float
        The input (the error).
    x : float
        The integral state.
    held : float
        The output before the freeze (the caller's memory slot, which it sets to the
        returned output at every call).
    KP, KI : float
        Proportional gain, integral gain (1/s).
    lo, hi : float
        The output limits.
    ks : float
        The tracking gain.
    frz : bool
        Frozen.

    Returns
    -------
    (float, float)
        Output, the integral state's derivative.
    """
    if frz:
        return held, 0.0
    return pi_track_aw(u, x, KP, KI, lo, hi, ks)
