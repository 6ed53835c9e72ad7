"""Write a PowerSimulationsDynamics.jl test's reference (its initial point and
eigenvalues, ``test/results/results_initial_conditions.jl`` and ``results_eigenvalues.jl``)
as JSON, read from a clone of that repository at a commit.

    python psid_reference.py [--x0 NAME] PSID_CLONE COMMIT TEST [LABEL=SUFFIX ...] > FILE.json

TEST: the test's number; each LABEL=SUFFIX one run, read from PSID's ``test<TEST>_x0_init
<SUFFIX>`` and ``test<TEST>_eigvals<SUFFIX>`` and written as ``x0_<LABEL>`` and
``eigvals_<LABEL>`` (without runs: one run, ``x0`` and ``eigvals``); ``--x0 NAME`` names
the initial point where PSID names it otherwise, ``{suffix}`` standing for SUFFIX (test 42:
``test_psse_dera{suffix}_init``).  The files here:

    python psid_reference.py PSID d94d74e7daaa445517da69cd0d528570fa438f28 47 \\
        plain= switch=_withSwitch rcrfd=_withRcRfd > SCRX/psid_test47.json
    python psid_reference.py PSID 4a2ff3d7098ab488174041ed6e18fb92076ab435 63 \\
        flag0=_Flag0 flag1=_Flag1 > DEGOV1/psid_test63.json
    python psid_reference.py PSID d94d74e7daaa445517da69cd0d528570fa438f28 58 \\
        flag0=_PowerFlag flag1=_GateFlag > PIDGOV/psid_test58.json
    python psid_reference.py PSID d94d74e7daaa445517da69cd0d528570fa438f28 60 \\
        > WPIDHY/psid_test60.json
    python psid_reference.py PSID d94d74e7daaa445517da69cd0d528570fa438f28 61 \\
        > ST8C/psid_test61.json
    python psid_reference.py --x0 'test_psse_dera{suffix}_init' PSID \
        d94d74e7daaa445517da69cd0d528570fa438f28 42 flag0=_freqflag0 flag1=_freqflag1 \
        > DERA_FREQFLAG0/psid_test42.json
"""

import json
import re
import subprocess
import sys

NUM = r"-?\d+\.\d+(?:e-?\d+)?"


def show(repo: str, commit: str, path: str) -> str:
    """The file `path` of `repo` at `commit`."""
    cmd = ["git", "-C", repo, "show", f"{commit}:{path}"]
    return subprocess.run(cmd, capture_output=True, text=True, check=True).stdout


def block(text: str, name: str, close: str) -> str:
    """The Julia definition `name = ...` up to `close`."""
    a = text.index(name + " = ")
    return text[a : text.index(close, a)]


def numbers(text: str) -> list[float]:
    """The decimal numbers of `text`."""
    return [float(v) for v in re.findall(NUM, text)]


def main(repo: str, commit: str, test: str, runs: dict[str, str], x0: str = "") -> dict:
    """The reference: source, then per run its x0 (bus voltages, states of
    generator-102-1; PSID's ``test<test>_x0_init<suffix>``, or `x0` with ``{suffix}``
    filled) and its eigenvalues as [real, imaginary]."""
    ic = show(repo, commit, "test/results/results_initial_conditions.jl")
    ev = show(repo, commit, "test/results/results_eigenvalues.jl")
    out: dict = {
        "source": f"NREL-Sienna/PowerSimulationsDynamics.jl {commit}: "
        "test/results/results_initial_conditions.jl, test/results/results_eigenvalues.jl"
    }
    for label, suffix in runs.items():
        key = f"_{label}" if label else ""
        name = x0.format(suffix=suffix) if x0 else f"test{test}_x0_init{suffix}"
        b = block(ic, name, "\n)\n")
        vr, vi, gen = b.index('"V_R"'), b.index('"V_I"'), b.index('"generator-102-1"')
        out[f"x0{key}"] = {
            "V_R": numbers(b[vr:vi]),
            "V_I": numbers(b[vi:gen]),
            "generator-102-1": numbers(b[gen:]),
        }
        e = block(ev, f"test{test}_eigvals{suffix}", "\n]\n")
        pairs = re.findall(rf"({NUM}) ([+-]) ({NUM})im", e)
        out[f"eigvals{key}"] = [
            [float(re_), float(im) if sign == "+" else -float(im)] for re_, sign, im in pairs
        ]
    return out


if __name__ == "__main__":
    args = sys.argv[1:]
    x0 = ""
    if args[:1] == ["--x0"]:
        x0, args = args[1], args[2:]
    repo, commit, test, *pairs = args
    runs = dict(p.split("=", 1) for p in pairs) or {"": ""}
    print(json.dumps(main(repo, commit, test, runs, x0), indent=1))
