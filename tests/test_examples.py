"""Every script in examples/ runs as a user runs it (a fresh process, its own working
directory) and prints the figures it is about."""

import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).parents[1] / "examples"

#: what each example must print (values from the paper's cases as the tests elsewhere
#: check them: Case 1's CCT 154 ms, the OMIB's equal-area CCT, Kundur's inter-area mode)
SHOWN = {
    "omib_equal_area.py": ["equal-area CCT 0.2437 s", "15 cycles: without storage stable=False"],
    "case2_with_storage.py": ["without storage: stable=False", "5 % ESDs: stable=True"],
    "cct_gain.py": ["no storage: CCT 154 ms", "5 % ESDs: CCT"],
    "modes.py": ["56 states", "0.612 Hz", "inter-area"],
    "screening.py": ["bus 3: CCT 238 ms", "bus 13: CCT above the search limit 0.5 s (robust)"],
    # the speed column of `stabctl estimate rmse kundur --fault 3 --far-bus 101
    # --clear-cycles 6 --tf 6 --runs 3`: 16.289, 16.270, 1.846 mHz (the example cleared the
    # fault 1.1 s after its start and printed 117.9, 117.7, 2.0)
    "pmu_estimation.py": [
        "raw : speed RMSE 16.4 mHz",
        "kf  : speed RMSE 16.4 mHz",
        "ekf : speed RMSE 2.1 mHz",
    ],
    "pmu_stream.py": ["received 361 frames", "ekf : relative-speed RMSE", "stable=True, 360"],
}


def test_every_example_is_checked():
    assert sorted(p.name for p in EXAMPLES.glob("*.py")) == sorted(SHOWN)


@pytest.mark.parametrize("name", sorted(SHOWN))
def test_example_runs_and_prints_its_figures(tmp_path, name):
    res = subprocess.run(
        [sys.executable, str(EXAMPLES / name)],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert res.returncode == 0, res.stderr[-2000:]
    for text in SHOWN[name]:
        assert text in res.stdout, (text, res.stdout)
