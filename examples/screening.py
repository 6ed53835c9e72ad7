"""Contingency screening: the CCT of a bolted fault at each of four Kundur buses, in
parallel processes, recorded in screening.jsonl (rerunning resumes), most critical first.

    python examples/screening.py
"""

from stabctl.parallel import RunnerOptions
from stabctl.stability.cct import SearchOptions
from stabctl.stability.screening import screen


def main():
    rows = screen(
        "kundur",
        "screening.jsonl",
        buses=[3, 13, 101, 120],
        search=SearchOptions(t_max=0.5),
        runner=RunnerOptions(workers=2, progress=False),
    )
    for r in rows:  # a fault still stable at t_max is recorded with the reason
        cct = f"{1000 * r['cct_s']:.0f} ms" if r["status"] == "ok" else r["error"]
        print(f"bus {r['bus']}: CCT {cct}")


if __name__ == "__main__":
    main()
