"""Energy (MWh) of a plan's devices (docs/placement.md, section 7).

Sizing (`size_energy`): the energy of each device comes from the verifying runs: its
state of charge along every run cleared at the required time (integrated by the simulator
between located switchings, `SimulationResult.meta["storage"]`), the largest excursion
over the contingencies, doubled (a device started half full) with ENERGY_MARGIN; the runs
that set each device's energy are then simulated again with that finite energy.  Inside
the program the energy is priced per MW (`mwh_per_mw`): at each site the excursion per MW
of its bang-bang modes along the latest runs (also where no device is installed yet).

Convergence in the step (`energy_half_step`): the runs that set the energies
(`energy_setters`) simulated again at half the integration step.
"""

from __future__ import annotations

import numpy as np

from stabctl.placement.context import PlanContext

#: Relative margin on the sized energy (the simulator integrates the state of charge
#: within its steps, the sizing on the recorded grid).
ENERGY_MARGIN = 0.05
MJ_PER_MWH = 3600.0  # 1 MWh = 3600 MJ


def mwh_per_mw(n_sites: int, checks: dict) -> np.ndarray:
    """Usable energy per MW at each of n_sites sites (MWh/MW), (n_sites,): twice the
    largest state-of-charge excursion per MW of its modes over the runs `checks` (name ->
    `stabctl.placement.evaluation.check` dict), with ENERGY_MARGIN."""
    exc = np.zeros(n_sites)
    for ck in checks.values():
        if ck["site_excursion_s"]:
            exc = np.maximum(exc, ck["site_excursion_s"])
    return (1 + ENERGY_MARGIN) * 2 * exc / MJ_PER_MWH


def energy_need(check: dict, k: int) -> float:
    """Energy need (MWh) of the k-th site with storage in a check run: twice its largest
    state-of-charge excursion (a device started half full)."""
    _, _, hi, lo = check["energy_mj"][k]
    return 2 * max(hi, -lo) / MJ_PER_MWH


def size_energy(pl: PlanContext, cons, mw, checks) -> tuple:
    """Usable energy per site (MWh) from the check runs at ratings mw: twice the largest
    state-of-charge excursion (device started half full) plus ENERGY_MARGIN, rounded up
    to 0.01 MWh; the runs that set it simulated again with that finite energy.
    Returns (mwh (n_sites,), per-site energy figures, all those runs stable)."""
    used = [j for j, p in enumerate(mw) if p > 0]
    n = len(pl.sites)
    mwh = np.zeros(n)
    energy: list[dict] = [{} for _ in range(n)]
    if not used:
        return mwh, energy, True
    setter = {}
    for c in cons:
        for k, j in enumerate(used):
            a, d, _, _ = checks[c.name]["energy_mj"][k]
            need = energy_need(checks[c.name], k)
            e = energy[j]
            e["absorbed_mj"] = max(e.get("absorbed_mj", 0.0), a)
            e["delivered_mj"] = max(e.get("delivered_mj", 0.0), d)
            if need >= mwh[j]:
                mwh[j], setter[j] = need, c
                e["need_mwh"] = need
    mwh = np.where(mw > 0, np.ceil(100 * (1 + ENERGY_MARGIN) * mwh - 1e-9) / 100, 0.0)
    mwh = np.where(mw > 0, np.maximum(mwh, 0.01), 0.0)
    for j in used:
        energy[j]["set_by"] = setter[j].name
    again = energy_setters({c.name: c for c in cons}, mw, energy)
    rerun = pl.check(again, mw, energy_mj=MJ_PER_MWH * mwh)
    ok = all(r["stable_at_check"] for r in rerun.values())
    pl.say(
        f"energy: {mwh.sum():.2f} MWh at {len(used)} site(s); {len(again)} run(s) "
        f"again with that energy: {'stable' if ok else 'UNSTABLE'}"
    )
    return mwh, energy, ok


def energy_setters(by_name: dict, mw, energy) -> list:
    """The contingencies whose check runs set a site's energy (`size_energy`), each once,
    in name order."""
    return [by_name[n] for n in sorted({energy[j]["set_by"] for j, p in enumerate(mw) if p > 0})]


def energy_half_step(checks: dict, mw, mwh, energy) -> dict:
    """The sized energies against `checks`, the runs that set them (`size_energy`)
    simulated again at half the step: {"max_energy_diff_mwh" (largest change of a site's
    energy need, `energy_need`, MWh), "max_energy_diff_pct" (the largest change relative
    to that site's need, %), "energy_covered_half" (every site's sized energy, margin and
    rounding included, at least its need at half the step)}; None each without sites (the
    percentage also when no site needed any energy at the full step)."""
    used = [j for j, p in enumerate(mw) if p > 0]
    if not used:
        return {
            "max_energy_diff_mwh": None,
            "max_energy_diff_pct": None,
            "energy_covered_half": None,
        }
    half = {j: energy_need(checks[energy[j]["set_by"]], k) for k, j in enumerate(used)}
    diff = {j: abs(half[j] - energy[j]["need_mwh"]) for j in used}
    return {
        "max_energy_diff_mwh": max(diff.values()),
        "max_energy_diff_pct": max(
            (100 * diff[j] / energy[j]["need_mwh"] for j in used if energy[j]["need_mwh"] > 0),
            default=None,
        ),
        "energy_covered_half": all(half[j] <= mwh[j] for j in used),
    }


def energy_note(e: dict) -> str:
    """Progress text of `energy_half_step`'s figures ('' without sites)."""
    if e["max_energy_diff_mwh"] is None:
        return ""
    pct = e["max_energy_diff_pct"]
    return (
        f"; energies within {e['max_energy_diff_mwh']:.3f} MWh"
        + ("" if pct is None else f" ({pct:.1f} %)")
        + " at half the step, "
        + ("covered by the sizing" if e["energy_covered_half"] else "NOT covered")
    )
