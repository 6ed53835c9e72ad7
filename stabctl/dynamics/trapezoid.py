"""Implicit trapezoidal integration of the simulator's model (``Simulator.run(method=
"trapezoid")``), the method ANDES 2.0 integrates with (``andes/routines/daeint.py``
``Trapezoid``), for like-for-like comparisons with it and for stiff cases at long steps.

Each step solves x_k+1 = x_k + h/2 (f(x_k) + f(x_k+1)) on the grid of
`stabctl.dynamics.grid` (every event time a grid point, the network of the interval the step
lies in: the "exact" semantics), f being the model's own evaluation
(`stabctl.dynamics.model.evaluate_kernel`, the network and loads solved inside it). The
solution is a chord Newton iteration on the model's states
(`stabctl.dynamics.model.active_states`) with the matrix I - h/2 A, A = df/dx by forward
differences of the same evaluation, factorised once per network stage and again after an
iteration that is slow to converge (above `SPARSE_ABOVE` states: sparse, its smallest
entries left out, kept into the next stage until an iteration is slow, and the columns of
the exciters', stabilisers' and governors' states of distinct machines differenced
together, `_column_groups`). Non-windup
limits follow ANDES's AntiWindup (``andes/core/discrete.py``; IEEE 421.5-2016 E.5): a state
the evaluation has set on its limit in this step (the limiter's reach 0,
`stabctl.models.blocks.nonwindup`) is held there, its residual and its correction zero,
while its derivative stays zero; held at an iterate after the LOCK-th, it stays held for the
step (ANDES's ``niter_lock``, against chattering on a limit that moves with the iterate).
After the LOCK-th iterate a state the evaluation has clamped at that iterate whose rule
update x_k + h/2 (f(x_k) + f(x_k+1)) lies past the limit is held on it too, though its
derivative there points back inside (`_pushed`): the rule's equation has no solution
within the limits (its residual keeps the sign that pushes the state out), the
evaluation clamps every Newton correction back onto the limit (a clamp's derivative is
0, so the iteration cannot move the state) and, its derivative not being 0, the hold
above does not take it; the step then ends on the limit, as PSS/E applies the limits of
its states after each step (the rule's update projected onto the limits).  ANDES leaves
such a state past the limit instead (its AntiWindup frees a state beyond a limit whose
derivative points inside), where stabctl's evaluation does not let a state be.  Without
it, ACTIVSg2000's EXAC2 regulators (K_A 1000, T_A 0.05 s) stalled in its first faulted
step (docs/cli.md) and tests/data/psse/smib_exac2.dyr's in its fifth, until the step was
halved.  Gated at LOCK (by then a converging iteration is near its step's solution,
where a clamped state's residual points inside) it is meant to act only where Newton
would not converge: benchmarks/fingerprint.py's runs and the ANDES comparisons are
bit-identical with it.  Likewise, in an iteration that shrank its last correction by less
than SLOW after the LOCK-th iterate, an integrator the evaluation has stopped at this
iterate (its derivative exactly 0) that ran at an earlier one is held where it stopped:
a non-windup PI (IEEE 421.5-2016 E.6, `stabctl.models.blocks.pi_nonwindup`: EXPIC1's)
stops its integral while its output is at a limit and its input drives it out, without
clamping the state, so that the rule's equation has no solution where the step's update
crosses the output's limit (ACTIVSg2000's EXPIC1 at bus 8079 in its first faulted step at
1/60 s: the integral alternated by 5.4e-3 between stopped and running for 25 iterations,
the step was halved three times).  A state held on a limit at the end of a step starts the next one
(in the same network stage) with derivative 0 while still driven into it, and a held
state's row of the matrix is taken 0 (`_Step.start`, `_Step.factorise`).  The other
slots, the memory of discrete logic (REECA1's timers and held values), are written
by the evaluation at every iterate, as ANDES updates its discrete flags, and advance by
their derivative at the step's start (x_k+1 = x_k + h f(x_k)): a timer (an event flag
extended by a time, REECA1's Thld, Thld2) runs down by h in each step and ends at the
first step end at or past its time, as ANDES's ExtendedEvent compares its end time with
the step's (the rule's mean of the derivatives -1 and 0 has no solution in a step that
ends within half a step of the timer's end: the iterates alternated, kundur_wtdta1's
Ipmax hold ending at 2.1 s). The step is
the grid's, always: ANDES's own "fixed" step shrinks by 0.95 after any step that took 7-14
Newton iterations (``ImplicitIter.niter_next_h``), so a like-for-like comparison holds
ANDES's step too (`stabctl.io.andes.andes_system`, ``fixed_step``).

Above SPARSE_ABOVE states (ACTIVSg2000) the matrix is sparse and a matrix costs seconds
(some 200 iterations), so the iteration keeps it from step to step and from stage to stage
and forms it again only where it would not converge with it (`_too_slow`, at most
MAX_FORMED times a step); the matrix holds every state's free row (`_Step.factorise`) and
the held states' rows are taken out of each solve (`_Step.solve`), so that a matrix formed
while other states were held stays right; the first iterate is one chord iteration from
x_k (x_k + h/2 M^-1 (f0 + f(x_k))) instead of the forward-Euler predictor x_k + h f(x_k),
whose step the stiff regulators (EXAC2 K_A 1000, T_A 0.05 s) took far past their limits.
ACTIVSg2000 with a fault at bus 2021 (1.0-1.1 s, line 2021-2002 tripped) at 1/60 s: 14
matrices in a 1.6 s run and no step halved, against 67 matrices in a 1.3 s run and its
first faulted step halved three times before (docs/cli.md, its PSS/E section).

Heun's predictor-corrector (`stabctl.dynamics.integrator`) stays the simulator's method:
compiled, with the storage devices' switching located inside the step and the PSTess event
semantics. This method is a Python loop around the compiled evaluation; it takes no storage
devices.
"""

from __future__ import annotations

import time
from functools import partial
from typing import Any

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from stabctl.dynamics.coi import coi_of_islands
from stabctl.dynamics.integrator import SPEED_BAND, recording, symptom
from stabctl.dynamics.model import (
    BUS_VOLTAGES,
    NO_BUS_VOLTAGES,
    DynamicModel,
    KeptBuses,
    active_states,
    evaluate_kernel,
    kernel_network,
    kernel_outputs,
)
from stabctl.dynamics.partition import judged_relative, stage_at
from stabctl.dynamics.results import SimulationResult
from stabctl.errors import NumericalInstabilityError, SimulationError
from stabctl.network.solution import V_RELEASE, L, no_solution_hint

#: Newton's convergence: the largest correction of a state below TOL (pu, rad)
TOL = 1e-10
#: iterations of one step at most; the matrix is formed again at the iterate after an
#: iteration that shrank the correction by less than SLOW (not twice in a row)
MAX_ITER, SLOW = 30, 0.25
#: an iteration that has not converged in MAX_ITER is accepted if its last STALL
#: corrections are all below STALL_TOL: a state on a limiter's kink (a non-windup limit
#: that moves with the iterate, REGCA1's LVPL) alternates between held and free by less
#: than that.  ANDES accepts any step whose correction is below 1e-4 (TDS tol).
STALL, STALL_TOL = 10, 1e-5
#: a step whose iteration does not converge is taken as two half steps, each again, at
#: most HALVINGS times
HALVINGS = 3
#: after this many iterations a state held on its limit stays held for the step (ANDES's
#: AntiWindup ``niter_lock``, against chattering)
LOCK = 4
#: `_Step`'s mark of a step whose network/load equations had no solution at an iterate
NO_NETWORK = -2
#: forward-difference step of the Jacobian, relative to max(1, |x|) (as the linearisation)
REL_STEP = 1e-7
#: above this many active states the matrix I - h/2 A is factorised sparse
#: (`scipy.sparse.linalg.splu`) with its entries below SPARSE_DROP in magnitude left out; at
#: or below it dense (`scipy.linalg.lu_factor`), as before.  ACTIVSg2000 (6467 active
#: states, A 9 % full): the dense LU took 16 s and each solve 52 ms (a 335 MB triangular
#: pass per Newton iteration); sparse with the drop, 1.5 s and 15 ms.  Dropping entries
#: only changes the chord iteration's matrix, not the equation it solves (the residual is
#: exact): the converged step is the same within TOL, the iteration contracts by about
#: 3e-4 more per iterate there (the matrix's dropped part, measured).
SPARSE_ABOVE, SPARSE_DROP = 2000, 1e-6
#: sparse, the matrix is formed again at most this many times in one step's iteration (a
#: matrix takes seconds there: ACTIVSg2000's first faulted step formed it 14 times in its
#: 30 iterations, alternating on a kink no matrix resolves, before it was halved)
MAX_FORMED = 2
#: sparse, the matrix is formed again only where the iteration will not converge with it
#: within MAX_ITER at the rate of its last iteration, or contracts by less than
#: SLOW_SPARSE, while its correction is above SLOW_FLOOR (`_too_slow`): a matrix costs as
#: much as some 200 iterations there (ACTIVSg2000: 4 to 6 s against 20 ms)
SLOW_SPARSE, SLOW_FLOOR = 0.9, 1e-7


class _Evaluation:
    """The model's evaluation with the run's kept buses: each network stage's matrices, the
    loads held low (released when the stage changes), the outputs of the last call."""

    def __init__(self, m: DynamicModel, nets):
        self.p = m.params._replace(reach=0.0, loads=m.params.loads.copy())
        self.nets = [kernel_network(n) for n in nets]
        n_nc = m.V_nc0.size
        self.kept = KeptBuses(
            V=m.V_nc0.copy(),
            held=np.zeros(n_nc, np.bool_),
            S_extra=np.zeros(n_nc, np.complex128),
        )
        self.out = kernel_outputs(m.mp.n, m.case.n_bus, m.cp.n, m.ep.n)
        self.stage = -1

    def __call__(self, x, stage, want=NO_BUS_VOLTAGES, kept=None) -> np.ndarray:
        """dx/dt at x (clamped in place) with the network of `stage`; kept: other kept-bus
        memory (a copy, for the difference quotients).  Raises SimulationError when the
        loads do not converge."""
        if kept is None:
            kept = self.kept
            if stage != self.stage:
                kept.held[:] = False
                self.stage = stage
        dx = np.zeros_like(x)
        if evaluate_kernel(x, self.p, self.nets[stage], kept, want, dx, self.out) < 0:
            raise SimulationError("the network/load equations did not converge")
        return dx

    def lock(self, on: bool) -> None:
        """Within a step (on), a load held at its impedance model stays held: its release
        voltage is raised out of reach (`stabctl.network.solution.solve_nc`), as ANDES
        locks a flag; at the step's start (off) it is V_RELEASE again."""
        self.p.loads[L.V_release] = np.inf if on else V_RELEASE

    def jacobian(self, x, f_x, stage, act, groups=()) -> np.ndarray:
        """df/dx over the states act (n_act, n_act) at x (derivatives f_x) by forward
        differences of the evaluation, the kept buses' memory untouched.  groups
        (`_column_groups`): columns (over act) differenced together in one evaluation,
        each with the rows (over act) it can reach; the other columns one at a time."""
        A = np.zeros((act.size, act.size))
        for rows, c, column in self._columns(x, f_x, stage, act, groups):
            A[rows, c] = column
        return A

    def chord_matrix(self, x, f_x, stage, act, groups, h) -> sp.csc_matrix:
        """I - h/2 A, A = `jacobian`, sparse, its off-diagonal entries (and the diagonal
        ones of h/2 A) below SPARSE_DROP in magnitude left out: the same numbers as the
        dense matrix thinned, gathered column by column without forming it (ACTIVSg2000:
        a dense A of 6467 x 6467 and the passes over it took 3 s of a matrix's 8)."""
        r_all, c_all, v_all = [], [], []
        for rows, c, column in self._columns(x, f_x, stage, act, groups):
            v = column * (-0.5 * h)
            keep = np.abs(v) >= SPARSE_DROP
            r_all.append(np.arange(act.size)[rows][keep])
            c_all.append(np.full(int(keep.sum()), c))
            v_all.append(v[keep])
        n = act.size
        A = sp.csc_matrix(
            (np.concatenate(v_all), (np.concatenate(r_all), np.concatenate(c_all))), (n, n)
        )
        return (A + sp.identity(n, format="csc")).tocsc()

    def _columns(self, x, f_x, stage, act, groups):
        """The Jacobian's columns (`jacobian`): (rows over act, a slice for all of them;
        column over act; the difference quotients of those rows)."""
        alone = np.ones(act.size, bool)
        for cols, rows in groups:
            q = act[cols]
            d = REL_STEP * np.maximum(1.0, np.abs(x[q]))
            xp = x.copy()
            xp[q] += d
            df = self._difference(xp, f_x, stage, act)
            for c, r, dc in zip(cols, rows, d, strict=True):
                yield r, c, df[r] / dc
            alone[cols] = False
        for c in np.flatnonzero(alone):
            q = act[c]
            d = REL_STEP * max(1.0, abs(x[q]))
            xp = x.copy()
            xp[q] += d
            yield slice(None), c, self._difference(xp, f_x, stage, act) / d

    def _difference(self, xp, f_x, stage, act) -> np.ndarray:
        """f(xp) - f_x over act, with a copy of the kept buses' memory."""
        return self(xp, stage, kept=self.kept_copy())[act] - f_x[act]

    def kept_copy(self) -> KeptBuses:
        """A copy of the kept buses' memory (the extra injections shared)."""
        return KeptBuses(self.kept.V.copy(), self.kept.held.copy(), self.kept.S_extra)


def _record(rec, k, x, out, nm) -> None:
    """Store grid index k as the integrator's compiled `_record` does (a compiled-only
    kernel: no call from Python, tests/test_jit_rules.py)."""
    rec.angle[k], rec.speed[k] = x[:nm], x[nm : 2 * nm]
    rec.pelect[k], rec.pmech[k], rec.efd[k] = out.pelect, out.pmech, out.efd
    rec.V[k] = out.V_bus
    if out.S_ibr.size:
        rec.S_ibr[k] = out.S_ibr


class _Step:
    """The chord Newton iteration of one trapezoidal step (module docstring)."""

    def __init__(self, f: _Evaluation, active: np.ndarray, groups=()):
        self.f, self.act, self.rest = f, np.flatnonzero(active), np.flatnonzero(~active)
        self.sparse = self.act.size > SPARSE_ABOVE
        # the Jacobian's column groups (`_column_groups`), on the sparse path only
        self.groups = groups if self.sparse else ()
        self.key: tuple = ()  # (stage, step) the factorised matrix belongs to (`_key`)
        self.lu: Any = None  # solves with the factorised matrix (`factorise`)
        self.border: dict = {}  # sparse: the held sets' borderings of the matrix (`solve`)
        # the states held on a limit at the last iterate of the last step (derivative 0
        # there) and the side of it (+1 upper, -1 lower): `start`
        self.held_end = np.zeros(0, np.int64)
        self.side = np.zeros(0)

    def start(self, f_x) -> np.ndarray:
        """The derivatives the rule takes at the start of the step that follows the last
        one in the same network stage: f_x, but 0 for a state held on a limit at the last
        step's last iterate that f_x still drives into it.  ANDES's trapezoid takes its
        stored derivative f0 (0 for a state its AntiWindup set on the limit at that
        iterate, which it also resets onto the limit there), the rule of a non-windup
        limit (IEEE 421.5-2016 E.5; WECC REGC_A's LVPL on Ip); stabctl's evaluation at the
        step's end leaves a state held on a limit that moves with other states (REGCA1's
        LVPL of its filtered voltage) below it by the last correction, free, so that the
        rule took the free derivative at the start of the step in which the limit lets
        go: kundur_reg's Ip rose by a whole step (0.276 pu) after the LVPL's release,
        ANDES's by half a step (docs/ibr.md section 12).  The predictor and the matrix
        keep the evaluated f_x (a held state's predictor past its limit clamps it from
        the first iterate)."""
        q = self.held_end
        f0 = f_x.copy()
        if q.size:
            into = f_x[q] * self.side[q] > 0.0
            f0[q[into]] = 0.0
        return f0

    def factorise(self, x, f_x, stage, h, held=None, side=None) -> None:
        """Factorise I - h/2 A at x; held: the rows (over the active states) of the states
        held on a limit there, whose derivative is 0 while held.  Dense, their rows of A
        are taken 0, as ANDES leaves a pegged state's Jacobian row out of its iteration
        (its residual set to 0).  A forward difference there crosses the limit's kink:
        REGCA1's Ip held on its LVPL is freed by a perturbation of the filtered voltage
        the LVPL follows, a derivative of 75 pu/s over 1e-7 (kundur_wtdta1: the next
        iterate's Ip at -700 pu and the step halved twice).

        Sparse (the matrix kept from step to step while the states held change under
        it), A is differenced at x with each held state moved inside its limit (side:
        +1 upper, -1 lower, over all states) by twice its difference step, so that its
        row is its free one (the limiter's kink not crossed), and the rows of the states
        held at an iterate are taken out of the solve there instead (`solve`).  With the
        held rows zeroed in the matrix (before), a state held when the matrix was formed
        and free at a later iterate had a row of 0, its correction the residual itself:
        ACTIVSg2000's EXAC2 V_A (T_A 0.05 s) then converged by h/(2 T_A) = 0.17 an
        iterate at 1/60 s, 5 to 13 iterations a step after its fault and a matrix formed
        again every one or two steps.  A is differenced against one more evaluation at
        that point as the evaluation has clamped it, not against f_x: a state the
        evaluation clamped onto a limit, its derivative pointing inside, keeps in f_x the
        derivative of the iterate before the clamp, and its row of A was that gap over
        the difference step in every column (ACTIVSg2000's first faulted step: EXAC2 V_A
        past VAMAX by 5.4 pu, T_A 0.05 s: 1e9 1/s), a matrix that slowed the iteration it
        was formed for."""
        if self.sparse:
            x = x.copy()
            if held is not None and side is not None and held.any():
                q = self.act[held]
                x[q] -= side[q] * 2.0 * REL_STEP * np.maximum(1.0, np.abs(x[q]))
            f_x = self.f(x.copy(), stage, kept=self.f.kept_copy())
            M = self.f.chord_matrix(x, f_x, stage, self.act, self.groups, h)
            self.lu = spla.splu(M).solve
            self.border = {}
        else:
            A = self.f.jacobian(x, f_x, stage, self.act, self.groups)
            if held is not None:
                A[held, :] = 0.0
            M = np.eye(self.act.size) - 0.5 * h * A
            self.lu = partial(sla.lu_solve, sla.lu_factor(M))
        self.key = self._key(stage, h)

    def solve(self, r, held) -> np.ndarray:
        """The correction dy of the chord iteration for the residual r (over the active
        states) with the states held (over the active states) fixed: dense, the matrix's
        (their rows 0 when it was formed); sparse, the matrix's with the held rows
        replaced by the identity's (dy = 0 there, the other rows solved exactly), through
        the factors of the whole matrix M bordered by the held columns E:
        dy = z - W S^-1 z_H with z = M^-1 r, W = M^-1 E, S = W_H (one solve per held
        state, when the held set changes)."""
        z = self.lu(r)
        if not self.sparse or not held.any():
            return z
        rows = np.flatnonzero(held)
        key = rows.tobytes()
        if key not in self.border:
            E = np.zeros((held.size, rows.size))
            E[rows, np.arange(rows.size)] = 1.0
            W = self.lu(E)
            self.border[key] = (W, sla.lu_factor(W[rows]))
        W, S = self.border[key]
        return z - W @ sla.lu_solve(S, z[rows])

    def __call__(self, x, f_x, stage, h, f0=None) -> tuple[np.ndarray, int]:
        """(x_k+1, -1) from x_k = x (derivatives f_x; f0 those the rule takes at x,
        `start`, f_x if None), or (last iterate, worst state) when
        Newton did not converge in MAX_ITER iterations, or (iterate, NO_NETWORK) when the
        network/load equations have no solution at an iterate (an iterate far from the
        step's solution: ieee14_wt3 after clearing a bus-8 fault through j0.05 pu, the
        first iterate's REGCA1 Ip at -16 pu, which a half step does not reach)."""
        if self.key != self._key(stage, h):
            self.factorise(x, f_x, stage, h, np.isin(self.act, self.held_end), self.side)
        f0 = f_x if f0 is None else f0
        act, rest, y = self.act, self.rest, x + h * f_x
        if self.sparse:  # the linearly implicit predictor: one chord iteration from x
            y[act] = x[act] + 0.5 * h * self.solve((f0 + f_x)[act], np.isin(act, self.held_end))
        pegged = np.zeros(x.size, bool)
        stirred = np.zeros(x.size, bool)  # a derivative not 0 at an iterate of the step
        side = np.zeros(x.size)
        held = np.zeros(act.size, bool)
        self.held_end = np.zeros(0, np.int64)
        last, slow, formed = np.zeros(STALL), False, 0
        for it in range(MAX_ITER):
            y_in = y.copy()
            try:
                f_y = self.f(y, stage)
            except SimulationError:  # an iterate off the solution: the halving retries
                return y, NO_NETWORK
            moved = act[y[act] != y_in[act]]
            pegged[moved] = True
            side[moved] = np.sign(y_in[moved] - y[moved])
            r = y - x - 0.5 * h * (f0 + f_y)
            now = (pegged & (f_y == 0.0))[act]
            if it > LOCK:
                # clamped at this iterate with the rule's update beyond the limit: held
                # there (`_pushed`); in a slow iteration, an integrator stopped at this
                # iterate that ran at an earlier one: held where it stopped (module
                # docstring)
                now |= _pushed(y_in, y, r)[act]
                if it >= 2 and last[(it - 1) % STALL] > SLOW * last[(it - 2) % STALL]:
                    now |= (stirred & (f_y == 0.0))[act]  # in a slow iteration only
            stirred |= f_y != 0.0
            held = now | (held & (it > LOCK))
            r[act[held]] = 0.0
            if slow and formed < (MAX_FORMED if self.sparse else MAX_ITER):
                self.factorise(y, f_y, stage, h, held, side)
                formed += 1
            dy = self.solve(r[act], held)
            dy[held] = 0.0
            y[act] -= dy
            y[rest] = x[rest] + h * f0[rest]
            worst = int(np.argmax(np.abs(dy)))
            last[it % STALL] = abs(dy[worst])
            if self.sparse:
                slow = (
                    it >= 1 and not slow and _too_slow(last[(it - 1) % STALL], last[it % STALL], it)
                )
            else:
                slow = it >= 1 and last[it % STALL] > SLOW * last[(it - 1) % STALL] and not slow
            self.held_end, self.side = act[held], side
            if last[it % STALL] <= TOL:
                return y, -1
        return y, -1 if np.max(last) <= STALL_TOL else int(act[worst])

    def _key(self, stage, h) -> tuple:
        """The matrix's key: a stage's steps are equal but for rounding.  Sparse (above
        SPARSE_ABOVE states) the matrix of the last stage is kept into the next one (its
        Jacobian, a difference quotient per state, is the run's dearest part: 10 s on
        ACTIVSg2000), formed again only where the iteration is slow (SLOW)."""
        return -1 if self.sparse else stage, round(h, 12)

    def halving(self, x, f_x, stage, h, f0=None, depth=0) -> tuple[np.ndarray, int]:
        """The step, or where Newton does not converge, two steps of h/2 (each again, down
        to h / 2**HALVINGS), as ANDES shrinks its step; the grid stays.  f0: `start`'s
        derivatives at x (f_x if None)."""
        held, side = self.held_end, self.side
        y, bad = self(x, f_x, stage, h, f0)
        if bad == -1 or depth == HALVINGS:
            return y, bad
        self.held_end, self.side = held, side
        y, bad = self.halving(x, f_x, stage, 0.5 * h, f0, depth + 1)
        if bad != -1:
            return y, bad
        f_y = self.f(y, stage)
        return self.halving(y, f_y, stage, 0.5 * h, self.start(f_y), depth + 1)


def run(
    sim, m: DynamicModel, grid, nets, limit: float, stop: bool, partitions=()
) -> SimulationResult:
    """Integrate the grid's steps with the trapezoidal rule (module docstring).

    Parameters
    ----------
    sim : Simulator
        The simulator (case, COI weights, islands, result assembly).
    m : DynamicModel
        The model of the run (no storage buses).
    grid : TimeGrid
        The event grid (`stabctl.dynamics.grid.time_grid`).
    nets : list of ReducedNetwork
        The network of each interval of the grid.
    limit : float
        Loss of synchronism: an angle more than this from its island's COI (rad, eq. 40).
    stop : bool
        End the run at the first step after which the limit is exceeded.
    partitions : sequence of Partition, optional
        The machines' islands stage by stage when the run trips machines or splits an
        island (`stabctl.dynamics.driver.Simulator.partitions`): the limit is judged
        against them; default none.

    Returns
    -------
    SimulationResult

    Raises
    ------
    NumericalInstabilityError
        Newton did not converge in a step, or a state left the physical range (non-finite,
        a speed more than `SPEED_BAND` pu from synchronous); names the time and state.
    SimulationError
        The network/load equations did not converge.  Both carry the partial result.
    """
    wall = time.perf_counter()
    f, nm, n_t = _Evaluation(m, nets), m.mp.n, grid.t.size
    active = active_states(m)
    step = _Step(f, active, _column_groups(m, np.flatnonzero(active)))
    rec = recording(n_t, nm, m.case.n_bus, 0, m.cp.n)
    x = m.x0.copy()
    s_step = -1  # the network stage of the last step taken (`_Step.start`)
    for k in range(n_t):
        s = int(grid.interval[k])
        try:
            f_x = f(x, s, BUS_VOLTAGES)
        except SimulationError as e:
            _fail(sim, grid, rec, k, wall, limit, e, SimulationError, partitions, nets)
        _record(rec, k, x, f.out, nm)
        h = float(grid.t[k + 1] - grid.t[k]) if k + 1 < n_t else 0.0
        if k + 1 == n_t or (stop and _separated(sim, x, nm, limit, partitions, grid.t[k])):
            break
        if h == 0.0:
            continue
        f.lock(True)
        try:
            x, bad = step.halving(x, f_x, s, h, step.start(f_x) if s == s_step else None)
            s_step = s
        except SimulationError as e:
            why = _at_step(str(e), h, sim.default_h)
            _fail(sim, grid, rec, k, wall, limit, why, SimulationError, partitions, nets)
        finally:
            f.lock(False)
        if bad == NO_NETWORK:
            why = _at_step("the network/load equations did not converge", h, sim.default_h)
            _fail(sim, grid, rec, k, wall, limit, why, SimulationError, partitions, nets)
        why = "Newton's iteration did not converge"
        if bad < 0:
            bad = _unhealthy_state(x, nm, _judged_now(partitions, grid.t[k + 1], nm))
            why = symptom(x[bad], bad, nm) if bad >= 0 else ""
        if why and bad >= 0 and np.isfinite(x[bad]):  # a separated machine's runaway
            res = sim._result(
                grid.t, rec, k + 1, time.perf_counter() - wall, limit, None, partitions
            )
            if res.ran_away(sim.case, bad, float(x[bad]), float(grid.t[k + 1])):
                return res
        if why:  # the step named as where the network fails (round 38)
            smaller = "" if h > 2 * sim.default_h else "; use a smaller step"  # (said)
            msg = (
                f"case '{sim.case.name}': trapezoidal step ending at t = {grid.t[k + 1]:.4f} s:"
                f" state {m.state_name(bad)} = {x[bad]:.6g}: {_at_step(why, h, sim.default_h)}"
                f"{smaller} (the run reached {grid.t[k]:.4f} s)"
            )
            _fail(sim, grid, rec, k, wall, limit, msg, NumericalInstabilityError, partitions)
    return sim._result(grid.t, rec, k + 1, time.perf_counter() - wall, limit, None, partitions)


def _at_step(why: str, h: float, default_h: float) -> str:
    """`why` a step failed, with the step named, and, for a step above twice the case's
    default, that a smaller one may succeed (at 0.5 s the network's failure was the
    step's, not the grid's, and nothing said so)."""
    if h > 2 * default_h:
        ratio = f"{h / default_h:.3g} times the case's default: a smaller --step may converge"
        return f"{why} (a step of {h:g} s, {ratio})"
    return f"{why} (a step of {h:g} s)"


def _too_slow(before, now, it) -> bool:
    """Sparse: whether the chord iteration, its last two corrections before and now (the
    largest of a state) at iteration it, is to have its matrix formed again: now above
    SLOW_FLOOR and either contracting by less than SLOW_SPARSE or, at its rate now / before,
    not reaching TOL within MAX_ITER iterations."""
    if now <= SLOW_FLOOR:
        return False
    rate = now / before if before > 0.0 else np.inf
    return rate > SLOW_SPARSE or it + np.log(TOL / now) / np.log(rate) > MAX_ITER - 1


def _pushed(y_in, y, r) -> np.ndarray:
    """The states the evaluation clamped onto a limit at this iterate (y_in before the
    evaluation, y after it) whose rule residual r = y - x - h/2 (f0 + f(y)) points past
    that limit: the rule's update x + h/2 (f0 + f(y)) lies beyond it (module docstring)."""
    return (y != y_in) & (r * (y_in - y) < 0.0)


#: the state blocks whose states reach only their machine's own states and controls: an
#: exciter's, stabiliser's or governor's state enters the derivatives of its own states,
#: of the other controls of its machine (the field voltage, the stabilising signal, the
#: mechanical power) and of the machine's, never the network's currents
LOCAL_BLOCKS = ("exc", "pss", "tg")


def _column_groups(m: DynamicModel, act: np.ndarray) -> list[tuple[np.ndarray, list]]:
    """The Jacobian's column groups: per slot of a `LOCAL_BLOCKS` block, its active states
    of distinct machines, each with the rows it can reach (over act: its machine's states
    and the states of every control of that machine, its shaft's).  Their difference
    quotients have disjoint rows, so one evaluation gives a group's columns, the same
    numbers as one evaluation per column: the network's solution, which couples the
    machines, does not move (bit for bit in every matrix of Kundur's fault run forced
    sparse, tests/dynamics/test_trapezoid.py, and in ACTIVSg2000's first three).
    ACTIVSg2000: 4463 of its 6467 columns in 19 groups, its Jacobian in 2.3 s instead of
    4.9 s."""
    L, n_x = m.layout, m.layout.size
    owner = np.full(n_x, -1)
    L.view(owner, "mac")[:] = np.arange(m.mp.n)
    for block, p in zip((*LOCAL_BLOCKS, "shaft"), (m.ep, m.pp, m.gp, m.tp), strict=True):
        L.view(owner, block)[:] = p.mac  # a shaft's: its machine's (the governor's torque)
    pos = np.full(n_x, -1)
    pos[act] = np.arange(act.size)
    on = owner[act]
    reach = {i: np.flatnonzero(on == i) for i in np.unique(on[on >= 0])}
    groups = []
    for block in LOCAL_BLOCKS:
        for slot in L.view(np.arange(n_x), block):
            cols = pos[slot][pos[slot] >= 0]
            mine = owner[act[cols]]
            while cols.size:  # a machine with two controls of a block: its own group
                _, first = np.unique(mine, return_index=True)
                groups.append((cols[first], [reach[i] for i in mine[first]]))
                cols, mine = np.delete(cols, first), np.delete(mine, first)
    return groups


def _separated(sim, x, nm, limit, partitions=(), t=0.0) -> bool:
    """Whether an angle of state x at time t (s) is more than limit from its island's COI
    (with partitions, among the machines judged then)."""
    angle = x[:nm]
    if partitions:
        dev = np.abs(
            judged_relative(angle[None], np.array([t]), sim.inertia, sim.island, partitions)
        )
        return bool(np.max(dev) > limit)
    return bool(np.max(np.abs(angle - coi_of_islands(angle, sim.inertia, sim.island))) > limit)


def _unhealthy_state(x, nm, judged) -> int:
    """The first non-finite state, else the speed of a judged machine (judged, bool
    (nm,)) more than SPEED_BAND pu from synchronous (the integrator's health rule,
    `symptom`), else -1."""
    bad = np.flatnonzero(~np.isfinite(x))
    if bad.size:
        return int(bad[0])
    off = np.where(judged, np.abs(x[nm : 2 * nm] - 1.0), 0.0)
    q = nm + int(np.argmax(off))
    return q if off[q - nm] > SPEED_BAND else -1


def _judged_now(partitions, t: float, nm: int) -> np.ndarray:
    """The machines the partition of time t judges (every machine without partitions)."""
    if not partitions:
        return np.ones(nm, bool)
    return partitions[int(stage_at(np.array([t]), partitions)[0])].judged


def _fail(sim, grid, rec, k, wall, limit, why, error, partitions=(), nets=()) -> None:
    res = sim._result(grid.t, rec, k + 1, time.perf_counter() - wall, limit, None, partitions)
    if error is SimulationError:
        k_end = min(k + 1, grid.t.size - 1)
        why = (
            f"case '{sim.case.name}': {why} in the step ending at t = "
            f"{grid.t[k_end]:.4f} s (the run reached {grid.t[k]:.4f} s)"
            + no_solution_hint(sim.case, nets[grid.interval[k_end]])
        )
    raise error(why, result=res)
