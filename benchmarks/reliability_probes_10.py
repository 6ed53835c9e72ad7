"""Tenth reliability round (round 35, part C): storage control, estimation and the PMU
streams on grids the developers did not study.

ANDES's IEEE 14 (with and without its storage device) and IEEE 39 imported with
import-andes, PSS/E's ThreeBusMulti with GENROU (an infinite bus) with import-psse, IEEE 14
made a 50 Hz case and renumbered with large, gapped bus numbers (odd n -> 900000 + 1000 n,
even n -> 10 n), and islanding faults (Kundur 10-1 islands G1, IEEE 14 7-8 islands G4): the
storage law checked switching by switching against the result file (voltage gate,
deadband, relative speed at the case's f0, an ideal device's power), estimate rmse, cct,
closed-loop and track, pmu serve / record / replay / plant / control, cct and sweep-cct
with storage.

Contract: each probe runs `stabctl` commands (or python -c with the library) in fresh
processes (the package of this repository first on PYTHONPATH), servers in their own
session under a timeout, and states what a careful tool does: the law's switchings agree
with the recorded speeds and voltages on any frequency and numbering; renumbered buses give
the same figures; a stream read over TCP, from a file or replayed gives the same track; a
refused input ends with exit status 2 and an ``error:`` line, no traceback.  The round
found p06 (estimate track took --v-gate and did nothing with it), p07 (pmu control, the
same), p08 (a WECC battery's converter columns named nowhere), p09 (the npz inertia
labelled H * MVA where an infinite bus makes it 1 / 0) and p17 (estimate closed-loop
counted 'switchings' a voltage gate held idle) short; they are resolved by design and the
probes now check the resolution: estimate track and pmu control refuse --v-gate, the npz
labels inertia a COI weight, closed-loop rows give ``mode_commands`` (commands sent).

    python benchmarks/reliability_probes_10.py [-k SUBSTRING] [ID ...]

ID: a probe's name or its prefix before the first ``_`` (``p06``); p00 imports the cases,
which any probe run alone makes first.  p01, p03 and p12 report one line per case or
option.  One line per probe (name, ok or SHORT, why), then the counts.  Needs Linux, the
``andes`` package (its case files), the ``timeout`` command and PSS/E's ThreeBus of
tests/data/psse_runs/GENROU.  NUMBA_CACHE_DIR is the caller's (numba's default when
unset); `stabctl compile` is run first (seconds with a warm cache, about a minute cold).
The work directory is a new temporary directory, removed at the end unless KEEP is set.
About 3-5 minutes on two cores with a warm kernel cache.  Exit status 1 if any probe is
short.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]  # the package under test
STABCTL = [sys.executable, "-m", "stabctl"]
ENV = dict(
    os.environ,
    PYTHONPATH=os.pathsep.join([str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])]),
)
ENV.pop("PYTHONWARNINGS", None)
THREEBUS = ROOT / "tests" / "data" / "psse_runs" / "GENROU"  # PSS/E's ThreeBusMulti, GENROU
WORK = Path(tempfile.mkdtemp(prefix="stabctl-probes-10."))
RESULTS: list[tuple[str, bool, str]] = []
PROBES: list = []
SERVERS: list[subprocess.Popen] = []
CASES: dict[str, str] = {}


def probe(fn):
    PROBES.append(fn)
    return fn


def report(pid, ok, why):
    RESULTS.append((pid, ok, why))
    print(f"{pid:<34} {'ok   ' if ok else 'SHORT'} {why}", flush=True)


def run(args, timeout=300):
    """(rc, stdout, stderr) of `stabctl args` in the work directory; rc 124 on timeout."""
    try:
        p = subprocess.run(
            [*STABCTL, *map(str, args)],
            cwd=WORK,
            env=ENV,
            capture_output=True,
            text=True,
            timeout=timeout,
            stdin=subprocess.DEVNULL,
        )
    except subprocess.TimeoutExpired as e:
        out = e.stdout.decode(errors="replace") if isinstance(e.stdout, bytes) else ""
        return 124, out, f"TIMEOUT after {timeout} s"
    return p.returncode, p.stdout, p.stderr


def pyrun(code, timeout=300):
    """The last stdout line of python -c code, parsed as JSON (RuntimeError if it fails)."""
    p = subprocess.run(
        [sys.executable, "-c", code],
        cwd=WORK,
        env=ENV,
        capture_output=True,
        text=True,
        timeout=timeout,
        stdin=subprocess.DEVNULL,
    )
    if p.returncode:
        raise RuntimeError(p.stderr[-400:])
    return json.loads(p.stdout.strip().splitlines()[-1])


def clean_error(rc, out, err):
    """The contract's shape of a refusal: exit 2, an `error:` line, no traceback."""
    text = out + err
    return rc == 2 and "error:" in text and "Traceback" not in text


def andes_cases() -> Path:
    import andes  # only to find ANDES's case files

    return Path(andes.__file__).parent / "cases"


# ---------------------------------------------------------------- servers


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _default_signals():
    for s in (signal.SIGINT, signal.SIGHUP, signal.SIGTERM, signal.SIGQUIT):
        signal.signal(s, signal.SIG_DFL)


def start_server(args, log):
    """`stabctl args` under `timeout 150` in its own session, default signal dispositions,
    stdout and stderr to the work directory's file `log`."""
    with open(WORK / log, "wb") as f:
        p = subprocess.Popen(
            ["timeout", "150", *STABCTL, *map(str, args)],
            cwd=WORK,
            env=ENV,
            stdout=f,
            stderr=subprocess.STDOUT,
            stdin=subprocess.DEVNULL,
            start_new_session=True,
            preexec_fn=_default_signals,
        )
    SERVERS.append(p)
    return p


def wait_listening(log, p, what="waiting for a", t=90):
    t0 = time.monotonic()
    while time.monotonic() - t0 < t:
        if what in (WORK / log).read_text(errors="replace"):
            return True
        if p.poll() is not None:
            return False
        time.sleep(0.3)
    return False


def stop_server(p, wait=15):
    """Wait `wait` s for the server to end, then SIGTERM its session, then SIGKILL."""
    try:
        p.wait(wait)
        return
    except subprocess.TimeoutExpired:
        pass
    for sig, grace in ((signal.SIGTERM, 10), (signal.SIGKILL, 10)):
        try:
            os.killpg(p.pid, sig)
        except ProcessLookupError:
            return
        try:
            p.wait(grace)
            return
        except subprocess.TimeoutExpired:
            continue


def kill_servers():
    for p in SERVERS:
        if p.poll() is None:
            try:
                os.killpg(p.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            p.wait()


def _serve_record(case, fault, far, rcfile, extra=()):
    """pmu serve (3 s, --speed 0) recorded by pmu record into rcfile."""
    port = free_port()
    log = f"serve_{port}.log"
    p = start_server(
        ["pmu", "serve", case, "--fault", fault, "--far-bus", far, "--tf", "3",
         "--port", port, "--speed", "0", "--no-q-limits", *extra],
        log,
    )  # fmt: skip
    if not wait_listening(log, p):
        stop_server(p, 0)
        raise RuntimeError("pmu serve did not listen: " + (WORK / log).read_text()[-300:])
    frames = "151" if "50" in case else "181"
    rc, _, e = run(["pmu", "record", f"127.0.0.1:{port}", "--frames", frames, "-o", rcfile], 120)
    stop_server(p, 20)
    if rc:
        raise RuntimeError(f"pmu record rc {rc}: {e[-200:]}")


# ---------------------------------------------------------------- cases


def big_number(n):
    """The renumbering of ieee14_big: odd n -> 900000 + 1000 n, even n -> 10 n."""
    return 900000 + int(n) * 1000 if int(n) % 2 else 10 * int(n)


def cases() -> dict[str, str]:
    """The cases (file names in the work directory), made once."""
    if CASES:
        return CASES
    (WORK / "cases").mkdir(exist_ok=True)
    out = {}
    src = andes_cases()
    for rel, name in (
        ("ieee14/ieee14_full.xlsx", "ieee14"),
        ("ieee14/ieee14_esd1.xlsx", "ieee14_esd1"),
        ("ieee39/ieee39_full.xlsx", "ieee39"),
    ):
        rc, _, e = run(["import-andes", src / rel, "-o", f"cases/{name}.json"], 300)
        if rc != 0:
            raise RuntimeError(f"import-andes {rel}: rc {rc}: {e[-300:]}")
        out[name] = f"cases/{name}.json"
    rc, _, e = run(
        ["import-psse", THREEBUS / "ThreeBusMulti.raw", THREEBUS / "ThreeBus_GENROU.dyr",
         "-o", "cases/threebus.json"],
        300,
    )  # fmt: skip
    if rc != 0:
        raise RuntimeError(f"import-psse ThreeBus: {e[-300:]}")
    out["threebus"] = "cases/threebus.json"
    d = json.loads((WORK / out["ieee14"]).read_text())
    # a 50 Hz variant: the same data, nominal frequency 50 Hz
    d50 = json.loads(json.dumps(d))
    d50["freq_hz"], d50["name"] = 50.0, d50["name"] + "_50"
    (WORK / "cases/ieee14_50.json").write_text(json.dumps(d50))
    out["ieee14_50"] = "cases/ieee14_50.json"
    # large bus numbers with gaps
    big = json.loads(json.dumps(d))
    t = big["tables"]
    for tab, cols in (
        ("buses", ["number"]),
        ("branches", ["from_bus", "to_bus"]),
        ("machines", ["bus"]),
        ("loads", ["bus"]),
        ("injections", ["bus"]),
    ):
        for c in cols:
            i = t[tab]["columns"].index(c)
            for r in t[tab]["rows"]:
                r[i] = big_number(r[i])
    big["name"] += "_big"
    (WORK / "cases/ieee14_big.json").write_text(json.dumps(big))
    out["ieee14_big"] = "cases/ieee14_big.json"
    CASES.update(out)
    return CASES


# ---------------------------------------------------------------- the law, checked


def law_problems(npz, js, f0, db=0.1, gate=0.8):
    """What in simulate's switchings (its --json) the result file `npz` contradicts."""
    z = np.load(WORK / npz)
    d = json.loads(js)
    t, sp, M, vm, isl = z["t"], z["speed"], z["inertia"], z["vmag"], z["island"]
    buses, machines = list(z["buses"]), list(z["machines"])
    rel = np.zeros_like(sp)
    for i in set(isl.tolist()):
        m = isl == i
        coi = (sp[:, m] * M[m]).sum(1) / M[m].sum()
        rel[:, m] = (sp[:, m] - coi[:, None]) * f0
    st = {s["device"]: s for s in d.get("storage", [])}
    probs = []
    for s in d.get("switchings", []):
        dev = st[s["device"]]
        b, mi = buses.index(dev["bus"]), machines.index(dev["machine"])
        v = np.interp(s["t_s"], t, vm[:, b])
        r = np.interp(s["t_s"], t, rel[:, mi])
        at = f"t={s['t_s']:.4f} D{s['device']}"
        if abs(r - s["rel_speed_hz"]) > max(3e-3, 0.03 * abs(r)):
            probs.append(f"{at} rel_speed_hz {s['rel_speed_hz']:.4f} != {r:.4f} (f0 {f0})")
        if s["mode_code"] != 0 and v < gate - 0.01:
            probs.append(f"{at} -> {s['mode']} at V={v:.3f} < {gate}")
        if (s["mode_code"] == 1 and s["rel_speed_hz"] < db - 1e-3) or (
            s["mode_code"] == -1 and s["rel_speed_hz"] > -db + 1e-3
        ):
            probs.append(f"{at} {s['mode']} inside the deadband ({s['rel_speed_hz']:.4f} Hz)")
    if d["esd"]["model"] == "ideal":  # an ideal device's power: its rating or 0
        for k, s in enumerate(d["storage"]):
            p = np.abs(z["pesd"][:, k]) * 100.0
            bad = (p > 1e-9) & (np.abs(p - s["pmax_mw"]) > 1e-6 * s["pmax_mw"])
            if bad.any():
                probs.append(
                    f"D{s['device']} power {p[bad][0]:.3f} MW, not 0 or its {s['pmax_mw']} MW"
                )
    return probs


# ---------------------------------------------------------------- probes


@probe
def p00_import_cases():
    c = cases()
    report("p00_import_cases", True, f"imported/derived {sorted(c)}")


@probe
def p01_law_on_imported_cases():
    """The law's switchings (gate, deadband, relative speed at f0, an ideal device's power)
    on IEEE 14, its 50 Hz and renumbered variants and IEEE 39, ideal and WECC devices."""
    c = cases()
    runs = [
        ("ieee14", ["--fault", "2", "--far-bus", "4", "--clear-cycles", "8"], 60.0),
        ("ieee14_50", ["--fault", "2", "--far-bus", "4", "--clear-cycles", "8"], 50.0),
        ("ieee14_big", ["--fault", "20", "--far-bus", "40", "--clear-cycles", "8"], 60.0),
        ("ieee39", ["--fault", "16", "--far-bus", "17", "--clear-cycles", "10"], 60.0),
    ]
    for name, fault, f0 in runs:
        for model in ("ideal", "wecc"):
            pid = f"p01_law_{name}_{model}"
            rc, o, e = run(
                ["simulate", c[name], *fault, "--esd-pct", "20", "--esd-model", model,
                 "--no-q-limits", "--json", "--out", f"{pid}.npz"],
                300,
            )  # fmt: skip
            if rc != 0:
                report(pid, False, f"simulate rc {rc}: {e.strip()[-200:]}")
                continue
            probs = law_problems(f"{pid}.npz", o, f0)
            n = len(json.loads(o).get("switchings", []))
            report(
                pid,
                not probs,
                f"{n} switchings checked (gate, deadband, rel. speed at f0 {f0:g} Hz, powers)"
                + (": " + "; ".join(probs[:3]) if probs else ""),
            )


@probe
def p02_big_numbers_same_figures():
    """estimate rmse on the renumbered IEEE 14: the same figures as on the original."""
    c = cases()
    common = ["--runs", "2", "--ambient-runs", "1", "--ambient-s", "5", "--no-q-limits", "--json"]
    a = run(["estimate", "rmse", c["ieee14"], "--fault", "2", "--far-bus", "4", *common], 300)
    b = run(["estimate", "rmse", c["ieee14_big"], "--fault", "20", "--far-bus", "40", *common])
    if a[0] or b[0]:
        report("p02_big_numbers_same_figures", False, f"rc {a[0]}/{b[0]}: {(a[2] + b[2])[-200:]}")
        return
    drop = ("case", "lines", "fault", "wall_time_s")
    ja, jb = ({k: v for k, v in json.loads(x[1]).items() if k not in drop} for x in (a, b))
    same = json.dumps(ja, sort_keys=True) == json.dumps(jb, sort_keys=True)
    report(
        "p02_big_numbers_same_figures",
        same,
        "estimate rmse on renumbered buses (900000+, gaps) "
        + ("gives the same figures" if same else "differs from the original numbering"),
    )


LOOP_PRELUDE = """
import json, numpy as np
from stabctl.cli.checks import model_settings
from stabctl.cli.options import controller
from stabctl.cli.pmu_options import fault_event
from stabctl.estimation import closed_loop as cl
from stabctl.estimation.pmu import PMUSettings
"""


def _island_loop(case, fault, far, pct, q_limits):
    """Closed loop with the 'ideal' estimator (true speeds) through the library, as
    `estimate closed-loop` runs it: per device its power at the end and its fraction of the
    time on after 2 s, the end speeds."""
    code = f"""{LOOP_PRELUDE}
c, ev, tf = fault_event({case!r}, {fault}, {far}, 1.0, 6.0, None)
sim = model_settings('ieee', None, {q_limits}).simulator(c)
loop = cl.LoopOptions({pct}, 'ideal', PMUSettings(rate=c.freq_hz), 0,
                      controller(0.1, 0.8, 'system', 0.0))
r = cl.run_closed_loop(sim, [ev], tf, loop).result
t, p = r.t, r.pesd
print(json.dumps({{'end': p[-1].tolist(),
                  'on': [float(np.mean(p[t > 2, k] != 0)) for k in range(p.shape[1])],
                  'speed': r.speed[-1].tolist(), 'stable': bool(r.stable)}}))
"""
    return pyrun(code)


@probe
def p03_islanding_fault_closed_loop():
    """An islanding fault: the device at the lost machine, which simulate keeps idle, is
    not held on by that machine's speed in the closed loop's COI."""
    # Kundur (built in) line 10-1 is G1's step-up: clearing it islands G1 (lost).
    # IEEE 14 line 7-8 is G4's only connection: clearing it islands G4.
    for pid, case, fault, far, pct, ql, lost in (
        ("p03_island_loop_kundur_10_1", "kundur", 10, 1, 5.0, True, 0),
        ("p03_island_loop_ieee14_7_8", str(WORK / cases()["ieee14"]), 7, 8, 20.0, False, 3),
    ):
        rc, o, e = run(
            ["simulate", case, "--fault", fault, "--far-bus", far, "--clear-cycles", "6",
             "--esd-pct", pct, "--json", *([] if ql else ["--no-q-limits"])],
            300,
        )  # fmt: skip
        if rc:
            report(pid, False, f"simulate rc {rc}: {e[-200:]}")
            continue
        dev_lost = json.loads(o)["storage"][lost]
        loop = _island_loop(case, fault, far, pct, ql)
        on_lost = loop["on"][lost]
        all_on = min(loop["on"]) > 0.6
        bad = dev_lost["switchings"] == 0 and on_lost > 0.5
        report(
            pid,
            not bad,
            f"simulate: D{lost + 1} (bus {dev_lost['bus']}, machine lost by islanding) switches "
            f"{dev_lost['switchings']} times; closed loop (ideal estimator): D{lost + 1} on "
            f"{100 * on_lost:.0f} % of the time after 2 s, every device on >= "
            f"{100 * min(loop['on']):.0f} %, P at end {[round(x, 3) for x in loop['end']]} pu, "
            f"end speeds {[round(x, 4) for x in loop['speed']]}"
            + (" (all devices held on by the lost machine's speed in the COI)" if all_on else ""),
        )


@probe
def p04_islanding_fault_cct_vs_estimate_cct():
    """Kundur 10-1 (G1 islanded) at 5 %: cct and estimate cct (ideal) within a cycle."""
    pid = "p04_island_cct_vs_estimate_cct"
    rc, o, e = run(
        ["cct", "kundur", "--fault", "10", "--far-bus", "1", "--esd-pct", "5", "--tol-ms", "4",
         "--json"],
        600,
    )  # fmt: skip
    if rc:
        report(pid, False, f"cct rc {rc}: {e[-200:]}")
        return
    c1 = json.loads(o)["cct_cycles"]
    rc, o, e = run(
        ["estimate", "cct", "kundur", "--fault", "10", "--far-bus", "1", "--esd-pct", "5",
         "--runs", "1", "--json"],
        900,
    )  # fmt: skip
    if rc:
        report(pid, False, f"estimate cct rc {rc}: {e[-200:]}")
        return
    c2 = json.loads(o)["cct_cycles"]["ideal"]["mean"]
    report(
        pid,
        abs(c1 - c2) <= 1.0,
        f"Kundur 10-1 (G1 islanded) at 5 %: cct {c1:.2f} cycles, estimate cct ideal {c2:.2f} "
        f"cycles (Kundur 3-101, no islanding, agrees: 11.9 vs 12.0 in docs/storage.md)",
    )


@probe
def p05_estimate_cct_50hz_grid_label():
    """estimate cct on a 50 Hz case: values on a 1/4-cycle lattice, not labelled 4.17 ms."""
    pid = "p05_estimate_cct_50hz_grid"
    rc, o, e = run(
        ["estimate", "cct", cases()["ieee14_50"], "--fault", "2", "--far-bus", "4",
         "--esd-pct", "20", "--runs", "1", "--no-q-limits", "--json"],
        900,
    )  # fmt: skip
    if rc:
        report(pid, False, f"rc {rc}: {e[-200:]}")
        return
    j = json.loads(o)
    head = j["lines"][0]
    vals = [v for r in j["cct_cycles"].values() for v in r["values"]]
    on_quarter = all(abs(v * 4 - round(v * 4)) < 1e-6 for v in vals)
    says_417 = "4.17 ms" in head and "1/4 cycle" in head
    report(
        pid,
        on_quarter and not says_417,
        f"50 Hz case: '{head[head.find('each found') :][:60]}...'; values {vals} "
        f"({'' if on_quarter else 'not '}on a 1/4-cycle lattice; 1/4 cycle at 50 Hz is 5 ms)",
    )


@probe
def p06_track_v_gate_refused():
    """estimate track given --v-gate (round 35: taken, and the same modes written for 0.8
    and 1.5): refused, exit 2, 'error: --v-gate given to estimate track'."""
    pid = "p06_track_v_gate_refused"
    c = cases()
    _serve_record(c["ieee14_50"], "2", "4", "r50.c37")
    bad, said = [], ""
    for g in ("0.8", "1.5"):
        rc, o, e = run(
            ["estimate", "track", c["ieee14_50"], "--source", "r50.c37", "--esd-pct", "10",
             "--v-gate", g, "--out", f"track_{g}.csv"],
            120,
        )  # fmt: skip
        said = e.strip().splitlines()[-1] if e.strip() else ""
        if not (clean_error(rc, o, e) and "error: --v-gate given to estimate track" in e):
            bad.append(f"--v-gate {g}: rc {rc}: {said[:100]}")
        elif (WORK / f"track_{g}.csv").exists():
            bad.append(f"--v-gate {g}: refused but track_{g}.csv written")
    report(
        pid,
        not bad,
        f"estimate track --v-gate 0.8 / 1.5: both refused, exit 2: '{said[:110]}'"
        if not bad
        else "; ".join(bad),
    )


@probe
def p07_control_v_gate_ignored():
    """pmu control --v-gate 1.5 against a plant: refused, or used (no ESD start); not taken
    and ignored while the plant's own 0.8 pu gate acts."""
    pid = "p07_control_v_gate_ignored"
    port = free_port()
    case = cases()["ieee14"]
    log = f"plant_{port}.log"
    p = start_server(
        ["pmu", "plant", case, "--fault", "2", "--far-bus", "4", "--clear-cycles", "12",
         "--tf", "3", "--esd-pct", "20", "--port", port, "--speed", "0", "--timeout", "30",
         "--no-q-limits", "--json"],
        log,
    )  # fmt: skip
    if not wait_listening(log, p):
        stop_server(p, 0)
        report(pid, False, "plant did not listen")
        return
    rc, o, e = run(
        ["pmu", "control", case, f"127.0.0.1:{port}", "--esd-pct", "20", "--v-gate", "1.5",
         "--timeout", "30"],
        120,
    )  # fmt: skip
    stop_server(p, 30)
    text = (WORK / log).read_text(errors="replace")
    starts = o.strip() or (e.strip().splitlines() or [""])[-1]
    try:
        row = json.JSONDecoder().raw_decode(text[text.find("{") :])[0]["closed_loop"]
        sw = row.get("mode_commands", row.get("switchings"))
    except (ValueError, KeyError, TypeError):
        sw = None
    ignored = rc == 0 and " 0 ESD start" not in starts and (sw or 0) > 0
    report(
        pid,
        not ignored,
        f"pmu control --v-gate 1.5 (rc {rc}): '{starts[:90]}'; plant mode commands {sw}"
        + (" (the controller's --v-gate taken and not used, not refused)" if ignored else ""),
    )


@probe
def p08_wecc_battery_converters_unnamed():
    """simulate --esd-model wecc: every pibr_pu.C* column named in --json converter_names."""
    pid = "p08_wecc_converters_unnamed"
    probs = []
    for name in ("ieee14_esd1", "ieee14"):
        rc, o, e = run(
            ["simulate", cases()[name], "--fault", "2", "--far-bus", "4", "--esd-pct", "20",
             "--esd-model", "wecc", "--no-q-limits", "--json", "--out", f"w_{name}.csv"],
            300,
        )  # fmt: skip
        if rc:
            report(pid, False, f"rc {rc}: {e[-200:]}")
            return
        names = json.loads(o).get("converter_names") or {}
        with open(WORK / f"w_{name}.csv") as f:
            header = f.readline().strip().split(",")
        cols = [c for c in header if c.startswith("pibr_pu.C")]
        unnamed = [c for c in cols if c.split(".C")[1] not in names]
        if unnamed:
            probs.append(
                f"{name}: columns {unnamed[0]}..{unnamed[-1]} (the batteries, = -pesd) not in "
                f"--json converter_names ({len(names)} named)"
            )
    report(pid, not probs, "; ".join(probs) or "every pibr column named")


@probe
def p09_infinite_bus_inertia_label():
    """ThreeBus with an infinite bus: the npz labels inertia a COI weight and holds those
    weights (H * MVA; in an island with an infinite bus 1 for it, 0 for the others)
    (round 35: labelled H * MVA, MW s, and holding 1 / 0)."""
    pid = "p09_infinite_bus_inertia_label"
    tb = cases()["threebus"]
    rc, _, e = run(
        ["simulate", tb, "--fault", "103", "--far-bus", "102", "--esd-pct", "10", "--json",
         "--out", "tb.npz"],
        120,
    )  # fmt: skip
    if rc:
        report(pid, False, f"rc {rc}: {e[-200:]}")
        return
    z = np.load(WORK / "tb.npz")
    unit = str(next(u for u in z["units"] if str(u).startswith("inertia")))
    m = json.loads((WORK / tb).read_text())["tables"]["machines"]
    H = np.array([r[m["columns"].index("H")] for r in m["rows"]], float)
    mva = np.array([r[m["columns"].index("mva")] for r in m["rows"]], float)
    island = np.asarray(z["island"]) if "island" in z.files else np.zeros(H.size, int)
    want = H * mva
    for k in np.unique(island[H == 0]):  # an island with infinite buses (H = 0)
        here = island == k
        want[here] = (H[here] == 0).astype(float)
    labelled = "COI weight" in unit and "infinite bus" in unit
    values = np.allclose(z["inertia"], want)
    report(
        pid,
        labelled and values,
        f"npz inertia {z['inertia'].tolist()} (COI weights {want.tolist()}: "
        f"{'equal' if values else 'DIFFER'}), labelled '{unit[:110]}'",
    )


@probe
def p10_tcp_roundtrip_big_numbers():
    """Renumbered IEEE 14: serve -> track over TCP, record -> track from the file, replay ->
    track over TCP: three identical CSVs."""
    case = cases()["ieee14_big"]
    track = ["estimate", "track", case, "--esd-pct", "10"]
    port = free_port()
    p = start_server(
        ["pmu", "serve", case, "--fault", "20", "--far-bus", "40", "--tf", "3", "--port", port,
         "--speed", "0", "--no-q-limits"],
        f"s_{port}.log",
    )  # fmt: skip
    wait_listening(f"s_{port}.log", p)
    rc1, _, _ = run(
        [*track, "--source", f"tcp://127.0.0.1:{port}", "--frames", "181", "--out", "tcp.csv"],
        120,
    )
    stop_server(p, 20)
    _serve_record(case, "20", "40", "big.c37")
    rc2, o2, _ = run([*track, "--source", "big.c37", "--out", "file.csv"], 120)
    port = free_port()
    p = start_server(["pmu", "replay", "big.c37", "--port", port, "--speed", "0"], f"r_{port}.log")
    wait_listening(f"r_{port}.log", p, "waiting")
    rc3, _, _ = run(
        [*track, "--source", f"tcp://127.0.0.1:{port}", "--frames", "181", "--out", "rep.csv"],
        120,
    )
    stop_server(p, 20)

    def rd(f):
        return (WORK / f).read_text() if (WORK / f).exists() else None

    same = rd("tcp.csv") == rd("file.csv") == rd("rep.csv") is not None
    report(
        "p10_tcp_roundtrip_big_numbers",
        same and not (rc1 or rc2 or rc3),
        f"serve->track tcp, record->track file, replay->track tcp: rc {rc1}/{rc2}/{rc3}, "
        f"{'identical CSVs' if same else 'CSVs differ'}; {o2.strip()[:80]}",
    )


@probe
def p11_fnom_mismatch_refused():
    """A 60 Hz controller on a 50 Hz plant: refused (exit 2) naming FNOM."""
    c = cases()
    port = free_port()
    p = start_server(
        ["pmu", "plant", c["ieee14_50"], "--fault", "2", "--far-bus", "4", "--tf", "3",
         "--esd-pct", "20", "--port", port, "--speed", "0", "--timeout", "15", "--rate", "10",
         "--no-q-limits"],
        f"pl_{port}.log",
    )  # fmt: skip
    wait_listening(f"pl_{port}.log", p)
    rc, _, e = run(
        ["pmu", "control", c["ieee14"], f"127.0.0.1:{port}", "--esd-pct", "20", "--rate", "10",
         "--timeout", "10"],
        60,
    )  # fmt: skip
    try:
        os.killpg(p.pid, signal.SIGTERM)
    except ProcessLookupError:
        pass
    stop_server(p, 10)
    report(
        "p11_fnom_mismatch_refused",
        rc == 2 and "FNOM" in e and "Traceback" not in e,
        f"60 Hz controller on a 50 Hz plant (rate 10): rc {rc}: {e.strip()[:140]}",
    )


@probe
def p12_cct_with_storage_bracket():
    """cct of IEEE 39 16-17 with storage (ideal, WECC, --coi critical): a CCT that is its
    bracket's stable end, a bracket within the tolerance, both ends among the probes."""
    for extra in (
        [],
        ["--esd-pct", "20"],
        ["--esd-pct", "20", "--esd-model", "wecc"],
        ["--esd-pct", "20", "--coi", "critical"],
    ):
        pid = "p12_cct_ieee39_" + ("_".join(x.strip("-") for x in extra) or "none")
        rc, o, e = run(
            ["cct", cases()["ieee39"], "--fault", "16", "--far-bus", "17", "--no-q-limits",
             "--tol-ms", "2", *extra, "--json"],
            600,
        )  # fmt: skip
        if rc:
            report(pid, False, f"rc {rc}: {e[-200:]}")
            continue
        j = json.loads(o)
        c, lo, hi = j.get("cct_s"), j.get("t_stable_s"), j.get("t_unstable_s")
        stab = [t for t, s in j["probes"] if s]
        unst = [t for t, s in j["probes"] if not s]
        ok = (
            c is not None
            and lo == c
            and hi - lo <= 0.002 + 1e-9
            and c in stab
            and hi in unst
            and "cct_cycles" in j
        )
        report(pid, ok, f"cct {c} s, bracket [{lo}, {hi}], {len(j['probes'])} probes")


@probe
def p13_sweep_big_numbers_wecc():
    """sweep-cct on the renumbered case, WECC devices, a fault list of big numbers: 6
    records, each a CCT or a verdict."""
    (WORK / "fbig.csv").write_text("bus,far_bus\n20,40\n913000,140\n901000,\n")
    rc, _, _ = run(
        ["sweep-cct", cases()["ieee14_big"], "--faults", "fbig.csv", "--esd-pct", "none,20",
         "--esd-model", "wecc", "--no-q-limits", "--tol-ms", "2", "--t-max", "0.3",
         "--workers", "1", "--out", "swbig.jsonl"],
        600,
    )  # fmt: skip
    recs = []
    if rc in (0, 1) and (WORK / "swbig.jsonl").exists():
        recs = [json.loads(x) for x in (WORK / "swbig.jsonl").read_text().splitlines()]
    labelled = all(
        r["status"] in ("ok", "verdict")
        and (r.get("verdict") or r["result"].get("cct_s") is not None)
        for r in recs
    )

    def what(r):
        k = r["key"].split("/")
        return f"{k[2]}/{k[4]}:{r.get('verdict') or r['result']['cct_s']}"

    report(
        "p13_sweep_big_numbers_wecc",
        rc == 0 and len(recs) == 6 and labelled,
        f"rc {rc}, {len(recs)} records, " + ", ".join(what(r) for r in recs),
    )


@probe
def p14_closed_loop_tcp_equals_process_50hz():
    """estimate closed-loop on the 50 Hz case, WECC devices: the same rows (stable, mode
    commands, false actions) with --transport tcp as in process."""
    pid = "p14_closed_loop_tcp_50hz"
    args = ["estimate", "closed-loop", cases()["ieee14_50"], "--fault", "2", "--far-bus", "4",
            "--clear-cycles", "12", "--tf", "3", "--esd-pct", "20", "--esd-model", "wecc",
            "--no-q-limits", "--json"]  # fmt: skip
    a = run(args, 300)
    b = run([*args, "--transport", "tcp"], 300)
    if a[0] or b[0]:
        report(pid, False, f"rc {a[0]}/{b[0]}: {(a[2] + b[2])[-200:]}")
        return
    ja, jb = json.loads(a[1])["closed_loop"], json.loads(b[1])["closed_loop"]

    def key(j):
        return {k: (v["stable"], v["mode_commands"], v["false_actions"]) for k, v in j.items()}

    report(pid, key(ja) == key(jb), f"process {key(ja)} / tcp {key(jb)}")


@probe
def p15_infinite_bus_estimation_refused():
    """estimate rmse on a case with an infinite bus: refused, naming it."""
    rc, _, e = run(
        ["estimate", "rmse", cases()["threebus"], "--fault", "103", "--far-bus", "102",
         "--runs", "1", "--ambient-s", "0"],
        120,
    )  # fmt: skip
    ok = rc == 2 and e.strip().startswith("error:") and "infinite bus" in e
    report(
        "p15_infinite_bus_estimation_refused",
        ok and "Traceback" not in e,
        f"rc {rc}: {e.strip()[:120]}",
    )


@probe
def p16_sweep_relabelled_record_wecc():
    """Round 34: a CCT record says the rating it answers and a verdict record its fault and
    rating, so a relabelled record is set aside on resume.  The same with --esd-model wecc
    (and a non-default controller option), whose jobs run controlled_cct_job."""
    (WORK / "f2.csv").write_text("bus,far_bus\n2,\n")
    res = {}
    for tag, extra in (
        ("ideal", []),
        ("wecc", ["--esd-model", "wecc"]),
        ("db005", ["--deadband-hz", "0.05"]),
    ):
        for t_max in ("0.3", "1.0"):  # a verdict record (above t_max), a CCT record
            out = f"rl_{tag}_{t_max}.jsonl"
            base = ["sweep-cct", cases()["ieee14"], "--faults", "f2.csv", "--no-q-limits",
                    "--tol-ms", "2", "--t-max", t_max, "--workers", "1", *extra]  # fmt: skip
            run([*base, "--esd-pct", "20", "--out", out], 300)
            rec = json.loads((WORK / out).read_text().splitlines()[0])
            rec["key"] = rec["key"].replace("esd20", "esd5")
            rec["inputs"]["esd_pct"] = 5.0
            (WORK / out).write_text(json.dumps(rec) + "\n")
            rc, o, e = run([*base, "--esd-pct", "5", "--out", out], 300)
            if "another search" in o + e:
                v = "set aside"
            elif "1 already in" in o + e:
                v = "taken as already done"
            else:
                v = f"rc {rc}?"
            res[f"{tag}/{'verdict' if t_max == '0.3' else 'cct'}"] = v
    bad = [k for k, v in res.items() if v != "set aside"]
    report(
        "p16_sweep_relabelled_record",
        not bad,
        "record of --esd-pct 20 relabelled as 5, resumed with --esd-pct 5: "
        + ", ".join(f"{k}: {v}" for k, v in res.items()),
    )


@probe
def p17_closed_loop_mode_commands():
    """estimate closed-loop --v-gate 1.5 (no bus reaches 1.5 pu, no device delivers power):
    its rows count `mode_commands` (commands sent, which a device's voltage gate may hold
    idle), no row a `switchings`, and its text says 'mode commands' (round 35: 26
    'switchings' reported with no power delivered)."""
    pid = "p17_closed_loop_mode_commands"
    args = ["estimate", "closed-loop", cases()["ieee14"], "--fault", "2", "--far-bus", "4",
            "--clear-cycles", "12", "--esd-pct", "20", "--v-gate", "1.5",
            "--no-q-limits"]  # fmt: skip
    rc, o, e = run([*args, "--json"], 300)
    if rc:
        report(pid, False, f"rc {rc}: {e[-200:]}")
        return
    j = json.loads(o)
    rows = j["closed_loop"]
    counts = {k: v.get("mode_commands") for k, v in rows.items()}
    keyed = all("mode_commands" in v for v in rows.values())
    old = [k for k, v in rows.items() if "switchings" in v]
    text = "\n".join(j.get("lines") or []) or run(args, 300)[1]  # the text, as printed
    says = "mode commands" in text
    report(
        pid,
        keyed and not old and says,
        f"--v-gate 1.5: mode_commands {counts}; rows with 'switchings': {old or 'none'}; "
        f"text says 'mode commands': {says}",
    )


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("ids", nargs="*", help="probe names or their prefixes (p06, p17)")
    ap.add_argument("-k", default="", help="run the probes whose name holds this")
    opts = ap.parse_args(argv)
    selected = [
        fn
        for fn in PROBES
        if (not opts.ids or fn.__name__ in opts.ids or fn.__name__.split("_")[0] in opts.ids)
        and opts.k in fn.__name__
    ]
    t_start = time.monotonic()
    print(f"stabctl of {ROOT}; work directory {WORK}", flush=True)
    rc, _, err = run(["compile"], timeout=900)  # a warm cache loads in seconds
    if rc != 0:
        print("stabctl compile failed:", err[-300:])
        shutil.rmtree(WORK, ignore_errors=True)
        return 2
    try:
        for fn in selected:
            try:
                fn()
            except Exception as ex:  # noqa: BLE001 - a probe that crashes is reported short
                report(fn.__name__, False, f"probe crashed: {type(ex).__name__}: {str(ex)[:200]}")
    finally:
        kill_servers()
        keep = bool(os.environ.get("KEEP"))
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
