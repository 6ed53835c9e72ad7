"""Write the stored ANDES reference traces of tests/io/test_andes.py and this folder's README.

Each test of tests/io/test_andes.py that compares with an ANDES time-domain run (or ANDES's
eigenvalues, or its initialisation) wraps each ANDES run in ``ref.run(tag, make)``
(tests/andes_refs.py); with ``STABCTL_ANDES_REFS=record`` the test runs ANDES and writes
``<test>.npz`` here: the values it compares (float64, as ANDES gives them, on ANDES's own
time grid: nothing is decimated), the ANDES version, the date and the ANDES calls of each
run (case file, disturbance, end time, step, options).  The ANDES settings are the tests'
own (stabctl.io.andes: power flow tolerance 1e-12, trapezoid with a fixed 5 ms step
unless the test says otherwise, Newton tolerance 1e-8; loads constant impedance), so that
a file is exactly what the live test compared with.

Run from the repository's root, with ANDES installed (``pip install -e ".[test,andes]"``)::

    python tests/data/andes_refs/make_refs.py                 # every file, then the README
    python tests/data/andes_refs/make_refs.py -k ieee14_ac8b  # the tests matching -k
    python tests/data/andes_refs/make_refs.py --readme        # the README only

Extra arguments go to pytest (``-k``, ``-n 2``).  The tests run as well, so a recording
that a test fails on is seen at once.  Made with ANDES 2.0.0 (each file records its
version; a new ANDES: record again, read the failures, and say in the commit what moved).
``STABCTL_ANDES_REFS=check python -m pytest tests/io/test_andes.py`` compares every stored
run with a fresh ANDES run without writing.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[2]


def record(pytest_args: list[str]) -> int:
    """Run tests/io/test_andes.py with ``STABCTL_ANDES_REFS=record`` (each test writes its
    file here), ``pytest_args`` appended; returns pytest's exit code."""
    env = dict(os.environ, STABCTL_ANDES_REFS="record")
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH", "")]))
    cmd = [sys.executable, "-m", "pytest", "tests/io/test_andes.py", "-q", "-p", "no:randomly"]
    return subprocess.call(cmd + pytest_args, cwd=ROOT, env=env)


def describe(path: Path) -> dict:
    """A stored file's metadata and, per run, its arrays' names and shapes."""
    with np.load(path, allow_pickle=False) as z:
        meta = json.loads(str(z["_meta"]))
        shapes = {k: z[k].shape for k in z.files if k != "_meta"}
    meta["size"] = path.stat().st_size
    meta["arrays"] = shapes
    return meta


def readme() -> str:
    """The README's text: what the folder holds, how to remake it, and one entry per file
    (the test, each run's ANDES calls: case, disturbance, end time and step, options; its
    arrays; the ANDES version)."""
    files = sorted(HERE.glob("*.npz"))
    metas = [(f, describe(f)) for f in files]
    total = sum(m["size"] for _, m in metas)
    versions = sorted({m["andes"] for _, m in metas})
    lines = [
        "# Stored ANDES reference traces",
        "",
        "ANDES's runs that tests/io/test_andes.py compares stabctl's live runs with, so that",
        "the default test run needs no ANDES time simulation (issue 51).  Written by",
        "`make_refs.py` (this folder; its docstring says how to rerun it), read by",
        "`tests/andes_refs.py`.  The README is written by the script as well.",
        "",
        f"{len(files)} files, {total / 1e6:.1f} MB; ANDES {', '.join(versions)}.",
        "",
        "Settings common to every run (stabctl.io.andes): ANDES's power flow with tolerance",
        "1e-12, PV buses without Q limits; loads constant impedance (ANDES's default);",
        "time-domain: trapezoid, fixed step (the `andes_speeds` step, 5 ms unless given),",
        "Newton tolerance 1e-8; a RAW file's lines on SBASE and its line-end shunts as",
        "ANDES Shunts.  `AndesFault(bus, t_fault, t_clear, r, x)` is ANDES's Fault model",
        "(a shunt r + jx pu at the bus, no line lost); `off=(...)` models switched off",
        "(u = 0) before set-up, e.g. the case's own Toggle.  Arrays are float64 on ANDES's",
        "own time grid `t` (its steps beside each event included); `wa` the GENROU speeds",
        "(pu) in static-generator order, `buses` their buses, `modes` EIG's eigenvalues.",
        "",
        "Modes (environment variable `STABCTL_ANDES_REFS`): unset, the stored traces;",
        "`live` (CI) also runs the `[live-andes]` smoke tests, which check the stored",
        "traces still equal ANDES's fresh run; `check` does that for every test; `record`",
        "rewrites the files (`make_refs.py`).",
        "",
        "| file | size (kB) | ANDES | runs: ANDES calls; arrays |",
        "|---|---:|---|---|",
    ]
    for f, m in metas:
        runs = []
        for tag, run in m["runs"].items():
            calls = "; ".join(f"`{c}`" for c in run["calls"])
            note = f" ({run['note']})" if run.get("note") else ""
            arrays = ", ".join(
                f"{k.split('/', 1)[1]} {'x'.join(map(str, s)) or 'scalar'}"
                for k, s in m["arrays"].items()
                if k.startswith(f"{tag}/")
            )
            runs.append(f"**{tag}**: {calls}{note}; {arrays}")
        cell = "<br>".join(runs).replace("|", "\\|")
        lines.append(f"| `{f.name}` | {m['size'] / 1e3:.0f} | {m['andes']} | {cell} |")
    return "\n".join(lines) + "\n"


def main(argv: list[str]) -> int:
    """Record (unless ``--readme``), then write README.md; returns the exit code."""
    code = 0
    if "--readme" not in argv:
        code = record(argv)
    (HERE / "README.md").write_text(readme())
    return code


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
