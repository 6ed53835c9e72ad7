"""Hostile inputs and faults, tried as a new user would: does each end as it should?

Each probe runs one `stabctl` command (in a fresh process, as a user types it) on a bad
input or under a fault and states what a careful tool does: exit status 2 with one
``error:`` line naming what and where (no traceback) and no output file, or, for a
legitimate run, exit 0.  The probes follow the findings of the second reliability round
(locked outputs, strict readers, special files, full disks, foreign servers, signals).

    python benchmarks/reliability_probes.py          # the table and the ok / short counts

Exit status 1 if any probe is short.
"""

from __future__ import annotations

import json
import os
import signal
import stat
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

STABCTL = [sys.executable, "-m", "stabctl.cli"]
ROOT = Path(__file__).resolve().parents[1]
PSSE = ROOT / "tests" / "data" / "psse"

sys.path.insert(0, str(ROOT / "tests"))
from pmu_streams import fake_server  # noqa: E402  (shared with tests/cli)


@dataclass
class Probe:
    finding: str
    what: str
    args: list
    exit: int | dict = 2  # a status, or {status: needle} (`verdict`)
    needle: str = ""  # text the stderr (or stdout) must hold
    no_file: str = ""  # a path that must not exist afterwards


def cli(text: str) -> list[str]:
    """A command's arguments as typed (no quoting needed in these probes)."""
    return text.split()


def run(args, cwd, timeout=600, **popen):
    """One stabctl command in ``cwd`` (``popen``: more `subprocess.run` arguments)."""
    return subprocess.run(
        STABCTL + [str(a) for a in args],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=timeout,
        **popen,
    )


def verdict(p: Probe, res, cwd: Path) -> str:
    """'ok' or what is short.  A probe whose outcome may be either of two honest ones (a
    run that ends in a warning on one machine's libm and diverges with its error on
    another's) gives `exit` as {status: needle} instead of a status and a needle."""
    err = res.stderr
    wanted = p.exit if isinstance(p.exit, dict) else {p.exit: p.needle}
    if res.returncode not in wanted:
        return f"exit {res.returncode}, want {' or '.join(map(str, wanted))}: {err.strip()[-120:]}"
    needle = wanted[res.returncode]
    if "Traceback" in err:
        return "traceback"
    if res.returncode == 2 and sum(line.startswith("error:") for line in err.splitlines()) != 1:
        return "not one error line"
    if needle and needle not in err + res.stdout:
        return f"no '{needle}' in {err.strip()[-120:]!r}"
    if p.no_file and (cwd / p.no_file).exists():
        return f"{p.no_file} written"
    return "ok"


def write(cwd: Path, name: str, text: str, encoding="utf-8") -> Path:
    path = cwd / name
    path.write_bytes(text.encode(encoding))
    return path


def case_file(cwd: Path, name: str, table: str, field: str, value) -> Path:
    from stabctl.io import load_case
    from stabctl.io.pst import case_to_dict

    d = case_to_dict(load_case("kundur"))
    t = d["tables"][table]
    t["rows"][0][t["columns"].index(field)] = value
    return write(cwd, name, json.dumps(d))


def andes_file(cwd: Path, name: str, edit) -> Path:
    import andes

    d = json.loads(Path(andes.get_case("ieee14/ieee14.json")).read_text())
    edit(d)
    return write(cwd, name, json.dumps(d))


def probes(cwd: Path) -> list[Probe]:
    faults = "bus,far_bus\n3,101\n"
    csv_rows = {
        "cut.csv": "bus,far_bus,t_fault\n3,101,1.0\n3\n",
        "dup_header.csv": "bus,far_bus,bus\n3,101,4\n",
        "extra.csv": "bus,far_bus\n3,101,1.0\n",
        "nan.csv": "bus,far_bus,t_fault\n3,101,nan\n",
        "inf.csv": "bus,far_bus,t_fault\n3,101,inf\n",
        "huge.csv": "bus,far_bus,t_fault\n3,101,1e300\n",
        "late.csv": "bus,far_bus,t_fault\n3,101,2000\n",
    }
    out = []
    for name, text in csv_rows.items():
        write(cwd, name, text)
        out.append(
            Probe(
                "4",
                f"fault CSV {name}",
                ["sweep-cct", "kundur", "--faults", name, "--out", "o.jsonl"],
                no_file="o.jsonl",
            )
        )
    write(cwd, "latin1.csv", "bus,far_bus\n3,101 \u00e9\n", "latin-1")
    write(cwd, "long.csv", 'bus,far_bus\n3,"' + "1" * 200_000 + '"\n')
    for name in ("latin1.csv", "long.csv"):
        out.append(
            Probe(
                "12",
                f"fault CSV {name}",
                ["sweep-cct", "kundur", "--faults", name, "--out", "o.jsonl"],
                no_file="o.jsonl",
            )
        )
    write(cwd, "f.csv", faults)
    place = ["place", "kundur", "--faults", "DEFAULT", "--target-cct-gain", "5", "--workers", "1"]
    write(cwd, "misspelt.csv", "bus,far_bus,required_clearing_cycle\n3,101,6\n")
    out.append(
        Probe(
            "5",
            "place: misspelt requirement column",
            ["place", "kundur", "--faults", "misspelt.csv", "--target-cct-gain", "5"],
            needle="'required_clearing_cycle' unknown",
        )
    )
    for name, text, needle in (
        ("costs_misspelt.csv", "machine,cost_mv\n1,5\n", "'cost_mv' unknown"),
        ("costs_m0.csv", "machine,cost_mw\n0,5\n", "machine 0 is outside"),
        ("costs_m99.csv", "machine,cost_mw\n99,5\n", "machine 99 is outside"),
        ("costs_dup.csv", "machine,cost_mw\n2,5\n2,6\n", "machine 2 listed twice"),
        ("costs_none.csv", "machine\n1\n", "no cost column"),
    ):
        write(cwd, name, text)
        out.append(
            Probe("5", f"place --site-costs {name}", [*place, "--site-costs", name], needle=needle)
        )
    write(cwd, "not_screening.jsonl", '{"key": "k", "status": "ok", "inputs": {}, "result": {}}\n')
    out.append(
        Probe(
            "5",
            "place --screening of other records",
            [*place, "--screening", "not_screening.jsonl"],
            needle="the records must be whole",
        )
    )
    for name, table, field, value, needle in (
        ("h_true.json", "machines", "H", True, "true is not a number"),
        ("xd.json", "machines", "xd", 0.2, "x_d must be >= x'd"),
        ("q.json", "buses", "qmin", 99.0, "qmax must be >= qmin"),
        ("v.json", "buses", "vmin", 1.6, "vmax must be >= vmin"),
    ):
        case_file(cwd, name, table, field, value)
        out.append(Probe("6", f"case {name}", ["simulate", name, "--tf", "1"], needle=needle))
    out += [
        Probe(
            "7",
            "--window-cycles 1e6",
            cli("estimate rmse kundur --fault 3 --far-bus 101 --window-cycles 1e6"),
            needle="--window-cycles",
        ),
        Probe(
            "7",
            "trip of a circuit the fault opens",
            cli("simulate kundur --fault 3 --far-bus 101 --trip 3 101 --t-trip 2 --tf 3"),
            needle="tripped twice",
        ),
    ]
    write(cwd, "cut.c37", "\xaa\x31\x00\x64" + "x" * 16, "latin-1")  # 100 bytes said, 20 there
    out += [
        Probe(
            "C37",
            "estimate rmse --source at no server",
            cli("estimate rmse kundur --fault 3 --far-bus 101 --source tcp://127.0.0.1:1"),
            needle="no C37.118.2 server at 127.0.0.1:1",
        ),
        Probe(
            "C37",
            "estimate track of a recording cut short",
            cli("estimate track kundur --source cut.c37 --out t.csv"),
            needle="cut short",
            no_file="t.csv",
        ),
        Probe(
            "C37",
            "pmu control with no plant",
            cli("pmu control kundur 127.0.0.1:1 --esd-pct 5"),
            needle="no plant at 127.0.0.1:1",
        ),
    ]
    link = cwd / "full.jsonl"
    link.symlink_to("/dev/full")
    zero = cwd / "zero.json"
    zero.symlink_to("/dev/zero")
    (cwd / "zero.jsonl").symlink_to("/dev/zero")  # the suffix right: the file refused
    out += [
        Probe(
            "8",
            "--out /dev/zero",
            ["sweep-cct", "kundur", "--faults", "f.csv", "--out", "/dev/zero"],
            needle="the file name must end in .jsonl",
        ),
        Probe(
            "8",
            "--out link to /dev/zero",
            ["sweep-cct", "kundur", "--faults", "f.csv", "--out", "zero.jsonl"],
            needle="not a regular file",
        ),
        Probe(
            "8",
            "--out link to /dev/full",
            ["sweep-cct", "kundur", "--faults", "f.csv", "--out", "full.jsonl"],
            needle="not a regular file",
        ),
        Probe(
            "8",
            "--faults /dev/zero",
            ["sweep-cct", "kundur", "--faults", "/dev/zero", "--out", "o.jsonl"],
            needle="not a regular file",
            no_file="o.jsonl",
        ),
        Probe(
            "8",
            "--screening /dev/urandom",
            [*place, "--screening", "/dev/urandom"],
            needle="not a regular file",
        ),
        Probe(
            "8",
            "case link to /dev/zero",
            ["simulate", "zero.json", "--tf", "1"],
            needle="not a regular file",
        ),
    ]
    for address in ("tls://127.0.0.1:8786", "ucx://127.0.0.1:8786", "tcp://127.0.0.1:99999"):
        out.append(
            Probe(
                "10",
                f"--scheduler {address}",
                _sweep_with_scheduler(address),
                needle="tcp://host:port",
                no_file="o.jsonl",
            )
        )
    out += [
        Probe(
            "11",
            "--drop 0.999",
            cli("estimate rmse kundur --fault 3 --far-bus 101 --drop 0.999")
            + cli("--runs 2 --ambient-s 0 --tf 3"),
            exit=0,
            needle="-: no error to take",
        ),
        Probe("11", "--cost-mw 1e308", [*place, "--cost-mw", "1e308"], needle="--cost-mw"),
        Probe("11", "--cost-site -1", [*place, "--cost-site", "-1"], needle="--cost-site"),
        Probe("11", "--cost-mw 1e9 (legitimate)", [*place, "--cost-mw", "1e9"], exit=0),
    ]
    lines = (PSSE / "five_bus.dyr").read_text().splitlines()
    write(cwd, "joined.dyr", "\n".join([lines[0] + lines[1], *lines[2:]]) + "\n")
    out.append(
        Probe(
            "3",
            "DYR record after '/' on a line",
            ["import-psse", PSSE / "five_bus_v33.raw", "joined.dyr", "-o", "j.json"],
            needle="after '/' would be a comment",
        )
    )
    try:
        import andes  # noqa: F401
    except ImportError:
        return out
    for name, edit, needle in (
        ("x_nan.json", lambda d: d["Line"][2].update(x=float("nan")), "x missing"),
        ("m_missing.json", lambda d: d["GENROU"][0].pop("M"), "M missing"),
        (
            "dup_gen.json",
            lambda d: d["GENROU"].append(dict(d["GENROU"][0], idx="GENROU_9", name="GENROU_9")),
            "a duplicated record",
        ),
    ):
        andes_file(cwd, name, edit)
        out.append(
            Probe(
                "2",
                f"import-andes {name}",
                ["import-andes", name, "-o", "a.json", "--skip-unsupported"],
                needle=needle,
                no_file="a.json",
            )
        )
    return out


def _sweep_with_scheduler(address: str) -> list[str]:
    """The sweep the scheduler probes run, on the Dask scheduler at ``address``."""
    return cli(f"sweep-cct kundur --faults f.csv --out o.jsonl --scheduler {address}")


def foreign_server_probe(cwd: Path) -> tuple[Probe, str]:
    """A web server where the Dask scheduler should be."""
    return _web_server_probe(
        cwd,
        "10",
        "--scheduler at a web server",
        lambda address: _sweep_with_scheduler(f"tcp://{address}"),
        "no Dask scheduler answers",
        "o.jsonl",
    )


def foreign_pmu_probe(cwd: Path) -> tuple[Probe, str]:
    """A web server where a C37.118.2 PMU stream should be."""
    return _web_server_probe(
        cwd,
        "C37",
        "estimate rmse --source at a web server",
        lambda address: cli(
            f"estimate rmse kundur --fault 3 --far-bus 101 --source tcp://{address}"
        ),
        "does not speak C37.118.2",
        "",
    )


def _web_server_probe(cwd: Path, finding, what, args_of, needle, no_file) -> tuple[Probe, str]:
    """A command pointed at a web server (which answers anything with a page): it must
    say so within a minute, not hang."""
    server, port = fake_server(
        lambda conn: conn.sendall(b"HTTP/1.1 200 OK\r\nContent-Length: 2\r\n\r\nhi" * 50),
        answer_all=True,
    )
    p = Probe(finding, what, args_of(f"127.0.0.1:{port}"), needle=needle, no_file=no_file)
    t0 = time.perf_counter()
    res = run(p.args, cwd)
    server.close()
    v = verdict(p, res, cwd)
    return p, v if time.perf_counter() - t0 < 60 else f"took {time.perf_counter() - t0:.0f} s"


def lock_probe(cwd: Path) -> tuple[Probe, str]:
    """A second sweep on a file a running sweep writes."""
    p = Probe(
        "1",
        "second sweep on a file being written",
        cli("sweep-cct miniwecc --faults DEFAULT --esd-pct none,5 --workers 1 --out busy.jsonl"),
        needle="is writing it",
    )
    first = subprocess.Popen(
        STABCTL + [str(a) for a in p.args],
        cwd=cwd,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    lock = cwd / ".busy.jsonl.lock"
    deadline = time.monotonic() + 300
    while not lock.exists() and time.monotonic() < deadline:
        time.sleep(0.1)
    try:
        return p, verdict(p, run(p.args, cwd), cwd)
    finally:
        first.kill()
        first.wait()


def sigterm_probe(cwd: Path) -> tuple[Probe, str]:
    """SIGTERM of a screening on two workers: the resume line and exit 143."""
    p = Probe(
        "13",
        "SIGTERM of a sweep",
        ["screen", "kundur", "--tol-ms", "0.05", "--workers", "2", "--out", "t.jsonl"],
        exit=143,
        needle="resume with: stabctl screen",
    )
    proc = subprocess.Popen(
        STABCTL + p.args, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    out = cwd / "t.jsonl"
    deadline = time.monotonic() + 300
    while not (out.exists() and out.read_text().count("\n")) and time.monotonic() < deadline:
        time.sleep(0.1)
    proc.send_signal(signal.SIGTERM)
    stdout, stderr = proc.communicate(timeout=60)
    res = subprocess.CompletedProcess(p.args, proc.returncode, stdout, stderr)
    v = verdict(p, res, cwd)
    if v == "ok" and "leaked" in stderr:
        v = "leaked semaphore"
    return p, v


def umask_probe(cwd: Path) -> tuple[Probe, str]:
    """A file written whole gets the mode of the user's umask."""
    p = Probe(
        "13",
        "import-psse output mode under umask 022",
        [
            "import-psse",
            PSSE / "five_bus_v33.raw",
            PSSE / "five_bus.dyr",
            "-o",
            "five.json",
            "--skip-unsupported",
        ],
        exit=0,
    )
    old = os.umask(0o022)
    try:
        res = run(p.args, cwd)
    finally:
        os.umask(old)
    v = verdict(p, res, cwd)
    mode = stat.S_IMODE((cwd / "five.json").stat().st_mode) if v == "ok" else 0
    return p, v if v != "ok" or mode == 0o644 else f"mode {mode:o}"


def main() -> int:
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        cwd = Path(tmp)
        for p in probes(cwd):
            res = run(p.args, cwd)
            rows.append((p, verdict(p, res, cwd)))
            (cwd / "o.jsonl").unlink(missing_ok=True)
        for special in (
            foreign_server_probe,
            foreign_pmu_probe,
            lock_probe,
            sigterm_probe,
            umask_probe,
        ):
            rows.append(special(cwd))
    return table(rows)


def table(rows) -> int:
    """Print the probes' verdicts and the ok / short counts; 1 if any probe is short."""
    width = max(len(p.what) for p, _ in rows)
    print(f"{'finding':>7}  {'probe':<{width}}  verdict")
    for p, v in rows:
        print(f"{p.finding:>7}  {p.what:<{width}}  {v}")
    short = sum(v != "ok" for _, v in rows)
    print(f"\n{len(rows) - short} ok, {short} short of {len(rows)} probes")
    return 1 if short else 0


if __name__ == "__main__":
    sys.exit(main())
