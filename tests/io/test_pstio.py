"""PST/PSTess importers and stabctl's own JSON case format.

tests/data/pstess/d2asbegp.m and d2asbegp.json are PSTess 1.1 files (MIT, see LICENSE and
NOTICE there); the .json is GNU Octave's evaluation of the .m.
"""

import json
import re
from pathlib import Path

import numpy as np
import pytest

from stabctl.errors import CaseError
from stabctl.io import load_case
from stabctl.io import pst as pstio

DATA = Path(__file__).parents[1] / "data" / "pstess"


# ---------------------------------------------------------------------------- .m files


def test_m_file_parses_to_octaves_matrices():
    mats = pstio.parse_m((DATA / "d2asbegp.m").read_text())
    octave = json.loads((DATA / "d2asbegp.json").read_text())
    for key, value in octave.items():
        np.testing.assert_array_equal(mats[key], np.array(value, float), err_msg=key)
    assert mats["ind_con"].size == 0 and mats["mld_con"].size == 0  # `= [];`
    assert mats["mac_con"].shape == (4, 21)  # rows continued with `...`
    assert mats["sw_con"].shape == (5, 7)  # commented-out rows skipped


def test_m_and_json_give_the_same_case_and_keep_sw_con():
    a = pstio.read_pst_m(DATA / "d2asbegp.m")
    b = pstio.read_pstess_json(DATA / "d2asbegp.json")
    assert a.name == b.name == "d2asbegp"
    assert a.equals(b)
    np.testing.assert_array_equal(a.sw_con[3], [0.2, 0, 0, 0, 0, 0, 0.01])
    assert set(a.extra) == {"lmod_con", "rlmod_con"}  # empty ind_con/mld_con dropped


def test_builtin_kundur_equals_fresh_import():
    fresh = pstio.read_pstess_json(DATA / "d2asbegp.json").replace(name="kundur")
    assert load_case("kundur").equals(fresh)


def test_m_syntax_accepted():
    text = """
% comment
disp('50% constant current load')
basmva = 100;   % scalar literal
a = [1, 2 3;  % commas or blanks
     4 -5 .6e1
     7 ...
     8 9];
b = [];
%{
x = anything(1);
%}
c = [1.5e-3 -2 +3];
"""
    m = pstio.parse_m(text)
    np.testing.assert_array_equal(m["a"], [[1, 2, 3], [4, -5, 6], [7, 8, 9]])
    assert m["b"].size == 0 and m["basmva"].item() == 100
    np.testing.assert_array_equal(m["c"], [[1.5e-3, -2, 3]])


@pytest.mark.parametrize(
    "text, pattern",
    [
        ("x = [1 2];\nbus = [1 22.0-2 3];\n", r"line 2: 'bus': '22.0-2' is not a number"),
        ("bus = [1 2 3;\n  4 PDC(1) 6];\n", r"line 2: 'bus': 'PDC\(1\)' is not a number"),
        ("x = [1 2];\n\ny = x;\n", r"line 3: 'y' is not a literal matrix or number: x"),
        ("a = 1;\nif a == 1\n b = 2;\nend\n", r"line 2: not a literal assignment: if a == 1"),
        ("for k = 1:3\n  z(k) = k;\nend\n", r"line 1: not a literal assignment: for k"),
        ("p = (1:1:34).';\n", r"line 1: 'p' is not a literal matrix or number"),
        ("q = [1 2]';\n", r"line 1: 'q' is not a literal matrix or number"),
        ("m = [1 2 3;\n 4 5];\n", r"line 2: 'm': row 2 has 2 columns, 1 other row\(s\) have 3"),
        # a broken first row is named, not the next one
        ("m = [1 2 3 4;\n 4 5 6;\n 7 8 9];\n", r"line 1: 'm': row 1 has 4 columns, 2 other"),
        ("m = [1 2 3;\n 4 5 6;\n", r"line 1: unterminated matrix"),
        ("r = [1 2] * 3;\n", r"line 1: 'r' is not a literal matrix or number"),
        ("s = [1 - 2];\n", r"line 1: 's': '-' is not a number"),
        # float() reads a fullwidth digit as its ASCII one (and Python's \d matches it)
        (
            "mac_con = [1 2;\n 3 \uff16.5];\n",
            r"line 2: 'mac_con': '\uff16.5' is not a number \(a number is written in ASCII",
        ),
        ("basmva = \uff11\uff10\uff10;\n", r"line 1: 'basmva' is not a literal matrix or number"),
    ],
)
def test_m_non_literal_statements_are_refused_with_line(text, pattern):
    with pytest.raises(CaseError, match=pattern):
        pstio.parse_m(text, "f.m")


def test_m_error_names_file(tmp_path):
    p = tmp_path / "bad.m"
    p.write_text("bus = [1 1 0 0 0 0 0 0 0 1];\nline = [1 2 0 x 0];\n")
    with pytest.raises(CaseError, match=r"bad\.m line 2: 'line': 'x' is not a number"):
        pstio.read_pst_m(p)


def test_m_without_line_matrix_is_refused(tmp_path):
    p = tmp_path / "noline.m"
    p.write_text("bus = [1 1 0 0 0 0 0 0 0 1];\n")
    with pytest.raises(CaseError, match="no 'line' matrix"):
        pstio.read_pst_m(p)


# ---------------------------------------------------------------------------- own format


@pytest.mark.parametrize("name", ["kundur", "miniwecc"])
def test_own_format_round_trip(tmp_path, name):
    case = load_case(name)
    path = pstio.write_case_json(case, tmp_path / f"{name}.json", licence="MIT, test")
    back = pstio.read_case_json(path)
    assert back.equals(case)
    assert (back.source, back.description) == (case.source, case.description)
    raw = json.loads(path.read_text())
    assert (raw["format"], raw["version"], raw["licence"]) == ("stabctl-case", 1, "MIT, test")
    assert raw["tables"]["machines"]["columns"][:8] == [
        "number",
        "bus",
        "mva",
        "xl",
        "ra",
        "xd",
        "xdp",
        "xdpp",
    ]
    assert load_case(path).equals(case)  # load_case by path, dispatch on content


def test_own_format_is_one_row_per_line(tmp_path):
    path = pstio.write_case_json(load_case("kundur"), tmp_path / "k.json")
    lines = path.read_text().splitlines()
    assert "        [1, 1.01, 18.5, 7.2615, 1.274, 0, 0, 0, 0, 1, 5, -2, 22, 1.1, 0.9]," in lines


def test_own_format_rejects_wrong_version_and_unknown_column(tmp_path):
    data = pstio.case_to_dict(load_case("kundur"))
    data["version"] = 99
    with pytest.raises(CaseError, match="version 99 not supported"):
        pstio.case_from_dict(data)
    data = pstio.case_to_dict(load_case("kundur"))
    data["tables"]["buses"]["columns"][1] = "voltage"
    with pytest.raises(CaseError, match=r"table 'buses' has unknown column\(s\) \['voltage'\]"):
        pstio.case_from_dict(data)


def test_a_column_named_twice_is_named(tmp_path):
    """A table naming a column twice in its 'columns' is refused naming that column and its
    positions (the error had said "names a column twice" without saying which), by the
    case file and a command alike."""
    from click.testing import CliRunner

    from stabctl.cli import main

    data = pstio.case_to_dict(load_case("kundur"))
    cols = data["tables"]["buses"]["columns"]
    k = cols.index("vmag")
    cols[k + 1] = "vmag"
    message = (
        f"table 'buses' names a column twice in its 'columns': 'vmag' at positions {k + 1}, {k + 2}"
    )
    with pytest.raises(CaseError, match=re.escape(message)):
        pstio.case_from_dict(data)
    path = tmp_path / "twice.json"
    path.write_text(json.dumps(data))
    res = CliRunner().invoke(main, ["cases", str(path)])
    assert res.exit_code == 2, res.output
    assert f"error: {path}: {message}" in res.output, res.output


def test_own_format_columns_by_name_in_any_order():
    data = pstio.case_to_dict(load_case("kundur"))
    t = data["tables"]["pss"]
    t["columns"] = t["columns"][::-1]
    t["rows"] = [r[::-1] for r in t["rows"]]
    assert pstio.case_from_dict(data).pss.equals(load_case("kundur").pss)


def test_validation_errors_surface_through_the_readers(tmp_path):
    data = pstio.case_to_dict(load_case("kundur"))
    data["tables"]["machines"]["rows"][2][15] = -1.0
    p = tmp_path / "negH.json"
    p.write_text(json.dumps(data))
    with pytest.raises(CaseError, match=r"table 'machines' row 3 \(machine 3\), field 'H'"):
        load_case(p)


@pytest.mark.parametrize(
    "record, needles",
    [
        (
            {"kind": "LineTrip", "from_bus": 3, "to_bus": 13, "t": 1.0},
            ["line 3-13 (circuit 1) tripped at 1 s: ", "no branch between bus 3 and bus 13"],
        ),
        (
            {"kind": "LineClose", "from_bus": 3, "to_bus": 101, "t": 1.5, "circuit": 3},
            ["line 3-101 (circuit 3) closed at 1.5 s: ", "circuit 3 between bus 3 and bus 101"],
        ),
        (
            {"kind": "Fault", "bus": 77, "t": 1.0, "clear_near": 1.1},
            ["3-phase fault at bus 77 at 1 s, cleared at 1.1 s", "bus 77 is not in case"],
        ),
        (
            {"kind": "Fault", "bus": 3, "t": 1.0, "clear_near": 1.1, "far_bus": 13},
            ["on line 3-13 (circuit 1)", "no branch between bus 3 and bus 13"],
        ),
        (
            {"kind": "LoadStep", "bus": 77, "t": 1.0, "P": 0.1},
            ["load step 0.1+0j pu at bus 77 at 1 s: ", "bus 77 is not in case"],
        ),
        (
            {"kind": "GeneratorTrip", "machine": 9, "t": 1.0},
            ["machine 9 tripped at 1 s: ", "machine 9 is not in case"],
        ),
    ],
)
def test_a_stored_event_of_a_bus_or_line_the_case_lacks_is_refused_at_load(
    tmp_path, record, needles
):
    """Kundur's buses are 1-4, 10-14, 20, 101, 110 and 120, bus 3 has no branch to bus 13
    and two circuits to bus 101, and its machines are 1-4: a case file whose own event
    names another bus, line or machine is refused when it is read, naming the file, the
    record, the event in words and what is missing, not when a run starts."""
    data = pstio.case_to_dict(load_case("kundur"))
    data["events"] = [{"kind": "LoadStep", "bus": 4, "t": 1.0, "P": 0.1, "source": "ok"}]
    data["events"].append({**record, "source": "Toggle 2"})
    p = tmp_path / "own.json"
    p.write_text(json.dumps(data))
    with pytest.raises(CaseError) as err:
        load_case(p)
    assert str(err.value).startswith(f"{p}: events[1] (Toggle 2): ")
    for needle in needles:
        assert needle in str(err.value)
    del data["events"][1]  # the same file with its first event alone loads
    p.write_text(json.dumps(data))
    assert load_case(p).events == (
        {"kind": "LoadStep", "bus": 4, "t": 1.0, "P": 0.1, "source": "ok"},
    )


def test_read_any_rejects_unknown_content(tmp_path):
    p = tmp_path / "x.json"
    p.write_text('{"hello": 1}')
    with pytest.raises(CaseError, match="neither a stabctl case nor a PSTess"):
        pstio.read_any(p)
    p.write_text("{not json")
    with pytest.raises(CaseError, match="invalid JSON at line 1"):
        pstio.read_any(p)


@pytest.mark.parametrize(
    "edit, needle",
    [
        # json keeps the last of a key given twice: the case ran at 50 MVA without a word
        (lambda text, _: text[:-1] + ', "base_mva": 50.0}', '"base_mva" given twice'),
        # a second "tables" replaced every table of the first
        (
            lambda text, data: text[:-1] + ', "tables": ' + json.dumps(data["tables"]) + "}",
            '"tables" given twice',
        ),
        # inside a table: the second "rows" replaced the first
        (
            lambda text, _: text.replace('"rows": [', '"rows": [], "rows": [', 1),
            '"rows" given twice',
        ),
    ],
    ids=["base_mva", "tables", "rows"],
)
def test_a_case_file_giving_a_key_twice_is_refused_naming_file_and_key(tmp_path, edit, needle):
    data = pstio.case_to_dict(load_case("kundur"))
    p = tmp_path / "twice.json"
    p.write_text(edit(json.dumps(data), data))
    with pytest.raises(CaseError, match=rf"^{p}: key {needle} in one object"):
        load_case(p)
    with pytest.raises(CaseError, match=rf"^{p}: key {needle}"):
        pstio.read_case_header(p)


def test_a_pstess_matrix_json_giving_a_key_twice_is_refused(tmp_path):
    case = load_case("kundur")
    p = tmp_path / "m.json"
    bus = json.dumps(case.buses.matrix().tolist())
    line = json.dumps(case.branches.matrix().tolist())
    p.write_text(f'{{"bus": {bus}, "line": {line}, "basmva": 100, "sys_freq": 60, "basmva": 10}}')
    twice = r'"basmva" given twice in one object \(100, then 10\)'
    with pytest.raises(CaseError, match=rf"^{p}: key {twice}"):
        pstio.read_any(p)


@pytest.mark.parametrize("edit", ["append", "pop"])
def test_a_table_row_of_another_width_is_named_with_file_table_and_counts(tmp_path, edit):
    """A first branch row with a value too many or too few was reported as "line row 2:
    wrong column count 14, row 1 has 15", without the file and blaming the good row 2."""
    data = pstio.case_to_dict(load_case("kundur"))
    row = data["tables"]["branches"]["rows"][0]
    row.append(1.0) if edit == "append" else row.pop()
    found = 15 if edit == "append" else 13
    p = tmp_path / "ragged.json"
    p.write_text(json.dumps(data))
    want = rf"^{p}: table 'branches' row 1: {found} value\(s\), the table names 14 columns "
    want += r"\(wrong column count\)$"
    with pytest.raises(CaseError, match=want):
        load_case(p)
    # a PSTess matrix file: its rows against the most rows' width, the file named
    mats = {"bus": data["tables"]["buses"]["rows"], "line": data["tables"]["branches"]["rows"]}
    p = tmp_path / "matrices.json"
    p.write_text(json.dumps({**mats, "basmva": 100.0, "sys_freq": 60.0}))
    with pytest.raises(CaseError, match=rf"^{p}: line row 1: {found} columns, 13 other row"):
        load_case(p)


def _with_motor(d, **values):
    """The case dict ``d`` with one motor at bus 1 (its declared defaults, ``values``)."""
    from stabctl.models.motors import MOTOR

    row = {p.name: p.default for p in MOTOR.params} | dict(number=1, bus=1) | values
    d["tables"]["motors"] = {"columns": list(row), "rows": [list(row.values())]}
    return d


def _set_value(d, table, column, value):
    t = d["tables"][table]
    t["rows"][0][t["columns"].index(column)] = value
    return d


@pytest.mark.parametrize(
    "edit, needle",
    [
        (lambda d: _set_value(d, "machines", "H", -1), "table 'machines' row 1 (machine 1), "),
        (lambda d: _set_value(d, "exciters", "TA", -0.05), "table 'exciters' row 1 (machine 1)"),
        (lambda d: _set_value(d, "governors", "invR", -20), "table 'governors' row 1 (machine"),
        (lambda d: _set_value(d, "pss", "T2", 0), "table 'pss' row 1 (machine 1), field 'T2'"),
        (lambda d: _with_motor(d, xm=-5), "table 'motors' row 1 (motor 1), field 'xm'"),
        (
            lambda d: d["tables"]["machines"]["rows"][0].pop(),
            "table 'machines' row 1: 28 value(s), the table names 29 columns",
        ),
        (
            lambda d: _set_value(d, "machines", "bus", 99),
            "table 'machines' row 1 (machine 1), field 'bus': bus 99 does not exist in table "
            "'buses'",
        ),
        (
            lambda d: _set_value(d, "exciters", "machine", 9),
            "table 'exciters' row 1 (machine 9), field 'machine': machine 9 does not exist "
            "in table 'machines'",
        ),
    ],
)
def test_a_case_file_s_errors_name_its_tables_as_it_names_them(tmp_path, edit, needle):
    """A stabctl case file names its tables machines, exciters, ...: its errors named
    PST's mac_con, exc_con, ... instead.  A PSTess matrix file keeps PST's."""
    d = pstio.case_to_dict(load_case("kundur"))
    edit(d)
    p = tmp_path / "c.json"
    p.write_text(json.dumps(d))
    with pytest.raises(CaseError) as err:
        load_case(p)
    assert str(err.value).startswith(f"{p}: {needle}"), str(err.value)
    assert "_con" not in str(err.value)


def test_a_pstess_matrix_file_s_errors_keep_pst_table_names(tmp_path):
    mats = json.loads((DATA / "d2asbegp.json").read_text())
    mats["mac_con"][0][15] = -1.0  # H
    p = tmp_path / "m.json"
    p.write_text(json.dumps(mats))
    with pytest.raises(CaseError, match=r"m.json: mac_con row 1 \(machine 1\), field 'H'"):
        load_case(p)


@pytest.mark.parametrize("field", ["Hm", "rs", "rr1", "rr2", "xm", "mva"])
def test_a_motor_the_model_cannot_run_is_refused_as_the_file_is_read(tmp_path, field):
    """A motor's Hm = 0 was refused only when the model was built, its error without the
    file: refused as the case is read, the file first."""
    d = _with_motor(pstio.case_to_dict(load_case("kundur")), **{field: 0})
    p = tmp_path / "m.json"
    p.write_text(json.dumps(d))
    with pytest.raises(CaseError) as err:
        load_case(p)
    assert str(err.value) == (
        f"{p}: table 'motors' row 1 (motor 1), field '{field}': must be > 0, got 0"
    )


def test_another_tool_s_case_is_pointed_to_its_importer(tmp_path):
    """An ANDES JSON case given where a case is read was "neither a stabctl case nor a
    PSTess matrix JSON": named as ANDES's, with the command converting it;
    an xlsx or RAW file the same."""
    p = tmp_path / "a.json"
    p.write_text(json.dumps({"Bus": [{"idx": 1, "u": 1.0, "Vn": 69.0}], "Line": []}))
    with pytest.raises(CaseError) as err:
        load_case(p)
    assert str(err.value) == (
        f"{p}: an ANDES JSON case (its model tables Bus, Line, ...), not a stabctl case: "
        f"convert it first with `stabctl import-andes {p} -o case.json`"
    )
    for suffix, command in ((".xlsx", "import-andes"), (".raw", "import-psse")):
        q = tmp_path / f"c{suffix}"
        q.write_text("x")
        with pytest.raises(CaseError) as err:
            load_case(q)
        assert str(err.value).startswith(f"{q}: unknown case file type (expected .json or .m); ")
        assert f"`stabctl {command} {q} " in str(err.value)
