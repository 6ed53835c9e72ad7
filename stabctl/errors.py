"""Exceptions raised by stabctl.

Every error names what is wrong and where (bus, row, field, iteration, time) so that the
CLI can print it and exit non-zero without a traceback; `counted` puts a count and its
noun in agreement in every message and report ("1 contingency", "2 contingencies").
"""

import dataclasses
from collections.abc import Iterator
from contextlib import AbstractContextManager, contextmanager
from contextvars import ContextVar
from numbers import Integral, Real

import numpy as np

#: "cli" while a command of stabctl's command line runs (`on_command_line`), else
#: "library": which of its words a message's advice takes (`advice`)
_FRONT: ContextVar[str] = ContextVar("stabctl_front", default="library")


def counted(n: int, noun: str, plural: str | None = None) -> str:
    """A count and its noun, singular for one: ``"1 frame"``, ``"181 frames"``.

    Parameters
    ----------
    n : int
        The count.
    noun : str
        The noun for one.
    plural : str, optional
        The noun for any other count; default `noun` + "s".

    Returns
    -------
    str
    """
    return f"{n} {noun if n == 1 else plural or noun + 's'}"


def advice(library: str, cli: str = "") -> str:
    """A message's advice on what to do, in the words of the caller: ``library`` (a
    function's argument, ``on_unsupported='skip'``) when stabctl is called as a library,
    ``cli`` (a command-line option, ``--skip-unsupported``) inside a command of its
    command line (`on_command_line`), where an option the command lacks is never
    advised ('' where none exists).

    Parameters
    ----------
    library : str
        The advice to a library's caller.
    cli : str, optional
        The advice to a command line's user; default none.

    Returns
    -------
    str
        The one for the caller.
    """
    return cli if _FRONT.get() == "cli" else library


def on_command_line() -> AbstractContextManager[None]:
    """Within this block errors advise command-line options, not Python arguments
    (`advice`): a command of stabctl's command line runs in it
    (`stabctl.cli.options.reports_errors`).

    Returns
    -------
    context manager
        The block runs as a command.
    """
    return speaking("cli")


def front() -> str:
    """Whose words messages take here (`advice`): ``"cli"`` inside a command of the
    command line, else ``"library"``; a worker process of a command is given its parent's
    (`stabctl.parallel`), whose errors and warnings advised Python arguments.

    Returns
    -------
    str
    """
    return _FRONT.get()


@contextmanager
def speaking(name: str) -> Iterator[None]:
    """Within this block messages take the words of `name` (`front`'s values).

    Parameters
    ----------
    name : str
        ``"cli"`` or ``"library"``.

    Yields
    ------
    None
        Nothing: the block runs in those words.
    """
    token = _FRONT.set(name)
    try:
        yield
    finally:
        _FRONT.reset(token)


def require_flag(value, name: str) -> bool:
    """``value`` when it is a bool (numpy's too), else `WrongTypeError` naming ``name``: a text
    such as ``"no"`` or ``"False"`` is true to Python and turned the setting on.

    Parameters
    ----------
    value : object
        The argument.
    name : str
        How to name it (``"Simulator(q_limits)"``).

    Returns
    -------
    bool

    Raises
    ------
    WrongTypeError
        Not a bool.
    """
    if not isinstance(value, (bool, np.bool_)):
        raise WrongTypeError(f"{name} must be True or False, got {value!r}")
    return bool(value)


def is_number(value) -> bool:
    """True for a real number (Python's or numpy's int or float, or a 0-d array of one:
    ``np.asarray(5.0)``), False for a bool, a text, None, a complex number or an array of
    one or more axes.

    Parameters
    ----------
    value : object
        The argument.

    Returns
    -------
    bool
    """
    if isinstance(value, np.ndarray):
        return value.ndim == 0 and value.dtype.kind in "iuf"
    return isinstance(value, Real) and not isinstance(value, (bool, np.bool_))


def is_whole_number(value) -> bool:
    """True for a number with no fraction (``3``, numpy's ``int64(3)``, ``3.0`` as the
    case tables hold bus numbers), False otherwise (a bool, a text, ``3.5``, NaN).

    Parameters
    ----------
    value : object
        The argument.

    Returns
    -------
    bool
    """
    if isinstance(value, Integral):
        return not isinstance(value, (bool, np.bool_))
    return is_number(value) and float(value).is_integer()


def require_number(value, name: str, unit: str = "") -> float:
    """``float(value)`` when it is a real number, else `WrongTypeError` naming ``name``
    (a text ``'0.005'`` failed deep inside with "'<' not supported between instances of
    'int' and 'str'").  The range is the caller's to check.

    Parameters
    ----------
    value : object
        The argument.
    name : str
        How to name it (``"Simulator(step)"``).
    unit : str, optional
        Its unit, said in the message (``"s"``).

    Returns
    -------
    float

    Raises
    ------
    WrongTypeError
        Not a real number (a bool, a text, None, an array).
    """
    if not is_number(value):
        of = f" of {unit}" if unit else ""
        raise WrongTypeError(f"{name}: a number{of} is needed, got {_shown(value)}")
    return float(value)


def require_items(value, name: str, wanted: str) -> list:
    """The items of ``value`` as a list when it is a collection (a list, a tuple, an array,
    a generator), else `WrongTypeError` naming ``name``: a text was read one character an
    item, a number failed with "'int' object is not iterable".

    Parameters
    ----------
    value : object
        The argument.
    name : str
        How to name it (``"run(events)"``).
    wanted : str
        What goes there (``"a list of events"``).

    Returns
    -------
    list

    Raises
    ------
    WrongTypeError
        A text, bytes, a mapping or anything that is not iterable.
    """
    if isinstance(value, (str, bytes, dict)) or not hasattr(value, "__iter__"):
        raise WrongTypeError(f"{name}: {wanted} is needed, got {_shown(value)}")
    return list(value)


def require_instance(value, kind: type, name: str, none: bool = False):
    """``value`` when it is a ``kind`` (or None, where `none`), else `WrongTypeError`
    naming ``name`` and the settings object needed (``Study(search)``: "SearchOptions(...)
    is needed, got None").

    Parameters
    ----------
    value : object
        The argument.
    kind : type
        Its class.
    name : str
        How to name it (``"Study(search)"``).
    none : bool, optional
        Whether None is taken.

    Returns
    -------
    object
        `value`.

    Raises
    ------
    WrongTypeError
        Of another type.
    """
    if not (isinstance(value, kind) or (none and value is None)):
        alone = f"{kind.__name__}(...)" + (" or None" if none else "")
        raise WrongTypeError(f"{name}: {alone} is needed, got {value!r}")
    return value


def check_fields(obj) -> None:
    """`WrongTypeError` naming the class and the field when a field of the dataclass
    ``obj`` annotated ``int``, ``float`` or ``bool`` (or one of them ``| None``) holds
    another type: ``Fault('3', 1.0)`` ran as bus 3, ``LineFault(3, 101, '1')`` failed
    in the search with a numpy message.  An ``int`` field takes a number with no fraction
    (``3.0``: the case tables hold bus numbers as floats) and holds it as an int from then
    on, so that it reads "bus 3" where it is shown, not "bus 3.0"; a ``float`` field any
    real number (`is_number`), held as Python's float.  Other fields are not checked here.

    Parameters
    ----------
    obj : dataclass instance
        The object, from its ``__post_init__``; its annotations are text (``from
        __future__ import annotations``) or types.

    Raises
    ------
    WrongTypeError
        A field holding another type than its annotation's.
    """
    for f in dataclasses.fields(obj):
        ann = f.type if isinstance(f.type, str) else getattr(f.type, "__name__", str(f.type))
        kinds = {k.strip() for k in ann.split("|")}
        value = getattr(obj, f.name)
        if value is None and "None" in kinds:
            continue
        name = f"{type(obj).__name__}({f.name})"
        if "bool" in kinds:
            require_flag(value, name)
        elif "int" in kinds:
            if not is_whole_number(value):
                raise WrongTypeError(f"{name}: a whole number is needed, got {_shown(value)}")
            object.__setattr__(obj, f.name, int(value))
        elif "float" in kinds:  # held as Python's float (a 0-d array, numpy's float32)
            object.__setattr__(obj, f.name, require_number(value, name))


def number_text(x: float) -> str:
    """A number as a message gives it: short (``:g``) unless that rounds it, then all its
    digits (``--rate 59.9999999`` was said as "--rate 60: must be one of ..., 60"), an
    integer's as written.

    Parameters
    ----------
    x : float
        The number.

    Returns
    -------
    str
    """
    short = f"{x:g}"
    if float(short) == x:
        return short
    return repr(x) if isinstance(x, int) else repr(float(x))


def _shown(value) -> str:
    """A value as a message shows it: its repr (cut at 60 characters) and its type."""
    text = repr(value)
    text = text if len(text) <= 60 else text[:57] + "..."
    return f"{text} ({type(value).__name__})"


def bus_numbers(value, name: str, wanted: str = "bus numbers") -> list[int]:
    """The bus numbers of a list argument as ints, else `WrongTypeError` naming ``name``: a
    text (``"13"`` was read one character an item: buses 1 and 3), a number or a 0-d
    array where a list goes, or an item with a fraction (``3.5`` was bus 3).

    Parameters
    ----------
    value : object
        The argument: a list, tuple, array or other collection of whole numbers.
    name : str
        How to name it (``"run(voltages)"``).
    wanted : str, optional
        What goes there; default "bus numbers".

    Returns
    -------
    list of int

    Raises
    ------
    WrongTypeError
        Not a collection of whole numbers.
    """
    if isinstance(value, (str, bytes)):
        raise WrongTypeError(f"{name}: {wanted}, got the text {value!r}")
    if isinstance(value, np.ndarray) and value.ndim != 1:  # a 0-d array cannot be iterated
        raise WrongTypeError(f"{name}: {wanted} (one row), got {_shown(value)}")
    items = require_items(value, name, f"a list of {wanted}")
    odd = [b for b in items if not is_whole_number(b)]
    if odd:
        raise WrongTypeError(f"{name}: {wanted}, got {_shown(odd[0])} among them")
    return [int(b) for b in items]


class StabctlError(Exception):
    """Base class of all stabctl errors (the CLI turns these into exit status 2)."""


class InputError(StabctlError, ValueError):
    """A parameter is out of its physical range (negative H, Pm above Pmax, ...)."""


class WrongTypeError(InputError, TypeError):
    """An argument of another type than its parameter's (a text where a number goes, a
    number where a list goes), named with its function or class; a `TypeError` as Python
    has it and an `InputError` as the CLI has it."""


class Verdict(StabctlError):
    """A study's answer that ends a search without a number, not a failure: sweeps
    (`stabctl.parallel.run_job`) record it with status "verdict", its `label` and the
    message, and never rerun it as failed.  A library call raises it (as its
    `InputError` subclasses do) so that code expecting a number cannot mistake it for one."""

    #: the verdict's label in records, tables and summaries
    label = "verdict"
    #: the contingency's islanding (`SimulationResult.meta` ``islanded``: per stage the
    #: buses cut from every generator, t_s, buses, load_shed_pu, and each island apart from
    #: the main grid, t_s, buses, machines), set by the search; empty: none
    islanded: tuple = ()
    #: the simulations the search ran to reach the verdict (set by the search; None: not
    #: counted)
    n_simulations: int | None = None
    #: a robust fault's stable run at the search limit ending off a normal operating point
    #: (`stabctl.dynamics.results.SimulationResult.end_concerns`: a phrase each) and the
    #: time it ended, s (set by the search; empty and None: none)
    end_concerns: tuple = ()
    end_t_s: float | None = None
    #: what the verdict answers (a CCT job's fault and storage rating, recorded with it
    #: and checked against its inputs on resume); empty: not said
    searched: dict = {}  # noqa: RUF012 - a class default, replaced, never mutated


class AboveSearchLimit(InputError, Verdict):
    """A CCT search found the fault still stable when cleared at its upper limit t_max: the
    CCT is above it.  A verdict on a robust fault, not a failure: sweeps record it as such
    and `screen`, `sweep-cct` and `cct` report it apart from failed searches."""

    label = "above t_max"


class InsecureContingency(InputError, Verdict):
    """A fault whose post-fault system loses synchronism even when cleared at once (the
    line trip alone is unstable): the system is N-1 insecure for this contingency, its CCT
    is 0.  A verdict, not a failure (`Verdict`)."""

    label = "N-1 insecure"


class CaseError(StabctlError, ValueError):
    """Malformed case data: names the table, the row and the field.

    Raised by a case table (`stabctl.case.system.Table`) it also says so in attributes,
    for an importer to name the source record and parameters instead
    (`stabctl.io.provenance`): ``table`` (``"exc_con"``), ``row`` (0-based), ``fields``
    (the table fields or ``alt`` names the rule reads, the one named first), ``values``
    (their values on that row) and ``rule`` (what the data must be, without the
    location); None and empty for an error of no one row.
    """

    def __init__(
        self,
        message: str = "",
        *,
        table: str | None = None,
        row: int | None = None,
        fields: tuple[str, ...] = (),
        values: tuple[float, ...] = (),
        rule: str = "",
    ):
        super().__init__(message)
        self.table, self.row, self.fields = table, row, tuple(fields)
        self.values, self.rule = tuple(values), rule

    def relocated(self, message: str) -> "CaseError":
        """The same error (type and attributes) with another message.

        Parameters
        ----------
        message : str
            The new message (the old one with its file named, or the source record's).

        Returns
        -------
        CaseError
            Of this error's type, with its attributes (``table``, ``row``, ``fields``,
            ``values``, ``rule``, a subclass's own) copied.
        """
        exc = type(self).__new__(type(self))  # a subclass's own __init__ takes other args
        exc.__dict__.update(self.__dict__)
        exc.args = (message,)
        return exc


class InitialLimitError(CaseError):
    """Controls whose initial point (from the power flow) lies outside their own limits.

    Attributes: table (``"exc_con"`` or ``"tg_con"``), rows (0-based rows of that table,
    every offending one), messages (one per row, naming the limit and the value).
    """

    def __init__(self, table: str, rows, messages):
        rows, messages = tuple(rows), tuple(messages)
        more = len(rows) - 1
        also = f" (and {more} more {table} row(s): {messages[1]}; ...)" if more else ""
        super().__init__(messages[0] + also, table=table, row=rows[0] if rows else None)
        self.rows, self.messages = rows, messages


#: where `refuse_initial` records instead of raising (`run_on_suspect_starts`), or None
_SUSPECT: ContextVar[list[InitialLimitError] | None] = ContextVar(
    "stabctl_suspect_starts", default=None
)


def refuse_initial(table: str, bad, message) -> None:
    """Raise :class:`InitialLimitError` for the True entries of ``bad`` (boolean array over
    the table's rows), ``message(i)`` describing row i (0-based); nothing if none.  Inside
    `run_on_suspect_starts` the refusal is recorded there instead and the
    initialisation goes on with the state outside its limit."""
    rows = [int(i) for i, b in enumerate(bad) if b]
    if not rows:
        return
    found = _SUSPECT.get()
    refusal = InitialLimitError(table, rows, [message(i) for i in rows])
    if found is None:
        raise refusal
    found.append(refusal)


@contextmanager
def run_on_suspect_starts() -> Iterator[list[InitialLimitError]]:
    """Within this block, controls whose initial point lies outside their own limits are
    not refused (`refuse_initial`) but listed in the yielded list, each refusal, and
    keep that initial point: PSS/E's "initial conditions suspect", where the run goes on
    and the limiter takes the state to its limit at the first step (PSS/E Program
    Operation Manual, "Dynamic Simulation Initialization").

    Yields
    ------
    list of InitialLimitError
        Filled with the refusals met inside the block (each the error `refuse_initial`
        would have raised: its table, rows and messages).
    """
    found: list[InitialLimitError] = []
    token = _SUSPECT.set(found)
    try:
        yield found
    finally:
        _SUSPECT.reset(token)


class UnknownBusError(CaseError, KeyError):
    """A bus number that is not in the case."""

    def __str__(self):  # KeyError quotes its message; keep it readable
        return str(self.args[0]) if self.args else "unknown bus"


class UnsharedCaseError(InputError):
    """The case a job names is not the client's where the job runs (a Dask worker in
    another working directory read its own ``c.json``, or none): the job is not run and
    not recorded, and its sweep stops (`stabctl.stability.cct.job_case`)."""


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
