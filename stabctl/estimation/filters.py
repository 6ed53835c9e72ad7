"""Kalman-filter estimation of machine speeds and of the centre-of-inertia (COI) speed from
PMU frames (`stabctl.estimation.pmu`), frame by frame, for the ESD controllers (paper Table 3).

Estimators, one filter per machine, all machines advanced together (docs/estimation.md):

- `FrequencyKF`, baseline: linear Kalman filter on the PMU frequency and ROCOF of the
  machine's bus; state [f - f0 (Hz), df/dt (Hz/s)], the ROCOF a random walk.  The speed
  estimate is 1 + (f - f0)/f0, i.e. the bus frequency is taken for the rotor speed; its
  forecast over the latency holds it (the bus ROCOF is not extrapolated).
- `SwingEKF`, model-based: extended Kalman filter on the swing equation of PSTess's machine
  models (docs/pst_models.md 1.6-1.9) driven by the measured electrical power; state
  [delta (rad), w = omega - 1 (pu), dPm (pu machine base), q1, q2 (q-axis rotor fluxes,
  pu)].  Over a frame interval dt, with the air-gap power P_ag = P + r_a |I|^2 (machine
  base, from the PMU phasors) and the mechanical power P_m of the turbine-governor model
  (PST tg, started in equilibrium at the first measured P_ag, driven by the estimated
  speed), both averaged over the interval's ends (trapezoid):
      a = ((P_m + dPm - P_ag) / omega - D w) / 2H     (subtransient; transient and
                                                        classical machines without 1/omega;
                                                        PSS/E's ((P_m + dPm - D w) / omega -
                                                        P_ag) / 2H, `swing_acceleration`)
      w' = w + dt a,   delta' = delta + omega_b dt (w + dt a / 2),   dPm' = dPm,
      q' = A_d q + b_d (I_q(delta, I) + I_q(delta', I')) / 2
  (A_d, b_d: exact zero-order-hold discretisation of the machine's linear q-axis circuits,
  I_q = Re(exp(-j delta) I) the q-axis current, machine base).  Measurement: the angle of
  the internal voltage E = V + Z I computed from the PMU phasors (Z = r_a + j x"_d,
  subtransient; r_a + j x'_d otherwise; plus the step-up branch for a PMU at the HV bus),
  h(x) = delta + asin(omega psi"_q / |E|) with psi"_q = c.q the q-axis subtransient flux
  (transient machines: delta - asin(E'_d / |E|); classical: delta).  The bus frequency is
  not used: during swings it differs from the rotor speed by tens of mHz.

The machines' models and the filters' tunings are in `stabctl.estimation.models`.  The
one-machine equations (`swing_*`) are compiled (numba) and shared by two paths:
`FrequencyKF` and `SwingEKF` run the Kalman algebra (Joseph form, as filterpy) in one
compiled loop over the machines, the fast path; their references in
`stabctl.estimation.reference` run one filterpy filter per machine (filterpy does the
algebra; tests check that both agree to rounding; `benchmarks/bench_estimator.py`).
Sources: filterpy 1.4 `KalmanFilter`, `ExtendedKalmanFilter`; IEEE C37.118.1-2011 for the
PMU noise (`stabctl.estimation.pmu`).

Online interface: `step(frame) -> (speed, variance)`, speed (n_mac,) pu, variance pu^2,
NaN until a machine's first valid frame; frames in increasing time-stamp order; where a
frame was dropped the filter predicts only.  `nis` holds the normalised innovation squared
of the last step (NaN where no update), chi-square with `dof` degrees of freedom when the
filter is consistent (`nis_bounds`).  `stabctl.estimation.models.coi_speed` and
`relative_speeds` turn the machine estimates into what each ESD controller needs (paper
eq. 40), with variances.
"""

from __future__ import annotations

import cmath
import math
from collections import namedtuple
from typing import NamedTuple

import numpy as np
from scipy.stats import chi2

from stabctl._jit.arrays import assign
from stabctl._jit.decorators import kernel, njit
from stabctl.errors import InputError
from stabctl.estimation.models import FrequencyTuning, MachineModels, SwingTuning
from stabctl.estimation.pmu import Frame
from stabctl.estimation.settings import PMUSettings, check_rate, nominal_rate
from stabctl.models.declaration import layout
from stabctl.models.machines import EM, SUB, TRA
from stabctl.models.machines import _dq as rotor_dq  # the one compiled dq transform


def nis_bounds(dof: int, coverage: float = 0.95) -> tuple[float, float]:
    """Two-sided chi-square interval holding `coverage` of a consistent filter's NIS."""
    a = (1 - coverage) / 2
    return float(chi2.ppf(a, dof)), float(chi2.ppf(1 - a, dof))


# -- packed parameters for the compiled kernels ----------------------------------------------
NG = 3  # states of a PST tg turbine-governor (`Governors`): the width of its blocks

#: The row of one machine in the packed parameters: (name, width, value from the
#: `MachineModels` m, shape (n,) or (n, width)) per block of columns, in order.
_MACHINE_ROW = (
    ("H", 1, lambda m: m.H),
    ("D", 1, lambda m: m.D),
    ("POT", 1, lambda m: m.pot),
    ("RA", 1, lambda m: m.ra),
    ("ZRE", 1, lambda m: m.z_emf.real),
    ("ZIM", 1, lambda m: m.z_emf.imag),
    ("PERSPEED", 1, lambda m: m.per_speed),
    ("SWING", 1, lambda m: m.psse_swing),
    ("QC1", 1, lambda m: m.qaxis.c[:, 0]),
    ("QC2", 1, lambda m: m.qaxis.c[:, 1]),
    ("QSIGN", 1, lambda m: m.qaxis.sign),
    ("QSPEED", 1, lambda m: m.qaxis.speed),
    ("KIND", 1, lambda m: m.qaxis.kind),
    ("XL", 1, lambda m: m.qaxis.xl),
    ("XQ", 1, lambda m: m.qaxis.xq),
    ("XQP", 1, lambda m: m.qaxis.xqp),
    ("XDP", 1, lambda m: m.qaxis.xdp),
    ("GACT", 1, lambda m: m.governor.active),
    ("WF", 1, lambda m: m.governor.wf),
    ("INVR", 1, lambda m: m.governor.invR),
    ("TMAX", 1, lambda m: m.governor.Tmax),
    ("GC", NG, lambda m: m.governor.c),  # P_m = c.g
    ("GU", NG, lambda m: m.governor.g_unit),  # g in equilibrium at P_m = 1
)
#: First column of each block of `_MACHINE_ROW` (``pr[C.POT]``, ``pr[C.GC:C.GC + NG]``);
#: module-global, so a compile-time constant to numba (as `stabctl.models.declaration.layout`).
C = namedtuple("MachineColumns", [name for name, _, _ in _MACHINE_ROW])(
    *(sum(width for _, width, _ in _MACHINE_ROW[:j]) for j in range(len(_MACHINE_ROW)))
)

#: The tuning vector: (name, attribute of the `SwingTuning` or one of the values
#: `_tuning_vector` computes) per entry, ``tv[T.F0]``.
_TUNING = (
    ("ANGLE", "angle_model_rad"),
    ("ACCEL", "accel_psd"),
    ("PMWALK", "pm_walk"),
    ("PM0", "pm0_sd"),
    ("FLUX0", "flux0_sd"),
    ("JUMP", "jump_pu"),
    ("SIG2", "sigma_phasor2"),
    ("SIGF", "sigma_freq"),
    ("F0", "f0"),
)
T = layout("SwingTuningColumns", _TUNING)

#: Held values per machine, ``hold[k, H.PAG]``: (name, meaning) per column.
H = layout(
    "HeldColumns",
    (
        ("PAG", "P_ag at the previous frame, measured or held (pu machine base)"),
        ("PAGVAR", "its variance"),
        ("DPAG", "its last measured change between frames"),
        ("IQVAR", "the variance of I_q"),
        ("PM0", "P_m at the start"),
    ),
)


class Held(NamedTuple):
    """What the swing filter holds per machine between frames (changed in place by the
    kernels): hold (n, len(H)) the values named by `H`; cur (n,) the last valid current
    phasor (complex pu, system base); g (n, NG) the governor states."""

    hold: np.ndarray
    cur: np.ndarray
    g: np.ndarray


class MachineFrame(NamedTuple):
    """One frame as the swing filter's machines see it, arrays (n,): v, i the voltage and
    current phasors of each machine's PMU (complex pu, system base), freq its frequency
    (Hz), valid whether all three were received and finite."""

    v: np.ndarray
    i: np.ndarray
    freq: np.ndarray
    valid: np.ndarray


class Discrete(NamedTuple):
    """The machines' linear systems discretised over one frame interval
    (`LinearSystems.discrete`): q-axis circuits Adq (n, 2, 2), bdq (n, 2); governors
    Adg (n, NG, NG), bdg (n, NG)."""

    Adq: np.ndarray
    bdq: np.ndarray
    Adg: np.ndarray
    bdg: np.ndarray


def _packed(m: MachineModels) -> np.ndarray:
    """Parameter matrix of the swing filter's compiled kernels, one `_MACHINE_ROW` per
    machine: (n, number of columns), columns named by `C`."""
    P = np.zeros((m.n, sum(width for _, width, _ in _MACHINE_ROW)))
    for (_, width, value), start in zip(_MACHINE_ROW, C):
        P[:, start : start + width] = np.reshape(value(m), (m.n, width))
    return P


def _tuning_vector(tun: SwingTuning, s: PMUSettings, f0: float) -> np.ndarray:
    """Tuning and PMU noise of the swing filter's compiled kernels, (len(T),), entries
    named by `T`: `_TUNING`'s attributes of `tun`, the PMU phasor noise variance
    sigma_phasor^2, the frequency noise sigma_freq (Hz) and f0 (Hz)."""
    values = {"sigma_phasor2": s.sigma_phasor**2, "sigma_freq": s.sigma_freq, "f0": f0}
    return np.array(
        [values[attr] if attr in values else getattr(tun, attr) for _, attr in _TUNING], float
    )


# -- swing filter equations, one machine (shared by the compiled and the filterpy paths) ---
@kernel
def wrap_angle(a):
    """Angle wrapped to [-pi, pi)."""
    return (a + math.pi) % (2 * math.pi) - math.pi


@kernel
def swing_measure(v, i, pr, sig2):
    """One machine's measurement quantities from its PMU phasors v, i (complex pu, system
    base): (theta, |E|, P_ag, var P_ag, var I_q, var theta) with E = V + Z I.

    To first order in the relative phasor errors (std s, sig2 = s^2, per component): angle
    of E: s^2 (|V|^2 + |Z I|^2) / |E|^2; P = Re(V conj I): 2 s^2 |S|^2; I_q: s^2 |I|^2
    (machine base, pot^2 |I|^2)."""
    pot = pr[C.POT]
    zi = complex(pr[C.ZRE], pr[C.ZIM]) * i
    e = v + zi
    S = v * np.conj(i)
    ia2 = (abs(i) * pot) ** 2
    emag = abs(e)
    return (
        math.atan2(e.imag, e.real),
        emag,
        pot * S.real + pr[C.RA] * ia2,
        2 * sig2 * (pot * abs(S)) ** 2,
        sig2 * ia2,
        sig2 * (abs(v) ** 2 + abs(zi) ** 2) / emag**2,
    )


@kernel
def swing_start(v, i, freq, r, pr, tv):
    """Initial state (5,) and covariance (5, 5) of one machine: steady state as PST's
    initialisation (docs/pst_models.md 1.7), speed from the bus frequency."""
    i_m = i * pr[C.POT]
    kind = int(pr[C.KIND])
    if kind == EM:
        delta = cmath.phase(v + 1j * pr[C.XDP] * i_m)
    else:
        delta = cmath.phase(v + complex(pr[C.RA], pr[C.XQ]) * i_m)
    curd, curq = rotor_dq(delta, i_m)
    edra = -rotor_dq(delta, v)[0] - pr[C.RA] * curd
    x = np.zeros(5)
    x[0], x[1] = delta, freq / tv[T.F0] - 1.0
    if kind == SUB:
        x[3], x[4] = edra + pr[C.XQP] * curq, edra + pr[C.XL] * curq
    elif kind == TRA:
        x[3] = rotor_dq(delta, v + complex(pr[C.RA], pr[C.XDP]) * i_m)[0]
    P = np.zeros((5, 5))
    P[0, 0] = r + tv[T.ANGLE] ** 2
    P[1, 1] = (tv[T.SIGF] / tv[T.F0]) ** 2
    P[2, 2] = tv[T.PM0] ** 2
    P[3, 3] = P[4, 4] = tv[T.FLUX0] ** 2
    return x, P


@kernel
def swing_begin(k, frame, pag, pag_var, iq_var, r, pr, tv, held):
    """Start machine k at its first valid frame (`MachineFrame`; its measured P_ag, the
    variances and r as `swing_measure` gives them): initial state and covariance
    (`swing_start`); its `Held` values (in place) with P_m = P_ag and the governor in
    equilibrium."""
    hold, cur_hold, g = held
    hold[k, H.PAG], hold[k, H.PAGVAR], hold[k, H.DPAG], hold[k, H.IQVAR], hold[k, H.PM0] = (
        pag,
        pag_var,
        0.0,
        iq_var,
        pag,
    )
    cur_hold[k] = frame.i[k]
    assign(g[k], pr[C.GU : C.GU + NG] * pag)
    return swing_start(frame.v[k], frame.i[k], frame.freq[k], r, pr, tv)


@kernel
def swing_inputs(k, frame, pag, pag_var, iq_var, held, w, pr, disc, tv):
    """Inputs of machine k over one interval ending at `frame` (`MachineFrame`; P_ag and
    the variances as `swing_measure` gives them when the frame is valid): (mean P_m, mean
    P_ag, variance of the mean P_ag, current at both ends, variance of I_q).

    Advances its governor (`Discrete` disc; demand from the estimated speed 1 + w, P_ref
    such that the start was an equilibrium at nominal speed) and its `Held` values (in
    place).  For a dropped frame the last P_ag and current are held and the variance of
    P_ag grows by the square of its last change between frames dP; a change of a measured
    P_ag above jump_pu adds dP^2 / 12 (event at an unknown instant)."""
    hold, cur_hold, g = held
    pm0 = hold[k, H.PM0]
    pm_before, pm_after = pm0, pm0
    if pr[C.GACT] > 0:
        pm_before = _dot(g[k], pr[C.GC : C.GC + NG])
        u = pm0 - (pr[C.WF] - 1.0) * pr[C.INVR] + (pr[C.WF] - 1.0 - w) * pr[C.INVR]
        assign(g[k], _mv(disc.Adg[k], g[k]) + disc.bdg[k] * min(max(u, 0.0), pr[C.TMAX]))
        pm_after = _dot(g[k], pr[C.GC : C.GC + NG])
    p0, v0, cur0, iq0 = hold[k, H.PAG], hold[k, H.PAGVAR], cur_hold[k], hold[k, H.IQVAR]
    if frame.valid[k]:
        dp = pag - p0
        var = 0.25 * (v0 + pag_var) + (dp * dp / 12 if abs(dp) > tv[T.JUMP] else 0.0)
        hold[k, H.DPAG], hold[k, H.IQVAR], cur_hold[k] = dp, iq_var, frame.i[k]
    else:
        pag, pag_var = p0, v0 + hold[k, H.DPAG] ** 2
        var = 0.25 * (v0 + pag_var)
    hold[k, H.PAG], hold[k, H.PAGVAR] = pag, pag_var
    return (
        0.5 * (pm_before + pm_after),
        0.5 * (p0 + pag),
        var,
        cur0,
        cur_hold[k],
        0.5 * (iq0 + hold[k, H.IQVAR]),
    )


@kernel
def swing_transition(x, pm, pag, cur0, cur1, dt, pr, Adq, bdq, f0):
    """Propagated state (5,), Jacobian F (5, 5) and sensitivity g (5,) to the mean P_ag
    of one machine over dt (module docstring)."""
    d, w, p = x[0], x[1], x[2]
    wb = 2 * math.pi * f0
    acc, c, cg, da_dw = swing_acceleration(
        pm + p, pag, w, pr[C.H], pr[C.D], pr[C.PERSPEED], pr[C.SWING]
    )
    d1 = d + wb * dt * (w + 0.5 * dt * acc)
    r0 = cmath.exp(-1j * d) * cur0 * pr[C.POT]
    r1 = cmath.exp(-1j * d1) * cur1 * pr[C.POT]
    iq = 0.5 * (r0.real + r1.real)
    xn = np.empty(5)
    xn[0], xn[1], xn[2] = d1, w + dt * acc, p
    assign(xn[3:], _mv(Adq, x[3:]) + bdq * iq)
    F = np.zeros((5, 5))
    F[0, 0] = F[2, 2] = 1.0
    F[0, 1] = wb * dt * (1 + 0.5 * dt * da_dw)
    F[0, 2] = wb * dt * 0.5 * dt * c
    F[1, 1] = 1 + dt * da_dw
    F[1, 2] = dt * c
    assign(F[3:, 3:], Adq)
    for j in range(3):  # I_q(delta') depends on (delta, w, dPm)
        dIq = 0.5 * r1.imag * F[0, j] + (0.5 * r0.imag if j == 0 else 0.0)
        F[3, j], F[4, j] = bdq[0] * dIq, bdq[1] * dIq
    g = np.zeros(5)
    g[0], g[1] = -wb * 0.5 * dt * dt * cg, -dt * cg
    return xn, F, g


@kernel
def swing_acceleration(pn, pag, w, H, D, per_speed, psse):
    """Rotor acceleration a = d omega/dt (pu/s) of the swing equation the simulator solves
    for the machine (`stabctl.models.machines`), from the mechanical power pn = P_m + dPm
    and the air-gap power pag (pu machine base) at speed deviation w (pu):

    - PST (per_speed 1, subtransient with speed effects): a = ((pn - pag)/omega - D w)/2H;
    - PSS/E (psse 1, mac_con psse_swing): a = ((pn - D w)/omega - pag)/2H (the stator at
      rated speed: the air-gap power is the torque);
    - otherwise: a = (pn - pag - D w)/2H.

    Arithmetic only: also evaluated on arrays (``swing_acceleration.py_func``).  Returns
    (a, da/dpn, -da/dpag, da/dw)."""
    speed = per_speed + psse - per_speed * psse  # 1 where the torque is a power / omega
    omega = 1.0 + w * speed
    cp = 1.0 / (2 * H * omega)
    cg = (1.0 - psse) * cp + psse / (2 * H)
    net = pn - psse * D * w - (1.0 - psse) * pag
    acc = cp * net - psse * pag / (2 * H) - (1.0 - psse) * D * w / (2 * H)
    da_dw = -(1.0 - psse) * D / (2 * H) - psse * D * cp - speed * cp * net / omega
    return acc, cp, cg, da_dw


@kernel
def swing_Q(g, pag_var, iq_var, bdq, dt, tv):
    """Process noise (5, 5) of one machine: measured-power noise through g, I_q noise
    through b_d, white unmodelled acceleration on (delta, w), random walk of dPm."""
    wb = 2 * math.pi * tv[T.F0]
    Q = np.zeros((5, 5))
    for a in range(5):
        for b in range(5):
            Q[a, b] = g[a] * g[b] * pag_var
    for a in range(2):
        for b in range(2):
            Q[3 + a, 3 + b] += bdq[a] * bdq[b] * iq_var
    q = tv[T.ACCEL]
    Q[0, 0] += q * wb * wb * dt**3 / 3
    Q[0, 1] += q * wb * dt * dt / 2
    Q[1, 0] += q * wb * dt * dt / 2
    Q[1, 1] += q * dt
    Q[2, 2] += tv[T.PMWALK] * dt
    return Q


@kernel
def swing_h(x, emag, pr):
    """Predicted internal-voltage angle of one machine and its Jacobian Hj (5,) (named so
    as not to hide the layout `H` of the held values)."""
    omega = 1.0 + x[1] if pr[C.QSPEED] > 0 else 1.0
    psi = pr[C.QC1] * x[3] + pr[C.QC2] * x[4]
    s = min(max(omega * psi / emag, -0.99), 0.99)
    k = pr[C.QSIGN] / (emag * math.sqrt(1 - s * s))
    Hj = np.zeros(5)
    Hj[0] = 1.0
    if pr[C.QSPEED] > 0:
        Hj[1] = k * psi
    Hj[3], Hj[4] = k * omega * pr[C.QC1], k * omega * pr[C.QC2]
    return x[0] + pr[C.QSIGN] * math.asin(s), Hj


# -- compiled filters, all machines ---------------------------------------------------------
@kernel
def _dot(a, b):
    acc = 0.0
    for j in range(a.size):
        acc += a[j] * b[j]
    return acc


@kernel
def _mv(A, x):
    """A x for small matrices (explicit loops: BLAS calls cost more at this size)."""
    y = np.zeros(A.shape[0])
    for a in range(A.shape[0]):
        for b in range(A.shape[1]):
            y[a] += A[a, b] * x[b]
    return y


@kernel
def _mm(A, B):
    C = np.zeros((A.shape[0], B.shape[1]))
    for a in range(A.shape[0]):
        for b in range(B.shape[1]):
            for c in range(A.shape[1]):
                C[a, b] += A[a, c] * B[c, b]
    return C


@kernel
def _inv2(S):
    """Inverse of a 2 x 2 matrix."""
    det = S[0, 0] * S[1, 1] - S[0, 1] * S[1, 0]
    out = np.empty((2, 2))
    out[0, 0], out[0, 1], out[1, 0], out[1, 1] = (
        S[1, 1] / det,
        -S[0, 1] / det,
        -S[1, 0] / det,
        S[0, 0] / det,
    )
    return out


@kernel
def _sandwich(F, P):
    """F P F' for small square matrices."""
    n = F.shape[0]
    FP = np.zeros((n, n))
    for a in range(n):
        for b in range(n):
            acc = 0.0
            for c in range(n):
                acc += F[a, c] * P[c, b]
            FP[a, b] = acc
    out = np.zeros((n, n))
    for a in range(n):
        for b in range(n):
            acc = 0.0
            for c in range(n):
                acc += FP[a, c] * F[b, c]
            out[a, b] = acc
    return out


@kernel
def _scalar_update(x, P, y, H, R):
    """Kalman update with one measurement (filterpy's equations, Joseph form); returns
    x, P and the NIS y^2 / S."""
    n = x.size
    PHt = _mv(P, H)
    S = _dot(H, PHt) + R
    K = PHt / S
    IKH = np.zeros((n, n))
    for a in range(n):
        IKH[a, a] = 1.0
        for b in range(n):
            IKH[a, b] -= K[a] * H[b]
    P1 = _sandwich(IKH, P)
    for a in range(n):
        for b in range(n):
            P1[a, b] += R * K[a] * K[b]
    return x + K * y, P1, y * y / S


@kernel
def _store(x, P, k, xk, Pk):
    """x[k], P[k] = xk, Pk (`stabctl._jit.arrays.assign`)."""
    assign(x[k], xk)
    assign(P[k], Pk)


@njit(cache=True)
def _swing_batch(x, P, nis, ready, held, frame, dt, par, disc, tv):
    """One frame of the swing filter for every machine (in place): predict the machines
    already started over dt (`Discrete` disc), update those with a valid frame
    (`MachineFrame`), start the others; x (n, 5), P (n, 5, 5), nis (n,), ready (n,),
    `Held` held, par the `_packed` rows (n, columns named by `C`), tv (len(T),)."""
    for k in range(x.shape[0]):
        nis[k] = np.nan
        pr = par[k]
        valid = frame.valid[k]
        if not (ready[k] or valid):
            continue
        theta = emag = pag = pag_var = iq_var = r = np.nan
        if valid:
            theta, emag, pag, pag_var, iq_var, r = swing_measure(
                frame.v[k], frame.i[k], pr, tv[T.SIG2]
            )
        if not ready[k]:
            _store(x, P, k, *swing_begin(k, frame, pag, pag_var, iq_var, r, pr, tv, held))
            ready[k] = True
            continue
        pm, pbar, pvar, c0, c1, iqv = swing_inputs(
            k, frame, pag, pag_var, iq_var, held, x[k, 1], pr, disc, tv
        )
        xn, F, gs = swing_transition(
            x[k], pm, pbar, c0, c1, dt, pr, disc.Adq[k], disc.bdq[k], tv[T.F0]
        )
        Pp = _sandwich(F, P[k]) + swing_Q(gs, pvar, iqv, disc.bdq[k], dt, tv)
        if valid:
            h, Hj = swing_h(xn, emag, pr)
            xu, Pu, nis[k] = _scalar_update(xn, Pp, wrap_angle(theta - h), Hj, r + tv[T.ANGLE] ** 2)
            _store(x, P, k, xu, Pu)
        else:
            _store(x, P, k, xn, Pp)


@njit(cache=True)
def _freq_batch(x, P, nis, ready, z, valid, dt, q, R):
    """One frame of the baseline filter for every machine (in place); z (n, 2) =
    [f - f0, ROCOF], R (2, 2)."""
    F, Q = np.zeros((2, 2)), np.empty((2, 2))
    F[0, 0], F[0, 1], F[1, 1] = 1.0, dt, 1.0
    Q[0, 0], Q[0, 1], Q[1, 0], Q[1, 1] = q * dt**3 / 3, q * dt**2 / 2, q * dt**2 / 2, q * dt
    for k in range(x.shape[0]):
        nis[k] = np.nan
        if not ready[k]:
            if valid[k]:
                _store(x, P, k, z[k], R)
                ready[k] = True
            continue
        xn, Pp = _mv(F, x[k]), _sandwich(F, P[k]) + Q
        if not valid[k]:
            _store(x, P, k, xn, Pp)
            continue
        y = z[k] - xn
        SI = _inv2(Pp + R)
        nis[k] = _dot(y, _mv(SI, y))
        K = _mm(Pp, SI)
        IK = -K
        IK[0, 0] += 1.0
        IK[1, 1] += 1.0
        _store(x, P, k, xn + _mv(K, y), _sandwich(IK, Pp) + _sandwich(K, R))


# -- filters --------------------------------------------------------------------------------
class _MachineFilters:
    """Frame bookkeeping shared by the estimators: frames in increasing time-stamp order,
    each machine starting at its first valid frame.  Subclasses implement
    `_advance(frame, dt)`, `_output()` and `_rate()` (or their own `forecast`); x, P are
    the states and covariances."""

    dof = 1

    def __init__(self, n: int, nx: int):
        self.t: float | None = None
        self.ready = np.zeros(n, bool)
        self.nis = np.full(n, np.nan)
        self.x, self.P = np.full((n, nx), np.nan), np.full((n, nx, nx), np.nan)

    def step(self, frame: Frame) -> tuple[np.ndarray, np.ndarray]:
        """Advance to the frame's time stamp and use its valid measurements.

        Returns the speed estimates (n,) pu and their variances (n,) pu^2 (NaN before a
        machine's first valid frame).  Raises InputError for a time stamp not after the
        previous one.
        """
        if self.t is not None and not frame.t > self.t:
            raise InputError(
                f"frame at t = {frame.t} s is not after the previous one "
                f"({self.t} s): frames must come in time-stamp order"
            )
        self._advance(frame, 0.0 if self.t is None else frame.t - self.t)
        self.t = frame.t
        return self._output()

    def forget(self, which: np.ndarray) -> None:
        """Start the machines `which` ((n,) bool) again, as before their first valid
        frame: each starts anew at its next valid frame (a machine without a usable value
        for longer than a gap is predicted across, `LoopController.act`).

        Parameters
        ----------
        which : numpy.ndarray of bool, shape (n,)
            The machines to start again.
        """
        self.ready[which] = False
        self.nis[which] = np.nan
        self.x[which], self.P[which] = np.nan, np.nan

    def forecast(self, horizon: float) -> tuple[np.ndarray, np.ndarray]:
        """Speed estimates (n,) pu and variances (n,) pu^2 `horizon` s after the last
        frame's time stamp, without changing the filter (e.g. to the instant a controller
        acts, latency included): the last rate of change of speed held."""
        speed, var = self._output()
        rate, rate_var, cov = self._rate()
        return speed + horizon * rate, var + 2 * horizon * cov + horizon**2 * rate_var


#: Hz: a first frame whose valid frequencies are, as a median, farther than this from a
#: FrequencyKF's f0 is not of its system (a 50 Hz system's read as 60 Hz); later frames
#: are not judged, as a fault's phase jumps swing a P-class estimate by more
F0_OFF_HZ = 5.0


class FrequencyKF(_MachineFilters):
    """Baseline filter on PMU frequency and ROCOF (compiled, all machines).

    pmu: (n,) index of each machine's PMU in the frames; settings: the PMUs' (noise);
    tuning: `FrequencyTuning`; f0: nominal frequency (Hz), the case's (`machine_models`
    gives it: ``models.f0``).

    Raises
    ------
    InputError
        The settings' rate is not a rate of f0 (`check_rate`); later, in `step`, a first
        frame whose valid frequencies are, as a median, more than `F0_OFF_HZ` from f0 (a
        50 Hz system's frames read with the default f0 of 60 Hz gave speeds of 0.84 pu).
    """

    name = "kf"
    dof = 2

    def __init__(
        self,
        pmu,
        settings: PMUSettings,
        tuning: FrequencyTuning = FrequencyTuning(),
        f0: float = 60.0,
    ):
        check_rate(settings.rate, f0, fix=f"give FrequencyKF the case's f0 (not {f0:g}), or {{}}")
        self.pmu, self.tun, self.f0 = np.asarray(pmu), tuning, f0
        super().__init__(self.pmu.size, 2)
        self.R = np.diag([settings.sigma_freq**2, settings.sigma_rocof**2])

    def _measure(self, frame: Frame):
        """z (n, 2) = [f - f0 (Hz), ROCOF (Hz/s)] and the valid mask (n,)."""
        z = np.stack([frame.freq[self.pmu] - self.f0, frame.rocof[self.pmu]], axis=1)
        ok = frame.valid[self.pmu] & np.isfinite(z).all(axis=1)
        if self.t is None and ok.any() and abs(np.median(z[ok, 0])) > F0_OFF_HZ:
            raise InputError(
                f"FrequencyKF(f0={self.f0:g}): the frame at t = {frame.t} s reads "
                f"{self.f0 + np.median(z[ok, 0]):.4g} Hz (median of its valid PMUs), not near "
                f"f0: give the case's nominal frequency as f0 (machine_models(case).f0)"
            )
        return z, ok

    def _advance(self, frame, dt):
        z, ok = self._measure(frame)
        _freq_batch(self.x, self.P, self.nis, self.ready, z, ok, dt, self.tun.rocof_walk, self.R)

    def _output(self):
        return 1.0 + self.x[:, 0] / self.f0, self.P[:, 0, 0] / self.f0**2

    def forecast(self, horizon: float) -> tuple[np.ndarray, np.ndarray]:
        """The filtered frequency as the speed `horizon` s ahead, held, not extrapolated
        with the ROCOF state: every ESD switching steps the bus angle, the PMU's ROCOF
        then swings +-dtheta / (2 pi w^2) (w its window), and extrapolating that over the
        latency fed the steps back into the commands (docs/estimation.md 2.1).  Variance:
        the filter's plus horizon^2 times that of the ROCOF (the unextrapolated change)."""
        speed, var = self._output()
        return speed, var + horizon**2 * self.P[:, 1, 1] / self.f0**2


class SwingEKF(_MachineFilters):
    """Model-based filter on the swing equation (compiled, all machines).

    models: `MachineModels` (`machine_models`); settings: the PMUs'; tuning: `SwingTuning`.
    """

    name = "ekf"

    def __init__(
        self, models: MachineModels, settings: PMUSettings, tuning: SwingTuning = SwingTuning()
    ):
        self.m = models
        super().__init__(models.n, 5)
        self.par, self.tv = _packed(models), _tuning_vector(tuning, settings, models.f0)
        self.held = Held(
            np.full((models.n, len(H)), np.nan),
            np.full(models.n, np.nan + 0j),
            np.zeros((models.n, NG)),
        )

    def forget(self, which: np.ndarray) -> None:
        """As `_MachineFilters.forget`, the values held between frames of those machines
        cleared too (`Held`).

        Parameters
        ----------
        which : numpy.ndarray of bool, shape (n,)
            The machines to start again.
        """
        super().forget(which)
        self.held.hold[which], self.held.cur[which], self.held.g[which] = np.nan, np.nan, 0.0

    def _frame(self, frame: Frame) -> MachineFrame:
        """This filter's machines' voltage, current, frequency and valid mask."""
        p = self.m.pmu
        v, i, f = frame.v[p], frame.i[p], frame.freq[p]
        return MachineFrame(
            v, i, f, frame.valid[p] & np.isfinite(v) & np.isfinite(i) & np.isfinite(f)
        )

    def _discrete(self, dt) -> Discrete:
        return Discrete(*self.m.qaxis.sys.discrete(dt), *self.m.governor.sys.discrete(dt))

    def _advance(self, frame, dt):
        _swing_batch(
            self.x,
            self.P,
            self.nis,
            self.ready,
            self.held,
            self._frame(frame),
            dt,
            self.par,
            self._discrete(dt),
            self.tv,
        )

    def _output(self):
        return 1.0 + self.x[:, 1], self.P[:, 1, 1]

    def _rate(self):
        """Acceleration (pu/s) from the swing equation at the last frame's powers, its
        variance (from those of dPm and P_ag) and its covariance with the speed."""
        m, w = self.m, self.x[:, 1]
        gov = m.governor
        hold = self.held.hold
        pm = np.where(gov.active, gov.output(self.held.g), hold[:, H.PM0])
        acc, c, cg, _ = swing_acceleration.py_func(
            pm + self.x[:, 2], hold[:, H.PAG], w, m.H, m.D, m.per_speed, m.psse_swing
        )
        return acc, c**2 * self.P[:, 2, 2] + cg**2 * hold[:, H.PAGVAR], c * self.P[:, 1, 2]


def compile_filters(models: MachineModels) -> None:
    """Compile the kernels of `FrequencyKF` and `SwingEKF` now, or load them from the
    on-disk cache: each filter of these machines takes one frame with every measurement
    lost (the types of a real run; nothing is estimated).  A study calls this before its
    first simulation, so that on a cold cache they compile here while the simulator's
    integrator compiles in a child process (`stabctl.dynamics.driver.Simulator`),
    instead of after it.

    Parameters
    ----------
    models : MachineModels
        As `machine_models` gives them.
    """
    n_pmu = int(models.pmu.max()) + 1
    lost = Frame(
        0.0,
        np.zeros(n_pmu, bool),
        np.full(n_pmu, np.nan + 0j),
        np.full(n_pmu, np.nan + 0j),
        np.full(n_pmu, np.nan),
        np.full(n_pmu, np.nan),
    )
    settings = PMUSettings(rate=nominal_rate(models.f0))
    for f in (FrequencyKF(models.pmu, settings, f0=models.f0), SwingEKF(models, settings)):
        f.step(lost)
