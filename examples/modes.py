"""Kundur's electromechanical modes from the simulator's own model, linearised as a
python-control StateSpace: frequency, damping, kind, and the machines that take part.

    python examples/modes.py
"""

import stabctl


def main():
    sim = stabctl.Simulator(stabctl.load_case("kundur"))
    lin = stabctl.linearise(sim)
    print(f"{lin.nstates} states")
    modes = stabctl.modal_analysis(lin)
    for k in modes.electromechanical:
        print(
            f"mode {k}: {modes.freq_hz[k]:.3f} Hz, damping {modes.damping[k]:.3f}, {modes.kind[k]}"
        )


if __name__ == "__main__":
    main()
