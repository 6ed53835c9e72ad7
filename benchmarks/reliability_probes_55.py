#!/usr/bin/env python
"""Round 59 (BB): silently wrong results found by invariance (metamorphic) checks.

A PSS/E RAW + DYR case is transformed in a way that leaves the physics unchanged, imported
again with `import-psse`, and the same study is run before and after: `simulate --json
--out X.npz` (every bus voltage magnitude and angle, the centre-of-inertia angle, each
machine's angle by its (bus, ID), the largest angle from the COI, the verdict), `cct
--json` (the CCT, its bracket) and `screen --json` (each bus's CCT and verdict).  The
runs share their step, so a difference beyond ~1e-6 (rad, pu) or another 1 ms CCT cell
with exit 0 and no warning is a silently wrong result.

    CLONE=<clone> PYTHONPATH=<clone> python benchmarks/reliability_probes_55.py [BB01 BB03 ...]

Cases: ANDES's IEEE 14 RAW (v32) + DYR (GENROU, ST2CUT, ESST3A, EXST1, IEEEST with
ICS 3 = electrical power on MBASE, TGOV1, IEEEG1; its ANDES Toggle records dropped in
every variant alike), PSS/E's ThreeBusMulti IEEEST run and the OMIB PSS2A run
(tests/data/psse_runs; PSS2A's second input is the electrical power), the powsybl IEEE 14
v33 and v35 files of tests/data/psse.  Transforms (POM v33 "Power Flow Raw Data File
Contents": branch R, X, B and line shunts in pu on SBASE, CZ 1 transformer R, X and CM 1
MAG1, MAG2 on SBASE, loads, fixed and switched shunts in MW / Mvar, generator PG, QG, QT,
QB, PT, PB in MW / Mvar, ZSORCE and every DYR machine, exciter, governor and stabiliser
quantity on MBASE):

  BB01-03 a generator split into two identical units (each half PG, QG, QT, QB, PT, PB,
          MBASE; its DYR records duplicated for ID '2'): the swing unit, a unit with
          IEEEST on electrical power, a unit of PSS2A with its power input;
  BB04-05 a branch (and a CZ 1 transformer) replaced by two parallel circuits of double
          R and X and half B; a trip of both circuits against a trip of the original;
  BB06-07 SBASE 100 -> 200 MVA with R, X doubled and B halved (IEEE 14; the
          three-bus IEEEST case whose infinite bus has MBASE 100);
  BB08    records reordered (buses, loads, generators, branches, transformers,
          switched shunts, DYR records) and records out of service added (a
          parallel circuit ahead of the faulted one, a generator with its GENCLS record
          at a bus that has one in service, a load, a fixed shunt);
  BB09    buses renumbered in RAW and DYR (simulate, cct, screen; eig's was AH11);
  BB10-11 a load split in two IDs; a load moved behind a near-zero-impedance jumper to a
          new bus (X 1e-6 pu and X = PSS/E's THRSHZ 1e-4 pu);
  BB12    the same IEEE 14 case as v33 and v35 (powsybl's files) with one DYR;
  BB15    IEEE 14's transformers written as CW 2 (kV) and CZ 2 (SBASE1-2 50 MVA), at
          SBASE 100 and 200;
  BB16-17 every case of tests/data/psse_runs (machines of each model, converter plants
          REGCA1/REECA1/REPCA1, DERA1, CSVGN1): its most modelled unit split; SBASE 200;
  BB13-14 Kundur's built-in case file: machine 1 split into two of 450 MVA (pfrac,
          qfrac 0.5; its exciter, PSS and governor rows duplicated); base_mva 200 with
          the bus table's powers, shunts and Q limits halved and the branches' r, x
          doubled, b halved.

Extends (no exact repeat): reliability_probes_8.py A13 (a second identical circuit added,
its two CCTs equal: here a branch replaced by two equivalent halves and compared with the
original), reliability_probes_38.py AH11 (Kundur's case file renumbered, eig only: here
RAW + DYR renumbered, simulate, cct, screen), reliability_probes_10.py (renumbered IEEE 14
for estimate), reliability_probes_13.py (SMIB on machine bases 37-500 MVA against the
equal-area criterion: here SBASE itself, a whole system), reliability_probes_24.py and
_8.py (an out-of-service machine named: here its effect on the results, and placed at a
bus with another machine), tests/io/test_psse_v35.py (power flow: here the dynamics).

Found (round 59): BB16 and BB17 SHORT for the REGCA1 + REECB1 + REPCA1 plant of the
RENA runs (every flag variant): SBASE 100 -> 200 alone (MBASE 100 kept) moves the plant's
fault and post-fault Q by up to 21-29 Mvar and bus 103's voltage by 0.018 pu (at 3.9 s:
16.7 vs 36.0 Mvar, 1.0203 vs 1.0350 pu); the plant split in two halves likewise; PSS/E's
parameters are on MBASE, so neither may change a result (the converter parameters are
put on the system base in stabctl.models.converters.converter_params, only the fields
marked as powers or impedances scaled).  Every machine model, exciter, stabiliser,
governor, DERA1 and CSVGN1 (CBASE halved with its unit) is invariant to 1e-9 or better.
BB11 SHORT is a modelling note: a branch of R 0, X 1e-4 pu (PSS/E's THRSHZ: a jumper)
is an impedance in stabctl, 1.1e-5 rad and 3.7e-6 pu from the merged buses; X 1e-6,
2e-6 rad.  BB14's 2.3e-6 rad arose only while the bolted fault is on (PST's -j1e7 pu
on the system base, twice the admittance at 200 MVA), as BB06's 8e-7: BB14 now judges the
same physical fault reactance and shows the bolted difference beside it.

One line per probe (id, ok or SHORT, figures), then the counts.  The work directory (the
variants' RAW, DYR, case and result files; the commands are printed with SHORT) is kept
with KEEP=1.  About 10-20 minutes on two busy cores with a warm kernel cache.
"""

# ruff: noqa
import importlib.util
import json
import os
import random
import re
import sys
from pathlib import Path

import numpy as np

from _probe_kit import Kit, tail

KIT = Kit("probes_bb59.", line="{pid:<6} {state:<5} {why}", timed=True)
CLONE, ENV, WD = Path(KIT.clone), KIT.env, KIT.wd
run, rec, probe = KIT.run, KIT.rec, KIT.probe

ANDES = Path(importlib.util.find_spec("andes").origin).parent / "cases"
PSR = CLONE / "tests" / "data" / "psse_runs"
PSSE = CLONE / "tests" / "data" / "psse"
TOL = 1e-6  # rad, pu: the same step, the same physics

# ============================================================================ RAW v32/v33
BUS, LOAD, FSH, GEN, BR, XF, AREA = 0, 1, 2, 3, 4, 5, 6
SWSH = 16  # v32/v33 section order: ... owner 14, FACTS 15, switched shunts 16
_TOK = re.compile(r"'[^']*'|\"[^\"]*\"|[^,\s]+")


def _cut(line):
    """(text before the first unquoted '/', the rest)."""
    q = None
    for i, c in enumerate(line):
        if q:
            if c == q:
                q = None
        elif c in "'\"":
            q = c
        elif c == "/":
            return line[:i], line[i:]
    return line, ""


def toks(line):
    return _TOK.findall(_cut(line)[0])


def f(x):
    return float(x)


def g(v):
    """A number as a RAW field."""
    return f"{v:.12g}"


def sid(tok):
    """An ID as PSS/E compares it: unquoted, blanks trimmed."""
    return tok.strip("'\"").strip()


class Raw:
    """A v32/v33 RAW file: its 3 heading lines, its sections (records: lists of lines,
    each a list of fields as written), each section's end line and what follows Q."""

    def __init__(self, text):
        lines = text.splitlines()
        self.head = lines[:3]
        self.sections, self.ends, self.tail = [], [], []
        cur, i = [], 3
        while i < len(lines):
            s = lines[i].strip()
            if s.upper() == "Q":
                self.tail = lines[i:]
                break
            if re.match(r"^0\s*(/|$)", s):
                self.sections.append(cur)
                self.ends.append(lines[i])
                cur, i = [], i + 1
                continue
            if not s:
                i += 1
                continue
            if len(self.sections) == XF:
                n = 4 if int(toks(lines[i])[2]) == 0 else 5
                cur.append([toks(x) for x in lines[i : i + n]])
                i += n
                continue
            cur.append([toks(lines[i])])
            i += 1

    def copy(self):
        return Raw(self.text())

    def text(self):
        out = list(self.head)
        for recs, end in zip(self.sections, self.ends):
            out += [", ".join(ln) for r in recs for ln in r]
            out.append(end)
        return "\n".join(out + self.tail) + "\n"

    @property
    def sbase(self):
        return f(toks(self.head[0])[1])

    def set_sbase(self, v):
        body, rest = _cut(self.head[0])
        t = _TOK.findall(body)
        t[1] = g(v)
        self.head[0] = ", ".join(t) + "     " + rest


def dyr_records(text):
    """The DYR records (field lists) whose first field is a bus number (ANDES's Toggle
    records of ieee14.dyr are none)."""
    recs, cur = [], []
    for line in text.splitlines():
        body, slash = _cut(line)
        cur += _TOK.findall(body)
        if slash:
            if cur and re.fullmatch(r"-?\d+", cur[0]):
                recs.append(cur)
            cur = []
    return recs


def dyr_text(recs):
    return "".join(" ".join(r) + " /\n" for r in recs)


def write(name, raw, dyr):
    """WD/name.raw, WD/name.dyr."""
    (WD / f"{name}.raw").write_text(raw.text() if isinstance(raw, Raw) else raw)
    (WD / f"{name}.dyr").write_text(dyr_text(dyr) if isinstance(dyr, list) else dyr)
    return WD / f"{name}.raw", WD / f"{name}.dyr"


IMPORTED = {}


def imp(name, raw, dyr, *extra):
    """import-psse of WD/name.raw + .dyr -> WD/name.json: (path, stderr) or raises."""
    if name in IMPORTED:
        return IMPORTED[name]
    r, d = write(name, raw, dyr)
    out = WD / f"{name}.json"
    rc, o, e, _ = run(["import-psse", r, d, "-o", out, *extra], timeout=600)
    if rc != 0:
        raise RuntimeError(f"import-psse {name} rc {rc}: {tail(e, 300)}")
    IMPORTED[name] = (out, e)
    return out, e


def warn_lines(err):
    return [ln for ln in err.splitlines() if "warning" in ln.lower()]


# ============================================================================ the studies
def case_machines(path):
    """[(bus, ID)] of the case file's machines in machine order."""
    d = json.loads(Path(path).read_text())
    t = d["tables"]["machines"]
    k = t["columns"].index("bus")
    ids = d.get("machine_ids") or {}
    return [(int(r[k]), sid(ids.get(str(n), "1"))) for n, r in enumerate(t["rows"], 1)]


def simulate(tag, case, args):
    """simulate CASE ARGS --json --out WD/tag.npz: (json, npz dict, stderr, command)."""
    npz = WD / f"{tag}.npz"
    cmd = ["simulate", case, *args, "--json", "--out", npz]
    rc, o, e, _ = run(cmd, timeout=900)
    shown = "python -m stabctl " + " ".join(map(str, cmd))
    if rc != 0:
        raise RuntimeError(f"{shown}: rc {rc}: {tail(e, 300)}")
    with np.load(npz) as z:
        arrays = {k: z[k] for k in z.files}
    return json.loads(o), arrays, e, shown


def coi(z):
    w = np.asarray(z["inertia"], float)
    a = z["angle"]
    if w.ndim == 1:
        return (a * w).sum(1) / w.sum()
    return (a * w).sum(1) / w.sum(1)


def compare(A, B, busmap=None, macmap=None, skip_buses=()):
    """Differences of run B from run A (each simulate()'s): {what: size}, and text
    problems (grid, verdict).  busmap: A's bus -> B's; macmap: B's (bus, ID) -> A's."""
    (ja, za, _, _), (jb, zb, _, _) = A, B
    d, bad = {}, []
    if za["t"].shape != zb["t"].shape or np.max(np.abs(za["t"] - zb["t"])) > 1e-12:
        return {"grid": np.inf}, [f"time grids differ ({za['t'].size} vs {zb['t'].size} points)"]
    ba, bb = [int(x) for x in za["buses"]], [int(x) for x in zb["buses"]]
    dv = da = 0.0
    for i, n in enumerate(ba):
        if n in skip_buses:
            continue
        m = (busmap or {}).get(n, n)
        if m not in bb:
            bad.append(f"bus {n} (as {m}) missing")
            continue
        j = bb.index(m)
        dv = max(dv, float(np.max(np.abs(za["vmag"][:, i] - zb["vmag"][:, j]))))
        da = max(da, float(np.max(np.abs(za["vang"][:, i] - zb["vang"][:, j]))))
    d["vmag"], d["vang"] = dv, da
    d["coi"] = float(np.max(np.abs(coi(za) - coi(zb))))
    d["maxang"] = abs(ja["max_angle_from_coi_rad"] - jb["max_angle_from_coi_rad"])
    if ja["verdict"] != jb["verdict"]:
        bad.append(f"verdict {ja['verdict']} -> {jb['verdict']}")
    if macmap is not None:
        ka, kb = macmap["A"], macmap["B"]
        dm = 0.0
        for j, key in enumerate(kb):
            src = macmap["map"](key)
            if src not in ka:
                bad.append(f"machine {key} has no counterpart")
                continue
            i = ka.index(src)
            dm = max(dm, float(np.max(np.abs(za["angle"][:, i] - zb["angle"][:, j]))))
        d["mac_angle"] = dm
    sa, sb = ja.get("stiff_intervals") or [], jb.get("stiff_intervals") or []
    if len(sa) != len(sb):
        bad.append(f"stiff intervals {len(sa)} -> {len(sb)}")
    return d, bad


def judged(d, bad, tol=TOL):
    worst = max(d.values()) if d else np.inf
    ok = not bad and worst <= tol
    txt = ", ".join(f"{k} {v:.1e}" for k, v in d.items())
    return ok, txt + ("; " + "; ".join(bad) if bad else "")


def cct(tag, case, args):
    cmd = ["cct", case, *args, "--json"]
    rc, o, e, _ = run(cmd, timeout=1800)
    shown = "python -m stabctl " + " ".join(map(str, cmd))
    if rc != 0:
        raise RuntimeError(f"{shown}: rc {rc}: {tail(e, 300)}")
    j = json.loads(o)
    return j, shown


def cct_key(j):
    """(CCT, its stable and unstable ends, half-step CCT), s."""
    return (j.get("cct_s"), (j.get("t_stable_s"), j.get("t_unstable_s")), j.get("cct_half_step_s"))


def screen(tag, case, buses):
    out = WD / f"{tag}.jsonl"
    if out.exists():
        out.unlink()
    cmd = [
        "screen",
        case,
        "--buses",
        ",".join(map(str, buses)),
        "--workers",
        1,
        "--out",
        out,
        "--json",
    ]
    rc, o, e, _ = run(cmd, timeout=1800)
    shown = "python -m stabctl " + " ".join(map(str, cmd))
    if rc != 0:
        raise RuntimeError(f"{shown}: rc {rc}: {tail(e, 300)}")
    return json.loads(o), shown


def screen_rows(j, busmap=None):
    """{bus (mapped back to A's numbering): (cct_s, verdict-ish)} of a screen --json."""
    rows = j if isinstance(j, list) else (j.get("results") or j.get("rows") or [])
    inv = {v: k for k, v in (busmap or {}).items()}
    out = {}
    for r in rows:
        b = r.get("bus")
        out[inv.get(b, b)] = (r.get("cct_s"), r.get("verdict") or r.get("status"))
    return out


# ============================================================================ the cases
def ieee14():
    raw = Raw((ANDES / "ieee14" / "ieee14.raw").read_text())
    dyr = dyr_records((ANDES / "ieee14" / "ieee14.dyr").read_text())
    return raw, dyr


def threebus():
    raw = Raw((PSR / "IEEEST" / "ThreeBusMulti.raw").read_text())
    dyr = dyr_records((PSR / "IEEEST" / "ThreeBus_IEEEST.dyr").read_text())
    return raw, dyr


def omib_pss2a():
    raw = Raw((PSR / "PSS2A" / "OMIB.raw").read_text())
    dyr = dyr_records((PSR / "PSS2A" / "OMIB_PSS2A.dyr").read_text())
    return raw, dyr


# ============================================================================ transforms
def split_gen(raw, dyr, bus, gid="1", new="2"):
    """Generator (bus, gid) -> two identical halves gid and new (RAW and DYR)."""
    raw, dyr = raw.copy(), [list(r) for r in dyr]
    recs = raw.sections[GEN]
    for k, r in enumerate(recs):
        t = r[0]
        if int(t[0]) == bus and sid(t[1]) == gid:
            for i in (2, 3, 4, 5, 8, 16, 17):  # PG QG QT QB MBASE PT PB
                t[i] = g(f(t[i]) / 2)
            twin = list(t)
            twin[1] = f"'{new}'"
            recs.insert(k + 1, [twin])
            break
    else:
        raise KeyError((bus, gid))
    more = []
    for r in dyr:
        more.append(r)
        if int(r[0]) == bus and sid(r[2]) == gid:
            if sid(r[1]) == "CSVGN1":  # CBASE (its 10th parameter) in Mvar: halved too
                r[12] = g(f(r[12]) / 2)
            more.append([r[0], r[1], f"'{new}'", *r[3:]])
    return raw, more


def parallel_branch(raw, i, j):
    """Branch i-j '1' -> circuits '1' and '2', each 2R, 2X, B/2 (line shunts /2)."""
    raw = raw.copy()
    recs = raw.sections[BR]
    for k, r in enumerate(recs):
        t = r[0]
        if {int(t[0]), abs(int(t[1]))} == {i, j}:
            t[3], t[4] = g(2 * f(t[3])), g(2 * f(t[4]))
            for n in (5, 9, 10, 11, 12):
                t[n] = g(f(t[n]) / 2)
            twin = list(t)
            twin[2] = "'2'"
            recs.insert(k + 1, [twin])
            return raw
    raise KeyError((i, j))


def parallel_xf(raw, i, j):
    """Two-winding CZ 1, CM 1 transformer i-j -> two of 2 (R1-2, X1-2), MAG / 2."""
    raw = raw.copy()
    recs = raw.sections[XF]
    for k, r in enumerate(recs):
        t = r[0]
        if {int(t[0]), abs(int(t[1]))} == {i, j} and int(t[2]) == 0:
            assert int(t[5]) == 1 and int(t[6]) == 1, "CZ 1, CM 1 only"
            t[7], t[8] = g(f(t[7]) / 2), g(f(t[8]) / 2)
            r[1][0], r[1][1] = g(2 * f(r[1][0])), g(2 * f(r[1][1]))
            twin = [list(x) for x in r]
            twin[0][3] = "'2'"
            recs.insert(k + 1, twin)
            return raw
    raise KeyError((i, j))


def rebase(raw, k):
    """SBASE x k with every system-base quantity rescaled (POM v33): branch R, X x k and
    B, GI, BI, GJ, BJ / k; CZ 1 transformer R, X x k; CM 1 MAG1, MAG2 / k."""
    raw = raw.copy()
    raw.set_sbase(raw.sbase * k)
    for r in raw.sections[BR]:
        t = r[0]
        t[3], t[4] = g(k * f(t[3])), g(k * f(t[4]))
        for n in (5, 9, 10, 11, 12):
            t[n] = g(f(t[n]) / k)
    for r in raw.sections[XF]:
        t = r[0]
        if int(t[6]) == 1:
            t[7], t[8] = g(f(t[7]) / k), g(f(t[8]) / k)
        if int(t[5]) == 1:
            z = r[1]
            pairs = (0, 1) if int(t[2]) == 0 else (0, 1, 3, 4, 6, 7)
            for n in pairs:
                z[n] = g(k * f(z[n]))
    return raw


def reorder(raw, dyr, seed, oos=None):
    """Records shuffled (buses, loads, fixed shunts, generators, branches, transformers,
    switched shunts; DYR records), every line written from its other end; `oos(raw,
    dyr)` adds records out of service."""
    raw, dyr = raw.copy(), [list(r) for r in dyr]
    rnd = random.Random(seed)
    for s in (BUS, LOAD, FSH, GEN, BR, XF, SWSH):
        if s < len(raw.sections):
            rnd.shuffle(raw.sections[s])
    rnd.shuffle(dyr)
    for r in raw.sections[BR]:  # every line written from its other end (GI, BI <-> GJ, BJ)
        t = r[0]
        t[0], t[1] = t[1], t[0]
        t[9], t[10], t[11], t[12] = t[11], t[12], t[9], t[10]
    if oos:  # after the shuffle: each ahead of its in-service namesake
        oos(raw, dyr)
    return raw, dyr


def renumber(raw, dyr, mp):
    """Bus numbers n -> mp[n] everywhere (RAW: buses, loads, shunts, generators and their
    IREG, branches, transformers and CONT, areas' ISW, switched shunts and SWREM; DYR)."""
    raw, dyr = raw.copy(), [list(r) for r in dyr]

    def m(tok):
        v = int(tok)
        if v == 0:
            return tok
        return str(int(np.sign(v)) * mp[abs(v)])

    for r in raw.sections[BUS]:
        r[0][0] = m(r[0][0])
    for s in (LOAD, FSH):
        for r in raw.sections[s]:
            r[0][0] = m(r[0][0])
    for r in raw.sections[GEN]:
        r[0][0], r[0][7] = m(r[0][0]), m(r[0][7])
    for r in raw.sections[BR]:
        r[0][0], r[0][1] = m(r[0][0]), m(r[0][1])
    for r in raw.sections[XF]:
        r[0][0], r[0][1], r[0][2] = m(r[0][0]), m(r[0][1]), m(r[0][2])
        for w in range(2, len(r) - (1 if int(r[0][2]) == 0 else 0)):
            if len(r[w]) > 7:
                r[w][7] = m(r[w][7])
    for r in raw.sections[AREA]:
        r[0][1] = m(r[0][1])
    for r in raw.sections[SWSH]:
        r[0][0], r[0][6] = m(r[0][0]), m(r[0][6])
    for r in dyr:
        r[0] = str(mp[int(r[0])])
    return raw, dyr


def split_load(raw, bus):
    raw = raw.copy()
    recs = raw.sections[LOAD]
    for k, r in enumerate(recs):
        t = r[0]
        if int(t[0]) == bus:
            for i in range(5, 11):
                t[i] = g(f(t[i]) / 2)
            twin = list(t)
            twin[1] = "'2'"
            recs.insert(k + 1, [twin])
            return raw
    raise KeyError(bus)


def jumper(raw, bus, new, x):
    """The loads of `bus` moved to a new bus `new` (its bus record a copy, IDE 1) behind a
    branch bus-new of R 0, X x, B 0."""
    raw = raw.copy()
    for r in raw.sections[BUS]:
        if int(r[0][0]) == bus:
            t = list(r[0])
            t[0], t[1], t[3] = str(new), "'JUMPER'", "1"
            raw.sections[BUS].append([t])
            break
    for r in raw.sections[LOAD]:
        if int(r[0][0]) == bus:
            r[0][0] = str(new)
    tmpl = list(raw.sections[BR][0][0])
    tmpl[0], tmpl[1], tmpl[2] = str(bus), str(new), "'1'"
    tmpl[3], tmpl[4], tmpl[5] = "0", g(x), "0"
    for n in (9, 10, 11, 12):
        tmpl[n] = "0"
    tmpl[13] = "1"
    raw.sections[BR].append([tmpl])
    return raw


def other_forms(raw, sbase12=50.0):
    """Every two-winding CW 1, CZ 1 transformer written as CW 2 (WINDV in kV: times its
    bus's BASKV, NOMV 0 = BASKV) and CZ 2 (R, X on SBASE1-2 = sbase12 MVA: times
    sbase12 / SBASE): the same transformer (POM Transformer Data)."""
    raw = raw.copy()
    kv = {int(r[0][0]): f(r[0][2]) for r in raw.sections[BUS]}
    for r in raw.sections[XF]:
        t = r[0]
        if int(t[2]) != 0 or int(t[4]) != 1 or int(t[5]) != 1:
            continue
        i, j = int(t[0]), abs(int(t[1]))
        t[4], t[5] = "2", "2"
        r[1][0] = g(f(r[1][0]) * sbase12 / raw.sbase)
        r[1][1] = g(f(r[1][1]) * sbase12 / raw.sbase)
        r[1][2] = g(sbase12)
        r[2][0], r[2][1] = g(f(r[2][0]) * kv[i]), "0"
        r[3][0], r[3][1] = g(f(r[3][0]) * kv[j]), "0"
    return raw


# ============================================================================ probes
SIM14 = ["--fault", 4, "--far-bus", 5, "--clear-cycles", 6, "--tf", 5]
CCT14 = ["--fault", 4, "--far-bus", 5]
BASES = {}


def base14():
    if "14" not in BASES:
        raw, dyr = ieee14()
        path, e = imp("i14", raw, dyr)
        BASES["14"] = (raw, dyr, path, simulate("i14", path, SIM14))
    return BASES["14"]


def base14_cct():
    if "14cct" not in BASES:
        _, _, path, _ = base14()
        BASES["14cct"] = cct("i14", path, CCT14)
    return BASES["14cct"]


def base14_screen():
    if "14scr" not in BASES:
        _, _, path, _ = base14()
        BASES["14scr"] = screen("i14_scr", path, [2, 9, 13])
    return BASES["14scr"]


def _split_probe(name, build, sim_args, bus):
    raw, dyr, basecase, A = build()
    r2, d2 = split_gen(raw, dyr, bus)
    path, e = imp(f"{name}_split{bus}", r2, d2)
    B = simulate(f"{name}_split{bus}", path, sim_args)
    ka, kb = case_machines(basecase), case_machines(path)
    mm = {"A": ka, "B": kb, "map": lambda key: (key[0], "1") if key[0] == bus else key}
    d, bad = compare(A, B, macmap=mm)
    ok, txt = judged(d, bad)
    new = [w for w in warn_lines(B[2]) if w not in warn_lines(A[2])]
    return ok, (
        f"{name} generator at bus {bus} split in two halves: {txt}"
        + (f"; new warnings {len(new)}: {tail(' '.join(new), 200)}" if new else "; no new warning")
        + ("" if ok else f" [{A[3]} vs {B[3]}]")
    )


@probe("BB01")
def _():
    """IEEE 14: the swing generator (bus 1: GENROU, ST2CUT, ESST3A, TGOV1) split."""
    return _split_probe("i14", base14, SIM14, 1)


@probe("BB02")
def _():
    """IEEE 14: generator 3 (IEEEST on electrical power, ICS 3: MBASE base) split, and
    generator 2 (ST2CUT, EXST1, IEEEG1) split: trajectories, and the CCT of 4-5."""
    ok3, t3 = _split_probe("i14", base14, SIM14, 3)
    ok2, t2 = _split_probe("i14", base14, SIM14, 2)
    A, _ = base14_cct()
    path, _ = IMPORTED["i14_split2"]
    B, shown = cct("i14_split2", path, CCT14)
    same = cct_key(A)[:2] == cct_key(B)[:2]
    return ok3 and ok2 and same, (
        f"{t3} | {t2} | CCT 4-5 {A.get('cct_s')} -> {B.get('cct_s')} "
        f"(bracket {cct_key(A)[1]} -> {cct_key(B)[1]})" + ("" if same else f" [{shown}]")
    )


@probe("BB03")
def _():
    """ThreeBusMulti IEEEST (ICS 1 speed) and OMIB PSS2A (ICS2 3 power): the GENROU unit
    with its exciter and stabiliser split."""

    def b3():
        if "3b" not in BASES:
            raw, dyr = threebus()
            p, _ = imp("tb", raw, dyr)
            BASES["3b"] = (
                raw,
                dyr,
                p,
                simulate("tb", p, ["--trip", 101, 102, "--t-trip", 1, "--tf", 5]),
            )
        return BASES["3b"]

    def om():
        if "om" not in BASES:
            raw, dyr = omib_pss2a()
            p, _ = imp("om", raw, dyr)
            BASES["om"] = (
                raw,
                dyr,
                p,
                simulate("om", p, ["--bus-fault", "1:0:0.3", 1, 1.05, "--tf", 6]),
            )
        return BASES["om"]

    ok1, t1 = _split_probe("tb", b3, ["--trip", 101, 102, "--t-trip", 1, "--tf", 5], 102)
    ok2, t2 = _split_probe("om", om, ["--bus-fault", "1:0:0.3", 1, 1.05, "--tf", 6], 1)
    return ok1 and ok2, f"{t1} | {t2}"


@probe("BB04")
def _():
    """IEEE 14: line 2-3 as two circuits of 2R, 2X, B/2: fault 4-5 the same; both
    circuits tripped = the original tripped; the CCT of 4-5."""
    raw, dyr, basecase, A = base14()
    r2 = parallel_branch(raw, 2, 3)
    path, e = imp("i14_par23", r2, dyr)
    B = simulate("i14_par23", path, SIM14)
    d1, b1 = compare(A, B)
    ok1, t1 = judged(d1, b1)
    TA = simulate("i14_trip23", basecase, ["--trip", 2, 3, "--t-trip", 1, "--tf", 5])
    TB = simulate(
        "i14_par23_trip", path, ["--trip", 2, "3:1", "--trip", 2, "3:2", "--t-trip", 1, "--tf", 5]
    )
    d2, b2 = compare(TA, TB)
    ok2, t2 = judged(d2, b2)
    CA, _ = base14_cct()
    CB, shown = cct("i14_par23", path, CCT14)
    ok3 = cct_key(CA)[:2] == cct_key(CB)[:2]
    return ok1 and ok2 and ok3, (
        f"fault 4-5: {t1}"
        + ("" if ok1 else f" [{A[3]} vs {B[3]}]")
        + f" | trip of both vs the original: {t2}"
        + ("" if ok2 else f" [{TA[3]} vs {TB[3]}]")
        + f" | CCT {CA.get('cct_s')} -> {CB.get('cct_s')}"
        + ("" if ok3 else f" [{shown}]")
    )


@probe("BB05")
def _():
    """IEEE 14: transformer 4-7 (CZ 1) as two of double R, X: fault 4-5 the same."""
    raw, dyr, basecase, A = base14()
    r2 = parallel_xf(raw, 4, 7)
    path, e = imp("i14_par47", r2, dyr)
    B = simulate("i14_par47", path, SIM14)
    d, b = compare(A, B)
    ok, t = judged(d, b)
    return ok, f"transformer 4-7 doubled: {t}" + ("" if ok else f" [{A[3]} vs {B[3]}]")


@probe("BB06")
def _():
    """IEEE 14 at SBASE 200 MVA (R, X x 2, B / 2; MW, Mvar, MBASE as they are): angles,
    voltages, COI; the CCT of 4-5; screen of buses 2, 9, 13."""
    raw, dyr, basecase, A = base14()
    r2 = rebase(raw, 2.0)
    path, e = imp("i14_sb200", r2, dyr)
    B = simulate("i14_sb200", path, SIM14)
    ka, kb = case_machines(basecase), case_machines(path)
    d, b = compare(A, B, macmap={"A": ka, "B": kb, "map": lambda k: k})
    # the electrical power in MW: pu on SBASE x SBASE
    pa = A[1]["pelect"] * 100.0
    pb = B[1]["pelect"] * 200.0
    d["pelect_MW/100"] = float(np.max(np.abs(pa - pb))) / 100.0
    ok1, t1 = judged(d, b)
    CA, _ = base14_cct()
    CB, shown = cct("i14_sb200", path, CCT14)
    ok2 = cct_key(CA)[:2] == cct_key(CB)[:2]
    SA, _ = base14_screen()
    SB, shs = screen("i14_sb200_scr", path, [2, 9, 13])
    ra, rb = screen_rows(SA), screen_rows(SB)
    ok3 = ra == rb and bool(ra)
    return ok1 and ok2 and ok3, (
        f"SBASE 200: {t1}"
        + ("" if ok1 else f" [{A[3]} vs {B[3]}]")
        + f" | CCT {CA.get('cct_s')} -> {CB.get('cct_s')}"
        + ("" if ok2 else f" [{shown}]")
        + f" | screen {ra} -> {rb}"
        + ("" if ok3 else f" [{shs}]")
    )


@probe("BB07")
def _():
    """ThreeBusMulti IEEEST at SBASE 200 (its infinite bus GENCLS H 0 on MBASE 100)."""
    raw, dyr = threebus()
    pa, _ = imp("tb", raw, dyr)
    args = ["--trip", 101, 102, "--t-trip", 1, "--tf", 5]
    A = BASES["3b"][3] if "3b" in BASES else simulate("tb", pa, args)
    pb, _ = imp("tb_sb200", rebase(raw, 2.0), dyr)
    B = simulate("tb_sb200", pb, args)
    d, b = compare(A, B)
    ok, t = judged(d, b)
    return ok, f"three-bus IEEEST at SBASE 200: {t}" + ("" if ok else f" [{A[3]} vs {B[3]}]")


def _oos(raw, dyr):
    """Records out of service: circuit '9' of 4-5 ahead of the in-service one, generator
    2 '9' (50 MW) with a GENCLS record, load 5 '9', fixed shunt at 9."""
    br = raw.sections[BR]
    k = next(i for i, r in enumerate(br) if {int(r[0][0]), int(r[0][1])} == {4, 5})
    t = list(br[k][0])
    t[2], t[13] = "'9'", "0"
    t[3], t[4] = "0.5", "0.9"
    br.insert(k, [t])
    gens = raw.sections[GEN]
    k = next(i for i, r in enumerate(gens) if int(r[0][0]) == 2)
    t = list(gens[k][0])
    t[1], t[2], t[3], t[14] = "'9'", "50", "10", "0"
    gens.insert(k, [t])
    dyr.append(["2", "'GENCLS'", "'9'", "3.0", "0.0"])
    loads = raw.sections[LOAD]
    k = next(i for i, r in enumerate(loads) if int(r[0][0]) == 5)
    t = list(loads[k][0])
    t[1], t[2], t[5], t[6] = "'9'", "0", "30", "10"
    loads.insert(k, [t])
    raw.sections[FSH].append([["9", "'1'", "0", "0.0", "25.0"]])


@probe("BB08")
def _():
    """IEEE 14 with every section and the DYR records shuffled and records out of service
    added (circuit 4-5 '9' ST 0 ahead of '1', generator 2 '9' STAT 0 with GENCLS, load
    5 '9' and a fixed shunt at 9 STATUS 0): fault 4-5 (circuit 1) and its CCT the same."""
    raw, dyr, basecase, A = base14()
    r2, d2 = reorder(raw, dyr, 59, _oos)
    path, e = imp("i14_reord", r2, d2)
    B = simulate("i14_reord", path, SIM14)
    ka, kb = case_machines(basecase), case_machines(path)
    d, b = compare(A, B, macmap={"A": ka, "B": kb, "map": lambda k: k})
    ok1, t1 = judged(d, b)
    CA, _ = base14_cct()
    CB, shown = cct("i14_reord", path, CCT14)
    ok2 = cct_key(CA)[:2] == cct_key(CB)[:2]
    return ok1 and ok2, (
        f"reordered + out-of-service records: {t1}"
        + ("" if ok1 else f" [{A[3]} vs {B[3]}]")
        + f" | CCT {CA.get('cct_s')} -> {CB.get('cct_s')}"
        + ("" if ok2 else f" [{shown}]")
        + f" | import said: {tail(' '.join(warn_lines(e)), 160)}"
    )


@probe("BB09")
def _():
    """IEEE 14 renumbered n -> 1000 + 111 ((7 n) mod 15) (the order scrambled: 1 -> 1777,
    2 -> 2554, 13 -> 1111, ...): simulate of the mapped fault, its CCT, screen of the
    mapped buses."""
    raw, dyr, basecase, A = base14()
    mp = {n: 1000 + 111 * ((7 * n) % 15) for n in range(1, 15)}
    assert len(set(mp.values())) == 14
    r2, d2 = renumber(raw, dyr, mp)
    path, e = imp("i14_renum", r2, d2)
    args = ["--fault", mp[4], "--far-bus", mp[5], "--clear-cycles", 6, "--tf", 5]
    B = simulate("i14_renum", path, args)
    ka, kb = case_machines(basecase), case_machines(path)
    inv = {v: k for k, v in mp.items()}
    d, b = compare(A, B, busmap=mp, macmap={"A": ka, "B": kb, "map": lambda k: (inv[k[0]], k[1])})
    ok1, t1 = judged(d, b)
    CA, _ = base14_cct()
    CB, shown = cct("i14_renum", path, ["--fault", mp[4], "--far-bus", mp[5]])
    ok2 = cct_key(CA)[:2] == cct_key(CB)[:2]
    SA, _ = base14_screen()
    SB, shs = screen("i14_renum_scr", path, [mp[2], mp[9], mp[13]])
    ra, rb = screen_rows(SA), screen_rows(SB, mp)
    ok3 = ra == rb and bool(ra)
    return ok1 and ok2 and ok3, (
        f"renumbered: {t1}"
        + ("" if ok1 else f" [{A[3]} vs {B[3]}]")
        + f" | CCT {CA.get('cct_s')} -> {CB.get('cct_s')}"
        + ("" if ok2 else f" [{shown}]")
        + f" | screen {ra} -> {rb}"
        + ("" if ok3 else f" [{shs}]")
    )


@probe("BB10")
def _():
    """IEEE 14: load 4 and load 9 each split in two IDs of half the power."""
    raw, dyr, basecase, A = base14()
    r2 = split_load(split_load(raw, 4), 9)
    path, e = imp("i14_ldsplit", r2, dyr)
    B = simulate("i14_ldsplit", path, SIM14)
    d, b = compare(A, B)
    ok, t = judged(d, b)
    return ok, f"loads 4 and 9 split: {t}" + ("" if ok else f" [{A[3]} vs {B[3]}]")


@probe("BB11")
def _():
    """IEEE 14: load 9 moved to a new bus 15 behind branch 9-15 (R 0, X 1e-6 pu; and X
    1e-4 pu, PSS/E's default zero-impedance threshold THRSHZ, which PSS/E's power flow
    and dynamics take as a jumper, the buses one): bus 9's voltage and the rest as
    before, bus 15 within X I of bus 9."""
    raw, dyr, basecase, A = base14()
    out, oks = [], []
    for x in (1e-6, 1e-4):
        tag = f"i14_jump{x:.0e}".replace("-", "m")
        path, e = imp(tag, jumper(raw, 9, 15, x), dyr)
        B = simulate(tag, path, SIM14)
        d, b = compare(A, B)
        z = B[1]
        bb = [int(v) for v in z["buses"]]
        d15 = float(np.max(np.abs(z["vmag"][:, bb.index(15)] - z["vmag"][:, bb.index(9)])))
        ok, t = judged(d, b, tol=TOL if x < 1e-5 else TOL)
        oks.append(ok)
        new = [w for w in warn_lines(e)]
        out.append(
            f"X {x:g}: {t}, |V15 - V9| {d15:.1e}"
            + (f"; import warns {tail(' '.join(new), 120)}" if new else "; import silent")
            + ("" if ok else f" [{A[3]} vs {B[3]}]")
        )
    return all(oks), " | ".join(out)


@probe("BB12")
def _():
    """powsybl's IEEE 14 as v33 and as v35 with one DYR (GENROU of ANDES's IEEE 14 at
    buses 1, 2, 3, 6, 8): the same run."""
    dyr = [
        r for r in dyr_records((ANDES / "ieee14" / "ieee14.dyr").read_text()) if "GENROU" in r[1]
    ]
    runs = []
    for v in ("v33", "v35"):
        raw = (PSSE / f"ieee14_{v}.raw").read_text()
        path, e = imp(f"pw14_{v}", raw, dyr)
        runs.append(simulate(f"pw14_{v}", path, SIM14))
    d, b = compare(*runs)
    ok, t = judged(d, b)
    return ok, f"v33 vs v35: {t}" + ("" if ok else f" [{runs[0][3]} vs {runs[1][3]}]")


@probe("BB15")
def _():
    """IEEE 14's four transformers written as CW 2 (WINDV in kV) and CZ 2 (R, X on
    SBASE1-2 = 50 MVA), at SBASE 100 and at SBASE 200: the same run."""
    raw, dyr, basecase, A = base14()
    out, oks = [], []
    for tag, r2 in (
        ("i14_forms", other_forms(raw)),
        ("i14_forms_sb200", other_forms(rebase(raw, 2.0))),
    ):
        path, e = imp(tag, r2, dyr)
        B = simulate(tag, path, SIM14)
        d, b = compare(A, B)
        ok, t = judged(d, b)
        oks.append(ok)
        out.append(f"{tag}: {t}" + ("" if ok else f" [{A[3]} vs {B[3]}]"))
    return all(oks), " | ".join(out)


# ============================================================================ Kundur's case file
KSIM = ["--fault", 3, "--far-bus", 101, "--clear-cycles", 6, "--tf", 6]
KCCT = ["--fault", 3, "--far-bus", 101]


def kundur_json():
    return json.loads((CLONE / "stabctl" / "case" / "data" / "kundur.json").read_text())


def kbase():
    if "k" not in BASES:
        p = WD / "k_base.json"
        p.write_text(json.dumps(kundur_json()))
        BASES["k"] = (p, simulate("k_base", p, KSIM))
    return BASES["k"]


def _col(t, name):
    return t["columns"].index(name)


@probe("BB13")
def _():
    """Kundur's case file with machine 1 (900 MVA, bus 1) split into machines 1 and 5 of
    450 MVA, pfrac = qfrac = 0.5, its exciter, PSS and governor rows duplicated: fault
    3-101 and its CCT the same."""
    pa, A = kbase()
    d = kundur_json()
    T = d["tables"]
    m = T["machines"]
    row = list(m["rows"][0])
    row[_col(m, "mva")] /= 2
    row[_col(m, "pfrac")], row[_col(m, "qfrac")] = 0.5, 0.5
    m["rows"][0] = row
    twin = list(row)
    twin[_col(m, "number")], twin[_col(m, "col19")] = 5, 5
    m["rows"].append(twin)
    for name in ("exciters", "pss", "governors"):
        t = T[name]
        k = _col(t, "machine")
        for r in list(t["rows"]):
            if r[k] == 1:
                t["rows"].append([*r[:k], 5, *r[k + 1 :]])
    pb = WD / "k_split1.json"
    pb.write_text(json.dumps(d))
    B = simulate("k_split1", pb, KSIM)
    ka = [(1, "1"), (2, "1"), (3, "1"), (4, "1")]
    kb = ka + [(1, "2")]
    mm = {
        "A": [(1, "1"), (2, "1"), (3, "1"), (4, "1")],
        "B": [(1, "1"), (2, "1"), (3, "1"), (4, "1"), (1, "2")],
        "map": lambda key: (key[0], "1"),
    }
    dd, bad = compare(A, B, macmap=mm)
    ok1, t1 = judged(dd, bad)
    CA, _ = cct("k_base", pa, KCCT)
    BASES["kcct"] = CA
    CB, shown = cct("k_split1", pb, KCCT)
    ok2 = cct_key(CA)[:2] == cct_key(CB)[:2]
    return ok1 and ok2, (
        f"machine 1 split: {t1}"
        + ("" if ok1 else f" [{A[3]} vs {B[3]}]")
        + f" | CCT {CA.get('cct_s')} -> {CB.get('cct_s')}"
        + ("" if ok2 else f" [{shown}]")
    )


@probe("BB14")
def _():
    """Kundur's case file at base_mva 200: the bus table's powers, shunts and Q limits
    halved, the branches' r, x doubled and b, g, b at the ends halved (machine data on
    their own MVA as they are): fault 3-101 through the same physical reactance (1e-7 pu
    at 100 MVA, 2e-7 pu at 200) and the bolted fault's CCT the same.  The bolted fault
    itself is PST's -j1e7 pu on the system base (docs/cli.md): at 200 MVA twice the
    admittance, so its run differs by ~2e-6 rad while the fault is on (shown, not judged)."""
    pa, A = kbase()
    d = kundur_json()
    d["base_mva"] = 200.0
    T = d["tables"]
    b = T["buses"]
    for r in b["rows"]:
        for name in ("pgen", "qgen", "pload", "qload", "gshunt", "bshunt", "qmax", "qmin"):
            r[_col(b, name)] /= 2
    br = T["branches"]
    for r in br["rows"]:
        r[_col(br, "r")] *= 2
        r[_col(br, "x")] *= 2
        for name in ("b", "g_from", "b_from", "g_to", "b_to"):
            r[_col(br, name)] /= 2
    pb = WD / "k_sb200.json"
    pb.write_text(json.dumps(d))
    clear = 1.0 + 6 / 60
    same = ["--trip", "3", "101", "--t-trip", clear, "--tf", 6]
    A1 = simulate("k_x100", pa, ["--bus-fault", "3:0:1e-7", 1.0, clear, *same])
    B1 = simulate("k_x200", pb, ["--bus-fault", "3:0:2e-7", 1.0, clear, *same])
    dd, bad = compare(A1, B1)
    ok1, t1 = judged(dd, bad)
    B = simulate("k_sb200", pb, KSIM)
    bolted = ", ".join(f"{k} {v:.1e}" for k, v in compare(A, B)[0].items())
    CA = BASES.get("kcct") or cct("k_base", pa, KCCT)[0]
    CB, shown = cct("k_sb200", pb, KCCT)
    ok2 = cct_key(CA)[:2] == cct_key(CB)[:2]
    return ok1 and ok2, (
        f"base 200 MVA, the same fault reactance: {t1}"
        + ("" if ok1 else f" [{A1[3]} vs {B1[3]}]")
        + f" | bolted (-j1e7 pu each): {bolted}"
        + f" | CCT {CA.get('cct_s')} -> {CB.get('cct_s')}"
        + ("" if ok2 else f" [{shown}]")
    )


# ============================================================================ every PSS/E run's case
def _run_cases():
    """(name, RAW, DYR) of each DYR of tests/data/psse_runs (the RAW beside it; CSVGN1's
    the _SVC one)."""
    out = []
    for d in sorted(PSR.iterdir()):
        if not d.is_dir():
            continue
        raws = sorted(d.glob("*.raw"))
        raws = [r for r in raws if "SVC" in r.name] or raws
        for k, y in enumerate(sorted(d.glob("*.dyr"))):
            if raws:
                out.append((d.name + (f"_{k}" if k else ""), raws[0], y))
    return out


def _target(raw, dyr):
    """The in-service generator (bus, ID) with the most DYR records, not a GENCLS of H 0."""
    best, n = None, -1
    for r in raw.sections[GEN]:
        t = r[0]
        key = (int(t[0]), sid(t[1]))
        if int(t[14]) == 0:
            continue
        mine = [x for x in dyr if int(x[0]) == key[0] and sid(x[2]) == key[1]]
        if any(sid(x[1]) == "GENCLS" and f(x[3]) == 0 for x in mine):
            continue
        if len(mine) > n:
            best, n = key, len(mine)
    return best


def _sweep(kind):
    bad, said, skipped = [], [], []
    for name, rp, dp in _run_cases():
        if only_runs and name not in only_runs:
            continue
        raw, dyr = Raw(rp.read_text()), dyr_records(dp.read_text())
        key = _target(raw, dyr)
        if key is None:
            skipped.append(f"{name}: no unit")
            continue
        bus = key[0]
        try:
            pa, _ = imp(f"r_{name}", raw, dyr)
        except RuntimeError as e:
            skipped.append(f"{name}: base import {tail(str(e), 100)}")
            continue
        xf = 0.1
        args = ["--bus-fault", f"{bus}:0:{xf}", 1, 1.1, "--tf", 4]
        try:
            A = BASES.get(("r", name)) or simulate(f"r_{name}", pa, args)
        except RuntimeError as e:
            skipped.append(f"{name}: base run {tail(str(e), 100)}")
            continue
        BASES[("r", name)] = A
        try:
            if kind == "split":
                r2, d2 = split_gen(raw, dyr, bus, key[1])
                pb, _ = imp(f"r_{name}_split", r2, d2)
                B = simulate(f"r_{name}_split", pb, args)
                mm = {
                    "A": case_machines(pa),
                    "B": case_machines(pb),
                    "map": lambda k: (k[0], key[1]) if k == (bus, "2") else k,
                }
                d, b = compare(A, B, macmap=mm)
            else:
                pb, _ = imp(f"r_{name}_sb200", rebase(raw, 2.0), dyr)
                args2 = ["--bus-fault", f"{bus}:0:{2 * xf}", 1, 1.1, "--tf", 4]
                B = simulate(f"r_{name}_sb200", pb, args2)
                d, b = compare(A, B)
                if "ibr_p" in A[1] and A[1]["ibr_p"].size:
                    d["ibr_p_MW/100"] = (
                        float(np.max(np.abs(A[1]["ibr_p"] * 100 - B[1]["ibr_p"] * 200))) / 100
                    )
                    d["ibr_q_MW/100"] = (
                        float(np.max(np.abs(A[1]["ibr_q"] * 100 - B[1]["ibr_q"] * 200))) / 100
                    )
        except RuntimeError as e:
            bad.append(f"{name}: variant failed: {tail(str(e), 200)}")
            continue
        ok, t = judged(d, b, tol=1e-5)
        worst = max(d.values()) if d else 0
        said.append(f"{name} {key} {worst:.0e}")
        if not ok:
            bad.append(f"{name} {key}: {t} [{A[3]} vs {B[3]}]")
    return not bad, ("; ".join(bad) + " || " if bad else "") + "worst: " + ", ".join(said) + (
        f" | skipped {'; '.join(skipped)}" if skipped else ""
    )


only_runs = [x for x in os.environ.get("BB_RUNS", "").split(",") if x]


@probe("BB16")
def _():
    """Every PSS/E run's case (tests/data/psse_runs): the unit with the most DYR records
    split in two; a fault at its bus through j0.1 pu, 1-1.1 s: the same run (1e-5)."""
    return _sweep("split")


@probe("BB17")
def _():
    """Every PSS/E run's case at SBASE 200 (the fault's X doubled with it): the same run,
    converter P, Q in MW (1e-5)."""
    return _sweep("sbase")


if __name__ == "__main__":
    KIT.main(banner="work dir {wd}, package {clone}")
