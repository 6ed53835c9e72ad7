"""The paper report's scorecard: each claim a section states (`scorecard.claim`) becomes a
row at the top of ``paper.md``, its verdict computed from the section's own figures."""

from types import SimpleNamespace

import numpy as np
import pytest

from stabctl.studies import paper
from stabctl.studies.paper_storage import first_actions
from stabctl.studies.scorecard import AGREES, DIFFERS, claim, gather


def test_gather_takes_the_rows_out_of_the_sections_in_order():
    parts = [
        "## 1\n" + claim("1", "x = 1", "1.0001", True) + "\ntext",
        "## 2\n" + claim("2", "y = 2", "3", False, "see 2"),
        "## 3 no claim",
    ]
    table, kept = gather(parts)
    assert kept == ["## 1\ntext", "## 2", "## 3 no claim"]
    assert "1 of 2 claims of the paper agree" in table[2]
    assert table[-3:] == [
        f"| 1 | x = 1 | 1.0001 | {AGREES} |",
        f"| 2 | y = 2 | 3 | {DIFFERS}: see 2 |",
        "",
    ]
    assert gather(["## none"]) == ([], ["## none"])


def test_the_first_action_of_each_device_after_clearing_is_its_sign():
    t = np.arange(6) * 0.1
    pesd = np.array([[0, 0], [0.5, -0.5], [0, 0], [0, 0.5], [-0.5, 0], [0, 0]])
    res = SimpleNamespace(t=t, pesd=pesd, devices=np.array([1, 2]))  # the fields it reads
    assert first_actions(res, 0.0) == {1: 1.0, 2: -1.0}
    assert first_actions(res, 0.15) == {1: -1.0, 2: 1.0}  # after t = 0.15 s only
    assert first_actions(res, 0.45) == {}


@pytest.mark.heavy
def test_the_analytic_part_s_claims_agree_with_tables_1_and_2(tmp_path):
    """Table 1 (0.15 % apart: the paper's omega0) and Table 2 agree; the minimum-time
    input is the full pulse; of Fig. 7's statements the combined law's speed swing is not
    below both laws alone (8.69 rad/s between 8.19 and 10.87)."""
    text = paper.write_paper_report(tmp_path, progress=lambda m: None, only=["analytic"])
    report = text.read_text()
    rows = [s for s in report.split("\n") if s.startswith("| 1 |") or s.startswith("| 3 |")]
    assert len(rows) == 3 and all(r.endswith(AGREES + " |") or f"{AGREES}:" in r for r in rows)
    assert "3 of 4 claims of the paper agree" in report
    assert "6 of 7 hold (not: combined law: speed swing below both alone)" in report
    assert "<!-- scorecard" not in report
