"""Kalman-filter estimation of machine speeds and of the centre-of-inertia (COI) speed from
PMU frames (`stabctl.pmu`), frame by frame, for the ESD controllers (paper Table 3).

Estimators, one filter per machine, all machines advanced together (docs/estimation.md):

- `FrequencyKF`, baseline: linear Kalman filter on the PMU frequency and ROCOF of the
  machine's bus; state [f - f0 (Hz), df/dt (Hz/s)], the ROCOF a random walk.  The speed
  estimate is 1 + (f - f0)/f0, i.e. the bus frequency is taken for the rotor speed.
- `SwingEKF`, model-based: extended Kalman filter on the swing equation of PSTess's machine
  models (docs/pst_models.md 1.6-1.9) driven by the measured electrical power; state
  [delta (rad), w = omega - 1 (pu), dPm (pu machine base), q1, q2 (q-axis rotor fluxes,
  pu)].  Over a frame interval dt, with the air-gap power P_ag = P + r_a |I|^2 (machine
  base, from the PMU phasors) and the mechanical power P_m of the turbine-governor model
  (PST tg, started in equilibrium at the first measured P_ag, driven by the estimated
  speed), both averaged over the interval's ends (trapezoid):
      a = ((P_m + dPm - P_ag) / omega - D w) / 2H     (subtransient; transient and
                                                        classical machines without 1/omega)
      w' = w + dt a,   delta' = delta + omega_b dt (w + dt a / 2),   dPm' = dPm,
      q' = A_d q + b_d (I_q(delta, I) + I_q(delta', I')) / 2
  (A_d, b_d: exact zero-order-hold discretisation of the machine's linear q-axis circuits,
  I_q = Re(exp(-j delta) I) the q-axis current, machine base).  Measurement: the angle of
  the internal voltage E = V + Z I computed from the PMU phasors (Z = r_a + j x"_d,
  subtransient; r_a + j x'_d otherwise; plus the step-up branch for a PMU at the HV bus),
  h(x) = delta + asin(omega psi"_q / |E|) with psi"_q = c.q the q-axis subtransient flux
  (transient machines: delta - asin(E'_d / |E|); classical: delta).  The bus frequency is
  not used: during swings it differs from the rotor speed by tens of mHz.

Both follow filterpy's equations: `FrequencyKFReference` and `SwingEKFReference` run one
filterpy filter per machine; `FrequencyKF` and `SwingEKF` run the same equations vectorised
over machines with numpy (tests check that they agree to rounding; the vectorised path is
the fast one, `benchmarks/bench_estimator.py`).

Online interface: `step(frame) -> (speed, variance)`, speed (n_mac,) pu, variance pu^2,
NaN until a machine's first valid frame; frames in increasing time-stamp order; where a
frame was dropped the filter predicts only.  `nis` holds the normalised innovation squared
of the last step (NaN where no update), chi-square with `dof` degrees of freedom when the
filter is consistent (`nis_bounds`).  `coi_speed` and `relative_speeds` turn the machine
estimates into what each ESD controller needs (paper eq. 40), with variances.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg
from filterpy.common import Q_continuous_white_noise
from filterpy.kalman import ExtendedKalmanFilter, KalmanFilter
from scipy.stats import chi2

from .case import Case
from .errors import InputError
from .machines import EM, SUB, TRA, machine_params, to_dq
from .pmu import Frame, PMUSettings


# -- tuning ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class FrequencyTuning:
    """Baseline filter: rocof_walk, spectral density of the ROCOF random walk ((Hz/s)^2
    per s); gate_sigma: innovation gate in standard deviations (inf: none).  The
    measurement noise comes from the PMU settings."""

    rocof_walk: float = 4.0
    gate_sigma: float = np.inf


@dataclass(frozen=True)
class SwingTuning:
    """Model-based filter (docs/estimation.md, tuning).  The measurement noise and the
    noise of the measured power and current come from the PMU settings (TVE); added here:

    angle_model_rad: standard deviation of unmodelled internal-angle error (rad);
    accel_psd: white unmodelled acceleration ((pu speed)^2/s); pm_walk: random walk of the
    mechanical-power correction ((pu machine base)^2/s); pm0_sd, flux0_sd: initial
    standard deviations of dPm and of the q-axis fluxes (pu); jump_pu: a change of P_ag
    between two frames above this (pu machine base) is taken for a network event at an
    unknown instant of the interval, adding dP^2/12 (the trapezoid's error variance) to the
    power noise; gate_sigma: innovation gate (standard deviations) beyond which a frame's
    angle is not used (an event's transient).
    """

    angle_model_rad: float = 0.002
    accel_psd: float = 1e-9
    pm_walk: float = 1e-6
    pm0_sd: float = 0.005
    flux0_sd: float = 0.01
    jump_pu: float = 0.1
    gate_sigma: float = 5.0


# -- machine models -------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class LinearSystems:
    """n linear systems dx/dt = A x + b u with a scalar input: A (n, k, k), b (n, k)."""

    A: np.ndarray
    b: np.ndarray
    _zoh: dict = field(default_factory=dict, repr=False)

    def take(self, k: int) -> "LinearSystems":
        return LinearSystems(self.A[k:k + 1], self.b[k:k + 1])

    def discrete(self, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """Exact zero-order-hold discretisation (A_d (n, k, k), b_d (n, k)) over dt (s),
        cached per dt."""
        key = round(dt, 12)
        if key not in self._zoh:
            n, k = self.b.shape
            M = np.zeros((n, k + 1, k + 1))
            M[:, :k, :k], M[:, :k, k] = self.A * dt, self.b * dt
            E = np.stack([scipy.linalg.expm(a) for a in M])
            self._zoh[key] = (E[:, :k, :k], E[:, :k, k])
        return self._zoh[key]


@dataclass(frozen=True, eq=False)
class Governors:
    """PST `tg` turbine-governors (stabctl.governors) as linear systems per machine:
    dg/dt = A g + b u, P_m = c.g, u = clip(P_ref + (wf - omega) / R, 0, T_max); in
    equilibrium g = P_m g_unit.  Machines without a governor (active False) keep P_m."""

    sys: LinearSystems
    c: np.ndarray
    g_unit: np.ndarray
    wf: np.ndarray
    invR: np.ndarray
    Tmax: np.ndarray
    active: np.ndarray

    @classmethod
    def from_case(cls, case: Case) -> "Governors":
        """The case's tg_con governors (none: every machine inactive)."""
        n = len(case.machines)
        A, b, c, gu = np.zeros((n, 3, 3)), np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3))
        wf, invR, Tmax, active = np.ones(n), np.zeros(n), np.full(n, np.inf), np.zeros(n, bool)
        g = case.governors
        for r in range(len(g)):
            k = case.machine_index(g.machine[r])
            Ts, Tc, T3, T4, T5 = g.Ts[r], g.Tc[r], g.T3[r], g.T4[r], g.T5[r]
            A[k] = [[-1 / Ts, 0, 0], [(1 - T3 / Tc) / Tc, -1 / Tc, 0],
                    [(1 - T4 / T5) * T3 / Tc / T5, (1 - T4 / T5) / T5, -1 / T5]]
            b[k, 0] = 1 / Ts
            c[k] = [T4 / T5 * T3 / Tc, T4 / T5, 1.0]
            gu[k] = [1.0, 1 - T3 / Tc, 1 - T4 / T5]
            wf[k], invR[k], Tmax[k], active[k] = g.wf[r], g.invR[r], g.Tmax[r], True
        return cls(LinearSystems(A, b), c, gu, wf, invR, Tmax, active)

    def take(self, k: int) -> "Governors":
        s = slice(k, k + 1)
        return Governors(self.sys.take(k), self.c[s], self.g_unit[s], self.wf[s],
                         self.invR[s], self.Tmax[s], self.active[s])

    def step(self, g: np.ndarray, pref: np.ndarray, omega: np.ndarray, dt: float) -> np.ndarray:
        """States (n, 3) after dt (s), the demand held."""
        Ad, bd = self.sys.discrete(dt)
        u = np.clip(pref + (self.wf - omega) * self.invR, 0.0, self.Tmax)
        return np.einsum("nij,nj->ni", Ad, g) + bd * u[:, None]

    def output(self, g: np.ndarray) -> np.ndarray:
        """Mechanical power (machine base), (n,); 0 for inactive machines."""
        return np.einsum("ni,ni->n", self.c, g)


@dataclass(frozen=True, eq=False)
class QAxis:
    """q-axis rotor circuits of PST's machine models, linear in q (n, 2) with the q-axis
    current I_q (machine base) as input, dq/dt = A q + b I_q (subtransient: q = (E'_d in
    PST's sign, psi_kq), psi"_q = p14 q1 + p15 q2; transient: q1 = E'_d, q2 unused;
    classical: none), and the angle of the internal voltage E behind Z:
    angle(E) = delta + sign asin(omega^speed (c.q) / |E|).  Arrays (n, ...)."""

    sys: LinearSystems
    c: np.ndarray
    sign: np.ndarray
    speed: np.ndarray
    kind: np.ndarray
    ra: np.ndarray
    xl: np.ndarray
    xq: np.ndarray
    xqp: np.ndarray
    xdp: np.ndarray

    @classmethod
    def from_case(cls, case: Case) -> "QAxis":
        """From the case's machine data with PST's substitutions (`machine_params`)."""
        mp = machine_params(case)
        n, sub, tra = mp.n, mp.kind == SUB, mp.kind == TRA
        with np.errstate(divide="ignore", invalid="ignore"):
            p11, p12, p13 = (np.nan_to_num(v) for v in (mp.p11, mp.p12, mp.p13))
            p14, p15 = np.nan_to_num(mp.p14), np.nan_to_num(mp.p15)
        A, b, c = np.zeros((n, 2, 2)), np.zeros((n, 2)), np.zeros((n, 2))
        Tq, Tqq = mp.Tqop, mp.Tqopp
        A[sub] = np.stack([np.stack([-(1 + p12 * p11) / Tq, p12 * p11 / Tq], -1),
                           np.stack([1 / Tqq, -1 / Tqq], -1)], 1)[sub]
        b[sub] = np.stack([(p12 * p11 * p13 - p12) / Tq, -p13 / Tqq], -1)[sub]
        c[sub] = np.stack([p14, p15], -1)[sub]
        A[tra, 0, 0] = -1 / Tq[tra]
        b[tra, 0] = ((mp.xq - mp.xqp) / Tq)[tra]
        c[tra, 0] = 1.0
        return cls(LinearSystems(A, b), c, np.where(tra, -1.0, 1.0), sub, mp.kind,
                   np.where(mp.kind == EM, 0.0, mp.ra), mp.xl, mp.xq, mp.xqp, mp.xdp)

    def take(self, k: int) -> "QAxis":
        s = slice(k, k + 1)
        return QAxis(self.sys.take(k), self.c[s], self.sign[s], self.speed[s], self.kind[s],
                     self.ra[s], self.xl[s], self.xq[s], self.xqp[s], self.xdp[s])

    def steady_state(self, v: np.ndarray, i_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Rotor angle (n,) and q-axis states (n, 2) in steady state at terminal voltage v
        and current i_m (machine base), as PST initialises them (docs/pst_models.md 1.7)."""
        em = self.kind == EM
        delta = np.angle(v + np.where(em, 1j * self.xdp, self.ra + 1j * self.xq) * i_m)
        curd, curq = to_dq(delta, i_m)
        edra = -to_dq(delta, v)[0] - self.ra * curd
        q = np.zeros((delta.size, 2))
        sub, tra = self.kind == SUB, self.kind == TRA
        q[sub] = np.stack([edra + self.xqp * curq, edra + self.xl * curq], -1)[sub]
        q[tra, 0] = to_dq(delta, v + (self.ra + 1j * self.xdp) * i_m)[0][tra]
        return delta, q


@dataclass(frozen=True, eq=False)
class MachineModels:
    """What the swing filter knows of each machine, arrays of shape (n,).

    numbers: machine numbers; pmu: index of the PMU measuring its current; H (s), D (pu)
    machine base; pot = base MVA / machine MVA; ra: armature resistance in the torque (pu
    machine base; 0 for classical machines); z_emf: impedance from the PMU bus to the
    internal voltage (complex pu, system base); per_speed: torque = power / omega (PST's
    subtransient model); inertia: H * MVA (MJ), the COI weights; f0 (Hz); governor,
    qaxis: `Governors`, `QAxis`.
    """

    numbers: np.ndarray
    pmu: np.ndarray
    H: np.ndarray
    D: np.ndarray
    pot: np.ndarray
    ra: np.ndarray
    z_emf: np.ndarray
    per_speed: np.ndarray
    inertia: np.ndarray
    f0: float
    governor: Governors
    qaxis: QAxis

    @property
    def n(self) -> int:
        return self.numbers.size

    def take(self, k: int) -> "MachineModels":
        """The model of machine index k alone (arrays of length 1)."""
        s = slice(k, k + 1)
        return MachineModels(self.numbers[s], self.pmu[s], self.H[s], self.D[s], self.pot[s],
                             self.ra[s], self.z_emf[s], self.per_speed[s], self.inertia[s],
                             self.f0, self.governor.take(k), self.qaxis.take(k))


def machine_models(case: Case, pmus) -> MachineModels:
    """Swing-filter models of every machine of the case from its data (mac_con, tg_con)
    and the PMU measuring its current: at its terminal bus, or at a bus joined to the
    terminal by branches whose series impedance r + jx is added to Z (taps and charging
    ignored).  Raises InputError if a machine has no PMU measuring its current."""
    mp = machine_params(case)
    which = {p.machine: j for j, p in enumerate(pmus) if p.machine is not None}
    missing = [int(n) for n in case.machines.number if int(n) not in which]
    if missing:
        raise InputError(f"no PMU measures the current of machine(s) {missing}")
    idx = np.array([which[int(n)] for n in case.machines.number])
    x = np.where(mp.kind == SUB, mp.xdpp, mp.xdp)
    z = (np.where(mp.kind == EM, 0.0, mp.ra) + 1j * x) * mp.mac_pot
    for k, j in enumerate(idx):
        z[k] += _series_impedance(case, int(case.machines.bus[k]), pmus[j].bus)
    return MachineModels(
        numbers=case.machines.number.astype(int), pmu=idx, H=mp.H.copy(), D=mp.D0.copy(),
        pot=mp.mac_pot, ra=np.where(mp.kind == EM, 0.0, mp.ra), z_emf=z,
        per_speed=mp.kind == SUB, inertia=mp.H * case.machines.mva, f0=case.freq_hz,
        governor=Governors.from_case(case), qaxis=QAxis.from_case(case))


def _series_impedance(case: Case, term: int, bus: int) -> complex:
    """Series impedance (pu) of the branches joining bus numbers term and bus, in
    parallel; 0 when they are the same bus."""
    if term == bus:
        return 0j
    br = case.branches
    sel = ((br.from_bus == term) & (br.to_bus == bus)) | ((br.from_bus == bus) & (br.to_bus == term))
    return complex(1.0 / np.sum(1.0 / (br.r[sel] + 1j * br.x[sel])))


# -- centre of inertia ------------------------------------------------------------------------
def coi_speed(speed: np.ndarray, var: np.ndarray, inertia: np.ndarray) -> tuple[float, float]:
    """COI speed sum(M_i w_i) / sum(M_i) (paper eq. 40, M = H*MVA) and its variance, the
    machine estimates taken as independent (one filter per machine, independent PMU
    noise).  speed, var: (n,) pu, pu^2."""
    w = inertia / inertia.sum()
    return float(w @ speed), float(w ** 2 @ var)


def relative_speeds(speed: np.ndarray, var: np.ndarray, inertia: np.ndarray,
                    coi: str = "system") -> tuple[np.ndarray, np.ndarray]:
    """omega_i - omega_COI of every machine (pu) and its variance (pu^2), the COI of all
    machines (coi="system") or of the others (coi="rest"), as `stabctl.storage.BangBangCOI`.

    With weights w = M / sum(M) and independent estimates: var = (1 - 2 w_i) s_i^2 +
    sum_j w_j^2 s_j^2 (system); s_i^2 + sum_{j != i} w_j^2 s_j^2 / (1 - w_i)^2 (rest).
    Raises InputError for another coi.
    """
    w = inertia / inertia.sum()
    if coi == "system":
        c, cv = coi_speed(speed, var, inertia)
        return speed - c, (1 - 2 * w) * var + cv
    if coi == "rest":
        rest = (w @ speed - w * speed) / (1 - w)
        return speed - rest, var + (w ** 2 @ var - w ** 2 * var) / (1 - w) ** 2
    raise InputError(f"coi must be 'system' or 'rest', got {coi!r}")


def nis_bounds(dof: int, coverage: float = 0.95) -> tuple[float, float]:
    """Two-sided chi-square interval holding `coverage` of a consistent filter's NIS."""
    a = (1 - coverage) / 2
    return float(chi2.ppf(a, dof)), float(chi2.ppf(1 - a, dof))


# -- baseline filter equations ------------------------------------------------------------
@dataclass
class _FreqMeasurement:
    """Baseline-filter inputs of one frame: z (n, 2) = [f - f0 (Hz), ROCOF (Hz/s)],
    R (2, 2), valid mask ok (n,)."""

    z: np.ndarray
    R: np.ndarray
    ok: np.ndarray


def _freq_measurements(frame: Frame, pmu: np.ndarray, f0: float, s: PMUSettings):
    z = np.stack([frame.freq[pmu] - f0, frame.rocof[pmu]], axis=1)
    return _FreqMeasurement(z=z, R=np.diag([s.sigma_freq ** 2, s.sigma_rocof ** 2]),
                            ok=frame.valid[pmu] & np.isfinite(z).all(axis=1))


def _freq_F(dt: float) -> np.ndarray:
    return np.array([[1.0, dt], [0.0, 1.0]])


# -- swing filter equations ---------------------------------------------------------------
@dataclass
class _SwingMeasurement:
    """Swing-filter inputs of one frame, arrays (n,): internal-voltage angle theta (rad)
    and magnitude emag (pu), terminal voltage v and current cur (complex pu, system base),
    bus frequency freq (Hz, for the start only), air-gap power pag and its noise variance
    (pu machine base), variance of I_q (pu^2 machine base), PMU noise variance of theta
    r (rad^2), valid mask ok."""

    theta: np.ndarray
    emag: np.ndarray
    v: np.ndarray
    cur: np.ndarray
    freq: np.ndarray
    pag: np.ndarray
    pag_var: np.ndarray
    iq_var: np.ndarray
    r: np.ndarray
    ok: np.ndarray


def _swing_measurements(frame: Frame, m: MachineModels, s: PMUSettings) -> _SwingMeasurement:
    """Internal voltage, air-gap power and noise from one frame.

    To first order in the relative phasor errors e_V, e_I (std s per component): the
    angle of E = V + Z I has variance s^2 (|V|^2 + |Z I|^2) / |E|^2, P = Re(V conj I)
    2 s^2 |S|^2, I_q (machine base) s^2 |I|^2 pot^2.
    """
    v, i, f = frame.v[m.pmu], frame.i[m.pmu], frame.freq[m.pmu]
    ok = frame.valid[m.pmu] & np.isfinite(v) & np.isfinite(i) & np.isfinite(f)
    e = v + m.z_emf * i
    S = v * np.conj(i)
    sig2 = s.sigma_phasor ** 2
    ia = np.abs(i) * m.pot
    return _SwingMeasurement(
        theta=np.angle(e), emag=np.abs(e), v=v, cur=i, freq=f, pag=m.pot * S.real + m.ra * ia ** 2,
        pag_var=2 * sig2 * (m.pot * np.abs(S)) ** 2, iq_var=sig2 * ia ** 2,
        r=sig2 * (np.abs(v) ** 2 + np.abs(m.z_emf * i) ** 2) / np.abs(e) ** 2, ok=ok)


@dataclass
class _SwingInputs:
    """Inputs over one interval: mean P_m and P_ag, the variance of the mean P_ag, the
    currents at both ends (complex, system base) and the variance of their I_q."""

    pm: np.ndarray
    pag: np.ndarray
    pag_var: np.ndarray
    cur0: np.ndarray
    cur1: np.ndarray
    iq_var: np.ndarray


def _swing_transition(x: np.ndarray, u: _SwingInputs, dt: float, m: MachineModels):
    """Propagated states (n, 5), Jacobian F (n, 5, 5) and the sensitivity g (n, 5) of the
    propagated states to the mean P_ag (module docstring)."""
    d, w, p = x[:, 0], x[:, 1], x[:, 2]
    wb = 2 * np.pi * m.f0
    omega = np.where(m.per_speed, 1.0 + w, 1.0)
    c = 1.0 / (2 * m.H * omega)
    acc = c * (u.pm + p - u.pag) - m.D * w / (2 * m.H)
    da_dw = -np.where(m.per_speed, c * (u.pm + p - u.pag) / omega, 0.0) - m.D / (2 * m.H)
    d1 = d + wb * dt * (w + 0.5 * dt * acc)
    r0, r1 = np.exp(-1j * d) * u.cur0 * m.pot, np.exp(-1j * d1) * u.cur1 * m.pot
    Ad, bd = m.qaxis.sys.discrete(dt)
    xn = np.empty_like(x)
    xn[:, 0], xn[:, 1], xn[:, 2] = d1, w + dt * acc, p
    xn[:, 3:] = np.einsum("nij,nj->ni", Ad, x[:, 3:]) + bd * (0.5 * (r0.real + r1.real))[:, None]
    F = np.zeros((m.n, 5, 5))
    F[:, 0, 0] = F[:, 2, 2] = 1.0
    F[:, 0, 1] = wb * dt * (1 + 0.5 * dt * da_dw)
    F[:, 0, 2] = wb * dt * 0.5 * dt * c
    F[:, 1, 1] = 1 + dt * da_dw
    F[:, 1, 2] = dt * c
    F[:, 3:, 3:] = Ad
    dIq = 0.5 * (r1.imag[:, None] * F[:, 0, :3])          # d I_q(delta') / d(delta, w, dPm)
    dIq[:, 0] += 0.5 * r0.imag                              # d I_q(delta) / d delta
    F[:, 3:, :3] = bd[:, :, None] * dIq[:, None, :]
    g = np.zeros((m.n, 5))
    g[:, 0], g[:, 1] = -wb * 0.5 * dt * dt * c, -dt * c
    return xn, F, g


def _swing_Q(g: np.ndarray, u: _SwingInputs, dt: float, m: MachineModels,
             tun: SwingTuning) -> np.ndarray:
    """Process noise (n, 5, 5): measured-power noise through g, I_q noise through b_d,
    white unmodelled acceleration on (delta, w), random walk of dPm."""
    wb = 2 * np.pi * m.f0
    bd = m.qaxis.sys.discrete(dt)[1]
    Q = g[:, :, None] * g[:, None, :] * u.pag_var[:, None, None]
    Q[:, 3:, 3:] += bd[:, :, None] * bd[:, None, :] * (0.5 * u.iq_var)[:, None, None]
    Q[:, :2, :2] += tun.accel_psd * np.array([[wb ** 2 * dt ** 3 / 3, wb * dt ** 2 / 2],
                                              [wb * dt ** 2 / 2, dt]])
    Q[:, 2, 2] += tun.pm_walk * dt
    return Q


def _swing_h(x: np.ndarray, emag: np.ndarray, m: MachineModels):
    """Predicted internal-voltage angle (n,) and its Jacobian H (n, 1, 5)."""
    qa = m.qaxis
    omega = np.where(qa.speed, 1.0 + x[:, 1], 1.0)
    psi = np.einsum("ni,ni->n", qa.c, x[:, 3:])
    s = np.clip(omega * psi / emag, -0.99, 0.99)
    k = qa.sign / (emag * np.sqrt(1 - s ** 2))
    H = np.zeros((m.n, 1, 5))
    H[:, 0, 0] = 1.0
    H[:, 0, 1] = np.where(qa.speed, k * psi, 0.0)
    H[:, 0, 3:] = (k * omega)[:, None] * qa.c
    return x[:, 0] + qa.sign * np.arcsin(s), H


def _wrap(a):
    """Angle(s) wrapped to [-pi, pi)."""
    return (a + np.pi) % (2 * np.pi) - np.pi


# -- Kalman algebra (filterpy's equations, vectorised) ------------------------------------
def _gated_R(P, y, H, R, gate):
    """Measurement noise with outliers removed, and the NIS of the full innovation.

    A component j whose innovation exceeds `gate` standard deviations of S = H P H' + R
    gets R_jj = 1e12 S_jj, i.e. is not used in this frame.  P (k, nx, nx), y (k, nz),
    H and R (k, nz, nx), (k, nz, nz).
    """
    S = H @ P @ np.swapaxes(H, 1, 2) + R
    nis = np.einsum("ki,kij,kj->k", y, np.linalg.inv(S), y)
    Sd = np.diagonal(S, axis1=1, axis2=2)
    k, j = np.nonzero(y ** 2 > gate ** 2 * Sd)
    Rg = R.copy()
    Rg[k, j, j] = 1e12 * Sd[k, j]
    return Rg, nis


def _batch_update(x, P, y, H, R):
    """Kalman update of a stack of filters, Joseph form as filterpy: x (k, nx),
    P (k, nx, nx), innovation y (k, nz), H (k, nz, nx), R (k, nz, nz); returns x, P."""
    Ht = np.swapaxes(H, 1, 2)
    PHt = P @ Ht
    K = PHt @ np.linalg.inv(H @ PHt + R)
    x = x + np.einsum("kij,kj->ki", K, y)
    IKH = np.eye(x.shape[1]) - K @ H
    return x, IKH @ P @ np.swapaxes(IKH, 1, 2) + K @ R @ np.swapaxes(K, 1, 2)


# -- filters --------------------------------------------------------------------------------
class _MachineFilters:
    """Time keeping shared by the estimators: frames in increasing time-stamp order, each
    machine starting at its first valid frame; subclasses implement `_measure`, `_init`,
    `_predict`, `_update`, `_output`."""

    dof = 1

    def __init__(self, n: int):
        self.t: float | None = None
        self.ready = np.zeros(n, bool)
        self.nis = np.full(n, np.nan)

    def step(self, frame: Frame) -> tuple[np.ndarray, np.ndarray]:
        """Advance to the frame's time stamp and use its valid measurements.

        Returns the speed estimates (n,) pu and their variances (n,) pu^2 (NaN before a
        machine's first valid frame).  Raises InputError for a time stamp not after the
        previous one.
        """
        if self.t is not None and not frame.t > self.t:
            raise InputError(f"frame at t = {frame.t} s is not after the previous one "
                             f"({self.t} s): frames must come in time-stamp order")
        meas = self._measure(frame)
        self.nis = np.full(self.ready.size, np.nan)
        if self.ready.any():
            self._predict(frame.t - self.t, meas)
            sel = meas.ok & self.ready
            if sel.any():
                self._update(meas, sel)
        new = meas.ok & ~self.ready
        if new.any():
            self._init(meas, new)
            self.ready |= new
        self.t = frame.t
        return self._output()


class FrequencyKF(_MachineFilters):
    """Baseline filter on PMU frequency and ROCOF, vectorised over machines.

    pmu: (n,) index of each machine's PMU in the frames; settings: the PMUs' (noise);
    tuning: `FrequencyTuning`; f0: nominal frequency (Hz).
    """

    name = "kf"
    dof = 2

    def __init__(self, pmu, settings: PMUSettings, tuning: FrequencyTuning = FrequencyTuning(),
                 f0: float = 60.0):
        self.pmu, self.s, self.tun, self.f0 = np.asarray(pmu), settings, tuning, f0
        super().__init__(self.pmu.size)
        self.x = np.full((self.pmu.size, 2), np.nan)
        self.P = np.full((self.pmu.size, 2, 2), np.nan)

    def _measure(self, frame):
        return _freq_measurements(frame, self.pmu, self.f0, self.s)

    def _init(self, meas, sel):
        self.x[sel], self.P[sel] = meas.z[sel], meas.R

    def _predict(self, dt, meas):
        F = _freq_F(dt)
        self.x = self.x @ F.T
        self.P = F @ self.P @ F.T + Q_continuous_white_noise(2, dt, self.tun.rocof_walk)

    def _update(self, meas, sel):
        k = int(sel.sum())
        y, H = meas.z[sel] - self.x[sel], np.broadcast_to(np.eye(2), (k, 2, 2))
        R, self.nis[sel] = _gated_R(self.P[sel], y, H, np.broadcast_to(meas.R, (k, 2, 2)),
                                    self.tun.gate_sigma)
        self.x[sel], self.P[sel] = _batch_update(self.x[sel], self.P[sel], y, H, R)

    def _output(self):
        return 1.0 + self.x[:, 0] / self.f0, self.P[:, 0, 0] / self.f0 ** 2


class SwingEKF(_MachineFilters):
    """Model-based filter on the swing equation, vectorised over machines.

    models: `MachineModels` (`machine_models`); settings: the PMUs'; tuning: `SwingTuning`.
    """

    name = "ekf"

    def __init__(self, models: MachineModels, settings: PMUSettings,
                 tuning: SwingTuning = SwingTuning()):
        self.m, self.s, self.tun = models, settings, tuning
        super().__init__(models.n)
        n = models.n
        self.x, self.P = np.full((n, 5), np.nan), np.full((n, 5, 5), np.nan)
        self._pag, self._pag_var = np.full(n, np.nan), np.full(n, np.nan)  # last valid
        self._cur, self._iq_var = np.full(n, np.nan + 0j), np.full(n, np.nan)
        self._pm0, self._g = np.full(n, np.nan), np.zeros((n, 3))  # start P_m, governors

    def _measure(self, frame):
        return _swing_measurements(frame, self.m, self.s)

    def _init(self, meas, sel):
        """Start in steady state at the first valid frame (PST's initialisation), speed
        from the bus frequency, P_m = P_ag, governors in equilibrium."""
        m, n = self.m, self.m.n
        delta, q = m.qaxis.steady_state(meas.v, meas.cur * m.pot)
        x0 = np.column_stack([delta, meas.freq / m.f0 - 1, np.zeros(n), q])
        P0 = np.zeros((n, 5, 5))
        P0[:, 0, 0] = meas.r + self.tun.angle_model_rad ** 2
        P0[:, 1, 1] = (self.s.sigma_freq / m.f0) ** 2
        P0[:, 2, 2] = self.tun.pm0_sd ** 2
        P0[:, 3, 3] = P0[:, 4, 4] = self.tun.flux0_sd ** 2
        self.x[sel], self.P[sel] = x0[sel], P0[sel]
        self._pag[sel], self._pag_var[sel], self._pm0[sel] = \
            meas.pag[sel], meas.pag_var[sel], meas.pag[sel]
        self._cur[sel], self._iq_var[sel] = meas.cur[sel], meas.iq_var[sel]
        self._g[sel] = (m.governor.g_unit * meas.pag[:, None])[sel]

    def _inputs(self, dt, meas) -> _SwingInputs:
        """Interval inputs; advances the governors (demand from the estimated speed, P_ref
        such that the start was an equilibrium at nominal speed) and the held values (the
        last valid P_ag and current stand in for a dropped frame)."""
        gov = self.m.governor
        pm_before = np.where(gov.active, gov.output(self._g), self._pm0)
        pref = self._pm0 - (gov.wf - 1.0) * gov.invR
        self._g = gov.step(self._g, pref, np.nan_to_num(1.0 + self.x[:, 1], nan=1.0), dt)
        pm = 0.5 * (pm_before + np.where(gov.active, gov.output(self._g), self._pm0))
        ok = meas.ok
        dp = meas.pag - self._pag
        jump = np.where(np.abs(dp) > self.tun.jump_pu, dp ** 2 / 12, 0.0)
        u = _SwingInputs(
            pm=pm, pag=np.where(ok, 0.5 * (self._pag + meas.pag), self._pag),
            pag_var=np.where(ok, 0.25 * (self._pag_var + meas.pag_var) + jump, self._pag_var),
            cur0=self._cur, cur1=np.where(ok, meas.cur, self._cur),
            iq_var=np.where(ok, 0.5 * (self._iq_var + meas.iq_var), self._iq_var))
        self._pag = np.where(ok, meas.pag, self._pag)
        self._pag_var = np.where(ok, meas.pag_var, self._pag_var)
        self._cur, self._iq_var = u.cur1, np.where(ok, meas.iq_var, self._iq_var)
        return u

    def _predict(self, dt, meas):
        u = self._inputs(dt, meas)
        self.x, F, g = _swing_transition(self.x, u, dt, self.m)
        self.P = F @ self.P @ np.swapaxes(F, 1, 2) + _swing_Q(g, u, dt, self.m, self.tun)

    def _innovation(self, meas):
        """Innovation (n,), Jacobian H (n, 1, 5) and noise R (n, 1, 1) of every machine."""
        h, H = _swing_h(self.x, meas.emag, self.m)
        R = (meas.r + self.tun.angle_model_rad ** 2)[:, None, None]
        return _wrap(meas.theta - h), H, R

    def _update(self, meas, sel):
        y, H, R = self._innovation(meas)
        y, H, R = y[sel, None], H[sel], R[sel]
        R, self.nis[sel] = _gated_R(self.P[sel], y, H, R, self.tun.gate_sigma)
        self.x[sel], self.P[sel] = _batch_update(self.x[sel], self.P[sel], y, H, R)

    def _output(self):
        return 1.0 + self.x[:, 1], self.P[:, 1, 1]


# -- filterpy reference implementations -----------------------------------------------------
class FrequencyKFReference(FrequencyKF):
    """`FrequencyKF` with one filterpy `KalmanFilter` per machine (reference, slower)."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.kfs = [KalmanFilter(dim_x=2, dim_z=2) for _ in range(self.pmu.size)]

    def _init(self, meas, sel):
        for k in np.flatnonzero(sel):
            self.kfs[k].x, self.kfs[k].P = meas.z[k].copy(), meas.R.copy()
            self.x[k], self.P[k] = self.kfs[k].x, self.kfs[k].P

    def _predict(self, dt, meas):
        for k in np.flatnonzero(self.ready):
            kf = self.kfs[k]
            kf.F, kf.Q = _freq_F(dt), Q_continuous_white_noise(2, dt, self.tun.rocof_walk)
            kf.predict()
            self.x[k], self.P[k] = kf.x, kf.P

    def _update(self, meas, sel):
        H = np.eye(2)
        for k in np.flatnonzero(sel):
            kf, z = self.kfs[k], meas.z[k]
            R, nis = _gated_R(kf.P[None], (z - kf.x)[None], H[None], meas.R[None],
                              self.tun.gate_sigma)
            kf.update(z, R=R[0], H=H)
            self.x[k], self.P[k], self.nis[k] = kf.x, kf.P, nis[0]


class _SwingEKF1(ExtendedKalmanFilter):
    """filterpy EKF of one machine; its nonlinear transition is evaluated by the shared
    swing equations and handed to `predict` as u."""

    def predict_x(self, u=0):
        self.x = u


class SwingEKFReference(SwingEKF):
    """`SwingEKF` with one filterpy `ExtendedKalmanFilter` per machine (reference, slower)."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.ekfs = [_SwingEKF1(dim_x=5, dim_z=1) for _ in range(self.m.n)]

    def _init(self, meas, sel):
        super()._init(meas, sel)
        for k in np.flatnonzero(sel):
            self.ekfs[k].x, self.ekfs[k].P = self.x[k].copy(), self.P[k].copy()

    def _predict(self, dt, meas):
        u = self._inputs(dt, meas)
        for k in np.flatnonzero(self.ready):
            mk, s = self.m.take(k), slice(k, k + 1)
            uk = _SwingInputs(*(getattr(u, f)[s] for f in u.__dataclass_fields__))
            xn, F, g = _swing_transition(self.x[s], uk, dt, mk)
            ekf = self.ekfs[k]
            ekf.F, ekf.Q = F[0], _swing_Q(g, uk, dt, mk, self.tun)[0]
            ekf.predict(u=xn[0])
            self.x[k], self.P[k] = ekf.x, ekf.P

    def _update(self, meas, sel):
        for k in np.flatnonzero(sel):
            mk, ekf, e = self.m.take(k), self.ekfs[k], meas.emag[k:k + 1]
            hH = lambda x: _swing_h(x[None], e, mk)  # noqa: E731  (h (1,), H (1, 1, 5))
            h, H = hH(ekf.x)
            R, nis = _gated_R(ekf.P[None], _wrap(meas.theta[k] - h)[None], H,
                              np.array([[[meas.r[k] + self.tun.angle_model_rad ** 2]]]),
                              self.tun.gate_sigma)
            ekf.update(np.array([meas.theta[k]]), HJacobian=lambda x: hH(x)[1][0],
                       Hx=lambda x: hH(x)[0], R=R[0], residual=lambda a, b: _wrap(a - b))
            self.x[k], self.P[k], self.nis[k] = ekf.x, ekf.P, nis[0]
