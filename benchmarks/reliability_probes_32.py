#!/usr/bin/env python
"""Thirty-second reliability round (round 46, part AB): variants of issue 54's findings 6, 8, 9,
its "Crashes" paragraph and the newcomer's frictions that the earlier probe scripts do not try:
converter data of PSS/E's RENA plant (REGCA1 + REECB1 + REPCA1 on ThreeBusRenewable) with
swapped deadbands, negative gains, NaN/inf/text fields, a short record, a record split over
lines with comments, a duplicate record, a record of a generator that is not in the RAW, an
unknown model and a converter on a bus without generator; ANDES converter and battery rows
(REECA1 Imax inf, ESD1 fields missing, PVD1 on a bus of no generator); the readers given a
UTF-8 byte-order mark, CRLF, UTF-16 and NUL bytes; coarse steps on miniWECC; odd
--fault/--far-bus/--trip values; the docs' and `--help` examples and `| head`.

    python benchmarks/reliability_probes_32.py

CLONE (default: this repository) is the package under test; NUMBA_CACHE_DIR the caller's
(warm it first with `python -m stabctl compile`).  Prints per probe: id, ok/SHORT, reason;
exits 1 if any is SHORT.  Every command has a timeout; work in a temporary directory
(removed at the end unless KEEP=1).

The round found 5 of 54 short, all SMALLER (wording, consistency): REGCA1 Iolim > 0 imported
without a word (AB15), a NUL byte within a DYR's first 4 KiB called UTF-16 (AB19), a bus fault
with a trip labelled "cleared without loss of a line" (AB43), DYR bus 103.0 / 1.03E2 read as
103 (AB57), a UTF-16 --screening file called "cut by a kill" (AB60); all five fixed.  About 10 minutes
with a warm kernel cache (`python reliability_probes_32.py AB15 AB19` runs only those).

The contract (issue 54, "What to build"): converter data validated by stabctl before ANDES
fills defaults; every case refused naming file:line/model/bus/field, or imported with every
change named; never run with a silent default; every reader bounds its input; a coarse
step warned or refused; a clear error (exit 2, one line, no traceback, nothing written).
"""

# ruff: noqa: E501, BLE001, E731, RUF021, F841, B007, RUF002, RUF059 - a tester's script, kept as written

import json
import os
import re
import subprocess
import sys
from pathlib import Path

from _probe_kit import Kit

KIT = Kit("probes_ab46_", path=False, prefixes=False)
CLONE, ENV, WD, RESULTS, PROBES = KIT.clone, KIT.env, KIT.wd, KIT.results, KIT.probes
rec, probe = KIT.rec, KIT.probe
REN = Path(CLONE, "tests/data/psse_runs/RENA_DEFAULT")
REN_RAW = str(REN / "ThreeBusRenewable.raw")
REN_DYR = (REN / "ThreeBus_REN_A_DEFAULT_FLAG.dyr").read_text()


def cli(args, timeout=240, env=None, shell_tail=None):
    """(rc, stdout, stderr) of `python -m stabctl args` in WD; nothing kept of a run out of time."""
    return KIT.cli(args, timeout, env=env, partial=False)


def sh(cmd, timeout=240):
    """(rc, stdout, stderr) of a shell pipeline in WD (python -m stabctl as `S`)."""
    try:
        p = subprocess.run(
            ["bash", "-o", "pipefail", "-c", cmd.replace("S ", f"{sys.executable} -m stabctl ")],
            capture_output=True,
            text=True,
            timeout=timeout,
            cwd=WD,
            env=ENV,
            stdin=subprocess.DEVNULL,
        )
        return p.returncode, p.stdout, p.stderr
    except subprocess.TimeoutExpired:
        return "timeout", "", ""


def last(s, n=220):
    s = s.strip().splitlines()
    return (s[-1] if s else "")[:n]


def refused(args, pat, out=None):
    """ok when exit 2, an `error:` naming `pat` (regex), no traceback, nothing written."""
    rc, o, e = cli(args)
    written = out and os.path.exists(os.path.join(WD, out))
    if rc == 2 and re.search(pat, e) and "Traceback" not in e and not written:
        return True, last(e, 200)
    return False, f"rc {rc}{' (written)' if written else ''}: {last(e) or last(o)} (wanted /{pat}/)"


def named_or_refused(args, pat, out):
    """ok when refused naming `pat`, or imported with a warning/summary line naming `pat`."""
    rc, o, e = cli(args)
    if "Traceback" in e:
        return False, f"traceback: {last(e)}"
    if rc == 2 and re.search(pat, e):
        return True, "refused: " + last(e, 200)
    if rc == 0 and re.search(pat, o + e):
        line = next(ln for ln in (o + e).splitlines() if re.search(pat, ln))
        return True, "imported, named: " + line.strip()[:200]
    return False, f"rc {rc}: nothing names /{pat}/ ({last(e) or last(o)})"


def dyr(name, text):
    Path(WD, name + ".dyr").write_text(text)
    return name + ".dyr"


def ren(name, old, new, count=1):
    assert old in REN_DYR, old
    return dyr(name, REN_DYR.replace(old, new, count))


def imp(name, dyrfile, *extra):
    return ["import-psse", REN_RAW, dyrfile, "-o", name + ".json", *extra]


# ------------------------------------------------------------------ PSS/E converter data
@probe("AB01")
def _():
    """REECB1 with its voltage deadband swapped (dbd1 0.01 > dbd2 -0.01; WECC REEC_B: dbd1
    <= 0 <= dbd2): refused naming dbd1/dbd2, or imported with the change named."""
    f = ren(
        "dbd",
        "-0.10000E-01     0.10000E-01\n          1.0000",
        "0.10000E-01     -0.10000E-01\n          1.0000",
    )
    return named_or_refused(imp("dbd", f), r"dbd1|dbd2|deadband", "dbd.json")


@probe("AB02")
def _():
    """REPCA1 with its frequency deadband swapped (fdbd1 0.01 > fdbd2 -0.01): refused
    naming fdbd1/fdbd2, or imported with the change named."""
    f = ren(
        "fdbd",
        "0.25000        -0.10000E-01     0.10000E-01",
        "0.25000        0.10000E-01     -0.10000E-01",
    )
    return named_or_refused(imp("fdbd", f), r"fdbd1|fdbd2|deadband", "fdbd.json")


@probe("AB03")
def _():
    """REECB1 with a negative reactive-current gain Kqv -1 (a positive voltage feedback, as
    REPCA1's Kc < 0 that RULES refuses): refused naming Kqv, or imported naming it."""
    f = ren(
        "kqv", "1.0000          1.1000         -1.1000", "-1.0000          1.1000         -1.1000"
    )
    return named_or_refused(imp("kqv", f), r"Kqv", "kqv.json")


@probe("AB04")
def _():
    """REECB1 Imax given as NaN: refused naming the record's file:line and the field."""
    f = ren("imaxnan", "1.1100         0.20000E-01", "NaN         0.20000E-01")
    return refused(imp("imaxnan", f), r"imaxnan\.dyr:\d+.*(Imax|finite|number)", "imaxnan.json")


@probe("AB05")
def _():
    """REGCA1 Tg given as inf: refused naming file:line and Tg (or 'not a finite number')."""
    f = ren("tginf", "0.20000E-01   10.000      0.90000", "inf   10.000      0.90000")
    return refused(imp("tginf", f), r"tginf\.dyr:\d+.*(Tg|finite)", "tginf.json")


@probe("AB06")
def _():
    """REPCA1 with text in a number field ('abc' for Kp): refused naming file:line."""
    f = ren("txt", "0.20000E-01      18.000", "0.20000E-01      abc")
    return refused(imp("txt", f), r"txt\.dyr:\d+", "txt.json")


@probe("AB07")
def _():
    """REGCA1 record short by two fields (Iqrmin and Accel missing before '/'): refused
    naming file:line, REGCA1 and the count, not read with defaults."""
    f = ren("short", "100.00      -100.00       0.0000      /", "100.00      /")
    return refused(imp("short", f), r"short\.dyr:\d+.*REGCA1", "short.json")


@probe("AB08")
def _():
    """The RENA DYR with each record's model name on a line of its own, a comment after
    each '/', and CRLF line ends: the same case as the file as written (PSS/E reads DYR
    free format)."""
    text = REN_DYR.replace("103 'REGCA1' 1", "103\n'REGCA1'\n 1").replace(
        "/\n", "/ a comment, 1 2 3\n"
    )
    Path(WD, "split.dyr").write_bytes(text.replace("\n", "\r\n").encode())
    a = cli(imp("plain", dyr("plain", REN_DYR), "--json"))
    b = cli(imp("split", "split.dyr", "--json"))
    if a[0] != 0:
        return False, f"the file as written: rc {a[0]} {last(a[2])}"
    if b[0] != 0:
        return False, f"rc {b[0]}: {last(b[2])}"
    ca = json.loads(Path(WD, "plain.json").read_text())
    cb = json.loads(Path(WD, "split.json").read_text())
    drop = lambda c: {
        k: v for k, v in c.items() if k not in ("provenance", "source", "origin", "name", "meta")
    }
    same = json.dumps(drop(ca), sort_keys=True) == json.dumps(drop(cb), sort_keys=True)
    return same, "same case" if same else "cases differ: " + ", ".join(
        k
        for k in ca
        if json.dumps(ca.get(k), sort_keys=True) != json.dumps(cb.get(k), sort_keys=True)
    )[:200]


@probe("AB09")
def _():
    """A second REECB1 for the same plant (103 '1'): refused naming the second record's
    file:line (not the later one silently taking over)."""
    i = REN_DYR.index("    103 'REECB1'")
    j = REN_DYR.index("    103 'REPCA1'")
    f = dyr("dup", REN_DYR + REN_DYR[i:j].replace("1.1100", "0.5000"))
    return refused(imp("dup", f), r"dup\.dyr:\d+.*(second|twice|again|duplicate)", "dup.json")


@probe("AB10")
def _():
    """The converter chain of a generator the RAW does not have (103 id '2'): refused naming
    the record, or (--skip-unsupported) left out with each record named."""
    f = dyr(
        "id2",
        REN_DYR.replace("103 'REGCA1' 1", "103 'REGCA1' 2")
        .replace("103 'REECB1' 1", "103 'REECB1' 2")
        .replace("103 'REPCA1' 1", "103 'REPCA1' 2"),
    )
    return refused(imp("id2", f), r"id2\.dyr:\d+.*103", "id2.json")


@probe("AB11")
def _():
    """A REGCA1 (with its REECB1, REPCA1) at bus 101, which has a load and no generator:
    refused naming bus 101 (a converter on a bus without a generator)."""
    f = dyr("bus101", REN_DYR.replace("    103 '", "    101 '"))
    return refused(imp("bus101", f), r"101", "bus101.json")


@probe("AB12")
def _():
    """An unknown converter model ('REGCX1') in place of REGCA1: refused naming file:line
    and the model; with --skip-unsupported the model and the controls left without it
    (REECB1, REPCA1) each named."""
    f = ren("unk", "'REGCA1'", "'REGCX1'")
    ok1, why1 = refused(imp("unk", f), r"unk\.dyr:\d+.*REGCX1", "unk.json")
    rc, o, e = cli(imp("unk2", f, "--skip-unsupported"))
    txt = o + e
    ok2 = (
        rc in (0, 2)
        and "REGCX1" in txt
        and ("REECB1" in txt and "REPCA1" in txt or rc == 2)
        and "Traceback" not in e
    )
    return (
        ok1 and ok2,
        f"{why1}; skip: rc {rc}, REGCX1/REECB1/REPCA1 named: {'REGCX1' in txt}/{'REECB1' in txt}/{'REPCA1' in txt}",
    )


@probe("AB13")
def _():
    """REECB1 with Vdip 1.2 > Vup 0.8 (a PSS/E file, not ANDES's): refused naming Vdip."""
    f = ren("vdip", "-99.000          99.000", "1.2000          0.8000")
    return refused(imp("vdip", f), r"Vdip", "vdip.json")


@probe("AB14")
def _():
    """REPCA1 Qmax -0.43 < Qmin 0.43 swapped (the Q command's limits): refused naming it."""
    f = ren("pcq", "0.43000        -0.43000", "-0.43000        0.43000")
    return refused(imp("pcq", f), r"Qmax|Qmin", "pcq.json")


@probe("AB15")
def _():
    """REGCA1 with Iolim +1.3 (the lower limit of its output Iq: positive, it pins Iq at
    1.3 pu above the power flow's) or Khv -1 (>= 0): refused at import naming the field, as
    Khv -1 is.  Round 46: Iolim +1.3 imported without a word (exit 0); simulate then refuses
    "converter C1 ... cannot start at its power-flow point" listing six possible causes
    (stabctl/models/converters/rules.py _REGC has no Iolim rule; table.py's Iolim has no
    bound)."""
    f = ren("iolim", "-1.3000      0.20000", "1.3000      0.20000")
    a = named_or_refused(imp("iolim", f), r"Iolim", "iolim.json")
    f2 = ren("khv", "0.0000       100.00", "-1.0000       100.00")
    b = named_or_refused(imp("khv", f2), r"Khv", "khv.json")
    return a[0] and b[0], f"Iolim: {a[1][:110]}; Khv: {b[1][:110]}"


# ------------------------------------------------------------------ readers
@probe("AB16")
def _():
    """A DYR that starts with a UTF-8 byte-order mark (Notepad's): the same import, or a
    refusal naming the mark -- not 'unknown model' for the first record."""
    Path(WD, "bom.dyr").write_bytes(b"\xef\xbb\xbf" + REN_DYR.encode())
    rc, o, e = cli(imp("bom", "bom.dyr"))
    return (
        rc == 0 or (rc == 2 and re.search(r"byte.order|BOM", e, re.I))
    ) and "Traceback" not in e, f"rc {rc}: {last(e) or last(o)}"


@probe("AB17")
def _():
    """A RAW that starts with a UTF-8 byte-order mark: imported, or refused naming it."""
    Path(WD, "bom.raw").write_bytes(b"\xef\xbb\xbf" + Path(REN_RAW).read_bytes())
    rc, o, e = cli(["import-psse", "bom.raw", dyr("plainr", REN_DYR), "-o", "bomr.json"])
    return (
        rc == 0 or (rc == 2 and re.search(r"byte.order|BOM", e, re.I))
    ) and "Traceback" not in e, f"rc {rc}: {last(e) or last(o)}"


@probe("AB18")
def _():
    """A DYR saved as UTF-16 (a Windows editor's 'Unicode'): refused naming the file and the
    encoding, one line, exit 2."""
    Path(WD, "u16.dyr").write_bytes(REN_DYR.encode("utf-16"))
    return refused(imp("u16", "u16.dyr"), r"u16\.dyr", "u16.json")


@probe("AB19")
def _():
    """A DYR with a NUL byte inside a number of the REGCA1 record (byte 100 of a 1.3 KB ASCII
    file): refused naming file:line, as the same NUL past the first 4 KiB is ("nul2.dyr:102
    REGCA1 (bus 103, id 1): Rrpwr = '10.0\\x0000': not a number").  Round 46: refused as "in
    UTF-16 or UTF-32 (a byte-order mark or NUL bytes at its start)" -- a file that is
    neither, no line named (stabctl/io/inputs.py case_text: any NUL in data[:4096])."""
    Path(WD, "nul.dyr").write_bytes(REN_DYR.replace("10.000", "10.0\x0000", 1).encode())
    return refused(imp("nul", "nul.dyr"), r"nul\.dyr:\d+", "nul.json")


@probe("AB20")
def _():
    """A `--faults` CSV with a UTF-8 byte-order mark and CRLF ends: read as the same faults
    (the header is `bus,far_bus`, not '\\ufeffbus')."""
    Path(WD, "f.csv").write_bytes(b"\xef\xbb\xbfbus,far_bus\r\n3,101\r\n")
    rc, o, e = cli(
        ["sweep-cct", "kundur", "--faults", "f.csv", "--out", "s.jsonl", "--tol-ms", "20"], 400
    )
    return rc == 0 and "Traceback" not in e, f"rc {rc}: {last(e) or last(o)}"


@probe("AB21")
def _():
    """A `--faults` CSV in UTF-16: refused naming the file (one line, exit 2)."""
    Path(WD, "f16.csv").write_bytes("bus,far_bus\n3,101\n".encode("utf-16"))
    return refused(
        ["sweep-cct", "kundur", "--faults", "f16.csv", "--out", "s16.jsonl"],
        r"f16\.csv",
        "s16.jsonl",
    )


@probe("AB22")
def _():
    """A case json saved with a byte-order mark, and one whose 'name' holds a 5 MB string:
    the first runs (or is refused naming the mark), the second is refused or runs, never a
    traceback or a hang."""
    src = Path(CLONE, "stabctl/case/data/kundur.json")
    Path(WD, "kb.json").write_bytes(b"\xef\xbb\xbf" + src.read_bytes())
    rc, o, e = cli(["simulate", "kb.json", "--fault", "3", "--far-bus", "101", "--tf", "1.5"])
    ok1 = (rc == 0 or rc == 2 and re.search(r"byte.order|BOM", e, re.I)) and "Traceback" not in e
    d = json.loads(src.read_text())
    d["name"] = "x" * 5_000_000
    Path(WD, "kn.json").write_text(json.dumps(d))
    rc2, o2, e2 = cli(["simulate", "kn.json", "--fault", "3", "--far-bus", "101", "--tf", "1.5"])
    ok2 = rc2 in (0, 2) and "Traceback" not in e2 and len(o2) < 100_000
    return (
        ok1 and ok2,
        f"BOM: rc {rc} {last(e) or last(o, 80)}; 5 MB name: rc {rc2}, {len(o2)} chars out, {last(e2, 100)}",
    )


# ------------------------------------------------------------------ ANDES converter and battery rows
def andes_case(rel):
    import importlib.util

    spec = importlib.util.find_spec("andes")
    return os.path.join(os.path.dirname(spec.origin), "cases", rel)


def andes_json(name, rel, edit):
    d = json.loads(Path(andes_case(rel)).read_text())
    edit(d)
    Path(WD, name + ".json").write_text(json.dumps(d))  # NaN/inf as NaN/Infinity
    return name + ".json"


def aimp(src, name, *extra):
    return ["import-andes", src, "-o", name + "_o.json", *extra]


@probe("AB23")
def _():
    """ANDES's ieee14_esd1.xlsx as shipped: its ESD1 rows give no En, EtaC, EtaD (ANDES
    fills them); imported naming each value not in the file, or refused -- not a battery
    run at ANDES's energy without a word."""
    rc, o, e = cli(aimp(andes_case("ieee14/ieee14_esd1.xlsx"), "esd"))
    txt = o + e
    named = [k for k in ("En", "EtaC", "EtaD") if re.search(rf"\b{k}\b", txt)]
    if "Traceback" in e:
        return False, f"traceback: {last(e)}"
    if rc == 2:
        return True, "refused: " + last(e, 200)
    return len(named) == 3, f"rc {rc}, named: {named} of En/EtaC/EtaD"


@probe("AB24")
def _():
    """ieee14_reecb1.json with REECB1 Imax = Infinity (JSON's): refused naming REECB1 and Imax
    (a current limit that is no limit), not run."""
    f = andes_json(
        "imaxinf",
        "ieee14/ieee14_reecb1.json",
        lambda d: d["REECB1"][0].__setitem__("Imax", float("inf")),
    )
    return refused(aimp(f, "imaxinf"), r"REECB1.*Imax|Imax.*REECB1", "imaxinf_o.json")


@probe("AB25")
def _():
    """ieee14_reecb1.json with REECB1's deadband swapped (dbd1 0.02, dbd2 -0.02): refused or
    imported naming dbd1/dbd2."""

    def ed(d):
        d["REECB1"][0]["dbd1"], d["REECB1"][0]["dbd2"] = 0.02, -0.02

    f = andes_json("adbd", "ieee14/ieee14_reecb1.json", ed)
    return named_or_refused(aimp(f, "adbd"), r"dbd1|dbd2", "adbd_o.json")


@probe("AB26")
def _():
    """ieee14_reecb1.json with the REGCA1's Tg key removed (a field missing from the row):
    refused, or imported naming 'Tg' (ANDES's default 0.1 s)."""
    f = andes_json("notg", "ieee14/ieee14_reecb1.json", lambda d: d["REGCA1"][0].pop("Tg"))
    return named_or_refused(aimp(f, "notg"), r"\bTg\b", "notg_o.json")


@probe("AB27")
def _():
    """ieee14_pvd1.json with the PVD1 at bus 999 (no such bus): refused naming PVD1 and
    999, one line, no traceback."""
    f = andes_json(
        "pvd999", "ieee14/ieee14_pvd1.json", lambda d: d["PVD1"][0].__setitem__("bus", 999)
    )
    return refused(aimp(f, "pvd999"), r"999", "pvd999_o.json")


@probe("AB28")
def _():
    """ieee14_pvd1.json with the PVD1 moved to bus 5 (a load bus, no generator) while its
    gen stays bus 8's StaticGen 6... (ANDES reads bus from the gen): refused naming the
    PVD1 and both buses, or imported naming the change of bus."""
    f = andes_json(
        "pvdbus5", "ieee14/ieee14_pvd1.json", lambda d: d["PVD1"][0].__setitem__("bus", 5)
    )
    return named_or_refused(aimp(f, "pvdbus5"), r"PVD1.*\b5\b|\b5\b.*PVD1", "pvdbus5_o.json")


@probe("AB29")
def _():
    """ieee14_reecb1.json with its REGCA1 row twice (same idx 1): refused naming REGCA1 and
    idx 1 (a duplicate device), one line, no traceback."""
    f = andes_json(
        "dupidx", "ieee14/ieee14_reecb1.json", lambda d: d["REGCA1"].append(dict(d["REGCA1"][0]))
    )
    return refused(aimp(f, "dupidx"), r"REGCA1|idx|duplicate", "dupidx_o.json")


@probe("AB30")
def _():
    """ieee14_reecb1.json with REGCA1 Tg as the text "0.1" (a number in quotes): imported as
    0.1 with the reading named, or refused naming Tg -- no traceback."""
    f = andes_json(
        "tgtext", "ieee14/ieee14_reecb1.json", lambda d: d["REGCA1"][0].__setitem__("Tg", "0.1")
    )
    rc, o, e = cli(aimp(f, "tgtext"))
    if "Traceback" in e or rc not in (0, 2):
        return False, f"rc {rc}: {last(e)}"
    if rc == 2:
        return ("Tg" in e), last(e, 200)
    c = json.loads(Path(WD, "tgtext_o.json").read_text())
    return True, f"imported (rc 0): {last(e, 120)}"


@probe("AB31")
def _():
    """An ANDES json with a model ANDES does not know ('REGCX1'): refused naming it."""
    f = andes_json(
        "unkm",
        "ieee14/ieee14_reecb1.json",
        lambda d: d.__setitem__("REGCX1", [dict(d["REGCA1"][0])]),
    )
    return refused(aimp(f, "unkm"), r"REGCX1", "unkm_o.json")


@probe("AB32")
def _():
    """ieee14_reecb1.json with REPCA1 Kc -1 and Ddn -10 in one row: refused naming the first
    (Kc) -- a test that both are checked: fix Kc and Ddn is named."""

    def ed(d):
        d["REPCA1"][0]["Kc"], d["REPCA1"][0]["Ddn"] = -1.0, -10.0

    a = refused(
        aimp(andes_json("kc", "ieee14/ieee14_reecb1.json", ed), "kc"), r"Kc|Ddn", "kc_o.json"
    )
    b = refused(
        aimp(
            andes_json(
                "ddn",
                "ieee14/ieee14_reecb1.json",
                lambda d: d["REPCA1"][0].__setitem__("Ddn", -10.0),
            ),
            "ddn",
        ),
        r"Ddn",
        "ddn_o.json",
    )
    return a[0] and b[0], f"{a[1][:110]} | {b[1][:110]}"


# ------------------------------------------------------------------ numerical honesty
def sim_json(args, timeout=300):
    rc, o, e = cli(["simulate", *args, "--json"], timeout)
    try:
        return rc, json.loads(o), e
    except Exception:
        return rc, None, e


@probe("AB40")
def _():
    """Kundur's line fault 3-101 cleared at 9.26 cycles (within a millisecond of its CCT)
    with the trapezoid at 16 ms (under the one-cycle bound: no warning) and at 2 ms: the
    verdicts differ (16 ms: loss of synchronism; 2 ms: stable); the contract is met when
    --check-step at 16 ms says the verdict depends on the step (simulate --help: a
    clearing near the CCT may depend on the step; --check-step says so)."""
    base = [
        "kundur",
        "--fault",
        "3",
        "--far-bus",
        "101",
        "--clear-cycles",
        "9.26",
        "--tf",
        "6",
        "--method",
        "trapezoid",
    ]
    rc1, fine, e1 = sim_json([*base, "--step", "0.002"], 600)
    rc2, coarse, e2 = sim_json([*base, "--step", "0.016"], 600)
    if fine is None or coarse is None:
        return False, f"rc {rc1}/{rc2}: {last(e1)} {last(e2)}"
    v1, v2 = fine.get("verdict"), coarse.get("verdict")
    rc3, o3, e3 = cli(["simulate", *base, "--step", "0.016", "--check-step"], 600)
    flagged = "depends on the step" in o3 + e3
    return v1 == v2 or flagged, f"2 ms: {v1}, 16 ms: {v2}; --check-step flags it: {flagged}"


@probe("AB41")
def _():
    """miniWECC, trapezoid at 0.05 s (3 cycles) on a line fault: warned on stderr and in
    --json's warnings (Kundur's 0.2 s is the earlier probe's)."""
    rc, d, e = sim_json(
        [
            "miniwecc",
            "--fault",
            "83",
            "--far-bus",
            "33",
            "--tf",
            "3",
            "--method",
            "trapezoid",
            "--step",
            "0.05",
        ],
        600,
    )
    if d is None:
        return rc == 2 and "Traceback" not in e, f"rc {rc}: {last(e)}"
    w = "trapezoid step" in e and bool(d.get("warnings"))
    return (
        w,
        f"verdict {d.get('verdict')}, stderr warned {'trapezoid step' in e}, json warnings {bool(d.get('warnings'))}",
    )


@probe("AB42")
def _():
    """cct kundur --fault 3 --far-bus 101 --trip 101 3 (the faulted circuit named from its
    other end): refused as `--trip 3 101` is ('faulted circuit'), not a second trip of
    the same circuit or a different CCT."""
    return refused(
        ["cct", "kundur", "--fault", "3", "--far-bus", "101", "--trip", "101", "3"],
        r"faulted|already|same",
    )


@probe("AB43")
def _():
    """cct kundur --fault 3 --trip 3 101 (a bus fault cleared by a trip, no --far-bus): the
    printed result names the bus fault AND the trip, and does not say the opposite.  Round
    46: "fault at bus 3 at 1 s, cleared without loss of a line, 3-101 also opened" (the CCT,
    0.154 s, is the line fault 3-101's, rightly; the words contradict themselves:
    stabctl/cli/format.py print_cct joins the bus fault's fixed phrase and the trips)."""
    rc, o, e = cli(["cct", "kundur", "--fault", "3", "--trip", "3", "101", "--json"], 600)
    if rc == 2:
        return "Traceback" not in e, "refused: " + last(e)
    try:
        d = json.loads(o)
    except Exception:
        return False, f"rc {rc}: {last(e)}"
    rc2, o2, e2 = cli(["cct", "kundur", "--fault", "3", "--trip", "3", "101"], 600)
    first = o2.strip().splitlines()[0] if o2.strip() else ""
    says_no_loss = "without loss of a line" in first
    trip_named = "3-101" in first and ("opened" in first or "opening" in first or "trip" in first)
    ok = trip_named and not says_no_loss
    return ok, f"text: {first[:160]!r}; cct {d.get('cct_s')} (the line fault 3-101's)" + (
        " -- says 'without loss of a line' and then that 3-101 opens" if says_no_loss else ""
    )


@probe("AB44")
def _():
    """cct kundur with --far-bus given as -101, 101.0, 1e2, ' 101', '0x65': each refused
    naming --far-bus (exit 2, no output)."""
    bad = []
    for v in ("-101", "101.0", "1e2", "0x65", "101.", "1_01", ""):
        rc, o, e = cli(["cct", "kundur", "--fault", "3", "--far-bus", v], 120)
        if rc != 2 or o.strip() or "far-bus" not in e or "Traceback" in e:
            bad.append(f"{v!r}: rc {rc} {last(e, 80)}")
    return not bad, "; ".join(
        bad
    ) or "7 refused naming --far-bus (' 101' with blanks is read as 101, as meant)"


@probe("AB45")
def _():
    """cct kundur --fault 3 --far-bus 101 --circuit 3 (Kundur's 3-101 has two circuits):
    refused naming the circuits there are."""
    return refused(
        ["cct", "kundur", "--fault", "3", "--far-bus", "101", "--circuit", "3"], r"circuit"
    )


@probe("AB46")
def _():
    """simulate kundur --fault 3 --far-bus 13 (no branch 3-13: the buses exist, a line does
    not): refused naming 3-13 and the buses 3 connects to, not a run with no line opened."""
    return refused(
        ["simulate", "kundur", "--fault", "3", "--far-bus", "13", "--tf", "2"], r"3.{0,10}13"
    )


# ------------------------------------------------------------------ the newcomer
@probe("AB50")
def _():
    """Output cut by `head`: `cases | head -1`, `simulate ... | head -1`, `cct --help |
    head -2`, `eig kundur | head -3`: no 'Broken pipe', no traceback on stderr."""
    bad = []
    for c in (
        "S cases | head -1",
        "S simulate kundur --fault 3 --far-bus 101 --tf 1.5 | head -1",
        "S cct --help | head -2",
        "S eig kundur | head -3",
        "S simulate kundur --fault 3 --far-bus 101 --tf 1.5 --json | head -c 20",
    ):
        rc, o, e = sh(c.replace("| head", "2>err.txt | head"), 300)
        err = Path(WD, "err.txt").read_text() if Path(WD, "err.txt").exists() else ""
        if "Broken pipe" in err or "Traceback" in err or rc == "timeout" or not o.strip():
            bad.append(f"{c[2:40]}: rc {rc} {last(err, 80)}")
    return not bad, "; ".join(bad) or "5 pipes cut cleanly"


def help_examples():
    """(command, line) of every example line in the subcommands' --help."""
    rc, o, e = cli(["--help"])
    cmds = re.findall(r"^  ([a-z][a-z-]+)\s{2,}", o.split("Commands:")[1], re.M)
    out = []
    for c in cmds:
        sub = [c]
        rc, h, e = cli([c, "--help"])
        if "Commands:" in h:  # a group (pmu, estimate)
            for s in re.findall(r"^  ([a-z][a-z-]+)\s{2,}", h.split("Commands:")[1], re.M):
                rc, h2, e = cli([c, s, "--help"])
                out += [
                    ((c, s), ln.strip(), h2)
                    for ln in h2.splitlines()
                    if ln.strip().startswith("stabctl ")
                ]
        out += [((c,), ln.strip(), h) for ln in h.splitlines() if ln.strip().startswith("stabctl ")]
    return out


@probe("AB51")
def _():
    """Every example in every --help names the command it is in (or one that exists) and only
    options that command has (`--help`'s own Options list), one command per line."""
    bad = []
    n = 0
    helps = {}
    for where, line, h in help_examples():
        n += 1
        words = line.split()[1:]
        path = []
        for w in words:
            if w.startswith("-"):
                break
            path.append(w)
        # the command the example runs: its first one or two words that are commands
        key = tuple(path[:2])
        if key not in helps:
            rc, hh, e = cli([*path[:2], "--help"])
            if rc != 0:
                rc, hh, e = cli([path[0], "--help"])
            helps[key] = hh if rc == 0 else ""
        hh = helps[key]
        if not hh:
            bad.append(f"{' '.join(where)}: '{line[:60]}' names no command")
            continue
        opts = set(re.findall(r"(--[a-z][a-z0-9-]*)", hh.split("Options:")[-1]))
        for w in words:
            if w.count("stabctl") and w != words[0]:
                bad.append(f"{' '.join(where)}: two commands on one line: {line[:80]}")
            m = re.match(r"(--[a-z][a-z0-9-]*)", w)
            if m and m.group(1) not in opts and m.group(1) not in ("--help",):
                bad.append(f"{' '.join(where)}: {m.group(1)} not an option of {' '.join(path[:2])}")
    return not bad, "; ".join(sorted(set(bad)))[:600] or f"{n} examples, options all known"


@probe("AB52")
def _():
    """The docs' command lines (docs/*.md and README.md code blocks and `stabctl ...` in
    backticks): each option named exists in that command's --help (static check)."""
    files = [Path(CLONE, "README.md"), *sorted(Path(CLONE, "docs").glob("*.md"))]
    helps, bad, n = {}, set(), 0
    cmds = set()
    rc, o, e = cli(["--help"])
    top = set(re.findall(r"^  ([a-z][a-z-]+)\s{2,}", o.split("Commands:")[1], re.M))
    for f in files:
        if f.name == "cli_reference.md":
            continue
        for line in f.read_text().splitlines():
            for m in re.finditer(r"(?:^\s*\$?\s*|`)(stabctl\s+[a-z][^`|;&#]*)", line):
                words = m.group(1).split()
                if len(words) < 2 or words[1] not in top:
                    continue
                path = [words[1]]
                if len(words) > 2 and re.match(r"^[a-z][a-z-]+$", words[2]):
                    path.append(words[2])
                key = tuple(path)
                if key not in helps:
                    rc, hh, e = cli([*path, "--help"])
                    if rc != 0:
                        rc, hh, e = cli([path[0], "--help"])
                        key = (path[0],)
                    helps[tuple(path)] = hh
                hh = helps[tuple(path)]
                opts = set(re.findall(r"(--[a-z][a-z0-9-]*)", hh))
                n += 1
                for w in words[2:]:
                    mm = re.match(r"(--[a-z][a-z0-9-]*)", w)
                    if mm and mm.group(1) not in opts:
                        bad.add(f"{f.name}: `{' '.join(words[:2])} ... {mm.group(1)}`")
    return not bad, f"{n} command lines; unknown options: " + "; ".join(sorted(bad))[
        :700
    ] if bad else f"{n} command lines, options all known"


@probe("AB53")
def _():
    """eig --report on the converter case of a PSS/E import (RENA's REGCA1 plant; issue 54's
    IndexError was ANDES's cases): a report written, exit 0, or a refusal naming why."""
    f = dyr("eigren", REN_DYR)
    rc, o, e = cli(imp("eigren", f))
    if rc != 0:
        return False, f"import rc {rc}: {last(e)}"
    rc, o, e = cli(["eig", "eigren.json", "--report", "--out-dir", "rep"], 600)
    reps = list(Path(WD, "rep").glob("*.md")) if Path(WD, "rep").exists() else []
    if rc == 0 and reps:
        return True, f"report {reps[0].name}"
    return rc == 2 and "Traceback" not in e and not reps, f"rc {rc}: {last(e)}"


@probe("AB54")
def _():
    """`eig kundur` text and `cases` text: units labelled (Hz, %, s or MW) in the header of
    each table, machines named (bus or name) not index only."""
    rc, o, e = cli(["eig", "kundur"], 300)
    rc2, o2, e2 = cli(["cases"])
    ok = (
        rc == 0
        and "Hz" in o
        and ("%" in o or "ratio" in o or "zeta" in o)
        and "(bus " in o
        and rc2 == 0
    )
    return (
        ok,
        f"eig rc {rc} Hz {'Hz' in o} zeta/%/ratio {'%' in o or 'ratio' in o or 'zeta' in o}, machines with buses {'(bus ' in o}; cases rc {rc2}: {o2.strip().splitlines()[0][:100] if o2.strip() else ''}",
    )


# ------------------------------------------------------------------ more variants
@probe("AB55")
def _():
    """docs/cli_reference.md (the built CLI reference): no option written with an en dash
    ('–fault') or em dash in place of '--' (issue 54: 90 times)."""
    t = Path(CLONE, "docs/cli_reference.md").read_text()
    bad = re.findall(r"[\u2013\u2014][a-z][a-z-]+", t)
    return (
        not bad,
        f"{len(bad)} dashes: {bad[:5]}" if bad else "no en/em dash before an option name",
    )


@probe("AB56")
def _():
    """Every --help text: no line holds two `stabctl ...` commands (examples run together)."""
    bad = []
    rc, o, e = cli(["--help"])
    cmds = re.findall(r"^  ([a-z][a-z-]+)\s{2,}", o.split("Commands:")[1], re.M)
    for c in cmds:
        rc, h, e = cli([c, "--help"])
        subs = (
            re.findall(r"^  ([a-z][a-z-]+)\s{2,}", h.split("Commands:")[1], re.M)
            if "Commands:" in h
            else []
        )
        texts = [(c, h)] + [(f"{c} {s}", cli([c, s, "--help"])[1]) for s in subs]
        for name, t in texts:
            for ln in t.splitlines():
                if len(re.findall(r"(?<![`'\w])stabctl [a-z]", ln)) > 1:
                    bad.append(f"{name}: {ln.strip()[:90]}")
    return not bad, "; ".join(bad)[:500] or "no help line with two commands"


@probe("AB57")
def _():
    """DYR records whose bus is written 103.0, 1.03E2 or -103: refused naming file:line and
    the bus field (as the RAW reader refuses a generator's I = '103.0': 'not an integer',
    and the fault CSV '3.0'), not read as bus 103 without a word.  Round 46: 103.0 and
    1.03E2 read as bus 103, exit 0 (stabctl/io/dyr.py _integer takes any integral float;
    its own message for others says "not an integer")."""
    bad = []
    for tag, b in (("f", "103.0"), ("e", "1.03E2"), ("n", "-103")):
        f = dyr("bus" + tag, REN_DYR.replace("    103 'REGCA1'", f"    {b} 'REGCA1'"))
        ok, why = refused(imp("bus" + tag, f), rf"bus{tag}\.dyr:\d+", "bus" + tag + ".json")
        if not ok:
            bad.append(f"{b}: {why}")
    return not bad, "; ".join(bad) or "all three refused naming file:line"


@probe("AB58")
def _():
    """The RENA DYR with its records in reverse order (REPCA1, REECB1, then REGCA1, GENCLS):
    the same case as the file as written (PSS/E reads DYR records in any order)."""
    recs = re.findall(r"\s*\d+ '[A-Z0-9]+'.*?/", REN_DYR, re.S)
    Path(WD, "rev.dyr").write_text("\n".join(r.strip("\n") for r in reversed(recs)) + "\n")
    a = cli(imp("plainv", dyr("plainv", REN_DYR)))
    b = cli(imp("rev", "rev.dyr"))
    if a[0] != 0 or b[0] != 0:
        return False, f"rc {a[0]}/{b[0]}: {last(b[2])}"
    ca = json.loads(Path(WD, "plainv.json").read_text())
    cb = json.loads(Path(WD, "rev.json").read_text())
    diff = [
        k
        for k in ca
        if k not in ("provenance", "source", "origin", "name", "meta")
        and json.dumps(ca[k], sort_keys=True) != json.dumps(cb.get(k), sort_keys=True)
    ]
    return not diff, "same case" if not diff else f"differ in {diff[:6]}"


@probe("AB59")
def _():
    """ieee14_esd1.xlsx with ESD1 SOCinit written as the text '50%' in one row: refused
    naming ESD1, the row and SOCinit (not ANDES's default 0.5 without a word)."""
    import pandas as pd

    x = pd.read_excel(andes_case("ieee14/ieee14_esd1.xlsx"), sheet_name=None)
    x["ESD1"]["SOCinit"] = x["ESD1"]["SOCinit"].astype(object)
    x["ESD1"].loc[0, "SOCinit"] = "50%"
    with pd.ExcelWriter(os.path.join(WD, "esdpct.xlsx")) as w:
        for k, v in x.items():
            v.to_excel(w, sheet_name=k, index=False)
    return refused(aimp("esdpct.xlsx", "esdpct"), r"SOCinit", "esdpct_o.json")


@probe("AB60")
def _():
    """place --screening given a UTF-16 file and one with a byte-order mark before a
    non-record line: refused naming the file (and line), exit 2, nothing written; the
    UTF-16 one saying so, as the --faults CSV's reader does ("not UTF-8 text ... save it as
    UTF-8").  Round 46: "line 1: not a whole sweep record (cut by a kill?)" for UTF-16."""
    Path(WD, "scr16.jsonl").write_bytes('{"a": 1}\n'.encode("utf-16"))
    a = refused(
        [
            "place",
            "kundur",
            "--faults",
            "DEFAULT",
            "--target-cct-gain",
            "10",
            "--screening",
            "scr16.jsonl",
            "--out",
            "p16.json",
        ],
        r"scr16\.jsonl.*(UTF|encod|text)",
        "p16.json",
    )
    Path(WD, "scrb.jsonl").write_bytes(b"\xef\xbb\xbf" + b'{"a": 1}\n')
    b = refused(
        [
            "place",
            "kundur",
            "--faults",
            "DEFAULT",
            "--target-cct-gain",
            "10",
            "--screening",
            "scrb.jsonl",
            "--out",
            "pb.json",
        ],
        r"scrb\.jsonl.{0,8}1",
        "pb.json",
    )
    return a[0] and b[0], f"UTF-16: {a[1][:120]} | BOM: {b[1][:120]}"


@probe("AB61")
def _():
    """A REECB1 for the GENCLS machine at bus 102 (a control with no REGCA1): refused naming
    file:line (or with --skip-unsupported left out, named) -- not dropped without a word."""
    i = REN_DYR.index("    103 'REECB1'")
    j = REN_DYR.index("    103 'REPCA1'")
    f = dyr("reec102", REN_DYR + REN_DYR[i:j].replace("103 'REECB1'", "102 'REECB1'"))
    a = refused(imp("reec102", f), r"reec102\.dyr:\d+.*REECB1", "reec102.json")
    rc, o, e = cli(imp("reec102s", f, "--skip-unsupported"))
    b = rc == 0 and re.search(r"reec102\.dyr:\d+.*REECB1", o + e) is not None
    return a[0] and b, f"{a[1][:140]} | --skip-unsupported rc {rc}, named {b}"


@probe("AB62")
def _():
    """eig --json on ANDES's ieee14_esd1.xlsx (ten ESD1 batteries) and ieee14_pvd1.json:
    a JSON of the modes (or a refusal naming why), no IndexError (issue 54's eig crash on
    converter cases)."""
    out = []
    ok = True
    for src, name in (("ieee14/ieee14_esd1.xlsx", "e1"), ("ieee14/ieee14_pvd1.json", "p1")):
        rc, o, e = cli(aimp(andes_case(src), name))
        if rc != 0:
            ok = False
            out.append(f"{name} import rc {rc}: {last(e, 80)}")
            continue
        rc, o, e = cli(["eig", name + "_o.json", "--no-q-limits", "--json"], 600)
        good = "Traceback" not in e and (rc == 0 and o.lstrip().startswith("{") or rc == 2)
        ok &= good
        out.append(f"{name}: rc {rc} {last(e, 100) if rc else 'json'}")
    return ok, "; ".join(out)


@probe("AB63")
def _():
    """cct kundur --fault 3 --far-bus 101 --esd-model wecc --esd-pct 5 --json (issue 54's
    crash was simulate's): a JSON CCT, exit 0, no traceback."""
    rc, o, e = cli(
        [
            "cct",
            "kundur",
            "--fault",
            "3",
            "--far-bus",
            "101",
            "--esd-model",
            "wecc",
            "--esd-pct",
            "5",
            "--json",
        ],
        900,
    )
    try:
        d = json.loads(o)
    except Exception:
        return False, f"rc {rc}: {last(e)}"
    return rc == 0 and "Traceback" not in e, f"rc {rc}, cct_s {d.get('cct_s')}"


@probe("AB64")
def _():
    """ieee14_reecb1.json whose REECB1 list is empty ([]) while its REPCA1 names ree 1: refused
    naming REPCA1 and the missing REECB1 1 (or with --skip-unsupported left out, named)."""
    f = andes_json("noreec", "ieee14/ieee14_reecb1.json", lambda d: d.__setitem__("REECB1", []))
    rc, o, e = cli(aimp(f, "noreec"))
    if "Traceback" in e:
        return False, f"traceback: {last(e)}"
    if rc == 2 and "REPCA1" in e:
        return True, last(e, 200)
    return False, f"rc {rc}: {last(e) or last(o)}"


def main():
    KIT.main()


if __name__ == "__main__":
    main()
