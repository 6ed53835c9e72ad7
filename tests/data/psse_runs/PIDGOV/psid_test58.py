"""Write psid_test58.json: PowerSimulationsDynamics.jl's reference of its test 58
(PIDGOV), its initial point and eigenvalues, read from a clone of that repository.

    python psid_test58.py PSID_CLONE COMMIT > psid_test58.json
"""

import json
import re
import subprocess
import sys

NUM = r"-?\d+\.\d+(?:e-?\d+)?"
#: PSID's names of the two runs: the feedback flag's value, 0 the power, 1 the gate
RUNS = {"PowerFlag": 0, "GateFlag": 1}


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


def main(repo: str, commit: str) -> dict:
    """The reference: source, then per feedback flag its x0 (bus voltages, states of
    generator-102-1) and its eigenvalues as [real, imaginary]."""
    ic = show(repo, commit, "test/results/results_initial_conditions.jl")
    ev = show(repo, commit, "test/results/results_eigenvalues.jl")
    out: dict = {
        "source": f"NREL-Sienna/PowerSimulationsDynamics.jl {commit}: "
        "test/results/results_initial_conditions.jl, test/results/results_eigenvalues.jl"
    }
    for name, flag in RUNS.items():
        b = block(ic, f"test58_x0_init_{name}", "\n)\n")
        vr, vi, gen = b.index('"V_R"'), b.index('"V_I"'), b.index('"generator-102-1"')
        out[f"x0_flag{flag}"] = {
            "V_R": numbers(b[vr:vi]),
            "V_I": numbers(b[vi:gen]),
            "generator-102-1": numbers(b[gen:]),
        }
        e = block(ev, f"test58_eigvals_{name}", "\n]\n")
        pairs = re.findall(rf"({NUM}) ([+-]) ({NUM})im", e)
        out[f"eigvals_flag{flag}"] = [
            [float(re_), float(im) if sign == "+" else -float(im)] for re_, sign, im in pairs
        ]
    return out


if __name__ == "__main__":
    print(json.dumps(main(*sys.argv[1:3]), indent=1))
