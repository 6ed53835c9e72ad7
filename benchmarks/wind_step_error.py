"""Step error of the wind turbine's P and Q, each tool against its own fine-step run (not a
test; ANDES needed).

ANDES's ``kundur/kundur_wtdta1.xlsx`` (a 700 MW REGCA1 + REECA1 + REPCA1 turbine with
WTDTA1, WTARA1, WTPTA1, WTTQA1; its Toggle and Fault records off) imported with
``import_andes``; a bus fault through j1e-3 pu at bus 7 from 1 s for 6 cycles, 5 s, run by
stabctl (Heun, fixed step) and by ANDES 2.0 (trapezoid, fixed step ``tstep``, its default
tolerance) at each step of STEPS.  Printed per step: the gap between the tools (largest
|stabctl - ANDES| of the turbine's P and Q on ANDES's time grid, the points beside the fault
and clearing instants left out, as tests/io/test_andes.py) and each tool's step error, its
gap to its own run at the finest step.  The tools' gap at the finest step is what is left
when neither step counts.

ANDES's event steps (``--event-eps``): ANDES steps 1e-4 s beside each event and takes the
first step after a switch with the pre-switch derivative (`stabctl.io.andes.andes_system`),
a delay of about 5e-5 s whatever its step: with both tools at 0.3125 ms it is the tools'
gap, 1.0e-3 P and 1.4e-3 Q; with ``--event-eps 1e-7``, 2.2e-4 and 1.7e-4.

Like for like (``--method trapezoid --fixed-step --event-eps 1e-7``): stabctl's trapezoid
against ANDES's with its step held, the tools' gap at 5 ms is then what the models differ
by (docs/ibr.md 8).

Run: python benchmarks/wind_step_error.py [--case kundur/kundur_wtdta1.xlsx] [--bus 7]
[--steps 0.005 ... 0.0003125] [--event-eps 1e-7] [--method heun|trapezoid] [--fixed-step]
"""

from __future__ import annotations

import argparse
import warnings

import numpy as np

STEPS = (0.005, 0.0025, 0.00125, 0.0003125)  # s; the last is the reference
T_FAULT, CYCLES, X_FAULT, T_END = 1.0, 6, 1e-3, 5.0


def runs(
    case_name: str, bus: int, steps=STEPS, event_eps=None, method="heun", fixed_step=False
) -> dict:
    """{step: (t, P, Q, Pa, Qa)} on ANDES's grid t (stabctl's interpolated)."""
    import andes

    from stabctl.dynamics.driver import Simulator
    from stabctl.dynamics.events import Fault
    from stabctl.io.andes import AndesFault, andes_converter_powers, andes_speeds, andes_system
    from stabctl.io.andes_case import import_andes

    path = andes.get_case(case_name)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the Toggle and Fault records left out
        case = import_andes(path, on_unsupported="skip")
    t_clear = T_FAULT + CYCLES / 60
    out = {}
    for h in steps:
        res = Simulator(case, q_limits=False).run(
            [Fault(bus, T_FAULT, t_clear, x=X_FAULT)], T_END, h=h, method=method
        )
        fault = AndesFault(bus, T_FAULT, t_clear, x=X_FAULT)
        ss = andes_system(
            path,
            fault=fault,
            off=("Toggle", "Fault"),
            event_eps=event_eps,
            fixed_step=fixed_step,
        )
        t, _ = andes_speeds(ss, T_END, h)
        Pa, Qa = andes_converter_powers(ss, "REGCA1")
        P = np.interp(t, res.t, res.ibr_p[:, 0])
        Q = np.interp(t, res.t, res.ibr_q[:, 0])
        out[h] = (t, P, Q, Pa[:, 0], Qa[:, 0])
        print(f"  ran {1e3 * h:g} ms", flush=True)
    return out


def gap(t, a, b, h) -> float:
    """Largest |a - b| on t, without the points in (te - h, te + 2e-4] of the fault and
    clearing instants te (ANDES records the instant before a jump, stabctl after it)."""
    keep = np.ones(t.size, bool)
    for te in (T_FAULT, T_FAULT + CYCLES / 60):
        keep &= ~((t > te - h) & (t <= te + 2e-4))
    return float(np.max(np.abs(a - b)[keep]))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--case", default="kundur/kundur_wtdta1.xlsx")
    ap.add_argument("--bus", type=int, default=7)
    ap.add_argument(
        "--steps", type=float, nargs="+", default=STEPS, help="steps (s), the last the reference"
    )
    ap.add_argument(
        "--event-eps",
        type=float,
        default=None,
        help="ANDES's steps beside each event (s; its default 1e-4): its first step after a "
        "switch uses the pre-switch derivative, a delay of about eps/2 (stabctl.io.andes."
        "andes_system); 1e-7 makes it negligible",
    )
    ap.add_argument(
        "--method",
        choices=("heun", "trapezoid"),
        default="heun",
        help="stabctl's integration method (trapezoid: ANDES's)",
    )
    ap.add_argument(
        "--fixed-step",
        action="store_true",
        help="hold ANDES's step at tstep (its trapezoid otherwise shrinks it by 0.95 after "
        "7-14 Newton iterations; stabctl.io.andes.andes_system)",
    )
    args = ap.parse_args()
    steps = tuple(args.steps)
    print(f"{args.case}: fault at bus {args.bus} through j{X_FAULT} pu, {CYCLES} cycles, {T_END} s")
    eps = "ANDES's default 1e-4" if args.event_eps is None else f"{args.event_eps:g}"
    print(f"ANDES's event steps: {eps} s")
    print(f"stabctl: {args.method}; ANDES's step: {'held' if args.fixed_step else 'its own'}")
    r = runs(args.case, args.bus, steps, args.event_eps, args.method, args.fixed_step)
    t_ref, P_ref, Q_ref, Pa_ref, Qa_ref = r[steps[-1]]
    print("step ms | tools' gap P, Q | stabctl step error P, Q | ANDES step error P, Q")
    for h in steps:
        t, P, Q, Pa, Qa = r[h]
        own = [gap(t, x, np.interp(t, t_ref, ref), h) for x, ref in ((P, P_ref), (Q, Q_ref))]
        theirs = [gap(t, x, np.interp(t, t_ref, ref), h) for x, ref in ((Pa, Pa_ref), (Qa, Qa_ref))]
        cells = [gap(t, P, Pa, h), gap(t, Q, Qa, h), *own, *theirs]
        print(f"{1e3 * h:7.4g} | " + " | ".join(f"{c:.2e}" for c in cells))


if __name__ == "__main__":
    main()
