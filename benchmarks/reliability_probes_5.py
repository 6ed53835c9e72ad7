"""Fifth reliability round: option combinations that are accepted but ignored, event
times beyond the run, number spellings Python accepts but a user does not mean, case-file
structure, PSS/E RAW/DYR corruptions, fault-CSV variants, PMU network options and paths.

Same machinery as the earlier rounds (`reliability_probes.run`, one `stabctl` command per
probe in a fresh process).  A bad input must end with exit status 2, exactly one line
starting ``error:`` naming what (the needle), no traceback, no new file in the work
directory and the inputs unchanged; a legitimate run exits 0.  An option accepted and
then ignored, or a value silently read as another, is a bad input here (exit 2 naming the
option) unless the probe says otherwise.

    python benchmarks/reliability_probes_5.py [-v] [-k SUBSTRING]

Probes marked `defect` in the first column were short when written (HEAD 1e712e4); the
others pass and guard against regressions.  Details of every short probe are written to
``<work>.shorts.txt``.  Exit status 1 if any probe is short.  About 5 minutes on one core
with a warm kernel cache.
"""

from __future__ import annotations

import copy
import json
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

BENCH = Path(__file__).resolve().parent
sys.path.insert(0, str(BENCH))
sys.path.insert(0, str(BENCH.parent / "tests"))

from reliability_probes import PSSE, run  # noqa: E402

WORK = Path(tempfile.mkdtemp(prefix="stabctl-probes-5."))
SHORTS = WORK.parent / (WORK.name + ".shorts.txt")
TIMEOUT = 120

SIM = "simulate kundur --fault 3 --far-bus 101 --tf 2"
CCT = "cct kundur --fault 3 --far-bus 101 --tol-ms 20"
RMSE = "estimate rmse kundur --fault 3 --far-bus 101 --runs 1 --tf 2"
PLACE = "place kundur --faults DEFAULT --workers 1 --target-cct-gain 5 --tol-ms 5"
TRACK = "estimate track kundur --source good.c37 --out t.csv"
SWEEP = "sweep-cct kundur --workers 1 --tol-ms 20 --out o.jsonl --faults"


@dataclass
class P5:
    tag: str  # 'defect' (short when written) or the area of a regression probe
    what: str
    args: list
    exit: int = 2
    needle: str = ""  # must be in stderr + stdout
    absent: str = ""  # must NOT be in stderr + stdout
    keep: tuple = ()  # files a probe may leave (a legitimate run's outputs)
    check: object = None  # extra check(res, cwd) -> '' or what is wrong
    extra: dict = field(default_factory=dict)


def args_of(text):
    return text.split() if isinstance(text, str) else [str(a) for a in text]


def snapshot(cwd: Path) -> dict:
    out = {}
    for p in cwd.rglob("*"):
        rel = str(p.relative_to(cwd))
        if p.is_symlink() or not p.is_file():
            out[rel] = None
        else:
            out[rel] = p.stat().st_mtime_ns, p.stat().st_size
    return out


def judge(p: P5, cwd: Path):
    before = snapshot(cwd)
    t0 = time.monotonic()
    try:
        res = run(p.args, cwd, TIMEOUT, stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired:
        return f"hang: no end in {TIMEOUT} s", None
    text = res.stderr + res.stdout
    errs = [x for x in res.stderr.splitlines() if x.startswith("error:")]
    v = "ok"
    if res.returncode != p.exit:
        tail = errs[-1] if errs else text.strip().splitlines()[-1] if text.strip() else ""
        v = f"exit {res.returncode}, want {p.exit}: {tail[:150]}"
    elif "Traceback" in res.stderr:
        v = "traceback"
    elif p.exit == 2 and len(errs) != 1:
        v = f"{len(errs)} error lines"
    elif p.needle and p.needle not in text:
        v = f"no {p.needle!r} in: {(errs[-1] if errs else text.strip()[-150:])[:160]}"
    elif p.absent and p.absent in text:
        v = f"{p.absent!r} in: {(errs[-1] if errs else text.strip()[-150:])[:160]}"
    elif p.check is not None:
        v = p.check(res, cwd) or "ok"
    after = snapshot(cwd)
    new = sorted(set(after) - set(before) - set(p.keep))
    changed = sorted(k for k in before if k in after and after[k] != before[k])
    if v == "ok" and p.exit != 0 and new:
        v = f"left behind: {', '.join(new)[:120]}"
    if v == "ok" and changed:
        v = f"input changed: {', '.join(changed)[:120]}"
    for rel in sorted(set(after) - set(before), reverse=True):  # clean for the next probe
        path = cwd / rel
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path, ignore_errors=True)
        else:
            path.unlink(missing_ok=True)
    if v != "ok":
        with SHORTS.open("a") as f:
            f.write(f"### [{p.tag}] {p.what}: {v}\n$ stabctl {' '.join(map(str, p.args))}\n")
            f.write(f"exit {res.returncode}\n--- stderr\n{res.stderr.strip()[-1500:]}\n")
            f.write(f"--- stdout\n{res.stdout.strip()[:600]}\nnew files: {new}\n\n")
    return v, time.monotonic() - t0


# --- inputs ----------------------------------------------------------------------------


def write(cwd, name, text, mode="w"):
    with open(cwd / name, mode, newline="" if mode == "w" else None) as f:
        f.write(text)


def prepare(cwd: Path):
    from stabctl.io import load_case
    from stabctl.io.pst import case_to_dict

    write(cwd, "f.csv", "bus,far_bus\n3,101\n")
    # case JSON variants: (name, edit) -> c_<name>.json
    base = case_to_dict(load_case("kundur"))

    def setf(d, table, col, value, row=0):
        t = d["tables"][table]
        t["rows"][row][t["columns"].index(col)] = value

    def swing_row(d):
        return [r[9] for r in d["tables"]["buses"]["rows"]].index(1.0)

    edits = {
        "extra_top": lambda d: d.update(solver_options={"tol": 1e-3}),
        "extra_col": lambda d: (
            d["tables"]["machines"]["columns"].append("Hx"),
            [r.append(5.0) for r in d["tables"]["machines"]["rows"]],
        ),
        "short_row": lambda d: d["tables"]["machines"]["rows"][0].pop(),
        "no_base": lambda d: d.pop("base_mva"),
        "no_machines": lambda d: d["tables"].pop("machines"),
        "freq_tiny": lambda d: d.update(freq_hz=1e-300),
        "freq_1": lambda d: d.update(freq_hz=1.0),
        "mach_on_pq": lambda d: setf(d, "machines", "bus", 4.0, 0),
        "name_list": lambda d: d.update(name=[1, 2]),
        # guarded (pass when written)
        "extra_table": lambda d: d["tables"].update(statcoms={"columns": ["bus"], "rows": [[3.0]]}),
        "long_row": lambda d: d["tables"]["machines"]["rows"][0].append(1.0),
        "col_lower": lambda d: d["tables"]["machines"]["columns"].__setitem__(15, "h"),
        "branch_absent": lambda d: setf(d, "branches", "to_bus", 999.0, 3),
        "machine_absent_bus": lambda d: setf(d, "machines", "bus", 999.0, 1),
        "exciter_absent": lambda d: setf(d, "exciters", "machine", 9.0, 1),
        "governor_absent": lambda d: setf(d, "governors", "machine", 9.0, 1),
        "pss_absent": lambda d: setf(d, "pss", "machine", 9.0, 1),
        "load_absent": lambda d: setf(d, "loads", "bus", 999.0, 0),
        "dup_machine": lambda d: setf(d, "machines", "number", 1.0, 1),
        "dup_exciter": lambda d: setf(d, "exciters", "machine", 1.0, 1),
        "zero_z_line": lambda d: setf(d, "branches", "x", 0.0, 0),
        "neg_H": lambda d: setf(d, "machines", "H", -6.5),
        "nan_H": lambda d: setf(d, "machines", "H", float("nan")),
        "inf_r": lambda d: setf(d, "branches", "r", float("inf"), 3),
        "zero_mva": lambda d: setf(d, "machines", "mva", 0.0),
        "base0": lambda d: d.update(base_mva=0),
        "base_str": lambda d: d.update(base_mva="100"),
        "freq_bool": lambda d: d.update(freq_hz=True),
        "kind9": lambda d: setf(d, "buses", "kind", 9.0, 3),
        "no_swing": lambda d: setf(d, "buses", "kind", 2.0, swing_row(d)),
        "bus0": lambda d: setf(d, "buses", "number", 0.0, 5),
        "bus_float": lambda d: setf(d, "buses", "number", 1.5, 0),
        "version99": lambda d: d.update(version=99),
        "exc_type99": lambda d: setf(d, "exciters", "type", 99.0),
        "tdop0": lambda d: setf(d, "machines", "Tdop", 0.0),
        "xd_neg": lambda d: setf(d, "machines", "xd", -1.8),
        "self_loop": lambda d: setf(
            d, "branches", "to_bus", d["tables"]["branches"]["rows"][3][0], 3
        ),
        "vmag0": lambda d: setf(d, "buses", "vmag", 0.0, 3),
        "cols_dup": lambda d: d["tables"]["machines"]["columns"].__setitem__(16, "H"),
        "rows_dict": lambda d: d["tables"]["machines"].update(rows={}),
        "tables_list": lambda d: d.update(tables=[]),
        "sw_con_text": lambda d: d.update(sw_con="garbage"),
        "island": lambda d: d["tables"]["buses"]["rows"].append(
            [77.0, 1.0, 0, 0, 0, 0, 0, 0, 0, 3.0, 0, 0, 230.0, 1.1, 0.9]
        ),
        "h_1e300": lambda d: setf(d, "machines", "H", 1e300),
    }
    for name, edit in edits.items():
        d = copy.deepcopy(base)
        edit(d)
        write(cwd, f"c_{name}.json", json.dumps(d))
    text = json.dumps(base)
    write(cwd, "c_truncated.json", text[: len(text) // 2])
    # PSS/E RAW and DYR
    sraw = (PSSE / "smib_v33.raw").read_text()
    sdyr = (PSSE / "smib.dyr").read_text()
    write(cwd, "smib.raw", sraw)
    write(cwd, "smib.dyr", sdyr)
    raws = {
        "trunc": "".join(sraw.splitlines(keepends=True)[:5]),
        "dupbus": sraw.replace("    2,'INFINITE", "    1,'INFINITE"),
        "branch_absent": sraw.replace("    1,      2,'1 ', 0.0", "    1,      9,'1 ', 0.0"),
        "zero_z": sraw.replace("0.00000E+0, 6.00000E-1", "0.00000E+0, 0.00000E+0"),
        "nan_x": sraw.replace("0.00000E+0, 6.00000E-1", "0.00000E+0, nan"),
        "version99": sraw.replace("0,   100.00, 33,", "0,   100.00, 99,"),
        "base0": sraw.replace("0,   100.00, 33,", "0,   0.00, 33,"),
        "busstr": sraw.replace("    1,'GEN ", "    X,'GEN "),
        "extra_fields": sraw.replace("0.90000\n    2,'INF", "0.90000, 7, 8\n    2,'INF"),
        "gen_absent_bus": sraw.replace("    2,'1 ',     0.000", "    7,'1 ',     0.000"),
        "neg_mbase": sraw.replace("   100.000, 0.00000E+0, 3.0", "  -100.000, 0.00000E+0, 3.0"),
        "semicolons": sraw.replace(",", ";"),
    }
    for name, text in raws.items():
        write(cwd, f"r_{name}.raw", text)
    dyrs = {
        "bom": "\ufeff" + sdyr,
        "negH": sdyr.replace("1 'GENCLS' 1   3.0", "1 'GENCLS' 1   -3.0"),
        "nanH": sdyr.replace("1 'GENCLS' 1   3.0", "1 'GENCLS' 1   nan"),
        "orphan_bus": sdyr + "    9 'GENCLS' 1   5.0  0.0 /\n",
        "orphan_id": sdyr + "    1 'GENCLS' 7   5.0  0.0 /\n",
        "dup": sdyr + "    1 'GENCLS' 1   4.0  0.0 /\n",
        "noslash": sdyr.replace("/", ""),
        "unknown_model": sdyr + "    1 'FOOBAR' 1   4.0  0.0 /\n",
        "few_params": sdyr.replace("1 'GENCLS' 1   3.0  0.0 /", "1 'GENCLS' 1   3.0 /"),
        "many_params": sdyr.replace("1 'GENCLS' 1   3.0  0.0 /", "1 'GENCLS' 1   3.0 0.0 5 6 /"),
        "text_param": sdyr.replace("1 'GENCLS' 1   3.0", "1 'GENCLS' 1   three"),
        "huge_H": sdyr.replace("1 'GENCLS' 1   3.0", "1 'GENCLS' 1   1e300"),
        "empty": "",
    }
    for name, text in dyrs.items():
        write(cwd, f"d_{name}.dyr", text)
    shutil.copy(cwd / "smib.raw", cwd / "colon:new\nline.raw")
    # fault CSVs
    csvs = {
        "t_underscore": "bus,far_bus,t_fault\n3,101,1_5\n",
        "t_after_tf": "bus,far_bus,t_fault\n3,101,3\n",
        "bus_fullwidth": "bus,far_bus\n\uff13,101\n",
        "bus_underscore": "bus,far_bus\n1_3,101\n",
        "bom_crlf": "\ufeffbus,far_bus\r\n3,101\r\n",
        "cr_only": "bus,far_bus\r3,101\r",
        "hdr_space": "bus, far_bus\n3,101\n",
        "col_order": "far_bus,bus\n101,3\n",
        "blank_mid": "bus,far_bus\n3,101\n\n13,101\n",
        "comment": "# faults\nbus,far_bus\n3,101\n",
        "trailing_comma": "bus,far_bus,\n3,101,\n",
        "dup_t_default": "bus,far_bus,t_fault\n3,101,1\n3,101,\n",
        "dup_t_spelt": "bus,far_bus,t_fault\n3,101,1\n3,101,1.0\n",
        "dup_bus_fault": "bus,far_bus\n3,\n3,\n",
        "extra_cells": "bus,far_bus\n3,101,,\n",
        "t_hex": "bus,far_bus,t_fault\n3,101,0x1\n",
        "long_line": "bus,far_bus\n3,101" + " " * 2_000_000 + "\n",
    }
    for name, text in csvs.items():
        write(cwd, f"x_{name}.csv", text)
    (cwd / "x_utf16.csv").write_bytes("bus,far_bus\n3,101\n".encode("utf-16"))
    # a recording of Kundur's bus-3 fault (2 s, 60 frames/s)
    from reliability_probes_3 import _record

    _record(cwd)
    for name in ("dup.c37", "back.c37", "absent.c37", "cfg_only.c37", "garbage_tail.c37",
                 "rate30.c37"):  # fmt: skip
        (cwd / name).unlink(missing_ok=True)


# --- probes ----------------------------------------------------------------------------


def probes() -> list[P5]:
    out: list[P5] = []

    def add(tag, what, args, **kw):
        out.append(P5(tag, what, args_of(args), **kw))

    # -- options accepted without the option they belong to, then ignored ---------------
    for args, needle in (
        ("simulate kundur --circuit 2 --tf 1", "--circuit"),
        ("simulate kundur --t-fault 0.5 --tf 1", "--t-fault"),
        ("simulate kundur --clear-cycles 3 --tf 1", "--clear-cycles"),
        ("simulate kundur --fault 3 --far-clear-cycles 8 --tf 2", "--far-clear-cycles"),
        ("simulate kundur --bus-fault 3 1 1.1 --clear-cycles 8 --tf 2", "--clear-cycles"),
        ("cct kundur --fault 3 --circuit 2 --tol-ms 20", "--circuit"),
        ("eig kundur --out-dir eigdir", "--out-dir"),
        ("omib --pmax 1.2 --delta0 0.3", "--delta0"),
        (f"{RMSE} --ambient-s 0 --ambient-pct 5", "--ambient-pct"),
        (f"{RMSE} --ambient-s 0 --ambient-runs 3", "--ambient-runs"),
        (f"{RMSE} --ambient-s 0 --ambient-tau-s 9", "--ambient-tau-s"),
        (f"{PLACE} --amplitude-hz 0.05", "--amplitude-hz"),
        (f"{TRACK} --drop 0.5", "--drop"),
        (f"{TRACK} --window-cycles 8", "--window-cycles"),
    ):
        words = [w for w in args.split() if w != "kundur"]
        short = words if len(words) <= 5 else words[:1] + words[-4:]
        add("defect", f"ignored: {' '.join(short)}", args, needle=needle)
    # a bus fault's CCT opens the further line at the clearing (the fix chose to apply it)
    add(
        "defect",
        "cct --trip without --far-bus named bus None",
        "cct kundur --fault 3 --trip 13 101 --tol-ms 20",
        exit=0,
        needle="cleared by opening 13-101",
        absent="bus None",
    )  # round 46's words for a bus fault's trip
    # the counterparts that are refused (guards)
    add("combo", "simulate --far-bus without --fault", "simulate kundur --far-bus 101 --tf 1",
        needle="--far-bus")  # fmt: skip
    add("combo", "simulate --t-trip without --trip", "simulate kundur --t-trip 1 --tf 1",
        needle="--t-trip")  # fmt: skip
    add("combo", "cct --coi critical without storage", f"{CCT} --coi critical", needle="--coi")
    add("combo", "sweep --coi critical", f"{SWEEP} f.csv --esd-pct 5 --coi critical",
        needle="critical")  # fmt: skip
    add("combo", "rmse --source with --runs", f"{RMSE} --source good.c37", needle="--runs")
    add("combo", "trapezoid with storage", f"{SIM} --method trapezoid --esd-pct 5",
        needle="trapezoid")  # fmt: skip
    add("combo", "trapezoid with pstess", f"{SIM} --method trapezoid --conventions pstess",
        needle="trapezoid")  # fmt: skip
    add("combo", "cases --bus-table without CASE", "cases --bus-table", needle="CASE")
    add("defect", "track --until and --frames, --frames first",
        f"{TRACK} --until 1.5 --frames 10", exit=0, keep=("t.csv",))  # fmt: skip
    add("defect", "track --until and --frames, --until first",
        f"{TRACK} --until 0.1 --frames 100", exit=0, keep=("t.csv",))  # fmt: skip
    # -- event times beyond the run's end ----------------------------------------------
    add("defect", "simulate: near-end clearing after --tf",
        f"{SIM} --clear-cycles 500", needle="--tf")  # fmt: skip
    add("defect", "simulate: far-end clearing after --tf",
        f"{SIM} --far-clear-cycles 500", needle="--tf")  # fmt: skip
    add("defect", "simulate --bus-fault cleared after --tf",
        "simulate kundur --bus-fault 3 1 9.3 --tf 2", needle="--tf")  # fmt: skip
    add("events", "simulate --t-fault after --tf", f"{SIM} --t-fault 3", needle="--tf")
    add("defect", "sweep-cct: CSV t_fault after --tf (recorded failed, exit 0)",
        f"{SWEEP} x_t_after_tf.csv --tf 2.5", needle="--tf 2.5")  # fmt: skip
    # -- number spellings ----------------------------------------------------------------
    add("defect", "CSV t_fault 1_5 (read as 15 s)", f"{SWEEP} x_t_underscore.csv",
        needle="1_5")  # fmt: skip
    add("defect", "simulate --tf 1_2 (read as 12 s)",
        "simulate kundur --fault 3 --far-bus 101 --tf 1_2", needle="--tf")  # fmt: skip
    add("defect", "simulate --fault 1_01 (read as bus 101)",
        "simulate kundur --fault 1_01 --far-bus 3 --tf 2", needle="--fault")  # fmt: skip
    add("defect", "simulate --fault \uff13 (fullwidth digit, read as 3)",
        "simulate kundur --fault \uff13 --far-bus 101 --tf 2", needle="--fault")  # fmt: skip
    add("defect", "CSV bus \uff13 (fullwidth digit; 1_3 is refused)",
        f"{SWEEP} x_bus_fullwidth.csv", needle="\uff13")  # fmt: skip
    add("num", "CSV bus 1_3", f"{SWEEP} x_bus_underscore.csv", needle="1_3")
    add("num", "simulate --fault 0x3", "simulate kundur --fault 0x3 --far-bus 101 --tf 2",
        needle="--fault")  # fmt: skip
    add("num", "CSV t_fault 0x1", f"{SWEEP} x_t_hex.csv", needle="0x1")
    add("num", "simulate --tf ' 2 ' (legit)", ["simulate", "kundur", "--tf", " 2 "], exit=0)
    for opt, v in (("--speed", "1e300"), ("--timeout", "nan")):
        add("num", f"pmu replay {opt} {v}",
            f"pmu replay good.c37 --port 0 --timeout 1 {opt} {v}", needle=opt)  # fmt: skip
    # -- case files ----------------------------------------------------------------------
    for name, needle in (
        ("extra_top", "solver_options"),  # unknown tables and columns are refused
        ("freq_tiny", "freq_hz"),
        ("name_list", "name"),
    ):
        add("defect", f"case c_{name}.json", ["simulate", f"c_{name}.json", "--fault", "3",
            "--far-bus", "101", "--tf", "1.5"], needle=needle)  # fmt: skip

    add(
        "defect",
        "case: machine 1 moved to PQ bus 4, swing bus 1 without a machine",
        "simulate c_mach_on_pq.json --fault 3 --far-bus 101 --tf 1.5",
        exit=0,
        needle="without a machine is netted",
    )  # fmt: skip  (a warning naming bus 1)
    for name, needle in (
        ("extra_table", "statcoms"), ("long_row", "column count"), ("col_lower", "'h'"),
        ("branch_absent", "999"), ("machine_absent_bus", "999"), ("exciter_absent", "9"),
        ("governor_absent", "machine 9"), ("pss_absent", "machine 9"), ("load_absent", "999"),
        ("dup_machine", "duplicate"), ("dup_exciter", "duplicate"), ("zero_z_line", "'x'"),
        ("neg_H", "'H'"), ("nan_H", "'H'"), ("inf_r", "'r'"), ("zero_mva", "'mva'"),
        ("base0", "base_mva"), ("base_str", "base_mva"), ("freq_bool", "freq_hz"),
        ("kind9", "kind"), ("no_swing", "swing"), ("bus0", "number"), ("bus_float", "1.5"),
        ("version99", "version"), ("exc_type99", "type"), ("tdop0", "Tdop"), ("xd_neg", "xd"),
        ("self_loop", "to_bus"), ("vmag0", "vmag"), ("cols_dup", "twice"),
        ("rows_dict", "rows"), ("tables_list", "tables"), ("sw_con_text", "sw_con"),
        ("island", "77"), ("h_1e300", "1e+15"), ("truncated", "c_truncated.json"),
        ("extra_col", "Hx"), ("short_row", "column count"), ("no_base", "base_mva"),
        ("no_machines", "machine 1 does not exist in table 'machines'"), ("freq_1", ""),
    ):  # fmt: skip
        add("case", f"case c_{name}.json", ["simulate", f"c_{name}.json", "--tf", "1"],
            needle=needle, exit=0 if name == "freq_1" else 2)  # fmt: skip
    # -- import-psse -------------------------------------------------------------------
    for name, needle in (
        ("trunc", "cut short"), ("dupbus", "bus 1 appears twice"), ("branch_absent", "bus 9"),
        ("zero_z", "R + jX"), ("nan_x", "nan"), ("version99", "99"), ("base0", "SBASE"),
        ("busstr", "'X'"), ("extra_fields", "field"), ("gen_absent_bus", "bus 7"),
        ("neg_mbase", "MBASE"), ("semicolons", "r_semicolons.raw:1"),
    ):  # fmt: skip
        add("psse", f"import-psse r_{name}.raw", ["import-psse", f"r_{name}.raw", "smib.dyr",
            "-o", "p.json"], needle=needle)  # fmt: skip
    for name, needle in (
        ("negH", "H = -3"), ("nanH", "nan"), ("orphan_bus", "bus 9"), ("orphan_id", "'7'"),
        ("dup", "second machine model"), ("noslash", "'/'"), ("unknown_model", "FOOBAR"),
        ("few_params", "got 1"), ("many_params", "got 4"), ("text_param", "three"),
        ("huge_H", "1e+15"), ("empty", "without a machine model"),
    ):  # fmt: skip
        add("psse", f"import-psse d_{name}.dyr", ["import-psse", "smib.raw", f"d_{name}.dyr",
            "-o", "p.json"], needle=needle)  # fmt: skip
    add("defect", "import-psse DYR with a BOM (a RAW with one is read)",
        "import-psse smib.raw d_bom.dyr -o p.json", exit=0, keep=("p.json",))  # fmt: skip
    add("psse", "import-psse RAW given as DYR too", "import-psse smib.raw smib.raw -o p.json",
        needle="smib.raw:1")  # fmt: skip
    add("psse", "import-psse -o /dev/full", "import-psse smib.raw smib.dyr -o /dev/full",
        needle="/dev/full")  # fmt: skip
    add("psse", "import-psse name with ':' and newline (legit)",
        ["import-psse", "colon:new\nline.raw", "smib.dyr", "-o", "o:ut\n.json"], exit=0,
        keep=("o:ut\n.json",))  # fmt: skip
    # -- fault CSVs ----------------------------------------------------------------------
    for name, exit_, needle in (
        ("bom_crlf", 0, ""), ("cr_only", 0, ""), ("hdr_space", 0, ""), ("col_order", 0, ""),
        ("blank_mid", 0, ""), ("comment", 2, "# faults"), ("trailing_comma", 2, "''"),
        ("dup_t_default", 2, "listed twice"), ("dup_t_spelt", 2, "listed twice"),
        ("dup_bus_fault", 2, "listed twice"), ("extra_cells", 2, "4 field(s)"),
        ("long_line", 2, "x_long_line.csv:2"), ("utf16", 2, "UTF-8"),
    ):  # fmt: skip
        add("csv", f"sweep-cct --faults x_{name}.csv", f"{SWEEP} x_{name}.csv", exit=exit_,
            needle=needle, keep=("o.jsonl",) if exit_ == 0 else ())  # fmt: skip
    add("csv", "place --site-costs a faults CSV",
        f"{PLACE} --site-costs f.csv", needle="'bus', 'far_bus' unknown")  # fmt: skip
    add("csv", "sweep-cct --out /dev/null", f"{SWEEP} f.csv".replace("o.jsonl", "/dev/null"),
        needle="the file name must end in .jsonl")  # fmt: skip
    # -- pmu network options -------------------------------------------------------------
    serve = "pmu serve kundur --fault 3 --far-bus 101 --timeout 1 --port 0"
    for args, needle in (
        (f"{serve} --allow 127.0.0.1/8", "127.0.0.1/8"),
        (f"{serve} --allow 256.1.1.1", "256.1.1.1"),
        ("pmu serve kundur --fault 3 --far-bus 101 --each-pmu --port 65535", "65535"),
        ("pmu record localhost:1 -o r.c37 --frames 5", "localhost:1"),
        ("pmu record 127.0.0.1:1 -o r.c37 --frames 0", "--frames"),
        ("pmu control kundur 127.0.0.1:1 --esd-pct 5 --timeout 2", "127.0.0.1:1"),
    ):
        add("pmu", " ".join(args.split()[:2] + args.split()[-2:]), args, needle=needle)
    return out


def main() -> int:
    sel = sys.argv[sys.argv.index("-k") + 1] if "-k" in sys.argv else ""
    SHORTS.write_text("")
    cwd = WORK
    prepare(cwd)
    rows = []
    for p in probes():
        if sel and sel not in p.what:
            continue
        v, dt = judge(p, cwd)
        rows.append((p, v))
        if "-v" in sys.argv:
            print(f"{dt or 0:6.1f} s  [{p.tag}] {p.what}: {v}", flush=True)
    width = max(len(p.what) for p, _ in rows)
    print(f"{'tag':>7}  {'probe':<{width}}  verdict")
    for p, v in rows:
        print(f"{p.tag:>7}  {p.what:<{width}}  {v}")
    short = sum(v != "ok" for _, v in rows)
    print(f"\n{len(rows) - short} ok, {short} short of {len(rows)} probes")
    print(f"work directory {WORK}; the short probes' output in {SHORTS}")
    return 1 if short else 0


if __name__ == "__main__":
    sys.exit(main())
