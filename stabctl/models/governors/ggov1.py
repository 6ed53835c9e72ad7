"""PSS/E's GGOV1 (tg_con type 9): the general governor-turbine (GE's, WECC's), gas
turbines and combined-cycle units.  Signals in pu on the turbine rating Trate (the
machine's MVA where Trate = 0); the mechanical power handed to the machine is times
Trate / MVA.

* Governor: the electrical power measured through 1/(1 + s Tpelec); the speed error
  e = P_ref - (omega - 1) - R sig, sig chosen by Rselect (1 the measured electrical
  power, -1 the fuel valve stroke (the true stroke), -2 the governor output fsr (the
  requested stroke), 0 none: isochronous), through the deadband +-db and limited to
  [minerr, maxerr], into the PID Kpgov + Kigov/s + s Kdgov/(1 + s Tdgov) -> fsrn.  With
  -2 the error depends on fsr through the PID's proportional and derivative paths, an
  algebraic loop: PSS/E and PSLF break it with the previous step's fsr (one step's
  delay); stabctl solves it exactly (`_order_error`), the limit of that as the step
  shrinks.
* Load (temperature) limiter: the fuel flow w_f through the lead-lag (1 + s Tsa)/(1 + s
  Tsb) and the lag Tfload is the measured exhaust temperature; the PI Kpload + Kiload/s
  of Ldref/Kturb + Wfnl minus it, at most 1 -> fsrt, its integrator's rate within [Rdown,
  Rup].
* Acceleration limiter: the speed's derivative s/(1 + s Ta) against Aset through the
  integrator Ka/s -> fsra.
* fsr = clip(min(fsrn, fsrt, fsra), Vmin, Vmax) is the valve's order; the actuator
  1/(s Tact) rate-limited to [Rclose, Ropen], position non-windup on [Vmin, Vmax] (the
  valve stroke); the fuel flow w_f = the stroke times the speed (Flag = 1) or times 1
  (Flag = 0); the turbine Kturb (w_f - Wfnl) through (1 + s Tc)/(1 + s Tb); pmech =
  that - Dm (omega - 1) (Dm > 0 as GridPACK's GGOV1 reads it, fsr0 free of Dm; OpenIPSL's
  Turbine subtracts Dm times its Dm_select of the speed and starts fsr0 Dm/Kturb higher).

The integrators of the controllers the low-value gate does not select track its output
(the governor's and the load limiter's at the rate (K_I/K_P)(fsr - their output), the
acceleration limiter's at 1/Ta): PSS/E's rest point (OpenIPSL's PSSE.TG.GGOV1: both PI
integrators start at fsr0) is then an equilibrium, and a controller takes over as soon as
its output falls below the others'.  PSS/E's acceleration limiter is written for its
fixed step DELT (fsra = fsr + Ka DELT (Aset - accel)); the tracking integrator has the
same threshold (accel = Aset) and, selected, the same rate Ka (Aset - accel) of fsr.

Not modelled, refused by name (`check`): the diesel engine's transport delay Teng > 0
(PSS/E asks for 0 or a multiple of its step; an ODE model has no delay), the
supplementary load controller Kimw != 0 and Dm < 0 (fuel flow scaled by speed^Dm).
Rselect's codes are PSS/E's, PSLF's, the CIM's DroopSignalFeedbackKind's and OpenIPSL's
R_select: 1 electrical power, 0 none, -1 fuel valve stroke, -2 governor output (until
2026-12-02 stabctl read -2 as the valve stroke and refused -1; then -2 was refused until
its loop was solved).  The rates Rup,
Rdown bound the load limiter's integrator (OpenIPSL has none).

Sources: PSS/E Model Library GGOV1 (the DYR record: ICONs Rselect, Flag; CONs R,
Tpelec, maxerr, minerr, Kpgov, Kigov, Kdgov, Tdgov, Vmax, Vmin, Tact, Kturb, Wfnl, Tb,
Tc, Teng, Tfload, Kpload, Kiload, Ldref, Dm, Ropen, Rclose, Kimw, Aset, Ka, Ta, Trate,
db, Tsa, Tsb, Rup, Rdown, as PowerSystems.jl's GeneralGovModel reads it); OpenIPSL
``Electrical/Controls/PSSE/TG/GGOV1.mo`` and its ``BaseClasses/GGOV1`` blocks; GridPACK's
``ggov1.cpp`` (PNNL; Rselect -2 fed back with the previous step's fsr); the WECC GGOV1
specification.  ANDES 2.0 has no GGOV1.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.errors import refuse_initial
from stabctl.models.blocks import GAIN_BEFORE, LBND, clip, lag, leadlag, nonwindup, washout
from stabctl.models.declaration import DyrModel, Limits, beyond, states
from stabctl.models.governors.table import AT_LIMIT, G

if TYPE_CHECKING:
    from stabctl.models.governors import GovernorParams

GGOV1 = 9
KINDS = {GGOV1: "GGOV1"}
#: GGOV1's speed error limits ordered (PSS/E Model Library GGOV1)
LIMITS = Limits("PSS/E Model Library GGOV1", ordered=(("maxerr", "minerr"),))
#: the time constants that must be >= 1e-3 s (declared tg_con fields)
NEEDS = ("Tpelec", "Tact", "Tb", "Tfload", "Tsb", "Tacc")
#: not the family's start-up check of the order against [Tmin, Tmax]: `initialise`
#: checks its fuel order, against [Vmin, Vmax]
ORDER_LIMITS = False
#: PSS/E's record (ICONs, then CONs) -> tg_con fields
_RECORD = ("Rselect", "Flag", "R", "Tpelec", "maxerr", "minerr", "Kpgov", "Kigov", "Kdgov")
_RECORD += ("Tdgov", "Vmax", "Vmin", "Tact", "Kturb", "Wfnl", "Tb", "Tc", "Teng", "Tfload")
_RECORD += ("Kpload", "Kiload", "Ldref", "Dm", "Ropen", "Rclose", "Kimw", "Aset", "Ka", "Ta")
_RECORD += ("Trate", "db", "Tsa", "Tsb", "Rup", "Rdown")
#: tg_con fields of GGOV1 of its own (tg_con columns 28-59), as the record names them
#: but R (Rdroop), Ka (Kacc), Ta (Tacc); Vmax, Vmin, Tc in the shared columns
FIELDS = tuple(
    {"R": "Rdroop", "Ka": "Kacc", "Ta": "Tacc"}.get(n, n)
    for n in _RECORD
    if n not in ("Vmax", "Vmin", "Tc")
)
DYR = (
    DyrModel(
        "GGOV1",
        _RECORD,
        {
            **{f: {"Rdroop": "R", "Kacc": "Ka", "Tacc": "Ta"}.get(f, f) for f in FIELDS},
            "Tmax": "Vmax",
            "Tmin": "Vmin",
            "Tc": "Tc",
        },
        kind=GGOV1,
    ),
)

#: the states: measured electrical power, the governor PID's integral and derivative,
#: the valve stroke, the turbine lead-lag's, the temperature lead-lag's, the measured
#: exhaust temperature, the load limiter's integral, the acceleration filter's, the
#: acceleration limiter's integral
S = states(
    "GGOV1States",
    ("Pe", "gov_i", "gov_d", "valve", "turbine", "temp_ll", "texm", "load_i", "accel_d")
    + ("accel_i",),
)
STATE_NAMES = {GGOV1: S._fields}


def has_state(p: GovernorParams):
    """Which slots of `S` are states: all but the PID's derivative without Kdgov."""
    on = np.ones(p.n, bool)
    return (on, on, (p.Kdgov != 0) & (p.Tdgov >= LBND), *(on,) * 7)


def time_constants(p: GovernorParams):
    """The declared time constants that set a state's speed: field -> where."""
    return {
        **{n: True for n in NEEDS},
        "Tdgov": (p.Kdgov != 0) & (p.Tdgov >= LBND),
    }


def check(g, r: int) -> str | None:
    """The first GGOV1 option of tg_con row r (0-based) stabctl does not model (module
    docstring), with the reason, or None."""
    if g.Teng[r] != 0:
        return (
            "field 'Teng': GGOV1's transport delay is not modelled (PSS/E: 0 or a "
            "multiple of its step); only Teng = 0"
        )
    if g.Rselect[r] not in (1, 0, -1, -2):
        return (
            "field 'Rselect': GGOV1 takes 1 (electrical power), 0 (isochronous), -1 "
            "(fuel valve stroke) or -2 (governor output)"
        )
    if g.Rselect[r] == -2 and g.Rdroop[r] < 0:
        return "field 'R': must be >= 0 with Rselect -2 (the governor output fed back)"
    if g.Kimw[r] != 0:
        return "field 'Kimw': GGOV1's supplementary load controller is not modelled"
    if g.Dm[r] < 0:
        return "field 'Dm': GGOV1 with Dm < 0 (fuel flow times speed^Dm) is not modelled"
    if g.Kdgov[r] != 0 and g.Tdgov[r] < LBND:
        return f"field 'Tdgov': must be >= {LBND} s with Kdgov != 0"
    if g.Kpgov[r] <= 0 or g.Kpload[r] <= 0:
        return "fields 'Kpgov', 'Kpload': must be > 0 (the integrators track through them)"
    if g.Kturb[r] <= 0:
        return "field 'Kturb': must be > 0"
    if g.Flag[r] not in (0, 1):
        return "field 'Flag': must be 0 or 1"
    return None


def initialise(p: GovernorParams, r, pmech0, order, x):
    """GGOV1 at rest on rows r at the initial mechanical power pmech0 (machine base, on
    the turbine base pm0 = pmech0 MVA/Trate): fsr0 = pm0/Kturb + Wfnl (Flag's speed 1,
    Dm's term 0), the valve, the governor's and the load limiter's integrals and the
    temperature at fsr0, the turbine lead-lag at (1 - Tc/Tb) pm0, the measured power at
    pm0, the acceleration limiter's integral at fsr0 + Ta Ka Aset (its rest with the
    tracking); returns P_ref = R sig0 (sig0 = pm0, fsr0 (Rselect -1 and -2) or 0 by
    Rselect).

    Raises CaseError (`refuse_initial`) where the start lies outside a limit: fsr0
    outside [Vmin, Vmax] (PSS/E's valve limits), the load limiter or the acceleration
    limiter below fsr0 at rest (pm0 above Ldref, or Aset < 0: the limiter, not the
    governor, would hold the unit at t = 0), beyond `START_LIMIT_TOL`."""
    pm0 = pmech0 / np.where(r, p.turbine_scale, 1.0)
    kt = np.where(r, p.Kturb, 1.0)
    fsr0 = pm0 / kt + p.Wfnl
    tlim = p.Ldref / kt + p.Wfnl
    fsrt0 = np.minimum(p.Kpload * (tlim - fsr0) + fsr0, 1.0)
    refuse_initial(
        "tg_con",
        r & beyond(fsr0, p.Tmin, p.Tmax),
        lambda i: (
            f"tg_con row {i + 1}: GGOV1's initial fuel order fsr0 = {fsr0[i]:.4f} outside "
            f"[Vmin, Vmax] = [{p.Tmin[i]:.4f}, {p.Tmax[i]:.4f}]"
        ),
    )
    refuse_initial(
        "tg_con",
        r & (beyond(fsr0, -np.inf, fsrt0) | (p.Aset < 0)),
        lambda i: (
            f"tg_con row {i + 1}: GGOV1's load limiter (Ldref {p.Ldref[i]:.4f}, initial "
            f"power {pm0[i]:.4f} pu of Trate) or acceleration limiter (Aset "
            f"{p.Aset[i]:.4f}) is below its governor at rest"
        ),
    )
    tb = np.where(r, p.Tb, 1.0)
    tsb = np.where(r, p.Tsb, 1.0)
    x[S.Pe, r] = pm0[r]
    x[S.gov_i, r] = fsr0[r]
    x[S.gov_d, r] = 0.0
    x[S.valve, r] = fsr0[r]
    x[S.turbine, r] = ((1 - p.Tc / tb) * pm0)[r]
    x[S.temp_ll, r] = ((1 - p.Tsa / tsb) * fsr0)[r]
    x[S.texm, r] = fsr0[r]
    x[S.load_i, r] = fsr0[r]
    x[S.accel_d, r] = 0.0
    x[S.accel_i, r] = (fsr0 + p.Tacc * p.Kacc * p.Aset)[r]
    sig = np.where(p.Rselect == 1, pm0, np.where(np.isin(p.Rselect, (-1, -2)), fsr0, 0.0))
    return (p.Rdroop * sig)[r]


@kernel(inline="always")
def _fuel(P, x, k, omega):
    """The fuel flow w_f: the valve stroke times the speed (Flag 1) or 1 (Flag 0)."""
    return x[S.valve, k] * (omega if P[k, G.FLAG] == 1 else 1.0)


@kernel(inline="always")
def pmech(P, x, k, omega):
    """GGOV1's mechanical power on the machine base: (Kturb (w_f - Wfnl) through (1 + s
    Tc)/(1 + s Tb) - Dm (omega - 1)) times Trate/MVA."""
    u = P[k, G.KTURB] * (_fuel(P, x, k, omega) - P[k, G.WFNL])
    y = leadlag(u, x[S.turbine, k], P[k, G.TC], P[k, G.TB])[0]
    return (y - P[k, G.DM] * (omega - 1.0)) * P[k, G.TSCALE]


@kernel(inline="always")
def _deadband(u, db):
    """The dead zone +-db: 0 inside, u -+ db outside."""
    if u > db:
        return u - db
    if u < -db:
        return u + db
    return 0.0


@kernel(inline="always")
def _error(u, P, k):
    """The governor's speed error: u through the dead zone +-db, limited to [minerr,
    maxerr]."""
    return clip(_deadband(u, P[k, G.DB]), P[k, G.MINERR], P[k, G.MAXERR])


@kernel(inline="always")
def _order_error(P, x, k, d, others):
    """The speed error with Rselect -2: the governor output fsr (the requested stroke) fed
    back, e = error(d - R fsr), fsr = clip(min(fsrn(e), others), Vmin, Vmax), fsrn(e) = a e
    + b (the PID's proportional and derivative paths and its integral), an algebraic loop
    solved exactly.  fsrn falls as fsr rises (a > 0, R >= 0), so the loop has one solution:
    f, the fixed point of f = fsrn(error(d - R f)), found on the piece of the piecewise-linear
    error that holds it (the limits maxerr and minerr, the dead zone, the two slopes), then
    clipped as the gate and the valve limits clip it.  d = P_ref - (omega - 1); others =
    min(fsrt, fsra)."""
    R, db = P[k, G.RDROOP], P[k, G.DB]
    a, b = P[k, G.KPGOV], x[S.gov_i, k]
    if P[k, G.KDGOV] != 0 and P[k, G.TDGOV] >= LBND:
        a += P[k, G.KDGOV] / P[k, G.TDGOV]
        b -= P[k, G.KDGOV] * x[S.gov_d, k] / P[k, G.TDGOV]
    hi, lo = P[k, G.MAXERR], P[k, G.MINERR]
    if _deadband(d - R * (a * hi + b), db) >= hi:  # the error at maxerr
        f = a * hi + b
    elif _deadband(d - R * (a * lo + b), db) <= lo:  # at minerr
        f = a * lo + b
    elif abs(d - R * b) <= db and lo <= 0.0 <= hi:  # in the dead zone
        f = b
    else:  # on a slope, above or below the dead zone
        f = (a * (d - np.sign(d - R * b) * db) + b) / (1.0 + a * R)
    f = clip(min(f, others), P[k, G.TMIN], P[k, G.TMAX])
    return _error(d - R * f, P, k)


@kernel(inline="always")
def derivatives(P, x, k, omega, pe, dx):
    """GGOV1's derivatives into dx[:, k] (module docstring) for its machine's speed omega
    and electrical power pe (pu, machine base); clamps the valve stroke in x."""
    dw = omega - 1.0
    pe_t = pe / P[k, G.TSCALE]
    pe_m, dx[S.Pe, k] = lag(pe_t, x[S.Pe, k], P[k, G.TPELEC])
    # the low-value gate's limiters
    w_f = _fuel(P, x, k, omega)
    t1, dx[S.temp_ll, k] = leadlag(w_f, x[S.temp_ll, k], P[k, G.TSA], P[k, G.TSB])
    texm, dx[S.texm, k] = lag(t1, x[S.texm, k], P[k, G.TFLOAD])
    diff = P[k, G.LDREF] / P[k, G.KTURB] + P[k, G.WFNL] - texm
    fsrt_pi = P[k, G.KPLOAD] * diff + x[S.load_i, k]
    fsrt = min(fsrt_pi, 1.0)
    accel, dx[S.accel_d, k] = washout(dw, x[S.accel_d, k], P[k, G.TACC], 1.0, GAIN_BEFORE)
    fsra = x[S.accel_i, k]
    # the governor
    sel = P[k, G.RSELECT]
    if sel == -2:
        err = _order_error(P, x, k, P[k, G.PREF] - dw, min(fsrt, fsra))
    else:
        sig = pe_m if sel == 1 else (x[S.valve, k] if sel == -1 else 0.0)
        err = _error(P[k, G.PREF] - dw - P[k, G.RDROOP] * sig, P, k)
    fsrn = P[k, G.KPGOV] * err + x[S.gov_i, k]
    if P[k, G.KDGOV] != 0 and P[k, G.TDGOV] >= LBND:
        yd, dx[S.gov_d, k] = washout(err, x[S.gov_d, k], P[k, G.TDGOV], P[k, G.KDGOV], GAIN_BEFORE)
        fsrn += yd
    lvg = min(fsrn, fsrt, fsra)
    # the integrators: their own input, and the tracking of the gate's output
    dx[S.gov_i, k] = P[k, G.KIGOV] * (err + (lvg - fsrn) / P[k, G.KPGOV])
    load = P[k, G.KILOAD] * (diff + (lvg - fsrt_pi) / P[k, G.KPLOAD])
    dx[S.load_i, k] = clip(load, P[k, G.RDOWN], P[k, G.RUP])
    dx[S.accel_i, k] = P[k, G.KACC] * (P[k, G.ASET] - accel) + (lvg - fsra) / P[k, G.TACC]
    # the actuator and the turbine
    fsr = clip(lvg, P[k, G.TMIN], P[k, G.TMAX])
    rate = clip((fsr - x[S.valve, k]) / P[k, G.TACT], P[k, G.RCLOSE], P[k, G.ROPEN])
    x[S.valve, k], dx[S.valve, k] = nonwindup(
        x[S.valve, k], rate, P[k, G.TMIN], P[k, G.TMAX], AT_LIMIT, 0.0
    )
    u = P[k, G.KTURB] * (_fuel(P, x, k, omega) - P[k, G.WFNL])
    dx[S.turbine, k] = leadlag(u, x[S.turbine, k], P[k, G.TC], P[k, G.TB])[1]
