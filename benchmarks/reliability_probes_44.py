#!/usr/bin/env python
"""Round 52 (AN): the two DOUBTFUL findings of round 51 settled: REGCB1's rate limit Rrpwr
(AK07) and WTTQA1's Tflag 0 speed-error sign (AK10), each against references whose
equations are written here in numpy from their source (never stabctl's code).

    CLONE=<clone> PYTHONPATH=<clone> python benchmarks/reliability_probes_44.py [AN01,...]

CLONE (default: this repository) is the package under test; its tests/ directory lends the
converter test rows and the RENA wind case.  Prints a line per probe (ok or SHORT with
figures); well under a minute with a warm kernel cache.

References (read with the search tools):
  GridPACK GridOPTICS/GridPACK  src/applications/modules/dynamic_simulation_full_y/
           model_classes/regcb1.cpp (computeModel: Ip_blk.setdxlimits(-1000, Rrpwr) for a
           command > 0, (-Rrpwr, 1000) else; RateFlag 1 lags Ipcmd Vt_filter) and
           wttqa1.cpp (computeModel: Tflag 1 (Pref0 - Pelec_filter)/(1 + domega_g), else
           1 + domega_g - omega_ref, i.e. wg - wref)
  Dynawo   dynawo/dynawo  .../Controls/WECC/REGC/BaseClasses/BaseREGC.mo (2025, commit
           fe54893e: RateLimFirstOrderFreeze dyMax RrpwrPu, dyMin -9999: the lag output's
           rise only, no dip gating; its older 2023 BaseREGC and 2021 REGCbCS.mo had
           +-Rrpwr) and REGCa.mo (2024: the same, up only); .../WECC/Mechanical/WTGQa.mo
           (add k1 +1 omegaGPu, k2 -1 wref: wg - wref when TFlag is false, (PRef0 -
           filtered Pe)/wg when true; cites EPRI 3002027129 and WECC's second-generation
           wind turbine models)
  InterPSS org.interpss.dstab.renewable.Regcb1Model (directionalActiveRate: dIp/dt <= Rrpwr
           for P0 >= 0, always) and Wttqa1Model (wref - wg: with ANDES, the minority)
  PowerWorld WTGTRQ_A as ORNL/GridKit GridKit/Model/PhasorDynamics/Wind/WTGTRQA/README.md
           transcribes its block diagram: e_w = w_g - w_ref
  OpenIPSL OpenIPSL/OpenIPSL  .../Renewables/PSSE/InverterInterface/REGCB.mo (Limiter
           [-inf, rrpwr] on the lag's error before the integrator 1/Tg: up only, but
           dIp/dt <= rrpwr/Tg, an outlier)

Found: AN01/AN02 ok (stabctl's REGCB1 is the reading of GridPACK, InterPSS and Dynawo's
2025 REGC base: Rrpwr bounds the rise of the Tg lag's output, the current with RateFlag 0,
the power Ipcmd Vf with RateFlag 1, at any voltage, the fall unbounded); AN03-AN05 REAL
(WTTQA1 Tflag 0: stabctl integrates wref - wg; GridPACK, Dynawo and PowerWorld wg - wref;
with WTDTA1's drive train wref - wg is a positive feedback: a real eigenvalue +0.4 /s, the
speed runs away).  In a scratch copy with wind.py `reference`'s Tflag 0 line read as
`Tsel = wg - wref`, AN03-AN05 pass (largest eigenvalue 0, torsional -1.55 +- 12.2j; the
speed back within 1e-4 pu, P back to 0.4000 by 5 s) and AN01/AN02 are unchanged.  Aside:
PowerWorld numbers the flag the other way (its Flag 0 "torque control" takes the power
error, 1 the speed error); GridPACK, Dynawo, InterPSS and ANDES all take Tflag 1 = power.
"""

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
sys.path.insert(0, str(CLONE / "tests"))
sys.path.insert(0, str(CLONE / "tests" / "models"))
sys.path.insert(0, str(CLONE / "tests" / "io"))

TMP = Path(tempfile.mkdtemp(prefix="an52_"))
PROBES = {}


def probe(pid):
    def deco(f):
        PROBES[pid] = f
        return f

    return deco


def rk4(f, x0, h, n, out, every=1):
    """Fixed-step RK4 of x' = f(t, x); returns (t, out(t, x)) every `every` steps."""
    x = np.array(x0, float)
    ts, ys = [0.0], [out(0.0, x)]
    for k in range(n):
        t = k * h
        k1 = f(t, x)
        k2 = f(t + h / 2, x + h / 2 * k1)
        k3 = f(t + h / 2, x + h / 2 * k2)
        k4 = f(t + h, x + h * k3)
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        if (k + 1) % every == 0:
            ts.append((k + 1) * h)
            ys.append(out((k + 1) * h, x))
    return np.array(ts), np.array(ys)


# ============================================================================== REGCB1
TG, TFLTR, RRPWR = 0.02, 0.1, 2.0


def regcb1_stabctl(v, cmd, rateflag, tf=0.4, h=1e-4):
    """stabctl's REGCB1 (Te 0: a current source) from rest at 1 pu, 0.5 pu, the bus held at
    v and the constant command Ipcmd `cmd`: its active power P(t)."""
    import test_converters as tc

    from stabctl.models import converters as conv

    cols = dict(gb_Rrpwr=RRPWR, gb_Te=0.0, gb_RateFlag=rateflag)
    _, _, x0, P = tc.regcb1(P_changes=[("IPCMD0", cmd)], **cols)
    Vk = np.full(3, v, complex)

    def f(t, y):
        x = y.reshape(x0.shape).copy()
        dx = np.zeros_like(x)
        conv.derivatives_at(P, x, Vk[:1], Vk, dx)
        return dx.ravel()

    def out(t, y):
        x = y.reshape(x0.shape).copy()
        return conv.derivatives_at(P, x, Vk[:1], Vk, np.zeros_like(x))[0].real

    return rk4(f, x0.ravel(), h, int(round(tf / h)), out, every=10)


def regcb1_ref(v, cmd, rateflag, ip0=0.5, tf=0.4, h=1e-4, form="gridpack"):
    """The references' active path (GridPACK regcb1.cpp computeModel; InterPSS
    Regcb1Model; Dynawo 2025 BaseREGC): the filter Vf (Tfltr, at least 0.01), the lag Tg
    of u = Ipcmd (RateFlag 0) or Ipcmd Vf (1) whose output s may rise at most Rrpwr pu/s
    (falls unbounded), Ip = s (or s/Vf); P = v Ip.  form "openipsl": the error u - s
    limited to rrpwr before the integrator 1/Tg; "dynawo2023": ds/dt in [-Rrpwr, Rrpwr]."""

    def d(t, y):
        vf, s = y
        vfl = max(vf, 0.01)
        u = cmd * (vfl if rateflag else 1.0)
        if form == "openipsl":
            ds = min(u - s, RRPWR) / TG
        elif form == "dynawo2023":
            ds = float(np.clip((u - s) / TG, -RRPWR, RRPWR))
        else:
            ds = min((u - s) / TG, RRPWR) if cmd > 0 else max((u - s) / TG, -RRPWR)
        return np.array([(v - vf) / TFLTR, ds])

    def out(t, y):
        vf, s = y
        return v * (s / max(vf, 0.01) if rateflag else s)

    y0 = [1.0, ip0]  # at rest at 1 pu: Vf 1, s = Ip0 (= Ip0 Vf with RateFlag 1)
    return rk4(d, y0, h, int(round(tf / h)), out, every=10)


def _regcb1_case(v, cmd, rf):
    ts, ps = regcb1_stabctl(v, cmd, rf)
    _, pr = regcb1_ref(v, cmd, rf)
    _, po = regcb1_ref(v, cmd, rf, form="openipsl")
    _, pd = regcb1_ref(v, cmd, rf, form="dynawo2023")
    k = int(np.argmin(np.abs(ts - 0.1)))
    return float(np.max(np.abs(ps - pr))), ps[k], pr[k], po[k], pd[k]


@probe("AN01")
def _():
    """RateFlag 0 at 1 pu: a rise 0.5 -> 1.0 ramps at Rrpwr 2 pu/s (0.7 at 0.1 s), a fall
    0.5 -> 0.2 follows the Tg lag unbounded, a small rise 0.5 -> 0.52 (0.04/Tg = 1 pu/s <
    Rrpwr) follows the lag."""
    rows, worst = [], 0.0
    for name, cmd in (("rise", 1.0), ("fall", 0.2), ("small rise", 0.52)):
        d, s, r, o, d23 = _regcb1_case(1.0, cmd, 0)
        worst = max(worst, d)
        rows.append(
            f"{name}: P(0.1 s) stabctl {s:.4f} ref {r:.4f} (OpenIPSL {o:.4f}, "
            f"Dynawo-2023 {d23:.4f})"
        )
    return worst < 1e-6, f"REGCB1 RateFlag 0, max |dP| {worst:.1e}; " + "; ".join(rows)


@probe("AN02")
def _():
    """RateFlag 1 with the bus held at 0.8 pu from t = 0 (no dip logic in REGC_B): the
    lagged quantity is the power Ipcmd Vf, its rise limited to Rrpwr pu/s; the fall free."""
    rows, worst = [], 0.0
    for name, cmd in (("rise", 1.0), ("fall", 0.2)):
        d, s, r, _, d23 = _regcb1_case(0.8, cmd, 1)
        worst = max(worst, d)
        rows.append(f"{name}: P(0.1 s) stabctl {s:.4f} ref {r:.4f} (Dynawo-2023 {d23:.4f})")
    return worst < 1e-6, f"REGCB1 RateFlag 1 at 0.8 pu, max |dP| {worst:.1e}; " + "; ".join(rows)


# ============================================================================== WTTQA1
# the wind case of tests/io/test_dyr_converters.py: WTDTA1 H 4.95 Htfrac 0.875 Freq1 1.8 Hz
# Dshaft 1.5 DAMP 0; WTTQA1 Tflag 0 Kpp 3 Kip 0.6 Tp 0.05 Twref 60 Temax 1.2 Temin 0, speed
# curve 0.2/0.58 0.4/0.72 0.6/0.86 0.8/1.0; P0 0.4 (wref 0.72)
H, FRAC, F1, DSH = 4.95, 0.875, 1.8, 1.5
KPP, KIP, TP, TWREF = 3.0, 0.6, 0.05, 60.0
CURVE = ((0.2, 0.58), (0.4, 0.72), (0.6, 0.86), (0.8, 1.0))


def loop_eigs(sign, P0=0.4, Tpe=0.02):
    """Eigenvalues of the WECC WTGT_A two-mass drive train (2 Ht dwt/dt = Pm/wt - Tsh -
    Dsh (wt - wg), 2 Hg dwg/dt = Tsh - Pe/wg + Dsh (wt - wg), dTsh/dt = Kshaft (wt - wg),
    Kshaft = 2 Ht Hg (2 pi Freq1)^2/H), Pm constant, with the WTGTRQ_A torque loop (Pe
    filter Tp, wref = lag Twref of the speed curve, PI (Kpp, Kip) of e = sign (wref - wg),
    Pref = PI wg) and the converter Pe = Pref through a lag Tpe: sign +1 stabctl's
    (ANDES, InterPSS) reading, -1 GridPACK's, Dynawo's and PowerWorld's (wg - wref)."""
    Ht, Hg = FRAC * H, (1 - FRAC) * H
    K = 2 * Ht * Hg * (2 * np.pi * F1) ** 2 / H
    xs, ys = zip(*CURVE)

    def rhs(x):
        wt, wg, Ts, Pef, wref, xi, Pe = x
        e = sign * (wref - wg)
        return np.array(
            [
                (P0 / wt - Ts - DSH * (wt - wg)) / (2 * Ht),
                (Ts - Pe / wg + DSH * (wt - wg)) / (2 * Hg),
                K * (wt - wg),
                (Pe - Pef) / TP,
                (np.interp(Pef, xs, ys) - wref) / TWREF,
                KIP * e,
                ((KPP * e + xi) * wg - Pe) / Tpe,
            ]
        )

    w = float(np.interp(P0, xs, ys))
    x0 = np.array([w, w, P0 / w, P0, w, P0 / w, P0])
    J = np.empty((7, 7))
    for j in range(7):
        dx = np.zeros(7)
        dx[j] = 1e-7
        J[:, j] = (rhs(x0 + dx) - rhs(x0 - dx)) / 2e-7
    return np.linalg.eigvals(J)


def _wind_case():
    import test_dyr_converters as t

    records = [t._WTDTA1, "103 'WTARA1' 1 0.007 0.0 /\n", t._WTPTA1, t._WTTQA1]
    return t, t._wind_case(TMP, *records)


@probe("AN03")
def _():
    """Linearised loops (written here from the WECC equations): which sign is stabilising,
    and stabctl's own Jacobian (central differences of its compiled derivatives, network
    at its initial voltages) at the same Tflag 0 point."""
    ev_s = loop_eigs(+1.0)
    ev_g = loop_eigs(-1.0)
    t, case = _wind_case()
    x0, _, f = t._evaluate(case)
    n = len(x0)
    J = np.empty((n, n))
    for j in range(n):
        h = 1e-6 * max(1.0, abs(x0[j]))
        dx = np.zeros(n)
        dx[j] = h
        J[:, j] = (f(x0 + dx) - f(x0 - dx)) / (2 * h)
    ev = np.linalg.eigvals(J)
    real = ev[np.abs(ev.imag) < 1e-9].real.max()
    osc = ev[np.abs(ev.imag) > 1.0]
    top = osc[np.argmax(osc.real)]
    ok = ev.real.max() < 1e-6
    why = "" if ok else " -> unstable; GridPACK/Dynawo/PowerWorld's wg - wref is the stable sign"
    return ok, (
        f"WTTQA1 Tflag 0 at P0 0.4 (wref 0.72): reference loop max Re, wref - wg "
        f"{ev_s.real.max():+.3f} /s, wg - wref {ev_g.real.max():+.3f} /s; stabctl's Jacobian: "
        f"largest real eigenvalue {real:+.3f} /s, torsional {top.real:+.3f}{top.imag:+.2f}j{why}"
    )


@probe("AN04")
def _():
    """stabctl's own derivatives, network at its initial voltages: both speeds 0.002 pu
    below wref at t = 0; the speed should return to wref (the reference loop with wg - wref
    does, within 0.001 pu by 20 s)."""
    t, case = _wind_case()
    x0, names, f = t._evaluate(case)
    iw, ir = names.index("ibr.wg.C1"), names.index("ibr.wref_tq.C1")
    x = x0.copy()
    x[iw] -= 0.002
    x[names.index("ibr.wt.C1")] -= 0.002
    _, ys = rk4(lambda _t, y: f(y), x, 1e-3, 20000, lambda _t, y: (y[iw], y[ir]), every=1000)
    gap = ys[:, 1] - ys[:, 0]
    return abs(gap[-1]) < 1e-3, (
        f"WTTQA1 Tflag 0, wg 0.002 below wref: wref - wg at 5/10/20 s "
        f"{gap[5]:.4f}/{gap[10]:.4f}/{gap[-1]:.4f} pu (wg {ys[-1, 0]:.3f} at 20 s)"
        + ("" if abs(gap[-1]) < 1e-3 else ": runs away")
    )


@probe("AN05")
def _():
    """The full simulator on the same case: a 0.2 pu, 0.1 s load pulse at bus 101; the
    converter's P should come back to 0.400."""
    from stabctl.dynamics.driver import Simulator
    from stabctl.dynamics.events import LoadStep

    _, case = _wind_case()
    res = Simulator(case, background_compile=False).run(
        events=[LoadStep(101, 0.5, 0.2), LoadStep(101, 0.6, -0.2)], t_end=40.0
    )
    p = res.ibr_p[:, 0]
    at = {s: float(p[min(np.searchsorted(res.t, s), len(p) - 1)]) for s in (10.0, 25.0, 40.0)}
    return abs(at[40.0] - 0.4) < 1e-3, (
        f"WTTQA1 Tflag 0, load pulse: converter P at 10/25/40 s "
        f"{at[10.0]:.4f}/{at[25.0]:.4f}/{at[40.0]:.4f} pu (0.4000 before)"
        + ("" if abs(at[40.0] - 0.4) < 1e-3 else ": no return")
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
                ok = False
                msg = "ERROR " + "".join(traceback.format_exception_only(type(e), e)).strip()
                traceback.print_exc()
            bad += not ok
            print(f"{pid}  {'ok' if ok else 'SHORT'}  {msg}", flush=True)
    finally:
        shutil.rmtree(TMP, ignore_errors=True)
    sys.exit(1 if bad else 0)
