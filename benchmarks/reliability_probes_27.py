#!/usr/bin/env python
"""Twenty-seventh reliability round (round 44, part X): variants of issue 54's items 6-9,
its crashes and frictions.

    python benchmarks/reliability_probes_27.py [ID_PREFIX ...]

Runs `python -m stabctl` from this repository (CLONE to test another checkout);
NUMBA_CACHE_DIR is the caller's.  Prints per probe `id ok|SHORT reason`; exits 1 if any is
SHORT.  Every command under a timeout; all work in a temporary directory.  About 4
minutes warm.  The round found short: a DERA1 whose Iqinj limits are swapped imported
and ran (X01), its FreqFlag-1 limit pairs refused only by the first run, unnamed (X02),
and `cct` naming G1 as losing synchronism at an unstable end where the run fails by a
voltage collapse before any machine separates (X03); all fixed.
"""

# ruff: noqa: E501, E401, I001, SIM115, RUF059, RUF021 - a tester's script, kept as written
import json, os, shutil, signal, struct, subprocess, sys, time

from _probe_kit import INHERIT, Kit

KIT = Kit("px44_", xdg=False)
CLONE, ENV, WD, RESULTS = KIT.clone, KIT.env, KIT.wd, KIT.results
RS = CLONE + "/tests/data/psse_runs/"
probe = KIT.probe


def run(args, timeout=200, cwd=WD):
    """(rc, stdout, stderr); the caller's stdin."""
    return KIT.cli(args, timeout, cwd=cwd, stdin=INHERIT)


DERA = open(RS + "DERA_FREQFLAG0/ThreeBus_DERA1.dyr").read()
DRAW = RS + "DERA_FREQFLAG0/ThreeBusMulti.raw"


def dera(name, subs):
    s = DERA
    for a, b in subs:
        assert a in s, a
        s = s.replace(a, b, 1)
    p = WD / f"{name}.dyr"
    p.write_text(s)
    return p


@probe("X01")
def x01():
    """DERA1 with Iqh1 < Iql1 (the limits of Iqinj swapped): REECA1/REECB1's same pair is
    refused at import naming the record ("it must be Iqh1 >= Iql1"); issue 54 item 8:
    impossible converter data must not run.  Expect import-psse to refuse (exit 2, line,
    model, field), or at least simulate to refuse."""
    bad = dera(
        "iq_bad",
        [
            ("0.02  0.02  -99.0  99.0", "0.02  0.02  -0.05  0.05"),
            ("0.8  1.0  -1.0 /", "0.8  -1.0  1.0 /"),
        ],
    )
    rc, o, e = run(["import-psse", DRAW, bad, "-o", "iq_bad.json"])
    if rc == 2 and "Iqh1" in e:
        return True, "refused at import naming Iqh1"
    rc2, o2, e2 = run(
        ["simulate", "iq_bad.json", "--bus-fault", "102:0:0.1", "1", "1.1", "--tf", "2"]
    )
    return (
        False,
        f"import-psse exit {rc} (wrote iq_bad.json), simulate exit {rc2}: {(o2 + e2).strip().splitlines()[-1][:160]!r} -- Iqh1=-1 < Iql1=1 ran",
    )


@probe("X02")
def x02():
    """DERA1 with FreqFlag 1 and contradictory P-path limits (dPmax<0<dPmin, femax<femin,
    Pmax<Pmin): the same pairs of REECA1/REPCA1 are refused at import by name; expect
    import-psse to refuse each naming the field (not a later simulate error that names
    other causes)."""
    why = []
    for name, a, b, field in (
        ("dp", "1.1  0.0  0.5  -0.5  0.02", "1.1  0.0  -0.5  0.5  0.02", "dPmax"),
        ("fe", "99.0  -99.0  1.1  0.0", "-99.0  99.0  1.1  0.0", "femax"),
        ("pm", "1.1  0.0  0.5  -0.5", "0.0  1.1  0.5  -0.5", "Pmax"),
    ):
        p = dera(
            name, [("102 'DERA1' 1   1  0  0  1  0  0", "102 'DERA1' 1   1  1  0  1  0  0"), (a, b)]
        )
        rc, o, e = run(["import-psse", DRAW, p, "-o", f"{name}.json"])
        if rc == 2 and field in e:
            continue
        rc2, o2, e2 = run(["simulate", f"{name}.json", "--tf", "2"])
        said = (o2 + e2).strip().splitlines()[-1] if (o2 + e2).strip() else ""
        why.append(
            f"{field}: import exit {rc}; simulate exit {rc2} {'names it' if field in said else 'without naming ' + field}"
        )
    return not why, "; ".join(why) or "each refused at import by name"


@probe("X03")
def x03():
    """cct's label of its unstable end must say what simulate computes there (issue 54
    item 9: labels say exactly what was computed).  cct kundur --fault 3 --far-bus 101
    --trip 13 120: compare its 'lose synchronism when cleared at T' with simulate at T."""
    rc, o, e = run(
        ["cct", "kundur", "--fault", "3", "--far-bus", "101", "--trip", "13", "120", "--json"]
    )
    d = json.loads(o)
    tu = d["t_unstable_s"]
    rc2, o2, e2 = run(
        [
            "simulate",
            "kundur",
            "--fault",
            "3",
            "--far-bus",
            "101",
            "--clear-cycles",
            round(tu * 60, 6),
            "--trip",
            "13",
            "120",
            "--t-trip",
            round(1 + tu, 6),
        ]
    )
    last = (o2 + e2).strip().splitlines()[-1]
    if d.get("separated_machines") and "voltage collapse" in last:
        return (
            False,
            f"cct: CCT {d['cct_s']} s, separated_machines {d['separated_machines']} ('G1 (bus 1) lose synchronism when cleared at {tu} s'); simulate at {tu} s: exit {rc2} {last[:140]!r}",
        )
    return True, f"cct and simulate agree at {tu} s"


@probe("X04")
def x04():
    """cct against simulate at CCT -+ 2 ms (line fault 3-101 and bus fault 3)."""
    why = []
    for extra in (["--far-bus", "101"], []):
        rc, o, e = run(["cct", "kundur", "--fault", "3", *extra, "--json"])
        c = json.loads(o)["cct_s"]
        for dt, want in ((-0.002, True), (0.002, False)):
            rc2, o2, e2 = run(
                [
                    "simulate",
                    "kundur",
                    "--fault",
                    "3",
                    *extra,
                    "--clear-cycles",
                    round((c + dt) * 60, 6),
                    "--json",
                ]
            )
            st = json.loads(o2)["stable"]
            if st != want:
                why.append(f"{extra} at {c + dt:.3f}: stable={st}")
    return not why, "; ".join(why) or "bracketed"


@probe("X05")
def x05():
    """Overlapping/duplicate bus faults: two overlapping bolted faults at one bus are their
    union (PSS/E keeps the bus shorted until the last clears); two equal X faults are one
    fault of X/2."""

    def ang(*a):
        rc, o, e = run(["simulate", "kundur", *a, "--json"])
        return json.loads(o)["max_angle_from_coi_rad"]

    a1 = ang("--bus-fault", "3", "1", "1.1", "--bus-fault", "3", "1.05", "1.2")
    a2 = ang("--bus-fault", "3", "1", "1.2")
    b1 = ang("--bus-fault", "3:0:0.05", "1", "1.1", "--bus-fault", "3:0:0.05", "1", "1.1")
    b2 = ang("--bus-fault", "3:0:0.025", "1", "1.1")
    ok = abs(a1 - a2) < 1e-6 and abs(b1 - b2) < 1e-6
    return ok, f"union {a1:.4f}/{a2:.4f}, parallel {b1:.4f}/{b2:.4f}"


@probe("X06")
def x06():
    """Odd --step values: heun above its limit, 0, nan, inf refused by name; trapezoid at a
    coarse step warned; an event off the step grid is reported at its own instant."""
    why = []
    for a in (["--step", "0.1"], ["--step", "0"], ["--step", "nan"], ["--step", "inf"]):
        rc, o, e = run(["simulate", "kundur", "--fault", "3", *a])
        if rc != 2 or "--step" not in e and "step" not in e:
            why.append(f"{a}: exit {rc}")
    rc, o, e = run(
        [
            "simulate",
            "kundur",
            "--fault",
            "3",
            "--far-bus",
            "101",
            "--method",
            "trapezoid",
            "--step",
            "0.05",
        ]
    )
    if "warning" not in e:
        why.append("trapezoid 0.05 s not warned")
    rc, o, e = run(
        [
            "simulate",
            "kundur",
            "--fault",
            "3",
            "--far-bus",
            "101",
            "--step",
            "0.015",
            "--t-fault",
            "1.007",
        ]
    )
    if "cleared at 1.107 s" not in o:
        why.append("off-grid event time not kept")
    return not why, "; ".join(why) or "refused, warned, kept"


def crc(data):
    c = 0xFFFF
    for x in data:
        c ^= x << 8
        for _ in range(8):
            c = ((c << 1) ^ 0x1021) & 0xFFFF if c & 0x8000 else (c << 1) & 0xFFFF
    return c


def recording():
    log = open(WD / "serve.log", "w")
    p = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "stabctl",
            "pmu",
            "serve",
            "kundur",
            "--fault",
            "3",
            "--far-bus",
            "101",
            "--speed",
            "0",
            "--port",
            "0",
            "--tf",
            "3",
        ],
        stdout=log,
        stderr=log,
        cwd=WD,
        env=ENV,
        start_new_session=True,
    )
    try:
        end = time.time() + 120
        while time.time() < end and "serving" not in (WD / "serve.log").read_text():
            time.sleep(0.3)
        addr = (WD / "serve.log").read_text().split(" on ")[1].split()[0]
        run(["pmu", "record", addr, "--frames", "181", "-o", "rec.c37"], 120)
    finally:
        try:
            os.killpg(p.pid, signal.SIGTERM)
        except ProcessLookupError:
            pass
        p.wait(10)
    return (WD / "rec.c37").read_bytes()


@probe("X07")
def x07():
    """Recordings (Kundur, 4 PMUs) with a repeated stamp, a frame stamped backwards, every
    value flagged absent (STAT 0x8000), NaN phasors, saturated FREQ: each refused (exit 2,
    nothing written); a 2-frame gap is tracked and said (issue 54 item 7)."""
    b = recording()
    n = int.from_bytes(b[2:4], "big")
    cfg, fr = b[:n], [bytearray(b[n + 104 * i : n + 104 * (i + 1)]) for i in range(181)]

    def fix(f):
        f[-2:] = crc(bytes(f[:-2])).to_bytes(2, "big")
        return f

    def C():
        return [bytearray(f) for f in fr]

    var = {}
    F = C()
    F.insert(71, bytearray(F[70]))
    var["dup"] = F
    F = C()
    F[70], F[71] = F[71], F[70]
    var["back"] = F
    F = C()
    for f in F:
        for k in range(4):
            f[14 + 22 * k : 16 + 22 * k] = struct.pack(">H", 0x8000)
        fix(f)
    var["absent"] = F
    F = C()
    for f in F:
        for k in range(4):
            f[16 + 22 * k : 32 + 22 * k] = struct.pack(">ffff", *[float("nan")] * 4)
        fix(f)
    var["nan"] = F
    F = C()
    for f in F:
        for k in range(4):
            f[32 + 22 * k : 34 + 22 * k] = struct.pack(">h", 32767)
        fix(f)
    var["freqsat"] = F
    why = []
    for name, F in var.items():
        (WD / f"{name}.c37").write_bytes(cfg + b"".join(bytes(f) for f in F))
        rc, o, e = run(
            ["estimate", "track", "kundur", "--source", f"{name}.c37", "--out", f"{name}.csv"]
        )
        if rc != 2 or (WD / f"{name}.csv").exists() or "Traceback" in e:
            why.append(f"{name}: exit {rc} {(o + e).strip()[-120:]!r}")
    F = C()
    (WD / "gap.c37").write_bytes(cfg + b"".join(bytes(f) for f in F[:60] + F[62:]))
    rc, o, e = run(["estimate", "track", "kundur", "--source", "gap.c37", "--out", "gap.csv"])
    if rc != 0 or "2 reporting instants missing" not in o + e:
        why.append(f"gap: exit {rc} {(o + e).strip()[-160:]!r}")
    return not why, "; ".join(why) or "refused or said"


@probe("X08")
def x08():
    """Crashes: a case that is a directory, nested JSON, ports out of range, a non-UTF-8
    file name, `| head -1`: never a traceback."""
    (WD / "dir.json").mkdir()
    (WD / "nest.json").write_text("[" * 100000 + "]" * 100000)
    shutil.copy(CLONE + "/tests/data/psse/smib_v33.raw", WD / os.fsdecode(b"x\xff.raw"))
    why = []
    for a in (
        ["simulate", "dir.json"],
        ["simulate", "nest.json"],
        ["import-andes", "nest.json", "-o", "o.json"],
        [
            "pmu",
            "serve",
            "kundur",
            "--fault",
            "3",
            "--far-bus",
            "101",
            "--each-pmu",
            "--port",
            "65535",
        ],
        ["pmu", "record", "127.0.0.1:65536", "--frames", "2", "-o", "r.c37"],
        [
            "estimate",
            "track",
            "kundur",
            "--source",
            "tcp://127.0.0.1:-1",
            "--frames",
            "2",
            "--out",
            "o.csv",
        ],
        ["import-psse", os.fsdecode(b"x\xff.raw"), "-o", os.fsdecode(b"o\xfe.json")],
        ["simulate", "kundur", "--out", os.fsdecode(b"z\xff.csv")],
    ):
        rc, o, e = run(a, 60)
        if rc != 2 or "Traceback" in e:
            why.append(f"{a[:2]}: exit {rc}")
    for a in (
        ["cases"],
        ["cases", "kundur", "--bus-table"],
        ["simulate", "kundur", "--fault", "3", "--json"],
        ["eig", "kundur"],
    ):
        p = subprocess.run(
            f"{sys.executable} -m stabctl {' '.join(a)} | head -1",
            shell=True,
            capture_output=True,
            text=True,
            timeout=120,
            cwd=WD,
            env=ENV,
        )
        if "Traceback" in p.stderr or "Broken pipe" in p.stderr:
            why.append(f"{a} | head: {p.stderr[-100:]!r}")
    return not why, "; ".join(why) or "no traceback"


@probe("X09")
def x09():
    """cct and simulate with storage options without --esd-pct, and --circuit without
    --far-bus: refused by name (issue 54 item 8's `--esd-model wecc` without `--esd-pct`)."""
    why = []
    for cmd in ("simulate", "cct"):
        for a in (
            ["--v-gate", "0.5"],
            ["--deadband-hz", "0.3"],
            ["--esd-model", "wecc"],
            ["--hysteresis-hz", "0.05"],
            ["--circuit", "2"],
        ):
            rc, o, e = run([cmd, "kundur", "--fault", "3", *a], 60)
            if rc != 2 or a[0] not in e:
                why.append(f"{cmd} {a}: exit {rc}")
    return not why, "; ".join(why) or "refused by name"


def main():
    KIT.main(
        (x01, x02, x03, x04, x05, x06, x07, x08, x09),
        summary="{ok} ok, {short} SHORT",
        keep_any=True,
        kept=None,
    )


if __name__ == "__main__":
    main()
