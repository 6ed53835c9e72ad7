#!/usr/bin/env python
"""Thirty-eighth reliability round (round 49, part AH): linearisation and modal analysis
(`stabctl eig`, its --report and --json, `linearise` / `modal_analysis`) against
independent computations and definitions, in variants the earlier rounds (_13, _22, _25,
_29, _30, _32, _36) do not try:

1. the linear model against the nonlinear simulator: A against a central-difference
   Jacobian taken here from `DynamicModel.evaluate` (a Python loop, another step, not the
   compiled `_differences`) on Kundur, miniWECC, ANDES's IEEE 14 read from PSS/E RAW+DYR and
   ANDES's kundur_full.xlsx; a tiny VREF / PREF step simulated (`Simulator.run` with
   `VrefStep` / `PrefStep`) against python-control's response of the StateSpace's
   `Vref_G<k>` / `Pref_G<k>` input;
2. the modal figures against their definitions (frequency = Im/2pi, damping = -Re/|lambda|,
   participations summing to 1 per mode, unit right eigenvectors, psi phi = I, A phi = lambda
   phi, speed shapes with largest 1 + 0j, the angle-reference mode) and --json's units;
3. known values: Kundur with and without PSS against the values docs/modal.md quotes
   (PSTess), and ANDES 2.0's own EIG of ANDES cases no test compares (kundur_sexs,
   ieee14_exac1, ieee14_gast);
4. consistency: miniWECC's text vs --json vs the API; A with other ESD input sets;
   a machine without governor and one at zero Pm; the system re-based to 200 MVA; the buses
   renumbered; a converter case (ieee14_pvd1) through import-andes, text vs --json vs API;
   an islanded case (two angle references).

    python reliability_probes_38.py [ID ...]

CLONE (default: this repository) is the package under test (PYTHONPATH), run as
`python -m stabctl`; NUMBA_CACHE_DIR the caller's (warm it with `python -m stabctl
compile`).  Prints per probe: id, ok/SHORT, reason; exits 1 if any is SHORT.  Every command
has a timeout; work in a temporary directory (removed at the end unless KEEP=1).  About
4 minutes with a warm kernel cache.

The round found short: AH13, an islanded case's second near-zero angle-reference mode shown
as "other" and the JSON's least-damped mode (damping ratio -1), and a coherent area joining
G1 with the other island's G3, G4; fixed (one reference mode per island, areas within an
island).  The 15 others ok.

The round found short (AH13): an islanded case (two swing buses, each island's angles
free to rotate) has two ~0 angle-reference eigenvalues, but modal_analysis marks one:
the other (kind 'other', damping ratio -1 for lambda = +3e-8 1/s) is --json's
damping_statistics['all'] least-damped mode while the same JSON says small_signal_stable,
and the coherent areas put G1 with G3 and G4 of the other island.  Everything else held:
A equals an independent Jacobian to 1e-9, VREF/PREF steps match the simulator within
0.2 %, ANDES's EIG within 0.015 %, re-basing, renumbering, ESD input sets and conventions
leave the eigenvalues unchanged.
"""

# ruff: noqa: E501, BLE001, RUF059, SIM115 - a tester's script, kept as written

import json
import os
import re
import sys
import textwrap

from _probe_kit import Kit

KIT = Kit("probes_ah49_", path=False, prefixes=False)
CLONE, ENV, WD, RESULTS, PROBES = KIT.clone, KIT.env, KIT.wd, KIT.results, KIT.probes
rec, probe = KIT.rec, KIT.probe
ANDES_CASES = None
try:
    import andes  # only to find its case files; its EIG runs in the children

    ANDES_CASES = os.path.join(os.path.dirname(andes.__file__), "cases")
except Exception:
    pass

PRELUDE = textwrap.dedent(
    """
    import json, math, os, sys, traceback, warnings
    import numpy as np
    import control as ct
    import stabctl
    from stabctl.io import load_case
    from stabctl.smallsignal.linearise import linearise
    from stabctl.smallsignal.modal import modal_analysis
    warnings.simplefilter("ignore")
    ANDES_CASES = %r
    def say(x):
        print("@@" + json.dumps(x, default=str))
    def eigs(sys_):
        return np.linalg.eigvals(np.asarray(sys_.A))
    """
)


def py(code, timeout=300):
    """Run a snippet (after PRELUDE) in a fresh interpreter; the dict it says last."""
    rc, out, err, _dt = KIT.run_argv(
        [sys.executable, "-c", (PRELUDE % ANDES_CASES) + textwrap.dedent(code)],
        timeout,
        partial=False,
    )
    if rc == "timeout":
        return {"kind": "timeout"}
    lines = [ln for ln in out.splitlines() if ln.startswith("@@")]
    if not lines:
        return {"kind": "crashed", "rc": rc, "err": err.strip()[-600:]}
    return json.loads(lines[-1][2:])


def cli(args, timeout=300, env=None):
    """(rc, stdout, stderr) of `python -m stabctl args` in WD; rc "timeout" with nothing."""
    return KIT.cli(args, timeout, env=env, partial=False)


def failed(o):
    """A child that crashed or timed out: the probe is short (its repro is the snippet)."""
    return False, f"{o.get('kind')}: {o.get('err', '')[-400:]}"


# Independent central differences of DynamicModel.evaluate (Python loop, step 1e-6 abs).
OWN_FD = """
from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.model import StageConfig, active_states
from stabctl.smallsignal.linearise import default_esd_buses
def own_jacobian(case, step=1e-6, q_limits=True):
    sim = Simulator(case, q_limits=q_limits, background_compile=False)
    lin = linearise(sim)
    model = sim.model_for(default_esd_buses(case))
    net = model.network(StageConfig())
    x0 = np.array(model.x0, float)
    names = [model.state_name(k).replace('.', '_') for k in range(x0.size)]
    idx = [names.index(s) for s in lin.state_labels]
    f0, _ = model.evaluate(x0.copy(), net, model.V_nc0)
    J = np.zeros((len(idx), len(idx)))
    kinks = []
    for c, k in enumerate(idx):
        h = step * max(abs(x0[k]), 1.0)
        xp = x0.copy(); xp[k] += h
        xm = x0.copy(); xm[k] -= h
        fp, _ = model.evaluate(xp, net, model.V_nc0)
        fm, _ = model.evaluate(xm, net, model.V_nc0)
        fp, fm, ff = fp[idx], fm[idx], f0[idx]
        J[:, c] = (fp - fm) / (2 * h)
        fwd, bwd = (fp - ff) / h, (ff - fm) / h
        if np.abs(fwd - bwd).max() > 1e-2 * max(np.abs(fwd).max(), np.abs(bwd).max(), 1e-300):
            kinks.append(lin.state_labels[c])
    return lin, J, kinks, float(np.abs(f0[idx]).max())
"""


# ------------------------------------------------------------------ 1. linear vs nonlinear
@probe("AH01")
def _():
    """A of linearise against a central-difference Jacobian of DynamicModel.evaluate taken
    here (step 1e-6, a Python loop, the same operating point) on Kundur, miniWECC, ANDES's
    IEEE 14 RAW+DYR read by load_psse and ANDES's kundur_full.xlsx read by import_andes:
    docs/modal.md says every entry comes from the simulator's own evaluation with an
    error near 1e-10 of the largest entry; columns where one-sided slopes differ (a limit
    at the point, named by linearise's warning) are left out and counted."""
    o = py(
        OWN_FD
        + textwrap.dedent(
            """
    from stabctl.io.psse import load_psse
    from stabctl.io.andes_case import import_andes
    out = {}
    cases = {"kundur": lambda: load_case("kundur"), "miniwecc": lambda: load_case("miniwecc")}
    if ANDES_CASES:
        cases["ieee14 psse"] = lambda: load_psse(ANDES_CASES + "/ieee14/ieee14.raw", ANDES_CASES + "/ieee14/ieee14.dyr", on_unsupported="skip")
        cases["andes kundur_full"] = lambda: import_andes(ANDES_CASES + "/kundur/kundur_full.xlsx")
    for name, mk in cases.items():
        try:
            lin, J, kinks, fmax = own_jacobian(mk(), q_limits=not name.startswith("andes"))
        except Exception as e:
            out[name] = {"error": f"{type(e).__name__}: {e}"[:300]}
            continue
        A = np.asarray(lin.A)
        keep = [c for c, s in enumerate(lin.state_labels) if s not in kinks]
        d = np.abs(A[:, keep] - J[:, keep]).max() / np.abs(A).max()
        le = np.sort_complex(np.linalg.eigvals(A))
        out[name] = {"n": A.shape[0], "rel_diff": float(d), "kinks": kinks[:5], "n_kinks": len(kinks), "f0max": fmax}
    say(out)
    """
        ),
        timeout=600,
    )
    if o.get("kind"):
        return failed(o)
    bad = [k for k, v in o.items() if "error" in v or v["rel_diff"] > 1e-6]
    why = "; ".join(
        f"{k}: {v['error']}"
        if "error" in v
        else f"{k} n={v['n']} max|A-J|/max|A|={v['rel_diff']:.1e}"
        + (f" ({v['n_kinks']} kinked cols left out: {v['kinks']})" if v["n_kinks"] else "")
        for k, v in o.items()
    )
    return not bad, why


@probe("AH02")
def _():
    """A tiny VREF step (1e-3 pu) and PREF step (1e-3 pu) of G1 simulated by Simulator.run
    (VrefStep / PrefStep, h = 1/960 s, exact semantics) against python-control's
    forced_response of the StateSpace's Vref_G1 / Pref_G1 column: speeds (omega_G<k>) and
    bus voltages (vmag_B<n>) within 2 % of the peak deviation (docs/modal.md's pulse check
    reports 0.01-0.42 %); Kundur 10 s and miniWECC 10 s."""
    o = py(
        """
    from stabctl.dynamics.driver import Simulator
    from stabctl.dynamics.events import VrefStep, PrefStep
    out = {}
    for cname in ("kundur", "miniwecc"):
        case = load_case(cname)
        sim = Simulator(case, background_compile=False)
        lin = linearise(sim)
        g = int(case.machines.number[0])
        for ev, inp, size in ((VrefStep(g, 0.5, 1e-3), f"Vref_G{g}", 1e-3), (PrefStep(g, 0.5, 1e-3), f"Pref_G{g}", 1e-3)):
            h = 1 / 960
            res = sim.run([ev], t_end=10.0, h=h, semantics="exact")
            j = lin.input_labels.index(inp)
            col = ct.ss(lin.A, lin.B[:, [j]], lin.C, lin.D[:, [j]])
            t = res.t
            u = np.where(t >= 0.5 - 1e-12, size, 0.0)
            y = ct.forced_response(ct.sample_system(col, h, method="zoh"), np.arange(t.size) * h, u).outputs.T
            lab = lin.output_labels
            G = [f"omega_G{int(m)}" for m in res.machines]
            B = [f"vmag_B{int(b)}" for b in res.buses]
            ys = y[:, [lab.index(n) for n in G]]
            yv = y[:, [lab.index(n) for n in B]]
            ns = res.speed - 1.0
            nv = res.vmag - res.vmag[0]
            es = float(np.abs(ys - ns).max() / np.abs(ns).max())
            ev_ = float(np.abs(yv - nv).max() / np.abs(nv).max())
            out[f"{cname} {inp}"] = {"speed": es, "vmag": ev_, "peak_speed": float(np.abs(ns).max()), "peak_v": float(np.abs(nv).max())}
    say(out)
    """,
        timeout=900,
    )
    if o.get("kind"):
        return failed(o)
    bad = [k for k, v in o.items() if v["speed"] > 0.02 or v["vmag"] > 0.02]
    return not bad, "; ".join(
        f"{k}: speed {v['speed']:.2%} of peak {v['peak_speed']:.1e}, vmag {v['vmag']:.2%} of {v['peak_v']:.1e}"
        for k, v in o.items()
    )


# ------------------------------------------------------------------ 2. definitions
@probe("AH03")
def _():
    """modal_analysis's figures against their definitions (docs/modal.md 'Modal analysis'):
    freq_hz = |Im|/2pi, damping = -Re/|lambda|, A phi = lambda phi, right eigenvectors of
    unit 2-norm, left rows with psi phi = I, participations >= 0 with columns summing to 1,
    speed shapes the omega rows of phi scaled to a largest of 1 + 0j, one eigenvalue per
    conjugate pair covering all of eig(A), the angle-reference mode ~0 with its right
    eigenvector parallel to the common rotation e (1 - cos < 1e-12); Kundur and miniWECC."""
    o = py(
        """
    out = {}
    for cname in ("kundur", "miniwecc"):
        lin = linearise(load_case(cname))
        ma = modal_analysis(lin)
        A = np.asarray(lin.A)
        lam, R, L, P = ma.eigenvalues, ma.right, ma.left, ma.participation
        chk = {}
        chk["freq"] = float(np.abs(ma.freq_hz - np.abs(lam.imag) / (2 * np.pi)).max())
        mag = np.abs(lam)
        z = np.where(mag > 0, -lam.real / np.where(mag > 0, mag, 1), 1.0)
        chk["damping"] = float(np.abs(ma.damping - z).max())
        chk["A_phi"] = float((np.abs(A @ R - R * lam).max(axis=0) / np.maximum(np.abs(lam), 1)).max() / np.abs(A).max())
        chk["unit"] = float(np.abs(np.linalg.norm(R, axis=0) - 1).max())
        chk["psi_phi"] = float(np.abs(L @ R - np.eye(lam.size)).max())
        chk["pf_sum"] = float(np.abs(P.sum(axis=0) - 1).max())
        chk["pf_neg"] = float(-min(P.min(), 0))
        speed = [i for i, s in enumerate(lin.state_labels) if s.startswith("mac_omega_G")]
        sh = R[speed] / R[speed][np.argmax(np.abs(R[speed]), axis=0), np.arange(lam.size)]
        chk["shape"] = float(np.abs(sh - ma.speed_shape).max())
        full = np.linalg.eigvals(A)
        half = full[full.imag >= -1e-9 * np.abs(full)]
        # every eigenvalue of A with Im >= 0 is one of ma's (and the count)
        chk["cover"] = float(max(np.min(np.abs(lam - e)) / max(abs(e), 1) for e in half))
        chk["count"] = [int(lam.size), int(half.size)]
        ref = ma.reference_mode
        e = np.zeros(len(lin.state_labels)); e[[i for i, s in enumerate(lin.state_labels) if s.startswith("mac_delta_G")]] = 1
        cosv = abs(np.vdot(e, R[:, ref])) / np.linalg.norm(e)
        chk["ref"] = [complex(lam[ref]).__repr__(), float(1 - cosv), str(ma.kind[ref])]
        # the reference mode's share of the statistics
        st = ma.damping_statistics()
        chk["stats_excl_ref"] = st["all"]["mode"] != ref
        out[cname] = chk
    say(out)
    """
    )
    if o.get("kind"):
        return failed(o)
    bad = []
    for c, k in o.items():
        for key, tol in (
            ("freq", 1e-12),
            ("damping", 1e-12),
            ("A_phi", 1e-9),
            ("unit", 1e-12),
            ("psi_phi", 1e-8),
            ("pf_sum", 1e-12),
            ("pf_neg", 0),
            ("shape", 1e-12),
            ("cover", 1e-8),
        ):
            if k[key] > tol:
                bad.append(f"{c} {key} {k[key]:.1e}")
        if k["count"][0] != k["count"][1]:
            bad.append(f"{c} {k['count'][0]} modes for {k['count'][1]} eigenvalues Im>=0")
        if k["ref"][1] > 1e-12 or k["ref"][2] != "angle reference":
            bad.append(f"{c} reference mode {k['ref']}")
        if not k["stats_excl_ref"]:
            bad.append(f"{c} statistics include the reference mode")
    return not bad, "; ".join(bad) or "; ".join(
        f"{c}: psi phi - I {k['psi_phi']:.0e}, A phi {k['A_phi']:.0e}, ref {k['ref'][0]} 1-cos {k['ref'][1]:.0e}, {k['count'][0]} modes"
        for c, k in o.items()
    )


@probe("AH04")
def _():
    """`eig kundur --json` against the API and the definitions: every mode's freq_hz =
    imag_rad_per_s / 2pi, damping_ratio = -real_per_s / |lambda|, the eigenvalues those of
    linearise's A, the reference_mode's eigenvalue the API's, units named in the keys
    (per_s, rad_per_s, hz); and --json's electromechanical list equal to the text's rows."""
    rc, out, err = cli(["eig", "kundur", "--json"])
    if rc != 0:
        return False, f"rc {rc}: {err[-300:]}"
    js = json.loads(out)
    o = py(
        """
    lin = linearise(load_case("kundur")); ma = modal_analysis(lin)
    say({"lam": [[float(l.real), float(l.imag)] for l in ma.eigenvalues], "ref": ma.reference_mode, "em": [int(i) for i in ma.electromechanical]})
    """
    )
    if o.get("kind"):
        return failed(o)
    bad = []
    modes = js["modes"]
    for m in modes:
        lam = complex(m["real_per_s"], m["imag_rad_per_s"])
        if abs(m["freq_hz"] - abs(lam.imag) / (2 * 3.141592653589793)) > 1e-12:
            bad.append(f"mode {m['mode']} freq")
        if abs(lam) > 0 and abs(m["damping_ratio"] + lam.real / abs(lam)) > 1e-12:
            bad.append(f"mode {m['mode']} damping")
    api = [complex(*x) for x in o["lam"]]
    if (
        len(api) != len(modes)
        or max(abs(complex(m["real_per_s"], m["imag_rad_per_s"]) - a) for m, a in zip(modes, api))
        > 1e-9
    ):
        bad.append("eigenvalues differ from the API's")
    if js["reference_mode"] != o["ref"] or js["electromechanical_modes"] != o["em"]:
        bad.append(
            f"ref/em {js['reference_mode']}/{js['electromechanical_modes']} vs API {o['ref']}/{o['em']}"
        )
    rc2, txt, _ = cli(["eig", "kundur"])
    rows = [int(x) for x in re.findall(r"^\s*(\d+)\s+[-+]?\d", txt, re.M)]
    if sorted(rows) != sorted(js["electromechanical_modes"]):
        bad.append(f"text rows {rows} vs json em {js['electromechanical_modes']}")
    return not bad, "; ".join(
        bad[:6]
    ) or f"{len(modes)} modes; em {js['electromechanical_modes']}; text rows {rows}"


# ------------------------------------------------------------------ 3. known values
@probe("AH05")
def _():
    """docs/modal.md 'Validation': Kundur without PSS has the unstable inter-area mode
    +0.0658 +- j3.9865 (0.634 Hz, PSTess), with PSS the electromechanical modes are 0.612,
    1.292, 1.340 Hz; `eig kundur --no-pss` says the case is small-signal unstable."""
    rc, out, err = cli(["eig", "kundur", "--no-pss", "--json"])
    rc2, out2, _ = cli(["eig", "kundur", "--json"])
    rc3, txt, _ = cli(["eig", "kundur", "--no-pss"])
    if rc or rc2 or rc3:
        return False, f"rc {rc}/{rc2}/{rc3}: {err[-200:]}"
    nop, wp = json.loads(out), json.loads(out2)
    em0 = [nop["modes"][i] for i in nop["electromechanical_modes"]]
    inter = min(em0, key=lambda m: abs(m["imag_rad_per_s"] - 3.9865))
    em1 = sorted(round(wp["modes"][i]["freq_hz"], 3) for i in wp["electromechanical_modes"])
    bad = []
    if abs(inter["real_per_s"] - 0.0658) > 5e-4 or abs(inter["imag_rad_per_s"] - 3.9865) > 5e-4:
        bad.append(f"no-PSS inter-area {inter['real_per_s']:+.4f} j{inter['imag_rad_per_s']:.4f}")
    if nop["small_signal_stable"] or "unstable" not in txt.lower():
        bad.append("no-PSS not said unstable")
    if em1 != [0.612, 1.292, 1.34]:
        bad.append(f"with PSS EM {em1}")
    return (
        not bad,
        "; ".join(bad)
        or f"no-PSS {inter['real_per_s']:+.4f} +- j{inter['imag_rad_per_s']:.4f} ({inter['kind']}); with PSS {em1}",
    )


@probe("AH06")
def _():
    """ANDES 2.0's own EIG (andes.load, PFlow, EIG.mu) of ANDES cases no test compares
    (kundur_sexs, kundur_exst1, ieee14_exac1, ieee14_ieeet1, ieee14_gast) against stabctl's
    import_andes(on_unsupported="skip": data ANDES defaults kept as ANDES runs them) +
    linearise(q_limits=False): every stabctl electromechanical mode within 1 % of
    ANDES's nearest eigenvalue (issue 29's target, docs/cli.md: Kundur 0.07 %)."""
    if not ANDES_CASES:
        return True, "andes not importable: skipped"
    o = py(
        """
    import logging, andes
    from stabctl.io.andes_case import import_andes
    logging.disable(logging.CRITICAL)
    out = {}
    for f in ("kundur/kundur_sexs.xlsx", "kundur/kundur_exst1.xlsx", "ieee14/ieee14_exac1.xlsx", "ieee14/ieee14_ieeet1.xlsx", "ieee14/ieee14_gast.xlsx"):
        p = ANDES_CASES + "/" + f
        try:
            ma = modal_analysis(linearise(import_andes(p, on_unsupported="skip"), q_limits=False))
        except Exception as e:
            out[f] = {"error": f"{type(e).__name__}: {e}"[:300]}
            continue
        ours = ma.eigenvalues[ma.electromechanical]
        ss = andes.load(p, setup=True, no_output=True, default_config=True)
        ss.PFlow.run()
        ss.EIG.run()
        th = np.asarray(ss.EIG.mu)
        gaps = [float(abs(l - th[np.argmin(np.abs(th - l))]) / abs(l)) for l in ours]
        th_em = th[(th.imag > 2 * np.pi * 0.1) & (th.imag < 2 * np.pi * 2.5)]
        out[f] = {"ours": [[round(l.real, 4), round(l.imag, 4)] for l in ours], "gaps": gaps,
                  "andes_em_count": int(th_em.size)}
    say(out)
    """,
        timeout=600,
    )
    if o.get("kind"):
        return failed(o)
    bad, why = [], []
    for f, v in o.items():
        if "error" in v:
            why.append(f"{f}: {v['error'][:150]}")
            continue
        g = max(v["gaps"]) if v["gaps"] else float("nan")
        if not v["gaps"] or g > 0.01:
            bad.append(f)
        why.append(f"{f}: {len(v['gaps'])} EM modes, worst {g:.3%}")
    return not bad, "; ".join(why)


# ------------------------------------------------------------------ 4. consistency
@probe("AH07")
def _():
    """`eig miniwecc` text vs --json vs API: the text's rows (mode number, f, damping) are
    --json's electromechanical modes with the same figures (as printed), and --json's
    eigenvalues are modal_analysis(linearise(load_case('miniwecc')))'s."""
    rc, txt, err = cli(["eig", "miniwecc"])
    rc2, out, err2 = cli(["eig", "miniwecc", "--json"])
    if rc or rc2:
        return False, f"rc {rc}/{rc2}: {(err + err2)[-300:]}"
    js = json.loads(out)
    o = py(
        """
    lin = linearise(load_case("miniwecc")); ma = modal_analysis(lin)
    say({"lam": [[float(l.real), float(l.imag)] for l in ma.eigenvalues]})
    """
    )
    if o.get("kind"):
        return failed(o)
    bad = []
    d = max(
        abs(complex(m["real_per_s"], m["imag_rad_per_s"]) - complex(*a))
        for m, a in zip(js["modes"], o["lam"])
    )
    if len(js["modes"]) != len(o["lam"]) or d > 1e-8:
        bad.append(f"json vs API eigenvalues differ by {d:.1e}")
    rows = {}
    for ln in txt.splitlines():
        m = re.match(r"^\s*(\d+)\s+([-+]?\d+\.\d+)\s+([-+]?\d+\.\d+)", ln)
        if m:
            rows[int(m.group(1))] = (float(m.group(2)), float(m.group(3)))
    em = js["electromechanical_modes"]
    if sorted(rows) != sorted(em):
        bad.append(f"text rows {sorted(rows)[:5]}... ({len(rows)}) vs json em ({len(em)})")
    for i, (f, z) in rows.items():
        if i < len(js["modes"]):
            m = js["modes"][i]
            if abs(f - m["freq_hz"]) > 6e-3 or abs(z - m["damping_ratio"]) > 6e-3 * max(1, abs(z)):
                bad.append(
                    f"mode {i}: text {f} {z} vs json {m['freq_hz']:.4f} {m['damping_ratio']:.4f}"
                )
    return not bad, "; ".join(bad[:5]) or f"{len(rows)} EM rows agree; eigenvalues equal to {d:.0e}"


@probe("AH08")
def _():
    """The ESD inputs do not change the dynamics: linearise(kundur) with esd_buses=[] (no
    storage input), the default HV buses, and every bus as an extra ESD bus (all kept in the
    reduced network) have the same A up to round-off (1e-8 of max|A|) and the same
    eigenvalues; the B columns of Vref/Pref the same; miniWECC with and without 20 extra
    load buses likewise."""
    o = py(
        """
    out = {}
    case = load_case("kundur")
    base = linearise(case)
    allb = [int(b) for b in case.buses.number]
    for tag, kw in (("none", dict(esd_buses=[])), ("all buses", dict(extra_buses=allb))):
        other = linearise(case, **kw)
        dA = float(np.abs(np.asarray(other.A) - np.asarray(base.A)).max() / np.abs(base.A).max())
        j0 = [base.input_labels.index(n) for n in base.input_labels if not n.startswith("P_esd")]
        j1 = [other.input_labels.index(n) for n in base.input_labels if not n.startswith("P_esd")]
        dB = float(np.abs(np.asarray(other.B)[:, j1] - np.asarray(base.B)[:, j0]).max() / np.abs(base.B[:, j0]).max())
        e0, e1 = np.sort_complex(eigs(base)), np.sort_complex(eigs(other))
        out["kundur " + tag] = {"dA": dA, "dB": dB, "dlam": float(np.abs(e0 - e1).max()), "ninp": other.ninputs}
    mw = load_case("miniwecc")
    b0 = linearise(mw)
    loads = [int(b) for b in mw.loads.bus][:20]
    b1 = linearise(mw, extra_buses=loads)
    e0, e1 = np.sort_complex(eigs(b0)), np.sort_complex(eigs(b1))
    out["miniwecc +20"] = {"dA": float(np.abs(np.asarray(b1.A) - np.asarray(b0.A)).max() / np.abs(b0.A).max()), "dB": 0.0, "dlam": float(np.abs(e0 - e1).max()), "ninp": b1.ninputs}
    say(out)
    """
    )
    if o.get("kind"):
        return failed(o)
    bad = [k for k, v in o.items() if v["dA"] > 1e-8 or v["dB"] > 1e-8]
    return not bad, "; ".join(
        f"{k}: dA {v['dA']:.0e} dB {v['dB']:.0e} dlam {v['dlam']:.0e} ({v['ninp']} inputs)"
        for k, v in o.items()
    )


@probe("AH09")
def _():
    """A machine without governor (Kundur's G1's tg_con row removed) and a machine at zero
    Pm (G2's generation moved to the swing: pgen 0 at its bus): eig gives a model whose
    states and inputs say so (no tg_*_G1 state, no Pref_G1 input; G2's governor at Pm 0
    linearised or refused by name), the reference mode still found, modes in the band.
    (G2's 7 pu taken off bus 4's load too, so that the power flow has the same transfer.)"""
    o = py(
        """
    import dataclasses
    out = {}
    case = load_case("kundur")
    g = case.governors
    keep = [i for i in range(len(g.machine)) if int(g.machine[i]) != 1]
    c1 = case.replace(governors=g.select(keep))
    try:
        lin = linearise(c1); ma = modal_analysis(lin)
        out["no gov G1"] = {"n": lin.nstates, "tg_G1": [s for s in lin.state_labels if s.startswith("tg_") and s.endswith("_G1")],
                            "pref_G1": "Pref_G1" in lin.input_labels, "ref": str(ma.kind[ma.reference_mode]) if ma.reference_mode is not None else None,
                            "em": [round(float(ma.freq_hz[i]), 3) for i in ma.electromechanical]}
    except Exception as e:
        out["no gov G1"] = {"error": f"{type(e).__name__}: {e}"[:300]}
    # G2 at zero Pm
    b = case.buses
    k2 = case.bus_index(int(case.machines.bus[1]))
    pg = np.array(b.pgen, float); pl = np.array(b.pload, float)
    k4 = case.bus_index(4)  # area 1's load bus: its load less by G2's output, the balance kept
    pl[k4] -= pg[k2]; pg[k2] = 0.0
    c2 = case.replace(buses=b.replace(pgen=pg, pload=pl))
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        try:
            lin = linearise(c2); ma = modal_analysis(lin)
            from stabctl.dynamics.driver import Simulator
            sim = Simulator(c2, background_compile=False)
            pm = float(np.asarray(sim.model_for([]).x0).size)
            out["G2 Pm 0"] = {"n": lin.nstates, "ref": str(ma.kind[ma.reference_mode]) if ma.reference_mode is not None else None,
                              "em": [round(float(ma.freq_hz[i]), 3) for i in ma.electromechanical],
                              "unstable": [int(i) for i in ma.unstable_modes()],
                              "warn": [str(x.message)[:200] for x in w]}
        except Exception as e:
            out["G2 Pm 0"] = {"error": f"{type(e).__module__}.{type(e).__name__}: {e}"[:300]}
    say(out)
    """
    )
    if o.get("kind"):
        return failed(o)
    bad = []
    a = o["no gov G1"]
    if (
        "error" in a
        or a["tg_G1"]
        or a["pref_G1"]
        or a["ref"] != "angle reference"
        or len(a["em"]) < 3
    ):
        bad.append(f"no gov G1: {a}")
    b = o["G2 Pm 0"]
    if "error" in b:
        if "stabctl" not in b["error"].split(":")[0]:
            bad.append(f"G2 Pm 0: {b['error']}")
    elif b["ref"] != "angle reference" or len(b["em"]) < 3:
        bad.append(f"G2 Pm 0: {b}")
    return not bad, "; ".join(bad) or f"no gov G1: {a['n']} states, EM {a['em']}; G2 Pm 0: {b}"


REBASE = """
def rebase(case, s):
    k = s / case.base_mva
    b, br = case.buses, case.branches
    nb = b.replace(pgen=b.pgen / k, qgen=b.qgen / k, pload=b.pload / k, qload=b.qload / k,
                   gshunt=b.gshunt / k, bshunt=b.bshunt / k, qmax=b.qmax / k, qmin=b.qmin / k)
    nbr = br.replace(r=br.r * k, x=br.x * k, b=br.b / k, g_from=br.g_from / k, b_from=br.b_from / k,
                     g_to=br.g_to / k, b_to=br.b_to / k)
    return case.replace(base_mva=s, buses=nb, branches=nbr)
"""


@probe("AH10")
def _():
    """The system re-based to 200 MVA and 237 MVA (bus powers, shunts and Q limits divided
    by S/100, branch impedances multiplied, admittances divided; machine and controller data
    on their own bases) is the same system: its electromechanical eigenvalues equal the
    100 MVA case's (1e-6 relative); the B columns of the ESD inputs (pu on the system base)
    per MW equal (200 MVA is exact in binary: 237 MVA tests rounding, not only bits)."""
    o = py(
        REBASE
        + textwrap.dedent(
            """
    out = {}
    for cname, s in (("kundur", 200.0), ("kundur", 237.0), ("miniwecc", 237.0)):
        case = load_case(cname)
        c2 = rebase(case, s)
        cname = f"{cname} at {s:g} MVA"
        try:
            l1, l2 = linearise(case), linearise(c2)
        except Exception as e:
            out[cname] = {"error": f"{type(e).__name__}: {e}"[:300]}; continue
        e1, e2 = np.sort_complex(eigs(l1)), np.sort_complex(eigs(l2))
        m1, m2 = modal_analysis(l1), modal_analysis(l2)
        em1 = m1.eigenvalues[m1.electromechanical]; em2 = m2.eigenvalues[m2.electromechanical]
        d = float(np.abs(e1 - e2).max() / np.abs(e1).max()) if e1.size == e2.size else float("inf")
        dem = float(np.abs(em1 - em2).max() / np.abs(em1).max()) if em1.size == em2.size else float("inf")
        j = [i for i, n in enumerate(l1.input_labels) if n.startswith("P_esd")]
        dB = float(np.abs(np.asarray(l2.B)[:, j] / (s / 100.0) - np.asarray(l1.B)[:, j]).max() / np.abs(np.asarray(l1.B)[:, j]).max())
        out[cname] = {"dlam": d, "dem": dem, "n": [int(e1.size), int(e2.size)], "dB_perMW": dB,
                      "inj": len(case.injections.bus) if hasattr(case.injections, "bus") else None}
    say(out)
    """
        )
    )
    if o.get("kind"):
        return failed(o)
    bad = []
    for c, v in o.items():
        if "error" in v:
            bad.append(f"{c}: {v['error']}")
        elif v["dem"] > 1e-6 or v["dB_perMW"] > 1e-6:
            bad.append(
                f"{c}: EM eigenvalues {v['dem']:.1e}, all {v['dlam']:.1e}, B per MW {v['dB_perMW']:.1e} (injections {v['inj']})"
            )
    return not bad, "; ".join(bad) or "; ".join(
        f"{c}: EM {v['dem']:.0e}, all {v['dlam']:.0e}, B per MW {v['dB_perMW']:.0e}"
        for c, v in o.items()
    )


@probe("AH11")
def _():
    """Bus renumbering: Kundur written as a case file with every bus number n mapped to
    7000 + (n * 37) % 1000 (all tables) and the bus and branch rows in reverse order, then `eig FILE --json`: the same eigenvalues
    (1e-9), the same electromechanical modes and kinds, the machines' names carrying the
    new buses, the best-ESD buses the mapped ones."""
    o = py(
        """
    from stabctl.io.pst import write_case_json
    case = load_case("kundur")
    write_case_json(case, "k_orig.json")
    d = json.load(open("k_orig.json"))
    nums = [int(r[0]) for r in d["tables"]["buses"]["rows"]]
    mp = {n: 7000 + (n * 37) % 1000 for n in nums}
    assert len(set(mp.values())) == len(mp)
    buscols = {"buses": ["number"], "branches": ["from_bus", "to_bus"], "machines": ["bus"], "loads": ["bus"],
               "injections": ["bus"], "converters": ["bus"], "svcs": ["bus"], "switched_shunts": ["bus"]}
    touched = {}
    for t, tab in d["tables"].items():
        cols = [c for c in tab["columns"] if c in buscols.get(t, []) or c in ("bus", "from_bus", "to_bus")]
        for c in cols:
            k = tab["columns"].index(c)
            for r in tab["rows"]:
                r[k] = mp[int(r[k])]
            touched.setdefault(t, []).append(c)
    if d.get("sw_con"):
        d["sw_con"] = None
    d["tables"]["buses"]["rows"] = d["tables"]["buses"]["rows"][::-1]  # and the bus rows reversed
    d["tables"]["branches"]["rows"] = d["tables"]["branches"]["rows"][::-1]
    json.dump(d, open("k_renum.json", "w"))
    say({"map": {str(k): v for k, v in mp.items()}, "touched": touched, "tables": list(d["tables"])})
    """
    )
    if o.get("kind"):
        return failed(o)
    mp = {int(k): v for k, v in o["map"].items()}
    rc1, out1, e1 = cli(["eig", os.path.join(WD, "k_orig.json"), "--json"])
    rc2, out2, e2 = cli(["eig", os.path.join(WD, "k_renum.json"), "--json"])
    if rc1 or rc2:
        return False, f"rc {rc1}/{rc2}: {(e1 + e2)[-300:]} (tables touched {o['touched']})"
    j1, j2 = json.loads(out1), json.loads(out2)
    bad = []
    l1 = sorted((round(m["real_per_s"], 9), round(m["imag_rad_per_s"], 9)) for m in j1["modes"])
    l2 = sorted((round(m["real_per_s"], 9), round(m["imag_rad_per_s"], 9)) for m in j2["modes"])
    dl = (
        max(abs(complex(*a) - complex(*b)) for a, b in zip(l1, l2))
        if len(l1) == len(l2)
        else float("inf")
    )
    if dl > 1e-7:
        bad.append(f"eigenvalues differ by {dl:.1e}")
    em1 = [
        (round(j1["modes"][i]["freq_hz"], 6), j1["modes"][i]["kind"])
        for i in j1["electromechanical_modes"]
    ]
    em2 = [
        (round(j2["modes"][i]["freq_hz"], 6), j2["modes"][i]["kind"])
        for i in j2["electromechanical_modes"]
    ]
    if em1 != em2:
        bad.append(f"EM modes {em1} vs {em2}")
    for i in j1["electromechanical_modes"]:
        b1 = j1["modes"][i].get("best_esd_bus", "")
        b2 = j2["modes"][i].get("best_esd_bus", "") if i < len(j2["modes"]) else ""
        n1 = int(b1.lstrip("B")) if b1 else None
        if n1 is not None and b2 != f"B{mp[n1]}":
            bad.append(f"mode {i} best ESD {b1} -> {b2} (want B{mp[n1]})")
    names2 = j2["machine_names"]
    if not all(any(str(v) in n for v in mp.values()) for n in names2.values()):
        bad.append(f"machine names {names2}")
    return not bad, "; ".join(
        bad
    ) or f"eigenvalues equal to {dl:.0e}; EM {em2}; names {list(names2.values())[:2]}"


@probe("AH12")
def _():
    """A converter case: ANDES's ieee14_pvd1.xlsx through `import-andes -o F.json`, then
    `eig F.json --no-q-limits` text, `--json` and the API (linearise(load_case(F),
    q_limits=False); with Q limits the CLI refuses the case, naming --no-q-limits): same modes, the
    JSON's eigenvalues those of A, text rows the JSON's electromechanical modes; the
    linearise warning (a limit active at the operating point) said on stderr."""
    if not ANDES_CASES:
        return True, "andes not importable: skipped"
    f = os.path.join(WD, "pvd1.json")
    rc, out, err = cli(
        ["import-andes", os.path.join(ANDES_CASES, "ieee14", "ieee14_pvd1.xlsx"), "-o", f]
    )
    if rc != 0:
        return False, f"import-andes rc {rc}: {err[-300:]}"
    rc1, txt, e1 = cli(["eig", f, "--no-q-limits"])
    rc2, js, e2 = cli(["eig", f, "--no-q-limits", "--json"])
    if rc1 or rc2:
        return False, f"eig rc {rc1}/{rc2}: {(e1 + e2)[-300:]}"
    j = json.loads(js)
    o = py(
        f"""
    lin = linearise(load_case({f!r}), q_limits=False); ma = modal_analysis(lin)
    say({{"lam": [[float(l.real), float(l.imag)] for l in ma.eigenvalues], "n": lin.nstates, "conv": [s for s in lin.state_labels if s.startswith("ibr")][:3]}})
    """
    )
    if o.get("kind"):
        return failed(o)
    bad = []
    d = (
        max(
            abs(complex(m["real_per_s"], m["imag_rad_per_s"]) - complex(*a))
            for m, a in zip(j["modes"], o["lam"])
        )
        if len(j["modes"]) == len(o["lam"])
        else float("inf")
    )
    if d > 1e-8:
        bad.append(f"json vs API {d:.1e}")
    rows = sorted(int(x) for x in re.findall(r"^\s*(\d+)\s+[-+]?\d+\.\d+", txt, re.M))
    if rows != sorted(j["electromechanical_modes"]):
        bad.append(f"text rows {rows} vs json {j['electromechanical_modes']}")
    if "limit" not in (e1 + e2).lower():
        bad.append(f"no word of the limit at the operating point on stderr ({(e1 or '')[:120]!r})")
    if j["n_states"] != o["n"]:
        bad.append(f"n_states {j['n_states']} vs {o['n']}")
    return not bad, "; ".join(
        bad
    ) or f"{o['n']} states ({o['conv']}), EM rows {rows}; stderr: {e1.strip()[:140]}"


@probe("AH13")
def _():
    """An islanded case: Kundur with the two 13-101 tie circuits opened, bus 11 (G3) made a
    second swing bus, G2 at 2.5 pu and bus 14's load 14 pu (each island balanced), written as
    a case file and run as `eig FILE --no-q-limits --json` (and the text).  Each island's
    common rotation of its angles is an angle-reference direction, so A has two ~0
    eigenvalues.  docs/modal.md: the angle-reference mode is marked `angle reference` and
    excluded from the damping statistics: the second one must be marked or left out too (or
    the case refused by name), never the 'least damped' mode of damping_statistics (a
    damping ratio of -1 for lambda ~ +1e-8) while the same JSON says small_signal_stable;
    and no coherent area joins machines of the two islands (they cannot swing together)."""
    o = py(
        """
    from stabctl.io.pst import write_case_json
    c = load_case("kundur"); b = c.buses; br = c.branches
    fb, tb = np.asarray(br.from_bus, int), np.asarray(br.to_bus, int)
    keep = [i for i in range(len(fb)) if not (101 in (fb[i], tb[i]) and 13 in (fb[i], tb[i]))]
    kind = np.array(b.kind, float); kind[c.bus_index(11)] = 1
    pg = np.array(b.pgen, float); pl = np.array(b.pload, float)
    pg[c.bus_index(2)] = 2.5; pl[c.bus_index(14)] = 14.0
    c2 = c.replace(name="kundur_split", branches=br.select(keep), buses=b.replace(kind=kind, pgen=pg, pload=pl))
    write_case_json(c2, "kundur_split.json")
    say({"ok": 1})
    """
    )
    if o.get("kind"):
        return failed(o)
    f = os.path.join(WD, "kundur_split.json")
    rc, out, err = cli(["eig", f, "--no-q-limits", "--json"])
    rc2, txt, err2 = cli(["eig", f, "--no-q-limits"])
    if rc != 0:
        ok = rc == 2 and "Traceback" not in err
        return ok, f"refused rc {rc}: {err.strip()[-250:]}"
    j = json.loads(out)
    small = [m for m in j["modes"] if abs(complex(m["real_per_s"], m["imag_rad_per_s"])) < 1e-4]
    st = j["damping_statistics"]
    bad = []
    for m in small:
        if m["mode"] == j["reference_mode"]:
            continue
        if m["kind"] != "angle reference" and any(v["mode"] == m["mode"] for v in st.values()):
            bad.append(
                f"second ~0 mode {m['mode']} ({m['real_per_s']:+.1e} 1/s, kind {m['kind']!r}) is damping_statistics' least damped: "
                f"{st['all']} while small_signal_stable={j['small_signal_stable']}"
            )
        if m["mode"] in j["electromechanical_modes"]:
            bad.append(f"second ~0 mode {m['mode']} electromechanical")
    # coherent areas: machines of different islands (G1, G2 | G3, G4) in one area
    isl = {1: "a", 2: "a", 3: "b", 4: "b"}
    for area, ks in j["areas"].items():
        if len({isl.get(int(k)) for k in ks}) > 1:
            bad.append(f"coherent {area} = {ks} mixes the two islands (G1, G2 | G3, G4)")
    return not bad, "; ".join(
        bad
    ) or f"~0 modes {[(m['mode'], m['kind']) for m in small]}; stats {st.get('all')}"


@probe("AH14")
def _():
    """`eig kundur --no-pss --report --out-dir R`: the report says the case is
    small-signal unstable naming the 0.634 Hz inter-area mode (its number, f and real part
    as --json's), and every row of its mode table (eigenvalue, f, damping) equals
    `eig kundur --no-pss --json`'s figures to the digits printed."""
    r = os.path.join(WD, "rep14")
    rc, out, err = cli(["eig", "kundur", "--no-pss", "--report", "--out-dir", r])
    rc2, js, err2 = cli(["eig", "kundur", "--no-pss", "--json"])
    if rc or rc2:
        return False, f"rc {rc}/{rc2}: {(err + err2)[-300:]}"
    j = json.loads(js)
    md = open(os.path.join(r, "eig_kundur_nopss.md")).read()
    bad = []
    uns = j["unstable_modes"]
    line = next((ln for ln in md.splitlines() if "Small-signal unstable" in ln), "")
    for i in uns:
        m = j["modes"][i]
        if (
            f"mode {i}," not in line
            or f"{m['freq_hz']:.3f} Hz" not in line
            or f"{m['real_per_s']:+.4g}" not in line
        ):
            bad.append(f"unstable mode {i} not as --json in {line[:160]!r}")
    if not uns:
        bad.append("--json lists no unstable mode")
    rows = re.findall(
        r"^\| (\d+) \| ([-0-9.]+) ± j([0-9.]+) \| ([0-9.]+) \| ([-0-9.]+) \|", md, re.M
    )
    for i, re_, im, f, z in rows:
        m = j["modes"][int(i)]
        if (
            f"{m['real_per_s']:.4f}",
            f"{m['imag_rad_per_s']:.4f}",
            f"{m['freq_hz']:.4f}",
            f"{m['damping_ratio']:.4f}",
        ) != (re_, im, f, z):
            bad.append(
                f"row {i}: {re_} j{im} {f} {z} vs json {m['real_per_s']:.4f} j{m['imag_rad_per_s']:.4f} {m['freq_hz']:.4f} {m['damping_ratio']:.4f}"
            )
    if sorted(int(x[0]) for x in rows) != sorted(j["electromechanical_modes"]):
        bad.append(f"table rows {[x[0] for x in rows]} vs json EM {j['electromechanical_modes']}")
    return not bad, "; ".join(bad[:4]) or f"{len(rows)} rows equal; {line[:150]}"


@probe("AH15")
def _():
    """eig --help: 'Under either --conventions the linear model is the same (a point inside
    every limit)': linearise(case, conventions='pstess') and 'ieee' give the same
    eigenvalues (1e-8 of the largest) on Kundur and miniWECC, and `eig kundur --conventions
    pstess --json` the same electromechanical modes as the default."""
    o = py(
        """
    out = {}
    for cname in ("kundur", "miniwecc"):
        case = load_case(cname)
        a, b = linearise(case), linearise(case, conventions="pstess")
        e1, e2 = np.sort_complex(eigs(a)), np.sort_complex(eigs(b))
        out[cname] = float(np.abs(e1 - e2).max() / np.abs(e1).max()) if e1.size == e2.size else float("inf")
    say(out)
    """
    )
    if o.get("kind"):
        return failed(o)
    rc, js1, e1 = cli(["eig", "kundur", "--json"])
    rc2, js2, e2 = cli(["eig", "kundur", "--conventions", "pstess", "--json"])
    if rc or rc2:
        return False, f"rc {rc}/{rc2}: {(e1 + e2)[-200:]}"
    j1, j2 = json.loads(js1), json.loads(js2)
    em1 = [round(j1["modes"][i]["freq_hz"], 6) for i in j1["electromechanical_modes"]]
    em2 = [round(j2["modes"][i]["freq_hz"], 6) for i in j2["electromechanical_modes"]]
    bad = [f"{k}: {v:.1e}" for k, v in o.items() if v > 1e-8]
    if em1 != em2:
        bad.append(f"CLI EM {em1} vs {em2}")
    return not bad, "; ".join(bad) or f"eigenvalues equal to {max(o.values()):.0e}; EM {em1}"


@probe("AH16")
def _():
    """The f_bus_B<n> outputs are in Hz (docs/modal.md: (d theta/dt) / 2 pi): 60 s after a
    step of Pref_G1 (linear model alone, python-control), when the swings have died out
    and the system runs at one new speed, every f_bus equals freq_hz * omega_coi (pu) and
    every omega_G equals omega_coi (Kundur, 60 Hz: within 1e-3 of the frequency change);
    the same with the case at 50 Hz (freq_hz replaced)."""
    o = py(
        """
    out = {}
    for fhz in (60.0, 50.0):
        case = load_case("kundur")
        if fhz != 60.0:
            case = case.replace(freq_hz=fhz)
        lin = linearise(case)
        j = lin.input_labels.index("Pref_G1")
        col = ct.ss(lin.A, lin.B[:, [j]], lin.C, lin.D[:, [j]])
        t = np.linspace(0, 60, 6001)
        y = ct.forced_response(col, t, np.full(t.size, 1e-3)).outputs
        lab = lin.output_labels
        end = y[:, -1]
        w = end[lab.index("omega_coi")]
        fb = np.array([end[i] for i, n in enumerate(lab) if n.startswith("f_bus_B")])
        wg = np.array([end[i] for i, n in enumerate(lab) if n.startswith("omega_G")])
        out[str(fhz)] = {"w_coi": float(w), "f_bus_rel": float(np.abs(fb - fhz * w).max() / abs(fhz * w)),
                         "w_rel": float(np.abs(wg - w).max() / abs(w)), "fb0": float(fb[0])}
    say(out)
    """
    )
    if o.get("kind"):
        return failed(o)
    bad = [
        f"{k} Hz: f_bus off by {v['f_bus_rel']:.1e}, speeds {v['w_rel']:.1e} (coi {v['w_coi']:.2e}, f_bus {v['fb0']:.2e})"
        for k, v in o.items()
        if v["f_bus_rel"] > 1e-3 or v["w_rel"] > 1e-3
    ]
    return not bad, "; ".join(bad) or "; ".join(
        f"{k} Hz: d omega_coi {v['w_coi']:.3e} pu, f_bus {v['fb0']:.3e} Hz (off {v['f_bus_rel']:.0e})"
        for k, v in o.items()
    )


if __name__ == "__main__":
    KIT.main(kept=None)
