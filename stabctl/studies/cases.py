"""The paper's two simulation cases: the ONE definition of their faults.

Case 1 (paper Section 5.1, Figs. 14-15): Kundur's two-area system, a three-phase fault at
PST bus 3 (Kundur bus 7) on line 3-101 (Kundur 7-8) at t = 1 s, the line tripped at
clearing.  Case 2 (paper Section 5.2, Figs. 17-19, Table 4): the miniWECC, a three-phase
fault at bus 83 on line 83-33 next to the Colstrip unit, the line tripped at clearing.

Each study chooses its own clearing time (the paper's figures, a CCT search, an estimator
run with a fault long enough to swing but short enough to stay stable); the clearing
cycles that a study uses are named beside the case here, so that no study writes the
fault out again.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from stabctl.errors import InputError
from stabctl.stability.cct import LineFault

__all__ = ["PaperCase", "CASE1", "CASE2", "PAPER_CASES", "DEFAULT_FAULTS", "default_faults"]


@dataclass(frozen=True)
class PaperCase:
    """One of the paper's simulation cases.

    Attributes
    ----------
    label : str
        "Case 1" or "Case 2" (the paper's names).
    case : str
        Built-in case name (:func:`stabctl.io.load_case`).
    fault : LineFault
        The fault: bus, far bus (line tripped at clearing), start time (s).
    t_end : float
        End of the figure runs (s).
    cycles : Mapping[str, float]
        Clearing after the fault start, in cycles of the case's frequency, per use:
        ``"figure"`` the paper's figure, ``"estimation"`` the estimator RMSE runs (long
        enough to swing, stable without storage).
    """

    label: str
    case: str
    fault: LineFault
    t_end: float
    cycles: Mapping[str, float] = field(default_factory=dict)

    @property
    def bus(self) -> int:
        """Faulted bus (PST numbering)."""
        return self.fault.bus

    @property
    def far_bus(self) -> int:
        """Far end of the faulted line (PST numbering)."""
        return self.fault.far_bus  # type: ignore[return-value]  # a paper case's: a line fault


CASE1 = PaperCase(
    "Case 1",
    "kundur",
    LineFault(3, 101, 1.0),
    t_end=8.0,
    cycles={"figure": 11, "paper": 21, "estimation": 7.0},
)
CASE2 = PaperCase(
    "Case 2",
    "miniwecc",
    LineFault(83, 33, 1.0),
    t_end=10.0,
    cycles={"figure": 6, "paper": 6, "estimation": 4.0},
)

#: the paper's cases by built-in case name
PAPER_CASES: Mapping[str, PaperCase] = {c.case: c for c in (CASE1, CASE2)}

#: Built-in fault lists of ``stabctl sweep-cct CASE --faults DEFAULT`` and the placement
#: study: the paper's fault and one more tie-line fault of each case.
DEFAULT_FAULTS: Mapping[str, tuple[LineFault, ...]] = {
    "kundur": (CASE1.fault, LineFault(13, 101, 1.0)),
    "miniwecc": (CASE2.fault, LineFault(40, 44, 1.0)),
}


def default_faults(case_name: str) -> tuple[LineFault, ...]:
    """The DEFAULT fault list of a built-in case.

    Parameters
    ----------
    case_name : str
        "kundur" or "miniwecc".

    Returns
    -------
    tuple of LineFault

    Raises
    ------
    InputError
        For any other case (the message names the cases that have one).
    """
    try:
        return DEFAULT_FAULTS[case_name]
    except KeyError:
        raise InputError(
            f"no DEFAULT fault list for case '{case_name}' (there is one for "
            f"{', '.join(DEFAULT_FAULTS)}); give --faults FILE.csv"
        ) from None
