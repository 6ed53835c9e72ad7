#!/usr/bin/env python
"""Round 59 (BD): an audit of the readers and importers for input changed, defaulted or
left out without a word, each candidate found by reading the code and proved here by the
smallest input that shows it.

    CLONE=<clone> PYTHONPATH=<clone> python benchmarks/reliability_probes_57.py [BD01 ...]

The project's standard (issue 54 and the developers' guide): "Nothing is changed,
defaulted or left out silently: an import names every such record and why."  A probe is
ok when the change is named (stderr, the import summary) or the input refused (exit 2,
``error:`` naming it); SHORT when the written case holds the change and nothing names it.
Inputs: ANDES's ieee14.raw/.dyr/.json (the `andes` extra), changed one thing at a time.

Paths probed (the code read):
  import-andes of a RAW file goes through ANDES 2.0's PSS/E reader
  (andes/io/psse.py): it keeps no line-end shunt (GI, BI, GJ, BJ: `_parse_line`), reads
  a transformer's magnetizing admittance as line charging B = MAG2 split over both ends
  and drops MAG1 (`_parse_transf_v33`: 'b': data[0][8]), keeps IDE 4 buses and every
  record at them (`_parse_bus_v33`), skips dc lines (no parser), ignores IREG, RT/XT,
  MODSW and COD; stabctl's `_branches_unlike_raw` (stabctl/io/andes_case.py:516) compares
  only ratio, phase and x, and nothing else of the RAW is compared
  (import-psse names each of these: stabctl/io/psse_raw.py).
  An ANDES case's Line b2, g2: stabctl/io/andes_case.py:1573 reads g1 + g/2, b1 + b/2 at
  both ends (as ANDES 2.0's equations do) and never b2, g2.
  Machines sharing a bus: stabctl/io/dyr.py:855 and dyr_converters.py `shares`: PG_k /
  sum(PG), 1/n of a sum 0 (PG +40 and -40 at one bus run at 0 and 0).
  GENROU T''qo = 0 / T'qo = 0: stabctl/models/machines.py:389-392 (PST's "no such
  circuit": x'q := x''d, 999 s), PSS/E's Model Library wants each > 0.

Found (round 59, BD, on main at 3499fa4e; 21 probes, about 2 minutes warm): 20 SHORT, 1
ok (BD20: refused, though by the equilibrium check, not naming pfrac; BD21 a machine at a
load bus runs from P = Q = 0 without a word, doubtful).  import-andes of a RAW names none of what ANDES's
reader drops or changes (BD01-BD09, BD14) though import-psse names each; MATPOWER's
SHIFT with TAP 0 and BASE_KV 0 (BD15, BD16); ANDES's Line b2, g2 and PV busr
(BD10, BD17: ANDES's own equations ignore them too); machine shares of a zero sum
(BD11), of a power flow that did not converge (BD09: qfrac +-5.3e7 written);
GENROU T''qo, T'qo of 0 read as PST's absent circuits (BD12, BD13); stabilisers of gain
0 other than IEEEST/PSS2 (BD18 ANDES's own ieee14 ST2CUT K1 = K2 = 0, BD19 PSS1A KS 0).
"""

# ruff: noqa
import json
import re
from pathlib import Path

from _probe_kit import Kit, tail

KIT = Kit("probes_bd59.", line="{pid:<6} {state:<5} {why}", timed=True, xdg=False)
CLONE, ENV, WD = KIT.clone, KIT.env, KIT.wd
run, rec, probe = KIT.cli, KIT.rec, KIT.probe


def andes_dir():
    import andes

    return Path(andes.__file__).parent / "cases" / "ieee14"


def src(name):
    return (andes_dir() / name).read_text()


def write(name, text):
    p = WD / name
    p.write_text(text)
    return p


def replaced(text, old, new, count=1):
    if old not in text:
        raise RuntimeError(f"probe input: {old[:50]!r} not in the file")
    return text.replace(old, new, count)


def table(path, name):
    d = json.loads(Path(path).read_text())
    t = d["tables"].get(name)
    if t is None:
        return []
    return [dict(zip(t["columns"], r)) for r in t["rows"]]


def numeric_rows(path):
    """The lines of a CSV that hold numbers (its data rows), as text."""
    return [ln for ln in Path(path).read_text().splitlines() if ln[:1].isdigit() or ln[:1] == "-"]


def said(text, *words):
    """The words (regex, case-insensitive) found in text."""
    return [w for w in words if re.search(w, text, re.I)]


def imp(kind, raw, dyr, out, *extra):
    """import-psse / import-andes of raw (+ dyr) to out: (rc, all output, out path)."""
    args = [f"import-{kind}", raw] + ([dyr] if dyr else []) + ["-o", WD / out, *extra]
    rc, o, e = run(args, 600)
    return rc, o + e, WD / out


def verdict(rc, text, words, changed_in_case, what):
    """ok when refused (rc 2, error: naming it) or named; SHORT when written silently."""
    if rc == 2 and "error:" in text and said(text, *words):
        return True, f"refused, named: {tail(text, 160)}"
    if rc != 0:
        return False, f"exit {rc}: {tail(text, 200)}"
    hits = said(text, *words)
    if hits:
        return True, f"named ({hits}): {what}"
    if not changed_in_case:
        return True, f"case holds the file's value: {what}"
    return False, f"written without a word: {what}"


GEN3 = (
    "     3,'1 ',    40.000,    15.000,    15.000,   -10.000,1.01000,     0,   100.000,"
    " 0.00000E+0, 1.30000E-1, 0.00000E+0, 0.00000E+0,1.00000,1,  100.0,    50.000,"
    "    10.000,   1,1.0000\n"
)
GENROU3_2 = """      3 'GENROU' 2     6.5000      0.60000E-01  0.20000      0.50000E-01
          5.0000       0.0000       1.8000       1.7500      0.60000
         0.80000      0.34000      0.15000      0.90000E-01  0.38000      /
"""


# ------------------------------------------------------------------ import-andes of a RAW
@probe("BD01")
def _():
    """import-andes of a RAW whose branch 2-3 has line-end shunts GI 2 MW, BI = BJ 5 Mvar
    (POM Non-Transformer Branch Data; import-psse keeps them): named or kept?"""
    old = "  0.00000,  0.00000,  0.00000,  0.00000,1,1,   0.00,   1,1.0000"
    t = src("ieee14.raw")
    line = "     2,      3,'1 ', 4.69900E-2, 1.97970E-1,   0.04380,  100.00,  100.00,    0.00,"
    t = replaced(
        t, line + old, line + "  2.00000,  5.00000,  0.00000,  5.00000,1,1,   0.00,   1,1.0000"
    )
    raw = write("bd01.raw", t)
    dyr = write("ieee14.dyr", src("ieee14.dyr"))
    rc, text, out = imp("andes", raw, dyr, "bd01.json", "--skip-unsupported")
    if rc != 0:
        return False, f"exit {rc}: {tail(text)}"
    br = [r for r in table(out, "branches") if {r["from_bus"], r["to_bus"]} == {2, 3}][0]
    ends = [br.get(k, 0) for k in ("g_from", "b_from", "g_to", "b_to")]
    lost = br["b"] == 0.0438 and not any(ends)
    return verdict(
        rc,
        text,
        [r"\bGI\b", r"\bBI\b", r"line-end", r"2-3.*shunt"],
        lost,
        f"branch 2-3 in the case b {br['b']}, line-end (g_from, b_from, g_to, b_to) {ends} "
        "(the RAW: GI 0.02, BI 0.05, BJ 0.05 pu; import-psse keeps them)",
    )


@probe("BD02")
def _():
    """import-andes of a RAW whose transformer 4-7 has a magnetizing admittance CM 1,
    MAG1 0.02, MAG2 -0.05 pu (POM: at the winding-1 bus; import-psse: g_from, b_from):
    ANDES reads MAG2 as line charging over both ends and drops MAG1."""
    t = replaced(
        src("ieee14.raw"),
        "     4,     7,     0,'1 ',1,1,1, 0.00000E+0, 0.00000E+0,2,",
        "     4,     7,     0,'1 ',1,1,1, 2.00000E-2,-5.00000E-2,2,",
    )
    raw = write("bd02.raw", t)
    dyr = write("ieee14.dyr", src("ieee14.dyr"))
    rc, text, out = imp("andes", raw, dyr, "bd02.json", "--skip-unsupported")
    if rc != 0:
        return False, f"exit {rc}: {tail(text)}"
    br = [r for r in table(out, "branches") if (r["from_bus"], r["to_bus"]) == (4, 7)][0]
    got = (br["b"], br.get("g_from", 0), br.get("b_from", 0))
    changed = got != (0, 0.02, -0.05)
    return verdict(
        rc,
        text,
        [r"MAG1", r"MAG2", r"magnetiz", r"4-7.*(shunt|charg)"],
        changed,
        f"transformer 4-7: charging b {got[0]}, g_from {got[1]}, b_from {got[2]} (the RAW: "
        "G 0.02, B -0.05 at bus 4, no charging)",
    )


@probe("BD03")
def _():
    """import-andes of a RAW whose bus 14 is isolated (IDE 4): PSS/E leaves it out with
    its load, branches 9-14, 13-14 and switched shunt (import-psse names the five)."""
    t = replaced(
        src("ieee14.raw"),
        "    14,'BUS14       ', 138.0000,1,",
        "    14,'BUS14       ', 138.0000,4,",
    )
    raw = write("bd03.raw", t)
    dyr = write("ieee14.dyr", src("ieee14.dyr"))
    rc, text, out = imp("andes", raw, dyr, "bd03.json", "--skip-unsupported")
    if rc != 0:
        return False, f"exit {rc}: {tail(text)}"
    buses = {r["number"] for r in table(out, "buses")}
    n_br = sum(14 in (r["from_bus"], r["to_bus"]) for r in table(out, "branches"))
    return verdict(
        rc,
        text,
        [r"IDE 4", r"isolated"],
        14 in buses,
        f"bus 14 in the case: {14 in buses}, {n_br} branches at it (PSS/E: none)",
    )


@probe("BD04")
def _():
    """import-andes of a RAW with a two-terminal dc line 2-4 (SETVL 10 MW): ANDES's reader
    has no dc line; import-psse names it unsupported ('the power it carries is lost')."""
    dc = (
        "'DC1', 1, 5.0, 10.0, 500.0, 0.0, 0.0, 0.0,'I', 0.0, 20, 1.0\n"
        " 2, 1, 20.0, 5.0, 0.0, 5.0, 500.0, 1.0, 1.0, 1.5, 0.51, 0.00625, 0, 0, 0,'1', 0.0\n"
        " 4, 1, 20.0, 5.0, 0.0, 5.0, 500.0, 1.0, 1.0, 1.5, 0.51, 0.00625, 0, 0, 0,'1', 0.0\n"
    )
    k = " 0 /End of Two-terminal dc line data"
    raw = write("bd04.raw", replaced(src("ieee14.raw"), k, dc + k))
    dyr = write("ieee14.dyr", src("ieee14.dyr"))
    rc, text, out = imp("andes", raw, dyr, "bd04.json", "--skip-unsupported")
    rc0, text0, _ = imp("andes", raw, dyr, "bd04s.json")
    ok, why = verdict(rc, text, [r"DC1", r"dc line"], True, "dc line DC1 2-4 (10 MW)")
    return ok, f"{why}; without --skip-unsupported: exit {rc0}"


@probe("BD05")
def _():
    """import-andes of a RAW whose generator at bus 6 regulates load bus 12 (IREG 12,
    VS 1.03): import-psse writes remote_regulation [6, 12, 1.03]; ANDES ignores IREG."""
    t = replaced(
        src("ieee14.raw"),
        "     6,'1 ',    30.000,    10.000,    10.000,    -6.000,1.03000,     0,",
        "     6,'1 ',    30.000,    10.000,    10.000,    -6.000,1.03000,    12,",
    )
    raw = write("bd05.raw", t)
    dyr = write("ieee14.dyr", src("ieee14.dyr"))
    rc, text, out = imp("andes", raw, dyr, "bd05.json", "--skip-unsupported")
    if rc != 0:
        return False, f"exit {rc}: {tail(text)}"
    reg = table(out, "remote_regulation")
    b6 = [r for r in table(out, "buses") if r["number"] == 6][0]
    return verdict(
        rc,
        text,
        [r"IREG", r"remote", r"regulat.*bus 12"],
        not reg,
        f"remote_regulation {reg or 'none'}; bus 6 held at {b6['vmag']} itself",
    )


@probe("BD06")
def _():
    """import-andes of ANDES's own ieee14.raw: its switched shunts at buses 9 and 14 have
    MODSW 1 (PSS/E switches them); both importers hold them at BINIT, import-psse names
    the two ('held at their RAW setting')."""
    raw = write("ieee14.raw", src("ieee14.raw"))
    dyr = write("ieee14.dyr", src("ieee14.dyr"))
    rc, text, out = imp("andes", raw, dyr, "bd06.json", "--skip-unsupported")
    rcp, textp, _ = imp("psse", raw, dyr, "bd06p.json", "--skip-unsupported")
    ok, why = verdict(
        rc,
        text,
        [r"MODSW", r"switched shunt", r"BINIT"],
        True,
        "2 switched shunts MODSW 1 held at BINIT",
    )
    return ok, f"{why}; import-psse names them: {bool(said(textp, 'MODSW 1'))}"


@probe("BD07")
def _():
    """import-andes of a RAW whose generator at bus 8 has a step-up transformer in its
    record (RT 0, XT 0.1, GTAP 1; POM Generator Data): import-psse names it unsupported;
    ANDES's reader drops RT, XT."""
    old = (
        "     8,'1 ',    35.000,    10.000,    10.000,    -6.000,1.03000,     0,   100.000,"
        " 0.00000E+0, 1.20000E-1, 0.00000E+0, 0.00000E+0,"
    )
    raw = write("bd07.raw", replaced(src("ieee14.raw"), old, old[:-12] + " 1.00000E-1,"))
    dyr = write("ieee14.dyr", src("ieee14.dyr"))
    rc, text, out = imp("andes", raw, dyr, "bd07.json", "--skip-unsupported")
    return verdict(
        rc,
        text,
        [r"\bXT\b", r"step-up"],
        True,
        "generator at bus 8: XT 0.1 (a step-up transformer) not in the case",
    )


@probe("BD08")
def _():
    """import-andes of a RAW whose transformer 4-7 has COD1 1 (its tap adjusted by PSS/E
    to hold bus 7): held at WINDV1 by both importers; import-psse names it."""
    old = "0.99677,   0.000,   0.000,    20.00,    20.00,     0.00,-1,      0,"
    raw = write(
        "bd08.raw",
        replaced(
            src("ieee14.raw"),
            old,
            "0.99677,   0.000,   0.000,    20.00,    20.00,     0.00, 1,      7,",
        ),
    )
    dyr = write("ieee14.dyr", src("ieee14.dyr"))
    rc, text, out = imp("andes", raw, dyr, "bd08.json", "--skip-unsupported")
    rcp, textp, _ = imp("psse", raw, dyr, "bd08p.json", "--skip-unsupported")
    ok, why = verdict(
        rc, text, [r"COD", r"tap control", r"held"], True, "transformer 4-7 COD1 1 held"
    )
    return ok, f"{why}; import-psse names it: {bool(said(textp, 'COD1 1'))}"


@probe("BD09")
def _():
    """import-andes of a RAW with a second generator at bus 3 (PG 10) whose VS 1.05 differs
    from the first's 1.01: import-psse leaves it out, named ('VS ... differs'); which VS
    does import-andes hold, and does it say?"""
    g2 = GEN3.replace("3,'1 ',    40.000", "3,'2 ',    10.000").replace("1.01000", "1.05000")
    raw = write("bd09.raw", replaced(src("ieee14.raw"), GEN3, GEN3 + g2))
    dyr = write("bd09.dyr", src("ieee14.dyr").rstrip("\n") + "\n" + GENROU3_2)
    rc, text, out = imp("andes", raw, dyr, "bd09.json", "--skip-unsupported")
    if rc != 0:
        ok = rc == 2 and "error:" in text and bool(said(text, r"VS", r"1\.05"))
        return ok, f"exit {rc}: {tail(text, 200)}"
    b3 = [r for r in table(out, "buses") if r["number"] == 3][0]
    q = [round(r["qfrac"], 3) for r in table(out, "machines") if r["bus"] == 3]
    numpy = "divide by zero encountered" in text
    ok, why = verdict(
        rc,
        text,
        [r"\bVS\b", r"v0", r"1\.05"],
        True,
        f"bus 3 held at {b3['vmag']} (generators' VS 1.01 and 1.05); its machines' qfrac "
        f"{q} (from ANDES's power flow, which did not converge)",
    )
    return ok and all(abs(x) <= 1 for x in q) and not numpy, why + (
        "; a bare numpy 'divide by zero encountered in divide' warning" if numpy else ""
    )


@probe("BD10")
def _():
    """import-andes of ANDES's ieee14.json whose Line_3 (2-3) has b2 0.3, g2 0.1 (ANDES's
    to-end shunt, `andes/models/line/line.py`): stabctl reads g1 + g/2, b1 + b/2 at both
    ends and never b2, g2 (as ANDES 2.0's equations): left out by name?"""
    d = json.loads(src("ieee14.json"))
    ln = [x for x in d["Line"] if x["idx"] == "Line_3"][0]
    ln["b2"], ln["g2"] = 0.3, 0.1
    case = write("bd10.json", json.dumps(d))
    rc, text, out = imp("andes", case, None, "bd10o.json", "--skip-unsupported")
    if rc != 0:
        ok = rc == 2 and bool(said(text, r"\bb2\b", r"\bg2\b"))
        return ok, f"exit {rc}: {tail(text, 200)}"
    br = [r for r in table(out, "branches") if {r["from_bus"], r["to_bus"]} == {2, 3}][0]
    ends = [br.get(k, 0) for k in ("g_from", "b_from", "g_to", "b_to")]
    return verdict(
        rc,
        text,
        [r"\bb2\b", r"\bg2\b"],
        not any(ends),
        f"branch 2-3 b {br['b']}, ends {ends} (file: b2 0.3, g2 0.1)",
    )


@probe("BD14")
def _():
    """import-andes of a RAW whose generator at bus 8 is a wind machine WMOD 2, WPF 0.9
    (POM Generator Data: Q limits +-|PG| tan(acos WPF), QT and QB not used): import-psse
    derives +-16.95 Mvar and names it; ANDES's reader keeps QT 10, QB -6."""
    old = (
        "     8,'1 ',    35.000,    10.000,    10.000,    -6.000,1.03000,     0,   100.000,"
        " 0.00000E+0, 1.20000E-1, 0.00000E+0, 0.00000E+0,1.00000,1,  100.0,    50.000,"
        "    10.000,   1,1.0000"
    )
    tail_ = ",   0,1.0000,   0,1.0000,   0,1.0000, 2, 0.9"
    raw = write("bd14.raw", replaced(src("ieee14.raw"), old, old + tail_))
    dyr = write("ieee14.dyr", src("ieee14.dyr"))
    rc, text, out = imp("andes", raw, dyr, "bd14.json", "--skip-unsupported")
    if rc != 0:
        return False, f"exit {rc}: {tail(text)}"
    b8 = [r for r in table(out, "buses") if r["number"] == 8][0]
    return verdict(
        rc,
        text,
        [r"WMOD", r"WPF"],
        abs(b8["qmax"] - 0.1695) > 1e-3,
        f"bus 8 Q limits {b8['qmax']}, {b8['qmin']} pu (PSS/E's WMOD 2: +-0.1695)",
    )


@probe("BD17")
def _():
    """import-andes of ANDES's ieee14.json whose PV at bus 6 has busr 12 (ANDES's 'bus idx
    for remote voltage control', declared in andes/models/static/pv.py, used by no
    equation): stabctl refuses a converter control's remote busr by name
    (andes_case.py:2011), the PV's?"""
    d = json.loads(src("ieee14.json"))
    for pv in d["PV"]:
        if pv["bus"] == 6:
            pv["busr"] = 12
    case = write("bd17.json", json.dumps(d))
    rc, text, out = imp("andes", case, None, "bd17o.json", "--skip-unsupported")
    if rc != 0:
        ok = rc == 2 and bool(said(text, r"busr"))
        return ok, f"exit {rc}: {tail(text, 200)}"
    reg = table(out, "remote_regulation")
    return verdict(
        rc,
        text,
        [r"busr"],
        not reg,
        f"remote_regulation {reg or 'none'}: bus 6 holds its own voltage",
    )


def case14_m():
    import andes

    return (Path(andes.__file__).parent / "cases" / "matpower" / "case14.m").read_text()


@probe("BD15")
def _():
    """import-andes of MATPOWER's case14.m whose branch 2-4 has TAP 0, SHIFT -5 deg
    (MATPOWER caseformat/makeYbus: TAP 0 is a ratio of 1, the shift applies all the same);
    ANDES's reader (andes/io/matpower.py: `data[8] == 0.0` -> not a transformer) drops the
    shift."""
    old = "\t2\t4\t0.05811\t0.17632\t0.034\t0\t0\t0\t0\t0\t1"
    m = write("bd15.m", replaced(case14_m(), old, old[:-4] + "\t-5\t1"))
    rc, text, out = imp("andes", m, None, "bd15.json", "--static")
    if rc != 0:
        ok = rc == 2 and bool(said(text, r"SHIFT", r"2-4"))
        return ok, f"exit {rc}: {tail(text, 200)}"
    br = [r for r in table(out, "branches") if (r["from_bus"], r["to_bus"]) == (2, 4)][0]
    return verdict(
        rc,
        text,
        [r"SHIFT", r"phase shift", r"branch 2-4"],
        br["phase_deg"] == 0,
        f"branch 2-4 tap {br['tap']}, phase {br['phase_deg']} deg (the file: SHIFT -5)",
    )


@probe("BD16")
def _():
    """import-andes of MATPOWER's case14.m as shipped: every BASE_KV is 0 (not given;
    stabctl's bus kv 0 is 'not given', which the C37 streams refuse for a PMU's bus);
    ANDES's reader makes each 110 kV (andes/io/matpower.py: `if baseKV == 0: baseKV =
    110`)."""
    m = write("case14.m", case14_m())
    rc, text, out = imp("andes", m, None, "bd16.json", "--static")
    if rc != 0:
        return False, f"exit {rc}: {tail(text, 200)}"
    kv = sorted({r["kv"] for r in table(out, "buses")})
    return verdict(
        rc,
        text,
        [r"BASE_KV", r"baseKV", r"110 kV"],
        kv != [0],
        f"bus kv {kv} in the case (the file: 0, not given)",
    )


# ------------------------------------------------------------------ import-psse
@probe("BD11")
def _():
    """import-psse of a RAW with two machines at bus 3: '1' PG +40 MW and '2' PG -40 MW (a
    pumped-storage unit pumping; PB -50): each machine's share PG_k / sum(PG) has a sum
    0, read as 1/2 each (stabctl/io/dyr.py:855): both machines run at 0 MW."""
    g2 = GEN3.replace("3,'1 ',    40.000", "3,'2 ',   -40.000").replace(
        "    50.000,    10.000,", "    50.000,   -50.000,"
    )
    raw = write("bd11.raw", replaced(src("ieee14.raw"), GEN3, GEN3 + g2))
    dyr = write("bd11.dyr", src("ieee14.dyr").rstrip("\n") + "\n" + GENROU3_2)
    rc, text, out = imp("psse", raw, dyr, "bd11.json", "--skip-unsupported")
    if rc != 0:
        ok = rc == 2 and bool(said(text, r"PG", r"share"))
        return ok, f"exit {rc}: {tail(text, 200)}"
    m = [r for r in table(out, "machines") if r["bus"] == 3]
    b3 = [r for r in table(out, "buses") if r["number"] == 3][0]
    p = [round(r["pfrac"] * b3["pgen"] * 100, 3) for r in m]
    return verdict(
        rc,
        text,
        [r"PG -40", r"share", r"sum.*0"],
        p != [40.0, -40.0],
        f"bus 3's machines run at {p} MW (pfrac {[r['pfrac'] for r in m]} of bus P "
        f"{b3['pgen']} pu); the RAW: +40, -40 MW",
    )


@probe("BD18")
def _():
    """import-psse of ANDES's ieee14.raw/.dyr as shipped: bus 1's ST2CUT has K1 = K2 = 0
    (MODE 1: its only input times 0; ieee14.dyr:4-8), so its output is 0 whatever the
    input, a stabiliser without effect; an IEEEST of KS 0 or a PSS2A of KS1 0 is named so
    (`_no_gain`, stabctl/io/dyr.py:1341, round 41), ST2CUT's is not (dyr.py:1299)."""
    raw = write("ieee14.raw", src("ieee14.raw"))
    dyr = write("ieee14.dyr", src("ieee14.dyr"))
    rc, text, out = imp("psse", raw, dyr, "bd18.json", "--skip-unsupported")
    if rc != 0:
        return False, f"exit {rc}: {tail(text)}"
    n = len(table(out, "pss"))
    ok, why = verdict(
        rc,
        text,
        [r"ST2CUT.*K1", r"K1 = 0", r"no effect"],
        True,
        f"{n} PSS in the case, bus 1's ST2CUT among them with K1 = K2 = 0",
    )
    if ok:
        return ok, why
    # the run with it against the run without it (the record taken out)
    rec_ = (
        "      1 'ST2CUT' 1          1            0            0            0\n"
        "          0.0000       0.0000       0.0000       0.0000       30.000\n"
        "          30.000      0.23000      0.25000E-01  0.23000      0.25000E-01\n"
        "          0.0000       0.0000      0.60000E-01 -0.60000E-01   0.0000\n"
        "          0.0000      /\n"
    )
    d2 = WD / "bd18_without" / "ieee14.dyr"
    d2.parent.mkdir(exist_ok=True)
    d2.write_text(replaced(src("ieee14.dyr"), rec_, ""))
    rc2, text2, out2 = imp("psse", raw, d2, "bd18_without.json", "--skip-unsupported")
    runs = []
    for case in (out, out2):
        csv = case.with_suffix(".csv")
        r = run(["simulate", case, "--fault", 2, "--tf", 3, "--out", csv], 900)
        if r[0] != 0:
            return ok, f"{why}; simulate exit {r[0]}: {tail(r[2], 160)}"
        runs.append(numeric_rows(csv))
    same = runs[0] == runs[1]
    return ok, f"{why}; bus-2 fault runs with and without it identical: {same}"


@probe("BD19")
def _():
    """import-psse of ieee14 with bus 3's IEEEST replaced by a PSS1A of KS 0 (its output
    always 0): named as IEEEST's KS 0 is?"""
    old = (
        "      3 'IEEEST' 1          3            0       0.0000       0.0000\n"
        "          0.0000       0.0000       0.0000       0.0000       0.0000\n"
        "          0.0000       0.0000      0.75000       1.0000       4.2000\n"
        "         -2.0000      0.10000     -0.10000       0.0000       0.0000      /\n"
    )
    new = "      3 'PSS1A' 1 1  0.0 0.0 0.15 0.05 0.15 0.05 1.0 0.02 0.0 0.1 -0.1 0.0 0.0 /\n"
    raw = write("ieee14.raw", src("ieee14.raw"))
    dyr = write("bd19.dyr", replaced(src("ieee14.dyr"), old, new))
    rc, text, out = imp("psse", raw, dyr, "bd19.json", "--skip-unsupported")
    if rc != 0:
        ok = rc == 2 and bool(said(text, r"KS"))
        return ok, f"exit {rc}: {tail(text, 200)}"
    n = len(table(out, "pss"))
    return verdict(
        rc,
        text,
        [r"PSS1A.*KS", r"KS = 0"],
        True,
        f"{n} PSS in the case, the PSS1A of KS 0 among them",
    )


def base_case():
    """ieee14 (ANDES's RAW + DYR) through import-psse: its case file, made once."""
    out = WD / "bd_base.json"
    if not out.exists():
        raw = write("ieee14.raw", src("ieee14.raw"))
        dyr = write("ieee14.dyr", src("ieee14.dyr"))
        rc, text, _ = imp("psse", raw, dyr, "bd_base.json", "--skip-unsupported")
        if rc != 0:
            raise RuntimeError(f"import-psse exit {rc}: {tail(text)}")
    return json.loads(out.read_text())


@probe("BD20")
def _():
    """A case file whose machine 2, alone at bus 2 (40 MW), has pfrac 0.5 (mac_con column
    22, 'fraction of the bus generation P'): half the bus's generation has no machine;
    refused, named, or run?"""
    d = base_case()
    m = d["tables"]["machines"]
    m["rows"][1][m["columns"].index("pfrac")] = 0.5
    case = write("bd20.json", json.dumps(d))
    rc, o, e = run(["simulate", case, "--tf", 2, "--json"], 900)
    text = o + e
    if rc == 2 and "error:" in text:
        return True, f"refused: {tail(text, 200)}"
    if rc != 0:
        return False, f"exit {rc}: {tail(text, 200)}"
    return bool(said(text, r"pfrac", r"fraction", r"share")), f"exit 0: {tail(text, 220)}"


@probe("BD21")
def _():
    """A case file with a sixth machine (machine 5's data) at bus 4, a load bus (kind 3, no
    generation): it starts at P = Q = 0; refused, named, or run without a word?"""
    d = base_case()
    m = d["tables"]["machines"]
    row = list(m["rows"][4])
    row[0], row[1] = 6, 4
    row[m["columns"].index("col19")] = 6
    m["rows"].append(row)
    case = write("bd21.json", json.dumps(d))
    rc, o, e = run(["simulate", case, "--tf", 2, "--json"], 900)
    text = o + e
    if rc == 2 and "error:" in text:
        return True, f"refused: {tail(text, 200)}"
    if rc != 0:
        return False, f"exit {rc}: {tail(text, 200)}"
    return bool(said(text, r"load bus", r"kind 3", r"no generation", r"machine 6")), (
        f"exit 0: {tail(text, 220)}"
    )


def _genrou_tc(pid, old, new, what):
    d = replaced(
        src("ieee14.dyr"),
        "      1 'GENROU' 1     6.5000      0.60000E-01  0.20000      0.50000E-01",
        new,
    )
    raw = write("ieee14.raw", src("ieee14.raw"))
    dyr = write(f"{pid}.dyr", d)
    rc, text, out = imp("psse", raw, dyr, f"{pid}.json", "--skip-unsupported")
    if rc != 0:
        ok = rc == 2 and bool(said(text, old))
        return ok, f"exit {rc}: {tail(text, 200)}"
    m = table(out, "machines")[0]
    return verdict(
        rc,
        text,
        [old],
        True,
        f"{what}; the case's row: xqp {m['xqp']}, Tqop {m['Tqop']}, Tqopp {m['Tqopp']}",
    )


@probe("BD12")
def _():
    """import-psse of a GENROU with T''qo = 0 (PSS/E Model Library: T''qo > 0): the run reads
    PST's 'no such circuit' (stabctl/models/machines.py:389: x'q := x''d = 0.23 for the
    file's X'q 0.8, T''qo 999 s)."""
    return _genrou_tc(
        "bd12",
        r"T''qo|T\"qo|Tqopp",
        "      1 'GENROU' 1     6.5000      0.60000E-01  0.20000      0.0",
        "T''qo 0 read as no q-axis subtransient circuit, X'q 0.8 run as X''d 0.23",
    )


@probe("BD13")
def _():
    """import-psse of a GENROU with T'qo = 0 (PSS/E Model Library: T'qo > 0): the run reads
    999 s (stabctl/models/machines.py:391), E'd frozen."""
    return _genrou_tc(
        "bd13",
        r"T'qo|Tqop\b",
        "      1 'GENROU' 1     6.5000      0.60000E-01  0.0      0.50000E-01",
        "T'qo 0 read as 999 s",
    )


if __name__ == "__main__":
    KIT.main(banner="work dir {wd}; package {clone}")
