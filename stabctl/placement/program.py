"""Convex ESD sizing and placement: the linear program of one iteration (docs/placement.md).

Decision: the rating P_j (MW) of an ESD at each candidate site j (a bus, tied to the
generator whose relative speed drives its bang-bang control), 0 <= P_j <= max_mw_j.

    minimise    sum_j cost_j P_j  (+ mu_t sum_c u_c + mu_d sum_m s_m)
    subject to  cct_c + gradient_c . (P - at_c) + u_c >= target_c + safety   every contingency c
                A_damp P <= b_damp + s                                (optional damping rows)
                |P_j - centre_j| <= radius                            (optional trust region)
                0 <= P_j <= upper_j,   u = 0 (hard) or u >= 0 (elastic, mu_t), s >= 0

Transient rows (`CCTCut`): the critical clearing time of each contingency linearised in the
ratings at the last simulated allocation; its value is the simulated CCT and its gradient
comes from the SIME margin of the run just beyond it (`stabctl.stability.sime`,
`stabctl.placement.evaluation`), corrected to pass through the other allocations simulated
nearby (`CCTCut.through`, `stabctl.placement.loop`).  Damping rows (`DampingRows`,
`stabctl.smallsignal.damping`): every electromechanical mode's eigenvalue linearised in the ratings,
kept left of the constant-damping line zeta_min.  Inside the verification loop the rows
are elastic (slacks at exact-penalty prices) so that every trust-region step has a
solution; hard rows give the infeasibility diagnosis.  The objective is the l1 norm of
the (non-negative) ratings, weighted by cost; being a linear program its solutions are
vertices, with at most as many sites as binding rows.  A per-site cost or a site limit is
met by greedy removal of sites (`sparse_allocation`).

Solved by cvxpy with Clarabel.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import cast

import cvxpy as cp
import numpy as np

from stabctl.errors import InputError, StabctlError
from stabctl.smallsignal.damping import DampingRows


class InfeasibleError(StabctlError):
    """No allocation within the site bounds reaches the targets.  `contingencies`: names of
    the contingencies that cannot be met even alone (empty when only their combination,
    the damping rows or the site limit fail)."""

    def __init__(self, message, contingencies=()):
        super().__init__(message)
        self.contingencies = tuple(contingencies)


def total_mw(mw) -> float:
    """Ratings summed (MW), to the watt: each is on a 0.1 MW grid, and a float sum printed
    134.10000000000002 in a plan's JSON.

    Parameters
    ----------
    mw : array_like of float
        Ratings, MW.

    Returns
    -------
    float
    """
    return round(float(np.sum(mw)), 6)


@dataclass(frozen=True)
class Site:
    """A candidate ESD site: `bus`, the `machine` (number) driving its bang-bang control,
    the largest rating `max_mw` (MW, > 0) and the cost per MW (> 0, any unit)."""

    bus: int
    machine: int
    max_mw: float
    cost: float = 1.0

    def __post_init__(self):
        if not (self.max_mw > 0 and self.cost > 0):
            raise InputError(
                f"site at bus {self.bus}: max_mw and cost must be > 0, got "
                f"{self.max_mw:g} MW and {self.cost:g}"
            )


def candidate_sites(case, max_pct: float = 50.0, machines=None, cost=None) -> tuple[Site, ...]:
    """One site per generator (default every one but infinite buses, or the numbers in
    `machines`) at its HV bus (`stabctl.storage.devices.hv_bus`), bounded at max_pct % of
    the machine's MVA; cost: a mapping machine number -> cost per MW (default 1 for all).

    An infinite bus (a machine of H = 0) is no site: its speed is the reference, so a
    device driven by it would idle (`stabctl.storage.control.relative_speeds`).

    Raises InputError for max_pct <= 0 or an infinite bus named in `machines`; CaseError
    for an unknown machine.
    """
    from stabctl.storage.devices import hv_bus

    if not max_pct > 0:
        raise InputError(f"largest site rating must be > 0 % of machine MVA, got {max_pct:g}")
    fixed = case.infinite_buses()
    if machines is None:
        nums = [int(k) for k in case.machines.number if int(k) not in fixed]
    else:
        nums = [int(k) for k in machines]
        named = [k for k in nums if k in fixed]
        if named:
            raise InputError(
                f"{', '.join(case.machine_name(k) for k in named)} "
                f"{'is an infinite bus' if len(named) == 1 else 'are infinite buses'} (H = 0, "
                "its speed the reference): a device there would idle, so it is no ESD site"
            )
    cost = cost or {}
    return tuple(
        Site(
            bus=hv_bus(case, k),
            machine=k,
            max_mw=max_pct / 100 * float(case.machines.mva[case.machine_index(k)]),
            cost=float(cost.get(k, 1.0)),
        )
        for k in nums
    )


@dataclass(frozen=True)
class CCTCut:
    """CCT of one contingency linearised in the ratings: cct(P) ~ cct_s + gradient . (P - at)
    (s; gradient (n_sites,) s/MW; at (n_sites,) MW, the allocation simulated)."""

    contingency: str
    target_s: float
    cct_s: float
    gradient: np.ndarray
    at_mw: np.ndarray

    def predicted(self, P) -> float:
        """Linearised CCT (s) at ratings P (MW)."""
        return float(self.cct_s + self.gradient @ (np.asarray(P, float) - self.at_mw))

    def through(self, points) -> CCTCut:
        """The cut corrected to pass through measured (ratings MW (n_sites,), CCT s)
        `points`: the gradient g is first scaled by the least-squares factor
        a = (S^T g) . d / |S^T g|^2 (SIME's error is mostly the one scalar
        d eta / d t_clear of the contingency; a kept in [0.1, 10]), then changed least
        (2-norm) to fit every point exactly, g' = a g + S (S^T S)^+ (d - a S^T g)
        (multi-secant quasi-Newton update, Nocedal and Wright sec. 6.2); S: steps from
        `at_mw` (n_sites, m), d: CCT changes (m,)."""
        pts = [(np.asarray(p, float) - self.at_mw, c - self.cct_s) for p, c in points]
        pts = [(s, d) for s, d in pts if np.any(s != 0)]
        if not pts:
            return self
        S = np.column_stack([s for s, _ in pts])
        d = np.array([d for _, d in pts])
        sg = S.T @ self.gradient
        a = float(np.clip(sg @ d / (sg @ sg), 0.1, 10.0)) if sg @ sg > 0 else 1.0
        g = a * self.gradient + S @ (np.linalg.pinv(S.T @ S) @ (d - a * sg))
        return CCTCut(self.contingency, self.target_s, self.cct_s, g, self.at_mw)


@dataclass
class Allocation:
    """Ratings mw (n_sites,) at `sites`; objective value; solve_time_s: Clarabel's own
    time, wall_time_s: with cvxpy's canonicalisation; slack: damping-row violation left
    (damping-ratio units); cct_slack: linearised CCT shortfall left (s, summed);
    predicted_cct_s: contingency -> linearised CCT at mw (s)."""

    sites: tuple
    mw: np.ndarray
    objective: float
    solve_time_s: float
    wall_time_s: float
    slack: float = 0.0
    cct_slack: float = 0.0
    predicted_cct_s: dict = field(default_factory=dict)

    @property
    def total_mw(self) -> float:
        return total_mw(self.mw)

    @property
    def n_sites(self) -> int:
        return int(np.count_nonzero(self.mw > 0))

    def rows(self) -> list[dict]:
        """Installed sites only: bus, machine, MW."""
        return [
            {"bus": s.bus, "machine": s.machine, "mw": float(p)}
            for s, p in zip(self.sites, self.mw)
            if p > 0
        ]


def solve_allocation(
    sites,
    cuts,
    *,
    safety_s: float = 0.0,
    damping: DampingRows | None = None,
    penalty: float | None = None,
    cct_penalty: float | None = None,
    upper=None,
    trust: tuple | None = None,
) -> Allocation:
    """Solve the linear program of the module docstring once (cvxpy, Clarabel).

    Args:
        sites: Site per decision variable; cuts: CCTCut per contingency (any number).
        safety_s: CCT margin required above each target (s).
        damping: linearised damping rows, elastic at `penalty` per unit of violation
            (default ten times the cost of every site at its bound).
        cct_penalty: None for hard CCT rows, else their slack's price per s of shortfall.
        upper: per-site upper bounds (MW, default each site's max_mw; 0 excludes a site).
        trust: (centre MW (n_sites,), radius MW (scalar or (n_sites,))) trust region.
    Returns the Allocation (ratings below 1e-6 MW set to 0).
    Raises InfeasibleError (hard rows only) naming the contingencies that cannot be met
    alone (`diagnose`), or the combination.
    """
    n = len(sites)
    cost = np.array([s.cost for s in sites])
    ub = np.array([s.max_mw for s in sites]) if upper is None else np.asarray(upper, float)
    P = cp.Variable(n, nonneg=True)
    u = cp.Variable(len(cuts), nonneg=True) if cct_penalty is not None and cuts else None
    lin = [c.cct_s + c.gradient @ (P - c.at_mw) for c in cuts]
    cons = [P <= ub] + [
        lin[i] + (0 if u is None else u[i]) >= c.target_s + safety_s for i, c in enumerate(cuts)
    ]
    obj = cost @ P + (0 if u is None else cct_penalty * cp.sum(u))
    slack = None
    if damping is not None and len(damping.b):
        slack = cp.Variable(len(damping.b), nonneg=True)
        cons.append(damping.A @ P <= damping.b + slack)
        obj = obj + (10 * float(cost @ ub) if penalty is None else penalty) * cp.sum(slack)
    if trust is not None:
        cons.append(cp.abs(P - trust[0]) <= trust[1])
    # the optimum does not change with the cost's scale, the solver's numerics do: costs
    # of 1e9 per MW made Clarabel report the program unbounded
    scale = float(np.max(np.abs(cost), initial=0.0)) or 1.0
    prob = cp.Problem(cp.Minimize(obj / scale), cons)
    wall = time.perf_counter()
    prob.solve(solver=cp.CLARABEL)
    wall = time.perf_counter() - wall
    if prob.status not in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE):
        raise _infeasible(cuts, ub, safety_s, prob.status)
    value = cast(np.ndarray, P.value)  # solved: not None
    mw = np.where(value > 1e-6, value, 0.0)
    return Allocation(
        sites=tuple(sites),
        mw=mw,
        objective=float(prob.value) * scale,
        solve_time_s=float(prob.solver_stats.solve_time or 0.0),
        wall_time_s=wall,
        slack=0.0 if slack is None else float(np.sum(cast(np.ndarray, slack.value))),
        cct_slack=0.0 if u is None else float(np.sum(cast(np.ndarray, u.value))),
        predicted_cct_s={c.contingency: c.predicted(mw) for c in cuts},
    )


def diagnose(cuts, upper, safety_s: float = 0.0) -> list[str]:
    """Contingencies whose linearised CCT cannot reach target + safety with every site
    between 0 and its upper bound (MW), each alone: the box maximum of a linear function."""
    ub = np.asarray(upper, float)
    bad = []
    for c in cuts:
        best = c.cct_s - c.gradient @ c.at_mw + np.maximum(c.gradient * ub, 0.0).sum()
        if best < c.target_s + safety_s - 1e-12:
            bad.append(c.contingency)
    return bad


def _infeasible(cuts, ub, safety_s, status) -> InfeasibleError:
    bad = diagnose(cuts, ub, safety_s)
    if bad:
        worst = {c.contingency: c for c in cuts}[bad[0]]
        best = (
            worst.cct_s - worst.gradient @ worst.at_mw + np.maximum(worst.gradient * ub, 0.0).sum()
        )
        return InfeasibleError(
            f"contingency {', '.join(bad)}: even with every site at its upper bound "
            f"({ub.sum():.0f} MW) the linearised CCT of {bad[0]} reaches only {best:.3f} s "
            f"against the target {worst.target_s:.3f} s",
            bad,
        )
    return InfeasibleError(
        f"the targets of {len(cuts)} contingencies cannot be met together "
        f"within the site bounds and limits (solver status {status})"
    )


def sparse_allocation(
    sites, cuts, *, max_sites: int | None = None, site_cost=0.0, upper=None, **kw
) -> Allocation:
    """Fewer sites by greedy backward elimination: while more than max_sites sites are
    used, or while leaving one out lowers objective + the cost of the sites used
    (site_cost: one number for every site, or one per site, shape (n_sites,)), the used site
    whose removal raises the objective least is removed (its bound set to 0; one program
    per used site per removal).  A heuristic: the site count is not convex.  (Reweighted
    l1 cannot do this on a linear program: its solution is already a vertex, and the
    weights 1 / (P_j + eps) only push the unused sites further out.)  upper and kw go to
    `solve_allocation`.

    Raises InfeasibleError (as solve_allocation, or when no used site can be left out
    to meet max_sites) and InputError for max_sites < 1 or site_cost < 0.
    """
    if max_sites is not None and max_sites < 1:
        raise InputError(f"max_sites must be >= 1, got {max_sites}")
    per_site = np.broadcast_to(np.asarray(site_cost, float), (len(sites),))
    if np.any(per_site < 0):
        raise InputError(f"site cost must be >= 0, got {per_site.min():g}")
    ub = np.array([s.max_mw for s in sites]) if upper is None else np.asarray(upper, float)
    alloc = solve_allocation(sites, cuts, upper=ub, **kw)
    total = lambda a: a.objective + float(per_site @ (a.mw > 0))  # noqa: E731
    while alloc.n_sites > 0:
        over = max_sites is not None and alloc.n_sites > max_sites
        if not over and not np.any(per_site > 0):
            break
        best = _drop_one_site(sites, cuts, alloc, ub, kw)
        if over and best is None:
            used = ", ".join(f"bus {sites[j].bus}" for j in np.nonzero(alloc.mw > 0)[0])
            raise InfeasibleError(
                f"with at most {max_sites} site(s): none of the "
                f"{alloc.n_sites} sites used ({used}) can be left out"
            )
        if not over and (best is None or total(best[0]) >= total(alloc)):
            break
        alloc, ub = best
    return alloc


def _drop_one_site(sites, cuts, alloc: Allocation, ub, kw):
    """The cheapest program with one more used site excluded, (allocation, bounds), or
    None when every exclusion is infeasible."""
    best = None
    for j in np.nonzero(alloc.mw > 0)[0]:
        trial_ub = ub.copy()
        trial_ub[j] = 0.0
        try:
            trial = solve_allocation(sites, cuts, upper=trial_ub, **kw)
        except InfeasibleError:
            continue
        if best is None or trial.objective < best[0].objective:
            best = (trial, trial_ub)
    return best
