"""Independent check of a `stabctl place --out PLAN.json` plan: each contingency the plan
says is met is searched again here with the plan's devices (its allocation rows: bus,
machine, MW; the plan's law from settings.controller; unlimited energy, then a run at the
required time with the sized MWh), by the library's CCT search from scratch (bisection,
the plan's tol/t_max/step/conventions/Q limits).

    PYTHONPATH=<clone> python verify_plan.py CASE.json PLAN.json

Prints one JSON line per contingency: name, required, plan's CCT, this CCT, met here,
within the 1 ms cell of the plan's, finite-energy run stable at the required time.
"""

import json
import re
import sys
from pathlib import Path

from stabctl.dynamics.options import ModelOptions
from stabctl.io import load_case
from stabctl.stability.cct import T_AFTER_FAULT, LineFault, SearchOptions, critical_clearing_time
from stabctl.storage.control import BangBangCOI
from stabctl.storage.devices import StorageDevice, StorageFleet

case_path, plan_path = sys.argv[1], sys.argv[2]
plan = json.loads(Path(plan_path).read_text())
st = plan["settings"]
law = dict(st["controller"])
if law.get("coi") == "critical":
    print(json.dumps({"skip": "coi critical"}))
    sys.exit(0)
law.pop("critical", None)
ctrl = BangBangCOI(**law)
case = load_case(case_path)
model = ModelOptions(
    conventions=st["conventions"],
    h=st["step_s"],
    q_limits=st["q_limits"],
    subintervals=st.get("subintervals", True),
)
sim = model.simulator(case)
alloc = plan["allocation"]
fleet = (
    StorageFleet(
        tuple(StorageDevice(int(a["bus"]), int(a["machine"]), float(a["mw"])) for a in alloc), ctrl
    )
    if alloc
    else None
)
fleet_e = (
    StorageFleet(
        tuple(
            StorageDevice(
                int(a["bus"]), int(a["machine"]), float(a["mw"]), energy_mj=float(a["mwh"]) * 3600.0
            )
            for a in alloc
        ),
        ctrl,
    )
    if alloc
    else None
)
tol = st["tol_s"]
search = SearchOptions(tol=tol, t_max=st["t_max_s"], t_end=st["t_end_s"], error_check=False)
print(
    json.dumps(
        {
            "n_sites": len(alloc),
            "total_mw": sum(a["mw"] for a in alloc),
            "verified": plan["verified"],
            "message": plan["message"][:200],
        }
    ),
    flush=True,
)
for c in plan["contingencies"]:
    if c["load"] not in (1, 1.0):
        continue
    m = re.match(r"fault at bus (\d+)(?: on line (\d+)-(\d+))? at ([\d.]+) s", c["fault"])
    bus, far, t_f = int(m.group(1)), (int(m.group(3)) if m.group(2) else None), float(m.group(4))
    f = LineFault(bus, far, t_f)
    out = {
        "name": c["name"],
        "met": c["met"],
        "required_s": c["required_s"],
        "plan_cct_s": c["cct_s"],
        "plan_cct0_s": c["cct_no_storage_s"],
    }
    if not c["met"] or fleet is None:
        print(json.dumps(out), flush=True)
        continue
    try:
        r = critical_clearing_time(sim, f, search, storage=fleet, h=st["step_s"])
        out["cct_here_s"] = r.cct_s
        out["met_here"] = r.cct_s >= c["required_s"] - 1e-9
        if c["cct_s"] is not None:
            out["same_cell"] = abs(r.cct_s - c["cct_s"]) <= tol + 1e-9
    except Exception as e:  # noqa: BLE001
        out["cct_here_error"] = f"{type(e).__name__}: {e}"[:300]
    try:
        run = sim.run(
            f.events(c["required_s"]), t_f + T_AFTER_FAULT, storage=fleet_e, stop_at_separation=True
        )
        out["finite_energy_stable_at_required"] = bool(run.stable)
    except Exception as e:  # noqa: BLE001
        out["finite_energy_error"] = f"{type(e).__name__}: {e}"[:300]
    print(json.dumps(out), flush=True)
