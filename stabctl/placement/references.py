"""What a plan is compared with and how far it is from its limits (docs/placement.md,
section 7): the clearing margins of its contingencies (`margins`), its tightest
contingencies and its energies again at half the integration step (`half_step`), the least
uniform fleet (the same % of MVA at every generator, bisection on the %) meeting the same
requirements (`least_uniform`), and each binding fault's own least allocation
(`faults_alone`).

Each takes the plan's `stabctl.placement.context.PlanContext`, its contingencies (cons)
and the keyword arguments of its evaluations (kw, `stabctl.placement.loop.evaluations`);
`result` is the plan's `stabctl.placement.plan.PlanResult`.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace

import numpy as np

from stabctl.errors import counted
from stabctl.placement.context import PlanContext
from stabctl.placement.energy import energy_half_step, energy_note, energy_setters, size_energy
from stabctl.placement.evaluation import VerifyOptions
from stabctl.placement.loop import PlaceOptions, WarmStart, _rounded, evaluations, place
from stabctl.placement.program import InfeasibleError, total_mw

#: Uniform fleet bisection: resolution (% of MVA).
UNIFORM_RES_PCT = 0.1


def margins(pl: PlanContext, cons, result, tol: float, cap_s: float, kw) -> None:
    """Fill the CCT and margin of every contingency row without one (those only checked
    at their required time T): a run cleared at T + cap_s; stable there, the margin is
    reported as at least cap_s (``margin_at_least``); otherwise a bisection with the
    allocation between T (stable, its check) and T + cap_s to `tol` (s), no gradient
    runs (`critical_clearing_time`)."""
    rows = {r["name"]: r for r in result.contingencies}
    todo = [c for c in cons if rows[c.name]["cct_s"] is None and rows[c.name]["met"]]
    if not todo:
        return
    pl.say(
        f"clearing margins of {counted(len(todo), 'contingency', 'contingencies')} (up to "
        f"{1000 * cap_s:g} ms, "
        f"{1000 * tol:g} ms)"
    )
    top = {c.name: round(min(c.target_cct_s + cap_s, pl.t_max), 12) for c in todo}
    far = pl.check([replace(c, target_cct_s=top[c.name]) for c in todo], result.mw)
    near = [c for c in todo if not far[c.name]["stable_at_check"]]
    for c in todo:
        if far[c.name]["stable_at_check"]:
            rows[c.name].update(margin_s=top[c.name] - c.target_cct_s, margin_at_least=True)
    if not near:
        return
    ev = evaluations(
        pl.case,
        near,
        result.mw,
        replace(kw, search=replace(kw.search, tol=tol)),
        VerifyOptions(
            brackets={c.name: (c.target_cct_s, top[c.name]) for c in near}, gradient=False
        ),
    )
    for c in near:
        rows[c.name].update(
            cct_s=ev[c.name]["cct_s"], cct_tol_s=tol, margin_s=ev[c.name]["cct_s"] - c.target_cct_s
        )


def half_step(pl: PlanContext, cons, result, n: int, kw, verdicts: bool = False) -> dict:
    """The allocation's n contingencies of least clearing margin (those with a simulated
    CCT) simulated again at half the integration step: each cleared at its required time
    (the verdict), and its CCT with the allocation to the plan's tolerance, the bisection
    starting from two tolerances either side of the CCT at the full step (shown converged
    in the step, as every figure that depends on it).

    The runs that set each site's energy (`size_energy`) are simulated again at half the
    step too: the energy is shown converged in the step as well.  With `verdicts`, every
    other contingency of the plan is too, cleared at its required time (a row without
    CCTs: `stabctl place`, whose plans have no clearing margins to rank by).

    Returns {"h_s" (the full step, s), "rows": [{"name", "required_s", "cct_s" (full
    step), "cct_tol_s" (its resolution), "cct_half_s", "stable_half" (at the required
    time)}] (a verdict's row: its CCTs None), "all_stable", "max_cct_diff_s" (largest
    |cct_half - cct| beyond the coarser resolution, s), and the energy's half-step figures
    (`energy_half_step`)}."""
    h = pl.step_s()
    by_name = {c.name: c for c in cons}
    rows = sorted(
        (r for r in result.contingencies if r["cct_s"] is not None), key=lambda r: r["margin_s"]
    )[:n]
    tight = [by_name[r["name"]] for r in rows]
    res_of = {r["name"]: r.get("cct_tol_s", pl.tol) for r in rows}
    others = (
        [by_name[r["name"]] for r in result.contingencies if r["name"] in by_name]
        if verdicts
        else []
    )
    # one batch: the tightest contingencies, those that set an energy (often the same), and
    # with verdicts every other one
    setters = energy_setters(by_name, result.mw, result.energy)
    batch = list({c.name: c for c in tight + setters + others}.values())
    checks = pl.check(batch, result.mw, h=h / 2)
    ev = evaluations(
        pl.case,
        tight,
        result.mw,
        replace(kw, model=replace(kw.model, h=h / 2)),
        VerifyOptions(
            brackets={
                r["name"]: (r["cct_s"] - 2 * res_of[r["name"]], r["cct_s"] + 2 * res_of[r["name"]])
                for r in rows
            },
            gradient=False,
        ),
    )
    out = [
        {
            "name": r["name"],
            "required_s": r["required_s"],
            "cct_s": r["cct_s"],
            "cct_tol_s": res_of[r["name"]],
            "cct_half_s": ev[r["name"]]["cct_s"],
            "stable_half": bool(checks[r["name"]]["stable_at_check"]),
        }
        for r in rows
    ]
    done = {o["name"] for o in out}
    out += [
        {
            "name": c.name,
            "required_s": c.target_cct_s,
            "cct_s": None,
            "cct_tol_s": None,
            "cct_half_s": None,
            "stable_half": bool(checks[c.name]["stable_at_check"]),
        }
        for c in others
        if c.name not in done
    ]
    diff = max(
        (
            max(0.0, abs(o["cct_half_s"] - o["cct_s"]) - o["cct_tol_s"])
            for o in out
            if o["cct_s"] is not None
        ),
        default=0.0,
    )
    ok = all(o["stable_half"] for o in out)
    energy = energy_half_step(checks, result.mw, result.mwh, result.energy)
    pl.say(
        f"half step ({1000 * h / 2:.3g} ms): {len(out)} {'' if verdicts else 'tightest '}"
        "contingencies "
        f"{'all stable' if ok else 'NOT all stable'} at their required time; CCTs within "
        f"{1000 * diff:.0f} ms beyond their resolution" + energy_note(energy)
    )
    return {"h_s": h, "rows": out, "all_stable": ok, "max_cct_diff_s": diff, **energy}


def least_uniform(pl: PlanContext, cons, failing, kw) -> dict:
    """The least uniform fleet (the same % of MVA at every generator, rounded up to 0.1 MW
    per site) meeting every contingency: bisection on the % (to UNIFORM_RES_PCT) with
    the check runs of the contingencies that fail without storage, then every
    contingency checked at the result and those failing without storage verified by
    their first unstable clearing time, as the active set of `plan`; a miss there moves
    the % up one resolution step and checks again.  The runs that set each site's energy
    are simulated again at half the step (shown converged, as the optimised allocation's
    in `half_step`).  Returns {"pct" (%), "total_mw", "mw_by_site" (MW), "mwh", "cost"
    (`CostModel.split`), "verified", "energy" (per site, as `PlanResult.energy`), and the
    energy's half-step figures (`energy_half_step`)}; pct None
    and verified False when even the site bounds fail."""
    fleet, pct_max = uniform_fleet(pl)
    if not failing:
        zero = np.zeros(len(pl.sites))
        return {
            "pct": 0.0,
            "total_mw": 0.0,
            "mwh": 0.0,
            "cost": pl.cost.split(pl.sites, zero, zero),
            "verified": True,
        }
    pct = least_pct(pl, failing, fleet, pct_max)
    if pct is None:
        pl.say(f"uniform: not met even at {pct_max:g} % of every MVA")
        return {"pct": None, "total_mw": None, "verified": False}
    pl.say(
        f"uniform: {pct:g} % meets the contingencies unstable without storage; "
        "checking every contingency"
    )
    pct, ok, checks = _verified_pct(pl, cons, failing, pct, fleet, pct_max, kw)
    return _uniform_result(pl, cons, pct, fleet(pct), ok, checks)


def uniform_fleet(pl: PlanContext) -> tuple:
    """The uniform fleets of a plan's candidate sites.

    Parameters
    ----------
    pl : PlanContext
        The plan (its sites and case).

    Returns
    -------
    fleet : callable
        fleet(pct): the MW per site, shape (n_sites,), of pct % of each site's machine
        MVA, within the site bounds and rounded (`stabctl.placement.loop._rounded`).
    pct_max : float
        The largest % every site bound allows (%).
    """
    mva = _mva(pl)
    upper = np.array([s.max_mw for s in pl.sites])
    return (
        lambda p: _rounded(np.minimum(p / 100 * mva, upper), pl.sites),
        float(np.min(100 * upper / mva)),
    )


def _stable(pl: PlanContext, which, mw) -> tuple:
    """(every contingency of `which` stable at its required time at ratings mw, the
    checks: name -> check dict)."""
    checks = pl.check(which, mw)
    return all(r["stable_at_check"] for r in checks.values()), checks


def least_pct(pl: PlanContext, failing, fleet, pct_max: float) -> float | None:
    """The least uniform fleet making contingencies stable at their required time.

    Doubling from 5 %, then bisection to UNIFORM_RES_PCT, on the check runs (one per
    contingency and %): stability need not be monotonic in the %, so the result is the
    bisection's, not necessarily the least.

    Parameters
    ----------
    pl : PlanContext
        The plan (its check runs).
    failing : sequence of Contingency
        The contingencies to make stable.
    fleet : callable
        fleet(pct) -> MW per site (`uniform_fleet`).
    pct_max : float
        The largest % tried (%).

    Returns
    -------
    float or None
        The % (rounded up to UNIFORM_RES_PCT); None when not even pct_max does.
    """
    lo, hi = 0.0, min(5.0, pct_max)
    while not _stable(pl, failing, fleet(hi))[0]:
        if hi >= pct_max:
            return None
        lo, hi = hi, min(2 * hi, pct_max)
    while hi - lo > UNIFORM_RES_PCT + 1e-9:
        mid = round(0.5 * (lo + hi), 6)
        lo, hi = (lo, mid) if _stable(pl, failing, fleet(mid))[0] else (mid, hi)
    return float(np.ceil(hi / UNIFORM_RES_PCT - 1e-6) * UNIFORM_RES_PCT)


def _verified_pct(pl: PlanContext, cons, failing, pct: float, fleet, pct_max: float, kw) -> tuple:
    """From pct up by UNIFORM_RES_PCT (at most to pct_max) until every contingency is
    stable at its required time and those of `failing` meet it by their CCT: (the %,
    verified, the checks of every contingency at it)."""
    while True:
        ok, checks = _stable(pl, cons, fleet(pct))
        if ok:
            pl.add_base(failing, pl.brackets, kw)
            ev = evaluations(pl.case, failing, fleet(pct), kw, VerifyOptions(base=pl.base))
            ok = all(c.met_by(ev[c.name]["cct_s"]) for c in failing)
        if ok or pct >= pct_max:
            return pct, ok, checks
        pct = round(pct + UNIFORM_RES_PCT, 6)


def _uniform_result(pl: PlanContext, cons, pct: float, mw, ok: bool, checks) -> dict:
    """`least_uniform`'s figures of the fleet mw (MW per site) at pct %: its energies
    sized from `checks` and checked at half the step."""
    mwh, energy, e_ok = size_energy(pl, cons, mw, checks)
    setters = energy_setters({c.name: c for c in cons}, mw, energy)
    half = energy_half_step(pl.check(setters, mw, h=pl.step_s() / 2), mw, mwh, energy)
    pl.say(
        f"uniform: {pct:g} % = {mw.sum():.0f} MW, "
        f"{'verified' if ok and e_ok else 'NOT verified'}" + energy_note(half)
    )
    return {
        "pct": pct,
        "total_mw": total_mw(mw),
        "mw_by_site": mw.tolist(),
        "mwh": float(mwh.sum()),
        "cost": pl.cost.split(pl.sites, mw, mwh),
        "verified": bool(ok and e_ok),
        "energy": energy,
        **half,
    }


def _mva(pl: PlanContext) -> np.ndarray:
    """MVA of the machine of each candidate site, (n_sites,)."""
    from stabctl.stability.cct import cached_simulator

    case = cached_simulator(pl.case, pl.model).case
    return np.array([float(case.machines.mva[case.machine_index(s.machine)]) for s in pl.sites])


def faults_alone(pl: PlanContext, cons, result, max_iter: int, kw) -> list:
    """Each fault of the final active set alone (all its load levels that fail without
    storage): its own least allocation, verified by `place` (MW, sites, verified).  The
    faults are solved at the same time (one thread each, sharing the worker pool: a
    single fault's batches are too small to keep every worker busy)."""
    by_name = {c.name: c for c in cons}
    faults = list(dict.fromkeys(by_name[n].fault_name for n in result.active))
    if not faults:
        return []
    sites = pl.priced(pl.energy_rate)

    def one(fname):
        mine = [by_name[n] for n in result.active if by_name[n].fault_name == fname]
        base = {c.name: pl.base[c.name] for c in mine}
        try:
            res = place(
                pl.case,
                mine,
                replace(kw, sites=sites),
                PlaceOptions(max_iter=max_iter, site_cost=pl.site_costs),
                WarmStart(base=base),
            )
        except InfeasibleError as exc:
            return {"fault": fname, "total_mw": None, "verified": False, "message": str(exc)}
        pl.say(f"alone: {fname}: {res.allocation.total_mw:.1f} MW")
        return {
            "fault": fname,
            "contingencies": [c.name for c in mine],
            "total_mw": res.allocation.total_mw,
            "allocation": res.allocation.rows(),
            "verified": res.verified,
        }

    with ThreadPoolExecutor(max_workers=len(faults)) as threads:
        return list(threads.map(one, faults))
