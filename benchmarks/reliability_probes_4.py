"""Fourth set of reliability probes: variants of rounds 2 and 3 on other subcommands.

Same machinery (`reliability_probes`: Probe, cli, run, verdict, table); a bad input must
end with exit status 2, one ``error:`` line naming what and where, no traceback and no
output file (no new file at all in the work directory); a legitimate run exits 0 with
complete output (with --json: strict JSON on stdout, no NaN/Infinity).

    python benchmarks/reliability_probes_4.py [-v] [-k SUBSTRING]

Work directory: a new temporary directory (its path printed; removed unless a probe is
short); details of every short probe are written beside it (``<work>.shorts.txt``).
Exit status 1 if any probe is short.  About 11 minutes on one core.
"""

from __future__ import annotations

import json
import os
import re
import resource
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

BENCH = Path(__file__).resolve().parent
sys.path.insert(0, str(BENCH))
sys.path.insert(0, str(BENCH.parent / "tests"))

from reliability_probes import PSSE, STABCTL, Probe, cli, run, table, verdict, write  # noqa: E402

WORK = Path(tempfile.mkdtemp(prefix="stabctl-probes-4."))
SHORTS = WORK.parent / (WORK.name + ".shorts.txt")
TIMEOUT = 60
# records files with damaged lines: moved aside with a warning and rerun (the design)
BY_DESIGN = ("deep.jsonl", "deep_obj.jsonl", "list_line.jsonl", "nan_line.jsonl", "str_line.jsonl")
PRISTINE: dict = {}

CCT = "cct kundur --fault 3 --far-bus 101"
SIM = "simulate kundur --fault 3 --far-bus 101 --tf 2"
RMSE = "estimate rmse kundur --fault 3 --far-bus 101 --runs 1 --tf 2 --ambient-s 0"
PLACE = "place kundur --faults DEFAULT --workers 1"
SWEEP = "sweep-cct kundur --faults f.csv --workers 1 --tol-ms 20"
SERVE = "pmu serve kundur --fault 3 --far-bus 101 --port 0 --timeout 1"


@dataclass
class P4(Probe):
    json_out: bool = False  # stdout must be strict JSON (a document or JSON lines)
    max_s: float = 0.0  # must end within this (fail before computing)
    limit_as: bool = False  # run under RLIMIT_AS 2.5 GB
    unchanged: str = ""  # an input file that must be left byte for byte
    extra: list = field(default_factory=list)


def strict_json(text: str):
    def bad(c):
        raise ValueError(f"non-standard constant {c}")

    text = text.strip()
    try:
        return json.loads(text, parse_constant=bad)
    except ValueError:
        pass
    lines = [x for x in text.splitlines() if x.strip()]
    if not lines:
        raise ValueError("no JSON on stdout")
    return [json.loads(x, parse_constant=bad) for x in lines]


def snapshot(cwd: Path) -> set:
    return {str(p.relative_to(cwd)) for p in cwd.rglob("*")}


def run4(args, cwd, timeout=TIMEOUT, limit_as=False):
    def pre():
        signal.signal(signal.SIGINT, signal.SIG_DFL)  # a background parent ignores it
        if limit_as:
            resource.setrlimit(resource.RLIMIT_AS, (2_500_000_000, 2_500_000_000))

    return run(args, cwd, timeout, preexec_fn=pre, stdin=subprocess.DEVNULL)


def log_short(p, v, res, extra=""):
    with SHORTS.open("a") as f:
        f.write(f"### {p.what}: {v}\n$ stabctl {' '.join(map(str, p.args))}\n")
        if res is not None:
            f.write(f"exit {res.returncode}\n--- stderr (head)\n")
            f.write("\n".join(res.stderr.strip().splitlines()[:8]) + "\n")
            f.write("--- stderr (tail)\n" + "\n".join(res.stderr.strip().splitlines()[-4:]) + "\n")
            f.write("--- stdout (head)\n" + "\n".join(res.stdout.strip().splitlines()[:6]) + "\n")
        if extra:
            f.write(extra + "\n")
        f.write("\n")


def judge(p: P4, cwd: Path) -> str:
    before = snapshot(cwd)
    digest = (cwd / p.unchanged).read_bytes() if p.unchanged else None
    t0 = time.monotonic()
    try:
        res = run4(p.args, cwd, limit_as=p.limit_as)
    except subprocess.TimeoutExpired:
        v = f"hang: no end in {TIMEOUT} s"
        log_short(p, v, None)
        cleanup(cwd, before)
        return v
    dt = time.monotonic() - t0
    v = verdict(p, res, cwd)
    new = sorted(snapshot(cwd) - before)
    if v == "ok" and p.exit == 2 and new:
        v = f"left behind: {', '.join(new)[:100]}"
    if v == "ok" and p.exit == 2 and "--json" in p.args and res.stdout.strip():
        v = f"stdout on error: {res.stdout.strip()[:80]!r}"
    if v == "ok" and p.json_out:
        try:
            strict_json(res.stdout)
        except ValueError as e:
            v = f"--json stdout not strict JSON: {str(e)[:90]}"
    if v == "ok" and p.max_s and dt > p.max_s:
        v = f"took {dt:.1f} s before failing (computed first?)"
    if v == "ok" and digest is not None and (cwd / p.unchanged).read_bytes() != digest:
        v = f"input {p.unchanged} changed"
    targets = {str(a) for i, a in enumerate(p.args) if i and p.args[i - 1] in ("--out", "-o")}
    for rel, data in PRISTINE.items():
        path = cwd / rel
        if not path.is_file() or path.read_bytes() != data:
            if v == "ok" and rel not in targets:
                v = f"input {rel} changed or removed"
            try:
                path.unlink(missing_ok=True)
                path.write_bytes(data)
            except OSError:  # an immutable or append-only file
                pass
    if v != "ok":
        log_short(p, v, res, f"elapsed {dt:.1f} s; new files: {new}")
    cleanup(cwd, before)
    return v


def cleanup(cwd: Path, before: set):
    for rel in sorted(snapshot(cwd) - before, reverse=True):
        path = cwd / rel
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path, ignore_errors=True)
        else:
            path.unlink(missing_ok=True)


# ---------------------------------------------------------------------------------------


def prepare(cwd: Path):
    from stabctl.io import load_case
    from stabctl.io.pst import case_to_dict

    write(cwd, "f.csv", "bus,far_bus\n3,101\n")
    write(cwd, "f_bom.csv", "\ufeffbus,far_bus\n3,101\n")
    write(cwd, "f_crlf.csv", "bus,far_bus\r\n3,101\r\n")
    write(cwd, "f_unknown_col.csv", "bus,far_bus,tfault\n3,101,1.5\n")
    write(cwd, "f_tab.csv", "bus\tfar_bus\n3\t101\n")
    write(cwd, "f_semicolon.csv", "bus;far_bus\n3;101\n")
    write(cwd, "f_blank_cell.csv", "bus,far_bus,t_fault\n3,101,\n")
    write(cwd, "f_circ_blank.csv", "bus,far_bus,circuit\n3,101,1\n3,101,\n")
    write(cwd, "f_space.csv", "bus,far_bus\n 3 , 101 \n")
    write(cwd, "f_quoted_hdr.csv", '"bus","far_bus"\n"3","101"\n')
    write(cwd, "f_upper.csv", "BUS,FAR_BUS\n3,101\n")
    write(cwd, "f_reversed.csv", "bus,far_bus\n101,3\n")  # the same line seen from 101
    write(cwd, "f_dup_rev.csv", "bus,far_bus\n3,101\n101,3\n")  # legit: two faults
    write(cwd, "f_no_line.csv", "bus,far_bus\n3,13\n")  # both buses exist, no line
    write(cwd, "f_big_bus.csv", "bus,far_bus\n99999999999999999999999,101\n")
    write(cwd, "f_nul.csv", "bus,far_bus\n3,101\x00\n")
    (cwd / "f_bin.csv").write_bytes(bytes(range(256)) * 40)
    write(cwd, "f_hexbus.csv", "bus,far_bus\n0x3,101\n")
    write(cwd, "f_tf_inf.csv", "bus,far_bus,t_fault\n3,101,-inf\n")
    os.mkfifo(cwd / "fifo.csv")
    (cwd / "dangling.csv").symlink_to(cwd / "no_such_target.csv")
    (cwd / "loop.csv").symlink_to(cwd / "loop.csv")
    # place per-row requirements
    write(cwd, "req_nan.csv", "bus,far_bus,required_clearing_cycles\n3,101,nan\n")
    write(cwd, "req_neg.csv", "bus,far_bus,target_cct_gain\n3,101,-5\n")
    write(cwd, "req_zero_s.csv", "bus,far_bus,target_cct_s\n3,101,0\n")
    write(cwd, "req_inf_s.csv", "bus,far_bus,target_cct_s\n3,101,inf\n")
    # site costs
    write(cwd, "sc_nan.csv", "machine,cost_mw\n1,nan\n")
    write(cwd, "sc_neg.csv", "machine,cost_mw\n1,-5\n")
    write(cwd, "sc_inf.csv", "machine,cost_mw\n1,inf\n")
    write(cwd, "sc_name.csv", "machine,cost_mw\nG1,5\n")
    write(cwd, "sc_float.csv", "machine,cost_mw\n1.0,5\n")
    write(cwd, "sc_empty.csv", "")
    write(cwd, "sc_bom.csv", "\ufeffmachine,cost_mw\n1,5\n")
    # records and JSON files
    write(cwd, "deep.jsonl", "[" * 100_000 + "]" * 100_000 + "\n")
    write(cwd, "deep_obj.jsonl", '{"a":' * 50_000 + "1" + "}" * 50_000 + "\n")
    (cwd / "bin.jsonl").write_bytes(bytes(range(256)) * 40)
    write(cwd, "list_line.jsonl", "[1, 2, 3]\n")
    write(cwd, "str_line.jsonl", '"just a string"\n')
    write(cwd, "nan_line.jsonl", '{"key": NaN}\n')
    write(cwd, "nostatus.jsonl", '{"key": "kundur/3-101/t1/esd-none"}\n')
    for name in ("imm.csv", "imm.json", "imm.jsonl", "app.csv", "app.json", "app.jsonl"):
        write(cwd, name, "")
        subprocess.run(["chattr", "+i" if name.startswith("imm") else "+a", str(cwd / name)])
    write(cwd, "huge_line.jsonl", '{"key": "' + "k" * 30_000_000 + '"}\n')
    (cwd / "adir").mkdir()
    write(cwd, "afile.txt", "a file, not a directory\n")
    (cwd / "ro").mkdir()
    subprocess.run(["chattr", "+i", str(cwd / "ro")], check=False)
    # case JSON variants
    d = case_to_dict(load_case("kundur"))
    text = json.dumps(d)
    write(cwd, "case.json", text)
    write(cwd, "case_bom.json", "\ufeff" + text)
    write(cwd, "case_trailing.json", text + "\n}garbage")
    write(cwd, "case_two_docs.json", text + "\n" + text)
    write(cwd, "case_crlf.json", json.dumps(d, indent=1).replace("\n", "\r\n"))
    dup = text[:-1] + ', "tables": {}}'  # a second "tables" key: the last wins in json
    write(cwd, "case_dupkey.json", dup)
    d2 = json.loads(text)
    d2["tables"]["buses"]["rows"].append(list(d2["tables"]["buses"]["rows"][0]))
    write(cwd, "case_dup_bus.json", json.dumps(d2))
    (cwd / "case_bin.json").write_bytes(bytes(range(256)) * 40)
    write(cwd, "case_huge_line.json", '{"x": "' + "a" * 30_000_000 + '"}')
    # PSS/E RAW variants
    raw = (PSSE / "five_bus_v33.raw").read_text()
    write(cwd, "five.raw", raw)
    write(cwd, "five.dyr", (PSSE / "five_bus.dyr").read_text())
    write(cwd, "five_crlf.raw", raw.replace("\n", "\r\n"))
    write(cwd, "five_bom.raw", "\ufeff" + raw)
    (cwd / "bin.raw").write_bytes(bytes(range(256)) * 40)
    write(cwd, "huge_line.raw", "0, 100.0, 33" + " " * 30_000_000 + "\n")
    (cwd / "bin.xlsx").write_bytes(b"PK\x03\x04" + bytes(range(256)) * 40)
    subprocess.run(
        STABCTL + cli("screen kundur --buses 3,13 --workers 1 --out scr.jsonl"),
        cwd=cwd,
        capture_output=True,
        check=True,
    )  # a screening's records
    # recordings
    try:
        from reliability_probes_3 import _record

        _record(cwd)
    except Exception as e:  # noqa: BLE001
        print("no recordings:", e)


def probes(cwd: Path) -> list[P4]:
    out: list[P4] = []

    def add(finding, what, args, **kw):
        what = re.sub(r"([a-z])\1{20,}", r"\1...(300)", what)
        out.append(P4(finding, what, cli(args) if isinstance(args, str) else args, **kw))

    # an option given twice: the last silently wins?
    add("twice", "cct --fault 3 --fault 13", "cct kundur --fault 3 --fault 13 --far-bus 101",
        needle="--fault")  # fmt: skip
    add("twice", "simulate --tf 1 --tf 2", f"{SIM} --tf 1", needle="--tf")

    # --- cct: every numeric option ------------------------------------------------------
    for opt, v in (
        ("--t-max", "nan"),
        ("--t-max", "inf"),
        ("--t-max", "-1"),
        ("--tol-ms", "0"),
        ("--tol-ms", "-0"),
        ("--tol-ms", "inf"),
        ("--t-fault", "nan"),
        ("--t-fault", "inf"),
        ("--t-fault", "1e308"),
        ("--step", "nan"),
        ("--step", "inf"),
        ("--step", "1e-9"),
        ("--tf", "nan"),
        ("--tf", "1e308"),
        ("--esd-pct", "nan"),
        ("--esd-pct", "-5"),
        ("--esd-pct", "1e308"),
        ("--deadband-hz", "nan"),
        ("--deadband-hz", "-0.1"),
        ("--v-gate", "nan"),
        ("--v-gate", "-1"),
        ("--hysteresis-hz", "nan"),
        ("--hysteresis-hz", "-0.05"),
        ("--circuit", "0"),
        ("--circuit", "3"),
    ):
        esd = " --esd-pct 5" if opt in ("--deadband-hz", "--v-gate", "--hysteresis-hz") else ""
        add(
            "num",
            f"cct {opt} {v}",
            f"{CCT}{esd} {opt} {v}",
            needle="circuit 3" if (opt, v) == ("--circuit", "3") else opt,
        )
    add(
        "num",
        "cct --hysteresis-hz above the deadband",
        f"{CCT} --esd-pct 5 --deadband-hz 0.1 --hysteresis-hz 0.2",
        needle="hysteresis",
    )
    add("num", "cct --esd-pct 0", f"{CCT} --esd-pct 0", needle="--esd-pct")
    add("bus", "cct --trip of no line", f"{CCT} --trip 1 2", needle="bus 1 and bus 2")
    add("bus", "cct --far-bus 4 --circuit 2", "cct kundur --fault 3 --far-bus 4 --circuit 2",
        needle="circuit")  # fmt: skip
    add("bus", "cct --fault 3 --far-bus 13 (no line)", "cct kundur --fault 3 --far-bus 13",
        needle="bus 3 and bus 13")  # fmt: skip
    add("bus", "cct --fault 999 --json", "cct kundur --fault 999 --far-bus 101 --json",
        needle="999")  # fmt: skip
    add("bus", "cct --fault 3 --far-bus 3", "cct kundur --fault 3 --far-bus 3", needle="3")
    # --- simulate: the numeric options round 3 did not cover ---------------------------
    for args, needle in (
        (f"{SIM} --separation-limit nan", "--separation-limit"),
        (f"{SIM} --separation-limit 0", "--separation-limit"),
        (f"{SIM} --separation-limit -1", "--separation-limit"),
        (f"{SIM} --clear-cycles nan", "--clear-cycles"),
        (f"{SIM} --far-clear-cycles inf", "--far-clear-cycles"),
        (f"{SIM} --circuit 3", "circuit"),
        (f"{SIM} --esd-pct nan", "--esd-pct"),
        (f"{SIM} --esd-pct 5 --deadband-hz nan", "--deadband-hz"),
        (f"{SIM} --esd-pct 5 --v-gate inf", "--v-gate"),
        ("simulate kundur --trip 3 101 --t-trip nan --tf 2", "--t-trip"),
        ("simulate kundur --trip 3 101 --t-trip 1 --t-trip 1.2 --tf 2", "--t-trip"),
        ("simulate kundur --trip-gen 99 1 --tf 2", "99"),
        ("simulate kundur --trip-gen 1 nan --tf 2", "--trip-gen"),
        ("simulate kundur --trip-gen 1 1 --trip-gen 1 1.5 --tf 2", "machine 1 tripped at 1.5 s"),
        ("simulate kundur --load-step 999 1 0.1 0 --tf 2", "999"),
        ("simulate kundur --load-step 4 1 nan 0 --tf 2", "--load-step"),
        ("simulate kundur --load-step 4 1 1e308 0 --tf 2", "--load-step"),
        ("simulate kundur --load-step 4 5 0.1 0 --tf 2", "load step"),
        ("simulate kundur --vref-step 99 1 0.01 --tf 2", "99"),
        ("simulate kundur --vref-step 1 1 inf --tf 2", "--vref-step"),
        ("simulate kundur --pref-step 1 inf 0.05 --tf 2", "--pref-step"),
        ("simulate kundur --pref-step 1 -1 0.05 --tf 2", "negative time"),
        ("simulate kundur --bus-fault 3:nan:0.05 1 1.1 --tf 2", "--bus-fault"),
        ("simulate kundur --bus-fault 3:-1:0.05 1 1.1 --tf 2", "--bus-fault"),
        ("simulate kundur --bus-fault 3:0:0.05:7 1 1.1 --tf 2", "--bus-fault"),
        ("simulate kundur --bus-fault 3:0 1 1.1 --tf 2", "--bus-fault"),
        ("simulate kundur --bus-fault 3 nan 1.1 --tf 2", "--bus-fault"),
        ("simulate kundur --close 3 101 1.6 --tf 2", "not open"),
        ("simulate kundur --trip 3 101 --t-trip 1 --close 3 101 nan --tf 2", "--close"),
        ("simulate kundur --trip 3 101 --t-trip 1.5 --close 3 101 1.2 --tf 2", "not open"),
        ("simulate kundur --trip 3 101:3 --t-trip 1 --tf 2", "3"),
        ("simulate kundur --trip 3 101:0 --t-trip 1 --tf 2", "--trip"),
    ):
        add("num", " ".join(args.split()[2:]).replace("--tf 2", "").strip(), args, needle=needle)
    # output paths of simulate: must fail before the run, leave nothing
    for out_arg, needle in (
        ("--out nodir/x.csv", "nodir"),
        ("--out afile.txt/x.csv", "afile.txt"),
        ("--out ro/x.csv", "ro"),
        ("--out adir", "adir"),
        ("--out x.txt", "--out"),
        ("--plot x.jpg", "--plot"),
        ("--plot nodir/x.png", "nodir"),
        ("--out x.csv --plot nodir/x.png", "nodir"),
        ("--out imm.csv", "imm.csv"),
        ("--out app.csv", "app.csv"),
        (f"--out {'x' * 300}.csv", "too long"),
    ):
        add("out", f"simulate {out_arg}", f"{SIM} {out_arg}", needle=needle, no_file="x.csv")
    add("out", "simulate --out x.npz --json (legit)", f"{SIM} --out x.npz --json", exit=0,
        json_out=True)  # fmt: skip
    # --- case JSON files ------------------------------------------------------------
    for name, exit_ in (
        ("case_bom.json", 0),  # a UTF-8 BOM is read, as an editor on Windows writes it
        ("case_crlf.json", 0),
        ("case_trailing.json", 2),
        ("case_two_docs.json", 2),
        ("case_dupkey.json", 2),
        ("case_dup_bus.json", 2),
        ("case_bin.json", 2),
        ("case_huge_line.json", 2),
        ("fifo.csv", 2),
        ("dangling.csv", 2),
        ("loop.csv", 2),
    ):
        named = {"case_bom.json": "BOM", "case_dup_bus.json": "duplicate bus"}.get(name, name)
        add("file", f"simulate case {name}", ["simulate", name, "--tf", "1"], exit=exit_,
            needle="" if exit_ == 0 else named)  # fmt: skip
    add("file", "cct case case_dupkey.json", ["cct", "case_dupkey.json", "--fault", "3"],
        needle="case_dupkey.json")  # fmt: skip
    add("file", "cases case_trailing.json", ["cases", "case_trailing.json"],
        needle="case_trailing.json")  # fmt: skip
    add("file", "cases nosuch", "cases nosuch", needle="nosuch")
    add("file", "compile nosuch", "compile nosuch", needle="nosuch")
    # --- screen -------------------------------------------------------------------
    for args, needle in (
        ("screen kundur --buses 999 --out s.jsonl", "999"),
        ("screen kundur --buses 3,3 --out s.jsonl", "3"),
        ("screen kundur --buses , --out s.jsonl", "--buses"),
        ("screen kundur --buses 3,,4 --out s.jsonl", "--buses"),
        ("screen kundur --buses 3 --workers 0 --out s.jsonl", "--workers"),
        ("screen kundur --buses 3 --workers -1 --out s.jsonl", "--workers"),
        ("screen kundur --buses 3 --workers 100000 --out s.jsonl", "--workers"),
        ("screen kundur --buses 3 --t-max nan --out s.jsonl", "--t-max"),
        ("screen kundur --buses 3 --t-max inf --out s.jsonl", "--t-max"),
        ("screen kundur --buses 3 --tol-ms 0 --out s.jsonl", "--tol-ms"),
        ("screen kundur --buses 3 --step nan --out s.jsonl", "--step"),
        ("screen kundur --lines --workers 1 --out nodir/s.jsonl", "nodir"),
        ("screen kundur --lines --workers 1 --out afile.txt/s.jsonl", "afile.txt"),
        ("screen kundur --lines --workers 1 --out ro/s.jsonl", "ro"),
        ("screen kundur --lines --workers 1 --out adir", "adir"),
        ("screen kundur --lines --workers 1 --out s.jsonl --plot nodir/s.png", "nodir"),
        ("screen kundur --lines --workers 1 --out s.jsonl --plot s.gif", "--plot"),
        ("screen kundur --buses 3 --out deep.jsonl", "deep.jsonl"),
        ("screen kundur --buses 3 --out deep_obj.jsonl", "deep_obj.jsonl"),
        ("screen kundur --buses 3 --out bin.jsonl", "bin.jsonl"),
        ("screen kundur --buses 3 --out list_line.jsonl", "list_line.jsonl"),
        ("screen kundur --buses 3 --out nan_line.jsonl", "nan_line.jsonl"),
        ("screen kundur --buses 3 --out huge_line.jsonl", "huge_line.jsonl"),
        ("screen kundur --buses 3 --out f.csv", "f.csv"),
    ):
        kw = dict(needle=needle, max_s=4.0)
        by_design = any(f"--out {n}" in args for n in BY_DESIGN)
        if by_design:
            kw = dict(exit=0, needle="moved to")
        if "s.jsonl" in args:
            kw["no_file"] = "s.jsonl"
        if not by_design and (
            "--out f.csv" in args or ".jsonl" in args.split("--out ")[-1].split()[0]
        ):
            tgt = args.split("--out ")[-1].split()[0]
            if (cwd / tgt).exists():
                kw["unchanged"] = tgt
        add("screen", " ".join(args.split()[2:]), args, **kw)
    add("json", "screen --buses 3 --json (legit)", "screen kundur --buses 3 --workers 1 "
        "--out s.jsonl --json", exit=0, json_out=True)  # fmt: skip
    # --- sweep-cct ------------------------------------------------------------------
    for args, needle in (
        (f"{SWEEP} --esd-pct nan --out o.jsonl", "--esd-pct"),
        (f"{SWEEP} --esd-pct -5 --out o.jsonl", "--esd-pct"),
        (f"{SWEEP} --esd-pct 5,5 --out o.jsonl", "--esd-pct"),
        (f"{SWEEP} --esd-pct 5,abc --out o.jsonl", "abc"),
        (f"{SWEEP} --esd-pct inf --out o.jsonl", "--esd-pct"),
        ("sweep-cct kundur --faults f.csv --workers 0 --out o.jsonl", "--workers"),
        (f"{SWEEP} --t-max inf --out o.jsonl", "--t-max"),
        (f"{SWEEP} --tf nan --out o.jsonl", "--tf"),
        (f"{SWEEP} --deadband-hz nan --esd-pct 5 --out o.jsonl", "--deadband-hz"),
        (f"{SWEEP} --out nodir/o.jsonl", "nodir"),
        (f"{SWEEP} --out ro/o.jsonl", "ro"),
        (f"{SWEEP} --out f.csv", "f.csv"),
        (f"{SWEEP} --out deep_obj.jsonl", "deep_obj.jsonl"),
        (f"{SWEEP} --out str_line.jsonl", "str_line.jsonl"),
        (f"{SWEEP} --out huge_line.jsonl", "huge_line.jsonl"),
        (f"{SWEEP} --out imm.jsonl", "imm.jsonl"),
        (f"{SWEEP} --out {'o' * 300}.jsonl", "too long"),
    ):
        tgt = args.split("--out ")[-1].split()[0]
        kw = dict(needle=needle, max_s=4.0, no_file="o.jsonl")
        if tgt == "imm.jsonl":
            kw["unchanged"] = tgt
        if tgt in BY_DESIGN:
            kw = dict(exit=0, needle="moved to")
        elif len(tgt) < 200 and (cwd / tgt).is_file():
            kw["unchanged"] = tgt
        add("sweep", " ".join(args.split()[6:]), args, **kw)
    for name, exit_, needle in (
        ("f_bom.csv", 0, ""),
        ("f_crlf.csv", 0, ""),
        ("f_quoted_hdr.csv", 0, ""),
        ("f_dup_rev.csv", 0, ""),
        ("f_unknown_col.csv", 2, "tfault"),
        ("f_tab.csv", 2, "f_tab.csv"),
        ("f_semicolon.csv", 2, "f_semicolon.csv"),
        ("f_blank_cell.csv", 0, ""),  # an empty optional cell: its default (--faults help)
        ("f_circ_blank.csv", 2, "listed twice"),
        ("f_upper.csv", 2, "f_upper.csv"),
        ("f_no_line.csv", 2, "bus 3 and bus 13"),
        ("f_big_bus.csv", 2, "f_big_bus.csv"),
        ("f_nul.csv", 2, "f_nul.csv"),
        ("f_bin.csv", 2, "f_bin.csv"),
        ("f_hexbus.csv", 2, "0x3"),
        ("f_tf_inf.csv", 2, "t_fault"),
        ("fifo.csv", 2, "fifo.csv"),
        ("dangling.csv", 2, "dangling.csv"),
        ("loop.csv", 2, "loop.csv"),
        ("no_such.csv", 2, "no_such.csv"),
    ):
        add(
            "csv",
            f"sweep-cct --faults {name}",
            ["sweep-cct", "kundur", "--faults", name, "--out", "o.jsonl", "--tol-ms", "20",
             "--workers", "1"],
            exit=exit_,
            needle=needle,
            no_file="" if exit_ == 0 else "o.jsonl",
        )  # fmt: skip
    add("csv", "sweep-cct --faults f_space.csv (spaces around numbers)",
        "sweep-cct kundur --faults f_space.csv --out o.jsonl --tol-ms 20 --workers 1",
        exit=0)  # fmt: skip
    add("json", "sweep-cct --json (legit)", f"{SWEEP} --out o.jsonl --json", exit=0,
        json_out=True)  # fmt: skip
    # --- place ----------------------------------------------------------------------
    for args, needle in (
        (f"{PLACE} --target-cct-gain nan", "--target-cct-gain"),
        (f"{PLACE} --target-cct-gain -5", "--target-cct-gain"),
        (f"{PLACE} --target-cct-gain inf", "--target-cct-gain"),
        (f"{PLACE} --target-cct-s 0", "--target-cct-s"),
        (f"{PLACE} --target-cct-s nan", "--target-cct-s"),
        (f"{PLACE} --required-clearing-cycles -1", "--required-clearing-cycles"),
        (f"{PLACE} --required-clearing-cycles nan", "--required-clearing-cycles"),
        (f"{PLACE} --target-cct-gain 5 --load-levels nan", "--load-levels"),
        (f"{PLACE} --target-cct-gain 5 --load-levels 0", "--load-levels"),
        (f"{PLACE} --target-cct-gain 5 --load-levels -1", "--load-levels"),
        (f"{PLACE} --target-cct-gain 5 --load-levels 1,1", "--load-levels"),
        (f"{PLACE} --target-cct-gain 5 --load-levels 1,", "--load-levels"),
        (f"{PLACE} --target-cct-gain 5 --cost-mwh nan", "--cost-mwh"),
        (f"{PLACE} --target-cct-gain 5 --cost-mw 0 --cost-mwh 0 --cost-site 0", "cost"),
        (f"{PLACE} --target-cct-gain 5 --zeta-min nan", "--zeta-min"),
        (f"{PLACE} --target-cct-gain 5 --zeta-min 2", "--zeta-min"),
        (f"{PLACE} --target-cct-gain 5 --max-sites 0", "--max-sites"),
        (f"{PLACE} --target-cct-gain 5 --max-sites -1", "--max-sites"),
        (f"{PLACE} --target-cct-gain 5 --max-site-pct 0", "--max-site-pct"),
        (f"{PLACE} --target-cct-gain 5 --max-site-pct nan", "--max-site-pct"),
        (f"{PLACE} --target-cct-gain 5 --max-site-pct 1e308", "--max-site-pct"),
        (f"{PLACE} --target-cct-gain 5 --amplitude-hz 0", "--amplitude-hz"),
        (f"{PLACE} --target-cct-gain 5 --max-iter 0", "--max-iter"),
        (f"{PLACE} --target-cct-gain 5 --max-rounds 0", "--max-rounds"),
        ("place kundur --faults DEFAULT --target-cct-gain 5 --workers 0", "--workers"),
        (f"{PLACE} --target-cct-gain 5 --out nodir/p.json", "nodir"),
        (f"{PLACE} --target-cct-gain 5 --out ro/p.json", "ro"),
        (f"{PLACE} --target-cct-gain 5 --out adir", "adir"),
        (f"{PLACE} --target-cct-gain 5 --screening bin.jsonl", "bin.jsonl"),
        (f"{PLACE} --target-cct-gain 5 --screening list_line.jsonl", "list_line.jsonl"),
        (f"{PLACE} --target-cct-gain 5 --screening huge_line.jsonl", "huge_line.jsonl"),
        (f"{PLACE} --target-cct-gain 5 --screening fifo.csv", "fifo.csv"),
        (f"{PLACE} --target-cct-gain 5 --screening f.csv", "f.csv"),
        (f"{PLACE} --target-cct-gain 5 --screening nostatus.jsonl", "nostatus.jsonl"),
        (f"{PLACE} --target-cct-gain 5 --screening scr.jsonl --out scr.jsonl", "scr.jsonl"),
        ("place kundur --faults f.csv --target-cct-gain 5 --workers 1 --out f.csv", "f.csv"),
        (f"{PLACE} --target-cct-gain 5 --out imm.json", "imm.json"),
        (f"{PLACE} --target-cct-gain 5 --out app.json", "app.json"),
        (f"{PLACE} --target-cct-gain 5 --out {'p' * 300}.json", "too long"),
        (
            "place kundur --faults req_nan.csv --target-cct-gain 5 --workers 1",
            "required_clearing_cycles",
        ),
        ("place kundur --faults req_neg.csv --target-cct-gain 5 --workers 1", "target_cct_gain"),
        (
            "place kundur --faults req_zero_s.csv --target-cct-gain 5 --workers 1",
            "req_zero_s.csv:2",
        ),
        ("place kundur --faults req_inf_s.csv --target-cct-gain 5 --workers 1", "target_cct_s"),
        ("place kundur --faults f_unknown_col.csv --target-cct-gain 5 --workers 1", "tfault"),
        (f"{PLACE} --target-cct-gain 5 --site-costs sc_nan.csv", "cost_mw"),
        (f"{PLACE} --target-cct-gain 5 --site-costs sc_neg.csv", "cost_mw"),
        (f"{PLACE} --target-cct-gain 5 --site-costs sc_inf.csv", "cost_mw"),
        (f"{PLACE} --target-cct-gain 5 --site-costs sc_name.csv", "G1"),
        (f"{PLACE} --target-cct-gain 5 --site-costs sc_float.csv", "1.0"),
        (f"{PLACE} --target-cct-gain 5 --site-costs sc_empty.csv", "sc_empty.csv"),
        (f"{PLACE} --target-cct-gain 5 --site-costs adir", "adir"),
    ):
        kw = dict(needle=needle, max_s=4.0, no_file="p.json")
        tgt = args.split("--out ")[-1].split()[0] if "--out " in args else ""
        if tgt in ("scr.jsonl", "f.csv", "imm.json", "app.json"):
            kw["unchanged"] = tgt
        add("place", " ".join(args.split()[2:]).replace("--faults DEFAULT --workers 1 ", ""),
            args, **kw)  # fmt: skip
    add("place", "place --site-costs sc_bom.csv (legit)",
        f"{PLACE} --target-cct-gain 5 --site-costs sc_bom.csv", exit=0)  # fmt: skip
    add("place", "place without any requirement", PLACE, needle="--target-cct-gain")
    add("json", "place --json (legit)", f"{PLACE} --target-cct-gain 5 --json", exit=0,
        json_out=True)  # fmt: skip
    # --- eig ------------------------------------------------------------------------
    add("eig", "eig --report --out-dir afile.txt", "eig kundur --report --out-dir afile.txt",
        needle="afile.txt", max_s=4.0)  # fmt: skip
    add("eig", "eig --report --out-dir ro", "eig kundur --report --out-dir ro", needle="ro",
        max_s=4.0)  # fmt: skip
    add("eig", "eig --areas -1", "eig kundur --areas -1", needle="--areas")
    add("eig", "eig nosuch", "eig nosuch", needle="nosuch")
    add("json", "eig --json (legit)", "eig kundur --json", exit=0, json_out=True)
    # --- estimate -------------------------------------------------------------------
    for opt, v in (
        ("--rate", "nan"),
        ("--rate", "59.999"),
        ("--latency-ms", "-1"),
        ("--latency-ms", "nan"),
        ("--latency-ms", "1e308"),
        ("--drop", "1"),
        ("--drop", "-0.1"),
        ("--drop", "nan"),
        ("--runs", "0"),
        ("--runs", "-1"),
        ("--tve-pct", "nan"),
        ("--fe-hz", "inf"),
        ("--k-sigma", "0"),
        ("--settle-ms", "nan"),
        ("--settle-ms", "-5"),
        ("--seed", "-1"),
        ("--clear-cycles", "nan"),
        ("--t-fault", "nan"),
    ):
        add("est", f"estimate rmse {opt} {v}", f"{RMSE} {opt} {v}", needle=opt)
    base = "estimate rmse kundur --fault 3 --far-bus 101 --runs 1 --tf 2"
    for opt, v in (
        ("--ambient-s", "nan"),
        ("--ambient-s", "-1"),
        ("--ambient-pct", "-1"),
        ("--ambient-tau-s", "0"),
        ("--ambient-tau-s", "nan"),
        ("--ambient-runs", "0"),
        ("--ambient-runs", "-1"),
    ):
        add("est", f"estimate rmse {opt} {v}", f"{base} --ambient-s 2 {opt} {v}", needle=opt)
    add("est", "estimate rmse --fault 999", "estimate rmse kundur --fault 999 --far-bus 101",
        needle="999")  # fmt: skip
    add(
        "est",
        "estimate cct --runs 0",
        "estimate cct kundur --fault 3 --far-bus 101 --esd-pct 5 --runs 0",
        needle="--runs",
    )
    add("est", "estimate cct --esd-pct nan",
        "estimate cct kundur --fault 3 --far-bus 101 --esd-pct nan --runs 1",
        needle="--esd-pct")  # fmt: skip
    add("est", "estimate cct --esd-pct 0",
        "estimate cct kundur --fault 3 --far-bus 101 --esd-pct 0 --runs 1",
        needle="--esd-pct")  # fmt: skip
    add("est", "estimate closed-loop --esd-pct -5",
        "estimate closed-loop kundur --fault 3 --far-bus 101 --esd-pct -5 --tf 2",
        needle="--esd-pct")  # fmt: skip
    add("est", "estimate closed-loop --rate 7",
        "estimate closed-loop kundur --fault 3 --far-bus 101 --esd-pct 5 --rate 7 --tf 2",
        needle="--rate")  # fmt: skip
    add("json", "estimate rmse --json (legit)", f"{RMSE} --json", exit=0, json_out=True)
    add("json", "estimate closed-loop --json (legit)",
        "estimate closed-loop kundur --fault 3 --far-bus 101 --esd-pct 5 --tf 2 --json",
        exit=0, json_out=True)  # fmt: skip
    if (cwd / "good.c37").exists():
        for args, needle in (
            ("estimate track kundur --source good.c37 --until nan --out t.csv", "--until"),
            ("estimate track kundur --source good.c37 --until -1 --out t.csv", "--until"),
            ("estimate track kundur --source good.c37 --out nodir/t.csv", "nodir"),
            ("estimate track kundur --source good.c37 --out ro/t.csv", "ro"),
            ("estimate track kundur --source good.c37 --out adir", "adir"),
            ("estimate track kundur --source good.c37 --out good.c37", "good.c37"),
            ("estimate track miniwecc --source good.c37 --out t.csv", "good.c37"),
            ("estimate track kundur --source good.c37 --window-cycles nan --out t.csv",
             "--window-cycles"),
            ("estimate track kundur --source good.c37 --esd-pct nan --out t.csv", "--esd-pct"),
            ("pmu replay good.c37 --port 0 --speed nan --timeout 1", "--speed"),
            ("pmu replay good.c37 --port 0 --speed -1 --timeout 1", "--speed"),
            ("pmu replay good.c37 --port 0 --timeout inf", "--timeout"),
            ("pmu replay good.c37 --port 0 --host 999.1.1.1 --timeout 1", "999.1.1.1"),
            ("pmu replay fifo.csv --port 0 --timeout 1", "fifo.csv"),
        ):  # fmt: skip
            kw = dict(needle=needle, no_file="t.csv")
            if "good.c37 --out good.c37" in args:
                kw["unchanged"] = "good.c37"
            add("pmu", " ".join(args.split()[:2] + args.split()[3:]), args, **kw)
    # --- pmu serve / plant / control / record ------------------------------------------
    for args, needle in (
        (f"{SERVE} --rate 7", "--rate"),
        (f"{SERVE} --drop 2", "--drop"),
        (f"{SERVE} --drop nan", "--drop"),
        (f"{SERVE} --host 999.1.1.1", "999.1.1.1"),
        (f"{SERVE} --host nosuchhost.invalid", "nosuchhost.invalid"),
        (f"{SERVE} --speed inf", "--speed"),
        (f"{SERVE} --tf nan", "--tf"),
        (f"{SERVE} --tve-pct -1", "--tve-pct"),
        (f"{SERVE} --window-cycles 0", "--window-cycles"),
        (f"{SERVE} --allow 10.0.0.1,,10.0.0.2", "--allow"),
        ("pmu serve kundur --fault 999 --far-bus 101 --port 0 --timeout 1", "999"),
        ("pmu plant kundur --fault 3 --far-bus 101 --esd-pct nan --port 0 --timeout 1",
         "--esd-pct"),
        ("pmu plant kundur --fault 3 --far-bus 101 --esd-pct 5 --port 0 --timeout -1",
         "--timeout"),
        ("pmu plant kundur --fault 3 --far-bus 101 --esd-pct 5 --port 0 --timeout 1 "
         "--deadband-hz nan", "--deadband-hz"),
        ("pmu control kundur 127.0.0.1:1 --esd-pct 5 --timeout nan", "--timeout"),
        ("pmu control kundur 127.0.0.1:1 --esd-pct 5 --latency-ms nan", "--latency-ms"),
        ("pmu control kundur 127.0.0.1:1 --esd-pct nan", "--esd-pct"),
        ("pmu control kundur 127.0.0.1 --esd-pct 5", "127.0.0.1"),
        ("pmu control kundur nohost.invalid:4712 --esd-pct 5 --timeout 2", "nohost.invalid"),
        ("pmu record 127.0.0.1:1 -o nodir/r.c37 --frames 5", "nodir"),
        ("pmu record 127.0.0.1:1 -o ro/r.c37 --frames 5", "ro"),
        ("pmu record 127.0.0.1:1 -o good.c37 --frames 5", ""),
        ("pmu record nohost.invalid:4712 -o r.c37 --frames 5", "nohost.invalid"),
    ):  # fmt: skip
        kw = dict(needle=needle, no_file="r.c37")
        if "-o good.c37" in args and (cwd / "good.c37").exists():
            kw["unchanged"] = "good.c37"
        add("pmu", " ".join(args.split()[:2]) + " " + " ".join(args.split()[-3:]), args, **kw)
    # --- omib -----------------------------------------------------------------------
    for args, needle in (
        ("omib --pm nan", "--pm"),
        ("omib --pm -0.5", "--pm"),
        ("omib --pm 0", "--pm"),
        ("omib --delta0 0", "--delta0"),
        ("omib --delta0 nan", "--delta0"),
        ("omib --delta0 2", "--delta0"),
        ("omib --delta0 -0.5", "--delta0"),
        ("omib --pmax 0.1", "Pmax"),
        ("omib --pmax nan", "--pmax"),
        ("omib --pmax inf", "--pmax"),
        ("omib --f0 0", "--f0"),
        ("omib --f0 nan", "--f0"),
        ("omib -c -1", "cycles"),
        ("omib -c nan", "cycles"),
        ("omib -c inf", "cycles"),
        ("omib -c 1e308", "cycles"),
        ("omib -c 6 abc", "abc"),
        ("omib -c 6 -3", "-3"),
    ):
        add("omib", args, args, needle=needle)
    add("json", "omib --json (legit)", "omib --json", exit=0, json_out=True)
    add("json", "omib -c 0 --json (a fault of no length)", "omib -c 0 --json",
        needle="a fault of no length would do nothing")  # fmt: skip
    # --- import-psse / import-andes -------------------------------------------------
    for args, needle, exit_ in (
        ("import-psse five.raw five.dyr -o nodir/p.json --skip-unsupported", "nodir", 2),
        ("import-psse five.raw five.dyr -o ro/p.json --skip-unsupported", "ro", 2),
        ("import-psse five.raw five.dyr -o adir --skip-unsupported", "adir", 2),
        ("import-psse five.raw five.dyr -o five.dyr --skip-unsupported", "five.dyr", 2),
        ("import-psse five.raw five.dyr -o five.raw --skip-unsupported", "five.raw", 2),
        ("import-psse bin.raw -o p.json", "bin.raw", 2),
        ("import-psse huge_line.raw -o p.json", "huge_line.raw", 2),
        ("import-psse fifo.csv -o p.json", "fifo.csv", 2),
        ("import-psse five.raw fifo.csv -o p.json", "fifo.csv", 2),
        ("import-psse five.raw adir -o p.json", "adir", 2),
        ("import-psse five_crlf.raw five.dyr -o p.json --skip-unsupported", "", 0),
        ("import-psse five_bom.raw five.dyr -o p.json --skip-unsupported", "", 0),
        ("import-andes bin.xlsx -o a.json", "bin.xlsx", 2),
        ("import-andes fifo.csv -o a.json", "fifo.csv", 2),
        ("import-andes five.raw five.dyr -o nodir/a.json --skip-unsupported", "nodir", 2),
        ("import-andes five.raw five.dyr -o five.dyr --skip-unsupported", "five.dyr", 2),
    ):
        kw = dict(exit=exit_, needle=needle, no_file="p.json" if exit_ else "")
        for tgt in ("five.dyr", "five.raw"):
            if f"-o {tgt}" in args:
                kw["unchanged"] = tgt
        add("imp", args.replace(" --skip-unsupported", ""), args, **kw)
    add("json", "import-psse --json (legit)",
        "import-psse five.raw five.dyr -o p.json --skip-unsupported --json", exit=0,
        json_out=True)  # fmt: skip
    # --- cases / paper --------------------------------------------------------------
    add("json", "cases --json (legit)", "cases --json", exit=0, json_out=True)
    add("json", "cases kundur --bus-table --line-table --json (legit)",
        "cases kundur --bus-table --line-table --json", exit=0, json_out=True)  # fmt: skip
    add("json", "cct --json above --t-max (legit)", f"{CCT} --t-max 0.1 --json", exit=0,
        json_out=True)  # fmt: skip
    add("json", "cct --json N-1 insecure-ish (legit)",
        "cct kundur --fault 3 --far-bus 101 --t-fault 1 --clear-cycles 1 --json"
        if False else f"{CCT} --json --esd-pct 5", exit=0, json_out=True)  # fmt: skip
    add("json", "simulate --json unstable run (legit)",
        f"{SIM} --clear-cycles 30 --json", exit=0, json_out=True)  # fmt: skip
    add("paper", "paper --out-dir afile.txt", "paper --out-dir afile.txt --only analytic",
        needle="afile.txt", max_s=4.0)  # fmt: skip
    add("paper", "paper --out-dir ro", "paper --out-dir ro --only analytic", needle="ro",
        max_s=4.0)  # fmt: skip
    add("paper", "paper --resume with no earlier run", "paper --out-dir newdir --resume "
        "--only analytic", exit=0)  # fmt: skip
    # --- sizes: sparse huge files under a 2.5 GB address-space limit -------------------
    big = cwd / "big.bin"
    with big.open("wb") as f:
        f.truncate(3 << 30)
    for args, needle in (
        (f"{PLACE} --target-cct-gain 5 --screening big.bin", "big.bin"),
        (f"{PLACE} --target-cct-gain 5 --site-costs big.bin", "big.bin"),
        (f"{SWEEP} --out big.bin", "big.bin"),
        ("screen kundur --buses 3 --out big.bin", "big.bin"),
        ("import-psse five.raw big.bin -o p.json", "big.bin"),
        ("import-andes big.bin -o a.json", "big.bin"),
        ("estimate track kundur --source big.bin --out t.csv", "big.bin"),
        ("pmu replay big.bin --port 0 --timeout 1", "big.bin"),
    ):
        add("size", f"{args.split()[0]} ... {needle} (3 GiB sparse)", args, needle=needle,
            limit_as=True, unchanged="")  # fmt: skip
    return out


# --- special probes: interrupts and resumes ----------------------------------------------


def _valid_jsonl(path: Path) -> tuple[bool, int, int, str]:
    """(all lines valid, count, distinct keys, message)."""
    if not path.exists():
        return True, 0, 0, "no file"
    text = path.read_text()
    if text and not text.endswith("\n"):
        return False, 0, 0, "last line without newline (cut)"
    keys = []
    for i, line in enumerate(text.splitlines(), 1):
        try:
            keys.append(strict_json(line)["key"])
        except (ValueError, KeyError, TypeError) as e:
            return False, 0, 0, f"line {i} invalid: {e}"
    return True, len(keys), len(set(keys)), "ok"


def interrupt_probe(cwd, finding, what, args, sig, when, out, kind, want_count=None):
    """Send `sig` at `when` (seconds or 'first' = after the first record); the run must end
    non-zero without a traceback, the file valid (JSONL: every line whole; JSON: absent or
    whole), no lock or temp file left; a JSONL run resumed to the end gives `want_count`
    distinct records."""
    p = P4(finding, what, cli(args), exit=128 + sig)
    rows = []
    sub = cwd / f"int_{len(list(cwd.glob('int_*')))}"
    sub.mkdir()
    for f in ("f.csv",):
        shutil.copy(cwd / f, sub / f)
    proc = subprocess.Popen(
        STABCTL + p.args,
        cwd=sub,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    t0 = time.monotonic()
    if when == "first":
        while time.monotonic() - t0 < 60:
            if (sub / out).exists() and (sub / out).read_text().count("\n"):
                break
            if proc.poll() is not None:
                break
            time.sleep(0.05)
    else:
        time.sleep(when)
    if proc.poll() is not None:
        stdout, stderr = proc.communicate()
        res = subprocess.CompletedProcess(p.args, proc.returncode, stdout, stderr)
        v = f"ended before the signal (exit {proc.returncode})"
        log_short(p, v, res)
        return [(p, v)]
    proc.send_signal(sig)
    if kind == "double":
        time.sleep(0.3)
        proc.send_signal(sig)
    t1 = time.monotonic()
    try:
        stdout, stderr = proc.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        proc.kill()
        stdout, stderr = proc.communicate()
        v = "did not end within 30 s of the signal"
        log_short(p, v, subprocess.CompletedProcess(p.args, -9, stdout, stderr))
        return [(p, v)]
    res = subprocess.CompletedProcess(p.args, proc.returncode, stdout, stderr)
    v = "ok"
    if proc.returncode == 0:
        v = "exit 0 after the signal"
    elif "Traceback" in stderr:
        v = "traceback"
    elif proc.returncode != 128 + sig and proc.returncode != -sig:
        v = f"exit {proc.returncode}, want {128 + sig}"
    elif sum(x.startswith("error:") for x in stderr.splitlines()) > 1:
        v = "more than one error line"
    elif time.monotonic() - t1 > 10:
        v = f"took {time.monotonic() - t1:.0f} s to stop"
    leftovers = [
        x.name for x in sub.iterdir() if x.name.startswith(".") or x.name.endswith((".tmp",))
    ]
    if v == "ok" and leftovers:
        v = f"left behind: {leftovers}"
    if v == "ok" and kind in ("jsonl", "double"):
        ok, n, distinct, msg = _valid_jsonl(sub / out)
        if not ok:
            v = f"{out}: {msg}"
    if v == "ok" and kind == "json" and (sub / out).exists():
        try:
            strict_json((sub / out).read_text())
            v = f"{out} written though interrupted"
        except ValueError as e:
            v = f"{out} partial: {e}"
    if v != "ok":
        log_short(p, v, res, f"files: {sorted(x.name for x in sub.iterdir())}")
    rows.append((p, v))
    if kind in ("jsonl", "double") and want_count:
        p2 = P4(finding, f"{what}: resumed to the end", p.args, exit=0)
        try:
            res2 = run4(p2.args, sub, timeout=180)
            v2 = verdict(p2, res2, sub)
            ok, n, distinct, msg = _valid_jsonl(sub / out)
            if v2 == "ok" and not ok:
                v2 = f"{out}: {msg}"
            elif v2 == "ok" and (n != want_count or distinct != n):
                v2 = f"{n} records ({distinct} distinct), want {want_count}"
            if v2 != "ok":
                log_short(p2, v2, res2)
        except subprocess.TimeoutExpired:
            v2 = "resume hung"
        rows.append((p2, v2))
    return rows


def truncated_resume_probe(cwd, what, args, out, want_count):
    """A finished sweep's records file with its last line cut in half: the rerun must
    neither crash nor keep the cut line, and end with every job recorded once (or refuse
    with exit 2 naming the file and line)."""
    sub = cwd / f"trunc_{out.replace('.', '_')}"
    sub.mkdir()
    shutil.copy(cwd / "f.csv", sub / "f.csv")
    p = P4("resume", what, cli(args), exit=0)
    first = run4(p.args, sub, timeout=180)
    if first.returncode != 0:
        log_short(p, "first run failed", first)
        return [(p, f"first run exit {first.returncode}")]
    text = (sub / out).read_text()
    lines = text.splitlines(keepends=True)
    cut = "".join(lines[:-1]) + lines[-1][: len(lines[-1]) // 2]
    (sub / out).write_text(cut)
    res = run4(p.args, sub, timeout=180)
    if res.returncode == 2:
        v = verdict(P4("", "", [], exit=2, needle=f"{out}:"), res, sub)
        v = "ok (refused)" if v == "ok" else v
        v = "ok" if v.startswith("ok") else v
    else:
        v = verdict(p, res, sub)
        ok, n, distinct, msg = _valid_jsonl(sub / out)
        if v == "ok" and not ok:
            v = f"{out}: {msg}"
        elif v == "ok" and (n != want_count or distinct != n):
            v = f"{n} records ({distinct} distinct), want {want_count}"
        elif v == "ok" and "warning" not in (res.stderr + res.stdout).lower():
            v = "cut line dropped without a word"
    if v != "ok":
        log_short(p, v, res, f"tail of file: {(sub / out).read_text()[-200:]!r}")
    return [(p, v)]


def changed_options_resume_probe(cwd, what, first_args, second_args, out, needle):
    """Resume of records made under other options (--t-max, --tol-ms): the records must not
    be reused silently as results of the new options."""
    sub = cwd / f"chg_{len(list(cwd.glob('chg_*')))}"
    sub.mkdir()
    shutil.copy(cwd / "f.csv", sub / "f.csv")
    p = P4("resume", what, cli(second_args), exit=0)
    first = run4(cli(first_args), sub, timeout=180)
    if first.returncode != 0:
        log_short(p, "first run failed", first)
        return [(p, f"first run exit {first.returncode}")]
    res = run4(p.args, sub, timeout=180)
    text = res.stdout + res.stderr
    if "Traceback" in res.stderr:
        v = "traceback"
    elif res.returncode == 2:
        v = "ok" if needle in text else f"refused without naming {needle}"
    elif (
        res.returncode == 0
        and "already in" in text
        and not any(
            w in text.lower()
            for w in ("other option", "other inputs", "different", "warning", "mismatch")
        )
    ):
        # the skipped count: "N run now, M already in"
        import re

        m = re.search(r"(\d+) run now, (\d+) already in", text)
        if m and int(m.group(2)) > 0:
            v = f"reused {m.group(2)} records of other options without a word"
        else:
            v = "ok"
    else:
        v = "ok" if res.returncode == 0 else f"exit {res.returncode}"
    if v != "ok":
        log_short(p, v, res, f"first: stabctl {first_args}")
    return [(p, v)]


def broken_pipe_probes(cwd: Path) -> list:
    """`... --json | head -1`: no error line, no traceback (round 3 had cases and eig)."""
    rows = []
    for args in (
        f"{CCT} --json",
        f"{SIM} --json",
        "screen kundur --buses 3,13 --workers 1 --out bp.jsonl --json",
        "sweep-cct kundur --faults DEFAULT --workers 1 --out bp2.jsonl --json",
        "omib --json",
        "cases kundur --bus-table",
        f"{RMSE} --json",
    ):
        p = P4("pipe", f"{args.split(' --')[0]} ... | head -1", cli(args), exit=0)
        proc = subprocess.Popen(STABCTL + p.args, cwd=cwd, stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE)  # fmt: skip
        proc.stdout.readline()
        proc.stdout.close()
        try:
            err = proc.stderr.read().decode()
            proc.wait(timeout=60)
            bad = [x for x in err.splitlines() if x.startswith("error") or "Traceback" in x]
            v = "ok" if not bad else bad[0][:100]
            if v == "ok" and proc.returncode not in (0, 141, -13):
                v = f"exit {proc.returncode}"
        except subprocess.TimeoutExpired:
            proc.kill()
            err, v = "", "hang after the pipe closed"
        if v != "ok":
            log_short(p, v, subprocess.CompletedProcess(p.args, proc.returncode, "", err))
        rows.append((p, v))
    for f in ("bp.jsonl", "bp2.jsonl"):
        (cwd / f).unlink(missing_ok=True)
    return rows


def full_stdout_probes(cwd: Path) -> list:
    """stdout on a full disk (/dev/full): a non-zero exit and one error line, no traceback."""
    rows = []
    for args in (f"{CCT} --json", "cases --json", "omib", "eig kundur"):
        p = P4("full", f"{args} > /dev/full", cli(args), exit=1)
        with open("/dev/full", "w") as full:
            res = subprocess.run(STABCTL + p.args, cwd=cwd, stdout=full, stderr=subprocess.PIPE,
                                 text=True, timeout=TIMEOUT)  # fmt: skip
        n_err = sum(x.startswith("error:") for x in res.stderr.splitlines())
        if res.returncode == 0:
            v = "exit 0: the output was lost without a word"
        elif "Traceback" in res.stderr:
            v = "traceback"
        elif n_err != 1:
            v = f"{n_err} error lines"
        else:
            v = "ok"
        if v != "ok":
            log_short(p, v, subprocess.CompletedProcess(p.args, res.returncode, "", res.stderr))
        rows.append((p, v))
    return rows


def specials(cwd: Path) -> list:
    rows = broken_pipe_probes(cwd) + full_stdout_probes(cwd)
    screen = "screen kundur --lines --tol-ms 0.05 --workers 1 --out s.jsonl"
    n_screen = 13 + 14  # buses + branch from-ends (checked against a clean run below)
    clean = run4(cli(screen.replace("s.jsonl", "clean.jsonl")), cwd, timeout=300)
    if clean.returncode == 0:
        n_screen = _valid_jsonl(cwd / "clean.jsonl")[1]
    sweep = "sweep-cct kundur --faults DEFAULT --esd-pct none,5,10 --tol-ms 0.05 " \
        "--workers 1 --out w.jsonl"  # fmt: skip
    rows += interrupt_probe(cwd, "int", "SIGINT of screen at 2 s", screen, signal.SIGINT, 2.0,
                            "s.jsonl", "jsonl", n_screen)  # fmt: skip
    rows += interrupt_probe(cwd, "int", "SIGINT of screen after its first record", screen,
                            signal.SIGINT, "first", "s.jsonl", "jsonl", n_screen)  # fmt: skip
    rows += interrupt_probe(cwd, "int", "double SIGINT of screen", screen, signal.SIGINT,
                            "first", "s.jsonl", "double", n_screen)  # fmt: skip
    rows += interrupt_probe(cwd, "int", "SIGTERM of screen at 2 s", screen, signal.SIGTERM,
                            2.0, "s.jsonl", "jsonl", n_screen)  # fmt: skip
    rows += interrupt_probe(cwd, "int", "SIGINT of sweep-cct after its first record", sweep,
                            signal.SIGINT, "first", "w.jsonl", "jsonl", 6)  # fmt: skip
    rows += interrupt_probe(cwd, "int", "SIGHUP of sweep-cct after its first record", sweep,
                            signal.SIGHUP, "first", "w.jsonl", "jsonl", 6)  # fmt: skip
    place = "place kundur --faults DEFAULT --target-cct-gain 5 --tol-ms 0.2 --workers 1 " \
        "--out p.json"  # fmt: skip
    rows += interrupt_probe(cwd, "int", "SIGTERM of place --out at 2 s", place,
                            signal.SIGTERM, 3.0, "p.json", "json")  # fmt: skip
    rows += interrupt_probe(cwd, "int", "SIGINT of place --out at 3 s", place, signal.SIGINT,
                            3.0, "p.json", "json")  # fmt: skip
    rows += interrupt_probe(cwd, "int", "SIGINT of simulate --out (long run)",
                            "simulate kundur --fault 3 --far-bus 101 --tf 600 --out x.csv",
                            signal.SIGINT, 2.5, "x.csv", "json")  # fmt: skip
    rows += truncated_resume_probe(cwd, "sweep-cct resume, last line cut",
                                   "sweep-cct kundur --faults DEFAULT --esd-pct none,5 "
                                   "--workers 1 --out w.jsonl", "w.jsonl", 4)  # fmt: skip
    rows += truncated_resume_probe(
        cwd,
        "screen resume, last line cut",
        "screen kundur --workers 1 --out s.jsonl",
        "s.jsonl",
        13,
    )
    rows += changed_options_resume_probe(
        cwd,
        "screen resume under another --t-max",
        "screen kundur --workers 1 --t-max 0.5 --out s.jsonl",
        "screen kundur --workers 1 --t-max 0.3 --out s.jsonl",
        "s.jsonl",
        "t_max",
    )
    rows += changed_options_resume_probe(
        cwd, "sweep-cct resume under another --tol-ms",
        "sweep-cct kundur --faults DEFAULT --workers 1 --tol-ms 1 --out w.jsonl",
        "sweep-cct kundur --faults DEFAULT --workers 1 --tol-ms 20 --out w.jsonl", "w.jsonl",
        "tol")  # fmt: skip
    rows += changed_options_resume_probe(
        cwd, "sweep-cct resume under other --conventions",
        "sweep-cct kundur --faults DEFAULT --workers 1 --out w.jsonl",
        "sweep-cct kundur --faults DEFAULT --workers 1 --conventions pstess --out w.jsonl",
        "w.jsonl", "--conventions")  # fmt: skip
    rows += changed_options_resume_probe(
        cwd, "place --screening of another --t-max / case",
        "screen kundur --workers 1 --buses 3 --t-max 0.1 --out s.jsonl",
        "place kundur --faults DEFAULT --target-cct-gain 5 --workers 1 --screening s.jsonl",
        "s.jsonl", "s.jsonl")  # fmt: skip
    return rows


def main() -> int:
    sel = sys.argv[sys.argv.index("-k") + 1] if "-k" in sys.argv else ""
    if WORK.exists():
        subprocess.run(["chattr", "-R", "-i", "-a", str(WORK)], check=False,
                       stderr=subprocess.DEVNULL)  # fmt: skip
        shutil.rmtree(WORK)
    WORK.mkdir(parents=True)
    SHORTS.write_text("")
    cwd = WORK
    rows = []
    try:
        prepare(cwd)
        for f in cwd.rglob("*"):
            if f.is_file() and not f.is_symlink() and f.stat().st_size < 64 << 20:
                PRISTINE[str(f.relative_to(cwd))] = f.read_bytes()
        for p in probes(cwd):
            if sel and sel not in p.what:
                continue
            t0 = time.perf_counter()
            v = judge(p, cwd)
            rows.append((p, v))
            if "-v" in sys.argv:
                print(f"{time.perf_counter() - t0:6.1f} s  {p.what}: {v}", flush=True)
        if not sel or sel == "special":
            rows += specials(cwd)
    finally:
        for name in ("ro", "imm.csv", "imm.json", "imm.jsonl", "app.csv", "app.json", "app.jsonl"):
            subprocess.run(
                ["chattr", "-i", "-a", str(cwd / name)], check=False, stderr=subprocess.DEVNULL
            )
        (cwd / "big.bin").unlink(missing_ok=True)
    status = table(rows)
    if status == 0:
        shutil.rmtree(WORK, ignore_errors=True)
        SHORTS.unlink(missing_ok=True)
    else:
        print(f"work directory {WORK}; the short probes' output in {SHORTS}")
    return status


if __name__ == "__main__":
    sys.exit(main())
