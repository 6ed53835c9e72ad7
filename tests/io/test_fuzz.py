"""Property-based fuzzing of every input reader and the CLI's numeric options (issue 15).

Each reader gets its own data with random truncations, line deletions, duplications and
swaps, and numbers replaced (nan, inf, 0, negative, huge, not a number, random floats).
Every example must end in a stabctl error (``stabctl.errors.StabctlError``) with a
message, or a valid case; any other exception fails the test, and so does an example that
runs longer than its time box (a hang).

Two profiles: the quick one runs in the normal test run (a few seconds per reader); the
``slow`` one, at least 1000 examples per reader, is

    python -m pytest -m slow tests/io/test_fuzz.py

Set STABCTL_FUZZ_REPORT=FILE to append each example's outcome (reader, "error" or
"valid") to FILE as JSON lines, e.g. to count them.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import signal
import tempfile
import warnings
from pathlib import Path

import pytest
from click.testing import CliRunner
from hypothesis import HealthCheck, given, note, settings
from hypothesis import strategies as st

from stabctl.case import Case
from stabctl.cli import main
from stabctl.dynamics.driver import Simulator
from stabctl.errors import StabctlError
from stabctl.io import load_case
from stabctl.io import pst as pstio
from stabctl.io.psse import load_psse

HERE = Path(__file__).parents[1]
PSSE = HERE / "data" / "psse"
_V33 = (PSSE / "five_bus_v33.raw").read_text()
#: a three-winding transformer record (v33) for the RAW seeds
_THREE_WINDING = (
    "    1,     3,     4,'T ',1,2,1, 0.0, 0.0,2,'T3          ',1,   1,1.0000\n"
    " 0.002, 0.10, 200.0, 0.004, 0.05, 50.0, 0.003, 0.08, 80.0, 0.99, -3.0\n"
    + "1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0, 0, 1.1, 0.9, 1.1, 0.9, 33, 0, 0.0, 0.0, 0.0\n" * 3
    + "0 / END OF TRANSFORMER DATA"
)
SEEDS = {
    "raw": [
        _V33,
        (PSSE / "five_bus_v34.raw").read_text(),
        (PSSE / "five_bus_v35.raw").read_text(),
        (PSSE / "five_bus_v36.raw").read_text(),
        _V33.replace("0 / END OF TRANSFORMER DATA", _THREE_WINDING, 1),
    ],
    "dyr": [(PSSE / "five_bus.dyr").read_text()],
    "case_json": [(Path(pstio.__file__).parents[1] / "case" / "data" / "kundur.json").read_text()],
    "pst_m": [(HERE / "data" / "pstess" / "d2asbegp.m").read_text()],
    "fault_csv": [
        "bus,far_bus,t_fault,circuit,required_clearing_cycles,target_cct_s\n"
        "3,101,1.0,1,6,\n13,101,1.5,1,,0.3\n1,,1.0,1,,\n"
    ],
    "site_costs": ["machine,cost_mw,cost_mwh,cost_site\n1,5,100,10\n3,,200,\n4,1.5,,\n"],
    "screening": [
        "".join(
            json.dumps(
                {
                    "key": f"k{n}",
                    "status": "ok",
                    "inputs": {"esd_pct": None, "t_max": 0.5},
                    "result": {
                        "fault": {
                            "bus": bus,
                            "far_bus": far,
                            "t_fault": 1.0,
                            "circuit": 1,
                            "trips": [],
                        },
                        "t_stable_s": 0.15 + 0.01 * n,
                        "t_unstable_s": 0.16 + 0.01 * n,
                    },
                }
            )
            + "\n"
            for n, (bus, far) in enumerate(((3, 101), (13, 101), (1, None)))
        )
    ],
}
TIME_BOX_S = 60  # no example may take longer (a hang fails the test)

_HEALTH = [HealthCheck.too_slow, HealthCheck.data_too_large]
QUICK = settings(max_examples=40, deadline=None, suppress_health_check=_HEALTH)
SLOW = settings(max_examples=1000, deadline=None, suppress_health_check=_HEALTH)

_NUMBER = re.compile(r"(?<![\w.])[-+]?(?:\d+\.?\d*|\.\d+)(?:[eEdD][-+]?\d+)?(?![\w.])")
_SPECIAL = [
    "nan",
    "NaN",
    "inf",
    "-inf",
    "Infinity",
    "-Infinity",
    "0",
    "0.0",
    "-1",
    "-0.5",
    "1e308",
    "-1e308",
    "1e-300",
    "99999",
    "",
    "x",
    "1.5",
    "2",
    "1e6",
]


# -- mutations ----------------------------------------------------------------------------


@st.composite
def numbers(draw) -> str:
    """A replacement for a number: special values, random floats and integers."""
    return draw(
        st.one_of(
            st.sampled_from(_SPECIAL),
            st.floats(allow_nan=True, allow_infinity=True).map(repr),
            st.integers(-(10**6), 10**6).map(str),
        )
    )


@st.composite
def mutated(draw, seeds: list[str]) -> str:
    """One of the seed texts after 1-4 random truncations, deletions, duplications, swaps
    and number replacements."""
    lines = draw(st.sampled_from(seeds)).splitlines(keepends=True)
    for _ in range(draw(st.integers(1, 4))):
        if not lines:
            break
        kind = draw(
            st.sampled_from(
                ["truncate", "delete", "duplicate", "swap", "number", "number", "number"]
            )
        )
        i = draw(st.integers(0, len(lines) - 1))
        if kind == "truncate":
            text = "".join(lines)
            lines = text[: draw(st.integers(0, len(text)))].splitlines(keepends=True)
        elif kind == "delete":
            del lines[i]
        elif kind == "duplicate":
            lines.insert(i, lines[i])
        elif kind == "swap":
            j = draw(st.integers(0, len(lines) - 1))
            lines[i], lines[j] = lines[j], lines[i]
        else:
            found = list(_NUMBER.finditer(lines[i]))
            if found:
                m = draw(st.sampled_from(found))
                lines[i] = lines[i][: m.start()] + draw(numbers()) + lines[i][m.end() :]
    return "".join(lines)


# -- outcome ------------------------------------------------------------------------------


class _Hang(Exception):
    """Raised by the time box (not a StabctlError: fails the property)."""


@contextlib.contextmanager
def time_box(seconds: int):
    def expired(signum, frame):
        raise _Hang(f"example ran longer than {seconds} s")

    old = signal.signal(signal.SIGALRM, expired)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


def outcome(reader: str, func) -> str:
    """Run func: "valid" if it returns, "error" for a StabctlError with a message; any
    other exception propagates (the property fails)."""
    with time_box(TIME_BOX_S), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            func()
            result = "valid"
        except StabctlError as exc:
            assert str(exc).strip(), f"{type(exc).__name__} without a message"
            result = "error"
    report = os.environ.get("STABCTL_FUZZ_REPORT")
    if report:
        with open(report, "a") as f:
            f.write(json.dumps({"reader": reader, "outcome": result}) + "\n")
    return result


def _file(tmp: str, name: str, text: str) -> Path:
    path = Path(tmp) / name
    path.write_text(text)
    return path


# -- properties ---------------------------------------------------------------------------


def raw_property(text):
    with tempfile.TemporaryDirectory() as tmp:
        raw = _file(tmp, "fuzz.raw", text)
        outcome("raw", lambda: _valid(load_psse(raw, PSSE / "five_bus.dyr")))
        outcome("raw", lambda: _valid(load_psse(raw, on_unsupported="skip", loads="raw")))


def dyr_property(text):
    with tempfile.TemporaryDirectory() as tmp:
        dyr = _file(tmp, "fuzz.dyr", text)
        outcome("dyr", lambda: _valid(load_psse(PSSE / "five_bus_v33.raw", dyr)))


def case_json_property(text):
    with tempfile.TemporaryDirectory() as tmp:
        path = _file(tmp, "fuzz.json", text)
        outcome("case_json", lambda: _valid(load_case(path)))


def pst_m_property(text):
    with tempfile.TemporaryDirectory() as tmp:
        path = _file(tmp, "fuzz.m", text)
        outcome("pst_m", lambda: _valid(load_case(path)))


def fault_csv_property(text):
    from stabctl.placement.requirements import read_requirements
    from stabctl.stability.cct import read_faults

    with tempfile.TemporaryDirectory() as tmp:
        path = _file(tmp, "fuzz.csv", text)
        outcome("fault_csv", lambda: read_faults(path))
        outcome("fault_csv", lambda: read_requirements(path))


def site_costs_property(text):
    from stabctl.placement.requirements import read_site_costs

    with tempfile.TemporaryDirectory() as tmp:
        path = _file(tmp, "costs.csv", text)
        outcome("site_costs", lambda: read_site_costs(path, 4))


def screening_property(text):
    from stabctl.placement.requirements import screening_brackets

    with tempfile.TemporaryDirectory() as tmp:
        path = _file(tmp, "screening.jsonl", text)
        outcome("screening", lambda: screening_brackets(path, "kundur", "any"))


def _valid(case):
    assert isinstance(case, Case)
    return case


for _name, _prop in (
    ("raw", raw_property),
    ("dyr", dyr_property),
    ("case_json", case_json_property),
    ("pst_m", pst_m_property),
    ("fault_csv", fault_csv_property),
    ("site_costs", site_costs_property),
    ("screening", screening_property),
):
    _strategy = mutated(SEEDS[_name])
    globals()[f"test_fuzz_{_name}_reader"] = QUICK(given(_strategy)(_prop))
    globals()[f"test_fuzz_{_name}_reader_slow"] = pytest.mark.slow(SLOW(given(_strategy)(_prop)))


# -- a mutated case runs or is refused ----------------------------------------------------

_KUNDUR = pstio.case_to_dict(load_case("kundur"))
_FIELDS = [
    (t, c)
    for t in ("machines", "exciters", "pss", "governors", "buses", "branches")
    for c in _KUNDUR["tables"][t]["columns"]
]


@st.composite
def mutated_kundur(draw) -> dict:
    """Kundur with 1-3 fields of its tables set to special or random values."""
    d = json.loads(json.dumps(_KUNDUR))
    for _ in range(draw(st.integers(1, 3))):
        table, col = draw(st.sampled_from(_FIELDS))
        t = d["tables"][table]
        row = draw(st.integers(0, len(t["rows"]) - 1))
        value = draw(
            st.one_of(
                st.sampled_from([0.0, -1.0, 1e-9, 1e9, 0.5, 2.0]),
                st.floats(-1e3, 1e3, allow_nan=False),
            )
        )
        t["rows"][row][t["columns"].index(col)] = value
        note(f"{table} row {row + 1} {col} = {value!r}")
    return d


def case_run_property(d):
    def run():
        case = pstio.case_from_dict(d)
        Simulator(case).run([], t_end=0.1)

    outcome("case_run", run)


test_fuzz_case_fields_run_or_refused = settings(QUICK, max_examples=15)(
    given(mutated_kundur())(case_run_property)
)
test_fuzz_case_fields_run_or_refused_slow = pytest.mark.slow(
    settings(SLOW, max_examples=300)(given(mutated_kundur())(case_run_property))
)


# -- CLI numeric options ------------------------------------------------------------------


def _cli_value():
    return st.one_of(
        st.sampled_from(["nan", "inf", "-inf", "0", "-1", "1e6", "1e-7", "0.5", "1", "5", "100"]),
        st.floats(-1e4, 1e4, allow_nan=False).map(repr),
    )


_OMIB = ["--H", "--pm", "--delta0", "--pmax", "--f0", "--fault-cycles"]
_SIMULATE = [
    "--t-fault",
    "--clear-cycles",
    "--far-clear-cycles",
    "--tf",
    "--step",
    "--separation-limit",
    "--esd-pct",
    "--deadband-hz",
    "--v-gate",
    "--hysteresis-hz",
]


def cli_property(command, options):
    args = [*command]
    for opt, value in options.items():
        args += [opt, value]

    def invoke():
        res = CliRunner().invoke(main, args)
        if res.exit_code == 2:
            lines = res.stderr.strip().splitlines()
            assert len(lines) == 1 and lines[0].startswith("error: "), (args, res.stderr)
            raise StabctlError(lines[0])
        assert res.exit_code == 0 and res.exception is None, (
            args,
            res.exit_code,
            res.exception,
            res.output,
        )

    outcome(f"cli {command[0]}", invoke)


def _options(names, most):
    return st.dictionaries(st.sampled_from(names), _cli_value(), min_size=1, max_size=most)


@QUICK
@given(_options(_OMIB, 4))
def test_fuzz_cli_omib(options):
    cli_property(["omib"], options)


@pytest.mark.slow
@SLOW
@given(_options(_OMIB, 4))
def test_fuzz_cli_omib_slow(options):
    cli_property(["omib"], options)


_FAULT = ["simulate", "kundur", "--fault", "3", "--far-bus", "101"]


@settings(QUICK, max_examples=12)
@given(_options(_SIMULATE, 3))
def test_fuzz_cli_simulate(options):
    cli_property(_FAULT, {"--tf": "2", **options})


@pytest.mark.slow
@settings(SLOW, max_examples=1000)
@given(_options(_SIMULATE, 3))
def test_fuzz_cli_simulate_slow(options):
    cli_property(_FAULT, {"--tf": "2", **options})
