"""Exciter models: PST `smpexc` (type 0, simple static) and `exc_st3` (type 3, IEEE ST3).

Source: PSTess 1.1 `exc_indx.m`, `smpexc.m`, `exc_st3.m`; equations, limits and PST's
quirks in docs/pst_models.md section 2.  A time constant below 1e-3 s means the block is
absent (no state).  States (3 slots per exciter): smpexc (V_TR, V_As, Efd); exc_st3
(V_TR, V_As, V_R).  Units: pu on the machine base; times in s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from .case import Case
from .errors import CaseError

LBND = 1e-3
SMP, ST3 = 0, 3
STATE_NAMES = ("VTR", "VAs", "Efd_or_VR")

# columns of the packed parameter matrix used by the compiled kernels
(E_KIND, E_MAC, E_TR, E_KA, E_TA, E_TB, E_TC, E_VRMAX, E_VRMIN, E_VIMAX, E_VIMIN, E_KJ,
 E_KPR, E_KPI, E_KI, E_XL, E_KC, E_EFDMAX, E_KG, E_VGMAX, E_TCTB, E_VREF, E_NCOL) = range(23)


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

    def packed(self, Vref: np.ndarray) -> np.ndarray:
        """Parameter matrix (n_exc, E_NCOL) for the compiled kernels, with Vref."""
        cols = (self.kind, self.mac, self.TR, self.KA, self.TA, self.TB, self.TC, self.Vrmax,
                self.Vrmin, self.VImax, self.VImin, self.KJ, self.KP.real, self.KP.imag,
                self.KI, self.XL, self.KC, self.Efdmax, self.KG, self.VGmax, self.tc_tb, Vref)
        return np.column_stack([np.asarray(c, float) for c in cols]).reshape(self.n, E_NCOL)

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


@njit(cache=True)
def _fex(IN, init):
    """Rectifier loading factor F_EX(I_N) of the ST3 (PST, with its initialisation quirk:
    sqrt(0.75 - I_N^0.2) and 1.708 in flag 0)."""
    if IN < 0.433:
        return 1.0 - 0.5771 * IN
    if 0.433 < IN < 0.75:
        return np.sqrt(max(0.75 - (IN ** 0.2 if init else IN * IN), 0.0))
    if IN > 0.75:
        return max(0.0, (1.708 if init else 1.732) * (1.0 - IN))
    return 0.0


@njit(cache=True)
def st3_source_voltage(KP, KI, XL, KC, eterm, theta, pelect, qelect, mac_pot, fldcur, init):
    """V_B = V_E F_EX of the ST3 potential/compound source (PST exc_st3 flag 0/1); KP is
    the complex K_P exp(j theta_P); pelect, qelect on the system base."""
    i_t = (pelect - 1j * qelect) / (eterm * np.exp(-1j * theta)) * mac_pot
    VE = np.abs(KP * eterm * np.exp(1j * theta) + 1j * (KI + KP * XL) * i_t)
    IN = KC * fldcur / VE if VE > 0 else 0.0
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
    bad = st3 & ((vex > p.Efdmax) | (VI > p.VImax) | (VI < p.VImin))
    if bad.any():
        i = int(np.nonzero(bad)[0][0])
        raise CaseError(f"exc_con row {i + 1}: initial field voltage {vex[i]:.3f} pu outside "
                        "the ST3 limits (Efdmax or VI range)")
    x[1] = np.where(smp, VA_smp, VA_st3)
    x[2] = np.where(smp, vex, VR)
    Vref = np.where(smp, eterm + VA_smp, eterm + VI)
    return x, Vref


@njit(cache=True)
def field_voltage(P, x, i, VTR_alg, pss_out, VB):
    """Field voltage exciter i hands its machine (PST flag 1).

    smpexc: the Efd state (unclamped) when T_A exists, else K_A times the (lead-lag of the)
    error, without limits; exc_st3: min(V_R V_B, Efdmax).
    """
    if P[i, E_KIND] == ST3:
        return min(x[2, i] * VB, P[i, E_EFDMAX])
    if P[i, E_TA] >= LBND:
        return x[2, i]
    VTR = x[0, i] if P[i, E_TR] >= LBND else VTR_alg
    err = P[i, E_VREF] - VTR + pss_out
    VA = P[i, E_TCTB] * err + (1 - P[i, E_TCTB]) * x[1, i] if P[i, E_TB] >= LBND else err
    return P[i, E_KA] * VA


@njit(cache=True)
def derivatives(P, x, i, eterm, pss_out, efd, dx):
    """Derivatives of exciter i into dx[:, i] (PST flag 2); clamps its limited state in x.

    smpexc: the Efd state is clamped to [Vrmin, Vrmax] after its derivative is computed and
    the derivative is kept (PST's misspelt dEFD, docs/pst_models.md 2.1).  exc_st3: V_R is
    clamped and its derivative zeroed when it pushes outward.
    """
    has_TR, has_TB = P[i, E_TR] >= LBND, P[i, E_TB] >= LBND
    VTR = x[0, i] if has_TR else eterm
    dx[0, i] = (eterm - x[0, i]) / P[i, E_TR] if has_TR else 0.0
    smp = P[i, E_KIND] == SMP
    VI = P[i, E_VREF] - VTR + pss_out
    if not smp:
        VI = min(max(VI, P[i, E_VIMIN]), P[i, E_VIMAX])
    u = VI if smp else P[i, E_KJ] * VI
    dx[1, i] = (u - x[1, i]) / P[i, E_TB] if has_TB else 0.0
    VA = P[i, E_TCTB] * u + (1 - P[i, E_TCTB]) * x[1, i] if has_TB else u
    lo, hi = P[i, E_VRMIN], P[i, E_VRMAX]
    if smp:
        if P[i, E_TA] >= LBND:
            dx[2, i] = (P[i, E_KA] * VA - x[2, i]) / P[i, E_TA]
            x[2, i] = min(max(x[2, i], lo), hi)
        else:
            dx[2, i] = 0.0
    else:
        d = (P[i, E_KA] * (VA - min(P[i, E_VGMAX], P[i, E_KG] * efd)) - x[2, i]) / P[i, E_TA]
        if (x[2, i] > hi and d > 0) or (x[2, i] < lo and d < 0):
            d = 0.0
        dx[2, i] = d
        x[2, i] = min(max(x[2, i], lo), hi)


@njit(cache=True)
def recorded_efd(P, x, i, efd_alg):
    """Efd as PST records it: the (clamped) smpexc state, or the ST3 algebraic value."""
    if P[i, E_KIND] == SMP and P[i, E_TA] >= LBND:
        return x[2, i]
    return efd_alg
