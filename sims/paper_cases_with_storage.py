"""The paper's Cases 1 and 2 with and without 5 % ESDs, and Table 4 (CCT versus rating).

Calls the library only; writes the same sections `stabctl paper` writes, into reports/.
Run: python sims/paper_cases_with_storage.py
"""

from pathlib import Path

from stabctl.studies.paper_storage import section_case1, section_case2, section_table4


def main(out=Path("reports")):
    out.mkdir(exist_ok=True)
    for section in (section_case1, section_case2):
        print(section(out))
    print(section_table4(out, out))


if __name__ == "__main__":
    main()
