"""Static var compensators: PSS/E's CSVGN1 (continuous SVC), a susceptance at its bus
driven by its voltage regulator.

The compensator is a fixed capacitor CBASE (Mvar) beside a thyristor-controlled reactor
of rating RBASE = the device's MVA (PSS/E: its generator's MBASE); its susceptance on the
system base (capacitive > 0) is::

    B = CBASE/S_b - y_R RBASE/S_b,
    y_R = 1/(1 + s T5) of y_V, non-windup on [RMIN/RBASE, 1]        (the thyristor)
    y_V = K (1 + s T1)(1 + s T2)/((1 + s T3)(1 + s T4)) of (|V| - V_ref), in [VMIN, VMAX]

(PSS/E Model Library CSVGN1; PowerSimulationsDynamics.jl's CSVGN1, whose run agrees with
PSS/E's within 1e-3 pu).  The regulator is the lead-lag (1 + s T2)/(1 + s T4) (state
``lead2``) followed by the lead-lag (1 + s T1)/(1 + s T3) whose lag state ``lead1`` and
output are held in [VMIN, VMAX] (IEEE Std 421.5-2016 E.8's non-windup lead-lag; PSS/E
draws the limits on the whole block, equal when T2 = T4 as in PSS/E's run); a lag below
1e-3 s is absent (its block passes; a lead without its lag and T5 below it are
refused, `svc_params`).

The power flow gives the compensator's share ``qfrac`` of its bus's reactive generation
Q0 (PSS/E: the generator its record is attached to, P = 0): B0 = Q0/|V0|^2.  At rest the
thyristor is at y_R0 = (CBASE/S_b - B0) S_b/RBASE, every regulator state at y_R0 and V_ref
= |V0| - y_R0/K; a start outside [RMIN/RBASE, 1] or [VMIN, VMAX] is refused
(`stabctl.errors.InitialLimitError`).  The network carries B0 among the bus's shunts; the
kernel draws the difference j (B - B0) V at the compensator's kept bus (as a switched
shunt's, `stabctl.models.shunts`).  States (`STATE_NAMES`): lead2, lead1, thyristor.
docs/pst_models.md section 18.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.errors import CaseError, refuse_initial
from stabctl.models.blocks import LBND, clip, leadlag_input_state, nonwindup
from stabctl.models.declaration import (
    Declared,
    DyrModel,
    Family,
    Param,
    beyond,
    check_packed,
    layout,
    pack,
    params_class,
    states,
)

if TYPE_CHECKING:
    from stabctl.case import Case

__all__ = [
    "SVC",
    "DYR",
    "N_STATES",
    "STATE_NAMES",
    "SvcParams",
    "svc_params",
    "time_constants",
    "initialise",
    "extra_admittance",
    "derivatives",
]

# --------------------------------------------------------------------------------------
# svc_con: static var compensators (stabctl's table; PSS/E CSVGN1)
# --------------------------------------------------------------------------------------

_T: dict = dict(unit="s", lo=0.0)

SVC = Family(
    table="svc_con",
    min_columns=14,
    key="number",
    key_label="compensator",
    params=(
        Param("number", "code", 1, integer=True, doc="compensator number"),
        Param("bus", "code", 2, integer=True, doc="bus number"),
        Param(
            "qfrac",
            "",
            3,
            lo=0.0,
            hi=1.0,
            doc="its share of the bus's reactive generation in the power flow (PSS/E: its "
            "generator's QG over the bus's)",
        ),
        Param("mva", "MVA", 4, lo=0.0, doc="reactor rating RBASE (PSS/E: the generator's MBASE)"),
        Param("K", "pu", 5, doc="regulator gain (pu of RBASE per pu of voltage)"),
        Param("T1", col=6, doc="regulator lead time constant", **_T),
        Param("T2", col=7, doc="regulator second lead time constant", **_T),
        Param("T3", col=8, doc="regulator lag time constant", **_T),
        Param("T4", col=9, doc="regulator second lag time constant", **_T),
        Param("T5", col=10, doc="thyristor firing lag time constant", **_T),
        Param("RMIN", "Mvar", 11, lo=0.0, doc="minimum reactor rating"),
        Param("VMAX", "pu", 12, doc="regulator output maximum (pu of RBASE)"),
        Param("VMIN", "pu", 13, doc="regulator output minimum (pu of RBASE)"),
        Param("CBASE", "Mvar", 14, lo=0.0, doc="capacitor rating"),
    ),
)

#: PSS/E's record: CONs K T1 T2 T3 T4 T5 RMIN VMAX VMIN CBASE (RBASE the generator's MBASE)
DYR = (
    DyrModel(
        "CSVGN1",
        ("K", "T1", "T2", "T3", "T4", "T5", "RMIN", "VMAX", "VMIN", "CBASE"),
        {n: n for n in ("K", "T1", "T2", "T3", "T4", "T5", "RMIN", "VMAX", "VMIN", "CBASE")},
    ),
)

N_STATES = 3
STATE_NAMES = ("lead2", "lead1", "thyristor")
#: the named slots, read by the kernels as ``x[S.thyristor, k]``
S = states("SvcStates", STATE_NAMES)
#: the kernels' packed columns: the kept-bus position, the susceptances on the system base
#: (capacitor C = CBASE/S_b, reactor R = RBASE/S_b, initial B0), the regulator, the
#: thyristor's limits
PACKED = (
    ("POS", "pos"),
    ("C", "c"),
    ("R", "r"),
    ("B0", "B0"),
    ("VREF", "Vref"),
    ("K", "K"),
    ("T1", "T1"),
    ("T2", "T2"),
    ("T3", "T3"),
    ("T4", "T4"),
    ("T5", "T5"),
    ("VMAX", "VMAX"),
    ("VMIN", "VMIN"),
    ("YMIN", "ymin"),
)
#: the kernels' column of each PACKED name: P[k, V.T5]
V = layout("SvcColumns", PACKED)
#: the non-windup rule (`blocks.nonwindup`): IEEE's, as a numpy boolean (a Python True
#: from compiled code is typed as a literal, a second compile of the block)
_AT_LIMIT = np.bool_(True)


@params_class(("pos", "bus_idx"), ())
class SvcParams(Declared):
    """Compensator constants, arrays of shape (n_svc,): ``pos`` the bus's position among
    the kept buses (set by the dynamic model), ``bus_idx`` its row, c = CBASE/S_b and r =
    RBASE/S_b (pu, system base), the initial susceptance B0 and reference Vref, the
    regulator K, T1..T5, VMAX, VMIN and the thyristor's lower limit ymin = RMIN/RBASE."""

    c: np.ndarray
    r: np.ndarray
    B0: np.ndarray
    Vref: np.ndarray
    K: np.ndarray
    T1: np.ndarray
    T2: np.ndarray
    T3: np.ndarray
    T4: np.ndarray
    T5: np.ndarray
    VMAX: np.ndarray
    VMIN: np.ndarray
    ymin: np.ndarray

    @property
    def n(self) -> int:
        return self.bus_idx.size

    def packed(self) -> np.ndarray:
        """Parameter matrix (n_svc, len(PACKED)) for the compiled kernels."""
        return pack(self, PACKED)

    def y0(self) -> np.ndarray:
        """The thyristor's initial output y_R0 = (c - B0)/r, (n_svc,)."""
        return (self.c - self.B0) / self.r

    def has_state(self) -> np.ndarray:
        """Boolean (N_STATES, n_svc): each lag of at least 1e-3 s is a state (T5 always)."""
        return np.vstack([self.T4 >= LBND, self.T3 >= LBND, self.T5 >= LBND])


check_packed(SvcParams, PACKED)


def check_table(t) -> None:
    """Refuse a svc_con row the model cannot run, as the table is made (the table's
    `_fail`, naming the row and field): mva or K not positive, T5 below 1e-3 s, a lead
    (T1, T2) without its lag (T3, T4), VMAX < VMIN.

    Parameters
    ----------
    t : stabctl.case.SvcTable
        The compensators.

    Raises
    ------
    CaseError
        The first row and field refused.
    """
    for name in ("mva", "K"):
        bad = np.flatnonzero(getattr(t, name) <= 0)
        if bad.size:
            t._fail(bad[0], name, "must be > 0")
    for lead, lag in (("T1", "T3"), ("T2", "T4")):
        bad = np.flatnonzero((getattr(t, lag) < LBND) & (getattr(t, lead) >= LBND))
        if bad.size:
            t._fail(bad[0], lead, f"a lead needs its lag {lag} >= {LBND} s")
    bad = np.flatnonzero(t.T5 < LBND)
    if bad.size:
        t._fail(bad[0], "T5", f"the thyristor lag must be >= {LBND} s")
    bad = np.flatnonzero(t.VMAX < t.VMIN)
    if bad.size:
        t._fail(bad[0], "VMAX", "must be >= VMIN")


def svc_params(case: Case, V: np.ndarray, S_gen: np.ndarray) -> SvcParams:
    """The compensators of a case at the solved power flow (bus voltages V, generation
    S_gen, complex (n_bus,) pu): B0 = qfrac Im(S_gen)/|V|^2 at its bus and V_ref = |V| -
    y_R0/K (module docstring).

    Parameters
    ----------
    case : Case
        The case (its ``svcs`` table).
    V, S_gen : ndarray of complex, shape (n_bus,)
        The power flow's bus voltages and generation (pu, system base).

    Returns
    -------
    SvcParams

    Raises
    ------
    InitialLimitError
        The thyristor's start outside [RMIN/RBASE, 1] or the regulator's outside [VMIN,
        VMAX] (beyond `START_LIMIT_TOL`).
    """
    t = case.svcs  # its rows checked as the table was made (`check_table`)
    sb = case.base_mva
    bus_idx = np.asarray(case.bus_indices(t.bus) if len(t) else np.zeros(0, int), np.int64)
    vm = np.abs(V[bus_idx])
    B0 = t.qfrac * S_gen[bus_idx].imag / vm**2
    c, r = t.CBASE / sb, t.mva / sb
    y0 = (c - B0) / r
    ymin = t.RMIN / t.mva
    refuse_initial(
        "svc_con",
        beyond(y0, ymin, 1.0) | beyond(y0, t.VMIN, t.VMAX),
        lambda i: (
            f"svc_con row {i + 1}: the power flow's susceptance {B0[i]:.4f} pu needs the "
            f"reactor at {y0[i]:.4f} pu of RBASE, outside [RMIN/RBASE, 1] = "
            f"[{ymin[i]:.4f}, 1] or [VMIN, VMAX] = [{t.VMIN[i]:.4f}, {t.VMAX[i]:.4f}]"
        ),
    )
    if len(t) and not np.all(np.isfinite(B0)):
        raise CaseError("svc_con: a compensator's bus has no power-flow voltage")
    return SvcParams(
        pos=np.full(len(t), -1, np.int64),
        bus_idx=bus_idx,
        c=c,
        r=r,
        B0=B0,
        Vref=vm - y0 / t.K,
        K=t.K.copy(),
        T1=t.T1.copy(),
        T2=t.T2.copy(),
        T3=t.T3.copy(),
        T4=t.T4.copy(),
        T5=t.T5.copy(),
        VMAX=t.VMAX.copy(),
        VMIN=t.VMIN.copy(),
        ymin=ymin,
    )


def time_constants(case: Case):
    """(label, values, mask) of the compensators' time constants that set a state's
    speed (the lags T3, T4 of at least 1e-3 s, T5)."""
    t = case.svcs
    return tuple((f"svc_con {n}", getattr(t, n), getattr(t, n) >= LBND) for n in ("T3", "T4", "T5"))


def initialise(p: SvcParams) -> np.ndarray:
    """States (N_STATES, n_svc) at rest: every one at y_R0 (the lead-lags' lagged inputs
    and the thyristor equal their input there)."""
    return np.tile(p.y0(), (N_STATES, 1))


@kernel
def susceptance(P, x, k):
    """Compensator k's susceptance (system base, capacitive > 0) from its thyristor."""
    return P[k, V.C] - clip(x[S.thyristor, k], P[k, V.YMIN], 1.0) * P[k, V.R]


@kernel
def extra_admittance(P, x, k):
    """The admittance compensator k draws beyond the network's (its susceptance less the
    power flow's B0), complex pu."""
    return 1j * (susceptance(P, x, k) - P[k, V.B0])


@kernel
def _regulator(P, x, k, vmag):
    """The regulator's output y_V at the bus voltage magnitude vmag, clamping the limited
    lag state in x: (y_V, d lead2/dt, d lead1/dt)."""
    u = P[k, V.K] * (vmag - P[k, V.VREF])
    T2, T4 = P[k, V.T2], P[k, V.T4]
    y2, d2 = leadlag_input_state(u, x[S.lead2, k], T2 / max(T4, LBND), T4)
    T1, T3 = P[k, V.T1], P[k, V.T3]
    lo, hi = P[k, V.VMIN], P[k, V.VMAX]
    if T3 < LBND:
        return clip(y2, lo, hi), d2, 0.0
    x[S.lead1, k], d1 = nonwindup(x[S.lead1, k], (y2 - x[S.lead1, k]) / T3, lo, hi, _AT_LIMIT, 0.0)
    r = T1 / T3
    return clip(r * y2 + (1 - r) * x[S.lead1, k], lo, hi), d2, d1


@kernel
def derivatives(P, x, k, vmag, dx):
    """Derivatives of compensator k into dx (3, n_svc) at its bus voltage magnitude vmag
    (pu): the regulator, then the thyristor lag non-windup on [RMIN/RBASE, 1] (clamps its
    state in x)."""
    y, dx[S.lead2, k], dx[S.lead1, k] = _regulator(P, x, k, vmag)
    x[S.thyristor, k], dx[S.thyristor, k] = nonwindup(
        x[S.thyristor, k], (y - x[S.thyristor, k]) / P[k, V.T5], P[k, V.YMIN], 1.0, _AT_LIMIT, 0.0
    )
