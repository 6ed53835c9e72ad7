"""Wall time of ESD placement (not a test).

1. The convex program alone, 34 sites (miniWECC): 10 CCT cuts (gradients drawn at random,
   seed 0, like SIME's: a few sites per contingency), the 33 real damping rows of the
   linearised miniWECC (`stabctl.smallsignal.damping`, zeta_min 0.05), elastic rows and a trust
   region, as inside the loop; median of 20 solves: Clarabel's own time and the wall time with
   cvxpy's canonicalisation.  Target: well under 1 s.
2. The verified placement (`stabctl.placement.loop.place`) of each case's DEFAULT
   contingencies (`stabctl sweep-cct`), targets = CCT of the uniform 5 % fleet, 2 workers:
   wall time, allocations simulated, simulations, total MW.
3. With --study: the whole study (`stabctl.studies.placement`, into reports/) per case.
4. With --activsg (alone): ACTIVSg2000 (imported as bench_scale.py does), ten contingencies
   (`ACTIVSG_FAULTS`: eight line faults with the line tripped, two bus faults, from a random
   sample of its N-1 with CCTs of 0.09-0.45 s and line 2021-2002) at three load levels
   (0.97, 0.985, 1.0: at 0.95 and 1.03 its power flow does not converge with PV Q limits, at
   1.02 a GGOV1 starts above its limit), CCT +5 % (a contingency stable cleared at the
   search limit, 1 s, held stable there), set aside what is infeasible, 2 workers:
   `stabctl place` in a subprocess, its wall and CPU time (children's getrusage), the runs
   and the verdict line.  Target: 30 minutes on 2 cores.

Run: python benchmarks/bench_placement.py [--study] [--activsg]
"""

import sys
import time

import numpy as np

from stabctl.io import load_case
from stabctl.parallel import RunnerOptions
from stabctl.placement.evaluation import Contingency, VerifyOptions
from stabctl.placement.loop import Study, WarmStart, baseline, evaluations, place
from stabctl.placement.program import CCTCut, candidate_sites, solve_allocation
from stabctl.smallsignal.damping import DampingModel, relay_df
from stabctl.smallsignal.linearise import linearise
from stabctl.stability.cct import cached_simulator
from stabctl.studies.cases import DEFAULT_FAULTS


def convex_solve_time(n_rep: int = 20) -> None:
    case = load_case("miniwecc")
    sites = candidate_sites(case)
    sys_ = linearise(
        cached_simulator("miniwecc"), esd_buses=list(dict.fromkeys(s.bus for s in sites))
    )
    rows = DampingModel(sys_, sites, relay_df(0.1, 0.2, case.freq_hz).real, case.base_mva).rows(
        np.zeros(len(sites)), 0.05
    )
    rng = np.random.default_rng(0)
    cuts = []
    for c in range(10):
        g = np.zeros(len(sites))
        g[rng.choice(len(sites), 3, replace=False)] = rng.uniform(1e-5, 3e-4, 3)
        cuts.append(CCTCut(f"c{c}", 0.15, 0.1, g, np.zeros(len(sites))))
    times, walls = [], []
    for _ in range(n_rep):
        a = solve_allocation(
            sites,
            cuts,
            damping=rows,
            cct_penalty=1e5,
            penalty=1e5,
            trust=(np.zeros(len(sites)), 500.0),
            safety_s=0.002,
        )
        times.append(a.solve_time_s)
        walls.append(a.wall_time_s)
    print(
        f"convex program, {len(sites)} sites, {len(cuts)} CCT rows, {len(rows.b)} damping "
        f"rows: Clarabel {1000 * np.median(times):.2f} ms, with cvxpy "
        f"{1000 * np.median(walls):.1f} ms (median of {n_rep}); target < 1000 ms: "
        f"{'ok' if np.median(walls) < 1.0 else 'MISSED'}"
    )


def verified_placement(case_name: str, workers: int = 2) -> None:
    faults = DEFAULT_FAULTS[case_name]
    case = load_case(case_name)
    sites = candidate_sites(case)
    mva = np.array([float(case.machines.mva[case.machine_index(s.machine)]) for s in sites])
    t = time.perf_counter()
    study = Study(runner=RunnerOptions(workers))
    base = baseline(case_name, faults, study)
    plain = [Contingency(f, 1.0) for f in faults]
    uni = evaluations(case_name, plain, 0.05 * mva, study, VerifyOptions(base=base, scan="full"))
    cons = [Contingency(c.fault, uni[c.name]["cct_s"]) for c in plain]
    t_targets = time.perf_counter() - t
    res = place(case_name, cons, study, warm=WarmStart(base=base))
    sims = sum(r["n_simulations"] for r in res.iterations)
    print(
        f"{case_name}: targets (no storage + uniform 5 %) {t_targets:.1f} s; verified "
        f"placement {res.wall_time_s:.1f} s, {len(res.iterations)} allocations, {sims} "
        f"simulations, {res.allocation.total_mw:.1f} MW vs {0.05 * mva.sum():.0f} MW "
        f"uniform, {'verified' if res.verified else 'NOT verified'}"
    )


#: the ten contingencies of --activsg: (bus, far bus or None, circuit or None)
ACTIVSG_FAULTS = (
    (6030, 7274, 1),
    (2021, 2002, 1),
    (8079, None, None),
    (1064, None, None),
    (2101, 5083, 1),
    (5252, 5340, 1),
    (5480, 5048, 4),
    (4159, 4168, 3),
    (5161, 5272, 1),
    (5316, 5161, 1),
)


def activsg_placement(workers: int = 2) -> None:
    """ACTIVSg2000's placement for ten contingencies at three load levels (module doc)."""
    import resource
    import subprocess
    import tempfile
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).parent))
    from bench_scale import _activsg2000

    from stabctl.io.pst import write_case_json

    with tempfile.TemporaryDirectory() as work:
        case_path, faults = Path(work) / "activsg.json", Path(work) / "faults.csv"
        write_case_json(_activsg2000(work), case_path)
        rows = [
            ",".join("" if v is None else str(v) for v in fault) for fault in ACTIVSG_FAULTS
        ]  # a bus fault names no circuit
        faults.write_text("bus,far_bus,circuit\n" + "\n".join(rows) + "\n")
        args = ["stabctl", "place", str(case_path), "--faults", str(faults)]
        args += ["--target-cct-gain", "5", "--set-aside-infeasible"]
        args += ["--load-levels", "0.97,0.985,1.0", "--workers", str(workers)]
        print("settings:", " ".join(args[2:]).replace(work, "."), flush=True)
        subprocess.run(["stabctl", "compile"], check=True, capture_output=True)
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t = time.perf_counter()
        out = subprocess.run(args, capture_output=True, text=True)
        wall = time.perf_counter() - t
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    print(out.stdout.strip() or out.stderr[-500:])  # the plan, contingency by contingency
    print(
        f"activsg2000: 10 contingencies x 3 load levels, {workers} workers: wall "
        f"{wall / 60:.1f} min, CPU {cpu / 60:.1f} min, exit {out.returncode} "
        f"(target 30 min wall on 2 cores)"
    )


def main():
    if "--activsg" in sys.argv:
        activsg_placement()
        return
    convex_solve_time()
    for name in ("kundur", "miniwecc"):
        verified_placement(name)
    if "--study" in sys.argv:
        from stabctl.studies.placement import placement_study

        for name in ("kundur", "miniwecc"):
            t = time.perf_counter()
            path = placement_study(name, "reports", progress=lambda msg: None)
            print(f"{name}: whole study {time.perf_counter() - t:.0f} s -> {path}")


if __name__ == "__main__":
    main()
