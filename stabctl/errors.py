"""Exceptions raised by stabctl.

Every error names what is wrong and where (bus, row, field, iteration, time) so that the
CLI can print it and exit non-zero without a traceback.
"""


class StabctlError(Exception):
    """Base class of all stabctl errors (the CLI turns these into exit status 2)."""


class InputError(StabctlError, ValueError):
    """A parameter is out of its physical range (negative H, Pm above Pmax, ...)."""


class CaseError(StabctlError, ValueError):
    """Malformed case data: names the table, the row and the field."""


class UnknownBusError(CaseError, KeyError):
    """A bus number that is not in the case."""

    def __str__(self):  # KeyError quotes its message; keep it readable
        return str(self.args[0]) if self.args else "unknown bus"


class PowerFlowError(StabctlError, RuntimeError):
    """Power flow did not converge: names the iteration count and the worst mismatch bus."""


class SimulationError(StabctlError, RuntimeError):
    """A dynamic run diverged (NaN, singular network); carries the partial result."""

    def __init__(self, message, result=None):
        super().__init__(message)
        self.result = result


class NumericalInstabilityError(SimulationError):
    """The integration left its stability region (a state alternating from step to step,
    a speed far outside any physical range, a non-finite state): a numerical failure, never
    a stability verdict.  Names the time and the state; carries the partial result."""
