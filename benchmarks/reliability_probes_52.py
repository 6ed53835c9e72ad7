#!/usr/bin/env python
"""Round 58 (AY): a newcomer runs the documentation.  Every shell command written in
README.md and docs/*.md (not docs/cli_reference.md, generated; not `stabctl paper`, the
commands said to take more than ~3 minutes, a Dask cluster or more than 2 cores) is run
as written, copied from the page, in a scratch directory, `stabctl` standing for
`python -m stabctl` with PYTHONPATH=CLONE (a one-line `stabctl` script first on PATH);
the docs' ```python blocks are run as written.  A probe checks the command ends as the
page implies (exit 0, or the refusal it describes) and that each figure the page gives
beside it (a CCT, a damping, a count, a quoted output line) is what the command prints
now, to the digits the page gives; timings are not figures here.  Names the pages give
(options in a synopsis, `stabctl.x.y` names) are checked to exist.

    CLONE=<clone> PYTHONPATH=<clone> python benchmarks/reliability_probes_52.py [AY01 ...]

Each probe's reason starts with the page and line.  The command text is looked up in the
page first (whitespace folded): a probe whose command is no longer written there is SHORT
("not in the page"), so the probes follow the pages.  Run with a warm kernel cache
(`stabctl compile`); about 20 min on 2 cores (ANDES imports, WECC-240, ACTIVSg2000, a
venv install, a cold simulation, andes_coverage.py).  Not run: `stabctl paper`, the test
suites (`pytest -n auto`, the slow fuzzing), the cold `stabctl compile` (3 min), the
benchmarks that only time, ACTIVSg2000's whole screenings, Dask.

Found (round 58, AY, at 0eea4fee; 50 ok, 11 SHORT): stale figures beside commands:
WECC-240 (cli.md:907 0.9027 rad, now 0.9606; cli.md:910 CCT 0.270 s, now 0.271 s),
ACTIVSg2000 (cli.md:790 1.13831 rad, now 1.1771; scale.md:150 CCT 0.247 s, now 0.250 s;
scale.md:139 0.175/0.362/0.431 s, now 0.259/0.360/0.427 s), docs/andes_coverage.md (90 of
91, now 85: the unknown-column check of 2026-11-27), placement run counts (:598 326 -> 280,
:599 521 -> 523, :666 64 -> 67, :667 146 -> 148); setup.md:111 (`import stabctl` does not
raise under NUMBA_DISABLE_JIT=1; the first use does); pst_models.md:1992
`stabctl.case.SvcTable` (in stabctl.case.system only).
"""

# ruff: noqa
import json
import os
import re
import shutil
import stat
import subprocess
import sys
from pathlib import Path

from _probe_kit import Kit, tail, tb

KIT = Kit("probes_ay56.", line="{pid:<6} {state:<5} {why}", timed=True)
CLONE, ENV, WD = Path(KIT.clone), KIT.env, KIT.wd
rec, probe = KIT.rec, KIT.probe
# the scratch kernel cache is the caller's (warm), not a fresh one in WD
ENV.pop("XDG_CACHE_HOME", None)
if os.environ.get("XDG_CACHE_HOME"):
    ENV["XDG_CACHE_HOME"] = os.environ["XDG_CACHE_HOME"]
BIN = WD / "bin"
BIN.mkdir()
(BIN / "stabctl").write_text(f'#!/bin/sh\nexec "{sys.executable}" -m stabctl "$@"\n')
(BIN / "stabctl").chmod(0o755)
ENV["PATH"] = f"{BIN}:{ENV['PATH']}"
ENV["PYTHONPATH"] = str(CLONE)


def page(name):
    return (CLONE / name).read_text()


def fold(s):
    return " ".join(s.split())


def written(name, cmd):
    """The doc line where cmd is written (whitespace folded, `\\` continuations too), or None."""
    text = page(name)
    flat = fold(text.replace("\\\n", " "))
    want = fold(cmd.replace("\\\n", " "))
    if want not in flat:
        return None
    # the line of the command's first words
    head = fold(want)[:40]
    lines = text.splitlines()
    for i in range(len(lines)):
        if head[:16] in fold(lines[i]) and head in fold(
            " ".join(lines[i : i + 3]).replace("\\", " ")
        ):
            return i + 1
    words = want.split()[:3]
    for i in range(len(lines)):
        if fold(lines[i]).endswith(" ".join(words[:1])) or " ".join(words[:2]) in fold(lines[i]):
            if head in fold(" ".join(lines[i : i + 3]).replace("\\", " ")):
                return i + 1
    return 0


def sh(cmd, timeout=600, cwd=None, env=None):
    """(rc, out, err) of `bash -c cmd` (nice) in cwd (default WD)."""
    try:
        p = subprocess.run(
            ["nice", "bash", "-c", cmd],
            capture_output=True,
            text=True,
            timeout=timeout,
            cwd=cwd or WD,
            env=env or ENV,
            stdin=subprocess.DEVNULL,
        )
        return p.returncode, p.stdout, p.stderr
    except subprocess.TimeoutExpired as e:
        return "timeout", str(e.stdout or ""), str(e.stderr or "")


def doc_run(name, cmd, timeout=600, cwd=None, env=None):
    """Run a command as written in page `name`: (where, rc, out, err); where 'file:line'."""
    ln = written(name, cmd)
    if ln is None:
        raise AssertionError(f"{name}: command not in the page: {cmd[:80]}")
    rc, out, err = sh(cmd, timeout, cwd, env)
    return f"{name}:{ln}", rc, out, err


def missing(text, figures):
    """The figures (strings) not in text."""
    return [f for f in figures if f not in text]


def verdict(where, rc, out, err, figures=(), want_rc=0):
    """(ok, why) for a run that should end want_rc and print every figure."""
    both = out + err
    if rc != want_rc:
        return False, f"{where}: exit {rc} (want {want_rc}): {tail(err or out, 300)}"
    if tb(both):
        return False, f"{where}: traceback: {tail(err, 300)}"
    miss = missing(both, figures)
    if miss:
        return False, f"{where}: the page's {miss} not printed; got: {tail(out, 400)}"
    return True, f"{where}: exit {rc}, {len(figures)} figure(s) as the page says"


def numbers(text):
    return re.findall(r"(?<![\w.])-?\d+\.\d+", text)


def agree(page_fig, text):
    """Whether a number printed in text agrees with page_fig at the page's digits (a printed
    value with more digits: within the page's half unit plus its own rounding)."""
    dec = len(page_fig.split(".")[1]) if "." in page_fig else 0
    want = float(page_fig)
    for x in numbers(text):
        dp = len(x.split(".")[1])
        if dp >= dec and abs(float(x) - want) <= 0.5 * 10**-dec + 0.5 * 10**-dp + 1e-12:
            return True
    return False


def copy_data(sub, dest):
    d = WD / dest
    if not d.exists():
        shutil.copytree(CLONE / "tests/data" / sub, d)
    return d


# ============================================================== README.md
SIM_MW = "stabctl simulate miniwecc --fault 83 --far-bus 33 --clear-cycles 6 --esd-pct 5"


@probe("AY01")
def _():
    where = f"README.md:{written('README.md', '$ ' + SIM_MW)}"
    rc, out, err = sh(SIM_MW)
    return verdict(
        where,
        rc,
        out,
        err,
        [
            "case miniwecc: 34 machines, 122 buses; 0-6 s, 1200 steps (h = 5 ms, heun, ieee conventions, PV Q limits held)",
            "3-phase fault at bus 83 at 1 s on line 83-33 (circuit 1), cleared at 1.1 s (after 100.0 ms), line tripped",
            "storage: 34 ESDs of 5 % of machine MVA at the generator HV buses, bang-bang COI (paper Table 3)",
            "stable: largest angle from the COI 1.8940 rad",
        ],
    )


@probe("AY02")
def _():
    cmd = "stabctl cct kundur --fault 3 --far-bus 101"
    where = f"README.md:{written('README.md', '$ ' + cmd)}"
    rc, out, err = sh(cmd)
    return verdict(
        where,
        rc,
        out,
        err,
        [
            "CCT 0.154 s = 9.24 cycles (stable at 0.154 s, unstable at 0.155 s = 9.30 cycles; tolerance 1 ms, "
        ],
    )


@probe("AY03")
def _():
    cmd = "stabctl eig kundur"
    where = f"README.md:{written('README.md', '$ ' + cmd)}"
    rc, out, err = sh(cmd)
    rows = [
        "   36   0.612   0.1319  inter-area G3 (bus 11) G4 (bus 12) vs G1 (bus 1) G2 (bus 2)  [areas 2 vs 1]",
        "   37   1.292   0.3637  local      G4 (bus 12) G2 (bus 2) vs G3 (bus 11) G1 (bus 1)",
        "   38   1.340   0.3560  local      G2 (bus 2) G3 (bus 11) vs G1 (bus 1) G4 (bus 12)",
        " mode    f Hz     zeta  kind       machines",
    ]
    got = [ln.rstrip() for ln in out.splitlines()]
    miss = [r for r in rows if r.rstrip() not in got]
    if rc != 0 or miss:
        near = [ln for ln in got if re.match(r"\s+3[678]\s", ln)]
        return False, f"{where}: exit {rc}; rows not printed as written: {miss}; got {near}"
    return True, f"{where}: the three modes' rows as written"


@probe("AY04")
def _():
    where, rc, out, err = doc_run("README.md", "stabctl cases kundur --bus-table --line-table")
    ok, why = verdict(where, rc, out, err)
    return ok and "101" in out, why + f" ({len(out.splitlines())} lines)"


@probe("AY05")
def _():
    m = re.search(r"```python\n(.*?)```", page("README.md"), re.S)
    code = m.group(1)
    ln = page("README.md")[: m.start()].count("\n") + 1
    (WD / "readme_snippet.py").write_text(code)
    rc, out, err = sh(f"{sys.executable} readme_snippet.py", 600)
    if rc != 0:
        return False, f"README.md:{ln}: python block exit {rc}: {tail(err)}"
    return (
        out.strip() == "0.154",
        f"README.md:{ln}: python block printed {out.strip()!r} (page: 0.154)",
    )


@probe("AY06")
def _():
    where, rc, out, err = doc_run("README.md", "stabctl compile --check")
    return verdict(where, rc, out, err)


@probe("AY07")
def _():
    # "Every command has --help" (README.md:93)
    rc, out, err = sh("stabctl --help")
    cmds = re.findall(r"^  ([a-z][a-z0-9-]+)\s", out.split("Commands:")[-1], re.M)
    bad = []
    for c in cmds:
        r, o, e = sh(f"stabctl {c} --help", 120)
        if r != 0 or "Usage" not in o:
            bad.append(f"{c}: {r}")
        subs = (
            re.findall(r"^  ([a-z][a-z0-9-]+)\s", o.split("Commands:")[-1], re.M)
            if "Commands:" in o
            else []
        )
        for s in subs:
            r2, o2, _ = sh(f"stabctl {c} {s} --help", 120)
            if r2 != 0 or "Usage" not in o2:
                bad.append(f"{c} {s}: {r2}")
    return (
        rc == 0 and not bad and len(cmds) > 5
    ), f"README.md:93: {len(cmds)} commands each take --help; failing: {bad}"


# ============================================================== docs/setup.md
@probe("AY08")
def _():
    # the compile's own log (the caller ran `stabctl compile`): each part with its seconds
    rc, out, err = sh("stabctl compile", 900)
    return verdict("docs/setup.md:98", rc, out, err)


@probe("AY09")
def _():
    rc, out, err = sh("stabctl compile --check nosuchcase")
    lines = [ln for ln in (out + err).splitlines() if ln.strip()]
    ok = rc == 2 and len(lines) == 1 and lines[0].startswith("error:") and not tb(err)
    return ok, f"docs/setup.md:103: compile --check nosuchcase: exit {rc}, {lines[:3]}"


@probe("AY10")
def _():
    # setup.md:108-111: a bad numba variable is one error line naming it, exit status 2
    cases = {
        "NUMBA_NUM_THREADS": "NUMBA_NUM_THREADS=0",
        "NUMBA_CACHE_DIR": f"NUMBA_CACHE_DIR={WD}/afile",
        "NUMBA_OPT": "NUMBA_OPT=x",
        "NUMBA_DISABLE_JIT": "NUMBA_DISABLE_JIT=1",
    }
    (WD / "afile").write_text("x")
    bad = []
    for var, setting in cases.items():
        rc, out, err = sh(f"{setting} stabctl cases kundur")
        lines = [ln for ln in (out + err).splitlines() if ln.strip()]
        if rc != 2 or len(lines) != 1 or var not in lines[0] or tb(err):
            bad.append(f"{setting}: exit {rc} {tail(out + err, 160)}")
    # setup.md:111: "`import stabctl` itself has no side effect, and its first use,
    # `stabctl.load_case` say, raises an ImportError naming it"
    rc, out, err = sh(f'NUMBA_DISABLE_JIT=1 {sys.executable} -c "import stabctl"')
    r2, o2, e2 = sh(
        f"NUMBA_DISABLE_JIT=1 {sys.executable} -c \"import stabctl; stabctl.load_case('kundur')\""
    )
    if rc != 0 or "ImportError" not in e2 or "NUMBA_DISABLE_JIT" not in e2:
        bad.append(
            f"under NUMBA_DISABLE_JIT=1: `import stabctl` exit {rc}; its first use exit {r2}: "
            f"{tail(e2, 120)}"
        )
    return not bad, f"docs/setup.md:108: numba variables: {bad or 'each one error line, exit 2'}"


@probe("AY11")
def _():
    # setup.md:159-166, run from the repository root
    block = re.search(r"```bash\n(ruff check \..*?)```", page("docs/setup.md"), re.S).group(1)
    bad, done = [], []
    for ln in block.splitlines():
        cmd = ln.split("#")[0].strip()
        if not cmd:
            continue
        rc, out, err = sh(cmd, 900, cwd=CLONE)
        done.append(cmd.split()[0])
        if rc != 0:
            bad.append(f"`{cmd}` exit {rc}: {tail(out + err, 200)}")
    return not bad, f"docs/setup.md:161: {len(done)} linters: {bad or 'each exit 0'}"


@probe("AY12")
def _():
    # setup.md:69: the cold simulation (pinned to one core, throwaway cache)
    cmd = "NUMBA_CACHE_DIR=$(mktemp -d) taskset -c 1 /usr/bin/time -v stabctl simulate kundur --fault 3 --far-bus 101 --tf 2"
    where, rc, out, err = doc_run("docs/setup.md", cmd, 900, env=dict(ENV, TMPDIR=str(WD)))
    return verdict(where, rc, out, err, ["stable"])


# ============================================================== docs/cli.md
@probe("AY13")
def _():
    cmd = "stabctl cases | head"
    ln = written("docs/cli.md", cmd)
    rc, out, err = sh("stabctl cases | head -1; echo rc=${PIPESTATUS[0]}")
    ok = not err.strip() and re.search(r"rc=(0|141)", out)
    return bool(
        ok
    ), f"docs/cli.md:{ln}: `stabctl cases | head -1`: {tail(out, 120)!r}, stderr {tail(err, 160)!r}"


@probe("AY14")
def _():
    where, rc, out, err = doc_run("docs/cli.md", "stabctl cases kundur")
    # cli.md:146: book 1..11 -> 1 2 11 12 10 20 3 101 13 120 110
    book = [1, 2, 11, 12, 10, 20, 3, 101, 13, 120, 110]
    flat = " ".join(out.split())
    pairs = [f"{k}" for k in book if str(k) not in flat]
    ok, why = verdict(where, rc, out, err)
    return ok and not pairs, why + f"; map: {tail(out[-600:], 300)}"


@probe("AY15")
def _():
    cmd = "stabctl cct miniwecc --fault 83 --far-bus 33 --tol-ms 5"
    where, rc, out, err = doc_run("docs/cli.md", cmd)
    return verdict(
        where, rc, out, err, ["machine(s) G14 (bus 32) lose synchronism when cleared at 0.080 s"]
    )


@probe("AY16")
def _():
    where, rc, out, err = doc_run("docs/cli.md", "stabctl screen kundur --buses 3,101")
    row = [ln for ln in out.splitlines() if re.match(r"\s*bus 3\b", ln)]
    pat = re.compile(r"bus 3\b.*0\.238\s+14\.28\s+0\s+G1 \(bus 1\), G2 \(bus 2\)")
    ok = rc == 0 and any(pat.search(r) for r in row)
    return (
        ok,
        f"{where}: exit {rc}; page `bus 3 ... 0.238 14.28 0  G1 (bus 1), G2 (bus 2)`; got {row}",
    )


@probe("AY17")
def _():
    (WD / "sims").exists() or (WD / "sims").symlink_to(CLONE / "sims")
    bad = []
    for cmd in (
        "python sims/case1_kundur_no_storage.py",
        "python sims/case2_miniwecc_no_storage.py",
    ):
        where, rc, out, err = doc_run("docs/cli.md", cmd)
        if rc != 0 or tb(err):
            bad.append(f"{where} exit {rc}: {tail(err, 200)}")
    pngs = (
        sorted(p.name for p in (WD / "reports").glob("*.png")) if (WD / "reports").exists() else []
    )
    return not bad and pngs, f"docs/cli.md:267: {bad or 'both exit 0'}; figures {pngs}"


@probe("AY18")
def _():
    cmd = "stabctl simulate kundur --bus-fault 3:0:0.05 1 1.1 --trip 3 101 --t-trip 1.1 --close 3 101 1.6 --vref-step 2 3 0.02 --pref-step 1 4 0.05 --tf 10"
    where = f"docs/cli.md:{written('docs/cli.md', '$ ' + cmd)}"
    rc, out, err = sh(cmd)
    return verdict(where, rc, out, err)


@probe("AY19")
def _():
    where, rc, out, err = doc_run("docs/cli.md", "stabctl screen kundur --lines")
    # cli.md:577: the faults on the step-up transformers 1-10, 2-20, 11-110, 12-120 island
    # their generator (either end's fault)
    lines = (out + err).splitlines()
    miss = []
    for a, b in ((1, 10), (2, 20), (11, 110), (12, 120)):
        gen = f"(bus {a})" if a < b else f"(bus {b})"
        hit = [
            ln
            for ln in lines
            if re.match(rf"bus ({a} line to {b}|{b} line to {a})\s+islands machine\(s\)", ln)
            and gen in ln
        ]
        if not hit:
            miss.append(f"{a}-{b}")
    ok = rc == 0 and not miss
    return ok, f"{where}: exit {rc}; transformer faults not islanding their generator: {miss}"


def psse_pair(pid_where, sub, imp, simc, figures=()):
    d = copy_data(f"psse_runs/{sub}", sub)
    w1, rc, out, err = doc_run(pid_where, imp, cwd=d)
    if rc != 0:
        return False, f"{w1}: exit {rc}: {tail(err, 300)}"
    w2, rc, out, err = doc_run(pid_where, simc, cwd=d)
    return verdict(f"{w1} + {w2}", rc, out, err, figures)


@probe("AY20")
def _():
    return psse_pair(
        "docs/cli.md",
        "RENA_DEFAULT",
        "stabctl import-psse ThreeBusRenewable.raw ThreeBus_REN_A_DEFAULT_FLAG.dyr -o c.json",
        "stabctl simulate c.json --trip 101 103 --t-trip 1 --tf 5",
    )


@probe("AY21")
def _():
    return psse_pair(
        "docs/cli.md",
        "DERA_FREQFLAG0",
        "stabctl import-psse ThreeBusMulti.raw ThreeBus_DERA1.dyr -o c.json",
        "stabctl simulate c.json --trip 101 102 --t-trip 2 --tf 4",
    )


@probe("AY22")
def _():
    return psse_pair(
        "docs/cli.md",
        "CSVGN1",
        "stabctl import-psse 3_BUS_System_SVC.raw 3_BUS_System_SVC.dyr -o c.json",
        "stabctl simulate c.json --load-step 2 0.005 -0.55 0 --tf 0.07 --step 0.0001",
    )


@probe("AY23")
def _():
    return psse_pair(
        "docs/ibr.md",
        "RENA_DEFAULT",
        "stabctl import-psse ThreeBusRenewable.raw ThreeBus_REN_A_DEFAULT_FLAG.dyr -o c.json",
        "stabctl simulate c.json --trip 101 103 --t-trip 1 --tf 5 --step 0.005",
    )


@probe("AY24")
def _():
    text = page("docs/cli.md")
    m = re.search(r"```bash\n(for f in 240bus.*?)```", text, re.S)
    ln = text[: m.start()].count("\n") + 2
    d = WD / "w240"
    d.mkdir(exist_ok=True)
    (d / "tests").exists() or (d / "tests").symlink_to(CLONE / "tests")
    rc, out, err = sh(m.group(1), 900, cwd=d)
    both = out + err
    figs = ["243 buses", "103 machines", "stable", "largest angle from the COI 0.9606 rad"]
    imp = re.findall(r"3731[^\n]*", both)
    miss = missing(both, figs)
    mvar = any("-188.9" in s and "-121" in s for s in imp)
    ok = rc == 0 and not miss and mvar
    return ok, (
        f"docs/cli.md:{ln}: block exit {rc}; figures missing {miss}; bus 3731 line with -188.9/-121: {mvar}"
        f" ({tail(' '.join(imp), 160)}); {tail(out, 240)}"
    )


@probe("AY25")
def _():
    d = WD / "w240"
    if not (d / "wecc240.json").exists():
        return False, "docs/cli.md:909: no wecc240.json (AY24 first)"
    where, rc, out, err = doc_run(
        "docs/cli.md", "stabctl cct wecc240.json --fault 1001 --far-bus 1201 --no-q-limits", cwd=d
    )
    ok, why = verdict(where, rc, out, err, ["CCT 0.271 s", "16.26", "half the step 0.270 s"])
    return ok, why + f"; {tail(out, 300)}"


@probe("AY26")
def _():
    d = WD / "w240"
    if not (d / "wecc240.json").exists():
        return False, "docs/cli.md:911: no wecc240.json (AY24 first)"
    where, rc, out, err = doc_run("docs/cli.md", "stabctl eig wecc240.json --no-q-limits", cwd=d)
    ok, why = verdict(where, rc, out, err, ["1833"])
    ia = [ln for ln in out.splitlines() if "inter-area" in ln]
    fz = sorted((float(x.split()[1]), float(x.split()[2])) for x in ia) if ia else []
    slow = fz[0] if fz else None
    good = slow is not None and f"{slow[0]:.2f}" == "0.41" and round(slow[1] * 100) == 19
    r2, o2, e2 = sh("stabctl eig wecc240.json --no-q-limits --no-pss", 900, cwd=d)
    ia2 = [ln for ln in o2.splitlines() if "inter-area" in ln]
    fz2 = sorted((float(x.split()[1]), float(x.split()[2])) for x in ia2) if ia2 else []
    s2 = fz2[0] if fz2 else None
    good2 = s2 is not None and f"{s2[0]:.3f}" == "0.394" and f"{s2[1] * 100:.1f}" == "8.2"
    return ok and good and good2, (
        f"{why}; slowest inter-area (Hz, zeta) {slow} (page 0.41 Hz, 19 %); --no-pss {s2} (page 0.394 Hz, 8.2 %)"
    )


@probe("AY27")
def _():
    text = page("docs/cli.md")
    m = re.search(r"```bash\n(for f in ACTIVSg2000.*?)```", text, re.S)
    ln = text[: m.start()].count("\n") + 2
    d = WD / "activsg"
    d.mkdir(exist_ok=True)
    (d / "tests").exists() or (d / "tests").symlink_to(CLONE / "tests")
    rc, out, err = sh(m.group(1), 900, cwd=d)
    if rc != 0:
        return verdict(f"docs/cli.md:{ln}", rc, out, err)
    # cli.md:789-791: "the 6-cycle fault above is stable, largest angle from the COI 1.17712
    # rad at half a cycle, 1.17707 at a quarter and 1.17699 at an eighth" (5 s runs; the
    # 10 s block's figure is the same, its largest angle coming early)
    r2, o2, e2 = sh(
        "stabctl simulate activsg2000.json --fault 2021 --far-bus 2002 --clear-cycles 6 --tf 10 --step 0.004166666666666667",
        600,
        cwd=d,
    )
    m = re.search(r"largest angle from the COI ([\d.]+) rad", o2)
    got = m.group(1) if m else f"exit {r2}"
    return (
        got.startswith("1.1771") and "1.1771" in out,
        f"docs/cli.md:{ln}: block exit 0; at a quarter cycle largest angle {got} rad (page :790 "
        f"1.17707); default step: {tail(out, 60)}",
    )


@probe("AY28")
def _():
    d = WD / "activsg"
    if not (d / "activsg2000.json").exists():
        return False, "docs/scale.md:150: no activsg2000.json (AY27 first)"
    where, rc, out, err = doc_run(
        "docs/scale.md", "stabctl cct activsg2000.json --fault 2021 --far-bus 2002", cwd=d
    )
    return verdict(where, rc, out, err, ["CCT 0.250 s", "13 simulations"])


@probe("AY29")
def _():
    d = WD / "activsg"
    if not (d / "activsg2000.json").exists():
        return False, "docs/scale.md:135: no activsg2000.json (AY27 first)"
    where, rc, out, err = doc_run(
        "docs/scale.md",
        "stabctl screen activsg2000.json --buses 2021,2002,2101,2127,2011,2017 --workers 2",
        cwd=d,
    )
    rows = {
        b: [ln for ln in out.splitlines() if re.match(rf"\s*bus {b}\b", ln)]
        for b in (2021, 2101, 2002)
    }
    want = {2021: "0.259", 2101: "0.360", 2002: "0.427"}
    bad = {b: rows[b] for b in want if not any(want[b] in r for r in rows[b])}
    return rc == 0 and not bad, f"{where}: exit {rc}; page CCTs {want}; rows differing {bad}"


# ============================================================== ANDES cases
def andes_case(name, xlsx):
    d = WD / "andes"
    d.mkdir(exist_ok=True)
    if not (d / name).exists():
        rc, out, err = sh(f"{sys.executable} -c \"import andes; print(andes.get_case('{xlsx}'))\"")
        path = out.strip()
        rc, o, e = sh(f"stabctl import-andes {path} -o {name}", 600, cwd=d)
        if rc != 0:
            raise AssertionError(f"import-andes {xlsx}: exit {rc}: {tail(e, 200)}")
    return d


@probe("AY30")
def _():
    text = page("docs/placement.md")
    m = re.search(r"```bash\n(python -c \"import andes.*?)```", text, re.S)
    ln = text[: m.start()].count("\n") + 2
    d = WD / "andes"
    d.mkdir(exist_ok=True)
    (d / "examples").exists() or (d / "examples").symlink_to(CLONE / "examples")
    lines = m.group(1).replace("\\\n", " ").splitlines()
    rc, out, err = sh(lines[0].split("#")[0], cwd=d)
    path = out.strip()
    if rc != 0 or not path:
        return False, f"docs/placement.md:{ln}: {lines[0][:60]} exit {rc}: {tail(err)}"
    steps = [lines[1].split("#")[0].replace("<that path>", path)] + [
        s.split("#")[0] for s in lines[2:]
    ]
    res = []
    for s in steps:
        rc, out, err = sh(s, 900, cwd=d)
        res.append((s.split()[1], rc))
        if rc != 0:
            return False, f"docs/placement.md:{ln}: `{s[:70]}` exit {rc}: {tail(err + out, 300)}"
    both = out + err
    label = "NOTHING TO PLACE (every contingency set aside as infeasible ("
    ok = rc == 0 and label in both and "192 runs simulated" in both
    return (
        ok,
        f"docs/placement.md:{ln}: {res}; place label as the page (:588): {label in both}; 192 runs (page): {'192 runs simulated' in both}; {tail(out, 200)}",
    )


@probe("AY31")
def _():
    d = andes_case("ieee39_full.json", "ieee39/ieee39_full.xlsx")
    where, rc, out, err = doc_run(
        "docs/placement.md",
        "stabctl cct ieee39_full.json --fault 26 --far-bus 29 --esd-pct 20",
        cwd=d,
    )
    ok, why = verdict(where, rc, out, err, ["CCT 0.436 s"])
    # placement.md:436: 0.497 s without storage, 0.469 s with 5 %, --coi rest 0.442 s
    extra = {}
    for args, fig in (
        ("", "CCT 0.497 s"),
        ("--esd-pct 5", "CCT 0.469 s"),
        ("--esd-pct 20 --coi rest", "CCT 0.442 s"),
    ):
        r, o, e = sh(f"stabctl cct ieee39_full.json --fault 26 --far-bus 29 {args}", cwd=d)
        m = re.search(r"CCT [\d.]+ s", o)
        extra[args or "none"] = (m.group(0) if m else f"exit {r}", fig)
    bad = {k: v for k, v in extra.items() if v[0] != v[1]}
    return ok and not bad, why + f"; the others (got, page): {extra}"


@probe("AY32")
def _():
    d = andes_case("wecc_full.json", "wecc/wecc_full.xlsx")
    where, rc, out, err = doc_run(
        "docs/placement.md",
        "stabctl cct wecc_full.json --fault 75 --far-bus 77 --esd-pct 50",
        cwd=d,
    )
    return verdict(where, rc, out, err, ["CCT 0.420 s", "unstable at 0.421 s"])


@probe("AY33")
def _():
    # estimation.md:888: ANDES's IEEE 39 (10 TGOV1) as ieee39.json
    d = andes_case("ieee39.json", "ieee39/ieee39_full.xlsx")
    where, rc, out, err = doc_run(
        "docs/estimation.md",
        "stabctl estimate rmse ieee39.json --fault 16 --far-bus 17 --clear-cycles 6 --runs 3 --no-q-limits",
        900,
        cwd=d,
    )
    figs = ["16.98", "16.96", "24.71", "18.61", "18.59", "19.65"]
    miss = [f for f in figs if not agree(f, out)]
    ok = rc == 0 and not miss and not tb(err)
    return (
        ok,
        f"{where}: exit {rc}; page figures not printed (to their digits): {miss}; {tail(out, 500)}",
    )


@probe("AY34")
def _():
    d = WD / "andes"
    d.mkdir(exist_ok=True)
    rc, out, err = sh(
        f"{sys.executable} -c \"import andes; print(andes.get_case('kundur/kundur_reg.xlsx'))\""
    )
    shutil.copy(out.strip(), d / "kundur_reg.xlsx")
    cmd = "stabctl import-andes kundur_reg.xlsx -o reg.json --skip-unsupported; stabctl simulate reg.json --no-q-limits --fault 8 --clear-cycles 6"
    where, rc, out, err = doc_run("docs/ibr.md", cmd, cwd=d)
    # ibr.md:689 "What was wrong": the fix says it runs now
    return verdict(where, rc, out, err)


# ============================================================== placement, storage
@probe("AY35")
def _():
    cmd = "stabctl cct miniwecc --fault 83 --far-bus 33 --esd-pct 5"
    where, rc, out, err = doc_run("docs/placement.md", cmd)
    return verdict(where, rc, out, err, ["CCT 0.110 s"])


@probe("AY36")
def _():
    (WD / "f.csv").write_text("bus,far_bus,required_clearing_cycles\n3,101,11\n")
    cmd = "stabctl place kundur --faults f.csv --required-clearing-cycles 10 --esd-model wecc"
    where, rc, out, err = doc_run("docs/placement.md", cmd, 900)
    both = out + err
    m = re.findall(r"[^\n]*\b110\b[^\n]*MW[^\n]*|[^\n]*MW[^\n]*\b110\b[^\n]*", both)
    ok = rc == 0 and "120.1" in both
    return (
        ok,
        f"{where}: exit {rc}; page 120.1 MW at bus 110: {'120.1' in both}; {tail(' | '.join(m), 300) or tail(out, 300)}",
    )


@probe("AY37")
def _():
    cmd = "stabctl cct kundur --fault 3 --far-bus 101 --esd-pct 5"
    ln = written(
        "docs/storage.md",
        "stabctl cct kundur --fault 3 --far-bus 101 --esd-pct 5 [--esd-model wecc]",
    )
    rc, out, err = sh(cmd)
    ok, why = verdict(f"docs/storage.md:{ln}", rc, out, err, ["CCT 0.199 s"])
    r2, o2, e2 = sh(cmd + " --esd-model wecc")
    ok2, why2 = verdict(f"docs/storage.md:{ln} (wecc)", r2, o2, e2, ["CCT 0.195 s"])
    return ok and ok2, f"{why}; {why2}"


# ============================================================== estimation
@probe("AY38")
def _():
    cmd = "stabctl estimate rmse kundur --fault 3 --far-bus 101 --clear-cycles 12 --conventions pstess --runs 20 --ambient-s 0"
    where, rc, out, err = doc_run("docs/estimation.md", cmd, 900)
    # estimation.md:294-296: Kundur bus 3, 12 cycles (mean over runs, mHz)
    page_rows = {
        "raw": "24.1 20.3 12.9 9.1 9.1",
        "kf": "24.1 20.3 12.9 9.1 9.1 0.63",
        "ekf": "1.4 0.9 1.08 12.0 1.8 0.96",
    }
    bad = []
    for est, figs in page_rows.items():
        row = next((ln for ln in out.splitlines() if ln.split()[:1] == [est]), "")
        # columns: speed COI relative rel.max at-arrival forecast NIS (value +-std each)
        vals = [v for v in re.findall(r"(\d+\.\d+) \+-", row)]
        want = figs.split()
        cols = [0, 1, 2, 4, 5, 6][: len(want)]
        for w, c in zip(want, cols):
            dec = len(w.split(".")[1])
            got = f"{float(vals[c]):.{dec}f}" if c < len(vals) else None
            if got != w:
                bad.append(f"{est} col {c}: {vals[c] if c < len(vals) else None} (page {w})")
    ok = rc == 0 and not bad and not tb(err)
    return (
        ok,
        f"{where}: exit {rc}; table row Kundur bus 3, 12 cycles against the run: {bad or 'every figure to its digits'}",
    )


# ============================================================== python blocks
def py_blocks(name):
    text = page(name)
    return [
        (text[: m.start()].count("\n") + 2, m.group(1))
        for m in re.finditer(r"```python\n(.*?)```", text, re.S)
    ]


@probe("AY39")
def _():
    blocks = py_blocks("docs/library.md")
    # the second block uses the first's names: one session, as a reader runs them
    (WD / "lib12.py").write_text(blocks[0][1] + "\n" + blocks[1][1])
    rc, out, err = sh(f"{sys.executable} lib12.py", 900)
    got = out.split()
    ok = rc == 0 and got[:2] == ["0.154", "0.15"]
    return (
        ok,
        f"docs/library.md:{blocks[0][0]},{blocks[1][0]}: exit {rc}; printed {got} (page 0.154, 0.15); {tail(err, 200) if rc else ''}",
    )


@probe("AY40")
def _():
    ln, code = py_blocks("docs/library.md")[2]
    (WD / "lib3.py").write_text(code)
    rc, out, err = sh(f"{sys.executable} lib3.py")
    ok = rc == 0 and re.match(r"True 0\.2437", out.strip())
    return (
        bool(ok),
        f"docs/library.md:{ln}: exit {rc}; printed {out.strip()!r} (page: True 0.2437...); {tail(err, 200)}",
    )


@probe("AY41")
def _():
    ln, code = py_blocks("docs/modal.md")[0]
    (WD / "modal.py").write_text(code)
    rc, out, err = sh(f"{sys.executable} modal.py")
    return rc == 0 and not tb(err), f"docs/modal.md:{ln}: exit {rc}; {tail(err, 200)}"


# ============================================================== names
NAME = re.compile(r"`(stabctl(?:\.[A-Za-z_][A-Za-z0-9_]*)+)")


def resolves(dotted):
    import importlib

    parts = dotted.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        try:
            for p in parts[i:]:
                obj = getattr(obj, p)
            return True
        except AttributeError:
            return False
    return False


@probe("AY42")
def _():
    sys.path.insert(0, str(CLONE))
    files = ["README.md"] + sorted(
        str(p.relative_to(CLONE))
        for p in (CLONE / "docs").glob("*.md")
        if p.name != "cli_reference.md"
    )
    bad, n = [], 0
    for f in files:
        text = page(f)
        for m in NAME.finditer(re.sub(r"\.\n\s*", ".", text)):
            name = m.group(1).rstrip(".")
            n += 1
            if not resolves(name):
                i = text.find(name)
                ln = text[:i].count("\n") + 1 if i >= 0 else "?"
                bad.append(f"{f}:{ln} {name}")
    bad = sorted(set(bad))
    return (
        not bad,
        f"{n} `stabctl.x` names in the pages; not importable: {bad[:25]}{' ...' if len(bad) > 25 else ''} ({len(bad)})",
    )


SYN = re.compile(r"`(stabctl (?:[a-z-]+ ){1,2}[^`]*--[^`]*)`")


@probe("AY43")
def _():
    # options in the pages' synopses (cli.md:155-171, placement.md:22, modal.md:348, ...)
    files = ["README.md"] + sorted(
        str(p.relative_to(CLONE))
        for p in (CLONE / "docs").glob("*.md")
        if p.name != "cli_reference.md"
    )
    helps, bad, n = {}, [], 0
    groups = {"estimate", "pmu"}
    for f in files:
        text = page(f)
        for m in SYN.finditer(text):
            s = " ".join(m.group(1).split())
            w = s.split()
            cmd = w[1:3] if w[1] in groups else w[1:2]
            if len(cmd) == 2 and cmd[1].startswith("-"):
                continue
            key = " ".join(cmd)
            if key not in helps:
                rc, o, e = sh(f"stabctl {key} --help", 120)
                helps[key] = o if rc == 0 else None
            h = helps[key]
            ln = text[: m.start()].count("\n") + 1
            if h is None:
                bad.append(f"{f}:{ln} `stabctl {key}`: no such command")
                continue
            for opt in set(re.findall(r"(?<![\w-])(--[a-z][a-z0-9-]*)", s)):
                n += 1
                if not re.search(rf"(?<![\w-]){re.escape(opt)}(?![\w-])", h):
                    bad.append(f"{f}:{ln} {key} {opt}")
    bad = sorted(set(bad))
    return not bad, f"{n} options in {len(helps)} commands' synopses; not in --help: {bad}"


@probe("AY44")
def _():
    # simulator.md:73: writes the committed dispatch; run as written it changes nothing
    where, rc, out, err = doc_run(
        "docs/simulator.md", "python -m stabctl.models.dispatch", cwd=CLONE
    )
    r, o, e = sh("git status --porcelain stabctl/", cwd=CLONE)
    return (
        rc == 0 and not o.strip(),
        f"{where}: exit {rc}; changed: {o.strip() or 'nothing'}; {tail(err, 160)}",
    )


@probe("AY45")
def _():
    # README.md:40 / setup.md:8 without `&& stabctl paper` (skipped: minutes), in a clone
    cmd = "python3 -m venv .venv && . .venv/bin/activate && pip install . && stabctl paper"
    ln = written("README.md", cmd)
    d = WD / "inst"
    subprocess.run(["git", "clone", "-q", str(CLONE), str(d)], check=True)
    env = {k: v for k, v in ENV.items() if k != "PYTHONPATH"}
    env["PATH"] = env["PATH"].replace(f"{BIN}:", "")
    rc, out, err = sh(cmd.replace(" && stabctl paper", ""), 900, cwd=d, env=env)
    if rc != 0:
        return False, f"README.md:{ln}: install exit {rc}: {tail(err, 300)}"
    r2, o2, e2 = sh(
        ". .venv/bin/activate && cd .. && stabctl cct kundur --fault 3 --far-bus 101 && stabctl paper --help",
        900,
        cwd=d,
        env=env,
    )
    return verdict(f"README.md:{ln} (installed stabctl)", r2, o2, e2, ["CCT 0.154 s = 9.24 cycles"])


@probe("AY46")
def _():
    # placement.md:576-582: the CCTs without storage of the placement faults
    # ("`stabctl cct CASE --fault B --far-bus F` gives each")
    table = {
        (
            "ieee39_full.json",
            "ieee39/ieee39_full.xlsx",
        ): "10-13 0.178, 16-17 0.210, 21-22 0.234, 23-24 0.258, 17-27 0.310",
        (
            "npcc.json",
            "npcc/npcc.xlsx",
        ): "16-29 0.131, 85-88 0.141, 14-15 0.154, 13-14 0.170, 1-2 0.198",
        (
            "wecc_full.json",
            "wecc/wecc_full.xlsx",
        ): "7-16 0.164, 84-155 0.205, 43-159 0.222, 75-77 0.255, 15-135 0.279, 118-128 0.305",
    }
    ln = written("docs/placement.md", "stabctl cct CASE --fault B --far-bus F")
    bad, n = [], 0
    for (case, xlsx), row in table.items():
        d = andes_case(case, xlsx)
        for item in row.split(", "):
            f, cct = item.split()
            b, fb = f.split("-")
            r, o, e = sh(f"stabctl cct {case} --fault {b} --far-bus {fb}", 600, cwd=d)
            m = re.search(r"CCT ([\d.]+) s", o)
            n += 1
            if r != 0 or not m or m.group(1) != cct:
                bad.append(
                    f"{case} {f}: {m.group(1) if m else f'exit {r} ' + tail(e, 120)} (page {cct})"
                )
    return not bad, f"docs/placement.md:{ln} table (:578-582): {n} CCTs; differing: {bad}"


def regenerated(page_name, cmd, timeout):
    """Run a page's generator as written (it rewrites the page in CLONE), diff, restore."""
    where, rc, out, err = doc_run(page_name, cmd, timeout, cwd=CLONE)
    r, diff, _ = sh(f"git diff -U0 -- {page_name}", cwd=CLONE)
    sh(f"git checkout -- {page_name}", cwd=CLONE)
    if rc != 0:
        return False, f"{where}: exit {rc}: {tail(err, 300)}"
    changed = [
        ln for ln in diff.splitlines() if ln[:1] in "+-" and not ln.startswith(("+++", "---"))
    ]
    return (
        not changed,
        f"{where}: the page as regenerated differs in {len(changed)} line(s): {tail(' || '.join(changed), 900)}",
    )


@probe("AY47")
def _():
    return regenerated(
        "docs/psse_runs.md", "python benchmarks/psse_runs.py --markdown docs/psse_runs.md", 1500
    )


@probe("AY48")
def _():
    return regenerated(
        "docs/andes_coverage.md",
        "python benchmarks/andes_coverage.py --markdown docs/andes_coverage.md",
        1800,
    )


@probe("AY49")
def _():
    where, rc, out, err = doc_run(
        "docs/ibr.md", "python benchmarks/psse_runs.py DERA_FREQFLAG0", 900, cwd=CLONE
    )
    # ibr.md:1036: largest |dV102| 1.8e-4 pu and |d angle V102| 7.3e-4 rad
    rows = {q: re.search(rf"\| {q}[^|]*\| ([0-9.e+-]+) \|", out) for q in ("V102", "angle V102")}
    got = {q: float(m.group(1)) if m else None for q, m in rows.items()}
    ok = (
        rc == 0
        and got["V102"] is not None
        and f"{got['V102']:.1e}" == "1.8e-04"
        and f"{got['angle V102']:.1e}" == "7.3e-04"
    )
    return (
        ok,
        f"{where}: exit {rc}; V102 {got['V102']} (page 1.8e-4), angle {got['angle V102']} (page 7.3e-4)",
    )


@probe("AY50")
def _():
    # cli.md:42: stdout closed -> one line `error: cannot write to standard output (stdout): ...`, status 2
    ln = written("docs/cli.md", "error: cannot write to standard output (stdout): <reason>")
    rc, out, err = sh("stabctl cases kundur >&-")
    lines = [x for x in err.splitlines() if x.strip()]
    ok = (
        rc == 2
        and len(lines) == 1
        and lines[0].startswith("error: cannot write to standard output (stdout): ")
    )
    return ok, f"docs/cli.md:{ln}: `stabctl cases kundur >&-`: exit {rc}, stderr {lines}"


def place_row(case, xlsx, faults, gain, figures, where_cmd):
    d = andes_case(case, xlsx)
    (d / "examples").exists() or (d / "examples").symlink_to(CLONE / "examples")
    scr = case.replace(".json", "_screen.jsonl")
    if not (d / scr).exists():
        r, o, e = sh(f"stabctl screen {case} --lines --out {scr} --workers 2", 900, cwd=d)
        if r != 0:
            return False, f"screen {case}: exit {r}: {tail(e, 200)}"
    cmd = (
        f"stabctl place {case} --faults examples/placement/{faults} "
        f"--target-cct-gain {gain} --set-aside-infeasible --screening {scr} --workers 2"
    )
    rc, out, err = sh(cmd, 900, cwd=d)
    both = out + err
    miss = [f for f in figures if f not in both]
    ok = rc == 0 and not miss and not tb(err)
    return (
        ok,
        f"{where_cmd} ({case}, +{gain} %): exit {rc}; page figures not printed: {miss}; {tail(out, 500)}",
    )


@probe("AY51")
def _():
    ln = written(
        "docs/placement.md",
        "stabctl place ieee39_full.json --faults examples/placement/ieee39_faults.csv",
    )
    # placement.md:596 CCT +5 %, IEEE 39 row
    return place_row(
        "ieee39_full.json",
        "ieee39/ieee39_full.xlsx",
        "ieee39_faults.csv",
        5,
        ["348.4", "102.0", "246.4", "0.226", "0.248", "0.326", "280 runs simulated"],
        f"docs/placement.md:{ln} table :596",
    )


@probe("AY52")
def _():
    ln = written(
        "docs/placement.md",
        "stabctl place ieee39_full.json --faults examples/placement/ieee39_faults.csv",
    )
    # placement.md:589 (+20 %) and :597 (+5 %), NPCC rows
    ok1, why1 = place_row(
        "npcc.json",
        "npcc/npcc.xlsx",
        "npcc_faults.csv",
        20,
        ["NOTHING TO PLACE", "190 runs simulated"],
        f"docs/placement.md:{ln} table :589",
    )
    ok2, why2 = place_row(
        "npcc.json",
        "npcc/npcc.xlsx",
        "npcc_faults.csv",
        5,
        ["499.0", "33.2", "99.3", "15.6", "350.9", "523 runs simulated"],
        f"docs/placement.md:{ln} table :597",
    )
    return ok1 and ok2, f"{why1} || {why2}"


@probe("AY53")
def _():
    cmd = "python analysis/ambient_step.py kundur 0.005 0.0041666666666666667 0.0020833333333333333 0.0010416666666666667"
    where, rc, out, err = doc_run("docs/estimation.md", cmd, 900, cwd=CLONE)
    if rc != 0:
        return False, f"{where}: exit {rc}: {tail(err, 300)}"
    # estimation.md:328-331: true raw kf ekf (mHz) per step
    page_rows = [
        ("0.005", "9.01 10.24 10.04 9.96"),
        ("0.00416", "9.02 10.44 10.22 9.96"),
        ("0.00208", "9.02 10.44 10.22 9.96"),
        ("0.00104", "9.02 10.44 10.22 9.96"),
    ]
    lines = [ln for ln in out.splitlines() if ln.strip()]
    bad = []
    for i, (h, figs) in enumerate(page_rows):
        row = next((ln for ln in lines if ln.split()[:1] and ln.split()[0].startswith(h)), None)
        if row is None:
            row = next((ln for ln in lines if f"{float(h) * 1e3:.2f}" in ln), None)
        if row is None:
            bad.append(f"no row for {h}")
            continue
        miss = [f for f in figs.split() if not agree(f, row)]
        if miss:
            bad.append(f"{h}: {miss} not in {row.strip()!r}")
    return (
        not bad,
        f"{where}: exit 0; the Kundur rows (:328-331): {bad or 'as the page'}; {tail(out, 300) if bad else ''}",
    )


@probe("AY54")
def _():
    # cli.md:320-321: Kundur (ieee) 5 % raises the Case-1 CCT from 9.2 to 11.9 cycles, 30 % to 20.5;
    # cli.md:337-339: fault at bus 3, line 3-20 tripped: 0.59 pu, 59.1 Hz at t = 20 s (--tf 20),
    # 0.56 pu and 58.5 Hz at the default 6 s
    bad = []
    for args, fig in (("", "9.2"), ("--esd-pct 5", "11.9"), ("--esd-pct 30", "20.5")):
        r, o, e = sh(f"stabctl cct kundur --fault 3 --far-bus 101 {args}")
        m = re.search(r"= ([\d.]+) cycles", o)
        if not m or not agree(fig, m.group(1)):
            bad.append(f"{args or 'none'}: {m.group(1) if m else r} (page {fig})")
    for tf, figs in (("--tf 20", ("0.59", "59.1")), ("", ("0.56", "58.5"))):
        r, o, e = sh(f"stabctl simulate kundur --fault 3 --far-bus 20 {tf}")
        note = next((ln for ln in o.splitlines() if "note: at the end" in ln), "")
        m = re.search(r"at ([\d.]+) pu and the machines it judges at ([\d.]+) Hz", note)
        if not m or not (agree(figs[0], m.group(1)) and agree(figs[1], m.group(2))):
            bad.append(f"3-20 {tf or 'default'}: {note.strip()[:120]} (page {figs})")
    return (
        not bad,
        f"docs/cli.md:320,337: Kundur CCT cycles with storage and the 3-20 end state: {bad or 'as the page'}",
    )


@probe("AY55")
def _():
    # cli.md:426-431: Kundur 1-10 CCT 0.440 s / 0.337 s --tf 10 / 0.001 s --tf 20; Case 1 under
    # pstess 0.269 s = 16.14 cycles, error 20 ms; Case 2 0.076 s = 4.56 cycles, error 0 ms, both
    runs = [
        ("kundur --fault 1 --far-bus 10", ["CCT 0.440 s"]),
        ("kundur --fault 1 --far-bus 10 --tf 10", ["CCT 0.337 s"]),
        ("kundur --fault 1 --far-bus 10 --tf 20", ["CCT 0.001 s"]),
        (
            "kundur --fault 3 --far-bus 101 --conventions pstess",
            ["CCT 0.269 s = 16.14 cycles", "numerical error 20 ms"],
        ),
        ("miniwecc --fault 83 --far-bus 33", ["CCT 0.076 s = 4.56 cycles", "numerical error 0 ms"]),
        (
            "miniwecc --fault 83 --far-bus 33 --conventions pstess",
            ["CCT 0.076 s = 4.56 cycles", "numerical error 0 ms"],
        ),
    ]
    bad = []
    for args, figs in runs:
        r, o, e = sh(f"stabctl cct {args}")
        miss = [f for f in figs if f not in o]
        if r != 0 or miss:
            got = re.findall(r"CCT [^(]*|numerical error \d+ ms", o)
            bad.append(f"{args}: {miss} not printed (got {got[:2]}, exit {r})")
    return not bad, f"docs/cli.md:427-431: {len(runs)} cct runs: {bad or 'as the page'}"


def text_block(name, first):
    """The ```text block of page `name` starting with `first`: (line, text)."""
    text = page(name)
    m = re.search(r"```text\n(" + re.escape(first) + r".*?)```", text, re.S)
    return text[: m.start()].count("\n") + 2, m.group(1)


def port_busy(port):
    r = subprocess.run(["ss", "-ltn"], capture_output=True, text=True)
    return f":{port} " in r.stdout


@probe("AY56")
def _():
    ln, block = text_block("docs/estimation.md", "stabctl pmu serve kundur")
    if port_busy(4712):
        return False, f"docs/estimation.md:{ln}: port 4712 busy (another user), not run"
    rc, out, err = sh(block + "\nwait\n", 600)
    ok = rc == 0 and not tb(err) and "ekf" in out
    return (
        ok,
        f"docs/estimation.md:{ln}: the block as written (serve &, then rmse --source): exit {rc}; {tail(err if rc else out, 300)}",
    )


@probe("AY57")
def _():
    ln, block = text_block("docs/estimation.md", "stabctl pmu record 127.0.0.1:4712")
    if port_busy(4712):
        return False, f"docs/estimation.md:{ln}: port 4712 busy (another user), not run"
    # the server the text names (`pmu serve --tf 60`), started first and given time to listen
    serve = "stabctl pmu serve miniwecc --fault 83 --far-bus 33 --tf 60 --speed 0 --port 4712 --wait 60 &\nsleep 20\n"
    rc, out, err = sh(serve + block + "\nwait\n", 900)
    ok = rc == 0 and not tb(err) and (WD / "tracked.csv").exists()
    n = len((WD / "tracked.csv").read_text().splitlines()) if (WD / "tracked.csv").exists() else 0
    return (
        ok,
        f"docs/estimation.md:{ln}: record 3601 frames + track: exit {rc}; tracked.csv {n} lines; {tail(err if rc else out, 300)}",
    )


@probe("AY58")
def _():
    ln, block = text_block("docs/estimation.md", "stabctl estimate closed-loop miniwecc")
    if port_busy(4713):
        return False, f"docs/estimation.md:{ln}: port 4713 busy (another user), not run"
    cmds = [c.split("  #")[0] for c in block.replace("\\\n", " ").splitlines() if c.strip()]
    r1, o1, e1 = sh(cmds[0], 600)
    r2, o2, e2 = sh("\n".join(cmds[1:]) + "\nwait\n", 600)
    ok = r1 == 0 and r2 == 0 and not tb(e1 + e2)
    return ok, (
        f"docs/estimation.md:{ln}: closed-loop --transport tcp exit {r1} ({tail(e1 if r1 else o1, 160)}); "
        f"plant & + control exit {r2} ({tail(e2 if r2 else o2, 200)})"
    )


@probe("AY59")
def _():
    cmd = "python benchmarks/converter_bus_faults.py --markdown FILE"
    ln = written("docs/ibr.md", cmd)
    rc, out, err = sh(cmd.replace("FILE", str(WD / "cbf.md")), 1500, cwd=CLONE)
    if rc != 0:
        return False, f"docs/ibr.md:{ln}: exit {rc}: {tail(err, 300)}"
    # the Kundur rows (stored ANDES runs) as the page's; the IEEE 14 rows come from
    # `--andes live` (ibr.md:922, about 100 s a case: not run), "not stored" here
    row = re.compile(r"^\| (kundur|ieee14)\S*\.(xlsx|json) \| \d")
    key = lambda x: tuple(x.split("|")[1:3])
    mine = {key(x): x for x in (WD / "cbf.md").read_text().splitlines() if row.match(x)}
    doc = {key(x): x for x in page("docs/ibr.md").splitlines() if row.match(x)}
    kundur = {k for k in doc if k[0].strip().startswith("kundur")}
    diff = [
        f"{doc.get(k)} -> {mine.get(k)}"
        for k in sorted(kundur | set(mine))
        if doc.get(k) != mine.get(k)
    ]
    unstored = (WD / "cbf.md").read_text().count("ANDES's runs not stored")
    return not diff, (
        f"docs/ibr.md:{ln}: {len(mine)} Kundur rows against the page's {len(kundur)}; differing: "
        f"{tail(' || '.join(diff[:6]), 600) or 'none'}; {unstored} IEEE 14 cases 'not stored' (page :922: --andes live)"
    )


@probe("AY60")
def _():
    # placement.md:666-668 and :684-688: ANDES cases planned with `--set-aside-infeasible
    # --workers 1` (the table's options; faults as listed, a bus fault `far_bus` empty)
    rows = [
        (
            "5bus/pjm5bus.xlsx",
            "1,2\n5,3\n2,\n",
            "--target-cct-gain 10",
            ["53.6 MW", "67 runs simulated"],
            ":666",
        ),
        (
            "kundur/kundur_motor.xlsx",
            "6,7\n8,9\n",
            "--target-cct-gain 10 --no-q-limits",
            ["118.3 MW", "148 runs simulated"],
            ":667",
        ),
        (
            "ieee14/ieee14_gast.xlsx",
            "1,2\n2,3\n",
            "--target-cct-gain 10",
            ["NOTHING TO PLACE", "74 runs simulated"],
            ":668",
        ),
        (
            "kundur/kundur_full.xlsx",
            "6,7\n9,10\n8,\n",
            "--target-cct-gain 10 --no-q-limits",
            ["126.1 MW"],
            ":686",
        ),
        ("smib/SMIB.xlsx", "3,2\n", "--target-cct-gain 10 --no-q-limits", ["45.0 MW"], ":688"),
    ]
    d = WD / "andes_place"
    d.mkdir(exist_ok=True)
    bad = []
    for xlsx, faults, opts, figs, at in rows:
        name = Path(xlsx).stem
        r, path, _ = sh(f"{sys.executable} -c \"import andes; print(andes.get_case('{xlsx}'))\"")
        if not (d / f"{name}.json").exists():
            r, o, e = sh(f"stabctl import-andes {path.strip()} -o {name}.json", 600, cwd=d)
            if r != 0:
                bad.append(f"{at} import {xlsx}: exit {r}: {tail(e, 160)}")
                continue
        (d / f"{name}.csv").write_text("bus,far_bus\n" + faults)
        r, o, e = sh(
            f"stabctl place {name}.json --faults {name}.csv {opts} --set-aside-infeasible --workers 1",
            900,
            cwd=d,
        )
        miss = [f for f in figs if f not in o + e]
        if r not in (0, 1) or miss or tb(e):
            head = next((ln for ln in o.splitlines() if ln.startswith("case ")), "")
            runs = re.findall(r"\d+ runs simulated", o)
            bad.append(f"{at} {name}: exit {r}, {miss} not printed; {head[:160]} {runs}")
    return not bad, f"docs/placement.md:666-688: {len(rows)} ANDES plans: {bad or 'as the page'}"


@probe("AY61")
def _():
    d = andes_case("ieee39_full.json", "ieee39/ieee39_full.xlsx")
    (d / "analysis").exists() or (d / "analysis").symlink_to(CLONE / "analysis")
    where, rc, out, err = doc_run(
        "docs/placement.md",
        "python analysis/storage_lowers_cct.py ieee39_full.json 26 29 20",
        900,
        cwd=d,
    )
    # placement.md:472-476: the three causes' table and 0.497 s without storage
    figs = ["0.436", "0.531", "0.446", "0.511", "0.428", "0.512", "0.497"]
    miss = [f for f in figs if f not in out]
    ok = rc == 0 and not miss and not tb(err)
    return (
        ok,
        f"{where}: exit {rc}; page CCTs not printed: {miss}; {tail(out, 300) if miss else ''}",
    )


if __name__ == "__main__":
    KIT.main(banner="work dir {wd}, package {clone}", keep_any=True)
