"""Contingency screening: the CCT of a bolted fault at each of four Kundur buses, in
parallel processes, recorded in screening_kundur.jsonl (rerunning resumes), most critical first.

    python examples/screening.py
"""

from stabctl.parallel import RunnerOptions
from stabctl.stability.cct import SearchOptions
from stabctl.stability.screening import screen


def main():
    rows = screen(
        "kundur",
        "screening_kundur.jsonl",
        buses=[3, 13, 101, 120],
        search=SearchOptions(t_max=0.5),
        runner=RunnerOptions(workers=2, progress=False),
    )
    for r in rows:  # verdict: "cct", "above t_max" (robust), "N-1 insecure" or "failed"
        if r["verdict"] == "cct":
            print(f"bus {r['bus']}: CCT {1000 * r['cct_s']:.0f} ms")
        elif r["verdict"] == "above t_max":
            print(f"bus {r['bus']}: CCT above the search limit {r['t_max_s']:g} s (robust)")
        elif r["verdict"] == "N-1 insecure":
            print(f"bus {r['bus']}: N-1 insecure, unstable even when cleared at once (CCT 0)")
        else:
            print(f"bus {r['bus']}: failed ({r['error']})")


if __name__ == "__main__":
    main()
