#!/usr/bin/env python
"""Thirty-fourth reliability round (round 47, part AD): PSS/E RAW + DYR import fidelity for
the classic models (machines, exciters, governors, stabilisers; no converters), variants
the earlier probe scripts do not try: saturation points PSS/E can fit but stabctl may drop
(S(1.0) = 0 with S(1.2) > 0, for GENROU, GENSAL and IEEET1), X''d > X'd, Xl above X'd,
H = 0 on a machine that is not the infinite bus, T'do = 0, SEXS TB = 0 (PSS/E: no
lead-lag), SEXS TE = 0, limits swapped (IEEET1 VRMAX < VRMIN, TGOV1 VMAX < VMIN, HYGOV
GMAX < GMIN, ESST1A VRMAX < VRMIN), IEEET1 KF > 0 with TF = 0, two exciters of other models
for one machine, a PSS without an exciter, an exciter and a governor on a GENCLS, an
unsupported machine (GENTPJ1); RAW records: QT < QB, PT < PB, a switched shunt with an
unknown MODSW, transformers with CW / CZ / CM codes 2 and 3 (their impedance, ratio and
magnetising admittance against the PSS/E conversions), a generator at an IDE 4 bus,
negative loads, a case whose power flow does not converge, a v33 file headed 35, a 30 deg
phase shifter whose far bus is not yet solved, MBASE 0, SBASE1-2 0, a transformer to
itself, ZSORCE X other than X''d; the same unit stated on MBASE 100 and on MBASE 200.

    python reliability_probes_34.py [ID ...]

CLONE (default: this repository) is the package under test, run as `python -m stabctl`;
NUMBA_CACHE_DIR the caller's (warm it with `python -m stabctl compile`).  Prints per
probe: id, ok/SHORT, reason; exits 1 if any is SHORT.  Every command has a timeout; all
work in a temporary directory (removed at the end unless KEEP=1).

The round found short: a zero first saturation point silently voiding the second
(GENROU, GENSAL, IEEET1: AD01, AD02, AD08), an exciter on a GENCLS imported and run with
an efd that acts on nothing (AD17), a radial 30 deg phase shifter refused as "does not
converge" from a RAW angle and a flat start that ignore the shift (AD33), ZSORCE X other
than X''d dropped without a word (AD44); all fixed (the ignored values named, the exciter
left out by name, the flat start with the phase shifts).  About 3 minutes with a warm
kernel cache.

The contract (README: "PSS/E cases ... are read as PSS/E reads them"; import-psse --help:
"Unsupported records are named as FILE:LINE RECORD with the reason"; issue 54: nothing
changed or defaulted silently): a record PSS/E would refuse or stabctl cannot represent is
refused (exit 2, `error:` naming file:line, model, bus, id and field, nothing written);
one read otherwise than written is imported with the change named; never a run with a
silently dropped value or a silently different model.  Where a value is accepted without
a word, the probe runs the case and checks the value changes the run as PSS/E's equations
say (or that it has no effect where PSS/E gives it none).
"""

# ruff: noqa: E501, RUF059, SIM115, RUF021 - a tester's script, kept as written

import csv
import json
import os
import re

from _probe_kit import INHERIT, Kit

KIT = Kit("probes_ad47_", path=False, prefixes=False)
CLONE, ENV, WD, RESULTS, PROBES = KIT.clone, KIT.env, KIT.wd, KIT.results, KIT.probes
rec, probe = KIT.rec, KIT.probe
RUNS = os.path.join(CLONE, "tests", "data", "psse_runs")
RAW = open(os.path.join(RUNS, "GENROU", "ThreeBusMulti.raw")).read()
GR = "8.0 0.03 0.4 0.05 6.175 0.05 1.8 1.7 0.3 0.55 0.25 0.2"  # GENROU up to Xl
INF = "    101 'GENCLS' 1 0.0 0.0 /\n"
GENROU = f"    102 'GENROU' 1 {GR} 0.1 0.8 /\n"
GENSAL = "    102 'GENSAL' 1 5.0 0.05 0.2 5.0 0.0 1.0 0.75 0.4 0.25 0.1 {s10} {s12} /\n"
SEXS = "    102 'SEXS' 1 0.4 5.0 20.0 1.0 -50.0 50.0 /\n"
# IEEET1: TR KA TA VRMAX VRMIN KE TE KF TF SWITCH E1 SE(E1) E2 SE(E2)
IEEET1 = (
    "    102 'IEEET1' 1 0.0 50.0 0.04 {vrmax} {vrmin} 1.0 0.8 {kf} {tf} 0 2.8 {se1} 3.73 {se2} /\n"
)
TGOV1 = "    102 'TGOV1' 1 0.05 0.2 {vmax} {vmin} 0.3 0.8 0 /\n"
HYGOV = "    102 'HYGOV' 1 0.05 0.075 12.0 0.5 20.5 0.1 {gmax} {gmin} 15.0 1.5 0.0 0.08 /\n"


def w(name, text):
    p = os.path.join(WD, name)
    with open(p, "w") as f:
        f.write(text)
    return p


def run(args, timeout=300):
    """(rc, stdout, stderr); the caller's stdin, nothing kept of a run out of time."""
    return KIT.cli(args, timeout, stdin=INHERIT, partial=False)


def imp(name, dyr, raw=RAW, extra=()):
    """import-psse of RAW text and DYR text (INF prepended); (rc, stdout+stderr, json path)."""
    r = w(name + ".raw", raw)
    args = ["import-psse", r]
    if dyr is not None:
        args.append(w(name + ".dyr", INF + dyr))
    out = os.path.join(WD, name + ".json")
    rc, o, e = run([*args, "-o", out, *extra])
    return rc, o + e, out


def trace(case, cols=("speed",), extra=()):
    """simulate the line trip 101-102 at 1 s to 4 s; the CSV rows' chosen columns."""
    out = case[:-5] + ".csv"
    rc, o, e = run(
        ["simulate", case, "--trip", 101, 102, "--t-trip", 1.0, "--tf", 4.0, "--out", out, *extra]
    )
    if rc != 0:
        raise RuntimeError(f"simulate {os.path.basename(case)}: rc {rc}: {(o + e).strip()[-250:]}")
    with open(out) as f:
        rows = list(csv.reader(f))
    head = rows[0]
    keep = [i for i, h in enumerate(head) if any(c in h for c in cols)]
    return [[float(r[i]) for i in keep] for r in rows[1:]]


def maxdiff(a, b):
    return max(abs(x - y) for ra, rb in zip(a, b) for x, y in zip(ra, rb))


def named(text, *pats):
    return all(re.search(p, text, re.I) for p in pats)


def last(text):
    t = [ln for ln in text.strip().splitlines() if ln.strip()]
    return t[-1][:260] if t else "(nothing)"


def refused_or_named(pid, dyr, pats, raw=RAW, effect=None):
    """ok when refused (rc 2, `error:` matching every pattern, nothing written) or imported
    with a warning matching them; accepted silently -> SHORT (with effect(): whether the
    run shows the value)."""
    rc, text, out = imp(pid, dyr, raw)
    if rc == 2:
        if "Traceback" in text:
            return False, f"rc 2 with a traceback: {last(text)}"
        if os.path.exists(out):
            return False, f"refused but {os.path.basename(out)} written"
        if named(text, *pats):
            return True, f"refused: {last(text)}"
        return False, f"refused without naming {pats}: {last(text)}"
    if rc == 0:
        warn = [
            ln
            for ln in text.splitlines()
            if re.search(r"warn|left out|read as|changed|ignored|held", ln, re.I)
        ]
        hit = [ln for ln in warn if named(ln, *pats[1:])] if warn else []
        if hit:
            return True, f"imported, named: {hit[0][:200]}"
        more = effect(out) if effect else ""
        return False, f"imported without a word (rc 0){more}: {last(text)}"
    return False, f"rc {rc}: {last(text)}"


# ------------------------------------------------------------------ DYR: machines


@probe("AD01")
def genrou_s10_zero():
    """GENROU S(1.0) = 0, S(1.2) = 0.5: PSS/E's quadratic function reads a zero S(1.0) as
    no saturation (OpenIPSL's PSS/E-verified SE(); PowerSystems.jl warns "Ignoring
    saturation"), so the run may be unsaturated -- but the file's S(1.2) = 0.5 is then a
    value without effect and must be named (or refused), not dropped without a word."""
    rc, text, out = imp("AD01", f"    102 'GENROU' 1 {GR} 0.0 0.5 /\n" + SEXS)
    if rc == 2:
        return named(text, r"S\(1\.[02]\)", r"102"), f"refused: {last(text)}"
    if rc != 0:
        return False, f"rc {rc}: {last(text)}"
    rc0, t0, out0 = imp("AD01n", f"    102 'GENROU' 1 {GR} 0.0 0.0 /\n" + SEXS)
    d = maxdiff(trace(out, ("efd",)), trace(out0, ("efd",)))
    word = re.search(r"S\(1\.2\)|saturation", text, re.I)
    if d < 1e-9 and not word:
        return (
            False,
            f"imported without a word and run identical to S(1.2) = 0 (max |dEfd| {d:.1e}): S(1.2) = 0.5 dropped silently",
        )
    return True, f"S(1.2) acts (max |dEfd| {d:.2e}) or named"


@probe("AD02")
def gensal_s10_zero():
    """GENSAL S(1.0) = 0, S(1.2) = 0.5: as AD01."""
    rc, text, out = imp("AD02", GENSAL.format(s10=0.0, s12=0.5) + SEXS)
    if rc == 2:
        return named(text, r"S\(1\.[02]\)", r"102"), f"refused: {last(text)}"
    if rc != 0:
        return False, f"rc {rc}: {last(text)}"
    rc0, t0, out0 = imp("AD02n", GENSAL.format(s10=0.0, s12=0.0) + SEXS)
    d = maxdiff(trace(out, ("efd",)), trace(out0, ("efd",)))
    word = re.search(r"S\(1\.2\)|saturation", text, re.I)
    if d < 1e-9 and not word:
        return (
            False,
            f"imported without a word and run identical to S(1.2) = 0 (max |dEfd| {d:.1e}): S(1.2) = 0.5 dropped silently",
        )
    return True, f"S(1.2) acts (max |dEfd| {d:.2e}) or named"


@probe("AD03")
def genrou_xdpp_above_xdp():
    """GENROU X''d = 0.35 > X'd = 0.3 (and X''q = X''d as PSS/E requires): refused naming it."""
    gr = "8.0 0.03 0.4 0.05 6.175 0.05 1.8 1.7 0.3 0.55 0.35 0.2 0.1 0.8"
    return refused_or_named(
        "AD03", f"    102 'GENROU' 1 {gr} /\n", [r"GENROU", r"102", r"X''?d|Xdpp|X.?d"]
    )


@probe("AD04")
def genrou_xl_above_xdp():
    """GENROU Xl = 0.35 above X'd = 0.3 (and X'q = 0.55 > Xl): refused naming Xl."""
    gr = "8.0 0.03 0.4 0.05 6.175 0.05 1.8 1.7 0.3 0.55 0.25 0.35 0.1 0.8"
    return refused_or_named("AD04", f"    102 'GENROU' 1 {gr} /\n", [r"GENROU", r"102", r"Xl"])


@probe("AD05")
def genrou_h_zero():
    """GENROU H = 0 at bus 102, which is not the swing bus: PSS/E's H = 0 means an infinite
    bus only for a GENCLS; refused naming H."""
    gr = "8.0 0.03 0.4 0.05 0.0 0.05 1.8 1.7 0.3 0.55 0.25 0.2 0.1 0.8"
    return refused_or_named("AD05", f"    102 'GENROU' 1 {gr} /\n", [r"GENROU", r"102", r"\bH\b"])


@probe("AD06")
def genrou_tdop_zero():
    """GENROU T'do = 0: no transient circuit; refused naming T'do."""
    gr = "0.0 0.03 0.4 0.05 6.175 0.05 1.8 1.7 0.3 0.55 0.25 0.2 0.1 0.8"
    return refused_or_named(
        "AD06", f"    102 'GENROU' 1 {gr} /\n", [r"GENROU", r"102", r"T'?d0|T'do|Tdo|Td0"]
    )


@probe("AD07")
def gentpj1_unsupported():
    """GENTPJ1 (not in stabctl's models): refused naming file:line, the model and bus."""
    rc, text, out = imp("AD07", f"    102 'GENTPJ1' 1 {GR} 0.1 0.8 0.0 /\n")
    ok = (
        rc == 2
        and named(text, r"AD07\.dyr:2", r"GENTPJ1")
        and not os.path.exists(out)
        and "Traceback" not in text
    )
    return ok, f"rc {rc}: {last(text)}"


# ------------------------------------------------------------------ DYR: exciters


@probe("AD08")
def ieeet1_se1_zero():
    """IEEET1 SE(E1) = 0, SE(E2) = 0.5: PSS/E's quadratic fit through (2.8, 0), (3.73,
    0.5) exists (A = 2.8); refused, named or acting -- never dropped silently."""
    rc, text, out = imp(
        "AD08", GENROU + IEEET1.format(vrmax=5.0, vrmin=-5.0, kf=0.05, tf=1.0, se1=0.0, se2=0.5)
    )
    if rc == 2:
        return named(text, r"IEEET1", r"102", r"SE|E1|E2|satur"), f"refused: {last(text)}"
    if rc != 0:
        return False, f"rc {rc}: {last(text)}"
    rc0, t0, out0 = imp(
        "AD08n", GENROU + IEEET1.format(vrmax=5.0, vrmin=-5.0, kf=0.05, tf=1.0, se1=0.0, se2=0.0)
    )
    d = maxdiff(trace(out, ("efd",)), trace(out0, ("efd",)))
    word = re.search(r"SE|saturation", text)
    if d < 1e-9 and not word:
        return (
            False,
            f"imported without a word, run identical to SE(E2) = 0 (max |dEfd| {d:.1e}): SE(E2) = 0.5 dropped silently",
        )
    return True, f"SE(E2) acts (max |dEfd| {d:.2e}) or named"


@probe("AD09")
def ieeet1_vr_swapped():
    """IEEET1 VRMAX = -5 < VRMIN = 5: refused naming VRMAX."""
    return refused_or_named(
        "AD09",
        GENROU + IEEET1.format(vrmax=-5.0, vrmin=5.0, kf=0.05, tf=1.0, se1=0.2, se2=0.5),
        [r"IEEET1", r"102", r"VRMAX|VRMIN"],
    )


@probe("AD10")
def ieeet1_tf_zero():
    """IEEET1 KF = 0.05 with TF = 0 (the rate feedback sKF/(1+sTF) a pure derivative):
    PSS/E needs TF > 0; refused naming TF."""
    return refused_or_named(
        "AD10",
        GENROU + IEEET1.format(vrmax=5.0, vrmin=-5.0, kf=0.05, tf=0.0, se1=0.2, se2=0.5),
        [r"IEEET1", r"102", r"TF"],
    )


@probe("AD11")
def ieeet1_se2_below_se1():
    """IEEET1 SE(E2) = 0.1 < SE(E1) = 0.3: saturation that falls with the voltage."""
    return refused_or_named(
        "AD11",
        GENROU + IEEET1.format(vrmax=5.0, vrmin=-5.0, kf=0.05, tf=1.0, se1=0.3, se2=0.1),
        [r"IEEET1", r"102", r"SE|satur"],
    )


@probe("AD12")
def sexs_tb_zero():
    """SEXS TB = 0 (PSS/E: TA = TA/TB * TB = 0, no lead-lag): accepted, TA/TB without
    effect (the run with TA/TB = 0.4 equals that with TA/TB = 1), or named / refused."""
    s = "    102 'SEXS' 1 {r} 0.0 20.0 1.0 -50.0 50.0 /\n"
    rc, text, out = imp("AD12", GENROU + s.format(r=0.4))
    if rc == 2:
        return named(text, r"SEXS", r"102", r"TB"), f"refused: {last(text)}"
    if rc != 0:
        return False, f"rc {rc}: {last(text)}"
    rc1, t1, out1 = imp("AD12n", GENROU + s.format(r=1.0))
    d = maxdiff(trace(out, ("efd",)), trace(out1, ("efd",)))
    word = re.search(r"\bTB\b", text)
    if d > 1e-6 and not word:
        return (
            False,
            f"TB = 0 accepted, but TA/TB = 0.4 changes the run against 1.0 (max |dEfd| {d:.3g}) without a word: not PSS/E's bypass",
        )
    return True, f"accepted; TA/TB without effect (max |dEfd| {d:.1e})" + (
        " and named" if word else ""
    )


@probe("AD13")
def sexs_te_zero():
    """SEXS TE = 0 (PSS/E: the exciter lag bypassed): accepted and run (efd follows K times
    the lead-lag, within EMIN/EMAX), or refused naming TE."""
    rc, text, out = imp("AD13", GENROU + "    102 'SEXS' 1 0.4 5.0 20.0 0.0 -50.0 50.0 /\n")
    if rc == 2:
        return named(text, r"SEXS", r"102", r"TE"), f"refused: {last(text)}"
    if rc != 0:
        return False, f"rc {rc}: {last(text)}"
    tr = trace(out, ("efd",))
    return all(
        abs(v) < 60 for r in tr for v in r
    ), f"accepted, run: efd in [{min(min(r) for r in tr):.3f}, {max(max(r) for r in tr):.3f}]"


@probe("AD14")
def esst1a_vr_swapped():
    """ESST1A VRMAX = -5 < VRMIN = 5 (PSS/E field order UEL VOS TR VIMAX VIMIN TC TB TC1 TB1
    KA TA VAMAX VAMIN VRMAX VRMIN KC KF TF KLR ILR): refused naming VRMAX."""
    st = "    102 'ESST1A' 1 1 1 0.0 0.5 -0.5 1.0 10.0 0.0 0.0 200.0 0.02 6.0 -6.0 -5.0 5.0 0.05 0.0 1.0 0.0 0.0 /\n"
    return refused_or_named("AD14", GENROU + st, [r"ESST1A", r"102", r"VRMAX|VRMIN"])


@probe("AD15")
def two_exciter_models():
    """SEXS and IEEET1 for one machine (two exciters of other models): refused naming both
    records (PSS/E allows one exciter per machine)."""
    return refused_or_named(
        "AD15",
        GENROU + SEXS + IEEET1.format(vrmax=5.0, vrmin=-5.0, kf=0.05, tf=1.0, se1=0.2, se2=0.5),
        [r"102", r"SEXS|IEEET1|exciter"],
    )


@probe("AD16")
def pss_without_exciter():
    """IEEEST for a machine with no exciter: its output has nowhere to go; refused or named."""
    st = "    102 'IEEEST' 1 1 0 0 0 0 0 0 0 0.1 0.02 0 0 1.5 1.5 10 0.1 -0.1 0 0 /\n"
    return refused_or_named("AD16", GENROU + st, [r"IEEEST", r"102", r"exciter"])


@probe("AD17")
def exciter_on_gencls():
    """SEXS on a GENCLS (constant E' behind X'd, no field winding: an exciter cannot act):
    refused or named -- not imported, run with an efd channel that moves and acts on
    nothing, without a word."""
    g = "    102 'GENCLS' 1 6.0 0.0 /\n"
    rc, text, out = imp("AD17", g + SEXS)
    if rc == 2:
        return named(text, r"SEXS|GENCLS", r"102"), f"refused: {last(text)}"
    if rc != 0:
        return False, f"rc {rc}: {last(text)}"
    if re.search(r"SEXS", text):
        return True, "imported, SEXS named"
    rc0, t0, out0 = imp("AD17n", g)
    a, b = (
        trace(out, ("speed", "angle", "pelect", "efd")),
        trace(out0, ("speed", "angle", "pelect", "efd")),
    )
    # columns: speed x2, angle x2, pelect x2, efd x2 (G1, G2)
    d_mech = max(abs(x - y) for ra, rb in zip(a, b) for x, y in zip(ra[:6], rb[:6]))
    d_efd = max(abs(ra[7] - rb[7]) for ra, rb in zip(a, b))
    return False, (
        f"imported without a word (exciters: 1); the run's efd of G2 moves (up to {d_efd:.3f} pu from the run "
        f"without SEXS) while speeds, angles and powers are identical (max diff {d_mech:.1e}): the exciter acts on nothing"
    )


@probe("AD18")
def governor_on_gencls():
    """TGOV1 on a GENCLS: PSS/E's GENCLS takes PMECH, so the governor acts (the run with it
    differs from the one without) -- or it is refused / named; never dropped silently."""
    g = "    102 'GENCLS' 1 6.0 0.0 /\n"
    rc, text, out = imp("AD18", g + TGOV1.format(vmax=1.2, vmin=0.1))
    if rc == 2:
        return named(text, r"TGOV1|GENCLS", r"102"), f"refused: {last(text)}"
    if rc != 0:
        return False, f"rc {rc}: {last(text)}"
    rc0, t0, out0 = imp("AD18n", g)
    d = maxdiff(trace(out, ("speed",)), trace(out0, ("speed",)))
    word = re.search(r"TGOV1", text)
    if d < 1e-9 and not word:
        return (
            False,
            f"imported without a word, run identical to no governor (max |dspeed| {d:.1e})",
        )
    return True, f"governor acts (max |dspeed| {d:.2e})" + (" and named" if word else "")


# ------------------------------------------------------------------ DYR: governors


@probe("AD19")
def tgov1_v_swapped():
    """TGOV1 VMAX = 0.1 < VMIN = 1.2: refused naming VMAX."""
    return refused_or_named(
        "AD19", GENROU + TGOV1.format(vmax=0.1, vmin=1.2), [r"TGOV1", r"102", r"VMAX|VMIN"]
    )


@probe("AD20")
def hygov_g_swapped():
    """HYGOV GMAX = 0 < GMIN = 1: refused naming GMAX."""
    return refused_or_named(
        "AD20", GENROU + SEXS + HYGOV.format(gmax=0.0, gmin=1.0), [r"HYGOV", r"102", r"GMAX|GMIN"]
    )


# ------------------------------------------------------------------ RAW records


def raw_gen(**kw):
    """ThreeBusMulti with generator 102's fields replaced (v33 columns)."""
    cols = [
        "I",
        "ID",
        "PG",
        "QG",
        "QT",
        "QB",
        "VS",
        "IREG",
        "MBASE",
        "ZR",
        "ZX",
        "RT",
        "XT",
        "GTAP",
        "STAT",
        "RMPCT",
        "PT",
        "PB",
        "O1",
        "F1",
    ]
    lines = RAW.splitlines(keepends=True)
    for k, ln in enumerate(lines):
        if ln.lstrip().startswith("102,'1 ',"):
            f = [x.strip() for x in ln.split(",")]
            for name, v in kw.items():
                f[cols.index(name)] = str(v)
            lines[k] = "   " + ",".join(f) + "\n"
    return "".join(lines)


@probe("AD21")
def qt_below_qb():
    """Generator 102 QT = -100 < QB = 100 (swapped Q limits): refused or named, naming QT."""
    return refused_or_named(
        "AD21", GENROU, [r"102", r"QT|QB|Q limit"], raw=raw_gen(QT="-100.0", QB="100.0")
    )


@probe("AD22")
def pt_below_pb():
    """Generator 102 PT = 0 < PB = 318 (swapped P limits): refused or named."""
    return refused_or_named("AD22", GENROU, [r"102", r"PT|PB"], raw=raw_gen(PT="0.0", PB="318.0"))


def with_section(after, text):
    """RAW with `text` inserted before the line ' 0 /End of <after> data'."""
    out = []
    for ln in RAW.splitlines(keepends=True):
        if ln.strip().startswith(f"0 /End of {after} data"):
            out.append(text)
        out.append(ln)
    return "".join(out)


@probe("AD23")
def swshunt_modsw_unknown():
    """A switched shunt at 103 with MODSW = 9 (no such mode): refused naming MODSW."""
    sh = "   103,9,0,1,1.10000,0.90000,     0,100.0,'            ',  50.00,   1,  50.00\n"
    return refused_or_named(
        "AD23", GENROU, [r"103", r"MODSW"], raw=with_section("Switched shunt", sh)
    )


def xf_raw(cw, cz, cm, r12, x12, sbase12, windv1, mag1=0.0, mag2=0.0, nomv1=0.0):
    windv2 = 13.8 if cw == 2 else 1.0  # kV with CW = 2, else pu
    """ThreeBusMulti with a 4th bus 104 (13.8 kV) fed by a two-winding transformer 103-104
    and a 10 MW load at 104."""
    raw = RAW.replace(
        " 0 /End of Bus data",
        "   104,'BUS 4', 13.8000,1,   1,   1,   1,1.00000,  -9.0000,1.10000,0.90000,1.10000,0.90000\n 0 /End of Bus data",
    ).replace(
        " 0 /End of Load data",
        "   104,'1 ',1,   1,   1,    10.000,     2.000,     0.000,     0.000,     0.000,     0.000,   1,1,0\n 0 /End of Load data",
    )
    xf = (
        f"   103,   104,     0,'1 ',{cw},{cz},{cm}, {mag1}, {mag2},2,'            ',1,   1,1.0000\n"
        f" {r12}, {x12}, {sbase12}\n"
        f"{windv1}, {nomv1},   0.000,   100.00,   100.00,   100.00, 0,      0, 1.10000, 0.90000, 1.10000, 0.90000,  33, 0, 0.00000, 0.00000,  0.000\n"
        f"{windv2},   0.000\n"
    )
    return raw.replace(" 0 /End of Transformer data", xf + " 0 /End of Transformer data")


def branch_row(out, i=103, j=104):
    d = json.load(open(out))
    t = d["tables"]["branches"]
    c = t["columns"]
    for r in t["rows"]:
        if {int(r[0]), int(r[1])} == {i, j}:
            return dict(zip(c, r))
    return None


def xf_probe(pid, want, **kw):
    rc, text, out = imp(pid, GENROU, raw=xf_raw(**kw))
    if rc != 0:
        return False, f"rc {rc}: {last(text)}"
    b = branch_row(out)
    if b is None:
        return False, "no branch 103-104 in the case"
    bad = {
        k: (b.get(k), v)
        for k, v in want.items()
        if b.get(k) is None or abs(float(b[k]) - v) > 1e-6 * max(1, abs(v))
    }
    got = ", ".join(f"{k} {b.get(k)}" for k in want)
    return not bad, (
        "as PSS/E: " + got
    ) if not bad else f"read otherwise than PSS/E, without a word: {bad} (got, PSS/E)"


@probe("AD24")
def xf_cz2():
    """CZ = 2: R, X on the winding base SBASE1-2 = 50 MVA -> system base x 100/50."""
    return xf_probe(
        "AD24",
        {"r": 0.004, "x": 0.16},
        cw=1,
        cz=2,
        cm=1,
        r12=0.002,
        x12=0.08,
        sbase12=50.0,
        windv1=1.0,
    )


@probe("AD25")
def xf_cz3():
    """CZ = 3: R12 the load loss in W (250 kW on 50 MVA: R = 0.005 pu winding base), X12 |Z|
    (0.08) -> R 0.01, X sqrt(0.08^2 - 0.005^2) * 2 on 100 MVA."""
    x = (0.08**2 - 0.005**2) ** 0.5 * 2
    return xf_probe(
        "AD25",
        {"r": 0.01, "x": x},
        cw=1,
        cz=3,
        cm=1,
        r12=250000.0,
        x12=0.08,
        sbase12=50.0,
        windv1=1.0,
    )


@probe("AD26")
def xf_cw2():
    """CW = 2: WINDV1 in kV (144.9 kV on the 138 kV bus -> ratio 1.05)."""
    return xf_probe(
        "AD26", {"tap": 1.05}, cw=2, cz=1, cm=1, r12=0.0, x12=0.08, sbase12=100.0, windv1=144.9
    )


@probe("AD27")
def xf_cw3():
    """CW = 3: WINDV1 in pu of NOMV1 (1.05 of 131.4 kV on the 138 kV bus -> 1.05 x 131.4/138)."""
    return xf_probe(
        "AD27",
        {"tap": 1.05 * 131.4 / 138.0},
        cw=3,
        cz=1,
        cm=1,
        r12=0.0,
        x12=0.08,
        sbase12=100.0,
        windv1=1.05,
        nomv1=131.4,
    )


@probe("AD28")
def xf_cm2():
    """CM = 2: MAG1 the no-load loss in W (100 kW), MAG2 the exciting current in pu of
    SBASE1-2 (0.01 on 50 MVA): G = 1e5/1e8 = 0.001, B = -sqrt((0.01*50/100)^2 - G^2) on
    the system base, at the winding-1 bus."""
    rc, text, out = imp(
        "AD28",
        GENROU,
        raw=xf_raw(
            cw=1, cz=1, cm=2, r12=0.0, x12=0.08, sbase12=50.0, windv1=1.0, mag1=100000.0, mag2=0.01
        ),
    )
    if rc == 2:
        ok = named(text, r"AD28\.raw:\d+", r"103-104", r"CM 2") and not os.path.exists(out)
        return ok, f"refused as unsupported (a limitation, named): {last(text)[-120:]}"
    if rc != 0:
        return False, f"rc {rc}: {last(text)}"
    b = branch_row(out)
    g = 0.001
    bb = -(((0.005) ** 2 - g**2) ** 0.5)
    got = (b.get("g_from"), b.get("b_from"), b.get("g_to"), b.get("b_to"))
    ok = (
        abs(got[0] - g) < 1e-7
        and abs(got[1] - bb) < 1e-7
        or abs(got[2] - g) < 1e-7
        and abs(got[3] - bb) < 1e-7
    )
    return ok, f"g/b at the ends {got}; PSS/E G {g}, B {bb:.6f}"


@probe("AD29")
def gen_at_ide4_bus():
    """Bus 102 (its generator and GENROU record in service) given IDE 4: PSS/E leaves the
    bus, its generator and branches out; stabctl: left out and named, with its DYR record."""
    raw = RAW.replace("   102,'BUS 2', 138.0000,2,", "   102,'BUS 2', 138.0000,4,")
    rc, text, out = imp("AD29", GENROU + SEXS, raw=raw)
    if rc == 2:
        return named(text, r"102"), f"refused: {last(text)}"
    ok = rc == 0 and named(text, r"102.*(isolated|IDE 4)|(isolated|IDE 4).*102")
    return ok, f"rc {rc}: " + " | ".join(ln[:150] for ln in text.splitlines() if "102" in ln)[:300]


@probe("AD30")
def negative_load():
    """A load of -50 MW, -10 Mvar at bus 103 besides its 250 MW: read as written (net 200
    MW at 103, the power flow solving), not dropped nor its sign turned."""
    raw = RAW.replace(
        " 0 /End of Load data",
        "   103,'2 ',1,   1,   1,   -50.000,   -10.000,     0.000,     0.000,     0.000,     0.000,   1,1,0\n 0 /End of Load data",
    )
    rc, text, out = imp("AD30", GENROU, raw=raw)
    if rc != 0:
        return False, f"rc {rc}: {last(text)}"
    d = json.load(open(out))
    t = d["tables"]["buses"]
    row = dict(zip(t["columns"], next(r for r in t["rows"] if int(r[0]) == 103)))
    ok = abs(row["pload"] - 2.0) < 1e-9 and abs(row["qload"] - 0.2) < 1e-9
    return ok, f"bus 103 pload {row['pload']}, qload {row['qload']} (want 2.0, 0.2)"


@probe("AD31")
def pf_not_converging():
    """A load of 5000 MW at bus 103 (no power-flow solution): refused naming the power flow,
    the worst mismatch and its bus; nothing written."""
    raw = RAW.replace(
        "   103,'1 ',1,   1,   1,   250.000,    30.000,",
        "   103,'1 ',1,   1,   1,  5000.000,  3000.000,",
    )
    rc, text, out = imp("AD31", GENROU, raw=raw)
    ok = (
        rc == 2
        and named(text, r"power flow", r"bus 10[123]|10[123]")
        and not os.path.exists(out)
        and "Traceback" not in text
    )
    return ok, f"rc {rc}: {last(text)}"


@probe("AD32")
def v33_headed_35():
    """ThreeBusMulti's v33 records under a header saying REV 35 (v35 adds fields to loads and
    generators): read the same (v35's trailing fields optional) or refused naming the
    version -- never a generator or load read from the wrong columns."""
    raw = RAW.replace("0,   100.00, 33, 0, 0, 60.00", "0,   100.00, 35, 0, 0, 60.00", 1)
    rc, text, out = imp("AD32", GENROU, raw=raw)
    if rc == 2:
        return named(
            text, r"AD32\.raw:\d+", r"35|version|REV|field|column|system-wide"
        ), f"refused: {last(text)}"
    if rc != 0:
        return False, f"rc {rc}: {last(text)}"
    rc0, t0, out0 = imp("AD32n", GENROU)
    a, b = json.load(open(out))["tables"], json.load(open(out0))["tables"]
    same = all(a[k]["rows"] == b[k]["rows"] for k in ("buses", "branches", "machines"))
    return (
        same,
        "read as the v33 file" if same else "tables differ from the v33 reading without a word",
    )


@probe("AD33")
def phase_shifter_30_flat():
    """A 30 deg phase shifter (ANG1 = 30) feeding a radial 10 MW load at bus 104, whose RAW
    angle is not yet solved (104 at 103's angle, as a flat RAW gives): PSS/E's flat start
    sets angles to the transformers' phase shifts and solves it (the solution is 30 deg
    below); stabctl's import must solve it too (it does from 104 at -39 deg) or, refusing,
    not call a solvable case non-convergent."""
    base = xf_raw(cw=1, cz=1, cm=1, r12=0.0, x12=0.08, sbase12=100.0, windv1=1.0)
    raw = base.replace("1.0, 0.0,   0.000,   100.00", "1.0, 0.0,   30.000,   100.00").replace(
        "1.00000,  -9.0000", "1.00000,  -8.7697"
    )
    rc, text, out = imp("AD33", GENROU, raw=raw)
    good = base.replace("1.0, 0.0,   0.000,   100.00", "1.0, 0.0,   30.000,   100.00").replace(
        "1.00000,  -9.0000", "1.00000, -39.0000"
    )
    rc2, text2, out2 = imp("AD33s", GENROU, raw=good)
    if rc == 0:
        return True, "solved from the unsolved angle"
    return False, (
        f"rc {rc}: refused as not converging ({last(text)[:150]}...), though the same case with bus 104's "
        f"RAW angle at -39 deg imports (rc {rc2}): the flat start ignores the 30 deg phase shift"
    )


@probe("AD34")
def gensal_xdpp_above_xdp():
    """GENSAL X''d = 0.45 > X'd = 0.4: refused naming both."""
    return refused_or_named(
        "AD34",
        "    102 'GENSAL' 1 5.0 0.05 0.2 5.0 0.0 1.0 0.75 0.4 0.45 0.1 0.1 0.3 /\n",
        [r"GENSAL", r"102", r"X''?d|x\"d"],
    )


@probe("AD35")
def tgov1_t3_zero():
    """TGOV1 T2 = 1 s with T3 = 0 (a lead without its lag): refused naming T3."""
    return refused_or_named(
        "AD35",
        GENROU + "    102 'TGOV1' 1 0.05 0.2 1.2 0.1 1.0 0.0 0 /\n",
        [r"TGOV1", r"102", r"T3"],
    )


@probe("AD36")
def hygov_tw_zero():
    """HYGOV TW = 0 (no water column): refused naming TW, or run as PSS/E's algebraic turbine."""
    return refused_or_named(
        "AD36",
        GENROU
        + SEXS
        + "    102 'HYGOV' 1 0.05 0.075 12.0 0.5 20.5 0.1 1.0 0.0 0.0 1.5 0.0 0.08 /\n",
        [r"HYGOV", r"102", r"TW"],
    )


@probe("AD37")
def mbase_zero():
    """Generator 102 MBASE = 0 (its DYR data per unit on nothing): refused naming MBASE."""
    return refused_or_named("AD37", GENROU, [r"102", r"MBASE"], raw=raw_gen(MBASE="0.0"))


@probe("AD38")
def xf_sbase_zero():
    """CZ = 2 with SBASE1-2 = 0: refused naming SBASE1-2."""
    return refused_or_named(
        "AD38",
        GENROU,
        [r"103-104", r"SBASE"],
        raw=xf_raw(cw=1, cz=2, cm=1, r12=0.002, x12=0.08, sbase12=0.0, windv1=1.0),
    )


@probe("AD39")
def xf_to_itself():
    """A two-winding transformer from bus 104 to bus 104: refused naming the record."""
    raw = xf_raw(cw=1, cz=1, cm=1, r12=0.0, x12=0.08, sbase12=100.0, windv1=1.0).replace(
        "   103,   104,     0,'1 '", "   104,   104,     0,'1 '"
    )
    return refused_or_named("AD39", GENROU, [r"AD39\.raw:\d+", r"104.*itself|itself.*104"], raw=raw)


@probe("AD40")
def sexs_k_zero():
    """SEXS K = 0 (efd = K x error cannot start at the field voltage): refused naming K."""
    return refused_or_named(
        "AD40",
        GENROU + "    102 'SEXS' 1 0.4 5.0 0.0 1.0 -50.0 50.0 /\n",
        [r"SEXS", r"102", r"\bK\b"],
    )


@probe("AD41")
def ieeet1_ke_zero_steady():
    """IEEET1 KE = 0: PSS/E computes KE so that V_R starts at 0 (docs/pst_models.md 12);
    the run must start in equilibrium (efd and speed flat to 1e-6 before the trip at 1 s)."""
    rc, text, out = imp(
        "AD41",
        GENROU
        + "    102 'IEEET1' 1 0.0 50.0 0.04 5.0 -5.0 0.0 0.8 0.05 1.0 0 2.8 0.1 3.73 0.3 /\n",
    )
    if rc != 0:
        return rc == 2 and named(text, r"IEEET1", r"KE"), f"rc {rc}: {last(text)}"
    tr = trace(out, ("efd", "speed"))
    pre = tr[: int(len(tr) * 0.2)]  # 0 .. 0.8 s of 4 s
    drift = max(abs(r[i] - pre[0][i]) for r in pre for i in range(len(r)))
    return (
        drift < 1e-6,
        f"imported (KE computed as PSS/E); drift of efd and speed before the event {drift:.1e}",
    )


@probe("AD42")
def genrou_negative_d():
    """GENROU D = -2 (negative damping): refused naming D."""
    return refused_or_named(
        "AD42",
        "    102 'GENROU' 1 8.0 0.03 0.4 0.05 6.175 -2.0 1.8 1.7 0.3 0.55 0.25 0.2 0.1 0.8 /\n",
        [r"GENROU", r"102", r"\bD\b"],
    )


@probe("AD43")
def mbase_restated():
    """The same GENROU + SEXS + TGOV1 unit stated on MBASE 100 and on MBASE 200 (PSS/E: H,
    D, R, VMAX, VMIN, Dt and the reactances, ZSORCE included, on MBASE; H and D halved,
    reactances and R doubled, VMAX/VMIN/Dt halved): the same machine, so the runs must agree
    (angles, speeds, system-base powers) to 1e-6."""
    d100 = (
        f"    102 'GENROU' 1 {GR} 0.1 0.8 /\n"
        + SEXS
        + "    102 'TGOV1' 1 0.05 0.2 1.2 0.1 0.3 0.8 0.5 /\n"
    )
    gr200 = "8.0 0.03 0.4 0.05 3.0875 0.025 3.6 3.4 0.6 1.1 0.5 0.4"
    d200 = (
        f"    102 'GENROU' 1 {gr200} 0.1 0.8 /\n"
        + SEXS
        + "    102 'TGOV1' 1 0.1 0.2 0.6 0.05 0.3 0.8 0.25 /\n"
    )
    rc1, t1, o1 = imp("AD43a", d100)
    rc2, t2, o2 = imp("AD43b", d200, raw=raw_gen(MBASE="200.000", ZX="5.000E-1"))
    if rc1 != 0 or rc2 != 0:
        return False, f"rc {rc1} / {rc2}: {last(t1)} | {last(t2)}"
    cols = ("speed", "angle", "pelect", "vmag")
    d = maxdiff(trace(o1, cols), trace(o2, cols))
    return (
        d < 1e-6,
        f"max difference of speeds, angles, pelect, |V| between MBASE 100 and 200: {d:.2e}",
    )


@probe("AD44")
def zsorce_not_xdpp():
    """Generator 102's ZSORCE X = 0.1 while its GENROU X''d = 0.25 (PSS/E: ZSORCE must be
    R_a + jX''d for GENROU/GENSAL -- R_a is taken from it, stabctl reads ZR as r_a -- and its
    data check flags a mismatch): refused or named, not one of the two dropped silently."""
    return refused_or_named(
        "AD44", GENROU, [r"102", r"ZSORCE|ZX|X''d|xsource"], raw=raw_gen(ZX="1.0E-1")
    )


def main():
    KIT.main(summary="\n{n} probes, {short} short", kept="work dir kept: {wd}")


if __name__ == "__main__":
    main()
