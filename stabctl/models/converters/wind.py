"""The wind turbine of a REECA1 (ibr_con ``wind``, ANDES 2.0's RenGovernor and its chain):
the drive train WTDTA1 (two masses) or WTDS (one), the aerodynamics WTARA1, the pitch
control WTPTA1 and the torque control WTTQA1 (ANDES ``renewable/wtdta1.py``, ``wtds.py``,
``wtara1.py``, ``wtpta1.py``, ``wttqa1.py``): their DYR records, named slots, checks,
initial states and kernels (docs/ibr.md 8).  Their parameters are ibr_con columns 145-182
(``wt_``, ``wa_``, ``wp_``, ``wq_``, :mod:`.table`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.models.blocks import anti_windup, clip, lag, pi_aw_hard_limit
from stabctl.models.converters.reeca1 import RE
from stabctl.models.converters.repca1 import PC
from stabctl.models.converters.table import NO_WIND, WTDS, WTDTA1, C
from stabctl.models.declaration import DyrModel, slots

if TYPE_CHECKING:
    from stabctl.models.converters import ConverterParams


DYR = (
    DyrModel(
        "WTDTA1",
        ("H", "DAMP", "Htfrac", "Freq1", "Dshaft"),
        {f"wt_{n}": n for n in ("H", "DAMP", "Htfrac", "Freq1", "Dshaft")},
    ),
    DyrModel("WTARA1", ("Ka", "Theta0"), {"wa_Ka": "Ka", "wa_theta0": "Theta0"}),
    DyrModel(
        "WTPTA1",
        ("Kiw", "Kpw", "Kic", "Kpc", "Kcc", "Tp", "TetaMax", "TetaMin", "RTetaMax", "RTetaMin"),
        {f"wp_{n}": n for n in ("Kiw", "Kpw", "Kic", "Kpc", "Kcc", "Tp")}
        | {"wp_thmax": "TetaMax", "wp_thmin": "TetaMin"}
        | {"wp_dthmax": "RTetaMax", "wp_dthmin": "RTetaMin"},
    ),
    #: WTTQ_A: ICON Tflag, then 15 CONs (TRATE: the turbine's MW rating, 0 its MBASE)
    DyrModel(
        "WTTQA1",
        ("Tflag", "Kpp", "Kip", "Tp", "Twref", "Temax", "Temin")
        + tuple(f"{v}{j}" for j in range(1, 5) for v in ("p", "spd"))
        + ("TRATE",),
        {f"wq_{n}": n for n in ("Tflag", "Kpp", "Kip", "Tp", "Twref", "Temax", "Temin")}
        | {f"wq_p{j}": f"p{j}" for j in range(1, 5)}
        | {f"wq_sp{j}": f"spd{j}" for j in range(1, 5)}
        | {"wq_Tn": "TRATE"},
    ),
)

#: the wind turbine's slots (``wind`` 1 or 2): the drive train's turbine and generator
#: speeds and shaft torque (WTDS: its one speed in ``wt``), WTTQA1's Pe filter, speed
#: reference and PI, WTPTA1's two PIs and pitch angle (deg)
WIND_SLOTS = (
    *("wt", "wg", "Tshaft", "Pe_filter_tq", "wref_tq", "PI_tq"),
    *("PIc_pitch", "PIw_pitch", "theta_pitch"),
)
#: the named slots, after the plant control's
WT = slots("WindSlots", WIND_SLOTS, first=int(PC[-1]) + 1)


def check(t, ree) -> None:
    """Refuse a wind turbine that its models cannot run: one without a REECA1 (``ree``
    the rows with one), a pitch control without the aerodynamics, a torque control
    without the pitch control (ANDES chains them: WTTQA1 -> WTPTA1 -> WTARA1 -> the drive
    train), a WTDTA1 whose inertia split Htfrac is not inside (0, 1) (WTDS is the one-mass
    train), an inertia H not above 0."""
    wind = t.wind != NO_WIND
    rules = (
        ("wind", wind & ~ree, "a wind turbine drives a REECA1 (reec 1) only"),
        ("aero", (t.aero == 1) & ~wind, "the aerodynamics need a drive train (wind 1 or 2)"),
        ("pitch", (t.pitch == 1) & (t.aero != 1), "a pitch control needs the aerodynamics"),
        ("torque", (t.torque == 1) & (t.pitch != 1), "a torque control needs the pitch control"),
        ("wt_H", wind & (t.wt_H <= 0), "must be > 0 (the drive train's inertia)"),
        (
            "wt_Htfrac",
            (t.wind == WTDTA1) & ((t.wt_Htfrac <= 0) | (t.wt_Htfrac >= 1)),
            "must lie inside (0, 1) for a two-mass WTDTA1 (WTDS: one mass)",
        ),
    )
    for field, bad, why in rules:
        rows = np.flatnonzero(bad)
        if rows.size:
            t._fail(rows[0], field, why)


def torque_limits(cp: ConverterParams) -> None:
    """WTTQA1's upper torque limit raised, in place, to its PI's initial output P0/fPe(P0)
    where that lies above it, as ANDES does when a limiter starts beyond its upper limit
    (andes/core/discrete.py Limiter ``allow_adjust``, ``adjust_upper``; kundur_wtds.xlsx:
    7 pu through a 100 MVA turbine against Temax 1.2)."""
    P = cp.packed()
    for k in np.flatnonzero(cp.torque == 1):
        torque0 = cp.P0[k] / _speed_curve.py_func(P, k, cp.P0[k])
        cp.wq_Temax[k] = max(cp.wq_Temax[k], torque0)


def initial(cp: ConverterParams, x: np.ndarray) -> None:
    """The wind turbines' initial states in x (N_STATES, n_ibr), in place (ANDES's
    initialisation, the torque control's values set last): both speeds at fPe(P0) with
    a torque control (WTTQA1), else at w0; the shaft torque P0 over that speed (WTDTA1);
    WTTQA1's Pe filter at P0, its speed reference at fPe(P0), its PI's integrator at
    P0/fPe(P0); WTPTA1's integrators at 0 and its pitch angle at the PIs' outputs (the
    speed PI's clip(Kpw (w - w0), thmin, thmax)).  PSS/E's reading (``psse`` 1): the pitch
    angle at WTARA1's theta0 (deg), held by the speed PI's integrator (its error wt -
    wref 0 at the start), the power PI's at 0 (PSS/E Model Library WTPTA1, WTARA1: the
    aerodynamics at rest at theta = theta0; GridPACK ``wtpta1.cpp`` starts the pitch lag
    at WTARA1's Theta0)."""
    P = cp.packed()
    for k in np.flatnonzero(cp.wind != NO_WIND):
        w = _speed_curve.py_func(P, k, cp.P0[k]) if cp.torque[k] == 1 else cp.wt_w0[k]
        x[WT.wt, k] = w
        if cp.wind[k] == WTDTA1:
            x[WT.wg, k] = w
            x[WT.Tshaft, k] = cp.P0[k] / w
        if cp.torque[k] == 1:
            x[WT.Pe_filter_tq, k], x[WT.wref_tq, k], x[WT.PI_tq, k] = cp.P0[k], w, cp.P0[k] / w
        if cp.pitch[k] == 1 and cp.psse[k] == 1:
            theta0 = np.clip(cp.wa_theta0[k], cp.wp_thmin[k], cp.wp_thmax[k])
            x[WT.PIw_pitch, k] = x[WT.theta_pitch, k] = theta0
        elif cp.pitch[k] == 1:
            lo, hi = cp.wp_thmin[k], cp.wp_thmax[k]
            yw = np.clip(cp.wp_Kpw[k] * (w - cp.wt_w0[k]), lo, hi)
            x[WT.theta_pitch, k] = yw + np.clip(0.0, lo, hi)


@kernel
def rest(P, k, dx):
    """Zero the derivatives of device k's wind slots (those its wind models do not write:
    all without a turbine)."""
    for j in range(len(WIND_SLOTS)):
        dx[WT.wt + j, k] = 0.0


@kernel
def _speeds(P, x, k):
    """The turbine and generator speeds (wt, wg) of device k's drive train, pu: WTDTA1's
    two masses, WTDS's one (both its speed)."""
    if P[k, C.WIND] == WTDS:
        return x[WT.wt, k], x[WT.wt, k]
    return x[WT.wt, k], x[WT.wg, k]


@kernel
def _speed_curve(P, k, u):
    """WTTQA1's speed reference fPe of device k at filtered power u (ANDES Piecewise of
    the points (p_j, sp_j), j = 1..4, flat beyond them)."""
    if u <= P[k, C.WQ_P1]:
        return P[k, C.WQ_SP1]
    if u <= P[k, C.WQ_P2]:
        kp = (P[k, C.WQ_SP2] - P[k, C.WQ_SP1]) / (P[k, C.WQ_P2] - P[k, C.WQ_P1])
        return P[k, C.WQ_SP1] + (u - P[k, C.WQ_P1]) * kp
    if u <= P[k, C.WQ_P3]:
        kp = (P[k, C.WQ_SP3] - P[k, C.WQ_SP2]) / (P[k, C.WQ_P3] - P[k, C.WQ_P2])
        return P[k, C.WQ_SP2] + (u - P[k, C.WQ_P2]) * kp
    if u <= P[k, C.WQ_P4]:
        kp = (P[k, C.WQ_SP4] - P[k, C.WQ_SP3]) / (P[k, C.WQ_P4] - P[k, C.WQ_P3])
        return P[k, C.WQ_SP3] + (u - P[k, C.WQ_P3]) * kp
    return P[k, C.WQ_SP4]


@kernel
def reference(P, x, k, Pe, dx):
    """The REECA1's speed and P reference from device k's wind turbine at its output Pe
    (pu): WTTQA1 (ANDES wttqa1.py) Pe through the lag Tp to the speed curve fPe, fPe
    through the lag Twref to wref, the PI (Kpp, Kip; windup and output limits [Temin,
    Temax]: ANDES's PIAWHardLimit, `blocks.pi_aw_hard_limit`) of (Pe - P0)/wg (Tflag 1)
    or wref - wg (0), Pref = PI wg; the REECA1's speed 1 + wg - fPe (ANDES's sum of the
    drive train's wg - 1 and the torque control's 1 - fPe).  PSS/E's reading (``psse``
    1) of Tflag 1: (P0 - the Tp-filtered Pe)/wg, the power held at its reference (GridPACK
    ``wttqa1.cpp``: (Pref0 - Pelec_filter)/(1 + domega_g); InterPSS's ``Wttqa1Model``:
    (Pref - filtered P)/wg), where ANDES's (Pe - P0)/wg raises the reference with the
    power (a positive feedback through the converter's P order); of Tflag 0: wg - wref, a
    generator above its speed reference takes more torque and slows (GridPACK's
    ``wttqa1.cpp`` 1 + domega_g - omega_ref; Dynawo's ``WTGQa.mo``; PowerWorld's WTGTRQ_A
    diagram), where ANDES's and InterPSS's wref - wg lowers the torque of a fast generator:
    a real eigenvalue of +0.405 1/s on a WTDTA1 drive train (round 52, AN03).  Without a
    torque control: Pref = P0/wg, the speed wg.  Returns (speed, Pref, the drive train's
    speed reference wr0: fPe, or w0 without WTTQA1)."""
    _, wg = _speeds(P, x, k)
    if P[k, C.TORQUE] == 0.0:
        return wg, P[k, C.P0] / wg, P[k, C.WT_W0]
    Pef, dx[WT.Pe_filter_tq, k] = lag(Pe, x[WT.Pe_filter_tq, k], P[k, C.WQ_TP])
    fPe = _speed_curve(P, k, Pef)
    wref, dx[WT.wref_tq, k] = lag(fPe, x[WT.wref_tq, k], P[k, C.WQ_TWREF])
    if P[k, C.WQ_TFLAG] != 1.0:  # PSS/E: a fast generator takes more torque
        Tsel = wg - wref if P[k, C.PSSE] == 1.0 else wref - wg
    elif P[k, C.PSSE] == 1.0:  # PSS/E: (Pref0 - the filtered Pe)/wg, negative feedback
        Tsel = (P[k, C.P0] - Pef) / wg
    else:
        Tsel = (Pe - P[k, C.P0]) / wg
    lo, hi = P[k, C.WQ_TEMIN], P[k, C.WQ_TEMAX]
    y, x[WT.PI_tq, k], dx[WT.PI_tq, k] = pi_aw_hard_limit(
        Tsel, x[WT.PI_tq, k], P[k, C.WQ_KPP], P[k, C.WQ_KIP], lo, hi
    )
    return 1.0 + wg - fPe, y * wg, fPe


@kernel
def _pitch_angle(P, x, k, wt, Pord, Pref, dx):
    """WTPTA1's pitch angle of device k (ANDES wtpta1.py, deg): the PI (Kpc, Kic) of
    Pord - Pref plus the PI (Kpw, Kiw) of Kcc (Pord - Pref) + wt - w0 (its speed
    reference: the drive train's w0, as ANDES initialises it), each limited to [thmin,
    thmax] (ANDES's PIAWHardLimit, `blocks.pi_aw_hard_limit`), through the lag Tp with
    the rate limits [dthmin, dthmax] on Tp dtheta/dt and the anti-windup limits [thmin,
    thmax] (LagAntiWindupRate; `blocks.anti_windup`).  PSS/E's reading (``psse`` 1): the
    speed reference is WTTQA1's wref (the Twref lag's state; w0 without a torque
    control), as the PSS/E Model Library's WTPTA1 and WECC's WTGPT_A take it from the
    torque control (GridPACK ``wtpta1.cpp``: wt - wref, ``setSpeedReference``), and the
    rate limits RTetaMax, RTetaMin bound dtheta/dt (deg/s), not Tp dtheta/dt."""
    lo, hi = P[k, C.WP_THMIN], P[k, C.WP_THMAX]
    e = Pord - Pref
    yc, x[WT.PIc_pitch, k], dx[WT.PIc_pitch, k] = pi_aw_hard_limit(
        e, x[WT.PIc_pitch, k], P[k, C.WP_KPC], P[k, C.WP_KIC], lo, hi
    )
    wref = P[k, C.WT_W0]
    if P[k, C.PSSE] == 1.0 and P[k, C.TORQUE] == 1.0:
        wref = x[WT.wref_tq, k]
    u = P[k, C.WP_KCC] * e + wt - wref
    yw, x[WT.PIw_pitch, k], dx[WT.PIw_pitch, k] = pi_aw_hard_limit(
        u, x[WT.PIw_pitch, k], P[k, C.WP_KPW], P[k, C.WP_KIW], lo, hi
    )
    Tp = P[k, C.WP_TP]
    if P[k, C.PSSE] == 1.0:  # PSS/E: RTetaMax, RTetaMin bound dtheta/dt, deg/s
        r = clip((yw + yc - x[WT.theta_pitch, k]) / Tp, P[k, C.WP_DTHMIN], P[k, C.WP_DTHMAX])
        Tp = 1.0
    else:  # ANDES's LagAntiWindupRate: Tp dtheta/dt
        r = clip(yw + yc - x[WT.theta_pitch, k], P[k, C.WP_DTHMIN], P[k, C.WP_DTHMAX])
    x[WT.theta_pitch, k], r = anti_windup(x[WT.theta_pitch, k], r, lo, hi)
    dx[WT.theta_pitch, k] = r / Tp
    return x[WT.theta_pitch, k]


@kernel
def mechanics(P, x, k, Pe, wg_ree, wr0, Pref, dx):
    """Device k's turbine (ANDES wtdta1.py, wtds.py, wtara1.py) at its output Pe, the
    REECA1's speed wg_ree and P reference Pref, the speed reference wr0: the aerodynamic
    power Pm = P0 - Ka theta (theta - theta0) (WTARA1; theta = rad(theta0) - theta0 plus
    the pitch angle, ANDES's mix of radians and degrees kept), P0 without; WTDTA1 2 Ht
    dwt/dt = Pm/wt - Tshaft - pd, 2 Hg dwg/dt = -Pe/wg + Tshaft - DAMP (wg - w0) + pd,
    dTshaft/dt = Kshaft (wt - wg), pd = Dshaft (wt - wg), Ht = Htfrac H, Hg = H - Ht,
    Kshaft = 2 Ht Hg Freq1^2/H; WTDS 2 H dw/dt = (Pm - Pe)/wg_ree - DAMP (w - wr0).

    PSS/E's reading (``psse`` 1, import-psse's default): theta is the pitch angle in
    degrees throughout (theta0 without a pitch control), so that Pm = P0 at theta =
    theta0 (PSS/E Model Library WTARA1); Freq1 is in Hz, Kshaft = 2 Ht Hg (2 pi
    Freq1)^2/H (OpenIPSL ``WTDTA1.mo``: Kshaft = 2 Ht Hg (2 pi Freq1)^2/(H w0) on the
    shaft angle, whose rate is w0 (wt - wg)), the torsional mode at about Freq1 Hz."""
    wt, wg = _speeds(P, x, k)
    theta0 = P[k, C.WA_THETA0]
    psse = P[k, C.PSSE] == 1.0
    theta = theta0 if psse else np.deg2rad(theta0)
    if P[k, C.PITCH] == 1.0:
        theta += _pitch_angle(P, x, k, wt, x[RE.Pord, k], Pref, dx) - theta0
    Pm = P[k, C.P0]
    if P[k, C.AERO] == 1.0:
        Pm += -(theta - theta0) * theta * P[k, C.WA_KA]
    H = P[k, C.WT_H]
    if P[k, C.WIND] == WTDS:
        d = (Pm - Pe) / wg_ree - P[k, C.WT_DAMP] * (wt - wr0)
        dx[WT.wt, k] = d / (2.0 * H)
        return
    Ht2 = 2.0 * (P[k, C.WT_HTFRAC] * H)
    Hg2 = 2.0 * H * (1.0 - P[k, C.WT_HTFRAC])
    pd = P[k, C.WT_DSHAFT] * (wt - wg)
    dx[WT.wt, k] = (Pm / wt - x[WT.Tshaft, k] - pd) / Ht2
    dx[WT.wg, k] = (-Pe / wg + x[WT.Tshaft, k] - P[k, C.WT_DAMP] * (wg - P[k, C.WT_W0]) + pd) / Hg2
    w_shaft = 2.0 * np.pi * P[k, C.WT_FREQ1] if psse else P[k, C.WT_FREQ1]
    dx[WT.Tshaft, k] = Ht2 * Hg2 * 0.5 * w_shaft**2 / H * (wt - wg)
