"""The same PSS/E case and disturbance in ANDES, for cross-validation and benchmarks.

ANDES (CURENT, ``pip install "stabctl[andes]"``) is an optional dependency: only this
module imports it, and only when called. Conventions of the runs, chosen so that both
tools solve the same problem:

* power flow: ANDES's Newton-Raphson with tolerance 1e-12 and its defaults (PV buses
  keep their voltage without Q limits, ``PV.config.pv2pq = 0``);
* dynamics: loads constant impedance (ANDES's default ``PQ.config.p2z = q2z = 1``; import
  the case with ``loads="impedance"``), implicit trapezoidal integration with a fixed step, Newton
  tolerance 1e-8;
* fault: ANDES's ``Fault`` model, a shunt ``rf + j xf`` at the bus from ``tf`` to ``tc``
  (no line lost);
* network: ANDES 2.0's PSS/E reader leaves a non-transformer branch on a 100 MVA base
  while its RAW data are on SBASE, and drops the line-end shunts GI, BI, GJ, BJ (and its
  ``Line`` power-flow equations put the from-end shunt at both ends); before set-up
  (:func:`andes_system`) the branches are put on SBASE and each line-end shunt becomes an
  ANDES ``Shunt`` at its bus, so that ANDES solves the RAW's network (exact while no line
  is switched; a no-op for SBASE = 100 MVA cases without line-end shunts); machines: its
  DYR reader leaves GENROU's and GENCLS's rated frequency ``fn`` at 60 Hz, set to the
  RAW's BASFRQ (N44: 50 Hz);
* records ANDES reads but stabctl does not map are removed from the DYR text for both
  tools (:func:`strip_dyr`), so that the comparison is like for like; optionally the
  machine saturation too (PSS/E's GENROU saturation, which ANDES follows, is not PST's
  ``mac_sub``, which has none; ``conventions="andes"`` reads it as ANDES does).

Source: ANDES 2.0 documentation (``andes.load``, ``System.add``, ``PFlow``, ``TDS``,
``EIG`` routines; ``Fault`` and ``Toggle`` models).
"""

from __future__ import annotations

import functools
import logging
import os
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from stabctl.errors import InputError

__all__ = [
    "AndesFault",
    "strip_dyr",
    "andes_system",
    "andes_powerflow",
    "andes_speeds",
    "andes_machine_buses",
    "andes_modes",
    "andes_separated",
    "andes_stable",
]


@dataclass(frozen=True)
class AndesFault:
    """Three-phase fault at ``bus`` from ``t_fault`` to ``t_clear`` (s) through
    ``r + jx`` (pu, system base), cleared without loss of a line."""

    bus: int
    t_fault: float
    t_clear: float
    r: float = 0.0
    x: float = 1e-4


def _andes():
    """The ``andes`` package, its logger set to print errors only and to write no file.

    ANDES's ``config_logger`` makes a directory ``andes-XXXXXXXX`` in the temporary
    directory (``andes.utils.paths.get_log_dir``: ``tempfile.mkdtemp``) on every call that
    gives no ``log_path``, for a log file it writes only with ``file=True`` (on the first
    call of a process: every ANDES message at DEBUG); given a ``log_path`` and
    ``file=False`` it makes and writes nothing, so that no load leaves a directory behind.
    """
    try:
        import andes
    except ImportError:
        raise InputError("ANDES is not installed: pip install 'stabctl[andes]'") from None
    andes.config_logger(stream_level=40, file=False, log_path=os.devnull)  # not written
    return andes


class _Held(logging.Handler):
    """A log handler that keeps the records it is given (`_andes_log`)."""

    def __init__(self, level: int):
        super().__init__(level)
        self.records: list[logging.LogRecord] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.records.append(record)


@contextmanager
def _andes_log() -> Iterator[list[logging.LogRecord]]:
    """ANDES's log (its logger ``andes``) held for the block instead of printed: the
    records of WARNING and above, for the caller to say what matters in its own words
    (:func:`_andes_said`); ANDES's handlers are put back after."""
    log = logging.getLogger("andes")
    held = _Held(logging.WARNING)
    saved = log.handlers[:], log.propagate, log.level
    log.handlers, log.propagate = [held], False
    log.setLevel(logging.WARNING)
    try:
        yield held.records
    finally:
        log.handlers, log.propagate = saved[0], saved[1]
        log.setLevel(saved[2])


def _andes_said(records: list[logging.LogRecord], exc: BaseException | None = None) -> str:
    """What ANDES said of a failure, one line: its first logged error (held by
    `_andes_log`; it names the model, parameter and device, where the exception it then
    raises often does not), else ``exc``'s message.

    Parameters
    ----------
    records : list of logging.LogRecord
        ANDES's log records.
    exc : BaseException, optional
        The exception ANDES raised.

    Returns
    -------
    str
        At most 300 characters.
    """
    errors = [r.getMessage() for r in records if r.levelno >= logging.ERROR]
    text = errors[0] if errors else (str(exc) if exc is not None else "")
    text = " ".join(text.split())
    return text.removeprefix("Error: ")[:300]  # ANDES's prefix of some


def strip_dyr(
    src: str | Path, dst: str | Path, models, unsaturated: bool = False
) -> tuple[str, ...]:
    """Copy the DYR file ``src`` to ``dst`` without the records of ``models`` (names in
    upper case, e.g. ``{"EXST1", "TOGGLE"}``); returns the removed model names in file
    order. ``unsaturated``: GENROU and GENSAL records get S(1.0) = S(1.2) = 0 (their last
    two CONs), as PST's machines have none (``conventions="andes"`` reads it as ANDES
    does, docs/pst_models.md 1.6a). A record ends at the line
    holding its ``/`` (PSS/E POM, Dynamics Data File)."""
    drop = {m.upper() for m in models}
    kept, record, removed = [], [], []
    for line in Path(src).read_text("latin-1").splitlines(keepends=True):  # bytes kept
        record.append(line)
        if "/" not in line:
            continue
        text = "".join(record)
        model = text.split("'")[1].strip().upper() if text.count("'") >= 2 else ""
        if model in drop:
            removed.append(model)
        else:
            kept.append(_unsaturated(text) if unsaturated and model in _SATURATED else text)
        record = []
    Path(dst).write_text("".join(kept + record), "latin-1")
    return tuple(removed)


_SATURATED = {"GENROU", "GENSAL"}


def _unsaturated(text: str) -> str:
    """The record with its last two numbers (S(1.0), S(1.2)) replaced by 0."""
    body, slash, comment = text.partition("/")
    head, quote, rest = body.rpartition("'")
    fields = rest.split()
    return f"{head}{quote} {' '.join(fields[:-2] + ['0.0', '0.0'])} {slash}{comment}"


def andes_system(
    raw: str | Path,
    dyr: str | Path | None = None,
    fault: AndesFault | None = None,
    config_option=(),
    off=(),
    event_eps: float | None = None,
    fixed_step: bool = False,
    edit=None,
):
    """An ANDES ``System`` of the RAW (+ DYR) files, or of any case file ANDES reads
    (xlsx, json, MATPOWER: ``dyr`` None), with ``fault`` added, set up; config_option:
    ANDES config overrides such as "Runtime.numba=1"; off: ANDES models whose devices are
    switched off (``u = 0``) before set-up, e.g. ``("Toggle",)`` for a case's own
    disturbance.  Only a RAW file gets :func:`_raw_network`'s corrections.

    event_eps: the length (s) of the steps ANDES takes beside each event time
    (``System.store_switch_times``, 1e-4 s by default; None keeps it).  ANDES's trapezoid
    takes the first step after a switch with the derivative stored before it (the switch
    does not recompute it, ``andes/routines/daeint.py``, ``tds.py`` ``do_switch``), so every
    state whose derivative jumps moves at the mean of its old and new rates for that step:
    a delay of about event_eps / 2 whatever the step ``tstep``.  On Kundur's wind turbine
    that delay is 1.0e-3 pu of P and 1.4e-3 of Q with both tools at 0.3125 ms; with 1e-7,
    2.2e-4 and 1.7e-4 (`benchmarks/wind_step_error.py`, docs/ibr.md).

    fixed_step: keep ANDES's trapezoid at its step ``tstep`` (but for the event steps).
    ANDES's "fixed" step is not fixed: after a step that took 7-14 Newton iterations it
    multiplies the next by 0.95, after 15 or more by 0.5, and grows it back by 1.1 up to
    ``tstep`` (``andes/routines/daeint.py`` ``ImplicitIter.niter_next_h``; on Kundur's
    wind turbine at 5 ms, 3.7-4.75 ms steps in the fault and after it).  With fixed_step
    ANDES keeps ``tstep`` after every converged step (a step that does not converge still
    shrinks), so that its run is comparable with stabctl's trapezoid at the same step
    (`stabctl.dynamics.trapezoid`).

    edit: a callable given the System before set-up (after ``off``), to change its data
    (the parameter lists ``ss.<Model>.<param>.v``; tests/io/test_andes.py scales EXDC2's
    VRMAX and VRMIN so)."""
    andes = _andes()
    kw: dict[str, Any] = {} if dyr is None else {"addfile": str(dyr)}
    if config_option:
        kw["config_option"] = list(config_option)
    ss = andes.load(str(raw), setup=False, no_output=True, default_config=True, **kw)
    if event_eps is not None:  # an instance attribute: the TDS calls system.store_switch_times
        ss.store_switch_times = functools.partial(type(ss).store_switch_times, ss, eps=event_eps)
    if fixed_step:
        _hold_step(ss.TDS)
    for name in off:
        model = ss.models[name]
        model.u.v = [0] * model.n
    if Path(raw).suffix.lower() == ".raw":
        _raw_network(ss, raw)
    _repair_esdc1a(ss)
    if edit is not None:
        edit(ss)
    if fault is not None:
        ss.add(
            "Fault",
            {
                "bus": fault.bus,
                "tf": fault.t_fault,
                "tc": fault.t_clear,
                "rf": fault.r,
                "xf": fault.x,
            },
        )
    ss.setup()
    ss.PFlow.config.tol = 1e-12
    return ss


def _hold_step(tds) -> None:
    """Make ANDES's TDS ``tds`` (its trapezoid) take ``tstep`` again after each converged
    step (`andes_system`, fixed_step); a step that does not converge shrinks as in ANDES.
    The TDS sets its method again at ``init`` (``set_method``), so that is where the
    method is replaced."""
    from andes.routines.daeint import Trapezoid

    class FixedStepTrapezoid(Trapezoid):
        @staticmethod
        def calc_h(tds):
            if tds.converged:
                tds.deltat = min(tds.config.tstep, tds.deltatmax)
            else:
                Trapezoid.calc_h(tds)

    set_method = tds.set_method

    def set_fixed(name: str = "trapezoid") -> None:
        set_method(name)
        if type(tds.method) is Trapezoid:
            tds.method = FixedStepTrapezoid()

    tds.set_method = set_fixed
    tds.set_method(tds.config.method)


def _repair_esdc1a(ss) -> None:
    """Before set-up: ANDES 2.0's ESDC1A regulator limiter on its own limits.  ``esdc1a.py``
    replaces ESDC2A's V_t-scaled limits ``VRU``, ``VRL`` by ``VRMAX``, ``VRMIN`` but its
    anti-windup lag ``LA`` (built by ESDC2A) keeps the removed services, which are never
    evaluated: the limit stays the float 0.0 and every ESDC1A case fails at
    initialisation (``TypeError`` in ``do_adjust_upper``; ieee14_esdc1a.xlsx).  Pointing
    ``LA`` and its limiter at the new services gives the model its documented limits."""
    m = ss.models.get("ESDC1A")
    if m is None or not m.n:
        return
    for block in (m.LA, m.LA.lim):
        block.upper, block.lower = m.VRU, m.VRL


def _raw_network(ss, raw) -> None:
    """Before set-up: ANDES's non-transformer ``Line`` rows on the system base (its PSS/E
    reader leaves ``Sn`` at 100 MVA, scaling R, X by SBASE/100 and B by 100/SBASE) and the
    RAW's line-end shunts (dropped by its reader) as ``Shunt`` devices at their buses
    (ANDES's ``Line`` equations would apply ``g1 + j b1`` at both ends); the machines'
    ``fn`` at the RAW's frequency."""
    from stabctl.io.psse_raw import read_raw

    line, mva = ss.Line, ss.config.mva
    for k in range(line.n):
        if not line.trans.v[k]:
            line.Sn.v[k] = mva
    data = read_raw(raw)
    for model in (ss.GENROU, ss.GENCLS):
        model.fn.v = [float(data.freq_hz)] * model.n
    rows = data.line
    vn = dict(zip(ss.Bus.idx.v, ss.Bus.Vn.v))
    for r in rows[np.any(rows[:, 10:14] != 0, axis=1)] if rows.shape[1] > 10 else ():
        for bus, g, b in ((int(r[0]), r[10], r[11]), (int(r[1]), r[12], r[13])):
            ss.add("Shunt", {"bus": bus, "g": float(g), "b": float(b), "Sn": mva, "Vn": vn[bus]})


def andes_powerflow(ss) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Run ANDES's power flow: (bus numbers, |V| pu, angle rad), each shape (n_bus,).
    Raises :class:`RuntimeError` if it does not converge."""
    if not ss.PFlow.run():
        raise RuntimeError("ANDES power flow did not converge")
    return np.array(ss.Bus.idx.v), np.array(ss.Bus.v.v), np.array(ss.Bus.a.v)


def andes_speeds(ss, t_end: float, step: float) -> tuple[np.ndarray, np.ndarray]:
    """Power flow and time-domain run to ``t_end`` (s) with fixed step ``step`` (s):
    (t shape (n_t,), GENROU rotor speeds pu shape (n_t, n_gen), columns in RAW generator
    order). Raises :class:`RuntimeError` if ANDES's run fails."""
    andes_powerflow(ss)
    ss.TDS.config.tf = t_end
    ss.TDS.config.tstep = step
    ss.TDS.config.fixt = 1
    ss.TDS.config.tol = 1e-8
    ss.TDS.config.no_tqdm = 1
    if not ss.TDS.run():
        raise RuntimeError("ANDES time-domain simulation failed")
    order = np.argsort(np.array(ss.GENROU.gen.v, dtype=float))
    t = np.array(ss.dae.ts.t)
    return t, np.asarray(ss.dae.ts.x)[:, ss.GENROU.omega.a[order]]


def andes_converter_powers(ss, model: str) -> tuple[np.ndarray, np.ndarray]:
    """The active and reactive powers the in-service devices of an ANDES converter model
    (``"PVD1"``, ``"ESD1"``, ``"REGCA1"``, ``"REGCP1"``) injected in the run of
    :func:`andes_speeds`, ANDES's ``Pe = Ipout_y v``, ``Qe = Iqout_y v``
    (``andes/models/distributed/pvd1.py``, class docstring; REGCA1, REGCP1: their algebraic
    ``Pe``, ``Qe``, ``renewable/regca1.py`` 280-283, ``regcp1.py``): (P, Q), each shape
    (n_t, n_dev), pu on the system base, devices in ANDES's
    order (the order :func:`stabctl.io.andes_case.import_andes` numbers them)."""
    m = ss.models[model]
    on = [k for k in range(m.n) if m.u.v[k]]
    x, y = np.asarray(ss.dae.ts.x), np.asarray(ss.dae.ts.y)
    if model in ("REGCA1", "REGCP1"):
        return y[:, m.Pe.a[on]], y[:, m.Qe.a[on]]
    v = y[:, m.v.a[on]]
    return x[:, m.Ipout_y.a[on]] * v, x[:, m.Iqout_y.a[on]] * v


def andes_machine_buses(ss) -> np.ndarray:
    """Bus numbers of :func:`andes_speeds`'s columns (GENROU in static-generator order),
    shape (n_gen,), to pair them with stabctl's machines."""
    order = np.argsort(np.array(ss.GENROU.gen.v, dtype=float))
    return np.array(ss.GENROU.bus.v, dtype=int)[order]


def andes_modes(ss) -> np.ndarray:
    """Eigenvalues (1/s, complex, shape (n_states,)) of ANDES's linearisation at its
    power flow (``EIG`` routine)."""
    andes_powerflow(ss)
    if not ss.EIG.run():
        raise RuntimeError("ANDES eigenvalue analysis failed")
    return np.asarray(ss.EIG.mu)


def andes_separated(ss) -> bool:
    """After a run: a GENROU rotor angle more than pi rad from the centre of inertia
    (inertia-weighted) at any stored time, stabctl's default criterion.  The weights are
    ANDES's ``GENROU.M`` as it is: ANDES converts M = 2H to the system base at set-up
    (``NumParam(power=True)``), so M is already proportional to H Sn (times Sn again
    would weight by H Sn^2)."""
    delta = np.asarray(ss.dae.ts.x)[:, ss.GENROU.delta.a]
    m = np.asarray(ss.GENROU.M.v)
    coi = delta @ m / m.sum()
    return bool(np.max(np.abs(delta - coi[:, None])) > np.pi)


def andes_stable(
    raw: str | Path, dyr: str | Path, fault: AndesFault, t_end: float, step: float
) -> bool:
    """ANDES's verdict on ``fault``: a run to ``t_end`` (s, fixed ``step``) without its own
    stop criterion, stable unless a rotor angle leaves the COI by more than pi rad or the
    run breaks down (machines slipping poles)."""
    ss = andes_system(raw, dyr, fault)
    ss.TDS.config.criteria = 0
    try:
        andes_speeds(ss, t_end, step)
    except RuntimeError:
        return False
    return not andes_separated(ss)
