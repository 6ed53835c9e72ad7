"""Synchronous machine models: PST `mac_sub` (subtransient), `mac_tra` (transient), `mac_em`
(classical), vectorised over all machines of a case.

Source: PSTess 1.1 `mac_indx.m`, `mac_sub.m`, `mac_tra.m`, `mac_em.m`; the equations and
PST's parameter substitutions are written out in docs/pst_models.md section 1.

Frames: network phasors X (system frame, rotating at omega_s) and rotor dq quantities are
related by d + jq = j exp(-j delta) X, X = exp(j delta) (q - j d).
Bases: machine currents, reactances, H, D, pmech, Efd on the machine base; pelect and the
network currents on the system base; mac_pot = base_mva / machine MVA.
States per machine (6 slots): delta (rad), omega (pu speed), E'q, psi_kd, E'd (PST sign),
psi_kq; `mac_tra` uses the first four, `mac_em` the first two (the others stay constant).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .case import Case

SUB, TRA, EM = 2, 1, 0
STATE_NAMES = ("delta", "omega", "eqp", "psikd", "edp", "psikq")


@dataclass(frozen=True, eq=False)
class MachineParams:
    """Machine data after PST's substitutions, arrays of shape (n_mac,).

    `kind` is SUB/TRA/EM as PST's `mac_indx` chooses it: x_d = 0 -> classical; x"_d = 0 ->
    transient; otherwise subtransient.  Substitutions (docs/pst_models.md 1.2, 1.8):
    subtransient x"_q := x"_d, T'qo = 0 -> 999, T"qo = 0 -> 999 with x'_q := x"_q;
    transient x'_q := x'_d, T'qo = 0 -> 999.
    """

    kind: np.ndarray
    bus_idx: np.ndarray
    mac_pot: np.ndarray
    ra: np.ndarray
    xl: np.ndarray
    xd: np.ndarray
    xdp: np.ndarray
    xdpp: np.ndarray
    xq: np.ndarray
    xqp: np.ndarray
    xqpp: np.ndarray
    Tdop: np.ndarray
    Tdopp: np.ndarray
    Tqop: np.ndarray
    Tqopp: np.ndarray
    H: np.ndarray
    D0: np.ndarray
    pfrac: np.ndarray
    qfrac: np.ndarray
    sat: np.ndarray  # (n_mac, 3) quadratic saturation a, b, c
    basrad: float

    @property
    def n(self) -> int:
        return self.kind.size

    @property
    def x_network(self) -> np.ndarray:
        """Reactance behind which the internal voltage feeds the network (machine base)."""
        return np.where(self.kind == SUB, self.xdpp, self.xdp)

    @property
    def y_internal(self) -> np.ndarray:
        """Internal-node admittance on the system base, 1/(r_a + j x mac_pot) as PST's
        `red_ybus` (r_a is not converted to the system base there; zero in our cases)."""
        return 1.0 / (self.ra + 1j * self.x_network * self.mac_pot)

    # derived constants of mac_sub (PST mac_pot columns 6-15)
    @property
    def p7(self):
        return self.xd - self.xdp

    @property
    def p8(self):
        return self.xdp - self.xl

    @property
    def p9(self):
        return (self.xdpp - self.xl) / self.p8

    @property
    def p10(self):
        return (self.xdp - self.xdpp) / self.p8

    @property
    def p6(self):
        return self.p10 / self.p8

    @property
    def p12(self):
        return self.xq - self.xqp

    @property
    def p13(self):
        return self.xqp - self.xl

    @property
    def p14(self):
        return (self.xqpp - self.xl) / self.p13

    @property
    def p15(self):
        return (self.xqp - self.xqpp) / self.p13

    @property
    def p11(self):
        return self.p15 / self.p13


def machine_params(case: Case) -> MachineParams:
    """PST machine parameters of a case, with PST's substitutions (see MachineParams)."""
    m = case.machines
    kind = np.where(m.xd == 0, EM, np.where(m.xdpp == 0, TRA, SUB))
    sub, tra = kind == SUB, kind == TRA
    xqpp = np.where(sub, m.xdpp, m.xqpp)
    Tqopp0 = sub & (m.Tqopp == 0)
    xqp = np.where(Tqopp0, xqpp, np.where(tra, m.xdp, m.xqp))
    Tqop = np.where(m.Tqop == 0, 999.0, m.Tqop)
    Tqopp = np.where(m.Tqopp == 0, 999.0, m.Tqopp)
    return MachineParams(
        kind=kind, bus_idx=case.bus_indices(m.bus), mac_pot=case.base_mva / m.mva,
        ra=m.ra.copy(), xl=m.xl.copy(), xd=m.xd.copy(), xdp=m.xdp.copy(), xdpp=m.xdpp.copy(),
        xq=m.xq.copy(), xqp=xqp, xqpp=xqpp, Tdop=m.Tdop.copy(), Tdopp=m.Tdopp.copy(),
        Tqop=Tqop, Tqopp=Tqopp, H=m.H.copy(), D0=m.D0.copy(), pfrac=m.pfrac.copy(),
        qfrac=m.qfrac.copy(), sat=saturation_coefficients(m.S10, m.S12),
        basrad=2 * np.pi * case.freq_hz)


def saturation_coefficients(S10: np.ndarray, S12: np.ndarray) -> np.ndarray:
    """Quadratic E_sat(e) = a e^2 + b e + c through (0.8, 0.8), (1, 1 + S10),
    (1.2, 1.2 (1 + S12)) (PST `mac_sub`/`mac_tra` flag 0); shape (n, 3)."""
    A = np.array([[0.64, 0.8, 1.0], [1.0, 1.0, 1.0], [1.44, 1.2, 1.0]])
    rhs = np.vstack([np.full_like(S10, 0.8), 1 + S10, 1.2 * (1 + S12)])
    return np.linalg.solve(A, rhs).T


def to_dq(delta, X):
    """(d, q) components of network phasors X in the rotor frame of angle delta."""
    z = 1j * np.exp(-1j * delta) * X
    return z.real, z.imag


def from_dq(delta, d, q):
    """Network phasor of rotor-frame components (d, q)."""
    return np.exp(1j * delta) * (q - 1j * d)


def initialise(p: MachineParams, V: np.ndarray, S_gen: np.ndarray):
    """Machine states, field voltage and mechanical power from the solved power flow.

    Args:
        p: machine parameters.
        V: complex bus voltages (pu), shape (n_bus,).
        S_gen: complex generation per bus (pu, system base), shape (n_bus,).
    Returns:
        x (6, n_mac) states, vex (n_mac,) field voltage, pmech (n_mac,) machine base.
    Source: docs/pst_models.md 1.7-1.9 (PST flag 0).
    """
    v = V[p.bus_idx]
    S = S_gen[p.bus_idx].real * p.pfrac + 1j * S_gen[p.bus_idx].imag * p.qfrac
    I = np.conj(S / v) * p.mac_pot                       # terminal current, machine base
    x = np.zeros((6, p.n))
    x[1] = 1.0
    sub = p.kind == SUB
    E_q = v + (p.ra + 1j * p.xq) * I                    # locates the q axis (sub, tra)
    E_tr = v + (p.ra + 1j * p.xdp) * I
    E_em = v + 1j * p.xdp * I
    x[0] = np.where(p.kind == EM, np.angle(E_em), np.angle(E_q))
    curdg, curqg = to_dq(x[0], I)
    ed, eq = to_dq(x[0], v)
    pmech = np.where(p.kind == EM, S.real * p.mac_pot, S.real * p.mac_pot + p.ra * np.abs(I) ** 2)
    # subtransient
    eqra = eq + p.ra * curqg
    edra = -ed - p.ra * curdg
    eqp_sub, psikd = eqra + p.xdp * curdg, eqra + p.xl * curdg
    edp_sub, psikq = edra + p.xqp * curqg, edra + p.xl * curqg
    Eqpe = eqp_sub - psikd - p.p8 * curdg
    vex_sub = eqp_sub + p.p7 * (curdg + p.p6 * Eqpe)
    # transient / classical: E' in the rotor frame
    E = np.where(p.kind == EM, E_em, E_tr)
    edp_t, eqp_t = to_dq(x[0], E)
    a, b, c = p.sat.T
    esat = np.where(eqp_t < 0.8, eqp_t, a * eqp_t ** 2 + b * eqp_t + c)
    vex_tra = np.where(p.kind == EM, eqp_t, esat + (p.xd - p.xdp) * curdg)
    x[2] = np.where(sub, eqp_sub, eqp_t)
    x[3] = np.where(sub, psikd, 0.0)
    x[4] = np.where(sub, edp_sub, edp_t)
    x[5] = np.where(sub, psikq, 0.0)
    vex = np.where(sub, vex_sub, vex_tra)
    return x, vex, pmech


def subtransient_fluxes(p: MachineParams, x):
    """psi"_d and psi"_q of the subtransient model (machine base)."""
    return p.p9 * x[2] + p.p10 * x[3], p.p14 * x[4] + p.p15 * x[5]


def internal_voltage(p: MachineParams, x) -> np.ndarray:
    """Voltage behind the network reactance, network frame (PST flag 1), shape (n_mac,).

    Subtransient: speed * exp(j delta) (psi"_d + j psi"_q); transient and classical:
    exp(j delta) (E'q - j E'd).
    """
    psidpp, psiqpp = subtransient_fluxes(p, x)
    sub = x[1] * np.exp(1j * x[0]) * (psidpp + 1j * psiqpp)
    other = np.exp(1j * x[0]) * (x[2] - 1j * x[4])
    return np.where(p.kind == SUB, sub, other)


def derivatives(p: MachineParams, x, cur, vex, pmech, initial_eqp=None):
    """Machine state derivatives and outputs (PST flag 2).

    Args:
        x: states (6, n_mac); cur: terminal currents (system base, network frame);
        vex: field voltages; pmech: mechanical power (machine base);
        initial_eqp: E'q at t = 0 (PST's `mac_tra` saturation test uses it).
    Returns:
        dx (6, n_mac), pelect (system base), qelect, eterm (pu), fldcur.
    """
    delta, omega = x[0], x[1]
    curd, curq = to_dq(delta, cur)
    curdg, curqg = curd * p.mac_pot, curq * p.mac_pot
    dx = np.zeros_like(x)
    dx[0] = p.basrad * (omega - 1.0)
    # subtransient
    psidpp, psiqpp = subtransient_fluxes(p, x)
    Eqpe = x[2] - x[3] - p.p8 * curdg
    fld_sub = x[2] + p.p7 * (curdg + p.p6 * Eqpe)
    Edpe = x[4] - x[5] - p.p13 * curqg
    ed_s = -p.ra * curdg - (omega * psiqpp - p.xqpp * curqg)
    eq_s = -p.ra * curqg + (omega * psidpp - p.xdpp * curdg)
    Te_sub = psidpp * curqg - psiqpp * curdg
    # transient / classical
    e0 = x[2] if initial_eqp is None else initial_eqp
    a, b, c = p.sat.T
    esat = np.where(e0 < 0.8, x[2], a * x[2] ** 2 + b * x[2] + c)
    fld_tra = esat + (p.xd - p.xdp) * curdg
    ed_t = x[4] - p.ra * curdg + p.xdp * curqg
    eq_t = x[2] - p.ra * curqg - p.xdp * curdg
    ed_e, eq_e = x[4] + p.xdp * curqg, x[2] - p.xdp * curdg
    sub, tra = p.kind == SUB, p.kind == TRA
    ed = np.where(sub, ed_s, np.where(tra, ed_t, ed_e))
    eq = np.where(sub, eq_s, np.where(tra, eq_t, eq_e))
    pelect = eq * curq + ed * curd
    qelect = eq * curd - ed * curq
    Te_other = np.where(tra, pelect * p.mac_pot + p.ra * (curdg ** 2 + curqg ** 2),
                        pelect * p.mac_pot)
    fldcur = np.where(sub, fld_sub, np.where(tra, fld_tra, x[2]))
    dx[2] = np.where(p.kind == EM, 0.0, (vex - fldcur) / p.Tdop)
    dx[3] = np.where(sub, Eqpe / p.Tdopp, 0.0)
    dx[4] = np.where(sub, (-x[4] + p.p12 * (-curqg - p.p11 * Edpe)) / p.Tqop,
                     np.where(tra, (-x[4] + (p.xq - p.xqp) * curqg) / p.Tqop, 0.0))
    dx[5] = np.where(sub, Edpe / p.Tqopp, 0.0)
    torque = np.where(sub, pmech / omega - Te_sub, pmech - Te_other)
    dx[1] = (torque - p.D0 * (omega - 1.0)) / (2 * p.H)
    return dx, pelect, qelect, np.hypot(ed, eq), fldcur


def stator_voltage_without_speed(p: MachineParams, x, cur):
    """Terminal voltage components from the subtransient stator equations without the speed
    factor (PST `exc_st3` flag 1 recomputes them this way): (ed, eq, curd, curq)."""
    curd, curq = to_dq(x[0], cur)
    curdg, curqg = curd * p.mac_pot, curq * p.mac_pot
    psidpp, psiqpp = subtransient_fluxes(p, x)
    ed = -p.ra * curdg - (psiqpp - p.xqpp * curqg)
    eq = -p.ra * curqg + (psidpp - p.xdpp * curdg)
    return ed, eq, curd, curq
