#!/usr/bin/env python
"""Fortieth reliability round (round 50, part AJ): the PSS/E stabiliser, governor and
converter models stabctl reads from DYR files that have NO PSS/E reference run in
tests/data/psse_runs, against the PSS/E Model Library as OpenIPSL implements it
(OpenIPSL/OpenIPSL, ``OpenIPSL/Electrical/Controls/PSSE/TG/*.mo``, ``.../PSS/*.mo``,
``OpenIPSL/Electrical/Renewables/PSSE/*``), the class of defect round 49 found in IEEET2
(a different signal fed back).  Each model is driven in a small PSS/E case shipped with the
repository (tests/data/psse_runs/TGOV1's ThreeBusMulti: GENROU at bus 102 against an
infinite bus; RENA_DEFAULT's ThreeBusRenewable: a REGCA1 plant at bus 103) with its record
put in the DYR file, and compared with an independent scipy integration of OpenIPSL's
equations written here, driven by the speed and electrical power stabctl recorded (so
that only the governor differs), or with the model's eigenvalues, or its start:

 AJ01 GGOV1 Rselect = 1 (electrical power droop): stabctl's pmech against OpenIPSL's
      GGOV1 blocks (PIDGovernor, Turbine) integrated here (checks the harness);
 AJ02 GGOV1 Rselect = -2: PSS/E (and PSLF, the CIM GovCT1, OpenIPSL's R_select) feed back
      the governor output (requested stroke), an algebraic loop, solved here in closed form;
 AJ03 GGOV1 Rselect = -1 (PSS/E: the true valve stroke): refused as "requested stroke";
 AJ04 IEEEG1, AJ05 IEESGO, AJ06 IEEEG2: pmech after a PREF step against OpenIPSL's
      ``IEEEG1.mo``, ``IEESGO.mo``, ``IEEEG2.mo`` integrated here;
 AJ07 STAB2A: the DYR record's CONs in the pss_con row as OpenIPSL's ``STAB2A.mo`` uses
      them (three washouts K2 T2 s/(1 + s T2), K3/(1 + s T3) + K4, (K5/(1 + s T5))^2,
      +-HLIM);
 AJ08 REECB1 with QFLAG = 1 (VFLAG 0: voltage control at Vref0; VFLAG 1: Q PI then V PI):
      PSS/E's REEC_B starts at rest (OpenIPSL's ``REECB1.mo``: V PI input clip(VFLAG ? Q PI
      : Vref0, Vmin, Vmax) - Vt_filt, Q PI starting at V0);
 AJ09 REECB1 QFLAG 1 VFLAG 0 (Vmin 0 so that stabctl starts): a 0.2 pu reactive load step
      at the plant's bus; PSS/E's integral voltage control (Kvi 60) returns |V| to Vref0;
 AJ10 WTDTA1: the shaft's torsional mode at Freq1 Hz (PSS/E Model Library: Freq1 in Hz;
      OpenIPSL ``WTDTA1.mo``: Kshaft = 2 Ht Hg (2 pi Freq1)^2/(H w0)) in `stabctl eig`;
 AJ11 WTARA1 with Theta0 = 5 deg (PSS/E: Pm = Pm0 - Ka theta (theta - theta0), at rest
      theta = theta0): starts at rest;
 AJ12 WTPTA1 with WTTQA1: the pitch speed PI acts on wt - wref, wref WTTQA1's speed
      reference (WECC WTGPT_A), so a turbine above its reference pitches.

    python reliability_probes_40.py [ID ...]

CLONE (default: this repository) is the package under test (PYTHONPATH), run as
`python -m stabctl`; NUMBA_CACHE_DIR the caller's (warm it with `python -m stabctl
compile`).  Prints per probe: id, ok/SHORT, reason; exits 1 if any is SHORT.  Every command
has a timeout; work in a temporary directory (removed at the end unless KEEP=1).  About 5
minutes with a warm kernel cache.

The round found short (REAL, fixed the same day but AJ02): AJ02-AJ03, GGOV1's Rselect -1
and -2 swapped (now -1 is the fuel valve stroke; -2, the governor output, was refused by name
as an algebraic loop, and AJ02 stayed short, until the next session solved the loop); AJ08-AJ09, REECB1 with QFLAG 1 read as ANDES reads it (no Vref0, no Vt_filter:
refused to start, or no voltage control); AJ10, WTDTA1's Freq1 read in pu (the torsional
mode 0.274 Hz for 1.8 Hz); AJ11, WTARA1's Theta0 mixing radians and degrees (refused to
start); AJ12, WTPTA1's speed PI against w0 = 1 instead of WTTQA1's reference.  The PSS/E
readings are marked per converter row (ibr_con column 303 psse); ANDES's stay for
import-andes.  The 5 others ok.
"""

# ruff: noqa: E501, BLE001, SIM115 - a tester's script, kept as written

import json
import os
import shutil
import sys
import textwrap

from _probe_kit import Kit

KIT = Kit("probes_aj50_", path=False, prefixes=False, line="{pid} {state}: {why}")
CLONE, ENV, WD, RESULTS, PROBES = KIT.clone, KIT.env, KIT.wd, KIT.results, KIT.probes
probe = KIT.probe
RUNS = os.path.join(CLONE, "tests", "data", "psse_runs")


def run(args, timeout=300):
    """A CLI command in WD: (rc, stdout + stderr); a timeout is rc -9."""
    rc, out, err, _dt = KIT.run(args, timeout, partial=False)
    return (-9, f"timeout after {timeout} s") if rc == "timeout" else (rc, out + err)


PRELUDE = textwrap.dedent(
    """
    import json, sys, warnings
    import numpy as np
    warnings.simplefilter("ignore")
    from scipy.integrate import solve_ivp
    from stabctl.io.psse import load_psse
    from stabctl.dynamics.driver import Simulator
    from stabctl.case.events import PrefStep, LoadStep
    def say(o):
        print("@@" + json.dumps(o))
    def pref_run(dyr, dP, t_end=15.0, h=1/960):
        case = load_psse("ThreeBusMulti.raw", dyr)
        sim = Simulator(case, background_compile=False)
        res = sim.run([PrefStep(2, 0.5, dP)], t_end=t_end, h=h)
        j = list(res.machines).index(2)
        return res.t, res.speed[:, j], res.pelect[:, j], res.pmech[:, j]
    def drive(rhs, x0, t, h):
        s = solve_ivp(rhs, (0, t[-1]), x0, t_eval=t, max_step=4 * h, rtol=1e-9, atol=1e-11)
        return s.y
    def ll(u, z, Ta, Tb):
        # (1 + s Ta)/(1 + s Tb): output, dz/dt (z lags u)
        return (Ta / Tb) * u + (1 - Ta / Tb) * z, (u - z) / Tb
    """
)


def py(*parts, timeout=600):
    """A child Python in WD (the package from CLONE) of the code parts (each dedented on its
    own); the dict it says, or kind/err."""
    code = PRELUDE + "\n".join(textwrap.dedent(c) for c in parts)
    rc, out, err, _dt = KIT.run_argv([sys.executable, "-c", code], timeout, partial=False)
    if rc == "timeout":
        return {"kind": "timeout", "err": f"after {timeout} s"}
    for line in reversed(out.splitlines()):
        if line.startswith("@@"):
            return json.loads(line[2:])
    return {"kind": f"crash rc {rc}", "err": err[-600:]}


def failed(o):
    return False, f"{o.get('kind')}: {o.get('err', '')[-400:]}"


# ------------------------------------------------------------------ the cases
TG = open(os.path.join(RUNS, "TGOV1", "ThreeBus_TGOV1.dyr")).read()
TG_BASE = "".join(l + "\n" for l in TG.splitlines() if "'TGOV1'" not in l)
REN = open(os.path.join(RUNS, "RENA_DEFAULT", "ThreeBus_REN_A_DEFAULT_FLAG.dyr")).read()
REN_FLAGS = (
    "          0          0       0       0       0\n"  # REECB1 IREG PFFLAG VFLAG QFLAG PQFLAG
)


def ggov1(rsel):
    """GGOV1 at bus 102: ICONs Rselect Flag; CONs R Tpelec maxerr minerr Kpgov Kigov Kdgov
    Tdgov Vmax Vmin Tact Kturb Wfnl Tb Tc Teng Tfload Kpload Kiload Ldref Dm Ropen Rclose Kimw
    Aset Ka Ta Trate db Tsa Tsb Rup Rdown (no limiter reached by the steps here)."""
    return (
        f"    102 'GGOV1' 1 {rsel} 1  0.04 1.0 0.05 -0.05 10.0 2.0 0.0 1.0 1.2 0.15 0.5 1.5 0.2 0.5 "
        "0.0 0.0 3.0 1.0 1.0 1.5 0.0 1.0 -1.0 0.0 1.0 10.0 0.1 0.0 0.0 4.0 5.0 99.0 -99.0 /\n"
    )


def ren(flags=None, drop=("REPCA1",), extra="", vmin=None):
    """The RENA plant's DYR without its REPCA1, REECB1 flags replaced, VMIN replaced,
    records appended."""
    recs = [r.strip("\n") for r in REN.split("/") if r.strip()]
    recs = [r for r in recs if not any(d in r for d in drop)]
    txt = "".join(r.rstrip() + " /\n" for r in recs)
    if flags is not None:
        assert REN_FLAGS in txt
        txt = txt.replace(REN_FLAGS, "          " + flags + "\n")
    if vmin is not None:
        old = "         0.44000        -0.44000          1.0500         0.90000 "
        assert old in txt
        txt = txt.replace(old, f"         0.44000        -0.44000          1.0500         {vmin} ")
    return txt + extra


#: a REECA1 with the REECB1's values (flags 0, no VDL curves) and a WTDTA1 (WECC-typical:
#: H 4.95 s, DAMP 0, Htfrac 0.875, Freq1 1.8 Hz, Dshaft 1.5)
REECA1 = (
    "    103 'REECA1' 1  0 0 0 0 0 0\n"
    "  -99.0 99.0 0.02 -0.01 0.01 1.0 1.1 -1.1 0.0 0.0 0.0 0.0\n"
    "  0.0 0.44 -0.44 1.05 0.9 0.0 0.01 10.0 60.0 0.0 0.02 99.0 -99.0 1.2 0.0 1.11 0.02\n"
    "  0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 /\n"
)
WT_H, WT_HTFRAC, WT_FREQ1, WT_DSHAFT = 4.95, 0.875, 1.8, 1.5
WTDTA1 = f"    103 'WTDTA1' 1  {WT_H} 0.0 {WT_HTFRAC} {WT_FREQ1} {WT_DSHAFT} /\n"


def write(name, txt):
    with open(os.path.join(WD, name), "w") as f:
        f.write(txt)
    return name


def setup():
    for d, f in (("TGOV1", "ThreeBusMulti.raw"), ("RENA_DEFAULT", "ThreeBusRenewable.raw")):
        shutil.copy(os.path.join(RUNS, d, f), WD)


# The independent GGOV1 (OpenIPSL PSSE.TG.GGOV1: PIDGovernor, Turbine; Dm = 0, Teng = 0,
# Kimw = 0, db = 0, Flag = 1, Trate = 0, Tc = 0; the limiters not selected), driven by the
# recorded speed and electrical power; mode: pe (Rselect 1), valve (R_select's -1:
# ValveStroke), requested (R_select's -2: GovernorOutput, the algebraic loop solved).
GGOV1_IND = """
R, Tpelec, maxerr, minerr, Kp, Ki = 0.04, 1.0, 0.05, -0.05, 10.0, 2.0
Vmax, Vmin, Tact, Kturb, Wfnl, Tb, Ropen, Rclose = 1.2, 0.15, 0.5, 1.5, 0.2, 0.5, 1.0, -1.0
def ggov1_ind(t, w, pe, pm, rsel, mode, dP, h):
    pm0 = pm[0]; fsr0 = pm0 / Kturb + Wfnl
    def rhs(tt, x):
        Pm_, xi, v, tb = x
        dw = np.interp(tt, t, w) - 1.0
        pref = R * (pm0 if rsel == 1 else fsr0) + (dP if tt >= 0.5 else 0.0)
        if mode == "requested":
            fsr = (Kp * (pref - dw) + xi) / (1 + Kp * R)
            err = pref - dw - R * fsr
        else:
            sig = Pm_ if mode == "pe" else v
            err = min(max(pref - dw - R * sig, minerr), maxerr)
            fsr = Kp * err + xi
        fsr = min(max(fsr, Vmin), Vmax)
        rate = min(max((fsr - v) / Tact, Rclose), Ropen)
        return [(np.interp(tt, t, pe) - Pm_) / Tpelec, Ki * err, rate,
                (Kturb * (v * (1.0 + dw) - Wfnl) - tb) / Tb]
    return drive(rhs, [pm0, fsr0, fsr0, pm0], t, h)[3]
"""


# ------------------------------------------------------------------ GGOV1
@probe("AJ01")
def _():
    """GGOV1 Rselect 1 (electrical-power droop), PREF +0.002 at 0.5 s, 15 s: stabctl's
    pmech against OpenIPSL's GGOV1 integrated here on stabctl's speed and power (within
    1e-5 pu): the harness AJ02 uses."""
    write("gg1.dyr", TG_BASE + ggov1(1))
    o = py(
        GGOV1_IND,
        """
    t, w, pe, pm = pref_run("gg1.dyr", 0.002)
    ind = ggov1_ind(t, w, pe, pm, 1, "pe", 0.002, 1/960)
    say({"diff": float(np.abs(ind - pm).max()), "peak": float(np.abs(pm - pm[0]).max())})
    """,
    )
    if o.get("kind"):
        return failed(o)
    return o[
        "diff"
    ] < 1e-5, f"max |pmech - OpenIPSL's| {o['diff']:.1e} pu (step response peak {o['peak']:.3f} pu)"


@probe("AJ02")
def _():
    """GGOV1 Rselect -2, PREF +0.002 at 0.5 s: PSS/E's GGOV1 feeds back the governor output
    (requested stroke; PSS/E and PSLF: '-1 fuel valve stroke (true stroke), -2 governor
    output (requested stroke)'; CIM DroopSignalFeedbackKind; OpenIPSL R_select.mo: -1
    ValveStroke, -2 GovernorOutput).  stabctl's pmech against both, integrated here."""
    write("gg2.dyr", TG_BASE + ggov1(-2))
    o = py(
        GGOV1_IND,
        """
    t, w, pe, pm = pref_run("gg2.dyr", 0.002)
    out = {m: float(np.abs(ggov1_ind(t, w, pe, pm, -2, m, 0.002, 1/960) - pm).max()) for m in ("requested", "valve")}
    out["peak"] = float(np.abs(pm - pm[0]).max())
    say(out)
    """,
    )
    if o.get("kind"):
        return failed(o)
    ok = o["requested"] < 1e-5
    return ok, (
        f"stabctl's pmech vs PSS/E's -2 (requested stroke fed back): max diff {o['requested']:.2e} pu "
        f"({o['requested'] / o['peak']:.1%} of the {o['peak']:.4f} pu response); vs the valve stroke "
        f"(PSS/E's -1): {o['valve']:.1e} pu"
    )


@probe("AJ03")
def _():
    """GGOV1 Rselect -1 (PSS/E: the true valve stroke, the droop signal of many WECC GGOV1
    records): imported and run, or refused with a reason true to PSS/E's meaning."""
    write("gg3.dyr", TG_BASE + ggov1(-1))
    rc, out = run(["import-psse", "ThreeBusMulti.raw", "gg3.dyr", "-o", "gg3.json"])
    line = next((l for l in out.splitlines() if "Rselect" in l), out.strip()[-300:])
    ok = rc == 0 or ("requested stroke" not in line)
    return ok, f"rc {rc}: {line.strip()[:300]}"


# ------------------------------------------------------------------ IEEEG1, IEESGO, IEEEG2
GOV_IND = {
    "IEEEG1": (
        "    102 'IEEEG1' 1 0 0 20 0.5 0.1 0.2 0.5 -0.5 1.5 0 0.3 0.3 0 7 0.4 0 0.6 0.3 0 0.05 0 0 /\n",
        """
    K, T1, T2, T3, Uo, Uc, T4, T5, T6, T7 = 20, 0.5, 0.1, 0.2, 0.5, -0.5, 0.3, 7, 0.6, 0.05
    Ks = [0.3, 0, 0.4, 0, 0.3, 0, 0, 0]
    g0 = pm[0] / sum(Ks)
    def rhs(tt, x):
        z, g, y4, y5, y6, y7 = x
        dw = np.interp(tt, t, w) - 1.0
        y, dz = ll(K * dw, z, T2, T1)
        pref = g0 + (dP if tt >= 0.5 else 0.0)
        dg = min(max((pref - y - g) / T3, Uc), Uo)
        return [dz, dg, (g - y4) / T4, (y4 - y5) / T5, (y5 - y6) / T6, (y6 - y7) / T7]
    Y = drive(rhs, [0, g0, g0, g0, g0, g0], t, h)
    ind = sum(Ks[2 * i] * Y[2 + i] + Ks[2 * i + 1] * Y[2 + i] for i in range(4))
    """,
    ),
    "IEESGO": (
        "    102 'IEESGO' 1 0.1 0.05 0.3 0.3 5 0.5 20 0.3 0.5 1.5 0 /\n",
        """
    T1, T2, T3, T4, T5, T6, K1, K2, K3 = 0.1, 0.05, 0.3, 0.3, 5, 0.5, 20, 0.3, 0.5
    g0 = pm[0]
    def rhs(tt, x):
        z1, z2, y4, y5, y6 = x
        dw = np.interp(tt, t, w) - 1.0
        y, dz2 = ll(z1, z2, T2, T3)
        u = min(max(g0 + (dP if tt >= 0.5 else 0.0) - y, 0.0), 1.5)
        return [(K1 * dw - z1) / T1, dz2, (u - y4) / T4, (y4 - y5) / T5, (y5 - y6) / T6]
    Y = drive(rhs, [0, 0, g0, g0, g0], t, h)
    ind = (1 - K2) * Y[2] + K2 * (1 - K3) * Y[3] + K2 * K3 * Y[4]
    """,
    ),
    "IEEEG2": (
        "    102 'IEEEG2' 1 20 5 0.5 0.5 1.5 0 1.0 /\n",
        """
    K, T1, T2, T3, T4 = 20, 5, 0.5, 0.5, 1.0
    p0 = pm[0]
    def rhs(tt, x):
        z, a, zw = x
        dw = np.interp(tt, t, w) - 1.0
        y, dz = ll(K * dw, z, T2, T1)
        gate = min(max(p0 + (dP if tt >= 0.5 else 0.0) - a, 0.0), 1.5)
        _, dzw = ll(gate, zw, -T4, 0.5 * T4)
        return [dz, (y - a) / T3, dzw]
    Y = drive(rhs, [0, 0, p0], t, h)
    gate = np.clip(p0 + np.where(t >= 0.5, dP, 0.0) - Y[1], 0.0, 1.5)
    ind = ll(gate, Y[2], -T4, 0.5 * T4)[0]
    """,
    ),
}


def gov_probe(name):
    rec, code = GOV_IND[name]
    write(f"{name}.dyr", TG_BASE + rec)
    o = py(
        f"""
    dP, h = 0.01, 1/960
    t, w, pe, pm = pref_run("{name}.dyr", dP, h=h)
    """,
        code,
        """
    say({"diff": float(np.abs(ind - pm).max()), "peak": float(np.abs(pm - pm[0]).max())})
    """,
    )
    if o.get("kind"):
        return failed(o)
    return o["diff"] < 2e-5 * max(1.0, o["peak"] / 0.01), (
        f"PREF +0.01 at 0.5 s, 15 s: max |pmech - OpenIPSL {name}.mo's| {o['diff']:.1e} pu (response peak {o['peak']:.4f} pu)"
    )


@probe("AJ04")
def _():
    """IEEEG1 (JBUS 0): the lead-lag K (1 + s T2)/(1 + s T1) on the speed deviation, the gate
    (P_ref - that - gate)/T3 in [Uc, Uo], four lags, K1..K8 after T4..T7: OpenIPSL
    IEEEG1.mo (its PMECH_HP + PMECH_LP)."""
    return gov_probe("IEEEG1")


@probe("AJ05")
def _():
    """IEESGO: K1/(1 + s T1), (1 + s T2)/(1 + s T3), P0 minus it in [PMIN, PMAX], lags T4,
    K2/(1 + s T5), K3/(1 + s T6), pmech (1 - K2) y4 + (1 - K3) y5 + y6: OpenIPSL IEESGO.mo."""
    return gov_probe("IEESGO")


@probe("AJ06")
def _():
    """IEEEG2: K (1 + s T2)/(1 + s T1) on the speed deviation, lag T3, P0 minus it in [PMIN,
    PMAX], water column (1 - s T4)/(1 + 0.5 s T4): OpenIPSL IEEEG2.mo."""
    return gov_probe("IEEEG2")


# ------------------------------------------------------------------ STAB2A
@probe("AJ07")
def _():
    """STAB2A K2 T2 K3 T3 K4 K5 T5 HLIM = 2 4 0.5 0.05 0.8 1.5 0.1 0.08 read into the
    pss_con row as stabctl/models/pss/stab2a.py's kernel uses it (KTw = K2 T2, Tw = T2, K1 =
    K3, Tr1 = T3, K2 = K4, column T5 = K5, T6 = T5, ymax = HLIM, ymin = -HLIM): OpenIPSL
    STAB2A.mo's -(K2 T2 s/(1 + s T2))^3, K3/(1 + s T3) + K4, (K5/(1 + s T5))^2, +-HLIM."""
    write("stab2a.dyr", TG + "    102 'STAB2A' 1 2.0 4.0 0.5 0.05 0.8 1.5 0.1 0.08 /\n")
    o = py("""
    c = load_psse("ThreeBusMulti.raw", "stab2a.dyr")
    p = c.pss
    got = {n: float(np.asarray(getattr(p, n))[0]) for n in ("type", "KTw", "Tw", "K1", "Tr1", "K2", "T5", "T6", "ymax", "ymin")}
    say(got)
    """)
    if o.get("kind"):
        return failed(o)
    want = dict(
        type=4, KTw=8.0, Tw=4.0, K1=0.5, Tr1=0.05, K2=0.8, T5=1.5, T6=0.1, ymax=0.08, ymin=-0.08
    )
    bad = {k: (o[k], v) for k, v in want.items() if abs(o[k] - v) > 1e-12}
    return not bad, f"pss_con row {o}" + (f"; differ (got, want): {bad}" if bad else "")


# ------------------------------------------------------------------ REECB1
FLAT = """
def flat(dyr, t_end=10.0):
    try:
        case = load_psse("ThreeBusRenewable.raw", dyr)
        res = Simulator(case, background_compile=False).run([], t_end=t_end, h=1/480)
    except Exception as e:
        return f"{type(e).__name__}: {e}"[:330]
    q = res.ibr_q[:, 0]
    return float(np.abs(q - q[0]).max())
"""


@probe("AJ08")
def _():
    """REECB1 QFLAG 1 (VFLAG 0: voltage control at Vref0 (0: the initial |V|); VFLAG 1: the
    Q PI's voltage order then the V PI), the RENA plant without REPCA1, a flat 10 s run:
    PSS/E's REEC_B starts at rest (OpenIPSL REECB1.mo: V PI input clip(VFLAG ? QPI : Vref0,
    Vmin, Vmax) - Vt_filt, 0 at the start).  Control: the file's own flags (0 0 0 0 0)."""
    for n, fl in (("f0", "0 0 0 0 0"), ("v0q1", "0 0 0 1 0"), ("v1q1", "0 0 1 1 0")):
        write(f"reecb1_{n}.dyr", ren(fl))
    o = py(
        FLAT,
        """
    say({n: flat(f"reecb1_{n}.dyr") for n in ("f0", "v0q1", "v1q1")})
    """,
    )
    if o.get("kind"):
        return failed(o)
    bad = {k: v for k, v in o.items() if isinstance(v, str) or v > 1e-6}
    return (
        not bad,
        "; ".join(
            f"{k}: " + (v if isinstance(v, str) else f"flat, max |dQ| {v:.1e}")
            for k, v in o.items()
        )
        + " (stabctl/models/converters/reeca1.py:control, REECB1 branch `u = QFLAG * clip(vflag * piq, lo, hi)`: no Vref0, no - Vt_filter; ANDES 2.0's reecb1.py reading)",
    )


@probe("AJ09")
def _():
    """REECB1 QFLAG 1 VFLAG 0 with Vmin 0 (so that stabctl's reading starts at rest): a 0.2
    pu reactive load step at bus 103 at 0.5 s, 10 s.  PSS/E's V PI (Kvp 10, Kvi 60) on
    Vref0 - Vt_filt (Vref0 0: the initial 1.015 pu) brings |V| back to 1.015 pu; the Iq
    command (Q priority, Imax 1.11) has room.  Control: QFLAG 0 (Q held)."""
    write("reecb1_vm0.dyr", ren("0 0 0 1 0", vmin="0.00000"))
    write("reecb1_q0.dyr", ren("0 0 0 0 0"))
    o = py("""
    out = {}
    for n in ("vm0", "q0"):
        case = load_psse("ThreeBusRenewable.raw", f"reecb1_{n}.dyr")
        res = Simulator(case, background_compile=False).run([LoadStep(103, 0.5, 0.0, 0.2)], t_end=10.0, h=1/480)
        v = res.vmag[:, list(res.buses).index(103)]; q = res.ibr_q[:, 0]
        out[n] = dict(v0=float(v[0]), v_end=float(v[-1]), dq=float(q[-1] - q[0]))
    say(out)
    """)
    if o.get("kind"):
        return failed(o)
    a, b = o["vm0"], o["q0"]
    ok = abs(a["v_end"] - a["v0"]) < 1e-3
    return ok, (
        f"QFLAG 1 VFLAG 0: |V| {a['v0']:.4f} -> {a['v_end']:.4f} pu at 10 s (Q {a['dq']:+.4f} pu); "
        f"QFLAG 0: {b['v0']:.4f} -> {b['v_end']:.4f} (Q {b['dq']:+.4f}): no voltage regulation"
    )


# ------------------------------------------------------------------ wind
@probe("AJ10")
def _():
    """WTDTA1 H 4.95 DAMP 0 Htfrac 0.875 Freq1 1.8 Dshaft 1.5 on a REECA1 (the RENA plant):
    the drive train's torsional mode in `stabctl eig --json` against the 3-state train's
    eigenvalues computed here (Pe, Pm constant) with PSS/E's Freq1 in Hz (OpenIPSL
    WTDTA1.mo: dTshaft/dt = 2 Ht Hg (2 pi Freq1)^2/H (wt - wg)) and with ANDES's per-unit
    reading (Kshaft = 2 Ht Hg Freq1^2/H)."""
    import numpy as np

    write("wt.dyr", ren(None, drop=("REPCA1", "REECB1"), extra=REECA1 + WTDTA1))
    rc, out = run(["import-psse", "ThreeBusRenewable.raw", "wt.dyr", "-o", "wt.json"])
    if rc != 0:
        return False, f"import rc {rc}: {out[-300:]}"
    rc, out = run(["eig", "wt.json", "--json"], timeout=600)
    try:
        d = json.loads(out[out.index("{") : out.rindex("}") + 1])
    except Exception:
        return False, f"eig rc {rc}: {out[-300:]}"
    tors = [
        m
        for m in d["modes"]
        if any("Tshaft" in s["state"] for s in m.get("dominant_states", [])[:1])
    ]
    if not tors:
        return False, "no mode dominated by the shaft torque"
    f = max(m["freq_hz"] for m in tors)
    P0 = 0.4
    Ht, Hg = WT_HTFRAC * WT_H, (1 - WT_HTFRAC) * WT_H

    def freq(K):
        A = np.array(
            [
                [(-P0 - WT_DSHAFT) / (2 * Ht), WT_DSHAFT / (2 * Ht), -1 / (2 * Ht)],
                [WT_DSHAFT / (2 * Hg), (P0 - WT_DSHAFT) / (2 * Hg), 1 / (2 * Hg)],
                [K, -K, 0.0],
            ]
        )
        return np.abs(np.linalg.eigvals(A).imag).max() / (2 * np.pi)

    f_hz = freq(2 * Ht * Hg * (2 * np.pi * WT_FREQ1) ** 2 / WT_H)
    f_pu = freq(2 * Ht * Hg * WT_FREQ1**2 / WT_H)
    return abs(f - f_hz) < 0.1 * f_hz, (
        f"stabctl's torsional mode {f:.3f} Hz; PSS/E's (Freq1 {WT_FREQ1} Hz) {f_hz:.3f} Hz, "
        f"ANDES's per-unit reading {f_pu:.3f} Hz (stabctl/models/converters/wind.py:mechanics "
        "dTshaft/dt = Ht2 Hg2 Freq1^2/(2H) (wt - wg))"
    )


@probe("AJ11")
def _():
    """WTARA1 Ka 0.007 with Theta0 = 5 deg (and with its pitch control WTPTA1): PSS/E's
    aerodynamics Pm = Pm0 - Ka theta (theta - theta0) sits at Pm0 with the pitch at theta0,
    a flat start; control Theta0 = 0."""
    wp = "    103 'WTPTA1' 1  25.0 150.0 30.0 3.0 0.0 0.3 27.0 0.0 10.0 -10.0 /\n"
    base = ren(None, drop=("REPCA1", "REECB1"), extra=REECA1 + WTDTA1)
    write("wa0.dyr", base + "    103 'WTARA1' 1  0.007 0.0 /\n")
    write("wa5.dyr", base + "    103 'WTARA1' 1  0.007 5.0 /\n")
    write("wa5p.dyr", base + "    103 'WTARA1' 1  0.007 5.0 /\n" + wp)
    o = py(
        FLAT,
        """
    say({n: flat(f"{n}.dyr") for n in ("wa0", "wa5", "wa5p")})
    """,
    )
    if o.get("kind"):
        return failed(o)
    bad = {k: v for k, v in o.items() if isinstance(v, str) or v > 1e-6}
    return (
        not bad,
        "; ".join(
            f"{k}: " + (v if isinstance(v, str) else f"flat, max |dQ| {v:.1e}")
            for k, v in o.items()
        )
        + " (stabctl/models/converters/wind.py:mechanics theta = rad(theta0) - theta0 + pitch, ANDES's mix)",
    )


@probe("AJ12")
def _():
    """WTPTA1 (Kiw 25 Kpw 150 Kic 30 Kpc 3 Kcc 0 Tp 0.3 TetaMax 27 TetaMin 0 RTetaMax 10
    RTetaMin -10) with WTTQA1 (speed curve 0.2/0.58 0.4/0.72 0.6/0.86 0.8/1.0, P0 0.4: the
    turbine runs at 0.72 pu), WTARA1, WTDTA1 on a REECA1: PSS/E's pitch speed PI acts on
    wt - wref, wref WTTQA1's speed reference (WECC WTGPT_A; PSS/E Model Library WTPTA1).
    At the start wt = wref: input 0; the turbine 0.05 pu above it must move the pitch
    (Kpw 0.05 = 7.5 deg through Tp, at the rate limit 10 deg/s).  Evaluated here:
    the initial states and dx/dt of the pitch states with wt + 0.05 (DynamicModel.evaluate)."""
    wq = "    103 'WTTQA1' 1  0  3.0 0.6 0.05 60.0 1.2 0.0  0.2 0.58 0.4 0.72 0.6 0.86 0.8 1.0  0.0 /\n"
    wp = "    103 'WTPTA1' 1  25.0 150.0 30.0 3.0 0.0 0.3 27.0 0.0 10.0 -10.0 /\n"
    write(
        "wtp.dyr",
        ren(
            None,
            drop=("REPCA1", "REECB1"),
            extra=REECA1 + WTDTA1 + "    103 'WTARA1' 1  0.007 0.0 /\n" + wp + wq,
        ),
    )
    o = py("""
    from stabctl.smallsignal.linearise import default_esd_buses
    from stabctl.dynamics.model import StageConfig
    case = load_psse("ThreeBusRenewable.raw", "wtp.dyr")
    sim = Simulator(case, background_compile=False)
    model = sim.model_for(default_esd_buses(case))
    x0 = np.array(model.x0, float)
    names = [model.state_name(k) for k in range(x0.size)]
    net = model.network(StageConfig())
    f0, _ = model.evaluate(x0.copy(), net, model.V_nc0)
    x = x0.copy(); x[names.index("ibr.wt.C1")] += 0.05
    f, _ = model.evaluate(x, net, model.V_nc0)
    say({"wt0": float(x0[names.index("ibr.wt.C1")]), "wref0": float(x0[names.index("ibr.wref_tq.C1")]),
         "w0": float(np.asarray(case.converters.wt_w0)[0]),
         "rest": float(max(abs(f0[k]) for k, n in enumerate(names) if "pitch" in n)),
         "dtheta": float(f[names.index("ibr.theta_pitch.C1")])})
    """)
    if o.get("kind"):
        return failed(o)
    ok = o["dtheta"] > 1.0
    return ok, (
        f"wt(0) {o['wt0']:.3f} = WTTQA1's wref {o['wref0']:.3f}, pitch PI reference w0 {o['w0']:.3f}; "
        f"at rest max |d pitch states/dt| {o['rest']:.1e}; wt + 0.05: d theta/dt {o['dtheta']:.3g} deg/s "
        "(PSS/E: 10 deg/s) (stabctl/models/converters/wind.py:_pitch_angle `u = Kcc e + wt - P[k, C.WT_W0]`)"
    )


if __name__ == "__main__":
    setup()
    KIT.main(summary="{n} probes, {short} SHORT", keep_any=True, kept="work dir kept: {wd}")
