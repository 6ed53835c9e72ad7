"""Print how closely stabctl's power flow matches PSTess's solved bus matrices.

    /work/venv/bin/python analysis/compare_powerflow_pstess.py

References: tests/data/pstess/*_loadflow_bus.csv (PSTess 1.1 bus_sol, copied from shared/).
"""

from pathlib import Path

import numpy as np

from stabctl.io import load_case
from stabctl.network.powerflow import solve_powerflow

DATA = Path(__file__).resolve().parents[1] / "tests" / "data" / "pstess"
REFS = {
    "kundur": "kundur_d2asbegp_default_loadflow_bus.csv",
    "miniwecc": "miniwecc_base_default_loadflow_bus.csv",
}

for name, ref_file in REFS.items():
    ref = np.loadtxt(DATA / ref_file, delimiter=",")
    res = solve_powerflow(load_case(name))
    got = res.bus_matrix()
    dv = np.max(np.abs(got[:, 1] - ref[:, 1]))
    da = np.max(np.abs(got[:, 2] - ref[:, 2]))
    dpq = np.max(np.abs(got[:, 3:7] - ref[:, 3:7]))
    rest = np.max(np.abs(got[:, 7:] - ref[:, 7:]))
    print(
        f"{name:9s} buses {len(ref):4d}  iterations {res.iterations}  "
        f"max|dV| {dv:.2e} pu  max|dtheta| {da:.2e} deg  max|dPQ| {dpq:.2e} pu  "
        f"cols 8-15 max diff {rest:.1e}"
    )
