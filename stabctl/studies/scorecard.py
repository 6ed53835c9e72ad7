"""The paper report's scorecard: each claim of the paper a section reproduces, the paper's
figure, ours and whether they agree, gathered at the top of ``reports/paper.md``.

A section states a claim where it computes it (`claim`): a marker line in its text, which
`gather` takes out and turns into the table, so that each row comes from the same numbers
as the section it summarises, and a part left out of the run leaves its rows out.
"""

from __future__ import annotations

import json

__all__ = ["AGREES", "DIFFERS", "claim", "gather"]

#: the verdicts of a row
AGREES, DIFFERS = "agrees", "differs"
#: how a claim's marker line starts (an HTML comment: invisible if one were left)
_MARK = "<!-- scorecard "


def claim(section: str, paper: str, ours: str, agrees: bool, why: str = "") -> str:
    """One row of the scorecard, as a marker line a section puts in its text.

    Parameters
    ----------
    section : str
        Where the report gives the details (``"1"``, ``"6"``).
    paper : str
        The paper's claim with its figure and where it is (``"Table 1: ..."``).
    ours : str
        Our figure, computed by the section.
    agrees : bool
        Whether our figure bears the claim out (computed, not written in).
    why : str, optional
        Where a difference is explained, or a qualifier of an agreement.

    Returns
    -------
    str
        The marker line (`gather` takes it out of the text).
    """
    verdict = AGREES if agrees else DIFFERS
    return _MARK + json.dumps([section, paper, ours, verdict, why]) + " -->"


def gather(parts: list[str]) -> tuple[list[str], list[str]]:
    """The scorecard of a report's parts, and the parts without their marker lines.

    Parameters
    ----------
    parts : list of str
        The report's sections, in order.

    Returns
    -------
    table : list of str
        The scorecard's markdown lines (a heading, a count of the claims that agree, the
        table), empty when no section stated a claim.
    parts : list of str
        The sections without the marker lines.
    """
    rows, kept = [], []
    for text in parts:
        lines = text.split("\n")
        rows += [json.loads(s[len(_MARK) : -len(" -->")]) for s in lines if s.startswith(_MARK)]
        kept.append("\n".join(s for s in lines if not s.startswith(_MARK)))
    if not rows:
        return [], kept
    n_agree = sum(r[3] == AGREES for r in rows)
    table = [
        "## Scorecard",
        "",
        f"{n_agree} of {len(rows)} claims of the paper agree with ours; each row's section "
        "gives the runs and, where they differ, the hypotheses tested.",
        "",
        "| section | the paper | ours | verdict |",
        "|---|---|---|---|",
    ]
    for section, paper, ours, verdict, why in rows:
        said = f"{verdict}: {why}" if why else verdict
        table.append(f"| {section} | {paper} | {ours} | {said} |")
    return [*table, ""], kept
