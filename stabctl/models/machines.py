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

from typing import TYPE_CHECKING, Any

import numpy as np

from stabctl._jit.arrays import magnitude
from stabctl._jit.decorators import kernel
from stabctl.models.declaration import (
    Declared,
    DyrModel,
    Family,
    Param,
    check_packed,
    layout,
    pack,
    params_class,
    states,
)
from stabctl.models.saturation import exponential_fit, quadratic_fit

if TYPE_CHECKING:
    from stabctl.case import Case


# --------------------------------------------------------------------------------------
# mac_con: synchronous machines (PST manual 3.22 Table 10)
# --------------------------------------------------------------------------------------

_REACT: dict[str, Any] = dict(unit="pu", lo=0.0)
_TC: dict[str, Any] = dict(unit="s", lo=0.0)

#: GENROU's and GENROE's parameters (PSS/E Model Library order) and the mac_con fields
#: each is copied to
_ROUND_ROTOR = (
    "T'do",
    "T''do",
    "T'qo",
    "T''qo",
    "H",
    "D",
    "Xd",
    "Xq",
    "X'd",
    "X'q",
    "X''d",
    "Xl",
    "S(1.0)",
    "S(1.2)",
)
_ROUND_ROTOR_COPY = {
    "Tdop": "T'do",
    "Tdopp": "T''do",
    "Tqop": "T'qo",
    "Tqopp": "T''qo",
    "H": "H",
    "D0": "D",
    "xd": "Xd",
    "xq": "Xq",
    "xdp": "X'd",
    "xqp": "X'q",
    "xdpp": "X''d",
    "xl": "Xl",
    "S10": "S(1.0)",
    "S12": "S(1.2)",
}
#: GENSAL's and GENSAE's: GENROU's without T'qo and X'q
_SALIENT_POLE = tuple(f for f in _ROUND_ROTOR if f not in ("T'qo", "X'q"))
_SALIENT_POLE_COPY = {k: v for k, v in _ROUND_ROTOR_COPY.items() if v in _SALIENT_POLE}

MACHINE = Family(
    table="mac_con",
    min_columns=16,
    key="number",
    key_label="machine",
    params=(
        Param("number", "code", 1, integer=True, doc="machine number"),
        Param("bus", "code", 2, integer=True, doc="bus number"),
        Param("mva", "MVA", 3, doc="machine base"),
        Param("xl", col=4, doc="leakage reactance", **_REACT),
        Param("ra", col=5, doc="armature resistance", **_REACT),
        Param("xd", col=6, doc="d-axis synchronous reactance (0: classical model)", **_REACT),
        Param("xdp", col=7, doc="d-axis transient reactance x'd", **_REACT),
        Param(
            "xdpp", col=8, doc='d-axis subtransient reactance x"d (0: transient model)', **_REACT
        ),
        Param("Tdop", col=9, doc="d-axis open-circuit transient time constant T'do", **_TC),
        Param("Tdopp", col=10, doc='d-axis open-circuit subtransient time constant T"do', **_TC),
        Param("xq", col=11, doc="q-axis synchronous reactance", **_REACT),
        Param("xqp", col=12, doc="q-axis transient reactance x'q", **_REACT),
        Param("xqpp", col=13, doc='q-axis subtransient reactance x"q', **_REACT),
        Param(
            "Tqop", col=14, doc="q-axis open-circuit transient time constant T'qo (0 kept)", **_TC
        ),
        Param("Tqopp", col=15, doc='q-axis open-circuit subtransient time constant T"qo', **_TC),
        Param("H", "s", 16, doc="inertia constant (MW s / MVA on machine base)"),
        Param(
            "D0",
            "pu",
            17,
            lo=0.0,
            doc="local damping coefficient d_o (>= 0: a damping torque opposes the speed "
            "deviation)",
        ),
        Param("D1", "pu", 18, doc="system damping coefficient d_1"),
        Param("col19", "", 19, doc='"bus number" in the manual; unused by PSTess, kept as given'),
        Param("S10", "", 20, doc="saturation factor S(1.0)"),
        Param("S12", "", 21, doc="saturation factor S(1.2)"),
        Param("pfrac", "", 22, default=1.0, doc="fraction of the bus generation P"),
        Param("qfrac", "", 23, default=1.0, doc="fraction of the bus generation Q"),
        Param(
            "speed_effects",
            "code",
            24,
            default=1.0,
            choices=(0.0, 1.0),
            doc="subtransient: 1 stator voltage and torque with speed (PST mac_sub), "
            "0 without (ANDES GENROU/GENSAL; PSS/E's stator, with psse_swing 1)",
        ),
        Param(
            "psse_sat",
            "code",
            25,
            default=0.0,
            choices=(0.0, 1.0, 2.0, 3.0, 4.0),
            doc="subtransient: PSS/E's saturation through S(1.0), S(1.2) (PSS/E Model "
            "Library): 0 none (PST mac_sub as modelled here); of the air-gap flux "
            '|psi"| on both axes, 1 quadratic (GENROU; ANDES GENROU/GENSAL), 2 '
            "exponential (GENROE), 4 exponential with the q axis's in its subtransient "
            "circuit (GENSAE, salient pole); 3 quadratic of E'q on the d axis only "
            "(GENSAL)",
        ),
        Param(
            "playback",
            "code",
            26,
            choices=(0.0, 1.0),
            doc="classical with H = 0: 1 a playback source (ANDES PLBVFU1): E' and the "
            "speed follow their targets (a Playback event) through the lags pb_Tv, pb_Tf",
        ),
        Param("pb_Tv", "s", 27, default=0.2, lo=0.0, doc="playback: lag of E' to its target"),
        Param(
            "pb_Tf", "s", 28, default=0.2, lo=0.0, doc="playback: lag of the speed to its target"
        ),
        Param(
            "psse_swing",
            "code",
            29,
            choices=(0.0, 1.0),
            doc="swing equation: 0 P_m / omega - T_e - D (omega - 1) with speed effects, "
            "P_m - T_e - D (omega - 1) without (PST); 1 PSS/E's (P_m - D (omega - 1)) / "
            "omega - T_e, the stator as speed_effects says (PSS/E Model Library GENROU, "
            "GENROE, GENSAL, GENSAE: stator at rated speed, speed_effects 0)",
        ),
    ),
    dyr=(
        # GENROU (GENROE: exponential saturation) -> mac_sub with x"q = x"d (set by the
        # importer)
        DyrModel("GENROU", _ROUND_ROTOR, _ROUND_ROTOR_COPY, andes=("GENROU",)),
        DyrModel("GENROE", _ROUND_ROTOR, _ROUND_ROTOR_COPY),
        # GENSAL (GENSAE: exponential saturation) -> mac_sub without the q-axis transient
        # circuit (x'q = x_q, T'qo = 0)
        DyrModel("GENSAL", _SALIENT_POLE, _SALIENT_POLE_COPY),
        DyrModel("GENSAE", _SALIENT_POLE, _SALIENT_POLE_COPY),
        # GENCLS -> mac_em behind x'd = ZSORCE X (set by the importer)
        DyrModel(
            "GENCLS",
            ("H", "D"),
            {"H": "H", "D0": "D"},
            andes=("GENCLS",),
        ),
    ),
)

SUB, TRA, EM = 2, 1, 0
STATE_NAMES = ("delta", "omega", "eqp", "psikd", "edp", "psikq")
#: the named slots of the machine states (`STATE_NAMES`), read by the kernels as
#: ``x[S.eqp, i]``: rotor angle (rad), speed (pu), E'q, psi_kd, E'd, psi_kq (pu)
S = states("MachineStates", STATE_NAMES)

#: mac_con fields (stabctl.models.machines.MACHINE) of MachineParams: columns 4-17 (xl .. D0,
#: after PST's substitutions) and the generation fractions pfrac, qfrac (22, 23)
TABLE_FIELDS = (*MACHINE.names[MACHINE.col("xl") - 1 : MACHINE.col("D0")], "pfrac", "qfrac")
#: packed parameter matrix of the kernels, (column name, MachineParams attribute) per
#: column: kind, mac_pot, mac_con columns 4-17 in declared order, PST's derived constants
#: (mac_pot columns 6-15), saturation, initial E'q, speed effects, PSS/E's saturation A, B,
#: gamma_qd and kind (mac_con psse_sat), the playback lags and PSS/E's swing equation
PACKED = (
    ("KIND", "kind"),
    ("POT", "mac_pot"),
    *((n.upper(), n) for n in TABLE_FIELDS[:-2]),
    *((f"P{k}", f"p{k}") for k in range(6, 16)),
    ("SA", "sat_a"),
    ("SB", "sat_b"),
    ("SC", "sat_c"),
    ("EQP0", "eqp0"),
    ("SPEED", "speed_effects"),
    ("GA", "gap_a"),
    ("GB", "gap_b"),
    ("GQD", "gqd"),
    ("PB", "playback"),
    ("PB_TV", "pb_Tv"),
    ("PB_TF", "pb_Tf"),
    ("GK", "sat_kind"),
    ("SWING", "psse_swing"),
)
#: the kernels' column of each PACKED name: P[i, K.XDP]
K = layout("MachineColumns", PACKED)


@params_class(("kind", "bus_idx", "mac_pot"), TABLE_FIELDS)
class MachineParams(Declared):
    """Machine data after PST's substitutions, arrays of shape (n_mac,).

    `kind` is SUB/TRA/EM as PST's `mac_indx` chooses it: x_d = 0 -> classical; x"_d = 0 ->
    transient; otherwise subtransient.  Substitutions (docs/pst_models.md 1.2, 1.8):
    subtransient x"_q := x"_d, T'qo = 0 -> 999, T"qo = 0 -> 999 with x'_q := x"_q;
    transient x'_q := x'_d, T'qo = 0 -> 999.  Fields: ``kind``, ``bus_idx`` (the bus's
    row), ``mac_pot`` (system base / machine base), the mac_con fields
    :data:`TABLE_FIELDS` under their declared names (stabctl.models.machines.MACHINE), then
    the derived ones below.
    """

    sat: np.ndarray  # (n_mac, 3) quadratic saturation a, b, c
    basrad: float
    speed_effects: np.ndarray  # bool: subtransient with speed in stator voltage and torque
    air_gap_sat: np.ndarray  # (n_mac, 2) A, B of PSS/E's saturation (0, 0: none)
    sat_kind: np.ndarray  # PSS/E's saturation: mac_con psse_sat of subtransient machines, else 0
    psse_swing: np.ndarray  # 1.0: PSS/E's swing equation (P_m - D (omega - 1)) / omega - T_e
    playback: np.ndarray  # 1.0: a playback source (classical, H = 0; docs/pst_models.md 17)
    pb_Tv: np.ndarray  # s, its E' lag
    pb_Tf: np.ndarray  # s, its speed lag

    @property
    def n(self) -> int:
        return self.kind.size

    def packed(self, eqp0: np.ndarray) -> np.ndarray:
        """Parameter matrix (n_mac, len(PACKED)) for the compiled kernels; eqp0 = initial E'q."""
        with np.errstate(divide="ignore", invalid="ignore"):  # mac_em: 0/0 constants unused
            return self._packed(eqp0)

    def _packed(self, eqp0):
        sat = {f"sat_{c}": self.sat[:, k] for k, c in enumerate("abc")}
        return np.nan_to_num(
            pack(
                self,
                PACKED,
                eqp0=eqp0,
                gap_a=self.air_gap_sat[:, 0],
                gap_b=self.air_gap_sat[:, 1],
                **sat,
            )
        )

    def subtransient_time_constants(self, xe: np.ndarray) -> np.ndarray:
        """Each machine's shortest subtransient time constant (s) with its stator closed
        through the reactance `xe` (machine base): T"do (x"d + xe)/(x'd + xe) and T"qo
        (x"q + xe)/(x'q + xe), the shorter; inf where the machine is not subtransient.
        At a bolted fault at its terminal (xe = 0) these are the short-circuit time
        constants T"d = T"do x"d/x'd and T"q (Kundur, Power System Stability and Control,
        section 4.1.4, the external reactance added to the stator's).

        Parameters
        ----------
        xe : ndarray, shape (n_mac,)
            External reactance of each machine, pu on its base, >= 0.

        Returns
        -------
        ndarray, shape (n_mac,)
        """
        xe = np.maximum(np.asarray(xe, float), 0.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            d = self.Tdopp * (self.xdpp + xe) / (self.xdp + xe)
            q = self.Tqopp * (self.xqpp + xe) / (self.xqp + xe)
        t = np.fmin(d, q)
        return np.where((self.kind == SUB) & (t > 0), t, np.inf)

    @property
    def x_network(self) -> np.ndarray:
        """Reactance behind which the internal voltage feeds the network (machine base)."""
        return np.where(self.kind == SUB, self.xdpp, self.xdp)

    @property
    def ra_network(self) -> np.ndarray:
        """Armature resistance behind which the internal voltage feeds the network (machine
        base): r_a for `mac_sub`/`mac_tra`, whose initialisation and stator equations use
        it; 0 for `mac_em`, which has no r_a anywhere in its equations (PST mac_em: E' =
        v + j x'_d I, pmech = pelect); also the estimators' machine model."""
        return np.where(self.kind == EM, 0.0, self.ra)

    @property
    def z_internal(self) -> np.ndarray:
        """Internal impedance on the system base, (r_a + j x) mac_pot (see y_internal)."""
        return (self.ra_network + 1j * self.x_network) * self.mac_pot

    @property
    def y_internal(self) -> np.ndarray:
        """Internal-node admittance on the system base, 1/((r_a + j x) mac_pot) as PST's
        `red_ybus`: the machine-base impedance r_a + j x converted to the system base, so
        that the network current is the one the stator equations (machine base, currents
        times mac_pot) and the flag-0 initialisation E = v + (r_a + j x) I assume.  With r_a
        left on the machine base here a flat run drifts (Kundur, r_a = 0.003: 4e-4 pu speed
        in 1 s).  Deviation from PST for `mac_em` with r_a != 0 only: PST's red_ybus puts
        r_a into the network although mac_em ignores it, so PST drifts there; we use
        `ra_network` (0) to keep the classical model's flat start exact."""
        return 1.0 / self.z_internal

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

    @property
    def gqd(self):
        """gamma_qd = (x_q - x_l) / (x_d - x_l): the q-axis share of the air-gap saturation
        (ANDES ``genrou.py`` ``gqd``)."""
        return (self.xq - self.xl) / (self.xd - self.xl)

    def psse_saturation(self, psi):
        """PSS/E's S_e(psi) per machine (`sat_kind`): quadratic B (psi - A)^2 / psi, 0 for
        psi <= A (GENROU, GENSAL; ANDES ``genrou.py`` ``Se``, ``Se0``), or exponential B
        psi^A (GENROE, GENSAE); 0 without saturation; psi (n_mac,): the air-gap flux
        magnitude |psi"| (GENROU, GENROE) or E'q (GENSAL, GENSAE)."""
        A, B = self.air_gap_sat.T
        exp = np.isin(self.sat_kind, _EXPONENTIAL)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            quad = np.where(psi > A, B * (psi - A) ** 2 / psi, 0.0)
            return np.where(self.sat_kind == 0, 0.0, np.where(exp, B * np.abs(psi) ** A, quad))


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
        kind=kind,
        bus_idx=case.bus_indices(m.bus),
        mac_pot=case.base_mva / m.mva,
        ra=m.ra.copy(),
        xl=m.xl.copy(),
        xd=m.xd.copy(),
        xdp=m.xdp.copy(),
        xdpp=m.xdpp.copy(),
        xq=m.xq.copy(),
        xqp=xqp,
        xqpp=xqpp,
        Tdop=m.Tdop.copy(),
        Tdopp=m.Tdopp.copy(),
        Tqop=Tqop,
        Tqopp=Tqopp,
        H=m.H.copy(),
        D0=m.D0.copy(),
        pfrac=m.pfrac.copy(),
        qfrac=m.qfrac.copy(),
        sat=saturation_coefficients(m.S10, m.S12),
        basrad=2 * np.pi * case.freq_hz,
        speed_effects=sub & (m.speed_effects == 1),
        playback=_playback(m, kind),
        pb_Tv=m.pb_Tv.copy(),
        pb_Tf=m.pb_Tf.copy(),
        air_gap_sat=_psse_saturation_fit(m, sub),
        sat_kind=np.where(sub, m.psse_sat, 0.0),
        psse_swing=m.psse_swing.copy(),
    )


#: psse_sat codes: saturation of the air-gap flux on both axes (GENROU, GENROE, GENSAE),
#: of E'q on the d axis (GENSAL); exponential (GENROE, GENSAE), the others quadratic;
#: GENSAE's q-axis saturation acts in its subtransient circuit (salient pole: no q-axis
#: transient circuit), GENROU's and GENROE's in the transient one
_AIR_GAP = (1.0, 2.0, 4.0)
_EXPONENTIAL = (2.0, 4.0)
_SALIENT_GAP = 4.0


def _psse_saturation_fit(m, sub) -> np.ndarray:
    """(n_mac, 2) A, B of each subtransient machine's PSS/E saturation (mac_con psse_sat)
    through (1.0, S(1.0)), (1.2, S(1.2)); (0, 0) without."""
    what = "mac_con row {row}: PSS/E saturation points (1.0, S(1.0)), (1.2, S(1.2))"
    exp = np.isin(m.psse_sat, _EXPONENTIAL)
    quad = quadratic_fit(1.0, m.S10, 1.2, m.S12, sub & (m.psse_sat > 0) & ~exp, what)
    expo = exponential_fit(1.0, m.S10, 1.2, m.S12, sub & exp, what)
    return np.column_stack([np.where(exp, e, q) for q, e in zip(quad, expo)])


check_packed(MachineParams, PACKED, ("eqp0", "gap_a", "gap_b", "sat_a", "sat_b", "sat_c"))


def _playback(m, kind) -> np.ndarray:
    """The playback flags (1.0 a playback source); CaseError for one that is not classical
    with H = 0 and r_a = 0 (its E' behind x'_d, its speed its target's) or whose lags are
    below 1e-3 s, naming the mac_con row."""
    pb = m.playback == 1
    for r in np.flatnonzero(pb & ((kind != EM) | (m.H != 0) | (m.ra != 0))):
        m._fail(r, "playback", "a playback source is classical (x_d = 0) with H = 0, r_a = 0")
    for name in ("pb_Tv", "pb_Tf"):
        for r in np.flatnonzero(pb & (getattr(m, name) < 1e-3)):
            m._fail(r, name, "a playback lag must be >= 0.001 s")
    return pb.astype(float)


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
    S_mac = S_gen[p.bus_idx].real * p.pfrac + 1j * S_gen[p.bus_idx].imag * p.qfrac
    I = np.conj(S_mac / v) * p.mac_pot  # terminal current, machine base
    x = np.zeros((len(STATE_NAMES), p.n))
    x[S.omega] = 1.0
    sub = p.kind == SUB
    # the q axis (sub, tra): along v + (r_a + j x_q) I, i.e. psi" + j (x_q - x"q) I with the
    # air-gap flux psi" = v + (r_a + j x"q) I; with PSS/E's GENROU saturation along
    # (1 + gamma_qd S_e0) psi" + j (x_q - x"q) I (ANDES genrou.py delta0: |psi"| (1 + S_e0
    # gamma_qd) against |I| (x"q - x_q)), where the q-axis flux equation is 0
    psi_pp = v + (p.ra + 1j * p.xqpp) * I
    air_gap = np.isin(p.sat_kind, _AIR_GAP)
    Se0 = np.where(air_gap, p.psse_saturation(np.abs(psi_pp)), 0.0)
    with np.errstate(invalid="ignore"):
        gap_q = np.where(Se0 > 0, p.gqd * Se0, 0.0)
    E_q = (1 + gap_q) * psi_pp + 1j * (p.xq - p.xqpp) * I
    E_tr = v + (p.ra + 1j * p.xdp) * I
    E_em = v + 1j * p.xdp * I
    x[S.delta] = np.where(p.kind == EM, np.angle(E_em), np.angle(E_q))
    curdg, curqg = to_dq(x[S.delta], I)
    ed, eq = to_dq(x[S.delta], v)
    pmech = np.where(
        p.kind == EM, S_mac.real * p.mac_pot, S_mac.real * p.mac_pot + p.ra * np.abs(I) ** 2
    )
    # subtransient
    eqra = eq + p.ra * curqg
    edra = -ed - p.ra * curdg
    eqp_sub, psikd = eqra + p.xdp * curdg, eqra + p.xl * curdg
    edp_sub, psikq = edra + p.xqp * curqg, edra + p.xl * curqg
    # GENSAE: E'd = 0 (no q-axis transient circuit), psi"_q = p15 psi_kq
    salient_gap = p.sat_kind == _SALIENT_GAP
    with np.errstate(divide="ignore", invalid="ignore"):
        edp_sub = np.where(salient_gap, 0.0, edp_sub)
        psikq = np.where(salient_gap, (edra + p.xqpp * curqg) / p.p15, psikq)
    Eqpe = eqp_sub - psikd - p.p8 * curdg
    # PSS/E's GENSAL, GENSAE: S_e(E'q) E'q on the d axis (no q-axis saturation)
    Se_eqp = np.where(sub & ~air_gap, p.psse_saturation(eqp_sub), 0.0)
    vex_sub = (
        eqp_sub
        + p.p7 * (curdg + p.p6 * Eqpe)
        + Se0 * to_dq(x[S.delta], psi_pp)[1]
        + Se_eqp * eqp_sub
    )
    # transient / classical: E' in the rotor frame
    E = np.where(p.kind == EM, E_em, E_tr)
    edp_t, eqp_t = to_dq(x[S.delta], E)
    a, b, c = p.sat.T
    esat = np.where(eqp_t < 0.8, eqp_t, a * eqp_t**2 + b * eqp_t + c)
    vex_tra = np.where(p.kind == EM, eqp_t, esat + (p.xd - p.xdp) * curdg)
    x[S.eqp] = np.where(sub, eqp_sub, eqp_t)
    x[S.psikd] = np.where(sub, psikd, 0.0)
    x[S.edp] = np.where(sub, edp_sub, edp_t)
    x[S.psikq] = np.where(sub, psikq, 0.0)
    vex = np.where(sub, vex_sub, vex_tra)
    return x, vex, pmech


# -- compiled runtime kernels (PST flag 1 and flag 2), one loop over machines -----------
# P is MachineParams.packed(); x the machine block of the state vector, shape (6, n_mac).


@kernel
def _fluxes(P, x, i):
    """psi"_d, psi"_q of machine i (subtransient model)."""
    return (
        P[i, K.P9] * x[S.eqp, i] + P[i, K.P10] * x[S.psikd, i],
        P[i, K.P14] * x[S.edp, i] + P[i, K.P15] * x[S.psikq, i],
    )


@kernel
def _dq(delta, X):
    """(d, q) of the network phasor X in the rotor frame: d + jq = j exp(-j delta) X."""
    return _dq_at(np.exp(-1j * delta), X)


@kernel
def _dq_at(back, X):
    """`_dq` with the rotation back = exp(-j delta) given (the conjugate of `internal_voltage`'s
    rot, bit for bit: the cosine is even and the sine odd)."""
    z = 1j * back * X
    return z.real, z.imag


@kernel
def _stator_speed(P, x, i):
    """Speed in the subtransient stator voltage and torque: omega with speed effects (PST
    mac_sub), 1 without (ANDES GENROU)."""
    return x[S.omega, i] if P[i, K.SPEED] > 0 else 1.0


@kernel
def divides_pmech_by_speed(P, i):
    """Whether machine i's swing equation takes P_m / omega as its torque (subtransient
    with speed effects, PST mac_sub; PSS/E's swing equation, mac_con psse_swing) rather
    than P_m (ANDES GENROU, mac_tra, mac_em)."""
    return (P[i, K.KIND] == SUB and P[i, K.SPEED] > 0) or P[i, K.SWING] > 0


@kernel
def internal_voltage(P, x, psi, rot):
    """Voltage behind the network reactance, network frame (PST flag 1), into psi (n_mac,),
    and each machine's rotation exp(j delta) into rot (n_mac,), for `field_currents` and
    `derivatives` (one sine and cosine per machine and evaluation instead of three).

    Subtransient: speed * exp(j delta) (psi"_d + j psi"_q) (speed 1 without speed
    effects); transient and classical: exp(j delta) (E'q - j E'd).
    """
    for i in range(P.shape[0]):
        e = np.exp(1j * x[S.delta, i])
        rot[i] = e
        if P[i, K.KIND] == SUB:
            psidpp, psiqpp = _fluxes(P, x, i)
            psi[i] = _stator_speed(P, x, i) * e * (psidpp + 1j * psiqpp)
        else:
            psi[i] = e * (x[S.eqp, i] - 1j * x[S.edp, i])


@kernel
def _psse_saturation(P, i, psi):
    """PSS/E's S_e(psi) of machine i (MachineParams.psse_saturation): quadratic B (psi -
    A)^2 / psi (0 for psi <= A) or exponential B psi^A (psse_sat 2, 4); 0 without."""
    if P[i, K.GB] == 0.0:
        return 0.0
    if P[i, K.GK] == 2.0 or P[i, K.GK] == 4.0:
        return P[i, K.GB] * abs(psi) ** P[i, K.GA]
    return P[i, K.GB] * (psi - P[i, K.GA]) ** 2 / psi if psi > P[i, K.GA] else 0.0


@kernel
def _gap_saturation(P, i, psidpp, psiqpp):
    """S_e(|psi"|) of machine i, PSS/E's GENROU (GENROE, GENSAE) saturation of the
    air-gap flux (ANDES ``genrou.py`` ``Se``); 0 without it and for GENSAL."""
    if P[i, K.GK] == 0.0 or P[i, K.GK] == 3.0:
        return 0.0
    return _psse_saturation(P, i, magnitude(psidpp, psiqpp))


@kernel
def _eqp_saturation(P, i, eqp):
    """S_e(E'q) E'q of machine i, PSS/E's GENSAL d-axis saturation; 0 otherwise."""
    if P[i, K.GK] != 3.0:
        return 0.0
    return _psse_saturation(P, i, eqp) * eqp


@kernel
def _air_gap_saturation(P, x, i):
    """S_e(|psi"|) of machine i at its state (`_gap_saturation`; 0 unless subtransient)."""
    if P[i, K.KIND] != SUB:
        return 0.0
    psidpp, psiqpp = _fluxes(P, x, i)
    return _gap_saturation(P, i, psidpp, psiqpp)


@kernel
def _field_current(P, x, i, cdg, gap):
    """Field current of machine i (machine base, vex = it in steady state) for the d-axis
    current cdg (machine base) and its air-gap saturation gap (`_air_gap_saturation`):
    subtransient E'q + p7 (i_d + p6 (E'q - psi_kd - p8 i_d)) (no saturation, docs 1.6)
    + S_e psi"_d with PSS/E's GENROU saturation (ANDES ``genrou.py`` ``XadIfd``) or
    + S_e(E'q) E'q with PSS/E's GENSAL's; transient E_Isat(E'q) + (x_d - x'_d) i_d (docs
    1.8, with PST's test on the initial E'q); classical: E' (constant)."""
    kind = P[i, K.KIND]
    e = x[S.eqp, i]
    if kind == SUB:
        psidpp = _fluxes(P, x, i)[0]
        return (
            e
            + P[i, K.P7] * (cdg + P[i, K.P6] * (e - x[S.psikd, i] - P[i, K.P8] * cdg))
            + gap * psidpp
            + _eqp_saturation(P, i, e)
        )
    if kind == TRA:
        esat = e if P[i, K.EQP0] < 0.8 else P[i, K.SA] * e * e + P[i, K.SB] * e + P[i, K.SC]
        return esat + (P[i, K.XD] - P[i, K.XDP]) * cdg
    return e


@kernel
def field_current(P, x, cur, rot, i):
    """Field current of machine i (machine base) at network current cur[i] (system base);
    rot: each machine's exp(j delta) (`internal_voltage`)."""
    cdg = _dq_at(np.conj(rot[i]), cur[i])[0] * P[i, K.POT]
    return _field_current(P, x, i, cdg, _air_gap_saturation(P, x, i))


@kernel
def field_currents(P, x, cur, rot, ifd, gap):
    """Field current of every machine (machine base) into ifd (n_mac,): `field_current`,
    computed once per evaluation for the exciters that read it and `derivatives`; rot:
    each machine's exp(j delta) (`internal_voltage`); its air-gap saturation into gap
    (n_mac,), which `derivatives` reads too."""
    for i in range(P.shape[0]):
        gap[i] = _air_gap_saturation(P, x, i)
        cdg = _dq_at(np.conj(rot[i]), cur[i])[0] * P[i, K.POT]
        ifd[i] = _field_current(P, x, i, cdg, gap[i])


@kernel
def derivatives(P, basrad, x, cur, rot, ifd, gap, vex, pmech, target, dx, pelect, qelect, eterm):
    """Machine derivatives into dx (6, n_mac) and outputs (PST flag 2, docs 1.6-1.9).

    cur: terminal currents (system base, network frame); rot: each machine's exp(j delta)
    (`internal_voltage`); ifd, gap: the field currents at cur (machine base) and the
    air-gap saturations (`field_currents`); vex: field voltages; pmech:
    mechanical power (machine base); target (n_mac, 2): a playback source's targets of
    E' and speed (pu; `playback` column, docs/pst_models.md 17).  pelect, qelect on the
    system base; eterm in pu.
    """
    for i in range(P.shape[0]):
        w = x[S.omega, i]
        ws = _stator_speed(P, x, i)
        curd, curq = _dq_at(np.conj(rot[i]), cur[i])
        pot = P[i, K.POT]
        cdg, cqg = curd * pot, curq * pot
        kind = P[i, K.KIND]
        dx[S.delta, i] = basrad * (w - 1.0)
        dx[S.psikd, i] = 0.0
        dx[S.psikq, i] = 0.0
        fld = ifd[i]
        if kind == SUB:
            psidpp, psiqpp = _fluxes(P, x, i)
            Eqpe = x[S.eqp, i] - x[S.psikd, i] - P[i, K.P8] * cdg
            Edpe = x[S.edp, i] - x[S.psikq, i] - P[i, K.P13] * cqg
            ed = -P[i, K.RA] * cdg - (ws * psiqpp - P[i, K.XQPP] * cqg)
            eq = -P[i, K.RA] * cqg + (ws * psidpp - P[i, K.XDPP] * cdg)
            dx[S.eqp, i] = (vex[i] - fld) / P[i, K.TDOP]
            dx[S.psikd, i] = Eqpe / P[i, K.TDOPP]
            # PSS/E's GENROU saturation: - gamma_qd S_e psi"_q (ANDES genrou.py XaqI1q, whose
            # e'_d, psi"_q are -E'd, -psi"_q here); GENSAE's in the subtransient circuit,
            # T"qo dpsi"_q/dt = -psi"_q - (x_q - x"q) i_q - gamma_qd S_e psi"_q
            gap_q = P[i, K.GQD] * gap[i] * psiqpp
            if P[i, K.GK] == _SALIENT_GAP:
                dx[S.edp, i] = (-x[S.edp, i] + P[i, K.P12] * (-cqg - P[i, K.P11] * Edpe)) / P[
                    i, K.TQOP
                ]
                dx[S.psikq, i] = (Edpe - gap_q / P[i, K.P15]) / P[i, K.TQOPP]
            else:
                dx[S.edp, i] = (
                    -x[S.edp, i] + P[i, K.P12] * (-cqg - P[i, K.P11] * Edpe) - gap_q
                ) / P[i, K.TQOP]
                dx[S.psikq, i] = Edpe / P[i, K.TQOPP]
            pm = pmech[i] / ws
            te = psidpp * cqg - psiqpp * cdg
        elif kind == TRA:
            ed = x[S.edp, i] - P[i, K.RA] * cdg + P[i, K.XDP] * cqg
            eq = x[S.eqp, i] - P[i, K.RA] * cqg - P[i, K.XDP] * cdg
            dx[S.eqp, i] = (vex[i] - fld) / P[i, K.TDOP]
            dx[S.edp, i] = (-x[S.edp, i] + (P[i, K.XQ] - P[i, K.XQP]) * cqg) / P[i, K.TQOP]
            pm = pmech[i]
            te = (eq * curq + ed * curd) * pot + P[i, K.RA] * (cdg**2 + cqg**2)
        else:
            ed = x[S.edp, i] + P[i, K.XDP] * cqg
            eq = x[S.eqp, i] - P[i, K.XDP] * cdg
            dx[S.eqp, i] = 0.0
            dx[S.edp, i] = 0.0
            pm = pmech[i]
            te = (eq * curq + ed * curd) * pot
        pelect[i] = eq * curq + ed * curd
        qelect[i] = eq * curd - ed * curq
        eterm[i] = magnitude(ed, eq)
        # H = 0: an infinite bus (classical, MachineTable), its speed held at 1 pu
        h2 = 2.0 * P[i, K.H]
        if P[i, K.SWING] > 0.0:  # PSS/E: (P_m - D (omega - 1)) / omega - T_e
            acc = (pmech[i] - P[i, K.D0] * (w - 1.0)) / w - te
        else:
            acc = (pm - te) - P[i, K.D0] * (w - 1.0)
        dx[S.omega, i] = acc / h2 if h2 > 0.0 else 0.0
        if P[i, K.PB] > 0.0:  # a playback source: E' and the speed lag their targets
            dx[S.omega, i] = (target[i, 1] - w) / P[i, K.PB_TF]
            dx[S.eqp, i] = (target[i, 0] - x[S.eqp, i]) / P[i, K.PB_TV]


@kernel
def stator_without_speed(P, x, cur, rot, i):
    """(ed, eq, curd, curq) of machine i from the subtransient stator equations without the
    speed factor (PST `exc_st3` flag 1 recomputes them this way); currents system base;
    rot: each machine's exp(j delta) (`internal_voltage`)."""
    curd, curq = _dq_at(np.conj(rot[i]), cur[i])
    pot = P[i, K.POT]
    psidpp, psiqpp = _fluxes(P, x, i)
    ed = -P[i, K.RA] * curd * pot - (psiqpp - P[i, K.XQPP] * curq * pot)
    eq = -P[i, K.RA] * curq * pot + (psidpp - P[i, K.XDPP] * curd * pot)
    return ed, eq, curd, curq


@kernel
def st3_field_current(P, x, cur, rot, i):
    """PST exc_st3's own field-current estimate E_Isat + p6 (E'q - psi_kd) + p7 i_d; rot:
    each machine's exp(j delta) (`internal_voltage`)."""
    e = x[S.eqp, i]
    esat = max(e, P[i, K.SA] * e * e + P[i, K.SB] * e + P[i, K.SC])
    curd = _dq_at(np.conj(rot[i]), cur[i])[0]
    return esat + P[i, K.P6] * (e - x[S.psikd, i]) + P[i, K.P7] * curd * P[i, K.POT]
