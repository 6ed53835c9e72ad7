"""What the estimators know of the machines (docs/estimation.md): the tuning of each filter
(`FrequencyTuning`, `SwingTuning`), the machine models of the swing filter
(`MachineModels` from `machine_models`: inertia, damping, the impedance from the PMU bus
to the internal voltage, PSTess's q-axis rotor circuits `QAxis` and tg turbine-governors
`Governors` as linear systems, `LinearSystems`), and the centre-of-inertia (COI) speed
and relative speeds each ESD controller needs from the machine estimates (`coi_speed`,
`relative_speeds`, paper eq. 40), with variances.  The filters themselves are in
`stabctl.estimation.filters`.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg

from stabctl.case import Case
from stabctl.dynamics.coi import coi_weights
from stabctl.errors import InputError
from stabctl.models.machines import SUB, TRA, machine_params
from stabctl.network.topology import machine_islands


# -- tuning ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class FrequencyTuning:
    """Baseline filter: rocof_walk, spectral density of the ROCOF random walk ((Hz/s)^2
    per s), sized for post-fault swings (the ROCOF of a 0.2 Hz swing at 1 Hz changes by
    about 8 Hz/s within a second).  The measurement noise comes from the PMU settings."""

    rocof_walk: float = 50.0


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
    power noise.
    """

    angle_model_rad: float = 0.002
    accel_psd: float = 1e-9
    pm_walk: float = 1e-6
    pm0_sd: float = 0.005
    flux0_sd: float = 0.01
    jump_pu: float = 0.1


# -- machine models -------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class LinearSystems:
    """n linear systems dx/dt = A x + b u with a scalar input: A (n, k, k), b (n, k)."""

    A: np.ndarray
    b: np.ndarray
    _zoh: dict = field(default_factory=dict, repr=False)

    def discrete(self, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """Exact zero-order-hold discretisation (A_d (n, k, k), b_d (n, k)) over dt (s),
        cached per dt."""
        key = round(dt, 12)
        if key not in self._zoh:
            n, k = self.b.shape
            M = np.zeros((n, k + 1, k + 1))
            M[:, :k, :k], M[:, :k, k] = self.A * dt, self.b * dt
            E = np.stack([scipy.linalg.expm(a) for a in M])
            self._zoh[key] = (np.ascontiguousarray(E[:, :k, :k]), np.ascontiguousarray(E[:, :k, k]))
        return self._zoh[key]


@dataclass(frozen=True, eq=False)
class Governors:
    """PST `tg` turbine-governors (stabctl.models.governors) as linear systems per machine:
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
    def from_case(cls, case: Case) -> Governors:
        """The case's tg_con governors (none: every machine inactive).  A governor other
        than PST tg (type 1: a PSS/E TGOV1, IEEEG1, GAST, HYGOV ...), which this linear
        model does not hold, leaves its machine inactive: its mechanical power held at the
        start, the filter's random walk dPm taking what the governor moves, and a
        UserWarning names each such machine with its model."""
        other = np.nonzero(case.governors.type != 1)[0]
        if other.size:
            warnings.warn(_held_governors(case, other), UserWarning, stacklevel=2)
        n = len(case.machines)
        A, b, c, gu = np.zeros((n, 3, 3)), np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3))
        wf, invR, Tmax, active = np.ones(n), np.zeros(n), np.full(n, np.inf), np.zeros(n, bool)
        g = case.governors
        for r in np.nonzero(g.type == 1)[0]:
            k = case.machine_index(g.machine[r])
            Ts, Tc, T3, T4, T5 = g.Ts[r], g.Tc[r], g.T3[r], g.T4[r], g.T5[r]
            A[k] = [
                [-1 / Ts, 0, 0],
                [(1 - T3 / Tc) / Tc, -1 / Tc, 0],
                [(1 - T4 / T5) * T3 / Tc / T5, (1 - T4 / T5) / T5, -1 / T5],
            ]
            b[k, 0] = 1 / Ts
            c[k] = [T4 / T5 * T3 / Tc, T4 / T5, 1.0]
            gu[k] = [1.0, 1 - T3 / Tc, 1 - T4 / T5]
            wf[k], invR[k], Tmax[k], active[k] = g.wf[r], g.invR[r], g.Tmax[r], True
        return cls(LinearSystems(A, b), c, gu, wf, invR, Tmax, active)

    def output(self, g: np.ndarray) -> np.ndarray:
        """Mechanical power (machine base), (n,); 0 for inactive machines."""
        return np.einsum("ni,ni->n", self.c, g)


def _held_governors(case: Case, rows: np.ndarray) -> str:
    """The warning of the governors (tg_con rows, 0-based) the estimators' model holds at
    their start: each machine with its model, a few named and the rest counted."""
    from stabctl.models.governors import TYPES

    g = case.governors
    named = []
    for r in rows[:5]:
        kind = int(g.type[r])
        model = "/".join(m.name for m in getattr(TYPES.get(kind), "DYR", ())) or f"type {kind}"
        named.append(f"{case.machine_name(int(g.machine[r]))} ({model})")
    more = f" and {rows.size - 5} more" if rows.size > 5 else ""
    return (
        f"the estimators' model holds the mechanical power of {rows.size} machine(s) at its "
        f"start: {', '.join(named)}{more} have governors other than PST's tg, which the "
        "filters' linear turbine model does not hold; their random walk dPm takes what "
        "those governors move (the simulation itself runs them in full; docs/estimation.md "
        "section 7)"
    )


@dataclass(frozen=True, eq=False)
class QAxis:
    """q-axis rotor circuits of PST's machine models, linear in q (n, 2) with the q-axis
    current I_q (machine base) as input, dq/dt = A q + b I_q (subtransient: q = (E'_d in
    PST's sign, psi_kq), psi"_q = p14 q1 + p15 q2; transient: q1 = E'_d, q2 unused;
    classical: none), and the angle of the internal voltage E behind Z:
    angle(E) = delta + sign asin(omega^speed (c.q) / |E|); kind (PST model) and the
    reactances that locate the rotor in steady state (`swing_start`).  Arrays (n, ...)."""

    sys: LinearSystems
    c: np.ndarray
    sign: np.ndarray
    speed: np.ndarray
    kind: np.ndarray
    xl: np.ndarray
    xq: np.ndarray
    xqp: np.ndarray
    xdp: np.ndarray

    @classmethod
    def from_case(cls, case: Case) -> QAxis:
        """From the case's machine data with PST's substitutions (`machine_params`)."""
        mp = machine_params(case)
        n, sub, tra = mp.n, mp.kind == SUB, mp.kind == TRA
        with np.errstate(divide="ignore", invalid="ignore"):
            p11, p12, p13 = (np.nan_to_num(v) for v in (mp.p11, mp.p12, mp.p13))
            p14, p15 = np.nan_to_num(mp.p14), np.nan_to_num(mp.p15)
        A, b, c = np.zeros((n, 2, 2)), np.zeros((n, 2)), np.zeros((n, 2))
        Tq, Tqq = mp.Tqop, mp.Tqopp
        A[sub] = np.stack(
            [
                np.stack([-(1 + p12 * p11) / Tq, p12 * p11 / Tq], -1),
                np.stack([1 / Tqq, -1 / Tqq], -1),
            ],
            1,
        )[sub]
        b[sub] = np.stack([(p12 * p11 * p13 - p12) / Tq, -p13 / Tqq], -1)[sub]
        c[sub] = np.stack([p14, p15], -1)[sub]
        A[tra, 0, 0] = -1 / Tq[tra]
        b[tra, 0] = ((mp.xq - mp.xqp) / Tq)[tra]
        c[tra, 0] = 1.0
        return cls(
            LinearSystems(A, b),
            c,
            np.where(tra, -1.0, 1.0),
            mp.speed_effects,
            mp.kind,
            mp.xl,
            mp.xq,
            mp.xqp,
            mp.xdp,
        )


@dataclass(frozen=True, eq=False)
class MachineModels:
    """What the swing filter knows of each machine, arrays of shape (n,).

    numbers: machine numbers; pmu: index of the PMU measuring its current; H (s), D (pu)
    machine base; pot = base MVA / machine MVA; ra: armature resistance in the torque (pu
    machine base; 0 for classical machines); z_emf: impedance from the PMU bus to the
    internal voltage (complex pu, system base); per_speed: torque = power / omega (PST's
    subtransient model); psse_swing: PSS/E's swing equation ((P_m - D w)/omega - P_ag)/2H
    (mac_con psse_swing, `stabctl.estimation.filters.swing_acceleration`); inertia: H *
    MVA (MJ), the COI weights; f0 (Hz); governor, qaxis: `Governors`, `QAxis`.
    """

    numbers: np.ndarray
    pmu: np.ndarray
    H: np.ndarray
    D: np.ndarray
    pot: np.ndarray
    ra: np.ndarray
    z_emf: np.ndarray
    per_speed: np.ndarray
    psse_swing: np.ndarray
    inertia: np.ndarray
    f0: float
    governor: Governors
    qaxis: QAxis

    @property
    def n(self) -> int:
        return self.numbers.size


def machine_models(case: Case, pmus) -> MachineModels:
    """Swing-filter models of every machine of the case from its data (mac_con, tg_con)
    and the PMU measuring its current: at its terminal bus, or at a bus joined to the
    terminal by branches whose series impedance r + jx is added to Z (taps and charging
    ignored).  Raises InputError if a machine has no PMU measuring its current, is an
    infinite bus (H = 0: no swing to filter), or the machines lie in several islands (the
    estimated COI, `coi_speed`, is the whole system's; the simulator's is each island's,
    `stabctl.dynamics.coi.coi_of_islands`)."""
    case.require_machines("the speed estimators filter each machine's swing and need one")
    mp = machine_params(case)
    infinite = case.machines.number[mp.H == 0].astype(int).tolist()
    if infinite:
        named = ", ".join(case.machine_name(k) for k in infinite)
        verb = "is an infinite bus" if len(infinite) == 1 else "are infinite buses"
        raise InputError(
            f"case '{case.name}': {named} {verb} (H = 0): the speed estimators filter each "
            "machine's swing equation and need H > 0"
        )
    island = machine_islands(case)
    if island.max() > 0:
        raise InputError(
            f"case '{case.name}': its machines lie in {island.max() + 1} islands (machine "
            f"{int(case.machines.number[np.argmax(island)])} is not connected to machine "
            f"{int(case.machines.number[0])}); the estimators' COI is one system's"
        )
    which = {p.machine: j for j, p in enumerate(pmus) if p.machine is not None}
    missing = [int(n) for n in case.machines.number if int(n) not in which]
    if missing:
        raise InputError(f"no PMU measures the current of machine(s) {missing}")
    idx = np.array([which[int(n)] for n in case.machines.number])
    z = mp.z_internal.copy()  # the simulator's internal impedance, system base
    for k, j in enumerate(idx):
        z[k] += _series_impedance(case, int(case.machines.bus[k]), pmus[j].bus)
    return MachineModels(
        numbers=case.machines.number.astype(int),
        pmu=idx,
        H=mp.H.copy(),
        D=mp.D0.copy(),
        pot=mp.mac_pot,
        ra=mp.ra_network,
        z_emf=z,
        per_speed=mp.speed_effects,
        psse_swing=mp.psse_swing,
        inertia=mp.H * case.machines.mva,
        f0=case.freq_hz,
        governor=Governors.from_case(case),
        qaxis=QAxis.from_case(case),
    )


def _series_impedance(case: Case, term: int, bus: int) -> complex:
    """Series impedance (pu) of the branches joining bus numbers term and bus, in
    parallel; 0 when they are the same bus."""
    if term == bus:
        return 0j
    br = case.branches
    sel = ((br.from_bus == term) & (br.to_bus == bus)) | (
        (br.from_bus == bus) & (br.to_bus == term)
    )
    return complex(1.0 / np.sum(1.0 / (br.r[sel] + 1j * br.x[sel])))


# -- centre of inertia ------------------------------------------------------------------------
def coi_speed(speed: np.ndarray, var: np.ndarray, inertia: np.ndarray):
    """COI speed sum(M_i w_i) / sum(M_i) (paper eq. 40, M = H*MVA) and its variance, the
    machine estimates taken as independent (one filter per machine, independent PMU
    noise).  speed, var: (..., n) pu, pu^2, machines on the last axis; returns (...)."""
    w = coi_weights(inertia)
    return speed @ w, var @ w**2


def relative_speeds(
    speed: np.ndarray, var: np.ndarray, inertia: np.ndarray, coi: str = "system"
) -> tuple[np.ndarray, np.ndarray]:
    """omega_i - omega_COI of every machine (pu) and its variance (pu^2), the COI of all
    machines (coi="system") or of the others (coi="rest"), as `stabctl.storage.devices.BangBangCOI`.
    speed, var: (..., n), machines on the last axis.

    With weights w = M / sum(M) and independent estimates: var = (1 - 2 w_i) s_i^2 +
    sum_j w_j^2 s_j^2 (system); s_i^2 + sum_{j != i} w_j^2 s_j^2 / (1 - w_i)^2 (rest).
    Raises InputError for another coi.
    """
    w = coi_weights(inertia)
    c, cv = coi_speed(speed, var, inertia)
    if coi == "system":
        return speed - c[..., None], (1 - 2 * w) * var + cv[..., None]
    if coi == "rest":
        rest = (c[..., None] - w * speed) / (1 - w)
        return speed - rest, var + (cv[..., None] - w**2 * var) / (1 - w) ** 2
    raise InputError(f"coi must be 'system' or 'rest', got {coi!r}")
