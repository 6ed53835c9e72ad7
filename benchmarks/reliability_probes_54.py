#!/usr/bin/env python
"""Round 58 (BA): silently wrong results from numerical settings (issue 54 item 6 and its
variants).  Each run at a large step (`--step` 0.01 .. 0.25, `--method` heun or
trapezoid, ieee or pstess conventions) is compared with the same run at a small step
(1/480 s, same method): a different verdict, or a largest angle from the COI off by more
than ANGLE_REL, with exit 0 and no warning (stderr 'warning' nor the JSON's `warnings`)
is SHORT.  A refusal (exit 2 naming the step) or a warning is ok.  `cct --step` large: a
CCT off the small-step one by more than its own error bar and TOL, with no word, is SHORT.

    CLONE=<clone> PYTHONPATH=<clone> python benchmarks/reliability_probes_54.py [BA01,...]

Cases: kundur (bus 3, far bus 101), miniwecc (bus 83, far bus 33), the PSS/E five-bus
case imported from tests/data/psse (five_bus_v33.raw + five_bus.dyr).
Found (round 58, BA; both fixed since): BA95-BA97 REAL: a case of GENCLS machines with a small damping
(D 0.01-0.1, machine base) at heun's default step (10 ms, 50 Hz) over 20 s: largest angle
0.7283 / 0.5603 / 0.4255 rad against 0.3036 / 0.3021 / 0.3003 at 1/480 s (140 / 85 / 42 %),
exit 0, no warning; with D = 0 the same run warns (a factor 5.2).  Cause
stabctl/dynamics/grid.py:247, check_heun_growth judges only machines with D0 == D1 == 0.
BA99-BA100 REAL: a run that lost synchronism (1.47 s) and goes on to --tf 30 fails at ~10.4 s
"numerical instability ... the step h = 0.00208 s is too large for this model: use a smaller
step", exit 2, the verdict lost, at every step and with both methods: the speed band
(stabctl/dynamics/integrator.py:386-389) judges separated machines, the message
(stabctl/dynamics/driver.py:1458-1466, trapezoid.py likewise) blames the step.
The grid of steps (BA01-BA48, BA71-BA94) and cct --step (BA61-BA68): ok (each run either
within 5 % of 1/480 s, warned, or refused naming the step).
Source: issue 54 item 6 ("the trapezoid's step bounded by accuracy (or a warning)"); the
developers' guide: nothing changed silently, no silent wrong result.
"""

# ruff: noqa
import json
import os
import re
from pathlib import Path

from _probe_kit import Kit, tail

KIT = Kit("probes_ba56.", line="{pid:<6} {state:<5} {why}", timed=True, xdg=False)
CLONE, ENV, WD = KIT.clone, KIT.env, KIT.wd
run, rec, probe = KIT.cli, KIT.rec, KIT.probe
ANGLE_REL = 0.05  # a largest angle off by more than 5 %
REF_H = 1 / 480
PSSE = Path(CLONE) / "tests" / "data" / "psse"

FAULTS = {
    "kundur": ["--fault", "3", "--far-bus", "101"],
    "miniwecc": ["--fault", "83", "--far-bus", "33"],
}
_REF = {}


def five():
    p = WD / "five.json"
    if not p.exists():
        rc, out, err = run(
            ["import-psse", PSSE / "five_bus_v33.raw", PSSE / "five_bus.dyr", "-o", p], 300
        )
        if rc != 0:
            raise RuntimeError(f"import-psse rc {rc}: {tail(err)}")
    return str(p)


ANDES_CASES = {
    "kundur_reg": ("kundur/kundur_reg.xlsx", ["--fault", "8"]),
    "ieee14_solar": ("ieee14/ieee14_solar.xlsx", ["--bus-fault", "4:0:0.05", "1", "1.1"]),
    "ieee14_wt3": ("ieee14/ieee14_wt3.xlsx", ["--fault", "4"]),
}


def andes_case(name):
    """An ANDES converter case imported (--skip-unsupported); run with --no-q-limits."""
    p = WD / f"{name}.json"
    if not p.exists():
        import subprocess, sys

        xlsx = subprocess.run(
            [
                sys.executable,
                "-c",
                f"import andes; print(andes.get_case('{ANDES_CASES[name][0]}'))",
            ],
            capture_output=True,
            text=True,
            env=ENV,
        ).stdout.strip()
        rc, out, err = run(["import-andes", xlsx, "-o", p, "--skip-unsupported"], 600)
        if rc != 0:
            raise RuntimeError(f"import-andes rc {rc}: {tail(err)}")
    return [str(p), *ANDES_CASES[name][1], "--no-q-limits"]


def case_args(case):
    if case in ANDES_CASES:
        return andes_case(case)
    if case == "five":
        return [five(), "--fault", "2", "--far-bus", "1"]
    return [case, *FAULTS[case]]


def sim(case, extra, h, method="heun", timeout=900):
    """(rc, json or None, stderr) of simulate --json."""
    args = ["simulate", *case_args(case), *extra, "--json", "--method", method]
    if h is not None:
        args += ["--step", h]
    rc, out, err = run(args, timeout)
    try:
        d = json.loads(out)
    except ValueError:
        d = None
    return rc, d, err


def ref(case, extra, method="heun"):
    key = (case, tuple(map(str, extra)), method)
    if key not in _REF:
        rc, d, err = sim(case, extra, REF_H, method)
        if rc != 0 or d is None:
            raise RuntimeError(f"reference rc {rc}: {tail(err)}")
        _REF[key] = d
    return _REF[key]


def warned(d, err):
    return bool(re.search(r"warning", err, re.I)) or bool(d and d.get("warnings"))


def _failed(tag, rc, err):
    """(ok, why) of a run that did not end with exit 0: a refusal naming the step is ok; a
    traceback or any other exit is SHORT."""
    if "Traceback" in err:
        return False, f"{tag}: traceback rc {rc}: {tail(err, 200)}"
    if rc == 2 and re.search(r"step", err):
        return True, f"{tag}: refused: {tail(err, 140)}"
    return False, f"{tag}: rc {rc}: {tail(err, 200)}"


def compare(case, extra, h, method="heun", conventions=None):
    x = list(extra) + (["--conventions", conventions] if conventions else [])
    r = ref(case, x, method)
    rc, d, err = sim(case, x, h, method)
    tag = f"{case} {' '.join(map(str, extra))} {method} h={h:g}"
    if rc != 0:
        return _failed(tag, rc, err)
    w = warned(d, err)
    a, b = d["max_angle_from_coi_rad"], r["max_angle_from_coi_rad"]
    same = d["verdict"] == r["verdict"]
    rel = abs(a - b) / abs(b) if b else 0.0
    fig = (
        f"{d['verdict']} max angle {a:.4f} vs ref({REF_H:.5f}) {r['verdict']} {b:.4f} "
        f"({rel:.1%}); warned={w}"
    )
    if w:
        return True, f"{tag}: {fig}"
    if not same:
        return False, f"{tag}: verdict differs with no warning: {fig}"
    if d["verdict"] == "stable" and rel > ANGLE_REL:
        return False, f"{tag}: angle off with no warning: {fig}"
    return True, f"{tag}: {fig}"


STEPS = [0.01, 1 / 60, 0.02, 0.05, 0.1, 0.25]
GRID = []
n = 0
for case, extra in [
    ("kundur", ["--clear-cycles", "6"]),
    ("kundur", ["--clear-cycles", "9"]),
    ("miniwecc", ["--clear-cycles", "6"]),
    ("five", ["--clear-cycles", "6"]),
]:
    for method in ("heun", "trapezoid"):
        for h in STEPS:
            n += 1
            GRID.append((f"BA{n:02d}", case, extra, h, method))

for _pid, _case, _extra, _h, _m in GRID:
    probe(_pid)(lambda c=_case, e=_extra, h=_h, m=_m: compare(c, e, h, m))

n = 70
for case in ANDES_CASES:
    for method in ("heun", "trapezoid"):
        for h in (0.01, 1 / 60, 0.02, 0.05):
            n += 1
            probe(f"BA{n:02d}")(
                lambda c=case, h=h, m=method: compare(
                    c, [] if "--bus-fault" in ANDES_CASES[c][1] else ["--clear-cycles", "6"], h, m
                )
            )

# ---------------------------------------------------------------- cct --step
_CREF = {}


def cct(case, h, extra=()):
    args = ["cct", *case_args(case), *extra, "--json"]
    if h is not None:
        args += ["--step", h]
    rc, out, err = run(args, 1500)
    try:
        d = json.loads(out)
    except ValueError:
        d = None
    return rc, d, err


def cct_compare(case, h, tol=0.005):
    """A CCT at step h against the CCT at 1/480 s: off by more than its own half-step
    error bar + tol (s) and the reference's bar, with no warning: SHORT."""
    if case not in _CREF:
        rc, d, err = cct(case, REF_H)
        if rc != 0 or d is None:
            raise RuntimeError(f"reference cct rc {rc}: {tail(err)}")
        _CREF[case] = d
    r = _CREF[case]
    rc, d, err = cct(case, h)
    tag = f"cct {case} h={h:g}"
    if rc != 0:
        return _failed(tag, rc, err)
    w = warned(None, err)
    c, c0 = d.get("cct_s"), r.get("cct_s")
    e, e0 = d.get("numerical_error_s") or 0, r.get("numerical_error_s") or 0
    fig = f"CCT {c} (+-{e}, half-step {d.get('cct_half_step_s')}) vs ref {c0} (+-{e0}); warned={w}"
    if c is None or c0 is None:
        return True, f"{tag}: {fig}"
    off = abs(c - c0)
    if not w and off > e + e0 + tol:
        return False, f"{tag}: CCT off by {off * 1e3:.1f} ms beyond its error bar: {fig}"
    return True, f"{tag}: {fig} (off {off * 1e3:.1f} ms)"


n = 60
for case in ("kundur", "five"):
    for h in (0.01, 1 / 60, 0.02, 0.05):
        n += 1
        probe(f"BA{n:02d}")(lambda c=case, h=h: cct_compare(c, h))


# ---------------------------------------------------------------- heun growth, damped a little
def gencls(d):
    """The PSS/E five-bus case with its three machines GENCLS (H 5, 0.5, 3 s), damping D."""
    p = WD / f"cls_{d:g}.json"
    if not p.exists():
        dyr = WD / f"cls_{d:g}.dyr"
        dyr.write_text(
            f"    1 'GENCLS' 1   5.0  {d} /\n    3 'GENCLS' 1   0.5  {d} /\n"
            f"    3 'GENCLS' '2' 3.0  {d} /\n"
        )
        rc, out, err = run(["import-psse", PSSE / "five_bus_v33.raw", dyr, "-o", p], 300)
        if rc != 0:
            raise RuntimeError(f"import-psse rc {rc}: {tail(err)}")
    return str(p)


def gencls_default_step(d):
    """heun at the case's default step (10 ms: half a cycle at 50 Hz), a 50 ms fault
    through j0.2 pu, 20 s: the largest angle against 1/480 s.  grid.check_heun_growth
    warns for D = 0 (a factor 5.2); a damping a few hundredths (GENCLS D, machine base)
    hides nothing of Heun's h^3 growth but switches the warning off."""
    c = gencls(d)
    base = ["simulate", c, "--bus-fault", "2:0:0.2", "1", "1.05", "--tf", "20", "--json"]
    rc, out, err = run(base, 300)
    rc0, out0, err0 = run([*base, "--step", REF_H], 300)
    if rc != 0 or rc0 != 0:
        return False, f"rc {rc}/{rc0}: {tail(err + err0, 200)}"
    dd, r = json.loads(out), json.loads(out0)
    w = warned(
        dd,
        re.sub(
            r"warning: the power flow differs[^\n]*|warning: [^\n]*held at their RAW[^\n]*", "", err
        ),
    )
    a, b = dd["max_angle_from_coi_rad"], r["max_angle_from_coi_rad"]
    rel = abs(a - b) / abs(b)
    fig = (
        f"GENCLS D={d:g}, heun default h={dd['step_s']:g}: {dd['verdict']} {a:.4f} rad vs "
        f"{b:.4f} at {REF_H:.5f} s ({rel:.0%}); warned={w}"
    )
    if not w and rel > ANGLE_REL:
        return (
            False,
            "largest angle off with no warning (grid.py:247 undamped only if D0 == D1 == 0): "
            + fig,
        )
    return True, fig


for _pid, _d in (("BA95", 0.01), ("BA96", 0.05), ("BA97", 0.1), ("BA98", 0.5)):
    probe(_pid)(lambda d=_d: gencls_default_step(d))


def separated_then_overspeed(method):
    """The PSS/E five-bus case (GENROU, no governor), its line fault cleared in 15 cycles,
    --tf 30, at 1/480 s: the machines separate at 1.47 s (--stop-at-separation says so);
    without it the run goes on until a separated machine passes 1.5 pu speed, and the
    command then fails 'numerical instability ... the step h is too large for this
    model: use a smaller step' (exit 2, the verdict lost), whatever the step."""
    base = [
        "simulate",
        five(),
        "--fault",
        "2",
        "--far-bus",
        "1",
        "--clear-cycles",
        "15",
        "--tf",
        "30",
        "--method",
        method,
        "--step",
        REF_H,
    ]
    rc, out, err = run(base, 600)
    rc1, out1, _ = run([*base, "--stop-at-separation"], 600)
    sep = re.search(r"loss of synchronism at t = [\d.]+ s", out1)
    if rc == 0:
        return True, f"exit 0: {tail(out, 160)}"
    if sep and re.search(r"step .* too large|smaller step", err):
        return False, (
            f"{method} h={REF_H:.5f}: rc {rc} '{tail(err, 170)}' though the run separated "
            f"first ({sep.group(0)} with --stop-at-separation): a physical runaway blamed on the step"
        )
    return rc == 2 and "Traceback" not in err, f"rc {rc}: {tail(err, 200)}"


probe("BA99")(lambda: separated_then_overspeed("heun"))
probe("BA100")(lambda: separated_then_overspeed("trapezoid"))


if __name__ == "__main__":
    KIT.main()
