#!/usr/bin/env python
"""Round 53 (AP): model fidelity of PSS/E's generator models (GENROU, GENROE, GENSAL,
GENSAE, GENCLS) and of PSS/E's network conventions as `import-psse RAW DYR` reads them, in
the aspects the PSS/E runs (tests/data/psse_runs: a line trip, default paths) and the
earlier rounds leave unchecked: the machines far from their operating point (speed 3-4 %
off, deep saturation, the terminal bolted to ground), D (PSS/E's damping on the machine
base, (Pm - D dw)/omega), the stator without the speed factor, Pm/omega, MBASE != SBASE,
the quadratic (GENROU, GENSAL) against the exponential (GENROE, GENSAE) fit of S(1.0),
S(1.2), GENSAL's d-axis-only saturation of E'q; ZSORCE on the machine base, GENCLS H = 0
as an infinite bus (EMF behind ZSORCE held), a bus fault through R + jX.

    CLONE=<clone> PYTHONPATH=<clone> python benchmarks/reliability_probes_46.py [AP01,AP03,...]

How: a one-machine case (tests/data/psse/smib_v33.raw with the machine at bus 1 put on
MBASE 200 MVA, 120 MW, 1.05 pu; the infinite bus a GENCLS H = 0 at bus 2), the machine's
record (PSS/E CON order) in the DYR file, read by stabctl.io.psse.load_psse; stabctl's
DynamicModel.evaluate gives the derivatives, the terminal voltage and the current at a
state; the reference is OpenIPSL's equations written here in numpy (never stabctl's
code): the machine's equilibrium solved by scipy's fsolve from the terminal V and I
(rotor derivatives 0), and its derivatives at a perturbed state driven by the terminal
voltage stabctl computed there (OpenIPSL's stator gives the current from it).  The state
maps: E'q, psi_kd as OpenIPSL; stabctl's E'd, psi_kq (and a salient machine's psi_kq, a
scale of psi"q) of the opposite sign (the scale read at the equilibrium).

References (read with the search tools):
  OpenIPSL OpenIPSL/OpenIPSL  OpenIPSL/Electrical/Machines/PSSE/GENROU.mo, GENROE.mo,
           GENSAL.mo, GENSAE.mo, GENCLS.mo, BaseClasses/baseMachine.mo (the swing
           der(w) = ((PMECH - D w)/(w + 1) - Te)/(2H), the stator ud = -PSIq - Ra id,
           uq = PSId - Ra iq without speed), OpenIPSL/NonElectrical/Functions/SE.mo
           (quadratic B (u - A)^2/u) and SE_exp.mo (S10 u^(ln(S12/S10)/ln 1.2));
           all but GENCLS's swing marked "VerifiedModel" (against PSS/E)
  PSS/E API dist_bus_fault(ibus, units, basekv, values): units 1 an admittance in MVA
           ([0, -2e9] bolted) and 3 an impedance in ohms at basekv (public psspy scripts,
           find_string "dist_bus_fault("; the manual itself not in the corpora), units 2
           the impedance in pu on the system base: stabctl's BUS:R:X

 AP01 GENROU equilibrium (S(1.0) 0.1, S(1.2) 0.5, MBASE 200): delta, E'q, psi_kd, E'd,
      psi_kq, efd0 = XadIfd, pm0 = Te against OpenIPSL's equations solved by fsolve
 AP02 GENROU derivatives at omega 1.03, E'q + 0.18 (|psi"| 1.3, deep saturation), D 2:
      all six against OpenIPSL, the current from the stator without speed
 AP03 GENROU D: d(domega/dt)/dD = -dw/(omega 2H) (D on the machine base, inside Pm/omega)
 AP04 GENROE: AP01 + AP02 (exponential saturation)
 AP05 GENSAL: AP01 + AP02 (quadratic saturation of E'q, d axis only)
 AP06 GENSAE: AP01 + AP02 (exponential saturation of |psi"|, both axes)
 AP07 bolted fault at the machine's terminal (the network's stage with the fault), omega
      1.04: |V| ~ 0, the current and every derivative of GENROU and GENSAL against OpenIPSL
 AP08 GENCLS (H 3 s, D 2 on MBASE 200) at omega 1.03: domega/dt against GridPACK's and
      OpenIPSL's GENCLS swing (Pm - Pe - D dw)/2H, no division by the speed (unlike the
      other machines), on the machine base (see note)
 AP09 `simulate --bus-fault 1:0.02:0.1` (pu on the system base, PSS/E units 2), GENCLS
      with ZSORCE 0.3 on MBASE 200 and the infinite bus's ZSORCE 0.01 on 100: both bus
      voltages at the fault instant against the two-node network solved by hand (EMFs from
      the power flow behind ZSORCE on the system base; the infinite bus's EMF held)
 AP10 the same case, a bolted --bus-fault at bus 1: G2 (GENCLS H = 0, PSS/E's infinite
      bus) keeps speed 1 and its EMF behind ZSORCE: |V2| = |E2| x_line / (x_line + ZSORCE)
 AP11 GENROU, GENSAL, GENROE at |psi"| (E'q) below the quadratic's A (S = 0) and far
      above 1.2 (about 1.67): the derivatives against OpenIPSL

Note (AP08): GENCLS's swing has no 1/omega in GridPACK (gencls.cpp: (p_Pm - Pe -
p_D p_dw)/(2 p_H)) nor in OpenIPSL (GENCLS.mo: (P_0/S_b - P - D omega)/(2H)), while the
PSS/E-verified baseMachine of GENROU &c. divides ((PMECH - D w)/(w + 1) - Te)/(2H);
stabctl follows each (dyr.py _PSSE_MACHINE, which cites PSS/E's own OMIB_GENCLS run).
OpenIPSL's GENCLS.mo takes P_0 and P on the system base with H on the machine base (a
base mix that only matters at MBASE != SBASE; physics and GridPACK: the machine base).

Found (round 53): nothing short.  The four machines' equilibria and derivatives at
perturbed, deeply saturated and terminal-faulted states agree with OpenIPSL to 1e-13 or
better; D, Pm/omega, the stator without speed, GENCLS's undivided swing, ZSORCE on MBASE,
H = 0 and the fault impedance (pu on the system base) as the references say.  About
15 s with a warm kernel cache.
"""

# ruff: noqa
import os
import shutil
import subprocess
import sys
import tempfile
import traceback
import warnings
from pathlib import Path

import numpy as np
from scipy.optimize import fsolve

warnings.simplefilter("ignore")
CLONE = Path(os.environ.get("CLONE", Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(CLONE))

from stabctl.dynamics.driver import Simulator  # noqa: E402
from stabctl.dynamics.model import StageConfig  # noqa: E402
from stabctl.io.psse import load_psse  # noqa: E402

TMP = Path(tempfile.mkdtemp(prefix="ap53_"))
PROBES = {}
SRC = (CLONE / "tests" / "data" / "psse" / "smib_v33.raw").read_text()
SBASE = 100.0
TOL = 1e-9


def probe(pid):
    def deco(f):
        PROBES[pid] = f
        return f

    return deco


def raw(mbase=200.0, pg=120.0, vs=1.05, zx=0.25, name="c.raw"):
    """smib_v33.raw with machine 1 on MBASE mbase, PG pg MW, VS vs, ZSORCE X zx."""
    out = []
    for ln in SRC.splitlines():
        if ln.startswith("    1,'1 ',    50.000"):
            f = ln.split(",")
            f[2], f[6], f[8], f[10] = f"{pg:10.3f}", f"{vs:.5f}", f"{mbase:9.3f}", f" {zx:.5E}"
            ln = ",".join(f)
        if ln.startswith("    1,'GEN"):
            f = ln.split(",")
            f[7] = f"{vs:.5f}"
            ln = ",".join(f)
        out.append(ln)
    p = TMP / name
    p.write_text("\n".join(out) + "\n")
    return p


# ======================================================= OpenIPSL's PSS/E machines
def se_quad(u, s10, s12):
    """OpenIPSL NonElectrical/Functions/SE.mo (E1 1.0, E2 1.2)."""
    if s10 == 0.0 or u <= 0.0:
        return 0.0
    a = np.sqrt(s10 * 1.0 / (s12 * 1.2)) if s12 != 0 else 0.0
    A = 1.2 - (1.0 - 1.2) / (a - 1)
    B = s12 * 1.2 * (a - 1) ** 2 / (1.0 - 1.2) ** 2
    return 0.0 if u <= A else B * (u - A) ** 2 / u


def se_exp(u, s10, s12):
    """OpenIPSL NonElectrical/Functions/SE_exp.mo."""
    return s10 * u ** (np.log(s12 / s10) / np.log(1.2))


def rhs(kind, p, st, V, efd, pm):
    """OpenIPSL PSSE GENROU/GENROE/GENSAL/GENSAE (equation sections, baseMachine's swing).
    st: delta, w (deviation), E'q, PSIkd, E'd (round rotor; 0 salient), PSIkq (round) or
    PSIppq (salient); V the terminal voltage (network frame).  Returns (derivatives,
    dict with the current I on the machine base, Te, XadIfd, |psi"|)."""
    d, w, Epq, PSIkd, Epd, X6 = st
    Xd, Xq, Xpd, Xpq, Xppd, Xl, Ra = (p[k] for k in ("Xd", "Xq", "Xpd", "Xpq", "Xppd", "Xl", "Ra"))
    Xppq = Xppd  # GENROU &c.: Xpp = Xppd (one X"d in the DYR record)
    K1d = (Xpd - Xppd) * (Xd - Xpd) / (Xpd - Xl) ** 2
    K3d = (Xppd - Xl) / (Xpd - Xl)
    K4d = (Xpd - Xppd) / (Xpd - Xl)
    sat = se_exp if kind in ("GENROE", "GENSAE") else se_quad
    PSIppd = Epq * K3d + PSIkd * K4d
    if kind in ("GENROU", "GENROE"):
        K1q = (Xpq - Xppq) * (Xq - Xpq) / (Xpq - Xl) ** 2
        K3q = (Xppq - Xl) / (Xpq - Xl)
        K4q = (Xpq - Xppq) / (Xpq - Xl)
        PSIppq = Epd * K3q + X6 * K4q
    else:
        PSIppq = X6
    z = V * np.exp(-1j * d)  # baseMachine: vr + j vi = exp(j delta) (uq - j ud)
    uq, ud = z.real, -z.imag
    # ud = -PSIq - Ra id = PSIppq + Xppq iq - Ra id; uq = PSId - Ra iq = PSIppd - Xppd id - Ra iq
    id_, iq = np.linalg.solve(np.array([[-Ra, Xppq], [-Xppd, -Ra]]), [ud - PSIppq, uq - PSIppd])
    PSId = PSIppd - Xppd * id_
    PSIq = -PSIppq - Xppq * iq
    Te = PSId * iq - PSIq * id_
    PSIpp = np.hypot(PSIppd, PSIppq)
    S10, S12 = p["S10"], p["S12"]
    f = np.zeros(6)
    f[0] = 2 * np.pi * 60.0 * w
    f[1] = ((pm - p["D"] * w) / (w + 1) - Te) / (2 * p["H"])
    f[3] = (Epq - PSIkd - (Xpd - Xl) * id_) / p["Tppd0"]
    if kind in ("GENROU", "GENROE"):
        se = sat(PSIpp, S10, S12)
        XadIfd = K1d * (Epq - PSIkd - (Xpd - Xl) * id_) + Epq + id_ * (Xd - Xpd) + se * PSIppd
        XaqIlq = (
            K1q * (Epd - X6 + (Xpq - Xl) * iq)
            + Epd
            - iq * (Xq - Xpq)
            + se * PSIppq * (Xq - Xl) / (Xd - Xl)
        )
        f[4] = -XaqIlq / p["Tpq0"]
        f[5] = (Epd - X6 + (Xpq - Xl) * iq) / p["Tppq0"]
    elif kind == "GENSAL":
        XadIfd = (
            K1d * (Epq - PSIkd - (Xpd - Xl) * id_)
            + (Xd - Xpd) * id_
            + (sat(Epq, S10, S12) + 1) * Epq
        )
        f[5] = (-PSIppq + (Xq - Xppq) * iq) / p["Tppq0"]
    else:  # GENSAE
        se = sat(PSIpp, S10, S12)
        XadIfd = Epq + K1d * (Epq - PSIkd - (Xpd - Xl) * id_) + (Xd - Xpd) * id_ + se * PSIppd
        f[5] = (-PSIppq + (Xq - Xppq) * iq - PSIppq * (Xq - Xl) / (Xd - Xl) * se) / p["Tppq0"]
    f[2] = (efd - XadIfd) / p["Tpd0"]
    return f, dict(I=np.exp(1j * d) * (iq - 1j * id_), Te=Te, XadIfd=XadIfd, PSIpp=PSIpp)


def equilibrium(kind, p, V, I, guess):
    """The machine's states with its rotor derivatives 0 and its stator giving V, I
    (machine base): (states, efd0 = XadIfd, pm0 = Te)."""
    rnd = kind in ("GENROU", "GENROE")

    def F(y):
        st = [y[0], 0.0, y[1], y[2], y[3] if rnd else 0.0, y[4]]
        f, o = rhs(kind, p, st, V, 0.0, 0.0)
        return [(o["I"] - I).real, (o["I"] - I).imag, f[3], f[5], f[4] if rnd else y[3]]

    y = fsolve(F, guess, xtol=1e-14)
    st = [y[0], 0.0, y[1], y[2], y[3] if rnd else 0.0, y[4]]
    _, o = rhs(kind, p, st, V, 0.0, 0.0)
    return np.array(st), o["XadIfd"], o["Te"]


PAR = dict(
    Tpd0=6.5, Tppd0=0.05, Tpq0=0.6, Tppq0=0.07, H=4.0, D=2.0, Xd=1.8, Xq=1.7, Xpd=0.30,
    Xpq=0.55, Xppd=0.25, Xl=0.20, S10=0.10, S12=0.50, Ra=0.0,
)  # fmt: skip
ROUND_CON = ("Tpd0", "Tppd0", "Tpq0", "Tppq0", "H", "D", "Xd", "Xq", "Xpd", "Xpq", "Xppd", "Xl", "S10", "S12")  # fmt: skip
SALIENT_CON = tuple(k for k in ROUND_CON if k not in ("Tpq0", "Xpq"))


class Machine:
    """One machine of `kind` at bus 1 (MBASE 200) against the infinite bus, loaded by
    stabctl; `at(x)` evaluates stabctl at a state, `ref_at(...)` OpenIPSL there."""

    def __init__(self, kind, par=PAR, mbase=200.0):
        self.kind, self.par, self.mbase = kind, dict(par), mbase
        cons = ROUND_CON if kind in ("GENROU", "GENROE") else SALIENT_CON
        dyr = TMP / f"{kind}.dyr"
        dyr.write_text(
            f"1 '{kind}' 1 " + " ".join(repr(float(par[k])) for k in cons) + " /\n"
            "2 'GENCLS' 1 0.0 0.0 /\n"
        )
        case = load_psse(raw(mbase=mbase, zx=par["Xppd"]), dyr)
        self.m = Simulator(case, background_compile=False).model_for(())
        self.net = self.m.network(StageConfig())
        self.x0 = np.array(self.m.x0, float)
        self.sal = kind in ("GENSAL", "GENSAE")

    def mac(self, x):
        return self.m.layout.view(x, "mac")[:, 0]

    def at(self, x, net=None):
        dx, o = self.m.evaluate(x.copy(), net or self.net, self.m.V_nc0)
        return self.mac(dx).copy(), o

    def init_check(self):
        """(worst difference of the equilibrium, scale of the salient q state, efd0, pm0)."""
        _, o = self.at(self.x0)
        s = self.mac(self.x0)
        I = o.cur[0] * SBASE / self.mbase
        g = [s[0], s[2], s[3], -s[4], -s[5]]
        st, efd0, pm0 = equilibrium(self.kind, self.par, o.V_bus[0], I, g)
        self.scale = st[5] / -s[5] if self.sal else 1.0
        self.efd0, self.pm0 = o.efd[0], o.pmech[0]
        mine = np.array([s[0], s[2], s[3], -s[4], -s[5] * self.scale, o.efd[0], o.pmech[0]])
        ref = np.array([st[0], st[2], st[3], st[4], st[5], efd0, pm0])
        return float(np.abs(mine - ref).max()), mine, ref

    def deriv_check(self, pert, net=None):
        """Worst difference of the six derivatives and of the current at x0 + pert."""
        x = self.x0.copy()
        mv = self.m.layout.view(x, "mac")
        for j, v in enumerate(pert):
            mv[j, 0] += v
        dm, o = self.at(x, net)
        s = self.mac(x)
        st = [s[0], s[1] - 1.0, s[2], s[3], -s[4], -s[5] * self.scale]
        f, r = rhs(self.kind, self.par, st, o.V_bus[0], self.efd0, self.pm0)
        mine = np.array([dm[0], dm[1], dm[2], dm[3], -dm[4], -dm[5] * self.scale])
        di = abs(o.cur[0] * SBASE / self.mbase - r["I"])
        rel = np.abs(mine - f) / np.maximum(np.abs(f), 1.0)
        return float(max(rel.max(), di)), mine, f, o, r


PERT_ROUND = (0.25, 0.03, 0.18, 0.12, -0.08, 0.06)
PERT_SALIENT = (0.25, 0.03, 0.18, 0.12, 0.0, 0.06)


def init_and_deriv(kind):
    M = Machine(kind)
    e0, mine, ref = M.init_check()
    e1, dm, f, o, r = M.deriv_check(PERT_SALIENT if M.sal else PERT_ROUND)
    ok = e0 < TOL and e1 < TOL
    return ok, (
        f"equilibrium max diff {e0:.1e} (efd0 {mine[5]:.6f} vs {ref[5]:.6f}); at omega 1.03, "
        f'|psi"| {r["PSIpp"]:.3f}: derivatives/current max rel diff {e1:.1e} '
        f"(domega/dt {dm[1]:.6e} vs {f[1]:.6e}, dE'q/dt {dm[2]:.6e} vs {f[2]:.6e})"
    )


@probe("AP01")
def _():
    M = Machine("GENROU")
    e0, mine, ref = M.init_check()
    return e0 < TOL, (
        f"GENROU equilibrium (MBASE 200, S 0.1/0.5) max diff {e0:.1e}: delta {mine[0]:.9f} vs "
        f"{ref[0]:.9f}, efd0 {mine[5]:.9f} vs {ref[5]:.9f}, pm0 {mine[6]:.9f} vs {ref[6]:.9f}"
    )


@probe("AP02")
def _():
    M = Machine("GENROU")
    M.init_check()
    e1, dm, f, o, r = M.deriv_check(PERT_ROUND)
    # the power of the check: a stator with the speed factor (V = omega psi" - j X"d I)
    # would draw another current, a swing without 1/omega another domega/dt
    V, w = o.V_bus[0], 1.03
    psi = (V + 1j * PAR["Xppd"] * r["I"]) * w
    i_speed = abs((psi - V) / (1j * PAR["Xppd"]) - r["I"])
    undiv = ((M.pm0 - PAR["D"] * 0.03) - r["Te"]) / (2 * PAR["H"])
    return e1 < TOL, (
        f"GENROU at omega 1.03, E'q +0.18 (|psi\"| {r['PSIpp']:.3f}), D 2: 6 derivatives + "
        f"current max rel diff {e1:.1e}; domega/dt {dm[1]:.9e} vs {f[1]:.9e} (without "
        f"1/omega {undiv:.6e}); the stator with speed would move I by {i_speed:.3f} pu"
    )


@probe("AP03")
def _():
    p0 = dict(PAR, D=0.0)
    A, B = Machine("GENROU", p0), Machine("GENROU", PAR)
    A.init_check()
    B.init_check()
    x = A.x0.copy()
    A.m.layout.view(x, "mac")[1, 0] = 1.03
    da, _ = A.at(x)
    db, _ = B.at(x)
    got = db[1] - da[1]
    want = -PAR["D"] * 0.03 / 1.03 / (2 * PAR["H"])
    return abs(got - want) < 1e-12, (
        f"d(domega/dt) from D 0 to 2 at omega 1.03: {got:.12e} vs -D dw/(omega 2H) {want:.12e}"
        f" (D dw/2H unscaled would be {-PAR['D'] * 0.03 / (2 * PAR['H']):.6e})"
    )


@probe("AP04")
def _():
    return init_and_deriv("GENROE")


@probe("AP05")
def _():
    ok, msg = init_and_deriv("GENSAL")
    return ok, msg + " (saturation of E'q on the d axis only)"


@probe("AP06")
def _():
    return init_and_deriv("GENSAE")


@probe("AP07")
def _():
    out, ok = [], True
    for kind in ("GENROU", "GENSAL"):
        M = Machine(kind)
        M.init_check()
        net = M.m.network(StageConfig(faults=((0, complex(0.0, -1e9)),)))
        pert = (0.1, 0.04, 0.0, 0.0, 0.0, 0.0)
        e1, dm, f, o, r = M.deriv_check(pert, net)
        ok &= e1 < TOL
        out.append(
            f"{kind} |V| {abs(o.V_bus[0]):.1e} |I| {abs(r['I']):.3f} pu(mbase) "
            f"Te {r['Te']:.4f} max rel diff {e1:.1e}"
        )
    return ok, "bolted fault at the terminal, omega 1.04: " + "; ".join(out)


@probe("AP08")
def _():
    dyr = TMP / "gencls.dyr"
    dyr.write_text("1 'GENCLS' 1 3.0 2.0 /\n2 'GENCLS' 1 0.0 0.0 /\n")
    case = load_psse(raw(mbase=200.0, pg=120.0, zx=0.3, name="cls.raw"), dyr)
    m = Simulator(case, background_compile=False).model_for(())
    net = m.network(StageConfig())
    x = np.array(m.x0, float)
    m.layout.view(x, "mac")[1, 0] = 1.03
    m.layout.view(x, "mac")[0, 0] += 0.2
    dx, o = m.evaluate(x.copy(), net, m.V_nc0)
    got = m.layout.view(dx, "mac")[1, 0]
    te = (o.V_bus[0] * np.conj(o.cur[0])).real * SBASE / 200.0  # lossless: Te = P (mbase)
    pm = 120.0 / 200.0
    grid = (pm - te - 2.0 * 0.03) / (2 * 3.0)  # GridPACK gencls.cpp, machine base
    div = ((pm - 2.0 * 0.03) / 1.03 - te) / (2 * 3.0)  # baseMachine's GENROU form
    oipsl = (pm * 2.0 - te * 2.0 - 2.0 * 0.03) / (2 * 3.0)  # GENCLS.mo: P on SBASE
    return abs(got - grid) < 1e-10, (
        f"GENCLS H 3 D 2 MBASE 200 at omega 1.03: domega/dt {got:.12e} vs GridPACK/OpenIPSL "
        f"(Pm - Pe - D dw)/2H on MBASE {grid:.12e}; the divided GENROU form would give "
        f"{div:.6e}, OpenIPSL GENCLS.mo's powers on SBASE {oipsl:.6e} (note)"
    )


def cli(*args, timeout=300):
    env = dict(os.environ, PYTHONPATH=str(CLONE))
    r = subprocess.run(
        [sys.executable, "-m", "stabctl", *map(str, args)],
        cwd=TMP, env=env, capture_output=True, text=True, timeout=timeout,
    )  # fmt: skip
    return r.returncode, r.stdout + r.stderr


def fault_case():
    js = TMP / "f.json"
    if not js.exists():
        r = raw(mbase=200.0, pg=50.0, vs=1.0, zx=0.3, name="f.raw")
        d = TMP / "f.dyr"
        d.write_text("1 'GENCLS' 1 3.0 0.0 /\n2 'GENCLS' 1 0.0 0.0 /\n")
        rc, out = cli("import-psse", r, d, "-o", js)
        if rc != 0:
            raise RuntimeError(out[-400:])
    return js


def run_fault(spec):
    js = fault_case()
    csv = TMP / f"f_{spec.replace(':', '_')}.csv"
    rc, out = cli("simulate", js, "--bus-fault", spec, 0.1, 0.2, "--tf", 0.3, "--out", csv)
    if rc != 0:
        raise RuntimeError(out[-400:])
    head = csv.read_text().splitlines()[0].split(",")
    a = np.loadtxt(csv, delimiter=",", skiprows=1)
    col = {h: a[:, k] for k, h in enumerate(head)}
    k0 = 0  # the pre-fault row, then the first row at 0.1 s after the fault
    k1 = int(np.nonzero(a[:, 0] >= 0.1 - 1e-12)[0][0])
    return col, k0, k1


def hand_fault(col, k0, k1, zf):
    """Bus voltages at the fault instant: EMFs behind ZSORCE (system base) from the
    pre-fault power flow, the rotor angles unchanged, the two-node network solved."""
    V = col["vmag_pu.B1"][k0] * np.exp(1j * col["vang_rad.B1"][k0])
    V2 = col["vmag_pu.B2"][k0] * np.exp(1j * col["vang_rad.B2"][k0])
    S1 = col["pelect_pu.G1"][k0] + 1j * col["qelect_pu.G1"][k0]
    S2 = col["pelect_pu.G2"][k0] + 1j * col["qelect_pu.G2"][k0]
    x1, x2, xl = 0.3 * SBASE / 200.0, 0.01 * SBASE / 100.0, 0.6
    E1 = V + 1j * x1 * np.conj(S1 / V)
    E2 = V2 + 1j * x2 * np.conj(S2 / V2)
    if zf == 0:  # bolted: V1 = 0, bus 2 a divider of E2 between ZSORCE and the line
        return np.array([0.0, abs(E2 * xl / (xl + x2))]), abs(E1)
    yf = 1.0 / zf
    Y = np.array(
        [[1 / (1j * x1) + 1 / (1j * xl) + yf, -1 / (1j * xl)],
         [-1 / (1j * xl), 1 / (1j * xl) + 1 / (1j * x2)]]
    )  # fmt: skip
    Vb = np.linalg.solve(Y, [E1 / (1j * x1), E2 / (1j * x2)])
    return np.abs(Vb), abs(E1)


@probe("AP09")
def _():
    col, k0, k1 = run_fault("1:0.02:0.1")
    want, e1 = hand_fault(col, k0, k1, 0.02 + 0.1j)
    got = np.array([col["vmag_pu.B1"][k1], col["vmag_pu.B2"][k1]])
    d = float(np.abs(got - want).max())
    return d < 1e-6, (
        f"--bus-fault 1:0.02:0.1 at 0.1 s: |V1|, |V2| {got[0]:.7f}, {got[1]:.7f} vs hand "
        f"{want[0]:.7f}, {want[1]:.7f} (Zf pu system base, ZSORCE 0.3 on 200 MVA = 0.15; "
        f"|E'1| {e1:.6f}); diff {d:.1e}"
    )


@probe("AP10")
def _():
    col, k0, k1 = run_fault("1")
    want, _ = hand_fault(col, k0, k1, 0)
    got = np.array([col["vmag_pu.B1"][k1], col["vmag_pu.B2"][k1]])
    w2 = col["speed_pu.G2"]
    d = float(np.abs(got - want).max())
    flat = float(np.abs(w2 - 1.0).max())
    return d < 1e-6 and flat == 0.0, (
        f"bolted bus fault at 1: |V1| {got[0]:.1e}, |V2| {got[1]:.7f} vs E2 x_line/(x_line + "
        f"ZSORCE) {want[1]:.7f}; infinite bus (GENCLS H 0) speed max |dw| {flat:.1e}"
    )


@probe("AP11")
def _():
    out, ok = [], True
    for kind in ("GENROU", "GENSAL", "GENROE"):
        M = Machine(kind)
        M.init_check()
        for de in (-0.45, 0.6):  # below the quadratic's A (S = 0) and far above 1.2
            pert = (0.1, 0.02, de, de * 0.9, 0.0, 0.0)
            e1, dm, f, o, r = M.deriv_check(pert)
            ok &= e1 < TOL
            out.append(f'{kind} |psi"| {r["PSIpp"]:.2f} {e1:.0e}')
    return ok, "saturation's two branches, max rel diff: " + ", ".join(out)


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
        if not os.environ.get("KEEP"):
            shutil.rmtree(TMP, ignore_errors=True)
    sys.exit(1 if bad else 0)
