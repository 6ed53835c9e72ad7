#!/usr/bin/env python
"""Twenty-sixth reliability round (round 43, parts U and V): import fidelity and the API.

U (PSS/E and ANDES data read as their tools read them): a REECA1 VDL curve with one
falling current point (PSS/E interpolates it; stabctl switched the whole curve off
without a word), falling voltages (refused naming the record), all points 0 (no curve,
named; every run was refused at a current limit 0), an ANDES REECA1 whose busr names its
own bus (was refused as remote), a three-winding transformer's winding left out by STAT 2
(not named), a RAW header without REV or BASFRQ (defaults taken without a word), and
`import-andes` of a 200 MB .json of NULs (refused, but at 1 GiB max RSS; bound 800 MiB).
V (the Python API): a run its monitor stopped, written to .npz and read back, said
"stable"; `solve_powerflow(drop=[-1])` named "row 0"; `modal_analysis(inertia="abcd")`
ended in numpy's bare ValueError.

    python benchmarks/reliability_probes_26.py

The package under test is this repository's (CLONE to test another checkout); the
kernel cache is the caller's (NUMBA_CACHE_DIR).  Prints per probe: id, ok/SHORT, reason;
exits 1 if any is SHORT.  Work in a temporary directory (removed unless KEEP=1).  About
two minutes with a warm kernel cache.  The round found all of them short; all fixed.
"""

# ruff: noqa: BLE001 - a tester's script, kept as written

import os
import shutil
import subprocess
import sys
import tempfile
import warnings
from pathlib import Path

CLONE = Path(os.environ.get("CLONE", Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(CLONE))
ENV = dict(os.environ, PYTHONPATH=str(CLONE))
WD = Path(tempfile.mkdtemp(prefix="probes_uv."))
RENA = CLONE / "tests" / "data" / "psse_runs" / "RENA_DEFAULT"
V33 = CLONE / "tests" / "data" / "psse" / "five_bus_v33.raw"
RESULTS = []


def probe(pid):
    def deco(fn):
        try:
            ok, why = fn()
        except Exception as exc:  # a probe's own crash is reported, not fatal
            ok, why = False, f"probe raised {type(exc).__name__}: {exc}"
        RESULTS.append((pid, ok))
        print(f"{pid:<10} {'ok' if ok else 'SHORT':<5} {why}", flush=True)
        return fn

    return deco


def stabctl(*args, timeout=120):
    """(exit code, stderr, max RSS in MiB) of a CLI run (GNU time's report)."""
    cmd = ["/usr/bin/time", "-f", "RSS %M", sys.executable, "-m", "stabctl", *map(str, args)]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=ENV, cwd=WD)
    lines = p.stderr.splitlines()
    rss = next((int(s.split()[1]) / 1024 for s in lines if s.startswith("RSS ")), float("nan"))
    own = ("RSS ", "Command exited with non-zero status")  # GNU time's lines
    return p.returncode, "\n".join(s for s in lines if not s.startswith(own)), rss


#: a REGCA1 + REECA1 plant on RENA's bus 103 (ANDES's ieee14_wt3 values in the PSS/E
#: Model Library's orders), its VDL curves written by `plant`
PLANT = (
    "102 'GENCLS' 1 0.0 0.0 /\n"
    "103 'REGCA1' 1 1 0.1 999.0 0.8 0.5 1.0 1.2 1.0 0.4 0.0 0.1 0.7 1.0 -1.0 0 /\n"
    "103 'REECA1' 1 0 0 0 0 0 0 0.8 1.1 0.02 -0.02 0.02 20.0 999.0 -999.0 1.03 0.0 -2.0 "
    "1.0 0.02 999.0 -999.0 999.0 -999.0 1.0 0.1 1.0 0.1 1.03 0.02 999.0 -999.0 999.0 "
    "-999.0 10.0 0.02 {vdl} 0.2 2.0 0.4 4.0 0.8 8.0 1.0 10.0 /\n"
)


def plant(vq, iq, name):
    path = WD / name
    path.write_text(PLANT.format(vdl=" ".join(f"{v} {i}" for v, i in zip(vq, iq))))
    return path


def load(raw, dyr=None):
    """(case, warnings' texts) of load_psse."""
    from stabctl.io.psse import load_psse

    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        case = load_psse(raw, dyr)
    return case, [str(w.message) for w in said]


def main():
    from stabctl.dynamics.driver import Simulator
    from stabctl.errors import CaseError

    raw = RENA / "ThreeBusRenewable.raw"

    @probe("U01-vdl")
    def _():
        """A falling current point: the curve applies (PSS/E, GridPACK interpolate it)."""
        case, _ = load(raw, plant((0.2, 0.4, 0.8, 1.0), (1.0, 0.5, 8.0, 10.0), "fall.dyr"))
        z = Simulator(case).model.cp.zVDL1[0]
        return z == 1.0, f"zVDL1 = {z:g} (1: the curve applies)"

    @probe("U02-vdl-v")
    def _():
        """Falling voltages: refused naming file:line and the fields."""
        try:
            load(raw, plant((0.2, 0.4, 0.3, 1.0), (2.0, 4.0, 8.0, 10.0), "volts.dyr"))
        except CaseError as exc:
            ok = "volts.dyr:3 REECA1" in str(exc) and "Vq1 <= Vq2 <= Vq3 <= Vq4" in str(exc)
            return ok, str(exc)[:120]
        return False, "imported"

    @probe("U03-vdl-0")
    def _():
        """All points 0: no curve (Imax alone), named at import; a run starts."""
        case, said = load(raw, plant((0,) * 4, (0,) * 4, "zero.dyr"))
        named = any("VDL1 (Vq1..Iq4) all 0: read as no curve" in s for s in said)
        verdict = Simulator(case).run([], 0.5).verdict
        return named and verdict == "stable", f"named {named}, run {verdict}"

    @probe("U04-busr")
    def _():
        """An ANDES REECA1 busr naming its REGCA1's own bus (ieee14_wt3: bus 8) imports."""
        import andes
        import pandas as pd

        from stabctl.io.andes_case import read_andes_case

        sheets = pd.read_excel(andes.get_case("ieee14/ieee14_wt3.xlsx"), sheet_name=None)
        sheets["REECA1"]["busr"] = 8
        path = WD / "own_busr.xlsx"
        with pd.ExcelWriter(path) as w:
            for name, rows in sheets.items():
                rows.to_excel(w, sheet_name=name, index=False)
        n = len(read_andes_case(path, on_unsupported="skip").case.converters)
        return n == 1, f"{n} converter row(s) (1 expected)"

    @probe("U05-3wdg")
    def _():
        """STAT 2 leaves winding 2 out: named among the records out of the network."""
        from stabctl.io.psse_raw import read_raw

        winding = "{w}, 0.0, 0.0, 0.0, 0.0, 0.0, 0, 0, 1.1, 0.9, 1.1, 0.9, 33, 0, 0.0, 0.0, 0.0\n"
        record = (
            "    1,     3,     4,'T ',1,2,1, 0.0, 0.0,2,'T3          ',2,   1,1.0000\n"
            " 0.002, 0.10, 200.0, 0.004, 0.05, 50.0, 0.003, 0.08, 80.0, 0.99, -3.0\n"
            + "".join(winding.format(w=1.0) for _ in range(3))
        )
        end = "0 / END OF TRANSFORMER DATA"
        path = WD / "s2.raw"
        path.write_text(V33.read_text().replace(end, record + end, 1))
        named = [str(s) for s in read_raw(path).switched_off if "winding 2 (bus 3)" in str(s)]
        return bool(named), named[0] if named else "winding 2 not named"

    @probe("U06-header")
    def _():
        """A header without REV and BASFRQ: both defaults named."""
        path = WD / "nohead.raw"
        path.write_text(V33.read_text().replace("0,   100.00, 33, 0, 1, 50.00", "0,   100.00", 1))
        _, said = load(path)
        ok = any("REV not given" in s and "BASFRQ not given" in s for s in said)
        return ok, "both named" if ok else f"warnings: {[s[:80] for s in said]}"

    @probe("U07-nuls")
    def _():
        """import-andes of a 200 MB .json of NULs: exit 2, one error line, RSS < 800 MiB."""
        big = WD / "big.json"
        with open(big, "wb") as f:
            f.truncate(200 * 2**20)
        rc, err, rss = stabctl("import-andes", big, "-o", WD / "o.json")
        ok = rc == 2 and len(err.strip().splitlines()) == 1 and rss < 800
        return ok, f"exit {rc}, max RSS {rss:.0f} MiB: {err.strip()[:90]}"

    @probe("V01-npz")
    def _():
        """A run its monitor stopped reads back from .npz as stopped, not stable."""
        from stabctl.dynamics.results import STOPPED, SimulationResult
        from stabctl.io import load_case
        from stabctl.stability.cct import LineFault

        sim = Simulator(load_case("kundur"))
        res = sim.run(
            LineFault(3, 101).events(0.5), 6.0, monitor=lambda r: "stop" if r.t[-1] > 1.5 else None
        )
        back = SimulationResult.from_npz(res.to_npz(WD / "stopped.npz"))
        return back.verdict == STOPPED, f"read back: {back.verdict!r}"

    @probe("V02-drop")
    def _():
        """solve_powerflow(drop=[-1]) names the index given, not "row 0"."""
        from stabctl.io import load_case
        from stabctl.network.powerflow import solve_powerflow

        try:
            solve_powerflow(load_case("kundur"), drop=[-1])
        except CaseError as exc:
            return "-1" in str(exc) and "row 0" not in str(exc), str(exc)
        return False, "solved"

    @probe("V03-inertia")
    def _():
        """modal_analysis(inertia="abcd"): stabctl's InputError naming the argument."""
        import stabctl
        from stabctl.errors import InputError
        from stabctl.io import load_case

        sys_ = stabctl.linearise(Simulator(load_case("kundur")))
        try:
            stabctl.modal_analysis(sys_, inertia="abcd")
        except InputError as exc:
            return "modal_analysis(inertia)" in str(exc), str(exc)[:100]
        except Exception as exc:
            return False, f"{type(exc).__name__}: {exc}"
        return False, "accepted"

    short = [pid for pid, ok in RESULTS if not ok]
    print(f"{len(RESULTS) - len(short)}/{len(RESULTS)} ok" + (f"; SHORT: {short}" if short else ""))
    return 1 if short else 0


if __name__ == "__main__":
    try:
        code = main()
    finally:
        if not os.environ.get("KEEP"):
            shutil.rmtree(WD, ignore_errors=True)
    sys.exit(code)
