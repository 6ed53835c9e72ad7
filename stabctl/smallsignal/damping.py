"""Small-signal damping with bang-bang ESDs, linearised in the ratings (docs/placement.md,
section 5).

A bang-bang ESD (paper Table 3: +-P_j outside a deadband d on its machine's speed relative
to the centre of inertia, idle inside) is a relay with a dead zone.  For an oscillation of
relative-speed amplitude A its first harmonic is that of a linear gain, the describing
function (Gelb, Vander Velde, Multiple-Input Describing Functions and Nonlinear System
Design, 1968, ch. 2):

    N(A) = P_j * n(A),   n(A) = 4 / (pi A) * sqrt(1 - (d / A)^2)  for A > d, 0 below,

so the ESD acts on a mode of that amplitude as the linear feedback P_j = K_j omega_rel_j,
K_j = n(A) P_j, LINEAR in the rating.  n(A) is computed by `control.describing_function`
(python-control) on the relay itself (`relay_df`); with hysteresis h it gains a small
lag, of relative size ~h / A, which is left out (the in-phase part is used).  Closing these loops
on the linearised model (`stabctl.smallsignal.linearise`: inputs P_esd_B<bus>, outputs
omega_rel_G<k>) gives A_cl(P) = A + B_s diag(n P / S_base) C_s, whose eigenvalues are recomputed
exactly (`stabctl.smallsignal.modal`); their first-order change is the residue of each site's
own loop (`stabctl.smallsignal.modal.mode_sensitivity`), d lambda_m / d K_j = R_m,jj.  The
damping ratio
-Re(lambda)/|lambda| >= zeta_min is the half plane Re(lambda) + kappa Im(lambda) <= 0,
kappa = zeta_min / sqrt(1 - zeta_min^2), linear in lambda and hence, to first order, in P.
Below the deadband (A <= d) the ESDs are idle and add no damping at all.
"""

from __future__ import annotations

from dataclasses import dataclass

import control as ct
import numpy as np

from stabctl.errors import InputError
from stabctl.smallsignal.modal import modal_analysis, mode_sensitivity


@dataclass(frozen=True)
class DampingRows:
    """Linearised damping constraints A P <= b (P in MW; rows normalised by |lambda|, so
    in damping-ratio units); labels: one per row (mode)."""

    A: np.ndarray
    b: np.ndarray
    labels: tuple = ()


class BangBangRelay(ct.DescribingFunctionNonlinearity):
    """The Table 3 law on a relative speed x (pu) with unit output: +1 above the deadband,
    -1 below minus it, 0 inside; with hysteresis a running relay stops only inside
    deadband - hysteresis (stateful then).  Deadband and hysteresis in pu speed."""

    def __init__(self, deadband: float, hysteresis: float = 0.0):
        super().__init__()
        self.db, self.hyst, self.mode = deadband, hysteresis, 0

    def __call__(self, x):
        keep = (self.mode == 1 and x > self.db - self.hyst) or (
            self.mode == -1 and x < self.hyst - self.db
        )
        if not keep:
            self.mode = 1 if x > self.db else -1 if x < -self.db else 0
        return float(self.mode)

    def _isstatic(self):
        return self.hyst == 0


def relay_df(
    deadband_hz: float, amplitude_hz: float, freq_hz: float, hysteresis_hz: float = 0.0
) -> complex:
    """Describing function n(A) of the unit bang-bang relay (`BangBangRelay`) at a
    relative-speed amplitude `amplitude_hz` (Hz), in pu power per pu speed per pu rating,
    by `control.describing_function` (first harmonic over one period, 4000 points).  Real
    4 / (pi A) sqrt(1 - (d / A)^2) without hysteresis, 0 at or below the deadband;
    hysteresis adds a small lag (imaginary part ~ -(4 / (pi A)) h / A).
    Raises InputError for a non-positive amplitude."""
    if not amplitude_hz > 0:
        raise InputError(f"oscillation amplitude must be > 0 Hz, got {amplitude_hz:g}")
    relay = BangBangRelay(deadband_hz / freq_hz, hysteresis_hz / freq_hz)
    return complex(ct.describing_function(relay, [amplitude_hz / freq_hz], num_points=4000)[0])


class DampingModel:
    """The linearised case with an equivalent-gain ESD at every site.

    Args:
        sys: `stabctl.smallsignal.linearise.linearise` model with an ESD input at every site bus.
        sites: `stabctl.placement.program.Site` sequence (bus, machine).
        gain: n(A), real (in-phase part of `relay_df`); base_mva: system base (MW per pu).
    Raises InputError when a site bus or machine has no input or output in sys.
    """

    def __init__(self, sys, sites, gain: float, base_mva: float):
        ins, outs = list(sys.input_labels), list(sys.output_labels)
        names = [(f"P_esd_B{s.bus}", f"omega_rel_G{s.machine}") for s in sites]
        missing = [n for pair in names for n, have in zip(pair, (ins, outs)) if n not in have]
        if missing:
            raise InputError(f"the linearised model lacks {', '.join(missing)}")
        self.sys, self.sites, self.scale = sys, tuple(sites), gain / base_mva
        self.col = [ins.index(i) for i, _ in names]
        self.row = [outs.index(o) for _, o in names]
        self.B_s = np.asarray(sys.B)[:, self.col]
        self.C_s = np.asarray(sys.C)[self.row]

    def closed_loop(self, mw) -> ct.StateSpace:
        """The model with the sites' loops closed at ratings mw (MW): A + B_s K C_s."""
        K = self.scale * np.asarray(mw, float)
        s = self.sys
        return ct.ss(
            np.asarray(s.A) + self.B_s @ (K[:, None] * self.C_s),
            s.B,
            s.C,
            s.D,
            states=s.state_labels,
            inputs=s.input_labels,
            outputs=s.output_labels,
        )

    def modes(self, mw):
        """`stabctl.smallsignal.modal.ModalAnalysis` of the closed loop at ratings mw (MW)."""
        return modal_analysis(self.closed_loop(mw))

    def em_damping(self, mw) -> tuple[np.ndarray, np.ndarray]:
        """(frequency Hz, damping ratio) of every electromechanical mode at ratings mw."""
        ma = self.modes(mw)
        em = ma.electromechanical
        return ma.freq_hz[em], ma.damping[em]

    def rows(self, mw, zeta_min: float) -> DampingRows:
        """Damping >= zeta_min of every electromechanical mode, linearised at ratings mw
        (MW): rows a_m . P <= b_m, each divided by |lambda_m|.

        Raises InputError for zeta_min outside [0, 1).
        """
        if not 0 <= zeta_min < 1:
            raise InputError(f"zeta_min must be in [0, 1), got {zeta_min:g}")
        kappa = zeta_min / np.sqrt(1 - zeta_min**2)
        mw = np.asarray(mw, float)
        sys_cl = self.closed_loop(mw)
        ma = modal_analysis(sys_cl)
        em = ma.electromechanical
        ms = mode_sensitivity(sys_cl, ma)
        R = ms.residues[em]  # (n_em, n_out, n_in)
        r = (
            np.stack(
                [
                    R[
                        :,
                        ms.outputs.index(self.sys.output_labels[o]),
                        ms.inputs.index(self.sys.input_labels[i]),
                    ]
                    for i, o in zip(self.col, self.row)
                ],
                axis=1,
            )
            * self.scale
        )
        lam = ma.eigenvalues[em]
        a = (r.real + kappa * r.imag) / np.abs(lam)[:, None]
        b = (-(lam.real + kappa * lam.imag)) / np.abs(lam) + a @ mw
        labels = tuple(f"{f:.3f} Hz" for f in ma.freq_hz[em])
        return DampingRows(A=a, b=b, labels=labels)
