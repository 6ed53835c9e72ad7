"""Linearised multi-machine model: the simulator's own equations differentiated numerically
at the power-flow point and handed to python-control as a `control.StateSpace`.

Method (PSTess `svm_mgen`, docs/pst_models.md 9; details and error study in docs/modal.md):
every active state, then every input, is perturbed by +-h, h = rel_step * max(abs(value), 1)
(PSTess: rel_step = 1e-4); each perturbed point is evaluated by `evaluate_kernel`, the
compiled single evaluation behind `DynamicModel.evaluate`, which re-solves the algebraic
network (non-conforming loads included) from the kept-bus voltages of the power flow, so
the network is eliminated exactly as in the simulation; columns are central differences
(f(+h) - f(-h)) / 2h.  The model equations are not written a second time here.

Signal names use '_' where `DynamicModel.state_name` has '.' (python-control reserves '.').
Inputs (columns of B and D, in this order):
    P_esd_B<n>  real power drawn by an energy-storage device at bus n (pu on the system
                base, + absorbs as `stabctl.storage.devices`), injected through `S_extra` at a kept
                bus; by default at every generator's HV bus (`storage.hv_bus`);
    Vref_G<k>   voltage reference of machine k's exciter (pu);
    Pref_G<k>   power reference of machine k's governor (pu on the machine base).
Outputs (rows of C and D, deviations from the operating point):
    omega_G<k>      machine speed (pu);
    omega_coi       centre-of-inertia speed, weights H*MVA (paper eq. 40) (pu), over every
                    machine (`stabctl.dynamics.coi.coi_inertia`);
    omega_rel_G<k>  omega_k - the COI speed of machine k's island (pu): omega_k - omega_coi
                    in a connected network; what the simulator's storage controllers act
                    on (`stabctl.dynamics.coi.coi_of_islands`);
    vmag_B<n>       bus voltage magnitude (pu);
    f_bus_B<n>      bus frequency deviation (Hz) = (d theta_n / dt) / 2 pi, by the chain rule
                    (C, D) = dtheta/dx (A, B) / 2 pi; the term dtheta/du du/dt (an impulse at
                    a step of an ESD input) is not representable and is left out.
States: the active slots of the simulator's state vector in its own (block-major) order,
named by `DynamicModel.state_name`; unused slots (docs/modal.md, "State counts") are left out.
"""

from __future__ import annotations

import warnings
from typing import NamedTuple

import control as ct
import numpy as np
from numba import typeof

from stabctl._jit.arrays import assign, max_abs
from stabctl._jit.background import await_background, compile_in_background
from stabctl._jit.decorators import njit
from stabctl.case import Case, require_case
from stabctl.dynamics.coi import coi_of_islands, coi_weights
from stabctl.dynamics.model import (
    BUS_VOLTAGES,
    DynamicModel,
    KeptBuses,
    KernelOutputs,
    StageConfig,
    active_states,
    call_evaluate,
    check_conventions,
    evaluate_address,
    kernel_network,
    kernel_outputs,
)
from stabctl.errors import (
    InputError,
    SimulationError,
    WrongTypeError,
    bus_numbers,
    is_number,
    require_flag,
)
from stabctl.models import converters as conv
from stabctl.models import exciters as exc
from stabctl.models import governors as gov

REL_STEP = 1e-4  # PSTess svm_mgen's relative perturbation
KINK_RATIO = 1e-2  # one-sided slopes differing more than this: a limit was crossed
#: a kink is checked again at 1/KINK_CHECK of the step: if the one-sided slopes still
#: differ by more than KINK_KEPT of what they did, it is at the point itself (a limit
#: crossed within the step falls away: Kundur's PSS limit at rel_step 1e-3, 60 % -> 11 %)
KINK_CHECK, KINK_KEPT = 4, 0.5
#: a column taken again at 1/KINK_CHECK of its step that moves by more than SATURATION_TOL
#: of its largest entry was not linear over +-step: a limiter saturated on both sides (a
#: high-gain path, e.g. the 240-bus WECC's IEEEST, 3900 pu/pu from speed to its output, at
#: +-0.1: its speed columns came out 13 times too small and the report found unstable
#: modes the run does not have); it is taken at smaller steps until it settles, at most
#: SATURATION_ROUNDS times
SATURATION_TOL, SATURATION_ROUNDS = 1e-3, 8
#: a limit active at the operating point: one side of a perturbation changes a derivative by
#: at most UNCHANGED times the column's largest change (exactly 0 on its limit, round-off of
#: a state a hair inside it: IEEE 14's valve 3.3e-12 above VMIN), the other by more than MOVED
UNCHANGED, MOVED = 1e-6, 1e-3
STATE, ESD, VREF, PREF = 0, 1, 2, 3
#: a state taken held whose own derivative its limit holds too: left out of the linear model
FROZEN = 2
#: what linearise does with a limit active at the operating point (a column whose one side
#: leaves a derivative unchanged that the other side moves), `linearise` limits
AUTO = 2
LIMIT_RULES = {"auto": AUTO, "hold": 1, "free": -1, "refuse": 0}
#: `_held_side` of a column that meets limits on both sides, each derivative on one side
#: (two limited controllers blocked in opposite directions: a WTPTA1's speed and
#: compensation pitch PIs both at the minimum pitch, a perturbation of the torque
#: controller's speed reference frees one and drives the other into its limit)
MIXED = 3
#: auto: the free side counts as linear in h when halving h halves its change within this
LINEAR_TOL = 0.1


class Perturbations(NamedTuple):
    """The difference columns of `_differences`, each array of shape (n_col,): kind what
    is perturbed (STATE, ESD, VREF, PREF; int64), which which one (STATE: flat state
    index; ESD: kept-bus position; VREF: exciter row; PREF: governor row; int64), step
    the perturbation h (in the unit of the perturbed quantity); rule the
    `LIMIT_RULES` value for limits active at the operating point."""

    kind: np.ndarray
    which: np.ndarray
    step: np.ndarray
    rule: int


class Differences(NamedTuple):
    """What `_differences` fills: J (n_col, n_x) d(dx/dt)/d(column), dV (n_col, n_bus)
    complex d(V_bus)/d(column), curv (n_col,) the kink measure max|f+ - 2 f0 + f-| /
    max|f+ - f-| of each column, V0 (n_bus,) complex the bus voltages at the operating
    point, held (n_col,) int8: where a limit is active at the operating point
    (`_held_side`), 1 if the column was taken with it held, -1 free, 0 no such limit,
    FROZEN a state held on its own limit."""

    J: np.ndarray
    dV: np.ndarray
    curv: np.ndarray
    V0: np.ndarray
    held: np.ndarray


def default_esd_buses(case: Case) -> list[int]:
    """The HV bus of every generator (`storage.hv_bus`), each bus once, in machine order."""
    from stabctl.storage.devices import hv_bus

    return list(dict.fromkeys(hv_bus(case, int(k)) for k in case.machines.number))


def linearise(
    target,
    esd_buses=None,
    extra_buses=(),
    rel_step: float = REL_STEP,
    conventions: str = "ieee",
    q_limits: bool = True,
    limits: str = "auto",
):
    """Linearised model of a case at its power-flow point, as a `control.StateSpace`.

    Central differences of the simulator's own equations (PSTess ``svm_mgen``,
    docs/pst_models.md 9; module docstring for the signals, docs/modal.md for the error
    study).

    Parameters
    ----------
    target : Case or Simulator
        A Case (its power flow is solved and a Simulator built) or a
        `stabctl.dynamics.driver.Simulator` (its operating point, conventions and
        cached models are used).
    esd_buses : iterable of int or None, optional
        Bus numbers with an ESD power input ``P_esd_B<n>`` (pu on the system base,
        + absorbs); None (default): every generator's HV bus (`default_esd_buses`).
    extra_buses : iterable of int, optional
        Further ESD buses, appended (repeats ignored); default none.
    rel_step : float, optional
        Relative perturbation h / max(abs(value), 1), in (0, 0.1); default PSTess's 1e-4
        (REL_STEP).
    conventions : {"ieee", "pstess"}, optional
        Model conventions when `target` is a Case (a Simulator keeps its own); default
        "ieee".  At a power-flow point inside every limit both give the same linear model.
    q_limits : bool, optional
        PV Q limits in the power flow when `target` is a Case (as `Simulator`); default
        True.
    limits : {"auto", "hold", "free", "refuse"}, optional
        A limit active at the operating point (an anti-windup integrator or a clipped
        signal on its limit there, e.g. a wind turbine's pitch at its minimum, a torque
        PI at its maximum): the model is not differentiable there, one side of a
        perturbation meets the limit, the other does not.  "hold": the limit holds, the
        slope of the side it clamps; "free": the other side's; "auto" (default): free
        when the other side's change is linear in the step (the state reached the limit
        with no drive beyond it: small-signal analysis with the limit inactive, as
        ANDES 2.0 frees a valve exactly at VMIN), held when it jumps (a state driven
        into its limit, held there as ANDES's ``AntiWindup`` flags freeze it,
        andes/core/discrete.py; such a state, its own rate held at 0, is left out of the
        model); "refuse": SimulationError.  A column that meets limits on both sides,
        each derivative on one (two limited controllers blocked in opposite
        directions: a WTPTA1's speed and compensation pitch PIs at the minimum pitch),
        is taken derivative by derivative by the same rule ("auto": free when each
        free side is linear in the step).  A `UserWarning` names
        the columns and the choice; a limit crossed within the step but not active at
        the point still raises (a smaller rel_step helps).

    Returns
    -------
    control.StateSpace
        Continuous-time model with named states, inputs and outputs (module docstring):
        A (n_x, n_x), B (n_x, n_u), C (n_y, n_x), D (n_y, n_u), n_x the number of active
        states, n_u = n_esd + n_exciters + n_governors inputs (``P_esd_B<n>``,
        ``Vref_G<k>``, ``Pref_G<k>``), n_y = 2 n_mac + 1 + 2 n_bus outputs
        (``omega_G<k>``, ``omega_coi``, ``omega_rel_G<k>`` in pu speed, ``vmag_B<n>`` in
        pu, ``f_bus_B<n>`` in Hz), deviations from the operating point.

    Raises
    ------
    UnknownBusError
        An ESD bus not in the case.
    InputError
        `rel_step` not in [MIN_REL_STEP, 0.1); unknown conventions or limits.
    SimulationError
        The network did not solve at a perturbed point, a perturbation crossed a limiter
        not active at the operating point (the linearisation would be meaningless), or
        one active there with limits="refuse".
    CaseError, PowerFlowError
        As `Simulator` when `target` is a Case.
    TypeError
        `target` neither a Case nor a Simulator.

    Examples
    --------
    Kundur's system: 56 states, inputs the ESD powers at the generators' HV buses (then
    the voltage and power references), outputs the speeds first:

    >>> import stabctl
    >>> lin = stabctl.linearise(stabctl.Simulator(stabctl.load_case("kundur")))
    >>> lin.nstates, lin.input_labels[:2], lin.output_labels[0]
    (56, ['P_esd_B10', 'P_esd_B20'], 'omega_G1')
    """
    from stabctl.dynamics.driver import Simulator

    check_conventions(conventions)  # a Simulator keeps its own, but no other value is one
    if esd_buses is not None:
        esd_buses = bus_numbers(esd_buses, "linearise(esd_buses)")
    extra_buses = bus_numbers(extra_buses, "linearise(extra_buses)")
    require_flag(q_limits, "linearise(q_limits)")
    if not isinstance(target, Simulator):
        target = require_case(target, "linearise(target)", " or Simulator")
    sim = (
        target
        if isinstance(target, Simulator)
        else Simulator(target, conventions=conventions, q_limits=q_limits, background_compile=False)
    )
    case = sim.case
    buses = list(default_esd_buses(case) if esd_buses is None else esd_buses)
    buses = list(dict.fromkeys(int(b) for b in [*buses, *extra_buses]))
    case.bus_indices(buses)
    return linearise_model(sim.model_for(buses), buses, rel_step, limits)


def linearise_model(
    model: DynamicModel, esd_buses=(), rel_step: float = REL_STEP, limits: str = "auto"
):
    """`linearise` on a built model whose reduced network keeps every bus of esd_buses.

    Raises InputError when an ESD bus is not kept, plus the errors of `linearise`.
    """
    _check_difference_settings(rel_step, limits)
    case = model.case
    pos = _kept_positions(model, esd_buses)
    act = np.nonzero(active_states(model))[0]
    kind, index, values = _columns(model, act, pos)
    step = rel_step * np.maximum(np.abs(values), 1.0)
    on_lvg = _lvg_flat(model)[1]
    if on_lvg.size:
        rows = ", ".join(str(int(case.converters.number[k])) for k in on_lvg)
        warnings.warn(
            f"{case.name}: converter(s) {rows}"
            " sit on their low-voltage gain's breakpoint Lvpnt1 at the operating point, where it"
            " has no derivative: linearised on its flat side (as ANDES's EIG)",
            stacklevel=3,
        )
    J, dV, V0, held = jacobian_columns(model, kind, index, step, limits)
    if held.any():
        how = {1: "held", -1: "free", FROZEN: "held, frozen: left out"}
        names = [f"{_what(model, kind, index, c)} ({how[held[c]]})" for c in np.nonzero(held)[0]]
        warnings.warn(
            f"{case.name}: {len(names)} perturbation(s) meet a limit active at the "
            f"operating point (limits={limits!r}): {', '.join(names)}",
            stacklevel=3,
        )
    n = act.size
    moving = held[:n] != FROZEN  # a frozen state does not move: not a state of the model
    rows = np.r_[np.nonzero(moving)[0], n : len(kind)]
    J, dV, act = J[rows], dV[rows], act[moving]
    n = act.size
    A, B = J[:n, act].T, J[n:, act].T
    C, D = output_matrices(model, act, A, B, dV[:n].T, dV[n:].T, V0)
    return ct.ss(
        A,
        B,
        C,
        D,
        states=[signal_name(model.state_name(int(k))) for k in act],
        inputs=_input_names(case, esd_buses, model),
        outputs=output_names(case),
        name=f"{case.name} linearised",
    )


class InputColumns(NamedTuple):
    """The ESD-input columns of a linearised model's B alone (`esd_columns`): B (n_x,
    n_esd) d(dx/dt)/d(P_esd) (per pu on the system base), state_labels (n_x,) and
    input_labels (n_esd,) named as `linearise` names them; what
    `stabctl.stability.sime.distribution_factors` reads of a `control.StateSpace`."""

    B: np.ndarray
    state_labels: list
    input_labels: list


def esd_columns(sim, esd_buses, rel_step: float = REL_STEP, limits: str = "auto") -> InputColumns:
    """The columns of `linearise`'s B for ESD power inputs at `esd_buses` only, without A.

    The same central differences of the simulator's own equations as `linearise` (the
    same columns to round-off), one pair of evaluations per bus instead of one per state
    and input: ACTIVSg2000's 90 generator HV buses in about a second where the whole
    model (6 467 states) takes 50 s.  Every active state is a row: a state that
    `linearise` leaves out as frozen on a limit (its own column needed to tell) keeps its
    row here, 0 wherever the limit holds it.

    Parameters
    ----------
    sim : Simulator
        The simulator of the case (its operating point and conventions).
    esd_buses : iterable of int
        Bus numbers of the ESD inputs ``P_esd_B<n>``, in order (repeats ignored).
    rel_step, limits
        As `linearise`.

    Returns
    -------
    InputColumns
        B (n_x, n_esd), state and input labels.

    Raises
    ------
    UnknownBusError
        An ESD bus not in the case.
    InputError, SimulationError
        As `linearise`.
    """
    _check_difference_settings(rel_step, limits)
    buses = list(dict.fromkeys(int(b) for b in esd_buses))
    sim.case.bus_indices(buses)
    model = sim.model_for(buses)
    pos = _kept_positions(model, buses)
    act = np.nonzero(active_states(model))[0]
    kind = np.full(pos.size, ESD, np.int64)
    J, _, _, _ = jacobian_columns(model, kind, pos, np.full(pos.size, rel_step), limits)
    return InputColumns(
        B=J[:, act].T,
        state_labels=[signal_name(model.state_name(int(k))) for k in act],
        input_labels=[f"P_esd_B{b}" for b in buses],
    )


def perturbation_error(target, rel_step: float = REL_STEP, factor: float = 10.0, **kw) -> dict:
    """Estimated finite-difference error of `linearise(target, rel_step=rel_step)`.

    Linearises again with rel_step / factor and compares: the truncation error of central
    differences falls as h^2 and the round-off of the network solution (load iteration to
    1e-10) grows as 1/h, so the difference bounds the error at the step where the larger of
    the two dominates (docs/modal.md, "Perturbation error").  kw go to `linearise`.

    Returns {"rel_step", "compare_step", "A", "B", "C", "D": max |difference| / max |entry|
    of each matrix, "eig": max |delta lambda| / max(|lambda|, 1) over all eigenvalues,
    "freq_hz", "damping": max change of the frequency and damping ratio of the
    oscillatory modes between F_MIN_HZ and F_MAX_HZ (stabctl.smallsignal.modal)}.
    """
    from stabctl.smallsignal.modal import F_MAX_HZ, F_MIN_HZ

    a = linearise(target, rel_step=rel_step, **kw)
    b = linearise(target, rel_step=rel_step / factor, **kw)
    out = {"rel_step": rel_step, "compare_step": rel_step / factor}
    for key in "ABCD":
        x, y = np.asarray(getattr(a, key)), np.asarray(getattr(b, key))
        out[key] = float(np.abs(x - y).max() / max(np.abs(x).max(), 1e-300)) if x.size else 0.0
    la_, lb = np.linalg.eigvals(a.A), np.linalg.eigvals(b.A)
    match = lb[np.argmin(np.abs(la_[:, None] - lb[None, :]), axis=1)]
    out["eig"] = float(np.max(np.abs(la_ - match) / np.maximum(np.abs(la_), 1.0)))
    f = lambda z: np.abs(z.imag) / (2 * np.pi)  # noqa: E731
    osc = (f(la_) >= F_MIN_HZ) & (f(la_) <= F_MAX_HZ)
    out["freq_hz"] = float(np.max(np.abs(f(la_) - f(match))[osc], initial=0.0))
    zeta = lambda z: -z.real / np.abs(z)  # noqa: E731
    out["damping"] = float(np.max(np.abs(zeta(la_[osc]) - zeta(match[osc])), initial=0.0))
    return out


def compare_pulse(
    sim,
    sys,
    bus: int,
    P: float = 0.05,
    t_on: float = 0.5,
    width: float = 0.125,
    t_end: float = 6.0,
    h: float = 1 / 1024,
    edge: float = 0.02,
) -> dict:
    """Responses of the linear model `sys` and of the nonlinear simulator `sim` to a power
    pulse drawn at `bus`: P pu (system base) from t_on for `width` s.

    Nonlinear: two `LoadStep` events (a constant conductance G = P / |V0|^2 switched in and
    out, so the power drawn is P (|V| / |V0|)^2, equal to P to first order) with 'exact'
    event semantics and step h.  Linear: the 'P_esd_B<bus>' column of sys discretised with
    a zero-order hold, exact for the piecewise-constant pulse.  Times must be multiples of h.

    Returns, per output group ("omega", "omega_rel", "vmag", "f_bus"), (max |linear -
    nonlinear|, max |nonlinear deviation|); f_bus of the simulation is the time derivative
    of the unwrapped bus angles / 2 pi, compared outside +-edge s of the pulse edges (the
    linear model leaves out the angle jump there, module docstring).
    Raises InputError when bus is not an ESD input of sys or a time is not on the grid.
    """
    from stabctl.dynamics.events import LoadStep

    name = f"P_esd_B{int(bus)}"
    if name not in sys.input_labels:
        raise InputError(f"{name} is not an input of the linear model")
    if any(abs(v / h - round(v / h)) > 1e-9 for v in (t_on, width, t_end)):
        raise InputError("t_on, width and t_end must be multiples of the step h")
    res = sim.run(
        [LoadStep(int(bus), t_on, P), LoadStep(int(bus), t_on + width, -P)],
        t_end=t_end,
        h=h,
        semantics="exact",
    )
    j = sys.input_labels.index(name)
    col = ct.ss(sys.A, sys.B[:, [j]], sys.C, sys.D[:, [j]])
    k = np.arange(res.t.size)
    u = np.where((k >= round(t_on / h)) & (k < round((t_on + width) / h)), P, 0.0)
    y = ct.forced_response(ct.sample_system(col, h, method="zoh"), k * h, u).outputs.T
    lab = sys.output_labels
    pick = lambda prefix, nums: y[:, [lab.index(f"{prefix}_{n}") for n in nums]]  # noqa: E731
    G = [f"G{int(m)}" for m in res.machines]
    B = [f"B{int(b)}" for b in res.buses]
    f_nl = np.gradient(np.unwrap(res.vang, axis=0), res.t, axis=0) / (2 * np.pi)
    away = (np.abs(res.t - t_on) > edge) & (np.abs(res.t - t_on - width) > edge)
    pairs = {
        "omega": (pick("omega", G), res.speed - 1.0),
        "omega_rel": (pick("omega_rel", G), res.relative_speed),
        "vmag": (pick("vmag", B), res.vmag - res.vmag[0]),
        "f_bus": (pick("f_bus", B)[away], f_nl[away]),
    }
    return {
        key: (float(np.abs(lin - nl).max()), float(np.abs(nl).max()))
        for key, (lin, nl) in pairs.items()
    }


#: the smallest relative step of the central differences: below it a difference of two
#: evaluations is round-off (double precision's 1e-16 over a step of 1e-9 leaves about 7
#: digits; round 44: 1e-16 divided by zero inside the kernel, 1e-12 blamed a limiter)
MIN_REL_STEP = 1e-9


def _check_difference_settings(rel_step: float, limits: str) -> None:
    """InputError for a rel_step outside [MIN_REL_STEP, 0.1) (WrongTypeError: not a
    number) or an unknown limits rule."""
    if not is_number(rel_step):
        raise WrongTypeError(f"rel_step must be a number, got {rel_step!r}")
    if not MIN_REL_STEP <= rel_step < 0.1:
        raise InputError(
            f"rel_step must be in [{MIN_REL_STEP:g}, 0.1), got {rel_step} (below {MIN_REL_STEP:g} "
            "the central differences are round-off)"
        )
    if limits not in LIMIT_RULES:
        raise InputError(f"limits must be one of {sorted(LIMIT_RULES)}, got {limits!r}")


def _kept_positions(model: DynamicModel, buses) -> np.ndarray:
    """Positions of the ESD buses among the model's kept buses; InputError if not kept."""
    idx = model.case.bus_indices(list(buses)) if len(buses) else np.zeros(0, int)
    pos = np.array([np.searchsorted(model.nc_idx, i) for i in idx], np.int64)
    bad = [b for b, p, i in zip(buses, pos, idx) if p >= model.nc_idx.size or model.nc_idx[p] != i]
    if bad:
        raise InputError(
            f"ESD bus(es) {bad} are not kept in the reduced network: build the "
            "model with them as injection buses (Simulator.model_for)"
        )
    return pos


def _columns(model: DynamicModel, act: np.ndarray, pos: np.ndarray):
    """What each difference column perturbs: (kind, index, nominal value) arrays, states
    first, then ESD powers, Vref of every exciter, Pref of every governor."""
    p = model.params
    n_e, n_g = p.EP.shape[0], p.GP.shape[0]
    kind = np.concatenate(
        [np.full(act.size, STATE), np.full(pos.size, ESD), np.full(n_e, VREF), np.full(n_g, PREF)]
    ).astype(np.int64)
    index = np.concatenate([act, pos, np.arange(n_e), np.arange(n_g)]).astype(np.int64)
    values = np.concatenate(
        [model.x0[act], np.zeros(pos.size), p.EP[:, exc.E.VREF], p.GP[:, gov.G.PREF]]
    )
    return kind, index, values


def jacobian_columns(model: DynamicModel, kind, index, step, limits: str = "auto"):
    """Central differences of all derivatives and bus voltages, one column per perturbation.

    Args:
        model: the dynamic model (pre-disturbance network); kind, index: what to perturb
            (STATE: flat state index; ESD: kept-bus position; VREF: exciter row; PREF:
            governor row), step: h per column, shape (n_col,); limits: a `LIMIT_RULES`
            key, what a column does whose one side a limit active at the operating
            point holds (`linearise`).
    Returns:
        J (n_col, n_x) d(dx/dt)/d(column), dV (n_col, n_bus) complex d(V_bus)/d(column),
        V0 (n_bus,) bus voltages at the operating point, held (n_col,) int8 per column a
        limit active at the operating point taken held (1), free (-1), or none (0).
    Raises:
        SimulationError: a perturbed network did not solve, a column's forward and
            backward slopes differ by more than KINK_RATIO with no limit held at the
            operating point (a limiter within the step: a smaller step helps; as far
            apart at 1/KINK_CHECK of the step: a kink at the point itself, said so), or a limit
            held there with limits="refuse".
    """
    args = _difference_arguments(model, kind, index, step, LIMIT_RULES[limits])
    # cold: _differences compiles in a child process while this one compiles the model
    compile_in_background(_differences, [typeof(a) for a in args])
    args[-1] = evaluate_address(args[3])
    await_background(_differences)
    bad = _differences(*args)
    res = args[5]
    J, dV, curv, V0, held = res
    if bad >= 0:
        raise SimulationError(
            f"the network did not solve with {_what(model, kind, index, bad)} perturbed"
        )
    if limits == "refuse" and held.any():
        k = int(np.nonzero(held)[0][0])
        raise SimulationError(
            f"perturbing {_what(model, kind, index, k)} meets a limit active at the "
            "operating point (one side of the perturbation leaves a derivative unchanged "
            "that the other moves): the linear model differs on the two sides; choose "
            'limits="hold" or "free"'
        )
    k = int(np.argmax(np.where(held != 0, 0.0, curv)))
    if curv[k] > KINK_RATIO:
        what = f"perturbing {_what(model, kind, index, k)} by +-{step[k]:.3g}"
        finer = _curvature(model, kind[k], index[k], step[k] / KINK_CHECK, limits)
        if finer > KINK_KEPT * curv[k]:  # as far apart at the finer step: at the point
            raise SimulationError(
                f"{what} meets a kink at the operating point (one-sided slopes differ by "
                f"{curv[k]:.1%}, by {finer:.1%} at 1/{KINK_CHECK} of the step, with no "
                "derivative left unchanged on one side to tell a held limit): a limit or a "
                "breakpoint of a piecewise-linear function sits at the point itself; the "
                "model has no linearisation there"
            )
        raise SimulationError(
            f"{what} crosses a limiter (one-sided slopes differ by {curv[k]:.1%}, by "
            f"{finer:.1%} at 1/{KINK_CHECK} of the step); use a smaller rel_step"
        )
    _unsaturated(model, np.asarray(kind), np.asarray(index), np.asarray(step, float), limits, res)
    return J, dV, V0, held


def _unsaturated(model: DynamicModel, kind, index, step, limits: str, res) -> None:
    """The columns of ``res`` (`Differences`, J and dV replaced in place) that a limiter
    saturates on both sides of the step taken again at steps KINK_CHECK times smaller
    until they settle (`SATURATION_TOL`): a symmetric saturation leaves no curvature for
    the kink test to see.  Columns with a limit active at the point (held) are one-sided
    by design and left as they are.  Raises SimulationError if a column has not settled
    after SATURATION_ROUNDS smaller steps or its network does not solve."""
    cols = np.flatnonzero(res.held == 0)
    h = step.copy()
    for _ in range(SATURATION_ROUNDS + 1):
        if not cols.size:
            return
        h[cols] /= KINK_CHECK
        args = _difference_arguments(model, kind[cols], index[cols], h[cols], LIMIT_RULES[limits])
        args[-1] = evaluate_address(args[3])
        bad = _differences(*args)
        if bad >= 0:
            raise SimulationError(
                f"the network did not solve with {_what(model, kind, index, cols[bad])} perturbed"
            )
        small = args[5]
        moved = np.abs(small.J - res.J[cols]).max(axis=1)
        off = moved > SATURATION_TOL * np.maximum(np.abs(small.J).max(axis=1), 1e-300)
        res.J[cols[off]] = small.J[off]
        res.dV[cols[off]] = small.dV[off]
        cols = cols[off]
    c = int(cols[0])
    raise SimulationError(
        f"perturbing {_what(model, kind, index, c)} by +-{h[c]:.3g}: the slope still moves "
        f"with the step after {SATURATION_ROUNDS} smaller steps (a limiter saturated at the "
        "point on both sides?); the model has no linearisation there"
    )


def _curvature(model: DynamicModel, kind, index, h: float, limits: str) -> float:
    """max|f+ - 2 f0 + f-| / max|f+ - f-| of one column (`_differences`) at step h (inf
    if its network does not solve)."""
    args = _difference_arguments(model, [kind], [index], [h], LIMIT_RULES[limits])
    args[-1] = evaluate_address(args[3])
    if _differences(*args) != -1:
        return np.inf
    return float(args[5].curv[0])


def _lvg_flat(model: DynamicModel) -> tuple[np.ndarray, np.ndarray]:
    """The converters' packed parameters with each REGCA1 on its low-voltage gain's
    breakpoint at the operating point taken on the flat side, and those rows
    (`stabctl.models.converters.flat_side_of_lvg`)."""
    return conv.flat_side_of_lvg(model.params.IP, np.abs(model.op.V[model.cp.bus_idx]))


def _difference_arguments(model: DynamicModel, kind, index, step, rule: int = 1) -> list:
    """The arguments of `_differences` for `jacobian_columns` (its `Differences` zeroed
    at position 5; the model's address 0 at the end, to be filled in); rule a
    `LIMIT_RULES` value."""
    net = model.network(StageConfig())
    IP, _ = _lvg_flat(model)
    p = model.params._replace(EP=model.params.EP.copy(), GP=model.params.GP.copy(), IP=IP)
    n_col, n_bus = len(kind), model.case.n_bus
    cols = Perturbations(
        np.asarray(kind, np.int64), np.asarray(index, np.int64), np.asarray(step, float), rule
    )
    res = Differences(
        np.zeros((n_col, model.layout.size)),
        np.zeros((n_col, n_bus), np.complex128),
        np.zeros(n_col),
        np.zeros(n_bus, np.complex128),
        np.zeros(n_col, np.int8),
    )
    return [cols, model.x0, model.V_nc0, p, kernel_network(net), res, 0]


def compile_differences(model: DynamicModel) -> None:
    """Compile the linearisation's kernel (`_differences`) for this model's argument types
    in this process, or load it from the on-disk cache, without linearising
    (``stabctl compile``).  The model's evaluation is compiled separately
    (`stabctl.dynamics.model.evaluate_address`): the kernel calls it by address.

    Parameters
    ----------
    model : DynamicModel
    """
    args = _difference_arguments(model, [STATE], [0], [1.0])
    _differences.compile(tuple(typeof(a) for a in args))


#: the owners of states, by their names' first part (`DynamicModel.state_name`), in words
_BLOCKS = {
    "mac": "machine",
    "exc": "exciter",
    "pss": "stabiliser",
    "tg": "governor",
    "ibr": "converter",
}


def _what(model, kind, index, c) -> str:
    """A perturbed column in a planner's words: whose state or set-point it is, its
    machine named as every output names it (``governor state tg.valve.G4 of G4 (bus 6,
    id '1')``, ``Pref of the governor of G4 (bus 6, id '1')``)."""
    case, k = model.case, int(index[c])
    if kind[c] == STATE:
        name = model.state_name(k)
        block, owner = name.split(".", 1)[0], name.rsplit(".", 1)[-1]
        return f"{_BLOCKS.get(block, block)} state {name} of {_owner(case, owner)}"
    if kind[c] == ESD:
        return f"ESD power at kept bus {k + 1}"
    mac = model.ep.mac if kind[c] == VREF else model.gp.mac
    what = "Vref of the exciter" if kind[c] == VREF else "Pref of the governor"
    return f"{what} of {case.machine_name(int(case.machines.number[int(mac[k])]))}"


def _owner(case, owner: str) -> str:
    """``G4`` or ``C17`` (a state name's last part) as outputs name them."""
    if owner[1:].isdigit() and owner[0] == "G":
        return case.machine_name(int(owner[1:]))
    if owner[1:].isdigit() and owner[0] == "C":
        rows = np.flatnonzero(case.converters.number == int(owner[1:]))
        if rows.size:
            return f"{owner} (bus {int(case.converters.bus[rows[0]])})"
    return owner


@njit(cache=True)
def _differences(cols, x0, V_nc0, p, net, res, evaluate):
    """Fill res.J, res.dV with central differences (see jacobian_columns) of the columns
    `cols` (`Perturbations`) and res.curv with max|f+ - 2 f0 + f-| / max|f+ - f-| per
    column; res.V0 with the unperturbed bus voltages (`Differences`).  x0 (n_x,) the
    state and V_nc0 (n_kept,) complex the kept-bus voltages at the operating point, p the
    kernel parameters (EP and GP perturbed in place, restored), net the pre-disturbance
    `KernelNetwork`; evaluate: the address of the model's evaluation (`call_evaluate`;
    the model is not compiled again into this kernel).  Returns -1, or the column whose
    network did not solve (-2: the unperturbed one)."""
    kind, index, step, rule = cols
    J, dV, curv, V0, held = res
    dx = np.zeros_like(x0)  # slots no kernel writes (unused by a model type) must stay 0:
    f0 = np.zeros_like(x0)  # the kink test below looks at every slot
    out = kernel_outputs(p.n_mac, net.R.shape[0], p.n_ibr, p.n_exc)
    S = np.zeros(V_nc0.size, np.complex128)
    at_op = KernelOutputs(
        out.cur, out.pelect, out.qelect, out.eterm, out.efd, out.pmech, V0, out.S_ibr, out.exc_in
    )
    if (
        call_evaluate(
            evaluate,
            x0.copy(),
            p,
            net,
            KeptBuses(V_nc0.copy(), np.zeros(V_nc0.size, np.bool_), S),
            BUS_VOLTAGES,
            f0,
            at_op,
        )
        < 0
    ):
        return -2
    fp, fm = np.zeros_like(x0), np.zeros_like(x0)
    Vp, Vm = np.zeros_like(V0), np.zeros_like(V0)
    for c in range(kind.size):
        j = index[c]
        if kind[c] == STATE:
            nominal = x0[j]
        elif kind[c] == ESD:
            nominal = 0.0
        elif kind[c] == VREF:
            nominal = p.EP[j, exc.E.VREF]
        else:
            nominal = p.GP[j, gov.G.PREF]
        h = step[c]
        hi, lo = nominal + h, nominal - h  # the steps taken are hi - nominal, nominal - lo
        for v, f, V in ((hi, fp, Vp), (lo, fm, Vm)):
            if _perturbed(kind[c], j, v, x0, V_nc0, p, net, S, evaluate, dx, out):
                return c
            assign(f, dx)
            assign(V, out.V_bus)
        curv[c] = max_abs(fp - 2.0 * f0 + fm) / max(max_abs(fp - fm), 1e-300)
        clamp = _held_side(fp, fm, f0)
        if clamp == MIXED:
            cut = (x0, V_nc0, p, net, S, evaluate, dx, out)
            if _rowwise(c, kind[c], j, nominal, h, rule, cut, fp, fm, f0, J, held):
                return c
            assign(dV[c], (Vp - Vm) / (hi - lo))
            continue
        side = clamp * rule  # the side whose one-sided slope is taken (AUTO: below)
        if clamp != 0 and rule == AUTO:
            # the free side linear in h (the limit reached, not driven into): free, else held
            free = fm if clamp > 0 else fp
            v = nominal - clamp * h / 2
            if _perturbed(kind[c], j, v, x0, V_nc0, p, net, S, evaluate, dx, out):
                return c
            linear = max_abs(free - 2.0 * dx + f0) <= LINEAR_TOL * max_abs(free - f0)
            side = -clamp if linear else clamp
        held[c] = 0 if clamp == 0 else (-1 if side == -clamp else 1)
        if held[c] > 0 and kind[c] == STATE:  # FROZEN: its own derivative held at 0 too
            own = (fp[j] if side > 0 else fm[j]) - f0[j]
            if abs(own) <= UNCHANGED * max(max_abs(fp - f0), max_abs(fm - f0)):
                held[c] = FROZEN
        if side > 0:
            assign(J[c], (fp - f0) / (hi - nominal))
            assign(dV[c], (Vp - V0) / (hi - nominal))
        elif side < 0:
            assign(J[c], (f0 - fm) / (nominal - lo))
            assign(dV[c], (V0 - Vm) / (nominal - lo))
        else:
            assign(J[c], (fp - fm) / (hi - lo))
            assign(dV[c], (Vp - Vm) / (hi - lo))
    return -1


@njit
def _perturbed(kind, j, v, x0, V_nc0, p, net, S, evaluate, dx, out) -> bool:
    """Evaluate the model (derivatives into dx, outputs into out) with what column (kind,
    j) perturbs set to v (the parameters restored after); True if the network did not
    solve."""
    x = x0.copy()
    S[:] = 0.0
    if kind == STATE:
        x[j] = v
    elif kind == ESD:
        S[j] = v
    elif kind == VREF:
        saved = p.EP[j, exc.E.VREF]
        p.EP[j, exc.E.VREF] = v
    else:
        saved = p.GP[j, gov.G.PREF]
        p.GP[j, gov.G.PREF] = v
    kept = KeptBuses(V_nc0.copy(), np.zeros(V_nc0.size, np.bool_), S)
    it = call_evaluate(evaluate, x, p, net, kept, BUS_VOLTAGES, dx, out)
    if kind == VREF:
        p.EP[j, exc.E.VREF] = saved
    elif kind == PREF:
        p.GP[j, gov.G.PREF] = saved
    return it < 0


@njit
def _held_side(fp, fm, f0) -> int:
    """The side of a column on which a limit active at the operating point holds: +1 (or
    -1) when the + (-) perturbation leaves some derivative as at f0 (`UNCHANGED`) that
    the other side moves (`MOVED`; a clamp engaged on that side only), and no derivative
    the other way round; MIXED when both show that (each in other derivatives); 0 when
    neither."""
    rows = _clamped_rows(fp, fm, f0)
    plus, minus = np.any(rows > 0), np.any(rows < 0)
    if plus and minus:
        return MIXED
    if plus == minus:
        return 0
    return 1 if plus else -1


@njit
def _clamped_rows(fp, fm, f0) -> np.ndarray:
    """Per derivative: +1 (-1) where the + (-) perturbation leaves it as at f0
    (`UNCHANGED`) and the other side moves it (`MOVED`), else 0 (`_held_side`)."""
    big = max(max_abs(fp - f0), max_abs(fm - f0))
    still, moved = UNCHANGED * big, MOVED * big
    rows = np.zeros(f0.size, np.int8)
    for i in range(f0.size):
        dp, dm = abs(fp[i] - f0[i]), abs(fm[i] - f0[i])
        if dp <= still and dm > moved:
            rows[i] = 1
        elif dm <= still and dp > moved:
            rows[i] = -1
    return rows


@njit
def _rowwise(c, kind, j, nominal, h, rule, model, fp, fm, f0, J, held) -> bool:
    """Column c of a MIXED column, derivative by derivative: one clamped on one side takes
    its free side's slope (limits "free"; "auto" when each free side's change is linear
    in h: the limits reached, not driven into) or its held side's ("hold"), the others
    the central difference; held[c] -1 (free) or 1 (held; FROZEN: a state whose own
    derivative its limit holds).  Under "refuse" held[c] is 1 (refused by the caller).
    model: `_perturbed`'s arguments after v (x0 ... out); fp, fm, f0: the derivatives
    at +h, -h and the point.  True if a network did not solve."""
    x0, V_nc0, p, net, S, evaluate, dx, out = model
    rows = _clamped_rows(fp, fm, f0)
    free = rule == -1
    if rule == AUTO:  # free if each free side's change is linear in h
        free = True
        for s in (1, -1):  # rows clamped on side s move on side -s
            if _perturbed(kind, j, nominal - s * h / 2, x0, V_nc0, p, net, S, evaluate, dx, out):
                return True
            other = fm if s > 0 else fp
            sel = rows == s
            bent = max_abs((other - 2.0 * dx + f0)[sel])
            free = free and bent <= LINEAR_TOL * max_abs((other - f0)[sel])
    for i in range(f0.size):
        if rows[i] == 0:
            J[c, i] = (fp[i] - fm[i]) / (2.0 * h)
        elif (rows[i] > 0) != free:  # the + side: held where clamped on +, free where on -
            J[c, i] = (fp[i] - f0[i]) / h
        else:
            J[c, i] = (f0[i] - fm[i]) / h
    held[c] = -1 if free else 1
    if held[c] > 0 and kind == STATE and rows[j] != 0:
        held[c] = FROZEN
    return False


def output_matrices(model: DynamicModel, act, A, B, dVx, dVu, V0):
    """C (n_out, n_x) and D (n_out, n_u) of the outputs (module docstring).

    dVx (n_bus, n_x), dVu (n_bus, n_u): d V_bus / d(state, input), complex; V0 (n_bus,).
    |V| and theta from dV: d|V| = Re(conj(V0) dV) / |V0|, dtheta = Im(conj(V0) dV) / |V0|^2.
    """
    nm = model.mp.n
    pos = {int(k): i for i, k in enumerate(act)}
    S = np.zeros((nm, act.size))  # omega_k = S x (an infinite bus's: constant)
    swing = [k for k in range(nm) if nm + k in pos]
    S[swing, [pos[nm + k] for k in swing]] = 1.0
    w = model.coi_inertia
    coi = coi_weights(w) @ S
    rel = S - coi_of_islands(S.T, w, model.island).T
    Vm = np.abs(V0)[:, None]
    dmag = lambda dV: (np.conj(V0)[:, None] * dV).real / Vm  # noqa: E731
    dang = lambda dV: (np.conj(V0)[:, None] * dV).imag / Vm**2  # noqa: E731
    Tx = dang(dVx)
    two_pi = 2 * np.pi
    C = np.vstack([S, coi, rel, dmag(dVx), Tx @ A / two_pi])
    D = np.vstack([np.zeros((2 * nm + 1, B.shape[1])), dmag(dVu), Tx @ B / two_pi])
    return C, D


def signal_name(name: str) -> str:
    """python-control reserves '.' for subsystem paths: 'mac.omega.G1' -> 'mac_omega_G1'."""
    return name.replace(".", "_")


def output_names(case: Case) -> list[str]:
    """Output names in order: omega_G<k>, omega_coi, omega_rel_G<k>, vmag_B<n>, f_bus_B<n>."""
    g = [f"G{int(k)}" for k in case.machines.number]
    b = [f"B{int(n)}" for n in case.buses.number]
    return (
        [f"omega_{x}" for x in g]
        + ["omega_coi"]
        + [f"omega_rel_{x}" for x in g]
        + [f"vmag_{x}" for x in b]
        + [f"f_bus_{x}" for x in b]
    )


def _input_names(case: Case, esd_buses, model: DynamicModel) -> list[str]:
    num = case.machines.number
    return (
        [f"P_esd_B{int(b)}" for b in esd_buses]
        + [f"Vref_G{int(num[m])}" for m in model.ep.mac]
        + [f"Pref_G{int(num[m])}" for m in model.gp.mac]
    )
