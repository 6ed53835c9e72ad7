"""How a case is simulated: model conventions, integration step and power-flow Q limits,
one settings object passed from the CLI to the searches, sweeps, placement and estimation
studies instead of three parameters in every signature.

A sweep records these settings in each job's inputs (`to_inputs`, `from_inputs`) exactly
as the flat fields it always wrote (``conventions``, ``h``, and ``q_limits`` only when
off), so records written before stay valid for resuming.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from stabctl.dynamics.model import check_conventions
from stabctl.errors import InputError


@dataclass(frozen=True)
class ModelOptions:
    """Model settings of every run of a study.

    Attributes
    ----------
    conventions : str
        ``"ieee"`` (IEEE Std 421.5 limiters, the default) or ``"pstess"`` (PSTess 1.1 bit
        for bit), docs/conventions.md.
    h : float or None
        Integration step, s; None: the simulator's default (`Simulator.default_h`).
    q_limits : bool
        PV generators' reactive-power limits enforced in the power flow.
    subintervals : bool
        Heun runs integrate exciter loops faster than their step in sub-steps of their
        own (True, the default; `stabctl.dynamics.subinterval`), or the whole model at one
        step, which such a loop then bounds (False).

    Raises
    ------
    InputError
        Unknown conventions, or a step that is not > 0.
    """

    conventions: str = "ieee"
    h: float | None = None
    q_limits: bool = True
    subintervals: bool = True

    def __post_init__(self) -> None:
        check_conventions(self.conventions)
        if self.h is not None and not self.h > 0:
            raise InputError(f"integration step must be > 0 s, got {self.h:g}")

    def simulator(self, case, **kwargs):
        """A `stabctl.dynamics.driver.Simulator` of `case` with these settings
        (``kwargs``: its other arguments, e.g. ``injection_buses``)."""
        from stabctl.dynamics.driver import Simulator

        return Simulator(
            case,
            conventions=self.conventions,
            step=self.h,
            q_limits=self.q_limits,
            subintervals=self.subintervals,
            **kwargs,
        )

    def key_suffix(self) -> str:
        """Sweep-key tail: '/pstess', '/h<step>', '/no-q-limits', '/single-rate' for
        non-default fields."""
        return (
            ("" if self.conventions == "ieee" else f"/{self.conventions}")
            + ("" if self.h is None else f"/h{self.h:g}")
            + ("" if self.q_limits else "/no-q-limits")
            + ("" if self.subintervals else "/single-rate")
        )

    def to_inputs(self) -> dict:
        """Fields of a job's recorded inputs: conventions, h, and q_limits and
        subintervals when off."""
        return {
            "conventions": self.conventions,
            "h": self.h,
            **({} if self.q_limits else {"q_limits": False}),
            **({} if self.subintervals else {"subintervals": False}),
        }

    @classmethod
    def from_inputs(cls, inputs: Mapping) -> ModelOptions:
        """The settings recorded in a job's inputs (`to_inputs`; absent fields default)."""
        return cls(
            conventions=inputs.get("conventions", "ieee"),
            h=inputs.get("h"),
            q_limits=bool(inputs.get("q_limits", True)),
            subintervals=bool(inputs.get("subintervals", True)),
        )
