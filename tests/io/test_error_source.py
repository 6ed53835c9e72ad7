"""Bad dynamic data is refused by an import naming where the user wrote it: the DYR record
(``file:line MODEL (bus B, id I)``), the ANDES device (``file: MODEL row R (idx I)``) or
the case file, with the parameter(s) as that format names them and their values as
written (exit status 2, one ``error:`` line, nothing written).  The values a run's model
cannot take are refused there, at import, not first by ``simulate``.

Sources of the limits: the PSS/E Model Library (GENROU X'd >= X''d; SEXS, IEEEST, IEEEG1
upper limits at or above their lower; HYGOV At, the turbine gain its start-up flow
divides by; PSS2A's ramp-tracking filter M N <= 8; the stabiliser input codes 0 to 6),
IEEE Std 421.5 (the exciters' saturation points and rate feedback), and stabctl's own
modelling floor of 1e-3 s for a lag its model needs (`stabctl.models.blocks.LBND`).
"""

import json
import re
from pathlib import Path

import pytest
from click.testing import CliRunner

from stabctl.cli import main
from stabctl.errors import CaseError
from stabctl.io import load_case

RAW = Path(__file__).parents[1] / "data" / "psse" / "smib_v33.raw"

#: a valid record of each model used (PSS/E Model Library parameter order)
RECORDS = {
    "GENROU": (
        "T'do T''do T'qo T''qo H D Xd Xq X'd X'q X''d Xl S10 S12",
        "4.6385 0.0626 0.4384 0.0541 6.5385 0 1.8689 1.7795 0.2426 0.2884 0.1508 0.1158 "
        "0.1152 0.441",
    ),
    "SEXS": ("TA/TB TB K TE EMIN EMAX", "0.1 10 100 0.05 -5 5"),
    "IEEET1": (
        "TR KA TA VRMAX VRMIN KE TE KF TF Switch E1 SE1 E2 SE2",
        "0 50 0.04 5 -5 1 0.5 0.05 1 0 2.8 0.04 3.73 0.33",
    ),
    "EXST1": (
        "TR VIMAX VIMIN TC TB KA TA VRMAX VRMIN KC KF TF",
        "0.02 0.2 -0.2 1 10 200 0.02 5 -5 0.05 0 1",
    ),
    "EXAC1": (
        "TR TB TC KA TA VRMAX VRMIN TE KF TF KC KD KE E1 SE1 E2 SE2",
        "0 0 0 400 0.02 9 -5 0.8 0.03 1 0.2 0.48 1 3.14 0.03 4.18 0.1",
    ),
    "TGOV1": ("R T1 VMAX VMIN T2 T3 Dt", "0.05 0.5 1.0 0.0 2.1 7.0 0.0"),
    "IEEEG1": (
        "JBUS M K T1 T2 T3 Uo Uc PMAX PMIN T4 K1 K2 T5 K3 K4 T6 K5 K6 T7 K7 K8",
        "0 0 20 0 0 0.1 1 -1 1 0 0.3 0.3 0 7 0.4 0 0.6 0.3 0 0 0 0",
    ),
    "HYGOV": (
        "R r Tr Tf Tg VELM GMAX GMIN TW At Dturb qNL",
        "0.05 0.3 5 0.05 0.5 0.2 1 0 1 1.2 0.5 0.08",
    ),
    "GAST": ("R T1 T2 T3 AT KT VMAX VMIN Dturb", "0.05 0.4 0.1 3 1 2 1 0 0"),
    "STAB1": ("K/T T T1/T3 T3 T2/T4 T4 HLIM", "20 10 1 0.05 1 0.05 0.1"),
    "IEEEST": (
        "ICS IB A1 A2 A3 A4 A5 A6 T1 T2 T3 T4 T5 T6 KS LSMAX LSMIN VCU VCL",
        "1 0 0 0 0 0 0 0 0.1 0.02 0.2 0.02 10 10 1 0.1 -0.1 0 0",
    ),
    "PSS2A": (
        "ICS1 IB1 ICS2 IB2 M N TW1 TW2 T6 TW3 TW4 T7 KS2 KS3 T8 T9 KS1 T1 T2 T3 T4 VSTMAX VSTMIN",
        "1 0 3 0 5 1 10 10 0 10 0 10 1.13 1 0.3 0.15 20 0.15 0.03 0.15 0.03 0.1 -0.1",
    ),
}
#: PSS/E's infinite bus at the SMIB case's bus 2 (GENCLS H = 0)
INFINITE = "    2 'GENCLS' 1 0.0 0.0 /"


def record(model: str, changes=None, bus: int = 1) -> str:
    """A DYR record of `model` at `bus`, id 1: its valid values but `changes` (parameter
    name -> value)."""
    names, values = (part.split() for part in RECORDS[model])
    given = dict(zip(names, values))
    for name, value in (changes or {}).items():
        assert name in given, name
        given[name] = str(value)
    return f"    {bus} '{model}' 1 " + " ".join(given[n] for n in names) + " /"


def imported(tmp_path, lines, *options):
    """import-psse of the SMIB RAW file with a DYR of `lines` (line 1 the machine, line
    2 the infinite bus): (the CliRunner result, the DYR file, the case file to write)."""
    dyr = tmp_path / "bad.dyr"
    dyr.write_text("\n".join(lines) + "\n")
    out = tmp_path / "bad.json"
    res = CliRunner().invoke(main, ["import-psse", str(RAW), str(dyr), "-o", str(out), *options])
    return res, dyr, out


def error_line(res) -> str:
    """The one ``error:`` line of a refused command."""
    errors = [line for line in res.output.splitlines() if line.startswith("error:")]
    assert res.exit_code == 2 and len(errors) == 1, res.output
    return errors[0]


@pytest.mark.parametrize(
    "machine, controls, expected",
    [
        # values the tables refused naming their own row and field (mac_con xdp, exc_con
        # Vrmax for SEXS's EMAX, TC for TA/TB, tg_con Uo for HYGOV's VELM, Ts for TGOV1's T1)
        (
            record("GENROU", {"X''d": 0.3}),
            [],
            "bad.dyr:1 GENROU (bus 1, id 1): X'd = 0.2426, X''d = 0.3: x'd must be >= x\"d",
        ),
        # round 40: a subtransient circuit slower than the transient one, and a lead
        # without its lag (TC had no effect on the run), were read without a word
        (
            record("GENROU", {"T'do": 0.03, "T''do": 8.0}),
            [],
            "bad.dyr:1 GENROU (bus 1, id 1): T''do = 8.0, T'do = 0.03: T\"do must be < T'do "
            "= 0.03 s (a subtransient machine, x'd > x\"d)",
        ),
        (
            record("GENROU", {"T'qo": 0.05, "T''qo": 0.4}),
            [],
            "bad.dyr:1 GENROU (bus 1, id 1): T''qo = 0.4, T'qo = 0.05: T\"qo must be < T'qo",
        ),
        (
            record("GENROU"),
            [record("EXST1", {"TB": 0, "TC": 10})],
            "bad.dyr:3 EXST1 (bus 1, id 1): TC = 10, TB = 0: a lead without its lag (a lag "
            "below 0.001 s bypasses the lead-lag) (exciter type 4, EXST1",
        ),
        (
            record("GENROU"),
            [record("EXAC1", {"TB": 0, "TC": 0.5})],
            "bad.dyr:3 EXAC1 (bus 1, id 1): TC = 0.5, TB = 0: a lead without its lag",
        ),
        # round 41: a governor's lead without its lag (no effect on the run) and a
        # stabiliser's, named in the record's own fields
        (
            record("GENROU"),
            [record("SEXS"), record("IEEEG1", {"T2": 1.0})],
            "bad.dyr:4 IEEEG1 (bus 1, id 1): T2 = 1.0, T1 = 0: a lead without its lag",
        ),
        # round 40: a negative washout time constant was "unsupported", named neither
        (
            record("GENROU"),
            [record("IEEET1"), record("IEEEST", {"T6": -4.2})],
            "bad.dyr:4 IEEEST (bus 1, id 1): T6 = -4.2: must be >= 0 (a time constant)",
        ),
        (
            record("GENROU"),
            [record("SEXS", {"EMIN": 5, "EMAX": -5})],
            "bad.dyr:3 SEXS (bus 1, id 1): EMAX = -5, EMIN = 5: the upper limit must be >= "
            "the lower (exciter type 0",
        ),
        (
            record("GENROU"),
            [record("SEXS", {"TE": -0.05})],
            "bad.dyr:3 SEXS (bus 1, id 1): TE = -0.05: must be >= 0",
        ),
        (
            record("GENROU"),
            [record("SEXS", {"TA/TB": -0.1})],
            "bad.dyr:3 SEXS (bus 1, id 1): TA/TB = -0.1, TB = 10 (giving exc_con 'TC' = -1): "
            "must be >= 0",
        ),
        (
            record("GENROU"),
            [record("SEXS"), record("HYGOV", {"VELM": -0.2})],
            "bad.dyr:4 HYGOV (bus 1, id 1): VELM = -0.2: must be >= 0",
        ),
        (
            record("GENROU"),
            [record("SEXS"), record("TGOV1", {"T1": -0.5})],
            "bad.dyr:4 TGOV1 (bus 1, id 1): T1 = -0.5: must be >= 0",
        ),
        (
            record("GENROU"),
            [record("SEXS"), record("STAB1", {"T3": -0.05})],
            "bad.dyr:4 STAB1 (bus 1, id 1): T1/T3 = 1, T3 = -0.05: must be >= 0",
        ),
        (
            record("GENROU"),
            [record("IEEET1"), record("IEEEST", {"LSMAX": -0.1, "LSMIN": 0.1})],
            "bad.dyr:4 IEEEST (bus 1, id 1): LSMAX = -0.1, LSMIN = 0.1: the upper limit must "
            "be >= the lower",
        ),
        (
            record("GENROU"),
            [record("SEXS"), record("IEEEG1", {"PMAX": 0, "PMIN": 1})],
            "bad.dyr:4 IEEEG1 (bus 1, id 1): PMAX = 0, PMIN = 1: the upper limit must be >= "
            "the lower",
        ),
        # values simulate refused at its set-up after the import wrote them
        (
            record("GENROU"),
            [record("IEEET1", {"TE": 0})],
            "bad.dyr:3 IEEET1 (bus 1, id 1): TE = 0: exciter type 1 needs TE >= 0.001 s",
        ),
        (
            record("GENROU"),
            [record("IEEET1", {"TF": 0})],
            "bad.dyr:3 IEEET1 (bus 1, id 1): TF = 0: exciter type 1 needs TF >= 0.001 s",
        ),
        (
            record("GENROU"),
            [record("EXST1", {"KF": 0.1, "TF": 0})],
            "bad.dyr:3 EXST1 (bus 1, id 1): TF = 0, KF = 0.1: exciter type 4 needs TF >= "
            "0.001 s where KF != 0",
        ),
        (
            record("GENROU"),
            [record("EXAC1", {"TE": 0})],
            "bad.dyr:3 EXAC1 (bus 1, id 1): TE = 0: exciter type",
        ),
        (
            record("GENROU"),
            [record("EXAC1", {"E1": 4.18, "SE1": 0.3})],
            "bad.dyr:3 EXAC1 (bus 1, id 1): E1 = 4.18, SE(E1) = 0.3, E2 = 4.18, SE(E2) = 0.1: ",
        ),
        (
            record("GENROU"),
            [record("SEXS"), record("TGOV1", {"T3": 0})],
            "bad.dyr:4 TGOV1 (bus 1, id 1): T3 = 0: must be >= 0.001 s for governor type 2",
        ),
        (
            record("GENROU"),
            [record("SEXS"), record("IEEEG1", {"T3": 0})],
            "bad.dyr:4 IEEEG1 (bus 1, id 1): T3 = 0: must be >= 0.001 s for governor type 3",
        ),
        (
            record("GENROU"),
            [record("SEXS"), record("IEEEG1", {"K1": 0, "K3": 0, "K5": 0})],
            "bad.dyr:4 IEEEG1 (bus 1, id 1): K1 = 0, K2 = 0, K3 = 0, K4 = 0, K5 = 0, K6 = 0, "
            "K7 = 0, K8 = 0: IEEEG1 power fractions K1..K8 must sum to > 0",
        ),
        (
            record("GENROU"),
            [record("SEXS"), record("GAST", {"T1": 0})],
            "bad.dyr:4 GAST (bus 1, id 1): T1 = 0: must be >= 0.001 s for governor type 6",
        ),
        (
            record("GENROU"),
            [record("SEXS"), record("HYGOV", {"At": 0})],
            "bad.dyr:4 HYGOV (bus 1, id 1): At = 0: must be > 0 (governor type 4, HYGOV",
        ),
        (
            record("GENROU"),
            [record("SEXS"), record("TGOV1", bus=2)],
            "bad.dyr:4 TGOV1 (bus 2, id 1): tg_con 'machine' = 2: machine 2 is an infinite bus",
        ),
        (
            record("GENROU"),
            [record("IEEET1"), record("PSS2A", {"M": 9, "N": 9})],
            "bad.dyr:4 PSS2A (bus 1, id 1): M = 9, N = 9, T9 = 0.15: a ramp-tracking filter "
            "(N = 9) needs 1 <= M, M N <= 8",
        ),
    ],
)
def test_a_dyr_value_is_refused_naming_its_record_and_parameters(
    tmp_path, machine, controls, expected
):
    """One error line naming file:line, model, bus and id, then the DYR parameters (as
    the PSS/E Model Library names them) with their values as written; nothing written."""
    res, _, out = imported(tmp_path, [machine, INFINITE, *controls])
    line = error_line(res)
    assert line.startswith(f"error: {expected}"), line
    assert not out.exists()


def test_an_unsupported_washout_names_its_parameters(tmp_path):
    """A washout time constant below 1e-3 s is left out as unsupported (with
    --skip-unsupported), the record named with its parameters and values."""
    controls = [record("IEEET1"), record("IEEEST", {"T6": 0})]
    res, _, _ = imported(tmp_path, [record("GENROU"), INFINITE, *controls])
    assert "IEEEST" in error_line(res) and "washout T5 = 10, T6 = 0: a numerator of 0" in res.output


def test_a_stabiliser_of_gain_0_is_named_as_without_effect(tmp_path):
    """Round 41: an IEEEST of KS 0 was counted "1 PSS" and the run was byte for byte the
    one without it.  Imported (PSS/E reads it), and named."""
    pss = record("IEEEST", {"KS": 0})
    res, _, _ = imported(tmp_path, [record("GENROU"), INFINITE, record("IEEET1"), pss])
    assert res.exit_code == 0, res.output
    assert "IEEEST (bus 1, id 1): KS = 0: its output is always 0, no effect on the run" in (
        res.output
    )


def test_ac8b_limits_it_does_not_model_are_named(tmp_path):
    """Round 41: AC8B's VFEMAX and VEMIN (not modelled) were read without a word; given
    as limits, the import names them as without effect (its summary of values read
    otherwise)."""
    ac8b = "    1 'AC8B' 1 0 80 5 10 0.1 1 0 35 0 1 0.5 0.02 1 1.2 0.55 1.1 1 6.5 0.3 9 3 /"
    res, _, _ = imported(tmp_path, [record("GENROU"), INFINITE, ac8b])
    assert res.exit_code == 0, res.output
    assert "VFEMAX = 1 has no effect: not modelled (as 999)" in res.output
    assert "VEMIN = 0.5 has no effect: not modelled (as -999)" in res.output


@pytest.mark.parametrize("code", ["7", "2.5", "-1"])
@pytest.mark.parametrize("skip", [(), ("--skip-unsupported",)])
def test_a_stabiliser_input_code_that_is_none_is_invalid_not_unsupported(tmp_path, code, skip):
    """IEEEST ICS 7 or 2.5 is no PSS/E input code (0 to 6): invalid data, named with the
    codes there are, refused even with --skip-unsupported, which it does not suggest."""
    lines = [record("GENROU"), INFINITE, record("IEEET1"), record("IEEEST", {"ICS": code})]
    res, _, out = imported(tmp_path, lines, *skip)
    line = error_line(res)
    assert line.startswith(
        f"error: bad.dyr:4 IEEEST (bus 1, id 1): ICS = {code}: not a PSS/E input code (an "
        "integer 0 to 6: 0 none, 1 rotor speed deviation,"
    ), line
    assert "--skip-unsupported" not in res.output and not out.exists()


def test_a_supported_input_code_of_an_unmodelled_signal_stays_unsupported(tmp_path):
    """ICS 2 (bus frequency) is a PSS/E input code stabctl does not model: unsupported,
    left out by --skip-unsupported."""
    lines = [record("GENROU"), INFINITE, record("IEEET1"), record("IEEEST", {"ICS": 2})]
    res, _, out = imported(tmp_path, lines)
    assert "unsupported record" in error_line(res) and "--skip-unsupported" in res.output
    res, _, out = imported(tmp_path, lines, "--skip-unsupported")
    assert res.exit_code == 0 and out.exists(), res.output


@pytest.mark.parametrize(
    "table, column, value, fields, expected",
    [
        # simulate refused these at its set-up, without naming the case file
        (
            "governors",
            "Ts",
            0,
            ("Ts",),
            "table 'governors' row 1 (machine 1), field 'Ts': must be >= 0.001 s for governor "
            "type 2, got 0",
        ),
        (
            "pss",
            "machine",
            2,
            ("machine",),
            "table 'pss' row 1 (machine 2), field 'machine': machine 2 has no exciter "
            "(table 'exciters') for the PSS output",
        ),
        (
            "governors",
            "machine",
            2,
            ("machine",),
            "table 'governors' row 1 (machine 2), field 'machine': machine 2 is an infinite bus",
        ),
    ],
)
def test_a_case_json_value_a_run_refuses_is_refused_naming_the_case_file(
    tmp_path, table, column, value, fields, expected
):
    """A case file (SEXS, TGOV1, STAB1 on the SMIB machine) with a value a run cannot
    take: refused as it is loaded, naming the file, table, row and field."""
    lines = [record("GENROU"), INFINITE, record("SEXS"), record("TGOV1"), record("STAB1")]
    res, _, out = imported(tmp_path, lines)
    assert res.exit_code == 0, res.output
    data = json.loads(out.read_text())
    rows = data["tables"][table]
    rows["rows"][0][rows["columns"].index(column)] = value
    bad = tmp_path / "bad_case.json"
    bad.write_text(json.dumps(data))
    with pytest.raises(CaseError) as err:
        load_case(bad)
    assert (err.value.row, err.value.fields) == (0, fields)
    res = CliRunner().invoke(main, ["simulate", str(bad), "--fault", "1", "--tf", "1.2"])
    line = error_line(res)
    assert line.startswith(f"error: {bad}: {expected}"), line


def andes_edited(tmp_path, case: str, model: str, field: str, value):
    """ANDES's case file as json with `field` of `model`'s first row set to `value`."""
    andes = pytest.importorskip("andes")
    pd = pytest.importorskip("pandas")
    sheets = pd.read_excel(andes.get_case(case), sheet_name=None)
    data = {
        name: [
            {k: v for k, v in row.items() if not (isinstance(v, float) and v != v)}
            for row in rows.dropna(axis=0, how="all").to_dict("records")
        ]
        for name, rows in sheets.items()
    }
    data[model][0][field] = value
    out = tmp_path / f"{model}_{field}.json"
    out.write_text(json.dumps(data, default=str))
    return out


@pytest.mark.parametrize(
    "case, model, field, value, expected",
    [
        # the table named its own column: ibr_con 'mva', 'pc_fdbd1', 'wq_Twref', 'dbd1'
        ("ieee14/ieee14_wt3.xlsx", "REGCA1", "Sn", -100, r"Sn = -100: device base must be > 0"),
        ("ieee14/ieee14_wt3.xlsx", "REECA1", "dbd1", 0.05, r"dbd1 = 0.05: must be <= 0"),
        ("ieee14/ieee14_wt3.xlsx", "REPCA1", "fdbd1", 0.05, r"fdbd1 = 0.05: must be <= 0"),
        (
            "ieee14/ieee14_wt3.xlsx",
            "WTTQA1",
            "Twref",
            -30,
            r"Twref = -30: it must be Twref >= 0\.001 s",
        ),
        # simulate refused them at set-up after the import wrote them
        ("ieee14/ieee14_wt3.xlsx", "REPCA1", "Tp", 0, r"Tp = 0: it must be Tp >= 0\.001 s \(a lag"),
        (
            "ieee14/ieee14_pvd1.xlsx",
            "PVD1",
            "tiq",
            0,
            r"tiq = 0: it must be tiq >= 0\.001 s \(a lag",
        ),
        # a link to a device the case lacks
        (
            "ieee14/ieee14_esd1.xlsx",
            "ESD1",
            "gen",
            99,
            r"gen = 99: no StaticGen \(PV, Slack\) of that idx in the case",
        ),
    ],
)
def test_an_andes_value_is_refused_naming_file_model_row_idx_and_parameter(
    tmp_path, case, model, field, value, expected
):
    """One error line naming the case file, the ANDES model (its sheet or json key), the
    row and idx of the device and ANDES's parameter name with its value as given."""
    path = andes_edited(tmp_path, case, model, field, value)
    out = tmp_path / "a.json"
    res = CliRunner().invoke(main, ["import-andes", str(path), "-o", str(out)])
    line = error_line(res)
    assert re.fullmatch(rf"error: {path.name}: {model} row 1 \(idx [^)]+\): {expected}.*", line)
    assert not out.exists()


FIVE_BUS = RAW.parent / "five_bus_v33.raw"
FIVE_BUS_DYR = RAW.parent / "five_bus.dyr"


@pytest.mark.parametrize(
    "old, new, expected",
    [
        # a number the RAW reader reads: named by the POM's name, not its position
        (
            "1,   1,   1,0.99000,  31.0000",
            "1,   1,   1,O.99000,  31.0000",
            "edited.raw:7 bus record: VM = 'O.99000': not a number",
        ),
        (
            "    2,'1 ',1,   1,   1,   100.000,",
            "    2,'1 ',1,   1,   1,   1OO.000,",
            "edited.raw:10 load record: PL = '1OO.000': not a number",
        ),
        # a number it does not read (a winding's RMA1): refused all the same, at its line
        (
            "240.00,   0.000,   0.000,   100.00,   100.00,   100.00, 0,      0, 1.10000,",
            "240.00,   0.000,   0.000,   100.00,   100.00,   100.00, 0,      0, 1.1OOOO,",
            "edited.raw:28 transformer record (line 3 of the record): RMA1 = '1.1OOOO': not a "
            "number",
        ),
        # a generator's own values, on its own record, as written
        (
            "    3,'1 ',   150.000,    20.000,   100.000,   -50.000,1.01000,",
            "    3,'1 ',   150.000,    20.000,   -50.000,   100.000,1.01000,",
            "edited.raw:18 generator record: generator at bus 3 '1': QT = -50.000, "
            "QB = 100.000: QT must be >= QB",
        ),
        (
            "    3,'1 ',   150.000,    20.000,   100.000,   -50.000,1.01000,",
            "    3,'1 ',   150.000,    20.000,   100.000,   -50.000,-1.01000,",
            "edited.raw:18 generator record: generator at bus 3 '1': VS = -1.01000: VS must be > 0",
        ),
    ],
)
def test_a_raw_value_is_refused_naming_line_field_and_value_as_written(
    tmp_path, old, new, expected
):
    """The RAW record's line, the field as the POM names it and its text as written; a
    malformed number in a field stabctl does not read is refused too (never accepted
    silently), and a generator's Q limits and VS on its own record, not the bus table."""
    text = FIVE_BUS.read_text()
    assert text.count(old) == 1, old
    raw = tmp_path / "edited.raw"
    raw.write_text(text.replace(old, new))
    out = tmp_path / "p.json"
    res = CliRunner().invoke(main, ["import-psse", str(raw), str(FIVE_BUS_DYR), "-o", str(out)])
    line = error_line(res)
    assert line.startswith(f"error: {expected}"), line
    assert not out.exists()


V35 = RAW.parent / "five_bus_v35.raw"


def refused_raw(tmp_path, source: Path, old: str, new: str, *options: str) -> tuple[str, Path]:
    """import-psse of `source` with `old` (once in it) replaced by `new`: the one error line
    (exit status 2 asserted) and the case file, which must not exist."""
    text = source.read_text()
    assert text.count(old) == 1, old
    raw = tmp_path / "edited.raw"
    raw.write_text(text.replace(old, new))
    out = tmp_path / "p.json"
    res = CliRunner().invoke(
        main, ["import-psse", str(raw), str(FIVE_BUS_DYR), "-o", str(out), *options]
    )
    assert not out.exists()
    return error_line(res), out


@pytest.mark.parametrize(
    "source, old, new, expected",
    [
        (
            FIVE_BUS,
            "    2,'1 ',1,   1,",
            "    2,'1 ',2,   1,",
            "edited.raw:10 load record: load at bus 2 '1': STATUS 2 must be 0 or 1",
        ),
        (
            FIVE_BUS,
            "    4,'1 ',1,   1,",
            "    4,'1 ',-1,   1,",
            "edited.raw:12 load record: load at bus 4 '1': STATUS -1 must be 0 or 1",
        ),
        # at an isolated bus too: the record is wrong wherever it is
        (
            FIVE_BUS,
            "    5,'1 ',1,   1,",
            "    5,'1 ',2,   1,",
            "edited.raw:13 load record: load at bus 5 '1': STATUS 2 must be 0 or 1",
        ),
        (
            FIVE_BUS,
            "    2,'1 ',1,     5.000",
            "    2,'1 ',3,     5.000",
            "edited.raw:15 fixed shunt record: fixed shunt at bus 2 '1': STATUS 3 must be 0 or 1",
        ),
        (
            FIVE_BUS,
            "1.00000,1,  100.0,   999.000",
            "1.00000,2,  100.0,   999.000",
            "edited.raw:17 generator record: generator at bus 1 '1': STAT 2 must be 0 or 1",
        ),
        (
            FIVE_BUS,
            "1.00000,0,  100.0",
            "1.00000,-1,  100.0",
            "edited.raw:20 generator record: generator at bus 3 '3': STAT -1 must be 0 or 1",
        ),
        (
            FIVE_BUS,
            "'1 ', 1.00000E-2, 1.00000E-1,   0.20000,  100.00,  100.00,  100.00,  0.00000,  "
            "0.00000,  0.00000,  0.00000,1,",
            "'1 ', 1.00000E-2, 1.00000E-1,   0.20000,  100.00,  100.00,  100.00,  0.00000,  "
            "0.00000,  0.00000,  0.00000,5,",
            "edited.raw:22 branch record: branch 1-2 '1': ST 5 must be 0 or 1",
        ),
        (
            FIVE_BUS,
            "0.05000,1,1,",
            "0.05000,-1,1,",
            "edited.raw:24 branch record: branch 1-2 '3': ST -1 must be 0 or 1",
        ),
        (
            FIVE_BUS,
            "'T1          ',1,",
            "'T1          ',7,",
            "edited.raw:26 transformer record (line 1 of the record): transformer 2-3 '1': "
            "STAT 7 must be 0 or 1",
        ),
        (
            FIVE_BUS,
            "    4,1,0,1,1.05000",
            "    4,1,0,4,1.05000",
            "edited.raw:{n} switched shunt record: switched shunt at bus 4: STAT 4 must be 0 or 1",
        ),
        # v35: the switched shunt's status is ST, after its ID
        (
            V35,
            "    4,'1 ',   1,  0,  1,1.05000",
            "    4,'1 ',   1,  0,  4,1.05000",
            "edited.raw:{n} switched shunt record: switched shunt at bus 4 '1': ST 4 must be 0 "
            "or 1",
        ),
        (
            V35,
            "    4,'1 ',   1,  0,  1,1.05000",
            "    4,'1 ',   1,  0,  -1,1.05000",
            "edited.raw:{n} switched shunt record: switched shunt at bus 4 '1': ST -1 must be 0 "
            "or 1",
        ),
    ],
)
def test_a_status_other_than_0_or_1_is_refused_naming_its_field(
    tmp_path, source, old, new, expected
):
    """PSS/E's POM gives loads, fixed shunts, generators, branches, two-winding
    transformers and switched shunts a status of 1 (in service) or 0 (out of service),
    nothing else: any other value is refused naming its line, the field by its POM name
    and the value as written (it had been read as in service without a word)."""
    n = next(k for k, t in enumerate(source.read_text().splitlines(), 1) if old in t)
    line, _ = refused_raw(tmp_path, source, old, new)
    assert line == f"error: {expected.format(n=n)}", line


@pytest.mark.parametrize("number", ["1000000", "999998", "-3"])
def test_a_bus_number_outside_pss_e_s_range_is_refused_as_written(tmp_path, number):
    """POM Bus Data: I is 1 to 999997; a bus number above (or not positive) is refused
    naming the line, field I and the number as written.  The other records' bus numbers
    name a bus of the bus data, so this one check bounds them all."""
    old = "    3,'GEN         ',"
    line, _ = refused_raw(tmp_path, FIVE_BUS, old, f"    {number},'GEN         ',")
    assert line == (
        f"error: edited.raw:6 bus record: I {number}: a bus number must be within 1 to 999997"
    ), line


def test_a_record_naming_a_bus_outside_the_range_is_refused_as_not_in_the_bus_data(tmp_path):
    """A load at bus 1000000: no such bus in the bus data (which holds none above
    999997)."""
    line, _ = refused_raw(tmp_path, FIVE_BUS, "    4,'1 ',1,   1,", "    1000000,'1 ',1,   1,")
    assert line == "error: edited.raw:12 load record: load bus 1000000 is not in the bus data"


def test_a_bus_given_twice_is_refused_naming_its_first_line(tmp_path):
    """A second record of bus 2 (its number written twice) names both lines."""
    line, _ = refused_raw(tmp_path, FIVE_BUS, "    3,'GEN         ',", "    2,'GEN         ',")
    assert line == "error: edited.raw:6 bus record: bus 2 appears twice (first at line 5)"


#: the first winding line (line 3 of the record) of the five-bus case's transformer T1
T1_WINDING_1 = "240.00,   0.000,   0.000,"


@pytest.mark.parametrize(
    "old, new, expected",
    [
        # the value as written, not as a float prints it
        (
            "  500.000, 0.00000E+0, 2.50000E-1",
            "  -200.0, 0.00000E+0, 2.50000E-1",
            "edited.raw:17 generator record: generator at bus 1 '1': MBASE -200.0 must be > 0",
        ),
        (
            "    4,'SUB         ', 115.0000,1,   1,   1,   1,0.99000,",
            "    4,'SUB         ', 115.0000,1,   1,   1,   1,-0.990,",
            "edited.raw:7 bus record: bus 4: VM -0.990 must be > 0",
        ),
        # a field of a transformer's winding line: at that line, and which line of the
        # record it is, as the field-count error says
        (
            T1_WINDING_1,
            "-240.00,   0.000,   0.000,",
            "edited.raw:28 transformer record (line 3 of the record): transformer 2-3 '1': "
            "WINDV1 -240.00 must be > 0",
        ),
        (
            T1_WINDING_1,
            "240.00,   0.000,   -190.0,",
            "edited.raw:28 transformer record (line 3 of the record): transformer 2-3 '1': "
            "ANG1 -190.0 degrees must be within -180 to 180",
        ),
        (
            T1_WINDING_1,
            "240.00,   -5.00,   0.000,",
            "edited.raw:28 transformer record (line 3 of the record): transformer 2-3 '1': "
            "NOMV1 -5.00 kV must be >= 0 (0: bus 2's BASKV)",
        ),
        (
            "21.000,   0.000",
            "-21.00,   0.000",
            "edited.raw:29 transformer record (line 4 of the record): transformer 2-3 '1': "
            "WINDV2 -21.00 must be > 0",
        ),
        (
            " 5.00000E-3, 8.00000E-2,   500.00",
            " 5.00000E-3, 8.00000E-2,   -50.0",
            "edited.raw:27 transformer record (line 2 of the record): transformer 2-3 '1': "
            "SBASE1-2 -50.0 MVA must be > 0",
        ),
        (
            " 0.00000E+0, 5.00000E-2,   100.00",
            " 0.00000E+0, 0.0,   100.00",
            "edited.raw:31 transformer record (line 2 of the record): transformer 4-2 '1': "
            "R1-2 = 0.00000E+0, X1-2 = 0.0: R1-2 + jX1-2 must not be 0",
        ),
        # the field count: the same form
        (
            " 5.00000E-3, 8.00000E-2,   500.00",
            " 5.00000E-3",
            "edited.raw:27 transformer record (line 2 of the record): 1 field(s), the v33 "
            "layout has 2 to 3",
        ),
        # a field of the first line: line 1 of the record
        (
            "    2,     3,     0,'1 ',2,2,1,",
            "    2,     3,     0,'1 ',5,2,1,",
            "edited.raw:26 transformer record (line 1 of the record): transformer 2-3 '1': "
            "CW 5 must be 1, 2 or 3",
        ),
    ],
)
def test_a_raw_field_is_named_at_its_own_line_with_its_text(tmp_path, old, new, expected):
    """Each field error names the file line that holds the field (for a record of several
    lines, which line of the record it is, as the field-count error does) and the value
    as the file writes it (MBASE -200.0 had been named -200, a winding's WINDV1 and ANG1
    the record's first line)."""
    line, _ = refused_raw(tmp_path, FIVE_BUS, old, new)
    assert line.startswith(f"error: {expected}"), line


#: the winding lines of a three-winding transformer (v33, CW 1)
WINDING = "1.0, 0.0, 0.0, 100.0, 100.0, 100.0, 0, 0, 1.1, 0.9, 1.1, 0.9, 33, 0, 0.0, 0.0, 0.0\n"
#: a three-winding transformer 1-2-4 for the five-bus case (v33, CW 1, CZ 1, CM 1), a
#: blank line before its winding-3 line
THREE_WINDING = (
    "    1,     2,     4,'9 ',1,1,1, 0.0, 0.0,2,'T3          ',1,   1,1.0000\n"
    " 1.0E-3, 5.0E-2, 100.0, 1.0E-3, 5.0E-2, 100.0, 1.0E-3, 5.0E-2, 100.0, 1.0, 0.0\n"
    + WINDING
    + WINDING
    + "\n"
    + WINDING.replace("1.0, 0.0, 0.0,", "1.0, 0.0, 0.00,")
)


@pytest.mark.parametrize(
    "old, new, expected",
    [
        (
            "'T3          ',1,",
            "'T3          ',5,",
            "edited.raw:34 transformer record (line 1 of the record): three-winding "
            "transformer 1-2-4 '9': STAT 5 must be 0, 1, 2, 3 or 4",
        ),
        (
            "100.0, 1.0, 0.0\n",
            "100.0, -1.00, 0.0\n",
            "edited.raw:35 transformer record (line 2 of the record): three-winding "
            "transformer 1-2-4 '9': VMSTAR -1.00 must be > 0",
        ),
        (
            "1.0, 0.0, 0.00,",
            "1.0, 0.0, 200.0,",
            "edited.raw:39 transformer record (line 5 of the record): three-winding "
            "transformer 1-2-4 '9': ANG3 200.0 degrees must be within -180 to 180",
        ),
    ],
)
def test_a_three_winding_field_is_named_at_its_own_line(tmp_path, old, new, expected):
    """A three-winding transformer's fields alike: STAT on line 1, VMSTAR on line 2, a
    winding's on its own line (the file's line, a blank line inside the record counted)."""
    marker = "0 / END OF TRANSFORMER DATA"
    source = tmp_path / "three.raw"
    source.write_text(FIVE_BUS.read_text().replace(marker, THREE_WINDING + marker))
    line, _ = refused_raw(tmp_path, source, old, new)
    assert line.startswith(f"error: {expected}"), line


#: a multi-terminal dc line (v33): NCONV 2, NDCBS 2, NDCLN 1, then those lines
MULTI_TERMINAL = (
    "'MTDC1', 2, 2, 1, 1, 500.0, 0.0, 0.0\n"
    "    2, 2, 20.0, 5.0, 0.0, 1.0, 230.0, 0.5, 1.0, 1.1, 0.9, 0.00625, 100.0, 1.0, 0.0, 1\n"
    "    4, 2, 20.0, 5.0, 0.0, 1.0, 115.0, 0.5, 1.0, 1.1, 0.9, 0.00625, -100.0, 1.0, 0.0, 1\n"
    "    1, 2, 1, 1, 'DC1', 0, 0.0, 1\n"
    "    2, 4, 1, 1, 'DC2', 0, 0.0, 1\n"
    "    1, 2, '1', 1, 5.0, 0.0\n"
)


@pytest.mark.parametrize(
    "old, new, expected",
    [
        # one record of six lines, named at its first (each line had been a record)
        (
            "'MTDC1', 2, 2, 1,",
            "'MTDC1', 2, 2, 1,",
            "edited.raw + five_bus.dyr: 1 unsupported record(s) (--skip-unsupported leaves "
            "them out): edited.raw:40 multi-terminal dc line 'MTDC1' (2 converters): dc lines "
            "are not modelled: the power it carries is lost",
        ),
        (
            "'MTDC1', 2, 2, 1,",
            "'MTDC1', 2, -2, 1,",
            "edited.raw:40 multi-terminal dc line record (line 1 of the record): NDCBS -2 must "
            "be >= 0",
        ),
    ],
)
def test_a_multi_terminal_dc_line_is_one_record_of_its_lines(tmp_path, old, new, expected):
    """POM Multi-Terminal DC Transmission Line Data: the record's first line is followed
    by NCONV converter, NDCBS dc bus and NDCLN dc link lines, all one record."""
    marker = "0 / END OF MULTI-TERMINAL DC DATA"
    source = tmp_path / "mtdc.raw"
    source.write_text(FIVE_BUS.read_text().replace(marker, MULTI_TERMINAL + marker))
    line, _ = refused_raw(tmp_path, source, old, new)
    assert line == f"error: {expected}", line


GNE = "'WIND1', 'WTGEN', 2, 2, 4, 3, 2, 1\n1, 1, 2\n0.5, 1.25, 3.0\n0, 7\n'ABC'\n"


def _with_gne(tmp_path) -> Path:
    """five_bus_v33.raw with the GNE record `GNE` in its GNE device data."""
    marker = "0 / END OF GNE DATA"
    source = tmp_path / "gne.raw"
    source.write_text(FIVE_BUS.read_text().replace(marker, GNE + marker))
    return source


def test_a_gne_device_is_one_record_of_its_lines(tmp_path):
    """POM GNE Device Data: 'NAME', 'MODEL', NTERM, the buses, NREAL, NINTG, NCHAR, then
    STATUS, OWNER, NMETR, then the values, ten a line.  Each line was read as a record of
    its own: an INTG line starting with 0 ended the section, and the import stopped at
    the CHAR line ("data after the last section").  The record is one unsupported record,
    named with its model and buses."""
    source = _with_gne(tmp_path)
    out = tmp_path / "g.json"
    res = CliRunner().invoke(
        main, ["import-psse", str(source), str(FIVE_BUS_DYR), "-o", str(out), "--skip-unsupported"]
    )
    assert res.exit_code == 0, res.output
    left_out = [line for line in res.output.splitlines() if line.startswith("  left out:")]
    assert left_out == [
        "  left out: gne.raw:49 gne device 'WIND1' (model 'WTGEN', bus(es) 2, 4; 3 REAL, 2 "
        "INTG, 1 CHAR values): PSS/E's generic network element runs a user-written model, "
        "which stabctl does not have"
    ]
    res = CliRunner().invoke(main, ["import-psse", str(source), str(FIVE_BUS_DYR), "-o", str(out)])
    assert "1 unsupported record(s)" in error_line(res)


@pytest.mark.parametrize(
    "old, new, expected",
    [
        (
            "2, 2, 4, 3, 2, 1",
            "2, 2, 4, 3, 2.5, 1",
            "line 1 of the record): NINTG = '2.5': not an integer",
        ),
        (
            "2, 2, 4, 3, 2, 1",
            "2, 2, 4, 3, 2",
            "line 1 of the record): 7 field(s), its NTERM 2 needs 8",
        ),
        ("'WTGEN', 2, 2, 4,", "'WTGEN', 0, 2, 4,", "line 1 of the record): NTERM 0 must be >= 1"),
        ("2, 2, 4, 3, 2, 1", "2, 2, 4, -3, 2, 1", "line 1 of the record): NREAL -3 must be >= 0"),
        ("1, 1, 2\n", "3, 1, 2\n", "line 2 of the record): STATUS 3 must be 0 or 1"),
        ("0.5, 1.25, 3.0", "0.5, 1.25", "line 3 of the record): 2 field(s), the v33 layout has 3"),
        ("0, 7", "0, x", "line 4 of the record): INTG2 = 'x': not a number"),
    ],
)
def test_a_malformed_gne_device_is_refused_at_its_line(tmp_path, old, new, expected):
    """A GNE record whose counts, status or value lines do not fit its layout is refused
    naming the file line and which line of the record."""
    line, _ = refused_raw(tmp_path, _with_gne(tmp_path), old, new, "--skip-unsupported")
    assert line.startswith("error: edited.raw:") and expected in line, line
    assert "gne device record (" in line, line


def test_an_unsolved_power_flow_is_refused_unless_kept(tmp_path):
    """A RAW whose power flow does not converge (90 times bus 2's load): every analysis
    command refuses the case, so the import does too, naming the power flow's worst
    mismatch and its bus and the option that writes it all the same (it had been written
    with a warning only); --keep-unsolved writes it with that warning."""
    old = "    2,'1 ',1,   1,   1,   100.000,"
    new = "    2,'1 ',1,   1,   1,  9000.000,"
    line, out = refused_raw(tmp_path, FIVE_BUS, old, new)
    assert re.fullmatch(
        r"error: edited\.raw: stabctl's power flow of the case \(Q limits on, as simulate "
        r"solves it\) does not converge, so every analysis command would refuse it: power "
        r"flow of case 'edited' did not converge after \d+ iteration\(s\): worst mismatch "
        r"[\d.]+ pu at bus 2 .*; nothing written \(--keep-unsolved writes it all the same\)",
        line,
    ), line
    raw = tmp_path / "edited.raw"
    res = CliRunner().invoke(
        main, ["import-psse", str(raw), str(FIVE_BUS_DYR), "-o", str(out), "--keep-unsolved"]
    )
    assert res.exit_code == 0 and out.exists(), res.output
    assert "warning: stabctl's power flow of the case did not converge" in res.output
    static = tmp_path / "s.json"
    res = CliRunner().invoke(main, ["import-psse", str(raw), "-o", str(static), "--static"])
    assert "worst mismatch" in error_line(res) and not static.exists()
    help_text = CliRunner().invoke(main, ["import-psse", "--help"]).output
    assert "--keep-unsolved" in help_text


def test_an_unsolved_power_flow_s_advice_names_whose_option_solves_it(tmp_path):
    """PSS/E's three-bus GENROU system with bus 102's Q limits at +-20 Mvar, bus 103's
    load at 150 Mvar and the lines from bus 101 five times longer converges only with
    the Q limits off: the import
    refuses it and says so, naming --no-q-limits as the option of the commands that run
    the case (import-psse has none)."""
    runs = Path(__file__).parents[1] / "data" / "psse_runs" / "GENROU"
    text = (runs / "ThreeBusMulti.raw").read_text()
    for old, new in (
        ("250.000,    30.000,", "250.000,   150.000,"),
        ("-3.247,   100.000,  -100.000,", "-3.247,   20.000,  -20.000,"),
        ("101,   102,'1 ', 1.00000E-2, 1.20000E-1,", "101,   102,'1 ', 1.00000E-2, 6.00000E-1,"),
        ("101,   103,'1 ', 1.00000E-2, 1.20000E-1,", "101,   103,'1 ', 1.00000E-2, 6.00000E-1,"),
    ):
        assert old in text, old
        text = text.replace(old, new)
    raw = tmp_path / "ql.raw"
    raw.write_text(text)
    out = tmp_path / "ql.json"
    res = CliRunner().invoke(
        main, ["import-psse", str(raw), str(runs / "ThreeBus_GENROU.dyr"), "-o", str(out)]
    )
    line = error_line(res)
    assert "with the PV buses' Q limits off it converges (--no-q-limits of the commands " in line
    assert not out.exists()


def test_a_bus_added_with_a_voltage_no_solution_is_near_imports_from_a_flat_start(tmp_path):
    """Round 32: PSS/E's three-bus GENROU system with a bus 104 added behind 0.001 pu from
    bus 103 (a 10 MW load), its RAW voltage left at 1 pu, 0 deg: the power flow from the
    RAW's voltages diverged (its first iterate clipped at 0.5 pu) and the import was
    refused; it now solves from a flat start, says so, and names bus 104 as where the
    RAW's voltages are not the solution."""
    runs = Path(__file__).parents[1] / "data" / "psse_runs" / "GENROU"
    text = (runs / "ThreeBusMulti.raw").read_text()
    nl = "\r\n" if "\r\n" in text else "\n"
    for end, line in (
        (" 0 /End of Bus data", "   104,'BUS 4', 138.0000,1,   1,   1,   1,1.00000,   0.0000"),
        (" 0 /End of Load data", "   104,'1 ',1, 1, 1, 10.0, 3.0, 0.0, 0.0, 0.0, 0.0, 1,1,0"),
        (" 0 /End of Branch data", "103,104,'1',0,1E-3,0,250,250,250,0,0,0,0,1,1,0,1,1"),
    ):  # fmt: skip
        assert end in text, end
        text = text.replace(end, line + nl + end, 1)
    raw = tmp_path / "added.raw"
    raw.write_text(text)
    out = tmp_path / "added.json"
    res = CliRunner().invoke(
        main, ["import-psse", str(raw), str(runs / "ThreeBus_GENROU.dyr"), "-o", str(out)]
    )
    assert res.exit_code == 0, res.output
    assert "from the case's own voltages; solved from a flat start instead" in res.stderr
    assert "(bus 104)" in res.stderr and out.exists()


@pytest.mark.parametrize(
    "machine, expected",
    [
        # a value that is no number: the parameter by its PSS/E name, not its position
        (record("GENROU", {"H": "nan"}), "bad.dyr:1 GENROU (bus 1, id 1): H = nan: not a finite"),
        (record("GENROU", {"Xd": "inf"}), "bad.dyr:1 GENROU (bus 1, id 1): Xd = inf: not a"),
        (record("GENROU", {"Xd": "1e999"}), "bad.dyr:1 GENROU (bus 1, id 1): Xd = 1e999: not a"),
        (record("GENROU", {"H": "abc"}), "bad.dyr:1 GENROU (bus 1, id 1): H = 'abc': not a number"),
        # a value refused by the tables: as written, E-notation kept
        (
            record("GENROU", {"X''d": "-1.508E-01"}),
            "bad.dyr:1 GENROU (bus 1, id 1): X''d = -1.508E-01: must be >= 0",
        ),
        (
            record("GENROU", bus=-1),
            "bad.dyr:1 GENROU (bus -1, id 1): IBUS = -1: a bus number must be a positive integer",
        ),
    ],
)
def test_a_dyr_value_is_named_by_its_psse_name_and_as_written(tmp_path, machine, expected):
    res, _, out = imported(tmp_path, [machine, INFINITE])
    line = error_line(res)
    assert line.startswith(f"error: {expected}"), line
    assert not out.exists()


def test_a_sexs_non_number_is_named_k(tmp_path):
    res, _, _ = imported(tmp_path, [record("GENROU"), INFINITE, record("SEXS", {"K": "1OO"})])
    assert error_line(res).startswith("error: bad.dyr:3 SEXS (bus 1, id 1): K = '1OO': not a")


def test_a_machine_record_of_no_generator_is_named_before_the_generator_it_leaves_bare(
    tmp_path,
):
    """GENROU id 'Z1' where the RAW's generator at bus 1 is '1': that record, its line and
    the ids there are, then the generator left without a machine; from the command line
    the advice is its option, from the library the argument."""
    stray = record("GENROU").replace(" 1 4.6385", " 'Z1' 4.6385")
    res, dyr, _ = imported(tmp_path, [INFINITE, stray])
    assert error_line(res) == (
        "error: bad.dyr:2 GENROU (bus 1, id Z1): matches no generator in service of the RAW "
        "data (bus 1's: id '1'); so generator(s) without a machine model record in the DYR "
        "data: machine 1 (bus 1, id 1) (--net-unmodelled nets them as negative loads)"
    )
    from stabctl.io.psse import import_psse

    with pytest.raises(CaseError, match=r"\(unmodelled='net' nets them") as err:
        import_psse(RAW, dyr)
    assert "--" not in str(err.value)


def test_a_generator_without_a_machine_record_is_named_with_the_records_it_has(tmp_path):
    """A SEXS for a generator the DYR gives no machine model: the generator is refused
    with the SEXS's file:line, the record the user wrote for it."""
    res, _, _ = imported(tmp_path, [INFINITE, record("SEXS")])
    assert error_line(res) == (
        "error: generator(s) without a machine model record in the DYR data: machine 1 "
        "(bus 1, id 1) (its DYR record(s): bad.dyr:2 SEXS) (--net-unmodelled nets them as "
        "negative loads)"
    )


def test_the_controls_of_a_netted_generator_are_named_as_left_out_with_it(tmp_path):
    """--net-unmodelled nets the generator without a machine model record; its SEXS is
    left out with it, said so (not "no such generator in the RAW data")."""
    res, _, out = imported(tmp_path, [INFINITE, record("SEXS")], "--net-unmodelled")
    assert res.exit_code == 0 and out.exists(), res.output
    assert (
        "left out with its netted generator: bad.dyr:2 SEXS (bus 1, id 1): left out with its "
        "generator, netted (no machine model)" in res.output
    )
    assert "no such generator" not in res.output


def test_an_unsupported_record_advises_the_option_on_the_command_line(tmp_path):
    res, dyr, _ = imported(tmp_path, [record("GENROU"), INFINITE, "    1 'FOOBAR' 1 1 2 3 /"])
    line = error_line(res)
    assert "(--skip-unsupported leaves them out)" in line and "on_unsupported" not in line
    from stabctl.io.psse import import_psse

    with pytest.raises(CaseError, match=r"\(on_unsupported='skip' leaves them out\)") as err:
        import_psse(RAW, dyr)
    assert "--" not in str(err.value)


def andes_xlsx_edited(tmp_path, case: str, sheet: str, row: int, column: str, value):
    """ANDES's xlsx case with `column` of spreadsheet row `row` of `sheet` set to `value`."""
    andes = pytest.importorskip("andes")
    openpyxl = pytest.importorskip("openpyxl")
    book = openpyxl.load_workbook(andes.get_case(case))
    ws = book[sheet]
    header = [c.value for c in ws[1]]
    ws.cell(row=row, column=header.index(column) + 1).value = value
    out = tmp_path / "edited.xlsx"
    book.save(out)
    return out


def test_andes_text_where_a_number_belongs_is_named_with_its_cell(tmp_path):
    """TGOV1 R 'abc' in an xlsx file, PVD1 Sn '100 MVA' in a json one: ANDES's own words
    were "could not convert string to float: 'abc'"; now the file, model, row (and the
    spreadsheet's row of an xlsx file), idx, parameter and text."""
    path = andes_xlsx_edited(tmp_path, "ieee14/ieee14_wt3.xlsx", "TGOV1", 2, "R", "abc")
    res = CliRunner().invoke(main, ["import-andes", str(path), "-o", str(tmp_path / "a.json")])
    assert error_line(res) == (
        "error: edited.xlsx: TGOV1 row 1 (idx TGOV1_1; spreadsheet row 2): R = 'abc': not a "
        "number (ANDES cannot read it)"
    )
    path = andes_edited(tmp_path, "ieee14/ieee14_pvd1.xlsx", "PVD1", "Sn", "100 MVA")
    res = CliRunner().invoke(main, ["import-andes", str(path), "-o", str(tmp_path / "a.json")])
    assert re.fullmatch(
        rf"error: {path.name}: PVD1 row 1 \(idx [^)]+\): Sn = '100 MVA': not a number .*",
        error_line(res),
    )


def test_an_andes_device_out_of_service_is_named_as_left_out(tmp_path):
    """TGOV1 row 1 with u = 0 was dropped without a word ("0 left out"); now named, as
    import-psse names the equipment out of service."""
    path = andes_xlsx_edited(tmp_path, "ieee14/ieee14_wt3.xlsx", "TGOV1", 2, "u", 0)
    out = tmp_path / "a.json"
    res = CliRunner().invoke(main, ["import-andes", str(path), "-o", str(out), "--json"])
    assert res.exit_code == 0, res.output
    summary = json.loads(res.stdout)
    assert summary["out_of_service"] == [
        "edited.xlsx: TGOV1 row 1 (idx TGOV1_1): out of service (u = 0)"
    ]


def test_a_case_json_with_a_byte_order_mark_is_read(tmp_path):
    """A case file saved with a UTF-8 BOM (Windows editors) was refused in Python's words
    ("decode using utf-8-sig"): it is read."""
    res, _, out = imported(tmp_path, [record("GENROU"), INFINITE])
    assert res.exit_code == 0, res.output
    bom = tmp_path / "bom.json"
    bom.write_bytes(b"\xef\xbb\xbf" + out.read_bytes())
    assert load_case(bom).equals(load_case(out))


def test_a_raw_or_dyr_saved_as_utf_16_is_named_so(tmp_path):
    """A RAW saved in UTF-16 (an editor's "Unicode") was refused as "SBASE = ' ': not a
    number" (round 29); the RAW and the DYR name their encoding and what to do."""
    from stabctl.io.psse import load_psse

    dyr = tmp_path / "c.dyr"
    dyr.write_text("\n".join([record("GENROU"), INFINITE]) + "\n")
    for kind, raw, dyr_file in (
        ("RAW", tmp_path / "u16.raw", dyr),
        ("DYR", RAW, tmp_path / "u16.dyr"),
    ):
        source = RAW if kind == "RAW" else dyr
        (raw if kind == "RAW" else dyr_file).write_bytes(source.read_text().encode("utf-16"))
        with pytest.raises(CaseError, match=rf"the {kind} file is in UTF-16 or UTF-32 .* save it"):
            load_psse(raw, dyr_file)
    # round 46: one NUL byte in an ASCII file (inside a number, near its start) was called
    # UTF-16, no line named; it is a damaged file, named with its line
    text = dyr.read_bytes()
    at = text.index(b"\n") + 9  # in line 2's H
    damaged = tmp_path / "nul.dyr"
    damaged.write_bytes(text[:at] + b"\x00" + text[at:])
    with pytest.raises(CaseError, match=rf"nul.dyr:2: the DYR file holds a NUL byte \(byte {at}\)"):
        load_psse(RAW, damaged)


def test_advice_is_in_the_callers_words():
    """A library caller is advised Python arguments, a command's user its options, and
    nothing where the command line has no such option."""
    from stabctl.errors import advice, on_command_line

    assert advice("(on_unsupported='skip')", "(--skip-unsupported)") == "(on_unsupported='skip')"
    with on_command_line():
        assert advice("(on_unsupported='skip')", "(--skip-unsupported)") == "(--skip-unsupported)"
        assert advice(" (Simulator(off_equilibrium='warn') runs it anyway)") == ""


def test_an_exciter_that_cannot_start_is_named_by_the_import_that_keeps_it(tmp_path):
    """SEXS EMAX = 0.5 below the field voltage its machine starts at: the import without
    --leave-out-infeasible wrote the case without a word, and every run then refused it.
    It is named there, with the option; with the option it is left out by name."""
    lines = [record("GENROU"), INFINITE, record("SEXS", {"EMAX": 0.5})]
    res, _, out = imported(tmp_path, lines)
    assert res.exit_code == 0 and out.exists(), res.output
    warned = [x for x in res.output.splitlines() if x.startswith("warning: the exciter")]
    assert len(warned) == 1 and warned[0].startswith(
        "warning: the exciter of G1 (bus 1, id '1'): Vrmax (SEXS's, SCRX's EMAX) = 0.5 below "
        "the initial field voltage"
    )
    assert warned[0].endswith(
        "every run refuses the case as written (--leave-out-infeasible leaves such a control"
        " out, named)"
    )
    res, _, out = imported(tmp_path, lines, "--leave-out-infeasible")
    assert res.exit_code == 0 and "1 control(s) outside their limits left out" in res.output


#: the five-bus case's generator at bus 3 '1' from its ZX on (v33)
GEN_3_1 = "2.00000E-1, 0.00000E+0, 0.00000E+0,1.00000,1,  100.0,   200.000,     0.000,   1,1.0000"
#: the five-bus case's switched shunt (v33: bus 4, MODSW 1, SWREM 0, BINIT 30 of one block)
SWSH = "    4,1,0,1,1.05000,0.95000,     0,100.0,'            ',    30.00,   1,    30.00"


@pytest.mark.parametrize(
    "source, old, new, expected",
    [
        # transformer codes, used by stabctl or not
        (
            FIVE_BUS,
            "'1 ',2,2,1,",
            "'1 ',2,2,5,",
            "edited.raw:26 transformer record (line 1 of the record): transformer 2-3 '1': "
            "CM 5 must be 1 or 2",
        ),
        (
            FIVE_BUS,
            "'1 ',2,2,1,",
            "'1 ',2,0,1,",
            "edited.raw:26 transformer record (line 1 of the record): transformer 2-3 '1': "
            "CZ 0 must be 1, 2 or 3",
        ),
        (
            FIVE_BUS,
            "0.00000E+0,2,'T1",
            "0.00000E+0,3,'T1",
            "edited.raw:26 transformer record (line 1 of the record): transformer 2-3 '1': "
            "NMETR 3 must be 1 or 2",
        ),
        (
            V35,
            "'            ', 0\n 5.00000E-03",
            "'            ', 7\n 5.00000E-03",
            "edited.raw:49 transformer record (line 1 of the record): transformer 2-3 '1': "
            "ZCOD 7 must be 0 or 1",
        ),
        # a winding's control: its code, its controlled bus, its limits
        (
            FIVE_BUS,
            "240.00,   0.000,   0.000,   100.00,   100.00,   100.00, 0,      0, 1.10000,",
            "240.00,   0.000,   0.000,   100.00,   100.00,   100.00, 9,      0, 1.10000,",
            "edited.raw:28 transformer record (line 3 of the record): transformer 2-3 '1': "
            "COD1 9 must be within -5 to 5",
        ),
        (
            FIVE_BUS,
            "240.00,   0.000,   0.000,   100.00,   100.00,   100.00, 0,      0, 1.10000,",
            "240.00,   0.000,   0.000,   100.00,   100.00,   100.00, 1,     77, 1.10000,",
            "edited.raw:28 transformer record (line 3 of the record): transformer 2-3 '1': "
            "CONT1 77: bus 77 is not in the bus data",
        ),
        (
            FIVE_BUS,
            "240.00,   0.000,   0.000,   100.00,   100.00,   100.00, 0,      0, 1.10000,",
            "240.00,   0.000,   0.000,   100.00,   100.00,   100.00, -1,     3, 0.8,",
            "edited.raw:28 transformer record (line 3 of the record): transformer 2-3 '1': "
            "RMA1 = 0.8, RMI1 = 0.90000: RMA1 must be >= RMI1 (COD1 -1)",
        ),
        (
            FIVE_BUS,
            "0.05000,1,1,",
            "0.05000,1,3,",
            "edited.raw:24 branch record: branch 1-2 '3': MET 3 must be 1 or 2",
        ),
        # generator fields
        (
            FIVE_BUS,
            GEN_3_1,
            GEN_3_1.replace("0.00000E+0,1.00000,1", "0.00000E+0,0.0,1"),
            "edited.raw:18 generator record: generator at bus 3 '1': GTAP 0.0 must be > 0",
        ),
        (
            FIVE_BUS,
            GEN_3_1,
            GEN_3_1.replace("200.000,     0.000", "-50.0,     0.000"),
            "edited.raw:18 generator record: generator at bus 3 '1': PT = -50.0, PB = 0.000: "
            "PT must be >= PB",
        ),
        (
            FIVE_BUS,
            GEN_3_1,
            GEN_3_1.replace("   1,1.0000", "   1,-0.5"),
            "edited.raw:18 generator record: generator at bus 3 '1': F1 -0.5 must be >= 0 (an "
            "ownership fraction)",
        ),
        # RMPCT must be positive, whether the plant regulates a remote bus or its own
        (
            FIVE_BUS,
            GEN_3_1,
            GEN_3_1.replace("100.0", "-100.0"),
            "edited.raw:18 generator record: generator at bus 3 '1': RMPCT -100.0 must be > 0",
        ),
        (
            V35,
            "   0,1.0000, 0, 1.000\n    3,'2 '",
            "   0,1.0000, 4, 1.000\n    3,'2 '",
            "edited.raw:33 generator record: generator at bus 3 '1': WMOD 4 must be within 0 to 3",
        ),
        (
            V35,
            "   0,1.0000, 0, 1.000\n    3,'2 '",
            "   0,1.0000, 2, 0.0\n    3,'2 '",
            "edited.raw:33 generator record: generator at bus 3 '1': WPF 0.0 must be within -1 "
            "to 1 and not 0 (WMOD 2)",
        ),
        (
            V35,
            "   0,1.0000, 0, 1.000\n    3,'2 '",
            "   0,1.0000, 3, -1.5\n    3,'2 '",
            "edited.raw:33 generator record: generator at bus 3 '1': WPF -1.5 must be within -1 "
            "to 1 and not 0 (WMOD 3)",
        ),
        # switched shunt fields
        (
            FIVE_BUS,
            SWSH,
            SWSH.replace("    30.00,   1", "    100.0,   1"),
            "edited.raw:47 switched shunt record: switched shunt at bus 4: BINIT 100.0 Mvar is "
            "outside the 0 to 30 Mvar its blocks in service reach (N1 = 1, B1 = 30.00)",
        ),
        (
            FIVE_BUS,
            SWSH,
            SWSH.replace("1.05000,0.95000", "0.90000,0.95000"),
            "edited.raw:47 switched shunt record: switched shunt at bus 4: VSWHI = 0.90000, "
            "VSWLO = 0.95000: VSWHI must be >= VSWLO (MODSW 1)",
        ),
        (
            FIVE_BUS,
            SWSH,
            SWSH.replace("     0,100.0", "     99,100.0"),
            "edited.raw:47 switched shunt record: switched shunt at bus 4: SWREM 99: bus 99 is "
            "not in the bus data",
        ),
        (
            FIVE_BUS,
            SWSH,
            SWSH.replace("    4,1,0,1", "    4,1,2,1"),
            "edited.raw:47 switched shunt record: switched shunt at bus 4: ADJM 2 must be 0 or 1",
        ),
        (
            FIVE_BUS,
            SWSH,
            SWSH.replace("    4,1,0,1", "    4,7,0,1"),
            "edited.raw:47 switched shunt record: switched shunt at bus 4: MODSW 7 must be within "
            "0 to 6",
        ),
        (
            V35,
            "  30.00, 1, 1,  30.00",
            "  30.00, 0, 1,  30.00",
            "edited.raw:89 switched shunt record: switched shunt at bus 4 '1': BINIT 30.00 Mvar "
            "is outside the 0 to 0 Mvar its blocks in service reach (none)",
        ),
    ],
)
def test_a_raw_code_or_limit_outside_the_pom_s_range_is_refused_naming_its_field(
    tmp_path, source, old, new, expected
):
    """The POM's ranges of the transformer, branch, generator and switched shunt fields,
    whether stabctl reads the field or not (NMETR, MET, ZCOD, GTAP, PT and PB, the
    ownership fractions): a value outside is refused naming the record's line, the field
    and its text (each had been read as its default, or as nothing, without a word).  A
    bus a control names (CONT, SWREM) must be in the bus data; a control's upper limit
    must not be below its lower; a switched shunt's BINIT must be reachable by its
    blocks in service (v35 and later: a block's status Si)."""
    line, _ = refused_raw(tmp_path, source, old, new)
    assert line == f"error: {expected}", line
