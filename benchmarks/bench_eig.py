"""Wall time to linearise and analyse miniWECC and Kundur (not a test).

Phases: building the model (power flow, initialisation, reduced network: `Simulator`),
linearisation (`stabctl.smallsignal.linearise.linearise`, 2 evaluations per state and input),
modal analysis (`stabctl.smallsignal.modal.modal_analysis`: eigenvalues, both eigenvector sets,
participations, areas) and residues (`mode_sensitivity`).  Best of several runs after a
warm-up (compilation excluded), one core.  Target: miniWECC linearise + analyse
<= 0.5 s; PSTess svm_mgen takes 22 s.
Run: python benchmarks/bench_eig.py
"""

from functools import partial

from _timing import best_of

from stabctl.dynamics.driver import Simulator
from stabctl.io import load_case
from stabctl.smallsignal.linearise import linearise
from stabctl.smallsignal.modal import modal_analysis, mode_sensitivity


def main():
    print(
        f"{'case':10} {'states':>6} {'inputs':>6} {'model s':>8} {'linearise s':>11} "
        f"{'analyse s':>9} {'residues s':>10} {'lin+analyse s':>13} {'target s':>8}"
    )
    for name, target in (("kundur", float("nan")), ("miniwecc", 0.5)):
        case = load_case(name)
        t_model, sim = best_of(partial(Simulator, case), 5)
        t_lin, sys = best_of(partial(linearise, sim), 5)
        t_ma, ma = best_of(partial(modal_analysis, sys), 5)
        t_res, _ = best_of(partial(mode_sensitivity, sys, ma), 5)
        total = t_lin + t_ma + t_res
        print(
            f"{name:10} {sys.nstates:6d} {sys.ninputs:6d} {t_model:8.3f} {t_lin:11.3f} "
            f"{t_ma:9.3f} {t_res:10.3f} {total:13.3f} {target:8.2f}"
        )


if __name__ == "__main__":
    main()
