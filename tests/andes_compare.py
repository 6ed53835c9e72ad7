"""Like-for-like runs of stabctl and ANDES on the same case and bus fault, shared by
tests/io/test_andes.py and benchmarks/converter_bus_faults.py: stabctl's run and
ANDES's (through ``ref.run``, tests/andes_refs.py: stored or live), both on ANDES's time
grid, and their gaps.  ANDES's calls are `logged` (a stored run's metadata names them).

A caller without stored runs (the benchmark) passes `LIVE` as ``ref``: ANDES runs.
"""

from __future__ import annotations

import warnings

import andes
import numpy as np
from andes_refs import logged

from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.events import Fault
from stabctl.errors import SimulationError
from stabctl.io.andes import (
    AndesFault,
    andes_converter_powers,
    andes_machine_buses,
    andes_speeds,
    andes_system,
)
from stabctl.io.andes_case import import_andes

andes_system, andes_speeds = map(logged, (andes_system, andes_speeds))

STEP = 0.005  # s, both tools


class Live:
    """A ``ref`` (tests/andes_refs.py `AndesRef`'s interface) whose runs are ANDES's own,
    live, never stored."""

    def run(self, tag, make, note="", inputs=None):
        """``make()``: ANDES's run ``tag``."""
        return make()


LIVE = Live()


def paired_rows(ours, theirs):
    """stabctl's machine row for each ANDES machine, given the machines' buses in each
    tool's order: the k-th ANDES unit at a bus is the k-th stabctl unit there (NPCC has
    two units at buses 23 and 54)."""
    rows = {}
    for k, b in enumerate(ours):
        rows.setdefault(int(b), []).append(k)
    return [rows[int(b)].pop(0) for b in theirs]


def speeds_on(t, res, case, buses):
    """stabctl's speeds on ANDES's time grid, columns in ANDES's machine order (its
    machines' ``buses``, `andes_machine_buses`)."""
    rows = paired_rows(case.machines.bus, buses)
    return np.column_stack([np.interp(t, res.t, res.speed[:, k]) for k in rows])


def speeds_run(ss, t_end, step=STEP, **more):
    """ANDES's run of ``ss`` to ``t_end``: a dict of its time grid ``t``, its speeds ``wa``
    and its machines' ``buses`` (`andes_speeds`), and ``more``'s items, each a function of
    ``ss`` after the run, for `AndesRef.run`."""
    t, wa = andes_speeds(ss, t_end, step)
    return dict(t=t, wa=wa, buses=andes_machine_buses(ss), **{k: f(ss) for k, f in more.items()})


def converter_powers(model):
    """ANDES ``model``'s converter powers ``Pa``, ``Qa`` (`andes_converter_powers`) as
    functions of the system for `speeds_run`."""
    return dict(
        Pa=lambda ss: andes_converter_powers(ss, model)[0],
        Qa=lambda ss: andes_converter_powers(ss, model)[1],
    )


def algebraic_gaps(t, ours, theirs, events, step=STEP):
    """Largest |ours - theirs| of an algebraic output on ANDES's grid t, leaving out the
    points in (te - step, te + 2e-4] of each event time te: ANDES records the instant
    before a jump and adds points 1e-4 s around it, stabctl records after it, so that an
    interpolation of stabctl's values there mixes both sides."""
    out = np.zeros(t.size, bool)
    for te in events:
        out |= (t > te - step) & (t <= te + 2e-4)
    return np.max(np.abs(ours - theirs)[~out])


def stabctl_fault_run(case, bus, cycles, h, t_end, x=1e-3, like_for_like=False):
    """stabctl's run of a bus fault through j x pu from 1 s for ``cycles`` (60 Hz), step h,
    to t_end, PV Q limits off: the trapezoid if like_for_like, else Heun (a `Result`;
    raises `SimulationError` where the run stops)."""
    method = "trapezoid" if like_for_like else "heun"
    sim = Simulator(case, q_limits=False)
    return sim.run([Fault(bus, 1.0, 1.0 + cycles / 60, x=x)], t_end, h=h, method=method)


def andes_fault_run(
    ref, path, bus, cycles, h, t_end, x=1e-3, model="REGCA1", like_for_like=False, edit=None
):
    """ANDES's run of the same fault (`stabctl_fault_run`), the case's own Toggle and Fault
    off, through ``ref.run`` under a tag made of the arguments: a dict of its grid ``t``,
    the GENROU speeds ``wa``, their ``buses`` and ``model``'s converter powers ``Pa``,
    ``Qa`` (`andes_converter_powers`).  like_for_like: ANDES's step held at h, its event
    steps 1e-7 s (`andes_system` fixed_step, event_eps); edit: ANDES's data changed before
    set-up (`keep_reeca1_ipmax`).  Raises RuntimeError where ANDES's run fails."""
    t_clear = 1.0 + cycles / 60
    tag = f"bus{bus}_{cycles}c_x{x:g}_h{h:g}_{t_end:g}s" + "_lfl" * like_for_like
    tag += f"_{edit.__name__}" if edit else ""
    return ref.run(
        tag,
        lambda: speeds_run(
            andes_system(
                path,
                fault=AndesFault(bus, 1.0, t_clear, x=x),
                off=("Toggle", "Fault"),
                event_eps=1e-7 if like_for_like else None,
                fixed_step=like_for_like,
                edit=edit,
            ),
            t_end,
            h,
            **converter_powers(model),
        ),
    )


def paired_run(res, case, a):
    """stabctl's run ``res`` of ``case`` against ANDES's ``a`` (`andes_fault_run`) on
    ANDES's grid t: the largest speed gap dw, the converter's P, Q (stabctl's, first
    converter, interpolated) and Pa, Qa (ANDES's), and ``res``."""
    t, wa = a["t"], a["wa"]
    return {
        "t": t,
        "dw": np.max(np.abs(speeds_on(t, res, case, a["buses"]) - wa)),
        "P": np.interp(t, res.t, res.ibr_p[:, 0]),
        "Q": np.interp(t, res.t, res.ibr_q[:, 0]),
        "Pa": a["Pa"][:, 0],
        "Qa": a["Qa"][:, 0],
        "res": res,
    }


def regca1_fault_run(
    ref,
    path,
    case,
    bus,
    cycles,
    h,
    t_end,
    x=1e-3,
    model="REGCA1",
    like_for_like=False,
    edit=None,
):
    """A bus fault through j x pu from 1 s, both tools at step h, on ANDES's grid t (the
    case's own Toggle and Fault off): `paired_run` of `stabctl_fault_run` and
    `andes_fault_run` (the same arguments)."""
    res = stabctl_fault_run(case, bus, cycles, h, t_end, x, like_for_like)
    a = andes_fault_run(ref, path, bus, cycles, h, t_end, x, model, like_for_like, edit)
    return paired_run(res, case, a)


def power_gaps(run, t_clear, h):
    """The converter's (P, Q) gaps (pu) of a `paired_run` whose fault, from 1 s, clears at
    t_clear (`algebraic_gaps`, the event instants left out)."""
    t = run["t"]
    return tuple(
        algebraic_gaps(t, run[ours], run[theirs], (1.0, t_clear), h)
        for ours, theirs in (("P", "Pa"), ("Q", "Qa"))
    )


def fault_gaps(ref, path, case, bus, cycles, h, t_end, **kw):
    """(speed, P, Q) gaps to ANDES of a bus fault through j1e-3 pu (or ``x``), both tools at
    step h (`regca1_fault_run`, returned last)."""
    run = regca1_fault_run(ref, path, case, bus, cycles, h, t_end, **kw)
    return run["dw"], *power_gaps(run, 1.0 + cycles / 60, h), run


def like_for_like_case(name):
    """ANDES's case file and its import (its Toggle and Fault records left out)."""
    path = andes.get_case(name)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return path, import_andes(path, on_unsupported="skip")


def keep_reeca1_ipmax(ss) -> None:
    """Before ANDES's set-up: its Fault, clearing, restores every algebraic variable to its
    pre-fault value (``Fault.config.restore``, mode 1: ANDES stops at clearing without it),
    the REECA1's Ipmax too; its VarHold Ipmaxh, evaluated at the first iterate after the dip
    before the Thld2 flag rises, then holds that pre-fault Ipmax (9.944 pu on Kundur's
    turbine) for Thld2, where the WECC REEC_A holds the limit of the dip (9.537 pu: 0.4 pu
    more active current for 1 s).  Ipmax is kept at its value at clearing."""
    fault = ss.Fault
    clear = fault.tc.callback

    def clear_keeping_ipmax(is_time):
        a = ss.REECA1.Ipmax.a
        kept = ss.dae.y[a].copy()
        out = clear(is_time)
        ss.dae.y[a] = kept
        return out

    fault.tc.callback = clear_keeping_ipmax


def restore_fault_angles(ss) -> None:
    """Before ANDES's set-up: its Fault, clearing, restores the algebraic variables to
    their pre-fault values but for the bus angles (``models/timer.py`` ``clear_fault``,
    mode 1: ``dae.y[Bus.n:]``, the angles being ``y[:Bus.n]``), so that its Newton
    iteration starts from the pre-fault magnitudes at the angles of the fault.  From
    there it can reach a solution of its power-balance equations with a bus at 0 V: at
    ``v = 0`` a bus's P and Q balance hold whatever flows into it (every term is a
    multiple of ``v``), a short circuit left in place (kundur_wtdta1's bus-6 fault: bus 7
    at 0.0000 pu from clearing on, ANDES's machines accelerating to 1.05 pu).  The angles
    are restored as well here (the pre-fault point, the solution before the fault)."""
    fault, nbus = ss.Fault, ss.Bus.n
    apply, clear = fault.tf.callback, fault.tc.callback
    stored = {}

    def apply_keeping_angles(is_time):
        before = ss.dae.y[:nbus].copy()
        out = apply(is_time)
        if out:
            stored["a"] = before
        return out

    def clear_restoring_angles(is_time):
        out = clear(is_time)
        if out and fault.config.restore and "a" in stored:
            ss.dae.y[:nbus] = stored["a"]
        return out

    fault.tf.callback = apply_keeping_angles
    fault.tc.callback = clear_restoring_angles


def keep_ipmax_restore_angles(ss) -> None:
    """`keep_reeca1_ipmax` and `restore_fault_angles`, both."""
    keep_reeca1_ipmax(ss)
    restore_fault_angles(ss)


#: the sweep of bus faults (benchmarks/converter_bus_faults.py, tests/io/test_andes.py
#: test_converter_case_bus_faults_match_andes): each bus of the case in turn, through
#: j x pu (X_FAULT, by the case's folder) from 1 s for 6 cycles (60 Hz: cleared at 1.1 s),
#: 3 s, both tools' trapezoid at 5 ms (ANDES's step held, its event steps 1e-7 s), PV Q
#: limits off, ANDES edited by `keep_ipmax_restore_angles`.  x: Kundur's own Fault
#: record's 1e-4 pu; on IEEE 14 ANDES's Newton iteration fails at the fault instant
#: through j1e-4 pu at 11 of ieee14_solar's 14 buses (stabctl runs them), and runs
#: through j1e-3 pu, the value of the IEEE 14 converter tests above
X_FAULT = {"kundur": 1e-4, "ieee14": 1e-3}
CYCLES, T_END = 6, 3.0
#: the stored ANDES traces' grid (s): its points on multiples of DECIMATE (the speeds are
#: smooth; P and Q jump at the events, whose points `algebraic_gaps` leaves out anyway)
DECIMATE = 0.01


def fault_x(name):
    """The sweep's fault reactance (pu) for ANDES's case ``name`` (``folder/file``)."""
    return X_FAULT[name.split("/")[0]]


def andes_sweep_run(path, bus, x):
    """ANDES's run of the sweep's fault at ``bus`` of the case file ``path``, through j x pu
    (`keep_ipmax_restore_angles`): its points on the `DECIMATE` grid of ``t``, the GENROU
    speeds ``wa`` and their ``buses``, the converter's ``Pa``, ``Qa`` (its REGCP1 if it
    has one, else its REGCA1), and ``ran`` 1 if it ran to `T_END`, 0 where it stopped
    (its values up to there)."""
    ss = andes_system(
        path,
        fault=AndesFault(bus, 1.0, 1.0 + CYCLES / 60, x=x),
        off=("Toggle", "Fault"),
        event_eps=1e-7,
        fixed_step=True,
        edit=keep_ipmax_restore_angles,
    )
    try:
        andes_speeds(ss, T_END, STEP)
        ran = 1
    except RuntimeError:
        ran = 0
    t = np.array(ss.dae.ts.t)
    keep = np.abs(t - np.round(t / DECIMATE) * DECIMATE) <= 2.5e-7
    order = np.argsort(np.array(ss.GENROU.gen.v, dtype=float))
    wa = np.asarray(ss.dae.ts.x)[:, ss.GENROU.omega.a[order]]
    P, Q = andes_converter_powers(ss, "REGCP1" if ss.REGCP1.n else "REGCA1")
    return dict(
        t=t[keep],
        wa=wa[keep],
        buses=andes_machine_buses(ss),
        Pa=P[keep],
        Qa=Q[keep],
        ran=ran,
    )


def sweep_case(ref, name, buses=None):
    """The sweep at each bus of ANDES's case ``name`` (or at ``buses``): per bus a dict of
    ``bus``, ``stabctl`` (None where it ran to `T_END`, else the time it stopped, s, and
    ``why`` its message),
    ``andes`` (None or where it stopped), and, where both have values past the
    clearing, ``dw``, ``dP``, ``dQ``: the largest speed (GENROU) and converter P, Q gaps
    (pu) on ANDES's stored grid up to the earlier stop.  ANDES's runs through ``ref``
    (tag ``bus<k>``)."""
    path, case = like_for_like_case(name)
    sim = Simulator(case, q_limits=False)
    t_clear, x = 1.0 + CYCLES / 60, fault_x(name)
    rows = []
    for bus in case.buses.number.astype(int) if buses is None else buses:
        a = ref.run(f"bus{bus}", lambda bus=bus: andes_sweep_run(path, int(bus), x))
        row = dict(bus=int(bus), stabctl=None, andes=None if a["ran"] else float(a["t"][-1]))
        try:
            res = sim.run([Fault(int(bus), 1.0, t_clear, x=x)], T_END, h=STEP, method="trapezoid")
        except SimulationError as exc:
            part = exc.result
            row["stabctl"] = float(part.t[-1]) if part is not None else float("nan")
            row["why"] = str(exc)
            rows.append(row)
            continue
        a = dict(a)
        within = a["t"] <= min(float(res.t[-1]), float(a["t"][-1]))
        a.update({k: a[k][within] for k in ("t", "wa", "Pa", "Qa")})
        if a["t"][-1] > t_clear + 0.05:
            run = paired_run(res, case, a)
            row["dw"] = float(run["dw"])
            row["dP"], row["dQ"] = (float(g) for g in power_gaps(run, t_clear, STEP))
        rows.append(row)
    return rows
