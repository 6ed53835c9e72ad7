#!/usr/bin/env python
"""Round 55 (AS): a systematic fuzz of every CLI option, by click introspection.

    CLONE=<clone> PYTHONPATH=<clone> python benchmarks/reliability_probes_48.py [AS-simulate,...]

Walks the `stabctl.cli.main` group; for every command and subcommand, every parameter
(options and the positional arguments) is given, one at a time, on an otherwise valid
cheap command line (BASE below: case kundur, --tf 0.2 or the command's cheapest form),
hostile values chosen by its click type:

  FLOAT   nan inf -inf -1 0 1e308 1e999 0x10 1_0 " 3"
  INT     the same plus 3.0 -0 2**63
  Choice  a wrong case, an empty string
  Path    /dev/null, a directory, a missing file, a FIFO without a reader
  TEXT    "", " ", nan
  tuple   too few and too many values, and nan / -1 in each numeric slot

Run in-process with click.testing.CliRunner (each in a fresh directory, SIGALRM as its
timeout: a BaseException the runner does not catch).  A probe per (command, parameter);
SHORT when a value gives: a traceback (exit 1 with an exception that is neither a
stabctl error nor click's usage error), a hang beyond the timeout for a value that is
nonsense (nan, inf, 1e999; a long run of a sane value is no finding), exit 0 for nan or
an infinity, an output file left behind by a refused command, or an error (exit 2) whose
message does not name the parameter.  Accepted -1 / 0 are listed in the ok line
("accepted: ...") for a reader to judge against the option's help.

EXTRA=1 runs a second pass (other spellings and tiny numbers: -0.0 1e-320 Infinity -nan
1e-12; ints +3 0003 -2**63-1) with a 20 s timeout.

Found (round 55, AS; every pass about 7 min in-process): every option refuses nan, inf,
1e999, 0x10, 1_0, 2**63 naming it; no hang, no output left by a refused command.  Short:
--k-sigma / --window-cycles tiny (1e-320) reach C37.118.2 encoding as inf/NaN (pmu serve,
estimate closed-loop --transport tcp: OverflowError/ValueError at estimation/c37.py:237;
estimate rmse: exit 0, all estimates '-'; --k-sigma 1e-12: the KF blames f0);
omib --delta0 1e-320 (error of Pmax_pre = inf, not the option); estimate rmse
--ambient-s below a frame (error without the option); place --cost-mw 0 (error without
either option); import-andes with a DYR ANDES's parser fails on (the RAW named, Python's
words); the file options' errors name their role ('fault list', 'site costs') not the flag.
Fixed (round 55): --k-sigma >= 1e-3 and --window-cycles >= 1 (PMUSettings too), the
C37.118.2 encoder names a non-finite value as out of range; omib's --delta0 range checked
before the model; --ambient-s below a frame, the costs of 0 and a DYR that is none named
by option and file; simulate --tf >= 1e-6 s (1e-320 ran 0 steps, 'stable'); the file
options' refusals prefixed by the option ('--faults: fault list nan: ...', --site-costs,
--screening); place's target beyond --t-max names the requirement's options.  Kept:
click's own words for extra tuple values, omib --fault-cycles 1e-320 (a positive length),
estimate track --until past the recording (the partial track written, as its help says).

The contract (stabctl/errors.py: "Every error names what is wrong and where ... so that
the CLI can print it and exit non-zero without a traceback"; stabctl.cli.options
reports_errors: "numeric options are checked first (check_number: finite, in range)").
"""

# ruff: noqa
import json
import os
import signal
import sys
import tempfile
import time
import traceback
from pathlib import Path

import click
from click.testing import CliRunner

from _probe_kit import Kit, tail

sys.path.insert(0, os.environ.get("CLONE", str(Path(__file__).resolve().parents[1])))
import stabctl.errors as E  # noqa: E402
from stabctl.cli import main as MAIN  # noqa: E402

FLOATS = ["nan", "inf", "-inf", "-1", "0", "1e308", "1e999", "0x10", "1_0", " 3"]
INTS = FLOATS + ["3.0", "-0", str(2**63)]
NONSENSE = {"nan", "inf", "-inf", "1e999", "Infinity", "-nan"}
if os.environ.get("EXTRA"):  # the second pass: other spellings and tiny numbers
    FLOATS = ["-0.0", "1e-320", "Infinity", "-nan", "1e-12"]
    INTS = ["+3", "0003", "-9223372036854775809"]
TEXTS = ["", " ", "nan"]
LISTS = {"esd_pct", "buses", "load_levels", "idcode", "allow", "host", "scheduler"}
LIST_VALUES = ["inf", "-1", "1e999", "1,,2", "1_0", "3,3", "0", str(2**63), "1,nan"]


class Hang(BaseException):
    """The alarm of one in-process run (not an Exception: CliRunner lets it through)."""


def _alarm(signum, frame):
    raise Hang()


signal.signal(signal.SIGALRM, _alarm)

TIMEOUT = {
    "pmu serve": 5,
    "pmu replay": 5,
    "pmu plant": 5,
    "pmu control": 5,
    "pmu record": 5,
    "place": 20,
    "paper": 20,
    "sweep-cct": 30,
    "screen": 30,
    "estimate cct": 30,
}
SKIP = set()


def commands(cmd=MAIN, path=()):
    if isinstance(cmd, click.Group):
        for n, c in cmd.commands.items():
            yield from commands(c, path + (n,))
    else:
        yield " ".join(path), cmd


def values_for(p):
    """[(label, argv tail)] of hostile values for parameter p."""
    t = p.type
    out = []
    if getattr(p, "is_flag", False) or getattr(p, "count", False):
        return out
    if isinstance(t, click.Tuple) or (p.nargs > 1 and not isinstance(p, click.Argument)):
        types = t.types if isinstance(t, click.Tuple) else [t] * p.nargs
        good = []
        for tt in types:
            if isinstance(tt, click.types.IntParamType):
                good.append("3")
            elif isinstance(tt, click.types.FloatParamType):
                good.append("0.1")
            else:
                good.append("3")
        out.append(("few", good[:-1]))
        out.append(("many", good + ["1"]))
        for i, tt in enumerate(types):
            if isinstance(tt, (click.types.IntParamType, click.types.FloatParamType)):
                for v in ("nan", "-1"):
                    g = list(good)
                    g[i] = v
                    out.append((f"[{i}]={v}", g))
        return out
    if isinstance(t, click.Choice):
        c0 = str(t.choices[0])
        wrong = c0.upper() if c0.upper() != c0 else c0.lower() + "x"
        return [(wrong, [wrong]), ("''", [""])]
    if isinstance(t, click.types.IntParamType) or isinstance(t, click.IntRange):
        return [(v, [v]) for v in INTS]
    if isinstance(t, click.types.FloatParamType):
        return [(v, [v]) for v in FLOATS]
    if isinstance(t, (click.Path, click.File)):
        return [(os.path.basename(v) or v, [v]) for v in PATHS]
    # text
    vals = [(repr(v), [v]) for v in TEXTS]
    if p.name in LISTS:  # numbers in a text list
        vals += [(repr(v), [v]) for v in LIST_VALUES]
    if isinstance(p, click.Argument) or p.name in (
        "case_name",
        "source",
        "screening",
        "faults",
        "site_costs",
    ):
        vals += [(os.path.basename(v) or v, [v]) for v in PATHS]
    return vals


def invoke(argv, timeout):
    """(exit code, output, exception or 'hang', files left, seconds) of one in-process run."""
    d = Path(tempfile.mkdtemp(dir=WD, prefix="c"))
    old = os.getcwd()
    os.chdir(d)
    runner = CliRunner()
    t = time.time()
    signal.alarm(timeout)
    try:
        r = runner.invoke(MAIN, argv, catch_exceptions=True)
        signal.alarm(0)
        code, out, exc = r.exit_code, r.output, r.exception
        if exc is not None and r.exc_info is not None and not isinstance(exc, SystemExit):
            tbk = traceback.extract_tb(r.exc_info[2])[-1]
            exc = (exc, f"{tbk.filename.split('stabctl/')[-1]}:{tbk.lineno}")
    except Hang:
        code, out, exc = "hang", "", "hang"
    finally:
        signal.alarm(0)
        os.chdir(old)
    files = sorted(str(p.relative_to(d)) for p in d.rglob("*"))
    if MISSING.exists():  # an output given the missing path made it: missing again
        if MISSING.is_dir():
            import shutil

            shutil.rmtree(MISSING)
        else:
            MISSING.unlink()
    return code, out, exc, files, time.time() - t


def place_value(base, p, tailv):
    """The base line with parameter p set to tailv (an option replacing its base value)."""
    argv = list(base)
    if isinstance(p, click.Argument) and p.nargs == -1:
        return argv + list(tailv)
    if isinstance(p, click.Argument):
        # positional: replace the base's argument in its position
        name = p.name
        cmdlen = 2 if argv[0] in ("estimate", "pmu") else 1
        args = [q for q in p_args_of(p)]
        idx = args.index(p)
        argv[cmdlen + idx] = tailv[0]
        return argv
    for o in p.opts:
        if o in argv:
            i = argv.index(o)
            n = p.nargs if p.nargs > 0 else 1
            del argv[i : i + 1 + n]
    return argv + [p.opts[0], *tailv]


_CMD = {}


def p_args_of(p):
    return [q for q in _CMD["cur"].params if isinstance(q, click.Argument)]


def names_of(p):
    n = list(p.opts) + [p.name, p.name.replace("_", "-"), p.name.upper()]
    if getattr(p, "metavar", None):
        n.append(p.metavar)
    if isinstance(p, click.Argument):
        n += [p.human_readable_name, p.name.split("_")[0], p.name.split("_")[0].upper()]
        if p.nargs == -1:  # omib's more cycles: --fault-cycles's
            n += ["--fault-cycles"]
    return [x for x in n if x]


def judge(name, p, label, tailv, code, out, exc, files, base_files):
    """None if fine, else the reason it is short; ('acc', label) for an accepted odd value."""
    nonsense = any(v in NONSENSE for v in tailv) or label == "[0]=nan" or "nan" in label
    if code in (129, 130, 143) and "interrupted:" in out:
        code = "hang"  # the alarm, taken by the command as an interrupt
    if code == "hang":
        if nonsense and name not in ("pmu serve", "pmu replay", "pmu plant"):
            return f"{label}: still running at the timeout"
        if nonsense:
            return f"{label}: accepted, the server started"
        return ("acc", f"{label}(ran on)")
    if isinstance(exc, tuple):
        e, where = exc
        if not isinstance(e, (E.StabctlError, click.ClickException)):
            return f"{label}: {type(e).__name__}: {str(e)[:100]} at {where}"
    if code == 0 and p.name in LISTS and label.strip("'") in LIST_VALUES + TEXTS:
        if p.name in ("esd_pct", "load_levels", "buses", "idcode") and label.strip("'") in (
            "inf",
            "1e999",
            "1,nan",
            "-1",
            "nan",
        ):
            return f"{label}: exit 0"
        return ("acc", label)
    if code == 0:
        if (
            nonsense
            and isinstance(p.type, click.types.FloatParamType | click.Tuple)
            or label.endswith("=nan")
        ):
            return f"{label}: exit 0"
        if label in (
            "-1",
            "0",
            "-0",
            "1e308",
            str(2**63),
            "-0.0",
            "1e-320",
            "1e-12",
            "-9223372036854775809",
            "few",
            "many",
            "''",
            "' '",
        ) or label.endswith("=-1"):
            return ("acc", label)
        return None
    # refused
    import re

    digits = lambda x: re.sub(r"\d+", "N", x or "")
    b = BASE_RESULT.get(name)
    if b and code == b[0] and digits(out) == digits(b[1]):
        return ("note", f"{label}: as the base line")
    new = list(files)
    if new and code != 0 and name == "estimate track" and "tracked are in" in out:
        # kept (round 55): a stream that stops before --until / --frames is tracked as far
        # as it came, written and named an error (exit 2), as `estimate track --help` says
        return ("note", f"{label}: exit {code}, the partial track kept as its help says")
    if new and code != 0:
        return f"{label}: exit {code} left {new[:3]}"
    if (
        code == 1
        and exc is not None
        and not isinstance(exc, tuple)
        and not isinstance(exc, SystemExit)
    ):
        return f"{label}: exit 1 {exc!r}"
    low = out
    if label == "many" and "unexpected extra argument" in out:
        return ("note", "many: click's 'unexpected extra argument'")
    if isinstance(p, click.Argument):
        if tailv and tailv[0].strip() and tailv[0] in out:
            return None  # the value (a path, a name) named
        if p.nargs == -1 and tailv[0].startswith("-") and "No such option" in out:
            return ("note", f"{label}: click read it as an option")
    if not any(n in low for n in names_of(p)):
        return f"{label}: exit {code} without its name: {tail(out, 160)}"
    return None


def setup():
    global KIT, CLONE, WD, rec, probe, FIX, FAULTS, ADIR, FIFO, MISSING, RAW, DYR, REC, PATHS, BASE
    KIT = Kit("probes_as55_", line="{pid:<34} {state:<5} {why}")
    CLONE, WD = KIT.clone, KIT.wd
    rec, probe = KIT.rec, KIT.probe
    sys.path.insert(0, CLONE)

    # fixtures, made once
    FIX = WD / "fix"
    FIX.mkdir()
    FAULTS = FIX / "faults.csv"
    FAULTS.write_text("bus,far_bus\n3,101\n")
    ADIR = FIX / "adir"
    ADIR.mkdir()
    FIFO = FIX / "fifo"
    os.mkfifo(FIFO)
    MISSING = FIX / "missing.json"
    DATA = Path(CLONE) / "tests" / "data" / "psse"
    RAW, DYR = DATA / "smib_v33.raw", DATA / "smib.dyr"
    REC = FIX / "k.c37"
    PATHS = ["/dev/null", str(ADIR), str(MISSING), str(FIFO)]

    # cheap valid command lines; {o} is the work dir's output stem
    BASE = {
        "omib": ["omib", "--fault-cycles", "6"],
        "paper": ["paper", "--only", "analytic", "--out-dir", "rep"],
        "cases": ["cases", "kundur"],
        "simulate": ["simulate", "kundur", "--tf", "0.2"],
        "cct": [
            "cct",
            "kundur",
            "--fault",
            "3",
            "--far-bus",
            "101",
            "--tol-ms",
            "20",
            "--t-max",
            "0.3",
        ],
        "sweep-cct": [
            "sweep-cct",
            "kundur",
            "--faults",
            str(FAULTS),
            "--workers",
            "1",
            "--tol-ms",
            "20",
            "--t-max",
            "0.3",
        ],
        "screen": [
            "screen",
            "kundur",
            "--buses",
            "3",
            "--workers",
            "1",
            "--tol-ms",
            "20",
            "--t-max",
            "0.3",
        ],
        "eig": ["eig", "kundur"],
        "estimate rmse": [
            "estimate",
            "rmse",
            "kundur",
            "--fault",
            "3",
            "--far-bus",
            "101",
            "--t-fault",
            "0.1",
            "--tf",
            "0.5",
            "--runs",
            "1",
            "--ambient-runs",
            "1",
            "--ambient-s",
            "1",
        ],
        "estimate closed-loop": [
            "estimate",
            "closed-loop",
            "kundur",
            "--fault",
            "3",
            "--far-bus",
            "101",
            "--t-fault",
            "0.1",
            "--esd-pct",
            "5",
            "--tf",
            "0.5",
        ],
        "estimate cct": [
            "estimate",
            "cct",
            "kundur",
            "--fault",
            "3",
            "--far-bus",
            "101",
            "--esd-pct",
            "5",
            "--runs",
            "1",
        ],
        "estimate track": ["estimate", "track", "kundur", "--source", str(REC), "--out", "t.csv"],
        "pmu serve": [
            "pmu",
            "serve",
            "kundur",
            "--fault",
            "3",
            "--far-bus",
            "101",
            "--t-fault",
            "0.1",
            "--tf",
            "0.5",
            "--port",
            "0",
            "--wait",
            "1",
            "--timeout",
            "1",
        ],
        "pmu replay": ["pmu", "replay", str(REC), "--port", "0", "--wait", "1", "--timeout", "1"],
        "pmu record": ["pmu", "record", "127.0.0.1:9", "--frames", "10", "-o", "r.c37"],
        "pmu plant": [
            "pmu",
            "plant",
            "kundur",
            "--fault",
            "3",
            "--far-bus",
            "101",
            "--esd-pct",
            "5",
            "--t-fault",
            "0.1",
            "--tf",
            "0.5",
            "--port",
            "0",
            "--timeout",
            "1",
        ],
        "pmu control": [
            "pmu",
            "control",
            "kundur",
            "127.0.0.1:9",
            "--esd-pct",
            "5",
            "--timeout",
            "1",
        ],
        "place": [
            "place",
            "kundur",
            "--faults",
            str(FAULTS),
            "--workers",
            "1",
            "--max-rounds",
            "1",
            "--max-iter",
            "1",
            "--tol-ms",
            "20",
            "--required-clearing-cycles",
            "6",
        ],
        "import-psse": ["import-psse", str(RAW), str(DYR), "-o", "c.json"],
        "import-andes": ["import-andes", str(RAW), str(DYR), "-o", "c.json"],
        "compile": ["compile", "kundur", "--check"],
    }


BASE_RESULT = {}


def make_recording():
    if REC.exists():
        return
    try:
        cfg, data = KIT.recording()
        import shutil

        shutil.copy(KIT.wd / "k.c37", REC)
    except Exception as e:  # noqa: BLE001
        print(f"# no recording: {e}", flush=True)


def fuzz_command(name, cmd):
    _CMD["cur"] = cmd
    base = BASE[name]
    to = TIMEOUT.get(name, 60)
    if os.environ.get("EXTRA"):
        to = min(to, 20)
    code, out, exc, files, dt = invoke(base, to)
    ok_base = code == 0
    BASE_RESULT[name] = (code, out)
    print(f"# base {name}: exit {code} {dt:.1f}s {tail(out, 120) if code != 0 else ''}", flush=True)
    for p in cmd.params:
        if p.name in ("help",):
            continue
        vals = values_for(p)
        if not vals:
            continue
        pid = f"AS-{name.replace(' ', '-')}-{p.opts[0].lstrip('-') if p.opts else p.name}"

        @probe(pid)
        def body(p=p, vals=vals):
            shorts, acc, notes = [], [], []
            for label, tv in vals:
                argv = place_value(base, p, tv)
                c, o, x, fl, dt = invoke(argv, to)
                j = judge(name, p, label, tv, c, o, x, fl, files)
                if isinstance(j, tuple) and j[0] == "note":
                    notes.append(j[1])
                elif isinstance(j, tuple):
                    acc.append(j[1])
                elif j:
                    shorts.append(j)
                    print(f"#   {' '.join(map(repr, argv))} -> {c}: {tail(o, 200)}", flush=True)
            why = (
                "; ".join(shorts)
                if shorts
                else f"{len(vals)} values"
                + (f", accepted: {' '.join(acc)}" if acc else "")
                + (f"; note: {'; '.join(notes)}" if notes else "")
            )
            return not shorts, why

        body()


if __name__ == "__main__":
    setup()
    only = set(a for a in sys.argv[1:])
    KIT.only = []  # filtering by command below
    want = lambda n: (
        not only
        or any(
            ("AS-" + n.replace(" ", "-")).startswith(o) or o.startswith("AS-" + n.replace(" ", "-"))
            for o in only
        )
    )
    if want("pmu replay") or want("estimate track"):
        make_recording()
    try:
        for name, cmd in commands():
            if name in SKIP or name not in BASE or not want(name):
                continue
            KIT.only = (
                [o for o in only if o.startswith("AS-" + name.replace(" ", "-") + "-")]
                if only
                else []
            )
            fuzz_command(name, cmd)
    finally:
        KIT.cleanup()
    KIT.report()
