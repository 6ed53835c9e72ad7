"""Twelfth reliability round (round 36, part E): a newcomer's first hours and the Python
API, on systems beyond the two home ones (PSS/E's ThreeBusMulti with GENROU, an infinite
bus, and the five-bus 50 Hz case of tests/data, ANDES's IEEE 39 and Kundur files).

README's one-minute start, every ```python block of README.md and docs/*.md (the values
their comments promise), the public docstrings' examples, examples/*.py, every example of
every --help and the options and defaults docs/cli.md names; simulate (--out csv, npz,
--json), cct, eig and place against the library's own figures on those cases; the public
entry points given wrong types, units, shapes and other systems' data; a sweep whose marks
directory in TMPDIR is removed while it runs.

Contract: each probe runs `stabctl` commands, or a Python script using the library, in
fresh processes (the package of this repository first on PYTHONPATH), each in its own
session under a timeout, and states what a careful library does: the views of one run
agree; a wrong argument is refused by a stabctl error naming it, as the CLI refuses the
option, not accepted with a silently wrong figure nor left to numpy's error deep inside.
The round found short: FrequencyKF left at f0 = 60 Hz on a 50 Hz case (speeds of 0.83 pu,
no word), Simulator.run's separation_limit and BangBangCOI's deadband_hz without the CLI's
ranges (180 -- degrees meant -- called a run stable whose machines slipped 87 rad; 100 --
mHz meant -- left every device idle), modal_analysis given a discrete-time model, zero
inertias or a model sliced by python-control (read as continuous, numpy's warning, a bare
ValueError), mode_sensitivity given a mismatched model and analysis (numpy's matmul
error), modal_analysis's areas with unknown or text keys (dropped without a word), the
C37.118.2 API's rate checks (stream_config, record and replay wrote and read a 50 Hz stream
under a CFG-2 of 60), a sweep whose marks directory was removed (every job recorded
failed), omib's help example (an option omib has not), fault_with_clearing's
far_clear_cycles on a bus fault (dropped), the inertia docstring (silent on an infinite
bus's 1 and 0), screen() given a loaded Case (an error naming load_case) and
SimulationResult's accessors (speed_at of one time, machine('1')).  They are fixed and the
probes are now their regression checks.

    python benchmarks/reliability_probes_12.py [-k SUBSTRING] [-v] [ID ...]

ID: a probe's name (``api.deadband_mhz``) or its prefix before the first ``.`` (``doc``,
``help``, ``cons``, ``api``, ``env``).  One line per probe (name, ok or SHORT, what was
checked and measured, its seconds), then the counts; -v adds the children's output under
each line.  Needs Linux (/proc), PSS/E's ThreeBusMulti and five-bus files of tests/data
and the ``control`` package; help.examples uses ANDES's case files when ``andes`` is
installed.  NUMBA_CACHE_DIR is the caller's (numba's default when unset); `stabctl compile`
is run first (seconds with a warm cache, about a minute cold).  The work directory is a new
temporary directory, removed at the end unless KEEP is set.  About 6 minutes on two idle
cores with a warm kernel cache (more on busy ones).  Exit status 1 if any probe is short.
"""

from __future__ import annotations

import argparse
import glob
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import textwrap
import time
import traceback
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]  # the package under test
STABCTL = [sys.executable, "-m", "stabctl"]
ENV = dict(
    os.environ,
    PYTHONPATH=os.pathsep.join([str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])]),
)
ENV.pop("PYTHONWARNINGS", None)
PSSE = ROOT / "tests" / "data" / "psse"  # the five-bus 50 Hz case
RUNS = ROOT / "tests" / "data" / "psse_runs"  # PSS/E's ThreeBusMulti runs
WORK = Path(tempfile.mkdtemp(prefix="stabctl-probes-12."))
RESULTS: list[tuple[str, bool, str]] = []
PROBES: list = []
SESSIONS: list[int] = []
VERBOSE = False
_N = [0]


# ---------------------------------------------------------------- processes


def session_procs(sid):
    """The processes (not zombies) of session sid."""
    out = []
    for d in glob.glob("/proc/[0-9]*"):
        try:
            with open(d + "/stat") as f:
                st = f.read()
            fields = st[st.rindex(")") + 2 :].split()
            if int(fields[3]) == sid and fields[0] != "Z":
                out.append(int(d[6:]))
        except (OSError, ValueError):
            pass
    return out


def kill_session(sid):
    for pid in session_procs(sid):
        try:
            os.kill(pid, signal.SIGKILL)
        except OSError:
            pass


def sh(argv, cwd=None, timeout=300, env=None):
    """(rc, stdout, stderr) of argv in its own session (cwd: the work directory); rc 124 on
    timeout.  Whatever the session still holds afterwards is killed."""
    p = subprocess.Popen(
        [*map(str, argv)],
        cwd=cwd or WORK,
        env=env or ENV,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    SESSIONS.append(p.pid)
    try:
        out, err = p.communicate(timeout=timeout)
        rc = p.returncode
    except subprocess.TimeoutExpired:
        kill_session(p.pid)
        out, err = p.communicate()
        rc, err = 124, f"{err}\nTIMEOUT after {timeout} s"
    kill_session(p.pid)
    return rc, out, err


def stab(*args, cwd=None, timeout=300):
    """`stabctl args`: (rc, stdout, stderr)."""
    return sh([*STABCTL, *args], cwd=cwd, timeout=timeout)


def py(code, cwd=None, timeout=300):
    """A Python script (dedented) run in a fresh process: (rc, stdout, stderr)."""
    _N[0] += 1
    path = WORK / f"_script{_N[0]}.py"
    path.write_text(textwrap.dedent(code))
    return sh([sys.executable, path], cwd=cwd, timeout=timeout)


def subdir():
    return Path(tempfile.mkdtemp(dir=WORK))


def last_line(text):
    lines = text.strip().splitlines()
    return lines[-1] if lines else ""


def imported():
    """ThreeBus GENROU (tb.json) and the five-bus 50 Hz case (fb.json), imported into the
    work directory once."""
    jobs = (
        ("tb.json", RUNS / "GENROU" / "ThreeBusMulti.raw", RUNS / "GENROU" / "ThreeBus_GENROU.dyr"),
        ("fb.json", PSSE / "five_bus_v33.raw", PSSE / "five_bus.dyr"),
    )
    for name, raw, dyr in jobs:
        if not (WORK / name).exists():
            rc, _, err = stab("import-psse", raw, dyr, "-o", name)
            if rc:
                raise RuntimeError(f"import-psse {raw.name}: exit {rc}: {last_line(err)}")


# ---------------------------------------------------------------- reporting


def probe(pid):
    """A probe named pid, returning (ok, why) or (ok, why, the children's output)."""

    def deco(f):
        f.pid = pid
        PROBES.append(f)
        return f

    return deco


def report(pid, ok, why, seconds, detail=""):
    RESULTS.append((pid, ok, why))
    print(f"{pid:<36} {'ok   ' if ok else 'SHORT'} {why}  [{seconds:.0f} s]", flush=True)
    if VERBOSE and detail.strip():
        print(textwrap.indent(detail.strip()[-3000:], "    | "), flush=True)


# ---------------------------------------------------------------- docs


@probe("doc.readme_console")
def doc_readme_console():
    """README's one-minute start: the three commands print the figures it shows."""
    want = [
        (["simulate", "miniwecc", "--fault", "83", "--far-bus", "33", "--clear-cycles", "6",
          "--esd-pct", "5"], "stable: largest angle from the COI 1.8940 rad"),
        (["cct", "kundur", "--fault", "3", "--far-bus", "101"], "CCT 0.154 s = 9.24 cycles"),
        (["eig", "kundur"], "36   0.612   0.1319  inter-area"),
    ]  # fmt: skip
    bad = []
    for args, needle in want:
        rc, out, _ = stab(*args)
        if rc != 0 or needle not in out:
            bad.append(f"{' '.join(args)}: exit {rc}, '{needle}' not printed")
    return not bad, "; ".join(bad) or (
        "simulate, cct and eig print README's '" + "', '".join(n for _, n in want) + "'"
    )


@probe("doc.python_blocks")
def doc_python_blocks():
    """Every ```python block of README.md and docs/*.md runs (a file's blocks as one
    script, as they build on each other); the values their print() comments promise."""
    by_file: dict[str, list[str]] = {}
    for f in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]:
        for b in re.findall(r"```python\n(.*?)```", f.read_text(), re.S):
            by_file.setdefault(f.name, []).append(b)
    bad, detail, n_values = [], "", 0
    for name, bs in by_file.items():
        code = "\n".join(bs)
        rc, out, err = py(code, cwd=subdir(), timeout=600)
        detail += f"{name}:\n{out}{err}"
        if rc != 0:
            bad.append(f"{name}: exit {rc}: {last_line(err)[:150]}")
            continue
        for needle in re.findall(r"print\(.*\)\s*#\s*(.+)", code):
            n_values += 1
            first = needle.split("...")[0].strip()
            if first not in out:
                bad.append(f"{name}: comment says '{needle.strip()}', output {out.split()[:6]}")
    n_blocks = sum(map(len, by_file.values()))
    return (
        not bad,
        "; ".join(bad)
        or f"{n_blocks} python blocks of {len(by_file)} files ({', '.join(by_file)}) run; "
        f"the {n_values} values their print() comments give are printed",
        detail,
    )


@probe("doc.doctests")
def doc_doctests():
    """The Examples sections of the public docstrings (doctest)."""
    mods = ["stabctl.storage.devices", "stabctl.stability.cct", "stabctl.io",
            "stabctl.smallsignal.linearise", "stabctl.smallsignal.modal"]  # fmt: skip
    rc, out, err = py(
        f"""
        import doctest, importlib
        f = a = 0
        for m in {mods!r}:
            flags = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE
            r = doctest.testmod(importlib.import_module(m), optionflags=flags)
            f += r.failed; a += r.attempted
        print("RESULT", f, a)
        """,
        timeout=600,
    )
    m = re.search(r"RESULT (\d+) (\d+)", out)
    ok = rc == 0 and bool(m) and m.group(1) == "0" and int(m.group(2)) > 0
    why = (
        f"{m.group(2)} docstring examples of {len(mods)} modules, {m.group(1)} failed"
        if m
        else f"exit {rc}: {last_line(err)[:150]}"
    )
    return ok, why, out + err


@probe("doc.examples_scripts")
def doc_examples_scripts():
    """examples/*.py as docs/examples.md says: each runs as it is, in an empty directory."""
    bad, names, detail = [], [], ""
    for f in sorted((ROOT / "examples").glob("*.py")):
        rc, _, err = sh([sys.executable, f], cwd=subdir(), timeout=300)
        names.append(f.name)
        detail += f"{f.name}: exit {rc}\n{err[-500:]}"
        if rc != 0:
            bad.append(f"{f.name} exit {rc}: {last_line(err)[:100]}")
    return (
        not bad and bool(names),
        "; ".join(bad) or (f"{len(names)} scripts exit 0: {', '.join(names)}"),
        detail,
    )


# ---------------------------------------------------------------- help texts


def help_text(cmd):
    return stab(*cmd.split(), "--help")[1]


@probe("help.examples")
def help_examples():
    """Every 'Example(s):' command of every --help runs (those needing no server, no user
    file and no minutes); ANDES's case files copied in, as the examples assume, when the
    andes package is installed."""
    import importlib.util

    cmds = ["cases", "compile", "eig", "import-andes", "import-psse", "omib", "paper", "place",
            "screen", "sweep-cct", "simulate", "cct", "estimate rmse", "estimate closed-loop",
            "estimate cct"]  # fmt: skip
    lines = []
    for c in cmds:
        m = re.search(r"Examples?[^\n]*:\n((?:    .*\n|\n)+)", help_text(c))
        if m:
            joined = m.group(1).replace("\\\n", " ")
            lines += [ln.strip() for ln in joined.splitlines() if ln.strip().startswith("stabctl ")]
    d = subdir()
    has_andes = importlib.util.find_spec("andes") is not None
    if has_andes:
        import andes  # only to find ANDES's case files

        for c in ("ieee39/ieee39_full.xlsx", "kundur/kundur.raw", "kundur/kundur_full.dyr"):
            shutil.copy(andes.get_case(c), d)
    # a user's file, a scheduler, minutes of work
    skip = ("faults.csv", "--scheduler", "paper --out-dir", "place kundur", "--workers 2 --plot")
    if not has_andes:
        skip += ("ieee39", "kundur.raw", "kundur_full")
    lines.sort(key=lambda s: 0 if "import-" in s else 1)  # imports before their users
    bad, ran, skipped, detail = [], [], 0, ""
    for ln in dict.fromkeys(lines):
        if any(s in ln for s in skip):
            skipped += 1
            continue
        ran.append(ln.split()[1])
        rc, _, err = stab(*ln.split()[1:], cwd=d, timeout=600)
        detail += f"$ {ln}: exit {rc}\n"
        if rc != 0:
            bad.append(f"`{ln}` exit {rc}: {last_line(err)[:120]}")
    why = "; ".join(bad) or (
        f"{len(ran)} help examples exit 0 (of {', '.join(dict.fromkeys(ran))}; {skipped} skipped: "
        f"a user's file, a scheduler or minutes of work{'' if has_andes else ', no andes'})"
    )
    return not bad and bool(ran), why, detail


@probe("help.options_vs_docs")
def help_options_vs_docs():
    """Every option docs/cli.md's and README's synopses name is in the command's --help,
    and the defaults written [--opt V] there are --help's defaults."""
    src = (ROOT / "docs" / "cli.md").read_text() + (ROOT / "README.md").read_text()
    syn = re.findall(r"`(stabctl [a-z-]+(?: [a-z-]+)?) ([^`]*)`", src)
    opt_re = r"(?<![\w-])(--[a-z][a-z0-9-]*)"
    cache, bad, n, n_def = {}, [], 0, 0
    for cmd, rest in syn:
        w = cmd.split()
        if w[1] in ("estimate", "pmu") and len(w) == 2:
            continue
        if w[1] not in ("estimate", "pmu") and len(w) == 3:
            rest, cmd = w[2] + " " + rest, " ".join(w[:2])
        if cmd not in cache:
            out = help_text(cmd[len("stabctl ") :])
            cache[cmd] = (set(re.findall(opt_re, out.split("Options:")[-1])), out)
        opts, out = cache[cmd]
        if not out:
            continue
        for o in re.findall(opt_re, rest):
            n += 1
            if o not in opts:
                bad.append(f"{cmd} {o}")
        for o, val in re.findall(r"\[(--[a-z][a-z0-9-]*) ([0-9.]+)\]", rest):
            m = re.search(re.escape(o) + r"[^\n]*(?:\n {20,}[^\n]*)*?\[default: ([^\]]+)\]", out)
            if m:
                try:
                    n_def += 1
                    if float(m.group(1)) != float(val):
                        bad.append(f"{cmd} {o}: docs {val}, help {m.group(1)}")
                except ValueError:
                    pass
    return not bad and n > 0, "; ".join(sorted(set(bad))) or (
        f"{n} option mentions of {len(cache)} commands found in their --help; "
        f"{n_def} defaults written there agree with --help's"
    )


# ---------------------------------------------------------------- consistency of views


@probe("cons.simulate_psse_storage")
def cons_simulate_psse_storage():
    """ThreeBus (PSS/E GENROU run, an infinite bus) with 20 % storage: simulate --out csv,
    --out npz --json and Simulator.run give the same numbers, names and storage figures."""
    imported()
    args = ["simulate", "tb.json", "--fault", "103", "--far-bus", "101", "--clear-cycles", "8",
            "--esd-pct", "20"]  # fmt: skip
    r1 = stab(*args, "--out", "tb.csv")
    r2 = stab(*args, "--out", "tb.npz", "--json")
    if r1[0] or r2[0]:
        return False, f"simulate exit {r1[0]}, {r2[0]}", r1[2] + r2[2]
    (WORK / "tb.jsonout").write_text(r2[1])
    rc, out, err = py("""
        import json, csv, numpy as np, stabctl
        c = stabctl.load_case("tb.json"); sim = stabctl.Simulator(c)
        r = sim.run([stabctl.fault_with_clearing(c, 103, 101, 1.0, 8)], t_end=6.0,
                    storage=stabctl.uniform_fleet(c, 20))
        names, data = r.columns()
        rows = list(csv.reader(open("tb.csv"))); arr = np.array(rows[1:], float)
        z = np.load("tb.npz"); j = json.load(open("tb.jsonout"))
        bad = []
        if rows[0] != names: bad.append("csv header")
        if np.max(np.abs(arr - data) / np.maximum(1, np.abs(data))) > 1e-8:
            bad.append("csv values")
        for k in ("speed", "angle", "pesd", "vmag"):
            if not np.array_equal(z[k], getattr(r, k)): bad.append("npz " + k)
        if abs(j["max_angle_from_coi_rad"] - r.max_angle_from_coi) > 1e-12:
            bad.append("json angle")
        if j["storage"] != r.meta["storage"]: bad.append("json storage")
        want = {str(int(m)): c.machine_name(int(m)) for m in r.machines}
        if j["machine_names"] != want: bad.append("names")
        print("BAD", bad, "ANGLE", r.max_angle_from_coi, "DEV", len(r.meta["storage"]),
              "ROWS", len(arr), "COLS", len(names))
    """)
    m = re.search(r"BAD \[\] ANGLE ([\d.e+-]+) DEV (\d+) ROWS (\d+) COLS (\d+)", out)
    if rc or not m:
        return False, (last_line(out) or last_line(err))[-200:], out + err
    return (
        True,
        (
            f"csv ({m.group(3)} rows x {m.group(4)} columns: header and values), npz (speed, "
            f"angle, pesd, vmag), --json (largest angle {float(m.group(1)):.4f} rad, "
            f"{m.group(2)} storage device(s), machine names) = Simulator.run's"
        ),
        out + err,
    )


@probe("cons.cct_eig_50hz")
def cons_cct_eig_50hz():
    """five-bus 50 Hz case: cct --json and critical_clearing_time agree (cycles of 50 Hz);
    eig --json and modal_analysis have the same eigenvalues; f_bus outputs in Hz at 50 Hz."""
    imported()
    r1 = stab("cct", "fb.json", "--fault", "2", "--far-bus", "1", "--circuit", "2", "--json")
    r2 = stab("eig", "fb.json", "--json")
    if r1[0] or r2[0]:
        return False, f"cct exit {r1[0]}, eig exit {r2[0]}", r1[2] + r2[2]
    (WORK / "fbcct.json").write_text(r1[1])
    (WORK / "fbeig.json").write_text(r2[1])
    rc, out, err = py("""
        import json, numpy as np, stabctl, warnings
        warnings.simplefilter("ignore")
        c = stabctl.load_case("fb.json"); sim = stabctl.Simulator(c)
        r = stabctl.critical_clearing_time(sim, stabctl.LineFault(2, 1, 1.0, circuit=2))
        j = json.load(open("fbcct.json")); e = json.load(open("fbeig.json"))
        bad = []
        cli = (j["cct_s"], j["cct_cycles"], j["separated_machines"])
        if cli != (r.cct_s, r.cct_cycles, list(r.separated)): bad.append("cct")
        if abs(r.cct_cycles - r.cct_s * 50) > 1e-9: bad.append("cycles not of 50 Hz")
        lin = stabctl.linearise(sim); ma = stabctl.modal_analysis(lin)
        ev = np.array([complex(m["real_per_s"], m["imag_rad_per_s"]) for m in e["modes"]])
        d = np.max(np.abs(np.sort_complex(ev) - np.sort_complex(ma.eigenvalues)))
        if d > 1e-9: bad.append("eigenvalues")
        if list(map(int, ma.electromechanical)) != e["electromechanical_modes"]:
            bad.append("em modes")
        w, V = np.linalg.eig(lin.A); k = int(np.argmin(np.abs(w))); y = lin.C @ V[:, k]
        ol = lin.output_labels
        ratio = (y[ol.index("f_bus_B1")] / y[ol.index("omega_coi")]).real
        if abs(ratio - 50) > 0.01: bad.append(f"f_bus/omega {ratio}")
        print("BAD", bad, "CCT", r.cct_s, r.cct_cycles, "EV", len(ev), d, "RATIO", ratio)
    """)
    m = re.search(r"BAD \[\] CCT (\S+) (\S+) EV (\d+) (\S+) RATIO (\S+)", out)
    if rc or not m:
        return False, (last_line(out) or last_line(err))[-200:], out + err
    return (
        True,
        (
            f"cct --json = critical_clearing_time: {float(m.group(1)):.4f} s = "
            f"{float(m.group(2)):.2f} cycles of 50 Hz; eig --json's {m.group(3)} eigenvalues = "
            f"modal_analysis's (largest difference {float(m.group(4)):.1e}); f_bus / omega_coi "
            f"{float(m.group(5)):.4f} Hz/pu"
        ),
        out + err,
    )


@probe("cons.place_plan_verified")
def cons_place_plan_verified():
    """place kundur (its help example): the plan's text names its total, and a
    StorageFleet of its allocation gives the CCTs the plan reports."""
    d = subdir()
    rc, out, err = stab("place", "kundur", "--faults", "DEFAULT", "--target-cct-gain", "10",
                        "--out", "plan.json", cwd=d, timeout=900)  # fmt: skip
    if rc:
        return False, f"place exit {rc}: {last_line(err)[:150]}", err
    rc, pout, perr = py(
        """
        import json, stabctl
        d = json.load(open("plan.json"))
        c = stabctl.load_case("kundur"); sim = stabctl.Simulator(c)
        fl = stabctl.StorageFleet(tuple(stabctl.StorageDevice(a["bus"], a["machine"], a["mw"])
                                        for a in d["allocation"]))
        bad = []
        for k in d["contingencies"]:
            b, f = map(int, k["name"].split("-"))
            r = stabctl.critical_clearing_time(sim, stabctl.LineFault(b, f), storage=fl)
            if abs(r.cct_s - k["cct_s"]) > 1e-9:
                bad.append(f"{k['name']}: plan {k['cct_s']}, Python {r.cct_s}")
        print("BAD", bad, "N", len(d["contingencies"]), "DEV", len(d["allocation"]))
        """,
        cwd=d,
    )
    total = json.loads((d / "plan.json").read_text())["total_mw"]
    m = re.search(r"BAD \[\] N (\d+) DEV (\d+)", pout)
    in_text = f"{total} MW" in out
    ok = rc == 0 and bool(m) and in_text
    if not ok:
        why = (last_line(pout) or last_line(perr))[-200:] + f"; '{total} MW' in the text: {in_text}"
        return False, why, pout + perr
    return (
        True,
        (
            f"plan of {total} MW on {m.group(2)} devices (the text says '{total} MW'); its "
            f"{m.group(1)} contingencies' CCTs reproduced by critical_clearing_time with its fleet"
        ),
        pout + perr,
    )


# ---------------------------------------------------------------- Python API


@probe("api.argument_checks_hold")
def api_argument_checks_hold():
    """Wrong types, units and shapes at the public entry points end in a stabctl error
    (InputError, WrongTypeError, UnknownBusError, CaseError) naming the argument."""
    rc, out, err = py("""
        import collections, inspect, json, warnings
        import stabctl, stabctl.errors as E
        warnings.simplefilter("ignore")
        ours = tuple(v for v in vars(E).values()
                     if inspect.isclass(v) and issubclass(v, Exception))
        k = stabctl.load_case("kundur"); mw = stabctl.load_case("miniwecc")
        sim = stabctl.Simulator(k)
        F = stabctl.LineFault(3, 101)
        nan = float("nan")
        cases = {
          "Fault bus '3'": lambda: stabctl.Fault("3", 1.0, 1.1),
          "Fault bus 3.5": lambda: stabctl.Fault(3.5, 1.0, 1.1),
          "run t_end nan": lambda: sim.run([], t_end=nan),
          "run h -0.01": lambda: sim.run([], t_end=1, h=-0.01),
          "run events=Fault": lambda: sim.run(stabctl.Fault(3, 1.0, 1.1)),
          "run fault bus 999": lambda: sim.run([stabctl.Fault(999, 1.0, 1.1)]),
          "run clear before start": lambda: sim.run(F.events(-0.1), t_end=2),
          "run fault x nan": lambda: sim.run([stabctl.Fault(3, 1.0, 1.1, x=nan)], t_end=2),
          "run voltages ['3']": lambda: sim.run([], t_end=1, voltages=["3"]),
          "run miniwecc fleet on kundur":
              lambda: sim.run(F.events(0.1), t_end=2, storage=stabctl.uniform_fleet(mw, 5)),
          "uniform_fleet pct nan": lambda: stabctl.uniform_fleet(k, nan),
          "uniform_fleet pct '5'": lambda: stabctl.uniform_fleet(k, "5"),
          "StorageDevice bus '10'": lambda: stabctl.StorageDevice("10", 1, 10.0),
          "linearise esd_buses '3'": lambda: stabctl.linearise(sim, esd_buses="3"),
          "linearise esd_buses [999]": lambda: stabctl.linearise(sim, esd_buses=[999]),
          "linearise 'kundur'": lambda: stabctl.linearise("kundur"),
          "modal_analysis inertia short":
              lambda: stabctl.modal_analysis(stabctl.linearise(sim), inertia=[1, 2]),
          "cct search=0.005": lambda: stabctl.critical_clearing_time(sim, F, 0.005),
          "cct fault=Fault":
              lambda: stabctl.critical_clearing_time(sim, stabctl.Fault(3, 1.0, 1.1)),
          "fault_with_clearing cycles -8": lambda: stabctl.fault_with_clearing(k, 3, 101, 1.0, -8),
          "load_case 3": lambda: stabctl.load_case(3),
          "load_case RAW": lambda: stabctl.load_case("x.raw"),
          "solve_powerflow tol -1": lambda: stabctl.solve_powerflow(k, tol=-1),
          "OMIB H -3":
              lambda: stabctl.OMIB(H=-3, Pm=0.5, Pmax_pre=1, Pmax_fault=0, Pmax_post=1),
        }
        bad, kinds = [], collections.Counter()
        for label, f in cases.items():
            try:
                f(); bad.append(label + ": accepted")
            except ours as e:
                kinds[type(e).__name__] += 1
            except TypeError as e:  # Python's own for a call's signature: names the function
                if "(" not in str(e): bad.append(f"{label}: {type(e).__name__} {e}")
                else: kinds["TypeError (signature)"] += 1
            except Exception as e:
                bad.append(f"{label}: {type(e).__name__} {str(e)[:80]}")
        print(json.dumps({"n": len(cases), "bad": bad, "kinds": kinds}))
    """)
    try:
        res = json.loads(last_line(out))
    except ValueError:
        return False, f"exit {rc}: {last_line(err)[:200]}", out + err
    if res["bad"]:
        return False, "; ".join(res["bad"])[:400], out + err
    kinds = ", ".join(f"{v} {k}" for k, v in sorted(res["kinds"].items()))
    return True, f"{res['n']} wrong inputs refused: {kinds}", out + err


@probe("api.frequencykf_f0_50hz")
def api_frequencykf_f0_50hz():
    """docs/estimation.md 2: `FrequencyKF(pmu_index, settings)` on a 50 Hz case: f0 left
    at its default 60 Hz refused (round 36: speeds of 0.833 pu, no word), both with the
    50 Hz systems' rate 50 (at once) and with a rate common to both, 10 (at the first
    frame); given the case's f0 = 50 the speeds are about 1 pu."""
    imported()
    rc, out, err = py("""
        import numpy as np, stabctl, warnings
        warnings.simplefilter("ignore")
        from stabctl.estimation.pmu import machine_pmus, phasor_truth, measure
        from stabctl.estimation.settings import PMUSettings
        from stabctl.estimation.filters import FrequencyKF
        c = stabctl.load_case("fb.json")
        r = stabctl.Simulator(c).run([stabctl.fault_with_clearing(c, 2, 1, 1.0, 6)], t_end=2.0)
        pmus = machine_pmus(c)
        for rate, f0 in ((50, None), (10, None), (50, 50.0)):
            s = PMUSettings(rate=rate)
            stream = measure(phasor_truth(c, r, pmus), s, seed=0)
            try:
                kw = {} if f0 is None else {"f0": f0}
                kf = FrequencyKF(np.arange(len(pmus)), s, **kw)
                for fr in stream: sp, _ = kf.step(fr)
                print("CASE", rate, f0, "SPEED", float(sp.min()), float(sp.max()))
            except Exception as e:
                print("CASE", rate, f0, "REFUSED", type(e).__name__, str(e)[:70])
    """)
    lines = [ln for ln in out.splitlines() if ln.startswith("CASE")]
    if rc or len(lines) != 3:
        return False, f"exit {rc}: {last_line(err)[:200]}", out + err
    good = re.search(r"SPEED ([\d.]+) ([\d.]+)", lines[2])
    ok = (
        "REFUSED" in lines[0]
        and "REFUSED" in lines[1]
        and bool(good)
        and all(abs(float(x) - 1) < 0.05 for x in good.groups())
    )
    if not ok:
        return False, " | ".join(lines)[-400:], out + err
    r50, r10 = (ln.split("REFUSED")[1].strip() for ln in lines[:2])
    return (
        True,
        (
            f"default f0 60 on the 50 Hz case refused at rate 50 ({r50[:80]}) and at rate 10 "
            f"({r10[:60]}...); f0=50: speeds {float(good.group(1)):.4f}.."
            f"{float(good.group(2)):.4f} pu at t = 2 s"
        ),
        out + err,
    )


@probe("api.separation_limit_degrees")
def api_separation_limit_degrees():
    """Simulator.run(separation_limit=...) holds the CLI's (0, 100] rad: 180 (degrees
    meant) and inf refused (round 36: miniWECC Case 2 without storage, 87 rad off the COI,
    called stable); pi calls it unstable; the CLI refuses --separation-limit 180."""
    rc, out, err = py("""
        import stabctl, warnings
        warnings.simplefilter("ignore")
        c = stabctl.load_case("miniwecc"); sim = stabctl.Simulator(c)
        f = stabctl.fault_with_clearing(c, 83, 33, 1.0, 6)
        for lim in (3.141592653589793, 180.0, float("inf")):
            try:
                r = sim.run([f], t_end=6.0, separation_limit=lim)
                print("LIM", lim, r.stable, round(r.max_angle_from_coi, 2))
            except Exception as e:
                print("LIM", lim, "refused", type(e).__name__, str(e)[:60])
    """)
    cli = stab("simulate", "miniwecc", "--fault", "83", "--far-bus", "33",
               "--separation-limit", "180")  # fmt: skip
    pi = re.search(r"LIM 3.14\S* (\w+) ([\d.]+)", out)
    refused = re.findall(r"LIM (180.0|inf) refused (.*)", out)
    ok = rc == 0 and len(refused) == 2 and bool(pi) and pi.group(1) == "False" and cli[0] == 2
    if not ok:
        return (
            False,
            " | ".join(out.strip().splitlines())[-300:]
            + (f"; CLI --separation-limit 180: exit {cli[0]} '{last_line(cli[2])[:80]}'"),
            out + err,
        )
    return (
        True,
        (
            f"separation_limit=pi: unstable ({pi.group(2)} rad); 180 and inf refused "
            f"({refused[0][1][:70]}); CLI --separation-limit 180: exit 2 "
            f"'{last_line(cli[2])[:60]}'"
        ),
        out + err,
    )


@probe("api.deadband_mhz")
def api_deadband_mhz():
    """BangBangCOI(deadband_hz=...) holds the CLI's [0, 10] Hz: 100 (mHz meant) refused
    (round 36: Case 2's 5 % ESDs never acted, the run unstable); 0.1 Hz runs them."""
    rc, out, err = py("""
        import stabctl, warnings
        warnings.simplefilter("ignore")
        c = stabctl.load_case("miniwecc"); sim = stabctl.Simulator(c)
        f = stabctl.fault_with_clearing(c, 83, 33, 1.0, 6)
        for db in (0.1, 100.0):
            try:
                ctl = stabctl.BangBangCOI(deadband_hz=db)
                r = sim.run([f], t_end=6.0, storage=stabctl.uniform_fleet(c, 5, controller=ctl))
                print("DB", db, r.stable, sum(d["switchings"] for d in r.meta["storage"]))
            except Exception as e:
                print("DB", db, "refused", type(e).__name__, str(e)[:70])
    """)
    good = re.search(r"DB 0.1 (\w+) (\d+)", out)
    bad = re.search(r"DB 100.0 refused (.*)", out)
    ok = rc == 0 and bool(good) and good.group(1) == "True" and int(good.group(2)) > 0
    ok = ok and bool(bad)
    if not ok:
        return False, " | ".join(out.strip().splitlines())[-300:] or last_line(err), out + err
    return (
        True,
        (
            f"deadband_hz=0.1: stable, {good.group(2)} switchings; deadband_hz=100 refused "
            f"({bad.group(1)[:80]})"
        ),
        out + err,
    )


@probe("api.modal_discrete_time")
def api_modal_discrete_time():
    """modal_analysis(control.c2d(linearise(...), 0.01)) refused (round 36: the
    discrete-time model read as a continuous one -- no electromechanical mode, frequencies
    below 0.03 Hz, damping -1)."""
    rc, out, err = py("""
        import stabctl, control as ct, numpy as np, warnings
        warnings.simplefilter("ignore")
        lin = stabctl.linearise(stabctl.Simulator(stabctl.load_case("kundur")))
        try:
            ma = stabctl.modal_analysis(ct.c2d(lin, 0.01))
            print("ACCEPTED em", len(ma.electromechanical), "max f", float(np.max(ma.freq_hz)),
                  "min damping", float(np.min(ma.damping)))
        except Exception as e:
            print("REFUSED", type(e).__module__ + "." + type(e).__name__, str(e)[:90])
    """)
    ok = rc == 0 and "REFUSED stabctl" in out and "Traceback" not in err
    return ok, (last_line(out) or last_line(err))[-200:], out + err


@probe("api.c37_rate_of_case")
def api_c37_rate_of_case():
    """docs/estimation.md 6's `c37.stream_config(case, pmus, rate=60)` on a 50 Hz case
    refused (round 36: c37.record wrote the 50-frame/s stream under a CFG-2 of DATA_RATE 60
    and c37.replay read it back, where the CLI's readers refuse the file); rate=50 records
    and replays the stream whole."""
    imported()
    rc, out, err = py("""
        import stabctl, warnings
        warnings.simplefilter("ignore")
        from stabctl.estimation.pmu import machine_pmus, phasor_truth, measure
        from stabctl.estimation.settings import PMUSettings
        from stabctl.estimation import c37
        c = stabctl.load_case("fb.json")
        r = stabctl.Simulator(c).run([stabctl.fault_with_clearing(c, 2, 1, 1.0, 6)], t_end=3.0)
        pmus = machine_pmus(c)
        stream = measure(phasor_truth(c, r, pmus), PMUSettings(rate=50), seed=0)
        print("FRAMES", len(stream))
        for rate in (60, 50):
            try:
                cfg = c37.stream_config(c, pmus, rate=rate)
                n = c37.record(f"run{rate}.c37", cfg, stream)
                print("RATE", rate, "WROTE", n, "REPLAYED", len(c37.replay(f"run{rate}.c37", cfg)))
            except Exception as e:
                print("RATE", rate, "REFUSED", type(e).__name__, str(e)[:70])
    """)
    frames = re.search(r"FRAMES (\d+)", out)
    r60 = re.search(r"RATE 60 REFUSED (.*)", out)
    r50 = re.search(r"RATE 50 WROTE (\d+) REPLAYED (\d+)", out)
    written60 = (WORK / "run60.c37").exists()
    ok = rc == 0 and bool(frames and r60 and r50) and not written60
    ok = ok and r50.group(1) == r50.group(2) == frames.group(1)
    if not ok:
        extra = ""
        if written60:
            t = stab("estimate", "track", "fb.json", "--source", "run60.c37", "--out", "t60.csv")
            extra = f"; run60.c37 written; CLI estimate track on it: exit {t[0]} {last_line(t[2])}"
        return False, " | ".join(out.strip().splitlines())[-300:] + extra, out + err
    return (
        True,
        (
            f"stream_config(50 Hz case, rate=60) refused ({r60.group(1)[:70]}), no file; rate=50: "
            f"{r50.group(1)} of {frames.group(1)} frames recorded and replayed"
        ),
        out + err,
    )


@probe("api.modal_zero_inertia")
def api_modal_zero_inertia():
    """modal_analysis(sys, inertia=[0, 0, 0, 0]) refused (round 36: passed the '>= 0'
    check, numpy warned 'invalid value encountered in divide' and Kundur's inter-area mode
    became 'local')."""
    rc, out, err = py("""
        import stabctl
        lin = stabctl.linearise(stabctl.Simulator(stabctl.load_case("kundur")))
        try:
            ma = stabctl.modal_analysis(lin, inertia=[0, 0, 0, 0])
            print("ACCEPTED kinds", list(ma.kind[ma.electromechanical]))
        except Exception as e:
            print("REFUSED", type(e).__module__ + "." + type(e).__name__, str(e)[:90])
    """)
    warned = "RuntimeWarning" in err
    ok = rc == 0 and "REFUSED stabctl" in out and not warned
    why = (last_line(out) or last_line(err))[-200:]
    return ok, why + ("; numpy's RuntimeWarning on stderr" if warned else ""), out + err


@probe("api.modal_sliced_model")
def api_modal_sliced_model():
    """modal_analysis(lin[:, :2]) -- python-control's indexing keeps the ESD inputs but
    renames the states x[i]: analysed, or refused by a stabctl error (round 36: a bare
    ValueError from modal.state_group)."""
    rc, out, err = py("""
        import stabctl, traceback
        lin = stabctl.linearise(stabctl.Simulator(stabctl.load_case("kundur")))
        try:
            ma = stabctl.modal_analysis(lin[:, :2])
            print("OK", len(ma.eigenvalues), "eigenvalues")
        except Exception as e:
            tb = traceback.extract_tb(e.__traceback__)[-1]
            print("ERR", type(e).__module__, type(e).__name__, str(e)[:80], "@", tb.name)
    """)
    ok = rc == 0 and (last_line(out).startswith(("ERR stabctl", "OK ")))
    return ok, (last_line(out) or last_line(err))[-200:], out + err


@probe("api.mode_sensitivity_mismatch")
def api_mode_sensitivity_mismatch():
    """docs/modal.md's mode_sensitivity(sys, ma) given the modal analysis of another
    model, or the two swapped: stabctl errors (round 36: numpy's matmul ValueError, an
    AttributeError)."""
    imported()
    rc, out, err = py("""
        import stabctl, warnings
        warnings.simplefilter("ignore")
        from stabctl.smallsignal.modal import mode_sensitivity
        k = stabctl.linearise(stabctl.Simulator(stabctl.load_case("kundur")))
        f = stabctl.linearise(stabctl.Simulator(stabctl.load_case("fb.json")))
        mk = stabctl.modal_analysis(k); mf = stabctl.modal_analysis(f)
        for label, fn in (("other", lambda: mode_sensitivity(k, mf)),
                          ("swapped", lambda: mode_sensitivity(mk, k))):
            try:
                fn(); print(label, "OK")
            except Exception as e:
                print(label, type(e).__module__ + "." + type(e).__name__, str(e)[:70])
    """)
    ok = rc == 0 and out.count("stabctl.errors") == 2
    return ok, " | ".join(out.strip().splitlines()) or last_line(err)[-200:], out + err


@probe("api.modal_areas_unknown")
def api_modal_areas_unknown():
    """modal_analysis(areas=...) with a machine not in the model (99) refused, and with
    text keys ('1') refused naming them (round 36: 99 dropped without a word; '1' told 'no
    area given for machine(s) [1, 2, 3, 4]')."""
    rc, out, err = py("""
        import stabctl
        lin = stabctl.linearise(stabctl.Simulator(stabctl.load_case("kundur")))
        for areas in ({1: "a", 2: "a", 3: "b", 4: "b", 99: "c"},
                      {"1": "a", "2": "a", "3": "b", "4": "b"}):
            try:
                print("ACCEPTED", list(stabctl.modal_analysis(lin, areas=areas).areas))
            except Exception as e:
                print("REFUSED", str(e)[:100])
    """)
    lines = out.strip().splitlines()
    ok = (
        rc == 0
        and len(lines) == 2
        and lines[0].startswith("REFUSED")
        and "99" in lines[0]
        and lines[1].startswith("REFUSED")
        and "'1'" in lines[1]
    )
    return ok, " | ".join(lines)[-300:] or last_line(err)[-200:], out + err


@probe("api.fault_with_clearing_far_cycles")
def api_fault_with_clearing_far_cycles():
    """fault_with_clearing(case, 3, None, 1.0, 6, far_clear_cycles=8) refused: a bus fault
    has no far end (round 36: the 8 cycles dropped silently), as the CLI refuses
    --far-clear-cycles without --far-bus."""
    rc, out, err = py("""
        import stabctl
        try:
            c = stabctl.load_case("kundur")
            print("ACCEPTED", stabctl.fault_with_clearing(c, 3, None, 1.0, 6, far_clear_cycles=8))
        except Exception as e:
            print("REFUSED", type(e).__name__, str(e)[:90])
    """)
    cli = stab("simulate", "kundur", "--fault", "3", "--far-clear-cycles", "8", "--tf", "2")
    ok = rc == 0 and last_line(out).startswith("REFUSED") and cli[0] == 2
    return (
        ok,
        (
            f"{(last_line(out) or last_line(err))[:160]}; CLI --far-clear-cycles without "
            f"--far-bus: exit {cli[0]} '{last_line(cli[2])[:60]}'"
        ),
        out + err,
    )


@probe("api.result_inertia_doc")
def api_result_inertia_doc():
    """SimulationResult's docstring of `inertia` says what a case with an infinite bus
    (ThreeBus GENROU) holds there: 1 and 0 (round 36: only 'COI weights H * MVA per
    machine, MW s', the npz's units string alone saying so)."""
    imported()
    _, out, err = py("""
        import stabctl
        from stabctl.dynamics.results import SimulationResult
        c = stabctl.load_case("tb.json")
        r = stabctl.Simulator(c).run([], t_end=0.1)
        doc = " ".join(SimulationResult.__doc__.split())
        entry = doc.split("inertia :")[1].split("island :")[0]
        print("INERTIA", list(map(float, r.inertia)), "DOC_MENTIONS_INFINITE",
              "infinite bus" in entry)
    """)
    m = re.search(r"INERTIA (\[.*?\]) DOC_MENTIONS_INFINITE (\w+)", out)
    if not m:
        return False, (last_line(out) or last_line(err))[-200:], out + err
    ok = m.group(2) == "True"
    return (
        ok,
        (
            f"r.inertia = {m.group(1)} for ThreeBus (an infinite bus); the docstring's inertia "
            f"entry names the infinite bus: {ok}"
        ),
        out + err,
    )


@probe("api.screen_given_case_object")
def api_screen_given_case_object():
    """stabctl.stability.screening.screen (docs/library.md) given a loaded Case: runs, or
    an error naming screen's own argument (round 36: one naming load_case(name_or_path))."""
    rc, out, err = py("""
        import stabctl
        from stabctl.parallel import RunnerOptions
        from stabctl.stability.screening import screen
        try:
            screen(stabctl.load_case("kundur"), "s.jsonl", buses=[3],
                   runner=RunnerOptions(workers=1))
            print("OK")
        except Exception as e:
            print("ERR", type(e).__name__, str(e)[:90])
    """)
    ok = rc == 0 and ("screen(" in out or out.strip() == "OK")
    return ok, (last_line(out) or last_line(err))[-200:], out + err


@probe("api.result_accessors")
def api_result_accessors():
    """SimulationResult.speed_at(1.5) (one time) gives the speeds, r.machine('1') (a
    number as text) is refused by a stabctl error (round 36: numpy's AxisError; 'machine 1
    is not in the result' though machine 1 is)."""
    rc, out, err = py("""
        import numpy as np, stabctl
        r = stabctl.Simulator(stabctl.load_case("kundur")).run([], t_end=1.0)
        for label, fn in (("speed_at(1.5)", lambda: np.shape(r.speed_at(1.5))),
                          ("machine('1')", lambda: r.machine("1"))):
            try:
                print(label, "OK", fn())
            except Exception as e:
                print(label, type(e).__module__ + "." + type(e).__name__, str(e)[:60])
    """)
    lines = out.strip().splitlines()
    ok = (
        rc == 0
        and len(lines) == 2
        and lines[0].startswith("speed_at(1.5) OK")
        and lines[1].startswith("machine('1') stabctl.")
        and "is not in the result" not in out
    )
    return ok, " | ".join(lines) or last_line(err)[-200:], out + err


# ---------------------------------------------------------------- environment


@probe("env.marks_dir_removed")
def env_marks_dir_removed():
    """A sweep whose marks directory in TMPDIR (stabctl-running-*) is removed while it
    runs (a tmp cleaner): it runs on, no job recorded failed, no error line (round 36:
    every job left recorded 'worker failed: FileNotFoundError', the command ending
    'error: <that directory>: No such file or directory')."""
    tmp = WORK / "tmpdir"
    tmp.mkdir(exist_ok=True)
    out_path = WORK / "sw_rm.jsonl"
    p = subprocess.Popen(
        [*STABCTL, "sweep-cct", "kundur", "--faults", "DEFAULT", "--esd-pct", "none,5",
         "--out", out_path, "--workers", "2"],
        cwd=WORK,
        env=dict(ENV, TMPDIR=str(tmp)),
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )  # fmt: skip
    SESSIONS.append(p.pid)
    removed, t_rm, t0 = None, 0.0, time.monotonic()
    while time.monotonic() - t0 < 60 and p.poll() is None:
        marks = glob.glob(str(tmp / "stabctl-running-*"))
        if marks:
            time.sleep(0.5)
            shutil.rmtree(marks[0], ignore_errors=True)
            removed, t_rm = marks[0], time.monotonic() - t0
            break
        time.sleep(0.05)
    try:
        _, err = p.communicate(timeout=240)
    except subprocess.TimeoutExpired:
        kill_session(p.pid)
        _, err = p.communicate()
    kill_session(p.pid)
    recs = [json.loads(ln) for ln in out_path.open()] if out_path.exists() else []
    failed = [r for r in recs if r.get("status") == "failed"]
    last = last_line(err)
    if removed is None:
        return (
            False,
            (
                f"the sweep ended (exit {p.returncode}) before its marks directory appeared: "
                "not tested"
            ),
            err,
        )
    ok = p.returncode == 0 and recs and not failed and "No such file or directory" not in err
    return (
        bool(ok),
        (
            f"marks directory removed {t_rm:.1f} s into the run: exit {p.returncode}, "
            f"{len(recs)} records, {len(failed)} failed"
            + (f" ({(failed[0].get('error') or '')[:60]})" if failed else "")
            + f"; last line '{last[:90]}'"
        ),
        err,
    )


def main(argv=None) -> int:
    global VERBOSE
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("ids", nargs="*", help="probe names or their prefixes (doc, api)")
    ap.add_argument("-k", default="", help="run the probes whose name holds this")
    ap.add_argument("-v", action="store_true", help="show the children's output")
    opts = ap.parse_args(argv)
    VERBOSE = opts.v
    selected = [
        fn
        for fn in PROBES
        if (not opts.ids or fn.pid in opts.ids or fn.pid.split(".")[0] in opts.ids)
        and opts.k in fn.pid
    ]
    t_start = time.monotonic()
    print(f"stabctl of {ROOT}; work directory {WORK}", flush=True)
    rc, _, err = stab("compile", timeout=900)  # a warm cache loads in seconds
    if rc != 0:
        print("stabctl compile failed:", err[-300:])
        shutil.rmtree(WORK, ignore_errors=True)
        return 2
    keep = bool(os.environ.get("KEEP"))
    try:
        for fn in selected:
            t0 = time.monotonic()
            try:
                ok, why, *detail = fn()
            except Exception as ex:  # noqa: BLE001 - a probe that crashes is reported short
                where = traceback.format_exc().splitlines()[-3].strip()
                ok, why = False, f"probe crashed: {type(ex).__name__}: {str(ex)[:200]} | {where}"
                detail = [traceback.format_exc()]
            report(fn.pid, bool(ok), why, time.monotonic() - t0, "".join(detail))
    finally:
        for sid in SESSIONS:
            kill_session(sid)
        if not keep:
            shutil.rmtree(WORK, ignore_errors=True)
    n_short = sum(not ok for _, ok, _ in RESULTS)
    print(
        f"\n{len(RESULTS)} probes, {len(RESULTS) - n_short} ok, {n_short} SHORT; "
        f"{time.monotonic() - t_start:.0f} s; work directory {WORK} "
        f"({'kept' if keep else 'removed'})"
    )
    return 1 if n_short else 0


if __name__ == "__main__":
    sys.exit(main())
