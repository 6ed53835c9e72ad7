"""Multi-mass torsional shafts: the five-mass spring-mass chain of a steam unit (HP, IP and
LP turbine sections, the generator rotor, the exciter), ANDES 2.0's ``SHAFT5``.

The generator rotor is the machine's own mass (its delta, omega and H); a shaft adds the
other four masses, eight states each (angle in electrical rad, speed in pu):
``dHP, wHP, dIP, wIP, dLP, wLP, dEX, wEX``.  Per mass i of inertia M_i = 2 H_i, with
springs K between neighbours, self damping D_i and mutual damping D_ij (machine base,
torque in pu per electrical rad and per pu speed)::

    d delta_i / dt = omega_b (omega_i - 1)
    M_HP d w_HP / dt = T_m - D_HP (w_HP - 1) - D_12 (w_HP - w_IP) + K_HP (d_IP - d_HP)
    M_IP d w_IP / dt = - D_IP (w_IP - 1) - D_12 (w_IP - w_HP) - D_23 (w_IP - w_LP)
                       + K_HP (d_HP - d_IP) + K_IP (d_LP - d_IP)
    M_LP d w_LP / dt = - D_LP (w_LP - 1) - D_23 (w_LP - w_IP) - D_34 (w_LP - omega)
                       + K_IP (d_IP - d_LP) + K_LP (delta - d_LP)
    M_EX d w_EX / dt = - D_EX (w_EX - 1) - D_45 (w_EX - omega) + K_EX (delta - d_EX)

The turbine's mechanical torque T_m (the governor's P_m, divided by w_HP where the machine
divides its own by the speed: PST's ``mac_sub``) drives the HP mass; the machine's swing
equation takes the shaft torque ``- D_34 (omega - w_LP) - D_45 (omega - w_EX) + K_LP (d_LP
- delta) + K_EX (d_EX - delta)`` in its place, keeping its own damping D.  At the operating
point every speed is 1 and each spring carries T_m0 up to the generator (d_LP = delta +
T_m0/K_LP, d_IP = d_LP + T_m0/K_IP, d_HP = d_IP + T_m0/K_HP, d_EX = delta).

Sources: ANDES 2.0 ``andes/models/shaft/shaft5.py`` (SHAFT5, its equations and
initialisation); F. Milano, Power System Modelling and Scripting (Springer 2010) section
15.1.10; P. Kundur, Power System Stability and Control (1994) section 15.5 (torsional
interaction, the multi-mass model).  docs/pst_models.md section 13.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.errors import CaseError
from stabctl.models import machines as mac
from stabctl.models.declaration import (
    Declared,
    Family,
    Param,
    check_packed,
    layout,
    pack,
    params_class,
    states,
)

if TYPE_CHECKING:
    from stabctl.case import Case

__all__ = [
    "SHAFT",
    "N_STATES",
    "STATE_NAMES",
    "ShaftParams",
    "shaft_params",
    "initialise",
    "rotor_torque",
    "derivatives",
]

_M: dict = dict(unit="s", lo=0.0)
_K: dict = dict(unit="pu", lo=0.0)
_D: dict = dict(unit="pu")

# --------------------------------------------------------------------------------------
# shaft_con: torsional shafts (stabctl's table; ANDES SHAFT5)
# --------------------------------------------------------------------------------------

SHAFT = Family(
    table="shaft_con",
    min_columns=9,
    key="machine",
    key_label="machine",
    params=(
        Param(
            "machine", "code", 1, integer=True, doc="machine number (its rotor: the generator mass)"
        ),
        Param("MHP", col=2, doc="HP turbine inertia M = 2H (MW s/MVA, machine base)", **_M),
        Param("MIP", col=3, doc="IP turbine inertia M = 2H", **_M),
        Param("MLP", col=4, doc="LP turbine inertia M = 2H", **_M),
        Param("MEX", col=5, doc="exciter inertia M = 2H", **_M),
        Param("KHP", col=6, doc="HP-IP shaft stiffness (pu torque per electrical rad)", **_K),
        Param("KIP", col=7, doc="IP-LP shaft stiffness", **_K),
        Param("KLP", col=8, doc="LP-generator shaft stiffness", **_K),
        Param("KEX", col=9, doc="generator-exciter shaft stiffness", **_K),
        Param("DHP", col=10, doc="HP self damping (pu torque per pu speed)", **_D),
        Param("DIP", col=11, doc="IP self damping", **_D),
        Param("DLP", col=12, doc="LP self damping", **_D),
        Param("DEX", col=13, doc="exciter self damping", **_D),
        Param("D12", col=14, doc="HP-IP mutual damping", **_D),
        Param("D23", col=15, doc="IP-LP mutual damping", **_D),
        Param("D34", col=16, doc="LP-generator mutual damping", **_D),
        Param("D45", col=17, doc="generator-exciter mutual damping", **_D),
    ),
)

STATE_NAMES = ("dHP", "wHP", "dIP", "wIP", "dLP", "wLP", "dEX", "wEX")
N_STATES = len(STATE_NAMES)
#: the named slots of a shaft's states (the masses' angles, rad, and speeds, pu), read by
#: the kernels as ``xs[S.wLP, k]``
S = states("ShaftStates", STATE_NAMES)
TABLE_FIELDS = SHAFT.names[1:]
#: packed parameter matrix of the kernels: the machine's row, then shaft_con columns 2-17
PACKED = (("MAC", "mac"), *((n, n) for n in TABLE_FIELDS))
#: the kernels' column of each PACKED name: P[k, T.KLP]
T = layout("ShaftColumns", PACKED)

#: the default step's share of a torsional mode (`ShaftParams.time_constants`): an
#: undamped mode of angular frequency w is listed as the time constant TORSIONAL_SHARE / w
TORSIONAL_SHARE = 0.1


@params_class(("mac",), TABLE_FIELDS)
class ShaftParams(Declared):
    """Shaft data, arrays of shape (n_shaft,): ``mac`` the machine's row, the shaft_con
    fields :data:`TABLE_FIELDS` under their declared names (:data:`SHAFT`), machine
    base; ``M_gen`` the generator rotor's M = 2H."""

    M_gen: np.ndarray

    @property
    def n(self) -> int:
        return self.mac.size

    def packed(self) -> np.ndarray:
        """Parameter matrix (n_shaft, len(PACKED)) for the compiled kernels."""
        return pack(self, PACKED)

    def torsional_frequencies(self, basrad: float) -> np.ndarray:
        """Undamped natural angular frequencies of each free chain HP-IP-LP-generator-
        exciter (rad/s; the generator unconnected to the network), shape (n_shaft, 4),
        ascending: the square roots of the eigenvalues of omega_b M^-1 K without the
        rigid-body mode; basrad is omega_b (rad/s)."""
        out = np.zeros((self.n, 4))
        for k in range(self.n):
            m = np.array([self.MHP[k], self.MIP[k], self.MLP[k], self.M_gen[k], self.MEX[k]])
            springs = (self.KHP[k], self.KIP[k], self.KLP[k], self.KEX[k])
            stiff = np.zeros((5, 5))
            for i, s in enumerate(springs):
                stiff[i : i + 2, i : i + 2] += s * np.array([[1.0, -1.0], [-1.0, 1.0]])
            lam = np.linalg.eigvals(stiff / m[:, None])
            out[k] = np.sqrt(basrad * np.sort(np.abs(lam.real))[1:])
        return out

    def time_constants(self, basrad: float):
        """(label, values, mask) for `stabctl.dynamics.grid.fastest_time_constant`: the
        fastest torsional mode w of each shaft as TORSIONAL_SHARE / w (s).  The explicit
        predictor-corrector (Heun) amplifies an undamped oscillation by 1 + (w h)^4 / 8
        per step, a growth rate of w (w h)^3 / 8 against the shaft's small damping: at the
        default step, half this value, w h = 0.05 and the rate is at most w 1.6e-5 1/s
        (0.005 1/s at 50 Hz)."""
        w = self.torsional_frequencies(basrad)[:, -1]
        return (("shaft_con torsional mode 0.1/w", TORSIONAL_SHARE / w, np.ones(self.n, bool)),)


check_packed(ShaftParams, PACKED)


#: the masses and stiffnesses the model divides by or needs positive
POSITIVE = ("MHP", "MIP", "MLP", "MEX", "KHP", "KIP", "KLP", "KEX")


def check_table(s) -> None:
    """Refuse a shaft_con row the model cannot run, as the table is made (the table's
    `_require`, naming the row and field): a mass or stiffness of :data:`POSITIVE` not
    > 0.

    Parameters
    ----------
    s : stabctl.case.ShaftTable
        The shafts.

    Raises
    ------
    CaseError
        The first row and field refused.
    """
    s._positive(*POSITIVE)


def shaft_params(case: Case) -> ShaftParams:
    """Shaft parameters of a case.

    Raises
    ------
    CaseError
        A shaft on an infinite bus (H = 0), naming the shaft_con row (its masses and
        stiffnesses checked as the table was made, `check_table`).
    """
    s = case.shafts
    rows = np.array([case.machine_index(m) for m in s.machine], int)
    H = case.machines.H[rows] if rows.size else np.zeros(0)
    for r in range(len(s)):
        if H[r] <= 0:
            raise CaseError(
                f"shaft_con row {r + 1}, field 'machine': machine {int(s.machine[r])} is an "
                "infinite bus (H = 0); a shaft needs a rotor that moves"
            )
    return ShaftParams(mac=rows, **{n: getattr(s, n).copy() for n in TABLE_FIELDS}, M_gen=2 * H)


def initialise(p: ShaftParams, delta0: np.ndarray, tm0: np.ndarray) -> np.ndarray:
    """Shaft states at the operating point, shape (N_STATES, n_shaft): every speed 1, the
    angles twisted by the mechanical torque each spring carries (ANDES shaft5.py v_str).

    Parameters
    ----------
    p : ShaftParams
        The shafts.
    delta0, tm0 : ndarray, shape (n_shaft,)
        The generator rotor's angle (rad) and the turbine's torque (machine base: the
        initial P_m, the speed being 1).

    Returns
    -------
    ndarray, shape (8, n_shaft)
    """
    x = np.ones((N_STATES, p.n))
    x[S.dEX] = delta0
    x[S.dLP] = delta0 + tm0 / p.KLP
    x[S.dIP] = x[S.dLP] + tm0 / p.KIP
    x[S.dHP] = x[S.dIP] + tm0 / p.KHP
    return x


@kernel
def rotor_torque(P, xs, k, delta, omega):
    """The shaft torque on the generator rotor of shaft k (machine base), the LP and
    exciter springs and mutual dampers, which replaces the turbine torque in its swing
    equation."""
    return (
        -P[k, T.D34] * (omega - xs[S.wLP, k])
        - P[k, T.D45] * (omega - xs[S.wEX, k])
        + P[k, T.KLP] * (xs[S.dLP, k] - delta)
        + P[k, T.KEX] * (xs[S.dEX, k] - delta)
    )


@kernel
def derivatives(P, MP, basrad, xs, k, xm, pmech, dx):
    """Derivatives of shaft k's eight states into dx (8, n_shaft); xm the machines'
    states (6, n_mac), pmech the turbines' P_m (machine base), MP the machines' packed
    parameters (whether the machine divides P_m by its speed)."""
    m = int(P[k, T.MAC])
    delta, omega = xm[mac.S.delta, m], xm[mac.S.omega, m]
    w_hp, w_ip, w_lp, w_ex = xs[S.wHP, k], xs[S.wIP, k], xs[S.wLP, k], xs[S.wEX, k]
    d_hp, d_ip, d_lp, d_ex = xs[S.dHP, k], xs[S.dIP, k], xs[S.dLP, k], xs[S.dEX, k]
    speed = w_hp if mac.divides_pmech_by_speed(MP, m) else 1.0
    for d, w in ((S.dHP, S.wHP), (S.dIP, S.wIP), (S.dLP, S.wLP), (S.dEX, S.wEX)):
        dx[d, k] = basrad * (xs[w, k] - 1.0)
    dx[S.wHP, k] = (
        pmech[m] / speed
        - P[k, T.DHP] * (w_hp - 1.0)
        - P[k, T.D12] * (w_hp - w_ip)
        + P[k, T.KHP] * (d_ip - d_hp)
    ) / P[k, T.MHP]
    dx[S.wIP, k] = (
        -P[k, T.DIP] * (w_ip - 1.0)
        - P[k, T.D12] * (w_ip - w_hp)
        - P[k, T.D23] * (w_ip - w_lp)
        + P[k, T.KHP] * (d_hp - d_ip)
        + P[k, T.KIP] * (d_lp - d_ip)
    ) / P[k, T.MIP]
    dx[S.wLP, k] = (
        -P[k, T.DLP] * (w_lp - 1.0)
        - P[k, T.D23] * (w_lp - w_ip)
        - P[k, T.D34] * (w_lp - omega)
        + P[k, T.KIP] * (d_ip - d_lp)
        + P[k, T.KLP] * (delta - d_lp)
    ) / P[k, T.MLP]
    dx[S.wEX, k] = (
        -P[k, T.DEX] * (w_ex - 1.0) - P[k, T.D45] * (w_ex - omega) + P[k, T.KEX] * (delta - d_ex)
    ) / P[k, T.MEX]
