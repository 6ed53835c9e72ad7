"""An ANDES case file's values checked as written, before ANDES fills its defaults, for
every model: a value ANDES would replace by its default (a GENROU M of 0 or -13 run at
H = 3 s), a formula whose value the file does not hold (read as empty: EXDC2 TA run at
0.04 s), a status ``u`` other than 0 or 1, a line of zero impedance, a negative event
time, a sheet that is no ANDES model, a column that is no parameter of its model, a
machine away from its static generator's bus.  Refused naming file, sheet, row, idx,
parameter and value; ANDES's own log is never shown."""

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

from stabctl.errors import CaseError, InputError
from stabctl.io.andes_case import read_andes_case

andes = pytest.importorskip("andes")
openpyxl = pytest.importorskip("openpyxl")

KUNDUR = "kundur/kundur_full.xlsx"


def cells_edited(tmp_path, edits, case=KUNDUR):
    """ANDES's case file with each (sheet, row, column, value) written (row 2: the first
    device; a column or sheet not there is added), saved by openpyxl, which computes no
    formula: a formula cell holds no value."""
    book = openpyxl.load_workbook(andes.get_case(case))
    for sheet, row, column, value in edits:
        ws = book[sheet] if sheet in book.sheetnames else book.create_sheet(sheet)
        header = [c.value for c in ws[1]]
        if column not in header:
            ws.cell(1, len(header) + 1, column)
            header.append(column)
        ws.cell(row, header.index(column) + 1).value = value  # None: emptied
    path = tmp_path / "edited.xlsx"
    book.save(path)
    return path


@pytest.mark.parametrize(
    "edits, needle",
    [
        # values ANDES replaces by its default (its NumParam flags), any model
        (
            [("GENROU", 2, "M", 0)],
            "GENROU row 1 (idx 1; spreadsheet row 2): M = 0 (must not be 0: ANDES would ",
        ),
        (
            [("GENROU", 2, "M", -13)],
            "GENROU row 1 (idx 1; spreadsheet row 2): M = -13 (must not be negative",
        ),
        (
            [("EXDC2", 2, "TF1", 0)],
            "EXDC2 row 1 (idx 1; spreadsheet row 2): TF1 = 0 (must not be 0",
        ),
        ([("Bus", 2, "Vn", 0)], "Bus row 1 (idx 1; spreadsheet row 2): Vn = 0 (must not be 0"),
        # a formula without a stored value, which pandas and ANDES read as empty
        (
            [("EXDC2", 2, "TA", "=1/0")],
            "EXDC2 row 1 (idx 1; spreadsheet row 2)"
            ": TA is a formula (=1/0) whose value the file does not hold",
        ),
        # round 30: a spreadsheet error value, read as empty and run at ANDES's default
        # (REECA1 Imax #VALUE! at 999 pu, said as "empty in the file")
        (
            [("EXDC2", 2, "TA", "#DIV/0!")],
            "EXDC2 row 1 (idx 1; spreadsheet row 2): TA is the spreadsheet error #DIV/0!",
        ),
        (
            [("GENROU", 2, "u", "#N/A")],
            "GENROU row 1 (idx 1; spreadsheet row 2): u is the spreadsheet error #N/A",
        ),
        # round 30: an idx given twice (the Toggle of line Line_8 reached row 3's line)
        (
            [("Line", 4, "idx", "Line_8")],
            "Line row 3 (spreadsheet row 4) and row 9 (spreadsheet row 10) both give idx "
            "'Line_8': ANDES would rename the second",
        ),
        (
            [("GENROU", 2, "u", 0.5)],
            "GENROU row 1 (idx 1; spreadsheet row 2): u = 0.5: the connection status",
        ),
        (
            [("Line", 2, "r", 0), ("Line", 2, "x", 0)],
            "Line row 1 (idx Line_0; spreadsheet row 2)"
            ": r = x = 0 between buses 5 and 6: a zero impedance",
        ),
        ([("Toggler", 2, "t", -1)], "Toggle 1: t = -1 s: an event time must be finite and >= 0"),
        # round 48: a PV's idx equal to the Slack's was refused only through its
        # consequence (two machines taking one static generator's power twice)
        (
            [("PV", 2, "idx", 1), ("GENROU", 3, "gen", 1)],
            "PV row 1 (spreadsheet row 2) and Slack row 1 (spreadsheet row 2) both give idx "
            "1: ANDES's StaticGen group holds both",
        ),
        # round 48: the Slack's bus out of service gave "bus: no swing bus (no row with
        # field 'kind' = 1)", naming neither the Slack nor its bus
        (
            [("Bus", 2, "u", 0)],
            "no Slack in service, so no swing bus: Slack 1 out of service with the device it "
            "serves or its bus",
        ),
        # a link to a device the case does not hold, any model (ANDES's message named
        # neither sheet nor row); a machine's share of its static generator out of [0, 1]
        (
            [("Line", 2, "bus2", 999)],
            "Line row 1 (idx Line_0; spreadsheet row 2): bus2 = 999: no ACNode (Bus) of that "
            "idx in the case (ANDES cannot link the device to it)",
        ),
        (
            [("TGOV1", 2, "syn", 9)],
            "TGOV1 row 1 (idx 1; spreadsheet row 2): syn = 9: no SynGen (GENROU) of that idx",
        ),
        (
            [("GENROU", 2, "gammap", 1.2)],
            "GENROU row 1 (idx 1; spreadsheet row 2): gammap = 1.2: it must be 0 <= gammap <= 1",
        ),
        (
            [("GENROU", 2, "bus", 7)],
            "GENROU 1 is at bus 7, its static generator Slack 1 at bus 1 (bus 7 has no PV "
            "or Slack)",
        ),
    ],
)
def test_values_andes_would_change_or_cannot_run_are_refused(tmp_path, edits, needle):
    path = cells_edited(tmp_path, edits)
    with pytest.raises(CaseError) as err:
        read_andes_case(path, on_unsupported="skip")
    assert str(err.value).startswith(f"{path.name}: ") and needle in str(err.value)


def test_own_events_of_unknown_devices_or_cleared_before_they_start_are_refused(tmp_path):
    """Round 48: an Alter of a device the case does not hold ended in a traceback
    ("'NOPE_9' is not in list"); a Fault with tc 0.9 s before its tf 1 s was imported and
    refused only by the run; a Fault's rf and xf left empty ran at ANDES's defaults
    without being listed among them."""
    path = cells_edited(tmp_path, [("Alter", 2, "dev", "NOPE_9")], "ieee14/ieee14_alter.xlsx")
    with pytest.raises(InputError, match=r"Alter 1: alters \w+ NOPE_9 \w+: the case has no"):
        read_andes_case(path)
    path = cells_edited(tmp_path, [("Fault", 2, "tc", 0.9)], "ieee14/ieee14_fault.xlsx")
    with pytest.raises(CaseError, match=r"Fault 1: tc = 0.9 s before tf = 1 s: a fault is"):
        read_andes_case(path)
    got = read_andes_case(andes.get_case("ieee14/ieee14_fault.xlsx"))
    assert "Fault xf = 0.0001 (row 1: empty in the file)" in got.defaulted
    assert "Fault rf = 0 (row 1: empty in the file)" in got.defaulted


@pytest.mark.parametrize(
    "edits, needle, bypassed",
    [
        # GENROU: negative damping, T'do of 0; T''qo of 0 is kept (no q-axis subtransient
        # winding, PST's convention), a negative one refused
        (
            [("GENROU", 2, "D", -1)],
            "GENROU row 1 (idx 1; spreadsheet row 2): D = -1: it must be >= 0",
            None,
        ),
        (
            [("GENROU", 2, "Td10", 0)],
            "GENROU row 1 (idx 1; spreadsheet row 2): Td10 = 0: it must be > 0",
            None,
        ),
        (
            [("GENROU", 2, "Tq20", -0.05)],
            "GENROU row 1 (idx 1; spreadsheet row 2): Tq20 = -0.05: it must be >= 0",
            [("GENROU", 2, "Tq20", 0)],
        ),
        # TGOV1: the lead T2 of 0 bypassed, a negative one refused; the valve lag T1 and
        # the lag T3 are no bypass (PSS/E Model Library: T1 > 0, T3 > 0); the droop R
        (
            [("TGOV1", 2, "T2", -2.1)],
            "TGOV1 row 1 (idx 1; spreadsheet row 2): T2 = -2.1: it must be >= 0",
            [("TGOV1", 2, "T2", 0)],
        ),
        (
            [("TGOV1", 2, "T1", 0)],
            "TGOV1 row 1 (idx 1; spreadsheet row 2): T1 = 0: it must be > 0",
            None,
        ),
        (
            [("TGOV1", 2, "T3", -7)],
            "TGOV1 row 1 (idx 1; spreadsheet row 2): T3 = -7: it must be > 0",
            None,
        ),
        (
            [("TGOV1", 2, "R", 0)],
            "TGOV1 row 1 (idx 1; spreadsheet row 2): R = 0: it must be > 0 (the droop)",
            None,
        ),
        # EXDC2: TA of 0 bypassed (PSS/E: no regulator lag); the exciter TE and the rate
        # feedback TF1 are no bypass
        (
            [("EXDC2", 2, "TA", -0.02)],
            "EXDC2 row 1 (idx 1; spreadsheet row 2): TA = -0.02: it must be >= 0",
            [("EXDC2", 2, "TA", 0)],
        ),
        (
            [("EXDC2", 2, "TE", 0)],
            "EXDC2 row 1 (idx 1; spreadsheet row 2): TE = 0: it must be > 0",
            None,
        ),
        (
            [("EXDC2", 2, "TF1", -1.246)],
            "EXDC2 row 1 (idx 1; spreadsheet row 2): TF1 = -1.246: it must be > 0",
            None,
        ),
    ],
)
def test_machine_exciter_and_governor_values_that_cannot_be_are_refused(
    tmp_path, edits, needle, bypassed
):
    """Kundur's GENROU, TGOV1 and EXDC2 rows with a negative damping or time constant, or
    a zero time constant or droop their model cannot take, imported without a word or were
    refused by a table row of the converted case (``mac_con row 4 (machine 4), field
    'D0'``) instead of the file's: refused before ANDES runs them, naming file, sheet,
    row, idx, parameter and value; a zero time constant the model bypasses imports."""
    path = cells_edited(tmp_path, edits)
    with pytest.raises(CaseError) as err:
        read_andes_case(path, on_unsupported="skip")
    assert str(err.value).startswith(f"{path.name}: {needle}"), str(err.value)
    if bypassed is not None:
        read_andes_case(cells_edited(tmp_path, bypassed), on_unsupported="skip")


def test_a_rate_feedback_without_its_time_constant_is_refused(tmp_path):
    """ESST1A's rate feedback KF / (1 + s TF) needs TF > 0 where KF != 0 (ANDES declares
    no limit on TF): refused naming both; with KF = 0 the feedback is off and TF = 0
    imports."""
    case = "ieee14/ieee14_esst1a.xlsx"
    path = cells_edited(tmp_path, [("ESST1A", 2, "KF", 0.1), ("ESST1A", 2, "TF", 0)], case)
    with pytest.raises(CaseError) as err:
        read_andes_case(path, on_unsupported="skip")
    assert str(err.value).startswith(
        "edited.xlsx: ESST1A row 1 (idx ESST1A_1; spreadsheet row 2)"
        ": TF = 0 with KF = 0.1: it must be > 0"
    ), str(err.value)
    path = cells_edited(tmp_path, [("ESST1A", 2, "KF", 0), ("ESST1A", 2, "TF", 0)], case)
    read_andes_case(path, on_unsupported="skip")


def test_every_machine_exciter_and_governor_read_from_andes_has_its_limits():
    """Each synchronous machine, exciter and governor model stabctl reads from ANDES has
    its value limits, each naming a parameter of ANDES's model; those it refuses at 0
    include every time constant its stabctl type needs (the type module's ``NEEDS``,
    through the record's copies and ANDES's psse-dyr.yaml)."""
    from stabctl.io import andes_case as ac
    from stabctl.io.dyr import DYR_MODELS
    from stabctl.models import exciters, governors

    ss = andes.system.System()
    groups = ("SynGen", "Exciter", "TurbineGov")
    read = {a for a in ac.MAPPED_MODELS if ss.models[a].group in groups}
    assert read == set(ac._DYNAMIC_LIMITS)
    yaml = ac._psse_yaml()
    for model, (positive, non_negative, rate) in ac._DYNAMIC_LIMITS.items():
        params = ss.models[model].params
        assert set(positive) | set(non_negative) | set(rate) <= set(params), model
        if ss.models[model].group == "SynGen":
            continue
        decl = DYR_MODELS[ac.MAPPED_MODELS[model]]
        family = exciters if ss.models[model].group == "Exciter" else governors
        needs = family.TYPES[decl.kind].NEEDS
        table = family.EXCITER if family is exciters else family.GOVERNOR
        fields = [n[1] if isinstance(n, tuple) else n for n in needs]
        spec = yaml.get(decl.name)  # None: ANDES's own model, its parameters by name
        inputs = spec["inputs"][2:] if spec else list(decl.fields)
        # by name where the names agree, else by position (as the import reads them)
        same = sorted(inputs) == sorted(decl.fields)
        named = dict(zip(decl.fields, decl.fields if same else inputs))
        andes_of = {
            str(v).split(";")[0]: k for k, v in (spec or {"outputs": {}})["outputs"].items()
        }
        for f in fields:
            copied = [d for t, d in decl.copy.items() if table.param(t) is table.param(f)]
            assert copied, (model, f)
            name = named.get(copied[0], copied[0])
            assert andes_of.get(name, name) in positive, (model, f, copied)


def test_a_required_control_parameter_left_empty_is_a_change_refused_unless_skipped(tmp_path):
    """EXDC2's TF1, which ANDES declares non-zero, left empty runs at ANDES's default 1 s:
    refused, or kept and named with --skip-unsupported; its TA (no such declaration) left
    empty is named with the default ANDES runs."""
    path = cells_edited(tmp_path, [("EXDC2", 2, "TF1", None), ("EXDC2", 2, "TA", None)])
    change = "EXDC2 (1: 1): TF1 left empty, run at ANDES's default 1 (it must not be 0)"
    with pytest.raises(InputError, match=r"to keep with a change: .*" + re.escape(change)):
        read_andes_case(path)
    with pytest.warns(UserWarning, match=re.escape(change)):
        got = read_andes_case(path, on_unsupported="skip")
    assert change in got.changed and "EXDC2 TA = 0.04 (row 1: empty in the file)" in got.defaulted


def test_a_sheet_that_is_no_model_or_a_column_that_is_no_parameter_is_named(tmp_path):
    """ANDES skips a sheet that is no model of its and a column that is no parameter of its
    model, with a log line stabctl did not show: a sheet is refused; a column is refused,
    or left out by name with --skip-unsupported (ANDES's own cases carry columns of its
    earlier versions: kundur_reg's REGCA1 Iqmax and Iqmin)."""
    with pytest.raises(InputError, match=r"edited.xlsx: sheet 'FOOBAR' is no ANDES model"):
        read_andes_case(cells_edited(tmp_path, [("FOOBAR", 2, "idx", 1)]), on_unsupported="skip")
    path = cells_edited(tmp_path, [("GENROU", 2, "Hfoo", 3.0)])
    column = "GENROU column 'Hfoo': no parameter of ANDES's GENROU"
    with pytest.raises(InputError, match=f"columns ANDES ignores: {column}"):
        read_andes_case(path)
    with pytest.warns(UserWarning, match=column):
        assert column in read_andes_case(path, on_unsupported="skip").left_out


def run_cli(*args, cwd):
    return subprocess.run(
        [sys.executable, "-m", "stabctl.cli", *map(str, args)],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_andes_s_log_is_said_in_stabctl_s_words_not_shown(tmp_path):
    """ANDES's own log lines reached stderr (its handler, set up on first use): a case ANDES
    cannot set up (a REECA1 option out of its choices) is one error line with ANDES's
    words; a case whose ANDES power flow fails imports with stabctl's warning only."""
    bad = cells_edited(tmp_path, [("REECA1", 2, "PFFLAG", 2)], case="kundur/kundur_reg.xlsx")
    res = run_cli("import-andes", bad, "-o", "bad.json", cwd=tmp_path)
    assert res.returncode == 2, res.stderr
    assert res.stderr.splitlines() == [
        "error: edited.xlsx: ANDES cannot read the case: option 2.0 is invalid for "
        "REECA1.PFFLAG. Options are (0, 1)."
    ]
    assert not (tmp_path / "bad.json").exists()
    heavy = cells_edited(tmp_path, [("PQ", 2, "p0", 100.0)])  # beyond what the grid carries
    res = run_cli("import-andes", heavy, "-o", "heavy.json", "--keep-unsolved", cwd=tmp_path)
    assert res.returncode == 0, res.stderr
    assert [line for line in res.stderr.splitlines() if not line.startswith("warning: ")] == []
    assert "ANDES's power flow of the case did not converge" in res.stderr


def test_an_unsolved_power_flow_is_refused_unless_kept(tmp_path):
    """Kundur with a bus load beyond what the grid carries: neither ANDES's power flow nor
    stabctl's converges.  import-andes wrote the case with a warning, exit 0 (every
    analysis command then refused it); it refuses it as import-psse does, naming the
    worst mismatch and its bus (exit status 2, nothing written), and --keep-unsolved
    writes it with the warnings."""
    heavy = cells_edited(tmp_path, [("PQ", 2, "p0", 100.0)])
    res = run_cli("import-andes", heavy, "-o", "heavy.json", cwd=tmp_path)
    assert res.returncode == 2, res.stderr
    assert re.fullmatch(
        r"error: edited\.xlsx: stabctl's power flow of the case \(Q limits off, as ANDES and "
        r"simulate --no-q-limits solve it\) does not converge, so every analysis command "
        r"would refuse it: power flow of case 'edited' did not converge after \d+ "
        r"iteration\(s\): worst mismatch [\d.]+ pu at bus \d+ .*; nothing written "
        r"\(--keep-unsolved writes it all the same\)",
        res.stderr.splitlines()[-1],
    ), res.stderr
    assert not (tmp_path / "heavy.json").exists()
    res = run_cli("import-andes", heavy, "-o", "heavy.json", "--keep-unsolved", cwd=tmp_path)
    assert res.returncode == 0 and (tmp_path / "heavy.json").exists(), res.stderr
    assert "warning: stabctl's power flow of the case did not converge" in res.stderr
    assert "--keep-unsolved" in run_cli("import-andes", "--help", cwd=tmp_path).stdout


def test_an_unsolved_power_flow_says_when_andes_s_converges_and_what_was_out(tmp_path):
    """Round 48: Kundur with bus 2 out of service (its machine and lines taken out with
    it): ANDES's power flow converges, stabctl's does not, and the refusal named only the
    mismatch.  It now says that ANDES's converges and which devices were left out."""
    off = cells_edited(tmp_path, [("Bus", 3, "u", 0)])
    res = run_cli("import-andes", off, "-o", "off.json", cwd=tmp_path)
    assert res.returncode == 2, res.stderr
    last = res.stderr.splitlines()[-1]
    assert "does not converge" in last and "(ANDES's own power flow of the file converges; " in last
    assert "device(s) out of service left out, as ANDES leaves them: " in last
    assert not (tmp_path / "off.json").exists()


def test_a_zero_impedance_branch_of_a_raw_file_is_refused_by_both_importers(tmp_path):
    """Kundur's RAW file with branch 8-9 '1' of R = X = 0: import-psse refuses it (R + jX
    must not be 0); ANDES's reader ran it at X = 1e-8 pu, which import-andes kept without a
    word: refused too, naming the line and its buses."""
    from stabctl.io.psse import load_psse

    text = Path(andes.get_case("kundur/kundur.raw")).read_text()
    branch = "     8,      9,'1 ', 2.00000E-3, 2.00000E-2,"
    assert text.count(branch) == 1
    raw = tmp_path / "kundur_zero.raw"
    raw.write_text(text.replace(branch, "     8,      9,'1 ', 0.00000E+0, 0.00000E+0,"))
    with pytest.raises((CaseError, InputError), match=r"branch 8-9 '1': R \+ jX must not be 0"):
        load_psse(raw)
    with pytest.raises(
        CaseError, match=r"kundur_zero.raw: Line Line_8 \(buses 8-9\): r = x = 0: a zero"
    ):
        read_andes_case(raw, on_unsupported="skip")


def test_andes_loads_leave_nothing_in_the_temporary_directory(tmp_path, monkeypatch):
    """ANDES's logger set-up made a directory andes-XXXXXXXX in the temporary directory on
    every ANDES call stabctl made (its ``get_log_dir``), the first of a process holding a
    debug log, the others empty: import-andes and the reference run's system leave the
    temporary directory as they found it."""
    import tempfile

    from click.testing import CliRunner

    from stabctl.cli import main
    from stabctl.io.andes import andes_system

    tmp = tmp_path / "tmp"
    tmp.mkdir()
    monkeypatch.setenv("TMPDIR", str(tmp))
    monkeypatch.setattr(tempfile, "tempdir", str(tmp))
    case = andes.get_case(KUNDUR)
    res = CliRunner().invoke(main, ["import-andes", case, "-o", str(tmp_path / "k.json")])
    assert res.exit_code == 0, res.output
    assert andes_system(case, off=("Toggle",)).is_setup
    assert sorted(p.name for p in tmp.iterdir()) == []


def test_a_json_file_not_in_andes_s_layout_is_named_for_what_it_is(tmp_path):
    """import-andes of a stabctl case file ended in "ANDES cannot read the case: 'int'
    object is not iterable" (ANDES read its "version": 1 as model rows); a stabctl case, a
    PSTess matrix file and any json whose key holds no list of device records are named
    for what they are, with the layout import-andes reads."""
    import json

    from stabctl.io import load_case
    from stabctl.io.pst import case_to_dict, write_case_json

    own = write_case_json(load_case("kundur"), tmp_path / "k.json")
    with pytest.raises(InputError, match=r'^k.json: a stabctl case file \("format": "stabctl-'):
        read_andes_case(own)
    res = run_cli("import-andes", own, "-o", "a.json", cwd=tmp_path)
    assert res.returncode == 2 and not (tmp_path / "a.json").exists()
    assert (
        res.stderr.startswith("error: k.json: a stabctl case file") and "iterable" not in res.stderr
    )
    assert "stabctl's commands read it as it is" in res.stderr and len(res.stderr.splitlines()) == 1
    tables = case_to_dict(load_case("kundur"))["tables"]
    pstess = tmp_path / "m.json"
    pstess.write_text(
        json.dumps({"bus": tables["buses"]["rows"], "line": tables["branches"]["rows"]})
    )
    with pytest.raises(InputError, match=r"^m.json: a PSTess matrix file"):
        read_andes_case(pstess)
    ieee14 = json.loads(Path(andes.get_case("ieee14/ieee14.json")).read_text())
    for key, value, what in (
        ("Bus", {"idx": 1}, "an object"),
        ("Line", [[1, 2]], "a list holding a list"),
        ("PQ", 3, "the value 3"),
    ):
        other = tmp_path / "other.json"
        other.write_text(json.dumps({**ieee14, key: value}))
        with pytest.raises(InputError, match=rf"^other.json: key '{key}' holds {what}, not a list"):
            read_andes_case(other)
    other.write_text("[1, 2]")
    with pytest.raises(InputError, match=r"^other.json: holds a list, not an ANDES case: an ANDES"):
        read_andes_case(other)
    # round 42 (R01): 200 MB of NULs was read whole three times (1 GiB) before ANDES's
    # "Expecting value"; a first byte no JSON text starts with is refused before reading on
    for text, said in ((b"\0" * 4096, r"b'\\x00'"), (b" \n\t", "nothing but white space")):
        other.write_bytes(text)
        with pytest.raises(InputError, match=rf"^other.json: not JSON text \(.*{said}"):
            read_andes_case(other)


def test_an_andes_case_without_a_line_is_named_so(tmp_path):
    """Round 42: an ANDES json of buses alone ended in "small: the data defines no 'line'
    matrix", the wording of a PSTess matrix file; IEEE 14 without its Line sheet (its 20
    branches, the transformers among them) is named for its lack of branches."""
    import json

    from stabctl.errors import CaseError

    ieee14 = json.loads(Path(andes.get_case("ieee14/ieee14.json")).read_text())
    assert len(ieee14["Line"]) == 20
    bare = tmp_path / "bare.json"
    bare.write_text(json.dumps({k: v for k, v in ieee14.items() if k != "Line"}))
    with pytest.raises(CaseError, match=r"^bare.json: no Line record \(ANDES's lines and tr"):
        read_andes_case(bare)


def test_an_andes_json_field_text_beyond_any_name_is_refused_before_andes_copies_it(
    tmp_path, monkeypatch
):
    """Round 42: a Bus idx of 266 million characters (a 254 MB file, under the input cap)
    took 2 GB in ANDES's copies before "no 'line' matrix"; a text of more than 1024
    characters in a device record is refused naming its row and field, and ANDES never
    reads the file."""
    import json

    from stabctl.io import andes_case

    ieee14 = json.loads(Path(andes.get_case("ieee14/ieee14.json")).read_text())
    ieee14["PQ"][2]["name"] = "x" * 1025
    long = tmp_path / "long.json"
    long.write_text(json.dumps(ieee14))
    monkeypatch.setattr(andes_case, "_load", lambda *a: pytest.fail("ANDES read it"))
    with pytest.raises(InputError, match=r"^long.json: PQ row 3: name holds a text of 1025 ch"):
        read_andes_case(long)


def test_an_andes_json_giving_a_key_twice_is_refused(tmp_path):
    """ANDES's json reader keeps the last of a model given twice: the first's devices were
    left out without a word."""
    text = Path(andes.get_case("5bus/pjm5bus.json")).read_text().rstrip()
    path = tmp_path / "twice.json"
    path.write_text(text[:-1] + ', "Area": [{"idx": 9, "u": 1, "name": "9"}]}')
    with pytest.raises(InputError, match=r'^twice.json: key "Area" given twice in one object'):
        read_andes_case(path)


@pytest.mark.parametrize(
    "field, value, shown, why",
    [
        ("Sn", True, "true", "ANDES reads it as 1"),
        ("u", False, "false", "ANDES reads it as 0"),
        ("Sn", [1], "[1]", "ANDES cannot read it"),
        ("Sn", {"v": 1}, '{"v": 1}', "ANDES cannot read it"),
    ],
)
def test_a_json_value_that_is_no_number_is_refused_naming_model_row_and_field(
    tmp_path, field, value, shown, why
):
    """ieee14_pvd1.json with a PVD1 value JSON true (ANDES ran it as 1 without a word), a
    list or an object (ANDES failed with numpy's "inhomogeneous shape", naming nothing of
    the file): refused naming the model, the row, the field and the value, as stabctl's
    own case files refuse them, nothing written."""
    import json

    data = json.loads(Path(andes.get_case("ieee14/ieee14_pvd1.json")).read_text())
    data["PVD1"][0][field] = value
    path = tmp_path / "edited.json"
    path.write_text(json.dumps(data))
    with pytest.raises(
        CaseError,
        match=rf"^edited\.json: PVD1 row 1 \(idx 1\): {field} = {re.escape(shown)}: not a number "
        rf"\({why}\)$",
    ):
        read_andes_case(path, on_unsupported="skip")
    res = run_cli("import-andes", path, "-o", "out.json", "--skip-unsupported", cwd=tmp_path)
    assert res.returncode == 2 and not (tmp_path / "out.json").exists()


def test_a_json_model_beyond_any_case_s_size_is_refused_before_andes_reads_it(
    tmp_path, monkeypatch
):
    """Round 30: 1.5 million json Bus records (50 MB, under the file cap) kept ANDES busy
    for minutes (about an hour near the cap) before its error."""
    from stabctl.io import andes_case

    path = tmp_path / "big.json"
    path.write_text(json.dumps({"Bus": [{"idx": k, "Vn": 110.0} for k in range(1, 5)]}))
    monkeypatch.setattr(andes_case, "MAX_MODEL_ROWS", 3)
    with pytest.raises(InputError, match=r"big.json: Bus holds 4 records, more than 3 \("):
        read_andes_case(path)


def test_an_xlsx_beyond_any_case_s_size_is_refused_before_it_is_read(tmp_path, monkeypatch):
    """A sheet of 3 million empty rows (78 MB of XML packed into 0.2 MB) kept pandas and
    ANDES busy for minutes: the rows are counted in the XML as it unpacks, and the file
    refused naming the sheet; a file that is no zip archive is named as such."""
    import zipfile

    from stabctl.io import andes_case

    path = tmp_path / "rows.xlsx"
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr(
            "xl/worksheets/sheet1.xml", "<sheetData>" + '<row r="1"/>' * 1001 + "</sheetData>"
        )
    monkeypatch.setattr(andes_case, "MAX_MODEL_ROWS", 1000)
    with pytest.raises(
        InputError, match=r"rows.xlsx: xl/worksheets/sheet1.xml holds more than 1000 rows"
    ):
        andes_case.check_xlsx_size(path)
    monkeypatch.setattr(andes_case, "MAX_MODEL_ROWS", 1001)
    andes_case.check_xlsx_size(path)  # 1001 rows: at the bound
    monkeypatch.setattr(andes_case, "MAX_XLSX_SHEET_BYTES", 100)
    with pytest.raises(InputError, match=r"sheet1.xml unpacks to \d+ bytes"):
        andes_case.check_xlsx_size(path)
    text = tmp_path / "text.xlsx"
    text.write_text("bus,name\n1,a\n")
    with pytest.raises(InputError, match=r"text.xlsx: not an xlsx workbook"):
        andes_case.check_xlsx_size(text)


def _zipped(path, parts):
    import zipfile

    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        for name, text in parts.items():
            z.writestr(name, text)
    return path


@pytest.mark.parametrize(
    "parts, said",
    [
        # a row tag with a namespace prefix: the count read '<row' only
        (
            {"xl/worksheets/sheet1.xml": "<x:sheetData>" + "<x:row/>" * 1001 + "</x:sheetData>"},
            r"xl/worksheets/sheet1.xml holds more than 1000 rows",
        ),
        # a sheet placed outside xl/worksheets/ by its relationships: not checked
        (
            {"xl/data/sheet1.xml": "<sheetData>" + "<row/>" * 1001 + "</sheetData>"},
            r"xl/data/sheet1.xml holds more than 1000 rows",
        ),
        # one row numbered far beyond: readers fill every row up to it (30 M rows of a
        # 17 kB file took 4 GB)
        (
            {"xl/worksheets/sheet1.xml": '<sheetData><row r="30000000"><c r="A30000000"/></row>'},
            r"sheet1.xml numbers a row 30000000, beyond 1000 rows",
        ),
        # a dimension reaching as far
        (
            {"xl/worksheets/sheet1.xml": '<dimension ref="A1:B5000"/><sheetData/>'},
            r"sheet1.xml numbers a row 5000, beyond 1000 rows",
        ),
    ],
)
def test_an_xlsx_s_rows_are_counted_however_written_and_wherever_placed(
    tmp_path, monkeypatch, parts, said
):
    """Round 34: the rows of an xlsx case escaped their count written with a namespace
    prefix, in a part outside xl/worksheets/ or as a row number far beyond the others."""
    from stabctl.io import andes_case

    monkeypatch.setattr(andes_case, "MAX_MODEL_ROWS", 1000)
    with pytest.raises(InputError, match=said):
        andes_case.check_xlsx_size(_zipped(tmp_path / "x.xlsx", parts))
    within = {"xl/worksheets/sheet1.xml": '<sheetData><row r="1001"/></sheetData>'}
    andes_case.check_xlsx_size(_zipped(tmp_path / "y.xlsx", within))  # the header + 1000


def test_an_xlsx_whose_parts_unpack_beyond_a_case_s_is_refused(tmp_path, monkeypatch):
    """A shared-strings part of 1.56 GB packed into 3.8 MB is no sheet: it was read whole
    (3.4 GB, then a MemoryError traceback).  Every part counts towards MAX_XLSX_BYTES."""
    from stabctl.io import andes_case

    monkeypatch.setattr(andes_case, "MAX_XLSX_BYTES", 10_000)
    strings = "<sst>" + "<si><t>a</t></si>" * 1000 + "</sst>"
    path = _zipped(tmp_path / "s.xlsx", {"xl/sharedStrings.xml": strings})
    with pytest.raises(InputError, match=r"s.xlsx: its parts unpack to 17011 bytes, more than"):
        andes_case.check_xlsx_size(path)


def test_an_xlsx_with_a_dangling_external_link_is_checked_as_any_other(tmp_path):
    """Round 34: a workbook naming an external link it does not hold made stabctl's own
    reading fail (openpyxl followed links; pandas and ANDES do not), and that failure was
    taken for 'nothing to check': a GENROU M = 0 ran at ANDES's default M = 6 without a
    word.  The links are not followed, so the rows are checked; a workbook stabctl cannot
    read at all after ANDES did is refused by name."""
    import zipfile

    path = cells_edited(tmp_path, [("GENROU", 2, "M", 0)])
    linked = tmp_path / "linked.xlsx"
    with zipfile.ZipFile(path) as src, zipfile.ZipFile(linked, "w", zipfile.ZIP_DEFLATED) as z:
        for info in src.infolist():
            data = src.read(info)
            if info.filename == "xl/workbook.xml":
                data = data.replace(
                    b"</sheets>",
                    b'</sheets><externalReferences><externalReference r:id="rId99"/>'
                    b"</externalReferences>",
                )
            z.writestr(info, data)
    with pytest.raises(CaseError, match=r"GENROU row 1 \(idx 1; spreadsheet row 2\): M = 0"):
        read_andes_case(linked)


def test_a_workbook_stabctl_cannot_read_after_andes_did_is_refused(tmp_path, monkeypatch):
    """Any failure of stabctl's reading of the rows (after ANDES read the file) refuses
    the file naming it, instead of importing it unchecked."""
    from stabctl.io import andes_case

    def cannot(path):
        raise KeyError("There is no item named 'xl/externalLinks/externalLink1.xml'")

    monkeypatch.setattr(andes_case, "_cell_texts", cannot)
    with pytest.raises(InputError, match=r"kundur_full.xlsx: ANDES reads the workbook, but"):
        read_andes_case(andes.get_case(KUNDUR))


@pytest.mark.parametrize("model, what", [("TGOV1", "turbine governor"), ("EXDC2", "exciter")])
def test_a_second_control_of_one_machine_is_refused_naming_both_rows(tmp_path, model, what):
    """Round 40: two TGOV1 of one GENROU in an ANDES json: ANDES said only "Your input
    data may be inconsistent" (two EXDC2 were named, as a DYR's are).  Both rows named."""
    case = json.loads(Path(andes.get_case("kundur/kundur_full.json")).read_text())
    case[model][1]["syn"] = case[model][0]["syn"]
    path = tmp_path / "twice.json"
    path.write_text(json.dumps(case))
    with pytest.raises(
        CaseError,
        match=rf"^twice.json: {model} row 2 \(idx 2\): a second {what} of syn 1 "
        rf"\(the first: {model} row 1 \(idx 1\)\)",
    ):
        read_andes_case(path)


def test_ac8b_limits_it_does_not_model_are_named_not_run_at_a_default(tmp_path):
    """Round 41: AC8B's VFEMAX 1 and VEMIN 0.5 were read without a word and had no effect
    on the run, and left out they were "run at ANDES's: AC8B VFEMAX = 999", a value no run
    uses.  Given, they are named as without effect (kept with --skip-unsupported); left
    out, not said to run at any value."""
    import math

    import pandas as pd

    sheets = pd.read_excel(andes.get_case("ieee14/ieee14_ac8b.xlsx"), sheet_name=None)
    case = {
        k: [
            {c: v for c, v in r.items() if not (isinstance(v, float) and math.isnan(v))}
            for r in df.dropna(axis=0, how="all").to_dict("records")
        ]
        for k, df in sheets.items()
    }
    path = tmp_path / "ac8b.json"
    path.write_text(json.dumps(case, default=str))
    got = read_andes_case(path)
    assert not [d for d in got.defaulted if "VFEMAX" in d or "VEMIN" in d], got.defaulted
    case["AC8B"][0] |= {"VFEMAX": 1.0, "VEMIN": 0.5}
    path.write_text(json.dumps(case, default=str))
    with pytest.raises(InputError, match=r"VFEMAX = 1 has no effect: not modelled"):
        read_andes_case(path)
