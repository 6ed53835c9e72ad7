"""The paper's single machine (OMIB): critical clearing time from the equal-area
criterion, and a 15-cycle fault that the feedback law of Section 3 keeps stable.

    python examples/omib_equal_area.py
"""

from stabctl.smib.feedback import PAPER_LAWS
from stabctl.smib.omib import PAPER_OMIB, simulate


def main():
    cct = PAPER_OMIB.critical_clearing_time()
    print(f"equal-area CCT {cct:.4f} s = {cct * 60:.2f} cycles")
    for cycles in (12, 15):
        bare = simulate(PAPER_OMIB, t_clear=cycles / 60, t_end=5.0)
        ctrl = simulate(PAPER_OMIB, t_clear=cycles / 60, t_end=5.0, law=PAPER_LAWS[3])
        print(f"{cycles} cycles: without storage stable={bare.stable}, with the law {ctrl.stable}")


if __name__ == "__main__":
    main()
