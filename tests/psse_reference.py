"""PSS/E's own runs of small RAW + DYR systems (tests/data/psse_runs, README there) and the
runner that repeats each as a user does: ``stabctl import-psse RAW DYR`` with no option,
then ``stabctl simulate`` with the run's disturbance, compared with PSS/E's channels.

One table, `RUNS`, read by tests/io/test_psse_runs.py (each run within the tolerance of
the PowerSimulationsDynamics.jl test that reads it) and benchmarks/psse_runs.py (the docs
page docs/psse_runs.md).  Importable from any test module (``tests/`` is on ``sys.path``).

Comparison (as the Julia tests): PSS/E's time stamps rounded to a tenth of its channel
step (1 ms at 5 ms, `Run.step`); at the event PSS/E
writes the pre-event row first, which is dropped (stabctl's row at the event time is the
post-event one); rotor angles relative to the infinite bus (PSS/E's GENCLS with H = 0)
and bus angle differences in rad (PSS/E's degrees converted); speeds in pu (PSS/E's
deviation plus 1 where its channel is a deviation); line flows in pu on the system base
(PSS/E's MW / Mvar over 100), from stabctl's bus voltages and the case's branch data;
bus angles not at the event time (PSS/E's post-event row repeats the pre-event angle); the
norm of the difference is the Julia test's: the largest absolute difference (``max``),
or the 2-norm over the samples (``l2``, the converter runs).
"""

from __future__ import annotations

import json
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parent / "data" / "psse_runs"
#: PSS/E's channel step (s); the runs use it, and half of it for the step-halving check
STEP = 0.005


@dataclass(frozen=True)
class Quantity:
    """One compared PSS/E channel: ``col`` its 0-based CSV column, ``kind`` (``delta``
    rotor angle of the machine at ``at[0]`` from the infinite bus's, ``speed_dev`` /
    ``speed`` PSS/E's speed as deviation / in pu, ``v`` bus voltage magnitude, ``angle``
    bus angle ``at[0]`` minus ``at[1]``, ``efd``, ``pm`` (machine base), ``pe``
    electrical power (system base), ``p_flow`` / ``q_flow`` branch ``at[0]``-``at[1]``
    (circuit 1) flow at its ``at[0]`` end, ``p_ibr`` / ``q_ibr`` the converter's
    output), ``tol`` the Julia test's tolerance (None: the test reads the column but
    asserts nothing on it), ``norm`` ``max`` or ``l2``."""

    col: int
    kind: str
    at: tuple[int, ...]
    tol: float | None
    norm: str = "max"
    #: compared at the event time too (False: PSS/E's post-event row repeats the
    #: pre-event value, as for an exciter's algebraic output, `Run` SEXS_NOTE)
    event_row: bool = True

    @property
    def label(self) -> str:
        where = {
            "delta": "delta G{}",
            "speed_dev": "speed G{}",
            "speed": "speed G{}",
            "v": "V{}",
            "angle": "angle V{}-V{}",
            "efd": "Efd G{}",
            "pm": "Pm G{}",
            "pe": "Pe G{}",
            "p_flow": "P {}->{}",
            "q_flow": "Q {}->{}",
            "p_ibr": "P G{}",
            "q_ibr": "Q G{}",
        }[self.kind]
        unit = {"delta": " (rad)", "angle": " (rad)", "p_flow": " (pu)", "q_flow": " (pu)"}
        return (
            where.format(*self.at)
            + unit.get(self.kind, "")
            + (" [2-norm]" if self.norm == "l2" else "")
        )


@dataclass(frozen=True)
class Run:
    """One PSS/E run: files under tests/data/psse_runs/<name>/, the disturbance as
    `stabctl simulate` options, the end time (s) and the compared quantities.  ``psse``
    is the PSS/E machine at bus ``inf_bus`` that is the infinite bus (angles from it);
    ``import_options`` what the user adds to ``import-psse`` (the load model)."""

    name: str
    raw: str
    dyr: str
    csv: str
    disturbance: tuple[str, ...]
    tf: float
    quantities: tuple[Quantity, ...]
    inf_bus: int = 101
    import_options: tuple[str, ...] = field(default=())
    models: str = ""
    #: (bus, time s, value pu): PSS/E's change of VREF of the exciter of the machine at
    #: the bus to the value at the time (PowerSimulationsDynamics.jl's
    #: ControlReferenceChange to V_ref); run as ``--vref-step MACHINE TIME DV`` with DV
    #: the value minus the exciter's initial reference (`vref_step`)
    vref: tuple[int, float, float] | None = None
    #: PSS/E's channel step (s): the run's step (and half of it for the step-halving
    #: check); its time stamps are rounded to a tenth of it
    step: float = STEP


def _trip(a: int, b: int) -> tuple[str, ...]:
    return ("--trip", str(a), str(b), "--t-trip", "1")


_THREE = "ThreeBusMulti.raw"
_TVC = "TVC_System_32.raw"


def _vref(bus: int, t: float, value: float) -> dict:
    """The keywords of a run whose disturbance is a step of VREF (`Run.vref`)."""
    return {"vref": (bus, t, value)}


def _delta(tol, col=1):
    return Quantity(col, "delta", (102,), tol)


#: the load runs' channels: V102, V103 and their angles from bus 101
_LOADS = (
    Quantity(1, "v", (102,), 0.05),
    Quantity(2, "angle", (102, 101), None),
    Quantity(3, "v", (103,), 0.05),
    Quantity(4, "angle", (103, 101), None),
)
#: the four-bus runs' (EXST1, EXAC1) channels: V1-V4 and the speed deviation of G2
_TVC_CHANNELS = (
    Quantity(1, "v", (1,), None),
    Quantity(2, "v", (2,), 1e-3),
    Quantity(3, "v", (3,), 1e-3),
    Quantity(4, "v", (4,), None),
    Quantity(5, "speed_dev", (2,), 1e-3),
)


RUNS: tuple[Run, ...] = (
    Run("OMIB_GENCLS", "OMIB.raw", "OMIB.dyr", "Test01_delta.csv", _trip(101, 102), 20.0,
        (_delta(2e-3),), models="GENCLS"),
    Run("GENROU", _THREE, "ThreeBus_GENROU.dyr", "TEST_GENROU.csv", _trip(101, 102), 20.0,
        (_delta(0.1),), models="GENROU"),
    Run("GENROU_HIGH_SAT", _THREE, "ThreeBus_GENROU_HIGH_SAT.dyr",
        "TEST_GENROU_HIGH_SAT.csv", _trip(101, 102), 20.0, (_delta(0.1),), models="GENROU"),
    Run("GENROE_HIGH_SAT", _THREE, "ThreeBus_GENROE_HIGH_SAT.dyr",
        "TEST_GENROE_HIGH_SAT.csv", _trip(101, 102), 20.0, (_delta(0.1),), models="GENROE"),
    Run("GENROU_NO_SAT", _THREE, "ThreeBus_GENROU_NO_SAT.dyr", "TEST_GENROU_NO_SAT.csv",
        _trip(101, 102), 20.0, (_delta(0.1),), models="GENROU"),
    Run("GENROE", _THREE, "ThreeBus_GENROE.dyr", "TEST_GENROE.csv", _trip(101, 102), 20.0,
        (_delta(0.1),), models="GENROE"),
    Run("GENSAL", _THREE, "ThreeBus_GENSAL.dyr", "TEST_GENSAL.csv", _trip(101, 102), 20.0,
        (_delta(0.1),), models="GENSAL"),
    Run("GENSAE", _THREE, "ThreeBus_GENSAE.dyr", "TEST_GENSAE.csv", _trip(101, 102), 20.0,
        (_delta(0.1),), models="GENSAE"),
    Run("ESAC1A", _THREE, "ThreeBus_ESAC1A.dyr", "TEST_ESAC1A.csv", _trip(101, 102), 20.0,
        (_delta(0.01), Quantity(2, "v", (102,), 0.01)), models="GENROU ESAC1A"),
    Run("ESAC1A_SAT", _THREE, "ThreeBus_ESAC1A_SAT.dyr", "TEST_ESAC1A_SAT.csv",
        _trip(101, 102), 20.0, (_delta(0.01), Quantity(2, "v", (102,), 0.01)),
        models="GENROU ESAC1A (saturated)"),
    Run("GAST", _THREE, "ThreeBus_GAST.dyr", "GAST_TEST.csv", _trip(101, 102), 20.0,
        (_delta(0.01), Quantity(2, "efd", (102,), None)), models="GENROU ESAC1A GAST"),
    Run("TGOV1", _THREE, "ThreeBus_TGOV1.dyr", "TEST_TGOV1.csv", _trip(101, 102), 20.0,
        (_delta(0.01), Quantity(2, "efd", (102,), None)), models="GENROU ESAC1A TGOV1"),
    Run("SEXS", _THREE, "ThreeBus_SEXS.dyr", "SEXS_RESULTS.csv", _trip(101, 102), 20.0,
        (
            Quantity(1, "v", (102,), 0.01),
            Quantity(2, "p_flow", (101, 103), 0.01),
            Quantity(3, "q_flow", (101, 103), 0.01),
            Quantity(4, "p_flow", (103, 101), 0.01),
            Quantity(5, "q_flow", (103, 101), 0.01),
            Quantity(6, "efd", (102,), 0.01),
            Quantity(7, "pm", (102,), 0.01),
        ), models="GENROU SEXS"),
    # SEXS with TE = 0: its Efd is algebraic, which PSS/E's channel writes one step late
    # (at 1.005 s the value stabctl has at 1.0 s): its post-event row repeats the
    # pre-event Efd, 0.24 pu below the post-event one; compared from the next row on
    Run("SEXS_NOTE", _THREE, "ThreeBus_SEXS_noTE.dyr", "SEXS_RESULTS_NoTE.csv",
        _trip(101, 102), 20.0,
        (
            Quantity(1, "v", (102,), 0.01),
            Quantity(2, "p_flow", (101, 103), 0.01),
            Quantity(3, "q_flow", (101, 103), 0.01),
            Quantity(4, "p_flow", (103, 101), 0.01),
            Quantity(5, "q_flow", (103, 101), 0.01),
            Quantity(6, "efd", (102,), 0.01, event_row=False),
            Quantity(7, "pm", (102,), 0.01),
        ), models="GENROU SEXS (TE 0)"),
    Run("IEEEST", _THREE, "ThreeBus_IEEEST.dyr", "IEEEST_SEXS_RESULTS_NOFILT.csv",
        _trip(101, 102), 20.0,
        (Quantity(1, "efd", (102,), 0.01), Quantity(2, "v", (102,), 0.01)),
        models="GENROU SEXS IEEEST"),
    Run("IEEEST_FILT", _THREE, "ThreeBus_IEEEST_with_filter.dyr",
        "IEEEST_SEXS_RESULTS_FILT.csv", _trip(101, 102), 20.0,
        (Quantity(1, "efd", (102,), 0.01), Quantity(2, "v", (102,), 0.01)),
        models="GENROU SEXS IEEEST (filter)"),
    Run("HYGOV", _THREE, "ThreeBus_HYGOV.dyr", "HYGOV_RESULTS.csv", _trip(101, 102), 20.0,
        (
            Quantity(1, "v", (102,), 1e-3),
            _delta(0.01, col=2),
            Quantity(3, "speed_dev", (102,), 1e-3),
        ), models="GENROU SEXS HYGOV"),
    Run("LOAD_CONST_P", _THREE, "ThreeBus_GENROU.dyr", "constantpower.csv", _trip(101, 102),
        20.0,
        _LOADS, import_options=("--loads", "raw"), models="GENROU, constant-power loads"),
    Run("LOAD_CONST_I", "ThreeBusMulti_const_i.raw", "ThreeBus_GENROU.dyr",
        "constantcurrent.csv", _trip(101, 102), 20.0,
        _LOADS, import_options=("--loads", "raw"), models="GENROU, constant-current loads"),
    Run("EXST1", _TVC, "TVC_System.dyr", "results_PSSe.csv", _trip(1, 4), 20.0,
        (*_TVC_CHANNELS, Quantity(6, "efd", (2,), None)), inf_bus=1, models="GENSAL EXST1 HYGOV"),
    Run("EXAC1", _TVC, "TVC_System.dyr", "results_PSSe.csv", _trip(1, 4), 20.0,
        _TVC_CHANNELS, inf_bus=1, models="GENSAL EXAC1 HYGOV"),
    # ESST1A's regulator closed through its rate feedback has a pole at -1109 1/s
    # (exst1.inner_loop_time_constants): at PSS/E's 5 ms Heun integrates it in
    # sub-intervals (docs/simulator.md; the trapezoid took it before)
    Run("ESST1A", _TVC, "TVC_System.dyr", "results_PSSe.csv",
        _trip(1, 4), 20.0,
        (
            Quantity(1, "v", (2,), 1e-3),
            Quantity(2, "v", (3,), 1e-3),
            Quantity(3, "speed", (2,), 1e-3),
            Quantity(4, "efd", (2,), 0.05),
        ), inf_bus=1, models="GENSAL ESST1A HYGOV"),
    Run("RENA_DEFAULT", "ThreeBusRenewable.raw", "ThreeBus_REN_A_DEFAULT_FLAG.dyr",
        "TEST_RENA_DEFAULT_FLAGS.csv", _trip(101, 103), 5.0,
        (
            Quantity(1, "p_ibr", (103,), 0.01, "l2"),
            Quantity(2, "q_ibr", (103,), 0.01, "l2"),
            Quantity(3, "v", (103,), 0.01, "l2"),
        ), inf_bus=102, models="REGCA1 REECB1 REPCA1"),
    Run("RENA_FREQ_FLAG", "ThreeBusRenewable.raw", "ThreeBus_REN_A_FREQ_FLAG.dyr",
        "TEST_RENA_FREQ_FLAG.csv", _trip(101, 103), 5.0,
        (
            Quantity(1, "p_ibr", (103,), 0.01, "l2"),
            Quantity(2, "q_ibr", (103,), 0.01, "l2"),
            Quantity(3, "v", (103,), 0.01, "l2"),
        ), inf_bus=102, models="REGCA1 REECB1 REPCA1 (Fflag 1)"),
    Run("RENA_Q_FLAG", "ThreeBusRenewable.raw",
        "ThreeBus_REN_A_NOFREQFLAG_with_REF_FLAG_Q_FLAG.dyr",
        "TEST_RENA_NOFREQ_REF_FLAG_Q_FLAG.csv", _trip(101, 103), 20.0,
        (Quantity(1, "angle", (103, 102), 0.01, "l2"), Quantity(2, "v", (103,), 0.01, "l2")),
        inf_bus=102, models="REGCA1 REECB1 (QFLAG 1) REPCA1"),
    Run("RENA_REF_FLAG", "ThreeBusRenewable.raw",
        "ThreeBus_REN_A_NOFREQFLAG_with_REF_FLAG.dyr", "TEST_RENA_NOFREQ_REF_FLAG.csv",
        _trip(101, 103), 10.0,
        (Quantity(1, "angle", (103, 102), 0.01, "l2"), Quantity(2, "v", (103,), 0.01, "l2")),
        inf_bus=102, models="REGCA1 REECB1 REPCA1"),
    Run("RENA_REF_FLAG_noV", "ThreeBusRenewable.raw",
        "ThreeBus_REN_A_NOFREQFLAG_with_REF_FLAG_no_V_FLAG.dyr",
        "TEST_RENA_NOFREQ_REF_FLAG.csv", _trip(101, 103), 10.0,
        (Quantity(1, "angle", (103, 102), 0.01, "l2"), Quantity(2, "v", (103,), 0.01, "l2")),
        inf_bus=102, models="REGCA1 REECB1 REPCA1"),
    # DEGOV: PSS/E's DYR has GAST on G102; the Julia test replaces it with its DEGOV
    # (README there), its reference read as the speed in pu over 5 s
    Run("DEGOV", _THREE, "ThreeBus_DEGOV.dyr", "degov_nodelay_speed_final.csv",
        _trip(101, 102), 5.0, (Quantity(1, "speed", (102,), 4.7e-5),),
        models="GENCLS DEGOV"),
    # the same with the engine's transport delay TD = 1 s (as its Julia test)
    Run("DEGOV_DELAY", _THREE, "ThreeBus_DEGOV_delay.dyr", "degov_delay_speed_final.csv",
        _trip(101, 102), 5.0, (Quantity(1, "speed", (102,), 3.1e-5),),
        models="GENCLS DEGOV (TD 1 s)"),
    # CSVGN1: 455 -> 400 MW of constant-impedance load at bus 2 at 5 ms, 70 ms at PSS/E's
    # 0.1 ms channel step; the SVC written as the Julia test builds it (README there)
    Run("CSVGN1", "3_BUS_System_SVC.raw", "3_BUS_System_SVC.dyr", "results_PSSe.csv",
        ("--load-step", "2", "0.005", "-0.55", "0"), 0.07,
        tuple(Quantity(b, "v", (b,), 1e-3) for b in (1, 2, 3)),
        inf_bus=1, models="GENCLS CSVGN1", step=1e-4),
    # DERA1: the line 101-102 tripped at 2 s, 4 s (as its Julia test); PSS/E's DYR has the
    # infinite bus only, the DERA1 record written from the Julia test's values (README there)
    Run("DERA_FREQFLAG0", _THREE, "ThreeBus_DERA1.dyr", "dera_freqflag0.csv",
        ("--trip", "101", "102", "--t-trip", "2"), 4.0,
        (Quantity(1, "v", (102,), 0.1), Quantity(2, "angle", (102, 101), 0.1)),
        models="GENCLS DERA1"),
    Run("DERA_FREQFLAG1", _THREE, "ThreeBus_DERA1.dyr", "dera_freqflag1.csv",
        ("--trip", "101", "102", "--t-trip", "2"), 4.0,
        (Quantity(1, "v", (102,), 0.1), Quantity(2, "angle", (102, 101), 0.1)),
        models="GENCLS DERA1 (FreqFlag 1)"),
    # nine units at bus 102 (GENROU with SEXS, GAST, TGOV1, HYGOV, IEEEST; two REGCA1
    # plants); the plant 'SW' (converter 2) tripped at 1 s; PSS/E's V101-V104
    Run("MULTIGEN_GEN_TRIP", "FourBusMulti.raw", "FourBus_multigen.dyr",
        "gen_trip_results.csv", ("--trip-converter", "2", "1"), 20.0,
        tuple(Quantity(k, "v", (100 + k,), 1e-3) for k in (1, 2, 3, 4)),
        models="GENROU SEXS GAST TGOV1 HYGOV IEEEST REGCA1 REECB1 REPCA1"),
    # the stabiliser runs: VREF of the machine at bus 1 stepped at 1 s (PSS/E's own
    # runs; the PSS2 DYRs written from the Julia tests' values, README there)
    Run("STAB1", "OMIB_SSS_60Hz.raw", "OMIB_SSS.dyr", "results_PSSe.csv", (), 20.0,
        (Quantity(1, "v", (1,), 1e-3), Quantity(2, "speed_dev", (1,), 1e-3)),
        inf_bus=2, models="GENROU SEXS STAB1", **_vref(1, 1.0, 1.0472)),
    *(
        Run(m, "OMIB.raw", f"OMIB_{m}.dyr", "results_PSSe.csv", (), 20.0,
            (
                Quantity(1, "pe", (1,), 5e-3),
                Quantity(2, "v", (1,), 2e-3),
                Quantity(3, "speed", (1,), 1e-4),
            ),
            inf_bus=2, models=f"GENROU SEXS {m}", **_vref(1, 1.0, 1.04691))
        for m in ("PSS2A", "PSS2B", "PSS2C")
    ),
)  # fmt: skip
BY_NAME = {r.name: r for r in RUNS}


@dataclass
class Outcome:
    """A run's result: ``diff`` per quantity (same order as ``run.quantities``) at PSS/E's
    step, ``halving`` the change of each when the step is halved; ``error`` the message
    of an import or simulation that failed (then both are empty)."""

    run: Run
    diff: list[float] = field(default_factory=list)
    halving: list[float] = field(default_factory=list)
    error: str = ""

    def passes(self, k: int) -> bool | None:
        """Quantity k within its tolerance (None: no tolerance)."""
        tol = self.run.quantities[k].tol
        if self.error:
            return False if tol is not None else None
        return None if tol is None else bool(self.diff[k] <= tol)

    def ok(self) -> bool:
        return not self.error and all(
            p is not False for p in map(self.passes, range(len(self.run.quantities)))
        )

    def shortfall(self) -> str:
        """Why the run is short (for pytest.xfail and the docs page); "" when it passes."""
        if self.error:
            return self.error
        bad = [
            f"{q.label} differs by {d:.3g} (tolerance {q.tol:g})"
            for q, d, p in zip(
                self.run.quantities, self.diff, map(self.passes, range(len(self.diff)))
            )
            if p is False
        ]
        return "; ".join(bad)


def psse_channels(run: Run) -> tuple[np.ndarray, np.ndarray]:
    """(t, columns) of PSS/E's CSV: header lines skipped, times rounded to 1 ms, the
    pre-event row at the event time dropped (stabctl's row there is the post-event one):
    the first of a duplicated time stamp, or the lone row where PSS/E wrote no
    post-event row (EXST1, EXAC1, ESST1A)."""
    rows = []
    for line in (DATA / run.name / run.csv).read_text().splitlines():
        try:
            rows.append([float(x) for x in line.split(",")])
        except ValueError:
            continue  # a header line
    m = np.array(rows)
    t = np.round(m[:, 0], int(round(-np.log10(run.step / 10))))
    keep = np.append(t[1:] != t[:-1], True) & ~np.isin(t, _event_times(run), assume_unique=False)
    dup = np.append(t[1:] == t[:-1], False)
    keep |= np.roll(dup, 1)  # the post-event row of a duplicated stamp
    return t[keep], m[keep]


def _event_times(run: Run) -> list[float]:
    d = run.disturbance
    return (
        [float(d[k + 1]) for k, a in enumerate(d) if a == "--t-trip"]
        + [float(d[k + 2]) for k, a in enumerate(d) if a == "--trip-converter"]
        + [float(d[k + 2]) for k, a in enumerate(d) if a == "--load-step"]
        + ([run.vref[1]] if run.vref else [])
    )


def vref_step(run: Run, case_file: Path) -> tuple[str, ...]:
    """The ``stabctl simulate`` options of the run's VREF step (`Run.vref`): the machine
    at the bus, the time and the change from its exciter's initial reference (as the
    run starts: ``Simulator(case).model.Vref``); () for a run without one."""
    if run.vref is None:
        return ()
    from stabctl.dynamics.driver import Simulator
    from stabctl.io import load_case

    bus, t, value = run.vref
    machine = _machine(json.loads(case_file.read_text()), bus)
    case = load_case(case_file)
    model = Simulator(case).model
    exc = np.flatnonzero(model.ep.mac == case.machine_index(machine))
    if exc.size != 1:
        raise KeyError(f"machine {machine} (bus {bus}) has {exc.size} exciters, expected one")
    dv = value - float(model.Vref[exc[0]])
    return ("--vref-step", str(machine), f"{t:g}", repr(dv))


def _stabctl(args: list[str]) -> tuple[int, str]:
    """Exit status and output of the stabctl command line (in process, as the console
    script)."""
    from click.testing import CliRunner

    from stabctl.cli import main

    res = CliRunner().invoke(main, args, catch_exceptions=True)
    out = res.output
    if res.exception is not None and not isinstance(res.exception, SystemExit):
        out += f"{type(res.exception).__name__}: {res.exception}"
    return res.exit_code, out


def _last_error(out: str) -> str:
    lines = [s.strip() for s in out.splitlines() if s.strip()]
    errs = [s for s in lines if s.lower().startswith("error")]
    return (errs or lines or ["(no output)"])[-1]


def _trajectories(csv: Path) -> dict[str, np.ndarray]:
    with csv.open() as fh:
        names = fh.readline().strip().split(",")
    data = np.loadtxt(csv, delimiter=",", skiprows=1, ndmin=2)
    return {n: data[:, k] for k, n in enumerate(names)}


def _branch_flow(case: dict, tr: dict, a: int, b: int) -> np.ndarray:
    """Complex power (pu, system base) into branch a-b (its first circuit) at bus a."""
    br = case["tables"]["branches"]
    cols = br["columns"]
    for row in br["rows"]:
        r = dict(zip(cols, row))
        if {int(r["from_bus"]), int(r["to_bus"])} == {a, b}:
            break
    else:
        raise KeyError(f"no branch {a}-{b} in the case")
    if r["tap"] not in (0, 1) or r["phase_deg"] != 0:
        raise ValueError(f"branch {a}-{b} is a transformer: flow not computed here")
    y = 1.0 / complex(r["r"], r["x"])
    va = tr[f"vmag_pu.B{a}"] * np.exp(1j * tr[f"vang_rad.B{a}"])
    vb = tr[f"vmag_pu.B{b}"] * np.exp(1j * tr[f"vang_rad.B{b}"])
    return va * np.conj((va - vb) * y + 1j * r["b"] / 2 * va)


def _machine(case: dict, bus: int) -> int:
    mt = case["tables"]["machines"]
    k_num, k_bus = mt["columns"].index("number"), mt["columns"].index("bus")
    for row in mt["rows"]:
        if int(row[k_bus]) == bus:
            return int(row[k_num])
    raise KeyError(f"no machine at bus {bus}")


def _stabctl_series(q: Quantity, run: Run, case: dict, tr: dict) -> np.ndarray:
    k = q.kind
    if k == "delta":
        g, inf = _machine(case, q.at[0]), _machine(case, run.inf_bus)
        return tr[f"angle_rad.G{g}"] - tr[f"angle_rad.G{inf}"]
    if k in ("speed", "speed_dev"):
        return tr[f"speed_pu.G{_machine(case, q.at[0])}"]
    if k == "v":
        return tr[f"vmag_pu.B{q.at[0]}"]
    if k == "angle":
        return tr[f"vang_rad.B{q.at[0]}"] - tr[f"vang_rad.B{q.at[1]}"]
    if k == "pe":
        return tr[f"pelect_pu.G{_machine(case, q.at[0])}"]
    if k in ("efd", "pm"):
        col = "efd_pu" if k == "efd" else "pmech_pu_mbase"
        return tr[f"{col}.G{_machine(case, q.at[0])}"]
    if k in ("p_flow", "q_flow"):
        s = _branch_flow(case, tr, *q.at)
        return s.real if k == "p_flow" else s.imag
    if k in ("p_ibr", "q_ibr"):
        cols = [n for n in tr if n.startswith(k[0] + "ibr_pu.C")]
        if len(cols) != 1:
            raise KeyError(f"{len(cols)} converter columns, expected one")
        return tr[cols[0]]
    raise ValueError(f"unknown quantity kind {k!r}")


def _psse_series(q: Quantity, col: np.ndarray) -> np.ndarray:
    if q.kind in ("delta", "angle"):
        return np.radians(col)
    if q.kind == "speed_dev":
        return col + 1.0
    if q.kind in ("p_flow", "q_flow"):
        return col / 100.0
    return col


def _norm(x: np.ndarray, norm: str) -> float:
    return float(np.max(np.abs(x)) if norm == "max" else np.sqrt(np.sum(x * x)))


def simulate(run: Run, workdir: Path, step: float) -> tuple[dict, dict]:
    """(case, trajectories) of the user's two commands at ``step`` s; raises RuntimeError
    with stabctl's error line when a command fails."""
    d = DATA / run.name
    case_file = workdir / f"{run.name}.json"
    if not case_file.exists():
        code, out = _stabctl(
            ["import-psse", str(d / run.raw), str(d / run.dyr), "-o", str(case_file)]
            + list(run.import_options)
        )
        if code != 0:
            raise RuntimeError(f"import-psse: {_last_error(out)}")
    csv = workdir / f"{run.name}_{step:g}.csv"
    code, out = _stabctl(
        ["simulate", str(case_file), *run.disturbance, *vref_step(run, case_file),
         "--tf", f"{run.tf:g}",
         "--step", f"{step:g}", "--out", str(csv)]
    )  # fmt: skip
    if code != 0:
        raise RuntimeError(f"simulate: {_last_error(out)}")
    return json.loads(case_file.read_text()), _trajectories(csv)


def compare(run: Run, workdir: Path | None = None) -> Outcome:
    """The run at PSS/E's step and at half of it, compared with PSS/E's channels; a run
    that cannot import or simulate gives an Outcome with its error message."""
    with tempfile.TemporaryDirectory() as tmp:
        wd = Path(workdir or tmp)
        t_ref, ref = psse_channels(run)
        try:
            series = []
            for step in (run.step, run.step / 2):
                case, tr = simulate(run, wd, step)
                series.append(
                    [
                        np.interp(t_ref, tr["t"], _stabctl_series(q, run, case, tr))
                        for q in run.quantities
                    ]
                )
        except (RuntimeError, KeyError, ValueError) as exc:
            return Outcome(run, error=str(exc).strip("'\""))
    out = Outcome(run)
    at_event = np.isin(t_ref, _event_times(run))
    for k, q in enumerate(run.quantities):
        # PSS/E's post-event row repeats the pre-event bus angle (RENA: V103 1.015 ->
        # 1.02464 there, ANGL 103 still 1.0995 deg, 2.627 deg 5 ms later): not compared
        use = ~at_event if q.kind == "angle" or not q.event_row else np.ones(len(t_ref), bool)
        d = series[0][k] - _psse_series(q, ref[:, q.col])
        out.diff.append(_norm(d[use], q.norm))
        out.halving.append(_norm((series[0][k] - series[1][k])[use], q.norm))
    return out


def markdown(outcomes: list[Outcome]) -> str:
    """The docs page docs/psse_runs.md: one row per run and quantity."""
    lines = [
        "# Agreement with PSS/E's own runs",
        "",
        "PSS/E's results for small RAW + DYR systems (published with the model tests of",
        "PowerSimulationsDynamics.jl, BSD-3; `tests/data/psse_runs/README.md`), repeated as a",
        "user runs them: `stabctl import-psse RAW DYR -o case.json` (no option; the load",
        "runs add `--loads raw`), then `stabctl simulate case.json --trip FROM TO --t-trip 1",
        "--step 0.005`. Difference: the norm the run's Julia test uses (largest absolute",
        "difference, or the 2-norm over the 5 ms samples for the converter runs) against",
        "PSS/E's channel; tolerance: that test's. Rotor angles from the infinite bus and bus",
        "angle differences in rad, line flows in pu on 100 MVA. Halving: the same norm",
        "between the runs at 5 ms and 2.5 ms (the step's own error). A run that stabctl",
        "cannot import or run is listed with its message. ESST1A's regulator loop's pole",
        "(-1109 1/s) is beyond Heun at 5 ms: its exciter takes sub-steps of 0.45 ms there",
        "(sub-intervals, docs/simulator.md). The stabiliser runs (STAB1, PSS2A, PSS2B,",
        "PSS2C) step VREF of the machine at bus 1 at 1 s instead of a trip: `--vref-step 1",
        "1 DV`, DV the Julia test's new V_ref minus the exciter's initial one; their DYRs",
        "and STAB1's 60 Hz are in `tests/data/psse_runs/README.md`. DEGOV (5 s, as its",
        "Julia test) has PSS/E's DYR with its GAST record replaced by that test's DEGOV;",
        "CSVGN1 its SVC written as a generator and a CSVGN1 record (the same README), its",
        "disturbance 55 MW of constant-impedance load shed at bus 2 at 5 ms (`--load-step",
        "2 0.005 -0.55 0`), run 70 ms at PSS/E's 0.1 ms channel step. DERA_FREQFLAG0",
        "(its DERA1 record written from the Julia test's values, the same README) trips",
        "101-102 at 2 s and runs 4 s, as its Julia test.",
        "",
        "Generated by `python benchmarks/psse_runs.py --markdown docs/psse_runs.md`;",
        "asserted by `tests/io/test_psse_runs.py` (runs still short are expected failures",
        "there, with the reason below).",
        "",
        "| run | models | quantity | difference | tolerance | pass | halving |",
        "|---|---|---|---|---|---|---|",
    ]
    for o in outcomes:
        r = o.run
        if o.error:
            lines.append(f"| {r.name} | {r.models} | (all) | error: {o.error} | | no | |")
            continue
        for k, q in enumerate(r.quantities):
            p = o.passes(k)
            tol = "-" if q.tol is None else f"{q.tol:g}"
            mark = {True: "yes", False: "**no**", None: "-"}[p]
            lines.append(
                f"| {r.name} | {r.models} | {q.label} | {o.diff[k]:.3g} | {tol} | {mark} "
                f"| {o.halving[k]:.2g} |"
            )
    n_ok = sum(o.ok() for o in outcomes)
    lines += ["", f"{n_ok} of {len(outcomes)} runs within every tolerance.", ""]
    return "\n".join(lines)
