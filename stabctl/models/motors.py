"""Induction motors: ANDES 2.0's fifth-order double-cage motor ``Motor5`` (F. Milano, Power
System Modelling and Scripting, Springer 2010, section 15.2), a dynamic load at its bus.

States per motor (`STATE_NAMES`): the slip s and the first and second cage voltages
e'_d, e'_q, e"_d, e"_q (pu, system base), in the frame of ANDES's motor, where the bus
voltage is v_d + j v_q = j V (V the network phasor).  With the stator algebraic::

    j V - E" = (r_s + j x") (I_d + j I_q),   E" = e"_d + j e"_q

the motor draws I = (I_d + j I_q) / j = V / Z + j E" / Z from the network (Z = r_s + j x"):
a shunt admittance 1/Z at its bus while it is on (`stabctl.dynamics.model`, in the network
stage) and the current j E"/Z (the kernel).  Its dynamics::

    M ds/dt = T_m - T_e,   T_e = e"_d I_d + e"_q I_q,   T_m = a + b s + c_2 s^2
    de'_d/dt = w_b s e'_q - (e'_d + (x_0 - x') I_q) / T'_0
    de'_q/dt = -w_b s e'_d - (e'_q - (x_0 - x') I_d) / T'_0
    de"_d/dt = -w_b s (e'_q - e"_q) + de'_d/dt + (e'_d - e"_d - (x' - x") I_q) / T"_0
    de"_q/dt = w_b s (e'_d - e"_d) + de'_q/dt + (e'_q - e"_q + (x' - x") I_d) / T"_0

with x_0 = x_s + x_m, x' = x_s + x_r1 x_m/(x_r1 + x_m), x" = x_s + x_r1 x_r2 x_m/(x_r1
x_r2 + x_r1 x_m + x_r2 x_m), T'_0 = (x_r1 + x_m)/(w_b r_r1), T"_0 = (x_r2 + x_r1 x_m/(x_r1
+ x_m))/(w_b r_r2), M = 2 H_m, a = c_1 + c_2 + c_3, b = -c_2 - 2 c_3 (ANDES's
``motorbase.py``, ``motor5.py``; its quadratic term is c_2 s^2 where Milano's is c_3 s^2:
kept as ANDES).

A motor starts out of service and is switched on by a `stabctl.dynamics.events.MotorSwitch`
(ANDES: ``u = 0`` and a ``Toggle``): its states start at 0 (no flux, s = 0: energised at
synchronous speed, as ANDES's).  Off, it draws nothing and its states stand still.
docs/pst_models.md section 14.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel
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
    "MOTOR",
    "N_STATES",
    "STATE_NAMES",
    "MotorParams",
    "motor_params",
    "admittance",
    "drawn_current",
    "derivatives",
]

_Z: dict = dict(unit="pu", lo=0.0)

# --------------------------------------------------------------------------------------
# mot_con: induction motors (stabctl's table; ANDES Motor5)
# --------------------------------------------------------------------------------------

MOTOR = Family(
    table="mot_con",
    min_columns=4,
    key="number",
    key_label="motor",
    params=(
        Param("number", "code", 1, integer=True, doc="motor number"),
        Param("bus", "code", 2, integer=True, doc="bus number"),
        Param(
            "in_service",
            "code",
            3,
            choices=(0.0,),
            doc="0: out of service at the start, switched on by a MotorSwitch event (a "
            "motor in service in the power flow is not read)",
        ),
        Param("mva", "MVA", 4, default=100.0, lo=0.0, doc="motor base Sn"),
        Param("rs", col=5, default=0.01, doc="stator resistance (motor base)", **_Z),
        Param("xs", col=6, default=0.15, doc="stator reactance", **_Z),
        Param("rr1", col=7, default=0.05, doc="first cage rotor resistance", **_Z),
        Param("xr1", col=8, default=0.15, doc="first cage rotor reactance", **_Z),
        Param("rr2", col=9, default=0.001, doc="second cage rotor resistance", **_Z),
        Param("xr2", col=10, default=0.04, doc="second cage rotor reactance", **_Z),
        Param("xm", col=11, default=5.0, doc="magnetising reactance", **_Z),
        Param("Hm", "s", 12, default=3.0, lo=0.0, doc="inertia constant (motor base)"),
        Param("c1", "pu", 13, default=0.1, doc="load torque coefficient c_1 (motor base)"),
        Param("c2", "pu", 14, default=0.02, doc="load torque coefficient c_2"),
        Param("c3", "pu", 15, default=0.02, doc="load torque coefficient c_3"),
    ),
)

STATE_NAMES = ("slip", "e1d", "e1q", "e2d", "e2q")
N_STATES = len(STATE_NAMES)
#: the named slots of a motor's states, read by the kernels as ``x[S.slip, k]``
S = states("MotorStates", STATE_NAMES)
#: the system-base constants the kernels take
PACKED = (
    ("POS", "pos"),
    ("RS", "rs"),
    ("X0", "x0"),
    ("X1", "x1"),
    ("X2", "x2"),
    ("T10", "T10"),
    ("T20", "T20"),
    ("M", "M"),
    ("A", "a"),
    ("B", "b"),
    ("C2", "c2"),
    ("WB", "wb"),
)
#: the kernels' column of each PACKED name: P[k, Q.X2]
Q = layout("MotorColumns", PACKED)


@params_class(("pos", "bus_idx"), ())
class MotorParams(Declared):
    """Motor constants on the system base, arrays of shape (n_motor,): ``pos`` the bus's
    position among the kept buses (set by the dynamic model), ``bus_idx`` its row, the
    stator resistance rs, x0, x1 (x'), x2 (x"), the open-circuit time constants T10, T20
    (s), M = 2 Hm Sn/Sb (s), the load torque a, b, c2 (times Sn/Sb), wb = 2 pi f (rad/s)."""

    rs: np.ndarray
    x0: np.ndarray
    x1: np.ndarray
    x2: np.ndarray
    T10: np.ndarray
    T20: np.ndarray
    M: np.ndarray
    a: np.ndarray
    b: np.ndarray
    c2: np.ndarray
    wb: np.ndarray

    @property
    def n(self) -> int:
        return self.bus_idx.size

    def packed(self) -> np.ndarray:
        """Parameter matrix (n_motor, len(PACKED)) for the compiled kernels."""
        return pack(self, PACKED)

    @property
    def Z(self) -> np.ndarray:
        """The stator impedance r_s + j x" (system base), complex (n_motor,)."""
        return self.rs + 1j * self.x2

    def time_constants(self):
        """(label, values, mask) of the time constants that set the states' speed."""
        on = np.ones(self.n, bool)
        return (("mot_con T'0", self.T10, on), ('mot_con T"0', self.T20, on))


check_packed(MotorParams, PACKED)


#: the columns the model divides by or needs positive: resistances, x_m, Hm, the base
POSITIVE = ("rs", "rr1", "rr2", "xm", "Hm", "mva")


def check_table(t) -> None:
    """Refuse a mot_con row the model cannot run, as the table is made (the table's
    `_require`, naming the row and field): a column of :data:`POSITIVE` not > 0.

    Parameters
    ----------
    t : stabctl.case.MotorTable
        The motors.

    Raises
    ------
    CaseError
        The first row and field refused.
    """
    t._positive(*POSITIVE)


def motor_params(case: Case) -> MotorParams:
    """The motors of a case on the system base (impedances times Sb/Sn, Hm and the torque
    coefficients times Sn/Sb); the table refused, as it was made, what the model cannot
    run (`check_table`).

    Parameters
    ----------
    case : Case
        The case (its ``motors``).

    Returns
    -------
    MotorParams
        The motors' constants.
    """
    t = case.motors  # its rows checked as the table was made (`check_table`)
    zs = case.base_mva / t.mva  # device-base impedance -> system base
    ps = 1.0 / zs
    rs, xs, rr1, xr1 = t.rs * zs, t.xs * zs, t.rr1 * zs, t.xr1 * zs
    rr2, xr2, xm = t.rr2 * zs, t.xr2 * zs, t.xm * zs
    wb = np.full(len(t), 2 * np.pi * case.freq_hz)
    return MotorParams(
        pos=np.full(len(t), -1, np.int64),
        bus_idx=np.asarray(case.bus_indices(t.bus) if len(t) else np.zeros(0, int), np.int64),
        rs=rs,
        x0=xs + xm,
        x1=xs + xr1 * xm / (xr1 + xm),
        x2=xs + xr1 * xr2 * xm / (xr1 * xr2 + xr1 * xm + xr2 * xm),
        T10=(xr1 + xm) / (wb * rr1),
        T20=(xr2 + xr1 * xm / (xr1 + xm)) / (wb * rr2),
        M=2 * t.Hm * ps,
        a=(t.c1 + t.c2 + t.c3) * ps,
        b=(-t.c2 - 2 * t.c3) * ps,
        c2=t.c2 * ps,
        wb=wb,
    )


def admittance(p: MotorParams) -> np.ndarray:
    """The admittance 1/Z each motor puts at its bus while on (system base), (n_motor,)."""
    return 1.0 / p.Z


@kernel
def drawn_current(P, x, k):
    """The current motor k draws besides its admittance 1/Z: j E"/Z (network frame, system
    base)."""
    Z = P[k, Q.RS] + 1j * P[k, Q.X2]
    return 1j * (x[S.e2d, k] + 1j * x[S.e2q, k]) / Z


@kernel
def derivatives(P, x, k, V, on, dx):
    """Derivatives of motor k into dx (N_STATES, n_motor) at its bus voltage V (complex) and the
    power it draws (P + j Q, system base); 0 and standing still while off (on 0)."""
    if on == 0.0:
        for r in range(N_STATES):
            dx[r, k] = 0.0
        return 0.0j
    s, e1d, e1q, e2d, e2q = x[S.slip, k], x[S.e1d, k], x[S.e1q, k], x[S.e2d, k], x[S.e2q, k]
    Z = P[k, Q.RS] + 1j * P[k, Q.X2]
    Idq = (1j * V - (e2d + 1j * e2q)) / Z
    Id, Iq = Idq.real, Idq.imag
    wb, T10, T20 = P[k, Q.WB], P[k, Q.T10], P[k, Q.T20]
    dx01, dx12 = P[k, Q.X0] - P[k, Q.X1], P[k, Q.X1] - P[k, Q.X2]
    te = e2d * Id + e2q * Iq
    tm = P[k, Q.A] + P[k, Q.B] * s + P[k, Q.C2] * s * s
    dx[S.slip, k] = (tm - te) / P[k, Q.M]
    de1d = wb * s * e1q - (e1d + dx01 * Iq) / T10
    de1q = -wb * s * e1d - (e1q - dx01 * Id) / T10
    dx[S.e1d, k] = de1d
    dx[S.e1q, k] = de1q
    dx[S.e2d, k] = -wb * s * (e1q - e2q) + de1d + (e1d - e2d - dx12 * Iq) / T20
    dx[S.e2q, k] = wb * s * (e1d - e2d) + de1q + (e1q - e2q + dx12 * Id) / T20
    return V * np.conj(Idq / 1j)
