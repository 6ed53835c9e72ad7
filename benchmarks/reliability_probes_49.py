#!/usr/bin/env python
"""Round 56 (AT): PAIRS of valid options, across commands and case types.

    CLONE=<clone> PYTHONPATH=<clone> python benchmarks/reliability_probes_49.py [AT-simulate,...]

Round 55 (reliability_probes_48.py) gave every option, alone, hostile values.  Here every
option gets only VALID values and the hunt is for their interactions (issue 54's crashes
came from pairs: `simulate --esd-model wecc --json`, `eig --report/--json` on a converter
case).  For each command, its factors (read by click introspection of `stabctl.cli.main`:
every boolean flag and choice option, and a few "interesting" values of the numeric ones,
with the CASE as one more factor) are covered pairwise by a seeded greedy all-pairs set
(every pair of values of two factors in at least one run; pairs a documented rule refuses,
e.g. a storage setting without --esd-pct, are left out), on five case types:

  kundur, miniwecc          built in (PSTess)
  solar                     ANDES ieee14_solar.xlsx (a REGCA1/REECA1/REPCA1 converter)
  motor                     ANDES kundur_motor.xlsx (an induction motor)
  five                      the PSS/E five-bus RAW + DYR of tests/data/psse (import-psse)

Each run is a subprocess (`python -m stabctl ...`, a fresh directory, a timeout).
Verdict per run, SHORT when: a traceback; an exit status other than 0/1/2; exit 0 with an
`error:` line; exit 2 without exactly one `error:` line, or one naming none of the run's
options, its case or a bus; a hang; a file left in the run's directory after exit 2;
--json output that is not JSON, or whose headline (verdict, CCT, number of modes, MW, the
EKF RMSE) differs from the text of the same run without --json (its twin, run too).
Silent no-ops: for each factor value that should change the result, one run of a row
holding it is repeated with the factor at its default; identical results (the run's
numbers, its settings line left out) are listed as "same" for a reader to judge (a note
line, not a SHORT: many a value legitimately changes nothing in a given case).

The three findings are probes of their own (AT-F1..F3), run after the pairs.

Found (round 56, AT; seed 56, about 45 min of runs on a shared 2-core machine): 254 rows
(cases 10, omib 7, simulate 34, cct 17, eig 21, screen 15, sweep-cct 17, estimate rmse 15,
closed-loop 15, estimate cct 13, track 11, import-psse 10, import-andes 8, pmu serve 12
with `estimate track` reading each stream, pmu plant 13 with `pmu control`, place 20, 16
hand-picked 3+-option lines), about 90 text twins: no traceback, no hang, no exit outside 0/1/2,
every exit 2 one `error:` line naming an option or the case, no file left by a refusal,
every --json valid and its headline equal to its twin's text.  Short (no-op check, then
confirmed by hand): pmu plant --hysteresis-hz accepted and ignored (the law runs in pmu
control; pmu control refuses the plant's --v-gate for that reason); estimate rmse refuses
--deadband-hz/--v-gate/--hysteresis-hz without --esd-pct although they set the
false-action rule counted on the ambient runs without storage; estimate closed-loop's
record ('control') leaves out the hysteresis that changed its mode commands.  All three
fixed (pmu plant refuses it; rmse takes the rule without storage where ambient runs count
it; both commands name their law in text and JSON); eig --no-pss on a case without a
stabiliser (DOUBTFUL D2) now refused.  Kept: --single-rate on a case with no fast exciter
loop (D1: runs as without it, its help says so); a motor case under --conventions pstess
diverging in its fault (D3: `place --set-aside-infeasible` stops with exit 2 naming the
smaller step, as it does for any numerical failure that is not the network's).

Environment: SEED (default 56), BUDGET_S (stop starting runs after this many seconds,
default 3600), TWINS=0 to skip the text twins, EFFECT=0 to skip the no-op check.
"""

# ruff: noqa
import itertools
import json
import os
import random
import re
import shutil
import sys
import time
from pathlib import Path

import click

import subprocess

from _probe_kit import Kit, free_port, stabctl, tail, tb, wait_listen

KIT = Kit("probes_at56_", line="{pid:<30} {state:<5} {why}")
CLONE, WD = KIT.clone, KIT.wd
rec, probe = KIT.rec, KIT.probe
sys.path.insert(0, CLONE)
from stabctl.cli import main as MAIN  # noqa: E402

SEED = int(os.environ.get("SEED", "56"))
BUDGET = float(os.environ.get("BUDGET_S", "3600"))
TWINS = os.environ.get("TWINS", "1") != "0"
EFFECT = os.environ.get("EFFECT", "1") != "0"
FIX = Path(os.environ.get("FIXTURES", WD / "fix"))
PSSE = Path(CLONE) / "tests" / "data" / "psse"
T0 = time.time()
NOTES = []  # (pid, text) for the report

# ---------------------------------------------------------------- case types
CASES = {
    # name: case argument, a faulted line (bus, far bus), a second bus, extra options
    "kundur": dict(case="kundur", bus=3, far=101, bus2=101),
    "miniwecc": dict(case="miniwecc", bus=83, far=33, bus2=33),
    "solar": dict(case="solar.json", bus=2, far=4, bus2=4),
    "motor": dict(case="motor.json", bus=7, far=8, bus2=8),
    "five": dict(case="five.json", bus=1, far=2, bus2=2),
}
#: ANDES cases import "as ANDES solves them" (no PV Q limits): --q-limits is refused
NEED_NO_Q = {"solar", "motor"}


def fixtures():
    """The imported cases and small input files, in FIX (made once)."""
    FIX.mkdir(parents=True, exist_ok=True)
    import andes

    A = Path(andes.__file__).parent / "cases"
    jobs = [
        (
            "solar.json",
            ["import-andes", A / "ieee14" / "ieee14_solar.xlsx", "-o", FIX / "solar.json"],
        ),
        (
            "motor.json",
            ["import-andes", A / "kundur" / "kundur_motor.xlsx", "-o", FIX / "motor.json"],
        ),
        (
            "five.json",
            [
                "import-psse",
                PSSE / "five_bus_v33.raw",
                PSSE / "five_bus.dyr",
                "-o",
                FIX / "five.json",
            ],
        ),
    ]
    for name, args in jobs:
        if not (FIX / name).exists():
            rc, o, e, _ = KIT.run(args, timeout=600, cwd=FIX)
            if rc != 0:
                raise RuntimeError(f"fixture {name}: exit {rc} {tail(e)}")
    for k, c in CASES.items():
        (FIX / f"faults_{k}.csv").write_text(f"bus,far_bus\n{c['bus']},{c['far']}\n")
        (FIX / f"faults2_{k}.csv").write_text(
            f"bus,far_bus\n{c['bus']},{c['far']}\n{c['far']},{c['bus']}\n"
        )
    (FIX / "five.json").exists()


def fault(k):
    """The fault options of case key k: its faulted line's two buses (as ints)."""
    return ["--fault", CASES[k]["bus"], "--far-bus", CASES[k]["far"]]


def case_arg(k):
    c = CASES[k]["case"]
    return str(FIX / c) if c.endswith(".json") else c


# ---------------------------------------------------------------- all-pairs
def allpairs(factors, valid, seed, tries=40):
    """Rows (dicts factor -> value index) covering every valid pair of two factors'
    values at least once: greedy (AETG-like), seeded.  `valid(partial)` says whether a
    partial row (dict name -> value) breaks no rule."""
    rnd = random.Random(seed)
    names = [f for f, _ in factors]
    vals = dict(factors)
    todo = set()
    for a, b in itertools.combinations(range(len(names)), 2):
        for i in range(len(vals[names[a]])):
            for j in range(len(vals[names[b]])):
                part = {names[a]: vals[names[a]][i], names[b]: vals[names[b]][j]}
                if valid(part):
                    todo.add((a, i, b, j))
    rows = []
    while todo:
        best, gain = None, -1
        for _ in range(tries):
            # seed the row with one uncovered pair, then fill greedily
            a, i, b, j = rnd.choice(sorted(todo))
            row = {a: i, b: j}
            order = [k for k in range(len(names)) if k not in row]
            rnd.shuffle(order)
            for k in order:
                cands = list(range(len(vals[names[k]])))
                rnd.shuffle(cands)
                scored = []
                for v in cands:
                    trial = {names[x]: vals[names[x]][y] for x, y in row.items()}
                    trial[names[k]] = vals[names[k]][v]
                    if not valid(trial):
                        continue
                    g = sum(
                        1
                        for x, y in row.items()
                        if ((min(x, k), y if x < k else v, max(x, k), v if x < k else y) in todo)
                    )
                    scored.append((g, -cands.index(v), v))
                if not scored:
                    row = None
                    break
                row[k] = max(scored)[2]
            if row is None:
                continue
            g = sum(
                1
                for (x, y), (z, w) in itertools.combinations(sorted(row.items()), 2)
                if (x, y, z, w) in todo
            )
            if g > gain:
                best, gain = row, g
        if best is None or gain <= 0:
            break
        for (x, y), (z, w) in itertools.combinations(sorted(best.items()), 2):
            todo.discard((x, y, z, w))
        rows.append({names[k]: vals[names[k]][v] for k, v in best.items()})
    return rows


# ---------------------------------------------------------------- the commands
def params_of(path):
    """The click parameters of a command path ('estimate rmse')."""
    c = MAIN
    for p in path.split():
        c = c.commands[p]
    out = {p.name: p for p in c.params}
    for p in c.params:  # by its option strings too ('search' for --search)
        for o in list(p.opts) + list(p.secondary_opts):
            out.setdefault(o.lstrip("-").replace("-", "_"), p)
    return out


def choices(path, name, drop=()):
    """A choice option's values, read from click (the first its default)."""
    p = params_of(path)[name]
    assert isinstance(p.type, click.Choice), (path, name)
    opt = p.opts[0]
    out = [None] + [c for c in p.type.choices if c != p.default and c not in drop]
    return [None if c is None else (opt, c) for c in out]


def flag(path, name):
    """A boolean flag's two values: absent, given (an on/off flag: its other form)."""
    p = params_of(path)[name]
    if p.secondary_opts:
        other = p.secondary_opts[0] if p.default else p.opts[0]
        return [None, (other,)]
    return [None, (p.opts[0],)]


def opt(name, *values):
    """A numeric/text option's values (None: not given)."""
    return [None] + [(name, str(v)) for v in values]


STORAGE = {"--esd-model", "--coi", "--hysteresis-hz", "--deadband-hz", "--v-gate"}


def tokens_of(row, c):
    """The argv tail of a row (case k's buses substituted)."""
    out = []
    for f, v in row.items():
        if f == "case" or v is None:
            continue
        for t in v:
            out.append(
                str(t).format(
                    bus=c["bus"],
                    far=c["far"],
                    bus2=c["bus2"],
                    fix=FIX,
                    k=c["key"],
                )
            )
    return out


def given(row, name):
    v = row.get(name)
    return v is not None


def first_tok(v):
    return None if v is None else v[0]


def storage_rule(row, need=STORAGE, esd="esd"):
    """A storage setting needs --esd-pct (options.check_storage_given)."""
    if esd in row and row[esd] is None:
        for f, v in row.items():
            if v is not None and first_tok(v) in need:
                return False
    return True


def q_rule(row):
    """solar, motor: the ANDES power flow has no Q limits (--q-limits would be refused);
    --single-rate is refused with --conventions pstess (one step always)."""
    if row.get("case") in NEED_NO_Q and "q" in row and row["q"] is None:
        return False
    if row.get("single") is not None and row.get("conv") is not None:
        return False
    return True


def spec():
    """{command: (factors, valid, base(case key) -> argv, timeout)}."""
    S = {}
    cases = list(CASES)
    # --- simulate
    P = "simulate"
    F = [
        ("case", cases),
        (
            "event",
            [
                ("--fault", "{bus}", "--far-bus", "{far}", "--t-fault", "0.5"),
                None,
                ("--bus-fault", "{bus}:0:0.01", "0.5", "0.6"),
                ("--trip", "{bus}", "{far}", "--t-trip", "0.5"),
                ("--load-step", "{bus2}", "0.5", "0.1", "0"),
                ("--trip-gen", "1", "0.5"),
            ],
        ),
        ("esd", opt("--esd-pct", 5)),
        ("esd_model", choices(P, "esd_model")),
        ("coi", choices(P, "coi")),
        ("hyst", opt("--hysteresis-hz", 0.05)),
        ("conv", choices(P, "conventions")),
        ("step", opt("--step", 0.002)),
        ("single", flag(P, "single_rate")),
        ("q", flag(P, "q_limits")),
        ("sep", opt("--separation-limit", 2)),
        ("stop", flag(P, "stop_at_separation")),
        ("check", flag(P, "check_step")),
        ("method", choices(P, "method")),
        ("suspect", choices(P, "suspect_starts")),
        ("out", [None, ("--out", "o.csv"), ("--out", "o.npz")]),
        ("plot", [None, ("--plot", "p.png")]),
        ("events", flag(P, "case_events")),
        ("farclr", [None, ("--far-clear-cycles", "9")]),
        ("json", flag(P, "as_json")),
    ]

    def v_sim(r):
        if not storage_rule(r) or not q_rule(r):
            return False
        if r.get("method") is not None and (r.get("esd") is not None or r.get("conv") is not None):
            return False  # the trapezoid: refused with storage and with pstess
        if r.get("events") is not None and r.get("case", "solar") not in ("solar", "motor"):
            return False  # only the ANDES cases have events of their own
        ev = r.get("event", "x")
        if (
            "farclr" in r
            and r["farclr"] is not None
            and ev != "x"
            and (ev is None or ev[0] != "--fault")
        ):
            return False
        return True

    # motor: its own event (motor switched on) at 2 s
    S[P] = (F, v_sim, lambda k, P=P: [P, case_arg(k), "--tf", "3" if k == "motor" else "2"], 180)

    # --- cct
    P = "cct"
    F = [
        ("case", cases),
        # both circuits of the faulted line out: --circuit 2 and --trip of circuit 1
        ("trip", [None, ("--circuit", "2", "--trip", "{bus}", "{far}")]),
        ("esd", opt("--esd-pct", 5)),
        ("esd_model", choices(P, "esd_model")),
        ("coi", choices(P, "coi")),
        ("hyst", opt("--hysteresis-hz", 0.05)),
        ("search", choices(P, "search")),
        ("conv", choices(P, "conventions")),
        ("step", opt("--step", 0.004)),
        ("single", flag(P, "single_rate")),
        ("q", flag(P, "q_limits")),
        ("tf", opt("--tf", 5)),
        ("json", flag(P, "as_json")),
    ]

    def v_cct(r):
        if not storage_rule(r) or not q_rule(r):
            return False
        # the second circuit of the faulted line exists in kundur (3-101:2), motor (7-8:2)
        # and five (1-2:2) only
        if r.get("trip") is not None and r.get("case", "kundur") not in ("kundur", "motor", "five"):
            return False
        return True

    S[P] = (
        F,
        v_cct,
        lambda k, P=P: [
            P,
            case_arg(k),
            *fault(k),
            *"--t-fault 0.5 --tol-ms 20 --t-max 0.4".split(),
        ],
        240,
    )

    # --- eig
    P = "eig"
    F = [
        ("case", cases),
        ("nopss", flag(P, "no_pss")),
        ("areas", opt("--areas", 2)),
        ("report", [None, ("--report", "--out-dir", "rep")]),
        ("conv", choices(P, "conventions")),
        ("q", flag(P, "q_limits")),
        ("limits", choices(P, "limits")),
        ("json", flag(P, "as_json")),
    ]
    S[P] = (F, lambda r: q_rule(r), lambda k, P=P: [P, case_arg(k)], 240)

    # --- screen
    P = "screen"
    F = [
        ("case", cases),
        ("lines", flag(P, "lines")),
        ("guess", flag(P, "guess")),
        ("search", choices(P, "search")),
        ("conv", choices(P, "conventions")),
        ("single", flag(P, "single_rate")),
        ("q", flag(P, "q_limits")),
        ("out", [None, ("--out", "s.jsonl")]),
        ("plot", [None, ("--plot", "s.png")]),
        ("retry", flag(P, "retry_failed")),
        ("step", opt("--step", 0.004)),
        ("json", flag(P, "as_json")),
    ]
    S[P] = (
        F,
        q_rule,
        lambda k, P=P: [
            *[P, case_arg(k), "--buses", CASES[k]["bus"]],
            *"--workers 1 --tol-ms 20 --t-max 0.3".split(),
        ],
        300,
    )

    # --- sweep-cct
    P = "sweep-cct"
    F = [
        ("case", cases),
        ("faults", [("--faults", "{fix}/faults_{k}.csv"), ("--faults", "{fix}/faults2_{k}.csv")]),
        ("esd", [None, ("--esd-pct", "5"), ("--esd-pct", "none,5")]),
        ("esd_model", choices(P, "esd_model")),
        ("coi", choices(P, "coi")),
        ("hyst", opt("--hysteresis-hz", 0.05)),
        ("conv", choices(P, "conventions")),
        ("single", flag(P, "single_rate")),
        ("q", flag(P, "q_limits")),
        ("out", [None, ("--out", "r.jsonl")]),
        ("retry", flag(P, "retry_failed")),
        ("tf", opt("--tf", 5)),
        ("json", flag(P, "as_json")),
    ]
    S[P] = (
        F,
        lambda r: storage_rule(r) and q_rule(r),
        lambda k, P=P: [P, case_arg(k), "--workers", "1", "--tol-ms", "20", "--t-max", "0.3"],
        300,
    )

    # --- place
    P = "place"
    F = [
        ("case", cases),
        (
            "req",
            [
                ("--required-clearing-cycles", "9"),
                ("--target-cct-gain", "1.2"),
                ("--target-cct-s", "0.2"),
            ],
        ),
        ("levels", [None, ("--load-levels", "0.9,1")]),
        ("uniform", flag(P, "uniform_reference")),
        ("alone", flag(P, "alone")),
        ("aside", flag(P, "set_aside_infeasible")),
        ("esd_model", choices(P, "esd_model")),
        ("coi", choices(P, "coi")),
        ("zeta", opt("--zeta-min", 0.05)),
        ("maxsites", opt("--max-sites", 1)),
        ("cost", [None, ("--cost-mwh", "10", "--cost-site", "5")]),
        ("conv", choices(P, "conventions")),
        ("single", flag(P, "single_rate")),
        ("q", flag(P, "q_limits")),
        ("out", [None, ("--out", "pl.json")]),
        ("json", flag(P, "as_json")),
    ]
    S[P] = (
        F,
        q_rule,
        lambda k, P=P: [
            *[P, case_arg(k), "--faults", f"{FIX}/faults_{k}.csv"],
            *"--workers 1 --max-rounds 1 --max-iter 1 --tol-ms 20 --t-max 0.5".split(),
        ],
        420,
    )

    # --- estimate rmse
    P = "estimate rmse"
    F = [
        ("case", cases),
        ("pmu_at", choices(P, "pmu_at")),
        ("esd", opt("--esd-pct", 5)),
        ("esd_model", choices(P, "esd_model")),
        ("coi", choices(P, "coi")),
        ("hyst", opt("--hysteresis-hz", 0.05)),
        ("rate", opt("--rate", 30)),
        ("drop", opt("--drop", 0.1)),
        ("conv", choices(P, "conventions")),
        ("single", flag(P, "single_rate")),
        ("q", flag(P, "q_limits")),
        ("json", flag(P, "as_json")),
    ]
    S[P] = (
        F,
        lambda r: storage_rule(r, STORAGE - {"--coi"}) and q_rule(r),
        lambda k: [
            *["estimate", "rmse", case_arg(k), *fault(k)],
            *"--t-fault 0.5 --tf 1.5 --runs 2 --ambient-runs 1 --ambient-s 1".split(),
        ],
        240,
    )

    # --- estimate closed-loop (needs --esd-pct)
    P = "estimate closed-loop"
    F = [
        ("case", cases),
        ("esd_model", choices(P, "esd_model")),
        ("coi", choices(P, "coi")),
        ("hyst", opt("--hysteresis-hz", 0.05)),
        ("transport", choices(P, "transport")),
        ("rate", opt("--rate", 30)),
        ("drop", opt("--drop", 0.1)),
        ("conv", choices(P, "conventions")),
        ("single", flag(P, "single_rate")),
        ("q", flag(P, "q_limits")),
        ("json", flag(P, "as_json")),
    ]
    S[P] = (
        F,
        q_rule,
        lambda k: [
            *["estimate", "closed-loop", case_arg(k), *fault(k)],
            *"--t-fault 0.5 --tf 1.5 --esd-pct 5".split(),
        ],
        240,
    )

    # --- estimate cct
    P = "estimate cct"
    F = [
        ("case", cases),
        ("esd_model", choices(P, "esd_model")),
        ("rate", opt("--rate", 30)),
        ("win", opt("--window-cycles", 4)),
        ("conv", choices(P, "conventions")),
        ("single", flag(P, "single_rate")),
        ("q", flag(P, "q_limits")),
        ("json", flag(P, "as_json")),
    ]
    S[P] = (
        F,
        q_rule,
        lambda k: ["estimate", "cct", case_arg(k), *fault(k), *"--esd-pct 5 --runs 1".split()],
        300,
    )

    # --- estimate track (the kundur recording; the other cases against it are refused)
    P = "estimate track"
    # (--out is required; --drop and --pmu-at hv are refused for a recording of terminal PMUs)
    F = [
        ("case", ["kundur"]),
        ("estimator", choices(P, "estimator")),
        ("esd", opt("--esd-pct", 5)),
        ("coi", choices(P, "coi")),
        ("hyst", opt("--hysteresis-hz", 0.05)),
        ("dead", opt("--deadband-hz", 0.05)),
        ("stop", [None, ("--frames", "90"), ("--until", "1.5")]),
        ("out", [("--out", "t.csv"), ("--out", "t.npz")]),
    ]
    S[P] = (
        F,
        lambda r: storage_rule(r, STORAGE - {"--coi"}),
        lambda k: ["estimate", "track", case_arg(k), "--source", str(FIX / "k.c37")],
        120,
    )

    # --- omib
    P = "omib"
    F = [
        ("case", ["-"]),
        ("more", [None, ("9", "12")]),
        ("H", opt("--H", 6)),
        ("pm", opt("--pm", 0.8)),
        ("delta0", opt("--delta0", 0.3)),
        ("pmax", opt("--pmax", 1.5)),
        ("f0", opt("--f0", 50)),
        ("json", flag(P, "as_json")),
    ]
    S[P] = (F, lambda r: True, lambda k: ["omib", "-c", "6"], 60)

    # --- cases
    P = "cases"
    F = [
        ("case", cases),
        ("bt", flag(P, "bus_table")),
        ("lt", flag(P, "line_table")),
        ("json", flag(P, "as_json")),
    ]
    S[P] = (F, lambda r: True, lambda k: ["cases", case_arg(k)], 60)

    # --- import-psse (five bus, smib)
    P = "import-psse"
    F = [
        ("case", ["five", "smib"]),
        ("skip", flag(P, "skip_unsupported")),
        ("loads", choices(P, "loads")),
        ("dconv", choices(P, "dyr_conventions")),
        ("net", flag(P, "net_unmodelled")),
        ("infeas", flag(P, "leave_out_infeasible")),
        ("keep", flag(P, "keep_unsolved")),
        ("islands", flag(P, "leave_out_islands")),
        ("json", flag(P, "as_json")),
    ]
    S[P] = (
        F,
        lambda r: True,
        lambda k: [
            "import-psse",
            *(
                [PSSE / "five_bus_v33.raw", PSSE / "five_bus.dyr"]
                if k == "five"
                else [PSSE / "smib_v33.raw", PSSE / "smib.dyr"]
            ),
            "-o",
            "c.json",
        ],
        120,
    )

    # --- import-andes (the converter and the motor case)
    P = "import-andes"
    F = [
        ("case", ["solar", "motor"]),
        ("skip", flag(P, "skip_unsupported")),
        ("dconv", [None]),
        ("infeas", flag(P, "leave_out_infeasible")),
        ("keep", flag(P, "keep_unsolved")),
        ("islands", flag(P, "leave_out_islands")),
        ("json", flag(P, "as_json")),
    ]

    def andes_base(k):
        import andes

        A = Path(andes.__file__).parent / "cases"
        x = (
            A / "ieee14" / "ieee14_solar.xlsx"
            if k == "solar"
            else A / "kundur" / "kundur_motor.xlsx"
        )
        return ["import-andes", x, "-o", "c.json"]

    S[P] = (F, lambda r: True, andes_base, 180)

    # --- pmu serve / plant (no client: each ends by itself after --wait / --timeout)
    P = "pmu serve"
    F = [
        ("case", cases),
        ("pmu_at", choices(P, "pmu_at")),
        ("each", flag(P, "each_pmu")),
        ("rate", opt("--rate", 30)),
        ("drop", opt("--drop", 0.1)),
        ("speed", opt("--speed", 0)),
        ("allow", opt("--allow", "127.0.0.1")),
        ("q", flag(P, "q_limits")),
    ]
    S[P] = (
        F,
        q_rule,
        lambda k: [
            *["pmu", "serve", case_arg(k), *fault(k)],
            *"--t-fault 0.2 --tf 0.5 --port 0 --wait 5 --timeout 20".split(),
        ],
        120,
    )
    P = "pmu plant"
    F = [
        ("case", cases),
        ("esd_model", choices(P, "esd_model")),
        ("coi", choices(P, "coi")),
        ("rate", opt("--rate", 30)),
        ("conv", choices(P, "conventions")),
        ("single", flag(P, "single_rate")),
        ("q", flag(P, "q_limits")),
        ("json", flag(P, "as_json")),
    ]
    S[P] = (
        F,
        q_rule,
        lambda k: [
            *["pmu", "plant", case_arg(k), *fault(k)],
            *"--esd-pct 5 --t-fault 0.2 --tf 0.5 --port 0 --timeout 20".split(),
        ],
        120,
    )
    return S


# ---------------------------------------------------------------- one run, judged
def run_row(cmd, base, row, timeout, tag):
    """(rc, out, err, secs, files, argv) of one row, in a fresh directory."""
    k = row.get("case")
    c = dict(CASES.get(k, dict(bus=0, far=0, bus2=0)), key=k)
    argv = [str(a) for a in base(k)] + tokens_of(row, c)
    d = WD / "runs" / tag
    if d.exists():
        shutil.rmtree(d)
    d.mkdir(parents=True)
    rc, out, err, dt = KIT.run(argv, timeout=timeout, cwd=d)
    files = sorted(str(p.relative_to(d)) for p in d.rglob("*") if p.is_file())
    logs = WD / "logs"
    logs.mkdir(exist_ok=True)
    (logs / f"{tag}.txt").write_text(
        f"$ {' '.join(argv)}\nexit {rc} in {dt:.1f} s, files {files}\n--- stdout\n{out}\n--- stderr\n{err}\n"
    )
    return rc, out, err, dt, files, argv


#: PMUs per case (one per in-service machine): the ports of serve --each-pmu
N_PMU = {"kundur": 4, "miniwecc": 34, "solar": 4, "motor": 4, "five": 3}


def run_server_row(cmd, base, row, timeout, tag):
    """A server row (pmu serve / pmu plant) with its client: `estimate track` reading the
    whole stream (serve), `pmu control` (plant).  The server judged as a run; the
    client's failure appended to its stderr as 'client: ...'."""
    k = row.get("case")
    c = dict(CASES[k], key=k)
    port = free_port() if not given(row, "each") else 20000 + random.Random(tag).randrange(20000)
    argv = [str(a) for a in base(k)] + tokens_of(row, c)
    argv[argv.index("--port") + 1] = str(port)
    d = WD / "runs" / tag
    if d.exists():
        shutil.rmtree(d)
    d.mkdir(parents=True)
    t = time.time()
    srv = subprocess.Popen(
        stabctl(argv),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=d,
        env=KIT.env,
        start_new_session=True,
        stdin=subprocess.DEVNULL,
    )
    crc, cout, cerr = None, "", ""
    if wait_listen(port, 120, srv):
        pick = lambda name: (
            [x for x in tokens_of({name: row.get(name)}, c)] if given(row, name) else []
        )
        if cmd == "pmu serve":
            n = N_PMU[k] if given(row, "each") else 1
            src = f"tcp://127.0.0.1:{port}" + (f"-{port + n - 1}" if n > 1 else "")
            cargs = [
                *["estimate", "track", case_arg(k), "--source", src],
                *"--out t.csv --until 0.5".split(),
                *pick("pmu_at"),
                *pick("rate"),
            ]
        else:
            cargs = [
                *["pmu", "control", case_arg(k), f"127.0.0.1:{port}"],
                *"--esd-pct 5 --timeout 20".split(),
                *pick("coi"),
                *pick("rate"),
            ]
        crc, cout, cerr, _ = KIT.run(cargs, timeout=timeout, cwd=d)
    rc, out, err = KIT.finish(srv, 40 if crc is not None else timeout)
    dt = time.time() - t
    if crc not in (None, 0):
        err += f"\nclient: exit {crc}: {tail(cout + cerr, 300)}"
    files = sorted(str(p.relative_to(d)) for p in d.rglob("*") if p.is_file())
    logs = WD / "logs"
    logs.mkdir(exist_ok=True)
    (logs / f"{tag}.txt").write_text(
        f"$ {' '.join(argv)}\nexit {rc} in {dt:.1f} s, files {files}\n--- stdout\n{out}\n"
        f"--- stderr\n{err}\n--- client exit {crc}\n{cout}\n{cerr}\n"
    )
    files = [f for f in files if f not in ("t.csv",)]
    return rc, out, err, dt, files, argv


def errors_of(text):
    return [ln for ln in text.splitlines() if ln.startswith("error:")]


def judge_run(cmd, row, rc, out, err, files, argv):
    """None if fine, else the reason it is short."""
    both = out + "\n" + err
    if rc == "timeout":
        return "hang (timeout)"
    if tb(both):
        last = [ln for ln in both.splitlines() if ln.strip()][-1]
        where = re.findall(r'File "([^"]+)", line (\d+)', both)
        w = [f"{f.split('stabctl/')[-1]}:{n}" for f, n in where if "stabctl" in f]
        return f"traceback: {last[:160]} at {w[-1] if w else '?'}"
    if rc not in (0, 1, 2):
        return f"exit {rc}: {tail(err, 160)}"
    errs = errors_of(out) + errors_of(err)
    if rc == 0 and errs:
        return f"exit 0 with {errs[0][:160]}"
    if rc == 2:
        if len(errs) != 1:
            return f"exit 2 with {len(errs)} error lines: {tail(err, 200)}"
        msg = errs[0]
        opts = [a for a in argv if a.startswith("-")]
        names = opts + [str(x) for x in argv] + ["CASE", "case", "bus", "--fault", "--far-bus"]
        if not any(n in msg for n in names if n and len(n) > 1):
            return f"exit 2, error names nothing of the run: {msg[:200]}"
        if files:
            left = [f for f in files if not f.startswith(".")]
            if left:
                return f"exit 2 left {left[:4]}: {msg[:120]}"
    if given(row, "json") and rc in (0, 1):
        try:
            json.loads(out)
        except ValueError as e:
            return f"--json output is not JSON ({e}): {tail(out, 120)}"
    return None


# headlines: (from the text, from the JSON); None when the command has none to compare
def _num(x, fmt):
    return None if x is None else fmt % x


def head_simulate(text, j):
    t = (
        "stable"
        if re.search(r"^stable:", text, re.M)
        else (
            "separated"
            if "loss of synchronism" in text
            else ("de-energised" if "de-energised" in text else "other")
        )
    )
    jv = j.get("verdict")
    jv = (
        "stable"
        if jv == "stable"
        else (
            "de-energised"
            if j.get("de_energised_s") is not None
            else ("separated" if j.get("separated_machines") else str(jv))
        )
    )
    return (t, jv)


def head_cct(text, j):
    m = re.search(r"^CCT ([\d.]+) s", text, re.M)
    return (m.group(1) if m else None, _num(j.get("cct_s"), "%.3f"))


def head_eig(text, j):
    rows = [ln for ln in text.splitlines() if re.match(r"^\s+\d+\s+[\d.]+\s+-?[\d.]+\s+\S", ln)]
    ss = "small-signal stable" in text
    return (
        (len(rows), ss),
        (len(j.get("electromechanical_modes", [])), j.get("small_signal_stable")),
    )


def _ccts(obj):
    out = []
    if isinstance(obj, dict):
        for kk, v in obj.items():
            if kk == "cct_s" and isinstance(v, (int, float)):
                out.append("%.3f" % v)
            else:
                out += _ccts(v)
    elif isinstance(obj, list):
        for v in obj:
            out += _ccts(v)
    return out


def head_table_ccts(text, j):
    js = sorted(set(_ccts(j if not isinstance(j, dict) else j.get("records", j))))
    txt = sorted(x for x in js if re.search(r"(?<![\d.])" + re.escape(x) + r"(?![\d])", text))
    return (txt, js)


def head_place(text, j):
    m = re.search(r"\): ([\d.]+) MW", text)
    return (m.group(1) if m else None, _num(j.get("total_mw"), "%.1f"))


def head_rmse(text, j):
    m = re.search(r"^ekf\s+([\d.]+)", text, re.M)
    try:
        v = j["estimators"]["ekf"]["speed_rmse_mhz"]["mean"]
    except (KeyError, TypeError):
        v = None
    return (m.group(1) if m else None, _num(v, "%.3f"))


def head_omib(text, j):
    m = re.search(r"CCT ([\d.]+) s", text)
    try:
        v = j["eac"]["t_cr_s"]
    except (KeyError, TypeError):
        v = None
    return (m.group(1) if m else None, _num(v, "%.4f"))


def head_closed_loop(text, j):
    t = re.findall(r"^  (ideal|raw|kf|ekf)\s+(\S+)\s+mode commands\s+(\d+)", text, re.M)
    cl = j.get("closed_loop", {})
    js = [
        (k, "stable" if v.get("stable") else "x", str(v.get("mode_commands")))
        for k, v in cl.items()
    ]
    return ([(a, "stable" if b == "stable" else "x", c) for a, b, c in t], js)


def head_est_cct(text, j):
    t = re.findall(r"^  (ideal|raw|kf|ekf)\s+([\d.]+)", text, re.M)
    js = [
        (k, "%.2f" % v["mean"])
        for k, v in j.get("cct_cycles", {}).items()
        if v.get("mean") is not None
    ]
    return (t, js)


HEAD = {
    "estimate closed-loop": head_closed_loop,
    "estimate cct": head_est_cct,
    "simulate": head_simulate,
    "cct": head_cct,
    "eig": head_eig,
    "screen": head_table_ccts,
    "sweep-cct": head_table_ccts,
    "place": head_place,
    "estimate rmse": head_rmse,
    "omib": head_omib,
}

#: factors whose values are not expected to change the result numbers (format, files,
#: speed of the search, a check printed beside): not in the no-op check
NO_EFFECT_CHECK = {
    "json",
    "out",
    "plot",
    "retry",
    "guess",
    "report",
    "check",
    "case",
    "event",
    "req",
    "faults",
    "more",
    "stop",
    "dconv",
    "suspect",
    "allow",
    "speed",
    "each",
    "transport",
    "search",
    "events",
}

_WALL = re.compile(
    r"wall [\d.]+ s|[\d.]+ ?s\b(?=[^\n]*wall)|in [\d.]+ s|\d+\.\d+ ?job/s|\[[^\]]*\]"
)


def numbers_of(text):
    """The numbers of a run's output after its first line (the settings echo), wall
    times left out."""
    lines = [ln for ln in text.splitlines() if "wall" not in ln and "linearised in" not in ln]
    body = "\n".join(lines[1:])
    return re.findall(r"-?\d+\.\d+(?:e-?\d+)?", body)


def explore(cmd, S, left):
    factors, valid, base, timeout = S[cmd]
    rows = allpairs(factors, valid, SEED)
    pid = "AT-" + cmd.replace(" ", "-")
    shorts, n_ok, n_ref, n_other, twins, effects = [], 0, 0, 0, 0, []
    seen_effect = set()
    print(f"# {cmd}: {len(rows)} rows cover every valid pair of {len(factors)} factors", flush=True)
    for i, row in enumerate(rows):
        if time.time() - T0 > BUDGET:
            shorts.append(f"budget reached after {i} of {len(rows)} rows")
            break
        tag = f"{pid}-{i}"
        runner = run_server_row if cmd in ("pmu serve", "pmu plant") else run_row
        rc, out, err, dt, files, argv = runner(cmd, base, row, timeout, tag)
        if "\nclient: exit" in err and rc in (0, 1):
            shorts.append(
                f"[{' '.join(argv)}] -> server exit {rc}, {err.split(chr(10) + 'client: ')[-1][:300]}"
            )
            print(
                f"#   SHORT {tag} client failed: {err.split(chr(10) + 'client: ')[-1][:300]}",
                flush=True,
            )
            continue
        why = judge_run(cmd, row, rc, out, err, files, argv)
        line = " ".join(argv[:1] + [a.replace(str(FIX) + "/", "") for a in argv[1:]])
        if why:
            shorts.append(f"[{line}] -> {why}")
            print(f"#   SHORT {tag} {line}\n#     {why}", flush=True)
            continue
        if rc == 0:
            n_ok += 1
        elif rc == 2:
            n_ref += 1
            print(f"#   refused {tag} {line}: {errors_of(out + err)[0][:200]}", flush=True)
        else:
            n_other += 1
            print(f"#   exit {rc} {tag} {line}: {tail(out + err, 200)}", flush=True)
        # the text twin of a --json run: the same headline
        if TWINS and given(row, "json") and rc in (0, 1) and cmd in HEAD:
            r2 = dict(row, json=None)
            rc2, out2, err2, _, _, argv2 = run_row(cmd, base, r2, timeout, tag + "-t")
            twins += 1
            why2 = judge_run(cmd, r2, rc2, out2, err2, [], argv2)
            if why2:
                shorts.append(f"[{' '.join(argv2)}] -> {why2}")
                continue
            try:
                ht, hj = HEAD[cmd](out2, json.loads(out))
            except Exception as e:  # noqa: BLE001
                shorts.append(f"[{line}] headline not read: {type(e).__name__}: {e}")
                continue
            if ht != hj or rc != rc2:
                shorts.append(f"[{line}] --json says {hj} (exit {rc}), the text {ht} (exit {rc2})")
                print(f"#   SHORT {tag} json/text: {hj} vs {ht}", flush=True)
        # the no-op check: one row per (factor, value), the factor at its default instead
        if EFFECT and rc in (0, 1) and not given(row, "json") and runner is run_row:
            for f, v in row.items():
                if f in NO_EFFECT_CHECK or v is None or (f, v) in seen_effect:
                    continue
                if f == "esd" and any(first_tok(row.get(g)) in STORAGE for g in row):
                    continue  # dropping --esd-pct would be refused, not compared
                r3 = dict(row, **{f: None})
                if not valid(r3):
                    continue
                seen_effect.add((f, v))
                rc3, out3, err3, _, _, argv3 = run_row(cmd, base, r3, timeout, f"{tag}-e-{f}")
                if rc3 == rc and numbers_of(out3) == numbers_of(out) and numbers_of(out):
                    effects.append(f"{' '.join(v)} (row {i}, {row.get('case')})")
    if effects:
        NOTES.append((pid, "same numbers with and without: " + "; ".join(effects)))
        print(f"# {pid} no-op candidates: " + "; ".join(effects), flush=True)
    why = (
        f"{len(rows)} rows: {n_ok} exit 0, {n_other} exit 1, {n_ref} refused (exit 2, named), "
        f"{twins} text twins"
    )
    return (not shorts, why + ("; SHORT: " + " || ".join(shorts) if shorts else ""))


#: hand-picked combinations of three or more options the pairs cannot reach (events,
#: storage, a converter, a check at half the step), each with its text twin when --json
EXTRA = [
    (
        "simulate",
        "solar",
        [
            "--trip-converter",
            "1",
            "0.5",
            "--esd-pct",
            "5",
            "--esd-model",
            "wecc",
            "--no-q-limits",
            "--json",
        ],
    ),
    (
        "simulate",
        "solar",
        [
            "--fault",
            "2",
            "--far-bus",
            "4",
            "--t-fault",
            "0.5",
            "--clear-cycles",
            "30",
            "--check-step",
            "--stop-at-separation",
            "--no-q-limits",
            "--json",
        ],
    ),
    (
        "simulate",
        "kundur",
        [
            "--fault",
            "3",
            "--far-bus",
            "101",
            "--t-fault",
            "0.5",
            "--clear-cycles",
            "12",
            "--check-step",
            "--stop-at-separation",
            "--esd-pct",
            "5",
            "--json",
        ],
    ),
    (
        "simulate",
        "kundur",
        [
            "--bus-fault",
            "3:0:0.05",
            "0.5",
            "0.6",
            "--trip",
            "3",
            "101",
            "--t-trip",
            "0.6",
            "--close",
            "3",
            "101",
            "1.2",
            "--vref-step",
            "2",
            "1",
            "0.02",
            "--pref-step",
            "1",
            "1.5",
            "0.05",
            "--esd-pct",
            "5",
            "--coi",
            "rest",
            "--check-step",
            "--json",
        ],
    ),
    ("simulate", "kundur", ["--pstess-default", "--esd-pct", "5", "--esd-model", "wecc", "--json"]),
    ("simulate", "miniwecc", ["--pstess-default", "--json"]),
    (
        "simulate",
        "motor",
        [
            "--case-events",
            "--no-q-limits",
            "--trip-gen",
            "2",
            "2.5",
            "--esd-pct",
            "5",
            "--esd-model",
            "wecc",
            "--json",
        ],
    ),
    (
        "simulate",
        "five",
        [
            "--fault",
            "1",
            "--far-bus",
            "2:2",
            "--t-fault",
            "0.5",
            "--far-clear-cycles",
            "12",
            "--method",
            "trapezoid",
            "--check-step",
            "--json",
        ],
    ),
    (
        "cct",
        "miniwecc",
        [
            "--fault",
            "83",
            "--far-bus",
            "33",
            "--t-fault",
            "0.5",
            "--tol-ms",
            "20",
            "--t-max",
            "0.4",
            "--esd-pct",
            "5",
            "--coi",
            "critical",
            "--esd-model",
            "wecc",
            "--search",
            "sime",
            "--json",
        ],
    ),
    (
        "cct",
        "solar",
        [
            "--fault",
            "2",
            "--far-bus",
            "4",
            "--t-fault",
            "0.5",
            "--tol-ms",
            "20",
            "--t-max",
            "0.4",
            "--esd-pct",
            "5",
            "--esd-model",
            "wecc",
            "--coi",
            "critical",
            "--no-q-limits",
            "--json",
        ],
    ),
    (
        "sweep-cct",
        "kundur",
        [
            "--faults",
            "{fix}/faults2_kundur.csv",
            "--esd-pct",
            "none,5,10",
            "--coi",
            "rest",
            "--esd-model",
            "wecc",
            "--workers",
            "1",
            "--tol-ms",
            "20",
            "--t-max",
            "0.3",
            "--json",
        ],
    ),
    (
        "screen",
        "motor",
        [
            "--lines",
            "--buses",
            "7",
            "--no-q-limits",
            "--workers",
            "1",
            "--tol-ms",
            "50",
            "--t-max",
            "0.3",
            "--plot",
            "m.png",
            "--json",
        ],
    ),
    ("eig", "solar", ["--report", "--json", "--no-q-limits", "--areas", "2", "--limits", "free"]),
    ("eig", "motor", ["--report", "--json", "--no-q-limits", "--conventions", "pstess"]),
    (
        "estimate rmse",
        "solar",
        [
            "--fault",
            "2",
            "--far-bus",
            "4",
            "--t-fault",
            "0.5",
            "--tf",
            "1.5",
            "--runs",
            "2",
            "--ambient-runs",
            "1",
            "--ambient-s",
            "1",
            "--esd-pct",
            "5",
            "--esd-model",
            "wecc",
            "--pmu-at",
            "hv",
            "--coi",
            "rest",
            "--drop",
            "0.2",
            "--no-q-limits",
            "--json",
        ],
    ),
    (
        "estimate closed-loop",
        "miniwecc",
        [
            "--fault",
            "83",
            "--far-bus",
            "33",
            "--t-fault",
            "0.5",
            "--tf",
            "1.5",
            "--esd-pct",
            "5",
            "--esd-model",
            "wecc",
            "--coi",
            "rest",
            "--transport",
            "codec",
            "--drop",
            "0.2",
            "--rate",
            "30",
            "--json",
        ],
    ),
]


def explore_extra():
    shorts, n = [], 0
    for i, (cmd, k, tail_) in enumerate(EXTRA):
        if time.time() - T0 > BUDGET:
            shorts.append("budget reached")
            break
        c = dict(CASES[k], key=k)
        toks = [t.format(fix=FIX) for t in tail_]
        base = lambda kk, cmd=cmd: (
            [*cmd.split(), case_arg(kk)] + (["--tf", "3"] if cmd == "simulate" else [])
        )
        row = {"case": k, "x": tuple(toks), "json": ("--json",) if "--json" in toks else None}
        row["x"] = tuple(t for t in toks if t != "--json")
        tag = f"AT-extra-{i}"
        rc, out, err, dt, files, argv = run_row(cmd, base, row, 300, tag)
        why = judge_run(cmd, row, rc, out, err, files, argv)
        line = " ".join(a.replace(str(FIX) + "/", "") for a in argv)
        n += 1
        if why:
            shorts.append(f"[{line}] -> {why}")
            print(f"#   SHORT {tag} {line}\n#     {why}", flush=True)
            continue
        print(
            f"#   {tag} exit {rc} {line}: {tail((errors_of(out + err) or [''])[0], 150)}",
            flush=True,
        )
        if row["json"] and rc in (0, 1) and cmd in HEAD:
            r2 = dict(row, json=None)
            rc2, out2, err2, _, _, argv2 = run_row(cmd, base, r2, 300, tag + "-t")
            try:
                ht, hj = HEAD[cmd](out2, json.loads(out))
            except Exception as e:  # noqa: BLE001
                shorts.append(f"[{line}] headline not read: {type(e).__name__}: {e}")
                continue
            if ht != hj or rc != rc2:
                shorts.append(f"[{line}] --json says {hj} (exit {rc}), the text {ht} (exit {rc2})")
    return (not shorts, f"{n} runs" + ("; SHORT: " + " || ".join(shorts) if shorts else ""))


# ---------------------------------------------------------------- the findings, as probes
def plant_loop(plant_extra, control_extra):
    """(plant's JSON closed_loop row, control's exit) of pmu plant kundur + pmu control raw."""
    port = free_port()
    d = WD / "runs" / f"plant{port}"
    d.mkdir(parents=True)
    srv = subprocess.Popen(
        stabctl(
            [
                *"pmu plant kundur --fault 3 --far-bus 101 --esd-pct 5 --t-fault 0.5".split(),
                *["--tf", "1.5", "--port", str(port), "--timeout", "20", "--speed", "0"],
                *["--json", *plant_extra],
            ]
        ),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=d,
        env=KIT.env,
        start_new_session=True,
        stdin=subprocess.DEVNULL,
    )
    if not wait_listen(port, 120, srv):
        rc, out, err = KIT.finish(srv, 5)
        raise RuntimeError(f"plant did not listen: exit {rc} {tail(err)}")
    crc, cout, cerr, _ = KIT.run(
        [
            *["pmu", "control", "kundur", f"127.0.0.1:{port}"],
            *"--esd-pct 5 --timeout 20 --estimator raw".split(),
            *control_extra,
        ],
        120,
        d,
    )
    rc, out, err = KIT.finish(srv, 60)
    row = json.loads(out)["closed_loop"]
    return {k: row[k] for k in ("stable", "mode_commands", "false_actions")}, crc


@probe("AT-F1-plant-hysteresis")
def f1():
    """pmu plant --hysteresis-hz: the modes are the controller's (pmu control's law); the
    plant's hysteresis changes nothing, yet it is accepted (pmu control refuses --v-gate,
    the plant's, for that reason: stabctl/cli/pmu.py 'refuse_given(("v_gate",) ...')."""
    base, _ = plant_loop([], [])
    try:
        plant, _ = plant_loop(["--hysteresis-hz", "0.05"], [])
    except RuntimeError as exc:  # refused by name (the fix): the plant never listens
        said = str(exc)
        ok = "exit 2" in said and "--hysteresis-hz given to pmu plant" in said
        return ok, said[:200]
    ctl, _ = plant_loop([], ["--hysteresis-hz", "0.05"])
    if plant == base and ctl != base:
        return False, (
            f"pmu plant --hysteresis-hz 0.05 accepted and ignored: {plant} as without "
            f"it; the same on pmu control: {ctl}"
        )
    return True, f"base {base}, plant's {plant}, control's {ctl}"


def rmse(extra):
    rc, out, err, _ = KIT.run(
        [
            *"estimate rmse kundur --fault 3 --far-bus 101 --t-fault 0.5 --tf 1.5".split(),
            *"--runs 1 --ambient-runs 1 --ambient-s 2 --json".split(),
            *extra,
        ],
        240,
    )
    return rc, (json.loads(out) if rc == 0 else None), err


@probe("AT-F2-rmse-false-action-rule")
def f2():
    """estimate rmse: the controller options set the rule of the false actions (its
    --esd-pct help), counted on the ambient runs with or without storage; without --esd-pct
    --deadband-hz is refused 'no storage to set', and with it the fault run has storage:
    the false actions at another deadband cannot be had with the RMSE of the run without
    storage."""
    rc, _, err = rmse(["--deadband-hz", "0.003"])
    rc2, d2, _ = rmse(["--esd-pct", "5", "--deadband-hz", "0.003"])
    rc3, d3, _ = rmse([])
    fa = lambda d: d["false_actions"]["raw"]["actions"]["mean"]
    sp = lambda d: d["estimators"]["ekf"]["speed_rmse_mhz"]["mean"]
    if rc == 2 and rc2 == 0 and rc3 == 0 and fa(d2) != fa(d3):
        return False, (
            f"--deadband-hz 0.003 alone: {errors_of(err)[0][:90]}; with --esd-pct 5 "
            f"raw false actions {fa(d2):g} (default {fa(d3):g}) but the EKF RMSE "
            f"{sp(d2):.3f} mHz is no longer the no-storage {sp(d3):.3f}"
        )
    return True, f"exit {rc}, {rc2}, {rc3}"


@probe("AT-F3-closed-loop-json-hysteresis")
def f3():
    """estimate closed-loop --json: 'control' records deadband, v-gate and COI; the
    hysteresis, which changes the mode commands, is recorded nowhere (text nor JSON)."""
    outs = []
    for extra in ([], ["--hysteresis-hz", "0.05"]):
        rc, out, err, _ = KIT.run(
            [
                *"estimate closed-loop kundur --fault 3 --far-bus 101 --t-fault 0.5".split(),
                *"--tf 1.5 --esd-pct 5 --json".split(),
                *extra,
            ],
            240,
        )
        outs.append(json.loads(out))
    a, b = outs
    if a["control"] == b["control"] and a["closed_loop"] != b["closed_loop"]:
        return False, (
            f"control {b['control']} the same with --hysteresis-hz 0.05, mode commands "
            f"raw {a['closed_loop']['raw']['mode_commands']} -> "
            f"{b['closed_loop']['raw']['mode_commands']}"
        )
    return True, "recorded"


def make_recording():
    if (FIX / "k.c37").exists():
        return
    KIT.recording()
    shutil.copy(KIT.wd / "k.c37", FIX / "k.c37")


ORDER = [
    "cases",
    "omib",
    "simulate",
    "cct",
    "eig",
    "screen",
    "sweep-cct",
    "estimate rmse",
    "estimate closed-loop",
    "estimate cct",
    "estimate track",
    "import-psse",
    "import-andes",
    "pmu serve",
    "pmu plant",
    "place",
    "extra",
]

if __name__ == "__main__":
    fixtures()
    S = spec()
    for cmd in ORDER:
        pid = "AT-" + cmd.replace(" ", "-")
        if not KIT.selected(pid):
            continue
        if cmd == "estimate track":
            make_recording()

        @probe(pid)
        def body(cmd=cmd):
            return explore_extra() if cmd == "extra" else explore(cmd, S, BUDGET)

        body()
    for f in (f1, f2, f3):
        f()
    for pid, n in NOTES:
        print(f"# note {pid}: {n}")
    KIT.cleanup(keep_any=True)
    KIT.report()
