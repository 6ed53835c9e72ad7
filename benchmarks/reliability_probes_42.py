#!/usr/bin/env python
"""Round 52 (AL): model fidelity of the WECC second-generation renewable models as stabctl
reads them from PSS/E DYR files, in the paths the PSS/E runs (tests/data/psse_runs/RENA_*:
REGCA1 + REECB1 + REPCA1, defaults) and rounds 32, 40, 41 leave untested: REECA1's
voltage-dip logic (Iqinj Kqv with dbd1/dbd2, Thld > 0 / < 0, Iqfrz, Thld2), its VDL
curves and PQFLAG priority; REGCA1's low-voltage active current management (Lvpnt0,
Lvpnt1), its LVPL (Lvplsw 1), its high-voltage reactive current management (Volim, Khv)
and Rrpwr on recovery; REPCA1's frequency path (Fflag 1, Ddn/Dup, fdbd1/fdbd2, Pmax) and
its voltage compensation (VcFlag 0 with Kc, VcFlag 1 with Rc/Xc).

How: the RENA case (ThreeBusRenewable.raw: the plant on bus 103, an infinite GENCLS on
bus 102) with a DYR whose REECA1 record (PSS/E's CON order) replaces the REECB1, run by
stabctl's Simulator (Heun, h = 1/960 s) through a fault at bus 103 through a reactance
(|V| 0.47-0.7 pu), a reactive load step, or a load step against a damped GENCLS (a
frequency offset).  Each controller is then integrated here from the reference's
equations, driven by the terminal voltage stabctl recorded (so only the controller
differs), and its P, Q compared with stabctl's; or a closed form (a steady state, a
limit, the time a timer expires) is checked on stabctl's record.

    CLONE=<clone> PYTHONPATH=<clone> python benchmarks/reliability_probes_42.py [AL01,AL03,...]

References (read with the search tools; equations written here, never stabctl's):
  GridPACK  GridOPTICS/GridPACK src/applications/modules/dynamic_simulation_full_y/
            model_classes/reeca1.cpp (predictor: Iqinj_sw states, Thld; CurrentLimitLogic),
            regca1.cpp (INorton: Lvpnt, Khv (V - Volim), Iolim)
  Dynawo    dynawo/dynawo dynawo/sources/Models/Modelica/Dynawo/Electrical/Controls/WECC/
            BaseControls/IqInjectionLogic.mo, CurrentLimitsCalculationA.mo (Thld2),
            REGC/REGCa.mo + REGC/BaseClasses/BaseREGC.mo (Rrpwr, LVPL on the output)
  OpenIPSL  OpenIPSL/OpenIPSL OpenIPSL/Electrical/Renewables/PSSE/ElectricalController/
            REECA1.mo, InverterInterface/REGCA1.mo (rrpwr on the lag's error),
            PlantController/REPCA1.mo

Found (round 52; the four REAL fixed the same day under PSS/E's reading, the probes since
compared with the references' Vt_filt divisions): REAL AL02 (REECA1/REECB1 divide the power order and the Q reference by
the raw |V|, the references by Vt_filt: P 0.444 vs 0.554 pu 10 ms after clearing), AL06
(the VDL curve of the lower-priority current is not applied: Q priority Ipmax = room
only, P priority Iqmax = room only; all three references take min(VDL, room)), AL08
(REGCA1 LVPL: a limit that falls below an Ip at its command (e < 0) does not bind, P 0.19
vs 0.158 pu in the fault; Dynawo and OpenIPSL limit the lag's output), AL13 (REPCA1 with
no monitored branch measures Pline = Qline = 0, so Fflag 1 becomes isochronous; GridPACK
and Dynawo measure the plant's own output).  AL09 (Rrpwr), DOUBTFUL in round 52 (OpenIPSL
and ANDES Rrpwr/Tg on the rise; Dynawo 2023 +-Rrpwr pu/s), settled in round 54: pu/s on
the rise of |Ip| under PSS/E's reading (GridPACK, InterPSS, Dynawo 2025, GridKit).  Ok (to 1e-4 pu or better): the 45
REECA1 CONs, the dip's Iqinj with dbd and freeze, Thld > 0 (Iqfrz) and < 0 as GridPACK
(Dynawo reads the sign the other way), Thld2, LVACM, Khv/Volim, Fflag 1 droop with a
branch, Pmax on the total reference, VcFlag 0 (Kc) and 1 (Rc, Xc), REECA1 QFLAG 1 with
VFLAG 1 and 0.  About 10 s with a warm kernel cache.
"""

# ruff: noqa
import os
import shutil
import sys
import tempfile
import traceback
import warnings
from pathlib import Path

import numpy as np

warnings.simplefilter("ignore")
CLONE = Path(os.environ.get("CLONE", Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(CLONE))

from stabctl.case.events import Fault, LoadStep  # noqa: E402
from stabctl.dynamics.driver import Simulator  # noqa: E402
from stabctl.io.psse import load_psse  # noqa: E402

TMP = Path(tempfile.mkdtemp(prefix="al52_"))
RAW = CLONE / "tests" / "data" / "psse_runs" / "RENA_DEFAULT" / "ThreeBusRenewable.raw"
PROBES = {}
H = 1 / 960


def probe(pid):
    def deco(f):
        PROBES[pid] = f
        return f

    return deco


# ------------------------------------------------------------------------ the DYR records
#: REGCA1: ICON Lvplsw; CONs Tg Rrpwr Brkpt Zerox Lvpl1 Volim Lvpnt1 Lvpnt0 Iolim Tfltr Khv
#: Iqrmax Iqrmin Accel (PSS/E order; RENA's values, Rrpwr opened to 999 but where probed)
REGC = dict(
    Lvplsw=0,
    Tg=0.02,
    Rrpwr=999.0,
    Brkpt=0.9,
    Zerox=0.4,
    Lvpl1=1.22,
    Volim=1.2,
    Lvpnt1=0.9,
    Lvpnt0=0.5,
    Iolim=-1.3,
    Tfltr=0.2,
    Khv=0.0,
    Iqrmax=100.0,
    Iqrmin=-100.0,
    Accel=0.0,
)
#: REECA1: ICONs IREG PFFLAG VFLAG QFLAG PFLAG PQFLAG; 45 CONs in PSS/E order
REEC_ICONS = ("IREG", "PFFLAG", "VFLAG", "QFLAG", "PFLAG", "PQFLAG")
REEC = dict(
    IREG=0,
    PFFLAG=0,
    VFLAG=0,
    QFLAG=0,
    PFLAG=0,
    PQFLAG=0,
    Vdip=0.9,
    Vup=1.3,
    Trv=0.02,
    dbd1=-0.05,
    dbd2=0.05,
    Kqv=2.0,
    Iqh1=1.05,
    Iql1=-1.05,
    Vref0=0.0,
    Iqfrz=0.0,
    Thld=0.0,
    Thld2=0.0,
    Tp=0.02,
    QMax=0.44,
    QMin=-0.44,
    VMAX=1.1,
    VMIN=0.9,
    Kqp=0.0,
    Kqi=0.01,
    Kvp=10.0,
    Kvi=60.0,
    Vref1=0.0,
    Tiq=0.02,
    dPmax=99.0,
    dPmin=-99.0,
    PMAX=1.2,
    PMIN=0.0,
    Imax=1.11,
    Tpord=0.02,
    **{f"{v}{j}": 0.0 for pair in (("Vq", "Iq"), ("Vp", "Ip")) for j in range(1, 5) for v in pair},
)
#: REPCA1: ICONs IREG BUS1 BUS2 CKT VCFlag RefFlag Fflag; 27 CONs in PSS/E order
REPC_ICONS = ("IREG", "BUS1", "BUS2", "CKT", "VCFlag", "RefFlag", "Fflag")
REPC = dict(
    IREG=0,
    BUS1=0,
    BUS2=0,
    CKT="'0 '",
    VCFlag=0,
    RefFlag=1,
    Fflag=0,
    Tfltr=0.02,
    Kp=0.0,
    Ki=5.0,
    Tft=0.0,
    Tfv=0.05,
    Vfrz=0.0,
    Rc=0.0,
    Xc=0.0,
    Kc=0.0,
    emax=0.3,
    emin=-0.3,
    dbd1=0.0,
    dbd2=0.0,
    Qmax=0.43,
    Qmin=-0.43,
    Kpg=0.0,
    Kig=2.0,
    Tp=0.05,
    fdbd1=-0.0002833,
    fdbd2=0.0002833,
    femax=99.0,
    femin=-99.0,
    Pmax=1.2,
    Pmin=0.0,
    Tg=0.05,
    Ddn=20.0,
    Dup=20.0,
)


def _fmt(v):
    return (
        v
        if isinstance(v, str)
        else (
            str(int(v))
            if float(v).is_integer() and abs(v) < 1e6 and not isinstance(v, float)
            else repr(float(v))
        )
    )


def record(name, d, n_icons):
    vals = list(d.values())
    icons = " ".join(str(int(v)) if not isinstance(v, str) else v for v in vals[:n_icons])
    cons = " ".join(repr(float(v)) for v in vals[n_icons:])
    return f"    103 '{name}' 1 {icons}\n  {cons} /\n"


def dyr(regc=None, reec=None, repc=None, gencls="0.0 0.0"):
    g = {**REGC, **(regc or {})}
    e = {**REEC, **(reec or {})}
    txt = f"    102 'GENCLS' 1 {gencls} /\n"
    txt += record("REGCA1", g, 1) + record("REECA1", e, len(REEC_ICONS))
    if repc is not None:
        txt += record("REPCA1", {**REPC, **repc}, len(REPC_ICONS))
    return txt


def simulate(events, t_end=1.0, **parts):
    """stabctl's run of the RENA case with the plant's records: (t, |V|, angle, P, Q of
    the plant, the case, the machine speed of bus 102)."""
    path = TMP / f"c{len(os.listdir(TMP))}.dyr"
    path.write_text(dyr(**parts))
    raw = TMP / "ThreeBusRenewable.raw"
    if not raw.exists():
        shutil.copy(RAW, raw)
    case = load_psse(str(raw), str(path))
    res = Simulator(case, background_compile=False).run(events, t_end=t_end, h=H)
    j = list(res.buses).index(103)
    return dict(
        t=res.t,
        v=res.vmag[:, j],
        a=res.vang[:, j],
        p=res.ibr_p[:, 0],
        q=res.ibr_q[:, 0],
        case=case,
        speed=res.speed[:, 0] if res.speed.size else None,
    )


# ----------------------------------------------------------------- the reference plant
def lvacm(v, p):
    """Low-voltage active current management (GridPACK regca1.cpp Lvpnt_blk, OpenIPSL
    LVACM.mo): 0 below Lvpnt0, 1 above Lvpnt1, linear between."""
    return float(np.clip((v - p["Lvpnt0"]) / (p["Lvpnt1"] - p["Lvpnt0"]), 0.0, 1.0))


def lvpl(vf, p):
    """Low-voltage power logic (Dynawo LowVoltagePowerLogic.mo, OpenIPSL LVPL.mo): 0 below
    Zerox, Lvpl1 (v - Zerox)/(Brkpt - Zerox) up to Brkpt, 9999 above."""
    if vf < p["Zerox"]:
        return 0.0
    if vf > p["Brkpt"]:
        return 9999.0
    return p["Lvpl1"] * (vf - p["Zerox"]) / (p["Brkpt"] - p["Zerox"])


def vdl(u, V, I):
    """A REECA1 VDL curve (GridPACK's piecewise-linear table, the ends held); no points
    (all 0): no limit."""
    if not any(V) and not any(I):
        return 1e8
    return float(np.interp(u, V, I))


def dbd(u, lo, hi):
    """Dead zone (Modelica DeadZone, GridPACK deadband): u - hi above hi, u - lo below lo."""
    return u - hi if u > hi else (u - lo if u < lo else 0.0)


def reference(
    rec,
    regc=None,
    reec=None,
    n_sub=8,
    thld_sign="gridpack",
    lvpl_kind="output",
    rrpwr_kind="pu/s",
    div="filtered",
):
    """REGCA1 + REECA1 (QFLAG 0, VFLAG 0, PFFLAG 0, PFLAG 0) of the PSS/E reading the
    references write, driven by stabctl's recorded |V| (linear between samples; on the
    step of an event, the sample after it): (P, Q) at the samples.

    REECA1 (GridPACK reeca1.cpp, Dynawo BaseREEC): Vt filter Trv; a dip while |V| < Vdip
    or > Vup (raw |V|); Iq path Q0/max(Vf, 0.01) through Tiq, frozen in a dip; Iqinj =
    clip(Kqv dbd(Vref0 - Vf), Iql1, Iqh1) in a dip, after it for |Thld| s: thld_sign
    "gridpack" (Thld > 0: Iqfrz, Thld < 0: the voltage-dependent injection; OpenIPSL's
    parameter text the same) or "dynawo" (IqInjectionLogic.mo: the opposite); Pord lag
    Tpord frozen in a dip, in [PMIN, PMAX]; Q priority (PQFLAG 0): Iqmax = min(VDLq(Vf),
    Imax), Ipmax = min(VDLp(Vf), sqrt(Imax^2 - Iqcmd^2)); P priority: Ipmax = min(VDLp, Imax),
    Iqmax = min(VDLq, sqrt(Imax^2 - Ipcmd^2)); Thld2: Ipmax held at its value at the dip's end
    for Thld2 s (Dynawo CurrentLimitsCalculationA.mo).  REGCA1: Ip lag Tg (Rrpwr: "pu/s",
    Dynawo's dy/dt in [-Rrpwr, Rrpwr]; "over Tg", OpenIPSL's error clipped at Rrpwr before
    1/Tg), LVPL on the voltage filtered by Tfltr ("output": Dynawo's limiter after the lag,
    OpenIPSL's VariableLimiter; "state": the lag's state clamped); Iq lag Tg; P = V Ip LVACM(V),
    Q = V (Iq - max(0, Khv (V - Volim))), the reactive current floored by Iolim (GridPACK)."""
    g = {**REGC, **(regc or {})}
    e = {**REEC, **(reec or {})}
    t, V = rec["t"], rec["v"]
    ev = rec.get("events", ())
    v0, P0, Q0 = V[0], rec["p"][0], rec["q"][0]
    Vref0 = e["Vref0"] if e["Vref0"] != 0 else v0
    Vq = [e[f"Vq{j}"] for j in range(1, 5)]
    Iqv = [e[f"Iq{j}"] for j in range(1, 5)]
    Vp = [e[f"Vp{j}"] for j in range(1, 5)]
    Ipv = [e[f"Ip{j}"] for j in range(1, 5)]
    Imax = e["Imax"]
    # states: Vf (Trv), Iqlag (Tiq), Pord (Tpord), Ip, Iq (Tg), Vfl (Tfltr)
    x = np.array([v0, Q0 / v0, P0, P0 / v0, Q0 / v0, v0])
    mem = dict(dip=False, end=-1.0, ipmax_frz=None, ipmax=None)

    def V_at(tt, k):
        if any(abs(t[k + 1] - te) < 1e-9 for te in ev):
            return V[k]  # the event at the step's end: the voltage before it
        w = (tt - t[k]) / (t[k + 1] - t[k])
        return (1 - w) * V[k] + w * V[k + 1]

    def algebra(tt, y, v, commit=False):
        Vf, Iql, Pord, Ip, Iq, Vfl = y
        dip = v < e["Vdip"] or v > e["Vup"]
        end = mem["end"]
        if mem["dip"] and not dip:
            end = tt  # the dip has just ended (within this step)
        after = (not dip) and end >= 0 and tt - end <= abs(e["Thld"])
        inj_v = float(
            np.clip(e["Kqv"] * dbd(Vref0 - Vf, e["dbd1"], e["dbd2"]), e["Iql1"], e["Iqh1"])
        )
        if dip:
            Iqinj = inj_v
        elif after and e["Thld"] != 0:
            frz = (e["Thld"] > 0) == (thld_sign == "gridpack")
            Iqinj = e["Iqfrz"] if frz else inj_v
        else:
            Iqinj = 0.0
        vfc = max(Vf if div == "filtered" else v, 0.01)
        q_vdl, p_vdl = vdl(Vf, Vq, Iqv), vdl(Vf, Vp, Ipv)
        ipo = min(max(Pord, e["PMIN"]), e["PMAX"]) / vfc
        if e["PQFLAG"] == 0:
            Iqmax = min(q_vdl, Imax)
            Iqcmd = float(np.clip(Iql + Iqinj, -Iqmax, Iqmax))
            Ipmax = min(p_vdl, np.sqrt(max(Imax**2 - Iqcmd**2, 0.0)))
        else:
            Ipmax = min(p_vdl, Imax)
            ipc = min(max(ipo, 0.0), Ipmax)
            Iqmax = min(q_vdl, np.sqrt(max(Imax**2 - ipc**2, 0.0)))
            Iqcmd = float(np.clip(Iql + Iqinj, -Iqmax, Iqmax))
        hold2 = (not dip) and end >= 0 and e["Thld2"] > 0 and tt - end <= e["Thld2"]
        if hold2 and mem["ipmax_frz"] is not None:
            Ipmax = mem["ipmax_frz"]
        Ipcmd = min(max(ipo, 0.0), Ipmax)
        if commit:
            if mem["dip"] and not dip:
                mem["end"] = tt
                mem["ipmax_frz"] = mem["ipmax"]
            mem["dip"] = dip
            if dip:
                mem["ipmax"] = Ipmax
        return dip, Iqcmd, Ipcmd

    def deriv(tt, y, v):
        Vf, Iql, Pord, Ip, Iq, Vfl = y
        dip, Iqcmd, Ipcmd = algebra(tt, y, v)
        d = np.zeros(6)
        d[0] = (v - Vf) / e["Trv"]
        vd = max(Vf if div == "filtered" else v, 0.01)
        d[1] = 0.0 if dip else (Q0 / vd - Iql) / e["Tiq"]
        dp = 0.0 if dip else (P0 - Pord) / e["Tpord"]
        if (Pord >= e["PMAX"] and dp > 0) or (Pord <= e["PMIN"] and dp < 0):
            dp = 0.0
        d[2] = dp
        lim = lvpl(Vfl, g) if g["Lvplsw"] else 9999.0
        err = Ipcmd - Ip
        if rrpwr_kind == "pu/s":
            d[3] = float(np.clip(err / g["Tg"], -g["Rrpwr"], g["Rrpwr"]))
        elif rrpwr_kind == "rise pu/s":
            d[3] = min(err / g["Tg"], g["Rrpwr"])
        else:
            d[3] = min(err, g["Rrpwr"]) / g["Tg"]
        if lvpl_kind == "state" and Ip >= lim and d[3] > 0:
            d[3] = 0.0
        d[4] = (Iqcmd - Iq) / g["Tg"]
        d[5] = (v - Vfl) / g["Tfltr"]
        return d

    def clamp(y):
        if lvpl_kind == "state" and g["Lvplsw"]:
            y[3] = min(y[3], lvpl(y[5], g))
        y[2] = min(max(y[2], e["PMIN"]), e["PMAX"])
        return y

    def out(y, v):
        ip = y[3]
        if g["Lvplsw"] and lvpl_kind == "output":
            ip = min(ip, lvpl(y[5], g))
        iq = max(y[4] - max(0.0, g["Khv"] * (v - g["Volim"])), g["Iolim"])
        return v * ip * lvacm(v, g), v * iq

    Ps, Qs = [out(x, V[0])[0]], [out(x, V[0])[1]]
    algebra(t[0], x, V[0], commit=True)
    for k in range(len(t) - 1):
        h = (t[k + 1] - t[k]) / n_sub
        for m in range(n_sub):
            t0 = t[k] + m * h
            v1, v2 = V_at(t0, k), V_at(t0 + h, k)
            k1 = deriv(t0, x, v1)
            x2 = clamp(x + h * k1)
            k2 = deriv(t0 + h, x2, v2)
            x = clamp(x + h / 2 * (k1 + k2))
            algebra(t0 + h, x, v2, commit=True)
        p_, q_ = out(x, V[k + 1])
        Ps.append(p_)
        Qs.append(q_)
    return np.array(Ps), np.array(Qs)


def compare(rec, ref, skip=(), n=3):
    """max |dP|, |dQ| outside n samples after each time in skip (the events; a timer's
    end, n 12: stabctl's timer expires up to one step (1/960 s) after the reference's,
    which moves Q by the Tg lag's rate for a few steps), each sample's distance taken to
    the reference's at the same sample or one step either side (a switch's timing
    resolution: one step)."""
    t = rec["t"]
    keep = np.ones(t.size, bool)
    for j, te in enumerate(skip):
        keep &= ~((t >= te - 1e-9) & (t <= te + (3 if j < 2 else n) * H))

    def tube(a, b):  # the distance to b's range over the sample and one step either side
        pad = np.concatenate([[b[0]], b, [b[-1]]])
        win = np.array([pad[j : j + a.size] for j in range(3)])
        return np.maximum(0.0, np.maximum(a - win.max(axis=0), win.min(axis=0) - a))

    dp = tube(rec["p"], ref[0])[keep]
    dq = tube(rec["q"], ref[1])[keep]
    return float(dp.max()), float(dq.max())


def at(rec, tt, key):
    return float(rec[key][int(np.argmin(np.abs(rec["t"] - tt)))])


DIP = dict(bus=103, t=0.1, clear_near=0.25)


# ---------------------------------------------------------------------------- the probes
@probe("AL01")
def _():
    """REECA1's 45 CONs read at PSS/E's positions (PSS/E Model Library REECA1: Vdip Vup Trv
    dbd1 dbd2 Kqv Iqh1 Iql1 Vref0 Iqfrz Thld Thld2 Tp QMax QMin VMAX VMIN Kqp Kqi Kvp Kvi
    Vref1 Tiq dPmax dPmin PMAX PMIN Imax Tpord, then (Vq, Iq) x 4 and (Vp, Ip) x 4; OpenIPSL
    REECA1.mo's parameter order the same): every CON a distinct value, read back from the
    converter table."""
    vals = dict(
        Vdip=0.81,
        Vup=1.21,
        Trv=0.021,
        dbd1=-0.051,
        dbd2=0.052,
        Kqv=2.1,
        Iqh1=1.051,
        Iql1=-1.052,
        Vref0=0.0,
        Iqfrz=0.11,
        Thld=0.31,
        Thld2=0.21,
        Tp=0.022,
        QMax=0.441,
        QMin=-0.442,
        VMAX=1.101,
        VMIN=0.901,
        Kqp=0.0,
        Kqi=0.011,
        Kvp=10.1,
        Kvi=60.1,
        Vref1=0.0,
        Tiq=0.023,
        dPmax=98.0,
        dPmin=-97.0,
        PMAX=1.19,
        PMIN=0.0,
        Imax=1.12,
        Tpord=0.024,
        Vq1=0.1,
        Iq1=1.0,
        Vq2=0.5,
        Iq2=1.01,
        Vq3=0.9,
        Iq3=1.02,
        Vq4=1.3,
        Iq4=1.03,
        Vp1=0.11,
        Ip1=0.9,
        Vp2=0.51,
        Ip2=0.91,
        Vp3=0.91,
        Ip3=0.92,
        Vp4=1.31,
        Ip4=0.93,
    )
    path = TMP / "al01.dyr"
    path.write_text(dyr(reec=vals))
    shutil.copy(RAW, TMP / "ThreeBusRenewable.raw")
    conv = load_psse(str(TMP / "ThreeBusRenewable.raw"), str(path)).converters
    bad = {
        k: (float(getattr(conv, k)[0]), v)
        for k, v in vals.items()
        if k not in ("Tiq",) and abs(float(getattr(conv, k)[0]) - v) > 1e-12
    }
    if abs(float(conv.tiq[0]) - vals["Tiq"]) > 1e-12:
        bad["Tiq"] = (float(conv.tiq[0]), vals["Tiq"])
    return not bad, f"45 REECA1 CONs, each distinct, read back: {len(vals) - len(bad)} in place" + (
        f"; misplaced (got, want): {bad}" if bad else ""
    )


def _dip_run(reec, x=0.07, t_end=1.0, regc=None):
    rec = simulate([Fault(x=x, **DIP)], t_end=t_end, reec=reec, regc=regc)
    rec["events"] = (0.1, 0.25)
    return rec


@probe("AL02")
def _():
    """REECA1 (Thld 0; Kqv 2, dbd +-0.05, Iqh1 1.05, Imax 1.11 Q priority) + REGCA1 through
    a fault at bus 103 (x 0.07 pu, |V| 0.47-0.51 pu, 0.1-0.25 s): P, Q against the
    references' plant driven by stabctl's |V|.  All three references divide the power
    order and the Q reference by the FILTERED voltage Vt_filt (max(., 0.01)): GridPACK
    reeca1.cpp computeModel `Pord/Vt_filter_lowcap_out`, `Qext/Vt_filter_lowcap_out`;
    OpenIPSL REECA1.mo division1/limiter7 on Vt_filt3 = VFilter.y (and division/limiter4 on
    Vt_filt1); Dynawo BaseREEC (UFilteredPu).  The same plant with the raw |V| in the
    divisions is run too, to show that the rest (Iqinj, freeze, current limits, LVACM)
    agrees."""
    rec = _dip_run({})
    dpf, dqf = compare(rec, reference(rec), skip=rec["events"])
    dpr, dqr = compare(rec, reference(rec, div="raw"), skip=rec["events"])
    k = int(round(0.26 / H))
    ref = reference(rec)
    return dpf < 5e-3 and dqf < 5e-3, (
        f"REAL: after clearing (0.26 s, |V| {rec['v'][k]:.3f}, Vt_filt lagging by Trv 0.02 s) P "
        f"stabctl {rec['p'][k]:.4f}, references {ref[0][k]:.4f}; max |dP| {dpf:.3f}, |dQ| "
        f"{dqf:.3f} pu against the references (Pord/Vt_filt, Qref/Vt_filt); with the raw |V| in "
        f"the divisions max |dP| {dpr:.1e}, |dQ| {dqr:.1e} (stabctl reeca1.py control divides by "
        "vp = max(v, 0.01), the unfiltered voltage, ANDES's reading)"
    )


@probe("AL03")
def _():
    """REECA1 Thld 0.3 > 0, Iqfrz 0.2: after the dip Iqinj = Iqfrz for Thld s (GridPACK
    reeca1.cpp predictor: Thld > 0 -> Iqinj_sw 2 = Iqfrz; OpenIPSL REECA1.mo's parameter
    text 'Iqinj is held at Iqfrz for Thld seconds following a voltage dip if Thld > 0');
    Dynawo IqInjectionLogic.mo reads the sign the other way (HoldIq > 0: the
    voltage-dependent injection, < 0: IqFrz).  Compared with the Vt_filt divisions, AL02 (AL02)."""
    reec = {"Thld": 0.3, "Iqfrz": 0.2}
    rec = _dip_run(reec)
    skip = (0.1, 0.25, 0.55)
    dg = compare(rec, reference(rec, reec=reec), skip=skip, n=12)
    dd = compare(rec, reference(rec, reec=reec, thld_sign="dynawo"), skip=skip, n=12)
    q = [at(rec, tt, "q") / at(rec, tt, "v") for tt in (0.45, 0.54, 0.6, 0.8)]
    return max(dg) < 5e-3, (
        f"Iq = Q/|V| at 0.45, 0.54, 0.60, 0.80 s: {', '.join(f'{v:.4f}' for v in q)} (Q0/V0 + "
        f"Iqfrz = {0.0995 / 1.015 + 0.2:.4f} until 0.55 s); max |dP|, |dQ| vs GridPACK's "
        f"reading {dg[0]:.1e}, {dg[1]:.1e}; vs Dynawo's {dd[0]:.1e}, {dd[1]:.2f} (Dynawo "
        "IqInjectionLogic.mo holds IqFrz for HoldIq < 0: minority reading)"
    )


@probe("AL04")
def _():
    """REECA1 Thld -0.3 < 0: the voltage-dependent Iqinj = Kqv dbd(Vref0 - Vt_filt) stays on
    for |Thld| s after the dip (GridPACK: Iqinj_sw 1 until thld_timer > -Thld); Vref0 1.15
    and Kqv 10 so that it is not 0 at the recovered voltage."""
    reec = {"Thld": -0.3, "Vref0": 1.15, "Kqv": 10.0}
    rec = _dip_run(reec)
    skip = (0.1, 0.25, 0.55)
    dg = compare(rec, reference(rec, reec=reec), skip=skip, n=12)
    dd = compare(rec, reference(rec, reec=reec, thld_sign="dynawo"), skip=skip, n=12)
    return max(dg) < 5e-3, (
        f"max |dP|, |dQ| vs GridPACK's reading {dg[0]:.1e}, {dg[1]:.1e} (Q at 0.45 s "
        f"{at(rec, 0.45, 'q'):.4f}, at 0.6 s {at(rec, 0.6, 'q'):.4f}); vs Dynawo's (IqFrz 0 "
        f"for HoldIq < 0) {dd[0]:.2f}, {dd[1]:.2f}"
    )


@probe("AL05")
def _():
    """REECA1 Thld2 0.2, Imax 1.02 (Q priority: Ipmax = sqrt(Imax^2 - Iqcmd^2) about 0.1
    in the dip): Ipmax held at its dip value for Thld2 s after it (Dynawo
    CurrentLimitsCalculationA.mo: ipMaxFrzPu = pre(ipMaxPu) at the dip's end, until time +
    tHoldIpMax; GridPACK leaves this timer out, OpenIPSL has no Thld2), so P stays near
    0.1 pu until 0.45 s; closed form: the time P first exceeds 0.2 pu."""
    reec = {"Thld2": 0.2, "Imax": 1.02}
    rec = _dip_run(reec)
    d = compare(rec, reference(rec, reec=reec), skip=(0.1, 0.25, 0.45), n=12)
    t, p = rec["t"], rec["p"]
    rise = float(t[np.flatnonzero((t > 0.26) & (p > 0.2))[0]])
    return max(d) < 5e-3 and 0.45 <= rise <= 0.47, (
        f"P at 0.35 s {at(rec, 0.35, 'p'):.4f} pu (held Ipmax {at(rec, 0.35, 'p') / at(rec, 0.35, 'v'):.4f}), "
        f"P > 0.2 pu first at {rise:.4f} s (0.25 + Thld2 = 0.45); max |dP|, |dQ| vs Dynawo's "
        f"hold (Vt_filt divisions, AL02) {d[0]:.1e}, {d[1]:.1e}"
    )


@probe("AL06")
def _():
    """REECA1 VDL curves (VDL1 (Vq, Iq) (0.2, 0.5) (0.5, 0.6) (0.9, 1.1) (1.3, 1.1); VDL2
    (Vp, Ip) (0.2, 0.3) (0.5, 0.35) (0.9, 1.1) (1.3, 1.1)) at Vt_filt in the dip with Kqv 4
    (Iqinj 1.05 at Iqh1), PQFLAG 0 and 1 (GridPACK CurrentLimitLogic: Q priority Iqmax =
    min(VDLq, Imax), Ipmax = min(VDLp, sqrt(Imax^2 - Iqcmd^2)); P priority Ipmax = min(VDLp,
    Imax), Iqmax = min(VDLq, sqrt(Imax^2 - Ipcmd^2)); Dynawo CurrentLimitsCalculationA.mo
    the same), LVACM off (Lvpnt0 0.05, Lvpnt1 0.1) so that P shows Ip."""
    curve = dict(
        Vq1=0.2,
        Iq1=0.5,
        Vq2=0.5,
        Iq2=0.6,
        Vq3=0.9,
        Iq3=1.1,
        Vq4=1.3,
        Iq4=1.1,
        Vp1=0.2,
        Ip1=0.3,
        Vp2=0.5,
        Ip2=0.35,
        Vp3=0.9,
        Ip3=1.1,
        Vp4=1.3,
        Ip4=1.1,
    )
    regc = {"Lvpnt0": 0.05, "Lvpnt1": 0.1}
    out, worst = [], 0.0
    for pq in (0, 1):
        reec = dict(curve, Kqv=4.0, PQFLAG=pq)
        rec = _dip_run(reec, regc=regc)
        d = compare(rec, reference(rec, reec=reec, regc=regc), skip=rec["events"])
        worst = max(worst, *d)
        v = at(rec, 0.24, "v")
        out.append(
            f"PQFLAG {pq}: at 0.24 s (|V| {v:.3f}) Ip {at(rec, 0.24, 'p') / v:.4f}, Iq "
            f"{at(rec, 0.24, 'q') / v:.4f}, max |dP|, |dQ| {d[0]:.1e}, {d[1]:.1e}"
        )
    return worst < 5e-3, (
        "REAL: "
        + "; ".join(out)
        + " (vs GridPACK/Dynawo/OpenIPSL, Vt_filt divisions, AL02): the VDL curve "
        "of the other current is not applied (Q priority: Ipmax = room only, VDLp 0.35 "
        "ignored; P priority: Iqmax = room only, VDLq 0.6 ignored)"
        if worst >= 5e-3
        else "; ".join(out)
    )


@probe("AL07")
def _():
    """REGCA1's low-voltage active current management (Lvpnt0 0.5, Lvpnt1 0.9): at the
    fault's first sample (x 0.15, |V| about 0.69) Ip is still Ip0 = P0/V0, so P = V Ip0 (V -
    Lvpnt0)/(Lvpnt1 - Lvpnt0) in closed form (GridPACK regca1.cpp INorton: Ipout = Ip
    Lvpnt_out; OpenIPSL LVACM.mo)."""
    rec = _dip_run({}, x=0.15)
    k = int(round(0.1 / H))
    v, p = rec["v"][k], rec["p"][k]
    ip0 = rec["p"][0] / rec["v"][0]
    want = v * ip0 * (v - 0.5) / 0.4
    return abs(p - want) < 1e-9, f"|V| {v:.4f}: P {p:.6f}, closed form {want:.6f}"


@probe("AL08")
def _():
    """REGCA1 LVPL (Lvplsw 1, Zerox 0.4, Brkpt 0.9, Lvpl1 0.5; Tfltr 0.2 s) through the
    x 0.15 fault (|V| about 0.69): the limit falls with the filtered voltage and rises
    after clearing.  Dynawo REGCa.mo (VariableLimiter after RateLimFirstOrderFreeze: the
    lag's output limited, its state not) and OpenIPSL REGCA1.mo (variableLimiter after
    integrator1) limit the output; ANDES (and a state clamp) hold the lag's state at the
    limit, so the current rises with Tg after the limit lifts."""
    regc = {"Lvplsw": 1, "Lvpl1": 0.5}
    rec = _dip_run({}, x=0.15, regc=regc)
    do = compare(rec, reference(rec, regc=regc, lvpl_kind="output"), skip=rec["events"])
    ds = compare(rec, reference(rec, regc=regc, lvpl_kind="state"), skip=rec["events"])
    k = int(round(0.2 / H))
    return max(do) < 5e-3, (
        f"REAL: at 0.2 s (|V| {rec['v'][k]:.3f}) P stabctl {rec['p'][k]:.4f}, LVPL-limited "
        f"references {reference(rec, regc=regc)[0][k]:.4f}; "
        f"max |dP|, |dQ| vs the output limit (Dynawo, OpenIPSL) {do[0]:.1e}, {do[1]:.1e}; vs "
        f"a state clamp {ds[0]:.1e}, {ds[1]:.1e} (P at 0.3 s {at(rec, 0.3, 'p'):.4f})"
    )


@probe("AL09")
def _():
    """REGCA1 Rrpwr 2 (pu/s) on the recovery after the x 0.07 fault (Tg 0.02; REECA1 Imax
    1.02 so that Ipmax, about 0.1 pu in the dip, lets the active current rise by 0.3 pu
    after it): Dynawo BaseREGC.mo RateLimFirstOrderFreeze(DyMax = RrpwrPu, DyMin =
    -RrpwrPu): dIp/dt in [-Rrpwr, Rrpwr]; OpenIPSL REGCA1.mo limiter4(uMax = rrpwr, uMin =
    -inf) on the error before integrator1(k = 1/Tg): dIp/dt <= Rrpwr/Tg (100 pu/s here);
    the PSS/E Model Library's unit (pu/s) with the rise alone limited is a third reading;
    GridPACK regca1.cpp applies no rate with Lvplsw 0."""
    regc, reec = {"Rrpwr": 2.0}, {"Imax": 1.02}
    rec = _dip_run(reec, regc=regc)
    runs = {
        kind: reference(rec, regc=regc, reec=reec, rrpwr_kind=kind)
        for kind in ("pu/s", "over Tg", "rise pu/s")
    }
    d = {kind: compare(rec, r, skip=rec["events"])[0] for kind, r in runs.items()}
    k = int(round(0.32 / H))
    return d["rise pu/s"] < 1e-3, (
        f"settled in round 54 (pu/s on the rise: GridPACK, InterPSS, Dynawo 2025, GridKit): "
        f"P at 0.32 s stabctl {rec['p'][k]:.4f}, Dynawo 2023 "
        f"(+-Rrpwr pu/s) {runs['pu/s'][0][k]:.4f}, OpenIPSL (Rrpwr/Tg on the rise) "
        f"{runs['over Tg'][0][k]:.4f}, Rrpwr pu/s on the rise {runs['rise pu/s'][0][k]:.4f}; max |dP| "
        f"{d['pu/s']:.3f}, {d['over Tg']:.1e}, {d['rise pu/s']:.3f} (ANDES's reading: OpenIPSL's)"
    )


@probe("AL10")
def _():
    """REGCA1 high-voltage reactive current management (Volim 1.05, Khv 2): a 0.8 pu
    capacitive load step at bus 103 at 0.1 s raises |V| above Volim; GridPACK regca1.cpp
    INorton: Iqout = Iq - max(0, Khv (V - Volim)) (its sign: Qg = -V Iqout, Iq_olim
    added), floored by Iolim; OpenIPSL REGCA1.mo KHV, min_limiter, IOLIM the same."""
    regc = {"Volim": 1.05, "Khv": 2.0}
    rec = simulate([LoadStep(103, 0.1, 0.0, -0.8)], t_end=0.6, regc=regc)
    rec["events"] = (0.1,)
    d = compare(rec, reference(rec, regc=regc), skip=rec["events"])
    return max(d) < 5e-3, (
        f"|V| {at(rec, 0.0, 'v'):.4f} -> {at(rec, 0.5, 'v'):.4f}: Q at 0.5 s {at(rec, 0.5, 'q'):.4f}; "
        f"max |dP|, |dQ| vs GridPACK/OpenIPSL {d[0]:.1e}, {d[1]:.1e}"
    )


# ------------------------------------------------------------------------------ REPCA1
BR = dict(BUS1=103, BUS2=101, CKT="'1 '")  # the monitored branch 103-101 (0.01 + j0.12 pu)
Z13 = 0.01 + 0.12j


def plant_run(repc, events, gencls="0.0 0.0", t_end=6.0, reec=None):
    """stabctl's run with a REPCA1: the end and start values of the plant's P, Q, the
    branch 103 -> 101's P, Q and current (from the recorded voltages), |V103|, speed."""
    path = TMP / f"p{len(os.listdir(TMP))}.dyr"
    path.write_text(dyr(repc=repc, gencls=gencls, reec=reec))
    shutil.copy(RAW, TMP / "ThreeBusRenewable.raw")
    case = load_psse(str(TMP / "ThreeBusRenewable.raw"), str(path))
    res = Simulator(case, background_compile=False).run(events, t_end=t_end, h=H)
    b = list(res.buses)
    V3 = res.vmag[:, b.index(103)] * np.exp(1j * res.vang[:, b.index(103)])
    V1 = res.vmag[:, b.index(101)] * np.exp(1j * res.vang[:, b.index(101)])
    I = (V3 - V1) / Z13
    S = V3 * np.conj(I)
    pick = lambda a: (a[0], a[-1])  # noqa: E731
    return dict(
        p=pick(res.ibr_p[:, 0]),
        q=pick(res.ibr_q[:, 0]),
        pl=pick(S.real),
        ql=pick(S.imag),
        V3=pick(V3),
        I=pick(I),
        Ig=pick(np.conj((res.ibr_p[:, 0] + 1j * res.ibr_q[:, 0]) / V3)),
        w=pick(res.speed[:, 0]),
        tail=float(np.ptp(res.ibr_p[-480:, 0])),
    )


def droop(w, rp):
    """REPCA1's droop Ddn/Dup of the deadbanded (1 - f) (WECC REPC_A; OpenIPSL REPCA1.mo
    deadZone1, DDN with limiter (<= 0), DUP with limiter1 (>= 0))."""
    e = dbd(1.0 - w, rp["fdbd1"], rp["fdbd2"])
    return rp["Ddn"] * min(e, 0.0) + rp["Dup"] * max(e, 0.0)


@probe("AL11")
def _():
    """REPCA1 Fflag 1 (Ddn = Dup 20, fdbd +-0.0002833, Kig 2, Kpg 0, Tg 0.05), the branch
    103-101 monitored, GENCLS 102 damped (H 3, D 40): a 0.1 pu load step at bus 101
    (under-frequency) and a -0.1 pu one (over-frequency; PMIN 0 of the REPCA1).  Closed
    form (OpenIPSL REPCA1.mo: KIG integrates Plant_pref + droop - Pbranch; GridPACK
    repca1.cpp and Dynawo REPCa.mo the same): at the end Pbranch - Pbranch0 = Ddn/Dup times
    the deadbanded 1 - f."""
    rp = {**REPC, **BR, "Fflag": 1}
    out, worst = [], 0.0
    for dP in (0.1, -0.1):
        r = plant_run(rp, [LoadStep(101, 0.5, dP, 0.0)], gencls="3.0 40.0")
        want = droop(r["w"][1], rp)
        got = r["pl"][1] - r["pl"][0]
        worst = max(worst, abs(got - want))
        out.append(f"load {dP:+g}: f {r['w'][1]:.6f} pu, dPbranch {got:+.5f} (droop {want:+.5f})")
    return worst < 2e-4, "; ".join(out)


@probe("AL12")
def _():
    """REPCA1 Pmax 0.405 (the P reference the PI hands the REECA1, in [Pmin, Pmax]: OpenIPSL
    REPCA1.mo KIG(y_start = p00) + KPG -> limiter3(Pmax, Pmin) -> simpleLag1(y_start =
    p00): a limit on the total reference, P0 0.4 inside it), the under-frequency step of
    AL11: the plant's P ends at Pmax."""
    rp = {**REPC, **BR, "Fflag": 1, "Pmax": 0.405}
    r = plant_run(rp, [LoadStep(101, 0.5, 0.1, 0.0)], gencls="3.0 40.0")
    return abs(r["p"][1] - 0.405) < 2e-4, (
        f"P {r['p'][0]:.4f} -> {r['p'][1]:.5f} pu (PSS/E reading: Pmax 0.405; the droop "
        f"alone {droop(r['w'][1], rp):+.4f} on the branch)"
    )


@probe("AL13")
def _():
    """REPCA1 Fflag 1 with no monitored branch (ICONs BUS1 BUS2 0 0, as RENA's DYR): GridPACK
    regca1.cpp feeds the plant controller the generator's own P, Q, V (setGenPQV), Dynawo's
    WECC plants their injector's PRegPu/QRegPu; so the droop steady state P - P0 = droop
    holds on the plant's own P.  The -0.1 pu step of AL11 (over-frequency)."""
    rp = {**REPC, "Fflag": 1}
    r = plant_run(rp, [LoadStep(101, 0.5, -0.1, 0.0)], gencls="3.0 40.0")
    want = droop(r["w"][1], rp)
    got = r["p"][1] - r["p"][0]
    return abs(got - want) < 2e-4, (
        f"REAL: f {r['w'][1]:.6f} pu (deadband edge {1 + rp['fdbd2']:.6f}), dP {got:+.5f} pu "
        f"where the references' steady state has dP = droop(f) = {want:+.5f} pu (stabctl "
        "measures an absent line, Pline = 0: the P PI integrates the droop alone, an "
        "isochronous control that pulls the frequency to the deadband's edge)"
    )


@probe("AL14")
def _():
    """REPCA1 VcFlag 0, Kc 0.1 (reactive droop), RefFlag 1, the branch 103-101 monitored,
    Ki 40, Kp 0, dbd 0: a 0.3 pu inductive load step at bus 101 (beyond the branch).  Closed form (OpenIPSL
    REPCA1.mo: VCFLAG false -> vreg + Kc qbranch, VREF = its initial value; GridPACK
    repca1.cpp the same): |V| + Kc Qbranch at the end equals its start."""
    rp = {**REPC, **BR, "VCFlag": 0, "Kc": 0.1, "Ki": 40.0}
    r = plant_run(rp, [LoadStep(101, 0.5, 0.0, 0.3)], t_end=8.0)
    vc = [abs(r["V3"][j]) + 0.1 * r["ql"][j] for j in (0, 1)]
    return abs(vc[1] - vc[0]) < 1e-4, (
        f"|V| {abs(r['V3'][0]):.5f} -> {abs(r['V3'][1]):.5f}, Qbranch {r['ql'][0]:.4f} -> "
        f"{r['ql'][1]:.4f}: |V| + Kc Qbranch {vc[0]:.5f} -> {vc[1]:.5f}"
    )


@probe("AL15")
def _():
    """REPCA1 VcFlag 1 (line drop compensation, Rc 0.005, Xc 0.05), the branch 103-101
    monitored, the step of AL14.  Closed form (OpenIPSL REPCA1.mo voltage_diff = |V -
    (Rc + j Xc) Ibranch|, the branch current leaving the plant's bus; GridPACK repca1.cpp
    the same): that compensated voltage at the end equals its start."""
    rp = {**REPC, **BR, "VCFlag": 1, "Rc": 0.005, "Xc": 0.05, "Ki": 40.0}
    r = plant_run(rp, [LoadStep(101, 0.5, 0.0, 0.3)], t_end=8.0)
    zc = 0.005 + 0.05j
    vc = [abs(r["V3"][j] - zc * r["I"][j]) for j in (0, 1)]
    vp = [abs(r["V3"][j] + zc * r["I"][j]) for j in (0, 1)]
    return abs(vc[1] - vc[0]) < 1e-4, (
        f"|V - Zc I| {vc[0]:.5f} -> {vc[1]:.5f} (|V + Zc I| {vp[0]:.5f} -> {vp[1]:.5f}); |V| "
        f"{abs(r['V3'][0]):.5f} -> {abs(r['V3'][1]):.5f}"
    )


# ------------------------------------------------------------------ REECA1 Q/V flags
@probe("AL16")
def _():
    """REECA1 QFLAG 1, VFLAG 1 (Q PI Kqi 5 -> V PI Kvi 60 on Vt_filt; GridPACK reeca1.cpp
    computeModel: Q_PI_blk(Qlim(Qext) - Qgen) -> Vlim -> Verr_PI_blk(. - Vt_filter);
    OpenIPSL REECA1.mo the same), no REPCA1: a 0.2 pu inductive load step at bus 101.
    Closed form: the Q PI's integral brings the plant's Q back to Qext = Q0."""
    reec = {"QFLAG": 1, "VFLAG": 1, "Kqi": 5.0, "Kqp": 0.0}
    rec = simulate([LoadStep(101, 0.5, 0.0, 0.2)], t_end=8.0, reec=reec)
    q0, q1 = rec["q"][0], rec["q"][-1]
    return abs(q1 - q0) < 1e-4, (
        f"Q {q0:.5f} -> {at(rec, 1.0, 'q'):.5f} (1 s) -> {q1:.5f} pu at 8 s; |V| "
        f"{rec['v'][0]:.5f} -> {rec['v'][-1]:.5f}"
    )


@probe("AL17")
def _():
    """REECA1 QFLAG 1, VFLAG 0 (the V PI on Vref1 + Qext - Vt_filt, started at rest: its
    reference the initial |V|; GridPACK reeca1.cpp init: Q_Pfflag = V_err_PI input +
    Vt_filter - Vbias, so the V PI's reference is V0), Vref1 0, no REPCA1: the load step of
    AL16.  Closed form: |V| returns to V0 (Kvi 60), Q rises."""
    reec = {"QFLAG": 1, "VFLAG": 0}
    rec = simulate([LoadStep(101, 0.5, 0.0, 0.2)], t_end=4.0, reec=reec)
    v0, v1 = rec["v"][0], rec["v"][-1]
    return abs(v1 - v0) < 1e-4, (
        f"|V| {v0:.5f} -> {at(rec, 0.52, 'v'):.5f} (0.52 s) -> {v1:.5f} pu at 4 s; Q "
        f"{rec['q'][0]:.4f} -> {rec['q'][-1]:.4f}"
    )


# ----------------------------------------------------------------------------- main
if __name__ == "__main__":
    pick = set(filter(None, (sys.argv[1] if len(sys.argv) > 1 else "").split(",")))
    bad = 0
    try:
        for pid, f in PROBES.items():
            if pick and pid not in pick:
                continue
            try:
                ok, msg = f()
            except Exception as e:  # noqa: BLE001
                ok, msg = (
                    False,
                    "ERROR " + "".join(traceback.format_exception_only(type(e), e)).strip(),
                )
                traceback.print_exc()
            bad += not ok
            print(f"{pid}  {'ok' if ok else 'SHORT'}  {msg}", flush=True)
    finally:
        shutil.rmtree(TMP, ignore_errors=True)
    sys.exit(1 if bad else 0)
