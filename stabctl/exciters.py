"""Exciter models: PST `smpexc` (type 0, simple static) and `exc_st3` (type 3, IEEE ST3).

Source: PSTess 1.1 `exc_indx.m`, `smpexc.m`, `exc_st3.m`; equations, limits and PST's
quirks in docs/pst_models.md section 2.  A time constant below 1e-3 s means the block is
absent (no state).  States (3 slots per exciter): smpexc (V_TR, V_As, Efd); exc_st3
(V_TR, V_As, V_R).  Units: pu on the machine base; times in s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .case import Case
from .errors import CaseError

LBND = 1e-3
SMP, ST3 = 0, 3
STATE_NAMES = ("VTR", "VAs", "Efd_or_VR")


@dataclass(frozen=True, eq=False)
class ExciterParams:
    """Exciter data of a case, arrays of shape (n_exc,); `mac` is the machine index."""

    kind: np.ndarray
    mac: np.ndarray
    TR: np.ndarray
    KA: np.ndarray
    TA: np.ndarray
    TB: np.ndarray
    TC: np.ndarray
    Vrmax: np.ndarray
    Vrmin: np.ndarray
    VImax: np.ndarray
    VImin: np.ndarray
    KJ: np.ndarray
    KP: np.ndarray  # complex K_P exp(j theta_P)
    KI: np.ndarray
    XL: np.ndarray
    KC: np.ndarray
    Efdmax: np.ndarray
    KG: np.ndarray
    VGmax: np.ndarray

    @property
    def n(self) -> int:
        return self.kind.size

    @property
    def has_TR(self):
        return self.TR >= LBND

    @property
    def has_TB(self):
        return self.TB >= LBND

    @property
    def has_TA(self):
        return self.TA >= LBND

    @property
    def tc_tb(self):
        """T_C/T_B where the lead-lag exists, 1 otherwise (PST exc_pot column 5)."""
        return np.where(self.has_TB, self.TC / np.where(self.has_TB, self.TB, 1.0), 1.0)


def exciter_params(case: Case) -> ExciterParams:
    """Exciter parameters; raises CaseError for a type stabctl does not model."""
    e = case.exciters
    bad = ~np.isin(e.type, (SMP, ST3))
    if bad.any():
        i = int(np.nonzero(bad)[0][0])
        raise CaseError(f"exc_con row {i + 1}: exciter type {int(e.type[i])} is not modelled "
                        "(supported: 0 smpexc, 3 exc_st3)")
    KA = np.where((e.type == ST3) & (e.KA == 0), 1.0, e.KA)
    return ExciterParams(
        kind=e.type.astype(int), mac=np.array([case.machine_index(m) for m in e.machine], int),
        TR=e.TR.copy(), KA=KA, TA=e.TA.copy(), TB=e.TB.copy(), TC=e.TC.copy(),
        Vrmax=e.Vrmax.copy(), Vrmin=e.Vrmin.copy(), VImax=e.VImax.copy(), VImin=e.VImin.copy(),
        KJ=e.KJ.copy(), KP=e.KP * np.exp(1j * np.deg2rad(e.thetaP)), KI=e.KI.copy(),
        XL=e.XL.copy(), KC=e.KC.copy(), Efdmax=e.Efdmax.copy(), KG=e.KG.copy(),
        VGmax=e.VGmax.copy())


def _fex(IN, init: bool = False):
    """Rectifier loading factor F_EX(I_N) of the ST3 (PST, with its initialisation quirk)."""
    mid = np.sqrt(np.clip(0.75 - (IN ** 0.2 if init else IN ** 2), 0, None))
    high = np.maximum(0.0, (1.708 if init else 1.732) * (1 - IN))
    return np.where(IN < 0.433, 1 - 0.5771 * IN,
                    np.where((IN > 0.433) & (IN < 0.75), mid, np.where(IN > 0.75, high, 0.0)))


def st3_source_voltage(p: ExciterParams, eterm, theta, pelect, qelect, mac_pot, fldcur,
                       init: bool = False):
    """V_B = V_E F_EX of the ST3 potential/compound source (PST exc_st3 flag 0/1)."""
    i_t = (pelect - 1j * qelect) / (eterm * np.exp(-1j * theta)) * mac_pot
    VE = np.abs(p.KP * eterm * np.exp(1j * theta) + 1j * (p.KI + p.KP * p.XL) * i_t)
    IN = p.KC * fldcur / np.where(VE > 0, VE, 1.0)
    return VE * _fex(IN, init)


def initialise(p: ExciterParams, vex, eterm, VB=None):
    """States (3, n_exc) and Vref (n_exc,) from the machines' field voltage and terminal
    voltage; VB is the ST3 source voltage (needed for type 3).  Raises CaseError when the
    initial field voltage violates a limit PST checks."""
    x = np.zeros((3, p.n))
    x[0] = eterm
    smp, st3 = p.kind == SMP, p.kind == ST3
    VA_smp = vex / p.KA
    VB = np.ones(p.n) if VB is None else np.where(st3, VB, 1.0)
    VR = vex / VB
    VA_st3 = VR / p.KA + np.minimum(p.VGmax, p.KG * vex)
    VI = VA_st3 / np.where(p.KJ == 0, 1.0, p.KJ)
    if np.any(st3 & (vex > p.Efdmax)) or np.any(st3 & ((VI > p.VImax) | (VI < p.VImin))):
        i = int(np.nonzero(st3 & ((vex > p.Efdmax) | (VI > p.VImax) | (VI < p.VImin)))[0][0])
        raise CaseError(f"exc_con row {i + 1}: initial field voltage {vex[i]:.3f} pu outside "
                        "the ST3 limits (Efdmax or VI range)")
    x[1] = np.where(smp, VA_smp, VA_st3)
    x[2] = np.where(smp, vex, VR)
    Vref = np.where(smp, eterm + VA_smp, eterm + VI)
    return x, Vref


def field_voltage(p: ExciterParams, x, Vref, VTR_alg, pss_out, VB):
    """Field voltage seen by the machine (PST flag 1), shape (n_exc,).

    smpexc: the Efd state (unclamped) when T_A exists, else K_A times the (lead-lag of the)
    error without limits; exc_st3: min(V_R V_B, Efdmax).
    """
    VTR = np.where(p.has_TR, x[0], VTR_alg)
    err = Vref - VTR + pss_out
    VA = np.where(p.has_TB, p.tc_tb * err + (1 - p.tc_tb) * x[1], err)
    smp = np.where(p.has_TA, x[2], p.KA * VA)
    st3 = np.minimum(x[2] * VB, p.Efdmax)
    return np.where(p.kind == SMP, smp, st3)


def derivatives(p: ExciterParams, x, Vref, eterm, pss_out, efd):
    """State derivatives (3, n_exc) (PST flag 2); clamps the limited states of x in place.

    smpexc: the Efd state is clamped to [Vrmin, Vrmax] after its derivative is computed and
    the derivative is kept (PST's misspelt dEFD: docs/pst_models.md 2.1).  exc_st3: V_R is
    clamped and its derivative zeroed when it pushes outward.
    """
    dx = np.zeros_like(x)
    VTR = np.where(p.has_TR, x[0], eterm)
    dx[0] = np.where(p.has_TR, (eterm - x[0]) / np.where(p.has_TR, p.TR, 1.0), 0.0)
    smp = p.kind == SMP
    VI = np.where(smp, Vref - VTR + pss_out, np.clip(Vref - VTR + pss_out, p.VImin, p.VImax))
    u = np.where(smp, VI, p.KJ * VI)
    TB = np.where(p.has_TB, p.TB, 1.0)
    dx[1] = np.where(p.has_TB, (u - x[1]) / TB, 0.0)
    VA = np.where(p.has_TB, p.tc_tb * u + (1 - p.tc_tb) * x[1], u)
    TA = np.where(p.has_TA | ~smp, p.TA, 1.0)
    d_smp = np.where(p.has_TA, (p.KA * VA - x[2]) / TA, 0.0)
    d_st3 = (p.KA * (VA - np.minimum(p.VGmax, p.KG * efd)) - x[2]) / TA
    st3 = ~smp
    d_st3 = np.where(st3 & (x[2] > p.Vrmax) & (d_st3 > 0), 0.0, d_st3)
    d_st3 = np.where(st3 & (x[2] < p.Vrmin) & (d_st3 < 0), 0.0, d_st3)
    dx[2] = np.where(smp, d_smp, d_st3)
    limited = smp & p.has_TA | st3
    x[2] = np.where(limited, np.clip(x[2], p.Vrmin, p.Vrmax), x[2])
    return dx


def recorded_efd(p: ExciterParams, x, efd_alg):
    """Efd as PST records it: the (clamped) smpexc state, or the ST3 algebraic value."""
    return np.where((p.kind == SMP) & p.has_TA, x[2], efd_alg)
